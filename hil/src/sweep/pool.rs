//! The workers: `jobs` threads take runs from a shared counter, each run starting its own
//! host-process firmware (built once beforehand), and send the finished rows to the calling
//! thread, which writes them (and so is the only writer of `runs.csv`).

use std::io::IsTerminal;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;

use super::generate::BatchScenario;
use super::measure::{self, RunRow};
use super::spec::Spec;
use crate::runner::{end_progress, progress_bar, run_quiet, QuietRun};

/// What the workers need.
pub struct Work<'a> {
    /// The sweep.
    pub spec: &'a Spec,
    /// Its scenarios.
    pub batch: &'a [BatchScenario],
    /// Each set's parameters (or why the scenario parser refused them).
    pub params: &'a [Result<vpf::Params, crate::scenario::ScenarioError>],
    /// How to run.
    pub run: QuietRun,
}

/// Runs one run of the sweep: run index `run` = set × scenarios + scenario.
pub fn run_one(w: &Work<'_>, run: usize) -> RunRow {
    let n = w.batch.len();
    let (set, j) = (run / n, run % n);
    let b = &w.batch[j];
    let mut sc = b.scenario.clone();
    match &w.params[set] {
        Ok(p) => {
            sc.params = vpf::Params {
                period_s: sc.dt_s as f32,
                ..*p
            };
        }
        Err(e) => return measure::failed(run, set, &b.id, e.to_string()),
    }
    match run_quiet(&sc, &w.run) {
        Ok(out) => measure::measure(
            run,
            set,
            &b.id,
            &out,
            &b.straight_m,
            w.spec.weights.deadband,
        ),
        Err(e) => measure::failed(run, set, &b.id, e.to_string()),
    }
}

/// Runs `pending` on `jobs` threads, each run `r` as `work(r)`; `on_row` gets each finished
/// row on the calling thread. Shows a progress bar (runs done of `total`, runs/s, ETA) on a
/// terminal unless `quiet`; `already` runs were done before. (`hil bench` uses it too.)
#[allow(clippy::too_many_arguments)]
pub fn run_all<R: Send>(
    work: &(dyn Fn(usize) -> R + Sync),
    pending: &[usize],
    jobs: usize,
    quiet: bool,
    already: usize,
    total: usize,
    mut on_row: impl FnMut(R) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let next = AtomicUsize::new(0);
    let show = !quiet && std::io::stderr().is_terminal();
    let mut result = Ok(());
    std::thread::scope(|s| {
        let (tx, rx) = mpsc::channel::<R>();
        for _ in 0..jobs.max(1).min(pending.len().max(1)) {
            let tx = tx.clone();
            let next = &next;
            s.spawn(move || loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(&run) = pending.get(i) else { break };
                if tx.send(work(run)).is_err() {
                    break;
                }
            });
        }
        drop(tx);
        let bar = progress_bar(
            total as u64,
            show,
            "{pos}/{len} runs  {rate} runs/s  ETA {left}",
        );
        bar.set_position(already as u64);
        bar.reset_eta();
        for row in rx {
            if let Err(e) = on_row(row) {
                // Stop handing out runs; the workers finish the ones they hold.
                next.store(usize::MAX / 2, Ordering::Relaxed);
                result = Err(e);
                break;
            }
            bar.inc(1);
        }
        end_progress(&bar);
    });
    result
}

/// Most worker threads a command line may ask for.
pub const MAX_JOBS: usize = 256;

/// `--jobs N`: `1 ..= MAX_JOBS` worker threads.
pub fn jobs(s: &str) -> Result<usize, String> {
    s.parse()
        .ok()
        .filter(|n| (1..=MAX_JOBS).contains(n))
        .ok_or_else(|| format!("expected 1 ..= {MAX_JOBS}"))
}

/// `1:02:03` or `2:03`.
pub fn clock(secs: f64) -> String {
    let s = if secs.is_finite() {
        secs.round() as u64
    } else {
        0
    };
    if s >= 3600 {
        format!("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
    } else {
        format!("{}:{:02}", s / 60, s % 60)
    }
}
