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
use std::fmt::Write as _;
use std::path::Path;

use super::criterion::{self, SetStats};
use super::measure::RunRow;
use super::spec::{Axis, Spec, Value};
use crate::output::svg::{esc, Svg};

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

    /// `sets.csv`: every set, ranked.
    pub fn sets_csv(&self, spec: &Spec) -> String {
        let mut s = String::from("rank,set");
        for p in &spec.params {
            let _ = write!(s, ",{}", p.name);
        }
        s.push_str(
            ",runs,successes,success_rate,collided,close,errors,mean_clearance_m,\
             worst_clearance_m,path_ratio,time_s,energy,oscillation_per_100m,cost,score\n",
        );
        let n = |x: f64, d: usize| {
            if x.is_finite() {
                format!("{x:.d$}")
            } else {
                String::new()
            }
        };
        for st in &self.ranked {
            let _ = write!(s, "{},{}", st.rank, st.set);
            for v in &spec.sets[st.set] {
                let _ = write!(s, ",{}", super::csv::quote(&v.plain()));
            }
            let _ = writeln!(
                s,
                ",{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                st.runs,
                st.successes,
                n(st.success_rate(), 4),
                st.collided,
                st.close,
                st.errors,
                n(st.mean_clearance_m, 4),
                n(st.worst_clearance_m, 4),
                n(st.path_ratio, 4),
                n(st.time_s, 2),
                n(st.energy, 2),
                n(st.oscillation, 3),
                n(st.cost, 4),
                n(st.score, 4)
            );
        }
        s
    }

    /// The ranked table as markdown: the top `top` sets.
    pub fn table(&self, spec: &Spec, top: usize) -> String {
        let mut s = String::from("| rank | set |");
        for p in &spec.params {
            let _ = write!(s, " {} |", symbol(&p.name));
        }
        s.push_str(
            " success | collided | < margin | clearance mean / worst (m) | path ratio | time (s) \
             | energy | reversals /100 m | J |\n|---:|---:|",
        );
        for _ in &spec.params {
            s.push_str("---:|");
        }
        s.push_str("---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
        for st in self.ranked.iter().take(top) {
            let _ = write!(s, "| {} | {} |", st.rank, st.set);
            for v in &spec.sets[st.set] {
                let _ = write!(s, " {} |", v.plain());
            }
            let _ = writeln!(
                s,
                " {:.1} % ({}/{}) | {} | {} | {} / {} | {} | {} | {} | {} | {} |",
                100.0 * st.success_rate(),
                st.successes,
                st.runs,
                st.collided,
                st.close,
                fixed(st.mean_clearance_m, 2),
                fixed(st.worst_clearance_m, 2),
                fixed(st.path_ratio, 3),
                fixed(st.time_s, 1),
                fixed(st.energy, 1),
                fixed(st.oscillation, 2),
                fixed(st.cost, 3)
            );
        }
        s
    }

    /// `ranking.md`.
    pub fn markdown(&self, spec: &Spec, ctx: &Context) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# Sweep \"{}\": ranking\n", spec.name);
        if !spec.description.is_empty() {
            let _ = writeln!(s, "{}\n", spec.description.trim());
        }
        let _ = writeln!(
            s,
            "- spec: `{}` (identity `{}`)\n- craft: {} (model `{}`), clearance margin {} m\n\
             - runs: {} of {} recorded ({} parameter sets × {} scenarios: {})\n- criterion: \
             no collision (hard), then success rate, then runs under the margin, then \
             J = {}·T/T_best + {}·E/E_best + {}·reversals per 100 m (see \
             `hil/src/sweep/criterion.rs`); oscillation deadband {:.1} °/s\n- date: {}\n",
            ctx.spec_file,
            ctx.identity,
            spec.craft.label,
            spec.craft.model.name(),
            spec.craft.margin_m,
            self.runs,
            ctx.total_runs,
            spec.sets.len(),
            ctx.scenarios.len(),
            families(&ctx.scenarios),
            spec.weights.time,
            spec.weights.energy,
            spec.weights.oscillation,
            spec.weights.deadband.to_degrees(),
            ctx.date
        );
        if let Some(w) = self.warning() {
            let _ = writeln!(s, "**{w}**\n");
        }
        let _ = writeln!(
            s,
            "## Ranked parameter sets (top 20 of {})\n",
            self.ranked.len()
        );
        s.push_str(&self.table(spec, 20));
        s.push_str(
            "\nsuccess: reached the goal without a collision; collided: runs with a collision; \
             < margin: runs whose minimum clearance was under the margin; clearance: the \
             runs' minimum clearance, mean and worst; path ratio, time, energy, reversals: means \
             over the successful runs; J: the cost (lower is better).\n\n",
        );
        s.push_str("## Influence of each parameter\n\nSpread of the criterion's mean score (1 best, 0 worst) across the parameter's values; the heat maps use the top two.\n\n| parameter | spread | best value (mean score) |\n|---|---:|---:|\n");
        for (name, spread, best) in &self.influence {
            let _ = writeln!(s, "| {} (`{name}`) | {spread:.3} | {best} |", symbol(name));
        }
        if let Some(b) = self.best() {
            let _ = writeln!(
                s,
                "\n## The recommended set (set {}) per scenario family\n\n\
                 | family | runs | success | collided | mean min. clearance (m) |\n\
                 |---|---:|---:|---:|---:|",
                b.set
            );
            for (fam, n, ok, hit, clear) in &self.best_by_family {
                let _ = writeln!(
                    s,
                    "| {fam} | {n} | {:.1} % | {hit} | {clear:.2} |",
                    100.0 * *ok as f64 / (*n).max(1) as f64
                );
            }
        }
        s.push_str(
            "\n## Heat maps\n\n![success rate](heatmap_success.svg)\n\n\
             ![mean minimum clearance](heatmap_clearance.svg)\n",
        );
        s
    }

    /// The heat map of `metric` ("success" or "clearance").
    pub fn heatmap(&self, spec: &Spec, metric: Metric) -> String {
        let (px, py) = self.axes;
        let bx = Binning::new(spec, px);
        let by = py.map(|p| Binning::new(spec, p));
        let (nx, ny) = (bx.labels.len(), by.as_ref().map_or(1, |b| b.labels.len()));
        let stats: BTreeMap<usize, &SetStats> = self.ranked.iter().map(|s| (s.set, s)).collect();
        let mut cells = vec![(0.0, 0usize); nx * ny];
        for (i, set) in spec.sets.iter().enumerate() {
            let Some(st) = stats.get(&i) else { continue };
            if st.runs == 0 {
                continue;
            }
            let v = match metric {
                Metric::Success => st.success_rate(),
                Metric::Clearance => st.mean_clearance_m,
            };
            if !v.is_finite() {
                continue;
            }
            let x = bx.index(&set[px]);
            let y = by.as_ref().map_or(0, |b| b.index(&set[py.unwrap_or(0)]));
            cells[y * nx + x].0 += v;
            cells[y * nx + x].1 += 1;
        }
        let values: Vec<Option<f64>> = cells
            .iter()
            .map(|c| (c.1 > 0).then(|| c.0 / c.1 as f64))
            .collect();
        let (lo, hi) = match metric {
            Metric::Success => (0.0, 1.0),
            Metric::Clearance => {
                let xs = values.iter().flatten();
                let lo = xs.clone().copied().fold(f64::INFINITY, f64::min);
                let hi = xs.copied().fold(f64::NEG_INFINITY, f64::max);
                if lo.is_finite() && hi > lo {
                    (lo, hi)
                } else {
                    (0.0, lo.max(0.0) + 1.0)
                }
            }
        };
        let (cw, ch) = (78.0, 46.0);
        let (left, top) = (120.0, 70.0);
        let w = (left + cw * nx as f64 + 150.0).max(820.0);
        let h = top + ch * ny as f64 + 80.0;
        let mut svg = Svg::new(w, h);
        let pname = |p: usize| {
            let n = &spec.params[p].name;
            if symbol(n) == n.as_str() {
                n.clone()
            } else {
                format!("{} ({n})", symbol(n))
            }
        };
        let title = match metric {
            Metric::Success => "Success rate (reached the goal, no collision)",
            Metric::Clearance => "Mean minimum clearance, m",
        };
        svg.text(
            left,
            24.0,
            &format!("{title} — sweep \"{}\"", spec.name),
            "font-size=\"15\" font-weight=\"bold\"",
        );
        svg.text(
            left,
            44.0,
            "each cell: mean over the parameter sets with these two values (n = sets); outlined: the recommended set",
            "font-size=\"11\" fill=\"#555\"",
        );
        let best = self.best().map(|b| {
            let set = &spec.sets[b.set];
            (
                bx.index(&set[px]),
                by.as_ref().map_or(0, |bb| bb.index(&set[py.unwrap_or(0)])),
            )
        });
        for yi in 0..ny {
            for xi in 0..nx {
                // Row 0 at the bottom (y grows upwards).
                let x = left + cw * xi as f64;
                let y = top + ch * (ny - 1 - yi) as f64;
                let v = values[yi * nx + xi];
                let fill = v.map_or("#eeeeee".to_string(), |v| {
                    colour(metric, (v - lo) / (hi - lo))
                });
                svg.rect(
                    x,
                    y,
                    cw,
                    ch,
                    &format!("fill=\"{fill}\" stroke=\"white\" stroke-width=\"1\""),
                );
                if let Some(v) = v {
                    let label = match metric {
                        Metric::Success => format!("{:.0} %", 100.0 * v),
                        Metric::Clearance => format!("{v:.2}"),
                    };
                    let dark = (v - lo) / (hi - lo) > 0.6 && metric == Metric::Clearance;
                    let col = if dark { "white" } else { "#111" };
                    svg.text(
                        x + cw / 2.0,
                        y + ch / 2.0,
                        &label,
                        &format!("text-anchor=\"middle\" fill=\"{col}\" font-size=\"13\""),
                    );
                    svg.text(
                        x + cw / 2.0,
                        y + ch / 2.0 + 14.0,
                        &format!("n = {}", cells[yi * nx + xi].1),
                        &format!("text-anchor=\"middle\" fill=\"{col}\" font-size=\"9\""),
                    );
                }
            }
        }
        if let Some((bxi, byi)) = best {
            let x = left + cw * bxi as f64;
            let y = top + ch * (ny - 1 - byi) as f64;
            svg.rect(
                x + 1.5,
                y + 1.5,
                cw - 3.0,
                ch - 3.0,
                "fill=\"none\" stroke=\"#000\" stroke-width=\"3\"",
            );
        }
        for (xi, l) in bx.labels.iter().enumerate() {
            svg.text(
                left + cw * (xi as f64 + 0.5),
                top + ch * ny as f64 + 18.0,
                l,
                "text-anchor=\"middle\" fill=\"#333\"",
            );
        }
        svg.text(
            left + cw * nx as f64 / 2.0,
            top + ch * ny as f64 + 42.0,
            &pname(px),
            "text-anchor=\"middle\" font-size=\"13\"",
        );
        if let (Some(by), Some(py)) = (&by, py) {
            for (yi, l) in by.labels.iter().enumerate() {
                let y = top + ch * (ny - 1 - yi) as f64 + ch / 2.0 + 4.0;
                svg.text(left - 8.0, y, l, "text-anchor=\"end\" fill=\"#333\"");
            }
            let (cx, cy) = (left - 70.0, top + ch * ny as f64 / 2.0);
            svg.raw(&format!(
                "<text x=\"{cx:.1}\" y=\"{cy:.1}\" text-anchor=\"middle\" font-size=\"13\" \
                 transform=\"rotate(-90 {cx:.1} {cy:.1})\">{}</text>\n",
                esc(&pname(py))
            ));
        }
        // Colour scale.
        let sx = left + cw * nx as f64 + 30.0;
        let steps = 20;
        let bar_h = (ch * ny as f64).max(120.0);
        for i in 0..steps {
            let t = i as f64 / (steps - 1) as f64;
            let y = top + bar_h * (1.0 - (i + 1) as f64 / steps as f64);
            svg.rect(
                sx,
                y,
                18.0,
                bar_h / steps as f64 + 0.5,
                &format!("fill=\"{}\"", colour(metric, t)),
            );
        }
        let fmt = |v: f64| match metric {
            Metric::Success => format!("{:.0} %", 100.0 * v),
            Metric::Clearance => format!("{v:.2} m"),
        };
        svg.text(sx + 24.0, top + 10.0, &fmt(hi), "fill=\"#333\"");
        svg.text(sx + 24.0, top + bar_h, &fmt(lo), "fill=\"#333\"");
        if metric == Metric::Clearance {
            svg.text(
                sx,
                top + bar_h + 20.0,
                &format!("margin {} m", spec.craft.margin_m),
                "fill=\"#333\" font-size=\"11\"",
            );
        }
        svg.finish()
    }

    /// `recipe.toml`: the recommended set as a `[planner]` table, with where it came from.
    pub fn recipe(&self, spec: &Spec, ctx: &Context) -> Option<String> {
        let b = self.best()?;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "# Recipe: {} (model \"{}\"): VPF planner parameters tuned by a sweep (seed 002).",
            spec.craft.label,
            spec.craft.model.name()
        );
        let _ = writeln!(
            s,
            "# Sweep: {} \"{}\" (identity {}), {} runs = {} parameter sets x {} scenarios ({}).",
            ctx.spec_file,
            spec.name,
            ctx.identity,
            self.runs,
            spec.sets.len(),
            ctx.scenarios.len(),
            families(&ctx.scenarios)
        );
        let _ = writeln!(s, "# date: {}", ctx.date);
        if let Some(w) = self.warning() {
            let _ = writeln!(s, "# WARNING: {w}");
        }
        let _ = writeln!(
            s,
            "# Recommended: set {}, rank 1 of {} by the criterion (hil/src/sweep/criterion.rs):",
            b.set,
            self.ranked.len()
        );
        let _ = writeln!(
            s,
            "#   success {:.1} % ({}/{}), runs with a collision {}, clearance mean {} m / worst {} m",
            100.0 * b.success_rate(),
            b.successes,
            b.runs,
            b.collided,
            fixed(b.mean_clearance_m, 2),
            fixed(b.worst_clearance_m, 2)
        );
        let _ = writeln!(
            s,
            "#   ({} runs under the {} m margin), path ratio {}, time {} s, energy {}, {} reversals/100 m.",
            b.close,
            spec.craft.margin_m,
            fixed(b.path_ratio, 3),
            fixed(b.time_s, 1),
            fixed(b.energy, 1),
            fixed(b.oscillation, 2)
        );
        let _ = writeln!(
            s,
            "# Evidence: ranking.md, sets.csv and heatmap_*.svg of the sweep's output directory\n\
             # (for the shipped recipes: hil/recipes/NAME/, described in hil/recipes/README.md).\n\
             # Use: cargo hil run SCENARIO.toml --params THIS_FILE (replaces the scenario's [planner])."
        );
        s.push_str("[planner]\n");
        let entries = spec.entries(b.set);
        for (k, v) in &entries {
            let _ = writeln!(s, "{k} = {}", v.toml());
        }
        if let Ok(p) = spec.params_of(b.set, super::spec::CHECK_DT_S) {
            let pinned: Vec<&str> = METHOD_INDEPENDENT
                .iter()
                .copied()
                .filter(|n| !entries.iter().any(|(k, _)| k == n))
                .collect();
            if !pinned.is_empty() {
                s.push_str(
                    "# Not swept: the planner's defaults at the time of the sweep, pinned.\n",
                );
                for n in pinned {
                    if let Some(v) = param_value(&p, n) {
                        let _ = writeln!(s, "{n} = {}", v.toml());
                    }
                }
            }
        }
        Some(s)
    }

    /// The top of the table for the terminal.
    pub fn print(&self, spec: &Spec, top: usize) -> String {
        let mut s = String::new();
        let names: Vec<String> = spec.params.iter().map(|p| p.name.clone()).collect();
        let _ = writeln!(
            s,
            "{:>4} {:>5} {} {:>8} {:>4} {:>4} {:>13} {:>6} {:>7} {:>6}",
            "rank",
            "set",
            names
                .iter()
                .map(|n| format!("{n:>9}"))
                .collect::<Vec<_>>()
                .join(" "),
            "success",
            "hit",
            "<mg",
            "clear mean/min",
            "path",
            "time s",
            "J"
        );
        for st in self.ranked.iter().take(top) {
            let vals: Vec<String> = spec.sets[st.set]
                .iter()
                .map(|v| format!("{:>9}", v.plain()))
                .collect();
            let _ = writeln!(
                s,
                "{:>4} {:>5} {} {:>7.1}% {:>4} {:>4} {:>6}/{:>6} {:>6} {:>7} {:>6}",
                st.rank,
                st.set,
                vals.join(" "),
                100.0 * st.success_rate(),
                st.collided,
                st.close,
                fixed(st.mean_clearance_m, 2),
                fixed(st.worst_clearance_m, 2),
                fixed(st.path_ratio, 2),
                fixed(st.time_s, 1),
                fixed(st.cost, 3)
            );
        }
        s
    }
}

