//! The route layer: where to go next when the straight line to the goal is blocked by
//! structure a local method cannot escape — a harbour's piers, a long wall with a distant gap,
//! a trap's walls.
//!
//! The local planners (VPF, multipoint, navfn) see a few metres around the vehicle and follow a
//! field to the goal-point; a wall across the way is a local minimum, and ghost goal-points
//! (seed 000 §III) find the way round only by trial. This layer runs in the **background**
//! (slow, preemptible, never delaying the periodic task): once per `replan_ms` of navigation
//! time it
//! 1. moves its [`grid::Grid`] with the vehicle and takes in the evidence map (charted
//!    obstacles and still contacts are marked as they arrive, and the sonar's features where
//!    the map does not reach: "Beyond the map", below);
//! 2. spreads a [`wavefront::Wavefront`] from the goal (or the window cell nearest a goal
//!    beyond the window) through free cells — first with the obstacles grown by 4 m, so
//!    the route keeps its distance; if that finds no way, or only one much longer than the
//!    straight line, again with less growth, down to only as much as keeps every way as wide
//!    as the hull (none for a small craft; a disc's octagon for a larger one, [`grow`]), and
//!    takes the widest pass whose way is at most a quarter longer than the shortest
//!    ([`acceptable`]); a large craft whose hull's pass finds none gets one more, with the
//!    obstacles as they are, and then any craft one that also steps through the cells'
//!    corners (`Router::bare_pass`; [`wavefront`], "Diagonal steps"). Keeping 4 m off on
//!    2 m cells closes every gap under about 10 m; a waypoint 26 m away behind a 5 m gap
//!    between two rocks was once reached after a 300 m tour of the field
//!    (`waypoints_through_clutter.toml`);
//! 3. walks down the wavefront from the vehicle and takes the farthest cell of the walk it can
//!    see in a straight line (`aim`);
//! 4. publishes a [`Route`] through a lock-free [`RouteSlot`].
//!
//! **Beyond the map.** The evidence map's window (64 cells of 0.5 m) reaches 12–20 m ahead
//! of the vehicle; the sonar reaches farther (the flat-fish's 40 m). Its features out there
//! reached the planner's obstacle table, but the route took in only the map (and the host's
//! contacts and charts), so it planned as if the water beyond the window were open: a
//! flat-fish was routed along a wall towards a gap the wall did not have, or at a rock it had
//! seen six times from 19 m, until the window came over them 10 m off; by then the way round
//! was a turn it could not make, its guard stopped it, and it turned on the spot (bench
//! clutter 4: 45 s of one stop; rocks are still left to the map, "Not kept" below). Each
//! feature that is a stretch of structure — a bar at
//! least 5 m long ([`STRUCTURE_HALF_M`]) — is now marked in the grid's sensed layer
//! ([`Router::feature`], [`Grid::mark_sensed`]); inside the window the map's belief replaces
//! it before every plan ([`Grid::absorb`]), so it counts only where the map does not reach,
//! and only until the window comes over it. Flat-fish with its recipe (`cargo hil bench
//! --models flatfish --params hil/recipes/flatfish.toml --seeds 170 [--trial 1]`): trial 0,
//! 1 783 → 1 832 of 2 040 (70 gained, 21 lost; wall gaps 124 → 154, U-traps and harbours
//! +6 each), contacts 1 → 1; trial 1, 1 786 → 1 815 (wall gaps 126 → 148), contacts 6 → 6.
//!
//! *Not kept:* every feature of two beams or more, circles too (rocks, and movers). Flat-fish
//! with its recipe, seeds 0–169: 1 783 → 1 849 of 2 040 — clutter 103 → 139 — but contacts
//! 1 → 9, crossing movers and the other flat-fish head-on, which the route now went round
//! where they had been, into their way. Leaving out the features on the movers the periodic
//! task has published to the map (`crate::sonar::Wakes`) made it worse: 14 contacts. Nor
//! (2026-12-06) marking a compact feature only once a later pass of the head finds it where
//! an earlier one saw it (within 1 m, 4–30 s before, in a ring of 24 sightings: 296 bytes of
//! RAM, 32 of flash; a mover at 0.3 m/s goes 1.7 m in the flat-fish's 5.8 s sweep, and a
//! logged crossing world marked 34 rocks and no mover). Clutter gained (seeds 0–169: 104 → 129
//! at trial 0, 96 → 130 at trial 1; seeds 170–305, 89 → 107), and boxes; all families,
//! 1 832 → 1 859, 1 815 → 1 846 and 1 452 → 1 482. But contacts rose 1 → 6, 6 → 11 and
//! 0 → 9, all with crossing movers and the other flat-fish head-on: the route round the rocks
//! it sees early changes where it meets the traffic, and that it meets it worse is measured,
//! not understood. Circles alone (2026-12-06): crossing, head-on and formation, seeds 0–169,
//! contacts 1 → 7; in crossing 46 every one of its 52 marks was one of the world's five
//! rocks, and the new contact was a 0.33 m/s mover that the tracker held as a rock's track
//! while it passed behind the rock, and that came out of it 2.7 m from a flat-fish its guard
//! had stopped: the marks are right; the traffic they lead it into is the tracker's problem.
//!
//! *Tried and not kept:* with every feature marked, clearing the marks where a beam looks
//! through them, so that a crossing mover's fits do not leave a trail beyond the window until
//! the map comes. Cleared
//! by every beam (to its nearest echo, or its range), wall gaps fell from 124 to 65 of 170:
//! a wall at a grazing angle returns nothing, and the beams along it cleared it. Cleared only
//! by a beam that met something farther on (an echo behind is proof of water in front),
//! seeds 0–67 of wall gaps, clutter, channels and crossings gave 226 of 272 with 2 contacts,
//! against 241 and 1 without clearing. A mover's trail out there is left to the map.
//!
//! *Tried and not kept* (2026-12-06): bringing the map out to the sonar instead, with 1 m
//! cells (`crate::sonar::EvidenceConfig::cell_m`; a 64 m window). Flat-fish with its recipe,
//! seeds 0–67: 735 → 742 of 816 (clutter 38 → 51 and boxes 44 → 53 of 68, but crossing
//! 68 → 63, head-on 68 → 65, channels 66 → 60 and wall gaps 64 → 60), contacts 0 → 6, five
//! of them a crossing mover running into a flat-fish its guard had stopped; with the guard's
//! astern tried as well (`crate::guidance::guard`, "Movers"), 739 and 5.
//!
//! *Tried and not kept:* keeping the last detour's goal-point while it leads off more than 60°
//! from the new one, is still in sight and its way is at most a quarter (and 4 cells) longer —
//! two nearly equal ways round a rock swap places as the map fills in, and a flat-fish sent one
//! way and then the other turns on the spot for minutes (bench clutter seed 10). Flat-fish with
//! its recipe, seeds 0–33: successes 333 → 324 of 408 (20 gained, 29 lost), contacts 0 → 0;
//! the turning back and forth is the field's and the guard's as much as the route's.
//!
//! *Tried and not kept:* taking in only believed map cells with a believed neighbour. One
//! spurious cell in the middle of a 5 m channel closes it on 2 m cells, and the route says
//! `Blocked` at the mouth or a bend (bench channel 433, VideoRay: one false cell 2.2 m from
//! each wall; the vehicle turned back and forth for 400 s). Without lone cells: VPF, all
//! families, seeds 400–599, successes 2 386 → 2 387 (channels 433, 419 and 479 gained, 468
//! and 501 lost), but head-on contacts 0 → 4: another VideoRay is one lone cell of the map,
//! and the route then led straight at it.
//!
//! *Tried and not kept:* the first pass's keep-off grown with the hull, so a flat-fish
//! (2.6 m in its recipe) keeps as much water beyond its hull as a VideoRay (3.5 m), 4 cells of
//! 2 m: with its recipe, all families, seeds 0–33, successes 333 → 274 of 408 (formations,
//! traps, wall gaps and serpentines went round by long ways and timed out). Nor less: 1 cell,
//! 333 → 304 with 4 contacts (box and clutter fields, where it stopped in gaps its guard would
//! not let it through). The keep-off stays 4 m whatever the hull.
//!
//! *Tried and not kept:* a large craft whose hull's passes find only a way longer than
//! [`acceptable`] of the straight line also trying the bare pass, and taking it when its way is
//! much shorter: on 2 m cells a 6.1 m gap between two rocks is two free cells, which the
//! flat-fish's hull pass (growth 1) closes, and the craft toured 150 m round the field (bench
//! clutter 11 at `--trial 1`). With its recipe, seeds 0–33 at `--trial 1`: 363 → 354, contacts
//! 2 → 3 — it was then sent at gaps it cannot pass, and its guard stopped it there. What
//! closes such gaps is the grid's quantisation (up to a cell lost on each side), not the hull.
//!
//! *Tried and not kept:* the hull's pass judged at the evidence map's resolution where the
//! map covers the window — a route cell closed when its centre is within the hull's radius
//! (2.6 m; or that and a map cell's half-diagonal, as the guard counts) of a believed cell,
//! rather than grown by whole cells. Whole cells close a gap or open a corner by up to a cell:
//! the ends of a wall the flat-fish's sonar saw 7.4 m apart at 50° to the grid left no way
//! through on 2 m cells, and the craft was sent round the wall's far end (bench wall gap 19).
//! Sent through such gaps, it came at them at an angle it could not turn out of and its
//! guard held it there: with its recipe, seeds 0–169, 1 783 → 1 788 of 2 040 (wall gaps
//! 127 → 126, 9 gained and 10 lost), contacts 4 → 4; with the half-diagonal, seeds 0–67,
//! 714 → 713.
//!
//! *Tried and not kept:* ways that turn. A craft that turns slowly pays for a turn in time,
//! a radian as much as v_max / ψ̇ metres of way (14 m for the flat-fish with its recipe); when
//! the way found turned it more than 90° (or 45°) off its heading, the way leaving the
//! vehicle more than 60° off that one's bearing was spread too (the cells nearer than the
//! aim in that sector closed), and the one whose length and turn cost less was taken — so
//! that two nearly equal ways round a wall stop swapping as the map fills in (bench wall gap
//! 19 and clutter 40 turned on the spot one way and then the other for a minute and more).
//! Clutter gained every time (seeds 0–169 at trials 0 and 1, 103 → 111 and 97 → 105 of 170;
//! seeds 170–237, 40 → 44 of 68), but harbours and head-on pairs gave it back: with its
//! recipe, seeds 0–169, 1 783 → 1 802 of 2 040 at trial 0 (contacts 4 → 5), 1 783 → 1 784 at
//! trial 1 (7 → 7); seeds 170–237, 719 → 720 of 816 (2 → 3); at 45°, seeds 0–169 at trial 0,
//! 1 794 with 7 contacts; only while the craft is at rest (under 0.2 m/s), 1 794 with 5.
//! Turning on the spot, its heading sweeps through every bearing, and a way that lay ahead for
//! a moment was taken: in head-on 7 it drove 4 m away from its goal round the other flat-fish
//! that stood in its way, turned back and ran out of time. Not worth its 1.2 KiB of flash.
//!
//! The periodic task then gives the planner `aim` as its goal-point while the route is fresh
//! and for its own goal (the goal itself when it is in plain sight); arrival is still judged at
//! the goal (`crate::planner::Planner::set_route`), and VPF cruises to a routed goal-point
//! (`crate::planner::vpf::goal_point`). When no route exists (the goal is enclosed as far as
//! the grid knows) it gets nothing: the planner runs exactly as without this layer, ghost
//! goal-points included. `Params::route_cell_m` = 0 turns the layer
//! off: the papers' planner unchanged.
//!
//! **Beside structure.** A goal a metre or two off a quay's face shares its 2 m cell with the
//! wall's echoes, so the line to it is never clear and the walk ends in a blocked cell: the
//! aim was then the centre of a cell beside the goal, and another as the vehicle moved, 1–1.5
//! m from the goal either way. A VideoRay that had arrived 1.7 m off a wall was sent back and
//! forth between two such centres at up to 1 m/s for the rest of the run (a world written by
//! hand, not generated). A way whose farthest cell in sight is the goal's own or one beside
//! it is now `Clear`: at this resolution that cell is the goal, and the last metres are the
//! local planner's and the guard's. Measured with the hold at the goal (`hil bench --families
//! berth`, `crate::planner::vpf`).
//!
//! That cell may hold the wall too, and then the wall's far side is one step from the goal:
//! a wall at 45° to the grid leaves the goal's cell open only at two corners, one on each
//! side. A VideoRay sent to a point 1.2 m off such a wall's face was routed round its end to
//! the far side and back for the whole run (a world written by hand). So the goal's
//! neighbour cells that the goal cannot see through the evidence map's believed cells (at
//! 0.5 m) are marked occupied ([`Router::close_hidden`]): the way into the goal's cell is
//! from the goal's own side.

