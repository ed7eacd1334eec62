//! Runs a scenario: one firmware per vehicle, the simulated world in between.
//!
//! Per period k (t = k·dt), for every vehicle: sample its navigation sensors and send `Nav`,
//! send the sonar pings that came due (or the contacts), and in lockstep send `Tick(t)`; then
//! collect each firmware's command for t, step each vehicle model by dt tracking it, and record.
//! In lockstep the same scenario and seed give the same outputs, bit for bit, as fast as the
//! firmware answers. In real time the firmware keeps its own clock, the loop is paced by the
//! wall clock, and each vehicle follows the newest command it has.
//!
//! The vehicles do not talk to each other: each firmware sees the others only through its sonar
//! (or contacts), and as agents for formation keeping when the scenario gives a formation.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use vpf::link::{ContactList, ContactsRepr, Message, NavRepr, TickRepr};
use vpf::planner::NavState;

use crate::faults::{FaultCounts, FaultTap};
use crate::firmware::{self, Firmware, Reply, Target};
use crate::output::{self, FrameLog, RunOutput, Summary};
use crate::ping360::sim::{self as ping360_sim, SimPing360};
use crate::scenario::{RunMode, Scenario, Sensing, SonarInterface, Window};
use crate::sim::contacts::{self, OtherVehicle};
use crate::sim::nav::{NavConfig, NavSensor};
use crate::sim::sonar::{Sonar, SonarConfig};
use crate::sim::vehicle::{new_model, ModelKind, VehicleModel};
use crate::types::{SetPoints, VehicleRecord, VehicleState, WaypointMark, P2};
use crate::upload::{self, Uploader};

/// How long to wait for a period's command before sending its `Tick` again (a Tick lost to a
/// link fault is otherwise never answered): the emulated board or a real one over a serial
/// adapter.
pub const TICK_RETRY: Duration = Duration::from_millis(200);
/// The same for the host-process firmware, which answers in well under a millisecond: under
/// bit errors a quarter of the Ticks are lost, and 200 ms each would make a run's wall time.
/// A Tick sent again to a firmware that was only slow is harmless: the period is answered
/// once and its command repeated.
pub const TICK_RETRY_HOST: Duration = Duration::from_millis(25);
/// How many times a `Tick` is sent before the firmware is given up on.
pub const TICK_ATTEMPTS: u32 = 200;

/// Radius of a vehicle's hull for clearance and collisions, m (a kinematic vehicle is a
/// point, as in seed 000; a VideoRay Pro III is about 0.36 m × 0.22 m). The flat-fish AUV
/// (4.5 m × 1.46 m) gets half its length, the circle that contains the hull at any heading:
/// a contact is never missed, at the price of counting a pass abeam closer than ≈ 1.5 m to its
/// side as one (the hull is a circle for the other vehicles' sonars and planners too).
pub fn hull_radius(model: ModelKind) -> f64 {
    match model {
        ModelKind::Kinematic => 0.0,
        ModelKind::VideoRay => 0.2,
        ModelKind::FlatFish => 0.5 * crate::sim::flatfish::FLATFISH_LENGTH_M,
    }
}

/// The radius a model turns on at its cruise speed with the heading autopilot at its limit, m
/// (0: it turns on the spot): what a world must leave room for (`crate::bench::turning`).
pub fn turning_radius(model: ModelKind) -> f64 {
    match model {
        ModelKind::Kinematic | ModelKind::VideoRay => 0.0,
        ModelKind::FlatFish => crate::sim::flatfish::FLATFISH_TURN_RADIUS_M,
    }
}

/// How to run.
#[derive(Clone, Debug)]
pub struct RunConfig {
    /// Which firmware.
    pub target: Target,
    /// Where the outputs go.
    pub out_dir: PathBuf,
    /// Show a progress bar on a terminal.
    pub progress: bool,
}

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// Building, starting or talking to a firmware failed.
    #[error("firmware: {0}")]
    Firmware(#[from] std::io::Error),
    /// The simulated Ping360 cannot be what the scenario's `[sonar]` asks, or what the board
    /// is built for.
    #[error("firmware: [sonar] {key}: {message}")]
    Ping360 {
        /// The `[sonar]` key at fault.
        key: &'static str,
        /// Why.
        message: String,
    },
    /// A simulated Ping360 asked of a real board (`--port`), whose sonar UART is wired to a
    /// real one.
    #[error(
        "firmware: a simulated Ping360 needs --firmware host or qemu (a board's sonar UART is \
         wired to a real one)"
    )]
    Ping360OnBoard,
    /// The firmware refused the scenario's parameters or mission.
    #[error(transparent)]
    Refused(#[from] crate::upload::Rejected),
    /// Writing the outputs failed.
    #[error("writing outputs: {0}")]
    Output(std::io::Error),
}

