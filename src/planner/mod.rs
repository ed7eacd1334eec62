//! The trajectory planner: one [`Planner::step`] per period, by the strategy in
//! `Params::strategy` — the VPF of seeds 000 and 001 (`vpf.rs`), or the multipoint potential
//! field (seed 003, [`multipoint`]) or a navigation function (seed 004, [`navfn`]), whose glue is
//! `strategy.rs`. Each strategy yields the force F of step 3; steps 4–6 are shared. Every
//! strategy plans against moving obstacles at their predicted positions
//! ([`Obstacle::predicted_shift`](crate::world::Obstacle::predicted_shift)).
//!
//! The VPF step, for the vehicle at p with measured velocity v and planned velocity v_c(k−1):
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
pub mod mission;
pub mod multipoint;
pub mod navfn;
pub mod setpoints;
mod strategy;
mod vpf;

use heapless::Vec;

use crate::field::{RotorSense, Stator};
use crate::math::Vec2;
use crate::params::{ParamError, Params, Strategy};
use crate::world::{World, MAX_OBSTACLES};

pub use crate::types::{
    Command, Formation, FormationError, HoldReason, Mission, Mode, NavState, PidSetpoints,
    StepError, MAX_COORD_M, MAX_NAV_SPEED,
};
pub use escape::{EscapeCounters, GhostGoal, StallCause, MAX_GHOSTS};
pub use gradient::SampleCircle;
pub use mission::{
    MissionEnd, MissionError, MissionProgress, Survey, Waypoint, WaypointError, Waypoints,
    MAX_WAYPOINTS,
};

use crate::types::nav::finite_coord;
use escape::Escape;
use setpoints::{Measured, SetpointState, V_EPS};
use strategy::ArcState;

/// Deceleration planned for arrival, as a fraction of F_max: half, so that an autopilot that
/// lags the speed set-point still stops in the arrival circle.
pub const ARRIVAL_BRAKE: f32 = 0.5;

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

/// Everything a step changes: worked on as a copy and kept only if the step succeeds.
#[derive(Clone, Debug)]
struct Motion {
    integrator: Integrator,
    setpoints: SetpointState,
    escape: Escape,
    rotor_sense: RotorSense,
    arc: ArcState,
    /// The navigation function's last descent direction (`strategy.rs`, saddles); zero when
    /// there is none yet.
    descent: Vec2,
    /// Arrival latch of the alternative strategies (`strategy.rs`).
    arrived: bool,
}

impl Motion {
    fn new(seed: u32) -> Self {
        Motion {
            integrator: Integrator::default(),
            setpoints: SetpointState::default(),
            escape: Escape::new(seed),
            rotor_sense: RotorSense::Free,
            arc: ArcState::default(),
            descent: Vec2::ZERO,
            arrived: false,
        }
    }
}

/// The waypoint mission in force and how far along it the vehicle is.
#[derive(Clone, Debug)]
struct Plan {
    /// The waypoints (one for a single-goal mission, whose radius is then 0: the parameter's).
    waypoints: Waypoints,
    /// Index of the waypoint being flown to.
    current: u8,
    /// The last waypoint has been reached (holding or loitering there).
    complete: bool,
    /// Counts changes of the goal (a new mission, the next waypoint), for the route layer.
    generation: u32,
}

/// The leg being flown: what the current waypoint asks of the strategies.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Leg {
    /// Arrival radius, m.
    radius: f32,
    /// The leg's own speed bound, m/s (∞: none).
    speed: f32,
    /// Not braked onto: an intermediate waypoint, or the last one of a mission that loiters.
    passing: bool,
    /// Circling the last waypoint: (radius, clockwise).
    loiter: Option<(f32, bool)>,
    /// The waypoint before (the leg's start), from the second leg on.
    from: Option<Vec2>,
}

/// Per-obstacle planning shifts for moving obstacles ([`crate::world::Obstacle::predicted_shift`]),
/// in table order.
type Shifts = Vec<Vec2, MAX_OBSTACLES>;

