//! The stream decoder: bytes from the UART in, parsed messages out, in the style of postcard's
//! `CobsAccumulator`, over one fixed buffer of [`MAX_RAW`] bytes.
//!
//! **Rules** (also in `docs/protocol.md`):
//! - Every 0x00 ends a frame and starts the next: the decoder is back in sync after any
//!   garbage as soon as it sees a 0x00, so at most the frame the garbage ran into is lost.
//!   Senders should begin with a 0x00 so that even that one survives.
//! - Empty frames (0x00 0x00) are ignored and not counted: a sender may flush with extra 0x00s.
//! - COBS is undone byte by byte; the encoded length is checked before each byte is taken, so
//!   a frame longer than [`MAX_FRAME`] (or one decoding to more than [`MAX_RAW`] bytes) is
//!   reported once, as [`Outcome::OverFull`], as soon as the limit is passed, and the rest of
//!   it up to the next 0x00 is skipped. Nothing past the buffer is ever written.
//! - At the 0x00, a frame is checked in this order: COBS complete, at least header + CRC,
//!   CRC, version, type (and direction, if the decoder is given one), payload. The first
//!   failure is returned as [`Outcome::Error`] and counted in exactly one [`RxCounters`]
//!   field.
//!
//! No input makes it panic, allocate or loop: each byte costs O(1), except the 0x00 that ends
//! a frame, which costs one CRC and one parse of that frame.

use super::cobs::Unstuffer;
use super::frame::{split_frame, Direction, Header};
use super::message::Message;
use super::{Error, DELIMITER, MAX_FRAME, MAX_RAW};

/// What the decoder did with a byte (or a chunk, up to the first event).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Outcome<'a> {
    /// Taken; no frame ended.
    Consumed,
    /// A frame ended and was accepted. The message borrows the decoder's buffer, until the
    /// next byte is pushed.
    Frame(Header, Message<'a>),
    /// The current frame passed [`MAX_FRAME`] and is dropped; bytes are skipped to the next
    /// 0x00. Counted in [`RxCounters::oversize`].
    OverFull,
    /// A frame ended and was refused.
    Error {
        /// The frame's header, if the frame got as far as a valid CRC, version and type (a
        /// runtime uses it to send a [`ReplyRepr`](super::ReplyRepr) for a refused Params or
        /// Mission message).
        header: Option<Header>,
        /// Why.
        error: Error,
    },
}

/// Counts of what the decoder accepted and refused, saturating.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RxCounters {
    /// Frames accepted.
    pub frames: u32,
    /// Frames refused for a CRC mismatch.
    pub crc: u32,
    /// Frames dropped for exceeding [`MAX_FRAME`].
    pub oversize: u32,
    /// Frames refused for malformed COBS or for being shorter than header + CRC.
    pub framing: u32,
    /// Frames refused for an unsupported protocol version.
    pub version: u32,
    /// Frames refused for an unknown message type, or one flowing the other way.
    pub unknown_type: u32,
    /// Frames refused for their payload: wrong length or a refused field.
    pub bad_payload: u32,
}

impl RxCounters {
    /// Every refusal, of any kind.
    pub fn rejected(&self) -> u32 {
        [
            self.crc,
            self.oversize,
            self.framing,
            self.version,
            self.unknown_type,
            self.bad_payload,
        ]
        .iter()
        .fold(0u32, |s, &c| s.saturating_add(c))
    }

    fn count(&mut self, e: &Error) {
        let c = match e {
            Error::Crc => &mut self.crc,
            Error::Oversize => &mut self.oversize,
            Error::Cobs | Error::Truncated | Error::BufferTooSmall => &mut self.framing,
            Error::Version(_) => &mut self.version,
            Error::UnknownType(_) | Error::WrongDirection(_) => &mut self.unknown_type,
            Error::Length | Error::Field { .. } => &mut self.bad_payload,
        };
        *c = c.saturating_add(1);
    }
}

/// What one byte did, before anything is borrowed from the buffer.
enum Step {
    Consumed,
    OverFull,
    Ended(usize),
    Refused(Error),
}

