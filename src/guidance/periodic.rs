//! The hard-real-time half of the runtime: one [`Periodic::on_tick`] per period.
//!
//! In order: apply queued requests (missions, parameters, charts; each answered with a reply),
//! send the replies the background owes (requests refused at the wire, or "busy"),
//! take at most [`SIGHTINGS_PER_PERIOD`] sightings into the world tables, age out stale sensed
//! entries, check the fail-safes, run one planner step (its cost measured by the board's counter),
//! and send the command and the telemetry. The work per period is bounded by the table and queue
//! capacities, and nothing waits: a full transmit queue drops the frame and counts it.

use crate::link::{
    CommandRepr, CostUnit, Header, Message, ReplyRepr, TelemetryCounters, TelemetryRepr,
    MAX_COBS_FRAME,
};
use crate::math::Vec2;
use crate::params::Params;
use crate::planner::{Command, Planner};
use crate::route::{Route, RouteConfig};
use crate::types::NavState;
use crate::world::{Obstacle, Origin, World};

use super::drift::{Drift, DriftConfig};
use super::failsafe::{self, FailsafeConfig, FreezeDetector, Situation, SonarWatch};
use super::guard::{self, GuardConfig, Verdict, HEAD_ON_ALONE_M as ALONE_M};
use super::tracks::{paces, TrackConfig, Tracks};
use super::upload::Upload;
use super::{
    BackgroundCounters, Control, NavSample, Sighting, CONTROL_QUEUE, REPLY_QUEUE,
    SIGHTINGS_PER_PERIOD,
};
use crate::link::RxCounters;
use crate::link::{BeliefRepr, BELIEF_ROWS};
use crate::sonar::ping360::Ping360Counters;
use crate::sonar::{EvidenceMap, Near, MAP_SIDE, MAX_WAKES};
use crate::world::MAX_MAP_CELLS;

/// The runtime's own settings (the planner's are [`Params`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RuntimeConfig {
    /// Fail-safes.
    pub failsafe: FailsafeConfig,
    /// Sonar feature association.
    pub tracks: TrackConfig,
    /// Sensed obstacles and agents not seen for this long are dropped, ms.
    pub max_age_ms: u64,
    /// The last-line check of every command against what is believed.
    pub guard: GuardConfig,
    /// Evidence-map cells within this distance of the vehicle enter the planner's world each
    /// period (a polar scan: the nearest in each bearing sector, `EvidenceMap::nearest`), m.
    /// At 6 m seed 000's stator (A⁺ = 2.5) has a gradient of 2A⁺/r³ ≈ 0.02 m/s², a twentieth
    /// of the goal's pull at its default reach; the snapshot's cost grows with its square.
    pub map_reach_m: f32,
    /// A [`BeliefRepr`] chunk of the evidence map goes out every this many periods (0: never);
    /// with 16-row chunks of the 64-row window the whole map takes four chunks.
    pub belief_every: u16,
    /// The route layer (`crate::route`): the background plans, this task follows.
    pub route: RouteConfig,
    /// The current's estimate, taken out of the set-points (`crate::guidance::drift`).
    pub drift: DriftConfig,
}

impl Default for RuntimeConfig {
    fn default() -> Self {
        RuntimeConfig {
            failsafe: FailsafeConfig::default(),
            tracks: TrackConfig::default(),
            max_age_ms: 30_000,
            guard: GuardConfig::default(),
            map_reach_m: 6.0,
            belief_every: 2,
            route: RouteConfig::default(),
            drift: DriftConfig::default(),
        }
    }
}

/// Navigation stamped further than this after the firmware's time is refused, ms: a fix from
/// the future would read as fresh forever and switch the stale-navigation hold off.
pub const MAX_NAV_LEAD_MS: u64 = 1000;

/// A quiet sonar's speed bound below which the vehicle holds instead, m/s.
const QUIET_STOP_MPS: f32 = 0.05;

/// A mover not seen for this long, ms, is not carried on to hide its echoes
/// ([`Periodic::publish_wakes`]): a sweep or three, as far as the tracker extrapolates one.
const WAKE_AGE_MS: u64 = 10_000;

