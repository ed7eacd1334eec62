//! The value types the planner, the wire format and the runtime share: the navigation state,
//! missions (a goal, waypoints, a survey, a formation), the command a period produces, a sonar
//! scanline, and the error that refuses any of them. Plain data with the checks that say what
//! a valid value is; no planning here, so that [`crate::link`] carries them without needing
//! [`crate::planner`], and the planner takes them without needing the link. (The parameter set
//! is [`crate::params`], also below both.)

pub mod command;
pub mod formation;
pub mod mission;
pub mod nav;
pub mod scanline;
pub mod step_error;

pub use command::{Command, HoldReason, Mode, PidSetpoints};
pub use formation::{Formation, FormationError};
pub use mission::{
    Mission, MissionEnd, MissionError, MissionProgress, Survey, Waypoint, WaypointError, Waypoints,
    MAX_WAYPOINTS,
};
pub use nav::{NavState, MAX_COORD_M, MAX_NAV_SPEED};
pub use scanline::{
    ScanError, Scanline, MAX_BINS, MAX_RANGE_M, MAX_STEP_RAD, MIN_RANGE_M, MIN_STEP_RAD,
};
pub use step_error::StepError;
