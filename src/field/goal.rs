//! The goal-point PDF, seed 000 eq. 13 (and 001 eq. 12 for formation nodes):
//!
//! f_GP(p) = −A⁻ · e^{−‖p − p_GP‖² / 2σ²}
//!
//! A⁻ is the attractiveness, σ the attractor reach. Ghost goal-points and the virtual leader use
//! the same function.

use crate::math::{exp, Vec2};

/// A Gaussian attractor with 1/2σ² precomputed (no division on the hot path).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GoalPdf {
    /// Centre p_GP.
    pub center: Vec2,
    a_minus: f32,
    inv_two_sigma2: f32,
}

impl GoalPdf {
    /// Attractor at `center` with attractiveness `a_minus` ≥ 0 and reach `sigma` > 0 (metres;
    /// validated by the parameters).
    pub fn new(center: Vec2, a_minus: f32, sigma: f32) -> Self {
        GoalPdf {
            center,
            a_minus,
            inv_two_sigma2: 0.5 / (sigma * sigma),
        }
    }

    /// f_GP(p).
    #[inline(always)]
    pub fn potential(&self, p: Vec2) -> f32 {
        -self.a_minus * exp(-(p - self.center).norm2() * self.inv_two_sigma2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deepest_at_the_goal_and_symmetric() {
        let g = GoalPdf::new(Vec2::new(1.0, 2.0), 3.0, 4.0);
        assert!((g.potential(Vec2::new(1.0, 2.0)) + 3.0).abs() < 1e-6);
        let a = g.potential(Vec2::new(5.0, 2.0));
        let b = g.potential(Vec2::new(1.0, -2.0));
        assert!((a - b).abs() < 1e-6);
        // One σ away: −A⁻·e^{−1/2}.
        assert!((a + 3.0 * libm::expf(-0.5)).abs() < 1e-5);
    }
}
