//! Obstacle geometry: the distance function r(p) each obstacle's potential distribution
//! function is built on (seed 000 eq. 10–12, seed 002 §1: circle, ellipse, rectangle, triangle).
//!
//! Every shape answers one question, its **signed distance**: positive outside (metres to the
//! surface), zero on it, negative inside. The papers only need r ≥ 0; the sign is ours, so that
//! the repulsion keeps rising inside an obstacle and its field still points out.

use crate::math::{max, min, sin_cos, sqrt, Vec2};

/// Most vertices a convex polygon may have (a triangle needs 3; sonar fits and charts rarely
/// need more than 8).
pub const MAX_POLYGON_VERTICES: usize = 8;

/// Largest extent (radius, half-size, semi-axis, vertex distance from the first vertex) a shape
/// may have, in metres. Bigger numbers are surely a unit or parsing error.
pub const MAX_EXTENT_M: f32 = 10_000.0;
/// Smallest size a shape may have, in metres (below it the geometry is degenerate).
pub const MIN_EXTENT_M: f32 = 1e-3;

/// Why a shape was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ShapeError {
    /// A coordinate, size or angle is NaN or infinite.
    NonFinite,
    /// A size is at most [`MIN_EXTENT_M`] or above [`MAX_EXTENT_M`].
    SizeOutOfRange,
    /// Fewer than 3 or more than [`MAX_POLYGON_VERTICES`] vertices.
    VertexCount,
    /// The polygon is not convex, or has (nearly) collinear or repeated vertices.
    NotConvex,
}

impl core::fmt::Display for ShapeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ShapeError::NonFinite => "shape has a non-finite coordinate, size or angle",
            ShapeError::SizeOutOfRange => "shape size out of range (1 mm .. 10 km)",
            ShapeError::VertexCount => "polygon needs 3 to 8 vertices",
            ShapeError::NotConvex => "polygon is not strictly convex",
        })
    }
}

impl core::error::Error for ShapeError {}

/// The geometry of an obstacle. Construct with the checked constructors; the fields stay
/// private so a `Shape` is always valid.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Shape {
    /// Circle of radius r₀ (seed 000 eq. 12).
    Circle(Circle),
    /// Rectangle with half-sizes a, b, rotated by φ (seed 000 eq. 10–11).
    Rectangle(Rectangle),
    /// Ellipse with semi-axes a, b, rotated by φ (seed 002 §1).
    Ellipse(Ellipse),
    /// Convex polygon, covering triangles (seed 002 §1).
    Polygon(Polygon),
}

/// See [`Shape::Circle`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Circle {
    center: Vec2,
    radius: f32,
}

/// See [`Shape::Rectangle`]. Also the ellipse's frame: centre, half-sizes and the rotation.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rectangle {
    center: Vec2,
    half: Vec2,
    angle: f32,
    cos: f32,
    sin: f32,
}

/// See [`Shape::Ellipse`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ellipse(Rectangle);

/// See [`Shape::Polygon`]. Vertices are stored counter-clockwise.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Polygon {
    vertices: [Vec2; MAX_POLYGON_VERTICES],
    /// 1/|edge|² per edge, so the hot loop has no division.
    inv_len2: [f32; MAX_POLYGON_VERTICES],
    len: u8,
}

fn check_size(v: f32) -> Result<f32, ShapeError> {
    if !v.is_finite() {
        Err(ShapeError::NonFinite)
    } else if !(MIN_EXTENT_M..=MAX_EXTENT_M).contains(&v) {
        Err(ShapeError::SizeOutOfRange)
    } else {
        Ok(v)
    }
}

fn check_point(p: Vec2) -> Result<Vec2, ShapeError> {
    if p.is_finite() {
        Ok(p)
    } else {
        Err(ShapeError::NonFinite)
    }
}

impl Shape {
    /// A circle (seed 000 eq. 12).
    pub fn circle(center: Vec2, radius: f32) -> Result<Shape, ShapeError> {
        Ok(Shape::Circle(Circle {
            center: check_point(center)?,
            radius: check_size(radius)?,
        }))
    }

    /// A rectangle of half-sizes `half.x` (along its own x axis) and `half.y`, rotated by
    /// `angle` radians from the global +x axis (seed 000 eq. 10–11).
    pub fn rectangle(center: Vec2, half: Vec2, angle: f32) -> Result<Shape, ShapeError> {
        Ok(Shape::Rectangle(Rectangle::new(center, half, angle)?))
    }

