//! The current: the water's drift over ground, estimated from navigation and taken out of the
//! set-points, so that the vehicle makes good over ground what the planner and the guard ask.
//!
//! **Why.** The planner's velocity (seed 000 eq. 6–7) and the guard's checks are over ground —
//! navigation reports position and velocity over ground — but the autopilot holds heading and
//! speed through the water. In a current c the vehicle makes good v + c: a guard's stop drifts
//! at |c|, and a course along a wall sets onto it. In a steady 0.2 m/s current, its direction
//! drawn per world (`hil bench --seeds 200 --current 0.2`, VPF, the VideoRay's own sonar), the
//! VideoRay touched something in 82 of 2 400 worlds (none in still water), 46 of them bent
//! channels: the guard had stopped it a metre off a wall and the water carried it on. None of
//! the seeds has a current; this departs from them only where there is one.
//!
//! **Estimate.** The water's velocity is what navigation reports over ground less the
//! vehicle's own way through the water, which is along its heading ψ (no sideslip in steady
//! flight) at the speed the autopilot was given: r = v_g − v_set·ê(ψ) − ĉ. Across the heading
//! the residual needs no speed at all; along it, only once the speed asked for has held still
//! for [`SETTLE_S`] (the autopilot has caught up). Both are skipped while the heading turns
//! faster than [`MAX_TURN_RPS`] (a turning hull skids); a slow-turning craft's, until it has
//! gone straight for as long as it takes to brake from v_max ([`straight`]). Each period ĉ
//! moves by T/τ of the
//! residual (τ = [`DriftConfig::tau_s`]). Seed 000's kinematic vehicle goes exactly where it
//! points at the speed it is given, so in still water its residual is zero and nothing
//! changes.
//!
//! **Compensation.** The command's velocity over ground is v_d = v_set·ê(ψ_set); through the
//! water that is w = v_d − ĉ, so ψ_set = ∠w and v_set = min(|w|, v_max) (the guard's stop
//! becomes station-keeping, head to the current, and so do the fail-safe holds that
//! [keep station](crate::planner::HoldReason::keeps_station): an obstacle too close, the sonar
//! blind; the others stay zero speed and are not handed here: `Periodic::make_good`). Below
//! [`DEADBAND_MPS`] nothing is changed, and a slow-turning craft is only told the current
//! (telemetry), never steered by it: it cannot stop where it is in a current, and made good
//! against it, its guard's stops became slow turns on the spot that drifted on all the same
//! (README, "In a current"). The
//! command's velocity v̄_c stays the planner's (over ground): the planner integrates on from
//! it, and the MAVLink bridge sends it to an autopilot that holds velocity over ground itself.
//!
//! **Capacity.** One vector and five scalars; no tables.

use crate::math::{atan2, max, min, Vec2};
use crate::params::Params;
use crate::types::{Command, NavState};

/// Tuning of the current's estimate. [`Default`] suits a VideoRay-class craft.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DriftConfig {
    /// Time constant of the estimate, s (0: no estimate and no compensation — the seeds'
    /// behaviour; for an autopilot that already holds a course over ground).
    pub tau_s: f32,
}

impl Default for DriftConfig {
    fn default() -> Self {
        DriftConfig { tau_s: 5.0 }
    }
}

/// Smallest current compensated, m/s: a VideoRay in still water believes up to 0.04 m/s
/// ([`HELD_MPS`]).
pub const DEADBAND_MPS: f32 = 0.05;

/// How far the speed asked for may wander and still count as held, m/s; and how long it must
/// hold before the residual along the heading is used, s (the autopilot has caught up). No
/// estimate while the heading turns faster than [`MAX_TURN_RPS`], rad/s (a turning hull
/// skids). With 0.05 m/s, 1.5 s and 0.3 rad/s a VideoRay in still water believed up to
/// 0.08 m/s (bench worlds, seeds 1 and 3); with these, at most 0.04 but in formations (0.07).
pub const HELD_MPS: f32 = 0.03;
/// See [`HELD_MPS`].
pub const SETTLE_S: f32 = 2.0;
/// See [`HELD_MPS`].
pub const MAX_TURN_RPS: f32 = 0.1;

/// Whether a turn of `turn` rad over `dt` s is straight enough to estimate from: under
/// [`MAX_TURN_RPS`], or for a slow-turning craft (`Params::turn_rate_rps` > 0) under
/// [`SLOW_STRAIGHT`] of its top rate — and for that craft only once it has been so for
/// [`settle_s`] ([`Drift::update`]): its hull skids through all of its turns and for a while
/// after. With the VideoRay's gate the flat-fish believed up to 0.09 m/s in still water
/// (`hil bench --models flatfish --params hil/recipes/flatfish.toml --seeds 170`).
fn straight(craft: &Params, turn: f32, dt: f32) -> bool {
    let rate = if craft.turns_slowly() {
        SLOW_STRAIGHT * craft.turn_rate_rps
    } else {
        MAX_TURN_RPS
    };
    turn <= rate * dt
}

