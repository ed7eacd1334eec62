//! Random scenarios from seeds: cluttered fields, narrow passages and U-traps, short (the
//! spec's `length_m`, 40–80 m by default) so that a sweep of thousands of runs stays cheap.
//!
//! Each generator draws its geometry in a local frame — start at the origin, goal on the +x
//! axis at the drawn length — then turns the whole layout by a random angle, and writes a
//! scenario file's text, which the scenario parser then checks like any other file. The same
//! (kind, seed, spec) gives the same text, bit for bit.
//!
//! Validity by construction:
//! - **clutter**: the obstacles' bounding circles keep a free gap of at least `min_gap_m` to
//!   each other and 4 m (× `scale`) to the start and the goal. Disjoint convex obstacles leave a connected
//!   free space, and with `min_gap_m` above the craft's diameter the inflated obstacles are
//!   still disjoint, so a collision-free path always exists. One obstacle always sits on the
//!   straight line, so the line itself is never free.
//! - **passage**: two walls on one line across the track leave an opening of the drawn width
//!   (`passage_gap_m`); nothing else comes within that width of the opening's centre, so the
//!   passage is open. The walls are long (10–20 m each, × `scale`) but finite: going round is
//!   allowed.
//! - **utrap**: a U (bottom and two side walls) opening towards the start, the straight line
//!   entering it; the start is at least 8 m and the goal (behind the U) at least 11 m from it
//!   (× `scale`).
//!
//! The spec's `scale` multiplies the generator's own sizes (obstacles of 0.8–2.5 m, walls,
//! the free room round the start and the goal, the field's width) for a larger craft; the
//! spec's ranges (`length_m`, `min_gap_m`, `passage_gap_m`, `utrap_*`) are metres as written.

use std::f64::consts::PI;
use std::fmt::Write as _;

use crate::scenario::{self, Scenario, ScenarioError, Sensing};
use crate::sim::Rng;
use crate::types::{SimShape, P2};

use super::spec::Spec;

/// The three generated families.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A cluttered field of circles and rectangles.
    Clutter,
    /// Two walls across the track with a narrow opening.
    Passage,
    /// A U-shaped trap opening towards the start.
    UTrap,
}

impl Kind {
    /// The spelling in ids and specs.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Clutter => "clutter",
            Kind::Passage => "passage",
            Kind::UTrap => "utrap",
        }
    }

    fn tag(self) -> u64 {
        match self {
            Kind::Clutter => 0xC1,
            Kind::Passage => 0xDA,
            Kind::UTrap => 0x07,
        }
    }
}

/// A generated scenario: its file text and what the generator guarantees about it.
#[derive(Clone, Debug)]
pub struct Generated {
    /// `clutter:3`, `passage:0`, ...
    pub id: String,
    /// The scenario file's text.
    pub text: String,
    /// Start and goal, m.
    pub start: P2,
    /// Goal, m.
    pub goal: P2,
    /// The obstacles (world frame).
    pub obstacles: Vec<SimShape>,
    /// Passage: the opening's centre and width, m.
    pub opening: Option<(P2, f64)>,
}

/// The seed of generated scenario `index` of `kind` under the spec's seed.
pub fn seed_of(spec_seed: u64, kind: Kind, index: usize) -> u64 {
    Rng::stream(
        spec_seed ^ kind.tag().wrapping_mul(0x9E37_79B9),
        index as u64,
    )
    .next_u64()
        >> 1
}

fn between(rng: &mut Rng, (lo, hi): (f64, f64)) -> f64 {
    lo + rng.uniform() * (hi - lo)
}

/// Rotation by `a` about the origin.
fn rot(p: P2, a: f64) -> P2 {
    let (s, c) = a.sin_cos();
    P2::new(c * p.x - s * p.y, s * p.x + c * p.y)
}

