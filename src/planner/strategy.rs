//! The alternative strategies in the planner loop: each turns the world into a force F, and
//! [`Planner::integrate`] bounds and integrates it exactly as for the VPF, so every strategy
//! respects F_max and v_max and emits the same [`Command`].
//!
//! Both see moving obstacles at their predicted positions ([`Context::predicted_shapes`]) and
//! other vehicles as circles of radius `agent_radius_m`. Neither uses ghost goal-points: those
//! are the VPF's escape (seed 000 §III); seed 003 leaves local minima to future work, and a
//! navigation function has none in a valid sphere world. Nor do they keep formation: a
//! mission's formation (001 §3.2) is the VPF's virtual leader; the alternatives fly to the
//! mission goal and give other vehicles a wide berth.

use super::multipoint::{self, ArcConfig, Selection};
use super::navfn::{self, NavfnError, SphereWorld};
use super::{Context, Motion, Planner};
use crate::field::Shape;
use crate::math::{max, min, sqrt, Vec2};
use crate::params::Params;
use crate::planner::Command;
use crate::world::Obstacle;

/// Gain of the alternative strategies' velocity tracking, × 1/T. With the bilinear integrator,
/// F = g·(v_d − v_c) has real poles (no overshoot) for g·T/2 ≤ 3 − 2√2 ≈ 0.17; 0.3/T (g·T/2 =
/// 0.15) is the fastest round value inside that.
const TRACK_GAIN: f32 = 0.3;

/// Once arrived, the alternative strategies hold zero speed until the vehicle is this many
/// arrival radii from the goal: a vehicle that cannot brake or turn on the spot (the flat-fish
/// coasts for metres) would otherwise circle the goal, re-approaching each time it drifts out.
/// Within as many radii of a routed goal the VPF's field is the goal-point's alone (the final
/// approach and hold, `crate::planner::vpf`).
pub(super) const ARRIVAL_RELEASE: f32 = 4.0;

/// Whether a vehicle `d` m from a goal of arrival radius `radius` is arrived, given whether it
/// was ([`ARRIVAL_RELEASE`]): within the radius, or within the release since it was.
pub(super) fn still_arrived(was: bool, d: f32, radius: f32) -> bool {
    d <= if was {
        ARRIVAL_RELEASE * radius
    } else {
        radius
    }
}

/// Cosine between two successive navigation-function descent directions below which the
/// descent counts as reversed, i.e. the vehicle crossed a critical point (a saddle) along its
/// stable manifold (`plan_navfn`): about 154°. The descent field is smooth away from critical
/// points, turning by a few degrees per period; only crossing one flips it.
const SADDLE_REVERSAL: f32 = -0.9;

/// The multipoint strategy's state between periods: the arc point being steered to and the
/// periods until the next choice (seed 003 §4: "the next one-step position").
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct ArcState {
    target: Option<Vec2>,
    periods_left: u32,
}

fn arc_config(p: &Params) -> ArcConfig {
    ArcConfig::of(p)
}

impl Context<'_> {
    /// The obstacles planned against (those left to the evidence map excepted) with their
    /// shifts to the predicted positions.
    fn planned_obstacles(&self) -> impl Iterator<Item = (&Obstacle, Vec2)> + Clone + '_ {
        let shift = |i: usize| self.shifts.get(i).copied().unwrap_or(Vec2::ZERO);
        self.world
            .obstacles()
            .iter()
            .enumerate()
            .filter(|(_, o)| !self.world.left_to_map(o))
            .map(move |(i, o)| (o, shift(i)))
    }

    /// The bounding circles (centre, radius) of [`Context::obstacle_shapes`], in its order,
    /// without building the shapes.
    fn obstacle_bounds(&self, agent_radius: f32) -> impl Iterator<Item = (Vec2, f32)> + Clone + '_ {
        let agents = self
            .world
            .agents()
            .iter()
            .map(move |a| (a.position, agent_radius));
        self.planned_obstacles()
            .map(|(o, shift)| (o.shape.center() + shift, o.shape.bounding_radius()))
            .chain(agents)
    }

    /// Obstacles at their predicted positions, then the other vehicles' circles: those
    /// `selection` holds (multipoint's region of interest).
    fn obstacle_shapes(
        &self,
        agent_radius: f32,
        selection: Selection,
    ) -> impl Iterator<Item = Shape> + '_ {
        let agents = self
            .world
            .agents()
            .iter()
            .map(move |a| (a.position, agent_radius));
        let obstacles = self.planned_obstacles().map(Placed::Obstacle);
        obstacles
            .chain(agents.map(Placed::Circle))
            .enumerate()
            .filter(move |&(i, _)| selection.obstacle(i))
            .filter_map(|(_, p)| match p {
                Placed::Obstacle((o, shift)) => Some(o.shape.translated(shift)),
                Placed::Circle((c, r)) => Shape::circle(c, r).ok(),
            })
    }
}

