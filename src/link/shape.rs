//! The wire form of an obstacle [`Shape`], shared by `Contacts` and `ChartObstacle`.
//!
//! A shape is a kind byte and a kind-dependent body (world frame, metres and radians):
//!
//! | kind | shape     | body                                              | bytes  |
//! |------|-----------|---------------------------------------------------|--------|
//! | 0    | circle    | cx f32, cy f32, radius f32                        | 1 + 12 |
//! | 1    | rectangle | cx, cy, half_x, half_y (own axes), angle f32      | 1 + 20 |
//! | 2    | ellipse   | cx, cy, semi_x, semi_y (own axes), angle f32      | 1 + 20 |
//! | 3    | polygon   | n u8 (3..=8), then n × (x f32, y f32), convex     | 2 + 8n |
//!
//! Parsing builds the shape with the library's checked constructors, so sizes
//! (1 mm ..= 10 km), convexity and finiteness are the library's rules; on top, every coordinate
//! must be within ±[`MAX_COORD_M`] and every angle within ±2π. A polygon may come in either
//! winding; it is stored, and re-emitted, counter-clockwise.

use super::codec::{angle, point, refuse, Reader, Writer};
use super::layout::Field;
use super::{Error, Problem};
use crate::field::shape::MAX_POLYGON_VERTICES;
use crate::field::{Shape, ShapeError};
use crate::math::Vec2;
use crate::types::MAX_COORD_M;

/// Kind code of a circle.
pub const KIND_CIRCLE: u8 = 0;
/// Kind code of a rectangle.
pub const KIND_RECTANGLE: u8 = 1;
/// Kind code of an ellipse.
pub const KIND_ELLIPSE: u8 = 2;
/// Kind code of a convex polygon.
pub const KIND_POLYGON: u8 = 3;
/// Longest wire form of a shape: a polygon of [`MAX_POLYGON_VERTICES`] vertices.
pub const MAX_SHAPE_LEN: usize = 2 + 8 * MAX_POLYGON_VERTICES;

/// The length of `shape`'s wire form.
pub fn shape_len(shape: &Shape) -> usize {
    match shape {
        Shape::Circle(_) => 1 + 12,
        Shape::Rectangle(_) | Shape::Ellipse(_) => 1 + 20,
        Shape::Polygon(p) => 2 + 8 * p.vertices().len(),
    }
}

fn problem(e: ShapeError) -> Problem {
    match e {
        ShapeError::NonFinite => Problem::NonFinite,
        ShapeError::SizeOutOfRange | ShapeError::VertexCount => Problem::OutOfRange,
        ShapeError::NotConvex => Problem::Invalid,
    }
}

/// The checks the constructors do not make: coordinates within ±[`MAX_COORD_M`], angles
/// within ±2π. Errors name field `index`.
pub(crate) fn check_shape(index: Field, shape: &Shape) -> Result<(), Error> {
    match shape {
        Shape::Circle(c) => point(index, c.center(), MAX_COORD_M),
        Shape::Rectangle(r) => {
            point(index, r.center(), MAX_COORD_M)?;
            angle(index, r.angle())
        }
        Shape::Ellipse(e) => {
            point(index, e.frame().center(), MAX_COORD_M)?;
            angle(index, e.frame().angle())
        }
        Shape::Polygon(p) => p
            .vertices()
            .iter()
            .try_for_each(|v| point(index, *v, MAX_COORD_M)),
    }
}

/// Reads a shape; errors name field `index`.
pub(crate) fn read_shape(r: &mut Reader<'_>, index: Field) -> Result<Shape, Error> {
    let kind = r.u8()?;
    let built = match kind {
        KIND_CIRCLE => {
            let c = r.vec2()?;
            let radius = r.f32()?;
            Shape::circle(c, radius)
        }
        KIND_RECTANGLE | KIND_ELLIPSE => {
            let c = r.vec2()?;
            let half = r.vec2()?;
            let a = r.f32()?;
            if kind == KIND_RECTANGLE {
                Shape::rectangle(c, half, a)
            } else {
                Shape::ellipse(c, half, a)
            }
        }
        KIND_POLYGON => {
            let n = usize::from(r.u8()?);
            if !(3..=MAX_POLYGON_VERTICES).contains(&n) {
                return refuse(index, Problem::OutOfRange);
            }
            let mut pts = [Vec2::ZERO; MAX_POLYGON_VERTICES];
            for p in pts.iter_mut().take(n) {
                *p = r.vec2()?;
            }
            Shape::polygon(pts.get(..n).unwrap_or(&[]))
        }
        _ => return refuse(index, Problem::UnknownCode),
    };
    let shape = built.map_err(|e| index.error(problem(e)))?;
    check_shape(index, &shape)?;
    Ok(shape)
}

