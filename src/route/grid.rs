//! The route layer's memory of obstacles: a coarse occupancy bitmap in the world frame that
//! scrolls with the vehicle, one `u64` per row.
//!
//! Two layers, because they are forgotten differently:
//! - **sensed**: the evidence map's believed cells, coarsened. Inside the evidence map's window
//!   the map is the truth (cells it has cleared are cleared here too, so a mover's wake or a
//!   false echo does not block a route for ever); outside it this layer remembers what the
//!   sonar saw after the vehicle has left it behind — the wall of a trap, the far side of a
//!   harbour — and the sonar's features beyond the window's reach, until the window comes
//!   over them ([`Grid::mark_sensed`]: inside the window [`Grid::absorb`] makes the map's
//!   belief the layer's before every plan, so a feature counts only beyond it).
//! - **known**: still contacts and charted obstacles, rasterised when they arrive; kept until
//!   the window scrolls past them or the chart is cleared.
//!
//! **Capacity.** Fixed: [`ROUTE_SIDE`]² cells per layer (2 × 512 bytes). What scrolls out of
//! the window is forgotten; the window re-centres when the vehicle is a quarter of the side off
//! centre, so at least a quarter of the side is always kept behind and ahead.

use crate::field::Shape;
use crate::math::Vec2;
use crate::sonar::{EvidenceMap, MAP_SIDE};

/// Cells per side of the route window (one `u64` row each).
pub const ROUTE_SIDE: usize = 64;
const SIDE_I: i32 = ROUTE_SIDE as i32;
const RECENTRE_CELLS: i32 = SIDE_I / 4;

/// One layer: row r is world row `y0 + r`, bit k of a row is world column `x0 + k`.
pub type Rows = [u64; ROUTE_SIDE];

/// The two layers and where they are.
#[derive(Clone, Debug)]
pub struct Grid {
    sensed: Rows,
    known: Rows,
    x0: i32,
    y0: i32,
    placed: bool,
    cell_m: f32,
}

fn floor_i(x: f32) -> i32 {
    // Positions are validated to ±100 km, cells ≥ 0.5 m: within i32. `as` saturates anyway.
    libm::floorf(x) as i32
}

/// `bits` moved `by` places towards bit 0 (negative: towards bit 63); 64 or more clears it.
fn shift_bits(bits: u64, by: i32) -> u64 {
    if by >= 0 {
        bits.checked_shr(by.unsigned_abs()).unwrap_or(0)
    } else {
        bits.checked_shl(by.unsigned_abs()).unwrap_or(0)
    }
}

/// Row `r` moved by `(dx, dy)` window cells: new (r, k) is old (r + dy, k + dx).
fn scroll(rows: &mut Rows, dx: i32, dy: i32) {
    let old = *rows;
    for (r, row) in rows.iter_mut().enumerate() {
        let from = r as i32 + dy;
        *row = usize::try_from(from)
            .ok()
            .and_then(|f| old.get(f))
            .map_or(0, |&b| shift_bits(b, dx));
    }
}

impl Grid {
    /// An empty grid of `cell_m`-metre cells (placed by the first [`Grid::follow`]).
    pub const fn new(cell_m: f32) -> Self {
        Grid {
            sensed: [0; ROUTE_SIDE],
            known: [0; ROUTE_SIDE],
            x0: 0,
            y0: 0,
            placed: false,
            cell_m,
        }
    }

    /// Cell size, m.
    pub fn cell_m(&self) -> f32 {
        self.cell_m
    }

    /// Whether the window has been placed.
    pub fn placed(&self) -> bool {
        self.placed
    }

    /// The window cell (column, row) holding `p`, if inside.
    pub fn cell_of(&self, p: Vec2) -> Option<(usize, usize)> {
        let k = 1.0 / self.cell_m;
        self.local(floor_i(p.x * k), floor_i(p.y * k))
    }

    /// The window cell (column, row) of world cell (i, j), if inside.
    fn local(&self, i: i32, j: i32) -> Option<(usize, usize)> {
        let c = usize::try_from(i.wrapping_sub(self.x0)).ok()?;
        let r = usize::try_from(j.wrapping_sub(self.y0)).ok()?;
        (c < ROUTE_SIDE && r < ROUTE_SIDE).then_some((c, r))
    }

    /// Centre of window cell (column, row), world frame, m.
    pub fn center(&self, c: usize, r: usize) -> Vec2 {
        Vec2::new(
            (self.x0 as f32 + c as f32 + 0.5) * self.cell_m,
            (self.y0 as f32 + r as f32 + 0.5) * self.cell_m,
        )
    }

    /// The window cell nearest to `p` (clamped onto the window), for a goal beyond it.
    pub fn clamp(&self, p: Vec2) -> (usize, usize) {
        let k = 1.0 / self.cell_m;
        let c = floor_i(p.x * k)
            .saturating_sub(self.x0)
            .clamp(0, SIDE_I - 1);
        let r = floor_i(p.y * k)
            .saturating_sub(self.y0)
            .clamp(0, SIDE_I - 1);
        (c as usize, r as usize)
    }