    /// An ellipse of semi-axes `semi.x`, `semi.y`, rotated by `angle` radians.
    pub fn ellipse(center: Vec2, semi: Vec2, angle: f32) -> Result<Shape, ShapeError> {
        Ok(Shape::Ellipse(Ellipse(Rectangle::new(
            center, semi, angle,
        )?)))
    }

    /// A convex polygon from 3 to [`MAX_POLYGON_VERTICES`] vertices in either winding order.
    pub fn polygon(points: &[Vec2]) -> Result<Shape, ShapeError> {
        Polygon::new(points).map(Shape::Polygon)
    }

    /// Signed distance from `p` to the surface in metres: > 0 outside, < 0 inside.
    pub fn signed_distance(&self, p: Vec2) -> f32 {
        match self {
            Shape::Circle(c) => c.signed_distance(p),
            Shape::Rectangle(r) => r.signed_distance(p),
            Shape::Ellipse(e) => e.signed_distance(p),
            Shape::Polygon(g) => g.signed_distance(p),
        }
    }

    /// The signed distance r at `p` (bit for bit [`Shape::signed_distance`]) and its gradient
    /// ∇r there, analytic: a unit vector for the exact distances (circle, rectangle, polygon;
    /// outward, also inside), the derivative of the estimate for the ellipse. Where r has no
    /// gradient (the centre of a circle, equidistant sides inside a rectangle) one of the
    /// one-sided ones is given. One evaluation, for the far field (`planner::gradient`).
    pub fn distance_gradient(&self, p: Vec2) -> (f32, Vec2) {
        match self {
            Shape::Circle(c) => c.distance_gradient(p),
            Shape::Rectangle(r) => r.distance_gradient(p),
            Shape::Ellipse(e) => e.distance_gradient(p),
            Shape::Polygon(g) => g.distance_gradient(p),
        }
    }

    /// Unit outward direction of the distance field at `p` (the direction in which the signed
    /// distance grows fastest), by forward differences over `h` metres from `d`, the signed
    /// distance at `p` the caller already has. Called once per obstacle per step (rotor
    /// potentials), never per gradient sample.
    pub fn outward_normal(&self, p: Vec2, d: f32, h: f32) -> Vec2 {
        if let Shape::Circle(c) = self {
            if let Some(n) = (p - c.center).normalized(1e-9) {
                return n;
            }
        }
        let dx = self.signed_distance(p + Vec2::new(h, 0.0)) - d;
        let dy = self.signed_distance(p + Vec2::new(0.0, h)) - d;
        Vec2::new(dx, dy)
            .normalized(1e-9)
            .or_else(|| (p - self.center()).normalized(1e-9))
            .unwrap_or(Vec2::new(1.0, 0.0))
    }

    /// The representative point of the obstacle (seed 001 eq. 1: its barycentre).
    pub fn center(&self) -> Vec2 {
        match self {
            Shape::Circle(c) => c.center,
            Shape::Rectangle(r) | Shape::Ellipse(Ellipse(r)) => r.center,
            Shape::Polygon(g) => g.centroid(),
        }
    }

    /// Radius of the smallest circle about [`Shape::center`] that holds the shape.
    pub fn bounding_radius(&self) -> f32 {
        match self {
            Shape::Circle(c) => c.radius,
            Shape::Rectangle(r) => r.half.norm(),
            Shape::Ellipse(Ellipse(r)) => crate::math::max(r.half.x, r.half.y),
            // One square root: √ is monotonic and correctly rounded, so the root of the
            // largest square is the largest root, bit for bit.
            Shape::Polygon(g) => {
                let c = g.centroid();
                let far2 = g
                    .vertices()
                    .iter()
                    .fold(0.0, |m, v| crate::math::max((*v - c).norm2(), m));
                crate::math::sqrt(far2)
            }
        }
    }

    /// The same shape moved by `d` metres (used for moving obstacles and tests).
    pub fn translated(&self, d: Vec2) -> Shape {
        let mut s = *self;
        match &mut s {
            Shape::Circle(c) => c.center += d,
            Shape::Rectangle(r) | Shape::Ellipse(Ellipse(r)) => r.center += d,
            Shape::Polygon(g) => g.vertices.iter_mut().for_each(|v| *v += d),
        }
        s
    }
}

