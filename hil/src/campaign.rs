//! `hil faults`: the fault campaign — each scenario flown under each kind of fault, one table.
//!
//! ```text
//! hil faults [SCENARIO.toml...] [--kinds none,ber,drops,freeze,loss,dropout,all]
//!            [--params RECIPE.toml] [--jobs N] [--out DIR]
//! ```
//!
//! The strengths are the ones the fault issue measured the firmware against: a bit-error rate
//! of 10⁻³ on every byte sent to the firmware, 20 % of the frames dropped, navigation frozen
//! (the same fix, fresh time stamps) or lost from 60 s to 80 s, no sonar from 60 s to 120 s, and
//! all of them at once. Every run is in lockstep with the host-process firmware and ends at
//! arrival, at the first contact or at the scenario's duration. A cell says whether the vehicle
//! reached its goal, its least clearance, and for navigation loss how long after the loss the
//! firmware held (within two periods of the navigation timeout, 1 s by default).

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use crate::error::Error;
use crate::output::metrics::Summary;
use crate::output::RunOutput;
use crate::runner::{run_quiet, QuietRun};
use crate::scenario::{self, Scenario, Window};
use crate::sweep::pool;

/// A kind of fault, at the campaign's strength.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// No fault: the baseline.
    None,
    /// Bit errors at 10⁻³ on every byte to the firmware.
    BitErrors,
    /// 20 % of the frames to the firmware dropped.
    Drops,
    /// The same navigation fix (fresh time stamps) from 60 s to 80 s.
    NavFreeze,
    /// No navigation from 60 s to 80 s.
    NavLoss,
    /// No sonar from 60 s to 120 s.
    SonarDropout,
    /// All of the above at once.
    All,
}

/// Every kind, in table order.
pub const KINDS: [Kind; 7] = [
    Kind::None,
    Kind::BitErrors,
    Kind::Drops,
    Kind::NavFreeze,
    Kind::NavLoss,
    Kind::SonarDropout,
    Kind::All,
];

/// The navigation fault window, s.
pub const NAV_WINDOW: Window = Window {
    from_s: 60.0,
    to_s: 80.0,
};
/// The sonar dropout window, s.
pub const SONAR_WINDOW: Window = Window {
    from_s: 60.0,
    to_s: 120.0,
};

impl Kind {
    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Kind::None => "none",
            Kind::BitErrors => "ber",
            Kind::Drops => "drops",
            Kind::NavFreeze => "freeze",
            Kind::NavLoss => "loss",
            Kind::SonarDropout => "dropout",
            Kind::All => "all",
        }
    }

    /// The column heading: what was done, as `hil run` options.
    pub fn heading(self) -> &'static str {
        match self {
            Kind::None => "none",
            Kind::BitErrors => "`--bit-error-rate 1e-3`",
            Kind::Drops => "`--drop-rate 0.2`",
            Kind::NavFreeze => "`--nav-freeze 60:80`",
            Kind::NavLoss => "`--nav-loss 60:80`",
            Kind::SonarDropout => "`--sonar-dropout 60:120`",
            Kind::All => "all combined",
        }
    }

    fn parse(s: &str) -> Option<Kind> {
        KINDS.into_iter().find(|k| k.name() == s)
    }

    /// `sc` with this fault added (its own faults, if any, are replaced).
    pub fn apply(self, sc: &Scenario) -> Scenario {
        let mut sc = sc.clone();
        let f = &mut sc.faults;
        *f = Default::default();
        let all = self == Kind::All;
        if all || self == Kind::BitErrors {
            f.bit_error_rate = 1e-3;
        }
        if all || self == Kind::Drops {
            f.drop_rate = 0.2;
        }
        if all || self == Kind::NavFreeze {
            f.nav_freeze = Some(NAV_WINDOW);
        }
        // Combined, the loss follows the freeze (the runner takes one window of each).
        if self == Kind::NavLoss {
            f.nav_loss = Some(NAV_WINDOW);
        }
        if all {
            f.nav_loss = Some(Window {
                from_s: NAV_WINDOW.to_s,
                to_s: NAV_WINDOW.to_s + 10.0,
            });
        }
        if all || self == Kind::SonarDropout {
            f.sonar_dropout = Some(SONAR_WINDOW);
        }
        sc
    }
}

