//! The planner's parameters: one validated struct with the papers' names, units and ranges.
//!
//! Seed 002 §1 calls them *method-independent* parameters: they do not follow from the vehicle's
//! physics and must be tuned (A_s⁺, A_r⁺, ε, n_γ, μ, F_max, v_max, σ, A⁻). Invalid values are
//! rejected with a [`ParamError`] naming the parameter; nothing is clamped silently.
//!
//! **Each parameter is declared once**, below: its doc, name, type, default, unit and range,
//! in wire order. From that line come the struct field, [`Params::default`],
//! [`Params::validate`], [`ParamId`] (name, unit, kind, range, doc, wire index), the `Params`
//! message's layout (`crate::link::control::params`), the scenario schema's `[planner]` keys
//! and ranges and the sweep's names (`hil`), and the checks that keep docs/protocol.md's
//! Params table and hil/scenarios/README.md's `[planner]` table true. Adding a parameter is one
//! declaration here and its use; a new wire layout also bumps the protocol version.
//!
//! Units: metres, seconds, radians. "Force" F is the potential difference across ε (seed 000
//! eq. 2), integrated into velocity with period T (eq. 5), so it has units of m/s².

#[macro_use]
mod table;

pub use table::{choice_of, Choice, Kind, ParamType, Range, Value};

use crate::math::PI;

/// Most gradient sample directions n_γ the planner precomputes (its sample table capacity).
pub const N_GAMMA_MAX: usize = 32;
/// Capacity of the ghost goal-point stack (`max_ghosts` at most this).
pub const MAX_GHOSTS: usize = 4;
/// Most multipoint arc points N (the capacity of the multipoint's stack arrays; `mp_points` at
/// most this).
pub const MAX_ARC_POINTS: usize = 32;
/// Most multipoint periphery points K per obstacle (`mp_periphery` at most this).
pub const MAX_PERIPHERY_POINTS: usize = 16;

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

