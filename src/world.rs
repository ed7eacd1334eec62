//! The planner's model of the theatre of operations: fixed-capacity tables of obstacles and of
//! other vehicles (agents), with ids, ageing and a stated overflow policy.
//!
//! Time is milliseconds since boot (`now_ms`), always passed in: the core reads no clock.
//!
//! **Overflow policy.**
//! - [`World::upsert_obstacle`] updates an entry with the same id, else appends; when the table
//!   is full it hands the obstacle back in [`Full`] and counts it in `rejected_full`.
//! - [`World::upsert_obstacle_or_evict`] (the sonar path) evicts, when full, the *sensed*
//!   obstacle farthest from the vehicle if the newcomer is nearer; charted obstacles (from the
//!   mission) are never evicted. Evictions are counted in `evicted`.
//! - Agents follow the same rules with [`World::upsert_agent`] (no eviction: 8 is a fleet).
//! - [`World::expire`] drops sensed obstacles and agents not seen for a given age.

use heapless::Vec;

use crate::field::{Shape, Stator};
use crate::math::Vec2;

/// Capacity of the obstacle table.
pub const MAX_OBSTACLES: usize = 32;
/// Capacity of the agent (other vehicle) table.
pub const MAX_AGENTS: usize = 8;
/// Fastest an obstacle or agent may be said to move, m/s (beyond any AUV, a unit error).
pub const MAX_OBJECT_SPEED: f32 = 20.0;
/// Most believed evidence-map cells the planner takes per step: one per bearing sector of the
/// map's polar scan ([`World::set_map`], `crate::sonar::EvidenceMap::nearest`).
pub const MAX_MAP_CELLS: usize = 32;

/// Where an obstacle came from, which decides its ageing and eviction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Origin {
    /// From the mission or a chart: kept until removed, never evicted.
    Charted,
    /// From the host's perception (contacts): ages out, may be evicted by a nearer one when
    /// the table is full.
    Sensed,
    /// From this firmware's own sonar feature extraction: as `Sensed`; and while an evidence
    /// map is in use ([`World::set_map`]) a still one is left to the map, which holds the same
    /// echoes without the fitted shape's gaps (a moving one stays: the map cannot predict it).
    Sonar,
}

/// An obstacle: its geometry, its stator PDF and bookkeeping.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Obstacle {
    /// Caller-chosen id; an upsert with the same id replaces the entry.
    pub id: u16,
    /// Geometry.
    pub shape: Shape,
    /// Velocity over ground, m/s (zero for static obstacles).
    pub velocity: Vec2,
    /// Where it came from.
    pub origin: Origin,
    /// When it was last seen or updated, ms.
    pub seen_ms: u64,
    stator: Stator,
}

/// Why an object was refused at the table's boundary.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ObjectError {
    /// A repulsiveness, position or velocity is NaN or infinite.
    NonFinite,
    /// Repulsiveness outside 0.001 ..= 100, or speed above [`MAX_OBJECT_SPEED`].
    OutOfRange,
}

impl core::fmt::Display for ObjectError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ObjectError::NonFinite => "object has a non-finite position, velocity or repulsion",
            ObjectError::OutOfRange => "object repulsion or speed out of range",
        })
    }
}

impl core::error::Error for ObjectError {}

fn check_velocity(v: Vec2) -> Result<Vec2, ObjectError> {
    if !v.is_finite() {
        Err(ObjectError::NonFinite)
    } else if v.norm2() > MAX_OBJECT_SPEED * MAX_OBJECT_SPEED {
        Err(ObjectError::OutOfRange)
    } else {
        Ok(v)
    }
}

impl Obstacle {
    /// A static obstacle with repulsiveness A⁺ = `a_plus` (seed 000 eq. 9, 12).
    pub fn new(
        id: u16,
        shape: Shape,
        a_plus: f32,
        origin: Origin,
        now_ms: u64,
    ) -> Result<Self, ObjectError> {
        if !a_plus.is_finite() {
            return Err(ObjectError::NonFinite);
        }
        if !(0.001..=100.0).contains(&a_plus) {
            return Err(ObjectError::OutOfRange);
        }
        Ok(Obstacle {
            id,
            shape,
            velocity: Vec2::ZERO,
            origin,
            seen_ms: now_ms,
            stator: Stator::new(a_plus),
        })
    }

    /// The same obstacle moving with `velocity` m/s.
    pub fn moving(mut self, velocity: Vec2) -> Result<Self, ObjectError> {
        self.velocity = check_velocity(velocity)?;
        Ok(self)
    }

