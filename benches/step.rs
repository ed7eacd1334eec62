//! Cost of one planner step versus the number of objects (criterion, host).
//!
//! `cargo bench --bench step` — obstacles 1, 8, 16, 32 (a mix of circles, rectangles, ellipses
//! and hexagons), then full capacity: 32 obstacles + 8 agents in formation, n_γ = 16. Ghost
//! goal-points add no cost per sample (only the top one attracts), so they are not varied.
//! Then each strategy at full tables (32 obstacles, half of them moving, + 8 agents): the
//! multipoint strategy chooses a new arc point only every r/u (10 periods at 1 m/s), so its
//! mean is far below its worst period (the self-test on QEMU reports both).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use std::hint::black_box;
use vpf::field::Shape;
use vpf::planner::Formation;
use vpf::world::{MAX_AGENTS, MAX_OBSTACLES};
use vpf::{Agent, Mission, NavState, Obstacle, Origin, Params, Planner, Strategy, Vec2, World};

fn obstacle(i: usize) -> Obstacle {
    let c = Vec2::new(10.0 + 7.0 * (i % 8) as f32, -20.0 + 9.0 * (i / 8) as f32);
    let shape = match i % 4 {
        0 => Shape::circle(c, 1.5),
        1 => Shape::rectangle(c, Vec2::new(2.0, 1.0), 0.3),
        2 => Shape::ellipse(c, Vec2::new(2.0, 1.0), -0.4),
        _ => {
            let hex: Vec<Vec2> = (0..6)
                .map(|k| c + Vec2::from_angle(k as f32 * 1.047) * 1.5)
                .collect();
            Shape::polygon(&hex)
        }
    }
    .unwrap();
    Obstacle::new(i as u16, shape, 2.5, Origin::Sensed, 0).unwrap()
}

fn world(obstacles: usize, agents: usize) -> World {
    let mut w = World::new();
    for i in 0..obstacles {
        w.upsert_obstacle(obstacle(i)).unwrap();
    }
    for i in 0..agents {
        let p = Vec2::new(-5.0 - 3.0 * i as f32, 4.0);
        w.upsert_agent(Agent::new(i as u16, p, Vec2::ZERO, 0).unwrap())
            .unwrap();
    }
    w
}

fn planner(formation: bool, strategy: Strategy) -> Planner {
    let mut p = Planner::new(Params {
        strategy,
        ..Params::default()
    })
    .unwrap();
    p.set_mission(Mission {
        goal: Vec2::new(80.0, 0.0),
        formation: formation.then_some(Formation {
            q: 4,
            lattice_m: 3.0,
            orientation: 0.0,
            attraction: 5.0,
        }),
    })
    .unwrap();
    p
}

fn bench_step(c: &mut Criterion) {
    let nav = NavState {
        position: Vec2::new(0.0, 0.0),
        heading: 0.0,
        velocity: Vec2::new(0.8, 0.1),
    };
    let mut group = c.benchmark_group("planner_step");
    let cases = [
        (1, 0),
        (8, 0),
        (16, 0),
        (MAX_OBSTACLES, 0),
        (MAX_OBSTACLES, MAX_AGENTS),
    ];
    for (n_obs, n_agents) in cases {
        let w = world(n_obs, n_agents);
        let mut p = planner(n_agents > 0, Strategy::Vpf);
        let id = format!("{n_obs}obs_{n_agents}agents");
        group.bench_with_input(BenchmarkId::from_parameter(id), &w, |b, w| {
            let mut t = 0u64;
            b.iter(|| {
                t += 100;
                black_box(p.step(t, black_box(&nav), w).unwrap())
            })
        });
    }
    group.finish();

    let mut group = c.benchmark_group("strategy_full_tables");
    let mut w = World::new();
    for i in 0..MAX_OBSTACLES {
        let v = Vec2::new(0.0, if i % 2 == 0 { 0.5 } else { 0.0 });
        w.upsert_obstacle(obstacle(i).moving(v).unwrap()).unwrap();
    }
    for a in world(0, MAX_AGENTS).agents() {
        w.upsert_agent(*a).unwrap();
    }
    for s in [Strategy::Vpf, Strategy::Multipoint, Strategy::Navfn] {
        let mut p = planner(false, s);
        group.bench_with_input(BenchmarkId::from_parameter(s.name()), &w, |b, w| {
            let mut t = 0u64;
            b.iter(|| {
                t += 100;
                black_box(p.step(t, black_box(&nav), w).unwrap())
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_step);
criterion_main!(benches);
