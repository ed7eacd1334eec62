//! The benchmark's world families: each world deterministic from (family, seed), drawn in a
//! local frame — start at the origin heading +x, goal on or near the +x axis — and then turned
//! by a random angle about the start, so no family is aligned with the grid or the axes.
//!
//! Missions are 100–300 m, except every fourth seed (40–80 m: short ones too). Sizes are for a
//! VideoRay-class craft (hull 0.2 m); a craft that needs more room gets fewer feasible draws
//! (each world is checked by [`super::feasible`] and, for a craft with a turning radius, by
//! [`super::turning`] before it is flown, and redrawn from the next sub-seed when it is not).
//! One thing is drawn for the craft's hull: a formation's lattice, [`formation_lattice`], so
//! that its vehicles start apart (with the VideoRay's 4 m for every hull up to 1 m: the same
//! worlds as before).

use std::f64::consts::PI;

use crate::sim::Rng;
use crate::types::{SimObstacle, SimShape, P2};

/// Families of missions flown when named (`--families survey,berth,face`): not in the
/// default set, so that its 204 worlds stay comparable from one change to the next.
pub const MISSION_FAMILIES: [Family; 3] = [Family::Survey, Family::Berth, Family::Face];

/// How long a berth's or a face's vehicle must hold at its goal after arriving, s
/// ([`Family::Berth`], [`Family::Face`]).
pub const BERTH_HOLD_S: f64 = 60.0;

/// The families, in table order (the default set).
pub const FAMILIES: [Family; 12] = [
    Family::Clutter,
    Family::Boxes,
    Family::WallGap,
    Family::Harbour,
    Family::UTrap,
    Family::LTrap,
    Family::Channel,
    Family::Serpentine,
    Family::Rocks,
    Family::Crossing,
    Family::HeadOn,
    Family::Formation,
];

/// A family of generated worlds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Family {
    /// A field of random circles.
    Clutter,
    /// A field of rotated rectangles.
    Boxes,
    /// Long walls across the track with one gap 20–40 m off the line.
    WallGap,
    /// A quay with piers: start in one berth, goal in another.
    Harbour,
    /// A U opening towards the start, the goal behind it.
    UTrap,
    /// An L across the track: the long arm blocks, the short one hooks back.
    LTrap,
    /// A channel with a bend, walls on both sides.
    Channel,
    /// Three long walls from alternate sides.
    Serpentine,
    /// Clusters of touching and overlapping rocks.
    Rocks,
    /// Movers crossing the track at up to the vehicle's speed, timed to meet it.
    Crossing,
    /// Two vehicles swapping ends, a few rocks.
    HeadOn,
    /// Three or four vehicles in a square formation transiting light clutter. The vehicles
    /// know each other's positions (`[sonar] vehicle_contacts`): seed 001's virtual leader is
    /// built on them; the obstacles still come from each vehicle's own sonar.
    Formation,
    /// A lawnmower survey (4–8 lines 8–12 m apart, 30–120 m long) over a field of rocks
    /// scattered across the area, none within 5 m of a waypoint: a waypoint mission of 8–16
    /// legs, every one checked flyable; the reference time is the sum of the legs'.
    Survey,
    /// A berth alongside a quay: the goal 0.8–2.8 m beyond the hull off the quay's face, by
    /// a pier on one side or both (a slip) or none, reached across light clutter — and held
    /// for [`BERTH_HOLD_S`] after arriving (an inspection station, a docking approach). The
    /// other families end at arrival, so only this one measures whether the vehicle stays.
    Berth,
    /// A goal 0.5–1.5 m beyond the hull off the face of one structure — a rock 2–16 m across,
    /// a pile, a wall at any angle to the way in, a wall's corner — reached across light
    /// clutter and held for [`BERTH_HOLD_S`] (an inspection station: nearer than a berth, as
    /// near as the feasibility check's margin allows).
    Face,
}

