//! `hil bench`: the benchmark every change to planning and perception is judged by — worlds the
//! project was not tuned on, generated from seeds, flown with default parameters.
//!
//! ```text
//! hil bench [--families a,b,...] [--seeds N] [--strategies vpf,...] [--models videoray,...]
//!           [--sensing scanlines,contacts] [--params RECIPE.toml] [--jobs N] [--out DIR] [--quiet]
//! ```
//!
//! - [`worlds`]: the twelve families, and the waypoint-mission family `survey` (flown when
//!   named), each world deterministic from (family, seed);
//! - [`feasible`]: the grid search that checks a world is flyable by the craft and gives the
//!   shortest feasible path (the reference time is that path at cruise speed);
//! - [`case`]: one run — world, scenario file, flight, measurements;
//! - [`report`]: the tables (`bench.md`) and `bench.json`.
//!
//! Every (family × seed × strategy × model × sensing) is one run, on all cores, in lockstep with
//! the host-process firmware, ended at arrival, at the first contact, or at three reference
//! times plus a minute. Each finished run is appended to `runs.jsonl` in the output directory,
//! so an interrupted bench run again with the same `--out` skips what is done (and more seeds
//! or families add to it); a different `--params` recipe is refused there. A failed run's
//! `plot.svg` and its scenario file (`world.toml`, for `hil run`) are kept under `failed/`.

pub mod case;
pub mod feasible;
pub mod report;
pub mod turning;
pub mod worlds;

use std::collections::HashSet;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use vpf::Strategy;

use crate::runner::QuietRun;
use crate::scenario::{self, Sensing};
use crate::sim::ModelKind;
use crate::sweep::{fnv1a, pool};
use case::{Case, Row};
use worlds::{Family, FAMILIES};

/// Bumped when the worlds or the row format change, so old rows are not mixed in.
pub const FORMAT: &str = "hil-bench-1";
/// Most runs one bench may hold (families × seeds × strategies × models × sensing).
pub const MAX_RUNS: usize = 100_000;

const USAGE: &str = "usage: hil bench [options]

Flies generated worlds the planner was not tuned on and tabulates how it did.

options:
  --families a,b,...        world families (default: these twelve): clutter, boxes, wall_gap,
                            harbour, utrap, ltrap, channel, serpentine, rocks, crossing, head_on,
                            formation; and, when named, the waypoint missions: survey
  --seeds N                 worlds per family, seeds 0 .. N-1 (default 17: 204 worlds)
  --strategies a,b,...      vpf, multipoint, navfn (default vpf)
  --models a,b,...          videoray, flatfish (default videoray)
  --sensing a,b,...         scanlines (the vehicle's own sonar), contacts (perfect perception)
                            (default scanlines)
  --params RECIPE.toml      planner parameters from a recipe instead of the defaults
  --jobs N                  worker threads (default: all cores)
  --out DIR                 output directory (default bench/default, or bench/<recipe>)
  --quiet                   no progress bar

Writes runs.jsonl (one row per run; rerun to resume), bench.md and bench.json (tables per
family and overall), and failed/<run>/{plot.svg, world.toml} for every run that failed.";

/// What to bench.
#[derive(Clone, Debug)]
pub struct Options {
    /// Families.
    pub families: Vec<Family>,
    /// Seeds 0 .. seeds per family.
    pub seeds: u64,
    /// Strategies.
    pub strategies: Vec<Strategy>,
    /// Models.
    pub models: Vec<ModelKind>,
    /// Sensing.
    pub sensing: Vec<Sensing>,
    /// A recipe's `[planner]`.
    pub params: Option<PathBuf>,
    /// Workers.
    pub jobs: Option<usize>,
    /// Output directory.
    pub out: Option<PathBuf>,
    /// No progress bar.
    pub quiet: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            families: FAMILIES.to_vec(),
            seeds: 17,
            strategies: vec![Strategy::Vpf],
            models: vec![ModelKind::VideoRay],
            sensing: vec![Sensing::Sonar],
            params: None,
            jobs: None,
            out: None,
            quiet: false,
        }
    }
}

fn list<T>(s: &str, what: &str, parse: impl Fn(&str) -> Option<T>) -> Result<Vec<T>, String> {
    let v: Result<Vec<T>, String> = s
        .split(',')
        .map(|x| parse(x.trim()).ok_or_else(|| format!("--{what}: unknown `{x}`")))
        .collect();
    v.and_then(|v| {
        if v.is_empty() {
            Err(format!("--{what}: empty list"))
        } else {
            Ok(v)
        }
    })
}