/// Whether obstacle `o`, last seen `age_ms` ago, is a mover whose echoes the evidence map
/// leaves out (`crate::sonar::wakes`): a sensed obstacle with a velocity, seen within
/// [`WAKE_AGE_MS`] — but, for a craft that turns slowly, moving at `own`, not a sonar track
/// that only keeps pace with it against other believed structure ([`paces`], not
/// [`guard::alone`]): that is the nearest stretch of a wall the craft runs along, whose
/// echoes are the wall. With the guard's `Believed::here`, the flat-fish with its recipe,
/// seeds 0–237 at trials 0 and 1: contacts 15 → 10 (the channel and U-trap ones gone, none
/// new), successes 5 015 → 5 015 of 5 712. Not for a VideoRay, which had no such contact: its
/// channels lost 4 of 200 (`hil bench --first-seed 1000 --seeds 200`), stopped at bends that
/// the painted echoes had closed with false cells 1–2 m off the walls of 5 m channels.
fn hides_wake(world: &World, o: &Obstacle, age_ms: u64, own: Option<Vec2>) -> bool {
    let r_map = world.map_radius() * core::f32::consts::SQRT_2;
    o.velocity != Vec2::ZERO
        && o.origin != Origin::Charted
        && age_ms <= WAKE_AGE_MS
        && !(o.origin == Origin::Sonar
            && own.is_some_and(|own| paces(o.velocity, own))
            && !guard::alone(world, o, o.shape.bounding_radius(), ALONE_M, r_map))
}

/// `c` with its speed set-point and planned velocity at most `v` (the planner is then handed
/// the velocity that went out, `Planner::override_velocity`).
fn slowed(mut c: Command, v: f32) -> Command {
    if c.v_set > v {
        let k = v / c.v_set;
        c.v_set = v;
        c.velocity = c.velocity * k;
    }
    c
}

/// What the periodic task reads from the slow side each period: the reading ends of the queues
/// and slots the background writes through [`BackgroundOutputs`](super::BackgroundOutputs).
pub trait PeriodicInputs {
    /// The newest navigation, if any has come.
    fn nav(&mut self) -> Option<NavSample>;
    /// The next queued sighting.
    fn sighting(&mut self) -> Option<Sighting>;
    /// The next queued request.
    fn control(&mut self) -> Option<Control>;
    /// The next reply the background owes (a request refused at the wire, or "busy").
    fn reply(&mut self) -> Option<ReplyRepr>;
    /// The slow side's counters, for telemetry.
    fn link_counters(&mut self) -> (RxCounters, BackgroundCounters);
    /// The newest route the background published, if any (`None` also while it is being
    /// written: the task keeps the one it had).
    fn route(&mut self) -> Option<Route>;
    /// The Ping360 driver's counters, for telemetry (rows 31 ..= 36). Zero where the firmware
    /// drives no Ping360 (the default).
    fn ping360_counters(&mut self) -> Ping360Counters {
        Ping360Counters::default()
    }
}

/// The periodic task's state.
pub struct Periodic {
    planner: Planner,
    world: World,
    tracks: Tracks,
    /// Runtime settings.
    pub config: RuntimeConfig,
    seq: u16,
    last_cost: u32,
    cost_unit: CostUnit,
    last_heading: f32,
    /// The last period's time and command: a repeated `Tick` for the same time (the host sent
    /// it again because the answer was slow or lost) gets the same command again instead of a
    /// second planner step, so lockstep runs do not depend on timing.
    last: Option<(u64, Command)>,
    counters: TelemetryCounters,
    /// Periods whose command the guard changed.
    guard_count: u32,
    freeze: FreezeDetector,
    /// Periods held because navigation had frozen.
    frozen_holds: u32,
    sonar: SonarWatch,
    /// Periods counted for the `Belief` schedule.
    belief_tick: u32,
    /// The newest route read from the background.
    route: Option<Route>,
    /// The newest navigation accepted.
    nav: Option<NavSample>,
    /// Stamp of the last navigation refused for coming from the future, ms.
    refused_nav_ms: Option<u64>,
    /// Navigation samples refused for coming from the future.
    future_navs: u32,
    /// A waypoint upload in progress.
    upload: Upload,
    /// The current believed.
    drift: Drift,
}

