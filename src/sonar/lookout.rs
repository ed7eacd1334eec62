//! The lookout: where the sonar last looked in each direction, and how far it saw clear there
//! — so the vehicle never outruns its own sonar (COLREG rule 5: "a proper look-out by sight
//! and hearing … so as to make a full appraisal of the situation").
//!
//! **Why.** The evidence map knows only what echoed. A mechanically scanned head looks along
//! each world bearing about once a sweep (9 s), but a vehicle that turns with the head freezes
//! the beam in the world frame, and a vehicle that turns into a new heading may be heading
//! where the head last looked from far away. In a bent channel (generated world channel 136,
//! VideoRay, VPF, own sonar) the vehicle spun round at the bend and then ran at 1 m/s into the
//! outer wall 4 m off: the head had last looked that way 13–17 s before, from 6 m to the side,
//! and no echo of that stretch of wall was ever believed. The guard checks only what is
//! believed, so nothing slowed it.
//!
//! **What is kept.** For each of [`LOOK_SECTORS`] world bearings, the end of the beam of the
//! head's last pass over it that saw farthest: its first echo the evidence map takes, or the
//! scan's full range when it heard nothing. (Farthest of a pass, not the last beam: another
//! vehicle beside the track stops a few beams short, and says nothing of the track the others
//! looked down.) Seen from the vehicle at `p` going along `u`, a beam ending at `q` vouches
//! for the way ahead as far as `(q − p)·u`, less how far beyond the hull to the side of the
//! track it ran, `|(q − p) × u|` ([`clear_ahead`]): a beam cast from here straight ahead
//! vouches for all of it, one cast from 6 m to the side for nothing. The guard asks for no
//! more speed than stops within that (`crate::guidance::guard`, "Lookout").
//!
//! None of the seeds has this; seed 000's vehicle perceives its obstacles whole.
//!
//! **Capacity and contexts.** Fixed: one word per sector, the end's map cell as two wrapping
//! 16-bit indices (exact within 16 km of the vehicle at 0.5 m cells), a word of sectors looked
//! at and the sector last written (136 bytes). One writer (the background, per scanline,
//! through `EvidenceMap::observe`), one reader (the periodic task); each end is one atomic
//! word, so a reader never sees half of one.

use core::sync::atomic::{AtomicU32, Ordering};

use crate::math::{Vec2, PI, TAU};

/// World bearings kept (11.25° each): about six pings of a 1.8°-step head per sector.
pub const LOOK_SECTORS: usize = 32;

/// Where the sonar last looked in each direction (module notes).
#[derive(Debug)]
pub struct Lookout {
    /// Per sector, the kept beam's end (the farthest-seeing of the last pass) as wrapping cell
    /// indices: column low, row high.
    ends: [AtomicU32; LOOK_SECTORS],
    /// Bit k: sector k has been looked along.
    looked: AtomicU32,
    /// The sector of the last beam recorded (the writer's own: a new pass begins when the
    /// head enters another sector).
    last: AtomicU32,
}

#[allow(clippy::declare_interior_mutable_const)]
const NONE: AtomicU32 = AtomicU32::new(0);

impl Default for Lookout {
    fn default() -> Self {
        Self::new()
    }
}

/// The sector of world direction `a`, rad.
fn sector(a: f32) -> usize {
    let k = libm::floorf((a + PI) / TAU * LOOK_SECTORS as f32);
    // A NaN or an angle a rounding past ±π lands on a valid sector all the same.
    (k as i32).rem_euclid(LOOK_SECTORS as i32) as usize
}

fn bit(k: usize) -> u32 {
    1u32.checked_shl(k as u32).unwrap_or(0)
}

fn cell(x: f32, cell_m: f32) -> i32 {
    libm::floorf(x / cell_m) as i32
}

impl Lookout {
    /// Nothing looked at.
    pub const fn new() -> Self {
        Lookout {
            ends: [NONE; LOOK_SECTORS],
            looked: AtomicU32::new(0),
            last: AtomicU32::new(u32::MAX),
        }
    }

    /// Whether the sonar has looked anywhere yet (a vehicle perceiving by contacts never does).
    pub fn any(&self) -> bool {
        self.looked.load(Ordering::Acquire) != 0
    }

