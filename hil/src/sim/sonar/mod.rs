//! A mechanically scanned imaging sonar like the Tritech Micron (pre-extracted contacts, for
//! scenarios that bypass it, are [`super::contacts`]).
//!
//! **The head.** It pings along one bearing at a time, listens for `2R/c` seconds (the echo's
//! round trip to the full range `R`), spends `ping_overhead_s` stepping the motor and sending
//! the line, and steps by `step_deg`: continuously round (the default) or back and forth over a
//! sector. At the default 30 m range, 1.8° steps and 5 ms overhead, a ping takes 45 ms and a
//! full 360° sweep (200 pings) 9.0 s — the "seconds per sweep" the firmware's extractor is
//! built for. Each ping is a [`Ping`]: `bins` 8-bit intensities equally spaced over
//! `0 ..= range_m`, nearest first (bin `i` covers `[iΔ, (i+1)Δ)`), and the head angle relative
//! to the bow, counter-clockwise — exactly the firmware's [`Scanline`].
//!
//! **The echo** (a simple sonar equation, tuned to the firmware extractor's defaults):
//! - the beam is sampled by `rays_per_beam` rays. The default, one ray on the axis, is a
//!   pencil beam: what the firmware's extractor is designed and tested for. More rays are
//!   spread evenly across the −3 dB width `beam_width_deg` (the Micron's 3°), weighted by the
//!   two-way (transmit × receive) Gaussian pattern — 1 on the axis, ¼ at the −3 dB edges — and
//!   a bin takes the strongest ray's return (as on a log-compressed display, a partly filled
//!   beam still shows). That models the beam's smearing: an obstacle's near face widens by up to
//!   half a beam on each side and flattens. Measured with the firmware's default extractor over
//!   24 single-circle scenes (radius 0.5–2.5 m at 6–26 m, one sweep each): one ray, median
//!   centre error 0.19 m and every detected circle within 0.31 m; five rays, median 0.71 m and
//!   5 of 24 fitted as rectangles 1–2 m off;
//! - each ray stops at the first surface it meets (obstacles at their position at the ping's
//!   time, other vehicles as circles of their hull radius): what lies behind is in its acoustic
//!   shadow;
//! - the return's strength is `echo_strength · w · (¼ + ¾·cos θ) · f / (1 + range_loss_per_m·r)`,
//!   with `w` the beam weight, θ the angle between the ray and the surface normal (grazing
//!   walls return less), `f` a per-ray fading factor uniform in `1 ± echo_fluctuation`, and the
//!   last factor the spreading and absorption loss the head's time-varied gain leaves (the
//!   firmware compensates the same `1 + 0.04·r` by default);
//! - the return fills the bins from the surface to `echo_length_m` behind it, falling to half
//!   (pulse length and surface roughness), and the beam's bins take the strongest ray's value;
//! - every bin gets background reverberation, exponentially distributed (fully developed
//!   speckle) with mean `noise_level`, and with probability `speckle_prob` a one-bin spike of
//!   100 ..= 255 (fish, bubbles, interference);
//! - with probability `false_echo_prob` per ping, a spurious target echo at a random range;
//! - bins nearer than `blanking_m` are 0 (receiver blanked during transmission).
//!
//! Scenarios fly the demanding end of this (`[sonar]` defaults: five rays across the 3° beam,
//! noise 0.2, speckle 0.002, 3 % false echoes), and by default 20 m in 3.6° steps, a 3.2 s
//! sweep (`crate::scenario::Sonar` says why): the firmware's evidence map is built for a real
//! head, not for the pencil beam.
//!
//! All randomness comes from one seeded generator, so the same configuration, seed and calls
//! give the same pings.
//!
//! [`Scanline`]: vpf::sonar::Scanline

mod config;

pub use config::{Sector, SonarConfig, SonarConfigError};

use super::rng::Rng;
use super::vehicle::wrap_pi;
use crate::types::{SimObstacle, SimShape, VehicleState, P2};
use vpf::sonar::{Pose, Scanline};

/// Most pings one [`Sonar::poll`] returns. If more are due (the caller paused for minutes of
/// simulated time), the older ones are dropped and the head restarts its pattern.
pub const MAX_PINGS_PER_POLL: usize = 10_000;
/// Longest pose extrapolation back to a ping's time, s (see [`Sonar::poll`]).
pub const MAX_EXTRAPOLATION_S: f64 = 1.0;

