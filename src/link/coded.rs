//! The coded frame: how frames to the firmware survive bit errors (`docs/protocol.md` §1).
//!
//! ```text
//! raw frame R (L bytes):   header | payload | CRC            (as every frame)
//! codeword C:              R | parity of block 0 | … | parity of block B−1
//! on the wire:             zero-substitute( whiten(C) ) | 0x00
//! ```
//!
//! - **Blocks.** R is cut into B = ⌈L / 239⌉ interleaved blocks — byte i of R belongs to block
//!   i mod B — and each gets the 16 parity bytes of RS(255, 239) ([`super::reed_solomon`]), so
//!   up to 8 wrong bytes per block are corrected. Interleaving spreads a burst of errors over
//!   the blocks. A scanline of 300 bins (328 raw bytes) is two blocks, 32 parity bytes.
//! - **Whitening.** C is XORed with the PN9 sequence (x⁹ + x⁵ + 1, all ones at the start,
//!   least significant bit first: `ff e1 1d 9a ed 85 33 24 …`, the data whitening of TI's
//!   CC1101 radios, design note DN509). Sonar bins are mostly small numbers with one bit set
//!   (1, 2, 4, 8); one flipped bit turns such a byte into 0x00, the delimiter, and cuts the
//!   frame in two. Whitened bytes are near uniform: 8 in 256 are one flip from 0x00.
//! - **Zero substitution.** 0x00 must not occur inside a frame. The whitened codeword is sent
//!   in chunks of up to 254 bytes, each preceded by its *key*: a non-zero byte value that does
//!   not occur in the chunk (there always is one: 255 candidates, at most 254 bytes). Each
//!   0x00 of the chunk is sent as the key. Unlike COBS, this keeps every byte in its place:
//!   a wrong byte on the wire is one wrong byte of the codeword, which the code corrects. A wrong
//!   key turns the chunk's zeros and the bytes equal to the new key into errors: after
//!   whitening, about two per chunk, which the code corrects too.
//!
//! The wire length gives the codeword length, which gives L and B: no length field is needed,
//! and a length the encoder cannot produce is a framing error.
//!
//! Nothing here allocates or panics; the decoder undoes the substitution and whitening
//! ([`unsubstitute_in_place`]) and corrects the blocks ([`correct`]) in place once the frame has
//! ended.

use super::reed_solomon::{self, Block, Uncorrectable, MAX_DATA, PARITY};
use super::Error;

/// Codeword bytes per chunk after a key.
pub const CHUNK: usize = 254;

/// Blocks of a raw frame of `raw_len` bytes (at least one).
pub const fn blocks(raw_len: usize) -> usize {
    if raw_len == 0 {
        1
    } else {
        raw_len.div_ceil(MAX_DATA)
    }
}

/// Codeword length of a raw frame of `raw_len` bytes: the frame and its parity.
pub const fn codeword_len(raw_len: usize) -> usize {
    raw_len + PARITY * blocks(raw_len)
}

/// Wire length of a codeword of `n` bytes, keys included, delimiter excluded.
pub const fn wire_len(n: usize) -> usize {
    n + n.div_ceil(CHUNK)
}

/// The raw frame's length for a codeword of `n` bytes, if an encoder can produce that length.
pub const fn raw_len_of(n: usize) -> Option<usize> {
    // blocks(L) is non-decreasing in L, so at most one block count fits.
    let mut b = 1;
    while b * PARITY < n {
        let raw = n - b * PARITY;
        if blocks(raw) == b {
            return Some(raw);
        }
        b += 1;
    }
    None
}

/// The PN9 whitening sequence, a byte at a time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pn9(u16);

impl Default for Pn9 {
    fn default() -> Self {
        Pn9::new()
    }
}

impl Pn9 {
    /// At the start of a frame: all nine bits set.
    pub const fn new() -> Self {
        Pn9(0x1FF)
    }

    /// The next byte of the sequence.
    pub fn next_byte(&mut self) -> u8 {
        // Bit k of the state is sequence bit n + k (k = 0 ..= 8), and b(n+9) = b(n) ⊕ b(n+5):
        // eight steps at once, four bits at a time (the second four use the first).
        let s = self.0;
        let lo = (s ^ (s >> 5)) & 0xF;
        let hi = ((s >> 4) ^ lo) & 0xF;
        self.0 = ((s >> 8) & 1) | (lo << 1) | (hi << 5);
        s as u8
    }
}

