//! Shape fit and confidence from a cluster's running moments.
//!
//! A cluster keeps, about its first point p₀ (so `f32` keeps centimetres far from the origin):
//! the hit count n, Σd, Σd dᵀ and Σd·|d|² (d = p − p₀), the sum of unit look directions
//! (sensor → hit), Σrange, Σstep, Σ(mean echo intensity) and its last point. From these:
//!
//! - mean m and covariance C = Σd dᵀ/n − (Σd/n)(Σd/n)ᵀ, principal spreads σ₁ ≥ σ₂ and the major
//!   axis angle φ = ½·atan2(2C₁₂, C₁₁ − C₂₂);
//! - the beam spacing on the target, h = mean range × mean step;
//! - **circle, algebraic** (n ≥ 4): the Kåsa least-squares circle, which needs only these
//!   moments: with centred coordinates (u, v) it solves `C·c = ½·(E[u(u²+v²)], E[v(u²+v²)])ᵀ`
//!   and R² = |c|² + tr C. The sonar sees roughly the near half of a circle, a wide enough arc
//!   for this to be within a few centimetres on clean data. It is used when C is well
//!   conditioned, the centre lies behind the mean as seen from the sensor, and R is within
//!   0.6–1.6 × the spread radius below (else noise or a straight wall has driven it);
//! - **rectangle** (otherwise, if n ≥ 5 and σ₁ > `elongation`·σ₂): x along the major axis. Its
//!   extent along the axis is the span of the first and last hits (the two angular ends of the
//!   visible face) widened by h/2 at each end — which, unlike the spread, is not biased by the
//!   denser beams on the near part of an oblique wall — or `√3·σ₁`, whichever is larger. Its
//!   half-thickness is `√3·σ₂` or `wall_half_thickness_m`, whichever is larger, and the centre
//!   is pushed that far behind the seen face, away from the sensor;
//! - **circle, from the spread** (otherwise, e.g. 1–3 hits): the beams sample the near face
//!   about evenly in the lateral coordinate; a uniform spread of width W has W² = 12σ₁² for a
//!   continuum, and n evenly spaced samples of spacing h add h² (`W = n·h`,
//!   σ² = h²(n² − 1)/12), so the diameter is `W = √(12σ₁² + h²)` and R = W/2. The points lie on
//!   the near face only: for a circle seen from afar with evenly spaced lateral samples their
//!   mean lies `π/4·R` in front of the centre (E[√(R² − y²)] over y uniform in ±R), so the
//!   centre is `m + (π/4)·R·û`, û the mean look direction;
//! - **confidence** = c_hits · fill · c_int, with c_hits = 1 − e^(−(n−1)/4) (one hit is no
//!   evidence of extent; 3 hits ≈ 0.39, 4 ≈ 0.53, 6 ≈ 0.71, 10 ≈ 0.89: a chain of three
//!   consistent runs is what speckle occasionally makes, four rarely), fill = hits / beams spanned (fading and speckle leave holes),
//!   c_int = mean compensated intensity / (2·threshold), clamped to 1 (runs are at least at the
//!   threshold, so c_int ≥ ½).
//!
//! Sizes are clamped to `min_radius_m ..= MAX_FEATURE_EXTENT_M`; a fit with any non-finite
//! number is refused (`None`), so a [`Feature`] is always finite.

use crate::math::{atan2, exp, sqrt, Vec2, PI};

use super::{ExtractorConfig, Feature, FeatureKind, MAX_FEATURE_EXTENT_M};

/// Fewest hits fitted as a rectangle: three or four points of a circle's near face often look
/// elongated, and a short wall is covered well enough by its spread circle.
const MIN_RECTANGLE_HITS: u32 = 5;

/// One run placed in the world frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Hit {
    /// Leading-edge point, world frame, m.
    pub point: Vec2,
    /// Unit direction sensor → point.
    pub look: Vec2,
    /// Leading-edge range, m.
    pub range: f32,
    /// Head step magnitude of the ping, rad.
    pub step: f32,
    /// Mean compensated intensity of the run.
    pub intensity: f32,
}

