//! Both halves of the runtime in one context, wired with queues of the same capacities and
//! policies as the firmware's: the host-process firmware and the tests run this.
//!
//! Bytes in with [`SingleContext::on_bytes`]; a period with [`SingleContext::on_tick`] (real
//! time), or by a `Tick` message from the host (lockstep), which runs the period right away.
//! Outgoing frames are appended to a caller-supplied transmit function.

use heapless::Deque;

use crate::link::{CostUnit, ReplyRepr, RxCounters};
use crate::params::Params;
use crate::planner::Command;
use crate::route::{Route, Router};
use crate::sonar::{EvidenceMap, ExtractorConfig};

use super::{
    Background, BackgroundCounters, Control, Inputs, NavSample, Periodic, RuntimeConfig, Sighting,
    Sink, CONTROL_QUEUE, REPLY_QUEUE, SIGHTING_QUEUE,
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
}

impl Sink for Queues {
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

impl Inputs for Queues {
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
}

/// The runtime in one context.
pub struct SingleContext {
    background: Background,
    periodic: Periodic,
    queues: Queues,
    map: EvidenceMap,
    router: Router,
    now_ms: u64,
}

impl SingleContext {
    /// A runtime with planner `params`, runtime `config` and default sonar extraction. Step
    /// costs are reported in `cost_unit` (what `cost` passed to the tick functions counts).
    pub fn new(
        params: Params,
        config: RuntimeConfig,
        cost_unit: CostUnit,
    ) -> Result<Self, crate::params::ParamError> {
        let periodic = Periodic::new(params, config, cost_unit)?;
        let background = Background::new(ExtractorConfig::default(), params.a_plus).ok_or(
            crate::params::ParamError {
                name: "sonar",
                problem: crate::params::ParamProblem::OutOfRange,
            },
        )?;
        Ok(SingleContext {
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
            },
            map: EvidenceMap::empty(),
            router: {
                let mut r = Router::new(config.route);
                r.set_cell(params.route_cell_m);
                r
            },
            now_ms: 0,
        })
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
        self.queues.rx = *self.background.rx_counters();
        self.queues.bg = self.background.counters;
        let cmd = self
            .periodic
            .on_tick(now_ms, &mut self.queues, Some(&self.map), cost, tx);
        self.queues.goal = self.periodic.goal();
        cmd
    }
}