impl Periodic {
    /// A runtime around a planner with `params`, costs reported in `cost_unit`.
    pub fn new(
        params: Params,
        config: RuntimeConfig,
        cost_unit: CostUnit,
    ) -> Result<Self, crate::params::ParamError> {
        Ok(Periodic {
            planner: Planner::new(params)?,
            world: World::new(),
            tracks: Tracks::default(),
            config,
            seq: 0,
            last_cost: 0,
            cost_unit,
            last_heading: 0.0,
            last: None,
            counters: TelemetryCounters::default(),
            guard_count: 0,
            freeze: FreezeDetector::default(),
            frozen_holds: 0,
            sonar: SonarWatch::default(),
            belief_tick: 0,
            route: None,
            nav: None,
            refused_nav_ms: None,
            future_navs: 0,
            upload: Upload::default(),
            drift: Drift::default(),
        })
    }

    /// The planner (read-only: requests go through [`Control`]).
    pub fn planner(&self) -> &Planner {
        &self.planner
    }

    /// The goal the planner flies to (the current waypoint) and its generation, for the route
    /// layer in the background (`crate::route::Router::follow`).
    pub fn goal(&self) -> (u32, Option<Vec2>) {
        let goal = self.planner.mission().map(|m| m.goal);
        (self.planner.goal_generation(), goal)
    }

    /// How far along its mission the vehicle is (by the newest navigation accepted).
    pub fn progress(&self) -> Option<crate::planner::MissionProgress> {
        let p = self.nav.map_or(Vec2::ZERO, |n| n.nav.position);
        self.planner.progress(p)
    }

    /// The newest navigation accepted.
    pub fn nav(&self) -> Option<NavSample> {
        self.nav
    }

    /// The newest route read from the background.
    pub fn route(&self) -> Option<&Route> {
        self.route.as_ref()
    }

    /// The world tables.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The sonar tracks behind the table's sonar obstacles.
    pub fn tracks(&self) -> &Tracks {
        &self.tracks
    }

    /// The planner period in ms, for the board's timer.
    pub fn period_ms(&self) -> u32 {
        (self.planner.params().period_s * 1000.0) as u32
    }

    /// Cost of the last planner step, in the board's unit; 0 when the last period held the
    /// vehicle without a step (a failsafe's hold), so a held period is never reported with an
    /// older step's cost.
    pub fn last_cost(&self) -> u32 {
        self.last_cost
    }

    /// The telemetry counters as last sent.
    pub fn counters(&self) -> &TelemetryCounters {
        &self.counters
    }

    /// Opens a waypoint upload of `count` waypoints from another protocol (MAVLink's mission
    /// protocol, `crate::guidance::mavlink`), into the same staging list as `MissionCount`:
    /// the mission in force keeps flying until the upload is complete. The last waypoint is
    /// held. `count` must be 1 ..= `MAX_WAYPOINTS` (the caller checked).
    pub fn open_upload(&mut self, count: u8) {
        let h = Header {
            msg_type: crate::link::MessageType::MissionCount,
            seq: 0,
        };
        let c = crate::link::MissionCountRepr {
            count,
            end: crate::planner::MissionEnd::Hold,
            formation: None,
        };
        let _ = self.upload.open(h, &c);
    }

    /// Stores waypoint `index` of the upload [`Self::open_upload`] opened: `Ok(true)` when it
    /// completed the mission, which is now in force; `Ok(false)` when more are to come;
    /// `Err` (counted as a refused mission) when no upload is open, the index is beyond it, or
    /// the whole list was refused.
    pub fn upload_item(
        &mut self,
        index: u8,
        waypoint: crate::planner::Waypoint,
    ) -> Result<bool, crate::link::Problem> {
        let h = Header {
            msg_type: crate::link::MessageType::MissionItem,
            seq: 0,
        };
        let m = crate::link::MissionItemRepr { index, waypoint };
        let reply = self.upload.item(h, &m, &mut self.planner);
        match reply.status {
            crate::link::ReplyStatus::Accepted => Ok(!self.upload.is_open()),
            crate::link::ReplyStatus::Rejected { problem, .. } => Err(problem),
            crate::link::ReplyStatus::Busy => Err(crate::link::Problem::Invalid),
        }
    }

