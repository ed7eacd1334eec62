//! `hil compare`: the same scenarios flown with each guidance strategy, side by side.
//!
//! Every (scenario, strategy) pair is an ordinary run (outputs in `OUT/<scenario>/<strategy>/`)
//! with only `params.strategy` changed; the pairs run on parallel worker threads, each with its
//! own firmware process. The table has one row per scenario, vehicle and strategy: reached,
//! time to goal, path length, minimum clearance and the firmware's reported planner step cost
//! (microseconds for the host-process firmware, instructions on QEMU).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use vpf::Strategy;

use crate::error::Error;
use crate::firmware::Target;
use crate::output::file_stem;
use crate::output::metrics::VehicleMetrics;
use crate::runner::{run, RunConfig, RunError};
use crate::scenario::Scenario;

/// Every strategy, in the order of the table.
pub const STRATEGIES: [Strategy; 3] = [Strategy::Vpf, Strategy::Multipoint, Strategy::Navfn];

/// One row: a vehicle of a scenario flown with one strategy.
#[derive(Debug)]
pub struct Row {
    /// Scenario name.
    pub scenario: String,
    /// The strategy.
    pub strategy: Strategy,
    /// The vehicle's metrics, or why the run failed.
    pub result: Result<VehicleMetrics, RunError>,
}

/// Runs every scenario with every strategy in `strategies` on `jobs` threads; outputs under
/// `out`. Rows come back in (scenario, strategy, vehicle) order.
pub fn compare(
    scenarios: &[Scenario],
    strategies: &[Strategy],
    target: &Target,
    out: &Path,
    jobs: usize,
) -> Vec<Row> {
    let pairs: Vec<(usize, Strategy)> = (0..scenarios.len())
        .flat_map(|i| strategies.iter().map(move |&s| (i, s)))
        .collect();
    let results: Mutex<Vec<Option<Vec<Row>>>> = Mutex::new(pairs.iter().map(|_| None).collect());
    let next = AtomicUsize::new(0);
    std::thread::scope(|scope| {
        for _ in 0..jobs.max(1) {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some(&(i, strategy)) = pairs.get(k) else {
                    break;
                };
                let rows = fly(&scenarios[i], strategy, target, out);
                if let Ok(mut r) = results.lock() {
                    r[k] = Some(rows);
                }
            });
        }
    });
    results
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .flatten()
        .flatten()
        .collect()
}

fn fly(sc: &Scenario, strategy: Strategy, target: &Target, out: &Path) -> Vec<Row> {
    let mut sc = sc.clone();
    sc.params.strategy = strategy;
    let dir: PathBuf = out.join(file_stem(&sc.name)).join(strategy.name());
    let cfg = RunConfig {
        target: target.clone(),
        out_dir: dir,
        progress: false,
    };
    let row = |result| Row {
        scenario: sc.name.clone(),
        strategy,
        result,
    };
    match run(&sc, &cfg) {
        Ok(r) => r.summary.vehicles.into_iter().map(|v| row(Ok(v))).collect(),
        Err(e) => vec![row(Err(e))],
    }
}

/// The comparison as a markdown table.
pub fn table(rows: &[Row]) -> String {
    let mut s = String::from(
        "| scenario | vehicle | strategy | reached | time to goal | path | min clearance | step cost mean / max |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = match &r.result {
            Ok(v) => {
                let unit = v.step_cost.unit.unwrap_or("");
                let cost = match (v.step_cost.mean, v.step_cost.max) {
                    (Some(mean), Some(max)) => format!("{mean:.0} / {max} {unit}"),
                    _ => "–".into(),
                };
                let clearance = match v.min_clearance_m {
                    Some(c) if v.collisions > 0 => {
                        format!("{c:.2} m ({} collisions)", v.collisions)
                    }
                    Some(c) => format!("{c:.2} m"),
                    None => "n/a".into(),
                };
                writeln!(
                    s,
                    "| {} | {} | {} | {} | {} | {:.1} m | {} | {} |",
                    r.scenario,
                    v.name,
                    r.strategy.name(),
                    if v.reached_goal { "yes" } else { "no" },
                    v.time_to_goal_s
                        .map_or_else(|| "–".into(), |t| format!("{t:.1} s")),
                    v.path_length_m,
                    clearance,
                    cost
                )
            }
            Err(e) => writeln!(
                s,
                "| {} | – | {} | run failed: {e} | | | | |",
                r.scenario,
                r.strategy.name()
            ),
        };
    }
    s
}

