//! Waypoint missions over the link, host → firmware: `MissionCount`, `MissionItem` and `Survey`
//! (since protocol version 6). Each is a request, answered with a [`ReplyRepr`](super::ReplyRepr).
//!
//! A waypoint mission goes up in small messages, as MAVLink's mission protocol does
//! (`MISSION_COUNT`, then one `MISSION_ITEM_INT` per waypoint): a queued request is a slot of
//! the firmware's request queue, and sixteen waypoints in one message would make every slot
//! 260 bytes bigger. `MissionCount` opens an upload (how many waypoints, the end, a formation);
//! each `MissionItem` fills one index, in any order, again if it came back busy; the reply to
//! the item that completes the list says whether the mission was taken, and only then does it
//! replace the mission in force. A `Survey` is expanded by the firmware itself
//! ([`crate::planner::Survey`]) and flown at once.
//!
//! Every field is checked here, with its row; what this module accepts the planner accepts.

use super::codec::{angle, finite, magnitude, refuse, within, Reader, Writer};
use super::formation::{self, FormationRows, FLAG_FORMATION};
use super::frame::MessageType;
use super::layout::Field;
use super::payload::Payload;
use super::{Error, Problem};
use field::{mission_count, mission_item, survey};

pub use super::formation::FORMATION_LEN;
use crate::math::Vec2;
use crate::types::mission::{
    LOITER_RADIUS_M, MAX_SURVEY_SIDE_M, MAX_WAYPOINT_RADIUS_M, MAX_WAYPOINT_SPEED,
    MIN_WAYPOINT_SPEED,
};
use crate::types::{
    Formation, MissionEnd, MissionError, Survey, Waypoint, MAX_COORD_M, MAX_WAYPOINTS,
};

/// `MissionCount` payload length without a formation.
pub const MISSION_COUNT_LEN: usize = 7;
/// `MissionItem` payload length.
pub const MISSION_ITEM_LEN: usize = 17;
/// `Survey` payload length without a formation.
pub const SURVEY_LEN: usize = 38;
/// Each message's rows (docs/protocol.md §6), by name: each constant is the row of the field
/// it names.
#[allow(missing_docs)]
pub mod field {
    /// `MissionCount`.
    pub mod mission_count {
        use crate::link::layout::Field;

        pub const COUNT: Field = Field::new(0, 0, "u8", "count");
        pub const END: Field = Field::new(1, 1, "u8", "end");
        pub const LOITER_RADIUS_M: Field = Field::new(2, 2, "f32", "loiter_radius_m");
        pub const FLAGS: Field = Field::new(3, 6, "u8", "flags");
        pub const Q: Field = Field::new(4, 7, "u8", "q");
        pub const LATTICE_M: Field = Field::new(5, 8, "f32", "lattice_m");
        pub const ORIENTATION: Field = Field::new(6, 12, "f32", "orientation");
        pub const ATTRACTION: Field = Field::new(7, 16, "f32", "attraction");
        /// Every row, in order.
        pub const ALL: &[Field] = &[
            COUNT,
            END,
            LOITER_RADIUS_M,
            FLAGS,
            Q,
            LATTICE_M,
            ORIENTATION,
            ATTRACTION,
        ];
    }

    /// `MissionItem`.
    pub mod mission_item {
        use crate::link::layout::Field;

        pub const INDEX: Field = Field::new(0, 0, "u8", "index");
        pub const X: Field = Field::new(1, 1, "f32", "x");
        pub const Y: Field = Field::new(2, 5, "f32", "y");
        pub const RADIUS_M: Field = Field::new(3, 9, "f32", "radius_m");
        pub const SPEED: Field = Field::new(4, 13, "f32", "speed");
        /// Every row, in order.
        pub const ALL: &[Field] = &[INDEX, X, Y, RADIUS_M, SPEED];
    }

    /// `Survey`.
    pub mod survey {
        use crate::link::layout::Field;

