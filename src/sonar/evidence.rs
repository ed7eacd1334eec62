//! The evidence map: what the sonar has seen, as a fixed-size occupancy grid in the world frame
//! that scrolls with the vehicle.
//!
//! **Why a grid.** Feature extraction (the rest of this module) fits one circle or rectangle per
//! echo cluster. Long walls, piers, corners and touching rocks come out as a few shapes with
//! gaps between them, and a shape is forgotten when it ages out of the table: the vehicle then
//! drives through a wall its sonar swept a minute ago. The grid keeps every echo where it was
//! seen, so extended and concave structure is represented as faithfully as the beam allows,
//! and a cell is cleared only when the sonar looks at it again and sees through it (coverage,
//! not age). None of the seeds has a map: it feeds seed 000's stator PDF (eq. 9, 12) with the
//! distance to the nearest believed cell, i.e. the union of everything seen acts as one
//! obstacle (see `crate::planner::gradient`). This departs from the papers' per-obstacle sum
//! on purpose: a wall made of many cells must repel like one wall, not like many rocks.
//!
//! **Cells.** [`MAP_SIDE`]² cells of `cell_m` metres; world cell (i, j) covers
//! [i·cell, (i+1)·cell) × [j·cell, (j+1)·cell) and lives in slot (i mod N, j mod N), so moving
//! the window never copies a cell: the columns or rows that leave are cleared and reused for
//! those that enter. Each cell holds an evidence count 0 ..= `max`: an echo's leading edge adds
//! `hit`, a beam that passes through (nearer than its first echo, less `stop_short_m`; or up to
//! `free_range_m` when it returns nothing) takes `miss`; a cell is believed occupied at
//! `occupied` or more. With the defaults a cell beyond `near_m` (8 m) needs two echoes before
//! it is believed — a second look, or the neighbouring beam of the same sweep returning an echo
//! within the extractor's cluster gap of it (a surface spans beams; a spurious echo at a random
//! range is one ping) — and three looks through it undo one echo, so speckle and false targets
//! fade within a sweep while a real surface, hit on every sweep, stays. (Without the
//! neighbour rule, a box swept once from 10 m was believed in one cell of six, and the vehicle
//! met its corner before the next sweep: generated box fields, own sonar.)
//! Within `near_m` one echo is believed: there the vehicle has no time to wait for a second
//! look, and a false one costs only a detour until the next look clears it.
//!
//! **Grazing silence.** A surface met at more than about 65° from its normal returns too little
//! to pass the extractor's peak (in the simulated sonar its echo falls as ¼ + ¾·cos θ): a beam
//! that runs along a wall hears nothing, and taken as open water it cleared the wall's own
//! cells. A vehicle in a channel saw the wall ahead only at such angles, believed a gap, and
//! the route layer led it through. So a beam that hears nothing stops clearing at a believed
//! cell that is part of a surface lying within 30° of the beam (`runs_along`: a believed
//! neighbour that way); a lone echo, or a surface crossed steeply (which would have answered),
//! is cleared as before. A beam with an echo clears as before: the smear of a wall's echoes a
//! cell or two into the water (the beam's width and the heading's error at range) lies along
//! the wall too, and kept, it closed narrow channels. (`hil bench`, all families, seeds 0–199 ×
//! 3 strategies: contacts 38 → 30; successes 6 933 → 6 902, navfn's in channels 58 → 46 of 200;
//! seeds 200–299 of five families, 20 → 17; the flat-fish lost 10 of 408 successes, see
//! docs/bench-history.md. Protecting from echo beams too gave 33 and 6 889; protecting only a
//! cell with believed neighbours on both sides along the beam lost the gain, since a silent
//! beam meets a wall's believed run at its near end.)
//!
//! **Contexts.** One writer, the background (scanlines, [`EvidenceMap::observe`]), and one
//! reader, the periodic task ([`EvidenceMap::nearest`], [`EvidenceMap::row_bits`]); the
//! other way round for the movers' places ([`Wakes`]: their echoes leave no wake). Cells are
//! packed two to an `AtomicU8` (plain byte loads and stores on a Cortex-M4; the one writer
//! rewrites a byte whole), the window origin is published under a sequence counter, so neither
//! side ever waits: a reader that catches the origin mid-move simply uses no map for that period.
//!
//! **Capacity.** Fixed: [`MAP_SIDE`]² half-bytes (counts 0 ..= 15, two cells to a byte). Echoes
//! outside the window are not stored (the window follows the vehicle, re-centring when it is an
//! eighth of the side off centre).

use core::sync::atomic::{AtomicI32, AtomicU32, AtomicU8, Ordering};

use super::lookout::Lookout;
use super::wakes::Wakes;
use crate::math::{min, Vec2};

/// Cells per side of the window.
pub const MAP_SIDE: usize = 64;
/// Cells in the window.
pub const MAP_CELLS: usize = MAP_SIDE * MAP_SIDE;
const SIDE_I: i32 = MAP_SIDE as i32;
const MASK: i32 = SIDE_I - 1;
/// Farthest a [`EvidenceMap::nearest`] query looks, cells (12 m at the default 0.5 m): a
/// large craft that brakes gently needs its whole stopping distance beyond its hull in view
/// (the flat-fish at 1 m/s: 2.5 m of hull and margin, 5.4 m of reaction and braking at
/// 0.1 m/s², `Periodic::map_reach`). The scan's cost grows with the square of the reach; a
/// VideoRay's is 6 m.
pub const MAX_REACH_CELLS: i32 = 24;
/// Sectors of bearing in a [`EvidenceMap::nearest`] scan (11.25° each).
pub const SECTORS: usize = 32;
/// Re-centre when the vehicle is this many cells off the window's centre: an eighth of the
/// side, so the window holds at least [`MAX_REACH_CELLS`] cells round the vehicle in every
/// direction, for the guard's reach and the route layer's view ahead (`crate::route` plans
/// over the window). A quarter left 8 m at the leading edge: the flat-fish at 1 m/s met piers
/// and boxes nothing had believed in time (bench, seeds 0–16: contacts with still structure
/// 17 in 204 worlds, 15 with the 12 m reach alone, 1 with both).
const RECENTRE_CELLS: i32 = SIDE_I / 8;
/// How far beyond a sonar feature's extent [`EvidenceMap::runs_on`] looks for the structure it
/// is a fragment of, m.
pub const RUN_ON_M: f32 = 2.0;

