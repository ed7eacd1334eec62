//! Escape from local minima with ghost goal-points, seed 000 §III eq. 16–17.
//!
//! **Detection** (the paper leaves the test open): the vehicle is in a local minimum when its
//! planned speed has stayed below `stall_speed` for `stall_time_s` while it is farther than
//! `arrival_radius_m` from the active goal-point. With friction the planner settles in a minimum,
//! so a settled vehicle away from its goal is exactly the symptom of Fig. 4. A vehicle that is
//! merely creeping up the Gaussian's shallow tail towards its goal is no such case: if it came
//! closer by more than a tenth of `stall_speed × stall_time_s` during the window, the window
//! starts again. When a stall is confirmed the caller says what holds the vehicle
//! ([`StallCause`]):
//! - the *static* field (obstacles and the goal-point alone): a ghost goal-point is placed;
//! - the formation's virtual leader (the field without it has a way down) away from the goal:
//!   the formation is released for `ghost_timeout_s` — the "partial formation break-up for
//!   obstacle circumnavigation" of 001 §1 — and re-forms afterwards (near the goal, being held
//!   by the formation is arrival in formation, and counts as held by other vehicles);
//! - other vehicles (four sharing one goal, Fig. 7): the vehicle waits. Their minima move with
//!   them, and perturbing out of them is the endless jitter 001 §1 describes.
//!
//! **Placement** (eq. 16–17), from the vehicle at p towards the active goal-point g:
//! ṽ = (g − p)/d, d = ‖g − p‖, and
//! r_GGP = p + λ·d·ṽ + α·d·R(π(1 + 2ρ)/2)·ṽ,
//! i.e. a fraction λ along the line to the goal and α·d to its left (ρ = 0) or right (ρ = 1).
//! The paper's eq. 16 lists the components of ṽ as (Δy, Δx), an extraction slip we read as
//! (Δx, Δy); its r_GGP is relative to the vehicle (as its Fig. 5 draws it). ρ comes from a seeded
//! generator, so runs repeat.
//!
//! **Stack.** A ghost replaces the goal-point while it is active. Stuck again on the way to a
//! ghost, the planner stacks another one computed towards that ghost. A ghost is removed when
//! the vehicle comes within ε_ghost, or after `ghost_timeout_s` ("for a given period of time").
//! The stack holds `max_ghosts` ≤ [`MAX_GHOSTS`] (0: ghosts off); when it is full a new ghost
//! replaces the top one (the one that just failed), counted in `replaced_full`.

use heapless::Vec;

use crate::math::{Vec2, XorShift32};
use crate::params::Params;

pub use crate::params::MAX_GHOSTS;

/// What holds a stalled vehicle in place (see the module notes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StallCause {
    /// A minimum of the static field: obstacles and the goal-point.
    Static,
    /// The formation's virtual leader.
    Formation,
    /// Other vehicles' repulsion.
    Vehicles,
}

/// A ghost goal-point and when it was placed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GhostGoal {
    /// Position, m.
    pub position: Vec2,
    /// When it was placed, ms.
    pub placed_ms: u64,
}

/// Ghost goal-point bookkeeping, for telemetry and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EscapeCounters {
    /// Ghosts placed.
    pub placed: u32,
    /// Ghosts removed because the vehicle reached them.
    pub reached: u32,
    /// Ghosts given up after the timeout.
    pub timed_out: u32,
    /// Ghosts that replaced the top of a full stack.
    pub replaced_full: u32,
    /// Times the formation was released to get out of a stall.
    pub formation_released: u32,
}

/// The local-minimum detector and the ghost stack.
#[derive(Clone, Debug)]
pub struct Escape {
    stack: Vec<GhostGoal, MAX_GHOSTS>,
    /// When the current stall began, and the distance to the target then.
    stall_since: Option<(u64, f32)>,
    formation_released_until_ms: Option<u64>,
    rng: XorShift32,
    /// Counters.
    pub counters: EscapeCounters,
}

impl Escape {
    /// An empty stack with the generator seeded from `seed`.
    pub fn new(seed: u32) -> Self {
        Escape {
            stack: Vec::new(),
            stall_since: None,
            formation_released_until_ms: None,
            rng: XorShift32::new(seed),
            counters: EscapeCounters::default(),
        }
    }

    /// The ghosts, bottom first.
    pub fn ghosts(&self) -> &[GhostGoal] {
        &self.stack
    }

    /// The goal-point the field attracts to now: the top ghost, else the mission's goal.
    pub fn active_target(&self, goal: Vec2) -> Vec2 {
        self.stack.last().map_or(goal, |g| g.position)
    }

    /// Whether the formation is released (ignored) at `now_ms`.
    pub fn formation_released(&self, now_ms: u64) -> bool {
        self.formation_released_until_ms
            .is_some_and(|until| now_ms < until)
    }

    /// Forgets all ghosts, the stall timer and a formation release (new mission, hold).
    pub fn reset(&mut self) {
        self.stack.clear();
        self.stall_since = None;
        self.formation_released_until_ms = None;
    }