        pub const CORNER_X: Field = Field::new(0, 0, "f32", "corner_x");
        pub const CORNER_Y: Field = Field::new(1, 4, "f32", "corner_y");
        pub const LENGTH_M: Field = Field::new(2, 8, "f32", "length_m");
        pub const WIDTH_M: Field = Field::new(3, 12, "f32", "width_m");
        pub const HEADING: Field = Field::new(4, 16, "f32", "heading");
        pub const SPACING_M: Field = Field::new(5, 20, "f32", "spacing_m");
        pub const RADIUS_M: Field = Field::new(6, 24, "f32", "radius_m");
        pub const SPEED: Field = Field::new(7, 28, "f32", "speed");
        pub const END: Field = Field::new(8, 32, "u8", "end");
        pub const LOITER_RADIUS_M: Field = Field::new(9, 33, "f32", "loiter_radius_m");
        pub const FLAGS: Field = Field::new(10, 37, "u8", "flags");
        pub const Q: Field = Field::new(11, 38, "u8", "q");
        pub const LATTICE_M: Field = Field::new(12, 39, "f32", "lattice_m");
        pub const ORIENTATION: Field = Field::new(13, 43, "f32", "orientation");
        pub const ATTRACTION: Field = Field::new(14, 47, "f32", "attraction");
        /// Every row, in order.
        pub const ALL: &[Field] = &[
            CORNER_X,
            CORNER_Y,
            LENGTH_M,
            WIDTH_M,
            HEADING,
            SPACING_M,
            RADIUS_M,
            SPEED,
            END,
            LOITER_RADIUS_M,
            FLAGS,
            Q,
            LATTICE_M,
            ORIENTATION,
            ATTRACTION,
        ];
    }
}

/// Where the end and the formation that close `MissionCount` and `Survey` sit in their tables.
struct TailRows {
    end: Field,
    loiter_radius_m: Field,
    formation: FormationRows,
}

macro_rules! tail_rows {
    ($m:ident) => {
        TailRows {
            end: $m::END,
            loiter_radius_m: $m::LOITER_RADIUS_M,
            formation: FormationRows {
                flags: $m::FLAGS,
                q: $m::Q,
                lattice_m: $m::LATTICE_M,
                orientation: $m::ORIENTATION,
                attraction: $m::ATTRACTION,
            },
        }
    };
}

const COUNT_TAIL: TailRows = tail_rows!(mission_count);
const SURVEY_TAIL: TailRows = tail_rows!(survey);

/// The end and formation that close `MissionCount` and `Survey`: `end` u8 (0 hold, 1 loiter
/// anticlockwise, 2 loiter clockwise) · `loiter_radius_m` f32 (0 with hold) · `flags` u8 (bit
/// 0: a formation follows) · \[`q` u8 · `lattice_m` f32 · `orientation` f32 · `attraction`
/// f32\].
fn read_tail(
    r: &mut Reader<'_>,
    rows: &TailRows,
) -> Result<(MissionEnd, Option<Formation>), Error> {
    let end = r.u8()?;
    let radius_m = r.f32()?;
    let end = match end {
        0 if radius_m == 0.0 => MissionEnd::Hold,
        0 => return refuse(rows.loiter_radius_m, Problem::Invalid),
        1 | 2 => MissionEnd::Loiter {
            radius_m,
            clockwise: end == 2,
        },
        _ => return refuse(rows.end, Problem::UnknownCode),
    };
    let flags = r.u8()?;
    if flags & !FLAG_FORMATION != 0 {
        return refuse(rows.formation.flags, Problem::UnknownCode);
    }
    let formation = if flags & FLAG_FORMATION != 0 {
        Some(formation::read(r)?)
    } else {
        None
    };
    Ok((end, formation))
}

fn check_tail(end: &MissionEnd, f: &Option<Formation>, rows: &TailRows) -> Result<(), Error> {
    if let MissionEnd::Loiter { radius_m, .. } = *end {
        within(
            rows.loiter_radius_m,
            radius_m,
            LOITER_RADIUS_M.0,
            LOITER_RADIUS_M.1,
        )?;
    }
    if let Some(f) = f {
        formation::check(f, &rows.formation)?;
    }
    Ok(())
}

fn tail_len(formation: &Option<Formation>) -> usize {
    6 + formation.map_or(0, |_| FORMATION_LEN)
}

fn write_tail(
    w: &mut Writer<'_>,
    end: &MissionEnd,
    formation: &Option<Formation>,
) -> Result<(), Error> {
    match *end {
        MissionEnd::Hold => {
            w.u8(0)?;
            w.f32(0.0)?;
        }
        MissionEnd::Loiter {
            radius_m,
            clockwise,
        } => {
            w.u8(if clockwise { 2 } else { 1 })?;
            w.f32(radius_m)?;
        }
    }
    formation::write(w, formation)
}

