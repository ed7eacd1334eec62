//! Property tests of the planner's promises over random worlds, states and parameters: it never
//! returns a non-finite command, always respects F_max and v_max, and refuses bad input without
//! changing its state.

use proptest::prelude::*;
use vpf::field::Shape;
use vpf::planner::{Formation, MAX_GHOSTS};
use vpf::world::{MAX_AGENTS, MAX_OBSTACLES};
use vpf::{Agent, Bounding, Mission, NavState, Obstacle, Origin, Params, Planner, Vec2, World};

fn coord() -> impl Strategy<Value = f32> {
    -60.0f32..60.0
}

fn shape() -> impl Strategy<Value = Shape> {
    prop_oneof![
        (coord(), coord(), 0.1f32..8.0).prop_map(|(x, y, r)| Shape::circle(Vec2::new(x, y), r)),
        (coord(), coord(), 0.1f32..6.0, 0.1f32..6.0, -4.0f32..4.0)
            .prop_map(|(x, y, a, b, t)| Shape::rectangle(Vec2::new(x, y), Vec2::new(a, b), t)),
        (coord(), coord(), 0.1f32..6.0, 0.1f32..6.0, -4.0f32..4.0)
            .prop_map(|(x, y, a, b, t)| Shape::ellipse(Vec2::new(x, y), Vec2::new(a, b), t)),
        (coord(), coord(), 0.5f32..6.0, 3usize..8).prop_map(|(x, y, r, n)| {
            let pts: Vec<Vec2> = (0..n)
                .map(|i| {
                    Vec2::new(x, y)
                        + Vec2::from_angle(i as f32 * std::f32::consts::TAU / n as f32) * r
                })
                .collect();
            Shape::polygon(&pts)
        }),
    ]
    .prop_filter_map("valid shape", |s| s.ok())
}

fn world() -> impl Strategy<Value = World> {
    (
        prop::collection::vec((shape(), 0.01f32..50.0), 0..=MAX_OBSTACLES),
        prop::collection::vec(
            (coord(), coord(), -1.0f32..1.0, -1.0f32..1.0),
            0..=MAX_AGENTS,
        ),
    )
        .prop_map(|(obs, agents)| {
            let mut w = World::new();
            for (i, (s, a)) in obs.into_iter().enumerate() {
                let o = Obstacle::new(i as u16, s, a, Origin::Sensed, 0).unwrap();
                w.upsert_obstacle(o).unwrap();
            }
            for (i, (x, y, vx, vy)) in agents.into_iter().enumerate() {
                let a = Agent::new(i as u16, Vec2::new(x, y), Vec2::new(vx, vy), 0).unwrap();
                w.upsert_agent(a).unwrap();
            }
            w
        })
}

fn params() -> impl Strategy<Value = Params> {
    (
        (
            0.02f32..1.0,
            0.01f32..2.0,
            4u8..=32,
            0.0f32..2.0,
            0.01f32..5.0,
            0.05f32..5.0,
        ),
        (
            0.01f32..20.0,
            0.0f32..20.0,
            0.01f32..2000.0,
            1.0f32..200.0,
            any::<bool>(),
        ),
        (0u8..=MAX_GHOSTS as u8, any::<u32>()),
    )
        .prop_map(
            |((t, eps, n, mu, fmax, vmax), (ap, ar, am, sig, split), (g, seed))| Params {
                period_s: t,
                epsilon_m: eps,
                n_gamma: n,
                mu,
                f_max: fmax,
                v_max: vmax,
                a_plus: ap,
                a_rotor: ar,
                a_minus: am,
                sigma_m: sig,
                bounding: if split {
                    Bounding::Split
                } else {
                    Bounding::Plain
                },
                stall_time_s: 0.5,
                max_ghosts: g,
                seed,
                ..Params::default()
            },
        )
}

