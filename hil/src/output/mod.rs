//! What a run leaves behind, in one directory:
//!
//! - `trajectory_<vehicle>.csv`: one row per sample ([`trajectory`]);
//! - `metrics.json`: per-vehicle metrics, the scenario, firmware and parameters ([`metrics`]);
//! - `plot.svg`: top view with obstacles, trajectories, goals, ghost goal-points and the
//!   potential field's contours ([`plot`]);
//! - `commands.svg`: commanded speed and heading over time ([`commands`]);
//! - `frames_<vehicle>.log`: the serial traffic, written while the run goes ([`frames`]).
//!
//! Nothing here panics on empty or odd input: no samples gives empty tables and a plot that
//! says so, and NaN values are skipped where they would break a number (plots, sums, minima).

pub mod belief;
pub mod commands;
pub mod frames;
pub mod metrics;
pub mod plot;
pub mod stdout;
pub(crate) mod svg;
pub mod trajectory;

use std::collections::HashSet;
use std::path::Path;

use crate::types::{SimObstacle, VehicleRecord, P2};

pub use frames::{Dir, FrameLog};
pub use metrics::{StepCost, Summary, VehicleMetrics};

/// Everything a run produced, as handed to [`write_all`].
#[derive(Clone, Debug)]
pub struct RunOutput {
    /// Scenario name (from the scenario file).
    pub scenario_name: String,
    /// Simulation period, s.
    pub dt_s: f64,
    /// The scenario's obstacles (truth, at t = 0, with their velocities).
    pub obstacles: Vec<SimObstacle>,
    /// One record per vehicle, in scenario order.
    pub vehicles: Vec<VehicleRecord>,
    /// Which firmware ran: `"qemu"`, `"host"` or `"port:/dev/..."`.
    pub firmware: String,
    /// Distance to the goal under which a vehicle counts as arrived, m.
    pub arrival_radius_m: f64,
    /// The planner parameters the run used.
    pub params: vpf::Params,
    /// The firmware was told where the other vehicles are (`[sonar] vehicle_contacts`): they
    /// are not its sonar's to find (the perception metrics leave them out of the misses).
    pub vehicles_known: bool,
    /// The water's velocity over ground, m/s (`[current]`; zero in still water).
    pub current: P2,
}

/// Makes sure the outputs can be written to `dir` before a run starts: creates it, then
/// creates and removes a probe file in it, so a bad path, a name too long or a read-only
/// directory fails at once instead of after the flight. The error names the directory.
pub fn prepare_dir(dir: &Path) -> std::io::Result<()> {
    let named = |e: std::io::Error| {
        std::io::Error::new(
            e.kind(),
            format!("cannot write the outputs to {}: {e}", dir.display()),
        )
    };
    std::fs::create_dir_all(dir).map_err(named)?;
    let probe = dir.join(".hil-write-probe");
    std::fs::write(&probe, b"").map_err(named)?;
    std::fs::remove_file(&probe).map_err(named)
}

/// Writes the trajectories, `metrics.json`, `plot.svg` and `commands.svg` into `dir` (created
/// if missing) and returns the metrics. Frame logs are written during the run by [`FrameLog`].
pub fn write_all(dir: &Path, run: &RunOutput) -> std::io::Result<Summary> {
    std::fs::create_dir_all(dir)?;
    let names = file_names(&run.vehicles);
    for (v, name) in run.vehicles.iter().zip(&names) {
        let path = dir.join(format!("trajectory_{name}.csv"));
        trajectory::write_csv(&path, v)?;
    }
    let summary = Summary::of(run);
    let json = serde_json::to_string_pretty(&summary).map_err(std::io::Error::other)?;
    std::fs::write(dir.join("metrics.json"), json + "\n")?;
    std::fs::write(dir.join("plot.svg"), plot::render(run))?;
    std::fs::write(dir.join("commands.svg"), commands::render(run))?;
    Ok(summary)
}

/// A vehicle name made safe for a file name: ASCII letters, digits, `-` and `_` kept, anything
/// else replaced by `_` (a name like `../x` must not leave the output directory).
pub fn file_stem(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() {
        "vehicle".to_string()
    } else {
        s
    }
}

/// Distinct file stems for the vehicles, in order: two names that sanitise alike get `_2`, `_3`
/// suffixes so that no trajectory overwrites another.
pub fn file_names(vehicles: &[VehicleRecord]) -> Vec<String> {
    let mut used = HashSet::new();
    vehicles
        .iter()
        .map(|v| {
            let base = file_stem(&v.name);
            let mut name = base.clone();
            let mut k = 2;
            while !used.insert(name.clone()) {
                name = format!("{base}_{k}");
                k += 1;
            }
            name
        })
        .collect()
}

