//! Frames: header, payload and CRC, coded (to the firmware) or COBS-encoded (to the host), and
//! ended by 0x00.
//!
//! ```text
//! decoded ("raw") frame:  version u8 | type u8 | seq u16 LE | payload … | CRC-16 LE
//!                         └──────────── CRC covers these ──────────────┘
//! on the wire, to the firmware:  zero-substitute(whiten(raw frame | RS parity)) | 0x00
//! on the wire, to the host:      COBS(raw frame) | 0x00
//! ```
//!
//! Frames to the firmware carry Reed–Solomon parity ([`super::coded`]): they are the long and
//! frequent ones (sonar scanlines, 330 bytes, 22 a second), and a receiver that corrects costs
//! the firmware's background a few tens of thousands of instructions a frame. Frames to the
//! host stay COBS: the firmware sends them from its periodic task, whose budget does not pay
//! for encoding parity, and a lost `Command` or `Telemetry` is replaced by the next period's.
//!
//! The sequence number counts frames per sender and direction, wrapping at 2¹⁶; receivers use
//! it to see gaps and to match replies to requests, never to reject a frame.

use super::cobs;
use super::coded;
use super::crc::Crc16;
use super::{Error, CRC_LEN, DELIMITER, HEADER_LEN, MAX_PAYLOAD, PROTOCOL_VERSION};

/// Which way a message flows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Direction {
    /// Host to firmware (message type codes 0x01..=0x7F).
    ToFirmware,
    /// Firmware to host (message type codes 0x81..=0xFF).
    ToHost,
}

/// The message types. The top bit of the code is the direction: clear for host → firmware,
/// set for firmware → host.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum MessageType {
    /// Navigation state ([`NavRepr`](super::NavRepr)).
    Nav = 0x01,
    /// One sonar ping ([`Scanline`](crate::sonar::Scanline)).
    Scanline = 0x02,
    /// Pre-extracted contacts ([`ContactsRepr`](super::ContactsRepr)).
    Contacts = 0x03,
    /// The mission ([`Mission`](crate::planner::Mission)).
    Mission = 0x04,
    /// A charted obstacle ([`ChartObstacleRepr`](super::ChartObstacleRepr)).
    ChartObstacle = 0x05,
    /// Remove charted obstacles ([`ChartClearRepr`](super::ChartClearRepr)).
    ChartClear = 0x06,
    /// The planner's parameters ([`Params`](crate::params::Params)).
    Params = 0x07,
    /// Lockstep time advance ([`TickRepr`](super::TickRepr)).
    Tick = 0x08,
    /// Opens a waypoint upload ([`MissionCountRepr`](super::MissionCountRepr)).
    MissionCount = 0x09,
    /// One waypoint of an upload ([`MissionItemRepr`](super::MissionItemRepr)).
    MissionItem = 0x0A,
    /// A lawnmower survey ([`SurveyRepr`](super::SurveyRepr)).
    Survey = 0x0B,
    /// The planner's output ([`CommandRepr`](super::CommandRepr)).
    Command = 0x81,
    /// Health and counters ([`TelemetryRepr`](super::TelemetryRepr)).
    Telemetry = 0x82,
    /// Accepted or rejected, for a Params, Mission or chart message
    /// ([`ReplyRepr`](super::ReplyRepr)).
    Reply = 0x83,
    /// A diagnostic text line ([`LogRepr`](super::LogRepr)).
    Log = 0x84,
    /// A chunk of the firmware's evidence map ([`BeliefRepr`](super::BeliefRepr)).
    Belief = 0x85,
}

impl MessageType {
    /// Every message type, in code order.
    pub const ALL: [MessageType; 16] = [
        MessageType::Nav,
        MessageType::Scanline,
        MessageType::Contacts,
        MessageType::Mission,
        MessageType::ChartObstacle,
        MessageType::ChartClear,
        MessageType::Params,
        MessageType::Tick,
        MessageType::MissionCount,
        MessageType::MissionItem,
        MessageType::Survey,
        MessageType::Command,
        MessageType::Telemetry,
        MessageType::Reply,
        MessageType::Log,
        MessageType::Belief,
    ];