pub mod grid;
pub mod handoff;
pub mod wavefront;

pub use grid::{Grid, Rows, ROUTE_SIDE};
pub use handoff::RouteSlot;
pub use wavefront::Wavefront;

use crate::field::Shape;
use crate::math::Vec2;
use crate::params::Params;
use crate::sonar::evidence::NEIGHBOURS;
use crate::sonar::{EvidenceMap, Feature, FeatureKind};
use wavefront::Cell;

/// Tuning of the route layer.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RouteConfig {
    /// Route cell size at start, m: 0 turns the layer off; else a whole multiple of the
    /// evidence map's cell. The window is [`ROUTE_SIDE`] cells wide (128 m at the default 2 m).
    /// The planner's `Params::route_cell_m` replaces it when parameters arrive.
    pub cell_m: f32,
    /// Navigation time between replans, ms.
    pub replan_ms: u32,
    /// A route older than this is not used (the background has stalled), ms.
    pub stale_ms: u32,
}

impl RouteConfig {
    /// The defaults, as a constant (for a board's `static` router).
    pub const DEFAULT: RouteConfig = RouteConfig {
        cell_m: 2.0,
        replan_ms: 1000,
        stale_ms: 5000,
    };
}

impl Default for RouteConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What the route says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RouteStatus {
    /// The goal (or the window's edge towards it) is in plain sight: go straight.
    Clear,
    /// Go to `aim` first.
    Detour,
    /// No way to the goal through what is believed: the local planner is on its own.
    Blocked,
}