    /// Counts a missed deadline (the board detects it).
    pub fn count_overrun(&mut self) {
        self.counters.deadline_overruns = self.counters.deadline_overruns.saturating_add(1);
    }

    /// One period at firmware time `now_ms`. `map` is the evidence map the background builds
    /// from the sonar (read only here). `cost` reads the board's monotonic counter (for the
    /// step cost); `tx` queues one whole frame and returns `false` when it does not fit.
    /// Returns the command sent.
    pub fn on_tick(
        &mut self,
        now_ms: u64,
        inputs: &mut impl PeriodicInputs,
        map: Option<&EvidenceMap>,
        cost: &mut impl FnMut() -> u32,
        tx: &mut impl FnMut(&[u8]) -> bool,
    ) -> Command {
        if let Some((t, cmd)) = self.last.filter(|(t, _)| *t == now_ms) {
            // The sightings that came since go into the tables now, as the next period would
            // take them: a repeated Tick (the harness's start-up Tick is one) must not leave
            // two periods' worth in their queue to overflow it.
            self.take_sightings(inputs, self.nav.map_or(Vec2::ZERO, |n| n.nav.position));
            let command = CommandRepr {
                time_ms: t,
                command: cmd,
            };
            self.send(&Message::Command(command), tx);
            return cmd;
        }
        // Bounded by the capacities (the background cannot add while this task runs on the
        // firmware; the bound keeps the period's cost fixed wherever it runs).
        for _ in 0..CONTROL_QUEUE {
            let Some(c) = inputs.control() else { break };
            let reply = self.apply(c);
            self.send(&Message::Reply(reply), tx);
        }
        for _ in 0..REPLY_QUEUE {
            let Some(r) = inputs.reply() else { break };
            self.send(&Message::Reply(r), tx);
        }
        let nav = self.accept_nav(inputs.nav(), now_ms);
        let position = nav.map_or(Vec2::ZERO, |n| n.nav.position);
        self.take_sightings(inputs, position);
        self.world.expire(now_ms, self.config.max_age_ms);
        if let (Some(m), Some(n)) = (map, nav) {
            self.snapshot(m, n.nav.position);
            self.publish_wakes(m, n.nav, now_ms);
        }

        if let Some(r) = inputs.route() {
            self.route = Some(r);
        }
        let aim = match (self.route, self.planner.mission()) {
            (Some(r), Some(m)) if self.planner.params().route_cell_m > 0.0 => {
                r.aim_for(m.goal, now_ms, self.config.route.stale_ms)
            }
            _ => None,
        };
        self.planner.set_route(aim);

        let (_, bg) = inputs.link_counters();
        let cmd = self.plan(
            now_ms,
            nav,
            (bg.scanlines, bg.swept_mrad, bg.head_mrad),
            map,
            cost,
        );
        let cmd = self.make_good(nav, cmd);
        self.last = Some((now_ms, cmd));
        self.last_heading = cmd.psi_set;
        let command = CommandRepr {
            time_ms: now_ms,
            command: cmd,
        };
        self.send(&Message::Command(command), tx);

        let (rx, bg) = inputs.link_counters();
        self.refresh_counters(&rx, &bg);
        let telemetry = TelemetryRepr {
            mission: self.progress().unwrap_or_default(),
            time_ms: now_ms,
            mode: cmd.mode,
            obstacles: self.world.obstacles().len() as u8,
            agents: self.world.agents().len() as u8,
            ghost_depth: cmd.ghost_depth,
            step_cost: self.last_cost,
            cost_unit: self.cost_unit,
            counters: self.counters,
            ping360: inputs.ping360_counters(),
            current: self.drift.estimate(),
        };
        self.send(&Message::Telemetry(telemetry), tx);
        if let Some(m) = map {
            self.send_belief(now_ms, m, tx);
        }
        cmd
    }