/// Tuning of the evidence map. [`Default`] suits a Micron-class sonar at 0–30 m.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EvidenceConfig {
    /// Cell size, m, 0.1 ..= 5 (the window is [`MAP_SIDE`] cells wide).
    pub cell_m: f32,
    /// Evidence an echo adds to its cell, 1 ..= `max`.
    pub hit: u8,
    /// Evidence a beam passing through takes, 0 ..= `max` (0: cells are never cleared).
    pub miss: u8,
    /// Evidence at which a cell is believed occupied, 1 ..= `max`.
    pub occupied: u8,
    /// Ceiling of the evidence count, 1 ..= 15 (a cell is half a byte).
    pub max: u8,
    /// Free space along a beam stops this far short of its first echo, m, 0 ..= 5 (a beam
    /// grazing a surface crosses the surface's own cells before it returns).
    pub stop_short_m: f32,
    /// A beam with no echo clears cells out to this range, m, 0 ..= 200 (a surface met at a
    /// grazing angle may return nothing: far cells are not cleared on silence).
    pub free_range_m: f32,
    /// An echo nearer than this is believed at once, m, 0 ..= 200: near the vehicle there is
    /// no time for a second look (at 1 m/s a 9-second sweep covers 9 m), and a false one costs
    /// a detour until the next look clears it. Farther echoes need `occupied` evidence.
    pub near_m: f32,
}

/// The defaults, as a constant for `static` maps.
const DEFAULT: EvidenceConfig = EvidenceConfig {
    cell_m: 0.5,
    hit: 3,
    miss: 1,
    occupied: 5,
    max: 12,
    stop_short_m: 1.0,
    free_range_m: 10.0,
    near_m: 8.0,
};

impl Default for EvidenceConfig {
    fn default() -> Self {
        DEFAULT
    }
}

/// Which [`EvidenceConfig`] field is out of range.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EvidenceError {
    /// `cell_m`.
    CellSize,
    /// `hit`, `miss`, `occupied` or `max`.
    Counts,
    /// `stop_short_m`, `free_range_m` or `near_m`.
    Ranges,
}

impl core::fmt::Display for EvidenceError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            EvidenceError::CellSize => "evidence map cell size out of 0.1 ..= 5 m",
            EvidenceError::Counts => "evidence map hit/miss/occupied/max out of range",
            EvidenceError::Ranges => {
                "evidence map stop_short_m, free_range_m or near_m out of range"
            }
        })
    }
}

impl core::error::Error for EvidenceError {}

impl EvidenceConfig {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), EvidenceError> {
        if !(0.1..=5.0).contains(&self.cell_m) {
            return Err(EvidenceError::CellSize);
        }
        let m = self.max;
        if !(1..=15).contains(&m)
            || !(1..=m).contains(&self.hit)
            || self.miss > m
            || !(1..=m).contains(&self.occupied)
        {
            return Err(EvidenceError::Counts);
        }
        if !(0.0..=5.0).contains(&self.stop_short_m)
            || !(0.0..=200.0).contains(&self.free_range_m)
            || !(0.0..=200.0).contains(&self.near_m)
        {
            return Err(EvidenceError::Ranges);
        }
        Ok(())
    }
}

/// One ping as the map needs it: where it started, where it looked, how far it reached and the
/// ranges of its echoes (nearest first).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beam<'a> {
    /// Sensor position, world frame, m.
    pub origin: Vec2,
    /// Unit look direction, world frame.
    pub look: Vec2,
    /// The scanline's range, m.
    pub range_m: f32,
    /// The sonar hears nothing nearer than this (its blanking distance), m: the beam says
    /// nothing about those cells, so they are neither hit nor cleared — a vehicle or rock
    /// that comes that close stays believed where it was last seen.
    pub blank_m: f32,
    /// Leading-edge ranges of the detected echoes, m, nearest first.
    pub echoes: &'a [f32],
    /// Bit k set: echo k continues an echo of the previous beam of the sweep (the same surface
    /// seen twice), so its cell is believed at once.
    pub seconded: u8,
    /// Bit k set: echo k is a vehicle the host reports (`crate::sonar::known`): the free
    /// water ends there, but its cell gets no hit.
    pub vehicles: u8,
}

/// The window's lower-left world cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Window {
    /// World cell index of the window's first column.
    pub x0: i32,
    /// World cell index of the window's first row.
    pub y0: i32,
}

impl Window {
    fn contains(self, i: i32, j: i32) -> bool {
        (i.wrapping_sub(self.x0) as u32) < MAP_SIDE as u32
            && (j.wrapping_sub(self.y0) as u32) < MAP_SIDE as u32
    }
}

/// The shared evidence grid. Put one in a `static` on a board (it is `Sync`); see the module
/// notes for who may call what.
pub struct EvidenceMap {
    /// Two cells per byte (a count is at most 15): the low nibble holds the even slot.
    cells: [AtomicU8; MAP_CELLS / 2],
    x0: AtomicI32,
    y0: AtomicI32,
    /// Odd while the writer moves the window.
    seq: AtomicU32,
    /// Whether the window has been placed (the first pose places it).
    placed: AtomicU8,
    cfg: EvidenceConfig,
    /// How far the sonar last saw clear along each bearing ([`Lookout`]), written with the cells.
    lookout: Lookout,
    /// Where the movers are ([`Wakes`]): written by the periodic task, read by `observe`.
    wakes: Wakes,
}

/// A believed-occupied cell near the vehicle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Near {
    /// The cell's centre, world frame, m.
    pub center: Vec2,
    /// Squared distance from the query point to the centre, m².
    pub d2: f32,
}

#[allow(clippy::declare_interior_mutable_const)]
const EMPTY: AtomicU8 = AtomicU8::new(0);

fn floor_i(x: f32) -> i32 {
    // Positions are validated to ±100 km, cells ≥ 0.1 m: within i32. `as` saturates anyway.
    libm::floorf(x) as i32
}

