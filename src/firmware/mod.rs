//! The firmware: the guidance runtime's two halves (`vpf::guidance`) on a Cortex-M4F, wired
//! with lock-free queues. Target-only; the board module supplies the hardware.
//!
//! Contexts, highest priority first:
//! 1. **UART receive and transmit interrupts** — O(1) per byte: move one byte between the UART
//!    and a lock-free SPSC byte queue. At 115 200 baud that is under 1 % of the CPU, so they
//!    cannot make the periodic task miss its deadline, and no received byte waits behind a
//!    planner step.
//! 2. **SysTick, the periodic task** — the hardware timer reloads every planner period (or an
//!    exact fraction of it, for periods longer than SysTick's 24 bits reach), so the schedule is
//!    absolute and cannot drift; each period runs [`Periodic::on_tick`] at `periods × T` and
//!    queues the frames it sends. A period still running when the next one is due is a missed
//!    deadline, counted. In lockstep mode (the host sent a `Tick`) the timer runs no periods:
//!    each `Tick` does, at the host's time.
//! 3. **Thread mode, the background** — everything slow and preemptible: frame decoding, sonar
//!    feature extraction ([`Background`]); it publishes the newest navigation in a
//!    critical-section cell and queues sightings and requests.
//!
//! Shared state is only: five SPSC queues (bytes in, bytes out, sightings, requests, owed
//! replies), and five small cells behind `critical_section` (newest navigation, link counters,
//! firmware time, lockstep tick, the goal flown to). A critical section never spans more than a copy of one of those cells.

#[cfg(feature = "selftest")]
pub mod selftest;

use core::cell::{Cell, RefCell};
use core::sync::atomic::{AtomicU32, Ordering};

use critical_section::Mutex;
use heapless::spsc::{Consumer, Producer, Queue};
use vpf::guidance::{
    Background, BackgroundCounters, Control, Inputs, NavSample, Periodic, RuntimeConfig, Sighting,
    Sink, CONTROL_QUEUE, REPLY_QUEUE, RX_QUEUE, SIGHTING_QUEUE, TX_QUEUE,
};
use vpf::link::{ReplyRepr, RxCounters};
use vpf::params::Params;
use vpf::route::{Route, RouteConfig, RouteSlot, Router};
use vpf::sonar::{EvidenceMap, ExtractorConfig};

use crate::board::active as board;

type Slot<T> = Mutex<RefCell<Option<T>>>;

// The queues. heapless 0.8's SPSC ends carry the capacity as a const parameter, so the index
// arithmetic has no runtime divisor (0.9's erased view keeps a division-by-zero panic path the
// link check rejects). A queue of N slots holds N − 1 items.
const RXN: usize = RX_QUEUE + 1;
const TXN: usize = TX_QUEUE + 1;
const SIGHTN: usize = SIGHTING_QUEUE + 1;
const CTRLN: usize = CONTROL_QUEUE + 1;
const REPLYN: usize = REPLY_QUEUE + 1;
static mut RX_Q: Queue<u8, RXN> = Queue::new();
static mut TX_Q: Queue<u8, TXN> = Queue::new();
static mut SIGHT_Q: Queue<Sighting, SIGHTN> = Queue::new();
static mut CTRL_Q: Queue<Control, CTRLN> = Queue::new();
static mut REPLY_Q: Queue<ReplyRepr, REPLYN> = Queue::new();
static SPLIT: core::sync::atomic::AtomicBool = core::sync::atomic::AtomicBool::new(false);

// The ends that interrupt handlers take once.
static RX_PRODUCER: Slot<Producer<'static, u8, RXN>> = Mutex::new(RefCell::new(None));
static TX_CONSUMER: Slot<Consumer<'static, u8, TXN>> = Mutex::new(RefCell::new(None));

