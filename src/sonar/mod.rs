//! Sonar feature extraction: scanlines of a mechanically scanned imaging sonar (Tritech
//! Micron-like) in, obstacle features out.
//!
//! The sonar head steps through bearings and returns one [`Scanline`] per ping: `bins` 8-bit
//! intensities equally spaced over `0 ..= range_m` (bin `i` covers `[iΔ, (i+1)Δ)` with
//! `Δ = range_m / bins`, and is read at its centre `(i + ½)Δ`). A 360° sweep takes seconds, so
//! every scanline comes with the vehicle [`Pose`] at its ping time and is put in the world frame
//! at once. [`Extractor::push_scanline`] runs the pipeline, in a preemptible low-priority context;
//! features leave through a caller-supplied sink (e.g. a `heapless::spsc::Producer`), never
//! blocking and never allocating:
//!
//! 1. **Detection** ([`detect`]): every bin beyond the blanking distance is multiplied by a
//!    range-dependent gain `g(r) = min(1 + k·r, g_max)` — a linear approximation of the residual
//!    spreading and absorption loss the head's own time-varied gain leaves (a `20·log10 r` curve
//!    is nearly linear over 1–30 m, and a linear gain costs one multiply-add per bin) — and
//!    compared with `threshold`. Consecutive bins above it, with gaps up to `run_gap_m`, form an
//!    echo run; a run counts if it is at least `min_run_bins` long and its peak reaches
//!    `peak_min` (hysteresis against speckle). The nearest `runs_per_beam` runs are kept, each
//!    with the range of its leading edge (the obstacle's near face), its peak and its mean.
//!
//!    **Weak echoes.** A run whose peak is below `feature_peak_min` (120; `peak_min` is 100)
//!    takes no part in the clusters and features below; it goes to the evidence map, and only
//!    when the neighbouring beam returned an echo within the cluster gap of it (a false target
//!    is one ping; a surface spans beams). A wall met more than about 65° from its normal
//!    returns that little (in the simulated sonar the echo falls as ¼ + ¾·cos θ), and with
//!    every run at 120 the wall ahead in a channel was never believed (`hil bench`). With
//!    `peak_min` 100 for features too, or weak echoes believed alone within the map's
//!    `near_m`, the crossing worlds' contacts rose (movers' fits and false targets); split as
//!    here, channels, harbours and crossing × 3 strategies, seeds 0–199: contacts 30 → 22;
//!    seeds 200–299 of five families, not looked at before: 16 → 9 (channels 10 → 2).
//! 2. **Clustering** (`cluster`): each run is paired with an open cluster whose last run, on
//!    one of the previous `max_missed_beams + 1` beams, is within `cluster_gap_m` in range —
//!    closest pairs first, one run per cluster per beam; a run left over opens a new cluster.
//!    A cluster closes when it has missed more than `max_missed_beams` beams, when it spans
//!    `max_span_rad` of head travel, or when the sweep breaks (direction reversal, a bearing
//!    jump, a time gap, a pose jump). Points are accumulated as running moments in the world
//!    frame, so each cluster is O(1) memory.
//! 3. **Fit** (`fit`): a circle from the algebraic (Kåsa) least-squares fit of the moments when
//!    it is well conditioned and plausible; else an oriented rectangle from the principal axes
//!    when the cluster is elongated (a wall); else a circle whose radius comes from the lateral
//!    spread and whose centre is pushed away from the sensor (the sonar sees only the near
//!    face). Plus a confidence in `0 ..= 1` from the number of hits, the fill of the beams
//!    spanned and the echo intensity. Closed clusters with at least `min_beams` hits and
//!    `min_confidence` leave as a [`Feature`]. The defaults take a strong echo on two adjacent
//!    beams (confidence ≈ 0.2): a target narrower than the beam — another VideoRay, 0.4 m
//!    across, is on one or two 1.8° pings of a 3° beam at any range — is never on three, and
//!    with three required two VideoRays meeting head-on never saw each other (generated
//!    head-on worlds, own sonar). A false target is one ping, so two beams agreeing within the
//!    cluster gap is also what the evidence map asks of a far echo (`evidence`). A single
//!    sweep cannot tell such a target from a chance chain of speckle, so consumers wanting
//!    sonar-only obstacles to be sure should ask for ≥ 0.5 (four or more consistent beams) or
//!    for persistence. One strong beam within 15 m taken as a feature too (a peak of 200,
//!    above the simulated false targets' 176) let two VideoRays see each other more often,
//!    but crossing and head-on worlds × 3 strategies, seeds 0–199, had 32 contacts against
//!    18: the movers' one-beam fragments opened tracks, and sightings seconds apart gave
//!    velocities far off; opening new tracks only, never updating one, 31. The converse is
//!    kept: a strong single beam leaves as a *glimpse* ([`GLIMPSE_INTENSITY`]: one
//!    beam, confidence 0) that alone never opens a track and gives a track seen once its
//!    second look (`crate::guidance::tracks`, "Glimpses"); it, and any other beam of one hit
//!    at least [`FAINT_INTENSITY`] (within [`FAINT_AHEAD_RAD`] of the bow,
//!    [`FAINT_AHEAD_INTENSITY`]: a *faint* sighting), the tracker believes as a new target
//!    only as one of two a sweep apart on a collision course (`crate::guidance::faint`).
//!
//! **Vehicles it is told about.** An echo on a vehicle the host reports (`Contacts` of kind
//! vehicle: a formation's mates) is that vehicle, not structure: it leaves no feature and no
//! believed cell, though the beam's free water ends there ([`KnownVehicles`], at most
//! [`MAX_KNOWN`], the stalest replaced when full; counted in [`Counters::vehicle_echoes`]).
//!
//! **Frames.** [`Pose::heading`] is the bow's direction, radians counter-clockwise from the world
//! +x axis (as [`Vec2::from_angle`]); [`Scanline::bearing_rad`] is the head angle relative to the
//! bow, counter-clockwise positive. A ping's world direction is `heading + bearing`; its origin is
//! the vehicle position plus the head offset (body frame: x forward, y to port).
//!
//! **Cost.** One scanline is O(bins) for detection (at most [`MAX_BINS`] multiply-compares,
//! with an early exit once `runs_per_beam` runs are found) plus O([`MAX_RUNS_PER_BEAM`] ×
//! [`MAX_CLUSTERS`]) for matching, plus at most [`MAX_CLUSTERS`] O(1) fits.
//!
//! **Capacities and policies when full.**
//! - Runs per beam: [`MAX_RUNS_PER_BEAM`]; farther runs are ignored (the nearest obstacle is
//!   the one that matters, and the sonar's shadow hides most behind it).
//! - Open clusters: [`MAX_CLUSTERS`]. [`ExtractorConfig::validate`] requires
//!   `runs_per_beam · (max_missed_beams + 1) ≤ MAX_CLUSTERS`, which is the most clusters that can
//!   be open at once, so the table cannot fill in operation; should it ever be full, the *new*
//!   cluster is dropped (its run ignored) and counted in [`Counters::clusters_dropped`], and the
//!   clusters already being tracked continue.
//! - Points per cluster: unbounded count, constant memory (running sums about the cluster's
//!   first point, so `f32` keeps centimetres far from the origin). A cluster is cut, emitted and
//!   restarted after `max_span_rad` of head travel, which also bounds the hits it sums.
//! - Known vehicles: [`MAX_KNOWN`]; a new one replaces the stalest, and a report older than
//!   [`MAX_AGE_MS`] hides nothing.
//! - Output: the sink returns `false` when it is full; the feature is then lost and counted in
//!   [`Counters::sink_full`]. The extractor never waits.

