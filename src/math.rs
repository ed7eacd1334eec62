//! Planar vectors, angles and the few transcendental functions the planner needs, behind one
//! interface so the hot path can be moved to fixed point or a faster approximation in one place.
//!
//! Units: metres, seconds, radians. Everything is `f32` (the Cortex-M4F FPU is single precision).

use core::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

/// π as `f32`.
pub const PI: f32 = core::f32::consts::PI;
/// 2π as `f32`.
pub const TAU: f32 = core::f32::consts::TAU;

/// A vector in the horizontal plane of the Earth-fixed frame (x east/north as the user chooses,
/// y 90° counter-clockwise from x). Metres, metres per second or newton-like force units.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Vec2 {
    /// x component.
    pub x: f32,
    /// y component.
    pub y: f32,
}

impl Vec2 {
    /// The zero vector.
    pub const ZERO: Vec2 = Vec2 { x: 0.0, y: 0.0 };

    /// A vector from its components.
    pub const fn new(x: f32, y: f32) -> Self {
        Vec2 { x, y }
    }

    /// The unit vector at angle `a` (radians, counter-clockwise from +x).
    pub fn from_angle(a: f32) -> Self {
        Vec2::new(cos(a), sin(a))
    }

    /// Scalar product ⟨self, o⟩.
    pub fn dot(self, o: Vec2) -> f32 {
        self.x * o.x + self.y * o.y
    }

    /// z component of the cross product: positive when `o` lies counter-clockwise of `self`.
    pub fn cross(self, o: Vec2) -> f32 {
        self.x * o.y - self.y * o.x
    }

    /// Squared length: no square root, for comparisons and Gaussians.
    pub fn norm2(self) -> f32 {
        self.dot(self)
    }

    /// Length.
    pub fn norm(self) -> f32 {
        sqrt(self.norm2())
    }

    /// The vector rotated by +90° (counter-clockwise).
    pub fn perp(self) -> Vec2 {
        Vec2::new(-self.y, self.x)
    }

    /// The vector rotated by angle `a`, given as its cosine and sine.
    pub fn rotate_cs(self, c: f32, s: f32) -> Vec2 {
        Vec2::new(c * self.x - s * self.y, s * self.x + c * self.y)
    }

    /// Direction, `atan2(y, x)`, in (−π, π]; 0 for the zero vector.
    pub fn angle(self) -> f32 {
        atan2(self.y, self.x)
    }

    /// The unit vector along `self`, or `None` when `self` is shorter than `min_len` (so a
    /// direction is never taken from numerical noise).
    pub fn normalized(self, min_len: f32) -> Option<Vec2> {
        let n = self.norm();
        if n > min_len && n.is_finite() {
            Some(self * (1.0 / n))
        } else {
            None
        }
    }

    /// `bound(v, max)` of seed 000 eq. 2 and 001 eq. 5: the vector with its modulus limited to
    /// `max`, direction kept.
    pub fn bounded(self, max: f32) -> Vec2 {
        let n2 = self.norm2();
        if n2 > max * max {
            self * (max / sqrt(n2))
        } else {
            self
        }
    }

    /// Both components finite.
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite()
    }
}

impl Add for Vec2 {
    type Output = Vec2;
    fn add(self, o: Vec2) -> Vec2 {
        Vec2::new(self.x + o.x, self.y + o.y)
    }
}
impl AddAssign for Vec2 {
    fn add_assign(&mut self, o: Vec2) {
        *self = *self + o;
    }
}
impl Sub for Vec2 {
    type Output = Vec2;
    fn sub(self, o: Vec2) -> Vec2 {
        Vec2::new(self.x - o.x, self.y - o.y)
    }
}
impl SubAssign for Vec2 {
    fn sub_assign(&mut self, o: Vec2) {
        *self = *self - o;
    }
}
impl Mul<f32> for Vec2 {
    type Output = Vec2;
    fn mul(self, k: f32) -> Vec2 {
        Vec2::new(self.x * k, self.y * k)
    }
}
impl Neg for Vec2 {
    type Output = Vec2;
    fn neg(self) -> Vec2 {
        Vec2::new(-self.x, -self.y)
    }
}