static NAV: Mutex<Cell<Option<NavSample>>> = Mutex::new(Cell::new(None));
static LINK: Mutex<Cell<(RxCounters, BackgroundCounters)>> = Mutex::new(Cell::new((
    RxCounters {
        frames: 0,
        crc: 0,
        oversize: 0,
        framing: 0,
        version: 0,
        unknown_type: 0,
        bad_payload: 0,
    },
    BackgroundCounters {
        sightings_dropped: 0,
        requests_busy: 0,
        requests_unanswered: 0,
        params_refused: 0,
        mission_refused: 0,
        nav_refused: 0,
        charts_refused: 0,
        scanlines_rejected: 0,
        scanlines: 0,
        swept_mrad: 0,
        head_mrad: 0,
        features_extracted: 0,
        contacts_rejected: 0,
        ticks_refused: 0,
    },
)));
static NOW_MS: Mutex<Cell<u64>> = Mutex::new(Cell::new(0));
/// The goal the periodic task flies to and its generation, for the route layer (`Sink::goal`).
static GOAL: Mutex<Cell<(u32, Option<vpf::Vec2>)>> = Mutex::new(Cell::new((0, None)));
/// Lockstep: `(active, pending tick time)`.
static LOCKSTEP: Mutex<Cell<(bool, Option<u64>)>> = Mutex::new(Cell::new((false, None)));
static RX_DROPPED: AtomicU32 = AtomicU32::new(0);
/// The evidence map: written by the background, read by the periodic task (atomic cells and a
/// sequence-counted window: `crate::sonar::evidence`), so it needs no lock and no `unsafe`.
static EVIDENCE: EvidenceMap = EvidenceMap::empty();
/// The newest route: written by the background, read by the periodic task (a sequence-counted
/// slot of atomics: `vpf::route::handoff`).
static ROUTE: RouteSlot = RouteSlot::new();

/// The periodic task's state, handed to SysTick once.
pub struct PeriodicCtx {
    /// The runtime's hard-real-time half (in its own static: it is the one big object, and
    /// building it in place keeps start-up's stack small).
    pub periodic: &'static mut Periodic,
    tx: Producer<'static, u8, TXN>,
    sightings: Consumer<'static, Sighting, SIGHTN>,
    controls: Consumer<'static, Control, CTRLN>,
    replies: Consumer<'static, ReplyRepr, REPLYN>,
    /// SysTick interrupts per period, and how many have passed in this one.
    ticks_per_period: u32,
    tick: u32,
    /// The period the timer is programmed for, ms.
    timer_period_ms: u32,
    /// Firmware time, ms: the sum of the periods run (real-time mode).
    time_ms: u64,
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
    /// Evidence-map cells the planner took in the last period.
    pub map_cells: u32,
}

static STATS: Mutex<Cell<Stats>> = Mutex::new(Cell::new(Stats {
    periods: 0,
    max_cost: 0,
    sum_cost: 0,
    overruns: 0,
    max_period: 0,
    map_cells: 0,
}));

static RUNTIME: Owned<Periodic> = Owned::new();
/// The route layer, the background's: built at compile time (in `.data`), so its 2.5 KiB never
/// pass through the stack.
static ROUTER: Owned<Router> = Owned::ready(Router::new(RouteConfig::DEFAULT));
static PERIODIC: Owned<PeriodicCtx> = Owned::new();

fn take<T>(slot: &Slot<T>) -> Option<T> {
    critical_section::with(|cs| slot.borrow(cs).try_borrow_mut().ok()?.take())
}

/// A value owned by one interrupt context after start-up: written once by `main` before that
/// interrupt is enabled, then used only by it. No copy, no lock, no borrow flag (a `RefCell`
/// would put a panicking path and a second copy of the state in the image).
pub struct Owned<T> {
    ready: core::sync::atomic::AtomicBool,
    value: core::cell::UnsafeCell<core::mem::MaybeUninit<T>>,
}

// SAFETY: access is confined to one context by the contract of `init` and `get`.
unsafe impl<T: Send> Sync for Owned<T> {}

impl<T> Owned<T> {
    /// Empty (in `.bss`: no flash copy of an initial value).
    pub const fn new() -> Self {
        Owned {
            ready: core::sync::atomic::AtomicBool::new(false),
            value: core::cell::UnsafeCell::new(core::mem::MaybeUninit::uninit()),
        }
    }

    /// Holding `v` from the start (for values a `const fn` can build).
    pub const fn ready(v: T) -> Self {
        Owned {
            ready: core::sync::atomic::AtomicBool::new(true),
            value: core::cell::UnsafeCell::new(core::mem::MaybeUninit::new(v)),
        }
    }

    /// Stores the value; `false` if it was already stored.
    ///
    /// # Safety
    /// Call before the owning interrupt can run (it must not observe a half-written value).
    pub unsafe fn init(&self, v: T) -> bool {
        if self.ready.load(Ordering::Acquire) {
            return false;
        }
        (*self.value.get()).write(v);
        self.ready.store(true, Ordering::Release);
        true
    }

