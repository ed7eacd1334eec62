//! One benchmark run: a generated world, checked feasible for the craft, written as a scenario
//! file, flown in lockstep with the host-process firmware, and measured into a [`Row`].

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::Read as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use vpf::{Params, Strategy};

use super::feasible::{self, Infeasible};
use super::turning;
use super::worlds::{self, Family, World};
use crate::error::Error;
use crate::output::{plot, RunOutput, Summary};
use crate::runner::{hull_radius, run_quiet, turning_radius, QuietRun};
use crate::scenario::{self, Sensing};
use crate::sim::ModelKind;
use crate::sweep::generate::{obstacle_table, wrap_deg};
use crate::types::P2;

/// Redraws of an infeasible world before it is given up.
pub const MAX_ATTEMPTS: u64 = 20;
/// Room beyond the hull the feasibility search requires, m.
pub const FEASIBLE_MARGIN_M: f64 = 0.5;
/// Cruise speed of the reference time, m/s: the planner's default v_max, which the VideoRay
/// reaches (its top speed is about 1.4 m/s) and the flat-fish cruises at (seed 003 §5).
pub const CRUISE_MPS: f64 = 1.0;

/// The sonar head's set-up a bench flies: its range (also the contacts' range with perfect
/// perception) and step. [`Default`]: the scenario schema's (`scenario::Sonar`), which is
/// what a VideoRay carries ([`Head::carried_by`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Head {
    /// Range, m.
    pub range_m: f64,
    /// Step, degrees.
    pub step_deg: f64,
}

impl Head {
    /// The set-up `model` carries unless the bench is told another: the default's step, and
    /// the range a scenario gives it (`scenario::Sonar::range_carried_by`: 40 m for the
    /// flat-fish, whose simulated head then sweeps in 5.8 s).
    pub fn carried_by(model: ModelKind) -> Head {
        Head {
            range_m: crate::scenario::Sonar::range_carried_by(model),
            ..Head::default()
        }
    }

    /// `sonar 20 m, 3.6° steps`: how the tables name it.
    pub fn name(&self) -> String {
        format!("sonar {} m, {}° steps", self.range_m, round3(self.step_deg))
    }
}

/// `x` to three decimals (3.6, not the 3.6000000000000005 of a round trip through radians).
fn round3(x: f64) -> f64 {
    (x * 1000.0).round() / 1000.0
}

impl Default for Head {
    fn default() -> Self {
        let d = scenario::Sonar::default();
        Head {
            range_m: d.range_m,
            step_deg: d.step.to_degrees(),
        }
    }
}

/// What to fly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Case {
    /// World family.
    pub family: Family,
    /// World seed.
    pub seed: u64,
    /// Planner strategy.
    pub strategy: Strategy,
    /// Vehicle model.
    pub model: ModelKind,
    /// Sensing.
    pub sensing: Sensing,
    /// The sea's draw ([`Case::sim_seed`]): 0 flies the world with its own seed.
    pub trial: u64,
    /// The sonar's set-up.
    pub head: Head,
    /// A steady current of this speed, m/s, its direction drawn from the world's seed
    /// ([`Case::current`]); 0: still water.
    pub current_mps: f64,
}

impl Case {
    /// World `seed` of `family` as the bench flies it by default: VPF, a VideoRay, its own
    /// sonar (the default head), trial 0, still water. Other flights are this with fields
    /// replaced (`Case { model: ModelKind::FlatFish, ..Case::new(family, seed) }`).
    pub fn new(family: Family, seed: u64) -> Case {
        Case {
            family,
            seed,
            strategy: Strategy::Vpf,
            model: ModelKind::VideoRay,
            sensing: Sensing::Sonar,
            trial: 0,
            head: Head::default(),
            current_mps: 0.0,
        }
    }

    /// The simulation's seed — the sonar's noise, speckle and false echoes, and every other
    /// draw of the flight: the world's seed for trial 0, else one mixed from both, so another
    /// trial flies the same world through other chance (`hil bench --trial`).
    pub fn sim_seed(&self) -> u64 {
        if self.trial == 0 {
            return self.seed;
        }
        let mixed = crate::sweep::fnv1a(&[&self.seed.to_le_bytes(), &self.trial.to_le_bytes()]);
        // The scenario schema's seed is a non-negative TOML integer (an i64).
        mixed >> 1
    }

    /// The current's velocity over ground, m/s: [`Case::current_mps`] in a direction drawn
    /// from the world's seed alone, so every strategy, model and trial of a world meets the
    /// same water.
    pub fn current(&self) -> P2 {
        let draw = crate::sweep::fnv1a(&[b"current", &self.seed.to_le_bytes()]);
        let a = (draw % 3600) as f64 / 3600.0 * std::f64::consts::TAU;
        P2::new(a.cos(), a.sin()).scale(self.current_mps)
    }

