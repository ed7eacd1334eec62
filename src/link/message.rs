//! Every message in one enum, and whole frames in and out.
//!
//! ```
//! use vpf::link::{Direction, Message, Payload, TickRepr, MAX_FRAME};
//!
//! // Firmware or host: emit a complete frame into a fixed buffer.
//! let mut tx = [0u8; MAX_FRAME];
//! let n = TickRepr { time_ms: 1000 }.emit_frame(1, &mut tx).unwrap();
//! assert_eq!(tx[n - 1], 0x00);
//!
//! // Whole encoded frame in hand (e.g. read up to a 0x00): decode it in place. A Tick flows
//! // to the firmware, so its frame is coded (its framing is its direction's).
//! let (header, msg) = Message::decode_frame(&mut tx[..n], Direction::ToFirmware).unwrap();
//! assert_eq!(header.seq, 1);
//! assert_eq!(msg, Message::Tick(TickRepr { time_ms: 1000 }));
//! ```
//!
//! For a byte stream use the [`Decoder`](super::Decoder) instead.

use super::belief::{BeliefRepr, BELIEF_MAX_LEN};
use super::cobs;
use super::coded;
use super::control::{
    ChartClearRepr, ChartObstacleRepr, TickRepr, MISSION_LEN_WITH_FORMATION, PARAMS_LEN,
};
use super::frame::{
    encode_frame, encode_frame_to_host, split_frame, Direction, Header, MessageType,
};
use super::mission::{MissionCountRepr, MissionItemRepr, SurveyRepr};
use super::payload::Payload;
use super::report::{CommandRepr, LogRepr, ReplyRepr, TelemetryRepr, COMMAND_LEN, TELEMETRY_LEN};
use super::sensors::{
    ContactsRepr, NavRepr, CONTACTS_HEAD_LEN, MAX_CONTACT_LEN, NAV_LEN_WITH_BODY, SCANLINE_HEAD_LEN,
};
use super::shape::MAX_SHAPE_LEN;
use super::{Error, DELIMITER, MAX_BINS, MAX_CONTACTS, MAX_FRAME, MAX_LOG_LEN, MAX_RAW};
use crate::params::Params;
use crate::types::{Mission, Scanline};

