//! Vehicle models: the kinematic vehicle of seed 000, and two 3-DOF twin-thruster vehicles with
//! their low-level surge-speed and heading autopilots ([`TwinThruster`]): a VideoRay Pro III
//! ([`VideoRay`]) and the 4.5 m flat-fish AUV of seed 003 ([`FlatFish`](super::flatfish::FlatFish),
//! in [`super::flatfish`]).
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

// ---------------------------------------------------------------------------------------------
// Kinematic vehicle

/// The kinematic vehicle of seed 000 (Barisic, Vukic, Miskovic 2007), eq. 8: it follows the
/// planner's commanded velocity vector `sp.velocity` exactly, and its position is the bilinear
/// (trapezoidal) integral `p(k+1) = p(k) + T/2·(v(k) + v(k−1))`, plus the current's drift
/// `T·c`. (The extracted eq. 8 reads `p(k−1)` on the right; with it the vehicle would cover
/// only `T·v` in two periods, half the commanded speed, so we read it as the trapezoidal rule
/// the text names.)
///
/// The heading is the direction of the commanded (water-relative) velocity, held when that
/// velocity is below 1 mm/s; `u` is its magnitude, `v = 0`, and `r` the heading change over the
/// step. `velocity` is `v(k)` plus the current. `thrust` is the surge force a VideoRay Pro III
/// hull needs to hold that speed through the water, `|X_u·s + X_u|u|·s|s||` with the
/// coefficients of [`VIDEORAY_PRO3`] — so the energy proxy of a kinematic run is comparable
/// with a dynamic one.
#[derive(Clone, Debug)]
pub struct Kinematic {
    state: VehicleState,
    /// v(k−1): the previous commanded velocity (water-relative), m/s.
    v_prev: P2,
}

impl Kinematic {
    /// At rest at `start`, heading `heading`.
    pub fn new(start: P2, heading: f64) -> Self {
        Kinematic {
            state: rest_state(start, heading),
            v_prev: P2::default(),
        }
    }
}

impl VehicleModel for Kinematic {
    fn kind(&self) -> ModelKind {
        ModelKind::Kinematic
    }

    fn state(&self) -> VehicleState {
        self.state
    }

    fn step(&mut self, dt: f64, sp: &SetPoints, current: P2) -> VehicleState {
        let Some(dt) = valid_dt(dt) else {
            return self.state;
        };
        let v = bounded(sanitize(sp.velocity), MAX_COMMAND_SPEED);
        let c = bounded(sanitize(current), MAX_COMMAND_SPEED);
        let s = &mut self.state;
        s.position = s
            .position
            .add(v.add(self.v_prev).scale(0.5 * dt))
            .add(c.scale(dt));
        let speed = v.norm();
        let old = s.heading;
        if speed > 1e-3 {
            s.heading = v.y.atan2(v.x);
        }
        s.r = wrap_pi(s.heading - old) / dt;
        s.u = speed;
        s.v = 0.0;
        s.velocity = v.add(c);
        let p = &VIDEORAY_PRO3;
        s.thrust = (p.x_u * speed + p.x_uu * speed * speed).abs();
        self.v_prev = v;
        self.state
    }
}

// ---------------------------------------------------------------------------------------------
// Twin-thruster 3-DOF vehicles: the VideoRay Pro III and the flat-fish AUV

