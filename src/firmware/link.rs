//! A byte link: one UART's two byte queues, between its interrupt handler(s) and the tasks.
//!
//! The UART is anything that implements `embedded-io`'s `Read + ReadReady` (receive) and
//! `Write + WriteReady` (transmit), so any HAL's UART plugs in behind a thin adapter. The
//! interrupt ends are O(1) per byte: they move bytes between the UART and a lock-free SPSC queue
//! and never wait. A second link (a sonar on its own UART) is a second [`ByteLink`] with its own
//! capacities, its own interrupt task(s) calling [`Receiver::receive`] and
//! [`Transmitter::transmit`], and its own consumer in the task that decodes it.

use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use embedded_io::{Read, ReadReady, Write, WriteReady};
use heapless::spsc::{Consumer, Producer, Queue};

/// A link's queues: `RX` received bytes and `TX` bytes to send (heapless keeps one slot free,
/// so they hold `RX − 1` and `TX − 1`), and the count of received bytes dropped on a full queue.
pub struct ByteLink<const RX: usize, const TX: usize> {
    received: Queue<u8, RX>,
    to_send: Queue<u8, TX>,
    dropped: AtomicU32,
    held: AtomicBool,
}

/// What a link hands out, once: each end to the one context that uses it.
pub struct LinkEnds<const RX: usize, const TX: usize> {
    /// For the receive interrupt.
    pub receiver: Receiver<RX>,
    /// For the transmit interrupt.
    pub transmitter: Transmitter<TX>,
    /// Received bytes, for the task that decodes them.
    pub inbox: Consumer<'static, u8, RX>,
    /// Bytes to send, for the task that emits frames.
    pub outbox: Outbox<TX>,
    /// Received bytes dropped on a full queue (read and reset by the task that reports them).
    pub dropped: &'static AtomicU32,
    /// Set by [`Receiver::receive_or_hold`] when it left a byte in the UART (the queue was
    /// full); the task that decodes takes it ([`take_held`]) and pends the receive interrupt.
    pub held: &'static AtomicBool,
}

impl<const RX: usize, const TX: usize> ByteLink<RX, TX> {
    /// Empty queues (in `.bss`).
    pub const fn new() -> Self {
        ByteLink {
            received: Queue::new(),
            to_send: Queue::new(),
            dropped: AtomicU32::new(0),
            held: AtomicBool::new(false),
        }
    }

    /// Splits the link into its ends (RTIC hands start-up the `'static` link exactly once).
    pub fn split(&'static mut self) -> LinkEnds<RX, TX> {
        let (rx_p, rx_c) = self.received.split();
        let (tx_p, tx_c) = self.to_send.split();
        let (dropped, held) = (&self.dropped, &self.held);
        LinkEnds {
            receiver: Receiver {
                queue: rx_p,
                dropped,
                held,
            },
            transmitter: Transmitter { queue: tx_c },
            inbox: rx_c,
            outbox: Outbox { queue: tx_p },
            dropped,
            held,
        }
    }
}

impl<const RX: usize, const TX: usize> Default for ByteLink<RX, TX> {
    fn default() -> Self {
        Self::new()
    }
}

/// The receive interrupt's end.
pub struct Receiver<const RX: usize> {
    queue: Producer<'static, u8, RX>,
    dropped: &'static AtomicU32,
    held: &'static AtomicBool,
}

impl<const RX: usize> Receiver<RX> {
    /// Moves every byte the UART holds into the queue; a byte that finds the queue full is
    /// dropped and counted (the decoder resyncs on the next frame), one the UART reports damaged
    /// is dropped (the frame's CRC catches it).
    pub fn receive<U: Read + ReadReady>(&mut self, uart: &mut U) {
        while let Ok(true) = uart.read_ready() {
            let mut byte = [0u8; 1];
            match uart.read(&mut byte) {
                Ok(1) => {
                    if self.queue.enqueue(byte[0]).is_err() {
                        self.dropped.fetch_add(1, Ordering::Relaxed);
                    }
                }
                Ok(_) => break,
                Err(_) => {}
            }
        }
    }