/// The sector (0 ..= [`SECTORS`] − 1, counter-clockwise from +x) of cell offset (di, dj),
/// without trigonometry: the octant from the signs and which is larger, the quarter of the
/// octant from |min|/|max| against tan 11.25°, 22.5°, 33.75° (in 1/65536).
fn sector(di: i32, dj: i32) -> usize {
    const TAN: [i64; 3] = [13_036, 27_146, 43_790];
    let (ax, ay) = (i64::from(di.unsigned_abs()), i64::from(dj.unsigned_abs()));
    let (lo, hi) = if ax >= ay { (ay, ax) } else { (ax, ay) };
    let k = TAN.iter().filter(|&&t| (lo << 16) > t * hi).count();
    // Within the first quadrant: 0 ..= 7 from +x.
    let q = if ax >= ay { k } else { 7 - k };
    match (di >= 0, dj >= 0) {
        (true, true) => q,
        (false, true) => 15 - q,
        (false, false) => 16 + q,
        (true, false) => 31 - q,
    }
}

/// Bit offset of slot `s`'s nibble in its byte.
fn nibble(s: usize) -> u8 {
    ((s & 1) as u8) * 4
}

fn slot(i: i32, j: i32) -> usize {
    ((j & MASK) * SIDE_I + (i & MASK)) as usize
}

impl EvidenceMap {
    /// An empty map (`cfg` is checked by [`EvidenceMap::new`]; this `const` one takes the
    /// defaults, for statics).
    pub const fn empty() -> Self {
        EvidenceMap {
            cells: [EMPTY; MAP_CELLS / 2],
            x0: AtomicI32::new(0),
            y0: AtomicI32::new(0),
            seq: AtomicU32::new(0),
            placed: AtomicU8::new(0),
            cfg: DEFAULT,
            lookout: Lookout::new(),
            wakes: Wakes::new(),
        }
    }

    /// An empty map with a checked configuration.
    pub fn new(cfg: EvidenceConfig) -> Result<Self, EvidenceError> {
        cfg.validate()?;
        Ok(EvidenceMap {
            cfg,
            ..EvidenceMap::empty()
        })
    }

    /// Its configuration.
    pub fn config(&self) -> &EvidenceConfig {
        &self.cfg
    }

    /// Cell size, m.
    pub fn cell_m(&self) -> f32 {
        self.cfg.cell_m
    }

    /// The window as last published, or `None` before the first pose or while it moves.
    pub fn window(&self) -> Option<Window> {
        if self.placed.load(Ordering::Acquire) == 0 {
            return None;
        }
        let s1 = self.seq.load(Ordering::Acquire);
        let w = Window {
            x0: self.x0.load(Ordering::Relaxed),
            y0: self.y0.load(Ordering::Relaxed),
        };
        let s2 = self.seq.load(Ordering::Acquire);
        (s1 == s2 && s1.is_multiple_of(2)).then_some(w)
    }

    fn cell_of(&self, p: Vec2) -> (i32, i32) {
        let k = 1.0 / self.cfg.cell_m;
        (floor_i(p.x * k), floor_i(p.y * k))
    }

    fn center_of(&self, i: i32, j: i32) -> Vec2 {
        let c = self.cfg.cell_m;
        Vec2::new((i as f32 + 0.5) * c, (j as f32 + 0.5) * c)
    }

    fn value(&self, i: i32, j: i32) -> u8 {
        let s = slot(i, j);
        self.cells
            .get(s / 2)
            .map_or(0, |c| (c.load(Ordering::Relaxed) >> nibble(s)) & 0xF)
    }

    /// Whether world cell (i, j) is believed occupied (false outside `w`).
    pub fn is_occupied(&self, w: Window, i: i32, j: i32) -> bool {
        w.contains(i, j) && self.value(i, j) >= self.cfg.occupied
    }

    /// Forgets everything (the window stays).
    pub fn clear(&self) {
        for c in &self.cells {
            c.store(0, Ordering::Relaxed);
        }
        self.lookout.clear();
    }

    /// Where the sonar last looked in each direction, and how far it saw clear.
    pub fn lookout(&self) -> &Lookout {
        &self.lookout
    }

    /// The movers whose echoes add no evidence (the periodic task publishes them: [`Wakes`]).
    pub fn wakes(&self) -> &Wakes {
        &self.wakes
    }

    /// How far ahead of `p` on `heading` the beam the lookout keeps for that bearing saw clear
    /// for a hull `beside_m` wide either side, m ([`Lookout::clear_ahead`] on this map's cells);
    /// `None` if the sonar never looked that way.
    pub fn clear_ahead(&self, p: Vec2, heading: f32, beside_m: f32) -> Option<f32> {
        self.lookout
            .clear_ahead(p, heading, beside_m, self.cfg.cell_m)
    }

    // ---- The writer's side (background) ----

    /// Believes the cell at `p` (writer only): an echo there was seconded by the next beam.
    /// Not one on a believed mover ([`Wakes`]).
    pub fn believe(&self, p: Vec2) {
        let Some(w) = self.window() else { return };
        if self.wakes.covers(p) {
            return;
        }
        let (i, j) = self.cell_of(p);
        if w.contains(i, j) {
            self.set(i, j, self.value(i, j).max(self.cfg.occupied));
        }
    }

    /// Keeps the window centred on `p` (writer only): when `p` is an eighth of the side off
    /// centre, the window moves and the cells that leave it are cleared for those that enter.
    pub fn follow(&self, p: Vec2) {
        let (ci, cj) = self.cell_of(p);
        let want = Window {
            x0: ci.saturating_sub(SIDE_I / 2),
            y0: cj.saturating_sub(SIDE_I / 2),
        };
        if self.placed.load(Ordering::Relaxed) == 0 {
            self.clear();
            self.publish(want);
            self.placed.store(1, Ordering::Release);
            return;
        }
        let old = Window {
            x0: self.x0.load(Ordering::Relaxed),
            y0: self.y0.load(Ordering::Relaxed),
        };
        let (dx, dy) = (
            want.x0.saturating_sub(old.x0),
            want.y0.saturating_sub(old.y0),
        );
        if dx.abs() < RECENTRE_CELLS && dy.abs() < RECENTRE_CELLS {
            return;
        }
        // The slots of the columns and rows that leave are cleared for those that enter
        // (readers of the old window see far-edge cells empty a moment early: harmless).
        if dx.abs() >= SIDE_I || dy.abs() >= SIDE_I {
            self.clear();
        } else {
            for i in leaving(old.x0, want.x0) {
                (0..SIDE_I).for_each(|j| self.set(i, j, 0));
            }
            for j in leaving(old.y0, want.y0) {
                (0..SIDE_I).for_each(|i| self.set(i, j, 0));
            }
        }
        self.publish(want);
    }