fn rotate_shape(sh: &SimShape, a: f64, about: P2) -> SimShape {
    match sh {
        SimShape::Circle { center, radius } => SimShape::Circle {
            center: rot(center.sub(about), a).add(about),
            radius: *radius,
        },
        SimShape::Rectangle {
            center,
            half_size,
            angle,
        } => SimShape::Rectangle {
            center: rot(center.sub(about), a).add(about),
            half_size: *half_size,
            angle: angle + a,
        },
        SimShape::Polygon { points } => SimShape::Polygon {
            points: points
                .iter()
                .map(|p| rot(p.sub(about), a).add(about))
                .collect(),
        },
    }
}

fn rect(center: P2, half: P2, angle: f64) -> SimShape {
    SimShape::Rectangle {
        center,
        half_size: half,
        angle,
    }
}

/// A random circle or rectangle at `c`, sizes times `k`.
fn blob(rng: &mut Rng, c: P2, k: f64) -> SimShape {
    if rng.uniform() < 0.5 {
        SimShape::Circle {
            center: c,
            radius: k * between(rng, (0.8, 2.5)),
        }
    } else {
        rect(
            c,
            P2::new(k * between(rng, (0.6, 3.0)), k * between(rng, (0.4, 1.5))),
            rng.uniform() * PI,
        )
    }
}

/// Free gap between two shapes' bounding circles.
fn gap(a: &SimShape, b: &SimShape) -> f64 {
    a.center().sub(b.center()).norm() - a.bounding_radius() - b.bounding_radius()
}

