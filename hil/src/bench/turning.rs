//! Can a craft that turns on a radius R fly a world? A hybrid-A* search (Dolgov, Thrun,
//! Montemerlo, Diebel, *Path planning for autonomous vehicles in unknown semi-structured
//! environments*, IJRR 2010) over continuous poses (x, y, ψ) with three motion primitives of
//! [`STEP_M`] — straight on, and arcs of radius R to either side — keeping `clearance` from
//! every static obstacle, from the start pose to within [`GOAL_TOL_M`] of the goal at any
//! heading. Poses are pruned by a closed set of [`feasible::CELL_M`]-ish cells × [`HEADINGS`]
//! heading bins, so the search is complete only up to that resolution: a world it finds a way
//! through has one (every primitive's samples were checked), a world it does not may still have
//! a narrower one. That errs on the side the bench wants — a world kept for a craft is one it
//! can fly at its cruise turning radius, without slowing to turn.
//!
//! The flat-fish (`crate::sim::flatfish`) turns on ≈ 22 m at its 1 m/s cruise; at lower speed
//! it turns tighter (its yaw rate, not its radius, is what is bounded), so this is the
//! conservative reading of "fits its turning radius".

use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashSet};

use super::feasible::{Infeasible, BORDER_M, MAX_SIDE};
use crate::types::{SimObstacle, P2};

/// Length of one motion primitive, m.
pub const STEP_M: f64 = 2.0;
/// Spacing of the clearance samples along a primitive, m.
pub const SAMPLE_M: f64 = 0.5;
/// Closed-set cell, m.
pub const CLOSED_CELL_M: f64 = 1.0;
/// Heading bins of the closed set (5° each).
pub const HEADINGS: usize = 72;
/// A pose within this of the goal has arrived, m.
pub const GOAL_TOL_M: f64 = 3.0;
/// Most poses expanded before the search gives up (as infeasible).
pub const MAX_EXPANSIONS: usize = 2_000_000;
/// Grid of the blocked test, m.
const GRID_M: f64 = 0.5;

#[derive(Clone, Copy)]
struct Pose {
    p: P2,
    psi: f64,
}

#[derive(Clone, Copy)]
struct Open {
    f: f64,
    g: f64,
    at: usize,
}

impl PartialEq for Open {
    fn eq(&self, o: &Self) -> bool {
        self.f == o.f
    }
}

impl Eq for Open {}

impl Ord for Open {
    fn cmp(&self, o: &Self) -> Ordering {
        o.f.total_cmp(&self.f)
    }
}

impl PartialOrd for Open {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// The blocked cells of the static obstacles grown by `clearance` (as `feasible` builds them).
struct Blocked {
    origin: P2,
    nx: usize,
    ny: usize,
    cells: Vec<bool>,
}

impl Blocked {
    fn new(obstacles: &[&SimObstacle], lo: P2, hi: P2, clearance: f64) -> Result<Self, Infeasible> {
        let origin = P2::new(lo.x - BORDER_M, lo.y - BORDER_M);
        let nx = ((hi.x - lo.x + 2.0 * BORDER_M) / GRID_M).ceil() as usize + 1;
        let ny = ((hi.y - lo.y + 2.0 * BORDER_M) / GRID_M).ceil() as usize + 1;
        if nx > MAX_SIDE || ny > MAX_SIDE {
            return Err(Infeasible::TooLarge);
        }
        let mut cells = vec![false; nx * ny];
        for o in obstacles {
            let (c, r) = (o.shape.center(), o.shape.bounding_radius() + clearance);
            let i0 = (((c.x - r - origin.x) / GRID_M).floor().max(0.0)) as usize;
            let j0 = (((c.y - r - origin.y) / GRID_M).floor().max(0.0)) as usize;
            let i1 = (((c.x + r - origin.x) / GRID_M).ceil() as usize).min(nx - 1);
            let j1 = (((c.y + r - origin.y) / GRID_M).ceil() as usize).min(ny - 1);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let q = P2::new(
                        origin.x + (i as f64 + 0.5) * GRID_M,
                        origin.y + (j as f64 + 0.5) * GRID_M,
                    );
                    if o.shape.signed_distance(q) < clearance {
                        cells[j * nx + i] = true;
                    }
                }
            }
        }
        Ok(Blocked {
            origin,
            nx,
            ny,
            cells,
        })
    }

    /// Blocked, or off the grid.
    fn at(&self, p: P2) -> bool {
        let (fx, fy) = (
            (p.x - self.origin.x) / GRID_M,
            (p.y - self.origin.y) / GRID_M,
        );
        if fx < 0.0 || fy < 0.0 || fx >= self.nx as f64 || fy >= self.ny as f64 {
            return true;
        }
        self.cells[fy as usize * self.nx + fx as usize]
    }
}

