//! A vehicle's waypoint mission in a scenario file: `waypoints = [...]` or a `[vehicle.survey]`,
//! with `end`, `loiter_radius_m` and `loiter_clockwise` (hil/scenarios/README.md). Checked here
//! with the library's own rules (`vpf::planner::mission`), each refusal at its key.

use std::ops::Range;

use toml::Spanned;
use vpf::planner::mission::{MAX_WAYPOINT_RADIUS_M, MAX_WAYPOINT_SPEED, MIN_WAYPOINT_SPEED};
use vpf::planner::{MissionEnd, Survey, Waypoint, Waypoints, MAX_WAYPOINTS};
use vpf::Params;

use super::file::{SurveyFile, VehicleFile, WaypointItem};
use super::values::{Items, Num};
use super::{At, ScenarioError};
use crate::types::P2;

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

/// A waypoint's position and where it was written (its key path and span), for the checks
/// against obstacles.
pub(super) type Placed = (P2, String, Range<usize>);

/// The mission of vehicle table `f` (at `at`), if it has one, with where each waypoint was
/// written (a survey's all at its table).
pub(super) fn parse(
    at: &At<'_>,
    f: &VehicleFile,
    params: &Params,
) -> Result<Option<(VehicleMission, Vec<Placed>)>, ScenarioError> {
    let end = end(at, f)?;
    let (list, placed, survey) = match (&f.waypoints, &f.survey) {
        (Some(_), Some(s)) => {
            return Err(at
                .child("survey", s.span())
                .refuse("give `waypoints` or `survey`, not both"))
        }
        (None, None) => {
            let rest = [
                ("end", f.end.as_ref().map(Spanned::span)),
                (
                    "loiter_radius_m",
                    f.loiter_radius_m.as_ref().map(Spanned::span),
                ),
                (
                    "loiter_clockwise",
                    f.loiter_clockwise.as_ref().map(Spanned::span),
                ),
            ];
            if let Some((k, Some(span))) = rest.into_iter().find(|(_, s)| s.is_some()) {
                return Err(at.fail(
                    k,
                    &span,
                    "applies to a waypoint mission: give `waypoints` or a `survey`",
                ));
            }
            return Ok(None);
        }
        (Some(v), None) => {
            let (list, placed) = list(at, v, params)?;
            (list, placed, None)
        }
        (None, Some(s)) => {
            let st = at.child("survey", s.span());
            let survey = survey_of(&st, s.get_ref(), params)?;
            let list = survey.waypoints().map_err(|e| st.refuse(e.to_string()))?;
            let placed = list
                .iter()
                .map(|w| {
                    let p = w.position();
                    let p = P2::new(f64::from(p.x), f64::from(p.y));
                    (p, st.path.clone(), s.span())
                })
                .collect();
            (list.to_vec(), placed, Some(survey))
        }
    };
    let waypoints = Waypoints::new(&list, end).map_err(|e| at.refuse(e.to_string()))?;
    Ok(Some((VehicleMission { waypoints, survey }, placed)))
}

fn end(at: &At<'_>, f: &VehicleFile) -> Result<MissionEnd, ScenarioError> {
    let loiter = match &f.end {
        Some(s) => at.choose("end", s, &[("hold", false), ("loiter", true)], "end")?,
        None => false,
    };
    if !loiter {
        let rest = [
            (
                "loiter_radius_m",
                f.loiter_radius_m.as_ref().map(Spanned::span),
            ),
            (
                "loiter_clockwise",
                f.loiter_clockwise.as_ref().map(Spanned::span),
            ),
        ];
        if let Some((k, Some(span))) = rest.into_iter().find(|(_, s)| s.is_some()) {
            return Err(at.fail(k, &span, "applies to end = \"loiter\" only"));
        }
        return Ok(MissionEnd::Hold);
    }
    let (lo, hi) = vpf::planner::mission::LOITER_RADIUS_M;
    let radius = f.loiter_radius_m.as_ref().ok_or_else(|| {
        let span = f.end.as_ref().map_or(at.span.clone(), Spanned::span);
        at.fail(
            "loiter_radius_m",
            &span,
            "missing: end = \"loiter\" circles the last waypoint at this radius",
        )
    })?;
    let radius_m = at.within("loiter_radius_m", radius, limit(lo), limit(hi), "m")?;
    Ok(MissionEnd::Loiter {
        radius_m: radius_m as f32,
        clockwise: f.loiter_clockwise.as_ref().is_some_and(|c| *c.get_ref()),
    })
}