declare_params! {
    /// The planner's parameters. Build from [`Params::default`] and change fields, then pass to
    /// [`Planner::new`](crate::planner::Planner::new) or
    /// [`Planner::set_params`](crate::planner::Planner::set_params), which validate. Each
    /// field's range is its [`ParamId::range`] (in the declaration in `src/params/mod.rs`).
    pub struct Params {
        /// T, the planner period in seconds (seed 000 eq. 5): 50 Hz .. 1 Hz.
        period_s: f32 = 0.1, "s", Range::Within(0.02, 1.0);
        /// ε, radius of the gradient sample circle in metres (000 eq. 3, "spatial resolution").
        epsilon_m: f32 = 0.25, "m", Range::Within(0.01, 10.0);
        /// n_γ, number of gradient sample directions (000 eq. 4, "angular resolution"), at most
        /// [`N_GAMMA_MAX`].
        n_gamma: u8 = 16, "", Range::Within(4.0, N_GAMMA_MAX as f32);
        /// μ, virtual viscous friction in 1/s (000 eq. 14, 001 eq. 4).
        mu: f32 = 0.4, "1/s", Range::Within(0.0, 10.0);
        /// F_max, bound on the controlling force in m/s² (001 eq. 5).
        f_max: f32 = 0.5, "m/s²", Range::Within(0.001, 100.0);
        /// v_max, bound on the commanded speed in m/s (000 eq. 5, 001 eq. 7).
        v_max: f32 = 1.0, "m/s", Range::Within(0.01, 20.0);
        /// A_s⁺, default static repulsiveness of an obstacle (000 eq. 9, 12; 002 eq. 1), m².
        /// Obstacles may carry their own.
        a_plus: f32 = 2.5, "m²", Range::Within(0.001, 100.0);
        /// A_r⁺, rotor amplification (001 eq. 3, 002 eq. 3), potential per metre (0 turns
        /// rotors off).
        a_rotor: f32 = 5.0, "", Range::Within(0.0, 100.0);
        /// A⁻, attractiveness of the goal-point (000 eq. 13).
        a_minus: f32 = 50.0, "", Range::Within(0.001, 1e4);
        /// σ, attractor reach of the goal-point in metres (000 eq. 13).
        sigma_m: f32 = 40.0, "m", Range::Within(0.1, 1e4);
        /// Plain or split bounding (001 §3.1).
        bounding: Bounding = Bounding::Split, "", Range::Any;
        /// r₀ of the circle another vehicle is seen as, metres (000 §III: 0.5).
        agent_radius_m: f32 = 0.5, "m", Range::Within(0.01, 100.0);
        /// A⁺ of the circle another vehicle is seen as (000 §III: 2.5).
        agent_a_plus: f32 = 2.5, "", Range::Within(0.001, 100.0);
        /// Distance to the goal-point under which the mission counts as reached, metres. Also the
        /// distance inside which no local minimum is suspected.
        arrival_radius_m: f32 = 1.0, "m", Range::Within(0.01, 100.0);
        /// λ of a ghost goal-point: fraction of the distance d to the goal along the line to it
        /// (000 eq. 17).
        ghost_lambda: f32 = 0.5, "", Range::Within(0.0, 1.0);
        /// α of a ghost goal-point: multiple of d offset across the line to the goal (000 eq. 17).
        ghost_alpha: f32 = 0.5, "", Range::Within(0.01, 2.0);
        /// ε_ghost: a ghost goal-point is removed once the vehicle is this close, metres (000 §III).
        ghost_eps_m: f32 = 1.0, "m", Range::Within(0.01, 100.0);
        /// Local-minimum test: planned speed below this, in m/s, ...
        stall_speed: f32 = 0.05, "m/s", Range::UpTo(0.0, ParamId::v_max);
        /// ... for this long, in seconds, while farther than `arrival_radius_m` from the active
        /// goal-point.
        stall_time_s: f32 = 5.0, "s", Range::Within(0.1, 600.0);
        /// A ghost goal-point is given up after this many seconds ("for a given period of time",
        /// 000 §III).
        ghost_timeout_s: f32 = 60.0, "s", Range::Within(1.0, 3600.0);
        /// Depth of the ghost goal-point stack in use, at most [`MAX_GHOSTS`] (0 turns ghost
        /// goal-points off: the plain method of 000 Fig. 4).
        max_ghosts: u8 = 4, "", Range::Within(0.0, MAX_GHOSTS as f32);
        /// Seed of the deterministic generator for the ghost's random side ρ (000 eq. 17).
        seed: u32 = 1, "", Range::Any;
        /// The guidance strategy.
        strategy: Strategy = Strategy::Vpf, "", Range::Any;
        /// Prediction horizon for moving obstacles, s: every strategy sees a moving obstacle where
        /// it will be at the closest approach within this horizon (`crate::world::Obstacle::
        /// predicted_shift`; 0: obstacles are taken where they are).
        horizon_s: f32 = 10.0, "s", Range::Within(0.0, 120.0);
        /// Multipoint (003): r, radius of the arc of candidate points ahead of the bow, m. The
        /// multipoint defaults are reasoned at `planner::multipoint::ArcConfig::default`.
        mp_arc_m: f32 = 1.0, "m", Range::Within(0.1, 100.0);
        /// Multipoint (003): N, points on the arc, at most [`MAX_ARC_POINTS`].
        mp_points: u8 = 25, "", Range::Within(3.0, MAX_ARC_POINTS as f32);
        /// Multipoint (003): ψ_m, the arc spans heading ± ψ_m (the largest turn), rad.
        mp_turn_rad: f32 = 0.2 * PI, "rad", Range::Within(0.05, PI);
        /// Multipoint (003 eq. 4): ξ, attraction gain.
        mp_xi: f32 = 1.0, "", Range::Within(0.001, 1e4);
        /// Multipoint (003 eq. 5): η, repulsion gain.
        mp_eta: f32 = 10.0, "", Range::Within(0.0, 1e6);
        /// Multipoint (003 eq. 5): d_t, influence distance of an obstacle point, m.
        mp_influence_m: f32 = 8.0, "m", Range::Within(0.1, 1000.0);
        /// Multipoint (003): K, points on the facing half of each obstacle's periphery, at most
        /// [`MAX_PERIPHERY_POINTS`].
        mp_periphery: u8 = 9, "", Range::Within(2.0, MAX_PERIPHERY_POINTS as f32);
        /// Navigation function (004): κ. 0 picks κ = M + 2 for M obstacles (the notes' rule of
        /// thumb κ > M + 1).
        nf_kappa: f32 = 0.0, "", Range::ZeroOr(1.0, 64.0, "auto");
        /// Navigation function (004): ρ₀, radius of the spherical workspace (obstacle 0), centred
        /// on the goal, m.
        nf_workspace_m: f32 = 1000.0, "m", Range::Within(1.0, 1e5);
        /// Cell of the background route layer's grid, m (`crate::route`): 0 turns the layer off
        /// (the planner as published, e.g. to reproduce the papers' runs); else a whole multiple
        /// of the evidence map's 0.5 m cell (otherwise only contacts and charts are routed
        /// round). The grid is 64 cells wide.
        route_cell_m: f32 = 2.0, "m", Range::ZeroOr(0.5, 8.0, "route layer off");
        /// The craft's largest yaw rate, rad/s: the guard (`crate::guidance::guard`) judges a
        /// command by the arc the vehicle sweeps turning towards it at this rate, and the speed
        /// set-point is cut while the heading is far from the commanded one (a craft that turns
        /// slowly goes where it points, not where it is told). 0 takes the craft to turn at once,
        /// as a VideoRay nearly does (≈ 1.5 rad/s).
        turn_rate_rps: f32 = 0.0, "rad/s", Range::ZeroOr(0.001, 10.0, "turns at once");
        /// The deceleration the craft really brakes at, m/s²: the guard's stopping distances use
        /// it. 0 takes F_max, the most the planner itself commands.
        brake_mps2: f32 = 0.0, "m/s²", Range::ZeroOr(0.001, 100.0, "F_max");
    }
}

