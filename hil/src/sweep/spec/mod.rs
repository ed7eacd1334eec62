//! The sweep file (`hil/sweeps/*.toml`): which parameters to vary and how, over which
//! scenarios, for which craft, and the criterion's weights. Parsed and validated into a
//! [`Spec`]; every refusal is a [`ScenarioError`] naming the file, the line and the key path,
//! exactly as the scenario parser does (`videoray.toml:14: key `sweep.params.a_plus`: ...`).
//!
//! The fixed `[planner]` table and every parameter set are checked by the scenario parser's own
//! `[planner]` rules ([`scenario::parse_planner`]), so a sweep accepts exactly the keys and
//! values a scenario does. The format is documented in `hil/sweeps/README.md`.

use std::fmt::Write as _;

use toml::de::{DeTable, DeValue};

mod reader;

use crate::scenario::{self, ModelKind, ScenarioError, Sensing, SourceText};
use crate::sim::Rng;
use reader::{type_name, value_integer, value_number, Table, Val};

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

/// A `[planner]` value as written: integer, float or string.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// An integer (`n_gamma = 16`).
    Int(i64),
    /// A float (`a_plus = 2.5`).
    Float(f64),
    /// A string (`bounding = "split"`).
    Str(String),
}

impl Value {
    /// TOML spelling: floats always with a decimal point or exponent, strings quoted.
    pub fn toml(&self) -> String {
        match self {
            Value::Int(i) => i.to_string(),
            Value::Float(f) => {
                let s = f.to_string();
                if s.contains(['.', 'e', 'E']) || !f.is_finite() {
                    s
                } else {
                    format!("{s}.0")
                }
            }
            Value::Str(s) => toml::Value::String(s.clone()).to_string(),
        }
    }

    /// CSV / table spelling: numbers as in TOML, strings bare.
    pub fn plain(&self) -> String {
        match self {
            Value::Str(s) => s.clone(),
            v => v.toml(),
        }
    }

    /// The number, if it is one (for heat-map axes and ordering).
    pub fn number(&self) -> Option<f64> {
        match self {
            Value::Int(i) => Some(*i as f64),
            Value::Float(f) => Some(*f),
            Value::Str(_) => None,
        }
    }

    /// Reads a CSV cell back as the same kind of value as `like`.
    pub fn parse_like(s: &str, like: &Value) -> Option<Value> {
        match like {
            Value::Int(_) => s.parse().ok().map(Value::Int),
            Value::Float(_) => s.parse().ok().map(Value::Float),
            Value::Str(_) => Some(Value::Str(s.to_string())),
        }
    }
}

/// Grid or random sampling of the parameter space.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Every combination of the listed values (the last parameter varies fastest).
    Grid,
    /// `samples` parameter sets drawn from the ranges with the spec's seed.
    Random {
        /// Number of sets.
        samples: usize,
    },
}

/// How one parameter varies.
#[derive(Clone, Debug, PartialEq)]
pub enum Axis {
    /// These values (grid; random mode draws one of them uniformly).
    List(Vec<Value>),
    /// Random mode only: uniform in `[min, max]` (log-uniform if `log`), rounded to 3
    /// significant digits; an integer range draws integers.
    Range {
        /// Lower bound.
        min: f64,
        /// Upper bound.
        max: f64,
        /// Log-uniform.
        log: bool,
        /// Integers (both bounds were written as integers).
        integer: bool,
    },
}

/// One swept parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Param {
    /// Its `[planner]` key.
    pub name: String,
    /// How it varies.
    pub axis: Axis,
    /// Line of its key in the spec (for errors found later).
    pub line: usize,
}

/// The craft the recipe is for.
#[derive(Clone, Debug, PartialEq)]
pub struct Craft {
    /// The model every vehicle of every scenario flies.
    pub model: ModelKind,
    /// The clearance margin the criterion asks for, m (the craft's size: a hull radius plus a
    /// safety distance).
    pub margin_m: f64,
    /// A human name for the recipe's header.
    pub label: String,
}