fn ping360_err((key, message): (&'static str, String)) -> RunError {
    RunError::Ping360 { key, message }
}

/// One simulated vehicle and its firmware.
struct SimVehicle {
    model: Box<dyn VehicleModel>,
    kind: ModelKind,
    nav: NavSensor,
    sonar: Sonar,
    sensing: Sensing,
    fw: Firmware,
    tap: FaultTap,
    record: VehicleRecord,
    setpoints: SetPoints,
    /// `Tick`s sent again because no command came back in time.
    tick_retries: u32,
    /// Of those, the ones whose first sending was answered after all (a second command for the
    /// same period came back): the firmware was slow, nothing was lost.
    ticks_slow: u32,
    /// The last period whose `Tick` was sent again, while its answers are still counted.
    resent: Option<u64>,
    /// Navigation samples waiting out the configured delay: (due time, sample).
    delayed: std::collections::VecDeque<(f64, NavState)>,
    frozen: Option<NavState>,
    /// The simulated Ping360 on its own port, its fault tap, and the commands the firmware's
    /// last telemetry counted (`[sonar] interface = "ping360"`).
    ping360: Option<(SimPing360, FaultTap, u32)>,
    /// The set-up requests (parameters, mission) on their way.
    upload: Uploader,
}

/// The result of a run: what was written, and the fault counts per vehicle.
pub struct RunResult {
    /// Everything recorded.
    pub output: RunOutput,
    /// The per-vehicle metrics and the printable summary.
    pub summary: Summary,
    /// Link faults injected, per vehicle.
    pub faults: Vec<FaultCounts>,
    /// `Tick`s sent again per vehicle (a lost Tick, or a slow firmware).
    pub tick_retries: Vec<u32>,
    /// Per vehicle with a simulated Ping360: what it did, and the faults on its port.
    pub ping360: Vec<Option<(ping360_sim::SimCounts, FaultCounts)>>,
    /// Of those, per vehicle, the ones the firmware had only been slow to answer (the period
    /// was answered twice); the rest were lost on the link.
    pub ticks_slow: Vec<u32>,
}

/// How [`run_quiet`] runs a scenario: the many short runs of a parameter sweep.
#[derive(Clone, Debug)]
pub struct QuietRun {
    /// Which firmware.
    pub target: Target,
    /// The firmware binary, built once by the caller ([`firmware::build`]).
    pub binary: PathBuf,
    /// End the run at the first period where a vehicle has collided (negative clearance) or
    /// every vehicle is within `arrival_radius_m` of its goal, instead of at `duration_s`.
    pub stop_early: bool,
    /// The host-process firmware on a Unix socket pair instead of a pty
    /// ([`Firmware::start_host_socket`]); other targets ignore it.
    pub socket: bool,
    /// In lockstep, the host firmware's runtime in this process instead of a process
    /// ([`Firmware::in_process`]: the same code, no wake-up or system call per period); other
    /// targets ignore it.
    pub in_process: bool,
}

impl QuietRun {
    /// The benchmark's and the fault campaign's runs: the host-process firmware (built here)
    /// on a socket pair, each run ended at arrival or first contact.
    pub fn host_until_done() -> std::io::Result<QuietRun> {
        Ok(QuietRun {
            target: Target::Host,
            binary: firmware::build(&Target::Host)?,
            stop_early: true,
            socket: true,
            in_process: true,
        })
    }
}

/// Runs `sc` and writes its outputs to `cfg.out_dir`, which is checked writable first (before
/// the firmware is built or a vehicle flies).
pub fn run(sc: &Scenario, cfg: &RunConfig) -> Result<RunResult, RunError> {
    output::prepare_dir(&cfg.out_dir).map_err(RunError::Output)?;
    let binary = firmware::build(&cfg.target)?;
    let how = RunOptions {
        log_dir: Some(&cfg.out_dir),
        progress: cfg.progress,
        stop_early: false,
        socket: false,
        in_process: false,
    };
    let sim = simulate(sc, &cfg.target, &binary, &how)?;
    let summary = output::write_all(&cfg.out_dir, &sim.output).map_err(RunError::Output)?;
    Ok(RunResult {
        output: sim.output,
        summary,
        faults: sim.faults,
        tick_retries: sim.tick_retries,
        ping360: sim.ping360,
        ticks_slow: sim.ticks_slow,
    })
}

/// Runs `sc` without writing anything (no frame logs, no outputs, no progress bar) on a
/// firmware built beforehand, and returns what was recorded; the metrics are
/// [`Summary::of`] the result. The sweep's run mode (`hil sweep`).
pub fn run_quiet(sc: &Scenario, q: &QuietRun) -> Result<RunOutput, RunError> {
    let how = RunOptions {
        log_dir: None,
        progress: false,
        stop_early: q.stop_early,
        socket: q.socket,
        in_process: q.in_process,
    };
    simulate(sc, &q.target, &q.binary, &how).map(|s| s.output)
}

/// How [`simulate`] runs: frame logs into `log_dir` if given, a progress bar if `progress`,
/// the end at arrival or collision if `stop_early`, the host firmware on a socket if `socket`
/// (in this process if `in_process`).
struct RunOptions<'a> {
    log_dir: Option<&'a std::path::Path>,
    progress: bool,
    stop_early: bool,
    socket: bool,
    in_process: bool,
}

