//! The AN386's ethernet controller (an SMSC LAN9220; QEMU models it as the register-compatible
//! LAN9118) as a second way into the control link: the same byte stream as UART0, carried in
//! raw ethernet frames, so that a period's bytes move in one frame instead of one byte per
//! interrupt.
//!
//! Why: QEMU's CMSDK UART has no FIFO and takes one byte per turn of QEMU's main loop (tens of
//! µs of host time a byte), which made a lockstep period of ~560 bytes cost ~25 ms of wall time.
//! The controller's receive FIFO takes a whole frame in one go. The HIL harness uses this link
//! on QEMU (`-nic socket,fd=…,model=lan9118`); UART0 stays the link for everything else
//! (`cargo qemu`, a real board), and the firmware answers on the link the host last spoke on.
//!
//! A frame: destination and source address, EtherType [`ETHERTYPE`] (IEEE 802 local
//! experimental), a 16-bit little-endian length `n`, then `n` bytes of the link's byte stream
//! (the length keeps a frame that the network padded to its 60-byte minimum exact). Frames of
//! another type, or damaged ones, are skipped. At start-up the firmware sends one empty frame:
//! the controller is up, and a frame sent from now on is not lost.
//!
//! Register map and FIFO formats: SMSC LAN9118 datasheet (system control and status registers,
//! §5.3; TX command A/B, §3.12; RX status, §3.13). Every wait on the hardware is bounded.

use core::sync::atomic::{AtomicBool, Ordering};

use vcell::VolatileCell;

use crate::firmware::link::{Receiver, Transmitter};

/// The controller's register block on the AN386.
const BASE: usize = 0x4020_0000;
/// The EtherType of the link's frames: 0x88B5, IEEE 802 local experimental.
pub const ETHERTYPE: u16 = 0x88B5;
/// Most link bytes in one frame (a 1514-byte frame less the header and the length).
pub const MAX_PAYLOAD: usize = 1496;

const RX_DATA: usize = 0x00;
const TX_DATA: usize = 0x20;
const RX_STATUS: usize = 0x40;
const IRQ_CFG: usize = 0x54;
const INT_STS: usize = 0x58;
const INT_EN: usize = 0x5c;
const BYTE_TEST: usize = 0x64;
const TX_CFG: usize = 0x70;
const HW_CFG: usize = 0x74;
const RX_FIFO_INF: usize = 0x7c;
const TX_FIFO_INF: usize = 0x80;
const PMT_CTRL: usize = 0x84;
const MAC_CSR_CMD: usize = 0xa4;
const MAC_CSR_DATA: usize = 0xa8;

/// BYTE_TEST's fixed value: the controller is there and the bus order is right.
const BYTE_TEST_VALUE: u32 = 0x8765_4321;
/// IRQ_CFG: output enabled, active high, push-pull.
const IRQ_ENABLE_HIGH: u32 = (1 << 8) | (1 << 4) | 1;
/// INT_STS / INT_EN: the receive status FIFO holds a frame.
const RSFL: u32 = 1 << 3;
/// TX_CFG: transmitter on; the status FIFO may overrun (nobody reads it).
const TX_ON_STATUS_OVERRUN: u32 = (1 << 1) | (1 << 2);
/// MAC_CR (MAC register 1): receiver and transmitter on, every destination address.
const MAC_CR: u32 = 1;
const MAC_CR_ON: u32 = (1 << 2) | (1 << 3) | (1 << 18);
/// MAC_CSR_CMD: busy / start bit.
const CSR_BUSY: u32 = 1 << 31;
/// RX status: the error summary bit.
const RX_STATUS_ERROR: u32 = 1 << 15;
/// TX command A: first and last segment of the frame.
const TX_FIRST_LAST: u32 = (1 << 13) | (1 << 12);
/// The header of a link frame, in FIFO words: 14 bytes of ethernet header and 2 of length.
const HEADER_WORDS: u32 = 4;
/// Polls of a status bit before start-up gives up on the controller.
const WAIT_POLLS: u32 = 100_000;

/// Set when the receive handler left a frame in the controller's FIFO for want of room in the
/// link's queue; the background then raises the interrupt again ([`resume_receive`]).
static HELD: AtomicBool = AtomicBool::new(false);
/// Whether the host last spoke over ethernet (then the firmware answers there too).
static HOST_HERE: AtomicBool = AtomicBool::new(false);

fn reg(offset: usize) -> &'static VolatileCell<u32> {
    // # Safety
    // `BASE + offset` is a 4-byte aligned register of the controller's block, always mapped on
    // this board; it is only touched through the `VolatileCell` (volatile loads and stores).
    // The controller is driven by one context at a time: start-up, then the one hardware task
    // bound to its interrupt.
    #[allow(unsafe_code)]
    unsafe {
        &*((BASE + offset) as *const VolatileCell<u32>)
    }
}

/// Polls `done` at most [`WAIT_POLLS`] times.
fn wait_for(done: impl Fn() -> bool) -> bool {
    (0..WAIT_POLLS).any(|_| done())
}

/// Whether the host last spoke over ethernet.
pub fn host_here() -> bool {
    HOST_HERE.load(Ordering::Relaxed)
}

/// The host spoke on UART0: answer there from now on.
pub fn host_left() {
    HOST_HERE.store(false, Ordering::Relaxed);
}

/// Whether a frame waits for room in the link's queue (the background then pends the
/// interrupt once it has taken bytes out).
pub fn resume_receive() -> bool {
    HELD.swap(false, Ordering::AcqRel)
}

