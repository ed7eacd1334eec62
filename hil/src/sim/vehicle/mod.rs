//! Vehicle models: the kinematic vehicle of seed 000, and two 3-DOF twin-thruster vehicles with
//! their low-level surge-speed and heading autopilots ([`TwinThruster`]): a VideoRay Pro III
//! ([`VideoRay`]) and the 4.5 m flat-fish AUV of seed 003 ([`FlatFish`](super::flatfish::FlatFish),
//! in [`super::flatfish`]).
//!
//! - `kinematic.rs`: the kinematic vehicle; `twin_thruster.rs`: the 3-DOF hull and its PI-D
//!   autopilots; `videoray.rs`: the VideoRay Pro III's parameters and gains.
//!
//! All advance with [`VehicleModel::step`]`(dt, set-points, current)` and report the true
//! [`VehicleState`] in the Earth-fixed frame (x, y; heading ψ counter-clockwise from +x, wrapped
//! to (−π, π]; body frame x forward, y to port). The ocean current is an Earth-frame velocity,
//! held constant over one step.
//!
//! **Input rules (no panics).** A step with `dt` that is not a positive finite number changes
//! nothing and returns the current state; `dt` above [`MAX_STEP_S`] is clamped to it (one call
//! then simulates less time than asked — a scenario's period is far below it). Non-finite
//! set-points or current components count as zero, except a non-finite heading set-point, which
//! holds the present heading. Speeds and commanded velocities are clamped to
//! [`MAX_COMMAND_SPEED`] (the firmware refuses navigation faster than 20 m/s anyway).

use crate::types::{SetPoints, VehicleState, P2};
use std::f64::consts::{PI, TAU};
use std::fmt;

mod kinematic;
mod twin_thruster;
mod videoray;

pub use kinematic::Kinematic;
pub use twin_thruster::{AutopilotGains, HullParams, PidGains, TwinThruster, VideoRayParams};
pub use videoray::{VideoRay, VIDEORAY_PRO3, VIDEORAY_PRO3_GAINS};

/// Longest step one [`VehicleModel::step`] call simulates, s.
pub const MAX_STEP_S: f64 = 3600.0;
/// Largest commanded speed (or velocity magnitude) accepted, m/s; larger ones are clamped.
pub const MAX_COMMAND_SPEED: f64 = 20.0;
/// Largest internal integration (and autopilot) step of the dynamic ([`TwinThruster`]) models, s.
pub const DYNAMIC_SUBSTEP_S: f64 = 0.01;

/// `a` wrapped to (−π, π]; a non-finite angle gives 0.
pub fn wrap_pi(a: f64) -> f64 {
    if !a.is_finite() {
        return 0.0;
    }
    let w = a.rem_euclid(TAU);
    if w > PI {
        w - TAU
    } else {
        w
    }
}

fn finite_or_zero(x: f64) -> f64 {
    if x.is_finite() {
        x
    } else {
        0.0
    }
}

fn sanitize(p: P2) -> P2 {
    P2::new(finite_or_zero(p.x), finite_or_zero(p.y))
}

/// `v` with its length clamped to `max`.
fn bounded(v: P2, max: f64) -> P2 {
    let n = v.norm();
    if n > max {
        v.scale(max / n)
    } else {
        v
    }
}

/// A positive finite `dt` clamped to [`MAX_STEP_S`], or `None`.
fn valid_dt(dt: f64) -> Option<f64> {
    (dt.is_finite() && dt > 0.0).then(|| dt.min(MAX_STEP_S))
}

/// Which vehicle model a scenario asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ModelKind {
    /// The kinematic vehicle of seed 000 eq. 8: it moves with the planner's commanded velocity.
    Kinematic,
    /// The VideoRay Pro III 3-DOF dynamic model with surge and heading autopilots.
    VideoRay,
    /// The 4.5 m flat-fish AUV of seed 003 §2, 3-DOF, with surge and heading autopilots.
    #[serde(alias = "flat-fish", alias = "flat_fish")]
    FlatFish,
}

impl ModelKind {
    /// The scenario spelling: `"kinematic"`, `"videoray"` or `"flatfish"`.
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Kinematic => "kinematic",
            ModelKind::VideoRay => "videoray",
            ModelKind::FlatFish => "flatfish",
        }
    }
}

impl fmt::Display for ModelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A model name that is none of `kinematic`, `videoray`, `flatfish`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown vehicle model `{0}` (expected `kinematic`, `videoray` or `flatfish`)")]
pub struct UnknownModel(pub String);