/// Running sums of a cluster's hits (constant size, any number of hits).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Moments {
    origin: Vec2,
    n: u32,
    sx: f32,
    sy: f32,
    sxx: f32,
    sxy: f32,
    syy: f32,
    /// Σ dx·|d|² and Σ dy·|d|², for the algebraic circle.
    sxz: f32,
    syz: f32,
    look: Vec2,
    range: f32,
    step: f32,
    intensity: f32,
    /// Last hit, relative to `origin` (the first hit is the origin itself).
    last: Vec2,
}

impl Moments {
    /// The moments of one hit.
    pub fn new(h: &Hit) -> Self {
        Moments {
            origin: h.point,
            n: 1,
            sx: 0.0,
            sy: 0.0,
            sxx: 0.0,
            sxy: 0.0,
            syy: 0.0,
            sxz: 0.0,
            syz: 0.0,
            look: h.look,
            range: h.range,
            step: h.step,
            intensity: h.intensity,
            last: Vec2::ZERO,
        }
    }

    /// Adds a hit.
    pub fn add(&mut self, h: &Hit) {
        let d = h.point - self.origin;
        self.n = self.n.saturating_add(1);
        self.sx += d.x;
        self.sy += d.y;
        self.sxx += d.x * d.x;
        self.sxy += d.x * d.y;
        self.syy += d.y * d.y;
        let z = d.norm2();
        self.sxz += d.x * z;
        self.syz += d.y * z;
        self.look += h.look;
        self.range += h.range;
        self.step += h.step;
        self.intensity += h.intensity;
        self.last = d;
    }

    /// Hits summed.
    pub fn hits(&self) -> u32 {
        self.n
    }

    /// Mean echo intensity of the hits (after the range gain).
    pub fn mean_intensity(&self) -> f32 {
        self.intensity / self.n.max(1) as f32
    }

