//! The periodic task (SysTick): runs [`Periodic::on_tick`] every period at `n × T`, or at the
//! host's time for each `Tick` in lockstep, and reports what it cost.

use core::sync::atomic::Ordering;

use vpf::guidance::{Control, NavSample, Periodic, PeriodicInputs, Sighting};
use vpf::link::ReplyRepr;
use vpf::route::Route;
use vpf::sonar::EvidenceMap;

use super::mavlink::MavOut;
use super::queues::Consumers;
use super::{ControlOutbox, GoalFlown, LinkCounters, Lockstep, Stats, ROUTE};
use crate::board::active as board;
use crate::board::systick::PeriodTimer;

/// The periodic task's own state (an RTIC `#[local]`).
pub struct PeriodicTask {
    /// The runtime's hard-real-time half (built in place in its own static: it is the one big
    /// object).
    pub runtime: &'static mut Periodic,
    /// The evidence map the background writes.
    evidence: &'static EvidenceMap,
    /// Frames out, to the control link's transmit interrupt.
    pub outbox: ControlOutbox,
    /// The control link's count of received bytes dropped on a full queue.
    pub rx_dropped: &'static core::sync::atomic::AtomicU32,
    /// Sightings, requests and owed replies from the background.
    pub queues: Consumers,
    /// SysTick, programmed for the planner period.
    pub timer: PeriodTimer,
    /// Fed every period.
    pub watchdog: board::Watchdog,
    /// The MAVLink line's sending half.
    pub mav: MavOut,
    /// SysTick interrupts per period, and how many have passed in this one.
    ticks_per_period: u32,
    tick: u32,
    /// The period the timer is programmed for, ms.
    timer_period_ms: u32,
    /// Firmware time, ms: the sum of the periods run (real-time mode).
    time_ms: u64,
    /// Whether the timer has been stopped for lockstep.
    lockstep: bool,
}

/// What the periodic task shares with the background, locked for the period (SysTick runs at
/// the resources' ceiling, so the locks cost nothing and mask nothing).
pub struct PeriodShared<'a> {
    /// The newest navigation (written by the background).
    pub nav: &'a Option<NavSample>,
    /// The background's counters, for telemetry.
    pub link_counters: &'a LinkCounters,
    /// Firmware time, for the background's time stamps.
    pub now_ms: &'a mut u64,
    /// The waypoint flown to, for the background's route layer.
    pub goal: &'a mut GoalFlown,
    /// Lockstep: whether the host runs the clock, and the `Tick` waiting to run.
    pub lockstep: &'a mut Lockstep,
    /// What the periodic task has done, for reports.
    pub stats: &'a mut Stats,
}

struct Inlet<'a> {
    queues: &'a mut Consumers,
    nav: Option<NavSample>,
    link_counters: LinkCounters,
}

impl PeriodicInputs for Inlet<'_> {
    fn nav(&mut self) -> Option<NavSample> {
        self.nav
    }
    fn sighting(&mut self) -> Option<Sighting> {
        self.queues.sightings.dequeue()
    }
    fn control(&mut self) -> Option<Control> {
        self.queues.controls.dequeue()
    }
    fn reply(&mut self) -> Option<ReplyRepr> {
        self.queues.replies.dequeue()
    }
    fn link_counters(&mut self) -> (vpf::link::RxCounters, vpf::guidance::BackgroundCounters) {
        (self.link_counters.0, self.link_counters.1)
    }
    fn ping360_counters(&mut self) -> vpf::sonar::ping360::Ping360Counters {
        self.link_counters.2
    }
    fn route(&mut self) -> Option<Route> {
        ROUTE.latest()
    }
}

impl PeriodicTask {
    /// The task's state; the timer is not running yet ([`PeriodicTask::start`]).
    pub fn new(
        (runtime, evidence): (&'static mut Periodic, &'static EvidenceMap),
        outbox: ControlOutbox,
        rx_dropped: &'static core::sync::atomic::AtomicU32,
        queues: Consumers,
        timer: PeriodTimer,
        watchdog: board::Watchdog,
        mav: MavOut,
    ) -> Self {
        PeriodicTask {
            runtime,
            evidence,
            outbox,
            rx_dropped,
            queues,
            timer,
            watchdog,
            mav,
            ticks_per_period: 1,
            tick: 0,
            timer_period_ms: 0,
            time_ms: 0,
            lockstep: false,
        }
    }

    /// Starts the timer at the planner's period (start-up, before interrupts are enabled).
    pub fn start(&mut self) {
        let period = self.runtime.period_ms();
        self.start_timer(period);
    }

    /// Programs the timer for `period_ms` and resets the period phase.
    fn start_timer(&mut self, period_ms: u32) {
        self.ticks_per_period = self.timer.start(period_ms);
        self.timer_period_ms = period_ms;
        self.tick = 0;
    }

    /// The SysTick body: runs a period when one is due (or when the host's `Tick` asked for it
    /// in lockstep).
    pub fn on_interrupt(&mut self, shared: PeriodShared<'_>) {
        let lockstep = shared.lockstep.active;
        let now = if lockstep {
            match shared.lockstep.pending.take() {
                Some(t) => t,
                None => return,
            }
        } else {
            self.tick = self.tick.saturating_add(1);
            if self.tick < self.ticks_per_period {
                return;
            }
            self.tick = 0;
            self.time_ms = self.time_ms.saturating_add(u64::from(self.timer_period_ms));
            self.time_ms
        };
        if lockstep && !self.lockstep {
            // From the first `Tick` on, the host runs the clock.
            self.lockstep = true;
            self.timer.enter_lockstep();
            self.watchdog.enter_lockstep();
        }
        if lockstep {
            // The cost counter runs while the period runs (`PeriodTimer::count`).
            self.timer.count(true);
        }
        *shared.now_ms = now;
        let dropped = self.rx_dropped.swap(0, Ordering::Relaxed);
        self.runtime.count_rx_dropped(dropped);

        let mut inputs = Inlet {
            queues: &mut self.queues,
            nav: *shared.nav,
            link_counters: *shared.link_counters,
        };
        let outbox = &mut self.outbox;
        // Whole frames only: a frame that does not fit is dropped (and counted by the runtime).
        let mut send = |frame: &[u8]| outbox.send(frame);
        let period_start = board::cost_now();
        let cmd = self.runtime.on_tick(
            now,
            &mut inputs,
            Some(self.evidence),
            &mut board::cost_now,
            &mut send,
        );
        self.mav.on_period(now, &cmd, self.runtime);
        let period_cost = board::cost_now().wrapping_sub(period_start);
        *shared.goal = self.runtime.goal();
        if lockstep {
            self.timer.count(false);
        }
        board::kick_tx();
        self.watchdog.feed();

        let cost = self.runtime.last_cost();
        // The next timer interrupt already came while this period ran: a missed deadline.
        let overrun = !lockstep && self.timer.overran();
        if overrun {
            self.runtime.count_overrun();
        }
        let st = shared.stats;
        st.periods = st.periods.saturating_add(1);
        st.max_cost = st.max_cost.max(cost);
        st.sum_cost = st.sum_cost.saturating_add(u64::from(cost));
        st.overruns = st.overruns.saturating_add(u32::from(overrun));
        st.max_period = st.max_period.max(period_cost);
        let fill = super::Fill::of(self.runtime);
        st.least_fill = if st.periods == 1 {
            fill
        } else {
            st.least_fill.least(fill)
        };
        // A new period from the parameters: reprogram the timer (absolute from here on).
        let period = self.runtime.period_ms();
        if !lockstep && period != self.timer_period_ms {
            self.start_timer(period);
        }
    }
}