/// One ping: the firmware's scanline, owned.
#[derive(Clone, Debug, PartialEq)]
pub struct Ping {
    /// Ping time, ms (the simulation clock).
    pub time_ms: u64,
    /// Head angle relative to the bow, counter-clockwise, rad, in (−π, π].
    pub bearing_rad: f32,
    /// Head step magnitude, rad.
    pub step_rad: f32,
    /// Range of the last bin's far edge, m.
    pub range_m: f32,
    /// Intensities, nearest first.
    pub bins: Vec<u8>,
    /// The true vehicle pose (the vehicle's reference point, not the head) the ping was
    /// rendered from. Not part of the scanline: the firmware uses its own navigation. For
    /// tests, plots and ground-truth checks.
    pub pose: Pose,
}

impl Ping {
    /// The firmware's view of this ping (borrows the bins).
    pub fn as_scanline(&self) -> Scanline<'_> {
        Scanline {
            time_ms: self.time_ms,
            bearing_rad: self.bearing_rad,
            step_rad: self.step_rad,
            range_m: self.range_m,
            bins: &self.bins,
        }
    }
}

/// What a ray met: range, and the cosine of the incidence angle.
#[derive(Clone, Copy, Debug)]
struct RayHit {
    range: f64,
    cos_inc: f64,
}

/// The simulated sonar head of one vehicle.
#[derive(Clone, Debug)]
pub struct Sonar {
    cfg: SonarConfig,
    rng: Rng,
    /// When the next ping is due, s (`None` until the first poll).
    next_ping: Option<f64>,
    /// Head angle relative to the bow, rad.
    bearing: f64,
    /// +1 counter-clockwise, −1 clockwise (sector scans reverse).
    dir: f64,
}

impl Sonar {
    /// A sonar with `cfg`, clamped into range (see [`SonarConfig::clamped`]).
    pub fn new(cfg: SonarConfig) -> Self {
        let cfg = cfg.clamped();
        let mut s = Sonar {
            cfg,
            rng: Rng::stream(cfg.seed, 0x50_4E_41_52),
            next_ping: None,
            bearing: 0.0,
            dir: 1.0,
        };
        s.restart_pattern();
        s
    }

    /// The configuration in use.
    pub fn config(&self) -> &SonarConfig {
        &self.cfg
    }

    /// The head at the start of its pattern.
    fn restart_pattern(&mut self) {
        (self.bearing, self.dir) = match self.cfg.sector {
            Sector::Continuous => (0.0, 1.0),
            Sector::Sweep {
                center_deg,
                width_deg,
            } => ((center_deg - 0.5 * width_deg).to_radians(), 1.0),
        };
    }

    /// Moves the head one step.
    fn advance_head(&mut self) {
        let step = self.cfg.step_deg.to_radians();
        match self.cfg.sector {
            Sector::Continuous => self.bearing = wrap_pi(self.bearing + step),
            Sector::Sweep {
                center_deg,
                width_deg,
            } => {
                let lo = (center_deg - 0.5 * width_deg).to_radians();
                let hi = (center_deg + 0.5 * width_deg).to_radians();
                let next = self.bearing + self.dir * step;
                // Half a step of tolerance, so rounding never adds a step beyond the end.
                if next > hi + 0.5 * step || next < lo - 0.5 * step {
                    self.dir = -self.dir;
                    self.bearing += self.dir * step;
                } else {
                    self.bearing = next;
                }
            }
        }
    }

    /// The pings due by time `t` s, oldest first (at most [`MAX_PINGS_PER_POLL`]).
    ///
    /// `vehicle` is the true state at `t`; a ping at an earlier time `tₚ` is rendered from the
    /// pose extrapolated back along the vehicle's velocity and yaw rate (at most
    /// [`MAX_EXTRAPOLATION_S`]), with the obstacles where they were at `tₚ` and the other
    /// vehicles (position and hull radius) where they are at `t`. The first poll pings at once;
    /// a non-finite `t` returns nothing. A ping's `time_ms` is `tₚ` in milliseconds (negative
    /// times count as 0).
    pub fn poll(
        &mut self,
        t: f64,
        vehicle: &VehicleState,
        obstacles: &[SimObstacle],
        others: &[(P2, f64)],
    ) -> Vec<Ping> {
        if !t.is_finite() {
            return Vec::new();
        }
        let period = self.cfg.ping_period_s();
        let mut next = *self.next_ping.get_or_insert(t);
        if next > t {
            return Vec::new();
        }
        // Pings due: floor((t − next)/period) + 1, saturating.
        let due = ((t - next) / period).floor() + 1.0;
        if due > MAX_PINGS_PER_POLL as f64 {
            next += (due - MAX_PINGS_PER_POLL as f64) * period;
            self.restart_pattern();
        }
        let mut out = Vec::new();
        while next <= t && out.len() < MAX_PINGS_PER_POLL {
            out.push(self.ping_at(next, t, vehicle, obstacles, others));
            self.advance_head();
            next += period;
        }
        self.next_ping = Some(next);
        out
    }

