//! `hil bench`: the benchmark every change to planning and perception is judged by — worlds the
//! project was not tuned on, generated from seeds, flown with default parameters.
//!
//! ```text
//! hil bench [--families a,b,...] [--seeds N] [--first-seed F] [--trial K] [--strategies vpf,...]
//!           [--models videoray,...] [--sensing scanlines,contacts] [--params RECIPE.toml]
//!           [--sonar-range M] [--sonar-step DEG] [--jobs N] [--out DIR] [--quiet]
//!           [--keep-worlds]
//! ```
//!
//! - [`worlds`]: the twelve families, and the mission families `survey` (waypoints),
//!   `berth` (a goal by a quay, held for a minute) and `face` (a goal nearer a rock's, a
//!   pile's or a wall's face, held for a minute), flown when named, each world
//!   deterministic from (family, seed);
//! - [`feasible`]: the grid search that checks a world is flyable by the craft and gives the
//!   shortest feasible path (the reference time is that path at cruise speed);
//! - [`turning`]: for a craft with a turning radius, the hybrid-A* search that checks it can
//!   fly the world from its start pose, and the least time it can (then the reference, if
//!   longer);
//! - [`case`]: one run — world, scenario file, flight, measurements;
//! - [`report`]: the tables (`bench.md`) and `bench.json`;
//! - [`diff`]: `hil bench-diff`, two benches of the same worlds compared run by run.
//!
//! Every (family × seed × strategy × model × sensing) is one run, on all cores, in lockstep with
//! the host-process firmware, ended at arrival, at the first contact, or at three reference
//! times plus a minute. Each finished run is appended to `runs.jsonl` in the output directory,
//! so an interrupted bench run again with the same `--out` skips what is done (and more seeds
//! or families add to it); a different `--params` recipe is refused there. A failed run's
//! `plot.svg` and its scenario file (`world.toml`, for `hil run`) are kept under `failed/`;
//! with `--keep-worlds`, every run's scenario file under `worlds/` too.

pub mod case;
pub mod diff;
pub mod feasible;
pub mod report;
pub mod turning;
pub mod worlds;

use std::collections::HashSet;
use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use vpf::Strategy;

use crate::error::Error;
use crate::runner::QuietRun;
use crate::scenario::{self, Sensing};
use crate::sim::ModelKind;
use crate::sweep::{fnv1a, pool};
use case::{Case, Head, Row};
use worlds::{Family, FAMILIES};

/// Bumped when the worlds or the row format change, so old rows are not mixed in.
pub const FORMAT: &str = "hil-bench-1";
/// Fastest current a bench flies, m/s: half a VideoRay's cruise, so every world stays one it
/// can make way in.
pub const MAX_CURRENT_MPS: f64 = 0.5;
/// Most runs one bench may hold (families × seeds × strategies × models × sensing).
pub const MAX_RUNS: usize = 100_000;

/// What to bench.
#[derive(Clone, Debug)]
pub struct Options {
    /// Families.
    pub families: Vec<Family>,
    /// Worlds per family: seeds `first_seed` .. `first_seed + seeds`.
    pub seeds: u64,
    /// The first seed.
    pub first_seed: u64,
    /// The sea's draw (`Case::sim_seed`; 0: each world's own seed).
    pub trial: u64,
    /// The sonar's range for every model, m (`None`: each model's own, [`Head::carried_by`]).
    pub sonar_range_m: Option<f64>,
    /// The sonar head's step, degrees.
    pub sonar_step_deg: f64,
    /// A steady current of this speed, m/s, in a direction drawn per world (0: still water).
    pub current_mps: f64,
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
    /// Keep every run's scenario file, not only a failed run's.
    pub keep_worlds: bool,
}

impl Options {
    /// The sonar set-up `model` flies with: its own ([`Head::carried_by`]) but for the range
    /// if one was given.
    pub fn head(&self, model: ModelKind) -> Head {
        Head {
            range_m: self
                .sonar_range_m
                .unwrap_or(Head::carried_by(model).range_m),
            step_deg: self.sonar_step_deg,
        }
    }

    /// The water, as the tables name it: `, current 0.2 m/s`, or nothing in still water.
    fn water(&self) -> String {
        if self.current_mps > 0.0 {
            format!(", current {} m/s", self.current_mps)
        } else {
            String::new()
        }
    }