/// The scenario batch.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenarios {
    /// Scenario files, as written (relative to the spec's directory).
    pub files: Vec<String>,
    /// Generated cluttered fields.
    pub clutter: usize,
    /// Generated narrow passages.
    pub passage: usize,
    /// Generated U-traps.
    pub utrap: usize,
    /// `hil bench` world families (`bench_families`), `bench_count` worlds of each, drawn for
    /// the craft's model (`crate::bench::worlds`).
    pub bench_families: Vec<crate::bench::worlds::Family>,
    /// Worlds per bench family.
    pub bench_count: usize,
    /// The first bench seed (`bench_first_seed`, default 0): the worlds are seeds
    /// `first .. first + bench_count`, so a recipe can be tuned on seeds `hil bench` (0 ..= 16
    /// by default) does not judge it on.
    pub bench_first_seed: u64,
    /// Start–goal distance of generated scenarios, m: `[min, max]`.
    pub length_m: (f64, f64),
    /// How the generated scenarios' vehicles sense obstacles.
    pub sensing: Sensing,
    /// Nominal cruise speed for the generated scenarios' durations, m/s.
    pub speed_mps: f64,
    /// A generated scenario lasts `time_factor × length / speed`, s.
    pub time_factor: f64,
    /// Scenario files run at most this long, s.
    pub duration_cap_s: Option<f64>,
    /// Clutter: free gap kept between obstacles' bounding circles, m.
    pub min_gap_m: f64,
    /// Clutter: obstacles per 100 m² of the field (`[min, max]`).
    pub density: (f64, f64),
    /// Passage: the opening's width, m (`[min, max]`).
    pub passage_gap_m: (f64, f64),
    /// U-trap: inner width, m (`[min, max]`).
    pub utrap_width_m: (f64, f64),
    /// U-trap: depth, m (`[min, max]`).
    pub utrap_depth_m: (f64, f64),
    /// Generated scenarios: a uniform current of up to this speed, random direction, m/s.
    pub current_mps: f64,
    /// Generated scenarios: navigation position noise, m (1 σ).
    pub nav_sigma_m: f64,
    /// Generated scenarios: the generator's own sizes (obstacles, walls, free room round the
    /// start and goal) times this, for a larger craft.
    pub scale: f64,
}

impl Scenarios {
    /// How many scenarios the batch holds: the files, then each generated family's count
    /// (saturating: only compared against a cap).
    pub fn count(&self) -> usize {
        [
            self.files.len(),
            self.clutter,
            self.passage,
            self.utrap,
            self.bench_families.len().saturating_mul(self.bench_count),
        ]
        .iter()
        .fold(0usize, |a, &n| a.saturating_add(n))
    }
}

impl Default for Scenarios {
    fn default() -> Self {
        Scenarios {
            files: Vec::new(),
            clutter: 0,
            passage: 0,
            utrap: 0,
            bench_families: Vec::new(),
            bench_count: 0,
            bench_first_seed: 0,
            length_m: (40.0, 80.0),
            sensing: Sensing::Contacts,
            speed_mps: 1.0,
            time_factor: 4.0,
            duration_cap_s: None,
            min_gap_m: 3.0,
            density: (1.0, 1.6),
            passage_gap_m: (2.5, 5.0),
            utrap_width_m: (6.0, 12.0),
            utrap_depth_m: (4.0, 8.0),
            current_mps: 0.0,
            nav_sigma_m: 0.0,
            scale: 1.0,
        }
    }
}

/// The criterion's weights (see `criterion.rs` for the criterion itself).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weights {
    /// Weight of the time to the goal relative to the best set's on the same scenario.
    pub time: f64,
    /// Weight of the energy proxy relative to the best set's on the same scenario.
    pub energy: f64,
    /// Weight per heading reversal per 100 m.
    pub oscillation: f64,
    /// Yaw-rate deadband of a heading reversal, rad/s.
    pub deadband: f64,
}

impl Default for Weights {
    fn default() -> Self {
        Weights {
            time: 1.0,
            energy: 1.0,
            oscillation: 0.05,
            deadband: 3f64.to_radians(),
        }
    }
}

