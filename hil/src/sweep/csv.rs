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

/// The header line (no newline) for `spec`.
pub fn header(spec: &Spec) -> String {
    let mut cols: Vec<String> = vec!["run".into(), "set".into(), "scenario".into()];
    cols.extend(spec.params.iter().map(|p| p.name.clone()));
    cols.extend(METRIC_COLUMNS.iter().map(|c| c.to_string()));
    cols.join(",")
}

/// A field quoted if it needs to be.
pub fn quote(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\"").replace(['\n', '\r'], " "))
    } else {
        s.to_string()
    }
}

/// Splits one CSV line (RFC 4180 quoting, no embedded newlines).
pub fn split(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', true) => quoted = false,
            ('"', false) if cur.is_empty() => quoted = true,
            (',', false) => out.push(std::mem::take(&mut cur)),
            (c, _) => cur.push(c),
        }
    }
    out.push(cur);
    out
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

/// One row as a CSV line (no newline). The last column, `end`, is a fixed `.`: a line cut off
/// by an interruption lacks it and is dropped on resume.
pub fn line(spec: &Spec, r: &RunRow) -> String {
    let mut cols: Vec<String> = vec![r.run.to_string(), r.set.to_string(), quote(&r.scenario)];
    if let Some(values) = spec.sets.get(r.set) {
        cols.extend(values.iter().map(|v| quote(&v.plain())));
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
        quote(&r.error),
        ".".into(),
    ]);
    cols.join(",")
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
pub fn parse(spec: &Spec, line: &str, total_runs: usize) -> Option<RunRow> {
    let c = split(line);
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

/// Reads `runs.csv`'s text: the complete rows, and how many lines were dropped as incomplete.
/// Errors if the header is not this spec's.
pub fn read(spec: &Spec, text: &str, total_runs: usize) -> Result<(Vec<RunRow>, usize), String> {
    let mut lines = text.lines();
    match lines.next() {
        Some(h) if h == header(spec) => {}
        Some(h) => {
            return Err(format!(
                "its header is not this sweep's:\n  found:    {h}\n  expected: {}",
                header(spec)
            ))
        }
        None => return Ok((Vec::new(), 0)),
    }
    let mut rows = Vec::new();
    let mut dropped = 0;
    for l in lines.filter(|l| !l.trim().is_empty()) {
        match parse(spec, l, total_runs) {
            Some(r) => rows.push(r),
            None => dropped += 1,
        }
    }
    Ok((rows, dropped))
}

/// The whole file for `rows` (sorted by run), header included.
pub fn render(spec: &Spec, rows: &[RunRow]) -> String {
    let mut s = header(spec);
    s.push('\n');
    for r in rows {
        s.push_str(&line(spec, r));
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoting_round_trips() {
        let fields = ["a", "b,c", "say \"hi\"", ""];
        let line: Vec<String> = fields.iter().map(|f| quote(f)).collect();
        assert_eq!(split(&line.join(",")), fields);
    }
}