    fn publish(&self, w: Window) {
        self.seq.fetch_add(1, Ordering::AcqRel);
        self.x0.store(w.x0, Ordering::Relaxed);
        self.y0.store(w.y0, Ordering::Relaxed);
        self.seq.fetch_add(1, Ordering::AcqRel);
    }

    fn set(&self, i: i32, j: i32, v: u8) {
        let s = slot(i, j);
        if let Some(c) = self.cells.get(s / 2) {
            // One writer: a plain read-modify-write of the shared byte loses nothing, and a
            // reader sees either nibble before or after, never a torn one.
            let shift = nibble(s);
            let old = c.load(Ordering::Relaxed);
            c.store(
                (old & !(0xF << shift)) | ((v & 0xF) << shift),
                Ordering::Relaxed,
            );
        }
    }

    /// Puts one ping in the map (writer only): misses along the beam up to its first echo (less
    /// `stop_short_m`) or to `free_range_m` when it returned nothing, a hit at every echo
    /// (enough to be believed within `near_m`) but one on a believed mover ([`Wakes`]).
    /// Cost: O(range / cell) byte updates.
    pub fn observe(&self, beam: &Beam<'_>) {
        let Some(w) = self.window() else { return };
        let cfg = self.cfg;
        if !(beam.origin.is_finite() && beam.look.is_finite() && beam.range_m.is_finite()) {
            return;
        }
        let silent = beam.echoes.is_empty();
        let seen_to = beam.echoes.first().copied().unwrap_or(beam.range_m);
        self.lookout
            .record(beam.origin, beam.look, seen_to, cfg.cell_m);
        let free_to = match beam.echoes.first() {
            Some(&r) => r - cfg.stop_short_m,
            None => min(beam.range_m, cfg.free_range_m),
        };
        if cfg.miss > 0 && free_to > 0.0 {
            // Half-cell steps visit every cell the ray crosses (corners aside); each cell once.
            let step = 0.5 * cfg.cell_m;
            let n = min(free_to / step, 4.0 * MAP_SIDE as f32) as u32;
            // Silence clears from the blanking distance out. Tried and not kept: clearing
            // nothing within 2 m on silence, for another VideoRay inside the blanking distance,
            // which shadows the cell it was last seen as (VPF head-on 1154): crossing and
            // head-on, seeds 1000–1199, contacts 3 → 2 with 3 gone and 2 new.
            let first = libm::ceilf(beam.blank_m.max(0.0) / step) as u32;
            let mut last = None;
            for k in first..=n {
                let p = beam.origin + beam.look * (k as f32 * step);
                let (i, j) = self.cell_of(p);
                if last == Some((i, j)) || !w.contains(i, j) {
                    continue;
                }
                last = Some((i, j));
                let v = self.value(i, j);
                // A believed surface this ray runs along: its silence is the grazing angle.
                if silent && v >= cfg.occupied && self.runs_along(w, i, j, beam.look) {
                    break;
                }
                self.set(i, j, v.saturating_sub(cfg.miss));
            }
        }
        for (k, &r) in beam.echoes.iter().enumerate() {
            if !(r.is_finite() && r >= 0.0 && r <= beam.range_m) {
                continue;
            }
            if k < 8 && beam.vehicles & (1 << k) != 0 {
                continue;
            }
            let p = beam.origin + beam.look * r;
            if self.wakes.covers(p) {
                continue;
            }
            let (i, j) = self.cell_of(p);
            if w.contains(i, j) {
                let seconded = k < 8 && beam.seconded & (1 << k) != 0;
                let add = if r <= cfg.near_m || seconded {
                    cfg.hit.max(cfg.occupied)
                } else {
                    cfg.hit
                };
                let v = self.value(i, j).saturating_add(add);
                self.set(i, j, v.min(cfg.max));
            }
        }
    }

    /// Whether believed cell (i, j) is part of a surface lying within 30° of direction `look`:
    /// a believed neighbour in that direction or the opposite one (of the eight; any direction
    /// has one within 22.5°).
    fn runs_along(&self, w: Window, i: i32, j: i32, look: Vec2) -> bool {
        const COS_30: f32 = 0.866;
        NEIGHBOURS.iter().any(|&(di, dj)| {
            let d = Vec2::new(di as f32, dj as f32);
            let along = look.dot(d).abs() >= COS_30 * d.norm();
            along && self.is_occupied(w, i.wrapping_add(di), j.wrapping_add(dj))
        })
    }

    // ---- The reader's side (periodic task) ----