/// Generates scenario `index` of `kind` for `spec`.
pub fn generate(spec: &Spec, kind: Kind, index: usize) -> Generated {
    let seed = seed_of(spec.seed, kind, index);
    let sc = &spec.scenarios;
    // The generator's own sizes (obstacles, walls, free room round the start and the goal);
    // the spec's ranges are in metres as written.
    let k = sc.scale;
    let mut rng = Rng::stream(seed, 1);
    let mut length = between(&mut rng, sc.length_m);
    let mut obstacles: Vec<SimShape> = Vec::new();
    let mut opening = None;
    let mut goal_y = 0.0;
    match kind {
        Kind::Clutter => {
            let half_w = (0.25 * length).max(10.0 * k);
            let (x0, x1) = (6.0 * k, length - 6.0 * k);
            let density = between(&mut rng, sc.density) / 100.0 / (k * k);
            let n = ((x1 - x0) * 2.0 * half_w * density).round().max(1.0) as usize;
            let goal = P2::new(length, 0.0);
            let fits = |o: &SimShape, placed: &[SimShape]| {
                let r = o.bounding_radius();
                o.center().norm() - r >= 4.0 * k
                    && o.center().sub(goal).norm() - r >= 4.0 * k
                    && placed.iter().all(|p| gap(o, p) >= sc.min_gap_m)
            };
            // The first obstacle blocks the straight line.
            for _ in 0..100 {
                let c = P2::new(
                    between(&mut rng, (0.35 * length, 0.65 * length)),
                    between(&mut rng, (-0.5, 0.5)) * k,
                );
                let o = blob(&mut rng, c, k);
                if fits(&o, &obstacles) {
                    obstacles.push(o);
                    break;
                }
            }
            for _ in 0..n * 60 {
                if obstacles.len() >= n {
                    break;
                }
                let c = P2::new(
                    between(&mut rng, (x0, x1)),
                    between(&mut rng, (-half_w, half_w)),
                );
                let o = blob(&mut rng, c, k);
                if fits(&o, &obstacles) {
                    obstacles.push(o);
                }
            }
        }
        Kind::Passage => {
            let xw = between(&mut rng, (0.4 * length, 0.6 * length));
            let w = between(&mut rng, sc.passage_gap_m);
            let yc = between(&mut rng, (-3.0, 3.0)) * k;
            let thick = between(&mut rng, (0.6, 1.5)) * k;
            let (ln, ls) = (
                between(&mut rng, (10.0, 20.0)) * k,
                between(&mut rng, (10.0, 20.0)) * k,
            );
            let tilt = between(&mut rng, (-20.0, 20.0)).to_radians();
            let centre = P2::new(xw, yc);
            let north = rect(
                P2::new(xw, yc + w / 2.0 + ln / 2.0),
                P2::new(thick / 2.0, ln / 2.0),
                0.0,
            );
            let south = rect(
                P2::new(xw, yc - w / 2.0 - ls / 2.0),
                P2::new(thick / 2.0, ls / 2.0),
                0.0,
            );
            obstacles.push(rotate_shape(&north, tilt, centre));
            obstacles.push(rotate_shape(&south, tilt, centre));
            opening = Some((centre, w));
            goal_y = between(&mut rng, (-3.0, 3.0)) * k;
            let goal = P2::new(length, goal_y);
            // A few loose rocks away from the opening.
            let extra = (rng.uniform() * 3.0) as usize;
            for _ in 0..extra * 40 {
                if obstacles.len() >= 2 + extra {
                    break;
                }
                let c = P2::new(
                    between(&mut rng, (6.0 * k, length - 6.0 * k)),
                    between(&mut rng, (-12.0, 12.0)) * k,
                );
                let r = between(&mut rng, (0.8, 2.0)) * k;
                let o = SimShape::Circle {
                    center: c,
                    radius: r,
                };
                let clear = obstacles
                    .iter()
                    .all(|p| p.signed_distance(c) - r >= sc.min_gap_m)
                    && c.sub(centre).norm() - r >= w.max(sc.min_gap_m) + 2.0 * k
                    && c.norm() - r >= 4.0 * k
                    && c.sub(goal).norm() - r >= 4.0 * k;
                if clear {
                    obstacles.push(o);
                }
            }
        }
        Kind::UTrap => {
            let width = between(&mut rng, sc.utrap_width_m);
            let depth = between(&mut rng, sc.utrap_depth_m);
            let thick = k;
            length = length.max(depth + 22.0 * k);
            let xb = between(
                &mut rng,
                ((0.45 * length).max(depth + 8.0 * k), length - 12.0 * k),
            );
            let yc = between(&mut rng, (-1.0, 1.0)) * (width / 2.0 - 1.0).max(0.0) * 0.5;
            let tilt = between(&mut rng, (-15.0, 15.0)).to_radians();
            let about = P2::new(xb, yc);
            let bottom = rect(
                P2::new(xb + thick / 2.0, yc),
                P2::new(thick / 2.0, width / 2.0 + thick),
                0.0,
            );
            let side = |s: f64| {
                rect(
                    P2::new(
                        xb - depth / 2.0 + thick / 2.0,
                        yc + s * (width / 2.0 + thick / 2.0),
                    ),
                    P2::new(depth / 2.0 + thick / 2.0, thick / 2.0),
                    0.0,
                )
            };
            for sh in [bottom, side(1.0), side(-1.0)] {
                obstacles.push(rotate_shape(&sh, tilt, about));
            }
            goal_y = between(&mut rng, (-3.0, 3.0)) * k;
        }
    }

    // The whole layout turned by a random angle about the start.
    let turn = rng.uniform() * 2.0 * PI;
    let heading = turn + between(&mut rng, (-30.0, 30.0)).to_radians();
    let start = P2::default();
    let goal = rot(P2::new(length, goal_y), turn);
    let obstacles: Vec<SimShape> = obstacles
        .iter()
        .map(|o| rotate_shape(o, turn, start))
        .collect();
    let opening = opening.map(|(c, w)| (rot(c, turn), w));
    let current = if sc.current_mps > 0.0 {
        let a = rng.uniform() * 2.0 * PI;
        Some(rot(P2::new(rng.uniform() * sc.current_mps, 0.0), a))
    } else {
        None
    };

    let id = format!("{}:{index}", kind.name());
    let duration = sc.time_factor * length / sc.speed_mps + 20.0;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "# Generated by `hil sweep` ({id}, seed {seed}): {} over {length:.1} m.",
        kind.name()
    );
    let _ = writeln!(t, "name = \"{} {index}\"", kind.name());
    let _ = writeln!(t, "duration_s = {:.1}", duration.ceil());
    let _ = writeln!(t, "dt_s = 0.1");
    let _ = writeln!(t, "seed = {seed}");
    let _ = writeln!(t, "\n[sonar]\nrange_m = 30.0");
    if sc.nav_sigma_m > 0.0 {
        let _ = writeln!(
            t,
            "\n[navigation]\nposition_sigma_m = {:.3}",
            sc.nav_sigma_m
        );
    }
    if let Some(c) = current {
        let _ = writeln!(t, "\n[current]\nvelocity = [{:.3}, {:.3}]", c.x, c.y);
    }
    let sensing = match sc.sensing {
        Sensing::Contacts => "contacts",
        Sensing::Sonar => "sonar",
    };
    let _ = writeln!(
        t,
        "\n[[vehicle]]\nname = \"auv\"\nmodel = \"{}\"\nstart = [0.0, 0.0]\nheading_deg = {:.1}\n\
         goal = [{:.3}, {:.3}]\nsensing = \"{sensing}\"",
        spec.craft.model.name(),
        wrap_deg(heading.to_degrees()),
        goal.x,
        goal.y
    );
    for o in &obstacles {
        obstacle_table(&mut t, o, P2::default());
    }
    // What the file says, not the unrounded draw, is what the checks below and the tests see.
    let parsed: Vec<SimShape> = match scenario::parse(&t, &id) {
        Ok(s) => s.obstacles.into_iter().map(|o| o.shape).collect(),
        Err(_) => obstacles,
    };
    Generated {
        id,
        text: t,
        start,
        goal,
        obstacles: parsed,
        opening,
    }
}

