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

use std::fmt;
use std::ops::Range;
use std::path::Path;

use toml::de::{DeTable, DeValue};
use toml::Spanned;
use vpf::field::shape::{MAX_EXTENT_M, MIN_EXTENT_M};
use vpf::field::{Shape, MAX_POLYGON_VERTICES};
use vpf::params::{Kind, ParamId, Value, PARAM_NAMES};
use vpf::planner::Formation;
use vpf::Params;

pub use vpf::params::Strategy;

pub use crate::sim::vehicle::Autopilot;
pub use crate::sim::vehicle::ModelKind;
use crate::types::{SimObstacle, SimShape, P2};

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

// ---------------------------------------------------------------------------------------------
// The validated scenario.

/// A validated scenario: plain data, SI units, angles in radians.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    /// Name, for logs and plots.
    pub name: String,
    /// Simulated time, s. `dt_s ..= 86400`.
    pub duration_s: f64,
    /// The planner period and the simulation step, s. `0.02 ..= 1`. Equal to `params.period_s`.
    pub dt_s: f64,
    /// Seed of the simulation's noise and faults.
    pub seed: u64,
    /// Lock-step (as fast as possible, deterministic) or real time.
    pub mode: RunMode,
    /// The planner's parameters: `Params::default()` with the `[planner]` overrides and
    /// `period_s = dt_s`, validated. The strategy the firmware runs is `params.strategy`.
    pub params: Params,
    /// The vehicles, in file order (at least one, at most [`MAX_VEHICLES`]).
    pub vehicles: Vec<Vehicle>,
    /// The obstacles (true geometry at t = 0), in file order.
    pub obstacles: Vec<SimObstacle>,
    /// The simulated sonar.
    pub sonar: Sonar,
    /// Navigation (position/heading) noise and rate.
    pub navigation: Navigation,
    /// Ocean current.
    pub current: Current,
    /// Injected link and sensor faults.
    pub faults: Faults,
}

/// How the runner paces the simulation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RunMode {
    /// Step as fast as the firmware answers; deterministic (the default).
    #[default]
    Lockstep,
    /// One step per `dt_s` of wall-clock time.
    Realtime,
}

/// How a vehicle's firmware learns about obstacles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Sensing {
    /// Raw sonar scanlines; the firmware extracts the obstacles itself.
    #[default]
    Sonar,
    /// Ready-made obstacle contacts (the truth within sonar range), as the seeds' charted
    /// obstacles.
    Contacts,
}

/// One vehicle.
#[derive(Clone, Debug, PartialEq)]
pub struct Vehicle {
    /// Unique name.
    pub name: String,
    /// Vehicle model.
    pub model: ModelKind,
    /// Start position, m.
    pub start: P2,
    /// Start heading, rad (counter-clockwise from +x).
    pub heading: f64,
    /// Goal-point, m: the last waypoint of a waypoint mission.
    pub goal: P2,
    /// A waypoint mission (`waypoints` or `survey`), if any; `None`: the single `goal`.
    pub mission: Option<VehicleMission>,
    /// Formation request, if any (orientation in rad).
    pub formation: Option<Formation>,
    /// How it senses obstacles.
    pub sensing: Sensing,
    /// What its autopilots track: the heading and speed set-points (the default), or seed
    /// 001's PI-D set-point decomposition.
    pub autopilot: Autopilot,
}

/// What the simulated sonar sends.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SonarMode {
    /// Raw scanlines of a mechanically scanned sonar (the default).
    #[default]
    Scanlines,
    /// Obstacle contacts.
    Contacts,
}

/// The simulated sonar.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sonar {
    /// Default sensing of the vehicles.
    pub mode: SonarMode,
    /// Range, m. 0.5 ..= 200; default 30.
    pub range_m: f64,
    /// Bins per scanline. 1 ..= 512; default 300.
    pub bins: u16,
    /// Head step, rad (default 1.8°).
    pub step: f64,
    /// Background noise level, 0 ..= 1; default 0.2 (a mean of 6 on the 0–255 scale).
    pub noise: f64,
    /// Speckle (one-bin spike) probability per bin, 0 ..= 1; default 0.002.
    pub speckle: f64,
    /// Rays across the 3° beam, 1 ..= 32; default 5 (1 is an ideal pencil beam).
    pub beam_rays: usize,
    /// Probability per ping of a spurious target echo (fish, a side lobe), 0 ..= 1; default
    /// 0.03.
    pub false_echoes: f64,
    /// With scanlines, the other vehicles also come as vehicle contacts (an acoustic
    /// positioning system, or a sonar that classifies them): seed 001's virtual leader takes the
    /// neighbours' positions as known. Default false: the vehicles see each other only through
    /// their sonars.
    pub vehicle_contacts: bool,
    /// How the scanlines reach the firmware: `Scanline` messages on the main link (default), or
    /// a simulated Ping360 on a port of its own that the firmware drives.
    pub interface: SonarInterface,
}

/// How a vehicle's sonar data reaches its firmware.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SonarInterface {
    /// `Scanline` messages on the main link (a sonar handled elsewhere).
    #[default]
    Link,
    /// A simulated Blue Robotics Ping360 on its own pty, answering the firmware's `transducer`
    /// commands with `device_data` (`crate::ping360::sim`): `bins` is its number of samples
    /// (200 ..= 512 here), `step_deg` a whole number of gradians (0.9° each, 1 ..= 12), the
    /// range sets the sample period.
    Ping360,
}

impl Default for Sonar {
    fn default() -> Self {
        Sonar {
            mode: SonarMode::Scanlines,
            range_m: 30.0,
            bins: 300,
            step: 1.8f64.to_radians(),
            noise: 0.2,
            speckle: 0.002,
            beam_rays: 5,
            false_echoes: 0.03,
            vehicle_contacts: false,
            interface: SonarInterface::Link,
        }
    }
}