    /// `clutter:3:vpf:videoray:scanlines`: the row's key in `runs.jsonl`.
    pub fn id(&self) -> String {
        format!(
            "{}:{}:{}:{}:{}",
            self.family.name(),
            self.seed,
            self.strategy.name(),
            self.model.name(),
            sensing_name(self.sensing)
        )
    }

    /// The configuration column of the tables: `vpf / videoray / scanlines`.
    pub fn config(&self) -> String {
        format!(
            "{} / {} / {}",
            self.strategy.name(),
            self.model.name(),
            sensing_name(self.sensing)
        )
    }
}

/// `scanlines` or `contacts`.
pub fn sensing_name(s: Sensing) -> &'static str {
    match s {
        Sensing::Sonar => "scanlines",
        Sensing::Contacts => "contacts",
    }
}

/// One finished run (one line of `runs.jsonl`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// [`Case::id`].
    pub id: String,
    /// Family name.
    pub family: String,
    /// World seed.
    pub seed: u64,
    /// `strategy / model / sensing`.
    pub config: String,
    /// Reached the goal (every vehicle) and no contact.
    pub success: bool,
    /// Some vehicle touched an obstacle or another vehicle.
    pub collided: bool,
    /// Worst signed clearance over the run, m.
    pub min_clearance_m: Option<f64>,
    /// Time to the last arrival over the reference time (shortest feasible path at cruise
    /// speed), when every vehicle arrived.
    pub time_ratio: Option<f64>,
    /// Path flown over the shortest feasible path (the longest-flying vehicle's).
    pub path_ratio: Option<f64>,
    /// The reference time, s.
    pub reference_s: Option<f64>,
    /// Periods whose command the guard changed (all vehicles).
    pub guard_periods: u32,
    /// Where the time under way went ([`time_shares`]): the share commanded at cruise (80 % of
    /// v_max or more) ...
    pub cruise_frac: Option<f64>,
    /// ... and the share the guard held the vehicle stopped.
    pub held_frac: Option<f64>,
    /// For true obstacle surface within sonar range, the distance to the nearest believed
    /// obstacle, m (p95); filled when the firmware reports what it believed.
    pub perception_miss_m: Option<f64>,
    /// The same distance's mean, m.
    pub perception_miss_mean_m: Option<f64>,
    /// Share of believed obstacle cells with no true surface near them.
    pub perception_false_frac: Option<f64>,
    /// A formation world's spacing error in transit ([`formation_spacing`]), a share of λ.
    #[serde(default)]
    pub formation_spacing: Option<f64>,
    /// How far the current the firmware believed at its last telemetry was from the true one
    /// (`--current`; zero in still water), m/s: the worst vehicle's.
    #[serde(default)]
    pub current_error_mps: Option<f64>,
    /// Why the run was not flown or failed to run (then `success` is false).
    pub error: Option<String>,
}

impl Row {
    /// A run not (yet) flown: no success, no contact, nothing measured.
    pub fn unflown(id: String, family: &str, seed: u64, config: String) -> Row {
        Row {
            id,
            family: family.to_string(),
            seed,
            config,
            success: false,
            collided: false,
            min_clearance_m: None,
            time_ratio: None,
            path_ratio: None,
            reference_s: None,
            guard_periods: 0,
            cruise_frac: None,
            held_frac: None,
            perception_miss_m: None,
            perception_miss_mean_m: None,
            perception_false_frac: None,
            formation_spacing: None,
            current_error_mps: None,
            error: None,
        }
    }
}

/// Largest `runs.jsonl` read, bytes (a row is under 1 KiB; `MAX_RUNS` of them fit).
pub const MAX_ROWS_BYTES: u64 = 128 << 20;

/// The rows of a bench directory's `runs.jsonl` (or of that file), by run id. A line that does
/// not parse (a cut-off last line) is skipped; a later row for the same id replaces an earlier.
pub fn read_rows(path: &Path) -> Result<BTreeMap<String, Row>, Error> {
    read_rows_within(path, MAX_ROWS_BYTES)
}

/// [`read_rows`], refusing a file longer than `max_bytes`.
fn read_rows_within(path: &Path, max_bytes: u64) -> Result<BTreeMap<String, Row>, Error> {
    let file = if path.is_dir() {
        path.join("runs.jsonl")
    } else {
        path.to_path_buf()
    };
    let f = std::fs::File::open(&file).map_err(Error::io("cannot open", &file))?;
    let mut text = String::new();
    f.take(max_bytes.saturating_add(1))
        .read_to_string(&mut text)
        .map_err(Error::io("cannot read", &file))?;
    if text.len() as u64 > max_bytes {
        return Err(Error::Unreadable {
            path: file,
            message: format!("larger than {max_bytes} bytes: not a bench's runs"),
        });
    }
    Ok(text
        .lines()
        .filter_map(|l| serde_json::from_str::<Row>(l).ok())
        .map(|r| (r.id.clone(), r))
        .collect())
}

