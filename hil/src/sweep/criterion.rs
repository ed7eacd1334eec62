//! The criterion: which parameter set is best.
//!
//! Seed 002 §2 asks for a criterion "based on actual considerations in operating AUVs in
//! constrained waterspaces". Such considerations are not commensurable — a collision is not
//! paid for by arriving sooner — so the criterion is **lexicographic**: a set is compared with
//! another on the first of these keys that differs, in this order:
//!
//! 1. **Collisions (hard constraint).** The number of runs with a collision, fewest first. Any
//!    collision-free set outranks every set that hit something once, however well that set
//!    did otherwise: a vehicle lost to a rock ends the mission and may end the vehicle.
//! 2. **Success rate**, highest first: the share of runs that reached the goal (the harness's
//!    rule: within the arrival radius, and still within twice it at the end) without a
//!    collision. A planner that stalls in a U-trap or never threads a passage fails the
//!    mission, even safely; this ranks above comfort.
//! 3. **Clearance below the margin**, fewest first: the share of runs whose minimum clearance
//!    came under the craft's margin (`[craft] margin_m` of the spec: hull size plus what
//!    navigation error and the autopilot's overshoot eat into). A pass closer than that is a
//!    near miss in real water, where the obstacle map and the navigation are worse than in the
//!    simulation.
//! 4. **Cost** J, lowest first: among sets equal so far, the cheaper and calmer. Over the set's
//!    successful runs, J is the mean of
//!    `w_t · T / T_best + w_e · E / E_best + w_o · reversals per 100 m`, where T and E are the
//!    run's time to the goal and energy proxy and T_best, E_best the best any set achieved on
//!    the same scenario (so a long scenario does not outweigh a short one, and 1.0 means "as
//!    good as the best"). The weights are the spec's `[criterion]` (defaults 1, 1, 0.05:
//!    time and energy count alike, and 10 heading reversals per 100 m cost as much as taking
//!    50 % longer). Oscillation is in because a planner that hunts left and right wears the
//!    thrusters and blurs the sonar picture, which the energy proxy only partly sees.
//! 5. The set's index, so that the order is total and reproducible.
//!
//! For the influence of a parameter and the heat maps a scalar is needed: the **score**
//! `1 − (rank − 1) / (n − 1)`, 1 for the best set and 0 for the worst, which follows the
//! lexicographic order exactly.

use std::cmp::Ordering;
use std::collections::HashMap;

use super::measure::RunRow;
use super::spec::Weights;

/// A parameter set's aggregate over its runs.
#[derive(Clone, Debug, PartialEq)]
pub struct SetStats {
    /// The set's index.
    pub set: usize,
    /// Runs recorded.
    pub runs: usize,
    /// Runs that succeeded.
    pub successes: usize,
    /// Runs with a collision.
    pub collided: usize,
    /// Runs whose minimum clearance was under the margin (collisions included).
    pub close: usize,
    /// Runs that could not be run (counted as failures).
    pub errors: usize,
    /// Mean of the runs' minimum clearances, m.
    pub mean_clearance_m: f64,
    /// Worst (lowest) minimum clearance, m.
    pub worst_clearance_m: f64,
    /// Mean path-length ratio over the successful runs.
    pub path_ratio: f64,
    /// Mean time to the goal over the successful runs, s.
    pub time_s: f64,
    /// Mean energy proxy over the successful runs.
    pub energy: f64,
    /// Mean heading reversals per 100 m over the successful runs.
    pub oscillation: f64,
    /// The cost J (infinite without a success).
    pub cost: f64,
    /// 1-based rank.
    pub rank: usize,
    /// `1 − (rank − 1) / (n − 1)`.
    pub score: f64,
}

impl SetStats {
    /// Successes over runs.
    pub fn success_rate(&self) -> f64 {
        if self.runs == 0 {
            0.0
        } else {
            self.successes as f64 / self.runs as f64
        }
    }

    /// Close passes over runs.
    pub fn close_rate(&self) -> f64 {
        if self.runs == 0 {
            1.0
        } else {
            self.close as f64 / self.runs as f64
        }
    }
}

fn mean(xs: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for x in xs.filter(|x| x.is_finite()) {
        s += x;
        n += 1;
    }
    if n == 0 {
        f64::NAN
    } else {
        s / n as f64
    }
}

/// The comparison of the criterion (see the module notes): `Less` means `a` is better.
pub fn compare(a: &SetStats, b: &SetStats) -> Ordering {
    a.collided
        .cmp(&b.collided)
        // Rates compared as exact fractions: a·d vs c·b.
        .then_with(|| (b.successes * a.runs.max(1)).cmp(&(a.successes * b.runs.max(1))))
        .then_with(|| (a.close * b.runs.max(1)).cmp(&(b.close * a.runs.max(1))))
        .then_with(|| a.cost.total_cmp(&b.cost))
        .then_with(|| a.set.cmp(&b.set))
}