/// Navigation (the vehicle's own position and heading) as the firmware receives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Navigation {
    /// Standard deviation of the position noise, m. 0 ..= 100; default 0.
    pub position_sigma_m: f64,
    /// Standard deviation of the heading noise, rad (default 0).
    pub heading_sigma: f64,
    /// Navigation frame rate, Hz. 0.1 ..= 1000; defaults to `1 / dt_s` (10 here, the rate at
    /// the default period).
    pub rate_hz: f64,
}

impl Default for Navigation {
    fn default() -> Self {
        Navigation {
            position_sigma_m: 0.0,
            heading_sigma: 0.0,
            rate_hz: 10.0,
        }
    }
}

/// A uniform, constant ocean current.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Current {
    /// Velocity over ground, m/s. |v| ≤ 5.
    pub velocity: P2,
}

/// A time window `[from_s, to_s)` of the run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Window {
    /// Start, s.
    pub from_s: f64,
    /// End, s (> `from_s`).
    pub to_s: f64,
}

impl Window {
    /// Whether simulation time `t` (s) falls in the window.
    pub fn contains(&self, t: f64) -> bool {
        t >= self.from_s && t < self.to_s
    }
}

/// Injected faults. All default to none.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Faults {
    /// Probability that a bit on the serial link is flipped. 0 ..= 0.01.
    pub bit_error_rate: f64,
    /// Probability that a whole frame is dropped. 0 ..= 1.
    pub drop_rate: f64,
    /// Extra delay of navigation frames, ms. 0 ..= 10000.
    pub nav_delay_ms: f64,
    /// Navigation frames repeat the last value (frozen) in this window.
    pub nav_freeze: Option<Window>,
    /// No navigation frames at all in this window.
    pub nav_loss: Option<Window>,
    /// No sonar data in this window.
    pub sonar_dropout: Option<Window>,
    /// Bit-error rate on the simulated Ping360's port (harness → firmware), 0 ..= 0.01. The
    /// two rates above apply to the main link only.
    pub ping360_bit_error_rate: f64,
    /// Probability that a whole `device_data` frame to the firmware is dropped, 0 ..= 1.
    pub ping360_drop_rate: f64,
}

// ---------------------------------------------------------------------------------------------
// Errors.

/// A refused scenario: where and why.
///
/// Displays as `FILE:LINE: key `KEY`: MESSAGE`. Errors that are not about one key (TOML syntax
/// errors, unreadable files) display as `FILE:LINE:COLUMN: MESSAGE` and `FILE: MESSAGE`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScenarioError {
    /// The file name as given to [`load`] or [`parse`].
    pub file: String,
    /// 1-based line of the offending key or value (of the table header for a missing key);
    /// 0 when there is no line (the file could not be read).
    pub line: usize,
    /// 1-based column, for TOML syntax errors only.
    pub column: Option<usize>,
    /// Key path, e.g. `obstacle[2].radius` (array indices 0-based, in file order); empty for
    /// errors not about a key.
    pub key: String,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.line, self.column, self.key.is_empty()) {
            (0, _, _) => write!(f, "{}: {}", self.file, self.message),
            (line, _, false) => write!(
                f,
                "{}:{}: key `{}`: {}",
                self.file, line, self.key, self.message
            ),
            (line, Some(col), true) => {
                write!(f, "{}:{}:{}: {}", self.file, line, col, self.message)
            }
            (line, None, true) => write!(f, "{}:{}: {}", self.file, line, self.message),
        }
    }
}

impl std::error::Error for ScenarioError {}

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

// ---------------------------------------------------------------------------------------------
// Source positions.

/// A TOML text and its file name, for errors that name file, line and key (shared with the
/// sweep spec parser, `crate::sweep::spec`).
#[derive(Clone, Copy)]
pub(crate) struct SourceText<'a> {
    pub(crate) file: &'a str,
    pub(crate) text: &'a str,
}

impl SourceText<'_> {
    pub(crate) fn line_of(&self, offset: usize) -> usize {
        let end = offset.min(self.text.len());
        1 + self.text.as_bytes()[..end]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
    }

    fn column_of(&self, offset: usize) -> usize {
        let end = offset.min(self.text.len());
        let bytes = &self.text.as_bytes()[..end];
        let line_start = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        // Count characters, not bytes (UTF-8 continuation bytes are 0b10xx_xxxx).
        1 + bytes[line_start..]
            .iter()
            .filter(|&&b| b & 0xC0 != 0x80)
            .count()
    }

    pub(crate) fn err(
        &self,
        span: &Range<usize>,
        key: &str,
        message: impl Into<String>,
    ) -> ScenarioError {
        ScenarioError {
            file: self.file.to_string(),
            line: self.line_of(span.start),
            column: None,
            key: key.to_string(),
            message: message.into(),
        }
    }

    pub(crate) fn syntax(&self, e: &toml::de::Error) -> ScenarioError {
        let at = e.span().map_or(0, |s| s.start);
        ScenarioError {
            file: self.file.to_string(),
            line: self.line_of(at),
            column: Some(self.column_of(at)),
            key: String::new(),
            message: format!("TOML syntax error: {}", e.message()),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Typed access to the spanned document.

pub(crate) type Val<'a> = Spanned<DeValue<'a>>;

/// One value with its key path and span, for checks that report it.
struct Located<'a, T> {
    v: T,
    span: Range<usize>,
    key: String,
    src: SourceText<'a>,
}

impl<T> Located<'_, T> {
    fn fail(&self, message: impl Into<String>) -> ScenarioError {
        self.src.err(&self.span, &self.key, message)
    }
}

impl Located<'_, f64> {
    /// `lo ..= hi`.
    fn within(&self, lo: f64, hi: f64, unit: &str) -> Result<f64, ScenarioError> {
        if (lo..=hi).contains(&self.v) {
            Ok(self.v)
        } else {
            Err(self.fail(format!(
                "must be in {lo} ..= {hi}{}, got {}",
                unit_suffix(unit),
                self.v
            )))
        }
    }

    /// A size of a shape: > 0, and within the firmware's shape limits.
    fn size(&self) -> Result<f64, ScenarioError> {
        if self.v <= 0.0 {
            return Err(self.fail(format!("must be > 0, got {}", self.v)));
        }
        self.within(f64::from(MIN_EXTENT_M), f64::from(MAX_EXTENT_M), "m")
    }
}

