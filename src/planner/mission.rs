//! Flying a waypoint mission: line-of-sight along a leg and the loiter circle at the end. The
//! mission itself — waypoints, the end, surveys — is a value type ([`crate::types::mission`]).
//!
//! None of the seed papers has waypoints: they fly one goal-point. The list is theirs flown one
//! goal-point at a time; the circle is followed with the vector field of Nelson, Barber, McLain
//! and Beard ("Vector field path following for miniature air vehicles", IEEE T-RO 23(3), 2007,
//! eq. 6): course χ = γ + s·(π/2 + atan(k·(d − r))), γ the bearing from the centre, d the
//! distance to it, s the sense — a goal-point is put σ_c ahead along that course.

use crate::math::{Vec2, PI};

pub use crate::types::mission::*;

/// Look-ahead along a leg, × the cruise reach σ_c ([`along_leg`]).
pub const LEG_LOOKAHEAD: f32 = 0.5;

/// Where to steer to fly the leg from `a` to `b` from `p`: the point `lookahead` m beyond `p`'s
/// projection on the leg, or `b` itself within that of it — line-of-sight guidance (Fossen,
/// "Handbook of Marine Craft Hydrodynamics and Motion Control", 2011, §10.3.2), so that a
/// vehicle pushed off a survey line by an obstacle comes back onto the line rather than cutting
/// straight to the next waypoint. The VPF then puts its cruise goal-point towards that point.
pub fn along_leg(p: Vec2, a: Vec2, b: Vec2, lookahead: f32) -> Vec2 {
    let d = b - a;
    let len = d.norm();
    if len < 1e-3 {
        return b;
    }
    let t = crate::math::max(0.0, crate::math::min((p - a).dot(d) / len, len));
    let s = t + lookahead;
    if s >= len {
        b
    } else {
        a + d * (s / len)
    }
}

/// Gain k of the loiter vector field, × 1/r: at (d − r) = r/2 the course is 45° off the tangent.
const LOITER_GAIN: f32 = 2.0;

/// Where to steer to circle `center` at radius `r` from `p` (the sense is counter-clockwise,
/// or clockwise): a point `reach` m ahead along the course of Nelson et al.'s vector field
/// (module notes). From the centre itself the vehicle heads out along +x.
pub fn loiter_aim(p: Vec2, center: Vec2, r: f32, clockwise: bool, reach: f32) -> Vec2 {
    let off = p - center;
    let d = off.norm();
    let gamma = if d > 1e-3 { off.angle() } else { 0.0 };
    let sense = if clockwise { -1.0 } else { 1.0 };
    let k = LOITER_GAIN / crate::math::max(r, 1e-3);
    let chi = gamma + sense * (0.5 * PI + libm::atanf(k * (d - r)));
    p + Vec2::from_angle(chi) * reach
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_loiter_field_points_along_the_circle_on_it_and_towards_it_from_afar() {
        let c = Vec2::new(5.0, 5.0);
        // On the circle, east of the centre: north (ccw) or south (cw).
        let on = c + Vec2::new(10.0, 0.0);
        let ccw = loiter_aim(on, c, 10.0, false, 1.0) - on;
        assert!((ccw - Vec2::new(0.0, 1.0)).norm() < 1e-5, "{ccw:?}");
        let cw = loiter_aim(on, c, 10.0, true, 1.0) - on;
        assert!((cw - Vec2::new(0.0, -1.0)).norm() < 1e-5, "{cw:?}");
        // Far out: almost straight at the centre.
        let far = c + Vec2::new(500.0, 0.0);
        let back = loiter_aim(far, c, 10.0, false, 1.0) - far;
        assert!(back.x < -0.99, "{back:?}");
        // Inside: heading outwards.
        let inside = c + Vec2::new(1.0, 0.0);
        let out = loiter_aim(inside, c, 10.0, false, 1.0) - inside;
        assert!(out.x > 0.3, "{out:?}");
    }
}
