//! `Belief` (0x85): what the firmware believes is there — a chunk of its evidence map
//! (`crate::sonar::evidence`) — so a host can show, beside the truth, whether a failure was
//! one of perception (the wall was never believed) or of planning (it was, and still hit).
//!
//! The firmware sends one chunk of at most [`BELIEF_ROWS`] rows of the 64-cell-wide window
//! every few periods, round-robin, so a host reassembles the whole map in a few chunks and the
//! link carries at most one chunk's bytes per period.
//!
//! Layout (21 + 8·rows bytes): 0 `time_ms` u64 · 1 `cell_m` f32 (0.05 ..= 10) · 2 `x0` i32 ·
//! 3 `y0` i32 · 4 `rows` u8 (0 ..= [`BELIEF_ROWS`]) · 5 the rows, each a u64 bitmap: bit k of
//! row r is world cell (x0 + k, y0 + r), which spans [i·cell, (i+1)·cell) × [j·cell,
//! (j+1)·cell) m; 1 = believed occupied. A chunk states every cell it covers: a 0 clears a
//! cell the host held.

use super::codec::{Reader, Writer};
use super::frame::MessageType;
use super::payload::Payload;
use super::{Error, Problem};

/// `Belief`'s rows (docs/protocol.md §6), by name: each constant is the row of the field it
/// names.
#[allow(missing_docs)]
pub mod field {
    use crate::link::layout::Field;

    pub const TIME_MS: Field = Field::new(0, 0, "u64", "time_ms");
    pub const CELL_M: Field = Field::new(1, 8, "f32", "cell_m");
    pub const X0: Field = Field::new(2, 12, "i32", "x0");
    pub const Y0: Field = Field::new(3, 16, "i32", "y0");
    pub const ROWS: Field = Field::new(4, 20, "u8", "rows");
    pub const BITMAP: Field = Field::new(5, 21, "rows × u64", "bitmap");
    /// Every row, in order.
    pub const ALL: &[Field] = &[TIME_MS, CELL_M, X0, Y0, ROWS, BITMAP];
}

/// Most rows in one `Belief` chunk.
pub const BELIEF_ROWS: usize = 16;
/// Longest `Belief` payload, bytes.
pub const BELIEF_MAX_LEN: usize = 21 + 8 * BELIEF_ROWS;

/// A chunk of the evidence map. The rows are borrowed as their wire bytes (8 per row, little
/// endian), so a `Message` stays small; [`BeliefRepr::row`] reads one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BeliefRepr<'a> {
    /// Firmware time, ms.
    pub time_ms: u64,
    /// Cell size, m, as f32 bits (kept as bits so the type is `Eq`; see [`BeliefRepr::cell_m`]).
    pub cell_bits: u32,
    /// World cell index of the chunk's first column.
    pub x0: i32,
    /// World cell index of the chunk's first row.
    pub y0: i32,
    /// The rows' bitmaps, 8 bytes each, little endian: bit k = column x0 + k. At most
    /// [`BELIEF_ROWS`] rows.
    pub bitmap: &'a [u8],
}

impl BeliefRepr<'_> {
    /// Cell size, m.
    pub fn cell_m(&self) -> f32 {
        f32::from_bits(self.cell_bits)
    }

    /// Rows in the chunk.
    pub fn rows(&self) -> usize {
        self.bitmap.len() / 8
    }

    /// Row `r`'s bitmap (0 past the end).
    pub fn row(&self, r: usize) -> u64 {
        let mut b = [0u8; 8];
        if let Some(src) = self.bitmap.get(8 * r..8 * r + 8) {
            b.copy_from_slice(src);
        }
        u64::from_le_bytes(b)
    }

    fn check(&self) -> Result<(), Error> {
        let c = self.cell_m();
        if !c.is_finite() {
            return Err(field::CELL_M.error(Problem::NonFinite));
        }
        if !(0.05..=10.0).contains(&c) {
            return Err(field::CELL_M.error(Problem::OutOfRange));
        }
        if !self.bitmap.len().is_multiple_of(8) || self.rows() > BELIEF_ROWS {
            return Err(field::ROWS.error(Problem::OutOfRange));
        }
        Ok(())
    }
}

