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

use crate::field::{GoalPdf, Stator};
use crate::math::{Vec2, TAU};
use crate::params::N_GAMMA_MAX;
use crate::world::{Agent, Obstacle};

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

/// Attractors one step can hold: the active goal-point (or ghost) and the virtual leader.
pub const MAX_ATTRACTORS: usize = 2;

/// Everything that shapes E during one step, borrowed from the world and the planner.
pub struct Field<'a> {
    /// Obstacles (stator PDFs with their own A⁺).
    pub obstacles: &'a [Obstacle],
    /// Other vehicles, seen as circles of radius `agent_radius` (000 §III).
    pub agents: &'a [Agent],
    /// r₀ of an agent's circle.
    pub agent_radius: f32,
    /// Stator of an agent's circle (A⁺ of 000 §III).
    pub agent_stator: Stator,
    /// Goal-point, ghost and virtual-leader attractors.
    pub attractors: &'a [GoalPdf],
    /// Sum of the obstacles' rotor gradients this step (see [`crate::field::rotor`]).
    pub rotor_gradient: Vec2,
    /// The vehicle's position, where the rotor potential is zero.
    pub origin: Vec2,
}

impl Field<'_> {
    /// E(x) (000 eq. 1; 001 eq. 2).
    pub fn potential(&self, x: Vec2) -> f32 {
        let mut e = (x - self.origin).dot(self.rotor_gradient);
        for o in self.obstacles {
            e += o.stator().potential(o.shape.signed_distance(x));
        }
        for a in self.agents {
            let r = (x - a.position).norm() - self.agent_radius;
            e += self.agent_stator.potential(r);
        }
        for g in self.attractors {
            e += g.potential(x);
        }
        e
    }

    /// F_nf, the no-friction controlling force (000 eq. 2; 001 eq. 4), sampled around
    /// [`Field::origin`].
    pub fn sampled_force(&self, circle: &SampleCircle) -> Vec2 {
        let e0 = self.potential(self.origin);
        let mut best = 0.0f32;
        let mut best_dir = Vec2::ZERO;
        for off in circle.offsets() {
            let drop = e0 - self.potential(self.origin + *off);
            if drop > best {
                best = drop;
                best_dir = *off;
            }
        }
        // best_dir has length ε; F_nf has the drop as modulus.
        best_dir * (best / circle.epsilon())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::Shape;
    use crate::world::Origin;

    #[test]
    fn force_points_at_the_goal_with_the_potential_drop_as_modulus() {
        let goal = [GoalPdf::new(Vec2::new(10.0, 0.0), 5.0, 8.0)];
        let f = Field {
            obstacles: &[],
            agents: &[],
            agent_radius: 0.5,
            agent_stator: Stator::new(2.5),
            attractors: &goal,
            rotor_gradient: Vec2::ZERO,
            origin: Vec2::ZERO,
        };
        let c = SampleCircle::new(0.25, 16);
        let force = f.sampled_force(&c);
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
                agents: &[],
                agent_radius: 0.5,
                agent_stator: Stator::new(2.5),
                attractors: &[],
                rotor_gradient: Vec2::ZERO,
                origin,
            };
            let force = f.sampled_force(&SampleCircle::new(0.25, 16));
            assert!(force.x > 0.0 && force.y.abs() < 1e-3 * force.x, "{force:?}");
        }
    }

    #[test]
    fn local_minimum_gives_zero_force() {
        let goal = [GoalPdf::new(Vec2::ZERO, 5.0, 8.0)];
        let f = Field {
            obstacles: &[],
            agents: &[],
            agent_radius: 0.5,
            agent_stator: Stator::new(2.5),
            attractors: &goal,
            rotor_gradient: Vec2::ZERO,
            origin: Vec2::new(0.01, 0.0),
        };
        assert_eq!(f.sampled_force(&SampleCircle::new(0.25, 16)), Vec2::ZERO);
    }
}
