//! Parameter tuning sweeps (seed 002): run a grid or a random sample of planner parameters over
//! a batch of scenarios — scenario files and randomly generated cluttered fields, narrow
//! passages and U-traps — in lockstep with the host-process firmware, rank the parameter sets
//! by a criterion, and write the recommended recipe.
//!
//! ```text
//! hil sweep SPEC.toml [--out DIR] [--jobs N] [--shard K/N] [--quiet]
//! hil merge DIR... [--out DIR]
//! ```
//!
//! - [`cli`]: `hil sweep` and `hil merge` on the command line;
//! - [`spec`]: the sweep file;
//! - [`generate`]: the random scenarios and the batch;
//! - [`measure`]: one run's row (success, clearance, path ratio, time, energy, oscillation);
//! - [`criterion`]: the ranking of the parameter sets;
//! - [`csv`]: `runs.csv`, appended as runs finish;
//! - [`pool`]: the worker threads and the progress bar;
//! - [`report`]: `sets.csv`, `ranking.md`, the heat maps and `recipe.toml`.
//!
//! The run list is every (parameter set, scenario) pair; run `r` is set `r / S`, scenario
//! `r % S` for S scenarios. Shard K of N takes the runs with `r % N == K − 1`. An output
//! directory holds `sweep.json` (the sweep's identity: a hash of the spec and of every
//! scenario's text, and the shard), `spec.toml` (a copy of the spec) and `runs.csv`; a run is
//! appended and flushed as it finishes, so an interrupted sweep restarted with the same `--out`
//! skips the runs already there, and a different spec (or shard) is refused there instead of
//! mixed in. The reports are always made from `runs.csv` as written (sorted by run), so the
//! merge of the shards gives the same files as the unsharded sweep.

pub mod cli;
pub mod criterion;
pub mod csv;
pub mod generate;
pub mod measure;
pub mod pool;
pub mod report;
pub mod spec;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::error::Error;
use crate::firmware::{self, Target};
use crate::runner::QuietRun;

pub use report::Report;
pub use spec::Spec;

/// Bumped when the generators or the row format change, so old results are not mixed in.
pub const FORMAT: &str = "hil-sweep-1";

/// How to sweep.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Output directory (default `sweeps/NAME`, or `sweeps/NAME/shard-K-of-N`).
    pub out: Option<PathBuf>,
    /// Worker threads (default: the available parallelism).
    pub jobs: Option<usize>,
    /// Run only the K-th of N slices: `(K, N)`, 1-based.
    pub shard: Option<(usize, usize)>,
    /// No progress bar and no ranked table on stdout.
    pub quiet: bool,
    /// The firmware's link: a pty (as `hil run`) instead of a socket pair.
    pub pty: bool,
    /// The firmware as a separate process (on the socket pair, or the pty with `pty`) instead
    /// of its runtime in this process.
    pub process: bool,
}

/// What a sweep did.
pub struct Outcome {
    /// Where the results are.
    pub dir: PathBuf,
    /// Runs done now.
    pub ran: usize,
    /// Runs found done already (resumed).
    pub skipped: usize,
    /// Runs in this shard (or the whole sweep).
    pub mine: usize,
    /// Wall-clock time of the runs done now (the firmware build excluded).
    pub elapsed: Duration,
    /// Worker threads used.
    pub jobs: usize,
    /// The report over the runs recorded in the directory.
    pub report: Report,
}

