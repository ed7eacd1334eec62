//! The whole Ping360 path in the loop: the firmware drives a simulated Ping360 on a port of its
//! own (`[sonar] interface = "ping360"`), turns its `device_data` into scanlines for the
//! extractor and the evidence map, and flies between two walls: the host-process firmware on a
//! pty, and the board image on QEMU through its UART1 (QEMU's second serial port) where
//! `qemu-system-arm` is installed (under CI, `CI=true`, it must be).

use std::path::{Path, PathBuf};

use hil::firmware::Target;
use hil::runner::{run, RunConfig, RunResult};
use hil::scenario::{self, Scenario, SonarInterface};
use vpf::link::ping::{Decoder, Event};

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

fn run_on(sc: &Scenario, test: &str) -> RunResult {
    run_with(sc, Target::Host, test)
}

fn run_with(sc: &Scenario, target: Target, test: &str) -> RunResult {
    let _ = std::fs::remove_dir_all(out_dir(test));
    let cfg = RunConfig {
        target,
        out_dir: out_dir(test),
        progress: false,
    };
    run(sc, &cfg).unwrap_or_else(|e| panic!("run failed: {e}"))
}

#[test]
fn the_firmware_drives_a_ping360_between_two_walls_to_the_goal() {
    let sc = scenario("ping360_narrow_gap.toml");
    assert_eq!(sc.sonar.interface, SonarInterface::Ping360);
    let r = run_on(&sc, "ping360_gap");
    println!("{}", r.summary);
    let m = &r.summary.vehicles[0];
    assert!(m.reached_goal, "did not reach the goal");
    assert!(
        m.min_clearance_m.is_some_and(|c| c > 0.0),
        "touched a wall: clearance {:?}",
        m.min_clearance_m
    );
    // It was the Ping360 that saw: every command answered, every answer a scanline, nothing
    // dropped; and no scanline came over the main link.
    let (sim, faults) = r.ping360[0].expect("a simulated Ping360");
    let p = m.ping360.expect("Ping360 counters in the telemetry");
    println!("{sim:?} {p:?}");
    assert!(p.commands > 1000, "{p:?}");
    assert!(p.data + 1 >= p.commands, "{p:?}");
    assert_eq!(
        (p.timeouts, p.checksum_errors, p.malformed, p.bytes_skipped),
        (0, 0, 0, 0)
    );
    assert_eq!(faults.corrupted + faults.dropped, 0);
    assert_eq!(sim.commands, p.commands);
    let c = m.counters.expect("telemetry");
    assert!(c.features_extracted > 0);
    // The raw bytes the sonar sent are logged, and are whole Ping frames.
    let raw = std::fs::read(out_dir("ping360_gap").join("ping360_videoray.bin")).unwrap();
    let mut d = Decoder::new();
    let mut ends = 0u32;
    let mut rest = &raw[..];
    while !rest.is_empty() {
        let (n, ev) = d.feed(rest);
        ends += u32::from(matches!(ev, Event::DataEnd(_)));
        rest = &rest[n..];
    }
    assert_eq!(ends, sim.answers);
    assert_eq!(d.counters().skipped, 0);
}

#[test]
fn a_lossy_ping360_port_is_counted_and_repeatable() {
    // Bit errors on the Ping360's port only (the main link clean): answers are lost, counted
    // by the firmware (checksum errors, timeouts), and the run is still bit for bit repeatable.
    let mut sc = scenario("ping360_narrow_gap.toml");
    sc.duration_s = 40.0;
    sc.faults.ping360_bit_error_rate = 2e-4;
    let a = run_on(&sc, "ping360_ber_a");
    let b = run_on(&sc, "ping360_ber_b");
    let read = |run: &str, f: &str| std::fs::read(out_dir(run).join(f)).expect("output written");
    assert_eq!(
        read("ping360_ber_a", "trajectory_videoray.csv"),
        read("ping360_ber_b", "trajectory_videoray.csv"),
        "trajectories differ"
    );
    assert_eq!(a.ping360, b.ping360, "the Ping360's exchanges differ");
    let p = a.summary.vehicles[0].ping360.expect("Ping360 counters");
    let (sim, faults) = a.ping360[0].unwrap();
    println!("{p:?} {sim:?} {faults:?}");
    assert_eq!(a.faults[0].corrupted, 0, "the main link stays clean");
    assert!(faults.corrupted > 50, "{faults:?}");
    assert!(p.checksum_errors > 0, "{p:?}");
    // Each corrupted answer is refused by the firmware (or, rarely, passes the 16-bit sum).
    assert_eq!(
        u64::from(sim.refused + sim.corrupted_accepted),
        faults.corrupted,
        "{sim:?}"
    );
    assert_eq!(p.data + sim.refused, sim.answers, "{p:?} {sim:?}");
}

#[test]
fn the_board_image_on_qemu_drives_the_ping360_through_its_second_uart_as_the_host_does() {
    if !hil::firmware::qemu_available() {
        assert!(
            std::env::var("CI").map_or(true, |v| v != "true"),
            "CI=true but qemu-system-arm is not installed"
        );
        eprintln!("SKIPPED: qemu-system-arm is not installed");
        return;
    }
    // Long enough to pass the gap and arrive (106 s on the host: the Ping360 sweeps in 15 s,
    // and twice by the walls the lookout holds the vehicle to 0.25 m/s until it has looked its
    // way again, `src/sonar/lookout.rs`; 97 s before it).
    let mut sc = scenario("ping360_narrow_gap.toml");
    sc.duration_s = 115.0;
    let q = run_with(&sc, Target::Qemu, "ping360_qemu");
    println!("{}", q.summary);
    let m = &q.summary.vehicles[0];
    assert!(m.reached_goal, "did not reach the goal on QEMU");
    assert!(m.min_clearance_m.is_some_and(|c| c > 0.0), "touched a wall");
    let (sim, faults) = q.ping360[0].expect("a simulated Ping360");
    let p = m
        .ping360
        .expect("the board's Ping360 counters in its telemetry");
    assert!(p.commands > 1000, "{p:?}");
    assert!(p.data + 1 >= p.commands, "{p:?}");
    assert_eq!(
        (p.timeouts, p.checksum_errors, p.malformed, p.bytes_skipped),
        (0, 0, 0, 0),
        "the UART1 link lost or damaged bytes"
    );
    assert_eq!(faults.corrupted + faults.dropped, 0);
    // The last telemetry may precede the command answering the last ping.
    assert!(
        sim.commands == p.commands || sim.commands == p.commands + 1,
        "{sim:?} {p:?}"
    );
    assert_eq!(
        q.output.vehicles[0].cost_unit,
        Some(vpf::link::CostUnit::Instructions),
        "not the board image"
    );
    // The same run on the host-process firmware: the same pings, the same flight, bit for bit.
    let h = run_with(&sc, Target::Host, "ping360_qemu_host");
    let read = |run: &str, f: &str| std::fs::read(out_dir(run).join(f)).expect("output written");
    assert!(
        read("ping360_qemu", "trajectory_videoray.csv")
            == read("ping360_qemu_host", "trajectory_videoray.csv"),
        "QEMU's trajectory differs from the host-process firmware's"
    );
    assert!(
        read("ping360_qemu", "ping360_videoray.bin")
            == read("ping360_qemu_host", "ping360_videoray.bin"),
        "the Ping360 was asked for different pings"
    );
    assert_eq!(q.ping360, h.ping360);
}
