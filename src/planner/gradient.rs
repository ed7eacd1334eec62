//! The virtual potential E and its sampled gradient, seed 000 eq. 1–4 and 001 eq. 4.
//!
//! E(p) = Σ f_obj(p) over obstacles (stator + rotor), other vehicles and attractors (eq. 1).
//! The controlling force is the largest potential drop from the vehicle to one of n_γ points on
//! a circle of radius ε around it, pointing at that point (eq. 2–4):
//!
//! |F_nf| = maxᵢ [E(p) − E(p + ε·γ̂ᵢ)],  ∠F_nf = ∠γ̂ᵢ of that maximum.
//!
//! When no sample is lower than the vehicle (a sampled local minimum) F_nf is zero. The sample
//! offsets ε·γ̂ᵢ are precomputed in a [`SampleCircle`] when the parameters change, so one step
//! costs (n_γ + 1) potential evaluations of multiply–adds, one `exp` and one square root per
//! object, and no trigonometry.
//!
//! The same pass also yields the force of two partial fields — without the formation's virtual
//! leader, and without the other vehicles too — which the local-minimum test needs to tell what
//! holds a stalled vehicle (`escape.rs`). Keeping the potential's terms apart costs three
//! additions per sample instead of two more passes.

use crate::field::edges::EdgeTable;
use crate::field::{GoalPdf, Shape, Stator};
use crate::math::{Vec2, TAU};
use crate::params::N_GAMMA_MAX;
use crate::world::{nearest_cell, Agent, Obstacle, Origin, MAX_MAP_CELLS};

/// The n_γ sample offsets ε·(cos 2πi/n_γ, sin 2πi/n_γ) (000 eq. 3–4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleCircle {
    offsets: [Vec2; N_GAMMA_MAX],
    n: usize,
    epsilon: f32,
}

impl SampleCircle {
    /// Precomputes the offsets (n is clamped to the table capacity; parameters are validated
    /// before this is called).
    pub fn new(epsilon: f32, n_gamma: u8) -> Self {
        let n = (n_gamma as usize).clamp(1, N_GAMMA_MAX);
        let mut offsets = [Vec2::ZERO; N_GAMMA_MAX];
        for (i, o) in offsets.iter_mut().take(n).enumerate() {
            *o = Vec2::from_angle(TAU * i as f32 / n as f32) * epsilon;
        }
        SampleCircle {
            offsets,
            n,
            epsilon,
        }
    }

    /// The offsets in use.
    pub fn offsets(&self) -> &[Vec2] {
        self.offsets.get(..self.n).unwrap_or(&[])
    }

    /// ε.
    pub fn epsilon(&self) -> f32 {
        self.epsilon
    }
}

/// The sampled force of the whole field and of two partial fields (see the module notes).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Forces {
    /// F_nf of the whole field.
    pub full: Vec2,
    /// F_nf without the virtual leader.
    pub without_leader: Vec2,
    /// F_nf of the static field: obstacles (stator and rotor) and the goal-point only.
    pub static_field: Vec2,
}

/// Everything that shapes E during one step, borrowed from the world and the planner.
pub struct Field<'a> {
    /// Obstacles (stator PDFs with their own A⁺).
    pub obstacles: &'a [Obstacle],
    /// Where each obstacle is evaluated relative to its table position (moving obstacles at
    /// their predicted positions), one per obstacle; an obstacle without one is left out.
    pub shifts: &'a [Vec2],
    /// Each obstacle's signed distance r and its gradient ∇r at the vehicle, evaluated where
    /// the obstacle is ([`Shape::distance_gradient`] at `origin − shift`); those missing are
    /// evaluated here.
    pub distances: &'a [(f32, Vec2)],
    /// Other vehicles, seen as circles of radius `agent_radius` (000 §III).
    pub agents: &'a [Agent],
    /// r₀ of an agent's circle.
    pub agent_radius: f32,
    /// Stator of an agent's circle (A⁺ of 000 §III).
    pub agent_stator: Stator,
    /// The active goal-point (the mission goal or a ghost).
    pub goal: GoalPdf,
    /// The formation's virtual leader, if any.
    pub leader: Option<GoalPdf>,
    /// Sum of the obstacles' rotor gradients this step (see [`crate::field::rotor`]).
    pub rotor_gradient: Vec2,
    /// The vehicle's position, where the rotor potential is zero.
    pub origin: Vec2,
    /// Believed evidence-map cells near the vehicle (centres), each a disc of `map_radius`.
    /// Together they are one obstacle: E gains f(r) of [`Field::map_stator`] with r the
    /// distance to the nearest disc (see `crate::sonar::evidence` for why one, not a sum).
    pub map: &'a [Vec2],
    /// Radius of a map cell's disc, m.
    pub map_radius: f32,
    /// Stator of the map (A_s⁺, as sensed obstacles get).
    pub map_stator: Stator,
    /// Leave still sonar-extracted obstacles out: the map holds their echoes
    /// ([`crate::world::World::left_to_map`]).
    pub leave_to_map: bool,
}