impl Circle {
    /// Seed 000 eq. 12's r: the distance to the centre less r₀.
    #[inline(always)]
    pub(crate) fn signed_distance(&self, p: Vec2) -> f32 {
        (p - self.center).norm() - self.radius
    }

    fn distance_gradient(&self, p: Vec2) -> (f32, Vec2) {
        let d = p - self.center;
        let len = d.norm();
        let n = if len > 0.0 {
            d * (1.0 / len)
        } else {
            Vec2::new(1.0, 0.0)
        };
        (len - self.radius, n)
    }

    /// Centre.
    pub fn center(&self) -> Vec2 {
        self.center
    }
    /// Radius r₀.
    pub fn radius(&self) -> f32 {
        self.radius
    }
}

impl Rectangle {
    fn new(center: Vec2, half: Vec2, angle: f32) -> Result<Self, ShapeError> {
        if !angle.is_finite() {
            return Err(ShapeError::NonFinite);
        }
        let (sin, cos) = sin_cos(angle);
        Ok(Rectangle {
            center: check_point(center)?,
            half: Vec2::new(check_size(half.x)?, check_size(half.y)?),
            angle,
            cos,
            sin,
        })
    }

    /// `R(−φ)(p − p_cen)`: `p` in the obstacle's own frame.
    fn local(&self, p: Vec2) -> Vec2 {
        (p - self.center).rotate_cs(self.cos, -self.sin)
    }

    /// Seed 000 eq. 10–11: outside, r = ‖disc ⊙ (|q| − [a b]ᵀ)‖ with disc the element-wise
    /// `|q| > [a b]ᵀ`, i.e. the Euclidean distance to the box. Inside (where the paper's r is 0)
    /// we return minus the depth, the distance to the nearest side.
    #[inline(always)]
    pub(crate) fn signed_distance(&self, p: Vec2) -> f32 {
        let q = self.local(p);
        let d = Vec2::new(q.x.abs() - self.half.x, q.y.abs() - self.half.y);
        let outside = Vec2::new(max(d.x, 0.0), max(d.y, 0.0)).norm();
        let inside = min(max(d.x, d.y), 0.0);
        outside + inside
    }

    /// Eq. 10–11's disc for every point fl(fl(`o` + d) − `s`) with |d| ≤ `epsilon`, decided
    /// once from the centre: for each axis 1 if every point has |q| beyond the half-size, 0 if
    /// every point has it within; `None` if an axis is undecided (the circle comes within
    /// 1.01ε + 10⁻⁵·U of a side's line, U = |o|₁ + |s|₁ + |p_cen|₁ + 2ε: the margin and its
    /// reasons are `field::edges`'s) or if every point is inside.
    pub(crate) fn disc_around(&self, o: Vec2, s: Vec2, epsilon: f32) -> Option<Vec2> {
        let q = self.local(o - s);
        let c = self.center;
        let scale = o.x.abs() + o.y.abs() + s.x.abs() + s.y.abs() + c.x.abs() + c.y.abs();
        let m = 1.01 * epsilon + 1e-5 * (scale + 2.0 * epsilon);
        let disc = |q: f32, half: f32| {
            let d = q.abs() - half;
            if d > m {
                Some(1.0)
            } else if d < -m {
                Some(0.0)
            } else {
                None
            }
        };
        let disc = Vec2::new(disc(q.x, self.half.x)?, disc(q.y, self.half.y)?);
        (disc != Vec2::ZERO).then_some(disc)
    }

    /// [`Rectangle::signed_distance`] at a point outside the box whose `disc` is known
    /// ([`Rectangle::disc_around`]): eq. 10–11 as printed, ‖disc ⊙ (|q| − [a b]ᵀ)‖, the same
    /// number without the comparisons (the element-wise max with 0 is the product with the
    /// disc, inside's term is +0, and x·0 squares to +0).
    #[inline(always)]
    pub(crate) fn outside_distance(&self, p: Vec2, disc: Vec2) -> f32 {
        let q = self.local(p);
        let d = Vec2::new(q.x.abs() - self.half.x, q.y.abs() - self.half.y);
        Vec2::new(d.x * disc.x, d.y * disc.y).norm()
    }