#[cfg(test)]
pub(crate) mod test_support {
    //! Small synthetic runs shared by the output tests.
    use super::RunOutput;
    use crate::types::{Sample, SimObstacle, SimShape, VehicleRecord, VehicleState, P2};

    /// A sample at `t` at (x, y) with the given clearance.
    pub fn sample(t: f64, x: f64, y: f64, nearest: f64) -> Sample {
        Sample {
            t,
            state: VehicleState {
                position: P2::new(x, y),
                heading: 0.3,
                u: 0.5,
                thrust: 2.0,
                ..VehicleState::default()
            },
            psi_cmd: (t * 0.7).sin() * 3.0,
            speed_cmd: 0.5 + 0.1 * t.sin(),
            mode: "Transit".into(),
            ghost_depth: 0,
            target: P2::new(10.0, 0.0),
            nearest_m: nearest,
        }
    }

    /// Two vehicles, three obstacles (one moving), a few ghosts.
    pub fn run() -> RunOutput {
        let a: Vec<Sample> = (0..=100)
            .map(|i| {
                let t = i as f64 * 0.2;
                sample(t, t * 0.5, 2.0 * (t * 0.3).sin(), 3.0 - t * 0.1)
            })
            .collect();
        let b: Vec<Sample> = (0..=80)
            .map(|i| {
                let t = i as f64 * 0.2;
                sample(t, -2.0 + t * 0.4, -3.0 + t * 0.2, 2.0)
            })
            .collect();
        RunOutput {
            scenario_name: "two <vehicles> & rocks".into(),
            dt_s: 0.2,
            obstacles: vec![
                SimObstacle {
                    shape: SimShape::Circle {
                        center: P2::new(5.0, 0.5),
                        radius: 1.0,
                    },
                    velocity: P2::default(),
                },
                SimObstacle {
                    shape: SimShape::Rectangle {
                        center: P2::new(2.0, -4.0),
                        half_size: P2::new(1.5, 0.5),
                        angle: 0.4,
                    },
                    velocity: P2::new(0.1, 0.05),
                },
                SimObstacle {
                    shape: SimShape::Polygon {
                        points: vec![P2::new(7.0, 3.0), P2::new(9.0, 3.0), P2::new(8.0, 5.0)],
                    },
                    velocity: P2::default(),
                },
            ],
            vehicles: vec![
                VehicleRecord {
                    name: "alpha".into(),
                    goal: P2::new(10.0, 0.0),
                    samples: a,
                    ghosts: vec![P2::new(4.0, 3.0)],
                    step_costs: vec![100, 300, 200],
                    cost_unit: Some(vpf::link::CostUnit::Instructions),
                    ..VehicleRecord::default()
                },
                VehicleRecord {
                    name: "beta".into(),
                    goal: P2::new(8.0, 1.0),
                    samples: b,
                    ..VehicleRecord::default()
                },
            ],
            firmware: "host".into(),
            arrival_radius_m: 1.0,
            params: vpf::Params::default(),
            vehicles_known: false,
            current: P2::new(0.0, 0.2),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_names_are_safe_and_distinct() {
        let v = |n: &str| VehicleRecord {
            name: n.into(),
            ..VehicleRecord::default()
        };
        let names = file_names(&[v("a b"), v("a/b"), v(""), v("../x"), v("ok-1")]);
        assert_eq!(names, ["a_b", "a_b_2", "vehicle", "___x", "ok-1"]);
    }

    #[test]
    fn write_all_writes_every_file() {
        let dir = std::env::temp_dir().join(format!("hil-output-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let run = test_support::run();
        let summary = write_all(&dir, &run).unwrap();
        assert_eq!(summary.vehicles.len(), 2);
        for f in [
            "trajectory_alpha.csv",
            "trajectory_beta.csv",
            "metrics.json",
            "plot.svg",
            "commands.svg",
        ] {
            let len = std::fs::metadata(dir.join(f)).unwrap().len();
            assert!(len > 0, "{f} is empty");
        }
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("metrics.json")).unwrap())
                .unwrap();
        assert_eq!(json["scenario"], "two <vehicles> & rocks");
        assert_eq!(json["vehicles"][0]["name"], "alpha");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn write_all_with_nothing_in_it() {
        let dir = std::env::temp_dir().join(format!("hil-output-empty-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let run = RunOutput {
            scenario_name: String::new(),
            dt_s: f64::NAN,
            obstacles: vec![],
            vehicles: vec![VehicleRecord::default()],
            firmware: String::new(),
            arrival_radius_m: f64::NAN,
            params: vpf::Params::default(),
            vehicles_known: false,
            current: P2::new(f64::NAN, 0.0),
        };
        let s = write_all(&dir, &run).unwrap();
        assert!(!s.to_string().is_empty());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
