//! Missions: a single goal ([`Mission`]), or a list of waypoints flown in order and what the
//! vehicle does at the end.
//!
//! A [`Waypoint`] is a position with an **arrival radius** and an optional **speed** (the
//! bound on the leg *to* it). The current waypoint advances when the vehicle comes within its
//! radius. Intermediate waypoints are passed at speed: the planner keeps its cruise goal-point
//! ahead of the vehicle and does not brake (`crate::planner::vpf::goal_point`,
//! `Planner::arrival_speed`). What happens at the last one is the [`MissionEnd`]:
//! - [`MissionEnd::Hold`]: brake onto it and keep station there — what a hovering vehicle (a
//!   ROV such as the VideoRay) does, and what a single-goal [`Mission`] has
//!   always done (it is the one-waypoint, hold-at-last case, with `Params::arrival_radius_m`);
//! - [`MissionEnd::Loiter`]: arrive at speed and then **circle** the last waypoint at the
//!   loiter radius, clockwise or not, at the last waypoint's speed — what a torpedo-shaped AUV,
//!   which needs way on to steer, does at the end of a mission (REMUS and Iver "loiter",
//!   MOOS-IvP's `BHV_Loiter`), and what MAVLink's `NAV_LOITER_UNLIM` means with a radius.
//!
//! None of the seed papers has waypoints; how the planner flies them is
//! `crate::planner::mission`.
//!
//! A **survey** ([`Survey`]) is a lawnmower over a rectangle: straight lines along the
//! rectangle's heading, spaced at most `spacing_m` apart across it, flown back and forth, each
//! line two waypoints. It is expanded into the same fixed-capacity list and refused, naming the
//! limit, when it does not fit.
//!
//! Capacity: [`MAX_WAYPOINTS`] waypoints (16 × 16 bytes); a longer route is flown as several
//! missions.

use heapless::Vec;

use super::{Formation, MAX_COORD_M};
use crate::math::{Vec2, PI};

/// The mission: where to go, and optionally which formation to keep. A single goal is the
/// one-waypoint, hold-at-last case of a waypoint mission ([`Planner::set_waypoints`](crate::planner::Planner::set_waypoints));
/// while one is flown, [`Planner::mission`](crate::planner::Planner::mission) gives the waypoint being flown to.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Mission {
    /// The goal-point p_GP, m (000 eq. 13).
    pub goal: Vec2,
    /// Formation by virtual leader (001 §3.2), if any.
    pub formation: Option<Formation>,
}

/// Most waypoints in a mission (a survey of 8 lines).
pub const MAX_WAYPOINTS: usize = 16;
/// Largest arrival radius, m.
pub const MAX_WAYPOINT_RADIUS_M: f32 = 1000.0;
/// Fastest speed a waypoint may ask for, m/s (the top of `Params::v_max`'s range; the planner
/// flies at most v_max anyway).
pub const MAX_WAYPOINT_SPEED: f32 = 20.0;
/// Smallest speed a waypoint may ask for, m/s (`Params::v_max`'s floor).
pub const MIN_WAYPOINT_SPEED: f32 = 0.01;
/// Loiter radii, m: at least a vehicle length, at most a kilometre.
pub const LOITER_RADIUS_M: (f32, f32) = (1.0, 1000.0);
/// Largest side of a survey rectangle, m.
pub const MAX_SURVEY_SIDE_M: f32 = 10_000.0;

/// Why a waypoint was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum WaypointError {
    /// A coordinate, the radius or the speed is NaN or infinite.
    NonFinite,
    /// A coordinate is beyond ±[`MAX_COORD_M`].
    Position,
    /// The arrival radius is not in (0, [`MAX_WAYPOINT_RADIUS_M`]].
    Radius,
    /// The speed is not in [`MIN_WAYPOINT_SPEED`] ..= [`MAX_WAYPOINT_SPEED`].
    Speed,
}

impl core::fmt::Display for WaypointError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            WaypointError::NonFinite => "a waypoint number is not finite",
            WaypointError::Position => "waypoint beyond ±100 km",
            WaypointError::Radius => "arrival radius must be > 0 and at most 1000 m",
            WaypointError::Speed => "speed must be 0.01 ..= 20 m/s",
        })
    }
}

