//! Formation guidance by a virtual leader, seed 001 §3.2, Table 1.
//!
//! Every sensed agent i proposes the node of its lattice nearest to this vehicle:
//! vlᵢ = x_agᵢ + λ·(cos θₖ, sin θₖ), θₖ = θ₀ + 2πk/q with k the bearing quantised by 2π/q
//! (Table 1 L1.1–L1.3; the paper's "quantise by π/3" is the q = 6 case). The virtual leader is
//! the mean of the proposals (step 2), and a goal-point PDF with σ = λ/3 (001 eq. 12) is placed on
//! it (step 3). One attractor per vehicle replaces the q wells per agent of 001 eq. 11, whose
//! mutual dragging made formations chaotic.
//!
//! **Bearing.** Table 1 writes βᵢ = atan2(x_agᵢ − p), the bearing *from this vehicle to the
//! agent*; taking the node in that direction would put the virtual leader on the far side of the
//! agent, behind it, and the vehicle would have to pass through the agent to reach it. We quantise
//! the bearing *from the agent to this vehicle*, so each agent offers the node on this vehicle's
//! side, which is what Fig. 2 of 001 draws.

use crate::math::{wrap_angle, Vec2, TAU};
use crate::world::Agent;

/// A formation slot request: the lattice this vehicle keeps with the others.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Formation {
    /// q, the formation descriptor: 3 (triangles), 4 (squares) or 6 (hexagons) (001 §3.2).
    pub q: u8,
    /// λ, the lattice length: the ideal distance between neighbours, m. 0.5 ..= 1000.
    pub lattice_m: f32,
    /// θ₀, orientation of the lattice's first node direction from +x, rad.
    pub orientation: f32,
    /// A⁻ of the virtual leader's goal-point PDF. 0.001 ..= 10⁴.
    pub attraction: f32,
}

/// Why a formation request was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FormationError {
    /// q is not 3, 4 or 6.
    Descriptor,
    /// A number is NaN or infinite.
    NonFinite,
    /// λ or the attraction is out of range.
    OutOfRange,
}

impl core::fmt::Display for FormationError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            FormationError::Descriptor => "formation descriptor q must be 3, 4 or 6",
            FormationError::NonFinite => "formation has a non-finite number",
            FormationError::OutOfRange => "formation lattice or attraction out of range",
        })
    }
}

impl Formation {
    /// Checks q, λ, θ₀ and A⁻.
    pub fn validate(&self) -> Result<(), FormationError> {
        if !matches!(self.q, 3 | 4 | 6) {
            return Err(FormationError::Descriptor);
        }
        let nums = [self.lattice_m, self.orientation, self.attraction];
        if nums.iter().any(|v| !v.is_finite()) {
            return Err(FormationError::NonFinite);
        }
        if !(0.5..=1000.0).contains(&self.lattice_m) || !(0.001..=1e4).contains(&self.attraction)
        {
            return Err(FormationError::OutOfRange);
        }
        Ok(())
    }

    /// σ of the virtual leader's PDF: λ/3 (001 eq. 12).
    pub fn sigma(&self) -> f32 {
        self.lattice_m / 3.0
    }

    /// The lattice node of `agent` nearest to the vehicle at `p` (Table 1, L1.1–L1.3).
    pub fn node(&self, agent: Vec2, p: Vec2) -> Vec2 {
        let step = TAU / self.q as f32;
        let beta = wrap_angle((p - agent).angle() - self.orientation);
        let k = libm::roundf(beta / step);
        agent + Vec2::from_angle(self.orientation + k * step) * self.lattice_m
    }

    /// The virtual leader: the mean of the agents' nearest nodes (Table 1, step 2), or `None`
    /// with no agent in sight.
    pub fn virtual_leader(&self, p: Vec2, agents: &[Agent]) -> Option<Vec2> {
        if agents.is_empty() {
            return None;
        }
        let sum = agents
            .iter()
            .fold(Vec2::ZERO, |s, a| s + self.node(a.position, p));
        Some(sum * (1.0 / agents.len() as f32))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Formation {
        Formation {
            q: 4,
            lattice_m: 2.0,
            orientation: 0.0,
            attraction: 10.0,
        }
    }

    #[test]
    fn node_is_on_this_vehicles_side_of_the_agent() {
        let f = square();
        // Vehicle north-north-east of the agent: the north node.
        let n = f.node(Vec2::new(5.0, 5.0), Vec2::new(5.5, 9.0));
        assert!((n - Vec2::new(5.0, 7.0)).norm() < 1e-5, "{n:?}");
        let hex = Formation { q: 6, ..f };
        let n = hex.node(Vec2::ZERO, Vec2::new(1.0, 1.9));
        assert!((n - Vec2::from_angle(TAU / 6.0) * 2.0).norm() < 1e-5);
    }

    #[test]
    fn leader_is_the_mean_of_the_proposals() {
        let f = square();
        let agents = [
            Agent::new(1, Vec2::new(0.0, 0.0), Vec2::ZERO, 0).unwrap(),
            Agent::new(2, Vec2::new(4.0, 0.0), Vec2::ZERO, 0).unwrap(),
        ];
        // From (2, 0.5): agent 1 offers (2, 0), agent 2 offers (2, 0).
        let v = f.virtual_leader(Vec2::new(2.0, 0.5), &agents).unwrap();
        assert!((v - Vec2::new(2.0, 0.0)).norm() < 1e-5);
        assert_eq!(f.virtual_leader(Vec2::ZERO, &[]), None);
    }

    #[test]
    fn bad_requests_are_refused() {
        assert_eq!(
            Formation { q: 5, ..square() }.validate(),
            Err(FormationError::Descriptor)
        );
        assert_eq!(
            Formation {
                lattice_m: f32::NAN,
                ..square()
            }
            .validate(),
            Err(FormationError::NonFinite)
        );
        assert_eq!(square().validate(), Ok(()));
    }
}
