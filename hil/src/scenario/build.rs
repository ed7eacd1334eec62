//! The schema's tables, key by key, built into a [`Scenario`] with every range checked.

use toml::de::DeValue;
use vpf::field::shape::MIN_EXTENT_M;
use vpf::field::{Shape, MAX_POLYGON_VERTICES};
use vpf::params::{Kind, ParamId, Value, PARAM_NAMES};
use vpf::planner::Formation;
use vpf::Params;

use super::reader::{
    check_position, choose, type_name, unit_suffix, value_pair, Located, ScenarioError, Table,
};
use super::{
    check_name, mission, Autopilot, Current, Faults, ModelKind, Navigation, RunMode, Scenario,
    Sensing, Sonar, SonarInterface, SonarMode, Vehicle, MAX_DURATION_S, MAX_OBSTACLES,
    MAX_VEHICLES, OBSTACLE_FACTOR,
};
use crate::types::{SimObstacle, SimShape, P2};

pub(super) const ROOT_KEYS: &[&str] = &[
    "name",
    "duration_s",
    "dt_s",
    "seed",
    "mode",
    "planner",
    "vehicle",
    "obstacle",
    "sonar",
    "navigation",
    "current",
    "faults",
];

pub(super) fn build(root: &Table<'_>) -> Result<Scenario, ScenarioError> {
    root.allow(ROOT_KEYS, "the scenario")?;

    let name = root.req_string("name")?;
    check_name(&name)?;
    let dt = root.req_number("dt_s")?;
    let dt_s = dt.within(0.02, 1.0, "s")?;
    let duration = root.req_number("duration_s")?;
    let duration_s = duration.within(dt_s, MAX_DURATION_S, "s (at least dt_s)")?;
    let seed = root.integer("seed")?.ok_or_else(|| root.missing("seed"))?;
    let seed_v =
        u64::try_from(seed.v).map_err(|_| seed.fail(format!("must be >= 0, got {}", seed.v)))?;
    let mode = match root.string("mode")? {
        Some(m) => choose(
            &m,
            &[
                ("lockstep", RunMode::Lockstep),
                ("realtime", RunMode::Realtime),
            ],
            "mode",
        )?,
        None => RunMode::Lockstep,
    };

    let params = planner(root, &dt)?;
    let sonar = sonar(root)?;
    let navigation = navigation(root, dt_s)?;
    let current = current(root)?;
    let faults = faults(root)?;

    let mut obstacles = Vec::new();
    let mut shapes = Vec::new();
    let tables = root.tables("obstacle")?;
    if let Some(t) = tables.get(MAX_OBSTACLES) {
        return Err(t.src.err(
            &t.span,
            &t.path,
            format!(
                "too many obstacles: {} of at most {MAX_OBSTACLES} ({OBSTACLE_FACTOR} × the \
                 firmware's table of {})",
                tables.len(),
                vpf::world::MAX_OBSTACLES
            ),
        ));
    }
    for t in tables {
        let (o, s) = obstacle(&t)?;
        obstacles.push(o);
        shapes.push(s);
    }

    let tables = root.tables("vehicle")?;
    if tables.is_empty() {
        return Err(root.src.err(
            &root.span_of("vehicle"),
            "vehicle",
            "no vehicle: a scenario needs at least one [[vehicle]]",
        ));
    }
    if let Some(t) = tables.get(MAX_VEHICLES) {
        return Err(t.src.err(
            &t.span,
            &t.path,
            format!(
                "too many vehicles: at most {MAX_VEHICLES} (the firmware tracks {} others)",
                MAX_VEHICLES - 1
            ),
        ));
    }
    let mut vehicles: Vec<Vehicle> = Vec::new();
    for t in &tables {
        let v = vehicle(t, &sonar, &params, &obstacles, &shapes, &vehicles)?;
        vehicles.push(v);
    }

    Ok(Scenario {
        name: name.v.to_string(),
        duration_s,
        dt_s,
        seed: seed_v,
        mode,
        params,
        vehicles,
        obstacles,
        sonar,
        navigation,
        current,
        faults,
    })
}

// --- [planner] -------------------------------------------------------------------------------