/// Any message, parsed. Variants borrow from the frame they were parsed from.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Message<'a> {
    /// Navigation state (host → firmware).
    Nav(NavRepr),
    /// One sonar ping (host → firmware).
    Scanline(Scanline<'a>),
    /// Pre-extracted contacts (host → firmware).
    Contacts(ContactsRepr<'a>),
    /// The mission (host → firmware).
    Mission(Mission),
    /// A charted obstacle (host → firmware).
    ChartObstacle(ChartObstacleRepr),
    /// Remove charted obstacles (host → firmware).
    ChartClear(ChartClearRepr),
    /// The parameter set (host → firmware).
    Params(Params),
    /// Lockstep time advance (host → firmware).
    Tick(TickRepr),
    /// Opens a waypoint upload (host → firmware).
    MissionCount(MissionCountRepr),
    /// One waypoint of an upload (host → firmware).
    MissionItem(MissionItemRepr),
    /// A lawnmower survey, expanded by the firmware (host → firmware).
    Survey(SurveyRepr),
    /// The planner's output (firmware → host).
    Command(CommandRepr),
    /// Health and counters (firmware → host).
    Telemetry(TelemetryRepr),
    /// Reply to Params, Mission and chart messages (firmware → host).
    Reply(ReplyRepr),
    /// A diagnostic line (firmware → host).
    Log(LogRepr<'a>),
    /// A chunk of the evidence map (firmware → host).
    Belief(BeliefRepr<'a>),
}

/// Applies `$f` to the payload inside any variant.
macro_rules! each {
    ($m:expr, $p:ident => $f:expr) => {
        match $m {
            Message::Nav($p) => $f,
            Message::Scanline($p) => $f,
            Message::Contacts($p) => $f,
            Message::Mission($p) => $f,
            Message::ChartObstacle($p) => $f,
            Message::ChartClear($p) => $f,
            Message::Params($p) => $f,
            Message::Tick($p) => $f,
            Message::MissionCount($p) => $f,
            Message::MissionItem($p) => $f,
            Message::Survey($p) => $f,
            Message::Command($p) => $f,
            Message::Telemetry($p) => $f,
            Message::Reply($p) => $f,
            Message::Log($p) => $f,
            Message::Belief($p) => $f,
        }
    };
}

fn type_of<'a, P: Payload<'a>>(_: &P) -> MessageType {
    P::TYPE
}

impl<'a> Message<'a> {
    /// Its wire type.
    pub fn message_type(&self) -> MessageType {
        each!(self, p => type_of(p))
    }

    /// Parses the payload of a message of type `msg_type`. Built for the target, the firmware
    /// parses only messages to the firmware: one to the host is [`Error::WrongDirection`], as
    /// its [`Decoder`](super::Decoder) refuses it before parsing anyway, and the five parsers
    /// it never runs stay out of flash.
    pub fn parse(msg_type: MessageType, payload: &'a [u8]) -> Result<Self, Error> {
        Ok(match msg_type {
            MessageType::Nav => Message::Nav(Payload::parse(payload)?),
            MessageType::Scanline => Message::Scanline(Payload::parse(payload)?),
            MessageType::Contacts => Message::Contacts(Payload::parse(payload)?),
            MessageType::Mission => Message::Mission(Payload::parse(payload)?),
            MessageType::ChartObstacle => Message::ChartObstacle(Payload::parse(payload)?),
            MessageType::ChartClear => Message::ChartClear(Payload::parse(payload)?),
            MessageType::Params => Message::Params(Payload::parse(payload)?),
            MessageType::Tick => Message::Tick(Payload::parse(payload)?),
            MessageType::MissionCount => Message::MissionCount(Payload::parse(payload)?),
            MessageType::MissionItem => Message::MissionItem(Payload::parse(payload)?),
            MessageType::Survey => Message::Survey(Payload::parse(payload)?),
            #[cfg(target_os = "none")]
            MessageType::Command
            | MessageType::Telemetry
            | MessageType::Reply
            | MessageType::Log
            | MessageType::Belief => return Err(Error::WrongDirection(msg_type.code())),
            #[cfg(not(target_os = "none"))]
            MessageType::Command => Message::Command(Payload::parse(payload)?),
            #[cfg(not(target_os = "none"))]
            MessageType::Telemetry => Message::Telemetry(Payload::parse(payload)?),
            #[cfg(not(target_os = "none"))]
            MessageType::Reply => Message::Reply(Payload::parse(payload)?),
            #[cfg(not(target_os = "none"))]
            MessageType::Log => Message::Log(Payload::parse(payload)?),
            #[cfg(not(target_os = "none"))]
            MessageType::Belief => Message::Belief(Payload::parse(payload)?),
        })
    }

    /// The number of payload bytes [`Message::emit`] writes.
    pub fn payload_len(&self) -> usize {
        each!(self, p => p.payload_len())
    }

    /// Validates and writes the payload; returns the bytes written.
    pub fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        each!(self, p => p.emit(out))
    }

    /// Writes a complete frame with sequence number `seq` into `out` (at least
    /// [`MAX_FRAME`] bytes always suffice); returns its length, delimiter included.
    pub fn emit_frame(&self, seq: u16, out: &mut [u8]) -> Result<usize, Error> {
        encode_frame(self.message_type(), seq, |buf| self.emit(buf), out)
    }

    /// [`Message::emit_frame`] for a sender of frames to the host only (the firmware): COBS
    /// alone, [`Error::WrongDirection`] for a message to the firmware.
    pub fn emit_frame_to_host(&self, seq: u16, out: &mut [u8]) -> Result<usize, Error> {
        encode_frame_to_host(self.message_type(), seq, |buf| self.emit(buf), out)
    }

    /// Parses a decoded frame: header ‖ payload ‖ CRC, COBS already removed (what the
    /// [`Decoder`](super::Decoder) buffers). See [`split_frame`] for the order of checks.
    pub fn parse_frame(raw: &'a [u8]) -> Result<(Header, Message<'a>), Error> {
        let (header, payload) = split_frame(raw)?;
        Ok((header, Message::parse(header.msg_type, payload)?))
    }

    /// Decodes one encoded frame in place and parses it: `encoded` is the frame's bytes, with
    /// or without the final 0x00, flowing `direction` (coded to the firmware, COBS to the host;
    /// a coded frame's errors are corrected). The buffer is overwritten by the decoded frame,
    /// which the message borrows.
    pub fn decode_frame(
        encoded: &'a mut [u8],
        direction: Direction,
    ) -> Result<(Header, Message<'a>), Error> {
        if encoded.len() > MAX_FRAME {
            return Err(Error::Oversize);
        }
        let body_len = match encoded.last() {
            Some(&DELIMITER) => encoded.len().saturating_sub(1),
            _ => encoded.len(),
        };
        let body = encoded.get_mut(..body_len).ok_or(Error::Cobs)?;
        let n = match direction {
            Direction::ToFirmware => coded::decode_in_place(body)?.0,
            Direction::ToHost => cobs::decode_in_place(body)?,
        };
        if n > MAX_RAW {
            return Err(Error::Oversize);
        }
        let body: &'a [u8] = body;
        Message::parse_frame(body.get(..n).ok_or(Error::Cobs)?)
    }
}

macro_rules! from_payload {
    ($($variant:ident($ty:ty)),* $(,)?) => {$(
        impl<'a> From<$ty> for Message<'a> {
            fn from(p: $ty) -> Self {
                Message::$variant(p)
            }
        }
    )*};
}

from_payload!(
    Nav(NavRepr),
    Scanline(Scanline<'a>),
    Contacts(ContactsRepr<'a>),
    Mission(Mission),
    ChartObstacle(ChartObstacleRepr),
    ChartClear(ChartClearRepr),
    Params(Params),
    Tick(TickRepr),
    MissionCount(MissionCountRepr),
    MissionItem(MissionItemRepr),
    Survey(SurveyRepr),
    Command(CommandRepr),
    Telemetry(TelemetryRepr),
    Reply(ReplyRepr),
    Log(LogRepr<'a>),
    Belief(BeliefRepr<'a>),
);

const fn max(a: usize, b: usize) -> usize {
    if a > b {
        a
    } else {
        b
    }
}

/// The longest payload of any message type (see [`MAX_PAYLOAD`](super::MAX_PAYLOAD)).
pub const fn max_payload_len() -> usize {
    let sensors = max(
        NAV_LEN_WITH_BODY,
        max(
            SCANLINE_HEAD_LEN + MAX_BINS,
            CONTACTS_HEAD_LEN + MAX_CONTACTS * MAX_CONTACT_LEN,
        ),
    );
    let control = max(
        max(MISSION_LEN_WITH_FORMATION, 6 + MAX_SHAPE_LEN),
        max(3, max(PARAMS_LEN, 8)),
    );
    let reports = max(
        max(COMMAND_LEN, TELEMETRY_LEN),
        max(6, max(1 + MAX_LOG_LEN, BELIEF_MAX_LEN)),
    );
    max(sensors, max(control, reports))
}

#[cfg(test)]
pub(crate) mod tests {
    extern crate std;
    use super::*;
    use crate::link::control::tests::{arb_chart, arb_mission, arb_params};
    use crate::link::report::tests::{arb_command, arb_log, arb_reply, arb_telemetry};
    use crate::link::report::LogLevel;
    use crate::link::sensors::tests::{arb_contact, arb_nav, arb_scanline};
    use crate::link::sensors::{Contact, ContactList};
    use crate::link::{ChartClearRepr, MAX_PAYLOAD};
    use crate::math::Vec2;
    use proptest::prelude::*;
    use std::string::String;
    use std::vec;
    use std::vec::Vec;

    /// The worked example of docs/protocol.md: Mission {goal (10, −5), no formation}, seq 7.
    /// CRC from Python's binascii.crc_hqx(raw, 0xFFFF) = 0xEDB1, and the coded frame from the
    /// protocol's Python reference code (its Reed–Solomon parity checked against `reedsolo`),
    /// both independent of this crate.
    #[test]
    fn worked_example_mission_frame() {
        let raw = [
            0x08, 0x04, 0x07, 0x00, // version 8, Mission, seq 7
            0x00, 0x00, 0x20, 0x41, // goal_x 10.0
            0x00, 0x00, 0xa0, 0xc0, // goal_y -5.0
            0x00, // flags: no formation
            0xb1, 0xed, // CRC-16 LE
        ];
        let wire = [
            0xff, // the chunk's key: 0xff does not occur in the whitened codeword
            // raw frame and parity c1 a4 17 4a ac 50 8e d0 8f af af 26 4c 2c 01 04, XOR PN9;
            // its one 0x00 (codeword byte 23, parity 0x8f XOR PN9 0x8f) is sent as the key
            0xf7, 0xe5, 0x1a, 0x9a, 0xed, 0x85, 0x13, 0x65, 0xea, 0x7a, 0x72, 0xf9, 0x70, 0x26,
            0xba, 0xcb, 0xf0, 0x6a, 0x67, 0x74, 0x3d, 0x83, 0x6a, 0xff, 0xc8, 0xf6, 0xe1, 0xee,
            0x93, 0x35, 0xce, //
            0x00, // delimiter
        ];
        let m = Message::Mission(Mission {
            goal: Vec2::new(10.0, -5.0),
            formation: None,
        });
        let mut out = [0u8; MAX_FRAME];
        let n = m.emit_frame(7, &mut out).unwrap();
        assert_eq!(&out[..n], &wire);
        let (h, back) = Message::parse_frame(&raw).unwrap();
        assert_eq!((h.msg_type, h.seq), (MessageType::Mission, 7));
        assert_eq!(back, m);
        let mut copy = wire;
        assert_eq!(
            Message::decode_frame(&mut copy, Direction::ToFirmware)
                .unwrap()
                .1,
            m
        );
        let mut no_delim = wire;
        assert_eq!(
            Message::decode_frame(&mut no_delim[..32], Direction::ToFirmware)
                .unwrap()
                .1,
            m
        );
        // Eight wrong bytes, corrected.
        let mut damaged = wire;
        for i in [1, 4, 9, 13, 17, 22, 26, 31] {
            damaged[i] ^= 0x21;
        }
        assert_eq!(
            Message::decode_frame(&mut damaged, Direction::ToFirmware)
                .unwrap()
                .1,
            m
        );
    }

    #[test]
    fn frame_level_refusals() {
        // Valid frame, wrong payload length for its type: Length, not a framing error.
        let mut out = [0u8; MAX_FRAME];
        let n = encode_frame(
            MessageType::Tick,
            0,
            |b| {
                b[..7].fill(1);
                Ok(7)
            },
            &mut out,
        )
        .unwrap();
        let to_fw = Direction::ToFirmware;
        assert_eq!(
            Message::decode_frame(&mut out[..n], to_fw),
            Err(Error::Length)
        );
        let mut garbage = [0x05, 1, 2, 0];
        assert_eq!(
            Message::decode_frame(&mut garbage, Direction::ToHost),
            Err(Error::Cobs)
        );
        let mut garbage = [0x05, 1, 2, 0];
        assert_eq!(
            Message::decode_frame(&mut garbage, to_fw),
            Err(Error::CodedLength)
        );
        let mut long = [1u8; MAX_FRAME + 1];
        assert_eq!(
            Message::decode_frame(&mut long, to_fw),
            Err(Error::Oversize)
        );
        assert_eq!(Message::parse_frame(&[1, 2, 3]), Err(Error::Truncated));
    }

    #[test]
    fn max_payload_is_the_largest_contacts_message() {
        let octagon: Vec<Vec2> = (0..8)
            .map(|k| Vec2::from_angle(k as f32 * core::f32::consts::TAU / 8.0) * 10.0)
            .collect();
        let c = Contact {
            id: 1,
            kind: crate::link::ContactKind::Obstacle,
            shape: crate::field::Shape::polygon(&octagon).unwrap(),
            velocity: Vec2::ZERO,
            confidence: 1.0,
        };
        let cs = [c; MAX_CONTACTS];
        let m = Message::Contacts(ContactsRepr {
            time_ms: 0,
            contacts: ContactList::new(&cs),
        });
        assert_eq!(m.payload_len(), MAX_PAYLOAD);
        let mut out = [0u8; MAX_FRAME];
        let n = m.emit_frame(0xffff, &mut out).unwrap();
        assert!(n <= MAX_FRAME);
        let (_, back) = Message::decode_frame(&mut out[..n], Direction::ToFirmware).unwrap();
        assert_eq!(back, m);
        // A full scanline fits too.
        let bins = [0u8; MAX_BINS];
        let s = Message::Scanline(Scanline {
            time_ms: 1,
            bearing_rad: 0.0,
            step_rad: 0.01,
            range_m: 50.0,
            bins: &bins,
        });
        let n = s.emit_frame(1, &mut out).unwrap();
        assert_eq!(
            Message::decode_frame(&mut out[..n], Direction::ToFirmware)
                .unwrap()
                .1,
            s
        );
    }

    #[test]
    fn messages_are_small_enough_for_an_interrupt_stack() {
        // A Message is passed by value on the firmware's stack: keep it near a Shape's size. The
        // largest is a Telemetry (152 B with its mission and Ping360 blocks, the two
        // forward-error-correction counters and the current); the stack's high-water mark is
        // measured by the self-test (`tests/qemu.rs`).
        assert!(core::mem::size_of::<Message<'_>>() <= 152);
        // The decoder holds a coded frame's codeword: the raw frame and 48 parity bytes.
        assert!(core::mem::size_of::<crate::link::Decoder>() <= crate::link::MAX_CODEWORD + 72);
    }

    #[test]
    fn dispatch_matches_the_types() {
        let mut out = [0u8; MAX_FRAME];
        let msgs = [
            Message::Tick(TickRepr { time_ms: 5 }),
            Message::ChartClear(ChartClearRepr::All),
            Message::Params(Params::default()),
            Message::Log(LogRepr {
                level: LogLevel::Warn,
                text: "x",
            }),
        ];
        for m in msgs {
            let n = m.emit(&mut out).unwrap();
            assert_eq!(n, m.payload_len());
            assert_eq!(Message::parse(m.message_type(), &out[..n]), Ok(m));
            // The same payload read as another type is refused, not misread.
            let other = if m.message_type() == MessageType::Tick {
                MessageType::Params
            } else {
                MessageType::Tick
            };
            assert!(Message::parse(other, &out[..n]).is_err());
        }
        assert_eq!(
            Message::from(TickRepr { time_ms: 1 }),
            Message::Tick(TickRepr { time_ms: 1 })
        );
    }

    /// OwnedMessage material for any message, so the strategy can outlive the borrow.
    #[derive(Clone, Debug)]
    pub(crate) enum OwnedMessage {
        Nav(NavRepr),
        Scanline((u64, f32, f32, f32, Vec<u8>)),
        Contacts(u64, Vec<Contact>),
        Mission(Mission),
        Chart(ChartObstacleRepr),
        Clear(ChartClearRepr),
        Params(Params),
        Tick(TickRepr),
        Command(CommandRepr),
        Telemetry(TelemetryRepr),
        Reply(ReplyRepr),
        Log((u8, String)),
        Belief(crate::link::belief::tests::OwnedBelief),
    }

    impl OwnedMessage {
        pub(crate) fn message(&self) -> Message<'_> {
            match self {
                OwnedMessage::Nav(n) => Message::Nav(*n),
                OwnedMessage::Scanline((t, b, s, r, bins)) => Message::Scanline(Scanline {
                    time_ms: *t,
                    bearing_rad: *b,
                    step_rad: *s,
                    range_m: *r,
                    bins,
                }),
                OwnedMessage::Contacts(t, cs) => Message::Contacts(ContactsRepr {
                    time_ms: *t,
                    contacts: ContactList::new(cs),
                }),
                OwnedMessage::Mission(m) => Message::Mission(*m),
                OwnedMessage::Chart(c) => Message::ChartObstacle(*c),
                OwnedMessage::Clear(c) => Message::ChartClear(*c),
                OwnedMessage::Params(p) => Message::Params(*p),
                OwnedMessage::Tick(t) => Message::Tick(*t),
                OwnedMessage::Command(c) => Message::Command(*c),
                OwnedMessage::Telemetry(t) => Message::Telemetry(*t),
                OwnedMessage::Reply(r) => Message::Reply(*r),
                OwnedMessage::Log((l, text)) => Message::Log(LogRepr {
                    level: LogLevel::from_code(*l).unwrap(),
                    text,
                }),
                OwnedMessage::Belief(b) => Message::Belief(crate::link::belief::tests::belief(b)),
            }
        }
    }

    pub(crate) fn arb_owned() -> impl Strategy<Value = OwnedMessage> {
        prop_oneof![
            arb_nav().prop_map(OwnedMessage::Nav),
            arb_scanline().prop_map(OwnedMessage::Scanline),
            (
                any::<u64>(),
                proptest::collection::vec(arb_contact(), 0..=MAX_CONTACTS)
            )
                .prop_map(|(t, c)| OwnedMessage::Contacts(t, c)),
            arb_mission().prop_map(OwnedMessage::Mission),
            arb_chart().prop_map(OwnedMessage::Chart),
            proptest::option::of(any::<u16>()).prop_map(|id| OwnedMessage::Clear(match id {
                Some(id) => ChartClearRepr::One(id),
                None => ChartClearRepr::All,
            })),
            arb_params().prop_map(OwnedMessage::Params),
            any::<u64>().prop_map(|t| OwnedMessage::Tick(TickRepr { time_ms: t })),
            arb_command().prop_map(OwnedMessage::Command),
            arb_telemetry().prop_map(OwnedMessage::Telemetry),
            arb_reply().prop_map(OwnedMessage::Reply),
            arb_log().prop_map(OwnedMessage::Log),
            crate::link::belief::tests::arb_belief().prop_map(OwnedMessage::Belief),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

        /// encode → decode is the identity, through whole frames.
        #[test]
        fn frames_round_trip(o in arb_owned(), seq in any::<u16>()) {
            let m = o.message();
            let mut out = [0u8; MAX_FRAME];
            let n = m.emit_frame(seq, &mut out).unwrap();
            prop_assert!(n <= MAX_FRAME);
            prop_assert!(m.payload_len() <= MAX_PAYLOAD);
            prop_assert_eq!(out[n - 1], 0);
            prop_assert!(!out[..n - 1].contains(&0));
            let dir = m.message_type().direction();
            let (h, back) = Message::decode_frame(&mut out[..n], dir).unwrap();
            prop_assert_eq!(h.seq, seq);
            prop_assert_eq!(h.msg_type, m.message_type());
            prop_assert_eq!(back, m);
        }

        /// Any corrupted byte of a frame is caught by the CRC (a single-byte error is a burst
        /// of at most 8 bits, which CRC-16 always detects), whichever field it hits.
        #[test]
        fn corruption_is_detected(o in arb_owned(), pos in any::<prop::sample::Index>(), flip in 1u8..=255) {
            let m = o.message();
            let mut out = [0u8; MAX_FRAME];
            let n = m.emit_frame(1, &mut out).unwrap();
            let raw_len = match m.message_type().direction() {
                Direction::ToFirmware => coded::decode_in_place(&mut out[..n - 1]).unwrap().0,
                Direction::ToHost => cobs::decode_in_place(&mut out[..n - 1]).unwrap(),
            };
            let raw = &mut out[..raw_len];
            let i = pos.index(raw_len);
            raw[i] ^= flip;
            prop_assert_eq!(Message::parse_frame(raw), Err(Error::Crc));
        }
    }
}