    /// The same obstacle with repulsiveness `a_plus` (checked as in [`Obstacle::new`]).
    pub fn with_a_plus(self, a_plus: f32) -> Result<Self, ObjectError> {
        let o = Obstacle::new(self.id, self.shape, a_plus, self.origin, self.seen_ms)?;
        Ok(Obstacle {
            velocity: self.velocity,
            ..o
        })
    }

    /// Its stator PDF.
    pub fn stator(&self) -> &Stator {
        &self.stator
    }

    /// Its repulsiveness A⁺.
    pub fn a_plus(&self) -> f32 {
        self.stator.a_plus()
    }

    /// How far a moving obstacle is shifted for planning at `now_ms`, for a vehicle at `p`
    /// moving with `v`: to where it will be at the closest approach, at most `horizon_s` ahead.
    ///
    /// Every strategy plans against the shifted shape (`shape` moved by this amount), so that
    /// a crossing obstacle repels from where the encounter will happen rather than from where
    /// it is now — the "predicted position over a short horizon" choice of issue 5. None of
    /// the seeds models motion in the field itself: 003 §5 re-plans every 1 s on the
    /// obstacles' *current* positions, which is the `horizon_s = 0` case. The time of closest
    /// approach of the two constant-velocity points is t* = −(Δp·Δv)/|Δv|² (Δp the obstacle's
    /// centre relative to the vehicle, Δv its velocity relative to the vehicle's), clamped to
    /// 0 ..= `horizon_s`; the time since the obstacle was seen (also at most the horizon) is
    /// added, so a sighting carried over a few periods is dead-reckoned to now. A static
    /// obstacle is never shifted.
    pub fn predicted_shift(&self, now_ms: u64, p: Vec2, v: Vec2, horizon_s: f32) -> Vec2 {
        if self.velocity == Vec2::ZERO || horizon_s.is_nan() || horizon_s <= 0.0 {
            return Vec2::ZERO;
        }
        let age_s = crate::math::min(now_ms.saturating_sub(self.seen_ms) as f32 * 1e-3, horizon_s);
        let dp = self.shape.center() + self.velocity * age_s - p;
        let dv = self.velocity - v;
        let dv2 = dv.norm2();
        let t = if dv2 > 1e-6 {
            crate::math::max(0.0, crate::math::min(-dp.dot(dv) / dv2, horizon_s))
        } else {
            0.0
        };
        self.velocity * (age_s + t)
    }
}

/// Another vehicle as seen by this one (000 §III: a circle; 001 §3.2: a formation neighbour).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Agent {
    /// Caller-chosen id (e.g. the sonar track); an upsert with the same id replaces the entry.
    pub id: u16,
    /// Position, m.
    pub position: Vec2,
    /// Velocity over ground, m/s.
    pub velocity: Vec2,
    /// When it was last seen, ms.
    pub seen_ms: u64,
}

impl Agent {
    /// A checked agent.
    pub fn new(id: u16, position: Vec2, velocity: Vec2, now_ms: u64) -> Result<Self, ObjectError> {
        if !position.is_finite() {
            return Err(ObjectError::NonFinite);
        }
        Ok(Agent {
            id,
            position,
            velocity: check_velocity(velocity)?,
            seen_ms: now_ms,
        })
    }
}

/// A table was full: the value is handed back.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Full<T>(pub T);

impl<T> core::fmt::Display for Full<T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("table full")
    }
}

impl<T: core::fmt::Debug> core::error::Error for Full<T> {}

/// Counters of the tables' boundary decisions, for telemetry.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WorldCounters {
    /// Objects refused because their table was full.
    pub rejected_full: u32,
    /// Sensed obstacles evicted by a nearer one.
    pub evicted: u32,
    /// Entries removed by [`World::expire`].
    pub expired: u32,
}

/// The obstacle and agent tables, and this period's view of the evidence map.
#[derive(Clone, Debug, Default)]
pub struct World {
    obstacles: Vec<Obstacle, MAX_OBSTACLES>,
    agents: Vec<Agent, MAX_AGENTS>,
    map: MapCells,
    /// Boundary counters.
    pub counters: WorldCounters,
}

/// The believed-occupied evidence-map cells nearest the vehicle (`crate::sonar::evidence`), as
/// discs of radius `radius` about their centres. Refreshed every period by the runtime.
#[derive(Clone, Debug, Default)]
pub struct MapCells {
    centers: Vec<Vec2, MAX_MAP_CELLS>,
    radius: f32,
    in_use: bool,
}

