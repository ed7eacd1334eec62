//! The scenario schema: every shipped scenario loads and matches the experiment it reproduces,
//! and every kind of bad input is refused with the file, the line and the key.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};

use hil::scenario::ModelKind;
use hil::scenario::{self, RunMode, Scenario, ScenarioError, Sensing, SonarMode, Strategy};
use hil::types::{SimShape, P2};
use vpf::field::Shape;

fn scenarios_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios")
}

fn shipped(name: &str) -> Scenario {
    let path = scenarios_dir().join(name);
    scenario::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// The firmware's view of an obstacle shape, for geometric checks.
fn vpf_shape(s: &SimShape) -> Shape {
    match s {
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
    .expect("a validated shape")
}

fn clearance(s: &Scenario, p: P2) -> f32 {
    s.obstacles
        .iter()
        .map(|o| vpf_shape(&o.shape).signed_distance(p.to_vpf()))
        .fold(f32::INFINITY, f32::min)
}

const SHIPPED: [&str; 14] = [
    "seed000_fig2_no_friction.toml",
    "seed000_fig3_friction.toml",
    "seed000_fig4_clutter_plain.toml",
    "seed000_fig6_clutter_ghosts.toml",
    "seed000_fig7_four_vehicles.toml",
    "seed001_fig3_formation_open.toml",
    "seed001_fig5_formation_clutter.toml",
    "u_trap.toml",
    "narrow_gap.toml",
    "random_clutter.toml",
    "seed003_case1_static.toml",
    "seed003_case2_moving.toml",
    "crossing_traffic.toml",
    "ping360_narrow_gap.toml",
];

#[test]
fn every_shipped_scenario_parses_and_starts_with_a_comment() {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(scenarios_dir()).expect("hil/scenarios exists") {
        let path = entry.expect("readable entry").path();
        if path.extension().is_some_and(|e| e == "toml") {
            let s = scenario::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(!s.vehicles.is_empty());
            assert_eq!(s.params.period_s, s.dt_s as f32);
            let text = std::fs::read_to_string(&path).expect("readable");
            assert!(
                text.starts_with("# "),
                "{} must start with a comment saying what it reproduces",
                path.display()
            );
            assert!(
                text.contains("Expect"),
                "{}: say what to expect",
                path.display()
            );
            found.push(path.file_name().unwrap().to_string_lossy().into_owned());
        }
    }
    for name in SHIPPED {
        assert!(found.iter().any(|f| f == name), "{name} is missing");
    }
}

#[test]
fn seed_000_scenarios_use_the_experiments_geometry_and_parameters() {
    let fig2 = shipped("seed000_fig2_no_friction.toml");
    let fig3 = shipped("seed000_fig3_friction.toml");
    assert_eq!(fig2.params.mu, 0.0);
    assert_eq!(fig3.params.mu, 0.4);
    for s in [&fig2, &fig3] {
        assert_eq!(s.duration_s, 600.0);
        assert_eq!(s.vehicles[0].start, P2::new(-30.0, 12.0));
        assert_eq!(s.vehicles[0].goal, P2::new(0.0, 0.0));
        assert!(s.obstacles.is_empty());
    }

    let fig4 = shipped("seed000_fig4_clutter_plain.toml");
    let fig6 = shipped("seed000_fig6_clutter_ghosts.toml");
    assert_eq!((fig4.params.max_ghosts, fig4.params.a_rotor), (0, 0.0));
    assert_eq!(fig6.params.a_rotor, 0.0);
    assert!(fig6.params.max_ghosts > 0);
    assert_eq!(fig4.obstacles, fig6.obstacles);
    assert_eq!(fig4.obstacles.len(), 10);
    // The rectangle of `clutter()` is rotated by 0.4 rad, given in degrees in the file.
    let angle = fig4
        .obstacles
        .iter()
        .find_map(|o| match o.shape {
            SimShape::Rectangle { angle, .. } => Some(angle),
            _ => None,
        })
        .expect("one rectangle");
    assert!((angle - 0.4).abs() < 1e-12, "{angle}");
    assert_eq!(fig4.vehicles[0].goal, P2::new(50.0, 0.0));

    let fig7 = shipped("seed000_fig7_four_vehicles.toml");
    assert_eq!(fig7.vehicles.len(), 4);
    // The papers' planner: the defaults, without the route layer.
    let papers = vpf::Params {
        route_cell_m: 0.0,
        ..vpf::Params::default()
    };
    assert_eq!(fig7.params, papers);

    for s in [&fig2, &fig3, &fig4, &fig6, &fig7] {
        assert_eq!(s.params.route_cell_m, 0.0);
        for v in &s.vehicles {
            assert_eq!(v.model, ModelKind::Kinematic);
            // Charted obstacles in the tests: contacts covering the whole theatre.
            assert_eq!(v.sensing, Sensing::Contacts);
        }
        assert_eq!(s.sonar.mode, SonarMode::Contacts);
        assert_eq!(s.dt_s, 0.1);
    }
}

#[test]
fn seed_001_scenarios_fly_the_square_formation() {
    let open = shipped("seed001_fig3_formation_open.toml");
    let clutter = shipped("seed001_fig5_formation_clutter.toml");
    assert!(open.obstacles.is_empty());
    assert_eq!(clutter.obstacles.len(), 3);
    for s in [&open, &clutter] {
        assert_eq!((s.params.sigma_m, s.params.a_minus), (80.0, 100.0));
        assert_eq!(s.vehicles.len(), 4);
        for v in &s.vehicles {
            let f = v.formation.expect("a formation");
            assert_eq!(
                (f.q, f.lattice_m, f.orientation, f.attraction),
                (4, 4.0, 0.0, 5.0)
            );
            assert_eq!(v.goal, P2::new(120.0, 0.0));
            assert_eq!(v.model, ModelKind::Kinematic);
        }
        assert_eq!(s.vehicles[2].start, P2::new(-4.0, 2.0));
    }
}

#[test]
fn videoray_scenarios_sense_as_their_headers_say() {
    // The walls of the U and the gap, and the random field, are sensed by the vehicle's own
    // sonar (the firmware's evidence map holds walls).
    for (name, sensing) in [
        ("u_trap.toml", Sensing::Sonar),
        ("narrow_gap.toml", Sensing::Sonar),
        ("random_clutter.toml", Sensing::Sonar),
    ] {
        let s = shipped(name);
        assert_eq!(s.params.strategy, Strategy::Vpf);
        assert_eq!(s.mode, RunMode::Lockstep);
        for v in &s.vehicles {
            assert_eq!(v.model, ModelKind::VideoRay, "{name}");
            assert_eq!(v.sensing, sensing, "{name}");
        }
    }
    let u = shipped("u_trap.toml");
    assert!(u.params.a_rotor > 0.0);
    assert_eq!(u.params.max_ghosts, 0);
    assert_eq!(u.obstacles.len(), 3);
}

#[test]
fn narrow_gap_is_about_three_metres_wide_on_the_track() {
    let s = shipped("narrow_gap.toml");
    // At the gap's centre both walls are 1.5 m away; 2 m to either side there is a wall.
    let mid = clearance(&s, P2::new(25.0, 0.0));
    assert!((mid - 1.5).abs() < 0.01, "{mid}");
    assert!(clearance(&s, P2::new(25.0, 2.0)) < 0.0);
    assert!(clearance(&s, P2::new(25.0, -2.0)) < 0.0);
}

/// Breadth-first search on a grid over the free space inflated by `margin`.
fn path_exists(s: &Scenario, from: P2, to: P2, margin: f32) -> bool {
    path_exists_in(s, from, to, margin, P2::new(-10.0, -30.0), (440, 240), 0.25)
}

/// [`path_exists`] on the `nx` × `ny` grid of cell `h` m whose corner is `lo`.
fn path_exists_in(
    s: &Scenario,
    from: P2,
    to: P2,
    margin: f32,
    lo: P2,
    (nx, ny): (usize, usize),
    h: f64,
) -> bool {
    let (x0, y0) = (lo.x, lo.y);
    let cell = |p: P2| {
        (
            ((p.x - x0) / h).round() as usize,
            ((p.y - y0) / h).round() as usize,
        )
    };
    let free =
        |i: usize, j: usize| clearance(s, P2::new(x0 + i as f64 * h, y0 + j as f64 * h)) > margin;
    let (start, goal) = (cell(from), cell(to));
    let mut seen = vec![false; nx * ny];
    let mut queue = VecDeque::from([start]);
    seen[start.0 * ny + start.1] = true;
    while let Some((i, j)) = queue.pop_front() {
        if (i, j) == goal {
            return true;
        }
        let next = [
            (i + 1, j),
            (i.wrapping_sub(1), j),
            (i, j + 1),
            (i, j.wrapping_sub(1)),
        ];
        for (a, b) in next {
            if a < nx && b < ny && !seen[a * ny + b] && free(a, b) {
                seen[a * ny + b] = true;
                queue.push_back((a, b));
            }
        }
    }
    false
}

#[test]
fn random_clutter_blocks_the_straight_line_but_leaves_a_clear_path() {
    let s = shipped("random_clutter.toml");
    assert!((13..=17).contains(&s.obstacles.len()));
    let v = &s.vehicles[0];
    let closest_on_line = (0..=800)
        .map(|k| clearance(&s, P2::new(f64::from(k) * 0.1, 0.0)))
        .fold(f32::INFINITY, f32::min);
    assert!(closest_on_line < 1.0, "the straight line is too easy");
    assert!(path_exists(&s, v.start, v.goal, 1.5));
    // The check itself can fail: a wall across the theatre closes every path.
    let mut walled = s.clone();
    walled.obstacles.push(hil::types::SimObstacle {
        shape: SimShape::Rectangle {
            center: P2::new(40.0, 0.0),
            half_size: P2::new(0.5, 40.0),
            angle: 0.0,
        },
        velocity: P2::default(),
    });
    assert!(!path_exists(&walled, v.start, v.goal, 1.5));
}

/// Where the track of obstacle `o` (a circle) crosses the straight line from `a` to `b`: the
/// time t and the distance along the line, if its centre crosses the segment.
fn crossing(o: &hil::types::SimObstacle, a: P2, b: P2) -> Option<(f64, f64)> {
    let SimShape::Circle { center, .. } = o.shape else {
        return None;
    };
    let len = b.sub(a).norm();
    let d = b.sub(a).scale(1.0 / len);
    let n = P2::new(-d.y, d.x);
    let across = |p: P2| p.sub(a).x * n.x + p.sub(a).y * n.y;
    let rate = o.velocity.x * n.x + o.velocity.y * n.y;
    if rate == 0.0 {
        return None;
    }
    let t = -across(center) / rate;
    let at = center.add(o.velocity.scale(t)).sub(a);
    let s = at.x * d.x + at.y * d.y;
    (t >= 0.0 && (0.0..=len).contains(&s)).then_some((t, s))
}

#[test]
fn seed_003_scenarios_fly_the_flat_fish_through_circles() {
    let hull = hil::runner::hull_radius(ModelKind::FlatFish);
    assert_eq!(hull, 2.25);
    let case1 = shipped("seed003_case1_static.toml");
    let case2 = shipped("seed003_case2_moving.toml");
    for s in [&case1, &case2] {
        assert_eq!(s.vehicles.len(), 1);
        let v = &s.vehicles[0];
        assert_eq!(v.model, ModelKind::FlatFish);
        assert_eq!(v.sensing, Sensing::Contacts);
        assert_eq!(
            (v.start, v.goal),
            (P2::new(30.0, 20.0), P2::new(170.0, 170.0))
        );
        assert_eq!(s.params.strategy, Strategy::Multipoint);
        assert_eq!(s.params.v_max, 1.0, "the paper's 1 m/s");
        assert!((300.0..=600.0).contains(&s.duration_s));
        for o in &s.obstacles {
            let SimShape::Circle { radius, .. } = o.shape else {
                panic!("seed 003 has circles only: {o:?}");
            };
            assert!((4.0..=10.0).contains(&radius), "{o:?}");
        }
        // A route exists for the hull, on a 1 m grid over the theatre (static circles).
        let statics = Scenario {
            obstacles: s
                .obstacles
                .iter()
                .filter(|o| o.velocity == P2::default())
                .cloned()
                .collect(),
            ..s.clone()
        };
        let theatre = (P2::new(0.0, 0.0), (201, 201), 1.0);
        assert!(path_exists_in(
            &statics,
            v.start,
            v.goal,
            hull as f32,
            theatre.0,
            theatre.1,
            theatre.2
        ));
    }

    // Case 1: 6-10 static circles, at least two blocking the straight line for the hull.
    assert!((6..=10).contains(&case1.obstacles.len()));
    assert!(case1.obstacles.iter().all(|o| o.velocity == P2::default()));
    let (a, b) = (P2::new(30.0, 20.0), P2::new(170.0, 170.0));
    let on_line = |s: &Scenario, t: f64| {
        s.obstacles
            .iter()
            .filter(|o| {
                (0..=2000).any(|k| {
                    let p = a.add(b.sub(a).scale(f64::from(k) / 2000.0));
                    o.signed_distance(t, p) < hull
                })
            })
            .count()
    };
    assert!(on_line(&case1, 0.0) >= 2, "the straight line is too easy");

    // Case 2: static circles too, and movers slower than the vehicle that cross the straight
    // line during the run, without ever overlapping a static circle.
    let (movers, statics): (Vec<_>, Vec<_>) = case2
        .obstacles
        .iter()
        .partition(|o| o.velocity != P2::default());
    assert!(statics.len() >= 2 && (2..=5).contains(&movers.len()));
    assert!(on_line(&case2, 0.0) >= 2);
    for m in &movers {
        let speed = m.velocity.norm();
        // 0.3-0.8 m/s, to the three decimals of the file's components.
        assert!((0.299..=0.801).contains(&speed), "{m:?}");
        let (t, _) = crossing(m, a, b).unwrap_or_else(|| panic!("never crosses: {m:?}"));
        assert!(t < 250.0, "crosses too late: {t} s");
        let SimShape::Circle { radius, .. } = m.shape else {
            unreachable!()
        };
        for st in &statics {
            let closest = (0..=4000)
                .map(|k| {
                    let t = f64::from(k) * 0.1;
                    st.signed_distance(t, m.shape_at(t).center()) - radius
                })
                .fold(f64::INFINITY, f64::min);
            assert!(closest > 0.0, "{m:?} runs through {st:?}");
        }
    }
}

#[test]
fn crossing_traffic_puts_the_videoray_on_collision_courses() {
    let s = shipped("crossing_traffic.toml");
    assert_eq!(s.params.strategy, Strategy::Vpf);
    let v = &s.vehicles[0];
    assert_eq!(
        (v.model, v.sensing),
        (ModelKind::VideoRay, Sensing::Contacts)
    );
    assert!((2..=3).contains(&s.obstacles.len()));
    for o in &s.obstacles {
        let speed = o.velocity.norm();
        assert!(
            speed > 0.0 && speed <= f64::from(s.params.v_max) + 1e-9,
            "{o:?}"
        );
        // It reaches the track within 5 s of when a vehicle at v_max, 1.3 s late off the
        // start, would be at the same place.
        let (t, along) = crossing(o, v.start, v.goal).expect("crosses the track");
        let there = along / f64::from(s.params.v_max) + 1.3;
        assert!(
            (t - there).abs() < 5.0,
            "{o:?}: crosses at {t} s, vehicle there at {there} s"
        );
    }
    // At least one crosses at the vehicle's full speed.
    assert!(s.obstacles.iter().any(|o| o.velocity.norm() >= 0.99));
}

#[test]
fn flat_fish_model_spellings_parse() {
    for name in ["flatfish", "flat-fish", "flat_fish"] {
        let text = BASE.replace("\"kinematic\"", &format!("\"{name}\""));
        let s = scenario::parse(&text, "ff.toml").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.vehicles[0].model, ModelKind::FlatFish, "{name}");
    }
    let e = refused(&BASE.replace("\"kinematic\"", "\"flat fish\""));
    assert!(e.message.contains("\"flatfish\""), "{e}");
}

// ---------------------------------------------------------------------------------------------
// Refusals.

/// A valid scenario; the bad inputs below append to it or replace a line of it.
const BASE: &str = r#"name = "base"
duration_s = 10.0
dt_s = 0.1
seed = 7

[[vehicle]]
name = "a"
model = "kinematic"
start = [0.0, 0.0]
goal = [10.0, 0.0]
"#;

/// The 1-based line of the only occurrence of `needle` in `text`.
fn line_of(text: &str, needle: &str) -> usize {
    assert_eq!(text.matches(needle).count(), 1, "`{needle}` must be unique");
    let at = text.find(needle).unwrap();
    1 + text[..at].matches('\n').count()
}

fn refused(text: &str) -> ScenarioError {
    match scenario::parse(text, "bad.toml") {
        Ok(s) => panic!("accepted: {s:?}"),
        Err(e) => {
            assert_eq!(e.file, "bad.toml");
            e
        }
    }
}

/// Asserts the error's key, its line (that of `needle`) and that its message contains `msg`.
fn assert_refused(text: &str, key: &str, needle: &str, msg: &str) -> ScenarioError {
    let e = refused(text);
    assert_eq!(e.key, key, "{e}");
    assert_eq!(e.line, line_of(text, needle), "{e}");
    assert!(e.message.contains(msg), "{e}");
    e
}

fn with(extra: &str) -> String {
    format!("{BASE}{extra}")
}

#[test]
fn the_base_scenario_is_valid_and_defaults_apply() {
    let s = scenario::parse(BASE, "base.toml").unwrap();
    assert_eq!(s.name, "base");
    assert_eq!(s.seed, 7);
    assert_eq!(s.mode, RunMode::Lockstep);
    assert_eq!(s.params, vpf::Params::default());
    assert_eq!(s.sonar, scenario::Sonar::default());
    // The transit set-up: 20 m in 3.6° steps (a 3.2 s sweep).
    assert_eq!(s.sonar.range_m, 20.0);
    assert!((s.sonar.step.to_degrees() - 3.6).abs() < 1e-9);
    assert_eq!(s.navigation.rate_hz, 10.0);
    assert_eq!(s.faults, scenario::Faults::default());
    assert_eq!(s.vehicles[0].heading, 0.0);
    assert_eq!(s.vehicles[0].sensing, Sensing::Sonar);
    assert_eq!(s.vehicles[0].formation, None);
}

#[test]
fn a_flat_fish_carries_its_sonar_at_40_m_unless_told_otherwise() {
    let flatfish = BASE.replace("\"kinematic\"", "\"flat-fish\"");
    let range = |text: &str| scenario::parse(text, "f.toml").unwrap().sonar.range_m;
    assert_eq!(range(&flatfish), scenario::Sonar::FLATFISH_RANGE_M);
    assert_eq!(range(&format!("{flatfish}[sonar]\nrange_m = 30.0\n")), 30.0);
    // Another model in the water: the default head for all of them.
    let other = "[[vehicle]]\nname = \"b\"\nmodel = \"videoray\"\nstart = [0.0, 5.0]\n\
                 goal = [10.0, 5.0]\n";
    assert_eq!(range(&format!("{flatfish}{other}")), 20.0);
}

#[test]
fn every_section_is_read_with_units_converted() {
    let text = with(
        r#"heading_deg = 90.0
sensing = "contacts"
[vehicle.formation]
q = 6
lattice_m = 3.0
orientation_deg = 30.0

[[vehicle]]
name = "b"
model = "videoray"
start = [0.0, 5.0]
goal = [10.0, 5.0]

[planner]
strategy = "vpf"
mu = 0.2
bounding = "plain"
n_gamma = 8
seed = 42

[sonar]
mode = "contacts"
range_m = 50
bins = 128
step_deg = 3.6
noise = 0.1
speckle = 0.2

[navigation]
position_sigma_m = 0.5
heading_sigma_deg = 2.0
rate_hz = 5.0

[current]
velocity = [0.1, -0.2]

[faults]
bit_error_rate = 0.001
drop_rate = 0.05
nav_delay_ms = 200
nav_freeze = [5.0, 6.0]
nav_loss = [7, 8]
sonar_dropout = [1.0, 2.5]

[[obstacle]]
shape = "circle"
center = [5.0, 2.5]
radius = 1.0
velocity = [0.0, 0.5]

[[obstacle]]
shape = "polygon"
points = [[20.0, 0.0], [22.0, 0.0], [21.0, 2.0]]
"#,
    )
    .replace("dt_s = 0.1", "dt_s = 0.05\nmode = \"realtime\"");
    let s = scenario::parse(&text, "full.toml").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.mode, RunMode::Realtime);
    assert_eq!(s.params.period_s, 0.05);
    assert_eq!(s.params.mu, 0.2);
    assert_eq!(s.params.bounding, vpf::Bounding::Plain);
    assert_eq!((s.params.n_gamma, s.params.seed), (8, 42));
    let a = &s.vehicles[0];
    assert!((a.heading - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    assert_eq!(a.sensing, Sensing::Contacts);
    let f = a.formation.unwrap();
    assert_eq!((f.q, f.lattice_m, f.attraction), (6, 3.0, 5.0));
    assert!((f.orientation - 30f32.to_radians()).abs() < 1e-6);
    // Without its own `sensing`, a vehicle takes the sonar's mode.
    assert_eq!(s.vehicles[1].sensing, Sensing::Contacts);
    assert_eq!(s.vehicles[1].model, ModelKind::VideoRay);
    assert_eq!(s.sonar.bins, 128);
    assert!((s.sonar.step - 3.6f64.to_radians()).abs() < 1e-12);
    assert_eq!(s.navigation.rate_hz, 5.0);
    assert!((s.navigation.heading_sigma - 2f64.to_radians()).abs() < 1e-12);
    assert_eq!(s.current.velocity, P2::new(0.1, -0.2));
    assert_eq!(s.faults.nav_delay_ms, 200.0);
    let loss = s.faults.nav_loss.unwrap();
    assert!(loss.contains(7.0) && !loss.contains(8.0));
    assert_eq!(s.obstacles[0].velocity, P2::new(0.0, 0.5));
    assert!(matches!(&s.obstacles[1].shape, SimShape::Polygon { points } if points.len() == 3));
}

#[test]
fn unknown_keys_are_refused_anywhere() {
    let text = BASE.replace("seed = 7", "seed = 7\ncolour = \"red\"");
    assert_refused(&text, "colour", "colour", "unknown key in the scenario");

    let text = with("\n[[obstacle]]\nshape = \"circle\"\ncenter = [5.0, 5.0]\nradius_m = 2.0\n");
    let e = assert_refused(
        &text,
        "obstacle[0].radius_m",
        "radius_m",
        "did you mean `radius`?",
    );
    assert_eq!(
        e.to_string(),
        format!(
            "bad.toml:{}: key `obstacle[0].radius_m`: unknown key in a circle obstacle \
             (did you mean `radius`?)",
            line_of(&text, "radius_m")
        )
    );

    // A key that belongs to another shape is unknown for this one.
    let text = with(
        "\n[[obstacle]]\nshape = \"circle\"\ncenter = [5.0, 5.0]\nradius = 1.0\nangle_deg = 3\n",
    );
    assert_refused(&text, "obstacle[0].angle_deg", "angle_deg", "unknown key");

    let text = with("[vehicle.formation]\nq = 4\nlattice_m = 2.0\nspacing = 1\n");
    assert_refused(
        &text,
        "vehicle[0].formation.spacing",
        "spacing",
        "unknown key",
    );

    let text = with("\n[planner]\nmu = 0.1\nfriction = 0.4\n");
    assert_refused(
        &text,
        "planner.friction",
        "friction",
        "unknown key in [planner]",
    );

    // Of two unknown keys, the first in the file is reported (not the first by name).
    let text = with("zeta = 1\nalpha = 2\n");
    assert_refused(
        &text,
        "vehicle[0].zeta",
        "zeta",
        "unknown key in a [[vehicle]]",
    );

    let text = with("\n[faults]\nbit_flips = 3\n");
    assert_refused(
        &text,
        "faults.bit_flips",
        "bit_flips",
        "unknown key in [faults]",
    );
}

#[test]
fn non_finite_numbers_are_refused() {
    let text = with("\n[[obstacle]]\nshape = \"circle\"\ncenter = [5.0, 5.0]\nradius = nan\n");
    let e = assert_refused(
        &text,
        "obstacle[0].radius",
        "radius",
        "must be a finite number",
    );
    assert!(e.message.contains("NaN"), "{e}");

    let text = BASE.replace("goal = [10.0, 0.0]", "goal = [10.0, -inf]");
    assert_refused(
        &text,
        "vehicle[0].goal[1]",
        "goal",
        "must be a finite number, got -inf",
    );

    let text = with("\n[planner]\nv_max = inf\n");
    assert_refused(&text, "planner.v_max", "v_max", "must be a finite number");
}

#[test]
fn negative_radius_names_file_line_and_key() {
    let text = with("\n[[obstacle]]\nshape = \"circle\"\ncenter = [5.0, 5.0]\nradius = -1\n");
    let e = assert_refused(&text, "obstacle[0].radius", "radius", "must be > 0, got -1");
    let line = line_of(&text, "radius");
    assert_eq!(line, 15);
    assert_eq!(
        e.to_string(),
        "bad.toml:15: key `obstacle[0].radius`: must be > 0, got -1"
    );
    assert_eq!(e.column, None);

    // The index counts obstacles in file order.
    let text = with(
        "\n[[obstacle]]\nshape = \"circle\"\ncenter = [5.0, 5.0]\nradius = 1\n\
         \n[[obstacle]]\nshape = \"rectangle\"\ncenter = [5.0, -5.0]\nhalf_size = [0.0, 1.0]\n",
    );
    assert_refused(
        &text,
        "obstacle[1].half_size[0]",
        "half_size",
        "must be > 0, got 0",
    );
}

#[test]
fn concave_self_intersecting_and_degenerate_polygons_are_refused() {
    // An arrow head: vertex 2 (at [21, 1]) is reflex.
    let text = with(
        "\n[[obstacle]]\nshape = \"polygon\"\npoints = [\n  [20.0, 0.0],\n  [24.0, 0.0],\n  \
         [21.0, 1.0],\n  [24.0, 2.0],\n  [20.0, 2.0],\n]\n",
    );
    let e = assert_refused(&text, "obstacle[0].points[2]", "[21.0, 1.0]", "concave");
    assert!(e.message.contains("split it into convex pieces"), "{e}");

    // A pentagram turns the same way at every vertex but crosses itself.
    let star: Vec<String> = (0..5)
        .map(|k| {
            let a = std::f64::consts::TAU * f64::from(k * 2) / 5.0;
            format!("[{:.4}, {:.4}]", 30.0 + 3.0 * a.cos(), 3.0 * a.sin())
        })
        .collect();
    let text = with(&format!(
        "\n[[obstacle]]\nshape = \"polygon\"\npoints = [{}]\n",
        star.join(", ")
    ));
    assert_refused(&text, "obstacle[0].points", "points", "self-intersecting");

    let text = with(
        "\n[[obstacle]]\nshape = \"polygon\"\npoints = [[20.0, 0.0], [21.0, 0.0], [22.0, 0.0]]\n",
    );
    assert_refused(&text, "obstacle[0].points[0]", "points", "collinear");

    let text = with("\n[[obstacle]]\nshape = \"polygon\"\npoints = [[20.0, 0.0], [21.0, 0.0]]\n");
    assert_refused(
        &text,
        "obstacle[0].points",
        "points",
        "3 ..= 8 vertices, got 2",
    );

    let text = with(
        "\n[[obstacle]]\nshape = \"polygon\"\npoints = [[20.0, 0.0], [20.0, 0.0], [22.0, 1.0]]\n",
    );
    assert_refused(&text, "obstacle[0].points[1]", "points", "repeats vertex 0");
}

#[test]
fn planner_parameters_are_checked_by_the_library() {
    let text = with("\n[planner]\nmu = 50\n");
    let e = assert_refused(&text, "planner.mu", "mu = 50", "must be in 0 ..= 10");
    assert!(e.message.ends_with("got 50"), "{e}");

    let text = with("\n[planner]\nmax_ghosts = 9\n");
    assert_refused(
        &text,
        "planner.max_ghosts",
        "max_ghosts",
        "must be in 0 ..= 4, got 9",
    );

    let text = with("\n[planner]\nn_gamma = 300\n");
    assert_refused(&text, "planner.n_gamma", "n_gamma", "got 300");

    let text = with("\n[planner]\nbounding = \"soft\"\n");
    assert_refused(
        &text,
        "planner.bounding",
        "bounding",
        "unknown bounding \"soft\"",
    );

    // A default that a changed parameter makes invalid is reported at [planner].
    let text = with("\n[planner]\nv_max = 0.01\n");
    let e = assert_refused(
        &text,
        "planner.stall_speed",
        "[planner]",
        "the default 0.05",
    );
    assert!(e.message.contains("v_max"), "{e}");

    let text = with("\n[planner]\nperiod_s = 0.2\n");
    assert_refused(&text, "planner.period_s", "period_s", "top-level `dt_s`");

    let text = with("\n[planner]\nstrategy = \"astar\"\n");
    assert_refused(&text, "planner.strategy", "strategy", "unknown strategy");
    for (name, s) in [
        ("navfn", vpf::Strategy::Navfn),
        ("multipoint", vpf::Strategy::Multipoint),
    ] {
        let text = with(&format!("\n[planner]\nstrategy = \"{name}\"\n"));
        assert_eq!(scenario::parse(&text, "t.toml").unwrap().params.strategy, s);
    }

    let text = BASE.replace("dt_s = 0.1", "dt_s = 2.0");
    assert_refused(&text, "dt_s", "dt_s", "must be in 0.02 ..= 1 s, got 2");
}

#[test]
fn a_ping360_interface_is_checked_against_what_a_ping360_can_do() {
    use hil::scenario::SonarInterface;
    let s = scenario::parse(&with("\n[sonar]\ninterface = \"ping360\"\n"), "p.toml").unwrap();
    assert_eq!(s.sonar.interface, SonarInterface::Ping360);
    let s = scenario::parse(BASE, "p.toml").unwrap();
    assert_eq!(s.sonar.interface, SonarInterface::Link);
    let text = with("\n[sonar]\ninterface = \"ping360\"\nstep_deg = 1.0\n");
    assert_refused(&text, "sonar.step_deg", "step_deg = 1.0", "whole gradians");
    let text = with("\n[sonar]\ninterface = \"ping360\"\nbins = 150\n");
    assert_refused(&text, "sonar.bins", "bins = 150", "200 ..= 1200 samples");
    let text = with("\n[sonar]\ninterface = \"ping360\"\nrange_m = 0.5\nbins = 500\n");
    assert_refused(&text, "sonar.range_m", "range_m = 0.5", "sample period");
    let text = with("\n[sonar]\ninterface = \"sidescan\"\n");
    assert_refused(
        &text,
        "sonar.interface",
        "sidescan",
        "unknown sonar interface",
    );
    let text = with("\n[faults]\nping360_bit_error_rate = 0.5\n");
    assert_refused(&text, "faults.ping360_bit_error_rate", "0.5", "");
}

#[test]
fn unknown_model_and_enumerations_are_refused() {
    let text = BASE.replace("\"kinematic\"", "\"torpedo\"");
    let e = assert_refused(
        &text,
        "vehicle[0].model",
        "torpedo",
        "unknown model \"torpedo\"",
    );
    assert!(e.message.contains("\"kinematic\" or \"videoray\""), "{e}");

    let text = BASE.replace("seed = 7", "seed = 7\nmode = \"turbo\"");
    assert_refused(&text, "mode", "turbo", "unknown mode");

    let text = with("sensing = \"radar\"\n");
    assert_refused(&text, "vehicle[0].sensing", "radar", "unknown sensing");

    let text = with("\n[[obstacle]]\nshape = \"ellipse\"\n");
    assert_refused(&text, "obstacle[0].shape", "ellipse", "unknown shape");
}

#[test]
fn missing_required_keys_point_at_their_table() {
    let text = BASE.replace("goal = [10.0, 0.0]\n", "");
    let e = assert_refused(
        &text,
        "vehicle[0].goal",
        "[[vehicle]]",
        "missing required key",
    );
    assert_eq!(
        e.to_string(),
        "bad.toml:6: key `vehicle[0].goal`: missing required key"
    );

    let text = BASE.replace("duration_s = 10.0\n", "");
    assert_refused(
        &text,
        "duration_s",
        "name = \"base\"",
        "missing required key",
    );

    let text = with("\n[[obstacle]]\nshape = \"circle\"\nradius = 1.0\n");
    assert_refused(
        &text,
        "obstacle[0].center",
        "[[obstacle]]",
        "missing required key",
    );

    let text = with("[vehicle.formation]\nq = 4\n");
    assert_refused(
        &text,
        "vehicle[0].formation.lattice_m",
        "[vehicle.formation]",
        "missing",
    );

    let text = BASE.split("[[vehicle]]").next().unwrap().to_string();
    let e = refused(&text);
    assert_eq!(e.key, "vehicle");
    assert!(e.message.contains("at least one [[vehicle]]"), "{e}");
}

#[test]
fn toml_syntax_errors_keep_line_and_column() {
    let text = BASE.replace("seed = 7", "seed = 7 8");
    let e = refused(&text);
    assert_eq!(e.line, 4);
    assert_eq!(e.column, Some(8));
    assert!(e.key.is_empty());
    assert!(e.message.starts_with("TOML syntax error: "), "{e}");
    assert!(
        e.to_string().starts_with("bad.toml:4:8: TOML syntax error"),
        "{e}"
    );

    let text = BASE.replace("seed = 7", "seed = 7\nname = \"again\"");
    let e = refused(&text);
    assert_eq!((e.line, e.column), (5, Some(1)));
    assert!(e.message.contains("duplicate key"), "{e}");
}

#[test]
fn wrong_types_are_refused() {
    let text = BASE.replace("duration_s = 10.0", "duration_s = \"long\"");
    assert_refused(
        &text,
        "duration_s",
        "duration_s",
        "expected a number, got a string",
    );

    let text = BASE.replace("seed = 7", "seed = 7.5");
    assert_refused(&text, "seed", "seed", "expected an integer, got a float");

    let text = BASE.replace("start = [0.0, 0.0]", "start = [0.0, 0.0, 1.0]");
    assert_refused(&text, "vehicle[0].start", "start", "expected a pair [x, y]");

    let text = BASE.replace("start = [0.0, 0.0]", "start = [0.0, \"north\"]");
    assert_refused(
        &text,
        "vehicle[0].start[1]",
        "start",
        "expected a number, got a string",
    );

    let text = BASE.replace("[[vehicle]]", "[vehicle]");
    assert_refused(&text, "vehicle", "[vehicle]", "expected an array of tables");

    let text = with("\n[sonar]\nbins = 0\n");
    assert_refused(&text, "sonar.bins", "bins", "must be in 1 ..= 512, got 0");

    let text = BASE.replace("seed = 7", "seed = -1");
    assert_refused(&text, "seed", "seed", "must be >= 0");
}

#[test]
fn impossible_geometry_is_refused() {
    // Start inside an obstacle.
    let text = with("\n[[obstacle]]\nshape = \"circle\"\ncenter = [0.5, 0.0]\nradius = 2.0\n");
    assert_refused(&text, "vehicle[0].start", "start", "inside obstacle[0]");

    // Goal inside a static obstacle (a moving one may uncover it).
    let obstacle = "\n[[obstacle]]\nshape = \"rectangle\"\ncenter = [10.0, 0.0]\nhalf_size = \
                    [1.0, 1.0]\nangle_deg = 45\n";
    assert_refused(
        &with(obstacle),
        "vehicle[0].goal",
        "goal",
        "inside the static obstacle[0]",
    );
    assert!(scenario::parse(&with(&format!("{obstacle}velocity = [0.0, 1.0]\n")), "t").is_ok());

    let second = "\n[[vehicle]]\nname=\"a\"\nmodel = \"videoray\"\nstart = [0.0, 20.0]\ngoal = \
                  [5.0, 5.0]\n";
    assert_refused(
        &with(second),
        "vehicle[1].name",
        "name=\"a\"",
        "two vehicles are named \"a\"",
    );

    let second = second
        .replace("\"a\"", "\"b\"")
        .replace("[0.0, 20.0]", "[0.3, 0.0]");
    assert_refused(
        &with(&second),
        "vehicle[1].start",
        "[0.3, 0.0]",
        "of vehicle \"a\"'s start",
    );

    let text = with("[vehicle.formation]\nq = 5\nlattice_m = 2.0\n");
    assert_refused(
        &text,
        "vehicle[0].formation.q",
        "q = 5",
        "must be 3, 4 or 6, got 5",
    );

    let text = with("\n[faults]\nnav_loss = [5.0, 2.0]\n");
    assert_refused(&text, "faults.nav_loss", "nav_loss", "0 <= from_s < to_s");

    let text = with("\n[current]\nvelocity = [10.0, 0.0]\n");
    assert_refused(&text, "current.velocity", "velocity", "at most 5 m/s");

    let text = BASE.replace("duration_s = 10.0", "duration_s = 0.01");
    assert_refused(&text, "duration_s", "duration_s", "at least dt_s");
}

#[test]
fn load_names_the_file_and_reports_missing_files() {
    let path = scenarios_dir().join("u_trap.toml");
    assert_eq!(
        shipped("u_trap.toml").name,
        "U-shaped trap: rotors on, ghosts off"
    );
    let missing = scenarios_dir().join("no_such_scenario.toml");
    let e = scenario::load(&missing).unwrap_err();
    assert_eq!(e.line, 0);
    assert!(e.to_string().starts_with(&missing.display().to_string()));
    assert!(e.message.contains("cannot read"), "{e}");
    // Errors of a loaded file carry its path.
    let bad = std::env::temp_dir().join(format!("hil-scenario-test-{}.toml", std::process::id()));
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&bad, text.replace("seed = 1", "seed = \"one\"")).unwrap();
    let e = scenario::load(&bad).unwrap_err();
    let _ = std::fs::remove_file(&bad);
    assert_eq!(e.file, bad.display().to_string());
    assert_eq!(e.key, "seed");
}

#[test]
fn no_input_makes_the_parser_panic() {
    // Every prefix of a real scenario, every line removed in turn, and every number replaced
    // by extreme values: each parses or is refused with a line inside the text.
    let text = std::fs::read_to_string(scenarios_dir().join("narrow_gap.toml")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let within = |t: &str, r: Result<Scenario, ScenarioError>| {
        if let Err(e) = r {
            assert!(e.line >= 1 && e.line <= t.lines().count() + 1, "{e}");
        }
    };
    for (i, _) in text.char_indices().step_by(3) {
        let t = &text[..i];
        within(t, scenario::parse(t, "p.toml"));
    }
    for skip in 0..lines.len() {
        let t: Vec<&str> = lines
            .iter()
            .enumerate()
            .filter(|&(i, _)| i != skip)
            .map(|(_, l)| *l)
            .collect();
        let t = t.join("\n");
        within(&t, scenario::parse(&t, "p.toml"));
    }
    for bad in [
        "1e400",
        "-0.0",
        "0",
        "-1",
        "99999999999999999999",
        "nan",
        "\"x\"",
        "[]",
        "{}",
    ] {
        for (i, l) in lines.iter().enumerate() {
            if let Some((k, _)) = l.split_once(" = ") {
                let mut t = lines.clone();
                let replaced = format!("{k} = {bad}");
                t[i] = &replaced;
                let t = t.join("\n");
                within(&t, scenario::parse(&t, "p.toml"));
            }
        }
    }
}

#[test]
fn the_readme_example_is_valid() {
    let readme = std::fs::read_to_string(scenarios_dir().join("README.md")).unwrap();
    let block = readme
        .split("```toml\n")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("README.md has a ```toml example");
    let s = scenario::parse(block, "README.md").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.vehicles.len(), 2);
    assert_eq!(s.obstacles.len(), 3);
    assert_eq!(s.vehicles[1].sensing, Sensing::Contacts);
    assert_eq!(s.faults.nav_loss.map(|w| w.to_s), Some(110.0));
}

#[test]
fn a_table_must_be_a_table_and_values_keep_their_toml_type() {
    // serde reads an array as a struct's fields in order: a table key refuses it.
    let text = with("formation = [4, 2.0]\n");
    assert_refused(
        &text,
        "vehicle[0].formation",
        "formation",
        "expected a table, got an array",
    );
    let text = with("\n[sonar]\nrange_m = 1979-05-27\n");
    assert_refused(
        &text,
        "sonar.range_m",
        "range_m",
        "expected a number, got a date-time",
    );
    let text = with("\n[[obstacle]]\nshape = \"circle\"\ncenter = [5.0, 5.0]\nradius = 1e400\n");
    assert_refused(&text, "obstacle[0].radius", "radius", "overflows");
    let text = BASE.replace("seed = 7", "seed = 99999999999999999999");
    assert_refused(&text, "seed", "seed", "too large");
    // A key unknown to every shape is hinted from the obstacle's own shape.
    let text = with("\n[[obstacle]]\nshape = \"rectangle\"\ncenter = [5.0, 5.0]\nradius = 1.0\n");
    assert_refused(
        &text,
        "obstacle[0].radius",
        "radius",
        "unknown key in a rectangle obstacle",
    );
}