    /// This period's view of the evidence map: the nearest believed cell per bearing sector.
    /// Not inlined, nor is [`Self::send_belief`]: their buffers would otherwise stay reserved
    /// in the period's frame under the planner step, where the stack is deepest.
    #[inline(never)]
    fn snapshot(&mut self, m: &EvidenceMap, p: Vec2) {
        let mut near: heapless::Vec<Near, MAX_MAP_CELLS> = heapless::Vec::new();
        let hull = self.planner.params().agent_radius_m;
        m.nearest(p, self.map_reach(m.cell_m()), hull, &mut near);
        // Cells as discs of half their side: neighbours touch, so a wall has no seams.
        self.world
            .set_map(near.iter().map(|c| c.center), 0.5 * m.cell_m());
    }

    /// Hands the map the movers whose echoes leave no wake ([`hides_wake`]), carried to
    /// `now_ms` on their velocity: the [`MAX_WAKES`] nearest the vehicle, nearest first. Not
    /// inlined: its buffer would otherwise sit on top of [`Self::snapshot`]'s.
    #[inline(never)]
    fn publish_wakes(&self, m: &EvidenceMap, nav: NavState, now_ms: u64) {
        let p = nav.position;
        let own = self.planner.params().turns_slowly().then_some(nav.velocity);
        let mut out: [Option<(f32, Vec2, f32)>; MAX_WAKES] = [None; MAX_WAKES];
        for o in self.world.obstacles() {
            let age = now_ms.saturating_sub(o.seen_ms);
            if !hides_wake(&self.world, o, age, own) {
                continue;
            }
            let c = o.shape.center() + o.velocity * (age as f32 * 1e-3);
            let mut entry = Some(((c - p).norm2(), c, o.shape.bounding_radius()));
            // Insertion, nearest first: the farthest falls off the end.
            for slot in out.iter_mut() {
                if slot.is_none_or(|(d, _, _)| entry.is_some_and(|(e, _, _)| e < d)) {
                    core::mem::swap(slot, &mut entry);
                }
            }
        }
        m.wakes()
            .publish(out.iter().flatten().map(|&(_, c, r)| (c, r)));
    }

    /// Every `belief_every` periods, the next chunk of the evidence map (round-robin).
    #[inline(never)]
    fn send_belief(&mut self, now_ms: u64, map: &EvidenceMap, tx: &mut impl FnMut(&[u8]) -> bool) {
        let every = u32::from(self.config.belief_every);
        self.belief_tick = self.belief_tick.wrapping_add(1);
        let Some(w) = map.window() else { return };
        if every == 0 || !self.belief_tick.is_multiple_of(every) {
            return;
        }
        let chunks = (MAP_SIDE / BELIEF_ROWS) as u32;
        let chunk = (self.belief_tick / every) % chunks;
        let first = chunk as i32 * BELIEF_ROWS as i32;
        let mut bytes = [0u8; 8 * BELIEF_ROWS];
        for (r, out) in bytes.chunks_exact_mut(8).enumerate() {
            out.copy_from_slice(&map.row_bits(w, first + r as i32).to_le_bytes());
        }
        let belief = BeliefRepr {
            time_ms: now_ms,
            cell_bits: map.cell_m().to_bits(),
            x0: w.x0,
            y0: w.y0.wrapping_add(first),
            bitmap: &bytes,
        };
        self.send(&Message::Belief(belief), tx);
    }

    /// The newest navigation unless it is stamped more than [`MAX_NAV_LEAD_MS`] after `now_ms`
    /// (a clock that cannot be right: refused once, counted in `bad_nav`); then the last
    /// accepted one, which ages into the stale-navigation hold.
    fn accept_nav(&mut self, newest: Option<NavSample>, now_ms: u64) -> Option<NavSample> {
        if let Some(n) = newest {
            if n.time_ms > now_ms.saturating_add(MAX_NAV_LEAD_MS) {
                if self.refused_nav_ms != Some(n.time_ms) {
                    self.refused_nav_ms = Some(n.time_ms);
                    self.future_navs = self.future_navs.saturating_add(1);
                }
            } else {
                self.nav = Some(n);
            }
        }
        self.nav
    }

