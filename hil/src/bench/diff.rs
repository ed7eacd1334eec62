//! `hil bench-diff BEFORE AFTER`: what a change did to the bench, run by run.
//!
//! Two benches of the same worlds (the same families, seeds and configurations, flown before and
//! after a change, e.g. `--out /tmp/before` at the parent commit and `--out /tmp/after`) are
//! matched by run id. Totals hide what matters with movers: a change that removes a dozen
//! contacts and adds a dozen others leaves the count where it was. So the diff lists the runs
//! whose contact came or went and whose success was gained or lost, per configuration and
//! family, and weighs the paired change with the exact sign test on the runs that changed
//! (McNemar's test: under "the change did nothing", each changed run is as likely to have
//! gone either way). A small p says the change is real; a large one, that the two benches
//! differ by no more than a trajectory a centimetre off would.
//!
//! Which runs end in a contact is chance (`hil bench --trial`: the same worlds flown again turn
//! over every contact run), so one pair of benches is often too few. More pairs — the same
//! change benched at other trials, `hil bench-diff B0 A0 B1 A1 …` — are pooled: every run of
//! every pair counts once, its id tagged with its pair (`#2`), and the sign test weighs them all.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::case::{read_rows, Row};

/// `hil bench-diff`'s command line.
#[derive(Clone, Debug, clap::Parser)]
#[command(
    name = "hil bench-diff",
    long_about = "Compares two benches of the same worlds run by run: successes gained and lost, \
                  contacts gone and new, per configuration and family, with the sign test's p.",
    after_help = "Each argument is a bench's output directory (or its runs.jsonl). Runs in only \
                  one of them are counted, not compared. Further BEFORE AFTER pairs (the same \
                  change at other trials, `hil bench --trial K`) are pooled with the first. \
                  Exit status 1 with --no-new-contacts when an AFTER has a contact its BEFORE \
                  did not."
)]
pub struct Args {
    /// The bench before the change.
    pub before: PathBuf,
    /// The bench after it.
    pub after: PathBuf,
    /// More pairs, pooled: BEFORE AFTER ...
    #[arg(value_name = "BEFORE AFTER")]
    pub more: Vec<PathBuf>,
    /// Fail (exit status 1) when a run has a contact after the change and had none before.
    #[arg(long)]
    pub no_new_contacts: bool,
}

/// One configuration × family of the diff.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Group {
    /// Runs in both benches.
    pub runs: usize,
    /// Successes before and after.
    pub successes: (usize, usize),
    /// Runs with a contact before and after.
    pub contacts: (usize, usize),
    /// Run ids that succeeded only after ...
    pub gained: Vec<String>,
    /// ... only before.
    pub lost: Vec<String>,
    /// Run ids with a contact only before ...
    pub contacts_gone: Vec<String>,
    /// ... only after.
    pub contacts_new: Vec<String>,
}

impl Group {
    fn add(&mut self, b: &Row, a: &Row) {
        self.runs += 1;
        self.successes.0 += usize::from(b.success);
        self.successes.1 += usize::from(a.success);
        self.contacts.0 += usize::from(b.collided);
        self.contacts.1 += usize::from(a.collided);
        let id = || a.id.clone();
        match (b.success, a.success) {
            (false, true) => self.gained.push(id()),
            (true, false) => self.lost.push(id()),
            _ => {}
        }
        match (b.collided, a.collided) {
            (true, false) => self.contacts_gone.push(id()),
            (false, true) => self.contacts_new.push(id()),
            _ => {}
        }
    }

    fn merge(&mut self, g: &Group) {
        self.runs += g.runs;
        self.successes.0 += g.successes.0;
        self.successes.1 += g.successes.1;
        self.contacts.0 += g.contacts.0;
        self.contacts.1 += g.contacts.1;
        self.gained.extend_from_slice(&g.gained);
        self.lost.extend_from_slice(&g.lost);
        self.contacts_gone.extend_from_slice(&g.contacts_gone);
        self.contacts_new.extend_from_slice(&g.contacts_new);
    }
}

