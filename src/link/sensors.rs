//! Sensor messages, host → firmware: `Nav`, `Scanline` and `Contacts`.
//!
//! Field rows (the `index` of [`Error::Field`]) are named in [`field`], one module per message,
//! as in the layout tables of `docs/protocol.md`.

use super::codec::{angle, finite, magnitude, refuse, within, Reader, Writer};
use super::frame::MessageType;
use super::payload::Payload;
use super::shape::{read_shape, shape_len, write_shape, MAX_SHAPE_LEN};
use super::{Error, Problem, MAX_BINS, MAX_CONTACTS};
use crate::field::Shape;
use crate::math::{Vec2, TAU};
use crate::types::{
    NavState, Scanline, MAX_COORD_M, MAX_NAV_SPEED, MAX_RANGE_M, MAX_STEP_RAD, MIN_RANGE_M,
    MIN_STEP_RAD,
};
use crate::world::{Agent, ObjectError, Obstacle, Origin, MAX_OBJECT_SPEED};
use field::{contacts, nav, scanline};

/// Largest yaw rate accepted in a `Nav` message, rad/s (one turn per second: beyond any AUV).
pub const MAX_YAW_RATE: f32 = TAU;

/// `Nav` payload length without body velocities.
pub const NAV_LEN: usize = 29;
/// `Nav` payload length with body velocities.
pub const NAV_LEN_WITH_BODY: usize = NAV_LEN + 12;
/// `Nav` flag bit: body velocities follow.
pub const NAV_FLAG_BODY: u8 = 0x01;

/// Each message's rows (docs/protocol.md §6), by name: each constant is the row of the field
/// it names.
#[allow(missing_docs)]
pub mod field {
    /// `Nav`.
    pub mod nav {
        use crate::link::layout::Field;

        pub const TIME_MS: Field = Field::new(0, 0, "u64", "time_ms");
        pub const X: Field = Field::new(1, 8, "f32", "x");
        pub const Y: Field = Field::new(2, 12, "f32", "y");
        pub const HEADING: Field = Field::new(3, 16, "f32", "heading");
        pub const VX: Field = Field::new(4, 20, "f32", "vx");
        pub const VY: Field = Field::new(5, 24, "f32", "vy");
        pub const FLAGS: Field = Field::new(6, 28, "u8", "flags");
        pub const U: Field = Field::new(7, 29, "f32", "u");
        pub const V: Field = Field::new(8, 33, "f32", "v");
        pub const R: Field = Field::new(9, 37, "f32", "r");
        /// Every row, in order.
        pub const ALL: &[Field] = &[TIME_MS, X, Y, HEADING, VX, VY, FLAGS, U, V, R];
    }

    /// `Scanline`.
    pub mod scanline {
        use crate::link::layout::Field;

        pub const TIME_MS: Field = Field::new(0, 0, "u64", "time_ms");
        pub const BEARING_RAD: Field = Field::new(1, 8, "f32", "bearing_rad");
        pub const STEP_RAD: Field = Field::new(2, 12, "f32", "step_rad");
        pub const RANGE_M: Field = Field::new(3, 16, "f32", "range_m");
        pub const BIN_COUNT: Field = Field::new(4, 20, "u16", "bin_count");
        pub const BINS: Field = Field::new(5, 22, "u8 × n", "bins");
        /// Every row, in order.
        pub const ALL: &[Field] = &[TIME_MS, BEARING_RAD, STEP_RAD, RANGE_M, BIN_COUNT, BINS];
    }

    /// `Contacts` (the entry's rows, 2–7, continue the message's; their offsets are in the entry).
    pub mod contacts {
        use crate::link::layout::Field;

        pub const TIME_MS: Field = Field::new(0, 0, "u64", "time_ms");
        pub const COUNT: Field = Field::new(1, 8, "u8", "count");
        pub const ID: Field = Field::new(2, 0, "u16", "id");
        pub const KIND: Field = Field::new(3, 2, "u8", "kind");
        pub const SHAPE: Field = Field::new(4, 3, "shape", "shape");
        pub const VX: Field = Field::new(5, 3, "f32", "vx").plus(" + s");
        pub const VY: Field = Field::new(6, 7, "f32", "vy").plus(" + s");
        pub const CONFIDENCE: Field = Field::new(7, 11, "f32", "confidence").plus(" + s");
        /// Every row, in order.
        pub const ALL: &[Field] = &[TIME_MS, COUNT, ID, KIND, SHAPE, VX, VY, CONFIDENCE];
    }
}

