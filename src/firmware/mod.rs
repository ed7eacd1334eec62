//! The firmware: the guidance runtime's two halves (`vpf::guidance`) on a Cortex-M4F, as an
//! RTIC v2 application ([`app`]). Target-only; the board module supplies the hardware.
//!
//! Contexts, highest priority first (RTIC priorities; the hardware's are the reverse):
//! 1. **UART interrupts** (priority 3, hardware tasks) — O(1) per byte: move bytes between the
//!    UARTs and their SPSC byte queues ([`link`]): the control link's, and the Ping360's
//!    ([`sonar`]). At 115 200 baud that is under 1 %
//!    of the CPU, so they cannot make the periodic task miss its deadline, and no received byte
//!    waits behind a planner step. They share nothing with a lower priority that needs a lock,
//!    so nothing ever masks them.
//! 2. **SysTick, the periodic task** (priority 2, hardware task) — the timer reloads every
//!    planner period (or an exact fraction of it, for periods longer than SysTick's 24 bits
//!    reach), so the schedule is absolute and cannot drift; each period runs
//!    [`vpf::guidance::Periodic::on_tick`] at `periods × T` and queues the frames it sends. A
//!    period still running when the next one is due is a missed deadline, counted. In lockstep
//!    mode (the host sent a `Tick`) the timer runs no periods: each `Tick` does, at the host's
//!    time ([`periodic`]).
//! 3. **Idle, the background** (priority 0, thread mode) — everything slow and preemptible:
//!    frame decoding, the Ping360 driver, sonar feature extraction, the evidence map and the
//!    route layer ([`background`]).
//!
//! What they share: the byte queues and the background→periodic queues (sightings, requests,
//! owed replies; [`queues`]), whose ends are RTIC `#[local]`s of the one task that uses each;
//! five `#[shared]` resources with ceiling locks at the periodic task's priority (newest
//! navigation, link counters, firmware time, the waypoint flown to, lockstep state) and the
//! self-test's statistics;
//! and two lock-free structures written by the background and read by the periodic task (the
//! evidence map and the route slot: sequence-counted atomics, no lock).

pub mod background;
pub mod fault;
pub mod link;
pub mod mavlink;
pub mod periodic;
pub mod queues;
#[cfg(feature = "selftest")]
pub mod selftest;
pub mod sonar;

use core::mem::MaybeUninit;

use vpf::guidance::{Background, BackgroundCounters, Periodic, RuntimeConfig, RX_QUEUE, TX_QUEUE};
use vpf::link::RxCounters;
use vpf::params::Params;
use vpf::route::{RouteConfig, RouteSlot, Router};
use vpf::sonar::ping360::{Ping360, Ping360Config, Ping360Counters};
use vpf::sonar::{EvidenceMap, ExtractorConfig};

use crate::board::active as board;
use crate::board::systick::PeriodTimer;
use background::BackgroundTask;
use link::{Receiver, Transmitter};
use mavlink::{MavLink, MavOut, MavPort, MissionQueue, MAV_RX_SLOTS, MAV_TX_SLOTS};
use periodic::PeriodicTask;
use queues::Queues;
use sonar::{SonarLink, SonarPort, SONAR_RX_SLOTS, SONAR_TX_SLOTS};

/// Slots of the control link's receive queue.
pub const CONTROL_RX_SLOTS: usize = queues::slots(RX_QUEUE);
/// Slots of the control link's transmit queue.
pub const CONTROL_TX_SLOTS: usize = queues::slots(TX_QUEUE);
/// The control link (the host's protocol, `docs/protocol.md`): UART0 on the emulated board,
/// USART2 on the NUCLEO.
pub type ControlLink = link::ByteLink<CONTROL_RX_SLOTS, CONTROL_TX_SLOTS>;
/// The periodic task's end of the control link.
pub type ControlOutbox = link::Outbox<CONTROL_TX_SLOTS>;

