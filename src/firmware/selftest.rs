//! The on-target self-test (`--features selftest`): measures what the budgets are about and
//! exits with the verdict. Run on QEMU with `-icount shift=0` so costs are instructions.
//!
//! 1. Loads the world to full capacity (32 obstacles of every shape, 8 agents, a formation, the
//!    evidence map's 32 cells and, for the VPF, 4 ghost goal-points) and gives the planner a
//!    mission and navigation through the same queues the UART feeds.
//! 2. Floods the background: the idle loop extracts synthetic sonar scanlines without pause,
//!    so the periodic task always preempts a busy extractor.
//! 3. Runs [`PERIODS`] periods with each strategy in turn (VPF, multipoint, navigation
//!    function) in two worlds — spread out ahead as far as a sonar sees, and in clutter with
//!    every obstacle within 9 m (the VPF's worst case: it samples every one) —, and the VPF
//!    flying a flat-fish (a slow-turning craft) in traffic closing from all round (the guard's
//!    worst case: stopping is run into and no motion is clear, so it searches all round for
//!    the least bad, `guidance::guard`), switched by a
//!    `Params` message as a host would, after [`WARMUP_PERIODS`] unmeasured ones, and reports per strategy the planner step cost (max and mean), the
//!    whole period's worst cost (map snapshot and guard included), deadline overruns,
//!    scanlines processed and the background's cost per scanline and per navigation frame (the
//!    route layer replans on those), and the least fill of the tables over the measured
//!    periods; then the stack high-water mark. It exits successfully only if no strategy
//!    overran, every measured period ran at full tables and every worst step was within
//!    [`STEP_BUDGET`]. Half the obstacles of the spread world move, so the prediction of moving obstacles is in the measured path.
//! 4. Before the floods and after them (the evidence map empty, then full), the guard's worst
//!    case, which no charted world reaches: a VideoRay (VPF) among 32 sonar contacts seen
//!    once ahead, each of which may be another vehicle ([`contacts`]), on navigation alone.
//! 5. A further flood (VPF, the spread world) brings its pings as Ping360 `device_data`
//!    through the Ping360 driver and its navigation as MAVLink (ATTITUDE, LOCAL_POSITION_NED)
//!    through the MAVLink line's decoder, so their paths are measured and in the stack's
//!    high-water mark; every period also sends the MAVLink set-point and what else is due.

use vpf::field::Shape;
use vpf::guidance::tracks::SONAR_ID_BASE;
use vpf::guidance::Sighting;
use vpf::link::{ChartClearRepr, Message, NavRepr, Payload};
use vpf::sonar::Scanline;
use vpf::world::{Agent, Obstacle, Origin, MAX_AGENTS, MAX_MAP_CELLS, MAX_OBSTACLES};
use vpf::{Mission, NavState, Params, Strategy, Vec2};

use super::background::{BackgroundTask, Exchange};
use super::Stats;
use crate::board::active as board;

/// Bins of the flood's scanlines (and of the link's cost measurement).
const FLOOD_BINS: usize = 400;
/// A transmit buffer for one such scanline frame, and one for a `Params` frame: the test's
/// stand-ins for the UART's queue hold only what they carry, so that the stack high-water
/// measures the firmware rather than the test (`MAX_FRAME` is the longest message's, 715).
const SCAN_FRAME: usize =
    vpf::link::frame_buffer_len(vpf::link::sensors::SCANLINE_HEAD_LEN + FLOOD_BINS);
const PARAMS_FRAME: usize = vpf::link::frame_buffer_len(vpf::link::control::PARAMS_LEN);

/// Periods measured per strategy.
pub const PERIODS: u32 = 50;
/// Periods run before measuring, per strategy: the evidence map fills, moving obstacles are
/// predicted and (VPF) the ghost goal-point stack builds up, so that every measured period
/// runs at full tables (the report gives the least fill over the measured periods).
pub const WARMUP_PERIODS: u32 = 20;
/// The planner step budget, instructions (shared/DESIGN.md).
pub const STEP_BUDGET: u32 = 100_000;

/// The worlds the strategies are measured in ([`obstacle`] says where).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Phase {
    Spread,
    Clutter,
    Traffic,
    /// No charted obstacles: sonar contacts ([`contacts`]).
    Contacts,
}

/// `p` for a flat-fish (seed 003's AUV, `hil/recipes/flatfish.toml`'s craft): a hull of
/// 2.6 m, turning at 0.046 rad/s and braking at 0.1 m/s², so that the guard judges its arcs
/// and courses.
fn flatfish(p: Params) -> Params {
    Params {
        agent_radius_m: 2.6,
        turn_rate_rps: 0.046,
        brake_mps2: 0.1,
        f_max: 0.15,
        ..p
    }
}