mod cluster;
pub mod detect;
pub mod evidence;
mod extractor;
mod fit;
mod known;
pub mod lookout;
pub mod ping360;
pub mod wakes;

use crate::field::{Shape, ShapeError};
use crate::math::{Vec2, PI};

pub use crate::types::scanline::{
    ScanError, Scanline, MAX_BINS, MAX_RANGE_M, MAX_STEP_RAD, MIN_RANGE_M, MIN_STEP_RAD,
};
pub use detect::Echo;
pub use evidence::{
    Beam, EvidenceConfig, EvidenceError, EvidenceMap, Near, Window, MAP_SIDE, MAX_REACH_CELLS,
};
pub use extractor::{
    Extractor, FAINT_AHEAD_INTENSITY, FAINT_AHEAD_RAD, FAINT_INTENSITY, GLIMPSE_INTENSITY,
};
pub use known::{KnownVehicles, ECHO_MARGIN_M, MAX_AGE_MS, MAX_KNOWN};
pub use lookout::{Lookout, LOOK_SECTORS};
pub use wakes::{Wakes, MAX_WAKES};

/// Largest accepted vehicle coordinate, m (100 km, as the planner's limit: `f32` still resolves
/// 8 mm there).
pub const MAX_POSITION_M: f32 = 100_000.0;
/// Most echo runs kept per beam (nearest first).
pub const MAX_RUNS_PER_BEAM: usize = 2;
/// Capacity of the open-cluster table.
pub const MAX_CLUSTERS: usize = 8;
/// Largest radius or half-size a feature is given, m (bigger fits are clamped).
pub const MAX_FEATURE_EXTENT_M: f32 = 100.0;

