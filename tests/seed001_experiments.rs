//! Seed 001 (Barisic, Vukic, Miskovic: the VPF method as a tool for formation guidance) and the
//! rotor potentials of 001 eq. 2–3, reproduced with the kinematic vehicle of seed 000 eq. 8.
//! Run with `--nocapture` to see the measured numbers.

mod common;
use common::lattice::{groups, lattice_error};
use common::*;
use vpf::math::XorShift32;
use vpf::planner::Formation;
use vpf::{Bounding, Obstacle, Origin, Params, Vec2};

const LATTICE: f32 = 4.0;

fn fleet_params() -> Params {
    // Goal 120 m away: σ and A⁻ sized so the goal-point reaches the start (000 eq. 13).
    Params {
        sigma_m: 80.0,
        a_minus: 100.0,
        ..Params::default()
    }
}

fn formation(q: u8) -> Formation {
    Formation {
        q,
        lattice_m: LATTICE,
        orientation: 0.0,
        attraction: 5.0,
    }
}

fn fleet(params: Params, f: Option<Formation>, starts: &[Vec2], goal: Vec2) -> Vec<Vehicle> {
    starts
        .iter()
        .map(|&s| {
            let v = Vehicle::new(params, s, 0.0, goal);
            match f {
                Some(f) => v.with_formation(f),
                None => v,
            }
        })
        .collect()
}

const SQUARE_STARTS: [Vec2; 4] = [
    Vec2::new(0.0, -9.0),
    Vec2::new(3.0, 8.0),
    Vec2::new(-4.0, 2.0),
    Vec2::new(5.0, -1.0),
];

/// What a fleet run measured about its formation (`common::lattice`).
#[derive(Debug)]
struct Shape {
    /// Worst lattice-shape error (÷ λ) over the stretch measured.
    worst_error: f32,
    /// Most groups (1: one connected formation) over the stretch measured.
    most_groups: usize,
}

/// Formation shape over `history[from..to]` (steps).
fn shape(f: &Formation, history: &[Vec<Vec2>], from: usize, to: usize) -> Shape {
    let stretch = &history[from..to];
    Shape {
        worst_error: stretch
            .iter()
            .map(|ps| lattice_error(f, ps))
            .fold(0.0, f32::max),
        most_groups: stretch.iter().map(|ps| groups(f, ps)).max().unwrap_or(0),
    }
}

/// The step at which the fleet's centroid first passes abscissa `x`.
fn step_at_x(history: &[Vec<Vec2>], x: f32) -> usize {
    history
        .iter()
        .position(|ps| ps.iter().map(|p| p.x).sum::<f32>() / ps.len() as f32 >= x)
        .unwrap_or(history.len())
}

/// A lattice patch of `n` nodes for q (compact: the first nodes of a spiral round the origin)
/// and a deterministic jitter of up to `jitter` m on each.
fn lattice_patch(q: u8, n: usize, jitter: f32, seed: u32) -> Vec<Vec2> {
    let l = LATTICE;
    let nodes: Vec<Vec2> = match q {
        // A 2 × 2 square, then the next ring.
        4 => [
            (0, 0),
            (1, 0),
            (0, 1),
            (1, 1),
            (-1, 0),
            (-1, 1),
            (0, 2),
            (1, 2),
        ]
        .iter()
        .map(|&(i, j)| Vec2::new(i as f32 * l, j as f32 * l))
        .collect(),
        // A centre and its hexagon.
        6 => std::iter::once(Vec2::ZERO)
            .chain((0..6).map(|k| Vec2::from_angle(k as f32 * std::f32::consts::FRAC_PI_3) * l))
            .collect(),
        // One hexagonal cell of the honeycomb: its six vertices (bonds along θ₀ + 2πk/3).
        _ => (0..6)
            .map(|k| Vec2::from_angle(k as f32 * std::f32::consts::FRAC_PI_3) * l)
            .collect(),
    };
    let mut rng = XorShift32::new(seed);
    nodes
        .into_iter()
        .take(n)
        .map(|p| {
            let a = unit(&mut rng) * std::f32::consts::TAU;
            p + Vec2::from_angle(a) * (jitter * unit(&mut rng))
        })
        .collect()
}

