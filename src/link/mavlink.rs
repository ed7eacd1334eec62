//! MAVLink 2 on a serial line: frames out, and a resyncing stream decoder for frames in.
//!
//! Frame (MAVLink 2, little-endian): `0xFD`, payload length, incompatibility flags,
//! compatibility flags, sequence, system id, component id, 24-bit message id, payload (trailing
//! zeros may be cut), CRC-16/MCRF4XX over everything after `0xFD` and then the message's
//! CRC_EXTRA byte, and 13 signature bytes if incompatibility flag 0x01 is set.
//!
//! The payloads are the `mavlink` crate's (generated from the official `common.xml`: field
//! order, lengths, CRC_EXTRA), used only through the message types this firmware reads or
//! writes (`X_DATA::deser` / `ser` and `MessageData::{ID, EXTRA_CRC, ENCODED_LEN}`). Why not the
//! crate's whole message set and framing: its `MavMessage::parse` over the dialect keeps a
//! reachable panic (measured: the image does not link), its raw frame buffer is 280 bytes of
//! RAM where this decoder holds [`MAX_KEPT`], and its `mav2-message-extensions` feature brings
//! its code generator (std) into a `no_std` build; so the framing is here, and the one
//! extension this firmware sends (`OBSTACLE_DISTANCE`'s body frame) is appended by hand
//! (extensions are outside CRC_EXTRA by the protocol's rule).
//!
//! **The decoder** takes bytes as they come and never waits: it hunts for `0xFD`, reads the
//! header, and then either keeps the payload (a message it knows: [`Known`], at most
//! [`MAX_KEPT`] bytes, the rest only summed) and checks the CRC with that message's CRC_EXTRA,
//! or, for a message it does not know, skips the payload and CRC (which it cannot check).
//! MAVLink 1 frames (`0xFE`) are skipped whole; unknown incompatibility flags drop the header
//! and resync. Everything refused is counted ([`MavCounters`]); nothing is fatal.

use ::mavlink::dialects::common::{
    ATTITUDE_DATA, GPS_GLOBAL_ORIGIN_DATA, HEARTBEAT_DATA, LOCAL_POSITION_NED_DATA,
    MISSION_COUNT_DATA, MISSION_ITEM_INT_DATA,
};
use ::mavlink::MessageData;

/// MAVLink 2 start-of-frame.
pub const STX_V2: u8 = 0xFD;
/// MAVLink 1 start-of-frame (skipped).
pub const STX_V1: u8 = 0xFE;
/// Bytes before the payload (with the start byte).
pub const HEADER_LEN: usize = 10;
/// Largest payload.
pub const MAX_PAYLOAD: usize = 255;
/// Largest frame this firmware sends (no signature).
pub const MAX_FRAME: usize = HEADER_LEN + MAX_PAYLOAD + 2;
/// Payload bytes the decoder keeps of a message it knows (the longest it reads, with
/// extensions, is `MISSION_ITEM_INT`'s 38).
pub const MAX_KEPT: usize = 64;
/// Incompatibility flag: the frame is signed (13 more bytes; this firmware does not check
/// signatures).
pub const INCOMPAT_SIGNED: u8 = 0x01;
const SIGNATURE_LEN: usize = 13;

/// One byte into a CRC-16/MCRF4XX (X.25) sum, as MAVLink's `crc_accumulate`.
pub const fn crc_accumulate(crc: u16, byte: u8) -> u16 {
    let mut tmp = byte ^ (crc as u8);
    tmp ^= tmp << 4;
    let t = tmp as u16;
    (crc >> 8) ^ (t << 8) ^ (t << 3) ^ (t >> 4)
}

/// The CRC of `bytes` from the MAVLink seed.
pub fn crc(bytes: &[u8]) -> u16 {
    bytes.iter().fold(0xFFFF, |c, &b| crc_accumulate(c, b))
}

/// The messages the decoder keeps (with their CRC_EXTRA); the rest are skipped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Known {
    /// HEARTBEAT (0).
    Heartbeat,
    /// ATTITUDE (30).
    Attitude,
    /// LOCAL_POSITION_NED (32).
    LocalPositionNed,
    /// MISSION_COUNT (44).
    MissionCount,
    /// GPS_GLOBAL_ORIGIN (49).
    GpsGlobalOrigin,
    /// MISSION_ITEM_INT (73).
    MissionItemInt,
}

