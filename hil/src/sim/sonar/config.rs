//! The simulated sonar's configuration: the head's motion, range, bins and beam, the echo's
//! strengths and noise, each checked and clamped to what the firmware takes.

use crate::types::P2;

/// How the head moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sector {
    /// Continuous rotation, counter-clockwise, starting straight ahead.
    Continuous,
    /// Back and forth over `center_deg ± width_deg/2` (relative to the bow), starting at the
    /// clockwise end and going counter-clockwise; it reverses at the first step that would
    /// pass an end by more than half a step (so when the width is not a whole number of steps,
    /// the head may pass an end by less than half a step). A width of 360° or more is
    /// continuous; a width below two steps is widened to two steps.
    Sweep {
        /// Centre of the sector, degrees counter-clockwise from the bow.
        center_deg: f64,
        /// Width of the sector, degrees.
        width_deg: f64,
    },
}

/// The sonar's configuration. [`Default`] is a Micron at 30 m: 300 bins, 1.8° steps,
/// continuous rotation.
///
/// [`SonarConfig::validate`] says which field is out of range; [`Sonar::new`](super::Sonar::new) instead clamps
/// every field into its range ([`SonarConfig::clamped`]; a non-finite number takes its
/// default), so a sonar can always be built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SonarConfig {
    /// Range of the last bin's far edge, m, 0.5 ..= 200 (the firmware's scanline limits).
    pub range_m: f64,
    /// Bins per ping, 1 ..= 512.
    pub bins: usize,
    /// Head step, degrees, 0.06 ..= 11.4 (the firmware's 1e-3 ..= 0.2 rad); the Micron offers
    /// 0.45, 0.9, 1.8 and 3.6.
    pub step_deg: f64,
    /// Rotation pattern.
    pub sector: Sector,
    /// Horizontal −3 dB beam width, degrees, 0.1 ..= 60 (the Micron's is 3°).
    pub beam_width_deg: f64,
    /// Rays cast across the beam, 1 ..= 32 (1: a pencil beam; see the module docs).
    pub rays_per_beam: usize,
    /// Speed of sound, m/s, 1000 ..= 2000.
    pub sound_speed: f64,
    /// Time per ping besides the echo's round trip (head step, line transfer), s, 0 ..= 10.
    /// The default 5 ms is an assumption (a stepper move of 1.8° plus a few hundred bytes on
    /// a fast serial line); it only stretches the sweep time.
    pub ping_overhead_s: f64,
    /// Mean background intensity, 0 ..= 255.
    pub noise_level: f64,
    /// Probability per bin of a one-bin speckle spike, 0 ..= 1.
    pub speckle_prob: f64,
    /// Probability per ping of a spurious target: an echo as long as a surface return, of
    /// 40–80 % of `echo_strength`, at a uniformly random range beyond the blanking distance
    /// (a fish, a side-lobe return from the bottom), 0 ..= 1.
    pub false_echo_prob: f64,
    /// Raw intensity of a normal-incidence return at zero range on the beam axis, 0 ..= 1000
    /// (bins saturate at 255).
    pub echo_strength: f64,
    /// Residual loss slope: the return falls as `1 / (1 + k·r)`, per metre, 0 ..= 1.
    pub range_loss_per_m: f64,
    /// Per-ray fading: the return is scaled by a uniform factor in `1 ± this`, 0 ..= 1.
    pub echo_fluctuation: f64,
    /// Length of a surface return along the beam, m, 0 ..= 5 (at least one bin is filled).
    pub echo_length_m: f64,
    /// Blanking distance: bins nearer than this are 0 and nothing nearer is seen, m,
    /// 0 ..= `range_m`.
    pub blanking_m: f64,
    /// Head position in the body frame (x forward, y to port), m, each axis within ±20.
    pub head_offset: P2,
    /// Seed of the noise.
    pub seed: u64,
}

impl Default for SonarConfig {
    fn default() -> Self {
        SonarConfig {
            range_m: 30.0,
            bins: 300,
            step_deg: 1.8,
            sector: Sector::Continuous,
            beam_width_deg: 3.0,
            rays_per_beam: 1,
            sound_speed: 1500.0,
            ping_overhead_s: 0.005,
            noise_level: 6.0,
            speckle_prob: 0.002,
            false_echo_prob: 0.0,
            echo_strength: 220.0,
            range_loss_per_m: 0.04,
            echo_fluctuation: 0.2,
            echo_length_m: 0.3,
            blanking_m: 0.5,
            head_offset: P2::new(0.0, 0.0),
            seed: 0,
        }
    }
}

/// A sonar configuration field out of range (its name, as in [`SonarConfig`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("sonar `{field}` is out of range or not a finite number (see SonarConfig)")]
pub struct SonarConfigError {
    /// The field.
    pub field: &'static str,
}

/// `x` clamped to `lo ..= hi`, or `default` if not finite.
fn clampf(x: f64, lo: f64, hi: f64, default: f64) -> f64 {
    if x.is_finite() {
        x.clamp(lo, hi)
    } else {
        default
    }
}

/// Firmware step limits, degrees, slightly inside so the `f32` conversion stays valid.
fn step_limits_deg() -> (f64, f64) {
    (
        f64::from(vpf::sonar::MIN_STEP_RAD).to_degrees() * 1.0001,
        f64::from(vpf::sonar::MAX_STEP_RAD).to_degrees() * 0.9999,
    )
}

