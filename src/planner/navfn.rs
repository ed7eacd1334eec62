//! Rimon–Koditschek navigation functions on a sphere world (seed 004, lectures 22–23, the
//! "sphere world" slides: obstacle functions β_i, distance-to-goal γ_κ, and φ_κ).
//!
//! A *sphere world* is a disc workspace (obstacle 0 is the complement of the disc of centre q_0
//! and radius ρ_0) holding M disjoint disc obstacles (q_j, ρ_j). Seed 004 defines
//!
//! - β_0(q) = ρ_0² − ‖q − q_0‖²,  β_j(q) = ‖q − q_j‖² − ρ_j²  (j = 1..M),  β = ∏_{i=0}^{M} β_i;
//! - γ_κ(q) = ‖q − q_d‖^{2κ};
//! - φ_κ(q) = ‖q − q_d‖² / (‖q − q_d‖^{2κ} + β(q))^{1/κ}  (= ρ_κ ∘ σ_1 ∘ φ̂, φ̂ = γ_κ/β),
//!
//! which is 0 at the goal q_d, 1 on every obstacle boundary, and (for κ large enough) has the
//! goal as its only minimum. The notes' rule of thumb is κ > M + 1 ([`kappa`]).
//!
//! # Numerics (our choices; the notes are silent)
//!
//! **Normalised coordinates.** Everything is evaluated in x = (q − q_0)/ρ_0, the workspace
//! becoming the unit disc: β̃_0 = 1 − ‖x‖², β̃_j = ‖x − x_j‖² − (ρ_j/ρ_0)². φ_κ is then
//! independent of the unit of length. In metres φ would differ only by the constant factor
//! ρ_0^{2(κ−M−1)} inside φ̂ = γ/β; σ_1 and ρ_κ are strictly increasing, so the interior critical
//! points — the goal, the saddles, any spurious minimum — and the level sets' order are the
//! same: only the profile of the values between 0 and 1 changes.
//!
//! **No products, only logs.** With M = 40 and κ = 42, ‖x − x_d‖^{2κ} and ∏β_i over- and underflow
//! `f32`. With every β_i > 0 (the free space), ∇β = β·Σ_i ∇β_i/β_i, and differentiating φ_κ:
//!
//! ∇φ = 2(q−q_d)(γ+β)^{−1/κ} − (d²/κ)(γ+β)^{−1/κ−1}(∇γ + ∇β),  ∇γ = 2κ d^{2κ−2}(q−q_d), d = ‖q−q_d‖
//!    = (γ+β)^{−1/κ−1}·[2(q−q_d)(γ+β) − 2γ(q−q_d) − (d²/κ)∇β]
//!    = (γ+β)^{−1/κ−1}·β·[2(q−q_d) − (d²/κ)·Σ_i ∇β_i/β_i].
//!
//! The bracket, the **direction**, needs neither γ nor β. We scale it by m = min_i β_i (so each
//! weight m/β_i is in (0, 1] and nothing overflows however close an obstacle is):
//! v = 2m(x − x_d) − (d²/κ)·Σ_i (m/β_i)∇β_i, and ∇φ = v·β(γ+β)^{−1/κ−1}/m. The **magnitude**
//! comes from logarithms: ln β = Σ ln β_i (a product of frexp mantissas with the exponents summed,
//! one `logf` at the end), ln γ = κ ln d², ln(γ+β) by log-sum-exp, and
//! ln‖∇_qφ‖ = ln β − ln m − (1 + 1/κ) ln(γ+β) + ln‖v‖ − ln ρ_0.
//! φ itself is exp(ln d² − ln(γ+β)/κ).
//!
//! # Policies (our choices)
//!
//! - **q outside the workspace or inside a circle** (β_i(q) ≤ 0, the closed obstacle set of
//!   seed 004): [`NavfnError::OutsideWorkspace`] / [`NavfnError::InsideObstacle`]; φ is not
//!   defined there. [`SphereWorld::escape_direction`] gives the way out: ∇β_i/‖∇β_i‖ of the
//!   violated obstacle functions, summed.
//! - **Goal inside (or on) a circle, or not strictly inside the workspace**: the circle is kept
//!   (it may hold a real obstacle), and every evaluation answers [`NavfnError::GoalBlocked`] —
//!   no navigation function to that goal exists, since φ(q_d) = 0 needs β(q_d) > 0.
//! - **Overlapping circles**: [`SphereWorld::push`] stores them as given. φ is still 1 on every
//!   boundary and < 1 in the free space, so descent never collides, but the theorem's hypothesis
//!   (disjoint closures) fails and a spurious minimum may appear in the crevice.
//!   [`SphereWorld::push_merged`] restores a sphere world by replacing intersecting circles with
//!   the smallest circle holding both; [`SphereWorld::is_sphere_world`] reports whether the
//!   hypotheses hold.
//! - **A circle crossing the workspace boundary**: kept as given (it cannot be merged with the
//!   boundary); the same remark holds: collision-free descent, convergence not guaranteed.
//!
//!
//! # For the integrator: turning −∇φ into a bounded force
//!
//! - **Magnitude.** Near the goal φ ≈ ‖q − q_d‖²/(ρ_0² β̃(q_d)^{1/κ}), so ‖∇φ‖ ≈
//!   2‖q − q_d‖/(ρ_0² β̃(q_d)^{1/κ}): linear, → 0 at q_d. Away from the goal, where γ ≫ β, φ is
//!   a plateau just below 1 and ‖∇φ‖ ≈ β/(κγ)·‖∇β/β‖ is tiny: over random free points it spans
//!   e^−45 … e^−1 1/m (40 circles, ρ_0 = 500 m) — far too many decades to scale a force by.
//!   Next to an obstacle close to the goal it can be large (β/γ big). So steer by the
//!   direction ([`SphereWorld::descent_direction`], exact even on the plateau, since it holds
//!   neither γ nor β) and choose the speed separately, e.g. min(v_max, k·‖q − q_d‖).
//! - **Discretisation.** The continuous flow q̇ = −∇φ never reaches a boundary (φ < 1 inside, 1
//!   on it). A discrete step must stay below the clearance: the direction turns away within
//!   about ρ_0‖x − x_d‖/(2κ) of an obstacle (where the attraction 2(x − x_d) balances the
//!   repulsion), so with large κ a fixed 0.5 m step can jump in (seen at κ ≥ 2M, 40 circles,
//!   ρ_0 = 300 m). Bounding the step by half of [`SphereWorld::clearance`] removed every such
//!   collision in the tests.
//! - **κ.** The rule of thumb κ = M + 2 reached the goal from all 200 starts in 10 worlds of
//!   3–8 circles (ρ_0 = 100 m). With the full table (40 circles, ρ_0 = 500 m) it left genuine
//!   spurious minima (10 of 40 starts in one world; 1–4 of 40 in each of four others); κ = 1.5·M
//!   removed them there. No κ is universal (seed 004: N depends on the geometry), and too large
//!   a κ makes the field turn abruptly (seed 004's warning): a stall detector is still needed.
//! - **Cost** per evaluation, M circles: 2(M+1) squared norms, M+1 divisions and 2(M+1)
//!   `frexpf` (bit operations), one square root, then 5 `logf`, 1 `log1pf` and 3
//!   [`crate::math::exp`]. [`SphereWorld::descent_direction`] is the same two passes and the
//!   square root, without any of the transcendental functions.

use heapless::Vec;

