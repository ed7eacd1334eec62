//! Faint pairs: another small vehicle, seen on one beam a sweep, as two sightings on a
//! collision course.
//!
//! **Why.** Another VideoRay (0.5 m across) 10–18 m off is narrower than a 3.6° step of the
//! head, so a sweep puts it on one beam, and its echo (a mean of 110–210 there) is no stronger
//! than most spurious targets': the extractor's rule — two beams, or one beam strong or
//! seconded (`crate::sonar::GLIMPSE_INTENSITY`) — drops it, and two VideoRays meeting head-on
//! saw each other only 2–5 m apart, too late for either to turn. In each of the eight head-on
//! contacts of the bench's second trial (`--trial 1`, seeds 200–599, VPF, multipoint and navfn)
//! at least one of the two had seen the other so on two sweeps in a row, at 18 → 12 → 6 m, 6–7 s
//! before they met (the extractor's echoes, logged on re-flown runs).
//!
//! **What.** The extractor lets such a beam out as a *faint* sighting
//! ([`crate::sonar::Feature::faint`]) when its mean is at least
//! [`crate::sonar::FAINT_INTENSITY`] (ahead, [`crate::sonar::FAINT_AHEAD_INTENSITY`]: "Ahead",
//! below). One is nothing. Two are a target when the later lies
//! where one seen at the earlier could have gone — [`PAIR_MIN_S`]..=[`PAIR_MAX_S`] apart (the
//! next sweep or the one after), at [`MIN_MPS`]..=[`MAX_MPS`] — and when that motion brings it
//! within [`THREAT_M`] of this vehicle within [`HORIZON_S`], on the two straight courses or
//! with this vehicle where it is (it may be turning); and only while this vehicle is under
//! way. A pair that passes clear is not worth the risk of believing a spurious one. The
//! tracker (`crate::guidance::tracks`, "Faint pairs") opens a mover of 0.3 m at the later
//! sighting with the pair's velocity, which the planner and the guard keep clear of as of any
//! mover; its later faint sightings are its next looks, and it goes when nothing has borne it
//! out for [`PAIR_MAX_S`] (a phantom left for the 30 s of a sensed obstacle held a VideoRay
//! "inside" it where it had been, in a crossing mover's way).
//!
//! **Spurious pairs.** The simulated sonar puts a spurious target on 3 % of its pings, at any
//! range (about three a sweep), as fish and side lobes do. Without the floor on the mean, they
//! paired into a phantom mover every 20–50 s under way, and navfn lost 14 of 400 crossing and
//! head-on worlds to them. The simulated ones are at most 176; a VideoRay's one-beam echoes
//! at 10–18 m were 131–212, most above 150. Nor are sightings within [`MIN_RANGE_M`] of the
//! head kept, nor any within `crate::sonar::FAINT_ALONE_M` of an obstacle believed (its edge).
//! With a slower sweep (the firmware's default 30 m at 1.8°: 9 s) pairs a sweep apart are
//! older than [`PAIR_MAX_S`], and the tracker is as without this. A slow-turning craft
//! (`Params::turn_rate_rps` > 0) opens none (`Periodic` hands it no velocity): it cannot step
//! aside from a mover 6 s off — its guard stops it — and phantoms stopped it again and again:
//! the flat-fish with its recipe, seeds 0–33, went 333 → 322 of 408 with pairs (27 lost, 16
//! gained, no contact either way; its bench's other vehicles are flat-fish, on many beams).
//!
//! **Ahead** (2026-12-07). What was left of the head-on contacts were pairs a floor of 150
//! never formed: re-flown with `hil echoes`, in each of the eight of seeds 0–199 (trials 0 and
//! 1), 1000–1199 and 6000–6199 (VPF 1111, 1154, 6155, 170; multipoint 59, 6067; navfn 1071,
//! 1098) the two VideoRays heard each other on one beam a sweep, at about 16, 10 and 4 m and
//! within 40° of the bow, with means of 110–150 on the first two. So within
//! [`crate::sonar::FAINT_AHEAD_RAD`] (45°) of the bow the floor is
//! [`crate::sonar::FAINT_AHEAD_INTENSITY`] (110), where a vessel met head-on is and closes at
//! twice the cruise; elsewhere it stays 150. A faint sighting with a believed map cell 1–2 m
//! from it is a wall's edge on one beam and pairs with nothing
//! ([`crate::sonar::EvidenceMap::occupied_between`]), as one by an obstacle already was.
//! *Tried first:* 110 all round. Crossing and head-on gained as much, but the phantoms of
//! three quarters of the spurious targets cost multipoint 37 of 2 400 worlds (seeds 0–199:
//! channels 197 → 181, wall gaps 194 → 184), and the median periods the guard intervened rose
//! by a third; with the map's cells as well, channels came back (192) and wall gaps did not
//! (180). Measured as kept: "The faint floor ahead" in docs/bench-history.md.
//!
//! *Tried and not kept* (2026-12-06): a weaker later sighting. In VPF head-on seed 1154 one
//! VideoRay saw the other on one beam at 16 m (a mean of about 160) and a sweep later at
//! 9.7 m (121, under the floor); neither vehicle believed the other until 3 m apart, and
//! they met. So the later of a pair was let be as weak as a mean of 110 (and was never kept
//! to start one). Crossing and head-on × VPF, multipoint and navfn, 1 200 runs a bench:
//! seeds 1000–1199, contacts 7 → 3; seeds 0–199, 1 → 3; seeds 1000–1199 at `--trial 1`,
//! 1 → 3 — 9 → 9 in all, successes 3 591 → 3 590. The new contacts were vehicles neither
//! believed at all, met on other paths: what it gains, chance takes back.
//!
//! None of the seeds has this; seed 000's vehicles perceive one another whole.
//!
//! **Capacity.** [`KEPT`] unpaired sightings, in a ring: a new one takes the oldest's place.

