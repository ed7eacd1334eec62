//! The background (RTIC's idle, thread mode): decodes received bytes, extracts sonar features,
//! builds the evidence map and the route, and passes navigation, sightings and requests to the
//! periodic task. Everything slow and preemptible is here.

use heapless::spsc::Consumer;
use rtic::Mutex;
use vpf::guidance::{Background, BackgroundOutputs, Control, NavSample, Sighting};
use vpf::link::ReplyRepr;
use vpf::route::{Route, Router};
use vpf::sonar::EvidenceMap;

use super::mavlink::MavPort;
use super::queues::Producers;
use super::sonar::SonarPort;
use super::{GoalFlown, LinkCounters, Lockstep, Stats, CONTROL_RX_SLOTS, ROUTE};

/// What the background shares with the periodic task: RTIC's shared resources seen from idle,
/// each access one short lock at the periodic task's priority (the UART's is above it, so no
/// lock here ever masks the UART).
pub trait Exchange {
    /// Publishes the newest navigation.
    fn publish_nav(&mut self, sample: NavSample);
    /// Publishes the link's counters, for telemetry.
    fn publish_counters(&mut self, counters: LinkCounters);
    /// Firmware time now, ms.
    fn now_ms(&mut self) -> u64;
    /// The waypoint the periodic task flies to, and its generation.
    fn goal(&mut self) -> GoalFlown;
    /// Lockstep: asks for a period at the host's time `time_ms`.
    fn request_period(&mut self, time_ms: u64);
    /// The host time of the requested period that has not run yet, if any.
    fn period_pending(&mut self) -> Option<u64>;
    /// What the periodic task has done so far.
    #[cfg(feature = "selftest")]
    fn stats(&mut self) -> Stats;
    /// The statistics so far, which then start again from zero (for reports per phase).
    #[cfg(feature = "selftest")]
    fn take_stats(&mut self) -> Stats;
}

/// Idle's view of the shared resources: RTIC's lock proxies, one per resource.
pub struct IdleShared<Nav, Counters, Now, Goal, Step, Report> {
    /// The newest navigation.
    pub nav: Nav,
    /// The link's counters.
    pub link_counters: Counters,
    /// Firmware time.
    pub now_ms: Now,
    /// The waypoint flown to.
    pub goal: Goal,
    /// Lockstep state.
    pub lockstep: Step,
    /// The periodic task's statistics (read by the self-test).
    #[cfg_attr(not(feature = "selftest"), allow(dead_code))]
    pub stats: Report,
}

impl<Nav, Counters, Now, Goal, Step, Report> Exchange
    for IdleShared<Nav, Counters, Now, Goal, Step, Report>
where
    Nav: Mutex<T = Option<NavSample>>,
    Counters: Mutex<T = LinkCounters>,
    Now: Mutex<T = u64>,
    Goal: Mutex<T = GoalFlown>,
    Step: Mutex<T = Lockstep>,
    Report: Mutex<T = Stats>,
{
    fn publish_nav(&mut self, sample: NavSample) {
        self.nav.lock(|n| *n = Some(sample));
    }
    fn publish_counters(&mut self, counters: LinkCounters) {
        self.link_counters.lock(|c| *c = counters);
    }
    fn now_ms(&mut self) -> u64 {
        self.now_ms.lock(|t| *t)
    }
    fn goal(&mut self) -> GoalFlown {
        self.goal.lock(|g| *g)
    }
    fn request_period(&mut self, time_ms: u64) {
        self.lockstep.lock(|l| {
            l.active = true;
            l.pending = Some(time_ms);
        });
    }
    fn period_pending(&mut self) -> Option<u64> {
        self.lockstep.lock(|l| l.pending)
    }
    #[cfg(feature = "selftest")]
    fn stats(&mut self) -> Stats {
        self.stats.lock(|s| *s)
    }
    #[cfg(feature = "selftest")]
    fn take_stats(&mut self) -> Stats {
        self.stats.lock(core::mem::take)
    }
}

/// Idle's body: polls for received bytes and sleeps until the next interrupt when there are
/// none (the self-test and stack-check images run their own test instead).
pub fn run(task: &mut BackgroundTask, shared: &mut impl Exchange) -> ! {
    if cfg!(feature = "stackcheck") {
        super::fault::overflow_the_stack();
    }
    #[cfg(feature = "selftest")]
    super::selftest::run(task, shared, vpf::params::Params::default());
    #[cfg(not(feature = "selftest"))]
    loop {
        let control = task.poll(shared);
        let sonar = task.poll_sonar(shared);
        let mavlink = task.poll_mavlink(shared);
        if !control && !sonar && !mavlink {
            // Interrupts off from the last look to the sleep: one that came between the polls
            // and WFI would otherwise run first and leave the background asleep until the next
            // one, which in lockstep (the host waiting on this firmware) never comes. WFI wakes
            // on a pending interrupt even while they are masked.
            cortex_m::interrupt::free(|_| {
                if task.nothing_received() {
                    cortex_m::asm::wfi();
                }
            });
        }
    }
}