/// FNV-1a, 64 bits: a stable hash with no dependency (identity, not security).
pub fn fnv1a(parts: &[&[u8]]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for p in parts {
        for &b in *p {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
        // Separator, so ("ab", "c") and ("a", "bc") differ.
        h ^= 0xff;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// The sweep described by the file at `spec_path`.
pub fn sweep(spec_path: &Path, opts: &Options) -> Result<Outcome, Error> {
    let spec = spec::load(spec_path)?;
    let spec_dir = spec_path.parent().unwrap_or(Path::new("."));
    let generate::Batch {
        scenarios: batch,
        left_out,
    } = generate::batch(&spec, spec_dir)?;
    for (id, why) in &left_out {
        eprintln!("hil sweep: {id} left out: {why}");
    }
    let n_scen = batch.len();
    let total = spec.sets.len() * n_scen;
    let mut parts: Vec<&[u8]> = vec![FORMAT.as_bytes(), spec.text.as_bytes()];
    for b in &batch {
        parts.push(b.id.as_bytes());
        parts.push(b.text.as_bytes());
    }
    let identity = format!("{:016x}", fnv1a(&parts));
    let shard_name = opts.shard.map(|(k, n)| format!("{k}/{n}"));
    let dir = opts.out.clone().unwrap_or_else(|| {
        let base = PathBuf::from("sweeps").join(crate::output::file_stem(&spec.name));
        match opts.shard {
            Some((k, n)) => base.join(format!("shard-{k}-of-{n}")),
            None => base,
        }
    });
    std::fs::create_dir_all(&dir).map_err(Error::io("cannot create", &dir))?;
    let scenario_ids: Vec<String> = batch.iter().map(|b| b.id.clone()).collect();

    // The directory's identity: new, or the same sweep and shard.
    let meta_path = dir.join("sweep.json");
    if let Ok(text) = std::fs::read_to_string(&meta_path) {
        let meta: serde_json::Value =
            serde_json::from_str(&text).map_err(Error::unreadable(&meta_path))?;
        let same =
            meta["identity"] == identity.as_str() && meta["shard"] == serde_json::json!(shard_name);
        if !same {
            return Err(Error::Mismatch(format!(
                "{} holds another sweep (identity {}, shard {}); this one is {identity}, shard {}. \
                 The spec or one of its scenarios changed: use another --out, or delete the \
                 directory to start over.",
                dir.display(),
                meta["identity"],
                meta["shard"],
                shard_name.as_deref().unwrap_or("none")
            )));
        }
    } else {
        let meta = serde_json::json!({
            "format": FORMAT,
            "name": spec.name,
            "spec_file": spec.file,
            "identity": identity,
            "shard": shard_name,
            "total_runs": total,
            "sets": spec.sets.len(),
            "scenarios": scenario_ids,
            "craft": spec.craft.model.name(),
        });
        let text = serde_json::to_string_pretty(&meta)?;
        std::fs::write(&meta_path, text + "\n").map_err(Error::io("cannot write", &meta_path))?;
        let copy = dir.join("spec.toml");
        std::fs::write(&copy, &spec.text).map_err(Error::io("cannot write", &copy))?;
    }

    // What is done already: complete rows of runs.csv (rewritten without a cut-off last line).
    let csv_path = dir.join("runs.csv");
    let mut rows = match std::fs::read_to_string(&csv_path) {
        Ok(text) => {
            let (rows, dropped) =
                csv::read(&spec, &text, total).map_err(Error::unreadable(&csv_path))?;
            if dropped > 0 {
                eprintln!(
                    "hil sweep: {}: dropped {dropped} incomplete row(s) (an interrupted write)",
                    csv_path.display()
                );
            }
            rows
        }
        Err(_) => Vec::new(),
    };
    rows.sort_by_key(|r| r.run);
    rows.dedup_by_key(|r| r.run);
    std::fs::write(&csv_path, csv::render(&spec, &rows))
        .map_err(Error::io("cannot write", &csv_path))?;

    let in_shard = |r: usize| opts.shard.is_none_or(|(k, n)| r % n == k - 1);
    let mine: Vec<usize> = (0..total).filter(|&r| in_shard(r)).collect();
    let done: std::collections::HashSet<usize> = rows.iter().map(|r| r.run).collect();
    let pending: Vec<usize> = mine.iter().copied().filter(|r| !done.contains(r)).collect();
    let skipped = mine.len() - pending.len();
    let jobs = opts.jobs.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(2, std::num::NonZeroUsize::get)
    });

    if !opts.quiet {
        eprintln!(
            "hil sweep: \"{}\": {} parameter sets × {n_scen} scenarios ({}) = {total} runs{}; \
             {} to run, {skipped} done already; {jobs} workers → {}",
            spec.name,
            spec.sets.len(),
            report::families(&scenario_ids),
            shard_name.as_ref().map_or(String::new(), |s| format!(
                ", shard {s}: {} runs",
                mine.len()
            )),
            pending.len(),
            dir.display()
        );
    }
    let mut started = Instant::now();
    let mut private = None;
    if !pending.is_empty() {
        let built = firmware::build(&Target::Host).map_err(Error::Build)?;
        // A private copy: a rebuild during the sweep (someone's `cargo test`) must not change
        // the firmware under the runs still to come.
        let binary = private_copy(&built)?;
        private = Some(binary.clone());
        let fw_hash = format!(
            "{:016x}",
            fnv1a(&[&std::fs::read(&binary).map_err(Error::io("cannot read", &binary))?])
        );
        note_firmware(&meta_path, &fw_hash, opts.quiet)?;
        started = Instant::now();
        let params: Vec<_> = (0..spec.sets.len())
            .map(|i| spec.params_of(i, spec::CHECK_DT_S))
            .collect();
        let work = pool::Work {
            spec: &spec,
            batch: &batch,
            params: &params,
            run: QuietRun {
                target: Target::Host,
                binary,
                stop_early: true,
                hold_s: 0.0,
                socket: !opts.pty,
                in_process: !opts.process && !opts.pty,
            },
        };
        let file = std::fs::OpenOptions::new()
            .append(true)
            .open(&csv_path)
            .map_err(Error::io("cannot open", &csv_path))?;
        let mut file = csv::writer(file);
        pool::run_all(
            &|run| pool::run_one(&work, run),
            &pending,
            jobs,
            opts.quiet,
            skipped,
            mine.len(),
            |row| {
                file.write_record(csv::record(&spec, &row))?;
                file.flush()
            },
        )
        .map_err(Error::io("cannot append to", &csv_path))?;
    }
    let elapsed = started.elapsed();
    if let Some(copy) = &private {
        let _ = std::fs::remove_file(copy);
    }

    // Sorted by run, then the reports from the file as written.
    let text = std::fs::read_to_string(&csv_path).map_err(Error::io("cannot read", &csv_path))?;
    let (mut rows, _) = csv::read(&spec, &text, total).map_err(Error::unreadable(&csv_path))?;
    rows.sort_by_key(|r| r.run);
    rows.dedup_by_key(|r| r.run);
    std::fs::write(&csv_path, csv::render(&spec, &rows))
        .map_err(Error::io("cannot write", &csv_path))?;
    let ctx = report::Context {
        spec_file: spec.file.clone(),
        identity,
        scenarios: scenario_ids,
        total_runs: total,
        date: report::today(),
    };
    let report =
        report::write(&dir, &spec, &rows, &ctx).map_err(Error::io("cannot write to", &dir))?;
    Ok(Outcome {
        dir,
        ran: pending.len(),
        skipped,
        mine: mine.len(),
        elapsed,
        jobs,
        report,
    })
}

/// Copies the firmware binary to a file of this process's own (in the system's temporary
/// directory).
fn private_copy(built: &Path) -> Result<PathBuf, Error> {
    static COUNT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = COUNT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let copy = std::env::temp_dir().join(format!("hil-sweep-firmware-{}-{k}", std::process::id()));
    std::fs::copy(built, &copy).map_err(Error::io("cannot copy the firmware to", &copy))?;
    Ok(copy)
}

/// Records the firmware's hash in `sweep.json`; warns if the directory's earlier runs used
/// another build (their rows are kept: the spec's identity does not cover the firmware).
fn note_firmware(meta_path: &Path, hash: &str, quiet: bool) -> Result<(), Error> {
    let text = std::fs::read_to_string(meta_path).map_err(Error::io("cannot read", meta_path))?;
    let mut meta: serde_json::Value =
        serde_json::from_str(&text).map_err(Error::unreadable(meta_path))?;
    let mut seen: Vec<String> = meta["firmware"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|h| h.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default();
    if seen.iter().any(|h| h == hash) {
        return Ok(());
    }
    if !seen.is_empty() && !quiet {
        eprintln!(
            "hil sweep: note: the firmware build differs from the one this directory's earlier              runs used (recorded in {})",
            meta_path.display()
        );
    }
    seen.push(hash.to_string());
    meta["firmware"] = serde_json::json!(seen);
    let text = serde_json::to_string_pretty(&meta)?;
    std::fs::write(meta_path, text + "\n").map_err(Error::io("cannot write", meta_path))
}

/// Merges the `runs.csv` of several output directories of one sweep (its shards, or partial
/// runs) into `out`, and writes the reports there. Returns the report and the spec.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<(Report, Spec, usize), Error> {
    let first = dirs
        .first()
        .ok_or(Error::Size("which directories? (hil merge DIR...)".into()))?;
    let mut identity: Option<(String, serde_json::Value)> = None;
    let mut spec: Option<Spec> = None;
    let mut rows: Vec<measure::RunRow> = Vec::new();
    for d in dirs {
        let meta_path = d.join("sweep.json");
        let text =
            std::fs::read_to_string(&meta_path).map_err(Error::io("cannot read", &meta_path))?;
        let meta: serde_json::Value =
            serde_json::from_str(&text).map_err(Error::unreadable(&meta_path))?;
        let id = meta["identity"].as_str().unwrap_or_default().to_string();
        match &identity {
            None => identity = Some((id, meta.clone())),
            Some((i, _)) if *i != id => {
                return Err(Error::Mismatch(format!(
                    "{} is another sweep (identity {id}, not {i} as {}): not merged",
                    d.display(),
                    first.display()
                )))
            }
            Some(_) => {}
        }
        if spec.is_none() {
            let path = d.join("spec.toml");
            let text = std::fs::read_to_string(&path).map_err(Error::io("cannot read", &path))?;
            let name = meta["spec_file"].as_str().unwrap_or("spec.toml");
            spec = Some(spec::parse(&text, name)?);
        }
        let Some(sp) = spec.as_ref() else { continue };
        let total = meta["total_runs"].as_u64().unwrap_or(0) as usize;
        let path = d.join("runs.csv");
        let text = std::fs::read_to_string(&path).map_err(Error::io("cannot read", &path))?;
        let (mut r, _) = csv::read(sp, &text, total).map_err(Error::unreadable(&path))?;
        rows.append(&mut r);
    }
    let (identity, meta) = identity.ok_or(Error::Size("nothing to merge".into()))?;
    let spec = spec.ok_or(Error::Size("nothing to merge".into()))?;
    rows.sort_by_key(|r| r.run);
    for w in rows.windows(2) {
        if w[0].run == w[1].run && w[0] != w[1] {
            return Err(Error::Mismatch(format!(
                "run {} is in two directories with different results (not the same firmware?)",
                w[0].run
            )));
        }
    }
    rows.dedup_by_key(|r| r.run);
    let total = meta["total_runs"].as_u64().unwrap_or(0) as usize;
    let scenarios: Vec<String> = meta["scenarios"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|s| s.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default();
    std::fs::create_dir_all(out).map_err(Error::io("cannot create", out))?;
    let mut merged = meta.clone();
    merged["shard"] = serde_json::Value::Null;
    merged["merged_from"] = serde_json::json!(dirs
        .iter()
        .map(|d| d.display().to_string())
        .collect::<Vec<_>>());
    let text = serde_json::to_string_pretty(&merged)?;
    let w = |name: &str, body: &str| {
        let p = out.join(name);
        std::fs::write(&p, body).map_err(Error::io("cannot write", &p))
    };
    w("sweep.json", &(text + "\n"))?;
    w("spec.toml", &spec.text)?;
    w("runs.csv", &csv::render(&spec, &rows))?;
    let ctx = report::Context {
        spec_file: spec.file.clone(),
        identity,
        scenarios,
        total_runs: total,
        date: report::today(),
    };
    let report =
        report::write(out, &spec, &rows, &ctx).map_err(Error::io("cannot write to", out))?;
    Ok((report, spec, total))
}
