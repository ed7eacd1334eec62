//! Per-vehicle metrics, `metrics.json`, and the end-of-run summary.
//!
//! Definitions (t is simulation time as recorded in the samples):
//! - **reached_goal**: the vehicle came within `arrival_radius_m` of its goal at some sample
//!   *and* its last position is within 2 × `arrival_radius_m`. "Ever" alone would count a
//!   vehicle that touched the goal and was pushed away; "at the end" alone would miss one that
//!   holds station just outside the radius under current. The factor 2 tolerates the latter.
//! - **time_to_goal_s**: t of the first sample within the arrival radius (null if none).
//! - **waypoints** (waypoint missions only; absent for a single goal): per waypoint its
//!   position, radius and `reached_s`, the first sample within its radius after the one before
//!   was reached (`types::waypoint_arrivals`). Such a mission is **reached** when every waypoint
//!   was, in order; its `time_to_goal_s` is the last one's.
//! - **path_length_m**: sum of the distances between consecutive finite positions.
//! - **min_clearance_m**: minimum of `nearest_m` (signed; negative means a collision).
//! - **collisions**: separate episodes of `nearest_m < 0` (a NaN sample neither starts nor
//!   ends one).
//! - **energy_proxy**: ∫|thrust| dt ≈ Σ|thrustᵢ|·dt with the run's period (N·s for the
//!   dynamic model's thrust).
//! - **arrival_error**, **final_error**: the vehicle's error at the first sample within the
//!   arrival radius (so its `t_s` is `time_to_goal_s`, the arrival time) and at the last
//!   sample with a finite position and heading — the errors seed 003 §5 reports at the goal: the
//!   goal's offset from the vehicle in the body frame (`surge_m` forward, `sway_m` to port;
//!   goal − position, rotated by −ψ) and the yaw error, heading set-point of that sample (the
//!   last one the firmware sent) minus heading, wrapped to (−180°, 180°] (null if the set-point
//!   is not finite). Null when there is no such sample.
//! - **step_cost**: maximum and mean of the firmware's reported step costs, with their unit.
//! - **counters**: the last telemetry's counters, by name.
//! - **current_believed**: the current the firmware believed at its last telemetry, m/s over
//!   ground (protocol 8's `Telemetry` rows 39–40), to set beside the scenario's `[current]`.
//!
//! JSON keys come out in declaration order of the structs below, so the file is stable.

use std::fmt;

use serde::Serialize;

use super::belief::Perception;
use super::RunOutput;
use crate::sim::contacts::OtherVehicle;
use crate::sim::vehicle::wrap_pi;
use crate::types::{waypoint_arrivals, Sample, VehicleRecord, WaypointMark, P2};
use vpf::link::TelemetryCounters;
use vpf::sonar::ping360::Ping360Counters;

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
    /// The error on arrival (first sample within the arrival radius; its `t_s` is the arrival
    /// time), null if it never arrived.
    pub arrival_error: Option<GoalError>,
    /// The error at the last sample with a finite position and heading.
    pub final_error: Option<GoalError>,
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
    /// How the firmware's believed map compared with the truth (`belief.rs`); `None` without
    /// `Belief` messages (contacts, or an older firmware).
    pub perception: Option<Perception>,
    /// The last telemetry's Ping360 port counters, when the firmware drove a Ping360 (it sent
    /// commands); null otherwise.
    pub ping360: Option<Ping360Counters>,
    /// The current the firmware believed at its last telemetry, m/s over ground (x, y); null
    /// if no telemetry arrived.
    pub current_believed: Option<[f64; 2]>,
    /// A waypoint mission's waypoints and when each was reached (absent for a single goal).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub waypoints: Option<Vec<WaypointArrival>>,
}

/// One waypoint of a mission and when the vehicle reached it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct WaypointArrival {
    /// The waypoint as judged (position, radius).
    #[serde(flatten)]
    pub mark: WaypointMark,
    /// First time within its radius after the one before was reached, s (null: never).
    pub reached_s: Option<f64>,
}

