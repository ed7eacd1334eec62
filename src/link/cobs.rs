//! Consistent Overhead Byte Stuffing (Cheshire & Baker, 1999): removes every 0x00 from a frame
//! so that 0x00 can delimit frames on the stream.
//!
//! The encoded frame is a sequence of blocks. A block is a code byte `c` (1..=255) followed by
//! `c − 1` non-zero data bytes; a block with `c < 255` stands for its data followed by a 0x00,
//! except the last block of the frame, whose implied 0x00 is dropped. A block with `c = 255`
//! has no implied 0x00 (254 bytes without a zero).
//!
//! The encoder here is the canonical one (as on Wikipedia's COBS page): when the data ends
//! exactly with a full 254-byte block, no empty block follows. The decoders accept that and the
//! variant with a trailing `0x01` alike. Overhead: at most one byte per 254 data bytes, at
//! least one; see [`max_encoded_len`].

use super::Error;

/// An upper bound on the COBS encoding of `n` bytes (without the delimiter):
/// `n + 1 + ⌊n / 254⌋`.
pub const fn max_encoded_len(n: usize) -> usize {
    n + 1 + n / 254
}

/// Byte access for the encoder, so one algorithm serves separate buffers and in-place use.
trait Io {
    fn read(&self, i: usize) -> Option<u8>;
    /// Writes `byte` at output position `pos`; `read_pos` is the source position of the byte
    /// most recently read (`usize::MAX` when all have been read).
    fn write(&mut self, pos: usize, byte: u8, read_pos: usize) -> Result<(), Error>;
}

struct Separate<'s, 'd> {
    src: &'s [u8],
    dst: &'d mut [u8],
}

impl Io for Separate<'_, '_> {
    fn read(&self, i: usize) -> Option<u8> {
        self.src.get(i).copied()
    }
    fn write(&mut self, pos: usize, byte: u8, _: usize) -> Result<(), Error> {
        *self.dst.get_mut(pos).ok_or(Error::BufferTooSmall)? = byte;
        Ok(())
    }
}

/// The source lies at `buf[start ..]`, the output grows from `buf[0]`.
struct InPlace<'b> {
    buf: &'b mut [u8],
    start: usize,
}

impl Io for InPlace<'_> {
    fn read(&self, i: usize) -> Option<u8> {
        self.buf.get(self.start.checked_add(i)?).copied()
    }
    fn write(&mut self, pos: usize, byte: u8, read_pos: usize) -> Result<(), Error> {
        // Never overwrite a source byte not yet read. With the source at offset
        // ≥ 1 + ⌊n/254⌋ this cannot happen (the output is then never ahead of the input);
        // the check makes a wrong offset an error instead of corrupt output.
        let read_abs = self.start.saturating_add(read_pos);
        if pos > read_abs {
            return Err(Error::BufferTooSmall);
        }
        *self.buf.get_mut(pos).ok_or(Error::BufferTooSmall)? = byte;
        Ok(())
    }
}

fn encode_with(io: &mut impl Io, n: usize) -> Result<usize, Error> {
    let mut code_pos = 0usize;
    let mut out = 1usize;
    let mut code = 1u8;
    for i in 0..n {
        let b = io.read(i).ok_or(Error::BufferTooSmall)?;
        if b != 0 {
            io.write(out, b, i)?;
            out = out.saturating_add(1);
            code = code.saturating_add(1);
        }
        if b == 0 || code == 0xFF {
            io.write(code_pos, code, i)?;
            code = 1;
            code_pos = out;
            // A full block at the very end needs no empty block after it.
            if b == 0 || i + 1 < n {
                out = out.saturating_add(1);
            }
        }
    }
    if code_pos < out {
        io.write(code_pos, code, usize::MAX)?;
    }
    Ok(out)
}

/// COBS-encodes `src` into `dst` (no delimiter is appended). Returns the encoded length, or
/// [`Error::BufferTooSmall`]; [`max_encoded_len`]`(src.len())` bytes always suffice.
pub fn encode(src: &[u8], dst: &mut [u8]) -> Result<usize, Error> {
    encode_with(&mut Separate { src, dst }, src.len())
}

/// COBS-encodes the `n` bytes at `buf[start ..]` into `buf[0 ..]`. `start` must be at least
/// `1 + ⌊n / 254⌋` (the most the output can get ahead of the input), else
/// [`Error::BufferTooSmall`].
pub(crate) fn encode_in_place(buf: &mut [u8], start: usize, n: usize) -> Result<usize, Error> {
    if start.checked_add(n).is_none_or(|end| end > buf.len()) {
        return Err(Error::BufferTooSmall);
    }
    encode_with(&mut InPlace { buf, start }, n)
}

