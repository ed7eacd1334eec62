//! Little-endian cursors over byte slices and the field checks every message shares.
//!
//! A [`Reader`] runs out with [`Error::Length`], a [`Writer`] with [`Error::BufferTooSmall`];
//! neither indexes, so no input can make them panic.

use super::layout::Field;
use super::{Error, Problem};
use crate::math::{Vec2, TAU};

/// Reads little-endian numbers from the front of a slice.
pub(crate) struct Reader<'a> {
    rest: &'a [u8],
}

impl<'a> Reader<'a> {
    pub(crate) fn new(bytes: &'a [u8]) -> Self {
        Reader { rest: bytes }
    }

    /// The next `n` bytes, borrowed.
    pub(crate) fn bytes(&mut self, n: usize) -> Result<&'a [u8], Error> {
        let (head, tail) = self.rest.split_at_checked(n).ok_or(Error::Length)?;
        self.rest = tail;
        Ok(head)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], Error> {
        let mut out = [0u8; N];
        let src = self.bytes(N)?;
        out.iter_mut().zip(src).for_each(|(d, s)| *d = *s);
        Ok(out)
    }

    pub(crate) fn u8(&mut self) -> Result<u8, Error> {
        Ok(u8::from_le_bytes(self.array()?))
    }

    pub(crate) fn u16(&mut self) -> Result<u16, Error> {
        Ok(u16::from_le_bytes(self.array()?))
    }

    pub(crate) fn u32(&mut self) -> Result<u32, Error> {
        Ok(u32::from_le_bytes(self.array()?))
    }

    pub(crate) fn u64(&mut self) -> Result<u64, Error> {
        Ok(u64::from_le_bytes(self.array()?))
    }

    pub(crate) fn f32(&mut self) -> Result<f32, Error> {
        Ok(f32::from_le_bytes(self.array()?))
    }

    pub(crate) fn vec2(&mut self) -> Result<Vec2, Error> {
        Ok(Vec2::new(self.f32()?, self.f32()?))
    }

    /// What is left, unread.
    pub(crate) fn rest(&self) -> &'a [u8] {
        self.rest
    }

    /// Succeeds only if every byte was read: trailing bytes are a length error.
    pub(crate) fn finish(self) -> Result<(), Error> {
        if self.rest.is_empty() {
            Ok(())
        } else {
            Err(Error::Length)
        }
    }
}

/// Writes little-endian numbers into a slice, front to back.
pub(crate) struct Writer<'a> {
    buf: &'a mut [u8],
    pos: usize,
}

impl<'a> Writer<'a> {
    pub(crate) fn new(buf: &'a mut [u8]) -> Self {
        Writer { buf, pos: 0 }
    }

    pub(crate) fn bytes(&mut self, src: &[u8]) -> Result<(), Error> {
        let end = self
            .pos
            .checked_add(src.len())
            .ok_or(Error::BufferTooSmall)?;
        let dst = self
            .buf
            .get_mut(self.pos..end)
            .ok_or(Error::BufferTooSmall)?;
        // zip instead of copy_from_slice: no length assertion to panic.
        dst.iter_mut().zip(src).for_each(|(d, s)| *d = *s);
        self.pos = end;
        Ok(())
    }

    pub(crate) fn u8(&mut self, v: u8) -> Result<(), Error> {
        self.bytes(&[v])
    }

    pub(crate) fn u16(&mut self, v: u16) -> Result<(), Error> {
        self.bytes(&v.to_le_bytes())
    }

    pub(crate) fn u32(&mut self, v: u32) -> Result<(), Error> {
        self.bytes(&v.to_le_bytes())
    }

    pub(crate) fn u64(&mut self, v: u64) -> Result<(), Error> {
        self.bytes(&v.to_le_bytes())
    }

    pub(crate) fn f32(&mut self, v: f32) -> Result<(), Error> {
        self.bytes(&v.to_le_bytes())
    }

    pub(crate) fn vec2(&mut self, v: Vec2) -> Result<(), Error> {
        self.f32(v.x)?;
        self.f32(v.y)
    }

    /// Bytes written so far.
    pub(crate) fn len(&self) -> usize {
        self.pos
    }
}

/// `v` must be finite.
pub(crate) fn finite(f: Field, v: f32) -> Result<(), Error> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(f.error(Problem::NonFinite))
    }
}

/// `v` must be finite and within `lo ..= hi`.
pub(crate) fn within(f: Field, v: f32, lo: f32, hi: f32) -> Result<(), Error> {
    finite(f, v)?;
    if (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(f.error(Problem::OutOfRange))
    }
}

/// `|v| ≤ max`, finite.
pub(crate) fn magnitude(f: Field, v: f32, max: f32) -> Result<(), Error> {
    within(f, v, -max, max)
}

/// An angle in radians: finite and within ±2π (a wider value is a unit error, e.g. degrees).
pub(crate) fn angle(f: Field, v: f32) -> Result<(), Error> {
    magnitude(f, v, TAU)
}

/// Both components of a point within ±`max`.
pub(crate) fn point(f: Field, p: Vec2, max: f32) -> Result<(), Error> {
    magnitude(f, p.x, max)?;
    magnitude(f, p.y, max)
}

/// A field refused with `problem`.
pub(crate) fn refuse<T>(f: Field, problem: Problem) -> Result<T, Error> {
    Err(f.error(problem))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reader_reads_little_endian_and_runs_out_cleanly() {
        let bytes = [
            0x01, 0x34, 0x12, 0x78, 0x56, 0x34, 0x12, 0x00, 0x00, 0x80, 0x3f, 0xff,
        ];
        let mut r = Reader::new(&bytes);
        assert_eq!(r.u8(), Ok(1));
        assert_eq!(r.u16(), Ok(0x1234));
        assert_eq!(r.u32(), Ok(0x1234_5678));
        assert_eq!(r.f32(), Ok(1.0));
        assert_eq!(r.u16(), Err(Error::Length));
        assert_eq!(r.rest(), &[0xff]);
        assert_eq!(r.finish(), Err(Error::Length));
    }

    #[test]
    fn writer_refuses_to_overrun() {
        let mut buf = [0u8; 5];
        let mut w = Writer::new(&mut buf);
        assert_eq!(w.u32(0xdead_beef), Ok(()));
        assert_eq!(w.u16(1), Err(Error::BufferTooSmall));
        assert_eq!(w.u8(7), Ok(()));
        assert_eq!(w.len(), 5);
        assert_eq!(buf, [0xef, 0xbe, 0xad, 0xde, 7]);
    }

    const F: Field = Field::new(4, 0, "f32", "f");

    #[test]
    fn checks_name_the_field_and_problem() {
        assert_eq!(
            within(F, f32::NAN, 0.0, 1.0),
            Err(Error::field(4, Problem::NonFinite))
        );
        assert_eq!(
            within(F, 1.5, 0.0, 1.0),
            Err(Error::field(4, Problem::OutOfRange))
        );
        assert_eq!(within(F, 1.0, 0.0, 1.0), Ok(()));
        assert_eq!(angle(F, 7.0), Err(Error::field(4, Problem::OutOfRange)));
        assert_eq!(angle(F, -6.0), Ok(()));
    }
}