/// A vehicle's error against its goal and its heading set-point at one sample, in its body
/// frame (x forward, y to port): what seed 003 §5 reports at the goal ("position errors in surge
/// and sway axes of 0.05 m, −0.1 m respectively and a yaw error of 3°").
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct GoalError {
    /// Time of the sample, s.
    pub t_s: f64,
    /// Goal offset along the body x axis, m: positive while the goal is ahead.
    pub surge_m: f64,
    /// Goal offset along the body y axis, m: positive while the goal is to port.
    pub sway_m: f64,
    /// Heading set-point minus heading, wrapped to (−180, 180], deg (null if the set-point is
    /// not finite).
    pub yaw_deg: Option<f64>,
}

impl GoalError {
    /// The error of sample `s` against `goal`; `None` unless its position, heading and the
    /// goal are finite.
    pub fn of(s: &Sample, goal: P2) -> Option<GoalError> {
        let st = &s.state;
        if !(finite(st.position) && finite(goal) && st.heading.is_finite()) {
            return None;
        }
        let d = goal.sub(st.position);
        let (sn, cs) = st.heading.sin_cos();
        Some(GoalError {
            t_s: s.t,
            surge_m: d.x * cs + d.y * sn,
            sway_m: -d.x * sn + d.y * cs,
            yaw_deg: s
                .psi_cmd
                .is_finite()
                .then(|| wrap_pi(s.psi_cmd - st.heading).to_degrees()),
        })
    }
}

impl fmt::Display for GoalError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "(t = {:.1} s) surge {:+.2} m, sway {:+.2} m, yaw ",
            self.t_s, self.surge_m, self.sway_m
        )?;
        match self.yaw_deg {
            Some(y) => write!(f, "{y:+.1}°"),
            None => f.write_str("n/a"),
        }
    }
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
/// included). Frames the forward error correction repaired are there too: a noisy link.
fn trouble(c: &TelemetryCounters) -> [(&'static str, u32); 18] {
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
        ("frozen_nav_holds", c.frozen_nav_holds),
        ("requests_busy", c.requests_busy),
        ("requests_unanswered", c.requests_unanswered),
        ("rx_fec_corrected", c.rx_fec_corrected),
        ("rx_fec_uncorrectable", c.rx_fec_uncorrectable),
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
                .enumerate()
                .map(|(i, v)| {
                    let mut m = VehicleMetrics::of(v, run.arrival_radius_m, run.dt_s);
                    m.perception = perception(run, i);
                    m
                })
                .collect(),
        }
    }
}

/// Vehicle `i`'s perception metrics (`belief.rs`), the other vehicles where they were.
fn perception(run: &RunOutput, i: usize) -> Option<Perception> {
    let v = run.vehicles.get(i)?;
    let others = |t: f64| {
        run.vehicles
            .iter()
            .enumerate()
            .filter(|(k, _)| *k != i)
            .filter_map(|(_, o)| {
                let k = ((t / run.dt_s.max(1e-3)).round() as usize)
                    .min(o.samples.len().checked_sub(1)?);
                let s = o.samples.get(k)?;
                Some(OtherVehicle {
                    id: 0,
                    position: s.state.position,
                    velocity: P2::default(),
                    hull_radius: o.hull_m,
                })
            })
            .collect()
    };
    super::belief::measure(&v.belief, &run.obstacles, &others, !run.vehicles_known)
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
        let mut arrival_error = None;
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
                    arrival_error = GoalError::of(s, v.goal);
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
        let mut reached =
            time_to_goal.is_some() && final_distance.is_some_and(|d| d <= 2.0 * arrival_radius_m);
        let waypoints = (!v.waypoints.is_empty()).then(|| {
            let times = waypoint_arrivals(&v.waypoints, &v.samples);
            v.waypoints
                .iter()
                .zip(times)
                .map(|(mark, reached_s)| WaypointArrival {
                    mark: *mark,
                    reached_s,
                })
                .collect::<Vec<_>>()
        });
        if let Some(w) = &waypoints {
            reached = w.iter().all(|a| a.reached_s.is_some());
            time_to_goal = w.last().and_then(|a| a.reached_s);
        }
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
            arrival_error,
            final_error: v
                .samples
                .iter()
                .rev()
                .find_map(|s| GoalError::of(s, v.goal)),
            energy_proxy: energy,
            max_ghost_depth: max_ghost,
            ghost_goal_points: v.ghosts.len(),
            final_mode: v.samples.last().map(|s| s.mode.clone()),
            step_cost,
            counters: v.telemetry.map(|t| t.counters),
            perception: None,
            ping360: v
                .telemetry
                .map(|t| t.ping360)
                .filter(|p| v.ping360 && p.commands > 0),
            current_believed: v
                .telemetry
                .map(|t| [f64::from(t.current.x), f64::from(t.current.y)]),
            waypoints,
        }
    }
}

