//! The sweep file's tables, each checked: `[craft]`, the fixed `[planner]` (by the scenario
//! parser's own `[planner]` rules), `[sweep]` and its parameters' axes, `[scenarios]`,
//! `[criterion]`.

use toml::Spanned;

use super::file::{AxisFile, CraftFile, CriterionFile, Entries, MinMax, ScenariosFile, SweepFile};
use super::{Axis, Craft, Mode, Param, Scenarios, Value, Weights, CHECK_DT_S, MAX_SETS};
use crate::scenario::{
    self, int_within, At, Int, ModelKind, Num, Opt, ScenarioError, Sensing, SourceText, Table,
};

pub(super) fn craft(root: &At<'_>, t: &Opt<Table<CraftFile>>) -> Result<Craft, ScenarioError> {
    let t = root.req("craft", t)?;
    let (at, f) = (root.child("craft", t.span()), t.get_ref());
    let m = at.req("model", &f.model)?;
    let model = m
        .get_ref()
        .parse::<ModelKind>()
        .map_err(|e| at.fail("model", &m.span(), e.to_string()))?;
    let margin_m = at.within("margin_m", at.req("margin_m", &f.margin_m)?, 0.0, 100.0, "")?;
    let label = f.label.as_ref().map_or(model.name(), |l| l.get_ref());
    Ok(Craft {
        model,
        margin_m,
        label: label.to_string(),
    })
}

/// The fixed `[planner]` keys, checked by the scenario parser on the spec's own text with every
/// line outside the table blanked (so its errors carry the spec's line numbers).
pub(super) fn base_planner(
    src: SourceText<'_>,
    t: &Opt<Entries<String, Value>>,
) -> Result<Vec<(String, Value)>, ScenarioError> {
    let Some(t) = t else {
        return Ok(Vec::new());
    };
    let entries = &t.get_ref().0;
    let out = entries
        .iter()
        .map(|(k, v)| (k.get_ref().clone(), v.get_ref().clone()))
        .collect();
    let last = entries
        .iter()
        .map(|(_, v)| v.span().end)
        .fold(t.span().end, usize::max);
    let (first_line, last_line) = (src.line_of(t.span().start), src.line_of(last));
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
    root: &At<'_>,
    t: &Opt<Table<SweepFile>>,
    base: &[(String, Value)],
) -> Result<SweepPart, ScenarioError> {
    let t = root.req("sweep", t)?;
    let (at, f) = (root.child("sweep", t.span()), t.get_ref());
    let mode = match f.mode.as_ref().map_or("grid", |m| m.get_ref().as_str()) {
        "grid" => {
            if let Some(v) = &f.samples {
                return Err(at.fail("samples", &v.span(), "only for mode = \"random\""));
            }
            Mode::Grid
        }
        "random" => Mode::Random {
            samples: int_within(
                &at,
                "samples",
                at.req("samples", &f.samples)?,
                1,
                MAX_SETS as i64,
            )? as usize,
        },
        other => {
            let span = f.mode.as_ref().map_or(0..0, Spanned::span);
            return Err(at.fail(
                "mode",
                &span,
                format!("unknown mode \"{other}\" (expected \"grid\" or \"random\")"),
            ));
        }
    };
    let p = at.req("params", &f.params)?;
    let pt = at.child("params", p.span());
    if p.get_ref().0.is_empty() {
        return Err(pt.refuse("no parameter to sweep"));
    }
    let mut params = Vec::new();
    for (k, v) in &p.get_ref().0 {
        let (name, kspan) = (k.get_ref().0.as_str(), k.span());
        if base.iter().any(|(b, _)| b == name) {
            return Err(pt.fail(
                name,
                &kspan,
                "is also fixed in [planner]: a parameter is either fixed or swept",
            ));
        }
        params.push(Param {
            name: name.to_string(),
            axis: axis(&pt, name, v, mode)?,
            line: pt.src.line_of(kspan.start),
        });
    }
    let heatmap = match &f.heatmap {
        None => None,
        Some(v) => {
            let names: Vec<&str> = v.get_ref().0.iter().map(|n| n.get_ref().as_str()).collect();
            let fail = |m: String| at.fail("heatmap", &v.span(), m);
            if names.len() != 2 || names[0] == names[1] {
                return Err(fail("expected two swept parameters, [\"x\", \"y\"]".into()));
            }
            if let Some(n) = names.iter().find(|n| !params.iter().any(|q| q.name == **n)) {
                return Err(fail(format!("`{n}` is not a swept parameter")));
            }
            Some((names[0].to_string(), names[1].to_string()))
        }
    };
    Ok((mode, params, heatmap))
}

