//! The ranking as text: `ranking.md` (the criterion's top of the table and each parameter's
//! influence) and the top of the table for the terminal.

use std::fmt::Write as _;

use super::{families, fixed, symbol, Context, Report};
use crate::sweep::spec::Spec;

impl Report {
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