/// The vehicle pose at a ping's time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pose {
    /// Position in the local Earth-fixed frame, m.
    pub position: Vec2,
    /// Bow direction, counter-clockwise from +x, rad.
    pub heading: f32,
}

impl Pose {
    /// Checks the pose is finite and within [`MAX_POSITION_M`] per axis.
    pub fn validate(&self) -> Result<(), ScanError> {
        let p = self.position;
        if p.is_finite()
            && self.heading.is_finite()
            && p.x.abs() <= MAX_POSITION_M
            && p.y.abs() <= MAX_POSITION_M
        {
            Ok(())
        } else {
            Err(ScanError::BadPose)
        }
    }
}

/// Tuning of the extractor. [`Default`] suits a Micron at 0–30 m range; see the module docs for
/// what each stage does with these numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ExtractorConfig {
    /// Detection threshold on the gain-compensated intensity (raw × g(r)), 1 ..= 4096.
    pub threshold: f32,
    /// A run counts only if its compensated peak reaches this (≥ `threshold`).
    pub peak_min: f32,
    /// ... and takes part in features only if its peak also reaches this, 1 ..= 4096; weaker
    /// runs feed the evidence map alone: a wall met at a grazing angle returns less than a
    /// target seen face on (module notes, "Weak echoes").
    pub feature_peak_min: f32,
    /// Gain slope k of g(r) = 1 + k·r, per metre, 0 ..= 1.
    pub gain_per_m: f32,
    /// Gain ceiling g_max, 1 ..= 16 (keeps far noise from being amplified without bound).
    pub gain_max: f32,
    /// Bins nearer than this are ignored (transducer ringing), m, 0 ..= 10. The default 1.0 is
    /// generous: in the real Ping360 recording (`../shared/data/ping360`, 16 µs pulse) the
    /// ring-down is gone by 0.25 m. 0.6 m (just beyond the simulated head's 0.5 m) was tried,
    /// to let two VideoRays see each other in close quarters; crossing and head-on × 3
    /// strategies, seeds 0–199: contacts 2 → 2, two gone and two new, each vehicle running into
    /// another it had not looked at in the last metres (the head comes round every 3.2 s).
    pub blanking_m: f32,
    /// Largest gap inside one run along a beam, m, 0 ..= 5.
    pub run_gap_m: f32,
    /// Shortest run, bins, 1 ..= 64.
    pub min_run_bins: u16,
    /// Runs kept per beam, nearest first, 1 ..= [`MAX_RUNS_PER_BEAM`].
    pub runs_per_beam: u8,
    /// Largest range difference between runs on adjacent beams of one cluster, m, 0.01 ..= 20.
    pub cluster_gap_m: f32,
    /// Beams a cluster may miss and still continue, 0 ..= 3 (echoes fade on single pings).
    pub max_missed_beams: u8,
    /// Fewest hits (beams with a run) for a feature, 1 ..= 1000.
    pub min_beams: u16,
    /// Features below this confidence are discarded, 0 ..= 1.
    pub min_confidence: f32,
    /// Ratio of principal spreads σ₁/σ₂ above which a cluster is fitted as a rectangle,
    /// 1.5 ..= 100 (the near arc of a circle has about 2.6).
    pub elongation: f32,
    /// Head travel after which a cluster is cut and emitted, rad, 0.05 ..= π.
    pub max_span_rad: f32,
    /// Half-thickness given to a wall (only its face is seen), m, 0.01 ..= 10.
    pub wall_half_thickness_m: f32,
    /// Smallest circle radius emitted, m, 0.01 ..= 10.
    pub min_radius_m: f32,
    /// Pings farther apart than this (or going back in time) break the sweep, ms, ≥ 1.
    pub max_gap_ms: u32,
    /// A sensor displacement between consecutive pings above this breaks the sweep (a
    /// navigation reset), m, 0.01 ..= 1000.
    pub max_pose_jump_m: f32,
    /// Sonar head position in the body frame (x forward, y to port), m, each axis within ±20.
    pub head_offset: Vec2,
}

