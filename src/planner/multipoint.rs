//! The multipoint potential field of seed 003 (`shared/seeds/003_b4b864f255c4676d.txt`,
//! Saravanakumar, Thomas and Asokan, §3 eq. 4–8, §4–5): the vehicle is steered to the point of
//! least potential on an arc ahead of its bow. No gradient is taken.
//!
//! **Per call of [`choose`]** (one "path element" of the paper):
//! 1. the arc of radius r about the vehicle is discretised into N points q_i, equiangular from
//!    ψ_h − ψ_m to ψ_h + ψ_m (003 §3, first step; ψ_h the heading, ψ_m the largest turn);
//! 2. each obstacle is discretised into K points p_j on the half of its periphery that faces
//!    the vehicle ([`periphery`]; 003 §3, third step);
//! 3. U_att(i) = ½ξ(d_a(i) + u)², d_a(i) = |q_i − q_goal| (003 eq. 4);
//! 4. U_obs(i,j) = ½η(1/d_o(i,j) − 1/d_t)²·d_a(i)² for d_o(i,j) = |q_i − p_j| ≤ d_t, else 0
//!    (003 eq. 5), summed over j (eq. 6) and over the obstacles (eq. 7);
//! 5. the arc point of least U_tot is the next point to steer to (eq. 8).
//!
//! **Where the paper is open or slipped, and what we chose:**
//! - *Arc points.* "Discretize the arc … into N points over ψ_h ± ψ_m": we include both ends, so
//!   the hardest allowed turn is a candidate, and an odd N has straight ahead as a candidate.
//!   N = 1 is straight ahead alone.
//! - *u in eq. 4* is the forward speed added to a distance, as printed (Ge & Cui's form with a
//!   velocity term folded in). Its only effect on the choice is to raise the attraction's slope
//!   from ξ·d_a to ξ·(d_a + u). We take it in m/s as a number of metres, clamp it to
//!   0 ..= [`MAX_SPEED`] (astern motion would make (d_a + u)² non-monotonic in d_a).
//! - *Eq. 5* writes the influence distance once as d_t and once as d_i, the distance as d_o and
//!   d_q, and indexes p_j up to N; we read one d_t, one d_o, and j = 1 … K.
//! - *The facing half of a periphery* (the paper has circles only, "the semicircular area …
//!   facing the bow"): for any shape, the boundary points hit by K equiangular rays from the
//!   shape's centre spread over ±90° about the bearing from the centre to the vehicle, both ends
//!   included (the flanks are what a passing vehicle skirts). For a circle this is exactly the
//!   paper's semicircle. The rays are intersected with the boundary in closed form (circle,
//!   rectangle, ellipse: one division or square root; convex polygon: one division per edge),
//!   so generating the points costs no `signed_distance` evaluation and is exact to rounding.
//! - *d_o → 0* (an arc point on a periphery point, or the vehicle inside an obstacle): d_o is
//!   clamped to [`MIN_OBSTACLE_DISTANCE_M`] before the reciprocal. Closer than a centimetre is a
//!   collision anyway; the clamp bounds 1/d_o so the repulsion is large but finite.
//! - *Speed-proportional interval* (§4: "executed at a time interval T that is proportional to
//!   the velocity"; §5: path elements every 1 s, planned every 1 m at 1 m/s): we read it as the
//!   time to cover the arc, r/u ([`replan_periods`]).
//!
//! **Scale.** Both U_att and U_obs grow with d_a², so the ratio of the *totals* does not depend
//! on the goal distance D (the point of Ge & Cui's d_a² factor: the repulsion vanishes at the
//! goal, so a goal near an obstacle stays reachable). The *choice*, however, compares arc points
//! with each other: across the arc U_att varies by about ξ·(D + u)·r·(1 − cos Δ) (Δ the angle
//! off the goal bearing), linear in D, while U_obs varies by ½η·D²·δΣ(1/d_o − 1/d_t)², square
//! in D. So the repulsion's steering authority grows about linearly with the goal distance: far
//! from the goal the vehicle gives obstacles a wider berth, and within a few metres of the goal
//! it is nearly pure attraction. The defaults are set for goals 10–300 m away.
//!
//! **Numerics.** Only the arg min matters, so [`choose`] compares
//! (U_tot(i) − ½ξ(D + u)²)/s² with s = max(D, 1 m): subtracting the part of U_att common to all
//! arc points keeps the attraction's small differences across the arc exact even at D = 100 km
//! (where f32 resolves only 8 mm of D itself), and dividing by s² keeps every term finite for
//! any finite input. Goals farther than [`MAX_GOAL_RANGE_M`] are moved in along their bearing
//! (only the bearing matters there). The reported [`ArcChoice::potential`] is U_tot itself.
//!
//! **Cost per call**, for N arc points, K periphery points and R obstacles within reach
//! (bounding circle within r + d_t of the vehicle; farther ones cost one norm and are skipped
//! exactly, since none of their points can reach an arc point):
//! - R·K ray–boundary intersections (K `sin_cos` per call, one per rectangle or ellipse, plus
//!   one division per edge for a polygon) — no `signed_distance` evaluation;
//! - at most N·K·R squared distances, of which those within d_t take a square root and a
//!   division (about 27 instructions a pair on the Cortex-M4F);
//! - N `signed_distance` evaluations per obstacle within reach whose periphery is coarse (see
//!   below; none with the defaults for obstacles up to 10 m in radius), so at most N·R;
//! - N norms and divisions for the attraction.
//!
//! Stack: about 32·(8 + 4) + 16·(8 + 8) bytes of arrays.
//!
//! **Region of interest, held to a budget (our departure).** Seed 003 §3 selects "the
//! obstacles within this region" of interest, the sonar's detection range and span, and
//! leaves its size open. Evaluated over every obstacle within reach, the sum is N·(K·R + M)
//! pairs for M map cells: at full tables in clutter (32 obstacles and 8 vehicles within 9 m,
//! 32 cells; N = 25, K = 9) 9800 pairs, 330 000 instructions, over the step budget. The
//! planner therefore narrows the region ([`region_of_interest`], before any shape is built)
//! to at most [`MAX_PAIRS`] pairs: everything within reach while that fits, else the nearest
//! distance bands ((r + d_t)/16 deep) whole and, in the first band that does not fit,
//! sources in table order while they fit. What is left out is the farthest: its terms are the
//! smallest ((1/d_o − 1/d_t)² falls from 0.14 at 2 m to 0.002 at 6 m with d_t = 8 m), and the
//! region is chosen afresh at every arc step, so an obstacle left out enters it as the vehicle
//! closes in. [`choose`] itself evaluates eq. 4–8 over whatever it is given.
//!
//! **Coarse peripheries (our addition).** Between two neighbouring periphery points, up to
//! πρ/(K − 1) apart on an obstacle of bounding radius ρ, the repulsion dips; once that spacing
//! exceeds d_t the vehicle can steer straight between them into the obstacle (with an even K,
//! right through a large circle's face). The paper's obstacles are small circles, where this
//! does not arise. When the spacing exceeds d_t/2 ([`periphery_is_coarse`]), we add for every
//! arc point one more obstacle point: the nearest point of the obstacle's boundary, whose
//! distance is the shape's signed distance (clamped like d_o, so inside an obstacle it is the
//! largest repulsion). Obstacles with a dense periphery get exactly the paper's eq. 5–7.

use crate::field::Shape;
use crate::math::{max, min, sin_cos, wrap_angle, Vec2, PI};

/// Most arc points N (the capacity of [`choose`]'s stack arrays; a larger [`ArcConfig::points`]
/// is clamped to it) and most periphery points K per obstacle (likewise).
pub use crate::params::{MAX_ARC_POINTS, MAX_PERIPHERY_POINTS};

/// Most (arc point, obstacle point) pairs one call of [`choose`] evaluates: the bound on its
/// cost at any table size (see the module notes, "Region of interest").
pub const MAX_PAIRS: usize = 1600;
/// Distance bands, each (r + d_t)/[`BANDS`] deep, in which [`choose`] narrows its region of
/// interest to [`MAX_PAIRS`].
const BANDS: usize = 16;
/// Obstacle points a coarse periphery's nearest-point term counts for in [`MAX_PAIRS`]: its N
/// signed distances cost about as much as this many points' N pairs.
const COARSE_POINTS: usize = 4;