    /// Row `r` of both layers OR-ed: what blocks a route.
    pub fn occupied_row(&self, r: usize) -> u64 {
        self.sensed.get(r).copied().unwrap_or(0) | self.known.get(r).copied().unwrap_or(0)
    }

    /// Whether window cell (column, row) is occupied in either layer.
    pub fn is_occupied(&self, (c, r): (usize, usize)) -> bool {
        self.occupied_row(r) & 1u64.checked_shl(c as u32).unwrap_or(0) != 0
    }

    /// Keeps the window around `p`: placed centred on the first call, re-centred (scrolling
    /// both layers, forgetting what leaves) when `p` is a quarter of the side off centre.
    pub fn follow(&mut self, p: Vec2) {
        if !p.is_finite() {
            return;
        }
        let k = 1.0 / self.cell_m;
        let want_x = floor_i(p.x * k).saturating_sub(SIDE_I / 2);
        let want_y = floor_i(p.y * k).saturating_sub(SIDE_I / 2);
        if !self.placed {
            (self.x0, self.y0, self.placed) = (want_x, want_y, true);
            return;
        }
        let (dx, dy) = (
            want_x.saturating_sub(self.x0),
            want_y.saturating_sub(self.y0),
        );
        if dx.abs() < RECENTRE_CELLS && dy.abs() < RECENTRE_CELLS {
            return;
        }
        scroll(&mut self.sensed, dx, dy);
        scroll(&mut self.known, dx, dy);
        (self.x0, self.y0) = (want_x, want_y);
    }

    /// Marks in the known layer every cell whose centre is within half a cell diagonal of
    /// `shape` (so a shape thinner than a cell still blocks it). Cost: the cells of the shape's
    /// bounding square.
    pub fn mark(&mut self, shape: &Shape) {
        self.mark_in(shape, false);
    }

    /// [`Grid::mark`] in the sensed layer.
    pub fn mark_sensed(&mut self, shape: &Shape) {
        self.mark_in(shape, true);
    }

    fn mark_in(&mut self, shape: &Shape, sensed: bool) {
        if !self.placed {
            return;
        }
        let reach = 0.71 * self.cell_m;
        let (c, rad) = (shape.center(), shape.bounding_radius() + reach);
        let k = 1.0 / self.cell_m;
        let (i0, i1) = (floor_i((c.x - rad) * k), floor_i((c.x + rad) * k));
        let (j0, j1) = (floor_i((c.y - rad) * k), floor_i((c.y + rad) * k));
        let clip = |a: i32, o: i32| a.saturating_sub(o).clamp(0, SIDE_I - 1);
        for r in clip(j0, self.y0)..=clip(j1, self.y0) {
            for col in clip(i0, self.x0)..=clip(i1, self.x0) {
                let x = self.center(col as usize, r as usize);
                if shape.signed_distance(x) <= reach {
                    let layer = if sensed {
                        &mut self.sensed
                    } else {
                        &mut self.known
                    };
                    if let Some(row) = layer.get_mut(r as usize) {
                        *row |= 1u64.checked_shl(col as u32).unwrap_or(0);
                    }
                }
            }
        }
    }

    /// Marks window cell (column, row) in the sensed layer (nothing outside the window).
    pub fn mark_sensed_cell(&mut self, (c, r): (usize, usize)) {
        if let Some(row) = self.sensed.get_mut(r) {
            *row |= 1u64.checked_shl(c as u32).unwrap_or(0);
        }
    }

    /// Whether the segment `a`→`b` crosses no cell set in `blocked` (cell `skip`, the
    /// vehicle's own, excepted; outside the window nothing is known, so nothing blocks).
    pub fn line_clear(&self, blocked: &Rows, a: Vec2, b: Vec2, skip: (usize, usize)) -> bool {
        let d = b - a;
        // Samples a quarter cell apart, at most one per quarter cell across the window twice.
        let n = libm::ceilf(d.norm() * 4.0 / self.cell_m).clamp(1.0, (8 * ROUTE_SIDE) as f32);
        let n = n as u32;
        (0..=n).all(|k| {
            let x = a + d * (k as f32 / n as f32);
            match self.cell_of(x) {
                Some(cell) if cell != skip => blocked
                    .get(cell.1)
                    .is_none_or(|row| row & 1u64.checked_shl(cell.0 as u32).unwrap_or(0) == 0),
                _ => true,
            }
        })
    }

    /// Forgets the known layer (the chart was cleared).
    pub fn forget_known(&mut self) {
        self.known = [0; ROUTE_SIDE];
    }

