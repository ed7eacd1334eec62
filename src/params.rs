//! The planner's parameters: one validated struct with the papers' names, units and ranges.
//!
//! Seed 002 §1 calls them *method-independent* parameters: they do not follow from the vehicle's
//! physics and must be tuned (A_s⁺, A_r⁺, ε, n_γ, μ, F_max, v_max, σ, A⁻). Invalid values are
//! rejected with a [`ParamError`] naming the parameter; nothing is clamped silently.
//!
//! Units: metres, seconds, radians. "Force" F is the potential difference across ε (seed 000
//! eq. 2), integrated into velocity with period T (eq. 5), so it has units of m/s².

/// Most gradient sample directions n_γ the planner precomputes (its sample table capacity).
pub const N_GAMMA_MAX: usize = 32;

/// How the force and commanded velocity are bounded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub enum Bounding {
    /// Bound the modulus, keep the direction (seed 001 eq. 5 and 7).
    Plain,
    /// Bound the components along and across the direction of travel in the order that keeps a
    /// heading-rate reserve (seed 001 §3.1).
    Split,
}

/// Which guidance strategy turns the world into set-points. All three produce the same
/// [`Command`](crate::planner::Command), bounded by F_max and v_max, from the same obstacle
/// table, under the same fail-safes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "lowercase"))]
pub enum Strategy {
    /// The virtual potential field of seeds 000/001 (sampled PDF gradient, friction, ghosts,
    /// rotors, formation).
    Vpf,
    /// The multipoint potential field of seed 003 (minimum-potential point on an arc ahead).
    Multipoint,
    /// Rimon–Koditschek navigation functions on a sphere world (seed 004).
    Navfn,
}

impl Strategy {
    /// The name used in scenario files and parameter files.
    pub const fn name(self) -> &'static str {
        match self {
            Strategy::Vpf => "vpf",
            Strategy::Multipoint => "multipoint",
            Strategy::Navfn => "navfn",
        }
    }

    /// The strategy called `name`, if any.
    pub fn from_name(name: &str) -> Option<Strategy> {
        [Strategy::Vpf, Strategy::Multipoint, Strategy::Navfn]
            .into_iter()
            .find(|s| s.name() == name)
    }
}