    /// Renders the ping at time `tp` from the state at `t`.
    fn ping_at(
        &mut self,
        tp: f64,
        t: f64,
        vehicle: &VehicleState,
        obstacles: &[SimObstacle],
        others: &[(P2, f64)],
    ) -> Ping {
        let (bearing, range_m, bins) = (self.bearing, self.cfg.range_m, self.cfg.bins);
        self.ping_along(tp, t, vehicle, bearing, range_m, bins, obstacles, others)
    }

    /// Renders one ping at time `tp` along the bow-relative bearing `bearing` (rad,
    /// counter-clockwise) with `bins` bins over `range_m`, from the state at `t` (extrapolated
    /// back to `tp` as [`Sonar::poll`] does): a head commanded from outside, as a Ping360's
    /// is. The head's own pattern does not move; the noise stream is the same one.
    #[allow(clippy::too_many_arguments)]
    pub fn ping_along(
        &mut self,
        tp: f64,
        t: f64,
        vehicle: &VehicleState,
        bearing: f64,
        range_m: f64,
        bins: usize,
        obstacles: &[SimObstacle],
        others: &[(P2, f64)],
    ) -> Ping {
        let back = (t - tp).clamp(0.0, MAX_EXTRAPOLATION_S);
        let fin = |x: f64| if x.is_finite() { x } else { 0.0 };
        let vel = P2::new(fin(vehicle.velocity.x), fin(vehicle.velocity.y));
        let pos = P2::new(fin(vehicle.position.x), fin(vehicle.position.y)).sub(vel.scale(back));
        let heading = wrap_pi(fin(vehicle.heading) - fin(vehicle.r) * back);
        let (sh, ch) = heading.sin_cos();
        let off = self.cfg.head_offset;
        let head = pos.add(P2::new(ch * off.x - sh * off.y, sh * off.x + ch * off.y));
        let bins = self.render(
            tp,
            head,
            heading + bearing,
            range_m,
            bins,
            obstacles,
            others,
        );
        Ping {
            time_ms: (tp.max(0.0) * 1000.0).round() as u64,
            bearing_rad: wrap_pi(bearing) as f32,
            step_rad: self.cfg.step_deg.to_radians() as f32,
            range_m: range_m as f32,
            bins,
            pose: Pose {
                position: pos.to_vpf(),
                heading: heading as f32,
            },
        }
    }

    /// The first surface along one ray, within `max` m.
    fn cast(
        &self,
        tp: f64,
        head: P2,
        dir: P2,
        max: f64,
        obstacles: &[SimObstacle],
        others: &[(P2, f64)],
    ) -> Option<RayHit> {
        let mut best: Option<(f64, P2)> = None;
        let mut consider = |r: Option<f64>, normal_at: &dyn Fn(P2) -> P2| {
            if let Some(r) = r.filter(|r| r.is_finite()) {
                if best.is_none_or(|(b, _)| r < b) {
                    best = Some((r, normal_at(head.add(dir.scale(r)))));
                }
            }
        };
        for o in obstacles {
            consider(o.ray_hit(tp, head, dir, max), &|p| o.outward_normal(tp, p));
        }
        for &(c, radius) in others {
            let shape = SimShape::Circle { center: c, radius };
            consider(shape.ray_hit(head, dir, max), &|p| shape.outward_normal(p));
        }
        best.map(|(range, n)| RayHit {
            range,
            cos_inc: -(n.x * dir.x + n.y * dir.y),
        })
    }