/// A validated sweep file.
#[derive(Clone, Debug)]
pub struct Spec {
    /// The file name as given (errors, reports).
    pub file: String,
    /// The file's text (hashed; copied next to the results).
    pub text: String,
    /// Name, for the default output directory and the reports.
    pub name: String,
    /// Free text for the recipe's header.
    pub description: String,
    /// Seed of the random sampling and of the generated scenarios.
    pub seed: u64,
    /// The craft.
    pub craft: Craft,
    /// The fixed `[planner]` keys, in file order.
    pub base: Vec<(String, Value)>,
    /// Grid or random.
    pub mode: Mode,
    /// The swept parameters, in file order.
    pub params: Vec<Param>,
    /// The heat maps' axes, if the file names them.
    pub heatmap: Option<(String, String)>,
    /// The scenario batch.
    pub scenarios: Scenarios,
    /// The criterion's weights.
    pub weights: Weights,
    /// The parameter sets: the swept parameters' values, in `params` order.
    pub sets: Vec<Vec<Value>>,
}

impl Spec {
    /// The full `[planner]` entries of set `i`: the fixed keys, then the swept ones.
    pub fn entries(&self, i: usize) -> Vec<(String, Value)> {
        let mut e = self.base.clone();
        for (p, v) in self.params.iter().zip(&self.sets[i]) {
            e.push((p.name.clone(), v.clone()));
        }
        e
    }

    /// Set `i`'s parameters at planner period `dt_s`, checked by the scenario parser.
    pub fn params_of(&self, i: usize, dt_s: f64) -> Result<vpf::Params, ScenarioError> {
        let text = planner_text(&self.entries(i));
        scenario::parse_planner(&text, &format!("{} (parameter set {i})", self.file), dt_s)
    }
}

/// A `[planner]` table holding `entries`.
pub fn planner_text(entries: &[(String, Value)]) -> String {
    let mut s = String::from("[planner]\n");
    for (k, v) in entries {
        let _ = writeln!(s, "{k} = {}", v.toml());
    }
    s
}

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

// ---------------------------------------------------------------------------------------------
// Reading: the scenario parser's span-aware `Table` (file order, unknown keys refused, key
// paths with dots), plus range-checked readers of our own.

/// The sweep spec's range-checked readers, on the scenario parser's [`Table`].
trait SpecReads<'a> {
    fn fail(&self, v: &Val<'_>, k: &str, message: impl Into<String>) -> ScenarioError;
    fn text(&self, k: &str) -> Result<Option<&'a str>, ScenarioError>;
    fn int_in(&self, k: &str, lo: i64, hi: i64) -> Result<Option<i64>, ScenarioError>;
    fn num_in(&self, k: &str, lo: f64, hi: f64) -> Result<Option<f64>, ScenarioError>;
    fn range_in(&self, k: &str, lo: f64, hi: f64) -> Result<Option<(f64, f64)>, ScenarioError>;
}

