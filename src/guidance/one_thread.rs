//! Both halves of the runtime in one context, wired with queues of the same capacities and
//! policies as the firmware's: the host-process firmware and the tests run this.
//!
//! Bytes in with [`OneThreadRuntime::on_bytes`]; a period with [`OneThreadRuntime::on_tick`] (real
//! time), or by a `Tick` message from the host (lockstep), which runs the period right away.
//! Outgoing frames are appended to a caller-supplied transmit function.

use heapless::Deque;

use crate::link::{CostUnit, ReplyRepr, RxCounters};
use crate::params::Params;
use crate::planner::Command;
use crate::route::{Route, Router};
use crate::sonar::ping360::{ConfigError, Ping360, Ping360Config, Ping360Counters};

use super::mavlink::{MavConfig, MavInbound, MavMission, MavOutbound};
use crate::sonar::{EvidenceMap, ExtractorConfig};

use super::{
    Background, BackgroundCounters, BackgroundOutputs, Control, NavSample, Periodic,
    PeriodicInputs, RuntimeConfig, Sighting, CONTROL_QUEUE, REPLY_QUEUE, SIGHTING_QUEUE,
};

/// The queues between the halves.
struct Queues {
    nav: Option<NavSample>,
    sightings: Deque<Sighting, SIGHTING_QUEUE>,
    controls: Deque<Control, CONTROL_QUEUE>,
    replies: Deque<ReplyRepr, REPLY_QUEUE>,
    tick: Option<u64>,
    route: Option<Route>,
    /// The periodic task's goal after its last period (`Periodic::goal`).
    goal: (u32, Option<crate::math::Vec2>),
    rx: RxCounters,
    bg: BackgroundCounters,
    ping360: Ping360Counters,
}

impl BackgroundOutputs for Queues {
    fn nav(&mut self, sample: NavSample) {
        self.nav = Some(sample);
    }
    fn sighting(&mut self, s: Sighting) -> bool {
        self.sightings.push_back(s).is_ok()
    }
    fn control(&mut self, c: Control) -> bool {
        self.controls.push_back(c).is_ok()
    }
    fn reply(&mut self, r: ReplyRepr) -> bool {
        self.replies.push_back(r).is_ok()
    }
    fn tick(&mut self, time_ms: u64) {
        self.tick = Some(time_ms);
    }
    fn route(&mut self, r: Route) {
        self.route = Some(r);
    }
    fn goal(&mut self) -> (u32, Option<crate::math::Vec2>) {
        self.goal
    }
}

impl PeriodicInputs for Queues {
    fn nav(&mut self) -> Option<NavSample> {
        self.nav
    }
    fn sighting(&mut self) -> Option<Sighting> {
        self.sightings.pop_front()
    }
    fn control(&mut self) -> Option<Control> {
        self.controls.pop_front()
    }
    fn reply(&mut self) -> Option<ReplyRepr> {
        self.replies.pop_front()
    }
    fn link_counters(&mut self) -> (RxCounters, BackgroundCounters) {
        (self.rx, self.bg)
    }
    fn route(&mut self) -> Option<Route> {
        self.route.take()
    }
    fn ping360_counters(&mut self) -> Ping360Counters {
        self.ping360
    }
}

/// Bytes for the Ping360 waiting to be written: a few `transducer` frames (24 bytes each; one
/// is outstanding at a time, so two never wait). Full: the driver sends again at its next poll.
pub const PING360_OUTBOX: usize = 96;

/// Whether a Ping360 driver may send commands yet: once navigation has come (a ping before it
/// could not be placed) or the host runs the clock (lockstep: from its first `Tick`, whatever
/// the firmware's own clock did before). The board images follow the same rule, so a lockstep
/// run pings the same on both.
pub fn ping360_started(background: &Background) -> bool {
    background.lockstep() || background.pose().is_some()
}

/// Bytes for the MAVLink line waiting to be written: a period's set-point, status, heartbeat,
/// obstacle distances and mission replies (about 400 bytes). Full: frames are dropped, counted.
pub const MAVLINK_OUTBOX: usize = 1024;
/// Mission-upload steps between the halves (as the firmware's queue).
pub const MAVLINK_MISSIONS: usize = 4;

