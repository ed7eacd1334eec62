//! A formation's wire form, shared by `Mission`, `MissionCount` and `Survey`: a flags byte whose
//! bit 0 announces it, then `q` u8, `lattice_m` f32, `orientation` f32, `attraction` f32. Each
//! message names the rows they take in its table ([`FormationRows`]).

use super::codec::{angle, refuse, within, Reader, Writer};
use super::layout::Field;
use super::{Error, Problem};
use crate::types::Formation;

/// Flag bit: a formation follows.
pub const FLAG_FORMATION: u8 = 0x01;
/// Bytes a formation adds (q u8, λ, θ₀, A⁻).
pub const FORMATION_LEN: usize = 13;

/// Where a formation's fields sit in a message's table.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FormationRows {
    /// The flags byte (a formation that contradicts itself is refused here, as invalid).
    pub flags: Field,
    /// q.
    pub q: Field,
    /// λ.
    pub lattice_m: Field,
    /// θ₀.
    pub orientation: Field,
    /// A⁻.
    pub attraction: Field,
}

/// The ranges of [`Formation::validate`], field by field so that a refusal names the row.
pub(crate) fn check(f: &Formation, rows: &FormationRows) -> Result<(), Error> {
    if !matches!(f.q, 3 | 4 | 6) {
        return refuse(rows.q, Problem::UnknownCode);
    }
    within(rows.lattice_m, f.lattice_m, 0.5, 1000.0)?;
    angle(rows.orientation, f.orientation)?;
    within(rows.attraction, f.attraction, 0.001, 1e4)?;
    f.validate().map_err(|_| rows.flags.error(Problem::Invalid))
}

/// Reads the four fields after the flags byte.
pub(crate) fn read(r: &mut Reader<'_>) -> Result<Formation, Error> {
    Ok(Formation {
        q: r.u8()?,
        lattice_m: r.f32()?,
        orientation: r.f32()?,
        attraction: r.f32()?,
    })
}

/// Writes the flags byte and, if there is one, the formation.
pub(crate) fn write(w: &mut Writer<'_>, f: &Option<Formation>) -> Result<(), Error> {
    match f {
        Some(f) => {
            w.u8(FLAG_FORMATION)?;
            w.u8(f.q)?;
            w.f32(f.lattice_m)?;
            w.f32(f.orientation)?;
            w.f32(f.attraction)
        }
        None => w.u8(0),
    }
}