/// Undoes zero substitution and whitening in place: `wire` is a coded frame's bytes without
/// the delimiter (no 0x00 among them); the codeword is then `wire[.. n]`. Returns `n`, or
/// [`Error::CodedLength`] if the wire length is not one the encoder produces (a last chunk
/// with its key alone). A few operations a byte, in one pass.
pub fn unsubstitute_in_place(wire: &mut [u8]) -> Result<usize, Error> {
    let mut white = Pn9::new();
    let mut n = 0usize;
    let mut at = 0usize;
    while let Some(&key) = wire.get(at) {
        let len = (wire.len() - at - 1).min(CHUNK);
        // The chunk's bytes move over its key (and the keys before it): n < at + 1 + k.
        for k in at + 1..at + 1 + len {
            let b = wire.get(k).copied().unwrap_or(0);
            let c = if b == key { 0 } else { b };
            if let Some(out) = wire.get_mut(n) {
                *out = c ^ white.next_byte();
            }
            n += 1;
        }
        at += 1 + len;
    }
    if wire_len(n) != wire.len() {
        return Err(Error::CodedLength);
    }
    Ok(n)
}

/// Block `index` of a codeword laid out as the encoder does: its data bytes every `blocks`
/// bytes of the raw frame, its parity after the raw frame.
struct Interleaved<'a> {
    codeword: &'a mut [u8],
    raw_len: usize,
    blocks: usize,
    index: usize,
    data: usize,
}

impl Interleaved<'_> {
    fn at(&self, i: usize) -> usize {
        if i < self.data {
            self.index + i * self.blocks
        } else {
            self.raw_len + PARITY * self.index + (i - self.data)
        }
    }
}

impl Block for Interleaved<'_> {
    fn size(&self) -> usize {
        self.data + PARITY
    }
    fn byte(&self, i: usize) -> u8 {
        self.codeword.get(self.at(i)).copied().unwrap_or(0)
    }
    fn correct(&mut self, i: usize, error: u8) {
        let at = self.at(i);
        if let Some(b) = self.codeword.get_mut(at) {
            *b ^= error;
        }
    }
}

/// Data bytes of block `index` of `blocks` over `raw_len` bytes.
const fn block_data(raw_len: usize, blocks: usize, index: usize) -> usize {
    if index >= raw_len {
        0
    } else {
        (raw_len - index).div_ceil(blocks)
    }
}

/// Corrects a codeword (whitening and substitution already undone) in place; its raw frame is
/// then `codeword[.. raw_len]`. Returns the bytes corrected, or [`Uncorrectable`] if a block
/// had too many errors (blocks before it may have been corrected already). Not inlined: its
/// workspace (syndromes, locator, error positions: about 150 bytes) stays off the stack frames
/// of the callers, which run the sonar extraction after it.
#[inline(never)]
pub fn correct(codeword: &mut [u8], raw_len: usize) -> Result<usize, Uncorrectable> {
    let blocks = blocks(raw_len);
    if codeword.len() != codeword_len(raw_len) {
        return Err(Uncorrectable);
    }
    let mut fixed = 0;
    for index in 0..blocks {
        let mut block = Interleaved {
            data: block_data(raw_len, blocks, index),
            codeword: &mut *codeword,
            raw_len,
            blocks,
            index,
        };
        fixed += reed_solomon::correct(&mut block)?;
    }
    Ok(fixed)
}