    /// Outside, the unit vector from the nearest point of the box; inside, the normal of the
    /// nearest side. Both in the box's frame, turned back by φ.
    fn distance_gradient(&self, p: Vec2) -> (f32, Vec2) {
        let q = self.local(p);
        let d = Vec2::new(q.x.abs() - self.half.x, q.y.abs() - self.half.y);
        let o = Vec2::new(max(d.x, 0.0), max(d.y, 0.0));
        let outside = o.norm();
        let inside = min(max(d.x, d.y), 0.0);
        let sign = |v: f32| if v < 0.0 { -1.0 } else { 1.0 };
        let local = if outside > 0.0 {
            Vec2::new(sign(q.x) * o.x, sign(q.y) * o.y) * (1.0 / outside)
        } else if d.x > d.y {
            Vec2::new(sign(q.x), 0.0)
        } else {
            Vec2::new(0.0, sign(q.y))
        };
        (outside + inside, local.rotate_cs(self.cos, self.sin))
    }

    /// Centre.
    pub fn center(&self) -> Vec2 {
        self.center
    }
    /// Half-sizes [a b] along the rectangle's own axes.
    pub fn half_size(&self) -> Vec2 {
        self.half
    }
    /// Rotation φ from the global +x axis, radians.
    pub fn angle(&self) -> f32 {
        self.angle
    }
}

impl Ellipse {
    /// The distance to an ellipse has no closed form (it is a quartic). We use the first-order
    /// estimate d ≈ k₀(k₀ − 1)/k₁ with k₀ = ‖q ⊘ s‖, k₁ = ‖q ⊘ s²‖ (s the semi-axes): exact on
    /// the surface and along both axes, linear and increasing along every ray from the centre
    /// (so the repulsion stays monotonic), and two square roots instead of an iteration.
    #[inline(always)]
    pub(crate) fn signed_distance(&self, p: Vec2) -> f32 {
        let r = &self.0;
        let q = r.local(p);
        let (a, b) = (r.half.x, r.half.y);
        let k0 = Vec2::new(q.x / a, q.y / b).norm();
        let k1 = Vec2::new(q.x / (a * a), q.y / (b * b)).norm();
        if k1 > 1e-12 {
            k0 * (k0 - 1.0) / k1
        } else {
            -min(a, b)
        }
    }

    /// The estimate's own gradient: with Q₁ = q ⊘ s², Q₂ = q ⊘ s⁴ (so ∇k₀ = Q₁/k₀ and
    /// ∇k₁ = Q₂/k₁), ∇d = (2k₀ − 1)·Q₁/(k₀k₁) − d·Q₂/k₁², turned back by φ.
    fn distance_gradient(&self, p: Vec2) -> (f32, Vec2) {
        let r = &self.0;
        let q = r.local(p);
        let (a, b) = (r.half.x, r.half.y);
        let k0 = Vec2::new(q.x / a, q.y / b).norm();
        let q1 = Vec2::new(q.x / (a * a), q.y / (b * b));
        let k1 = q1.norm();
        if k1 <= 1e-12 || k0 <= 0.0 {
            return (-min(a, b), Vec2::new(1.0, 0.0).rotate_cs(r.cos, r.sin));
        }
        let d = k0 * (k0 - 1.0) / k1;
        let q2 = Vec2::new(q1.x / (a * a), q1.y / (b * b));
        let g = q1 * ((2.0 * k0 - 1.0) / (k0 * k1)) - q2 * (d / (k1 * k1));
        (d, g.rotate_cs(r.cos, r.sin))
    }

    /// The ellipse's centre, semi-axes and rotation, as a rectangle frame.
    pub fn frame(&self) -> &Rectangle {
        &self.0
    }
}

