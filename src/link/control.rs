//! Control messages, host → firmware: `Mission`, `ChartObstacle`, `ChartClear`, `Params` and
//! `Tick`. The firmware answers the first four with a [`ReplyRepr`](super::ReplyRepr).
//!
//! `Mission` and `Params` parse straight into the library's [`Mission`] and [`Params`].

use super::codec::{magnitude, refuse, within, Reader, Writer};
use super::formation::{self, FormationRows};
use super::frame::MessageType;
use super::payload::Payload;
use super::shape::{read_shape, shape_len, write_shape};
use super::{Error, Problem};
use crate::field::Shape;
use crate::params::{Kind, ParamId, Params, Value};
use crate::types::{Mission, MAX_COORD_M};
use crate::world::{ObjectError, Obstacle, Origin};
use field::{chart_clear, chart_obstacle, mission};

/// `Mission` payload length without a formation.
pub const MISSION_LEN: usize = 9;
/// `Mission` payload length with a formation.
pub const MISSION_LEN_WITH_FORMATION: usize = 22;
/// `Mission` flag bit: a formation follows.
pub const MISSION_FLAG_FORMATION: u8 = formation::FLAG_FORMATION;

/// Each message's rows (docs/protocol.md §6), by name: each constant is the row of the field
/// it names.
#[allow(missing_docs)]
pub mod field {
    /// `Mission`.
    pub mod mission {
        use crate::link::layout::Field;

        pub const GOAL_X: Field = Field::new(0, 0, "f32", "goal_x");
        pub const GOAL_Y: Field = Field::new(1, 4, "f32", "goal_y");
        pub const FLAGS: Field = Field::new(2, 8, "u8", "flags");
        pub const Q: Field = Field::new(3, 9, "u8", "q");
        pub const LATTICE_M: Field = Field::new(4, 10, "f32", "lattice_m");
        pub const ORIENTATION: Field = Field::new(5, 14, "f32", "orientation");
        pub const ATTRACTION: Field = Field::new(6, 18, "f32", "attraction");
        /// Every row, in order.
        pub const ALL: &[Field] = &[GOAL_X, GOAL_Y, FLAGS, Q, LATTICE_M, ORIENTATION, ATTRACTION];
    }

    /// `ChartObstacle`.
    pub mod chart_obstacle {
        use crate::link::layout::Field;

        pub const ID: Field = Field::new(0, 0, "u16", "id");
        pub const A_PLUS: Field = Field::new(1, 2, "f32", "a_plus");
        pub const SHAPE: Field = Field::new(2, 6, "shape", "shape");
        /// Every row, in order.
        pub const ALL: &[Field] = &[ID, A_PLUS, SHAPE];
    }

    /// `ChartClear`.
    pub mod chart_clear {
        use crate::link::layout::Field;

        pub const SCOPE: Field = Field::new(0, 0, "u8", "scope");
        pub const ID: Field = Field::new(1, 1, "u16", "id");
        /// Every row, in order.
        pub const ALL: &[Field] = &[SCOPE, ID];
    }

    /// `Tick`.
    pub mod tick {
        use crate::link::layout::Field;

        pub const TIME_MS: Field = Field::new(0, 0, "u64", "time_ms");
        /// Every row, in order.
        pub const ALL: &[Field] = &[TIME_MS];
    }

    /// `Params`: the rows are the parameters, [`ParamId`](crate::params::ParamId), in
    /// declaration order.
    pub use crate::params::ParamId as params;
}

/// The rows of `Mission`'s formation.
const FORMATION_ROWS: FormationRows = FormationRows {
    flags: mission::FLAGS,
    q: mission::Q,
    lattice_m: mission::LATTICE_M,
    orientation: mission::ORIENTATION,
    attraction: mission::ATTRACTION,
};

fn check_mission(m: &Mission) -> Result<(), Error> {
    magnitude(mission::GOAL_X, m.goal.x, MAX_COORD_M)?;
    magnitude(mission::GOAL_Y, m.goal.y, MAX_COORD_M)?;
    if let Some(f) = &m.formation {
        formation::check(f, &FORMATION_ROWS)?;
    }
    Ok(())
}

