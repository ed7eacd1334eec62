//! The extractor: sweep bookkeeping around detection, clustering and fit.
//!
//! Per accepted scanline:
//! 1. compare with the previous ping: the bearing advance `d = wrap(bearing − last)` must be
//!    between ½ and `max_missed_beams + 1.5` steps, in the same direction as before, with time
//!    moving forward by at most `max_gap_ms` and the sensor by at most `max_pose_jump_m`;
//!    otherwise the sweep is broken and every open cluster is closed first. A continuous 360°
//!    scan is not a break: bearings compare modulo 2π, so an obstacle across the bow or the stern
//!    stays one cluster (`max_span_rad` bounds how far a cluster can reach);
//! 2. advance the beam number by `round(|d| / step)` (missing pings count as missed beams) and
//!    close clusters that have now missed more than `max_missed_beams` beams;
//! 3. detect runs, put each leading edge in the world frame with this ping's pose, and assign
//!    it to the cluster table;
//! 4. close clusters that missed this beam one too many times, or that span `max_span_rad`.
//!
//! A closed cluster leaves as a [`Feature`] if it has `min_beams` hits and `min_confidence`,
//! or as a *glimpse* if it is one beam of a strong echo ([`GLIMPSE_INTENSITY`]) or one beam
//! the neighbouring beam returned a weaker echo beside (*seconded*: not one ping, so not a
//! spurious target); any other beam of one hit at least [`FAINT_INTENSITY`] leaves as a
//! *faint* sighting, for the tracker's pairs.

use crate::math::{cos, sin, wrap_angle, Vec2};

use super::cluster::{Assign, Cluster, Table};
use super::detect::detect;
use super::evidence::{Beam, EvidenceMap};
use super::fit::Hit;
use super::known::KnownVehicles;
use super::{
    ConfigError, Counters, ExtractorConfig, Feature, Pose, ScanError, Scanline, FAINT_ALONE_M,
    MAX_RUNS_PER_BEAM,
};

/// Mean intensity from which a cluster of one beam leaves as a *glimpse*: a feature of one
/// beam and confidence 0, which the tracker takes only as the second look at a target seen
/// once (`crate::guidance::tracks`, "Glimpses"), never as a new obstacle. Another VideoRay,
/// narrower than the 3° beam, is on one 1.8° ping as often as on two: two meeting head-on
/// each saw the other on two beams at 26 m, and a sweep later, at 8 m, on one (a return of
/// 210, saturating at 250), so neither ever rated the other (generated head-on seed 93). A
/// spurious target, which is one ping too, returns less (the simulated ones at most 176;
/// speckle is one bin, shorter than a run). A weaker hit is a glimpse when a neighbouring
/// beam returned an echo beside it, too weak to be a hit (the map believes such a pair,
/// `EvidenceMap::believe`): head-on seed 111 saw the other vehicle so a sweep after its
/// first sighting, a hit of mean 182 and a 114 beside it.
pub const GLIMPSE_INTENSITY: f32 = 200.0;

/// Mean intensity from which any other one-beam echo leaves as a *faint* sighting
/// ([`Feature::faint`]), which the tracker believes only as one of two on a collision course
/// (`crate::guidance::faint`): another VideoRay at 10–18 m returned 131–212 on its one beam,
/// most above this; the simulated spurious targets return at most 176 (0.4–0.8 of a surface
/// echo's strength, spread evenly: a floor of 150 leaves about a third of them). Without the
/// floor, pairs of them made a phantom mover every 20–50 s under way. Ahead, lower:
/// [`FAINT_AHEAD_INTENSITY`].
pub const FAINT_INTENSITY: f32 = 150.0;

/// The faint floor within [`FAINT_AHEAD_RAD`] of the bow, where a vehicle met head-on is seen
/// and closes at twice the cruise: another VideoRay 10–18 m ahead returned 100–210 on its one
/// beam, and in the bench's head-on contacts most of the first two sightings were 110–150
/// (`hil echoes`), so neither vehicle believed the other until it was on two beams 3–4 m off.
/// Three quarters of the spurious targets clear this; a quarter of the bearings keeps the
/// phantoms they pair into few (`crate::guidance::faint`, "Ahead").
pub const FAINT_AHEAD_INTENSITY: f32 = 110.0;

/// Half-width of the sector ahead with the lower faint floor, rad (45°).
pub const FAINT_AHEAD_RAD: f32 = core::f32::consts::FRAC_PI_4;

/// A faint sighting with a believed map cell more than this and at most
/// [`super::FAINT_ALONE_M`] from it is structure's edge ([`Feature::runs_on`]), m: nearer is
/// the cell its own echo made (one echo is believed within the map's `near_m`).
pub const FAINT_OWN_M: f32 = 1.0;

/// Whether a one-beam echo of mean intensity `mean` at `center` is bright enough for a faint
/// sighting: [`FAINT_INTENSITY`], or [`FAINT_AHEAD_INTENSITY`] within [`FAINT_AHEAD_RAD`] of
/// the bow as of the latest ping `last`. (Not inlined: `close_where` has a copy per caller.)
#[inline(never)]
fn faint_enough(mean: f32, center: Vec2, last: Option<&LastPing>) -> bool {
    mean >= FAINT_INTENSITY
        || (mean >= FAINT_AHEAD_INTENSITY
            && last.is_some_and(|l| {
                let d = center - l.sensor;
                let along = d.dot(Vec2::new(cos(l.heading), sin(l.heading)));
                let c = cos(FAINT_AHEAD_RAD);
                along > 0.0 && along * along >= c * c * d.norm2()
            }))
}

/// Whether bit `k` of a per-echo mask is set (none beyond the eighth).
fn flagged(mask: u8, k: usize) -> bool {
    k < 8 && mask & (1 << k) != 0
}

/// What the extractor remembers of the previous ping.
#[derive(Clone, Copy, Debug, PartialEq)]
struct LastPing {
    /// Wrapped head bearing, rad.
    bearing: f32,
    time_ms: u64,
    /// Sensor position, world frame, m.
    sensor: Vec2,
    /// The bow's direction, world frame, rad.
    heading: f32,
    /// Sweep direction: +1 counter-clockwise, −1 clockwise, 0 not yet known.
    dir: i8,
    /// Its echoes' leading edges, world frame, m (the first `echo_count`).
    echoes: [Vec2; MAX_RUNS_PER_BEAM],
    echo_count: usize,
}

/// Sonar scanlines → obstacle features. Owns a fixed-capacity cluster table; no heap, O(bins)
/// per scanline, never blocks (features go to a caller-supplied sink).
#[derive(Clone, Debug, PartialEq)]
pub struct Extractor {
    cfg: ExtractorConfig,
    table: Table,
    last: Option<LastPing>,
    /// Beam number of the last accepted ping (wraps after 2³² pings, years of pinging).
    beam: u32,
    counters: Counters,
    /// The vehicles the host reports: their echoes are neither features nor map hits.
    known: KnownVehicles,
}

