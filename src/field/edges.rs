//! A convex polygon's edges laid out for the points of one sample circle: the polygon's
//! signed distance ([`crate::field::shape`]) at n_γ points, bit for bit, for less.
//!
//! [`Polygon::signed_distance`] measures, at each point, the segments of the edges the point
//! lies strictly outside of (cross product < 0), or every segment when it is inside. Two
//! things here cost less and change no number:
//!
//! - **Rows.** Each edge's start vertex a, vector e = b − a and 1/|e|² side by side, found once
//!   per polygon and step, where the polygon keeps vertices and 1/|e|² in two arrays and
//!   walks them round from the closing edge at every point.
//! - **Sides.** Which side of an edge's line a point lies on is decided, for all points of the
//!   circle at once, from the circle's centre when the circle is clear of the line (below):
//!   an edge every point lies outside of is measured without its test; an edge no point lies
//!   outside of is not visited (except inside the polygon, where every segment is measured).
//!   Only the edges whose line crosses the circle (or comes near it) are tested per point.
//!
//! **Why the sides agree with the per-point test, bit for bit.** The points are
//! x = fl(fl(o + d) − s), |d| ≤ ε, o the vehicle, s the obstacle's shift; the centre is
//! c = fl(o − s). The per-point test is the sign of fl(e × fl(x − a)). Each coordinate above is
//! rounded at most three times, by at most u = 2⁻²⁴ of a number no larger than
//! U = |o|₁ + |s|₁ + |a|₁ + 2ε, so fl(x − a) = (c − a) + d + η with |η| ≤ 8uU, and the cross
//! product's own rounding is at most 2u·|e|·U: the computed crosses at x and at c differ by at
//! most |e|·(ε + 12uU) (e × d is at most |e|ε). An edge is decided from the centre only when
//! |fl(e × fl(c − a))| > |e|·(1.01ε + 10⁻⁵·U), more than 160 times that rounding margin (10⁻⁵ ≫
//! 12u ≈ 7·10⁻⁷) and 1 % beyond ε for the rounding of |e| and of the comparison: then every
//! point's computed cross has the centre's sign. NaN decides nothing (every comparison fails):
//! such an edge is tested per point, as before.

use super::shape::{segment_distance2, Polygon, MAX_POLYGON_VERTICES};
use crate::math::{min, sqrt, Vec2};

/// One edge from a to b: a, e = b − a and 1/|e|².
#[derive(Clone, Copy, Default)]
struct EdgeRow {
    a: Vec2,
    e: Vec2,
    inv: f32,
}

/// A polygon's edges for the points of one circle: rows `..outside` have every point outside
/// their line, rows `outside..tested` are tested per point, the rest have no point outside.
pub(crate) struct EdgeTable {
    rows: [EdgeRow; MAX_POLYGON_VERTICES],
    outside: usize,
    tested: usize,
    n: usize,
}

impl EdgeTable {
    /// Every edge tested per point: valid for any point.
    #[cfg(test)]
    fn new(g: &Polygon) -> Self {
        let mut t = EdgeTable::empty();
        g.each_edge_from(|a, e, inv| {
            if let Some(slot) = t.rows.get_mut(t.n) {
                *slot = EdgeRow { a, e, inv };
                t.n += 1;
            }
        });
        t.tested = t.n;
        t
    }

    /// For the points fl(fl(`o` + d) − `s`) with |d| ≤ `epsilon`: the sides decided from the
    /// centre where the circle is clear of an edge's line (module notes).
    pub(crate) fn around(g: &Polygon, o: Vec2, s: Vec2, epsilon: f32) -> Self {
        let c = o - s;
        let scale = o.x.abs() + o.y.abs() + s.x.abs() + s.y.abs() + 2.0 * epsilon;
        // Each edge's side (0 outside, 1 tested, 2 no point outside) and how many of each.
        let mut sides = [1u8; MAX_POLYGON_VERTICES];
        let mut count = [0usize; 3];
        let mut i = 0;
        g.each_edge_from(|a, e, inv| {
            let k = e.cross(c - a);
            let m = 1.01 * epsilon + 1e-5 * (scale + a.x.abs() + a.y.abs());
            // |k|/|e| > m, without a root.
            let side = match (k * k * inv > m * m, k < 0.0) {
                (false, _) => 1,
                (true, true) => 0,
                (true, false) => 2,
            };
            if let (Some(slot), Some(n)) = (sides.get_mut(i), count.get_mut(usize::from(side))) {
                *slot = side;
                *n += 1;
            }
            i += 1;
        });
        // The rows grouped by side (order within a group changes no minimum).
        let mut t = EdgeTable::empty();
        let [outside, tested, _] = count;
        let mut next = [0, outside, outside + tested];
        let mut i = 0;
        g.each_edge_from(|a, e, inv| {
            let side = sides.get(i).copied().unwrap_or(1);
            if let Some(k) = next.get_mut(usize::from(side)) {
                if let Some(row) = t.rows.get_mut(*k) {
                    *row = EdgeRow { a, e, inv };
                    *k += 1;
                    t.n += 1;
                }
            }
            i += 1;
        });
        t.outside = outside;
        t.tested = outside + tested;
        t
    }

