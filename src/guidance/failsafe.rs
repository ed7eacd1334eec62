//! Fail-safes checked by the periodic task before it plans: each turns the command into a hold
//! with its reason, until the condition clears.
//!
//! - no mission → hold;
//! - navigation older than `nav_timeout_ms` (or none yet) → hold, until fresh navigation;
//! - inside an obstacle's surface → all-stop;
//! - a collision that cannot be avoided at the current speed → all-stop. "Cannot be avoided":
//!   braking at F_max (the most the planner ever commands) from speed v needs v²/2F_max metres,
//!   and the nearest surface is closer than that.

use crate::planner::HoldReason;

/// The fail-safes' settings.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FailsafeConfig {
    /// Navigation older than this holds the vehicle, ms. The default, 150 ms, is 1.5 periods at
    /// 10 Hz: a lost navigation stream stops the vehicle at the second tick after the last fix.
    pub nav_timeout_ms: u64,
}

impl Default for FailsafeConfig {
    fn default() -> Self {
        FailsafeConfig {
            nav_timeout_ms: 150,
        }
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
    let stopping = s.speed * s.speed / (2.0 * s.f_max);
    if s.clearance_m < stopping {
        return Some(HoldReason::CollisionImminent);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok() -> Situation {
        Situation {
            has_mission: true,
            nav_age_ms: Some(10),
            clearance_m: 5.0,
            speed: 1.0,
            f_max: 0.5,
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
            nav_age_ms: Some(151),
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
        let slow = Situation {
            clearance_m: 0.9,
            speed: 0.5,
            ..ok()
        };
        assert_eq!(check(&c, &slow), None);
    }
}