impl Extractor {
    /// An extractor with a checked configuration.
    pub fn new(cfg: ExtractorConfig) -> Result<Self, ConfigError> {
        cfg.validate()?;
        Ok(Extractor {
            cfg,
            table: Table::new(),
            last: None,
            beam: 0,
            counters: Counters::default(),
            known: KnownVehicles::default(),
        })
    }

    /// Vehicle `id` (hull radius `radius`, m) was reported at `center`, moving at `velocity`,
    /// at `time_ms`: its echoes are left out from now on ([`KnownVehicles`]).
    pub fn report_vehicle(
        &mut self,
        id: u16,
        center: Vec2,
        radius: f32,
        velocity: Vec2,
        time_ms: u64,
    ) {
        self.known.report(id, center, radius, velocity, time_ms);
    }

    /// Its configuration.
    pub fn config(&self) -> &ExtractorConfig {
        &self.cfg
    }

    /// What it has done so far.
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// Clusters currently open (waiting for more beams).
    pub fn open_clusters(&self) -> usize {
        self.table.len()
    }

    /// Processes one scanline taken at `pose`. Features completed by it are handed to `out`,
    /// which returns `false` when it cannot take one (the feature is then counted in
    /// [`Counters::sink_full`] and lost). Returns how many features `out` accepted.
    ///
    /// A refused scanline (see [`ScanError`]) changes nothing but [`Counters::rejected`].
    pub fn push_scanline(
        &mut self,
        scan: &Scanline<'_>,
        pose: Pose,
        out: &mut impl FnMut(Feature) -> bool,
    ) -> Result<usize, ScanError> {
        self.push_scanline_mapped(scan, pose, None, out)
    }

    /// [`Extractor::push_scanline`], also putting the ping into `map` (the same detection
    /// feeds both, so a scanline is thresholded once). The map follows the vehicle, and marks
    /// each feature whose structure runs on beyond it ([`Feature::runs_on`]).
    pub fn push_scanline_mapped(
        &mut self,
        scan: &Scanline<'_>,
        pose: Pose,
        map: Option<&EvidenceMap>,
        out: &mut impl FnMut(Feature) -> bool,
    ) -> Result<usize, ScanError> {
        let out = &mut |mut f: Feature| {
            f.runs_on = map.is_some_and(|m| {
                m.runs_on(f.center, f.radius)
                    || (f.faint && m.occupied_between(f.center, FAINT_OWN_M, FAINT_ALONE_M))
            });
            out(f)
        };
        if let Err(e) = scan.validate().and_then(|()| pose.validate()) {
            self.counters.rejected = self.counters.rejected.saturating_add(1);
            return Err(e);
        }
        self.counters.scanlines = self.counters.scanlines.saturating_add(1);
        let step = scan.step_rad.abs();
        let bearing = wrap_angle(scan.bearing_rad);
        let (ch, sh) = (cos(pose.heading), sin(pose.heading));
        let sensor = pose.position + self.cfg.head_offset.rotate_cs(ch, sh);
        let mut emitted = 0;

        // 1. Continuity with the previous ping.
        let mut dir = 0i8;
        let mut advance = 1u32;
        // The previous beam's echoes, if it is the neighbour of this one in the same sweep.
        let mut neighbour: Option<LastPing> = None;
        if let Some(last) = self.last {
            let d = wrap_angle(bearing - last.bearing);
            let ad = d.abs();
            dir = if d >= 0.0 { 1 } else { -1 };
            let max_adj = (f32::from(self.cfg.max_missed_beams) + 1.5) * step;
            let same = ad < 0.5 * step;
            let broken = same
                || ad > max_adj
                || (last.dir != 0 && dir != last.dir)
                || scan.time_ms < last.time_ms
                || scan.time_ms.saturating_sub(last.time_ms) > u64::from(self.cfg.max_gap_ms)
                || (sensor - last.sensor).norm() > self.cfg.max_pose_jump_m;
            if broken {
                self.counters.sweep_breaks = self.counters.sweep_breaks.saturating_add(1);
                emitted += self.close_where(|_| true, out);
                // After a stall or a jump the direction is unknown; after a reversal it is `d`'s.
                if same || ad > max_adj {
                    dir = 0;
                }
            } else {
                // ½ ≤ |d|/step ≤ max_missed + 1.5, so this is 1 ..= max_missed + 2.
                advance = libm::roundf(ad / step).max(1.0) as u32;
                self.table.advance(ad);
                neighbour = Some(last);
            }
        }
        let beam = self.beam.wrapping_add(advance);
        self.beam = beam;

        // 2. Clusters that missed too many beams while pings were missing cannot continue.
        let missed = u32::from(self.cfg.max_missed_beams);
        emitted += self.close_where(|c| c.since(beam) > missed.saturating_add(1), out);

        // 3. Runs → world-frame hits → clusters.
        let echoes = detect(scan, &self.cfg);
        let look = Vec2::from_angle(pose.heading + bearing);
        let mut here = LastPing {
            bearing,
            time_ms: scan.time_ms,
            sensor,
            heading: pose.heading,
            dir,
            echoes: [Vec2::ZERO; MAX_RUNS_PER_BEAM],
            echo_count: 0,
        };
        for (slot, e) in here.echoes.iter_mut().zip(echoes.iter()) {
            *slot = sensor + look * e.range_m;
            here.echo_count += 1;
        }
        self.last = Some(here);
        // Bit k: echo k is a vehicle the host reports, not structure.
        let vehicle = here
            .echoes
            .iter()
            .take(here.echo_count)
            .enumerate()
            .filter(|&(_, p)| self.known.covers(*p, scan.time_ms))
            .fold(0u8, |m, (k, _)| m | 1u8.checked_shl(k as u32).unwrap_or(0));
        self.counters.vehicle_echoes = self
            .counters
            .vehicle_echoes
            .saturating_add(vehicle.count_ones());
        let strong = crate::math::max(self.cfg.peak_min, self.cfg.feature_peak_min);
        // An echo the neighbouring beam also returned (within the cluster gap), weak or strong:
        // the second look a far cell needs, and what makes a one-beam cluster a glimpse — a
        // false target or a fish is one ping, a surface or a vehicle spans beams. `partner[k]`
        // is echo k's on the previous beam.
        let gap2 = self.cfg.cluster_gap_m * self.cfg.cluster_gap_m;
        let mut partner = [None; MAX_RUNS_PER_BEAM];
        if let Some(prev) = neighbour {
            let before = prev.echoes.get(..prev.echo_count).unwrap_or(&[]);
            for (k, (p, slot)) in here.echoes.iter().zip(partner.iter_mut()).enumerate() {
                if k < here.echo_count && !flagged(vehicle, k) {
                    *slot = before.iter().find(|q| (**q - *p).norm2() <= gap2).copied();
                }
            }
        }
        let seconded = partner
            .iter()
            .enumerate()
            .filter(|(_, q)| q.is_some())
            .fold(0u8, |m, (k, _)| m | 1u8.checked_shl(k as u32).unwrap_or(0));
        if let Some(map) = map {
            // Both ends of a seconded pair are believed.
            partner.iter().flatten().for_each(|q| map.believe(*q));
            // A weak echo is a wall at a grazing angle only if the neighbouring beam saw it too;
            // alone it may be a false target, and it is left out.
            let mut ranges: heapless::Vec<f32, MAX_RUNS_PER_BEAM> = heapless::Vec::new();
            let mut kept_seconded = 0u8;
            let mut kept_vehicle = 0u8;
            for (k, e) in echoes.iter().enumerate() {
                let twice = flagged(seconded, k);
                let known = flagged(vehicle, k);
                if e.peak < strong && !twice && !known {
                    continue;
                }
                if ranges.push(e.range_m).is_err() {
                    break;
                }
                let bit = 1u8
                    .checked_shl(ranges.len().saturating_sub(1) as u32)
                    .unwrap_or(0);
                if twice {
                    kept_seconded |= bit;
                }
                if known {
                    kept_vehicle |= bit;
                }
            }
            map.follow(pose.position);
            map.observe(&Beam {
                origin: sensor,
                look,
                range_m: scan.range_m,
                blank_m: self.cfg.blanking_m,
                echoes: &ranges,
                seconded: kept_seconded,
                vehicles: kept_vehicle,
            });
        }
        // Pushed, not collected: heapless' `collect` panics on overflow.
        let mut hits: heapless::Vec<Hit, MAX_RUNS_PER_BEAM> = heapless::Vec::new();
        for (_, e) in echoes
            .iter()
            .enumerate()
            .filter(|&(k, e)| e.peak >= strong && !flagged(vehicle, k))
        {
            let _ = hits.push(Hit {
                point: sensor + look * e.range_m,
                look,
                range: e.range_m,
                step,
                intensity: e.mean,
            });
        }
        self.counters.echoes = self.counters.echoes.saturating_add(hits.len() as u32);
        let fates = self
            .table
            .assign_beam(&hits, beam, scan.time_ms, self.cfg.cluster_gap_m);
        // Both ends of a seconded pair mark their clusters (this beam's hit, the previous
        // beam's, whichever is strong enough to be one).
        for (e, q) in echoes.iter().zip(partner) {
            if let (Some(q), Some(prev)) = (q, neighbour) {
                self.table.second(beam, e.range_m);
                self.table
                    .second(beam.wrapping_sub(advance), (q - prev.sensor).norm());
            }
        }
        let dropped = fates.iter().filter(|a| **a == Assign::Full).count() as u32;
        self.counters.clusters_dropped = self.counters.clusters_dropped.saturating_add(dropped);

        // 4. Clusters that ended on this beam, or grew too wide.
        let max_span = self.cfg.max_span_rad;
        emitted += self.close_where(|c| c.since(beam) > missed || c.span_rad >= max_span, out);
        Ok(emitted)
    }