/// A parameter's declared range and unit, for messages (the decision is `Params::validate`'s).
pub(super) fn param_range(id: ParamId) -> String {
    let range = match (id.range(), id.kind()) {
        (vpf::params::Range::Any, Kind::U32) => format!("0 ..= {}", u32::MAX),
        (r, _) => r.to_string(),
    };
    format!("{range}{}", unit_suffix(id.unit()))
}

/// A parameter's value as a scenario would write it.
pub(super) fn param_value(p: &Params, id: ParamId) -> String {
    p.get(id).to_string()
}

pub(super) fn planner(root: &Table<'_>, dt: &Located<'_, f64>) -> Result<Params, ScenarioError> {
    let mut params = Params {
        period_s: dt.v as f32,
        ..Params::default()
    };
    // Every name validate reports is a declared parameter.
    let id_of = |name: &str| ParamId::from_name(name).unwrap_or(ParamId::period_s);
    let Some(t) = root.table("planner")? else {
        params.validate().map_err(|e| {
            root.src.err(
                &root.span,
                &format!("planner.{}", e.name),
                format!(
                    "the default value {} is refused by vpf ({e})",
                    param_value(&params, id_of(e.name))
                ),
            )
        })?;
        return Ok(params);
    };
    t.allow(&PARAM_NAMES, "[planner] (the names of vpf::Params' fields)")?;

    for &(name, _, _) in &t.entries {
        let Some(id) = ParamId::from_name(name) else {
            continue;
        };
        let value = match id.kind() {
            _ if id == ParamId::period_s => {
                return Err(t.src.err(
                    &t.span_of(name),
                    &t.key(name),
                    "the planner period is the top-level `dt_s`; set it there",
                ))
            }
            Kind::Code(names) => {
                let s = t.req_string(name)?;
                let choices: Vec<(&str, u8)> = names.iter().copied().zip(0u8..).collect();
                Value::Code(choose(&s, &choices, name)?)
            }
            Kind::U8 | Kind::U32 => {
                let i = t.integer(name)?.ok_or_else(|| t.missing(name))?;
                let refuse = || i.fail(format!("must be in {}, got {}", param_range(id), i.v));
                if id.kind() == Kind::U8 {
                    Value::U8(u8::try_from(i.v).map_err(|_| refuse())?)
                } else {
                    Value::U32(u32::try_from(i.v).map_err(|_| refuse())?)
                }
            }
            // Out-of-f32 values become infinite and are refused by validate below.
            Kind::F32 => Value::F32(t.req_number(name)?.v as f32),
        };
        params.set(id, value);
    }

    params.validate().map_err(|e| {
        let id = id_of(e.name);
        let value = param_value(&params, id);
        // Every number read is a finite f64, so a non-finite f32 here overflowed: out of range.
        let problem = format!("must be in {}", param_range(id));
        if e.name == "period_s" {
            dt.fail(format!("{problem}, got {}", dt.v))
        } else if t.has(e.name) {
            t.src.err(
                &t.span_of(e.name),
                &t.key(e.name),
                format!("{problem}, got {value}"),
            )
        } else {
            t.src.err(
                &t.span,
                &t.key(e.name),
                format!(
                    "{problem}, got the default {value} (v_max = {}); set it in [planner]",
                    params.v_max
                ),
            )
        }
    })?;
    Ok(params)
}

// --- [sonar], [navigation], [current], [faults] ----------------------------------------------