impl core::error::Error for WaypointError {}

/// Why a mission was refused. Nothing changes when one is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MissionError {
    /// No waypoint.
    Empty,
    /// More waypoints than the list holds: `needed` against the `limit`, [`MAX_WAYPOINTS`].
    TooMany {
        /// How many were asked for (a survey: two per line).
        needed: usize,
        /// The capacity.
        limit: usize,
    },
    /// Waypoint `index` (0-based) is bad.
    Waypoint {
        /// Which one.
        index: usize,
        /// What is wrong.
        error: WaypointError,
    },
    /// The loiter radius is non-finite or outside [`LOITER_RADIUS_M`].
    LoiterRadius,
    /// A survey's rectangle or spacing is non-finite, not positive or too large.
    SurveyArea,
}

impl core::fmt::Display for MissionError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            MissionError::Empty => f.write_str("mission has no waypoint"),
            MissionError::TooMany { needed, limit } => {
                write!(f, "{needed} waypoints, the mission holds at most {limit}")
            }
            MissionError::Waypoint { index, error } => write!(f, "waypoint {index}: {error}"),
            MissionError::LoiterRadius => f.write_str("loiter radius must be 1 ..= 1000 m"),
            MissionError::SurveyArea => f.write_str(
                "survey sides and spacing must be finite, > 0 and at most 10 km; corner within ±100 km",
            ),
        }
    }
}

impl core::error::Error for MissionError {}

/// A waypoint: where, how close counts as arrived, and how fast to fly the leg to it. Built
/// only through [`Waypoint::new`] (and [`Waypoint::with_speed`]), so every one is valid.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Waypoint {
    position: Vec2,
    radius_m: f32,
    /// 0: no speed of its own (v_max).
    speed: f32,
}

impl Waypoint {
    /// A waypoint at `position` (m, within ±[`MAX_COORD_M`]) reached within `radius_m` (m,
    /// (0, [`MAX_WAYPOINT_RADIUS_M`]]), flown to at the planner's v_max.
    pub fn new(position: Vec2, radius_m: f32) -> Result<Self, WaypointError> {
        if !position.is_finite() || !radius_m.is_finite() {
            return Err(WaypointError::NonFinite);
        }
        if position.x.abs() > MAX_COORD_M || position.y.abs() > MAX_COORD_M {
            return Err(WaypointError::Position);
        }
        if !(radius_m > 0.0 && radius_m <= MAX_WAYPOINT_RADIUS_M) {
            return Err(WaypointError::Radius);
        }
        Ok(Waypoint {
            position,
            radius_m,
            speed: 0.0,
        })
    }

    /// The same waypoint flown to at `speed` m/s ([`MIN_WAYPOINT_SPEED`] ..=
    /// [`MAX_WAYPOINT_SPEED`]; the planner's v_max still bounds it), or at v_max with `None`.
    pub fn with_speed(self, speed: Option<f32>) -> Result<Self, WaypointError> {
        let Some(s) = speed else {
            return Ok(Waypoint { speed: 0.0, ..self });
        };
        if !s.is_finite() {
            return Err(WaypointError::NonFinite);
        }
        if !(MIN_WAYPOINT_SPEED..=MAX_WAYPOINT_SPEED).contains(&s) {
            return Err(WaypointError::Speed);
        }
        Ok(Waypoint { speed: s, ..self })
    }

    /// A single-goal mission's waypoint: its radius (0 here) is `Params::arrival_radius_m`,
    /// whatever that is when it is flown. `position` is checked by the caller.
    pub(crate) const fn with_parameter_radius(position: Vec2) -> Self {
        Waypoint {
            position,
            radius_m: 0.0,
            speed: 0.0,
        }
    }

    /// Position, m.
    pub fn position(&self) -> Vec2 {
        self.position
    }

    /// Arrival radius, m (0 for a single-goal mission's: `Params::arrival_radius_m`).
    pub fn radius_m(&self) -> f32 {
        self.radius_m
    }

    /// The speed of the leg to it, m/s, if it has one.
    pub fn speed(&self) -> Option<f32> {
        (self.speed > 0.0).then_some(self.speed)
    }
}