impl<'a> SpecReads<'a> for Table<'a> {
    fn fail(&self, v: &Val<'_>, k: &str, message: impl Into<String>) -> ScenarioError {
        self.src.err(&v.span(), &self.key(k), message)
    }

    fn text(&self, k: &str) -> Result<Option<&'a str>, ScenarioError> {
        let Some(v) = self.get(k) else {
            return Ok(None);
        };
        match v.get_ref() {
            DeValue::String(s) => Ok(Some(s.as_ref())),
            other => Err(self.fail(v, k, format!("expected a string, got {}", type_name(other)))),
        }
    }

    fn int_in(&self, k: &str, lo: i64, hi: i64) -> Result<Option<i64>, ScenarioError> {
        let Some(v) = self.get(k) else {
            return Ok(None);
        };
        let i = value_integer(self.src, &self.key(k), v)?;
        if !(lo..=hi).contains(&i) {
            return Err(self.fail(v, k, format!("must be in {lo} ..= {hi}, got {i}")));
        }
        Ok(Some(i))
    }

    fn num_in(&self, k: &str, lo: f64, hi: f64) -> Result<Option<f64>, ScenarioError> {
        let Some(v) = self.get(k) else {
            return Ok(None);
        };
        let x = value_number(self.src, &self.key(k), v)?;
        if !(lo..=hi).contains(&x) {
            return Err(self.fail(v, k, format!("must be in {lo} ..= {hi}, got {x}")));
        }
        Ok(Some(x))
    }

    /// `[min, max]` with `lo <= min <= max <= hi`.
    fn range_in(&self, k: &str, lo: f64, hi: f64) -> Result<Option<(f64, f64)>, ScenarioError> {
        let Some(v) = self.get(k) else {
            return Ok(None);
        };
        let key = self.key(k);
        let DeValue::Array(a) = v.get_ref() else {
            return Err(self.fail(
                v,
                k,
                format!("expected [min, max], got {}", type_name(v.get_ref())),
            ));
        };
        if a.len() != 2 {
            return Err(self.fail(v, k, format!("expected [min, max], got {} items", a.len())));
        }
        let x = value_number(self.src, &format!("{key}[0]"), &a[0])?;
        let y = value_number(self.src, &format!("{key}[1]"), &a[1])?;
        if !(lo <= x && x <= y && y <= hi) {
            return Err(self.fail(
                v,
                k,
                format!("must be [min, max] with {lo} <= min <= max <= {hi}, got [{x}, {y}]"),
            ));
        }
        Ok(Some((x, y)))
    }
}

/// A `[planner]` value: integer, finite float or string.
fn value_any(src: SourceText<'_>, key: &str, v: &Val<'_>) -> Result<Value, ScenarioError> {
    match v.get_ref() {
        DeValue::Integer(_) => value_integer(src, key, v).map(Value::Int),
        DeValue::Float(_) => value_number(src, key, v).map(Value::Float),
        DeValue::String(s) => Ok(Value::Str(s.to_string())),
        other => Err(src.err(
            &v.span(),
            key,
            format!("expected a number or a string, got {}", type_name(other)),
        )),
    }
}

// ---------------------------------------------------------------------------------------------
// The schema.

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

    let craft = craft(&root)?;
    let base = base_planner(&root, src)?;
    let (mode, params, heatmap) = sweep(&root, &base)?;
    let scenarios = scenarios(&root)?;
    let weights = criterion(&root)?;

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
    spec.sets = expand(&spec, &root)?;
    check_runs(&spec, &root)?;
    check_sets(&spec)?;
    Ok(spec)
}

fn craft(root: &Table<'_>) -> Result<Craft, ScenarioError> {
    let t = root.table("craft")?.ok_or_else(|| root.missing("craft"))?;
    t.allow(&["model", "margin_m", "label"], "[craft]")?;
    let m = t.text("model")?.ok_or_else(|| t.missing("model"))?;
    let model = m.parse::<ModelKind>().map_err(|e| {
        let v = t.get("model").map_or(0..0, |v| v.span());
        t.src.err(&v, &t.key("model"), e.to_string())
    })?;
    let margin_m = t
        .num_in("margin_m", 0.0, 100.0)?
        .ok_or_else(|| t.missing("margin_m"))?;
    let label = t.text("label")?.unwrap_or(model.name()).to_string();
    Ok(Craft {
        model,
        margin_m,
        label,
    })
}

/// The fixed `[planner]` keys, checked by the scenario parser on the spec's own text with every
/// line outside the table blanked (so its errors carry the spec's line numbers).
fn base_planner(
    root: &Table<'_>,
    src: SourceText<'_>,
) -> Result<Vec<(String, Value)>, ScenarioError> {
    let Some(t) = root.table("planner")? else {
        return Ok(Vec::new());
    };
    let mut out = Vec::new();
    let mut last = t.span.end;
    for (k, _, v) in &t.entries {
        out.push((k.to_string(), value_any(src, &t.key(k), v)?));
        last = last.max(v.span().end);
    }
    let (first_line, last_line) = (src.line_of(t.span.start), src.line_of(last));
    let kept: String = src
        .text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if (first_line..=last_line).contains(&(i + 1)) {
                format!("{l}\n")
            } else {
                "\n".to_string()
            }
        })
        .collect();
    scenario::parse_planner(&kept, src.file, CHECK_DT_S)?;
    Ok(out)
}

