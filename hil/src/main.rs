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
//! hil sonar-replay --ping360 FILE [--plot FILE.svg] [detection options]
//! hil ping360-raw DUMP.txt OUT.bin
//! ```
//!
//! `hil run` also takes `--params RECIPE.toml` (a `[planner]` table, as `hil sweep` writes).

use std::path::PathBuf;
use std::process::ExitCode;

use hil::firmware::Target;
use hil::runner::{run, RunConfig};
use hil::scenario::{self, Scenario, Window};

const USAGE: &str = "usage:
  hil run SCENARIO.toml [options]   run a scenario, write outputs to --out (default runs/NAME-TIME)
  hil check SCENARIO.toml...        validate scenario files
  hil sweep SPEC.toml [options]     tune the planner's parameters over a scenario batch
  hil merge DIR...                  combine a sweep's shards (hil sweep --help)
  hil compare [SCENARIO.toml...]    fly scenarios with each strategy, print a table (hil compare --help)
  hil bench [options]               fly generated worlds, tabulate success and safety (hil bench --help)
  hil faults SCENARIO.toml... [options]  fly each scenario under each fault, print a table (hil faults --help)
  hil sonar-replay --ping360 FILE [options]  raw Ping360 bytes through the firmware's parser and extractor
  hil ping360-raw DUMP.txt OUT.bin  a brping text dump of device_data messages as raw Ping bytes

options for run:
  --out DIR                 output directory
  --firmware qemu|qemu-uart|host
                            the emulated Cortex-M4 in QEMU, linked through its ethernet controller
                            (default), or through its UART on a pty (slower), or the firmware as a
                            host process
  --port /dev/ttyXXX        a real board on a serial adapter (flashed beforehand)
  --baud N                  the port's baud rate (default 115200; the boards' control link)
  --quiet                   no progress bar
  --params RECIPE.toml      planner parameters from a recipe (replace the scenario's [planner])
  --bit-error-rate X        corrupt bytes sent to the firmware on its main link at this bit-error rate
  --drop-rate X             drop this fraction of the frames sent to the firmware on its main link
  --ping360-bit-error-rate X  the same on the simulated Ping360's port ([sonar] interface = \"ping360\")
  --ping360-drop-rate X     drop this fraction of the Ping360's device_data frames
  --nav-delay-ms X          delay navigation by X ms
  --nav-freeze FROM:TO      repeat the same navigation fix between FROM and TO seconds
  --nav-loss FROM:TO        send no navigation between FROM and TO seconds
  --sonar-dropout FROM:TO   send no sonar between FROM and TO seconds

Scenario files: hil/scenarios/README.md. Outputs: trajectory_*.csv, metrics.json, plot.svg,
commands.svg, frames_*.log.";

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

struct Args {
    scenario: PathBuf,
    out: Option<PathBuf>,
    target: Target,
    quiet: bool,
    faults: Vec<(String, String)>,
    params: Option<PathBuf>,
}

/// The options of `hil run`; `Err("")` for `--help`.
fn parse_run(mut it: impl Iterator<Item = String>) -> Result<Args, String> {
    let mut args = Args {
        scenario: PathBuf::new(),
        out: None,
        target: Target::Qemu,
        quiet: false,
        faults: Vec::new(),
        params: None,
    };
    let mut scenario = None;
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or_else(|| format!("{a} needs a value"));
        match a.as_str() {
            "--out" => args.out = Some(PathBuf::from(value()?)),
            "--firmware" => {
                args.target = match value()?.as_str() {
                    "qemu" => Target::Qemu,
                    "qemu-uart" => Target::QemuUart,
                    "host" => Target::Host,
                    other => {
                        return Err(format!(
                            "--firmware {other}: expected qemu, qemu-uart or host"
                        ))
                    }
                }
            }
            "--port" => {
                let baud = match &args.target {
                    Target::Port(_, b) => *b,
                    _ => hil::firmware::PORT_BAUD,
                };
                args.target = Target::Port(PathBuf::from(value()?), baud);
            }
            "--baud" => {
                let v = value()?;
                let b: u32 = v
                    .parse()
                    .ok()
                    .filter(|b| (1200..=4_000_000).contains(b))
                    .ok_or(format!(
                        "--baud {v}: expected a baud rate, 1200 ..= 4000000"
                    ))?;
                match &mut args.target {
                    Target::Port(_, baud) => *baud = b,
                    _ => return Err("--baud goes after --port".into()),
                }
            }
            "--quiet" => args.quiet = true,
            "--params" => args.params = Some(PathBuf::from(value()?)),
            "-h" | "--help" => return Err(String::new()),
            "--bit-error-rate"
            | "--drop-rate"
            | "--nav-delay-ms"
            | "--nav-freeze"
            | "--nav-loss"
            | "--sonar-dropout"
            | "--ping360-bit-error-rate"
            | "--ping360-drop-rate" => {
                let v = value()?;
                args.faults.push((a.clone(), v));
            }
            s if s.starts_with("--") => return Err(format!("unknown option {s}")),
            s => {
                if scenario.replace(PathBuf::from(s)).is_some() {
                    return Err("one scenario per run".into());
                }
            }
        }
    }
    args.scenario = scenario.ok_or("which scenario? (hil run SCENARIO.toml)")?;
    Ok(args)
}