/// What one step reads, shared by the strategies.
#[derive(Clone, Copy)]
struct Context<'a> {
    now_ms: u64,
    nav: &'a NavState,
    world: &'a World,
    mission: Mission,
    /// The leg to `mission.goal`.
    leg: Leg,
    /// Where the strategy steers for: the route layer's goal-point, else the mission goal.
    aim: Vec2,
    /// Whether the route layer gave `aim` (VPF then cruises to it).
    routed: bool,
    /// Where each obstacle is planned against, relative to where it is.
    shifts: &'a Shifts,
    /// Signed distance to the nearest obstacle or vehicle circle as they are now, m (for the
    /// VPF infinite until `plan_vpf` has measured the obstacles).
    clearance: f32,
}

impl Context<'_> {
    /// The obstacles' shapes at their predicted positions (those left to the evidence map
    /// excepted: [`World::left_to_map`]).
    fn predicted_shapes(&self) -> impl Iterator<Item = crate::field::Shape> + '_ {
        let shift = |i: usize| self.shifts.get(i).copied().unwrap_or(Vec2::ZERO);
        self.world
            .obstacles()
            .iter()
            .enumerate()
            .filter(|(_, o)| !self.world.left_to_map(o))
            .map(move |(i, o)| o.shape.translated(shift(i)))
    }
}

/// The planner: parameters, mission and the state carried between periods.
#[derive(Clone, Debug)]
pub struct Planner {
    params: Params,
    circle: SampleCircle,
    agent_stator: Stator,
    /// Stator of the evidence map (A_s⁺ = `params.a_plus`, as sensed obstacles).
    map_stator: Stator,
    /// The leg being flown: its goal is the current waypoint's.
    mission: Option<Mission>,
    /// The waypoints of the mission.
    plan: Plan,
    /// The route layer's goal-point for the next step, if it has one (`set_route`).
    route: Option<Vec2>,
    motion: Motion,
    /// Refused-input counters.
    pub counters: PlannerCounters,
}

