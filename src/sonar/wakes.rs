//! Where the movers are: the one thing the periodic task writes into the evidence map, so that
//! a mover's echoes leave no wake of believed cells behind it.
//!
//! **Why.** The map keeps every echo where it was seen until beams see through its cell again
//! (`super::evidence`). A crossing mover is hit on several beams of every sweep; each echo adds
//! evidence where the mover was, and the cells it leaves fill faster than later beams clear
//! them. The wake is a line of believed cells along the mover's track, a wall to the route
//! layer: a vehicle that had to cross the track was routed round the wake's end, which is the
//! mover, and escorted it away from its goal (generated crossing worlds, own sonar: a navfn
//! VideoRay followed a mover 250 m south-west with its goal 230 m north-east). The tracker's
//! test for structure (`EvidenceMap::runs_on`) also took the wake for a wall the mover was a
//! fragment of, and dropped its velocity.
//!
//! **What.** Each period the periodic task publishes the movers it believes (sensed obstacles
//! with a velocity), where it believes they are now: the nearest [`MAX_WAKES`] to the vehicle.
//! An echo within a published mover's radius and [`super::ECHO_MARGIN_M`] adds no evidence,
//! exactly as an echo of a vehicle the host reports (`super::known`): the beam's free water
//! still ends there, and the extractor still makes it a feature (the tracker needs it). A
//! mover's first sightings, before the tracker gives it a velocity, are painted as before;
//! so, for a craft that turns slowly, are the echoes of a sonar track that only keeps pace
//! with it against other believed structure, as the nearest stretch of a wall seems to while
//! the craft runs along it (`crate::guidance::tracks::paces`).
//!
//! **Contexts.** The periodic task is the only writer and the background (`observe`) the
//! only reader. The slots are atomics written whole; a reader preempted mid-read may pair one
//! period's x with the next period's y, a tenth of a second's motion apart, inside the margin.
//! No lock, no wait on either side.
//!
//! **Capacity.** [`MAX_WAKES`] movers, the nearest first; farther ones paint their wakes as
//! before (a wake beyond the nearest four is far from the vehicle's next turns).

use core::sync::atomic::{AtomicU32, Ordering};

use crate::math::Vec2;

/// How many movers' echoes are left out of the map.
pub const MAX_WAKES: usize = 4;

/// One mover: centre x, centre y and reach (radius + margin), as `f32` bits.
type Slot = [AtomicU32; 3];

#[allow(clippy::declare_interior_mutable_const)]
const EMPTY: Slot = [AtomicU32::new(0), AtomicU32::new(0), AtomicU32::new(0)];

/// The movers the periodic task believes, where it believes they are now (module notes).
#[derive(Debug)]
pub struct Wakes {
    slots: [Slot; MAX_WAKES],
    /// Slots in use, 0 ..= [`MAX_WAKES`].
    count: AtomicU32,
}

impl Default for Wakes {
    fn default() -> Self {
        Self::new()
    }
}

impl Wakes {
    /// None.
    pub const fn new() -> Self {
        Wakes {
            slots: [EMPTY; MAX_WAKES],
            count: AtomicU32::new(0),
        }
    }

    /// The writer's side (periodic task): the movers now, as (centre, radius) — at most
    /// [`MAX_WAKES`] of them, the nearest first; the rest are ignored. Non-finite ones are
    /// skipped.
    pub fn publish(&self, movers: impl Iterator<Item = (Vec2, f32)>) {
        let mut n = 0;
        for ((c, r), slot) in movers
            .filter(|(c, r)| c.is_finite() && r.is_finite() && *r >= 0.0)
            .zip(self.slots.iter())
        {
            let reach = r + super::ECHO_MARGIN_M;
            for (cell, v) in slot.iter().zip([c.x, c.y, reach]) {
                cell.store(v.to_bits(), Ordering::Relaxed);
            }
            n += 1;
        }
        self.count.store(n, Ordering::Release);
    }

    /// The reader's side (background): whether an echo at `p` is one of the movers.
    pub fn covers(&self, p: Vec2) -> bool {
        let n = self.count.load(Ordering::Acquire) as usize;
        self.slots.iter().take(n).any(|slot| {
            let [x, y, reach] = slot
                .each_ref()
                .map(|cell| f32::from_bits(cell.load(Ordering::Relaxed)));
            (p - Vec2::new(x, y)).norm2() <= reach * reach
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_echo_on_a_published_mover_is_covered_and_nothing_else() {
        let w = Wakes::new();
        assert!(!w.covers(Vec2::ZERO), "none published");
        w.publish([(Vec2::new(10.0, 0.0), 1.5)].into_iter());
        // Its hull and the margin.
        assert!(w.covers(Vec2::new(7.6, 0.0)));
        assert!(!w.covers(Vec2::new(7.4, 0.0)));
        // The next period it has moved on: where it was is structure again.
        w.publish([(Vec2::new(12.0, 0.0), 1.5)].into_iter());
        assert!(!w.covers(Vec2::new(8.0, 0.0)));
        assert!(w.covers(Vec2::new(13.0, 1.0)));
        w.publish(core::iter::empty());
        assert!(!w.covers(Vec2::new(12.0, 0.0)), "no movers: nothing hidden");
    }

    #[test]
    fn only_the_first_max_wakes_and_only_finite_ones_are_kept() {
        let w = Wakes::new();
        let movers = (0..2 * MAX_WAKES).map(|k| (Vec2::new(10.0 * k as f32, 0.0), 1.0));
        w.publish(
            [(Vec2::new(f32::NAN, 0.0), 1.0), (Vec2::ZERO, f32::INFINITY)]
                .into_iter()
                .chain(movers),
        );
        for k in 0..2 * MAX_WAKES {
            let kept = k < MAX_WAKES;
            assert_eq!(w.covers(Vec2::new(10.0 * k as f32, 0.0)), kept, "mover {k}");
        }
    }
}