/// `Mission` (0x04): go to the goal, optionally keeping a formation (seed 001 §3.2).
///
/// Layout (9 or 22 bytes): 0 `goal_x` f32 · 1 `goal_y` f32 (|·| ≤ [`MAX_COORD_M`]) ·
/// 2 `flags` u8 (bit 0: formation follows) · \[3 `q` u8 (3, 4 or 6) · 4 `lattice_m` f32
/// (0.5 ..= 1000) · 5 `orientation` f32 (rad, ±2π) · 6 `attraction` f32 (0.001 ..= 10⁴)\].
/// A parsed mission is always accepted by
/// [`Planner::set_mission`](crate::planner::Planner::set_mission).
impl<'a> Payload<'a> for Mission {
    const TYPE: MessageType = MessageType::Mission;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let goal = r.vec2()?;
        let flags = r.u8()?;
        if flags & !MISSION_FLAG_FORMATION != 0 {
            return refuse(mission::FLAGS, Problem::UnknownCode);
        }
        let formation = if flags & MISSION_FLAG_FORMATION != 0 {
            Some(formation::read(&mut r)?)
        } else {
            None
        };
        r.finish()?;
        let m = Mission { goal, formation };
        check_mission(&m)?;
        Ok(m)
    }

    fn payload_len(&self) -> usize {
        if self.formation.is_some() {
            MISSION_LEN_WITH_FORMATION
        } else {
            MISSION_LEN
        }
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        check_mission(self)?;
        let mut w = Writer::new(out);
        w.vec2(self.goal)?;
        formation::write(&mut w, &self.formation)?;
        Ok(w.len())
    }
}

/// `ChartObstacle` (0x05): an obstacle from the chart or the mission plan. Charted obstacles
/// never age out and are never evicted; the same id replaces the entry.
///
/// Layout (6 + shape bytes): 0 `id` u16 · 1 `a_plus` f32 (A⁺, 0.001 ..= 100) · 2 `shape`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChartObstacleRepr {
    /// Obstacle id.
    pub id: u16,
    /// Repulsiveness A⁺ (seed 000 eq. 9).
    pub a_plus: f32,
    /// Geometry, world frame.
    pub shape: Shape,
}

impl ChartObstacleRepr {
    /// The obstacle for the world table, charted at `now_ms`.
    pub fn to_obstacle(&self, now_ms: u64) -> Result<Obstacle, ObjectError> {
        Obstacle::new(self.id, self.shape, self.a_plus, Origin::Charted, now_ms)
    }

    fn check(&self) -> Result<(), Error> {
        within(chart_obstacle::A_PLUS, self.a_plus, 0.001, 100.0)?;
        super::shape::check_shape(chart_obstacle::SHAPE, &self.shape)
    }
}

impl<'a> Payload<'a> for ChartObstacleRepr {
    const TYPE: MessageType = MessageType::ChartObstacle;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let id = r.u16()?;
        let a_plus = r.f32()?;
        let shape = read_shape(&mut r, chart_obstacle::SHAPE)?;
        r.finish()?;
        let c = ChartObstacleRepr { id, a_plus, shape };
        c.check()?;
        Ok(c)
    }

    fn payload_len(&self) -> usize {
        6 + shape_len(&self.shape)
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        self.check()?;
        let mut w = Writer::new(out);
        w.u16(self.id)?;
        w.f32(self.a_plus)?;
        write_shape(&mut w, chart_obstacle::SHAPE, &self.shape)?;
        Ok(w.len())
    }
}

/// `ChartClear` (0x06): remove charted obstacles (sensed ones are left to age out).
///
/// Layout (3 bytes): 0 `scope` u8 (0: every charted obstacle, 1: the one with `id`) ·
/// 1 `id` u16 (0 when scope is 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ChartClearRepr {
    /// Every charted obstacle.
    All,
    /// The charted obstacle with this id.
    One(u16),
}

impl<'a> Payload<'a> for ChartClearRepr {
    const TYPE: MessageType = MessageType::ChartClear;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let scope = r.u8()?;
        let id = r.u16()?;
        r.finish()?;
        match (scope, id) {
            (0, 0) => Ok(ChartClearRepr::All),
            (0, _) => refuse(chart_clear::ID, Problem::Invalid),
            (1, id) => Ok(ChartClearRepr::One(id)),
            _ => refuse(chart_clear::SCOPE, Problem::UnknownCode),
        }
    }

    fn payload_len(&self) -> usize {
        3
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        let (scope, id) = match *self {
            ChartClearRepr::All => (0, 0),
            ChartClearRepr::One(id) => (1, id),
        };
        let mut w = Writer::new(out);
        w.u8(scope)?;
        w.u16(id)?;
        Ok(w.len())
    }
}