fn apply_faults(sc: &mut Scenario, faults: &[(String, String)]) -> Result<(), String> {
    for (k, v) in faults {
        match k.as_str() {
            "--bit-error-rate" => sc.faults.bit_error_rate = rate(v, 0.01)?,
            "--drop-rate" => sc.faults.drop_rate = rate(v, 1.0)?,
            "--nav-delay-ms" => sc.faults.nav_delay_ms = rate(v, 10_000.0)?,
            "--nav-freeze" => sc.faults.nav_freeze = Some(window(v)?),
            "--nav-loss" => sc.faults.nav_loss = Some(window(v)?),
            "--sonar-dropout" => sc.faults.sonar_dropout = Some(window(v)?),
            "--ping360-bit-error-rate" => sc.faults.ping360_bit_error_rate = rate(v, 0.01)?,
            "--ping360-drop-rate" => sc.faults.ping360_drop_rate = rate(v, 1.0)?,
            _ => {}
        }
    }
    Ok(())
}

fn default_out(name: &str) -> PathBuf {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    PathBuf::from("runs").join(format!("{}-{secs}", hil::output::file_stem(name)))
}

fn cmd_run(it: impl Iterator<Item = String>) -> ExitCode {
    let args = match parse_run(it) {
        Ok(a) => a,
        Err(e) if e.is_empty() => {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            eprintln!("hil run: {e}\n\n{USAGE}");
            return ExitCode::from(2);
        }
    };
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
    if let Err(e) = apply_faults(&mut sc, &args.faults) {
        eprintln!("hil run: {e}");
        return ExitCode::from(2);
    }
    let mut target = args.target;
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

fn cmd_check(files: impl Iterator<Item = String>) -> ExitCode {
    let mut ok = true;
    let mut any = false;
    for f in files {
        if f == "-h" || f == "--help" {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        any = true;
        match scenario::load(std::path::Path::new(&f)) {
            Ok(s) => println!("{f}: ok ({}, {} vehicles)", s.name, s.vehicles.len()),
            Err(e) => {
                eprintln!("{e}");
                ok = false;
            }
        }
    }
    if !any {
        eprintln!("{USAGE}");
        return ExitCode::from(2);
    }
    if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(2)
    }
}

fn main() -> ExitCode {
    let mut it = std::env::args().skip(1);
    match it.next().as_deref() {
        Some("run") => cmd_run(it),
        Some("check") => cmd_check(it),
        Some("sweep") => hil::sweep::cli_sweep(it),
        Some("merge") => hil::sweep::cli_merge(it),
        Some("compare") => hil::compare::cli(it),
        Some("bench") => hil::bench::cli(it),
        Some("faults") => hil::campaign::cli(it),
        Some("sonar-replay") => hil::ping360::replay::cli(it),
        Some("ping360-raw") => hil::ping360::replay::cli_raw(it),
        Some("-h" | "--help") => {
            println!("{USAGE}");
            ExitCode::SUCCESS
        }
        _ => {
            eprintln!("{USAGE}");
            ExitCode::from(2)
        }
    }
}