/// A radius: finite, > 0 and at most `max`.
fn positive(row: Field, v: f32, max: f32) -> Result<(), Error> {
    finite(row, v)?;
    if v > 0.0 && v <= max {
        Ok(())
    } else {
        refuse(row, Problem::OutOfRange)
    }
}

/// A leg's speed: 0 (none: v_max) or [`MIN_WAYPOINT_SPEED`] ..= [`MAX_WAYPOINT_SPEED`].
fn speed(row: Field, v: f32) -> Result<Option<f32>, Error> {
    finite(row, v)?;
    if v == 0.0 {
        return Ok(None);
    }
    within(row, v, MIN_WAYPOINT_SPEED, MAX_WAYPOINT_SPEED)?;
    Ok(Some(v))
}

/// `MissionCount` (0x09): open a waypoint upload of `count` waypoints.
///
/// Layout (7 bytes, or 20 with a formation): 0 `count` u8 (1 ..= [`MAX_WAYPOINTS`]) · 1 `end`
/// u8 · 2 `loiter_radius_m` f32 · 3 `flags` u8 · \[4 `q` · 5 `lattice_m` · 6 `orientation` ·
/// 7 `attraction`\] (rows 1–7: [`read_tail`]). The mission in force is kept until the upload
/// completes; a new `MissionCount` starts it again.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MissionCountRepr {
    /// Waypoints that will follow.
    pub count: u8,
    /// What happens at the last.
    pub end: MissionEnd,
    /// A formation every vehicle keeps on the way (seed 001 §3.2).
    pub formation: Option<Formation>,
}

impl MissionCountRepr {
    fn check(&self) -> Result<(), Error> {
        if self.count == 0 || usize::from(self.count) > MAX_WAYPOINTS {
            return refuse(mission_count::COUNT, Problem::OutOfRange);
        }
        check_tail(&self.end, &self.formation, &COUNT_TAIL)
    }
}

impl<'a> Payload<'a> for MissionCountRepr {
    const TYPE: MessageType = MessageType::MissionCount;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let count = r.u8()?;
        let (end, formation) = read_tail(&mut r, &COUNT_TAIL)?;
        r.finish()?;
        let m = MissionCountRepr {
            count,
            end,
            formation,
        };
        m.check()?;
        Ok(m)
    }

    fn payload_len(&self) -> usize {
        1 + tail_len(&self.formation)
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        self.check()?;
        let mut w = Writer::new(out);
        w.u8(self.count)?;
        write_tail(&mut w, &self.end, &self.formation)?;
        Ok(w.len())
    }
}

/// `MissionItem` (0x0A): waypoint `index` of the upload.
///
/// Layout (17 bytes): 0 `index` u8 (< the upload's count) · 1 `x` f32 · 2 `y` f32 (m, ±100 km) ·
/// 3 `radius_m` f32 (arrival radius, 0 < r ≤ 1000) · 4 `speed` f32 (m/s of the leg to it; 0:
/// the planner's v_max, else 0.01 ..= 20).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MissionItemRepr {
    /// Its place in the list, 0-based.
    pub index: u8,
    /// The waypoint.
    pub waypoint: Waypoint,
}

impl MissionItemRepr {
    fn check(&self) -> Result<(), Error> {
        if usize::from(self.index) >= MAX_WAYPOINTS {
            return refuse(mission_item::INDEX, Problem::OutOfRange);
        }
        Ok(())
    }
}

