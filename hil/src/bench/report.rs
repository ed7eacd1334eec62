//! The bench's tables: per configuration (strategy / model / sensing), one row per family and
//! one overall. Success = every vehicle reached its goal and nothing was touched.

use std::fmt::Write as _;
use std::path::Path;

use serde::Serialize;
use vpf::Params;

use super::case::Row;

/// One line of a table.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Line {
    /// Family, or `all`.
    pub family: String,
    /// Runs.
    pub runs: usize,
    /// Runs that succeeded.
    pub successes: usize,
    /// Runs with a contact.
    pub collisions: usize,
    /// Runs not flown (no feasible draw, a refused scenario, a firmware that failed).
    pub errors: usize,
    /// Runs whose world had a feasible draw for the craft: the share that succeeded is of
    /// these. A world with none (a short serpentine for the flat-fish's 22 m turns) is no
    /// world to fail; a refused scenario or a firmware that failed is a failure.
    pub drawn: usize,
    /// One-sided 95 % upper bound on the collision rate over the runs flown ([`upper95`]).
    pub collision_rate_upper95: Option<f64>,
    /// Worst minimum clearance, m.
    pub worst_clearance_m: Option<f64>,
    /// Median minimum clearance, m.
    pub median_clearance_m: Option<f64>,
    /// Median time over the reference time, of the runs where every vehicle arrived.
    pub median_time_ratio: Option<f64>,
    /// Median path over the shortest feasible path.
    pub median_path_ratio: Option<f64>,
    /// Median periods the guard intervened in.
    pub median_guard_periods: Option<f64>,
    /// Mean share of the time under way at cruise ([`Row::cruise_frac`]).
    pub mean_cruise_frac: Option<f64>,
    /// Mean share of the time under way held stopped by the guard ([`Row::held_frac`]).
    pub mean_held_frac: Option<f64>,
    /// Median perception miss (p95 per run), m.
    pub median_perception_miss_m: Option<f64>,
    /// Median perception miss (mean per run), m.
    pub median_perception_miss_mean_m: Option<f64>,
    /// Median share of believed cells with no true surface near.
    pub median_perception_false: Option<f64>,
    /// Median formation spacing error, a share of λ ([`super::case::formation_spacing`]).
    pub median_formation_spacing: Option<f64>,
    /// Median error of the current believed at the end ([`Row::current_error_mps`]), m/s.
    pub median_current_error_mps: Option<f64>,
}

/// The tables of every configuration.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// `(configuration, lines)`, families first, `all` last.
    pub tables: Vec<(String, Vec<Line>)>,
    /// Where the parameters came from.
    pub params: String,
}