/// What [`simulate`] recorded.
struct Simulated {
    output: RunOutput,
    faults: Vec<FaultCounts>,
    tick_retries: Vec<u32>,
    ping360: Vec<Option<(ping360_sim::SimCounts, FaultCounts)>>,
    ticks_slow: Vec<u32>,
}

/// The run itself.
fn simulate(
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
        s.upload.send(&mut s.fw, 0)?;
    }

    let steps = (sc.duration_s / sc.dt_s).round().max(1.0) as u64;
    let started = Instant::now();
    let bar = progress_bar(
        steps,
        how.progress && std::io::stderr().is_terminal(),
        "t = {msg} s",
    );
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
                s.upload.send(&mut s.fw, k)?;
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
        if how.stop_early && finished(&sims, f64::from(params.arrival_radius_m)) {
            break;
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
    };
    Ok(Simulated {
        output,
        faults,
        tick_retries,
        ping360,
        ticks_slow,
    })
}

/// Whether a run can end early: a vehicle has collided at the last sample, or every vehicle's
/// last sample is within `arrival_radius_m` of its goal (a waypoint mission: every waypoint
/// reached, in order).
fn finished(sims: &[SimVehicle], arrival_radius_m: f64) -> bool {
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
    collided || arrived
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

/// Sends this period's navigation and sonar, with the scenario's sensor faults. A Ping360 of
/// its own is served first, while the main link is quiet (`crate::ping360::sim` says why).
fn send_sensors(
    s: &mut SimVehicle,
    sc: &Scenario,
    t: f64,
    truth: &VehicleState,
    others: &[OtherVehicle],
) -> Result<(), RunError> {
    let t_ms = (t * 1000.0).round() as u64;
    let in_window = |w: &Option<Window>| w.as_ref().is_some_and(|w| w.contains(t));
    if let Some((p, tap, expected)) = s.ping360.as_mut() {
        let lockstep = sc.mode == RunMode::Lockstep;
        let hulls: Vec<(P2, f64)> = others.iter().map(|o| (o.position, o.hull_radius)).collect();
        tap.t = t;
        p.sync(*expected, (t - sc.dt_s).max(0.0), lockstep)?;
        p.answer(
            t,
            truth,
            &sc.obstacles,
            &hulls,
            &mut s.sonar,
            tap,
            lockstep,
            in_window(&sc.faults.sonar_dropout),
        )?;
    }
    let fresh = s.nav.sample(t, truth);
    let nav = if in_window(&sc.faults.nav_freeze) {
        *s.frozen.get_or_insert(fresh)
    } else {
        s.frozen = None;
        fresh
    };
    s.delayed
        .push_back((t + sc.faults.nav_delay_ms / 1000.0, nav));
    let mut latest = None;
    while s.delayed.front().is_some_and(|(due, _)| *due <= t + 1e-9) {
        latest = s.delayed.pop_front().map(|(_, n)| n);
    }
    if let (Some(nav), false) = (latest, in_window(&sc.faults.nav_loss)) {
        let m = Message::Nav(NavRepr {
            time_ms: t_ms,
            nav,
            body: None,
        });
        s.fw.send(&m, &mut s.tap)?;
    }
    if in_window(&sc.faults.sonar_dropout) {
        return Ok(());
    }
    match s.sensing {
        Sensing::Sonar if s.ping360.is_some() => {
            if sc.sonar.vehicle_contacts {
                send_contacts(s, t, t_ms, truth, &[], others, sc.sonar.range_m)?;
            }
        }
        Sensing::Sonar => {
            let hulls: Vec<(P2, f64)> =
                others.iter().map(|o| (o.position, o.hull_radius)).collect();
            for ping in s.sonar.poll(t, truth, &sc.obstacles, &hulls) {
                s.fw.send(&Message::Scanline(ping.as_scanline()), &mut s.tap)?;
            }
            if sc.sonar.vehicle_contacts {
                send_contacts(s, t, t_ms, truth, &[], others, sc.sonar.range_m)?;
            }
        }
        Sensing::Contacts => {
            send_contacts(s, t, t_ms, truth, &sc.obstacles, others, sc.sonar.range_m)?
        }
    }
    Ok(())
}

/// Sends the obstacles and vehicles within `range` m as contacts.
fn send_contacts(
    s: &mut SimVehicle,
    t: f64,
    t_ms: u64,
    truth: &VehicleState,
    obstacles: &[crate::types::SimObstacle],
    others: &[OtherVehicle],
    range: f64,
) -> Result<(), RunError> {
    let found = contacts::contacts(t, truth, obstacles, others, range);
    for chunk in found.chunks(vpf::link::MAX_CONTACTS) {
        let m = Message::Contacts(ContactsRepr {
            time_ms: t_ms,
            contacts: ContactList::new(chunk),
        });
        s.fw.send(&m, &mut s.tap)?;
    }
    Ok(())
}

/// Collects the firmware's answer for this period and records it.
fn collect(s: &mut SimVehicle, mode: RunMode, t_ms: u64) -> Result<(), RunError> {
    let got = match mode {
        RunMode::Lockstep => {
            let mut attempt = 1;
            loop {
                let answered = |inbox: &[Reply]| {
                    inbox
                        .iter()
                        .any(|r| matches!(r, Reply::Command(c) if c.time_ms == t_ms))
                };
                let wait = if s.fw.target == Target::Host {
                    TICK_RETRY_HOST
                } else {
                    TICK_RETRY
                };
                match s.fw.receive_until(wait, &mut s.tap, answered) {
                    Ok(got) => break got,
                    Err(e)
                        if e.kind() == std::io::ErrorKind::TimedOut && attempt < TICK_ATTEMPTS =>
                    {
                        attempt += 1;
                        s.tick_retries += 1;
                        s.resent = Some(t_ms);
                        s.fw.send(&Message::Tick(TickRepr { time_ms: t_ms }), &mut s.tap)?;
                    }
                    Err(e) => return Err(e.into()),
                }
            }
        }
        RunMode::Realtime => s.fw.receive_until(Duration::ZERO, &mut s.tap, |_| true)?,
    };
    if let Some(resent) = s.resent {
        // A period whose Tick went out twice and came back answered twice (now, or with the
        // next period's answers) had only been slow; once, and a Tick was lost.
        let answers = got
            .iter()
            .filter(|r| matches!(r, Reply::Command(c) if c.time_ms == resent))
            .count();
        if answers >= 2 || (answers == 1 && resent != t_ms) {
            s.ticks_slow += 1;
        }
        if answers >= 2 || resent != t_ms {
            s.resent = None;
        }
    }
    for r in &got {
        match r {
            // A rejected set-up request ends the run; a busy one goes again.
            Reply::Reply(rep) => s.upload.on_reply(rep)?,
            Reply::Belief(c) => {
                let position = s.model.state().position;
                s.record.belief.apply(c, t_ms as f64 * 1e-3, position);
            }
            Reply::Telemetry(tel) => {
                if let Some((_, _, expected)) = s.ping360.as_mut() {
                    *expected = tel.ping360.commands;
                }
                s.record.telemetry = Some(*tel);
                s.record.cost_unit = Some(tel.cost_unit);
                if tel.step_cost > 0 {
                    s.record.step_costs.push(tel.step_cost);
                }
            }
            _ => {}
        }
    }
    let command = got.iter().rev().find_map(|r| match r {
        Reply::Command(c) => Some(c.command),
        _ => None,
    });
    if let Some(c) = command {
        let sp = &c.setpoints;
        s.setpoints = SetPoints {
            psi: f64::from(c.psi_set),
            speed: f64::from(c.v_set),
            velocity: P2::new(f64::from(c.velocity.x), f64::from(c.velocity.y)),
            pid: crate::types::PidFeeds {
                a_c: f64::from(sp.a_c),
                v_c: f64::from(sp.v_c),
                i_surge: f64::from(sp.i_surge),
                alpha_c: f64::from(sp.alpha_c),
                omega_c: f64::from(sp.omega_c),
                phi_c: f64::from(sp.phi_c),
            },
        };
        let target = P2::new(f64::from(c.target.x), f64::from(c.target.y));
        if target.sub(s.record.goal).norm() > 0.5
            && !s.record.ghosts.iter().any(|g| g.sub(target).norm() < 0.5)
            && c.ghost_depth > 0
        {
            s.record.ghosts.push(target);
        }
        // Time, state and clearance are filled in by the caller.
        s.record.samples.push(crate::types::Sample {
            t: 0.0,
            state: VehicleState::default(),
            psi_cmd: f64::from(c.psi_set),
            speed_cmd: f64::from(c.v_set),
            mode: format!("{:?}", c.mode),
            ghost_depth: c.ghost_depth,
            target,
            nearest_m: f64::INFINITY,
        });
    } else if let Some(prev) = s.record.samples.last().cloned() {
        // Real time, nothing new: the vehicle keeps following the last command.
        s.record.samples.push(prev);
    }
    Ok(())
}

/// True clearance: distance from the hull to the nearest obstacle surface or other hull.
fn nearest(
    sc: &Scenario,
    t: f64,
    state: &VehicleState,
    hull: f64,
    others: &[(P2, f64)],
    me: usize,
) -> f64 {
    let p = state.position;
    let obstacles = sc.obstacles.iter().map(|o| o.signed_distance(t, p) - hull);
    let vehicles = others
        .iter()
        .enumerate()
        .filter(|(j, _)| *j != me)
        .map(|(_, (q, r))| q.sub(p).norm() - hull - r);
    obstacles.chain(vehicles).fold(f64::INFINITY, f64::min)
}

/// A progress bar on stderr (`[####    ]  42%  {what}`) for `total` steps, redrawn in place
/// (at most 20 times a second) if `show`, hidden otherwise; `what` is an indicatif template
/// after the percentage, which may also use `{rate}` (steps per second) and `{left}` (the
/// estimated time left, `1:02:03`). Shared by `hil run` and `hil sweep`; [`end_progress`]
/// ends its line.
pub fn progress_bar(total: u64, show: bool, what: &str) -> indicatif::ProgressBar {
    use indicatif::{ProgressState, ProgressStyle};
    if !show {
        return indicatif::ProgressBar::hidden();
    }
    let style = ProgressStyle::with_template(&format!("[{{bar:40}}] {{percent:>3}}%  {what}"))
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("## ")
        .with_key("rate", |s: &ProgressState, w: &mut dyn std::fmt::Write| {
            let _ = write!(w, "{:.1}", s.per_sec());
        })
        .with_key("left", |s: &ProgressState, w: &mut dyn std::fmt::Write| {
            let _ = write!(w, "{}", crate::sweep::pool::clock(s.eta().as_secs_f64()));
        });
    indicatif::ProgressBar::new(total).with_style(style)
}

/// Leaves the bar as it is and ends its line.
pub fn end_progress(bar: &indicatif::ProgressBar) {
    if !bar.is_hidden() {
        bar.abandon();
        eprintln!();
    }
}