/// Runs the self-test; never returns.
pub fn run(idle: &mut BackgroundTask, x: &mut impl Exchange, params: Params) -> ! {
    board::log(b"selftest: full tables, sonar flood, 50 periods per strategy and world\n");
    link_costs(idle, x);
    // Before any flood, with the evidence map empty (so that the nearest contact is near
    // enough for close quarters), and again after the floods, with it full.
    let mut ok = contacts(idle, x, params);
    remove_boot_contacts(idle, x);
    let strategies = [Strategy::Vpf, Strategy::Multipoint, Strategy::Navfn];
    for (strategy, w) in strategies
        .iter()
        .map(|&s| (s, Phase::Spread))
        .chain(strategies.iter().map(|&s| (s, Phase::Clutter)))
        .chain([(Strategy::Vpf, Phase::Traffic)])
    {
        let p = Params { strategy, ..params };
        let p = if w == Phase::Traffic { flatfish(p) } else { p };
        // VPF: a vehicle held so hard by friction (μ at its largest) that its planned speed
        // stays below the stall speed (at its largest, v_max) is stalled every `stall_time_s`
        // (at its least), by the static field (whose force is far below μ·v_max here), so
        // ghost goal-points stack to `max_ghosts` in a few periods (000 §III); with λ = 0 and
        // α = 1 (eq. 17) each lies as far off as its target, so none is ever reached and the
        // full stack's top, replaced at each stall, stays put in distance. Only the top ghost
        // is in the field (it replaces the goal-point), so the depth changes no cost; it is
        // loaded because the budget names it. These settings cost the same at any value.
        let p = if strategy == Strategy::Vpf {
            Params {
                mu: 10.0,
                stall_speed: p.v_max,
                stall_time_s: 0.1,
                ghost_lambda: 0.0,
                ghost_alpha: 1.0,
                ..p
            }
        } else {
            p
        };
        set_strategy(idle, x, p);
        // Loaded again per phase: the upserts (same ids) replace the obstacles and refresh the
        // agents, which age out.
        load_world(idle, x, w);
        let _ = x.take_stats();
        let _ = flood(idle, x, WARMUP_PERIODS, None);
        let _ = x.take_stats();
        let flood = flood(idle, x, PERIODS, None);
        let ghosts = if strategy == Strategy::Vpf {
            p.max_ghosts
        } else {
            0
        };
        ok &= report(strategy, w, &flood, x, ghosts);
    }
    // The Ping360's path: the spread world's flood, its pings as `device_data` through the driver.
    set_strategy(idle, x, params);
    load_world(idle, x, Phase::Spread);
    let _ = x.take_stats();
    let mut sonar = PingStats::default();
    flood(idle, x, PERIODS, Some(&mut sonar));
    let s = x.take_stats();
    report_ping360(idle, params.strategy, &s, &sonar);
    ok &= s.overruns == 0 && s.periods >= PERIODS && s.max_cost <= STEP_BUDGET;
    ok &= contacts(idle, x, params);
    report_object_costs();
    report_stack();
    board::log(if ok {
        b"selftest: PASS\n"
    } else {
        b"selftest: FAIL\n"
    });
    board::exit(ok)
}

/// The Ping360 flood's line. Not inlined, like the other reports: their line buffers stay out
/// of [`run`]'s frame, under every measurement's stack.
#[inline(never)]
fn report_ping360(idle: &BackgroundTask, strategy: Strategy, s: &Stats, sonar: &PingStats) {
    let mut line = Line::new();
    line.push(b"selftest: Ping360 flood (");
    line.push(strategy.name().as_bytes());
    line.push(b") periods ");
    line.num(u64::from(s.periods));
    line.push(b", overruns ");
    line.num(u64::from(s.overruns));
    line.push(b", device_data of 300 samples fed ");
    line.num(u64::from(sonar.fed));
    line.push(b", scanlines ");
    line.num(u64::from(idle.ping360_counters().data));
    line.push(b" (background per ping max ");
    line.num(u64::from(sonar.max_cost));
    line.push(b" mean ");
    line.num(sonar.sum_cost / u64::from(sonar.measured.max(1)));
    line.push(b"), MAVLink frames ");
    line.num(u64::from(idle.mavlink_counters().frames));
    line.push(b"\n");
    board::log(line.bytes());
}

#[inline(never)]
fn report_stack() {
    let mut line = Line::new();
    line.push(b"selftest: stack high-water ");
    line.num(stack_high_water() as u64);
    line.push(b" bytes\n");
    board::log(line.bytes());
}

