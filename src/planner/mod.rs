//! The VPF trajectory planner (seeds 000 and 001): one [`Planner::step`] per period.
//!
//! Per step, for the vehicle at p with measured velocity v and planned velocity v_c(k−1):
//! 1. E = obstacles' stator + rotor PDFs + other vehicles' circles + the active goal-point (the
//!    mission goal or the top ghost) + the formation's virtual leader ([`gradient::Field`]);
//! 2. F_nf = sampled gradient on the ε circle (000 eq. 2–4);
//! 3. F = F_nf − μ·v_c(k−1), virtual viscous friction (000 eq. 14, 001 eq. 4);
//! 4. F̄ = bound(F, F_max), plain or split (001 eq. 5, §3.1) — [`bound`];
//! 5. v̄_c = bound(T/2·(F̄(k) + F̄(k−1)) + v_c(k−1), v_max), bilinear integration (000 eq. 5,
//!    001 eq. 6–7);
//! 6. ψ_set = arg v̄_c, v_set = |v̄_c| (000 eq. 6–7), and the PI-D set-points ([`setpoints`]);
//! 7. the local-minimum detector places or removes ghost goal-points ([`escape`]).
//!
//! **Which velocity is integrated.** 000 eq. 5 integrates the planned velocity v(k−1); 001 eq. 4
//! and 6 write the measured one. We integrate and brake the *planned* velocity, as 000 does: the
//! planner is then a reference generator whose output does not depend on the autopilot's lag or
//! the navigation noise, and the kinematic experiments of 000 are reproduced exactly. The
//! measured velocity sets the direction of travel for split bounding and the set-points, as 001
//! §3.1 asks.
//!
//! The planner never panics, never allocates, and never returns a non-finite command: bad input
//! is refused with a [`StepError`] and the previous state is kept.

pub mod bound;
pub mod escape;
pub mod formation;
pub mod gradient;
pub mod setpoints;

use heapless::Vec;

use crate::field::{GoalPdf, RotorSense, RotorTerm, Stator};
use crate::math::Vec2;
use crate::params::{ParamError, Params};
use crate::world::World;

pub use escape::{EscapeCounters, GhostGoal, StallCause, MAX_GHOSTS};
pub use formation::{Formation, FormationError};
pub use gradient::SampleCircle;
pub use setpoints::PidSetpoints;

use escape::Escape;
use gradient::Field;
use setpoints::{Measured, SetpointState};

/// Largest coordinate accepted for the vehicle or a goal, m (100 km: beyond any AUV mission in a
/// local frame, and where `f32` still resolves 8 mm).
pub const MAX_COORD_M: f32 = 100_000.0;
/// Largest speed over ground accepted from navigation, m/s.
pub const MAX_NAV_SPEED: f32 = 20.0;
/// Step of the central differences for obstacle normals, m.
const NORMAL_STEP_M: f32 = 0.01;

/// The vehicle's navigation state, as the planner needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NavState {
    /// Position in the local Earth-fixed frame, m.
    pub position: Vec2,
    /// Compass heading from +x, counter-clockwise, rad.
    pub heading: f32,
    /// Velocity over ground in the Earth-fixed frame, m/s.
    pub velocity: Vec2,
}

/// The mission: where to go, and optionally which formation to keep.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Mission {
    /// The goal-point p_GP, m (000 eq. 13).
    pub goal: Vec2,
    /// Formation by virtual leader (001 §3.2), if any.
    pub formation: Option<Formation>,
}

/// Why the planner holds instead of planning.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HoldReason {
    /// No mission has been given.
    NoMission,
    /// Navigation is older than the runtime's timeout.
    StaleNav,
    /// The vehicle is inside an obstacle's surface.
    InsideObstacle,
    /// A collision cannot be avoided at the current speed.
    CollisionImminent,
}

/// What the planner is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Mode {
    /// Zero set-points, for the reason given.
    Hold(HoldReason),
    /// Following the field to the mission goal.
    Transit,
    /// Following the field to a ghost goal-point (000 §III).
    Escape,
    /// Within the arrival radius of the goal (the field keeps station).
    Arrived,
}

