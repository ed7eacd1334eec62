//! `hil`: run a scenario against the VPF firmware.
//!
//! ```text
//! hil run SCENARIO.toml [--out DIR] [--firmware qemu|qemu-uart|host] [--port /dev/ttyXXX [--baud N]]
//!         [--quiet]
//!         [--bit-error-rate X] [--drop-rate X] [--nav-delay-ms X]
//!         [--nav-freeze FROM:TO] [--nav-loss FROM:TO] [--sonar-dropout FROM:TO]
//!         [--ping360-bit-error-rate X] [--ping360-drop-rate X]
//! hil check SCENARIO.toml...
//! hil sweep SPEC.toml [--out DIR] [--jobs N] [--shard K/N] [--quiet]
//! hil merge DIR... [--out DIR]
//! hil compare [SCENARIO.toml...] [--strategies vpf,multipoint,navfn] [--firmware host|qemu]
//! hil bench [--families ...] [--seeds N] [--strategies ...] [--models ...] [--sensing ...]
//! hil beliefs FRAMES.log --at T1,T2,... [--radius M] [--cells] [--tracks]
//! hil echoes RUN_DIR --between T0,T1 (--towards V | --point X,Y) [--vehicle V] [--within DEG] [--all]
//! hil sonar-replay --ping360 FILE [--plot FILE.svg] [detection options]
//! hil ping360-raw DUMP.txt OUT.bin
//! ```
//!
//! `hil run` also takes `--params RECIPE.toml` (a `[planner]` table, as `hil sweep` writes).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{CommandFactory as _, FromArgMatches as _, Parser, Subcommand};
use hil::firmware::Target;
use hil::runner::{run, RunConfig};
use hil::scenario::{self, Scenario, Window};

/// `hil`'s command line.
#[derive(Parser)]
#[command(
    name = "hil",
    about = "The host-side hardware-in-the-loop harness: simulated vehicles and sonars against the \
             VPF firmware.",
    after_help = "Scenario files: hil/scenarios/README.md. Outputs: trajectory_*.csv, \
                  metrics.json, plot.svg, commands.svg, frames_*.log."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    #[command(about = "run a scenario, write outputs to --out (default runs/NAME-TIME)")]
    Run(RunArgs),
    #[command(about = "validate scenario files")]
    Check(CheckArgs),
    #[command(about = "tune the planner's parameters over a scenario batch")]
    Sweep(hil::sweep::cli::SweepArgs),
    #[command(about = "combine a sweep's shards (hil sweep --help)")]
    Merge(hil::sweep::cli::MergeArgs),
    #[command(about = "fly scenarios with each strategy, print a table")]
    Compare(hil::compare::Args),
    #[command(about = "fly generated worlds, tabulate success and safety")]
    Bench(hil::bench::Args),
    #[command(
        name = "bench-diff",
        about = "two benches of the same worlds, run by run: what a change gained and lost"
    )]
    BenchDiff(hil::bench::diff::Args),
    #[command(about = "fly each scenario under each fault, print a table")]
    Faults(hil::campaign::Args),
    #[command(about = "what the firmware believed at given times of a run, from its frame log")]
    Beliefs(hil::beliefs::Args),
    #[command(
        about = "what a vehicle's sonar heard towards another vehicle or a point, from a run"
    )]
    Echoes(hil::echoes::Args),
    #[command(about = "raw Ping360 bytes through the firmware's parser and extractor")]
    SonarReplay(hil::ping360::replay::Args),
    #[command(
        name = "ping360-raw",
        about = "a brping text dump of device_data messages as raw Ping bytes"
    )]
    Ping360Raw(hil::ping360::replay::RawArgs),
}