    /// The fitted feature, `None` if any number came out non-finite. `spanned` is the number of
    /// beams from the first to the last hit (≥ hits when beams were missed).
    pub fn fit(&self, spanned: u32, time_ms: u64, cfg: &ExtractorConfig) -> Option<Feature> {
        let n = self.n.max(1) as f32;
        let inv_n = 1.0 / n;
        let mean_rel = Vec2::new(self.sx * inv_n, self.sy * inv_n);
        let mean = self.origin + mean_rel;
        let a = crate::math::max_num(self.sxx * inv_n - mean_rel.x * mean_rel.x, 0.0);
        let b = self.sxy * inv_n - mean_rel.x * mean_rel.y;
        let c = crate::math::max_num(self.syy * inv_n - mean_rel.y * mean_rel.y, 0.0);
        let half_trace = 0.5 * (a + c);
        let disc = sqrt(0.25 * (a - c) * (a - c) + b * b);
        let sigma1 = sqrt(crate::math::max_num(half_trace + disc, 0.0));
        let sigma2 = sqrt(crate::math::max_num(half_trace - disc, 0.0));
        let phi = 0.5 * atan2(2.0 * b, a - c);
        // Unit vectors never cancel within a half turn of head travel; the fallback is for safety.
        let look = self.look.normalized(1e-6).unwrap_or(Vec2::new(1.0, 0.0));
        let spacing = (self.range * inv_n) * (self.step * inv_n);

        // Radius from the spread (see the module docs), and the algebraic circle if it agrees.
        let spread_r = 0.5 * sqrt(12.0 * sigma1 * sigma1 + spacing * spacing);
        let kasa = if self.n >= 4 {
            let m2 = mean_rel.norm2();
            let tu = self.sxz * inv_n
                - 3.0 * mean_rel.x * a
                - 2.0 * mean_rel.y * b
                - mean_rel.x * c
                - mean_rel.x * m2;
            let tv = self.syz * inv_n
                - 3.0 * mean_rel.y * c
                - 2.0 * mean_rel.x * b
                - mean_rel.y * a
                - mean_rel.y * m2;
            let det = a * c - b * b;
            let conditioned = det > 1e-6 * (a + c) * (a + c) && det > 1e-12;
            conditioned
                .then(|| {
                    let k = 0.5 / det;
                    let off = Vec2::new(k * (c * tu - b * tv), k * (a * tv - b * tu));
                    (off, sqrt(off.norm2() + a + c))
                })
                .filter(|&(off, r)| {
                    off.dot(look) > 0.0 && r >= 0.6 * spread_r && r <= 1.6 * spread_r
                })
        } else {
            None
        };
        let elongated =
            self.n >= MIN_RECTANGLE_HITS && sigma1 > 1e-4 && sigma1 > cfg.elongation * sigma2;

        let (center, radius, kind) = if let Some((off, r)) = kasa {
            let radius = clamp_extent(r, cfg.min_radius_m);
            (mean + off, radius, FeatureKind::Circle { radius })
        } else if elongated {
            let axis = Vec2::from_angle(phi);
            let mut normal = axis.perp();
            if normal.dot(look) < 0.0 {
                normal = -normal;
            }
            let p_first = (-mean_rel).dot(axis);
            let p_last = (self.last - mean_rel).dot(axis);
            let lo = p_first.min(p_last) - 0.5 * spacing;
            let hi = p_first.max(p_last) + 0.5 * spacing;
            let half_x = (0.5 * (hi - lo)).max(sqrt(3.0) * sigma1);
            let half = Vec2::new(
                clamp_extent(half_x, cfg.min_radius_m),
                clamp_extent(sqrt(3.0) * sigma2, cfg.wall_half_thickness_m),
            );
            let center = mean + axis * (0.5 * (hi + lo)) + normal * half.y;
            (
                center,
                half.norm(),
                FeatureKind::Rectangle { half, angle: phi },
            )
        } else {
            let radius = clamp_extent(spread_r, cfg.min_radius_m);
            let center = mean + look * (0.25 * PI * radius);
            (center, radius, FeatureKind::Circle { radius })
        };

        let fill = n / (spanned.max(self.n) as f32);
        let c_hits = 1.0 - exp(-(n - 1.0) / 4.0);
        let c_int = (self.intensity * inv_n / (2.0 * cfg.threshold.max(1.0))).clamp(0.0, 1.0);
        let confidence = (c_hits * fill * c_int).clamp(0.0, 1.0);

        let finite = center.is_finite()
            && radius.is_finite()
            && confidence.is_finite()
            && match kind {
                FeatureKind::Circle { radius } => radius.is_finite(),
                FeatureKind::Rectangle { half, angle } => half.is_finite() && angle.is_finite(),
            };
        finite.then_some(Feature {
            center,
            radius,
            kind,
            confidence,
            time_ms,
            beams: u16::try_from(self.n).unwrap_or(u16::MAX),
            runs_on: false,
            faint: false,
        })
    }
}

