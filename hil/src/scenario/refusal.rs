//! A refusal met while serde reads the file, put in the schema's words: the key path found from
//! the error's span in the document, an unknown key with a "did you mean" hint, a wrong type as
//! "expected a number, got a string".

use toml::de::{DeTable, DeValue};

use super::{ScenarioError, SourceText};

/// How a document's tables are called in "unknown key in …": given the document and the key
/// path of the table, its name, and its keys where they are not its struct's fields (an
/// obstacle's are its shape's).
pub(crate) type Naming =
    dyn Fn(&DeTable<'_>, &[Seg<'_>]) -> (String, Option<&'static [&'static str]>);

/// `e`, met reading `src`, its tables named by `naming`.
pub(crate) fn refusal(src: SourceText<'_>, e: &toml::de::Error, naming: &Naming) -> ScenarioError {
    let span = e.span().unwrap_or(0..0);
    // The text parsed before it was read, so it parses again.
    let doc = DeTable::parse(src.text)
        .map(|d| d.into_inner())
        .unwrap_or_default();
    let mut path = Vec::new();
    find(&doc, span.start, &mut path);
    let key = key_path(&path);
    let message = e.message();
    let message = if let Some(rest) = message.strip_prefix("unknown field `") {
        let (field, expected) = rest.split_once('`').unwrap_or((rest, ""));
        unknown_field(&doc, &path, field, expected, naming)
    } else if let Some((got, expected)) = message
        .strip_prefix("invalid type: ")
        .and_then(|m| m.rsplit_once(", expected "))
    {
        // The document's own type: serde sees a date-time as a table.
        let got = value_at(&doc, &path).map_or(got, |v| type_name(v));
        let expected = if expected == "a boolean" {
            "true or false"
        } else {
            expected
        };
        format!("expected {expected}, got {got}")
    } else if message == "floating-point number overflowed" {
        "the number overflows a 64-bit float (past ±1.8e308)".to_string()
    } else {
        message.to_string()
    };
    src.err(&span, &key, message)
}

/// A key of `parent`'s table not in its struct: serde names the struct's fields in `expected`.
fn unknown_field(
    doc: &DeTable<'_>,
    path: &[Seg<'_>],
    field: &str,
    expected: &str,
    naming: &Naming,
) -> String {
    // A date-time is read as a table with one private key.
    if field.starts_with("$__toml_private") {
        return "expected a table, got a date-time".into();
    }
    let (what, keys) = naming(doc, &path[..path.len().saturating_sub(1)]);
    let allowed: Vec<&str> = match keys {
        Some(keys) => keys.to_vec(),
        None => expected.split('`').skip(1).step_by(2).collect(),
    };
    unknown_key(field, &allowed, &what)
}

/// The keys of `path`, its array indices left out: `vehicle[0].survey` is `vehicle.survey`.
pub(crate) fn keys_of<'a>(path: &[Seg<'a>]) -> Vec<&'a str> {
    path.iter()
        .filter_map(|s| match s {
            Seg::Key(k) => Some(*k),
            Seg::Index(_) => None,
        })
        .collect()
}

/// "unknown key in `what`", with the nearest allowed key if it is close enough to be a typo.
pub(crate) fn unknown_key(key: &str, allowed: &[&str], what: &str) -> String {
    let hint = match closest(key, allowed) {
        Some(c) => format!(" (did you mean `{c}`?)"),
        None => format!(" (expected one of: {})", allowed.join(", ")),
    };
    format!("unknown key in {what}{hint}")
}

/// "unknown `what` "got" (expected "a" or "b")".
pub(super) fn unknown_choice(what: &str, got: &str, names: &[&str]) -> String {
    let names: Vec<String> = names.iter().map(|n| format!("\"{n}\"")).collect();
    format!("unknown {what} \"{got}\" (expected {})", names.join(" or "))
}

/// The allowed key nearest to `key` by edit distance, if it is close enough to be a typo.
pub(crate) fn closest<'k>(key: &str, allowed: &[&'k str]) -> Option<&'k str> {
    allowed
        .iter()
        .map(|a| (strsim::levenshtein(key, a), *a))
        .filter(|&(d, a)| d <= 2.max(a.len() / 4))
        .min_by_key(|&(d, _)| d)
        .map(|(_, a)| a)
}

/// The value at `path` in `doc`.
pub(crate) fn value_at<'a>(doc: &'a DeTable<'a>, path: &[Seg<'_>]) -> Option<&'a DeValue<'a>> {
    let (Seg::Key(first), rest) = path.split_first()? else {
        return None;
    };
    let mut v = doc.iter().find(|(k, _)| k.get_ref() == *first)?.1.get_ref();
    for seg in rest {
        v = match (seg, v) {
            (Seg::Key(key), DeValue::Table(t)) => t.iter().find(|(k, _)| k.get_ref() == *key)?.1,
            (Seg::Index(i), DeValue::Array(a)) => a.get(*i)?,
            _ => return None,
        }
        .get_ref();
    }
    Some(v)
}

/// A TOML value's type, as refusals name it ("a string", "an array").
fn type_name(v: &DeValue<'_>) -> &'static str {
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

// ---------------------------------------------------------------------------------------------
// The key path at a place in the document.

/// A step of a key path.
pub(crate) enum Seg<'a> {
    Key(&'a str),
    Index(usize),
}

fn key_path(path: &[Seg<'_>]) -> String {
    let mut s = String::new();
    for seg in path {
        match seg {
            Seg::Key(k) if s.is_empty() => s.push_str(k),
            Seg::Key(k) => {
                s.push('.');
                s.push_str(k);
            }
            Seg::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

/// Appends to `path` the deepest key or array item of `t` written at `at`; whether one is.
/// Every child is searched, not only those whose parent's span holds `at`: an array of tables
/// spans its headers, not its keys.
fn find<'a>(t: &'a DeTable<'a>, at: usize, path: &mut Vec<Seg<'a>>) -> bool {
    for (k, v) in t.iter() {
        path.push(Seg::Key(k.get_ref().as_ref()));
        if k.span().contains(&at) || find_in(v, at, path) || v.span().contains(&at) {
            return true;
        }
        path.pop();
    }
    false
}

fn find_in<'a>(v: &'a toml::Spanned<DeValue<'a>>, at: usize, path: &mut Vec<Seg<'a>>) -> bool {
    match v.get_ref() {
        DeValue::Table(t) => find(t, at, path),
        DeValue::Array(items) => items.iter().enumerate().any(|(i, item)| {
            path.push(Seg::Index(i));
            let found = find_in(item, at, path) || item.span().contains(&at);
            if !found {
                path.pop();
            }
            found
        }),
        _ => false,
    }
}