fn axis(p: &At<'_>, k: &str, v: &Spanned<AxisFile>, mode: Mode) -> Result<Axis, ScenarioError> {
    match v.get_ref() {
        AxisFile::List(items) => {
            if items.0.is_empty() {
                return Err(p.fail(k, &v.span(), "needs at least one value"));
            }
            let mut values: Vec<Value> = Vec::new();
            for (i, item) in items.0.iter().enumerate() {
                let x = item.get_ref();
                if values.contains(x) {
                    return Err(p.fail(
                        &format!("{k}[{i}]"),
                        &item.span(),
                        format!("value {} is listed twice", x.toml()),
                    ));
                }
                values.push(x.clone());
            }
            Ok(Axis::List(values))
        }
        AxisFile::Range(r) => {
            if mode == Mode::Grid {
                return Err(p.fail(
                    k,
                    &v.span(),
                    "a range { min, max } needs mode = \"random\"; a grid lists its values",
                ));
            }
            let t = p.child(k, v.span());
            let (min_v, max_v) = (t.req("min", &r.min)?, t.req("max", &r.max)?);
            let number = |key: &str, v: &Spanned<Value>| match v.get_ref() {
                Value::Str(_) => Err(t.fail(key, &v.span(), "expected a number, got a string")),
                x => Ok(x.number().unwrap_or(0.0)),
            };
            let (min, max) = (number("min", min_v)?, number("max", max_v)?);
            let integer = matches!(
                (min_v.get_ref(), max_v.get_ref()),
                (Value::Int(_), Value::Int(_))
            );
            let log = r.log.as_ref().is_some_and(|l| *l.get_ref());
            if min > max {
                let m = format!("must be >= min ({min}), got {max}");
                return Err(t.fail("max", &max_v.span(), m));
            }
            if log && min <= 0.0 {
                let m = format!("a log range needs min > 0, got {min}");
                return Err(t.fail("min", &min_v.span(), m));
            }
            Ok(Axis::Range {
                min,
                max,
                log,
                integer,
            })
        }
    }
}

/// `key`'s number within `lo ..= hi`, if given.
fn num(
    at: &At<'_>,
    key: &str,
    v: &Opt<Num>,
    lo: f64,
    hi: f64,
) -> Result<Option<f64>, ScenarioError> {
    v.as_ref()
        .map(|v| at.within(key, v, lo, hi, ""))
        .transpose()
}

/// `key`'s `[min, max]` with `lo <= min <= max <= hi`, if given.
fn range(
    at: &At<'_>,
    key: &str,
    v: &Opt<MinMax>,
    lo: f64,
    hi: f64,
) -> Result<Option<(f64, f64)>, ScenarioError> {
    let Some(v) = v else {
        return Ok(None);
    };
    let MinMax(x, y) = *v.get_ref();
    if !(lo <= x && x <= y && y <= hi) {
        return Err(at.fail(
            key,
            &v.span(),
            format!("must be [min, max] with {lo} <= min <= max <= {hi}, got [{x}, {y}]"),
        ));
    }
    Ok(Some((x, y)))
}

/// `key`'s integer within `lo ..= hi`, if given.
fn int(
    at: &At<'_>,
    key: &str,
    v: &Opt<Int>,
    lo: i64,
    hi: i64,
) -> Result<Option<i64>, ScenarioError> {
    v.as_ref()
        .map(|v| int_within(at, key, v, lo, hi))
        .transpose()
}

