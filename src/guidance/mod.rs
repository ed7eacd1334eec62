//! The hardware-independent guidance runtime: what the firmware runs, minus the board.
//!
//! Two halves, meant for two priorities:
//! - [`Periodic`] — the hard-real-time task, once per period: take the newest navigation, apply
//!   queued requests, drain queued sightings into the obstacle table, check the fail-safes, run
//!   one planner step, send the command, telemetry and replies. It never waits on anything.
//! - [`Background`] — the slow side, preemptible: decode received bytes, publish navigation,
//!   run sonar feature extraction on scanlines, and queue sightings and requests for the periodic
//!   task.
//!
//! They meet only through what the board provides (lock-free SPSC queues and RTIC shared
//! resources on the firmware; plain values on a host): the newest [`NavSample`], a
//! queue of [`Sighting`]s, a queue of [`Control`] requests and a ring of replies owed to
//! requests that never reach the periodic task (refused at the wire, or "busy"). The board also
//! carries the outgoing frames. Capacities, and what happens when each is full:
//!
//! | queue | capacity | when full |
//! | --- | --- | --- |
//! | received bytes (board) | [`RX_QUEUE`] | byte left in the UART, its interrupt off until the background has taken bytes: lossless on QEMU (the emulated UART holds the input back); on a real UART the next byte overruns, lost and counted (`rx_bytes_dropped`); the decoder resyncs on the next 0x00 |
//! | sightings | [`SIGHTING_QUEUE`] | sighting dropped, counted (`features_dropped`) |
//! | requests | [`CONTROL_QUEUE`] | request answered "busy" through the reply ring (nothing changed; the host sends it again), counted (`requests_busy`) |
//! | owed replies (6 B each) | [`REPLY_QUEUE`] | request dropped without an answer, counted (`requests_unanswered`) |
//!
//! Every request gets exactly one reply as long as at most [`REQUESTS_PER_PERIOD`] (a start-up
//! burst: parameters, mission and a full chart) arrive between two periods. Requests are big
//! (a `Params` or a polygon, 152 B a slot), so their queue stays short and a host paces a larger
//! burst on the replies: it sends again what was answered "busy" (docs/protocol.md §9). Replies
//! are 6 bytes, so their ring is sized for the whole burst.
//! | transmitted bytes (board) | [`TX_QUEUE`] | whole frame dropped, counted (`tx_frames_dropped`) |
//!
//! Time is passed in (milliseconds); nothing here reads a clock.

pub mod background;
pub mod drift;
pub mod failsafe;
pub mod faint;
pub mod guard;
pub mod mavlink;
pub mod one_thread;
pub mod periodic;
pub mod tracks;
pub mod upload;

pub use background::{Background, BackgroundCounters, BackgroundOutputs};
pub use drift::DriftConfig;
pub use failsafe::FailsafeConfig;
pub use guard::{GuardConfig, Verdict};
pub use one_thread::OneThreadRuntime;
pub use periodic::{Periodic, PeriodicInputs, RuntimeConfig};
pub use tracks::TrackConfig;

use crate::link::{ChartClearRepr, Header, MissionCountRepr, MissionItemRepr, SurveyRepr};
use crate::params::Params;
use crate::planner::{Mission, NavState};
use crate::sonar::Feature;
use crate::world::{Agent, Obstacle};

/// Capacity of the board's received-byte queue: about 45 ms of 115 200 baud, four times the
/// longest the background is busy elsewhere (a route replan and a period that preempts it).
pub const RX_QUEUE: usize = 512;
/// Capacity of the sighting queue (one sonar sweep rarely yields more).
pub const SIGHTING_QUEUE: usize = 16;
/// Capacity of the request queue (a `Control` is 152 bytes: RAM, not this number, is short).
pub const CONTROL_QUEUE: usize = 4;
/// Most requests answered between two periods: a start-up burst of parameters, a mission and a
/// full chart (every obstacle slot charted).
pub const REQUESTS_PER_PERIOD: usize = 2 + crate::world::MAX_OBSTACLES;
/// Capacity of the ring of replies owed without a request in the queue (refused at the wire, or
/// "busy"): with the queue, one answer for each of [`REQUESTS_PER_PERIOD`] requests.
pub const REPLY_QUEUE: usize = REQUESTS_PER_PERIOD - CONTROL_QUEUE;
/// Capacity of the board's transmit-byte queue: a period's command, telemetry, belief chunk and
/// replies. The most a period sends, the one answering a start-up burst of
/// [`REQUESTS_PER_PERIOD`] requests, is 691 bytes (`tests/requests.rs` checks it stays under
/// three quarters of this); 115 200 baud carries 1.15 KiB a 100 ms period.
pub const TX_QUEUE: usize = 1024;
/// Most sightings the periodic task takes per period (bounds its cost).
pub const SIGHTINGS_PER_PERIOD: usize = SIGHTING_QUEUE;

/// The newest navigation and when it arrived, firmware time.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NavSample {
    /// The navigation state.
    pub nav: NavState,
    /// Arrival, ms (firmware time).
    pub time_ms: u64,
}

/// Something seen in the water, on its way to the world tables.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Sighting {
    /// A feature the firmware extracted from sonar scanlines (no identity yet).
    Feature(Feature),
    /// An obstacle contact from the host's own feature extraction (host's id).
    Obstacle(Obstacle),
    /// Another vehicle (host's id).
    Agent(Agent),
}

/// A request for the periodic task, answered with a [`crate::link::ReplyRepr`] to its header.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Control {
    /// Set the mission.
    Mission(Header, Mission),
    /// Set the parameters.
    Params(Header, Params),
    /// Add or replace a charted obstacle.
    Chart(Header, Obstacle),
    /// Remove charted obstacles.
    ChartClear(Header, ChartClearRepr),
    /// Open a waypoint upload (`crate::guidance::upload`).
    MissionCount(Header, MissionCountRepr),
    /// One waypoint of the upload.
    MissionItem(Header, MissionItemRepr),
    /// Fly a lawnmower survey.
    Survey(Header, SurveyRepr),
}

impl Control {
    /// The header of the request, which its reply names.
    pub const fn header(&self) -> Header {
        match self {
            Control::Mission(h, _)
            | Control::Params(h, _)
            | Control::Chart(h, _)
            | Control::ChartClear(h, _)
            | Control::MissionCount(h, _)
            | Control::MissionItem(h, _)
            | Control::Survey(h, _) => *h,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A queued request is the size of its largest kind (a `Params`, a charted polygon): the
    /// waypoint messages go up one waypoint at a time so that the four slots do not grow.
    #[test]
    fn a_request_slot_stays_152_bytes() {
        assert_eq!(core::mem::size_of::<Control>(), 152);
        assert!(core::mem::size_of::<crate::link::SurveyRepr>() < 152);
        assert!(core::mem::size_of::<crate::link::MissionItemRepr>() <= 24);
    }
}