/// Floor on d_o in eq. 5 of seed 003, m: closer than this the repulsion stops growing, so an
/// arc point on a periphery point (or a vehicle inside an obstacle) gives a large finite
/// potential, not an infinite or NaN one.
pub const MIN_OBSTACLE_DISTANCE_M: f32 = 0.01;
/// Largest forward speed u used in seed 003 eq. 4, m/s (far above any AUV; keeps the term
/// finite for absurd inputs). Negative speeds count as 0.
pub const MAX_SPEED: f32 = 100.0;
/// A goal farther than this (per coordinate, m) is moved in along its bearing before eq. 4–5
/// are evaluated: its bearing is all that matters at such a range, and the squares stay finite.
pub const MAX_GOAL_RANGE_M: f32 = 1e15;
/// Longest re-planning interval [`replan_periods`] returns, s. At speeds so low that r/u would
/// exceed it (0.2 m/s with a 1 m arc), or at a standstill, the planner still re-plans this
/// often: moving obstacles at up to 1 m/s shift at most 5 m, half the default d_t, in between.
pub const MAX_REPLAN_S: f32 = 5.0;

/// The parameters of the multipoint potential field (seed 003 §3). Check with
/// [`ArcConfig::is_valid`]; [`choose`] refuses an invalid one.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct ArcConfig {
    /// r, radius of the arc of candidate points about the vehicle, m. 0.1 ..= 100.
    pub arc_m: f32,
    /// N, arc points. Odd recommended (straight ahead is then a candidate). 0 is read as 1,
    /// above [`MAX_ARC_POINTS`] as [`MAX_ARC_POINTS`].
    pub points: u8,
    /// ψ_m, the arc spans heading ± ψ_m: the largest turn per arc step, rad. 0 ..= π.
    pub max_turn_rad: f32,
    /// ξ, attraction gain (seed 003 eq. 4). 0.001 ..= 10⁴.
    pub xi: f32,
    /// η, repulsion gain (seed 003 eq. 5). 0 ..= 10⁶ (0 ignores obstacles).
    pub eta: f32,
    /// d_t, influence distance of an obstacle's periphery point (seed 003 eq. 5), m.
    /// 0.1 ..= 1000.
    pub influence_m: f32,
    /// K, points on the facing half of each obstacle's periphery. 0 is read as 1, above
    /// [`MAX_PERIPHERY_POINTS`] as [`MAX_PERIPHERY_POINTS`].
    pub periphery: u8,
}

impl Default for ArcConfig {
    /// For a 1–5 m vehicle at about 1 m/s, planning every metre as in seed 003 §5. Checked by
    /// the closed-loop tests below (a point vehicle hopping from arc point to arc point):
    ///
    /// - r = 1 m: the paper's path element, 1 m per 1 s at 1 m/s;
    /// - N = 25 over ψ_m = ±36° (0.2π): 3° resolution, and an odd N so straight ahead is a
    ///   candidate. 36° per metre of path is a tight turn (about 1.6 m radius) that the
    ///   trajectory tracker smooths; the field uses it only when an obstacle is close. ±27°
    ///   and ±45° behave alike in the tests; ±36° took the fewest steps in the paper's scene;
    /// - d_t = 8 m: a vehicle on a collision course starts turning 8 m before the surface,
    ///   1.6–8 vehicle lengths, and settles about d_t − 1 m off an obstacle it passes: a 7 m
    ///   berth, more than a 5 m vehicle's length, while a 14 m gap between two obstacles is
    ///   still taken down its middle;
    /// - ξ = 1, η = 10: only η/ξ matters. With 10, a vehicle heading straight at a circle of
    ///   3 m radius 15 m ahead passes it with more than 2.5 m clearance (half a 5 m vehicle)
    ///   for goals from 2 m behind the obstacle (where the d_a² factor has nearly switched the
    ///   repulsion off) to 300 m beyond it (5–7 m clearance). η/ξ from 5 to 100 all pass the
    ///   tests; larger values mostly push the vehicle out to d_t earlier;
    /// - K = 9 (odd, so the point facing the vehicle is one of them): one point every 22.5°,
    ///   dense enough (spacing ≤ d_t/2) on obstacles up to 10 m in radius; larger ones get the
    ///   nearest-point term of the module notes.
    ///
    /// The values are declared as the `mp_*` parameters' defaults (`crate::params`).
    fn default() -> Self {
        ArcConfig::of(&crate::params::Params::default())
    }
}

impl ArcConfig {
    /// The multipoint settings of a parameter set (its `mp_*` parameters).
    pub fn of(p: &crate::params::Params) -> ArcConfig {
        ArcConfig {
            arc_m: p.mp_arc_m,
            points: p.mp_points,
            max_turn_rad: p.mp_turn_rad,
            xi: p.mp_xi,
            eta: p.mp_eta,
            influence_m: p.mp_influence_m,
            periphery: p.mp_periphery,
        }
    }

    /// Every field finite and in the range its documentation gives (`points` and `periphery`
    /// are clamped, never refused).
    pub fn is_valid(&self) -> bool {
        in_range(self.arc_m, 0.1, 100.0)
            && in_range(self.max_turn_rad, 0.0, PI)
            && in_range(self.xi, 1e-3, 1e4)
            && in_range(self.eta, 0.0, 1e6)
            && in_range(self.influence_m, 0.1, 1000.0)
    }

    /// N as used: [`ArcConfig::points`] clamped to 1 ..= [`MAX_ARC_POINTS`].
    pub fn arc_points(&self) -> usize {
        (self.points as usize).clamp(1, MAX_ARC_POINTS)
    }

    /// K as used: [`ArcConfig::periphery`] clamped to 1 ..= [`MAX_PERIPHERY_POINTS`].
    pub fn periphery_points(&self) -> usize {
        (self.periphery as usize).clamp(1, MAX_PERIPHERY_POINTS)
    }

    /// Direction of arc point `i` (0-based) of [`ArcConfig::arc_points`], unwrapped, rad:
    /// ψ_h − ψ_m + 2ψ_m·i/(N − 1), from the hardest right turn (i = 0, clockwise) to the hardest
    /// left one (seed 003 §3, first step). Straight ahead when N = 1.
    pub fn arc_bearing(&self, heading: f32, i: usize) -> f32 {
        let n = self.arc_points();
        if n < 2 {
            return heading;
        }
        let t = i as f32 / (n - 1) as f32;
        heading + self.max_turn_rad * (2.0 * t - 1.0)
    }
}

/// `lo ≤ v ≤ hi`, false for NaN.
fn in_range(v: f32, lo: f32, hi: f32) -> bool {
    v >= lo && v <= hi
}

/// The arc point [`choose`] picked (seed 003 eq. 8).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ArcChoice {
    /// q_i, the point to steer to, world frame, m.
    pub point: Vec2,
    /// Its direction from the vehicle, world frame, rad in (−π, π].
    pub bearing: f32,
    /// U_tot at q_i (seed 003 eq. 7, with the nearest-point term of coarse peripheries),
    /// saturated at `f32::MAX`.
    pub potential: f32,
    /// i, 0-based, counted from the hardest right turn (see [`ArcConfig::arc_bearing`]).
    pub index: u8,
}

/// The K points p_j on the half of `shape`'s periphery that faces `viewer` (seed 003 §3, the
/// obstacle points of eq. 5), written to the front of `out`; returns how many:
/// min(k, [`MAX_PERIPHERY_POINTS`], `out.len()`), spread over the whole facing half whatever
/// the count. 0 when `viewer` is not finite.
///
/// Point j lies where the ray from the shape's centre at angle β + φ_j meets the boundary, β the
/// bearing from the centre to `viewer` and φ_j equiangular over −90° ..= +90° (φ = 0 alone for
/// one point). For a circle these are the paper's equiangular points on the semicircle facing
/// the vehicle. A viewer at the centre faces +x.
pub fn periphery(shape: &Shape, viewer: Vec2, k: u8, out: &mut [Vec2]) -> usize {
    let mut rays = [(0.0, 0.0); MAX_PERIPHERY_POINTS];
    let n = facing_rays((k as usize).min(out.len()), &mut rays);
    periphery_along(shape, viewer, rays.get(..n).unwrap_or(&[]), out)
}