/// The planner's parameters. Build from [`Params::default`] and change fields, then pass to
/// [`Planner::new`](crate::planner::Planner::new) or
/// [`Planner::set_params`](crate::planner::Planner::set_params), which validate.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Params {
    /// T, the planner period in seconds (seed 000 eq. 5). 0.02 ..= 1.0 (50 Hz .. 1 Hz).
    pub period_s: f32,
    /// ε, radius of the gradient sample circle in metres (000 eq. 3, "spatial resolution").
    /// 0.01 ..= 10.
    pub epsilon_m: f32,
    /// n_γ, number of gradient sample directions (000 eq. 4, "angular resolution").
    /// 4 ..= [`N_GAMMA_MAX`].
    pub n_gamma: u8,
    /// μ, virtual viscous friction in 1/s (000 eq. 14, 001 eq. 4). 0 ..= 10.
    pub mu: f32,
    /// F_max, bound on the controlling force in m/s² (001 eq. 5). 0.001 ..= 100.
    pub f_max: f32,
    /// v_max, bound on the commanded speed in m/s (000 eq. 5, 001 eq. 7). 0.01 ..= 20.
    pub v_max: f32,
    /// A_s⁺, default static repulsiveness of an obstacle (000 eq. 9, 12; 002 eq. 1), m².
    /// Obstacles may carry their own. 0.001 ..= 100.
    pub a_plus: f32,
    /// A_r⁺, rotor amplification (001 eq. 3, 002 eq. 3), potential per metre. 0 ..= 100
    /// (0 turns rotors off).
    pub a_rotor: f32,
    /// A⁻, attractiveness of the goal-point (000 eq. 13). 0.001 ..= 10⁴.
    pub a_minus: f32,
    /// σ, attractor reach of the goal-point in metres (000 eq. 13). 0.1 ..= 10⁴.
    pub sigma_m: f32,
    /// Plain or split bounding (001 §3.1).
    pub bounding: Bounding,
    /// r₀ of the circle another vehicle is seen as, metres (000 §III: 0.5). 0.01 ..= 100.
    pub agent_radius_m: f32,
    /// A⁺ of the circle another vehicle is seen as (000 §III: 2.5). 0.001 ..= 100.
    pub agent_a_plus: f32,
    /// Distance to the goal-point under which the mission counts as reached, metres. Also the
    /// distance inside which no local minimum is suspected. 0.01 ..= 100.
    pub arrival_radius_m: f32,
    /// λ of a ghost goal-point: fraction of the distance d to the goal along the line to it
    /// (000 eq. 17). 0 ..= 1.
    pub ghost_lambda: f32,
    /// α of a ghost goal-point: multiple of d offset across the line to the goal (000 eq. 17).
    /// 0.01 ..= 2.
    pub ghost_alpha: f32,
    /// ε_ghost: a ghost goal-point is removed once the vehicle is this close, metres (000 §III).
    /// 0.01 ..= 100.
    pub ghost_eps_m: f32,
    /// Local-minimum test: planned speed below this, in m/s, ... 0 ..= v_max.
    pub stall_speed: f32,
    /// ... for this long, in seconds, while farther than `arrival_radius_m` from the active
    /// goal-point. 0.1 ..= 600.
    pub stall_time_s: f32,
    /// A ghost goal-point is given up after this many seconds ("for a given period of time",
    /// 000 §III). 1 ..= 3600.
    pub ghost_timeout_s: f32,
    /// Depth of the ghost goal-point stack in use, 0 ..= [`MAX_GHOSTS`] (0 turns ghost
    /// goal-points off: the plain method of 000 Fig. 4).
    ///
    /// [`MAX_GHOSTS`]: crate::planner::MAX_GHOSTS
    pub max_ghosts: u8,
    /// Seed of the deterministic generator for the ghost's random side ρ (000 eq. 17).
    pub seed: u32,
    /// The guidance strategy.
    pub strategy: Strategy,
    /// Prediction horizon for moving obstacles, s: every strategy sees a moving obstacle where
    /// it will be at the closest approach within this horizon (`crate::world::Obstacle::
    /// predicted_shift`). 0 ..= 120 (0: obstacles are taken where they are).
    pub horizon_s: f32,
    /// Multipoint (003): r, radius of the arc of candidate points ahead of the bow, m.
    /// 0.1 ..= 100.
    pub mp_arc_m: f32,
    /// Multipoint (003): N, points on the arc. 3 ..= 32.
    pub mp_points: u8,
    /// Multipoint (003): ψ_m, the arc spans heading ± ψ_m (the largest turn), rad. 0.05 ..= π.
    pub mp_turn_rad: f32,
    /// Multipoint (003 eq. 4): ξ, attraction gain. 0.001 ..= 10⁴.
    pub mp_xi: f32,
    /// Multipoint (003 eq. 5): η, repulsion gain. 0 ..= 10⁶.
    pub mp_eta: f32,
    /// Multipoint (003 eq. 5): d_t, influence distance of an obstacle point, m. 0.1 ..= 1000.
    pub mp_influence_m: f32,
    /// Multipoint (003): K, points on the facing half of each obstacle's periphery. 2 ..= 16.
    pub mp_periphery: u8,
    /// Navigation function (004): κ. 0 picks κ = M + 2 for M obstacles (the notes' rule of
    /// thumb κ > M + 1); otherwise 1 ..= 64.
    pub nf_kappa: f32,
    /// Navigation function (004): ρ₀, radius of the spherical workspace (obstacle 0), centred
    /// on the goal, m. 1 ..= 10⁵.
    pub nf_workspace_m: f32,
    /// Cell of the background route layer's grid, m (`crate::route`): 0 turns the layer off
    /// (the planner as published, e.g. to reproduce the papers' runs), else 0.5 ..= 8, a whole
    /// multiple of the evidence map's 0.5 m cell (otherwise only contacts and charts are
    /// routed round). The grid is 64 cells wide.
    pub route_cell_m: f32,
    /// The craft's largest yaw rate, rad/s: the guard (`crate::guidance::guard`) judges a
    /// command by the arc the vehicle sweeps turning towards it at this rate, and the speed
    /// set-point is cut while the heading is far from the commanded one (a craft that turns
    /// slowly goes where it points, not where it is told). 0 (the default) takes the craft to
    /// turn at once, as a VideoRay nearly does (≈ 1.5 rad/s); else 0.001 ..= 10.
    pub turn_rate_rps: f32,
    /// The deceleration the craft really brakes at, m/s²: the guard's stopping distances use it.
    /// 0 (the default) takes F_max, the most the planner itself commands; else 0.001 ..= 100.
    pub brake_mps2: f32,
}

