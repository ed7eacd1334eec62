//! Per-beam detection: gain-compensated threshold along one scanline, echo runs, the nearest
//! strong ones kept.
//!
//! Bin `i` is read at its centre range `r = (i + ½)Δ`. Its compensated intensity is
//! `raw · g(r)` with `g(r) = min(1 + k·r, g_max)`. Bins nearer than the blanking distance are
//! skipped. A run starts at a bin at or above `threshold` and continues through bins below it for
//! at most `run_gap_m` (converted to whole bins for this scanline's Δ). It is kept if it is at
//! least `min_run_bins` long (first to last bin above threshold) and its compensated peak
//! reaches `peak_min`. Scanning stops as soon as `runs_per_beam` runs are kept, so the cost is
//! at most one multiply-add and a compare per bin.

use heapless::Vec;

use super::{ExtractorConfig, Scanline, MAX_RUNS_PER_BEAM};

/// One echo run along a beam.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Echo {
    /// Range of the leading edge (centre of the first bin above threshold): the near face, m.
    pub range_m: f32,
    /// From the first to the last bin above threshold, m (bins × Δ).
    pub length_m: f32,
    /// Largest compensated intensity in the run.
    pub peak: f32,
    /// Mean compensated intensity over the run's bins above threshold (≥ `threshold`).
    pub mean: f32,
    /// Bins above threshold in the run.
    pub hits: u16,
}

/// A run being grown.
#[derive(Clone, Copy)]
struct Open {
    first: usize,
    last: usize,
    peak: f32,
    sum: f32,
    hits: u16,
}

/// The nearest strong echo runs of `scan`, nearest first (at most `cfg.runs_per_beam`, at most
/// [`MAX_RUNS_PER_BEAM`]). Expects a validated scanline and configuration; on anything else it
/// returns no runs or fewer, never panics.
pub fn detect(scan: &Scanline<'_>, cfg: &ExtractorConfig) -> Vec<Echo, MAX_RUNS_PER_BEAM> {
    let mut out = Vec::new();
    let want = usize::from(cfg.runs_per_beam).min(MAX_RUNS_PER_BEAM);
    let bin_m = scan.bin_m();
    if want == 0 || !(bin_m.is_finite() && bin_m > 0.0) {
        return out;
    }
    // Whole bins of gap allowed; `as` saturates and maps NaN to 0.
    let gap_bins = (cfg.run_gap_m / bin_m) as usize;
    // First bin whose centre is at or beyond the blanking distance.
    let first = libm::ceilf(cfg.blanking_m / bin_m - 0.5).max(0.0) as usize;
    let mut open: Option<Open> = None;

    for (i, &raw) in scan.bins.iter().enumerate().skip(first) {
        let r = (i as f32 + 0.5) * bin_m;
        let gain = (1.0 + cfg.gain_per_m * r).min(cfg.gain_max);
        let v = f32::from(raw) * gain;
        if v >= cfg.threshold {
            match open.as_mut() {
                Some(o) => {
                    o.last = i;
                    o.peak = o.peak.max(v);
                    o.sum += v;
                    o.hits = o.hits.saturating_add(1);
                }
                None => {
                    open = Some(Open {
                        first: i,
                        last: i,
                        peak: v,
                        sum: v,
                        hits: 1,
                    })
                }
            }
        } else if let Some(o) = open {
            if i.saturating_sub(o.last) > gap_bins {
                open = None;
                if let Some(e) = finish(o, bin_m, cfg) {
                    // `want ≤ capacity`, so the push cannot fail; stop once enough are kept.
                    let _ = out.push(e);
                    if out.len() >= want {
                        return out;
                    }
                }
            }
        }
    }
    if let Some(e) = open.and_then(|o| finish(o, bin_m, cfg)) {
        if out.len() < want {
            let _ = out.push(e);
        }
    }
    out
}