    /// The value, if stored.
    ///
    /// # Safety
    /// Only the owning context may call this, and it must not hold two results at once.
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn get(&self) -> Option<&mut T> {
        if self.ready.load(Ordering::Acquire) {
            Some((*self.value.get()).assume_init_mut())
        } else {
            None
        }
    }
}

/// Builds the runtime and hands its parts to their contexts; returns the background's state
/// for the idle loop. `None` only if the defaults were invalid (they are tested not to be).
///
/// Not inlined: building the periodic state moves a few kilobytes through temporaries, and
/// that stack must be released before `main` goes on to run the idle loop for ever.
#[inline(never)]
pub fn init(params: Params) -> Option<Idle> {
    if SPLIT.swap(true, Ordering::AcqRel) {
        return None;
    }
    // SAFETY: the queues are split exactly once (guarded above), before any interrupt that
    // uses them is enabled; afterwards each end lives in one context only.
    #[allow(static_mut_refs)]
    let ((rx_p, rx_c), (tx_p, tx_c), (s_p, s_c), (c_p, c_c), (r_p, r_c)) = unsafe {
        (
            RX_Q.split(),
            TX_Q.split(),
            SIGHT_Q.split(),
            CTRL_Q.split(),
            REPLY_Q.split(),
        )
    };
    critical_section::with(|cs| {
        RX_PRODUCER.borrow(cs).replace(Some(rx_p));
        TX_CONSUMER.borrow(cs).replace(Some(tx_c));
    });
    let periodic = Periodic::new(params, RuntimeConfig::default(), board::COST_UNIT).ok()?;
    // SAFETY: SysTick, the only user, is not running yet; `get` is called once, here, and the
    // reference moves into the periodic context.
    let periodic = unsafe {
        if !RUNTIME.init(periodic) {
            return None;
        }
        RUNTIME.get()?
    };
    // Contacts get the planner's A_s⁺ when the periodic task admits them.
    let background = Background::new(ExtractorConfig::default(), params.a_plus)?;
    // SAFETY: the background (thread mode) is the router's only user, and takes it once, here.
    let router = unsafe { ROUTER.get()? };
    router.set_cell(params.route_cell_m);
    let ctx = PeriodicCtx {
        periodic,
        tx: tx_p,
        sightings: s_c,
        controls: c_c,
        replies: r_c,
        ticks_per_period: 1,
        tick: 0,
        timer_period_ms: 0,
        time_ms: 0,
    };
    // SAFETY: SysTick, the owner, is not running yet (`start` enables it later).
    if !unsafe { PERIODIC.init(ctx) } {
        return None;
    }
    Some(Idle {
        background,
        router,
        rx: rx_c,
        sink: IdleSink {
            sightings: s_p,
            controls: c_p,
            replies: r_p,
        },
    })
}

/// What the periodic task has done so far.
#[cfg(feature = "selftest")]
pub fn stats() -> Stats {
    critical_section::with(|cs| STATS.borrow(cs).get())
}

/// The statistics so far, which then start again from zero (for reports per phase).
#[cfg(feature = "selftest")]
pub fn take_stats() -> Stats {
    critical_section::with(|cs| STATS.borrow(cs).take())
}

struct PeriodicInputs<'a> {
    sightings: &'a mut Consumer<'static, Sighting, SIGHTN>,
    controls: &'a mut Consumer<'static, Control, CTRLN>,
    replies: &'a mut Consumer<'static, ReplyRepr, REPLYN>,
}

impl Inputs for PeriodicInputs<'_> {
    fn nav(&mut self) -> Option<NavSample> {
        critical_section::with(|cs| NAV.borrow(cs).get())
    }
    fn sighting(&mut self) -> Option<Sighting> {
        self.sightings.dequeue()
    }
    fn control(&mut self) -> Option<Control> {
        self.controls.dequeue()
    }
    fn reply(&mut self) -> Option<ReplyRepr> {
        self.replies.dequeue()
    }
    fn link_counters(&mut self) -> (RxCounters, BackgroundCounters) {
        critical_section::with(|cs| LINK.borrow(cs).get())
    }
    fn route(&mut self) -> Option<Route> {
        ROUTE.latest()
    }
}