/// The names of [`Params`]' fields in wire order: the parameter index of a `Params` field and
/// of a [`ReplyRepr`](super::ReplyRepr) rejecting it (from the declaration in `crate::params`).
pub use crate::params::PARAM_NAMES;

/// The wire index of the parameter called `name` (as in
/// [`ParamError::name`](crate::params::ParamError)).
pub fn param_index(name: &str) -> Option<u8> {
    ParamId::from_name(name).map(ParamId::index)
}

const fn wire_len(ids: &[ParamId]) -> usize {
    match ids {
        [first, rest @ ..] => first.kind().wire_len() + wire_len(rest),
        [] => 0,
    }
}

/// `Params` payload length: every declared parameter's wire length.
pub const PARAMS_LEN: usize = wire_len(&ParamId::ALL);

/// The `f32` parameters must be finite (the ranges are the planner's).
fn check_params(p: &Params) -> Result<(), Error> {
    ParamId::ALL.iter().try_for_each(|&id| match p.get(id) {
        Value::F32(v) if !v.is_finite() => Err(Error::field(id.index(), Problem::NonFinite)),
        _ => Ok(()),
    })
}

/// `Params` (0x07): the whole parameter set, every parameter of [`Params`] in declaration order
/// ([`ParamId`]: its index is the row) as its [`Kind`] says: `f32`, `u8`, `u32`, or an enum's
/// `u8` code (`bounding`: 0 plain, 1 split; `strategy`: 0 vpf, 1 multipoint, 2 navfn).
///
/// Only non-finite numbers and unknown codes are refused here. Ranges are checked by
/// [`Planner::set_params`](crate::planner::Planner::set_params), whose
/// [`ParamError`](crate::params::ParamError) the firmware turns into a [`ReplyRepr`](super::ReplyRepr) with
/// [`ReplyRepr::from_step_error`](super::ReplyRepr::from_step_error). So a host can also send
/// out-of-range values on purpose, to test that they are refused.
impl<'a> Payload<'a> for Params {
    const TYPE: MessageType = MessageType::Params;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let mut p = Params::default();
        for id in ParamId::ALL {
            let v = match id.kind() {
                Kind::F32 => Value::F32(r.f32()?),
                Kind::U8 => Value::U8(r.u8()?),
                Kind::U32 => Value::U32(r.u32()?),
                Kind::Code(_) => Value::Code(r.u8()?),
            };
            if !p.set(id, v) {
                return Err(Error::field(id.index(), Problem::UnknownCode));
            }
        }
        r.finish()?;
        check_params(&p)?;
        Ok(p)
    }

    fn payload_len(&self) -> usize {
        PARAMS_LEN
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        check_params(self)?;
        let mut w = Writer::new(out);
        for id in ParamId::ALL {
            match self.get(id) {
                Value::F32(v) => w.f32(v)?,
                Value::U8(v) | Value::Code(v) => w.u8(v)?,
                Value::U32(v) => w.u32(v)?,
            }
        }
        Ok(w.len())
    }
}

/// `Tick` (0x08): lockstep mode. The host owns the clock: each Tick sets the firmware's time
/// and runs the planner periods due up to it, so a simulation runs deterministically and
/// faster than real time.
///
/// Layout (8 bytes): 0 `time_ms` u64.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TickRepr {
    /// The new firmware time, ms.
    pub time_ms: u64,
}

impl<'a> Payload<'a> for TickRepr {
    const TYPE: MessageType = MessageType::Tick;

    fn parse(payload: &'a [u8]) -> Result<Self, Error> {
        let mut r = Reader::new(payload);
        let time_ms = r.u64()?;
        r.finish()?;
        Ok(TickRepr { time_ms })
    }

    fn payload_len(&self) -> usize {
        8
    }

