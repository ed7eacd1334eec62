//! The Ping360 on a UART of its own: the driver (`vpf::sonar::ping360`) run by the background,
//! its bytes in and out through a second [`ByteLink`](super::link::ByteLink).
//!
//! - **Bytes in**: the sonar UART's receive task queues them ([`SONAR_RX_SLOTS`]); when the
//!   queue is full it leaves the byte in the UART and turns its interrupt off
//!   ([`Receiver::receive_or_hold`](super::link::Receiver::receive_or_hold)), and the
//!   background pends it again once it has taken bytes. A `device_data` of the board's
//!   settings is 324 bytes; the queue covers the longest the background is busy elsewhere (a
//!   route replan, ≈ 7 ms at 180 MHz, and a period that preempts it, ≈ 3 ms: ≈ 120 bytes at
//!   115 200 baud) twice over.
//! - **Bytes out**: `transducer` commands (24 bytes; one is outstanding at a time) into
//!   [`SONAR_TX_SLOTS`]; full: the driver sends again at its next poll.
//! - **When**: the background feeds received bytes to [`vpf::sonar::ping360::Ping360::on_bytes`]
//!   with the newest pose and hands each scanline to `Background::on_scanline` (the extractor
//!   and the evidence map, as a `Scanline` message's). The driver's poll (its first command and
//!   its timeouts) runs once per period: in real time after each period, in lockstep at each
//!   `Tick`'s time just before that period runs, so the period's telemetry counts the command
//!   (the HIL harness relies on it). It starts once navigation has come, or at the first `Tick`
//!   (`vpf::guidance::one_thread::ping360_started`, the host-process firmware's rule).

use core::sync::atomic::AtomicBool;

use heapless::spsc::Consumer;
use vpf::sonar::ping360::{Ping360, Ping360Counters};

use super::link::{self, ByteLink, Outbox};
use super::queues::slots;

/// Slots of the sonar link's receive queue.
pub const SONAR_RX_SLOTS: usize = slots(256);
/// Slots of the sonar link's transmit queue: two `transducer` frames.
pub const SONAR_TX_SLOTS: usize = slots(2 * vpf::sonar::ping360::driver::TRANSDUCER_FRAME_LEN);
/// The sonar's byte link: UART1 on the emulated board, USART1 on the NUCLEO.
pub type SonarLink = ByteLink<SONAR_RX_SLOTS, SONAR_TX_SLOTS>;

/// The background's end of the sonar: the driver and its queue ends.
pub struct SonarPort {
    /// The Ping360 driver.
    pub driver: Ping360,
    /// Bytes the sonar sent.
    pub inbox: Consumer<'static, u8, SONAR_RX_SLOTS>,
    /// Bytes for the sonar.
    pub outbox: Outbox<SONAR_TX_SLOTS>,
    /// The receive task left a byte in the UART (its queue was full).
    pub held: &'static AtomicBool,
    /// Firmware time of the last poll (real time: once per period).
    pub polled_ms: Option<u64>,
}

impl SonarPort {
    /// The driver around the link's ends.
    pub fn new(
        driver: Ping360,
        inbox: Consumer<'static, u8, SONAR_RX_SLOTS>,
        outbox: Outbox<SONAR_TX_SLOTS>,
        held: &'static AtomicBool,
    ) -> Self {
        SonarPort {
            driver,
            inbox,
            outbox,
            held,
            polled_ms: None,
        }
    }

    /// Takes up to `buf.len()` received bytes; pends the receive task if it held one back.
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
        if n > 0 && link::take_held(self.held) {
            crate::board::active::resume_sonar_rx();
        }
        n
    }

    /// The driver's poll at `now_ms` (its first command, its timeouts), once per `now_ms`.
    pub fn poll(&mut self, now_ms: u64) {
        if self.polled_ms == Some(now_ms) {
            return;
        }
        self.polled_ms = Some(now_ms);
        let outbox = &mut self.outbox;
        self.driver.poll(now_ms, &mut |f| outbox.send(f));
        crate::board::active::kick_sonar_tx();
    }

    /// The driver's counters.
    pub fn counters(&self) -> Ping360Counters {
        self.driver.counters()
    }
}
