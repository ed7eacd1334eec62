//! What the firmware believed: its evidence map reassembled from `Belief` chunks, and how it
//! compares with the truth (the bench's perception columns).
//!
//! **Map.** Each chunk states every cell of its rows: a set bit adds the cell, a clear bit
//! removes it. `ever` keeps every cell ever believed (what the plot shows faintly: "was this
//! wall ever seen?"). A snapshot of the whole map is kept each time a chunk completes a pass
//! over the window's rows (64 rows in 16-row chunks), at most one per [`SNAPSHOT_EVERY_S`], with
//! the vehicle's true position then, for the perception metrics.
//!
//! **Perception metrics**, over the snapshots of one vehicle:
//! - *miss*: true surface points (every [`SURFACE_STEP_M`] along every obstacle's boundary at
//!   the snapshot's time, and round the other vehicles' hulls unless the firmware is told where
//!   they are, which it then need not believe) within [`SEEN_RANGE_M`] of the
//!   vehicle and in its line of sight, against the distance to the nearest believed cell's
//!   centre; the metric is the 95th percentile over all such points and snapshots. A perfect
//!   map gives about half a cell; a wall never believed gives its distance to anything else.
//! - *false*: the share of believed cells farther than a cell's diagonal plus 0.5 m from any
//!   true surface (stale trails of movers count: the vehicle steered round something not there).

use std::collections::BTreeSet;

use crate::sim::contacts::OtherVehicle;
use crate::types::{SimObstacle, SimShape, P2};

/// Shortest time between two kept snapshots, s.
pub const SNAPSHOT_EVERY_S: f64 = 5.0;
/// Spacing of the true-surface samples, m.
pub const SURFACE_STEP_M: f64 = 0.5;
/// True surface within this range of the vehicle counts as "inside sonar range", m (the
/// window's half side at the default cell, well inside the sonar's 30 m).
pub const SEEN_RANGE_M: f64 = 15.0;

/// One chunk as received.
#[derive(Clone, Debug, PartialEq)]
pub struct Chunk {
    /// Cell size, m.
    pub cell_m: f64,
    /// First column's world cell index.
    pub x0: i32,
    /// First row's world cell index.
    pub y0: i32,
    /// Row bitmaps, bit k = column x0 + k.
    pub rows: Vec<u64>,
}

impl Chunk {
    /// From a received `Belief`.
    pub fn of(b: &vpf::link::BeliefRepr<'_>) -> Chunk {
        Chunk {
            cell_m: f64::from(b.cell_m()),
            x0: b.x0,
            y0: b.y0,
            rows: (0..b.rows()).map(|r| b.row(r)).collect(),
        }
    }
}

/// A whole map at one time.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Snapshot {
    /// Time, s.
    pub t: f64,
    /// The vehicle's true position, m.
    pub position: P2,
    /// Believed cells.
    pub cells: Vec<(i32, i32)>,
}

/// A vehicle's belief over a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Belief {
    /// Cell size, m (0 before the first chunk).
    pub cell_m: f64,
    /// Believed now.
    pub cells: BTreeSet<(i32, i32)>,
    /// Ever believed.
    pub ever: BTreeSet<(i32, i32)>,
    /// Whole-map snapshots (see the module notes).
    pub snapshots: Vec<Snapshot>,
    rows_since: usize,
}

impl Belief {
    /// Takes a chunk received at `t` s with the vehicle truly at `position`.
    pub fn apply(&mut self, c: &Chunk, t: f64, position: P2) {
        if !(c.cell_m.is_finite() && c.cell_m > 0.0) {
            return;
        }
        self.cell_m = c.cell_m;
        for (r, bits) in c.rows.iter().enumerate() {
            let j = c.y0.wrapping_add(r as i32);
            for k in 0..64 {
                let cell = (c.x0.wrapping_add(k), j);
                if bits >> k & 1 == 1 {
                    self.cells.insert(cell);
                    self.ever.insert(cell);
                } else {
                    self.cells.remove(&cell);
                }
            }
        }
        // Forget what fell out of the window (the firmware did): keep 64 × 64 about the chunk.
        let (x0, y_lo, y_hi) = (c.x0, c.y0.saturating_sub(64), c.y0.saturating_add(64));
        self.cells
            .retain(|&(i, j)| i >= x0 && i < x0.saturating_add(64) && j > y_lo && j < y_hi);
        self.rows_since += c.rows.len();
        let due = self
            .snapshots
            .last()
            .is_none_or(|s| t - s.t >= SNAPSHOT_EVERY_S);
        if self.rows_since >= 64 {
            self.rows_since = 0;
            if due {
                self.snapshots.push(Snapshot {
                    t,
                    position,
                    cells: self.cells.iter().copied().collect(),
                });
            }
        }
    }