impl RouteStatus {
    fn code(self) -> u8 {
        match self {
            RouteStatus::Clear => 1,
            RouteStatus::Detour => 2,
            RouteStatus::Blocked => 3,
        }
    }

    fn from_code(c: u8) -> Option<Self> {
        match c {
            1 => Some(RouteStatus::Clear),
            2 => Some(RouteStatus::Detour),
            3 => Some(RouteStatus::Blocked),
            _ => None,
        }
    }
}

/// One replan's result.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Route {
    /// The intermediate goal-point, m (the goal itself when `Clear`).
    pub aim: Vec2,
    /// The goal this route leads to, m.
    pub goal: Vec2,
    /// Navigation time of the replan, ms.
    pub time_ms: u64,
    /// What it says.
    pub status: RouteStatus,
}

impl Route {
    /// What the planner should head for at `now_ms` with goal `goal`, if this route (no older
    /// than `stale_ms`, for that goal) has a way: `aim` for a detour, the goal itself when it
    /// is in plain sight; `None` when there is no way or no fresh route (the planner is then
    /// on its own, as published).
    pub fn aim_for(&self, goal: Vec2, now_ms: u64, stale_ms: u32) -> Option<Vec2> {
        let fresh = now_ms.saturating_sub(self.time_ms) <= u64::from(stale_ms);
        (fresh && self.goal == goal && self.status != RouteStatus::Blocked).then_some(self.aim)
    }
}

/// Route counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RouteCounters {
    /// Replans run.
    pub replans: u32,
    /// Replans that found no way.
    pub blocked: u32,
}

/// Most wavefront layers per spread: enough for any simple path in the window.
const MAX_LAYERS: u32 = (ROUTE_SIDE * ROUTE_SIDE / 2) as u32;
/// Longest walk down the wavefront looking for the farthest visible cell.
const MAX_WALK: usize = 2 * ROUTE_SIDE;
/// Contacts slower than this are marked as still structure, m/s.
const STILL_SPEED: f32 = 0.1;
/// A sonar feature counts in the route as structure when it is a bar at least twice this
/// long, m: a wall's, a pier's or a box's side. A mover is fitted as a circle, or as a bar no
/// longer than a vehicle (another flat-fish: 3.6 m); module notes, "Beyond the map".
pub const STRUCTURE_HALF_M: f32 = 2.5;

/// The background's route planner.
#[derive(Clone, Debug)]
pub struct Router {
    cfg: RouteConfig,
    /// Cells the first pass grows obstacles by ([`keep_off_cells`]).
    keep_off: u8,
    /// Cells the last pass grows obstacles by ([`last_pass_growth`]).
    narrowest: u8,
    /// Whether the last resort steps through the cells' corners too (`Router::bare_pass`).
    corners: bool,
    grid: Grid,
    wave: Wavefront,
    /// What blocks the wavefront in the current pass (a field, not a local: 512 bytes off the
    /// background's stack).
    blocked: Rows,
    goal: Option<Vec2>,
    /// The periodic task's goal generation last followed (`Router::follow`).
    generation: u32,
    last_ms: Option<u64>,
    /// Counters.
    pub counters: RouteCounters,
}

impl Router {
    /// A router with `cfg` (a cell size that is not a whole multiple of the evidence map's is
    /// not refused here: the map is then not taken in, and only contacts and charts count).
    pub const fn new(cfg: RouteConfig) -> Self {
        Router {
            cfg,
            keep_off: keep_off_cells(cfg.cell_m),
            narrowest: 0,
            corners: true,
            grid: Grid::new(cfg.cell_m),
            wave: Wavefront::new(),
            blocked: [0; ROUTE_SIDE],
            goal: None,
            generation: 0,
            last_ms: None,
            counters: RouteCounters {
                replans: 0,
                blocked: 0,
            },
        }
    }