    /// A polar scan of the map round `p`: in each of [`SECTORS`] equal sectors of bearing, the
    /// believed-occupied cell nearest `p` within `radius_m` (at most [`MAX_REACH_CELLS`]
    /// cells), nearest first, at most `out`'s capacity K of them. A cell lying wholly within
    /// `hull_m` of `p` is passed over: the vehicle's own hull is water, so an echo there is
    /// false (speckle near the head), and a cell within the sonar's blanking range is never
    /// looked through again to be cleared — believed, it held a flat-fish (2.25 m hull)
    /// "inside an obstacle" 27 m from anything, for the rest of a bench run. So is a cell
    /// whose disc (of half a cell) holds `p` itself, whatever the hull: no surface is under
    /// the vehicle's centre, and a VideoRay (0.5 m) that came to rest 0.24 m from a speckle
    /// cell's centre, not wholly within its hull, was held "inside" it for good.
    ///
    /// Why per sector and not simply the K nearest: between two piers, in a channel or in a
    /// corner, the nearest wall alone has more than K cells within reach, and the K nearest
    /// would hide every other wall from the planner and the guard. One cell per bearing is what
    /// a range scan would show — every side with something on it — and the nearest distance
    /// overall (the stator's input) is the same. One pass over the square of side 2·radius
    /// about `p`, clipped to the window: a nibble load per cell, a few integer comparisons per
    /// occupied one. Returns `false` (and leaves `out` empty) when there is no map to read.
    pub fn nearest<const K: usize>(
        &self,
        p: Vec2,
        radius_m: f32,
        hull_m: f32,
        out: &mut heapless::Vec<Near, K>,
    ) -> bool {
        out.clear();
        let Some(w) = self.window() else { return false };
        if !p.is_finite() || radius_m.is_nan() || radius_m < 0.0 {
            return false;
        }
        let (ci, cj) = self.cell_of(p);
        let cell = self.cfg.cell_m;
        let r = min(radius_m / cell, MAX_REACH_CELLS as f32) as i32;
        let r2 = r * r;
        let (i0, i1) = (
            ci.saturating_sub(r).max(w.x0),
            ci.saturating_add(r).min(w.x0 + MASK),
        );
        let (j0, j1) = (
            cj.saturating_sub(r).max(w.y0),
            cj.saturating_add(r).min(w.y0 + MASK),
        );
        // Cells that may lie wholly within the hull, or hold `p`: at most this many cells off
        // (squared).
        let half_diagonal = core::f32::consts::FRAC_1_SQRT_2 * cell;
        let inside = if hull_m > half_diagonal {
            min(hull_m / cell, MAX_REACH_CELLS as f32) as i32 + 1
        } else {
            1
        };
        let inside2 = inside * inside + 1;
        let under = |d: f32| d + half_diagonal <= hull_m || d <= 0.5 * cell;
        // Per sector: squared cell distance and the cell (d2 = i32::MAX: none yet).
        let mut best = [(i32::MAX, 0i32, 0i32); SECTORS];
        for j in j0..=j1 {
            for i in i0..=i1 {
                let (di, dj) = (i - ci, j - cj);
                let d2 = di * di + dj * dj;
                if d2 > r2 || self.value(i, j) < self.cfg.occupied {
                    continue;
                }
                if d2 <= inside2 && under((self.center_of(i, j) - p).norm()) {
                    continue;
                }
                if let Some(b) = best.get_mut(sector(di, dj)) {
                    if d2 < b.0 {
                        *b = (d2, i, j);
                    }
                }
            }
        }
        let mut all: heapless::Vec<Near, SECTORS> = heapless::Vec::new();
        for &(_, i, j) in best.iter().filter(|b| b.0 != i32::MAX) {
            let center = self.center_of(i, j);
            // SECTORS entries at most: never full.
            let _ = all.push(Near {
                center,
                d2: (center - p).norm2(),
            });
        }
        sort_by_distance(&mut all);
        for n in all.iter().take(K) {
            let _ = out.push(*n);
        }
        true
    }

    /// Whether believed structure runs on through a sonar feature at `center` of radius
    /// `extent`: believed cells lie in the ring from two half-diagonals to [`RUN_ON_M`] plus
    /// one beyond the extent, on two sides at least a right angle apart as seen from the
    /// centre. Its own echoes are believed cells within the ring's inside; a wall's fragment
    /// has the rest of the wall on both sides; a mover has at most its wake on one side (the
    /// echoes of its sightings before it was rated: [`Wakes`]) and a rock it passes on another —
    /// with any believed cell in the ring, real movers of the bench's crossing worlds lost
    /// their velocity (contacts 6 → 26 in 300 runs).
    /// Cost: O(((extent + [`RUN_ON_M`]) / cell)²) nibble loads; for the background.
    pub fn runs_on(&self, center: Vec2, extent: f32) -> bool {
        let Some(w) = self.window() else { return false };
        if !center.is_finite() || !extent.is_finite() || extent < 0.0 {
            return false;
        }
        let cell = self.cfg.cell_m;
        let half_diagonal = core::f32::consts::FRAC_1_SQRT_2 * cell;
        let inner = extent + 2.0 * half_diagonal;
        let outer = extent + RUN_ON_M + half_diagonal;
        // At most the window: extents are bounded by the extractor, but not here.
        let r = min(outer / cell + 1.0, SIDE_I as f32) as i32;
        let (ci, cj) = self.cell_of(center);
        // Bit k: a believed ring cell lies in sector k (of SECTORS) round the centre.
        let mut sides = 0u32;
        for j in cj.saturating_sub(r)..=cj.saturating_add(r) {
            for i in ci.saturating_sub(r)..=ci.saturating_add(r) {
                let d2 = (self.center_of(i, j) - center).norm2();
                if d2 > inner * inner && d2 <= outer * outer && self.is_occupied(w, i, j) {
                    sides |= 1 << sector(i - ci, j - cj);
                }
            }
        }
        // Sectors k + 8 ..= k + 24 are a right angle or more from sector k.
        (0..SECTORS as u32)
            .any(|k| sides & (1 << k) != 0 && sides & 0x1_FFFF_u32.rotate_left(k + 8) != 0)
    }

    /// Whether a believed cell's centre lies more than `inner` and at most `outer` from `p`:
    /// structure beside a one-beam echo, not the cell the echo itself made (false with no
    /// window, or for a non-finite or negative distance).
    pub fn occupied_between(&self, p: Vec2, inner: f32, outer: f32) -> bool {
        let Some(w) = self.window() else { return false };
        if !(p.is_finite() && inner >= 0.0 && outer >= inner && outer.is_finite()) {
            return false;
        }
        let cell = self.cfg.cell_m;
        let r = min(outer / cell + 1.0, SIDE_I as f32) as i32;
        let (ci, cj) = self.cell_of(p);
        for j in cj.saturating_sub(r)..=cj.saturating_add(r) {
            for i in ci.saturating_sub(r)..=ci.saturating_add(r) {
                let d2 = (self.center_of(i, j) - p).norm2();
                if d2 > inner * inner && d2 <= outer * outer && self.is_occupied(w, i, j) {
                    return true;
                }
            }
        }
        false
    }

    /// Whether the segment `a`→`b` passes through a believed cell farther than `skip_m` from
    /// `a` (false with no window), at [`ALONG_SAMPLES`] points. (Out of line: 48 bytes less
    /// flash than inlined into the route's replan.)
    #[inline(never)]
    pub fn occupied_along(&self, a: Vec2, b: Vec2, skip_m: f32) -> bool {
        let Some(w) = self.window() else { return false };
        (1..=ALONG_SAMPLES).any(|k| {
            let x = a + (b - a) * (k as f32 / ALONG_SAMPLES as f32);
            let (i, j) = self.cell_of(x);
            (x - a).norm2() > skip_m * skip_m && self.is_occupied(w, i, j)
        })
    }