/// The link's own cost, in the background: a scanline frame of 400 bins (428 raw bytes, two
/// Reed–Solomon blocks, 463 bytes on the wire with its delimiter) decoded as it arrived clean,
/// and with 16 wrong bytes (8 in each block, the most the code corrects) repaired. The frame is refused once
/// decoded (its range is 0 m: `rx_bad_payload`), so no extraction is in the measurement; the
/// least of eight tries, so that a period preempting one does not count. Not inlined: its
/// frame buffer would otherwise sit under every later measurement's stack.
#[inline(never)]
fn link_costs(idle: &mut BackgroundTask, x: &mut impl Exchange) {
    let bins = [7u8; FLOOD_BINS];
    let scan = Scanline {
        time_ms: x.now_ms(),
        bearing_rad: 0.0,
        step_rad: 0.0314,
        range_m: 40.0,
        bins: &bins,
    };
    let mut costs = [u32::MAX; 2];
    for (damaged, least) in costs.iter_mut().enumerate() {
        for seq in 0..8u16 {
            let mut frame = [0u8; SCAN_FRAME];
            let refused = vpf::link::encode_frame(
                vpf::link::MessageType::Scanline,
                seq,
                |buf| {
                    let n = scan.emit(buf)?;
                    // range_m, offset 16: 0 m is out of range.
                    if let Some(r) = buf.get_mut(16..20) {
                        r.fill(0);
                    }
                    Ok(n)
                },
                &mut frame,
            );
            let Ok(n) = refused else { continue };
            if damaged == 1 {
                // Codeword bytes 40 .. 56 (wire bytes 41 .. 57, after the first key) alternate
                // between the two blocks; none is made 0x00.
                for b in frame.iter_mut().skip(41).take(16) {
                    *b = if *b == 0x5A { 0xA5 } else { *b ^ 0x5A };
                }
            }
            let Some(bytes) = frame.get(..n) else {
                continue;
            };
            let periods = x.stats().periods;
            let start = board::cost_now();
            idle.feed(bytes, x);
            let cost = board::cost_now().wrapping_sub(start);
            if x.stats().periods == periods {
                *least = (*least).min(cost);
            }
        }
    }
    let mut line = Line::new();
    line.push(b"selftest: link, a 400-bin scanline frame decoded: clean ");
    line.num(u64::from(costs[0]));
    line.push(b" instructions, with 16 wrong bytes corrected ");
    line.num(u64::from(costs[1]));
    line.push(b"\n");
    board::log(line.bytes());
}

/// What the background did during a flood.
struct Flood {
    scanlines: u32,
    /// Cost of decoding and processing one scanline frame (extraction and evidence map), in
    /// the board's unit, over the frames no period preempted: the largest and the sum.
    max_cost: u32,
    sum_cost: u64,
    measured: u32,
    /// Largest cost of a navigation frame no period preempted: the route layer replans on
    /// one in eight (once per second), so this is a replan's cost.
    max_nav_cost: u32,
}

/// What the Ping360's path cost during the floods.
#[derive(Default)]
struct PingStats {
    fed: u32,
    max_cost: u32,
    sum_cost: u64,
    measured: u32,
}

/// One `device_data` of the board's settings (300 samples, one echo at 4–5.5 m) through the Ping360 driver, the extractor and the evidence map, as the sonar UART
/// would bring it; its buffers in a frame of its own, so the flood's does not grow.
#[inline(never)]
fn feed_ping360(idle: &mut BackgroundTask, x: &mut impl Exchange, ping: u32, st: &mut PingStats) {
    let cfg = vpf::sonar::ping360::Ping360Config::BOARD;
    let mut data = [0u8; 300];
    for (i, d) in data.iter_mut().enumerate() {
        let r = (i as u32).wrapping_mul(2_654_435_761).wrapping_add(ping) >> 28;
        // The flood's wall (0.1 m a sample, as its scanlines' bins): echoes at 4–5.5 m.
        *d = if (40..43).contains(&(i as u32).wrapping_sub(ping % 15)) {
            220
        } else {
            (r * 4) as u8
        };
    }
    let m = vpf::link::ping::Message::DeviceData(vpf::link::ping::DeviceDataRepr {
        settings: cfg.settings(((ping * 2) % 400) as u16),
        data: &data,
    });
    let mut frame = [0u8; 8 + 14 + 300 + 2];
    let Ok(n) = vpf::link::ping::emit_frame(&m, 2, 0, &mut frame) else {
        return;
    };
    let Some(bytes) = frame.get(..n) else {
        return;
    };
    let periods = x.stats().periods;
    let start = board::cost_now();
    idle.feed_ping360(bytes, x);
    let cost = board::cost_now().wrapping_sub(start);
    st.fed += 1;
    if x.stats().periods == periods {
        st.max_cost = st.max_cost.max(cost);
        st.sum_cost += u64::from(cost);
        st.measured += 1;
    }
}