impl Known {
    /// The message with id `id`, if it is one this firmware reads.
    pub const fn of(id: u32) -> Option<Known> {
        Some(match id {
            HEARTBEAT_DATA::ID => Known::Heartbeat,
            ATTITUDE_DATA::ID => Known::Attitude,
            LOCAL_POSITION_NED_DATA::ID => Known::LocalPositionNed,
            MISSION_COUNT_DATA::ID => Known::MissionCount,
            GPS_GLOBAL_ORIGIN_DATA::ID => Known::GpsGlobalOrigin,
            MISSION_ITEM_INT_DATA::ID => Known::MissionItemInt,
            _ => return None,
        })
    }

    /// Its CRC_EXTRA (from the message definition).
    pub const fn crc_extra(self) -> u8 {
        match self {
            Known::Heartbeat => HEARTBEAT_DATA::EXTRA_CRC,
            Known::Attitude => ATTITUDE_DATA::EXTRA_CRC,
            Known::LocalPositionNed => LOCAL_POSITION_NED_DATA::EXTRA_CRC,
            Known::MissionCount => MISSION_COUNT_DATA::EXTRA_CRC,
            Known::GpsGlobalOrigin => GPS_GLOBAL_ORIGIN_DATA::EXTRA_CRC,
            Known::MissionItemInt => MISSION_ITEM_INT_DATA::EXTRA_CRC,
        }
    }
}

/// What the decoder counted. Saturating.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct MavCounters {
    /// Frames of a known message whose CRC matched.
    pub frames: u32,
    /// Frames of a known message dropped for a CRC mismatch.
    pub crc_errors: u32,
    /// Frames of messages this firmware does not read (skipped, unchecked).
    pub ignored: u32,
    /// MAVLink 1 frames (skipped).
    pub v1_frames: u32,
    /// Headers dropped for incompatibility flags this firmware does not know.
    pub unsupported: u32,
    /// Bytes skipped looking for a frame start.
    pub skipped: u32,
    /// Known frames whose payload the bridge refused (a value out of range, not a number, or
    /// an enum value the definitions do not have); counted by the bridge.
    pub refused: u32,
}

fn bump(c: &mut u32) {
    *c = c.saturating_add(1);
}

/// A frame the decoder kept.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frame<'a> {
    /// Sender's system id.
    pub sysid: u8,
    /// Sender's component id.
    pub compid: u8,
    /// Which message.
    pub message: Known,
    /// Its payload as received (trailing zeros may be cut: `deser` zero-extends), at most
    /// [`MAX_KEPT`] bytes.
    pub payload: &'a [u8],
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// Looking for a start byte.
    Hunt,
    /// Reading the 9 header bytes after `0xFD`.
    Header(u8),
    /// Reading the payload: bytes left.
    Payload(u8),
    /// Reading the CRC: bytes read.
    Crc(u8),
    /// Skipping bytes (a signature, a MAVLink 1 frame, an unknown message's payload and CRC).
    Skip(u16),
    /// A MAVLink 1 frame: its length byte comes next.
    V1Len,
}

/// The stream decoder. About 90 bytes.
#[derive(Clone, Debug)]
pub struct MavDecoder {
    state: State,
    header: [u8; HEADER_LEN - 1],
    known: Option<Known>,
    crc: u16,
    got_crc: u16,
    buf: [u8; MAX_KEPT],
    kept: u8,
    counters: MavCounters,
}

impl Default for MavDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl MavDecoder {
    /// A decoder hunting for a frame.
    pub const fn new() -> Self {
        MavDecoder {
            state: State::Hunt,
            header: [0; HEADER_LEN - 1],
            known: None,
            crc: 0xFFFF,
            got_crc: 0,
            buf: [0; MAX_KEPT],
            kept: 0,
            counters: MavCounters {
                frames: 0,
                crc_errors: 0,
                ignored: 0,
                v1_frames: 0,
                unsupported: 0,
                skipped: 0,
                refused: 0,
            },
        }
    }

    /// What it counted.
    pub fn counters(&self) -> &MavCounters {
        &self.counters
    }

    /// Counts a known frame whose payload the caller refused.
    pub fn count_refused(&mut self) {
        bump(&mut self.counters.refused);
    }

    fn header_byte(&self, i: usize) -> u8 {
        self.header.get(i).copied().unwrap_or(0)
    }