use crate::math::Vec2;

/// Unpaired faint sightings kept.
pub const KEPT: usize = 8;
/// Shortest time between the two sightings of a pair, s: not the same pass of the head.
pub const PAIR_MIN_S: f32 = 1.5;
/// Longest time between the two sightings of a pair, s: two sweeps of 20 m at 3.6° (3.2 s
/// each), so a target missed on one sweep still pairs.
pub const PAIR_MAX_S: f32 = 7.0;
/// Slowest motion between the two, m/s (the tracker's floor for a mover).
pub const MIN_MPS: f32 = 0.3;
/// Fastest motion between the two, m/s: a vehicle of the VideoRay's class at full speed, with
/// the half metre a one-beam fit may be off.
pub const MAX_MPS: f32 = 1.5;
/// Faint sightings nearer than this are not kept, m: spurious echoes come at any range alike,
/// so per square metre they crowd round the head (within 3.5 m were 19 of the 23 pairs two
/// VideoRays made in a bench head-on world before the floor on the mean), and another vehicle
/// that near is on two beams.
pub const MIN_RANGE_M: f32 = 4.0;
/// Least distance between the two, m: less is one place seen twice.
pub const MIN_MOVE_M: f32 = 1.0;
/// The pair's course must come this close to this vehicle's, m: two hulls and the guard's
/// margin, and the metre the two-point velocity may be off over the horizon.
pub const THREAT_M: f32 = 3.0;
/// ... within this time, s.
pub const HORIZON_S: f32 = 15.0;
/// A vehicle slower than this opens no pairs, m/s: holding station it has no way to keep
/// clear, and nothing to gain by believing a spurious one.
pub const UNDER_WAY_MPS: f32 = 0.3;

/// A faint sighting: where and when.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Faint {
    center: Vec2,
    /// Its time, ms, wrapping (a pair is seconds apart).
    time_ms: u32,
}

/// Two faint sightings of one target on a collision course.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair {
    /// The earlier sighting, m.
    pub first: Vec2,
    /// The target's velocity from the two, m/s.
    pub velocity: Vec2,
}

/// The unpaired faint sightings (module notes).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FaintPairs {
    kept: [Option<Faint>; KEPT],
    /// The place the next unpaired sighting takes: the oldest's.
    next: u8,
}

impl FaintPairs {
    /// An empty table.
    pub const fn new() -> Self {
        FaintPairs {
            kept: [None; KEPT],
            next: 0,
        }
    }

    /// A faint sighting at `center`, `time_ms`, seen by a vehicle at `own` moving at
    /// `own_velocity`: the pair it completes (its partner is forgotten), or none (it is kept).
    pub fn sighting(
        &mut self,
        center: Vec2,
        time_ms: u64,
        own: Vec2,
        own_velocity: Vec2,
    ) -> Option<Pair> {
        let r = center - own;
        if !r.is_finite() || r.norm2() < MIN_RANGE_M * MIN_RANGE_M {
            return None;
        }
        let under_way = own_velocity.norm2() >= UNDER_WAY_MPS * UNDER_WAY_MPS;
        // Milliseconds, wrapping every 49 days: the two of a pair are seconds apart.
        let now = time_ms as u32;
        for slot in self.kept.iter_mut() {
            let Some(f) = *slot else { continue };
            // Negative when it is later than this one.
            let dt = now.wrapping_sub(f.time_ms) as i32 as f32 * 1e-3;
            let moved = center - f.center;
            let v = moved * (1.0 / dt);
            let pairs = under_way
                && (PAIR_MIN_S..=PAIR_MAX_S).contains(&dt)
                && moved.norm2() >= MIN_MOVE_M * MIN_MOVE_M
                && (MIN_MPS * MIN_MPS..=MAX_MPS * MAX_MPS).contains(&v.norm2())
                // Straight courses, or this vehicle where it is: it may be turning.
                && (comes_near(r, v - own_velocity) || comes_near(r, v));
            if pairs {
                *slot = None;
                return Some(Pair {
                    first: f.center,
                    velocity: v,
                });
            }
        }
        if let Some(slot) = self.kept.get_mut(usize::from(self.next)) {
            *slot = Some(Faint {
                center,
                time_ms: now,
            });
        }
        self.next = (self.next + 1) % KEPT as u8;
        None
    }
}