type SweepPart = (Mode, Vec<Param>, Option<(String, String)>);

fn sweep(root: &Table<'_>, base: &[(String, Value)]) -> Result<SweepPart, ScenarioError> {
    let t = root.table("sweep")?.ok_or_else(|| root.missing("sweep"))?;
    t.allow(&["mode", "samples", "heatmap", "params"], "[sweep]")?;
    let mode = match t.text("mode")?.unwrap_or("grid") {
        "grid" => {
            if let Some(v) = t.get("samples") {
                return Err(t.fail(v, "samples", "only for mode = \"random\""));
            }
            Mode::Grid
        }
        "random" => Mode::Random {
            samples: t
                .int_in("samples", 1, MAX_SETS as i64)?
                .ok_or_else(|| t.missing("samples"))? as usize,
        },
        other => {
            let v = t.get("mode").map_or(0..0, |v| v.span());
            return Err(t.src.err(
                &v,
                &t.key("mode"),
                format!("unknown mode \"{other}\" (expected \"grid\" or \"random\")"),
            ));
        }
    };
    let p = t.table("params")?.ok_or_else(|| t.missing("params"))?;
    if p.entries.is_empty() {
        return Err(t.src.err(&p.span, &p.path, "no parameter to sweep"));
    }
    let names: Vec<&str> = vpf::link::PARAM_NAMES
        .iter()
        .copied()
        .filter(|n| *n != "period_s")
        .collect();
    let mut params = Vec::new();
    for (k, kspan, v) in &p.entries {
        if !names.contains(k) {
            return Err(p.src.err(
                kspan,
                &p.key(k),
                format!(
                    "not a [planner] parameter (expected one of: {})",
                    names.join(", ")
                ),
            ));
        }
        if base.iter().any(|(b, _)| b == k) {
            return Err(p.src.err(
                kspan,
                &p.key(k),
                "is also fixed in [planner]: a parameter is either fixed or swept",
            ));
        }
        let axis = axis(&p, k, v, mode)?;
        params.push(Param {
            name: k.to_string(),
            axis,
            line: p.src.line_of(kspan.start),
        });
    }
    let heatmap = match t.get("heatmap") {
        None => None,
        Some(v) => {
            let bad = || {
                t.fail(
                    v,
                    "heatmap",
                    "expected two swept parameters, [\"x\", \"y\"]",
                )
            };
            let DeValue::Array(a) = v.get_ref() else {
                return Err(bad());
            };
            let names: Vec<&str> = a
                .iter()
                .filter_map(|x| match x.get_ref() {
                    DeValue::String(s) => Some(s.as_ref()),
                    _ => None,
                })
                .collect();
            if names.len() != 2 || a.len() != 2 || names[0] == names[1] {
                return Err(bad());
            }
            for n in &names {
                if !params.iter().any(|q| q.name == *n) {
                    return Err(t.fail(v, "heatmap", format!("`{n}` is not a swept parameter")));
                }
            }
            Some((names[0].to_string(), names[1].to_string()))
        }
    };
    Ok((mode, params, heatmap))
}