/// Square root, correctly rounded. On the Cortex-M4F it is the FPU's `vsqrt.f32` (14 cycles);
/// libm's portable `sqrtf` is a software routine of a hundred-odd instructions there, and the
/// hot path takes one or two square roots per object and gradient sample.
///
/// A called function, not inlined: the hard-float ABI brings x and takes the result in s0, so
/// the body is the instruction and a return. An inline `asm!` cannot name an FPU register here
/// (Rust's `sreg` operand class needs a `vfp2` feature this target does not declare), so it
/// moved x through a core register and saved s0 around the instruction: 29 bytes at each of
/// 157 call sites, 2 748 bytes of the NUCLEO image. `cargo selftest`, step max in
/// instructions: VPF in clutter 73 280 → 74 480 and flying a flat-fish in traffic 88 320 →
/// 90 080 (a call and a return, and values kept across it), multipoint 86 960 → 82 880 and
/// navfn 56 800 → 53 960 (shorter code); stack high-water 9 140 → 9 124 bytes.
#[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
#[unsafe(naked)]
pub extern "C" fn sqrt(x: f32) -> f32 {
    // SAFETY (of the naked body): x arrives in s0 and the result leaves in s0 (AAPCS-VFP); no
    // other register, no memory, no stack. `.fpu` lets the assembler take the FPU instruction.
    core::arch::naked_asm!(".fpu fpv4-sp-d16", "vsqrt.f32 s0, s0", "bx lr")
}

/// Square root, correctly rounded (libm, elsewhere than on the Cortex-M4F).
#[cfg(not(all(target_arch = "arm", target_abi = "eabihf")))]
pub fn sqrt(x: f32) -> f32 {
    libm::sqrtf(x)
}