/// How one vehicle did under one fault.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Outcome {
    /// Vehicle name.
    pub vehicle: String,
    /// Reached its goal (the metrics' rule).
    pub reached: bool,
    /// First time within the arrival radius, s.
    pub time_to_goal_s: Option<f64>,
    /// Closest approach to the goal, m.
    pub closest_m: Option<f64>,
    /// Least signed clearance, m (negative: contact).
    pub min_clearance_m: Option<f64>,
    /// Contact episodes.
    pub collisions: u32,
    /// Separate stale-navigation holds (entries into `Hold(StaleNav)`).
    pub stale_nav_holds: u32,
    /// Under navigation loss: seconds from the loss to the first hold (`None`: never held,
    /// or the run ended before the loss).
    pub hold_after_loss_s: Option<f64>,
    /// The run ended before the fault window opened (arrived first): the fault was not tried.
    pub before_fault: bool,
}

/// One cell: a scenario under a fault, every vehicle (or why the run failed).
#[derive(Clone, Debug, serde::Serialize)]
pub struct Cell {
    /// Scenario name.
    pub scenario: String,
    /// The fault's name.
    pub kind: &'static str,
    /// Per vehicle, or the error.
    pub result: Result<Vec<Outcome>, String>,
}

/// Measures a finished run under `kind`.
pub fn outcomes(out: &RunOutput, kind: Kind) -> Vec<Outcome> {
    let s = Summary::of(out);
    let window_from = match kind {
        Kind::None | Kind::BitErrors | Kind::Drops => None,
        Kind::SonarDropout => Some(SONAR_WINDOW.from_s),
        _ => Some(NAV_WINDOW.from_s),
    };
    out.vehicles
        .iter()
        .zip(&s.vehicles)
        .map(|(rec, m)| {
            let stale = |mode: &str| mode == "Hold(StaleNav)";
            let stale_nav_holds = rec
                .samples
                .windows(2)
                .filter(|w| stale(&w[1].mode) && !stale(&w[0].mode))
                .count() as u32;
            let hold_after_loss_s = (kind == Kind::NavLoss)
                .then(|| {
                    rec.samples
                        .iter()
                        .find(|x| x.t >= NAV_WINDOW.from_s && stale(&x.mode))
                        .map(|x| x.t - NAV_WINDOW.from_s)
                })
                .flatten();
            let last_t = rec.samples.last().map_or(0.0, |x| x.t);
            Outcome {
                vehicle: m.name.clone(),
                reached: m.reached_goal,
                time_to_goal_s: m.time_to_goal_s,
                closest_m: m.min_goal_distance_m,
                min_clearance_m: m.min_clearance_m,
                collisions: m.collisions,
                stale_nav_holds,
                hold_after_loss_s,
                before_fault: window_from.is_some_and(|from| last_t < from),
            }
        })
        .collect()
}

/// Flies `sc` under `kind` on `run`'s firmware.
pub fn fly(sc: &Scenario, kind: Kind, run: &QuietRun) -> Cell {
    Cell {
        scenario: sc.name.clone(),
        kind: kind.name(),
        result: run_quiet(&kind.apply(sc), run)
            .map(|out| outcomes(&out, kind))
            .map_err(|e| e.to_string()),
    }
}

/// The text of one cell: `reached 118 s, +1.41 m`, `not reached (10.5 m), +4.95 m`,
/// `**collided** (−0.84 m)`, with `hold +0.1 s` under navigation loss.
pub fn describe(o: &Outcome) -> String {
    let clearance = o
        .min_clearance_m
        .map_or_else(|| "–".to_string(), |c| format!("{c:+.2} m"));
    let mut s = if o.collisions > 0 {
        format!("**collided** ({clearance})")
    } else if o.reached {
        format!(
            "reached {:.0} s, {clearance}",
            o.time_to_goal_s.unwrap_or(0.0)
        )
    } else {
        format!(
            "**not reached** ({:.1} m short), {clearance}",
            o.closest_m.unwrap_or(f64::NAN)
        )
    };
    if o.before_fault {
        s.push_str(", arrived before the fault");
    }
    if let Some(h) = o.hold_after_loss_s {
        let _ = write!(s, ", hold +{h:.1} s");
    }
    if o.stale_nav_holds > 1 {
        let _ = write!(s, ", {} nav holds", o.stale_nav_holds);
    }
    s
}