impl std::str::FromStr for ModelKind {
    type Err = UnknownModel;
    /// Case-insensitive; `video_ray`, `video-ray`, `videoray_pro3`, `flat-fish` and `flat_fish`
    /// are accepted too.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "kinematic" => Ok(ModelKind::Kinematic),
            "videoray" | "video_ray" | "video-ray" | "videoray_pro3" => Ok(ModelKind::VideoRay),
            "flatfish" | "flat-fish" | "flat_fish" => Ok(ModelKind::FlatFish),
            _ => Err(UnknownModel(s.to_string())),
        }
    }
}

/// A simulated vehicle: its true state, advanced by the firmware's set-points.
pub trait VehicleModel: Send + fmt::Debug {
    /// Which model this is.
    fn kind(&self) -> ModelKind;
    /// The true state now.
    fn state(&self) -> VehicleState;
    /// Advances `dt` seconds tracking `sp` in the Earth-frame current `current` (m/s), and
    /// returns the new state. See the module docs for how odd inputs are treated.
    fn step(&mut self, dt: f64, sp: &SetPoints, current: P2) -> VehicleState;
}

/// A model of `kind` at `start` with heading `heading` (rad), at rest, its autopilots in mode
/// `autopilot` (the kinematic model has none and ignores it). Non-finite coordinates or
/// heading count as zero.
pub fn new_model(
    kind: ModelKind,
    start: P2,
    heading: f64,
    autopilot: Autopilot,
) -> Box<dyn VehicleModel> {
    match kind {
        ModelKind::Kinematic => Box::new(Kinematic::new(start, heading)),
        ModelKind::VideoRay => {
            let mut v = VideoRay::new(start, heading);
            v.set_autopilot(autopilot);
            Box::new(v)
        }
        ModelKind::FlatFish => {
            let mut v = super::flatfish::FlatFish::new(start, heading);
            v.set_autopilot(autopilot);
            Box::new(v)
        }
    }
}

/// What the autopilots of a [`TwinThruster`] track.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Autopilot {
    /// The heading set-point ψ_set and the speed set-point v_set (000 eq. 6–7) with their own
    /// PI-D loops (the default).
    #[default]
    Plain,
    /// Seed 001 §2's parallel PI-D set-points, as the paper intends them
    /// ([`TwinThruster`]'s docs): surge on v_c with the integral channel I_surge and the
    /// acceleration a_c fed forward; heading on φ_c with the turn rate ω_c as the derivative
    /// channel's set-point and α_c fed forward.
    SetPoints,
}