/// The terms of E at one point, kept apart: (obstacles and goal-point, other vehicles, leader).
#[derive(Clone, Copy)]
struct Terms {
    fixed: f32,
    vehicles: f32,
    leader: f32,
}

/// The far field's error per object, in units of F_nf (potential per metre): an object whose
/// linearisation errs by at most this much on every sample is linearised ([`far_gradient`]).
/// With every one of 32 obstacles and 8 vehicles at that bound, F_nf errs by at most 0.008,
/// 1.6 % of the default F_max (0.5) and a fifth of the friction at the default stall speed
/// (μ·0.05 = 0.02); a real table's far objects err far less (the bound falls as r⁻⁴).
pub const FAR_FORCE_ERROR: f32 = 2e-4;

/// The gradient of a stator PDF f(r(x)) (000 eq. 9, 12) at the vehicle, if the object is far
/// enough to be linearised over the sample circle; `None` if it must be sampled.
///
/// **Departure from the paper (an approximation), and its bound.** Eq. 2–4 evaluate E at the
/// n_γ sample points. An object at distance r ≫ ε contributes across the circle, to first
/// order, its value at the centre plus ⟨ε·γ̂ᵢ, ∇f⟩; its value cancels in every drop
/// E(p) − E(p + ε·γ̂ᵢ), so it adds −⟨ε·γ̂ᵢ, ∇f⟩ — one dot product per sample for all far
/// objects together, as the rotor terms do. Taylor's remainder bounds the error on each drop
/// by ½ε²·sup‖∇²f‖ over the circle, and for f(r) = e^{A/r²} − 1 with x = A/r²:
/// ‖∇²f‖ ≤ f″(r) + |f′(r)|·‖∇²r‖ = e^x·(4x² + 6x)/r² + 2x·e^x/r · 1/r = 4x·e^x·(x + 2)/r²,
/// since the distance to a convex shape has ‖∇²r‖ ≤ 1/r. All of it falls with r, so it is
/// taken at r_m = r − ε, the nearest the circle comes (r is 1-Lipschitz). Linearising only
/// where x = A/r_m² ≤ 1/8 (e^x ≤ 1.134), the error on F_nf = drop/ε is at most
/// 2ε·x·e^x·(x + 2)/r_m² ≤ 4.82·ε·A/r_m⁴, and the object is linearised when that is at most
/// [`FAR_FORCE_ERROR`]: with the defaults (A⁺ = 2.5, ε = 0.25 m) beyond r ≈ 11.3 m.
///
/// The ellipse's distance is an estimate (`field::shape`), homogeneous of degree one far out
/// but not the Euclidean distance: its curvature across rays grows with the aspect ratio (a
/// 2.4:1 ellipse erred 3.5 × the circle's bound at 19 m in the test). It is held to the bound
/// multiplied by `kappa` = (a/b)² (long over short semi-axis, squared; 1 for the other
/// shapes), i.e. linearised (a/b)^½ times farther out — a factor chosen, not derived, and
/// checked for every shape against the sampled field over random worlds
/// (`tests::far_field_stays_within_its_bound`).
#[inline(always)]
fn far_gradient(stator: &Stator, r: f32, grad_r: Vec2, epsilon: f32, kappa: f32) -> Option<Vec2> {
    let r_m = r - epsilon;
    let a = stator.a_plus();
    let r_m2 = r_m * r_m;
    // x = A/r_m² ≤ 1/8 and 4.82·ε·A·κ ≤ FAR_FORCE_ERROR·r_m⁴, without a division.
    let error = 4.82 * epsilon * a * kappa;
    if r_m <= 0.0 || 8.0 * a > r_m2 || error > FAR_FORCE_ERROR * r_m2 * r_m2 {
        return None;
    }
    Some(grad_r * stator.slope(r))
}