/// Whether a target at `r` (from this vehicle, farther than [`THREAT_M`]) moving at `w`
/// (relative) comes within [`THREAT_M`] of it within [`HORIZON_S`].
#[inline(never)]
fn comes_near(r: Vec2, w: Vec2) -> bool {
    let t = -r.dot(w) / crate::math::max(w.norm2(), 1e-6);
    let t = crate::math::min(crate::math::max(t, 0.0), HORIZON_S);
    (r + w * t).norm2() <= THREAT_M * THREAT_M
}

#[cfg(test)]
mod tests {
    use super::*;

    const STILL: Vec2 = Vec2::ZERO;
    /// Under way along x at 1 m/s.
    const U: Vec2 = Vec2::new(1.0, 0.0);

    #[test]
    fn a_vehicle_coming_head_on_pairs_on_the_next_sweep() {
        let mut p = FaintPairs::new();
        let u = Vec2::new(1.0, 0.0);
        // Seen 15 m ahead; a sweep (3.2 s) later 3.2 m nearer, having come at 1 m/s too.
        assert_eq!(p.sighting(Vec2::new(15.0, 0.3), 1000, Vec2::ZERO, u), None);
        let pair = p.sighting(Vec2::new(11.8, 0.2), 4200, Vec2::new(3.2, 0.0), u);
        let pair = pair.expect("a pair");
        assert_eq!(pair.first, Vec2::new(15.0, 0.3));
        assert!(
            (pair.velocity - Vec2::new(-1.0, -0.03)).norm() < 0.01,
            "{pair:?}"
        );
        // Its partner is gone: the next sighting pairs with nothing.
        assert_eq!(
            p.sighting(Vec2::new(8.6, 0.2), 7400, Vec2::new(6.4, 0.0), u),
            None
        );
    }

    #[test]
    fn pairs_that_pass_clear_go_away_or_could_be_no_vehicle_are_no_target() {
        let no_pair_at = |a: (f32, f32, u64), b: (f32, f32, u64), u: Vec2| {
            let mut p = FaintPairs::new();
            let _ = p.sighting(Vec2::new(a.0, a.1), a.2, Vec2::ZERO, u);
            p.sighting(Vec2::new(b.0, b.1), b.2, Vec2::ZERO, u)
                .is_none()
        };
        let no_pair = |a, b| no_pair_at(a, b, U);
        // Heading at the vehicle a sweep later: the pair; not while it holds station.
        assert!(!no_pair((10.0, 0.0, 0), (7.0, 0.0, 3200)));
        assert!(
            no_pair_at((10.0, 0.0, 0), (7.0, 0.0, 3200), STILL),
            "holding station"
        );
        assert!(
            no_pair((10.0, 2.0, 0), (10.0, 5.2, 3200)),
            "crossing 10 m off"
        );
        assert!(no_pair((10.0, 0.0, 0), (13.0, 0.0, 3200)), "going away");
        assert!(no_pair((20.0, 0.0, 0), (12.0, 0.0, 3200)), "2.5 m/s");
        assert!(
            no_pair((10.0, 0.0, 0), (9.0, 0.0, 1000)),
            "the same pass of the head"
        );
        assert!(
            no_pair((10.0, 0.0, 0), (6.0, 0.0, 9600)),
            "three sweeps apart"
        );
        assert!(
            no_pair((6.0, 0.0, 0), (5.2, 0.0, 3200)),
            "one place seen twice"
        );
        assert!(no_pair((10.0, 0.0, 3200), (7.0, 0.0, 0)), "back in time");
        let before_wrap = u64::from(u32::MAX) - 1000;
        let after = (1u64 << 32) + 2199;
        assert!(
            !no_pair((10.0, 0.0, before_wrap), (7.0, 0.0, after)),
            "3.2 s across the wrap"
        );
        // Near the head, nothing is kept.
        let mut p = FaintPairs::new();
        assert_eq!(p.sighting(Vec2::new(3.0, 0.0), 0, Vec2::ZERO, U), None);
        assert_eq!(p.sighting(Vec2::new(f32::NAN, 0.0), 0, Vec2::ZERO, U), None);
        assert_eq!(p, FaintPairs::new());
    }

    #[test]
    fn the_table_keeps_the_newest_sightings() {
        let mut p = FaintPairs::new();
        // KEPT + 1 sightings round a 10 m circle, 40° and 0.1 s apart: none pairs with another.
        let at = |k: usize| Vec2::from_angle(k as f32 * 40f32.to_radians()) * 10.0;
        for k in 0..=KEPT {
            assert_eq!(p.sighting(at(k), 100 * k as u64, Vec2::ZERO, U), None);
        }
        // 3 m from the first towards the vehicle, a sweep later: it was replaced.
        assert_eq!(p.sighting(at(0) * 0.7, 3200, Vec2::ZERO, U), None);
        // The same from the last: it is kept.
        let pair = p.sighting(at(KEPT) * 0.7, 100 * KEPT as u64 + 3200, Vec2::ZERO, U);
        assert_eq!(pair.map(|q| q.first), Some(at(KEPT)));
    }
}