impl Planner {
    /// A planner with validated parameters and no mission (it holds until given one).
    pub fn new(params: Params) -> Result<Self, ParamError> {
        params.validate()?;
        Ok(Planner {
            params,
            circle: SampleCircle::new(params.epsilon_m, params.n_gamma),
            agent_stator: Stator::new(params.agent_a_plus),
            map_stator: Stator::new(params.a_plus),
            mission: None,
            plan: Plan {
                waypoints: Waypoints::single(Waypoint::with_parameter_radius(Vec2::ZERO)),
                current: 0,
                complete: false,
                generation: 0,
            },
            route: None,
            motion: Motion::new(params.seed),
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
        self.map_stator = Stator::new(params.a_plus);
        self.params = params;
        Ok(())
    }

    /// The mission in force; its goal is the waypoint being flown to.
    pub fn mission(&self) -> Option<&Mission> {
        self.mission.as_ref()
    }

    /// The waypoints of the mission in force (one, with radius 0 — `Params::arrival_radius_m`
    /// — for a single-goal mission).
    pub fn waypoints(&self) -> Option<&Waypoints> {
        self.mission.map(|_| &self.plan.waypoints)
    }

    /// How far along its mission the vehicle at `p` is.
    pub fn progress(&self, p: Vec2) -> Option<MissionProgress> {
        self.mission?;
        let wps = &self.plan.waypoints;
        let count = wps.len() as u8;
        Some(if self.plan.complete {
            MissionProgress {
                current: count,
                count,
                to_go_m: 0.0,
            }
        } else {
            MissionProgress {
                current: self.plan.current,
                count,
                to_go_m: wps.distance_to_go(p, usize::from(self.plan.current)),
            }
        })
    }

    /// Counts goal changes (a new mission, the next waypoint): the runtime hands the route
    /// layer the new goal when it changes.
    pub fn goal_generation(&self) -> u32 {
        self.plan.generation
    }

    /// Sets a new single-goal mission: the one-waypoint, hold-at-last case (ghosts are cleared;
    /// the planned velocity is kept, so a goal change on the move is smooth). An invalid mission
    /// is refused and the old one kept.
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
        let single = Waypoint::with_parameter_radius(mission.goal);
        self.start(Waypoints::single(single), mission.formation);
        Ok(())
    }

    /// Sets a waypoint mission, flown by every vehicle of a formation alike (ghosts are
    /// cleared, the planned velocity kept). An invalid formation is refused and the old mission
    /// kept; the waypoints were checked when they were made.
    pub fn set_waypoints(
        &mut self,
        waypoints: &Waypoints,
        formation: Option<Formation>,
    ) -> Result<(), StepError> {
        let checked = match (formation.map(|f| f.validate()), waypoints.end().validate()) {
            (Some(Err(e)), _) => Err(StepError::BadFormation(e)),
            (_, Err(e)) => Err(StepError::BadMission(e)),
            _ if waypoints.is_empty() => Err(StepError::BadMission(MissionError::Empty)),
            _ => Ok(()),
        };
        if checked.is_err() {
            self.counters.bad_mission = self.counters.bad_mission.saturating_add(1);
            return checked;
        }
        self.start(waypoints.clone(), formation);
        Ok(())
    }

    /// Flies `waypoints` from the first.
    fn start(&mut self, waypoints: Waypoints, formation: Option<Formation>) {
        let goal = waypoints.get(0).map_or(Vec2::ZERO, |w| w.position());
        self.plan = Plan {
            waypoints,
            current: 0,
            complete: false,
            generation: self.plan.generation.wrapping_add(1),
        };
        self.mission = Some(Mission { goal, formation });
        self.next_goal();
    }

    /// Ghosts, the rotor sense, the multipoint arc and the arrival latch belong to one goal.
    fn next_goal(&mut self) {
        self.motion.escape.reset();
        self.motion.rotor_sense = RotorSense::Free;
        self.motion.arc = ArcState::default();
        self.motion.descent = Vec2::ZERO;
        self.motion.arrived = false;
    }

    /// The leg to the current waypoint.
    fn leg(&self) -> Leg {
        let plan = &self.plan;
        let i = usize::from(plan.current);
        let w = plan.waypoints.get(i);
        let last = i + 1 >= plan.waypoints.len();
        let loiter = match plan.waypoints.end() {
            MissionEnd::Loiter {
                radius_m,
                clockwise,
            } => Some((radius_m, clockwise)),
            MissionEnd::Hold => None,
        };
        let radius = w.map_or(0.0, |w| w.radius_m());
        Leg {
            radius: if radius > 0.0 {
                radius
            } else {
                self.params.arrival_radius_m
            },
            speed: w.and_then(|w| w.speed()).unwrap_or(f32::INFINITY),
            passing: !last || loiter.is_some(),
            loiter: loiter.filter(|_| plan.complete),
            from: i
                .checked_sub(1)
                .and_then(|k| plan.waypoints.get(k))
                .map(|w| w.position()),
        }
    }

    /// After a step: within the current waypoint's radius, the next waypoint becomes the goal,
    /// or the mission is complete.
    ///
    /// In formation, arrival is judged at the formation's centre — the mean position of this
    /// vehicle and the others within its footprint λ·√(N + 1) (N + 1 lattice cells) — within
    /// the radius plus λ: a fleet cannot all pass within a few metres of one point, and vehicles
    /// judging by their own positions would turn one by one and drag each other apart. Every
    /// vehicle that sees the same fleet sees the same centre, so they turn together.
    fn advance(&mut self, p: Vec2, agents: &[crate::world::Agent]) {
        let Some(m) = self.mission.as_mut() else {
            return;
        };
        if self.plan.complete {
            return;
        }
        let (centre, slack) = match m.formation {
            None => (p, 0.0),
            Some(f) => {
                let reach = f.lattice_m * crate::math::sqrt(agents.len() as f32 + 1.0);
                let (sum, n) = agents
                    .iter()
                    .filter(|a| (a.position - p).norm2() <= reach * reach)
                    .fold((p, 1.0f32), |(s, n), a| (s + a.position, n + 1.0));
                (sum * (1.0 / n), f.lattice_m)
            }
        };
        let current = self.plan.waypoints.get(usize::from(self.plan.current));
        let radius = current.map_or(0.0, |w| w.radius_m());
        let radius = if radius > 0.0 {
            radius
        } else {
            self.params.arrival_radius_m
        };
        if (m.goal - centre).norm() > radius + slack {
            return;
        }
        let next = usize::from(self.plan.current) + 1;
        match self.plan.waypoints.get(next) {
            Some(w) => {
                m.goal = w.position();
                self.plan.current = next as u8;
                self.plan.generation = self.plan.generation.wrapping_add(1);
                self.next_goal();
            }
            None => self.plan.complete = true,
        }
    }

    /// The route layer's goal-point for this step (`crate::route`: an intermediate one, or the
    /// mission goal when it is in plain sight), or `None` when there is no route (the planner
    /// as published). Set by the runtime before each step; arrival is still judged at the
    /// mission goal.
    pub fn set_route(&mut self, aim: Option<Vec2>) {
        self.route = aim.filter(|a| finite_coord(*a));
    }

    /// Drops the mission: the planner holds.
    pub fn clear_mission(&mut self) {
        self.mission = None;
        self.reset_motion();
    }

    /// Forgets the planned motion and ghosts (after a hold, so planning restarts from rest).
    pub fn reset_motion(&mut self) {
        self.motion.integrator = Integrator::default();
        self.motion.setpoints.reset();
        self.motion.escape.reset();
        self.motion.rotor_sense = RotorSense::Free;
        self.motion.arc = ArcState::default();
        self.motion.descent = Vec2::ZERO;
        self.motion.arrived = false;
    }

    /// Makes the planned velocity v̄ what was actually commanded (the runtime's guard changed
    /// it), so the next step integrates from there (000 eq. 5) and a vehicle held back shows
    /// as stalled to the local-minimum test.
    pub fn override_velocity(&mut self, velocity: Vec2) {
        if velocity.is_finite() {
            self.motion.integrator = Integrator {
                force: Vec2::ZERO,
                velocity,
            };
            self.motion.setpoints.restart_integral();
        }
    }

    /// The ghost goal-points, bottom first.
    pub fn ghosts(&self) -> &[GhostGoal] {
        self.motion.escape.ghosts()
    }

    /// Ghost goal-point counters.
    pub fn escape_counters(&self) -> EscapeCounters {
        self.motion.escape.counters
    }

    /// The rotor sense chosen for the current obstacle encounter.
    pub fn rotor_sense(&self) -> RotorSense {
        self.motion.rotor_sense
    }

    /// One planner period at time `now_ms` (ms since boot, monotonic), for the vehicle in state
    /// `nav` in `world`, by the strategy in `params.strategy`. On error the state is unchanged.
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
        let mut shifts = Shifts::new();
        for o in world.obstacles() {
            let shift = o.predicted_shift(now_ms, p, nav.velocity, self.params.horizon_s);
            // Same capacity as the obstacle table: never full.
            let _ = shifts.push(shift);
        }
        // The VPF measures every obstacle where it is planned against, which for a still one
        // is where it is: it finds the clearance from those distances (`plan_vpf`).
        let clearance = match self.params.strategy {
            Strategy::Vpf => f32::INFINITY,
            Strategy::Multipoint | Strategy::Navfn => {
                world.clearance(p, self.params.agent_radius_m)
            }
        };
        let leg = self.leg();
        let reach = vpf::cruise_reach(&self.params);
        let aim = match (leg.loiter, self.route, leg.from) {
            (Some((r, clockwise)), _, _) => mission::loiter_aim(p, mission.goal, r, clockwise, r),
            // The route layer's way round something: follow it.
            (None, Some(a), _) if a != mission.goal => a,
            // The goal in plain sight (or no route), on a leg from a waypoint: along the leg,
            // so that a survey flies its lines.
            (None, _, Some(from)) => {
                mission::along_leg(p, from, mission.goal, mission::LEG_LOOKAHEAD * reach)
            }
            (None, route, None) => route.unwrap_or(mission.goal),
        };
        let cx = Context {
            now_ms,
            nav,
            world,
            mission,
            leg,
            aim,
            routed: self.route.is_some(),
            shifts: &shifts,
            clearance,
        };
        let mut motion = self.motion.clone();
        let cmd = match self.params.strategy {
            Strategy::Vpf => self.plan_vpf(&mut motion, &cx),
            Strategy::Multipoint => self.plan_multipoint(&mut motion, &cx),
            Strategy::Navfn => self.plan_navfn(&mut motion, &cx),
        };
        if !cmd.is_finite() {
            self.counters.non_finite = self.counters.non_finite.saturating_add(1);
            return Err(StepError::NonFinite);
        }
        self.motion = motion;
        self.advance(p, world.agents());
        Ok(cmd)
    }

