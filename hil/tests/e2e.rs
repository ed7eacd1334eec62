//! End-to-end HIL runs: the harness, a firmware and the simulated world together.
//!
//! The runs use the host-process firmware (the same runtime and protocol as the board), and one
//! runs on QEMU's emulated Cortex-M4 where `qemu-system-arm` is installed — under CI
//! (`CI=true`) it must be, and that test fails instead of skipping.

use std::path::{Path, PathBuf};

use hil::firmware::Target;
use hil::runner::{run, RunConfig, RunResult};
use hil::scenario::{self, Scenario, Window};

fn scenario(name: &str) -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name);
    scenario::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn out_dir(test: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../target/hil-tests")
        .join(test)
}

fn run_on(sc: &Scenario, target: Target, test: &str) -> RunResult {
    let _ = std::fs::remove_dir_all(out_dir(test));
    let cfg = RunConfig {
        target,
        out_dir: out_dir(test),
        progress: false,
    };
    run(sc, &cfg).unwrap_or_else(|e| panic!("run failed: {e}"))
}

#[test]
fn paper_scenario_reaches_its_goal_with_positive_clearance() {
    let sc = scenario("seed000_fig6_clutter_ghosts.toml");
    let r = run_on(&sc, Target::Host, "fig6");
    let m = &r.summary.vehicles[0];
    println!("{}", r.summary);
    assert!(m.reached_goal, "did not reach the goal");
    assert!(
        m.min_clearance_m.is_some_and(|c| c > 0.0),
        "touched an obstacle"
    );
    assert!(
        m.ghost_goal_points >= 1,
        "the clutter needs ghost goal-points"
    );
    for f in [
        "metrics.json",
        "plot.svg",
        "commands.svg",
        "trajectory_auv.csv",
        "frames_auv.log",
    ] {
        assert!(out_dir("fig6").join(f).is_file(), "{f} missing");
    }
}

#[test]
fn lockstep_runs_are_bit_for_bit_repeatable() {
    // A dynamic vehicle, a noisy sonar and noisy navigation: everything seeded.
    let mut sc = scenario("random_clutter.toml");
    sc.duration_s = 60.0;
    let a = run_on(&sc, Target::Host, "repeat_a");
    let b = run_on(&sc, Target::Host, "repeat_b");
    assert!(a.output.vehicles[0].samples.len() > 500);
    let read = |run: &str, f: &str| std::fs::read(out_dir(run).join(f)).expect("output written");
    let csv = "trajectory_videoray.csv";
    assert_eq!(
        read("repeat_a", csv),
        read("repeat_b", csv),
        "trajectories differ"
    );
    // The host firmware's step costs are wall-clock microseconds, and on a loaded machine a
    // period's answer may be late: the harness sends its Tick again (`tick_retries`), which
    // the firmware counts as a frame received. Nothing else may differ.
    let frames = |r: &RunResult| {
        let c = r.output.vehicles[0].telemetry.map(|t| t.counters);
        c.map(|c| c.rx_frames.saturating_sub(r.tick_retries[0]))
    };
    assert_eq!(
        frames(&a),
        frames(&b),
        "frames other than resent Ticks differ"
    );
    let metrics = |run: &str| {
        let mut v: serde_json::Value = serde_json::from_slice(&read(run, "metrics.json")).unwrap();
        for veh in v["vehicles"].as_array_mut().unwrap() {
            veh.as_object_mut().unwrap().remove("step_cost");
            veh["counters"].as_object_mut().unwrap().remove("rx_frames");
        }
        v
    };
    assert_eq!(metrics("repeat_a"), metrics("repeat_b"), "metrics differ");
    let counters = |r: &RunResult| {
        let c = r.output.vehicles[0].telemetry.map(|t| t.counters);
        c.map(|c| vpf::link::TelemetryCounters { rx_frames: 0, ..c })
    };
    assert_eq!(counters(&a), counters(&b));
}

#[test]
fn corrupted_link_still_reaches_the_goal_and_the_counters_show_it() {
    let mut sc = scenario("seed000_fig3_friction.toml");
    sc.faults.bit_error_rate = 2e-4;
    sc.faults.drop_rate = 0.02;
    let r = run_on(&sc, Target::Host, "corrupt");
    let m = &r.summary.vehicles[0];
    let f = r.faults[0];
    let tel = r.output.vehicles[0].telemetry.expect("telemetry");
    println!(
        "{}\nfaults {f:?}, tick retries {:?}, of which slow {:?}",
        r.summary, r.tick_retries, r.ticks_slow
    );
    assert!(f.corrupted > 50 && f.dropped > 50, "{f:?}");
    // Dropped and corrupted Ticks are re-sent, and reported as lost (answered once), not slow.
    assert!(r.tick_retries[0] > r.ticks_slow[0]);
    // Protocol 7: the forward error correction repairs most corrupted frames, and counts them;
    // those beyond repair (a block with more than 8 wrong bytes, a frame cut in two or run into
    // the next) are refused and counted too.
    let c = tel.counters;
    assert!(c.rx_fec_corrected > 50, "{c:?}");
    assert!(
        c.rx_fec_uncorrectable + c.rx_crc_errors + c.rx_framing_errors + c.rx_oversize > 0,
        "{c:?}"
    );
    assert!(
        u64::from(c.rx_fec_corrected + c.rx_fec_uncorrectable) <= f.corrupted,
        "{c:?} {f:?}"
    );
    assert!(m.reached_goal && m.collisions == 0);
}

