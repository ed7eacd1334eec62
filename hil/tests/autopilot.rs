//! Seed 001 Fig. 4 and 6: the helm commands of four AUVs in formation, uncluttered and in
//! severe clutter, and how well the vehicles' autopilots track them — with the planner's PI-D
//! set-point decomposition (001 §2: a_c, v_c, I_surge; α_c, ω_c, φ_c) driving the autopilots,
//! and without it (heading and speed set-points only, the default). The vehicles are VideoRays
//! flying the seed 001 scenarios on the host-process firmware.
//!
//! Tracking error: over every sample in transit (mode Transit, commanded speed above 0.1 m/s),
//! the RMS of the heading error ψ_set − ψ and of the surge speed error v_set − u.
//!
//! **Not reproduced.** The paper shows no numbers, and with the set-points as this planner
//! computes them the comparison goes the other way (measured on single VideoRays, where the
//! seed 001 formation scenarios with VideoRays collide in either mode): crossing_traffic
//! 10.6° / 0.075 m/s RMS plain against 48.7° / 1.11 m/s with the decomposition, random_clutter
//! 13.7° / 0.076 against 22.5° / 0.47, and the decomposition's runs do not arrive. The likely
//! causes, not yet fixed: ω_c and α_c are one-period differences of a command that jumps (a
//! 90° change of φ_c in one 0.1 s period asks for 15 rad/s), which saturate the yaw moment
//! through the derivative channel and the feed-forward; and the planner's ideal position runs
//! on while the guard or a hold stops the vehicle, so I_surge winds to its limit and the
//! integral channel drives full thrust. This test measures and prints the comparison and
//! asserts only that both modes fly and report finite errors; it does not assert the paper's
//! claim.

use std::path::Path;

use hil::firmware::Target;
use hil::runner::{run, RunConfig};
use hil::scenario::{self, Autopilot, ModelKind};
use hil::sim::wrap_pi;

/// (RMS heading error in degrees, RMS speed error in m/s, vehicles that reached the goal,
/// samples) over the fleet.
fn tracking(file: &str, autopilot: Autopilot) -> (f64, f64, usize, usize) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(file);
    let mut sc = scenario::load(&path).unwrap_or_else(|e| panic!("{e}"));
    for v in &mut sc.vehicles {
        v.model = ModelKind::VideoRay;
        v.autopilot = autopilot;
    }
    let out = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../target/hil-tests/autopilot")
        .join(format!("{file}-{autopilot:?}"));
    let _ = std::fs::remove_dir_all(&out);
    let cfg = RunConfig {
        target: Target::Host,
        out_dir: out,
        progress: false,
    };
    let r = run(&sc, &cfg).unwrap_or_else(|e| panic!("run failed: {e}"));
    let (mut psi2, mut v2, mut n) = (0.0, 0.0, 0usize);
    for rec in &r.output.vehicles {
        for s in rec
            .samples
            .iter()
            .filter(|s| s.mode == "Transit" && s.speed_cmd > 0.1)
        {
            psi2 += wrap_pi(s.psi_cmd - s.state.heading).to_degrees().powi(2);
            v2 += (s.speed_cmd - s.state.u).powi(2);
            n += 1;
        }
    }
    let reached = r.summary.vehicles.iter().filter(|m| m.reached_goal).count();
    let nf = n.max(1) as f64;
    ((psi2 / nf).sqrt(), (v2 / nf).sqrt(), reached, n)
}

#[test]
fn helm_tracking_with_and_without_the_pid_setpoint_decomposition() {
    for file in ["crossing_traffic.toml", "random_clutter.toml"] {
        let (plain_psi, plain_v, plain_reached, n_plain) = tracking(file, Autopilot::Plain);
        let (pid_psi, pid_v, pid_reached, n_pid) = tracking(file, Autopilot::SetPoints);
        println!(
            "{file}: plain autopilots: heading {plain_psi:.2}° RMS, speed {plain_v:.3} m/s RMS \
             ({n_plain} samples, {plain_reached} reached); PI-D set-points: heading \
             {pid_psi:.2}° RMS, speed {pid_v:.3} m/s RMS ({n_pid} samples, {pid_reached} reached)"
        );
        assert!(
            n_plain > 500 && n_pid > 500,
            "too little transit to measure"
        );
        assert!([plain_psi, plain_v, pid_psi, pid_v]
            .iter()
            .all(|x| x.is_finite()));
        assert_eq!(
            plain_reached, 1,
            "the default (plain) autopilots no longer arrive"
        );
    }
}
