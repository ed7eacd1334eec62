//! The wire codes of the planner's [`Mode`] and [`HoldReason`] (docs/protocol.md §7), which
//! `Command` and `Telemetry` both carry.

use super::codec::refuse;
use super::layout::Field;
use super::{Error, Problem};
use crate::types::{HoldReason, Mode};

/// The wire codes of a [`Mode`]: (mode, hold reason). Mode 0 hold, 1 transit, 2 escape,
/// 3 arrived, 4 guarded, 5 loiter; hold reason 0 none (any mode but hold), 1 no mission, 2 stale navigation,
/// 3 inside an obstacle, 4 collision imminent.
pub const fn mode_codes(mode: Mode) -> (u8, u8) {
    match mode {
        Mode::Hold(r) => (
            0,
            match r {
                HoldReason::NoMission => 1,
                HoldReason::StaleNav => 2,
                HoldReason::InsideObstacle => 3,
                HoldReason::CollisionImminent => 4,
                HoldReason::FrozenNav => 5,
                HoldReason::SonarBlind => 6,
            },
        ),
        Mode::Transit => (1, 0),
        Mode::Escape => (2, 0),
        Mode::Arrived => (3, 0),
        Mode::Guarded => (4, 0),
        Mode::Loiter => (5, 0),
    }
}

/// The [`Mode`] of wire codes (mode, reason), read from fields `mode_row` and `reason_row`.
pub(crate) fn mode_from_codes(
    mode: u8,
    reason: u8,
    mode_row: Field,
    reason_row: Field,
) -> Result<Mode, Error> {
    let m = match mode {
        0 => Mode::Hold(match reason {
            1 => HoldReason::NoMission,
            2 => HoldReason::StaleNav,
            3 => HoldReason::InsideObstacle,
            4 => HoldReason::CollisionImminent,
            5 => HoldReason::FrozenNav,
            6 => HoldReason::SonarBlind,
            _ => return refuse(reason_row, Problem::UnknownCode),
        }),
        1 => Mode::Transit,
        2 => Mode::Escape,
        3 => Mode::Arrived,
        4 => Mode::Guarded,
        5 => Mode::Loiter,
        _ => return refuse(mode_row, Problem::UnknownCode),
    };
    if mode != 0 && reason != 0 {
        return refuse(reason_row, Problem::Invalid);
    }
    Ok(m)
}