/// Feeds `m` to the background as the host's link would, framed in `N` bytes (the message's
/// own size: the test's buffers hold only what they carry).
fn send<const N: usize>(idle: &mut BackgroundTask, x: &mut impl Exchange, m: Message<'_>) {
    let mut frame = [0u8; N];
    if let Ok(n) = m.emit_frame(0, &mut frame) {
        if let Some(f) = frame.get(..n) {
            idle.feed(f, x);
        }
    }
}

/// Switches the planner's parameters by a `Params` message, as a host would.
fn set_strategy(idle: &mut BackgroundTask, x: &mut impl Exchange, p: Params) {
    send::<PARAMS_FRAME>(idle, x, Message::Params(p));
}

/// `periods` periods of sonar flood: scanline messages on the control link, or with `sonar`
/// Ping360 `device_data` through its driver.
fn flood(
    idle: &mut BackgroundTask,
    x: &mut impl Exchange,
    periods: u32,
    mut sonar: Option<&mut PingStats>,
) -> Flood {
    let mut bins = [0u8; FLOOD_BINS];
    let mut ping = 0u32;
    let mut f = Flood {
        scanlines: 0,
        max_cost: 0,
        sum_cost: 0,
        measured: 0,
        max_nav_cost: 0,
    };
    while x.stats().periods < periods {
        // Keep navigation fresh (the periodic task holds on stale navigation), and serve the
        // UART as the firmware would.
        if ping.is_multiple_of(8) {
            let periods = x.stats().periods;
            let start = board::cost_now();
            if sonar.is_some() {
                send_nav_mavlink(idle, x);
            } else {
                send_nav(idle, x);
            }
            let cost = board::cost_now().wrapping_sub(start);
            if x.stats().periods == periods {
                f.max_nav_cost = f.max_nav_cost.max(cost);
            }
        }
        idle.poll(x);
        if let Some(st) = sonar.as_deref_mut() {
            feed_ping360(idle, x, ping, st);
            ping = ping.wrapping_add(1);
            continue;
        }
        // One synthetic ping: a wall of echoes at a bearing-dependent range, with speckle.
        for (i, b) in bins.iter_mut().enumerate() {
            let r = (i as u32).wrapping_mul(2_654_435_761).wrapping_add(ping) >> 28;
            // One strong echo per ping at 4–5.5 m: over the sweeps, the evidence map fills
            // every sector of the planner's polar scan within reach (32 cells: full capacity).
            *b = if (40..43).contains(&(i as u32).wrapping_sub(ping % 15)) {
                220
            } else {
                (r * 4) as u8
            };
        }
        let scan = Scanline {
            time_ms: x.now_ms(),
            bearing_rad: ((ping % 200) as f32) * 0.0314 - core::f32::consts::PI,
            step_rad: 0.0314,
            range_m: 40.0,
            bins: &bins,
        };
        let mut frame = [0u8; SCAN_FRAME];
        if let Ok(n) = scan.emit_frame(ping as u16, &mut frame) {
            if let Some(bytes) = frame.get(..n) {
                let periods = x.stats().periods;
                let start = board::cost_now();
                idle.feed(bytes, x);
                let cost = board::cost_now().wrapping_sub(start);
                f.scanlines += 1;
                if x.stats().periods == periods {
                    f.max_cost = f.max_cost.max(cost);
                    f.sum_cost += u64::from(cost);
                    f.measured += 1;
                }
            }
        }
        ping = ping.wrapping_add(1);
    }
    f
}

fn send_nav(idle: &mut BackgroundTask, x: &mut impl Exchange) {
    let now = x.now_ms();
    let nav = NavRepr {
        time_ms: now,
        nav: NavState {
            // A fix that changes (by millimetres), as a real one does: the same fix over and
            // over while commanded to move is a frozen navigation source, and holds.
            position: Vec2::new((now % 1000) as f32 * 1e-5, 0.0),
            heading: 0.0,
            velocity: Vec2::new(0.8, 0.1),
        },
        body: None,
    };
    send::<64>(idle, x, Message::Nav(nav));
}

