//! Why a step or a setting was refused: the planner's error, which the runtime turns into a
//! reply naming the field.

use super::{FormationError, MissionError};
use crate::params::ParamError;

/// Why a step or a setting was refused. The planner's state is unchanged after any of them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StepError {
    /// Navigation has a non-finite or out-of-range number.
    BadNav,
    /// The mission's goal is non-finite or out of range.
    BadGoal,
    /// The mission's formation request is invalid.
    BadFormation(FormationError),
    /// The waypoint mission is invalid.
    BadMission(MissionError),
    /// A parameter is invalid.
    BadParams(ParamError),
    /// The computation produced a non-finite number (never expected; the step is discarded).
    NonFinite,
}

impl core::fmt::Display for StepError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            StepError::BadNav => f.write_str("navigation state non-finite or out of range"),
            StepError::BadGoal => f.write_str("goal non-finite or out of range"),
            StepError::BadFormation(e) => write!(f, "formation refused: {e}"),
            StepError::BadMission(e) => write!(f, "mission refused: {e}"),
            StepError::BadParams(e) => write!(f, "{e}"),
            StepError::NonFinite => f.write_str("planner produced a non-finite number"),
        }
    }
}

impl core::error::Error for StepError {}
