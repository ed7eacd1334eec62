//! What one run of a sweep measured: one row of `runs.csv`.
//!
//! Per vehicle the harness's own metrics are used ([`VehicleMetrics`]: reached goal,
//! collisions, minimum clearance, path length, time, energy proxy); a run with several vehicles
//! is aggregated (success needs all of them; clearance is the worst; path ratio and oscillation
//! are over the fleet's total path; time is the last arrival; energy is the sum).
//!
//! **Oscillation** is counted as heading reversals per 100 m of path. The yaw rate at sample k
//! is the true heading's change over the step, r = wrap(ψₖ − ψₖ₋₁) / Δt (the same for every
//! vehicle model). Each sample's rate is classed +1 above the deadband δ, −1 below −δ, and 0
//! inside it; a **reversal** is a +1 followed by a −1 or the reverse, with any number of 0s in
//! between (a turn that pauses in the deadband and goes on the same way is not a reversal). δ
//! is the spec's `[criterion] deadband_deg_s` (3 °/s by default: above the heading autopilot's
//! jitter on a straight leg, well below a deliberate turn). The path in the denominator is
//! at least 1 m, so a vehicle that wobbles in place does not divide by zero.

use crate::output::{RunOutput, Summary};
use crate::sim::wrap_pi;

/// One finished run.
#[derive(Clone, Debug, PartialEq)]
pub struct RunRow {
    /// Run index in the sweep's run list.
    pub run: usize,
    /// Parameter set index.
    pub set: usize,
    /// Scenario id (`file:...`, `clutter:3`, ...).
    pub scenario: String,
    /// Every vehicle reached its goal (the harness's rule) and none collided.
    pub success: bool,
    /// Some vehicle collided (negative clearance at some sample).
    pub collided: bool,
    /// Minimum signed clearance over the run and the vehicles, m (NaN if none recorded).
    pub min_clearance_m: f64,
    /// Path length over the straight start–goal distance (fleet totals).
    pub path_ratio: f64,
    /// Time of the last vehicle's arrival, or the run's end without one, s.
    pub time_s: f64,
    /// Energy proxy, summed over the vehicles (∫|thrust| dt).
    pub energy: f64,
    /// Heading reversals per 100 m of path (see the module notes).
    pub oscillation: f64,
    /// Ghost goal-points used (all vehicles).
    pub ghosts: usize,
    /// Simulated time, s.
    pub sim_time_s: f64,
    /// Why the run could not be run, if it could not (then it counts as failed).
    pub error: String,
}

/// Heading reversals in a heading series sampled every `dt` s, with deadband `deadband` rad/s.
pub fn reversals(headings: &[f64], dt: f64, deadband: f64) -> u32 {
    let mut last = 0i8;
    let mut n = 0;
    for w in headings.windows(2) {
        let r = wrap_pi(w[1] - w[0]) / dt;
        let sign = if r > deadband {
            1
        } else if r < -deadband {
            -1
        } else {
            0
        };
        if sign != 0 {
            if last != 0 && sign != last {
                n += 1;
            }
            last = sign;
        }
    }
    n
}

/// The row of a finished run.
pub fn measure(
    run: usize,
    set: usize,
    scenario: &str,
    out: &RunOutput,
    straight_m: &[f64],
    deadband: f64,
) -> RunRow {
    let summary = Summary::of(out);
    let vs = &summary.vehicles;
    let success = !vs.is_empty() && vs.iter().all(|v| v.reached_goal && v.collisions == 0);
    let collided = vs.iter().any(|v| v.collisions > 0);
    let min_clearance_m = vs
        .iter()
        .filter_map(|v| v.min_clearance_m)
        .fold(f64::NAN, f64::min);
    let path: f64 = vs.iter().map(|v| v.path_length_m).sum();
    let straight: f64 = straight_m.iter().sum();
    let sim_time_s = vs.iter().filter_map(|v| v.duration_s).fold(0.0, f64::max);
    let time_s = if vs.iter().all(|v| v.time_to_goal_s.is_some()) {
        vs.iter()
            .filter_map(|v| v.time_to_goal_s)
            .fold(0.0, f64::max)
    } else {
        sim_time_s
    };
    let turns: u32 = out
        .vehicles
        .iter()
        .map(|v| {
            let h: Vec<f64> = v.samples.iter().map(|s| s.state.heading).collect();
            reversals(&h, out.dt_s, deadband)
        })
        .sum();
    RunRow {
        run,
        set,
        scenario: scenario.to_string(),
        success,
        collided,
        min_clearance_m,
        path_ratio: if straight > 0.0 {
            path / straight
        } else {
            f64::NAN
        },
        time_s,
        energy: vs.iter().map(|v| v.energy_proxy).sum(),
        oscillation: 100.0 * f64::from(turns) / path.max(1.0),
        ghosts: vs.iter().map(|v| v.ghost_goal_points).sum(),
        sim_time_s,
        error: String::new(),
    }
}

/// The row of a run that could not be run.
pub fn failed(run: usize, set: usize, scenario: &str, error: String) -> RunRow {
    RunRow {
        run,
        set,
        scenario: scenario.to_string(),
        success: false,
        collided: false,
        min_clearance_m: f64::NAN,
        path_ratio: f64::NAN,
        time_s: f64::NAN,
        energy: f64::NAN,
        oscillation: f64::NAN,
        ghosts: 0,
        sim_time_s: 0.0,
        error,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reversals_need_both_signs_beyond_the_deadband() {
        let dt = 0.1;
        // Rates (rad/s): +0.1, +0.1, 0, +0.1 (no reversal: paused in the deadband), −0.1 (1),
        // −0.01 (inside the deadband), +0.2 (2).
        let rates = [0.1, 0.1, 0.0, 0.1, -0.1, -0.01, 0.2];
        let mut h = vec![0.0];
        for r in rates {
            let last = *h.last().unwrap();
            h.push(last + r * dt);
        }
        assert_eq!(reversals(&h, dt, 0.05), 2);
        assert_eq!(reversals(&h, dt, 0.15), 0);
        assert_eq!(reversals(&[], dt, 0.05), 0);
        // Across ±π: a steady turn through the wrap is not a reversal.
        let h = [3.1, -3.13, -3.05, -2.9];
        assert_eq!(reversals(&h, dt, 0.05), 0);
    }
}
