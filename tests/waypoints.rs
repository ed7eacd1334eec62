//! Waypoint missions on the kinematic vehicle of seed 000 eq. 8 (`common`): the order, passing
//! intermediate waypoints at speed, braking onto the last (one at a rock's face too), a leg's
//! own speed, loitering, a survey, a formation flying the same list, and refusals.
//!
//! The route layer's part is played by hand: each period the planner is told the goal is in
//! plain sight (`Planner::set_route(Some(goal))`), which is what the runtime does in open water.

mod common;

use common::{run_fleet, Vehicle};
use vpf::planner::{
    Formation, MissionEnd, MissionError, Mode, StepError, Survey, Waypoint, Waypoints,
};
use vpf::{Params, Vec2};

fn wp(x: f32, y: f32, r: f32) -> Waypoint {
    Waypoint::new(Vec2::new(x, y), r).unwrap()
}

/// One routed period; returns the command.
fn step(v: &mut Vehicle, now_ms: u64) -> vpf::Command {
    v.route_clear = true;
    v.step(now_ms)
}

/// Flies `v` for `seconds`; per period: time s, position, commanded speed, mode, waypoint index.
fn fly(v: &mut Vehicle, seconds: f32) -> Vec<(f32, Vec2, f32, Mode, u8)> {
    let t = v.planner.params().period_s;
    (0..(seconds / t) as u64)
        .map(|k| {
            let cmd = step(v, (k as f32 * t * 1000.0) as u64);
            let i = v.planner.progress(v.p).unwrap().current;
            (k as f32 * t, v.p, cmd.v_set, cmd.mode, i)
        })
        .collect()
}

/// The square's corners, anticlockwise from (40, 0).
fn square() -> Waypoints {
    Waypoints::new(
        &[
            wp(40.0, 0.0, 2.0),
            wp(40.0, 40.0, 2.0),
            wp(0.0, 40.0, 2.0),
            wp(0.0, 5.0, 1.0),
        ],
        MissionEnd::Hold,
    )
    .unwrap()
}

#[test]
fn waypoints_are_flown_in_order_passed_at_speed_and_the_last_is_braked_onto() {
    let params = Params::default();
    let mut v = Vehicle::new(params, Vec2::ZERO, 0.0, Vec2::ZERO);
    v.planner.set_waypoints(&square(), None).unwrap();
    let p0 = v.planner.progress(v.p).unwrap();
    assert_eq!((p0.current, p0.count), (0, 4));
    assert!((p0.to_go_m - 155.0).abs() < 1e-3, "{p0:?}");

    let trace = fly(&mut v, 400.0);
    // The index only ever goes up, one at a time, and each advance happens within that
    // waypoint's radius.
    let wps = square();
    let mut seen = 0u8;
    for (t, p, _, _, i) in &trace {
        assert!(*i == seen || *i == seen + 1, "jumped to {i} at {t}");
        if *i == seen + 1 {
            let w = wps.get(usize::from(seen)).unwrap();
            assert!(
                (*p - w.position()).norm() <= w.radius_m() + 0.2,
                "advanced at {p:?}"
            );
            seen = *i;
        }
    }
    assert_eq!(seen, 4, "every waypoint reached");
    // Intermediate waypoints are passed at speed: the commanded speed where the index moves
    // on (1 → 2 and 2 → 3) is near v_max, not a stop.
    let passing: Vec<f32> = trace
        .windows(2)
        .filter(|w| w[1].4 == w[0].4 + 1 && w[1].4 < 4)
        .map(|w| w[0].2)
        .collect();
    assert_eq!(passing.len(), 3);
    assert!(
        passing.iter().all(|s| *s > 0.8 * params.v_max),
        "passing speeds {passing:?}"
    );
    // The last one is braked onto and held: inside its 1 m radius, stopped, mode Arrived.
    let (_, end, speed, mode, _) = *trace.last().unwrap();
    assert!((end - Vec2::new(0.0, 5.0)).norm() < 1.0, "{end:?}");
    assert!(speed < 0.05, "{speed}");
    assert_eq!(mode, Mode::Arrived);
    let done = v.planner.progress(v.p).unwrap();
    assert_eq!((done.current, done.count, done.to_go_m), (4, 4, 0.0));
    // At cruise: the 155 m took little more than 155 s at 1 m/s (turns and the final brake).
    let arrived = trace.iter().find(|x| x.4 == 4).unwrap().0;
    assert!(arrived < 200.0, "arrived after {arrived} s");
}

