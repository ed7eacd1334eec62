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
//! - `reader.rs`: the spanned document walked table by table, with the spec's range-checked
//!   reads;
//! - `tables.rs`: each table of the file read and checked (`[craft]`, `[planner]`, `[sweep]`,
//!   `[scenarios]`, `[criterion]`);
//! - `sets.rs`: the parameter sets — the grid's combinations or the random draws — and their
//!   checks.

use toml::de::DeTable;

mod reader;
mod schema;
mod sets;
mod tables;

pub use schema::*;

use crate::scenario::{ScenarioError, SourceText};
use reader::{SpecReads, Table};

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
    let doc = DeTable::parse(text).map_err(|e| src.syntax(&e))?;
    let root = Table::new(src, String::new(), 0..0, doc.get_ref());
    root.allow(
        &[
            "name",
            "description",
            "seed",
            "craft",
            "planner",
            "sweep",
            "scenarios",
            "criterion",
        ],
        "the sweep file",
    )?;
    let name = root.text("name")?.ok_or_else(|| root.missing("name"))?;
    if name.trim().is_empty() {
        let v = root.get("name").map_or(0..0, |v| v.span());
        return Err(src.err(&v, "name", "must not be empty"));
    }
    let description = root.text("description")?.unwrap_or_default().to_string();
    let seed = root
        .int_in("seed", 0, i64::MAX)?
        .ok_or_else(|| root.missing("seed"))? as u64;

    let craft = tables::craft(&root)?;
    let base = tables::base_planner(&root, src)?;
    let (mode, params, heatmap) = tables::sweep(&root, &base)?;
    let scenarios = tables::scenarios(&root)?;
    let weights = tables::criterion(&root)?;

    let mut spec = Spec {
        file: file.to_string(),
        text: text.to_string(),
        name: name.to_string(),
        description,
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
    spec.sets = sets::expand(&spec, &root)?;
    sets::check_runs(&spec, &root)?;
    sets::check_sets(&spec)?;
    Ok(spec)
}
