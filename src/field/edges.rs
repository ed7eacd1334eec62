//! A convex polygon's edges laid out for the points of one sample circle: the polygon's
//! signed distance ([`crate::field::shape`]) at n_γ points, bit for bit, for less.
//!
//! [`Polygon::signed_distance`] measures, at each point, the segments of the edges the point
//! lies strictly outside of (cross product < 0), or every segment when it is inside. Three
//! things here cost less and change no number:
//!
//! - **Rows.** Each edge's start vertex a, vector e = b − a and 1/|e|² side by side, found once
//!   per polygon and step (in one pass with the sides), where the polygon keeps vertices and
//!   1/|e|² in two arrays and walks them round from the closing edge at every point.
//! - **Sides.** Which side of an edge's line a point lies on is decided, for all points of the
//!   circle at once, from the circle's centre when the circle is clear of the line (below):
//!   an edge every point lies outside of is measured without its test; an edge no point lies
//!   outside of is not visited. Only the edges whose line crosses the circle (or comes near
//!   it) are tested per point. A point found inside the polygon (no edge faces it: rare on
//!   the sample circle) is measured by the polygon itself.
//! - **Ends.** For an edge every point lies outside of, whether the nearest point of its
//!   segment is its start (or its end) for every point is decided the same way, from the
//!   centre's projection ([`nearest`]); the projection is then not computed per point.
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

/// One edge from a to b: a, e = b − a and 1/|e|², and where the nearest point of its segment
/// lies for every point of the circle, if that is known.
#[derive(Clone, Copy, Default)]
struct EdgeRow {
    a: Vec2,
    e: Vec2,
    inv: f32,
    nearest: Nearest,
}

/// Where on an edge's segment the nearest point to every point of the circle lies: the
/// clamped projection t = min(max(⟨w, e⟩/|e|², 0), 1) of `segment_distance2`.
#[derive(Clone, Copy, Default, PartialEq)]
enum Nearest {
    /// Not known: t is computed per point.
    #[default]
    Projected,
    /// t = 0 at every point: the segment's distance is |w|, bit for bit (w − e·0 is w).
    Start,
    /// t = 1 at every point: |w − e|, bit for bit (e·1 is e).
    End,
}

/// A polygon's edges for the points of one circle: rows `..outside` have every point outside
/// their line, rows `tested..` are tested per point; the edges no point lies outside of are
/// left out. One table serves a step's polygons in turn ([`EdgeTable::fill`]).
pub(crate) struct EdgeTable {
    rows: [EdgeRow; MAX_POLYGON_VERTICES],
    outside: usize,
    tested: usize,
}

/// Where the nearest point of the segment from a along `e` lies for every point of a circle
/// about c (`w` = c − a, `inv` = 1/|e|², `m` the sides' margin of the module notes): from
/// ⟨w, e⟩ against 0 and against |e|², decided when it is farther than |e|·m from either
/// (the margin grown by 10⁻⁵·|e|₁ for the rounding of w − e).
fn nearest(w: Vec2, e: Vec2, inv: f32, m: f32) -> Nearest {
    let d0 = e.dot(w);
    let d1 = e.dot(w - e);
    let m1 = m + 1e-5 * (e.x.abs() + e.y.abs());
    if d0 < 0.0 && d0 * d0 * inv > m * m {
        Nearest::Start
    } else if d1 > 0.0 && d1 * d1 * inv > m1 * m1 {
        Nearest::End
    } else {
        Nearest::Projected
    }
}

impl EdgeTable {
    /// An empty table (every point inside: [`EdgeTable::signed_distance`] asks the polygon).
    pub(crate) fn new() -> Self {
        EdgeTable {
            rows: [EdgeRow::default(); MAX_POLYGON_VERTICES],
            outside: 0,
            tested: MAX_POLYGON_VERTICES,
        }
    }

