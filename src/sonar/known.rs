//! The vehicles the host tells the firmware about (`Contacts` of kind vehicle: a formation's
//! mates, whose positions seed 001's virtual leader needs): their echoes are not structure.
//!
//! The sonar also sees those vehicles. Taken as rocks, each left believed cells where it had
//! been in the evidence map, and sonar tracks where the world table already holds it as an
//! agent: a formation of flat-fish (9 m apart) found its route enclosed by its mates' wakes
//! and sat for minutes (`hil bench --families formation`, own sonar). An echo within a known
//! vehicle's hull and [`ECHO_MARGIN_M`] of where it is now (its last report carried on its
//! reported velocity) is that vehicle: the extractor leaves it out of the features and the map
//! adds no hit for it, though the beam's free water still ends there (behind it is its
//! acoustic shadow, not open water). The price: structure within that metre of a mate's hull
//! goes unseen while the mate is there (the mate itself is about to touch it).
//!
//! **Capacity.** [`MAX_KNOWN`] vehicles (the world's agent table, `crate::world::MAX_AGENTS`):
//! a report updates the entry with its id; a new id takes a free entry or, when full, the
//! stalest one's. A report older than [`MAX_AGE_MS`] no longer hides anything: a vehicle the
//! host stopped reporting is seen as the sonar sees it.

use heapless::Vec;

use crate::math::Vec2;

/// How many vehicles are remembered: as many as the world holds agents.
pub const MAX_KNOWN: usize = crate::world::MAX_AGENTS;

/// A report this old, ms, hides no echo (a few sweeps' worth of a slow acoustic link).
pub const MAX_AGE_MS: u32 = 10_000;

/// An echo this far outside a known vehicle's hull, m, is still that vehicle: a fix and its
/// report are a period or two apart, and the hull is fitted to the sonar's leading edge.
pub const ECHO_MARGIN_M: f32 = 1.0;

/// One reported vehicle: 24 bytes (the static RAM budget is counted in hundreds).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Known {
    center: Vec2,
    velocity: Vec2,
    /// Time of the report, ms, modulo 2³² (ages are wrapping differences: under 49 days).
    seen_ms: u32,
    id: u16,
    /// Hull radius, decimetres rounded up (saturating at 25.5 m).
    radius_dm: u8,
}

/// The vehicles reported by the host, where they are.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct KnownVehicles {
    known: Vec<Known, MAX_KNOWN>,
}

impl KnownVehicles {
    /// Vehicle `id` of hull radius `radius` m is at `center` moving at `velocity` at
    /// `time_ms` (non-finite values are ignored: the link checked them already).
    pub fn report(&mut self, id: u16, center: Vec2, radius: f32, velocity: Vec2, time_ms: u64) {
        if !(center.is_finite() && velocity.is_finite() && radius.is_finite()) {
            return;
        }
        let k = Known {
            center,
            velocity,
            seen_ms: time_ms as u32,
            id,
            // `as` saturates: 25.5 m and more give 255, negatives 0.
            radius_dm: libm::ceilf(radius * 10.0) as u8,
        };
        let now = k.seen_ms;
        let slot = self.known.iter().position(|q| q.id == id).or_else(|| {
            // Full: the stalest entry goes.
            (self.known.len() == MAX_KNOWN)
                .then(|| {
                    (0..self.known.len()).max_by_key(|&i| {
                        self.known.get(i).map_or(0, |q| now.wrapping_sub(q.seen_ms))
                    })
                })
                .flatten()
        });
        match slot.and_then(|i| self.known.get_mut(i)) {
            Some(q) => *q = k,
            None => {
                let _ = self.known.push(k);
            }
        }
    }

    /// Whether an echo at `p` at `time_ms` is one of the known vehicles.
    pub fn covers(&self, p: Vec2, time_ms: u64) -> bool {
        let now = time_ms as u32;
        self.known.iter().any(|k| {
            // A report from the future (clocks a period apart) is as good as a fresh one.
            let age = now.wrapping_sub(k.seen_ms);
            let age = if age > u32::MAX / 2 { 0 } else { age };
            if age > MAX_AGE_MS {
                return false;
            }
            let here = k.center + k.velocity * (age as f32 * 1e-3);
            let reach = f32::from(k.radius_dm) * 0.1 + ECHO_MARGIN_M;
            (p - here).norm2() <= reach * reach
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_echo_on_a_reported_vehicle_is_covered_where_it_has_moved_to() {
        let mut k = KnownVehicles::default();
        k.report(7, Vec2::new(10.0, 0.0), 2.25, Vec2::new(0.0, 1.0), 1_000);
        // 3 s later it is at (10, 3): an echo off its near face, not one where it was.
        assert!(k.covers(Vec2::new(7.5, 3.0), 4_000));
        assert!(!k.covers(Vec2::new(7.5, 0.0), 4_000));
        // Nothing else is hidden, and a stale report hides nothing.
        assert!(!k.covers(Vec2::new(20.0, 3.0), 4_000));
        assert!(!k.covers(Vec2::new(10.0, 1.0), 1_000 + u64::from(MAX_AGE_MS) + 1));
    }

    #[test]
    fn the_same_id_updates_and_a_full_table_replaces_the_stalest() {
        let mut k = KnownVehicles::default();
        for i in 0..MAX_KNOWN as u16 {
            // Vehicle 0 is the stalest.
            k.report(
                i,
                Vec2::new(100.0 * f32::from(i), 0.0),
                1.0,
                Vec2::ZERO,
                1_000 + u64::from(i),
            );
        }
        k.report(3, Vec2::new(0.0, 50.0), 1.0, Vec2::ZERO, 2_000);
        assert!(k.covers(Vec2::new(0.0, 50.0), 2_000), "moved");
        assert!(!k.covers(Vec2::new(300.0, 0.0), 2_000), "not where it was");
        k.report(99, Vec2::new(0.0, -50.0), 1.0, Vec2::ZERO, 2_000);
        assert!(
            k.covers(Vec2::new(0.0, -50.0), 2_000),
            "the newcomer is kept"
        );
        assert!(!k.covers(Vec2::ZERO, 2_000), "the stalest went");
        assert!(k.covers(Vec2::new(100.0, 0.0), 2_000), "the others stay");
    }

    #[test]
    fn bad_reports_are_ignored() {
        let mut k = KnownVehicles::default();
        k.report(1, Vec2::new(f32::NAN, 0.0), 1.0, Vec2::ZERO, 0);
        k.report(1, Vec2::ZERO, f32::INFINITY, Vec2::ZERO, 0);
        assert!(!k.covers(Vec2::ZERO, 0));
    }
}