/// The decoder's, the background's and the Ping360 driver's counters, as the telemetry reports
/// them.
pub type LinkCounters = (RxCounters, BackgroundCounters, Ping360Counters);

/// The waypoint the periodic task flies to and its generation (`Periodic::goal`), for the
/// background's route layer.
pub type GoalFlown = (u32, Option<vpf::Vec2>);

/// Lockstep state, shared by the background (which decodes `Tick`s) and the periodic task.
#[derive(Clone, Copy, Debug, Default)]
pub struct Lockstep {
    /// A `Tick` has come: the host runs the clock.
    pub active: bool,
    /// The host time of the period asked for and not yet run.
    pub pending: Option<u64>,
}

/// What the periodic task has done, for reports.
#[derive(Clone, Copy, Debug, Default)]
pub struct Stats {
    /// Periods run.
    pub periods: u32,
    /// Largest planner step cost, in the board's unit.
    pub max_cost: u32,
    /// Sum of step costs, for the mean.
    pub sum_cost: u64,
    /// Missed deadlines.
    pub overruns: u32,
    /// Largest cost of a whole period (requests, sightings, evidence-map snapshot, fail-safes,
    /// planner step, guard, frames), in the board's unit.
    pub max_period: u32,
    /// How full the planner's tables were: the least over the periods counted, so that a full
    /// fill says every counted period ran at full tables.
    pub least_fill: Fill,
}

/// How full the planner's tables were in a period (for the self-test's report: the budgets are
/// stated at full tables).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Fill {
    /// Obstacles in the field (those not left to the evidence map).
    pub obstacles: u8,
    /// Other vehicles.
    pub agents: u8,
    /// Evidence-map cells the planner took.
    pub map_cells: u8,
    /// Ghost goal-points stacked.
    pub ghosts: u8,
    /// Sonar contacts no sighting has given a velocity (the guard's head-on and close-quarters
    /// hypotheses: `vpf::guidance::guard`).
    pub contacts: u8,
}

impl Fill {
    /// The fill of `runtime`'s tables now.
    pub fn of(runtime: &vpf::guidance::Periodic) -> Fill {
        let world = runtime.world();
        // One pass over the table, every period.
        let (obstacles, contacts) = world.obstacles().iter().fold((0u8, 0u8), |(n, c), o| {
            let contact = o.origin == vpf::Origin::Sonar && o.velocity == vpf::Vec2::ZERO;
            (
                n.saturating_add(u8::from(!world.left_to_map(o))),
                c.saturating_add(u8::from(contact)),
            )
        });
        Fill {
            obstacles,
            contacts,
            agents: world.agents().len() as u8,
            map_cells: world.map_cells().len() as u8,
            ghosts: runtime.planner().ghosts().len() as u8,
        }
    }

    /// The least of each.
    pub fn least(self, o: Fill) -> Fill {
        Fill {
            obstacles: self.obstacles.min(o.obstacles),
            agents: self.agents.min(o.agents),
            map_cells: self.map_cells.min(o.map_cells),
            ghosts: self.ghosts.min(o.ghosts),
            contacts: self.contacts.min(o.contacts),
        }
    }
}

/// The newest route: written by the background, read by the periodic task (a sequence-counted
/// slot of atomics: `vpf::route::handoff`).
static ROUTE: RouteSlot = RouteSlot::new();

/// The statics the firmware is built in (an RTIC `init` local: `.bss`, never on the stack).
pub struct Memory {
    control: ControlLink,
    sonar: SonarLink,
    mavlink: MavLink,
    missions: MissionQueue,
    queues: Queues,
    runtime: MaybeUninit<Periodic>,
    router: MaybeUninit<Router>,
    /// Written by the background, read by the periodic task (atomic cells and a
    /// sequence-counted window: `vpf::sonar::evidence`), so it needs no lock.
    evidence: MaybeUninit<EvidenceMap>,
}