    /// The table of `g` for the points fl(fl(`o` + d) − `s`) with |d| ≤ `epsilon`: the sides
    /// decided from the centre where the circle is clear of an edge's line (module notes). One
    /// pass: the outside rows fill the table from the front, the tested ones from the back.
    pub(crate) fn fill(&mut self, g: &Polygon, o: Vec2, s: Vec2, epsilon: f32) {
        let c = o - s;
        let scale = o.x.abs() + o.y.abs() + s.x.abs() + s.y.abs() + 2.0 * epsilon;
        let (mut outside, mut tested) = (0, MAX_POLYGON_VERTICES);
        let (vertices, inv) = g.edge_arrays();
        let (Some(&last), Some(&inv_last)) = (vertices.last(), inv.last()) else {
            return;
        };
        // As `Polygon::each_edge`: the closing edge first, each edge from its start vertex a.
        let (mut a, mut inv_a) = (last, inv_last);
        for (&b, &inv_b) in vertices.iter().zip(inv) {
            let e = b - a;
            let k = e.cross(c - a);
            let m = 1.01 * epsilon + 1e-5 * (scale + a.x.abs() + a.y.abs());
            // |k|/|e| > m, without a root.
            let slot = if k * k * inv_a > m * m {
                (k < 0.0).then(|| {
                    outside += 1;
                    (outside - 1, nearest(c - a, e, inv_a, m))
                })
            } else {
                // Near the line, or NaN: tested per point.
                tested -= 1;
                Some((tested, Nearest::Projected))
            };
            if let Some((row, nearest)) = slot.and_then(|(i, n)| Some((self.rows.get_mut(i)?, n))) {
                *row = EdgeRow {
                    a,
                    e,
                    inv: inv_a,
                    nearest,
                };
            }
            a = b;
            inv_a = inv_b;
        }
        self.outside = outside;
        self.tested = tested;
    }

    /// [`Polygon::signed_distance`] of `g` at `p`, one of the points the table was filled for.
    #[inline(always)]
    pub(crate) fn signed_distance(&self, g: &Polygon, p: Vec2) -> f32 {
        let outside = self.rows.get(..self.outside).unwrap_or(&[]);
        let tested = self.rows.get(self.tested..).unwrap_or(&[]);
        let mut best2 = f32::INFINITY;
        let mut inside = outside.is_empty();
        for r in outside {
            let w = p - r.a;
            let d2 = match r.nearest {
                Nearest::Start => w.norm2(),
                Nearest::End => (w - r.e).norm2(),
                Nearest::Projected => segment_distance2(r.e, w, r.inv),
            };
            best2 = min(d2, best2);
        }
        for r in tested {
            let w = p - r.a;
            if r.e.cross(w) < 0.0 {
                inside = false;
                best2 = min(segment_distance2(r.e, w, r.inv), best2);
            }
        }
        if inside {
            g.signed_distance(p)
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
        let (mut t, mut all) = (EdgeTable::new(), EdgeTable::new());
        let mut ends = 0;
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
            // One table for every polygon in turn, as in a step.
            t.fill(&g, o, s, epsilon);
            all.fill(&g, o, s, f32::INFINITY);
            decided += n + t.tested - MAX_POLYGON_VERTICES;
            for r in t.rows.iter().take(t.outside) {
                ends += usize::from(r.nearest != Nearest::Projected);
            }
            edges += n;
            let circle: [Vec2; 16] =
                core::array::from_fn(|i| Vec2::from_angle(TAU * i as f32 / 16.0) * epsilon);
            for d in circle.into_iter().chain([Vec2::ZERO]) {
                let x = (o + d) - s;
                let want = g.signed_distance(x);
                inside += usize::from(want < 0.0);
                assert_eq!(
                    t.signed_distance(&g, x).to_bits(),
                    want.to_bits(),
                    "{g:?} {o:?} {s:?} {d:?}"
                );
                assert_eq!(all.signed_distance(&g, x).to_bits(), want.to_bits());
            }
        }
        assert!(
            decided * 2 > edges && decided < edges,
            "{decided} of {edges}"
        );
        assert!(inside > 1000, "{inside}");
        assert!(ends > 1000, "{ends}");
    }
}