impl Default for ExtractorConfig {
    fn default() -> Self {
        ExtractorConfig {
            threshold: 90.0,
            peak_min: 100.0,
            feature_peak_min: 120.0,
            gain_per_m: 0.04,
            gain_max: 3.0,
            blanking_m: 1.0,
            run_gap_m: 0.2,
            min_run_bins: 2,
            runs_per_beam: 2,
            cluster_gap_m: 1.0,
            max_missed_beams: 1,
            min_beams: 2,
            min_confidence: 0.15,
            elongation: 4.0,
            max_span_rad: PI / 2.0,
            wall_half_thickness_m: 0.25,
            min_radius_m: 0.1,
            max_gap_ms: 1_000,
            max_pose_jump_m: 5.0,
            head_offset: Vec2::ZERO,
        }
    }
}

/// Which configuration field is out of range (or inconsistent with another).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// `threshold` or `peak_min` (which must be ≥ `threshold`).
    Threshold,
    /// `gain_per_m` or `gain_max`.
    Gain,
    /// `blanking_m`.
    Blanking,
    /// `run_gap_m` or `min_run_bins`.
    Run,
    /// `runs_per_beam`, `max_missed_beams`, or their product exceeding [`MAX_CLUSTERS`].
    Capacity,
    /// `cluster_gap_m`.
    ClusterGap,
    /// `min_beams` or `min_confidence`.
    Acceptance,
    /// `elongation`, `max_span_rad`, `wall_half_thickness_m` or `min_radius_m`.
    Fit,
    /// `max_gap_ms` or `max_pose_jump_m`.
    Continuity,
    /// `head_offset`.
    HeadOffset,
}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ConfigError::Threshold => "sonar threshold or peak_min out of range",
            ConfigError::Gain => "sonar gain slope or ceiling out of range",
            ConfigError::Blanking => "sonar blanking distance out of range",
            ConfigError::Run => "sonar run gap or minimum run length out of range",
            ConfigError::Capacity => {
                "sonar runs_per_beam x (max_missed_beams + 1) exceeds the cluster table"
            }
            ConfigError::ClusterGap => "sonar cluster gap out of range",
            ConfigError::Acceptance => "sonar min_beams or min_confidence out of range",
            ConfigError::Fit => "sonar fit parameters out of range",
            ConfigError::Continuity => "sonar max_gap_ms or max_pose_jump_m out of range",
            ConfigError::HeadOffset => "sonar head offset non-finite or beyond 20 m",
        })
    }
}