impl World {
    /// Empty tables.
    pub const fn new() -> Self {
        World {
            obstacles: Vec::new(),
            agents: Vec::new(),
            map: MapCells {
                centers: Vec::new(),
                radius: 0.0,
                in_use: false,
            },
            counters: WorldCounters {
                rejected_full: 0,
                evicted: 0,
                expired: 0,
            },
        }
    }

    /// The obstacles.
    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }

    /// The other vehicles.
    pub fn agents(&self) -> &[Agent] {
        &self.agents
    }

    /// Inserts, or replaces the entry with the same id. Full: the obstacle comes back.
    pub fn upsert_obstacle(&mut self, o: Obstacle) -> Result<(), Full<Obstacle>> {
        if let Some(slot) = self.obstacles.iter_mut().find(|x| x.id == o.id) {
            *slot = o;
            return Ok(());
        }
        self.obstacles.push(o).map_err(|o| {
            self.counters.rejected_full = self.counters.rejected_full.saturating_add(1);
            Full(o)
        })
    }

    /// As [`World::upsert_obstacle`], but when full a sensed obstacle farther from `vehicle`
    /// than the newcomer is evicted to make room (returned as `Ok(Some(evicted))`).
    pub fn upsert_obstacle_or_evict(
        &mut self,
        o: Obstacle,
        vehicle: Vec2,
    ) -> Result<Option<Obstacle>, Full<Obstacle>> {
        let o = match self.upsert_obstacle(o) {
            Ok(()) => return Ok(None),
            Err(Full(o)) => o,
        };
        let dist = |x: &Obstacle| x.shape.signed_distance(vehicle);
        let new_d = dist(&o);
        let farthest = self
            .obstacles
            .iter_mut()
            .filter(|x| x.origin != Origin::Charted)
            .max_by(|a, b| dist(a).total_cmp(&dist(b)));
        match farthest {
            Some(slot) if dist(slot) > new_d => {
                let mut old = o;
                // A swap, not `mem::replace`: the latter's copy into an aliased slot links
                // compiler_builtins' 1.5 KB `memmove` into the image.
                core::mem::swap(slot, &mut old);
                // upsert_obstacle counted a rejection that became an eviction.
                self.counters.rejected_full = self.counters.rejected_full.saturating_sub(1);
                self.counters.evicted = self.counters.evicted.saturating_add(1);
                Ok(Some(old))
            }
            _ => Err(Full(o)),
        }
    }

    /// Removes the obstacle with `id`, returning it.
    pub fn remove_obstacle(&mut self, id: u16) -> Option<Obstacle> {
        let i = self.obstacles.iter().position(|x| x.id == id)?;
        swap_remove(&mut self.obstacles, i)
    }

    /// Removes every charted obstacle (sensed ones stay).
    pub fn remove_charted(&mut self) {
        self.obstacles.retain(|o| o.origin != Origin::Charted);
    }

    /// Inserts, or replaces the agent with the same id. Full: the agent comes back.
    pub fn upsert_agent(&mut self, a: Agent) -> Result<(), Full<Agent>> {
        if let Some(slot) = self.agents.iter_mut().find(|x| x.id == a.id) {
            *slot = a;
            return Ok(());
        }
        self.agents.push(a).map_err(|a| {
            self.counters.rejected_full = self.counters.rejected_full.saturating_add(1);
            Full(a)
        })
    }

    /// Removes the agent with `id`.
    pub fn remove_agent(&mut self, id: u16) -> Option<Agent> {
        let i = self.agents.iter().position(|x| x.id == id)?;
        swap_remove(&mut self.agents, i)
    }

    /// Drops sensed obstacles and agents last seen more than `max_age_ms` before `now_ms`.
    pub fn expire(&mut self, now_ms: u64, max_age_ms: u64) {
        let fresh = |seen: u64| now_ms.saturating_sub(seen) <= max_age_ms;
        let before = self.obstacles.len() + self.agents.len();
        self.obstacles
            .retain(|o| o.origin == Origin::Charted || fresh(o.seen_ms));
        self.agents.retain(|a| fresh(a.seen_ms));
        let gone = before - (self.obstacles.len() + self.agents.len());
        self.counters.expired = self.counters.expired.saturating_add(gone as u32);
    }

    /// Removes everything (counters kept).
    pub fn clear(&mut self) {
        self.obstacles.clear();
        self.agents.clear();
    }

    /// Signed distance from `p` to the nearest obstacle surface, agent circle of radius
    /// `agent_radius` or believed map cell, metres (`f32::INFINITY` for an empty world).
    /// Negative means inside.
    pub fn clearance(&self, p: Vec2, agent_radius: f32) -> f32 {
        let obstacles = self
            .obstacles
            .iter()
            .filter(|o| !self.left_to_map(o))
            .map(|o| o.shape.signed_distance(p));
        let agents = self
            .agents
            .iter()
            .map(|a| (p - a.position).norm() - agent_radius);
        obstacles
            .chain(agents)
            .fold(self.map_distance(p), crate::math::min_num)
    }

    /// Replaces this period's map cells: `centers` (the nearest first; those beyond
    /// [`MAX_MAP_CELLS`] are ignored), each a disc of `radius` m. From now on still
    /// [`Origin::Sonar`] obstacles are left to the map ([`World::left_to_map`]).
    pub fn set_map(&mut self, centers: impl Iterator<Item = Vec2>, radius: f32) {
        self.map.centers.clear();
        for c in centers.filter(|c| c.is_finite()) {
            if self.map.centers.push(c).is_err() {
                break;
            }
        }
        self.map.radius = if radius.is_finite() {
            crate::math::max_num(radius, 0.0)
        } else {
            0.0
        };
        self.map.in_use = true;
    }

    /// This period's believed map cells (centres), nearest first.
    pub fn map_cells(&self) -> &[Vec2] {
        &self.map.centers
    }

    /// Radius of a map cell's disc, m.
    pub fn map_radius(&self) -> f32 {
        self.map.radius
    }

    /// Whether an evidence map feeds this world.
    pub fn map_in_use(&self) -> bool {
        self.map.in_use
    }

    /// Signed distance from `x` to the nearest map cell's disc, m (`INFINITY` with none).
    pub fn map_distance(&self, x: Vec2) -> f32 {
        nearest_cell(&self.map.centers, x).map_or(f32::INFINITY, |(_, d)| d - self.map.radius)
    }

    /// Whether obstacle `o` is represented by the map instead of its own PDF: a still
    /// obstacle from the firmware's own sonar while a map is in use (see [`Origin::Sonar`]).
    pub fn left_to_map(&self, o: &Obstacle) -> bool {
        self.map.in_use && o.origin == Origin::Sonar && o.velocity == Vec2::ZERO
    }
}