/// A world drawn for a case and found feasible for its craft ([`feasible_world`]).
pub struct Drawn {
    /// The world.
    pub world: World,
    /// Which draw of the (family, seed) it is.
    pub attempt: u64,
    /// The shortest path of the longest mission, m.
    pub shortest_m: f64,
    /// The reference time, s: that path at [`CRUISE_MPS`]; for a craft with a turning
    /// radius, its first leg no faster than the craft can fly it from its start pose
    /// (`turning::least_time`: a 40 m mission that starts pointing into an L-shaped trap
    /// takes the flat-fish 81 m at cruise, slowing to turn).
    pub reference_s: f64,
}

/// The world of `case`, feasible for its craft. Feasible: every vehicle has a way through its
/// mission that keeps its hull and [`FEASIBLE_MARGIN_M`] from every static obstacle
/// (`feasible`; a waypoint mission leg by leg, from the start to the first waypoint and from
/// each to the next, its shortest path the legs' sum), and, for a craft with a turning radius
/// (`crate::runner::turning_radius`), one it can fly on that radius from its start pose to its
/// first waypoint without slowing to turn (`turning`). Worlds are drawn for the craft's hull
/// (`worlds::generate`: a formation's lattice).
pub fn feasible_world(case: &Case) -> Result<Drawn, Infeasible> {
    let hull = hull_radius(case.model);
    let clearance = hull + FEASIBLE_MARGIN_M;
    let radius = turning_radius(case.model);
    let mut last = Infeasible::NoPath;
    for attempt in 0..MAX_ATTEMPTS {
        let w = worlds::generate(case.family, case.seed, attempt, hull);
        let (mut longest, mut slowest): (f64, f64) = (0.0, 0.0);
        let mut ok = true;
        'crafts: for c in &w.crafts {
            // A craft that turns on a radius flies its first leg from its start pose.
            let mut turning_first = 0.0;
            if radius > 0.0 {
                let first = w.legs(c).into_iter().next().unwrap_or(c.goal);
                let (o, s, h) = (&w.obstacles, c.start, c.heading);
                match turning::reachable(o, s, h, first, clearance, radius)
                    .and_then(|_| turning::least_time(o, s, h, first, clearance, radius))
                {
                    Ok(d) => turning_first = d,
                    Err(e) => {
                        last = e;
                        ok = false;
                        break 'crafts;
                    }
                }
            }
            let mut from = c.start;
            let (mut total, mut timed) = (0.0, 0.0);
            for (i, to) in w.legs(c).into_iter().enumerate() {
                match feasible::shortest_path(&w.obstacles, from, to, clearance) {
                    Ok(d) => {
                        total += d;
                        timed += if i == 0 { d.max(turning_first) } else { d };
                    }
                    Err(e) => {
                        last = e;
                        ok = false;
                        break 'crafts;
                    }
                }
                from = to;
            }
            longest = longest.max(total);
            slowest = slowest.max(timed);
        }
        if ok {
            return Ok(Drawn {
                world: w,
                attempt,
                shortest_m: longest,
                reference_s: slowest / CRUISE_MPS,
            });
        }
    }
    Err(last)
}

/// The scenario file of `world` for `case`, flown for `duration_s`.
pub fn scenario_text(world: &World, attempt: u64, case: &Case, duration_s: f64) -> String {
    let mut t = String::new();
    let trial = match case.trial {
        0 => String::new(),
        k => format!(", trial {k}"),
    };
    let _ = writeln!(
        t,
        "# Generated by `hil bench`: family {}, seed {}, attempt {attempt}{trial}.",
        case.family.name(),
        case.seed
    );
    let _ = writeln!(t, "name = \"{}\"", case.id());
    let _ = writeln!(
        t,
        "duration_s = {duration_s:.1}\ndt_s = 0.1\nseed = {}",
        case.sim_seed()
    );
    let _ = writeln!(t, "\n[planner]\nstrategy = \"{}\"", case.strategy.name());
    let _ = writeln!(
        t,
        "\n[sonar]\nmode = \"{}\"\nrange_m = {:.2}\nstep_deg = {:.3}",
        sensing_name(case.sensing),
        case.head.range_m,
        case.head.step_deg
    );
    if world.formation_m.is_some() {
        // The virtual leader needs the neighbours' positions (seed 001 takes them as known).
        t.push_str("vehicle_contacts = true\n");
    }
    if case.current_mps > 0.0 {
        let c = case.current();
        let _ = writeln!(t, "\n[current]\nvelocity = [{:.4}, {:.4}]", c.x, c.y);
    }
    let sensing = match case.sensing {
        Sensing::Sonar => "sonar",
        Sensing::Contacts => "contacts",
    };
    for (k, c) in world.crafts.iter().enumerate() {
        // A survey's goal is its last waypoint.
        let goal = match world.survey {
            Some(_) => String::new(),
            None => format!("goal = [{:.3}, {:.3}]\n", c.goal.x, c.goal.y),
        };
        let _ = writeln!(
            t,
            "\n[[vehicle]]\nname = \"v{k}\"\nmodel = \"{}\"\nstart = [{:.3}, {:.3}]\n\
             heading_deg = {:.3}\n{goal}sensing = \"{sensing}\"",
            case.model.name(),
            c.start.x,
            c.start.y,
            wrap_deg(c.heading.to_degrees()),
        );
        if let Some(l) = world.formation_m {
            let _ = writeln!(t, "formation = {{ q = 4, lattice_m = {l:.1} }}");
        }
        if let Some(s) = world.survey {
            let _ = writeln!(
                t,
                "\n[vehicle.survey]\ncorner = [{:.4}, {:.4}]\nlength_m = {:.4}\n\
                     width_m = {:.4}\nheading_deg = {:.6}\nspacing_m = {:.4}\nradius_m = {:.2}",
                s.corner.x,
                s.corner.y,
                s.length_m,
                s.width_m,
                f64::from(s.heading).to_degrees(),
                s.spacing_m,
                s.radius_m
            );
        }
    }
    for o in &world.obstacles {
        obstacle_table(&mut t, &o.shape, o.velocity);
    }
    t
}

