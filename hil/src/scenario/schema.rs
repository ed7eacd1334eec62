//! The validated scenario: the plain values a run is built from (what the reader gives).

use vpf::planner::Formation;
use vpf::Params;

use super::{Autopilot, ModelKind, VehicleMission};
use crate::types::{SimObstacle, P2};

/// A validated scenario: plain data, SI units, angles in radians.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    /// Name, for logs and plots.
    pub name: String,
    /// Simulated time, s. `dt_s ..= 86400`.
    pub duration_s: f64,
    /// The planner period and the simulation step, s. `0.02 ..= 1`. Equal to `params.period_s`.
    pub dt_s: f64,
    /// Seed of the simulation's noise and faults.
    pub seed: u64,
    /// Lock-step (as fast as possible, deterministic) or real time.
    pub mode: RunMode,
    /// The planner's parameters: `Params::default()` with the `[planner]` overrides and
    /// `period_s = dt_s`, validated. The strategy the firmware runs is `params.strategy`.
    pub params: Params,
    /// The vehicles, in file order (at least one, at most [`MAX_VEHICLES`](super::MAX_VEHICLES)).
    pub vehicles: Vec<Vehicle>,
    /// The obstacles (true geometry at t = 0), in file order.
    pub obstacles: Vec<SimObstacle>,
    /// The simulated sonar.
    pub sonar: Sonar,
    /// Navigation (position/heading) noise and rate.
    pub navigation: Navigation,
    /// Ocean current.
    pub current: Current,
    /// Injected link and sensor faults.
    pub faults: Faults,
}

/// How the runner paces the simulation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RunMode {
    /// Step as fast as the firmware answers; deterministic (the default).
    #[default]
    Lockstep,
    /// One step per `dt_s` of wall-clock time.
    Realtime,
}

/// How a vehicle's firmware learns about obstacles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Sensing {
    /// Raw sonar scanlines; the firmware extracts the obstacles itself.
    #[default]
    Sonar,
    /// Ready-made obstacle contacts (the truth within sonar range), as the seeds' charted
    /// obstacles.
    Contacts,
}

/// One vehicle.
#[derive(Clone, Debug, PartialEq)]
pub struct Vehicle {
    /// Unique name.
    pub name: String,
    /// Vehicle model.
    pub model: ModelKind,
    /// Start position, m.
    pub start: P2,
    /// Start heading, rad (counter-clockwise from +x).
    pub heading: f64,
    /// Goal-point, m: the last waypoint of a waypoint mission.
    pub goal: P2,
    /// A waypoint mission (`waypoints` or `survey`), if any; `None`: the single `goal`.
    pub mission: Option<VehicleMission>,
    /// Formation request, if any (orientation in rad).
    pub formation: Option<Formation>,
    /// How it senses obstacles.
    pub sensing: Sensing,
    /// What its autopilots track: the heading and speed set-points (the default), or seed
    /// 001's PI-D set-point decomposition.
    pub autopilot: Autopilot,
}

/// What the simulated sonar sends.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SonarMode {
    /// Raw scanlines of a mechanically scanned sonar (the default).
    #[default]
    Scanlines,
    /// Obstacle contacts.
    Contacts,
}

/// The simulated sonar.
///
/// **Default set-up: a transit among traffic** — 20 m range in 3.6° steps, a 360° sweep every
/// 3.2 s (100 pings of 2·20/1500 s + 5 ms), the Micron's low-resolution mode. Movers are met
/// by how often the head looks again, not by how far it sees: another VideoRay echoes only
/// within about 8 m, so at the high-resolution 30 m / 1.8° (a 9 s sweep) two closing at
/// 2 m/s saw each other once, if at all. On generated worlds (`hil bench`) it cut contacts by
/// about two thirds at about the same success; the numbers are in docs/bench-history.md ("The
/// sonar's set-up"). The 3° beam leaves 0.6° between pings, 0.2 m at 20 m. The shipped
/// scenarios name their own set-up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sonar {
    /// Default sensing of the vehicles.
    pub mode: SonarMode,
    /// Range, m. 0.5 ..= 200; default 20, or [`Sonar::FLATFISH_RANGE_M`] when every vehicle
    /// is a flat-fish ([`Sonar::range_carried_by`]).
    pub range_m: f64,
    /// Bins per scanline. 1 ..= 512; default 300.
    pub bins: u16,
    /// Head step, rad (default 3.6°).
    pub step: f64,
    /// Background noise level, 0 ..= 1; default 0.2 (a mean of 6 on the 0–255 scale).
    pub noise: f64,
    /// Speckle (one-bin spike) probability per bin, 0 ..= 1; default 0.002.
    pub speckle: f64,
    /// Rays across the 3° beam, 1 ..= 32; default 5 (1 is an ideal pencil beam).
    pub beam_rays: usize,
    /// Probability per ping of a spurious target echo (fish, a side lobe), 0 ..= 1; default
    /// 0.03.
    pub false_echoes: f64,
    /// With scanlines, the other vehicles also come as vehicle contacts (an acoustic
    /// positioning system, or a sonar that classifies them): seed 001's virtual leader takes the
    /// neighbours' positions as known. Default false: the vehicles see each other only through
    /// their sonars.
    pub vehicle_contacts: bool,
    /// How the scanlines reach the firmware: `Scanline` messages on the main link (default), or
    /// a simulated Ping360 on a port of its own that the firmware drives.
    pub interface: SonarInterface,
}