impl SonarConfig {
    /// Every field clamped into its documented range; a non-finite number takes the default's
    /// value (a non-finite head offset is zero).
    pub fn clamped(&self) -> SonarConfig {
        let d = SonarConfig::default();
        let range_m = clampf(
            self.range_m,
            f64::from(vpf::sonar::MIN_RANGE_M),
            f64::from(vpf::sonar::MAX_RANGE_M),
            d.range_m,
        );
        let (smin, smax) = step_limits_deg();
        let step_deg = clampf(self.step_deg, smin, smax, d.step_deg);
        let sector = match self.sector {
            Sector::Continuous => Sector::Continuous,
            Sector::Sweep {
                center_deg,
                width_deg,
            } => {
                let w = clampf(width_deg, 2.0 * step_deg, 360.0, 360.0);
                if w >= 360.0 {
                    Sector::Continuous
                } else {
                    Sector::Sweep {
                        center_deg: clampf(center_deg, -360.0, 360.0, 0.0),
                        width_deg: w,
                    }
                }
            }
        };
        let off = |x: f64| clampf(x, -20.0, 20.0, 0.0);
        SonarConfig {
            range_m,
            bins: self.bins.clamp(1, vpf::sonar::MAX_BINS),
            step_deg,
            sector,
            beam_width_deg: clampf(self.beam_width_deg, 0.1, 60.0, d.beam_width_deg),
            rays_per_beam: self.rays_per_beam.clamp(1, 32),
            sound_speed: clampf(self.sound_speed, 1000.0, 2000.0, d.sound_speed),
            ping_overhead_s: clampf(self.ping_overhead_s, 0.0, 10.0, d.ping_overhead_s),
            noise_level: clampf(self.noise_level, 0.0, 255.0, d.noise_level),
            speckle_prob: clampf(self.speckle_prob, 0.0, 1.0, d.speckle_prob),
            false_echo_prob: clampf(self.false_echo_prob, 0.0, 1.0, d.false_echo_prob),
            echo_strength: clampf(self.echo_strength, 0.0, 1000.0, d.echo_strength),
            range_loss_per_m: clampf(self.range_loss_per_m, 0.0, 1.0, d.range_loss_per_m),
            echo_fluctuation: clampf(self.echo_fluctuation, 0.0, 1.0, d.echo_fluctuation),
            echo_length_m: clampf(self.echo_length_m, 0.0, 5.0, d.echo_length_m),
            blanking_m: clampf(self.blanking_m, 0.0, range_m, d.blanking_m.min(range_m)),
            head_offset: P2::new(off(self.head_offset.x), off(self.head_offset.y)),
            seed: self.seed,
        }
    }

    /// `Ok` when every field is within its documented range (so [`SonarConfig::clamped`] would
    /// change nothing), else the first field that is not.
    pub fn validate(&self) -> Result<(), SonarConfigError> {
        let c = self.clamped();
        let bad = |field| Err(SonarConfigError { field });
        // `!=` is true for NaN, so non-finite values are caught too.
        let checks: [(&'static str, bool); 17] = [
            ("range_m", c.range_m != self.range_m),
            ("bins", c.bins != self.bins),
            ("step_deg", c.step_deg != self.step_deg),
            (
                "sector",
                match (self.sector, c.sector) {
                    (Sector::Sweep { .. }, Sector::Continuous) => {
                        !matches!(self.sector, Sector::Sweep { width_deg, .. } if width_deg == 360.0)
                    }
                    (a, b) => a != b,
                },
            ),
            ("beam_width_deg", c.beam_width_deg != self.beam_width_deg),
            ("rays_per_beam", c.rays_per_beam != self.rays_per_beam),
            ("sound_speed", c.sound_speed != self.sound_speed),
            ("ping_overhead_s", c.ping_overhead_s != self.ping_overhead_s),
            ("noise_level", c.noise_level != self.noise_level),
            ("speckle_prob", c.speckle_prob != self.speckle_prob),
            ("false_echo_prob", c.false_echo_prob != self.false_echo_prob),
            ("echo_strength", c.echo_strength != self.echo_strength),
            (
                "range_loss_per_m",
                c.range_loss_per_m != self.range_loss_per_m,
            ),
            (
                "echo_fluctuation",
                c.echo_fluctuation != self.echo_fluctuation,
            ),
            ("echo_length_m", c.echo_length_m != self.echo_length_m),
            ("blanking_m", c.blanking_m != self.blanking_m),
            ("head_offset", c.head_offset != self.head_offset),
        ];
        match checks.iter().find(|(_, differs)| *differs) {
            Some((field, _)) => bad(field),
            None => Ok(()),
        }
    }

    /// Duration of one ping: the round trip to full range plus the overhead, s.
    pub fn ping_period_s(&self) -> f64 {
        2.0 * self.range_m / self.sound_speed + self.ping_overhead_s
    }

    /// Pings in one sweep: a full turn, or one pass over the sector.
    pub fn pings_per_sweep(&self) -> usize {
        let deg = match self.sector {
            Sector::Continuous => 360.0,
            Sector::Sweep { width_deg, .. } => width_deg,
        };
        // Finite after clamping; `as` saturates anyway.
        (deg / self.step_deg).round().max(1.0) as usize
    }

    /// Time for one sweep ([`SonarConfig::pings_per_sweep`] pings), s.
    pub fn sweep_time_s(&self) -> f64 {
        self.pings_per_sweep() as f64 * self.ping_period_s()
    }
}