    /// Arrived within the arrival radius (or latched there, `strategy.rs`), escaping while a
    /// ghost goal-point is up, else in transit.
    fn mode(&self, m: &Motion, cx: &Context<'_>) -> Mode {
        let d = (cx.mission.goal - cx.nav.position).norm();
        let ghosts = !m.escape.ghosts().is_empty();
        if cx.leg.loiter.is_some() && !ghosts {
            Mode::Loiter
        } else if (!cx.leg.passing && d <= cx.leg.radius) || m.arrived {
            Mode::Arrived
        } else if ghosts {
            Mode::Escape
        } else {
            Mode::Transit
        }
    }

    /// The fastest the vehicle may go and still stop on the goal, m/s: on a route straight to
    /// the mission's goal (no intermediate goal-point, no ghost), √(2·a·(d − r/2)) with a =
    /// [`ARRIVAL_BRAKE`]·F_max, d the distance to go and r the arrival radius, so it stops
    /// halfway into the arrival circle; unbounded otherwise. None of the seeds brakes: their
    /// goal-point field slows the vehicle by itself, with the time constant μσ²/(A⁻ε) of
    /// its Gaussian's core (≈ 50 s with the defaults), which is what makes arrivals crawl.
    ///
    /// A waypoint that is passed (not the last, or the last of a mission that loiters) is
    /// not braked onto.
    fn arrival_speed(&self, m: &Motion, cx: &Context<'_>) -> f32 {
        let goal = cx.mission.goal;
        if cx.leg.passing || !cx.routed || cx.aim != goal || m.escape.active_target(cx.aim) != goal
        {
            return f32::INFINITY;
        }
        let prm = &self.params;
        let to_go = (goal - cx.nav.position).norm() - 0.5 * cx.leg.radius;
        crate::math::sqrt(2.0 * ARRIVAL_BRAKE * prm.f_max * crate::math::max(0.0, to_go))
    }

