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
    /// Median perception miss (p95 per run), m.
    pub median_perception_miss_m: Option<f64>,
    /// Median perception miss (mean per run), m.
    pub median_perception_miss_mean_m: Option<f64>,
    /// Median share of believed cells with no true surface near.
    pub median_perception_false: Option<f64>,
}

/// The tables of every configuration.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// `(configuration, lines)`, families first, `all` last.
    pub tables: Vec<(String, Vec<Line>)>,
    /// Where the parameters came from.
    pub params: String,
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

fn line(family: &str, rows: &[&Row]) -> Line {
    let f =
        |get: &dyn Fn(&Row) -> Option<f64>| median(rows.iter().filter_map(|r| get(r)).collect());
    Line {
        family: family.to_string(),
        runs: rows.len(),
        successes: rows.iter().filter(|r| r.success).count(),
        collisions: rows.iter().filter(|r| r.collided).count(),
        errors: rows.iter().filter(|r| r.error.is_some()).count(),
        worst_clearance_m: rows
            .iter()
            .filter_map(|r| r.min_clearance_m)
            .reduce(f64::min),
        median_clearance_m: f(&|r| r.min_clearance_m),
        median_time_ratio: f(&|r| r.time_ratio),
        median_path_ratio: f(&|r| r.path_ratio),
        median_guard_periods: f(&|r| Some(f64::from(r.guard_periods))),
        median_perception_miss_m: f(&|r| r.perception_miss_m),
        median_perception_miss_mean_m: f(&|r| r.perception_miss_mean_m),
        median_perception_false: f(&|r| r.perception_false_frac),
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
        let mut s = String::new();
        for (config, lines) in &self.tables {
            let _ = writeln!(s, "### {config} ({})\n", self.params);
            s.push_str(
                "| family | runs | success | collisions | not flown | clearance worst / median (m) \
                 | time / ref (median) | path / shortest (median) | guard periods (median) \
                 | perception miss mean / p95 (m) | false cells |\n\
                 |---|---|---|---|---|---|---|---|---|---|---|\n",
            );
            for l in lines {
                let pct = if l.runs > 0 {
                    100.0 * l.successes as f64 / l.runs as f64
                } else {
                    0.0
                };
                let _ = writeln!(
                    s,
                    "| {} | {} | {} ({pct:.0} %) | {} | {} | {} / {} | {} | {} | {} | {} / {} | {} |",
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
                    opt(l.median_perception_miss_mean_m, 2),
                    opt(l.median_perception_miss_m, 2),
                    opt(l.median_perception_false, 3),
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
            perception_miss_m: None,
            perception_miss_mean_m: None,
            perception_false_frac: None,
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
        assert_eq!(all.worst_clearance_m, Some(-0.3));
        assert_eq!(all.median_clearance_m, Some(1.0));
        assert_eq!(all.median_time_ratio, Some(1.5));
        let md = r.markdown();
        assert!(md.contains("| clutter | 2 | 1 (50 %) | 1 |"), "{md}");
        assert!(md.contains("| **all** | 3 | 2 (67 %) | 1 |"), "{md}");
    }
}