/// What the vehicle does once it has reached the last waypoint.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MissionEnd {
    /// Brake onto the last waypoint and keep station there.
    Hold,
    /// Circle the last waypoint at `radius_m` ([`LOITER_RADIUS_M`]), counter-clockwise seen
    /// from above unless `clockwise`, at the last waypoint's speed (or v_max).
    Loiter {
        /// Radius of the circle, m.
        radius_m: f32,
        /// Sense of the circle.
        clockwise: bool,
    },
}

impl MissionEnd {
    /// Checks the loiter radius.
    pub fn validate(&self) -> Result<(), MissionError> {
        match *self {
            MissionEnd::Hold => Ok(()),
            MissionEnd::Loiter { radius_m, .. } => {
                let (lo, hi) = LOITER_RADIUS_M;
                if radius_m.is_finite() && (lo..=hi).contains(&radius_m) {
                    Ok(())
                } else {
                    Err(MissionError::LoiterRadius)
                }
            }
        }
    }
}

/// A mission's waypoints and its end, validated: never empty, at most [`MAX_WAYPOINTS`].
#[derive(Clone, Debug, PartialEq)]
pub struct Waypoints {
    list: Vec<Waypoint, MAX_WAYPOINTS>,
    end: MissionEnd,
}

impl Waypoints {
    /// The mission through `points` in order, ending with `end`.
    pub fn new(points: &[Waypoint], end: MissionEnd) -> Result<Self, MissionError> {
        end.validate()?;
        if points.is_empty() {
            return Err(MissionError::Empty);
        }
        let list = Vec::from_slice(points).map_err(|()| MissionError::TooMany {
            needed: points.len(),
            limit: MAX_WAYPOINTS,
        })?;
        Ok(Waypoints { list, end })
    }

    /// One waypoint, held at: a single-goal mission.
    pub fn single(w: Waypoint) -> Self {
        let mut list = Vec::new();
        // A fresh list has room for one.
        let _ = list.push(w);
        Waypoints {
            list,
            end: MissionEnd::Hold,
        }
    }

    /// The lawnmower over `survey`'s rectangle, ending with `end` ([`Survey::waypoints`]).
    pub fn survey(survey: &Survey, end: MissionEnd) -> Result<Self, MissionError> {
        end.validate()?;
        let list = survey.waypoints()?;
        Ok(Waypoints { list, end })
    }

    /// The waypoints, in order.
    pub fn as_slice(&self) -> &[Waypoint] {
        &self.list
    }

    /// How many.
    pub fn len(&self) -> usize {
        self.list.len()
    }

    /// Never (a valid list is not empty); for the convention.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// What happens at the last one.
    pub fn end(&self) -> MissionEnd {
        self.end
    }

    /// Waypoint `i`.
    pub fn get(&self, i: usize) -> Option<&Waypoint> {
        self.list.get(i)
    }

    /// Length of the route from `p` through waypoints `from ..`, m.
    pub fn distance_to_go(&self, p: Vec2, from: usize) -> f32 {
        let mut last = p;
        let mut sum = 0.0;
        for w in self.list.iter().skip(from) {
            sum += (w.position - last).norm();
            last = w.position;
        }
        sum
    }
}

/// A lawnmower survey: the rectangle with one corner at `corner`, `length_m` along `heading`
/// (rad, counter-clockwise from +x) and `width_m` to its left (counter-clockwise side), covered
/// by lines along the heading at most `spacing_m` apart.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Survey {
    /// The corner the survey starts at, m.
    pub corner: Vec2,
    /// Side along the heading (the lines' length), m.
    pub length_m: f32,
    /// Side across it, m.
    pub width_m: f32,
    /// Direction of the first line, rad.
    pub heading: f32,
    /// Largest distance between neighbouring lines, m (a sonar's swath less its overlap).
    pub spacing_m: f32,
    /// Arrival radius of every waypoint, m.
    pub radius_m: f32,
    /// Speed of every leg, m/s (`None`: v_max).
    pub speed: Option<f32>,
}