/// The SysTick body: run a period when one is due (or when the host's `Tick` asked for it in
/// lockstep).
pub fn on_systick(ctx: &mut PeriodicCtx) {
    let (lockstep, pending) = critical_section::with(|cs| {
        let cell = LOCKSTEP.borrow(cs);
        let (active, pending) = cell.get();
        cell.set((active, None));
        (active, pending)
    });
    let now = if lockstep {
        match pending {
            Some(t) => t,
            None => return,
        }
    } else {
        ctx.tick = ctx.tick.saturating_add(1);
        if ctx.tick < ctx.ticks_per_period {
            return;
        }
        ctx.tick = 0;
        ctx.time_ms = ctx.time_ms.saturating_add(u64::from(ctx.timer_period_ms));
        ctx.time_ms
    };
    critical_section::with(|cs| NOW_MS.borrow(cs).set(now));
    let dropped = RX_DROPPED.swap(0, Ordering::Relaxed);
    ctx.periodic.count_rx_dropped(dropped);

    let mut inputs = PeriodicInputs {
        sightings: &mut ctx.sightings,
        controls: &mut ctx.controls,
        replies: &mut ctx.replies,
    };
    let tx = &mut ctx.tx;
    let mut send = |frame: &[u8]| {
        // Whole frames only: a frame that does not fit is dropped (and counted by the caller).
        if tx.capacity() - tx.len() < frame.len() {
            return false;
        }
        frame.iter().all(|&b| tx.enqueue(b).is_ok())
    };
    let period_start = board::cost_now();
    ctx.periodic.on_tick(
        now,
        &mut inputs,
        Some(&EVIDENCE),
        &mut board::cost_now,
        &mut send,
    );
    let period_cost = board::cost_now().wrapping_sub(period_start);
    let goal = ctx.periodic.goal();
    critical_section::with(|cs| GOAL.borrow(cs).set(goal));
    board::kick_tx();
    board::feed_watchdog();

    let cost = ctx.periodic.last_cost();
    // The next timer interrupt already came while this period ran: a missed deadline.
    let overrun = !lockstep && board::timer_pending();
    if overrun {
        ctx.periodic.count_overrun();
    }
    critical_section::with(|cs| {
        let cell = STATS.borrow(cs);
        let mut st = cell.get();
        st.periods = st.periods.saturating_add(1);
        st.max_cost = st.max_cost.max(cost);
        st.sum_cost = st.sum_cost.saturating_add(u64::from(cost));
        st.overruns = st.overruns.saturating_add(u32::from(overrun));
        st.max_period = st.max_period.max(period_cost);
        st.map_cells = ctx.periodic.world().map_cells().len() as u32;
        cell.set(st);
    });
    // A new period from the parameters: reprogram the timer (absolute from here on).
    let period = ctx.periodic.period_ms();
    if !lockstep && period != ctx.timer_period_ms {
        start_timer(ctx, period);
    }
}

/// Programs the board's timer for `period_ms` and resets the period phase.
pub fn start_timer(ctx: &mut PeriodicCtx, period_ms: u32) {
    ctx.ticks_per_period = board::start_timer(period_ms);
    ctx.timer_period_ms = period_ms;
    ctx.tick = 0;
}

/// The receive interrupt's body: one byte into the queue (dropped and counted when full).
pub fn on_rx_byte(rx: &mut Producer<'static, u8, RXN>, b: u8) {
    if rx.enqueue(b).is_err() {
        RX_DROPPED.fetch_add(1, Ordering::Relaxed);
    }
}

/// The receive interrupt's producer, taken once.
pub fn rx_producer() -> Option<Producer<'static, u8, RXN>> {
    take(&RX_PRODUCER)
}

/// The transmit interrupt's consumer, taken once.
pub fn tx_consumer() -> Option<Consumer<'static, u8, TXN>> {
    take(&TX_CONSUMER)
}

/// A receive-queue producer, as the board's receive interrupt holds it.
pub type RxProducer = Producer<'static, u8, RXN>;
/// A transmit-queue consumer, as the board's transmit interrupt holds it.
pub type TxConsumer = Consumer<'static, u8, TXN>;

struct IdleSink {
    sightings: Producer<'static, Sighting, SIGHTN>,
    controls: Producer<'static, Control, CTRLN>,
    replies: Producer<'static, ReplyRepr, REPLYN>,
}