/// (sin φ_j, cos φ_j) of the K equiangular ray offsets of [`periphery`] (φ over −90° ..= +90°,
/// or 0 alone), written to the front of `rays`; returns how many: min(k,
/// [`MAX_PERIPHERY_POINTS`]). The same for every obstacle, so [`choose`] computes them once.
fn facing_rays(k: usize, rays: &mut [(f32, f32); MAX_PERIPHERY_POINTS]) -> usize {
    let n = k.min(MAX_PERIPHERY_POINTS);
    let step = if n > 1 { PI / (n - 1) as f32 } else { 0.0 };
    let first = if n > 1 { -0.5 * PI } else { 0.0 };
    for (j, slot) in rays.iter_mut().take(n).enumerate() {
        *slot = sin_cos(first + step * j as f32);
    }
    n
}

/// [`periphery`] along the ray offsets `rays` (from [`facing_rays`]).
fn periphery_along(shape: &Shape, viewer: Vec2, rays: &[(f32, f32)], out: &mut [Vec2]) -> usize {
    let c = shape.center();
    if rays.is_empty() || !viewer.is_finite() || !c.is_finite() {
        return 0;
    }
    let toward = (viewer - c).normalized(1e-6).unwrap_or(Vec2::new(1.0, 0.0));
    let frame = Frame::of(shape);
    let mut n = 0;
    for (&(s, co), slot) in rays.iter().zip(out.iter_mut()) {
        let dir = toward.rotate_cs(co, s);
        *slot = c + dir * boundary_distance(shape, &frame, c, dir);
        n += 1;
    }
    n
}

/// The rotation of a rectangle's or an ellipse's own axes, (sin, cos), computed once per
/// shape for all its periphery points; (0, 1) for the other shapes.
struct Frame {
    sin: f32,
    cos: f32,
}

impl Frame {
    fn of(shape: &Shape) -> Frame {
        let angle = match shape {
            Shape::Rectangle(r) => r.angle(),
            Shape::Ellipse(e) => e.frame().angle(),
            _ => 0.0,
        };
        let (sin, cos) = sin_cos(angle);
        Frame { sin, cos }
    }
}

/// Distance from the centre `c` of `shape` along the unit direction `dir` to its boundary, in
/// closed form (`frame`: the shape's axes, [`Frame::of`]). The centre is inside every shape (a
/// convex polygon's vertex average is interior).
fn boundary_distance(shape: &Shape, frame: &Frame, c: Vec2, dir: Vec2) -> f32 {
    let (s, co) = (frame.sin, frame.cos);
    match shape {
        Shape::Circle(ci) => ci.radius(),
        Shape::Rectangle(r) => {
            let l = dir.rotate_cs(co, -s);
            let h = r.half_size();
            // The ray leaves the box through the side it reaches first.
            let tx = if l.x.abs() > 1e-9 {
                h.x / l.x.abs()
            } else {
                f32::INFINITY
            };
            let ty = if l.y.abs() > 1e-9 {
                h.y / l.y.abs()
            } else {
                f32::INFINITY
            };
            min(tx, ty)
        }
        Shape::Ellipse(e) => {
            let f = e.frame();
            let l = dir.rotate_cs(co, -s);
            let h = f.half_size();
            // (t·l.x/a)² + (t·l.y/b)² = 1.
            let q = Vec2::new(l.x / h.x, l.y / h.y).norm();
            if q > 0.0 {
                1.0 / q
            } else {
                0.0
            }
        }
        Shape::Polygon(g) => {
            let v = g.vertices();
            let mut t = f32::INFINITY;
            for (i, a) in v.iter().enumerate() {
                let b = v.get(i + 1).or(v.first()).copied().unwrap_or(*a);
                let e = b - *a;
                // Outward normal of a counter-clockwise edge.
                let nrm = Vec2::new(e.y, -e.x);
                let nd = nrm.dot(dir);
                if nd > 0.0 {
                    t = min(t, nrm.dot(*a - c) / nd);
                }
            }
            if t.is_finite() {
                t
            } else {
                shape.bounding_radius()
            }
        }
    }
}

/// (1/d_o − 1/d_t)² of seed 003 eq. 5 for d_o ≤ d_t (the caller checks), with d_o clamped to
/// [`MIN_OBSTACLE_DISTANCE_M`] (also for a negative signed distance, inside an obstacle).
fn repulsion(d_o: f32, inv_dt: f32) -> f32 {
    let w = 1.0 / max(d_o, MIN_OBSTACLE_DISTANCE_M) - inv_dt;
    w * w
}

/// The K periphery points of an obstacle of bounding radius `radius` are too sparse for an
/// influence distance `dt`: neighbours more than d_t/2 apart along the facing half (πρ/(K − 1),
/// exact for a circle, an upper bound for the other shapes).
pub fn periphery_is_coarse(radius: f32, k: usize, dt: f32) -> bool {
    k < 2 || PI * radius > 0.5 * dt * (k - 1) as f32
}

/// Adds the obstacle points `points` (relative to the vehicle) to each arc point's
/// Σ(1/d_o − 1/d_t)² (eq. 5–6), for the pairs within d_t. Each arc point's sum takes the points
/// in their order, so the sums do not depend on how the points are batched.
fn accumulate(points: &[Vec2], arc: &[Vec2], rep: &mut [f32], dt2: f32, inv_dt: f32) {
    for (a, acc) in arc.iter().zip(rep.iter_mut()) {
        let mut sum = *acc;
        for p in points {
            let d2 = (*p - *a).norm2();
            if d2 <= dt2 {
                sum += repulsion(crate::math::sqrt(d2), inv_dt);
            }
        }
        *acc = sum;
    }
}

/// An obstacle point relative to the vehicle that can reach an arc point: finite and within
/// `reach` (r + d_t) of the vehicle; with its distance.
fn within_reach(p: Vec2, reach: f32) -> Option<f32> {
    let d2 = p.norm2();
    (p.is_finite() && d2 <= reach * reach).then(|| crate::math::sqrt(d2))
}

/// Obstacle points an obstacle counts for in [`MAX_PAIRS`]: K, and with a coarse periphery
/// [`COARSE_POINTS`] more for its N signed distances.
fn obstacle_points_counted(radius: f32, k: usize, dt: f32) -> usize {
    if periphery_is_coarse(radius, k, dt) {
        k + COARSE_POINTS
    } else {
        k
    }
}

/// Which obstacles and obstacle points [`region_of_interest`] selected: bit i for the i-th
/// of each kind it was given.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Selection {
    obstacles: u64,
    points: u64,
}

impl Selection {
    /// Whether the `i`-th obstacle is in the region of interest.
    pub fn obstacle(&self, i: usize) -> bool {
        i < MAX_SOURCES && self.obstacles & (1 << i) != 0
    }
    /// Whether the `i`-th obstacle point is in the region of interest.
    pub fn point(&self, i: usize) -> bool {
        i < MAX_SOURCES && self.points & (1 << i) != 0
    }
}

/// Most obstacles, and most obstacle points, [`region_of_interest`] considers; further ones
/// are left out (the world's tables hold 32 obstacles and 8 vehicles, and 32 map cells).
pub const MAX_SOURCES: usize = 64;

