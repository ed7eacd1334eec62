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
            Shape::Circle(c) => (p - c.center).norm() - c.radius,
            Shape::Rectangle(r) => r.signed_distance(p),
            Shape::Ellipse(e) => e.signed_distance(p),
            Shape::Polygon(g) => g.signed_distance(p),
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
            Shape::Ellipse(Ellipse(r)) => r.half.x.max(r.half.y),
            Shape::Polygon(g) => {
                let c = g.centroid();
                g.vertices().iter().fold(0.0, |m, v| m.max((*v - c).norm()))
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
    fn signed_distance(&self, p: Vec2) -> f32 {
        let q = self.local(p);
        let d = Vec2::new(q.x.abs() - self.half.x, q.y.abs() - self.half.y);
        let outside = Vec2::new(max(d.x, 0.0), max(d.y, 0.0)).norm();
        let inside = min(max(d.x, d.y), 0.0);
        outside + inside
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
    fn signed_distance(&self, p: Vec2) -> f32 {
        let r = &self.0;
        let q = r.local(p);
        let (a, b) = (r.half.x, r.half.y);
        let k0 = Vec2::new(q.x / a, q.y / b).norm();
        let k1 = Vec2::new(q.x / (a * a), q.y / (b * b)).norm();
        if k1 > 1e-12 {
            k0 * (k0 - 1.0) / k1
        } else {
            -a.min(b)
        }
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
        let scale = used.iter().fold(0.0f32, |m, v| m.max((*v - first).norm()));
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
    fn signed_distance(&self, p: Vec2) -> f32 {
        let v = self.vertices();
        let mut best2 = f32::INFINITY;
        let mut inside = true;
        for (i, inv) in self.inv_len2.iter().take(v.len()).enumerate() {
            let (a, b) = edge(v, i);
            let e = b - a;
            let w = p - a;
            let t = min(max(w.dot(e) * inv, 0.0), 1.0);
            best2 = min((w - e * t).norm2(), best2);
            inside &= e.cross(w) >= 0.0;
        }
        let d = sqrt(best2);
        if inside {
            -d
        } else {
            d
        }
    }
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