impl Polygon {
    fn new(points: &[Vec2]) -> Result<Self, ShapeError> {
        let n = points.len();
        if !(3..=MAX_POLYGON_VERTICES).contains(&n) {
            return Err(ShapeError::VertexCount);
        }
        let mut vertices = [Vec2::ZERO; MAX_POLYGON_VERTICES];
        for (slot, p) in vertices.iter_mut().zip(points) {
            *slot = check_point(*p)?;
        }
        let used = vertices.get(..n).unwrap_or(&[]);
        let first = used.first().copied().unwrap_or(Vec2::ZERO);
        if used.iter().any(|v| (*v - first).norm() > MAX_EXTENT_M) {
            return Err(ShapeError::SizeOutOfRange);
        }
        // Signed area tells the winding; store counter-clockwise.
        let area2: f32 = (0..n).map(|i| edge(used, i).0.cross(edge(used, i).1)).sum();
        if area2 < 0.0 {
            if let Some(s) = vertices.get_mut(..n) {
                s.reverse();
            }
        }
        let used = vertices.get(..n).unwrap_or(&[]);
        // Strict convexity: every corner turns left by a non-negligible amount.
        let scale = used
            .iter()
            .fold(0.0f32, |m, v| crate::math::max_num(m, (*v - first).norm()));
        let mut inv_len2 = [0.0; MAX_POLYGON_VERTICES];
        for i in 0..n {
            let (a, b) = edge(used, i);
            let (_, c) = edge(used, i + 1);
            let e = b - a;
            let len2 = e.norm2();
            if len2 < MIN_EXTENT_M * MIN_EXTENT_M || e.cross(c - b) <= 1e-6 * scale * scale {
                return Err(ShapeError::NotConvex);
            }
            if let Some(slot) = inv_len2.get_mut(i) {
                *slot = 1.0 / len2;
            }
        }
        Ok(Polygon {
            vertices,
            inv_len2,
            len: n as u8,
        })
    }

    /// The vertices, counter-clockwise.
    pub fn vertices(&self) -> &[Vec2] {
        self.vertices.get(..self.len as usize).unwrap_or(&[])
    }

    /// Vertex average (the barycentre of the vertices; enough as a representative point).
    pub fn centroid(&self) -> Vec2 {
        let v = self.vertices();
        let sum = v.iter().fold(Vec2::ZERO, |s, p| s + *p);
        sum * (1.0 / v.len().max(1) as f32)
    }

    /// Exact signed distance: the nearest edge segment gives the magnitude; the point is inside
    /// when it lies left of every (counter-clockwise) edge.
    ///
    /// Outside, only the segments of the edges the point lies strictly outside of are measured:
    /// the nearest point q lies on one of them. (If q is inside an edge, p is outside that
    /// edge's line. If q is a vertex, the direction u = (p − q)/|p − q| lies strictly inside
    /// the cone of its two edges' outward normals, which are less than π apart, so u makes an
    /// angle below π/2 with at least one of them — p is outside that edge's line — and that
    /// edge's segment holds q.) Each edge first costs one cross product; a far point faces
    /// about half of them. Inside (rare on the sample circle) every segment is measured, as
    /// before. A nearest vertex is then measured from one of its edges only, which may round
    /// its distance differently (by the rounding of the coordinates) from the lesser of both.
    #[inline(always)]
    pub(crate) fn signed_distance(&self, p: Vec2) -> f32 {
        let mut best2 = f32::INFINITY;
        let mut inside = true;
        self.each_edge(p, |e, w, inv| {
            if e.cross(w) < 0.0 {
                inside = false;
                best2 = min(segment_distance2(e, w, inv), best2);
            }
        });
        if inside {
            self.each_edge(p, |e, w, inv| {
                best2 = min(segment_distance2(e, w, inv), best2)
            });
            -sqrt(best2)
        } else {
            sqrt(best2)
        }
    }

    /// The vertices and each edge's 1/|e|² (edge i from vertex i to i + 1, the last one
    /// closing), for [`super::edges::EdgeTable`].
    pub(crate) fn edge_arrays(&self) -> (&[Vec2], &[f32]) {
        let n = usize::from(self.len).min(MAX_POLYGON_VERTICES);
        (
            self.vertices.get(..n).unwrap_or(&[]),
            self.inv_len2.get(..n).unwrap_or(&[]),
        )
    }

    /// `f(e, w, 1/|e|²)` for each edge from a to b (e = b − a, w = p − a), the closing edge
    /// first; no modulo on the way round.
    #[inline(always)]
    fn each_edge(&self, p: Vec2, mut f: impl FnMut(Vec2, Vec2, f32)) {
        let n = usize::from(self.len).min(MAX_POLYGON_VERTICES);
        let v = self.vertices.get(..n).unwrap_or(&[]);
        let inv = self.inv_len2.get(..n).unwrap_or(&[]);
        let (Some(&last), Some(&inv_last)) = (v.last(), inv.last()) else {
            return;
        };
        let mut a = last;
        let mut inv_a = inv_last;
        for (&b, &inv_b) in v.iter().zip(inv) {
            f(b - a, p - a, inv_a);
            a = b;
            inv_a = inv_b;
        }
    }