/// Physical parameters of a 3-DOF (surge u, sway v, yaw r) vehicle driven by two horizontal
/// thrusters in differential ([`TwinThruster`]).
///
/// Hydrodynamic coefficients follow Fossen's notation and the signs of the source (added-mass
/// terms as positive magnitudes, damping as negative derivatives).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HullParams {
    /// Dry mass m, kg.
    pub mass: f64,
    /// Rigid-body yaw inertia I_z, kg·m².
    pub iz: f64,
    /// Surge added mass X_u̇ (magnitude), kg.
    pub x_udot: f64,
    /// Sway added mass Y_v̇ (magnitude), kg.
    pub y_vdot: f64,
    /// Yaw added inertia N_ṙ (magnitude), kg·m².
    pub n_rdot: f64,
    /// Linear surge damping X_u, N·s/m (negative).
    pub x_u: f64,
    /// Linear sway damping Y_v, N·s/m (negative).
    pub y_v: f64,
    /// Linear yaw damping N_r, N·m·s (negative).
    pub n_r: f64,
    /// Quadratic surge damping X_u|u|, N·s²/m² (negative).
    pub x_uu: f64,
    /// Quadratic sway damping Y_v|v|, N·s²/m² (negative).
    pub y_vv: f64,
    /// Quadratic yaw damping N_r|r|, N·m·s² (negative).
    pub n_rr: f64,
    /// Largest thrust of one horizontal thruster, either direction, N.
    pub thrust_max: f64,
    /// Lateral distance of each horizontal thruster from the centre line, m.
    pub arm: f64,
    /// Fraction of the thrusters' largest yaw moment, 2·arm·thrust_max, that the heading
    /// autopilot may command, `(0, 1]`. 1 lets a turn take all the thrust (the vehicle slows
    /// down in hard turns); below 1 keeps `2·thrust_max·(1 − yaw_share)` of surge force for the
    /// speed loop whatever the heading error (a "rudder limit").
    pub yaw_share: f64,
}

/// The former name of [`HullParams`], from when the VideoRay was the only dynamic model.
pub type VideoRayParams = HullParams;

/// The VideoRay Pro III.
///
/// - **Hydrodynamics** — X_u̇ = 1.94, Y_v̇ = 6.05, N_ṙ = 0.0118; X_u = −0.95, Y_v = −5.87,
///   N_r = −0.023; X_u|u| = −6.04, Y_v|v| = −30.73, N_r|r| = −0.45: W. Wang, *Autonomous
///   Control of a Differential Thrust Micro ROV*, MASc thesis, University of Waterloo, 2006,
///   p. 19 (identified on a VideoRay Pro III), as used by the public VideoRay simulators (e.g.
///   K. DeMarco's `videoray_pro_3_params.m`, Georgia Tech, 2013). Those simulators use the
///   inertia terms as the whole diagonal of M; we read them, with the naming, as added mass and
///   add the rigid-body terms below (m₁₁ = 5.54 kg, m₂₂ = 9.65 kg), which is the conservative
///   (slower) reading.
/// - **m = 3.6 kg**: the Pro III's weight in air, "8 pounds" in VideoRay's material.
/// - **I_z = 0.066 kg·m²**: assumption — a uniform 3.6 kg box of the Pro III's footprint
///   (≈ 0.37 m × 0.29 m), m(L² + W²)/12. The real mass is concentrated nearer the centre
///   (camera, thrusters are light), so this errs towards a slower yaw; the heading loop has
///   margin either way since m₃₃ is tiny next to the yaw drag.
/// - **thrust_max = 5.3 N per thruster**: assumption, chosen so that both horizontal thrusters
///   at full power balance Wang's surge drag at 1.25 m/s (0.95·1.25 + 6.04·1.25² ≈ 10.6 N), the
///   ≈ 2.4 kn top speed quoted for the Pro III class.
/// - **arm = 0.10 m**: assumption — the two horizontal thrusters sit about 0.2 m apart at the
///   rear corners of the ≈ 0.29 m wide frame. The largest yaw moment is then 2·5.3·0.1 ≈
///   1.06 N·m, a top turn rate of ≈ 1.5 rad/s (≈ 85 °/s) against N_r|r|.
/// - **yaw_share = 1**: an ROV turns on the spot; the heading loop may use all the thrust.
pub const VIDEORAY_PRO3: HullParams = HullParams {
    mass: 3.6,
    iz: 0.066,
    x_udot: 1.94,
    y_vdot: 6.05,
    n_rdot: 0.0118,
    x_u: -0.95,
    y_v: -5.87,
    n_r: -0.023,
    x_uu: -6.04,
    y_vv: -30.73,
    n_rr: -0.45,
    thrust_max: 5.3,
    arm: 0.10,
    yaw_share: 1.0,
};

