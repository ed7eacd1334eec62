//! Navigation sensors: what the firmware is told about the vehicle's own state.
//!
//! A [`NavSensor`] turns the true [`VehicleState`] into the firmware's
//! [`NavState`] — position, heading, velocity over ground — with white
//! Gaussian noise at a fixed update rate, holding the last fix between updates (a USBL or
//! DVL-aided navigation filter delivering at a few hertz). The noise comes from a seeded
//! generator, so the same seed and the same sequence of calls give the same fixes, and a sigma
//! of zero gives the truth exactly (to `f32`).

use super::rng::Rng;
use super::vehicle::wrap_pi;
use crate::types::{VehicleState, P2};
use vpf::planner::NavState;

/// Fastest velocity a fix reports, m/s (the firmware refuses navigation faster than this).
pub const MAX_NAV_SPEED: f64 = vpf::planner::MAX_NAV_SPEED as f64;

/// Noise and rate of a [`NavSensor`]. A negative or non-finite sigma counts as 0; a rate that
/// is not a positive finite number means "a new fix at every call". [`Default`] is perfect
/// navigation: no noise, a fix at every call.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NavConfig {
    /// Standard deviation of the position error per axis, m.
    pub position_sigma_m: f64,
    /// Standard deviation of the heading error, rad.
    pub heading_sigma_rad: f64,
    /// Standard deviation of the velocity error per axis, m/s.
    pub velocity_sigma: f64,
    /// Fixes per second.
    pub rate_hz: f64,
    /// Seed of the noise.
    pub seed: u64,
}

/// A sigma as used: finite and non-negative, else 0.
fn sigma(s: f64) -> f64 {
    if s.is_finite() && s > 0.0 {
        s
    } else {
        0.0
    }
}

/// The navigation sensor of one vehicle.
#[derive(Clone, Debug)]
pub struct NavSensor {
    cfg: NavConfig,
    /// Separate streams per quantity, so changing one sigma does not change the others' noise.
    pos_rng: Rng,
    head_rng: Rng,
    vel_rng: Rng,
    held: Option<NavState>,
    /// Time of the held fix, s.
    fix_time: f64,
    /// When the next fix is due, s.
    next_due: f64,
}

impl NavSensor {
    /// A sensor with `cfg` (see [`NavConfig`] for how odd values are read).
    pub fn new(cfg: NavConfig) -> Self {
        NavSensor {
            cfg: NavConfig {
                position_sigma_m: sigma(cfg.position_sigma_m),
                heading_sigma_rad: sigma(cfg.heading_sigma_rad),
                velocity_sigma: sigma(cfg.velocity_sigma),
                rate_hz: cfg.rate_hz,
                seed: cfg.seed,
            },
            pos_rng: Rng::stream(cfg.seed, 1),
            head_rng: Rng::stream(cfg.seed, 2),
            vel_rng: Rng::stream(cfg.seed, 3),
            held: None,
            fix_time: f64::NEG_INFINITY,
            next_due: f64::NEG_INFINITY,
        }
    }

    /// Perfect navigation: the truth at every call.
    pub fn perfect() -> Self {
        NavSensor::new(NavConfig::default())
    }

    /// The configuration in use (sigmas as used).
    pub fn config(&self) -> &NavConfig {
        &self.cfg
    }

    /// The update period, s, if the rate is a positive finite number.
    fn period(&self) -> Option<f64> {
        let r = self.cfg.rate_hz;
        (r.is_finite() && r > 0.0).then(|| 1.0 / r)
    }

    /// Time of the fix [`NavSensor::sample`] last returned, s (`None` before the first).
    pub fn fix_time(&self) -> Option<f64> {
        self.held.map(|_| self.fix_time)
    }

    /// The fix at time `t` s for the true state `truth`: a new noisy fix when one is due (fixes
    /// fall on the grid `t₀ + k/rate` from the first call's time `t₀`; missed slots are
    /// skipped, not replayed), else the held one. A non-finite `t` never triggers a new fix
    /// (except the very first), and time going backwards just holds.
    pub fn sample(&mut self, t: f64, truth: &VehicleState) -> NavState {
        let due = match self.held {
            None => true,
            Some(_) => t.is_finite() && t >= self.next_due,
        };
        if !due {
            if let Some(h) = self.held {
                return h;
            }
        }
        let fix = self.measure(truth);
        self.held = Some(fix);
        if t.is_finite() {
            self.fix_time = t;
            self.next_due = match self.period() {
                None => t,
                Some(p) if self.next_due.is_finite() => {
                    // Next grid point strictly after t.
                    let k = ((t - self.next_due) / p).floor() + 1.0;
                    self.next_due + k.max(1.0) * p
                }
                Some(p) => t + p,
            };
        }
        fix
    }