pub(super) fn sonar(root: &Table<'_>) -> Result<Sonar, ScenarioError> {
    let mut s = Sonar::default();
    let Some(t) = root.table("sonar")? else {
        return Ok(s);
    };
    t.allow(
        &[
            "mode",
            "range_m",
            "bins",
            "step_deg",
            "noise",
            "speckle",
            "beam_rays",
            "false_echoes",
            "vehicle_contacts",
            "interface",
        ],
        "[sonar]",
    )?;
    let interface = match t.string("interface")? {
        Some(i) => Some(choose(
            &i,
            &[
                ("link", SonarInterface::Link),
                ("ping360", SonarInterface::Ping360),
            ],
            "sonar interface",
        )?),
        None => None,
    };
    if let Some(m) = t.string("mode")? {
        s.mode = choose(
            &m,
            &[
                ("scanlines", SonarMode::Scanlines),
                ("contacts", SonarMode::Contacts),
            ],
            "sonar mode",
        )?;
    }
    if let Some(r) = t.number("range_m")? {
        s.range_m = r.within(
            f64::from(vpf::sonar::MIN_RANGE_M),
            f64::from(vpf::sonar::MAX_RANGE_M),
            "m",
        )?;
    }
    if let Some(b) = t.integer("bins")? {
        let max = vpf::sonar::MAX_BINS as i64;
        if !(1..=max).contains(&b.v) {
            return Err(b.fail(format!("must be in 1 ..= {max}, got {}", b.v)));
        }
        s.bins = b.v as u16;
    }
    if let Some(d) = t.number("step_deg")? {
        let lo = f64::from(vpf::sonar::MIN_STEP_RAD).to_degrees();
        let hi = f64::from(vpf::sonar::MAX_STEP_RAD).to_degrees();
        // Rounded inward so the printed range is safe to use.
        let (lo, hi) = ((lo * 100.0).ceil() / 100.0, (hi * 100.0).floor() / 100.0);
        s.step = d.within(lo, hi, "degrees")?.to_radians();
    }
    if let Some(n) = t.number("noise")? {
        s.noise = n.within(0.0, 1.0, "")?;
    }
    if let Some(n) = t.number("speckle")? {
        s.speckle = n.within(0.0, 1.0, "")?;
    }
    if let Some(b) = t.integer("beam_rays")? {
        if !(1..=32).contains(&b.v) {
            return Err(b.fail(format!("must be in 1 ..= 32, got {}", b.v)));
        }
        s.beam_rays = b.v as usize;
    }
    if let Some(n) = t.number("false_echoes")? {
        s.false_echoes = n.within(0.0, 1.0, "")?;
    }
    if let Some(b) = t.boolean("vehicle_contacts")? {
        s.vehicle_contacts = b;
    }
    if interface == Some(SonarInterface::Ping360) {
        s.interface = SonarInterface::Ping360;
        let at = |key: &str| t.get(key).map(|v| v.span()).unwrap_or(t.span.clone());
        crate::ping360::sim::firmware_config(&s)
            .map_err(|(key, msg)| t.src.err(&at(key), &t.key(key), msg))?;
    }
    Ok(s)
}

pub(super) fn navigation(root: &Table<'_>, dt_s: f64) -> Result<Navigation, ScenarioError> {
    let mut n = Navigation {
        rate_hz: 1.0 / dt_s,
        ..Navigation::default()
    };
    let Some(t) = root.table("navigation")? else {
        return Ok(n);
    };
    t.allow(
        &["position_sigma_m", "heading_sigma_deg", "rate_hz"],
        "[navigation]",
    )?;
    if let Some(x) = t.number("position_sigma_m")? {
        n.position_sigma_m = x.within(0.0, 100.0, "m")?;
    }
    if let Some(x) = t.number("heading_sigma_deg")? {
        n.heading_sigma = x.within(0.0, 180.0, "degrees")?.to_radians();
    }
    if let Some(x) = t.number("rate_hz")? {
        n.rate_hz = x.within(0.1, 1000.0, "Hz")?;
    }
    Ok(n)
}

pub(super) fn current(root: &Table<'_>) -> Result<Current, ScenarioError> {
    let Some(t) = root.table("current")? else {
        return Ok(Current::default());
    };
    t.allow(&["velocity"], "[current]")?;
    Ok(Current {
        velocity: t.velocity("velocity", 5.0)?.unwrap_or_default(),
    })
}