fn axis(p: &Table<'_>, k: &str, v: &Val<'_>, mode: Mode) -> Result<Axis, ScenarioError> {
    let key = p.key(k);
    match v.get_ref() {
        DeValue::Array(a) => {
            if a.is_empty() {
                return Err(p.fail(v, k, "needs at least one value"));
            }
            let mut values = Vec::new();
            for (i, item) in a.iter().enumerate() {
                let x = value_any(p.src, &format!("{key}[{i}]"), item)?;
                if values.contains(&x) {
                    return Err(p.src.err(
                        &item.span(),
                        &format!("{key}[{i}]"),
                        format!("value {} is listed twice", x.toml()),
                    ));
                }
                values.push(x);
            }
            Ok(Axis::List(values))
        }
        DeValue::Table(t) => {
            let t = Table::new(p.src, key.clone(), v.span(), t);
            if mode == Mode::Grid {
                return Err(p.fail(
                    v,
                    k,
                    "a range { min, max } needs mode = \"random\"; a grid lists its values",
                ));
            }
            t.allow(&["min", "max", "log"], "a parameter range")?;
            let min_v = t.get("min").ok_or_else(|| t.missing("min"))?;
            let max_v = t.get("max").ok_or_else(|| t.missing("max"))?;
            let min = value_number(t.src, &t.key("min"), min_v)?;
            let max = value_number(t.src, &t.key("max"), max_v)?;
            let integer = matches!(min_v.get_ref(), DeValue::Integer(_))
                && matches!(max_v.get_ref(), DeValue::Integer(_));
            let log = match t.get("log") {
                None => false,
                Some(l) => match l.get_ref() {
                    DeValue::Boolean(b) => *b,
                    other => {
                        return Err(t.fail(
                            l,
                            "log",
                            format!("expected a boolean, got {}", type_name(other)),
                        ))
                    }
                },
            };
            if min > max {
                return Err(t.fail(max_v, "max", format!("must be >= min ({min}), got {max}")));
            }
            if log && min <= 0.0 {
                return Err(t.fail(
                    min_v,
                    "min",
                    format!("a log range needs min > 0, got {min}"),
                ));
            }
            Ok(Axis::Range {
                min,
                max,
                log,
                integer,
            })
        }
        other => Err(p.fail(
            v,
            k,
            format!(
                "expected a list of values or a range {{ min, max }}, got {}",
                type_name(other)
            ),
        )),
    }
}

fn scenarios(root: &Table<'_>) -> Result<Scenarios, ScenarioError> {
    let mut s = Scenarios::default();
    let t = root
        .table("scenarios")?
        .ok_or_else(|| root.missing("scenarios"))?;
    t.allow(
        &[
            "files",
            "clutter",
            "passage",
            "utrap",
            "bench_families",
            "bench_count",
            "bench_first_seed",
            "length_m",
            "sensing",
            "speed_mps",
            "time_factor",
            "duration_cap_s",
            "min_gap_m",
            "density",
            "passage_gap_m",
            "utrap_width_m",
            "utrap_depth_m",
            "current_mps",
            "nav_sigma_m",
            "scale",
        ],
        "[scenarios]",
    )?;
    if let Some(v) = t.get("files") {
        let DeValue::Array(a) = v.get_ref() else {
            return Err(t.fail(v, "files", "expected a list of scenario file paths"));
        };
        for (i, item) in a.iter().enumerate() {
            match item.get_ref() {
                DeValue::String(f) => s.files.push(f.to_string()),
                other => {
                    return Err(t.src.err(
                        &item.span(),
                        &format!("{}[{i}]", t.key("files")),
                        format!("expected a path (string), got {}", type_name(other)),
                    ))
                }
            }
        }
    }
    let count = |k: &str| t.int_in(k, 0, 100_000).map(|x| x.unwrap_or(0) as usize);
    s.clutter = count("clutter")?;
    s.passage = count("passage")?;
    s.utrap = count("utrap")?;
    if let Some(v) = t.get("bench_families") {
        let DeValue::Array(a) = v.get_ref() else {
            return Err(t.fail(v, "bench_families", "expected a list of bench family names"));
        };
        for (i, item) in a.iter().enumerate() {
            let family = match item.get_ref() {
                DeValue::String(f) => crate::bench::worlds::Family::parse(f),
                _ => None,
            };
            let Some(family) = family else {
                return Err(t.src.err(
                    &item.span(),
                    &format!("{}[{i}]", t.key("bench_families")),
                    format!(
                        "expected a bench family: one of {}",
                        crate::bench::worlds::FAMILIES.map(|f| f.name()).join(", ")
                    ),
                ));
            };
            s.bench_families.push(family);
        }
    }
    s.bench_count = count("bench_count")?;
    s.bench_first_seed = t.int_in("bench_first_seed", 0, 1_000_000)?.unwrap_or(0) as u64;
    if s.bench_families.is_empty() {
        s.bench_count = 0;
    }
    if s.files.is_empty() && s.clutter + s.passage + s.utrap + s.bench_count == 0 {
        return Err(t.src.err(
            &t.span,
            &t.path,
            "no scenario: list `files` or ask for generated `clutter`, `passage`, `utrap` or \
             `bench_families` with `bench_count`",
        ));
    }
    if let Some(r) = t.range_in("length_m", 15.0, 1000.0)? {
        s.length_m = r;
    }
    if let Some(x) = t.text("sensing")? {
        s.sensing = match x {
            "contacts" => Sensing::Contacts,
            "sonar" => Sensing::Sonar,
            other => {
                let v = t.get("sensing").map_or(0..0, |v| v.span());
                return Err(t.src.err(
                    &v,
                    &t.key("sensing"),
                    format!("unknown sensing \"{other}\" (expected \"contacts\" or \"sonar\")"),
                ));
            }
        };
    }
    if let Some(x) = t.num_in("speed_mps", 0.05, 20.0)? {
        s.speed_mps = x;
    }
    if let Some(x) = t.num_in("time_factor", 1.0, 100.0)? {
        s.time_factor = x;
    }
    s.duration_cap_s = t.num_in("duration_cap_s", 1.0, 86_400.0)?;
    if let Some(x) = t.num_in("min_gap_m", 0.5, 100.0)? {
        s.min_gap_m = x;
    }
    if let Some(r) = t.range_in("density", 0.0, 10.0)? {
        s.density = r;
    }
    if let Some(r) = t.range_in("passage_gap_m", 0.5, 50.0)? {
        s.passage_gap_m = r;
    }
    if let Some(r) = t.range_in("utrap_width_m", 2.0, 100.0)? {
        s.utrap_width_m = r;
    }
    if let Some(r) = t.range_in("utrap_depth_m", 1.0, 100.0)? {
        s.utrap_depth_m = r;
    }
    if let Some(x) = t.num_in("current_mps", 0.0, 5.0)? {
        s.current_mps = x;
    }
    if let Some(x) = t.num_in("nav_sigma_m", 0.0, 100.0)? {
        s.nav_sigma_m = x;
    }
    if let Some(x) = t.num_in("scale", 0.1, 100.0)? {
        s.scale = x;
    }
    Ok(s)
}

