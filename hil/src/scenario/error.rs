//! Refusals that name the file, the line and the key path, and the places (a table's key path
//! and span) the checks after reading report them at.

use std::fmt;
use std::ops::Range;

use toml::Spanned;

// ---------------------------------------------------------------------------------------------
// Errors.

/// A refused scenario: where and why.
///
/// Displays as `FILE:LINE: key `KEY`: MESSAGE`. Errors that are not about one key (TOML syntax
/// errors, unreadable files) display as `FILE:LINE:COLUMN: MESSAGE` and `FILE: MESSAGE`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScenarioError {
    /// The file name as given to [`load`](super::load) or [`parse`](super::parse).
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
// Places.

/// Where a table of the file is — its key path (`vehicle[1].formation`) and span — for the
/// checks that follow reading, which report at one of its keys.
#[derive(Clone)]
pub(crate) struct At<'a> {
    pub(crate) src: SourceText<'a>,
    pub(crate) path: String,
    pub(crate) span: Range<usize>,
}

impl<'a> At<'a> {
    /// The root table (its span empty: a missing top-level key is reported at line 1).
    pub(crate) fn root(src: SourceText<'a>) -> Self {
        At {
            src,
            path: String::new(),
            span: 0..0,
        }
    }

    /// Table `key` of this one, spanning `span`.
    pub(crate) fn child(&self, key: &str, span: Range<usize>) -> Self {
        At {
            src: self.src,
            path: self.key(key),
            span,
        }
    }

    /// The key path of `key` in this table.
    pub(crate) fn key(&self, key: &str) -> String {
        if self.path.is_empty() {
            key.to_string()
        } else {
            format!("{}.{key}", self.path)
        }
    }

    /// A refusal of `key`'s value, written at `span`.
    pub(crate) fn fail(
        &self,
        key: &str,
        span: &Range<usize>,
        message: impl Into<String>,
    ) -> ScenarioError {
        self.src.err(span, &self.key(key), message)
    }

    /// A refusal of the whole table (at its header).
    pub(crate) fn refuse(&self, message: impl Into<String>) -> ScenarioError {
        self.src.err(&self.span, &self.path, message)
    }

    /// `key` is required and absent: reported at the table's header.
    pub(crate) fn missing(&self, key: &str) -> ScenarioError {
        self.fail(key, &self.span, "missing required key")
    }

    /// The value of required `key`, or its refusal.
    pub(crate) fn req<'v, T>(
        &self,
        key: &str,
        v: &'v Option<Spanned<T>>,
    ) -> Result<&'v Spanned<T>, ScenarioError> {
        v.as_ref().ok_or_else(|| self.missing(key))
    }
}