    /// The grid (for tests and tools).
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// Whether the layer runs.
    pub fn enabled(&self) -> bool {
        self.cfg.cell_m > 0.0
    }

    /// The planner's parameters: the cell size (`Params::route_cell_m`; 0: off; a change
    /// starts an empty grid) and the hull (`Params::agent_radius_m`), which sets how narrow a
    /// way the last pass may take ([`last_pass_growth`]).
    pub fn set_params(&mut self, prm: &Params) {
        let cell_m = prm.route_cell_m;
        if cell_m.is_finite() && cell_m >= 0.0 && cell_m != self.cfg.cell_m {
            self.cfg.cell_m = cell_m;
            self.grid = Grid::new(cell_m);
            self.last_ms = None;
        }
        self.keep_off = keep_off_cells(self.cfg.cell_m);
        self.narrowest = last_pass_growth(prm.agent_radius_m, self.cfg.cell_m, self.keep_off);
        self.corners = prm.strategy != crate::params::Strategy::Navfn;
    }

    /// A new mission goal (replanned at the next navigation), or none.
    pub fn set_goal(&mut self, goal: Option<Vec2>) {
        if self.goal != goal {
            self.goal = goal;
            self.last_ms = None;
        }
    }

    /// The periodic task's goal (`crate::planner::Planner::goal_generation`): taken when its
    /// generation changes — a waypoint mission accepted, the next waypoint — and replanned at
    /// the next navigation. (A `Mission` message sets the goal as soon as it is queued,
    /// [`Router::set_goal`]; the periodic task's same goal follows a period later and changes
    /// nothing.)
    pub fn follow(&mut self, generation: u32, goal: Option<Vec2>) {
        if generation != self.generation {
            self.generation = generation;
            self.set_goal(goal);
        }
    }

    /// A charted or sensed obstacle: still ones are marked.
    pub fn obstacle(&mut self, shape: &Shape, velocity: Vec2) {
        if self.enabled() && velocity.norm2() <= STILL_SPEED * STILL_SPEED {
            self.grid.mark(shape);
        }
    }

    /// A feature of the vehicle's own sonar, into the sensed layer if it is a stretch of
    /// structure ([`STRUCTURE_HALF_M`]; module notes, "Beyond the map").
    pub fn feature(&mut self, f: &Feature) {
        let half = match f.kind {
            FeatureKind::Rectangle { half, .. } => crate::math::max(half.x, half.y),
            FeatureKind::Circle { .. } => 0.0,
        };
        if self.enabled() && !f.faint && half >= STRUCTURE_HALF_M {
            if let Ok(shape) = f.to_shape() {
                self.grid.mark_sensed(&shape);
            }
        }
    }

    /// The chart was cleared.
    pub fn forget_charts(&mut self) {
        self.grid.forget_known();
    }

    /// New navigation: replans when `replan_ms` has passed since the last replan (or the goal
    /// changed) and returns the route to publish.
    pub fn on_nav(&mut self, p: Vec2, now_ms: u64, map: Option<&EvidenceMap>) -> Option<Route> {
        if !self.enabled() || !p.is_finite() {
            return None;
        }
        self.grid.follow(p);
        let goal = self.goal?;
        let due = self
            .last_ms
            .is_none_or(|t| now_ms < t || now_ms - t >= u64::from(self.cfg.replan_ms));
        if !due {
            return None;
        }
        self.last_ms = Some(now_ms);
        if let Some(m) = map {
            self.grid.absorb(m);
        }
        self.counters.replans = self.counters.replans.saturating_add(1);
        let (status, aim) = self.plan(p, goal, map);
        if status == RouteStatus::Blocked {
            self.counters.blocked = self.counters.blocked.saturating_add(1);
        }
        Some(Route {
            aim,
            goal,
            time_ms: now_ms,
            status,
        })
    }

    /// Steps 2–3 of the module notes.
    fn plan(&mut self, p: Vec2, goal: Vec2, map: Option<&EvidenceMap>) -> (RouteStatus, Vec2) {
        let Some(start) = self.grid.cell_of(p) else {
            return (RouteStatus::Blocked, goal);
        };
        let inside = self.grid.cell_of(goal);
        let source = inside.unwrap_or_else(|| self.grid.clamp(goal));
        if let (Some(c), Some(m)) = (inside, map) {
            self.close_hidden(goal, c, m);
        }
        if !self.choose_pass(start, source) {
            return (RouteStatus::Blocked, goal);
        }
        let end = if inside.is_some() {
            goal
        } else {
            self.grid.center(source.0, source.1)
        };
        self.aim(p, start, source, end, goal)
    }

    /// Marks occupied, in the sensed layer, the neighbours of the goal's cell `cell` whose
    /// centres the goal cannot see through the evidence map's believed cells ("Beside
    /// structure", module notes; believed cells within [`OWN_CELL_M`] of the goal hide
    /// nothing: a speckle cell on the goal is not a wall). The map's next absorb rewrites them.
    fn close_hidden(&mut self, goal: Vec2, (c, r): Cell, map: &EvidenceMap) {
        for (dc, dr) in NEIGHBOURS {
            let n = (
                c.wrapping_add_signed(dc as isize),
                r.wrapping_add_signed(dr as isize),
            );
            if map.occupied_along(goal, self.grid.center(n.0, n.1), OWN_CELL_M) {
                self.grid.mark_sensed_cell(n);
            }
        }
    }