impl<'a> Payload<'a> for BeliefRepr<'a> {
    const TYPE: MessageType = MessageType::Belief;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let time_ms = r.u64()?;
        let cell_bits = r.u32()?;
        let x0 = r.u32()? as i32;
        let y0 = r.u32()? as i32;
        let rows = usize::from(r.u8()?);
        if rows > BELIEF_ROWS {
            return Err(field::ROWS.error(Problem::OutOfRange));
        }
        let bitmap = r.bytes(8 * rows)?;
        r.finish()?;
        let b = BeliefRepr {
            time_ms,
            cell_bits,
            x0,
            y0,
            bitmap,
        };
        b.check()?;
        Ok(b)
    }

    fn payload_len(&self) -> usize {
        21 + self.bitmap.len()
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        self.check()?;
        let mut w = Writer::new(out);
        w.u64(self.time_ms)?;
        w.u32(self.cell_bits)?;
        w.u32(self.x0 as u32)?;
        w.u32(self.y0 as u32)?;
        w.u8(self.rows() as u8)?;
        w.bytes(self.bitmap)?;
        Ok(w.len())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    extern crate std;
    use super::*;
    use proptest::prelude::*;
    use std::vec::Vec;

    /// (time, cell, x0, y0, bitmap bytes) for a borrowed `BeliefRepr`.
    pub(crate) type OwnedBelief = (u64, f32, i32, i32, Vec<u8>);

    pub(crate) fn belief(o: &OwnedBelief) -> BeliefRepr<'_> {
        BeliefRepr {
            time_ms: o.0,
            cell_bits: o.1.to_bits(),
            x0: o.2,
            y0: o.3,
            bitmap: &o.4,
        }
    }

    pub(crate) fn arb_belief() -> impl proptest::strategy::Strategy<Value = OwnedBelief> {
        (
            any::<u64>(),
            0.05f32..10.0,
            any::<i32>(),
            any::<i32>(),
            (0..=BELIEF_ROWS).prop_flat_map(|r| proptest::collection::vec(any::<u8>(), 8 * r)),
        )
    }

    #[test]
    fn belief_bytes() {
        let mut rows = [0u8; 16];
        rows[..8].copy_from_slice(&(1u64 << 12).to_le_bytes());
        rows[8..].copy_from_slice(&0x8000_0000_0000_0001u64.to_le_bytes());
        let b = BeliefRepr {
            time_ms: 1000,
            cell_bits: 0.5f32.to_bits(),
            x0: -32,
            y0: 5,
            bitmap: &rows,
        };
        let mut want = std::vec![0xe8, 0x03, 0, 0, 0, 0, 0, 0]; // 1000 ms
        want.extend([0x00, 0x00, 0x00, 0x3f]); // 0.5
        want.extend([0xe0, 0xff, 0xff, 0xff]); // −32
        want.extend([5, 0, 0, 0, 2]);
        want.extend([0, 0x10, 0, 0, 0, 0, 0, 0]);
        want.extend([1, 0, 0, 0, 0, 0, 0, 0x80]);
        let mut out = [0u8; BELIEF_MAX_LEN];
        assert_eq!(b.emit(&mut out), Ok(want.len()));
        assert_eq!(&out[..want.len()], &want[..]);
        let parsed = BeliefRepr::parse(&want).unwrap();
        assert_eq!(parsed, b);
        assert_eq!(
            (parsed.row(0), parsed.row(1), parsed.row(2)),
            (1 << 12, 0x8000_0000_0000_0001, 0)
        );
        // Refused: a cell size out of range, more rows than fit, a short payload.
        let mut bad = want.clone();
        bad[8..12].copy_from_slice(&20.0f32.to_le_bytes());
        assert_eq!(
            BeliefRepr::parse(&bad),
            Err(Error::field(1, Problem::OutOfRange))
        );
        let mut bad = want.clone();
        bad[20] = 17;
        assert_eq!(
            BeliefRepr::parse(&bad),
            Err(Error::field(4, Problem::OutOfRange))
        );
        assert_eq!(
            BeliefRepr::parse(&want[..want.len() - 1]),
            Err(Error::Length)
        );
    }

    proptest! {
        #[test]
        fn round_trips(o in arb_belief()) {
            let b = belief(&o);
            let mut out = [0u8; BELIEF_MAX_LEN];
            let n = b.emit(&mut out).unwrap();
            prop_assert_eq!(n, b.payload_len());
            prop_assert_eq!(BeliefRepr::parse(&out[..n]), Ok(b));
        }
    }
}