/// The larger of two numbers, by one comparison (`f32::max` is a libm call on the Cortex-M4F,
/// which has no min/max instruction). For NaN in either, returns `b`.
pub fn max(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

/// The smaller of two numbers, by one comparison (see [`max`]). For NaN in either, returns `b`.
pub fn min(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

/// `f32::min` as the Cortex-M4F's `fminf` computes it (x if x < y or y is NaN, else y), inline
/// instead of a call: the same number there, and on the host (see [`max_num`]).
#[inline(always)]
pub fn min_num(x: f32, y: f32) -> f32 {
    if x < y || y.is_nan() {
        x
    } else {
        y
    }
}

/// `f32::max` as the Cortex-M4F's `fmaxf` computes it (y if x < y or x is NaN, else x): the
/// same number on the host, where `f32::max` may pick the other zero of ±0 (a `−0` speed
/// set-point on the host against `0` on the board split their lockstep trajectories).
#[inline(always)]
pub fn max_num(x: f32, y: f32) -> f32 {
    if x < y || x.is_nan() {
        y
    } else {
        x
    }
}

/// Four-quadrant arc tangent (libm; micromath's returns NaN at the origin).
pub fn atan2(y: f32, x: f32) -> f32 {
    libm::atan2f(y, x)
}

/// Sine (see [`sin_cos`]).
pub fn sin(a: f32) -> f32 {
    sin_cos(a).0
}

/// Cosine (see [`sin_cos`]).
pub fn cos(a: f32) -> f32 {
    sin_cos(a).1
}

/// Sine and cosine in single precision: Cody–Waite reduction by π/2 to |r| ≤ π/4, then the
/// Taylor polynomials of sin and cos to degree 9 and 8 (error below 4·10⁻⁷ absolute for
/// |a| ≤ 10⁴ rad, checked against libm in the tests). libm's `sinf`/`cosf` evaluate their
/// kernels in double precision, which is software floating point on the Cortex-M4F.
/// Non-finite input gives (0, 1).
pub fn sin_cos(a: f32) -> (f32, f32) {
    if !a.is_finite() {
        return (0.0, 1.0);
    }
    const FRAC_2_PI: f32 = core::f32::consts::FRAC_2_PI;
    // π/2 split in an 8-bit high part (k·PIO2_HI is exact for |k| < 2¹⁶) and the rest.
    const PIO2_HI: f32 = 1.570_312_5;
    const PIO2_LO: f32 = 4.838_268e-4;
    let k = libm::roundf(a * FRAC_2_PI);
    let r = (a - k * PIO2_HI) - k * PIO2_LO;
    let r2 = r * r;
    let s = r
        * (1.0
            + r2 * (-1.0 / 6.0
                + r2 * (1.0 / 120.0 + r2 * (-1.0 / 5040.0 + r2 * (1.0 / 362_880.0)))));
    let c = 1.0 + r2 * (-0.5 + r2 * (1.0 / 24.0 + r2 * (-1.0 / 720.0 + r2 * (1.0 / 40_320.0))));
    // Quadrant: k mod 4, from the (exactly representable) integer k.
    match (k as i32) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// Wraps an angle to (−π, π].
pub fn wrap_angle(a: f32) -> f32 {
    if !a.is_finite() {
        return 0.0;
    }
    let mut w = libm::remainderf(a, TAU);
    if w <= -PI {
        w += TAU;
    }
    w
}

/// Largest argument [`exp`] accepts; above it the result is clamped (e^88 ≈ 1.65·10³⁸ is the
/// last finite `f32` power of e).
pub const EXP_ARG_MAX: f32 = 88.0;
/// Smallest argument [`exp`] evaluates; below it the result is 0.
pub const EXP_ARG_MIN: f32 = -87.0;

/// e^x for the hot path: Cody–Waite range reduction to 2ⁿ·e^r with |r| ≤ ln2/2 and a
/// degree-6 Taylor polynomial for e^r (relative error below 2·10⁻⁷ over the whole range,
/// checked against libm in the tests). Multiply–adds and one integer shift, no table, no
/// division: the shape that ports to fixed point. Arguments are clamped to
/// [`EXP_ARG_MIN`, `EXP_ARG_MAX`], so the result is always finite and never NaN for finite input;
/// NaN input gives 0.
#[inline(always)]
pub fn exp(x: f32) -> f32 {
    // NaN fails both comparisons and falls to the `else` branch: treated as −∞.
    let x = if x >= EXP_ARG_MIN {
        if x > EXP_ARG_MAX {
            EXP_ARG_MAX
        } else {
            x
        }
    } else {
        return 0.0;
    };
    exp_within(x)
}

/// [`exp`] without its clamps, for a caller that knows its argument lies in
/// [[`EXP_ARG_MIN`], [`EXP_ARG_MAX`]] (the stator PDF's exponents, `field::stator`): there the
/// same number, bit for bit, for five instructions less. Outside that range the result is not
/// e^x (but no panic: the exponent's bits wrap).
#[inline(always)]
pub fn exp_within(x: f32) -> f32 {
    // Round half away from zero with one conversion instruction (x is in range, so it fits).
    let y = x * LOG2E;
    exp_reduced(x, y + if y >= 0.0 { 0.5 } else { -0.5 })
}

/// [`exp_within`] for x ∈ [0, [`EXP_ARG_MAX`]], where x·log₂e ≥ 0 always rounds up by ½: the
/// same number, without the sign test.
#[inline(always)]
pub fn exp_nonnegative(x: f32) -> f32 {
    exp_reduced(x, x * LOG2E + 0.5)
}

/// log₂e, for the range reduction of [`exp`].
const LOG2E: f32 = core::f32::consts::LOG2_E;

/// 2ⁿ·e^r with n = ⌊`half_up`⌋ towards zero (x·log₂e rounded half away from zero) and
/// r = x − n·ln2.
#[inline(always)]
fn exp_reduced(x: f32, half_up: f32) -> f32 {
    // ln2 split in a short high part (exact products with n) and a low correction.
    const LN2_HI: f32 = 0.693_145_75;
    const LN2_LO: f32 = 1.428_606_8e-6;
    let n = half_up as i32 as f32;
    let r = (x - n * LN2_HI) - n * LN2_LO;
    let p = 1.0
        + r * (1.0
            + r * (0.5
                + r * (1.0 / 6.0 + r * (1.0 / 24.0 + r * (1.0 / 120.0 + r * (1.0 / 720.0))))));
    // n ∈ [−126, 127] for x in range, so the biased exponent is a normal one.
    let bits = ((n as i32).wrapping_add(127) as u32) << 23;
    p * f32::from_bits(bits)
}

/// Deterministic pseudo-random bits for the planner's random choices (the ghost goal-point's
/// side ρ, seed 000 eq. 17): xorshift32, seeded from the parameters so runs repeat exactly.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct XorShift32(u32);

impl XorShift32 {
    /// A generator from a seed (0 is mapped to a fixed non-zero state: xorshift needs one).
    pub const fn new(seed: u32) -> Self {
        XorShift32(if seed == 0 { 0x9E37_79B9 } else { seed })
    }

    /// The next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        x
    }

    /// A fair coin.
    pub fn next_bool(&mut self) -> bool {
        self.next_u32() & 0x8000_0000 != 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_matches_libm_across_the_range() {
        let mut worst = 0.0f32;
        let mut x = -80.0f32;
        while x < 88.0 {
            let want = libm::expf(x);
            let got = exp(x);
            assert_eq!(got.to_bits(), exp_within(x).to_bits(), "{x}");
            if x >= 0.0 {
                assert_eq!(got.to_bits(), exp_nonnegative(x).to_bits(), "{x}");
            }
            worst = worst.max(((got - want) / want).abs());
            x += 0.0137;
        }
        assert!(worst < 2e-7 * 4.0, "worst relative error {worst}");
    }

    #[test]
    fn min_num_is_f32_min() {
        let v = [
            f32::NAN,
            -3.0,
            -1.0,
            -0.5,
            0.5,
            1.0,
            2.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        for x in v {
            for y in v {
                let (got, want) = (min_num(x, y), x.min(y));
                assert!(got == want || (got.is_nan() && want.is_nan()), "{x} {y}");
            }
        }
    }

    #[test]
    fn exp_never_overflows_or_returns_nan() {
        for x in [f32::INFINITY, 1e30, 89.0, 200.0] {
            assert!(exp(x).is_finite() && exp(x) > 1e38);
        }
        for x in [f32::NEG_INFINITY, -1e30, -88.0, f32::NAN] {
            assert_eq!(exp(x), 0.0);
        }
    }

    #[test]
    fn sin_cos_match_libm() {
        let mut worst = 0.0f32;
        let mut a = -10_000.0f32;
        while a < 10_000.0 {
            let (s, c) = sin_cos(a);
            worst = worst
                .max((s - libm::sinf(a)).abs())
                .max((c - libm::cosf(a)).abs());
            a += 0.731;
        }
        assert!(worst < 4e-7 * 8.0, "worst error {worst}");
        let mut a = -7.0f32;
        while a < 7.0 {
            let (s, c) = sin_cos(a);
            assert!((s - libm::sinf(a)).abs() < 4e-7, "{a}");
            assert!((c - libm::cosf(a)).abs() < 4e-7, "{a}");
            a += 0.001;
        }
        assert_eq!(sin_cos(f32::NAN), (0.0, 1.0));
    }

    #[test]
    fn wrap_angle_lands_in_half_open_interval() {
        for a in [-10.0f32, -PI, -3.0, 0.0, 3.0, PI, 7.0, 100.0] {
            let w = wrap_angle(a);
            assert!(w > -PI - 1e-6 && w <= PI + 1e-6, "{a} -> {w}");
            assert!((sin(w) - sin(a)).abs() < 1e-3 && (cos(w) - cos(a)).abs() < 1e-3);
        }
    }

    #[test]
    fn bounded_keeps_direction_and_limits_modulus() {
        let v = Vec2::new(3.0, 4.0).bounded(1.0);
        assert!((v.norm() - 1.0).abs() < 1e-6);
        assert!((v.x / v.y - 0.75).abs() < 1e-6);
        assert_eq!(Vec2::new(0.3, 0.4).bounded(1.0), Vec2::new(0.3, 0.4));
    }

    #[test]
    fn xorshift_repeats_for_a_seed_and_gives_both_sides() {
        let mut a = XorShift32::new(7);
        let mut b = XorShift32::new(7);
        let bits: [bool; 64] = core::array::from_fn(|_| a.next_bool());
        let again: [bool; 64] = core::array::from_fn(|_| b.next_bool());
        assert_eq!(bits, again);
        assert!(bits.iter().any(|&x| x) && bits.iter().any(|&x| !x));
    }
}
