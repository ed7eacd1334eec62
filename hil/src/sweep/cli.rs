//! `hil sweep` and `hil merge` on the command line: the options, the printed outcome and the
//! ranked table.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::{generate, merge, pool, spec, sweep, Options, Outcome, Report, Spec};

/// `hil sweep`'s command line.
#[derive(Clone, Debug, clap::Parser)]
#[command(
    name = "hil sweep",
    long_about = "Runs every parameter set of SPEC over its scenarios (files and generated ones) on \
             the host-process firmware, ranks the sets and writes runs.csv, sets.csv, \
             ranking.md, heatmap_success.svg, heatmap_clearance.svg and recipe.toml to --out. \
             Re-running with the same --out resumes.",
    after_help = "Spec format: hil/sweeps/README.md. Shards: hil merge --help."
)]
pub struct SweepArgs {
    /// the sweep spec (with --merge: the shards' directories)
    #[arg(value_name = "SPEC.toml", required = true)]
    spec: Vec<PathBuf>,
    /// output directory (default sweeps/NAME, or sweeps/NAME/shard-K-of-N)
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// worker threads (default: the number of cores)
    #[arg(long, value_name = "N", value_parser = pool::jobs)]
    jobs: Option<usize>,
    /// run only the K-th of N slices of the run list (e.g. a Slurm array task)
    #[arg(long, value_name = "K/N", value_parser = shard)]
    shard: Option<(usize, usize)>,
    /// no progress bar, no table
    #[arg(long)]
    quiet: bool,
    /// print scenario ID of the batch (e.g. clutter:3) as a scenario file, and exit
    #[arg(long, value_name = "ID")]
    show: Option<String>,
    /// the host firmware: its runtime in this process (default: no process wake-up and no
    /// system call per period), or the vpf-firmware process on a socket pair or a pty
    #[arg(long, value_name = "inproc|socket|pty", value_parser = ["inproc", "socket", "pty"])]
    link: Option<String>,
    /// the same as hil merge: combine the directories given
    #[arg(long)]
    merge: bool,
}

/// `hil merge`'s command line.
#[derive(Clone, Debug, clap::Parser)]
#[command(
    name = "hil merge",
    long_about = "Combines the runs.csv of a sweep's shards (hil sweep --shard K/N) into one report, \
             the same files as the unsharded sweep."
)]
pub struct MergeArgs {
    /// the shards' output directories
    #[arg(value_name = "DIR", required = true)]
    dirs: Vec<PathBuf>,
    /// output directory (default: the parent of the first DIR, merged/)
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// no table
    #[arg(long)]
    quiet: bool,
}

/// `"K/N"` → `(K, N)` with `1 <= K <= N`.
pub fn shard(s: &str) -> Result<(usize, usize), String> {
    let (k, n) = s
        .split_once('/')
        .ok_or_else(|| "expected K/N, e.g. 2/8".to_string())?;
    let k: usize = k.parse().map_err(|_| "K is not a number".to_string())?;
    let n: usize = n.parse().map_err(|_| "N is not a number".to_string())?;
    if n == 0 || k == 0 || k > n {
        return Err("need 1 <= K <= N".into());
    }
    Ok((k, n))
}