#[test]
fn navigation_loss_stops_the_vehicle_within_two_periods_of_the_timeout() {
    let mut sc = scenario("seed000_fig3_friction.toml");
    sc.duration_s = 30.0;
    sc.faults.nav_loss = Some(Window {
        from_s: 10.0,
        to_s: 20.0,
    });
    let r = run_on(&sc, Target::Host, "navloss");
    let samples = &r.output.vehicles[0].samples;
    let first_hold = samples
        .iter()
        .find(|s| s.t >= 10.0 - 1e-9 && s.mode.contains("StaleNav"))
        .expect("a stale-navigation hold");
    println!("hold at t = {:.2} s", first_hold.t);
    // Until the timeout the late fix is dead-reckoned and the vehicle slows.
    let timeout_s = vpf::guidance::FailsafeConfig::default().nav_timeout_ms as f64 * 1e-3;
    assert!(first_hold.t <= 10.0 + timeout_s + 2.0 * sc.dt_s + 1e-9);
    assert!(samples
        .iter()
        .any(|s| s.t > 10.1 && s.t < first_hold.t && s.mode == "Transit"));
    assert_eq!(first_hold.speed_cmd, 0.0);
    let moving_before = samples.iter().any(|s| s.t < 10.0 && s.speed_cmd > 0.1);
    let moving_after = samples.iter().any(|s| s.t > 21.0 && s.speed_cmd > 0.1);
    assert!(
        moving_before && moving_after,
        "planning must resume when navigation returns"
    );
}

#[test]
fn bad_scenario_files_give_the_documented_error() {
    let dir = out_dir("bad_scenario");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        "name = \"bad\"\nduration_s = 10.0\ndt_s = 0.1\nseed = 1\n\n[[vehicle]]\nname = \"a\"\nmodel = \"kinematic\"\nstart = [0.0, 0.0]\ngoal = [5.0, 0.0]\n\n[[obstacle]]\nshape = \"circle\"\ncenter = [2.0, 3.0]\nradius = -1.0\n",
    )
    .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_hil"))
        .arg("check")
        .arg(&bad)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        err.contains("bad.toml:15: key `obstacle[0].radius`: must be > 0"),
        "{err}"
    );
}

#[test]
fn a_scenario_runs_on_the_emulated_cortex_m4() {
    if !hil::firmware::qemu_available() {
        assert!(
            std::env::var("CI").map_or(true, |v| v != "true"),
            "CI=true but qemu-system-arm is not installed"
        );
        eprintln!("SKIPPED: qemu-system-arm is not installed");
        return;
    }
    let mut sc = scenario("seed000_fig3_friction.toml");
    sc.duration_s = 60.0;
    let r = run_on(&sc, Target::Qemu, "qemu");
    let rec = &r.output.vehicles[0];
    println!("{}", r.summary);
    assert_eq!(rec.cost_unit, Some(vpf::link::CostUnit::Instructions));
    let max = rec.step_costs.iter().max().copied().unwrap_or(0);
    assert!(
        max > 1_000 && max <= 100_000,
        "step cost {max} instructions"
    );
    // Same lockstep inputs, same planner code: the Cortex-M4 build and the host build fly the
    // same trajectory, bit for bit.
    run_on(&sc, Target::Host, "qemu_vs_host");
    let csv = |run: &str| std::fs::read(out_dir(run).join("trajectory_auv.csv")).unwrap();
    assert_eq!(
        csv("qemu"),
        csv("qemu_vs_host"),
        "QEMU and host trajectories differ"
    );
    // A clean link loses nothing (a Tick answered late on a loaded machine is only slow).
    assert_eq!(
        r.tick_retries[0] - r.ticks_slow[0],
        0,
        "a Tick was lost on a clean link"
    );
    // The same image with the link on its UART (one byte per QEMU main-loop turn: a shorter
    // run) flies the same trajectory too.
    sc.duration_s = 15.0;
    let uart = run_on(&sc, Target::QemuUart, "qemu_uart");
    assert_eq!(uart.output.firmware, "qemu-uart");
    run_on(&sc, Target::Host, "qemu_uart_vs_host");
    assert_eq!(
        csv("qemu_uart"),
        csv("qemu_uart_vs_host"),
        "QEMU (UART) and host trajectories differ"
    );
}

#[test]
fn no_collision_under_any_fault() {
    // A VideoRay with its sonar in clutter, under each fault kind in turn.
    let base = scenario("random_clutter.toml");
    type Fault = (&'static str, fn(&mut Scenario));
    let faults: [Fault; 5] = [
        ("bit errors", |s| s.faults.bit_error_rate = 1e-4),
        ("dropped frames", |s| s.faults.drop_rate = 0.05),
        ("delayed navigation", |s| s.faults.nav_delay_ms = 500.0),
        ("frozen navigation", |s| {
            s.faults.nav_freeze = Some(Window {
                from_s: 40.0,
                to_s: 45.0,
            })
        }),
        ("sonar dropout", |s| {
            s.faults.sonar_dropout = Some(Window {
                from_s: 20.0,
                to_s: 60.0,
            })
        }),
    ];
    for (i, (what, apply)) in faults.iter().enumerate() {
        let mut sc = base.clone();
        sc.duration_s = 150.0;
        apply(&mut sc);
        let r = run_on(&sc, Target::Host, &format!("fault_{i}"));
        let m = &r.summary.vehicles[0];
        println!(
            "{what}: min clearance {:?}, collisions {}",
            m.min_clearance_m, m.collisions
        );
        assert_eq!(m.collisions, 0, "collision under {what}");
    }
}