/// One period's output: set-points for the autopilots, and what produced them.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Command {
    /// ψ_set, heading set-point, rad in (−π, π] (000 eq. 6).
    pub psi_set: f32,
    /// v_set, speed set-point, m/s, 0 ..= v_max (000 eq. 7).
    pub v_set: f32,
    /// PI-D set-points (001 §2).
    pub setpoints: PidSetpoints,
    /// Mode.
    pub mode: Mode,
    /// F̄, the bounded controlling force, m/s².
    pub force: Vec2,
    /// v̄_c, the bounded commanded velocity, m/s.
    pub velocity: Vec2,
    /// The active goal-point (mission goal or top ghost), m.
    pub target: Vec2,
    /// Number of stacked ghost goal-points.
    pub ghost_depth: u8,
    /// Signed distance to the nearest obstacle or vehicle circle, m (negative: inside).
    pub clearance_m: f32,
}

impl Command {
    /// A hold: zero speed, heading kept at `heading`.
    pub fn hold(reason: HoldReason, heading: f32) -> Command {
        Command {
            psi_set: crate::math::wrap_angle(heading),
            v_set: 0.0,
            setpoints: PidSetpoints {
                phi_c: crate::math::wrap_angle(heading),
                ..PidSetpoints::default()
            },
            mode: Mode::Hold(reason),
            force: Vec2::ZERO,
            velocity: Vec2::ZERO,
            target: Vec2::ZERO,
            ghost_depth: 0,
            clearance_m: f32::INFINITY,
        }
    }

    /// Every number finite (clearance may be +∞ in an empty world).
    pub fn is_finite(&self) -> bool {
        let s = &self.setpoints;
        [
            self.psi_set,
            self.v_set,
            s.a_c,
            s.v_c,
            s.i_surge,
            s.alpha_c,
            s.omega_c,
            s.phi_c,
        ]
        .iter()
        .all(|x| x.is_finite())
            && self.force.is_finite()
            && self.velocity.is_finite()
            && self.target.is_finite()
            && !self.clearance_m.is_nan()
    }
}

/// Why a step or a setting was refused. The planner's state is unchanged after any of them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StepError {
    /// Navigation has a non-finite or out-of-range number.
    BadNav,
    /// The mission's goal is non-finite or out of range.
    BadGoal,
    /// The mission's formation request is invalid.
    BadFormation(FormationError),
    /// A parameter is invalid.
    BadParams(ParamError),
    /// The computation produced a non-finite number (never expected; the step is discarded).
    NonFinite,
}

impl core::fmt::Display for StepError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            StepError::BadNav => f.write_str("navigation state non-finite or out of range"),
            StepError::BadGoal => f.write_str("goal non-finite or out of range"),
            StepError::BadFormation(e) => write!(f, "formation refused: {e}"),
            StepError::BadParams(e) => write!(f, "{e}"),
            StepError::NonFinite => f.write_str("planner produced a non-finite number"),
        }
    }
}

/// Counters of refused inputs, for telemetry.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlannerCounters {
    /// Steps refused for bad navigation.
    pub bad_nav: u32,
    /// Missions refused.
    pub bad_mission: u32,
    /// Parameter sets refused.
    pub bad_params: u32,
    /// Steps discarded for a non-finite result.
    pub non_finite: u32,
}

/// The integrator state carried from one period to the next.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Integrator {
    /// F̄(k−1).
    force: Vec2,
    /// v̄_c(k−1).
    velocity: Vec2,
}

/// The planner: parameters, mission and the state carried between periods.
#[derive(Clone, Debug)]
pub struct Planner {
    params: Params,
    circle: SampleCircle,
    agent_stator: Stator,
    mission: Option<Mission>,
    integrator: Integrator,
    setpoints: SetpointState,
    escape: Escape,
    rotor_sense: RotorSense,
    /// Refused-input counters.
    pub counters: PlannerCounters,
}

fn finite_coord(p: Vec2) -> bool {
    p.is_finite() && p.x.abs() <= MAX_COORD_M && p.y.abs() <= MAX_COORD_M
}

