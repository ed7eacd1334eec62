//! The serial link's wire format: how the host and the firmware talk over a byte stream.
//!
//! The full specification, for people writing their own host software, is
//! `docs/protocol.md`; this module is its implementation, shared by the firmware and the
//! host-side HIL harness. As in smoltcp's `wire` module, the formats are kept apart from any
//! logic: each message is a plain `Repr` (or a library type such as [`Params`]) with
//! [`Payload::parse`] and [`Payload::emit`], and the runtime decides what to do with it.
//!
//! The messages carry the crate's value types ([`crate::types`], [`crate::params`]); nothing
//! here needs the planner.
//!
//! **Layers** (one file each):
//! - [`crc`]: CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, check 0x29B1), table-free;
//! - [`cobs`]: Consistent Overhead Byte Stuffing, so 0x00 can delimit frames (to the host);
//! - [`reed_solomon`]: RS(255, 239) over GF(2⁸), the forward error correction;
//! - [`coded`]: the coded frame to the firmware: Reed–Solomon parity, whitening, zero
//!   substitution, so that up to 8 wrong bytes per 239 are corrected on the way;
//! - [`frame`]: header (version, type, sequence), payload and CRC, coded (to the firmware) or
//!   COBS-encoded (to the host), 0x00-ended;
//! - [`decoder`]: the stream decoder: bytes in, one [`Outcome`] per byte or chunk, resync on
//!   the next 0x00, a counter for every rejection;
//! - [`layout`]: [`Field`](layout::Field), a named row of a message's layout; each message file's
//!   `field` module names its rows (checked against `docs/protocol.md` by a test);
//! - [`shape`]: the wire form of an obstacle [`Shape`](crate::field::Shape);
//! - [`sensors`], [`control`], [`mission`] (host → firmware), [`report`] (firmware → host) and
//!   [`belief`]: the messages, each with a `field` module naming its rows; [`formation`], the
//!   formation block three of them share; [`modes`] and [`counters`], the mode codes and
//!   counters the reports carry;
//! - [`payload`]: the [`Payload`] trait every message implements (parse, emit, length);
//! - [`message`]: [`Message`], every message in one enum, and whole-frame parse/emit.
//!
//! **Frame** on the wire: to the firmware `zero-substitute(whiten(header ‖ payload ‖ CRC ‖
//! parity)) ‖ 0x00`, to the host `COBS(header ‖ payload ‖ CRC) ‖ 0x00`, where the header is
//! `version u8, type u8, sequence u16`, the CRC covers header and payload, and every number is
//! little-endian (floats are IEEE-754 `f32`). The message type's direction says which framing a
//! frame has.
//!
//! **Validation.** Every parse checks lengths exactly, refuses NaN and infinities, unknown enum
//! codes and out-of-range values with a typed [`Error`] naming the field (its row in the layout
//! table of `docs/protocol.md`) and the [`Problem`]. Emitting refuses what parsing would refuse,
//! so a frame this module emits is always accepted by this module. The one exception is
//! [`Params`]: only non-finite numbers and unknown codes are refused at the wire, the ranges are
//! checked by [`Planner::set_params`](crate::planner::Planner::set_params), which names the
//! parameter, and the firmware reports it back in a [`ReplyRepr`].
//!
//! Nothing here allocates, panics or indexes out of bounds on any input.

pub mod belief;
pub mod cobs;
mod codec;
pub mod coded;
pub mod control;
pub mod counters;
pub mod crc;
pub mod decoder;
pub mod formation;
pub mod frame;
pub mod layout;
pub mod mavlink;
pub mod message;
pub mod mission;
pub mod modes;
pub mod payload;
pub mod ping;
pub mod reed_solomon;
pub mod report;
pub mod sensors;
pub mod shape;