/// A waypoint's arrival radius (the planner's `arrival_radius_m` when absent).
fn radius(
    at: &At<'_>,
    key: &str,
    r: &Option<Spanned<Num>>,
    params: &Params,
) -> Result<f64, ScenarioError> {
    match r {
        Some(r) => at.positive(key, r, (0.0, limit(MAX_WAYPOINT_RADIUS_M)), "m"),
        None => Ok(f64::from(params.arrival_radius_m)),
    }
}

/// A waypoint's speed, if it sets one.
fn speed(at: &At<'_>, key: &str, v: &Option<Spanned<Num>>) -> Result<Option<f64>, ScenarioError> {
    let (lo, hi) = (limit(MIN_WAYPOINT_SPEED), limit(MAX_WAYPOINT_SPEED));
    v.as_ref()
        .map(|v| at.within(key, v, lo, hi, "m/s"))
        .transpose()
}

/// `waypoints = [[x, y], { at = [x, y], radius_m = r, speed = v }, ...]`.
fn list(
    at: &At<'_>,
    v: &Spanned<Items<WaypointItem>>,
    params: &Params,
) -> Result<(Vec<Waypoint>, Vec<Placed>), ScenarioError> {
    let items = &v.get_ref().0;
    if items.is_empty() {
        return Err(at.fail("waypoints", &v.span(), "no waypoint: give at least one"));
    }
    if items.len() > MAX_WAYPOINTS {
        return Err(at.fail(
            "waypoints",
            &v.span(),
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
        let k = format!("waypoints[{i}]");
        let (p, radius, speed) = match item.get_ref() {
            WaypointItem::Table(w) => {
                let wt = at.child(&k, item.span());
                let a = wt.req("at", &w.at)?;
                let p = (wt.position("at", a)?, wt.key("at"), a.span());
                (
                    p,
                    radius(&wt, "radius_m", &w.radius_m, params)?,
                    speed(&wt, "speed", &w.speed)?,
                )
            }
            WaypointItem::At(pair) => {
                let p = at.position(&k, &Spanned::new(item.span(), *pair))?;
                (
                    (p, at.key(&k), item.span()),
                    f64::from(params.arrival_radius_m),
                    None,
                )
            }
        };
        let w = Waypoint::new(p.0.to_vpf(), radius as f32)
            .and_then(|w| w.with_speed(speed.map(|s| s as f32)))
            .map_err(|e| at.src.err(&p.2, &p.1, format!("refused by vpf: {e}")))?;
        list.push(w);
        placed.push(p);
    }
    Ok((list, placed))
}

/// `[vehicle.survey]`: corner, length_m, width_m, heading_deg, spacing_m, radius_m, speed.
fn survey_of(at: &At<'_>, f: &SurveyFile, params: &Params) -> Result<Survey, ScenarioError> {
    let side = limit(vpf::planner::mission::MAX_SURVEY_SIDE_M);
    let positive = |key: &str, v| at.positive(key, at.req(key, v)?, (0.0, side), "m");
    let corner = at.position("corner", at.req("corner", &f.corner)?)?;
    let length_m = positive("length_m", &f.length_m)?;
    let width_m = positive("width_m", &f.width_m)?;
    let spacing_m = positive("spacing_m", &f.spacing_m)?;
    let heading = at.degrees("heading_deg", &f.heading_deg)?;
    let radius_m = radius(at, "radius_m", &f.radius_m, params)?;
    let speed = speed(at, "speed", &f.speed)?;
    let survey = Survey {
        corner: corner.to_vpf(),
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
        let span = f.spacing_m.as_ref().map_or(at.span.clone(), Spanned::span);
        return Err(at.fail(
            "spacing_m",
            &span,
            format!(
                "the survey needs {lines} lines ({} waypoints); a mission holds at most \
                 {MAX_WAYPOINTS} ({max_lines} lines): make spacing_m at least {:.2} m or width_m \
                 narrower",
                2.0 * lines,
                width_m / (max_lines - 1) as f64
            ),
        ));
    }
    survey
        .waypoints()
        .map_err(|e| at.refuse(format!("refused by vpf: {e}")))?;
    Ok(survey)
}