/// How long a run may take: three reference times and a minute, at least two minutes.
pub fn duration_s(reference_s: f64) -> f64 {
    (3.0 * reference_s + 60.0).max(120.0)
}

/// A recipe's planner parameters and the file they came from.
pub type Recipe<'a> = (&'a Params, &'a Path);

/// Flies `case` and measures it. `recipe`: planner parameters from a recipe (the case's
/// strategy kept). `failed_dir`: where a failed run's plot and scenario file go.
pub fn fly(case: &Case, recipe: Option<Recipe>, run: &QuietRun, failed_dir: &Path) -> Row {
    fly_keeping(case, recipe, run, failed_dir, None)
}

/// [`fly`], also keeping the run's scenario file under `worlds_dir/<id>/` whatever its outcome
/// (`hil bench --keep-worlds`).
pub fn fly_keeping(
    case: &Case,
    recipe: Option<Recipe>,
    run: &QuietRun,
    failed_dir: &Path,
    worlds_dir: Option<&Path>,
) -> Row {
    let mut row = Row::unflown(case.id(), case.family.name(), case.seed, case.config());
    let Drawn {
        world,
        attempt,
        shortest_m: shortest,
        reference_s: reference,
    } = match feasible_world(case) {
        Ok(d) => d,
        Err(e) => {
            row.error = Some(format!("no feasible draw in {MAX_ATTEMPTS}: {e}"));
            return row;
        }
    };
    row.reference_s = Some(reference);
    let hold_s = case.family.hold_s();
    let text = scenario_text(&world, attempt, case, duration_s(reference) + hold_s);
    let mut sc = match scenario::parse(&text, &case.id()) {
        Ok(s) => s,
        Err(e) => {
            row.error = Some(format!("generated scenario refused: {e}"));
            return row;
        }
    };
    if let Some((p, _)) = recipe {
        sc.params = Params {
            strategy: case.strategy,
            period_s: sc.dt_s as f32,
            ..*p
        };
    }
    let run = QuietRun {
        hold_s,
        ..run.clone()
    };
    let out = match run_quiet(&sc, &run) {
        Ok(o) => o,
        Err(e) => {
            row.error = Some(e.to_string());
            return row;
        }
    };
    measure(&mut row, &out, &world, shortest, reference);
    row.success &= held(&out, hold_s);
    let text = || format!("{}{text}", flown_with(recipe.map(|(_, f)| f)));
    if !row.success {
        keep_failure(failed_dir, case, &text(), &out);
    }
    if let Some(dir) = worlds_dir {
        let d = dir.join(crate::output::file_stem(&case.id()));
        if std::fs::create_dir_all(&d).is_ok() {
            let _ = std::fs::write(d.join("world.toml"), text());
        }
    }
    row
}