impl Survey {
    /// Lines needed: ⌈width / spacing⌉ + 1, evenly spaced, so that the rectangle's both long
    /// sides are flown and no two lines are farther apart than `spacing_m`.
    pub fn lines(&self) -> Result<usize, MissionError> {
        let sides = [self.length_m, self.width_m, self.spacing_m];
        let ok = sides
            .iter()
            .all(|s| s.is_finite() && *s > 0.0 && *s <= MAX_SURVEY_SIDE_M)
            && self.heading.is_finite()
            && self.heading.abs() <= 2.0 * PI
            && self.corner.is_finite();
        if !ok {
            return Err(MissionError::SurveyArea);
        }
        // ⌈w/s⌉ without a float-to-int conversion that could saturate: both are ≤ 10 km and
        // s > 0, but w/s can still be huge (1e4 / 1e-30), so it is compared before it is cast.
        let ratio = self.width_m / self.spacing_m;
        if ratio >= MAX_WAYPOINTS as f32 {
            return Err(MissionError::TooMany {
                needed: 2 * (MAX_WAYPOINTS / 2 + 1),
                limit: MAX_WAYPOINTS,
            });
        }
        let whole = ratio as usize;
        let gaps = if (whole as f32) < ratio {
            whole + 1
        } else {
            whole
        };
        Ok(gaps.max(1) + 1)
    }

    /// The waypoints: line k runs from its start to its end (even k) or back (odd k); two per
    /// line, all with `radius_m` and `speed`.
    pub fn waypoints(&self) -> Result<Vec<Waypoint, MAX_WAYPOINTS>, MissionError> {
        let lines = self.lines()?;
        if 2 * lines > MAX_WAYPOINTS {
            return Err(MissionError::TooMany {
                needed: 2 * lines,
                limit: MAX_WAYPOINTS,
            });
        }
        let along = Vec2::from_angle(self.heading);
        let across = along.perp();
        let step = self.width_m / (lines - 1) as f32;
        let mut list = Vec::new();
        for k in 0..lines {
            let a = self.corner + across * (step * k as f32);
            let b = a + along * self.length_m;
            let (first, second) = if k % 2 == 0 { (a, b) } else { (b, a) };
            for (j, p) in [first, second].into_iter().enumerate() {
                let w = Waypoint::new(p, self.radius_m)
                    .and_then(|w| w.with_speed(self.speed))
                    .map_err(|error| MissionError::Waypoint {
                        index: 2 * k + j,
                        error,
                    })?;
                // 2·lines ≤ MAX_WAYPOINTS was checked above.
                let _ = list.push(w);
            }
        }
        Ok(list)
    }
}

