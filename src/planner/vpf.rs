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

/// Seed 000's goal-point PDF (eq. 13) for a vehicle at `p` heading for `target`.
///
/// **Departure from the paper, and why.** The force is the drop of the potential across the
/// sample circle (eq. 2–4), so eq. 13 pulls with A⁻·ε·d/σ²·e^{−d²/2σ²} at distance d: a
/// Gaussian's tail, 0.27·A⁻ε/σ at 2σ and nothing 150 m out with the default σ = 40 m. So a
/// target farther than σ is replaced by a goal-point σ ahead on the straight line to it — a
/// "carrot on a stick" (000 §III's own image for ghost goal-points) — where eq. 13, with the
/// paper's A⁻ and σ, pulls hardest: A⁻·ε·e^{−1/2}/σ, whatever the distance. Within σ of the
/// target the field is the paper's. A route layer's intermediate goal-point (`detour`,
/// `crate::route`) is a waypoint to pass, not to stop on: it gets the goal-point σ out along
/// the line to it even when it is nearer.
///
/// The settled speed is then A⁻·ε·e^{−1/2}/(σ·μ) (0.47 m/s with the defaults) or v_max if
/// less. A smaller σ for the carrot would cruise at v_max, and was measured (`hil bench`): at
/// 1 m/s the vehicle outruns its 9-second sonar sweep and grazes structure not yet seen.
pub fn goal_point(p: Vec2, target: Vec2, detour: bool, prm: &crate::params::Params) -> GoalPdf {
    let sigma = prm.sigma_m;
    let d = target - p;
    let n2 = d.norm2();
    if (n2 <= sigma * sigma && !detour) || n2 < 1e-12 {
        return GoalPdf::new(target, prm.a_minus, sigma);
    }
    GoalPdf::new(p + d * (sigma / crate::math::sqrt(n2)), prm.a_minus, sigma)
}

impl Planner {
    /// One VPF period: E, its sampled gradient and friction give F; the ghost goal-points
    /// are updated after the shared integration.
    pub(super) fn plan_vpf(&self, m: &mut Motion, cx: &Context<'_>) -> Command {
        let p = cx.nav.position;
        let prm = self.params;
        let world = cx.world;
        let target = m.escape.active_target(cx.aim);
        let detour = target == cx.aim && cx.aim != cx.mission.goal;

        // Attractors: the active goal-point — as a cruise goal-point when far — and the
        // virtual leader (001 Table 1).
        let goal = goal_point(p, target, detour, &prm);
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
        m.escape.update(cx.now_ms, p, speed, cx.aim, &prm, cause);
        cmd.target = m.escape.active_target(cx.aim);
        cmd.ghost_depth = m.escape.ghosts().len() as u8;
        cmd.mode = self.mode(m, cx);
        cmd
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_far_goal_pulls_as_hard_as_eq_13_can_and_a_near_one_as_the_paper() {
        let prm = crate::params::Params::default();
        let sigma = prm.sigma_m;
        let e = Vec2::new(prm.epsilon_m, 0.0);
        let drop = |g: GoalPdf| g.potential(Vec2::ZERO) - g.potential(e);
        // 300 m away: the drop across ε is eq. 13's largest, A⁻·ε·e^{−1/2}/σ.
        let far = goal_point(Vec2::ZERO, Vec2::new(300.0, 0.0), false, &prm);
        let best = prm.a_minus * prm.epsilon_m * libm::expf(-0.5) / sigma;
        assert!((drop(far) - best).abs() < 0.02 * best, "{}", drop(far));
        // Within σ: eq. 13 as published.
        let near = Vec2::new(0.5 * sigma, 0.0);
        assert_eq!(
            goal_point(Vec2::ZERO, near, false, &prm),
            GoalPdf::new(near, prm.a_minus, sigma)
        );
        // A route's goal-point 3 m off pulls as hard as a far goal.
        let via = goal_point(Vec2::ZERO, Vec2::new(3.0, 0.0), true, &prm);
        assert!((drop(via) - best).abs() < 0.02 * best);
    }
}