/// The MAVLink line's two halves and the queue between them.
struct Mav {
    inbound: MavInbound,
    outbound: MavOutbound,
    missions: Deque<MavMission, MAVLINK_MISSIONS>,
    out: heapless::Vec<u8, MAVLINK_OUTBOX>,
}

/// The runtime in one context.
pub struct OneThreadRuntime {
    background: Background,
    periodic: Periodic,
    queues: Queues,
    map: EvidenceMap,
    router: Router,
    now_ms: u64,
    ping360: Option<Ping360>,
    ping360_out: heapless::Vec<u8, PING360_OUTBOX>,
    mavlink: Option<Mav>,
}

impl OneThreadRuntime {
    /// A runtime with planner `params`, runtime `config` and default sonar extraction. Step
    /// costs are reported in `cost_unit` (what `cost` passed to the tick functions counts).
    pub fn new(
        params: Params,
        config: RuntimeConfig,
        cost_unit: CostUnit,
    ) -> Result<Self, crate::params::ParamError> {
        let periodic = Periodic::new(params, config, cost_unit)?;
        let background =
            Background::new(ExtractorConfig::default(), params.a_plus).map_err(|_| {
                crate::params::ParamError {
                    name: "sonar",
                    problem: crate::params::ParamProblem::OutOfRange,
                }
            })?;
        Ok(OneThreadRuntime {
            background,
            periodic,
            queues: Queues {
                nav: None,
                sightings: Deque::new(),
                controls: Deque::new(),
                replies: Deque::new(),
                tick: None,
                route: None,
                goal: (0, None),
                rx: RxCounters::default(),
                bg: BackgroundCounters::default(),
                ping360: Ping360Counters::default(),
            },
            map: EvidenceMap::empty(),
            router: {
                let mut r = Router::new(config.route);
                r.set_params(&params);
                r
            },
            now_ms: 0,
            ping360: None,
            ping360_out: heapless::Vec::new(),
            mavlink: None,
        })
    }

    /// Drives a Ping360 on a port of its own with `cfg` ([`Self::on_ping360_bytes`] takes its
    /// bytes, [`Self::take_ping360_output`] gives what to write to it). Its first command goes
    /// out at the first period after navigation has come, or at the first `Tick`
    /// ([`ping360_started`]).
    pub fn set_ping360(&mut self, cfg: Ping360Config) -> Result<(), ConfigError> {
        self.ping360 = Some(Ping360::new(cfg)?);
        Ok(())
    }

    /// The Ping360 driver, if one is set.
    pub fn ping360(&self) -> Option<&Ping360> {
        self.ping360.as_ref()
    }

    /// Feeds bytes received from the Ping360: each ping becomes a scanline for the extractor
    /// and the evidence map, placed with the newest navigation when its data began to arrive.
    /// Ignored without a Ping360 ([`Self::set_ping360`]).
    pub fn on_ping360_bytes(&mut self, bytes: &[u8]) {
        let OneThreadRuntime {
            background,
            queues,
            map,
            now_ms,
            ping360,
            ping360_out,
            router,
            ..
        } = self;
        let Some(driver) = ping360.as_mut() else {
            return;
        };
        let pose = background.pose();
        driver.on_bytes(
            bytes,
            *now_ms,
            pose,
            &mut |f| ping360_out.extend_from_slice(f).is_ok(),
            &mut |scan, pose| background.on_scanline(scan, pose, queues, Some(map), Some(router)),
        );
    }

    /// What is to be written to the Ping360 now (taken: the next call returns only what came
    /// after).
    pub fn take_ping360_output(&mut self) -> heapless::Vec<u8, PING360_OUTBOX> {
        core::mem::take(&mut self.ping360_out)
    }

    /// Speaks MAVLink 2 to an autopilot and a ground station on a line of its own
    /// ([`Self::on_mavlink_bytes`] takes its bytes, [`Self::take_mavlink_output`] gives what to
    /// write; `crate::guidance::mavlink`).
    pub fn set_mavlink(&mut self, cfg: MavConfig) {
        self.mavlink = Some(Mav {
            inbound: MavInbound::new(cfg),
            outbound: MavOutbound::new(cfg),
            missions: Deque::new(),
            out: heapless::Vec::new(),
        });
    }

