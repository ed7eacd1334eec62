//! Per-vehicle metrics, `metrics.json`, and the end-of-run summary.
//!
//! Definitions (t is simulation time as recorded in the samples):
//! - **reached_goal**: the vehicle came within `arrival_radius_m` of its goal at some sample
//!   *and* its last position is within 2 × `arrival_radius_m`. "Ever" alone would count a
//!   vehicle that touched the goal and was pushed away; "at the end" alone would miss one that
//!   holds station just outside the radius under current. The factor 2 tolerates the latter.
//! - **time_to_goal_s**: t of the first sample within the arrival radius (null if none).
//! - **path_length_m**: sum of the distances between consecutive finite positions.
//! - **min_clearance_m**: minimum of `nearest_m` (signed; negative means a collision).
//! - **collisions**: separate episodes of `nearest_m < 0` (a NaN sample neither starts nor
//!   ends one).
//! - **energy_proxy**: ∫|thrust| dt ≈ Σ|thrustᵢ|·dt with the run's period (N·s for the
//!   dynamic model's thrust).
//! - **step_cost**: maximum and mean of the firmware's reported step costs, with their unit.
//! - **counters**: the last telemetry's counters, by name.
//!
//! JSON keys come out in declaration order of the structs below, so the file is stable.

use std::fmt;

use serde::Serialize;

use super::RunOutput;
use crate::types::{VehicleRecord, P2};
use vpf::link::TelemetryCounters;

/// Everything `metrics.json` holds; its `Display` is the end-of-run summary.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Scenario name.
    pub scenario: String,
    /// Which firmware ran.
    pub firmware: String,
    /// Simulation period, s.
    pub dt_s: f64,
    /// Arrival radius, m.
    pub arrival_radius_m: f64,
    /// The rule behind `reached_goal`, spelled out for whoever reads the file.
    pub reached_goal_rule: &'static str,
    /// The planner parameters.
    pub params: vpf::Params,
    /// One entry per vehicle, in scenario order.
    pub vehicles: Vec<VehicleMetrics>,
}

/// The rule behind [`VehicleMetrics::reached_goal`].
pub const REACHED_GOAL_RULE: &str = "came within arrival_radius_m of the goal at some sample \
and the last position is within 2 x arrival_radius_m";

/// Metrics of one vehicle.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VehicleMetrics {
    /// Vehicle name.
    pub name: String,
    /// Its goal, m.
    pub goal: P2,
    /// Number of samples.
    pub samples: usize,
    /// Time of the last sample, s (null without samples).
    pub duration_s: Option<f64>,
    /// See the module notes.
    pub reached_goal: bool,
    /// First time within the arrival radius, s.
    pub time_to_goal_s: Option<f64>,
    /// Distance travelled, m.
    pub path_length_m: f64,
    /// Minimum signed clearance, m (negative: collision).
    pub min_clearance_m: Option<f64>,
    /// Number of collision episodes.
    pub collisions: u32,
    /// Distance from the last position to the goal, m.
    pub final_distance_m: Option<f64>,
    /// Closest approach to the goal, m.
    pub min_goal_distance_m: Option<f64>,
    /// ∫|thrust| dt.
    pub energy_proxy: f64,
    /// Deepest ghost goal-point stack seen.
    pub max_ghost_depth: u8,
    /// Number of ghost goal-points recorded.
    pub ghost_goal_points: usize,
    /// The firmware's mode at the last sample.
    pub final_mode: Option<String>,
    /// Step cost statistics.
    pub step_cost: StepCost,
    /// The last telemetry's counters (null if no telemetry arrived).
    pub counters: Option<TelemetryCounters>,
}

/// Statistics of the firmware's reported planner step costs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StepCost {
    /// Largest cost.
    pub max: Option<u32>,
    /// Mean cost.
    pub mean: Option<f64>,
    /// Number of reports.
    pub count: usize,
    /// `"us"`, `"cycles"`, `"instructions"` or `"unknown"` (null if never reported).
    pub unit: Option<&'static str>,
}

