//! The firmware's sonar path end to end on simulated pings: the scanning sonar sees a crossing
//! target and a rock; the extractor turns scanlines into features; the tracker associates them
//! across sweeps and estimates each one's velocity (`vpf::guidance::tracks`). Run with
//! `--nocapture` for the numbers.

use hil::sim::sonar::{Sonar, SonarConfig};
use hil::types::{SimObstacle, SimShape, VehicleState, P2};
use vpf::guidance::tracks::{TrackConfig, Tracks};
use vpf::sonar::{Extractor, ExtractorConfig, Pose};
use vpf::{Vec2, World};

#[test]
fn sonar_features_of_a_crossing_target_are_tracked_with_its_velocity() {
    // Crossing at 0.8 m/s from 28 m to starboard to 28 m to port, inside the 30 m range for the
    // whole 70 s: 8 sweeps.
    let target_v = P2::new(0.0, 0.8);
    let obstacles = [
        SimObstacle {
            shape: SimShape::Circle {
                center: P2::new(8.0, -28.0),
                radius: 1.5,
            },
            velocity: target_v,
        },
        SimObstacle {
            shape: SimShape::Circle {
                center: P2::new(-12.0, 6.0),
                radius: 2.0,
            },
            velocity: P2::default(),
        },
    ];
    // A vehicle holding station at the origin, heading +x.
    let vehicle = VehicleState::default();
    let sonar_cfg = SonarConfig::default();
    let mut sonar = Sonar::new(sonar_cfg);
    let mut extractor = Extractor::new(ExtractorConfig::default()).unwrap();
    let mut world = World::new();
    let mut tracks = Tracks::default();
    let cfg = TrackConfig::default();
    let pose = Pose {
        position: Vec2::ZERO,
        heading: 0.0,
    };
    let mut features = 0;
    let dt = 0.1;
    let duration_s = 70.0;
    for k in 0..(duration_s / dt) as usize {
        let t = k as f64 * dt;
        for ping in sonar.poll(t, &vehicle, &obstacles, &[]) {
            let mut found = Vec::new();
            let _ = extractor.push_scanline(&ping.as_scanline(), pose, &mut |f| {
                found.push(f);
                true
            });
            for f in found {
                features += 1;
                tracks.admit(&cfg, 2.5, &mut world, &f, Vec2::ZERO);
            }
        }
    }
    let sweep_s = sonar_cfg.sweep_time_s();
    println!(
        "{features} features in {duration_s} s (sweep {sweep_s:.1} s), {} obstacles",
        world.obstacles().len()
    );
    for o in world.obstacles() {
        println!(
            "  id {:#06x} at {:?}, velocity {:?}, seen {} ms",
            o.id,
            o.shape.center(),
            o.velocity,
            o.seen_ms
        );
    }
    // The crossing target: one obstacle, near its true position when last seen, moving at
    // about its true velocity.
    let mover = world
        .obstacles()
        .iter()
        .find(|o| o.shape.center().x > 5.0)
        .expect("the target is in the table");
    let truth = Vec2::new(8.0, -28.0 + 0.8 * mover.seen_ms as f32 / 1000.0);
    assert!(
        (mover.shape.center() - truth).norm() < 1.5,
        "{mover:?} vs {truth:?}"
    );
    let v = mover.velocity;
    assert!(
        (v - Vec2::new(0.0, 0.8)).norm() < 0.15,
        "estimated velocity {v:?}, true (0, 0.8)"
    );
    // The rock: kept, not moving.
    let rock = world
        .obstacles()
        .iter()
        .find(|o| o.shape.center().x < 0.0)
        .expect("the rock is in the table");
    assert_eq!(rock.velocity, Vec2::ZERO);
    // Each target is one track: no trail of stale copies behind the mover.
    assert_eq!(world.obstacles().len(), 2, "{:?}", world.obstacles());
}
