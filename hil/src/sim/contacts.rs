//! Pre-extracted contacts: the firmware's [`Contact`]s for scenarios that bypass the sonar
//! (`sensing = "contacts"`, perfect perception) — every obstacle and vehicle within range,
//! with its true geometry.

use crate::types::{SimObstacle, VehicleState, P2};
use vpf::link::{Contact, ContactKind};

/// Another vehicle, as [`contacts`] reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OtherVehicle {
    /// Its contact id (the firmware's agent table is keyed by it).
    pub id: u16,
    /// Position, m.
    pub position: P2,
    /// Velocity over ground, m/s.
    pub velocity: P2,
    /// Hull radius, m.
    pub hull_radius: f64,
}

/// The firmware's largest object speed, m/s (faster contacts are refused on the wire).
const MAX_OBJECT_SPEED: f64 = 20.0;

/// A velocity the wire accepts: finite, at most [`MAX_OBJECT_SPEED`].
fn wire_velocity(v: P2) -> vpf::Vec2 {
    if !(v.x.is_finite() && v.y.is_finite()) {
        return vpf::Vec2::ZERO;
    }
    let n = v.norm();
    let v = if n > MAX_OBJECT_SPEED {
        v.scale(MAX_OBJECT_SPEED / n)
    } else {
        v
    };
    v.to_vpf()
}

/// Pre-extracted contacts at time `t` s: every obstacle whose surface, and every other vehicle
/// whose hull, is within `range` m of `vehicle`'s position, nearest first, with confidence 1.
///
/// Obstacle `i` of `obstacles` has id `i` (obstacles beyond index 65 535 are left out) and its
/// true shape at `t` ([`SimObstacle::to_vpf`]); obstacles the firmware's shape type refuses
/// (e.g. a non-convex or 9-vertex polygon) are left out. Vehicles are circles of their hull
/// radius (at least 1 cm) with their own ids. Velocities are clamped to 20 m/s, the wire's
/// limit. A NaN `range` gives nothing; an infinite one, everything.
pub fn contacts(
    t: f64,
    vehicle: &VehicleState,
    obstacles: &[SimObstacle],
    others: &[OtherVehicle],
    range: f64,
) -> Vec<Contact> {
    let p = vehicle.position;
    // False for NaN distances or range: those are never "within".
    let within = |d: f64| d.partial_cmp(&range).is_some_and(|o| o.is_le());
    let mut found: Vec<(f64, Contact)> = Vec::new();
    for (i, o) in obstacles.iter().enumerate() {
        let Ok(id) = u16::try_from(i) else { break };
        let d = o.signed_distance(t, p);
        if !within(d) {
            continue;
        }
        if let Ok(shape) = o.to_vpf(t) {
            found.push((
                d,
                Contact {
                    id,
                    kind: ContactKind::Obstacle,
                    shape,
                    velocity: wire_velocity(o.effective_velocity()),
                    confidence: 1.0,
                },
            ));
        }
    }
    for v in others {
        let r = if v.hull_radius.is_finite() {
            v.hull_radius.abs().max(0.01)
        } else {
            0.01
        };
        let d = v.position.sub(p).norm() - r;
        if !within(d) {
            continue;
        }
        if let Ok(shape) = vpf::field::Shape::circle(v.position.to_vpf(), r as f32) {
            found.push((
                d,
                Contact {
                    id: v.id,
                    kind: ContactKind::Vehicle,
                    shape,
                    velocity: wire_velocity(v.velocity),
                    confidence: 1.0,
                },
            ));
        }
    }
    found.sort_by(|a, b| a.0.total_cmp(&b.0));
    found.into_iter().map(|(_, c)| c).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::SimShape;
    use vpf::link::Payload;

    fn still(x: f64, y: f64, heading: f64) -> VehicleState {
        VehicleState {
            position: P2::new(x, y),
            heading,
            ..VehicleState::default()
        }
    }

    fn circle(x: f64, y: f64, r: f64) -> SimObstacle {
        SimObstacle::fixed(SimShape::Circle {
            center: P2::new(x, y),
            radius: r,
        })
    }

    #[test]
    fn contacts_within_range_nearest_first() {
        let v = still(0.0, 0.0, 0.0);
        let obs = [
            circle(30.0, 0.0, 1.0), // surface at 29 m
            circle(10.0, 0.0, 1.0), // 9 m
            SimObstacle {
                velocity: P2::new(0.0, 100.0), // clamped to 20 m/s
                ..circle(0.0, -5.0, 1.0)       // 4 m at t = 0
            },
            SimObstacle::fixed(SimShape::Polygon {
                // Non-convex: the firmware cannot take it.
                points: vec![
                    P2::new(1.0, 1.0),
                    P2::new(3.0, 1.0),
                    P2::new(2.0, 1.5),
                    P2::new(3.0, 2.0),
                    P2::new(1.0, 2.0),
                ],
            }),
        ];
        let others = [OtherVehicle {
            id: 0x8001,
            position: P2::new(0.0, 7.0),
            velocity: P2::new(0.5, 0.0),
            hull_radius: 0.5,
        }];
        let c = contacts(0.0, &v, &obs, &others, 20.0);
        let ids: Vec<u16> = c.iter().map(|c| c.id).collect();
        assert_eq!(ids, vec![2, 0x8001, 1]);
        assert_eq!(c[1].kind, ContactKind::Vehicle);
        assert_eq!(c[0].kind, ContactKind::Obstacle);
        assert!((c[0].velocity.norm() - 20.0).abs() < 1e-3);
        assert_eq!(
            c[2].shape,
            vpf::field::Shape::circle(vpf::Vec2::new(10.0, 0.0), 1.0).unwrap()
        );
        assert_eq!(c[1].velocity, vpf::Vec2::new(0.5, 0.0));
        // Later the moving one is out of range; a wider range takes the far circle.
        let c = contacts(2.0, &v, &obs, &others, 30.0);
        let ids: Vec<u16> = c.iter().map(|c| c.id).collect();
        assert_eq!(ids, vec![0x8001, 1, 0]);
        assert!(contacts(0.0, &v, &obs, &others, f64::NAN).is_empty());
        assert_eq!(contacts(0.0, &v, &obs, &others, f64::INFINITY).len(), 4);
        // Every contact goes on the wire.
        let c = contacts(0.0, &v, &obs, &others, f64::INFINITY);
        let repr = vpf::link::ContactsRepr {
            time_ms: 0,
            contacts: vpf::link::ContactList::new(&c),
        };
        let mut buf = [0u8; 1024];
        assert!(repr.emit(&mut buf).is_ok());
    }
}