impl<'a> Payload<'a> for MissionItemRepr {
    const TYPE: MessageType = MessageType::MissionItem;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let index = r.u8()?;
        let p = r.vec2()?;
        let radius_m = r.f32()?;
        let v = r.f32()?;
        r.finish()?;
        magnitude(mission_item::X, p.x, MAX_COORD_M)?;
        magnitude(mission_item::Y, p.y, MAX_COORD_M)?;
        positive(mission_item::RADIUS_M, radius_m, MAX_WAYPOINT_RADIUS_M)?;
        let v = speed(mission_item::SPEED, v)?;
        // The checks above are Waypoint::new's and with_speed's, row by row.
        let waypoint = Waypoint::new(p, radius_m)
            .and_then(|w| w.with_speed(v))
            .map_err(|_| mission_item::X.error(Problem::Invalid))?;
        let m = MissionItemRepr { index, waypoint };
        m.check()?;
        Ok(m)
    }

    fn payload_len(&self) -> usize {
        MISSION_ITEM_LEN
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        self.check()?;
        let mut w = Writer::new(out);
        w.u8(self.index)?;
        w.vec2(self.waypoint.position())?;
        w.f32(self.waypoint.radius_m())?;
        w.f32(self.waypoint.speed().unwrap_or(0.0))?;
        Ok(w.len())
    }
}

/// `Survey` (0x0B): a lawnmower over a rectangle, expanded and flown by the firmware
/// ([`Survey`]).
///
/// Layout (38 bytes, or 51 with a formation): 0 `corner_x` f32 · 1 `corner_y` f32 (m, ±100 km) ·
/// 2 `length_m` f32 (along the heading) · 3 `width_m` f32 (to its left) · 4 `heading` f32
/// (rad, ±2π) · 5 `spacing_m` f32 (largest line spacing; sides and spacing 0 < · ≤ 10 000;
/// the lines, ⌈width / spacing⌉ + 1, must fit the mission: at most 8, else out of range) ·
/// 6 `radius_m` f32 · 7 `speed` f32 (as `MissionItem`'s) · 8 `end` u8 · 9 `loiter_radius_m` f32
/// · 10 `flags` u8 · \[11 `q` · 12 `lattice_m` · 13 `orientation` · 14 `attraction`\].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SurveyRepr {
    /// The area and how to mow it.
    pub survey: Survey,
    /// What happens at the last waypoint.
    pub end: MissionEnd,
    /// A formation every vehicle keeps on the way.
    pub formation: Option<Formation>,
}

impl SurveyRepr {
    fn check(&self) -> Result<(), Error> {
        let s = &self.survey;
        magnitude(survey::CORNER_X, s.corner.x, MAX_COORD_M)?;
        magnitude(survey::CORNER_Y, s.corner.y, MAX_COORD_M)?;
        positive(survey::LENGTH_M, s.length_m, MAX_SURVEY_SIDE_M)?;
        positive(survey::WIDTH_M, s.width_m, MAX_SURVEY_SIDE_M)?;
        angle(survey::HEADING, s.heading)?;
        positive(survey::SPACING_M, s.spacing_m, MAX_SURVEY_SIDE_M)?;
        positive(survey::RADIUS_M, s.radius_m, MAX_WAYPOINT_RADIUS_M)?;
        speed(survey::SPEED, s.speed.unwrap_or(0.0))?;
        if s.speed == Some(0.0) {
            return refuse(survey::SPEED, Problem::OutOfRange);
        }
        check_tail(&self.end, &self.formation, &SURVEY_TAIL)?;
        // Too many lines for the list: the spacing is what to change.
        match s.waypoints() {
            Ok(_) => Ok(()),
            Err(MissionError::TooMany { .. }) => refuse(survey::SPACING_M, Problem::OutOfRange),
            Err(_) => refuse(survey::CORNER_X, Problem::Invalid),
        }
    }
}