fn unit_suffix(unit: &str) -> String {
    if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    }
}

pub(crate) fn type_name(v: &DeValue<'_>) -> &'static str {
    match v {
        DeValue::String(_) => "a string",
        DeValue::Integer(_) => "an integer",
        DeValue::Float(_) => "a float",
        DeValue::Boolean(_) => "a boolean",
        DeValue::Datetime(_) => "a date-time",
        DeValue::Array(_) => "an array",
        DeValue::Table(_) => "a table",
    }
}

fn join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

/// A table of the document with its key path and the span of its header (shared with the
/// sweep spec parser, which adds its own range-checked readers).
pub(crate) struct Table<'a> {
    pub(crate) src: SourceText<'a>,
    pub(crate) path: String,
    pub(crate) span: Range<usize>,
    /// (key, key span, value), in file order.
    pub(crate) entries: Vec<(&'a str, Range<usize>, &'a Val<'a>)>,
}

impl<'a> Table<'a> {
    pub(crate) fn new(
        src: SourceText<'a>,
        path: String,
        span: Range<usize>,
        t: &'a DeTable<'a>,
    ) -> Self {
        let mut entries: Vec<_> = t
            .iter()
            .map(|(k, v)| (k.get_ref().as_ref(), k.span(), v))
            .collect();
        // The map is sorted by name; file order makes "the first error" the first in the file.
        entries.sort_by_key(|e| e.1.start);
        Table {
            src,
            path,
            span,
            entries,
        }
    }

    pub(crate) fn key(&self, key: &str) -> String {
        join(&self.path, key)
    }

    pub(crate) fn get(&self, key: &str) -> Option<&'a Val<'a>> {
        self.entries.iter().find(|e| e.0 == key).map(|e| e.2)
    }

    pub(crate) fn span_of(&self, key: &str) -> Range<usize> {
        self.entries
            .iter()
            .find(|e| e.0 == key)
            .map_or(self.span.clone(), |e| e.1.clone())
    }

    fn has(&self, key: &str) -> bool {
        self.get(key).is_some()
    }

    /// Refuses any key not in `allowed`; `what` names the table in the message.
    pub(crate) fn allow(&self, allowed: &[&str], what: &str) -> Result<(), ScenarioError> {
        for (k, span, _) in &self.entries {
            if allowed.contains(k) {
                continue;
            }
            let hint = match closest(k, allowed) {
                Some(c) => format!(" (did you mean `{c}`?)"),
                None => format!(" (expected one of: {})", allowed.join(", ")),
            };
            return Err(self
                .src
                .err(span, &self.key(k), format!("unknown key in {what}{hint}")));
        }
        Ok(())
    }

    pub(crate) fn missing(&self, key: &str) -> ScenarioError {
        self.src
            .err(&self.span, &self.key(key), "missing required key")
    }

    fn got<T>(&self, key: &str, v: T, span: Range<usize>) -> Located<'a, T> {
        Located {
            v,
            span,
            key: self.key(key),
            src: self.src,
        }
    }

    fn number(&self, key: &str) -> Result<Option<Located<'a, f64>>, ScenarioError> {
        self.get(key)
            .map(|v| value_number(self.src, &self.key(key), v).map(|x| self.got(key, x, v.span())))
            .transpose()
    }

    fn req_number(&self, key: &str) -> Result<Located<'a, f64>, ScenarioError> {
        self.number(key)?.ok_or_else(|| self.missing(key))
    }

    fn integer(&self, key: &str) -> Result<Option<Located<'a, i64>>, ScenarioError> {
        self.get(key)
            .map(|v| value_integer(self.src, &self.key(key), v).map(|x| self.got(key, x, v.span())))
            .transpose()
    }

    fn string(&self, key: &str) -> Result<Option<Located<'a, &'a str>>, ScenarioError> {
        self.get(key)
            .map(|v| match v.get_ref() {
                DeValue::String(s) => Ok(self.got(key, s.as_ref(), v.span())),
                other => Err(self.src.err(
                    &v.span(),
                    &self.key(key),
                    format!("expected a string, got {}", type_name(other)),
                )),
            })
            .transpose()
    }

    fn boolean(&self, key: &str) -> Result<Option<bool>, ScenarioError> {
        self.get(key)
            .map(|v| match v.get_ref() {
                DeValue::Boolean(b) => Ok(*b),
                other => Err(self.src.err(
                    &v.span(),
                    &self.key(key),
                    format!("expected true or false, got {}", type_name(other)),
                )),
            })
            .transpose()
    }

    fn req_string(&self, key: &str) -> Result<Located<'a, &'a str>, ScenarioError> {
        self.string(key)?.ok_or_else(|| self.missing(key))
    }

    /// A pair `[x, y]` of finite numbers.
    fn pair(&self, key: &str) -> Result<Option<Located<'a, P2>>, ScenarioError> {
        self.get(key)
            .map(|v| value_pair(self.src, &self.key(key), v).map(|p| self.got(key, p, v.span())))
            .transpose()
    }

    /// A position: a pair within ±[`MAX_POSITION_M`].
    fn position(&self, key: &str) -> Result<Option<Located<'a, P2>>, ScenarioError> {
        let Some(p) = self.pair(key)? else {
            return Ok(None);
        };
        check_position(&p)?;
        Ok(Some(p))
    }

    fn req_position(&self, key: &str) -> Result<Located<'a, P2>, ScenarioError> {
        self.position(key)?.ok_or_else(|| self.missing(key))
    }

    /// A velocity: a pair of at most `max` m/s.
    fn velocity(&self, key: &str, max: f64) -> Result<Option<P2>, ScenarioError> {
        let Some(v) = self.pair(key)? else {
            return Ok(None);
        };
        if v.v.norm() > max {
            return Err(v.fail(format!(
                "speed must be at most {max} m/s, got {}",
                v.v.norm()
            )));
        }
        Ok(Some(v.v))
    }

    /// A time window `[from_s, to_s]` with 0 ≤ from < to.
    fn window(&self, key: &str) -> Result<Option<Window>, ScenarioError> {
        let Some(w) = self.pair(key)? else {
            return Ok(None);
        };
        let (from_s, to_s) = (w.v.x, w.v.y);
        if from_s < 0.0 || to_s <= from_s {
            return Err(w.fail(format!(
                "must be [from_s, to_s] with 0 <= from_s < to_s, got [{from_s}, {to_s}]"
            )));
        }
        Ok(Some(Window { from_s, to_s }))
    }

    pub(crate) fn table(&self, key: &str) -> Result<Option<Table<'a>>, ScenarioError> {
        self.get(key)
            .map(|v| as_table(self.src, self.key(key), v))
            .transpose()
    }

    /// An array of tables (`[[key]]`), each with its indexed path.
    fn tables(&self, key: &str) -> Result<Vec<Table<'a>>, ScenarioError> {
        let Some(v) = self.get(key) else {
            return Ok(Vec::new());
        };
        let DeValue::Array(items) = v.get_ref() else {
            return Err(self.src.err(
                &v.span(),
                &self.key(key),
                format!(
                    "expected an array of tables (`[[{key}]]`), got {}",
                    type_name(v.get_ref())
                ),
            ));
        };
        items
            .iter()
            .enumerate()
            .map(|(i, item)| as_table(self.src, format!("{}[{i}]", self.key(key)), item))
            .collect()
    }
}