    /// Feeds bytes until a frame it keeps is complete: how many bytes it took, and the frame
    /// (its payload borrowed from the decoder until the next call).
    pub fn feed(&mut self, bytes: &[u8]) -> (usize, Option<Frame<'_>>) {
        let mut used = 0;
        let mut done = false;
        for &b in bytes {
            used += 1;
            if self.step(b) {
                done = true;
                break;
            }
        }
        if !done {
            return (used, None);
        }
        let sysid = self.header_byte(4);
        let compid = self.header_byte(5);
        let n = usize::from(self.kept).min(MAX_KEPT);
        let frame = match (self.known, self.buf.get(..n)) {
            (Some(message), Some(payload)) => Some(Frame {
                sysid,
                compid,
                message,
                payload,
            }),
            _ => None,
        };
        (used, frame)
    }

    /// One byte; `true` when a kept frame has just completed with a matching CRC.
    fn step(&mut self, b: u8) -> bool {
        match self.state {
            State::Hunt => match b {
                STX_V2 => {
                    self.state = State::Header(0);
                    self.crc = 0xFFFF;
                }
                STX_V1 => self.state = State::V1Len,
                _ => bump(&mut self.counters.skipped),
            },
            State::V1Len => {
                // seq, sysid, compid, msgid, payload, CRC.
                bump(&mut self.counters.v1_frames);
                self.state = State::Skip(u16::from(b) + 4 + 2);
            }
            State::Header(i) => {
                if let Some(h) = self.header.get_mut(usize::from(i)) {
                    *h = b;
                }
                self.crc = crc_accumulate(self.crc, b);
                let i = i + 1;
                if usize::from(i) < HEADER_LEN - 1 {
                    self.state = State::Header(i);
                    return false;
                }
                let incompat = self.header_byte(1);
                if incompat & !INCOMPAT_SIGNED != 0 {
                    bump(&mut self.counters.unsupported);
                    self.state = State::Hunt;
                    return false;
                }
                let id = u32::from(self.header_byte(6))
                    | u32::from(self.header_byte(7)) << 8
                    | u32::from(self.header_byte(8)) << 16;
                let len = self.header_byte(0);
                self.known = Known::of(id);
                self.kept = 0;
                self.state = match (self.known, len) {
                    (Some(_), 0) => State::Crc(0),
                    (Some(_), n) => State::Payload(n),
                    (None, n) => {
                        bump(&mut self.counters.ignored);
                        State::Skip(u16::from(n) + 2 + self.signature_len())
                    }
                };
            }
            State::Payload(left) => {
                self.crc = crc_accumulate(self.crc, b);
                if let Some(slot) = self.buf.get_mut(usize::from(self.kept)) {
                    *slot = b;
                    self.kept += 1;
                }
                self.state = if left > 1 {
                    State::Payload(left - 1)
                } else {
                    State::Crc(0)
                };
            }
            State::Crc(0) => {
                self.got_crc = u16::from(b);
                self.state = State::Crc(1);
            }
            State::Crc(_) => {
                self.got_crc |= u16::from(b) << 8;
                let extra = self.known.map_or(0, Known::crc_extra);
                let ok = crc_accumulate(self.crc, extra) == self.got_crc;
                let sig = self.signature_len();
                self.state = if sig > 0 {
                    State::Skip(sig)
                } else {
                    State::Hunt
                };
                if ok {
                    bump(&mut self.counters.frames);
                    // A signed frame is handed over now; its signature is skipped after.
                    return true;
                }
                bump(&mut self.counters.crc_errors);
            }
            State::Skip(left) => {
                self.state = if left > 1 {
                    State::Skip(left - 1)
                } else {
                    State::Hunt
                };
            }
        }
        false
    }

    fn signature_len(&self) -> u16 {
        if self.header_byte(1) & INCOMPAT_SIGNED != 0 {
            SIGNATURE_LEN as u16
        } else {
            0
        }
    }
}

/// Writes a MAVLink 2 frame of message `id` (CRC_EXTRA `crc_extra`) with `payload` into `out`
/// from `sysid`/`compid` with sequence `seq`, trailing zeros of the payload cut (the protocol's
/// rule); its length, or `None` if `out` is too short or the payload too long.
pub fn emit_frame(
    seq: u8,
    (sysid, compid): (u8, u8),
    (id, crc_extra): (u32, u8),
    payload: &[u8],
    out: &mut [u8],
) -> Option<usize> {
    let mut len = payload.len().min(MAX_PAYLOAD + 1);
    while len > 1 && payload.get(len - 1) == Some(&0) {
        len -= 1;
    }
    let payload = payload.get(..len)?;
    let len8 = u8::try_from(len).ok()?;
    let [i0, i1, i2, _] = id.to_le_bytes();
    let head = [STX_V2, len8, 0, 0, seq, sysid, compid, i0, i1, i2];
    let total = HEADER_LEN + len + 2;
    let frame = out.get_mut(..total)?;
    let (h, rest) = frame.split_at_mut(HEADER_LEN);
    h.copy_from_slice(&head);
    let (p, c) = rest.split_at_mut(len);
    p.copy_from_slice(payload);
    let sum = head
        .iter()
        .skip(1)
        .chain(payload.iter())
        .fold(0xFFFF, |c, &b| crc_accumulate(c, b));
    c.copy_from_slice(&crc_accumulate(sum, crc_extra).to_le_bytes());
    Some(total)
}