/// The background's own state (an RTIC `#[local]` of idle).
pub struct BackgroundTask {
    background: Background,
    router: &'static mut Router,
    /// The evidence map it writes (the periodic task reads it).
    evidence: &'static EvidenceMap,
    inbox: Consumer<'static, u8, CONTROL_RX_SLOTS>,
    /// The control link's receive task held a byte back (its queue was full).
    held: &'static core::sync::atomic::AtomicBool,
    queues: Producers,
    sonar: SonarPort,
    mav: MavPort,
}

/// The background's [`BackgroundOutputs`]: its queue ends and the shared resources.
struct Outlet<'a, X: Exchange> {
    queues: &'a mut Producers,
    exchange: &'a mut X,
}

impl<X: Exchange> BackgroundOutputs for Outlet<'_, X> {
    fn nav(&mut self, sample: NavSample) {
        self.exchange.publish_nav(sample);
    }
    fn sighting(&mut self, s: Sighting) -> bool {
        self.queues.sightings.enqueue(s).is_ok()
    }
    fn control(&mut self, c: Control) -> bool {
        self.queues.controls.enqueue(c).is_ok()
    }
    fn reply(&mut self, r: ReplyRepr) -> bool {
        self.queues.replies.enqueue(r).is_ok()
    }
    fn tick(&mut self, time_ms: u64) {
        self.exchange.request_period(time_ms);
    }
    fn route(&mut self, r: Route) {
        ROUTE.publish(&r);
    }
    fn goal(&mut self) -> (u32, Option<vpf::Vec2>) {
        self.exchange.goal()
    }
}

impl BackgroundTask {
    /// The background's state around its queue ends.
    pub fn new(
        background: Background,
        (router, evidence): (&'static mut Router, &'static EvidenceMap),
        (inbox, held): (
            Consumer<'static, u8, CONTROL_RX_SLOTS>,
            &'static core::sync::atomic::AtomicBool,
        ),
        queues: Producers,
        sonar: SonarPort,
        mav: MavPort,
    ) -> Self {
        BackgroundTask {
            background,
            router,
            evidence,
            inbox,
            held,
            queues,
            sonar,
            mav,
        }
    }

    /// No byte waits in any receive queue (the control link's, the Ping360's, MAVLink's).
    #[cfg_attr(feature = "selftest", allow(dead_code))]
    fn nothing_received(&self) -> bool {
        !self.inbox.ready() && !self.sonar.inbox.ready() && !self.mav.received()
    }

    /// Decodes what has been received; `true` if there was anything.
    pub fn poll(&mut self, exchange: &mut impl Exchange) -> bool {
        let mut buf = [0u8; 64];
        let mut n = 0;
        for slot in buf.iter_mut() {
            match self.inbox.dequeue() {
                Some(b) => {
                    *slot = b;
                    n += 1;
                }
                None => break,
            }
        }
        if n > 0 && super::link::take_held(self.held) {
            crate::board::active::resume_control_rx();
        }
        let Some(mut rest) = buf.get(..n) else {
            return false;
        };
        if n > 0 {
            crate::board::active::received_bytes_taken();
        }
        while !rest.is_empty() {
            let now = exchange.now_ms();
            rest = self.background.on_bytes(
                rest,
                now,
                &mut Outlet {
                    queues: &mut self.queues,
                    exchange: &mut *exchange,
                },
                Some(self.evidence),
                Some(self.router),
            );
            if let Some(time_ms) = exchange.period_pending() {
                // The sonar's side first: what it sent so far, then its poll at the period's
                // time, so that this period's telemetry counts the command it sends.
                while self.sonar_bytes(exchange) {}
                self.sonar.poll(time_ms);
                self.publish_counters(exchange);
                // Run the requested period now, before later bytes are decoded: SysTick
                // preempts at once.
                cortex_m::peripheral::SCB::set_pendst();
                while exchange.period_pending().is_some() {
                    cortex_m::asm::nop();
                }
            }
        }
        self.publish_counters(exchange);
        n > 0
    }