/// Gains of one PI-D loop: `out = kp·e + ki·∫e dt − kd·ẏ`, the derivative on the measurement
/// `y` (no kick on set-point steps).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PidGains {
    /// Proportional gain.
    pub kp: f64,
    /// Integral gain.
    pub ki: f64,
    /// Derivative gain (on the measurement's rate).
    pub kd: f64,
}

/// Gains of the two autopilots.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AutopilotGains {
    /// Surge speed: e in m/s, out in N; the measurement's rate is the surge acceleration.
    pub surge: PidGains,
    /// Heading: e in rad, out in N·m; the measurement's rate is the yaw rate r (a gyro).
    pub heading: PidGains,
}

/// Autopilot gains for [`VIDEORAY_PRO3`], tuned on this model (see the tests in this file for
/// the measured step responses). Surge: with m₁₁ = 5.54 kg and a drag slope of ≈ 13 N·s/m at
/// 1 m/s, kp = 40 puts the closed-loop pole near 9.5 rad/s; ki = 30 removes the drag offset over
/// ≈ 1.5 s without overshoot (the integrator only winds while the thrust is unsaturated).
/// Heading: with m₃₃ = 0.078 kg·m², kp = 5 and kd = 1 give ω ≈ 8 rad/s, ζ ≈ 0.8 in the linear
/// range; turns larger than ≈ 12° saturate the yaw moment, and the derivative term starts
/// braking when kp·e falls below kd·r, early enough to stop the turn with < 1° overshoot. The
/// model has no steady yaw disturbance, so ki is kept small (a larger one trades a faster
/// trim of the last tenths of a degree for several degrees of overshoot: ki = 4 gave 4.4°).
pub const VIDEORAY_PRO3_GAINS: AutopilotGains = AutopilotGains {
    surge: PidGains {
        kp: 40.0,
        ki: 30.0,
        kd: 0.0,
    },
    heading: PidGains {
        kp: 5.0,
        ki: 0.3,
        kd: 1.0,
    },
};

/// One PI-D loop with clamping anti-windup.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Pid {
    integral: f64,
}

impl Pid {
    /// The output for error `e` and measurement rate `y_dot`, saturated to `±limit`; integrates
    /// `e·h` only when that does not push further into saturation (conditional integration),
    /// and keeps `|ki·∫e|` within `limit_max` (the largest limit ever used).
    fn update(
        &mut self,
        g: &PidGains,
        e: f64,
        y_dot: f64,
        h: f64,
        limit: f64,
        limit_max: f64,
    ) -> f64 {
        let raw = g.kp * e + g.ki * self.integral - g.kd * y_dot;
        let out = raw.clamp(-limit, limit);
        let pushing_out = (raw > limit && e > 0.0) || (raw < -limit && e < 0.0);
        if !pushing_out && g.ki > 0.0 {
            let bound = limit_max / g.ki;
            self.integral = (self.integral + e * h).clamp(-bound, bound);
        }
        if out.is_finite() {
            out
        } else {
            self.integral = 0.0;
            0.0
        }
    }
}