/// A bench's rows by run id.
pub type Bench = BTreeMap<String, Row>;

/// The whole diff.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Diff {
    /// Per (configuration, family), in name order.
    pub groups: BTreeMap<(String, String), Group>,
    /// Runs only in the first bench, only in the second.
    pub unmatched: (usize, usize),
}

impl Diff {
    /// Matches `before` and `after` by run id.
    pub fn of(before: &Bench, after: &Bench) -> Diff {
        let mut d = Diff::default();
        for (id, b) in before {
            match after.get(id) {
                Some(a) => d
                    .groups
                    .entry((a.config.clone(), a.family.clone()))
                    .or_default()
                    .add(b, a),
                None => d.unmatched.0 += 1,
            }
        }
        d.unmatched.1 = after.keys().filter(|id| !before.contains_key(*id)).count();
        d
    }

    /// `pairs` pooled: each pair matched by run id ([`Diff::of`]), its ids tagged `#k` (k from
    /// 1) when there is more than one pair, and every pair's groups merged.
    pub fn pooled(pairs: &[(Bench, Bench)]) -> Diff {
        let mut d = Diff::default();
        for (k, (before, after)) in pairs.iter().enumerate() {
            let mut one = Diff::of(before, after);
            if pairs.len() > 1 {
                for g in one.groups.values_mut() {
                    for ids in [
                        &mut g.gained,
                        &mut g.lost,
                        &mut g.contacts_gone,
                        &mut g.contacts_new,
                    ] {
                        ids.iter_mut()
                            .for_each(|id| *id = format!("{id}#{}", k + 1));
                    }
                }
            }
            for (key, g) in &one.groups {
                d.groups.entry(key.clone()).or_default().merge(g);
            }
            d.unmatched.0 += one.unmatched.0;
            d.unmatched.1 += one.unmatched.1;
        }
        d
    }

    /// Every group of a configuration merged, per configuration.
    pub fn totals(&self) -> BTreeMap<String, Group> {
        let mut t: BTreeMap<String, Group> = BTreeMap::new();
        for ((config, _), g) in &self.groups {
            t.entry(config.clone()).or_default().merge(g);
        }
        t
    }

    /// The tables and lists, in Markdown.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "| configuration | family | runs | success | gained / lost (p) | contacts | \
             gone / new (p) |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|");
        let totals = self.totals();
        let line = |s: &mut String, config: &str, family: &str, g: &Group| {
            let _ = writeln!(
                s,
                "| {config} | {family} | {} | {} → {} | {} / {} ({}) | {} → {} | {} / {} ({}) |",
                g.runs,
                g.successes.0,
                g.successes.1,
                g.gained.len(),
                g.lost.len(),
                p_text(sign_test(g.gained.len(), g.lost.len())),
                g.contacts.0,
                g.contacts.1,
                g.contacts_gone.len(),
                g.contacts_new.len(),
                p_text(sign_test(g.contacts_gone.len(), g.contacts_new.len())),
            );
        };
        for ((config, family), g) in &self.groups {
            line(&mut s, config, family, g);
        }
        for (config, g) in &totals {
            line(&mut s, config, "**all**", g);
        }
        for (config, g) in &totals {
            let _ = writeln!(s, "\n{config}:");
            for (what, ids) in [
                ("contacts gone", &g.contacts_gone),
                ("contacts new", &g.contacts_new),
                ("successes gained", &g.gained),
                ("successes lost", &g.lost),
            ] {
                let _ = writeln!(s, "- {what} ({}): {}", ids.len(), short_ids(ids));
            }
        }
        if self.unmatched != (0, 0) {
            let _ = writeln!(
                s,
                "\nnot compared: {} runs only before, {} only after",
                self.unmatched.0, self.unmatched.1
            );
        }
        s
    }
}

