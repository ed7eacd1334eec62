//! The parameter sets: the grid's combinations (the last parameter varying fastest) or the
//! random draws (seeded, rounded to 3 significant digits), each checked by the scenario
//! parser's `[planner]` rules, and the sweep's size held to [`MAX_RUNS`].

use super::{Axis, Mode, Spec, Value, CHECK_DT_S, MAX_RUNS, MAX_SETS};
use crate::scenario::{At, ScenarioError};
use crate::sim::Rng;

/// 3 significant digits (random draws stay readable, and the CSV, the recipe and the firmware
/// see the same number).
fn round3(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let mag = 10f64.powi(x.abs().log10().floor() as i32 - 2);
    let r = (x / mag).round() * mag;
    // Print-stable: through the shortest decimal spelling.
    format!("{r:.12}").parse::<f64>().unwrap_or(r)
}

/// Refuses a sweep of more than [`MAX_RUNS`] runs, naming the product.
/// `scenarios_at` is the `[scenarios]` table, where the refusal is reported.
pub(super) fn check_runs(spec: &Spec, scenarios_at: &At<'_>) -> Result<(), ScenarioError> {
    let sets = spec.sets.len();
    let scenarios = spec.scenarios.count();
    match sets.checked_mul(scenarios) {
        Some(runs) if runs <= MAX_RUNS => Ok(()),
        runs => Err(scenarios_at.refuse(format!(
            "{sets} parameter sets × {scenarios} scenarios = {} runs; at most {MAX_RUNS} \
                 (fewer sets, or fewer scenarios)",
            runs.map_or_else(|| "too many".to_string(), |r| r.to_string())
        ))),
    }
}

/// The parameter sets: the grid's combinations, or the random draws. `sweep` is the `[sweep]`
/// table, where a grid too large is reported.
pub(super) fn expand(spec: &Spec, sweep: &At<'_>) -> Result<Vec<Vec<Value>>, ScenarioError> {
    match spec.mode {
        Mode::Grid => {
            let lists: Vec<&Vec<Value>> = spec
                .params
                .iter()
                .filter_map(|p| match &p.axis {
                    Axis::List(v) => Some(v),
                    Axis::Range { .. } => None,
                })
                .collect();
            let total = lists
                .iter()
                .try_fold(1usize, |acc, l| acc.checked_mul(l.len()))
                .filter(|n| *n <= MAX_SETS);
            let Some(total) = total else {
                return Err(sweep.fail(
                    "params",
                    &sweep.span,
                    format!("the grid has more than {MAX_SETS} parameter sets"),
                ));
            };
            let mut sets = Vec::with_capacity(total);
            for mut i in 0..total {
                let mut set = vec![Value::Int(0); lists.len()];
                for (j, l) in lists.iter().enumerate().rev() {
                    set[j] = l[i % l.len()].clone();
                    i /= l.len();
                }
                sets.push(set);
            }
            Ok(sets)
        }
        Mode::Random { samples } => Ok((0..samples)
            .map(|i| {
                let mut rng = Rng::stream(spec.seed, 0x5E75 + i as u64);
                spec.params
                    .iter()
                    .map(|p| match &p.axis {
                        Axis::List(v) => {
                            let k = ((rng.uniform() * v.len() as f64) as usize).min(v.len() - 1);
                            v[k].clone()
                        }
                        Axis::Range {
                            min,
                            max,
                            log,
                            integer,
                        } => {
                            let u = rng.uniform();
                            if *integer {
                                let span = (max - min + 1.0).max(1.0);
                                Value::Int((min + (u * span).floor()).min(*max) as i64)
                            } else if *log {
                                Value::Float(round3((min.ln() + u * (max.ln() - min.ln())).exp()))
                            } else {
                                Value::Float(round3(min + u * (max - min)))
                            }
                        }
                    })
                    .collect()
            })
            .collect()),
    }
}

/// Every set must pass the scenario parser's `[planner]` checks; a refusal is reported at the
/// swept parameter it names (or at the first swept parameter), with the set's values.
pub(super) fn check_sets(spec: &Spec) -> Result<(), ScenarioError> {
    for i in 0..spec.sets.len() {
        if let Err(e) = spec.params_of(i, CHECK_DT_S) {
            let named = e.key.strip_prefix("planner.").unwrap_or(&e.key);
            let p = spec
                .params
                .iter()
                .find(|p| p.name == named)
                .unwrap_or(&spec.params[0]);
            let values: Vec<String> = spec
                .params
                .iter()
                .zip(&spec.sets[i])
                .map(|(p, v)| format!("{} = {}", p.name, v.toml()))
                .collect();
            return Err(ScenarioError {
                file: spec.file.clone(),
                line: p.line,
                column: None,
                key: format!("sweep.params.{}", p.name),
                message: format!(
                    "parameter set {i} ({}) is refused: {}",
                    values.join(", "),
                    e.message
                ),
            });
        }
    }
    Ok(())
}
