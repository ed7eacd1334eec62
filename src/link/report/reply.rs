//! `Reply` (0x83): the firmware's answer to every request.

use super::field::reply;
use crate::link::codec::{refuse, Reader, Writer};
use crate::link::control::field::{chart_obstacle, mission};
use crate::link::control::param_index;
use crate::link::frame::{Direction, Header, MessageType};
use crate::link::payload::Payload;
use crate::link::{Error, Problem};
use crate::params::ParamProblem;
use crate::types::{FormationError, StepError};
use crate::world::ObjectError;

/// The `field` of a rejection that concerns the message as a whole (its length, a full
/// table) rather than one field.
pub const FIELD_WHOLE_MESSAGE: u8 = 0xFF;

/// The verdict of a [`ReplyRepr`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ReplyStatus {
    /// The message was applied.
    Accepted,
    /// The message was refused; nothing changed.
    Rejected {
        /// The refused field's row in the message's layout table (for `Params`, the parameter
        /// index of [`PARAM_NAMES`](super::PARAM_NAMES)), or [`FIELD_WHOLE_MESSAGE`].
        field: u8,
        /// Why.
        problem: Problem,
    },
    /// The firmware's request queue was full: the message was not looked at and nothing
    /// changed; send it again after the next period's replies.
    Busy,
}

/// `Reply` (0x83, the "ParamsReply"): the firmware's answer to a `Params`, `Mission`,
/// `ChartObstacle` or `ChartClear` message, matched by type and sequence number.
///
/// Layout (6 bytes): 0 `to_type` u8 (a host → firmware type) · 1 `to_seq` u16 · 2 `status` u8
/// (0 accepted, 1 rejected, 2 busy) · 3 `field` u8 · 4 `problem` u8 ([`Problem`] code); `field`
/// and `problem` are 0 when accepted or busy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ReplyRepr {
    /// Type of the message replied to.
    pub to_type: MessageType,
    /// Sequence number of the message replied to.
    pub to_seq: u16,
    /// Accepted, or why not.
    pub status: ReplyStatus,
}

impl ReplyRepr {
    /// The message with header `to` was applied.
    pub const fn accepted(to: Header) -> Self {
        ReplyRepr {
            to_type: to.msg_type,
            to_seq: to.seq,
            status: ReplyStatus::Accepted,
        }
    }

    /// The message with header `to` was refused for `problem` in `field`.
    pub const fn rejected(to: Header, field: u8, problem: Problem) -> Self {
        ReplyRepr {
            to_type: to.msg_type,
            to_seq: to.seq,
            status: ReplyStatus::Rejected { field, problem },
        }
    }

    /// The message with header `to` found the request queue full: not applied, send it again.
    pub const fn busy(to: Header) -> Self {
        ReplyRepr {
            to_type: to.msg_type,
            to_seq: to.seq,
            status: ReplyStatus::Busy,
        }
    }

    /// The message with header `to` failed to parse with `e` (from the decoder's
    /// [`Outcome::Error`](super::Outcome::Error)).
    pub const fn from_error(to: Header, e: Error) -> Self {
        match e {
            Error::Field { index, problem } => ReplyRepr::rejected(to, index, problem),
            _ => ReplyRepr::rejected(to, FIELD_WHOLE_MESSAGE, Problem::Invalid),
        }
    }

    /// The planner refused the `Params` or `Mission` message with header `to`
    /// ([`Planner::set_params`](crate::planner::Planner::set_params),
    /// [`Planner::set_mission`](crate::planner::Planner::set_mission)): names the parameter or
    /// mission field.
    pub fn from_step_error(to: Header, e: StepError) -> Self {
        let (field, problem) = match e {
            StepError::BadParams(pe) => (
                param_index(pe.name).unwrap_or(FIELD_WHOLE_MESSAGE),
                match pe.problem {
                    ParamProblem::NonFinite => Problem::NonFinite,
                    ParamProblem::OutOfRange => Problem::OutOfRange,
                },
            ),
            // The wire already refused non-finite goals: only the range is left.
            StepError::BadGoal => (mission::GOAL_X.row, Problem::OutOfRange),
            StepError::BadFormation(FormationError::Descriptor) => {
                (mission::Q.row, Problem::UnknownCode)
            }
            StepError::BadFormation(FormationError::NonFinite) => {
                (mission::FLAGS.row, Problem::NonFinite)
            }
            StepError::BadFormation(FormationError::OutOfRange) => {
                (mission::FLAGS.row, Problem::OutOfRange)
            }
            // Waypoint missions are checked at the wire, row by row (`super::mission`).
            StepError::BadNav | StepError::BadMission(_) => (FIELD_WHOLE_MESSAGE, Problem::Invalid),
            StepError::NonFinite => (FIELD_WHOLE_MESSAGE, Problem::NonFinite),
        };
        ReplyRepr::rejected(to, field, problem)
    }

    /// The world refused the `ChartObstacle` with header `to`
    /// ([`ChartObstacleRepr::to_obstacle`](super::ChartObstacleRepr::to_obstacle)): its
    /// `a_plus` (row 1).
    pub const fn from_object_error(to: Header, e: ObjectError) -> Self {
        let problem = match e {
            ObjectError::NonFinite => Problem::NonFinite,
            ObjectError::OutOfRange => Problem::OutOfRange,
        };
        ReplyRepr::rejected(to, chart_obstacle::A_PLUS.row, problem)
    }

    /// The obstacle table was full (charted obstacles are never evicted).
    pub const fn table_full(to: Header) -> Self {
        ReplyRepr::rejected(to, FIELD_WHOLE_MESSAGE, Problem::TableFull)
    }

    fn check(&self) -> Result<(), Error> {
        if self.to_type.direction() != Direction::ToFirmware {
            return refuse(reply::TO_TYPE, Problem::Invalid);
        }
        Ok(())
    }
}

impl<'a> Payload<'a> for ReplyRepr {
    const TYPE: MessageType = MessageType::Reply;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let to_type = r.u8()?;
        let to_seq = r.u16()?;
        let status = r.u8()?;
        let field = r.u8()?;
        let problem = r.u8()?;
        r.finish()?;
        let to_type =
            MessageType::from_code(to_type).ok_or(reply::TO_TYPE.error(Problem::UnknownCode))?;
        let status = match status {
            0 if field == 0 && problem == 0 => ReplyStatus::Accepted,
            0 => return refuse(reply::FIELD, Problem::Invalid),
            1 => ReplyStatus::Rejected {
                field,
                problem: Problem::from_code(problem)
                    .ok_or(reply::PROBLEM.error(Problem::UnknownCode))?,
            },
            2 if field == 0 && problem == 0 => ReplyStatus::Busy,
            2 => return refuse(reply::FIELD, Problem::Invalid),
            _ => return refuse(reply::STATUS, Problem::UnknownCode),
        };
        let reply = ReplyRepr {
            to_type,
            to_seq,
            status,
        };
        reply.check()?;
        Ok(reply)
    }

    fn payload_len(&self) -> usize {
        6
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        self.check()?;
        let (status, field, problem) = match self.status {
            ReplyStatus::Accepted => (0, 0, 0),
            ReplyStatus::Rejected { field, problem } => (1, field, problem.code()),
            ReplyStatus::Busy => (2, 0, 0),
        };
        let mut w = Writer::new(out);
        w.u8(self.to_type.code())?;
        w.u16(self.to_seq)?;
        w.u8(status)?;
        w.u8(field)?;
        w.u8(problem)?;
        Ok(w.len())
    }
}