#[test]
fn a_goal_at_a_rocks_face_is_reached_and_held() {
    // Ge and Cui's "goal non-reachable with obstacles nearby": 0.1 m off a rock's face (where
    // a sonar's cells put a face half a metre off) the rock's stator outpulls the goal-point,
    // and with the rock in the field to the end the vehicle stopped 2 m short
    // (`crate::planner::vpf`, "The final approach"). Within four arrival radii the field is
    // the goal-point's alone; the kinematic vehicle has no guard, so this also shows that the
    // field does not drive it at the rock.
    let goal = Vec2::new(40.0, 0.0);
    let rock = common::circle(1, 44.1, 0.0, 4.0);
    let mut v = Vehicle::new(Params::default(), Vec2::new(0.0, 3.0), 0.0, goal);
    v.world = common::world_of(&[rock]);
    let trace = fly(&mut v, 120.0);
    let r = Params::default().arrival_radius_m;
    let first = trace.iter().position(|s| (s.1 - goal).norm() <= r);
    let first = first.expect("arrives");
    assert!(trace[first].0 < 60.0, "arrived at {} s", trace[first].0);
    // Held: within the radius for the rest of the run, never touching the rock.
    for s in &trace[first..] {
        assert!((s.1 - goal).norm() <= r, "{s:?}");
    }
    for s in &trace {
        assert!(v.world.clearance(s.1, 0.0) > 0.0, "{s:?}");
    }
}

#[test]
fn a_legs_own_speed_bounds_the_leg_to_it() {
    let slow = wp(40.0, 0.0, 2.0).with_speed(Some(0.4)).unwrap();
    let route = Waypoints::new(&[slow, wp(80.0, 0.0, 2.0)], MissionEnd::Hold).unwrap();
    let mut v = Vehicle::new(Params::default(), Vec2::ZERO, 0.0, Vec2::ZERO);
    v.planner.set_waypoints(&route, None).unwrap();
    let trace = fly(&mut v, 200.0);
    let first = trace.iter().filter(|x| x.4 == 0);
    assert!(first.clone().all(|x| x.2 <= 0.4 + 1e-6));
    assert!(first.clone().any(|x| x.2 > 0.39));
    // The second leg has none of its own: v_max.
    assert!(trace.iter().filter(|x| x.4 == 1).any(|x| x.2 > 0.95));
}

#[test]
fn loiter_circles_the_last_waypoint_at_its_radius() {
    let end = MissionEnd::Loiter {
        radius_m: 12.0,
        clockwise: false,
    };
    let route = Waypoints::new(&[wp(30.0, 0.0, 2.0), wp(60.0, 20.0, 2.0)], end).unwrap();
    let mut v = Vehicle::new(Params::default(), Vec2::ZERO, 0.0, Vec2::ZERO);
    v.planner.set_waypoints(&route, None).unwrap();
    let trace = fly(&mut v, 600.0);
    let c = Vec2::new(60.0, 20.0);
    // The last 200 s: on the circle, moving, mode Loiter, going round anticlockwise.
    let tail: Vec<_> = trace.iter().filter(|x| x.0 >= 400.0).collect();
    for (t, p, speed, mode, i) in &tail {
        let d = (*p - c).norm();
        assert!((d - 12.0).abs() < 1.5, "off the circle at {t}: {d}");
        assert!(*speed > 0.5, "{speed}");
        assert_eq!((*mode, *i), (Mode::Loiter, 2));
    }
    let turned: f32 = tail
        .windows(2)
        .map(|w| vpf::math::wrap_angle((w[1].1 - c).angle() - (w[0].1 - c).angle()))
        .sum();
    // 200 s at ≈ 1 m/s on a 75 m circumference: more than two turns, anticlockwise.
    assert!(turned > 2.0 * vpf::math::TAU, "turned {turned} rad");
    // And clockwise when asked.
    let cw = MissionEnd::Loiter {
        radius_m: 12.0,
        clockwise: true,
    };
    let route = Waypoints::new(&[wp(30.0, 0.0, 2.0)], cw).unwrap();
    let mut v = Vehicle::new(Params::default(), Vec2::ZERO, 0.0, Vec2::ZERO);
    v.planner.set_waypoints(&route, None).unwrap();
    let trace = fly(&mut v, 300.0);
    let c = Vec2::new(30.0, 0.0);
    let turned: f32 = trace
        .iter()
        .filter(|x| x.0 >= 150.0)
        .collect::<Vec<_>>()
        .windows(2)
        .map(|w| vpf::math::wrap_angle((w[1].1 - c).angle() - (w[0].1 - c).angle()))
        .sum();
    assert!(turned < -vpf::math::TAU, "turned {turned} rad");
}