    /// Its wire code.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// The type with wire code `code`, if any.
    pub const fn from_code(code: u8) -> Option<MessageType> {
        Some(match code {
            0x01 => MessageType::Nav,
            0x02 => MessageType::Scanline,
            0x03 => MessageType::Contacts,
            0x04 => MessageType::Mission,
            0x05 => MessageType::ChartObstacle,
            0x06 => MessageType::ChartClear,
            0x07 => MessageType::Params,
            0x08 => MessageType::Tick,
            0x09 => MessageType::MissionCount,
            0x0A => MessageType::MissionItem,
            0x0B => MessageType::Survey,
            0x81 => MessageType::Command,
            0x82 => MessageType::Telemetry,
            0x83 => MessageType::Reply,
            0x84 => MessageType::Log,
            0x85 => MessageType::Belief,
            _ => return None,
        })
    }

    /// Which way it flows.
    pub const fn direction(self) -> Direction {
        if self.code() & 0x80 == 0 {
            Direction::ToFirmware
        } else {
            Direction::ToHost
        }
    }
}

/// The frame header, after the version byte has been checked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Header {
    /// What the payload is.
    pub msg_type: MessageType,
    /// The sender's frame counter, wrapping.
    pub seq: u16,
}

impl Header {
    /// Parses the first [`HEADER_LEN`] bytes: [`Error::Truncated`] if fewer,
    /// [`Error::Version`] for another protocol version, [`Error::UnknownType`] for an undefined
    /// type code.
    pub fn parse(bytes: &[u8]) -> Result<Header, Error> {
        let Some(&[version, code, s0, s1]) = bytes.first_chunk::<HEADER_LEN>() else {
            return Err(Error::Truncated);
        };
        if version != PROTOCOL_VERSION {
            return Err(Error::Version(version));
        }
        let msg_type = MessageType::from_code(code).ok_or(Error::UnknownType(code))?;
        Ok(Header {
            msg_type,
            seq: u16::from_le_bytes([s0, s1]),
        })
    }

    /// Writes the header (with [`PROTOCOL_VERSION`]) into the first [`HEADER_LEN`] bytes.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        let dst = out
            .first_chunk_mut::<HEADER_LEN>()
            .ok_or(Error::BufferTooSmall)?;
        let [s0, s1] = self.seq.to_le_bytes();
        *dst = [PROTOCOL_VERSION, self.msg_type.code(), s0, s1];
        Ok(HEADER_LEN)
    }
}

/// The size of a transmit buffer that [`encode_frame`] can always fill with a payload of
/// `payload_len` bytes, either way (the encoded frame itself may be a few bytes shorter). For
/// any message, [`MAX_FRAME`](super::MAX_FRAME) is enough.
pub const fn frame_buffer_len(payload_len: usize) -> usize {
    let n = coded::codeword_len(HEADER_LEN + payload_len + CRC_LEN);
    coded::wire_len(n) + 2
}

/// Writes a complete frame — coded (a message type to the firmware) or COBS (to the host) —
/// into `out` and returns its length, delimiter included. `payload` writes the payload into the
/// buffer it is given and returns the number of bytes written (e.g. `|buf| repr.emit(buf)`).
///
/// Works within `out` alone: the raw frame is assembled a few bytes in and encoded towards the
/// front, so no scratch buffer is needed. `out` should be at least
/// [`frame_buffer_len`]`(payload_len)` bytes ([`MAX_FRAME`](super::MAX_FRAME) fits every
/// message); a payload longer than [`MAX_PAYLOAD`] is refused with [`Error::Oversize`], since
/// no receiver would accept it.
pub fn encode_frame<F>(
    msg_type: MessageType,
    seq: u16,
    payload: F,
    out: &mut [u8],
) -> Result<usize, Error>
where
    F: FnOnce(&mut [u8]) -> Result<usize, Error>,
{
    match msg_type.direction() {
        Direction::ToFirmware => encode_with(msg_type, seq, payload, out, coded::encode_in_place),
        Direction::ToHost => encode_with(msg_type, seq, payload, out, cobs::encode_in_place),
    }
}

