//! `runs.csv`: one row per finished run, appended and flushed as runs finish (which is what
//! makes a sweep resumable), read back for resuming, merging and reporting.

use super::measure::RunRow;
use super::spec::{Spec, Value};

/// The metric columns after `run,set,scenario` and the parameter columns.
pub const METRIC_COLUMNS: [&str; 11] = [
    "success",
    "collided",
    "min_clearance_m",
    "path_ratio",
    "time_s",
    "energy",
    "oscillation_per_100m",
    "ghosts",
    "sim_time_s",
    "error",
    "end",
];

/// The header's columns for `spec`.
pub fn header(spec: &Spec) -> Vec<String> {
    let mut cols: Vec<String> = vec!["run".into(), "set".into(), "scenario".into()];
    cols.extend(spec.params.iter().map(|p| p.name.clone()));
    cols.extend(METRIC_COLUMNS.iter().map(|c| c.to_string()));
    cols
}

/// A CSV writer on `w`: RFC 4180 quoting only where needed, `\n` line ends.
pub fn writer<W: std::io::Write>(w: W) -> ::csv::Writer<W> {
    ::csv::WriterBuilder::new()
        .terminator(::csv::Terminator::Any(b'\n'))
        .from_writer(w)
}

/// A text field on one line: the file is read back line by line.
pub fn one_line(s: &str) -> String {
    s.replace(['\n', '\r'], " ")
}

/// The fields of each line of `text` (RFC 4180 quoting, no embedded newlines), blank lines
/// skipped; a line that is not valid CSV gives no fields.
fn records(text: &str) -> impl Iterator<Item = Vec<String>> + '_ {
    text.lines().filter(|l| !l.trim().is_empty()).map(|l| {
        ::csv::ReaderBuilder::new()
            .has_headers(false)
            .from_reader(l.as_bytes())
            .into_records()
            .next()
            .and_then(Result::ok)
            .map(|r| r.iter().map(String::from).collect())
            .unwrap_or_default()
    })
}

fn num(x: f64, decimals: usize) -> String {
    if x.is_finite() {
        let s = format!("{x:.decimals$}");
        // No "-0.0000".
        if s.trim_start_matches('-')
            .chars()
            .all(|c| c == '0' || c == '.')
        {
            s.trim_start_matches('-').to_string()
        } else {
            s
        }
    } else {
        String::new()
    }
}

/// One row's fields. The last column, `end`, is a fixed `.`: a line cut off by an interruption
/// lacks it and is dropped on resume.
pub fn record(spec: &Spec, r: &RunRow) -> Vec<String> {
    let mut cols: Vec<String> = vec![r.run.to_string(), r.set.to_string(), one_line(&r.scenario)];
    if let Some(values) = spec.sets.get(r.set) {
        cols.extend(values.iter().map(|v| one_line(&v.plain())));
    }
    cols.extend([
        u8::from(r.success).to_string(),
        u8::from(r.collided).to_string(),
        num(r.min_clearance_m, 4),
        num(r.path_ratio, 4),
        num(r.time_s, 2),
        num(r.energy, 3),
        num(r.oscillation, 3),
        r.ghosts.to_string(),
        num(r.sim_time_s, 2),
        one_line(&r.error),
        ".".into(),
    ]);
    cols
}

fn float(s: &str) -> Option<f64> {
    if s.is_empty() {
        Some(f64::NAN)
    } else {
        s.parse().ok()
    }
}

/// Reads a line back; `None` if it is incomplete or does not fit the spec (wrong column count,
/// a set or run out of range, parameter values that are not the set's).
pub fn parse(spec: &Spec, c: &[String], total_runs: usize) -> Option<RunRow> {
    let np = spec.params.len();
    if c.len() != 3 + np + METRIC_COLUMNS.len() || c.last().map(String::as_str) != Some(".") {
        return None;
    }
    let run: usize = c[0].parse().ok()?;
    let set: usize = c[1].parse().ok()?;
    if run >= total_runs || set >= spec.sets.len() {
        return None;
    }
    for (cell, v) in c[3..3 + np].iter().zip(&spec.sets[set]) {
        if Value::parse_like(cell, v).as_ref() != Some(v) {
            return None;
        }
    }
    let m = &c[3 + np..];
    Some(RunRow {
        run,
        set,
        scenario: c[2].clone(),
        success: m[0] == "1",
        collided: m[1] == "1",
        min_clearance_m: float(&m[2])?,
        path_ratio: float(&m[3])?,
        time_s: float(&m[4])?,
        energy: float(&m[5])?,
        oscillation: float(&m[6])?,
        ghosts: m[7].parse().ok()?,
        sim_time_s: float(&m[8])?,
        error: m[9].clone(),
    })
}

/// `runs.csv` was written by another sweep: its header names other parameters.
#[derive(Debug, thiserror::Error)]
#[error("its header is not this sweep's:\n  found:    {found}\n  expected: {expected}")]
pub struct OtherHeader {
    /// The file's header.
    pub found: String,
    /// This sweep's.
    pub expected: String,
}

/// Reads `runs.csv`'s text: the complete rows, and how many lines were dropped as incomplete.
/// Errors if the header is not this spec's.
pub fn read(
    spec: &Spec,
    text: &str,
    total_runs: usize,
) -> Result<(Vec<RunRow>, usize), OtherHeader> {
    let mut lines = records(text);
    match lines.next() {
        Some(h) if h == header(spec) => {}
        Some(h) => {
            return Err(OtherHeader {
                found: h.join(","),
                expected: header(spec).join(","),
            })
        }
        None => return Ok((Vec::new(), 0)),
    }
    let mut rows = Vec::new();
    let mut dropped = 0;
    for l in lines {
        match parse(spec, &l, total_runs) {
            Some(r) => rows.push(r),
            None => dropped += 1,
        }
    }
    Ok((rows, dropped))
}

/// The whole file for `rows` (sorted by run), header included.
pub fn render(spec: &Spec, rows: &[RunRow]) -> String {
    let mut w = writer(Vec::new());
    // Writing to memory cannot fail.
    let _ = w.write_record(header(spec));
    for r in rows {
        let _ = w.write_record(record(spec, r));
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoting_round_trips_on_one_line() {
        let fields = ["a", "b,c", "say \"hi\"", "", "two\nlines"];
        let mut w = writer(Vec::new());
        w.write_record(fields.map(one_line)).unwrap();
        let text = String::from_utf8(w.into_inner().unwrap()).unwrap();
        assert_eq!(text, "a,\"b,c\",\"say \"\"hi\"\"\",,two lines\n");
        let back: Vec<Vec<String>> = records(&text).collect();
        assert_eq!(back, [fields.map(one_line)]);
    }
}