/// Where a primitive of curvature `k` (1/m; 0 straight) takes `from` after `s` m.
fn advance(from: Pose, k: f64, s: f64) -> Pose {
    if k == 0.0 {
        return Pose {
            p: P2::new(from.p.x + s * from.psi.cos(), from.p.y + s * from.psi.sin()),
            psi: from.psi,
        };
    }
    let psi = from.psi + k * s;
    Pose {
        p: P2::new(
            from.p.x + (psi.sin() - from.psi.sin()) / k,
            from.p.y - (psi.cos() - from.psi.cos()) / k,
        ),
        psi,
    }
}

/// Whether a craft at `start` heading `heading` (rad) that turns on `radius` m and keeps
/// `clearance` m from every static obstacle can reach within [`GOAL_TOL_M`] of `goal` (module
/// notes): `Ok(length)` when it can, the length of the way found (the primitives flown, and
/// the straight remainder to `goal`), m.
pub fn reachable(
    obstacles: &[SimObstacle],
    start: P2,
    heading: f64,
    goal: P2,
    clearance: f64,
    radius: f64,
) -> Result<f64, Infeasible> {
    search(obstacles, start, heading, goal, clearance, radius, &[1.0])
}

/// The least time in which that craft reaches `goal` if it may also slow down to turn
/// tighter — its yaw rate, not its radius, is what is bounded, so at a fraction f of its
/// cruise speed it turns on f·`radius` — as the distance it would cover at cruise in that
/// time, m. Primitives at [`SLOWER`] fractions of cruise; this is the reference a craft with a
/// turning radius is timed against (`crate::bench::case`): the grid's shortest path is one it
/// cannot always fly (a 62 m one into an L-shaped trap: 141 m on the cruise radius alone, 81 m
/// slowing to turn).
pub fn least_time(
    obstacles: &[SimObstacle],
    start: P2,
    heading: f64,
    goal: P2,
    clearance: f64,
    radius: f64,
) -> Result<f64, Infeasible> {
    search(obstacles, start, heading, goal, clearance, radius, &SLOWER)
}

/// The speeds, as fractions of cruise, of [`least_time`]'s primitives.
pub const SLOWER: [f64; 3] = [1.0, 0.5, 0.25];

