//! Sonar features into the obstacle table: association by position, ids, and the table's
//! eviction policy.
//!
//! The extractor (`crate::sonar`) emits a feature per sweep per obstacle, without identity. A
//! feature whose centre lies within the association gate of a sensed obstacle already in the
//! table updates that obstacle (new shape, refreshed `seen_ms`); otherwise it becomes a new
//! sensed obstacle with a fresh id from [`SONAR_ID_BASE`] upwards. Features below the confidence
//! floor are dropped (a single sweep cannot tell three beams of speckle from a small target; see
//! the sonar module). When the table is full, the sensed obstacle farthest from the vehicle is
//! evicted if the newcomer is nearer ([`World::upsert_obstacle_or_evict`]); otherwise the
//! newcomer is dropped. Stale sensed obstacles age out in the periodic task.

use crate::math::Vec2;
use crate::sonar::Feature;
use crate::world::{Obstacle, Origin, World};

/// First id given to sonar-derived obstacles; ids from the host (charts, contacts) should stay
/// below it.
pub const SONAR_ID_BASE: u16 = 0xC000;

/// Association settings.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TrackConfig {
    /// Features below this confidence are dropped. 0 ..= 1.
    pub min_confidence: f32,
    /// Extra distance beyond the larger of the two radii within which a feature is the same
    /// obstacle, m.
    pub gate_m: f32,
    /// Repulsiveness A⁺ given to sonar obstacles.
    pub a_plus: f32,
}

impl Default for TrackConfig {
    fn default() -> Self {
        TrackConfig {
            min_confidence: 0.5,
            gate_m: 1.0,
            a_plus: 2.5,
        }
    }
}

/// What became of one feature.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Admission {
    /// Updated the obstacle with this id.
    Updated(u16),
    /// Added as a new obstacle with this id.
    Added(u16),
    /// Dropped: confidence below the floor.
    LowConfidence,
    /// Dropped: its shape or repulsion was refused.
    Invalid,
    /// Dropped: the table is full of nearer obstacles.
    TableFull,
}

/// Id allocation for sonar obstacles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tracks {
    next_id: u16,
}

impl Default for Tracks {
    fn default() -> Self {
        Tracks {
            next_id: SONAR_ID_BASE,
        }
    }
}

impl Tracks {
    /// Puts `f` into `world`, seen from the vehicle at `vehicle`.
    pub fn admit(
        &mut self,
        cfg: &TrackConfig,
        world: &mut World,
        f: &Feature,
        vehicle: Vec2,
    ) -> Admission {
        // NaN confidence fails the comparison and is dropped too.
        let confident = f.confidence >= cfg.min_confidence;
        if !confident {
            return Admission::LowConfidence;
        }
        let Ok(shape) = f.to_shape() else {
            return Admission::Invalid;
        };
        let same = world.obstacles().iter().find(|o| {
            o.origin == Origin::Sensed
                && o.id >= SONAR_ID_BASE
                && (o.shape.center() - f.center).norm()
                    <= o.shape.bounding_radius().max(f.radius) + cfg.gate_m
        });
        let (id, fresh) = match same {
            Some(o) => (o.id, false),
            None => (self.next_id, true),
        };
        let Ok(o) = Obstacle::new(id, shape, cfg.a_plus, Origin::Sensed, f.time_ms) else {
            return Admission::Invalid;
        };
        match world.upsert_obstacle_or_evict(o, vehicle) {
            Ok(_) if fresh => {
                self.next_id = self.next_id.checked_add(1).unwrap_or(SONAR_ID_BASE);
                Admission::Added(id)
            }
            Ok(_) => Admission::Updated(id),
            Err(_) => Admission::TableFull,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sonar::FeatureKind;

    fn feature(x: f32, y: f32, r: f32, confidence: f32) -> Feature {
        Feature {
            center: Vec2::new(x, y),
            radius: r,
            kind: FeatureKind::Circle { radius: r },
            confidence,
            time_ms: 1000,
            beams: 6,
        }
    }

    #[test]
    fn same_place_updates_new_place_adds() {
        let cfg = TrackConfig::default();
        let mut w = World::new();
        let mut t = Tracks::default();
        let a = t.admit(&cfg, &mut w, &feature(10.0, 0.0, 1.0, 0.9), Vec2::ZERO);
        assert_eq!(a, Admission::Added(SONAR_ID_BASE));
        let b = t.admit(&cfg, &mut w, &feature(10.4, 0.3, 1.1, 0.9), Vec2::ZERO);
        assert_eq!(b, Admission::Updated(SONAR_ID_BASE));
        let c = t.admit(&cfg, &mut w, &feature(20.0, 0.0, 1.0, 0.9), Vec2::ZERO);
        assert_eq!(c, Admission::Added(SONAR_ID_BASE + 1));
        assert_eq!(w.obstacles().len(), 2);
    }

    #[test]
    fn weak_or_broken_features_are_dropped() {
        let cfg = TrackConfig::default();
        let mut w = World::new();
        let mut t = Tracks::default();
        let weak = feature(10.0, 0.0, 1.0, 0.3);
        assert_eq!(
            t.admit(&cfg, &mut w, &weak, Vec2::ZERO),
            Admission::LowConfidence
        );
        let nan = feature(10.0, 0.0, 1.0, f32::NAN);
        assert_eq!(
            t.admit(&cfg, &mut w, &nan, Vec2::ZERO),
            Admission::LowConfidence
        );
        let broken = feature(f32::INFINITY, 0.0, 1.0, 0.9);
        assert_eq!(
            t.admit(&cfg, &mut w, &broken, Vec2::ZERO),
            Admission::Invalid
        );
        assert!(w.obstacles().is_empty());
    }
}