    /// Closes every open cluster now (e.g. when the sonar stops), emitting those that qualify;
    /// the next scanline starts a new sweep. Returns how many features `out` accepted.
    pub fn flush(&mut self, out: &mut impl FnMut(Feature) -> bool) -> usize {
        self.last = None;
        self.close_where(|_| true, out)
    }

    /// Forgets every open cluster and the previous ping, emitting nothing; counters are kept.
    pub fn reset(&mut self) {
        self.table.clear();
        self.last = None;
    }

    /// Closes the clusters for which `close` holds; fits and emits those that qualify.
    fn close_where(
        &mut self,
        close: impl Fn(&Cluster) -> bool,
        out: &mut impl FnMut(Feature) -> bool,
    ) -> usize {
        let Extractor {
            cfg,
            table,
            counters,
            last,
            ..
        } = self;
        let mut accepted = 0;
        table.close_where(close, |c| {
            let hits = c.moments.hits();
            let single = hits == 1;
            let mean = c.moments.mean_intensity();
            let glimpse = single && (c.seconded || mean >= GLIMPSE_INTENSITY);
            let candidate = single && !glimpse && mean >= FAINT_AHEAD_INTENSITY;
            // A one-beam echo not a glimpse but bright enough (ahead, less) leaves as a faint
            // sighting.
            let faint = |f: &Feature| candidate && faint_enough(mean, f.center, last.as_ref());
            let feature = (hits >= u32::from(cfg.min_beams) || glimpse || candidate)
                .then(|| c.moments.fit(c.spanned(), c.time_ms, cfg))
                .flatten()
                .filter(|f| f.confidence >= cfg.min_confidence || glimpse || faint(f))
                .map(|mut f| {
                    f.faint = faint(&f) && f.confidence < cfg.min_confidence;
                    f
                });
            match feature {
                Some(f) if out(f) => {
                    if f.faint {
                        counters.faint = counters.faint.saturating_add(1);
                    } else {
                        counters.features = counters.features.saturating_add(1);
                        accepted += 1;
                    }
                }
                Some(_) => counters.sink_full = counters.sink_full.saturating_add(1),
                None => counters.clusters_discarded = counters.clusters_discarded.saturating_add(1),
            }
        });
        accepted
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{sqrt, XorShift32, PI};
    use crate::sonar::{FeatureKind, MAX_BINS};
    use heapless::Vec as HVec;
    use proptest::prelude::*;

    /// Features collected in a test.
    type Found = HVec<Feature, 64>;

    /// What the sonar sees: circles and wall segments.
    #[derive(Clone, Copy)]
    enum Obj {
        Circle(Vec2, f32),
        Wall(Vec2, Vec2),
    }

    /// Range along the ray `s + t·u` to the nearest object, if any.
    fn cast(scene: &[Obj], s: Vec2, u: Vec2) -> Option<f32> {
        let mut best: Option<f32> = None;
        for o in scene {
            let t = match *o {
                Obj::Circle(c, r) => {
                    let to_c = c - s;
                    let uc = u.dot(to_c);
                    let disc = uc * uc - to_c.norm2() + r * r;
                    (disc >= 0.0 && uc - sqrt(disc) > 0.0).then(|| uc - sqrt(disc))
                }
                Obj::Wall(a, b) => {
                    // s + t·u = a + w·(b − a), 0 ≤ w ≤ 1, t > 0.
                    let e = b - a;
                    let den = u.cross(e);
                    if den.abs() < 1e-9 {
                        None
                    } else {
                        let t = (a - s).cross(e) / den;
                        let w = (a - s).cross(u) / den;
                        (t > 0.0 && (0.0..=1.0).contains(&w)).then_some(t)
                    }
                }
            };
            if let Some(t) = t {
                best = Some(best.map_or(t, |b: f32| crate::math::min_num(b, t)));
            }
        }
        best
    }

    /// Synthetic sonar: background noise, speckle, an echo 0.3 m deep at the nearest surface
    /// whose raw level falls as 1/(1 + 0.04 r) (the default gain restores ~200), then shadow.
    struct Sonar {
        rng: XorShift32,
        noise: u8,
        speckle_per_mille: u32,
    }

    impl Sonar {
        fn new(seed: u32, noise: u8, speckle_per_mille: u32) -> Self {
            Sonar {
                rng: XorShift32::new(seed),
                noise,
                speckle_per_mille,
            }
        }

        fn ping(&mut self, scene: &[Obj], s: Vec2, u: Vec2, range: f32, bins: &mut [u8]) {
            let n = bins.len();
            let dr = range / n as f32;
            let hit = cast(scene, s, u);
            for (i, b) in bins.iter_mut().enumerate() {
                let (r0, r1) = (i as f32 * dr, (i + 1) as f32 * dr);
                let mut v = u32::from(self.noise) * (self.rng.next_u32() % 256) / 256;
                if self.rng.next_u32() % 1000 < self.speckle_per_mille {
                    v = 100 + self.rng.next_u32() % 156;
                }
                if let Some(t) = hit {
                    if r1 > t && r0 < t + 0.3 {
                        v = (200.0 / (1.0 + 0.04 * r0)) as u32;
                    } else if r0 >= t + 0.3 {
                        v /= 4; // acoustic shadow
                    }
                }
                *b = v.min(255) as u8;
            }
        }
    }

    /// The vehicle's track: constant speed along a slowly turning heading.
    #[derive(Clone, Copy)]
    struct Track {
        start: Vec2,
        heading: f32,
        speed: f32,
        yaw_rate: f32,
    }

    impl Track {
        fn pose(&self, t_s: f32) -> Pose {
            // Integrate the turning path in small steps (the test's ground truth).
            let mut p = self.start;
            let mut h = self.heading;
            let n = (t_s / 0.01) as usize;
            for _ in 0..n {
                p += Vec2::from_angle(h) * (self.speed * 0.01);
                h += self.yaw_rate * 0.01;
            }
            Pose {
                position: p,
                heading: h,
            }
        }
    }

    const STILL: Track = Track {
        start: Vec2::ZERO,
        heading: 0.0,
        speed: 0.0,
        yaw_rate: 0.0,
    };

    /// How the head scans in a test: a continuous scan from `bearing0`, `step` rad per ping
    /// (the sign is the direction), `dt_ms` apart, `bins` bins over `range` metres.
    #[derive(Clone, Copy)]
    struct Head {
        bearing0: f32,
        step: f32,
        pings: usize,
        dt_ms: u64,
        range: f32,
        bins: usize,
    }

    /// One revolution at 1.8° per ping, 60 ms apart (12 s), 300 bins over 30 m, from the stern
    /// round (so obstacles ahead and abeam are mid-sweep).
    const SCAN: Head = Head {
        bearing0: -PI,
        step: PI / 100.0,
        pings: 200,
        dt_ms: 60,
        range: 30.0,
        bins: 300,
    };

    /// Runs the scan over the scene from the track, then flushes; returns the features.
    fn sweep(
        ex: &mut Extractor,
        sonar: &mut Sonar,
        scene: &[Obj],
        track: Track,
        head: Head,
    ) -> Found {
        let mut found = Found::new();
        let mut bins = [0u8; MAX_BINS];
        let nbins = head.bins.min(MAX_BINS);
        for k in 0..head.pings {
            let t_ms = k as u64 * head.dt_ms;
            let pose = track.pose(t_ms as f32 / 1000.0);
            let bearing = wrap_angle(head.bearing0 + k as f32 * head.step);
            let (c, s) = (cos(pose.heading), sin(pose.heading));
            let sensor = pose.position + ex.config().head_offset.rotate_cs(c, s);
            let u = Vec2::from_angle(pose.heading + bearing);
            sonar.ping(scene, sensor, u, head.range, &mut bins[..nbins]);
            let scan = Scanline {
                time_ms: t_ms,
                bearing_rad: bearing,
                step_rad: head.step,
                range_m: head.range,
                bins: &bins[..nbins],
            };
            ex.push_scanline(&scan, pose, &mut |f| keep(&mut found, f))
                .unwrap();
        }
        ex.flush(&mut |f| keep(&mut found, f));
        found
    }

    /// Collects a feature; a glimpse (one beam: speckle makes them too, and only the tracker's
    /// second look at a target takes one) is accepted and left out.
    fn keep(found: &mut Found, f: Feature) -> bool {
        f.beams == 1 || found.push(f).is_ok()
    }

    fn circle_of(f: &Feature) -> f32 {
        match f.kind {
            FeatureKind::Circle { radius } => radius,
            FeatureKind::Rectangle { .. } => panic!("expected a circle, got {f:?}"),
        }
    }

    const STEP: f32 = SCAN.step;
    const FULL: usize = SCAN.pings;

    #[test]
    fn a_face_swept_once_from_afar_is_believed_along_its_length() {
        // A 4 m face across the +x axis at 12 m (beyond the map's near_m): each cell is hit by
        // one or two beams in one sweep. Neighbouring beams second each other's echoes, so the
        // face is believed along its length after a single sweep; an echo only one beam
        // returns (a false target) is not.
        let scene = [Obj::Wall(Vec2::new(12.0, -2.0), Vec2::new(12.0, 2.0))];
        let map = EvidenceMap::new(crate::sonar::EvidenceConfig::default()).unwrap();
        let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
        let mut sonar = Sonar::new(1, 30, 2);
        let mut bins = [0u8; MAX_BINS];
        let head = SCAN;
        for k in 0..head.pings {
            let bearing = wrap_angle(head.bearing0 + k as f32 * head.step);
            let u = Vec2::from_angle(bearing);
            sonar.ping(&scene, Vec2::ZERO, u, head.range, &mut bins[..head.bins]);
            let scan = Scanline {
                time_ms: k as u64 * head.dt_ms,
                bearing_rad: bearing,
                step_rad: head.step,
                range_m: head.range,
                bins: &bins[..head.bins],
            };
            let pose = STILL.pose(0.0);
            ex.push_scanline_mapped(&scan, pose, Some(&map), &mut |_| true)
                .unwrap();
        }
        let w = map.window().unwrap();
        let face_rows = (-4..4).filter(|&j| map.is_occupied(w, 24, j)).count();
        // (Without the neighbour rule: 1 of 8.)
        assert!(
            face_rows >= 6,
            "{face_rows} of 8 cells of the face believed"
        );
        // One ping's echo at 14 m on a bearing no neighbour saw.
        let mut lone = [0u8; 300];
        lone[140..143].fill(220);
        let quiet = [0u8; 300];
        let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
        for (k, bins) in [&quiet, &lone, &quiet].into_iter().enumerate() {
            let sl = Scanline {
                time_ms: 60 * k as u64,
                bearing_rad: 1.0 + k as f32 * head.step,
                step_rad: head.step,
                range_m: 30.0,
                bins,
            };
            ex.push_scanline_mapped(&sl, STILL.pose(0.0), Some(&map), &mut |_| true)
                .unwrap();
        }
        let p = Vec2::from_angle(1.0 + head.step) * 14.05;
        let cell = |x: f32| libm::floorf(x / 0.5) as i32;
        assert!(
            !map.is_occupied(w, cell(p.x), cell(p.y)),
            "a lone echo is not believed"
        );
    }

    /// The `k`-th of a run of 30 m scanlines one step apart, 60 ms apart, from the bow.
    fn nth_line(k: usize, bins: &[u8]) -> Scanline<'_> {
        Scanline {
            time_ms: 60 * k as u64,
            bearing_rad: k as f32 * SCAN.step,
            step_rad: SCAN.step,
            range_m: 30.0,
            bins,
        }
    }