impl Memory {
    /// Empty.
    pub const fn new() -> Self {
        Memory {
            control: ControlLink::new(),
            sonar: SonarLink::new(),
            mavlink: MavLink::new(),
            missions: MissionQueue::new(),
            queues: Queues::new(),
            runtime: MaybeUninit::uninit(),
            router: MaybeUninit::uninit(),
            evidence: MaybeUninit::uninit(),
        }
    }
}

impl Default for Memory {
    fn default() -> Self {
        Self::new()
    }
}

/// What start-up hands to the contexts: each part to the one task that owns it.
pub struct Started {
    /// The SysTick task's state, its timer running.
    pub periodic: PeriodicTask,
    /// Idle's state.
    pub background: BackgroundTask,
    /// The control link's receive-interrupt end.
    pub receiver: Receiver<CONTROL_RX_SLOTS>,
    /// The control link's transmit-interrupt end.
    pub transmitter: Transmitter<CONTROL_TX_SLOTS>,
    /// The sonar link's receive-interrupt end.
    pub sonar_receiver: Receiver<SONAR_RX_SLOTS>,
    /// The sonar link's transmit-interrupt end.
    pub sonar_transmitter: Transmitter<SONAR_TX_SLOTS>,
    /// The MAVLink link's receive-interrupt end.
    pub mav_receiver: Receiver<MAV_RX_SLOTS>,
    /// The MAVLink link's transmit-interrupt end.
    pub mav_transmitter: Transmitter<MAV_TX_SLOTS>,
}

/// The runtime's settings: the defaults; the self-test scans the evidence map as far as any
/// craft's stopping distance may make it (`MAX_REACH_CELLS`), so the periods it measures carry
/// the largest map snapshot.
fn runtime_config() -> RuntimeConfig {
    let mut c = RuntimeConfig::default();
    if cfg!(feature = "selftest") {
        let cell = vpf::sonar::EvidenceConfig::default().cell_m;
        c.map_reach_m = vpf::sonar::MAX_REACH_CELLS as f32 * cell;
    }
    c
}

/// Builds the runtime with `params` in `memory` and `router`, splits the queues into their
/// ends and starts the period timer. `None` only if the defaults were invalid (they are tested
/// not to be).
pub fn start(
    memory: &'static mut Memory,
    params: Params,
    timer: PeriodTimer,
    watchdog: board::Watchdog,
) -> Option<Started> {
    let runtime = Periodic::new(params, runtime_config(), board::COST_UNIT).ok()?;
    let runtime = memory.runtime.write(runtime);
    // Contacts get the planner's A_s⁺ when the periodic task admits them.
    let background = Background::new(ExtractorConfig::default(), params.a_plus).ok()?;
    let router = memory.router.write(Router::new(RouteConfig::DEFAULT));
    let evidence: &'static EvidenceMap = memory.evidence.write(EvidenceMap::empty());
    router.set_params(&params);
    let ping360 = Ping360::new(Ping360Config::BOARD).ok()?;
    let sonar = memory.sonar.split();
    let mav = memory.mavlink.split();
    let (missions_in, missions_out) = memory.missions.split();
    let mav_cfg = vpf::guidance::mavlink::MavConfig::default();
    let link = memory.control.split();
    let (producers, consumers) = memory.queues.split();
    let mut periodic = PeriodicTask::new(
        (runtime, evidence),
        link.outbox,
        link.dropped,
        consumers,
        timer,
        watchdog,
        MavOut::new(mav_cfg, mav.outbox, missions_out),
    );
    periodic.start();
    Some(Started {
        periodic,
        background: BackgroundTask::new(
            background,
            (router, evidence),
            (link.inbox, link.held),
            producers,
            SonarPort::new(ping360, sonar.inbox, sonar.outbox, sonar.held),
            MavPort::new(mav_cfg, mav.inbox, missions_in, mav.dropped),
        ),
        receiver: link.receiver,
        transmitter: link.transmitter,
        sonar_receiver: sonar.receiver,
        sonar_transmitter: sonar.transmitter,
        mav_receiver: mav.receiver,
        mav_transmitter: mav.transmitter,
    })
}