    /// One noisy measurement of `truth`.
    fn measure(&mut self, truth: &VehicleState) -> NavState {
        let c = self.cfg;
        let pos = P2::new(
            truth.position.x + c.position_sigma_m * self.pos_rng.gaussian(),
            truth.position.y + c.position_sigma_m * self.pos_rng.gaussian(),
        );
        let heading = wrap_pi(truth.heading + c.heading_sigma_rad * self.head_rng.gaussian());
        let mut vel = P2::new(
            truth.velocity.x + c.velocity_sigma * self.vel_rng.gaussian(),
            truth.velocity.y + c.velocity_sigma * self.vel_rng.gaussian(),
        );
        if !(vel.x.is_finite() && vel.y.is_finite()) {
            vel = P2::default();
        }
        let n = vel.norm();
        if n > MAX_NAV_SPEED {
            vel = vel.scale(MAX_NAV_SPEED / n);
        }
        NavState {
            position: pos.to_vpf(),
            heading: heading as f32,
            velocity: vel.to_vpf(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn truth(x: f64) -> VehicleState {
        VehicleState {
            position: P2::new(x, -2.0),
            heading: 1.0,
            velocity: P2::new(0.5, 0.25),
            ..VehicleState::default()
        }
    }

    #[test]
    fn zero_sigma_is_the_truth_at_every_call() {
        let mut n = NavSensor::perfect();
        for k in 0..10 {
            let s = truth(k as f64 * 0.1);
            let f = n.sample(k as f64 * 0.1, &s);
            assert_eq!(f.position, s.position.to_vpf());
            assert_eq!(f.heading, 1.0);
            assert_eq!(f.velocity, s.velocity.to_vpf());
        }
    }

    #[test]
    fn sample_and_hold_at_the_rate() {
        let mut n = NavSensor::new(NavConfig {
            rate_hz: 2.0,
            ..NavConfig::default()
        });
        // Called at 10 Hz for 2 s: fixes at 0, 0.5, 1.0, 1.5 s.
        let mut fixes = Vec::new();
        for k in 0..20 {
            let t = k as f64 * 0.1;
            let f = n.sample(t, &truth(t));
            fixes.push(f64::from(f.position.x));
        }
        let expect: Vec<f64> = (0..20).map(|k| (k / 5) as f64 * 0.5).collect();
        for (a, b) in fixes.iter().zip(&expect) {
            assert!((a - b).abs() < 1e-6, "{fixes:?}");
        }
        assert!((n.fix_time().unwrap() - 1.5).abs() < 1e-12);
        // A jump skips slots; time going back holds.
        let f = n.sample(10.2, &truth(10.2));
        assert!((f64::from(f.position.x) - 10.2).abs() < 1e-5);
        let g = n.sample(3.0, &truth(3.0));
        assert_eq!(f, g);
        let g = n.sample(f64::NAN, &truth(99.0));
        assert_eq!(f, g);
        // Next slot after 10.2 on the 0.5 s grid is 10.5.
        assert_eq!(n.sample(10.49, &truth(10.49)), f);
        assert!((f64::from(n.sample(10.5, &truth(10.5)).position.x) - 10.5).abs() < 1e-5);
    }

    #[test]
    fn noise_has_the_configured_spread_and_is_seeded() {
        let cfg = NavConfig {
            position_sigma_m: 0.5,
            heading_sigma_rad: 0.05,
            velocity_sigma: 0.1,
            rate_hz: 0.0,
            seed: 11,
        };
        let run = |cfg: NavConfig| {
            let mut n = NavSensor::new(cfg);
            (0..20_000)
                .map(|k| n.sample(k as f64, &truth(0.0)))
                .collect::<Vec<_>>()
        };
        let a = run(cfg);
        assert_eq!(a, run(cfg));
        assert_ne!(a, run(NavConfig { seed: 12, ..cfg }));
        let sd = |xs: Vec<f64>| {
            let m = xs.iter().sum::<f64>() / xs.len() as f64;
            let v = xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / xs.len() as f64;
            (m, v.sqrt())
        };
        let (mx, sx) = sd(a.iter().map(|f| f64::from(f.position.x)).collect());
        let (mh, sh) = sd(a.iter().map(|f| f64::from(f.heading)).collect());
        let (mv, sv) = sd(a.iter().map(|f| f64::from(f.velocity.y)).collect());
        assert!(mx.abs() < 0.02 && (sx - 0.5).abs() < 0.02, "{mx} {sx}");
        assert!(
            (mh - 1.0).abs() < 0.002 && (sh - 0.05).abs() < 0.002,
            "{mh} {sh}"
        );
        assert!(
            (mv - 0.25).abs() < 0.005 && (sv - 0.1).abs() < 0.004,
            "{mv} {sv}"
        );
    }

    #[test]
    fn odd_configs_and_states_do_not_panic() {
        let mut n = NavSensor::new(NavConfig {
            position_sigma_m: f64::NAN,
            heading_sigma_rad: -1.0,
            velocity_sigma: f64::INFINITY,
            rate_hz: f64::NAN,
            seed: 0,
        });
        let s = VehicleState {
            heading: 7.0,
            velocity: P2::new(100.0, 0.0),
            ..VehicleState::default()
        };
        let f = n.sample(0.0, &s);
        assert_eq!(f.position, vpf::Vec2::ZERO);
        assert!((f64::from(f.heading) - (7.0 - std::f64::consts::TAU)).abs() < 1e-6);
        assert!((f64::from(f.velocity.norm()) - MAX_NAV_SPEED).abs() < 1e-3);
        assert_eq!(f.validate(), Ok(()));
    }
}
