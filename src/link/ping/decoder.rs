//! The stream decoder: Ping protocol bytes in, one [`Event`] at a time out.
//!
//! It hunts for `'B' 'R'`, reads the 8-byte header, then the payload and the checksum, summing
//! as it goes. Payloads of up to [`SMALL_PAYLOAD`] bytes are kept, for the caller to parse once
//! the checksum has matched ([`Event::Frame`], [`Decoder::payload`]). A `device_data`'s
//! samples are **streamed** instead: its 14-byte head is parsed as soon as it is in
//! ([`Event::DataHead`]), every chunk of samples is handed over as it arrives
//! ([`Event::Data`], bytes of the caller's own input), and [`Event::DataEnd`] says the checksum
//! matched. Until then the samples are unchecked: a caller that reduces them on the fly must
//! throw its result away on [`Event::Dropped`]. So the decoder holds 42 bytes, not 1224.
//!
//! **Resync.** Bytes outside a frame are skipped and counted until the next `'B' 'R'`. A header
//! announcing more than [`MAX_PAYLOAD`] is refused at once and the hunt goes on from the byte
//! after its `'B'` (the header's other bytes are looked at again). A frame whose checksum fails
//! is dropped and counted, and the hunt goes on after it: its samples were not kept, so a
//! frame start hidden inside a corrupted frame is lost with it (the next one is found).
//! A `device_data` whose head is refused (its data length disagrees with the payload length, or
//! a field is out of range) is still read to its checksum, so the stream stays in step.
//!
//! **Cost.** O(1) per byte; samples are summed in one pass over each chunk.

use super::frame::Header;
use super::ping360::{DeviceDataHead, DEVICE_DATA_HEAD_LEN};
use super::{id, Error, HEADER_LEN, MAX_PAYLOAD, START};

/// Longest payload kept whole for [`Decoder::payload`]: every message of
/// [`super::Message`] but `device_data` (whose samples stream through) and long `nack` texts.
pub const SMALL_PAYLOAD: usize = 32;

/// What the bytes fed so far amount to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// Nothing complete yet (all the input was consumed).
    Nothing,
    /// A frame whose checksum matched (not a `device_data`); its payload is
    /// [`Decoder::payload`].
    Frame(Header),
    /// A `device_data`'s head: samples follow.
    DataHead(Header, DeviceDataHead),
    /// The last this-many bytes consumed are samples of the `device_data` in progress
    /// (unchecked until [`Event::DataEnd`]).
    Data(usize),
    /// The `device_data` in progress is complete and its checksum matched.
    DataEnd(Header),
    /// The frame in progress was dropped: [`Error::Checksum`], [`Error::Oversize`], or the
    /// reason its `device_data` head was refused.
    Dropped(Error),
}

/// What the decoder dropped and accepted, since it was made. Saturating.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DecoderCounters {
    /// Frames whose checksum matched (refused `device_data` heads not included).
    pub frames: u32,
    /// Frames dropped for a checksum mismatch.
    pub checksum: u32,
    /// Headers refused for announcing more than [`MAX_PAYLOAD`] bytes.
    pub oversize: u32,
    /// `device_data` frames whose head was refused (the checksum matched).
    pub malformed: u32,
    /// Bytes skipped while hunting for `'B' 'R'` (line noise, the rest of a refused header).
    pub skipped: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// Looking for `'B'`.
    Hunt,
    /// Got `'B'`, want `'R'`.
    Start2,
    /// Header bytes in so far (2 ..= 7).
    Header(u8),
    /// Payload bytes in so far (kept up to [`SMALL_PAYLOAD`]).
    Payload(u16),
    /// `device_data` samples still to come; `stream`: hand them over (the head was accepted).
    Data { left: u16, stream: bool },
    /// Checksum bytes in so far (0 or 1) and the first one.
    Checksum(u8, u8),
}

/// The stream decoder. 42 bytes of buffers; no heap.
#[derive(Clone, Debug)]
pub struct Decoder {
    state: State,
    header: [u8; HEADER_LEN],
    head: Header,
    buf: [u8; SMALL_PAYLOAD],
    sum: u16,
    /// Why the `device_data` in progress will be dropped, if its head was refused.
    refused: Option<Error>,
    counters: DecoderCounters,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

fn bump(c: &mut u32) {
    *c = c.saturating_add(1);
}

impl Decoder {
    /// A decoder hunting for the first frame.
    pub const fn new() -> Self {
        Decoder {
            state: State::Hunt,
            header: [0; HEADER_LEN],
            head: Header {
                payload_len: 0,
                message_id: 0,
                src: 0,
                dst: 0,
            },
            buf: [0; SMALL_PAYLOAD],
            sum: 0,
            refused: None,
            counters: DecoderCounters {
                frames: 0,
                checksum: 0,
                oversize: 0,
                malformed: 0,
                skipped: 0,
            },
        }
    }

