//! The wavefront: a discrete navigation function on the route grid, spread from the goal
//! through free cells one layer per step (4-neighbour breadth-first search; 8-neighbour as the
//! route's last resort, "Diagonal steps" below).
//!
//! Seed 004 (Rimon–Koditschek) asks for a potential with no local minimum but the goal; on a
//! grid the wavefront distance is exactly that — every reachable cell but the goal has a
//! neighbour one step nearer — and unlike a sphere world it needs no assumption about the
//! obstacles' shape. It is the classic discrete navigation function (Barraquand–Latombe).
//!
//! **Memory.** The distance is kept modulo 3 in two bit planes (label 3 = not reached): on a
//! 4-neighbour grid a neighbour's distance differs by exactly one, so "one step nearer" is
//! "label − 1 mod 3". A layer's frontier is the cells labelled with its distance mod 3: older
//! cells with the same label have no unreached neighbour left, so they add nothing. Each layer
//! is a few word operations per row.
//!
//! **Diagonal steps.** The route's last resort ([`Wavefront::spread`] with `diagonal`) also
//! steps to the four corner neighbours, between two blocked cells: a 5 m channel at 45° to
//! the grid, its walls' map cells coarsened to 2 m, leaves only a staircase of cells that
//! touch at their corners (the 8-neighbour distance differs by one between neighbours too,
//! so the labels mod 3 still hold).

use super::grid::{Rows, ROUTE_SIDE};

/// Distance labels modulo 3 in two bit planes; both bits set = not reached.
#[derive(Clone, Debug)]
pub struct Wavefront {
    lo: Rows,
    hi: Rows,
    /// Spread through corners too (module notes, "Diagonal steps").
    diagonal: bool,
}

/// A window cell: (column, row).
pub type Cell = (usize, usize);

fn bit(c: usize) -> u64 {
    1u64.checked_shl(c as u32).unwrap_or(0)
}

impl Default for Wavefront {
    fn default() -> Self {
        Self::new()
    }
}

impl Wavefront {
    /// Nothing reached.
    pub const fn new() -> Self {
        Wavefront {
            lo: [u64::MAX; ROUTE_SIDE],
            hi: [u64::MAX; ROUTE_SIDE],
            diagonal: false,
        }
    }

    fn row(&self, r: usize) -> (u64, u64) {
        (
            self.lo.get(r).copied().unwrap_or(u64::MAX),
            self.hi.get(r).copied().unwrap_or(u64::MAX),
        )
    }

    /// Cells of row `r` labelled `l` (0 ..= 2); none outside the window.
    fn labelled(&self, r: Option<usize>, l: u8) -> u64 {
        let Some((lo, hi)) = r.filter(|&r| r < ROUTE_SIDE).map(|r| self.row(r)) else {
            return 0;
        };
        let lo = if l & 1 == 1 { lo } else { !lo };
        let hi = if l & 2 == 2 { hi } else { !hi };
        lo & hi
    }

    fn set(&mut self, r: usize, bits: u64, l: u8) {
        if let (Some(lo), Some(hi)) = (self.lo.get_mut(r), self.hi.get_mut(r)) {
            *lo = if l & 1 == 1 { *lo | bits } else { *lo & !bits };
            *hi = if l & 2 == 2 { *hi | bits } else { *hi & !bits };
        }
    }

    /// The label of a cell: its distance from the source mod 3, `None` if not reached.
    pub fn label(&self, (c, r): Cell) -> Option<u8> {
        let (lo, hi) = self.row(r);
        let m = bit(c);
        if m == 0 || (lo & hi & m) != 0 {
            return None;
        }
        Some(u8::from(lo & m != 0) | (u8::from(hi & m != 0) << 1))
    }

    /// Spreads from `source` through cells not set in `blocked` (the source itself may be
    /// blocked) until `target` is reached, at most `max_layers` layers; through the corners
    /// too if `diagonal`. Returns the target's distance in steps, `None` if it was not
    /// reached.
    pub fn spread(
        &mut self,
        blocked: &Rows,
        (source, target): (Cell, Cell),
        max_layers: u32,
        diagonal: bool,
    ) -> Option<u32> {
        self.lo = [u64::MAX; ROUTE_SIDE];
        self.hi = [u64::MAX; ROUTE_SIDE];
        self.diagonal = diagonal;
        let beside = |f: u64| if diagonal { f | (f << 1) | (f >> 1) } else { f };
        self.set(source.1, bit(source.0), 0);
        for layer in 0..max_layers {
            if self.label(target).is_some() {
                return Some(layer);
            }
            let (l, next) = ((layer % 3) as u8, ((layer + 1) % 3) as u8);
            let mut grew = false;
            for r in 0..ROUTE_SIDE {
                let f = self.labelled(Some(r), l);
                let around =
                    beside(self.labelled(r.checked_sub(1), l) | self.labelled(Some(r + 1), l));
                let (lo, hi) = self.row(r);
                let free = !blocked.get(r).copied().unwrap_or(u64::MAX);
                let new = (f | (f << 1) | (f >> 1) | around) & free & lo & hi;
                if new != 0 {
                    // New cells get label `next` ≠ `l`: rows below still see this layer intact.
                    self.set(r, new, next);
                    grew = true;
                }
            }
            if !grew {
                return None;
            }
        }
        self.label(target).map(|_| max_layers)
    }