    #[test]
    fn a_weak_echo_feeds_the_map_when_two_beams_agree_and_never_a_feature() {
        // At 4 m (within the map's near_m, gain 1.16) a raw 95 is 110 compensated: above
        // peak_min (100), below feature_peak_min (120) — a wall met at a grazing angle.
        let mut weak = [0u8; 300];
        weak[40..43].fill(95);
        let quiet = [0u8; 300];
        let step = SCAN.step;
        let fly = |lines: &[&[u8; 300]]| {
            let map = EvidenceMap::new(crate::sonar::EvidenceConfig::default()).unwrap();
            let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
            let mut features = 0;
            for (k, bins) in lines.iter().enumerate() {
                let sl = nth_line(k, &bins[..]);
                let mut count = |_| {
                    features += 1;
                    true
                };
                ex.push_scanline_mapped(&sl, STILL.pose(0.0), Some(&map), &mut count)
                    .unwrap();
            }
            let mut count = |_| {
                features += 1;
                true
            };
            ex.flush(&mut count);
            let w = map.window().unwrap();
            let p = Vec2::from_angle(step) * 4.05;
            let cell = |x: f32| libm::floorf(x / 0.5) as i32;
            (map.is_occupied(w, cell(p.x), cell(p.y)), features)
        };
        assert_eq!(
            fly(&[&quiet, &weak, &quiet]),
            (false, 0),
            "alone: maybe false"
        );
        assert_eq!(
            fly(&[&weak, &weak, &quiet]),
            (true, 0),
            "two beams: a surface"
        );
    }