impl Default for Params {
    /// A VideoRay-class default: 10 Hz, 1 m/s, the papers' μ = 0.4 and agent circle
    /// {r₀ = 0.5, A⁺ = 2.5}. The other values are a starting point for the tuning of seed 002.
    /// The multipoint settings are [`ArcConfig::default`]'s, reasoned there.
    ///
    /// [`ArcConfig::default`]: crate::planner::multipoint::ArcConfig
    fn default() -> Self {
        let arc = crate::planner::multipoint::ArcConfig::default();
        Params {
            period_s: 0.1,
            epsilon_m: 0.25,
            n_gamma: 16,
            mu: 0.4,
            f_max: 0.5,
            v_max: 1.0,
            a_plus: 2.5,
            a_rotor: 5.0,
            a_minus: 50.0,
            sigma_m: 40.0,
            bounding: Bounding::Split,
            agent_radius_m: 0.5,
            agent_a_plus: 2.5,
            arrival_radius_m: 1.0,
            ghost_lambda: 0.5,
            ghost_alpha: 0.5,
            ghost_eps_m: 1.0,
            stall_speed: 0.05,
            stall_time_s: 5.0,
            ghost_timeout_s: 60.0,
            max_ghosts: 4,
            seed: 1,
            strategy: Strategy::Vpf,
            horizon_s: 10.0,
            mp_arc_m: arc.arc_m,
            mp_points: arc.points,
            mp_turn_rad: arc.max_turn_rad,
            mp_xi: arc.xi,
            mp_eta: arc.eta,
            mp_influence_m: arc.influence_m,
            mp_periphery: arc.periphery,
            nf_kappa: 0.0,
            nf_workspace_m: 1000.0,
            route_cell_m: 2.0,
            turn_rate_rps: 0.0,
            brake_mps2: 0.0,
        }
    }
}

/// What is wrong with a parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ParamProblem {
    /// NaN or infinite.
    NonFinite,
    /// Outside its documented range.
    OutOfRange,
}

/// A rejected parameter set: which parameter (its field name) and why.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParamError {
    /// The field name in [`Params`].
    pub name: &'static str,
    /// What is wrong with it.
    pub problem: ParamProblem,
}

impl core::fmt::Display for ParamError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let why = match self.problem {
            ParamProblem::NonFinite => "is not a finite number",
            ParamProblem::OutOfRange => "is out of its documented range",
        };
        write!(f, "parameter `{}` {}", self.name, why)
    }
}

fn check(name: &'static str, v: f32, lo: f32, hi: f32) -> Result<(), ParamError> {
    let problem = if !v.is_finite() {
        ParamProblem::NonFinite
    } else if v < lo || v > hi {
        ParamProblem::OutOfRange
    } else {
        return Ok(());
    };
    Err(ParamError { name, problem })
}

impl Params {
    /// The deceleration the guard plans stops with, m/s²: `brake_mps2`, or F_max when it is 0.
    pub fn brake(&self) -> f32 {
        if self.brake_mps2 > 0.0 {
            self.brake_mps2
        } else {
            self.f_max
        }
    }