/// Fills `row` from a finished run.
fn measure(row: &mut Row, out: &RunOutput, world: &World, shortest: f64, reference: f64) {
    let s = Summary::of(out);
    let vs = &s.vehicles;
    row.collided = vs.iter().any(|v| v.collisions > 0);
    row.min_clearance_m = vs.iter().filter_map(|v| v.min_clearance_m).reduce(f64::min);
    row.guard_periods = vs
        .iter()
        .filter_map(|v| v.counters.map(|c| c.guard_interventions))
        .sum();
    (row.cruise_frac, row.held_frac) = time_shares(out);
    row.formation_spacing = world.formation_m.and_then(|l| formation_spacing(out, l));
    row.current_error_mps = vs
        .iter()
        .filter_map(|v| v.current_believed)
        .map(|[x, y]| P2::new(x, y).sub(out.current).norm())
        .reduce(f64::max);
    // Perception: the worst vehicle's miss, the fleet's mean share of false cells.
    let seen: Vec<_> = vs.iter().filter_map(|v| v.perception).collect();
    row.perception_miss_m = seen.iter().map(|p| p.miss_p95_m).reduce(f64::max);
    row.perception_miss_mean_m = seen.iter().map(|p| p.miss_mean_m).reduce(f64::max);
    row.perception_false_frac = (!seen.is_empty())
        .then(|| seen.iter().map(|p| p.false_frac).sum::<f64>() / seen.len() as f64);
    let arrived = match world.formation_m {
        // A formation settles round the goal, not on it: N + 1 lattice cells of side λ fit
        // within λ·√(N + 1) (as the planner's own arrival-in-formation test).
        Some(l) => {
            let reach = l * ((vs.len() + 1) as f64).sqrt() + 1.0;
            vs.iter()
                .all(|v| v.final_distance_m.is_some_and(|d| d <= reach))
        }
        None => vs.iter().all(|v| v.reached_goal),
    };
    row.success = !vs.is_empty() && arrived && !row.collided;
    let path = vs.iter().map(|v| v.path_length_m).fold(0.0, f64::max);
    row.path_ratio = (shortest > 0.0).then(|| path / shortest);
    let last = vs
        .iter()
        .map(|v| v.time_to_goal_s)
        .collect::<Option<Vec<f64>>>();
    row.time_ratio = match (world.formation_m, last) {
        (None, Some(t)) if reference > 0.0 => {
            Some(t.iter().fold(0.0f64, |a, &b| a.max(b)) / reference)
        }
        _ => None,
    };
}

/// Whether every vehicle, from its first sample within the arrival radius, stayed within
/// twice it for `hold_s` (trivially so with 0): it arrived and stayed, rather than touched
/// the goal and was pushed off (`hil bench --families berth`).
pub fn held(out: &RunOutput, hold_s: f64) -> bool {
    let r = out.arrival_radius_m;
    hold_s <= 0.0
        || out.vehicles.iter().all(|v| {
            let off = |s: &crate::types::Sample| s.state.position.sub(v.goal).norm();
            let after = v.samples.iter().skip_while(|s| off(s) > r);
            let (first, last) = (after.clone().next(), after.clone().last());
            after.clone().all(|s| off(s) <= 2.0 * r)
                && first
                    .zip(last)
                    .is_some_and(|(a, b)| b.t - a.t >= hold_s - 1e-6)
        })
}

/// A speed command under this, m/s, is a stop.
const STOPPED_MPS: f64 = 0.05;

/// Where a run's time under way went, over every vehicle's periods in transit, escaping a
/// trap or guarded (not holding, arrived or loitering): the share commanded at 80 % of v_max
/// or more, and the share the guard held the vehicle stopped. A run that times out with little
/// time at cruise was slowed — by turns, the field, the guard — rather than led astray; `None`
/// with no such period.
pub fn time_shares(out: &RunOutput) -> (Option<f64>, Option<f64>) {
    let cruise_at = 0.8 * f64::from(out.params.v_max);
    let (mut under_way, mut cruise, mut held) = (0u32, 0u32, 0u32);
    for s in out.vehicles.iter().flat_map(|v| &v.samples) {
        let guarded = s.mode == "Guarded";
        if !(guarded || s.mode == "Transit" || s.mode == "Escape") {
            continue;
        }
        under_way += 1;
        cruise += u32::from(s.speed_cmd >= cruise_at);
        held += u32::from(guarded && s.speed_cmd < STOPPED_MPS);
    }
    let share = |k: u32| (under_way > 0).then(|| f64::from(k) / f64::from(under_way));
    (share(cruise), share(held))
}

/// How well a formation kept its lattice `lattice` m in transit: over the periods in which
/// every vehicle is under way (transit, escaping or guarded: before the first arrives), each
/// vehicle's |distance to its nearest mate − λ| over λ, the mean. 0 is a formation kept on its
/// lattice; 1 is a vehicle a whole λ off (alone, or on top of a mate). Success alone cannot tell
/// a formation that held together from vehicles that each went their own way. `None` with
/// fewer than two vehicles or no such period.
pub fn formation_spacing(out: &RunOutput, lattice: f64) -> Option<f64> {
    let vs = &out.vehicles;
    let periods = vs.iter().map(|v| v.samples.len()).min()?;
    if vs.len() < 2 || lattice.is_nan() || lattice <= 0.0 {
        return None;
    }
    let under_way = |m: &str| matches!(m, "Transit" | "Escape" | "Guarded");
    let (mut sum, mut n) = (0.0, 0u32);
    for k in 0..periods {
        let at: Vec<(&str, P2)> = vs
            .iter()
            .filter_map(|v| v.samples.get(k))
            .map(|s| (s.mode.as_str(), s.state.position))
            .collect();
        if !at.iter().all(|(m, _)| under_way(m)) {
            continue;
        }
        for (i, (_, p)) in at.iter().enumerate() {
            let nearest = at
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, (_, q))| q.sub(*p).norm())
                .fold(f64::INFINITY, f64::min);
            sum += (nearest - lattice).abs() / lattice;
            n += 1;
        }
    }
    (n > 0).then(|| sum / f64::from(n))
}

