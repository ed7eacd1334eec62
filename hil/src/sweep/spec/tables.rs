//! The sweep file's tables, each read and checked: `[craft]`, the fixed `[planner]` (by the
//! scenario parser's own `[planner]` rules), `[sweep]` and its parameters' axes, `[scenarios]`,
//! `[criterion]`.

use toml::de::DeValue;

use super::reader::{type_name, value_any, value_number, SpecReads, Table, Val};
use super::{Axis, Craft, Mode, Param, Scenarios, Value, Weights, CHECK_DT_S, MAX_SETS};
use crate::scenario::{self, ModelKind, ScenarioError, Sensing, SourceText};

pub(super) fn craft(root: &Table<'_>) -> Result<Craft, ScenarioError> {
    let t = root.table("craft")?.ok_or_else(|| root.missing("craft"))?;
    t.allow(&["model", "margin_m", "label"], "[craft]")?;
    let m = t.text("model")?.ok_or_else(|| t.missing("model"))?;
    let model = m.parse::<ModelKind>().map_err(|e| {
        let v = t.get("model").map_or(0..0, |v| v.span());
        t.src.err(&v, &t.key("model"), e.to_string())
    })?;
    let margin_m = t
        .num_in("margin_m", 0.0, 100.0)?
        .ok_or_else(|| t.missing("margin_m"))?;
    let label = t.text("label")?.unwrap_or(model.name()).to_string();
    Ok(Craft {
        model,
        margin_m,
        label,
    })
}

/// The fixed `[planner]` keys, checked by the scenario parser on the spec's own text with every
/// line outside the table blanked (so its errors carry the spec's line numbers).
pub(super) fn base_planner(
    root: &Table<'_>,
    src: SourceText<'_>,
) -> Result<Vec<(String, Value)>, ScenarioError> {
    let Some(t) = root.table("planner")? else {
        return Ok(Vec::new());
    };
    let mut out = Vec::new();
    let mut last = t.span.end;
    for (k, _, v) in &t.entries {
        out.push((k.to_string(), value_any(src, &t.key(k), v)?));
        last = last.max(v.span().end);
    }
    let (first_line, last_line) = (src.line_of(t.span.start), src.line_of(last));
    let kept: String = src
        .text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if (first_line..=last_line).contains(&(i + 1)) {
                format!("{l}\n")
            } else {
                "\n".to_string()
            }
        })
        .collect();
    scenario::parse_planner(&kept, src.file, CHECK_DT_S)?;
    Ok(out)
}

type SweepPart = (Mode, Vec<Param>, Option<(String, String)>);

pub(super) fn sweep(
    root: &Table<'_>,
    base: &[(String, Value)],
) -> Result<SweepPart, ScenarioError> {
    let t = root.table("sweep")?.ok_or_else(|| root.missing("sweep"))?;
    t.allow(&["mode", "samples", "heatmap", "params"], "[sweep]")?;
    let mode = match t.text("mode")?.unwrap_or("grid") {
        "grid" => {
            if let Some(v) = t.get("samples") {
                return Err(t.fail(v, "samples", "only for mode = \"random\""));
            }
            Mode::Grid
        }
        "random" => Mode::Random {
            samples: t
                .int_in("samples", 1, MAX_SETS as i64)?
                .ok_or_else(|| t.missing("samples"))? as usize,
        },
        other => {
            let v = t.get("mode").map_or(0..0, |v| v.span());
            return Err(t.src.err(
                &v,
                &t.key("mode"),
                format!("unknown mode \"{other}\" (expected \"grid\" or \"random\")"),
            ));
        }
    };
    let p = t.table("params")?.ok_or_else(|| t.missing("params"))?;
    if p.entries.is_empty() {
        return Err(t.src.err(&p.span, &p.path, "no parameter to sweep"));
    }
    let names: Vec<&str> = vpf::link::PARAM_NAMES
        .iter()
        .copied()
        .filter(|n| *n != "period_s")
        .collect();
    let mut params = Vec::new();
    for (k, kspan, v) in &p.entries {
        if !names.contains(k) {
            return Err(p.src.err(
                kspan,
                &p.key(k),
                format!(
                    "not a [planner] parameter (expected one of: {})",
                    names.join(", ")
                ),
            ));
        }
        if base.iter().any(|(b, _)| b == k) {
            return Err(p.src.err(
                kspan,
                &p.key(k),
                "is also fixed in [planner]: a parameter is either fixed or swept",
            ));
        }
        let axis = axis(&p, k, v, mode)?;
        params.push(Param {
            name: k.to_string(),
            axis,
            line: p.src.line_of(kspan.start),
        });
    }
    let heatmap = match t.get("heatmap") {
        None => None,
        Some(v) => {
            let bad = || {
                t.fail(
                    v,
                    "heatmap",
                    "expected two swept parameters, [\"x\", \"y\"]",
                )
            };
            let DeValue::Array(a) = v.get_ref() else {
                return Err(bad());
            };
            let names: Vec<&str> = a
                .iter()
                .filter_map(|x| match x.get_ref() {
                    DeValue::String(s) => Some(s.as_ref()),
                    _ => None,
                })
                .collect();
            if names.len() != 2 || a.len() != 2 || names[0] == names[1] {
                return Err(bad());
            }
            for n in &names {
                if !params.iter().any(|q| q.name == *n) {
                    return Err(t.fail(v, "heatmap", format!("`{n}` is not a swept parameter")));
                }
            }
            Some((names[0].to_string(), names[1].to_string()))
        }
    };
    Ok((mode, params, heatmap))
}