    /// The centre of cell (i, j), m.
    pub fn center(&self, (i, j): (i32, i32)) -> P2 {
        P2::new(
            (f64::from(i) + 0.5) * self.cell_m,
            (f64::from(j) + 0.5) * self.cell_m,
        )
    }
}

/// Points every `step` m along the boundary of `shape`.
fn boundary(shape: &SimShape, step: f64) -> Vec<P2> {
    let ring = |pts: &[P2]| {
        let mut out = Vec::new();
        for (k, a) in pts.iter().enumerate() {
            let b = pts[(k + 1) % pts.len()];
            let d = b.sub(*a);
            let n = (d.norm() / step).ceil().max(1.0) as usize;
            out.extend((0..n).map(|m| a.add(d.scale(m as f64 / n as f64))));
        }
        out
    };
    match shape {
        SimShape::Circle { center, radius } => {
            let n = (2.0 * std::f64::consts::PI * radius / step).ceil().max(8.0) as usize;
            (0..n)
                .map(|k| {
                    let a = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
                    center.add(P2::new(a.cos(), a.sin()).scale(*radius))
                })
                .collect()
        }
        SimShape::Rectangle { .. } => shape.corners().map_or_else(Vec::new, |c| ring(&c)),
        SimShape::Polygon { points } => ring(points),
    }
}

/// The perception metrics of one vehicle (see the module notes).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Perception {
    /// 95th percentile of the miss distance, m.
    pub miss_p95_m: f64,
    /// Mean miss distance, m.
    pub miss_mean_m: f64,
    /// Share of believed cells with no true surface near.
    pub false_frac: f64,
    /// Snapshots measured.
    pub snapshots: usize,
}