    /// Spreads the passes, widest first, and leaves `blocked` and the wavefront holding the
    /// widest pass whose way is no longer than [`acceptable`] of the shortest found — a route
    /// that keeps its distance, unless keeping it costs a detour round the whole field (a
    /// 5 m gap between two rocks is closed by 4 m of keep-off on 2 m cells). `false` when no
    /// pass finds a way.
    fn choose_pass(&mut self, start: Cell, source: Cell) -> bool {
        let (wide, narrow) = (self.keep_off, self.narrowest);
        let passes = [wide, wide.midpoint(narrow), narrow];
        // No way is shorter than the 4-neighbour distance: a pass within reach of it is taken.
        let straight = (start.0.abs_diff(source.0) + start.1.abs_diff(source.1)) as u32;
        let mut ways = [None; 3];
        let mut spread_last = None;
        for (k, &g) in passes.iter().enumerate() {
            if k > 0 && passes.get(k - 1) == Some(&g) {
                continue;
            }
            let d = self.spread(g, start, source);
            spread_last = Some(g);
            if let (Some(d), Some(slot)) = (d, ways.get_mut(k)) {
                *slot = Some(d);
                if d <= acceptable(straight) {
                    return true;
                }
            }
        }
        let Some(shortest) = ways.iter().flatten().min().copied() else {
            return self.bare_pass(start, source);
        };
        let chosen = passes
            .iter()
            .zip(ways)
            .find(|(_, d)| d.is_some_and(|d| d <= acceptable(shortest)));
        match chosen {
            Some((&g, _)) if spread_last == Some(g) => true,
            Some((&g, _)) => self.spread(g, start, source).is_some(),
            None => false,
        }
    }

    /// The last resort when no pass found a way: the obstacles as they are, as a small craft's
    /// last pass has them, for a large craft whose hull's pass found none; then, for any
    /// craft (navfn's excepted), the same through the cells' corners too. On 2 m cells the
    /// hull's growth closes a channel a flat-fish fits that runs at 45° to the grid (9 m
    /// between the walls' centres): routed nowhere, it was left to the field, which turned it
    /// at the mouth towards the goal beyond a wall and held it there for the whole run (bench
    /// channel seed 18). A 5 m channel at 45° is closed for a VideoRay by the map's cells
    /// along its walls, bar a staircase of cells that touch at their corners: it stopped at a
    /// bend for the rest of the run (held-out channel 4013). The guard still keeps the hull
    /// off what is believed; a way too narrow for it ends where the guard stops it, as no way
    /// did. Not for navfn:
    /// its sphere world (seed 004) holds a 5 m channel's walls as rows of spheres, between
    /// which it crept up the channel, stopped by its guard most of the way (bench channel 8:
    /// 50 m in 600 s), where routed nowhere it had gone round the walls. VPF, seeds 0–199,
    /// 1000–1199, … 5000–5199 (`cargo hil bench --first-seed F --seeds 200`): 14 370 →
    /// 14 389 of 14 400 (20 channels gained, one clutter world near its time limit lost),
    /// contacts 6 → 5; the flat-fish with its recipe, run for run the same.
    fn bare_pass(&mut self, start: Cell, source: Cell) -> bool {
        if self.narrowest > 0 && self.spread(0, start, source).is_some() {
            return true;
        }
        if !self.corners {
            return false;
        }
        self.fill_blocked(0, start, source);
        let ends = (source, start);
        self.wave
            .spread(&self.blocked, ends, MAX_LAYERS, true)
            .is_some()
    }

    /// One pass: `blocked` filled with obstacles grown by `growth` cells and the wavefront
    /// spread through it; the way's length in steps, if there is one.
    fn spread(&mut self, growth: u8, start: Cell, source: Cell) -> Option<u32> {
        self.fill_blocked(growth, start, source);
        self.wave
            .spread(&self.blocked, (source, start), MAX_LAYERS, false)
    }

    /// Walks down from `start` (at most [`MAX_WALK`] steps) and returns the farthest cell of
    /// the walk seen in a straight line from `p` — found by bisection, a handful of line checks
    /// instead of one per step; `Clear` with the goal itself when the walk's end (`end`) is in
    /// sight.
    fn aim(
        &self,
        p: Vec2,
        start: Cell,
        source: Cell,
        end: Vec2,
        goal: Vec2,
    ) -> (RouteStatus, Vec2) {
        let (g, blocked) = (&self.grid, &self.blocked);
        // Cells as bytes (the window is 64 wide): 256 bytes of stack for the whole walk.
        let mut walk: heapless::Vec<(u8, u8), MAX_WALK> = heapless::Vec::new();
        let mut cell = start;
        while let Some(next) = self.wave.downhill(cell, source) {
            if walk.push((next.0 as u8, next.1 as u8)).is_err() {
                break;
            }
            cell = next;
        }
        let center = |&(c, r): &(u8, u8)| g.center(usize::from(c), usize::from(r));
        let seen = |k: usize| {
            walk.get(k)
                .is_some_and(|c| g.line_clear(blocked, p, center(c), start))
        };
        if cell == source && g.line_clear(blocked, p, end, start) {
            return (RouteStatus::Clear, goal);
        }
        let Some(&first) = walk.first() else {
            return (RouteStatus::Blocked, goal);
        };
        // The largest k with walk[k] in sight, if the first step is (a vehicle at a cell's
        // corner may not see even that: it then aims at the first step anyway).
        let (mut lo, mut hi) = (0, walk.len() - 1);
        if seen(0) {
            while lo < hi {
                let mid = (lo + hi).div_ceil(2);
                if seen(mid) {
                    lo = mid;
                } else {
                    hi = mid - 1;
                }
            }
        }
        let c = walk.get(lo).copied().unwrap_or(first);
        // A way's last step into the goal's own cell (or one beside it) is the goal at this
        // resolution ("Beside structure", module notes).
        let beside = |a: u8, b: usize| usize::from(a).abs_diff(b) <= 1;
        if cell == source && beside(c.0, source.0) && beside(c.1, source.1) {
            return (RouteStatus::Clear, goal);
        }
        (RouteStatus::Detour, center(&c))
    }
}