pub(super) fn axis(p: &Table<'_>, k: &str, v: &Val<'_>, mode: Mode) -> Result<Axis, ScenarioError> {
    let key = p.key(k);
    match v.get_ref() {
        DeValue::Array(a) => {
            if a.is_empty() {
                return Err(p.fail(v, k, "needs at least one value"));
            }
            let mut values = Vec::new();
            for (i, item) in a.iter().enumerate() {
                let x = value_any(p.src, &format!("{key}[{i}]"), item)?;
                if values.contains(&x) {
                    return Err(p.src.err(
                        &item.span(),
                        &format!("{key}[{i}]"),
                        format!("value {} is listed twice", x.toml()),
                    ));
                }
                values.push(x);
            }
            Ok(Axis::List(values))
        }
        DeValue::Table(t) => {
            let t = Table::new(p.src, key.clone(), v.span(), t);
            if mode == Mode::Grid {
                return Err(p.fail(
                    v,
                    k,
                    "a range { min, max } needs mode = \"random\"; a grid lists its values",
                ));
            }
            t.allow(&["min", "max", "log"], "a parameter range")?;
            let min_v = t.get("min").ok_or_else(|| t.missing("min"))?;
            let max_v = t.get("max").ok_or_else(|| t.missing("max"))?;
            let min = value_number(t.src, &t.key("min"), min_v)?;
            let max = value_number(t.src, &t.key("max"), max_v)?;
            let integer = matches!(min_v.get_ref(), DeValue::Integer(_))
                && matches!(max_v.get_ref(), DeValue::Integer(_));
            let log = match t.get("log") {
                None => false,
                Some(l) => match l.get_ref() {
                    DeValue::Boolean(b) => *b,
                    other => {
                        return Err(t.fail(
                            l,
                            "log",
                            format!("expected a boolean, got {}", type_name(other)),
                        ))
                    }
                },
            };
            if min > max {
                return Err(t.fail(max_v, "max", format!("must be >= min ({min}), got {max}")));
            }
            if log && min <= 0.0 {
                return Err(t.fail(
                    min_v,
                    "min",
                    format!("a log range needs min > 0, got {min}"),
                ));
            }
            Ok(Axis::Range {
                min,
                max,
                log,
                integer,
            })
        }
        other => Err(p.fail(
            v,
            k,
            format!(
                "expected a list of values or a range {{ min, max }}, got {}",
                type_name(other)
            ),
        )),
    }
}