    /// Forgets every look.
    pub fn clear(&self) {
        self.looked.store(0, Ordering::Release);
    }

    /// A beam cast from `origin` along the unit vector `look` saw clear for `clear_m` metres;
    /// `cell_m` is the map's cell. Writer side. Of the beams of one pass of the head over a
    /// sector, the one that saw farthest is kept: a target beside the track takes a few of them
    /// and says nothing of the track, which the others looked down.
    pub fn record(&self, origin: Vec2, look: Vec2, clear_m: f32, cell_m: f32) {
        let end = origin + look * clear_m;
        if !(end.is_finite() && cell_m > 0.0) {
            return;
        }
        let k = sector(look.angle());
        let same_pass = self.last.swap(k as u32, Ordering::Relaxed) == k as u32;
        let farther = self
            .end_in(k, origin, cell_m)
            .is_none_or(|old| (old - origin).norm() < clear_m);
        if same_pass && !farther {
            return;
        }
        let i = cell(end.x, cell_m) as u16 as u32;
        let j = cell(end.y, cell_m) as u16 as u32;
        if let Some(e) = self.ends.get(k) {
            e.store(i | (j << 16), Ordering::Relaxed);
            self.looked.fetch_or(bit(k), Ordering::Release);
        }
    }

    /// Where the beam kept for `heading`'s bearing (the farthest-seeing of the head's last pass)
    /// ended, as seen from `p` (the end nearest `p` of those its cell indices stand for);
    /// `None` if the sonar never looked that way. `cell_m` as in [`Lookout::record`].
    pub fn end(&self, p: Vec2, heading: f32, cell_m: f32) -> Option<Vec2> {
        self.end_in(sector(heading), p, cell_m)
    }

    /// [`Lookout::end`] for sector `k`.
    fn end_in(&self, k: usize, p: Vec2, cell_m: f32) -> Option<Vec2> {
        if self.looked.load(Ordering::Acquire) & bit(k) == 0 || !p.is_finite() {
            return None;
        }
        let word = self.ends.get(k)?.load(Ordering::Relaxed);
        // The end relative to p's cell, in cells: exact while it is within 2¹⁵ cells.
        let (pi, pj) = (cell(p.x, cell_m), cell(p.y, cell_m));
        let di = (word as u16).wrapping_sub(pi as u16) as i16;
        let dj = ((word >> 16) as u16).wrapping_sub(pj as u16) as i16;
        let corner = Vec2::new(pi as f32 * cell_m, pj as f32 * cell_m);
        Some(corner + Vec2::new(f32::from(di) + 0.5, f32::from(dj) + 0.5) * cell_m)
    }

    /// How far ahead of `p`, going along heading `heading`, the beam kept for that bearing saw
    /// clear, m ([`clear_ahead`] of its [`Lookout::end`]); `None` if the sonar never looked
    /// that way.
    pub fn clear_ahead(&self, p: Vec2, heading: f32, beside_m: f32, cell_m: f32) -> Option<f32> {
        self.end(p, heading, cell_m)
            .map(|q| clear_ahead(q, p, heading, beside_m))
    }
}