/// The same navigation as [`send_nav`], as an autopilot's ATTITUDE and LOCAL_POSITION_NED on
/// the MAVLink line (NED: north is the firmware's y, yaw = π/2 − heading).
#[inline(never)]
fn send_nav_mavlink(idle: &mut BackgroundTask, x: &mut impl Exchange) {
    use mavlink::dialects::common::{ATTITUDE_DATA, LOCAL_POSITION_NED_DATA};
    use mavlink::{MavlinkVersion, MessageData};
    let now = x.now_ms();
    let att = ATTITUDE_DATA {
        time_boot_ms: now as u32,
        yaw: core::f32::consts::FRAC_PI_2,
        ..ATTITUDE_DATA::default()
    };
    let pos = LOCAL_POSITION_NED_DATA {
        time_boot_ms: now as u32,
        x: 0.0,
        y: (now % 1000) as f32 * 1e-5,
        vx: 0.1,
        vy: 0.8,
        ..LOCAL_POSITION_NED_DATA::default()
    };
    let mut payload = [0u8; 255];
    let mut frame = [0u8; 64];
    let n = att.ser(MavlinkVersion::V2, &mut payload);
    if let Some(f) = payload.get(..n).and_then(|p| {
        vpf::link::mavlink::emit_frame(
            0,
            (1, 1),
            (ATTITUDE_DATA::ID, ATTITUDE_DATA::EXTRA_CRC),
            p,
            &mut frame,
        )
    }) {
        if let Some(bytes) = frame.get(..f) {
            idle.feed_mavlink(bytes, x);
        }
    }
    let n = pos.ser(MavlinkVersion::V2, &mut payload);
    if let Some(f) = payload.get(..n).and_then(|p| {
        vpf::link::mavlink::emit_frame(
            1,
            (1, 1),
            (
                LOCAL_POSITION_NED_DATA::ID,
                LOCAL_POSITION_NED_DATA::EXTRA_CRC,
            ),
            p,
            &mut frame,
        )
    }) {
        if let Some(bytes) = frame.get(..f) {
            idle.feed_mavlink(bytes, x);
        }
    }
}

/// Full tables, through the same request and sighting queues as the UART path: the mission
/// (with a formation), [`MAX_OBSTACLES`] obstacles of every shape and [`MAX_AGENTS`] other
/// vehicles ([`obstacle`] says where). The sighting queue holds fewer than that and a period
/// takes what it holds, so when it is full the load waits for a period to drain it.
///
/// The obstacles are charted: a sensed one would be evicted by the nearer features the sonar
/// flood extracts (the table's overflow policy, `World::upsert_obstacle_or_evict`), and a
/// still feature is left to the evidence map, which would empty the field being measured.
fn load_world(idle: &mut BackgroundTask, x: &mut impl Exchange, w: Phase) {
    let mission = Mission {
        goal: Vec2::new(80.0, 0.0),
        formation: Some(vpf::planner::Formation {
            q: 4,
            lattice_m: 3.0,
            orientation: 0.0,
            attraction: 5.0,
        }),
    };
    send::<128>(idle, x, Message::Mission(mission));
    let now = x.now_ms();
    let obstacles = (0..MAX_OBSTACLES).filter_map(|i| obstacle(i, now, w).map(Sighting::Obstacle));
    let agents = (0..MAX_AGENTS).filter_map(|i| {
        let p = Vec2::new(-5.0 - 3.0 * i as f32, 4.0);
        Agent::new(i as u16, p, Vec2::ZERO, now)
            .ok()
            .map(Sighting::Agent)
    });
    for s in obstacles.chain(agents) {
        while !idle.push_sighting(s) {
            next_period(idle, x);
        }
    }
    next_period(idle, x);
}