    /// The nearest edge's segment gives r and the unit vector from its nearest point. One
    /// walk round the edges: r is [`Polygon::signed_distance`]'s, bit for bit (outside the
    /// least of the facing segments, inside the least of all, the same numbers; the test
    /// `distance_gradient_is_the_distance_and_its_slope` holds it to that).
    fn distance_gradient(&self, p: Vec2) -> (f32, Vec2) {
        let mut facing2 = f32::INFINITY;
        let mut inside = true;
        let mut best = (f32::INFINITY, Vec2::new(1.0, 0.0), Vec2::ZERO);
        self.each_edge(p, |e, w, inv| {
            let t = min(max(w.dot(e) * inv, 0.0), 1.0);
            let from = w - e * t;
            let d2 = from.norm2();
            if e.cross(w) < 0.0 {
                inside = false;
                facing2 = min(d2, facing2);
            }
            if d2 < best.0 {
                best = (d2, from, e);
            }
        });
        let (d2, from, e) = best;
        let len = sqrt(d2);
        let r = if inside { -len } else { sqrt(facing2) };
        if len > 0.0 {
            let n = from * (1.0 / len);
            (r, if r < 0.0 { -n } else { n })
        } else {
            // On the surface: the edge's outward normal (right of a counter-clockwise edge).
            let n = Vec2::new(e.y, -e.x)
                .normalized(0.0)
                .unwrap_or(Vec2::new(1.0, 0.0));
            (r, n)
        }
    }
}

/// Squared distance from p to the segment from a along e (w = p − a, `inv` = 1/|e|²).
#[inline(always)]
pub(crate) fn segment_distance2(e: Vec2, w: Vec2, inv: f32) -> f32 {
    let t = min(max(w.dot(e) * inv, 0.0), 1.0);
    (w - e * t).norm2()
}