/// Bound on the lattice-shape error of a formed fleet, ÷ λ: every vehicle within 10 % of λ of
/// its node.
const FORMED: f32 = 0.1;

/// Equilibrium for q = 3, 4 and 6 (001 §3.2): a fleet started within 0.05·λ of the lattice —
/// a honeycomb cell of six, a 2 × 2 square, a hexagon of six round a seventh — stays within
/// [`FORMED`] of it, as one group, while it transits open water towards a goal 100 m away.
#[test]
fn every_lattice_is_an_equilibrium_in_transit() {
    let goal = Vec2::new(100.0, 10.0);
    for (q, n) in [(3u8, 6usize), (4, 4), (6, 7)] {
        let f = formation(q);
        let near = lattice_patch(q, n, 0.05 * LATTICE, 7);
        let mut vehicles = fleet(fleet_params(), Some(f), &near, goal);
        let history = run_fleet(&mut vehicles, &[], 150.0);
        let held = shape(&f, &history, 0, history.len());
        let moved = (centroid(history.last().unwrap()) - centroid(&near)).norm();
        println!(
            "q = {q}, {n} vehicles from near the lattice: worst error {:.3} λ, most groups {}, \
             moved {moved:.1} m",
            held.worst_error, held.most_groups
        );
        assert!(moved > 25.0, "q = {q}: the fleet did not transit");
        assert!(
            held.worst_error < FORMED,
            "q = {q}: left the lattice: {held:?}"
        );
        assert_eq!(held.most_groups, 1, "q = {q}: split");
    }
}

/// Scattered starts (001 §3.2): ten fleets per q and size, started anywhere in a square of
/// 5·λ (1.5 m apart), fly 200 s towards a goal 100 m away; a fleet has assembled when its
/// lattice error is within [`FORMED`] and it is one group over the last second.
///
/// Table 1 does not assemble every scattered fleet, and this test states how often it does
/// (measured, 200 s): three vehicles 10/10 for q = 4 and 6, 8/10 for q = 3; four vehicles 8/10
/// for q = 4 and 6, 3/10 for q = 3. The failures are Table 1's: a vehicle with neighbours
/// listens only to them, so two sub-formations that have each assembled fly side by side
/// (two groups); and where a vehicle's neighbours propose nodes of different lattices, the
/// mean of Table 1 step 2 can sit where the vehicle already is (one group, off the lattice) —
/// with q = 3 more often, since two neighbours 60° apart fit neither sublattice. The bounds
/// below are one fleet under the measured counts.
#[test]
fn scattered_fleets_assemble_as_often_as_table_1_allows() {
    let goal = Vec2::new(100.0, 10.0);
    for (q, n, at_least) in [
        (3u8, 3usize, 7),
        (4, 3, 9),
        (6, 3, 9),
        (3, 4, 2),
        (4, 4, 7),
        (6, 4, 7),
    ] {
        let f = formation(q);
        let mut assembled = 0;
        let mut worst_start = f32::INFINITY;
        for seed in 1..=10u32 {
            let mut rng = XorShift32::new(seed * 7919 + q as u32);
            let mut starts: Vec<Vec2> = Vec::new();
            while starts.len() < n {
                let p = Vec2::new(unit(&mut rng), unit(&mut rng)) * (5.0 * LATTICE);
                if starts.iter().all(|o| (*o - p).norm() > 1.5) {
                    starts.push(p);
                }
            }
            worst_start = worst_start.min(lattice_error(&f, &starts));
            let mut vehicles = fleet(fleet_params(), Some(f), &starts, goal);
            let history = run_fleet(&mut vehicles, &[], 200.0);
            let end = shape(&f, &history, history.len() - 10, history.len());
            if end.worst_error < FORMED && end.most_groups == 1 {
                assembled += 1;
            }
        }
        println!("q = {q}, {n} vehicles scattered: {assembled}/10 assembled");
        assert!(worst_start > FORMED, "q = {q}: a start was already formed");
        assert!(
            assembled >= at_least,
            "q = {q}, {n} vehicles: {assembled}/10"
        );
    }
}

