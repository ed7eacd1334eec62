//! Seed 001 (Barisic, Vukic, Miskovic: the VPF method as a tool for formation guidance) and the
//! rotor potentials of 001 eq. 2–3, reproduced with the kinematic vehicle of seed 000 eq. 8.
//! Run with `--nocapture` to see the measured numbers.

mod common;
use common::*;
use vpf::field::Shape;
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

fn square_fleet(goal: Vec2) -> Vec<Vehicle> {
    let f = Formation {
        q: 4,
        lattice_m: LATTICE,
        orientation: 0.0,
        attraction: 5.0,
    };
    let starts = [
        Vec2::new(0.0, -9.0),
        Vec2::new(3.0, 8.0),
        Vec2::new(-4.0, 2.0),
        Vec2::new(5.0, -1.0),
    ];
    starts
        .iter()
        .map(|&s| Vehicle::new(fleet_params(), s, 0.0, goal).with_formation(f))
        .collect()
}

/// 001 Fig. 3: four vehicles with a square formation (q = 4, λ = 4 m) in open water assemble
/// into the lattice: every vehicle ends with its nearest neighbour within 10 % of λ, and none
/// ever comes closer than 2 m to another.
#[test]
fn fig3_four_vehicles_form_the_square_lattice_in_open_water() {
    let goal = Vec2::new(120.0, 0.0);
    let mut fleet = square_fleet(goal);
    let history = run_fleet(&mut fleet, &[], 900.0);
    let nn = nearest_neighbour(history.last().unwrap());
    let closest = history
        .iter()
        .map(|ps| min_pair_distance(ps))
        .fold(f32::INFINITY, f32::min);
    println!(
        "open water: nearest neighbours {nn:?} (λ = {LATTICE}), closest approach {closest:.2}"
    );
    for d in &nn {
        assert!(
            (d - LATTICE).abs() <= 0.1 * LATTICE,
            "off the lattice: {nn:?}"
        );
    }
    assert!(closest > 2.0);
}

/// 001 Fig. 5: the same fleet through a cluttered stretch splits around the obstacles (two
/// vehicles pass on each side of the middle obstacle) without touching any, then re-forms.
///
/// Stated tolerance after re-forming: nearest neighbours within 15 % of λ. Vehicles held back
/// by the formation against the obstacles release it for a while (escape.rs) and re-form.
#[test]
fn fig5_formation_splits_around_obstacles_and_reforms() {
    let goal = Vec2::new(120.0, 0.0);
    let obstacles = [
        circle(0, 50.0, 0.0, 3.0),
        circle(1, 62.0, 9.0, 2.5),
        circle(2, 62.0, -8.0, 2.5),
    ];
    let mut fleet = square_fleet(goal);
    let history = run_fleet(&mut fleet, &obstacles, 900.0);
    let world = world_of(&obstacles);
    let clearance = history
        .iter()
        .flatten()
        .map(|p| world.clearance(*p, 0.0))
        .fold(f32::INFINITY, f32::min);
    // Split: at the middle obstacle's abscissa some vehicles are left of it and some right.
    let at_obstacle: Vec<f32> = (0..4)
        .map(|i| {
            history
                .iter()
                .find(|ps| ps[i].x >= 50.0)
                .map(|ps| ps[i].y)
                .unwrap()
        })
        .collect();
    let released: u32 = fleet
        .iter()
        .map(|v| v.planner.escape_counters().formation_released)
        .sum();
    let nn = nearest_neighbour(history.last().unwrap());
    println!(
        "clutter: lateral positions at x = 50: {at_obstacle:?}, min clearance {clearance:.2}, \
         formation releases {released}, final nearest neighbours {nn:?}"
    );
    assert!(at_obstacle.iter().any(|&y| y > 3.0) && at_obstacle.iter().any(|&y| y < -3.0));
    assert!(clearance > 0.0, "touched an obstacle");
    for d in &nn {
        assert!(
            (d - LATTICE).abs() <= 0.15 * LATTICE,
            "did not re-form: {nn:?}"
        );
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
        let rock = Shape::circle(Vec2::new(45.0, 2.5), 3.0).unwrap();
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