/// The region of interest of seed 003 §3 ("this region is defined by the detection range …
/// of the sonar sensor. The obstacles within this region are only selected"), held to
/// [`MAX_PAIRS`] (see the module notes): `obstacles` are the bounding circles (centre,
/// radius) of the obstacles [`choose`] would be given, `points` the obstacle points, both
/// relative to nothing (world frame) and iterated twice.
///
/// Everything within reach (bounding circle within r + d_t of `position`) is taken when its
/// pairs fit [`MAX_PAIRS`]. Otherwise the region shrinks: sources are taken by distance band
/// ((r + d_t)/[`BANDS`] deep), nearest band first, whole bands while they fit; in the first
/// band that does not, obstacles then points in the order given while they fit; nothing
/// farther. An obstacle counts K points (more with a coarse periphery), an obstacle point
/// one, each N pairs. A source that is not finite is not selected ([`choose`] refuses it).
pub fn region_of_interest(
    cfg: &ArcConfig,
    position: Vec2,
    obstacles: impl Iterator<Item = (Vec2, f32)> + Clone,
    points: impl Iterator<Item = Vec2> + Clone,
) -> Selection {
    let n = cfg.arc_points();
    let k = cfg.periphery_points();
    let dt = cfg.influence_m;
    let reach = cfg.arc_m + dt;
    // The band of a source whose nearest point is `gap` ≤ reach metres from the vehicle;
    // `as` saturates (a negative gap, inside an obstacle, is band 0).
    let band = |gap: f32| ((gap * (BANDS as f32 / reach)) as usize).min(BANDS - 1);
    let obstacle_gap = |(c, radius): (Vec2, f32)| {
        let gap = (c - position).norm() - radius;
        (gap <= reach).then_some(gap)
    };
    let point_gap = |p: Vec2| within_reach(p - position, reach);

    // How many pairs each band holds.
    let mut load = [0usize; BANDS];
    for o in obstacles.clone().take(MAX_SOURCES) {
        if let (Some(gap), true) = (obstacle_gap(o), o.1.is_finite()) {
            if let Some(l) = load.get_mut(band(gap)) {
                *l += obstacle_points_counted(o.1, k, dt) * n;
            }
        }
    }
    for p in points.clone().take(MAX_SOURCES) {
        if let Some(l) = point_gap(p).and_then(|gap| load.get_mut(band(gap))) {
            *l += n;
        }
    }
    // The first band that does not fit whole, and the pairs left for it.
    let mut last_band = BANDS;
    let mut spare = 0;
    let mut pairs = 0;
    for (b, &l) in load.iter().enumerate() {
        if pairs + l > MAX_PAIRS {
            last_band = b;
            spare = MAX_PAIRS - pairs;
            break;
        }
        pairs += l;
    }
    let mut take = |gap: f32, cost: usize| {
        let b = band(gap);
        if b < last_band {
            true
        } else if b == last_band && cost <= spare {
            spare -= cost;
            true
        } else {
            false
        }
    };
    let mut sel = Selection::default();
    for (i, o) in obstacles.enumerate().take(MAX_SOURCES) {
        if let (Some(gap), true) = (obstacle_gap(o), o.1.is_finite()) {
            if take(gap, obstacle_points_counted(o.1, k, dt) * n) {
                sel.obstacles |= 1 << i;
            }
        }
    }
    for (i, p) in points.enumerate().take(MAX_SOURCES) {
        if let Some(gap) = point_gap(p) {
            if take(gap, n) {
                sel.points |= 1 << i;
            }
        }
    }
    sel
}

/// Evaluates U_tot at every arc point (seed 003 eq. 4–7) and returns the point of least
/// potential (eq. 8), for the vehicle at `position` with heading ψ_h = `heading` (rad, world
/// frame) and forward speed u = `speed` (m/s). `obstacles` yields each obstacle's shape, already
/// moved to its predicted position by the caller; it is traversed once. `obstacle_points` are
/// further obstacle points taken as they are (one p_j each: the evidence map's cells).
///
/// Returns `None` when an input is not finite (position, heading, speed, goal, an obstacle's
/// centre or size), when `cfg` is not [valid](ArcConfig::is_valid), or when no arc point gives
/// a finite potential (which finite valid inputs never cause). Equal potentials go to the lower
/// index (the harder right turn). The goal may be anywhere, inside the arc or behind.
pub fn choose(
    cfg: &ArcConfig,
    position: Vec2,
    heading: f32,
    speed: f32,
    goal: Vec2,
    obstacles: impl Iterator<Item = Shape>,
    obstacle_points: impl Iterator<Item = Vec2>,
) -> Option<ArcChoice> {
    let inputs_finite =
        position.is_finite() && goal.is_finite() && heading.is_finite() && speed.is_finite();
    if !inputs_finite || !cfg.is_valid() {
        return None;
    }
    let n = cfg.arc_points();
    let k = cfg.periphery_points();
    let r = cfg.arc_m;
    let dt = cfg.influence_m;
    let u = min(max(speed, 0.0), MAX_SPEED);

    // The arc, relative to the vehicle (exact however large the coordinates).
    let mut arc = [Vec2::ZERO; MAX_ARC_POINTS];
    for (i, a) in arc.iter_mut().take(n).enumerate() {
        *a = Vec2::from_angle(cfg.arc_bearing(heading, i)) * r;
    }

    // Σ over obstacles and their periphery points of (1/d_o − 1/d_t)² (eq. 5–7 without the
    // common factor ½η·d_a², applied below).
    let mut rep = [0.0f32; MAX_ARC_POINTS];
    let reach = r + dt;
    let dt2 = dt * dt;
    let inv_dt = 1.0 / dt;
    let arc_n = arc.get(..n).unwrap_or(&arc);
    if cfg.eta > 0.0 {
        // The bounding circle's gap to the vehicle, if within reach: no periphery point of an
        // obstacle whose bounding circle is beyond r + d_t can come within d_t of an arc
        // point. (An offset that overflows to ∞ is beyond; all operands are finite, so no
        // NaN.) `None` for a shape that is not finite.
        let gap = |shape: &Shape| {
            let centre = shape.center();
            let radius = shape.bounding_radius();
            if !centre.is_finite() || !radius.is_finite() {
                return None;
            }
            let gap = (centre - position).norm() - radius;
            Some((gap <= reach).then_some((gap, radius)))
        };
        let mut rays = [(0.0, 0.0); MAX_PERIPHERY_POINTS];
        let m = facing_rays(k, &mut rays);
        let rays = rays.get(..m).unwrap_or(&[]);
        let mut points = [Vec2::ZERO; MAX_PERIPHERY_POINTS];
        for shape in obstacles {
            let Some((_, radius)) = gap(&shape)? else {
                continue;
            };
            let m = periphery_along(&shape, position, rays, &mut points);
            // Each p_j relative to the vehicle, those beyond reach left out.
            let mut near = 0;
            for j in 0..m {
                let p = points.get(j).copied().unwrap_or(Vec2::ZERO) - position;
                if within_reach(p, reach).is_some() {
                    if let Some(slot) = points.get_mut(near) {
                        *slot = p;
                        near += 1;
                    }
                }
            }
            accumulate(
                points.get(..near).unwrap_or(&[]),
                arc_n,
                &mut rep,
                dt2,
                inv_dt,
            );
            // Coarse periphery (see the module notes): the nearest boundary point joins the p_j.
            if periphery_is_coarse(radius, k, dt) {
                for (a, acc) in arc.iter().zip(rep.iter_mut()).take(n) {
                    let d = shape.signed_distance(position + *a);
                    if d <= dt {
                        *acc += repulsion(d, inv_dt);
                    }
                }
            }
        }

        // Obstacle points given as such (evidence-map cells): each is one p_j of eq. 5,
        // batched.
        let mut batch = 0;
        for p in obstacle_points {
            let p = p - position;
            if within_reach(p, reach).is_none() {
                continue;
            }
            if let Some(slot) = points.get_mut(batch) {
                *slot = p;
                batch += 1;
            }
            if batch == points.len() {
                accumulate(&points, arc_n, &mut rep, dt2, inv_dt);
                batch = 0;
            }
        }
        accumulate(
            points.get(..batch).unwrap_or(&[]),
            arc_n,
            &mut rep,
            dt2,
            inv_dt,
        );
    }

    // The goal, relative to the vehicle; halved if the difference overflows, then moved in
    // to MAX_GOAL_RANGE_M (its bearing is kept).
    let mut g = goal - position;
    if !g.is_finite() {
        g = goal * 0.5 - position * 0.5;
    }
    let extent = max(g.x.abs(), g.y.abs());
    if extent > MAX_GOAL_RANGE_M {
        g = g * (MAX_GOAL_RANGE_M / extent);
    }
    let dist = g.norm();
    let s = max(dist, 1.0);
    let inv_s = 1.0 / s;
    let lead = (dist + u) * inv_s;
    let half_xi = 0.5 * cfg.xi;
    let half_eta = 0.5 * cfg.eta;

    let mut best: Option<(usize, f32)> = None;
    for (i, (a, sum)) in arc.iter().zip(rep.iter()).take(n).enumerate() {
        let d_a = (g - *a).norm();
        // δ = d_a − D without cancellation: d_a² − D² = r² − 2⟨a, g⟩, and d_a + D ≥ r > 0.
        let delta = (r * r - 2.0 * a.dot(g)) / (d_a + dist);
        let dn = delta * inv_s;
        let an = d_a * inv_s;
        // (U_att(i) − ½ξ(D + u)²)/s², eq. 4 expanded about D.
        let att = cfg.xi * lead * dn + half_xi * dn * dn;
        // U_rep(i)/s², eq. 5–7.
        let rep_i = half_eta * an * an * *sum;
        let total = att + rep_i;
        if total.is_finite() && best.is_none_or(|(_, b)| total < b) {
            best = Some((i, total));
        }
    }
    let (i, total) = best?;
    let a = arc.get(i).copied().unwrap_or(Vec2::ZERO);
    let potential = (total + half_xi * lead * lead) * s * s;
    Some(ArcChoice {
        point: position + a,
        bearing: wrap_angle(cfg.arc_bearing(heading, i)),
        potential: if potential.is_finite() {
            potential
        } else {
            f32::MAX
        },
        index: i as u8,
    })
}