    /// Bytes the queue has room for (a link that moves bytes in blocks takes no more).
    #[cfg_attr(not(feature = "mps2-an386"), allow(dead_code))] // the ethernet link
    pub fn room(&self) -> usize {
        self.queue.capacity() - self.queue.len()
    }

    /// Queues one received byte; dropped and counted if the queue is full.
    #[cfg_attr(not(feature = "mps2-an386"), allow(dead_code))] // the ethernet link
    pub fn push(&mut self, byte: u8) {
        if self.queue.enqueue(byte).is_err() {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }
}

impl<const RX: usize> Receiver<RX> {
    /// Moves bytes from the UART into the queue while it has room; when it is full, leaves the
    /// byte in the UART and returns `true`: the caller turns its receive interrupt off, and the
    /// decoding task pends it again once it has taken bytes ([`take_held`]). Nothing is
    /// dropped here. On QEMU the emulated UART then holds the rest of the input back (a lossless
    /// link, whatever the emulator's pace); on a real UART the next byte overruns the one
    /// waiting after one byte time, and the line error loses it (counted by the protocol's
    /// checksum), as a drop would.
    pub fn receive_or_hold<U: Read + ReadReady>(&mut self, uart: &mut U) -> bool {
        while let Ok(true) = uart.read_ready() {
            if !self.queue.ready() {
                self.held.store(true, Ordering::Release);
                return true;
            }
            let mut byte = [0u8; 1];
            match uart.read(&mut byte) {
                Ok(1) => {
                    let _ = self.queue.enqueue(byte[0]);
                }
                Ok(_) => break,
                // A byte lost on the line (an overrun after a hold, noise, framing): counted.
                Err(_) => {
                    self.dropped.fetch_add(1, Ordering::Relaxed);
                }
            }
        }
        false
    }
}

/// Whether a receiver held a byte back since the last call (clears it): the decoding task
/// then pends the receive interrupt, which takes the byte now that there is room.
pub fn take_held(held: &AtomicBool) -> bool {
    held.swap(false, Ordering::AcqRel)
}

/// The transmit interrupt's end.
pub struct Transmitter<const TX: usize> {
    queue: Consumer<'static, u8, TX>,
}

impl<const TX: usize> Transmitter<TX> {
    /// Sends queued bytes while the UART takes them; whether bytes remain (the caller keeps its
    /// transmit interrupt on only while they do).
    pub fn transmit<U: Write + WriteReady>(&mut self, uart: &mut U) -> bool {
        while let Some(&b) = self.queue.peek() {
            if !matches!(uart.write_ready(), Ok(true)) {
                break;
            }
            match uart.write(&[b]) {
                Ok(1) => {
                    let _ = self.queue.dequeue();
                }
                _ => break,
            }
        }
        self.queue.ready()
    }

    /// Bytes waiting to be sent.
    #[cfg_attr(not(feature = "mps2-an386"), allow(dead_code))] // the ethernet link
    pub fn len(&self) -> usize {
        self.queue.len()
    }

    /// Whether no bytes wait.
    #[cfg_attr(not(feature = "mps2-an386"), allow(dead_code))] // the ethernet link
    pub fn is_empty(&self) -> bool {
        !self.queue.ready()
    }

    /// Takes the next byte to send (a link that moves bytes in blocks).
    #[cfg_attr(not(feature = "mps2-an386"), allow(dead_code))] // the ethernet link
    pub fn pop(&mut self) -> Option<u8> {
        self.queue.dequeue()
    }
}

/// The sending task's end.
pub struct Outbox<const TX: usize> {
    queue: Producer<'static, u8, TX>,
}

impl<const TX: usize> Outbox<TX> {
    /// Queues a whole frame; `false` (nothing queued) if it does not fit.
    pub fn send(&mut self, frame: &[u8]) -> bool {
        if self.queue.capacity() - self.queue.len() < frame.len() {
            return false;
        }
        frame.iter().all(|&b| self.queue.enqueue(b).is_ok())
    }
}