/// Hybrid A* from (`start`, `heading`) to within [`GOAL_TOL_M`] of `goal`, with straight and
/// turning primitives at each of `speeds` (fractions of cruise; at f the turn is on f·`radius`
/// and a primitive costs its length ÷ f): the cost of the way found, in metres at cruise. The
/// estimate is the straight-line distance, never more than the cost, so the way is the least
/// the search's resolution finds (its closed set prunes by cell, so not always the least there
/// is).
fn search(
    obstacles: &[SimObstacle],
    start: P2,
    heading: f64,
    goal: P2,
    clearance: f64,
    radius: f64,
    speeds: &[f64],
) -> Result<f64, Infeasible> {
    let statics: Vec<&SimObstacle> = obstacles
        .iter()
        .filter(|o| o.velocity.norm() == 0.0)
        .collect();
    let (mut lo, mut hi) = (
        P2::new(start.x.min(goal.x), start.y.min(goal.y)),
        P2::new(start.x.max(goal.x), start.y.max(goal.y)),
    );
    for o in &statics {
        let (c, r) = (o.shape.center(), o.shape.bounding_radius());
        lo = P2::new(lo.x.min(c.x - r), lo.y.min(c.y - r));
        hi = P2::new(hi.x.max(c.x + r), hi.y.max(c.y + r));
    }
    // Room to turn round outside the box.
    let room = 2.0 * radius.max(0.0);
    let (lo, hi) = (
        P2::new(lo.x - room, lo.y - room),
        P2::new(hi.x + room, hi.y + room),
    );
    let blocked = Blocked::new(&statics, lo, hi, clearance)?;
    if blocked.at(start) || blocked.at(goal) {
        return Err(Infeasible::EndpointBlocked);
    }
    let k = if radius > 0.0 { 1.0 / radius } else { 0.0 };
    let tau = std::f64::consts::TAU;
    let key = |q: Pose| {
        let i = ((q.p.x - blocked.origin.x) / CLOSED_CELL_M) as i64;
        let j = ((q.p.y - blocked.origin.y) / CLOSED_CELL_M) as i64;
        let h = ((q.psi.rem_euclid(tau) / tau) * HEADINGS as f64) as i64 % HEADINGS as i64;
        (i, j, h)
    };
    let h = |p: P2| (goal.x - p.x).hypot(goal.y - p.y);
    let mut poses = vec![Pose {
        p: start,
        psi: heading,
    }];
    let mut closed: HashSet<(i64, i64, i64)> = HashSet::new();
    let mut open = BinaryHeap::new();
    open.push(Open {
        f: h(start),
        g: 0.0,
        at: 0,
    });
    let samples = (STEP_M / SAMPLE_M).ceil() as usize;
    let mut expanded = 0;
    while let Some(Open { g, at, .. }) = open.pop() {
        let q = poses[at];
        if h(q.p) <= GOAL_TOL_M {
            return Ok(g + h(q.p));
        }
        if !closed.insert(key(q)) {
            continue;
        }
        expanded += 1;
        if expanded > MAX_EXPANSIONS {
            break;
        }
        // Straight on at the fastest; turns at every speed.
        let fastest = speeds.iter().copied().fold(0.0, f64::max);
        let turns = speeds
            .iter()
            .filter(|&&f| f > 0.0)
            .flat_map(|&f| [(k / f, f), (-k / f, f)])
            .chain((fastest > 0.0).then_some((0.0, fastest)));
        for (kk, f) in turns {
            let clear = (1..=samples).all(|n| {
                let s = STEP_M * n as f64 / samples as f64;
                !blocked.at(advance(q, kk, s).p)
            });
            if !clear {
                continue;
            }
            let next = advance(q, kk, STEP_M);
            if closed.contains(&key(next)) {
                continue;
            }
            let cost = g + STEP_M / f;
            poses.push(next);
            open.push(Open {
                f: cost + h(next.p),
                g: cost,
                at: poses.len() - 1,
            });
        }
    }
    Err(Infeasible::NoPath)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::SimShape;

    fn wall(center: P2, half: P2) -> SimObstacle {
        SimObstacle::fixed(SimShape::Rectangle {
            center,
            half_size: half,
            angle: 0.0,
        })
    }

    #[test]
    fn open_water_is_reachable_even_behind_the_start() {
        let o = P2::new(0.0, 0.0);
        let ahead = reachable(&[], o, 0.0, P2::new(80.0, 0.0), 2.75, 22.0);
        assert!(
            ahead.as_ref().is_ok_and(|&d| (d - 80.0).abs() < 0.5),
            "{ahead:?}"
        );
        // Behind: half a turn of 22 m radius first (π·22 = 69 m), 44 m out to the side.
        let behind = reachable(&[], o, 0.0, P2::new(-30.0, 0.0), 2.75, 22.0);
        assert!(
            behind.as_ref().is_ok_and(|&d| d > 69.0 + 30.0),
            "{behind:?}"
        );
    }

    #[test]
    fn slowing_to_turn_tighter_takes_less_time_than_the_cruise_circle() {
        // Behind the start: at cruise, half a 22 m circle, 44 m out to the side, and back; at a
        // quarter of cruise half a 5.5 m circle (17 m of arc, each metre four at cruise), then
        // about 30 m straight.
        let o = P2::new(0.0, 0.0);
        let cruise = reachable(&[], o, 0.0, P2::new(-30.0, 0.0), 2.75, 22.0);
        let least = least_time(&[], o, 0.0, P2::new(-30.0, 0.0), 2.75, 22.0);
        assert!(
            matches!((&cruise, &least), (Ok(c), Ok(l)) if l < c && *l >= 30.0),
            "{cruise:?} {least:?}"
        );
        // Straight ahead it changes nothing.
        let ahead = least_time(&[], o, 0.0, P2::new(80.0, 0.0), 2.75, 22.0);
        assert!(
            ahead.as_ref().is_ok_and(|&d| (d - 80.0).abs() < 0.5),
            "{ahead:?}"
        );
    }

    #[test]
    fn a_wall_close_ahead_stops_a_wide_turner_not_a_tight_one() {
        // A wall 12 m ahead across the track, 80 m wide; the goal beside the start, behind it.
        let obs = [wall(P2::new(12.0, 0.0), P2::new(0.5, 40.0))];
        let (s, g) = (P2::new(0.0, 0.0), P2::new(0.0, 30.0));
        // Heading at the wall: a 22 m turn does not fit in 12 m; a 3 m one does.
        assert_eq!(
            reachable(&obs, s, 0.0, g, 2.75, 22.0),
            Err(Infeasible::NoPath)
        );
        assert!(reachable(&obs, s, 0.0, g, 2.75, 3.0).is_ok());
        // Heading along the wall, the goal is a straight run away.
        let up = std::f64::consts::FRAC_PI_2;
        assert!(reachable(&obs, s, up, g, 2.75, 22.0).is_ok());
    }

    #[test]
    fn a_channel_narrower_than_the_hull_is_infeasible() {
        let obs = [
            wall(P2::new(50.0, 4.0), P2::new(50.0, 0.5)),
            wall(P2::new(50.0, -4.0), P2::new(50.0, 0.5)),
            wall(P2::new(100.5, 0.0), P2::new(0.5, 4.5)),
        ];
        // 7 m between the walls' faces: 3.5 m each side, more than 2.75 m.
        let r = reachable(&obs, P2::new(5.0, 0.0), 0.0, P2::new(95.0, 0.0), 2.75, 22.0);
        assert!(r.as_ref().is_ok_and(|&d| (d - 90.0).abs() < 0.5), "{r:?}");
        let r = reachable(&obs, P2::new(5.0, 0.0), 0.0, P2::new(95.0, 0.0), 3.75, 22.0);
        assert!(r.is_err(), "{r:?}");
    }
}