#[test]
fn a_survey_is_mowed_line_by_line() {
    let s = Survey {
        corner: Vec2::new(10.0, -20.0),
        length_m: 50.0,
        width_m: 30.0,
        heading: 0.0,
        spacing_m: 10.0,
        radius_m: 2.0,
        speed: None,
    };
    let route = Waypoints::survey(&s, MissionEnd::Hold).unwrap();
    assert_eq!(route.len(), 8);
    let mut v = Vehicle::new(Params::default(), Vec2::ZERO, 0.0, Vec2::ZERO);
    v.planner.set_waypoints(&route, None).unwrap();
    let trace = fly(&mut v, 500.0);
    assert_eq!(v.planner.progress(v.p).unwrap().current, 8, "finished");
    // On each line (between its two waypoints) the vehicle stays within 3 m of it.
    for line in 0..4u8 {
        let y = -20.0 + 10.0 * f32::from(line);
        for x in trace.iter().filter(|x| x.4 == 2 * line + 1) {
            assert!((x.1.y - y).abs() < 3.0, "line {line}: {:?}", x.1);
        }
    }
}

#[test]
fn a_formation_flies_the_same_waypoints_and_keeps_its_shape() {
    // Seed 001 Fig. 3's square fleet (q = 4, λ = 4 m), now through three legs.
    let f = Formation {
        q: 4,
        lattice_m: 4.0,
        orientation: 0.0,
        attraction: 5.0,
    };
    let route = Waypoints::new(
        &[wp(60.0, 0.0, 2.0), wp(60.0, 60.0, 2.0), wp(0.0, 60.0, 2.0)],
        MissionEnd::Hold,
    )
    .unwrap();
    let starts = [(0.0, 0.0), (-4.0, 1.0), (1.0, -4.0), (-4.0, -4.0)];
    let mut fleet: Vec<Vehicle> = starts
        .iter()
        .map(|&(x, y)| {
            let mut v = Vehicle::new(Params::default(), Vec2::new(x, y), 0.0, Vec2::ZERO);
            v.planner.set_waypoints(&route, Some(f)).unwrap();
            v.route_clear = true;
            v
        })
        .collect();
    let history = run_fleet(&mut fleet, &[], 500.0);
    // Everyone went through every waypoint in order and ended in a square round the last:
    // the fleet judges arrival at its centre, so all turned together.
    for v in &fleet {
        let p = v.planner.progress(v.p).unwrap();
        assert_eq!(p.current, 3, "{p:?}");
        assert!((v.p - Vec2::new(0.0, 60.0)).norm() < 4.0, "{:?}", v.p);
    }
    let arrived = history
        .iter()
        .position(|ps| ps.iter().all(|p| (*p - Vec2::new(0.0, 60.0)).norm() < 4.0))
        .unwrap();
    // 180 m of legs at 1 m/s: at cruise, not dragged.
    assert!(
        arrived as f32 * 0.1 < 260.0,
        "together after {} s",
        arrived as f32 * 0.1
    );
    // In formation on the way: over the second leg's middle (x = 60, y 20..40) each vehicle's
    // nearest neighbour is within 25 % of λ, and nobody comes closer than half of it.
    let mid: Vec<&Vec<Vec2>> = history
        .iter()
        .filter(|ps| ps.iter().all(|p| p.x > 50.0 && p.y > 20.0 && p.y < 40.0))
        .collect();
    assert!(mid.len() > 50, "{} periods on the second leg", mid.len());
    for ps in mid {
        for d in common::nearest_neighbour(ps) {
            assert!((d - 4.0).abs() < 1.0, "nearest neighbour at {d} m");
        }
        assert!(common::min_pair_distance(ps) > 2.0);
    }
}

#[test]
fn bad_missions_are_refused_and_the_old_one_kept() {
    let mut v = Vehicle::new(Params::default(), Vec2::ZERO, 0.0, Vec2::new(5.0, 0.0));
    let bad = Formation {
        q: 5,
        lattice_m: 4.0,
        orientation: 0.0,
        attraction: 5.0,
    };
    assert!(matches!(
        v.planner.set_waypoints(&square(), Some(bad)),
        Err(StepError::BadFormation(_))
    ));
    assert_eq!(v.planner.mission().unwrap().goal, Vec2::new(5.0, 0.0));
    assert_eq!(v.planner.progress(v.p).unwrap().count, 1);
    assert_eq!(v.planner.counters.bad_mission, 1);
    assert_eq!(
        Waypoints::new(&[], MissionEnd::Hold),
        Err(MissionError::Empty)
    );
    // A single goal is the one-waypoint case: hold at it, radius from the parameters.
    let w = v.planner.waypoints().unwrap();
    assert_eq!((w.len(), w.end()), (1, MissionEnd::Hold));
    assert_eq!(w.get(0).unwrap().radius_m(), 0.0);
}
