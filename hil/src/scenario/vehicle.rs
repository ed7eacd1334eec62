//! A `[[vehicle]]` built with its mission and formation, checked against the world it starts in:
//! its start and goal outside the obstacles, its start clear of the vehicles before it.

use vpf::field::Shape;
use vpf::planner::Formation;
use vpf::Params;

use super::build::check_name;
use super::file::{FormationFile, VehicleFile};
use super::{mission, At, Autopilot, ModelKind, ScenarioError, Sensing, Sonar, SonarMode, Vehicle};
use crate::types::{SimObstacle, P2};

/// What a vehicle is checked against: the scenario read so far.
pub(super) struct World<'w> {
    pub(super) sonar: &'w Sonar,
    pub(super) params: &'w Params,
    pub(super) obstacles: &'w [SimObstacle],
    pub(super) shapes: &'w [Shape],
    /// The vehicles before it in the file.
    pub(super) earlier: &'w [Vehicle],
}

/// The models' names in a scenario file.
pub(super) const MODELS: [(&str, ModelKind); 5] = [
    ("kinematic", ModelKind::Kinematic),
    ("videoray", ModelKind::VideoRay),
    ("flatfish", ModelKind::FlatFish),
    ("flat-fish", ModelKind::FlatFish),
    ("flat_fish", ModelKind::FlatFish),
];

pub(super) fn vehicle(
    at: &At<'_>,
    f: &VehicleFile,
    w: &World<'_>,
) -> Result<Vehicle, ScenarioError> {
    let name = at.req("name", &f.name)?;
    check_name(at, "name", name)?;
    if let Some(i) = w.earlier.iter().position(|v| v.name == *name.get_ref()) {
        return Err(at.fail(
            "name",
            &name.span(),
            format!(
                "two vehicles are named \"{}\" (vehicle[{i}] too); names must be unique",
                name.get_ref()
            ),
        ));
    }
    let model = at.choose("model", at.req("model", &f.model)?, &MODELS, "model")?;
    let start_v = at.req("start", &f.start)?;
    let start = at.position("start", start_v)?;
    let heading = at.degrees("heading_deg", &f.heading_deg)?;
    let mission = mission::parse(at, f, w.params)?;
    // The goal, and where it was written: given, or the mission's last waypoint.
    let goal = match (&f.goal, &mission) {
        (Some(g), None) => (at.position("goal", g)?, at.key("goal"), g.span()),
        (Some(g), Some(_)) => {
            return Err(at.fail(
                "goal",
                &g.span(),
                "give a `goal` or a waypoint mission (`waypoints`, `survey`), not both",
            ))
        }
        (None, Some((_, placed))) => match placed.last() {
            Some(p) => p.clone(),
            None => return Err(at.missing("goal")),
        },
        (None, None) => return Err(at.missing("goal")),
    };
    let formation = match &f.formation {
        Some(t) => Some(formation(&at.child("formation", t.span()), t.get_ref())?),
        None => None,
    };
    let sensing = match &f.sensing {
        Some(s) => at.choose(
            "sensing",
            s,
            &[("sonar", Sensing::Sonar), ("contacts", Sensing::Contacts)],
            "sensing",
        )?,
        None => match w.sonar.mode {
            SonarMode::Scanlines => Sensing::Sonar,
            SonarMode::Contacts => Sensing::Contacts,
        },
    };
    let autopilot = match &f.autopilot {
        Some(s) => at.choose(
            "autopilot",
            s,
            &[("plain", Autopilot::Plain), ("pid", Autopilot::SetPoints)],
            "autopilot",
        )?,
        None => Autopilot::Plain,
    };

    for (i, (o, s)) in w.obstacles.iter().zip(w.shapes).enumerate() {
        if s.signed_distance(start.to_vpf()) <= 0.0 {
            return Err(at.fail(
                "start",
                &start_v.span(),
                format!("start [{}, {}] is inside obstacle[{i}]", start.x, start.y),
            ));
        }
        // A moving obstacle may uncover the goal later; a static one never will.
        let fixed = o.velocity == P2::default();
        if fixed && s.signed_distance(goal.0.to_vpf()) <= 0.0 {
            return Err(at.src.err(
                &goal.2,
                &goal.1,
                format!(
                    "goal [{}, {}] is inside the static obstacle[{i}]",
                    goal.0.x, goal.0.y
                ),
            ));
        }
        for (k, (p, key, span)) in mission.iter().flat_map(|(_, placed)| placed).enumerate() {
            if fixed && s.signed_distance(p.to_vpf()) <= 0.0 {
                return Err(at.src.err(
                    span,
                    key,
                    format!(
                        "waypoint {k} [{:.2}, {:.2}] is inside the static obstacle[{i}]",
                        p.x, p.y
                    ),
                ));
            }
        }
    }
    let hull = 2.0 * f64::from(w.params.agent_radius_m);
    if let Some(other) = w.earlier.iter().find(|v| v.start.sub(start).norm() < hull) {
        return Err(at.fail(
            "start",
            &start_v.span(),
            format!(
                "start is within {hull} m (two agent radii) of vehicle \"{}\"'s start",
                other.name
            ),
        ));
    }

    Ok(Vehicle {
        name: name.get_ref().clone(),
        model,
        start,
        heading,
        goal: goal.0,
        mission: mission.map(|(m, _)| m),
        formation,
        sensing,
        autopilot,
    })
}

fn formation(at: &At<'_>, f: &FormationFile) -> Result<Formation, ScenarioError> {
    let q = at.req("q", &f.q)?;
    if !matches!(q.get_ref().0, 3 | 4 | 6) {
        return Err(at.fail(
            "q",
            &q.span(),
            format!(
                "the formation descriptor must be 3, 4 or 6, got {}",
                q.get_ref().0
            ),
        ));
    }
    let lattice_m = at.within(
        "lattice_m",
        at.req("lattice_m", &f.lattice_m)?,
        0.5,
        1000.0,
        "m",
    )?;
    let orientation = at.degrees("orientation_deg", &f.orientation_deg)?;
    let attraction = match &f.attraction {
        Some(a) => at.within("attraction", a, 0.001, 1e4, "")?,
        None => 5.0,
    };
    let f = Formation {
        q: q.get_ref().0 as u8,
        lattice_m: lattice_m as f32,
        orientation: orientation as f32,
        attraction: attraction as f32,
    };
    f.validate()
        .map_err(|e| at.refuse(format!("refused by vpf: {e}")))?;
    Ok(f)
}