    #[test]
    fn a_strong_echo_on_one_beam_leaves_as_a_glimpse() {
        // Another VideoRay at 8 m on one ping (head-on seed 93: a return of 210, saturating):
        // a glimpse, of one beam and confidence 0, for the tracker. A weaker one-ping echo
        // leaves as a faint sighting (it may be a spurious target: `Feature::faint`) — ahead,
        // a weaker one too — and a weaker one still leaves nothing.
        // `off`: the head's bearing from the bow.
        let fly_off = |level: u8, off: f32| {
            let mut bins = [0u8; 300];
            bins[80..83].fill(level);
            let quiet = [0u8; 300];
            let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
            let mut found = heapless::Vec::<Feature, 4>::new();
            for (k, b) in [&quiet, &bins, &quiet, &quiet].iter().enumerate() {
                let mut sl = nth_line(k, &b[..]);
                sl.bearing_rad += off;
                ex.push_scanline(&sl, STILL.pose(0.0), &mut |f| found.push(f).is_ok())
                    .unwrap();
            }
            ex.flush(&mut |f| found.push(f).is_ok());
            found
        };
        let fly = |level| fly_off(level, 0.0);
        let strong = fly(200);
        assert_eq!(strong.len(), 1, "{strong:?}");
        assert!(strong
            .iter()
            .all(|f| f.beams == 1 && f.confidence == 0.0 && !f.faint));
        assert!(strong.iter().all(|f| (f.center.norm() - 8.0).abs() < 0.5));
        // At 8 m (gain 1.32): a raw 120 is 158, a raw 95 is 125, a raw 80 is 106.
        let faint =
            |found: &[Feature]| found.len() == 1 && found.iter().all(|f| f.beams == 1 && f.faint);
        assert!(faint(&fly(120)) && faint(&fly(95)));
        assert!(fly(80).is_empty());
        // Astern 125 is not enough, nor 60° off the bow; 40° off it is.
        assert!(faint(&fly_off(120, PI - 0.1)));
        assert!(fly_off(95, PI - 0.1).is_empty());
        assert!(fly_off(95, 60f32.to_radians()).is_empty());
        assert!(faint(&fly_off(95, -40f32.to_radians())));
    }

    #[test]
    fn a_hit_the_neighbouring_beam_seconds_with_a_weak_echo_leaves_as_a_glimpse() {
        // At 8 m (gain 1.32): a raw 120 is a hit (158), too weak for a glimpse alone; a raw 80
        // beside it (106) is an echo but no hit. Another VideoRay at 13 m was seen so, a sweep
        // after its first sighting (generated head-on seed 111): one beam, but not one ping.
        let fly = |lines: &[u8]| {
            let mut found = heapless::Vec::<Feature, 4>::new();
            let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
            for (k, &level) in lines.iter().enumerate() {
                let mut bins = [0u8; 300];
                bins[80..83].fill(level);
                let sl = nth_line(k, &bins[..]);
                ex.push_scanline(&sl, STILL.pose(0.0), &mut |f| found.push(f).is_ok())
                    .unwrap();
            }
            ex.flush(&mut |f| found.push(f).is_ok());
            found
        };
        for lines in [[0, 120, 80, 0, 0], [0, 80, 120, 0, 0]] {
            let found = fly(&lines);
            assert_eq!(found.len(), 1, "{lines:?}: {found:?}");
            assert!(found
                .iter()
                .all(|f| f.beams == 1 && f.confidence == 0.0 && !f.faint));
        }
        // The weak echo a beam further off seconds nothing: the hit is only faint.
        assert!(fly(&[0, 120, 0, 80, 0]).iter().all(|f| f.faint));
    }

    #[test]
    fn one_circle_from_a_moving_turning_vehicle() {
        // 1 m/s, turning 1°/s, 60 ms per ping: the vehicle moves 12 m and turns 12° in the sweep.
        let track = Track {
            start: Vec2::new(0.0, 0.0),
            heading: 0.3,
            speed: 1.0,
            yaw_rate: 0.0175,
        };
        let truth = Vec2::new(14.0, 9.0);
        let scene = [Obj::Circle(truth, 1.5)];
        let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
        let mut sonar = Sonar::new(1, 30, 2);
        let found = sweep(&mut ex, &mut sonar, &scene, track, SCAN);
        let strong: HVec<&Feature, 64> = found.iter().filter(|f| f.confidence > 0.5).collect();
        assert_eq!(strong.len(), 1, "{found:?}");
        let f = strong[0];
        let err = (f.center - truth).norm();
        let r = circle_of(f);
        // Measured: 0.03 m and 1.52 m from 10 beams.
        assert!(err < 0.15, "centre error {err} m: {f:?}");
        assert!((r - 1.5).abs() < 0.15, "radius {r}: {f:?}");
        assert!(f.beams >= 8, "{f:?}");
        assert!(f.to_shape().is_ok());
        let c = ex.counters();
        assert_eq!(c.scanlines, FULL as u32);
        assert_eq!((c.rejected, c.clusters_dropped, c.sink_full), (0, 0, 0));
    }