/// `hil compare`'s command line.
#[derive(Clone, Debug, clap::Parser)]
#[command(
    name = "hil compare",
    long_about = "Flies each scenario (default: every hil/scenarios/*.toml) with each strategy and \
             prints a markdown table (also written to OUT/comparison.md); each run's outputs are \
             in OUT/<scenario>/<strategy>/."
)]
pub struct Args {
    /// scenario files (default: every hil/scenarios/*.toml)
    #[arg(value_name = "SCENARIO.toml")]
    files: Vec<PathBuf>,
    /// the strategies (default: all three)
    #[arg(long, value_name = "vpf,multipoint,navfn", value_delimiter = ',', value_parser = strategy)]
    strategies: Vec<Strategy>,
    /// the firmware as a host process (default) or in QEMU
    #[arg(long, value_name = "host|qemu", value_parser = firmware)]
    firmware: Option<Target>,
    /// worker threads (default: the number of cores)
    #[arg(long, value_name = "N", value_parser = crate::sweep::pool::jobs)]
    jobs: Option<usize>,
    /// output directory (default runs/compare-TIME)
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

fn strategy(s: &str) -> Result<Strategy, String> {
    Strategy::from_name(s.trim())
        .ok_or_else(|| format!("unknown strategy `{s}` (vpf, multipoint or navfn)"))
}

fn firmware(s: &str) -> Result<Target, String> {
    match s {
        "host" => Ok(Target::Host),
        "qemu" => Ok(Target::Qemu),
        _ => Err("expected host or qemu".into()),
    }
}

/// `hil compare ...`.
pub fn cli(args: Args) -> std::process::ExitCode {
    match cli_inner(args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("hil compare: {e}");
            std::process::ExitCode::from(2)
        }
    }
}

fn cli_inner(args: Args) -> Result<(), Error> {
    let Args {
        mut files,
        strategies,
        firmware,
        jobs,
        out,
    } = args;
    let strategies = if strategies.is_empty() {
        STRATEGIES.to_vec()
    } else {
        strategies
    };
    let target = firmware.unwrap_or(Target::Host);
    let jobs = jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if files.is_empty() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
        let entries = std::fs::read_dir(&dir).map_err(Error::io("cannot list", &dir))?;
        files = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        files.sort();
    }
    let mut scenarios = files
        .iter()
        .map(|f| crate::scenario::load(f))
        .collect::<Result<Vec<_>, _>>()?;
    if target != Target::Host {
        // The board images drive their Ping360 with `Ping360Config::BOARD` only (QEMU), and a
        // real board's sonar UART is wired to a real one.
        scenarios.retain(|s| {
            if s.sonar.interface != crate::scenario::SonarInterface::Ping360 {
                return true;
            }
            let why = match target {
                Target::Qemu => crate::ping360::sim::firmware_config(&s.sonar)
                    .and_then(|c| crate::ping360::sim::board_config_matches(&c))
                    .err()
                    .map(|(k, m)| format!("[sonar] {k}: {m}")),
                _ => Some("a simulated Ping360 needs --firmware host or qemu".into()),
            };
            if let Some(why) = &why {
                eprintln!("hil compare: leaving out \"{}\": {why}", s.name);
            }
            why.is_none()
        });
    }
    let out = out.unwrap_or_else(|| {
        let secs = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs());
        PathBuf::from("runs").join(format!("compare-{secs}"))
    });
    eprintln!(
        "hil compare: {} scenarios × {} strategies on the {target} firmware, {jobs} jobs → {}",
        scenarios.len(),
        strategies.len(),
        out.display()
    );
    let rows = compare(&scenarios, &strategies, &target, &out, jobs);
    let md = table(&rows);
    println!("{md}");
    std::fs::create_dir_all(&out).map_err(Error::io("cannot create", &out))?;
    let path = out.join("comparison.md");
    std::fs::write(&path, &md).map_err(Error::io("cannot write", &path))?;
    Ok(())
}