/// `1.23 m`, or `n/a`.
struct MaybeValue(Option<f64>, &'static str);

impl fmt::Display for MaybeValue {
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
        if let Some(w) = &self.waypoints {
            let times: Vec<String> = w
                .iter()
                .map(|a| a.reached_s.map_or("–".into(), |t| format!("{t:.1}")))
                .collect();
            let n = w.iter().filter(|a| a.reached_s.is_some()).count();
            write!(
                f,
                "{n} of {} waypoints (at t = {} s); ",
                w.len(),
                times.join(", ")
            )?;
        }
        match (self.reached_goal, self.time_to_goal_s) {
            _ if self.samples == 0 => {}
            (true, Some(t)) => write!(f, "reached its goal at t = {t:.1} s")?,
            (false, Some(t)) => write!(
                f,
                "did NOT reach its goal (was within the arrival radius at t = {t:.1} s but ended {} away)",
                MaybeValue(self.final_distance_m, "m")
            )?,
            _ => write!(
                f,
                "did NOT reach its goal (closest {}, final {})",
                MaybeValue(self.min_goal_distance_m, "m"),
                MaybeValue(self.final_distance_m, "m")
            )?,
        }
        write!(
            f,
            "; path {:.2} m over {}; minimum clearance {}; ",
            self.path_length_m,
            MaybeValue(self.duration_s, "s"),
            MaybeValue(self.min_clearance_m, "m")
        )?;
        match self.collisions {
            0 => f.write_str("no collisions")?,
            1 => f.write_str("1 COLLISION")?,
            n => write!(f, "{n} COLLISIONS")?,
        }
        if let Some(e) = &self.arrival_error {
            write!(f, "; error on arrival {e}")?;
        }
        if let Some(e) = &self.final_error {
            write!(f, "; final error {e}")?;
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
        if let Some([x, y]) = self.current_believed.filter(|c| c[0].hypot(c[1]) >= 0.005) {
            write!(f, "; believed a current of ({x:.2}, {y:.2}) m/s")?;
        }
        match &self.counters {
            None => f.write_str("; no telemetry received")?,
            Some(c) => {
                write!(
                    f,
                    "; firmware received {} frames, extracted {} sonar features, evicted {} obstacles, guard intervened in {} periods",
                    c.rx_frames, c.features_extracted, c.table_evicted, c.guard_interventions
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
        if let Some(p) = &self.ping360 {
            write!(
                f,
                "; Ping360: {} commands, {} pings, {} timeouts, {} checksum errors, {} malformed, {} bytes skipped",
                p.commands, p.data, p.timeouts, p.checksum_errors, p.malformed, p.bytes_skipped
            )?;
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
    fn goal_errors_are_in_the_body_frame_on_arrival_and_at_the_end() {
        use std::f64::consts::{FRAC_PI_2, PI};
        let at = |t: f64, x: f64, y: f64, heading: f64, psi_cmd: f64| {
            let mut s = sample(t, x, y, 1.0);
            s.state.heading = heading;
            s.psi_cmd = psi_cmd;
            s
        };
        let three = 3f64.to_radians();
        let mut v = VehicleRecord {
            goal: P2::new(10.0, 5.0),
            samples: vec![
                at(0.0, 0.0, 0.0, 0.0, 0.0),
                // Arrives heading north (+y), 0.5 m west of and 0.2 m short of the goal: the
                // goal is 0.2 m ahead and 0.5 m to starboard.
                at(1.0, 9.5, 4.8, FRAC_PI_2, FRAC_PI_2 + three),
                // Ends heading west (ψ = π), 5 cm east and 10 cm north of the goal: it is 5 cm
                // ahead and 10 cm to port. The set-point, −177°, is 3° to port across ±180°.
                at(2.0, 10.05, 5.1, PI, -PI + three),
            ],
            ..VehicleRecord::default()
        };
        let m = VehicleMetrics::of(&v, 1.0, 1.0);
        assert_eq!(m.time_to_goal_s, Some(1.0));
        let close = |a: f64, b: f64| (a - b).abs() < 1e-9;
        let a = m.arrival_error.expect("arrived");
        assert_eq!(a.t_s, 1.0);
        assert!(close(a.surge_m, 0.2) && close(a.sway_m, -0.5), "{a:?}");
        assert!(close(a.yaw_deg.unwrap(), 3.0), "{a:?}");
        let e = m.final_error.expect("has samples");
        assert_eq!(e.t_s, 2.0);
        assert!(close(e.surge_m, 0.05) && close(e.sway_m, 0.1), "{e:?}");
        assert!(close(e.yaw_deg.unwrap(), 3.0), "{e:?}");
        let text = m.to_string();
        assert!(
            text.contains(
                "error on arrival (t = 1.0 s) surge +0.20 m, sway -0.50 m, yaw +3.0°; final error \
                 (t = 2.0 s) surge +0.05 m, sway +0.10 m, yaw +3.0°"
            ),
            "{text}"
        );
        let json = serde_json::to_value(&m).unwrap();
        assert_eq!(json["final_error"]["t_s"], 2.0);
        assert!((json["arrival_error"]["sway_m"].as_f64().unwrap() + 0.5).abs() < 1e-9);

        // A last sample without a heading is skipped; a set-point that is not finite has no yaw
        // error; a vehicle that never comes within the radius has no arrival error.
        v.samples[2].psi_cmd = f64::NAN;
        v.samples.push(at(3.0, 12.0, 5.0, f64::NAN, 0.0));
        let m = VehicleMetrics::of(&v, 0.1, 1.0);
        assert!(m.time_to_goal_s.is_none() && m.arrival_error.is_none());
        let e = m.final_error.unwrap();
        assert_eq!((e.t_s, e.yaw_deg), (2.0, None));
        assert!(m.to_string().contains("yaw n/a"), "{m}");
        let json = serde_json::to_value(&m).unwrap();
        assert!(json["arrival_error"].is_null() && json["final_error"]["yaw_deg"].is_null());
    }

    #[test]
    fn empty_record() {
        let m = VehicleMetrics::of(&VehicleRecord::default(), 1.0, 0.1);
        assert_eq!(m.samples, 0);
        assert!(!m.reached_goal);
        assert_eq!(m.path_length_m, 0.0);
        assert!(m.min_clearance_m.is_none() && m.final_distance_m.is_none());
        assert!(m.arrival_error.is_none() && m.final_error.is_none());
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
            ping360: Default::default(),
            current: vpf::Vec2::new(0.5, -0.25),
            mission: Default::default(),
        });
        let m = VehicleMetrics::of(&v, 1.0, 0.5);
        assert_eq!(m.step_cost.max, Some(30));
        assert_eq!(m.step_cost.mean, Some(20.0));
        assert_eq!(m.step_cost.unit, Some("cycles"));
        let json = serde_json::to_value(&m).unwrap();
        assert_eq!(json["counters"]["rx_frames"], 7);
        assert_eq!(json["counters"]["deadline_overruns"], 2);
        assert_eq!(json["counters"].as_object().unwrap().len(), 22);
        assert!(m.to_string().contains("deadline_overruns 2"));
        assert_eq!(json["current_believed"][0], 0.5);
        assert_eq!(json["current_believed"][1], -0.25);
        assert!(m
            .to_string()
            .contains("believed a current of (0.50, -0.25) m/s"));
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
