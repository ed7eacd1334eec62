//! The `[planner]` table: its keys, kinds and ranges come from the library's one parameter
//! declaration (`vpf::params`), so a new parameter is read, checked and named here with no
//! change to this file. The decision on a value is `Params::validate`'s; this file puts the
//! refusal at its key.

use std::fmt;

use serde::de::{self, DeserializeSeed, Deserializer, MapAccess, Visitor};
use serde::Deserialize;
use toml::Spanned;
use vpf::params::{Kind, ParamId, Value, PARAM_NAMES};
use vpf::Params;

use super::values::{unit_suffix, Int, Num};
use super::{unknown_choice, unknown_key, At, ScenarioError};

/// The `[planner]` overrides, in file order, each with its key's span.
pub(super) struct Planner(Vec<(Spanned<ParamKey>, Value)>);

/// A `[planner]` key: a declared parameter other than the period.
pub(super) struct ParamKey(ParamId);

/// What the table is called in a refusal of an unknown key.
const TABLE: &str = "[planner] (the names of vpf::Params' fields)";

impl<'de> Deserialize<'de> for ParamKey {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        match ParamId::from_name(&name) {
            Some(ParamId::period_s) => Err(de::Error::custom(
                "the planner period is the top-level `dt_s`; set it there",
            )),
            Some(id) => Ok(ParamKey(id)),
            None => Err(de::Error::custom(unknown_key(&name, &PARAM_NAMES, TABLE))),
        }
    }
}

/// Reads a parameter's value as its declared kind.
struct ParamSeed(ParamId);

impl<'de> DeserializeSeed<'de> for ParamSeed {
    type Value = Value;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Value, D::Error> {
        let id = self.0;
        Ok(match id.kind() {
            Kind::Code(names) => {
                let s = String::deserialize(d)?;
                match names.iter().position(|n| *n == s) {
                    Some(i) => Value::Code(i as u8),
                    None => return Err(de::Error::custom(unknown_choice(id.name(), &s, names))),
                }
            }
            Kind::U8 | Kind::U32 => {
                let Int(i) = Int::deserialize(d)?;
                let refuse = || de::Error::custom(format!("must be in {}, got {i}", range(id)));
                if id.kind() == Kind::U8 {
                    Value::U8(u8::try_from(i).map_err(|_| refuse())?)
                } else {
                    Value::U32(u32::try_from(i).map_err(|_| refuse())?)
                }
            }
            // Out-of-f32 values become infinite and are refused by validate.
            Kind::F32 => Value::F32(Num::deserialize(d)?.0 as f32),
        })
    }
}

impl<'de> Deserialize<'de> for Planner {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Planner;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a table")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Planner, A::Error> {
                let mut entries = Vec::new();
                while let Some(key) = map.next_key::<Spanned<ParamKey>>()? {
                    let value = map.next_value_seed(ParamSeed(key.get_ref().0))?;
                    entries.push((key, value));
                }
                Ok(Planner(entries))
            }
        }
        d.deserialize_map(V)
    }
}

/// A parameter's declared range and unit, for messages (the decision is `Params::validate`'s).
fn range(id: ParamId) -> String {
    let range = match (id.range(), id.kind()) {
        (vpf::params::Range::Any, Kind::U32) => format!("0 ..= {}", u32::MAX),
        (r, _) => r.to_string(),
    };
    format!("{range}{}", unit_suffix(id.unit()))
}

/// The parameters of `[planner]` (`planner` absent: the defaults) at the period `dt_s`
/// (written at `dt`), validated by the library. `root` is the document the table is in.
pub(super) fn planner(
    root: &At<'_>,
    planner: &Option<Spanned<Planner>>,
    dt_s: f64,
    dt: &std::ops::Range<usize>,
) -> Result<Params, ScenarioError> {
    let mut params = Params {
        period_s: dt_s as f32,
        ..Params::default()
    };
    let (t, entries) = match planner {
        Some(p) => (root.child("planner", p.span()), &p.get_ref().0[..]),
        None => (root.child("planner", root.span.clone()), &[][..]),
    };
    for (key, value) in entries {
        params.set(key.get_ref().0, *value);
    }
    let Err(e) = params.validate() else {
        return Ok(params);
    };
    // Every name validate reports is a declared parameter.
    let id = ParamId::from_name(e.name).unwrap_or(ParamId::period_s);
    let value = params.get(id).to_string();
    if planner.is_none() {
        return Err(root.fail(
            &format!("planner.{}", e.name),
            &root.span,
            format!("the default value {value} is refused by vpf ({e})"),
        ));
    }
    // Every number read is a finite f64, so a non-finite f32 here overflowed: out of range.
    let problem = format!("must be in {}", range(id));
    if id == ParamId::period_s {
        return Err(root.fail("dt_s", dt, format!("{problem}, got {dt_s}")));
    }
    Err(match entries.iter().find(|(k, _)| k.get_ref().0 == id) {
        Some((k, _)) => t.fail(e.name, &k.span(), format!("{problem}, got {value}")),
        None => t.fail(
            e.name,
            &t.span,
            format!(
                "{problem}, got the default {value} (v_max = {}); set it in [planner]",
                params.v_max
            ),
        ),
    })
}
