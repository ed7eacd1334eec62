//! The VPF strategy (seeds 000 and 001): steps 1–3 and 7 of the loop in the module notes of
//! [`crate::planner`]; steps 4–6 are [`Planner::integrate`], shared with the other strategies.
//!
//! Moving obstacles enter at their predicted positions ([`Context::shifts`]): their stator and
//! rotor PDFs are evaluated around the shifted shape. Other vehicles are not shifted: their
//! circles also place the formation's virtual leader, which must see where they are.
//!
//! **The final approach and holding at the goal** (not in the seeds; only with the route
//! layer, so the papers' experiments fly as published). A goal within an obstacle's reach is
//! no minimum of E: the goal-point's Gaussian core pulls with A⁻·ε·d/σ² (0.008 m/s² a metre
//! out, with the defaults) and a quay 2 m off pushes with f′(r) of eq. 12, a hundred times
//! that — the "goals non-reachable with obstacles nearby" of Ge and Cui (*New potential
//! functions for mobile robot path planning*, IEEE T-RA 16(5), 2000). A VideoRay sent to a
//! point 1–2 m off a wall arrived and was pushed out again, its rotors circling it round the
//! goal at up to 0.9 m/s for minutes; sent to one 0.5 m off a rock's face, it never arrived:
//! the field held it 2 m short, its rotors swinging it from side to side. So within
//! [`ARRIVAL_RELEASE`] arrival radii of a goal in plain sight — where a vehicle that has
//! arrived is held (latched on arrival, released there, as the other strategies hold:
//! [`still_arrived`]) — its field is the goal-point, the other vehicles and the virtual
//! leader: the obstacles, the map and the rotors are left to the guard, which keeps the hull
//! off what is believed whatever the field asks. Ge and Cui make the goal the minimum by
//! scaling the repulsion with the distance to the goal; leaving the last metres to the guard
//! does the same without a second tuning, and the route has already said the way is clear.
//! Such a field always has a way down, so a stall on the final approach is the guard's, at
//! something believed beside the way (a lone speckle cell 0.5 m off held a VideoRay 2 m
//! short for the rest of a run: bench rocks seed 43); it places a ghost goal-point, which
//! brings back the whole field, and a ghost is dropped once the goal is reached.
//! Not for a craft that turns slowly (`Params::turns_slowly`): it reaches its wider arrival
//! circle on the whole field, and stopped by its guard 11 m short of a berth, it could not
//! turn out (the flat-fish with its recipe, berth seeds 0–59, 57 → 56; its nine other
//! families, seeds 0–169, 1 335 → 1 334: nothing gained); it holds once arrived, as before.

use heapless::Vec;

use super::escape::StallCause;
use super::gradient::Field;
use super::strategy::{still_arrived, ARRIVAL_RELEASE};
use super::{Context, Motion, Planner};
use crate::field::{GoalPdf, RotorSense, RotorTerm};
use crate::math::{min_num, Vec2};
use crate::planner::Command;
use crate::world::MAX_OBSTACLES;

/// One rotor normal per obstacle, and one for the evidence map.
const MAX_NORMALS: usize = MAX_OBSTACLES + 1;

/// Reach σ_c of the cruise goal-point, m: where eq. 13's steepest drop across ε,
/// A⁻·ε·e^{−1/2}/σ_c (at distance σ_c from its centre), balances friction at v_max, μ·v_max —
/// so a vehicle pulled by it settles at v_max. Never more than the paper's σ (with no
/// friction any reach cruises).
pub fn cruise_reach(prm: &crate::params::Params) -> f32 {
    let drag = prm.mu * prm.v_max;
    if drag <= 0.0 {
        return prm.sigma_m;
    }
    let sigma_c = prm.a_minus * prm.epsilon_m * libm::expf(-0.5) / drag;
    crate::math::min(prm.sigma_m, sigma_c)
}

/// How far ahead an unrouted goal-point is carried, in attractor reaches σ.
pub const CARROT_SIGMAS: f32 = 2.0;

/// How the goal-point is placed ([`goal_point`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Approach {
    /// No route layer: the paper's field, a far goal carried 2σ ahead.
    Unrouted,
    /// The route layer's goal is in plain sight: cruise to within σ_c of it.
    Routed,
    /// The route layer's intermediate goal-point: a waypoint to pass, cruise all the way.
    Detour,
}