use crate::field::Shape;
use crate::math::{exp, max, min, Vec2};

/// Most disc obstacles a [`SphereWorld`] holds: the 32 table obstacles plus 8 other vehicles.
pub const MAX_SPHERES: usize = 40;

/// Smallest κ accepted. ρ_κ(x) = x^{1/κ} of seed 004 is the "distortion" making q_d a
/// nondegenerate minimum for κ ≥ 1; below 1, φ would no longer be smooth at the goal.
pub const MIN_KAPPA: f32 = 1.0;

/// Why a sphere world or an evaluation was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NavfnError {
    /// [`MAX_SPHERES`] circles are already stored; the new one was not (the caller counts it).
    Full,
    /// An input coordinate, radius or κ is NaN or infinite, or an intermediate overflowed.
    NonFinite,
    /// q is on or outside the workspace boundary (β_0(q) ≤ 0).
    OutsideWorkspace,
    /// q is in or on circle `index` (β_j(q) ≤ 0; index into the table, 0-based, boundary not
    /// counted). [`SphereWorld::escape_direction`] gives the way out.
    InsideObstacle(u8),
    /// The goal is in or on a circle, or not strictly inside the workspace: φ is undefined.
    GoalBlocked,
    /// A radius is not strictly positive.
    InvalidRadius,
    /// κ is below [`MIN_KAPPA`].
    InvalidKappa,
}

impl core::fmt::Display for NavfnError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            NavfnError::Full => f.write_str("sphere world full"),
            NavfnError::NonFinite => f.write_str("a number is not finite"),
            NavfnError::OutsideWorkspace => f.write_str("outside the workspace"),
            NavfnError::InsideObstacle(i) => write!(f, "inside obstacle circle {i}"),
            NavfnError::GoalBlocked => {
                f.write_str("goal inside an obstacle or outside the workspace")
            }
            NavfnError::InvalidRadius => f.write_str("radius not strictly positive"),
            NavfnError::InvalidKappa => f.write_str("kappa below its minimum"),
        }
    }
}

impl core::error::Error for NavfnError {}

/// The circle enclosing a table shape, for the sphere world: the shape's own
/// [`Shape::center`] and [`Shape::bounding_radius`] (seed 004 models obstacles as discs; the
/// enclosure is our choice). Circle → itself; rectangle → its centre and half-diagonal;
/// ellipse → its centre and semi-major axis; convex polygon → the vertex average and the
/// farthest vertex from it (not always the smallest enclosing circle, but always enclosing).
/// The caller adds its margin (the vehicle's radius) to the radius.
pub fn enclosing_circle(shape: &Shape) -> (Vec2, f32) {
    (shape.center(), shape.bounding_radius())
}

/// κ for `obstacles` circles by seed 004's rule of thumb "κ > number of obstacles + 1": κ = M + 2
/// (the workspace boundary is not counted in M). A finite `set` > 0 overrides it, raised to
/// [`MIN_KAPPA`].
pub fn kappa(set: f32, obstacles: usize) -> f32 {
    if set.is_finite() && set > 0.0 {
        max(set, MIN_KAPPA)
    } else {
        obstacles.min(1 << 20) as f32 + 2.0
    }
}

/// A disc obstacle, with its squared radius in normalised coordinates cached.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Sphere {
    center: Vec2,
    radius: f32,
    /// (ρ_j/ρ_0)².
    r2n: f32,
}

/// One evaluation of the navigation function at a free point.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NavEval {
    /// φ_κ(q) ∈ [0, 1].
    pub value: f32,
    /// −∇φ/‖∇φ‖, the unit descent direction; zero at the goal or at a critical point (saddle).
    pub descent: Vec2,
    /// ‖∇φ_κ(q)‖, 1/m (underflows to 0 where φ is flat; clamped at ≈ 1.7·10³⁸).
    pub grad_norm: f32,
    /// ln‖∇φ_κ(q)‖ (ln of 1/m), exact even where `grad_norm` underflows; −∞ at the goal or at a
    /// critical point.
    pub ln_grad_norm: f32,
}

/// The sphere world of seed 004: workspace disc, goal, κ and up to [`MAX_SPHERES`] disc
/// obstacles. Build it once per planning period (or keep it and [`SphereWorld::clear`] it).
#[derive(Clone, Debug)]
pub struct SphereWorld {
    center: Vec2,
    radius: f32,
    inv_radius: f32,
    ln_radius: f32,
    goal: Vec2,
    kappa: f32,
    spheres: Vec<Sphere, MAX_SPHERES>,
    goal_blocked: bool,
}

/// Unit vector along `v` and its length as a·n (a = the largest |component|, n ∈ [1, √2]), robust
/// to subnormal components; `None` for the zero vector or non-finite input.
fn unit_scaled(v: Vec2) -> Option<(Vec2, f32, f32)> {
    let a = max(v.x.abs(), v.y.abs());
    if !(a > 0.0 && a.is_finite()) {
        return None;
    }
    // Divide (not multiply by 1/a, which overflows for subnormal a): components in [−1, 1].
    let u = Vec2::new(v.x / a, v.y / a);
    let n = u.norm();
    Some((u * (1.0 / n), a, n))
}

/// ln(eᵃ + eᵇ), stable.
fn log_sum_exp(a: f32, b: f32) -> f32 {
    let hi = max(a, b);
    let lo = min(a, b);
    hi + libm::log1pf(exp(lo - hi))
}

/// The smallest circle holding both circles (they are assumed to intersect or touch), radius
/// grown by 10⁻⁶ relative so rounding never leaves a sliver of either outside.
fn enclose(a: (Vec2, f32), b: (Vec2, f32)) -> (Vec2, f32) {
    let d = (b.0 - a.0).norm();
    if d + b.1 <= a.1 {
        return a;
    }
    if d + a.1 <= b.1 {
        return b;
    }
    // Neither contains the other, so d > 0.
    let r = 0.5 * (d + a.1 + b.1);
    (a.0 + (b.0 - a.0) * ((r - a.1) / d), r * (1.0 + 1e-6))
}

/// Pass-one results at a free point.
struct Core {
    /// ‖x − x_d‖².
    d2: f32,
    /// The descent-direction bracket scaled by m (see the module doc): ∇φ ∝ +v.
    v: Vec2,
    /// m = min_i β̃_i.
    m: f32,
    /// β̃ = ∏ β̃_i = `mant`·2^`expo`, `mant` ∈ [0.5, 1).
    mant: f32,
    /// See `mant`.
    expo: i32,
}

impl SphereWorld {
    /// A sphere world with workspace disc (`center`, `radius`), goal q_d and κ (see [`kappa`]),
    /// and no circles yet. Errors: [`NavfnError::NonFinite`], [`NavfnError::InvalidRadius`]
    /// (radius ≤ 0, or so small its inverse overflows), [`NavfnError::InvalidKappa`] (κ <
    /// [`MIN_KAPPA`]), [`NavfnError::GoalBlocked`] (goal not strictly inside the workspace).
    pub fn new(center: Vec2, radius: f32, goal: Vec2, kappa: f32) -> Result<Self, NavfnError> {
        if !(center.is_finite() && radius.is_finite() && goal.is_finite() && kappa.is_finite()) {
            return Err(NavfnError::NonFinite);
        }
        let inv_radius = 1.0 / radius;
        if !(radius > 0.0 && inv_radius.is_finite()) {
            return Err(NavfnError::InvalidRadius);
        }
        if kappa < MIN_KAPPA {
            return Err(NavfnError::InvalidKappa);
        }
        let mut w = SphereWorld {
            center,
            radius,
            inv_radius,
            ln_radius: libm::logf(radius),
            goal,
            kappa,
            spheres: Vec::new(),
            goal_blocked: false,
        };
        w.set_goal(goal)?;
        Ok(w)
    }