    /// The set-ups flown, as the tables name them: one, or each model's
    /// (`flatfish: sonar 40 m, 3.6° steps`).
    fn heads(&self) -> String {
        let heads: Vec<Head> = self.models.iter().map(|&m| self.head(m)).collect();
        if heads.windows(2).all(|w| w[0] == w[1]) {
            heads.first().map_or_else(String::new, Head::name)
        } else {
            let each = self.models.iter().zip(&heads);
            each.map(|(m, h)| format!("{}: {}", m.name(), h.name()))
                .collect::<Vec<_>>()
                .join("; ")
        }
    }
}

impl Default for Options {
    fn default() -> Self {
        Options {
            families: FAMILIES.to_vec(),
            seeds: 17,
            first_seed: 0,
            trial: 0,
            sonar_range_m: None,
            sonar_step_deg: Head::default().step_deg,
            current_mps: 0.0,
            strategies: vec![Strategy::Vpf],
            models: vec![ModelKind::VideoRay],
            sensing: vec![Sensing::Sonar],
            params: None,
            jobs: None,
            out: None,
            quiet: false,
            keep_worlds: false,
        }
    }
}

/// `hil bench`'s command line.
#[derive(Clone, Debug, clap::Parser)]
#[command(
    name = "hil bench",
    long_about = "Flies generated worlds the planner was not tuned on and tabulates how it did.",
    after_help = "Writes runs.jsonl (one row per run; rerun to resume), bench.md and bench.json \
                  (tables per family and overall), and failed/<run>/{plot.svg, world.toml} for \
                  every run that failed (with --keep-worlds, worlds/<run>/world.toml for every \
                  run flown)."
)]
pub struct Args {
    /// world families (default: these twelve): clutter, boxes, wall_gap, harbour, utrap, ltrap,
    /// channel, serpentine, rocks, crossing, head_on, formation; and, when named, the missions:
    /// survey (waypoints), berth (a goal by a quay, held for a minute), face (a goal 0.5–1.5 m
    /// beyond the hull off a rock, a pile or a wall, held for a minute)
    #[arg(long, value_name = "a,b,...", value_delimiter = ',', value_parser = family)]
    families: Vec<Family>,
    /// worlds per family, seeds F .. F+N-1 (default 17: 204 worlds)
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=10_000))]
    seeds: Option<u64>,
    /// the first seed F (default 0): judge a change on seeds it was not chosen on, e.g.
    /// `--first-seed 200 --seeds 100`
    #[arg(long, value_name = "F", value_parser = clap::value_parser!(u64).range(0..=1_000_000))]
    first_seed: Option<u64>,
    /// the sea's draw K (default 0): the same worlds flown through other chance — the sonar's
    /// noise, speckle and false echoes drawn anew — so `hil bench-diff` of two trials shows
    /// how many outcomes chance alone turns over, the floor a change must beat
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u64).range(0..=1_000_000))]
    trial: Option<u64>,
    /// the sonar's range for every model, m (default: each model's own, 20 for the VideoRay and
    /// 40 for the flat-fish; with contacts, the range they are given within)
    #[arg(long, value_name = "M", value_parser = sonar_range)]
    sonar_range: Option<f64>,
    /// the sonar head's step, degrees (default 3.6: a 360° sweep in 3.2 s at 20 m); 1.8 at
    /// 30 m is the Micron's high-resolution 9 s sweep
    #[arg(long, value_name = "DEG", value_parser = sonar_step)]
    sonar_step: Option<f64>,
    /// a steady current of this speed, m/s (default 0: still water), 0 ..= 0.5, in a direction
    /// drawn from each world's seed; times are against the still-water reference
    #[arg(long, value_name = "M/S", value_parser = current)]
    current: Option<f64>,
    /// vpf, multipoint, navfn (default vpf)
    #[arg(long, value_name = "a,b,...", value_delimiter = ',', value_parser = strategy)]
    strategies: Vec<Strategy>,
    /// videoray, flatfish (default videoray)
    #[arg(long, value_name = "a,b,...", value_delimiter = ',', value_parser = model)]
    models: Vec<ModelKind>,
    /// scanlines (the vehicle's own sonar), contacts (perfect perception) (default scanlines)
    #[arg(long, value_name = "a,b,...", value_delimiter = ',', value_parser = sensing)]
    sensing: Vec<Sensing>,
    /// planner parameters from a recipe instead of the defaults
    #[arg(long, value_name = "RECIPE.toml")]
    params: Option<PathBuf>,
    /// worker threads (default: all cores)
    #[arg(long, value_name = "N", value_parser = crate::sweep::pool::jobs)]
    jobs: Option<usize>,
    /// output directory (default bench/default, or bench/<recipe>)
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// no progress bar
    #[arg(long)]
    quiet: bool,
    /// also keep the scenario file of every run flown, not only of a failed one, under
    /// worlds/<run>/world.toml (a few KB each): to fly any run again with `hil run`
    #[arg(long)]
    keep_worlds: bool,
}