impl Router {
    /// Fills `blocked` for a pass: the occupied cells grown by `growth` cells, but never round
    /// the vehicle and the goal themselves; with no growth, the occupied cells as they are,
    /// the vehicle's own cell excepted. The hull's pass grows them as octagons ([`grow`]): it
    /// stands for the hull, a disc. The keep-off passes grow squares: as octagons too, routes
    /// passed nearer rocks on the diagonals, and two vehicles met more often in the same gaps
    /// (VideoRay, all families × 3 strategies, seeds 200–299: contacts 10 → 25, head-on
    /// 3 → 14; seeds 0–199: 21 → 22, successes 6 961 → 6 994).
    fn fill_blocked(&mut self, growth: u8, start: Cell, source: Cell) {
        for (r, row) in self.blocked.iter_mut().enumerate() {
            *row = self.grid.occupied_row(r);
        }
        if growth == 0 {
            if let Some(row) = self.blocked.get_mut(start.1) {
                *row &= !1u64.checked_shl(start.0 as u32).unwrap_or(0);
            }
            return;
        }
        let hull = growth == self.narrowest;
        for k in 0..growth {
            grow(&mut self.blocked, !hull || k % 2 == 1);
        }
        for (c, r) in [start, source] {
            // The 3 × 3 cells round it, set back to what is occupied there.
            let cols = (0b111u64 << c) >> 1;
            for rr in r.saturating_sub(1)..=r + 1 {
                let keep = self.grid.occupied_row(rr);
                if let Some(o) = self.blocked.get_mut(rr) {
                    *o = (*o & !cols) | (keep & cols);
                }
            }
        }
    }
}

/// Believed map cells this near the goal do not hide its neighbours from it, m.
const OWN_CELL_M: f32 = 0.5;

/// The longest way, in steps, taken to keep the route off obstacles when a way `shortest`
/// steps long passes nearer them: a quarter longer and 4 cells more.
fn acceptable(shortest: u32) -> u32 {
    shortest.saturating_add(shortest / 4).saturating_add(4)
}

/// Distance the first pass keeps the route off obstacles, m: two of the default 2 m cells.
const KEEP_OFF_M: f32 = 4.0;
/// Most cells a pass grows obstacles by.
const MAX_GROWTH: u8 = 8;

/// Cells the first pass grows obstacles by, so the route keeps [`KEEP_OFF_M`] from them
/// whatever the cell size (a finer grid is a finer route, not one that hugs obstacles): at
/// least one, at most [`MAX_GROWTH`]; 2 on the default 2 m cells, 4 on 1 m cells.
const fn keep_off_cells(cell_m: f32) -> u8 {
    // Rounded up; `as` saturates, and takes NaN (no cell size) to 0.
    let g = (KEEP_OFF_M / cell_m + 0.999) as u8;
    if g < 1 {
        1
    } else if g > MAX_GROWTH {
        MAX_GROWTH
    } else {
        g
    }
}

/// Cells the last pass grows obstacles by: the fewest that leave open only ways as wide as a
/// hull of radius `hull_m`. A way k free cells across is at least k cells wide, and growing
/// both sides by g leaves a free cell only where k ≥ 2g + 1; so g = ⌈(2·hull/cell − 1)/2⌉,
/// at least 0, at most the first pass's `keep_off`. 0 for a VideoRay (0.5 m) on 2 m cells, as
/// before; 1 for the flat-fish (2.25 m), which would otherwise be routed through 2 m gaps it
/// cannot pass and stop before them, held by the guard.
fn last_pass_growth(hull_m: f32, cell_m: f32, keep_off: u8) -> u8 {
    if !(hull_m > 0.0 && cell_m > 0.0) {
        return 0;
    }
    // `as` saturates: a negative count gives 0.
    let g = libm::ceilf((2.0 * hull_m / cell_m - 1.0) * 0.5) as u8;
    g.min(keep_off)
}