    fn empty() -> Self {
        EdgeTable {
            rows: [EdgeRow::default(); MAX_POLYGON_VERTICES],
            outside: 0,
            tested: 0,
            n: 0,
        }
    }

    /// [`Polygon::signed_distance`] at `p`, one of the points the table was made for.
    #[inline(always)]
    pub(crate) fn signed_distance(&self, p: Vec2) -> f32 {
        let rows = self.rows.get(..self.n).unwrap_or(&[]);
        let outside = rows.get(..self.outside).unwrap_or(&[]);
        let tested = rows.get(self.outside..self.tested).unwrap_or(&[]);
        let mut best2 = f32::INFINITY;
        let mut inside = outside.is_empty();
        for r in outside {
            best2 = min(segment_distance2(r.e, p - r.a, r.inv), best2);
        }
        for r in tested {
            let w = p - r.a;
            if r.e.cross(w) < 0.0 {
                inside = false;
                best2 = min(segment_distance2(r.e, w, r.inv), best2);
            }
        }
        if inside {
            for r in rows {
                best2 = min(segment_distance2(r.e, p - r.a, r.inv), best2);
            }
            -sqrt(best2)
        } else {
            sqrt(best2)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::Shape;
    use crate::math::{XorShift32, TAU};

    /// Every point of random circles — clear of the polygon, crossing its edges, inside it,
    /// tangent to edge lines, far from the origin — gets the polygon's own distance, bit for
    /// bit, and most edges are decided from the centre.
    #[test]
    fn the_table_gives_the_polygons_distance_bit_for_bit() {
        let mut rng = XorShift32::new(31);
        let mut u = move || (rng.next_u32() >> 8) as f32 / (1u32 << 24) as f32;
        let (mut decided, mut edges, mut inside) = (0usize, 0usize, 0usize);
        for case in 0..4000 {
            let far = [0.0, 100.0, 3000.0][case % 3];
            let c = Vec2::from_angle(TAU * u()) * (far * u());
            let n = 3 + (u() * 6.0) as usize;
            let (size, start) = (0.05 + 3.0 * u(), TAU * u());
            let pts: [Vec2; MAX_POLYGON_VERTICES] = core::array::from_fn(|k| {
                let a = start + TAU * (k as f32 + 0.4 * u()) / n as f32;
                c + Vec2::from_angle(a) * size
            });
            let Ok(Shape::Polygon(g)) = Shape::polygon(&pts[..n]) else {
                continue;
            };
            let epsilon = 0.01 + 0.5 * u();
            let s = Vec2::new(u() - 0.5, u() - 0.5) * (4.0 * u());
            // The circle's centre near the polygon, or just clear of one of its edge lines.
            let mut o = c + s + Vec2::from_angle(TAU * u()) * (3.0 * size * u());
            if case % 4 == 0 {
                let v = g.vertices();
                let (a, b) = (v[0], v[1]);
                let normal = Vec2::new(b.y - a.y, a.x - b.x).normalized(0.0).unwrap();
                let along = a + (b - a) * (2.0 * u() - 0.5);
                o = along + s + normal * (epsilon * (1.0 + 0.1 * (u() - 0.5)));
            }
            let t = EdgeTable::around(&g, o, s, epsilon);
            decided += t.outside + (t.n - t.tested);
            edges += t.n;
            let circle: [Vec2; 16] =
                core::array::from_fn(|i| Vec2::from_angle(TAU * i as f32 / 16.0) * epsilon);
            for d in circle.into_iter().chain([Vec2::ZERO]) {
                let x = (o + d) - s;
                let want = g.signed_distance(x);
                inside += usize::from(want < 0.0);
                assert_eq!(
                    t.signed_distance(x).to_bits(),
                    want.to_bits(),
                    "{g:?} {o:?} {s:?} {d:?}"
                );
                assert_eq!(
                    EdgeTable::new(&g).signed_distance(x).to_bits(),
                    want.to_bits()
                );
            }
        }
        assert!(
            decided * 2 > edges && decided < edges,
            "{decided} of {edges}"
        );
        assert!(inside > 1000, "{inside}");
    }
}