/// Degrees in (-180, 180].
/// Appends the `[[obstacle]]` table of `shape` moving at `velocity` m/s to a scenario file's
/// text (centimetre-rounded coordinates; `hil bench` writes its worlds with it too).
pub fn obstacle_table(t: &mut String, shape: &SimShape, velocity: P2) {
    match shape {
        SimShape::Circle { center, radius } => {
            let _ = writeln!(
                t,
                "\n[[obstacle]]\nshape = \"circle\"\ncenter = [{:.3}, {:.3}]\nradius = {radius:.3}",
                center.x, center.y
            );
        }
        SimShape::Rectangle {
            center,
            half_size,
            angle,
        } => {
            let _ = writeln!(
                t,
                "\n[[obstacle]]\nshape = \"rectangle\"\ncenter = [{:.3}, {:.3}]\n\
                 half_size = [{:.3}, {:.3}]\nangle_deg = {:.2}",
                center.x,
                center.y,
                half_size.x,
                half_size.y,
                wrap_deg(angle.to_degrees())
            );
        }
        SimShape::Polygon { points } => {
            let pts: Vec<String> = points
                .iter()
                .map(|p| format!("[{:.3}, {:.3}]", p.x, p.y))
                .collect();
            let _ = writeln!(
                t,
                "\n[[obstacle]]\nshape = \"polygon\"\npoints = [{}]",
                pts.join(", ")
            );
        }
    }
    if velocity.norm() > 0.0 {
        let _ = writeln!(t, "velocity = [{:.3}, {:.3}]", velocity.x, velocity.y);
    }
}

/// An angle in degrees within −180 ..= 180 (the scenario schema takes ±360).
pub fn wrap_deg(d: f64) -> f64 {
    let w = d.rem_euclid(360.0);
    if w > 180.0 {
        w - 360.0
    } else {
        w
    }
}

/// One scenario of the batch, ready to run.
#[derive(Clone, Debug)]
pub struct BatchScenario {
    /// `file:PATH` or `clutter:3` etc.
    pub id: String,
    /// The scenario (its vehicles' model replaced by the craft's; duration capped).
    pub scenario: Scenario,
    /// The straight-line start–goal distance per vehicle, m.
    pub straight_m: Vec<f64>,
    /// The text it came from (hashed into the sweep's identity).
    pub text: String,
}