    /// The neighbour of a reached `cell` one step nearer the source (a corner one too after a
    /// diagonal spread), preferring the one nearest `toward` (the source: fewer turns in the
    /// staircase). `None` at the source.
    pub fn downhill(&self, cell: Cell, toward: Cell) -> Option<Cell> {
        let l = self.label(cell)?;
        let want = (l + 2) % 3;
        let (c, r) = cell;
        let d2 = |(a, b): Cell| {
            let dx = a as i32 - toward.0 as i32;
            let dy = b as i32 - toward.1 as i32;
            dx * dx + dy * dy
        };
        // (c + dc − 1, r + dr − 1), after a diagonal spread only.
        let corner = |dc: usize, dr: usize| {
            let n = (
                c.checked_add(dc)?.checked_sub(1)?,
                r.checked_add(dr)?.checked_sub(1)?,
            );
            Some(n).filter(|_| self.diagonal)
        };
        [
            c.checked_sub(1).map(|c| (c, r)),
            Some((c + 1, r)),
            r.checked_sub(1).map(|r| (c, r)),
            Some((c, r + 1)),
            corner(0, 0),
            corner(2, 0),
            corner(0, 2),
            corner(2, 2),
        ]
        .into_iter()
        .flatten()
        .filter(|&n| self.label(n) == Some(want))
        .min_by_key(|&n| d2(n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wall across column 10 from row 0 to row 40: the way round is over its top.
    fn wall() -> Rows {
        let mut b = [0u64; ROUTE_SIDE];
        for row in b.iter_mut().take(41) {
            *row |= 1 << 10;
        }
        b
    }

    #[test]
    fn the_way_down_goes_round_the_wall_and_has_no_minimum() {
        let mut w = Wavefront::new();
        let (source, target) = ((20, 5), (2, 5));
        assert_eq!(
            w.spread(&wall(), (source, target), 400, false),
            Some(36 + 18 + 36)
        );
        let mut cell = target;
        let mut steps = 0;
        let mut highest = 0;
        while let Some(n) = w.downhill(cell, source) {
            cell = n;
            highest = highest.max(cell.1);
            steps += 1;
            assert!(steps < 400);
        }
        assert_eq!(cell, source, "every walk ends at the source");
        assert_eq!(highest, 41, "over the wall's top");
        // Shortest 4-neighbour path: up 36, across 18, down 36.
        assert_eq!(steps, 36 + 18 + 36);
    }

    #[test]
    fn cells_that_touch_only_at_their_corners_are_crossed_only_by_diagonal_steps() {
        // Cell (k, k) blocked for every k: the free cells on either side of that line touch
        // only at their corners.
        let mut b = [0u64; ROUTE_SIDE];
        for (k, row) in b.iter_mut().enumerate() {
            *row = 1 << k;
        }
        let (source, target) = ((5, 30), (30, 5));
        let mut w = Wavefront::new();
        assert_eq!(w.spread(&b, (source, target), 4000, false), None);
        // Diagonally, the straight way: 25 steps, one of them through a corner.
        assert_eq!(w.spread(&b, (source, target), 4000, true), Some(25));
        let (mut cell, mut steps) = (target, 0);
        while let Some(n) = w.downhill(cell, source) {
            assert_ne!(b[n.1] & (1 << n.0), 1 << n.0, "{n:?} is blocked");
            cell = n;
            steps += 1;
            assert!(steps <= 25);
        }
        assert_eq!(cell, source, "the walk ends at the source");
    }

    #[test]
    fn an_enclosed_target_is_not_reached() {
        let mut b = [0u64; ROUTE_SIDE];
        for (r, row) in b.iter_mut().enumerate().take(13).skip(7) {
            *row = if r == 7 || r == 12 {
                0b11_1111 << 7
            } else {
                0b10_0001 << 7
            };
        }
        let mut w = Wavefront::new();
        assert_eq!(w.spread(&b, ((40, 40), (9, 9)), 4000, false), None);
        assert_eq!(w.label((9, 9)), None);
        assert!(w.label((0, 0)).is_some(), "everything outside is reached");
    }
}