    /// Takes in the evidence map: every route cell wholly inside the map's window becomes
    /// what the map believes there (occupied if any of its map cells is). The route cell must
    /// be a whole number of map cells; otherwise nothing is taken.
    pub fn absorb(&mut self, map: &EvidenceMap) {
        let Some(w) = map.window() else { return };
        if !self.placed {
            return;
        }
        let ratio = libm::roundf(self.cell_m / map.cell_m());
        if !(ratio >= 1.0 && (ratio * map.cell_m() - self.cell_m).abs() < 1e-3) {
            return;
        }
        let n = ratio as i32;
        // Route cells whose map cells all lie in the map's window.
        // (`n` ≥ 1 here; the checked forms keep the division's panic path out of the image.)
        let div = |a: i32| a.checked_div_euclid(n).unwrap_or(0);
        let first = |a0: i32| div(a0) + i32::from(a0.checked_rem_euclid(n) != Some(0));
        let last = |a0: i32| div(a0 + MAP_SIDE as i32) - 1;
        let block = 1u64.checked_shl(n as u32).map_or(u64::MAX, |b| b - 1);
        for j in first(w.y0)..=last(w.y0) {
            let Some(row) = usize::try_from(j.wrapping_sub(self.y0))
                .ok()
                .and_then(|r| self.sensed.get_mut(r))
            else {
                continue;
            };
            // The map rows of route row j, OR-ed.
            let bits = (0..n).fold(0u64, |b, dj| b | map.row_bits(w, j * n + dj - w.y0));
            let (mut seen, mut covered) = (0u64, 0u64);
            for i in first(w.x0)..=last(w.x0) {
                let Ok(c) = u32::try_from(i.wrapping_sub(self.x0)) else {
                    continue;
                };
                let Some(here) = 1u64.checked_shl(c) else {
                    continue;
                };
                covered |= here;
                let cells = block.checked_shl((i * n - w.x0) as u32).unwrap_or(0);
                if bits & cells != 0 {
                    seen |= here;
                }
            }
            *row = (*row & !covered) | seen;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wall_is_marked_and_scrolls_with_the_window() {
        let mut g = Grid::new(2.0);
        g.follow(Vec2::ZERO);
        let wall = Shape::rectangle(Vec2::new(10.0, 0.0), Vec2::new(0.5, 20.0), 0.0).unwrap();
        g.mark(&wall);
        let (c, r) = g.cell_of(Vec2::new(10.0, 5.0)).unwrap();
        assert!(g.is_occupied((c, r)));
        let (c, r) = g.cell_of(Vec2::new(14.0, 5.0)).unwrap();
        assert!(!g.is_occupied((c, r)));
        // Move 40 m east and 20 m north: the wall is still where it was in the world.
        g.follow(Vec2::new(40.0, 20.0));
        let (c, r) = g.cell_of(Vec2::new(10.0, 15.0)).unwrap();
        assert!(g.is_occupied((c, r)));
        let (c, r) = g.cell_of(Vec2::new(10.0, 25.0)).unwrap();
        assert!(!g.is_occupied((c, r)), "beyond the wall's end");
        // Far away: forgotten.
        g.follow(Vec2::new(400.0, 0.0));
        assert!((0..ROUTE_SIDE).all(|r| g.occupied_row(r) == 0));
    }

    #[test]
    fn the_evidence_map_decides_inside_its_window() {
        use crate::sonar::Beam;
        let map = EvidenceMap::empty();
        map.follow(Vec2::ZERO);
        let mut g = Grid::new(4.0 * map.cell_m());
        g.follow(Vec2::ZERO);
        // Two pings see a surface 6 m east.
        let echoes = [6.0];
        let beam = Beam {
            origin: Vec2::ZERO,
            look: Vec2::new(1.0, 0.0),
            range_m: 20.0,
            blank_m: 0.5,
            echoes: &echoes,
            seconded: 0,
            vehicles: 0,
        };
        map.observe(&beam);
        map.observe(&beam);
        g.absorb(&map);
        let (c, r) = g.cell_of(Vec2::new(6.1, 0.1)).unwrap();
        assert!(g.is_occupied((c, r)));
        // Looked through many times: cleared in the map, so here too.
        let clear = Beam {
            echoes: &[],
            ..beam
        };
        for _ in 0..20 {
            map.observe(&clear);
        }
        g.absorb(&map);
        assert!(!g.is_occupied((c, r)));
    }

    #[test]
    fn a_feature_beyond_the_maps_window_blocks_until_the_map_looks_there() {
        let map = EvidenceMap::empty();
        map.follow(Vec2::ZERO);
        let mut g = Grid::new(2.0);
        g.follow(Vec2::ZERO);
        let at = |x: f32| Vec2::new(x, 1.0);
        let occupied = |g: &Grid, x: f32| g.is_occupied(g.cell_of(at(x)).unwrap());
        let rock = |x: f32| Shape::circle(at(x), 0.5).unwrap();
        // The map's window holds 16 m either side: a rock's fit 31 m off counts; one 9 m off
        // is the map's to believe, and the map has seen nothing there.
        g.mark_sensed(&rock(31.0));
        g.mark_sensed(&rock(9.0));
        g.absorb(&map);
        assert!(occupied(&g, 31.0));
        assert!(!occupied(&g, 9.0));
        // The window comes over the first: the map's belief replaces the fit's.
        map.follow(at(24.0));
        g.follow(at(24.0));
        g.absorb(&map);
        assert!(!occupied(&g, 31.0));
    }
}