    #[test]
    fn ignoring_the_motion_would_misplace_it() {
        // The same obstacle, with the pose frozen at the sweep's start: the fit lands elsewhere,
        // which shows the per-ping pose is what keeps the centre right.
        let track = Track {
            start: Vec2::ZERO,
            heading: 0.3,
            speed: 1.0,
            yaw_rate: 0.0175,
        };
        let truth = Vec2::new(14.0, 9.0);
        let scene = [Obj::Circle(truth, 1.5)];
        let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
        let mut sonar = Sonar::new(1, 30, 0);
        let mut bins = [0u8; 300];
        let mut found = Found::new();
        let frozen = track.pose(0.0);
        for k in 0..FULL {
            let t_ms = k as u64 * 60;
            let pose = track.pose(t_ms as f32 / 1000.0);
            let bearing = wrap_angle(-PI + k as f32 * STEP);
            sonar.ping(
                &scene,
                pose.position,
                Vec2::from_angle(pose.heading + bearing),
                30.0,
                &mut bins,
            );
            let scan = Scanline {
                time_ms: t_ms,
                bearing_rad: bearing,
                step_rad: STEP,
                range_m: 30.0,
                bins: &bins,
            };
            ex.push_scanline(&scan, frozen, &mut |f| found.push(f).is_ok())
                .unwrap();
        }
        ex.flush(&mut |f| found.push(f).is_ok());
        let best = found
            .iter()
            .map(|f| (f.center - truth).norm())
            .fold(f32::INFINITY, f32::min);
        assert!(best > 1.0, "frozen pose still fits within {best} m");
    }

    #[test]
    fn two_obstacles_give_two_features() {
        let scene = [
            Obj::Circle(Vec2::new(10.0, 0.0), 1.0),
            Obj::Circle(Vec2::new(-6.0, 12.0), 2.0),
        ];
        let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
        let mut sonar = Sonar::new(7, 30, 2);
        let track = Track {
            heading: 1.0,
            speed: 0.5,
            ..STILL
        };
        let found = sweep(
            &mut ex,
            &mut sonar,
            &scene,
            track,
            Head { bins: 400, ..SCAN },
        );
        let strong: HVec<&Feature, 64> = found.iter().filter(|f| f.confidence > 0.5).collect();
        assert_eq!(strong.len(), 2, "{found:?}");
        for (c, r) in [(Vec2::new(10.0, 0.0), 1.0), (Vec2::new(-6.0, 12.0), 2.0)] {
            let f = strong
                .iter()
                .min_by(|a, b| (a.center - c).norm().total_cmp(&(b.center - c).norm()))
                .unwrap();
            let err = (f.center - c).norm();
            // Measured: 0.21 m / 1.19 m for the small one (6 beams), 0.02 m / 1.98 m.
            assert!(err < 0.3, "centre error {err} for {c:?}: {f:?}");
            assert!((circle_of(f) - r).abs() < 0.25, "radius for {r}: {f:?}");
        }
    }

    #[test]
    fn an_obstacle_across_the_stern_stays_one_feature_in_either_direction() {
        // Dead astern of a vehicle at rest: bearings about ±π, where the head angle wraps.
        let truth = Vec2::new(-12.0, 0.3);
        let scene = [Obj::Circle(truth, 1.5)];
        for step in [SCAN.step, -SCAN.step] {
            let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
            let head = Head {
                bearing0: 0.0,
                step,
                ..SCAN
            };
            let found = sweep(&mut ex, &mut Sonar::new(4, 30, 2), &scene, STILL, head);
            assert_eq!(found.len(), 1, "{found:?}");
            assert!((found[0].center - truth).norm() < 0.15, "{found:?}");
            assert_eq!(ex.counters().sweep_breaks, 0);
        }
    }

    #[test]
    fn a_wall_is_fitted_as_rectangles_on_its_face() {
        // A wall along y = 8 from x = −12 to 12; the vehicle drives along it at 1 m/s.
        let scene = [Obj::Wall(Vec2::new(-12.0, 8.0), Vec2::new(12.0, 8.0))];
        let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
        let mut sonar = Sonar::new(3, 30, 2);
        let track = Track {
            start: Vec2::new(-3.0, 0.0),
            speed: 1.0,
            ..STILL
        };
        let found = sweep(&mut ex, &mut sonar, &scene, track, SCAN);
        let strong: HVec<&Feature, 64> = found.iter().filter(|f| f.confidence > 0.5).collect();
        assert!(!strong.is_empty(), "{found:?}");
        let mut covered = 0.0;
        for f in &strong {
            let FeatureKind::Rectangle { half, angle } = f.kind else {
                panic!("wall piece not a rectangle: {f:?}")
            };
            assert!(
                angle.abs() < 0.05 || (angle.abs() - PI).abs() < 0.05,
                "{f:?}"
            );
            let face = f.center.y - half.y;
            assert!((face - 8.0).abs() < 0.15, "face at {face}: {f:?}");
            assert!(
                f.center.x - half.x > -12.5 && f.center.x + half.x < 12.5,
                "{f:?}"
            );
            covered += 2.0 * half.x;
        }
        // The wall is 24 m long; within 90° of its normal and 30 m most of it is seen.
        assert!(covered > 15.0, "covered {covered} m of 24: {strong:?}");
    }

    #[test]
    fn speckle_alone_gives_no_confident_feature() {
        // Heavy speckle (3 % of bins at 100–255, and bright background) over three sweeps, with
        // every closed cluster let out: chance chains of three runs do occur, but none of four.
        let cfg = ExtractorConfig {
            min_confidence: 0.0,
            ..ExtractorConfig::default()
        };
        let mut ex = Extractor::new(cfg).unwrap();
        let mut sonar = Sonar::new(42, 35, 30);
        let found = sweep(
            &mut ex,
            &mut sonar,
            &[],
            STILL,
            Head {
                pings: 3 * FULL,
                ..SCAN
            },
        );
        let worst = found.iter().map(|f| f.confidence).fold(0.0, f32::max);
        assert!(
            worst < 0.45,
            "speckle feature of confidence {worst}: {found:?}"
        );
        assert!(found.iter().all(|f| f.beams <= 3), "{found:?}");
        assert!(ex.counters().echoes > 300, "the speckle should make runs");
        // Realistic speckle (0.5 %) with the default configuration: nothing leaves but faint
        // sightings, which alone open nothing (`crate::guidance::faint`).
        let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
        let mut sonar = Sonar::new(43, 30, 5);
        let found = sweep(
            &mut ex,
            &mut sonar,
            &[],
            STILL,
            Head {
                pings: 3 * FULL,
                ..SCAN
            },
        );
        assert!(found.is_empty(), "{found:?}");
        let c = ex.counters();
        assert!(c.clusters_discarded.saturating_add(c.faint) > 0 || c.echoes == 0);
    }