    /// Its counters.
    pub fn counters(&self) -> &DecoderCounters {
        &self.counters
    }

    /// The payload of the last [`Event::Frame`]; `None` if it was longer than
    /// [`SMALL_PAYLOAD`] (only its checksum was checked).
    pub fn payload(&self) -> Option<&[u8]> {
        self.buf.get(..usize::from(self.head.payload_len))
    }

    /// Feeds bytes until an event other than [`Event::Nothing`] happens or the input runs out.
    /// Returns how many bytes were consumed and the event; feed the rest again.
    pub fn feed(&mut self, bytes: &[u8]) -> (usize, Event) {
        let mut i = 0;
        while let Some(rest) = bytes.get(i..).filter(|r| !r.is_empty()) {
            if let State::Data { left, stream } = self.state {
                let n = usize::from(left).min(rest.len());
                let chunk = rest.get(..n).unwrap_or(&[]);
                self.sum = chunk
                    .iter()
                    .fold(self.sum, |s, &b| s.wrapping_add(u16::from(b)));
                // n ≤ left, a u16.
                let left = left - n as u16;
                self.state = if left == 0 {
                    State::Checksum(0, 0)
                } else {
                    State::Data { left, stream }
                };
                i += n;
                if stream && n > 0 {
                    return (i, Event::Data(n));
                }
                continue;
            }
            let b = rest.first().copied().unwrap_or(0);
            i += 1;
            let ev = self.byte(b);
            if ev != Event::Nothing {
                return (i, ev);
            }
        }
        (i, Event::Nothing)
    }

    /// One byte outside a `device_data`'s samples.
    fn byte(&mut self, b: u8) -> Event {
        match self.state {
            State::Hunt => {
                if b == START[0] {
                    self.state = State::Start2;
                } else {
                    bump(&mut self.counters.skipped);
                }
                Event::Nothing
            }
            State::Start2 => {
                if b == START[1] {
                    self.header[0] = START[0];
                    self.header[1] = START[1];
                    self.state = State::Header(2);
                } else {
                    // The 'B' was noise; this byte may start a frame.
                    bump(&mut self.counters.skipped);
                    self.state = State::Hunt;
                    return self.byte(b);
                }
                Event::Nothing
            }
            State::Header(got) => {
                if let Some(slot) = self.header.get_mut(usize::from(got)) {
                    *slot = b;
                }
                let got = got + 1;
                if usize::from(got) < HEADER_LEN {
                    self.state = State::Header(got);
                    return Event::Nothing;
                }
                self.start_payload()
            }
            State::Payload(got) => {
                self.sum = self.sum.wrapping_add(u16::from(b));
                if let Some(slot) = self.buf.get_mut(usize::from(got)) {
                    *slot = b;
                }
                let got = got.saturating_add(1);
                if self.head.message_id == id::DEVICE_DATA
                    && usize::from(got) == DEVICE_DATA_HEAD_LEN
                {
                    return self.start_data();
                }
                self.state = if got >= self.head.payload_len {
                    State::Checksum(0, 0)
                } else {
                    State::Payload(got)
                };
                Event::Nothing
            }
            // Handled in `feed`; unreachable here, but harmless.
            State::Data { .. } => Event::Nothing,
            State::Checksum(0, _) => {
                self.state = State::Checksum(1, b);
                Event::Nothing
            }
            State::Checksum(_, lo) => {
                self.state = State::Hunt;
                self.end_frame(u16::from_le_bytes([lo, b]))
            }
        }
    }

    /// The header is in: check it, then expect the payload.
    fn start_payload(&mut self) -> Event {
        match Header::parse(&self.header) {
            Ok(h) => {
                self.head = h;
                self.sum = super::checksum(&self.header);
                self.refused = None;
                self.state = if h.payload_len == 0 {
                    State::Checksum(0, 0)
                } else {
                    State::Payload(0)
                };
                Event::Nothing
            }
            Err(e) => {
                // Only Oversize can happen (the start bytes were matched). Look again at the
                // header's bytes after its 'B': one of them may start the real frame. Seven
                // bytes cannot complete a header, so this does not recurse further.
                bump(&mut self.counters.oversize);
                bump(&mut self.counters.skipped);
                self.state = State::Hunt;
                let again = self.header;
                for &b in again.iter().skip(1) {
                    self.byte(b);
                }
                Event::Dropped(e)
            }
        }
    }