impl core::error::Error for ConfigError {}

/// `lo ..= hi`, false for NaN.
fn within(v: f32, lo: f32, hi: f32) -> bool {
    (lo..=hi).contains(&v)
}

impl ExtractorConfig {
    /// Checks every field's range (see the field docs) and the capacity rule.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if !within(self.threshold, 1.0, 4096.0)
            || !within(self.peak_min, self.threshold, 4096.0)
            || !within(self.feature_peak_min, 1.0, 4096.0)
        {
            return Err(ConfigError::Threshold);
        }
        if !within(self.gain_per_m, 0.0, 1.0) || !within(self.gain_max, 1.0, 16.0) {
            return Err(ConfigError::Gain);
        }
        if !within(self.blanking_m, 0.0, 10.0) {
            return Err(ConfigError::Blanking);
        }
        if !within(self.run_gap_m, 0.0, 5.0) || !(1..=64).contains(&self.min_run_bins) {
            return Err(ConfigError::Run);
        }
        let runs = usize::from(self.runs_per_beam);
        let beams = usize::from(self.max_missed_beams) + 1;
        if !(1..=MAX_RUNS_PER_BEAM).contains(&runs) || beams > 4 || runs * beams > MAX_CLUSTERS {
            return Err(ConfigError::Capacity);
        }
        if !within(self.cluster_gap_m, 0.01, 20.0) {
            return Err(ConfigError::ClusterGap);
        }
        if !(1..=1000).contains(&self.min_beams) || !within(self.min_confidence, 0.0, 1.0) {
            return Err(ConfigError::Acceptance);
        }
        if !within(self.elongation, 1.5, 100.0)
            || !within(self.max_span_rad, 0.05, PI)
            || !within(self.wall_half_thickness_m, 0.01, 10.0)
            || !within(self.min_radius_m, 0.01, 10.0)
        {
            return Err(ConfigError::Fit);
        }
        if self.max_gap_ms == 0 || !within(self.max_pose_jump_m, 0.01, 1000.0) {
            return Err(ConfigError::Continuity);
        }
        if !within(self.head_offset.x, -20.0, 20.0) || !within(self.head_offset.y, -20.0, 20.0) {
            return Err(ConfigError::HeadOffset);
        }
        Ok(())
    }
}

/// The geometry fitted to a cluster.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FeatureKind {
    /// A compact echo: a circle of this radius, m.
    Circle {
        /// Radius, m.
        radius: f32,
    },
    /// An elongated echo (a wall, a hull): an oriented rectangle.
    Rectangle {
        /// Half-sizes along the rectangle's own axes (x along the principal axis), m.
        half: Vec2,
        /// Rotation of the principal axis from world +x, rad, in (−π/2, π/2].
        angle: f32,
    },
}

/// An obstacle seen by the sonar over one or more adjacent beams, in the world frame.
/// Every number is finite.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Feature {
    /// Centre, m (already pushed behind the seen face).
    pub center: Vec2,
    /// Radius of the circle, or the rectangle's bounding radius, m.
    pub radius: f32,
    /// The fitted geometry.
    pub kind: FeatureKind,
    /// Belief that this is a real obstacle, 0 ..= 1.
    pub confidence: f32,
    /// Time of the last ping that contributed, ms.
    pub time_ms: u64,
    /// Beams with an echo in this feature.
    pub beams: u16,
    /// Believed structure runs on beyond it in the evidence map (set by
    /// `Extractor::push_scanline_mapped`, [`EvidenceMap::runs_on`]): a fragment of a wall, a
    /// pier or a cluster of rocks, which the tracker never gives a velocity. For a faint
    /// sighting, any believed cell 1–2 m from it ([`EvidenceMap::occupied_between`]): the edge
    /// of a wall seen on one beam, which the tracker pairs with nothing.
    pub runs_on: bool,
    /// One beam of an echo too weak to be a glimpse: alone it may be a spurious target, so the
    /// tracker takes it only as one of a pair on a collision course
    /// (`crate::guidance::faint`).
    pub faint: bool,
}

