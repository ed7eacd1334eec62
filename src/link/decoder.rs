//! The stream decoder: bytes from the UART in, parsed messages out, in the style of postcard's
//! `CobsAccumulator`, over one fixed buffer of [`MAX_RAW`] bytes.
//!
//! **Rules** (also in `docs/protocol.md`):
//! - Every 0x00 ends a frame and starts the next: the decoder is back in sync after any
//!   garbage as soon as it sees a 0x00, so at most the frame the garbage ran into is lost.
//!   Senders should begin with a 0x00 so that even that one survives.
//! - Empty frames (0x00 0x00) are ignored and not counted: a sender may flush with extra 0x00s.
//! - The framing is the direction's: a decoder of frames to the firmware takes coded frames
//!   ([`super::coded`]), one of frames to the host COBS frames.
//! - The framing is undone byte by byte; the encoded length is checked before each byte is
//!   taken, so a frame longer than [`MAX_CODED_FRAME`] or [`MAX_COBS_FRAME`] (or one decoding
//!   to more than [`MAX_RAW`] bytes) is reported once, as [`Outcome::OverFull`], as soon as the
//!   limit is passed, and the rest of it up to the next 0x00 is skipped. Nothing past the
//!   buffer is ever written.
//! - At the 0x00, a frame is checked in this order: COBS complete (to the host) or a length
//!   the encoder produces and, unless its CRC matches as it came, at most 8 wrong bytes per
//!   block, which are corrected (to the firmware), at least header + CRC, CRC, version, type (and direction), payload. The first
//!   failure is returned as [`Outcome::Error`] and counted in exactly one [`RxCounters`]
//!   field; a coded frame whose bytes were corrected and that passed its CRC also counts in
//!   [`RxCounters::corrected`].
//!
//! No input makes it panic, allocate or loop: each byte costs O(1), except the 0x00 that ends
//! a frame, which costs one CRC, one parse and, for a coded frame, one Reed–Solomon check of
//! each block (and its correction if it has errors).

use super::cobs::Unstuffer;
use super::coded;
use super::frame::{check_crc, split_body, split_frame, Direction, Header};
use super::message::Message;
use super::{Error, CRC_LEN, DELIMITER, HEADER_LEN, MAX_COBS_FRAME, MAX_CODED_FRAME, MAX_RAW};

/// What the decoder did with a byte (or a chunk, up to the first event).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Outcome<'a> {
    /// Taken; no frame ended.
    Consumed,
    /// A frame ended and was accepted. The message borrows the decoder's buffer, until the
    /// next byte is pushed.
    Frame(Header, Message<'a>),
    /// The current frame passed its framing's longest ([`MAX_CODED_FRAME`] or
    /// [`MAX_COBS_FRAME`]) and is dropped; bytes are skipped to the next 0x00. Counted in [`RxCounters::oversize`].
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
    /// Frames dropped for exceeding the longest frame.
    pub oversize: u32,
    /// Frames refused for malformed COBS, a coded frame's impossible length, or for being
    /// shorter than header + CRC.
    pub framing: u32,
    /// Coded frames with more wrong bytes than the code corrects (more than 8 in a block).
    pub uncorrectable: u32,
    /// Coded frames whose wrong bytes were corrected and which then passed their CRC (not a
    /// refusal: they are counted in `frames` too if their content was accepted).
    pub corrected: u32,
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
            self.uncorrectable,
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
            Error::Cobs | Error::CodedLength | Error::Truncated | Error::BufferTooSmall => {
                &mut self.framing
            }
            Error::Uncorrectable => &mut self.uncorrectable,
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
    /// A frame ended: its decoded length, whether its CRC has been checked already (then the
    /// length is the body's, header and payload), and whether the code corrected bytes in it.
    Ended {
        len: usize,
        checked: bool,
        corrected: bool,
    },
    Refused(Error),
}

/// The stream decoder. About 730 bytes; the firmware keeps one per serial port in a static.
#[derive(Clone, Debug)]
pub struct Decoder {
    /// The frame's bytes: a COBS frame's raw bytes, decoded as they come, or a coded frame's
    /// wire bytes, turned into its codeword (raw frame and parity) and corrected in place at
    /// its end.
    buf: [u8; MAX_CODED_FRAME - 1],
    /// Decoded bytes of the current frame in `buf`.
    len: usize,
    /// Encoded bytes of the current frame, delimiter excluded.
    encoded: usize,
    unstuffer: Unstuffer,
    /// Dropping the rest of an oversize frame.
    skipping: bool,
    /// The direction accepted, which is also the framing: coded to the firmware, COBS to the
    /// host.
    accept: Direction,
    /// `accept` is [`Direction::ToFirmware`].
    coded: bool,
    counters: RxCounters,
}