fn as_table<'a>(
    src: SourceText<'a>,
    path: String,
    v: &'a Val<'a>,
) -> Result<Table<'a>, ScenarioError> {
    match v.get_ref() {
        DeValue::Table(t) => Ok(Table::new(src, path, v.span(), t)),
        other => Err(src.err(
            &v.span(),
            &path,
            format!("expected a table, got {}", type_name(other)),
        )),
    }
}

pub(crate) fn value_integer(
    src: SourceText<'_>,
    key: &str,
    v: &Val<'_>,
) -> Result<i64, ScenarioError> {
    match v.get_ref() {
        DeValue::Integer(i) => i64::from_str_radix(i.as_str(), i.radix())
            .map_err(|_| src.err(&v.span(), key, format!("integer {i} is too large"))),
        other => Err(src.err(
            &v.span(),
            key,
            format!("expected an integer, got {}", type_name(other)),
        )),
    }
}

/// A finite number; integers are accepted where numbers are expected.
pub(crate) fn value_number(
    src: SourceText<'_>,
    key: &str,
    v: &Val<'_>,
) -> Result<f64, ScenarioError> {
    let x = match v.get_ref() {
        DeValue::Integer(_) => value_integer(src, key, v)? as f64,
        DeValue::Float(f) => f
            .as_str()
            .parse::<f64>()
            .map_err(|_| src.err(&v.span(), key, format!("cannot read number `{f}`")))?,
        other => {
            return Err(src.err(
                &v.span(),
                key,
                format!("expected a number, got {}", type_name(other)),
            ))
        }
    };
    if x.is_finite() {
        Ok(x)
    } else {
        Err(src.err(&v.span(), key, format!("must be a finite number, got {x}")))
    }
}

fn value_pair(src: SourceText<'_>, key: &str, v: &Val<'_>) -> Result<P2, ScenarioError> {
    match v.get_ref() {
        DeValue::Array(a) if a.len() == 2 => {
            let x = value_number(src, &format!("{key}[0]"), &a[0])?;
            let y = value_number(src, &format!("{key}[1]"), &a[1])?;
            Ok(P2::new(x, y))
        }
        DeValue::Array(a) => Err(src.err(
            &v.span(),
            key,
            format!("expected a pair [x, y], got an array of {} items", a.len()),
        )),
        other => Err(src.err(
            &v.span(),
            key,
            format!("expected a pair [x, y], got {}", type_name(other)),
        )),
    }
}

fn check_position(p: &Located<'_, P2>) -> Result<(), ScenarioError> {
    if p.v.x.abs() > MAX_POSITION_M || p.v.y.abs() > MAX_POSITION_M {
        return Err(p.fail(format!(
            "coordinates must be within ±{MAX_POSITION_M} m, got [{}, {}]",
            p.v.x, p.v.y
        )));
    }
    Ok(())
}

/// The allowed key nearest to `key` by edit distance, if it is close enough to be a typo.
fn closest<'k>(key: &str, allowed: &[&'k str]) -> Option<&'k str> {
    allowed
        .iter()
        .map(|a| (edit_distance(key, a), *a))
        .filter(|&(d, a)| d <= 2.max(a.len() / 4))
        .min_by_key(|&(d, _)| d)
        .map(|(_, a)| a)
}

fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != cb)).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}

/// Matches a string value against `(name, value)` choices.
fn choose<T: Copy>(
    s: &Located<'_, &str>,
    choices: &[(&str, T)],
    what: &str,
) -> Result<T, ScenarioError> {
    if let Some(&(_, t)) = choices.iter().find(|c| c.0 == s.v) {
        return Ok(t);
    }
    let names: Vec<String> = choices.iter().map(|c| format!("\"{}\"", c.0)).collect();
    Err(s.fail(format!(
        "unknown {what} \"{}\" (expected {})",
        s.v,
        names.join(" or ")
    )))
}

// ---------------------------------------------------------------------------------------------
// The schema.

const ROOT_KEYS: &[&str] = &[
    "name",
    "duration_s",
    "dt_s",
    "seed",
    "mode",
    "planner",
    "vehicle",
    "obstacle",
    "sonar",
    "navigation",
    "current",
    "faults",
];