    /// Row `r` (0 ..= [`MAP_SIDE`] − 1) of window `w` as a bitmap, bit k = column `w.x0 + k`.
    pub fn row_bits(&self, w: Window, r: i32) -> u64 {
        let j = w.y0.wrapping_add(r);
        (0..SIDE_I).fold(0u64, |bits, k| {
            if self.is_occupied(w, w.x0.wrapping_add(k), j) {
                bits | (1u64 << k)
            } else {
                bits
            }
        })
    }
}

/// Points [`EvidenceMap::occupied_along`] looks at: about a quarter of a 0.5 m cell apart
/// over the longest segment the route asks about, 4.2 m from a goal in a corner of its 2 m
/// cell to the centre of the diagonal neighbour beyond it.
const ALONG_SAMPLES: u32 = 32;

/// The eight neighbours of a cell (of this map's, or of the route's grid).
pub(crate) const NEIGHBOURS: [(i32, i32); 8] = [
    (1, 0),
    (1, 1),
    (0, 1),
    (-1, 1),
    (-1, 0),
    (-1, -1),
    (0, -1),
    (1, -1),
];

/// The world indices (columns or rows) that leave a window side moving from `old` to `new`.
fn leaving(old: i32, new: i32) -> core::ops::Range<i32> {
    if new >= old {
        old..new
    } else {
        new + SIDE_I..old + SIDE_I
    }
}