/// The counters that indicate trouble, by name, with their values (all of them; zero ones
/// included).
fn trouble(c: &TelemetryCounters) -> [(&'static str, u32); 13] {
    [
        ("rx_crc_errors", c.rx_crc_errors),
        ("rx_oversize", c.rx_oversize),
        ("rx_framing_errors", c.rx_framing_errors),
        ("rx_unknown", c.rx_unknown),
        ("rx_bad_payload", c.rx_bad_payload),
        ("bad_nav", c.bad_nav),
        ("bad_params", c.bad_params),
        ("bad_mission", c.bad_mission),
        ("rx_bytes_dropped", c.rx_bytes_dropped),
        ("features_dropped", c.features_dropped),
        ("tx_frames_dropped", c.tx_frames_dropped),
        ("deadline_overruns", c.deadline_overruns),
        ("table_full", c.table_full),
    ]
}

impl Summary {
    /// The metrics of a run.
    pub fn of(run: &RunOutput) -> Summary {
        Summary {
            scenario: run.scenario_name.clone(),
            firmware: run.firmware.clone(),
            dt_s: run.dt_s,
            arrival_radius_m: run.arrival_radius_m,
            reached_goal_rule: REACHED_GOAL_RULE,
            params: run.params,
            vehicles: run
                .vehicles
                .iter()
                .map(|v| VehicleMetrics::of(v, run.arrival_radius_m, run.dt_s))
                .collect(),
        }
    }
}

fn finite(p: P2) -> bool {
    p.x.is_finite() && p.y.is_finite()
}

fn cost_unit_name(u: vpf::link::CostUnit) -> &'static str {
    match u {
        vpf::link::CostUnit::Unknown => "unknown",
        vpf::link::CostUnit::Microseconds => "us",
        vpf::link::CostUnit::Cycles => "cycles",
        vpf::link::CostUnit::Instructions => "instructions",
    }
}

fn min_opt(acc: Option<f64>, x: f64) -> Option<f64> {
    if !x.is_finite() {
        return acc;
    }
    Some(acc.map_or(x, |a| a.min(x)))
}

impl VehicleMetrics {
    /// The metrics of one vehicle, for an arrival radius (m) and simulation period (s). A
    /// non-finite or non-positive `dt_s` falls back to the samples' own time steps.
    pub fn of(v: &VehicleRecord, arrival_radius_m: f64, dt_s: f64) -> VehicleMetrics {
        let dist = |p: P2| p.sub(v.goal).norm();
        let mut time_to_goal = None;
        let mut path = 0.0;
        let mut last_pos: Option<P2> = None;
        let mut min_clear = None;
        let mut min_goal = None;
        let mut collisions = 0u32;
        let mut colliding = false;
        let mut energy = 0.0;
        let mut last_t: Option<f64> = None;
        let mut max_ghost = 0u8;
        for s in &v.samples {
            let p = s.state.position;
            if finite(p) {
                if let Some(q) = last_pos {
                    path += p.sub(q).norm();
                }
                last_pos = Some(p);
                let d = dist(p);
                min_goal = min_opt(min_goal, d);
                // NaN radius compares false: never reached.
                if time_to_goal.is_none() && d <= arrival_radius_m && s.t.is_finite() {
                    time_to_goal = Some(s.t);
                }
            }
            let c = s.nearest_m;
            min_clear = min_opt(min_clear, c);
            if !c.is_nan() {
                if c < 0.0 && !colliding {
                    collisions += 1;
                }
                colliding = c < 0.0;
            }
            let step = if dt_s.is_finite() && dt_s > 0.0 {
                dt_s
            } else {
                match last_t {
                    Some(t0) if s.t.is_finite() && s.t > t0 => s.t - t0,
                    _ => 0.0,
                }
            };
            if s.t.is_finite() {
                last_t = Some(s.t);
            }
            if s.state.thrust.is_finite() {
                energy += s.state.thrust.abs() * step;
            }
            max_ghost = max_ghost.max(s.ghost_depth);
        }
        let final_distance = last_pos.map(dist);
        let reached =
            time_to_goal.is_some() && final_distance.is_some_and(|d| d <= 2.0 * arrival_radius_m);
        let costs = &v.step_costs;
        let step_cost = StepCost {
            max: costs.iter().copied().max(),
            mean: (!costs.is_empty())
                .then(|| costs.iter().map(|&c| f64::from(c)).sum::<f64>() / costs.len() as f64),
            count: costs.len(),
            unit: v.cost_unit.map(cost_unit_name),
        };
        VehicleMetrics {
            name: v.name.clone(),
            goal: v.goal,
            samples: v.samples.len(),
            duration_s: v.samples.iter().rev().map(|s| s.t).find(|t| t.is_finite()),
            reached_goal: reached,
            time_to_goal_s: time_to_goal,
            path_length_m: path,
            min_clearance_m: min_clear,
            collisions,
            final_distance_m: final_distance,
            min_goal_distance_m: min_goal,
            energy_proxy: energy,
            max_ghost_depth: max_ghost,
            ghost_goal_points: v.ghosts.len(),
            final_mode: v.samples.last().map(|s| s.mode.clone()),
            step_cost,
            counters: v.telemetry.map(|t| t.counters),
        }
    }
}

