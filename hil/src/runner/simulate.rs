//! The run itself: each vehicle's model, sensors and firmware set up (its link, its Ping360 if
//! it has one, its set-up requests), then period by period until the end or an early finish.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use vpf::link::{Message, TickRepr};
use vpf::planner::NavState;

use crate::faults::FaultTap;
use crate::firmware::{self, Firmware, Reply, Target};
use crate::output::{self, FrameLog, RunOutput};
use crate::ping360::sim::{self as ping360_sim, SimPing360};
use crate::scenario::{RunMode, Scenario, Sensing, SonarInterface};
use crate::sim::contacts::OtherVehicle;
use crate::sim::nav::{NavConfig, NavSensor};
use crate::sim::sonar::{Sonar, SonarConfig};
use crate::sim::vehicle::{new_model, ModelKind, VehicleModel};
use crate::types::{SetPoints, VehicleRecord, WaypointMark, P2};
use crate::upload::{self, Uploader};

use super::exchange::{collect, nearest, send_sensors};
use super::{
    end_progress, hull_radius, ping360_err, progress_bar, RunError, RunOptions, Simulated,
};

/// One simulated vehicle and its firmware.
pub(super) struct SimVehicle {
    pub(super) model: Box<dyn VehicleModel>,
    pub(super) kind: ModelKind,
    pub(super) nav: NavSensor,
    pub(super) sonar: Sonar,
    pub(super) sensing: Sensing,
    pub(super) fw: Firmware,
    pub(super) tap: FaultTap,
    pub(super) record: VehicleRecord,
    pub(super) setpoints: SetPoints,
    /// `Tick`s sent again because no command came back in time.
    pub(super) tick_retries: u32,
    /// Of those, the ones whose first sending was answered after all (a second command for the
    /// same period came back): the firmware was slow, nothing was lost.
    pub(super) ticks_slow: u32,
    /// The last period whose `Tick` was sent again, while its answers are still counted.
    pub(super) resent: Option<u64>,
    /// Navigation samples waiting out the configured delay: (due time, sample).
    pub(super) delayed: std::collections::VecDeque<(f64, NavState)>,
    pub(super) frozen: Option<NavState>,
    /// The simulated Ping360 on its own port, its fault tap, and the commands the firmware's
    /// last telemetry counted (`[sonar] interface = "ping360"`).
    pub(super) ping360: Option<(SimPing360, FaultTap, u32)>,
    /// The set-up requests (parameters, mission) on their way.
    pub(super) upload: Uploader,
}