/// The controller, its receive interrupt on.
pub struct Ethernet {
    /// Words of the current frame still in the receive FIFO.
    words_left: u32,
    /// Header words of the current frame read so far.
    header: u32,
    /// Link bytes of the current frame still to take.
    bytes_left: u32,
}

impl Ethernet {
    /// Resets and starts the controller; `None` if there is none (BYTE_TEST) or it does not
    /// come ready.
    pub fn take() -> Option<Ethernet> {
        if reg(BYTE_TEST).get() != BYTE_TEST_VALUE {
            return None;
        }
        reg(HW_CFG).set(1);
        if !wait_for(|| reg(HW_CFG).get() & 1 == 0) || !wait_for(|| reg(PMT_CTRL).get() & 1 != 0) {
            return None;
        }
        reg(MAC_CSR_DATA).set(MAC_CR_ON);
        reg(MAC_CSR_CMD).set(CSR_BUSY | MAC_CR);
        if !wait_for(|| reg(MAC_CSR_CMD).get() & CSR_BUSY == 0) {
            return None;
        }
        reg(TX_CFG).set(TX_ON_STATUS_OVERRUN);
        reg(INT_STS).set(u32::MAX);
        reg(INT_EN).set(RSFL);
        reg(IRQ_CFG).set(IRQ_ENABLE_HIGH);
        // An empty frame says the controller is up: the host waits for it before it sends.
        start_frame(0);
        Some(Ethernet {
            words_left: 0,
            header: 0,
            bytes_left: 0,
        })
    }

    /// The interrupt's body: received frames into the link's queue (as far as it has room),
    /// then, if the host is on this link, queued bytes out.
    pub fn on_interrupt<const RX: usize, const TX: usize>(
        &mut self,
        receiver: &mut Receiver<RX>,
        transmitter: &mut Transmitter<TX>,
    ) {
        reg(INT_STS).set(RSFL);
        self.receive(receiver);
        if host_here() {
            transmit(transmitter);
        }
    }

    /// Moves received link bytes into the queue, word by word; stops with the rest of a frame
    /// left in the FIFO when the queue has no room for the next word (and says so in [`HELD`]).
    fn receive<const RX: usize>(&mut self, receiver: &mut Receiver<RX>) {
        loop {
            if self.words_left == 0 {
                if (reg(RX_FIFO_INF).get() >> 16) & 0xff == 0 {
                    return;
                }
                let status = reg(RX_STATUS).get();
                // The frame's length with its 4-byte CRC, in whole FIFO words.
                self.words_left = ((status >> 16) & 0x3fff).div_ceil(4);
                self.header = 0;
                self.bytes_left = 0;
                if status & RX_STATUS_ERROR != 0 {
                    // Damaged: skipped (header counted as read, no link bytes taken).
                    self.header = HEADER_WORDS;
                }
                continue;
            }
            if self.header < HEADER_WORDS {
                let w = reg(RX_DATA).get();
                self.words_left -= 1;
                self.header += 1;
                if self.header == HEADER_WORDS && (w & 0xffff) as u16 == ETHERTYPE.swap_bytes() {
                    // Never more than the frame holds (its data words less the CRC's).
                    let room = self.words_left.saturating_sub(1) * 4;
                    self.bytes_left = (w >> 16).min(room);
                    HOST_HERE.store(true, Ordering::Relaxed);
                }
                continue;
            }
            if self.bytes_left > 0 {
                let n = self.bytes_left.min(4);
                if receiver.room() < n as usize {
                    HELD.store(true, Ordering::Release);
                    return;
                }
                let w = reg(RX_DATA).get();
                self.words_left -= 1;
                self.bytes_left -= n;
                for b in w.to_le_bytes().iter().take(n as usize) {
                    receiver.push(*b);
                }
                continue;
            }
            // Padding and the CRC.
            let _ = reg(RX_DATA).get();
            self.words_left -= 1;
        }
    }
}

/// Sends the queued bytes in frames of up to [`MAX_PAYLOAD`], while the controller's transmit
/// FIFO has room for a whole frame.
fn transmit<const TX: usize>(transmitter: &mut Transmitter<TX>) {
    while !transmitter.is_empty() {
        let n = transmitter.len().min(MAX_PAYLOAD);
        if !start_frame(n) {
            return;
        }
        let fifo = reg(TX_DATA);
        let mut left = n;
        while left > 0 {
            let mut w = [0u8; 4];
            for slot in w.iter_mut().take(left.min(4)) {
                *slot = transmitter.pop().unwrap_or(0);
            }
            fifo.set(u32::from_le_bytes(w));
            left = left.saturating_sub(4);
        }
    }
}

/// Writes the command words and the header of a frame carrying `n` link bytes (the caller
/// writes them next); `false`, writing nothing, if the transmit FIFO has no room for it.
fn start_frame(n: usize) -> bool {
    let total = 4 * HEADER_WORDS + n as u32;
    // Free bytes of the data FIFO: the whole frame with its two command words must fit.
    if reg(TX_FIFO_INF).get() & 0xffff < total + 8 {
        return false;
    }
    let fifo = reg(TX_DATA);
    fifo.set(TX_FIRST_LAST | total);
    fifo.set(total);
    // Broadcast destination (the host's address is not known), a locally administered source
    // address (02:00:56:50:46:01), the EtherType (big-endian on the wire) and the length.
    fifo.set(u32::MAX);
    fifo.set(0x0002_ffff);
    fifo.set(0x0146_5056);
    fifo.set(u32::from(ETHERTYPE.swap_bytes()) | (n as u32) << 16);
    true
}