/// `v`, or `default` if it is empty.
fn or<T>(v: Vec<T>, default: Vec<T>) -> Vec<T> {
    if v.is_empty() {
        default
    } else {
        v
    }
}

impl From<Args> for Options {
    fn from(a: Args) -> Self {
        let d = Options::default();
        Options {
            families: or(a.families, d.families),
            seeds: a.seeds.unwrap_or(d.seeds),
            first_seed: a.first_seed.unwrap_or(d.first_seed),
            trial: a.trial.unwrap_or(d.trial),
            sonar_range_m: a.sonar_range.or(d.sonar_range_m),
            sonar_step_deg: a.sonar_step.unwrap_or(d.sonar_step_deg),
            current_mps: a.current.unwrap_or(d.current_mps),
            strategies: or(a.strategies, d.strategies),
            models: or(a.models, d.models),
            sensing: or(a.sensing, d.sensing),
            params: a.params,
            jobs: a.jobs,
            out: a.out,
            quiet: a.quiet,
            keep_worlds: a.keep_worlds,
        }
    }
}

/// A number within `lo ..= hi` (the firmware's scanline limits, or the bench's current).
fn within(s: &str, lo: f32, hi: f32, unit: &str) -> Result<f64, String> {
    let (lo, hi) = (f64::from(lo), f64::from(hi));
    match s.parse::<f64>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok(v),
        _ => Err(format!(
            "`{s}`: a number of {unit} within {lo:.3} ..= {hi:.3}"
        )),
    }
}

fn sonar_range(s: &str) -> Result<f64, String> {
    within(
        s,
        vpf::sonar::MIN_RANGE_M,
        vpf::sonar::MAX_RANGE_M,
        "metres",
    )
}

fn sonar_step(s: &str) -> Result<f64, String> {
    // Rounded inward to what the scenario schema takes.
    let lo = (vpf::sonar::MIN_STEP_RAD.to_degrees() * 100.0).ceil() / 100.0;
    let hi = (vpf::sonar::MAX_STEP_RAD.to_degrees() * 100.0).floor() / 100.0;
    within(s, lo, hi, "degrees")
}

fn current(s: &str) -> Result<f64, String> {
    within(s, 0.0, MAX_CURRENT_MPS as f32, "m/s")
}

fn family(s: &str) -> Result<Family, String> {
    Family::parse(s).ok_or_else(|| format!("unknown family `{s}`"))
}

fn strategy(s: &str) -> Result<Strategy, String> {
    [Strategy::Vpf, Strategy::Multipoint, Strategy::Navfn]
        .into_iter()
        .find(|x| x.name() == s)
        .ok_or_else(|| format!("unknown strategy `{s}` (vpf, multipoint or navfn)"))
}

fn model(s: &str) -> Result<ModelKind, String> {
    [
        ModelKind::VideoRay,
        ModelKind::FlatFish,
        ModelKind::Kinematic,
    ]
    .into_iter()
    .find(|m| m.name() == s)
    .ok_or_else(|| format!("unknown model `{s}`"))
}

fn sensing(s: &str) -> Result<Sensing, String> {
    match s {
        "scanlines" | "sonar" => Ok(Sensing::Sonar),
        "contacts" => Ok(Sensing::Contacts),
        _ => Err(format!("unknown sensing `{s}` (scanlines or contacts)")),
    }
}