fn build(root: &Table<'_>) -> Result<Scenario, ScenarioError> {
    root.allow(ROOT_KEYS, "the scenario")?;

    let name = root.req_string("name")?;
    check_name(&name)?;
    let dt = root.req_number("dt_s")?;
    let dt_s = dt.within(0.02, 1.0, "s")?;
    let duration = root.req_number("duration_s")?;
    let duration_s = duration.within(dt_s, MAX_DURATION_S, "s (at least dt_s)")?;
    let seed = root.integer("seed")?.ok_or_else(|| root.missing("seed"))?;
    let seed_v =
        u64::try_from(seed.v).map_err(|_| seed.fail(format!("must be >= 0, got {}", seed.v)))?;
    let mode = match root.string("mode")? {
        Some(m) => choose(
            &m,
            &[
                ("lockstep", RunMode::Lockstep),
                ("realtime", RunMode::Realtime),
            ],
            "mode",
        )?,
        None => RunMode::Lockstep,
    };

    let params = planner(root, &dt)?;
    let sonar = sonar(root)?;
    let navigation = navigation(root, dt_s)?;
    let current = current(root)?;
    let faults = faults(root)?;

    let mut obstacles = Vec::new();
    let mut shapes = Vec::new();
    let tables = root.tables("obstacle")?;
    if let Some(t) = tables.get(MAX_OBSTACLES) {
        return Err(t.src.err(
            &t.span,
            &t.path,
            format!(
                "too many obstacles: {} of at most {MAX_OBSTACLES} ({OBSTACLE_FACTOR} × the \
                 firmware's table of {})",
                tables.len(),
                vpf::world::MAX_OBSTACLES
            ),
        ));
    }
    for t in tables {
        let (o, s) = obstacle(&t)?;
        obstacles.push(o);
        shapes.push(s);
    }

    let tables = root.tables("vehicle")?;
    if tables.is_empty() {
        return Err(root.src.err(
            &root.span_of("vehicle"),
            "vehicle",
            "no vehicle: a scenario needs at least one [[vehicle]]",
        ));
    }
    if let Some(t) = tables.get(MAX_VEHICLES) {
        return Err(t.src.err(
            &t.span,
            &t.path,
            format!(
                "too many vehicles: at most {MAX_VEHICLES} (the firmware tracks {} others)",
                MAX_VEHICLES - 1
            ),
        ));
    }
    let mut vehicles: Vec<Vehicle> = Vec::new();
    for t in &tables {
        let v = vehicle(t, &sonar, &params, &obstacles, &shapes, &vehicles)?;
        vehicles.push(v);
    }

    Ok(Scenario {
        name: name.v.to_string(),
        duration_s,
        dt_s,
        seed: seed_v,
        mode,
        params,
        vehicles,
        obstacles,
        sonar,
        navigation,
        current,
        faults,
    })
}

// --- [planner] -------------------------------------------------------------------------------

/// A parameter's declared range and unit, for messages (the decision is `Params::validate`'s).
fn param_range(id: ParamId) -> String {
    let range = match (id.range(), id.kind()) {
        (vpf::params::Range::Any, Kind::U32) => format!("0 ..= {}", u32::MAX),
        (r, _) => r.to_string(),
    };
    format!("{range}{}", unit_suffix(id.unit()))
}

/// A parameter's value as a scenario would write it.
fn param_value(p: &Params, id: ParamId) -> String {
    p.get(id).to_string()
}

fn planner(root: &Table<'_>, dt: &Located<'_, f64>) -> Result<Params, ScenarioError> {
    let mut params = Params {
        period_s: dt.v as f32,
        ..Params::default()
    };
    // Every name validate reports is a declared parameter.
    let id_of = |name: &str| ParamId::from_name(name).unwrap_or(ParamId::period_s);
    let Some(t) = root.table("planner")? else {
        params.validate().map_err(|e| {
            root.src.err(
                &root.span,
                &format!("planner.{}", e.name),
                format!(
                    "the default value {} is refused by vpf ({e})",
                    param_value(&params, id_of(e.name))
                ),
            )
        })?;
        return Ok(params);
    };
    t.allow(&PARAM_NAMES, "[planner] (the names of vpf::Params' fields)")?;

    for &(name, _, _) in &t.entries {
        let Some(id) = ParamId::from_name(name) else {
            continue;
        };
        let value = match id.kind() {
            _ if id == ParamId::period_s => {
                return Err(t.src.err(
                    &t.span_of(name),
                    &t.key(name),
                    "the planner period is the top-level `dt_s`; set it there",
                ))
            }
            Kind::Code(names) => {
                let s = t.req_string(name)?;
                let choices: Vec<(&str, u8)> = names.iter().copied().zip(0u8..).collect();
                Value::Code(choose(&s, &choices, name)?)
            }
            Kind::U8 | Kind::U32 => {
                let i = t.integer(name)?.ok_or_else(|| t.missing(name))?;
                let refuse = || i.fail(format!("must be in {}, got {}", param_range(id), i.v));
                if id.kind() == Kind::U8 {
                    Value::U8(u8::try_from(i.v).map_err(|_| refuse())?)
                } else {
                    Value::U32(u32::try_from(i.v).map_err(|_| refuse())?)
                }
            }
            // Out-of-f32 values become infinite and are refused by validate below.
            Kind::F32 => Value::F32(t.req_number(name)?.v as f32),
        };
        params.set(id, value);
    }

    params.validate().map_err(|e| {
        let id = id_of(e.name);
        let value = param_value(&params, id);
        // Every number read is a finite f64, so a non-finite f32 here overflowed: out of range.
        let problem = format!("must be in {}", param_range(id));
        if e.name == "period_s" {
            dt.fail(format!("{problem}, got {}", dt.v))
        } else if t.has(e.name) {
            t.src.err(
                &t.span_of(e.name),
                &t.key(e.name),
                format!("{problem}, got {value}"),
            )
        } else {
            t.src.err(
                &t.span,
                &t.key(e.name),
                format!(
                    "{problem}, got the default {value} (v_max = {}); set it in [planner]",
                    params.v_max
                ),
            )
        }
    })?;
    Ok(params)
}