/// The head of a failed run's scenario file flown with a recipe: the file does not carry the
/// recipe's `[planner]`, and without it `hil run` flies another planner.
fn flown_with(recipe: Option<&Path>) -> String {
    recipe.map_or_else(String::new, |f| {
        format!(
            "# Flown by the bench with `--params {0}`: fly it again as the bench did with\n\
             # `hil run world.toml --params {0}` (without it, the [planner] below).\n",
            f.display()
        )
    })
}

/// A failed run's plot and scenario file, under `dir/<id>/`, so `hil run` can fly it again.
fn keep_failure(dir: &Path, case: &Case, text: &str, out: &RunOutput) {
    let d: PathBuf = dir.join(crate::output::file_stem(&case.id()));
    if std::fs::create_dir_all(&d).is_ok() {
        let _ = std::fs::write(d.join("world.toml"), text);
        let _ = std::fs::write(d.join("plot.svg"), plot::render(out));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failure_flown_with_a_recipe_says_how_to_fly_it_again() {
        assert_eq!(flown_with(None), "");
        let head = flown_with(Some(Path::new("hil/recipes/flatfish.toml")));
        assert!(head.lines().all(|l| l.starts_with("# ")), "{head}");
        assert!(
            head.contains("--params hil/recipes/flatfish.toml"),
            "{head}"
        );
        let world = format!("{head}name = \"w\"\n");
        assert!(
            toml::from_str::<toml::Table>(&world).is_ok(),
            "still a scenario file"
        );
    }

    #[test]
    fn a_missing_or_oversized_file_is_refused_with_its_name() {
        let dir = std::env::temp_dir().join(format!("bench-diff-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let e = read_rows(&dir.join("nothing")).unwrap_err().to_string();
        assert!(e.contains("nothing"), "{e}");
        // A bench directory's runs.jsonl, with a cut-off last line.
        let line = serde_json::to_string(&Row::unflown(
            "rocks:3:vpf:videoray:scanlines".into(),
            "rocks",
            3,
            "vpf / videoray / scanlines".into(),
        ))
        .unwrap();
        std::fs::write(dir.join("runs.jsonl"), format!("{line}\n{{\"id\":\"cut")).unwrap();
        let rows = read_rows(&dir).unwrap();
        assert_eq!(rows.len(), 1);
        assert!(rows.contains_key("rocks:3:vpf:videoray:scanlines"));
        let e = read_rows_within(&dir, 64).unwrap_err().to_string();
        assert!(e.contains("larger than 64 bytes"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
    use worlds::{FAMILIES, MISSION_FAMILIES};

    #[test]
    fn time_under_way_is_split_into_cruise_and_held_by_the_guard() {
        let mut out = crate::output::test_support::run();
        out.params.v_max = 1.0;
        // Vehicle alpha: 4 periods at cruise, 2 held by the guard, 1 slow, 3 holding (not
        // under way); vehicle beta: 2 arrived (not under way) and 1 escaping at cruise.
        let plan = [
            ("Transit", 0.9),
            ("Transit", 0.8),
            ("Escape", 1.0),
            ("Guarded", 0.85),
            ("Guarded", 0.0),
            ("Guarded", 0.01),
            ("Transit", 0.3),
            ("Hold(StaleNav)", 0.0),
            ("Hold(NoMission)", 0.0),
            ("Hold(StaleNav)", 0.0),
        ];
        let set = |v: &mut crate::types::VehicleRecord, plan: &[(&str, f64)]| {
            v.samples.truncate(plan.len());
            for (s, (mode, speed)) in v.samples.iter_mut().zip(plan) {
                s.mode = (*mode).into();
                s.speed_cmd = *speed;
            }
        };
        set(&mut out.vehicles[0], &plan);
        set(
            &mut out.vehicles[1],
            &[("Arrived", 0.0), ("Arrived", 0.0), ("Escape", 0.95)],
        );
        let (cruise, held) = time_shares(&out);
        // Under way: 7 + 1 periods; at cruise 4 + 1; held 2.
        assert_eq!(cruise, Some(5.0 / 8.0));
        assert_eq!(held, Some(2.0 / 8.0));
        // Nothing under way: no shares.
        for v in &mut out.vehicles {
            set(v, &[("Hold(StaleNav)", 0.0)]);
        }
        assert_eq!(time_shares(&out), (None, None));
    }

    #[test]
    fn a_berth_is_held_only_by_a_vehicle_that_arrives_and_stays_for_the_hold() {
        let mut out = crate::output::test_support::run();
        out.arrival_radius_m = 1.0;
        out.vehicles.truncate(1);
        // One sample a second: 10 m out, then 0.5 m off the goal from t = 1 s.
        let at = |d: &[f64]| {
            let mut o = out.clone();
            let v = &mut o.vehicles[0];
            v.samples.truncate(d.len());
            for (k, (s, &d)) in v.samples.iter_mut().zip(d).enumerate() {
                s.t = k as f64;
                s.state.position = v.goal.add(P2::new(d, 0.0));
            }
            o
        };
        let stays = at(&[10.0, 0.5, 0.9, 1.9, 0.5, 0.5]);
        assert!(held(&stays, 4.0), "within twice the radius for 4 s");
        assert!(!held(&stays, 5.0), "the run ended before the hold did");
        assert!(
            !held(&at(&[10.0, 0.5, 2.1, 0.5, 0.5, 0.5]), 4.0),
            "pushed off"
        );
        assert!(!held(&at(&[10.0, 3.0, 2.0]), 1.0), "never arrived");
        assert!(held(&at(&[10.0, 3.0]), 0.0), "no hold asked");
    }

    #[test]
    fn a_formation_on_its_lattice_has_no_spacing_error_and_one_apart_has() {
        let mut out = crate::output::test_support::run();
        // Two vehicles 4 m apart for 3 periods, then 6 m for 1, then one arrived (not counted).
        let plan = [
            (4.0, "Transit"),
            (4.0, "Guarded"),
            (4.0, "Escape"),
            (6.0, "Transit"),
        ];
        for (i, v) in out.vehicles.iter_mut().enumerate() {
            v.samples.truncate(plan.len() + 1);
            for (k, s) in v.samples.iter_mut().enumerate() {
                let (gap, mode) = plan.get(k).copied().unwrap_or((40.0, "Arrived"));
                s.state.position = P2::new(i as f64 * gap, 0.0);
                s.mode = mode.into();
            }
        }
        // On a 4 m lattice: three periods on it, one half a λ off.
        let e = formation_spacing(&out, 4.0).unwrap();
        assert!((e - 0.5 / 4.0).abs() < 1e-12, "{e}");
        assert_eq!(formation_spacing(&out, 0.0), None);
        out.vehicles.truncate(1);
        assert_eq!(formation_spacing(&out, 4.0), None, "no mate");
    }

    #[test]
    fn the_world_file_names_the_sonar_set_up_it_was_flown_with() {
        let case = |head| Case {
            head,
            ..Case::new(Family::HeadOn, 3)
        };
        for head in [
            Head::default(),
            Head {
                range_m: 30.0,
                step_deg: 1.8,
            },
        ] {
            let c = case(head);
            let d = feasible_world(&c).unwrap();
            let sc = scenario::parse(&scenario_text(&d.world, d.attempt, &c, 100.0), "t").unwrap();
            assert_eq!(sc.sonar.range_m, head.range_m);
            assert!((sc.sonar.step.to_degrees() - head.step_deg).abs() < 1e-9);
        }
        let d = scenario::Sonar::default();
        assert_eq!(
            (Head::default().range_m, round3(Head::default().step_deg)),
            (d.range_m, 3.6),
            "the bench flies the schema's default: a 360° sweep in {:.1} s",
            360.0 / 3.6 * (2.0 * d.range_m / 1500.0 + 0.005)
        );
    }

    #[test]
    fn a_world_in_a_current_meets_the_same_water_whatever_flies_it() {
        let case = |strategy, trial, current_mps| Case {
            strategy,
            trial,
            current_mps,
            ..Case::new(Family::Channel, 7)
        };
        let water = |c: &Case| {
            let d = feasible_world(c).unwrap();
            scenario::parse(&scenario_text(&d.world, d.attempt, c, 100.0), "t")
                .unwrap()
                .current
                .velocity
        };
        let v = water(&case(Strategy::Vpf, 0, 0.3));
        assert!((v.norm() - 0.3).abs() < 1e-3, "{v:?}");
        assert_eq!(water(&case(Strategy::Navfn, 1, 0.3)), v);
        assert_eq!(water(&case(Strategy::Vpf, 0, 0.0)), P2::default());
        // Another world, other water.
        let other = Case {
            seed: 8,
            ..case(Strategy::Vpf, 0, 0.3)
        };
        assert!(water(&other).sub(v).norm() > 1e-3);
    }

    #[test]
    fn another_trial_flies_the_same_world_through_other_chance() {
        let case = |trial| Case {
            trial,
            ..Case::new(Family::Crossing, 5)
        };
        assert_eq!(
            case(0).sim_seed(),
            5,
            "trial 0: the world's own seed, as before trials"
        );
        let seeds = [case(1).sim_seed(), case(2).sim_seed()];
        assert!(
            seeds.iter().all(|&s| s != 5 && s <= i64::MAX as u64),
            "{seeds:?}"
        );
        assert_ne!(seeds[0], seeds[1]);
        let text = |c: &Case| {
            let d = feasible_world(c).unwrap();
            scenario_text(&d.world, d.attempt, c, 100.0)
        };
        let (t0, t1) = (text(&case(0)), text(&case(1)));
        // All but the seed and the header's trial.
        let but_chance = |t: &str| {
            t.replace(", trial 1.", ".")
                .lines()
                .filter(|l| !l.starts_with("seed = "))
                .collect::<Vec<_>>()
                .join("\n")
        };
        assert_eq!(
            but_chance(&t0),
            but_chance(&t1),
            "the same world, vehicles and movers"
        );
        assert!(t1.contains(", trial 1."), "{t1}");
        let sc = scenario::parse(&t1, "trial 1").unwrap();
        assert_eq!(sc.seed, seeds[0]);
    }

    #[test]
    fn every_family_gives_a_feasible_scenario_the_parser_accepts() {
        for family in FAMILIES.into_iter().chain(MISSION_FAMILIES) {
            for seed in 0..3 {
                let case = Case::new(family, seed);
                let Drawn {
                    world: w,
                    attempt,
                    shortest_m: shortest,
                    ..
                } = feasible_world(&case).unwrap_or_else(|e| panic!("{}: {e}", case.id()));
                let straight = w
                    .crafts
                    .iter()
                    .map(|c| c.goal.sub(c.start).norm())
                    .fold(0.0, f64::max);
                assert!(
                    shortest >= straight - 1.0,
                    "{}: {shortest} < {straight}",
                    case.id()
                );
                let text = scenario_text(&w, attempt, &case, duration_s(shortest));
                let sc = scenario::parse(&text, &case.id())
                    .unwrap_or_else(|e| panic!("{}: {e}\n{text}", case.id()));
                assert_eq!(sc.vehicles.len(), w.crafts.len());
                assert_eq!(sc.obstacles.len(), w.obstacles.len());
            }
        }
    }

    /// The flat-fish is timed against the way it can fly from its start pose: a short L-trap
    /// mission that starts pointing into the trap takes it longer than the grid's path (seed 7:
    /// 62 m, 81 m at cruise with its turns); the VideoRay, which turns on the spot, is timed
    /// against the grid's path.
    #[test]
    fn a_turning_craft_is_timed_against_the_way_it_can_turn() {
        let case = |model| Case {
            model,
            ..Case::new(Family::LTrap, 7)
        };
        let f = feasible_world(&case(ModelKind::FlatFish)).unwrap();
        assert!(
            f.reference_s > f.shortest_m / CRUISE_MPS + 10.0,
            "{} s for {} m",
            f.reference_s,
            f.shortest_m
        );
        let v = feasible_world(&case(ModelKind::VideoRay)).unwrap();
        assert_eq!(v.reference_s, v.shortest_m / CRUISE_MPS);
    }

    /// A survey world: 4–8 lines, every waypoint clear of the rocks, every leg flyable (the
    /// reference is the legs' sum, longer than the waypoints' polyline), and the scenario file
    /// gives the firmware the same lawnmower (to the millimetre).
    #[test]
    fn survey_worlds_are_lawnmowers_over_rocks_flyable_leg_by_leg() {
        for seed in 0..6 {
            let case = Case::new(Family::Survey, seed);
            let Drawn {
                world: w,
                attempt,
                shortest_m: shortest,
                ..
            } = feasible_world(&case).unwrap();
            let s = w.survey.unwrap();
            let lines = s.lines().unwrap();
            assert!((4..=8).contains(&lines), "{lines}");
            let legs = w.legs(&w.crafts[0]);
            assert_eq!(legs.len(), 2 * lines);
            assert!(w.obstacles.len() >= 3, "{}", w.obstacles.len());
            for p in &legs {
                let near = w
                    .obstacles
                    .iter()
                    .map(|o| o.signed_distance(0.0, *p))
                    .fold(f64::INFINITY, f64::min);
                assert!(near >= 4.9, "seed {seed}: a waypoint {near} m from a rock");
            }
            let mut polyline = 0.0;
            let mut from = w.crafts[0].start;
            for p in &legs {
                polyline += p.sub(from).norm();
                from = *p;
            }
            assert!(shortest >= polyline - 1.0, "{shortest} < {polyline}");
            let text = scenario_text(&w, attempt, &case, duration_s(shortest));
            let sc = scenario::parse(&text, &case.id()).unwrap_or_else(|e| panic!("{e}\n{text}"));
            let m = sc.vehicles[0].mission.as_ref().unwrap();
            assert!(m.survey.is_some());
            for (a, b) in m.positions().iter().zip(&legs) {
                assert!(a.sub(*b).norm() < 1e-3, "{a:?} vs {b:?}");
            }
        }
    }
}
