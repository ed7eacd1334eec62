//! The ocean current: an Earth-frame water velocity, constant or slowly swinging.

use crate::types::P2;
use std::f64::consts::TAU;

/// A current `mean + swing·sin(2π t / period_s)`, m/s in the Earth frame: a steady drift plus
/// an optional slow oscillation (a tidal or eddy variation). The vehicle models hold it
/// constant over one step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Current {
    /// Mean velocity, m/s.
    pub mean: P2,
    /// Amplitude of the oscillation, m/s (zero for a steady current).
    pub swing: P2,
    /// Period of the oscillation, s; not a positive finite number means no oscillation.
    pub period_s: f64,
}

impl Current {
    /// A steady current.
    pub fn steady(mean: P2) -> Self {
        Current {
            mean,
            ..Current::default()
        }
    }

    /// The current at time `t` s. Non-finite components (and a non-finite `t`) count as zero.
    pub fn at(&self, t: f64) -> P2 {
        let fin = |x: f64| if x.is_finite() { x } else { 0.0 };
        let mean = P2::new(fin(self.mean.x), fin(self.mean.y));
        let p = self.period_s;
        if !(p.is_finite() && p > 0.0) {
            return mean;
        }
        let s = (TAU * fin(t) / p).sin();
        mean.add(P2::new(fin(self.swing.x), fin(self.swing.y)).scale(s))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steady_and_swinging() {
        let c = Current::steady(P2::new(0.2, -0.1));
        assert_eq!(c.at(0.0), P2::new(0.2, -0.1));
        assert_eq!(c.at(1e6), P2::new(0.2, -0.1));
        let s = Current {
            mean: P2::new(0.1, 0.0),
            swing: P2::new(0.0, 0.3),
            period_s: 100.0,
        };
        assert!((s.at(25.0).y - 0.3).abs() < 1e-12);
        assert!((s.at(75.0).y + 0.3).abs() < 1e-12);
        assert!(s.at(50.0).y.abs() < 1e-12 && s.at(50.0).x == 0.1);
        let bad = Current {
            mean: P2::new(f64::NAN, 1.0),
            swing: P2::new(1.0, 1.0),
            period_s: -3.0,
        };
        assert_eq!(bad.at(f64::NAN), P2::new(0.0, 1.0));
    }
}