// --- [sonar], [navigation], [current], [faults] ----------------------------------------------

fn sonar(root: &Table<'_>) -> Result<Sonar, ScenarioError> {
    let mut s = Sonar::default();
    let Some(t) = root.table("sonar")? else {
        return Ok(s);
    };
    t.allow(
        &[
            "mode",
            "range_m",
            "bins",
            "step_deg",
            "noise",
            "speckle",
            "beam_rays",
            "false_echoes",
            "vehicle_contacts",
            "interface",
        ],
        "[sonar]",
    )?;
    let interface = match t.string("interface")? {
        Some(i) => Some(choose(
            &i,
            &[
                ("link", SonarInterface::Link),
                ("ping360", SonarInterface::Ping360),
            ],
            "sonar interface",
        )?),
        None => None,
    };
    if let Some(m) = t.string("mode")? {
        s.mode = choose(
            &m,
            &[
                ("scanlines", SonarMode::Scanlines),
                ("contacts", SonarMode::Contacts),
            ],
            "sonar mode",
        )?;
    }
    if let Some(r) = t.number("range_m")? {
        s.range_m = r.within(
            f64::from(vpf::sonar::MIN_RANGE_M),
            f64::from(vpf::sonar::MAX_RANGE_M),
            "m",
        )?;
    }
    if let Some(b) = t.integer("bins")? {
        let max = vpf::sonar::MAX_BINS as i64;
        if !(1..=max).contains(&b.v) {
            return Err(b.fail(format!("must be in 1 ..= {max}, got {}", b.v)));
        }
        s.bins = b.v as u16;
    }
    if let Some(d) = t.number("step_deg")? {
        let lo = f64::from(vpf::sonar::MIN_STEP_RAD).to_degrees();
        let hi = f64::from(vpf::sonar::MAX_STEP_RAD).to_degrees();
        // Rounded inward so the printed range is safe to use.
        let (lo, hi) = ((lo * 100.0).ceil() / 100.0, (hi * 100.0).floor() / 100.0);
        s.step = d.within(lo, hi, "degrees")?.to_radians();
    }
    if let Some(n) = t.number("noise")? {
        s.noise = n.within(0.0, 1.0, "")?;
    }
    if let Some(n) = t.number("speckle")? {
        s.speckle = n.within(0.0, 1.0, "")?;
    }
    if let Some(b) = t.integer("beam_rays")? {
        if !(1..=32).contains(&b.v) {
            return Err(b.fail(format!("must be in 1 ..= 32, got {}", b.v)));
        }
        s.beam_rays = b.v as usize;
    }
    if let Some(n) = t.number("false_echoes")? {
        s.false_echoes = n.within(0.0, 1.0, "")?;
    }
    if let Some(b) = t.boolean("vehicle_contacts")? {
        s.vehicle_contacts = b;
    }
    if interface == Some(SonarInterface::Ping360) {
        s.interface = SonarInterface::Ping360;
        let at = |key: &str| t.get(key).map(|v| v.span()).unwrap_or(t.span.clone());
        crate::ping360::sim::firmware_config(&s)
            .map_err(|(key, msg)| t.src.err(&at(key), &t.key(key), msg))?;
    }
    Ok(s)
}

fn navigation(root: &Table<'_>, dt_s: f64) -> Result<Navigation, ScenarioError> {
    let mut n = Navigation {
        rate_hz: 1.0 / dt_s,
        ..Navigation::default()
    };
    let Some(t) = root.table("navigation")? else {
        return Ok(n);
    };
    t.allow(
        &["position_sigma_m", "heading_sigma_deg", "rate_hz"],
        "[navigation]",
    )?;
    if let Some(x) = t.number("position_sigma_m")? {
        n.position_sigma_m = x.within(0.0, 100.0, "m")?;
    }
    if let Some(x) = t.number("heading_sigma_deg")? {
        n.heading_sigma = x.within(0.0, 180.0, "degrees")?.to_radians();
    }
    if let Some(x) = t.number("rate_hz")? {
        n.rate_hz = x.within(0.1, 1000.0, "Hz")?;
    }
    Ok(n)
}

fn current(root: &Table<'_>) -> Result<Current, ScenarioError> {
    let Some(t) = root.table("current")? else {
        return Ok(Current::default());
    };
    t.allow(&["velocity"], "[current]")?;
    Ok(Current {
        velocity: t.velocity("velocity", 5.0)?.unwrap_or_default(),
    })
}

fn faults(root: &Table<'_>) -> Result<Faults, ScenarioError> {
    let mut f = Faults::default();
    let Some(t) = root.table("faults")? else {
        return Ok(f);
    };
    t.allow(
        &[
            "bit_error_rate",
            "drop_rate",
            "nav_delay_ms",
            "nav_freeze",
            "nav_loss",
            "sonar_dropout",
            "ping360_bit_error_rate",
            "ping360_drop_rate",
        ],
        "[faults]",
    )?;
    if let Some(x) = t.number("ping360_bit_error_rate")? {
        f.ping360_bit_error_rate = x.within(0.0, 0.01, "")?;
    }
    if let Some(x) = t.number("ping360_drop_rate")? {
        f.ping360_drop_rate = x.within(0.0, 1.0, "")?;
    }
    if let Some(x) = t.number("bit_error_rate")? {
        f.bit_error_rate = x.within(0.0, 0.01, "")?;
    }
    if let Some(x) = t.number("drop_rate")? {
        f.drop_rate = x.within(0.0, 1.0, "")?;
    }
    if let Some(x) = t.number("nav_delay_ms")? {
        f.nav_delay_ms = x.within(0.0, 10_000.0, "ms")?;
    }
    f.nav_freeze = t.window("nav_freeze")?;
    f.nav_loss = t.window("nav_loss")?;
    f.sonar_dropout = t.window("sonar_dropout")?;
    Ok(f)
}