/// A uniform number in [0, 1).
fn unit(rng: &mut XorShift32) -> f32 {
    (rng.next_u32() >> 8) as f32 / (1u32 << 24) as f32
}

fn centroid(ps: &[Vec2]) -> Vec2 {
    ps.iter().fold(Vec2::ZERO, |s, p| s + *p) * (1.0 / ps.len() as f32)
}

/// 001 Fig. 3: four vehicles with a square formation (q = 4, λ = 4 m) in open water assemble
/// into the lattice and keep it **while moving**: from 60 s on (assembled) until the fleet's
/// centroid is 30 m from the goal, the lattice-shape error stays within [`FORMED`] and the
/// fleet is one group. None ever comes closer than 2 m to another. The same fleet with the
/// formation off (each vehicle flies to the goal on its own, seeing the others as obstacles)
/// fails these assertions.
///
/// (Within about 25 m of the goal the goal's pull falls under the hold of the leader's well —
/// the formation stalls the fleet, `fig5_...` below — and the formation release of
/// `escape.rs` takes it in. The lattice Table 1 holds is any connected patch of nodes: an L or
/// a line of four along a lattice axis is as much an equilibrium as a 2 × 2 square, and this
/// fleet flies as an L.)
#[test]
fn fig3_four_vehicles_form_the_square_lattice_in_open_water() {
    let goal = Vec2::new(120.0, 0.0);
    let f = formation(4);
    let run = |formed: bool| {
        let mut fleet = fleet(fleet_params(), formed.then_some(f), &SQUARE_STARTS, goal);
        let history = run_fleet(&mut fleet, &[], 600.0);
        let from = (60.0 / fleet_params().period_s) as usize;
        let to = step_at_x(&history, 90.0);
        let closest = history
            .iter()
            .map(|ps| min_pair_distance(ps))
            .fold(f32::INFINITY, f32::min);
        (shape(&f, &history, from, to), closest, to)
    };
    let (on, closest, to) = run(true);
    let (off, _, _) = run(false);
    println!(
        "open water, formation on (60 s to {:.0} s): {on:?}, closest approach {closest:.2} m",
        to as f32 * 0.1
    );
    println!("open water, formation off: {off:?}");
    let holds = |s: &Shape| s.worst_error < FORMED && s.most_groups == 1;
    assert!(holds(&on), "formation not kept in transit: {on:?}");
    assert!(closest > 2.0);
    assert!(
        !holds(&off),
        "the control run without formation passed: {off:?}"
    );
}

/// A severely cluttered stretch (001 Fig. 5: "severely cluttered mission theater"): twelve
/// circles of 1.5–3 m radius between x = 40 and x = 80, across the fleet's track.
fn severe_clutter() -> Vec<vpf::Obstacle> {
    vec![
        circle(0, 45.0, 0.0, 3.0),
        circle(1, 47.0, 11.0, 2.0),
        circle(2, 46.0, -10.0, 2.5),
        circle(3, 55.0, 6.0, 2.0),
        circle(4, 56.0, -5.0, 2.5),
        circle(5, 54.0, 17.0, 1.5),
        circle(6, 57.0, -16.0, 2.0),
        circle(7, 65.0, 0.5, 2.5),
        circle(8, 66.0, 11.0, 2.0),
        circle(9, 67.0, -10.0, 2.0),
        circle(10, 75.0, 6.0, 3.0),
        circle(11, 76.0, -6.0, 2.0),
    ]
}

