//! Seeded, structure-aware fuzz test of the serial link and the runtime's byte path (issue
//! "Faults and bad input").
//!
//! A bounded number of inputs, from a small deterministic PRNG (xorshift64*) with a fixed seed,
//! go through [`OneThreadRuntime::on_bytes`] exactly as `src/host.rs` and `tests/runtime.rs` feed
//! it, each followed by one period (a `Tick` frame in lockstep mode, `on_tick` in real time, as
//! `src/host.rs` does). Every input is built from frames of all the protocol's message types
//! (`docs/protocol.md` §4; host → firmware ones as the firmware's input, firmware → host ones,
//! which it must refuse by direction), made with the library's own encoders, then mutated with
//! the layout of `docs/protocol.md` in mind: bit flips, byte overwrites, truncation,
//! extension, splices of two frames, header version/type/sequence, NaN/±∞/1e30/−0/subnormals
//! in the float fields at their documented offsets, counts and lengths at 0, max and max + 1,
//! times at 0 and `u64::MAX`. The CRC is recomputed after the mutation in most cases (so the
//! payload parsers are reached) and left broken in the others. Frames are coded as the
//! protocol's frames to the firmware are (Reed–Solomon parity, whitening, zero substitution;
//! written here from `docs/protocol.md`, apart from the library), and some are damaged on the
//! wire: up to 8 wrong bytes per block (corrected), more (uncorrectable), wrong keys, stray
//! 0x00s, cut or lengthened frames, other valid keys. Inputs also include raw garbage,
//! oversize runs, COBS frames (the other direction's framing: noise here), and frames glued
//! without delimiters. Each run starts with valid parameters, a mission, a chart and navigation, and
//! valid navigation is interleaved so that the planner plans and the vehicle moves.
//!
//! After every input, checked:
//! - no panic (a panic is reported with the seed, run, input index and the input's bytes);
//! - every frame the firmware sends decodes cleanly with a host [`Decoder`];
//! - one `Command` per period that ran (`on_bytes`' returned commands are the sent ones), each
//!   within the `Command` table of `docs/protocol.md`: finite everywhere but `clearance_m`
//!   (which may be +∞, never NaN or −∞), `psi_set` in [−π, π], `phi_c` within ±2π, `v_set`
//!   in [0, v_max] of the parameters in force (and `velocity` no faster), zero speed in hold;
//! - the receive counters of every `Telemetry` equal those of a standalone
//!   [`Decoder`] fed the same bytes (with the documented moves: requests refused at the wire
//!   out of `rx_bad_payload` into `bad_params`/`bad_mission`, Ticks back in time into it),
//!   and `bad_params`/`bad_mission` are the planner's refusals plus those;
//! - every request (`Params`, `Mission`, `ChartObstacle`, `ChartClear`, `MissionCount`,
//!   `MissionItem`, `Survey`) with a trusted header gets exactly one `Reply`, by the end of
//!   the period after the input.
//!
//! A fifth of the inputs are fed in random pieces (as reads of a serial port come), so frames
//! are also cut across `on_bytes` calls.
//!
//! With `--nocapture` it prints a one-line summary: inputs, frames accepted per type, refused
//! per reason, periods and how many of them planned.
//!
//! Environment (both optional):
//! - `VPF_FUZZ_SEED`: the seed, decimal or `0x` hex (default [`DEFAULT_SEED`]);
//! - `VPF_FUZZ_INPUTS`: the number of inputs (default [`DEFAULT_INPUTS`]).
//!
//! ```text
//! VPF_FUZZ_SEED=7 VPF_FUZZ_INPUTS=1000000 cargo test --release --test fuzz -- --nocapture
//! ```

use std::collections::BTreeMap;
use std::f32::consts::{PI, TAU};
use std::panic::{catch_unwind, AssertUnwindSafe};

use vpf::field::Shape;
use vpf::guidance::{OneThreadRuntime, RuntimeConfig};
use vpf::link::{
    BeliefRepr, BodyVelocity, ChartClearRepr, ChartObstacleRepr, CommandRepr, Contact, ContactKind,
    ContactList, ContactsRepr, CostUnit, Decoder, Direction, Error, Header, LogLevel, LogRepr,
    Message, MessageType, MissionCountRepr, MissionItemRepr, NavRepr, Outcome, ReplyRepr,
    SurveyRepr, TelemetryCounters, TelemetryRepr, TickRepr, MAX_FRAME,
};
use vpf::planner::{
    Formation, HoldReason, MissionEnd, MissionProgress, Survey, Waypoint, MAX_GHOSTS,
};
use vpf::sonar::Scanline;
use vpf::{Command, Mission, Mode, NavState, Params, Strategy, Vec2};

/// The seed when `VPF_FUZZ_SEED` is not set.
const DEFAULT_SEED: u64 = 0x5EED_F022_0000_0001;
/// The number of inputs when `VPF_FUZZ_INPUTS` is not set.
const DEFAULT_INPUTS: u64 = 50_000;
/// Inputs per run (a fresh runtime each run).
const INPUTS_PER_RUN: u64 = 150;

// ---------------------------------------------------------------------------------------------
// PRNG

/// xorshift64* (Vigna 2016), seeded through splitmix64.
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Self {
        let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        Rng(if z == 0 { 1 } else { z })
    }

    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform in 0..n (n > 0).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }

    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit() as f32
    }

    fn byte(&mut self) -> u8 {
        self.next() as u8
    }

    fn pick<T: Copy>(&mut self, xs: &[T]) -> T {
        xs[self.below(xs.len())]
    }

    fn bytes(&mut self, n: usize) -> Vec<u8> {
        (0..n).map(|_| self.byte()).collect()
    }
}

// ---------------------------------------------------------------------------------------------
// Framing, written from docs/protocol.md (independent of `vpf::link`'s own CRC, COBS and code)

/// CRC-16/CCITT-FALSE.
fn crc16(data: &[u8]) -> u16 {
    let mut crc = 0xFFFFu16;
    for &b in data {
        crc ^= u16::from(b) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 {
                (crc << 1) ^ 0x1021
            } else {
                crc << 1
            };
        }
    }
    crc
}

/// COBS, canonical; with `trailing_empty`, the accepted variant with an empty block after a
/// final full one.
fn cobs_encode(data: &[u8], trailing_empty: bool) -> Vec<u8> {
    let mut out = Vec::with_capacity(data.len() + data.len() / 254 + 2);
    let mut block: Vec<u8> = Vec::with_capacity(254);
    for (i, &b) in data.iter().enumerate() {
        if b == 0 {
            out.push(block.len() as u8 + 1);
            out.append(&mut block);
        } else {
            block.push(b);
            if block.len() == 254 {
                out.push(0xFF);
                out.append(&mut block);
                if i == data.len() - 1 {
                    if trailing_empty {
                        out.push(0x01);
                    }
                    return out;
                }
            }
        }
    }
    out.push(block.len() as u8 + 1);
    out.append(&mut block);
    out
}

fn cobs_decode(enc: &[u8]) -> Option<Vec<u8>> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < enc.len() {
        let code = usize::from(enc[i]);
        if code == 0 || i + code > enc.len() {
            return None;
        }
        out.extend_from_slice(&enc[i + 1..i + code]);
        i += code;
        if code < 0xFF && i < enc.len() {
            out.push(0);
        }
    }
    Some(out)
}

/// A frame before framing: header fields and payload.
#[derive(Clone, Debug)]
struct Frame {
    version: u8,
    ty: u8,
    seq: u16,
    payload: Vec<u8>,
}

impl Frame {
    /// header ‖ payload ‖ CRC.
    fn raw(&self) -> Vec<u8> {
        let mut raw = vec![self.version, self.ty];
        raw.extend_from_slice(&self.seq.to_le_bytes());
        raw.extend_from_slice(&self.payload);
        let crc = crc16(&raw);
        raw.extend_from_slice(&crc.to_le_bytes());
        raw
    }
}