/// Codes the `raw_len`-byte raw frame at `buf[start ..]` into `buf[0 ..]` (parity, whitening,
/// zero substitution; no delimiter) and returns the wire length. The parity is appended after
/// the raw frame first, so `buf` needs `start + codeword_len(raw_len)` bytes, and `start` must
/// be at least the number of chunks (1 + ⌊n / 254⌋ always is), else
/// [`Error::BufferTooSmall`]. Not inlined, so that the firmware's periodic task, which sends
/// only frames to the host, does not carry its workspace in its stack frame.
#[inline(never)]
pub(crate) fn encode_in_place(
    buf: &mut [u8],
    start: usize,
    raw_len: usize,
) -> Result<usize, Error> {
    let n = codeword_len(raw_len);
    let chunks = n.div_ceil(CHUNK);
    let region = buf
        .get_mut(start..)
        .and_then(|r| r.get_mut(..n))
        .ok_or(Error::BufferTooSmall)?;
    if start < chunks {
        return Err(Error::BufferTooSmall);
    }
    let blocks = blocks(raw_len);
    for index in 0..blocks {
        let data = block_data(raw_len, blocks, index);
        let p = reed_solomon::parity_by_table(
            (0..data).map(|i| region.get(index + i * blocks).copied().unwrap_or(0)),
        );
        let at = raw_len + PARITY * index;
        region
            .get_mut(at..at + PARITY)
            .ok_or(Error::BufferTooSmall)?
            .copy_from_slice(&p);
    }
    let mut white = Pn9::new();
    for b in region.iter_mut() {
        *b ^= white.next_byte();
    }
    // Zero substitution towards the front: chunk c's key goes to 255·c and its bytes after it,
    // never past a byte not yet read (start ≥ chunks).
    for c in 0..chunks {
        let from = start + c * CHUNK;
        let len = CHUNK.min(n - c * CHUNK);
        let key = key_for(buf.get(from..from + len).ok_or(Error::BufferTooSmall)?);
        let out = c * (CHUNK + 1);
        *buf.get_mut(out).ok_or(Error::BufferTooSmall)? = key;
        for k in 0..len {
            let b = buf.get(from + k).copied().ok_or(Error::BufferTooSmall)?;
            *buf.get_mut(out + 1 + k).ok_or(Error::BufferTooSmall)? = if b == 0 { key } else { b };
        }
    }
    Ok(wire_len(n))
}

/// The largest non-zero byte value that does not occur in `chunk` (≤ 254 bytes, so there is
/// one; it has many bits set, so a flipped bit seldom makes it 0x00).
fn key_for(chunk: &[u8]) -> u8 {
    let mut present = [0u32; 8];
    for &b in chunk {
        if let Some(w) = present.get_mut(usize::from(b >> 5)) {
            *w |= 1 << (b & 31);
        }
    }
    (1..=255u8)
        .rev()
        .find(|&v| {
            present
                .get(usize::from(v >> 5))
                .is_some_and(|w| w & (1 << (v & 31)) == 0)
        })
        .unwrap_or(0xFF)
}

/// Decodes one coded frame in place (`wire`: its bytes without the delimiter): the corrected
/// raw frame is then `wire[.. raw_len]`. Returns `(raw_len, bytes corrected)`;
/// [`Error::Cobs`] for a 0x00 inside, [`Error::CodedLength`] for a length the encoder cannot
/// produce, [`Error::Uncorrectable`] for too many errors.
pub fn decode_in_place(wire: &mut [u8]) -> Result<(usize, usize), Error> {
    if wire.contains(&0) {
        return Err(Error::Cobs);
    }
    let n = unsubstitute_in_place(wire)?;
    let raw_len = raw_len_of(n).ok_or(Error::CodedLength)?;
    let codeword = wire.get_mut(..n).ok_or(Error::CodedLength)?;
    let fixed = correct(codeword, raw_len).map_err(|_| Error::Uncorrectable)?;
    Ok((raw_len, fixed))
}