/// Edge `i` of a closed polygon: (vᵢ, vᵢ₊₁ mod n).
fn edge(v: &[Vec2], i: usize) -> (Vec2, Vec2) {
    let n = v.len().max(1);
    let a = v.get(i % n).copied().unwrap_or(Vec2::ZERO);
    let b = v.get((i + 1) % n).copied().unwrap_or(Vec2::ZERO);
    (a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f32, b: f32) -> bool {
        (a - b).abs() < 1e-4
    }

    #[test]
    fn circle_distance_is_signed() {
        let c = Shape::circle(Vec2::new(1.0, 1.0), 2.0).unwrap();
        assert!(close(c.signed_distance(Vec2::new(5.0, 1.0)), 2.0));
        assert!(close(c.signed_distance(Vec2::new(1.0, 1.0)), -2.0));
    }

    #[test]
    fn rotated_rectangle_matches_paper_distance_outside_and_depth_inside() {
        let r = Shape::rectangle(
            Vec2::ZERO,
            Vec2::new(2.0, 1.0),
            core::f32::consts::FRAC_PI_2,
        )
        .unwrap();
        // Rotated by 90°: the long side now runs along y.
        assert!(close(r.signed_distance(Vec2::new(0.0, 3.0)), 1.0));
        assert!(close(r.signed_distance(Vec2::new(2.0, 0.0)), 1.0));
        // Corner region: Euclidean distance to the corner (1, 2).
        assert!(close(r.signed_distance(Vec2::new(4.0, 6.0)), 5.0));
        assert!(close(r.signed_distance(Vec2::new(0.5, 0.0)), -0.5));
    }

    #[test]
    fn ellipse_distance_is_exact_on_axes_and_zero_on_surface() {
        let e = Shape::ellipse(Vec2::ZERO, Vec2::new(3.0, 1.0), 0.0).unwrap();
        assert!(close(e.signed_distance(Vec2::new(5.0, 0.0)), 2.0));
        assert!(close(e.signed_distance(Vec2::new(0.0, -4.0)), 3.0));
        let a = 0.7f32;
        let on = Vec2::new(3.0 * libm::cosf(a), libm::sinf(a));
        assert!(e.signed_distance(on).abs() < 1e-5);
        assert!(e.signed_distance(Vec2::ZERO) < 0.0);
    }

    #[test]
    fn polygon_accepts_either_winding_and_measures_exactly() {
        let cw = [
            Vec2::new(0.0, 0.0),
            Vec2::new(0.0, 2.0),
            Vec2::new(2.0, 0.0),
        ];
        let t = Shape::polygon(&cw).unwrap();
        assert!(close(t.signed_distance(Vec2::new(-1.0, 1.0)), 1.0));
        assert!(close(t.signed_distance(Vec2::new(-3.0, -4.0)), 5.0));
        assert!(t.signed_distance(Vec2::new(0.5, 0.5)) < 0.0);
    }

    #[test]
    fn bad_shapes_are_refused_with_the_reason() {
        assert_eq!(
            Shape::circle(Vec2::new(f32::NAN, 0.0), 1.0),
            Err(ShapeError::NonFinite)
        );
        assert_eq!(
            Shape::circle(Vec2::ZERO, 0.0),
            Err(ShapeError::SizeOutOfRange)
        );
        let concave = [
            Vec2::new(0.0, 0.0),
            Vec2::new(4.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 4.0),
        ];
        assert_eq!(Shape::polygon(&concave), Err(ShapeError::NotConvex));
        let line = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(2.0, 0.0),
        ];
        assert_eq!(Shape::polygon(&line), Err(ShapeError::NotConvex));
        assert_eq!(Shape::polygon(&line[..2]), Err(ShapeError::VertexCount));
    }

    /// Random shapes of every kind about `c`, from `rng`.
    fn random_shape(rng: &mut crate::math::XorShift32, c: Vec2) -> Shape {
        let mut u = || (rng.next_u32() >> 8) as f32 / (1u32 << 24) as f32;
        let size = Vec2::new(0.2 + 3.0 * u(), 0.2 + 3.0 * u());
        let angle = 6.3 * u();
        match (u() * 4.0) as u32 {
            0 => Shape::circle(c, size.x).unwrap(),
            1 => Shape::rectangle(c, size, angle).unwrap(),
            2 => Shape::ellipse(c, size, angle).unwrap(),
            _ => {
                // A convex polygon: 3–8 points at increasing angles on a jittered circle.
                let n = 3 + (u() * 6.0) as usize;
                let start = 6.3 * u();
                let mut pts = [Vec2::ZERO; MAX_POLYGON_VERTICES];
                for (k, pt) in pts.iter_mut().take(n).enumerate() {
                    let a = start + core::f32::consts::TAU * (k as f32 + 0.4 * u()) / n as f32;
                    *pt = c + Vec2::from_angle(a) * size.x;
                }
                Shape::polygon(&pts[..n]).unwrap_or(Shape::circle(c, size.x).unwrap())
            }
        }
    }

    #[test]
    fn polygon_distance_over_facing_edges_is_the_distance_over_all_edges() {
        let mut rng = crate::math::XorShift32::new(11);
        let mut polygons = 0;
        for _ in 0..2000 {
            let Shape::Polygon(g) = random_shape(&mut rng, Vec2::new(1.0, -2.0)) else {
                continue;
            };
            polygons += 1;
            for k in 0..50 {
                let r = 0.05 * (rng.next_u32() % 200) as f32;
                let p = Vec2::new(1.0, -2.0) + Vec2::from_angle(0.37 * k as f32) * r;
                // Every segment measured (the definition).
                let v = g.vertices();
                let mut best2 = f32::INFINITY;
                let mut inside = true;
                for (i, inv) in g.inv_len2.iter().take(v.len()).enumerate() {
                    let (a, b) = edge(v, i);
                    let (e, w) = (b - a, p - a);
                    best2 = best2.min(segment_distance2(e, w, *inv));
                    inside &= e.cross(w) >= 0.0;
                }
                let want = if inside { -best2.sqrt() } else { best2.sqrt() };
                // The same number but in the last bit: a vertex nearest p is measured from
                // one of its edges where the definition takes the lesser of both roundings.
                // (w − e differs from p − b by the rounding of coordinates of size |p|.)
                let got = g.signed_distance(p);
                let scale = v.iter().fold(p.norm(), |m, a| m.max(a.norm()));
                assert!(
                    (got - want).abs() <= 4.0 * f32::EPSILON * scale,
                    "{g:?} at {p:?}: {got} vs {want}"
                );
            }
        }
        assert!(polygons > 300);
    }

    #[test]
    fn distance_gradient_is_the_distance_and_its_slope() {
        let mut rng = crate::math::XorShift32::new(5);
        for _ in 0..2000 {
            let c = Vec2::new(3.0, 4.0);
            let s = random_shape(&mut rng, c);
            let a = 0.001 * (rng.next_u32() % 6283) as f32;
            let dist = 0.01 * (rng.next_u32() % 2000) as f32;
            let p = c + Vec2::from_angle(a) * dist;
            let (r, g) = s.distance_gradient(p);
            assert_eq!(
                r.to_bits(),
                s.signed_distance(p).to_bits(),
                "{s:?} at {p:?}"
            );
            if !matches!(s, Shape::Ellipse(_)) {
                assert!((g.norm() - 1.0).abs() < 1e-4, "{s:?} at {p:?}: {g:?}");
            }
            // Central differences agree where the distance is smooth (not on a ridge inside,
            // nor at a corner's edge): skip points near where r has a kink.
            let h = 1e-3;
            let fd = Vec2::new(
                s.signed_distance(p + Vec2::new(h, 0.0)) - s.signed_distance(p - Vec2::new(h, 0.0)),
                s.signed_distance(p + Vec2::new(0.0, h)) - s.signed_distance(p - Vec2::new(0.0, h)),
            ) * (0.5 / h);
            if r > 0.05 {
                assert!(
                    (fd - g).norm() < 2e-2 * g.norm().max(0.1),
                    "{s:?} at {p:?}: {g:?} vs {fd:?}"
                );
            }
        }
    }

    /// Eq. 10–11 with the disc decided once for a sample circle gives the rectangle's own
    /// distance at every point of it, bit for bit: circles clear of the sides, grazing a
    /// side's line, far from the origin.
    #[test]
    fn a_decided_disc_gives_the_rectangles_distance_bit_for_bit() {
        let mut rng = crate::math::XorShift32::new(17);
        let mut u = move || (rng.next_u32() >> 8) as f32 / (1u32 << 24) as f32;
        let tau = core::f32::consts::TAU;
        let (mut decided, mut cases) = (0, 0);
        for case in 0..6000 {
            let far = [0.0, 100.0, 3000.0][case % 3];
            let c = Vec2::from_angle(tau * u()) * (far * u());
            let half = Vec2::new(0.05 + 2.0 * u(), 0.05 + 2.0 * u());
            let Shape::Rectangle(r) = Shape::rectangle(c, half, tau * u()).unwrap() else {
                unreachable!()
            };
            let epsilon = 0.01 + 0.5 * u();
            let s = Vec2::new(u() - 0.5, u() - 0.5) * (4.0 * u());
            // In the box's frame: anywhere near it, or just clear of a side's line.
            let mut q = Vec2::new(u() - 0.5, u() - 0.5) * (6.0 * half.norm());
            if case % 2 == 0 {
                q.x = (half.x + epsilon * (1.0 + 0.1 * (u() - 0.5)))
                    * if u() < 0.5 { -1.0 } else { 1.0 };
            }
            let o = c + q.rotate_cs(r.cos, r.sin) + s;
            cases += 1;
            let Some(disc) = r.disc_around(o, s, epsilon) else {
                continue;
            };
            decided += 1;
            for i in 0..16 {
                let x = (o + Vec2::from_angle(tau * i as f32 / 16.0) * epsilon) - s;
                let want = r.signed_distance(x);
                assert!(want > 0.0);
                assert_eq!(
                    r.outside_distance(x, disc).to_bits(),
                    want.to_bits(),
                    "{r:?} {x:?}"
                );
            }
        }
        assert!(
            decided * 3 > cases && decided < cases,
            "{decided} of {cases}"
        );
    }

    #[test]
    fn outward_normal_points_away_inside_and_outside() {
        let r = Shape::rectangle(Vec2::ZERO, Vec2::new(2.0, 1.0), 0.0).unwrap();
        let at = |p: Vec2| r.outward_normal(p, r.signed_distance(p), 0.01);
        let n = at(Vec2::new(0.0, 3.0));
        assert!(close(n.y, 1.0));
        let n = at(Vec2::new(1.9, 0.1));
        assert!(close(n.x, 1.0));
    }
}
