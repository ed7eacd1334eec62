//! The waypoint upload: `MissionCount` opens it, `MissionItem`s fill it, and the item that
//! completes it hands the whole list to the planner (`docs/protocol.md`, `crate::link::mission`).
//!
//! The staging list is the periodic task's, apart from the mission in force, which keeps flying
//! until the new one is complete and accepted (two lists of [`MAX_WAYPOINTS`]: the price of
//! never flying half a mission). Items may come in any order and again (a host resends what
//! came back "busy"); an item outside the open upload is refused and changes nothing.

use crate::link::mission::field::mission_item;
use crate::link::{Header, MissionCountRepr, MissionItemRepr, Problem, ReplyRepr};
use crate::math::Vec2;
use crate::planner::{Formation, MissionEnd, Planner, Waypoint, Waypoints, MAX_WAYPOINTS};

/// Placeholder for the slots not yet filled (never flown: the received mask says which are).
const EMPTY: Waypoint = Waypoint::with_parameter_radius(Vec2::ZERO);

/// An upload in progress.
#[derive(Clone, Debug)]
pub struct Upload {
    items: [Waypoint; MAX_WAYPOINTS],
    /// Waypoints announced by the `MissionCount` (0: no upload open).
    count: u8,
    /// Bit i: item i has come.
    received: u16,
    end: MissionEnd,
    formation: Option<Formation>,
}

impl Default for Upload {
    fn default() -> Self {
        Upload {
            items: [EMPTY; MAX_WAYPOINTS],
            count: 0,
            received: 0,
            end: MissionEnd::Hold,
            formation: None,
        }
    }
}

impl Upload {
    /// Whether an upload is open.
    pub fn is_open(&self) -> bool {
        self.count > 0
    }

    /// Opens an upload (dropping any unfinished one); the wire checked `c`.
    pub fn open(&mut self, h: Header, c: &MissionCountRepr) -> ReplyRepr {
        self.count = c.count;
        self.received = 0;
        self.end = c.end;
        self.formation = c.formation;
        ReplyRepr::accepted(h)
    }

    /// Stores item `m`; once every item has come, the mission goes to `planner` and the upload
    /// closes. Refused (field 0, the index) when no upload is open or the index is beyond its
    /// count.
    pub fn item(&mut self, h: Header, m: &MissionItemRepr, planner: &mut Planner) -> ReplyRepr {
        // Refusals here are counted with the planner's refused missions (`bad_mission`).
        let mut refuse = |problem| {
            let c = &mut planner.counters.bad_mission;
            *c = c.saturating_add(1);
            ReplyRepr::rejected(h, mission_item::INDEX.row, problem)
        };
        if !self.is_open() {
            return refuse(Problem::Invalid);
        }
        let i = usize::from(m.index);
        let Some(slot) = self.items.get_mut(i).filter(|_| m.index < self.count) else {
            return refuse(Problem::OutOfRange);
        };
        *slot = m.waypoint;
        self.received |= 1 << i;
        let all = u16::MAX >> (16 - u32::from(self.count));
        if self.received & all != all {
            return ReplyRepr::accepted(h);
        }
        let items = self.items.get(..usize::from(self.count)).unwrap_or(&[]);
        let result = Waypoints::new(items, self.end)
            .map_err(crate::planner::StepError::BadMission)
            .and_then(|w| planner.set_waypoints(&w, self.formation));
        self.count = 0;
        self.received = 0;
        match result {
            Ok(()) => ReplyRepr::accepted(h),
            Err(e) => ReplyRepr::from_step_error(h, e),
        }
    }
}