/// `family seed` for each run id (`family:seed:strategy:model:sensing`; the configuration is
/// the list's heading).
fn short_ids(ids: &[String]) -> String {
    if ids.is_empty() {
        return "–".to_string();
    }
    let mut short: Vec<(&str, u64, &str, &str)> = ids
        .iter()
        .map(|id| {
            // A pooled diff's pair tag (`#2`) is kept.
            let (id, pair) = id.split_once('#').unwrap_or((id, ""));
            let mut parts = id.split(':');
            match (parts.next(), parts.next().and_then(|s| s.parse().ok())) {
                (Some(f), Some(seed)) => (f, seed, pair, ""),
                _ => ("", 0, pair, id),
            }
        })
        .collect();
    // By family, then seed in number order (clutter 2 before clutter 10).
    short.sort_unstable();
    short
        .iter()
        .map(|&(f, seed, pair, whole)| {
            let pair = if pair.is_empty() {
                String::new()
            } else {
                format!(" #{pair}")
            };
            if whole.is_empty() {
                format!("{f} {seed}{pair}")
            } else {
                format!("{whole}{pair}")
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The two-sided exact sign test of `a` runs changed one way against `b` the other (McNemar's
/// exact test on the discordant pairs): the probability, were either way equally likely, of a
/// split at least this uneven. `None` when nothing changed.
pub fn sign_test(a: usize, b: usize) -> Option<f64> {
    let n = a + b;
    if n == 0 {
        return None;
    }
    let k = a.min(b);
    // P(X ≤ k) for X ~ B(n, ½), summed in logs (n may be thousands).
    let ln_half_n = n as f64 * 0.5f64.ln();
    let mut ln_c = 0.0; // ln C(n, 0)
    let mut tail = 0.0;
    for i in 0..=k {
        if i > 0 {
            ln_c += ((n - i + 1) as f64).ln() - (i as f64).ln();
        }
        tail += (ln_c + ln_half_n).exp();
    }
    Some((2.0 * tail).min(1.0))
}

fn p_text(p: Option<f64>) -> String {
    match p {
        None => "–".to_string(),
        Some(p) if p < 0.001 => "p < 0.001".to_string(),
        Some(p) => format!("p = {p:.3}"),
    }
}

/// `hil bench-diff ...`.
pub fn cli(args: &Args) -> ExitCode {
    let read = |p: &Path| {
        read_rows(p).map_err(|e| {
            eprintln!("hil bench-diff: {e}");
            ExitCode::FAILURE
        })
    };
    if args.more.len() % 2 == 1 {
        eprintln!("hil bench-diff: benches come in BEFORE AFTER pairs; one is left over");
        return ExitCode::FAILURE;
    }
    let paths: Vec<&PathBuf> = [&args.before, &args.after]
        .into_iter()
        .chain(&args.more)
        .collect();
    let mut pairs = Vec::new();
    for pair in paths.chunks(2) {
        if let [b, a] = pair {
            match (read(b), read(a)) {
                (Ok(b), Ok(a)) => pairs.push((b, a)),
                (Err(e), _) | (_, Err(e)) => return e,
            }
        }
    }
    let d = Diff::pooled(&pairs);
    if d.groups.is_empty() {
        eprintln!(
            "hil bench-diff: no run is in both {} and {}",
            args.before.display(),
            args.after.display()
        );
        return ExitCode::FAILURE;
    }
    if let Err(e) = crate::output::stdout::print(&d.markdown()) {
        eprintln!("hil bench-diff: standard output: {e}");
        return ExitCode::FAILURE;
    }
    let new = d
        .totals()
        .values()
        .map(|g| g.contacts_new.len())
        .sum::<usize>();
    if args.no_new_contacts && new > 0 {
        eprintln!("hil bench-diff: {new} runs have a contact they did not have before");
        return ExitCode::FAILURE;
    }
    ExitCode::SUCCESS
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(family: &str, seed: u64, success: bool, collided: bool) -> Row {
        let id = format!("{family}:{seed}:vpf:videoray:scanlines");
        let config = "vpf / videoray / scanlines".to_string();
        Row {
            success,
            collided,
            ..Row::unflown(id, family, seed, config)
        }
    }

    fn bench(rows: &[Row]) -> BTreeMap<String, Row> {
        rows.iter().map(|r| (r.id.clone(), r.clone())).collect()
    }

    #[test]
    fn a_contact_that_moved_shows_as_one_gone_and_one_new() {
        let before = bench(&[
            row("crossing", 1, false, true),
            row("crossing", 2, true, false),
            row("clutter", 1, false, false),
            row("clutter", 9, true, false),
        ]);
        let after = bench(&[
            row("crossing", 1, true, false),
            row("crossing", 2, false, true),
            row("clutter", 1, true, false),
            row("rocks", 4, true, false),
        ]);
        let d = Diff::of(&before, &after);
        assert_eq!(d.unmatched, (1, 1));
        let crossing = &d.groups[&("vpf / videoray / scanlines".into(), "crossing".into())];
        assert_eq!(crossing.contacts, (1, 1), "the count hides it ...");
        assert_eq!(crossing.contacts_gone.len(), 1, "... the diff does not");
        assert_eq!(crossing.contacts_new.len(), 1);
        let all = &d.totals()["vpf / videoray / scanlines"];
        assert_eq!((all.runs, all.successes), (3, (1, 2)));
        assert_eq!((all.gained.len(), all.lost.len()), (2, 1));
        let md = d.markdown();
        assert!(md.contains("contacts new (1): crossing 2"), "{md}");
        assert!(
            md.contains("successes gained (2): clutter 1, crossing 1"),
            "{md}"
        );
        assert!(md.contains("1 runs only before, 1 only after"), "{md}");
    }

    #[test]
    fn pairs_at_other_trials_are_pooled_run_by_run() {
        // The same change benched at two trials: a contact gone in each, one new in the second.
        let pair = |gone: u64, new: Option<u64>| {
            let before = bench(&[
                row("head_on", gone, false, true),
                row("head_on", 8, true, false),
            ]);
            let after = bench(&[
                row("head_on", gone, true, false),
                row("head_on", 8, new.is_none(), new.is_some()),
            ]);
            (before, after)
        };
        let one = Diff::pooled(&[pair(3, None)]);
        assert_eq!(
            one,
            Diff::of(&pair(3, None).0, &pair(3, None).1),
            "one pair: as before"
        );
        let d = Diff::pooled(&[pair(3, None), pair(5, Some(8))]);
        let all = &d.totals()["vpf / videoray / scanlines"];
        assert_eq!(all.runs, 4, "every run of every pair counts");
        assert_eq!((all.contacts_gone.len(), all.contacts_new.len()), (2, 1));
        let md = d.markdown();
        assert!(
            md.contains("contacts gone (2): head_on 3 #1, head_on 5 #2"),
            "{md}"
        );
        assert!(md.contains("contacts new (1): head_on 8 #2"), "{md}");
    }

    #[test]
    fn the_sign_test_tells_a_real_change_from_noise() {
        assert_eq!(sign_test(0, 0), None);
        // 1 against 1: nothing to see.
        assert!((sign_test(1, 1).unwrap() - 1.0).abs() < 1e-12);
        // 5 against 0: 2 · 2⁻⁵.
        assert!((sign_test(5, 0).unwrap() - 0.0625).abs() < 1e-12);
        assert_eq!(sign_test(0, 5), sign_test(5, 0));
        // 13 gone, 20 new (a lane-offset trial): no evidence either way.
        assert!(sign_test(13, 20).unwrap() > 0.2);
        // 40 gained, 10 lost: real.
        assert!(sign_test(40, 10).unwrap() < 0.001);
        // Large n stays finite.
        let p = sign_test(5000, 5000).unwrap();
        assert!(p.is_finite() && p > 0.9, "{p}");
    }
}