/// The far field's curvature factor κ of a shape ([`far_gradient`]): (a/b)² for an ellipse,
/// 1 for the exact distances.
fn curvature(shape: &Shape) -> f32 {
    match shape {
        Shape::Ellipse(e) => {
            let s = e.frame().half_size();
            let q = crate::math::max(s.x, s.y) / crate::math::min(s.x, s.y);
            q * q
        }
        _ => 1.0,
    }
}

/// Adds `f(x − shift)` at every sample point x (the centre, then the circle) to `acc`.
#[inline(always)]
fn add_samples(
    acc: &mut [f32],
    origin: Vec2,
    offsets: &[Vec2],
    shift: Vec2,
    centre: f32,
    f: impl Fn(Vec2) -> f32,
) {
    let Some((first, rest)) = acc.split_first_mut() else {
        return;
    };
    *first += centre;
    for (a, off) in rest.iter_mut().zip(offsets) {
        *a += f((origin + *off) - shift);
    }
}

impl Field<'_> {
    /// E(x) (000 eq. 1; 001 eq. 2).
    pub fn potential(&self, x: Vec2) -> f32 {
        let t = self.terms(x);
        t.fixed + t.vehicles + t.leader
    }

    fn terms(&self, x: Vec2) -> Terms {
        let mut fixed = (x - self.origin).dot(self.rotor_gradient) + self.goal.potential(x);
        for (o, &shift) in self.obstacles.iter().zip(self.shifts) {
            if self.leave_to_map && o.origin == Origin::Sonar && o.velocity == Vec2::ZERO {
                continue;
            }
            fixed += o.stator().potential(o.shape.signed_distance(x - shift));
        }
        if let Some((_, d)) = nearest_cell(self.map, x) {
            fixed += self.map_stator.potential(d - self.map_radius);
        }
        let mut vehicles = 0.0;
        for a in self.agents {
            let r = (x - a.position).norm() - self.agent_radius;
            vehicles += self.agent_stator.potential(r);
        }
        let leader = self.leader.map_or(0.0, |l| l.potential(x));
        Terms {
            fixed,
            vehicles,
            leader,
        }
    }

    /// F_nf, the no-friction controlling force (000 eq. 2; 001 eq. 4), sampled around
    /// [`Field::origin`], for the whole field and the two partial fields.
    ///
    /// Object by object: each near object is evaluated at the centre and the n_γ samples
    /// into one sum per sample (so its shape is dispatched and its constants loaded once,
    /// not per sample), each far one only linearised ([`far_gradient`]). The sums are added
    /// in the order [`Field::potential`] adds them, so with no far object every drop is the
    /// same number, bit for bit, as from n_γ + 1 calls of it.
    pub fn sampled_forces(&self, circle: &SampleCircle) -> Forces {
        let offsets = circle.offsets();
        let samples = offsets.len() + 1;
        let epsilon = circle.epsilon();
        let origin = self.origin;
        let mut fixed = [0.0f32; N_GAMMA_MAX + 1];
        let mut vehicles = [0.0f32; N_GAMMA_MAX + 1];
        let fixed = fixed.get_mut(..samples).unwrap_or(&mut []);
        let vehicles = vehicles.get_mut(..samples).unwrap_or(&mut []);

        // The rotor's linear term and the goal-point, at every sample.
        if let Some((first, rest)) = fixed.split_first_mut() {
            // (x − origin is exactly zero at the centre.)
            *first = Vec2::ZERO.dot(self.rotor_gradient) + self.goal.potential(origin);
            for (f, off) in rest.iter_mut().zip(offsets) {
                let x = origin + *off;
                *f = (x - origin).dot(self.rotor_gradient) + self.goal.potential(x);
            }
        }
        // The obstacles, in table order: a near one sampled, a far one's gradient summed.
        let mut far = Vec2::ZERO;
        // A polygon's edge table, made when the first near polygon comes.
        let mut edges: Option<EdgeTable> = None;
        for (i, (o, &shift)) in self.obstacles.iter().zip(self.shifts).enumerate() {
            if self.leave_to_map && o.origin == Origin::Sonar && o.velocity == Vec2::ZERO {
                continue;
            }
            let st = *o.stator();
            let (r, g) = match self.distances.get(i) {
                Some(&d) => d,
                None => o.shape.distance_gradient(origin - shift),
            };
            if let Some(g) = far_gradient(&st, r, g, epsilon, curvature(&o.shape)) {
                far += g;
                continue;
            }
            let centre = st.potential(r);
            match &o.shape {
                Shape::Circle(c) => add_samples(fixed, origin, offsets, shift, centre, |x| {
                    st.potential(c.signed_distance(x))
                }),
                Shape::Rectangle(r) => match r.disc_around(origin, shift, epsilon) {
                    Some(disc) => add_samples(fixed, origin, offsets, shift, centre, |x| {
                        st.potential(r.outside_distance(x, disc))
                    }),
                    None => add_samples(fixed, origin, offsets, shift, centre, |x| {
                        st.potential(r.signed_distance(x))
                    }),
                },
                Shape::Ellipse(e) => add_samples(fixed, origin, offsets, shift, centre, |x| {
                    st.potential(e.signed_distance(x))
                }),
                Shape::Polygon(g) => {
                    let edges = edges.get_or_insert_with(EdgeTable::new);
                    edges.fill(g, origin, shift, epsilon);
                    add_samples(fixed, origin, offsets, shift, centre, |x| {
                        st.potential(edges.signed_distance(g, x))
                    })
                }
            }
        }
        // The evidence map: one obstacle, the distance to its nearest cell.
        if !self.map.is_empty() {
            let st = self.map_stator;
            let (d2, bounds) = map_bounds(self.map, origin, epsilon);
            let centre = st.potential(crate::math::sqrt(d2) - self.map_radius);
            add_samples(fixed, origin, offsets, Vec2::ZERO, centre, |x| {
                st.potential(
                    nearest_distance_bounded(self.map, bounds.as_ref(), x) - self.map_radius,
                )
            });
        }
        // The other vehicles, likewise.
        let mut far_vehicles = Vec2::ZERO;
        for a in self.agents {
            let st = self.agent_stator;
            let radius = self.agent_radius;
            let d = origin - a.position;
            let len = d.norm();
            let r = len - radius;
            if len > 0.0 {
                if let Some(g) = far_gradient(&st, r, d * (1.0 / len), epsilon, 1.0) {
                    far_vehicles += g;
                    continue;
                }
            }
            add_samples(
                vehicles,
                origin,
                offsets,
                a.position,
                st.potential(r),
                |x| st.potential(x.norm() - radius),
            );
        }
        // The far objects' linear terms, last (adding zero when there are none leaves every
        // sum as it was).
        for ((f, v), off) in fixed
            .iter_mut()
            .zip(vehicles.iter_mut())
            .skip(1)
            .zip(offsets)
        {
            let x = origin + *off;
            *f += (x - origin).dot(far);
            *v += (x - origin).dot(far_vehicles);
        }

        let leader0 = self.leader.map_or(0.0, |l| l.potential(origin));
        let (f0, v0) = (
            fixed.first().copied().unwrap_or(0.0),
            vehicles.first().copied().unwrap_or(0.0),
        );
        let mut best = [(0.0f32, Vec2::ZERO); 3];
        let rest = fixed.iter().zip(vehicles.iter()).skip(1);
        for ((f, v), off) in rest.zip(offsets) {
            let leader = self.leader.map_or(0.0, |l| l.potential(origin + *off));
            let fixed = f0 - f;
            let without_leader = fixed + (v0 - v);
            let full = without_leader + (leader0 - leader);
            for (slot, drop) in best.iter_mut().zip([full, without_leader, fixed]) {
                if drop > slot.0 {
                    *slot = (drop, *off);
                }
            }
        }
        // Each direction has length ε; F_nf has the drop as modulus.
        let force = |(drop, dir): (f32, Vec2)| dir * (drop / epsilon);
        let [full, without_leader, static_field] = best;
        Forces {
            full: force(full),
            without_leader: force(without_leader),
            static_field: force(static_field),
        }
    }
}

