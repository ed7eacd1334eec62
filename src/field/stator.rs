//! The stator (static repulsion) PDF of an obstacle, seed 000 eq. 9 and 12:
//!
//! f(r) = e^{A⁺/r²} − 1,
//!
//! with r the distance from the sampled point to the obstacle's surface and A⁺ its
//! repulsiveness. (Seed 001 eq. 1 and 002 eq. 1 write e^{A⁺/r}; we follow 000, whose shapes and
//! agent parameters {r₀ = 0.5, A⁺ = 2.5} we reproduce. The "− 1" makes a far obstacle
//! contribute nothing.)
//!
//! **Clamp.** e^{A⁺/r²} overflows `f32` once A⁺/r² > 88, and the paper's r stops at 0 on the
//! surface. We evaluate the paper's formula down to the distance r_c where the exponent reaches
//! [`EXP_CAP`], and continue below r_c (and on into the obstacle, where the signed distance is
//! negative) along the tangent line at r_c. The result is C¹, strictly decreasing in r
//! everywhere, finite for any finite r, and its gradient inside an obstacle still points out, so
//! a vehicle that finds itself inside is pushed out instead of sitting on a flat plateau.

use crate::math::{exp, exp_nonnegative, exp_within, sqrt};

/// Largest exponent A⁺/r² evaluated with the paper's formula. e²⁰ ≈ 4.9·10⁸: at that level the
/// force is far beyond any F_max, and 32 obstacles plus the continuation stay well inside `f32`
/// (≤ 10³⁸) for any obstacle the shapes accept.
pub const EXP_CAP: f32 = 20.0;

/// Below this exponent x = A⁺/r², e^x − 1 is summed as its series to x⁴/24: the truncation
/// is below 3·10⁻⁶ of the value, the series is more accurate than e^x − 1 in `f32` (which
/// cancels), and it skips the `exp` for the far obstacles that are most of a full table.
const SERIES_MAX: f32 = 0.125;

/// The stator PDF of one obstacle with its clamp point precomputed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Stator {
    a_plus: f32,
    /// r_c = √(A⁺ / EXP_CAP).
    r_c: f32,
    /// f(r_c).
    f_c: f32,
    /// −f′(r_c) = 2A⁺/r_c³ · e^{A⁺/r_c²} > 0.
    slope_c: f32,
}

impl Stator {
    /// The PDF for repulsiveness `a_plus` > 0 (finite; checked by the callers' parameter
    /// validation).
    pub fn new(a_plus: f32) -> Self {
        let r_c = sqrt(a_plus / EXP_CAP);
        let e = exp(EXP_CAP);
        Stator {
            a_plus,
            r_c,
            f_c: e - 1.0,
            slope_c: 2.0 * a_plus / (r_c * r_c * r_c) * e,
        }
    }

    /// Repulsiveness A⁺.
    pub fn a_plus(&self) -> f32 {
        self.a_plus
    }

    /// f(r) for a signed distance r (metres; negative inside the obstacle).
    #[inline(always)]
    pub fn potential(&self, r: f32) -> f32 {
        if r > self.r_c {
            let x = self.a_plus / (r * r);
            if x < SERIES_MAX {
                x * (1.0 + x * (0.5 + x * (1.0 / 6.0 + x * (1.0 / 24.0))))
            } else {
                // Above r_c the exponent is at most EXP_CAP (to its rounding): within `exp`'s
                // range, so without its clamps (here and below), and here positive.
                exp_nonnegative(x) - 1.0
            }
        } else {
            self.f_c + self.slope_c * (self.r_c - r)
        }
    }

    /// f′(r) = df/dr: −2A⁺/r³·e^{A⁺/r²} (the derivative of eq. 9's PDF), and −f′(r_c) on
    /// the continuation below r_c. Negative: the potential falls with distance.
    pub fn slope(&self, r: f32) -> f32 {
        if r > self.r_c {
            let x = self.a_plus / (r * r);
            -2.0 * x / r * exp_nonnegative(x)
        } else {
            -self.slope_c
        }
    }

    /// The rotor's distance weight h(r) = 1 − e^{−A⁺/r²} ∈ (0, 1]: 1 at and inside the surface,
    /// ≈ A⁺/r² far away, so the rotor reaches exactly as far as this stator does.
    #[inline(always)]
    pub fn reach(&self, r: f32) -> f32 {
        if r > self.r_c {
            1.0 - exp_within(-self.a_plus / (r * r))
        } else {
            1.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_paper_formula_away_from_the_clamp() {
        let s = Stator::new(2.5);
        for r in [0.5f32, 1.0, 2.0, 10.0] {
            let want = libm::expf(2.5 / (r * r)) - 1.0;
            assert!((s.potential(r) - want).abs() <= want * 1e-5, "r = {r}");
        }
    }

    #[test]
    fn strictly_decreasing_and_finite_through_the_surface_and_inside() {
        let s = Stator::new(2.5);
        let mut r = 5.0f32;
        let mut last = s.potential(r);
        while r > -3.0 {
            r -= 0.001;
            let f = s.potential(r);
            assert!(f.is_finite());
            assert!(f > last, "not increasing at r = {r}: {f} <= {last}");
            last = f;
        }
    }

    #[test]
    fn continuous_at_the_clamp_point() {
        let s = Stator::new(0.7);
        let below = s.potential(s.r_c - 1e-6);
        let above = s.potential(s.r_c + 1e-6);
        assert!((below - above).abs() / above < 1e-3);
    }

    #[test]
    fn series_branch_matches_libm_and_meets_the_exp_branch() {
        let s = Stator::new(2.5);
        for r in [4.0f32, 4.4, 4.47, 4.48, 5.0, 10.0, 100.0] {
            let exact = libm::expm1f(2.5 / (r * r));
            let got = s.potential(r);
            assert!(
                (got - exact).abs() <= 3e-6 * exact,
                "r {r}: {got} vs {exact}"
            );
        }
    }

    #[test]
    fn slope_is_the_derivative() {
        let s = Stator::new(2.5);
        for r in [0.3f32, 0.5, 1.0, 3.0, 12.0] {
            let h = 1e-3 * r;
            let fd = (s.potential(r + h) - s.potential(r - h)) / (2.0 * h);
            assert!((s.slope(r) - fd).abs() <= 1e-3 * fd.abs(), "r {r}");
        }
    }

    #[test]
    fn far_obstacle_contributes_nothing() {
        assert!(Stator::new(2.5).potential(1e4) < 1e-6);
        assert!(Stator::new(2.5).reach(1e4) < 1e-6);
        assert_eq!(Stator::new(2.5).reach(-1.0), 1.0);
    }
}