    /// The `n` bins over `range_m` of one ping whose beam axis points along `look` (world
    /// angle, rad).
    #[allow(clippy::too_many_arguments)]
    fn render(
        &mut self,
        tp: f64,
        head: P2,
        look: f64,
        range_m: f64,
        n: usize,
        obstacles: &[SimObstacle],
        others: &[(P2, f64)],
    ) -> Vec<u8> {
        let c = self.cfg;
        let n = n.max(1);
        let bin_m = range_m / n as f64;
        let mut level = vec![0.0f64; n];
        let half_bw = 0.5 * c.beam_width_deg.to_radians();
        for j in 0..c.rays_per_beam {
            // Evenly across the beam, edges included when there are several rays.
            let frac = if c.rays_per_beam == 1 {
                0.0
            } else {
                2.0 * j as f64 / (c.rays_per_beam - 1) as f64 - 1.0
            };
            let (s, co) = (look + frac * half_bw).sin_cos();
            let weight = 0.25f64.powf(frac * frac);
            let fade = 1.0 + c.echo_fluctuation * (2.0 * self.rng.uniform() - 1.0);
            let Some(hit) = self.cast(tp, head, P2::new(co, s), range_m, obstacles, others) else {
                continue;
            };
            if hit.range < c.blanking_m {
                // Inside the blanking zone: the receiver hears nothing, and the ray is blocked.
                continue;
            }
            let amp = c.echo_strength * weight * (0.25 + 0.75 * hit.cos_inc.clamp(0.0, 1.0)) * fade
                / (1.0 + c.range_loss_per_m * hit.range);
            let first = (hit.range / bin_m).floor() as usize;
            let len_bins = ((c.echo_length_m / bin_m).ceil() as usize).max(1);
            for k in 0..len_bins {
                let Some(l) = level.get_mut(first + k) else {
                    break;
                };
                let v = amp * (1.0 - 0.5 * k as f64 / len_bins as f64);
                *l = l.max(v);
            }
        }
        if c.false_echo_prob > 0.0 && self.rng.chance(c.false_echo_prob) {
            let r = c.blanking_m + self.rng.uniform() * (range_m - c.blanking_m);
            let amp =
                c.echo_strength * (0.4 + 0.4 * self.rng.uniform()) / (1.0 + c.range_loss_per_m * r);
            let first = (r / bin_m).floor() as usize;
            let len_bins = ((c.echo_length_m / bin_m).ceil() as usize).max(1);
            for l in level.iter_mut().skip(first).take(len_bins) {
                *l = l.max(amp);
            }
        }
        let mut bins = Vec::with_capacity(n);
        for (i, echo) in level.iter().enumerate() {
            let background = c.noise_level * self.rng.exponential();
            let spike = if self.rng.chance(c.speckle_prob) {
                100.0 + 155.0 * self.rng.uniform()
            } else {
                0.0
            };
            let r_centre = (i as f64 + 0.5) * bin_m;
            let v = if r_centre < c.blanking_m {
                0.0
            } else {
                (echo + background).max(spike)
            };
            bins.push(v.round().clamp(0.0, 255.0) as u8);
        }
        bins
    }
}