/// Codes a raw frame (header, payload, CRC) into `out` (no delimiter); returns the wire
/// length. For hosts and tests that build raw frames themselves (`encode_frame` does all of
/// it from a message).
pub fn encode(raw: &[u8], out: &mut [u8]) -> Result<usize, Error> {
    let start = 1 + out.len() / CHUNK;
    out.get_mut(start..start + raw.len())
        .ok_or(Error::BufferTooSmall)?
        .copy_from_slice(raw);
    encode_in_place(out, start, raw.len())
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use proptest::prelude::*;
    use std::vec::Vec;

    fn enc(raw: &[u8]) -> Vec<u8> {
        let mut out = std::vec![0u8; wire_len(codeword_len(raw.len())) + 4];
        let n = encode(raw, &mut out).unwrap();
        out.truncate(n);
        out
    }

    /// Wire bytes to the corrected raw frame, as the stream decoder does it.
    fn dec(wire: &[u8]) -> Result<(Vec<u8>, usize), Uncorrectable> {
        let mut cw = wire.to_vec();
        let n = unsubstitute_in_place(&mut cw).map_err(|_| Uncorrectable)?;
        cw.truncate(n);
        let raw_len = raw_len_of(cw.len()).ok_or(Uncorrectable)?;
        let fixed = correct(&mut cw, raw_len)?;
        cw.truncate(raw_len);
        Ok((cw, fixed))
    }

    /// TI design note DN509 lists the PN9 sequence's first bytes.
    #[test]
    fn pn9_is_the_cc1101_whitening_sequence() {
        let mut w = Pn9::new();
        let got: Vec<u8> = (0..16).map(|_| w.next_byte()).collect();
        assert_eq!(
            got,
            [
                0xff, 0xe1, 0x1d, 0x9a, 0xed, 0x85, 0x33, 0x24, 0xea, 0x7a, 0xd2, 0x39, 0x70, 0x97,
                0x57, 0x0a
            ]
        );
        // Period 511 bits: the byte sequence repeats after 511 bytes.
        let mut w = Pn9::new();
        let a: Vec<u8> = (0..1022).map(|_| w.next_byte()).collect();
        assert_eq!(a[..511], a[511..]);
    }

    #[test]
    fn lengths_round_trip_and_gaps_are_refused() {
        for raw in 1..=700 {
            let n = codeword_len(raw);
            assert_eq!(raw_len_of(n), Some(raw), "{raw}");
        }
        // 240 raw bytes take two blocks: codewords of 256 ..= 271 bytes cannot happen.
        assert_eq!(codeword_len(239), 255);
        assert_eq!(codeword_len(240), 272);
        assert!((256..272).all(|n| raw_len_of(n).is_none()));
        assert_eq!(raw_len_of(16), None);
        assert_eq!(raw_len_of(0), None);
        // The longest frame: 663 raw bytes, three blocks, three chunks.
        assert_eq!(codeword_len(663), 711);
        assert_eq!(wire_len(711), 714);
    }

    #[test]
    fn the_wire_has_no_zero_and_decodes_back() {
        for raw in [
            std::vec![0u8; 6],
            (0..=255u8).collect::<Vec<u8>>(),
            std::vec![0xFFu8; 663],
            // Bytes equal to the whitening sequence whiten to zeros.
            {
                let mut w = Pn9::new();
                (0..300).map(|_| w.next_byte()).collect()
            },
        ] {
            let wire = enc(&raw);
            assert!(!wire.contains(&0));
            assert_eq!(wire.len(), wire_len(codeword_len(raw.len())));
            assert_eq!(dec(&wire), Ok((raw, 0)));
        }
    }

    #[test]
    fn a_wrong_key_is_corrected_too() {
        let raw: Vec<u8> = (0..328).map(|i| (i % 9) as u8).collect();
        let mut wire = enc(&raw);
        wire[0] ^= 0x10;
        wire[255] ^= 0x01;
        assert_eq!(dec(&wire).map(|(r, _)| r), Ok(raw));
    }

    #[test]
    fn encoding_refuses_small_buffers() {
        let raw = [1u8; 100];
        let mut out = [0u8; 110];
        assert_eq!(encode(&raw, &mut out), Err(Error::BufferTooSmall));
        let mut buf = [0u8; 200];
        assert_eq!(encode_in_place(&mut buf, 0, 10), Err(Error::BufferTooSmall));
    }

    proptest! {
        #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

        /// Up to eight corrupted wire bytes in each block's share survive; here, up to eight in
        /// the whole frame, keys aside (a wrong key adds errors of its own: tested above).
        #[test]
        fn corrupted_bytes_are_corrected(
            raw in proptest::collection::vec(any::<u8>(), 6..=663),
            hits in proptest::collection::vec((any::<usize>(), 1u8..=255), 0..=8),
        ) {
            let mut wire = enc(&raw);
            for (pos, e) in hits {
                let i = pos % wire.len();
                if i.is_multiple_of(CHUNK + 1) {
                    continue;
                }
                // A byte that becomes 0x00 would end the frame: that is the delimiter's business.
                if wire[i] ^ e != 0 {
                    wire[i] ^= e;
                }
            }
            let got = dec(&wire);
            prop_assert_eq!(got.map(|(r, _)| r), Ok(raw));
        }

        #[test]
        fn arbitrary_wire_bytes_never_panic(bytes in proptest::collection::vec(1u8..=255, 0..800)) {
            let _ = dec(&bytes);
        }
    }
}