/// The guard's worst case, which the flooded worlds (charted) never reach: a VideoRay at
/// cruise in open water with every table slot a sonar contact seen once — a small circle
/// within 55° of the bow, alone (4.7 m from the next), so each may be another vehicle coming
/// its way (`guidance::guard`, "Head-on"). With the evidence map empty the nearest (3 m
/// ahead) is also near enough for "Close quarters"; with it full, every "alone" test reads
/// its cells too, and the nearest, inside the flood's ring of echoes, is structure.
/// Navigation only, no scanlines: a sighting would take a contact's slot or see it again.
/// True if no period overran, every step was within [`STEP_BUDGET`] and every contact stayed
/// one seen once.
#[inline(never)]
fn contacts(idle: &mut BackgroundTask, x: &mut impl Exchange, params: Params) -> bool {
    use vpf::sonar::{Feature, FeatureKind};
    set_strategy(
        idle,
        x,
        Params {
            strategy: Strategy::Vpf,
            ..params
        },
    );
    send::<32>(idle, x, Message::ChartClear(ChartClearRepr::All));
    load_world(idle, x, Phase::Contacts);
    // Rows across the bow 4.7 m apart, from 3 m out, as many as fit within 55° of it.
    let rows = (0..8u32).flat_map(|row| {
        let r = 3.0 + 4.7 * row as f32;
        let n = ((1.92 * r / 4.7) as u32).max(1);
        let step = 1.92 / n.saturating_sub(1).max(1) as f32;
        let first = if n > 1 { -0.96 } else { 0.0 };
        (0..n).map(move |k| Vec2::from_angle(first + step * k as f32) * r)
    });
    for c in rows.take(MAX_OBSTACLES) {
        let f = Feature {
            center: c,
            radius: 0.25,
            kind: FeatureKind::Circle { radius: 0.25 },
            confidence: 0.2,
            time_ms: x.now_ms(),
            beams: 2,
            runs_on: false,
            faint: false,
        };
        while !idle.push_sighting(Sighting::Feature(f)) {
            next_period(idle, x);
        }
    }
    let _ = quiet(idle, x, WARMUP_PERIODS);
    let s = quiet(idle, x, PERIODS);
    let mut line = Line::new();
    line.push(b"selftest: vpf, sonar contacts seen once ahead");
    push_costs(&mut line, &s);
    line.push(b", least contacts ");
    line.num(u64::from(s.least_fill.contacts));
    line.push(b" of ");
    line.num(MAX_OBSTACLES as u64);
    line.push(b", map cells ");
    line.num(u64::from(s.least_fill.map_cells));
    line.push(b"\n");
    board::log(line.bytes());
    s.overruns == 0
        && s.max_cost <= STEP_BUDGET
        && s.periods >= PERIODS
        && usize::from(s.least_fill.contacts) == MAX_OBSTACLES
}

/// Removes the contacts [`contacts`] left at boot, by id as a host may, so that the charted
/// worlds get the table: the tracker numbers its tracks from its base, and nothing else had
/// been tracked.
fn remove_boot_contacts(idle: &mut BackgroundTask, x: &mut impl Exchange) {
    for id in (0..MAX_OBSTACLES as u16).map(|k| k.saturating_add(SONAR_ID_BASE)) {
        send::<32>(idle, x, Message::ChartClear(ChartClearRepr::One(id)));
        // One request a period: the control queue is short.
        next_period(idle, x);
    }
}

/// `periods` periods with fresh navigation and nothing else; their stats.
fn quiet(idle: &mut BackgroundTask, x: &mut impl Exchange, periods: u32) -> Stats {
    let _ = x.take_stats();
    while x.stats().periods < periods {
        send_nav(idle, x);
        next_period(idle, x);
    }
    x.take_stats()
}

/// Obstacle `i` of the self-test's world: a circle, a rectangle, an ellipse or a hexagon.
///
/// - Spread: a grid 10–59 m ahead, 20 m either side, as a sonar's table
///   holds obstacles out to its range; every other one crosses at 0.5 m/s.
/// - Clutter: all 32 within 2–9 m of the vehicle (rings of 8 at 3, 5, 7 and 9 m), still, so
///   that the VPF samples every one on its circle (none is far enough to be linearised,
///   `planner::gradient::far_gradient`): the step's worst case.
/// - Traffic: all 32 on a ring 16 m round the vehicle, each closing on it at 1 m/s (7–12 m
///   off over the measured periods): every motion meets one.
fn obstacle(i: usize, now_ms: u64, w: Phase) -> Option<Obstacle> {
    let (c, scale, v) = match w {
        Phase::Clutter => {
            let ring = (i / 8) as f32;
            let a = (i % 8) as f32 * 0.785 + ring * 0.2;
            (Vec2::from_angle(a) * (3.0 + 2.0 * ring), 0.5, Vec2::ZERO)
        }
        Phase::Spread => {
            let c = Vec2::new(10.0 + 7.0 * (i % 8) as f32, -20.0 + 9.0 * (i / 8) as f32);
            let v = if i.is_multiple_of(2) { 0.5 } else { 0.0 };
            (c, 1.0, Vec2::new(0.0, v))
        }
        Phase::Contacts => return None,
        Phase::Traffic => {
            let u = Vec2::from_angle(i as f32 * (2.0 * core::f32::consts::PI / 32.0));
            (u * 16.0, 0.5, u * -1.0)
        }
    };
    let shape = match i % 4 {
        0 => Shape::circle(c, 1.5 * scale),
        1 => Shape::rectangle(c, Vec2::new(2.0, 1.0) * scale, 0.3),
        2 => Shape::ellipse(c, Vec2::new(2.0, 1.0) * scale, -0.4),
        _ => {
            let mut hex = [Vec2::ZERO; 6];
            for (k, v) in hex.iter_mut().enumerate() {
                *v = c + Vec2::from_angle(k as f32 * 1.047) * (1.5 * scale);
            }
            Shape::polygon(&hex)
        }
    }
    .ok()?;
    Obstacle::new(i as u16, shape, 2.5, Origin::Charted, now_ms)
        .and_then(|o| o.moving(v))
        .ok()
}

