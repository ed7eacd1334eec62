//! What a sweep leaves besides `runs.csv`: the parameter sets ranked (`sets.csv`, and
//! `ranking.md` with the criterion's top of the table and each parameter's influence), heat
//! maps of success rate and mean minimum clearance over the two most influential parameters
//! (`heatmap_success.svg`, `heatmap_clearance.svg`), and the recommended recipe
//! (`recipe.toml`, a `[planner]` table that `hil run --params` takes).
//!
//! **Influence** of a parameter: the sets are grouped by its value and the criterion's score
//! (1 best … 0 worst, see `criterion.rs`) averaged per group; the influence is the spread
//! (largest minus smallest group mean). The heat maps use the two parameters with the largest
//! spread, unless the spec names them (`[sweep] heatmap`). Each cell averages the sets having
//! that pair of values (a marginal over the other parameters); the recommended set's cell is
//! outlined. Parameters drawn from a continuous range are binned (8 bins, log-spaced for a log
//! range).

use std::collections::BTreeMap;
use std::path::Path;

use super::criterion::{self, SetStats};
use super::measure::RunRow;
use super::spec::{Axis, Spec, Value};

mod heatmap;
mod ranking;
mod recipe;
mod sets_csv;

pub use heatmap::Metric;

/// The method-independent parameters of seed 002 §1, pinned in every recipe.
pub const METHOD_INDEPENDENT: [&str; 9] = [
    "a_plus",
    "a_rotor",
    "epsilon_m",
    "n_gamma",
    "mu",
    "f_max",
    "v_max",
    "sigma_m",
    "a_minus",
];

/// The papers' symbol of a parameter, for tables and axes.
pub fn symbol(name: &str) -> &str {
    match name {
        "a_plus" => "A_s⁺",
        "a_rotor" => "A_r⁺",
        "epsilon_m" => "ε",
        "n_gamma" => "n_γ",
        "mu" => "μ",
        "f_max" => "F_max",
        "v_max" => "v_max",
        "sigma_m" => "σ",
        "a_minus" => "A⁻",
        other => other,
    }
}

/// Facts about the sweep for the reports' headers.
#[derive(Clone, Debug)]
pub struct Context {
    /// The spec file as given on the command line.
    pub spec_file: String,
    /// The sweep's identity (hash of the spec and its scenarios).
    pub identity: String,
    /// Scenario ids in batch order.
    pub scenarios: Vec<String>,
    /// Runs in the whole sweep.
    pub total_runs: usize,
    /// Date of the report, `YYYY-MM-DD`.
    pub date: String,
}

/// Today's date (UTC) as `YYYY-MM-DD`.
pub fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    date_of(secs)
}

/// `YYYY-MM-DD` of a Unix time (H. Hinnant's civil-from-days).
pub fn date_of(unix_s: u64) -> String {
    let z = (unix_s / 86_400) as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}")
}

/// Everything the report holds, computed once.
pub struct Report {
    /// Sets, best first.
    pub ranked: Vec<SetStats>,
    /// (parameter, spread of the mean score, best value by mean score), most influential first.
    pub influence: Vec<(String, f64, String)>,
    /// The heat maps' axes (indices into `spec.params`); the second is `None` with one
    /// parameter.
    pub axes: (usize, Option<usize>),
    /// Runs recorded.
    pub runs: usize,
    /// The recommended set per scenario family: (family, runs, successes, collided, mean
    /// minimum clearance).
    pub best_by_family: Vec<(String, usize, usize, usize, f64)>,
}

fn fixed(x: f64, d: usize) -> String {
    if x.is_finite() {
        format!("{x:.d$}")
    } else {
        "–".into()
    }
}

/// A cell key of a value on an axis (its bin for a continuous range).
struct Binning {
    edges: Option<(Vec<f64>, bool)>,
    labels: Vec<String>,
}

impl Binning {
    fn new(spec: &Spec, p: usize) -> Binning {
        let mut values: Vec<Value> = Vec::new();
        for s in &spec.sets {
            if !values.contains(&s[p]) {
                values.push(s[p].clone());
            }
        }
        let numeric: Option<Vec<f64>> = values.iter().map(Value::number).collect();
        if let (Some(mut xs), true) = (numeric.clone(), values.len() > 10) {
            xs.sort_by(f64::total_cmp);
            let log = matches!(spec.params[p].axis, Axis::Range { log: true, .. }) && xs[0] > 0.0;
            let (lo, hi) = (xs[0], xs[xs.len() - 1]);
            let tr = |x: f64| if log { x.ln() } else { x };
            let un = |x: f64| if log { x.exp() } else { x };
            let n = 8;
            let edges: Vec<f64> = (0..=n)
                .map(|i| un(tr(lo) + (tr(hi) - tr(lo)) * i as f64 / n as f64))
                .collect();
            let labels = (0..n)
                .map(|i| {
                    let c = un((tr(edges[i]) + tr(edges[i + 1])) / 2.0);
                    format!("{}", sig3(c))
                })
                .collect();
            return Binning {
                edges: Some((edges, log)),
                labels,
            };
        }
        if let Some(mut xs) = numeric {
            xs.sort_by(f64::total_cmp);
            values = xs
                .into_iter()
                .map(|x| {
                    values
                        .iter()
                        .find(|v| v.number() == Some(x))
                        .cloned()
                        .unwrap_or(Value::Float(x))
                })
                .collect();
        }
        Binning {
            edges: None,
            labels: values.iter().map(Value::plain).collect(),
        }
    }

    fn index(&self, v: &Value) -> usize {
        match (&self.edges, v.number()) {
            (Some((edges, _)), Some(x)) => {
                let n = edges.len() - 1;
                (0..n).find(|&i| x < edges[i + 1]).unwrap_or(n - 1)
            }
            _ => self
                .labels
                .iter()
                .position(|l| *l == v.plain())
                .unwrap_or(0),
        }
    }
}