    /// `cmd`'s set-points through the water, so that the vehicle makes good over ground what
    /// was planned (`crate::guidance::drift`): the guard's stops and the holds that
    /// [keep station](crate::planner::HoldReason::keeps_station) hold it head to the current.
    /// Other holds keep zero speed and are not handed to the estimate.
    fn make_good(&mut self, nav: Option<NavSample>, cmd: Command) -> Command {
        let idle = matches!(cmd.mode, crate::planner::Mode::Hold(r) if !r.keeps_station());
        let (Some(n), false) = (nav, idle) else {
            return cmd;
        };
        let (cfg, p) = (&self.config.drift, self.planner.params());
        self.drift.update(cfg, &n.nav, p, p.period_s);
        self.drift
            .compensate(cfg, cmd, p, n.nav.heading, p.period_s)
    }

    /// Fail-safes, then the planner.
    fn plan(
        &mut self,
        now_ms: u64,
        nav: Option<NavSample>,
        sonar: (u32, u32, u32),
        map: Option<&EvidenceMap>,
        cost: &mut impl FnMut() -> u32,
    ) -> Command {
        let params = *self.planner.params();
        let (clearance_m, closing) = nav.map_or((f32::INFINITY, true), |n| {
            let (p, r) = (n.nav.position, params.agent_radius_m);
            let now = self.world.clearance(p, r);
            let on = p + n.nav.velocity * failsafe::CLOSING_LOOKAHEAD_S;
            (now, self.world.clearance(on, r) < now)
        });
        let situation = Situation {
            has_mission: self.planner.mission().is_some(),
            nav_age_ms: nav.map(|n| now_ms.saturating_sub(n.time_ms)),
            clearance_m,
            speed: nav.map_or(0.0, |n| n.nav.velocity.norm()),
            f_max: params.f_max,
            closing,
        };
        let commanded = self.last.map_or(0.0, |(_, c)| c.v_set);
        let frozen = nav.is_some_and(|n| self.freeze.update(&n.nav, n.time_ms, commanded));
        self.frozen_holds = self.frozen_holds.saturating_add(u32::from(frozen));
        let quiet = nav.and_then(|n| {
            let (cfg, p) = (&self.config.failsafe, n.nav.position);
            self.sonar.update(cfg, sonar, now_ms, p, params.f_max)
        });
        let spent = quiet.is_some_and(|v| v < QUIET_STOP_MPS);
        let hold = failsafe::check(&self.config.failsafe, &situation)
            .or(frozen.then_some(crate::planner::HoldReason::FrozenNav))
            .or(spent.then_some(crate::planner::HoldReason::SonarBlind));
        let (Some(n), None) = (nav, hold) else {
            self.planner.reset_motion();
            self.last_cost = 0;
            let heading = nav.map_or(self.last_heading, |n| n.nav.heading);
            let reason = hold.unwrap_or(crate::planner::HoldReason::StaleNav);
            let mut c = Command::hold(reason, heading);
            c.clearance_m = situation.clearance_m;
            return c;
        };
        // A late fix (frames lost) is carried forward to now, and slows the vehicle.
        let age = situation.nav_age_ms.unwrap_or(0);
        let period = u64::from(self.period_ms());
        let (state, late) = failsafe::dead_reckon(&self.config.failsafe, &n.nav, age, period);
        // ... and so does a sonar whose pings are lost on the way.
        let bound = [
            quiet,
            late.map(|k| k * params.v_max),
            self.sonar.delivery().map(|d| d * params.v_max),
        ]
        .into_iter()
        .flatten()
        .reduce(crate::math::min);
        let start = cost();
        let result = self.planner.step(now_ms, &state, &self.world);
        self.last_cost = cost().wrapping_sub(start);
        match result {
            Ok(c) => {
                let c = bound.map_or(c, |v| slowed(c, v));
                let (c, verdict) = guard::check(
                    &self.config.guard,
                    &params,
                    now_ms,
                    &state,
                    &self.world,
                    &self.tracks,
                    map,
                    c,
                    bound.unwrap_or(params.v_max),
                );
                if verdict != Verdict::Clear || bound.is_some() {
                    // The planner continues from the motion that was sent, so a vehicle the
                    // guard holds back is seen as stalled and escapes (ghost goal-points).
                    self.planner.override_velocity(c.velocity);
                }
                if verdict != Verdict::Clear {
                    self.guard_count = self.guard_count.saturating_add(1);
                }
                c
            }
            // Refused input (counted by the planner): hold, with the last heading.
            Err(_) => Command::hold(crate::planner::HoldReason::StaleNav, self.last_heading),
        }
    }