/// Serves the background until the periodic task has run one more period.
fn next_period(idle: &mut BackgroundTask, x: &mut impl Exchange) {
    let start = x.stats().periods;
    while x.stats().periods == start {
        idle.poll(x);
    }
}

/// The periods `s` counts and their costs: the planner's step (max and mean), the whole
/// period, overruns.
fn push_costs(line: &mut Line, s: &Stats) {
    line.push(b" periods ");
    line.num(u64::from(s.periods));
    line.push(b", step cost max ");
    line.num(u64::from(s.max_cost));
    line.push(b" mean ");
    line.num(s.sum_cost / u64::from(s.periods.max(1)));
    line.push(b" instructions, whole period max ");
    line.num(u64::from(s.max_period));
    line.push(b", overruns ");
    line.num(u64::from(s.overruns));
}

/// Prints one strategy's lines; true if it met the budget at full tables (`ghosts`: the
/// depth the ghost goal-point stack was loaded to, 0 for a strategy without them).
fn report(strategy: Strategy, w: Phase, flood: &Flood, x: &mut impl Exchange, ghosts: u8) -> bool {
    let name = |line: &mut Line| {
        line.push(b"selftest: ");
        line.push(strategy.name().as_bytes());
        line.push(match w {
            Phase::Spread => b"",
            Phase::Clutter => b" in clutter",
            Phase::Traffic => b", a flat-fish in traffic",
            Phase::Contacts => b", sonar contacts",
        });
    };
    let s = x.take_stats();
    let mut line = Line::new();
    name(&mut line);
    push_costs(&mut line, &s);
    line.push(b", scanlines extracted ");
    line.num(u64::from(flood.scanlines));
    line.push(b" (background per scanline max ");
    line.num(u64::from(flood.max_cost));
    line.push(b" mean ");
    line.num(flood.sum_cost / u64::from(flood.measured.max(1)));
    line.push(b"; navigation with route replan max ");
    line.num(u64::from(flood.max_nav_cost));
    line.push(b")\n");
    board::log(line.bytes());
    let f = s.least_fill;
    let mut line = Line::new();
    name(&mut line);
    line.push(b" least table fill over those periods: obstacles ");
    line.num(u64::from(f.obstacles));
    line.push(b" of ");
    line.num(MAX_OBSTACLES as u64);
    line.push(b", agents ");
    line.num(u64::from(f.agents));
    line.push(b" of ");
    line.num(MAX_AGENTS as u64);
    line.push(b", map cells ");
    line.num(u64::from(f.map_cells));
    line.push(b" of ");
    line.num(MAX_MAP_CELLS as u64);
    line.push(b", ghost goal-points ");
    line.num(u64::from(f.ghosts));
    line.push(b" of ");
    line.num(u64::from(ghosts));
    line.push(b"\n");
    board::log(line.bytes());
    let full = usize::from(f.obstacles) == MAX_OBSTACLES
        && usize::from(f.agents) == MAX_AGENTS
        && usize::from(f.map_cells) == MAX_MAP_CELLS
        && f.ghosts == ghosts;
    full && s.overruns == 0 && s.max_cost <= STEP_BUDGET && s.periods >= PERIODS
}

/// Copies of an object in a measured field: the cost per object is the field's cost less the
/// empty field's, divided by this.
const COPIES: usize = 8;