/// The world-frame bearing of `p` seen from `from` with heading `heading`, relative to the bow,
/// in (−π, π]. A helper for tests and scenario checks.
pub fn relative_bearing(from: P2, heading: f64, p: P2) -> f64 {
    let d = p.sub(from);
    wrap_pi(d.y.atan2(d.x) - heading)
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpf::sonar::{Extractor, ExtractorConfig, Feature};

    fn still(x: f64, y: f64, heading: f64) -> VehicleState {
        VehicleState {
            position: P2::new(x, y),
            heading,
            ..VehicleState::default()
        }
    }

    fn circle(x: f64, y: f64, r: f64) -> SimObstacle {
        SimObstacle::fixed(SimShape::Circle {
            center: P2::new(x, y),
            radius: r,
        })
    }

    /// All pings of `secs` seconds, polled every 0.1 s.
    fn run(
        sonar: &mut Sonar,
        secs: f64,
        v: &VehicleState,
        obs: &[SimObstacle],
        others: &[(P2, f64)],
    ) -> Vec<Ping> {
        let mut out = Vec::new();
        let steps = (secs / 0.1).round() as usize;
        for k in 0..=steps {
            out.extend(sonar.poll(k as f64 * 0.1, v, obs, others));
        }
        out
    }

    #[test]
    fn timing_and_bearings_of_a_continuous_sweep() {
        let cfg = SonarConfig::default();
        assert!((cfg.ping_period_s() - 0.045).abs() < 1e-12);
        assert_eq!(cfg.pings_per_sweep(), 200);
        assert!((cfg.sweep_time_s() - 9.0).abs() < 1e-9);
        let mut s = Sonar::new(cfg);
        let pings = run(&mut s, 9.0, &still(0.0, 0.0, 0.0), &[], &[]);
        // Pings at 0, 45, 90, … ms up to 9.0 s: 201 of them.
        assert_eq!(pings.len(), 201);
        for (k, p) in pings.iter().enumerate() {
            assert_eq!(p.time_ms, 45 * k as u64);
            let want = k as f64 * 1.8f64.to_radians();
            assert!(
                wrap_pi(f64::from(p.bearing_rad) - want).abs() < 1e-5,
                "ping {k}"
            );
            assert!(p.bearing_rad.abs() <= std::f32::consts::PI);
            assert_eq!(p.bins.len(), 300);
            assert_eq!(p.as_scanline().validate(), Ok(()));
        }
        // The 201st ping is back where the first was.
        assert!(pings[200].bearing_rad.abs() < 1e-5);
    }

    #[test]
    fn echo_lands_in_the_right_bin_and_shadows_what_is_behind() {
        let cfg = SonarConfig {
            noise_level: 0.0,
            speckle_prob: 0.0,
            echo_fluctuation: 0.0,
            ..SonarConfig::default()
        };
        let mut s = Sonar::new(cfg);
        // Vehicle at (5, 5) facing +y; a circle 10 m ahead (near face at 9 m), and another
        // behind it, in its shadow.
        let v = still(5.0, 5.0, std::f64::consts::FRAC_PI_2);
        let obs = [circle(5.0, 15.0, 1.0), circle(5.0, 22.0, 1.0)];
        let p = &s.poll(0.0, &v, &obs, &[])[0];
        assert_eq!(p.bearing_rad, 0.0);
        let strong: Vec<usize> = (0..p.bins.len()).filter(|&i| p.bins[i] > 50).collect();
        // Near face at 9.0 m: bins 90 .. 92 (0.3 m long at 0.1 m per bin).
        assert_eq!(strong, vec![90, 91, 92], "{:?}", &p.bins[85..100]);
        // Normal incidence on the axis: 220 / (1 + 0.04·9) ≈ 162.
        assert!((155..=165).contains(&p.bins[90]), "{}", p.bins[90]);
        assert!(p.bins[90] > p.bins[92]);
        // Nothing else, not even the shadowed circle at 20 m, and nothing in the blanking.
        assert!(p
            .bins
            .iter()
            .enumerate()
            .all(|(i, &b)| strong.contains(&i) || b == 0));
        // Looking backwards: nothing.
        let back = Sonar::new(SonarConfig {
            sector: Sector::Sweep {
                center_deg: 180.0,
                width_deg: 10.0,
            },
            ..cfg
        })
        .poll(0.0, &v, &obs, &[])
        .remove(0);
        assert!(back.bins.iter().all(|&b| b == 0));
    }

    #[test]
    fn echo_weakens_with_range_and_incidence() {
        let quiet = SonarConfig {
            noise_level: 0.0,
            speckle_prob: 0.0,
            echo_fluctuation: 0.0,
            rays_per_beam: 1,
            ..SonarConfig::default()
        };
        let peak = |obs: &[SimObstacle]| {
            let p = Sonar::new(quiet).poll(0.0, &still(0.0, 0.0, 0.0), obs, &[]);
            *p[0].bins.iter().max().unwrap()
        };
        let near = peak(&[circle(5.0, 0.0, 1.0)]);
        let far = peak(&[circle(25.0, 0.0, 1.0)]);
        assert!(near > far && far > 90, "{near} {far}");
        // A wall at normal incidence vs. the same wall turned 60° away.
        let wall = |angle: f64| {
            SimObstacle::fixed(SimShape::Rectangle {
                center: P2::new(10.0, 0.0),
                half_size: P2::new(0.2, 8.0),
                angle,
            })
        };
        let square = peak(&[wall(0.0)]);
        let oblique = peak(&[wall(60f64.to_radians())]);
        assert!(
            f64::from(oblique) < 0.8 * f64::from(square),
            "{square} {oblique}"
        );
    }

    #[test]
    fn same_seed_same_pings_other_seed_other_noise() {
        let obs = [circle(8.0, 3.0, 1.0)];
        let v = still(0.0, 0.0, 0.3);
        let pings = |seed| {
            run(
                &mut Sonar::new(SonarConfig {
                    seed,
                    ..SonarConfig::default()
                }),
                2.0,
                &v,
                &obs,
                &[],
            )
        };
        let a = pings(1);
        assert_eq!(a, pings(1));
        assert_ne!(a, pings(2));
        // The noise is there: non-zero bins far from any echo.
        assert!(a[0].bins[250..].iter().any(|&b| b > 0));
    }

    #[test]
    fn speckle_and_background_have_the_configured_statistics() {
        let cfg = SonarConfig {
            speckle_prob: 0.01,
            noise_level: 6.0,
            ..SonarConfig::default()
        };
        let pings = run(&mut Sonar::new(cfg), 9.0, &still(0.0, 0.0, 0.0), &[], &[]);
        let bins: Vec<u8> = pings.iter().flat_map(|p| p.bins[5..].to_vec()).collect();
        let spikes = bins.iter().filter(|&&b| b >= 100).count() as f64 / bins.len() as f64;
        assert!((spikes - 0.01).abs() < 0.002, "{spikes}");
        let low: Vec<f64> = bins
            .iter()
            .filter(|&&b| b < 100)
            .map(|&b| f64::from(b))
            .collect();
        let mean = low.iter().sum::<f64>() / low.len() as f64;
        assert!((mean - 6.0).abs() < 0.3, "{mean}");
        // Blanked bins (centre nearer than 0.5 m) are zero.
        assert!(pings.iter().all(|p| p.bins[..5].iter().all(|&b| b == 0)));
    }

    #[test]
    fn moving_obstacles_and_other_vehicles_are_seen_where_they_are() {
        let quiet = SonarConfig {
            noise_level: 0.0,
            speckle_prob: 0.0,
            echo_fluctuation: 0.0,
            ..SonarConfig::default()
        };
        let first_echo_m = |p: &Ping| p.bins.iter().position(|&b| b > 50).map(|i| i as f64 * 0.1);
        // An obstacle moving towards the vehicle at 1 m/s: at t = 4 s it is 4 m closer.
        let moving = SimObstacle {
            velocity: P2::new(-1.0, 0.0),
            ..circle(20.0, 0.0, 1.0)
        };
        let mut s = Sonar::new(SonarConfig {
            sector: Sector::Sweep {
                center_deg: 0.0,
                width_deg: 3.6,
            },
            ..quiet
        });
        let obs = std::slice::from_ref(&moving);
        let mut pings = s.poll(0.0, &still(0.0, 0.0, 0.0), obs, &[]);
        pings.extend(s.poll(4.0, &still(0.0, 0.0, 0.0), obs, &[]));
        assert_eq!(pings.len(), 89);
        for p in &pings {
            // Each ping sees the obstacle where it was at the ping's own time.
            let tp = p.time_ms as f64 / 1000.0;
            let b = f64::from(p.bearing_rad);
            let want = moving
                .ray_hit(tp, P2::default(), P2::new(b.cos(), b.sin()), 30.0)
                .unwrap();
            let got = first_echo_m(p).unwrap();
            assert!((got - want).abs() <= 0.1, "{got} vs {want} at {tp} s");
        }
        let last = first_echo_m(pings.last().unwrap()).unwrap();
        assert!(last < 15.3, "{last}");
        // Another vehicle (hull radius 0.5) 6 m to port: seen when the head looks left.
        let mut s = Sonar::new(SonarConfig {
            sector: Sector::Sweep {
                center_deg: 90.0,
                width_deg: 3.6,
            },
            ..quiet
        });
        let p = s.poll(0.0, &still(0.0, 0.0, 0.0), &[], &[(P2::new(0.0, 6.0), 0.5)]);
        let r = first_echo_m(&p[0]);
        assert!(r.is_some_and(|r| (r - 5.5).abs() < 0.15), "{r:?}");
    }

    #[test]
    fn sector_scan_reverses_at_the_ends() {
        let mut s = Sonar::new(SonarConfig {
            sector: Sector::Sweep {
                center_deg: 0.0,
                width_deg: 9.0,
            },
            ..SonarConfig::default()
        });
        let b: Vec<f64> = run(&mut s, 0.6, &still(0.0, 0.0, 0.0), &[], &[])
            .iter()
            .map(|p| f64::from(p.bearing_rad).to_degrees())
            .collect();
        let want = [
            -4.5, -2.7, -0.9, 0.9, 2.7, 4.5, 2.7, 0.9, -0.9, -2.7, -4.5, -2.7, -0.9, 0.9,
        ];
        assert_eq!(b.len(), want.len());
        for (x, w) in b.iter().zip(want) {
            assert!((x - w).abs() < 1e-3, "{b:?}");
        }
    }

    /// Features the firmware's extractor (default configuration) finds in `pings`, each ping
    /// with its true pose.
    fn extract(pings: &[Ping]) -> Vec<Feature> {
        let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
        let mut feats: Vec<Feature> = Vec::new();
        for p in pings {
            ex.push_scanline(&p.as_scanline(), p.pose, &mut |f| {
                feats.push(f);
                true
            })
            .unwrap();
        }
        ex.flush(&mut |f| {
            feats.push(f);
            true
        });
        assert_eq!(ex.counters().rejected, 0);
        feats
    }

    fn centre(f: &Feature) -> P2 {
        P2::new(f.center.x.into(), f.center.y.into())
    }

    #[test]
    fn the_firmware_extractor_finds_the_circle() {
        // One full sweep of a scene with one circle, noise and speckle on, fed to the firmware's
        // own extractor with its default configuration: from three still poses, and from a
        // vehicle moving at 1 m/s while turning 1°/s (pings rendered at their own poses).
        let truth = P2::new(12.0, 7.0);
        let obs = [circle(truth.x, truth.y, 1.5)];
        let cases: [(u64, f64, P2, f64); 4] = [
            (1, 0.0, P2::new(0.0, 0.0), 0.0),
            (2, 2.0, P2::new(3.0, -4.0), 0.0),
            (3, -1.0, P2::new(20.0, 15.0), 0.0),
            (4, 0.3, P2::new(-4.0, -3.0), 1.0),
        ];
        for (seed, heading, start, speed) in cases {
            let mut s = Sonar::new(SonarConfig {
                seed,
                ..SonarConfig::default()
            });
            let mut pings = Vec::new();
            let (mut pos, mut h, yaw_rate) = (start, heading, speed * 0.0175);
            let dt = 0.01;
            for k in 0..=900 {
                let vel = P2::new(h.cos(), h.sin()).scale(speed);
                let v = VehicleState {
                    position: pos,
                    heading: h,
                    velocity: vel,
                    r: yaw_rate,
                    ..VehicleState::default()
                };
                pings.extend(s.poll(k as f64 * dt, &v, &obs, &[]));
                pos = pos.add(vel.scale(dt));
                h += yaw_rate * dt;
            }
            assert_eq!(pings.len(), 201);
            let feats = extract(&pings);
            let best = feats
                .iter()
                .min_by(|a, b| {
                    let da = centre(a).sub(truth).norm();
                    da.total_cmp(&centre(b).sub(truth).norm())
                })
                .expect("a feature");
            let err = centre(best).sub(truth).norm();
            eprintln!(
                "seed {seed}, speed {speed}: {} features; best centre error {err:.3} m, \
                 radius {:.2} m, {} beams, confidence {:.2}",
                feats.len(),
                best.radius,
                best.beams,
                best.confidence
            );
            assert!(err < 0.5, "centre off by {err} m: {best:?}");
            assert!(
                !best.is_rectangle() && (best.radius - 1.5).abs() < 0.3,
                "{best:?}"
            );
            assert!(best.confidence >= 0.5, "{best:?}");
            // Noise and speckle do not make confident phantoms.
            let phantoms = feats
                .iter()
                .filter(|f| f.confidence >= 0.5 && centre(f).sub(truth).norm() > 3.0)
                .count();
            assert_eq!(phantoms, 0, "{feats:?}");
        }
    }

    #[test]
    fn more_rays_smear_the_echo_across_the_beam() {
        // Pings with an echo from a wall 10 m ahead whose ends are at ±12.0°. The pencil beam
        // sees it on the pings at 0, ±1.8°, …, ±10.8° (and 0° again after the full turn): 14.
        // Five rays over the 3° beam also catch it on the pings at ±12.6°, whose ray at
        // ±11.85° (weight 0.71) returns ≈ 109 at near-normal incidence.
        let obs = [SimObstacle::fixed(SimShape::Rectangle {
            center: P2::new(10.1, 0.0),
            half_size: P2::new(0.1, 10.0 * 12f64.to_radians().tan()),
            angle: 0.0,
        })];
        let count = |rays| {
            let mut s = Sonar::new(SonarConfig {
                rays_per_beam: rays,
                noise_level: 0.0,
                speckle_prob: 0.0,
                echo_fluctuation: 0.0,
                ..SonarConfig::default()
            });
            run(&mut s, 9.0, &still(0.0, 0.0, 0.0), &obs, &[])
                .iter()
                .filter(|p| p.bins.iter().any(|&b| b >= 60))
                .count()
        };
        let (one, five) = (count(1), count(5));
        assert_eq!((one, five), (14, 16));
    }

    #[test]
    fn head_offset_and_pose_extrapolation() {
        let quiet = SonarConfig {
            noise_level: 0.0,
            speckle_prob: 0.0,
            echo_fluctuation: 0.0,
            head_offset: P2::new(0.5, 0.0),
            ..SonarConfig::default()
        };
        // Head 0.5 m ahead of the centre: the face at 9 m from the centre is 8.5 m from the head.
        let mut s = Sonar::new(quiet);
        let p = s.poll(0.0, &still(0.0, 0.0, 0.0), &[circle(10.0, 0.0, 1.0)], &[]);
        assert_eq!(p[0].bins.iter().position(|&b| b > 50), Some(85));
        // Polled late while moving at 2 m/s: each ping is rendered from the pose back along
        // the track at its own time.
        let mut s = Sonar::new(SonarConfig {
            head_offset: P2::default(),
            ..quiet
        });
        let moving = VehicleState {
            velocity: P2::new(2.0, 0.0),
            r: 0.5,
            ..still(0.0, 0.0, 0.0)
        };
        assert_eq!(s.poll(0.0, &moving, &[], &[]).len(), 1);
        let p = s.poll(0.145, &moving, &[circle(10.0, 0.0, 1.0)], &[]);
        assert_eq!(
            p.iter().map(|p| p.time_ms).collect::<Vec<_>>(),
            vec![45, 90, 135]
        );
        for q in &p {
            let back = 0.145 - q.time_ms as f64 / 1000.0;
            assert!(
                (f64::from(q.pose.position.x) + 2.0 * back).abs() < 1e-6,
                "{q:?}"
            );
            assert!(
                (f64::from(q.pose.heading) + 0.5 * back).abs() < 1e-6,
                "{q:?}"
            );
        }
    }

    #[test]
    fn odd_inputs_never_panic() {
        let cfg = SonarConfig {
            range_m: f64::NAN,
            bins: 0,
            step_deg: 100.0,
            sector: Sector::Sweep {
                center_deg: f64::INFINITY,
                width_deg: 0.0,
            },
            beam_width_deg: -1.0,
            rays_per_beam: 0,
            sound_speed: 0.0,
            ping_overhead_s: f64::NAN,
            noise_level: 1e9,
            speckle_prob: 2.0,
            false_echo_prob: f64::NAN,
            echo_strength: f64::NAN,
            range_loss_per_m: -3.0,
            echo_fluctuation: 5.0,
            echo_length_m: 100.0,
            blanking_m: 1e6,
            head_offset: P2::new(f64::NAN, 1e6),
            seed: 9,
        };
        assert_eq!(cfg.validate(), Err(SonarConfigError { field: "range_m" }));
        assert_eq!(SonarConfig::default().validate(), Ok(()));
        assert_eq!(
            SonarConfig {
                bins: 600,
                ..SonarConfig::default()
            }
            .validate(),
            Err(SonarConfigError { field: "bins" })
        );
        let c = cfg.clamped();
        assert_eq!(c.validate(), Ok(()));
        let mut s = Sonar::new(cfg);
        let weird = VehicleState {
            position: P2::new(f64::NAN, 1e300),
            heading: f64::INFINITY,
            r: f64::NAN,
            ..VehicleState::default()
        };
        let bad_obs = [
            circle(f64::NAN, 0.0, 1.0),
            SimObstacle::fixed(SimShape::Polygon { points: vec![] }),
            circle(0.0, 0.0, -2.0),
        ];
        assert!(s.poll(f64::NAN, &weird, &bad_obs, &[]).is_empty());
        let p = s.poll(
            0.0,
            &weird,
            &bad_obs,
            &[(P2::new(f64::NAN, 0.0), f64::INFINITY)],
        );
        assert_eq!(p.len(), 1);
        for q in &p {
            assert_eq!(q.as_scanline().validate(), Ok(()));
        }
        // A huge jump in time is bounded.
        let p = s.poll(1e12, &still(0.0, 0.0, 0.0), &[], &[]);
        assert_eq!(p.len(), MAX_PINGS_PER_POLL);
        assert!(p.windows(2).all(|w| w[0].time_ms <= w[1].time_ms));
        assert!(s.poll(-5.0, &still(0.0, 0.0, 0.0), &[], &[]).is_empty());
    }

    #[test]
    fn relative_bearing_is_ccw_from_the_bow() {
        let b = relative_bearing(
            P2::new(1.0, 1.0),
            std::f64::consts::FRAC_PI_2,
            P2::new(0.0, 1.0),
        );
        assert!((b - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }
}
