//! MAVLink 2 on a UART of its own (`vpf::guidance::mavlink`): the autopilot and the ground
//! station. UART2 on the emulated board, USART6 on the NUCLEO.
//!
//! - **Bytes in** (the background): [`MavPort`] feeds them to the bridge's inbound half, which
//!   publishes navigation as a `Nav` message would and queues mission-upload steps for the
//!   periodic task ([`MISSION_SLOTS`]; full: the step is dropped and counted, the uploader
//!   sends it again when asked). The receive queue ([`MAV_RX_SLOTS`]) holds 22 ms of a
//!   115 200-baud line, twice the longest the background is busy elsewhere; a byte that finds
//!   it full is dropped and counted (`rx_bytes_dropped` is the control link's; this one's count
//!   is [`MavPort::dropped`]), and the frame's CRC refuses what it damaged.
//! - **Bytes out** (the periodic task, after each period): [`MavOut`] sends the set-point, and
//!   what is due of the status, heartbeat, obstacle distances and mission replies; the busiest
//!   period is about 360 bytes ([`MAV_TX_SLOTS`]; a frame that does not fit is dropped whole
//!   and counted).

use core::sync::atomic::{AtomicU32, Ordering};

use heapless::spsc::{Consumer, Producer, Queue};
use vpf::guidance::mavlink::{MavConfig, MavInbound, MavMission, MavOutbound};
use vpf::guidance::{Background, BackgroundOutputs, Periodic};
use vpf::planner::Command;
use vpf::route::Router;
use vpf::sonar::EvidenceMap;

use super::link::{ByteLink, Outbox};
use super::queues::slots;

/// Slots of the MAVLink link's receive queue.
pub const MAV_RX_SLOTS: usize = slots(256);
/// Slots of its transmit queue.
pub const MAV_TX_SLOTS: usize = slots(384);
/// Slots of the mission-upload queue from the background to the periodic task.
pub const MISSION_SLOTS: usize = slots(4);
/// The MAVLink byte link.
pub type MavLink = ByteLink<MAV_RX_SLOTS, MAV_TX_SLOTS>;
/// The mission-upload queue.
pub type MissionQueue = Queue<MavMission, MISSION_SLOTS>;

/// The background's end.
pub struct MavPort {
    inbound: MavInbound,
    inbox: Consumer<'static, u8, MAV_RX_SLOTS>,
    missions: Producer<'static, MavMission, MISSION_SLOTS>,
    /// Received bytes dropped on a full queue.
    #[allow(dead_code)]
    pub dropped: &'static AtomicU32,
}

impl MavPort {
    /// The inbound half around its queue ends.
    pub fn new(
        cfg: MavConfig,
        inbox: Consumer<'static, u8, MAV_RX_SLOTS>,
        missions: Producer<'static, MavMission, MISSION_SLOTS>,
        dropped: &'static AtomicU32,
    ) -> Self {
        MavPort {
            inbound: MavInbound::new(cfg),
            inbox,
            missions,
            dropped,
        }
    }

    /// Bytes wait in the receive queue.
    pub fn received(&self) -> bool {
        self.inbox.ready()
    }

    /// Takes up to `buf.len()` received bytes.
    pub fn take(&mut self, buf: &mut [u8]) -> usize {
        let mut n = 0;
        for slot in buf.iter_mut() {
            match self.inbox.dequeue() {
                Some(b) => {
                    *slot = b;
                    n += 1;
                }
                None => break,
            }
        }
        n
    }

    /// Bytes from the line into the inbound half.
    pub fn feed(
        &mut self,
        bytes: &[u8],
        now_ms: u64,
        background: &mut Background,
        sink: &mut impl BackgroundOutputs,
        map: Option<&EvidenceMap>,
        router: Option<&mut Router>,
    ) {
        let missions = &mut self.missions;
        self.inbound
            .on_bytes(bytes, now_ms, background, sink, map, router, &mut |m| {
                missions.enqueue(m).is_ok()
            });
    }

    /// The line's counters so far and the bytes dropped on a full queue. (The board images
    /// have no telemetry rows for them yet: read them with a debugger.)
    #[allow(dead_code)]
    pub fn counters(&self) -> (vpf::link::mavlink::MavCounters, u32) {
        (
            *self.inbound.counters(),
            self.dropped.load(Ordering::Relaxed),
        )
    }
}

/// The periodic task's end.
pub struct MavOut {
    outbound: MavOutbound,
    outbox: Outbox<MAV_TX_SLOTS>,
    missions: Consumer<'static, MavMission, MISSION_SLOTS>,
}

impl MavOut {
    /// The outbound half around its queue ends.
    pub fn new(
        cfg: MavConfig,
        outbox: Outbox<MAV_TX_SLOTS>,
        missions: Consumer<'static, MavMission, MISSION_SLOTS>,
    ) -> Self {
        MavOut {
            outbound: MavOutbound::new(cfg),
            outbox,
            missions,
        }
    }

    /// After the period at `now_ms` that sent `cmd`. Not inlined: its frame buffers must not
    /// stay reserved under the planner step's.
    #[inline(never)]
    pub fn on_period(&mut self, now_ms: u64, cmd: &Command, runtime: &mut Periodic) {
        let (missions, outbox) = (&mut self.missions, &mut self.outbox);
        self.outbound
            .on_period(now_ms, cmd, runtime, &mut || missions.dequeue(), &mut |f| {
                outbox.send(f)
            });
        crate::board::active::kick_mavlink_tx();
    }
}