/// The squared distance from `origin` to the nearest of `centers`, and, when `centers` are
/// nearest first (as the runtime gives them, `crate::sonar::EvidenceMap::nearest`) and fit,
/// for each a lower bound on its squared distance from any sample point (distance less ε,
/// with a margin for rounding), ascending.
fn map_bounds(centers: &[Vec2], origin: Vec2, epsilon: f32) -> (f32, Option<[f32; MAX_MAP_CELLS]>) {
    let mut best = f32::INFINITY;
    let mut bounds = [0.0f32; MAX_MAP_CELLS];
    let mut sorted = centers.len() <= MAX_MAP_CELLS;
    let mut last = 0.0f32;
    for (&c, slot) in centers.iter().zip(bounds.iter_mut()) {
        let d2 = (c - origin).norm2();
        if d2 < best {
            best = d2;
        }
        let d = crate::math::sqrt(d2) - (epsilon * 1.001 + 1e-4);
        let bound = if d > 0.0 { d * d } else { 0.0 };
        sorted &= bound >= last;
        last = bound;
        *slot = bound;
    }
    (best, sorted.then_some(bounds))
}

/// As [`nearest_distance`] (the same number), but with [`map_bounds`]'s ascending lower
/// bounds the search stops at the first cell that cannot be strictly nearer than the best so
/// far, nor can any after it: on the sample circle, a few cells instead of all.
#[inline(always)]
fn nearest_distance_bounded(
    centers: &[Vec2],
    bounds: Option<&[f32; MAX_MAP_CELLS]>,
    x: Vec2,
) -> f32 {
    let Some(bounds) = bounds else {
        return nearest_distance(centers, x);
    };
    let mut best = f32::INFINITY;
    for (&c, &bound) in centers.iter().zip(bounds) {
        if bound >= best {
            break;
        }
        let d2 = (c - x).norm2();
        if d2 < best {
            best = d2;
        }
    }
    crate::math::sqrt(best)
}