impl Choice for Bounding {
    const ALL: &'static [Self] = &[Bounding::Plain, Bounding::Split];
    const NAMES: &'static [&'static str] = &["plain", "split"];
    fn code(self) -> u8 {
        self as u8
    }
}

impl Choice for Strategy {
    const ALL: &'static [Self] = &[Strategy::Vpf, Strategy::Multipoint, Strategy::Navfn];
    const NAMES: &'static [&'static str] = &["vpf", "multipoint", "navfn"];
    fn code(self) -> u8 {
        self as u8
    }
}

/// `ParamType` for a [`Choice`]: its code on the wire.
macro_rules! choice_param {
    ($($t:ty),*) => {$(
        impl ParamType for $t {
            const KIND: Kind = Kind::Code(<$t as Choice>::NAMES);
            fn to_value(self) -> Value {
                Value::Code(self.code())
            }
            fn from_value(v: Value) -> Option<Self> {
                match v {
                    Value::Code(c) => choice_of(c),
                    _ => None,
                }
            }
        }
    )*};
}
choice_param!(Bounding, Strategy);

impl ParamId {
    /// The parameter with wire index `index`.
    pub fn from_index(index: usize) -> Option<ParamId> {
        ParamId::ALL.get(index).copied()
    }

    /// The parameter called `name`.
    pub fn from_name(name: &str) -> Option<ParamId> {
        ParamId::ALL.into_iter().find(|p| p.name() == name)
    }

    /// Its wire index (the row of docs/protocol.md's Params table).
    pub const fn index(self) -> u8 {
        self as u8
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

impl core::fmt::Display for ParamProblem {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ParamProblem::NonFinite => "is not a finite number",
            ParamProblem::OutOfRange => "is out of its documented range",
        })
    }
}

impl core::error::Error for ParamProblem {}

impl core::fmt::Display for ParamError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "parameter `{}` {}", self.name, self.problem)
    }
}

impl core::error::Error for ParamError {}

impl Params {
    /// Whether the craft turns at a bounded rate (`turn_rate_rps` > 0, a flat-fish) rather than
    /// at once, as seeds 000 and 001's vehicles do.
    pub fn turns_slowly(&self) -> bool {
        self.turn_rate_rps > 0.0
    }

    /// The deceleration the guard plans stops with, m/s²: `brake_mps2`, or F_max when it is 0.
    pub fn brake(&self) -> f32 {
        if self.brake_mps2 > 0.0 {
            self.brake_mps2
        } else {
            self.f_max
        }
    }

    /// Checks every parameter against its declared range, in wire order; the first refused
    /// is named.
    pub fn validate(&self) -> Result<(), ParamError> {
        ParamId::ALL.iter().try_for_each(|&id| self.check(id))
    }

    fn check(&self, id: ParamId) -> Result<(), ParamError> {
        let v = self.get(id).as_f32();
        let (lo, hi) = match id.range() {
            Range::Any => return Ok(()),
            Range::Within(lo, hi) => (lo, hi),
            Range::ZeroOr(_, _, _) if v == 0.0 => return Ok(()),
            Range::ZeroOr(lo, hi, _) => (lo, hi),
            Range::UpTo(lo, other) => (lo, self.get(other).as_f32()),
        };
        table::check(id.name(), v, lo, hi)
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