/// A slow-turning craft counts as straight below this fraction of its top turn rate.
const SLOW_STRAIGHT: f32 = 0.25;

/// How long a craft must have gone straight, and been asked for the same speed, before its
/// residual is used, s: [`SETTLE_S`], or for a slow-turning craft, whose skid outlasts its turns
/// and whose speed follows its set-point slowly, the time it takes to brake from v_max if longer.
fn settle_s(craft: &Params) -> f32 {
    if craft.turns_slowly() {
        max(SETTLE_S, craft.v_max / craft.brake())
    } else {
        SETTLE_S
    }
}

/// A residual larger than this is not water but a fault (a position jump, a hull held against a
/// wall), m/s.
const MAX_RESIDUAL_MPS: f32 = 3.0;

/// The current's estimate and what it needs from the last period.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Drift {
    /// ĉ, m/s over ground.
    estimate: Vec2,
    /// The speed set-point sent last period, m/s, and the heading then; `None` before the
    /// first.
    sent: Option<(f32, f32)>,
    /// The speed asked for has held within [`HELD_MPS`] of this, m/s, for this long, s.
    held: (f32, f32),
    /// The heading has been straight ([`straight`]) for this long, s.
    straight_s: f32,
}

impl Drift {
    /// ĉ, m/s over ground.
    pub fn estimate(&self) -> Vec2 {
        self.estimate
    }

    /// Takes this period's navigation in (`dt` s after the last): the residual of the way the
    /// last command should have made good, for `craft` ([`straight`]).
    pub fn update(&mut self, cfg: &DriftConfig, nav: &NavState, craft: &Params, dt: f32) {
        let Some((v_set, psi0)) = self.sent else {
            return;
        };
        // Unwrapped: across ±π it reads as a fast turn, and that one period is skipped.
        let turn = (nav.heading - psi0).abs();
        self.straight_s = if straight(craft, turn, dt) {
            self.straight_s + dt
        } else {
            0.0
        };
        let settle = settle_s(craft);
        let steady = if craft.turns_slowly() {
            self.straight_s >= settle
        } else {
            self.straight_s > 0.0
        };
        if !(cfg.tau_s > 0.0 && steady) {
            return;
        }
        let e = Vec2::from_angle(nav.heading);
        let r = nav.velocity - e * v_set - self.estimate;
        // Also false for NaN: nothing but finite navigation moves the estimate.
        let plausible = r.norm2() < MAX_RESIDUAL_MPS * MAX_RESIDUAL_MPS;
        if !plausible {
            return;
        }
        // Across the heading always; along it once the speed has held.
        let along = if self.held.1 >= settle { 1.0 } else { 0.0 };
        let step = r - e * ((1.0 - along) * r.dot(e));
        // Not bounded: no residual passes above 3 m/s, and a current beyond v_max is met at
        // v_max all the same (`compensate`).
        self.estimate += step * min(1.0, dt / cfg.tau_s);
    }

