//! The sweep file (`hil/sweeps/*.toml`): which parameters to vary and how, over which
//! scenarios, for which craft, and the criterion's weights. Parsed and validated into a
//! [`Spec`]; every refusal is a [`ScenarioError`] naming the file, the line and the key path,
//! exactly as the scenario parser does (`videoray.toml:14: key `sweep.params.a_plus`: ...`).
//!
//! The fixed `[planner]` table and every parameter set are checked by the scenario parser's own
//! `[planner]` rules ([`scenario::parse_planner`](crate::scenario::parse_planner)), so a sweep accepts exactly the keys and
//! values a scenario does. The format is documented in `hil/sweeps/README.md`.
//!
//! - `schema.rs`: the validated spec's types;
//! - `file.rs`: the file's tables as serde reads them (the scenario reader's values and
//!   refusals: file, line, key path, "did you mean");
//! - `tables.rs`: each table of the file read and checked (`[craft]`, `[planner]`, `[sweep]`,
//!   `[scenarios]`, `[criterion]`);
//! - `sets.rs`: the parameter sets — the grid's combinations or the random draws — and their
//!   checks.

mod file;
mod schema;
mod sets;
mod tables;

pub use schema::*;

use crate::scenario::{self, int_within, At, ScenarioError, SourceText};

/// The planner period the parameter sets are checked at, s (every generated scenario uses it;
/// a scenario file's own `dt_s` replaces it at run time).
pub const CHECK_DT_S: f64 = 0.1;

/// Most parameter sets a sweep may have (a guard against a grid that multiplies out by
/// mistake).
pub const MAX_SETS: usize = 100_000;

/// Most runs a sweep may hold (parameter sets × scenarios), refused before any scenario is
/// generated or any run allocated: each factor has its own cap, but their product could ask
/// for billions (this cap is about 35 min on two cores at 50 runs/s). `hil bench` has the same
/// cap (`crate::bench::MAX_RUNS`).
pub const MAX_RUNS: usize = 100_000;

/// Reads and validates the sweep file at `path`.
pub fn load(path: &std::path::Path) -> Result<Spec, ScenarioError> {
    let file = path.display().to_string();
    match std::fs::read_to_string(path) {
        Ok(text) => parse(&text, &file),
        Err(e) => Err(ScenarioError {
            file,
            line: 0,
            column: None,
            key: String::new(),
            message: format!("cannot read the sweep file: {e}"),
        }),
    }
}

/// Parses and validates sweep `text`; `file` names it in errors.
pub fn parse(text: &str, file: &str) -> Result<Spec, ScenarioError> {
    let src = SourceText { file, text };
    let f: file::SpecFile = scenario::read(src, &file::naming)?;
    let root = At::root(src);
    let name = root.req("name", &f.name)?;
    if name.get_ref().trim().is_empty() {
        return Err(root.fail("name", &name.span(), "must not be empty"));
    }
    let description = f.description.as_ref().map_or("", |d| d.get_ref());
    let seed = int_within(&root, "seed", root.req("seed", &f.seed)?, 0, i64::MAX)? as u64;

    let craft = tables::craft(&root, &f.craft)?;
    let base = tables::base_planner(src, &f.planner)?;
    let (mode, params, heatmap) = tables::sweep(&root, &f.sweep, &base)?;
    let scenarios = tables::scenarios(&root, &f.scenarios)?;
    let weights = tables::criterion(&root, &f.criterion)?;

    let mut spec = Spec {
        file: file.to_string(),
        text: text.to_string(),
        name: name.get_ref().clone(),
        description: description.to_string(),
        seed,
        craft,
        base,
        mode,
        params,
        heatmap,
        scenarios,
        weights,
        sets: Vec::new(),
    };
    // The sizes are refused at their tables' headers (both are required, so present).
    let span_of = |t: Option<std::ops::Range<usize>>| t.unwrap_or(0..0);
    let sweep_at = root.child("sweep", span_of(f.sweep.as_ref().map(|t| t.span())));
    spec.sets = sets::expand(&spec, &sweep_at)?;
    let scenarios_span = span_of(f.scenarios.as_ref().map(|t| t.span()));
    sets::check_runs(&spec, &root.child("scenarios", scenarios_span))?;
    sets::check_sets(&spec)?;
    Ok(spec)
}
