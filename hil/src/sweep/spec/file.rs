//! The sweep file's tables as serde reads them (the scenario reader's leaf values and refusals):
//! every key optional and spanned, unknown keys refused; `[planner]` and `[sweep.params]` keep
//! their keys in file order, with values of any kind.

use std::fmt;

use serde::de::value::MapAccessDeserializer;
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;
use toml::de::DeTable;
use toml::Spanned;

use super::Value;
use crate::scenario::{closest, keys_of, Int, Item, Items, Num, Opt, Seg, Table};

/// The document.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct SpecFile {
    pub name: Opt<String>,
    pub description: Opt<String>,
    pub seed: Opt<Int>,
    pub craft: Opt<Table<CraftFile>>,
    pub planner: Opt<Entries<String, Value>>,
    pub sweep: Opt<Table<SweepFile>>,
    pub scenarios: Opt<Table<ScenariosFile>>,
    pub criterion: Opt<Table<CriterionFile>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct CraftFile {
    pub model: Opt<String>,
    pub margin_m: Opt<Num>,
    pub label: Opt<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct SweepFile {
    pub mode: Opt<String>,
    pub samples: Opt<Int>,
    pub heatmap: Opt<Items<String>>,
    pub params: Opt<Entries<Swept, AxisFile>>,
}

/// How one parameter varies, as written: a list of values, or a range `{ min, max, log }`.
pub(super) enum AxisFile {
    List(Items<Value>),
    Range(RangeFile),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct RangeFile {
    pub min: Opt<Value>,
    pub max: Opt<Value>,
    pub log: Opt<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct ScenariosFile {
    pub files: Opt<Items<String>>,
    pub clutter: Opt<Int>,
    pub passage: Opt<Int>,
    pub utrap: Opt<Int>,
    pub bench_families: Opt<Items<String>>,
    pub bench_count: Opt<Int>,
    pub bench_first_seed: Opt<Int>,
    pub length_m: Opt<MinMax>,
    pub sensing: Opt<String>,
    pub speed_mps: Opt<Num>,
    pub time_factor: Opt<Num>,
    pub duration_cap_s: Opt<Num>,
    pub min_gap_m: Opt<Num>,
    pub density: Opt<MinMax>,
    pub passage_gap_m: Opt<MinMax>,
    pub utrap_width_m: Opt<MinMax>,
    pub utrap_depth_m: Opt<MinMax>,
    pub current_mps: Opt<Num>,
    pub nav_sigma_m: Opt<Num>,
    pub scale: Opt<Num>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a table")]
pub(super) struct CriterionFile {
    pub time: Opt<Num>,
    pub energy: Opt<Num>,
    pub oscillation: Opt<Num>,
    pub deadband_deg_s: Opt<Num>,
}

/// A table's keys and values in file order, each with its key's span.
pub(super) struct Entries<K, V>(pub Vec<(Spanned<K>, Spanned<V>)>);

impl<'de, K: Deserialize<'de>, V: Deserialize<'de>> Deserialize<'de> for Entries<K, V> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Vis<K, V>(std::marker::PhantomData<(K, V)>);
        impl<'de, K: Deserialize<'de>, V: Deserialize<'de>> Visitor<'de> for Vis<K, V> {
            type Value = Entries<K, V>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a table")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Entries<K, V>, A::Error> {
                let mut entries = Vec::new();
                while let Some(key) = map.next_key()? {
                    entries.push((key, map.next_value()?));
                }
                Ok(Entries(entries))
            }
        }
        d.deserialize_map(Vis(std::marker::PhantomData))
    }
}

/// A `[sweep.params]` key: a `[planner]` parameter (not the period, which is `dt_s`).
pub(super) struct Swept(pub String);

impl<'de> Deserialize<'de> for Swept {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        if name != "period_s" && vpf::link::PARAM_NAMES.contains(&name.as_str()) {
            return Ok(Swept(name));
        }
        let names: Vec<&str> = vpf::link::PARAM_NAMES
            .iter()
            .copied()
            .filter(|n| *n != "period_s")
            .collect();
        let hint = match closest(&name, &names) {
            Some(c) => format!("did you mean `{c}`?"),
            None => format!("expected one of: {}", names.join(", ")),
        };
        Err(de::Error::custom(format!(
            "not a [planner] parameter ({hint})"
        )))
    }
}

/// `[min, max]`: two finite numbers.
pub(super) struct MinMax(pub f64, pub f64);

impl<'de> Deserialize<'de> for MinMax {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = MinMax;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("[min, max]")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<MinMax, A::Error> {
                let mut v = Vec::new();
                while let Some(Num(x)) = seq.next_element()? {
                    v.push(x);
                }
                match v[..] {
                    [min, max] => Ok(MinMax(min, max)),
                    _ => Err(de::Error::custom(format!(
                        "expected [min, max], got {} items",
                        v.len()
                    ))),
                }
            }
        }
        d.deserialize_any(V)
    }
}

// A `[planner]` value: an integer, a finite float or a string.
impl<'de> Deserialize<'de> for Value {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Value;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number or a string")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Value, E> {
                Ok(Value::Int(v))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Value, E> {
                let i = i64::try_from(v);
                i.map(Value::Int)
                    .map_err(|_| E::custom(format!("integer {v} is too large")))
            }
            fn visit_i128<E: de::Error>(self, v: i128) -> Result<Value, E> {
                Err(E::custom(format!("integer {v} is too large")))
            }
            fn visit_u128<E: de::Error>(self, v: u128) -> Result<Value, E> {
                Err(E::custom(format!("integer {v} is too large")))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Value, E> {
                if v.is_finite() {
                    Ok(Value::Float(v))
                } else {
                    Err(E::custom(format!("must be a finite number, got {v}")))
                }
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Value, E> {
                Ok(Value::Str(v.to_string()))
            }
        }
        d.deserialize_any(V)
    }
}

impl<'de> Deserialize<'de> for AxisFile {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = AxisFile;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a list of values or a range { min, max }")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<AxisFile, A::Error> {
                let seq = de::value::SeqAccessDeserializer::new(seq);
                Items::deserialize(seq).map(AxisFile::List)
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<AxisFile, A::Error> {
                RangeFile::deserialize(MapAccessDeserializer::new(map)).map(AxisFile::Range)
            }
        }
        d.deserialize_any(V)
    }
}

impl Item for String {
    const LIST: &'static str = "an array of strings";
}

impl Item for Value {
    const LIST: &'static str = "a list of values";
}

/// What the sweep file's tables are called in "unknown key in …".
pub(super) fn naming(
    _: &DeTable<'_>,
    parent: &[Seg<'_>],
) -> (String, Option<&'static [&'static str]>) {
    let name = match keys_of(parent)[..] {
        [] => "the sweep file".to_string(),
        ["sweep", "params", _] => "a parameter range".to_string(),
        ref keys => format!("[{}]", keys.join(".")),
    };
    (name, None)
}
