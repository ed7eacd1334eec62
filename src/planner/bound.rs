//! Bounding of the controlling force and of the commanded velocity.
//!
//! - Plain bounding, `bound(v, max)` (seed 001 eq. 5 and 7): modulus limited, direction kept.
//! - Split bounding (seed 001 §3.1): the vector is decomposed along ê₁, the direction of travel,
//!   and ê₂ = [[0, 1], [−1, 0]]·ê₁ (eq. 9–10). If the parallel part is negative (slow down) it is
//!   bounded first and the perpendicular part gets what is left of the budget; otherwise the
//!   perpendicular part (the turn) is bounded first. A vehicle cruising at v_max towards an
//!   obstacle thus keeps the authority to turn instead of spending it all on braking.

use crate::math::{max_num, min_num, sqrt, Vec2};
use crate::params::Bounding;

/// Bounds `v` to modulus `max` with the chosen method. `e1` is the unit direction of travel;
/// without one (vehicle at rest with no heading), split bounding falls back to plain.
pub fn bound(v: Vec2, max: f32, e1: Option<Vec2>, method: Bounding) -> Vec2 {
    match (method, e1) {
        (Bounding::Split, Some(e1)) => split(v, max, e1),
        _ => v.bounded(max),
    }
}

/// 001 §3.1, both cases.
fn split(v: Vec2, max: f32, e1: Vec2) -> Vec2 {
    let e2 = Vec2::new(e1.y, -e1.x);
    let par = v.dot(e1);
    let perp = v.dot(e2);
    let rest = |first: f32| sqrt(max_num(max * max - first * first, 0.0));
    let (par_b, perp_b) = if par < 0.0 {
        let par_b = -min_num(max, -par);
        (par_b, perp.signum() * min_num(perp.abs(), rest(par_b)))
    } else {
        let perp_b = perp.signum() * min_num(perp.abs(), max);
        (min_num(par, rest(perp_b)), perp_b)
    };
    e1 * par_b + e2 * perp_b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_keeps_the_turn_when_accelerating_or_coasting() {
        let e1 = Vec2::new(1.0, 0.0);
        // Forward 3, sideways 4, bound 4: the sideways part survives whole, nothing is left.
        let b = bound(Vec2::new(3.0, 4.0), 4.0, Some(e1), Bounding::Split);
        assert!((b.y - 4.0).abs() < 1e-6 && b.x.abs() < 1e-6);
        // Plain bounding scales both.
        let p = bound(Vec2::new(3.0, 4.0), 4.0, Some(e1), Bounding::Plain);
        assert!((p.x - 2.4).abs() < 1e-6 && (p.y - 3.2).abs() < 1e-6);
    }

    #[test]
    fn split_keeps_the_braking_when_slowing_down() {
        let e1 = Vec2::new(0.0, 1.0);
        // Braking 3 (along −ê₁), sideways 4, bound 3: all braking, no turn left.
        let b = bound(Vec2::new(4.0, -3.0), 3.0, Some(e1), Bounding::Split);
        assert!((b.y + 3.0).abs() < 1e-6 && b.x.abs() < 1e-5, "{b:?}");
    }

    #[test]
    fn never_exceeds_the_bound_and_leaves_small_vectors_alone() {
        let e1 = Vec2::new(0.6, 0.8);
        for v in [
            Vec2::new(10.0, -3.0),
            Vec2::new(-7.0, 2.0),
            Vec2::new(0.1, 0.2),
        ] {
            for m in [Bounding::Plain, Bounding::Split] {
                let b = bound(v, 1.0, Some(e1), m);
                assert!(b.norm() <= 1.0 + 1e-5);
                if v.norm() <= 1.0 {
                    assert!((b - v).norm() < 1e-6);
                }
            }
        }
    }
}