fn parse_strategy(s: &str) -> Option<Strategy> {
    [Strategy::Vpf, Strategy::Multipoint, Strategy::Navfn]
        .into_iter()
        .find(|x| x.name() == s)
}

fn parse_model(s: &str) -> Option<ModelKind> {
    [
        ModelKind::VideoRay,
        ModelKind::FlatFish,
        ModelKind::Kinematic,
    ]
    .into_iter()
    .find(|m| m.name() == s)
}

fn parse_sensing(s: &str) -> Option<Sensing> {
    match s {
        "scanlines" | "sonar" => Some(Sensing::Sonar),
        "contacts" => Some(Sensing::Contacts),
        _ => None,
    }
}

/// Parses the command line after `hil bench`; `Ok(None)` for `--help`.
pub fn parse_args(mut it: impl Iterator<Item = String>) -> Result<Option<Options>, String> {
    let mut o = Options::default();
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or_else(|| format!("{a} needs a value"));
        match a.as_str() {
            "-h" | "--help" => return Ok(None),
            "--families" => o.families = list(&value()?, "families", Family::parse)?,
            "--seeds" => {
                let v = value()?;
                o.seeds = v
                    .parse()
                    .ok()
                    .filter(|n| (1..=10_000).contains(n))
                    .ok_or_else(|| format!("--seeds {v}: expected 1 ..= 10000"))?;
            }
            "--strategies" => o.strategies = list(&value()?, "strategies", parse_strategy)?,
            "--models" => o.models = list(&value()?, "models", parse_model)?,
            "--sensing" => o.sensing = list(&value()?, "sensing", parse_sensing)?,
            "--params" => o.params = Some(PathBuf::from(value()?)),
            "--jobs" => {
                let v = value()?;
                o.jobs = Some(
                    v.parse()
                        .ok()
                        .filter(|n| (1..=256).contains(n))
                        .ok_or_else(|| format!("--jobs {v}: expected 1 ..= 256"))?,
                );
            }
            "--out" => o.out = Some(PathBuf::from(value()?)),
            "--quiet" => o.quiet = true,
            other => return Err(format!("unknown option {other}")),
        }
    }
    Ok(Some(o))
}

/// Every case of `o`, in table order.
pub fn cases(o: &Options) -> Vec<Case> {
    let mut v = Vec::new();
    for &strategy in &o.strategies {
        for &model in &o.models {
            for &sensing in &o.sensing {
                for &family in &o.families {
                    for seed in 0..o.seeds {
                        v.push(Case {
                            family,
                            seed,
                            strategy,
                            model,
                            sensing,
                        });
                    }
                }
            }
        }
    }
    v
}

fn io_error<'a>(what: &'a str, p: &'a Path) -> impl Fn(std::io::Error) -> String + 'a {
    move |e| format!("{what} {}: {e}", p.display())
}