/// A source of [`Context::obstacle_shapes`] before its shape is built.
enum Placed<'a> {
    Obstacle((&'a Obstacle, Vec2)),
    Circle((Vec2, f32)),
}

impl Planner {
    /// Multipoint potential field (seed 003 §3–4). Every `replan_periods` (the time to cover
    /// the arc at the commanded speed, as the paper scales its interval with speed) the
    /// minimum-potential arc point is chosen (eq. 4–8); in between the vehicle is steered at
    /// it. Within one arc radius of the goal it steers at the goal itself (the last path
    /// element ends there).
    #[inline(never)]
    pub(super) fn plan_multipoint(&self, m: &mut Motion, cx: &Context<'_>) -> Command {
        let prm = &self.params;
        let p = cx.nav.position;
        let goal = cx.aim;
        let speed = self.cruise_speed(m, cx);
        let arc = &mut m.arc;
        let reached = arc
            .target
            .is_none_or(|t| (t - p).norm() < 0.25 * prm.mp_arc_m);
        if (goal - p).norm() <= prm.mp_arc_m {
            *arc = ArcState {
                target: Some(goal),
                periods_left: 0,
            };
        } else if arc.periods_left == 0 || reached {
            let cfg = arc_config(prm);
            let cells = cx.world.map_cells().iter().copied();
            let selection = multipoint::region_of_interest(
                &cfg,
                p,
                cx.obstacle_bounds(prm.agent_radius_m),
                cells.clone(),
            );
            let choice = multipoint::choose(
                &cfg,
                p,
                cx.nav.heading,
                speed,
                goal,
                cx.obstacle_shapes(prm.agent_radius_m, selection),
                cells
                    .enumerate()
                    .filter(|&(i, _)| selection.point(i))
                    .map(|(_, c)| c),
            );
            *arc = ArcState {
                target: choice.map(|c| c.point),
                periods_left: multipoint::replan_periods(prm.mp_arc_m, speed, prm.period_s)
                    .saturating_sub(1),
            };
        } else {
            arc.periods_left = arc.periods_left.saturating_sub(1);
        }
        let aim = arc.target.unwrap_or(goal) - p;
        self.track(m, cx, aim.normalized(1e-6).unwrap_or(Vec2::ZERO) * speed)
    }

    /// Navigation function on a sphere world (seed 004): the vehicle descends φ_κ along
    /// −∇φ/‖∇φ‖ at the cruise speed. Only the direction of the gradient is used: ‖∇φ‖ spans
    /// tens of orders of magnitude (φ is a plateau just below 1 away from the goal), so a
    /// force proportional to it would crawl far out and be violent near obstacles.
    ///
    /// The workspace is the disc of radius ρ₀ = `nf_workspace_m` about the goal (obstacle 0).
    /// Each obstacle becomes its enclosing circle ([`navfn::enclosing_circle`]) grown by the
    /// vehicle's own radius (taken as `agent_radius_m`, the size vehicles are given), other
    /// vehicles circles of twice that; overlapping circles are merged into one enclosing both,
    /// since a sphere world needs disjoint obstacles. κ = `nf_kappa`, or M + 2 for the M
    /// circles left (the notes' rule of thumb; with tens of circles it can leave spurious
    /// minima, see `navfn.rs`). Outside the free space (inside an enclosing circle, beyond ρ₀)
    /// the vehicle heads out along the way out; with the goal inside a circle there is no
    /// navigation function and it heads straight at the goal.
    ///
    /// **Saddles.** Besides the goal, φ has a saddle behind every obstacle (seed 004: a
    /// navigation function is a Morse function; its other critical points are saddles). Its
    /// stable manifold is a line: a vehicle on it descends to the saddle and, the descent
    /// reversing there, chatters on it, left only when rounding errors grow. The planner
    /// perturbs deterministically: when the descent is zero or reverses within one period
    /// (cosine below [`SADDLE_REVERSAL`] with the last one) away from the goal, it steers for
    /// that period square to the line to the goal, to its left. Off the stable manifold,
    /// descent carries the vehicle away from the saddle.
    #[inline(never)]
    pub(super) fn plan_navfn(&self, m: &mut Motion, cx: &Context<'_>) -> Command {
        let p = cx.nav.position;
        let straight = (cx.aim - p).normalized(1e-6).unwrap_or(Vec2::ZERO);
        let mut direction = match self.sphere_world(cx) {
            Ok(world) => match world.eval(p) {
                Ok(e) => e.descent,
                Err(NavfnError::GoalBlocked) => straight,
                Err(_) => world.escape_direction(p).unwrap_or(straight),
            },
            Err(_) => straight,
        };
        let far = (cx.aim - p).norm() > self.params.arrival_radius_m;
        let reversed = direction == Vec2::ZERO || direction.dot(m.descent) < SADDLE_REVERSAL;
        if far && reversed && m.descent != Vec2::ZERO {
            direction = straight.perp();
        }
        m.descent = direction;
        let speed = self.cruise_speed(m, cx);
        self.track(m, cx, direction * speed)
    }

    /// v_max (seed 003's constant u), reduced near the goal so that the goal stays reachable
    /// within the bounds: to √(2·F_max·d) to stop on it, and to √(F_max·d / (2 sin θ)), θ the
    /// angle between the heading and the goal, so that the turn onto it, of radius v²/F_max at
    /// the bounded lateral acceleration, fits inside the circle through the goal tangent to the
    /// heading (diameter d / sin θ; a goal behind counts as θ = 90°). Zero from arrival until
    /// the vehicle is [`ARRIVAL_RELEASE`] arrival radii away. A waypoint that is passed is not
    /// stopped on: only the turn bounds the speed.
    fn cruise_speed(&self, m: &mut Motion, cx: &Context<'_>) -> f32 {
        let prm = &self.params;
        let d = (cx.mission.goal - cx.nav.position).norm();
        // The turn is onto the route's goal-point when there is one (it is where we steer).
        let to_goal = cx.aim - cx.nav.position;
        let bow = Vec2::from_angle(cx.nav.heading);
        let sin_theta = if bow.dot(to_goal) < 0.0 {
            1.0
        } else {
            bow.cross(to_goal).abs() / max(to_goal.norm(), 1e-6)
        };
        let turn = sqrt(prm.f_max * to_goal.norm() / (2.0 * max(sin_theta, 1e-6)));
        if cx.leg.passing {
            // A waypoint to pass (or the loiter circle): no stop on it.
            m.arrived = false;
            return min(prm.v_max, turn);
        }
        m.arrived = still_arrived(m.arrived, d, cx.leg.radius);
        if m.arrived {
            0.0
        } else {
            min(min(prm.v_max, sqrt(2.0 * prm.f_max * d)), turn)
        }
    }

    /// F = [`TRACK_GAIN`]/T · (v_d − v_c): the force that makes the planned velocity follow
    /// `desired`, then the shared bounding and integration.
    fn track(&self, m: &mut Motion, cx: &Context<'_>, desired: Vec2) -> Command {
        let f = (desired - m.integrator.velocity) * (TRACK_GAIN / self.params.period_s);
        self.integrate(m, cx, f)
    }

    fn sphere_world(&self, cx: &Context<'_>) -> Result<SphereWorld, NavfnError> {
        let prm = &self.params;
        let goal = cx.aim;
        let mut world = SphereWorld::new(goal, prm.nf_workspace_m, goal, 1.0)?;
        for shape in cx.predicted_shapes() {
            let (c, r) = navfn::enclosing_circle(&shape);
            world.push_merged(c, r + prm.agent_radius_m)?;
        }
        for a in cx.world.agents() {
            world.push_merged(a.position, 2.0 * prm.agent_radius_m)?;
        }
        // Evidence-map cells are small spheres; a wall of them merges into one enclosing
        // sphere, which is how far a sphere world can represent it.
        for &c in cx.world.map_cells() {
            world.push_merged(c, cx.world.map_radius() + prm.agent_radius_m)?;
        }
        world.set_kappa(max(1.0, navfn::kappa(prm.nf_kappa, world.len())))?;
        Ok(world)
    }
}