/// The state of a vehicle at rest.
fn rest_state(start: P2, heading: f64) -> VehicleState {
    VehicleState {
        position: sanitize(start),
        heading: wrap_pi(heading),
        ..VehicleState::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    fn sp(psi: f64, speed: f64) -> SetPoints {
        SetPoints {
            psi,
            speed,
            velocity: P2::new(speed * psi.cos(), speed * psi.sin()),
            ..SetPoints::default()
        }
    }

    /// 10–90 % rise time and overshoot (fraction of the step) of a response sampled every
    /// `dt`, for a step from `y0` to `y1`.
    fn step_metrics(ys: &[f64], dt: f64, y0: f64, y1: f64) -> (f64, f64) {
        let span = y1 - y0;
        let frac = |y: f64| (y - y0) / span;
        let t10 = ys.iter().position(|&y| frac(y) >= 0.1).unwrap() as f64 * dt;
        let t90 = ys.iter().position(|&y| frac(y) >= 0.9).unwrap() as f64 * dt;
        let peak = ys.iter().map(|&y| frac(y)).fold(f64::MIN, f64::max);
        (t90 - t10, (peak - 1.0).max(0.0))
    }

    #[test]
    fn wrap_pi_range() {
        assert_eq!(wrap_pi(PI), PI);
        assert!((wrap_pi(-PI) - PI).abs() < 1e-12);
        assert!((wrap_pi(3.0 * PI / 2.0) + FRAC_PI_2).abs() < 1e-12);
        assert!((wrap_pi(-7.0) - (-7.0 + TAU)).abs() < 1e-12);
        assert_eq!(wrap_pi(f64::NAN), 0.0);
    }

    #[test]
    fn model_kind_parses_and_prints() {
        assert_eq!("VideoRay".parse::<ModelKind>(), Ok(ModelKind::VideoRay));
        assert_eq!(" kinematic ".parse::<ModelKind>(), Ok(ModelKind::Kinematic));
        assert!("rov".parse::<ModelKind>().is_err());
        assert_eq!(ModelKind::VideoRay.to_string(), "videoray");
        assert_eq!(
            new_model(ModelKind::VideoRay, P2::default(), 0.0, Autopilot::Plain).kind(),
            ModelKind::VideoRay
        );
    }

    #[test]
    fn kinematic_integrates_bilinearly_with_current() {
        let mut k = new_model(
            ModelKind::Kinematic,
            P2::new(1.0, 2.0),
            0.3,
            Autopilot::Plain,
        );
        assert_eq!(k.state().heading, 0.3);
        let cmd = SetPoints {
            velocity: P2::new(0.0, 1.0),
            ..SetPoints::default()
        };
        // First step: v(k−1) = 0, so half the distance.
        let s = k.step(0.5, &cmd, P2::default());
        assert!((s.position.y - 2.25).abs() < 1e-12 && (s.position.x - 1.0).abs() < 1e-12);
        assert!((s.heading - FRAC_PI_2).abs() < 1e-12);
        assert_eq!(s.u, 1.0);
        let s = k.step(0.5, &cmd, P2::new(0.2, 0.0));
        assert!((s.position.y - 2.75).abs() < 1e-12);
        assert!((s.position.x - 1.1).abs() < 1e-12);
        assert_eq!(s.velocity, P2::new(0.2, 1.0));
        // Thrust: Pro III surge drag at 1 m/s.
        assert!((s.thrust - 6.99).abs() < 1e-9);
        // Stopping holds the heading.
        let s = k.step(0.5, &SetPoints::default(), P2::default());
        assert!((s.heading - FRAC_PI_2).abs() < 1e-12);
        assert!((s.position.y - 3.0).abs() < 1e-12);
        assert_eq!(s.thrust, 0.0);
    }

    #[test]
    fn bad_inputs_change_nothing_or_are_clamped() {
        for kind in [
            ModelKind::Kinematic,
            ModelKind::VideoRay,
            ModelKind::FlatFish,
        ] {
            let mut m = new_model(
                kind,
                P2::new(f64::NAN, 1.0),
                f64::INFINITY,
                Autopilot::SetPoints,
            );
            let s0 = m.state();
            assert_eq!(s0.position, P2::new(0.0, 1.0));
            assert_eq!(s0.heading, 0.0);
            for dt in [0.0, -1.0, f64::NAN, f64::INFINITY] {
                assert_eq!(m.step(dt, &sp(1.0, 1.0), P2::default()), s0);
            }
            let wild = SetPoints {
                psi: f64::NAN,
                speed: 1e30,
                velocity: P2::new(f64::INFINITY, 1e30),
                pid: crate::types::PidFeeds {
                    a_c: 1e30,
                    v_c: f64::NAN,
                    i_surge: f64::INFINITY,
                    alpha_c: -1e30,
                    omega_c: f64::NAN,
                    phi_c: f64::INFINITY,
                },
            };
            for _ in 0..50 {
                let s = m.step(0.1, &wild, P2::new(f64::NAN, 1e9));
                for v in [
                    s.position.x,
                    s.position.y,
                    s.heading,
                    s.u,
                    s.v,
                    s.r,
                    s.thrust,
                ] {
                    assert!(v.is_finite(), "{kind:?}: {s:?}");
                }
                assert!(s.velocity.norm() <= 2.0 * MAX_COMMAND_SPEED + 1e-9);
            }
        }
    }

    #[test]
    fn videoray_top_speed_is_about_1_25_m_s() {
        let mut m = VideoRay::new(P2::default(), 0.0);
        let mut s = m.state();
        for _ in 0..300 {
            s = m.step(0.1, &sp(0.0, 3.0), P2::default());
        }
        assert!((s.u - 1.248).abs() < 0.01, "top speed {}", s.u);
        assert!((s.thrust - 10.6).abs() < 1e-9, "full thrust {}", s.thrust);
        assert!(s.position.x > 30.0 && s.position.y.abs() < 1e-6);
    }

    #[test]
    fn videoray_surge_step_response() {
        let mut m = VideoRay::new(P2::default(), 0.0);
        let dt = 0.01;
        let us: Vec<f64> = (0..2000)
            .map(|_| m.step(dt, &sp(0.0, 1.0), P2::default()).u)
            .collect();
        let (rise, overshoot) = step_metrics(&us, dt, 0.0, 1.0);
        let last = *us.last().unwrap();
        eprintln!(
            "surge 0→1 m/s: rise {rise:.2} s, overshoot {:.1} %, final {last:.4}",
            overshoot * 100.0
        );
        assert!(rise < 1.5, "rise {rise}");
        assert!(overshoot < 0.05, "overshoot {overshoot}");
        assert!((last - 1.0).abs() < 0.01, "final {last}");
    }

    #[test]
    fn videoray_heading_step_response() {
        // A 90° turn while cruising at 0.5 m/s, and one from rest.
        for cruise in [0.5, 0.0] {
            let mut m = VideoRay::new(P2::default(), 0.0);
            for _ in 0..1000 {
                m.step(0.01, &sp(0.0, cruise), P2::default());
            }
            let dt = 0.01;
            let psis: Vec<f64> = (0..1000)
                .map(|_| m.step(dt, &sp(FRAC_PI_2, cruise), P2::default()).heading)
                .collect();
            let (rise, overshoot) = step_metrics(&psis, dt, 0.0, FRAC_PI_2);
            let last = *psis.last().unwrap();
            eprintln!(
                "heading 0→90° at {cruise} m/s: rise {rise:.2} s, overshoot {:.2}° , final err {:.3}°",
                overshoot * 90.0,
                (last - FRAC_PI_2).to_degrees()
            );
            assert!(rise < 1.5, "rise {rise}");
            assert!(overshoot * 90.0 < 5.0, "overshoot {}°", overshoot * 90.0);
            assert!((last - FRAC_PI_2).abs() < 0.01, "final {last}");
        }
    }

    #[test]
    fn videoray_turns_the_short_way_across_pi() {
        let mut m = VideoRay::new(P2::default(), 3.0);
        let mut min_abs = f64::MAX;
        for _ in 0..500 {
            let s = m.step(0.01, &sp(-3.0, 0.0), P2::default());
            // Going the short way (through ±π) it never passes near 0.
            min_abs = min_abs.min(s.heading.abs());
        }
        assert!(min_abs > 2.9, "{min_abs}");
        assert!((m.state().heading + 3.0).abs() < 0.01);
    }

    #[test]
    fn videoray_current_drifts_the_ground_track() {
        let mut still = VideoRay::new(P2::default(), 0.0);
        let mut drift = VideoRay::new(P2::default(), 0.0);
        let c = P2::new(0.0, 0.3);
        for _ in 0..100 {
            still.step(0.1, &sp(0.0, 1.0), P2::default());
            drift.step(0.1, &sp(0.0, 1.0), c);
        }
        let (a, b) = (still.state(), drift.state());
        // Same motion through the water; the current adds 0.3 m/s × 10 s sideways.
        assert!((a.u - b.u).abs() < 1e-9 && (a.position.x - b.position.x).abs() < 1e-9);
        assert!((b.position.y - a.position.y - 3.0).abs() < 1e-9);
        assert!((b.velocity.y - 0.3).abs() < 1e-9 && (b.velocity.x - 1.0).abs() < 0.01);
    }

    #[test]
    fn videoray_skids_outward_in_a_turn_and_is_deterministic() {
        let run = || {
            let mut m = VideoRay::new(P2::default(), 0.0);
            let mut side = 0.0f64;
            for k in 0..600 {
                let s = m.step(0.05, &sp(0.05 * k as f64 * 0.3, 1.0), P2::default());
                side = side.min(s.v);
            }
            (m.state(), side)
        };
        let (a, side) = run();
        let (b, _) = run();
        assert_eq!(a, b);
        // Turning left (r > 0), the sway is to starboard (v < 0): outward.
        assert!(side < -0.02, "{side}");
    }

    #[test]
    fn substeps_do_not_depend_on_the_call_period_much() {
        let mut a = VideoRay::new(P2::default(), 0.0);
        let mut b = VideoRay::new(P2::default(), 0.0);
        for _ in 0..100 {
            a.step(0.1, &sp(1.0, 1.0), P2::default());
        }
        for _ in 0..1000 {
            b.step(0.01, &sp(1.0, 1.0), P2::default());
        }
        let d = a.state().position.sub(b.state().position).norm();
        assert!(d < 1e-6, "{d}");
    }
}