/// Body-frame velocities from a DVL or the vehicle's own estimator.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BodyVelocity {
    /// u, surge (forward), m/s, |u| ≤ [`MAX_NAV_SPEED`].
    pub u: f32,
    /// v, sway (to port), m/s, |v| ≤ [`MAX_NAV_SPEED`].
    pub v: f32,
    /// r, yaw rate, counter-clockwise positive, rad/s, |r| ≤ [`MAX_YAW_RATE`].
    pub r: f32,
}

/// `Nav` (0x01): the vehicle's navigation state at `time_ms`.
///
/// Layout (29 or 41 bytes): 0 `time_ms` u64 · 1 `x` f32 · 2 `y` f32 · 3 `heading` f32 ·
/// 4 `vx` f32 · 5 `vy` f32 · 6 `flags` u8 · \[7 `u` f32 · 8 `v` f32 · 9 `r` f32 if flag bit 0\].
/// Velocity over ground is sent as Earth-frame components (vx, vy), not speed and course, so
/// that it is continuous at zero speed and maps directly to [`NavState::velocity`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NavRepr {
    /// Time of validity of the fix, ms (the firmware's time base in lockstep mode; otherwise
    /// the sender's, and the firmware stamps arrival itself).
    pub time_ms: u64,
    /// Position (|x|, |y| ≤ [`MAX_COORD_M`]), heading (±2π) and velocity over ground
    /// (‖v‖ ≤ [`MAX_NAV_SPEED`]). A parsed `NavRepr` always passes [`NavState::validate`].
    pub nav: NavState,
    /// Body velocities, if the sender has them.
    pub body: Option<BodyVelocity>,
}

impl NavRepr {
    fn check(&self) -> Result<(), Error> {
        let n = &self.nav;
        magnitude(nav::X, n.position.x, MAX_COORD_M)?;
        magnitude(nav::Y, n.position.y, MAX_COORD_M)?;
        angle(nav::HEADING, n.heading)?;
        finite(nav::VX, n.velocity.x)?;
        finite(nav::VY, n.velocity.y)?;
        if n.velocity.norm2() > MAX_NAV_SPEED * MAX_NAV_SPEED {
            return refuse(nav::VX, Problem::OutOfRange);
        }
        if let Some(b) = self.body {
            magnitude(nav::U, b.u, MAX_NAV_SPEED)?;
            magnitude(nav::V, b.v, MAX_NAV_SPEED)?;
            magnitude(nav::R, b.r, MAX_YAW_RATE)?;
        }
        Ok(())
    }
}

impl<'a> Payload<'a> for NavRepr {
    const TYPE: MessageType = MessageType::Nav;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let time_ms = r.u64()?;
        let position = r.vec2()?;
        let heading = r.f32()?;
        let velocity = r.vec2()?;
        let flags = r.u8()?;
        if flags & !NAV_FLAG_BODY != 0 {
            return refuse(nav::FLAGS, Problem::UnknownCode);
        }
        let body = if flags & NAV_FLAG_BODY != 0 {
            Some(BodyVelocity {
                u: r.f32()?,
                v: r.f32()?,
                r: r.f32()?,
            })
        } else {
            None
        };
        r.finish()?;
        let repr = NavRepr {
            time_ms,
            nav: NavState {
                position,
                heading,
                velocity,
            },
            body,
        };
        repr.check()?;
        Ok(repr)
    }

    fn payload_len(&self) -> usize {
        if self.body.is_some() {
            NAV_LEN_WITH_BODY
        } else {
            NAV_LEN
        }
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        self.check()?;
        let mut w = Writer::new(out);
        w.u64(self.time_ms)?;
        w.vec2(self.nav.position)?;
        w.f32(self.nav.heading)?;
        w.vec2(self.nav.velocity)?;
        match self.body {
            Some(b) => {
                w.u8(NAV_FLAG_BODY)?;
                w.f32(b.u)?;
                w.f32(b.v)?;
                w.f32(b.r)?;
            }
            None => w.u8(0)?,
        }
        Ok(w.len())
    }
}

/// `Scanline` payload length before the bins.
pub const SCANLINE_HEAD_LEN: usize = 22;