/// The run as an [`Echo`] if it is long and strong enough.
fn finish(o: Open, bin_m: f32, cfg: &ExtractorConfig) -> Option<Echo> {
    let len_bins = o.last.saturating_sub(o.first).saturating_add(1);
    if len_bins < usize::from(cfg.min_run_bins) || o.peak < cfg.peak_min || o.hits == 0 {
        return None;
    }
    Some(Echo {
        range_m: (o.first as f32 + 0.5) * bin_m,
        length_m: len_bins as f32 * bin_m,
        peak: o.peak,
        mean: o.sum / f32::from(o.hits),
        hits: o.hits,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg() -> ExtractorConfig {
        ExtractorConfig {
            gain_per_m: 0.0,
            ..ExtractorConfig::default()
        }
    }

    fn scan(bins: &[u8]) -> Scanline<'_> {
        Scanline {
            time_ms: 0,
            bearing_rad: 0.0,
            step_rad: 0.03,
            range_m: bins.len() as f32 * 0.1,
            bins,
        }
    }

    #[test]
    fn run_reports_leading_edge_peak_and_mean() {
        let mut bins = [0u8; 300];
        bins[100..104].copy_from_slice(&[100, 200, 150, 100]);
        let runs = detect(&scan(&bins), &cfg());
        assert_eq!(runs.len(), 1);
        let e = runs[0];
        assert!((e.range_m - 10.05).abs() < 1e-4, "{e:?}");
        assert!((e.length_m - 0.4).abs() < 1e-4);
        assert_eq!(e.peak, 200.0);
        assert!((e.mean - 137.5).abs() < 1e-4);
        assert_eq!(e.hits, 4);
    }

    #[test]
    fn small_gaps_are_bridged_and_large_ones_split() {
        let mut bins = [0u8; 300];
        // Gap of 2 bins (0.2 m, allowed), then a gap of 5 bins (split).
        bins[50..52].copy_from_slice(&[200, 200]);
        bins[54..56].copy_from_slice(&[200, 200]);
        bins[61..63].copy_from_slice(&[200, 200]);
        let runs = detect(&scan(&bins), &cfg());
        assert_eq!(runs.len(), 2);
        assert_eq!(runs[0].hits, 4);
        assert!((runs[0].length_m - 0.6).abs() < 1e-4);
        assert!((runs[1].range_m - 6.15).abs() < 1e-4);
    }

    #[test]
    fn keeps_only_the_nearest_runs_and_skips_weak_short_and_blanked_ones() {
        let mut bins = [0u8; 300];
        bins[3..8].fill(255); // inside the 1 m blanking
        bins[20] = 255; // one bin: too short
        bins[30..34].fill(85); // above threshold, peak below peak_min
        bins[40..43].fill(200); // kept 1st
        bins[80..83].fill(200); // kept 2nd
        bins[120..123].fill(200); // beyond runs_per_beam
        let runs = detect(&scan(&bins), &cfg());
        assert_eq!(runs.len(), 2, "{runs:?}");
        assert!((runs[0].range_m - 4.05).abs() < 1e-4 && (runs[1].range_m - 8.05).abs() < 1e-4);
        let one = ExtractorConfig {
            runs_per_beam: 1,
            ..cfg()
        };
        assert_eq!(detect(&scan(&bins), &one).len(), 1);
    }

    #[test]
    fn gain_lifts_far_echoes_over_the_threshold() {
        let mut bins = [0u8; 300];
        bins[250..253].fill(60); // 25 m: 60 raw, 60 × (1 + 0.04·25) = 120 compensated
        assert!(detect(&scan(&bins), &cfg()).is_empty());
        let with_gain = ExtractorConfig::default();
        let runs = detect(&scan(&bins), &with_gain);
        assert_eq!(runs.len(), 1);
        assert!(runs[0].peak >= 120.0 && runs[0].peak < 122.0);
        // The ceiling holds: 0.5 /m would give 13.5 at 25 m, capped at 3.
        let steep = ExtractorConfig {
            gain_per_m: 0.5,
            ..with_gain
        };
        assert!((detect(&scan(&bins), &steep)[0].peak - 180.0).abs() < 1e-3);
    }

    #[test]
    fn a_run_reaching_the_last_bin_is_kept() {
        let mut bins = [0u8; 50];
        bins[47..].fill(255);
        let runs = detect(&scan(&bins), &cfg());
        assert_eq!(runs.len(), 1);
        assert!((runs[0].range_m - 4.75).abs() < 1e-4);
    }
}