    /// How far round the vehicle the evidence map's cells enter the world, m: `map_reach_m`,
    /// or farther when the guard needs it to see a whole stopping distance beyond the hull at
    /// v_max (a large craft that brakes gently: the flat-fish's 2.25 m hull and 5 m from
    /// 1 m/s at 0.1 m/s²). The map's scan stops at `MAX_REACH_CELLS` cells (12 m) either way.
    fn map_reach(&self, cell_m: f32) -> f32 {
        let p = self.planner.params();
        let g = &self.config.guard;
        let stop = p.v_max * p.period_s + p.v_max * p.v_max / (2.0 * p.brake()) + g.margin_m;
        let need = p.agent_radius_m + g.hull_margin_m + stop + cell_m;
        crate::math::max(self.config.map_reach_m, need)
    }

    /// Applies one request and says how it went. Not inlined: a survey's expanded list is on its
    /// stack, which must not stay reserved under the planner step's.
    #[inline(never)]
    fn apply(&mut self, c: Control) -> ReplyRepr {
        let reply = |h: Header, r: Result<(), crate::planner::StepError>| match r {
            Ok(()) => ReplyRepr::accepted(h),
            Err(e) => ReplyRepr::from_step_error(h, e),
        };
        match c {
            Control::Mission(h, m) => reply(h, self.planner.set_mission(m)),
            Control::Params(h, p) => reply(h, self.planner.set_params(p)),
            Control::Chart(h, o) => match self.world.upsert_obstacle(o) {
                Ok(()) => ReplyRepr::accepted(h),
                Err(_) => ReplyRepr::table_full(h),
            },
            Control::ChartClear(h, which) => {
                match which {
                    crate::link::ChartClearRepr::All => self.world.remove_charted(),
                    crate::link::ChartClearRepr::One(id) => {
                        self.world.remove_obstacle(id);
                    }
                }
                ReplyRepr::accepted(h)
            }
            Control::MissionCount(h, m) => self.upload.open(h, &m),
            Control::MissionItem(h, m) => self.upload.item(h, &m, &mut self.planner),
            Control::Survey(h, s) => match crate::planner::Waypoints::survey(&s.survey, s.end) {
                Ok(w) => reply(h, self.planner.set_waypoints(&w, s.formation)),
                // The wire checked that it fits; counted with the planner's refusals anyway.
                Err(e) => {
                    let c = &mut self.planner.counters.bad_mission;
                    *c = c.saturating_add(1);
                    reply(h, Err(crate::planner::StepError::BadMission(e)))
                }
            },
        }
    }

    /// Takes up to [`SIGHTINGS_PER_PERIOD`] queued sightings into the tables.
    fn take_sightings(&mut self, inputs: &mut impl PeriodicInputs, vehicle: Vec2) {
        // A slow-turning craft opens no faint pairs (`crate::guidance::faint`, "Spurious
        // pairs"): taken for still, it is never under way.
        let slow_turning = self.planner.params().turns_slowly();
        let velocity = self.nav.map_or(Vec2::ZERO, |n| n.nav.velocity);
        self.tracks
            .own_velocity(if slow_turning { Vec2::ZERO } else { velocity });
        for _ in 0..SIGHTINGS_PER_PERIOD {
            let Some(s) = inputs.sighting() else { break };
            self.admit(s, vehicle);
        }
    }

    /// Puts a sighting into the tables. Sensed obstacles (sonar features and contacts) get
    /// the planner's A_s⁺ (`Params::a_plus`, seed 002's static repulsion), so tuning it reaches
    /// them; charted obstacles keep their own.
    fn admit(&mut self, s: Sighting, vehicle: Vec2) {
        let a_plus = self.planner.params().a_plus;
        match s {
            // Refusals and evictions are counted by the world table.
            Sighting::Feature(f) => {
                let cfg = self.config.tracks;
                let _ = self
                    .tracks
                    .admit(&cfg, a_plus, &mut self.world, &f, vehicle);
            }
            Sighting::Obstacle(o) => {
                if let Ok(o) = o.with_a_plus(a_plus) {
                    let _ = self.world.upsert_obstacle_or_evict(o, vehicle);
                }
            }
            Sighting::Agent(a) => {
                let _ = self.world.upsert_agent(a);
            }
        }
    }