fn nav() -> impl Strategy<Value = NavState> {
    (coord(), coord(), -10.0f32..10.0, -3.0f32..3.0, -3.0f32..3.0).prop_map(|(x, y, h, vx, vy)| {
        NavState {
            position: Vec2::new(x, y),
            heading: h,
            velocity: Vec2::new(vx, vy),
        }
    })
}

fn mission() -> impl Strategy<Value = Mission> {
    (
        coord(),
        coord(),
        prop::option::of((prop_oneof![Just(3u8), Just(4), Just(6)], 0.5f32..10.0)),
    )
        .prop_map(|(x, y, f)| Mission {
            goal: Vec2::new(x, y),
            formation: f.map(|(q, l)| Formation {
                q,
                lattice_m: l,
                orientation: 0.3,
                attraction: 5.0,
            }),
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// Over 40 periods from random states: finite, bounded commands, whatever the world.
    #[test]
    fn commands_are_finite_and_bounded(p in params(), w in world(), n in nav(), m in mission()) {
        let mut planner = Planner::new(p).unwrap();
        planner.set_mission(m).unwrap();
        let mut nav = n;
        for k in 0..40u64 {
            let cmd = planner.step(k * 100, &nav, &w).unwrap();
            prop_assert!(cmd.is_finite(), "{cmd:?}");
            prop_assert!(cmd.v_set <= p.v_max * (1.0 + 1e-5));
            prop_assert!(cmd.velocity.norm() <= p.v_max * (1.0 + 1e-5));
            prop_assert!(cmd.force.norm() <= p.f_max * (1.0 + 1e-5), "{:?}", cmd.force);
            prop_assert!(cmd.psi_set.abs() <= std::f32::consts::PI + 1e-6);
            prop_assert!(cmd.ghost_depth as usize <= p.max_ghosts as usize);
            // Move kinematically (000 eq. 8) so the next period sees a new state.
            nav.position += cmd.velocity * p.period_s;
            nav.velocity = cmd.velocity;
        }
    }

    /// A non-finite or absurd number anywhere in the input is refused, and the planner goes on
    /// exactly as if the bad input had never come.
    #[test]
    fn bad_input_is_refused_and_changes_nothing(
        w in world(), n in nav(), m in mission(), which in 0usize..6, bad in prop_oneof![
            Just(f32::NAN), Just(f32::INFINITY), Just(f32::NEG_INFINITY), Just(1e9f32)]
    ) {
        let mut planner = Planner::new(Params::default()).unwrap();
        planner.set_mission(m).unwrap();
        planner.step(0, &n, &w).unwrap();
        let reference = planner.clone();

        let mut broken = n;
        match which {
            0 => broken.position.x = bad,
            1 => broken.position.y = bad,
            2 => broken.velocity.x = bad,
            3 => broken.velocity.y = bad,
            4 => broken.heading = if bad.is_finite() { f32::NAN } else { bad },
            _ => {
                let p = Params { mu: bad, ..Params::default() };
                prop_assert!(planner.set_params(p).is_err());
                prop_assert_eq!(planner.params(), reference.params());
                let bad_goal = Mission { goal: Vec2::new(bad, 0.0), formation: None };
                prop_assert!(planner.set_mission(bad_goal).is_err());
                prop_assert_eq!(planner.mission(), reference.mission());
                broken.position.x = f32::NAN;
            }
        }
        prop_assert!(planner.step(100, &broken, &w).is_err());
        let mut reference = reference;
        let a = planner.step(200, &n, &w).unwrap();
        let b = reference.step(200, &n, &w).unwrap();
        prop_assert_eq!(a, b);
    }
}

#[test]
fn without_a_mission_the_planner_holds() {
    let mut planner = Planner::new(Params::default()).unwrap();
    let n = NavState {
        position: Vec2::ZERO,
        heading: 1.0,
        velocity: Vec2::new(0.5, 0.0),
    };
    let cmd = planner.step(0, &n, &World::new()).unwrap();
    assert_eq!(cmd.v_set, 0.0);
    assert_eq!(
        cmd.mode,
        vpf::Mode::Hold(vpf::planner::HoldReason::NoMission)
    );
}