/// Decodes one COBS frame (without its delimiter) from `src` into `dst`; returns the decoded
/// length. [`Error::Cobs`] if a block runs past the end or a 0x00 is inside;
/// [`Error::BufferTooSmall`] if `dst` is too short (`src.len()` bytes always suffice).
pub fn decode(src: &[u8], dst: &mut [u8]) -> Result<usize, Error> {
    let mut u = Unstuffer::new();
    let mut n = 0usize;
    for &b in src {
        if let Some(d) = u.push(b)? {
            *dst.get_mut(n).ok_or(Error::BufferTooSmall)? = d;
            n += 1;
        }
    }
    u.finish()?;
    Ok(n)
}

/// Decodes one COBS frame (without its delimiter) in place; returns the decoded length. The
/// decoded bytes are at `buf[.. len]`; the output never overtakes the input.
pub fn decode_in_place(buf: &mut [u8]) -> Result<usize, Error> {
    let mut u = Unstuffer::new();
    let mut n = 0usize;
    for i in 0..buf.len() {
        let b = buf.get(i).copied().ok_or(Error::Cobs)?;
        if let Some(d) = u.push(b)? {
            // n ≤ i: each input byte yields at most one output byte.
            *buf.get_mut(n).ok_or(Error::Cobs)? = d;
            n += 1;
        }
    }
    u.finish()?;
    Ok(n)
}

/// A byte-at-a-time COBS decoder: each encoded byte yields at most one decoded byte, so the
/// stream decoder can check its length bound before storing anything.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Unstuffer {
    /// Data bytes still due in the current block (0: the next byte is a code byte).
    left: u8,
    /// The current block implies a 0x00, emitted only if another block follows.
    zero_pending: bool,
}

impl Unstuffer {
    /// A decoder at the start of a frame.
    pub const fn new() -> Self {
        Unstuffer {
            left: 0,
            zero_pending: false,
        }
    }

    /// Takes the next encoded byte; returns the decoded byte it completes, if any. A 0x00
    /// (which must not occur inside a frame) is [`Error::Cobs`].
    pub fn push(&mut self, byte: u8) -> Result<Option<u8>, Error> {
        if byte == 0 {
            return Err(Error::Cobs);
        }
        if self.left == 0 {
            let out = self.zero_pending.then_some(0);
            self.zero_pending = byte != 0xFF;
            self.left = byte - 1;
            Ok(out)
        } else {
            self.left -= 1;
            Ok(Some(byte))
        }
    }

