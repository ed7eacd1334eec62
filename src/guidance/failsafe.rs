//! Fail-safes checked by the periodic task before it plans: each turns the command into a hold
//! with its reason, until the condition clears.
//!
//! - no mission → hold;
//! - navigation more than a period late → dead-reckoned from the last fix and slowed
//!   ([`dead_reckon`]); older than `nav_timeout_ms` (or none yet) → hold, until fresh navigation;
//! - inside an obstacle's surface → all-stop;
//! - a collision that cannot be avoided at the current speed → all-stop. "Cannot be avoided":
//!   braking at F_max (the most the planner ever commands) from speed v needs v²/2F_max metres,
//!   and the nearest surface is closer than that;
//! - frozen navigation ([`FreezeDetector`]) → hold, until a fix that differs;
//! - a sonar that cannot see ([`SonarWatch`]): not yet swept once round → hold; gone quiet →
//!   slow down, and hold once the vehicle has gone as far as the map it has can be trusted,
//!   until scanlines come again.

use crate::math::Vec2;
use crate::planner::{HoldReason, NavState};

/// The fail-safes' settings.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FailsafeConfig {
    /// Navigation older than this holds the vehicle, ms. Until then a late fix is
    /// dead-reckoned and the speed tapers to zero ([`dead_reckon`]). The default, 1000 ms, is
    /// ArduPilot's upper bound (0.5–1 s) for a position estimate without fresh navigation: a
    /// noisy link that loses one frame in three (bit errors at 10⁻³ on a 50-byte frame) almost
    /// never loses ten in a row, and a vehicle at 1 m/s is all but stopped when it holds.
    pub nav_timeout_ms: u64,
    /// A sonar that has delivered scanlines and then none for this long is quiet, ms (a
    /// scanning sonar sends one every 50 ms or so).
    pub sonar_quiet_ms: u64,
    /// How far the vehicle may go on the map it has once the sonar is quiet, m: the range
    /// within which the last sweeps are trusted to have shown everything there is (half the
    /// evidence map's 10 m free range: thin structure seen edge-on is missed further out).
    pub sonar_quiet_travel_m: f32,
}

impl Default for FailsafeConfig {
    fn default() -> Self {
        FailsafeConfig {
            nav_timeout_ms: 1000,
            sonar_quiet_ms: 2000,
            sonar_quiet_travel_m: 5.0,
        }
    }
}

/// A sonar that cannot see (issue "Faults": never drive into what the sonar can no longer
/// see). Two cases:
/// - **not yet swept**: the sonar has spoken but has not yet looked once all round the vehicle
///   since it started — the map holds only part of what is there, so the vehicle waits (one
///   sweep: 9 s for a Micron at 30 m);
/// - **gone quiet**: no scanline for `sonar_quiet_ms`. Obstacles stay where they were (the
///   evidence map forgets by coverage, not age), but what the sonar has not yet seen is not in
///   it: the vehicle may still travel `sonar_quiet_travel_m` from where it went quiet, at a
///   speed from which it can stop within what is left (v ≤ √(2·F_max·left)), and holds when that
///   is spent.
///
/// A third case is a sonar that speaks but loses pings on the way (a noisy link: bit errors
/// at 10⁻³ spoil nine scanline frames in ten): the map then has holes where rocks may hide.
/// Over each turn of the head the share of pings that arrived is measured ([`Self::delivery`]),
/// and below [`DELIVERY_FULL`] the vehicle's speed is bounded by that share of v_max, so that
/// it gets as many looks per metre travelled as with every ping delivered.
///
/// A vehicle whose sonar has never spoken (perception by contacts) is not watched.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SonarWatch {
    /// Scanlines counted by the background, and when the count last changed.
    last: Option<(u32, u64)>,
    /// Where the vehicle was when the sonar went quiet.
    quiet_at: Option<Vec2>,
    /// Swept and head bearing (mrad) at the start of the current turn.
    turn_from: (u32, u32),
    /// Share of pings that arrived over the last full turn, if below [`DELIVERY_FULL`].
    delivery: Option<f32>,
}

/// One full turn, mrad.
const SWEEP_MRAD: u32 = 6283;
/// A share of delivered pings at or above which the sonar counts as seeing everything.
pub const DELIVERY_FULL: f32 = 0.95;

impl SonarWatch {
    /// Share of pings that arrived over the last full turn of the head, when below
    /// [`DELIVERY_FULL`] (`None`: the sonar delivers).
    pub fn delivery(&self) -> Option<f32> {
        self.delivery
    }