    /// The decoder's, the background's and the sonar driver's counters, for telemetry.
    fn publish_counters(&mut self, exchange: &mut impl Exchange) {
        exchange.publish_counters((
            *self.background.rx_counters(),
            self.background.counters,
            self.sonar.counters(),
        ));
    }

    /// The Ping360's side: what it sent, and in real time the driver's poll once per period;
    /// `true` if there were bytes.
    #[cfg_attr(feature = "selftest", allow(dead_code))]
    pub fn poll_sonar(&mut self, exchange: &mut impl Exchange) -> bool {
        let busy = self.sonar_bytes(exchange);
        if !self.background.lockstep()
            && vpf::guidance::one_thread::ping360_started(&self.background)
        {
            let now = exchange.now_ms();
            self.sonar.poll(now);
        }
        self.publish_counters(exchange);
        busy
    }

    /// The MAVLink line: up to 64 received bytes (navigation, mission uploads); `true` if
    /// there were any.
    #[cfg_attr(feature = "selftest", allow(dead_code))]
    pub fn poll_mavlink(&mut self, exchange: &mut impl Exchange) -> bool {
        let mut buf = [0u8; 64];
        let n = self.mav.take(&mut buf);
        let Some(bytes) = buf.get(..n).filter(|b| !b.is_empty()) else {
            return false;
        };
        self.feed_mavlink(bytes, exchange);
        true
    }

    /// Feeds up to 64 bytes from the sonar to its driver; `true` if there were any.
    fn sonar_bytes(&mut self, exchange: &mut impl Exchange) -> bool {
        let mut buf = [0u8; 64];
        let n = self.sonar.take(&mut buf);
        let Some(bytes) = buf.get(..n).filter(|b| !b.is_empty()) else {
            return false;
        };
        self.feed_ping360(bytes, exchange);
        true
    }

    /// The Ping360 driver's counters (for the self-test).
    #[cfg(feature = "selftest")]
    pub fn ping360_counters(&self) -> vpf::sonar::ping360::Ping360Counters {
        self.sonar.counters()
    }

    /// Bytes from the sonar into its driver: each ping into the extractor and the evidence
    /// map, placed with the pose the background had when its data began to come; commands out.
    pub fn feed_ping360(&mut self, bytes: &[u8], exchange: &mut impl Exchange) {
        let now = exchange.now_ms();
        let pose = self.background.pose();
        let BackgroundTask {
            background,
            queues,
            sonar,
            router,
            ..
        } = self;
        let outbox = &mut sonar.outbox;
        let mut outlet = Outlet {
            queues,
            exchange: &mut *exchange,
        };
        sonar.driver.on_bytes(
            bytes,
            now,
            pose,
            &mut |f| outbox.send(f),
            &mut |scan, pose| {
                background.on_scanline(
                    scan,
                    pose,
                    &mut outlet,
                    Some(self.evidence),
                    Some(&mut **router),
                )
            },
        );
        crate::board::active::kick_sonar_tx();
    }

    /// The MAVLink line's decoder counters (for the self-test).
    #[cfg(feature = "selftest")]
    pub fn mavlink_counters(&self) -> vpf::link::mavlink::MavCounters {
        self.mav.counters().0
    }

    /// Feeds MAVLink bytes, as received on its UART (the self-test feeds its own).
    pub fn feed_mavlink(&mut self, bytes: &[u8], exchange: &mut impl Exchange) {
        let now = exchange.now_ms();
        let BackgroundTask {
            background,
            router,
            queues,
            mav,
            ..
        } = self;
        let mut outlet = Outlet {
            queues,
            exchange: &mut *exchange,
        };
        mav.feed(
            bytes,
            now,
            background,
            &mut outlet,
            Some(self.evidence),
            Some(&mut **router),
        );
    }

    /// Queues a sighting as the background would (for the self-test); false when the queue is
    /// full (the sighting is not queued).
    #[cfg(feature = "selftest")]
    pub fn push_sighting(&mut self, s: Sighting) -> bool {
        self.queues.sightings.enqueue(s).is_ok()
    }

    /// Decodes `bytes` as if received (for the self-test).
    #[cfg(feature = "selftest")]
    pub fn feed(&mut self, bytes: &[u8], exchange: &mut impl Exchange) {
        let now = exchange.now_ms();
        let mut rest = bytes;
        while !rest.is_empty() {
            rest = self.background.on_bytes(
                rest,
                now,
                &mut Outlet {
                    queues: &mut self.queues,
                    exchange: &mut *exchange,
                },
                Some(self.evidence),
                Some(self.router),
            );
        }
    }
}
