//! The scenario file's tables as serde reads them: every key optional and spanned (the
//! builders check presence, ranges and cross-references at the key), unknown keys refused
//! (`deny_unknown_fields`), and the name each table goes by in a refusal.

use std::fmt;

use serde::de::value::{MapAccessDeserializer, SeqAccessDeserializer};
use serde::de::{Deserializer, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;
use toml::Spanned;

use toml::de::{DeTable, DeValue};

use super::planner::Planner;
use super::refusal::{keys_of, value_at, Seg};
use super::values::{Int, Item, Items, Num, Pair, Table};

/// `Option<Spanned<T>>`: a key that may be absent, with where it was written.
pub(crate) type Opt<T> = Option<Spanned<T>>;

/// The document.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct ScenarioFile {
    pub name: Opt<String>,
    pub duration_s: Opt<Num>,
    pub dt_s: Opt<Num>,
    pub seed: Opt<Int>,
    pub mode: Opt<String>,
    pub planner: Opt<Planner>,
    pub vehicle: Opt<Items<Table<VehicleFile>>>,
    #[serde(default)]
    pub obstacle: Items<Table<ObstacleFile>>,
    pub sonar: Opt<Table<SonarFile>>,
    pub navigation: Opt<Table<NavigationFile>>,
    pub current: Opt<Table<CurrentFile>>,
    pub faults: Opt<Table<FaultsFile>>,
}

/// A parameter file: a document holding only a `[planner]` table.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct ParamFile {
    pub planner: Opt<Planner>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct SonarFile {
    pub mode: Opt<String>,
    pub range_m: Opt<Num>,
    pub bins: Opt<Int>,
    pub step_deg: Opt<Num>,
    pub noise: Opt<Num>,
    pub speckle: Opt<Num>,
    pub beam_rays: Opt<Int>,
    pub false_echoes: Opt<Num>,
    pub vehicle_contacts: Opt<bool>,
    pub interface: Opt<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct NavigationFile {
    pub position_sigma_m: Opt<Num>,
    pub heading_sigma_deg: Opt<Num>,
    pub rate_hz: Opt<Num>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct CurrentFile {
    pub velocity: Opt<Pair>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct FaultsFile {
    pub bit_error_rate: Opt<Num>,
    pub drop_rate: Opt<Num>,
    pub nav_delay_ms: Opt<Num>,
    pub nav_freeze: Opt<Pair>,
    pub nav_loss: Opt<Pair>,
    pub sonar_dropout: Opt<Pair>,
    pub ping360_bit_error_rate: Opt<Num>,
    pub ping360_drop_rate: Opt<Num>,
}

/// An `[[obstacle]]`: the keys of every shape (which of them a shape takes is
/// [`shape_keys`]'s, checked by the builder once the shape is known).
#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct ObstacleFile {
    pub shape: Opt<String>,
    pub center: Opt<Pair>,
    pub radius: Opt<Num>,
    pub half_size: Opt<Pair>,
    pub angle_deg: Opt<Num>,
    pub points: Opt<Items<Pair>>,
    pub velocity: Opt<Pair>,
}

impl Item for Table<ObstacleFile> {
    const LIST: &'static str = "an array of tables (`[[obstacle]]`)";
}

/// The keys an obstacle of `shape` takes; `None` for an unknown shape.
pub(super) fn shape_keys(shape: &str) -> Option<&'static [&'static str]> {
    match shape {
        "circle" => Some(&["shape", "center", "radius", "velocity"]),
        "rectangle" => Some(&["shape", "center", "half_size", "angle_deg", "velocity"]),
        "polygon" => Some(&["shape", "points", "velocity"]),
        _ => None,
    }
}

/// A `[[vehicle]]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct VehicleFile {
    pub name: Opt<String>,
    pub model: Opt<String>,
    pub start: Opt<Pair>,
    pub heading_deg: Opt<Num>,
    pub goal: Opt<Pair>,
    pub formation: Opt<Table<FormationFile>>,
    pub sensing: Opt<String>,
    pub autopilot: Opt<String>,
    pub waypoints: Opt<Items<WaypointItem>>,
    pub survey: Opt<Table<SurveyFile>>,
    pub end: Opt<String>,
    pub loiter_radius_m: Opt<Num>,
    pub loiter_clockwise: Opt<bool>,
}

impl Item for Table<VehicleFile> {
    const LIST: &'static str = "an array of tables (`[[vehicle]]`)";
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct FormationFile {
    pub q: Opt<Int>,
    pub lattice_m: Opt<Num>,
    pub orientation_deg: Opt<Num>,
    pub attraction: Opt<Num>,
}

/// A waypoint: `[x, y]`, or `{ at = [x, y], radius_m = .., speed = .. }`.
pub(super) enum WaypointItem {
    At(Pair),
    Table(WaypointTable),
}

// By hand rather than `untagged`, which buffers the value and so loses its spans.
impl<'de> Deserialize<'de> for WaypointItem {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = WaypointItem;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a waypoint ([x, y] or { at = [x, y], radius_m = .., speed = .. })")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<WaypointItem, A::Error> {
                Pair::deserialize(SeqAccessDeserializer::new(seq)).map(WaypointItem::At)
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<WaypointItem, A::Error> {
                WaypointTable::deserialize(MapAccessDeserializer::new(map)).map(WaypointItem::Table)
            }
        }
        d.deserialize_any(V)
    }
}

impl Item for WaypointItem {
    const LIST: &'static str =
        "an array of waypoints ([x, y] or { at = [x, y], radius_m = .., speed = .. })";
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct WaypointTable {
    pub at: Opt<Pair>,
    pub radius_m: Opt<Num>,
    pub speed: Opt<Num>,
}

/// `[vehicle.survey]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct SurveyFile {
    pub corner: Opt<Pair>,
    pub length_m: Opt<Num>,
    pub width_m: Opt<Num>,
    pub heading_deg: Opt<Num>,
    pub spacing_m: Opt<Num>,
    pub radius_m: Opt<Num>,
    pub speed: Opt<Num>,
}

/// What a table of a scenario (`root`: of a parameter file) is called in "unknown key in …",
/// and an obstacle's keys, which are its shape's.
pub(super) fn naming(
    root: &'static str,
) -> impl Fn(&DeTable<'_>, &[Seg<'_>]) -> (String, Option<&'static [&'static str]>) {
    move |doc, parent| {
        if let [Seg::Key("obstacle"), Seg::Index(i)] = parent {
            let shape = value_at(
                doc,
                &[Seg::Key("obstacle"), Seg::Index(*i), Seg::Key("shape")],
            );
            if let Some(DeValue::String(shape)) = shape {
                if let Some(keys) = shape_keys(shape) {
                    return (format!("a {shape} obstacle"), Some(keys));
                }
            }
        }
        (table_name(&keys_of(parent), root), None)
    }
}

fn table_name(parent: &[&str], root: &str) -> String {
    match parent {
        [] => root.to_string(),
        ["vehicle"] => "a [[vehicle]]".into(),
        ["vehicle", "formation"] => "a formation".into(),
        ["vehicle", "survey"] => "a survey".into(),
        ["vehicle", "waypoints"] => "a waypoint".into(),
        ["obstacle"] => "an obstacle".into(),
        [name] => format!("[{name}]"),
        _ => format!("`{}`", parent.join(".")),
    }
}