/// How a vehicle's sonar data reaches its firmware.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SonarInterface {
    /// `Scanline` messages on the main link (a sonar handled elsewhere).
    #[default]
    Link,
    /// A simulated Blue Robotics Ping360 on its own pty, answering the firmware's `transducer`
    /// commands with `device_data` (`crate::ping360::sim`): `bins` is its number of samples
    /// (200 ..= 512 here), `step_deg` a whole number of gradians (0.9° each, 1 ..= 12), the
    /// range sets the sample period.
    Ping360,
}

impl Sonar {
    /// The flat-fish's sonar range, m: farther than the 20 m default, which is less than its
    /// 22 m turning radius at cruise — at 20 m it commits to a turn before it can see the way
    /// round (`hil/recipes/README.md`, "A longer look"). A Ping360 reaches 50 m; at 40 m
    /// its sweep takes 5.8 s instead of 3.2 s.
    pub const FLATFISH_RANGE_M: f64 = 40.0;

    /// The range of the head `model` carries unless told another: [`Sonar::FLATFISH_RANGE_M`]
    /// for the flat-fish, the default's 20 m for the others.
    pub fn range_carried_by(model: ModelKind) -> f64 {
        match model {
            ModelKind::FlatFish => Sonar::FLATFISH_RANGE_M,
            ModelKind::VideoRay | ModelKind::Kinematic => Sonar::default().range_m,
        }
    }
}

impl Default for Sonar {
    fn default() -> Self {
        Sonar {
            mode: SonarMode::Scanlines,
            range_m: 20.0,
            bins: 300,
            step: 3.6f64.to_radians(),
            noise: 0.2,
            speckle: 0.002,
            beam_rays: 5,
            false_echoes: 0.03,
            vehicle_contacts: false,
            interface: SonarInterface::Link,
        }
    }
}

/// Navigation (the vehicle's own position and heading) as the firmware receives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Navigation {
    /// Standard deviation of the position noise, m. 0 ..= 100; default 0.
    pub position_sigma_m: f64,
    /// Standard deviation of the heading noise, rad (default 0).
    pub heading_sigma: f64,
    /// Navigation frame rate, Hz. 0.1 ..= 1000; defaults to `1 / dt_s` (10 here, the rate at
    /// the default period).
    pub rate_hz: f64,
}

impl Default for Navigation {
    fn default() -> Self {
        Navigation {
            position_sigma_m: 0.0,
            heading_sigma: 0.0,
            rate_hz: 10.0,
        }
    }
}

/// A uniform, constant ocean current.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Current {
    /// Velocity over ground, m/s. |v| ≤ 5.
    pub velocity: P2,
}

/// A time window `[from_s, to_s)` of the run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    /// Start, s.
    pub from_s: f64,
    /// End, s (> `from_s`).
    pub to_s: f64,
}

impl Window {
    /// Whether simulation time `t` (s) falls in the window.
    pub fn contains(&self, t: f64) -> bool {
        t >= self.from_s && t < self.to_s
    }
}

/// Injected faults. All default to none.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Faults {
    /// Probability that a bit on the serial link is flipped. 0 ..= 0.01.
    pub bit_error_rate: f64,
    /// Probability that a whole frame is dropped. 0 ..= 1.
    pub drop_rate: f64,
    /// Extra delay of navigation frames, ms. 0 ..= 10000.
    pub nav_delay_ms: f64,
    /// Navigation frames repeat the last value (frozen) in this window.
    pub nav_freeze: Option<Window>,
    /// No navigation frames at all in this window.
    pub nav_loss: Option<Window>,
    /// No sonar data in this window.
    pub sonar_dropout: Option<Window>,
    /// Bit-error rate on the simulated Ping360's port (harness → firmware), 0 ..= 0.01. The
    /// two rates above apply to the main link only.
    pub ping360_bit_error_rate: f64,
    /// Probability that a whole `device_data` frame to the firmware is dropped, 0 ..= 1.
    pub ping360_drop_rate: f64,
}