/// Insertion sort by d² (K ≤ a few dozen; core's sorts keep a panic path the firmware's
/// link-time check refuses).
fn sort_by_distance(out: &mut [Near]) {
    for k in 1..out.len() {
        let mut m = k;
        while m > 0 {
            let (Some(a), Some(b)) = (out.get(m - 1), out.get(m)) else {
                break;
            };
            if a.d2 <= b.d2 {
                break;
            }
            out.swap(m - 1, m);
            m -= 1;
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    fn map() -> EvidenceMap {
        let m = EvidenceMap::new(EvidenceConfig::default()).unwrap();
        m.follow(Vec2::ZERO);
        m
    }

    /// One ray.
    fn look(m: &EvidenceMap, from: Vec2, angle: f32, echo: Option<f32>) {
        let echoes: heapless::Vec<f32, 1> = echo.into_iter().collect();
        m.observe(&Beam {
            origin: from,
            look: Vec2::from_angle(angle),
            range_m: 30.0,
            blank_m: 0.0,
            echoes: &echoes,
            seconded: 0,
            vehicles: 0,
        });
    }

    /// Two rays the same way (a surface is seen by neighbouring rays).
    fn ping(m: &EvidenceMap, from: Vec2, angle: f32, echo: Option<f32>) {
        look(m, from, angle, echo);
        look(m, from, angle, echo);
    }

    #[test]
    fn a_published_mover_leaves_no_wake_and_a_rock_beside_it_is_still_seen() {
        let m = map();
        let w = m.window().unwrap();
        // A mover of radius 1 m crossing at 5 m, pinged once a metre along its track.
        for k in 0..6 {
            let at = Vec2::new(5.0, k as f32 - 2.0);
            m.wakes().publish([(at, 1.0)].into_iter());
            ping(
                &m,
                Vec2::ZERO,
                libm::atan2f(at.y, at.x),
                Some(at.norm() - 1.0),
            );
            m.believe(at - Vec2::new(1.0, 0.0));
        }
        let mut near: heapless::Vec<Near, 8> = heapless::Vec::new();
        m.nearest(Vec2::ZERO, 10.0, 0.0, &mut near);
        assert!(
            near.is_empty(),
            "a wake: {:?}",
            near.first().map(|c| c.center)
        );
        // An echo 3.2 m from the mover now published (beyond its hull and the margin) is
        // structure.
        m.wakes().publish([(Vec2::new(5.0, 3.0), 1.0)].into_iter());
        ping(&m, Vec2::ZERO, 0.0, Some(4.0));
        assert!(m.is_occupied(w, 8, 0));
    }

    #[test]
    fn two_echoes_make_a_cell_occupied_and_looks_through_it_clear_it() {
        // Beyond `near_m` (one echo is enough nearer: see the next test).
        let m = EvidenceMap::new(EvidenceConfig {
            near_m: 3.0,
            ..EvidenceConfig::default()
        })
        .unwrap();
        m.follow(Vec2::ZERO);
        look(&m, Vec2::ZERO, 0.0, Some(6.1));
        let w = m.window().unwrap();
        assert!(!m.is_occupied(w, 12, 0), "one echo may be a false target");
        look(&m, Vec2::ZERO, 0.0, Some(6.2));
        assert!(m.is_occupied(w, 12, 0));
        let mut near: heapless::Vec<Near, 8> = heapless::Vec::new();
        assert!(m.nearest(Vec2::ZERO, 10.0, 0.0, &mut near));
        assert_eq!(near.len(), 1);
        assert!((near[0].center - Vec2::new(6.25, 0.25)).norm() < 1e-6);
        // Beams that see past it (echo at 14 m) clear it.
        for _ in 0..2 {
            ping(&m, Vec2::ZERO, 0.0, Some(14.0));
        }
        assert!(!m.is_occupied(w, 12, 0));
        assert!(m.is_occupied(w, 28, 0));
    }

    #[test]
    fn silence_clears_only_near_cells_and_stops_short_of_echoes() {
        let m = map();
        ping(&m, Vec2::ZERO, 0.0, Some(15.2)); // a far surface (inside the ±16 m window)
        ping(&m, Vec2::ZERO, 0.0, Some(3.0)); // a near one
        let w = m.window().unwrap();
        for _ in 0..10 {
            ping(&m, Vec2::ZERO, 0.0, None);
        }
        assert!(!m.is_occupied(w, 6, 0), "within free_range_m: cleared");
        assert!(
            m.is_occupied(w, 30, 0),
            "beyond free_range_m: kept on silence"
        );
        // An echo at 3.2 m does not clear the cell at 3 m (stop short by 1 m).
        ping(&m, Vec2::ZERO, 0.0, Some(3.0));
        for _ in 0..10 {
            ping(&m, Vec2::ZERO, 0.0, Some(3.2));
        }
        assert!(m.is_occupied(w, 6, 0));
    }

    #[test]
    fn silence_along_a_believed_wall_does_not_clear_it_and_silence_across_it_does() {
        let m = map();
        // A wall's face along y = 2.25 (cells j = 4), x = 1 .. 8 m, and a lone echo beside it.
        (2..16).for_each(|i| m.believe(Vec2::new(0.5 * i as f32 + 0.25, 2.25)));
        m.believe(Vec2::new(3.25, 1.25));
        let w = m.window().unwrap();
        // Beams 5° off the wall, hearing nothing: it is the grazing angle, not open water.
        for _ in 0..10 {
            look(&m, Vec2::new(0.0, 1.4), 0.087, None);
        }
        assert!((2..16).all(|i| m.is_occupied(w, i, 4)), "the wall stays");
        // A beam across it that hears nothing proves it is not there.
        for _ in 0..10 {
            look(
                &m,
                Vec2::new(5.25, -3.0),
                core::f32::consts::FRAC_PI_2,
                None,
            );
        }
        assert!(!m.is_occupied(w, 10, 4), "crossed at right angles: cleared");
        assert!(m.is_occupied(w, 9, 4) && m.is_occupied(w, 11, 4));
        // A lone echo in a grazing beam's way has no wall to hide behind.
        for _ in 0..10 {
            look(&m, Vec2::new(0.0, 1.25), 0.0, None);
        }
        assert!(!m.is_occupied(w, 6, 2), "a lone echo is cleared");
    }

    #[test]
    fn a_wall_runs_on_through_its_fragment_and_a_wake_does_not() {
        let m = map();
        // A fragment of radius 1 m at (5, 0), fitted behind the face of a wall along x = 4.
        let (c, extent) = (Vec2::new(5.0, 0.0), 1.0);
        assert!(!m.runs_on(c, extent), "nothing believed");
        // Its own echoes, on the face within its extent: not structure beyond it.
        (-2..=2).for_each(|k| m.believe(Vec2::new(4.2, 0.4 * k as f32)));
        assert!(!m.runs_on(c, extent));
        // A mover's wake: last sweep's echoes on one side only.
        (0..4).for_each(|k| m.believe(Vec2::new(5.0 + 0.4 * k as f32, -2.6)));
        assert!(!m.runs_on(c, extent), "one side is a wake, not a wall");
        // The wall on both sides of it.
        for y in [-2.5, -2.0, 2.0, 2.5] {
            m.believe(Vec2::new(4.2, y));
        }
        assert!(m.runs_on(c, extent));
        // Farther than the ring's outer edge (extent + RUN_ON_M), it does not count.
        let far = map();
        for y in [-4.5, 4.5] {
            far.believe(Vec2::new(4.2, y));
        }
        assert!(!far.runs_on(c, extent));
    }

    #[test]
    fn structure_beside_a_one_beam_echo_is_found_and_its_own_cell_is_not() {
        let m = map();
        let p = Vec2::new(5.1, 0.1);
        assert!(!m.occupied_between(p, 1.0, 2.0), "nothing believed");
        // The cell the echo itself made.
        m.believe(p);
        assert!(!m.occupied_between(p, 1.0, 2.0));
        // Wall 1.5 m off: beside it; 2.6 m off: not.
        let far = map();
        far.believe(Vec2::new(5.1, 2.7));
        assert!(!far.occupied_between(p, 1.0, 2.0));
        m.believe(Vec2::new(5.1, 1.6));
        assert!(m.occupied_between(p, 1.0, 2.0));
        assert!(!m.occupied_between(Vec2::new(f32::NAN, 0.0), 1.0, 2.0));
        assert!(!m.occupied_between(p, 2.0, 1.0), "inner beyond outer");
    }

    #[test]
    fn silence_inside_the_blanking_distance_clears_nothing() {
        let m = map();
        ping(&m, Vec2::ZERO, 0.0, Some(2.1));
        let w = m.window().unwrap();
        // The sonar has come within 1.5 m of it (blanking 2 m) and hears nothing.
        for _ in 0..10 {
            m.observe(&Beam {
                origin: Vec2::new(0.6, 0.0),
                look: Vec2::new(1.0, 0.0),
                range_m: 30.0,
                blank_m: 2.0,
                echoes: &[],
                seconded: 0,
                vehicles: 0,
            });
        }
        assert!(
            m.is_occupied(w, 4, 0),
            "kept: it was inside the blanking distance"
        );
        assert!(!m.is_occupied(w, 10, 0) || !m.is_occupied(w, 12, 0));
    }

    #[test]
    fn one_echo_is_believed_within_near_m_and_only_there() {
        let m = map();
        let w = m.window().unwrap();
        look(&m, Vec2::ZERO, 0.0, Some(6.1));
        assert!(m.is_occupied(w, 12, 0), "6 m: no time for a second look");
        look(&m, Vec2::ZERO, core::f32::consts::FRAC_PI_2, Some(9.1));
        assert!(
            !m.is_occupied(w, 0, 18),
            "9 m: one echo may be a false target"
        );
    }

    #[test]
    fn nearest_keeps_the_k_nearest_in_order() {
        let m = map();
        for (k, r) in [9.0f32, 2.0, 5.0, 7.0, 3.0].iter().enumerate() {
            ping(&m, Vec2::ZERO, k as f32 * 1.2, Some(*r));
        }
        let mut near: heapless::Vec<Near, 3> = heapless::Vec::new();
        m.nearest(Vec2::ZERO, 12.0, 0.0, &mut near);
        let d: std::vec::Vec<f32> = near.iter().map(|n| n.d2.sqrt()).collect();
        assert_eq!(d.len(), 3);
        assert!(d[0] < d[1] && d[1] < d[2] && d[2] < 5.6, "{d:?}");
        // Radius bounds the search.
        m.nearest(Vec2::ZERO, 2.5, 0.0, &mut near);
        assert_eq!(near.len(), 1);
    }

    #[test]
    fn a_cell_inside_the_hull_is_passed_over_and_one_it_touches_is_not() {
        let m = map();
        m.believe(Vec2::new(0.3, 0.2));
        m.believe(Vec2::new(0.2, 2.6));
        let mut near: heapless::Vec<Near, 4> = heapless::Vec::new();
        m.nearest(Vec2::ZERO, 6.0, 0.0, &mut near);
        assert_eq!(near.len(), 2, "without a hull both");
        // A 2.25 m hull holds the cell at 0.36 m wholly; the one at 2.6 m reaches out of it.
        m.nearest(Vec2::ZERO, 6.0, 2.25, &mut near);
        assert_eq!(near.len(), 1);
        // A 0.5 m hull holds neither wholly: both count ...
        m.nearest(Vec2::ZERO, 6.0, 0.5, &mut near);
        assert_eq!(near.len(), 2);
        // ... until the vehicle stands within the first one's disc (0.07 m from its centre).
        m.nearest(Vec2::new(0.2, 0.2), 6.0, 0.5, &mut near);
        assert_eq!(near.len(), 1);
        m.nearest(Vec2::new(0.2, 0.2), 6.0, 0.0, &mut near);
        assert_eq!(near.len(), 1, "whatever the hull");
        m.nearest(Vec2::ZERO, 6.0, 2.25, &mut near);
        assert!(
            (near[0].center - Vec2::new(0.25, 2.75)).norm() < 1e-6,
            "{near:?}"
        );
    }

    #[test]
    fn a_near_wall_does_not_hide_the_one_across_the_channel() {
        let m = map();
        // A wall 1 m north (long: more cells within reach than the scan keeps) and one 3 m
        // south, each seen twice.
        for k in -40..=40 {
            let x = k as f32 * 0.1;
            for _ in 0..2 {
                m.observe(&Beam {
                    origin: Vec2::new(x, 0.0),
                    look: Vec2::new(0.0, 1.0),
                    range_m: 30.0,
                    blank_m: 0.0,
                    echoes: &[1.0],
                    seconded: 0,
                    vehicles: 0,
                });
                m.observe(&Beam {
                    origin: Vec2::new(x, 0.0),
                    look: Vec2::new(0.0, -1.0),
                    range_m: 30.0,
                    blank_m: 0.0,
                    echoes: &[3.0],
                    seconded: 0,
                    vehicles: 0,
                });
            }
        }
        let mut near: heapless::Vec<Near, 32> = heapless::Vec::new();
        m.nearest(Vec2::ZERO, 6.0, 0.0, &mut near);
        assert!(near.iter().any(|n| n.center.y > 0.9), "the north wall");
        assert!(near.iter().any(|n| n.center.y < -2.5), "the south wall too");
        assert!(
            near.first().is_some_and(|n| n.center.y > 0.9),
            "nearest first"
        );
    }

    #[test]
    fn sectors_go_round_counter_clockwise() {
        let angles = (0..64).map(|k| k as f32 * core::f32::consts::TAU / 64.0 + 0.01);
        let mut last = 0;
        for a in angles {
            let s = sector((100.0 * a.cos()) as i32, (100.0 * a.sin()) as i32);
            let want = (a / (core::f32::consts::TAU / 32.0)) as usize;
            assert!(s.abs_diff(want) <= 1, "angle {a}: sector {s}, want {want}");
            assert!(s >= last || (last == 31 && s == 0));
            last = s;
        }
    }

    #[test]
    fn the_window_follows_and_forgets_what_it_leaves() {
        let m = map();
        ping(&m, Vec2::ZERO, core::f32::consts::PI, Some(10.0)); // at x ≈ −10
        let before = m.window().unwrap();
        // 20 m east: beyond the re-centring threshold (8 cells = 4 m): the window moves.
        m.follow(Vec2::new(20.0, 0.0));
        let after = m.window().unwrap();
        assert_eq!(after.x0, before.x0 + 40);
        assert!(!m.is_occupied(after, -20, 0), "left the window");
        // Its slot now belongs to x ≈ +22 and must be empty.
        assert!(!m.is_occupied(after, -20 + 64, 0));
        // Things still inside are kept.
        let m = map();
        ping(&m, Vec2::ZERO, 0.0, Some(10.0));
        m.follow(Vec2::new(5.0, 0.0));
        let w = m.window().unwrap();
        assert!(m.is_occupied(w, 20, 0));
    }

    #[test]
    fn the_window_always_holds_the_farthest_reach_round_the_vehicle() {
        // Walked out and back on a spiral, the vehicle never has the window's
        // edge nearer than `MAX_REACH_CELLS` cells in any direction.
        let m = map();
        for k in 0..2000 {
            let t = k as f32 * 0.01;
            let p = Vec2::from_angle(5.0 * t) * (30.0 * crate::math::sin(0.5 * t));
            m.follow(p);
            let w = m.window().unwrap();
            let (ci, cj) = m.cell_of(p);
            for (di, dj) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                let (i, j) = (ci + di * MAX_REACH_CELLS, cj + dj * MAX_REACH_CELLS);
                assert!(w.contains(i, j), "at {p:?}: cell ({i}, {j}) outside {w:?}");
            }
        }
    }

    #[test]
    fn bad_input_changes_nothing() {
        let m = map();
        ping(&m, Vec2::new(f32::NAN, 0.0), 0.0, Some(3.0));
        m.observe(&Beam {
            origin: Vec2::ZERO,
            look: Vec2::new(1.0, 0.0),
            range_m: 30.0,
            blank_m: 0.0,
            echoes: &[f32::INFINITY, -1.0, 40.0],
            seconded: 0,
            vehicles: 0,
        });
        let mut near: heapless::Vec<Near, 4> = heapless::Vec::new();
        m.nearest(Vec2::ZERO, 30.0, 0.0, &mut near);
        assert!(near.is_empty());
        assert!(!m.nearest(Vec2::new(f32::NAN, 0.0), 5.0, 0.0, &mut near));
        assert!(EvidenceMap::new(EvidenceConfig {
            cell_m: 0.0,
            ..EvidenceConfig::default()
        })
        .is_err());
    }

    #[test]
    fn row_bits_match_cells() {
        let m = map();
        ping(&m, Vec2::ZERO, 0.0, Some(6.1));
        let w = m.window().unwrap();
        let r = 0 - w.y0;
        assert_eq!(m.row_bits(w, r), 1u64 << (12 - w.x0));
        assert_eq!(m.row_bits(w, r + 1), 0);
    }
}