/// A vehicle in the horizontal plane driven by two horizontal thrusters in differential: a
/// Fossen-style 3-DOF model with diagonal inertia (rigid body + added mass), linear and
/// quadratic damping, and PI-D surge-speed and heading autopilots. [`VideoRay`] and
/// [`FlatFish`](super::flatfish::FlatFish) are this model with their own [`HullParams`] and
/// [`AutopilotGains`].
///
/// With ν = (u, v, r) the velocity relative to the water, m₁₁ = m + X_u̇, m₂₂ = m + Y_v̇,
/// m₃₃ = I_z + N_ṙ:
///
/// ```text
/// m₁₁ u̇ = X + m₂₂ v r + X_u u + X_u|u| u|u|
/// m₂₂ v̇ = −m₁₁ u r    + Y_v v + Y_v|v| v|v|
/// m₃₃ ṙ = N           + N_r r + N_r|r| r|r|
/// ṗ = R(ψ) (u, v) + c,   ψ̇ = r
/// ```
///
/// The surge–sway terms are Fossen's rigid-body and added-mass Coriolis–centripetal forces
/// (they make the vehicle skid outward in a turn); the yaw equation is decoupled, as in Wang's
/// identified VideoRay model — the Munk moment (m₁₁ − m₂₂)uv of slender-body theory and the
/// sway–yaw cross derivatives N_v, Y_r are left out (each model's docs say why for its hull).
/// The hydrodynamics act on the water-relative velocity: for a current that is constant in the
/// Earth frame (irrotational), the equations in ν_r hold exactly (Fossen, *Handbook of Marine
/// Craft Hydrodynamics and Motion Control*, 2011, Property 10.1), and the ground velocity is
/// `R(ψ)ν_r + c`. So `u`, `v` in [`VehicleState`] are water-relative, as its docs say.
///
/// **Thrusters.** Starboard and port thrust `T_s`, `T_p`, each within ±`thrust_max`, give
/// `X = T_s + T_p` and `N = arm·(T_s − T_p)`. Yaw has priority: the heading autopilot's N is
/// limited to ±`yaw_share`·2·arm·thrust_max, and the surge force to what the thrusters have
/// left, ±(2·thrust_max − |N|/arm). Thruster dynamics and the weaker reverse thrust of real
/// propellers are neglected (assumption: they are fast next to the vehicles' surge time
/// constants, ≈ 0.4 s for the VideoRay and several seconds for the flat-fish).
///
/// **Autopilots** run every integration substep (≤ [`DYNAMIC_SUBSTEP_S`], i.e. ≥ 100 Hz): a
/// PI-D surge loop tracking `sp.speed` with the water-relative surge u, and a PI-D heading loop
/// tracking `sp.psi` with the error wrapped to (−π, π] and the gyro rate r as derivative. Both
/// use conditional-integration anti-windup. Between autopilot updates the thrust is held, and
/// the dynamics are integrated with classical RK4.
///
/// **Set-point mode** ([`Autopilot::SetPoints`]), seed 001 §2: the planner's decomposition
/// {(a_c, v_c, I_surge), (α_c, ω_c, φ_c)} feeds the channels of the same two loops:
///
/// ```text
/// X = m₁₁·a_c + kp·(v_c − u) + ki·I_surge + kd·(a_c − u̇)
/// N = m₃₃·α_c + kp·wrap(φ_c − ψ) + ki·∫wrap(φ_c − ψ) + kd·(ω_c − r)
/// ```
///
/// The accelerations are fed forward through the inertias (what the planner's double
/// integrator asks of the hull), the derivative channels compare commanded with measured
/// rates instead of braking every rate, and the surge integral channel is the planner's own:
/// I_surge, how far the vehicle lags the ideal double-integrator position along its travel,
/// replaces the loop's integral of the speed error (whose time integral it is). The gains are
/// the plain mode's.
///
/// **`thrust`** in the state is `|T_s| + |T_p|` averaged over the step, N: the total effort of
/// the two thrusters (for the energy proxy ∫|thrust| dt). In pure surge it equals |X|; in a
/// pure turn, |N|/arm.
#[derive(Clone, Debug)]
pub struct TwinThruster {
    kind: ModelKind,
    params: HullParams,
    gains: AutopilotGains,
    /// `[x, y, ψ, u, v, r]`: position, heading (wrapped every substep), water-relative velocity.
    x: [f64; 6],
    surge: Pid,
    heading: Pid,
    prev_u: f64,
    state: VehicleState,
    autopilot: Autopilot,
}