/// `v` clamped to `lo ..= MAX_FEATURE_EXTENT_M` (NaN gives `lo`).
fn clamp_extent(v: f32, lo: f32) -> f32 {
    if v >= lo {
        v.min(MAX_FEATURE_EXTENT_M)
    } else {
        lo
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{cos, sin};

    fn cfg() -> ExtractorConfig {
        ExtractorConfig::default()
    }

    /// Near-face hits of a circle from a fixed sensor, one per beam `step` apart (beam centres
    /// at `(k + phase)·step` off the line of sight), ranges quantised to bin centres of `bin_m`
    /// (0 for exact ranges).
    fn circle_moments(
        sensor: Vec2,
        center: Vec2,
        r: f32,
        step: f32,
        phase: f32,
        bin_m: f32,
    ) -> Moments {
        let to_c = center - sensor;
        let d = to_c.norm();
        let half = libm::asinf(r / d);
        let mut m: Option<Moments> = None;
        for k in -400i32..=400 {
            let off = (k as f32 + phase) * step;
            if off.abs() >= half {
                continue;
            }
            let u = Vec2::from_angle(to_c.angle() + off);
            // Ray–circle: t = u·c − √((u·c)² − |c|² + r²).
            let uc = u.dot(to_c);
            let mut t = uc - sqrt(uc * uc - d * d + r * r);
            if bin_m > 0.0 {
                t = (libm::floorf(t / bin_m) + 0.5) * bin_m;
            }
            let h = Hit {
                point: sensor + u * t,
                look: u,
                range: t,
                step,
                intensity: 200.0,
            };
            match m.as_mut() {
                Some(m) => m.add(&h),
                None => m = Some(Moments::new(&h)),
            }
        }
        m.unwrap()
    }

    /// Centre and radius errors of the fit, m.
    fn circle_errors(m: &Moments, center: Vec2, r: f32) -> (f32, f32) {
        let f = m.fit(m.hits(), 5, &cfg()).unwrap();
        assert_eq!(f.time_ms, 5);
        let FeatureKind::Circle { radius } = f.kind else {
            panic!("not a circle: {f:?}")
        };
        ((f.center - center).norm(), (radius - r).abs())
    }

    #[test]
    fn circle_fit_is_exact_on_clean_arcs_even_far_from_the_origin() {
        // A large offset checks the moments about the first point keep their precision.
        for (off, d, r, step) in [
            (Vec2::ZERO, 12.0, 1.5, 0.0314),
            (Vec2::new(40_000.0, -30_000.0), 12.0, 1.5, 0.0314),
            (Vec2::ZERO, 20.0, 0.8, 0.0157),
            (Vec2::ZERO, 8.0, 2.0, 0.0628),
            (Vec2::ZERO, 5.0, 1.5, 0.0314),
        ] {
            let sensor = off + Vec2::new(1.0, 2.0);
            let center = sensor + Vec2::from_angle(0.7) * d;
            let m = circle_moments(sensor, center, r, step, 0.5, 0.0);
            let (ce, re) = circle_errors(&m, center, r);
            assert!(ce < 0.03 && re < 0.03, "errors {ce} {re} for r {r} at {d}");
        }
    }

    #[test]
    fn circle_fit_with_quantised_ranges_is_within_two_bins() {
        // 0.1 m bins, four beam phases: worst centre and radius errors (measured: 0.16, 0.14).
        let mut worst = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for (d, r, step) in [
            (12.0, 1.5, 0.0314),
            (16.6, 1.5, 0.0314),
            (20.0, 0.8, 0.0157),
            (8.0, 2.0, 0.0628),
            (12.0, 2.0, 0.03),
            (5.0, 1.5, 0.0314),
        ] {
            for phase in [0.0, 0.25, 0.5, 0.75] {
                let center = Vec2::from_angle(-2.0) * d;
                let m = circle_moments(Vec2::ZERO, center, r, step, phase, 0.1);
                let (ce, re) = circle_errors(&m, center, r);
                if ce.max(re) > worst.0.max(worst.1) {
                    worst = (ce, re, d, phase);
                }
            }
        }
        assert!(worst.0 < 0.2 && worst.1 < 0.2, "worst errors {worst:?}");
    }

    #[test]
    fn three_hits_use_the_spread_circle() {
        // R = 0.5 m at 25 m with 0.9° steps: three beams; the spread fit is within 0.25 m.
        for phase in [0.0, 0.25, 0.75] {
            let center = Vec2::new(25.0, 0.0);
            let m = circle_moments(Vec2::ZERO, center, 0.5, 0.0157, phase, 0.1);
            assert_eq!(m.hits(), 3);
            let (ce, re) = circle_errors(&m, center, 0.5);
            assert!(ce < 0.25 && re < 0.15, "errors {ce} {re}");
        }
    }

    #[test]
    fn a_line_of_hits_fits_a_rectangle_behind_its_face() {
        // Wall y = 8 seen from the origin, beams every 0.03 rad between 60° and 120°.
        let mut m: Option<Moments> = None;
        let mut beams = 0;
        for k in 0..=34 {
            let th = 1.05 + 0.03 * k as f32;
            let u = Vec2::new(cos(th), sin(th));
            let t = 8.0 / u.y;
            let h = Hit {
                point: u * t,
                look: u,
                range: t,
                step: 0.03,
                intensity: 150.0,
            };
            beams += 1;
            match m.as_mut() {
                Some(m) => m.add(&h),
                None => m = Some(Moments::new(&h)),
            }
        }
        let m = m.unwrap();
        let f = m.fit(beams, 0, &cfg()).unwrap();
        let FeatureKind::Rectangle { half, angle } = f.kind else {
            panic!("not a rectangle: {f:?}")
        };
        assert!(
            angle.abs() < 0.01 || (angle.abs() - PI).abs() < 0.01,
            "{angle}"
        );
        // x ends of the hits: 8/tan(1.05) = 4.59 and 8/tan(2.07) = −4.36, each widened by half
        // a beam spacing (mean range 8.6 m × 0.03 / 2 = 0.13 m).
        let (x_lo, x_hi) = (f.center.x - half.x, f.center.x + half.x);
        assert!(
            (x_lo + 4.49).abs() < 0.05 && (x_hi - 4.72).abs() < 0.05,
            "{x_lo} {x_hi}"
        );
        assert!(
            (f.center.y - half.y - 8.0).abs() < 0.02,
            "face at {}",
            f.center.y - half.y
        );
        assert!((half.y - 0.25).abs() < 1e-6);
        let s = f.to_shape().unwrap();
        assert!(s.signed_distance(Vec2::new(0.0, 7.0)) > 0.95);
        assert!((f.radius - half.norm()).abs() < 1e-5);
    }

    #[test]
    fn confidence_grows_with_hits_fill_and_intensity() {
        let h = |x: f32, i: f32| Hit {
            point: Vec2::new(x, 10.0),
            look: Vec2::new(0.0, 1.0),
            range: 10.0,
            step: 0.03,
            intensity: i,
        };
        let build = |n: usize, i: f32| {
            let mut m = Moments::new(&h(0.0, i));
            for k in 1..n {
                m.add(&h(0.1 * k as f32, i));
            }
            m
        };
        let c = cfg();
        let few = build(3, 180.0).fit(3, 0, &c).unwrap().confidence;
        let many = build(12, 180.0).fit(12, 0, &c).unwrap().confidence;
        let holes = build(12, 180.0).fit(24, 0, &c).unwrap().confidence;
        let weak = build(12, 95.0).fit(12, 0, &c).unwrap().confidence;
        assert!(
            few < many && holes < many && weak < many,
            "{few} {many} {holes} {weak}"
        );
        assert!((many - (1.0 - libm::expf(-11.0 / 4.0))).abs() < 1e-5);
        assert!((holes - 0.5 * many).abs() < 1e-5);
    }

    #[test]
    fn single_hit_is_a_small_finite_circle() {
        let m = Moments::new(&Hit {
            point: Vec2::new(3.0, 4.0),
            look: Vec2::new(0.6, 0.8),
            range: 5.0,
            step: 0.01,
            intensity: 100.0,
        });
        let f = m.fit(1, 0, &cfg()).unwrap();
        // Diameter = beam spacing 5 × 0.01 = 0.05 m → clamped to min_radius.
        assert_eq!(f.kind, FeatureKind::Circle { radius: 0.1 });
        assert!(f.to_shape().is_ok());
        assert!((f.center - Vec2::new(3.0, 4.0)).norm() < 0.1);
    }
}