    /// Checks every parameter against its documented range.
    pub fn validate(&self) -> Result<(), ParamError> {
        check("period_s", self.period_s, 0.02, 1.0)?;
        check("epsilon_m", self.epsilon_m, 0.01, 10.0)?;
        check("n_gamma", self.n_gamma as f32, 4.0, N_GAMMA_MAX as f32)?;
        check("mu", self.mu, 0.0, 10.0)?;
        check("f_max", self.f_max, 0.001, 100.0)?;
        check("v_max", self.v_max, 0.01, 20.0)?;
        check("a_plus", self.a_plus, 0.001, 100.0)?;
        check("a_rotor", self.a_rotor, 0.0, 100.0)?;
        check("a_minus", self.a_minus, 0.001, 1e4)?;
        check("sigma_m", self.sigma_m, 0.1, 1e4)?;
        check("agent_radius_m", self.agent_radius_m, 0.01, 100.0)?;
        check("agent_a_plus", self.agent_a_plus, 0.001, 100.0)?;
        check("arrival_radius_m", self.arrival_radius_m, 0.01, 100.0)?;
        check("ghost_lambda", self.ghost_lambda, 0.0, 1.0)?;
        check("ghost_alpha", self.ghost_alpha, 0.01, 2.0)?;
        check("ghost_eps_m", self.ghost_eps_m, 0.01, 100.0)?;
        check("stall_speed", self.stall_speed, 0.0, self.v_max)?;
        check("stall_time_s", self.stall_time_s, 0.1, 600.0)?;
        check("ghost_timeout_s", self.ghost_timeout_s, 1.0, 3600.0)?;
        let ghosts = crate::planner::MAX_GHOSTS as f32;
        check("max_ghosts", self.max_ghosts as f32, 0.0, ghosts)?;
        check("horizon_s", self.horizon_s, 0.0, 120.0)?;
        check("mp_arc_m", self.mp_arc_m, 0.1, 100.0)?;
        let arc = crate::planner::multipoint::MAX_ARC_POINTS as f32;
        check("mp_points", self.mp_points as f32, 3.0, arc)?;
        check("mp_turn_rad", self.mp_turn_rad, 0.05, core::f32::consts::PI)?;
        check("mp_xi", self.mp_xi, 0.001, 1e4)?;
        check("mp_eta", self.mp_eta, 0.0, 1e6)?;
        check("mp_influence_m", self.mp_influence_m, 0.1, 1000.0)?;
        let k = crate::planner::multipoint::MAX_PERIPHERY_POINTS as f32;
        check("mp_periphery", self.mp_periphery as f32, 2.0, k)?;
        if self.nf_kappa != 0.0 {
            check("nf_kappa", self.nf_kappa, 1.0, 64.0)?;
        }
        check("nf_workspace_m", self.nf_workspace_m, 1.0, 1e5)?;
        if self.route_cell_m != 0.0 {
            check("route_cell_m", self.route_cell_m, 0.5, 8.0)?;
        }
        if self.turn_rate_rps != 0.0 {
            check("turn_rate_rps", self.turn_rate_rps, 0.001, 10.0)?;
        }
        if self.brake_mps2 != 0.0 {
            check("brake_mps2", self.brake_mps2, 0.001, 100.0)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid() {
        assert_eq!(Params::default().validate(), Ok(()));
    }

    #[test]
    fn each_bad_value_is_named() {
        let bad = |p: Params| p.validate();
        let d = Params::default();
        assert_eq!(
            bad(Params { mu: f32::NAN, ..d }),
            Err(ParamError {
                name: "mu",
                problem: ParamProblem::NonFinite
            })
        );
        assert_eq!(
            bad(Params { n_gamma: 64, ..d }).map_err(|e| e.name),
            Err("n_gamma")
        );
        assert_eq!(
            bad(Params { period_s: 2.0, ..d }).map_err(|e| e.problem),
            Err(ParamProblem::OutOfRange)
        );
        let fast_stall = Params {
            stall_speed: d.v_max * 2.0,
            ..d
        };
        assert_eq!(bad(fast_stall).map_err(|e| e.name), Err("stall_speed"));
        assert_eq!(
            bad(Params { max_ghosts: 5, ..d }).map_err(|e| e.name),
            Err("max_ghosts")
        );
    }
}