pub use belief::{BeliefRepr, BELIEF_ROWS};
pub use control::{
    param_index, ChartClearRepr, ChartObstacleRepr, TickRepr, PARAMS_LEN, PARAM_NAMES,
};
pub use counters::{Ping360Counters, TelemetryCounters};
pub use decoder::{Decoder, Outcome, RxCounters};
pub use frame::{
    encode_frame, encode_frame_to_host, frame_buffer_len, split_frame, Direction, Header,
    MessageType,
};
pub use message::Message;
pub use mission::{MissionCountRepr, MissionItemRepr, SurveyRepr};
pub use payload::Payload;
pub use report::{
    CommandRepr, CostUnit, LogLevel, LogRepr, ReplyRepr, ReplyStatus, TelemetryRepr,
    FIELD_WHOLE_MESSAGE,
};
pub use sensors::{BodyVelocity, Contact, ContactKind, ContactList, ContactsRepr, NavRepr};

#[cfg(doc)]
use crate::params::Params;

/// The protocol version this module speaks, first byte of every header. Frames with another
/// version are refused (and counted): a new version is a new, incompatible layout.
pub const PROTOCOL_VERSION: u8 = 8;
/// The frame delimiter. COBS guarantees it appears nowhere inside a frame.
pub const DELIMITER: u8 = 0x00;
/// Length of the frame header: version u8, message type u8, sequence u16.
pub const HEADER_LEN: usize = 4;
/// Length of the CRC trailer (CRC-16, little-endian).
pub const CRC_LEN: usize = 2;
/// Most intensity bins in one [`Scanline`](crate::sonar::Scanline) message (the Micron's
/// maximum resolution; the same number as the sonar module's).
pub const MAX_BINS: usize = crate::types::MAX_BINS;
/// Most contacts in one `Contacts` message (a sonar that extracts features itself rarely
/// reports more per ping; send several messages for more).
pub const MAX_CONTACTS: usize = 8;
/// Longest `Log` text, bytes of UTF-8.
pub const MAX_LOG_LEN: usize = 96;
/// Longest payload of any message: a `Contacts` message with [`MAX_CONTACTS`] octagons.
pub const MAX_PAYLOAD: usize = message::max_payload_len();
/// Longest decoded frame: header, payload and CRC. The decoder's buffer has this size.
pub const MAX_RAW: usize = HEADER_LEN + MAX_PAYLOAD + CRC_LEN;
/// Longest codeword of a frame to the firmware: the raw frame and its Reed–Solomon parity.
pub const MAX_CODEWORD: usize = coded::codeword_len(MAX_RAW);
/// Longest frame to the host on the wire, COBS overhead and the 0x00 delimiter included. A
/// frame whose bytes exceed it is dropped as soon as they do (counted as oversize), and the
/// decoder skips to the next 0x00.
pub const MAX_COBS_FRAME: usize = cobs::max_encoded_len(MAX_RAW) + 1;
/// Longest frame to the firmware on the wire: the codeword, its keys and the delimiter. Longer
/// ones are dropped as [`MAX_COBS_FRAME`] says.
pub const MAX_CODED_FRAME: usize = coded::wire_len(MAX_CODEWORD) + 1;
/// Longest frame on the wire either way: a transmit buffer size that fits every message.
pub const MAX_FRAME: usize = if MAX_CODED_FRAME > MAX_COBS_FRAME {
    MAX_CODED_FRAME
} else {
    MAX_COBS_FRAME
};

/// What is wrong with a field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum Problem {
    /// NaN or infinite.
    NonFinite = 1,
    /// Outside the documented range (or a count beyond a capacity).
    OutOfRange = 2,
    /// An enum code or flag bit that is not defined.
    UnknownCode = 3,
    /// Structurally invalid: a polygon that is not convex, text that is not UTF-8, fields that
    /// contradict each other.
    Invalid = 4,
    /// Valid, but a table is full (in replies only).
    TableFull = 5,
}

impl Problem {
    /// Its wire code.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// The problem with wire code `code`, if any.
    pub const fn from_code(code: u8) -> Option<Problem> {
        Some(match code {
            1 => Problem::NonFinite,
            2 => Problem::OutOfRange,
            3 => Problem::UnknownCode,
            4 => Problem::Invalid,
            5 => Problem::TableFull,
            _ => return None,
        })
    }
}

impl core::fmt::Display for Problem {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Problem::NonFinite => "not a finite number",
            Problem::OutOfRange => "out of range",
            Problem::UnknownCode => "unknown code",
            Problem::Invalid => "invalid",
            Problem::TableFull => "table full",
        })
    }
}

