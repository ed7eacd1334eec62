//! Ground-truth geometry of the simulated obstacles: where they are at time t, how far a point
//! is from them, where a sonar ray first meets them, and their firmware (`f32`) form.
//!
//! Conventions, shared with the firmware's `vpf::field::Shape`: the signed distance is positive
//! outside (metres to the surface), zero on it and negative inside; rectangle angles are radians
//! counter-clockwise from +x. Any input is accepted without panicking: a negative radius or
//! half-size counts by its magnitude, a non-finite velocity or time counts as zero, and shapes
//! with non-finite numbers are never hit and are at a NaN distance (callers compare with `<`, so
//! NaN is "not near"). [`SimShape::to_vpf`] is where invalid shapes are refused.

use crate::types::{SimObstacle, SimShape, P2};
use vpf::field::{Shape, ShapeError};

/// Cross product z-component `a × b`.
fn cross(a: P2, b: P2) -> f64 {
    a.x * b.y - a.y * b.x
}

fn dot(a: P2, b: P2) -> f64 {
    a.x * b.x + a.y * b.y
}

/// `p` rotated by the angle whose cosine and sine are `c`, `s`.
fn rotate(p: P2, c: f64, s: f64) -> P2 {
    P2::new(c * p.x - s * p.y, s * p.x + c * p.y)
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: P2, a: P2, b: P2) -> f64 {
    let e = b.sub(a);
    let l2 = dot(e, e);
    let s = if l2 > 0.0 {
        (dot(p.sub(a), e) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.sub(a.add(e.scale(s))).norm()
}

/// Whether `p` is inside the closed polygon (crossing-number rule, so any simple polygon works,
/// convex or not, in either winding order).
fn polygon_contains(points: &[P2], p: P2) -> bool {
    let n = points.len();
    if n < 3 {
        return false;
    }
    let mut inside = false;
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (points[i], points[j]);
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if p.x < x {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

/// Nearest `t ≥ 0` at which the ray `o + t·d` crosses an edge of the closed polygon.
fn polygon_ray(points: &[P2], o: P2, d: P2) -> Option<f64> {
    let n = points.len();
    if n < 2 {
        return None;
    }
    let mut best: Option<f64> = None;
    for i in 0..n {
        let a = points[i];
        let b = points[(i + 1) % n];
        let e = b.sub(a);
        let denom = cross(d, e);
        if denom.abs() < 1e-12 {
            // Parallel to this edge: the neighbouring edges catch a grazing hit.
            continue;
        }
        let w = a.sub(o);
        let t = cross(w, e) / denom;
        let s = cross(w, d) / denom;
        if t >= 0.0 && (0.0..=1.0).contains(&s) && t.is_finite() {
            best = Some(best.map_or(t, |b: f64| b.min(t)));
        }
    }
    best
}

/// A finite time, or 0.
fn finite_or_zero(t: f64) -> f64 {
    if t.is_finite() {
        t
    } else {
        0.0
    }
}

impl SimShape {
    /// The same shape moved by `d`.
    pub fn translated(&self, d: P2) -> SimShape {
        match self {
            SimShape::Circle { center, radius } => SimShape::Circle {
                center: center.add(d),
                radius: *radius,
            },
            SimShape::Rectangle {
                center,
                half_size,
                angle,
            } => SimShape::Rectangle {
                center: center.add(d),
                half_size: *half_size,
                angle: *angle,
            },
            SimShape::Polygon { points } => SimShape::Polygon {
                points: points.iter().map(|p| p.add(d)).collect(),
            },
        }
    }

    /// The shape's representative point: the centre, or a polygon's area centroid (its vertex
    /// mean when the area is degenerate; the origin for an empty polygon).
    pub fn center(&self) -> P2 {
        match self {
            SimShape::Circle { center, .. } | SimShape::Rectangle { center, .. } => *center,
            SimShape::Polygon { points } => {
                if points.is_empty() {
                    return P2::default();
                }
                let n = points.len();
                let mean = points
                    .iter()
                    .fold(P2::default(), |s, p| s.add(*p))
                    .scale(1.0 / n as f64);
                // Shoelace about the mean, so far-away polygons keep their precision.
                let (mut a2, mut cx, mut cy) = (0.0, 0.0, 0.0);
                for i in 0..n {
                    let p = points[i].sub(mean);
                    let q = points[(i + 1) % n].sub(mean);
                    let c = cross(p, q);
                    a2 += c;
                    cx += (p.x + q.x) * c;
                    cy += (p.y + q.y) * c;
                }
                if a2.abs() > 1e-12 {
                    mean.add(P2::new(cx / (3.0 * a2), cy / (3.0 * a2)))
                } else {
                    mean
                }
            }
        }
    }

    /// Radius of a circle about [`SimShape::center`] that holds the shape.
    pub fn bounding_radius(&self) -> f64 {
        match self {
            SimShape::Circle { radius, .. } => radius.abs(),
            SimShape::Rectangle { half_size, .. } => {
                P2::new(half_size.x.abs(), half_size.y.abs()).norm()
            }
            SimShape::Polygon { points } => {
                let c = self.center();
                points.iter().fold(0.0, |m, p| m.max(p.sub(c).norm()))
            }
        }
    }

    /// A rectangle's corners, counter-clockwise (other shapes: none).
    pub fn corners(&self) -> Option<[P2; 4]> {
        if let SimShape::Rectangle {
            center,
            half_size,
            angle,
        } = self
        {
            let (s, c) = angle.sin_cos();
            let (a, b) = (half_size.x.abs(), half_size.y.abs());
            let k = |x: f64, y: f64| center.add(rotate(P2::new(x, y), c, s));
            Some([k(a, b), k(-a, b), k(-a, -b), k(a, -b)])
        } else {
            None
        }
    }

    /// Signed distance from `p` to the surface, m: positive outside, negative inside.
    ///
    /// A polygon is any closed simple polygon (convex or not; its inside by the crossing-number
    /// rule); with fewer than three vertices it is a point or a segment (never "inside"), and an
    /// empty polygon is infinitely far away.
    pub fn signed_distance(&self, p: P2) -> f64 {
        match self {
            SimShape::Circle { center, radius } => p.sub(*center).norm() - radius.abs(),
            SimShape::Rectangle {
                center,
                half_size,
                angle,
            } => {
                let (s, c) = angle.sin_cos();
                let q = rotate(p.sub(*center), c, -s);
                let dx = q.x.abs() - half_size.x.abs();
                let dy = q.y.abs() - half_size.y.abs();
                let outside = P2::new(dx.max(0.0), dy.max(0.0)).norm();
                let inside = dx.max(dy).min(0.0);
                outside + inside
            }
            SimShape::Polygon { points } => {
                let n = points.len();
                if n == 0 {
                    return f64::INFINITY;
                }
                let d = (0..n)
                    .map(|i| segment_distance(p, points[i], points[(i + 1) % n]))
                    .fold(f64::INFINITY, f64::min);
                if polygon_contains(points, p) {
                    -d
                } else {
                    d
                }
            }
        }
    }

    /// Distance along the ray `origin + s·dir_unit` (s ≥ 0) to the first surface it meets, if
    /// that is within `max_range`. `dir_unit` is normalised here (a zero or non-finite
    /// direction hits nothing). An origin inside the shape (or on its surface) is blocked at
    /// once: `Some(0.0)` — a sensor buried in an obstacle sees nothing beyond it.
    pub fn ray_hit(&self, origin: P2, dir_unit: P2, max_range: f64) -> Option<f64> {
        let len = dir_unit.norm();
        if !(len > 1e-12 && len.is_finite()) || max_range.is_nan() || max_range < 0.0 {
            return None;
        }
        let d = dir_unit.scale(1.0 / len);
        let sd = self.signed_distance(origin);
        if sd.is_nan() {
            return None;
        }
        if sd <= 0.0 {
            return Some(0.0);
        }
        let t = match self {
            SimShape::Circle { center, radius } => {
                let oc = origin.sub(*center);
                let b = dot(d, oc);
                let disc = b * b - (dot(oc, oc) - radius * radius);
                if disc < 0.0 {
                    return None;
                }
                let t = -b - disc.sqrt();
                (t >= 0.0).then_some(t)
            }
            SimShape::Rectangle { .. } => self.corners().and_then(|c| polygon_ray(&c, origin, d)),
            SimShape::Polygon { points } => polygon_ray(points, origin, d),
        }?;
        (t.is_finite() && t <= max_range).then_some(t)
    }

    /// Unit outward normal of the distance field at `p` (central differences over 1 cm; the
    /// direction from the centre when the field is flat there).
    pub fn outward_normal(&self, p: P2) -> P2 {
        let h = 0.01;
        let gx = self.signed_distance(p.add(P2::new(h, 0.0)))
            - self.signed_distance(p.sub(P2::new(h, 0.0)));
        let gy = self.signed_distance(p.add(P2::new(0.0, h)))
            - self.signed_distance(p.sub(P2::new(0.0, h)));
        let g = P2::new(gx, gy);
        let n = g.norm();
        if n > 1e-9 && n.is_finite() {
            return g.scale(1.0 / n);
        }
        let r = p.sub(self.center());
        let rn = r.norm();
        if rn > 1e-9 && rn.is_finite() {
            r.scale(1.0 / rn)
        } else {
            P2::new(1.0, 0.0)
        }
    }

    /// The firmware's shape (`f32`): `Shape::circle`, `Shape::rectangle` or `Shape::polygon`,
    /// with the firmware's own checks (finite numbers, sizes 1 mm ..= 10 km, 3 ..= 8 vertices,
    /// strictly convex polygons). Negative sizes count by their magnitude, as everywhere here.
    pub fn to_vpf(&self) -> Result<Shape, ShapeError> {
        match self {
            SimShape::Circle { center, radius } => {
                Shape::circle(center.to_vpf(), radius.abs() as f32)
            }
            SimShape::Rectangle {
                center,
                half_size,
                angle,
            } => Shape::rectangle(
                center.to_vpf(),
                P2::new(half_size.x.abs(), half_size.y.abs()).to_vpf(),
                *angle as f32,
            ),
            SimShape::Polygon { points } => {
                let v: Vec<vpf::Vec2> = points.iter().map(|p| p.to_vpf()).collect();
                Shape::polygon(&v)
            }
        }
    }
}

impl SimObstacle {
    /// A static obstacle.
    pub fn fixed(shape: SimShape) -> Self {
        SimObstacle {
            shape,
            velocity: P2::default(),
        }
    }

    /// The velocity actually used: a non-finite velocity counts as zero (a static obstacle).
    pub fn effective_velocity(&self) -> P2 {
        let v = self.velocity;
        if v.x.is_finite() && v.y.is_finite() {
            v
        } else {
            P2::default()
        }
    }

    /// The shape at time `t` s: translated by `velocity · t` (a non-finite `t` counts as 0).
    pub fn shape_at(&self, t: f64) -> SimShape {
        self.shape
            .translated(self.effective_velocity().scale(finite_or_zero(t)))
    }

    /// The obstacle's centre at time `t` (see [`SimShape::center`]).
    pub fn position(&self, t: f64) -> P2 {
        self.shape
            .center()
            .add(self.effective_velocity().scale(finite_or_zero(t)))
    }

    /// Signed distance from `p` to the obstacle at time `t`, m.
    pub fn signed_distance(&self, t: f64, p: P2) -> f64 {
        // Moving the point instead of the shape: same answer, no allocation.
        let back = self.effective_velocity().scale(finite_or_zero(t));
        self.shape.signed_distance(p.sub(back))
    }

    /// First surface hit of a ray at time `t` (see [`SimShape::ray_hit`]).
    pub fn ray_hit(&self, t: f64, origin: P2, dir_unit: P2, max_range: f64) -> Option<f64> {
        let back = self.effective_velocity().scale(finite_or_zero(t));
        self.shape.ray_hit(origin.sub(back), dir_unit, max_range)
    }

    /// Outward normal of the obstacle at time `t` at `p` (see [`SimShape::outward_normal`]).
    pub fn outward_normal(&self, t: f64, p: P2) -> P2 {
        let back = self.effective_velocity().scale(finite_or_zero(t));
        self.shape.outward_normal(p.sub(back))
    }

    /// The firmware's shape at time `t` (see [`SimShape::to_vpf`]).
    pub fn to_vpf(&self, t: f64) -> Result<Shape, ShapeError> {
        self.shape_at(t).to_vpf()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(x: f64, y: f64, r: f64) -> SimShape {
        SimShape::Circle {
            center: P2::new(x, y),
            radius: r,
        }
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-9
    }

    #[test]
    fn circle_distance_and_ray() {
        let c = circle(10.0, 0.0, 2.0);
        assert!(close(c.signed_distance(P2::new(0.0, 0.0)), 8.0));
        assert!(close(c.signed_distance(P2::new(10.0, 1.0)), -1.0));
        let hit = c.ray_hit(P2::default(), P2::new(1.0, 0.0), 30.0);
        assert!(close(hit.unwrap(), 8.0));
        // Not normalised on input: still metres.
        assert!(close(
            c.ray_hit(P2::default(), P2::new(5.0, 0.0), 30.0).unwrap(),
            8.0
        ));
        assert_eq!(c.ray_hit(P2::default(), P2::new(-1.0, 0.0), 30.0), None);
        assert_eq!(c.ray_hit(P2::default(), P2::new(0.0, 1.0), 30.0), None);
        assert_eq!(c.ray_hit(P2::default(), P2::new(1.0, 0.0), 7.9), None);
        // Tangent-ish ray at y = 1.9 hits at x = 10 − √(4 − 3.61).
        let t = c
            .ray_hit(P2::new(0.0, 1.9), P2::new(1.0, 0.0), 30.0)
            .unwrap();
        assert!(close(t, 10.0 - (4.0f64 - 3.61).sqrt()));
        // Inside: blocked at once.
        assert_eq!(
            c.ray_hit(P2::new(10.0, 0.0), P2::new(1.0, 0.0), 30.0),
            Some(0.0)
        );
    }

    #[test]
    fn rectangle_distance_and_ray_follow_the_rotation() {
        // 4 × 2 box at (5, 5) rotated 90°: it spans x 4..6, y 3..7.
        let r = SimShape::Rectangle {
            center: P2::new(5.0, 5.0),
            half_size: P2::new(2.0, 1.0),
            angle: std::f64::consts::FRAC_PI_2,
        };
        assert!(close(r.signed_distance(P2::new(0.0, 5.0)), 4.0));
        assert!(close(r.signed_distance(P2::new(5.0, 0.0)), 3.0));
        assert!(close(r.signed_distance(P2::new(5.0, 5.0)), -1.0));
        assert!(close(r.signed_distance(P2::new(7.0, 8.0)), 2f64.sqrt()));
        let t = r
            .ray_hit(P2::new(5.0, -10.0), P2::new(0.0, 1.0), 100.0)
            .unwrap();
        assert!(close(t, 13.0));
        let t = r
            .ray_hit(P2::new(0.0, 6.5), P2::new(1.0, 0.0), 100.0)
            .unwrap();
        assert!(close(t, 4.0));
        assert_eq!(r.ray_hit(P2::new(0.0, 7.5), P2::new(1.0, 0.0), 100.0), None);
    }

    #[test]
    fn polygon_distance_ray_and_centroid() {
        // Right triangle (0,0) (4,0) (0,4), clockwise on purpose.
        let p = SimShape::Polygon {
            points: vec![P2::new(0.0, 0.0), P2::new(0.0, 4.0), P2::new(4.0, 0.0)],
        };
        assert!(close(p.signed_distance(P2::new(-3.0, 1.0)), 3.0));
        assert!(close(p.signed_distance(P2::new(1.0, 1.0)), -1.0));
        let far = p.signed_distance(P2::new(3.0, 3.0));
        assert!(close(far, 2.0f64.sqrt()));
        let c = p.center();
        assert!(close(c.x, 4.0 / 3.0) && close(c.y, 4.0 / 3.0));
        let t = p
            .ray_hit(P2::new(10.0, 1.0), P2::new(-1.0, 0.0), 50.0)
            .unwrap();
        assert!(close(t, 7.0));
        // Degenerate polygons never panic.
        let empty = SimShape::Polygon { points: vec![] };
        assert_eq!(empty.signed_distance(P2::default()), f64::INFINITY);
        assert_eq!(empty.ray_hit(P2::default(), P2::new(1.0, 0.0), 10.0), None);
        let seg = SimShape::Polygon {
            points: vec![P2::new(2.0, -1.0), P2::new(2.0, 1.0)],
        };
        assert!(close(
            seg.ray_hit(P2::default(), P2::new(1.0, 0.0), 10.0).unwrap(),
            2.0
        ));
        assert!(close(seg.signed_distance(P2::default()), 2.0));
    }

    #[test]
    fn moving_obstacle_translates_with_its_velocity() {
        let o = SimObstacle {
            shape: circle(0.0, 0.0, 1.0),
            velocity: P2::new(0.5, -0.25),
        };
        let p = o.position(4.0);
        assert!(close(p.x, 2.0) && close(p.y, -1.0));
        assert!(close(o.signed_distance(4.0, P2::new(2.0, 2.0)), 2.0));
        let t = o
            .ray_hit(4.0, P2::new(2.0, 5.0), P2::new(0.0, -1.0), 30.0)
            .unwrap();
        assert!(close(t, 5.0));
        assert_eq!(o.shape_at(4.0), circle(2.0, -1.0, 1.0));
        // Non-finite velocity or time: static.
        let bad = SimObstacle {
            shape: circle(1.0, 1.0, 1.0),
            velocity: P2::new(f64::NAN, 0.0),
        };
        assert_eq!(bad.position(10.0), P2::new(1.0, 1.0));
        assert_eq!(o.position(f64::INFINITY), P2::new(0.0, 0.0));
    }

    #[test]
    fn to_vpf_matches_the_firmware_distance() {
        let shapes = [
            circle(3.0, -2.0, 1.5),
            SimShape::Rectangle {
                center: P2::new(-4.0, 1.0),
                half_size: P2::new(2.0, 0.5),
                angle: 0.4,
            },
            SimShape::Polygon {
                points: vec![P2::new(0.0, 0.0), P2::new(4.0, 0.0), P2::new(0.0, 4.0)],
            },
        ];
        for s in &shapes {
            let v = s.to_vpf().unwrap();
            for &(x, y) in &[
                (0.0, 9.0),
                (3.0, -2.5),
                (-4.0, 1.2),
                (1.0, 1.0),
                (-7.0, -3.0),
            ] {
                let p = P2::new(x, y);
                let ours = s.signed_distance(p);
                let theirs = f64::from(v.signed_distance(p.to_vpf()));
                assert!(
                    (ours - theirs).abs() < 1e-3,
                    "{s:?} at {p:?}: {ours} vs {theirs}"
                );
            }
        }
        let moving = SimObstacle {
            shape: circle(0.0, 0.0, 1.0),
            velocity: P2::new(1.0, 0.0),
        };
        let c = moving.to_vpf(3.0).unwrap().center();
        assert_eq!((c.x, c.y), (3.0, 0.0));
        assert_eq!(
            circle(0.0, 0.0, 0.0).to_vpf(),
            Err(ShapeError::SizeOutOfRange)
        );
        assert_eq!(
            circle(f64::NAN, 0.0, 1.0).to_vpf(),
            Err(ShapeError::NonFinite)
        );
    }

    #[test]
    fn outward_normal_points_away() {
        let r = SimShape::Rectangle {
            center: P2::default(),
            half_size: P2::new(2.0, 1.0),
            angle: 0.0,
        };
        let n = r.outward_normal(P2::new(0.5, 3.0));
        assert!(close(n.x, 0.0) && (n.y - 1.0).abs() < 1e-6);
        let c = circle(0.0, 0.0, 1.0).outward_normal(P2::new(-3.0, 0.0));
        assert!((c.x + 1.0).abs() < 1e-6);
    }

    #[test]
    fn nan_shapes_are_never_hit() {
        let c = circle(f64::NAN, 0.0, 1.0);
        assert_eq!(c.ray_hit(P2::default(), P2::new(1.0, 0.0), 10.0), None);
        assert!(c.signed_distance(P2::default()).is_nan());
        let good = circle(5.0, 0.0, 1.0);
        assert_eq!(
            good.ray_hit(P2::default(), P2::new(f64::NAN, 0.0), 10.0),
            None
        );
        assert_eq!(good.ray_hit(P2::default(), P2::default(), 10.0), None);
        assert_eq!(
            good.ray_hit(P2::default(), P2::new(1.0, 0.0), f64::NAN),
            None
        );
    }
}