    /// The set-points that make good `cmd`'s velocity over ground in the current believed
    /// (`cmd` as it is below the deadband), with the vehicle now heading `heading`; `dt` s
    /// after the last. Records what was sent for the next update.
    pub fn compensate(
        &mut self,
        cfg: &DriftConfig,
        mut cmd: Command,
        craft: &Params,
        heading: f32,
        dt: f32,
    ) -> Command {
        // Held is judged on the speed asked for, before the current is taken out: the estimate
        // moves the set-point only slowly (T/τ a period), which the autopilot follows at once,
        // and judged after, a vehicle holding station head to a 0.35 m/s current never held
        // still long enough to learn the current along its heading (bench channel 8: it drifted
        // 0.7 m onto the wall while its set-point climbed 0.17 → 0.28 m/s in 10 s).
        self.held = if (cmd.v_set - self.held.0).abs() > HELD_MPS {
            (cmd.v_set, 0.0)
        } else {
            (self.held.0, self.held.1 + dt)
        };
        let c = self.estimate;
        // A slow-turning craft is only told what the current is: it cannot hold station on the
        // spot, and making good its planner's velocity made it no safer (README, "In a current").
        let acts = !craft.turns_slowly();
        if cfg.tau_s > 0.0 && acts && c.norm2() >= DEADBAND_MPS * DEADBAND_MPS {
            let w = Vec2::from_angle(cmd.psi_set) * cmd.v_set - c;
            let speed = min(w.norm(), craft.v_max);
            if speed > 1e-3 {
                cmd.psi_set = atan2(w.y, w.x);
            }
            cmd.v_set = speed;
            cmd.setpoints.phi_c = cmd.psi_set;
            cmd.setpoints.v_c = speed;
        }
        self.sent = Some((cmd.v_set, heading));
        cmd
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::{HoldReason, Mode};

    /// The guard's stop, heading `psi` (a hold that keeps station is flown the same).
    fn stopped(psi: f32) -> Command {
        Command {
            mode: Mode::Guarded,
            ..Command::hold(HoldReason::NoMission, psi)
        }
    }

    fn nav(heading: f32, velocity: Vec2) -> NavState {
        NavState {
            position: Vec2::ZERO,
            heading,
            velocity,
        }
    }

    /// Flies `periods` of 100 ms: the vehicle points where it was told and goes at the speed it
    /// was told through water that moves at `current`; returns the last command sent.
    fn fly(
        d: &mut Drift,
        cfg: &DriftConfig,
        current: Vec2,
        want: Command,
        periods: u64,
    ) -> Command {
        let mut sent = stopped(0.0);
        for _ in 0..periods {
            let through = Vec2::from_angle(sent.psi_set) * sent.v_set;
            d.update(
                cfg,
                &nav(sent.psi_set, through + current),
                &Params::default(),
                0.1,
            );
            sent = d.compensate(cfg, want, &Params::default(), sent.psi_set, 0.1);
        }
        sent
    }

    #[test]
    fn a_stop_in_a_current_heads_into_it_at_its_speed() {
        let cfg = DriftConfig::default();
        let mut d = Drift::default();
        let current = Vec2::new(0.0, -0.2);
        let stop = stopped(0.0);
        let sent = fly(&mut d, &cfg, current, stop, 300);
        assert!((d.estimate() - current).norm() < 0.01, "{:?}", d.estimate());
        assert!(
            (sent.psi_set - core::f32::consts::FRAC_PI_2).abs() < 0.05,
            "{sent:?}"
        );
        assert!((sent.v_set - 0.2).abs() < 0.01, "{sent:?}");
    }

    #[test]
    fn a_cross_current_is_met_with_a_crab_angle_that_makes_good_the_course() {
        let cfg = DriftConfig::default();
        let mut d = Drift::default();
        let current = Vec2::new(0.0, 0.3);
        let mut east = stopped(0.0);
        east.v_set = 0.8;
        let sent = fly(&mut d, &cfg, current, east, 600);
        let made_good = Vec2::from_angle(sent.psi_set) * sent.v_set + current;
        assert!(
            (made_good - Vec2::new(0.8, 0.0)).norm() < 0.02,
            "{made_good:?}"
        );
    }

    #[test]
    fn in_still_water_nothing_changes() {
        let cfg = DriftConfig::default();
        let mut d = Drift::default();
        let mut cmd = stopped(1.0);
        cmd.v_set = 0.7;
        let sent = fly(&mut d, &cfg, Vec2::ZERO, cmd, 100);
        assert_eq!(d.estimate(), Vec2::ZERO);
        assert_eq!(sent, cmd);
    }

    #[test]
    fn a_slow_turning_craft_learns_the_current_once_straight_and_is_only_told_it() {
        let cfg = DriftConfig::default();
        let craft = Params {
            turn_rate_rps: 0.046,
            brake_mps2: 0.1,
            v_max: 0.65,
            ..Params::default()
        };
        let mut cruise = stopped(0.0);
        cruise.v_set = 0.5;
        let current = Vec2::new(0.0, 0.2);
        // Swinging at half its top rate, it skids: it learns nothing.
        let mut d = Drift::default();
        for k in 0..300 {
            let heading = 0.023 * 0.1 * k as f32;
            let through = Vec2::from_angle(heading) * 0.5;
            d.update(&cfg, &nav(heading, through + current), &craft, 0.1);
            assert_eq!(d.compensate(&cfg, cruise, &craft, heading, 0.1), cruise);
        }
        assert_eq!(d.estimate(), Vec2::ZERO);
        // Straight, it learns the current once v_max / brake = 6.5 s have passed, and its
        // set-points are left as they were asked.
        let mut d = Drift::default();
        let through = Vec2::new(0.5, 0.0);
        for k in 0..400 {
            d.update(&cfg, &nav(0.0, through + current), &craft, 0.1);
            assert_eq!(d.compensate(&cfg, cruise, &craft, 0.0, 0.1), cruise);
            if k == 60 {
                assert_eq!(d.estimate(), Vec2::ZERO, "before it has settled");
            }
        }
        assert!((d.estimate() - current).norm() < 0.01, "{:?}", d.estimate());
    }

    #[test]
    fn switched_off_it_estimates_nothing() {
        let cfg = DriftConfig { tau_s: 0.0 };
        let mut d = Drift::default();
        let stop = stopped(0.0);
        let sent = fly(&mut d, &cfg, Vec2::new(0.3, 0.0), stop, 100);
        assert_eq!(d.estimate(), Vec2::ZERO);
        assert_eq!(sent, stop);
    }
}