impl<'a> Payload<'a> for SurveyRepr {
    const TYPE: MessageType = MessageType::Survey;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let corner = Vec2::new(r.f32()?, r.f32()?);
        let length_m = r.f32()?;
        let width_m = r.f32()?;
        let heading = r.f32()?;
        let spacing_m = r.f32()?;
        let radius_m = r.f32()?;
        let v = r.f32()?;
        let (end, formation) = read_tail(&mut r, &SURVEY_TAIL)?;
        r.finish()?;
        let s = SurveyRepr {
            survey: Survey {
                corner,
                length_m,
                width_m,
                heading,
                spacing_m,
                radius_m,
                speed: speed(survey::SPEED, v)?,
            },
            end,
            formation,
        };
        s.check()?;
        Ok(s)
    }

    fn payload_len(&self) -> usize {
        32 + tail_len(&self.formation)
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        self.check()?;
        let s = &self.survey;
        let mut w = Writer::new(out);
        w.vec2(s.corner)?;
        for v in [
            s.length_m,
            s.width_m,
            s.heading,
            s.spacing_m,
            s.radius_m,
            s.speed.unwrap_or(0.0),
        ] {
            w.f32(v)?;
        }
        write_tail(&mut w, &self.end, &self.formation)?;
        Ok(w.len())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    extern crate std;
    use super::*;
    use crate::link::Message;
    use proptest::prelude::*;
    use std::vec::Vec;

    fn le(vals: &[f32]) -> Vec<u8> {
        vals.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    #[test]
    fn mission_count_bytes_and_refusals() {
        // 5 waypoints, loiter clockwise at 12 m, no formation.
        let mut b = std::vec![5u8, 2];
        b.extend(le(&[12.0]));
        b.push(0);
        let m = MissionCountRepr::parse(&b).unwrap();
        assert_eq!(
            m,
            MissionCountRepr {
                count: 5,
                end: MissionEnd::Loiter {
                    radius_m: 12.0,
                    clockwise: true
                },
                formation: None
            }
        );
        let mut out = [0u8; 32];
        assert_eq!(m.emit(&mut out), Ok(MISSION_COUNT_LEN));
        assert_eq!(&out[..7], &b[..]);
        let with = |i: usize, v: &[u8]| {
            let mut c = b.clone();
            c[i..i + v.len()].copy_from_slice(v);
            MissionCountRepr::parse(&c)
        };
        assert_eq!(with(0, &[0]), Err(Error::field(0, Problem::OutOfRange)));
        assert_eq!(with(0, &[17]), Err(Error::field(0, Problem::OutOfRange)));
        assert_eq!(with(1, &[3]), Err(Error::field(1, Problem::UnknownCode)));
        assert_eq!(
            with(2, &0.5f32.to_le_bytes()),
            Err(Error::field(2, Problem::OutOfRange))
        );
        assert_eq!(
            with(2, &f32::NAN.to_le_bytes()),
            Err(Error::field(2, Problem::NonFinite))
        );
        // Hold with a loiter radius contradicts itself.
        assert_eq!(with(1, &[0]), Err(Error::field(2, Problem::Invalid)));
        assert_eq!(with(6, &[2]), Err(Error::field(3, Problem::UnknownCode)));
        assert_eq!(MissionCountRepr::parse(&b[..6]), Err(Error::Length));
        // With a formation: q = 5 is refused on its row.
        let mut f = b.clone();
        f[6] = 1;
        f.push(5);
        f.extend(le(&[4.0, 0.0, 5.0]));
        assert_eq!(
            MissionCountRepr::parse(&f),
            Err(Error::field(4, Problem::UnknownCode))
        );
        f[7] = 4;
        let m = MissionCountRepr::parse(&f).unwrap();
        assert_eq!(m.formation.map(|f| f.q), Some(4));
        assert_eq!(m.payload_len(), 20);
    }

    #[test]
    fn mission_item_bytes_and_refusals() {
        let mut b = std::vec![3u8];
        b.extend(le(&[10.0, -5.0, 2.0, 0.0]));
        let m = MissionItemRepr::parse(&b).unwrap();
        assert_eq!(m.index, 3);
        assert_eq!(m.waypoint.position(), Vec2::new(10.0, -5.0));
        assert_eq!((m.waypoint.radius_m(), m.waypoint.speed()), (2.0, None));
        let mut out = [0u8; MISSION_ITEM_LEN];
        assert_eq!(m.emit(&mut out), Ok(MISSION_ITEM_LEN));
        assert_eq!(&out[..], &b[..]);
        let with = |i: usize, v: f32| {
            let mut c = b.clone();
            c[i..i + 4].copy_from_slice(&v.to_le_bytes());
            MissionItemRepr::parse(&c)
        };
        assert_eq!(with(1, f32::NAN), Err(Error::field(1, Problem::NonFinite)));
        assert_eq!(with(5, 2e5), Err(Error::field(2, Problem::OutOfRange)));
        assert_eq!(with(9, 0.0), Err(Error::field(3, Problem::OutOfRange)));
        assert_eq!(with(9, -1.0), Err(Error::field(3, Problem::OutOfRange)));
        assert_eq!(with(13, 0.001), Err(Error::field(4, Problem::OutOfRange)));
        assert_eq!(with(13, 25.0), Err(Error::field(4, Problem::OutOfRange)));
        assert_eq!(with(13, 0.5).unwrap().waypoint.speed(), Some(0.5));
        let mut c = b.clone();
        c[0] = 16;
        assert_eq!(
            MissionItemRepr::parse(&c),
            Err(Error::field(0, Problem::OutOfRange))
        );
        assert_eq!(MissionItemRepr::parse(&b[..16]), Err(Error::Length));
    }

    #[test]
    fn survey_bytes_and_refusals() {
        let mut b = le(&[10.0, -20.0, 50.0, 30.0, 0.0, 10.0, 2.0, 0.8]);
        b.push(0);
        b.extend(le(&[0.0]));
        b.push(0);
        assert_eq!(b.len(), SURVEY_LEN);
        let s = SurveyRepr::parse(&b).unwrap();
        assert_eq!(s.survey.lines(), Ok(4));
        assert_eq!(s.survey.speed, Some(0.8));
        assert_eq!(s.end, MissionEnd::Hold);
        let mut out = [0u8; 64];
        assert_eq!(s.emit(&mut out), Ok(SURVEY_LEN));
        assert_eq!(&out[..SURVEY_LEN], &b[..]);
        let with = |i: usize, v: f32| {
            let mut c = b.clone();
            c[i..i + 4].copy_from_slice(&v.to_le_bytes());
            SurveyRepr::parse(&c)
        };
        assert_eq!(with(8, 0.0), Err(Error::field(2, Problem::OutOfRange)));
        assert_eq!(
            with(12, f32::INFINITY),
            Err(Error::field(3, Problem::NonFinite))
        );
        assert_eq!(with(16, 7.0), Err(Error::field(4, Problem::OutOfRange)));
        // Nine lines do not fit sixteen waypoints: the spacing's row.
        assert_eq!(with(20, 3.0), Err(Error::field(5, Problem::OutOfRange)));
        assert_eq!(with(24, 0.0), Err(Error::field(6, Problem::OutOfRange)));
        assert_eq!(with(28, 30.0), Err(Error::field(7, Problem::OutOfRange)));
        assert_eq!(with(33, 10.0), Err(Error::field(9, Problem::Invalid)));
    }

    /// Test vectors of docs/protocol.md §11: coded frames computed apart from this crate, with
    /// the protocol's Python reference code (§12: `binascii.crc_hqx` for the CRC, its
    /// Reed–Solomon parity checked against `reedsolo`).
    #[test]
    fn worked_examples_of_the_mission_upload() {
        let cases: [(Message<'_>, u16, &str); 3] = [
            (
                Message::MissionCount(MissionCountRepr {
                    count: 2,
                    end: MissionEnd::Hold,
                    formation: None,
                }),
                8,
                "ff f7 e8 15 9a ef 85 33 24 ea 7a d2 aa 6a de 5d 56 e6 f1 b7 45 f5 3a 14 b6 02 dd 37 65 f5 00",
            ),
            (
                Message::MissionItem(MissionItemRepr {
                    index: 1,
                    waypoint: Waypoint::new(Vec2::new(40.0, 10.0), 2.0)
                        .unwrap()
                        .with_speed(Some(0.5))
                        .unwrap(),
                }),
                9,
                "ff f7 eb 14 9a ec 85 33 04 a8 7a d2 19 31 97 57 0a 14 7d 2d d8 52 44 dc 5f b6 7b a5 bc 37 f7 99 05 1d 90 ab 0e 9a 51 16 00",
            ),
            (
                Message::Survey(SurveyRepr {
                    survey: Survey {
                        corner: Vec2::new(0.0, 0.0),
                        length_m: 40.0,
                        width_m: 20.0,
                        heading: 0.0,
                        spacing_m: 10.0,
                        radius_m: 2.0,
                        speed: None,
                    },
                    end: MissionEnd::Hold,
                    formation: None,
                }),
                10,
                "ff f7 ea 17 9a ed 85 33 24 ea 7a d2 39 70 97 77 48 54 7d 8d 99 6d 0d ba 8f 67 59 e7 e3 bf 34 ca 58 30 53 93 df 92 ec a7 15 8a dc ef 99 a4 a6 dd e1 7e 3e 40 e6 4c 9b 77 28 d4 ca e7 d0 00",
            ),
        ];
        for (m, seq, wire) in cases {
            let mut out = [0u8; crate::link::MAX_FRAME];
            let n = m.emit_frame(seq, &mut out).unwrap();
            let hex: Vec<std::string::String> =
                out[..n].iter().map(|b| std::format!("{b:02x}")).collect();
            assert_eq!(hex.join(" "), wire, "{m:?}");
            let back = Message::decode_frame(&mut out[..n], crate::link::Direction::ToFirmware);
            assert_eq!(back.unwrap().1, m);
        }
    }

    pub(crate) fn arb_end() -> impl Strategy<Value = MissionEnd> {
        prop_oneof![
            Just(MissionEnd::Hold),
            (1.0f32..1000.0, any::<bool>()).prop_map(|(radius_m, clockwise)| {
                MissionEnd::Loiter {
                    radius_m,
                    clockwise,
                }
            }),
        ]
    }

    pub(crate) fn arb_formation() -> impl Strategy<Value = Option<Formation>> {
        proptest::option::of(
            (
                prop_oneof![Just(3u8), Just(4), Just(6)],
                0.5f32..1000.0,
                -6.2f32..6.2,
                0.001f32..1e4,
            )
                .prop_map(|(q, lattice_m, orientation, attraction)| Formation {
                    q,
                    lattice_m,
                    orientation,
                    attraction,
                }),
        )
    }

    pub(crate) fn arb_count() -> impl Strategy<Value = MissionCountRepr> {
        (1u8..=16, arb_end(), arb_formation()).prop_map(|(count, end, formation)| {
            MissionCountRepr {
                count,
                end,
                formation,
            }
        })
    }

    pub(crate) fn arb_item() -> impl Strategy<Value = MissionItemRepr> {
        (
            0u8..16,
            (-1e5f32..1e5, -1e5f32..1e5),
            0.01f32..1000.0,
            proptest::option::of(0.01f32..20.0),
        )
            .prop_map(|(index, (x, y), r, v)| MissionItemRepr {
                index,
                waypoint: Waypoint::new(Vec2::new(x, y), r)
                    .unwrap()
                    .with_speed(v)
                    .unwrap(),
            })
    }

    pub(crate) fn arb_survey() -> impl Strategy<Value = SurveyRepr> {
        (
            (-1e4f32..1e4, -1e4f32..1e4),
            (1.0f32..5000.0, 1.0f32..500.0, -6.2f32..6.2),
            (1.0f32..1000.0, proptest::option::of(0.01f32..20.0)),
            arb_end(),
            arb_formation(),
        )
            .prop_map(
                |((x, y), (length_m, width_m, heading), (radius_m, speed), end, formation)| {
                    SurveyRepr {
                        survey: Survey {
                            corner: Vec2::new(x, y),
                            length_m,
                            width_m,
                            heading,
                            // Wide enough that it always fits: at most 8 lines.
                            spacing_m: width_m / 6.5,
                            radius_m,
                            speed,
                        },
                        end,
                        formation,
                    }
                },
            )
    }

    proptest! {
        #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

        /// What the wire accepts, the planner accepts.
        #[test]
        fn upload_messages_round_trip(c in arb_count(), i in arb_item(), s in arb_survey()) {
            let mut out = [0u8; 64];
            let n = c.emit(&mut out).unwrap();
            prop_assert_eq!(n, c.payload_len());
            prop_assert_eq!(MissionCountRepr::parse(&out[..n]), Ok(c));
            let n = i.emit(&mut out).unwrap();
            prop_assert_eq!(MissionItemRepr::parse(&out[..n]), Ok(i));
            let n = s.emit(&mut out).unwrap();
            prop_assert_eq!(n, s.payload_len());
            prop_assert_eq!(SurveyRepr::parse(&out[..n]), Ok(s));
            let wps = crate::planner::Waypoints::survey(&s.survey, s.end).unwrap();
            let mut planner = crate::planner::Planner::new(crate::params::Params::default()).unwrap();
            prop_assert_eq!(planner.set_waypoints(&wps, s.formation), Ok(()));
        }

        #[test]
        fn upload_parsers_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..64)) {
            let _ = MissionCountRepr::parse(&bytes);
            let _ = MissionItemRepr::parse(&bytes);
            let _ = SurveyRepr::parse(&bytes);
        }
    }
}