/// The stream decoder. About 700 bytes; the firmware keeps one per serial port in a static.
#[derive(Clone, Debug)]
pub struct Decoder {
    buf: [u8; MAX_RAW],
    /// Decoded bytes of the current frame in `buf`.
    len: usize,
    /// Encoded bytes of the current frame, delimiter excluded.
    encoded: usize,
    unstuffer: Unstuffer,
    /// Dropping the rest of an oversize frame.
    skipping: bool,
    accept: Option<Direction>,
    counters: RxCounters,
}

impl Default for Decoder {
    fn default() -> Self {
        Decoder::new()
    }
}

impl Decoder {
    /// A decoder accepting messages of either direction.
    pub const fn new() -> Self {
        Decoder {
            buf: [0; MAX_RAW],
            len: 0,
            encoded: 0,
            unstuffer: Unstuffer::new(),
            skipping: false,
            accept: None,
            counters: RxCounters {
                frames: 0,
                crc: 0,
                oversize: 0,
                framing: 0,
                version: 0,
                unknown_type: 0,
                bad_payload: 0,
            },
        }
    }

    /// A decoder that refuses messages flowing the other way ([`Error::WrongDirection`],
    /// counted as unknown): the firmware's accepts [`Direction::ToFirmware`], a host's
    /// [`Direction::ToHost`].
    pub const fn accepting(direction: Direction) -> Self {
        let mut d = Decoder::new();
        d.accept = Some(direction);
        d
    }

    /// The counters so far.
    pub fn counters(&self) -> &RxCounters {
        &self.counters
    }

    /// Drops the frame in progress and skips to the next 0x00 (e.g. after a UART overrun or
    /// framing error, which corrupts the frame). Not counted: the caller knows why.
    pub fn discard_frame(&mut self) {
        self.reset_frame();
        self.skipping = true;
    }

    fn reset_frame(&mut self) {
        self.len = 0;
        self.encoded = 0;
        self.unstuffer = Unstuffer::new();
        self.skipping = false;
    }

    fn overfull(&mut self) -> Step {
        self.reset_frame();
        self.skipping = true;
        self.counters.count(&Error::Oversize);
        Step::OverFull
    }

    fn step(&mut self, byte: u8) -> Step {
        if byte == DELIMITER {
            if self.skipping || self.encoded == 0 {
                // The end of a dropped frame (already reported), or an empty frame.
                self.reset_frame();
                return Step::Consumed;
            }
            let complete = self.unstuffer.finish();
            let len = self.len;
            self.reset_frame();
            return match complete {
                Ok(()) => Step::Ended(len),
                Err(e) => {
                    self.counters.count(&e);
                    Step::Refused(e)
                }
            };
        }
        if self.skipping {
            return Step::Consumed;
        }
        // The frame with its delimiter must fit in MAX_FRAME: checked before taking the byte.
        if self.encoded >= MAX_FRAME - 1 {
            return self.overfull();
        }
        self.encoded += 1;
        match self.unstuffer.push(byte) {
            Ok(Some(d)) => match self.buf.get_mut(self.len) {
                Some(slot) => {
                    *slot = d;
                    self.len += 1;
                    Step::Consumed
                }
                // Only a non-canonical encoding (runs of 0x01) can decode past MAX_RAW.
                None => self.overfull(),
            },
            Ok(None) => Step::Consumed,
            // Unreachable (0x00 was handled above), but a refusal rather than a panic.
            Err(_) => Step::Consumed,
        }
    }

