//! CRC-16/CCITT-FALSE, the frame check sequence.
//!
//! Parameters (Williams' model, as in the CRC catalogue): width 16, poly 0x1021, init 0xFFFF,
//! refin false, refout false, xorout 0x0000, **check 0x29B1** (the CRC of ASCII "123456789").
//! It is what Python's `binascii.crc_hqx(data, 0xFFFF)` computes.
//!
//! Why this one: a 16-bit CRC detects every error burst up to 16 bits and, for frames up to
//! 4 kB, every error of up to three bits, which covers our frames (at most
//! [`MAX_RAW`](super::MAX_RAW) bytes) with two bytes of overhead.
//!
//! **Table-free.** The byte-wise update below (the shift-and-xor form of the 0x1021 polynomial
//! used by XMODEM implementations) costs about ten ALU operations per byte and no flash for a
//! table; its equality with the bit-by-bit definition is tested on all bytes from all states.
//!
//! On the wire the CRC follows the payload **little-endian**, like every other number.

/// The CRC of ASCII "123456789", the catalogue's check value.
pub const CHECK: u16 = 0x29B1;
/// The initial register value.
pub const INIT: u16 = 0xFFFF;
/// The generator polynomial x¹⁶ + x¹² + x⁵ + 1, MSB-first, without the x¹⁶ term.
pub const POLY: u16 = 0x1021;

/// An incremental CRC-16/CCITT-FALSE.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crc16 {
    state: u16,
}

impl Default for Crc16 {
    fn default() -> Self {
        Crc16::new()
    }
}

impl Crc16 {
    /// A CRC over no bytes yet.
    pub const fn new() -> Self {
        Crc16 { state: INIT }
    }

    /// Adds one byte.
    pub const fn update_byte(self, byte: u8) -> Self {
        let s = self.state;
        // x is the byte entering the register's top; its two nibbles fold in at bits 12, 5, 0.
        let mut x = (s >> 8) ^ byte as u16;
        x ^= x >> 4;
        Crc16 {
            state: (s << 8) ^ (x << 12) ^ (x << 5) ^ x,
        }
    }

    /// Adds bytes.
    pub fn update(self, bytes: &[u8]) -> Self {
        bytes.iter().fold(self, |c, &b| c.update_byte(b))
    }

    /// The CRC of the bytes added so far.
    pub const fn value(self) -> u16 {
        self.state
    }
}

/// The CRC-16/CCITT-FALSE of `bytes`.
pub fn crc16(bytes: &[u8]) -> u16 {
    Crc16::new().update(bytes).value()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The definition: shift the message through the register one bit at a time.
    fn bitwise(state: u16, byte: u8) -> u16 {
        let mut c = state ^ ((byte as u16) << 8);
        for _ in 0..8 {
            c = if c & 0x8000 != 0 {
                (c << 1) ^ POLY
            } else {
                c << 1
            };
        }
        c
    }

    #[test]
    fn check_value_is_the_catalogue_one() {
        assert_eq!(crc16(b"123456789"), CHECK);
        assert_eq!(CHECK, 0x29B1);
    }

    #[test]
    fn known_vectors() {
        // From Python's binascii.crc_hqx(data, 0xFFFF), an independent implementation.
        assert_eq!(crc16(b""), 0xFFFF);
        assert_eq!(crc16(&[0x00]), 0xE1F0);
        assert_eq!(crc16(&[0xFF, 0xFF]), 0x0000);
        assert_eq!(crc16(b"A"), 0xB915);
        assert_eq!(crc16(&[1, 2, 3]), 0xADAD);
    }

    #[test]
    fn bytewise_update_equals_bitwise_definition_everywhere() {
        // Every byte from a spread of register states (all 2^24 would be slow in debug).
        for s in (0..=u16::MAX)
            .step_by(97)
            .chain([0, 0xFFFF, 0x8000, 0x0001])
        {
            for b in 0..=255u8 {
                assert_eq!(
                    Crc16 { state: s }.update_byte(b).value(),
                    bitwise(s, b),
                    "state {s:#06x} byte {b:#04x}"
                );
            }
        }
    }

    #[test]
    fn incremental_equals_one_shot() {
        let data = b"the quick brown fox jumps over the lazy dog";
        let (a, b) = data.split_at(17);
        assert_eq!(Crc16::new().update(a).update(b).value(), crc16(data));
    }

    #[test]
    fn single_bit_flips_are_detected() {
        let data = *b"VPF frame under test, 32 bytes..";
        let good = crc16(&data);
        for i in 0..data.len() * 8 {
            let mut d = data;
            d[i / 8] ^= 1 << (i % 8);
            assert_ne!(crc16(&d), good, "bit {i}");
        }
    }
}