/// Every case of `o`, in table order.
pub fn cases(o: &Options) -> Vec<Case> {
    let mut v = Vec::new();
    for &strategy in &o.strategies {
        for &model in &o.models {
            for &sensing in &o.sensing {
                for &family in &o.families {
                    for seed in o.first_seed..o.first_seed.saturating_add(o.seeds) {
                        v.push(Case {
                            family,
                            seed,
                            strategy,
                            model,
                            sensing,
                            trial: o.trial,
                            head: o.head(model),
                            current_mps: o.current_mps,
                        });
                    }
                }
            }
        }
    }
    v
}

/// Runs the bench; returns the report over every row in the output directory.
pub fn bench(o: &Options) -> Result<(PathBuf, report::Report), Error> {
    let all = cases(o);
    if all.len() > MAX_RUNS {
        return Err(Error::Size(format!(
            "{} runs asked for; at most {MAX_RUNS} (fewer seeds, families or configurations)",
            all.len()
        )));
    }
    let (params, recipe_text) = match &o.params {
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(Error::io("cannot read", p))?;
            let prm = scenario::parse_planner(&text, &p.display().to_string(), 0.1)?;
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
    std::fs::create_dir_all(&dir).map_err(Error::io("cannot create", &dir))?;
    // The head's set-up and the water are part of what was flown; trial 0 and still water add
    // nothing more.
    let trial = o.trial.to_le_bytes();
    let head = o.heads() + &o.water();
    let mut parts: Vec<&[u8]> = vec![FORMAT.as_bytes(), recipe_text.as_bytes(), head.as_bytes()];
    if o.trial != 0 {
        parts.push(&trial);
    }
    let identity = format!("{:016x}", fnv1a(&parts));
    let id_path = dir.join("identity");
    match std::fs::read_to_string(&id_path) {
        Ok(old) if old.trim() != identity => {
            return Err(Error::Mismatch(format!(
                "{} holds a bench with other parameters (identity {}; this one is {identity}): \
                 use another --out, or delete it to start over",
                dir.display(),
                old.trim()
            )))
        }
        Ok(_) => {}
        Err(_) => {
            std::fs::write(&id_path, &identity).map_err(Error::io("cannot write", &id_path))?
        }
    }

    // Rows already there: complete lines of runs.jsonl (a cut-off last line is dropped).
    let rows_path = dir.join("runs.jsonl");
    let mut rows: Vec<Row> = if rows_path.exists() {
        case::read_rows(&rows_path)?.into_values().collect()
    } else {
        Vec::new()
    };
    let done: HashSet<String> = rows.iter().map(|r| r.id.clone()).collect();
    let pending: Vec<usize> = (0..all.len())
        .filter(|&i| !done.contains(&all[i].id()))
        .collect();
    let jobs = o.jobs.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(2, std::num::NonZeroUsize::get)
    });
    if !o.quiet {
        eprintln!(
            "hil bench: {} runs ({} families × {} seeds from {} × {} configurations), {} to fly, \
             {} done already; {jobs} workers → {}",
            all.len(),
            o.families.len(),
            o.seeds,
            o.first_seed,
            o.strategies.len() * o.models.len() * o.sensing.len(),
            pending.len(),
            all.len() - pending.len(),
            dir.display()
        );
    }
    if !pending.is_empty() {
        let run = QuietRun::host_until_done().map_err(Error::Build)?;
        let failed = dir.join("failed");
        let file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&rows_path)
            .map_err(Error::io("cannot open", &rows_path))?;
        let mut file = std::io::BufWriter::new(file);
        let recipe = params.as_ref().zip(o.params.as_deref());
        let worlds = o.keep_worlds.then(|| dir.join("worlds"));
        let fly = |i: usize| case::fly_keeping(&all[i], recipe, &run, &failed, worlds.as_deref());
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
        .map_err(Error::io("cannot append to", &rows_path))?;
    }
    // The report covers the cases asked for, in table order.
    let wanted: HashSet<String> = all.iter().map(Case::id).collect();
    rows.retain(|r| wanted.contains(&r.id));
    let order: std::collections::HashMap<String, usize> =
        all.iter().enumerate().map(|(i, c)| (c.id(), i)).collect();
    rows.sort_by_key(|r| order.get(&r.id).copied().unwrap_or(usize::MAX));
    rows.dedup_by(|a, b| a.id == b.id);
    let mut rep = report::Report::of(&rows, &params.unwrap_or_default(), o.params.as_deref());
    rep.params
        .push_str(&format!("; {}{}", o.heads(), o.water()));
    if o.trial != 0 {
        rep.params.push_str(&format!(", trial {}", o.trial));
    }
    let md = dir.join("bench.md");
    std::fs::write(&md, rep.markdown()).map_err(Error::io("cannot write", &md))?;
    let js = dir.join("bench.json");
    let json = serde_json::json!({
        "format": FORMAT,
        "trial": o.trial,
        "current_mps": o.current_mps,
        "sonar": o.models.iter().map(|&m| {
            let h = o.head(m);
            serde_json::json!({ "model": m.name(), "range_m": h.range_m, "step_deg": h.step_deg })
        }).collect::<Vec<_>>(),
        "summary": rep.json(),
        "runs": rows
    });
    std::fs::write(
        &js,
        serde_json::to_string_pretty(&json).unwrap_or_default() + "\n",
    )
    .map_err(Error::io("cannot write", &js))?;
    Ok((dir, rep))
}