/// Writes a good CRC over all but the last two bytes.
fn fix_crc(raw: &mut [u8]) {
    if raw.len() >= 2 {
        let n = raw.len() - 2;
        let crc = crc16(&raw[..n]);
        raw[n..].copy_from_slice(&crc.to_le_bytes());
    }
}

/// GF(2⁸) modulo 0x11D: powers of α = 2 (twice round, so sums of logarithms need no
/// reduction) and logarithms.
fn gf_tables() -> ([u8; 510], [u8; 256]) {
    let (mut exp, mut log) = ([0u8; 510], [0u8; 256]);
    let mut x = 1u16;
    for i in 0..255 {
        exp[i] = x as u8;
        exp[i + 255] = x as u8;
        log[x as usize] = i as u8;
        x <<= 1;
        if x & 0x100 != 0 {
            x ^= 0x11D;
        }
    }
    (exp, log)
}

/// The 16 Reed–Solomon parity bytes of `data` (generator roots α⁰ … α¹⁵), by polynomial
/// division as docs/protocol.md §12 does it.
fn rs_parity(data: &[u8]) -> [u8; 16] {
    let (exp, log) = gf_tables();
    let mul = |a: u8, b: u8| {
        if a == 0 || b == 0 {
            0
        } else {
            exp[usize::from(log[a as usize]) + usize::from(log[b as usize])]
        }
    };
    // g(x), highest power first.
    let mut g = vec![1u8];
    for &root in &exp[..16] {
        let mut next = g.clone();
        next.push(0);
        for (k, &c) in g.iter().enumerate() {
            next[k + 1] ^= mul(c, root);
        }
        g = next;
    }
    let mut rem = [0u8; 16];
    for &d in data {
        let f = d ^ rem[0];
        rem.copy_within(1.., 0);
        rem[15] = 0;
        for (r, &gk) in rem.iter_mut().zip(&g[1..]) {
            *r ^= mul(gk, f);
        }
    }
    rem
}

/// The PN9 whitening sequence's first `n` bytes (x⁹ + x⁵ + 1, seed all ones, LSB first).
fn pn9(n: usize) -> Vec<u8> {
    let mut s = 0x1FFu16;
    (0..n)
        .map(|_| {
            let out = s as u8;
            for _ in 0..8 {
                s = (s >> 1) | (((s ^ (s >> 5)) & 1) << 8);
            }
            out
        })
        .collect()
}

/// A raw frame's coded form (to the firmware), without the delimiter; `key` picks each chunk's
/// key among the values that do not occur in it (any is allowed).
fn code(raw: &[u8], key: impl Fn(&[u8]) -> u8) -> Vec<u8> {
    let blocks = raw.len().div_ceil(239).max(1);
    let mut cw = raw.to_vec();
    for j in 0..blocks {
        let data: Vec<u8> = raw.iter().skip(j).step_by(blocks).copied().collect();
        cw.extend(rs_parity(&data));
    }
    let white = pn9(cw.len());
    for (b, w) in cw.iter_mut().zip(white) {
        *b ^= w;
    }
    let mut out = Vec::new();
    for chunk in cw.chunks(254) {
        let k = key(chunk);
        out.push(k);
        out.extend(chunk.iter().map(|&b| if b == 0 { k } else { b }));
    }
    out
}

/// The largest absent value (the reference encoder's choice).
fn largest_key(chunk: &[u8]) -> u8 {
    (1..=255u8)
        .rev()
        .find(|v| !chunk.contains(v))
        .unwrap_or(0xFF)
}

/// The smallest absent value: also a valid key.
fn smallest_key(chunk: &[u8]) -> u8 {
    (1..=255u8).find(|v| !chunk.contains(v)).unwrap_or(1)
}

/// A raw frame on the wire to the firmware: coded, delimited.
fn wire(raw: &[u8]) -> Vec<u8> {
    let mut w = code(raw, largest_key);
    w.push(0);
    w
}

// ---------------------------------------------------------------------------------------------
// Valid messages of every type, with the library's encoders

/// What the generators need to know about the run.
struct Ctx<'a> {
    p: Vec2,
    v: Vec2,
    t: u64,
    sonar: bool,
    /// Raw frames the firmware sent (firmware → host), to be echoed back.
    pool: &'a [Vec<u8>],
}

fn payload_of(m: &Message<'_>) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME];
    let n = m
        .emit(&mut buf)
        .unwrap_or_else(|e| panic!("the generator made an invalid {m:?}: {e}"));
    buf[..n].to_vec()
}

fn shape(rng: &mut Rng, c: Vec2) -> Shape {
    let angle = rng.range(-PI, PI);
    let s = match rng.below(4) {
        0 => Shape::circle(c, rng.range(0.2, 5.0)),
        1 => Shape::rectangle(
            c,
            Vec2::new(rng.range(0.1, 4.0), rng.range(0.1, 4.0)),
            angle,
        ),
        2 => Shape::ellipse(
            c,
            Vec2::new(rng.range(0.1, 4.0), rng.range(0.1, 4.0)),
            angle,
        ),
        _ => {
            let n = 3 + rng.below(6);
            let r = rng.range(0.5, 5.0);
            let pts: Vec<Vec2> = (0..n)
                .map(|i| c + Vec2::from_angle(angle + TAU * i as f32 / n as f32) * r)
                .collect();
            Shape::polygon(&pts)
        }
    };
    s.unwrap_or_else(|_| Shape::circle(c, 1.0).expect("a valid circle"))
}

/// A point 3–40 m from the vehicle.
fn near(rng: &mut Rng, p: Vec2) -> Vec2 {
    p + Vec2::from_angle(rng.range(-PI, PI)) * rng.range(3.0, 40.0)
}

fn sane_params(rng: &mut Rng) -> Params {
    let strategy = if rng.chance(0.8) {
        Strategy::Vpf
    } else {
        rng.pick(&[Strategy::Multipoint, Strategy::Navfn])
    };
    Params {
        sigma_m: rng.range(10.0, 60.0),
        v_max: rng.range(0.3, 3.0),
        f_max: rng.range(0.2, 2.0),
        strategy,
        route_cell_m: rng.pick(&[0.0, 2.0]),
        seed: rng.next() as u32,
        ..Params::default()
    }
}

fn nav(t: u64, p: Vec2, v: Vec2) -> NavRepr {
    NavRepr {
        time_ms: t,
        nav: NavState {
            position: p,
            heading: if v.norm() > 0.01 { v.angle() } else { 0.0 },
            velocity: v,
        },
        body: None,
    }
}

/// Host → firmware types, weighted.
const TO_FIRMWARE: [(u8, u32); 11] = [
    (0x01, 16), // Nav
    (0x02, 10), // Scanline
    (0x03, 10), // Contacts
    (0x04, 8),  // Mission
    (0x05, 10), // ChartObstacle
    (0x06, 4),  // ChartClear
    (0x07, 8),  // Params
    (0x08, 6),  // Tick
    (0x09, 4),  // MissionCount
    (0x0A, 8),  // MissionItem
    (0x0B, 3),  // Survey
];
const TO_HOST: [u8; 5] = [0x81, 0x82, 0x83, 0x84, 0x85];

fn pick_type(rng: &mut Rng) -> u8 {
    if rng.chance(0.2) {
        return rng.pick(&TO_HOST);
    }
    let total: u32 = TO_FIRMWARE.iter().map(|&(_, w)| w).sum();
    let mut x = rng.below(total as usize) as u32;
    for &(ty, w) in &TO_FIRMWARE {
        if x < w {
            return ty;
        }
        x -= w;
    }
    0x01
}

fn formation(rng: &mut Rng) -> Option<Formation> {
    rng.chance(0.2).then(|| Formation {
        q: rng.pick(&[3, 4, 6]),
        lattice_m: rng.range(0.5, 50.0),
        orientation: rng.range(-PI, PI),
        attraction: rng.range(0.01, 100.0),
    })
}

fn mission_end(rng: &mut Rng) -> MissionEnd {
    if rng.chance(0.6) {
        MissionEnd::Hold
    } else {
        MissionEnd::Loiter {
            radius_m: rng.range(1.0, 30.0),
            clockwise: rng.chance(0.5),
        }
    }
}