/// How far along its mission a vehicle is (all zero: no mission).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MissionProgress {
    /// Index of the waypoint being flown to, 0-based; equal to `count` once the last one has
    /// been reached (holding or loitering there).
    pub current: u8,
    /// Waypoints in the mission (1 for a single goal).
    pub count: u8,
    /// Distance from the vehicle through the remaining waypoints, m (0 once complete).
    pub to_go_m: f32,
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    fn wp(x: f32, y: f32) -> Waypoint {
        Waypoint::new(Vec2::new(x, y), 2.0).unwrap()
    }

    #[test]
    fn waypoints_are_checked_where_they_are_made() {
        let p = Vec2::new(1.0, 2.0);
        assert_eq!(
            Waypoint::new(Vec2::new(f32::NAN, 0.0), 1.0),
            Err(WaypointError::NonFinite)
        );
        assert_eq!(
            Waypoint::new(Vec2::new(2e5, 0.0), 1.0),
            Err(WaypointError::Position)
        );
        assert_eq!(Waypoint::new(p, 0.0), Err(WaypointError::Radius));
        assert_eq!(Waypoint::new(p, -1.0), Err(WaypointError::Radius));
        assert_eq!(
            Waypoint::new(p, f32::INFINITY),
            Err(WaypointError::NonFinite)
        );
        let w = Waypoint::new(p, 3.0).unwrap();
        assert_eq!(w.with_speed(Some(0.0)), Err(WaypointError::Speed));
        assert_eq!(w.with_speed(Some(21.0)), Err(WaypointError::Speed));
        assert_eq!(w.with_speed(Some(f32::NAN)), Err(WaypointError::NonFinite));
        let fast = w.with_speed(Some(0.7)).unwrap();
        assert_eq!((fast.speed(), w.speed()), (Some(0.7), None));
        assert_eq!((fast.position(), fast.radius_m()), (p, 3.0));
    }

    #[test]
    fn lists_are_refused_empty_too_long_or_with_a_bad_loiter() {
        assert_eq!(
            Waypoints::new(&[], MissionEnd::Hold),
            Err(MissionError::Empty)
        );
        let many = [wp(0.0, 0.0); MAX_WAYPOINTS + 1];
        assert_eq!(
            Waypoints::new(&many, MissionEnd::Hold),
            Err(MissionError::TooMany {
                needed: 17,
                limit: 16
            })
        );
        assert!(Waypoints::new(&many[..MAX_WAYPOINTS], MissionEnd::Hold).is_ok());
        for radius_m in [0.5, f32::NAN, 2000.0] {
            let end = MissionEnd::Loiter {
                radius_m,
                clockwise: false,
            };
            assert_eq!(
                Waypoints::new(&many[..2], end),
                Err(MissionError::LoiterRadius)
            );
        }
        let w = Waypoints::new(&[wp(3.0, 4.0), wp(3.0, 10.0)], MissionEnd::Hold).unwrap();
        assert_eq!(w.distance_to_go(Vec2::ZERO, 0), 11.0);
        assert_eq!(
            w.distance_to_go(Vec2::ZERO, 1),
            libm::sqrtf(3.0 * 3.0 + 100.0)
        );
        assert_eq!(w.distance_to_go(Vec2::ZERO, 2), 0.0);
    }

    #[test]
    fn a_survey_mows_the_rectangle_back_and_forth() {
        // 60 m along +y, 25 m to its left (−x), lines at most 10 m apart: 4 lines 8.33 m apart.
        let s = Survey {
            corner: Vec2::new(10.0, 0.0),
            length_m: 60.0,
            width_m: 25.0,
            heading: 0.5 * PI,
            spacing_m: 10.0,
            radius_m: 2.0,
            speed: Some(0.8),
        };
        assert_eq!(s.lines(), Ok(4));
        let w = Waypoints::survey(&s, MissionEnd::Hold).unwrap();
        let pts: std::vec::Vec<Vec2> = w.as_slice().iter().map(|w| w.position()).collect();
        let want = [
            (10.0, 0.0),
            (10.0, 60.0),
            (1.667, 60.0),
            (1.667, 0.0),
            (-6.667, 0.0),
            (-6.667, 60.0),
            (-15.0, 60.0),
            (-15.0, 0.0),
        ];
        assert_eq!(pts.len(), want.len());
        for (p, (x, y)) in pts.iter().zip(want) {
            assert!((p.x - x).abs() < 1e-2 && (p.y - y).abs() < 1e-3, "{p:?}");
        }
        assert!(w.as_slice().iter().all(|w| w.speed() == Some(0.8)));
        // A width that is a whole number of spacings flies exactly that spacing.
        assert_eq!(Survey { width_m: 20.0, ..s }.lines(), Ok(3));
        // Eight lines fit, nine do not: the error names the limit.
        assert_eq!(Survey { width_m: 70.0, ..s }.lines(), Ok(8));
        assert!(Waypoints::survey(&Survey { width_m: 70.0, ..s }, MissionEnd::Hold).is_ok());
        assert_eq!(
            Waypoints::survey(&Survey { width_m: 71.0, ..s }, MissionEnd::Hold),
            Err(MissionError::TooMany {
                needed: 18,
                limit: 16
            })
        );
        assert!(matches!(
            Waypoints::survey(
                &Survey {
                    spacing_m: 1e-30,
                    ..s
                },
                MissionEnd::Hold
            ),
            Err(MissionError::TooMany { limit: 16, .. })
        ));
        for bad in [
            Survey {
                spacing_m: 0.0,
                ..s
            },
            Survey { width_m: -1.0, ..s },
            Survey {
                length_m: f32::NAN,
                ..s
            },
            Survey {
                heading: 100.0,
                ..s
            },
        ] {
            assert_eq!(
                Waypoints::survey(&bad, MissionEnd::Hold),
                Err(MissionError::SurveyArea)
            );
        }
        // A bad per-waypoint setting names the first waypoint.
        assert_eq!(
            Waypoints::survey(&Survey { radius_m: 0.0, ..s }, MissionEnd::Hold),
            Err(MissionError::Waypoint {
                index: 0,
                error: WaypointError::Radius
            })
        );
    }
}
