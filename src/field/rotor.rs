//! Rotor potentials, seed 001 eq. 2–3 (and 002 eq. 2–3): each obstacle adds to its stator PDF a
//! rotor PDF f_r[A_r⁺, p_obs](x, p_AUV) that is identically zero at the vehicle's own position
//! and adds "a vector perpendicular to the line along the shortest distance between the
//! obstacle and the AUV, whose magnitude varies with that distance".
//!
//! The exact form is in a paper we do not have (Barisic, Vukic, Omerdic 2008). Our definition
//! meets every property the seeds state:
//!
//! f_r⁽ⁱ⁾(x; p) = −A_r⁺ · h_i(r_i(p)) · ⟨x − p, t̂_i(p)⟩
//!
//! - n̂_i(p) is the obstacle's outward normal at the vehicle (along the shortest distance), and
//!   t̂_i = s · perp(n̂_i) its tangent, s = +1 counter-clockwise about the obstacle, −1 clockwise;
//! - h_i(r) = 1 − e^{−A_s⁺/r²} ∈ (0, 1] ([`Stator::reach`](super::Stator::reach)): 1 at the
//!   surface, ≈ A_s⁺/r² far away, so the rotor reaches as far as the obstacle's stator does;
//! - f_r is linear in x, so it is exactly zero at x = p (the seeds' f_r(p_AUV) ≡ 0), and the
//!   sampled gradient (000 eq. 2) sees a uniform push of A_r⁺·h·ε along t̂: the planner sums the
//!   obstacles' rotor gradients once per step and adds one dot product per sample.
//!
//! **Rotation sense.** Rotors break obstacle-attached local minima only if they circulate the
//! same way around neighbouring obstacles: in a U-shaped trap a common sense carries the vehicle
//! along the bottom, then back out along a side wall, while a per-obstacle "towards the goal"
//! choice would push it into the corner. So one sense holds for all obstacles. It is chosen
//! towards the goal when an encounter begins (the first obstacle whose rotor weight is
//! significant is passed on the goal's side, ties counter-clockwise) and kept until no obstacle
//! is in reach any more ([`RotorSense::update`]).

use crate::math::Vec2;

/// Rotor weight below which an obstacle is out of reach (encounter over, sense released).
pub const ROTOR_REACH_MIN: f32 = 0.05;

/// The common rotation sense of all rotor potentials during one obstacle encounter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RotorSense {
    /// No obstacle in reach: no sense chosen yet.
    #[default]
    Free,
    /// Counter-clockwise about every obstacle.
    Ccw,
    /// Clockwise about every obstacle.
    Cw,
}

impl RotorSense {
    /// The sign s of t̂ = s · perp(n̂): +1, −1, or 0 when free.
    pub fn sign(self) -> f32 {
        match self {
            RotorSense::Free => 0.0,
            RotorSense::Ccw => 1.0,
            RotorSense::Cw => -1.0,
        }
    }

    /// Keeps the sense during an encounter; chooses it towards the goal when one begins.
    ///
    /// `strongest` is the outward normal n̂ and weight h of the obstacle with the largest rotor
    /// weight this step, if any; `to_goal` points from the vehicle to its active goal-point.
    pub fn update(self, strongest: Option<(Vec2, f32)>, to_goal: Vec2) -> RotorSense {
        match strongest {
            Some((n, h)) if h >= ROTOR_REACH_MIN => match self {
                RotorSense::Free => {
                    // Pass on the goal's side. A counter-clockwise circulation (t̂ = perp n̂)
                    // carries the vehicle towards the side where n̂ × to_goal > 0.
                    if n.cross(to_goal) < 0.0 {
                        RotorSense::Cw
                    } else {
                        RotorSense::Ccw
                    }
                }
                kept => kept,
            },
            _ => RotorSense::Free,
        }
    }
}

/// One obstacle's rotor contribution for this step: the constant gradient −A_r⁺·h·t̂ of its
/// linear rotor PDF, so that E_r(x) = ⟨x − p, gradient⟩.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotorTerm {
    /// ∇f_r (potential per metre), constant over the sample circle.
    pub gradient: Vec2,
}

impl RotorTerm {
    /// The term for an obstacle with outward normal `n` and rotor weight `h` at the vehicle.
    pub fn new(a_rotor: f32, n: Vec2, h: f32, sense: RotorSense) -> Self {
        let tangent = n.perp() * sense.sign();
        RotorTerm {
            gradient: tangent * (-a_rotor * h),
        }
    }

    /// f_r(x) for the vehicle at `p`: zero at x = p by construction.
    pub fn potential(&self, x: Vec2, p: Vec2) -> f32 {
        (x - p).dot(self.gradient)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_at_vehicle_and_decreasing_along_the_tangent() {
        let n = Vec2::new(0.0, -1.0); // vehicle below the obstacle
        let t = RotorTerm::new(2.0, n, 0.5, RotorSense::Ccw);
        let p = Vec2::new(3.0, 4.0);
        assert_eq!(t.potential(p, p), 0.0);
        // Counter-clockwise below an obstacle is +x: the potential drops that way.
        assert!(t.potential(p + Vec2::new(0.1, 0.0), p) < 0.0);
        assert!(t.potential(p + Vec2::new(-0.1, 0.0), p) > 0.0);
    }

    #[test]
    fn sense_is_chosen_towards_the_goal_and_kept_until_out_of_reach() {
        let n = Vec2::new(0.0, -1.0); // obstacle straight ahead (+y)
        let up_left = Vec2::new(-1.0, 5.0);
        let up_right = Vec2::new(1.0, 5.0);
        // Goal a little left: pass on the left, i.e. move −x below the obstacle: clockwise.
        let s = RotorSense::Free.update(Some((n, 0.5)), up_left);
        assert_eq!(s, RotorSense::Cw);
        assert_eq!(
            RotorSense::Free.update(Some((n, 0.5)), up_right),
            RotorSense::Ccw
        );
        // Kept while in reach, whatever the goal does; released when out of reach.
        assert_eq!(s.update(Some((n, 0.5)), up_right), RotorSense::Cw);
        assert_eq!(s.update(Some((n, 0.01)), up_right), RotorSense::Free);
        assert_eq!(s.update(None, up_right), RotorSense::Free);
    }
}