impl TwinThruster {
    /// A vehicle reporting itself as `kind`, with these parameters and gains, at rest at
    /// `start`. Masses, inertias, thrust and arm below 1e-6 are raised to 1e-6, damping
    /// coefficients are used with a negative sign whatever sign is given, and `yaw_share` is
    /// clamped to `[1e-6, 1]` (non-finite: 1), so the model stays well posed.
    pub fn new(
        kind: ModelKind,
        params: HullParams,
        gains: AutopilotGains,
        start: P2,
        heading: f64,
    ) -> Self {
        let pos = |x: f64| {
            if x.is_finite() {
                x.abs().max(1e-6)
            } else {
                1e-6
            }
        };
        let neg = |x: f64| -finite_or_zero(x).abs();
        let p = HullParams {
            mass: pos(params.mass),
            iz: pos(params.iz),
            x_udot: finite_or_zero(params.x_udot).abs(),
            y_vdot: finite_or_zero(params.y_vdot).abs(),
            n_rdot: finite_or_zero(params.n_rdot).abs(),
            x_u: neg(params.x_u),
            y_v: neg(params.y_v),
            n_r: neg(params.n_r),
            x_uu: neg(params.x_uu),
            y_vv: neg(params.y_vv),
            n_rr: neg(params.n_rr),
            thrust_max: pos(params.thrust_max),
            arm: pos(params.arm),
            yaw_share: if params.yaw_share.is_finite() {
                params.yaw_share.clamp(1e-6, 1.0)
            } else {
                1.0
            },
        };
        let g = |k: PidGains| PidGains {
            kp: finite_or_zero(k.kp),
            ki: finite_or_zero(k.ki),
            kd: finite_or_zero(k.kd),
        };
        let state = rest_state(start, heading);
        TwinThruster {
            kind,
            params: p,
            gains: AutopilotGains {
                surge: g(gains.surge),
                heading: g(gains.heading),
            },
            x: [
                state.position.x,
                state.position.y,
                state.heading,
                0.0,
                0.0,
                0.0,
            ],
            surge: Pid::default(),
            heading: Pid::default(),
            prev_u: 0.0,
            state,
            autopilot: Autopilot::Plain,
        }
    }

    /// Selects what the autopilots track (from the next step).
    pub fn set_autopilot(&mut self, autopilot: Autopilot) {
        self.autopilot = autopilot;
    }

    /// Its parameters (as sanitised by [`TwinThruster::new`]).
    pub fn params(&self) -> &HullParams {
        &self.params
    }

    /// Its autopilot gains.
    pub fn gains(&self) -> &AutopilotGains {
        &self.gains
    }

    /// Thruster allocation with yaw priority: the applied `(X, N)` and `|T_s| + |T_p|`.
    fn allocate(&self, x_cmd: f64, n_cmd: f64) -> (f64, f64, f64) {
        let p = &self.params;
        let n_max = 2.0 * p.arm * p.thrust_max;
        let n = n_cmd.clamp(-n_max, n_max);
        let x_max = (2.0 * p.thrust_max - n.abs() / p.arm).max(0.0);
        let x = x_cmd.clamp(-x_max, x_max);
        let ts = 0.5 * (x + n / p.arm);
        let tp = 0.5 * (x - n / p.arm);
        (x, n, ts.abs() + tp.abs())
    }

    /// Time derivative of `[x, y, ψ, u, v, r]` under thrust `(X, N)` and current `c`.
    fn deriv(&self, s: &[f64; 6], x_f: f64, n_f: f64, c: P2) -> [f64; 6] {
        let p = &self.params;
        let (psi, u, v, r) = (s[2], s[3], s[4], s[5]);
        let m11 = p.mass + p.x_udot;
        let m22 = p.mass + p.y_vdot;
        let m33 = p.iz + p.n_rdot;
        let (sn, cs) = psi.sin_cos();
        [
            u * cs - v * sn + c.x,
            u * sn + v * cs + c.y,
            r,
            (x_f + m22 * v * r + p.x_u * u + p.x_uu * u * u.abs()) / m11,
            (-m11 * u * r + p.y_v * v + p.y_vv * v * v.abs()) / m22,
            (n_f + p.n_r * r + p.n_rr * r * r.abs()) / m33,
        ]
    }