/// The re-planning interval of seed 003 §4 ("a time interval T that is proportional to the
/// velocity"; §5: every 1 s, i.e. every 1 m at 1 m/s), read as the time to cover the arc, r/u,
/// in whole planner periods of `period_s` seconds, rounded to the nearest and at least 1.
///
/// - `speed` ≤ 0 or NaN (a standstill, astern, bad navigation): no division; the cap
///   [`MAX_REPLAN_S`] in periods, which also bounds the interval at low speed;
/// - `period_s` or `arc_m` not positive and finite: 1 (re-plan every period, the safe side).
pub fn replan_periods(arc_m: f32, speed: f32, period_s: f32) -> u32 {
    if !(period_s > 0.0 && period_s.is_finite() && arc_m > 0.0 && arc_m.is_finite()) {
        return 1;
    }
    let cap = MAX_REPLAN_S / period_s;
    let periods = if speed > 0.0 {
        // min(NaN or ∞, cap) is cap.
        min(arc_m / speed / period_s, cap)
    } else {
        cap
    };
    // `as` saturates at u32::MAX.
    max(libm::roundf(periods), 1.0) as u32
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::FRAC_PI_4;

    fn none() -> core::iter::Empty<Shape> {
        core::iter::empty()
    }

    fn circle(x: f32, y: f32, r: f32) -> Shape {
        Shape::circle(Vec2::new(x, y), r).unwrap()
    }

    /// Angular step between arc points.
    fn resolution(cfg: &ArcConfig) -> f32 {
        2.0 * cfg.max_turn_rad / (cfg.arc_points() - 1) as f32
    }

    #[test]
    fn open_water_heads_for_the_goal_bearing() {
        let cfg = ArcConfig::default();
        let p = Vec2::new(3.0, -2.0);
        for (heading, goal) in [
            (0.0, Vec2::new(100.0, -2.0)),
            (0.3, Vec2::new(50.0, 20.0)),
            (1.9, Vec2::new(-20.0, 40.0)),
            (-2.5, Vec2::new(-60.0, -70.0)),
        ] {
            let c = choose(&cfg, p, heading, 1.0, goal, none(), core::iter::empty()).unwrap();
            let want = (goal - p).angle();
            let off = wrap_angle(c.bearing - want).abs();
            assert!(
                off <= 0.5 * resolution(&cfg) + 1e-4,
                "{heading}: off by {off}"
            );
            assert!(((c.point - p).norm() - cfg.arc_m).abs() < 1e-5);
            assert!(c.potential.is_finite() && c.potential > 0.0);
        }
        // Straight at the goal, with an odd N: the middle point.
        let c = choose(
            &cfg,
            p,
            0.0,
            1.0,
            Vec2::new(100.0, -2.0),
            none(),
            core::iter::empty(),
        )
        .unwrap();
        assert_eq!(c.index as usize, cfg.arc_points() / 2);
        assert!(c.bearing.abs() < 1e-6);
    }

    #[test]
    fn potential_is_eq_4_in_open_water() {
        let cfg = ArcConfig::default();
        let goal = Vec2::new(40.0, 0.0);
        let c = choose(
            &cfg,
            Vec2::ZERO,
            0.0,
            1.5,
            goal,
            none(),
            core::iter::empty(),
        )
        .unwrap();
        let d_a = (goal - c.point).norm();
        let want = 0.5 * cfg.xi * (d_a + 1.5) * (d_a + 1.5);
        assert!(
            (c.potential - want).abs() < 1e-4 * want,
            "{} vs {want}",
            c.potential
        );
    }

    #[test]
    fn choice_and_potential_match_eq_4_to_8_evaluated_directly() {
        let cfg = ArcConfig::default();
        let obstacles = [
            circle(6.0, 1.0, 3.0),
            circle(2.0, -7.0, 2.0),
            circle(50.0, 0.0, 4.0),
        ];
        for (p, heading, goal) in [
            (Vec2::new(1.0, 0.0), 0.1, Vec2::new(40.0, 3.0)),
            (Vec2::new(0.0, -2.0), -0.4, Vec2::new(12.0, -9.0)),
            (Vec2::new(-3.0, 1.0), 0.0, Vec2::new(200.0, 0.0)),
        ] {
            // Eq. 4–8 as printed, arc point by arc point.
            let mut want = (0, f32::INFINITY);
            for i in 0..cfg.arc_points() {
                let q = p + Vec2::from_angle(cfg.arc_bearing(heading, i)) * cfg.arc_m;
                let d_a = (q - goal).norm();
                let mut u_tot = 0.5 * cfg.xi * (d_a + 1.0) * (d_a + 1.0);
                for o in &obstacles {
                    let mut pts = [Vec2::ZERO; MAX_PERIPHERY_POINTS];
                    let k = periphery(o, p, cfg.periphery, &mut pts);
                    for pj in &pts[..k] {
                        let d_o = (q - *pj).norm();
                        if d_o <= cfg.influence_m {
                            let w = 1.0 / d_o - 1.0 / cfg.influence_m;
                            u_tot += 0.5 * cfg.eta * w * w * d_a * d_a;
                        }
                    }
                }
                if u_tot < want.1 {
                    want = (i, u_tot);
                }
            }
            let got = choose(
                &cfg,
                p,
                heading,
                1.0,
                goal,
                obstacles.iter().copied(),
                core::iter::empty(),
            )
            .unwrap();
            assert_eq!(got.index as usize, want.0, "{p:?}");
            assert!(
                (got.potential - want.1).abs() < 1e-4 * want.1,
                "{got:?} vs {want:?}"
            );
        }
    }

    #[test]
    fn goal_behind_turns_as_hard_as_allowed() {
        let cfg = ArcConfig::default();
        let last = cfg.arc_points() - 1;
        // Behind and a little to the left: the hardest left turn.
        let c = choose(
            &cfg,
            Vec2::ZERO,
            0.0,
            1.0,
            Vec2::new(-50.0, 1.0),
            none(),
            core::iter::empty(),
        )
        .unwrap();
        assert_eq!(c.index as usize, last);
        assert!((c.bearing - cfg.max_turn_rad).abs() < 1e-5);
        // Behind and to the right: the hardest right turn.
        let c = choose(
            &cfg,
            Vec2::ZERO,
            0.0,
            1.0,
            Vec2::new(-50.0, -1.0),
            none(),
            core::iter::empty(),
        )
        .unwrap();
        assert_eq!(c.index, 0);
        assert!((c.bearing + cfg.max_turn_rad).abs() < 1e-5);
        // Dead astern: either extreme.
        let c = choose(
            &cfg,
            Vec2::ZERO,
            0.0,
            1.0,
            Vec2::new(-50.0, 0.0),
            none(),
            core::iter::empty(),
        )
        .unwrap();
        assert!(c.index == 0 || c.index as usize == last, "{}", c.index);
        // Goal inside the arc, behind: still the nearest arc point, an extreme.
        let c = choose(
            &cfg,
            Vec2::ZERO,
            0.0,
            1.0,
            Vec2::new(-0.3, 0.2),
            none(),
            core::iter::empty(),
        )
        .unwrap();
        assert_eq!(c.index as usize, last);
    }

    #[test]
    fn obstacle_dead_ahead_turns_away_from_it() {
        let cfg = ArcConfig::default();
        for (obstacle, side) in [
            (circle(8.0, 0.3, 3.0), -1.0f32), // a little left of the line: turn right
            (circle(8.0, -0.3, 3.0), 1.0),    // a little right: turn left
            (circle(6.0, 0.0, 3.0), 0.0),     // on the line: either side, but off it
        ] {
            let c = choose(
                &cfg,
                Vec2::ZERO,
                0.0,
                1.0,
                Vec2::new(60.0, 0.0),
                [obstacle].into_iter(),
                core::iter::empty(),
            )
            .unwrap();
            assert!(c.point.y.abs() > 0.05, "stays on the line: {c:?}");
            if side != 0.0 {
                assert!(c.point.y * side > 0.0, "turned towards the obstacle: {c:?}");
            }
            assert!(obstacle.signed_distance(c.point) > 0.0);
        }
    }

    #[test]
    fn far_obstacles_change_nothing() {
        let cfg = ArcConfig::default();
        let goal = Vec2::new(80.0, 10.0);
        let free = choose(
            &cfg,
            Vec2::ZERO,
            0.2,
            1.0,
            goal,
            none(),
            core::iter::empty(),
        )
        .unwrap();
        let far = [circle(0.0, 30.0, 5.0), circle(-20.0, 0.0, 8.0)];
        let with = choose(
            &cfg,
            Vec2::ZERO,
            0.2,
            1.0,
            goal,
            far.into_iter(),
            core::iter::empty(),
        )
        .unwrap();
        assert_eq!(free, with);
        // η = 0 ignores even a near one.
        let cfg0 = ArcConfig { eta: 0.0, ..cfg };
        let near = [circle(4.0, 0.5, 2.0)];
        let a = choose(
            &cfg0,
            Vec2::ZERO,
            0.2,
            1.0,
            goal,
            near.into_iter(),
            core::iter::empty(),
        )
        .unwrap();
        let b = choose(
            &cfg0,
            Vec2::ZERO,
            0.2,
            1.0,
            goal,
            none(),
            core::iter::empty(),
        )
        .unwrap();
        assert_eq!(a, b);
    }

    fn check_periphery(shape: &Shape, viewer: Vec2, k: u8) {
        let mut out = [Vec2::ZERO; MAX_PERIPHERY_POINTS];
        let m = periphery(shape, viewer, k, &mut out);
        assert_eq!(m, (k as usize).min(MAX_PERIPHERY_POINTS));
        let c = shape.center();
        let tol = 1e-5 * shape.bounding_radius().max(1.0);
        let toward = (viewer - c).normalized(1e-6).unwrap();
        for p in &out[..m] {
            let d = shape.signed_distance(*p);
            assert!(d.abs() < tol, "{shape:?}: {p:?} is {d} off the boundary");
            let along = (*p - c).normalized(1e-9).unwrap().dot(toward);
            assert!(along > -1e-5, "{shape:?}: {p:?} is on the far half");
        }
        // Both flanks and the face are covered: first at −90°, middle facing, last at +90°.
        if m >= 3 {
            let dir = |p: Vec2| (p - c).normalized(1e-9).unwrap();
            assert!(dir(out[0]).dot(toward).abs() < 1e-4);
            assert!(toward.cross(dir(out[0])) < 0.0);
            assert!(toward.cross(dir(out[m - 1])) > 0.0);
            if m % 2 == 1 {
                assert!((dir(out[m / 2]).dot(toward) - 1.0).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn periphery_points_lie_on_the_facing_half_of_the_boundary() {
        let shapes = [
            circle(10.0, -4.0, 3.0),
            Shape::rectangle(Vec2::new(-5.0, 7.0), Vec2::new(4.0, 1.5), 0.7).unwrap(),
            Shape::ellipse(Vec2::new(20.0, 20.0), Vec2::new(6.0, 2.0), -1.2).unwrap(),
            Shape::polygon(&[
                Vec2::new(0.0, 0.0),
                Vec2::new(5.0, -1.0),
                Vec2::new(7.0, 3.0),
                Vec2::new(3.0, 6.0),
                Vec2::new(-1.0, 4.0),
            ])
            .unwrap(),
            Shape::polygon(&[
                Vec2::new(0.0, 0.0),
                Vec2::new(0.0, 2.0),
                Vec2::new(2.0, 0.0),
            ])
            .unwrap(),
        ];
        for shape in &shapes {
            for viewer in [
                Vec2::new(30.0, 1.0),
                Vec2::new(-12.0, -30.0),
                Vec2::new(0.5, 40.0),
            ] {
                for k in [1, 2, 3, 8, 9, 16] {
                    check_periphery(shape, viewer, k);
                }
            }
        }
    }

    #[test]
    fn periphery_of_a_circle_is_the_papers_semicircle() {
        let s = circle(0.0, 0.0, 2.0);
        let mut out = [Vec2::ZERO; 5];
        assert_eq!(periphery(&s, Vec2::new(10.0, 0.0), 5, &mut out), 5);
        let want = [
            Vec2::new(0.0, -2.0),
            Vec2::new(2.0 * libm::cosf(FRAC_PI_4), -2.0 * libm::sinf(FRAC_PI_4)),
            Vec2::new(2.0, 0.0),
            Vec2::new(2.0 * libm::cosf(FRAC_PI_4), 2.0 * libm::sinf(FRAC_PI_4)),
            Vec2::new(0.0, 2.0),
        ];
        for (p, w) in out.iter().zip(want) {
            assert!((*p - w).norm() < 1e-5, "{p:?} vs {w:?}");
        }
    }

    #[test]
    fn periphery_respects_k_capacity_and_the_output_length() {
        let s = circle(0.0, 0.0, 2.0);
        let v = Vec2::new(0.0, -9.0);
        let mut big = [Vec2::ZERO; 40];
        assert_eq!(periphery(&s, v, 16, &mut big), 16);
        assert_eq!(periphery(&s, v, 17, &mut big), MAX_PERIPHERY_POINTS);
        assert_eq!(periphery(&s, v, 255, &mut big), MAX_PERIPHERY_POINTS);
        assert_eq!(periphery(&s, v, 0, &mut big), 0);
        let mut small = [Vec2::ZERO; 3];
        assert_eq!(periphery(&s, v, 9, &mut small), 3);
        // Three points still span the whole facing half.
        assert!(
            (small[0] - Vec2::new(-2.0, 0.0)).norm() < 1e-5,
            "{:?}",
            small[0]
        );
        assert!((small[1] - Vec2::new(0.0, -2.0)).norm() < 1e-5);
        assert!((small[2] - Vec2::new(2.0, 0.0)).norm() < 1e-5);
        assert_eq!(periphery(&s, Vec2::new(f32::NAN, 0.0), 9, &mut big), 0);
        // A viewer at the centre faces +x.
        assert_eq!(periphery(&s, Vec2::ZERO, 1, &mut big), 1);
        assert!((big[0] - Vec2::new(2.0, 0.0)).norm() < 1e-6);
    }

    #[test]
    fn arc_and_periphery_counts_clamp_to_capacity() {
        let goal = Vec2::new(0.0, 50.0);
        let obstacles = || [circle(3.0, 0.0, 1.5), circle(-2.0, 4.0, 2.0)].into_iter();
        let at = |points: u8, periphery: u8| ArcConfig {
            points,
            periphery,
            ..ArcConfig::default()
        };
        let full = choose(
            &at(32, 16),
            Vec2::ZERO,
            0.4,
            1.0,
            goal,
            obstacles(),
            core::iter::empty(),
        )
        .unwrap();
        assert!((full.index as usize) < MAX_ARC_POINTS);
        for (points, periphery) in [(33, 16), (32, 17), (255, 255)] {
            let over = choose(
                &at(points, periphery),
                Vec2::ZERO,
                0.4,
                1.0,
                goal,
                obstacles(),
                core::iter::empty(),
            );
            assert_eq!(over, Some(full), "N = {points}, K = {periphery}");
        }
        assert_eq!(at(255, 255).arc_points(), MAX_ARC_POINTS);
        assert_eq!(at(255, 255).periphery_points(), MAX_PERIPHERY_POINTS);
        // 0 reads as 1: straight ahead is the only candidate.
        let one = choose(
            &at(0, 0),
            Vec2::ZERO,
            0.4,
            1.0,
            goal,
            obstacles(),
            core::iter::empty(),
        )
        .unwrap();
        assert_eq!(one.index, 0);
        assert!((one.bearing - 0.4).abs() < 1e-6);
        // The extremes of a full arc are exactly ±ψ_m.
        let cfg = at(32, 16);
        assert!((cfg.arc_bearing(0.0, 0) + cfg.max_turn_rad).abs() < 1e-6);
        assert!((cfg.arc_bearing(0.0, 31) - cfg.max_turn_rad).abs() < 1e-6);
    }

    #[test]
    fn non_finite_or_invalid_input_gives_none() {
        let cfg = ArcConfig::default();
        let p = Vec2::ZERO;
        let g = Vec2::new(10.0, 0.0);
        let nan = f32::NAN;
        assert_eq!(
            choose(
                &cfg,
                Vec2::new(nan, 0.0),
                0.0,
                1.0,
                g,
                none(),
                core::iter::empty()
            ),
            None
        );
        assert_eq!(
            choose(&cfg, p, nan, 1.0, g, none(), core::iter::empty()),
            None
        );
        assert_eq!(
            choose(&cfg, p, f32::INFINITY, 1.0, g, none(), core::iter::empty()),
            None
        );
        assert_eq!(
            choose(&cfg, p, 0.0, nan, g, none(), core::iter::empty()),
            None
        );
        assert_eq!(
            choose(
                &cfg,
                p,
                0.0,
                1.0,
                Vec2::new(0.0, nan),
                none(),
                core::iter::empty()
            ),
            None
        );
        let bad_obstacle = circle(3.0, 0.0, 1.0).translated(Vec2::new(nan, 0.0));
        assert_eq!(
            choose(
                &cfg,
                p,
                0.0,
                1.0,
                g,
                [bad_obstacle].into_iter(),
                core::iter::empty()
            ),
            None
        );
        for bad in [
            ArcConfig { arc_m: 0.0, ..cfg },
            ArcConfig { xi: nan, ..cfg },
            ArcConfig { eta: -1.0, ..cfg },
            ArcConfig {
                influence_m: f32::INFINITY,
                ..cfg
            },
            ArcConfig {
                max_turn_rad: 4.0,
                ..cfg
            },
        ] {
            assert!(!bad.is_valid());
            assert_eq!(
                choose(&bad, p, 0.0, 1.0, g, none(), core::iter::empty()),
                None
            );
        }
        assert!(cfg.is_valid());
    }

    #[test]
    fn finite_input_gives_a_finite_choice_in_the_corners() {
        let cfg = ArcConfig::default();
        let o = circle(2.0, 0.0, 3.0);
        // Vehicle inside an obstacle, on its centre, exactly on a periphery point.
        for p in [
            Vec2::new(1.0, 0.5),
            Vec2::new(2.0, 0.0),
            Vec2::new(-1.0, 0.0),
        ] {
            let c = choose(
                &cfg,
                p,
                0.0,
                1.0,
                Vec2::new(30.0, 0.0),
                [o].into_iter(),
                core::iter::empty(),
            )
            .unwrap();
            assert!(c.point.is_finite() && c.potential.is_finite(), "{c:?}");
        }
        // An arc point exactly on a periphery point (the facing point of this circle).
        let touching = circle(2.0, 0.0, 1.0);
        let c = choose(
            &cfg,
            Vec2::ZERO,
            0.0,
            1.0,
            Vec2::new(30.0, 0.0),
            [touching].into_iter(),
            core::iter::empty(),
        )
        .unwrap();
        assert!(c.potential.is_finite() && c.index as usize != cfg.arc_points() / 2);
        // Goal on the vehicle, speed 0, astern, huge.
        for speed in [0.0, -3.0, 1e30] {
            let c = choose(
                &cfg,
                Vec2::ZERO,
                0.0,
                speed,
                Vec2::ZERO,
                none(),
                core::iter::empty(),
            )
            .unwrap();
            assert!(c.potential.is_finite());
        }
        // Extreme coordinates: far goal, overflowing offsets, far vehicle.
        let big = f32::MAX;
        let cases = [
            (Vec2::ZERO, Vec2::new(1e30, 1e30)),
            (Vec2::new(-big, -big), Vec2::new(big, big)),
            (Vec2::new(1e20, -1e20), Vec2::new(1e20 + 1e14, -1e20)),
        ];
        for (p, g) in cases {
            let c = choose(
                &cfg,
                p,
                0.0,
                1.0,
                g,
                [o, o.translated(p)].into_iter(),
                core::iter::empty(),
            )
            .unwrap();
            assert!(c.point.is_finite() && c.potential.is_finite(), "{c:?}");
        }
        // The far goal's bearing still wins in open water.
        let c = choose(
            &cfg,
            Vec2::ZERO,
            0.0,
            1.0,
            Vec2::new(1e30, 1e30),
            none(),
            core::iter::empty(),
        )
        .unwrap();
        assert!((c.bearing - cfg.max_turn_rad).abs() < 1e-5, "{c:?}");
        let c = choose(
            &cfg,
            Vec2::ZERO,
            0.0,
            1.0,
            Vec2::new(1e30, 1e28),
            none(),
            core::iter::empty(),
        )
        .unwrap();
        assert!(
            (c.bearing - 0.01).abs() <= 0.5 * resolution(&cfg) + 1e-5,
            "{c:?}"
        );
        // Extreme gains.
        let hard = ArcConfig {
            eta: 1e6,
            xi: 1e-3,
            influence_m: 1000.0,
            ..cfg
        };
        let many = core::iter::repeat_n(o, 1000);
        let c = choose(
            &hard,
            Vec2::new(-0.5, 0.0),
            0.0,
            1.0,
            Vec2::new(1e5, 0.0),
            many,
            core::iter::empty(),
        )
        .unwrap();
        assert!(c.potential.is_finite());
    }

    /// A point vehicle at `speed` hopping to the chosen arc point every `replan_periods`:
    /// returns (reached, steps, least clearance to any obstacle along the path).
    fn run(
        cfg: &ArcConfig,
        start: Vec2,
        heading: f32,
        goal: Vec2,
        obstacles: &[Shape],
        max_steps: usize,
    ) -> (bool, usize, f32) {
        let period = 0.1;
        let speed = 1.0;
        let mut p = start;
        let mut heading = heading;
        let mut clearance = f32::INFINITY;
        for step in 0..max_steps {
            if (goal - p).norm() < 2.0 {
                return (true, step, clearance);
            }
            let c = choose(
                cfg,
                p,
                heading,
                speed,
                goal,
                obstacles.iter().copied(),
                core::iter::empty(),
            )
            .unwrap();
            let n = replan_periods(cfg.arc_m, speed, period);
            let travel = speed * period * n as f32;
            let dir = (c.point - p).normalized(1e-9).unwrap();
            // Check clearance along the hop, every 10 cm.
            for sub in 1..=10 {
                let q = p + dir * (travel * sub as f32 / 10.0);
                for o in obstacles {
                    clearance = clearance.min(o.signed_distance(q));
                }
            }
            p += dir * travel;
            heading = dir.angle();
        }
        (false, max_steps, clearance)
    }

    #[test]
    fn head_on_circle_15_m_ahead_is_avoided_in_time() {
        let cfg = ArcConfig::default();
        // 3 m radius, 15 m ahead, dead on the track; goals near and far beyond.
        let o = [circle(15.0, 0.0, 3.0)];
        for goal_x in [20.0, 25.0, 40.0, 100.0, 300.0] {
            let goal = Vec2::new(goal_x, 0.0);
            let (reached, _, clear) = run(&cfg, Vec2::ZERO, 0.0, goal, &o, 1000);
            assert!(reached, "goal at {goal_x}");
            assert!(clear > 2.5, "goal at {goal_x}: clearance {clear}");
        }
    }

    #[test]
    fn passes_beside_and_between_obstacles() {
        let cfg = ArcConfig::default();
        let goal = Vec2::new(100.0, 0.0);
        // An obstacle 2 m or 6 m clear of the track: pushed out to about d_t − 1 m.
        for clear in [2.0, 6.0] {
            let o = [circle(15.0, clear + 3.0, 3.0)];
            let (reached, steps, c) = run(&cfg, Vec2::ZERO, 0.0, goal, &o, 400);
            assert!(reached && steps < 110, "{clear}: {steps}");
            assert!(
                c > cfg.influence_m - 2.0 && c < cfg.influence_m,
                "{clear}: {c}"
            );
        }
        // Gaps of 6 and 14 m between two 5 m circles: taken down the middle.
        for gap in [6.0f32, 14.0] {
            let o = [
                circle(30.0, 5.0 + gap / 2.0, 5.0),
                circle(30.0, -5.0 - gap / 2.0, 5.0),
            ];
            let (reached, steps, c) = run(&cfg, Vec2::ZERO, 0.0, Vec2::new(100.0, 0.3), &o, 400);
            assert!(reached && steps < 110, "{gap}: {steps}");
            assert!(c > 0.4 * gap, "{gap}: {c}");
        }
    }

    #[test]
    fn large_obstacles_are_not_entered_between_periphery_points() {
        // An even K has no point facing the vehicle; on a 60 m circle its points are 12.6 m
        // apart, more than d_t: without the nearest-point term the vehicle drives straight in.
        let cfg = ArcConfig {
            periphery: 16,
            ..ArcConfig::default()
        };
        for rad in [15.0f32, 60.0] {
            assert_eq!(
                periphery_is_coarse(rad, cfg.periphery_points(), cfg.influence_m),
                rad > 20.0
            );
            let o = [circle(20.0 + rad, 0.5, rad)];
            let goal = Vec2::new(60.0 + 2.0 * rad, 0.0);
            let (reached, _, c) = run(&cfg, Vec2::ZERO, 0.0, goal, &o, 2000);
            assert!(reached && c > 2.5, "radius {rad}: clearance {c}");
        }
        // A 100 m wall 2 m off the track, and the default K.
        let cfg = ArcConfig::default();
        let wall = Shape::rectangle(Vec2::new(60.0, 3.0), Vec2::new(50.0, 1.0), 0.02).unwrap();
        assert!(periphery_is_coarse(
            wall.bounding_radius(),
            9,
            cfg.influence_m
        ));
        let (reached, _, c) = run(&cfg, Vec2::ZERO, 0.0, Vec2::new(120.0, 0.0), &[wall], 400);
        assert!(reached && c > 2.5, "wall: clearance {c}");
        // The defaults' periphery is dense up to ρ = 10.2 m: the paper's eq. 5–7 exactly.
        assert!(!periphery_is_coarse(10.0, 9, 8.0));
        assert!(periphery_is_coarse(10.5, 9, 8.0));
        assert!(periphery_is_coarse(0.1, 1, 8.0));
    }

    #[test]
    fn paper_scenario_reaches_the_goal_without_collision() {
        let cfg = ArcConfig::default();
        // Seed 003 §5, case 1: (30, 20) to (170, 170) past static circles of 5–10 m.
        let obstacles = [
            circle(60.0, 52.0, 8.0),
            circle(100.0, 90.0, 10.0),
            circle(118.0, 125.0, 6.0),
            circle(140.0, 138.0, 5.0),
            circle(85.0, 55.0, 7.0),
        ];
        let start = Vec2::new(30.0, 20.0);
        let goal = Vec2::new(170.0, 170.0);
        let (reached, steps, clear) = run(&cfg, start, 0.0, goal, &obstacles, 1000);
        assert!(reached, "after {steps} steps");
        assert!(clear > 2.5, "came within {clear} m of an obstacle");
        // About the straight-line 205 m plus detours.
        assert!(steps < 300, "{steps} steps");
    }

    #[test]
    fn region_of_interest_takes_everything_in_reach_when_it_fits() {
        extern crate std;
        use std::vec::Vec;
        let cfg = ArcConfig::default();
        let obstacles = [
            (Vec2::new(3.0, 0.0), 1.0),
            (Vec2::new(0.0, -6.0), 2.0),
            (Vec2::new(30.0, 0.0), 1.0), // beyond r + d_t
            (Vec2::new(f32::NAN, 0.0), 1.0),
        ];
        let points = [Vec2::new(2.0, 2.0), Vec2::new(0.0, 20.0)];
        let sel = region_of_interest(
            &cfg,
            Vec2::ZERO,
            obstacles.iter().copied(),
            points.iter().copied(),
        );
        let taken: Vec<bool> = (0..4).map(|i| sel.obstacle(i)).collect();
        assert_eq!(taken, [true, true, false, false]);
        assert!(sel.point(0) && !sel.point(1));
    }

    #[test]
    fn region_of_interest_holds_the_pair_budget_nearest_first() {
        extern crate std;
        use std::vec::Vec;
        let cfg = ArcConfig::default();
        let (n, k) = (cfg.arc_points(), cfg.periphery_points());
        // 40 small obstacles from 1.5 m to 9 m, in a shuffled order, and 32 points at 4–5 m.
        let gap = |i: usize| 1.5 + 7.5 * ((i * 17) % 40) as f32 / 40.0;
        let obstacles: Vec<(Vec2, f32)> = (0..40)
            .map(|i| (Vec2::from_angle(i as f32 * 0.7) * (gap(i) + 0.5), 0.5))
            .collect();
        let points: Vec<Vec2> = (0..32)
            .map(|i| Vec2::from_angle(i as f32 * 0.2) * (4.0 + i as f32 / 32.0))
            .collect();
        let sel = region_of_interest(
            &cfg,
            Vec2::ZERO,
            obstacles.iter().copied(),
            points.iter().copied(),
        );
        let taken_o: Vec<usize> = (0..40).filter(|&i| sel.obstacle(i)).collect();
        let taken_p = (0..32).filter(|&i| sel.point(i)).count();
        let pairs = (taken_o.len() * k + taken_p) * n;
        assert!(pairs <= MAX_PAIRS, "{pairs} pairs");
        // Nothing left out is nearer, by a band, than something taken.
        let band = (cfg.arc_m + cfg.influence_m) / BANDS as f32;
        let farthest_taken = taken_o.iter().map(|&i| gap(i)).fold(0.0, f32::max);
        for i in (0..40).filter(|i| !taken_o.contains(i)) {
            assert!(gap(i) > farthest_taken - band - 1e-4, "obstacle {i}");
        }
        // And the budget is used: the next source would not have fitted.
        assert!(pairs + k * n > MAX_PAIRS, "{pairs} pairs");
    }

    #[test]
    fn replan_interval_is_the_time_to_cover_the_arc() {
        assert_eq!(replan_periods(1.0, 1.0, 0.1), 10);
        assert_eq!(replan_periods(1.0, 2.0, 0.1), 5);
        assert_eq!(replan_periods(1.0, 0.5, 0.1), 20);
        assert_eq!(replan_periods(1.0, 20.0, 0.1), 1);
        assert_eq!(replan_periods(1.0, 1.0, 1.0), 1);
        // Standstill, astern, NaN, very slow: the cap, no division by zero.
        let cap = libm::roundf(MAX_REPLAN_S / 0.1) as u32;
        for v in [0.0, -1.0, f32::NAN, 1e-30, f32::MIN_POSITIVE] {
            assert_eq!(replan_periods(1.0, v, 0.1), cap, "speed {v}");
        }
        assert_eq!(replan_periods(1.0, f32::INFINITY, 0.1), 1);
        // Bad period or arc: every period.
        for (arc, period) in [
            (1.0, 0.0),
            (1.0, -0.1),
            (1.0, f32::NAN),
            (0.0, 0.1),
            (f32::NAN, 0.1),
        ] {
            assert_eq!(replan_periods(arc, 1.0, period), 1);
        }
        assert_eq!(replan_periods(1.0, 0.0, 1e-30), u32::MAX);
    }
}
