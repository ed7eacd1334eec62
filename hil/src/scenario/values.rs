//! The leaf values of a scenario file as serde reads them — a finite number, an integer, a pair
//! `[x, y]`, a table, an array — each refusing a wrong type in the schema's words, and the range
//! checks the builders apply to them at their keys.

use std::fmt;
use std::marker::PhantomData;

use serde::de::value::MapAccessDeserializer;
use serde::de::{self, Deserialize, Deserializer, MapAccess, SeqAccess, Visitor};
use toml::Spanned;
use vpf::field::shape::{MAX_EXTENT_M, MIN_EXTENT_M};

use super::{unknown_choice, At, ScenarioError, Window, MAX_POSITION_M};
use crate::types::P2;

/// A finite number; an integer is accepted where a number is expected.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Num(pub(crate) f64);

/// An integer.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Int(pub(crate) i64);

/// A pair `[x, y]` of finite numbers.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pair(pub(crate) P2);

/// A table, and only a table (serde would read an array as a struct's fields in order).
#[derive(Debug)]
pub(crate) struct Table<T>(pub(crate) T);

impl<T> std::ops::Deref for Table<T> {
    type Target = T;
    fn deref(&self) -> &T {
        &self.0
    }
}

/// An array whose items are `T`, refused as a whole with `T`'s [`Item::LIST`] when it is not
/// an array.
#[derive(Debug)]
pub(crate) struct Items<T>(pub(crate) Vec<Spanned<T>>);

impl<T> Default for Items<T> {
    fn default() -> Self {
        Items(Vec::new())
    }
}

/// What an array of these is called in a refusal.
pub(crate) trait Item {
    const LIST: &'static str;
}

fn too_large<E: de::Error>(v: impl fmt::Display) -> E {
    E::custom(format!("integer {v} is too large"))
}

impl<'de> Deserialize<'de> for Num {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Num;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Num, E> {
                Ok(Num(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Num, E> {
                i64::try_from(v).map_err(|_| too_large(v))?;
                Ok(Num(v as f64))
            }
            fn visit_i128<E: de::Error>(self, v: i128) -> Result<Num, E> {
                Err(too_large(v))
            }
            fn visit_u128<E: de::Error>(self, v: u128) -> Result<Num, E> {
                Err(too_large(v))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Num, E> {
                if v.is_finite() {
                    Ok(Num(v))
                } else {
                    Err(E::custom(format!("must be a finite number, got {v}")))
                }
            }
        }
        d.deserialize_any(V)
    }
}

impl<'de> Deserialize<'de> for Int {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Int;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an integer")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Int, E> {
                Ok(Int(v))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Int, E> {
                i64::try_from(v).map(Int).map_err(|_| too_large(v))
            }
            fn visit_i128<E: de::Error>(self, v: i128) -> Result<Int, E> {
                Err(too_large(v))
            }
            fn visit_u128<E: de::Error>(self, v: u128) -> Result<Int, E> {
                Err(too_large(v))
            }
        }
        d.deserialize_any(V)
    }
}

impl<'de> Deserialize<'de> for Pair {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Pair;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a pair [x, y]")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Pair, A::Error> {
                let mut xy = Vec::new();
                while let Some(Num(x)) = seq.next_element()? {
                    xy.push(x);
                }
                match xy[..] {
                    [x, y] => Ok(Pair(P2::new(x, y))),
                    _ => Err(de::Error::custom(format!(
                        "expected a pair [x, y], got an array of {} items",
                        xy.len()
                    ))),
                }
            }
        }
        d.deserialize_any(V)
    }
}

impl<'de, T: Deserialize<'de> + Item> Deserialize<'de> for Items<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(PhantomData<T>);
        impl<'de, T: Deserialize<'de> + Item> Visitor<'de> for V<T> {
            type Value = Items<T>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(T::LIST)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Items<T>, A::Error> {
                let mut items = Vec::new();
                while let Some(item) = seq.next_element()? {
                    items.push(item);
                }
                Ok(Items(items))
            }
        }
        d.deserialize_any(V(PhantomData))
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Table<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for V<T> {
            type Value = Table<T>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a table")
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Table<T>, A::Error> {
                T::deserialize(MapAccessDeserializer::new(map)).map(Table)
            }
        }
        d.deserialize_any(V(PhantomData))
    }
}

impl Item for Pair {
    const LIST: &'static str = "an array of [x, y] vertices";
}

// ---------------------------------------------------------------------------------------------
// Range checks, each refusal at its key.

/// ` unit`, or nothing for a plain number.
pub(crate) fn unit_suffix(unit: &str) -> String {
    if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    }
}