    /// Steps 4–6 of the loop, shared by every strategy: bound the force F (001 eq. 5),
    /// integrate it bilinearly into the planned velocity and bound that (000 eq. 5, 001
    /// eq. 6–7), and decompose into set-points (000 eq. 6–7, 001 §2).
    fn integrate(&self, m: &mut Motion, cx: &Context<'_>, f: Vec2) -> Command {
        let prm = &self.params;
        let measured = Measured {
            position: cx.nav.position,
            velocity: cx.nav.velocity,
            heading: cx.nav.heading,
        };
        // At rest ê₁ is the heading: a craft that turns slowly, with the force astern, may spin
        // on the spot after it; plain bounding at rest measured worse (docs/bench-history.md,
        // "plain bounding for a stopped slow-turning craft"), and so did ê₁ at rest from the last planned
        // velocity, as eq. 9 takes it (setpoints.rs), which ends the spin (boxes seed 102: 30
        // → 1 s at rest commanded more than 150° off): flat-fish with its recipe, seeds 0–33,
        // 366 → 361 of 408; 102–169, 712 → 709 of 816.
        let e1 = Some(measured.e1());
        let f_bar = bound::bound(f, prm.f_max, e1, prm.bounding);
        let v_c = (f_bar + m.integrator.force) * (0.5 * prm.period_s) + m.integrator.velocity;
        let arrival = self.arrival_speed(m, cx);
        let v_lim = crate::math::min(prm.v_max, arrival);
        // A waypoint's own speed bounds the leg to it.
        let v_lim = crate::math::min(v_lim, cx.leg.speed);
        let v_bar = bound::bound(v_c, v_lim, e1, prm.bounding);
        let sp = m
            .setpoints
            .decompose(prm.period_s, f_bar, v_bar, &measured, prm.turn_rate_rps);
        m.integrator = Integrator {
            force: f_bar,
            velocity: v_bar,
        };
        // The speed set-point is v̄ along the commanded heading: below V_EPS the heading is
        // kept (setpoints.rs), and a small v̄ pointing elsewhere — back to the goal after an
        // overshoot — must not push the vehicle on along the old heading.
        let v_set = if v_bar.norm2() > V_EPS * V_EPS {
            v_bar.norm()
        } else {
            crate::math::max(0.0, v_bar.dot(Vec2::from_angle(sp.phi_c)))
        };
        // A craft that turns slowly goes where it points, not where it is told
        // (`Params::turn_rate_rps`; our addition, none of the seeds has it: 000 and 001 fly a
        // craft that turns at once): its speed set-point follows the turn it can make
        // ([`turning_speed`]). The planned velocity v̄ is not cut: the field's motion, the stall
        // test and the set-points stay the paper's.
        let target = m.escape.active_target(cx.aim);
        let v_set = if prm.turns_slowly() {
            let p = cx.nav.position;
            let others = cx.world.agents().iter().fold(f32::INFINITY, |c, a| {
                crate::math::min(c, (a.position - p).norm() - 2.0 * prm.agent_radius_m)
            });
            turning_speed(
                v_set,
                crate::math::wrap_angle(sp.phi_c - cx.nav.heading),
                (target - p).norm(),
                prm.turn_rate_rps,
                others,
                // Bounded only while it steers for the goal it stops on.
                arrival.is_finite(),
            )
        } else {
            v_set
        };
        Command {
            psi_set: sp.phi_c,
            v_set: crate::math::min_num(v_set, v_lim),
            setpoints: sp,
            mode: self.mode(m, cx),
            force: f_bar,
            velocity: v_bar,
            target,
            ghost_depth: m.escape.ghosts().len() as u8,
            clearance_m: cx.clearance,
        }
    }
}