/// 001 Fig. 5: the square fleet, formed before the clutter, splits around the obstacles
/// (vehicles pass on both sides of the first one) without touching any, and re-forms: after
/// the clutter (centroid past x = 80 m) it is within [`FORMED`] of the lattice, one group, by
/// the time the centroid is at x = 90 m, and stays so to x = 95 m.
///
/// **What re-forms it, and the release.** Re-formation is the paper's own mechanism: once past
/// the obstacles each vehicle's virtual leader (Table 1) pulls it back onto its neighbours'
/// nodes. The run as 001 has it — `max_ghosts = 0`: no ghost goal-points and no formation
/// release, rotors on — re-forms the same way, and then stalls: within about 25 m of the goal
/// the goal's pull is weaker than the hold of the leaders' wells (each centred where its
/// vehicle is in a finished formation), and the fleet stops short. Our addition (`escape.rs`),
/// releasing the formation for `ghost_timeout_s` when it holds a vehicle away from the goal,
/// takes the fleet in; it re-forms on arrival. Both behaviours are asserted.
#[test]
fn fig5_formation_splits_around_obstacles_and_reforms() {
    let goal = Vec2::new(120.0, 0.0);
    let f = formation(4);
    let obstacles = severe_clutter();
    let world = world_of(&obstacles);
    let run = |params: Params| {
        let mut fleet = fleet(params, Some(f), &SQUARE_STARTS, goal);
        let history = run_fleet(&mut fleet, &obstacles, 900.0);
        let clearance = history
            .iter()
            .flatten()
            .map(|p| world.clearance(*p, 0.0))
            .fold(f32::INFINITY, f32::min);
        let sides: Vec<f32> = (0..4)
            .map(|i| {
                history
                    .iter()
                    .find(|ps| ps[i].x >= 45.0)
                    .map_or(f32::NAN, |ps| ps[i].y)
            })
            .collect();
        let released: u32 = fleet
            .iter()
            .map(|v| v.planner.escape_counters().formation_released)
            .sum();
        let before = shape(
            &f,
            &history,
            step_at_x(&history, 20.0),
            step_at_x(&history, 35.0),
        );
        let after = step_at_x(&history, 80.0);
        // Re-formed from the step after the last one, before x = 95 m, that was not formed.
        let end = step_at_x(&history, 95.0);
        let formed =
            |k: usize| lattice_error(&f, &history[k]) < FORMED && groups(&f, &history[k]) == 1;
        let reformed = (after < end).then(|| {
            let k = (after..end)
                .rev()
                .find(|&k| !formed(k))
                .map_or(after, |k| k + 1);
            centroid(&history[k.min(end)]).x
        });
        let split = shape(&f, &history, step_at_x(&history, 40.0), after).most_groups;
        let short = (centroid(history.last().unwrap()) - goal).norm();
        (sides, clearance, released, before, split, reformed, short)
    };
    for (name, params) in [
        ("with the release", fleet_params()),
        (
            "as 001 (no release)",
            Params {
                max_ghosts: 0,
                ..fleet_params()
            },
        ),
    ] {
        let (sides, clearance, released, before, split, reformed, short) = run(params);
        println!(
            "clutter, {name}: formed before {before:?}; {split} groups in the clutter; lateral \
             positions at x = 45: {sides:?}; min clearance {clearance:.2} m; re-formed for good \
             (to x = 95 m) at centroid x = {reformed:?} m; formation releases {released}; centroid \
             {short:.1} m from the goal at the end"
        );
        assert!(
            before.worst_error < FORMED && before.most_groups == 1,
            "{name}: not formed before"
        );
        assert!(split > 1, "{name}: did not split");
        assert!(sides.iter().any(|&y| y > 3.0) && sides.iter().any(|&y| y < -3.0));
        assert!(clearance > 0.0, "{name}: touched an obstacle");
        let x = reformed.expect("the fleet got past the clutter");
        assert!(x < 90.0, "{name}: re-formed for good only at x = {x}");
        if params.max_ghosts == 0 {
            assert_eq!(released, 0);
            assert!(short > 15.0, "{name}: expected to stall short of the goal");
        } else {
            assert!(released > 0);
            assert!(short < LATTICE * 2.0, "{name}: not brought in: {short}");
        }
    }
}

