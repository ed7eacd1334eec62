//! The Ping protocol of Blue Robotics: the wire format a Ping360 scanning sonar speaks on its
//! serial line, kept apart from any logic as in smoltcp's `wire` module.
//!
//! Checked against Blue Robotics' published definitions (`bluerobotics/ping-protocol`:
//! `docs/index.md` for the framing, `src/definitions/common.json` and `ping360.json` for the
//! messages); the test vectors of [`frame`] are the protocol documentation's own.
//!
//! **Frame** (little-endian): `'B' 'R'` · `payload_length` u16 · `message_id` u16 ·
//! `src_device_id` u8 · `dst_device_id` u8 · payload · `checksum` u16, the sum of every byte
//! before it, modulo 2¹⁶.
//!
//! **Layers** (one file each):
//! - [`frame`]: [`Frame`], a checked view over a frame's bytes (header fields, payload,
//!   checksum), and [`emit_frame`];
//! - [`common`]: the common messages a driver needs: `ack` (1), `nack` (2), `protocol_version`
//!   (5), `general_request` (6);
//! - [`ping360`]: the Ping360's `device_data` (2300) and `transducer` (2601);
//! - [`message`]: [`Message`], every message above in one enum, parsed by id;
//! - [`decoder`]: the stream decoder: bytes in, events out, resync on the next `'B' 'R'`, a
//!   counter for everything it drops. It streams `device_data`'s samples through instead of
//!   buffering them (a 1200-sample frame is 1224 bytes; the decoder holds 42).
//!
//! Nothing here allocates, panics or indexes out of bounds on any input.

pub mod common;
pub mod decoder;
pub mod frame;
pub mod message;
pub mod ping360;

pub use common::{AckRepr, GeneralRequestRepr, NackRepr, ProtocolVersionRepr};
pub use decoder::{Decoder, DecoderCounters, Event};
pub use frame::{emit_frame, Frame, Header};
pub use message::Message;
pub use ping360::{DeviceDataHead, DeviceDataRepr, PingSettings, TransducerRepr};

/// The two start bytes of every frame, ASCII `'B' 'R'`.
pub const START: [u8; 2] = *b"BR";
/// Header length: start bytes, payload length, message id, source and destination ids.
pub const HEADER_LEN: usize = 8;
/// Checksum length.
pub const CHECKSUM_LEN: usize = 2;
/// Most samples in one `device_data` (the definition's "supported values: 200~1200").
pub const MAX_SAMPLES: usize = 1200;
/// Longest payload accepted: a `device_data` with [`MAX_SAMPLES`] samples. A header that
/// announces more is refused at once ([`Error::Oversize`]), so a corrupted length cannot make
/// the decoder swallow the stream.
pub const MAX_PAYLOAD: usize = ping360::DEVICE_DATA_HEAD_LEN + MAX_SAMPLES;
/// Device id of the host (the protocol reserves no id for it; 0 is "unknown", as Blue Robotics'
/// own tools send).
pub const HOST_ID: u8 = 0;

/// Message ids used here.
pub mod id {
    /// `ack`: acknowledged.
    pub const ACK: u16 = 1;
    /// `nack`: not acknowledged, with a text.
    pub const NACK: u16 = 2;
    /// `protocol_version`.
    pub const PROTOCOL_VERSION: u16 = 5;
    /// `general_request`: asks the device to send a message.
    pub const GENERAL_REQUEST: u16 = 6;
    /// Ping360 `device_data`: one ping's settings and samples.
    pub const DEVICE_DATA: u16 = 2300;
    /// Ping360 `transducer`: move the head, ping, answer with `device_data`.
    pub const TRANSDUCER: u16 = 2601;
}

/// Why bytes could not be parsed or emitted. Small and `Copy`, like smoltcp's `wire::Error`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// Fewer bytes than the header, payload length and checksum need.
    Truncated,
    /// The frame does not start with `'B' 'R'`.
    Start,
    /// The checksum does not match the bytes before it.
    Checksum,
    /// The payload length exceeds [`MAX_PAYLOAD`].
    Oversize,
    /// The payload's length is wrong for its message id (or a `device_data`'s data length
    /// disagrees with it).
    Length,
    /// A field's value is outside what the definition allows (the field's name).
    Field(&'static str),
    /// A message id this module does not parse.
    UnknownId(u16),
    /// The output buffer is too small.
    BufferTooSmall,
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::Truncated => f.write_str("shorter than its header, payload and checksum"),
            Error::Start => f.write_str("does not start with 'B' 'R'"),
            Error::Checksum => f.write_str("checksum mismatch"),
            Error::Oversize => write!(f, "payload longer than {MAX_PAYLOAD} bytes"),
            Error::Length => f.write_str("payload length wrong for its message"),
            Error::Field(name) => write!(f, "field `{name}` out of range"),
            Error::UnknownId(id) => write!(f, "message id {id} not handled"),
            Error::BufferTooSmall => f.write_str("output buffer too small"),
        }
    }
}

impl core::error::Error for Error {}

/// The little-endian u16 at `at`, if the slice holds it.
fn get_u16(bytes: &[u8], at: usize) -> Option<u16> {
    match bytes.get(at..at.checked_add(2)?)? {
        [lo, hi] => Some(u16::from_le_bytes([*lo, *hi])),
        _ => None,
    }
}

/// Writes `v` little-endian at `at`; `false` if it does not fit.
fn put_u16(bytes: &mut [u8], at: usize, v: u16) -> bool {
    match at.checked_add(2).and_then(|end| bytes.get_mut(at..end)) {
        Some(dst) => {
            dst.copy_from_slice(&v.to_le_bytes());
            true
        }
        None => false,
    }
}

/// The Ping protocol checksum: the sum of `bytes`, modulo 2¹⁶.
pub fn checksum(bytes: &[u8]) -> u16 {
    bytes
        .iter()
        .fold(0u16, |s, &b| s.wrapping_add(u16::from(b)))
}

#[cfg(test)]
mod tests {
    use super::*;
    extern crate std;
    use std::string::ToString;

    #[test]
    fn checksum_is_the_byte_sum_mod_2_16() {
        // The protocol documentation's general_request example: 66 + 82 + 2 + 6 + 5 = 161.
        assert_eq!(checksum(&[0x42, 0x52, 2, 0, 6, 0, 0, 0, 5, 0]), 161);
        assert_eq!(checksum(&[0xff; 258]), (258u32 * 255 % 65536) as u16);
        assert_eq!(checksum(&[]), 0);
    }

    #[test]
    fn capacities_and_errors_display() {
        assert_eq!(MAX_PAYLOAD, 1214);
        assert_eq!(
            Error::Field("angle").to_string(),
            "field `angle` out of range"
        );
        assert_eq!(Error::UnknownId(7).to_string(), "message id 7 not handled");
        assert_eq!(get_u16(&[1, 2, 3], 1), Some(0x0302));
        assert_eq!(get_u16(&[1, 2, 3], 2), None);
        assert_eq!(get_u16(&[1, 2, 3], usize::MAX), None);
        let mut b = [0u8; 3];
        assert!(put_u16(&mut b, 1, 0xABCD));
        assert_eq!(b, [0, 0xCD, 0xAB]);
        assert!(!put_u16(&mut b, 2, 1));
    }
}