/// The run itself.
pub(super) fn simulate(
    sc: &Scenario,
    target: &Target,
    binary: &std::path::Path,
    how: &RunOptions<'_>,
) -> Result<Simulated, RunError> {
    let mut params = sc.params;
    params.period_s = sc.dt_s as f32;

    let mut sims = Vec::new();
    for (i, v) in sc.vehicles.iter().enumerate() {
        let lockstep = sc.mode == RunMode::Lockstep;
        let seed = sc.seed.wrapping_add(1000 * i as u64);
        // A Ping360 of its own: for the host-process firmware a pty whose slave it opens as its
        // sonar port; on QEMU the board's UART1, QEMU's second serial port.
        let mut extra = Vec::new();
        let mut ping360_port = None;
        let ping360 = sc.sonar.interface == SonarInterface::Ping360 && v.sensing == Sensing::Sonar;
        let mut ping360_cfg = None;
        if ping360 {
            let cfg = ping360_sim::firmware_config(&sc.sonar).map_err(ping360_err)?;
            match target {
                Target::Host => {
                    let (master, slave) = firmware::open_pty()?;
                    extra = ping360_sim::firmware_args(&slave, &cfg);
                    ping360_port = Some(master);
                }
                Target::Qemu | Target::QemuUart => {
                    ping360_sim::board_config_matches(&cfg).map_err(ping360_err)?
                }
                Target::Port(..) => return Err(RunError::Ping360OnBoard),
            }
            ping360_cfg = Some(cfg);
        }
        // In process only without a Ping360 port (that one is the process's own serial port).
        let mut fw = if how.in_process && lockstep && *target == Target::Host && extra.is_empty() {
            Firmware::in_process()
        } else if how.socket && *target == Target::Host {
            Firmware::start_host_socket(binary, &extra)
        } else if *target == Target::Qemu {
            Firmware::start_qemu_ethernet(binary, lockstep, ping360)
        } else if *target == Target::QemuUart {
            Firmware::start_qemu(binary, lockstep, ping360)
        } else {
            Firmware::start(target, binary, lockstep, &extra)
        }?;
        if matches!(target, Target::Qemu | Target::QemuUart) && ping360 {
            ping360_port = fw.take_sonar_port();
        }
        let ping360_port = ping360_port.zip(ping360_cfg);
        if how.stop_early && lockstep {
            // The sweep's runs: one write per period (see `Firmware::set_batching`).
            fw.set_batching(true)?;
        }
        let log = match how.log_dir {
            Some(dir) => Some(FrameLog::create(dir, &v.name).map_err(RunError::Output)?),
            None => None,
        };
        let nav = NavSensor::new(NavConfig {
            position_sigma_m: sc.navigation.position_sigma_m,
            heading_sigma_rad: sc.navigation.heading_sigma,
            velocity_sigma: 0.0,
            rate_hz: sc.navigation.rate_hz,
            seed,
        });
        let sonar = Sonar::new(SonarConfig {
            range_m: sc.sonar.range_m,
            bins: usize::from(sc.sonar.bins),
            step_deg: sc.sonar.step.to_degrees(),
            // The sonar's background is exponential with this mean; past ~30 it floods every bin.
            noise_level: sc.sonar.noise * 30.0,
            speckle_prob: sc.sonar.speckle,
            rays_per_beam: sc.sonar.beam_rays,
            false_echo_prob: sc.sonar.false_echoes,
            seed: seed.wrapping_add(7),
            ..SonarConfig::default()
        });
        let ping360 = match ping360_port {
            Some((master, cfg)) => {
                let raw = how
                    .log_dir
                    .map(|d| d.join(format!("ping360_{}.bin", output::file_stem(&v.name))));
                let sim =
                    SimPing360::new(master, cfg, sonar.config().ping_overhead_s, raw.as_deref())
                        .map_err(RunError::Output)?;
                let tap = FaultTap::new(
                    sc.faults.ping360_bit_error_rate,
                    sc.faults.ping360_drop_rate,
                    seed.wrapping_add(17),
                    None,
                );
                Some((sim, tap, 0))
            }
            None => None,
        };
        sims.push(SimVehicle {
            model: new_model(v.model, v.start, v.heading, v.autopilot),
            kind: v.model,
            nav,
            sonar,
            sensing: v.sensing,
            fw,
            tap: FaultTap::new(
                sc.faults.bit_error_rate,
                sc.faults.drop_rate,
                seed.wrapping_add(13),
                log,
            ),
            record: VehicleRecord {
                name: v.name.clone(),
                goal: v.goal,
                waypoints: marks(v),
                ping360: ping360.is_some(),
                hull_m: hull_radius(v.model),
                ..VehicleRecord::default()
            },
            setpoints: SetPoints {
                psi: v.heading,
                ..SetPoints::default()
            },
            tick_retries: 0,
            ticks_slow: 0,
            resent: None,
            delayed: Default::default(),
            frozen: None,
            ping360,
            upload: Uploader::new(upload::requests(
                params,
                v.goal,
                v.mission.as_ref(),
                v.formation,
            )),
        });
    }

    // Lockstep starts before anything else: a first `Tick` stops the firmware's own clock from
    // running periods between the set-up messages and the first planned period (which would
    // make the run depend on timing). Its command (a hold: no mission, no navigation yet) is
    // discarded.
    if sc.mode == RunMode::Lockstep {
        for s in sims.iter_mut() {
            let mut clean = crate::firmware::NoTap;
            s.fw.send(&Message::Tick(TickRepr { time_ms: 0 }), &mut clean)?;
            // With a Ping360, its telemetry too (it counts the commands sent).
            let ping360 = s.ping360.is_some();
            let got =
                s.fw.receive_until(Duration::from_secs(10), &mut clean, |inbox| {
                    inbox.iter().any(|r| match r {
                        Reply::Command(c) => !ping360 && c.time_ms == 0,
                        Reply::Telemetry(t) => ping360 && t.time_ms == 0,
                        _ => false,
                    })
                })?;
            // The Ping360's first command went out in that period: how many to read.
            if let Some((p, _, expected)) = s.ping360.as_mut() {
                p.tick(0);
                for r in &got {
                    if let Reply::Telemetry(t) = r {
                        *expected = t.ping360.commands;
                    }
                }
            }
        }
    }
    // Parameters and missions go out next; the firmware answers them at its next period. A
    // waypoint mission's items follow as the replies come (`upload`).
    for s in sims.iter_mut() {
        s.upload.send(&mut s.fw, 0, &mut s.tap.clean())?;
    }

    let steps = (sc.duration_s / sc.dt_s).round().max(1.0) as u64;
    let started = Instant::now();
    let bar = progress_bar(
        steps,
        how.progress && std::io::stderr().is_terminal(),
        "t = {msg} s",
    );
    // When every vehicle had first arrived (the hold's clock, `RunOptions::hold_s`).
    let mut arrived_at: Option<f64> = None;
    for k in 0..steps {
        let t = k as f64 * sc.dt_s;
        let t_ms = (t * 1000.0).round() as u64;
        let fleet: Vec<OtherVehicle> = sims
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let st = s.model.state();
                OtherVehicle {
                    // Vehicle contact ids sit above the obstacles' (one per obstacle index).
                    id: 0x8000 + i as u16,
                    position: st.position,
                    velocity: st.velocity,
                    hull_radius: hull_radius(s.kind),
                }
            })
            .collect();
        for (i, s) in sims.iter_mut().enumerate() {
            s.tap.t = t;
            let truth = s.model.state();
            let others: Vec<OtherVehicle> = fleet
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, o)| *o)
                .collect();
            send_sensors(s, sc, t, &truth, &others)?;
            if sc.mode == RunMode::Lockstep {
                s.fw.send(&Message::Tick(TickRepr { time_ms: t_ms }), &mut s.tap)?;
            }
            if let Some((p, _, _)) = s.ping360.as_mut() {
                p.tick(t_ms);
            }
        }
        if sc.mode == RunMode::Realtime {
            let due = Duration::from_secs_f64(t + sc.dt_s);
            if let Some(wait) = due.checked_sub(started.elapsed()) {
                std::thread::sleep(wait);
            }
        }
        let hulls: Vec<(P2, f64)> = fleet.iter().map(|o| (o.position, o.hull_radius)).collect();
        for (i, s) in sims.iter_mut().enumerate() {
            collect(s, sc.mode, t_ms)?;
            if !s.upload.done() {
                s.upload.send(&mut s.fw, k, &mut s.tap.clean())?;
            }
            let state = s.model.state();
            let near = nearest(sc, t, &state, hull_radius(s.kind), &hulls, i);
            if let Some(last) = s.record.samples.last_mut() {
                last.t = t;
                last.state = state;
                last.nearest_m = near;
            }
            let next = s.record.waypoints.get(s.record.waypoints_reached);
            if next.is_some_and(|m| state.position.sub(m.position).norm() <= m.radius_m) {
                s.record.waypoints_reached += 1;
            }
            s.model.step(sc.dt_s, &s.setpoints, sc.current.velocity);
        }
        if !bar.is_hidden() && (k % 50 == 0 || k + 1 == steps) {
            bar.set_position(k + 1);
            bar.set_message(format!("{t:7.1}"));
        }
        if how.stop_early {
            let (collided, arrived) = finished(&sims, f64::from(params.arrival_radius_m));
            if arrived {
                arrived_at.get_or_insert(t);
            }
            if collided || arrived_at.is_some_and(|a| t - a >= how.hold_s) {
                break;
            }
        }
    }
    end_progress(&bar);

    for s in sims.iter_mut() {
        if let Some((p, _, _)) = s.ping360.as_mut() {
            p.finish().map_err(RunError::Output)?;
        }
    }
    let faults = sims.iter().map(|s| s.tap.counts).collect();
    let tick_retries = sims.iter().map(|s| s.tick_retries).collect();
    let ping360 = sims
        .iter()
        .map(|s| s.ping360.as_ref().map(|(p, tap, _)| (p.counts, tap.counts)))
        .collect();
    let ticks_slow = sims.iter().map(|s| s.ticks_slow).collect();
    let vehicles: Vec<VehicleRecord> = sims.into_iter().map(|s| s.record).collect();
    let output = RunOutput {
        scenario_name: sc.name.clone(),
        dt_s: sc.dt_s,
        obstacles: sc.obstacles.clone(),
        vehicles,
        firmware: target.to_string(),
        arrival_radius_m: f64::from(params.arrival_radius_m),
        params,
        vehicles_known: sc.sonar.vehicle_contacts,
        current: sc.current.velocity,
    };
    Ok(Simulated {
        output,
        faults,
        tick_retries,
        ping360,
        ticks_slow,
    })
}