pub(super) fn faults(root: &Table<'_>) -> Result<Faults, ScenarioError> {
    let mut f = Faults::default();
    let Some(t) = root.table("faults")? else {
        return Ok(f);
    };
    t.allow(
        &[
            "bit_error_rate",
            "drop_rate",
            "nav_delay_ms",
            "nav_freeze",
            "nav_loss",
            "sonar_dropout",
            "ping360_bit_error_rate",
            "ping360_drop_rate",
        ],
        "[faults]",
    )?;
    if let Some(x) = t.number("ping360_bit_error_rate")? {
        f.ping360_bit_error_rate = x.within(0.0, 0.01, "")?;
    }
    if let Some(x) = t.number("ping360_drop_rate")? {
        f.ping360_drop_rate = x.within(0.0, 1.0, "")?;
    }
    if let Some(x) = t.number("bit_error_rate")? {
        f.bit_error_rate = x.within(0.0, 0.01, "")?;
    }
    if let Some(x) = t.number("drop_rate")? {
        f.drop_rate = x.within(0.0, 1.0, "")?;
    }
    if let Some(x) = t.number("nav_delay_ms")? {
        f.nav_delay_ms = x.within(0.0, 10_000.0, "ms")?;
    }
    f.nav_freeze = t.window("nav_freeze")?;
    f.nav_loss = t.window("nav_loss")?;
    f.sonar_dropout = t.window("sonar_dropout")?;
    Ok(f)
}

// --- [[obstacle]] ----------------------------------------------------------------------------

/// Largest obstacle speed, m/s (the firmware's `MAX_OBJECT_SPEED`).
pub(super) const MAX_OBSTACLE_SPEED: f64 = vpf::world::MAX_OBJECT_SPEED as f64;

pub(super) fn obstacle(t: &Table<'_>) -> Result<(SimObstacle, Shape), ScenarioError> {
    let kind = t.req_string("shape")?;
    let shape = match kind.v {
        "circle" => {
            t.allow(
                &["shape", "center", "radius", "velocity"],
                "a circle obstacle",
            )?;
            let center = t.req_position("center")?.v;
            let radius = t.req_number("radius")?.size()?;
            SimShape::Circle { center, radius }
        }
        "rectangle" => {
            t.allow(
                &["shape", "center", "half_size", "angle_deg", "velocity"],
                "a rectangle obstacle",
            )?;
            let center = t.req_position("center")?.v;
            let half = t.pair("half_size")?.ok_or_else(|| t.missing("half_size"))?;
            for (i, v) in [half.v.x, half.v.y].into_iter().enumerate() {
                let side = Located {
                    v,
                    span: half.span.clone(),
                    key: format!("{}[{i}]", half.key),
                    src: half.src,
                };
                side.size()?;
            }
            let angle = match t.number("angle_deg")? {
                Some(a) => a.within(-360.0, 360.0, "degrees")?.to_radians(),
                None => 0.0,
            };
            SimShape::Rectangle {
                center,
                half_size: half.v,
                angle,
            }
        }
        "polygon" => {
            t.allow(&["shape", "points", "velocity"], "a polygon obstacle")?;
            SimShape::Polygon {
                points: polygon(t)?,
            }
        }
        other => {
            return Err(kind.fail(format!(
                "unknown shape \"{other}\" (expected \"circle\", \"rectangle\" or \"polygon\")"
            )))
        }
    };
    let velocity = t
        .velocity("velocity", MAX_OBSTACLE_SPEED)?
        .unwrap_or_default();
    // The firmware's own constructors are the last word on what geometry it accepts.
    let vpf_shape = match &shape {
        SimShape::Circle { center, radius } => Shape::circle(center.to_vpf(), *radius as f32),
        SimShape::Rectangle {
            center,
            half_size,
            angle,
        } => Shape::rectangle(center.to_vpf(), half_size.to_vpf(), *angle as f32),
        SimShape::Polygon { points } => {
            let pts: Vec<vpf::Vec2> = points.iter().map(|p| p.to_vpf()).collect();
            Shape::polygon(&pts)
        }
    }
    .map_err(|e| {
        t.src.err(
            &t.span,
            &t.path,
            format!("refused by the firmware's geometry: {e}"),
        )
    })?;
    Ok((SimObstacle { shape, velocity }, vpf_shape))
}

