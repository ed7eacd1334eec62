//! Potential distribution functions (PDFs): the scalar fields each feature of the theatre of
//! operations contributes to the virtual potential E (seed 000 eq. 1).
//!
//! - [`stator`]: the repulsion of an obstacle as a function of its distance r (000 eq. 9, 12);
//! - [`goal`]: the Gaussian attraction of a goal-point (000 eq. 13, 001 eq. 12);
//! - [`rotor`]: the tangential rotor term that is zero at the vehicle (001 eq. 2–3);
//! - [`shape`]: the distance r(p) for circles, rectangles, ellipses and convex polygons;
//! - `edges`: a polygon's edges laid out for the points of one sample circle.

pub(crate) mod edges;
pub mod goal;
pub mod rotor;
pub mod shape;
pub mod stator;

pub use goal::GoalPdf;
pub use rotor::{RotorSense, RotorTerm};
pub use shape::{Shape, ShapeError, MAX_POLYGON_VERTICES};
pub use stator::Stator;