/// The one-sided 95 % upper confidence bound on a rate of which `k` runs in `n` showed it
/// (Clopper–Pearson: the p at which k or fewer in n has probability 5 %). 0 collisions in 204
/// worlds says the rate is below 1.5 %, not that it is zero; `None` for no runs.
pub fn upper95(k: usize, n: usize) -> Option<f64> {
    if n == 0 {
        return None;
    }
    if k >= n {
        return Some(1.0);
    }
    // P(X ≤ k) for X ~ B(n, p), summed in logs (n may be 100 000).
    let at_most_k = |p: f64| -> f64 {
        let (lp, lq) = (p.ln(), (1.0 - p).ln());
        let mut log_pmf = n as f64 * lq;
        let mut total = log_pmf;
        for i in 0..k {
            log_pmf += ((n - i) as f64 / (i + 1) as f64).ln() + lp - lq;
            // log(e^total + e^log_pmf), the larger first.
            let (a, b) = (total.max(log_pmf), total.min(log_pmf));
            total = a + (b - a).exp().ln_1p();
        }
        total.exp()
    };
    // P(X ≤ k) falls as p grows: bisect for 0.05.
    let (mut lo, mut hi) = (k as f64 / n as f64, 1.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if at_most_k(mid) > 0.05 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(hi)
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

fn mean(v: Vec<f64>) -> Option<f64> {
    let v: Vec<f64> = v.into_iter().filter(|x| x.is_finite()).collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn line(family: &str, rows: &[&Row]) -> Line {
    let f =
        |get: &dyn Fn(&Row) -> Option<f64>| median(rows.iter().filter_map(|r| get(r)).collect());
    let m = |get: &dyn Fn(&Row) -> Option<f64>| mean(rows.iter().filter_map(|r| get(r)).collect());
    let collisions = rows.iter().filter(|r| r.collided).count();
    let errors = rows.iter().filter(|r| r.error.is_some()).count();
    Line {
        family: family.to_string(),
        runs: rows.len(),
        successes: rows.iter().filter(|r| r.success).count(),
        collisions,
        errors,
        // The reference time comes with the draw (`super::case`).
        drawn: rows.iter().filter(|r| r.reference_s.is_some()).count(),
        // Over the runs flown: one not flown says nothing of the rate.
        collision_rate_upper95: upper95(collisions, rows.len() - errors),
        worst_clearance_m: rows
            .iter()
            .filter_map(|r| r.min_clearance_m)
            .reduce(f64::min),
        median_clearance_m: f(&|r| r.min_clearance_m),
        median_time_ratio: f(&|r| r.time_ratio),
        median_path_ratio: f(&|r| r.path_ratio),
        median_guard_periods: f(&|r| Some(f64::from(r.guard_periods))),
        mean_cruise_frac: m(&|r| r.cruise_frac),
        mean_held_frac: m(&|r| r.held_frac),
        median_perception_miss_m: f(&|r| r.perception_miss_m),
        median_perception_miss_mean_m: f(&|r| r.perception_miss_mean_m),
        median_perception_false: f(&|r| r.perception_false_frac),
        median_formation_spacing: f(&|r| r.formation_spacing),
        median_current_error_mps: f(&|r| r.current_error_mps),
    }
}

impl Report {
    /// The report over `rows` (in table order).
    pub fn of(rows: &[Row], _params: &Params, recipe: Option<&Path>) -> Report {
        let mut configs: Vec<String> = Vec::new();
        for r in rows {
            if !configs.contains(&r.config) {
                configs.push(r.config.clone());
            }
        }
        let tables = configs
            .into_iter()
            .map(|c| {
                let mine: Vec<&Row> = rows.iter().filter(|r| r.config == c).collect();
                let mut families: Vec<&str> = Vec::new();
                for r in &mine {
                    if !families.contains(&r.family.as_str()) {
                        families.push(&r.family);
                    }
                }
                let mut lines: Vec<Line> = families
                    .iter()
                    .map(|f| {
                        let of: Vec<&Row> =
                            mine.iter().copied().filter(|r| r.family == *f).collect();
                        line(f, &of)
                    })
                    .collect();
                lines.push(line("all", &mine));
                (c, lines)
            })
            .collect();
        Report {
            tables,
            params: recipe.map_or("default parameters".to_string(), |p| {
                format!("parameters from {}", p.display())
            }),
        }
    }

    /// The tables as markdown.
    pub fn markdown(&self) -> String {
        let opt = |v: Option<f64>, d: usize| v.map_or("–".to_string(), |x| format!("{x:.d$}"));
        let pct_of =
            |v: Option<f64>| v.map_or("–".to_string(), |x| format!("{:.0} %", 100.0 * x));
        let mut s = String::new();
        for (config, lines) in &self.tables {
            let _ = writeln!(s, "### {config} ({})\n", self.params);
            s.push_str(
                "| family | runs | success (of worlds drawn) | collisions | collision rate (95 % bound) | not flown \
                 | clearance worst / median (m) | time / ref (median) | path / shortest (median) \
                 | guard periods (median) | under way: at cruise / held (mean) \
                 | perception miss mean / p95 (m) | false cells | formation spacing error \
                 | current believed, error (m/s) |\n\
                 |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
            );
            for l in lines {
                let pct = if l.drawn > 0 {
                    100.0 * l.successes as f64 / l.drawn as f64
                } else {
                    0.0
                };
                let bound = l
                    .collision_rate_upper95
                    .map_or("–".to_string(), |u| format!("≤ {:.1} %", 100.0 * u));
                let _ = writeln!(
                    s,
                    "| {} | {} | {} ({pct:.0} %) | {} | {bound} | {} | {} / {} | {} | {} | {} | {} / {} \
                     | {} / {} | {} | {} | {} |",
                    if l.family == "all" {
                        "**all**".to_string()
                    } else {
                        l.family.clone()
                    },
                    l.runs,
                    l.successes,
                    l.collisions,
                    l.errors,
                    opt(l.worst_clearance_m, 2),
                    opt(l.median_clearance_m, 2),
                    opt(l.median_time_ratio, 2),
                    opt(l.median_path_ratio, 2),
                    opt(l.median_guard_periods, 0),
                    pct_of(l.mean_cruise_frac),
                    pct_of(l.mean_held_frac),
                    opt(l.median_perception_miss_mean_m, 2),
                    opt(l.median_perception_miss_m, 2),
                    opt(l.median_perception_false, 3),
                    pct_of(l.median_formation_spacing),
                    opt(l.median_current_error_mps, 3),
                );
            }
            s.push('\n');
        }
        s
    }

    /// The tables as JSON.
    pub fn json(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or(serde_json::Value::Null)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(family: &str, success: bool, collided: bool, clear: f64) -> Row {
        Row {
            id: format!("{family}:{clear}"),
            family: family.to_string(),
            seed: 0,
            config: "vpf / videoray / scanlines".to_string(),
            success,
            collided,
            min_clearance_m: Some(clear),
            time_ratio: success.then_some(1.5),
            path_ratio: Some(1.2),
            reference_s: Some(100.0),
            guard_periods: 3,
            cruise_frac: Some(if success { 0.8 } else { 0.4 }),
            held_frac: Some(0.1),
            perception_miss_m: None,
            perception_miss_mean_m: None,
            perception_false_frac: None,
            formation_spacing: None,
            current_error_mps: None,
            error: None,
        }
    }

    #[test]
    fn families_and_the_overall_line_count_what_happened() {
        let rows = [
            row("clutter", true, false, 1.0),
            row("clutter", false, true, -0.3),
            row("harbour", true, false, 2.0),
        ];
        let r = Report::of(&rows, &Params::default(), None);
        let (_, lines) = &r.tables[0];
        assert_eq!(lines.len(), 3);
        let all = &lines[2];
        assert_eq!((all.runs, all.successes, all.collisions), (3, 2, 1));
        assert_eq!(all.collision_rate_upper95, upper95(1, 3));
        assert_eq!(all.worst_clearance_m, Some(-0.3));
        assert_eq!(all.median_clearance_m, Some(1.0));
        assert_eq!(all.median_time_ratio, Some(1.5));
        // At cruise 80 % of the time in the successes, 40 % in the failure.
        assert!((all.mean_cruise_frac.unwrap() - 2.0 / 3.0).abs() < 1e-12);
        let md = r.markdown();
        assert!(md.contains("| clutter | 2 | 1 (50 %) | 1 |"), "{md}");
        assert!(md.contains("| 60 % / 10 % |"), "{md}");
        assert!(
            md.contains("| **all** | 3 | 2 (67 %) | 1 | ≤ 86.5 % |"),
            "{md}"
        );
        // A world with no feasible draw for the craft counts in the runs, not in the share
        // that succeeded; a run whose firmware failed is a failure.
        let mut undrawn = row("harbour", false, false, 0.0);
        undrawn.reference_s = None;
        undrawn.error = Some("no feasible draw in 20: no path wide enough for the hull".into());
        let mut broke = row("harbour", false, false, 0.0);
        broke.error = Some("the firmware exited".into());
        let of = |rows: &[Row]| Report::of(rows, &Params::default(), None).markdown();
        let short = of(&[row("harbour", true, false, 2.0), undrawn]);
        assert!(
            short.contains("| harbour | 2 | 1 (100 %) | 0 | ≤ 95.0 % | 1 |"),
            "{short}"
        );
        let short = of(&[row("harbour", true, false, 2.0), broke]);
        assert!(short.contains("| harbour | 2 | 1 (50 %) | 0 |"), "{short}");
    }

    #[test]
    fn the_collision_bound_is_the_exact_binomial_one() {
        // None in n: 1 − 0.05^(1/n), the "rule of three" (≈ 3/n) for large n.
        for n in [1, 17, 204, 2400] {
            let u = upper95(0, n).unwrap();
            let exact = 1.0 - 0.05f64.powf(1.0 / n as f64);
            assert!((u - exact).abs() < 1e-9, "n {n}: {u} vs {exact}");
        }
        assert!((upper95(0, 204).unwrap() - 0.0146).abs() < 1e-4);
        // One in 3: P(X ≤ 1) = (1 − p)³ + 3p(1 − p)² = 0.05 at p ≈ 0.8647.
        assert!((upper95(1, 3).unwrap() - 0.8647).abs() < 1e-3);
        // 5 in 2 400: tabulated Clopper–Pearson one-sided bound ≈ 0.44 %.
        let u = upper95(5, 2400).unwrap();
        assert!(u > 0.0040 && u < 0.0048, "{u}");
        // Large counts stay finite and above the observed rate.
        let u = upper95(300, 100_000).unwrap();
        assert!(u > 0.003 && u < 0.0034, "{u}");
        assert_eq!(upper95(3, 3), Some(1.0));
        assert_eq!(upper95(0, 0), None);
    }
}