    /// One period of the detector: removes reached or expired ghosts; when the vehicle at `p`,
    /// with planned speed `speed`, has been stalled long enough, asks `cause` what holds it
    /// (towards the active target) and places a ghost, releases the formation, or waits.
    pub fn update(
        &mut self,
        now_ms: u64,
        p: Vec2,
        speed: f32,
        goal: Vec2,
        params: &Params,
        cause: impl FnOnce(Vec2) -> StallCause,
    ) {
        let timeout_ms = (params.ghost_timeout_s * 1000.0) as u64;
        while let Some(top) = self.stack.last().copied() {
            if (top.position - p).norm() <= params.ghost_eps_m {
                self.counters.reached = self.counters.reached.saturating_add(1);
            } else if now_ms.saturating_sub(top.placed_ms) >= timeout_ms {
                self.counters.timed_out = self.counters.timed_out.saturating_add(1);
            } else {
                break;
            }
            self.stack.pop();
            self.stall_since = None;
        }

        let target = self.active_target(goal);
        let dist = (target - p).norm();
        let far = dist > params.arrival_radius_m;
        if params.max_ghosts == 0 || !(far && speed < params.stall_speed) {
            self.stall_since = None;
            return;
        }
        let (since, start_dist) = *self.stall_since.get_or_insert((now_ms, dist));
        if now_ms.saturating_sub(since) < (params.stall_time_s * 1000.0) as u64 {
            return;
        }
        if start_dist - dist > 0.1 * params.stall_speed * params.stall_time_s {
            // Creeping towards the target, not trapped: watch another window.
            self.stall_since = Some((now_ms, dist));
            return;
        }
        match cause(target) {
            StallCause::Static => {}
            StallCause::Formation => {
                self.formation_released_until_ms = Some(now_ms.saturating_add(timeout_ms));
                self.counters.formation_released =
                    self.counters.formation_released.saturating_add(1);
                self.stall_since = None;
                return;
            }
            StallCause::Vehicles => {
                self.stall_since = None;
                return;
            }
        }
        let ghost = GhostGoal {
            position: self.place(p, target, params),
            placed_ms: now_ms,
        };
        self.counters.placed = self.counters.placed.saturating_add(1);
        if self.stack.len() >= params.max_ghosts as usize {
            if let Some(top) = self.stack.last_mut() {
                *top = ghost;
            }
            self.counters.replaced_full = self.counters.replaced_full.saturating_add(1);
        } else if self.stack.push(ghost).is_err() {
            // Unreachable while max_ghosts <= MAX_GHOSTS (validated); counted if it ever is.
            self.counters.replaced_full = self.counters.replaced_full.saturating_add(1);
        }
        self.stall_since = None;
    }

    /// 000 eq. 16–17, with ρ drawn from the seeded generator.
    fn place(&mut self, p: Vec2, target: Vec2, params: &Params) -> Vec2 {
        let rho = self.rng.next_bool();
        ghost_point(p, target, params.ghost_lambda, params.ghost_alpha, rho)
    }
}