/// A faint sighting ([`Feature::faint`]) within this of an obstacle believed, m, is that
/// obstacle's edge on one beam: the tracker pairs it with nothing (`crate::guidance::faint`).
pub const FAINT_ALONE_M: f32 = 2.0;

impl Feature {
    /// The planner's shape for this feature (a circle or a rectangle); feed it to
    /// `Obstacle::new(id, shape, a_plus, Origin::Sensed, feature.time_ms)`.
    pub fn to_shape(&self) -> Result<Shape, ShapeError> {
        match self.kind {
            FeatureKind::Circle { radius } => Shape::circle(self.center, radius),
            FeatureKind::Rectangle { half, angle } => Shape::rectangle(self.center, half, angle),
        }
    }

    /// True when this is a rectangle (elongated) fit.
    pub fn is_rectangle(&self) -> bool {
        matches!(self.kind, FeatureKind::Rectangle { .. })
    }
}

/// What the extractor has done since it was made (saturating counts).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Counters {
    /// Scanlines accepted and processed.
    pub scanlines: u32,
    /// Scanlines refused with a [`ScanError`].
    pub rejected: u32,
    /// Echo runs detected (at most [`MAX_RUNS_PER_BEAM`] per scanline).
    pub echoes: u32,
    /// Features handed to, and accepted by, the sink.
    pub features: u32,
    /// Features the sink refused (it was full): lost.
    pub sink_full: u32,
    /// New clusters not opened because the table was full (their run was ignored).
    pub clusters_dropped: u32,
    /// Clusters closed without a feature: too few beams, too little confidence, or a
    /// degenerate fit.
    pub clusters_discarded: u32,
    /// One-beam echoes let out as faint sightings ([`Feature::faint`]).
    pub faint: u32,
    /// Sweep breaks (direction reversal, bearing jump, time gap, pose jump) that closed every
    /// open cluster.
    pub sweep_breaks: u32,
    /// Echoes left out as a vehicle the host reports ([`known`]).
    pub vehicle_echoes: u32,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan(bins: &[u8]) -> Scanline<'_> {
        Scanline {
            time_ms: 0,
            bearing_rad: 0.0,
            step_rad: 0.03,
            range_m: 30.0,
            bins,
        }
    }

    #[test]
    fn bad_scanlines_are_refused_with_the_right_error() {
        let bins = [0u8; 600];
        let ok = scan(&bins[..100]);
        assert_eq!(ok.validate(), Ok(()));
        let nan_range = Scanline {
            range_m: f32::NAN,
            ..ok
        };
        assert_eq!(nan_range.validate(), Err(ScanError::NonFinite));
        let inf_bearing = Scanline {
            bearing_rad: f32::INFINITY,
            ..ok
        };
        assert_eq!(inf_bearing.validate(), Err(ScanError::NonFinite));
        assert_eq!(scan(&[]).validate(), Err(ScanError::NoBins));
        assert_eq!(scan(&bins[..513]).validate(), Err(ScanError::TooManyBins));
        assert_eq!(scan(&bins[..512]).validate(), Ok(()));
        for r in [0.4, 200.5, -1.0] {
            let s = Scanline { range_m: r, ..ok };
            assert_eq!(s.validate(), Err(ScanError::RangeOutOfRange), "{r}");
        }
        for st in [0.0, 0.5, -0.3] {
            let s = Scanline { step_rad: st, ..ok };
            assert_eq!(s.validate(), Err(ScanError::StepOutOfRange), "{st}");
        }
        assert_eq!(
            Scanline {
                step_rad: -0.03,
                ..ok
            }
            .validate(),
            Ok(())
        );
    }

    #[test]
    fn bad_poses_are_refused() {
        let good = Pose {
            position: Vec2::new(1.0e4, -3.0),
            heading: 7.0,
        };
        assert_eq!(good.validate(), Ok(()));
        for p in [
            Pose {
                position: Vec2::new(f32::NAN, 0.0),
                ..good
            },
            Pose {
                heading: f32::NEG_INFINITY,
                ..good
            },
            Pose {
                position: Vec2::new(0.0, 2.0e5),
                ..good
            },
        ] {
            assert_eq!(p.validate(), Err(ScanError::BadPose));
        }
    }

    #[test]
    fn default_config_is_valid_and_each_check_bites() {
        let d = ExtractorConfig::default();
        assert_eq!(d.validate(), Ok(()));
        let cases: [(ExtractorConfig, ConfigError); 10] = [
            (
                ExtractorConfig {
                    peak_min: 50.0,
                    ..d
                },
                ConfigError::Threshold,
            ),
            (
                ExtractorConfig {
                    gain_per_m: f32::NAN,
                    ..d
                },
                ConfigError::Gain,
            ),
            (
                ExtractorConfig {
                    blanking_m: -1.0,
                    ..d
                },
                ConfigError::Blanking,
            ),
            (
                ExtractorConfig {
                    min_run_bins: 0,
                    ..d
                },
                ConfigError::Run,
            ),
            (
                ExtractorConfig {
                    max_missed_beams: 4,
                    ..d
                },
                ConfigError::Capacity,
            ),
            (
                ExtractorConfig {
                    cluster_gap_m: 0.0,
                    ..d
                },
                ConfigError::ClusterGap,
            ),
            (
                ExtractorConfig {
                    min_confidence: 1.5,
                    ..d
                },
                ConfigError::Acceptance,
            ),
            (
                ExtractorConfig {
                    elongation: 1.0,
                    ..d
                },
                ConfigError::Fit,
            ),
            (
                ExtractorConfig { max_gap_ms: 0, ..d },
                ConfigError::Continuity,
            ),
            (
                ExtractorConfig {
                    head_offset: Vec2::new(0.0, f32::INFINITY),
                    ..d
                },
                ConfigError::HeadOffset,
            ),
        ];
        for (cfg, want) in cases {
            assert_eq!(cfg.validate(), Err(want));
        }
        // One run per beam leaves room for 4 beams of memory.
        let one = ExtractorConfig {
            runs_per_beam: 1,
            max_missed_beams: 3,
            ..d
        };
        assert_eq!(one.validate(), Ok(()));
    }

    #[test]
    fn features_convert_to_planner_shapes() {
        let c = Feature {
            center: Vec2::new(3.0, 4.0),
            radius: 1.5,
            kind: FeatureKind::Circle { radius: 1.5 },
            confidence: 0.9,
            time_ms: 10,
            beams: 7,
            runs_on: false,
            faint: false,
        };
        let s = c.to_shape().unwrap();
        assert!((s.signed_distance(Vec2::new(3.0, 0.0)) - 2.5).abs() < 1e-5);
        let r = Feature {
            kind: FeatureKind::Rectangle {
                half: Vec2::new(2.0, 0.25),
                angle: 0.0,
            },
            ..c
        };
        assert!(r.is_rectangle());
        let s = r.to_shape().unwrap();
        assert!((s.signed_distance(Vec2::new(3.0, 5.25)) - 1.0).abs() < 1e-5);
        let bad = Feature {
            kind: FeatureKind::Circle { radius: 0.0 },
            ..c
        };
        assert_eq!(bad.to_shape(), Err(ShapeError::SizeOutOfRange));
    }
}