/// [`encode_frame`] for the firmware, which sends only frames to the host: COBS alone, so the
/// image carries no encoder of coded frames; a message type to the firmware is refused with
/// [`Error::WrongDirection`].
pub fn encode_frame_to_host<F>(
    msg_type: MessageType,
    seq: u16,
    payload: F,
    out: &mut [u8],
) -> Result<usize, Error>
where
    F: FnOnce(&mut [u8]) -> Result<usize, Error>,
{
    if msg_type.direction() != Direction::ToHost {
        return Err(Error::WrongDirection(msg_type.code()));
    }
    encode_with(msg_type, seq, payload, out, cobs::encode_in_place)
}

/// The frame's raw bytes assembled at `out[start ..]` and encoded to the front by `encode`
/// (`(buf, start, raw_len) -> wire length`), then the delimiter.
fn encode_with<F>(
    msg_type: MessageType,
    seq: u16,
    payload: F,
    out: &mut [u8],
    encode: fn(&mut [u8], usize, usize) -> Result<usize, Error>,
) -> Result<usize, Error>
where
    F: FnOnce(&mut [u8]) -> Result<usize, Error>,
{
    // Either encoding can run ahead of its input by 1 + ⌊n/254⌋ bytes: leave that gap in front.
    let start = 1 + out.len() / 254;
    let region = out.get_mut(start..).ok_or(Error::BufferTooSmall)?;
    let (head, rest) = region
        .split_at_mut_checked(HEADER_LEN)
        .ok_or(Error::BufferTooSmall)?;
    Header { msg_type, seq }.emit(head)?;
    let n = payload(rest)?;
    if n > MAX_PAYLOAD {
        return Err(Error::Oversize);
    }
    let covered = HEADER_LEN + n;
    let crc = Crc16::new()
        .update(region.get(..covered).ok_or(Error::BufferTooSmall)?)
        .value();
    let crc_dst = region
        .get_mut(covered..)
        .and_then(|r| r.first_chunk_mut::<CRC_LEN>())
        .ok_or(Error::BufferTooSmall)?;
    *crc_dst = crc.to_le_bytes();
    let encoded = encode(out, start, covered + CRC_LEN)?;
    *out.get_mut(encoded).ok_or(Error::BufferTooSmall)? = DELIMITER;
    Ok(encoded + 1)
}

/// Checks a decoded frame (header ‖ payload ‖ CRC, no COBS, no delimiter) and splits it.
///
/// Checks in this order, so that line noise counts as a CRC error rather than as an unknown
/// version or type: length ([`Error::Truncated`]), CRC ([`Error::Crc`]), version
/// ([`Error::Version`]), type ([`Error::UnknownType`]).
pub fn split_frame(raw: &[u8]) -> Result<(Header, &[u8]), Error> {
    split_body(check_crc(raw)?)
}

/// Checks a decoded frame's length and CRC; its body (header ‖ payload).
pub(crate) fn check_crc(raw: &[u8]) -> Result<&[u8], Error> {
    if raw.len() < HEADER_LEN + CRC_LEN {
        return Err(Error::Truncated);
    }
    let (body, crc) = raw.split_last_chunk::<CRC_LEN>().ok_or(Error::Truncated)?;
    if Crc16::new().update(body).value() != u16::from_le_bytes(*crc) {
        return Err(Error::Crc);
    }
    Ok(body)
}

