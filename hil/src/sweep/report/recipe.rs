//! `recipe.toml`: the recommended set as a `[planner]` table that `hil run --params` takes,
//! with where it came from.

use std::fmt::Write as _;

use super::{families, fixed, Context, Report, METHOD_INDEPENDENT};
use crate::sweep::spec::{Spec, Value};

impl Report {
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
        if let Ok(p) = spec.params_of(b.set, crate::sweep::spec::CHECK_DT_S) {
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