/// Seed 000's goal-point PDF (eq. 13) for a vehicle at `p` heading for `target`.
///
/// **Departure from the paper, and why.** The force is the drop of the potential across the
/// sample circle (eq. 2–4), so eq. 13 pulls with A⁻·ε·d/σ²·e^{−d²/2σ²} at distance d: a
/// Gaussian's tail. With the defaults (A⁻ = 50, ε = 0.25 m, σ = 40 m, μ = 0.4) that balances
/// friction at 0.47 m/s at best (d = σ), at 0.21 m/s at 2σ, and not at all 150 m out.
/// - [`Approach::Unrouted`] (no route layer, e.g. the papers' experiments): a target farther
///   than 2σ is carried 2σ ahead on the straight line to it — a "carrot on a stick" (000 §III's
///   own image for ghost goal-points) that still pulls; within 2σ, the paper's field. Every
///   paper experiment starts within 2σ of its goal, so their runs are as published.
/// - [`Approach::Routed`] and [`Approach::Detour`] (the route layer has a way): a **cruise
///   goal-point** σ_c ahead on the line, with reach σ_c ([`cruise_reach`], 19 m with the
///   defaults), whose pull settles the vehicle at v_max whatever the distance; for a goal in
///   plain sight until it has arrived (the planned speed is capped to brake onto the goal,
///   `Planner::arrival_speed`; the paper's field, whose final approach has the time constant
///   μσ²/(A⁻ε) ≈ 50 s, then holds it there), for an intermediate goal-point all the way (it is
///   passed, not stopped on).
///
/// `arrival_m` is the goal's arrival radius (`Params::arrival_radius_m`, or a waypoint's own).
/// An intermediate waypoint of a mission, and the last one of a mission that loiters, are
/// approached as [`Approach::Detour`] — passed at speed — whether routed or not: the papers fly
/// one goal and say nothing of waypoints.
pub fn goal_point(
    p: Vec2,
    target: Vec2,
    how: Approach,
    prm: &crate::params::Params,
    arrival_m: f32,
) -> GoalPdf {
    let d = target - p;
    let n2 = d.norm2();
    let (ahead, sigma) = match how {
        Approach::Unrouted => (CARROT_SIGMAS * prm.sigma_m, prm.sigma_m),
        Approach::Routed | Approach::Detour => (cruise_reach(prm), cruise_reach(prm)),
    };
    let near = match how {
        Approach::Unrouted => ahead,
        // Brought in at speed (`Planner::arrival_speed` brakes): the paper's field only
        // once arrived, to hold the vehicle there.
        Approach::Routed => arrival_m,
        Approach::Detour => 0.0,
    };
    if n2 <= near * near || n2 < 1e-12 {
        return GoalPdf::new(target, prm.a_minus, prm.sigma_m);
    }
    GoalPdf::new(p + d * (ahead / crate::math::sqrt(n2)), prm.a_minus, sigma)
}

