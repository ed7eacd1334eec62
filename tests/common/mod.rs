//! The kinematic vehicle of seed 000 eq. 8 and small helpers the experiment tests share.
//!
//! The vehicle follows the planned velocity exactly, integrated bilinearly:
//! p(k+1) = p(k) + T/2·(v(k) + v(k−1)). (The paper writes p(k−1) on the right, a slip: with it
//! the position would skip every other step.) Navigation reports the position, the velocity and
//! the course as heading.
#![allow(dead_code)]

pub mod lattice;

use vpf::field::Shape;
use vpf::planner::{Command, Formation};
use vpf::{Mission, NavState, Obstacle, Origin, Params, Planner, Vec2, World};

/// One simulated vehicle: its planner, its view of the world, and its kinematic state.
pub struct Vehicle {
    pub planner: Planner,
    pub world: World,
    pub p: Vec2,
    pub v: Vec2,
    pub heading: f32,
    pub last: Option<Command>,
    /// Play the route layer in open water: tell the planner each period that its goal is in
    /// plain sight (`Planner::set_route`), as the runtime does. Off: the papers' planner.
    pub route_clear: bool,
}

impl Vehicle {
    pub fn new(params: Params, start: Vec2, heading: f32, goal: Vec2) -> Self {
        let mut planner = Planner::new(params).expect("valid params");
        planner
            .set_mission(Mission {
                goal,
                formation: None,
            })
            .expect("valid mission");
        Vehicle {
            planner,
            world: World::new(),
            p: start,
            v: Vec2::ZERO,
            heading,
            last: None,
            route_clear: false,
        }
    }

    pub fn with_formation(mut self, f: Formation) -> Self {
        let goal = self.planner.mission().expect("mission").goal;
        self.planner
            .set_mission(Mission {
                goal,
                formation: Some(f),
            })
            .expect("valid formation");
        self
    }

    pub fn nav(&self) -> NavState {
        NavState {
            position: self.p,
            heading: self.heading,
            velocity: self.v,
        }
    }

    /// One period: plan, then move (000 eq. 8).
    pub fn step(&mut self, now_ms: u64) -> Command {
        if self.route_clear {
            let goal = self.planner.mission().map(|m| m.goal);
            self.planner.set_route(goal);
        }
        let cmd = self
            .planner
            .step(now_ms, &self.nav(), &self.world)
            .expect("step succeeds");
        let t = self.planner.params().period_s;
        self.p += (cmd.velocity + self.v) * (0.5 * t);
        self.v = cmd.velocity;
        if cmd.v_set > 1e-3 {
            self.heading = cmd.psi_set;
        }
        self.last = Some(cmd);
        cmd
    }

    pub fn goal(&self) -> Vec2 {
        self.planner.mission().expect("mission").goal
    }
}

/// What a single-vehicle run measured.
#[derive(Debug, Default)]
pub struct Trace {
    pub positions: Vec<Vec2>,
    pub speeds: Vec<f32>,
    pub min_clearance: f32,
    pub max_ghost_depth: u8,
}

impl Trace {
    pub fn final_position(&self) -> Vec2 {
        *self.positions.last().expect("ran at least one step")
    }
    pub fn path_length(&self) -> f32 {
        self.positions
            .windows(2)
            .map(|w| (w[1] - w[0]).norm())
            .sum()
    }
}

/// Runs one vehicle for `seconds`, recording the trace; clearance is measured against the
/// vehicle's own world (obstacles are charted, so it is the true geometry).
pub fn run(v: &mut Vehicle, seconds: f32) -> Trace {
    let t = v.planner.params().period_s;
    let steps = (seconds / t) as u64;
    let mut trace = Trace {
        min_clearance: f32::INFINITY,
        ..Trace::default()
    };
    for k in 0..steps {
        let now = (k as f32 * t * 1000.0) as u64;
        let cmd = v.step(now);
        trace.positions.push(v.p);
        trace.speeds.push(cmd.v_set);
        trace.min_clearance = trace.min_clearance.min(v.world.clearance(v.p, 0.0));
        trace.max_ghost_depth = trace.max_ghost_depth.max(cmd.ghost_depth);
    }
    trace
}

pub fn circle(id: u16, x: f32, y: f32, r: f32) -> Obstacle {
    Obstacle::new(
        id,
        Shape::circle(Vec2::new(x, y), r).expect("valid circle"),
        2.5,
        Origin::Charted,
        0,
    )
    .expect("valid obstacle")
}

pub fn rect(id: u16, x: f32, y: f32, hx: f32, hy: f32, angle: f32) -> Obstacle {
    Obstacle::new(
        id,
        Shape::rectangle(Vec2::new(x, y), Vec2::new(hx, hy), angle).expect("valid rectangle"),
        2.5,
        Origin::Charted,
        0,
    )
    .expect("valid obstacle")
}

pub fn world_of(obstacles: &[Obstacle]) -> World {
    let mut w = World::new();
    for o in obstacles {
        w.upsert_obstacle(*o).expect("room in the table");
    }
    w
}

/// Several vehicles; each sees the others as agents (000 Fig. 7, 001 §3.2) and the shared
/// obstacles. Returns per-step positions of all vehicles.
pub fn run_fleet(fleet: &mut [Vehicle], obstacles: &[Obstacle], seconds: f32) -> Vec<Vec<Vec2>> {
    let t = fleet[0].planner.params().period_s;
    let steps = (seconds / t) as u64;
    let mut history = Vec::new();
    for k in 0..steps {
        let now = (k as f32 * t * 1000.0) as u64;
        let snapshot: Vec<(Vec2, Vec2)> = fleet.iter().map(|v| (v.p, v.v)).collect();
        for (i, veh) in fleet.iter_mut().enumerate() {
            let mut w = world_of(obstacles);
            for (j, &(p, vel)) in snapshot.iter().enumerate() {
                if j != i {
                    w.upsert_agent(vpf::Agent::new(j as u16, p, vel, now).expect("valid agent"))
                        .expect("room for agents");
                }
            }
            veh.world = w;
            veh.step(now);
        }
        history.push(fleet.iter().map(|v| v.p).collect());
    }
    history
}

/// Smallest distance between any two vehicles in one snapshot.
pub fn min_pair_distance(ps: &[Vec2]) -> f32 {
    let mut m = f32::INFINITY;
    for i in 0..ps.len() {
        for j in i + 1..ps.len() {
            m = m.min((ps[i] - ps[j]).norm());
        }
    }
    m
}

/// Each vehicle's distance to its nearest neighbour.
pub fn nearest_neighbour(ps: &[Vec2]) -> Vec<f32> {
    (0..ps.len())
        .map(|i| {
            (0..ps.len())
                .filter(|&j| j != i)
                .map(|j| (ps[i] - ps[j]).norm())
                .fold(f32::INFINITY, f32::min)
        })
        .collect()
}