/// How far ahead of `p` on `heading` a beam that ended at `end` vouches for, m (module notes;
/// negative when it ended behind or far to the side): its end's distance along the track, less
/// how far beyond `beside_m` (the hull) to the side of the track it ran.
pub fn clear_ahead(end: Vec2, p: Vec2, heading: f32, beside_m: f32) -> f32 {
    let (d, u) = (end - p, Vec2::from_angle(heading));
    let aside = libm::fabsf(d.cross(u)) - beside_m;
    d.dot(u) - if aside > 0.0 { aside } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_beam_straight_ahead_vouches_for_its_length() {
        let l = Lookout::new();
        assert_eq!(l.clear_ahead(Vec2::ZERO, 0.0, 0.0, 0.5), None);
        assert!(!l.any());
        l.record(Vec2::ZERO, Vec2::from_angle(0.0), 10.0, 0.5);
        assert!(l.any());
        let c = l.clear_ahead(Vec2::ZERO, 0.0, 0.0, 0.5).unwrap_or(f32::NAN);
        assert!((c - 10.0).abs() < 0.6, "{c}");
        // Three metres on, three metres less.
        let c = l
            .clear_ahead(Vec2::new(3.0, 0.0), 0.0, 0.0, 0.5)
            .unwrap_or(f32::NAN);
        assert!((c - 7.0).abs() < 0.6, "{c}");
        // Another direction was not looked along.
        assert_eq!(l.clear_ahead(Vec2::ZERO, 1.0, 0.0, 0.5), None);
    }

    #[test]
    fn of_one_pass_the_beam_that_saw_farthest_is_kept() {
        let l = Lookout::new();
        // A pass over the sector ahead: a beam down the track hears nothing to 30 m, the next
        // meets a target beside it at 4 m.
        l.record(Vec2::ZERO, Vec2::from_angle(0.05), 30.0, 0.5);
        l.record(Vec2::ZERO, Vec2::from_angle(0.08), 4.0, 0.5);
        let c = l
            .clear_ahead(Vec2::ZERO, 0.0, 0.75, 0.5)
            .unwrap_or(f32::NAN);
        assert!(c > 25.0, "{c}");
        // The next pass, after the head has been round: the newest beam counts again.
        l.record(Vec2::ZERO, Vec2::from_angle(2.0), 30.0, 0.5);
        l.record(Vec2::ZERO, Vec2::from_angle(0.08), 4.0, 0.5);
        let c = l
            .clear_ahead(Vec2::ZERO, 0.0, 0.75, 0.5)
            .unwrap_or(f32::NAN);
        assert!((c - 4.0).abs() < 0.6, "{c}");
    }

    #[test]
    fn a_beam_from_the_side_vouches_for_nothing() {
        let l = Lookout::new();
        // Cast along +y from 6 m to the side of a vehicle heading +y.
        l.record(Vec2::new(6.0, 0.0), Vec2::from_angle(PI / 2.0), 5.0, 0.5);
        let c = l
            .clear_ahead(Vec2::ZERO, PI / 2.0, 0.0, 0.5)
            .unwrap_or(f32::NAN);
        assert!(c < 0.0, "{c}");
        // Within a hull of 6 m of the track, it vouches for its length.
        let c = l
            .clear_ahead(Vec2::ZERO, PI / 2.0, 6.5, 0.5)
            .unwrap_or(f32::NAN);
        assert!((c - 5.0).abs() < 0.6, "{c}");
        // Passed by: its end behind the vehicle.
        l.record(Vec2::ZERO, Vec2::from_angle(PI / 2.0), 5.0, 0.5);
        let c = l
            .clear_ahead(Vec2::new(0.0, 8.0), PI / 2.0, 0.0, 0.5)
            .unwrap_or(f32::NAN);
        assert!(c < -2.0, "{c}");
    }

    #[test]
    fn far_from_the_origin_the_ends_still_hold() {
        let l = Lookout::new();
        // 20 km out: the cell indices wrap, their differences do not.
        let p = Vec2::new(20_000.0, -20_000.0);
        l.record(p, Vec2::from_angle(-PI / 2.0), 12.0, 0.5);
        let c = l.clear_ahead(p, -PI / 2.0, 0.0, 0.5).unwrap_or(f32::NAN);
        assert!((c - 12.0).abs() < 0.6, "{c}");
        l.clear();
        assert_eq!(l.clear_ahead(p, -PI / 2.0, 0.0, 0.5), None);
    }

    #[test]
    fn bad_numbers_are_refused_not_stored() {
        let l = Lookout::new();
        l.record(Vec2::new(f32::NAN, 0.0), Vec2::from_angle(0.0), 10.0, 0.5);
        l.record(Vec2::ZERO, Vec2::from_angle(0.0), f32::INFINITY, 0.5);
        assert_eq!(l.clear_ahead(Vec2::ZERO, 0.0, 0.0, 0.5), None);
        assert_eq!(sector(f32::NAN), sector(f32::NAN));
        assert!(sector(PI) < LOOK_SECTORS && sector(-PI) < LOOK_SECTORS);
    }
}