    /// The MAVLink line's decoder counters, frames dropped on a full outbox, and upload
    /// steps dropped on a full queue, if it is set.
    pub fn mavlink_counters(&self) -> Option<(crate::link::mavlink::MavCounters, u32, u32)> {
        self.mavlink.as_ref().map(|m| {
            (
                *m.inbound.counters(),
                m.outbound.frames_dropped,
                m.inbound.missions_dropped,
            )
        })
    }

    /// Feeds bytes from the MAVLink line (ignored without [`Self::set_mavlink`]).
    pub fn on_mavlink_bytes(&mut self, bytes: &[u8]) {
        let OneThreadRuntime {
            background,
            queues,
            map,
            router,
            now_ms,
            mavlink,
            ..
        } = self;
        let Some(m) = mavlink.as_mut() else { return };
        let missions = &mut m.missions;
        m.inbound.on_bytes(
            bytes,
            *now_ms,
            background,
            queues,
            Some(map),
            Some(router),
            &mut |x| missions.push_back(x).is_ok(),
        );
    }

    /// What is to be written to the MAVLink line now (taken).
    pub fn take_mavlink_output(&mut self) -> heapless::Vec<u8, MAVLINK_OUTBOX> {
        self.mavlink
            .as_mut()
            .map(|m| core::mem::take(&mut m.out))
            .unwrap_or_default()
    }

    /// The periodic half (planner, world, counters).
    pub fn periodic(&self) -> &Periodic {
        &self.periodic
    }

    /// Counts received bytes the host dropped before they reached [`Self::on_bytes`] (its
    /// input queue was full), in telemetry's `rx_bytes_dropped` as on the board.
    pub fn count_rx_dropped(&mut self, n: u32) {
        self.periodic.count_rx_dropped(n);
    }

    /// The route layer.
    pub fn router(&self) -> &Router {
        &self.router
    }

    /// The evidence map the sonar builds.
    pub fn map(&self) -> &EvidenceMap {
        &self.map
    }

    /// Whether the host drives time with `Tick` messages (lockstep).
    pub fn lockstep(&self) -> bool {
        self.background.lockstep()
    }

    /// Firmware time of the last period, ms.
    pub fn now_ms(&self) -> u64 {
        self.now_ms
    }

    /// Feeds received bytes; a `Tick` among them runs a period at once (lockstep). Returns the
    /// commands of the periods that ran.
    pub fn on_bytes(
        &mut self,
        bytes: &[u8],
        cost: &mut impl FnMut() -> u32,
        tx: &mut impl FnMut(&[u8]) -> bool,
    ) -> heapless::Vec<Command, 4> {
        let mut ran = heapless::Vec::new();
        let mut rest = bytes;
        while !rest.is_empty() {
            rest = self.background.on_bytes(
                rest,
                self.now_ms,
                &mut self.queues,
                Some(&self.map),
                Some(&mut self.router),
            );
            if let Some(t) = self.queues.tick.take() {
                // More than 4 ticks in one call: the later commands are still sent, not returned.
                let _ = ran.push(self.on_tick(t, cost, tx));
            }
        }
        ran
    }

    /// Runs one period at firmware time `now_ms`.
    pub fn on_tick(
        &mut self,
        now_ms: u64,
        cost: &mut impl FnMut() -> u32,
        tx: &mut impl FnMut(&[u8]) -> bool,
    ) -> Command {
        self.now_ms = now_ms;
        let started = ping360_started(&self.background);
        if let Some(p) = self.ping360.as_mut().filter(|_| started) {
            let out = &mut self.ping360_out;
            p.poll(now_ms, &mut |f| out.extend_from_slice(f).is_ok());
            self.queues.ping360 = p.counters();
        }
        self.queues.rx = *self.background.rx_counters();
        self.queues.bg = self.background.counters;
        let cmd = self
            .periodic
            .on_tick(now_ms, &mut self.queues, Some(&self.map), cost, tx);
        self.queues.goal = self.periodic.goal();
        if let Some(m) = self.mavlink.as_mut() {
            let (missions, out) = (&mut m.missions, &mut m.out);
            m.outbound.on_period(
                now_ms,
                &cmd,
                &mut self.periodic,
                &mut || missions.pop_front(),
                &mut |f| out.extend_from_slice(f).is_ok(),
            );
        }
        cmd
    }
}
