//! The [`Payload`] trait: what every message's wire form implements, in smoltcp's `Repr`
//! style. Its own file so that the message files and [`Message`](super::Message), which lists
//! them all, both depend on it and not on each other.

use super::frame::{encode_frame, MessageType};
use super::Error;
#[cfg(doc)]
use super::MAX_FRAME;

/// A message's payload: its wire type, and parse/emit in smoltcp's `Repr` style.
///
/// `parse` checks the length exactly and every field (see each type's layout); `emit` refuses
/// exactly what `parse` would refuse, writes [`Payload::payload_len`] bytes and returns that
/// number.
pub trait Payload<'a>: Sized {
    /// The message type this payload travels as.
    const TYPE: MessageType;

    /// Parses and validates a payload (the bytes between header and CRC). Borrowed fields
    /// (scanline bins, contacts, log text) point into `payload`.
    fn parse(payload: &'a [u8]) -> Result<Self, Error>;

    /// The number of bytes [`Payload::emit`] writes.
    fn payload_len(&self) -> usize;

    /// Validates and writes the payload into `out`; returns the bytes written.
    fn emit(&self, out: &mut [u8]) -> Result<usize, Error>;

    /// Writes a complete frame (COBS, CRC, delimiter) with sequence number `seq` into `out`;
    /// returns its length. [`MAX_FRAME`] bytes always suffice.
    fn emit_frame(&self, seq: u16, out: &mut [u8]) -> Result<usize, Error> {
        encode_frame(Self::TYPE, seq, |buf| self.emit(buf), out)
    }
}