/// `hil sweep ...`.
pub fn cli_sweep(args: SweepArgs) -> ExitCode {
    let (process, pty) = match args.link.as_deref() {
        Some("socket") => (true, false),
        Some("pty") => (true, true),
        _ => (false, false),
    };
    let opts = Options {
        out: args.out,
        jobs: args.jobs,
        shard: args.shard,
        quiet: args.quiet,
        pty,
        process,
    };
    if args.merge {
        // `hil sweep --merge DIR...`: the same as `hil merge`.
        return do_merge(&args.spec, opts.out, opts.quiet);
    }
    let [spec_path] = &args.spec[..] else {
        eprintln!("hil sweep: one spec per sweep");
        return ExitCode::from(2);
    };
    if let Some(id) = &args.show {
        return show_scenario(spec_path, id);
    }
    match sweep(spec_path, &opts) {
        Ok(o) => {
            if let Ok(spec) = spec::load(spec_path) {
                print_outcome(&o, &spec.name);
                if !opts.quiet {
                    print_report(&o.report, &spec, &o.dir);
                }
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("hil sweep: {e}");
            ExitCode::from(2)
        }
    }
}

/// `hil merge DIR... [--out DIR]`.
pub fn cli_merge(args: MergeArgs) -> ExitCode {
    do_merge(&args.dirs, args.out, args.quiet)
}

fn print_outcome(o: &Outcome, spec_name: &str) {
    let rate = if o.elapsed.as_secs_f64() > 0.0 && o.ran > 0 {
        format!(
            ", {:.2} runs/s on {} workers",
            o.ran as f64 / o.elapsed.as_secs_f64(),
            o.jobs
        )
    } else {
        String::new()
    };
    println!(
        "sweep \"{spec_name}\": {} runs done now, {} resumed, {} of {} in this directory, in {}{rate}",
        o.ran,
        o.skipped,
        o.report.runs,
        o.mine,
        pool::clock(o.elapsed.as_secs_f64())
    );
}

fn print_report(r: &Report, spec: &Spec, dir: &Path) {
    print!("{}", r.print(spec, 10));
    if let Some(b) = r.best() {
        println!(
            "recommended: set {} ({}); recipe {}",
            b.set,
            spec.params
                .iter()
                .zip(&spec.sets[b.set])
                .map(|(p, v)| format!("{} = {}", p.name, v.plain()))
                .collect::<Vec<_>>()
                .join(", "),
            dir.join("recipe.toml").display()
        );
    }
    println!(
        "outputs in {}: runs.csv, sets.csv, ranking.md, heatmap_success.svg, heatmap_clearance.svg, recipe.toml",
        dir.display()
    );
}

/// `hil sweep SPEC --show ID`: prints a scenario of the batch as a scenario file (with the
/// craft's model; a scenario file is printed as it is).
fn show_scenario(spec_path: &Path, id: &str) -> ExitCode {
    let spec = match spec::load(spec_path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    let spec_dir = spec_path.parent().unwrap_or(Path::new("."));
    match generate::batch(&spec, spec_dir) {
        Ok(generate::Batch {
            scenarios: batch,
            left_out,
        }) => match batch.iter().find(|b| b.id == id) {
            Some(b) => {
                print!("{}", b.text);
                ExitCode::SUCCESS
            }
            None => {
                if let Some((_, why)) = left_out.iter().find(|(l, _)| l == id) {
                    eprintln!("hil sweep: `{id}` is left out of this batch: {why}");
                    return ExitCode::from(2);
                }
                let ids: Vec<&str> = batch.iter().map(|b| b.id.as_str()).collect();
                eprintln!(
                    "hil sweep: no scenario `{id}` in this batch: {}",
                    ids.join(", ")
                );
                ExitCode::from(2)
            }
        },
        Err(e) => {
            eprintln!("{e}");
            ExitCode::from(2)
        }
    }
}

fn do_merge(dirs: &[PathBuf], out: Option<PathBuf>, quiet: bool) -> ExitCode {
    let out = out.unwrap_or_else(|| {
        dirs.first()
            .and_then(|d| d.parent())
            .map_or_else(|| PathBuf::from("merged"), |p| p.join("merged"))
    });
    match merge(dirs, &out) {
        Ok((r, spec, total)) => {
            println!(
                "merged {} directories: {} of {total} runs{}",
                dirs.len(),
                r.runs,
                if r.runs < total {
                    " (INCOMPLETE: some shards are missing or unfinished)"
                } else {
                    ""
                }
            );
            if !quiet {
                print_report(&r, &spec, &out);
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("hil merge: {e}");
            ExitCode::from(2)
        }
    }
}