/// Aggregates `rows` per parameter set (`n_sets` of them) and ranks the sets, best first.
pub fn rank(rows: &[RunRow], n_sets: usize, margin_m: f64, w: &Weights) -> Vec<SetStats> {
    // The best time and energy any set achieved on each scenario.
    let mut best: HashMap<&str, (f64, f64)> = HashMap::new();
    for r in rows.iter().filter(|r| r.success) {
        let e = best
            .entry(r.scenario.as_str())
            .or_insert((f64::INFINITY, f64::INFINITY));
        e.0 = e.0.min(r.time_s);
        e.1 = e.1.min(r.energy);
    }
    let mut by_set: Vec<Vec<&RunRow>> = vec![Vec::new(); n_sets];
    for r in rows {
        if let Some(v) = by_set.get_mut(r.set) {
            v.push(r);
        }
    }
    let ratio = |x: f64, b: f64| if b > 0.0 { x / b } else { 1.0 };
    let mut stats: Vec<SetStats> = by_set
        .iter()
        .enumerate()
        .map(|(set, rs)| {
            let ok: Vec<&&RunRow> = rs.iter().filter(|r| r.success).collect();
            let cost = if ok.is_empty() {
                f64::INFINITY
            } else {
                mean(ok.iter().map(|r| {
                    let (bt, be) = best[r.scenario.as_str()];
                    w.time * ratio(r.time_s, bt)
                        + w.energy * ratio(r.energy, be)
                        + w.oscillation * r.oscillation
                }))
            };
            SetStats {
                set,
                runs: rs.len(),
                successes: ok.len(),
                collided: rs.iter().filter(|r| r.collided).count(),
                close: rs
                    .iter()
                    .filter(|r| {
                        r.collided || r.min_clearance_m.is_nan() || r.min_clearance_m < margin_m
                    })
                    .count(),
                errors: rs.iter().filter(|r| !r.error.is_empty()).count(),
                mean_clearance_m: mean(rs.iter().map(|r| r.min_clearance_m)),
                worst_clearance_m: rs
                    .iter()
                    .map(|r| r.min_clearance_m)
                    .filter(|x| x.is_finite())
                    .fold(f64::NAN, f64::min),
                path_ratio: mean(ok.iter().map(|r| r.path_ratio)),
                time_s: mean(ok.iter().map(|r| r.time_s)),
                energy: mean(ok.iter().map(|r| r.energy)),
                oscillation: mean(ok.iter().map(|r| r.oscillation)),
                cost,
                rank: 0,
                score: 0.0,
            }
        })
        .collect();
    stats.sort_by(compare);
    let n = stats.len();
    for (i, s) in stats.iter_mut().enumerate() {
        s.rank = i + 1;
        s.score = if n > 1 {
            1.0 - i as f64 / (n - 1) as f64
        } else {
            1.0
        };
    }
    stats
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(
        set: usize,
        scenario: &str,
        success: bool,
        collided: bool,
        clear: f64,
        t: f64,
    ) -> RunRow {
        RunRow {
            run: 0,
            set,
            scenario: scenario.into(),
            success,
            collided,
            min_clearance_m: clear,
            path_ratio: 1.1,
            time_s: t,
            energy: t * 2.0,
            oscillation: 1.0,
            ghosts: 0,
            sim_time_s: t,
            error: String::new(),
        }
    }

    #[test]
    fn a_collision_ranks_below_any_collision_free_set() {
        let rows = vec![
            // Set 0: succeeds everywhere, fast, but hits once.
            row(0, "a", true, false, 2.0, 10.0),
            row(0, "b", false, true, -0.1, 10.0),
            // Set 1: never collides, never arrives.
            row(1, "a", false, false, 3.0, 100.0),
            row(1, "b", false, false, 3.0, 100.0),
            // Set 2: collision-free, one success.
            row(2, "a", true, false, 0.2, 30.0),
            row(2, "b", false, false, 1.0, 100.0),
        ];
        let r = rank(&rows, 3, 0.5, &Weights::default());
        let order: Vec<usize> = r.iter().map(|s| s.set).collect();
        assert_eq!(order, [2, 1, 0]);
        assert_eq!(r[2].collided, 1);
        assert_eq!((r[0].rank, r[0].score), (1, 1.0));
        assert_eq!(r[2].score, 0.0);
    }

    #[test]
    fn margin_then_cost_break_ties() {
        let rows = vec![
            row(0, "a", true, false, 0.3, 10.0), // under the 0.5 m margin
            row(1, "a", true, false, 0.9, 20.0),
            row(2, "a", true, false, 0.8, 15.0),
        ];
        let r = rank(&rows, 3, 0.5, &Weights::default());
        let order: Vec<usize> = r.iter().map(|s| s.set).collect();
        assert_eq!(order, [2, 1, 0]);
        // Set 2: T/T_best = 1.5, E/E_best = 1.5, 0.05 × 1 reversal per 100 m.
        assert!((r[0].cost - 3.05).abs() < 1e-12, "{}", r[0].cost);
    }
}