    /// Takes the background's scanline count, swept bearing and head travel (mrad) at `now_ms`
    /// with the vehicle at `p`; returns the speed bound while the sonar cannot see (`None`: it
    /// can; `Some(0.0)`: hold).
    pub fn update(
        &mut self,
        cfg: &FailsafeConfig,
        (scanlines, swept_mrad, head_mrad): (u32, u32, u32),
        now_ms: u64,
        p: Vec2,
        f_max: f32,
    ) -> Option<f32> {
        match self.last {
            Some((n, _)) if n == scanlines => {}
            _ => {
                // Scanlines at start-up are not a change: the sonar must speak first.
                self.last = (scanlines > 0).then_some((scanlines, now_ms));
                self.quiet_at = None;
            }
        }
        let (swept0, head0) = self.turn_from;
        let turned = head_mrad.saturating_sub(head0);
        if turned >= SWEEP_MRAD {
            let share = swept_mrad.saturating_sub(swept0) as f32 / turned as f32;
            self.delivery = (share < DELIVERY_FULL).then_some(crate::math::max(0.0, share));
            self.turn_from = (swept_mrad, head_mrad);
        }
        let (_, since) = self.last?;
        if swept_mrad < SWEEP_MRAD {
            return Some(0.0);
        }
        if now_ms.saturating_sub(since) < cfg.sonar_quiet_ms {
            return None;
        }
        let from = *self.quiet_at.get_or_insert(p);
        let left = cfg.sonar_quiet_travel_m - (p - from).norm();
        Some(crate::math::sqrt(2.0 * f_max * crate::math::max(0.0, left)))
    }
}

/// What the fail-safes look at, once per period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Situation {
    /// A mission is set.
    pub has_mission: bool,
    /// Age of the newest navigation, ms; `None` if none has come yet.
    pub nav_age_ms: Option<u64>,
    /// Signed distance to the nearest obstacle surface or vehicle circle, m.
    pub clearance_m: f32,
    /// Speed over ground, m/s.
    pub speed: f32,
    /// F_max, m/s².
    pub f_max: f32,
    /// The vehicle's motion brings it nearer that surface: the clearance a moment on along
    /// its velocity ([`CLOSING_LOOKAHEAD_S`]) is smaller.
    pub closing: bool,
}

/// How far on along its velocity the vehicle is looked at to tell whether it is closing on
/// the nearest surface, s.
pub const CLOSING_LOOKAHEAD_S: f32 = 0.5;

/// Frozen navigation: a source that keeps sending the very same fix (position and heading
/// identical to the last bit) while the vehicle is commanded to move has stopped measuring —
/// a frozen DVL solution, a stuck serial buffer. Real fixes of a moving vehicle always change.
/// After [`FreezeDetector::FROZEN_FIXES`] such fixes in a row the vehicle holds, and stays
/// held until a fix differs (holding, it is no longer commanded to move, so "still the same"
/// must not release it).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FreezeDetector {
    last: Option<(Vec2, f32, u64)>,
    same: u32,
    frozen: bool,
}

impl FreezeDetector {
    /// Identical fixes in a row, while commanded to move, that make a freeze (0.5 s at 10 Hz).
    pub const FROZEN_FIXES: u32 = 5;
    /// Commanded speed above which the vehicle must be seen to move, m/s.
    pub const MOVING_MPS: f32 = 0.1;

    /// Takes this period's newest fix (stamped `time_ms`) and the speed commanded last period;
    /// returns whether navigation is frozen. A fix already seen (same stamp) changes nothing.
    pub fn update(&mut self, nav: &NavState, time_ms: u64, commanded_mps: f32) -> bool {
        let fix = (nav.position, nav.heading, time_ms);
        match self.last {
            Some((_, _, t)) if t == time_ms => {}
            Some((p, h, _)) if p == nav.position && h == nav.heading => {
                if commanded_mps > Self::MOVING_MPS || self.frozen {
                    self.same = self.same.saturating_add(1);
                }
                self.frozen |= self.same >= Self::FROZEN_FIXES;
            }
            _ => {
                self.same = 0;
                self.frozen = false;
            }
        }
        self.last = Some(fix);
        self.frozen
    }
}