impl Sink for IdleSink {
    fn nav(&mut self, sample: NavSample) {
        critical_section::with(|cs| NAV.borrow(cs).set(Some(sample)));
    }
    fn sighting(&mut self, s: Sighting) -> bool {
        self.sightings.enqueue(s).is_ok()
    }
    fn control(&mut self, c: Control) -> bool {
        self.controls.enqueue(c).is_ok()
    }
    fn reply(&mut self, r: ReplyRepr) -> bool {
        self.replies.enqueue(r).is_ok()
    }
    fn tick(&mut self, time_ms: u64) {
        critical_section::with(|cs| LOCKSTEP.borrow(cs).set((true, Some(time_ms))));
        board::enter_lockstep();
    }
    fn route(&mut self, r: Route) {
        ROUTE.publish(&r);
    }
    fn goal(&mut self) -> (u32, Option<vpf::Vec2>) {
        critical_section::with(|cs| GOAL.borrow(cs).get())
    }
}

/// The background (thread mode) state.
pub struct Idle {
    background: Background,
    router: &'static mut Router,
    rx: Consumer<'static, u8, RXN>,
    sink: IdleSink,
}

impl Idle {
    /// Decodes what has been received; `true` if there was anything.
    pub fn poll(&mut self) -> bool {
        let mut buf = [0u8; 64];
        let mut n = 0;
        for slot in buf.iter_mut() {
            match self.rx.dequeue() {
                Some(b) => {
                    *slot = b;
                    n += 1;
                }
                None => break,
            }
        }
        let Some(mut rest) = buf.get(..n) else {
            return false;
        };
        while !rest.is_empty() {
            let now = critical_section::with(|cs| NOW_MS.borrow(cs).get());
            rest = self.background.on_bytes(
                rest,
                now,
                &mut self.sink,
                Some(&EVIDENCE),
                Some(self.router),
            );
            let ticked = critical_section::with(|cs| LOCKSTEP.borrow(cs).get().1.is_some());
            if ticked {
                // Run the requested period now, before later bytes are decoded.
                cortex_m::peripheral::SCB::set_pendst();
                while critical_section::with(|cs| LOCKSTEP.borrow(cs).get().1.is_some()) {
                    cortex_m::asm::nop();
                }
            }
        }
        let counters = (*self.background.rx_counters(), self.background.counters);
        critical_section::with(|cs| LINK.borrow(cs).set(counters));
        n > 0
    }

    /// Queues a sighting as the background would (for the self-test).
    #[cfg(feature = "selftest")]
    pub fn push_sighting(&mut self, s: Sighting) {
        let _ = self.sink.sighting(s);
    }

    /// Decodes `bytes` as if received (for the self-test).
    #[cfg(feature = "selftest")]
    pub fn feed(&mut self, bytes: &[u8]) {
        let now = critical_section::with(|cs| NOW_MS.borrow(cs).get());
        let mut rest = bytes;
        while !rest.is_empty() {
            rest = self.background.on_bytes(
                rest,
                now,
                &mut self.sink,
                Some(&EVIDENCE),
                Some(self.router),
            );
        }
    }
}

/// Firmware time now, ms.
#[cfg(feature = "selftest")]
pub fn now_ms() -> u64 {
    critical_section::with(|cs| NOW_MS.borrow(cs).get())
}

/// Starts the periodic task's timer at the planner's period.
pub fn start() {
    // SAFETY: called from `main` once, before the timer runs: SysTick cannot hold the value.
    if let Some(ctx) = unsafe { PERIODIC.get() } {
        let period = ctx.periodic.period_ms();
        start_timer(ctx, period);
    }
}

/// The SysTick exception: the periodic task, sole user of `PERIODIC` once started.
#[cortex_m_rt::exception]
fn SysTick() {
    // SAFETY: SysTick owns `PERIODIC` and cannot preempt itself.
    if let Some(ctx) = unsafe { PERIODIC.get() } {
        on_systick(ctx);
    }
}

/// A hard fault (a stack overflow into the guard region, a bad address): report and stop, so
/// a fault is never a silent hang.
#[cortex_m_rt::exception]
unsafe fn HardFault(frame: &cortex_m_rt::ExceptionFrame) -> ! {
    let mut line = *b"vpf-firmware: hard fault at pc 0x00000000\n";
    let pc = frame.pc();
    let hex = b"0123456789abcdef";
    for (i, slot) in line.iter_mut().skip(33).take(8).enumerate() {
        let nibble = (pc >> (28 - 4 * i as u32)) & 0xF;
        *slot = hex.get(nibble as usize).copied().unwrap_or(b'?');
    }
    board::log(&line);
    board::exit(false)
}