/// What one object costs in a VPF step: the sampled field (`Field::sampled_forces`, the
/// vehicle's point and n_γ samples) with [`COPIES`] of it, less the field without it, per
/// copy; each the least of a few runs, so that a period preempting one does not count. Near
/// (2–3 m off: sampled, on the stator's exponential branch) and far (25 m off: linearised,
/// `planner::gradient::far_gradient`).
fn report_object_costs() {
    use vpf::field::{GoalPdf, Stator};
    use vpf::planner::gradient::Field;
    use vpf::planner::SampleCircle;
    let params = Params::default();
    let circle = SampleCircle::new(params.epsilon_m, params.n_gamma);
    let stator = Stator::new(params.a_plus);
    let origin = Vec2::new(0.1, 0.2);
    let shifts = [Vec2::ZERO; COPIES];
    let field = |obstacles: &[Obstacle], agents: &[Agent], map: &[Vec2]| {
        let f = Field {
            obstacles,
            shifts: &shifts,
            distances: &[],
            agents,
            agent_radius: params.agent_radius_m,
            agent_stator: stator,
            goal: GoalPdf::new(Vec2::new(80.0, 0.0), params.a_minus, params.sigma_m),
            leader: None,
            rotor_gradient: Vec2::ZERO,
            origin,
            map,
            map_radius: 0.25,
            map_stator: stator,
            leave_to_map: false,
        };
        (0..5)
            .map(|_| {
                let start = board::cost_now();
                core::hint::black_box(f.sampled_forces(core::hint::black_box(&circle)));
                board::cost_now().wrapping_sub(start)
            })
            .min()
            .unwrap_or(0)
    };
    let empty = field(&[], &[], &[]);
    let per = |cost: u32| u64::from(cost.saturating_sub(empty)) / COPIES as u64;
    for (far, c) in [(false, Vec2::new(3.0, 1.5)), (true, Vec2::new(25.0, 5.0))] {
        let mut line = Line::new();
        line.push(if far {
            b"selftest: vpf field cost per far object (linearised): ".as_slice()
        } else {
            b"selftest: vpf field cost per near object (n_gamma + 1 samples): ".as_slice()
        });
        let shapes: [(&[u8], Option<Shape>); 4] = [
            (b"circle", Shape::circle(c, 1.0).ok()),
            (
                b"rectangle",
                Shape::rectangle(c, Vec2::new(1.0, 0.5), 0.3).ok(),
            ),
            (
                b"ellipse",
                Shape::ellipse(c, Vec2::new(1.0, 0.5), -0.4).ok(),
            ),
            (b"hexagon", {
                let mut hex = [Vec2::ZERO; 6];
                for (k, v) in hex.iter_mut().enumerate() {
                    *v = c + Vec2::from_angle(k as f32 * 1.047) * 1.0;
                }
                Shape::polygon(&hex).ok()
            }),
        ];
        for (name, shape) in shapes {
            let Some(shape) = shape else { continue };
            let Ok(o) = Obstacle::new(0, shape, params.a_plus, Origin::Sensed, 0) else {
                continue;
            };
            line.push(name);
            line.push(b" ");
            line.num(per(field(&[o; COPIES], &[], &[])));
            line.push(b", ");
        }
        let mut agents: heapless::Vec<Agent, COPIES> = heapless::Vec::new();
        for i in 0..COPIES {
            if let Ok(a) = Agent::new(i as u16, c, Vec2::ZERO, 0) {
                let _ = agents.push(a);
            }
        }
        line.push(b"agent ");
        line.num(per(field(&[], &agents, &[])));
        if !far {
            line.push(b", map cell ");
            line.num(per(field(&[], &[], &[c; COPIES])));
            line.push(b"; goal-point alone ");
            line.num(u64::from(empty));
        }
        line.push(b"\n");
        board::log(line.bytes());
    }
}

/// Bytes of stack ever used: cortex-m-rt paints the stack with 0xCCCC_CCCC at boot
/// (`paint-stack`); the high-water mark is where the paint ends.
fn stack_high_water() -> usize {
    extern "C" {
        static _stack_end: u32;
        static _stack_start: u32;
    }
    // # Safety
    // The linker's stack bounds (flip-link: the bottom of RAM up to `.data`); the region between
    // them is RAM reserved for the stack, word-aligned, and only read here, word by word, with
    // volatile loads (the live stack above the paint is never read as Rust values).
    #[allow(unsafe_code)]
    unsafe {
        let lo = core::ptr::addr_of!(_stack_end) as usize;
        let hi = core::ptr::addr_of!(_stack_start) as usize;
        let mut p = lo;
        while p < hi && core::ptr::read_volatile(p as *const u32) == 0xCCCC_CCCC {
            p += 4;
        }
        hi - p
    }
}

/// A tiny line buffer with decimal numbers (no `core::fmt`, which carries panicking paths).
struct Line {
    buf: [u8; 384],
    len: usize,
}

impl Line {
    fn new() -> Self {
        Line {
            buf: [0; 384],
            len: 0,
        }
    }
    fn push(&mut self, s: &[u8]) {
        for &b in s {
            if let Some(slot) = self.buf.get_mut(self.len) {
                *slot = b;
                self.len += 1;
            }
        }
    }
    fn num(&mut self, mut n: u64) {
        let mut digits = [0u8; 20];
        let mut k = 0;
        loop {
            if let Some(d) = digits.get_mut(k) {
                *d = b'0' + (n % 10) as u8;
            }
            k += 1;
            n /= 10;
            if n == 0 || k >= digits.len() {
                break;
            }
        }
        while k > 0 {
            k -= 1;
            let d = digits.get(k).copied().unwrap_or(b'?');
            self.push(&[d]);
        }
    }
    fn bytes(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or(&[])
    }
}
