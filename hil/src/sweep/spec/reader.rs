//! The sweep spec's reader: the spanned TOML document walked table by table, in file order,
//! unknown keys refused with the scenario reader's "did you mean" hint, each refusal naming
//! file, line and key path as a scenario's do.

use std::ops::Range;

use toml::de::{DeTable, DeValue};
use toml::Spanned;

use super::Value;
pub(crate) use crate::scenario::type_name;
use crate::scenario::{unknown_key, ScenarioError, SourceText};

// ---------------------------------------------------------------------------------------------
// Typed access to the spanned document.

pub(crate) type Val<'a> = Spanned<DeValue<'a>>;

pub(crate) fn join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

/// A table of the document with its key path and the span of its header.
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

    /// Refuses any key not in `allowed`; `what` names the table in the message.
    pub(crate) fn allow(&self, allowed: &[&str], what: &str) -> Result<(), ScenarioError> {
        for (k, span, _) in &self.entries {
            if allowed.contains(k) {
                continue;
            }
            return Err(self
                .src
                .err(span, &self.key(k), unknown_key(k, allowed, what)));
        }
        Ok(())
    }

    pub(crate) fn missing(&self, key: &str) -> ScenarioError {
        self.src
            .err(&self.span, &self.key(key), "missing required key")
    }

    pub(crate) fn table(&self, key: &str) -> Result<Option<Table<'a>>, ScenarioError> {
        self.get(key)
            .map(|v| as_table(self.src, self.key(key), v))
            .transpose()
    }
}

pub(crate) fn as_table<'a>(
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

// ---------------------------------------------------------------------------------------------
// The spec's range-checked reads.

/// The sweep spec's range-checked reads, on a [`Table`].
pub(super) trait SpecReads<'a> {
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
pub(super) fn value_any(
    src: SourceText<'_>,
    key: &str,
    v: &Val<'_>,
) -> Result<Value, ScenarioError> {
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
