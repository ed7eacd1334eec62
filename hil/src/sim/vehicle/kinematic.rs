//! The kinematic vehicle of seed 000: it follows the commanded velocity exactly.

use super::{
    bounded, rest_state, sanitize, valid_dt, wrap_pi, ModelKind, VehicleModel, MAX_COMMAND_SPEED,
    VIDEORAY_PRO3,
};
use crate::types::{SetPoints, VehicleState, P2};

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
