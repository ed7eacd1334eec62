//! Twin-thruster 3-DOF vehicles (the VideoRay Pro III, the flat-fish AUV): the hull's
//! parameters, its PI-D surge and heading autopilots, and the model that integrates them.

use super::{
    bounded, finite_or_zero, rest_state, sanitize, valid_dt, wrap_pi, Autopilot, ModelKind,
    VehicleModel, DYNAMIC_SUBSTEP_S, MAX_COMMAND_SPEED,
};
use crate::types::{SetPoints, VehicleState, P2};

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
/// quadratic damping, and PI-D surge-speed and heading autopilots. [`VideoRay`](super::VideoRay) and
/// [`FlatFish`](crate::sim::flatfish::FlatFish) are this model with their own [`HullParams`] and
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
