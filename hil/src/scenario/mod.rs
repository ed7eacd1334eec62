//! The scenario schema: a TOML file describing one run (vehicles, obstacles, sonar, navigation,
//! current, faults and the planner's parameters), parsed and validated into a plain
//! [`Scenario`].
//!
//! Every refusal is a [`ScenarioError`] naming the file, the line and the key path of the
//! offending key or value, e.g. ``u_trap.toml:12: key `obstacle[2].radius`: must be > 0, got -1``.
//! The schema is documented in `hil/scenarios/README.md`.
//!
//! The document is read by serde into the file's tables (`file.rs`: every key spanned, unknown
//! keys refused), then built into a [`Scenario`] with every range and cross-reference checked
//! at its key.
//!
//! - `schema.rs`: the validated scenario's types;
//! - `error.rs`: refusals naming file, line and key path, and the places they are reported at;
//! - `file.rs`: the file's tables as serde reads them; `values.rs`: its leaf values (numbers,
//!   pairs, lists) and their range checks; `refusal.rs`: serde's refusals in the schema's words
//!   (key path from the span, "did you mean" hints). The sweep spec (`crate::sweep::spec`) is
//!   read with the same three and `read`;
//! - `build.rs`: the document built into a [`Scenario`]; `planner.rs`: the `[planner]` table,
//!   its keys from the library's parameter declaration; `obstacle.rs`, `vehicle.rs`,
//!   `mission.rs`: an obstacle, a vehicle, a vehicle's waypoint mission.

use std::path::Path;

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
mod error;
mod file;
mod obstacle;
mod planner;
mod refusal;
mod schema;
mod values;
mod vehicle;

pub(crate) use error::At;
pub use error::ScenarioError;
pub(crate) use error::SourceText;
pub(crate) use file::Opt;
pub(crate) use refusal::{closest, unknown_key};
pub(crate) use refusal::{keys_of, Naming, Seg};
use refusal::{refusal, unknown_choice};
pub use schema::*;
pub(crate) use values::{int_within, Int, Item, Items, Num, Table};

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
    let f: file::ScenarioFile = read(src, &file::naming("the scenario"))?;
    build::build(&At::root(src), &f)
}

/// Reads `src` as a `T` (its syntax, types and keys), each refusal at its key, its tables
/// named by `naming`. (The sweep spec's reader too.)
pub(crate) fn read<T: serde::de::DeserializeOwned>(
    src: SourceText<'_>,
    naming: &Naming,
) -> Result<T, ScenarioError> {
    let doc = toml::de::DeTable::parse(src.text).map_err(|e| src.syntax(&e))?;
    T::deserialize(toml::de::Deserializer::from(doc)).map_err(|e| refusal(src, &e, naming))
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

/// Parses a parameter file — a document holding only a `[planner]` table, with the keys and
/// checks of a scenario's `[planner]` (the recipes `hil sweep` writes) — into the parameters
/// it gives (`Params::default()` with its overrides) at planner period `dt_s`. Errors name
/// `file`, the line and the key, as for a scenario.
pub fn parse_planner(text: &str, file: &str, dt_s: f64) -> Result<Params, ScenarioError> {
    let src = SourceText { file, text };
    let f: file::ParamFile = read(
        src,
        &file::naming("a parameter file (only a [planner] table)"),
    )?;
    planner::planner(&At::root(src), &f.planner, dt_s, &(0..0))
}