/// Late navigation (issue "Faults": a late or lost frame is no reason to throw the vehicle's
/// motion away). A fix more than one period old (`age_ms > period_ms`: at least one frame lost)
/// is carried forward on its own velocity over ground to now, and the speed is bounded by a
/// fraction of v_max that falls linearly from 1, one period late, to 0 at `nav_timeout_ms`,
/// where [`check`] holds. Returns the state to plan from and that fraction (`None`: on time).
/// Fixes up to one period old are used as they are (the ordinary jitter of an asynchronous
/// navigation stream).
pub fn dead_reckon(
    cfg: &FailsafeConfig,
    nav: &NavState,
    age_ms: u64,
    period_ms: u64,
) -> (NavState, Option<f32>) {
    if age_ms <= period_ms {
        return (*nav, None);
    }
    let predicted = NavState {
        position: nav.position + nav.velocity * (age_ms as f32 * 1e-3),
        ..*nav
    };
    let window = cfg.nav_timeout_ms.saturating_sub(period_ms).max(1);
    let late = (age_ms - period_ms).min(window);
    (predicted, Some(1.0 - late as f32 / window as f32))
}

/// The first fail-safe that applies, in order of precedence, or `None` to plan normally.
pub fn check(cfg: &FailsafeConfig, s: &Situation) -> Option<HoldReason> {
    match s.nav_age_ms {
        None => return Some(HoldReason::StaleNav),
        Some(age) if age > cfg.nav_timeout_ms => return Some(HoldReason::StaleNav),
        Some(_) => {}
    }
    if !s.has_mission {
        return Some(HoldReason::NoMission);
    }
    if s.clearance_m < 0.0 {
        return Some(HoldReason::InsideObstacle);
    }
    // Only while closing: a vehicle already moving away from the nearest surface is not
    // stopped beside it. A mover that came out of a rock's echo 3 m off a VideoRay passing at
    // 1 m/s made it all-stop in the mover's way (bench crossing 1, sonar 20 m / 3.6°); going
    // on, it passed 0.6 m clear.
    let stopping = s.speed * s.speed / (2.0 * s.f_max);
    if s.clearance_m < stopping && s.closing {
        return Some(HoldReason::CollisionImminent);
    }
    None
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    #[test]
    fn a_late_fix_is_carried_forward_and_slows_the_vehicle_until_the_timeout() {
        let cfg = FailsafeConfig::default();
        let nav = NavState {
            position: Vec2::new(10.0, 0.0),
            heading: 0.0,
            velocity: Vec2::new(1.0, 0.5),
        };
        assert_eq!(dead_reckon(&cfg, &nav, 100, 100), (nav, None), "on time");
        let (p, k) = dead_reckon(&cfg, &nav, 300, 100);
        assert!(
            (p.position - Vec2::new(10.3, 0.15)).norm() < 1e-5,
            "{:?}",
            p.position
        );
        assert_eq!((p.heading, p.velocity), (nav.heading, nav.velocity));
        let k = k.unwrap();
        assert!((k - (1.0 - 200.0 / 900.0)).abs() < 1e-6, "{k}");
        let (_, at_timeout) = dead_reckon(&cfg, &nav, cfg.nav_timeout_ms, 100);
        assert_eq!(at_timeout, Some(0.0));
        let (_, beyond) = dead_reckon(&cfg, &nav, 10 * cfg.nav_timeout_ms, 100);
        assert_eq!(beyond, Some(0.0), "never negative");
        let odd = FailsafeConfig {
            nav_timeout_ms: 50,
            ..cfg
        };
        let (_, k) = dead_reckon(&odd, &nav, 150, 100);
        assert_eq!(
            k,
            Some(0.0),
            "a timeout under a period: no division by zero"
        );
    }

    #[test]
    fn the_share_of_pings_that_arrived_is_measured_over_each_turn() {
        let cfg = FailsafeConfig::default();
        let mut w = SonarWatch::default();
        // Every ping: swept = head travel.
        w.update(&cfg, (100, 6300, 6300), 1000, Vec2::ZERO, 0.5);
        assert_eq!(w.delivery(), None);
        // The next turn, one ping in ten arrived.
        w.update(&cfg, (110, 6930, 12_600), 2000, Vec2::ZERO, 0.5);
        let d = w.delivery().unwrap();
        assert!((d - 0.1).abs() < 1e-6, "{d}");
        // Not yet a turn since: unchanged; then all again.
        w.update(&cfg, (120, 8000, 13_000), 3000, Vec2::ZERO, 0.5);
        assert_eq!(w.delivery(), Some(d));
        w.update(&cfg, (200, 14_000, 19_000), 4000, Vec2::ZERO, 0.5);
        assert_eq!(w.delivery(), None, "{:?}", w.delivery());
    }

    #[test]
    fn a_sonar_that_cannot_see_slows_or_holds_the_vehicle() {
        let cfg = FailsafeConfig::default();
        let mut w = SonarWatch::default();
        let swept = (5, 7000, 7000);
        // Never spoken: not watched.
        assert_eq!(w.update(&cfg, (0, 0, 0), 10_000, Vec2::ZERO, 0.5), None);
        // Spoken, but not yet once round: hold.
        assert_eq!(
            w.update(&cfg, (3, 3000, 3000), 10_000, Vec2::ZERO, 0.5),
            Some(0.0)
        );
        assert_eq!(w.update(&cfg, swept, 10_000, Vec2::ZERO, 0.5), None);
        assert_eq!(
            w.update(&cfg, swept, 11_000, Vec2::ZERO, 0.5),
            None,
            "not yet quiet"
        );
        let v = w.update(&cfg, swept, 12_000, Vec2::ZERO, 0.5).unwrap();
        assert!((v - (2.0f32 * 0.5 * 5.0).sqrt()).abs() < 1e-3, "{v}");
        let v = w
            .update(&cfg, swept, 15_000, Vec2::new(4.0, 0.0), 0.5)
            .unwrap();
        assert!((v - 1.0).abs() < 1e-3, "1 m left: {v}");
        assert_eq!(
            w.update(&cfg, swept, 20_000, Vec2::new(5.5, 0.0), 0.5),
            Some(0.0)
        );
        // It speaks again: released.
        assert_eq!(
            w.update(&cfg, (6, 7030, 7030), 20_100, Vec2::new(5.5, 0.0), 0.5),
            None
        );
    }

    fn ok() -> Situation {
        Situation {
            has_mission: true,
            nav_age_ms: Some(10),
            clearance_m: 5.0,
            speed: 1.0,
            f_max: 0.5,
            closing: true,
        }
    }

    #[test]
    fn a_fix_that_stops_changing_while_moving_is_frozen_until_it_changes() {
        let mut d = FreezeDetector::default();
        let at = |x: f32| NavState {
            position: Vec2::new(x, 0.0),
            heading: 0.0,
            velocity: Vec2::ZERO,
        };
        // Moving normally.
        for k in 0..10u64 {
            assert!(!d.update(&at(k as f32 * 0.1), k * 100, 1.0));
        }
        // A new fix, then the same one again with fresh stamps while commanded at 1 m/s:
        // frozen at its fifth repeat.
        let frozen: std::vec::Vec<bool> = (10..17u64)
            .map(|k| d.update(&at(5.0), k * 100, 1.0))
            .collect();
        assert_eq!(frozen, [false, false, false, false, false, true, true]);
        // Held (commanded 0): still frozen while the fix stays the same.
        assert!(d.update(&at(5.0), 1700, 0.0));
        // A new fix releases it.
        assert!(!d.update(&at(5.1), 1800, 0.0));
        // Standing still on purpose is not a freeze.
        let mut d = FreezeDetector::default();
        for k in 0..20u64 {
            assert!(!d.update(&at(3.0), k * 100, 0.0));
        }
    }

    #[test]
    fn normal_situation_plans() {
        assert_eq!(check(&FailsafeConfig::default(), &ok()), None);
    }

    #[test]
    fn each_condition_holds_with_its_reason() {
        let c = FailsafeConfig::default();
        let stale = Situation {
            nav_age_ms: Some(c.nav_timeout_ms + 1),
            ..ok()
        };
        assert_eq!(check(&c, &stale), Some(HoldReason::StaleNav));
        let never = Situation {
            nav_age_ms: None,
            ..ok()
        };
        assert_eq!(check(&c, &never), Some(HoldReason::StaleNav));
        let idle = Situation {
            has_mission: false,
            ..ok()
        };
        assert_eq!(check(&c, &idle), Some(HoldReason::NoMission));
        let inside = Situation {
            clearance_m: -0.1,
            ..ok()
        };
        assert_eq!(check(&c, &inside), Some(HoldReason::InsideObstacle));
        // 1 m/s braking at 0.5 m/s² needs 1 m.
        let close = Situation {
            clearance_m: 0.9,
            ..ok()
        };
        assert_eq!(check(&c, &close), Some(HoldReason::CollisionImminent));
        // ... but not one already moving away from that surface.
        let leaving = Situation {
            closing: false,
            ..close
        };
        assert_eq!(check(&c, &leaving), None);
        let slow = Situation {
            clearance_m: 0.9,
            speed: 0.5,
            ..ok()
        };
        assert_eq!(check(&c, &slow), None);
    }
}