impl Family {
    /// The family's name in the CLI and the tables.
    pub fn name(self) -> &'static str {
        match self {
            Family::Clutter => "clutter",
            Family::Boxes => "boxes",
            Family::WallGap => "wall_gap",
            Family::Harbour => "harbour",
            Family::UTrap => "utrap",
            Family::LTrap => "ltrap",
            Family::Channel => "channel",
            Family::Serpentine => "serpentine",
            Family::Rocks => "rocks",
            Family::Crossing => "crossing",
            Family::HeadOn => "head_on",
            Family::Formation => "formation",
            Family::Survey => "survey",
            Family::Berth => "berth",
            Family::Face => "face",
        }
    }

    /// How long a world's vehicles must hold at their goals after arriving, s: the run goes
    /// on that long after they all arrived ([`BERTH_HOLD_S`] for a berth or a face, else
    /// none).
    pub fn hold_s(self) -> f64 {
        if matches!(self, Family::Berth | Family::Face) {
            BERTH_HOLD_S
        } else {
            0.0
        }
    }

    /// The family named `s`.
    pub fn parse(s: &str) -> Option<Family> {
        FAMILIES
            .iter()
            .chain(&MISSION_FAMILIES)
            .copied()
            .find(|f| f.name() == s)
    }
}

/// One vehicle of a world.
#[derive(Clone, Debug, PartialEq)]
pub struct Craft {
    /// Start, m.
    pub start: P2,
    /// Initial heading, rad.
    pub heading: f64,
    /// Goal, m.
    pub goal: P2,
}

/// A generated world: obstacles (true geometry at t = 0) and vehicles.
#[derive(Clone, Debug, PartialEq)]
pub struct World {
    /// Its family.
    pub family: Family,
    /// Its seed.
    pub seed: u64,
    /// The obstacles.
    pub obstacles: Vec<SimObstacle>,
    /// The vehicles (one, except head-on and formation).
    pub crafts: Vec<Craft>,
    /// A square formation of this lattice, m, for every vehicle (formation worlds).
    pub formation_m: Option<f64>,
    /// The survey the (one) vehicle flies, world frame (survey worlds; its goal is the last
    /// waypoint).
    pub survey: Option<vpf::planner::Survey>,
}

impl World {
    /// Each vehicle's waypoints in order (for a single goal, just the goal).
    pub fn legs(&self, craft: &Craft) -> Vec<P2> {
        match self.survey.and_then(|s| s.waypoints().ok()) {
            Some(list) => list
                .iter()
                .map(|w| {
                    let p = w.position();
                    P2::new(f64::from(p.x), f64::from(p.y))
                })
                .collect(),
            None => vec![craft.goal],
        }
    }
}

fn between(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    lo + rng.uniform() * (hi - lo)
}

fn circle(c: P2, r: f64) -> SimShape {
    SimShape::Circle {
        center: c,
        radius: r,
    }
}

/// A wall: a rectangle from `a` to `b`, `t` m thick.
fn wall(a: P2, b: P2, t: f64) -> SimShape {
    let d = b.sub(a);
    SimShape::Rectangle {
        center: a.add(d.scale(0.5)),
        half_size: P2::new(0.5 * d.norm(), 0.5 * t),
        angle: d.y.atan2(d.x),
    }
}

/// The light clutter on a berth's or a face's way in: rocks of 0.8–2.5 m radius over the first
/// `length` − 25 m, none within 6 m of the start.
fn clutter_on_the_way(rng: &mut Rng, length: f64, start: P2) -> Vec<SimShape> {
    scatter(
        rng,
        (length / 20.0) as usize,
        (10.0, length - 25.0),
        20.0,
        3.0,
        &[start],
        6.0,
        &mut |r, c| circle(c, between(r, 0.8, 2.5)),
    )
}

fn rot(p: P2, a: f64) -> P2 {
    let (s, c) = a.sin_cos();
    P2::new(c * p.x - s * p.y, s * p.x + c * p.y)
}

