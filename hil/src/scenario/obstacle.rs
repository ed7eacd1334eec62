//! An `[[obstacle]]` built into its true shape and the firmware's: a circle, a rectangle or a
//! convex polygon, each checked by the firmware's own constructors, a polygon's faults named at
//! the vertex.

use std::ops::Range;

use toml::Spanned;
use vpf::field::shape::MIN_EXTENT_M;
use vpf::field::{Shape, MAX_POLYGON_VERTICES};

use super::file::{shape_keys, ObstacleFile};
use super::values::{Items, Num, Pair};
use super::{unknown_key, At, ScenarioError};
use crate::types::{SimObstacle, SimShape, P2};

/// Largest obstacle speed, m/s (the firmware's `MAX_OBJECT_SPEED`).
pub(super) const MAX_OBSTACLE_SPEED: f64 = vpf::world::MAX_OBJECT_SPEED as f64;

pub(super) fn obstacle(
    at: &At<'_>,
    f: &ObstacleFile,
) -> Result<(SimObstacle, Shape), ScenarioError> {
    let kind = at.req("shape", &f.shape)?;
    let shape_name = kind.get_ref().as_str();
    let Some(keys) = shape_keys(shape_name) else {
        return Err(at.fail(
            "shape",
            &kind.span(),
            format!(
                "unknown shape \"{shape_name}\" (expected \"circle\", \"rectangle\" or \"polygon\")"
            ),
        ));
    };
    // The keys of another shape are unknown to this one: the first in the file is reported.
    let mut given: [(&str, Option<Range<usize>>); 6] = [
        ("center", f.center.as_ref().map(Spanned::span)),
        ("radius", f.radius.as_ref().map(Spanned::span)),
        ("half_size", f.half_size.as_ref().map(Spanned::span)),
        ("angle_deg", f.angle_deg.as_ref().map(Spanned::span)),
        ("points", f.points.as_ref().map(Spanned::span)),
        ("velocity", f.velocity.as_ref().map(Spanned::span)),
    ];
    given.sort_by_key(|(_, s)| s.as_ref().map_or(usize::MAX, |s| s.start));
    for (key, s) in given {
        if let Some(s) = s.filter(|_| !keys.contains(&key)) {
            let what = format!("a {shape_name} obstacle");
            return Err(at.fail(key, &s, unknown_key(key, keys, &what)));
        }
    }
    let shape = match shape_name {
        "circle" => SimShape::Circle {
            center: at.position("center", at.req("center", &f.center)?)?,
            radius: {
                let r = at.req("radius", &f.radius)?;
                at.size("radius", r)?
            },
        },
        "rectangle" => {
            let center = at.position("center", at.req("center", &f.center)?)?;
            let half = at.req("half_size", &f.half_size)?;
            let half_size = half.get_ref().0;
            for (i, v) in [half_size.x, half_size.y].into_iter().enumerate() {
                at.size(
                    &format!("half_size[{i}]"),
                    &Spanned::new(half.span(), Num(v)),
                )?;
            }
            SimShape::Rectangle {
                center,
                half_size,
                angle: at.degrees("angle_deg", &f.angle_deg)?,
            }
        }
        _ => SimShape::Polygon {
            points: polygon(at, at.req("points", &f.points)?)?,
        },
    };
    let velocity = at.velocity("velocity", &f.velocity, MAX_OBSTACLE_SPEED)?;
    // The firmware's own constructors are the last word on what geometry it accepts.
    let vpf_shape = shape
        .to_vpf()
        .map_err(|e| at.refuse(format!("refused by the firmware's geometry: {e}")))?;
    Ok((SimObstacle { shape, velocity }, vpf_shape))
}

/// A convex polygon's vertices, refusing degenerate and concave ones with the vertex at fault.
fn polygon(at: &At<'_>, v: &Spanned<Items<Pair>>) -> Result<Vec<P2>, ScenarioError> {
    let items = &v.get_ref().0;
    let n = items.len();
    let whole = |m: &str| at.fail("points", &v.span(), m);
    if !(3..=MAX_POLYGON_VERTICES).contains(&n) {
        return Err(whole(&format!(
            "a polygon needs 3 ..= {MAX_POLYGON_VERTICES} vertices, got {n}"
        )));
    }
    let key = |i: usize| format!("points[{}]", i % n);
    let mut pts = Vec::with_capacity(n);
    for (i, p) in items.iter().enumerate() {
        pts.push(at.position(&key(i), p)?);
    }
    let vertex = |i: usize, m: String| at.fail(&key(i), &items[i % n].span(), m);
    let pt = |i: usize| pts[i % n];
    for i in 0..n {
        if pt(i + 1).sub(pt(i)).norm() < f64::from(MIN_EXTENT_M) {
            return Err(vertex(
                i + 1,
                format!(
                    "degenerate polygon: vertex {} repeats vertex {i}",
                    (i + 1) % n
                ),
            ));
        }
    }
    // Turn at each vertex: the cross product of the edges into and out of it.
    let turn = |i: usize| {
        let (p, c, q) = (pt(i + n - 1), pt(i), pt(i + 1));
        let (e1, e2) = (c.sub(p), q.sub(c));
        let cross = e1.x * e2.y - e1.y * e2.x;
        let dot = e1.x * e2.x + e1.y * e2.y;
        (cross, dot, e1.norm() * e2.norm())
    };
    let area2: f64 = (0..n)
        .map(|i| {
            let (a, b) = (pt(i), pt(i + 1));
            a.x * b.y - a.y * b.x
        })
        .sum();
    let mut total_turn = 0.0;
    for i in 0..n {
        let (cross, dot, scale) = turn(i);
        if cross.abs() <= 1e-6 * scale {
            return Err(vertex(
                i,
                format!(
                    "degenerate polygon: vertex {i} is collinear with its neighbours; remove it"
                ),
            ));
        }
        if cross * area2 < 0.0 {
            return Err(vertex(
                i,
                format!(
                    "concave polygon (reflex vertex {i}): obstacles must be convex, split it \
                     into convex pieces"
                ),
            ));
        }
        total_turn += cross.atan2(dot);
    }
    // All turns one way but winding more than once round: a star, which crosses itself.
    if (total_turn.abs() - std::f64::consts::TAU).abs() > 1e-6 {
        return Err(whole(
            "self-intersecting polygon: obstacles must be convex, split it into convex pieces",
        ));
    }
    Ok(pts)
}