/// The table: one row per scenario and vehicle, one column per kind.
pub fn markdown(scenarios: &[Scenario], kinds: &[Kind], cells: &[Cell]) -> String {
    let mut t = String::from("| scenario |");
    for k in kinds {
        let _ = write!(t, " {} |", k.heading());
    }
    t.push_str("\n|---|");
    t.push_str(&"---|".repeat(kinds.len()));
    t.push('\n');
    for (i, sc) in scenarios.iter().enumerate() {
        for (v, vehicle) in sc.vehicles.iter().enumerate() {
            let _ = write!(t, "| {}", sc.name);
            if sc.vehicles.len() > 1 {
                let _ = write!(t, " ({})", vehicle.name);
            }
            t.push_str(" |");
            for j in 0..kinds.len() {
                let text = match &cells[i * kinds.len() + j].result {
                    Ok(o) => o.get(v).map_or_else(|| "–".into(), describe),
                    Err(e) => format!("run failed: {e}"),
                };
                let _ = write!(t, " {text} |");
            }
            t.push('\n');
        }
    }
    t
}

/// The scenarios the fault issue measured, flown when none are given.
pub const DEFAULT_SCENARIOS: [&str; 3] = [
    "hil/scenarios/random_clutter.toml",
    "hil/scenarios/narrow_gap.toml",
    "hil/scenarios/crossing_traffic.toml",
];

/// `hil faults`'s command line.
#[derive(Clone, Debug, clap::Parser)]
#[command(
    name = "hil faults",
    long_about = "Flies each scenario under each kind of fault on the host-process firmware (lockstep) \
             and prints one table: reached or not, least clearance, and under navigation loss how \
             soon the firmware held. Without scenarios: random_clutter, narrow_gap and \
             crossing_traffic from hil/scenarios.",
    after_help = "Any cell can be flown again with its plots: hil run SCENARIO.toml --firmware host \
                  <the column's options>."
)]
pub struct Args {
    /// scenario files (default: random_clutter, narrow_gap and crossing_traffic)
    #[arg(value_name = "SCENARIO.toml")]
    scenarios: Vec<PathBuf>,
    /// none, ber (--bit-error-rate 1e-3), drops (--drop-rate 0.2), freeze (--nav-freeze 60:80),
    /// loss (--nav-loss 60:80), dropout (--sonar-dropout 60:120), all (combined; the loss
    /// follows the freeze, 80:90) (default: all seven)
    #[arg(long, value_name = "a,b,...", value_delimiter = ',', value_parser = kind)]
    kinds: Vec<Kind>,
    /// planner parameters from a recipe (replace each scenario's [planner])
    #[arg(long, value_name = "RECIPE.toml")]
    params: Option<PathBuf>,
    /// worker threads (default: all cores)
    #[arg(long, value_name = "N", value_parser = pool::jobs)]
    jobs: Option<usize>,
    /// also write faults.md and faults.json there
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

fn kind(s: &str) -> Result<Kind, String> {
    Kind::parse(s.trim()).ok_or_else(|| format!("unknown kind `{s}`"))
}

/// What to fly.
#[derive(Clone, Debug)]
struct Options {
    scenarios: Vec<PathBuf>,
    kinds: Vec<Kind>,
    params: Option<PathBuf>,
    jobs: Option<usize>,
    out: Option<PathBuf>,
}

impl From<Args> for Options {
    fn from(a: Args) -> Self {
        Options {
            scenarios: if a.scenarios.is_empty() {
                DEFAULT_SCENARIOS.iter().map(PathBuf::from).collect()
            } else {
                a.scenarios
            },
            kinds: if a.kinds.is_empty() {
                KINDS.to_vec()
            } else {
                a.kinds
            },
            params: a.params,
            jobs: a.jobs,
            out: a.out,
        }
    }
}

/// Loads the scenarios (a recipe's `[planner]` replacing theirs).
fn load(o: &Options) -> Result<Vec<Scenario>, Error> {
    let recipe = match &o.params {
        Some(p) => Some((
            std::fs::read_to_string(p).map_err(Error::io("cannot read", p))?,
            p.display().to_string(),
        )),
        None => None,
    };
    o.scenarios
        .iter()
        .map(|path| {
            let mut sc = scenario::load(path)?;
            if let Some((text, file)) = &recipe {
                sc.params = scenario::parse_planner(text, file, sc.dt_s)?;
            }
            Ok(sc)
        })
        .collect()
}

/// `hil faults ...`.
pub fn cli(args: Args) -> ExitCode {
    match campaign(&args.into()) {
        Ok(table) => {
            println!("{table}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("hil faults: {e}");
            ExitCode::FAILURE
        }
    }
}

fn campaign(o: &Options) -> Result<String, Error> {
    let scenarios = load(o)?;
    if let Some(dir) = &o.out {
        std::fs::create_dir_all(dir).map_err(Error::io("cannot create", dir))?;
    }
    let run = QuietRun::host_until_done().map_err(Error::Build)?;
    let jobs = o.jobs.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(2, std::num::NonZeroUsize::get)
    });
    let n = o.kinds.len();
    let total = scenarios.len() * n;
    let mut cells: Vec<Option<Cell>> = vec![None; total];
    let pending: Vec<usize> = (0..total).collect();
    let work = |i: usize| (i, fly(&scenarios[i / n], o.kinds[i % n], &run));
    pool::run_all(&work, &pending, jobs, false, 0, total, |(i, cell)| {
        cells[i] = Some(cell);
        Ok(())
    })?;
    let cells: Vec<Cell> = cells.into_iter().flatten().collect();
    let table = markdown(&scenarios, &o.kinds, &cells);
    if let Some(dir) = &o.out {
        let write = |name: &str, text: String| {
            let p = dir.join(name);
            std::fs::write(&p, text).map_err(Error::io("cannot write", &p))
        };
        write("faults.md", table.clone())?;
        let json = serde_json::to_string_pretty(&cells)?;
        write("faults.json", json + "\n")?;
    }
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::*;

