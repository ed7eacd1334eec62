//! A vehicle's waypoint mission in a scenario file: `waypoints = [...]` or a `[vehicle.survey]`,
//! with `end`, `loiter_radius_m` and `loiter_clockwise` (hil/scenarios/README.md). Checked here
//! with the library's own rules (`vpf::planner::mission`), each refusal at its key.

use vpf::planner::{MissionEnd, Survey, Waypoint, Waypoints, MAX_WAYPOINTS};
use vpf::Params;

use super::{type_name, value_pair, DeValue, Located, ScenarioError, Table, Val};
use crate::types::P2;

/// The keys of a vehicle's mission, besides `goal`.
pub(super) const KEYS: [&str; 5] = [
    "waypoints",
    "survey",
    "end",
    "loiter_radius_m",
    "loiter_clockwise",
];

/// A vehicle's waypoint mission, as the firmware is given it.
#[derive(Clone, Debug, PartialEq)]
pub struct VehicleMission {
    /// The waypoints and the end (a survey's expanded by the library, as the firmware does).
    pub waypoints: Waypoints,
    /// The survey it came from, sent as one `Survey` message; `None`: sent item by item.
    pub survey: Option<Survey>,
}

impl VehicleMission {
    /// Its waypoints' positions, in order.
    pub fn positions(&self) -> Vec<P2> {
        self.waypoints
            .as_slice()
            .iter()
            .map(|w| {
                let p = w.position();
                P2::new(f64::from(p.x), f64::from(p.y))
            })
            .collect()
    }
}

/// A limit of the library's as the file writes it (`0.01`, not `0.009999999776482582`).
fn limit(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(f64::from(v))
}

/// A waypoint's position as written, for the checks against obstacles.
pub(super) struct Placed<'a> {
    pub(super) at: Located<'a, P2>,
}

/// The mission of vehicle table `t`, if it has one, with where each waypoint was written (a
/// survey's all at its table).
pub(super) fn parse<'a>(
    t: &Table<'a>,
    params: &Params,
) -> Result<Option<(VehicleMission, Vec<Placed<'a>>)>, ScenarioError> {
    let end = end(t)?;
    let waypoints = t.get("waypoints");
    let survey = t.table("survey")?;
    let (list, placed, survey) = match (waypoints, survey) {
        (Some(_), Some(s)) => {
            return Err(s
                .src
                .err(&s.span, &s.path, "give `waypoints` or `survey`, not both"))
        }
        (None, None) => {
            if let Some(k) = ["end", "loiter_radius_m", "loiter_clockwise"]
                .iter()
                .find(|k| t.get(k).is_some())
            {
                return Err(t.src.err(
                    &t.span_of(k),
                    &t.key(k),
                    "applies to a waypoint mission: give `waypoints` or a `survey`",
                ));
            }
            return Ok(None);
        }
        (Some(v), None) => {
            let (list, placed) = list(t, v, params)?;
            (list, placed, None)
        }
        (None, Some(s)) => {
            let survey = survey_of(&s, params)?;
            let list = survey
                .waypoints()
                .map_err(|e| s.src.err(&s.span, &s.path, e.to_string()))?;
            let placed = list
                .iter()
                .map(|w| {
                    let p = w.position();
                    Placed {
                        at: Located {
                            v: P2::new(f64::from(p.x), f64::from(p.y)),
                            span: s.span.clone(),
                            key: s.path.clone(),
                            src: s.src,
                        },
                    }
                })
                .collect();
            (list.to_vec(), placed, Some(survey))
        }
    };
    let waypoints =
        Waypoints::new(&list, end).map_err(|e| t.src.err(&t.span, &t.path, e.to_string()))?;
    Ok(Some((VehicleMission { waypoints, survey }, placed)))
}

fn end(t: &Table<'_>) -> Result<MissionEnd, ScenarioError> {
    let kind = match t.string("end")? {
        Some(s) => super::choose(&s, &[("hold", false), ("loiter", true)], "end")?,
        None => false,
    };
    let radius = t.number("loiter_radius_m")?;
    let clockwise = t.boolean("loiter_clockwise")?;
    if !kind {
        if let Some(k) = ["loiter_radius_m", "loiter_clockwise"]
            .iter()
            .find(|k| t.get(k).is_some())
        {
            return Err(t
                .src
                .err(&t.span_of(k), &t.key(k), "applies to end = \"loiter\" only"));
        }
        return Ok(MissionEnd::Hold);
    }
    let (lo, hi) = vpf::planner::mission::LOITER_RADIUS_M;
    let radius = radius.ok_or_else(|| {
        t.src.err(
            &t.span_of("end"),
            &t.key("loiter_radius_m"),
            "missing: end = \"loiter\" circles the last waypoint at this radius",
        )
    })?;
    let radius_m = radius.within(limit(lo), limit(hi), "m")?;
    Ok(MissionEnd::Loiter {
        radius_m: radius_m as f32,
        clockwise: clockwise.unwrap_or(false),
    })
}