/// Grows the set cells by one cell, in place: to the four side neighbours, and with
/// `diagonal` to the four corner ones too. Alternating the two, sides first, g steps grow a
/// cell into an octagon about g cells across each way — nearer a disc of that radius than a
/// square, which grows a wall lying at 45° by √2 as much as one along the grid. One 2 m
/// square step for the flat-fish's hull closed the generated channels that run diagonally
/// (8.3 m of water between the walls), and the route said `Blocked` from the start.
fn grow(rows: &mut Rows, diagonal: bool) {
    let wide = |b: u64| b | (b << 1) | (b >> 1);
    let mut above = 0u64;
    for r in 0..ROUTE_SIDE {
        let below = rows.get(r + 1).copied().unwrap_or(0);
        if let Some(row) = rows.get_mut(r) {
            let here = *row;
            *row = if diagonal {
                wide(above) | wide(here) | wide(below)
            } else {
                above | wide(here) | below
            };
            above = here;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn router_with_wall() -> Router {
        let mut r = Router::new(RouteConfig::default());
        r.grid.follow(Vec2::ZERO);
        // A wall 40 m long across the straight line, from y = −30 to +10: the way round is
        // over its northern end.
        let wall = Shape::rectangle(Vec2::new(20.0, -10.0), Vec2::new(0.5, 20.0), 0.0).unwrap();
        r.obstacle(&wall, Vec2::ZERO);
        r
    }

    #[test]
    fn a_wall_across_the_way_gives_a_detour_round_its_open_end() {
        let mut r = router_with_wall();
        r.set_goal(Some(Vec2::new(50.0, 0.0)));
        let route = r.on_nav(Vec2::ZERO, 0, None).unwrap();
        assert_eq!(route.status, RouteStatus::Detour);
        assert!(
            route.aim.y > 10.0,
            "round the northern end: {:?}",
            route.aim
        );
        assert!(route.aim.x < 20.0 + 4.0, "{:?}", route.aim);
        // The aim is seen from the vehicle: the wall is not between them.
        assert!(route.aim.x < 19.0 || route.aim.y > 12.0);
        // No replan before `replan_ms`.
        assert_eq!(r.on_nav(Vec2::ZERO, 500, None), None);
        assert!(r.on_nav(Vec2::ZERO, 1000, None).is_some());
    }

    #[test]
    fn a_goal_beside_a_wall_is_reached_from_its_own_side() {
        // A 30 m wall 1 m thick at −44.4° to the grid; the goal 1.18 m off its south-western
        // face shares a 2 m cell with it, whose only open neighbours are its corners — one on
        // each side (`hil run`, a world written by hand: the vehicle was routed round the
        // wall's end to the far side, and back, for the whole run). The sonar sees the face
        // towards the vehicle.
        let dir = Vec2::new(0.714, -0.700);
        let far = Vec2::new(0.700, 0.714);
        let centre = Vec2::new(61.17, 1.2);
        let goal = Vec2::new(60.0, 0.0);
        let side = |v: Vec2| (v - centre).dot(far);
        for (p, face) in [
            (Vec2::new(60.3, -3.3), -0.5),
            (Vec2::new(52.5, 0.0), -0.5),
            (Vec2::new(66.7, 2.7), 0.5),
            (Vec2::new(59.7, 9.6), 0.5),
        ] {
            let map = EvidenceMap::new(crate::sonar::EvidenceConfig::default()).unwrap();
            map.follow(p);
            (-60..=60).for_each(|k| map.believe(centre + dir * (0.25 * k as f32) + far * face));
            let mut r = Router::new(RouteConfig::default());
            r.grid.follow(p);
            r.set_goal(Some(goal));
            let route = r.on_nav(p, 0, Some(&map)).unwrap();
            if side(p) < 0.0 {
                assert_eq!(route.status, RouteStatus::Clear, "{p:?}: {route:?}");
            } else {
                // Round an end of the wall, never through it to the goal.
                assert_eq!(route.status, RouteStatus::Detour, "{p:?}: {route:?}");
                assert!(
                    side(route.aim) > 0.0 || (route.aim - centre).dot(dir).abs() > 15.0,
                    "{p:?}: {route:?}"
                );
            }
        }
    }

    #[test]
    fn a_gap_too_narrow_to_keep_off_is_taken_rather_than_a_way_round_the_field() {
        // Two walls 38 m long across the line, 8 m apart at the line: rows y ∈ [−4, 4) minus
        // the cells within reach of the walls leave 4 m free; any keep-off closes it, and the
        // way round their ends is 80 m more.
        let mut r = Router::new(RouteConfig::default());
        r.grid.follow(Vec2::ZERO);
        for y in [23.0, -23.0] {
            let wall = Shape::rectangle(Vec2::new(20.0, y), Vec2::new(0.5, 19.0), 0.0).unwrap();
            r.obstacle(&wall, Vec2::ZERO);
        }
        r.set_goal(Some(Vec2::new(50.0, 0.0)));
        let route = r.on_nav(Vec2::new(0.0, 0.5), 0, None).unwrap();
        assert_ne!(route.status, RouteStatus::Blocked);
        assert!(route.aim.y.abs() < 4.0 && route.aim.x > 20.0, "{route:?}");
    }

    #[test]
    fn the_route_keeps_the_same_distance_off_whatever_the_cell() {
        assert_eq!(keep_off_cells(2.0), 2, "the default 2 m cells: as before");
        assert_eq!(keep_off_cells(1.0), 4);
        assert_eq!(keep_off_cells(0.25), MAX_GROWTH);
        assert_eq!(keep_off_cells(f32::NAN), 1);
        // The last pass: the VideoRay none, the flat-fish one 2 m cell or two 1 m cells.
        assert_eq!(last_pass_growth(0.5, 2.0, 2), 0);
        assert_eq!(last_pass_growth(2.25, 2.0, 2), 1);
        assert_eq!(last_pass_growth(2.25, 1.0, 4), 2);
    }

    #[test]
    fn open_water_and_an_enclosed_goal_leave_the_planner_alone() {
        let mut r = Router::new(RouteConfig::default());
        r.set_goal(Some(Vec2::new(500.0, 80.0)));
        let route = r.on_nav(Vec2::ZERO, 0, None).unwrap();
        assert_eq!(route.status, RouteStatus::Clear);
        assert_eq!(route.aim, Vec2::new(500.0, 80.0));
        assert_eq!(route.aim_for(route.goal, 0, 5000), Some(route.goal));
        assert_eq!(route.aim_for(route.goal, 6000, 5000), None, "stale");

        let mut r = Router::new(RouteConfig::default());
        r.grid.follow(Vec2::ZERO);
        let ring = [
            Shape::rectangle(Vec2::new(30.0, 0.0), Vec2::new(10.0, 0.5), 0.0).unwrap(),
            Shape::rectangle(Vec2::new(30.0, 20.0), Vec2::new(10.0, 0.5), 0.0).unwrap(),
            Shape::rectangle(Vec2::new(20.0, 10.0), Vec2::new(0.5, 10.0), 0.0).unwrap(),
            Shape::rectangle(Vec2::new(40.0, 10.0), Vec2::new(0.5, 10.0), 0.0).unwrap(),
        ];
        ring.iter().for_each(|s| r.obstacle(s, Vec2::ZERO));
        r.set_goal(Some(Vec2::new(30.0, 10.0)));
        let route = r.on_nav(Vec2::new(-10.0, 10.0), 0, None).unwrap();
        assert_eq!(route.status, RouteStatus::Blocked);
        assert_eq!(r.counters.blocked, 1);
    }

    #[test]
    fn the_goal_follows_the_periodic_tasks_generation_only_when_it_changes() {
        let mut r = Router::new(RouteConfig::default());
        // A `Mission` message set the goal when it was queued ...
        r.set_goal(Some(Vec2::new(50.0, 0.0)));
        assert!(r.on_nav(Vec2::ZERO, 0, None).is_some());
        // ... the periodic task's same goal a period later changes nothing (no replan).
        r.follow(1, Some(Vec2::new(50.0, 0.0)));
        assert_eq!(r.on_nav(Vec2::ZERO, 100, None), None);
        // The next waypoint (a new generation) is planned to at once.
        r.follow(2, Some(Vec2::new(50.0, 40.0)));
        let route = r.on_nav(Vec2::ZERO, 200, None).unwrap();
        assert_eq!(route.goal, Vec2::new(50.0, 40.0));
        // An old generation's goal is not taken again.
        r.follow(2, Some(Vec2::new(0.0, 99.0)));
        assert_eq!(r.on_nav(Vec2::ZERO, 300, None), None);
    }

    #[test]
    fn a_moving_contact_is_not_structure_and_off_means_nothing() {
        let mut r = router_with_wall();
        let boat = Shape::circle(Vec2::new(5.0, 0.0), 3.0).unwrap();
        r.obstacle(&boat, Vec2::new(1.0, 0.0));
        let cell = r.grid.cell_of(Vec2::new(5.0, 0.0)).unwrap();
        assert!(!r.grid.is_occupied(cell));

        let mut off = Router::new(RouteConfig::default());
        off.set_params(&Params {
            route_cell_m: 0.0,
            ..Params::default()
        });
        off.set_goal(Some(Vec2::new(50.0, 0.0)));
        assert_eq!(off.on_nav(Vec2::ZERO, 0, None), None);
    }

    #[test]
    fn a_sonar_feature_counts_as_structure_only_as_a_long_bar() {
        let at = |x: f32| Vec2::new(x, 1.0);
        let feature = |x: f32, kind: FeatureKind, faint: bool| Feature {
            center: at(x),
            radius: 3.0,
            kind,
            confidence: 0.5,
            time_ms: 0,
            beams: 6,
            runs_on: false,
            faint,
        };
        let bar = |half: f32| FeatureKind::Rectangle {
            half: Vec2::new(half, 0.5),
            angle: 0.0,
        };
        let mut r = Router::new(RouteConfig::default());
        r.grid.follow(Vec2::ZERO);
        r.feature(&feature(-30.0, bar(3.0), false));
        r.feature(&feature(30.0, bar(1.8), false));
        r.feature(&feature(40.0, FeatureKind::Circle { radius: 3.0 }, false));
        r.feature(&feature(50.0, bar(3.0), true));
        let occupied = |x: f32| r.grid.is_occupied(r.grid.cell_of(at(x)).unwrap());
        assert!(occupied(-30.0), "a wall's stretch");
        assert!(!occupied(30.0), "a bar as long as a vehicle");
        assert!(!occupied(40.0), "a circle: a rock, or a mover");
        assert!(!occupied(50.0), "a faint sighting");
    }

    #[test]
    fn growth_alternates_sides_and_corners() {
        let one = |diagonal: bool| {
            let mut rows = [0u64; ROUTE_SIDE];
            rows[10] = 1 << 10;
            grow(&mut rows, diagonal);
            rows.iter().map(|r| r.count_ones()).sum::<u32>()
        };
        assert_eq!(one(false), 5, "a cross");
        assert_eq!(one(true), 9, "a square");
    }

    /// A router for a craft of hull `hull_m` in a channel of two charted walls 60 m long at
    /// 45° to the grid, their centres `apart_m` apart, and its route to a goal 45 m up it.
    fn channel_at_45_degrees(hull_m: f32, apart_m: f32) -> Route {
        channel_at_45_degrees_for(hull_m, apart_m, crate::params::Strategy::Vpf)
    }

    /// [`channel_at_45_degrees`] for a craft flown by `strategy`.
    fn channel_at_45_degrees_for(
        hull_m: f32,
        apart_m: f32,
        strategy: crate::params::Strategy,
    ) -> Route {
        let mut r = Router::new(RouteConfig::default());
        r.set_params(&Params {
            agent_radius_m: hull_m,
            strategy,
            ..Params::default()
        });
        r.grid.follow(Vec2::ZERO);
        let axis = Vec2::from_angle(crate::math::PI / 4.0);
        let side = axis.perp() * (0.5 * apart_m);
        for s in [side, -side] {
            let wall =
                Shape::rectangle(axis * 25.0 + s, Vec2::new(30.0, 0.5), crate::math::PI / 4.0)
                    .unwrap();
            r.obstacle(&wall, Vec2::ZERO);
        }
        r.set_goal(Some(axis * 45.0));
        r.on_nav(Vec2::ZERO, 0, None).unwrap()
    }

    #[test]
    fn a_channel_at_45_degrees_ten_metres_wide_is_open_to_the_flat_fish() {
        // 10 m of water. The flat-fish's hull (2.25 m) grows the walls by one 2 m cell: a side
        // step leaves a way; a square one (corners too) closes channels at 45° narrower than
        // 12 m.
        let route = channel_at_45_degrees(2.25, 11.0);
        assert_ne!(route.status, RouteStatus::Blocked, "{route:?}");
    }

    #[test]
    fn a_narrower_channel_the_hulls_pass_closes_is_still_routed_up() {
        // 8.3 m of water (bench channel seed 18): the hull's pass closes it, the bare one does
        // not, and the way goes up the channel, not round the walls.
        let route = channel_at_45_degrees(2.6, 9.3);
        assert_ne!(route.status, RouteStatus::Blocked, "{route:?}");
        let axis = Vec2::from_angle(crate::math::PI / 4.0);
        assert!(route.aim.dot(axis) > 5.0, "{route:?}");
        assert!(route.aim.cross(axis).abs() < 4.65, "{route:?}");
    }

    #[test]
    fn a_five_metre_channel_at_45_degrees_is_routed_up_through_the_corners() {
        // 5 m of water between walls 1 m thick: on 2 m cells the walls leave only cells that
        // touch at their corners. A VideoRay's way goes up the channel through them.
        for apart in [6.0, 6.5] {
            let route = channel_at_45_degrees(0.5, apart);
            assert_ne!(route.status, RouteStatus::Blocked, "{apart} m: {route:?}");
            let axis = Vec2::from_angle(crate::math::PI / 4.0);
            assert!(route.aim.dot(axis) > 2.0, "{apart} m: {route:?}");
            assert!(route.aim.cross(axis).abs() < 2.5, "{apart} m: {route:?}");
            // Not navfn's: its sphere world creeps between the walls (`Router::bare_pass`).
            let navfn = channel_at_45_degrees_for(0.5, apart, crate::params::Strategy::Navfn);
            assert_eq!(navfn.status, RouteStatus::Blocked, "{apart} m: {navfn:?}");
        }
    }
}