impl core::error::Error for Problem {}

/// Why bytes could not be parsed or emitted. Small and `Copy`, like smoltcp's `wire::Error`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error {
    /// The output buffer is too small for what is being emitted.
    BufferTooSmall,
    /// A decoded frame is shorter than a header and a CRC.
    Truncated,
    /// The COBS encoding is malformed (a block runs past the end of the frame, or a 0x00 is
    /// inside it).
    Cobs,
    /// A coded frame (to the firmware) of a length the encoder cannot produce.
    CodedLength,
    /// A coded frame with more wrong bytes than the Reed–Solomon code corrects (more than 8 in
    /// a block).
    Uncorrectable,
    /// The CRC does not match the frame's contents.
    Crc,
    /// The frame exceeds [`MAX_FRAME`] on the wire or [`MAX_RAW`] decoded, or a payload
    /// exceeds [`MAX_PAYLOAD`].
    Oversize,
    /// The header's protocol version is not [`PROTOCOL_VERSION`].
    Version(u8),
    /// The header's message type code is not defined.
    UnknownType(u8),
    /// A defined message type, but not one this receiver accepts (it flows the other way).
    WrongDirection(u8),
    /// The payload is shorter or longer than its type, flags and counts require.
    Length,
    /// A field's value is refused.
    Field {
        /// The field's row in the message's layout table in `docs/protocol.md` (for `Params`,
        /// the parameter index of [`PARAM_NAMES`]).
        index: u8,
        /// What is wrong with it.
        problem: Problem,
    },
}

impl Error {
    /// A [`Error::Field`] error.
    pub const fn field(index: u8, problem: Problem) -> Error {
        Error::Field { index, problem }
    }
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::BufferTooSmall => f.write_str("output buffer too small"),
            Error::Truncated => f.write_str("frame shorter than header and CRC"),
            Error::Cobs => f.write_str("malformed COBS encoding"),
            Error::CodedLength => f.write_str("coded frame of an impossible length"),
            Error::Uncorrectable => f.write_str("more errors than the code corrects"),
            Error::Crc => f.write_str("CRC mismatch"),
            Error::Oversize => f.write_str("frame or payload too long"),
            Error::Version(v) => write!(f, "unsupported protocol version {v}"),
            Error::UnknownType(t) => write!(f, "unknown message type 0x{t:02x}"),
            Error::WrongDirection(t) => write!(f, "message type 0x{t:02x} not accepted here"),
            Error::Length => f.write_str("payload length wrong for its message type"),
            Error::Field { index, problem } => write!(f, "field {index}: {problem}"),
        }
    }
}

/// So host code can use `?` into `Box<dyn Error>` and friends.
impl core::error::Error for Error {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capacities_are_as_documented() {
        assert_eq!(MAX_BINS, 512);
        assert_eq!(MAX_CONTACTS, 8);
        // Contacts: 9-byte head + 8 × (id 2, kind 1, octagon 66, velocity 8, confidence 4).
        assert_eq!(MAX_PAYLOAD, 9 + 8 * 81);
        assert_eq!(MAX_RAW, 663);
        // 663 raw bytes: one code byte, two more for the 254-byte blocks, one delimiter.
        assert_eq!(MAX_COBS_FRAME, 667);
        // 663 raw bytes: three blocks of 16 parity bytes, three chunk keys, one delimiter.
        assert_eq!(MAX_CODEWORD, 711);
        assert_eq!(MAX_CODED_FRAME, 715);
        assert_eq!(MAX_FRAME, 715);
    }

    #[test]
    fn problem_codes_round_trip_and_display() {
        for code in 0..=255u8 {
            if let Some(p) = Problem::from_code(code) {
                assert_eq!(p.code(), code);
            } else {
                assert!(code == 0 || code > 5);
            }
        }
        extern crate std;
        use std::string::ToString;
        assert_eq!(
            Error::field(3, Problem::NonFinite).to_string(),
            "field 3: not a finite number"
        );
        assert_eq!(
            Error::UnknownType(0x7f).to_string(),
            "unknown message type 0x7f"
        );
    }
}