/// `waypoints = [[x, y], { at = [x, y], radius_m = r, speed = v }, ...]`.
fn list<'a>(
    t: &Table<'a>,
    v: &'a Val<'a>,
    params: &Params,
) -> Result<(Vec<Waypoint>, Vec<Placed<'a>>), ScenarioError> {
    let key = t.key("waypoints");
    let DeValue::Array(items) = v.get_ref() else {
        return Err(t.src.err(
            &v.span(),
            &key,
            format!(
                "expected an array of waypoints ([x, y] or {{ at = [x, y], radius_m = .., speed = .. }}), got {}",
                type_name(v.get_ref())
            ),
        ));
    };
    if items.is_empty() {
        return Err(t.src.err(&v.span(), &key, "no waypoint: give at least one"));
    }
    if items.len() > MAX_WAYPOINTS {
        return Err(t.src.err(
            &v.span(),
            &key,
            format!(
                "{} waypoints; a mission holds at most {MAX_WAYPOINTS} (fly a longer route as \
                 several scenarios or missions)",
                items.len()
            ),
        ));
    }
    let mut list = Vec::new();
    let mut placed = Vec::new();
    for (i, item) in items.iter().enumerate() {
        let k = format!("{key}[{i}]");
        let (at, radius, speed) = match item.get_ref() {
            DeValue::Table(_) => {
                let w = super::as_table(t.src, k.clone(), item)?;
                w.allow(&["at", "radius_m", "speed"], "a waypoint")?;
                let at = w.req_position("at")?;
                let radius = match w.number("radius_m")? {
                    Some(r) => {
                        if r.v <= 0.0 {
                            return Err(r.fail(format!("must be > 0, got {}", r.v)));
                        }
                        r.within(
                            0.0,
                            limit(vpf::planner::mission::MAX_WAYPOINT_RADIUS_M),
                            "m",
                        )?
                    }
                    None => f64::from(params.arrival_radius_m),
                };
                let speed = match w.number("speed")? {
                    Some(s) => Some(s.within(
                        limit(vpf::planner::mission::MIN_WAYPOINT_SPEED),
                        limit(vpf::planner::mission::MAX_WAYPOINT_SPEED),
                        "m/s",
                    )?),
                    None => None,
                };
                (at, radius, speed)
            }
            _ => {
                let at = Located {
                    v: value_pair(t.src, &k, item)?,
                    span: item.span(),
                    key: k.clone(),
                    src: t.src,
                };
                super::check_position(&at)?;
                (at, f64::from(params.arrival_radius_m), None)
            }
        };
        let w = Waypoint::new(at.v.to_vpf(), radius as f32)
            .and_then(|w| w.with_speed(speed.map(|s| s as f32)))
            .map_err(|e| at.fail(format!("refused by vpf: {e}")))?;
        list.push(w);
        placed.push(Placed { at });
    }
    Ok((list, placed))
}

/// `[vehicle.survey]`: corner, length_m, width_m, heading_deg, spacing_m, radius_m, speed.
fn survey_of(s: &Table<'_>, params: &Params) -> Result<Survey, ScenarioError> {
    s.allow(
        &[
            "corner",
            "length_m",
            "width_m",
            "heading_deg",
            "spacing_m",
            "radius_m",
            "speed",
        ],
        "a survey",
    )?;
    let side = vpf::planner::mission::MAX_SURVEY_SIDE_M;
    let positive = |key: &str| -> Result<f64, ScenarioError> {
        let g = s.req_number(key)?;
        if g.v <= 0.0 {
            return Err(g.fail(format!("must be > 0, got {}", g.v)));
        }
        g.within(0.0, limit(side), "m")
    };
    let corner = s.req_position("corner")?;
    let length_m = positive("length_m")?;
    let width_m = positive("width_m")?;
    let spacing_m = positive("spacing_m")?;
    let heading = match s.number("heading_deg")? {
        Some(h) => h.within(-360.0, 360.0, "degrees")?.to_radians(),
        None => 0.0,
    };
    let radius_m = match s.number("radius_m")? {
        Some(r) if r.v <= 0.0 => return Err(r.fail(format!("must be > 0, got {}", r.v))),
        Some(r) => r.within(
            0.0,
            limit(vpf::planner::mission::MAX_WAYPOINT_RADIUS_M),
            "m",
        )?,
        None => f64::from(params.arrival_radius_m),
    };
    let speed = match s.number("speed")? {
        Some(v) => Some(v.within(
            limit(vpf::planner::mission::MIN_WAYPOINT_SPEED),
            limit(vpf::planner::mission::MAX_WAYPOINT_SPEED),
            "m/s",
        )?),
        None => None,
    };
    let survey = Survey {
        corner: corner.v.to_vpf(),
        length_m: length_m as f32,
        width_m: width_m as f32,
        heading: heading as f32,
        spacing_m: spacing_m as f32,
        radius_m: radius_m as f32,
        speed: speed.map(|v| v as f32),
    };
    // Lines ⌈width / spacing⌉ + 1, two waypoints each: name the limit and the way out.
    let lines = (width_m / spacing_m).ceil() + 1.0;
    if 2.0 * lines > MAX_WAYPOINTS as f64 {
        let max_lines = MAX_WAYPOINTS / 2;
        let g = s.req_number("spacing_m")?;
        return Err(g.fail(format!(
            "the survey needs {lines} lines ({} waypoints); a mission holds at most \
             {MAX_WAYPOINTS} ({max_lines} lines): make spacing_m at least {:.2} m or width_m \
             narrower",
            2.0 * lines,
            width_m / (max_lines - 1) as f64
        )));
    }
    survey
        .waypoints()
        .map_err(|e| s.src.err(&s.span, &s.path, format!("refused by vpf: {e}")))?;
    Ok(survey)
}