/// A heat map's quantity.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// Success rate.
    Success,
    /// Mean minimum clearance.
    Clearance,
}

/// Red–yellow–green for success, white–blue for clearance; `t` in 0..=1.
fn colour(metric: Metric, t: f64) -> String {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let stops: &[(f64, [f64; 3])] = match metric {
        Metric::Success => &[
            (0.0, [215.0, 48.0, 39.0]),
            (0.5, [254.0, 224.0, 139.0]),
            (1.0, [26.0, 152.0, 80.0]),
        ],
        Metric::Clearance => &[(0.0, [247.0, 251.0, 255.0]), (1.0, [8.0, 81.0, 156.0])],
    };
    let i = stops
        .windows(2)
        .position(|w| t <= w[1].0)
        .unwrap_or(stops.len() - 2);
    let (a, b) = (stops[i], stops[i + 1]);
    let u = (t - a.0) / (b.0 - a.0);
    let c: Vec<u8> = (0..3)
        .map(|k| (a.1[k] + u * (b.1[k] - a.1[k])).round() as u8)
        .collect();
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
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

/// A parameter's value in `p`, as a recipe writes it (an enum by its name).
fn param_value(p: &vpf::Params, name: &str) -> Option<Value> {
    use vpf::params::{Kind, ParamId, Value as V};
    let id = ParamId::from_name(name)?;
    Some(match (p.get(id), id.kind()) {
        (V::F32(x), _) => Value::Float(x.to_string().parse().unwrap_or(f64::from(x))),
        (V::Code(c), Kind::Code(names)) => Value::Str(names.get(usize::from(c))?.to_string()),
        (V::U8(x) | V::Code(x), _) => Value::Int(i64::from(x)),
        (V::U32(x), _) => Value::Int(i64::from(x)),
    })
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

    #[test]
    fn colours_span_the_scale() {
        assert_eq!(colour(Metric::Success, 0.0), "#d73027");
        assert_eq!(colour(Metric::Success, 1.0), "#1a9850");
        assert_eq!(colour(Metric::Clearance, f64::NAN), "#f7fbff");
    }
}
