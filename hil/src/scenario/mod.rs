//! The scenario schema: a TOML file describing one run (vehicles, obstacles, sonar, navigation,
//! current, faults and the planner's parameters), parsed and validated into a plain
//! [`Scenario`].
//!
//! Every refusal is a [`ScenarioError`] naming the file, the line and the key path of the
//! offending key or value, e.g. `u_trap.toml:12: key `obstacle[2].radius`: must be > 0, got -1`.
//! The schema is documented in `hil/scenarios/README.md`.
//!
//! The document is parsed with `toml`'s span-preserving [`DeTable`] and walked by hand rather
//! than through serde, so that every message can carry the key path and the line, and so that
//! unknown keys are refused everywhere.
//!
//! - `schema.rs`: the validated scenario's types;
//! - `reader.rs`: errors naming file, line and key path; spans; typed access to tables and
//!   values, unknown keys refused with a "did you mean" hint (shared with the sweep spec);
//! - `build.rs`: the tables, key by key, built into a [`Scenario`] with every range checked;
//! - `mission.rs`: a vehicle's waypoint mission.

use std::path::Path;

use toml::de::{DeTable, DeValue};
use vpf::Params;

pub use vpf::params::Strategy;

pub use crate::sim::vehicle::Autopilot;
pub use crate::sim::vehicle::ModelKind;

mod mission;
pub use mission::VehicleMission;

/// Largest coordinate accepted for a position, m (the firmware's `MAX_POSITION_M`).
pub const MAX_POSITION_M: f64 = vpf::sonar::MAX_POSITION_M as f64;
/// Most vehicles in a scenario: each firmware tracks at most `vpf::world::MAX_AGENTS` others.
pub const MAX_VEHICLES: usize = vpf::world::MAX_AGENTS + 1;
/// Longest scenario, s (a day: anything longer is surely a unit error).
pub const MAX_DURATION_S: f64 = 86_400.0;
/// How many times the firmware's obstacle table (`vpf::world::MAX_OBSTACLES`) a scenario may
/// hold in true obstacles. The firmware sees only what its sonar or contacts show nearby, so a
/// world may well hold more than its table; but every obstacle costs every sonar ray, every
/// period, and the plot, and a world far past this is a generator gone wrong.
pub const OBSTACLE_FACTOR: usize = 16;
/// Most obstacles in a scenario: [`OBSTACLE_FACTOR`] × the firmware's table (512).
pub const MAX_OBSTACLES: usize = OBSTACLE_FACTOR * vpf::world::MAX_OBSTACLES;
/// Longest scenario or vehicle name, in characters. Names become directory and file names
/// (made file-safe by `output::file_stem`, one byte per character, plus a `-<time>` suffix),
/// and file systems refuse names past 255 bytes.
pub const MAX_NAME_CHARS: usize = 200;
/// Largest scenario file, bytes: far past any hand-written or generated world within
/// [`MAX_OBSTACLES`], and refused before it is parsed, so a runaway file costs nothing.
pub const MAX_SCENARIO_BYTES: usize = 4 << 20;

mod build;
mod reader;
mod schema;

use build::*;
pub use reader::ScenarioError;
pub(crate) use reader::*;
pub use schema::*;

// ---------------------------------------------------------------------------------------------
// Entry points.

/// Reads and validates the scenario file at `path`. Errors name the file as `path` displays.
pub fn load(path: &Path) -> Result<Scenario, ScenarioError> {
    let file = path.display().to_string();
    // Refuse a huge file before reading it (`parse` checks the text's length again).
    if let Ok(m) = std::fs::metadata(path) {
        if m.len() > MAX_SCENARIO_BYTES as u64 {
            return Err(too_big(&file, m.len()));
        }
    }
    match std::fs::read_to_string(path) {
        Ok(text) => parse(&text, &file),
        Err(e) => Err(ScenarioError {
            file,
            line: 0,
            column: None,
            key: String::new(),
            message: format!("cannot read the scenario: {e}"),
        }),
    }
}

/// Parses and validates scenario `text`; `file` is the name used in errors.
pub fn parse(text: &str, file: &str) -> Result<Scenario, ScenarioError> {
    if text.len() > MAX_SCENARIO_BYTES {
        return Err(too_big(file, text.len() as u64));
    }
    let src = SourceText { file, text };
    let doc = DeTable::parse(text).map_err(|e| src.syntax(&e))?;
    let root = Table::new(src, String::new(), 0..0, doc.get_ref());
    build(&root)
}

fn too_big(file: &str, bytes: u64) -> ScenarioError {
    ScenarioError {
        file: file.to_string(),
        line: 0,
        column: None,
        key: String::new(),
        message: format!(
            "the scenario is {bytes} bytes; at most {MAX_SCENARIO_BYTES} (a scenario holds at \
             most {MAX_OBSTACLES} obstacles)"
        ),
    }
}

/// A name that will become a directory or file name: not blank, at most [`MAX_NAME_CHARS`].
fn check_name(name: &Located<'_, &str>) -> Result<(), ScenarioError> {
    if name.v.trim().is_empty() {
        return Err(name.fail("must not be empty"));
    }
    let n = name.v.chars().count();
    if n > MAX_NAME_CHARS {
        return Err(name.fail(format!(
            "{n} characters; at most {MAX_NAME_CHARS} (names become directory and file names)"
        )));
    }
    Ok(())
}

/// Parses a parameter file — a document holding only a `[planner]` table, with the keys and
/// checks of a scenario's `[planner]` (the recipes `hil sweep` writes) — into the parameters
/// it gives (`Params::default()` with its overrides) at planner period `dt_s`. Errors name
/// `file`, the line and the key, as for a scenario.
pub fn parse_planner(text: &str, file: &str, dt_s: f64) -> Result<Params, ScenarioError> {
    let src = SourceText { file, text };
    let doc = DeTable::parse(text).map_err(|e| src.syntax(&e))?;
    let root = Table::new(src, String::new(), 0..0, doc.get_ref());
    root.allow(&["planner"], "a parameter file (only a [planner] table)")?;
    let dt = Located {
        v: dt_s,
        span: 0..0,
        key: "dt_s".into(),
        src,
    };
    planner(&root, &dt)
}