/// Whether, at the last sample, a vehicle has collided, and whether every vehicle is within
/// `arrival_radius_m` of its goal (a waypoint mission: every waypoint reached, in order): the
/// run can end early.
fn finished(sims: &[SimVehicle], arrival_radius_m: f64) -> (bool, bool) {
    let last = |s: &SimVehicle| s.record.samples.last().cloned();
    let collided = sims
        .iter()
        .any(|s| last(s).is_some_and(|x| x.nearest_m < 0.0));
    let arrived = sims.iter().all(|s| {
        if !s.record.waypoints.is_empty() {
            return s.record.waypoints_reached == s.record.waypoints.len();
        }
        last(s).is_some_and(|x| x.state.position.sub(s.record.goal).norm() <= arrival_radius_m)
    });
    (collided, arrived)
}

/// A vehicle's waypoints as the harness judges them (`WaypointMark`): empty for a single goal.
fn marks(v: &crate::scenario::Vehicle) -> Vec<WaypointMark> {
    let slack = v.formation.map_or(0.0, |f| f64::from(f.lattice_m));
    v.mission.as_ref().map_or_else(Vec::new, |m| {
        m.positions()
            .into_iter()
            .zip(m.waypoints.as_slice())
            .map(|(position, w)| WaypointMark {
                position,
                radius_m: f64::from(w.radius_m()) + slack,
            })
            .collect()
    })
}