/// Runs the bench; returns the report over every row in the output directory.
pub fn bench(o: &Options) -> Result<(PathBuf, report::Report), String> {
    let all = cases(o);
    if all.len() > MAX_RUNS {
        return Err(format!(
            "{} runs asked for; at most {MAX_RUNS} (fewer seeds, families or configurations)",
            all.len()
        ));
    }
    let (params, recipe_text) = match &o.params {
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(io_error("cannot read", p))?;
            let prm = scenario::parse_planner(&text, &p.display().to_string(), 0.1)
                .map_err(|e| e.to_string())?;
            (Some(prm), text)
        }
        None => (None, String::new()),
    };
    let dir = o.out.clone().unwrap_or_else(|| {
        let name = o
            .params
            .as_ref()
            .and_then(|p| p.file_stem())
            .map_or("default".to_string(), |s| s.to_string_lossy().into_owned());
        PathBuf::from("bench").join(crate::output::file_stem(&name))
    });
    std::fs::create_dir_all(&dir).map_err(io_error("cannot create", &dir))?;
    let identity = format!(
        "{:016x}",
        fnv1a(&[FORMAT.as_bytes(), recipe_text.as_bytes()])
    );
    let id_path = dir.join("identity");
    match std::fs::read_to_string(&id_path) {
        Ok(old) if old.trim() != identity => {
            return Err(format!(
                "{} holds a bench with other parameters (identity {}; this one is {identity}): \
                 use another --out, or delete it to start over",
                dir.display(),
                old.trim()
            ))
        }
        Ok(_) => {}
        Err(_) => {
            std::fs::write(&id_path, &identity).map_err(io_error("cannot write", &id_path))?
        }
    }

    // Rows already there: complete lines of runs.jsonl (a cut-off last line is dropped).
    let rows_path = dir.join("runs.jsonl");
    let mut rows: Vec<Row> = std::fs::read_to_string(&rows_path)
        .map(|t| {
            t.lines()
                .filter_map(|l| serde_json::from_str(l).ok())
                .collect()
        })
        .unwrap_or_default();
    let done: HashSet<String> = rows.iter().map(|r| r.id.clone()).collect();
    let pending: Vec<usize> = (0..all.len())
        .filter(|&i| !done.contains(&all[i].id()))
        .collect();
    let jobs = o.jobs.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(2, std::num::NonZeroUsize::get)
    });
    if !o.quiet {
        eprintln!(
            "hil bench: {} runs ({} families × {} seeds × {} configurations), {} to fly, {} done \
             already; {jobs} workers → {}",
            all.len(),
            o.families.len(),
            o.seeds,
            o.strategies.len() * o.models.len() * o.sensing.len(),
            pending.len(),
            all.len() - pending.len(),
            dir.display()
        );
    }
    if !pending.is_empty() {
        let run = QuietRun::host_until_done().map_err(|e| format!("building the firmware: {e}"))?;
        let failed = dir.join("failed");
        let file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&rows_path)
            .map_err(io_error("cannot open", &rows_path))?;
        let mut file = std::io::BufWriter::new(file);
        let fly = |i: usize| case::fly(&all[i], params.as_ref(), &run, &failed);
        pool::run_all(
            &fly,
            &pending,
            jobs,
            o.quiet,
            all.len() - pending.len(),
            all.len(),
            |row: Row| {
                let line = serde_json::to_string(&row).map_err(std::io::Error::other)?;
                writeln!(file, "{line}")?;
                file.flush()?;
                rows.push(row);
                Ok(())
            },
        )
        .map_err(io_error("cannot append to", &rows_path))?;
    }
    // The report covers the cases asked for, in table order.
    let wanted: HashSet<String> = all.iter().map(Case::id).collect();
    rows.retain(|r| wanted.contains(&r.id));
    let order: std::collections::HashMap<String, usize> =
        all.iter().enumerate().map(|(i, c)| (c.id(), i)).collect();
    rows.sort_by_key(|r| order.get(&r.id).copied().unwrap_or(usize::MAX));
    rows.dedup_by(|a, b| a.id == b.id);
    let rep = report::Report::of(&rows, &params.unwrap_or_default(), o.params.as_deref());
    let md = dir.join("bench.md");
    std::fs::write(&md, rep.markdown()).map_err(io_error("cannot write", &md))?;
    let js = dir.join("bench.json");
    let json = serde_json::json!({ "format": FORMAT, "summary": rep.json(), "runs": rows });
    std::fs::write(
        &js,
        serde_json::to_string_pretty(&json).unwrap_or_default() + "\n",
    )
    .map_err(io_error("cannot write", &js))?;
    Ok((dir, rep))
}

/// `hil bench ...`.
pub fn cli(it: impl Iterator<Item = String>) -> ExitCode {
    let o = match parse_args(it) {
        Ok(Some(o)) => o,
        Ok(None) => {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            eprintln!("hil bench: {e}\n\n{USAGE}");
            return ExitCode::from(2);
        }
    };
    match bench(&o) {
        Ok((dir, rep)) => {
            println!("{}", rep.markdown());
            println!("outputs in {}", dir.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("hil bench: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arguments_parse_and_refuse_with_a_reason() {
        let o = parse_args(
            [
                "--families",
                "clutter,harbour",
                "--seeds",
                "3",
                "--sensing",
                "scanlines,contacts",
            ]
            .map(String::from)
            .into_iter(),
        )
        .unwrap()
        .unwrap();
        assert_eq!(o.families, [Family::Clutter, Family::Harbour]);
        assert_eq!(cases(&o).len(), 2 * 3 * 2);
        let e = parse_args(["--families", "reef"].map(String::from).into_iter()).unwrap_err();
        assert!(e.contains("reef"), "{e}");
        assert!(parse_args(["--seeds", "0"].map(String::from).into_iter()).is_err());
        assert!(parse_args(["--help"].map(String::from).into_iter())
            .unwrap()
            .is_none());
        assert_eq!(cases(&Options::default()).len(), 12 * 17);
    }
}