impl Planner {
    /// One VPF period: E, its sampled gradient and friction give F; the ghost goal-points
    /// are updated after the shared integration.
    #[inline(never)]
    pub(super) fn plan_vpf(&self, m: &mut Motion, cx: &Context<'_>) -> Command {
        let p = cx.nav.position;
        let prm = self.params;
        let world = cx.world;
        // A ghost goal-point is moot at the goal: one placed on the final approach outlived
        // the arrival and led a held vehicle off its berth (module notes). Without a route the
        // papers' ghosts run their course.
        let d = (cx.mission.goal - p).norm();
        if cx.routed && d <= cx.leg.radius {
            m.escape.reset();
        }
        let target = m.escape.active_target(cx.aim);
        let how = if target != cx.aim {
            // A ghost goal-point is up: the field as published.
            Approach::Unrouted
        } else if cx.leg.passing {
            // A waypoint to pass, or the loiter circle: cruise all the way.
            Approach::Detour
        } else if !cx.routed {
            // No route: the field as published.
            Approach::Unrouted
        } else if cx.aim == cx.mission.goal {
            Approach::Routed
        } else {
            Approach::Detour
        };

        // The final approach and the hold (module notes): arrival latched as the other
        // strategies latch theirs; the field the goal's alone within their release.
        m.arrived = how == Approach::Routed && still_arrived(m.arrived, d, cx.leg.radius);
        let approach = !prm.turns_slowly() && d <= ARRIVAL_RELEASE * cx.leg.radius;
        let holds = how == Approach::Routed && (m.arrived || approach);

        // Attractors: the active goal-point — as a cruise goal-point when far — and the
        // virtual leader (001 Table 1).
        let goal = goal_point(p, target, how, &prm, cx.leg.radius);
        let formation = cx
            .mission
            .formation
            .filter(|_| !m.escape.formation_released(cx.now_ms));
        let leader = formation.and_then(|f| {
            let vl = f.virtual_leader(p, world.agents())?;
            Some((f, f.leader_pdf(p, vl)))
        });

        // Each obstacle's distance r and its gradient ∇r at the vehicle (the obstacle at its
        // predicted position), once: the rotor's normals and the field's far test share them.
        let mut distances: Vec<(f32, Vec2), MAX_OBSTACLES> = Vec::new();
        // With them the clearance as things are now: a still obstacle's distance is the one
        // found here (bit for bit `signed_distance`), a moving one is measured where it is.
        let nearest_map = crate::world::nearest_cell(world.map_cells(), p);
        let mut clearance = nearest_map.map_or(f32::INFINITY, |(_, d)| d - world.map_radius());
        for (o, &shift) in world.obstacles().iter().zip(cx.shifts) {
            let (r, g) = o.shape.distance_gradient(p - shift);
            if !world.left_to_map(o) {
                clearance = min_num(
                    clearance,
                    if shift == Vec2::ZERO {
                        r
                    } else {
                        o.shape.signed_distance(p)
                    },
                );
            }
            // Same capacity as the obstacle table: never full.
            let _ = distances.push((r, g));
        }
        for a in world.agents() {
            clearance = min_num(clearance, (p - a.position).norm() - prm.agent_radius_m);
        }
        let cx = &Context { clearance, ..*cx };
        // The rotor terms: one normal per obstacle, and one for the map (one obstacle: its
        // normal points away from the nearest believed cell). The normal is ∇r/|∇r| (for the
        // exact distances ∇r is already a unit vector).
        let mut normals: Vec<(Vec2, f32), MAX_NORMALS> = Vec::new();
        if prm.a_rotor > 0.0 {
            for ((o, &(r, g)), &shift) in world.obstacles().iter().zip(&distances).zip(cx.shifts) {
                if world.left_to_map(o) {
                    continue;
                }
                let n = g
                    .normalized(1e-9)
                    .or_else(|| (p - shift - o.shape.center()).normalized(1e-9))
                    .unwrap_or(Vec2::new(1.0, 0.0));
                let _ = normals.push((n, o.stator().reach(r)));
            }
            if let Some((c, d)) = nearest_map {
                if let Some(n) = (p - c).normalized(1e-6) {
                    let _ = normals.push((n, self.map_stator.reach(d - world.map_radius())));
                }
            }
        }
        // The sense: one per encounter (rotor.rs), or on a route each obstacle's own towards
        // the goal-point (see `rotor_sense`).
        let strongest = normals.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1));
        let common = m.rotor_sense.update(strongest, target - p);
        let rotor_gradient = normals.iter().fold(Vec2::ZERO, |g, &(n, h)| {
            let sense = if cx.routed {
                RotorSense::Free.update(Some((n, 1.0)), target - p)
            } else {
                common
            };
            g + RotorTerm::new(prm.a_rotor, n, h, sense).gradient
        });
        m.rotor_sense = common;

        let field = Field {
            obstacles: if holds { &[] } else { world.obstacles() },
            shifts: cx.shifts,
            distances: &distances,
            agents: world.agents(),
            agent_radius: prm.agent_radius_m,
            agent_stator: self.agent_stator,
            goal,
            leader: leader.map(|(_, pdf)| pdf),
            rotor_gradient: if holds { Vec2::ZERO } else { rotor_gradient },
            origin: p,
            map: if holds { &[] } else { world.map_cells() },
            map_radius: world.map_radius(),
            map_stator: self.map_stator,
            leave_to_map: world.map_in_use(),
        };
        let forces = field.sampled_forces(&self.circle);
        // A craft that turns slowly waits for its node rather than turning back to it.
        let full = if prm.turns_slowly() && leader.is_some() {
            super::formation::hold_back(forces.full, forces.without_leader, target - p)
        } else {
            forces.full
        };
        // Virtual viscous friction, 000 eq. 14: F = F_nf − μ·v(k−1). Seed 001 eq. 4 prints
        // "+ μ·v(k−1)"; with μ ≥ 0 that would push the vehicle on in the direction it moves
        // and pump energy in, the opposite of the friction 001 cites from [1, 2] ("virtual
        // viscose friction") and of 000 eq. 14 (the force ξ·|v| at angle π + arg v, i.e.
        // against the motion), whose purpose is to siphon kinetic energy (000 Fig. 2 → 3).
        // 002 writes the friction against the motion too. We take the sign of 000 and 002.
        let f = full - m.integrator.velocity * prm.mu;
        let mut cmd = self.integrate(m, cx, f);

        // What holds a stalled vehicle (escape.rs): is there a way down without the virtual
        // leader, or without the other vehicles too? "A way down" is a descent stronger than
        // what friction balances at the stall speed. *Tried and not kept:* a stall with a way
        // down and no other vehicle in the table taken as the static field's, for a ghost (it
        // is then the guard that holds the vehicle): the flat-fish with its recipe, seeds
        // 0–33, 358 → 310 of 408 — its guard holds it at every bend of a channel while it
        // turns on the spot, and the ghosts led it off the way (channels 31 → 16).
        // On the final approach the field has a way down by construction: what holds the
        // vehicle is the guard, at something believed, so a ghost goal-point takes it round
        // with the whole field (module notes).
        let approaching = holds && !m.arrived;
        let cause = |target: Vec2| {
            if approaching {
                return StallCause::Static;
            }
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
    fn a_routed_goal_pulls_at_cruise_speed_an_unrouted_one_as_the_paper() {
        let prm = crate::params::Params::default();
        let sigma_c = cruise_reach(&prm);
        assert!(sigma_c > 10.0 && sigma_c < prm.sigma_m, "{sigma_c}");
        let e = Vec2::new(prm.epsilon_m, 0.0);
        let drop = |g: GoalPdf| g.potential(Vec2::ZERO) - g.potential(e);
        let far = Vec2::new(300.0, 0.0);
        // Routed, 300 m away: the drop across ε balances friction at v_max.
        let routed = goal_point(
            Vec2::ZERO,
            far,
            Approach::Routed,
            &prm,
            prm.arrival_radius_m,
        );
        assert!((drop(routed) - prm.mu * prm.v_max).abs() < 0.03 * prm.mu);
        // Closer than σ_c it still pulls at cruise (the arrival brake slows the vehicle) ...
        let near = Vec2::new(0.5 * sigma_c, 0.0);
        let brought = goal_point(
            Vec2::ZERO,
            near,
            Approach::Routed,
            &prm,
            prm.arrival_radius_m,
        );
        assert!((brought.center - Vec2::new(sigma_c, 0.0)).norm() < 1e-3);
        // ... and once arrived, eq. 13 as published holds it there.
        let there = Vec2::new(0.9 * prm.arrival_radius_m, 0.0);
        let paper = GoalPdf::new(there, prm.a_minus, prm.sigma_m);
        assert_eq!(
            goal_point(
                Vec2::ZERO,
                there,
                Approach::Routed,
                &prm,
                prm.arrival_radius_m
            ),
            paper
        );
        // A route's intermediate goal-point 3 m off pulls as hard as a far goal.
        let via = goal_point(
            Vec2::ZERO,
            Vec2::new(0.0, 3.0),
            Approach::Detour,
            &prm,
            prm.arrival_radius_m,
        );
        assert!((via.center - Vec2::new(0.0, sigma_c)).norm() < 1e-3);
        // Unrouted: carried 2σ ahead, the paper's field within 2σ.
        let carrot = goal_point(
            Vec2::ZERO,
            far,
            Approach::Unrouted,
            &prm,
            prm.arrival_radius_m,
        );
        assert!((carrot.center - Vec2::new(80.0, 0.0)).norm() < 1e-3);
        let fifty = Vec2::new(50.0, 0.0);
        assert_eq!(
            goal_point(
                Vec2::ZERO,
                fifty,
                Approach::Unrouted,
                &prm,
                prm.arrival_radius_m
            ),
            GoalPdf::new(fifty, prm.a_minus, prm.sigma_m)
        );
    }
}
