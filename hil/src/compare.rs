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

use crate::firmware::Target;
use crate::output::file_stem;
use crate::output::metrics::VehicleMetrics;
use crate::runner::{run, RunConfig};
use crate::scenario::Scenario;

/// Every strategy, in the order of the table.
pub const STRATEGIES: [Strategy; 3] = [Strategy::Vpf, Strategy::Multipoint, Strategy::Navfn];

/// One row: a vehicle of a scenario flown with one strategy.
#[derive(Clone, Debug)]
pub struct Row {
    /// Scenario name.
    pub scenario: String,
    /// The strategy.
    pub strategy: Strategy,
    /// The vehicle's metrics, or why the run failed.
    pub result: Result<VehicleMetrics, String>,
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
    let results: Mutex<Vec<Option<Vec<Row>>>> = Mutex::new(vec![None; pairs.len()]);
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
        Err(e) => vec![row(Err(e.to_string()))],
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

const USAGE: &str = "usage: hil compare [SCENARIO.toml...] [--strategies vpf,multipoint,navfn]
                   [--firmware host|qemu] [--jobs N] [--out DIR]

Flies each scenario (default: every hil/scenarios/*.toml) with each strategy and prints a
markdown table (also written to OUT/comparison.md); each run's outputs are in
OUT/<scenario>/<strategy>/. Default firmware: host; default jobs: the number of cores.";

/// `hil compare ...`.
pub fn cli(it: impl Iterator<Item = String>) -> std::process::ExitCode {
    match cli_inner(it) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        // `--help`: the usage, on stdout, and success.
        Err(e) if e.is_empty() => {
            println!("{USAGE}");
            std::process::ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("hil compare: {e}\n\n{USAGE}");
            std::process::ExitCode::from(2)
        }
    }
}

fn cli_inner(mut it: impl Iterator<Item = String>) -> Result<(), String> {
    let mut files: Vec<PathBuf> = Vec::new();
    let mut strategies = STRATEGIES.to_vec();
    let mut target = Target::Host;
    let mut jobs = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut out = None;
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or_else(|| format!("{a} needs a value"));
        match a.as_str() {
            "--strategies" => {
                strategies = value()?
                    .split(',')
                    .map(|s| {
                        Strategy::from_name(s.trim()).ok_or_else(|| {
                            format!("unknown strategy `{s}` (vpf, multipoint or navfn)")
                        })
                    })
                    .collect::<Result<_, _>>()?;
            }
            "--firmware" => {
                target = match value()?.as_str() {
                    "host" => Target::Host,
                    "qemu" => Target::Qemu,
                    other => return Err(format!("--firmware {other}: expected host or qemu")),
                }
            }
            "--jobs" => {
                jobs = value()?
                    .parse()
                    .ok()
                    .filter(|&n| n > 0)
                    .ok_or("--jobs needs a positive integer")?;
            }
            "--out" => out = Some(PathBuf::from(value()?)),
            "--help" | "-h" => return Err(String::new()),
            s if s.starts_with("--") => return Err(format!("unknown option {s}")),
            s => files.push(PathBuf::from(s)),
        }
    }
    if files.is_empty() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
        let entries = std::fs::read_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        files = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        files.sort();
    }
    let mut scenarios = files
        .iter()
        .map(|f| crate::scenario::load(f).map_err(|e| e.to_string()))
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
    std::fs::create_dir_all(&out).map_err(|e| e.to_string())?;
    std::fs::write(out.join("comparison.md"), &md).map_err(|e| e.to_string())?;
    Ok(())
}