pub(super) fn scenarios(
    root: &At<'_>,
    t: &Opt<Table<ScenariosFile>>,
) -> Result<Scenarios, ScenarioError> {
    let t = root.req("scenarios", t)?;
    let (at, f) = (root.child("scenarios", t.span()), t.get_ref());
    let mut s = Scenarios::default();
    if let Some(files) = &f.files {
        s.files = files
            .get_ref()
            .0
            .iter()
            .map(|f| f.get_ref().clone())
            .collect();
    }
    let count = |k: &str, v: &Opt<Int>| int(&at, k, v, 0, 100_000).map(|x| x.unwrap_or(0) as usize);
    s.clutter = count("clutter", &f.clutter)?;
    s.passage = count("passage", &f.passage)?;
    s.utrap = count("utrap", &f.utrap)?;
    for (i, name) in f
        .bench_families
        .iter()
        .flat_map(|v| &v.get_ref().0)
        .enumerate()
    {
        let Some(family) = crate::bench::worlds::Family::parse(name.get_ref()) else {
            return Err(at.fail(
                &format!("bench_families[{i}]"),
                &name.span(),
                format!(
                    "expected a bench family: one of {}",
                    crate::bench::worlds::FAMILIES.map(|f| f.name()).join(", ")
                ),
            ));
        };
        s.bench_families.push(family);
    }
    s.bench_count = count("bench_count", &f.bench_count)?;
    s.bench_first_seed =
        int(&at, "bench_first_seed", &f.bench_first_seed, 0, 1_000_000)?.unwrap_or(0) as u64;
    if s.bench_families.is_empty() {
        s.bench_count = 0;
    }
    if s.files.is_empty() && s.clutter + s.passage + s.utrap + s.bench_count == 0 {
        return Err(at.refuse(
            "no scenario: list `files` or ask for generated `clutter`, `passage`, `utrap` or \
             `bench_families` with `bench_count`",
        ));
    }
    let d = Scenarios::default();
    s.length_m = range(&at, "length_m", &f.length_m, 15.0, 1000.0)?.unwrap_or(d.length_m);
    if let Some(x) = &f.sensing {
        s.sensing = at.choose(
            "sensing",
            x,
            &[("contacts", Sensing::Contacts), ("sonar", Sensing::Sonar)],
            "sensing",
        )?;
    }
    s.speed_mps = num(&at, "speed_mps", &f.speed_mps, 0.05, 20.0)?.unwrap_or(d.speed_mps);
    s.time_factor = num(&at, "time_factor", &f.time_factor, 1.0, 100.0)?.unwrap_or(d.time_factor);
    s.duration_cap_s = num(&at, "duration_cap_s", &f.duration_cap_s, 1.0, 86_400.0)?;
    s.min_gap_m = num(&at, "min_gap_m", &f.min_gap_m, 0.5, 100.0)?.unwrap_or(d.min_gap_m);
    s.density = range(&at, "density", &f.density, 0.0, 10.0)?.unwrap_or(d.density);
    s.passage_gap_m =
        range(&at, "passage_gap_m", &f.passage_gap_m, 0.5, 50.0)?.unwrap_or(d.passage_gap_m);
    s.utrap_width_m =
        range(&at, "utrap_width_m", &f.utrap_width_m, 2.0, 100.0)?.unwrap_or(d.utrap_width_m);
    s.utrap_depth_m =
        range(&at, "utrap_depth_m", &f.utrap_depth_m, 1.0, 100.0)?.unwrap_or(d.utrap_depth_m);
    s.current_mps = num(&at, "current_mps", &f.current_mps, 0.0, 5.0)?.unwrap_or(d.current_mps);
    s.nav_sigma_m = num(&at, "nav_sigma_m", &f.nav_sigma_m, 0.0, 100.0)?.unwrap_or(d.nav_sigma_m);
    s.scale = num(&at, "scale", &f.scale, 0.1, 100.0)?.unwrap_or(d.scale);
    Ok(s)
}

pub(super) fn criterion(
    root: &At<'_>,
    t: &Opt<Table<CriterionFile>>,
) -> Result<Weights, ScenarioError> {
    let mut w = Weights::default();
    let Some(t) = t else {
        return Ok(w);
    };
    let (at, f) = (root.child("criterion", t.span()), t.get_ref());
    w.time = num(&at, "time", &f.time, 0.0, 1000.0)?.unwrap_or(w.time);
    w.energy = num(&at, "energy", &f.energy, 0.0, 1000.0)?.unwrap_or(w.energy);
    w.oscillation = num(&at, "oscillation", &f.oscillation, 0.0, 1000.0)?.unwrap_or(w.oscillation);
    if let Some(x) = num(&at, "deadband_deg_s", &f.deadband_deg_s, 0.0, 360.0)? {
        w.deadband = x.to_radians();
    }
    Ok(w)
}