/// `hil run`'s options.
#[derive(clap::Args)]
#[command(
    after_help = "Scenario files: hil/scenarios/README.md. Outputs: trajectory_*.csv, \
                        metrics.json, plot.svg, commands.svg, frames_*.log."
)]
struct RunArgs {
    /// the scenario file
    #[arg(value_name = "SCENARIO.toml")]
    scenario: PathBuf,
    /// output directory
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// the emulated Cortex-M4 in QEMU, linked through its ethernet controller (default), or
    /// through its UART on a pty (slower), or the firmware as a host process
    #[arg(long, value_name = "qemu|qemu-uart|host", value_parser = firmware)]
    firmware: Option<Target>,
    /// a real board on a serial adapter (flashed beforehand)
    #[arg(long, value_name = "/dev/ttyXXX", conflicts_with = "firmware")]
    port: Option<PathBuf>,
    /// the port's baud rate (default 115200; the boards' control link)
    #[arg(long, value_name = "N", requires = "port",
          value_parser = clap::value_parser!(u32).range(1200..=4_000_000))]
    baud: Option<u32>,
    /// no progress bar
    #[arg(long)]
    quiet: bool,
    /// planner parameters from a recipe (replace the scenario's [planner])
    #[arg(long, value_name = "RECIPE.toml")]
    params: Option<PathBuf>,
    /// corrupt bytes sent to the firmware on its main link at this bit-error rate
    #[arg(long, value_name = "X", value_parser = |s: &str| rate(s, 0.01))]
    bit_error_rate: Option<f64>,
    /// drop this fraction of the frames sent to the firmware on its main link
    #[arg(long, value_name = "X", value_parser = |s: &str| rate(s, 1.0))]
    drop_rate: Option<f64>,
    /// the same on the simulated Ping360's port ([sonar] interface = "ping360")
    #[arg(long, value_name = "X", value_parser = |s: &str| rate(s, 0.01))]
    ping360_bit_error_rate: Option<f64>,
    /// drop this fraction of the Ping360's device_data frames
    #[arg(long, value_name = "X", value_parser = |s: &str| rate(s, 1.0))]
    ping360_drop_rate: Option<f64>,
    /// delay navigation by X ms
    #[arg(long, value_name = "X", value_parser = |s: &str| rate(s, 10_000.0))]
    nav_delay_ms: Option<f64>,
    /// repeat the same navigation fix between FROM and TO seconds
    #[arg(long, value_name = "FROM:TO", value_parser = window)]
    nav_freeze: Option<Window>,
    /// send no navigation between FROM and TO seconds
    #[arg(long, value_name = "FROM:TO", value_parser = window)]
    nav_loss: Option<Window>,
    /// send no sonar between FROM and TO seconds
    #[arg(long, value_name = "FROM:TO", value_parser = window)]
    sonar_dropout: Option<Window>,
}

/// `hil check`'s options.
#[derive(clap::Args)]
struct CheckArgs {
    /// the scenario files
    #[arg(value_name = "SCENARIO.toml", required = true)]
    files: Vec<PathBuf>,
}

fn firmware(s: &str) -> Result<Target, String> {
    match s {
        "qemu" => Ok(Target::Qemu),
        "qemu-uart" => Ok(Target::QemuUart),
        "host" => Ok(Target::Host),
        _ => Err("expected qemu, qemu-uart or host".into()),
    }
}

fn window(s: &str) -> Result<Window, String> {
    let (a, b) = s
        .split_once(':')
        .ok_or_else(|| format!("`{s}`: expected FROM:TO in seconds"))?;
    let from_s: f64 = a.parse().map_err(|_| format!("`{a}` is not a number"))?;
    let to_s: f64 = b.parse().map_err(|_| format!("`{b}` is not a number"))?;
    if !(from_s.is_finite() && to_s.is_finite() && to_s > from_s && from_s >= 0.0) {
        return Err(format!("`{s}`: need 0 <= FROM < TO"));
    }
    Ok(Window { from_s, to_s })
}

fn rate(s: &str, max: f64) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|_| format!("`{s}` is not a number"))?;
    if v.is_finite() && (0.0..=max).contains(&v) {
        Ok(v)
    } else {
        Err(format!("`{s}`: must be within 0..={max}"))
    }
}

/// The command line's faults over the scenario's own.
fn apply_faults(sc: &mut Scenario, a: &RunArgs) {
    let f = &mut sc.faults;
    let set = |to: &mut f64, v: Option<f64>| *to = v.unwrap_or(*to);
    set(&mut f.bit_error_rate, a.bit_error_rate);
    set(&mut f.drop_rate, a.drop_rate);
    set(&mut f.nav_delay_ms, a.nav_delay_ms);
    set(&mut f.ping360_bit_error_rate, a.ping360_bit_error_rate);
    set(&mut f.ping360_drop_rate, a.ping360_drop_rate);
    f.nav_freeze = a.nav_freeze.or(f.nav_freeze);
    f.nav_loss = a.nav_loss.or(f.nav_loss);
    f.sonar_dropout = a.sonar_dropout.or(f.sonar_dropout);
}

fn default_out(name: &str) -> PathBuf {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    PathBuf::from("runs").join(format!("{}-{secs}", hil::output::file_stem(name)))
}

