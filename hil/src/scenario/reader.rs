//! The reader under the schema: errors that name file, line and key path; the document's
//! spans; typed access to its tables and values with unknown keys refused and "did you mean"
//! hints. Shared with the sweep spec parser (`crate::sweep::spec`).

use std::fmt;
use std::ops::Range;

use toml::de::{DeTable, DeValue};
use toml::Spanned;
use vpf::field::shape::{MAX_EXTENT_M, MIN_EXTENT_M};

use super::{Window, MAX_POSITION_M};
use crate::types::P2;

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

    pub(super) fn column_of(&self, offset: usize) -> usize {
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
pub(super) struct Located<'a, T> {
    pub(super) v: T,
    pub(super) span: Range<usize>,
    pub(super) key: String,
    pub(super) src: SourceText<'a>,
}

impl<T> Located<'_, T> {
    pub(super) fn fail(&self, message: impl Into<String>) -> ScenarioError {
        self.src.err(&self.span, &self.key, message)
    }
}

impl Located<'_, f64> {
    /// `lo ..= hi`.
    pub(super) fn within(&self, lo: f64, hi: f64, unit: &str) -> Result<f64, ScenarioError> {
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
    pub(super) fn size(&self) -> Result<f64, ScenarioError> {
        if self.v <= 0.0 {
            return Err(self.fail(format!("must be > 0, got {}", self.v)));
        }
        self.within(f64::from(MIN_EXTENT_M), f64::from(MAX_EXTENT_M), "m")
    }
}

pub(super) fn unit_suffix(unit: &str) -> String {
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

pub(super) fn join(path: &str, key: &str) -> String {
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

    pub(super) fn has(&self, key: &str) -> bool {
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

    pub(super) fn got<T>(&self, key: &str, v: T, span: Range<usize>) -> Located<'a, T> {
        Located {
            v,
            span,
            key: self.key(key),
            src: self.src,
        }
    }

    pub(super) fn number(&self, key: &str) -> Result<Option<Located<'a, f64>>, ScenarioError> {
        self.get(key)
            .map(|v| value_number(self.src, &self.key(key), v).map(|x| self.got(key, x, v.span())))
            .transpose()
    }

    pub(super) fn req_number(&self, key: &str) -> Result<Located<'a, f64>, ScenarioError> {
        self.number(key)?.ok_or_else(|| self.missing(key))
    }

    pub(super) fn integer(&self, key: &str) -> Result<Option<Located<'a, i64>>, ScenarioError> {
        self.get(key)
            .map(|v| value_integer(self.src, &self.key(key), v).map(|x| self.got(key, x, v.span())))
            .transpose()
    }

    pub(super) fn string(&self, key: &str) -> Result<Option<Located<'a, &'a str>>, ScenarioError> {
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

    pub(super) fn boolean(&self, key: &str) -> Result<Option<bool>, ScenarioError> {
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

    pub(super) fn req_string(&self, key: &str) -> Result<Located<'a, &'a str>, ScenarioError> {
        self.string(key)?.ok_or_else(|| self.missing(key))
    }

    /// A pair `[x, y]` of finite numbers.
    pub(super) fn pair(&self, key: &str) -> Result<Option<Located<'a, P2>>, ScenarioError> {
        self.get(key)
            .map(|v| value_pair(self.src, &self.key(key), v).map(|p| self.got(key, p, v.span())))
            .transpose()
    }

    /// A position: a pair within ±[`MAX_POSITION_M`].
    pub(super) fn position(&self, key: &str) -> Result<Option<Located<'a, P2>>, ScenarioError> {
        let Some(p) = self.pair(key)? else {
            return Ok(None);
        };
        check_position(&p)?;
        Ok(Some(p))
    }

    pub(super) fn req_position(&self, key: &str) -> Result<Located<'a, P2>, ScenarioError> {
        self.position(key)?.ok_or_else(|| self.missing(key))
    }

    /// A velocity: a pair of at most `max` m/s.
    pub(super) fn velocity(&self, key: &str, max: f64) -> Result<Option<P2>, ScenarioError> {
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
    pub(super) fn window(&self, key: &str) -> Result<Option<Window>, ScenarioError> {
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
    pub(super) fn tables(&self, key: &str) -> Result<Vec<Table<'a>>, ScenarioError> {
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

pub(super) fn as_table<'a>(
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

pub(super) fn value_pair(src: SourceText<'_>, key: &str, v: &Val<'_>) -> Result<P2, ScenarioError> {
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

pub(super) fn check_position(p: &Located<'_, P2>) -> Result<(), ScenarioError> {
    if p.v.x.abs() > MAX_POSITION_M || p.v.y.abs() > MAX_POSITION_M {
        return Err(p.fail(format!(
            "coordinates must be within ±{MAX_POSITION_M} m, got [{}, {}]",
            p.v.x, p.v.y
        )));
    }
    Ok(())
}

/// The allowed key nearest to `key` by edit distance, if it is close enough to be a typo.
pub(super) fn closest<'k>(key: &str, allowed: &[&'k str]) -> Option<&'k str> {
    allowed
        .iter()
        .map(|a| (strsim::levenshtein(key, a), *a))
        .filter(|&(d, a)| d <= 2.max(a.len() / 4))
        .min_by_key(|&(d, _)| d)
        .map(|(_, a)| a)
}

/// Matches a string value against `(name, value)` choices.
pub(super) fn choose<T: Copy>(
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