    /// Moves the goal (circles kept). [`NavfnError::GoalBlocked`] when it is not strictly inside
    /// the workspace — then the goal is still set, and evaluations answer `GoalBlocked` until a
    /// valid goal is set. A goal inside a circle is accepted here and reported by the
    /// evaluations and [`SphereWorld::goal_blocked`].
    pub fn set_goal(&mut self, goal: Vec2) -> Result<(), NavfnError> {
        if !goal.is_finite() {
            return Err(NavfnError::NonFinite);
        }
        self.goal = goal;
        self.goal_blocked = self.spheres.iter().any(|s| self.blocks_goal(s));
        if self.beta0(goal) > 0.0 {
            Ok(())
        } else {
            self.goal_blocked = true;
            Err(NavfnError::GoalBlocked)
        }
    }

    /// Sets κ (≥ [`MIN_KAPPA`], finite).
    pub fn set_kappa(&mut self, kappa: f32) -> Result<(), NavfnError> {
        if !kappa.is_finite() {
            Err(NavfnError::NonFinite)
        } else if kappa < MIN_KAPPA {
            Err(NavfnError::InvalidKappa)
        } else {
            self.kappa = kappa;
            Ok(())
        }
    }

    /// Removes every circle (workspace, goal and κ kept).
    pub fn clear(&mut self) {
        self.spheres.clear();
        self.goal_blocked = self.beta0(self.goal) <= 0.0;
    }

    /// Adds the disc obstacle (`center`, `radius`) as given: β_j of seed 004. Errors:
    /// [`NavfnError::NonFinite`], [`NavfnError::InvalidRadius`] (≤ 0), [`NavfnError::Full`]
    /// (nothing stored). A circle holding the goal is stored (see the module doc).
    pub fn push(&mut self, center: Vec2, radius: f32) -> Result<(), NavfnError> {
        let s = self.sphere(center, radius)?;
        self.spheres.push(s).map_err(|_| NavfnError::Full)?;
        self.goal_blocked |= self.blocks_goal(&s);
        Ok(())
    }

    /// Adds the disc obstacle, first merging it with every stored circle whose closure it meets
    /// (repeatedly: the merged circle may meet others) into the smallest circle holding both,
    /// so the circles stay pairwise disjoint as seed 004's sphere world requires. Merging
    /// shrinks the free space (conservative; the vehicle may find itself inside a merged circle:
    /// [`SphereWorld::escape_direction`]); indices of stored circles may change. Errors as
    /// [`SphereWorld::push`]; `Full` only when no merge happened and the table is full (then
    /// nothing changed).
    pub fn push_merged(&mut self, center: Vec2, radius: f32) -> Result<(), NavfnError> {
        let mut c = self.sphere(center, radius)?;
        // Each merge removes one stored circle, so this terminates within len + 1 rounds.
        for _ in 0..=MAX_SPHERES {
            let hit = self
                .spheres
                .iter()
                .position(|s| (s.center - c.center).norm() <= s.radius + c.radius);
            let Some(i) = hit else { break };
            let Some(s) = self.spheres.get(i).copied() else {
                break;
            };
            let (mc, mr) = enclose((s.center, s.radius), (c.center, c.radius));
            // Validate before removing, so no obstacle is ever lost: should the merged circle
            // be unrepresentable (radii near f32's range), the overlap is left as it is.
            let Ok(merged) = self.sphere(mc, mr) else {
                break;
            };
            crate::world::swap_remove(&mut self.spheres, i);
            c = merged;
        }
        self.spheres.push(c).map_err(|_| NavfnError::Full)?;
        self.goal_blocked =
            self.beta0(self.goal) <= 0.0 || self.spheres.iter().any(|s| self.blocks_goal(s));
        Ok(())
    }

    /// Number of circles (M; the workspace boundary is not counted).
    pub fn len(&self) -> usize {
        self.spheres.len()
    }

    /// No circles.
    pub fn is_empty(&self) -> bool {
        self.spheres.is_empty()
    }