    #[test]
    fn sector_scan_reversal_closes_clusters() {
        // Sweep 0 → 0.6 rad and back over a circle at bearing 0.3: two passes, two features,
        // none spanning the turn.
        let truth = Vec2::from_angle(0.3) * 12.0;
        let scene = [Obj::Circle(truth, 1.5)];
        let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
        let mut sonar = Sonar::new(9, 30, 0);
        let mut bins = [0u8; 300];
        let mut found = Found::new();
        let n = 20;
        for k in 0..(4 * n) {
            let phase = k % (2 * n);
            let bearing = if phase < n { phase } else { 2 * n - phase } as f32 * 0.03;
            sonar.ping(
                &scene,
                Vec2::ZERO,
                Vec2::from_angle(bearing),
                30.0,
                &mut bins,
            );
            let scan = Scanline {
                time_ms: k as u64 * 60,
                bearing_rad: bearing,
                step_rad: 0.03,
                range_m: 30.0,
                bins: &bins,
            };
            ex.push_scanline(&scan, Pose::default(), &mut |f| found.push(f).is_ok())
                .unwrap();
        }
        ex.flush(&mut |f| found.push(f).is_ok());
        assert_eq!(found.len(), 4, "{found:?}");
        assert!(ex.counters().sweep_breaks >= 3);
        for f in &found {
            assert!((f.center - truth).norm() < 0.15, "{f:?}");
        }
    }

    #[test]
    fn a_break_in_time_or_pose_splits_and_a_full_sink_counts() {
        let truth = Vec2::new(12.0, 0.0);
        let scene = [Obj::Circle(truth, 2.0)];
        let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
        let mut sonar = Sonar::new(5, 20, 0);
        let mut bins = [0u8; 300];
        let mut found = Found::new();
        let mut refused = 0;
        for k in -12i32..=12 {
            let bearing = k as f32 * 0.03;
            sonar.ping(
                &scene,
                Vec2::ZERO,
                Vec2::from_angle(bearing),
                30.0,
                &mut bins,
            );
            // A 5 s stall mid-obstacle.
            let t = (k + 12) as u64 * 60 + if k > 0 { 5_000 } else { 0 };
            let scan = Scanline {
                time_ms: t,
                bearing_rad: bearing,
                step_rad: 0.03,
                range_m: 30.0,
                bins: &bins,
            };
            // The sink accepts the first feature only.
            ex.push_scanline(&scan, Pose::default(), &mut |f| {
                if found.is_empty() {
                    found.push(f).is_ok()
                } else {
                    refused += 1;
                    false
                }
            })
            .unwrap();
        }
        ex.flush(&mut |_| false);
        assert_eq!(ex.counters().sweep_breaks, 1);
        assert_eq!(found.len(), 1);
        assert!(found[0].time_ms < 13 * 60, "{found:?}");
        // The second half closed on the first beam past the obstacle, into the full sink.
        assert_eq!(refused, 1);
        assert_eq!(ex.counters().sink_full, refused);
        assert_eq!(ex.counters().features, 1);
        assert_eq!(ex.open_clusters(), 0);
    }

    #[test]
    fn missing_pings_are_bridged_up_to_max_missed() {
        let truth = Vec2::new(12.0, 0.0);
        let scene = [Obj::Circle(truth, 2.0)];
        let run = |skip: &[i32]| {
            let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
            let mut sonar = Sonar::new(5, 20, 0);
            let mut bins = [0u8; 300];
            let mut found = Found::new();
            for k in -12i32..=12 {
                if skip.contains(&k) {
                    continue;
                }
                let bearing = k as f32 * 0.03;
                sonar.ping(
                    &scene,
                    Vec2::ZERO,
                    Vec2::from_angle(bearing),
                    30.0,
                    &mut bins,
                );
                let scan = Scanline {
                    time_ms: (k + 12) as u64 * 60,
                    bearing_rad: bearing,
                    step_rad: 0.03,
                    range_m: 30.0,
                    bins: &bins,
                };
                ex.push_scanline(&scan, Pose::default(), &mut |f| found.push(f).is_ok())
                    .unwrap();
            }
            ex.flush(&mut |f| found.push(f).is_ok());
            found
        };
        assert_eq!(run(&[]).len(), 1);
        let one_missing = run(&[0]);
        assert_eq!(one_missing.len(), 1, "{one_missing:?}");
        assert!(one_missing[0].confidence < run(&[])[0].confidence);
        // Two missing pings in a row exceed max_missed_beams = 1: two halves.
        assert_eq!(run(&[0, 1]).len(), 2);
    }

    #[test]
    fn head_offset_is_applied() {
        // Head 1.5 m forward of the reference point; vehicle heading 90°, at rest.
        let cfg = ExtractorConfig {
            head_offset: Vec2::new(1.5, 0.0),
            ..ExtractorConfig::default()
        };
        let truth = Vec2::new(-5.0, 10.0);
        let scene = [Obj::Circle(truth, 1.0)];
        let track = Track {
            heading: PI / 2.0,
            ..STILL
        };
        let mut ex = Extractor::new(cfg).unwrap();
        let found = sweep(&mut ex, &mut Sonar::new(2, 20, 0), &scene, track, SCAN);
        assert_eq!(found.len(), 1, "{found:?}");
        assert!((found[0].center - truth).norm() < 0.15, "{found:?}");
        // The same pings, taken from the offset head but processed as if the head were at the
        // reference point, land the obstacle about 1.5 m off.
        let mut bins = [0u8; 300];
        let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
        let mut sonar = Sonar::new(2, 20, 0);
        let mut found = Found::new();
        for k in 0..FULL {
            let bearing = wrap_angle(-PI + k as f32 * STEP);
            let u = Vec2::from_angle(PI / 2.0 + bearing);
            sonar.ping(&scene, Vec2::new(0.0, 1.5), u, 30.0, &mut bins);
            let scan = Scanline {
                time_ms: k as u64 * 60,
                bearing_rad: bearing,
                step_rad: STEP,
                range_m: 30.0,
                bins: &bins,
            };
            let pose = track.pose(0.0);
            ex.push_scanline(&scan, pose, &mut |f| found.push(f).is_ok())
                .unwrap();
        }
        ex.flush(&mut |f| found.push(f).is_ok());
        assert_eq!(found.len(), 1, "{found:?}");
        let off = (found[0].center - truth).norm();
        assert!((off - 1.5).abs() < 0.2, "{off}");
    }