    fn refresh_counters(&mut self, rx: &RxCounters, bg: &BackgroundCounters) {
        let c = &mut self.counters;
        c.set_rx(rx);
        // One counter per kind of refusal: requests refused at the wire are counted as refused
        // requests of their kind (and answered), not with the unanswered frames; navigation
        // refused at the wire with the navigation the planner refused.
        let wire_requests = bg
            .params_refused
            .saturating_add(bg.mission_refused)
            .saturating_add(bg.nav_refused);
        c.rx_bad_payload = c
            .rx_bad_payload
            .saturating_sub(wire_requests)
            .saturating_add(bg.ticks_refused);
        let p = self.planner.counters;
        c.bad_nav = p
            .bad_nav
            .saturating_add(self.future_navs)
            .saturating_add(bg.nav_refused);
        c.bad_params = p.bad_params.saturating_add(bg.params_refused);
        c.bad_mission = p
            .bad_mission
            .saturating_add(bg.mission_refused)
            .saturating_add(bg.charts_refused);
        c.requests_busy = bg.requests_busy;
        c.requests_unanswered = bg.requests_unanswered;
        c.features_dropped = bg.sightings_dropped;
        c.features_extracted = bg.features_extracted;
        c.table_full = self.world.counters.rejected_full;
        c.table_evicted = self.world.counters.evicted;
        c.guard_interventions = self.guard_count;
        c.frozen_nav_holds = self.frozen_holds;
    }

    /// Counts bytes the board's receive queue dropped.
    pub fn count_rx_dropped(&mut self, n: u32) {
        self.counters.rx_bytes_dropped = self.counters.rx_bytes_dropped.saturating_add(n);
    }

    fn send(&mut self, msg: &Message<'_>, tx: &mut impl FnMut(&[u8]) -> bool) {
        // The firmware sends only frames to the host: COBS, never longer than this.
        let mut buf = [0u8; MAX_COBS_FRAME];
        self.seq = self.seq.wrapping_add(1);
        let sent = match msg.emit_frame_to_host(self.seq, &mut buf) {
            Ok(n) => buf.get(..n).is_some_and(tx),
            Err(_) => false,
        };
        if !sent {
            self.counters.tx_frames_dropped = self.counters.tx_frames_dropped.saturating_add(1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::Shape;

    /// A sonar track of radius 1 m at (0, 5), seen now, moving east at `v` m/s.
    fn track(v: f32) -> Obstacle {
        Obstacle::new(
            0xC000,
            Shape::circle(Vec2::new(0.0, 5.0), 1.0).unwrap(),
            2.5,
            Origin::Sonar,
            0,
        )
        .and_then(|o| o.moving(Vec2::new(v, 0.0)))
        .unwrap()
    }

    #[test]
    fn a_track_keeping_pace_against_a_wall_is_the_wall_and_alone_it_is_a_mover() {
        // A flat-fish runs east at 0.6 m/s along a wall at y = 5.5 (map cells every 0.5 m).
        let own = Some(Vec2::new(0.6, 0.0));
        let mut w = World::new();
        w.set_map((-20..=20).map(|k| Vec2::new(k as f32 * 0.5, 5.5)), 0.25);
        assert!(
            !hides_wake(&w, &track(0.6), 0, own),
            "the wall's fragment is painted"
        );
        assert!(
            hides_wake(&w, &track(1.2), 0, own),
            "faster than the vehicle: a mover"
        );
        assert!(
            hides_wake(&w, &track(0.6), 0, Some(Vec2::ZERO)),
            "the craft at rest"
        );
        assert!(
            hides_wake(&w, &track(0.6), 0, None),
            "a craft that turns at once"
        );
        let open = World::new();
        assert!(
            hides_wake(&open, &track(0.6), 0, own),
            "in open water: a mover"
        );
        assert!(
            !hides_wake(&open, &track(0.6), WAKE_AGE_MS + 1, None),
            "too old"
        );
    }
}