/// `Scanline` (0x02): one ping of a mechanically scanned imaging sonar, parsed straight into
/// the sonar module's [`Scanline`], whose `bins` borrow the frame (no copy).
///
/// Layout (22 + n bytes): 0 `time_ms` u64 · 1 `bearing_rad` f32 (head angle from the bow,
/// counter-clockwise positive, ±2π) · 2 `step_rad` f32 (signed; magnitude
/// [`MIN_STEP_RAD`] ..= [`MAX_STEP_RAD`]) · 3 `range_m` f32 ([`MIN_RANGE_M`] ..=
/// [`MAX_RANGE_M`]) · 4 `bin_count` u16 (1 ..= [`MAX_BINS`]) · 5 `bins` u8 × n, nearest first.
impl<'a> Payload<'a> for Scanline<'a> {
    const TYPE: MessageType = MessageType::Scanline;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let time_ms = r.u64()?;
        let bearing_rad = r.f32()?;
        let step_rad = r.f32()?;
        let range_m = r.f32()?;
        let n = usize::from(r.u16()?);
        if !(1..=MAX_BINS).contains(&n) {
            return refuse(scanline::BIN_COUNT, Problem::OutOfRange);
        }
        let bins = r.bytes(n)?;
        r.finish()?;
        let s = Scanline {
            time_ms,
            bearing_rad,
            step_rad,
            range_m,
            bins,
        };
        check_scanline(&s)?;
        Ok(s)
    }

    fn payload_len(&self) -> usize {
        SCANLINE_HEAD_LEN + self.bins.len()
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        check_scanline(self)?;
        let mut w = Writer::new(out);
        w.u64(self.time_ms)?;
        w.f32(self.bearing_rad)?;
        w.f32(self.step_rad)?;
        w.f32(self.range_m)?;
        // check_scanline bounds the count by MAX_BINS (512): the cast cannot truncate.
        w.u16(self.bins.len() as u16)?;
        w.bytes(self.bins)?;
        Ok(w.len())
    }
}

fn check_scanline(s: &Scanline<'_>) -> Result<(), Error> {
    angle(scanline::BEARING_RAD, s.bearing_rad)?;
    finite(scanline::STEP_RAD, s.step_rad)?;
    within(
        scanline::STEP_RAD,
        s.step_rad.abs(),
        MIN_STEP_RAD,
        MAX_STEP_RAD,
    )?;
    within(scanline::RANGE_M, s.range_m, MIN_RANGE_M, MAX_RANGE_M)?;
    if !(1..=MAX_BINS).contains(&s.bins.len()) {
        return refuse(scanline::BIN_COUNT, Problem::OutOfRange);
    }
    // The sonar module's own rules, in case they are ever stricter than the wire's.
    s.validate()
        .map_err(|_| scanline::BINS.error(Problem::Invalid))
}

/// What a contact is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum ContactKind {
    /// An obstacle (goes to the obstacle table as a sensed obstacle).
    Obstacle = 0,
    /// Another vehicle (goes to the agent table; its position is the shape's centre).
    Vehicle = 1,
}

impl ContactKind {
    /// The kind with wire code `code`, if any.
    pub const fn from_code(code: u8) -> Option<ContactKind> {
        match code {
            0 => Some(ContactKind::Obstacle),
            1 => Some(ContactKind::Vehicle),
            _ => None,
        }
    }
}

/// One pre-extracted sonar contact, in the world frame.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Contact {
    /// The sender's track id; the same id updates the same table entry.
    pub id: u16,
    /// Obstacle or vehicle.
    pub kind: ContactKind,
    /// Geometry, world frame (see [`shape`](super::shape) for the wire form).
    pub shape: Shape,
    /// Velocity over ground, m/s, ‖v‖ ≤ [`MAX_OBJECT_SPEED`].
    pub velocity: Vec2,
    /// Belief that the contact is real, 0 ..= 1.
    pub confidence: f32,
}

impl Contact {
    /// The obstacle for the world table, with repulsiveness `a_plus` (usually
    /// `Params::a_plus`), seen at `now_ms`.
    pub fn to_obstacle(&self, a_plus: f32, now_ms: u64) -> Result<Obstacle, ObjectError> {
        Obstacle::new(self.id, self.shape, a_plus, Origin::Sensed, now_ms)?.moving(self.velocity)
    }

    /// The agent for the world table (at the shape's centre), seen at `now_ms`.
    pub fn to_agent(&self, now_ms: u64) -> Result<Agent, ObjectError> {
        Agent::new(self.id, self.shape.center(), self.velocity, now_ms)
    }

    /// Wire length of this contact.
    pub fn wire_len(&self) -> usize {
        2 + 1 + shape_len(&self.shape) + 8 + 4
    }