pub(super) fn scenarios(root: &Table<'_>) -> Result<Scenarios, ScenarioError> {
    let mut s = Scenarios::default();
    let t = root
        .table("scenarios")?
        .ok_or_else(|| root.missing("scenarios"))?;
    t.allow(
        &[
            "files",
            "clutter",
            "passage",
            "utrap",
            "bench_families",
            "bench_count",
            "bench_first_seed",
            "length_m",
            "sensing",
            "speed_mps",
            "time_factor",
            "duration_cap_s",
            "min_gap_m",
            "density",
            "passage_gap_m",
            "utrap_width_m",
            "utrap_depth_m",
            "current_mps",
            "nav_sigma_m",
            "scale",
        ],
        "[scenarios]",
    )?;
    if let Some(v) = t.get("files") {
        let DeValue::Array(a) = v.get_ref() else {
            return Err(t.fail(v, "files", "expected a list of scenario file paths"));
        };
        for (i, item) in a.iter().enumerate() {
            match item.get_ref() {
                DeValue::String(f) => s.files.push(f.to_string()),
                other => {
                    return Err(t.src.err(
                        &item.span(),
                        &format!("{}[{i}]", t.key("files")),
                        format!("expected a path (string), got {}", type_name(other)),
                    ))
                }
            }
        }
    }
    let count = |k: &str| t.int_in(k, 0, 100_000).map(|x| x.unwrap_or(0) as usize);
    s.clutter = count("clutter")?;
    s.passage = count("passage")?;
    s.utrap = count("utrap")?;
    if let Some(v) = t.get("bench_families") {
        let DeValue::Array(a) = v.get_ref() else {
            return Err(t.fail(v, "bench_families", "expected a list of bench family names"));
        };
        for (i, item) in a.iter().enumerate() {
            let family = match item.get_ref() {
                DeValue::String(f) => crate::bench::worlds::Family::parse(f),
                _ => None,
            };
            let Some(family) = family else {
                return Err(t.src.err(
                    &item.span(),
                    &format!("{}[{i}]", t.key("bench_families")),
                    format!(
                        "expected a bench family: one of {}",
                        crate::bench::worlds::FAMILIES.map(|f| f.name()).join(", ")
                    ),
                ));
            };
            s.bench_families.push(family);
        }
    }
    s.bench_count = count("bench_count")?;
    s.bench_first_seed = t.int_in("bench_first_seed", 0, 1_000_000)?.unwrap_or(0) as u64;
    if s.bench_families.is_empty() {
        s.bench_count = 0;
    }
    if s.files.is_empty() && s.clutter + s.passage + s.utrap + s.bench_count == 0 {
        return Err(t.src.err(
            &t.span,
            &t.path,
            "no scenario: list `files` or ask for generated `clutter`, `passage`, `utrap` or \
             `bench_families` with `bench_count`",
        ));
    }
    if let Some(r) = t.range_in("length_m", 15.0, 1000.0)? {
        s.length_m = r;
    }
    if let Some(x) = t.text("sensing")? {
        s.sensing = match x {
            "contacts" => Sensing::Contacts,
            "sonar" => Sensing::Sonar,
            other => {
                let v = t.get("sensing").map_or(0..0, |v| v.span());
                return Err(t.src.err(
                    &v,
                    &t.key("sensing"),
                    format!("unknown sensing \"{other}\" (expected \"contacts\" or \"sonar\")"),
                ));
            }
        };
    }
    if let Some(x) = t.num_in("speed_mps", 0.05, 20.0)? {
        s.speed_mps = x;
    }
    if let Some(x) = t.num_in("time_factor", 1.0, 100.0)? {
        s.time_factor = x;
    }
    s.duration_cap_s = t.num_in("duration_cap_s", 1.0, 86_400.0)?;
    if let Some(x) = t.num_in("min_gap_m", 0.5, 100.0)? {
        s.min_gap_m = x;
    }
    if let Some(r) = t.range_in("density", 0.0, 10.0)? {
        s.density = r;
    }
    if let Some(r) = t.range_in("passage_gap_m", 0.5, 50.0)? {
        s.passage_gap_m = r;
    }
    if let Some(r) = t.range_in("utrap_width_m", 2.0, 100.0)? {
        s.utrap_width_m = r;
    }
    if let Some(r) = t.range_in("utrap_depth_m", 1.0, 100.0)? {
        s.utrap_depth_m = r;
    }
    if let Some(x) = t.num_in("current_mps", 0.0, 5.0)? {
        s.current_mps = x;
    }
    if let Some(x) = t.num_in("nav_sigma_m", 0.0, 100.0)? {
        s.nav_sigma_m = x;
    }
    if let Some(x) = t.num_in("scale", 0.1, 100.0)? {
        s.scale = x;
    }
    Ok(s)
}

pub(super) fn criterion(root: &Table<'_>) -> Result<Weights, ScenarioError> {
    let mut w = Weights::default();
    let Some(t) = root.table("criterion")? else {
        return Ok(w);
    };
    t.allow(
        &["time", "energy", "oscillation", "deadband_deg_s"],
        "[criterion]",
    )?;
    if let Some(x) = t.num_in("time", 0.0, 1000.0)? {
        w.time = x;
    }
    if let Some(x) = t.num_in("energy", 0.0, 1000.0)? {
        w.energy = x;
    }
    if let Some(x) = t.num_in("oscillation", 0.0, 1000.0)? {
        w.oscillation = x;
    }
    if let Some(x) = t.num_in("deadband_deg_s", 0.0, 360.0)? {
        w.deadband = x.to_radians();
    }
    Ok(w)
}