    /// One RK4 step of length `h` with the thrust held.
    fn rk4(&mut self, h: f64, x_f: f64, n_f: f64, c: P2) {
        let add = |a: &[f64; 6], k: &[f64; 6], f: f64| {
            let mut o = *a;
            o.iter_mut().zip(k).for_each(|(o, k)| *o += f * k);
            o
        };
        let s = self.x;
        let k1 = self.deriv(&s, x_f, n_f, c);
        let k2 = self.deriv(&add(&s, &k1, 0.5 * h), x_f, n_f, c);
        let k3 = self.deriv(&add(&s, &k2, 0.5 * h), x_f, n_f, c);
        let k4 = self.deriv(&add(&s, &k3, h), x_f, n_f, c);
        for i in 0..6 {
            self.x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
}

impl VehicleModel for TwinThruster {
    fn kind(&self) -> ModelKind {
        self.kind
    }

    fn state(&self) -> VehicleState {
        self.state
    }

    fn step(&mut self, dt: f64, sp: &SetPoints, current: P2) -> VehicleState {
        let Some(dt) = valid_dt(dt) else {
            return self.state;
        };
        let c = bounded(sanitize(current), MAX_COMMAND_SPEED);
        let speed_ref = finite_or_zero(sp.speed).clamp(-MAX_COMMAND_SPEED, MAX_COMMAND_SPEED);
        let feeds = Feeds::new(self.autopilot, sp);
        // The epsilon keeps 0.1 / 0.01 at 10 substeps despite rounding.
        let n = (dt / DYNAMIC_SUBSTEP_S - 1e-9).ceil().max(1.0);
        let h = dt / n;
        let p = self.params;
        let n_lim = p.yaw_share * (2.0 * p.arm * p.thrust_max);
        let x_lim = 2.0 * p.thrust_max;
        let mut effort = 0.0;
        for _ in 0..(n as u64) {
            let (psi, u, r) = (self.x[2], self.x[3], self.x[5]);
            let u_dot = (u - self.prev_u) / h;
            self.prev_u = u;
            let (n_cmd, x_cmd) = match feeds {
                None => {
                    // Heading first: yaw has the thrusters' priority, surge gets what is left.
                    let e_psi = if sp.psi.is_finite() {
                        wrap_pi(sp.psi - psi)
                    } else {
                        0.0
                    };
                    let n_cmd = self
                        .heading
                        .update(&self.gains.heading, e_psi, r, h, n_lim, n_lim);
                    let x_avail = (x_lim - n_cmd.abs() / p.arm).max(0.0);
                    let x_cmd = self.surge.update(
                        &self.gains.surge,
                        speed_ref - u,
                        u_dot,
                        h,
                        x_avail,
                        x_lim,
                    );
                    (n_cmd, x_cmd)
                }
                Some(f) => self.pid_setpoints(&f, psi, u, r, u_dot, h, n_lim, x_lim),
            };
            let (x_f, n_f, e) = self.allocate(x_cmd, n_cmd);
            effort += e;
            self.rk4(h, x_f, n_f, c);
            if !self.x.iter().all(|v| v.is_finite()) {
                // Cannot happen with sane parameters; never hand NaN to the runner.
                self.x = [
                    self.state.position.x,
                    self.state.position.y,
                    self.state.heading,
                    0.0,
                    0.0,
                    0.0,
                ];
            }
            self.x[2] = wrap_pi(self.x[2]);
        }
        let [x, y, psi, u, v, r] = self.x;
        let (sn, cs) = psi.sin_cos();
        self.state = VehicleState {
            position: P2::new(x, y),
            heading: psi,
            u,
            v,
            r,
            velocity: P2::new(u * cs - v * sn + c.x, u * sn + v * cs + c.y),
            thrust: effort / n,
        };
        self.state
    }
}

/// The PI-D set-points of one step, sanitised (non-finite counts as zero, a non-finite φ_c as
/// the plain heading set-point), or `None` in plain mode.
#[derive(Clone, Copy, Debug)]
struct Feeds {
    a_c: f64,
    v_c: f64,
    i_surge: f64,
    alpha_c: f64,
    omega_c: f64,
    phi_c: f64,
}

impl Feeds {
    fn new(mode: Autopilot, sp: &SetPoints) -> Option<Feeds> {
        if mode != Autopilot::SetPoints {
            return None;
        }
        let f = &sp.pid;
        let speed = |x: f64| finite_or_zero(x).clamp(-MAX_COMMAND_SPEED, MAX_COMMAND_SPEED);
        Some(Feeds {
            a_c: finite_or_zero(f.a_c),
            v_c: speed(f.v_c),
            i_surge: finite_or_zero(f.i_surge),
            alpha_c: finite_or_zero(f.alpha_c),
            omega_c: finite_or_zero(f.omega_c),
            phi_c: if f.phi_c.is_finite() { f.phi_c } else { sp.psi },
        })
    }
}

impl TwinThruster {
    /// Set-point mode (see the type's docs): the yaw moment and the surge force, yaw first.
    #[allow(clippy::too_many_arguments)]
    fn pid_setpoints(
        &mut self,
        f: &Feeds,
        psi: f64,
        u: f64,
        r: f64,
        u_dot: f64,
        h: f64,
        n_lim: f64,
        x_lim: f64,
    ) -> (f64, f64) {
        let p = self.params;
        let g = self.gains;
        let m11 = p.mass + p.x_udot;
        let m33 = p.iz + p.n_rdot;
        let e_psi = if f.phi_c.is_finite() {
            wrap_pi(f.phi_c - psi)
        } else {
            0.0
        };
        // The loop's own integral of the heading error, its derivative channel on ω_c − r
        // (the `y_dot` argument is the measured minus the commanded rate), α_c fed forward.
        let pid = self
            .heading
            .update(&g.heading, e_psi, r - f.omega_c, h, n_lim, n_lim);
        let n_cmd = (pid + m33 * f.alpha_c).clamp(-n_lim, n_lim);
        let x_avail = (x_lim - n_cmd.abs() / p.arm).max(0.0);
        // The integral channel within the plain loop's anti-windup bound (|ki·∫e| ≤ X_max).
        let integral = if g.surge.ki > 0.0 {
            (g.surge.ki * f.i_surge).clamp(-x_lim, x_lim)
        } else {
            0.0
        };
        let raw = m11 * f.a_c + g.surge.kp * (f.v_c - u) + integral + g.surge.kd * (f.a_c - u_dot);
        let x_cmd = if raw.is_finite() {
            raw.clamp(-x_avail, x_avail)
        } else {
            0.0
        };
        (n_cmd, x_cmd)
    }
}

/// The VideoRay Pro III in the horizontal plane: a [`TwinThruster`] with [`VIDEORAY_PRO3`] and
/// [`VIDEORAY_PRO3_GAINS`]. Its yaw equation is decoupled as in Wang's identified model: the
/// Munk moment is left out because Wang's yaw identification has no such term and it is poorly
/// predicted for a bluff box hull.
#[derive(Clone, Debug)]
pub struct VideoRay(TwinThruster);

impl VideoRay {
    /// The Pro III ([`VIDEORAY_PRO3`], [`VIDEORAY_PRO3_GAINS`]) at rest at `start`.
    pub fn new(start: P2, heading: f64) -> Self {
        VideoRay::with_params(VIDEORAY_PRO3, VIDEORAY_PRO3_GAINS, start, heading)
    }

    /// A vehicle with other parameters or gains (experiments; the defaults are the Pro III),
    /// sanitised as [`TwinThruster::new`] says.
    pub fn with_params(params: HullParams, gains: AutopilotGains, start: P2, heading: f64) -> Self {
        VideoRay(TwinThruster::new(
            ModelKind::VideoRay,
            params,
            gains,
            start,
            heading,
        ))
    }

    /// Its parameters.
    pub fn params(&self) -> &HullParams {
        self.0.params()
    }

    /// Selects what its autopilots track ([`TwinThruster::set_autopilot`]).
    pub fn set_autopilot(&mut self, autopilot: Autopilot) {
        self.0.set_autopilot(autopilot);
    }
}

impl VehicleModel for VideoRay {
    fn kind(&self) -> ModelKind {
        self.0.kind()
    }

    fn state(&self) -> VehicleState {
        self.0.state()
    }

    fn step(&mut self, dt: f64, sp: &SetPoints, current: P2) -> VehicleState {
        self.0.step(dt, sp, current)
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