    fn check(&self) -> Result<(), Error> {
        super::shape::check_shape(contacts::SHAPE, &self.shape)?;
        finite(contacts::VX, self.velocity.x)?;
        finite(contacts::VY, self.velocity.y)?;
        if self.velocity.norm2() > MAX_OBJECT_SPEED * MAX_OBJECT_SPEED {
            return refuse(contacts::VX, Problem::OutOfRange);
        }
        within(contacts::CONFIDENCE, self.confidence, 0.0, 1.0)
    }

    fn read(r: &mut Reader<'_>) -> Result<Contact, Error> {
        let id = r.u16()?;
        let kind = r.u8()?;
        let kind =
            ContactKind::from_code(kind).ok_or(contacts::KIND.error(Problem::UnknownCode))?;
        let shape = read_shape(r, contacts::SHAPE)?;
        let velocity = r.vec2()?;
        let confidence = r.f32()?;
        let c = Contact {
            id,
            kind,
            shape,
            velocity,
            confidence,
        };
        c.check()?;
        Ok(c)
    }

    fn write(&self, w: &mut Writer<'_>) -> Result<(), Error> {
        self.check()?;
        w.u16(self.id)?;
        w.u8(self.kind as u8)?;
        write_shape(w, contacts::SHAPE, &self.shape)?;
        w.vec2(self.velocity)?;
        w.f32(self.confidence)
    }
}

/// Longest wire form of one contact.
pub const MAX_CONTACT_LEN: usize = 2 + 1 + MAX_SHAPE_LEN + 8 + 4;
/// `Contacts` payload length before the entries.
pub const CONTACTS_HEAD_LEN: usize = 9;

/// The contacts of a `Contacts` message: either borrowed from a parsed frame (validated, decoded
/// on iteration, no copy) or a slice of [`Contact`]s to send.
#[derive(Clone, Copy)]
pub struct ContactList<'a>(List<'a>);

#[derive(Clone, Copy)]
enum List<'a> {
    /// `count` validated entries, back to back.
    Wire {
        bytes: &'a [u8],
        count: u8,
    },
    Slice(&'a [Contact]),
}

impl<'a> ContactList<'a> {
    /// Contacts to send (at most [`MAX_CONTACTS`], checked on emit).
    pub const fn new(contacts: &'a [Contact]) -> Self {
        ContactList(List::Slice(contacts))
    }

    /// How many contacts.
    pub fn len(&self) -> usize {
        match self.0 {
            List::Wire { count, .. } => usize::from(count),
            List::Slice(s) => s.len(),
        }
    }

    /// No contacts.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The contacts, in order.
    pub fn iter(&self) -> ContactIter<'a> {
        ContactIter(match self.0 {
            List::Wire { bytes, count } => Iter::Wire {
                reader: bytes,
                left: count,
            },
            List::Slice(s) => Iter::Slice(s.iter()),
        })
    }
}

impl<'a> From<&'a [Contact]> for ContactList<'a> {
    fn from(s: &'a [Contact]) -> Self {
        ContactList::new(s)
    }
}

impl<'a> IntoIterator for &ContactList<'a> {
    type Item = Contact;
    type IntoIter = ContactIter<'a>;
    fn into_iter(self) -> ContactIter<'a> {
        self.iter()
    }
}

impl PartialEq for ContactList<'_> {
    fn eq(&self, other: &Self) -> bool {
        self.len() == other.len() && self.iter().eq(other.iter())
    }
}

impl core::fmt::Debug for ContactList<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

#[cfg(feature = "defmt")]
impl defmt::Format for ContactList<'_> {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "ContactList({=usize} contacts)", self.len());
    }
}

/// Iterator over a [`ContactList`].
#[derive(Clone)]
pub struct ContactIter<'a>(Iter<'a>);

#[derive(Clone)]
enum Iter<'a> {
    Wire { reader: &'a [u8], left: u8 },
    Slice(core::slice::Iter<'a, Contact>),
}

impl Iterator for ContactIter<'_> {
    type Item = Contact;

    fn next(&mut self) -> Option<Contact> {
        match &mut self.0 {
            Iter::Wire { reader, left } => {
                if *left == 0 {
                    return None;
                }
                let mut r = Reader::new(reader);
                // Validated at parse: this does not fail; if it ever did, the list just ends.
                let c = Contact::read(&mut r).ok();
                *reader = r.rest();
                *left = if c.is_some() { *left - 1 } else { 0 };
                c
            }
            Iter::Slice(it) => it.next().copied(),
        }
    }
}