fn rotated(sh: &SimShape, a: f64) -> SimShape {
    match sh {
        SimShape::Circle { center, radius } => circle(rot(*center, a), *radius),
        SimShape::Rectangle {
            center,
            half_size,
            angle,
        } => SimShape::Rectangle {
            center: rot(*center, a),
            half_size: *half_size,
            angle: angle + a,
        },
        SimShape::Polygon { points } => SimShape::Polygon {
            points: points.iter().map(|p| rot(*p, a)).collect(),
        },
    }
}

/// Free gap between the bounding circles of `s` and each of `placed`, m (∞ with none).
fn gap(s: &SimShape, placed: &[SimShape]) -> f64 {
    placed
        .iter()
        .map(|p| s.center().sub(p.center()).norm() - s.bounding_radius() - p.bounding_radius())
        .fold(f64::INFINITY, f64::min)
}

/// Scatters shapes from `draw` over x in `xs`, |y| ≤ `half_w`, keeping `min_gap` between
/// them and `keep` m from each of `away`, until `n` are placed or the tries run out.
#[allow(clippy::too_many_arguments)]
fn scatter(
    rng: &mut Rng,
    n: usize,
    xs: (f64, f64),
    half_w: f64,
    min_gap: f64,
    away: &[P2],
    keep: f64,
    draw: &mut dyn FnMut(&mut Rng, P2) -> SimShape,
) -> Vec<SimShape> {
    let mut out: Vec<SimShape> = Vec::new();
    for _ in 0..n * 40 {
        if out.len() >= n {
            break;
        }
        let c = P2::new(between(rng, xs.0, xs.1), between(rng, -half_w, half_w));
        let s = draw(rng, c);
        let clear = away
            .iter()
            .all(|a| s.center().sub(*a).norm() - s.bounding_radius() >= keep);
        if clear && gap(&s, &out) >= min_gap {
            out.push(s);
        }
    }
    out
}

/// The square lattice λ of a formation world for a craft of hull radius `hull_m`, m: 4 m (seed
/// 001's λ, ten VideoRay hulls) or four hull radii (two lengths), whichever is larger — room
/// for two hulls, the guard's margins round each and a hull's width between them. The
/// family's obstacle spacing grows with it (by λ / 4 m).
pub fn formation_lattice(hull_m: f64) -> f64 {
    f64::max(4.0, 4.0 * hull_m)
}