/// A convex polygon's vertices, refusing degenerate and concave ones with the vertex at fault.
pub(super) fn polygon(t: &Table<'_>) -> Result<Vec<P2>, ScenarioError> {
    let v = t.get("points").ok_or_else(|| t.missing("points"))?;
    let key = t.key("points");
    let DeValue::Array(items) = v.get_ref() else {
        return Err(t.src.err(
            &v.span(),
            &key,
            format!(
                "expected an array of [x, y] vertices, got {}",
                type_name(v.get_ref())
            ),
        ));
    };
    let n = items.len();
    if !(3..=MAX_POLYGON_VERTICES).contains(&n) {
        return Err(t.src.err(
            &v.span(),
            &key,
            format!("a polygon needs 3 ..= {MAX_POLYGON_VERTICES} vertices, got {n}"),
        ));
    }
    let mut pts = Vec::with_capacity(n);
    for (i, item) in items.iter().enumerate() {
        let p = Located {
            v: value_pair(t.src, &format!("{key}[{i}]"), item)?,
            span: item.span(),
            key: format!("{key}[{i}]"),
            src: t.src,
        };
        check_position(&p)?;
        pts.push(p);
    }
    let at = |i: usize| &pts[i % n];
    for i in 0..n {
        let (a, b) = (at(i), at(i + 1));
        if b.v.sub(a.v).norm() < f64::from(MIN_EXTENT_M) {
            return Err(b.fail(format!(
                "degenerate polygon: vertex {} repeats vertex {i}",
                (i + 1) % n
            )));
        }
    }
    // Turn at each vertex: the cross product of the edges into and out of it.
    let turn = |i: usize| {
        let (p, c, q) = (at(i + n - 1).v, at(i).v, at(i + 1).v);
        let (e1, e2) = (c.sub(p), q.sub(c));
        let cross = e1.x * e2.y - e1.y * e2.x;
        let dot = e1.x * e2.x + e1.y * e2.y;
        (cross, dot, e1.norm() * e2.norm())
    };
    let area2: f64 = (0..n)
        .map(|i| {
            let (a, b) = (at(i).v, at(i + 1).v);
            a.x * b.y - a.y * b.x
        })
        .sum();
    let mut total_turn = 0.0;
    for i in 0..n {
        let (cross, dot, scale) = turn(i);
        if cross.abs() <= 1e-6 * scale {
            return Err(at(i).fail(format!(
                "degenerate polygon: vertex {i} is collinear with its neighbours; remove it"
            )));
        }
        if cross * area2 < 0.0 {
            return Err(at(i).fail(format!(
                "concave polygon (reflex vertex {i}): obstacles must be convex, split it into \
                 convex pieces"
            )));
        }
        total_turn += cross.atan2(dot);
    }
    // All turns one way but winding more than once round: a star, which crosses itself.
    if (total_turn.abs() - std::f64::consts::TAU).abs() > 1e-6 {
        return Err(t.src.err(
            &v.span(),
            &key,
            "self-intersecting polygon: obstacles must be convex, split it into convex pieces",
        ));
    }
    Ok(pts.into_iter().map(|p| p.v).collect())
}

// --- [[vehicle]] -----------------------------------------------------------------------------