#[cfg(test)]
mod tests {
    use super::*;
    use ::mavlink::dialects::common::{MavModeFlag, MavState, MavType};
    use ::mavlink::MavlinkVersion;
    extern crate std;
    use std::vec::Vec;

    fn heartbeat(seq: u8) -> Vec<u8> {
        let hb = HEARTBEAT_DATA {
            custom_mode: 4,
            mavtype: MavType::MAV_TYPE_SUBMARINE,
            base_mode: MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED,
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
            ..HEARTBEAT_DATA::default()
        };
        let mut p = [0u8; 255];
        let n = hb.ser(MavlinkVersion::V2, &mut p);
        let mut out = [0u8; MAX_FRAME];
        let len = emit_frame(
            seq,
            (1, 1),
            (HEARTBEAT_DATA::ID, HEARTBEAT_DATA::EXTRA_CRC),
            &p[..n],
            &mut out,
        )
        .unwrap();
        out[..len].to_vec()
    }

    #[test]
    fn the_crc_is_mavlinks() {
        // The crate's own CRC (crc-any's MCRF4XX) over the same bytes.
        let bytes = b"\x09\x00\x00\x07\x01\x01\x00\x00\x00abcdefghi";
        assert_eq!(
            crc_accumulate(crc(bytes), 50),
            ::mavlink::calculate_crc(bytes, 50)
        );
    }

    #[test]
    fn a_frame_round_trips_through_noise_and_resyncs() {
        let mut stream = b"\x00\x55noise".to_vec();
        stream.extend(heartbeat(7));
        stream.extend(heartbeat(8));
        let mut d = MavDecoder::new();
        let mut rest = &stream[..];
        let mut got = Vec::new();
        while !rest.is_empty() {
            let (n, f) = d.feed(rest);
            if let Some(f) = f {
                let hb = HEARTBEAT_DATA::deser(MavlinkVersion::V2, f.payload).unwrap();
                got.push((f.sysid, f.compid, f.message, hb.custom_mode));
            }
            rest = &rest[n..];
        }
        assert_eq!(
            got,
            [(1, 1, Known::Heartbeat, 4), (1, 1, Known::Heartbeat, 4)]
        );
        let c = d.counters();
        assert_eq!((c.frames, c.skipped, c.crc_errors), (2, 7, 0));
    }

    #[test]
    fn corruption_unknown_messages_and_v1_are_counted_never_fatal() {
        let mut d = MavDecoder::new();
        let mut bad = heartbeat(1);
        bad[12] ^= 0x10;
        let unknown = {
            let mut out = [0u8; MAX_FRAME];
            let n = emit_frame(2, (1, 1), (24, 24), &[1, 2, 3, 4], &mut out).unwrap();
            out[..n].to_vec()
        };
        let v1 = [STX_V1, 2, 0, 1, 1, 0, 9, 9, 0xAA, 0xBB];
        let mut stream = bad;
        stream.extend(unknown);
        stream.extend(v1);
        stream.extend(heartbeat(3));
        let mut rest = &stream[..];
        let mut frames = 0;
        while !rest.is_empty() {
            let (n, f) = d.feed(rest);
            frames += usize::from(f.is_some());
            rest = &rest[n..];
        }
        let c = *d.counters();
        assert_eq!(frames, 1);
        assert_eq!(
            (c.crc_errors, c.ignored, c.v1_frames, c.frames),
            (1, 1, 1, 1),
            "{c:?}"
        );
    }

    #[test]
    fn trailing_zeros_are_cut_and_restored() {
        let mut out = [0u8; MAX_FRAME];
        let n = emit_frame(0, (1, 191), (0, 50), &[5, 0, 0, 0, 0, 0, 0, 0, 0], &mut out).unwrap();
        assert_eq!(out[1], 1, "payload cut to one byte");
        let mut d = MavDecoder::new();
        let (_, f) = d.feed(&out[..n]);
        let hb = HEARTBEAT_DATA::deser(MavlinkVersion::V2, f.unwrap().payload).unwrap();
        assert_eq!(hb.custom_mode, 5);
    }
}