/// The sweep's scenarios, and the bench worlds left out of it.
#[derive(Clone, Debug, Default)]
pub struct Batch {
    /// The scenarios to fly.
    pub scenarios: Vec<BatchScenario>,
    /// Bench worlds with no draw the craft can fly (`bench:FAMILY:SEED`, why), left out as
    /// `hil bench` leaves them unflown: a flat-fish has none in some serpentines.
    pub left_out: Vec<(String, String)>,
}

/// The sweep's scenarios: the listed files (relative to `spec_dir`), then the generated ones,
/// each family in index order. A file or generated scenario that does not parse is an error; a
/// bench world with no feasible draw for the craft is left out ([`Batch::left_out`]), and an
/// error only when nothing is left to fly.
pub fn batch(spec: &Spec, spec_dir: &std::path::Path) -> Result<Batch, ScenarioError> {
    let mut out = Vec::new();
    let mut left_out = Vec::new();
    let fix = |mut s: Scenario, id: String, text: String| {
        for v in &mut s.vehicles {
            v.model = spec.craft.model;
        }
        if let (Some(cap), true) = (spec.scenarios.duration_cap_s, id.starts_with("file:")) {
            s.duration_s = s.duration_s.min(cap.max(s.dt_s));
        }
        let straight_m = s
            .vehicles
            .iter()
            .map(|v| v.goal.sub(v.start).norm())
            .collect();
        BatchScenario {
            id,
            scenario: s,
            straight_m,
            text,
        }
    };
    for f in &spec.scenarios.files {
        let path = spec_dir.join(f);
        let text = std::fs::read_to_string(&path).map_err(|e| ScenarioError {
            file: path.display().to_string(),
            line: 0,
            column: None,
            key: String::new(),
            message: format!("cannot read the scenario (listed in {}): {e}", spec.file),
        })?;
        let s = scenario::parse(&text, &path.display().to_string())?;
        out.push(fix(s, format!("file:{f}"), text));
    }
    let families = [
        (Kind::Clutter, spec.scenarios.clutter),
        (Kind::Passage, spec.scenarios.passage),
        (Kind::UTrap, spec.scenarios.utrap),
    ];
    for (kind, n) in families {
        for i in 0..n {
            let g = generate(spec, kind, i);
            let s = scenario::parse(&g.text, &g.id)?;
            out.push(fix(s, g.id, g.text));
        }
    }
    // `hil bench` worlds: the same world `hil bench` flies for this craft, checked feasible.
    let sc = &spec.scenarios;
    for &family in &sc.bench_families {
        for i in 0..sc.bench_count {
            let case = crate::bench::case::Case {
                family,
                seed: sc.bench_first_seed + i as u64,
                strategy: vpf::Strategy::Vpf,
                model: spec.craft.model,
                sensing: sc.sensing,
                trial: 0,
                head: crate::bench::case::Head::default(),
                current_mps: 0.0,
            };
            let id = format!("bench:{}:{}", family.name(), sc.bench_first_seed + i as u64);
            let crate::bench::case::Drawn {
                world: w,
                attempt,
                reference_s,
                ..
            } = match crate::bench::case::feasible_world(&case) {
                Ok(found) => found,
                Err(e) => {
                    left_out.push((id, format!("no draw fits the craft: {e}")));
                    continue;
                }
            };
            let limit = crate::bench::case::duration_s(reference_s);
            let text = crate::bench::case::scenario_text(&w, attempt, &case, limit);
            let s = scenario::parse(&text, &id)?;
            out.push(fix(s, id, text));
        }
    }
    if out.is_empty() {
        let why: Vec<String> = left_out
            .iter()
            .map(|(id, e)| format!("{id}: {e}"))
            .collect();
        return Err(ScenarioError {
            file: spec.file.clone(),
            line: 0,
            column: None,
            key: "scenarios".into(),
            message: format!("no scenario to fly ({})", why.join("; ")),
        });
    }
    Ok(Batch {
        scenarios: out,
        left_out,
    })
}