/// The perception metrics of `belief` against `obstacles` and the other vehicles
/// (`others(t)` gives them at time `t`; their hulls count as surface to believe if
/// `others_to_find`); `None` when no snapshot was taken.
pub fn measure(
    belief: &Belief,
    obstacles: &[SimObstacle],
    others: &dyn Fn(f64) -> Vec<OtherVehicle>,
    others_to_find: bool,
) -> Option<Perception> {
    if belief.snapshots.is_empty() || belief.cell_m <= 0.0 {
        return None;
    }
    let mut misses: Vec<f64> = Vec::new();
    let (mut false_cells, mut cells) = (0usize, 0usize);
    let near = belief.cell_m * std::f64::consts::SQRT_2 + 0.5;
    for s in &belief.snapshots {
        let shapes: Vec<SimShape> = obstacles
            .iter()
            .map(|o| o.shape_at(s.t))
            .chain(others(s.t).into_iter().map(|v| SimShape::Circle {
                center: v.position,
                radius: v.hull_radius,
            }))
            .collect();
        let centres: Vec<P2> = s.cells.iter().map(|&c| belief.center(c)).collect();
        let to_find = if others_to_find {
            shapes.len()
        } else {
            obstacles.len()
        };
        for sh in shapes.iter().take(to_find) {
            for p in boundary(sh, SURFACE_STEP_M) {
                let to = p.sub(s.position);
                let d = to.norm();
                if !(1e-6..=SEEN_RANGE_M).contains(&d) {
                    continue;
                }
                // Line of sight: nothing else (nor the same shape's far side) nearer on the ray.
                let dir = to.scale(1.0 / d);
                let hidden = shapes
                    .iter()
                    .filter_map(|o| o.ray_hit(s.position, dir, d))
                    .any(|h| h < d - 0.25);
                if hidden {
                    continue;
                }
                let m = centres
                    .iter()
                    .map(|c| c.sub(p).norm())
                    .fold(f64::INFINITY, f64::min);
                misses.push(m.min(2.0 * SEEN_RANGE_M));
            }
        }
        for c in &centres {
            cells += 1;
            if shapes.iter().all(|o| o.signed_distance(*c).abs() > near) {
                false_cells += 1;
            }
        }
    }
    misses.sort_by(f64::total_cmp);
    let p95 = misses
        .get(((misses.len() as f64 * 0.95) as usize).min(misses.len().saturating_sub(1)))
        .copied()
        .unwrap_or(0.0);
    let mean = if misses.is_empty() {
        0.0
    } else {
        misses.iter().sum::<f64>() / misses.len() as f64
    };
    Some(Perception {
        miss_p95_m: p95,
        miss_mean_m: mean,
        false_frac: if cells > 0 {
            false_cells as f64 / cells as f64
        } else {
            0.0
        },
        snapshots: belief.snapshots.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wall() -> SimObstacle {
        SimObstacle::fixed(SimShape::Rectangle {
            center: P2::new(5.0, 0.0),
            half_size: P2::new(0.25, 3.0),
            angle: 0.0,
        })
    }

    /// A belief holding `cells`, one snapshot from the origin.
    fn belief(cells: &[(i32, i32)]) -> Belief {
        let mut b = Belief {
            cell_m: 0.5,
            ..Belief::default()
        };
        b.snapshots.push(Snapshot {
            t: 0.0,
            position: P2::new(0.0, 0.0),
            cells: cells.to_vec(),
        });
        b
    }

    #[test]
    fn chunks_set_and_clear_cells_and_snapshot_a_full_pass() {
        let mut b = Belief::default();
        let mut rows = vec![0u64; 16];
        rows[0] = 0b101;
        for k in 0..4 {
            let c = Chunk {
                cell_m: 0.5,
                x0: -32,
                y0: -32 + 16 * k,
                rows: rows.clone(),
            };
            b.apply(&c, 1.0, P2::new(0.0, 0.0));
        }
        assert!(b.cells.contains(&(-32, -32)) && b.cells.contains(&(-30, -32)));
        assert_eq!(b.snapshots.len(), 1);
        assert_eq!(b.snapshots[0].cells.len(), 8);
        rows[0] = 0;
        b.apply(
            &Chunk {
                cell_m: 0.5,
                x0: -32,
                y0: -32,
                rows,
            },
            2.0,
            P2::new(0.0, 0.0),
        );
        assert!(!b.cells.contains(&(-32, -32)));
        assert!(b.ever.contains(&(-32, -32)), "ever believed stays");
    }

    #[test]
    fn a_perfect_belief_misses_little_and_a_blind_one_a_lot() {
        // The wall's near face at x = 4.75, cells of 0.5 m along it (x index 9: 4.5–5.0).
        let face: Vec<(i32, i32)> = (-6..6).map(|j| (9, j)).collect();
        let none = |_: f64| Vec::new();
        let good = measure(&belief(&face), &[wall()], &none, true).unwrap();
        assert!(good.miss_p95_m < 1.0, "{good:?}");
        assert_eq!(good.false_frac, 0.0);
        // Nothing believed but a cell far away: every surface point is missed, the cell false.
        let blind = measure(&belief(&[(-20, 0)]), &[wall()], &none, true).unwrap();
        assert!(blind.miss_p95_m > 10.0, "{blind:?}");
        assert_eq!(blind.false_frac, 1.0);
        assert!(measure(&Belief::default(), &[wall()], &none, true).is_none());
        // Another vehicle 3 m off, not in the map: a miss unless the firmware is told where it is.
        let other = |_: f64| {
            vec![OtherVehicle {
                id: 1,
                position: P2::new(0.0, 3.0),
                velocity: P2::default(),
                hull_radius: 0.5,
            }]
        };
        let unseen = measure(&belief(&face), &[wall()], &other, true).unwrap();
        assert!(unseen.miss_p95_m > 2.0, "{unseen:?}");
        let told = measure(&belief(&face), &[wall()], &other, false).unwrap();
        assert_eq!(told.miss_p95_m, good.miss_p95_m);
    }
}
