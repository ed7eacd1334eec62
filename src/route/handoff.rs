//! The lock-free handoff of the newest route from the background to the periodic task.
//!
//! One writer (background), one reader (periodic), a sequence counter around the fields: the
//! writer makes it odd, stores, makes it even; the reader keeps what it read only if the
//! counter was the same even number before and after. The reader never waits: a read that
//! races a write returns `None` and the periodic task keeps the route it had.

use core::sync::atomic::{AtomicU32, AtomicU8, Ordering};

use super::{Route, RouteStatus};
use crate::math::Vec2;

/// A one-slot, overwrite-newest route mailbox. Put one in a `static` on a board.
pub struct RouteSlot {
    seq: AtomicU32,
    /// aim.x, aim.y, goal.x, goal.y as f32 bits; time_ms low and high words.
    words: [AtomicU32; 6],
    status: AtomicU8,
}

#[allow(clippy::declare_interior_mutable_const)]
const ZERO: AtomicU32 = AtomicU32::new(0);

impl Default for RouteSlot {
    fn default() -> Self {
        Self::new()
    }
}

impl RouteSlot {
    /// Empty.
    pub const fn new() -> Self {
        RouteSlot {
            seq: AtomicU32::new(0),
            words: [ZERO; 6],
            status: AtomicU8::new(0),
        }
    }

    /// Publishes `r` (writer only).
    pub fn publish(&self, r: &Route) {
        self.seq.fetch_add(1, Ordering::AcqRel);
        let w = [
            r.aim.x.to_bits(),
            r.aim.y.to_bits(),
            r.goal.x.to_bits(),
            r.goal.y.to_bits(),
            r.time_ms as u32,
            (r.time_ms >> 32) as u32,
        ];
        for (slot, v) in self.words.iter().zip(w) {
            slot.store(v, Ordering::Relaxed);
        }
        self.status.store(r.status.code(), Ordering::Relaxed);
        self.seq.fetch_add(1, Ordering::AcqRel);
    }

    /// The newest route, `None` if none was published yet or a write was in progress.
    pub fn latest(&self) -> Option<Route> {
        let s1 = self.seq.load(Ordering::Acquire);
        let mut w = [0u32; 6];
        for (v, slot) in w.iter_mut().zip(&self.words) {
            *v = slot.load(Ordering::Relaxed);
        }
        let status = RouteStatus::from_code(self.status.load(Ordering::Relaxed));
        let s2 = self.seq.load(Ordering::Acquire);
        if s1 != s2 || !s1.is_multiple_of(2) || s1 == 0 {
            return None;
        }
        let [ax, ay, gx, gy, t0, t1] = w;
        Some(Route {
            aim: Vec2::new(f32::from_bits(ax), f32::from_bits(ay)),
            goal: Vec2::new(f32::from_bits(gx), f32::from_bits(gy)),
            time_ms: u64::from(t0) | (u64::from(t1) << 32),
            status: status?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_newest_route_is_read_back_whole() {
        let slot = RouteSlot::new();
        assert_eq!(slot.latest(), None);
        let r = Route {
            aim: Vec2::new(1.5, -2.0),
            goal: Vec2::new(150.0, 3.0),
            time_ms: (7u64 << 32) + 12,
            status: RouteStatus::Detour,
        };
        slot.publish(&r);
        assert_eq!(slot.latest(), Some(r));
    }
}