/// Splits a frame's body whose CRC has been checked into its header (version and type
/// checked) and payload.
pub(crate) fn split_body(body: &[u8]) -> Result<(Header, &[u8]), Error> {
    let header = Header::parse(body)?;
    let payload = body.get(HEADER_LEN..).ok_or(Error::Truncated)?;
    Ok((header, payload))
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::link::MAX_FRAME;
    use std::vec::Vec;

    #[test]
    fn type_codes_round_trip_and_carry_the_direction() {
        for t in MessageType::ALL {
            assert_eq!(MessageType::from_code(t.code()), Some(t));
            let to_fw = (0x01..=0x7F).contains(&t.code());
            assert_eq!(t.direction() == Direction::ToFirmware, to_fw);
        }
        let defined = (0..=255u8)
            .filter(|&c| MessageType::from_code(c).is_some())
            .count();
        assert_eq!(defined, MessageType::ALL.len());
    }

    #[test]
    fn header_bytes() {
        let h = Header {
            msg_type: MessageType::Tick,
            seq: 0x0201,
        };
        let mut b = [0u8; 4];
        assert_eq!(h.emit(&mut b), Ok(4));
        assert_eq!(b, [0x08, 0x08, 0x01, 0x02]);
        assert_eq!(Header::parse(&b), Ok(h));
        assert_eq!(Header::parse(&[7, 8, 0, 0]), Err(Error::Version(7)));
        assert_eq!(
            Header::parse(&[8, 0x42, 0, 0]),
            Err(Error::UnknownType(0x42))
        );
        assert_eq!(Header::parse(&[3, 8, 0]), Err(Error::Truncated));
    }

    /// A Tick frame (the example in docs/protocol.md): raw = 08 08 01 00 | e8 03 00 00 00 00
    /// 00 00 | CRC, the CRC computed independently with Python's `binascii.crc_hqx(raw,
    /// 0xFFFF)` = 0xE4FB, sent LE as fb e4. A Tick flows to the firmware: the wire bytes are its
    /// coded frame, from the protocol's Python reference code (docs/protocol.md §12).
    #[test]
    fn tick_frame_vector() {
        let raw = [
            0x08, 0x08, 0x01, 0x00, 0xe8, 0x03, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xfb, 0xe4,
        ];
        let wire = [
            0xff, 0xf7, 0xe9, 0x1c, 0x9a, 0x05, 0x86, 0x33, 0x24, 0xea, 0x7a, 0xd2, 0x39, 0x8b,
            0x73, 0xd5, 0x90, 0x65, 0x0e, 0xb9, 0x9b, 0x07, 0xe4, 0xb4, 0x3d, 0x62, 0x81, 0xd5,
            0x09, 0x80, 0x28, 0x00,
        ];
        let mut out = [0u8; 40];
        let n = encode_frame(
            MessageType::Tick,
            1,
            |b| {
                let d = b.first_chunk_mut::<8>().ok_or(Error::BufferTooSmall)?;
                *d = 1000u64.to_le_bytes();
                Ok(8)
            },
            &mut out,
        )
        .unwrap();
        assert_eq!(&out[..n], &wire);
        let (h, payload) = split_frame(&raw).unwrap();
        assert_eq!(
            h,
            Header {
                msg_type: MessageType::Tick,
                seq: 1
            }
        );
        assert_eq!(payload, &raw[4..12]);
    }

    /// A Reply, firmware to host, so COBS (docs/protocol.md §11): raw 08 83 01 00 | 04 07 00 00
    /// 00 00 | 22 1f (CRC 0x1F22 from `binascii.crc_hqx`); COBS "08 83 01" + zero → 04 08 83 01;
    /// "04 07" + zero → 03 04 07; three single zeros → 01 01 01; the tail → 03 22 1f.
    #[test]
    fn reply_frame_vector() {
        let wire = [
            0x04, 0x08, 0x83, 0x01, 0x03, 0x04, 0x07, 0x01, 0x01, 0x01, 0x03, 0x22, 0x1f, 0x00,
        ];
        let mut out = [0u8; 32];
        let n = encode_frame(
            MessageType::Reply,
            1,
            |b| {
                let d = b.first_chunk_mut::<6>().ok_or(Error::BufferTooSmall)?;
                *d = [0x04, 0x07, 0, 0, 0, 0];
                Ok(6)
            },
            &mut out,
        )
        .unwrap();
        assert_eq!(&out[..n], &wire);
    }

    #[test]
    fn split_frame_checks_in_order() {
        assert_eq!(split_frame(&[8, 8, 0, 0, 0]), Err(Error::Truncated));
        let mut raw = [
            0x08, 0x08, 0x01, 0x00, 0xe8, 0x03, 0, 0, 0, 0, 0, 0, 0xfb, 0xe4,
        ];
        raw[5] ^= 0x10;
        assert_eq!(split_frame(&raw), Err(Error::Crc));
        // A well-formed frame of version 1 is refused for its version, with a valid CRC.
        let mut v1: Vec<u8> = std::vec![1, 8, 0, 0];
        let crc = crate::link::crc::crc16(&v1);
        v1.extend(crc.to_le_bytes());
        assert_eq!(split_frame(&v1), Err(Error::Version(1)));
        let mut t: Vec<u8> = std::vec![8, 0x55, 0, 0];
        let crc = crate::link::crc::crc16(&t);
        t.extend(crc.to_le_bytes());
        assert_eq!(split_frame(&t), Err(Error::UnknownType(0x55)));
    }

    #[test]
    fn encode_frame_refuses_what_does_not_fit() {
        let mut out = [0u8; 10];
        let r = encode_frame(MessageType::Tick, 0, |b| Ok(b.len().min(8)), &mut out);
        assert_eq!(r, Err(Error::BufferTooSmall));
        let mut big = [0u8; 2 * MAX_FRAME];
        let r = encode_frame(MessageType::Log, 0, |_| Ok(MAX_PAYLOAD + 1), &mut big);
        assert_eq!(r, Err(Error::Oversize));
        // A writer claiming more than it was given is caught too.
        let mut out = [0u8; 20];
        let r = encode_frame(MessageType::Log, 0, |b| Ok(b.len() + 5), &mut out);
        assert_eq!(r, Err(Error::BufferTooSmall));
    }

    #[test]
    fn the_firmwares_encoder_sends_to_the_host_only() {
        let mut a = [0u8; MAX_FRAME];
        let mut b = [0u8; MAX_FRAME];
        let payload = |buf: &mut [u8]| {
            buf.get_mut(..3)
                .ok_or(Error::BufferTooSmall)?
                .copy_from_slice(&[1, 0, 2]);
            Ok(3)
        };
        let n = encode_frame(MessageType::Log, 5, payload, &mut a).unwrap();
        assert_eq!(
            encode_frame_to_host(MessageType::Log, 5, payload, &mut b),
            Ok(n)
        );
        assert_eq!(a[..n], b[..n]);
        assert_eq!(
            encode_frame_to_host(MessageType::Tick, 5, payload, &mut b),
            Err(Error::WrongDirection(0x08))
        );
    }

    #[test]
    fn max_payload_fits_max_frame_and_frame_buffer_len() {
        for n in [0, 1, 249, 250, 251, 252, 500, 505, 506, MAX_PAYLOAD] {
            for fill in [0x00u8, 0x5a] {
                let mut out = std::vec![0u8; frame_buffer_len(n)];
                let len = encode_frame(
                    MessageType::Log,
                    7,
                    |b| {
                        b.get_mut(..n).ok_or(Error::BufferTooSmall)?.fill(fill);
                        Ok(n)
                    },
                    &mut out,
                )
                .unwrap();
                assert!(len <= MAX_FRAME);
                assert_eq!(out[len - 1], 0);
                assert!(!out[..len - 1].contains(&0));
                let mut enc = out[..len - 1].to_vec();
                let m = cobs::decode_in_place(&mut enc).unwrap();
                let (h, p) = split_frame(&enc[..m]).unwrap();
                assert_eq!(h.seq, 7);
                assert_eq!(p.len(), n);
                assert!(p.iter().all(|&b| b == fill));
            }
        }
        assert!(frame_buffer_len(MAX_PAYLOAD) <= MAX_FRAME + 1);
        let mut out = [0u8; MAX_FRAME];
        let r = encode_frame(
            MessageType::Log,
            0,
            |b| Ok(b.len().min(MAX_PAYLOAD)),
            &mut out,
        );
        assert!(r.is_ok(), "{r:?}");
    }
}