/// 001 §3.1: cruising at v_max with a goal force far above F_max (the "wind-up" case), past an
/// obstacle 2.5 m off the track: split bounding starts the turn earlier and loses no speed,
/// where plain bounding turns later and dips below v_max.
///
/// (Head-on, the opposite holds: with the force pointing backwards split bounding gives braking
/// the priority, as the paper specifies, and slows the vehicle more than plain bounding.)
#[test]
fn split_bounding_turns_earlier_and_keeps_speed() {
    let measure = |bounding| {
        let p = Params {
            bounding,
            mu: 0.1,
            a_minus: 2000.0,
            sigma_m: 60.0,
            a_rotor: 0.0,
            max_ghosts: 0,
            ..Params::default()
        };
        let mut v = Vehicle::new(p, Vec2::ZERO, 0.0, Vec2::new(80.0, 0.0));
        let rock = vpf::field::Shape::circle(Vec2::new(45.0, 2.5), 3.0).unwrap();
        v.world = world_of(&[Obstacle::new(0, rock, 30.0, Origin::Charted, 0).unwrap()]);
        let tr = run(&mut v, 200.0);
        let turn_x = tr.positions.iter().find(|q| q.y.abs() > 0.3).unwrap().x;
        let from = tr.positions.iter().position(|q| q.x > 20.0).unwrap();
        let to = tr.positions.iter().position(|q| q.x > 60.0).unwrap();
        assert_eq!(
            tr.speeds[from], 1.0,
            "not cruising at v_max before the obstacle"
        );
        let v_min = tr.speeds[from..to]
            .iter()
            .copied()
            .fold(f32::INFINITY, f32::min);
        (turn_x, v_min, tr.min_clearance)
    };
    let (plain_turn, plain_v, plain_clear) = measure(Bounding::Plain);
    let (split_turn, split_v, split_clear) = measure(Bounding::Split);
    println!(
        "plain: turn at x = {plain_turn:.2} m, min speed {plain_v:.3} m/s, clearance {plain_clear:.2} m\n\
         split: turn at x = {split_turn:.2} m, min speed {split_v:.3} m/s, clearance {split_clear:.2} m"
    );
    assert!(split_turn < plain_turn - 0.1, "split did not turn earlier");
    assert!(split_v > plain_v + 0.02, "split lost as much speed");
    assert!(split_clear > plain_clear);
}

/// Rotor potentials (001 eq. 2–3): a U-shaped obstacle opening towards the start. The stator
/// field alone holds the vehicle at the bottom of the U; with rotors (and no ghost goal-points)
/// it circulates out along a side wall and reaches the goal.
#[test]
fn rotor_potentials_escape_a_u_shaped_trap() {
    let u = [
        rect(0, 30.0, 0.0, 0.5, 6.5, 0.0),
        rect(1, 26.0, 6.0, 4.0, 0.5, 0.0),
        rect(2, 26.0, -6.0, 4.0, 0.5, 0.0),
    ];
    let goal = Vec2::new(50.0, 0.0);
    let run_with = |a_rotor| {
        let p = Params {
            a_rotor,
            max_ghosts: 0,
            ..Params::default()
        };
        let mut v = Vehicle::new(p, Vec2::new(0.0, 0.5), 0.0, goal);
        v.world = world_of(&u);
        let tr = run(&mut v, 600.0);
        ((tr.final_position() - goal).norm(), tr.min_clearance)
    };
    let (stator_err, _) = run_with(0.0);
    let (rotor_err, rotor_clear) = run_with(Params::default().a_rotor);
    println!("stator only: {stator_err:.1} m from the goal; with rotors: {rotor_err:.2} m, clearance {rotor_clear:.2} m");
    assert!(
        stator_err > 15.0,
        "the stator field was expected to trap the vehicle"
    );
    assert!(rotor_err < Params::default().arrival_radius_m);
    assert!(rotor_clear > 0.0);
}