    use clap::Parser as _;

    fn parse(args: &[&str]) -> Result<Options, clap::Error> {
        Args::try_parse_from(std::iter::once("faults").chain(args.iter().copied())).map(Into::into)
    }

    #[test]
    fn arguments_parse_and_refuse_with_a_reason() {
        let o = parse(&["a.toml", "--kinds", "ber,loss"]).unwrap();
        assert_eq!(o.kinds, [Kind::BitErrors, Kind::NavLoss]);
        assert_eq!(o.scenarios, [PathBuf::from("a.toml")]);
        let o = parse(&[]).unwrap();
        assert_eq!(o.kinds, KINDS);
        assert_eq!(o.scenarios.len(), DEFAULT_SCENARIOS.len());
        let e = parse(&["--kinds", "ber,eels"]).unwrap_err().to_string();
        assert!(e.contains("eels"), "{e}");
        let help = parse(&["--help"]).unwrap_err();
        assert_eq!(help.kind(), clap::error::ErrorKind::DisplayHelp);
    }

    #[test]
    fn each_kind_sets_its_fault_and_only_its_fault() {
        let sc = scenario::parse(
            "name = \"t\"\nduration_s = 10.0\ndt_s = 0.1\nseed = 1\n[faults]\n\
             drop_rate = 0.5\n[[vehicle]]\nname = \"a\"\nmodel = \"kinematic\"\n\
             start = [0.0, 0.0]\ngoal = [10.0, 0.0]\n",
            "t.toml",
        )
        .unwrap();
        let none = Kind::None.apply(&sc).faults;
        assert_eq!(
            none.drop_rate, 0.0,
            "the scenario's own faults are replaced"
        );
        assert_eq!(Kind::BitErrors.apply(&sc).faults.bit_error_rate, 1e-3);
        assert_eq!(Kind::NavLoss.apply(&sc).faults.nav_loss, Some(NAV_WINDOW));
        assert_eq!(Kind::NavLoss.apply(&sc).faults.bit_error_rate, 0.0);
        let all = Kind::All.apply(&sc).faults;
        assert!(all.bit_error_rate > 0.0 && all.drop_rate > 0.0);
        assert!(all.nav_freeze.is_some() && all.nav_loss.is_some() && all.sonar_dropout.is_some());
    }
}