/// The speed set-point of a craft that turns at most at `rate` (ψ̇, rad/s), for the plan's
/// speed `v`, the heading error `e` (commanded − present, rad) and the distance `d` to the
/// point steered for (m):
/// - from 90° off on, none: it turns on the spot first (going on would take it away);
/// - otherwise the larger of v·cos e (it goes where it points, and turns on a tighter circle
///   than at v) and the fastest speed whose turn still passes through that point: the circle
///   tangent to the heading through a point d away at bearing e has radius d / (2 sin e), and a
///   turn at ψ̇ and speed u has radius u/ψ̇, so u ≤ ψ̇·d / (2 sin e). That one is kept within
///   ψ̇ times `others`, the room to the nearest other vehicle (m): the guard judges vehicles by
///   their closest approach on straight lines, which does not see a turn;
/// - never more than v; and, `arriving` at the goal it stops on (not a point it passes or a
///   carrot it chases), never more than the speed whose turn passes through it.
///
/// The v·cos e floor lets a craft steering for a far point sweep on a turn wider than the
/// circle through it: the point moves on with the craft. The goal does not. Within about
/// v·sin 2e / ψ̇ of it (14 m at 0.65 m/s) that floor is the faster, and a flat-fish flew round
/// its goal on a circle that never met the arrival radius (clutter seed 20: 0.2 m short when
/// its time ran out). Capping every point steered for by the turn through it cost more than
/// it gained (carrots and detour points come close on turns): `cargo hil bench --models
/// flatfish --params hil/recipes/flatfish.toml --seeds 170`, 1 832 → 1 816 of 2 040. Capping
/// the goal alone: 1 832 → 1 837 (5 gained, none lost), and on seeds 170–339 (`--first-seed
/// 170`) 1 806 → 1 808 (2 gained, none lost), through other chance (`--trial 1`) 1 820 →
/// 1 821 (2 gained, 1 lost); contacts 0, 2 and 2 as before.
///
/// With the cos e cut alone, a flat-fish stopped to turn whenever its heading was 60–90° off,
/// even towards a goal-point 40 m away that it could have reached on the turn
/// (`cargo hil bench --models flatfish --params hil/recipes/flatfish.toml --seeds 34`: 259 of
/// 408 worlds, 7 contacts; with this, 275, 3).
fn turning_speed(v: f32, e: f32, d: f32, rate: f32, others: f32, arriving: bool) -> f32 {
    // `e` is wrapped to ±π by the caller; NaN turns on the spot too.
    let ahead = e.abs() < core::f32::consts::FRAC_PI_2;
    if !ahead {
        return 0.0;
    }
    let cos_e = crate::math::cos(e);
    let reach = rate * d / crate::math::max(2.0 * crate::math::sin(e).abs(), 1e-6);
    let v = if arriving {
        crate::math::min_num(v, reach)
    } else {
        v
    };
    let reach = crate::math::min_num(reach, rate * crate::math::max(0.0, others));
    crate::math::min(v, crate::math::max(reach, v * cos_e))
}