/// `1.23 m`, or `n/a`.
struct Opt(Option<f64>, &'static str);

impl fmt::Display for Opt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(x) => write!(f, "{x:.2} {}", self.1),
            None => f.write_str("n/a"),
        }
    }
}

impl fmt::Display for VehicleMetrics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let name = if self.name.is_empty() {
            "(unnamed)"
        } else {
            &self.name
        };
        write!(f, "{name}: ")?;
        if self.samples == 0 {
            f.write_str("no samples recorded")?;
        }
        match (self.reached_goal, self.time_to_goal_s) {
            _ if self.samples == 0 => {}
            (true, Some(t)) => write!(f, "reached its goal at t = {t:.1} s")?,
            (false, Some(t)) => write!(
                f,
                "did NOT reach its goal (was within the arrival radius at t = {t:.1} s but ended {} away)",
                Opt(self.final_distance_m, "m")
            )?,
            _ => write!(
                f,
                "did NOT reach its goal (closest {}, final {})",
                Opt(self.min_goal_distance_m, "m"),
                Opt(self.final_distance_m, "m")
            )?,
        }
        write!(
            f,
            "; path {:.2} m over {}; minimum clearance {}; ",
            self.path_length_m,
            Opt(self.duration_s, "s"),
            Opt(self.min_clearance_m, "m")
        )?;
        match self.collisions {
            0 => f.write_str("no collisions")?,
            1 => f.write_str("1 COLLISION")?,
            n => write!(f, "{n} COLLISIONS")?,
        }
        write!(f, "; energy proxy {:.1}", self.energy_proxy)?;
        if self.max_ghost_depth > 0 || self.ghost_goal_points > 0 {
            write!(
                f,
                "; {} ghost goal-point(s), stack depth up to {}",
                self.ghost_goal_points, self.max_ghost_depth
            )?;
        }
        if let (Some(max), Some(mean)) = (self.step_cost.max, self.step_cost.mean) {
            write!(
                f,
                "; step cost max {max}, mean {mean:.0} {}",
                self.step_cost.unit.unwrap_or("(unit unknown)")
            )?;
        }
        match &self.counters {
            None => f.write_str("; no telemetry received")?,
            Some(c) => {
                write!(
                    f,
                    "; firmware received {} frames, extracted {} sonar features, evicted {} obstacles",
                    c.rx_frames, c.features_extracted, c.table_evicted
                )?;
                let bad: Vec<String> = trouble(c)
                    .iter()
                    .filter(|(_, n)| *n > 0)
                    .map(|(k, n)| format!("{k} {n}"))
                    .collect();
                if bad.is_empty() {
                    f.write_str(", no error counters")?;
                } else {
                    write!(f, ", error counters: {}", bad.join(", "))?;
                }
            }
        }
        f.write_str(".")
    }
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let reached = self.vehicles.iter().filter(|v| v.reached_goal).count();
        write!(
            f,
            "Scenario \"{}\" on firmware {}: {reached} of {} vehicle(s) reached the goal.",
            self.scenario,
            self.firmware,
            self.vehicles.len()
        )?;
        for v in &self.vehicles {
            write!(f, "\n  {v}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::test_support::sample;

    fn straight(n: usize, nearest: impl Fn(usize) -> f64) -> VehicleRecord {
        // 0 → 10 m along x at 1 m per 0.5 s.
        VehicleRecord {
            name: "s".into(),
            goal: P2::new(10.0, 0.0),
            samples: (0..=n)
                .map(|i| sample(i as f64 * 0.5, i as f64, 0.0, nearest(i)))
                .collect(),
            ..VehicleRecord::default()
        }
    }

    #[test]
    fn straight_path_to_the_goal() {
        let v = straight(10, |_| 2.0);
        let m = VehicleMetrics::of(&v, 1.0, 0.5);
        assert!((m.path_length_m - 10.0).abs() < 1e-12);
        // First sample within 1 m of x = 10 is x = 9 at t = 4.5 s.
        assert_eq!(m.time_to_goal_s, Some(4.5));
        assert!(m.reached_goal);
        assert_eq!(m.final_distance_m, Some(0.0));
        assert_eq!(m.min_clearance_m, Some(2.0));
        assert_eq!(m.collisions, 0);
        assert_eq!(m.duration_s, Some(5.0));
        // |thrust| = 2 for 11 samples of 0.5 s.
        assert!((m.energy_proxy - 11.0).abs() < 1e-12);
        assert!(m.counters.is_none());
    }

    #[test]
    fn collisions_are_counted_per_episode() {
        let c = [
            1.0,
            -0.1,
            -0.2,
            0.5,
            f64::NAN,
            -0.3,
            f64::NAN,
            -0.1,
            0.2,
            -0.5,
            0.0,
        ];
        let v = straight(10, |i| c[i]);
        let m = VehicleMetrics::of(&v, 1.0, 0.5);
        // Episodes: [1,2], [5..7] (NaN does not end it), [9].
        assert_eq!(m.collisions, 3);
        assert_eq!(m.min_clearance_m, Some(-0.5));
    }

    #[test]
    fn passing_through_is_not_reaching() {
        let v = VehicleRecord {
            goal: P2::new(5.0, 0.0),
            ..straight(10, |_| 1.0)
        };
        let m = VehicleMetrics::of(&v, 1.0, 0.5);
        assert_eq!(m.time_to_goal_s, Some(2.0));
        assert!(!m.reached_goal, "ended 5 m away");
        assert_eq!(m.min_goal_distance_m, Some(0.0));
        let text = m.to_string();
        assert!(text.contains("did NOT reach"), "{text}");
    }

    #[test]
    fn nan_positions_are_bridged_and_nan_radius_never_reaches() {
        let mut v = straight(10, |_| 1.0);
        v.samples[3].state.position = P2::new(f64::NAN, 0.0);
        v.samples[10].state.position = P2::new(f64::NAN, f64::NAN);
        let m = VehicleMetrics::of(&v, 1.0, 0.5);
        assert!((m.path_length_m - 9.0).abs() < 1e-12);
        assert_eq!(m.final_distance_m, Some(1.0));
        assert!(m.reached_goal);
        let m = VehicleMetrics::of(&v, f64::NAN, f64::NAN);
        assert!(!m.reached_goal && m.time_to_goal_s.is_none());
        // Falls back to the samples' time steps: 10 steps of 0.5 s (the first sample has none).
        assert!((m.energy_proxy - 10.0).abs() < 1e-12);
    }

    #[test]
    fn empty_record() {
        let m = VehicleMetrics::of(&VehicleRecord::default(), 1.0, 0.1);
        assert_eq!(m.samples, 0);
        assert!(!m.reached_goal);
        assert_eq!(m.path_length_m, 0.0);
        assert!(m.min_clearance_m.is_none() && m.final_distance_m.is_none());
        assert!(m.step_cost.max.is_none() && m.step_cost.mean.is_none());
        assert!(
            m.to_string().starts_with("(unnamed): no samples recorded;"),
            "{m}"
        );
    }

    #[test]
    fn step_costs_and_counters() {
        let mut v = straight(2, |_| 1.0);
        v.step_costs = vec![10, 30, 20];
        v.cost_unit = Some(vpf::link::CostUnit::Cycles);
        let mut counters = vpf::link::TelemetryCounters {
            rx_frames: 7,
            ..Default::default()
        };
        counters.deadline_overruns = 2;
        v.telemetry = Some(vpf::link::TelemetryRepr {
            time_ms: 1000,
            mode: vpf::Mode::Transit,
            obstacles: 1,
            agents: 0,
            ghost_depth: 0,
            step_cost: 20,
            cost_unit: vpf::link::CostUnit::Cycles,
            counters,
        });
        let m = VehicleMetrics::of(&v, 1.0, 0.5);
        assert_eq!(m.step_cost.max, Some(30));
        assert_eq!(m.step_cost.mean, Some(20.0));
        assert_eq!(m.step_cost.unit, Some("cycles"));
        let json = serde_json::to_value(&m).unwrap();
        assert_eq!(json["counters"]["rx_frames"], 7);
        assert_eq!(json["counters"]["deadline_overruns"], 2);
        assert_eq!(json["counters"].as_object().unwrap().len(), 16);
        assert!(m.to_string().contains("deadline_overruns 2"));
    }

    #[test]
    fn json_keys_are_in_a_stable_order_and_nan_is_null() {
        let mut run = crate::output::test_support::run();
        run.dt_s = f64::NAN;
        let s = Summary::of(&run);
        let text = serde_json::to_string_pretty(&s).unwrap();
        let keys = [
            "\"scenario\"",
            "\"firmware\"",
            "\"dt_s\"",
            "\"params\"",
            "\"vehicles\"",
        ];
        let pos: Vec<usize> = keys.iter().map(|k| text.find(k).unwrap()).collect();
        assert!(pos.windows(2).all(|w| w[0] < w[1]), "{pos:?}");
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert!(v["dt_s"].is_null());
        assert_eq!(v["params"]["bounding"], "Split");
        assert_eq!(v["params"]["n_gamma"], 16);
        assert!(s
            .to_string()
            .starts_with("Scenario \"two <vehicles> & rocks\" on firmware host"));
    }
}