impl Decoder {
    /// A decoder of frames flowing `direction`, in that direction's framing; it refuses
    /// messages flowing the other way ([`Error::WrongDirection`], counted as unknown): the
    /// firmware's accepts [`Direction::ToFirmware`] (coded frames), a host's
    /// [`Direction::ToHost`] (COBS frames).
    pub const fn accepting(direction: Direction) -> Self {
        Decoder {
            buf: [0; MAX_CODED_FRAME - 1],
            len: 0,
            encoded: 0,
            unstuffer: Unstuffer::new(),
            skipping: false,
            accept: direction,
            coded: matches!(direction, Direction::ToFirmware),
            counters: RxCounters {
                frames: 0,
                crc: 0,
                oversize: 0,
                framing: 0,
                uncorrectable: 0,
                corrected: 0,
                version: 0,
                unknown_type: 0,
                bad_payload: 0,
            },
        }
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
            let ended = if self.coded {
                self.correct()
            } else {
                self.unstuffer.finish().map(|()| Step::Ended {
                    len: self.len,
                    checked: false,
                    corrected: false,
                })
            };
            self.reset_frame();
            return match ended {
                Ok(step) => step,
                Err(e) => {
                    self.counters.count(&e);
                    Step::Refused(e)
                }
            };
        }
        if self.skipping {
            return Step::Consumed;
        }
        // The frame with its delimiter must fit: checked before taking the byte.
        if self.coded {
            // Kept as it came (undone at the frame's end): the buffer holds the longest frame.
            return match self.buf.get_mut(self.len) {
                Some(slot) => {
                    *slot = byte;
                    self.len += 1;
                    self.encoded += 1;
                    Step::Consumed
                }
                None => self.overfull(),
            };
        }
        if self.encoded >= MAX_COBS_FRAME - 1 {
            return self.overfull();
        }
        self.encoded += 1;
        match self.unstuffer.push(byte) {
            // A COBS frame decodes to at most MAX_RAW bytes.
            Ok(Some(d)) => match self.buf.get_mut(self.len).filter(|_| self.len < MAX_RAW) {
                Some(slot) => {
                    *slot = d;
                    self.len += 1;
                    Step::Consumed
                }
                // Only a non-canonical COBS encoding (runs of 0x01) can decode past MAX_RAW.
                None => self.overfull(),
            },
            Ok(None) => Step::Consumed,
            // Unreachable (0x00 was handled above), but a refusal rather than a panic.
            Err(_) => Step::Consumed,
        }
    }

    /// The end of a coded frame: its length checked; its CRC checked as it came and, if it
    /// does not match, again after its blocks are corrected in place.
    fn correct(&mut self) -> Result<Step, Error> {
        let wire = self.buf.get_mut(..self.len).ok_or(Error::CodedLength)?;
        let n = coded::unsubstitute_in_place(wire)?;
        let raw_len = coded::raw_len_of(n).ok_or(Error::CodedLength)?;
        if raw_len < HEADER_LEN + CRC_LEN {
            return Err(Error::Truncated);
        }
        let len = raw_len - CRC_LEN;
        // Most frames arrive clean: the CRC (10 operations a byte) says so, and the code (16
        // table look-ups a byte and more) runs only for those it refuses.
        let raw = self.buf.get(..raw_len).ok_or(Error::CodedLength)?;
        if check_crc(raw).is_ok() {
            return Ok(Step::Ended {
                len,
                checked: true,
                corrected: false,
            });
        }
        let codeword = self.buf.get_mut(..n).ok_or(Error::CodedLength)?;
        let fixed = coded::correct(codeword, raw_len).map_err(|_| Error::Uncorrectable)?;
        check_crc(self.buf.get(..raw_len).ok_or(Error::CodedLength)?)?;
        Ok(Step::Ended {
            len,
            checked: true,
            corrected: fixed > 0,
        })
    }

    /// Parses the `len` decoded bytes in the buffer: a raw frame, or (`checked`) the body of
    /// one whose CRC has been checked; `corrected`: the code corrected some.
    fn deliver(&mut self, len: usize, checked: bool, corrected: bool) -> Outcome<'_> {
        let Decoder {
            buf,
            counters,
            accept,
            ..
        } = self;
        let raw = buf.get(..len).unwrap_or(&[]);
        let split = if checked {
            split_body(raw)
        } else {
            split_frame(raw)
        };
        let (header, payload) = match split {
            Ok(hp) => hp,
            Err(error) => {
                counters.count(&error);
                return Outcome::Error {
                    header: None,
                    error,
                };
            }
        };
        if corrected {
            counters.corrected = counters.corrected.saturating_add(1);
        }
        let parsed = if header.msg_type.direction() == *accept {
            Message::parse(header.msg_type, payload)
        } else {
            Err(Error::WrongDirection(header.msg_type.code()))
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
            Step::Ended {
                len,
                checked,
                corrected,
            } => self.deliver(len, checked, corrected),
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
    /// use vpf::link::Direction;
    /// let mut dec = Decoder::accepting(Direction::ToHost);
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
                Step::Ended {
                    len,
                    checked,
                    corrected,
                } => return (self.deliver(len, checked, corrected), rest),
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
    use crate::link::message::tests::{arb_owned, OwnedMessage};
    use crate::link::{
        coded, crc::crc16, encode_frame, LogLevel, LogRepr, MessageType, Payload, Problem,
        TickRepr, MAX_FRAME, MAX_PAYLOAD, PROTOCOL_VERSION,
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

    fn firmware() -> Decoder {
        Decoder::accepting(Direction::ToFirmware)
    }

    fn host() -> Decoder {
        Decoder::accepting(Direction::ToHost)
    }

    fn tick(seq: u16, t: u64) -> Vec<u8> {
        let mut out = [0u8; MAX_FRAME];
        let n = TickRepr { time_ms: t }.emit_frame(seq, &mut out).unwrap();
        out[..n].to_vec()
    }

    /// Header and payload with their CRC.
    fn raw(bytes: &[u8]) -> Vec<u8> {
        let mut r = bytes.to_vec();
        r.extend(crc16(bytes).to_le_bytes());
        r
    }

    /// A raw frame in the coded framing, delimited.
    fn coded_wire(raw: &[u8]) -> Vec<u8> {
        let mut out = std::vec![0u8; MAX_FRAME + 8];
        let n = coded::encode(raw, &mut out).unwrap();
        let mut w = out[..n].to_vec();
        w.push(0);
        w
    }

    /// A raw frame in COBS, delimited.
    fn cobs_wire(raw: &[u8]) -> Vec<u8> {
        let mut out = std::vec![0u8; MAX_FRAME];
        let n = crate::link::cobs::encode(raw, &mut out).unwrap();
        let mut w = out[..n].to_vec();
        w.push(0);
        w
    }

    /// The Tick of the frame.rs vector (docs/protocol.md §11), coded: raw
    /// `08 08 01 00 e8 03 00 00 00 00 00 00 fb e4`, computed with the protocol's Python
    /// reference code.
    const TICK_1000_SEQ_1: [u8; 32] = [
        0xff, 0xf7, 0xe9, 0x1c, 0x9a, 0x05, 0x86, 0x33, 0x24, 0xea, 0x7a, 0xd2, 0x39, 0x8b, 0x73,
        0xd5, 0x90, 0x65, 0x0e, 0xb9, 0x9b, 0x07, 0xe4, 0xb4, 0x3d, 0x62, 0x81, 0xd5, 0x09, 0x80,
        0x28, 0x00,
    ];

    /// `n` wrong bytes spread over the Tick frame (never 0x00, never the key).
    fn damaged_tick(n: usize) -> Vec<u8> {
        let mut t = TICK_1000_SEQ_1.to_vec();
        for k in 0..n {
            let i = 1 + (k * 7) % 30;
            t[i] = if t[i] == 0x5a { 0xa5 } else { 0x5a };
        }
        t
    }

    #[test]
    fn decodes_a_known_frame_byte_by_byte() {
        let mut d = firmware();
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
        assert_eq!(d.counters().corrected, 0);
        assert_eq!(d.counters().rejected(), 0);
        assert_eq!(tick(1, 1000), TICK_1000_SEQ_1);
    }

    #[test]
    fn eight_wrong_bytes_are_corrected_and_counted_more_are_refused() {
        let mut d = firmware();
        let log = run(&mut d, &damaged_tick(8));
        assert_eq!(log.frames, [(MessageType::Tick, 1)]);
        assert_eq!(d.counters().corrected, 1);
        assert_eq!(d.counters().frames, 1);
        let log = run(&mut d, &damaged_tick(14));
        assert_eq!(log.errors, [(None, Error::Uncorrectable)]);
        assert_eq!(d.counters().uncorrectable, 1);
        assert_eq!(d.counters().rejected(), 1);
        // A clean frame after it is not counted as corrected.
        run(&mut d, &TICK_1000_SEQ_1);
        assert_eq!((d.counters().frames, d.counters().corrected), (2, 1));
    }

    #[test]
    fn feed_stops_at_each_event_and_returns_the_rest() {
        let mut d = firmware();
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
        let mut d = firmware();
        let mut s = std::vec![0x00, 0x00]; // empty frames: ignored, not counted
                                           // CRC: a good code around a wrong CRC.
        let mut bad_crc = raw(&[PROTOCOL_VERSION, 0x08, 1, 0, 0xe8, 3, 0, 0, 0, 0, 0, 0]);
        bad_crc[5] ^= 0x10;
        s.extend(coded_wire(&bad_crc));
        // Framing: a length no encoder makes, and a frame too short for header + CRC.
        s.extend([0x05, 0x01, 0x02, 0x00]);
        s.extend(coded_wire(&[1, 2, 3]));
        // More wrong bytes than the code corrects.
        s.extend(damaged_tick(14));
        // Version and type, with good CRCs.
        for (v, t) in [(1u8, 0x08u8), (PROTOCOL_VERSION, 0x7e)] {
            s.extend(coded_wire(&raw(&[v, t, 0, 0])));
        }
        // A message of the other direction, coded.
        s.extend(coded_wire(&raw(&[PROTOCOL_VERSION, 0x84, 0, 0, 1, b'x'])));
        // Payload: a Tick with 7 bytes, and a Mission with an unknown flag.
        let mut out = [0u8; MAX_FRAME];
        let n = encode_frame(MessageType::Tick, 9, |b| Ok(b.len().min(7)), &mut out).unwrap();
        s.extend(&out[..n]);
        let n = encode_frame(
            MessageType::Mission,
            10,
            |b| {
                b[..9].fill(0);
                b[8] = 0x80;
                Ok(9)
            },
            &mut out,
        )
        .unwrap();
        s.extend(&out[..n]);
        // Oversize: MAX_CODED_FRAME non-zero bytes.
        s.extend(std::iter::repeat_n(0x55u8, MAX_CODED_FRAME));
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
                Error::CodedLength,
                Error::Truncated,
                Error::Uncorrectable,
                Error::Version(1),
                Error::UnknownType(0x7e),
                Error::WrongDirection(0x84),
                Error::Length,
                Error::field(2, Problem::UnknownCode),
            ]
        );
        // Payload errors carry the header, so the runtime can reply.
        assert_eq!(
            log.errors[7].0,
            Some(Header {
                msg_type: MessageType::Tick,
                seq: 9
            })
        );
        assert!(log.errors[..6].iter().all(|e| e.0.is_none()));
        assert_eq!(
            *d.counters(),
            RxCounters {
                frames: 1,
                crc: 1,
                oversize: 1,
                framing: 2,
                uncorrectable: 1,
                corrected: 0,
                version: 1,
                unknown_type: 2,
                bad_payload: 2,
            }
        );
        assert_eq!(d.counters().rejected(), 10);
    }

    #[test]
    fn a_host_decoder_counts_cobs_refusals() {
        let mut d = host();
        let mut s = Vec::new();
        let mut bad_crc = raw(&[PROTOCOL_VERSION, 0x84, 0, 0, 1, b'x']);
        bad_crc[5] ^= 0x01;
        s.extend(cobs_wire(&bad_crc));
        s.extend([0x05, 0x01, 0x00]); // a block running past the end
        s.extend([0x03, 0x01, 0x02, 0x00]); // too short
        s.extend(cobs_wire(&raw(&[PROTOCOL_VERSION, 0x08, 0, 0]))); // a Tick: wrong way
        let log = run(&mut d, &s);
        let errs: Vec<Error> = log.errors.iter().map(|e| e.1).collect();
        assert_eq!(
            errs,
            [
                Error::Crc,
                Error::Cobs,
                Error::Truncated,
                Error::WrongDirection(0x08)
            ]
        );
        // A coded frame means nothing here: a COBS error or a CRC error, never a frame.
        let log = run(&mut d, &TICK_1000_SEQ_1);
        assert!(log.frames.is_empty() && log.errors.len() == 1);
    }

    #[test]
    fn oversize_is_reported_as_soon_as_the_limit_is_passed() {
        // COBS (to the host): full 254-byte blocks (code 0xFF, no implied zeros): 666 encoded
        // bytes decode to 663 = MAX_RAW, so only the encoded bound can trip.
        let mut d = host();
        let stream: Vec<u8> = std::iter::repeat_n(
            core::iter::once(0xFF).chain(std::iter::repeat_n(0x55, 254)),
            3,
        )
        .flatten()
        .collect();
        // MAX_COBS_FRAME − 1 encoded bytes plus the delimiter is the largest frame.
        for &b in &stream[..MAX_COBS_FRAME - 1] {
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
        // The same 666 bytes then a delimiter: a complete-length frame, refused for COBS
        // (its last block is short), not for size.
        let log = run(&mut d, &stream[..MAX_COBS_FRAME - 1]);
        assert_eq!(log, Log::default());
        assert_eq!(
            d.push(0),
            Outcome::Error {
                header: None,
                error: Error::Cobs
            }
        );
        // Coded (to the firmware): MAX_CODED_FRAME − 1 bytes fit, one more does not.
        let mut d = firmware();
        for _ in 0..MAX_CODED_FRAME - 1 {
            assert_eq!(d.push(0x55), Outcome::Consumed);
        }
        assert_eq!(d.push(0x55), Outcome::OverFull);
        assert_eq!(d.push(0x00), Outcome::Consumed);
        let log = run(&mut d, &tick(3, 3));
        assert_eq!(log.frames, [(MessageType::Tick, 3)]);
    }

    #[test]
    fn non_canonical_encodings_cannot_overrun_the_buffer() {
        // 0x01 codes decode to one zero each: the decoded length hits MAX_RAW before the
        // encoded one hits MAX_COBS_FRAME.
        let mut d = host();
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
        let mut d = host();
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
        // A full-size payload to the firmware fits in MAX_CODED_FRAME.
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
        assert_eq!(n, MAX_CODED_FRAME);
        let mut d = firmware();
        let log = run(&mut d, &out[..n]);
        assert_eq!(log.overfull, 0);
        // Not a valid scanline (bin count 0xffff), but not oversize either.
        assert_eq!(log.errors.len(), 1);
        assert_eq!(log.errors[0].1, Error::field(4, Problem::OutOfRange));
    }

    #[test]
    fn discard_frame_skips_to_the_next_delimiter() {
        let mut d = firmware();
        let t = tick(1, 1);
        run(&mut d, &t[..5]);
        d.discard_frame();
        let log = run(&mut d, &t[5..]);
        assert_eq!(log, Log::default());
        let log = run(&mut d, &t);
        assert_eq!(log.frames.len(), 1);
    }

    /// The frames of the messages that flow `direction`, and their (type, seq).
    fn encode_all(
        msgs: &[OwnedMessage],
        direction: Direction,
    ) -> (Vec<Vec<u8>>, Vec<(MessageType, u16)>) {
        let mut frames = Vec::new();
        let mut ids = Vec::new();
        for (i, o) in msgs.iter().enumerate() {
            let m = o.message();
            if m.message_type().direction() != direction {
                continue;
            }
            let mut out = [0u8; MAX_FRAME];
            let n = m.emit_frame(i as u16, &mut out).unwrap();
            frames.push(out[..n].to_vec());
            ids.push((m.message_type(), i as u16));
        }
        (frames, ids)
    }

    fn either_way() -> impl Strategy<Value = Direction> {
        prop_oneof![Just(Direction::ToFirmware), Just(Direction::ToHost)]
    }

    #[test]
    fn a_damage_the_crc_misses_is_taken_as_it_came() {
        // A Tick's coded frame with three wrong bytes whose raw frame still passes the CRC
        // (found by the property test below): taken as it came, not corrected; its damaged
        // header names no message type, and it is refused as such (`docs/protocol.md` §1).
        let msgs = std::vec![OwnedMessage::Tick(TickRepr { time_ms: 0 })];
        let (frames, _) = encode_all(&msgs, Direction::ToFirmware);
        let mut f = frames[0].clone();
        for (i, e) in [(3, 67u8), (11, 93), (2, 245)] {
            f[i] ^= e;
        }
        let mut stream = std::vec![0u8];
        stream.extend(f);
        let mut d = firmware();
        let log = run(&mut d, &stream);
        assert!(log.frames.is_empty());
        let c = d.counters();
        assert_eq!((c.unknown_type, c.corrected, c.crc), (1, 0, 0));
    }

    proptest! {
        #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

        /// (1) Arbitrary bytes: no panic, at most one event per byte, and every event counted.
        #[test]
        fn never_panics_and_counts_every_event(
            bytes in proptest::collection::vec(
                prop_oneof![any::<u8>(), Just(0u8), 1u8..=8], 0..3000),
            direction in either_way(),
        ) {
            let mut d = Decoder::accepting(direction);
            let log = run(&mut d, &bytes);
            let c = *d.counters();
            prop_assert_eq!(c.frames as usize, log.frames.len());
            prop_assert_eq!(c.oversize as usize, log.overfull);
            prop_assert_eq!(c.rejected() as usize, log.errors.len() + log.overfull);
            // Through feed, in random chunks, the same events.
            let mut d2 = Decoder::accepting(direction);
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
            msgs in proptest::collection::vec(arb_owned(), 1..6),
            flush in any::<bool>(),
            direction in either_way(),
        ) {
            let (frames, ids) = encode_all(&msgs, direction);
            prop_assume!(!ids.is_empty());
            let mut stream = garbage.clone();
            if flush {
                stream.push(0);
            }
            for f in &frames {
                stream.extend(f);
            }
            stream.extend(&tail);
            let mut d = Decoder::accepting(direction);
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
            msgs in proptest::collection::vec(arb_owned(), 1..8),
            chunk in 1usize..64,
            direction in either_way(),
        ) {
            let (frames, ids) = encode_all(&msgs, direction);
            let mut stream = std::vec![0u8];
            for f in &frames {
                stream.extend(f);
            }
            let mut d = Decoder::accepting(direction);
            let mut got = 0usize;
            for mut c in stream.chunks(chunk) {
                while !c.is_empty() {
                    let (o, rest) = d.feed(c);
                    match o {
                        Outcome::Consumed => {}
                        Outcome::Frame(h, m) => {
                            let i = usize::from(ids[got].1);
                            prop_assert_eq!(h.seq as usize, i);
                            prop_assert_eq!(m, msgs[i].message());
                            got += 1;
                        }
                        other => prop_assert!(false, "unexpected {:?}", other),
                    }
                    c = rest;
                }
            }
            prop_assert_eq!(got, ids.len());
            prop_assert_eq!(d.counters().rejected(), 0);
        }

        /// (4) Frames to the firmware with up to eight wrong bytes each (none made 0x00, the
        /// delimiter's business, nor a chunk's key) all arrive, and each one damaged outside
        /// its parity is counted as corrected (damaged parity alone passes the CRC as it is).
        /// A damage whose raw frame still passes the CRC (1 in 65 536) is taken as it came, by
        /// design (`docs/protocol.md` §1): such a case is left out, not passed.
        #[test]
        fn damaged_coded_frames_arrive(
            msgs in proptest::collection::vec(arb_owned(), 1..6),
            hits in proptest::collection::vec(
                proptest::collection::vec((any::<usize>(), 1u8..=255), 0..=8), 6),
        ) {
            let (frames, ids) = encode_all(&msgs, Direction::ToFirmware);
            let mut stream = std::vec![0u8];
            let mut damaged = 0;
            for (orig, h) in frames.iter().zip(hits.iter()) {
                let f = orig;
                let mut f = f.clone();
                let body = f.len() - 1;
                for &(pos, e) in h {
                    let i = pos % body;
                    if !i.is_multiple_of(coded::CHUNK + 1) && f[i] ^ e != 0 {
                        f[i] ^= e;
                    }
                }
                // Counted as corrected: frames whose raw part (not only parity) was hit.
                let unsub = |w: &[u8]| -> Vec<u8> {
                    let mut cw = w[..w.len() - 1].to_vec();
                    let n = coded::unsubstitute_in_place(&mut cw).unwrap();
                    cw.truncate(n);
                    cw
                };
                let (a, b) = (unsub(orig), unsub(&f));
                let raw_len = coded::raw_len_of(a.len()).unwrap();
                let hit = a[..raw_len] != b[..raw_len];
                prop_assume!(!(hit && check_crc(&b[..raw_len]).is_ok()), "damage the CRC misses");
                damaged += usize::from(hit);
                stream.extend(f);
            }
            let mut d = firmware();
            let log = run(&mut d, &stream);
            prop_assert_eq!(log.frames, ids);
            prop_assert_eq!(d.counters().corrected as usize, damaged);
            prop_assert_eq!(d.counters().rejected(), 0);
        }
    }
}