/// The ghost goal-point of 000 eq. 16–17 for the vehicle at `p` and the active goal-point
/// `target`: r_GGP = p + λ·d·ṽ + α·d·R(π(1 + 2ρ)/2)·ṽ, ρ = `rho` (false: 0, true: 1).
/// R(π/2)·ṽ is ṽ turned counter-clockwise (to the left of the line to the goal), R(3π/2)·ṽ
/// clockwise (to the right).
pub fn ghost_point(p: Vec2, target: Vec2, lambda: f32, alpha: f32, rho: bool) -> Vec2 {
    let to = target - p;
    let d = to.norm();
    let v = to.normalized(1e-6).unwrap_or(Vec2::new(1.0, 0.0));
    let side = if rho { -v.perp() } else { v.perp() };
    p + v * (lambda * d) + side * (alpha * d)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> Params {
        Params {
            stall_time_s: 2.0,
            ghost_timeout_s: 30.0,
            ..Params::default()
        }
    }

    #[test]
    fn eq_17_puts_the_ghost_lambda_along_and_alpha_across_on_the_side_rho_picks() {
        // λ ≠ α, the vehicle away from the origin, the goal up and to the right of it:
        // d = 10, ṽ = (0.6, 0.8), left of ṽ (ρ = 0) is (−0.8, 0.6), right (ρ = 1) (0.8, −0.6).
        let p = Vec2::new(3.0, -2.0);
        let goal = Vec2::new(9.0, 6.0);
        let (lambda, alpha) = (0.3, 0.7);
        let left = ghost_point(p, goal, lambda, alpha, false);
        let right = ghost_point(p, goal, lambda, alpha, true);
        // p + 3·ṽ + 7·(left or right of ṽ).
        let want_left = Vec2::new(3.0 + 1.8 - 5.6, -2.0 + 2.4 + 4.2);
        let want_right = Vec2::new(3.0 + 1.8 + 5.6, -2.0 + 2.4 - 4.2);
        assert!((left - want_left).norm() < 1e-4, "ρ = 0: {left:?}");
        assert!((right - want_right).norm() < 1e-4, "ρ = 1: {right:?}");
        // ρ = 0 is counter-clockwise of the line to the goal, ρ = 1 clockwise.
        assert!((goal - p).cross(left - p) > 0.0);
        assert!((goal - p).cross(right - p) < 0.0);
    }

    #[test]
    fn stall_far_from_goal_places_a_ghost_per_eq_17() {
        let p = Params {
            ghost_lambda: 0.25,
            ghost_alpha: 0.75,
            ..params()
        };
        let at = Vec2::new(-4.0, 7.0);
        let goal = Vec2::new(-4.0, 27.0);
        // Ghosts on both sides, each where eq. 17 and that placement's draw of ρ put it.
        let mut sides = [false, false];
        for seed in [1, 7, 0x9e37_79b9, 0x8000_0001, 0xdead_beef, 123_456_789] {
            let mut e = Escape::new(seed);
            let mut rho = XorShift32::new(seed);
            for k in 0..=20u64 {
                e.update(k * 100, at, 0.0, goal, &p, |_| StallCause::Static);
            }
            let g = e.ghosts().first().copied().unwrap();
            let right = rho.next_bool();
            // λ·d = 5 along the line (north), α·d = 15 across it: west is left, east right.
            let want = Vec2::new(if right { 11.0 } else { -19.0 }, 12.0);
            assert!((g.position - want).norm() < 1e-4, "seed {seed}: {g:?}");
            assert_eq!(e.active_target(goal), g.position);
            sides[right as usize] = true;
        }
        assert_eq!(sides, [true, true], "both values of ρ drawn");
    }

    #[test]
    fn no_ghost_when_moving_or_near_the_goal() {
        let p = params();
        let mut e = Escape::new(3);
        for k in 0..100u64 {
            e.update(k * 100, Vec2::ZERO, 0.5, Vec2::new(20.0, 0.0), &p, |_| {
                StallCause::Static
            });
            e.update(k * 100, Vec2::ZERO, 0.0, Vec2::new(0.5, 0.0), &p, |_| {
                StallCause::Static
            });
        }
        assert!(e.ghosts().is_empty());
    }

    #[test]
    fn ghosts_stack_replace_when_full_and_pop_when_reached_or_timed_out() {
        let p = params();
        let mut e = Escape::new(5);
        let goal = Vec2::new(40.0, 0.0);
        let mut t = 0u64;
        while e.counters.placed < (MAX_GHOSTS + 1) as u32 {
            e.update(t, Vec2::ZERO, 0.0, goal, &p, |_| StallCause::Static);
            t += 100;
        }
        assert_eq!(e.ghosts().len(), MAX_GHOSTS);
        assert_eq!(e.counters.replaced_full, 1);
        let top = e.active_target(goal);
        e.update(t, top, 0.5, goal, &p, |_| StallCause::Static);
        assert_eq!(e.ghosts().len(), MAX_GHOSTS - 1);
        assert_eq!(e.counters.reached, 1);
        e.update(t + 31_000, Vec2::new(-100.0, 0.0), 0.5, goal, &p, |_| {
            StallCause::Static
        });
        assert!(e.ghosts().is_empty());
        assert_eq!(e.counters.timed_out, MAX_GHOSTS as u32 - 1);
    }

    #[test]
    fn no_ghost_while_creeping_towards_the_goal() {
        let p = params();
        let mut e = Escape::new(3);
        // 0.03 m/s towards the goal: slow, but 0.6 m closer in 20 s.
        for k in 0..200u64 {
            let x = 0.003 * k as f32;
            e.update(
                k * 100,
                Vec2::new(x, 0.0),
                0.03,
                Vec2::new(20.0, 0.0),
                &p,
                |_| StallCause::Static,
            );
        }
        assert!(e.ghosts().is_empty());
    }

    #[test]
    fn no_ghost_when_other_vehicles_hold_the_vehicle() {
        let p = params();
        let mut e = Escape::new(3);
        for k in 0..100u64 {
            e.update(k * 100, Vec2::ZERO, 0.0, Vec2::new(20.0, 0.0), &p, |_| {
                StallCause::Vehicles
            });
        }
        assert!(e.ghosts().is_empty());
    }

    #[test]
    fn a_formation_stall_releases_the_formation_for_a_while() {
        let p = params();
        let mut e = Escape::new(3);
        for k in 0..=20u64 {
            e.update(k * 100, Vec2::ZERO, 0.0, Vec2::new(20.0, 0.0), &p, |_| {
                StallCause::Formation
            });
        }
        assert!(e.ghosts().is_empty());
        assert!(e.formation_released(2_100));
        assert!(!e.formation_released(2_000 + 30_000));
        assert_eq!(e.counters.formation_released, 1);
    }

    #[test]
    fn same_seed_same_sides() {
        let p = params();
        let run = |seed| {
            let mut e = Escape::new(seed);
            for k in 0..200u64 {
                e.update(k * 100, Vec2::ZERO, 0.0, Vec2::new(20.0, 0.0), &p, |_| {
                    StallCause::Static
                });
            }
            e.ghosts()
                .iter()
                .map(|g| g.position.y > 0.0)
                .fold(0u32, |a, b| a * 2 + b as u32)
        };
        assert_eq!(run(9), run(9));
    }
}