/// Writes a shape (after [`check_shape`]); errors name field `index`.
pub(crate) fn write_shape(w: &mut Writer<'_>, index: Field, shape: &Shape) -> Result<(), Error> {
    check_shape(index, shape)?;
    match shape {
        Shape::Circle(c) => {
            w.u8(KIND_CIRCLE)?;
            w.vec2(c.center())?;
            w.f32(c.radius())
        }
        Shape::Rectangle(r) => {
            w.u8(KIND_RECTANGLE)?;
            w.vec2(r.center())?;
            w.vec2(r.half_size())?;
            w.f32(r.angle())
        }
        Shape::Ellipse(e) => {
            let r = e.frame();
            w.u8(KIND_ELLIPSE)?;
            w.vec2(r.center())?;
            w.vec2(r.half_size())?;
            w.f32(r.angle())
        }
        Shape::Polygon(p) => {
            let v = p.vertices();
            w.u8(KIND_POLYGON)?;
            // At most MAX_POLYGON_VERTICES (8): the cast cannot truncate.
            w.u8(v.len() as u8)?;
            v.iter().try_for_each(|p| w.vec2(*p))
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    extern crate std;
    use super::*;
    use proptest::prelude::*;

    /// A shape in row 9 of some message.
    const AT: Field = Field::new(9, 0, "shape", "shape");
    const AT0: Field = Field::new(0, 0, "shape", "shape");

    fn roundtrip(bytes: &[u8]) -> Result<(Shape, std::vec::Vec<u8>), Error> {
        let mut r = Reader::new(bytes);
        let s = read_shape(&mut r, AT)?;
        r.finish()?;
        let mut out = [0u8; MAX_SHAPE_LEN];
        let mut w = Writer::new(&mut out);
        write_shape(&mut w, AT, &s)?;
        let n = w.len();
        assert_eq!(n, shape_len(&s));
        Ok((s, out[..n].to_vec()))
    }

    #[test]
    fn circle_bytes() {
        // kind 0, centre (1, -2), radius 0.5
        let b = [
            0x00, 0x00, 0x00, 0x80, 0x3f, 0x00, 0x00, 0x00, 0xc0, 0x00, 0x00, 0x00, 0x3f,
        ];
        let (s, out) = roundtrip(&b).unwrap();
        assert_eq!(s, Shape::circle(Vec2::new(1.0, -2.0), 0.5).unwrap());
        assert_eq!(out, b);
    }

    #[test]
    fn rectangle_and_ellipse_bytes() {
        // kind 1, centre (0, 10), half (2, 0.25), angle 1.0
        let mut b = std::vec![0x01];
        b.extend([0x00, 0x00, 0x00, 0x00]);
        b.extend([0x00, 0x00, 0x20, 0x41]);
        b.extend([0x00, 0x00, 0x00, 0x40]);
        b.extend([0x00, 0x00, 0x80, 0x3e]);
        b.extend([0x00, 0x00, 0x80, 0x3f]);
        let (s, out) = roundtrip(&b).unwrap();
        let want = Shape::rectangle(Vec2::new(0.0, 10.0), Vec2::new(2.0, 0.25), 1.0).unwrap();
        assert_eq!(s, want);
        assert_eq!(out, b);
        b[0] = 0x02;
        let (s, _) = roundtrip(&b).unwrap();
        let want = Shape::ellipse(Vec2::new(0.0, 10.0), Vec2::new(2.0, 0.25), 1.0).unwrap();
        assert_eq!(s, want);
    }

    #[test]
    fn polygon_bytes_and_winding() {
        // Triangle (0,0) (0,1) (1,0): clockwise; stored and re-emitted counter-clockwise.
        let cw = [
            0x03, 0x03, //
            0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, //
            0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80, 0x3f, //
            0x00, 0x00, 0x80, 0x3f, 0x00, 0x00, 0x00, 0x00,
        ];
        let ccw = [
            0x03, 0x03, //
            0x00, 0x00, 0x80, 0x3f, 0x00, 0x00, 0x00, 0x00, //
            0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80, 0x3f, //
            0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
        ];
        let (s, out) = roundtrip(&cw).unwrap();
        assert_eq!(out, ccw);
        assert_eq!(roundtrip(&ccw).unwrap().0, s);
    }

    #[test]
    fn bad_shapes_name_the_field_and_problem() {
        let f = |p| Err(Error::field(9, p));
        // Unknown kind.
        assert_eq!(roundtrip(&[7]).map(|x| x.0), f(Problem::UnknownCode));
        // Negative radius.
        let mut b = [0u8; 13];
        b[9..13].copy_from_slice(&(-1.0f32).to_le_bytes());
        assert_eq!(roundtrip(&b).map(|x| x.0), f(Problem::OutOfRange));
        // NaN centre.
        b[1..5].copy_from_slice(&f32::NAN.to_le_bytes());
        assert_eq!(roundtrip(&b).map(|x| x.0), f(Problem::NonFinite));
        // Centre beyond 100 km.
        let mut b = [0u8; 13];
        b[1..5].copy_from_slice(&2.0e5f32.to_le_bytes());
        b[9..13].copy_from_slice(&1.0f32.to_le_bytes());
        assert_eq!(roundtrip(&b).map(|x| x.0), f(Problem::OutOfRange));
        // Polygon with 9 vertices, and a collinear one.
        assert_eq!(roundtrip(&[3, 9]).map(|x| x.0), f(Problem::OutOfRange));
        let mut b = std::vec![3, 3];
        for (x, y) in [(0.0f32, 0.0f32), (1.0, 1.0), (2.0, 2.0)] {
            b.extend(x.to_le_bytes());
            b.extend(y.to_le_bytes());
        }
        assert_eq!(roundtrip(&b).map(|x| x.0), f(Problem::Invalid));
        // Rectangle angle of 10 rad (degrees sent as radians, say).
        let mut b = std::vec![1];
        for v in [0.0f32, 0.0, 1.0, 1.0, 10.0] {
            b.extend(v.to_le_bytes());
        }
        assert_eq!(roundtrip(&b).map(|x| x.0), f(Problem::OutOfRange));
        // Truncated.
        assert_eq!(roundtrip(&[0, 0, 0]).map(|x| x.0), Err(Error::Length));
    }

    /// Valid shapes of every kind, for the property tests of the messages that carry them.
    pub(crate) fn arb_shape() -> impl Strategy<Value = Shape> {
        let c = (-1e4f32..1e4, -1e4f32..1e4);
        prop_oneof![
            (c.clone(), 0.01f32..100.0)
                .prop_map(|((x, y), r)| Shape::circle(Vec2::new(x, y), r).unwrap()),
            (
                c.clone(),
                0.01f32..100.0,
                0.01f32..100.0,
                -6.0f32..6.0,
                any::<bool>()
            )
                .prop_map(|((x, y), a, b, t, ell)| {
                    let (c, h) = (Vec2::new(x, y), Vec2::new(a, b));
                    if ell {
                        Shape::ellipse(c, h, t).unwrap()
                    } else {
                        Shape::rectangle(c, h, t).unwrap()
                    }
                }),
            (c, 1.0f32..100.0, 3usize..=8, -3.0f32..3.0, any::<bool>()).prop_filter_map(
                "convex",
                |((x, y), r, n, rot, cw)| {
                    let mut pts: std::vec::Vec<Vec2> = (0..n)
                        .map(|k| {
                            let a = rot + k as f32 * crate::math::TAU / n as f32;
                            Vec2::new(x + r * libm::cosf(a), y + r * libm::sinf(a))
                        })
                        .collect();
                    if cw {
                        pts.reverse();
                    }
                    Shape::polygon(&pts).ok()
                }
            ),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

        #[test]
        fn shapes_round_trip(s in arb_shape()) {
            let mut out = [0u8; MAX_SHAPE_LEN];
            let mut w = Writer::new(&mut out);
            write_shape(&mut w, AT0, &s).unwrap();
            let n = w.len();
            prop_assert_eq!(n, shape_len(&s));
            let mut r = Reader::new(&out[..n]);
            prop_assert_eq!(read_shape(&mut r, AT0), Ok(s));
            prop_assert_eq!(r.finish(), Ok(()));
        }

        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..80)) {
            let mut r = Reader::new(&bytes);
            let _ = read_shape(&mut r, AT0);
        }
    }
}