    fn emit(&self, out: &mut [u8]) -> Result<usize, Error> {
        let mut w = Writer::new(out);
        w.u64(self.time_ms)?;
        Ok(w.len())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    extern crate std;
    use super::*;
    use crate::link::shape::tests::arb_shape;
    use crate::math::Vec2;
    use crate::types::Formation;
    use proptest::prelude::*;
    use proptest::strategy::Strategy;
    use std::vec::Vec;

    fn le(vals: &[f32]) -> Vec<u8> {
        vals.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    #[test]
    fn mission_bytes() {
        let b = [
            0x00, 0x00, 0x20, 0x41, // goal_x = 10
            0x00, 0x00, 0xa0, 0xc0, // goal_y = -5
            0x00, // no formation
        ];
        let m = Mission::parse(&b).unwrap();
        let want = Mission {
            goal: Vec2::new(10.0, -5.0),
            formation: None,
        };
        assert_eq!(m, want);
        let mut out = [0u8; 32];
        assert_eq!(m.emit(&mut out), Ok(9));
        assert_eq!(&out[..9], &b);

        let mut f = b.to_vec();
        f[8] = 1;
        f.push(6); // hexagonal
        f.extend(le(&[2.0, 0.0, 10.0]));
        let m = Mission::parse(&f).unwrap();
        let want = Formation {
            q: 6,
            lattice_m: 2.0,
            orientation: 0.0,
            attraction: 10.0,
        };
        assert_eq!(m.formation, Some(want));
        assert_eq!(m.emit(&mut out), Ok(22));
        assert_eq!(&out[..22], &f[..]);
    }

    #[test]
    fn mission_refusals() {
        let mut f = std::vec![0u8; 8];
        f.push(1);
        f.push(5);
        f.extend(le(&[2.0, 0.0, 10.0]));
        assert_eq!(
            Mission::parse(&f),
            Err(Error::field(3, Problem::UnknownCode))
        );
        f[9] = 4;
        assert!(Mission::parse(&f).is_ok());
        f[10..14].copy_from_slice(&0.1f32.to_le_bytes());
        assert_eq!(
            Mission::parse(&f),
            Err(Error::field(4, Problem::OutOfRange))
        );
        f[10..14].copy_from_slice(&2.0f32.to_le_bytes());
        f[18..22].copy_from_slice(&f32::NAN.to_le_bytes());
        assert_eq!(Mission::parse(&f), Err(Error::field(6, Problem::NonFinite)));
        f[8] = 3;
        assert_eq!(
            Mission::parse(&f),
            Err(Error::field(2, Problem::UnknownCode))
        );
        f[8] = 0;
        assert_eq!(Mission::parse(&f), Err(Error::Length));
        let mut g = std::vec![0u8; 9];
        g[0..4].copy_from_slice(&1e6f32.to_le_bytes());
        assert_eq!(
            Mission::parse(&g),
            Err(Error::field(0, Problem::OutOfRange))
        );
    }

    #[test]
    fn chart_bytes() {
        // id 0x1234, A⁺ 2.5, circle at (100, 0) radius 4.
        let mut b = std::vec![0x34, 0x12, 0x00, 0x00, 0x20, 0x40, 0x00];
        b.extend(le(&[100.0, 0.0, 4.0]));
        let c = ChartObstacleRepr::parse(&b).unwrap();
        let want = ChartObstacleRepr {
            id: 0x1234,
            a_plus: 2.5,
            shape: Shape::circle(Vec2::new(100.0, 0.0), 4.0).unwrap(),
        };
        assert_eq!(c, want);
        let mut out = [0u8; 80];
        assert_eq!(want.emit(&mut out), Ok(b.len()));
        assert_eq!(&out[..b.len()], &b[..]);
        let o = want.to_obstacle(9).unwrap();
        assert_eq!((o.id, o.origin, o.a_plus()), (0x1234, Origin::Charted, 2.5));
        b[2..6].copy_from_slice(&200.0f32.to_le_bytes());
        assert_eq!(
            ChartObstacleRepr::parse(&b),
            Err(Error::field(1, Problem::OutOfRange))
        );

        assert_eq!(ChartClearRepr::parse(&[0, 0, 0]), Ok(ChartClearRepr::All));
        assert_eq!(
            ChartClearRepr::parse(&[1, 0x34, 0x12]),
            Ok(ChartClearRepr::One(0x1234))
        );
        assert_eq!(
            ChartClearRepr::parse(&[0, 1, 0]),
            Err(Error::field(1, Problem::Invalid))
        );
        assert_eq!(
            ChartClearRepr::parse(&[2, 0, 0]),
            Err(Error::field(0, Problem::UnknownCode))
        );
        assert_eq!(ChartClearRepr::parse(&[1, 0]), Err(Error::Length));
        let mut out = [0u8; 3];
        assert_eq!(ChartClearRepr::One(0x1234).emit(&mut out), Ok(3));
        assert_eq!(out, [1, 0x34, 0x12]);
    }

    #[test]
    fn params_bytes_in_declaration_order() {
        let p = Params::default();
        let mut out = [0u8; PARAMS_LEN];
        assert_eq!(p.emit(&mut out), Ok(PARAMS_LEN));
        // Hand-checked fields of the default set.
        assert_eq!(&out[0..4], &[0xcd, 0xcc, 0xcc, 0x3d]); // period_s 0.1
        assert_eq!(&out[4..8], &[0x00, 0x00, 0x80, 0x3e]); // epsilon_m 0.25
        assert_eq!(out[8], 16); // n_gamma
        assert_eq!(&out[9..13], &[0xcd, 0xcc, 0xcc, 0x3e]); // mu 0.4
        assert_eq!(&out[29..33], &[0x00, 0x00, 0x48, 0x42]); // a_minus 50
        assert_eq!(out[37], 1); // bounding: split
        assert_eq!(&out[38..42], &[0x00, 0x00, 0x00, 0x3f]); // agent_radius_m 0.5
        assert_eq!(&out[70..74], &[0x00, 0x00, 0x70, 0x42]); // ghost_timeout_s 60
        assert_eq!(out[74], 4); // max_ghosts
        assert_eq!(&out[75..79], &[1, 0, 0, 0]); // seed
        assert_eq!(out[79], 0); // strategy: vpf
        assert_eq!(&out[80..84], &[0x00, 0x00, 0x20, 0x41]); // horizon_s 10
        assert_eq!(out[88], 25); // mp_points
        assert_eq!(out[105], 9); // mp_periphery
        assert_eq!(&out[110..114], &[0x00, 0x00, 0x7a, 0x44]); // nf_workspace_m 1000
        assert_eq!(&out[114..118], &[0x00, 0x00, 0x00, 0x40]); // route_cell_m 2
        assert_eq!(&out[118..126], &[0; 8]); // turn_rate_rps 0, brake_mps2 0
        assert_eq!(Params::parse(&out), Ok(p));

        // Non-finite and unknown codes are refused at the wire, naming the parameter.
        let mut bad = out;
        bad[9..13].copy_from_slice(&f32::NAN.to_le_bytes());
        assert_eq!(
            Params::parse(&bad),
            Err(Error::field(3, Problem::NonFinite))
        );
        assert_eq!(PARAM_NAMES[3], "mu");
        let mut bad = out;
        bad[37] = 2;
        assert_eq!(
            Params::parse(&bad),
            Err(Error::field(10, Problem::UnknownCode))
        );
        // Ranges are not checked here, but by Params::validate (reply path).
        let mut far = out;
        far[0..4].copy_from_slice(&5.0f32.to_le_bytes());
        let parsed = Params::parse(&far).unwrap();
        let e = parsed.validate().unwrap_err();
        assert_eq!(param_index(e.name), Some(0));
        assert_eq!(Params::parse(&out[..PARAMS_LEN - 1]), Err(Error::Length));
        let mut bad = out;
        bad[79] = 3;
        assert_eq!(
            Params::parse(&bad),
            Err(Error::field(22, Problem::UnknownCode))
        );
        assert_eq!(PARAM_NAMES[22], "strategy");
    }

    #[test]
    fn param_names_match_the_validator() {
        // Every name Params::validate can report has an index.
        let p = Params {
            period_s: f32::NAN,
            ..Params::default()
        };
        assert_eq!(param_index(p.validate().unwrap_err().name), Some(0));
        let p = Params {
            stall_speed: 100.0,
            ..Params::default()
        };
        assert_eq!(param_index(p.validate().unwrap_err().name), Some(17));
        let p = Params {
            n_gamma: 1,
            ..Params::default()
        };
        assert_eq!(param_index(p.validate().unwrap_err().name), Some(2));
        assert_eq!(param_index("nope"), None);
    }

    #[test]
    fn tick_bytes() {
        let b = [0xe8, 0x03, 0, 0, 0, 0, 0, 0];
        assert_eq!(TickRepr::parse(&b), Ok(TickRepr { time_ms: 1000 }));
        assert_eq!(TickRepr::parse(&b[..7]), Err(Error::Length));
        let mut out = [0u8; 8];
        assert_eq!(TickRepr { time_ms: 1000 }.emit(&mut out), Ok(8));
        assert_eq!(out, b);
    }

    pub(crate) fn arb_mission() -> impl Strategy<Value = Mission> {
        (
            (-1e5f32..1e5, -1e5f32..1e5),
            proptest::option::of((
                prop_oneof![Just(3u8), Just(4), Just(6)],
                0.5f32..1000.0,
                -6.2f32..6.2,
                0.001f32..1e4,
            )),
        )
            .prop_map(|((x, y), f)| Mission {
                goal: Vec2::new(x, y),
                formation: f.map(|(q, lattice_m, orientation, attraction)| Formation {
                    q,
                    lattice_m,
                    orientation,
                    attraction,
                }),
            })
    }

    /// Any parameter set the wire carries: every f32 finite, any u8 and u32, any defined code.
    pub(crate) fn arb_params() -> impl Strategy<Value = Params> {
        use crate::params::PARAM_COUNT;
        (
            proptest::collection::vec(-1e6f32..1e6, PARAM_COUNT),
            proptest::collection::vec(any::<u8>(), PARAM_COUNT),
            any::<u32>(),
        )
            .prop_map(|(f, b, seed)| {
                let mut p = Params::default();
                for (i, id) in ParamId::ALL.into_iter().enumerate() {
                    let v = match id.kind() {
                        Kind::F32 => Value::F32(f[i]),
                        Kind::U8 => Value::U8(b[i]),
                        Kind::U32 => Value::U32(seed),
                        Kind::Code(names) => Value::Code(b[i] % names.len() as u8),
                    };
                    assert!(p.set(id, v));
                }
                p
            })
    }

    pub(crate) fn arb_chart() -> impl Strategy<Value = ChartObstacleRepr> {
        (any::<u16>(), 0.001f32..100.0, arb_shape())
            .prop_map(|(id, a_plus, shape)| ChartObstacleRepr { id, a_plus, shape })
    }

    proptest! {
        #![proptest_config(ProptestConfig { failure_persistence: None, ..ProptestConfig::default() })]

        #[test]
        fn mission_round_trips(m in arb_mission()) {
            let mut out = [0u8; MISSION_LEN_WITH_FORMATION];
            let n = m.emit(&mut out).unwrap();
            prop_assert_eq!(n, m.payload_len());
            prop_assert_eq!(Mission::parse(&out[..n]), Ok(m));
            // What the wire accepts, the planner accepts.
            let mut planner = crate::planner::Planner::new(Params::default()).unwrap();
            prop_assert_eq!(planner.set_mission(m), Ok(()));
        }

        #[test]
        fn params_round_trip(p in arb_params()) {
            let mut out = [0u8; PARAMS_LEN];
            prop_assert_eq!(p.emit(&mut out), Ok(PARAMS_LEN));
            prop_assert_eq!(Params::parse(&out), Ok(p));
        }

        #[test]
        fn chart_round_trips(c in arb_chart(), id in any::<u16>(), all in any::<bool>()) {
            let mut out = [0u8; 80];
            let n = c.emit(&mut out).unwrap();
            prop_assert_eq!(n, c.payload_len());
            prop_assert_eq!(ChartObstacleRepr::parse(&out[..n]), Ok(c));
            let cc = if all { ChartClearRepr::All } else { ChartClearRepr::One(id) };
            prop_assert_eq!(cc.emit(&mut out), Ok(3));
            prop_assert_eq!(ChartClearRepr::parse(&out[..3]), Ok(cc));
        }

        #[test]
        fn control_parsers_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..100)) {
            let _ = Mission::parse(&bytes);
            let _ = ChartObstacleRepr::parse(&bytes);
            let _ = ChartClearRepr::parse(&bytes);
            let _ = Params::parse(&bytes);
            let _ = TickRepr::parse(&bytes);
        }
    }
}