/// `hil bench ...`.
pub fn cli(args: Args) -> ExitCode {
    match bench(&args.into()) {
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

    use clap::Parser as _;

    fn parse(args: &[&str]) -> Result<Options, clap::Error> {
        Args::try_parse_from(std::iter::once("bench").chain(args.iter().copied())).map(Into::into)
    }

    #[test]
    fn arguments_parse_and_refuse_with_a_reason() {
        let o = parse(&[
            "--families",
            "clutter,harbour",
            "--seeds",
            "3",
            "--sensing",
            "scanlines,contacts",
        ])
        .unwrap();
        assert_eq!(o.families, [Family::Clutter, Family::Harbour]);
        assert_eq!(cases(&o).len(), 2 * 3 * 2);
        let e = parse(&["--families", "reef"]).unwrap_err().to_string();
        assert!(e.contains("reef"), "{e}");
        assert!(parse(&["--seeds", "0"]).is_err());
        let help = parse(&["--help"]).unwrap_err();
        assert_eq!(help.kind(), clap::error::ErrorKind::DisplayHelp);
        assert!(help.to_string().contains("--families"), "{help}");
        assert_eq!(cases(&parse(&[]).unwrap()).len(), 12 * 17);
        // Held-out seeds: 200 .. 204 of one family.
        let o = parse(&["--families", "rocks", "--seeds", "5", "--first-seed", "200"]).unwrap();
        let seeds: Vec<u64> = cases(&o).iter().map(|c| c.seed).collect();
        assert_eq!(seeds, [200, 201, 202, 203, 204]);
        assert!(cases(&o).iter().all(|c| c.trial == 0));
        let o = parse(&["--families", "rocks", "--seeds", "2", "--trial", "3"]).unwrap();
        assert!(cases(&o).iter().all(|c| c.trial == 3));
        assert_eq!(cases(&Options::default()).len(), 12 * 17);
        // The sonar's set-up: the scenario schema's unless named, checked against the
        // firmware's scanline limits.
        let d = crate::scenario::Sonar::default();
        assert!(cases(&o).iter().all(|c| c.head.range_m == d.range_m
            && (c.head.step_deg.to_radians() - d.step).abs() < 1e-12));
        // The flat-fish carries its own range; a range named is every model's.
        let o = parse(&["--models", "videoray,flatfish"]).unwrap();
        assert!(cases(&o).iter().all(|c| c.head.range_m
            == match c.model {
                ModelKind::FlatFish => crate::scenario::Sonar::FLATFISH_RANGE_M,
                _ => d.range_m,
            }));
        assert_eq!(
            o.heads(),
            "videoray: sonar 20 m, 3.6° steps; flatfish: sonar 40 m, 3.6° steps"
        );
        let o = parse(&[
            "--models",
            "videoray,flatfish",
            "--sonar-range",
            "30",
            "--sonar-step",
            "1.8",
        ])
        .unwrap();
        assert!(cases(&o).iter().all(|c| c.head
            == Head {
                range_m: 30.0,
                step_deg: 1.8
            }));
        assert_eq!(o.heads(), "sonar 30 m, 1.8° steps");
        for bad in [
            ["--sonar-range", "0.1"],
            ["--sonar-step", "20"],
            ["--sonar-step", "NaN"],
        ] {
            let e = parse(&bad).unwrap_err().to_string();
            assert!(e.contains("within"), "{bad:?}: {e}");
        }
    }
}