#[cfg(test)]
mod tests {
    use super::turning_speed;

    #[test]
    fn a_slow_turning_craft_keeps_its_speed_on_a_turn_that_reaches_its_goal_point() {
        let (v, rate, deg) = (0.567, 0.046, core::f32::consts::PI / 180.0);
        let open = f32::INFINITY;
        // Straight on: the plan's speed.
        assert_eq!(turning_speed(v, 0.0, 40.0, rate, open, false), v);
        // 60° off, a goal-point 40 m away: the turn at 0.567 m/s (radius 12.3 m) reaches it.
        assert_eq!(turning_speed(v, 60.0 * deg, 40.0, rate, open, false), v);
        // ... 4 m away it does not: cut to v·cos e, as before.
        let cut = turning_speed(v, 60.0 * deg, 4.0, rate, open, false);
        assert!((cut - v * 0.5).abs() < 1e-4, "{cut}");
        // ... nor with another vehicle 3 m off the hull.
        let near = turning_speed(v, 60.0 * deg, 40.0, rate, 3.0, false);
        assert!((near - v * 0.5).abs() < 1e-4, "{near}");
        // From 90° off on it turns on the spot, whatever lies ahead.
        assert_eq!(turning_speed(v, 100.0 * deg, 400.0, rate, open, false), 0.0);
        assert_eq!(turning_speed(v, f32::NAN, 40.0, rate, open, false), 0.0);
    }

    #[test]
    fn a_slow_turning_craft_arriving_slows_to_a_turn_through_its_goal() {
        let (v, rate, deg) = (0.65, 0.046, core::f32::consts::PI / 180.0);
        let open = f32::INFINITY;
        // The goal 4 m away, 60° off: the circle through it has radius 4 / (2 sin 60°) = 2.31 m,
        // flown at 0.046 × 2.31 = 0.106 m/s, not at v·cos e = 0.325 m/s.
        let arriving = turning_speed(v, 60.0 * deg, 4.0, rate, open, true);
        assert!(
            (arriving - 0.046 * 4.0 / 3f32.sqrt()).abs() < 1e-4,
            "{arriving}"
        );
        let passing = turning_speed(v, 60.0 * deg, 4.0, rate, open, false);
        assert!((passing - v * 0.5).abs() < 1e-4, "{passing}");
        // Far off, or dead ahead, arriving changes nothing.
        assert_eq!(turning_speed(v, 60.0 * deg, 40.0, rate, open, true), v);
        assert_eq!(turning_speed(v, 0.0, 4.0, rate, open, true), v);
        // It never asks for more than the turn through the goal, near other vehicles either.
        let near = turning_speed(v, 60.0 * deg, 4.0, rate, 30.0, true);
        assert!(near <= arriving + 1e-6, "{near}");
    }
}