/// The centre nearest `x` among `centers` and its distance, m.
pub fn nearest_cell(centers: &[Vec2], x: Vec2) -> Option<(Vec2, f32)> {
    let mut best: Option<(Vec2, f32)> = None;
    for &c in centers {
        let d2 = (c - x).norm2();
        if best.is_none_or(|(_, b)| d2 < b) {
            best = Some((c, d2));
        }
    }
    best.map(|(c, d2)| (c, crate::math::sqrt(d2)))
}

/// `Vec::swap_remove` by a swap with the last element and a pop. heapless moves the last
/// element with `ptr::copy`, which links compiler_builtins' 1.5 KB `memmove` into the image.
/// `None` when `i` is out of range.
pub fn swap_remove<T, const N: usize>(v: &mut Vec<T, N>, i: usize) -> Option<T> {
    let last = v.len().checked_sub(1)?;
    let (head, tail) = v.split_at_mut(last);
    if let (Some(a), Some(b)) = (head.get_mut(i), tail.first_mut()) {
        core::mem::swap(a, b);
    } else if i != last {
        return None;
    }
    v.pop()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(id: u16, x: f32, origin: Origin) -> Obstacle {
        let s = Shape::circle(Vec2::new(x, 0.0), 1.0).unwrap();
        Obstacle::new(id, s, 2.5, origin, 0).unwrap()
    }

    #[test]
    fn swap_remove_moves_the_last_into_the_gap_and_refuses_out_of_range() {
        let mut v: Vec<u8, 4> = Vec::from_slice(&[1, 2, 3, 4]).unwrap();
        assert_eq!(swap_remove(&mut v, 1), Some(2));
        assert_eq!(v.as_slice(), &[1, 4, 3]);
        assert_eq!(swap_remove(&mut v, 2), Some(3));
        assert_eq!(v.as_slice(), &[1, 4]);
        assert_eq!(swap_remove(&mut v, 2), None);
        assert_eq!(v.as_slice(), &[1, 4]);
        assert_eq!(swap_remove(&mut v, 0), Some(1));
        assert_eq!(swap_remove(&mut v, 0), Some(4));
        assert_eq!(swap_remove(&mut v, 0), None);
    }

    #[test]
    fn full_table_hands_the_obstacle_back_and_counts() {
        let mut w = World::new();
        for i in 0..MAX_OBSTACLES as u16 {
            w.upsert_obstacle(circle(i, i as f32 * 3.0, Origin::Sensed))
                .unwrap();
        }
        let extra = circle(999, 1.0, Origin::Sensed);
        assert_eq!(w.upsert_obstacle(extra), Err(Full(extra)));
        assert_eq!(w.counters.rejected_full, 1);
        // Same id replaces, even when full.
        w.upsert_obstacle(circle(3, -50.0, Origin::Sensed)).unwrap();
        assert_eq!(w.obstacles().len(), MAX_OBSTACLES);
    }

    #[test]
    fn eviction_replaces_the_farthest_sensed_obstacle_never_a_charted_one() {
        let mut w = World::new();
        w.upsert_obstacle(circle(0, 500.0, Origin::Charted))
            .unwrap();
        for i in 1..MAX_OBSTACLES as u16 {
            w.upsert_obstacle(circle(i, i as f32 * 3.0, Origin::Sensed))
                .unwrap();
        }
        let near = circle(100, 1.5, Origin::Sensed);
        let out = w.upsert_obstacle_or_evict(near, Vec2::ZERO).unwrap();
        assert_eq!(out.map(|o| o.id), Some(MAX_OBSTACLES as u16 - 1));
        assert_eq!(w.counters.evicted, 1);
        assert!(w.obstacles().iter().any(|o| o.id == 0));
        // A newcomer farther than everything sensed is refused.
        let far = circle(101, 400.0, Origin::Sensed);
        assert!(w.upsert_obstacle_or_evict(far, Vec2::ZERO).is_err());
        assert_eq!(w.counters.rejected_full, 1);
    }

    #[test]
    fn expire_drops_stale_sensed_entries_only() {
        let mut w = World::new();
        w.upsert_obstacle(circle(1, 0.0, Origin::Charted)).unwrap();
        w.upsert_obstacle(circle(2, 5.0, Origin::Sensed)).unwrap();
        w.upsert_agent(Agent::new(7, Vec2::ZERO, Vec2::ZERO, 0).unwrap())
            .unwrap();
        w.expire(10_000, 5_000);
        assert_eq!(w.obstacles().len(), 1);
        assert!(w.agents().is_empty());
        assert_eq!(w.counters.expired, 2);
    }

    #[test]
    fn a_crossing_obstacle_is_planned_at_the_closest_approach() {
        let shape = Shape::circle(Vec2::new(10.0, -10.0), 1.0).unwrap();
        let o = Obstacle::new(1, shape, 1.0, Origin::Sensed, 0)
            .unwrap()
            .moving(Vec2::new(0.0, 1.0))
            .unwrap();
        // Vehicle at the origin going +x at 1 m/s: they meet at (10, 0) after 10 s.
        let v = Vec2::new(1.0, 0.0);
        let s = o.predicted_shift(0, Vec2::ZERO, v, 30.0);
        assert!((s - Vec2::new(0.0, 10.0)).norm() < 1e-4, "{s:?}");
        // The horizon caps the look-ahead; a sighting 2 s old is carried forward.
        let s = o.predicted_shift(0, Vec2::ZERO, v, 4.0);
        assert!((s - Vec2::new(0.0, 4.0)).norm() < 1e-4, "{s:?}");
        let s = o.predicted_shift(2000, Vec2::ZERO, v, 4.0);
        assert!((s - Vec2::new(0.0, 6.0)).norm() < 1e-3, "{s:?}");
        // Receding: no look-ahead beyond now. Static, or horizon 0: no shift.
        let s = o.predicted_shift(0, Vec2::new(0.0, -20.0), Vec2::ZERO, 30.0);
        assert_eq!(s, Vec2::ZERO);
        assert_eq!(o.predicted_shift(0, Vec2::ZERO, v, 0.0), Vec2::ZERO);
        let still = Obstacle::new(2, shape, 1.0, Origin::Sensed, 0).unwrap();
        assert_eq!(still.predicted_shift(0, Vec2::ZERO, v, 30.0), Vec2::ZERO);
    }

    #[test]
    fn bad_objects_are_refused() {
        let s = Shape::circle(Vec2::ZERO, 1.0).unwrap();
        assert_eq!(
            Obstacle::new(1, s, f32::NAN, Origin::Charted, 0),
            Err(ObjectError::NonFinite)
        );
        assert_eq!(
            Obstacle::new(1, s, 0.0, Origin::Charted, 0),
            Err(ObjectError::OutOfRange)
        );
        assert_eq!(
            Agent::new(1, Vec2::ZERO, Vec2::new(100.0, 0.0), 0),
            Err(ObjectError::OutOfRange)
        );
    }
}