    #[test]
    fn a_reported_vehicle_is_neither_a_feature_nor_a_believed_cell() {
        // A 1 m hull 8 m off and a rock 12 m off on the other side, swept once from rest with
        // the map. Unreported, both are features and believed; reported, the vehicle is neither,
        // and the rock is seen as before.
        let (mate, rock) = (Vec2::new(8.0, 0.0), Vec2::new(-12.0, 0.0));
        let scene = [Obj::Circle(mate, 1.0), Obj::Circle(rock, 1.5)];
        let fly = |reported: bool| {
            let map = EvidenceMap::new(crate::sonar::EvidenceConfig::default()).unwrap();
            let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
            if reported {
                ex.report_vehicle(3, mate, 1.0, Vec2::ZERO, 0);
            }
            let mut sonar = Sonar::new(5, 30, 2);
            let mut bins = [0u8; MAX_BINS];
            let mut found = Found::new();
            for k in 0..SCAN.pings {
                let bearing = wrap_angle(SCAN.bearing0 + k as f32 * SCAN.step);
                sonar.ping(
                    &scene,
                    Vec2::ZERO,
                    Vec2::from_angle(bearing),
                    30.0,
                    &mut bins[..300],
                );
                let scan = Scanline {
                    time_ms: k as u64 * SCAN.dt_ms,
                    bearing_rad: bearing,
                    step_rad: SCAN.step,
                    range_m: 30.0,
                    bins: &bins[..300],
                };
                ex.push_scanline_mapped(&scan, STILL.pose(0.0), Some(&map), &mut |f| {
                    found.push(f).is_ok()
                })
                .unwrap();
            }
            ex.flush(&mut |f| found.push(f).is_ok());
            let w = map.window().unwrap();
            let believed_near = |c: Vec2, r: f32| {
                let cell = |x: f32| libm::floorf(x / 0.5) as i32;
                let (i0, j0) = (cell(c.x - r), cell(c.y - r));
                (i0..=cell(c.x + r)).any(|i| (j0..=cell(c.y + r)).any(|j| map.is_occupied(w, i, j)))
            };
            let features_near =
                |c: Vec2| found.iter().filter(|f| (f.center - c).norm() < 2.0).count();
            (
                features_near(mate),
                believed_near(mate, 2.0),
                features_near(rock),
                believed_near(rock, 2.0),
                ex.counters().vehicle_echoes,
            )
        };
        let (f, b, fr, br, masked) = fly(false);
        assert!(
            f >= 1 && b && fr >= 1 && br && masked == 0,
            "unreported: {f} {b} {fr} {br}"
        );
        let (f, b, fr, br, masked) = fly(true);
        assert_eq!((f, b), (0, false), "reported: the vehicle is neither");
        assert!(fr >= 1 && br, "the rock is still seen");
        assert!(masked > 0);
    }

    #[test]
    fn state_is_small() {
        // The extractor lives in a static or on a task stack of a few kB: about 1 kB, and the
        // vehicles it is told about (`KnownVehicles`, 200 bytes on a 64-bit host).
        let size = core::mem::size_of::<Extractor>();
        assert!(size <= 1024 + 200, "Extractor is {size} bytes");
        assert!(core::mem::size_of::<Feature>() <= 48);
    }

    #[test]
    fn rejected_scanlines_change_nothing_but_the_count() {
        let mut ex = Extractor::new(ExtractorConfig::default()).unwrap();
        let bins = [200u8; 513];
        let good = Scanline {
            time_ms: 0,
            bearing_rad: 0.0,
            step_rad: 0.03,
            range_m: 30.0,
            bins: &bins[..300],
        };
        let mut sink = |_f: Feature| true;
        assert_eq!(ex.push_scanline(&good, Pose::default(), &mut sink), Ok(0));
        let before = ex.clone();
        let cases = [
            (
                Scanline {
                    range_m: f32::NAN,
                    ..good
                },
                Pose::default(),
                ScanError::NonFinite,
            ),
            (
                Scanline { bins: &[], ..good },
                Pose::default(),
                ScanError::NoBins,
            ),
            (
                Scanline {
                    bins: &bins,
                    ..good
                },
                Pose::default(),
                ScanError::TooManyBins,
            ),
            (
                Scanline {
                    range_m: 500.0,
                    ..good
                },
                Pose::default(),
                ScanError::RangeOutOfRange,
            ),
            (
                good,
                Pose {
                    position: Vec2::new(f32::NAN, 0.0),
                    heading: 0.0,
                },
                ScanError::BadPose,
            ),
        ];
        for (s, p, want) in cases {
            assert_eq!(ex.push_scanline(&s, p, &mut sink), Err(want));
        }
        let after = ex.counters();
        assert_eq!(after.rejected, 5);
        assert_eq!(
            Counters {
                rejected: 0,
                ..after
            },
            before.counters()
        );
        assert_eq!(ex.open_clusters(), before.open_clusters());
        assert!(Extractor::new(ExtractorConfig {
            threshold: f32::NAN,
            ..ExtractorConfig::default()
        })
        .is_err());
        ex.reset();
        assert_eq!(ex.open_clusters(), 0);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        #[test]
        fn arbitrary_scanlines_never_panic_or_emit_non_finite(
            seeds in proptest::collection::vec(any::<u32>(), 1..60),
            nbins in 0usize..600,
            range in prop_oneof![Just(f32::NAN), Just(f32::INFINITY), -10.0f32..250.0, 0.5f32..200.0],
            step in prop_oneof![Just(0.0f32), -0.3f32..0.3, 0.001f32..0.2],
            bearing0 in prop_oneof![Just(f32::NAN), -1.0e6f32..1.0e6, -7.0f32..7.0],
            x in prop_oneof![Just(f32::INFINITY), -2.0e5f32..2.0e5],
            heading in -100.0f32..100.0,
            dense in any::<bool>(),
            min_beams in 1u16..4,
        ) {
            let cfg = ExtractorConfig { min_beams, min_confidence: 0.0, ..ExtractorConfig::default() };
            let mut ex = Extractor::new(cfg).unwrap();
            let mut bins = [0u8; 600];
            let mut check = |f: Feature| {
                assert!(f.center.is_finite() && f.radius.is_finite() && f.radius > 0.0, "{f:?}");
                assert!((0.0..=1.0).contains(&f.confidence), "{f:?}");
                assert!(f.to_shape().is_ok(), "{f:?}");
                true
            };
            for (k, s) in seeds.iter().enumerate() {
                let mut rng = XorShift32::new(*s);
                for b in bins.iter_mut().take(nbins) {
                    let v = rng.next_u32();
                    *b = if dense { (v % 256) as u8 } else if v.is_multiple_of(7) { 255 } else { 0 };
                }
                let scan = Scanline {
                    time_ms: u64::from(*s % 3) * 1_000 + k as u64 * 50,
                    bearing_rad: bearing0 + step * k as f32 * if s.is_multiple_of(11) { -1.0 } else { 1.0 },
                    step_rad: step,
                    range_m: range,
                    bins: &bins[..nbins],
                };
                let pose = Pose {
                    position: Vec2::new(x + (s % 5) as f32, k as f32 * 0.1),
                    heading: heading + (s % 13) as f32 * 0.01,
                };
                let _ = ex.push_scanline(&scan, pose, &mut check);
            }
            ex.flush(&mut check);
            let c = ex.counters();
            prop_assert_eq!(c.scanlines + c.rejected, seeds.len() as u32);
            prop_assert_eq!(c.clusters_dropped, 0);
        }
    }
}