// --- [[obstacle]] ----------------------------------------------------------------------------

/// Largest obstacle speed, m/s (the firmware's `MAX_OBJECT_SPEED`).
const MAX_OBSTACLE_SPEED: f64 = vpf::world::MAX_OBJECT_SPEED as f64;

fn obstacle(t: &Table<'_>) -> Result<(SimObstacle, Shape), ScenarioError> {
    let kind = t.req_string("shape")?;
    let shape = match kind.v {
        "circle" => {
            t.allow(
                &["shape", "center", "radius", "velocity"],
                "a circle obstacle",
            )?;
            let center = t.req_position("center")?.v;
            let radius = t.req_number("radius")?.size()?;
            SimShape::Circle { center, radius }
        }
        "rectangle" => {
            t.allow(
                &["shape", "center", "half_size", "angle_deg", "velocity"],
                "a rectangle obstacle",
            )?;
            let center = t.req_position("center")?.v;
            let half = t.pair("half_size")?.ok_or_else(|| t.missing("half_size"))?;
            for (i, v) in [half.v.x, half.v.y].into_iter().enumerate() {
                let side = Located {
                    v,
                    span: half.span.clone(),
                    key: format!("{}[{i}]", half.key),
                    src: half.src,
                };
                side.size()?;
            }
            let angle = match t.number("angle_deg")? {
                Some(a) => a.within(-360.0, 360.0, "degrees")?.to_radians(),
                None => 0.0,
            };
            SimShape::Rectangle {
                center,
                half_size: half.v,
                angle,
            }
        }
        "polygon" => {
            t.allow(&["shape", "points", "velocity"], "a polygon obstacle")?;
            SimShape::Polygon {
                points: polygon(t)?,
            }
        }
        other => {
            return Err(kind.fail(format!(
                "unknown shape \"{other}\" (expected \"circle\", \"rectangle\" or \"polygon\")"
            )))
        }
    };
    let velocity = t
        .velocity("velocity", MAX_OBSTACLE_SPEED)?
        .unwrap_or_default();
    // The firmware's own constructors are the last word on what geometry it accepts.
    let vpf_shape = match &shape {
        SimShape::Circle { center, radius } => Shape::circle(center.to_vpf(), *radius as f32),
        SimShape::Rectangle {
            center,
            half_size,
            angle,
        } => Shape::rectangle(center.to_vpf(), half_size.to_vpf(), *angle as f32),
        SimShape::Polygon { points } => {
            let pts: Vec<vpf::Vec2> = points.iter().map(|p| p.to_vpf()).collect();
            Shape::polygon(&pts)
        }
    }
    .map_err(|e| {
        t.src.err(
            &t.span,
            &t.path,
            format!("refused by the firmware's geometry: {e}"),
        )
    })?;
    Ok((SimObstacle { shape, velocity }, vpf_shape))
}

/// A convex polygon's vertices, refusing degenerate and concave ones with the vertex at fault.
fn polygon(t: &Table<'_>) -> Result<Vec<P2>, ScenarioError> {
    let v = t.get("points").ok_or_else(|| t.missing("points"))?;
    let key = t.key("points");
    let DeValue::Array(items) = v.get_ref() else {
        return Err(t.src.err(
            &v.span(),
            &key,
            format!(
                "expected an array of [x, y] vertices, got {}",
                type_name(v.get_ref())
            ),
        ));
    };
    let n = items.len();
    if !(3..=MAX_POLYGON_VERTICES).contains(&n) {
        return Err(t.src.err(
            &v.span(),
            &key,
            format!("a polygon needs 3 ..= {MAX_POLYGON_VERTICES} vertices, got {n}"),
        ));
    }
    let mut pts = Vec::with_capacity(n);
    for (i, item) in items.iter().enumerate() {
        let p = Located {
            v: value_pair(t.src, &format!("{key}[{i}]"), item)?,
            span: item.span(),
            key: format!("{key}[{i}]"),
            src: t.src,
        };
        check_position(&p)?;
        pts.push(p);
    }
    let at = |i: usize| &pts[i % n];
    for i in 0..n {
        let (a, b) = (at(i), at(i + 1));
        if b.v.sub(a.v).norm() < f64::from(MIN_EXTENT_M) {
            return Err(b.fail(format!(
                "degenerate polygon: vertex {} repeats vertex {i}",
                (i + 1) % n
            )));
        }
    }
    // Turn at each vertex: the cross product of the edges into and out of it.
    let turn = |i: usize| {
        let (p, c, q) = (at(i + n - 1).v, at(i).v, at(i + 1).v);
        let (e1, e2) = (c.sub(p), q.sub(c));
        let cross = e1.x * e2.y - e1.y * e2.x;
        let dot = e1.x * e2.x + e1.y * e2.y;
        (cross, dot, e1.norm() * e2.norm())
    };
    let area2: f64 = (0..n)
        .map(|i| {
            let (a, b) = (at(i).v, at(i + 1).v);
            a.x * b.y - a.y * b.x
        })
        .sum();
    let mut total_turn = 0.0;
    for i in 0..n {
        let (cross, dot, scale) = turn(i);
        if cross.abs() <= 1e-6 * scale {
            return Err(at(i).fail(format!(
                "degenerate polygon: vertex {i} is collinear with its neighbours; remove it"
            )));
        }
        if cross * area2 < 0.0 {
            return Err(at(i).fail(format!(
                "concave polygon (reflex vertex {i}): obstacles must be convex, split it into \
                 convex pieces"
            )));
        }
        total_turn += cross.atan2(dot);
    }
    // All turns one way but winding more than once round: a star, which crosses itself.
    if (total_turn.abs() - std::f64::consts::TAU).abs() > 1e-6 {
        return Err(t.src.err(
            &v.span(),
            &key,
            "self-intersecting polygon: obstacles must be convex, split it into convex pieces",
        ));
    }
    Ok(pts.into_iter().map(|p| p.v).collect())
}