fn sig3(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let mag = 10f64.powi(x.abs().log10().floor() as i32 - 2);
    let r = (x / mag).round() * mag;
    format!("{r:.10}").parse().unwrap_or(r)
}

impl Report {
    /// Ranks the sets of `rows` and works out the influences and the heat-map axes.
    pub fn new(spec: &Spec, rows: &[RunRow]) -> Report {
        let ranked = criterion::rank(rows, spec.sets.len(), spec.craft.margin_m, &spec.weights);
        let score: BTreeMap<usize, f64> = ranked.iter().map(|s| (s.set, s.score)).collect();
        let mut influence: Vec<(String, f64, String)> = spec
            .params
            .iter()
            .enumerate()
            .map(|(p, param)| {
                let bins = Binning::new(spec, p);
                let mut sums = vec![(0.0, 0usize); bins.labels.len()];
                for (i, set) in spec.sets.iter().enumerate() {
                    let b = bins.index(&set[p]);
                    sums[b].0 += score.get(&i).copied().unwrap_or(0.0);
                    sums[b].1 += 1;
                }
                let means: Vec<(f64, &String)> = sums
                    .iter()
                    .zip(&bins.labels)
                    .filter(|(s, _)| s.1 > 0)
                    .map(|(s, l)| (s.0 / s.1 as f64, l))
                    .collect();
                let hi = means.iter().map(|m| m.0).fold(f64::NEG_INFINITY, f64::max);
                let lo = means.iter().map(|m| m.0).fold(f64::INFINITY, f64::min);
                let best = means
                    .iter()
                    .find(|m| m.0 == hi)
                    .map_or(String::new(), |m| m.1.clone());
                (param.name.clone(), hi - lo, best)
            })
            .collect();
        influence.sort_by(|a, b| b.1.total_cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
        let index = |n: &str| spec.params.iter().position(|p| p.name == n);
        let axes = match &spec.heatmap {
            Some((x, y)) => (index(x).unwrap_or(0), index(y)),
            None => {
                let first = index(&influence[0].0).unwrap_or(0);
                (first, influence.get(1).and_then(|i| index(&i.0)))
            }
        };
        let mut best_by_family: Vec<(String, usize, usize, usize, f64)> = Vec::new();
        if let Some(b) = ranked.first() {
            for r in rows.iter().filter(|r| r.set == b.set) {
                let fam = family(&r.scenario).to_string();
                let i = match best_by_family.iter().position(|f| f.0 == fam) {
                    Some(i) => i,
                    None => {
                        best_by_family.push((fam, 0, 0, 0, 0.0));
                        best_by_family.len() - 1
                    }
                };
                let e = &mut best_by_family[i];
                e.1 += 1;
                e.2 += usize::from(r.success);
                e.3 += usize::from(r.collided);
                if r.min_clearance_m.is_finite() {
                    e.4 += r.min_clearance_m;
                }
            }
            for e in &mut best_by_family {
                e.4 /= e.1.max(1) as f64;
            }
        }
        Report {
            ranked,
            influence,
            axes,
            runs: rows.len(),
            best_by_family,
        }
    }

    /// The recommended set (rank 1).
    pub fn best(&self) -> Option<&SetStats> {
        self.ranked.first()
    }

    /// What is wrong with the recommendation, if it is not a usable recipe.
    pub fn warning(&self) -> Option<&'static str> {
        let b = self.best()?;
        if b.collided > 0 {
            Some(
                "No parameter set is collision-free on this batch: the recommendation is the \
                 least bad, not a safe recipe.",
            )
        } else if b.successes == 0 {
            Some(
                "No collision-free parameter set reached any goal: the recommendation is only \
                 the safest set (it never collides because it never gets far), not a usable \
                 recipe.",
            )
        } else {
            None
        }
    }
}

/// The family of a scenario id: `files`, `clutter`, `passage` or `utrap`.
pub fn family(id: &str) -> &str {
    match id.split_once(':') {
        Some(("file", _)) => "files",
        Some((k, _)) => k,
        None => id,
    }
}

/// `3 files, 10 clutter, 10 passage, 10 utrap`.
pub fn families(ids: &[String]) -> String {
    let mut counts: Vec<(&str, usize)> = Vec::new();
    for id in ids {
        let fam = family(id);
        match counts.iter_mut().find(|c| c.0 == fam) {
            Some(c) => c.1 += 1,
            None => counts.push((fam, 1)),
        }
    }
    counts
        .iter()
        .map(|(k, n)| format!("{n} {k}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Writes `sets.csv`, `ranking.md`, the heat maps and `recipe.toml` into `dir`; returns the
/// report.
pub fn write(dir: &Path, spec: &Spec, rows: &[RunRow], ctx: &Context) -> std::io::Result<Report> {
    let r = Report::new(spec, rows);
    std::fs::write(dir.join("sets.csv"), r.sets_csv(spec))?;
    std::fs::write(dir.join("ranking.md"), r.markdown(spec, ctx))?;
    std::fs::write(
        dir.join("heatmap_success.svg"),
        r.heatmap(spec, Metric::Success),
    )?;
    std::fs::write(
        dir.join("heatmap_clearance.svg"),
        r.heatmap(spec, Metric::Clearance),
    )?;
    if let Some(recipe) = r.recipe(spec, ctx) {
        std::fs::write(dir.join("recipe.toml"), recipe)?;
    }
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates() {
        assert_eq!(date_of(0), "1970-01-01");
        assert_eq!(date_of(951_782_400), "2000-02-29");
        assert_eq!(date_of(1_700_000_000), "2023-11-14");
    }
}