/// A valid payload of type `ty`.
fn payload(rng: &mut Rng, ctx: &Ctx<'_>, ty: u8) -> Vec<u8> {
    let t = ctx.t;
    match ty {
        0x01 => {
            let time_ms = match rng.below(10) {
                0 => t.saturating_sub(rng.below(5000) as u64),
                1 => t + rng.below(2000) as u64,
                _ => t,
            };
            let mut n = nav(time_ms, ctx.p, ctx.v);
            if rng.chance(0.3) {
                n.nav.position = ctx.p + Vec2::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0));
                n.nav.heading = rng.range(-TAU, TAU) * 0.999;
                n.nav.velocity = Vec2::from_angle(rng.range(-PI, PI)) * rng.range(0.0, 5.0);
            }
            if rng.chance(0.3) {
                n.body = Some(BodyVelocity {
                    u: rng.range(-20.0, 20.0),
                    v: rng.range(-20.0, 20.0),
                    r: rng.range(-TAU, TAU) * 0.999,
                });
            }
            payload_of(&Message::Nav(n))
        }
        0x02 => {
            let n = match rng.below(4) {
                0 => 1,
                1 => 512,
                _ => 1 + rng.below(512),
            };
            let bins: Vec<u8> = (0..n)
                .map(|_| if rng.chance(0.05) { rng.byte() } else { 0 })
                .collect();
            let step = rng.range(0.001, 0.2) * if rng.chance(0.5) { -1.0 } else { 1.0 };
            payload_of(&Message::Scanline(Scanline {
                time_ms: t,
                bearing_rad: rng.range(-TAU, TAU) * 0.999,
                step_rad: step,
                range_m: rng.range(0.5, 200.0),
                bins: &bins,
            }))
        }
        0x03 => {
            let n = if rng.chance(0.2) { 8 } else { rng.below(9) };
            let contacts: Vec<Contact> = (0..n)
                .map(|_| Contact {
                    id: rng.below(64) as u16,
                    kind: if rng.chance(0.7) {
                        ContactKind::Obstacle
                    } else {
                        ContactKind::Vehicle
                    },
                    shape: {
                        let c = near(rng, ctx.p);
                        shape(rng, c)
                    },
                    velocity: Vec2::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0)),
                    confidence: rng.range(0.0, 1.0),
                })
                .collect();
            payload_of(&Message::Contacts(ContactsRepr {
                time_ms: t,
                contacts: ContactList::new(&contacts),
            }))
        }
        0x04 => {
            let goal = ctx.p + Vec2::from_angle(rng.range(-PI, PI)) * rng.range(10.0, 80.0);
            let formation = rng.chance(0.2).then(|| Formation {
                q: rng.pick(&[3, 4, 6]),
                lattice_m: rng.range(0.5, 50.0),
                orientation: rng.range(-PI, PI),
                attraction: rng.range(0.01, 100.0),
            });
            let m = Message::Mission(Mission { goal, formation });
            let mut buf = [0u8; MAX_FRAME];
            match m.emit(&mut buf) {
                Ok(n) => buf[..n].to_vec(),
                Err(_) => payload_of(&Message::Mission(Mission {
                    goal,
                    formation: None,
                })),
            }
        }
        0x05 => {
            let c = near(rng, ctx.p);
            payload_of(&Message::ChartObstacle(ChartObstacleRepr {
                id: rng.below(40) as u16,
                a_plus: rng.range(0.01, 10.0),
                shape: shape(rng, c),
            }))
        }
        0x06 => payload_of(&Message::ChartClear(if rng.chance(0.3) {
            ChartClearRepr::All
        } else {
            ChartClearRepr::One(rng.below(40) as u16)
        })),
        0x07 => {
            let mut p = payload_of(&Message::Params(sane_params(rng)));
            if rng.chance(0.2) {
                // One parameter anywhere (usually out of its range): the planner refuses it.
                let o = rng.pick(&param_f32());
                p[o..o + 4].copy_from_slice(&rng.range(-10.0, 1000.0).to_le_bytes());
            }
            p
        }
        0x08 => {
            let time_ms = match rng.below(20) {
                0 => t.saturating_sub(1 + rng.below(1000) as u64),
                1 => t,
                2 => u64::MAX,
                3 => 0,
                4 => t + (rng.next() >> 24),
                _ => t + rng.below(300) as u64,
            };
            payload_of(&Message::Tick(TickRepr { time_ms }))
        }
        0x09 => {
            // Short uploads mostly, so that random items complete some.
            let count = if rng.chance(0.8) {
                1 + rng.below(3) as u8
            } else {
                1 + rng.below(16) as u8
            };
            let m = Message::MissionCount(MissionCountRepr {
                count,
                end: mission_end(rng),
                formation: formation(rng),
            });
            payload_of(&m)
        }
        0x0A => {
            let p = near(rng, ctx.p);
            let w = Waypoint::new(p, rng.range(0.5, 5.0))
                .and_then(|w| w.with_speed(rng.chance(0.3).then(|| rng.range(0.1, 3.0))))
                .expect("a valid waypoint");
            let slots = if rng.chance(0.8) { 3 } else { 16 };
            payload_of(&Message::MissionItem(MissionItemRepr {
                index: rng.below(slots) as u8,
                waypoint: w,
            }))
        }
        0x0B => {
            let width_m = rng.range(5.0, 60.0);
            let s = Survey {
                corner: near(rng, ctx.p),
                length_m: rng.range(5.0, 80.0),
                width_m,
                heading: rng.range(-PI, PI),
                spacing_m: width_m / rng.range(0.5, 6.9),
                radius_m: rng.range(0.5, 5.0),
                speed: rng.chance(0.3).then(|| rng.range(0.1, 3.0)),
            };
            payload_of(&Message::Survey(SurveyRepr {
                survey: s,
                end: mission_end(rng),
                formation: formation(rng),
            }))
        }
        0x81 => {
            let mut command = Command::hold(HoldReason::NoMission, rng.range(-PI, PI));
            command.clearance_m = f32::INFINITY;
            payload_of(&Message::Command(CommandRepr {
                time_ms: t,
                command,
            }))
        }
        0x82 => payload_of(&Message::Telemetry(TelemetryRepr {
            time_ms: t,
            mode: Mode::Transit,
            obstacles: 1,
            agents: 0,
            ghost_depth: 0,
            step_cost: rng.next() as u32,
            cost_unit: CostUnit::Unknown,
            counters: TelemetryCounters::default(),
            ping360: Default::default(),
            current: Default::default(),
            mission: MissionProgress::default(),
        })),
        0x83 => payload_of(&Message::Reply(ReplyRepr::accepted(Header {
            msg_type: MessageType::Params,
            seq: rng.next() as u16,
        }))),
        0x84 => {
            let text = ["", "ok", "planner: ghost goal-point pushed ✓", "Grüße"];
            payload_of(&Message::Log(LogRepr::truncated(
                LogLevel::Warn,
                rng.pick(&text),
            )))
        }
        _ => {
            let rows = rng.below(17);
            let bitmap = rng.bytes(8 * rows);
            payload_of(&Message::Belief(BeliefRepr {
                time_ms: t,
                cell_bits: 0.5f32.to_bits(),
                x0: rng.next() as i32,
                y0: -32,
                bitmap: &bitmap,
            }))
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Layout knowledge for the mutations (payload offsets from docs/protocol.md §5–§6)

/// Offsets of the f32 parameters in `Params`, from the parameter declaration.
fn param_f32() -> Vec<usize> {
    use vpf::params::{Kind, ParamId};
    let mut offset = 0;
    let mut out = Vec::new();
    for id in ParamId::ALL {
        if id.kind() == Kind::F32 {
            out.push(offset);
        }
        offset += id.kind().wire_len();
    }
    out
}

/// Floats of a shape starting at `o` (its kind byte); returns the shape's length.
fn shape_floats(p: &[u8], o: usize, out: &mut Vec<usize>) -> Option<usize> {
    match *p.get(o)? {
        0 => {
            out.extend((0..3).map(|i| o + 1 + 4 * i));
            Some(13)
        }
        1 | 2 => {
            out.extend((0..5).map(|i| o + 1 + 4 * i));
            Some(21)
        }
        3 => {
            let n = usize::from(*p.get(o + 1)?);
            out.extend((0..2 * n).map(|i| o + 2 + 4 * i));
            Some(2 + 8 * n)
        }
        _ => None,
    }
}

fn float_offsets(ty: u8, p: &[u8]) -> Vec<usize> {
    let mut v = Vec::new();
    match ty {
        0x01 => v.extend([8, 12, 16, 20, 24, 29, 33, 37]),
        0x02 => v.extend([8, 12, 16]),
        0x03 => {
            let mut o = 9;
            for _ in 0..p.get(8).copied().unwrap_or(0).min(8) {
                o += 3;
                let Some(s) = shape_floats(p, o, &mut v) else {
                    break;
                };
                o += s;
                v.extend([o, o + 4, o + 8]);
                o += 12;
            }
        }
        0x04 => v.extend([0, 4, 10, 14, 18]),
        0x05 => {
            v.push(2);
            shape_floats(p, 6, &mut v);
        }
        0x07 => v.extend(param_f32()),
        // MissionCount: loiter radius and the formation's; MissionItem: x, y, radius, speed;
        // Survey: rows 0–7, the loiter radius and the formation's.
        0x09 => v.extend([2, 8, 12, 16]),
        0x0A => v.extend([1, 5, 9, 13]),
        0x0B => v.extend([0, 4, 8, 12, 16, 20, 24, 28, 33, 39, 43, 47]),
        0x81 => v.extend((0..15).map(|i| 8 + 4 * i)),
        0x85 => v.push(8),
        _ => {}
    }
    v.retain(|&o| o + 4 <= p.len());
    v
}

fn special_float(rng: &mut Rng) -> f32 {
    rng.pick(&[
        f32::NAN,
        -f32::NAN,
        f32::from_bits(0x7FC0_0001),
        f32::from_bits(0xFFFF_FFFF),
        f32::INFINITY,
        f32::NEG_INFINITY,
        1e30,
        -1e30,
        -0.0,
        0.0,
        f32::from_bits(1),
        -f32::from_bits(1),
        f32::MIN_POSITIVE / 2.0,
        f32::MAX,
        f32::MIN,
        f32::EPSILON,
        100_000.0,
        100_000.01,
        TAU,
        TAU + 1e-3,
        -TAU - 1e-3,
        20.0,
        20.001,
    ])
}

fn put_u16(p: &mut [u8], o: usize, v: u16) {
    if let Some(d) = p.get_mut(o..o + 2) {
        d.copy_from_slice(&v.to_le_bytes());
    }
}

fn put_u8(p: &mut [u8], o: usize, v: u8) {
    if let Some(d) = p.get_mut(o) {
        *d = v;
    }
}

/// Sets a count, length, flag or enum field to an edge value, and in half the cases makes the
/// payload's length agree with it (so the parse goes past the length check).
fn mutate_count(rng: &mut Rng, ty: u8, p: &mut Vec<u8>) {
    let agree = rng.chance(0.5);
    match ty {
        0x01 => {
            let f = rng.pick(&[0u8, 1, 2, 0x80, 0xFF, 3]);
            put_u8(p, 28, f);
            if agree {
                p.resize(if f & 1 != 0 { 41 } else { 29 }, 0);
            }
        }
        0x02 => {
            let cur = p.len().saturating_sub(22) as u16;
            let n = rng.pick(&[
                0u16,
                1,
                511,
                512,
                513,
                0xFFFF,
                cur.wrapping_sub(1),
                cur.wrapping_add(1),
            ]);
            put_u16(p, 20, n);
            if agree {
                p.resize(22 + usize::from(n).min(700), 0);
            }
        }
        0x03 => {
            let cur = p.get(8).copied().unwrap_or(0);
            if rng.chance(0.6) || cur == 0 {
                let n = rng.pick(&[
                    0u8,
                    1,
                    7,
                    8,
                    9,
                    255,
                    cur.wrapping_sub(1),
                    cur.wrapping_add(1),
                ]);
                put_u8(p, 8, n);
                if agree && n > cur {
                    // One more circle entry per extra count (28 bytes each).
                    for _ in cur..n.min(12) {
                        p.extend_from_slice(&[1, 0, 0, 0]);
                        for f in [5.0f32, 5.0, 1.0, 0.0, 0.0, 0.5] {
                            p.extend_from_slice(&f.to_le_bytes());
                        }
                    }
                }
            } else {
                // The first entry's shape kind, or its polygon's vertex count.
                let o = 9 + 3;
                if p.get(o) == Some(&3) {
                    put_u8(p, o + 1, rng.pick(&[0u8, 1, 2, 3, 8, 9, 255]));
                } else {
                    put_u8(p, o, rng.pick(&[0u8, 1, 2, 3, 4, 255]));
                }
            }
        }
        0x04 => {
            if rng.chance(0.5) {
                let f = rng.pick(&[0u8, 1, 2, 0xFF]);
                put_u8(p, 8, f);
                if agree {
                    p.resize(if f & 1 != 0 { 22 } else { 9 }, 0);
                }
            } else {
                put_u8(p, 9, rng.pick(&[0u8, 3, 4, 5, 6, 255]));
            }
        }
        0x05 => {
            if p.get(6) == Some(&3) && rng.chance(0.6) {
                let n = rng.pick(&[0u8, 1, 2, 3, 8, 9, 255]);
                put_u8(p, 7, n);
                if agree {
                    p.resize(8 + 8 * usize::from(n), 0);
                }
            } else {
                put_u8(p, 6, rng.pick(&[0u8, 1, 2, 3, 4, 255]));
            }
        }
        0x06 => {
            put_u8(p, 0, rng.pick(&[0u8, 1, 2, 255]));
            put_u16(p, 1, rng.pick(&[0u16, 1, 0xFFFF]));
        }
        0x07 => {
            let (o, vals): (usize, &[u8]) = rng.pick(&[
                (8, &[0u8, 3, 4, 32, 33, 255][..]),
                (37, &[0, 1, 2, 255][..]),
                (74, &[0, 4, 5, 255][..]),
                (79, &[0, 1, 2, 3, 255][..]),
                (88, &[0, 2, 3, 32, 33, 255][..]),
                (105, &[0, 1, 2, 16, 17, 255][..]),
            ]);
            put_u8(p, o, rng.pick(vals));
        }
        0x09 | 0x0B => {
            // The count, the end code or the flags (a formation that is or is not there).
            let base = if ty == 0x09 { 1 } else { 32 };
            match rng.below(3) {
                0 if ty == 0x09 => put_u8(p, 0, rng.pick(&[0u8, 1, 2, 16, 17, 255])),
                0 | 1 => put_u8(p, base, rng.pick(&[0u8, 1, 2, 3, 255])),
                _ => {
                    let f = rng.pick(&[0u8, 1, 2, 0xFF]);
                    put_u8(p, base + 5, f);
                    if agree {
                        p.resize(base + 6 + if f & 1 != 0 { 13 } else { 0 }, 0);
                    }
                }
            }
        }
        0x0A => put_u8(p, 0, rng.pick(&[0u8, 1, 2, 15, 16, 17, 255])),
        0x81 => {
            let o = rng.pick(&[68usize, 69, 70]);
            put_u8(p, o, rng.pick(&[0u8, 1, 4, 5, 6, 7, 255]));
        }
        0x82 => {
            let o = rng.pick(&[76usize, 77, 78, 79, 80, 81]);
            put_u8(p, o, rng.pick(&[0u8, 1, 4, 5, 6, 7, 8, 9, 32, 33, 255]));
        }
        0x83 => {
            let o = rng.pick(&[0usize, 3, 4, 5]);
            put_u8(p, o, rng.pick(&[0u8, 1, 2, 3, 5, 6, 8, 9, 0x81, 255]));
        }
        0x84 => {
            if rng.chance(0.5) {
                put_u8(p, 0, rng.pick(&[0u8, 3, 4, 255]));
            } else {
                let extra = rng
                    .pick(&[96usize, 97, 200])
                    .saturating_sub(p.len().saturating_sub(1));
                p.extend(std::iter::repeat_n(b'a', extra));
                if p.len() > 1 && rng.chance(0.5) {
                    let at = 1 + rng.below(p.len() - 1);
                    p[at] = rng.pick(&[0xC3, 0xFF, 0x80, 0xED]);
                }
            }
        }
        _ => {
            let rows = rng.pick(&[0u8, 1, 16, 17, 255]);
            put_u8(p, 20, rows);
            if agree {
                p.resize(21 + 8 * usize::from(rows), 0);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Mutations

/// A frame of a random type, valid or mutated; returns its raw bytes (header ‖ payload ‖ CRC,
/// before coding).
fn gen_raw(rng: &mut Rng, ctx: &Ctx<'_>, seq: &mut u16) -> Vec<u8> {
    *seq = seq.wrapping_add(1);
    if !ctx.pool.is_empty() && rng.chance(0.05) {
        // The firmware's own output, looped back.
        let mut raw = ctx.pool[rng.below(ctx.pool.len())].clone();
        if rng.chance(0.5) {
            let i = rng.below(raw.len());
            raw[i] ^= 1 << rng.below(8);
            if rng.chance(0.8) {
                fix_crc(&mut raw);
            }
        }
        return raw;
    }
    let ty = pick_type(rng);
    let mut f = Frame {
        version: vpf::link::PROTOCOL_VERSION,
        ty,
        seq: *seq,
        payload: payload(rng, ctx, ty),
    };
    let mut mutations = match rng.below(10) {
        0..=2 => 0,
        3..=6 => 1,
        7 | 8 => 2,
        _ => 3 + rng.below(4),
    };
    if ty == 0x02 && !ctx.sonar {
        // A run without sonar stays so (one scanline starts the sonar watch, which holds the
        // vehicle until a whole sweep): break the head step or the range.
        let o = rng.pick(&[12usize, 16]);
        let bad = rng.pick(&[f32::NAN, f32::INFINITY, -0.0, 0.0, 1e30, f32::from_bits(1)]);
        f.payload[o..o + 4].copy_from_slice(&bad.to_le_bytes());
    }
    while mutations > 0 {
        mutations -= 1;
        mutate_frame(rng, ctx, &mut f, seq);
    }
    let mut raw = f.raw();
    // Raw-level damage after the CRC was computed.
    if rng.chance(0.12) {
        let flips = 1 + rng.below(3);
        for _ in 0..flips {
            let i = rng.below(raw.len());
            raw[i] ^= 1 << rng.below(8);
        }
        // Most of the time the CRC is fixed up so the damage reaches the parsers.
        if rng.chance(0.75) {
            fix_crc(&mut raw);
        }
    }
    if rng.chance(0.03) {
        // A bad CRC on an otherwise valid frame.
        let n = raw.len();
        raw[n - 1 - rng.below(2)] ^= 1 + rng.below(255) as u8;
    }
    raw
}

fn mutate_frame(rng: &mut Rng, ctx: &Ctx<'_>, f: &mut Frame, seq: &mut u16) {
    let p = &mut f.payload;
    match rng.below(12) {
        // Bit flips in the payload.
        0 => {
            for _ in 0..1 + rng.below(4) {
                if !p.is_empty() {
                    let i = rng.below(p.len());
                    p[i] ^= 1 << rng.below(8);
                }
            }
        }
        // Byte overwrites.
        1 => {
            if !p.is_empty() {
                let i = rng.below(p.len());
                let any = rng.byte();
                p[i] = rng.pick(&[0x00, 0xFF, 0x80, 0x7F, 0x01, any]);
            }
        }
        // Special floats at documented offsets (or anywhere).
        2..=4 => {
            let offs = float_offsets(f.ty, p);
            let o = if !offs.is_empty() && rng.chance(0.85) {
                rng.pick(&offs)
            } else if p.len() >= 4 {
                rng.below(p.len() - 3)
            } else {
                return;
            };
            p[o..o + 4].copy_from_slice(&special_float(rng).to_le_bytes());
        }
        // Counts, lengths, flags and codes at their edges.
        5 | 6 => mutate_count(rng, f.ty, p),
        // Truncation.
        7 => {
            let n = if rng.chance(0.5) {
                p.len().saturating_sub(1)
            } else {
                rng.below(p.len() + 1)
            };
            p.truncate(n);
        }
        // Extension.
        8 => {
            let n = if rng.chance(0.5) {
                1
            } else {
                1 + rng.below(40)
            };
            let more = rng.bytes(n);
            p.extend_from_slice(&more);
        }
        // Splice with another frame's payload (maybe of another type).
        9 => {
            let ty = pick_type(rng);
            let other = payload(rng, ctx, ty);
            let i = rng.below(p.len() + 1);
            let j = rng.below(other.len() + 1);
            p.truncate(i);
            p.extend_from_slice(&other[j..]);
        }
        // Header: version, type (the payload read as another type's), sequence.
        10 => match rng.below(3) {
            0 => f.version = rng.pick(&[0u8, 5, 7, 0x85, 0xFF]),
            1 => {
                f.ty = rng.pick(&[
                    0x00, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0x09, 0x0A, 0x0B, 0x0C,
                    0x7F, 0x80, 0x81, 0x82, 0x83, 0x84, 0x85, 0x86, 0xFF,
                ])
            }
            _ => {
                f.seq = rng.pick(&[0, 0xFFFF, f.seq.wrapping_sub(1)]);
                *seq = f.seq;
            }
        },
        // Times at their edges.
        _ => {
            if matches!(f.ty, 0x01 | 0x02 | 0x03 | 0x08) && p.len() >= 8 {
                let any = rng.next();
                let t = rng.pick(&[
                    0,
                    u64::MAX,
                    u64::MAX - 1,
                    ctx.t + 1000,
                    ctx.t + 1001,
                    ctx.t.saturating_sub(1),
                    any,
                ]);
                p[..8].copy_from_slice(&t.to_le_bytes());
            }
        }
    }
}

/// One input: the bytes of one or more frames, garbage, or both.
fn gen_input(rng: &mut Rng, ctx: &Ctx<'_>, seq: &mut u16) -> Vec<u8> {
    let mut out = Vec::new();
    if rng.chance(0.3) {
        out.push(0);
    }
    match rng.below(20) {
        // Frames glued: one to four, some delimiters left out.
        0..=2 => {
            let n = 2 + rng.below(3);
            for k in 0..n {
                let raw = gen_raw(rng, ctx, seq);
                out.extend(code(&raw, largest_key));
                if k + 1 == n || rng.chance(0.6) {
                    out.push(0);
                }
            }
        }
        // Raw garbage, with or without delimiters.
        3 => {
            let n = 1 + rng.below(900);
            let zeros = rng.pick(&[0.0, 0.01, 0.05, 0.2]);
            out.extend((0..n).map(|_| if rng.chance(zeros) { 0 } else { rng.byte() }));
        }
        // Oversize: more than MAX_FRAME bytes without a delimiter, then a valid frame.
        4 => {
            let n = rng.pick(&[MAX_FRAME - 2, MAX_FRAME - 1, MAX_FRAME, MAX_FRAME + 1])
                + if rng.chance(0.3) { rng.below(800) } else { 0 };
            out.extend((0..n).map(|_| 1 + rng.below(255) as u8));
            out.push(0);
            let raw = gen_raw(rng, ctx, seq);
            out.extend(wire(&raw));
        }
        // Frames in COBS, the framing of the other direction (and of versions up to 6): noise to
        // the firmware. Non-canonical COBS: runs of 0x01, or long full blocks.
        5 => {
            if rng.chance(0.5) {
                let n = rng.pick(&[600usize, 663, 664, 665, 666, 667, 700]);
                out.extend(std::iter::repeat_n(1u8, n));
            } else {
                for _ in 0..1 + rng.below(4) {
                    out.push(0xFF);
                    out.extend((0..254).map(|_| 1 + rng.below(255) as u8));
                }
            }
            out.push(0);
        }
        // Damage on the wire: wrong bytes (up to 8 per block are corrected, more are not),
        // a wrong key, a stray 0x00, a cut frame, a byte too many, another valid key.
        6 => {
            let raw = gen_raw(rng, ctx, seq);
            let mut enc = code(&raw, largest_key);
            match rng.below(6) {
                0 | 1 => {
                    let hits = rng.pick(&[1usize, 4, 8, 9, 16, 40]);
                    for _ in 0..hits {
                        let i = rng.below(enc.len());
                        let b = enc[i] ^ (1 + rng.below(255) as u8);
                        if b != 0 {
                            enc[i] = b;
                        }
                    }
                }
                2 => {
                    let at = 255 * rng.below(enc.len().div_ceil(255));
                    let k = enc[at] ^ (1 << rng.below(8));
                    if k != 0 {
                        enc[at] = k;
                    }
                }
                3 => {
                    let i = rng.below(enc.len());
                    enc[i] = 0;
                }
                4 => {
                    if rng.chance(0.5) {
                        enc.truncate(rng.below(enc.len()));
                    } else {
                        let i = rng.below(enc.len() + 1);
                        enc.insert(i, 1 + rng.below(255) as u8);
                    }
                }
                _ => enc = code(&raw, smallest_key),
            }
            out.extend(enc);
            out.push(0);
        }
        // A COBS frame in the non-canonical encoding with a trailing 0x01: noise here.
        7 => {
            let raw = gen_raw(rng, ctx, seq);
            out.extend(cobs_encode(&raw, rng.chance(0.5)));
            out.push(0);
        }
        // Garbage before a frame, with or without a resync delimiter.
        8 => {
            let n = 1 + rng.below(20);
            out.extend((0..n).map(|_| 1 + rng.below(255) as u8));
            if rng.chance(0.5) {
                out.push(0);
            }
            let raw = gen_raw(rng, ctx, seq);
            out.extend(wire(&raw));
        }
        // One frame.
        _ => {
            let raw = gen_raw(rng, ctx, seq);
            out.extend(wire(&raw));
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// The model: a standalone decoder fed the same bytes, and what the runtime must report

fn is_request(t: MessageType) -> bool {
    matches!(
        t,
        MessageType::Params
            | MessageType::Mission
            | MessageType::ChartObstacle
            | MessageType::ChartClear
            | MessageType::MissionCount
            | MessageType::MissionItem
            | MessageType::Survey
    )
}

fn error_kind(e: &Error) -> &'static str {
    match e {
        Error::Crc => "crc",
        Error::Cobs => "cobs",
        Error::CodedLength => "coded length",
        Error::Uncorrectable => "uncorrectable",
        Error::Truncated => "short",
        Error::Oversize => "oversize",
        Error::Version(_) => "version",
        Error::UnknownType(_) => "type",
        Error::WrongDirection(_) => "direction",
        Error::Length => "length",
        Error::Field { .. } => "field",
        Error::BufferTooSmall => "buffer",
    }
}

fn type_name(t: MessageType) -> String {
    format!("{t:?}")
}

#[derive(Default)]
struct Stats {
    inputs: u64,
    runs: u64,
    bytes: u64,
    periods: u64,
    planned: u64,
    holds: BTreeMap<String, u64>,
    accepted: BTreeMap<String, u64>,
    refused: BTreeMap<&'static str, u64>,
    refused_payload: BTreeMap<String, u64>,
    replies: u64,
    non_finite_steps: u64,
}

/// The telemetry's receive counters: frames, crc, oversize, framing, unknown, bad payload,
/// corrected, uncorrectable.
type Rx = [u32; 8];

fn rx_of(c: &TelemetryCounters) -> Rx {
    [
        c.rx_frames,
        c.rx_crc_errors,
        c.rx_oversize,
        c.rx_framing_errors,
        c.rx_unknown,
        c.rx_bad_payload,
        c.rx_fec_corrected,
        c.rx_fec_uncorrectable,
    ]
}

enum Event {
    None,
    Tick(u64),
    Request(MessageType, u16, Option<f32>, bool),
    WireRequest(MessageType, u16),
    /// A `Nav` refused at the wire (counted in `bad_nav`, not `rx_bad_payload`).
    WireNav,
}

struct Model {
    dec: Decoder,
    last_tick: Option<u64>,
    last_period: Option<u64>,
    wire_params: u32,
    wire_mission: u32,
    wire_nav: u32,
    charts_refused: u32,
    ticks_refused: u32,
    /// Periods run (commands owed).
    periods: usize,
    /// Expected receive counters of each telemetry (fresh periods), this input.
    telemetry: Vec<Rx>,
    /// Requests not yet answered: (type, seq).
    outstanding: Vec<(MessageType, u16)>,
    /// Largest v_max of a valid parameter set seen in this input.
    v_max: f32,
}

impl Model {
    fn new() -> Self {
        Model {
            dec: Decoder::accepting(Direction::ToFirmware),
            last_tick: None,
            last_period: None,
            wire_params: 0,
            wire_mission: 0,
            wire_nav: 0,
            charts_refused: 0,
            ticks_refused: 0,
            periods: 0,
            telemetry: Vec::new(),
            outstanding: Vec::new(),
            v_max: 0.0,
        }
    }

    fn expected_rx(&self) -> Rx {
        let c = self.dec.counters();
        [
            c.frames,
            c.crc,
            c.oversize,
            c.framing,
            c.version + c.unknown_type,
            c.bad_payload
                .saturating_sub(self.wire_params + self.wire_mission + self.wire_nav)
                .saturating_add(self.ticks_refused),
            c.corrected,
            c.uncorrectable,
        ]
    }

    /// A period runs at `t`: it sends a command, and telemetry unless it repeats the last.
    fn period(&mut self, t: u64) {
        self.periods += 1;
        if self.last_period != Some(t) {
            self.telemetry.push(self.expected_rx());
        }
        self.last_period = Some(t);
    }

    fn push(&mut self, bytes: &[u8], stats: &mut Stats) {
        for &b in bytes {
            let event = match self.dec.push(b) {
                Outcome::Consumed => Event::None,
                Outcome::OverFull => {
                    *stats.refused.entry("oversize").or_default() += 1;
                    Event::None
                }
                Outcome::Frame(h, m) => {
                    *stats.accepted.entry(type_name(h.msg_type)).or_default() += 1;
                    match m {
                        Message::Tick(t) => Event::Tick(t.time_ms),
                        Message::Params(p) => Event::Request(
                            h.msg_type,
                            h.seq,
                            p.validate().ok().map(|_| p.v_max),
                            false,
                        ),
                        Message::ChartObstacle(c) => {
                            Event::Request(h.msg_type, h.seq, None, c.to_obstacle(0).is_err())
                        }
                        Message::Mission(_)
                        | Message::ChartClear(_)
                        | Message::MissionCount(_)
                        | Message::MissionItem(_)
                        | Message::Survey(_) => Event::Request(h.msg_type, h.seq, None, false),
                        _ => Event::None,
                    }
                }
                Outcome::Error { header, error } => {
                    *stats.refused.entry(error_kind(&error)).or_default() += 1;
                    match header {
                        Some(h) => {
                            if matches!(error, Error::Length | Error::Field { .. }) {
                                *stats
                                    .refused_payload
                                    .entry(type_name(h.msg_type))
                                    .or_default() += 1;
                            }
                            if h.msg_type.direction() == Direction::ToFirmware
                                && is_request(h.msg_type)
                            {
                                Event::WireRequest(h.msg_type, h.seq)
                            } else if h.msg_type == MessageType::Nav {
                                Event::WireNav
                            } else {
                                Event::None
                            }
                        }
                        None => Event::None,
                    }
                }
            };
            match event {
                Event::None => {}
                Event::Tick(t) => {
                    if self.last_tick.is_some_and(|l| t < l) {
                        self.ticks_refused += 1;
                    } else {
                        self.last_tick = Some(t);
                        self.period(t);
                    }
                }
                Event::Request(ty, seq, v_max, chart_refused) => {
                    self.outstanding.push((ty, seq));
                    if let Some(v) = v_max {
                        self.v_max = self.v_max.max(v);
                    }
                    self.charts_refused += u32::from(chart_refused);
                }
                Event::WireNav => self.wire_nav += 1,
                Event::WireRequest(ty, seq) => {
                    self.outstanding.push((ty, seq));
                    if ty == MessageType::Params {
                        self.wire_params += 1;
                    } else {
                        self.wire_mission += 1;
                    }
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The harness: a host in front of the runtime

/// What the firmware sent during one input.
#[derive(Default)]
struct Sent {
    commands: Vec<Command>,
    telemetry: Vec<TelemetryCounters>,
    replies: Vec<ReplyRepr>,
}

struct Harness {
    fw: OneThreadRuntime,
    model: Model,
    host: Decoder,
    seq: u16,
    /// Firmware time of the harness's last period, ms.
    t: u64,
    p: Vec2,
    v: Vec2,
    sonar: bool,
    /// Drive time with `Tick` frames (lockstep) from the start.
    lockstep: bool,
    /// The harness's last period was not a repeat (it sent telemetry).
    fresh: bool,
    sweep: u32,
    pool: Vec<Vec<u8>>,
    sent: Sent,
}

impl Harness {
    fn new(sonar: bool) -> Self {
        Harness {
            fw: OneThreadRuntime::new(
                Params::default(),
                RuntimeConfig::default(),
                CostUnit::Unknown,
            )
            .expect("default runtime"),
            model: Model::new(),
            host: Decoder::accepting(Direction::ToHost),
            seq: 0,
            t: 0,
            p: Vec2::ZERO,
            v: Vec2::ZERO,
            sonar,
            lockstep: false,
            fresh: false,
            sweep: 0,
            pool: Vec::new(),
            sent: Sent::default(),
        }
    }

    fn frame(&mut self, m: Message<'_>) -> Vec<u8> {
        self.seq = self.seq.wrapping_add(1);
        let mut buf = [0u8; MAX_FRAME];
        let n = m.emit_frame(self.seq, &mut buf).expect("a valid frame");
        buf[..n].to_vec()
    }

    /// Decodes what the firmware sent; every frame must be accepted.
    fn receive(&mut self, out: &[u8]) -> Vec<Command> {
        let mut commands = Vec::new();
        for chunk in out.split(|&b| b == 0).filter(|c| !c.is_empty()) {
            if self.pool.len() < 64 {
                if let Some(raw) = cobs_decode(chunk) {
                    self.pool.push(raw);
                }
            }
        }
        for &b in out {
            match self.host.push(b) {
                Outcome::Consumed => {}
                Outcome::Frame(_, m) => match m {
                    Message::Command(c) => commands.push(c.command),
                    Message::Telemetry(t) => self.sent.telemetry.push(t.counters),
                    Message::Reply(r) => self.sent.replies.push(r),
                    _ => {}
                },
                other => panic!("the firmware sent a frame a host refuses: {other:?}"),
            }
        }
        self.sent.commands.extend_from_slice(&commands);
        commands
    }

    /// Feeds bytes to the runtime (and to the model), as `src/host.rs` does.
    fn feed(&mut self, bytes: &[u8], stats: &mut Stats) {
        let mut out = Vec::new();
        let ran = self.fw.on_bytes(bytes, &mut || 0, &mut |f: &[u8]| {
            out.extend_from_slice(f);
            true
        });
        self.model.push(bytes, stats);
        let sent = self.receive(&out);
        assert_eq!(
            ran.len(),
            sent.len().min(4),
            "on_bytes returned {} commands but sent {}",
            ran.len(),
            sent.len()
        );
        assert!(
            ran.iter().zip(&sent).all(|(a, b)| a == b),
            "on_bytes returned other commands than it sent: {ran:?} vs {sent:?}"
        );
    }

    fn send(&mut self, m: Message<'_>, stats: &mut Stats) {
        let f = self.frame(m);
        self.feed(&f, stats);
    }

    /// The next period's time.
    fn next_time(&self) -> u64 {
        let period = u64::from(self.fw.periodic().period_ms().max(1));
        self.t
            .max(self.model.last_tick.unwrap_or(0))
            .saturating_add(period)
    }

    /// Valid navigation (and, with a sonar, a scanline of an empty sweep) for time `t`.
    fn sense(&mut self, t: u64, stats: &mut Stats) {
        let n = nav(t, self.p, self.v);
        self.send(Message::Nav(n), stats);
        if self.sonar {
            self.sweep += 1;
            let bins = [0u8; 64];
            let bearing = (self.sweep as f32 * 0.2) % TAU - PI;
            self.send(
                Message::Scanline(Scanline {
                    time_ms: t,
                    bearing_rad: bearing,
                    step_rad: 0.2,
                    range_m: 30.0,
                    bins: &bins,
                }),
                stats,
            );
        }
    }

    /// One period at the next time: a `Tick` (after a 0x00) in lockstep, `on_tick` otherwise.
    fn tick(&mut self, t: u64, stats: &mut Stats) -> Command {
        self.t = t;
        self.fresh = self.model.last_period != Some(t);
        if self.lockstep || self.fw.lockstep() {
            let mut bytes = vec![0u8];
            bytes.extend(self.frame(Message::Tick(TickRepr { time_ms: t })));
            self.feed(&bytes, stats);
        } else {
            let mut out = Vec::new();
            let cmd = self.fw.on_tick(t, &mut || 0, &mut |f: &[u8]| {
                out.extend_from_slice(f);
                true
            });
            self.model.period(t);
            let sent = self.receive(&out);
            assert_eq!(
                sent,
                vec![cmd],
                "on_tick returned another command than it sent"
            );
        }
        *self.sent.commands.last().expect("a period sends a command")
    }

    /// Checks what the firmware sent for the input just fed (and the period after it).
    fn check(&mut self, v_max_before: f32, stats: &mut Stats) {
        let sent = std::mem::take(&mut self.sent);
        assert_eq!(
            sent.commands.len(),
            self.model.periods,
            "one command per period that ran"
        );
        let planner = self.fw.periodic().planner();
        let v_max_now = planner.params().v_max;
        let bound = v_max_before.max(v_max_now).max(self.model.v_max);
        for (i, c) in sent.commands.iter().enumerate() {
            let last = i + 1 == sent.commands.len();
            // The last command was planned with the parameters in force now.
            check_command(c, if last { v_max_now } else { bound });
        }
        assert_eq!(
            sent.telemetry.len(),
            self.model.telemetry.len(),
            "one telemetry per period that is not a repeat"
        );
        for (k, (t, want)) in sent.telemetry.iter().zip(&self.model.telemetry).enumerate() {
            assert_eq!(
                rx_of(t),
                *want,
                "telemetry {k}: receive counters [frames, crc, oversize, framing, unknown, \
                 bad payload, corrected, uncorrectable] differ from a standalone decoder's (counters {t:?})"
            );
        }
        for r in &sent.replies {
            let at = self
                .model
                .outstanding
                .iter()
                .position(|&(ty, seq)| ty == r.to_type && seq == r.to_seq);
            match at {
                Some(i) => {
                    self.model.outstanding.remove(i);
                }
                None => panic!("a reply to no request: {r:?}"),
            }
        }
        stats.replies += sent.replies.len() as u64;
        // The harness's own period was fresh: everything before it has been answered.
        if self.fresh {
            let t = sent.telemetry.last().expect("telemetry");
            assert!(
                self.model.outstanding.is_empty(),
                "requests never answered: {:?} (counters {t:?})",
                self.model.outstanding
            );
            assert_eq!(t.requests_unanswered, 0);
            let p = planner.counters;
            assert_eq!(
                t.bad_params,
                p.bad_params + self.model.wire_params,
                "bad_params: the planner's {} + {} refused at the wire",
                p.bad_params,
                self.model.wire_params
            );
            assert_eq!(
                t.bad_mission,
                p.bad_mission + self.model.wire_mission + self.model.charts_refused,
                "bad_mission: the planner's {} + {} refused at the wire + {} charts refused",
                p.bad_mission,
                self.model.wire_mission,
                self.model.charts_refused
            );
            assert_eq!(t.tx_frames_dropped, 0);
            stats.non_finite_steps = stats.non_finite_steps.max(u64::from(p.non_finite));
        }
        self.model.periods = 0;
        self.model.telemetry.clear();
        self.model.v_max = 0.0;
    }
}

/// The `Command` table of docs/protocol.md, and the planner's own bounds.
fn check_command(c: &Command, v_max: f32) {
    let s = &c.setpoints;
    let finite = [
        ("psi_set", c.psi_set),
        ("v_set", c.v_set),
        ("a_c", s.a_c),
        ("v_c", s.v_c),
        ("i_surge", s.i_surge),
        ("alpha_c", s.alpha_c),
        ("omega_c", s.omega_c),
        ("phi_c", s.phi_c),
        ("target_x", c.target.x),
        ("target_y", c.target.y),
        ("force_x", c.force.x),
        ("force_y", c.force.y),
        ("velocity_x", c.velocity.x),
        ("velocity_y", c.velocity.y),
    ];
    for (name, v) in finite {
        assert!(v.is_finite(), "command {name} is not finite: {c:?}");
    }
    assert!(
        !c.clearance_m.is_nan() && c.clearance_m != f32::NEG_INFINITY,
        "command clearance is NaN or −∞: {c:?}"
    );
    assert!(c.psi_set.abs() <= PI, "psi_set outside [−π, π]: {c:?}");
    assert!(s.phi_c.abs() <= TAU, "phi_c outside ±2π: {c:?}");
    assert!(
        (0.0..=v_max).contains(&c.v_set) && c.v_set <= 20.0,
        "v_set outside [0, v_max = {v_max}]: {c:?}"
    );
    assert!(
        c.velocity.norm() <= v_max * (1.0 + 1e-5) + 1e-6,
        "velocity faster than v_max = {v_max}: {c:?}"
    );
    assert!(usize::from(c.ghost_depth) <= MAX_GHOSTS, "{c:?}");
    if let Mode::Hold(r) = c.mode {
        // Zero over ground; through the water only a hold that keeps station moves, head to
        // the current (protocol §7).
        assert_eq!(c.velocity, Vec2::ZERO, "a hold with velocity: {c:?}");
        assert!(
            r.keeps_station() || c.v_set == 0.0,
            "a hold with speed: {c:?}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// The test

fn env_u64(name: &str, default: u64) -> u64 {
    match std::env::var(name) {
        Ok(s) => {
            let s = s.trim().replace('_', "");
            let parsed = match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
                Some(hex) => u64::from_str_radix(hex, 16),
                None => s.parse(),
            };
            parsed.unwrap_or_else(|_| panic!("{name}={s} is not a number"))
        }
        Err(_) => default,
    }
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn panic_text(e: &(dyn std::any::Any + Send)) -> String {
    e.downcast_ref::<String>()
        .cloned()
        .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_else(|| "(no message)".into())
}

/// The start of a run: parameters, a mission, a chart and navigation, then a first period.
fn setup(rng: &mut Rng, h: &mut Harness, stats: &mut Stats) {
    let mut bytes = vec![0u8];
    let params = sane_params(rng);
    bytes.extend(h.frame(Message::Params(params)));
    let goal = Vec2::from_angle(rng.range(-PI, PI)) * rng.range(30.0, 80.0);
    bytes.extend(h.frame(Message::Mission(Mission {
        goal,
        formation: None,
    })));
    for id in 0..rng.below(3) {
        let c = goal * rng.range(0.3, 0.7) + Vec2::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0));
        let chart = ChartObstacleRepr {
            id: id as u16,
            a_plus: 2.5,
            shape: shape(rng, c),
        };
        bytes.extend(h.frame(Message::ChartObstacle(chart)));
    }
    h.feed(&bytes, stats);
    h.lockstep = rng.chance(0.8);
    let t = if h.lockstep { 0 } else { 100 };
    h.sense(t, stats);
    h.tick(t, stats);
    h.check(Params::default().v_max, stats);
}

#[test]
fn structure_aware_fuzz_of_the_byte_path() {
    assert_eq!(crc16(b"123456789"), 0x29B1, "the test's own CRC");
    let seed = env_u64("VPF_FUZZ_SEED", DEFAULT_SEED);
    let inputs = env_u64("VPF_FUZZ_INPUTS", DEFAULT_INPUTS);
    let started = std::time::Instant::now();
    let mut rng = Rng::new(seed);
    let mut stats = Stats::default();
    let mut done = 0u64;
    while done < inputs {
        let run = stats.runs;
        stats.runs += 1;
        let mut h = Harness::new(rng.chance(0.3));
        // The setup itself goes through the checks too.
        setup(&mut rng, &mut h, &mut stats);
        for k in 0..INPUTS_PER_RUN.min(inputs - done) {
            done += 1;
            let ctx = Ctx {
                p: h.p,
                v: h.v,
                t: h.t,
                sonar: h.sonar,
                pool: &h.pool,
            };
            let mut seq = h.seq;
            let input = gen_input(&mut rng, &ctx, &mut seq);
            h.seq = seq;
            let nav_first = rng.chance(0.2);
            let nav = rng.chance(0.9);
            stats.inputs += 1;
            stats.bytes += input.len() as u64;
            let result = catch_unwind(AssertUnwindSafe(|| {
                let v_max_before = h.fw.periodic().planner().params().v_max;
                if nav_first {
                    let t = h.next_time();
                    h.sense(t, &mut stats);
                }
                if rng.chance(0.2) {
                    // In pieces, as reads of a serial port come (frames cut anywhere).
                    let mut rest: &[u8] = &input;
                    while !rest.is_empty() {
                        let n = 1 + rng.below(rest.len().min(64));
                        h.feed(&rest[..n], &mut stats);
                        rest = &rest[n..];
                    }
                } else {
                    h.feed(&input, &mut stats);
                }
                let t = h.next_time();
                if nav && !nav_first {
                    h.sense(t, &mut stats);
                }
                let cmd = h.tick(t, &mut stats);
                h.check(v_max_before, &mut stats);
                stats.periods += 1;
                match cmd.mode {
                    Mode::Hold(r) => *stats.holds.entry(format!("{r:?}")).or_default() += 1,
                    _ => stats.planned += 1,
                }
                // The vehicle follows the command (seed 000 eq. 8, as in tests/runtime.rs).
                let dt = h.fw.periodic().planner().params().period_s;
                h.p += h.v * dt;
                h.v = cmd.velocity;
            }));
            if let Err(e) = result {
                panic!(
                    "fuzz failure: seed {seed:#x}, run {run}, input {k} (input {done} of \
                     {inputs}), {} bytes: {}\n  input: {}\n  reproduce (the run's earlier \
                     inputs matter): VPF_FUZZ_SEED={seed:#x} VPF_FUZZ_INPUTS={done} \
                     cargo test --test fuzz",
                    input.len(),
                    panic_text(&*e),
                    hex(&input)
                );
            }
            // A Tick far in the future leaves nothing to fuzz in this run.
            if h.model.last_tick.is_some_and(|t| t > u64::MAX / 4) {
                break;
            }
        }
    }
    let planned = 100.0 * stats.planned as f64 / stats.periods.max(1) as f64;
    println!(
        "fuzz: seed {seed:#x}, {} inputs in {} runs, {} bytes, {:.2} s; frames accepted (the \
         harness's own included) {:?}; \
         refused {:?}; refused payload by type {:?}; {} replies; {} harness periods, \
         {planned:.1}% planned, holds {:?}; planner non-finite steps (max in a run) {}",
        stats.inputs,
        stats.runs,
        stats.bytes,
        started.elapsed().as_secs_f64(),
        stats.accepted,
        stats.refused,
        stats.refused_payload,
        stats.replies,
        stats.periods,
        stats.holds,
        stats.non_finite_steps,
    );
}
