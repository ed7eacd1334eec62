//! The scenario's set-up requests — parameters, then the mission — sent as docs/protocol.md §9
//! asks of a host: at most [`IN_FLIGHT`] unanswered at a time, again what came back "busy".
//!
//! A single-goal mission is two requests and goes out at once (as before waypoint missions). A
//! waypoint mission is a `MissionCount` and one `MissionItem` per waypoint, or one `Survey`.
//! A request still unanswered after [`STALE_PERIODS`] (its reply lost to a link fault) sends
//! the whole mission again from its `MissionCount`: an item resent alone could land in an
//! upload that a resent count had restarted.

use std::collections::VecDeque;

use vpf::link::{
    Message, MessageType, MissionCountRepr, MissionItemRepr, Problem, ReplyRepr, ReplyStatus,
    SurveyRepr,
};
use vpf::planner::Formation;
use vpf::{Mission, Params};

use crate::firmware::{Firmware, Tap};
use crate::scenario::VehicleMission;
use crate::types::P2;

/// Requests unanswered at a time: the firmware's request queue (`vpf::guidance::CONTROL_QUEUE`).
pub const IN_FLIGHT: usize = vpf::guidance::CONTROL_QUEUE;
/// Periods after which an unanswered request is taken as lost.
pub const STALE_PERIODS: u64 = 20;

/// A set-up request the firmware refused: the message, the field (its row in the message's
/// layout) and the problem, as its reply gave them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("the firmware refused the scenario's {to:?} message (field {field}: {problem:?})")]
pub struct Rejected {
    /// The refused message's type.
    pub to: MessageType,
    /// The refused field's row, or `vpf::link::FIELD_WHOLE_MESSAGE`.
    pub field: u8,
    /// Why.
    pub problem: Problem,
}

/// A vehicle's set-up requests on their way.
pub struct Uploader {
    /// Everything, in order: resent from the mission's start after a loss.
    all: Vec<Message<'static>>,
    pending: VecDeque<Message<'static>>,
    /// (sequence number, request, period sent).
    in_flight: Vec<(u16, Message<'static>, u64)>,
}

/// The requests that set a vehicle up: its parameters, then its mission.
pub fn requests(
    params: Params,
    goal: P2,
    mission: Option<&VehicleMission>,
    formation: Option<Formation>,
) -> Vec<Message<'static>> {
    let mut out = vec![Message::Params(params)];
    match mission {
        None => out.push(Message::Mission(Mission {
            goal: goal.to_vpf(),
            formation,
        })),
        Some(VehicleMission {
            survey: Some(s),
            waypoints,
        }) => out.push(Message::Survey(SurveyRepr {
            survey: *s,
            end: waypoints.end(),
            formation,
        })),
        Some(VehicleMission {
            survey: None,
            waypoints,
        }) => {
            out.push(Message::MissionCount(MissionCountRepr {
                count: waypoints.len() as u8,
                end: waypoints.end(),
                formation,
            }));
            out.extend(waypoints.as_slice().iter().enumerate().map(|(i, w)| {
                Message::MissionItem(MissionItemRepr {
                    index: i as u8,
                    waypoint: *w,
                })
            }));
        }
    }
    out
}

impl Uploader {
    /// Requests to send, in order.
    pub fn new(all: Vec<Message<'static>>) -> Self {
        Uploader {
            pending: all.iter().copied().collect(),
            all,
            in_flight: Vec::new(),
        }
    }

    /// Whether everything was accepted.
    pub fn done(&self) -> bool {
        self.pending.is_empty() && self.in_flight.is_empty()
    }

    /// Sends what fits in flight at `period`, through `tap` (the run's frame log without its
    /// faults, `crate::faults::FaultTap::clean`: a scenario's set-up is not what a fault run
    /// tests).
    pub fn send(
        &mut self,
        fw: &mut Firmware,
        period: u64,
        tap: &mut dyn Tap,
    ) -> std::io::Result<()> {
        if self
            .in_flight
            .iter()
            .any(|(_, _, at)| period.saturating_sub(*at) > STALE_PERIODS)
        {
            self.restart_mission();
        }
        while self.in_flight.len() < IN_FLIGHT {
            let Some(m) = self.pending.pop_front() else {
                break;
            };
            fw.send(&m, tap)?;
            self.in_flight.push((fw.last_seq(), m, period));
        }
        Ok(())
    }

    /// A reply: accepted (done with it), busy (send it again) or rejected (the message that
    /// names the request and the field).
    pub fn on_reply(&mut self, r: &ReplyRepr) -> Result<(), Rejected> {
        let Some(i) = self
            .in_flight
            .iter()
            .position(|(seq, m, _)| *seq == r.to_seq && m.message_type() == r.to_type)
        else {
            return Ok(());
        };
        let (_, m, _) = self.in_flight.remove(i);
        match r.status {
            ReplyStatus::Accepted => Ok(()),
            ReplyStatus::Busy => {
                self.pending.push_front(m);
                Ok(())
            }
            ReplyStatus::Rejected { field, problem } => Err(Rejected {
                to: r.to_type,
                field,
                problem,
            }),
        }
    }

    /// Everything from the mission's first request goes again (the parameters, if they were
    /// accepted, stay).
    fn restart_mission(&mut self) {
        let params_pending = self
            .pending
            .iter()
            .chain(self.in_flight.iter().map(|(_, m, _)| m))
            .any(|m| matches!(m, Message::Params(_)));
        self.in_flight.clear();
        self.pending = self
            .all
            .iter()
            .filter(|m| params_pending || !matches!(m, Message::Params(_)))
            .copied()
            .collect();
    }
}