// --- [[vehicle]] -----------------------------------------------------------------------------

fn vehicle(
    t: &Table<'_>,
    sonar: &Sonar,
    params: &Params,
    obstacles: &[SimObstacle],
    shapes: &[Shape],
    earlier: &[Vehicle],
) -> Result<Vehicle, ScenarioError> {
    let mut keys = vec![
        "name",
        "model",
        "start",
        "heading_deg",
        "goal",
        "formation",
        "sensing",
        "autopilot",
    ];
    keys.extend(mission::KEYS);
    t.allow(&keys, "a [[vehicle]]")?;
    let name = t.req_string("name")?;
    check_name(&name)?;
    if let Some(i) = earlier.iter().position(|v| v.name == name.v) {
        return Err(name.fail(format!(
            "two vehicles are named \"{}\" (vehicle[{i}] too); names must be unique",
            name.v
        )));
    }
    let model = choose(
        &t.req_string("model")?,
        &[
            ("kinematic", ModelKind::Kinematic),
            ("videoray", ModelKind::VideoRay),
            ("flatfish", ModelKind::FlatFish),
            ("flat-fish", ModelKind::FlatFish),
            ("flat_fish", ModelKind::FlatFish),
        ],
        "model",
    )?;
    let start = t.req_position("start")?;
    let heading = match t.number("heading_deg")? {
        Some(h) => h.within(-360.0, 360.0, "degrees")?.to_radians(),
        None => 0.0,
    };
    let mission = mission::parse(t, params)?;
    let goal = match (t.position("goal")?, &mission) {
        (Some(g), None) => g,
        (Some(g), Some(_)) => {
            return Err(
                g.fail("give a `goal` or a waypoint mission (`waypoints`, `survey`), not both")
            )
        }
        (None, Some((_, placed))) => match placed.last() {
            Some(p) => Located {
                v: p.at.v,
                span: p.at.span.clone(),
                key: p.at.key.clone(),
                src: p.at.src,
            },
            None => return Err(t.missing("goal")),
        },
        (None, None) => return Err(t.src.err(&t.span, &t.key("goal"), "missing required key")),
    };
    let formation = match t.table("formation")? {
        Some(f) => Some(formation(&f)?),
        None => None,
    };
    let sensing = match t.string("sensing")? {
        Some(s) => choose(
            &s,
            &[("sonar", Sensing::Sonar), ("contacts", Sensing::Contacts)],
            "sensing",
        )?,
        None => match sonar.mode {
            SonarMode::Scanlines => Sensing::Sonar,
            SonarMode::Contacts => Sensing::Contacts,
        },
    };

    let autopilot = match t.string("autopilot")? {
        Some(s) => choose(
            &s,
            &[("plain", Autopilot::Plain), ("pid", Autopilot::SetPoints)],
            "autopilot",
        )?,
        None => Autopilot::Plain,
    };

    for (i, (o, s)) in obstacles.iter().zip(shapes).enumerate() {
        if s.signed_distance(start.v.to_vpf()) <= 0.0 {
            return Err(start.fail(format!(
                "start [{}, {}] is inside obstacle[{i}]",
                start.v.x, start.v.y
            )));
        }
        // A moving obstacle may uncover the goal later; a static one never will.
        if o.velocity == P2::default() && s.signed_distance(goal.v.to_vpf()) <= 0.0 {
            return Err(goal.fail(format!(
                "goal [{}, {}] is inside the static obstacle[{i}]",
                goal.v.x, goal.v.y
            )));
        }
        for (k, w) in mission.iter().flat_map(|(_, placed)| placed).enumerate() {
            if o.velocity == P2::default() && s.signed_distance(w.at.v.to_vpf()) <= 0.0 {
                return Err(w.at.fail(format!(
                    "waypoint {k} [{:.2}, {:.2}] is inside the static obstacle[{i}]",
                    w.at.v.x, w.at.v.y
                )));
            }
        }
    }
    let hull = 2.0 * f64::from(params.agent_radius_m);
    if let Some(other) = earlier.iter().find(|v| v.start.sub(start.v).norm() < hull) {
        return Err(start.fail(format!(
            "start is within {hull} m (two agent radii) of vehicle \"{}\"'s start",
            other.name
        )));
    }

    Ok(Vehicle {
        name: name.v.to_string(),
        model,
        start: start.v,
        heading,
        goal: goal.v,
        mission: mission.map(|(m, _)| m),
        formation,
        sensing,
        autopilot,
    })
}

fn formation(t: &Table<'_>) -> Result<Formation, ScenarioError> {
    t.allow(
        &["q", "lattice_m", "orientation_deg", "attraction"],
        "a formation",
    )?;
    let q = t.integer("q")?.ok_or_else(|| t.missing("q"))?;
    if !matches!(q.v, 3 | 4 | 6) {
        return Err(q.fail(format!(
            "the formation descriptor must be 3, 4 or 6, got {}",
            q.v
        )));
    }
    let lattice_m = t.req_number("lattice_m")?.within(0.5, 1000.0, "m")?;
    let orientation = match t.number("orientation_deg")? {
        Some(o) => o.within(-360.0, 360.0, "degrees")?.to_radians(),
        None => 0.0,
    };
    let attraction = match t.number("attraction")? {
        Some(a) => a.within(0.001, 1e4, "")?,
        None => 5.0,
    };
    let f = Formation {
        q: q.v as u8,
        lattice_m: lattice_m as f32,
        orientation: orientation as f32,
        attraction: attraction as f32,
    };
    f.validate()
        .map_err(|e| t.src.err(&t.span, &t.path, format!("refused by vpf: {e}")))?;
    Ok(f)
}
