//! Is a world flyable by a craft, and how long is its shortest path? A grid search over the
//! static obstacles grown by the hull radius and a margin.
//!
//! The grid has [`CELL_M`] cells over the box round the start, the goal and the obstacles
//! (plus [`BORDER_M`]); a cell is blocked when its centre is closer than `clearance` to a
//! static obstacle (moving ones are ignored: they pass). Dijkstra with 8 neighbours and octile
//! steps (1 or √2 cells) gives the path length; 8-connected paths are at most ≈ 8 % longer
//! than the true shortest (the worst case, a path at 22.5° to the grid), so the reference time
//! it gives errs on the generous side.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use crate::types::{SimObstacle, P2};

/// Grid cell, m.
pub const CELL_M: f64 = 0.5;
/// Free room round the box of start, goal and obstacles, m.
pub const BORDER_M: f64 = 20.0;
/// Largest grid side, cells (a 1 km world at 0.5 m).
pub const MAX_SIDE: usize = 2000;

/// Why a world could not be searched.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Infeasible {
    /// The start or the goal is within `clearance` of an obstacle.
    #[error("start or goal too close to an obstacle for the hull")]
    EndpointBlocked,
    /// No path: the goal is walled off.
    #[error("no path wide enough for the hull")]
    NoPath,
    /// The world is larger than [`MAX_SIDE`] cells a side.
    #[error("world larger than the feasibility grid")]
    TooLarge,
}

#[derive(Clone, Copy, PartialEq)]
struct Node {
    cost: f64,
    at: usize,
}

impl Eq for Node {}

impl Ord for Node {
    fn cmp(&self, o: &Self) -> Ordering {
        // A min-heap on cost (costs are finite).
        o.cost.total_cmp(&self.cost)
    }
}

impl PartialOrd for Node {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// Length of the shortest path from `start` to `goal` that keeps `clearance` m from every
/// static obstacle, m.
pub fn shortest_path(
    obstacles: &[SimObstacle],
    start: P2,
    goal: P2,
    clearance: f64,
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
    let origin = P2::new(lo.x - BORDER_M, lo.y - BORDER_M);
    let nx = ((hi.x - lo.x + 2.0 * BORDER_M) / CELL_M).ceil() as usize + 1;
    let ny = ((hi.y - lo.y + 2.0 * BORDER_M) / CELL_M).ceil() as usize + 1;
    if nx > MAX_SIDE || ny > MAX_SIDE {
        return Err(Infeasible::TooLarge);
    }
    let centre = |i: usize, j: usize| {
        P2::new(
            origin.x + (i as f64 + 0.5) * CELL_M,
            origin.y + (j as f64 + 0.5) * CELL_M,
        )
    };
    // Blocked cells: each obstacle marks the cells of its grown bounding box.
    let mut blocked = vec![false; nx * ny];
    for o in &statics {
        let (c, r) = (o.shape.center(), o.shape.bounding_radius() + clearance);
        let i0 = (((c.x - r - origin.x) / CELL_M).floor().max(0.0)) as usize;
        let j0 = (((c.y - r - origin.y) / CELL_M).floor().max(0.0)) as usize;
        let i1 = (((c.x + r - origin.x) / CELL_M).ceil() as usize).min(nx - 1);
        let j1 = (((c.y + r - origin.y) / CELL_M).ceil() as usize).min(ny - 1);
        for j in j0..=j1 {
            for i in i0..=i1 {
                if o.shape.signed_distance(centre(i, j)) < clearance {
                    blocked[j * nx + i] = true;
                }
            }
        }
    }
    let cell_of = |p: P2| {
        let i = ((p.x - origin.x) / CELL_M) as usize;
        let j = ((p.y - origin.y) / CELL_M) as usize;
        j.min(ny - 1) * nx + i.min(nx - 1)
    };
    let (s, g) = (cell_of(start), cell_of(goal));
    if blocked[s] || blocked[g] {
        return Err(Infeasible::EndpointBlocked);
    }
    let mut dist = vec![f64::INFINITY; nx * ny];
    let mut heap = BinaryHeap::new();
    dist[s] = 0.0;
    heap.push(Node { cost: 0.0, at: s });
    const STEPS: [(i64, i64, f64); 8] = [
        (1, 0, 1.0),
        (-1, 0, 1.0),
        (0, 1, 1.0),
        (0, -1, 1.0),
        (1, 1, std::f64::consts::SQRT_2),
        (1, -1, std::f64::consts::SQRT_2),
        (-1, 1, std::f64::consts::SQRT_2),
        (-1, -1, std::f64::consts::SQRT_2),
    ];
    while let Some(Node { cost, at }) = heap.pop() {
        if at == g {
            // Cell centres to the true endpoints: within half a diagonal each.
            return Ok(cost * CELL_M);
        }
        if cost > dist[at] {
            continue;
        }
        let (i, j) = ((at % nx) as i64, (at / nx) as i64);
        for (di, dj, w) in STEPS {
            let (a, b) = (i + di, j + dj);
            if a < 0 || b < 0 || a >= nx as i64 || b >= ny as i64 {
                continue;
            }
            let n = b as usize * nx + a as usize;
            // A diagonal step must not cut a blocked corner.
            let corner = di != 0
                && dj != 0
                && (blocked[j as usize * nx + a as usize] || blocked[b as usize * nx + i as usize]);
            if blocked[n] || corner {
                continue;
            }
            let c = cost + w;
            if c < dist[n] {
                dist[n] = c;
                heap.push(Node { cost: c, at: n });
            }
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
    fn open_water_is_the_straight_line() {
        let d = shortest_path(&[], P2::new(0.0, 0.0), P2::new(50.0, 0.0), 0.7).unwrap();
        assert!((d - 50.0).abs() <= 1.0, "{d}");
    }

    #[test]
    fn a_wall_with_a_gap_is_passed_through_the_gap() {
        // Wall across x = 25 from y = −40 to 40, a 4 m gap at y = 20..24.
        let obs = [
            wall(P2::new(25.0, -10.0), P2::new(0.5, 30.0)),
            wall(P2::new(25.0, 32.0), P2::new(0.5, 8.0)),
        ];
        let d = shortest_path(&obs, P2::new(0.0, 0.0), P2::new(50.0, 0.0), 0.7).unwrap();
        // Through (25, 22): 2 × √(25² + 22²) ≈ 66.6 m; within the grid's 8 % above it.
        assert!((66.0..72.0).contains(&d), "{d}");
        // Too narrow for a 2.75 m clearance: round the ends, or not at all.
        let r = shortest_path(&obs, P2::new(0.0, 0.0), P2::new(50.0, 0.0), 2.75);
        assert!(r.as_ref().map_or(true, |d| *d > 100.0), "{r:?}");
    }

    #[test]
    fn a_closed_box_is_infeasible() {
        let obs = [
            wall(P2::new(0.0, 10.0), P2::new(10.0, 0.5)),
            wall(P2::new(0.0, -10.0), P2::new(10.0, 0.5)),
            wall(P2::new(10.0, 0.0), P2::new(0.5, 10.0)),
            wall(P2::new(-10.0, 0.0), P2::new(0.5, 10.0)),
        ];
        let r = shortest_path(&obs, P2::new(0.0, 0.0), P2::new(40.0, 0.0), 0.7);
        assert_eq!(r, Err(Infeasible::NoPath));
        let r = shortest_path(&obs, P2::new(9.8, 0.0), P2::new(40.0, 0.0), 0.7);
        assert_eq!(r, Err(Infeasible::EndpointBlocked));
    }
}