impl NavState {
    /// Checks that every number is finite and in range.
    pub fn validate(&self) -> Result<(), StepError> {
        let ok = finite_coord(self.position)
            && self.heading.is_finite()
            && self.velocity.is_finite()
            && self.velocity.norm2() <= MAX_NAV_SPEED * MAX_NAV_SPEED;
        if ok {
            Ok(())
        } else {
            Err(StepError::BadNav)
        }
    }
}

impl Planner {
    /// A planner with validated parameters and no mission (it holds until given one).
    pub fn new(params: Params) -> Result<Self, ParamError> {
        params.validate()?;
        Ok(Planner {
            params,
            circle: SampleCircle::new(params.epsilon_m, params.n_gamma),
            agent_stator: Stator::new(params.agent_a_plus),
            mission: None,
            integrator: Integrator::default(),
            setpoints: SetpointState::default(),
            escape: Escape::new(params.seed),
            rotor_sense: RotorSense::Free,
            counters: PlannerCounters::default(),
        })
    }

    /// The parameters in force.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Replaces the parameters if they are valid; otherwise keeps the old ones and says why.
    /// The integrator and ghosts are kept (parameters may be tuned on the move).
    pub fn set_params(&mut self, params: Params) -> Result<(), StepError> {
        if let Err(e) = params.validate() {
            self.counters.bad_params = self.counters.bad_params.saturating_add(1);
            return Err(StepError::BadParams(e));
        }
        self.circle = SampleCircle::new(params.epsilon_m, params.n_gamma);
        self.agent_stator = Stator::new(params.agent_a_plus);
        self.params = params;
        Ok(())
    }

    /// The mission in force.
    pub fn mission(&self) -> Option<&Mission> {
        self.mission.as_ref()
    }

    /// Sets a new mission (ghosts are cleared; the planned velocity is kept, so a goal change on
    /// the move is smooth). An invalid mission is refused and the old one kept.
    pub fn set_mission(&mut self, mission: Mission) -> Result<(), StepError> {
        let checked = if !finite_coord(mission.goal) {
            Err(StepError::BadGoal)
        } else if let Some(Err(e)) = mission.formation.map(|f| f.validate()) {
            Err(StepError::BadFormation(e))
        } else {
            Ok(())
        };
        if checked.is_err() {
            self.counters.bad_mission = self.counters.bad_mission.saturating_add(1);
            return checked;
        }
        self.mission = Some(mission);
        self.escape.reset();
        self.rotor_sense = RotorSense::Free;
        Ok(())
    }

    /// Drops the mission: the planner holds.
    pub fn clear_mission(&mut self) {
        self.mission = None;
        self.reset_motion();
    }

    /// Forgets the planned motion and ghosts (after a hold, so planning restarts from rest).
    pub fn reset_motion(&mut self) {
        self.integrator = Integrator::default();
        self.setpoints.reset();
        self.escape.reset();
        self.rotor_sense = RotorSense::Free;
    }

    /// The ghost goal-points, bottom first.
    pub fn ghosts(&self) -> &[GhostGoal] {
        self.escape.ghosts()
    }

    /// Ghost goal-point counters.
    pub fn escape_counters(&self) -> EscapeCounters {
        self.escape.counters
    }

    /// The rotor sense chosen for the current obstacle encounter.
    pub fn rotor_sense(&self) -> RotorSense {
        self.rotor_sense
    }

