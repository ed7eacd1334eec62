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

use crate::field::{GoalPdf, Stator};
use crate::math::{Vec2, TAU};
use crate::params::N_GAMMA_MAX;
use crate::world::{nearest_cell, Agent, Obstacle, Origin};

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
    pub fn sampled_forces(&self, circle: &SampleCircle) -> Forces {
        let t0 = self.terms(self.origin);
        let mut best = [(0.0f32, Vec2::ZERO); 3];
        for off in circle.offsets() {
            let t = self.terms(self.origin + *off);
            let fixed = t0.fixed - t.fixed;
            let without_leader = fixed + (t0.vehicles - t.vehicles);
            let full = without_leader + (t0.leader - t.leader);
            for (slot, drop) in best.iter_mut().zip([full, without_leader, fixed]) {
                if drop > slot.0 {
                    *slot = (drop, *off);
                }
            }
        }
        // Each direction has length ε; F_nf has the drop as modulus.
        let force = |(drop, dir): (f32, Vec2)| dir * (drop / circle.epsilon());
        let [full, without_leader, static_field] = best;
        Forces {
            full: force(full),
            without_leader: force(without_leader),
            static_field: force(static_field),
        }
    }
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

    #[test]
    fn local_minimum_gives_zero_force() {
        let f = Field {
            obstacles: &[],
            shifts: &[],
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