    /// Parses the `len` decoded bytes in the buffer.
    fn deliver(&mut self, len: usize) -> Outcome<'_> {
        let Decoder {
            buf,
            counters,
            accept,
            ..
        } = self;
        let raw = buf.get(..len).unwrap_or(&[]);
        let (header, payload) = match split_frame(raw) {
            Ok(hp) => hp,
            Err(error) => {
                counters.count(&error);
                return Outcome::Error {
                    header: None,
                    error,
                };
            }
        };
        let parsed = match accept {
            Some(dir) if header.msg_type.direction() != *dir => {
                Err(Error::WrongDirection(header.msg_type.code()))
            }
            _ => Message::parse(header.msg_type, payload),
        };
        match parsed {
            Ok(message) => {
                counters.frames = counters.frames.saturating_add(1);
                Outcome::Frame(header, message)
            }
            Err(error) => {
                counters.count(&error);
                Outcome::Error {
                    header: Some(header),
                    error,
                }
            }
        }
    }

    /// Takes one byte.
    pub fn push(&mut self, byte: u8) -> Outcome<'_> {
        match self.step(byte) {
            Step::Consumed => Outcome::Consumed,
            Step::OverFull => Outcome::OverFull,
            Step::Ended(len) => self.deliver(len),
            Step::Refused(error) => Outcome::Error {
                header: None,
                error,
            },
        }
    }

    /// Takes bytes from `input` up to and including the first one that produces something
    /// other than [`Outcome::Consumed`]; returns that outcome and the bytes not yet taken
    /// (feed them next). Returns [`Outcome::Consumed`] and an empty rest when the whole chunk
    /// was taken without event.
    ///
    /// ```
    /// use vpf::link::{Decoder, Outcome};
    /// # fn handle(_: &vpf::link::Message<'_>) {}
    /// let mut dec = Decoder::new();
    /// let mut chunk: &[u8] = &[0x00, 0x05, 0x01];
    /// while !chunk.is_empty() {
    ///     let (outcome, rest) = dec.feed(chunk);
    ///     if let Outcome::Frame(_, msg) = outcome {
    ///         handle(&msg);
    ///     }
    ///     chunk = rest;
    /// }
    /// ```
    pub fn feed<'i>(&mut self, input: &'i [u8]) -> (Outcome<'_>, &'i [u8]) {
        let mut rest = input;
        while let Some((&byte, tail)) = rest.split_first() {
            rest = tail;
            match self.step(byte) {
                Step::Consumed => {}
                Step::OverFull => return (Outcome::OverFull, rest),
                Step::Ended(len) => return (self.deliver(len), rest),
                Step::Refused(error) => {
                    return (
                        Outcome::Error {
                            header: None,
                            error,
                        },
                        rest,
                    )
                }
            }
        }
        (Outcome::Consumed, rest)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::link::message::tests::arb_owned;
    use crate::link::PROTOCOL_VERSION;
    use crate::link::{
        encode_frame, LogLevel, LogRepr, MessageType, Payload, TickRepr, MAX_PAYLOAD,
    };
    use proptest::prelude::*;
    use std::vec::Vec;

    /// What a whole byte sequence produced: accepted (type, seq) pairs, and events.
    #[derive(Debug, Default, PartialEq)]
    struct Log {
        frames: Vec<(MessageType, u16)>,
        errors: Vec<(Option<Header>, Error)>,
        overfull: usize,
    }

    fn run(dec: &mut Decoder, bytes: &[u8]) -> Log {
        let mut log = Log::default();
        for &b in bytes {
            match dec.push(b) {
                Outcome::Consumed => {}
                Outcome::Frame(h, _) => log.frames.push((h.msg_type, h.seq)),
                Outcome::OverFull => log.overfull += 1,
                Outcome::Error { header, error } => log.errors.push((header, error)),
            }
        }
        log
    }

    fn tick(seq: u16, t: u64) -> Vec<u8> {
        let mut out = [0u8; MAX_FRAME];
        let n = TickRepr { time_ms: t }.emit_frame(seq, &mut out).unwrap();
        out[..n].to_vec()
    }

    /// The Tick frame of frame.rs's vector, byte for byte.
    const TICK_1000_SEQ_1: [u8; 16] = [
        0x04, 0x06, 0x08, 0x01, 0x03, 0xe8, 0x03, 0x01, 0x01, 0x01, 0x01, 0x01, 0x03, 0x6d, 0xf4,
        0x00,
    ];

    #[test]
    fn decodes_a_known_frame_byte_by_byte() {
        let mut d = Decoder::new();
        let (last, body) = TICK_1000_SEQ_1.split_last().unwrap();
        for &b in body {
            assert_eq!(d.push(b), Outcome::Consumed);
        }
        match d.push(*last) {
            Outcome::Frame(h, Message::Tick(t)) => {
                assert_eq!((h.msg_type, h.seq, t.time_ms), (MessageType::Tick, 1, 1000));
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(d.counters().frames, 1);
        assert_eq!(d.counters().rejected(), 0);
    }

    #[test]
    fn feed_stops_at_each_event_and_returns_the_rest() {
        let mut d = Decoder::new();
        let mut stream = std::vec![0x00];
        stream.extend(tick(1, 10));
        stream.extend(tick(2, 20));
        stream.extend([0x13, 0x37]);
        let (o, rest) = d.feed(&stream);
        assert!(matches!(o, Outcome::Frame(h, _) if h.seq == 1));
        let (o, rest) = d.feed(rest);
        assert!(
            matches!(o, Outcome::Frame(h, Message::Tick(TickRepr { time_ms: 20 })) if h.seq == 2)
        );
        let (o, rest) = d.feed(rest);
        assert_eq!(o, Outcome::Consumed);
        assert!(rest.is_empty());
        // The partial frame completes across chunks.
        let (o, _) = d.feed(&[0x00]);
        assert!(matches!(o, Outcome::Error { header: None, .. }));
    }

    #[test]
    fn every_rejection_is_counted_in_its_own_counter() {
        let mut d = Decoder::new();
        let mut s = std::vec![0x00, 0x00]; // empty frames: ignored, not counted
                                           // CRC: flip a payload byte of a good frame (0xe8 → 0xe9; still no zero).
        let mut bad_crc = TICK_1000_SEQ_1.to_vec();
        bad_crc[5] = 0xe9;
        s.extend(&bad_crc);
        // Framing: a block running past the end, and a frame too short for header + CRC.
        s.extend([0x05, 0x01, 0x00]);
        s.extend([0x03, 0x01, 0x02, 0x00]);
        // Version and type, with good CRCs.
        for (v, t) in [(1u8, 0x08u8), (PROTOCOL_VERSION, 0x7e)] {
            let mut raw = std::vec![v, t, 0, 0];
            let crc = crate::link::crc::crc16(&raw);
            raw.extend(crc.to_le_bytes());
            let mut enc = std::vec![0u8; 16];
            let n = crate::link::cobs::encode(&raw, &mut enc).unwrap();
            s.extend(&enc[..n]);
            s.push(0);
        }
        // Payload: a Tick with 7 bytes, and a Log with an unknown level.
        let mut out = [0u8; 64];
        let n = encode_frame(MessageType::Tick, 9, |b| Ok(b.len().min(7)), &mut out).unwrap();
        s.extend(&out[..n]);
        let n = encode_frame(
            MessageType::Log,
            10,
            |b| {
                b[0] = 9;
                Ok(1)
            },
            &mut out,
        )
        .unwrap();
        s.extend(&out[..n]);
        // Oversize: MAX_FRAME non-zero bytes.
        s.extend(std::iter::repeat_n(0x55u8, MAX_FRAME));
        s.push(0);
        // And a good frame at the end, which must survive all of the above.
        s.extend(tick(11, 5));

        let log = run(&mut d, &s);
        assert_eq!(log.frames, [(MessageType::Tick, 11)]);
        assert_eq!(log.overfull, 1);
        let errs: Vec<Error> = log.errors.iter().map(|e| e.1).collect();
        assert_eq!(
            errs,
            [
                Error::Crc,
                Error::Cobs,
                Error::Truncated,
                Error::Version(1),
                Error::UnknownType(0x7e),
                Error::Length,
                Error::field(0, crate::link::Problem::UnknownCode),
            ]
        );
        // Payload errors carry the header, so the runtime can reply.
        assert_eq!(
            log.errors[5].0,
            Some(Header {
                msg_type: MessageType::Tick,
                seq: 9
            })
        );
        assert!(log.errors[..5].iter().all(|e| e.0.is_none()));
        assert_eq!(
            *d.counters(),
            RxCounters {
                frames: 1,
                crc: 1,
                oversize: 1,
                framing: 2,
                version: 1,
                unknown_type: 1,
                bad_payload: 2,
            }
        );
        assert_eq!(d.counters().rejected(), 8);
    }

    #[test]
    fn oversize_is_reported_as_soon_as_the_limit_is_passed() {
        let mut d = Decoder::new();
        // Full 254-byte blocks (code 0xFF, no implied zeros): 666 encoded bytes decode to
        // 663 = MAX_RAW, so only the encoded bound can trip.
        let stream: Vec<u8> = std::iter::repeat_n(
            core::iter::once(0xFF).chain(std::iter::repeat_n(0x55, 254)),
            3,
        )
        .flatten()
        .collect();
        // MAX_FRAME − 1 encoded bytes plus the delimiter is the largest frame: not oversize.
        for &b in &stream[..MAX_FRAME - 1] {
            assert_eq!(d.push(b), Outcome::Consumed);
        }
        // One more byte and it is dropped, at once.
        assert_eq!(d.push(0x55), Outcome::OverFull);
        for _ in 0..1000 {
            assert_eq!(d.push(0x55), Outcome::Consumed);
        }
        assert_eq!(d.push(0x00), Outcome::Consumed);
        assert_eq!(d.counters().oversize, 1);
        assert_eq!(d.counters().rejected(), 1);
        let log = run(&mut d, &tick(3, 3));
        assert_eq!(log.frames, [(MessageType::Tick, 3)]);
        // The same 666 bytes then a delimiter: a complete-length frame, refused for COBS
        // (its last block is short), not for size.
        let log = run(&mut d, &stream[..MAX_FRAME - 1]);
        assert_eq!(log, Log::default());
        assert_eq!(
            d.push(0),
            Outcome::Error {
                header: None,
                error: Error::Cobs
            }
        );
    }

    #[test]
    fn non_canonical_encodings_cannot_overrun_the_buffer() {
        // 0x01 codes decode to one zero each: the decoded length hits MAX_RAW before the
        // encoded one hits MAX_FRAME.
        let mut d = Decoder::new();
        let log = run(&mut d, &[0x01; MAX_RAW + 2]);
        assert_eq!(log.overfull, 1);
        assert_eq!(d.push(0), Outcome::Consumed);
    }

    #[test]
    fn the_largest_messages_pass() {
        let text = "é".repeat(48);
        let log_msg = LogRepr {
            level: LogLevel::Info,
            text: &text,
        };
        let mut out = [0u8; MAX_FRAME];
        let n = log_msg.emit_frame(4, &mut out).unwrap();
        let mut d = Decoder::new();
        let (o, _) = d.feed(&out[..n]);
        assert_eq!(
            o,
            Outcome::Frame(
                Header {
                    msg_type: MessageType::Log,
                    seq: 4
                },
                Message::Log(log_msg)
            )
        );
        // A full-size payload of 0xff bytes (the most COBS overhead) fits in MAX_FRAME.
        let n = encode_frame(
            MessageType::Scanline,
            5,
            |b| {
                b[..MAX_PAYLOAD].fill(0xff);
                Ok(MAX_PAYLOAD)
            },
            &mut out,
        )
        .unwrap();
        assert!(n <= MAX_FRAME);
        let log = run(&mut d, &out[..n]);
        assert_eq!(log.overfull, 0);
        // Not a valid scanline (bin count 0xffff), but not oversize either.
        assert_eq!(log.errors.len(), 1);
        assert_eq!(
            log.errors[0].1,
            Error::field(4, crate::link::Problem::OutOfRange)
        );
    }

    #[test]
    fn direction_filter() {
        let mut fw = Decoder::accepting(Direction::ToFirmware);
        let mut out = [0u8; MAX_FRAME];
        let n = LogRepr {
            level: LogLevel::Info,
            text: "hi",
        }
        .emit_frame(1, &mut out)
        .unwrap();
        let log = run(&mut fw, &out[..n]);
        assert_eq!(log.errors[0].1, Error::WrongDirection(0x84));
        assert_eq!(fw.counters().unknown_type, 1);
        let log = run(&mut fw, &tick(2, 2));
        assert_eq!(log.frames.len(), 1);
        let mut host = Decoder::accepting(Direction::ToHost);
        let log = run(&mut host, &tick(2, 2));
        assert_eq!(log.errors[0].1, Error::WrongDirection(0x08));
    }

    #[test]
    fn discard_frame_skips_to_the_next_delimiter() {
        let mut d = Decoder::new();
        let t = tick(1, 1);
        run(&mut d, &t[..5]);
        d.discard_frame();
        let log = run(&mut d, &t[5..]);
        assert_eq!(log, Log::default());
        let log = run(&mut d, &t);
        assert_eq!(log.frames.len(), 1);
    }

    fn encode_all(
        msgs: &[crate::link::message::tests::OwnedMessage],
    ) -> (Vec<Vec<u8>>, Vec<(MessageType, u16)>) {
        let mut frames = Vec::new();
        let mut ids = Vec::new();
        for (i, o) in msgs.iter().enumerate() {
            let m = o.message();
            let mut out = [0u8; MAX_FRAME];
            let n = m.emit_frame(i as u16, &mut out).unwrap();
            frames.push(out[..n].to_vec());
            ids.push((m.message_type(), i as u16));
        }
        (frames, ids)
    }

    proptest! {
        #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

        /// (1) Arbitrary bytes: no panic, at most one event per byte, and every event counted.
        #[test]
        fn never_panics_and_counts_every_event(
            bytes in proptest::collection::vec(
                prop_oneof![any::<u8>(), Just(0u8), 1u8..=8], 0..3000)
        ) {
            let mut d = Decoder::new();
            let log = run(&mut d, &bytes);
            let c = *d.counters();
            prop_assert_eq!(c.frames as usize, log.frames.len());
            prop_assert_eq!(c.oversize as usize, log.overfull);
            prop_assert_eq!(c.rejected() as usize, log.errors.len() + log.overfull);
            // Through feed, in random chunks, the same events.
            let mut d2 = Decoder::new();
            let mut rest: &[u8] = &bytes;
            let mut n_events = 0usize;
            while !rest.is_empty() {
                let (o, r) = d2.feed(rest);
                if o != Outcome::Consumed { n_events += 1; }
                rest = r;
            }
            prop_assert_eq!(n_events, log.frames.len() + log.errors.len() + log.overfull);
            prop_assert_eq!(d2.counters(), d.counters());
        }

        /// (2) Valid frames after arbitrary garbage: the first may be lost (the garbage runs
        /// into it), every later one is recovered, in order. With a 0x00 after the garbage
        /// none is lost. Garbage after the frames does not disturb them.
        #[test]
        fn resyncs_after_garbage_losing_at_most_one_frame(
            garbage in proptest::collection::vec(any::<u8>(), 0..1500),
            tail in proptest::collection::vec(any::<u8>(), 0..200),
            msgs in proptest::collection::vec(arb_owned(), 1..4),
            flush in any::<bool>(),
        ) {
            let (frames, ids) = encode_all(&msgs);
            let mut stream = garbage.clone();
            if flush {
                stream.push(0);
            }
            for f in &frames {
                stream.extend(f);
            }
            stream.extend(&tail);
            let mut d = Decoder::new();
            let log = run(&mut d, &stream);
            let got = log.frames;
            // Garbage can only yield a frame by passing the CRC by chance, so accepted frames
            // are checked as a contiguous run inside whatever was decoded.
            let contains = |needle: &[(MessageType, u16)]| {
                needle.is_empty() || got.windows(needle.len()).any(|w| w == needle)
            };
            // After the first delimiter in the frames, everything is recovered.
            prop_assert!(contains(&ids[1..]), "{:?} not in {:?}", &ids[1..], got);
            // With a delimiter between garbage and frames, nothing is lost.
            if flush || garbage.last().is_none_or(|&b| b == 0) {
                prop_assert!(contains(&ids), "{:?} not in {:?}", ids, got);
            }
        }

        /// (3) encode → decode is the identity for random valid messages, through the stream
        /// decoder, in chunks of random size.
        #[test]
        fn stream_round_trip(
            msgs in proptest::collection::vec(arb_owned(), 1..6),
            chunk in 1usize..64,
        ) {
            let mut stream = std::vec![0u8];
            let mut out = [0u8; MAX_FRAME];
            for (i, o) in msgs.iter().enumerate() {
                let n = o.message().emit_frame(i as u16, &mut out).unwrap();
                stream.extend(&out[..n]);
            }
            let mut d = Decoder::new();
            let mut got = 0usize;
            for mut c in stream.chunks(chunk) {
                while !c.is_empty() {
                    let (o, rest) = d.feed(c);
                    match o {
                        Outcome::Consumed => {}
                        Outcome::Frame(h, m) => {
                            prop_assert_eq!(h.seq as usize, got);
                            prop_assert_eq!(m, msgs[got].message());
                            got += 1;
                        }
                        other => prop_assert!(false, "unexpected {:?}", other),
                    }
                    c = rest;
                }
            }
            prop_assert_eq!(got, msgs.len());
            prop_assert_eq!(d.counters().rejected(), 0);
        }
    }
}