    /// Ends the frame: [`Error::Cobs`] if the last block is incomplete. Resets for the next.
    pub fn finish(&mut self) -> Result<(), Error> {
        let complete = self.left == 0;
        *self = Unstuffer::new();
        if complete {
            Ok(())
        } else {
            Err(Error::Cobs)
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use proptest::prelude::*;
    use std::vec::Vec;

    fn enc(src: &[u8]) -> Vec<u8> {
        let mut out = std::vec![0u8; max_encoded_len(src.len())];
        let n = encode(src, &mut out).unwrap();
        out.truncate(n);
        out
    }

    fn dec(src: &[u8]) -> Result<Vec<u8>, Error> {
        let mut out = std::vec![0u8; src.len()];
        let n = decode(src, &mut out)?;
        out.truncate(n);
        Ok(out)
    }

    /// The examples of the Wikipedia COBS article, checked by hand there.
    #[test]
    fn wikipedia_vectors() {
        let cases: &[(&[u8], &[u8])] = &[
            (&[], &[0x01]),
            (&[0x00], &[0x01, 0x01]),
            (&[0x00, 0x00], &[0x01, 0x01, 0x01]),
            (&[0x00, 0x11, 0x00], &[0x01, 0x02, 0x11, 0x01]),
            (&[0x11, 0x22, 0x00, 0x33], &[0x03, 0x11, 0x22, 0x02, 0x33]),
            (&[0x11, 0x22, 0x33, 0x44], &[0x05, 0x11, 0x22, 0x33, 0x44]),
            (&[0x11, 0x00, 0x00, 0x00], &[0x02, 0x11, 0x01, 0x01, 0x01]),
        ];
        for (raw, cobs) in cases {
            assert_eq!(enc(raw), *cobs, "{raw:02x?}");
            assert_eq!(dec(cobs).unwrap(), *raw, "{cobs:02x?}");
        }
    }

    #[test]
    fn wikipedia_long_vectors() {
        // 01 02 … FE (254 bytes) → FF 01 … FE: a full block, no empty block after it.
        let a: Vec<u8> = (0x01..=0xFE).collect();
        let mut want = std::vec![0xFF];
        want.extend(&a);
        assert_eq!(enc(&a), want);
        // 00 01 … FE (255 bytes) → 01 FF 01 … FE.
        let mut b = std::vec![0x00];
        b.extend(&a);
        let mut want = std::vec![0x01, 0xFF];
        want.extend(&a);
        assert_eq!(enc(&b), want);
        // 01 02 … FE FF (255 bytes) → FF 01 … FE 02 FF.
        let c: Vec<u8> = (0x01..=0xFF).collect();
        let mut want = std::vec![0xFF];
        want.extend(&a);
        want.extend([0x02, 0xFF]);
        assert_eq!(enc(&c), want);
        // 02 03 … FF 00 (255 bytes) → FF 02 … FF 01 01.
        let mut d: Vec<u8> = (0x02..=0xFF).collect();
        d.push(0x00);
        let mut want = std::vec![0xFF];
        want.extend(0x02..=0xFF);
        want.extend([0x01, 0x01]);
        assert_eq!(enc(&d), want);
        // 03 04 … FF 00 01 (255 bytes) → FE 03 … FF 02 01.
        let mut e: Vec<u8> = (0x03..=0xFF).collect();
        e.extend([0x00, 0x01]);
        let mut want = std::vec![0xFE];
        want.extend(0x03..=0xFF);
        want.extend([0x02, 0x01]);
        assert_eq!(enc(&e), want);
        for raw in [a, b, c, d, e] {
            assert_eq!(dec(&enc(&raw)).unwrap(), raw);
        }
    }

    #[test]
    fn decoder_accepts_the_trailing_empty_block_variant() {
        let a: Vec<u8> = (0x01..=0xFE).collect();
        let mut cobs = std::vec![0xFF];
        cobs.extend(&a);
        cobs.push(0x01);
        assert_eq!(dec(&cobs).unwrap(), a);
    }

    #[test]
    fn malformed_input_is_refused() {
        assert_eq!(dec(&[0x03, 0x11]), Err(Error::Cobs)); // block runs past the end
        assert_eq!(dec(&[0x02, 0x00]), Err(Error::Cobs)); // zero inside
        assert_eq!(dec(&[0x00]), Err(Error::Cobs));
        let mut small = [0u8; 1];
        assert_eq!(
            decode(&[0x03, 0x11, 0x22], &mut small),
            Err(Error::BufferTooSmall)
        );
        let mut small = [0u8; 4];
        assert_eq!(
            encode(&[1, 2, 3, 4], &mut small),
            Err(Error::BufferTooSmall)
        );
    }

    #[test]
    fn in_place_decoding_matches() {
        let mut buf = [0x03, 0x11, 0x22, 0x02, 0x33];
        let n = decode_in_place(&mut buf).unwrap();
        assert_eq!(&buf[..n], &[0x11, 0x22, 0x00, 0x33]);
    }

    #[test]
    fn in_place_encoding_refuses_a_short_offset() {
        // 300 non-zero bytes need an offset of 2; with 1 the output would overtake the input.
        let mut buf = std::vec![0u8; 400];
        for (i, b) in buf.iter_mut().enumerate().skip(1).take(300) {
            *b = (i % 200) as u8 + 1;
        }
        assert_eq!(
            encode_in_place(&mut buf, 1, 300),
            Err(Error::BufferTooSmall)
        );
        assert_eq!(
            encode_in_place(&mut buf, 390, 20),
            Err(Error::BufferTooSmall)
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

        #[test]
        fn round_trip_and_bounds(
            raw in prop_oneof![
                proptest::collection::vec(any::<u8>(), 0..800),
                proptest::collection::vec(1u8..=255, 0..800),
                proptest::collection::vec(prop_oneof![Just(0u8), 1u8..=255], 0..800),
            ]
        ) {
            let e = enc(&raw);
            prop_assert!(e.len() <= max_encoded_len(raw.len()));
            prop_assert!(e.len() > raw.len());
            prop_assert!(!e.contains(&0));
            prop_assert_eq!(dec(&e).unwrap(), raw.clone());
            // Incremental decoding gives the same bytes.
            let mut u = Unstuffer::new();
            let out: Vec<u8> = e.iter().filter_map(|&b| u.push(b).unwrap()).collect();
            prop_assert_eq!(u.finish(), Ok(()));
            prop_assert_eq!(&out, &raw);
            // In place, from the smallest allowed offset, equals the two-buffer encoding.
            let start = 1 + raw.len() / 254;
            let mut buf = std::vec![0xAAu8; start + raw.len() + 1];
            buf[start..start + raw.len()].copy_from_slice(&raw);
            let n = encode_in_place(&mut buf, start, raw.len()).unwrap();
            prop_assert_eq!(&buf[..n], &e[..]);
        }

        #[test]
        fn decoding_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
            let mut out = std::vec![0u8; bytes.len()];
            if let Ok(n) = decode(&bytes, &mut out) {
                // Whatever decodes re-encodes to something that decodes the same.
                let again = dec(&enc(&out[..n])).unwrap();
                prop_assert_eq!(&again[..], &out[..n]);
            }
            let mut copy = bytes.clone();
            let _ = decode_in_place(&mut copy);
        }
    }
}