    /// One planner period at time `now_ms` (ms since boot, monotonic), for the vehicle in state
    /// `nav` in `world`. On error the state is unchanged.
    pub fn step(
        &mut self,
        now_ms: u64,
        nav: &NavState,
        world: &World,
    ) -> Result<Command, StepError> {
        if let Err(e) = nav.validate() {
            self.counters.bad_nav = self.counters.bad_nav.saturating_add(1);
            return Err(e);
        }
        let Some(mission) = self.mission else {
            self.reset_motion();
            return Ok(Command::hold(HoldReason::NoMission, nav.heading));
        };
        let p = nav.position;
        let prm = self.params;
        let target = self.escape.active_target(mission.goal);

        // Attractors: the active goal-point and the virtual leader (001 Table 1).
        let goal = GoalPdf::new(target, prm.a_minus, prm.sigma_m);
        let formation = mission
            .formation
            .filter(|_| !self.escape.formation_released(now_ms));
        let leader = formation.and_then(|f| {
            let vl = f.virtual_leader(p, world.agents())?;
            Some((f, GoalPdf::new(vl, f.attraction, f.sigma())))
        });

        // Clearance, and the rotor terms: one normal per obstacle, one sense per encounter.
        let mut normals: Vec<(Vec2, f32), { crate::world::MAX_OBSTACLES }> = Vec::new();
        let mut clearance = f32::INFINITY;
        for o in world.obstacles() {
            let r = o.shape.signed_distance(p);
            clearance = clearance.min(r);
            if prm.a_rotor > 0.0 {
                let _ = normals.push((
                    o.shape.outward_normal(p, r, NORMAL_STEP_M),
                    o.stator().reach(r),
                ));
            }
        }
        for a in world.agents() {
            clearance = clearance.min((p - a.position).norm() - prm.agent_radius_m);
        }
        let strongest = normals.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1));
        let sense = self.rotor_sense.update(strongest, target - p);
        let rotor_gradient = normals.iter().fold(Vec2::ZERO, |g, &(n, h)| {
            g + RotorTerm::new(prm.a_rotor, n, h, sense).gradient
        });

        let field = Field {
            obstacles: world.obstacles(),
            agents: world.agents(),
            agent_radius: prm.agent_radius_m,
            agent_stator: self.agent_stator,
            goal,
            leader: leader.map(|(_, pdf)| pdf),
            rotor_gradient,
            origin: p,
        };
        let measured = Measured {
            position: p,
            velocity: nav.velocity,
            heading: nav.heading,
        };
        let e1 = Some(measured.e1());

        let forces = field.sampled_forces(&self.circle);
        let f_nf = forces.full;
        let f = f_nf - self.integrator.velocity * prm.mu;
        let f_bar = bound::bound(f, prm.f_max, e1, prm.bounding);
        let v_c = (f_bar + self.integrator.force) * (0.5 * prm.period_s) + self.integrator.velocity;
        let v_bar = bound::bound(v_c, prm.v_max, e1, prm.bounding);

        let mut setpoints = self.setpoints;
        let sp = setpoints.decompose(prm.period_s, f_bar, v_bar, &measured);
        let mut escape = self.escape.clone();
        // What holds a stalled vehicle (escape.rs): is there a way down without the virtual
        // leader, or without the other vehicles too? "A way down" is a descent stronger than
        // what friction balances at the stall speed.
        let cause = |target: Vec2| {
            let free = |f: Vec2| f.norm() > prm.mu * prm.stall_speed;
            if let Some((f, _)) = leader {
                if free(forces.without_leader) {
                    // Held by the formation near the goal is arrival in formation, not a stall:
                    // N + 1 lattice cells of side λ fit within λ·√(N + 1) of it.
                    let n = world.agents().len() as f32 + 1.0;
                    let footprint = f.lattice_m * crate::math::sqrt(n);
                    return if (target - p).norm() <= footprint {
                        StallCause::Vehicles
                    } else {
                        StallCause::Formation
                    };
                }
            }
            if free(forces.static_field) {
                StallCause::Vehicles
            } else {
                StallCause::Static
            }
        };
        escape.update(now_ms, p, v_bar.norm(), mission.goal, &prm, cause);

        let goal_dist = (mission.goal - p).norm();
        let mode = if goal_dist <= prm.arrival_radius_m {
            Mode::Arrived
        } else if escape.ghosts().is_empty() {
            Mode::Transit
        } else {
            Mode::Escape
        };
        let cmd = Command {
            psi_set: sp.phi_c,
            v_set: v_bar.norm().min(prm.v_max),
            setpoints: sp,
            mode,
            force: f_bar,
            velocity: v_bar,
            target: escape.active_target(mission.goal),
            ghost_depth: escape.ghosts().len() as u8,
            clearance_m: clearance,
        };
        if !cmd.is_finite() {
            self.counters.non_finite = self.counters.non_finite.saturating_add(1);
            return Err(StepError::NonFinite);
        }
        self.integrator = Integrator {
            force: f_bar,
            velocity: v_bar,
        };
        self.setpoints = setpoints;
        self.escape = escape;
        self.rotor_sense = sense;
        Ok(cmd)
    }
}