pub(super) fn vehicle(
    t: &Table<'_>,
    sonar: &Sonar,
    params: &Params,
    obstacles: &[SimObstacle],
    shapes: &[Shape],
    earlier: &[Vehicle],
) -> Result<Vehicle, ScenarioError> {
    let mut keys = vec![
        "name",
        "model",
        "start",
        "heading_deg",
        "goal",
        "formation",
        "sensing",
        "autopilot",
    ];
    keys.extend(mission::KEYS);
    t.allow(&keys, "a [[vehicle]]")?;
    let name = t.req_string("name")?;
    check_name(&name)?;
    if let Some(i) = earlier.iter().position(|v| v.name == name.v) {
        return Err(name.fail(format!(
            "two vehicles are named \"{}\" (vehicle[{i}] too); names must be unique",
            name.v
        )));
    }
    let model = choose(
        &t.req_string("model")?,
        &[
            ("kinematic", ModelKind::Kinematic),
            ("videoray", ModelKind::VideoRay),
            ("flatfish", ModelKind::FlatFish),
            ("flat-fish", ModelKind::FlatFish),
            ("flat_fish", ModelKind::FlatFish),
        ],
        "model",
    )?;
    let start = t.req_position("start")?;
    let heading = match t.number("heading_deg")? {
        Some(h) => h.within(-360.0, 360.0, "degrees")?.to_radians(),
        None => 0.0,
    };
    let mission = mission::parse(t, params)?;
    let goal = match (t.position("goal")?, &mission) {
        (Some(g), None) => g,
        (Some(g), Some(_)) => {
            return Err(
                g.fail("give a `goal` or a waypoint mission (`waypoints`, `survey`), not both")
            )
        }
        (None, Some((_, placed))) => match placed.last() {
            Some(p) => Located {
                v: p.at.v,
                span: p.at.span.clone(),
                key: p.at.key.clone(),
                src: p.at.src,
            },
            None => return Err(t.missing("goal")),
        },
        (None, None) => return Err(t.src.err(&t.span, &t.key("goal"), "missing required key")),
    };
    let formation = match t.table("formation")? {
        Some(f) => Some(formation(&f)?),
        None => None,
    };
    let sensing = match t.string("sensing")? {
        Some(s) => choose(
            &s,
            &[("sonar", Sensing::Sonar), ("contacts", Sensing::Contacts)],
            "sensing",
        )?,
        None => match sonar.mode {
            SonarMode::Scanlines => Sensing::Sonar,
            SonarMode::Contacts => Sensing::Contacts,
        },
    };

    let autopilot = match t.string("autopilot")? {
        Some(s) => choose(
            &s,
            &[("plain", Autopilot::Plain), ("pid", Autopilot::SetPoints)],
            "autopilot",
        )?,
        None => Autopilot::Plain,
    };

    for (i, (o, s)) in obstacles.iter().zip(shapes).enumerate() {
        if s.signed_distance(start.v.to_vpf()) <= 0.0 {
            return Err(start.fail(format!(
                "start [{}, {}] is inside obstacle[{i}]",
                start.v.x, start.v.y
            )));
        }
        // A moving obstacle may uncover the goal later; a static one never will.
        if o.velocity == P2::default() && s.signed_distance(goal.v.to_vpf()) <= 0.0 {
            return Err(goal.fail(format!(
                "goal [{}, {}] is inside the static obstacle[{i}]",
                goal.v.x, goal.v.y
            )));
        }
        for (k, w) in mission.iter().flat_map(|(_, placed)| placed).enumerate() {
            if o.velocity == P2::default() && s.signed_distance(w.at.v.to_vpf()) <= 0.0 {
                return Err(w.at.fail(format!(
                    "waypoint {k} [{:.2}, {:.2}] is inside the static obstacle[{i}]",
                    w.at.v.x, w.at.v.y
                )));
            }
        }
    }
    let hull = 2.0 * f64::from(params.agent_radius_m);
    if let Some(other) = earlier.iter().find(|v| v.start.sub(start.v).norm() < hull) {
        return Err(start.fail(format!(
            "start is within {hull} m (two agent radii) of vehicle \"{}\"'s start",
            other.name
        )));
    }

    Ok(Vehicle {
        name: name.v.to_string(),
        model,
        start: start.v,
        heading,
        goal: goal.v,
        mission: mission.map(|(m, _)| m),
        formation,
        sensing,
        autopilot,
    })
}

pub(super) fn formation(t: &Table<'_>) -> Result<Formation, ScenarioError> {
    t.allow(
        &["q", "lattice_m", "orientation_deg", "attraction"],
        "a formation",
    )?;
    let q = t.integer("q")?.ok_or_else(|| t.missing("q"))?;
    if !matches!(q.v, 3 | 4 | 6) {
        return Err(q.fail(format!(
            "the formation descriptor must be 3, 4 or 6, got {}",
            q.v
        )));
    }
    let lattice_m = t.req_number("lattice_m")?.within(0.5, 1000.0, "m")?;
    let orientation = match t.number("orientation_deg")? {
        Some(o) => o.within(-360.0, 360.0, "degrees")?.to_radians(),
        None => 0.0,
    };
    let attraction = match t.number("attraction")? {
        Some(a) => a.within(0.001, 1e4, "")?,
        None => 5.0,
    };
    let f = Formation {
        q: q.v as u8,
        lattice_m: lattice_m as f32,
        orientation: orientation as f32,
        attraction: attraction as f32,
    };
    f.validate()
        .map_err(|e| t.src.err(&t.span, &t.path, format!("refused by vpf: {e}")))?;
    Ok(f)
}