impl At<'_> {
    /// `key`'s number within `lo ..= hi`.
    pub(crate) fn within(
        &self,
        key: &str,
        v: &Spanned<Num>,
        lo: f64,
        hi: f64,
        unit: &str,
    ) -> Result<f64, ScenarioError> {
        let x = v.get_ref().0;
        if (lo..=hi).contains(&x) {
            return Ok(x);
        }
        let m = format!("must be in {lo} ..= {hi}{}, got {x}", unit_suffix(unit));
        Err(self.fail(key, &v.span(), m))
    }

    /// `key`'s number > 0 and within `lo ..= hi` (unit `unit`).
    pub(crate) fn positive(
        &self,
        key: &str,
        v: &Spanned<Num>,
        (lo, hi): (f64, f64),
        unit: &str,
    ) -> Result<f64, ScenarioError> {
        let x = v.get_ref().0;
        if x <= 0.0 {
            return Err(self.fail(key, &v.span(), format!("must be > 0, got {x}")));
        }
        self.within(key, v, lo, hi, unit)
    }

    /// A size of a shape: > 0, and within the firmware's shape limits.
    pub(crate) fn size(&self, key: &str, v: &Spanned<Num>) -> Result<f64, ScenarioError> {
        let limits = (f64::from(MIN_EXTENT_M), f64::from(MAX_EXTENT_M));
        self.positive(key, v, limits, "m")
    }

    /// An angle in degrees within ±360, in radians; 0 when absent.
    pub(crate) fn degrees(
        &self,
        key: &str,
        v: &Option<Spanned<Num>>,
    ) -> Result<f64, ScenarioError> {
        match v {
            Some(a) => Ok(self.within(key, a, -360.0, 360.0, "degrees")?.to_radians()),
            None => Ok(0.0),
        }
    }

    /// A position: a pair within ±[`MAX_POSITION_M`].
    pub(crate) fn position(&self, key: &str, v: &Spanned<Pair>) -> Result<P2, ScenarioError> {
        let p = v.get_ref().0;
        if p.x.abs() > MAX_POSITION_M || p.y.abs() > MAX_POSITION_M {
            return Err(self.fail(
                key,
                &v.span(),
                format!(
                    "coordinates must be within ±{MAX_POSITION_M} m, got [{}, {}]",
                    p.x, p.y
                ),
            ));
        }
        Ok(p)
    }

    /// A velocity: a pair of at most `max` m/s; zero when absent.
    pub(crate) fn velocity(
        &self,
        key: &str,
        v: &Option<Spanned<Pair>>,
        max: f64,
    ) -> Result<P2, ScenarioError> {
        let Some(v) = v else {
            return Ok(P2::default());
        };
        let speed = v.get_ref().0.norm();
        if speed > max {
            return Err(self.fail(
                key,
                &v.span(),
                format!("speed must be at most {max} m/s, got {speed}"),
            ));
        }
        Ok(v.get_ref().0)
    }

    /// A time window `[from_s, to_s]` with 0 ≤ from < to.
    pub(crate) fn window(
        &self,
        key: &str,
        v: &Option<Spanned<Pair>>,
    ) -> Result<Option<Window>, ScenarioError> {
        let Some(w) = v else {
            return Ok(None);
        };
        let P2 { x: from_s, y: to_s } = w.get_ref().0;
        if from_s < 0.0 || to_s <= from_s {
            return Err(self.fail(
                key,
                &w.span(),
                format!("must be [from_s, to_s] with 0 <= from_s < to_s, got [{from_s}, {to_s}]"),
            ));
        }
        Ok(Some(Window { from_s, to_s }))
    }

    /// Matches `key`'s string against `(name, value)` choices.
    pub(crate) fn choose<T: Copy>(
        &self,
        key: &str,
        s: &Spanned<String>,
        choices: &[(&str, T)],
        what: &str,
    ) -> Result<T, ScenarioError> {
        match choices.iter().find(|c| c.0 == s.get_ref()) {
            Some(&(_, t)) => Ok(t),
            None => {
                let names: Vec<&str> = choices.iter().map(|c| c.0).collect();
                let m = unknown_choice(what, s.get_ref(), &names);
                Err(self.fail(key, &s.span(), m))
            }
        }
    }
}

/// An integer value checked within `lo ..= hi` (its refusal at `key`).
pub(crate) fn int_within(
    at: &At<'_>,
    key: &str,
    v: &Spanned<Int>,
    lo: i64,
    hi: i64,
) -> Result<i64, ScenarioError> {
    let i = v.get_ref().0;
    if (lo..=hi).contains(&i) {
        Ok(i)
    } else {
        Err(at.fail(key, &v.span(), format!("must be in {lo} ..= {hi}, got {i}")))
    }
}
