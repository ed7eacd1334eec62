//! The validated sweep spec: what to vary and how, over which scenarios, for which craft, and
//! the criterion's weights.

use std::fmt::Write as _;

use crate::scenario::{self, ModelKind, ScenarioError, Sensing};

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
