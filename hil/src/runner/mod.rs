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

//!
//! - `simulate.rs`: the run itself — each vehicle's firmware started and set up, then the
//!   periods; `exchange.rs`: what one period sends each firmware and collects from it;
//!   `progress.rs`: the progress bar (shared with the worker pool).

use std::path::PathBuf;
use std::time::Duration;

use crate::faults::FaultCounts;
use crate::firmware::{self, Target};
use crate::output::{self, RunOutput, Summary};
use crate::ping360::sim as ping360_sim;
use crate::scenario::Scenario;
use crate::sim::vehicle::ModelKind;

mod exchange;
mod progress;
mod simulate;

pub use progress::{end_progress, progress_bar};
use simulate::simulate;

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
    /// With `stop_early`, how long every vehicle must have been arrived before the run ends,
    /// s (0: at once): the time it must hold there (a berth, `crate::bench::worlds`).
    pub hold_s: f64,
    /// The host-process firmware on a Unix socket pair instead of a pty
    /// ([`Firmware::start_host_socket`](crate::firmware::Firmware::start_host_socket)); other targets ignore it.
    pub socket: bool,
    /// In lockstep, the host firmware's runtime in this process instead of a process
    /// ([`Firmware::in_process`](crate::firmware::Firmware::in_process): the same code, no wake-up or system call per period); other
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
            hold_s: 0.0,
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
        hold_s: 0.0,
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
        hold_s: q.hold_s,
        socket: q.socket,
        in_process: q.in_process,
    };
    simulate(sc, &q.target, &q.binary, &how).map(|s| s.output)
}

/// How [`simulate`] runs: frame logs into `log_dir` if given, a progress bar if `progress`,
/// the end at arrival (held for `hold_s`) or collision if `stop_early`, the host firmware on
/// a socket if `socket` (in this process if `in_process`).
struct RunOptions<'a> {
    log_dir: Option<&'a std::path::Path>,
    progress: bool,
    stop_early: bool,
    hold_s: f64,
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