/// `Contacts` (0x03): features a sonar extracted itself, up to [`MAX_CONTACTS`].
///
/// Layout (9 + Σ entries bytes): 0 `time_ms` u64 · 1 `count` u8 (0 ..= 8) · then `count`
/// entries of: 2 `id` u16 · 3 `kind` u8 (0 obstacle, 1 vehicle) · 4 `shape` (see
/// [`shape`](super::shape)) · 5 `vx` f32 · 6 `vy` f32 (‖v‖ ≤ 20 m/s) · 7 `confidence` f32
/// (0 ..= 1).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ContactsRepr<'a> {
    /// Time of the observation, ms.
    pub time_ms: u64,
    /// The contacts.
    pub contacts: ContactList<'a>,
}

impl<'a> Payload<'a> for ContactsRepr<'a> {
    const TYPE: MessageType = MessageType::Contacts;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let time_ms = r.u64()?;
        let count = r.u8()?;
        if usize::from(count) > MAX_CONTACTS {
            return refuse(contacts::COUNT, Problem::OutOfRange);
        }
        let entries = r.rest();
        for _ in 0..count {
            Contact::read(&mut r)?;
        }
        let used = entries.len().saturating_sub(r.rest().len());
        r.finish()?;
        Ok(ContactsRepr {
            time_ms,
            contacts: ContactList(List::Wire {
                bytes: entries.get(..used).unwrap_or(&[]),
                count,
            }),
        })
    }

    fn payload_len(&self) -> usize {
        CONTACTS_HEAD_LEN + self.contacts.iter().map(|c| c.wire_len()).sum::<usize>()
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        let n = self.contacts.len();
        if n > MAX_CONTACTS {
            return refuse(contacts::COUNT, Problem::OutOfRange);
        }
        let mut w = Writer::new(out);
        w.u64(self.time_ms)?;
        // n ≤ MAX_CONTACTS (8): the cast cannot truncate.
        w.u8(n as u8)?;
        self.contacts.iter().try_for_each(|c| c.write(&mut w))?;
        Ok(w.len())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    extern crate std;
    use super::*;
    use crate::link::shape::tests::arb_shape;
    use proptest::prelude::*;
    use std::vec::Vec;

    fn le(vals: &[f32]) -> Vec<u8> {
        vals.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    #[test]
    fn nav_bytes() {
        // time 1000 ms, at (10, -5), heading 0.5 rad, moving (1, 0) m/s, no body velocities.
        let b: [u8; NAV_LEN] = [
            0xe8, 0x03, 0, 0, 0, 0, 0, 0, // time_ms
            0x00, 0x00, 0x20, 0x41, // x = 10
            0x00, 0x00, 0xa0, 0xc0, // y = -5
            0x00, 0x00, 0x00, 0x3f, // heading = 0.5
            0x00, 0x00, 0x80, 0x3f, // vx = 1
            0x00, 0x00, 0x00, 0x00, // vy = 0
            0x00, // flags
        ];
        let n = NavRepr::parse(&b).unwrap();
        let want = NavRepr {
            time_ms: 1000,
            nav: NavState {
                position: Vec2::new(10.0, -5.0),
                heading: 0.5,
                velocity: Vec2::new(1.0, 0.0),
            },
            body: None,
        };
        assert_eq!(n, want);
        assert_eq!(n.nav.validate(), Ok(()));
        let mut out = [0u8; 64];
        assert_eq!(want.emit(&mut out), Ok(NAV_LEN));
        assert_eq!(&out[..NAV_LEN], &b);

        // With body velocities u = 1, v = 0, r = -0.25.
        let mut b2 = b.to_vec();
        b2[28] = 0x01;
        b2.extend([0x00, 0x00, 0x80, 0x3f, 0, 0, 0, 0, 0x00, 0x00, 0x80, 0xbe]);
        let n2 = NavRepr::parse(&b2).unwrap();
        assert_eq!(
            n2.body,
            Some(BodyVelocity {
                u: 1.0,
                v: 0.0,
                r: -0.25
            })
        );
        assert_eq!(n2.emit(&mut out), Ok(NAV_LEN_WITH_BODY));
        assert_eq!(&out[..NAV_LEN_WITH_BODY], &b2[..]);
    }

    #[test]
    fn nav_refusals() {
        let good = NavRepr {
            time_ms: 5,
            nav: NavState {
                position: Vec2::new(1.0, 2.0),
                heading: 0.0,
                velocity: Vec2::ZERO,
            },
            body: None,
        };
        let mut b = [0u8; 64];
        let n = good.emit(&mut b).unwrap();
        let b = &b[..n];
        let set = |off: usize, v: f32| {
            let mut c = b.to_vec();
            c[off..off + 4].copy_from_slice(&v.to_le_bytes());
            NavRepr::parse(&c)
        };
        assert_eq!(set(8, f32::NAN), Err(Error::field(1, Problem::NonFinite)));
        assert_eq!(set(12, 2.0e5), Err(Error::field(2, Problem::OutOfRange)));
        assert_eq!(
            set(16, f32::INFINITY),
            Err(Error::field(3, Problem::NonFinite))
        );
        assert_eq!(set(16, 90.0), Err(Error::field(3, Problem::OutOfRange)));
        assert_eq!(set(20, 25.0), Err(Error::field(4, Problem::OutOfRange)));
        assert_eq!(
            set(24, f32::NEG_INFINITY),
            Err(Error::field(5, Problem::NonFinite))
        );
        let mut flags = b.to_vec();
        flags[28] = 0x02;
        assert_eq!(
            NavRepr::parse(&flags),
            Err(Error::field(6, Problem::UnknownCode))
        );
        // Flag set but no body bytes; body bytes without the flag; short.
        flags[28] = 0x01;
        assert_eq!(NavRepr::parse(&flags), Err(Error::Length));
        let mut long = b.to_vec();
        long.extend([0u8; 12]);
        assert_eq!(NavRepr::parse(&long), Err(Error::Length));
        assert_eq!(NavRepr::parse(&b[..28]), Err(Error::Length));
        // Emit refuses what parse would refuse.
        let bad = NavRepr {
            body: Some(BodyVelocity {
                u: 0.0,
                v: 0.0,
                r: 100.0,
            }),
            ..good
        };
        assert_eq!(
            bad.emit(&mut [0u8; 64]),
            Err(Error::field(9, Problem::OutOfRange))
        );
    }

    #[test]
    fn scanline_bytes_borrow_the_bins() {
        let mut b = std::vec![0x10, 0x27, 0, 0, 0, 0, 0, 0]; // 10 000 ms
        b.extend(le(&[-0.5, 0.03125, 20.0])); // bearing, step, range
        b.extend([0x04, 0x00]); // 4 bins
        b.extend([0, 7, 200, 255]);
        assert_eq!(&b[8..12], &[0x00, 0x00, 0x00, 0xbf]);
        assert_eq!(&b[16..20], &[0x00, 0x00, 0xa0, 0x41]);
        let s = Scanline::parse(&b).unwrap();
        assert_eq!(s.time_ms, 10_000);
        assert_eq!(s.bearing_rad, -0.5);
        assert_eq!(s.step_rad, 0.03125);
        assert_eq!(s.range_m, 20.0);
        assert_eq!(s.bins, &[0, 7, 200, 255]);
        // Borrowed, not copied: the bins point into the payload.
        assert!(core::ptr::eq(s.bins.as_ptr(), b[22..].as_ptr()));
        assert_eq!(s.validate(), Ok(()));
        let mut out = [0u8; 64];
        assert_eq!(s.emit(&mut out), Ok(26));
        assert_eq!(&out[..26], &b[..]);
    }

    #[test]
    fn scanline_refusals() {
        let mut b = std::vec![0u8; 8];
        b.extend(le(&[0.0, 0.03, 20.0]));
        b.extend([0x02, 0x00, 1, 2]);
        assert!(Scanline::parse(&b).is_ok());
        let mut c = b.clone();
        c[20..22].copy_from_slice(&0u16.to_le_bytes());
        assert_eq!(
            Scanline::parse(&c[..22]),
            Err(Error::field(4, Problem::OutOfRange))
        );
        c[20..22].copy_from_slice(&513u16.to_le_bytes());
        assert_eq!(
            Scanline::parse(&c),
            Err(Error::field(4, Problem::OutOfRange))
        );
        c[20..22].copy_from_slice(&3u16.to_le_bytes());
        assert_eq!(Scanline::parse(&c), Err(Error::Length));
        let mut c = b.clone();
        c.push(9);
        assert_eq!(Scanline::parse(&c), Err(Error::Length));
        let mut c = b.clone();
        c[16..20].copy_from_slice(&500.0f32.to_le_bytes());
        assert_eq!(
            Scanline::parse(&c),
            Err(Error::field(3, Problem::OutOfRange))
        );
        let mut c = b.clone();
        c[12..16].copy_from_slice(&f32::NAN.to_le_bytes());
        assert_eq!(
            Scanline::parse(&c),
            Err(Error::field(2, Problem::NonFinite))
        );
        c[12..16].copy_from_slice(&(-0.5f32).to_le_bytes());
        assert_eq!(
            Scanline::parse(&c),
            Err(Error::field(2, Problem::OutOfRange))
        );
        let mut c = b.clone();
        c[8..12].copy_from_slice(&f32::INFINITY.to_le_bytes());
        assert_eq!(
            Scanline::parse(&c),
            Err(Error::field(1, Problem::NonFinite))
        );
    }

    #[test]
    fn contacts_bytes() {
        // time 7 ms; two contacts: obstacle 0x0102, circle (1, 2) r 0.5, still, confidence 1;
        // vehicle 3, circle (0, 0) r 1, moving (0.5, 0), confidence 0.25.
        let mut b = std::vec![7, 0, 0, 0, 0, 0, 0, 0, 2];
        b.extend([0x02, 0x01, 0x00, 0x00]);
        b.extend(le(&[1.0, 2.0, 0.5, 0.0, 0.0, 1.0]));
        b.extend([0x03, 0x00, 0x01, 0x00]);
        b.extend(le(&[0.0, 0.0, 1.0, 0.5, 0.0, 0.25]));
        let c = ContactsRepr::parse(&b).unwrap();
        assert_eq!(c.time_ms, 7);
        let v: Vec<Contact> = c.contacts.iter().collect();
        let want = [
            Contact {
                id: 0x0102,
                kind: ContactKind::Obstacle,
                shape: Shape::circle(Vec2::new(1.0, 2.0), 0.5).unwrap(),
                velocity: Vec2::ZERO,
                confidence: 1.0,
            },
            Contact {
                id: 3,
                kind: ContactKind::Vehicle,
                shape: Shape::circle(Vec2::ZERO, 1.0).unwrap(),
                velocity: Vec2::new(0.5, 0.0),
                confidence: 0.25,
            },
        ];
        assert_eq!(v, want);
        let sent = ContactsRepr {
            time_ms: 7,
            contacts: ContactList::new(&want),
        };
        assert_eq!(c, sent);
        let mut out = [0u8; 128];
        assert_eq!(sent.payload_len(), b.len());
        assert_eq!(sent.emit(&mut out), Ok(b.len()));
        assert_eq!(&out[..b.len()], &b[..]);
        // To the world tables.
        let o = want[0].to_obstacle(2.5, 100).unwrap();
        assert_eq!((o.id, o.origin, o.seen_ms), (0x0102, Origin::Sensed, 100));
        let a = want[1].to_agent(100).unwrap();
        assert_eq!(
            (a.id, a.position, a.velocity),
            (3, Vec2::ZERO, Vec2::new(0.5, 0.0))
        );
    }

    #[test]
    fn contacts_refusals() {
        let mut b = std::vec![0u8; 8];
        b.push(9);
        assert_eq!(
            ContactsRepr::parse(&b),
            Err(Error::field(1, Problem::OutOfRange))
        );
        let mut b = std::vec![0u8; 8];
        b.push(1);
        b.extend([0, 0, 2]); // kind 2
        b.extend([0u8; 13 + 12]);
        assert_eq!(
            ContactsRepr::parse(&b),
            Err(Error::field(3, Problem::UnknownCode))
        );
        let mut b = std::vec![0u8; 8];
        b.push(1);
        b.extend([0, 0, 0, 0]);
        b.extend(le(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.5]));
        assert_eq!(
            ContactsRepr::parse(&b),
            Err(Error::field(7, Problem::OutOfRange))
        );
        let n = b.len();
        b[n - 12..n - 8].copy_from_slice(&30.0f32.to_le_bytes());
        assert_eq!(
            ContactsRepr::parse(&b),
            Err(Error::field(5, Problem::OutOfRange))
        );
        b[n - 4..].copy_from_slice(&0.5f32.to_le_bytes());
        assert_eq!(
            ContactsRepr::parse(&b),
            Err(Error::field(5, Problem::OutOfRange))
        );
        b[n - 12..n - 8].copy_from_slice(&3.0f32.to_le_bytes());
        assert!(ContactsRepr::parse(&b).is_ok());
        b.push(0);
        assert_eq!(ContactsRepr::parse(&b), Err(Error::Length));
        // Count says 2, one entry present.
        b.pop();
        b[8] = 2;
        assert_eq!(ContactsRepr::parse(&b), Err(Error::Length));
        // Emit refuses more than MAX_CONTACTS.
        let one = ContactsRepr::parse(&{
            let mut x = b.clone();
            x[8] = 1;
            x
        })
        .unwrap()
        .contacts
        .iter()
        .next()
        .unwrap();
        let nine = [one; 9];
        let r = ContactsRepr {
            time_ms: 0,
            contacts: ContactList::new(&nine),
        };
        assert_eq!(
            r.emit(&mut [0u8; 2048]),
            Err(Error::field(1, Problem::OutOfRange))
        );
    }

    pub(crate) fn arb_nav() -> impl Strategy<Value = NavRepr> {
        (
            any::<u64>(),
            (-1e5f32..1e5, -1e5f32..1e5),
            -6.2f32..6.2,
            (-14.0f32..14.0, -14.0f32..14.0),
            proptest::option::of((-20.0f32..20.0, -20.0f32..20.0, -6.0f32..6.0)),
        )
            .prop_map(|(t, (x, y), h, (vx, vy), body)| NavRepr {
                time_ms: t,
                nav: NavState {
                    position: Vec2::new(x, y),
                    heading: h,
                    velocity: Vec2::new(vx, vy),
                },
                body: body.map(|(u, v, r)| BodyVelocity { u, v, r }),
            })
    }

    pub(crate) fn arb_contact() -> impl Strategy<Value = Contact> {
        (
            any::<u16>(),
            any::<bool>(),
            arb_shape(),
            (-14.0f32..14.0, -14.0f32..14.0),
            0.0f32..=1.0,
        )
            .prop_map(|(id, veh, shape, (vx, vy), confidence)| Contact {
                id,
                kind: if veh {
                    ContactKind::Vehicle
                } else {
                    ContactKind::Obstacle
                },
                shape,
                velocity: Vec2::new(vx, vy),
                confidence,
            })
    }

    /// OwnedMessage scanline fields: (time, bearing, step, range, bins).
    pub(crate) fn arb_scanline() -> impl Strategy<Value = (u64, f32, f32, f32, Vec<u8>)> {
        (
            any::<u64>(),
            -6.2f32..6.2,
            prop_oneof![0.001f32..0.2, -0.2f32..-0.001],
            0.5f32..200.0,
            proptest::collection::vec(any::<u8>(), 1..=MAX_BINS),
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

        #[test]
        fn nav_round_trips(n in arb_nav()) {
            let mut out = [0u8; NAV_LEN_WITH_BODY];
            let len = n.emit(&mut out).unwrap();
            prop_assert_eq!(len, n.payload_len());
            let back = NavRepr::parse(&out[..len]).unwrap();
            prop_assert_eq!(back, n);
            prop_assert_eq!(back.nav.validate(), Ok(()));
        }

        #[test]
        fn scanline_round_trips((t, b, s, r, bins) in arb_scanline()) {
            let sl = Scanline { time_ms: t, bearing_rad: b, step_rad: s, range_m: r, bins: &bins };
            let mut out = [0u8; SCANLINE_HEAD_LEN + MAX_BINS];
            let len = sl.emit(&mut out).unwrap();
            prop_assert_eq!(len, sl.payload_len());
            prop_assert_eq!(Scanline::parse(&out[..len]).unwrap(), sl);
        }

        #[test]
        fn contacts_round_trip(t in any::<u64>(), cs in proptest::collection::vec(arb_contact(), 0..=MAX_CONTACTS)) {
            let repr = ContactsRepr { time_ms: t, contacts: ContactList::new(&cs) };
            let mut out = [0u8; CONTACTS_HEAD_LEN + MAX_CONTACTS * MAX_CONTACT_LEN];
            let len = repr.emit(&mut out).unwrap();
            prop_assert_eq!(len, repr.payload_len());
            let back = ContactsRepr::parse(&out[..len]).unwrap();
            prop_assert_eq!(back, repr);
            prop_assert_eq!(back.contacts.len(), cs.len());
        }

        #[test]
        fn sensor_parsers_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..700)) {
            let _ = NavRepr::parse(&bytes);
            let _ = Scanline::parse(&bytes);
            if let Ok(c) = ContactsRepr::parse(&bytes) {
                // Whatever parses iterates fully.
                prop_assert_eq!(c.contacts.iter().count(), c.contacts.len());
            }
        }
    }
}
