//! The VPF strategy (seeds 000 and 001): steps 1–3 and 7 of the loop in the module notes of
//! [`crate::planner`]; steps 4–6 are [`Planner::integrate`], shared with the other strategies.
//!
//! Moving obstacles enter at their predicted positions ([`Context::shifts`]): their stator and
//! rotor PDFs are evaluated around the shifted shape. Other vehicles are not shifted: their
//! circles also place the formation's virtual leader, which must see where they are.

use heapless::Vec;

use super::escape::StallCause;
use super::gradient::Field;
use super::{Context, Motion, Planner};
use crate::field::{GoalPdf, RotorTerm};
use crate::math::Vec2;
use crate::planner::Command;
use crate::world::MAX_OBSTACLES;

/// One rotor normal per obstacle, and one for the evidence map.
const MAX_NORMALS: usize = MAX_OBSTACLES + 1;

/// Step of the central differences for obstacle normals, m.
const NORMAL_STEP_M: f32 = 0.01;

/// How far ahead the goal-point is carried, in attractor reaches σ.
pub const CARROT_SIGMAS: f32 = 2.0;

/// Where seed 000's goal-point PDF (eq. 13) is centred for a vehicle at `p` heading for
/// `target`: the target itself within [`CARROT_SIGMAS`]·σ, else the point that far along the
/// straight line to it — a "carrot on a stick" (000 §III's own image for the ghost
/// goal-points).
///
/// **Departure from the paper, and why.** Eq. 13 is a Gaussian of reach σ: its pull
/// A⁻·d/σ²·e^{−d²/2σ²} at distance d is 0.27·A⁻/σ at 2σ and below one thousandth of that
/// at 5σ, under friction and rounding, so a goal 150 m away with the default σ = 40 m does not
/// move the vehicle at all. Carried to 2σ ahead, the goal-point pulls with its 2σ strength
/// until the real goal is within 2σ, and from there on the field is the paper's. Every paper
/// experiment starts within 2σ of its goal, so their runs are unchanged.
pub fn carrot(p: Vec2, target: Vec2, sigma: f32) -> Vec2 {
    let d = target - p;
    let reach = CARROT_SIGMAS * sigma;
    let n2 = d.norm2();
    if n2 <= reach * reach {
        target
    } else {
        p + d * (reach / crate::math::sqrt(n2))
    }
}

impl Planner {
    /// One VPF period: E, its sampled gradient and friction give F; the ghost goal-points
    /// are updated after the shared integration.
    pub(super) fn plan_vpf(&self, m: &mut Motion, cx: &Context<'_>) -> Command {
        let p = cx.nav.position;
        let prm = self.params;
        let world = cx.world;
        let target = m.escape.active_target(cx.mission.goal);

        // Attractors: the active goal-point — carried within reach — and the virtual leader
        // (001 Table 1).
        let goal = GoalPdf::new(carrot(p, target, prm.sigma_m), prm.a_minus, prm.sigma_m);
        let formation = cx
            .mission
            .formation
            .filter(|_| !m.escape.formation_released(cx.now_ms));
        let leader = formation.and_then(|f| {
            let vl = f.virtual_leader(p, world.agents())?;
            Some((f, GoalPdf::new(vl, f.attraction, f.sigma())))
        });

        // The rotor terms: one normal per obstacle, one sense per encounter.
        let mut normals: Vec<(Vec2, f32), MAX_NORMALS> = Vec::new();
        if prm.a_rotor > 0.0 {
            for (o, &shift) in world.obstacles().iter().zip(cx.shifts) {
                if world.left_to_map(o) {
                    continue;
                }
                let x = p - shift;
                let r = o.shape.signed_distance(x);
                let _ = normals.push((
                    o.shape.outward_normal(x, r, NORMAL_STEP_M),
                    o.stator().reach(r),
                ));
            }
        }
        // The map is one obstacle: its normal points away from the nearest believed cell.
        if prm.a_rotor > 0.0 {
            if let Some((c, d)) = crate::world::nearest_cell(world.map_cells(), p) {
                if let Some(n) = (p - c).normalized(1e-6) {
                    let r = d - world.map_radius();
                    let _ = normals.push((n, self.map_stator.reach(r)));
                }
            }
        }
        let strongest = normals.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1));
        let sense = m.rotor_sense.update(strongest, target - p);
        let rotor_gradient = normals.iter().fold(Vec2::ZERO, |g, &(n, h)| {
            g + RotorTerm::new(prm.a_rotor, n, h, sense).gradient
        });
        m.rotor_sense = sense;

        let field = Field {
            obstacles: world.obstacles(),
            shifts: cx.shifts,
            agents: world.agents(),
            agent_radius: prm.agent_radius_m,
            agent_stator: self.agent_stator,
            goal,
            leader: leader.map(|(_, pdf)| pdf),
            rotor_gradient,
            origin: p,
            map: world.map_cells(),
            map_radius: world.map_radius(),
            map_stator: self.map_stator,
            leave_to_map: world.map_in_use(),
        };
        let forces = field.sampled_forces(&self.circle);
        let f = forces.full - m.integrator.velocity * prm.mu;
        let mut cmd = self.integrate(m, cx, f);

        // What holds a stalled vehicle (escape.rs): is there a way down without the virtual
        // leader, or without the other vehicles too? "A way down" is a descent stronger than
        // what friction balances at the stall speed.
        let cause = |target: Vec2| {
            let free = |f: Vec2| f.norm() > prm.mu * prm.stall_speed;
            if let Some((f, _)) = leader {
                if free(forces.without_leader) {
                    // Held by the formation near the goal is arrival in formation, not a stall:
                    // N + 1 lattice cells of side λ fit within λ·√(N + 1) of it.
                    let n = world.agents().len() as f32 + 1.0;
                    let footprint = f.lattice_m * crate::math::sqrt(n);
                    return if (target - p).norm() <= footprint {
                        StallCause::Vehicles
                    } else {
                        StallCause::Formation
                    };
                }
            }
            if free(forces.static_field) {
                StallCause::Vehicles
            } else {
                StallCause::Static
            }
        };
        let speed = cmd.velocity.norm();
        m.escape
            .update(cx.now_ms, p, speed, cx.mission.goal, &prm, cause);
        cmd.target = m.escape.active_target(cx.mission.goal);
        cmd.ghost_depth = m.escape.ghosts().len() as u8;
        cmd.mode = self.mode(m, cx);
        cmd
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_goal_point_is_carried_within_reach_and_never_past_the_goal() {
        let g = Vec2::new(300.0, 0.0);
        assert!((carrot(Vec2::ZERO, g, 40.0) - Vec2::new(80.0, 0.0)).norm() < 1e-3);
        assert_eq!(carrot(Vec2::new(250.0, 0.0), g, 40.0), g);
        let c = carrot(Vec2::new(0.0, 100.0), Vec2::ZERO, 10.0);
        assert!((c - Vec2::new(0.0, 80.0)).norm() < 1e-4, "{c:?}");
    }
}