fn criterion(root: &Table<'_>) -> Result<Weights, ScenarioError> {
    let mut w = Weights::default();
    let Some(t) = root.table("criterion")? else {
        return Ok(w);
    };
    t.allow(
        &["time", "energy", "oscillation", "deadband_deg_s"],
        "[criterion]",
    )?;
    if let Some(x) = t.num_in("time", 0.0, 1000.0)? {
        w.time = x;
    }
    if let Some(x) = t.num_in("energy", 0.0, 1000.0)? {
        w.energy = x;
    }
    if let Some(x) = t.num_in("oscillation", 0.0, 1000.0)? {
        w.oscillation = x;
    }
    if let Some(x) = t.num_in("deadband_deg_s", 0.0, 360.0)? {
        w.deadband = x.to_radians();
    }
    Ok(w)
}

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
fn check_runs(spec: &Spec, root: &Table<'_>) -> Result<(), ScenarioError> {
    let sets = spec.sets.len();
    let scenarios = spec.scenarios.count();
    match sets.checked_mul(scenarios) {
        Some(runs) if runs <= MAX_RUNS => Ok(()),
        runs => Err(root.src.err(
            &root.span_of("scenarios"),
            "scenarios",
            format!(
                "{sets} parameter sets × {scenarios} scenarios = {} runs; at most {MAX_RUNS} \
                 (fewer sets, or fewer scenarios)",
                runs.map_or_else(|| "too many".to_string(), |r| r.to_string())
            ),
        )),
    }
}

/// The parameter sets: the grid's combinations, or the random draws.
fn expand(spec: &Spec, root: &Table<'_>) -> Result<Vec<Vec<Value>>, ScenarioError> {
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
                return Err(root.src.err(
                    &root.span_of("sweep"),
                    "sweep.params",
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
fn check_sets(spec: &Spec) -> Result<(), ScenarioError> {
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