fn cmd_run(args: RunArgs) -> ExitCode {
    let mut sc = match scenario::load(&args.scenario) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    if let Some(recipe) = &args.params {
        let text = match std::fs::read_to_string(recipe) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("hil run: cannot read {}: {e}", recipe.display());
                return ExitCode::from(2);
            }
        };
        match scenario::parse_planner(&text, &recipe.display().to_string(), sc.dt_s) {
            Ok(p) => {
                sc.params = p;
                eprintln!(
                    "hil: planner parameters from {} (instead of the scenario's [planner])",
                    recipe.display()
                );
            }
            Err(e) => {
                eprintln!("{e}");
                return ExitCode::from(2);
            }
        }
    }
    apply_faults(&mut sc, &args);
    let mut target = match args.port {
        Some(port) => Target::Port(port, args.baud.unwrap_or(hil::firmware::PORT_BAUD)),
        None => args.firmware.unwrap_or(Target::Qemu),
    };
    if matches!(target, Target::Qemu | Target::QemuUart) && !hil::firmware::qemu_available() {
        eprintln!("hil: qemu-system-arm not found; running the host-process firmware instead");
        target = Target::Host;
    }
    let out_dir = args.out.unwrap_or_else(|| default_out(&sc.name));
    eprintln!(
        "hil: {} ({} vehicle{}, {} s at {} Hz) on the {target} firmware → {}",
        sc.name,
        sc.vehicles.len(),
        if sc.vehicles.len() == 1 { "" } else { "s" },
        sc.duration_s,
        (1.0 / sc.dt_s).round(),
        out_dir.display()
    );
    let cfg = RunConfig {
        target,
        out_dir: out_dir.clone(),
        progress: !args.quiet,
    };
    match run(&sc, &cfg) {
        Ok(result) => {
            println!("{}", result.summary);
            for ((((v, f), retries), slow), p360) in sc
                .vehicles
                .iter()
                .zip(&result.faults)
                .zip(&result.tick_retries)
                .zip(&result.ticks_slow)
                .zip(&result.ping360)
            {
                if let Some((p, f)) = p360 {
                    println!(
                        "{}: simulated Ping360: {} commands, {} answered; its port: {} of {} frames dropped, {} corrupted ({} bits), {} of them passed the checksum",
                        v.name, p.commands, p.answers, f.dropped, f.frames, f.corrupted,
                        f.bits_flipped, p.corrupted_accepted
                    );
                }
                if *retries > 0 {
                    println!(
                        "{}: {retries} Tick(s) sent again: {} lost on the link, {slow} answered \
                         late (the firmware was slow)",
                        v.name,
                        retries - slow
                    );
                }
                if f.dropped + f.corrupted > 0 {
                    println!(
                        "{}: main-link faults injected: {} of {} frames dropped, {} corrupted ({} bits)",
                        v.name, f.dropped, f.frames, f.corrupted, f.bits_flipped
                    );
                }
            }
            println!("outputs in {}", out_dir.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("hil: {e}");
            ExitCode::FAILURE
        }
    }
}

fn cmd_check(args: CheckArgs) -> ExitCode {
    let mut ok = true;
    for f in &args.files {
        match scenario::load(f) {
            Ok(s) => println!(
                "{}: ok ({}, {} vehicles)",
                f.display(),
                s.name,
                s.vehicles.len()
            ),
            Err(e) => {
                eprintln!("{e}");
                ok = false;
            }
        }
    }
    if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(2)
    }
}

/// Every command's help opens with its usage line, as the README writes them.
const HELP: &str = "{about-with-newline}\nusage: {usage}\n\n{all-args}{after-help}";

fn main() -> ExitCode {
    let cmd = Cli::command()
        .help_template(HELP)
        .mut_subcommands(|c| c.help_template(HELP));
    let cli = match Cli::from_arg_matches(&cmd.get_matches()) {
        Ok(c) => c,
        Err(e) => e.exit(),
    };
    match cli.command {
        Command::Run(a) => cmd_run(a),
        Command::Check(a) => cmd_check(a),
        Command::Sweep(a) => hil::sweep::cli::cli_sweep(a),
        Command::Merge(a) => hil::sweep::cli::cli_merge(a),
        Command::Compare(a) => hil::compare::cli(a),
        Command::Bench(a) => hil::bench::cli(a),
        Command::BenchDiff(a) => hil::bench::diff::cli(&a),
        Command::Faults(a) => hil::campaign::cli(a),
        Command::Beliefs(a) => hil::beliefs::cli(&a),
        Command::Echoes(a) => hil::echoes::cli(&a),
        Command::SonarReplay(a) => hil::ping360::replay::cli(a),
        Command::Ping360Raw(a) => hil::ping360::replay::cli_raw(a),
    }
}