/// World `seed` of `family`, attempt `attempt` (a redraw after an infeasible one), for a craft
/// of hull radius `hull_m` (m; only a formation's spacing depends on it).
pub fn generate(family: Family, seed: u64, attempt: u64, hull_m: f64) -> World {
    let tag = family as u64 + 1;
    let mut rng = Rng::stream(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ tag, attempt);
    let short = seed % 4 == 3;
    let length = if short {
        between(&mut rng, 40.0, 80.0)
    } else {
        between(&mut rng, 100.0, 300.0)
    };
    let goal = P2::new(length, 0.0);
    let start = P2::new(0.0, 0.0);
    let mut shapes: Vec<SimShape> = Vec::new();
    let mut movers: Vec<SimObstacle> = Vec::new();
    let mut crafts = vec![Craft {
        start,
        heading: 0.0,
        goal,
    }];
    let mut formation_m = None;
    let mut survey = None;
    match family {
        Family::Clutter | Family::Boxes => {
            let boxes = family == Family::Boxes;
            let half_w = 25.0;
            let n = (length * 2.0 * half_w / between(&mut rng, 90.0, 160.0)) as usize;
            shapes = scatter(
                &mut rng,
                n,
                (8.0, length - 8.0),
                half_w,
                2.0,
                &[start, goal],
                5.0,
                &mut |r, c| {
                    if boxes {
                        SimShape::Rectangle {
                            center: c,
                            half_size: P2::new(between(r, 0.8, 4.0), between(r, 0.5, 2.0)),
                            angle: r.uniform() * PI,
                        }
                    } else {
                        circle(c, between(r, 0.8, 3.0))
                    }
                },
            );
        }
        Family::WallGap => {
            // One or two walls across the track, each 60–100 m long, a 4–8 m gap 20–40 m off.
            let walls = if length > 120.0 { 2 } else { 1 };
            for k in 0..walls {
                let x = length * (k as f64 + 1.0) / (walls as f64 + 1.0);
                let side = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
                let off = side * between(&mut rng, 20.0, 40.0);
                let w = between(&mut rng, 4.0, 8.0);
                let half = between(&mut rng, 30.0, 50.0);
                let (lo, hi) = (off - 0.5 * w, off + 0.5 * w);
                shapes.push(wall(P2::new(x, -half + off.min(0.0)), P2::new(x, lo), 1.0));
                shapes.push(wall(P2::new(x, hi), P2::new(x, half + off.max(0.0)), 1.0));
            }
        }
        Family::Harbour => {
            // A quay along y = 0 with piers every `spacing` m; berth to berth along it.
            let spacing = between(&mut rng, 14.0, 22.0);
            let pier = between(&mut rng, 12.0, 20.0);
            let berths = ((length / spacing).round() as usize).clamp(2, 10);
            let quay_len = spacing * (berths as f64 + 1.0);
            shapes.push(wall(P2::new(-spacing, -1.0), P2::new(quay_len, -1.0), 2.0));
            for k in 0..=berths + 1 {
                let x = -0.5 * spacing + k as f64 * spacing;
                shapes.push(wall(P2::new(x, 0.0), P2::new(x, pier), 1.5));
            }
            let y = between(&mut rng, 3.0, 0.6 * pier);
            crafts[0] = Craft {
                start: P2::new(0.0, y),
                heading: PI / 2.0,
                goal: P2::new(spacing * berths as f64, between(&mut rng, 3.0, 0.6 * pier)),
            };
        }
        Family::UTrap | Family::LTrap => {
            let x = between(&mut rng, 0.4, 0.6) * length;
            let depth = between(&mut rng, 8.0, 16.0);
            let half = between(&mut rng, 8.0, 15.0);
            // The bottom across the track, the arms reaching back towards the start.
            shapes.push(wall(P2::new(x, -half), P2::new(x, half), 1.0));
            shapes.push(wall(P2::new(x - depth, half), P2::new(x, half), 1.0));
            if family == Family::UTrap {
                shapes.push(wall(P2::new(x - depth, -half), P2::new(x, -half), 1.0));
            } else {
                // An L: the long side extends past the track, no second arm.
                let more = between(&mut rng, 10.0, 25.0);
                shapes.push(wall(P2::new(x, -half - more), P2::new(x, -half), 1.0));
            }
        }
        Family::Channel => {
            // Two parallel walls 6–12 m apart along a track with one bend of 30–60°.
            let width = between(&mut rng, 6.0, 12.0);
            let bend = between(&mut rng, 30.0, 60.0).to_radians()
                * if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            let leg = 0.5 * length;
            let corner = P2::new(leg, 0.0);
            let end = corner.add(rot(P2::new(leg, 0.0), bend));
            crafts[0].goal = end;
            let n1 = P2::new(0.0, 0.5 * width);
            let n2 = rot(n1, bend);
            for s in [1.0, -1.0] {
                let a0 = P2::new(-5.0, 0.0).add(n1.scale(s));
                let a1 = corner.add(n1.scale(s));
                let b0 = corner.add(n2.scale(s));
                let b1 = end.add(rot(P2::new(5.0, 0.0), bend)).add(n2.scale(s));
                shapes.push(wall(a0, a1, 1.0));
                shapes.push(wall(b0, b1, 1.0));
            }
        }
        Family::Serpentine => {
            let reach = between(&mut rng, 30.0, 45.0);
            let first = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            for k in 0..3 {
                let x = length * (k as f64 + 1.0) / 4.0;
                let s = if k % 2 == 0 { first } else { -first };
                // From far on one side to `reach − 44 + …` past the line: the gap is on the
                // other side, 6–12 m wide at the wall's end.
                let tip = -s * between(&mut rng, 6.0, 12.0);
                shapes.push(wall(P2::new(x, s * reach), P2::new(x, tip), 1.0));
            }
        }
        Family::Rocks => {
            let clusters = (length / 35.0).ceil() as usize;
            for k in 0..clusters {
                let c = P2::new(
                    length * (k as f64 + 1.0) / (clusters as f64 + 1.0),
                    between(&mut rng, -6.0, 6.0),
                );
                let n = 3 + (rng.uniform() * 4.0) as usize;
                for _ in 0..n {
                    let p = c.add(P2::new(
                        between(&mut rng, -4.0, 4.0),
                        between(&mut rng, -4.0, 4.0),
                    ));
                    shapes.push(circle(p, between(&mut rng, 1.0, 2.5)));
                }
            }
        }
        Family::Crossing => {
            // Movers crossing at 0.3–1.0 m/s, timed to reach the track when a vehicle at
            // 0.6 m/s would be there, from either side.
            let n = (length / 40.0).ceil() as usize;
            for k in 0..n {
                let x = length * (k as f64 + 1.0) / (n as f64 + 1.0);
                let speed = between(&mut rng, 0.3, 1.0);
                let t_meet = x / 0.6;
                let s = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
                let y0 = -s * speed * t_meet;
                movers.push(SimObstacle {
                    shape: circle(P2::new(x, y0), between(&mut rng, 1.0, 2.0)),
                    velocity: P2::new(0.0, s * speed),
                });
            }
            shapes = scatter(
                &mut rng,
                (length / 25.0) as usize,
                (10.0, length - 10.0),
                20.0,
                3.0,
                &[start, goal],
                6.0,
                &mut |r, c| circle(c, between(r, 0.8, 2.0)),
            );
        }
        Family::HeadOn => {
            let off = between(&mut rng, -1.0, 1.0);
            crafts.push(Craft {
                start: P2::new(length, off),
                heading: PI,
                goal: P2::new(0.0, off),
            });
            shapes = scatter(
                &mut rng,
                (length / 30.0) as usize,
                (15.0, length - 15.0),
                15.0,
                3.0,
                &[start, goal, P2::new(0.0, off), P2::new(length, off)],
                6.0,
                &mut |r, c| circle(c, between(r, 0.8, 2.0)),
            );
        }
        Family::Survey => {
            // Lines ⌈width / spacing⌉ + 1 = `lines` (the width a little under a whole number of
            // spacings); the area to the left of +x from the origin, the start short of it.
            let spacing = between(&mut rng, 8.0, 12.0);
            let lines = 4 + (rng.uniform() * 5.0) as usize;
            let width = spacing * (lines as f64 - 1.0) - 0.5;
            let long = (0.4 * length).max(30.0);
            let s = vpf::planner::Survey {
                corner: vpf::Vec2::ZERO,
                length_m: long as f32,
                width_m: width as f32,
                heading: 0.0,
                spacing_m: spacing as f32,
                radius_m: 2.0,
                speed: None,
            };
            crafts[0].start = P2::new(-between(&mut rng, 5.0, 15.0), -between(&mut rng, 3.0, 10.0));
            let half = 0.5 * width;
            // Rocks over the area and 5 m round it, in a frame centred on the area's midline.
            let mut away: Vec<P2> = s
                .waypoints()
                .map(|l| l.to_vec())
                .unwrap_or_default()
                .iter()
                .map(|w| P2::new(f64::from(w.position().x), f64::from(w.position().y) - half))
                .collect();
            away.push(crafts[0].start.sub(P2::new(0.0, half)));
            let area = (long + 10.0) * (width + 10.0);
            let n = (area / between(&mut rng, 150.0, 250.0)) as usize;
            shapes = scatter(
                &mut rng,
                n,
                (-5.0, long + 5.0),
                half + 5.0,
                2.0,
                &away,
                5.0,
                &mut |r, c| circle(c, between(r, 0.8, 2.5)),
            )
            .iter()
            .map(|sh| match sh {
                SimShape::Circle { center, radius } => {
                    circle(center.add(P2::new(0.0, half)), *radius)
                }
                other => other.clone(),
            })
            .collect();
            survey = Some(s);
        }
        Family::Berth => {
            // The quay's face across the track beyond the goal; the goal `off` m in front of
            // it, `lateral` m off the track.
            let off = hull_m + between(&mut rng, 0.8, 2.8);
            let lateral = between(&mut rng, -10.0, 10.0);
            crafts[0].goal = P2::new(length, lateral);
            let face = length + off;
            let half = between(&mut rng, 30.0, 60.0);
            shapes.push(wall(
                P2::new(face + 2.0, lateral - half),
                P2::new(face + 2.0, lateral + half),
                4.0,
            ));
            // Piers 8–20 m long out of the face, 1.5–4 m beyond the hull either side of the
            // goal: none, one or two.
            let piers = (rng.uniform() * 3.0) as usize;
            let first = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            for k in 0..piers {
                let side = if k == 0 { first } else { -first };
                let y = lateral + side * (hull_m + between(&mut rng, 1.5, 4.0) + 0.75);
                let reach = between(&mut rng, 8.0, 20.0);
                shapes.push(wall(P2::new(face - reach, y), P2::new(face, y), 1.5));
            }
            shapes.extend(clutter_on_the_way(&mut rng, length, start));
        }
        Family::Face => {
            // The face `off` m beyond the goal along `u`, which leans at most 70° off the way
            // in, so the goal's open side faces the start.
            let off = hull_m + between(&mut rng, 0.5, 1.5);
            let lean = between(&mut rng, -1.2, 1.2);
            let (u, along) = (
                P2::new(lean.cos(), lean.sin()),
                P2::new(-lean.sin(), lean.cos()),
            );
            let goal = P2::new(length, between(&mut rng, -10.0, 10.0));
            crafts[0].goal = goal;
            let face = goal.add(u.scale(off));
            match (rng.uniform() * 4.0) as usize {
                0 => {
                    let r = between(&mut rng, 1.0, 8.0);
                    shapes.push(circle(face.add(u.scale(r)), r));
                }
                1 => shapes.push(circle(face.add(u.scale(0.3)), 0.3)),
                k => {
                    let (half, t) = (between(&mut rng, 10.0, 25.0), 1.0);
                    let mid = face.add(u.scale(0.5 * t));
                    shapes.push(wall(
                        mid.sub(along.scale(half)),
                        mid.add(along.scale(half)),
                        t,
                    ));
                    if k == 3 {
                        // A second wall square to it, its face 1–3 m beyond the hull beside
                        // the goal, reaching 8–15 m out of the first.
                        let side = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
                        let beside = hull_m + between(&mut rng, 1.0, 3.0) + 0.5 * t;
                        let at = mid.add(along.scale(side * beside));
                        let reach = between(&mut rng, 8.0, 15.0);
                        shapes.push(wall(at, at.sub(u.scale(reach)), t));
                    }
                }
            }
            shapes.extend(clutter_on_the_way(&mut rng, length, start));
        }
        Family::Formation => {
            let lattice = formation_lattice(hull_m);
            let room = lattice / 4.0;
            formation_m = Some(lattice);
            let n = 3 + (rng.uniform() * 2.0) as usize;
            crafts = (0..n)
                .map(|k| Craft {
                    start: P2::new(-((k / 2) as f64) * lattice, (k % 2) as f64 * lattice),
                    heading: 0.0,
                    goal,
                })
                .collect();
            shapes = scatter(
                &mut rng,
                (length / 20.0) as usize,
                (15.0 * room, length - 15.0 * room),
                20.0 * room,
                6.0 * room,
                &[start, goal],
                10.0 * room,
                &mut |r, c| circle(c, between(r, 0.8, 2.0)),
            );
        }
    }
    let turn = rng.uniform() * 2.0 * PI;
    let mut obstacles: Vec<SimObstacle> = shapes
        .iter()
        .map(|s| SimObstacle::fixed(rotated(s, turn)))
        .collect();
    obstacles.extend(movers.iter().map(|m| SimObstacle {
        shape: rotated(&m.shape, turn),
        velocity: rot(m.velocity, turn),
    }));
    for c in &mut crafts {
        c.start = rot(c.start, turn);
        c.goal = rot(c.goal, turn);
        c.heading += turn;
    }
    // The survey turned with the world (its heading kept within ±180°), its goal the last
    // waypoint.
    let survey = survey.map(|s: vpf::planner::Survey| vpf::planner::Survey {
        corner: rot(P2::new(f64::from(s.corner.x), f64::from(s.corner.y)), turn).to_vpf(),
        heading: (turn - if turn > PI { 2.0 * PI } else { 0.0 }) as f32,
        ..s
    });
    let mut world = World {
        family,
        seed,
        obstacles,
        crafts,
        formation_m,
        survey,
    };
    if let Some(c) = world.crafts.first() {
        if let Some(&last) = world.legs(c).last() {
            world.crafts[0].goal = last;
        }
    }
    world
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn worlds_are_deterministic_and_differ_by_seed() {
        for f in FAMILIES {
            assert_eq!(
                generate(f, 3, 0, 0.2),
                generate(f, 3, 0, 0.2),
                "{}",
                f.name()
            );
            assert_ne!(
                generate(f, 3, 0, 0.2),
                generate(f, 4, 0, 0.2),
                "{}",
                f.name()
            );
            assert_eq!(Family::parse(f.name()), Some(f));
        }
    }

    #[test]
    fn a_formation_is_spaced_for_the_hull_and_the_videoray_worlds_are_unchanged() {
        assert_eq!(formation_lattice(0.2), 4.0);
        assert_eq!(formation_lattice(1.0), 4.0);
        let hull = 2.25;
        for seed in 0..8 {
            // Every family but the formation is drawn the same for any hull.
            for f in FAMILIES.iter().filter(|&&f| f != Family::Formation) {
                assert_eq!(generate(*f, seed, 0, 0.2), generate(*f, seed, 0, hull));
            }
            let w = generate(Family::Formation, seed, 0, hull);
            assert_eq!(w.formation_m, Some(9.0));
            for (i, a) in w.crafts.iter().enumerate() {
                for b in &w.crafts[i + 1..] {
                    // Two hulls, two guard margins (2 × 0.25 m) and more apart.
                    let gap = a.start.sub(b.start).norm() - 2.0 * hull;
                    assert!(gap >= 4.0, "seed {seed}: {gap}");
                }
            }
        }
    }

    #[test]
    fn a_berth_or_face_goal_lies_its_stated_distance_beyond_the_hull_off_the_structure() {
        // (family, metres beyond the hull): the first obstacle is the quay or the face, and
        // nothing else is nearer.
        for (family, lo, hi) in [(Family::Berth, 0.8, 2.8), (Family::Face, 0.5, 1.5)] {
            for hull in [0.2, 2.25] {
                for seed in 0..16 {
                    let w = generate(family, seed, 0, hull);
                    let goal = w.crafts[0].goal;
                    let off = w.obstacles[0].shape.signed_distance(goal);
                    assert!(
                        (hull + lo - 1e-9..=hull + hi + 1e-9).contains(&off),
                        "{family:?}, hull {hull}, seed {seed}: {off} m off"
                    );
                    let nearest = w
                        .obstacles
                        .iter()
                        .map(|o| o.shape.signed_distance(goal))
                        .fold(f64::INFINITY, f64::min);
                    assert!(
                        nearest >= hull + lo - 1e-9,
                        "{family:?}, seed {seed}: {nearest}"
                    );
                }
            }
        }
    }

    #[test]
    fn every_family_has_obstacles_and_a_mission_of_the_stated_length() {
        for f in FAMILIES {
            for seed in 0..4 {
                let w = generate(f, seed, 0, 0.2);
                assert!(
                    !w.obstacles.is_empty() || f == Family::HeadOn,
                    "{}",
                    f.name()
                );
                for c in &w.crafts {
                    let d = c.goal.sub(c.start).norm();
                    assert!((30.0..=330.0).contains(&d), "{} {seed}: {d}", f.name());
                }
            }
        }
    }
}
