//! The vehicle's navigation state and the limits every position and speed is checked against.

use super::StepError;
use crate::math::Vec2;

/// Largest coordinate accepted for the vehicle or a goal, m (100 km: beyond any AUV mission in a
/// local frame, and where `f32` still resolves 8 mm).
pub const MAX_COORD_M: f32 = 100_000.0;
/// Largest speed over ground accepted from navigation, m/s.
pub const MAX_NAV_SPEED: f32 = 20.0;

/// The vehicle's navigation state, as the planner needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NavState {
    /// Position in the local Earth-fixed frame, m.
    pub position: Vec2,
    /// Compass heading from +x, counter-clockwise, rad.
    pub heading: f32,
    /// Velocity over ground in the Earth-fixed frame, m/s.
    pub velocity: Vec2,
}

pub(crate) fn finite_coord(p: Vec2) -> bool {
    p.is_finite() && p.x.abs() <= MAX_COORD_M && p.y.abs() <= MAX_COORD_M
}

impl NavState {
    /// Checks that every number is finite and in range.
    pub fn validate(&self) -> Result<(), StepError> {
        let ok = finite_coord(self.position)
            && self.heading.is_finite()
            && self.velocity.is_finite()
            && self.velocity.norm2() <= MAX_NAV_SPEED * MAX_NAV_SPEED;
        if ok {
            Ok(())
        } else {
            Err(StepError::BadNav)
        }
    }
}