/// The distance from `x` to the nearest of `centers`, m (as [`nearest_cell`], without the
/// centre; infinite with none).
#[inline(always)]
fn nearest_distance(centers: &[Vec2], x: Vec2) -> f32 {
    let mut best = f32::INFINITY;
    for &c in centers {
        let d2 = (c - x).norm2();
        if d2 < best {
            best = d2;
        }
    }
    crate::math::sqrt(best)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::Shape;

    /// A field with nothing, for `..no_map()` in the tests.
    fn no_map() -> Field<'static> {
        Field {
            obstacles: &[],
            shifts: &[],
            distances: &[],
            agents: &[],
            agent_radius: 0.5,
            agent_stator: Stator::new(2.5),
            goal: GoalPdf::new(Vec2::ZERO, 1.0, 1.0),
            leader: None,
            rotor_gradient: Vec2::ZERO,
            origin: Vec2::ZERO,
            map: &[],
            map_radius: 0.0,
            map_stator: Stator::new(2.5),
            leave_to_map: false,
        }
    }

    #[test]
    fn force_points_at_the_goal_with_the_potential_drop_as_modulus() {
        let f = Field {
            obstacles: &[],
            shifts: &[],
            distances: &[],
            agents: &[],
            agent_radius: 0.5,
            agent_stator: Stator::new(2.5),
            goal: GoalPdf::new(Vec2::new(10.0, 0.0), 5.0, 8.0),
            leader: None,
            rotor_gradient: Vec2::ZERO,
            origin: Vec2::ZERO,
            ..no_map()
        };
        let c = SampleCircle::new(0.25, 16);
        let force = f.sampled_forces(&c).full;
        assert!(force.y.abs() < 1e-6 && force.x > 0.0);
        let drop = f.potential(Vec2::ZERO) - f.potential(Vec2::new(0.25, 0.0));
        assert!((force.norm() - drop).abs() < 1e-6);
    }

    #[test]
    fn force_points_away_from_an_obstacle_even_from_inside() {
        let s = Shape::circle(Vec2::ZERO, 2.0).unwrap();
        let obs = [Obstacle::new(0, s, 2.5, Origin::Charted, 0).unwrap()];
        for origin in [Vec2::new(3.0, 0.0), Vec2::new(1.0, 0.0)] {
            let f = Field {
                obstacles: &obs,
                shifts: &[Vec2::ZERO],
                distances: &[],
                agents: &[],
                agent_radius: 0.5,
                agent_stator: Stator::new(2.5),
                goal: GoalPdf::new(origin, 0.001, 100.0),
                leader: None,
                rotor_gradient: Vec2::ZERO,
                origin,
                ..no_map()
            };
            let force = f.sampled_forces(&SampleCircle::new(0.25, 16)).full;
            assert!(force.x > 0.0 && force.y.abs() < 1e-3 * force.x, "{force:?}");
        }
    }

    /// F_nf of the three fields with every object sampled (eq. 2–4 as published: E at the
    /// centre and at the n_γ points, through [`Field::potential`]'s terms).
    fn exact_forces(f: &Field<'_>, circle: &SampleCircle) -> (Forces, [f32; 3]) {
        let t0 = f.terms(f.origin);
        let mut best = [(0.0f32, Vec2::ZERO); 3];
        for off in circle.offsets() {
            let t = f.terms(f.origin + *off);
            let fixed = t0.fixed - t.fixed;
            let without_leader = fixed + (t0.vehicles - t.vehicles);
            let full = without_leader + (t0.leader - t.leader);
            for (slot, drop) in best.iter_mut().zip([full, without_leader, fixed]) {
                if drop > slot.0 {
                    *slot = (drop, *off);
                }
            }
        }
        let e = circle.epsilon();
        let force = |(drop, dir): (f32, Vec2)| dir * (drop / e);
        let [a, b, c] = best;
        (
            Forces {
                full: force(a),
                without_leader: force(b),
                static_field: force(c),
            },
            [a.0 / e, b.0 / e, c.0 / e],
        )
    }

    /// The drop towards `dir` of the exact field `which` (0 full, 1 without leader, 2 static),
    /// over ε.
    fn exact_drop(f: &Field<'_>, dir: Vec2, which: usize, e: f32) -> f32 {
        let (t0, t) = (f.terms(f.origin), f.terms(f.origin + dir));
        let fixed = t0.fixed - t.fixed;
        let without_leader = fixed + (t0.vehicles - t.vehicles);
        let full = without_leader + (t0.leader - t.leader);
        [full, without_leader, fixed][which] / e
    }

    #[test]
    fn far_field_stays_within_its_bound() {
        let mut rng = crate::math::XorShift32::new(2024);
        let mut u = move || (rng.next_u32() >> 8) as f32 / (1u32 << 24) as f32;
        let circle = SampleCircle::new(0.25, 16);
        let (mut linearised, mut worst, mut erred) = (0usize, 0.0f32, 0usize);
        for _ in 0..300 {
            let mut obstacles = [Obstacle::new(
                0,
                Shape::circle(Vec2::ZERO, 1.0).unwrap(),
                1.0,
                Origin::Charted,
                0,
            )
            .unwrap(); 32];
            let mut shifts = [Vec2::ZERO; 32];
            for (o, s) in obstacles.iter_mut().zip(shifts.iter_mut()) {
                let c = Vec2::from_angle(TAU * u()) * (1.5 + 40.0 * u());
                let size = Vec2::new(0.2 + 2.0 * u(), 0.2 + 2.0 * u());
                let shape = match (4.0 * u()) as u32 {
                    0 => Shape::circle(c, size.x),
                    1 => Shape::rectangle(c, size, TAU * u()),
                    2 => Shape::ellipse(c, size, TAU * u()),
                    _ => {
                        let hex: [Vec2; 6] = core::array::from_fn(|k| {
                            c + Vec2::from_angle(k as f32 * 1.047 + u()) * size.x
                        });
                        Shape::polygon(&hex)
                    }
                }
                .unwrap();
                *o = Obstacle::new(0, shape, 0.5 + 9.5 * u(), Origin::Charted, 0).unwrap();
                *s = Vec2::new(u() - 0.5, u() - 0.5) * 4.0;
            }
            let agents: [Agent; 8] = core::array::from_fn(|i| {
                let p = Vec2::from_angle(TAU * u()) * (1.0 + 30.0 * u());
                Agent::new(i as u16, p, Vec2::ZERO, 0).unwrap()
            });
            let f = Field {
                obstacles: &obstacles,
                shifts: &shifts,
                distances: &[],
                agents: &agents,
                agent_radius: 0.5,
                agent_stator: Stator::new(2.5),
                goal: GoalPdf::new(Vec2::from_angle(TAU * u()) * 60.0, 50.0, 40.0),
                leader: Some(GoalPdf::new(Vec2::new(u(), u()) * 5.0, 5.0, 3.0)),
                rotor_gradient: Vec2::new(u() - 0.5, u() - 0.5),
                origin: Vec2::ZERO,
                ..no_map()
            };
            // The stated bound: FAR_FORCE_ERROR per linearised object.
            let far = obstacles
                .iter()
                .zip(&shifts)
                .filter(|(o, &s)| {
                    let (r, g) = o.shape.distance_gradient(-s);
                    far_gradient(o.stator(), r, g, 0.25, curvature(&o.shape)).is_some()
                })
                .count()
                + agents
                    .iter()
                    .filter(|a| {
                        let d = -a.position;
                        let r = d.norm() - 0.5;
                        far_gradient(&Stator::new(2.5), r, d * (1.0 / d.norm()), 0.25, 1.0)
                            .is_some()
                    })
                    .count();
            linearised += far;
            // Plus rounding: the sums of E are rounded (differently, the far objects' values
            // left out) to the ulp of E's size, which near an obstacle is large.
            let t0 = f.terms(f.origin);
            let size = t0.fixed.abs() + t0.vehicles.abs() + t0.leader.abs();
            let rounding = 64.0 * f32::EPSILON * size / 0.25;
            let bound = far as f32 * FAR_FORCE_ERROR + rounding;
            let got = f.sampled_forces(&circle);
            let (want, moduli) = exact_forces(&f, &circle);
            let pairs = [
                (got.full, want.full),
                (got.without_leader, want.without_leader),
                (got.static_field, want.static_field),
            ];
            for (which, (g, w)) in pairs.into_iter().enumerate() {
                // |F_nf| is the largest drop over ε: it errs by at most the bound. A changed
                // direction is one whose exact drop is within twice the bound of the largest.
                let err = (g.norm() - w.norm()).abs();
                worst = worst.max(err / bound);
                erred += usize::from(err > 0.0);
                assert!(err <= bound * 1.01 + 1e-6, "|F| errs by {err} > {bound}");
                if g != Vec2::ZERO {
                    let drop = exact_drop(&f, g * (0.25 / g.norm()), which, 0.25);
                    assert!(
                        drop >= moduli[which] - 2.0 * bound - 1e-5,
                        "{drop} vs {moduli:?}"
                    );
                }
            }
        }
        // The approximation was in play, and its error is seen (not zero) but inside the bound.
        assert!(linearised > 300 * 20, "{linearised}");
        assert!(erred > 100, "{erred}");
        assert!(worst <= 1.0, "{worst}");
    }

    #[test]
    fn local_minimum_gives_zero_force() {
        let f = Field {
            obstacles: &[],
            shifts: &[],
            distances: &[],
            agents: &[],
            agent_radius: 0.5,
            agent_stator: Stator::new(2.5),
            goal: GoalPdf::new(Vec2::ZERO, 5.0, 8.0),
            leader: None,
            rotor_gradient: Vec2::ZERO,
            origin: Vec2::new(0.01, 0.0),
            ..no_map()
        };
        assert_eq!(
            f.sampled_forces(&SampleCircle::new(0.25, 16)).full,
            Vec2::ZERO
        );
    }

    #[test]
    fn partial_fields_separate_what_holds_the_vehicle() {
        // Another vehicle sits between this one and the goal.
        let agents = [Agent::new(1, Vec2::new(1.5, 0.0), Vec2::ZERO, 0).unwrap()];
        let f = Field {
            obstacles: &[],
            shifts: &[],
            agents: &agents,
            agent_radius: 0.5,
            agent_stator: Stator::new(2.5),
            goal: GoalPdf::new(Vec2::new(10.0, 0.0), 5.0, 8.0),
            leader: Some(GoalPdf::new(Vec2::new(-3.0, 0.0), 50.0, 1.0)),
            rotor_gradient: Vec2::ZERO,
            origin: Vec2::ZERO,
            ..no_map()
        };
        let forces = f.sampled_forces(&SampleCircle::new(0.25, 16));
        assert!(forces.full.x < 0.0, "the leader pulls back: {forces:?}");
        assert!(forces.without_leader.x < 0.0, "the vehicle ahead repels");
        assert!(forces.static_field.x > 0.0, "alone, the goal pulls");
    }
}