    /// The circles (centre, radius), m, in table order (the order of `InsideObstacle` indices).
    pub fn spheres(&self) -> impl Iterator<Item = (Vec2, f32)> + '_ {
        self.spheres.iter().map(|s| (s.center, s.radius))
    }

    /// The goal q_d, m.
    pub fn goal(&self) -> Vec2 {
        self.goal
    }

    /// κ.
    pub fn kappa(&self) -> f32 {
        self.kappa
    }

    /// The goal is in or on a circle or not strictly inside the workspace: evaluations answer
    /// [`NavfnError::GoalBlocked`].
    pub fn goal_blocked(&self) -> bool {
        self.goal_blocked
    }

    /// Seed 004's sphere-world hypotheses hold: every circle's closure strictly inside the
    /// workspace, closures pairwise disjoint, goal free. When false, descent of φ still never
    /// collides (φ < 1 inside, = 1 on boundaries) but may stop at a spurious minimum. O(M²).
    pub fn is_sphere_world(&self) -> bool {
        if self.goal_blocked {
            return false;
        }
        let inside = self
            .spheres
            .iter()
            .all(|s| (s.center - self.center).norm() + s.radius < self.radius);
        let disjoint = self.spheres.iter().enumerate().all(|(i, a)| {
            self.spheres
                .iter()
                .skip(i + 1)
                .all(|b| (a.center - b.center).norm() > a.radius + b.radius)
        });
        inside && disjoint
    }

    /// φ_κ(q) ∈ [0, 1] (seed 004, the navigation function slide), evaluated in logs (module doc).
    pub fn value(&self, q: Vec2) -> Result<f32, NavfnError> {
        self.eval(q).map(|e| e.value)
    }

    /// ∇φ_κ(q), 1/m, by the γ-free form ∇φ = β(γ+β)^{−1/κ−1}[2(q−q_d) − (d²/κ)Σ∇β_i/β_i]
    /// (module doc). Finite everywhere in the free space; zero at the goal. Its magnitude spans
    /// many decades (see [`NavEval::ln_grad_norm`]); steer by [`SphereWorld::descent_direction`].
    pub fn gradient(&self, q: Vec2) -> Result<Vec2, NavfnError> {
        self.eval(q).map(|e| e.descent * -e.grad_norm)
    }

    /// −∇φ_κ(q)/‖∇φ_κ(q)‖, the unit descent direction, from the bracket alone: no logarithm, no
    /// exponential (module doc). Zero at the goal and at critical points (saddles: the planner
    /// perturbs off them, `Planner::plan_navfn` in `strategy.rs`).
    pub fn descent_direction(&self, q: Vec2) -> Result<Vec2, NavfnError> {
        let c = self.core(q)?;
        Ok(unit_scaled(c.v).map_or(Vec2::ZERO, |(u, _, _)| -u))
    }

    /// φ, ∇φ direction and magnitude in one pass.
    pub fn eval(&self, q: Vec2) -> Result<NavEval, NavfnError> {
        let c = self.core(q)?;
        let at_goal = NavEval {
            value: 0.0,
            descent: Vec2::ZERO,
            grad_norm: 0.0,
            ln_grad_norm: f32::NEG_INFINITY,
        };
        if c.d2 <= 0.0 {
            return Ok(at_goal);
        }
        let ln_beta = libm::logf(c.mant) + c.expo as f32 * core::f32::consts::LN_2;
        let ln_d2 = libm::logf(c.d2);
        // ln(γ + β), γ = d^{2κ}.
        let ln_sum = log_sum_exp(self.kappa * ln_d2, ln_beta);
        let inv_k = 1.0 / self.kappa;
        let value = min(exp(ln_d2 - ln_sum * inv_k), 1.0);
        let (descent, ln_grad_norm) = match unit_scaled(c.v) {
            Some((u, a, n)) => (
                -u,
                ln_beta - libm::logf(c.m) - (1.0 + inv_k) * ln_sum + libm::logf(a) + libm::logf(n)
                    - self.ln_radius,
            ),
            None => (Vec2::ZERO, f32::NEG_INFINITY),
        };
        let grad_norm = if descent == Vec2::ZERO {
            0.0
        } else {
            exp(ln_grad_norm)
        };
        if !(value.is_finite() && grad_norm.is_finite() && !ln_grad_norm.is_nan()) {
            return Err(NavfnError::NonFinite);
        }
        Ok(NavEval {
            value,
            descent,
            grad_norm,
            ln_grad_norm,
        })
    }

    /// The way out of the obstacle sets q is in: the sum of the unit outward directions
    /// ∇β_i/‖∇β_i‖ (toward the workspace centre for the boundary, away from the centre for a
    /// circle) of every violated β_i ≤ 0, normalised. At a circle's very centre, where ∇β_j = 0,
    /// the direction toward the goal is taken (it leaves the circle when the goal is outside
    /// it), else +x. `None` when q is free (no escape needed), non-finite, or the directions
    /// cancel exactly.
    pub fn escape_direction(&self, q: Vec2) -> Option<Vec2> {
        if !q.is_finite() {
            return None;
        }
        let mut sum = Vec2::ZERO;
        let mut any = false;
        if self.beta0(q) <= 0.0 {
            any = true;
            sum += (self.center - q).normalized(0.0).unwrap_or(Vec2::ZERO);
        }
        for s in self.spheres.iter() {
            if self.beta_j(s, q) <= 0.0 {
                any = true;
                let out = (q - s.center)
                    .normalized(0.0)
                    .or_else(|| (self.goal - s.center).normalized(0.0))
                    .unwrap_or(Vec2::new(1.0, 0.0));
                sum += out;
            }
        }
        if any {
            sum.normalized(1e-6)
        } else {
            None
        }
    }

    /// Signed distance from q to the nearest obstacle set, m: min(ρ_0 − ‖q − q_0‖,
    /// min_j ‖q − q_j‖ − ρ_j); negative inside one, NaN for non-finite q. Not part of seed 004:
    /// it bounds the integrator's step (move less than the clearance per step, see the module
    /// doc), one square root per circle.
    pub fn clearance(&self, q: Vec2) -> f32 {
        let boundary = self.radius - (q - self.center).norm();
        self.spheres
            .iter()
            .fold(boundary, |c, s| min(c, (q - s.center).norm() - s.radius))
    }

    // ---- internals ----

    fn sphere(&self, center: Vec2, radius: f32) -> Result<Sphere, NavfnError> {
        if !(center.is_finite() && radius.is_finite()) {
            return Err(NavfnError::NonFinite);
        }
        if radius <= 0.0 {
            return Err(NavfnError::InvalidRadius);
        }
        let rn = radius * self.inv_radius;
        let r2n = rn * rn;
        if !r2n.is_finite() {
            return Err(NavfnError::NonFinite);
        }
        Ok(Sphere {
            center,
            radius,
            r2n,
        })
    }

    /// β̃_0(q) = 1 − ‖(q − q_0)/ρ_0‖² (seed 004, obstacle functions, normalised).
    fn beta0(&self, q: Vec2) -> f32 {
        1.0 - ((q - self.center) * self.inv_radius).norm2()
    }

    /// β̃_j(q) = ‖(q − q_j)/ρ_0‖² − (ρ_j/ρ_0)² (seed 004, obstacle functions, normalised).
    fn beta_j(&self, s: &Sphere, q: Vec2) -> f32 {
        ((q - s.center) * self.inv_radius).norm2() - s.r2n
    }

    fn blocks_goal(&self, s: &Sphere) -> bool {
        self.beta_j(s, self.goal) <= 0.0
    }

    /// (β̃_i, ∇_x β̃_i) for i = 0 (boundary), 1..M, at normalised point x.
    fn terms(&self, q: Vec2) -> impl Iterator<Item = (f32, Vec2)> + '_ {
        let x = (q - self.center) * self.inv_radius;
        core::iter::once((1.0 - x.norm2(), x * -2.0)).chain(self.spheres.iter().map(move |s| {
            let y = (q - s.center) * self.inv_radius;
            (y.norm2() - s.r2n, y * 2.0)
        }))
    }

    /// Checks q, and computes the scaled bracket, m and ln β (module doc).
    fn core(&self, q: Vec2) -> Result<Core, NavfnError> {
        if !q.is_finite() {
            return Err(NavfnError::NonFinite);
        }
        if self.goal_blocked {
            return Err(NavfnError::GoalBlocked);
        }
        // Pass 1: free-space check, m = min β̃_i, β̃ as mantissa product and exponent sum.
        let mut m = f32::INFINITY;
        let mut mant = 1.0f32;
        let mut expo = 0i32;
        for (i, (b, _)) in self.terms(q).enumerate() {
            if !b.is_finite() {
                return Err(NavfnError::NonFinite);
            }
            if b <= 0.0 {
                return Err(match i {
                    0 => NavfnError::OutsideWorkspace,
                    j => NavfnError::InsideObstacle(u8::try_from(j - 1).unwrap_or(u8::MAX)),
                });
            }
            m = min(m, b);
            let (bm, be) = libm::frexpf(b); // b = bm·2^be, bm ∈ [0.5, 1)
            let (pm, pe) = libm::frexpf(mant * bm);
            mant = pm;
            expo = expo.saturating_add(be).saturating_add(pe);
        }
        // Pass 2: Σ (m/β̃_i) ∇β̃_i, each weight in (0, 1].
        let s = self
            .terms(q)
            .fold(Vec2::ZERO, |acc, (b, g)| acc + g * (m / b));
        let e = (q - self.goal) * self.inv_radius;
        let d2 = e.norm2();
        let v = e * (2.0 * m) - s * (d2 / self.kappa);
        if !v.is_finite() {
            return Err(NavfnError::NonFinite);
        }
        Ok(Core {
            d2,
            v,
            m,
            mant,
            expo,
        })
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::math::XorShift32;
    use std::println;
    use std::vec::Vec as StdVec;

    fn uniform(rng: &mut XorShift32, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * ((rng.next_u32() >> 8) as f32 / 16_777_216.0)
    }

    fn in_disc(rng: &mut XorShift32, c: Vec2, r: f32) -> Vec2 {
        loop {
            let p = Vec2::new(uniform(rng, -r, r), uniform(rng, -r, r));
            if p.norm2() < r * r {
                return c + p;
            }
        }
    }

    fn clearance(w: &SphereWorld, q: Vec2) -> f32 {
        w.clearance(q)
    }

    /// A random sphere world: workspace radius `ws` at an offset centre, `n` circles of
    /// radius `r_lo..r_hi`, clear of the goal, the boundary and each other by `gap` metres.
    fn random_world(
        rng: &mut XorShift32,
        ws: f32,
        n: usize,
        (r_lo, r_hi): (f32, f32),
        gap: f32,
        kappa_set: f32,
    ) -> SphereWorld {
        let c0 = Vec2::new(uniform(rng, -300.0, 300.0), uniform(rng, -300.0, 300.0));
        let goal = in_disc(rng, c0, 0.7 * ws);
        let mut w = SphereWorld::new(c0, ws, goal, kappa(kappa_set, n)).unwrap();
        let mut tries = 0;
        while w.len() < n && tries < 100_000 {
            tries += 1;
            let r = uniform(rng, r_lo, r_hi);
            let p = in_disc(rng, c0, ws - r - gap);
            let clear_goal = (p - goal).norm() >= r + gap;
            let clear_others = w.spheres().all(|(q, s)| (p - q).norm() >= r + s + gap);
            if clear_goal && clear_others {
                w.push(p, r).unwrap();
            }
        }
        assert_eq!(w.len(), n, "could not place {n} circles");
        assert!(w.is_sphere_world());
        w
    }

    fn random_free(rng: &mut XorShift32, w: &SphereWorld, min_clear: f32) -> Vec2 {
        loop {
            let q = in_disc(rng, w.center, w.radius);
            if clearance(w, q) > min_clear && (q - w.goal).norm() > 1.0 {
                return q;
            }
        }
    }

    struct Run {
        reached: bool,
        steps: usize,
        min_clear: f32,
        final_dist: f32,
    }

    /// Bounded-speed gradient descent q ← q + h·(−∇φ/‖∇φ‖), h = min(h_max, ‖q − q_d‖): the
    /// speed saturates at h_max per step far away and falls linearly to zero at the goal,
    /// as ‖∇φ‖ does near q_d.
    fn descend(w: &SphereWorld, start: Vec2, h_max: f32, max_steps: usize) -> Run {
        descend_guarded(w, start, h_max, max_steps, false)
    }

    /// As [`descend`]; with `guard`, the step is also at most half the clearance.
    fn descend_guarded(
        w: &SphereWorld,
        start: Vec2,
        h_max: f32,
        max_steps: usize,
        guard: bool,
    ) -> Run {
        let mut q = start;
        let mut min_clear = clearance(w, q);
        for k in 0..max_steps {
            let dist = (q - w.goal).norm();
            if dist < 0.05 {
                return Run {
                    reached: true,
                    steps: k,
                    min_clear,
                    final_dist: dist,
                };
            }
            let d = match w.descent_direction(q) {
                Ok(d) => d,
                Err(_) => {
                    return Run {
                        reached: false,
                        steps: k,
                        min_clear: clearance(w, q),
                        final_dist: dist,
                    };
                }
            };
            let h = if guard {
                h_max.min(0.5 * clearance(w, q))
            } else {
                h_max
            };
            q += d * h.min(dist);
            min_clear = min_clear.min(clearance(w, q));
        }
        let final_dist = (q - w.goal).norm();
        Run {
            reached: final_dist < 0.5,
            steps: max_steps,
            min_clear,
            final_dist,
        }
    }

    #[test]
    fn goal_is_zero_and_values_in_unit_interval() {
        let mut rng = XorShift32::new(11);
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for _ in 0..10 {
            let w = random_world(&mut rng, 100.0, 8, (3.0, 12.0), 2.0, 0.0);
            assert_eq!(w.value(w.goal()).unwrap(), 0.0);
            assert_eq!(w.gradient(w.goal()).unwrap(), Vec2::ZERO);
            for _ in 0..200 {
                let q = random_free(&mut rng, &w, 1e-3);
                let e = w.eval(q).unwrap();
                lo = lo.min(e.ln_grad_norm);
                hi = hi.max(e.ln_grad_norm);
                assert!((0.0..=1.0).contains(&e.value), "{e:?}");
                assert!(e.grad_norm.is_finite() && e.descent.is_finite());
                assert!((e.descent.norm() - 1.0).abs() < 1e-5);
            }
        }
        println!("M = 8, κ = 10, ρ_0 = 100 m: ln‖∇φ‖ from {lo:.1} to {hi:.1} (1/m)");
    }

    #[test]
    fn value_tends_to_one_on_every_boundary() {
        // Goal at the centre, four circles 40 m out, κ = M + 2.
        let c0 = Vec2::new(120.0, -40.0);
        let mut w = SphereWorld::new(c0, 100.0, c0, kappa(0.0, 4)).unwrap();
        for k in 0..4 {
            let a = k as f32 * 1.5;
            w.push(c0 + Vec2::from_angle(a) * 40.0, 5.0 + 2.0 * k as f32)
                .unwrap();
        }
        // (point on the boundary, outward unit normal into the free space)
        let mut probes: StdVec<(Vec2, Vec2)> = StdVec::new();
        for k in 0..8 {
            let n = Vec2::from_angle(0.3 + k as f32 * 0.8);
            probes.push((c0 + n * 100.0, -n));
        }
        for (p, r) in w.spheres() {
            for k in 0..8 {
                let n = Vec2::from_angle(k as f32 * 0.8);
                probes.push((p + n * r, n));
            }
        }
        // Near a boundary 1 − φ ≈ β/(κγ) ∝ δ, the clearance: it must fall about tenfold per
        // decade of δ, down to f32's resolution of φ (≈ 1e-7).
        let mut worst = 0.0f32;
        for (b, n) in probes {
            let mut last = 0.0;
            let mut gap = 1.0f32;
            for delta in [3.0f32, 1.0, 0.1, 0.01, 1e-3, 1e-4] {
                let v = w.value(b + n * delta).unwrap();
                assert!(
                    v >= last - 1e-6,
                    "φ not increasing toward the boundary: {v} < {last}"
                );
                if delta <= 1e-3 && gap > 1e-5 {
                    assert!(
                        1.0 - v < 0.3 * gap,
                        "1 − φ = {} at δ = {delta} m from {b:?}",
                        1.0 - v
                    );
                }
                gap = 1.0 - v;
                last = v;
            }
            worst = worst.max(1.0 - last);
        }
        println!("1 − φ at 0.1 mm from a boundary: at most {worst:.1e}");
        assert!(worst < 5e-3);
        // On and beyond the boundary: refused.
        assert_eq!(
            w.value(c0 + Vec2::new(100.5, 0.0)),
            Err(NavfnError::OutsideWorkspace)
        );
        let (p1, r1) = w.spheres().nth(1).unwrap();
        assert_eq!(
            w.value(p1 + Vec2::new(0.0, r1 * 0.5)),
            Err(NavfnError::InsideObstacle(1))
        );
    }

    #[test]
    fn gradient_matches_central_differences() {
        let mut rng = XorShift32::new(7);
        let (mut checked_fd, mut checked_log) = (0, 0);
        let mut worst_fd = 0.0f32;
        let mut worst_log = 0.0f32;
        for world in 0..10 {
            let n = 3 + world % 6;
            let w = random_world(&mut rng, 100.0, n, (3.0, 12.0), 2.0, 0.0);
            let k = w.kappa();
            for _ in 0..100 {
                let q = random_free(&mut rng, &w, 0.5);
                let e = w.eval(q).unwrap();
                let g = w.gradient(q).unwrap();
                // (a) Central differences of `value` (f32: meaningful where ‖∇φ‖·h ≫ 1e-6).
                let h = 0.01;
                let dx = Vec2::new(h, 0.0);
                let dy = Vec2::new(0.0, h);
                let fd = Vec2::new(
                    (w.value(q + dx).unwrap() - w.value(q - dx).unwrap()) / (2.0 * h),
                    (w.value(q + dy).unwrap() - w.value(q - dy).unwrap()) / (2.0 * h),
                );
                if g.norm() > 2e-3 {
                    let rel = (fd - g).norm() / g.norm();
                    worst_fd = worst_fd.max(rel);
                    checked_fd += 1;
                    assert!(rel < 0.02, "FD {fd:?} vs analytic {g:?} at {q:?}");
                }
                // (b) Everywhere, flat regions included: ∇φ = (φ/κ)·β/(γ+β)·∇ln φ̂,
                // φ̂ = γ/β, with ln φ̂ = κ ln d² − Σ ln β_i differenced in f32 (well conditioned).
                let ln_hat = |p: Vec2| {
                    let d2 = ((p - w.goal) * w.inv_radius).norm2();
                    k * libm::logf(d2) - w.terms(p).map(|(b, _)| libm::logf(b)).sum::<f32>()
                };
                let h = 1e-2;
                let grad_ln_hat = Vec2::new(
                    (ln_hat(q + dx * (h / 0.01)) - ln_hat(q - dx * (h / 0.01))) / (2.0 * h),
                    (ln_hat(q + dy * (h / 0.01)) - ln_hat(q - dy * (h / 0.01))) / (2.0 * h),
                );
                let lh = ln_hat(q);
                // ln(β/(γ+β)) = −ln(1 + φ̂) = −softplus(ln φ̂).
                let ln_ratio = -log_sum_exp(0.0, lh);
                let ln_pred = libm::logf(e.value / k) + ln_ratio + libm::logf(grad_ln_hat.norm());
                let dir_pred = grad_ln_hat.normalized(0.0).unwrap();
                let dir_err = (dir_pred + e.descent).norm();
                let ln_err = (ln_pred - e.ln_grad_norm).abs();
                worst_log = worst_log.max(ln_err).max(dir_err);
                checked_log += 1;
                assert!(
                    dir_err < 0.01 && ln_err < 0.01,
                    "at {q:?}: {e:?} ln_pred {ln_pred} dir {dir_pred:?}"
                );
            }
        }
        println!(
            "gradient check: {checked_fd} points vs FD of φ (worst rel. err {worst_fd:.2e}), \
             {checked_log} points vs FD of ln φ̂ (worst err {worst_log:.2e})"
        );
        assert!(checked_fd > 100);
    }

    #[test]
    fn finite_near_the_goal_and_near_obstacles() {
        let c0 = Vec2::new(0.0, 0.0);
        let goal = Vec2::new(1e-3, 0.0);
        let mut w = SphereWorld::new(c0, 100.0, goal, kappa(0.0, 2)).unwrap();
        w.push(Vec2::new(30.0, 0.0), 10.0).unwrap();
        w.push(Vec2::new(-50.0, 20.0), 5.0).unwrap();
        // Approaching the goal: ∇φ → 0 linearly, always pointing at the goal.
        let mut last = f32::INFINITY;
        for d in [10.0f32, 1.0, 1e-2, 1e-4, 1e-8] {
            let q = goal + Vec2::new(0.0, d);
            let g = w.gradient(q).unwrap();
            assert!(g.is_finite() && g.norm() < last, "{d}: {g:?}");
            assert!(g.y > 0.0 && g.x.abs() <= 0.1 * g.y);
            last = g.norm();
        }
        // The near-goal slope: ‖∇φ‖ ≈ 2‖q − q_d‖/(ρ_0² β̃(q_d)^{1/κ}).
        let ln_beta_d: f32 = w.terms(goal).map(|(b, _)| libm::logf(b)).sum();
        let slope = 2.0 / (100.0f32 * 100.0 * libm::expf(ln_beta_d / w.kappa()));
        let g = w.gradient(goal + Vec2::new(0.0, 1e-3)).unwrap();
        assert!(
            (g.norm() / 1e-3 / slope - 1.0).abs() < 1e-3,
            "{} vs {slope}",
            g.norm() / 1e-3
        );
        // Subnormal offsets from a goal at the origin.
        let mut w0 = SphereWorld::new(c0, 100.0, c0, 3.0).unwrap();
        w0.push(Vec2::new(30.0, 0.0), 10.0).unwrap();
        for d in [1e-20f32, 1e-30, 1e-38, 1e-44] {
            let q = Vec2::new(d, -d);
            let e = w0.eval(q).unwrap();
            assert!(e.grad_norm.is_finite() && e.grad_norm < 1e-10);
            assert!(e.value >= 0.0 && e.value < 1e-10);
            // Below ≈ 1e-38·ρ_0 the normalised offset underflows to 0: "at the goal".
            let dir = w0.descent_direction(q).unwrap();
            let want = Vec2::new(-1.0, 1.0) * core::f32::consts::FRAC_1_SQRT_2;
            assert!(
                (dir - want).norm() < 1e-5 || (d < 1e-36 && dir == Vec2::ZERO),
                "{d}: {dir:?}"
            );
        }
        // Approaching an obstacle: finite, pointing away from it.
        for delta in [1.0f32, 1e-2, 1e-4, 2e-6] {
            let q = Vec2::new(30.0, 10.0 + delta);
            let e = w.eval(q).unwrap();
            assert!(e.grad_norm.is_finite() && e.value <= 1.0, "{delta}: {e:?}");
            let want = if delta < 0.1 { 0.99 } else { 0.0 };
            assert!(e.descent.y > want, "descent {:?} at {delta}", e.descent);
        }
        // And the boundary.
        let q = Vec2::new(0.0, -100.0 + 1e-5);
        let e = w.eval(q).unwrap();
        assert!(e.grad_norm.is_finite() && e.descent.y > 0.99, "{e:?}");
    }

    /// The requirement: from many random starts in random sphere worlds, every run
    /// reaches the goal without collision.
    #[test]
    fn random_starts_reach_the_goal_without_collision() {
        let mut rng = XorShift32::new(2024);
        let (worlds, starts) = (10, 20);
        let (mut runs, mut reached) = (0, 0);
        let mut min_clear = f32::INFINITY;
        let mut max_steps = 0;
        for world in 0..worlds {
            let n = 3 + world % 6; // 3..=8
            let w = random_world(&mut rng, 100.0, n, (3.0, 12.0), 2.0, 0.0);
            for _ in 0..starts {
                let s = random_free(&mut rng, &w, 0.5);
                let r = descend(&w, s, 0.5, 4000);
                runs += 1;
                assert!(r.min_clear > 0.0, "collision: world {world} from {s:?}");
                assert!(
                    r.reached,
                    "world {world} (M = {n}, κ = {}) from {s:?}: stopped {} m away",
                    w.kappa(),
                    r.final_dist
                );
                reached += 1;
                min_clear = min_clear.min(r.min_clear);
                max_steps = max_steps.max(r.steps);
            }
        }
        println!(
            "navfn: {worlds} worlds × {starts} starts = {runs} runs, {reached} reached the goal, \
             min clearance {min_clear:.3} m, at most {max_steps} steps of ≤ 0.5 m"
        );
        assert_eq!(reached, worlds * starts);
    }

    /// The full table (40 circles in a 500 m workspace), κ = M + 2 = 42: γ and β far outside
    /// f32's range, yet every value finite. The rule of thumb is *not* enough here: a few
    /// starts end in genuine spurious minima of φ (checked on ln φ̂ = κ ln d² − Σ ln β_i, which
    /// f32 evaluates to ~1e-4); κ = 1.5·M = 60 removes them in this world.
    #[test]
    fn full_table_and_large_kappa_stay_finite() {
        let mut rng = XorShift32::new(99);
        let w = random_world(&mut rng, 500.0, MAX_SPHERES, (3.0, 20.0), 2.0, 0.0);
        assert_eq!(w.kappa(), 42.0);
        assert_eq!(w.clone().push(w.center, 1.0), Err(NavfnError::Full));
        let mut lo = f32::INFINITY;
        let mut hi = f32::NEG_INFINITY;
        for _ in 0..500 {
            let q = random_free(&mut rng, &w, 1e-3);
            let e = w.eval(q).unwrap();
            assert!(e.value.is_finite() && e.grad_norm.is_finite() && e.ln_grad_norm.is_finite());
            lo = lo.min(e.ln_grad_norm);
            hi = hi.max(e.ln_grad_norm);
        }
        println!("M = 40, κ = 42, ρ_0 = 500 m: ln‖∇φ‖ from {lo:.1} to {hi:.1} (1/m)");
        let ln_hat = |w: &SphereWorld, p: Vec2| {
            let d2 = ((p - w.goal) * w.inv_radius).norm2();
            w.kappa * libm::logf(d2) - w.terms(p).map(|(b, _)| libm::logf(b)).sum::<f32>()
        };
        for (k, want_all) in [(42.0f32, false), (60.0, true)] {
            let mut w = w.clone();
            w.set_kappa(k).unwrap();
            let mut rng = XorShift32::new(1234);
            let mut ok = 0;
            for _ in 0..40 {
                let s = random_free(&mut rng, &w, 0.5);
                let r = descend_guarded(&w, s, 0.5, 20_000, true);
                assert!(r.min_clear > 0.0);
                if r.reached {
                    ok += 1;
                    continue;
                }
                // Stuck: a genuine minimum of φ̂ (hence of φ), not a numerical artefact.
                let mut q = s;
                for _ in 0..20_000 {
                    let h = 0.5f32.min(0.5 * w.clearance(q)).min((q - w.goal).norm());
                    q += w.descent_direction(q).unwrap() * h;
                }
                let c = ln_hat(&w, q);
                for rad in [2.0f32, 5.0] {
                    for j in 0..32 {
                        let p = q + Vec2::from_angle(j as f32 * 0.196) * rad;
                        assert!(ln_hat(&w, p) > c, "κ = {k}: not a minimum at {q:?}");
                    }
                }
                println!(
                    "  κ = {k}: spurious minimum at {q:?}, {:.1} m from the goal",
                    (q - w.goal).norm()
                );
            }
            println!("M = 40, κ = {k}, ρ_0 = 500 m: {ok}/40 starts reached the goal, no collision");
            if want_all {
                assert_eq!(ok, 40);
            } else {
                assert!(ok >= 30);
            }
        }
    }

    /// Exploratory (ignored; `cargo test -p vpf --lib kappa_sweep -- --ignored --nocapture`):
    /// reached/collided out of 40 starts per world and κ, with the plain 0.5 m step and with
    /// the step also bounded by half the clearance.
    #[test]
    #[ignore]
    fn kappa_sweep() {
        let mut rng = XorShift32::new(77);
        for (ws, n) in [
            (500.0f32, 40usize),
            (300.0, 40),
            (300.0, 20),
            (150.0, 12),
            (100.0, 8),
        ] {
            for world in 0..4 {
                let w = random_world(&mut rng, ws, n, (3.0, 20.0f32.min(ws * 0.12)), 2.0, 0.0);
                let mut line = std::format!("ρ_0 {ws} m, M {n}, world {world}:");
                let m = n as f32;
                for kset in [m + 2.0, 1.25 * m, 1.5 * m, 2.0 * m, 3.0 * m] {
                    let mut w2 = w.clone();
                    w2.set_kappa(kset).unwrap();
                    let mut rng2 = XorShift32::new(1000 + world);
                    let (mut ok, mut col, mut okg, mut colg) = (0, 0, 0, 0);
                    for _ in 0..40 {
                        let s = random_free(&mut rng2, &w2, 0.5);
                        let r = descend(&w2, s, 0.5, 20_000);
                        ok += r.reached as usize;
                        col += (r.min_clear <= 0.0) as usize;
                        let r = descend_guarded(&w2, s, 0.5, 20_000, true);
                        okg += r.reached as usize;
                        colg += (r.min_clear <= 0.0) as usize;
                    }
                    line += &std::format!(" κ{kset}: {ok}(c{col})|{okg}(c{colg})");
                }
                println!("{line}");
            }
        }
    }

    #[test]
    fn capacity_and_bad_inputs() {
        let mut w = SphereWorld::new(Vec2::ZERO, 1000.0, Vec2::ZERO, 3.0).unwrap();
        for k in 0..MAX_SPHERES {
            w.push(Vec2::new(10.0 + 20.0 * k as f32, 0.0), 1.0).unwrap();
        }
        assert_eq!(w.push(Vec2::new(0.0, 500.0), 1.0), Err(NavfnError::Full));
        assert_eq!(w.len(), MAX_SPHERES);
        assert!(w.is_sphere_world());
        let nan = f32::NAN;
        assert_eq!(w.value(Vec2::new(nan, 0.0)), Err(NavfnError::NonFinite));
        assert_eq!(
            w.gradient(Vec2::new(0.0, f32::INFINITY)),
            Err(NavfnError::NonFinite)
        );
        assert_eq!(w.escape_direction(Vec2::new(nan, 0.0)), None);
        let mut e = SphereWorld::new(Vec2::ZERO, 10.0, Vec2::ZERO, 3.0).unwrap();
        assert_eq!(e.push(Vec2::new(nan, 1.0), 1.0), Err(NavfnError::NonFinite));
        assert_eq!(e.push(Vec2::new(5.0, 1.0), nan), Err(NavfnError::NonFinite));
        assert_eq!(
            e.push(Vec2::new(5.0, 1.0), 0.0),
            Err(NavfnError::InvalidRadius)
        );
        assert_eq!(
            e.push_merged(Vec2::new(5.0, 1.0), -1.0),
            Err(NavfnError::InvalidRadius)
        );
        assert!(e.is_empty());
        assert_eq!(
            SphereWorld::new(Vec2::new(nan, 0.0), 1.0, Vec2::ZERO, 3.0).err(),
            Some(NavfnError::NonFinite)
        );
        assert_eq!(
            SphereWorld::new(Vec2::ZERO, 0.0, Vec2::ZERO, 3.0).err(),
            Some(NavfnError::InvalidRadius)
        );
        assert_eq!(
            SphereWorld::new(Vec2::ZERO, 1e-40, Vec2::ZERO, 3.0).err(),
            Some(NavfnError::InvalidRadius)
        );
        assert_eq!(
            SphereWorld::new(Vec2::ZERO, 1.0, Vec2::ZERO, 0.5).err(),
            Some(NavfnError::InvalidKappa)
        );
        assert_eq!(
            SphereWorld::new(Vec2::ZERO, 1.0, Vec2::ZERO, nan).err(),
            Some(NavfnError::NonFinite)
        );
        assert_eq!(
            SphereWorld::new(Vec2::ZERO, 1.0, Vec2::new(2.0, 0.0), 3.0).err(),
            Some(NavfnError::GoalBlocked)
        );
        assert_eq!(e.set_kappa(0.0), Err(NavfnError::InvalidKappa));
        assert_eq!(e.set_kappa(nan), Err(NavfnError::NonFinite));
    }

    #[test]
    fn goal_blocked_and_escape_directions() {
        let mut w = SphereWorld::new(Vec2::ZERO, 50.0, Vec2::new(10.0, 0.0), 4.0).unwrap();
        w.push(Vec2::new(-10.0, 0.0), 5.0).unwrap();
        assert!(!w.goal_blocked());
        // Escape: inside circle 0, outward from its centre.
        let q = Vec2::new(-10.0, 3.0);
        assert_eq!(w.gradient(q), Err(NavfnError::InsideObstacle(0)));
        let d = w.escape_direction(q).unwrap();
        assert!((d - Vec2::new(0.0, 1.0)).norm() < 1e-6);
        // At the very centre: toward the goal.
        let d = w.escape_direction(Vec2::new(-10.0, 0.0)).unwrap();
        assert!((d - Vec2::new(1.0, 0.0)).norm() < 1e-6);
        // Outside the workspace: back toward its centre.
        let d = w.escape_direction(Vec2::new(0.0, -60.0)).unwrap();
        assert!((d - Vec2::new(0.0, 1.0)).norm() < 1e-6);
        assert_eq!(
            w.value(Vec2::new(0.0, -60.0)),
            Err(NavfnError::OutsideWorkspace)
        );
        // Free: no escape needed.
        assert_eq!(w.escape_direction(Vec2::new(0.0, 20.0)), None);
        // A circle over the goal: stored, evaluations refused, until the goal moves.
        w.push(Vec2::new(11.0, 0.0), 2.0).unwrap();
        assert!(w.goal_blocked() && !w.is_sphere_world());
        assert_eq!(w.value(Vec2::new(0.0, 20.0)), Err(NavfnError::GoalBlocked));
        assert_eq!(
            w.descent_direction(Vec2::new(0.0, 20.0)),
            Err(NavfnError::GoalBlocked)
        );
        w.set_goal(Vec2::new(0.0, 30.0)).unwrap();
        assert!(!w.goal_blocked() && w.is_sphere_world());
        assert!(w.gradient(Vec2::new(0.0, 20.0)).unwrap().is_finite());
        assert_eq!(
            w.set_goal(Vec2::new(0.0, 50.0)),
            Err(NavfnError::GoalBlocked)
        );
        assert_eq!(w.value(Vec2::new(0.0, 20.0)), Err(NavfnError::GoalBlocked));
        w.set_goal(Vec2::new(0.0, 30.0)).unwrap();
        w.clear();
        assert!(w.is_empty() && !w.goal_blocked());
    }

    #[test]
    fn overlapping_circles_are_merged_into_a_sphere_world() {
        let mut w = SphereWorld::new(Vec2::ZERO, 100.0, Vec2::new(60.0, 0.0), 5.0).unwrap();
        // A chain of three overlapping circles, pushed out of order, and a separate one.
        w.push_merged(Vec2::new(0.0, -10.0), 6.0).unwrap();
        w.push_merged(Vec2::new(0.0, 10.0), 6.0).unwrap();
        w.push_merged(Vec2::new(-40.0, 0.0), 5.0).unwrap();
        assert_eq!(w.len(), 3);
        w.push_merged(Vec2::new(0.0, 0.0), 5.0).unwrap(); // bridges the first two
        assert_eq!(w.len(), 2);
        assert!(w.is_sphere_world());
        // The merged circle holds all three originals.
        let (c, r) = w.spheres().find(|(c, _)| c.x > -20.0).unwrap();
        for (p, s) in [
            (Vec2::new(0.0, -10.0), 6.0),
            (Vec2::new(0.0, 10.0), 6.0),
            (Vec2::ZERO, 5.0),
        ] {
            assert!(
                (p - c).norm() + s <= r * (1.0 + 1e-6),
                "{p:?} {s} not in {c:?} {r}"
            );
        }
        // Contained circle: absorbed without growth.
        w.push_merged(Vec2::new(0.0, 1.0), 1.0).unwrap();
        assert_eq!(w.len(), 2);
        assert_eq!(w.spheres().find(|(c, _)| c.x > -20.0).unwrap().1, r);
        // Descent from behind the merged wall reaches the goal.
        let mut rng = XorShift32::new(5);
        for _ in 0..20 {
            let s = Vec2::new(
                -uniform(&mut rng, 10.0, 30.0),
                uniform(&mut rng, -20.0, 20.0),
            );
            if clearance(&w, s) < 0.5 {
                continue;
            }
            let run = descend(&w, s, 0.5, 4000);
            assert!(run.reached && run.min_clear > 0.0);
        }
    }

    #[test]
    fn circle_across_the_boundary_still_never_collides() {
        // Not a sphere world: the circle crosses the workspace boundary.
        let mut w =
            SphereWorld::new(Vec2::ZERO, 100.0, Vec2::new(50.0, 0.0), kappa(0.0, 2)).unwrap();
        w.push(Vec2::new(0.0, 95.0), 15.0).unwrap();
        w.push(Vec2::new(20.0, -20.0), 8.0).unwrap();
        assert!(!w.is_sphere_world());
        let mut rng = XorShift32::new(3);
        let mut reached = 0;
        for _ in 0..50 {
            let s = random_free(&mut rng, &w, 0.5);
            let r = descend(&w, s, 0.5, 4000);
            assert!(r.min_clear > 0.0);
            reached += r.reached as usize;
        }
        println!("circle across the boundary: {reached}/50 starts reached the goal");
    }

    #[test]
    fn kappa_rule_and_enclosing_circles() {
        assert_eq!(kappa(0.0, 8), 10.0);
        assert_eq!(kappa(-1.0, 0), 2.0);
        assert_eq!(kappa(f32::NAN, 3), 5.0);
        assert_eq!(kappa(7.5, 3), 7.5);
        assert_eq!(kappa(0.2, 3), MIN_KAPPA);
        let c = Shape::circle(Vec2::new(1.0, 2.0), 3.0).unwrap();
        assert_eq!(enclosing_circle(&c), (Vec2::new(1.0, 2.0), 3.0));
        let r = Shape::rectangle(Vec2::new(5.0, 0.0), Vec2::new(3.0, 4.0), 0.7).unwrap();
        let (p, rad) = enclosing_circle(&r);
        assert_eq!(p, Vec2::new(5.0, 0.0));
        assert!((rad - 5.0).abs() < 1e-6);
        let e = Shape::ellipse(Vec2::ZERO, Vec2::new(2.0, 6.0), 0.3).unwrap();
        assert_eq!(enclosing_circle(&e).1, 6.0);
        let t = Shape::polygon(&[
            Vec2::new(0.0, 0.0),
            Vec2::new(6.0, 0.0),
            Vec2::new(0.0, 3.0),
        ])
        .unwrap();
        let (p, rad) = enclosing_circle(&t);
        // Every vertex and edge point is inside.
        for v in [
            Vec2::new(0.0, 0.0),
            Vec2::new(6.0, 0.0),
            Vec2::new(0.0, 3.0),
            Vec2::new(3.0, 1.5),
        ] {
            assert!((v - p).norm() <= rad + 1e-5);
        }
    }
}