    /// A `device_data`'s head is in: parse it and stream (or skip) the samples.
    fn start_data(&mut self) -> Event {
        let len = usize::from(self.head.payload_len);
        let data_left = len.saturating_sub(DEVICE_DATA_HEAD_LEN);
        // payload_len ≤ MAX_PAYLOAD (checked with the header), so this fits a u16.
        let left = data_left.min(MAX_PAYLOAD) as u16;
        let head = self
            .buf
            .get(..DEVICE_DATA_HEAD_LEN)
            .ok_or(Error::Length)
            .and_then(|h| DeviceDataHead::parse(h, len));
        let stream = head.is_ok();
        self.refused = head.err();
        self.state = if left == 0 {
            State::Checksum(0, 0)
        } else {
            State::Data { left, stream }
        };
        match head {
            Ok(h) => Event::DataHead(self.head, h),
            Err(_) => Event::Nothing,
        }
    }

    /// The checksum is in.
    fn end_frame(&mut self, got: u16) -> Event {
        if got != self.sum {
            bump(&mut self.counters.checksum);
            return Event::Dropped(Error::Checksum);
        }
        if let Some(e) = self.refused.take() {
            bump(&mut self.counters.malformed);
            return Event::Dropped(e);
        }
        bump(&mut self.counters.frames);
        if self.head.message_id == id::DEVICE_DATA {
            Event::DataEnd(self.head)
        } else {
            Event::Frame(self.head)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{emit_frame, GeneralRequestRepr, Message};
    use super::super::{DeviceDataRepr, PingSettings};
    use super::*;
    extern crate std;
    use std::vec::Vec;

    const GENERAL_REQUEST_5: [u8; 12] = [
        0x42, 0x52, 0x02, 0x00, 0x06, 0x00, 0x00, 0x00, 0x05, 0x00, 0xa1, 0x00,
    ];

    fn device_data(angle: u16, data: &[u8]) -> Vec<u8> {
        let m = Message::DeviceData(DeviceDataRepr {
            settings: PingSettings {
                mode: 1,
                gain_setting: 0,
                angle,
                transmit_duration: 16,
                sample_period: 90,
                transmit_frequency: 1000,
                number_of_samples: data.len() as u16,
            },
            data,
        });
        let mut buf = std::vec![0u8; 2000];
        let n = emit_frame(&m, 2, 0, &mut buf).unwrap();
        buf.truncate(n);
        buf
    }

    /// Everything the decoder says about `input`, fed in chunks of `chunk` bytes: events, and
    /// the samples it streamed (per device_data that ended well).
    fn run(d: &mut Decoder, input: &[u8], chunk: usize) -> (Vec<Event>, Vec<Vec<u8>>) {
        let (mut events, mut done, mut cur) = (Vec::new(), Vec::new(), Vec::new());
        for piece in input.chunks(chunk) {
            let mut rest = piece;
            while !rest.is_empty() {
                let (n, ev) = d.feed(rest);
                let (used, tail) = rest.split_at(n);
                match ev {
                    Event::Data(k) => cur.extend_from_slice(&used[n - k..]),
                    Event::DataHead(..) => cur.clear(),
                    Event::DataEnd(_) => done.push(std::mem::take(&mut cur)),
                    _ => {}
                }
                if ev != Event::Nothing {
                    events.push(ev);
                }
                rest = tail;
            }
        }
        (events, done)
    }

    #[test]
    fn a_small_frame_any_chunking() {
        for chunk in [1, 2, 5, 64] {
            let mut d = Decoder::new();
            let (ev, _) = run(&mut d, &GENERAL_REQUEST_5, chunk);
            assert_eq!(
                ev,
                [Event::Frame(Header {
                    payload_len: 2,
                    message_id: 6,
                    src: 0,
                    dst: 0
                })]
            );
            assert_eq!(d.payload(), Some(&[5u8, 0][..]));
            assert_eq!(
                Message::parse(6, d.payload().unwrap()),
                Ok(Message::GeneralRequest(GeneralRequestRepr {
                    requested_id: 5
                }))
            );
            assert_eq!(d.counters().frames, 1);
        }
    }

    #[test]
    fn device_data_streams_its_samples() {
        let samples: Vec<u8> = (0..1200u32).map(|i| (i * 7 % 251) as u8).collect();
        let frame = device_data(150, &samples);
        assert_eq!(frame.len(), 8 + 14 + 1200 + 2);
        for chunk in [1, 3, 64, 4096] {
            let mut d = Decoder::new();
            let (ev, done) = run(&mut d, &frame, chunk);
            assert!(matches!(ev[0], Event::DataHead(h, dh)
                if h.message_id == 2300 && dh.settings.angle == 150 && dh.data_len == 1200));
            assert!(matches!(ev.last(), Some(Event::DataEnd(_))));
            assert_eq!(done, core::slice::from_ref(&samples));
        }
    }

    #[test]
    fn garbage_between_frames_is_skipped_and_counted() {
        let mut input = b"xxBBRx\x42".to_vec();
        input.extend_from_slice(&GENERAL_REQUEST_5);
        input.extend_from_slice(b"noise");
        input.extend_from_slice(&device_data(7, &[1, 2, 3]));
        let mut d = Decoder::new();
        let (ev, done) = run(&mut d, &input, 3);
        // "xxBBRx" is noise, but its "BR" starts a header whose length ("x\x42") is 0x4278:
        // oversize, refused; the rescan finds the real frame's 'B' 'R' inside that header.
        assert_eq!(ev[0], Event::Dropped(Error::Oversize));
        assert!(matches!(ev[1], Event::Frame(h) if h.message_id == 6));
        assert_eq!(done, [std::vec![1, 2, 3]]);
        let c = *d.counters();
        assert_eq!((c.frames, c.checksum, c.oversize), (2, 0, 1));
        // x, x, B (then "BR" starts the refused header), its B, R, x, 0x42, and "noise".
        assert_eq!(c.skipped, 3 + 4 + 5, "{c:?}");
    }

    #[test]
    fn a_bad_checksum_drops_the_frame_and_the_next_one_is_found() {
        let good = device_data(10, &[9; 300]);
        let mut bad = good.clone();
        bad[100] ^= 0x10;
        let mut input = bad.clone();
        input.extend_from_slice(&good);
        let mut d = Decoder::new();
        let (ev, done) = run(&mut d, &input, 7);
        assert!(ev.contains(&Event::Dropped(Error::Checksum)));
        assert_eq!(done.len(), 1);
        assert_eq!(d.counters().checksum, 1);
        assert_eq!(d.counters().frames, 1);
        // A corrupted checksum byte itself: the same.
        let mut bad = good.clone();
        let last = bad.len() - 1;
        bad[last] ^= 1;
        let mut d = Decoder::new();
        let (ev, _) = run(&mut d, &bad, 1);
        assert_eq!(ev.last(), Some(&Event::Dropped(Error::Checksum)));
    }

    #[test]
    fn an_oversize_header_is_refused_and_rescanned() {
        // 'B' 'R' then a length of 0xFFFF, and inside the refused header a real frame begins.
        let mut input = std::vec![0x42, 0x52, 0xFF, 0xFF];
        input.extend_from_slice(&GENERAL_REQUEST_5);
        let mut d = Decoder::new();
        let (ev, _) = run(&mut d, &input, 1);
        assert_eq!(ev[0], Event::Dropped(Error::Oversize));
        assert!(matches!(ev[1], Event::Frame(h) if h.message_id == 6));
        assert_eq!(d.counters().oversize, 1);
    }

    #[test]
    fn a_device_data_with_a_refused_head_stays_in_step() {
        let mut f = device_data(10, &[1, 2, 3, 4]);
        f[8 + 2] = 0x90;
        f[8 + 3] = 0x01; // angle 400
        let sum = super::super::checksum(&f[..f.len() - 2]);
        let n = f.len();
        f[n - 2..].copy_from_slice(&sum.to_le_bytes());
        let mut input = f.clone();
        input.extend_from_slice(&GENERAL_REQUEST_5);
        let mut d = Decoder::new();
        let (ev, done) = run(&mut d, &input, 5);
        assert_eq!(ev[0], Event::Dropped(Error::Field("angle")));
        assert!(matches!(ev[1], Event::Frame(_)));
        assert!(done.is_empty());
        assert_eq!(d.counters().malformed, 1);
        assert_eq!(d.counters().skipped, 0);
    }

    #[test]
    fn a_long_payload_is_checked_but_not_kept() {
        let text = [b'x'; 40];
        let m = Message::Nack(super::super::NackRepr {
            nacked_id: 2601,
            text: &text,
        });
        let mut buf = [0u8; 64];
        let n = emit_frame(&m, 2, 0, &mut buf).unwrap();
        let mut d = Decoder::new();
        let (ev, _) = run(&mut d, &buf[..n], 8);
        assert!(matches!(ev[..], [Event::Frame(h)] if h.payload_len == 42));
        assert_eq!(d.payload(), None);
    }

    #[test]
    fn any_bytes_never_panic_and_every_byte_is_accounted_for() {
        let mut rng = crate::math::XorShift32::new(7);
        let mut d = Decoder::new();
        let mut input = Vec::new();
        for _ in 0..20_000 {
            input.push((rng.next_u32() >> 24) as u8);
            if rng.next_u32().is_multiple_of(500) {
                input.extend_from_slice(&device_data(3, &[5; 50]));
            }
        }
        let (_, done) = run(&mut d, &input, 13);
        assert!(!done.is_empty());
        assert!(d.counters().skipped > 10_000);
    }
}
