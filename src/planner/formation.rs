//! Formation guidance by a virtual leader, seed 001 §3.2, Table 1.
//!
//! Every sensed agent i proposes a node of *its* formation lattice for this vehicle; the virtual
//! leader is the mean of the proposals (Table 1, step 2), and a goal-point PDF with σ = λ/3
//! (001 eq. 12) is placed on it (step 3). One attractor per vehicle replaces the q wells per
//! agent of 001 eq. 11, whose mutual dragging made formations chaotic.
//!
//! The lattices (q is "the number of vertices of a regular polygon that tiles the plane", with
//! nodes λ·(cos θₖ, sin θₖ), θₖ = θ₀ + 2πk/q around each agent): q = 4 the square lattice, q = 6
//! the triangular one, q = 3 the honeycomb.
//!
//! **The honeycomb's two sublattices (q = 3).** The paper's nodes sit at the same bearings
//! θ₀ + 2πk/3 round every agent. But if B sits on one of A's nodes, A lies at that bearing + π
//! from B, which is none of B's node bearings: no pair is an equilibrium, and the vehicles
//! chase each other. A honeycomb has two sublattices whose node directions are opposite:
//! θ₀ + 2πk/3 on one, θ₀ + π + 2πk/3 on the other (together, the six directions of Table 1's
//! π/3 quantum), and every neighbour of a vertex is on the other sublattice. So each vehicle
//! decides which sublattice it is on from the bearings βᵢ to its neighbours: the one whose
//! directions they fit, by the sign of Σᵢ cos 3(βᵢ − θ₀) (+1 on a node direction of the
//! θ₀ set, −1 on one of the θ₀ + π set; ties count as the θ₀ set) — and takes the agents' nodes
//! from the *other* set. Neighbours decide consistently: seen from the agent the bearing is
//! βᵢ + π and cos 3(βᵢ + π − θ₀) = −cos 3(βᵢ − θ₀), so a pair always puts itself on opposite
//! sublattices. q = 4 and q = 6 are Bravais lattices (one set of directions for every vertex)
//! and are as the paper gives them.
//!
//! **Which node.** Table 1 quantises the bearing βᵢ by 2π/q (its "π/3" is the q = 6 case) and
//! takes the node in that direction on the agent's first ring. Two readings were needed:
//! 1. The paper's βᵢ = atan2(x_agᵢ − p) is the bearing *to* the agent; that node lies behind the
//!    agent and the vehicle would have to pass through it. We use the bearing *from* the agent,
//!    so the node is on this vehicle's side (what 001 Fig. 2 draws).
//! 2. Averaging over *all* agents, a finished formation is not an equilibrium: in a square of
//!    four, the diagonal vehicle (at √2·λ) proposes a side node and drags each vehicle by λ/3;
//!    and far-apart vehicles that disagree on the lattice settle on compromise points. So only
//!    *neighbours* propose — agents inside the first shell, halfway between the first ring (λ)
//!    and the second (√2·λ for q = 4, √3·λ for q = 3 and 6). A vehicle with no neighbour yet
//!    joins its nearest agent's first ring, which is Table 1 applied to that agent alone.
//!
//! **A craft that turns slowly waits rather than turns back** ([`hold_back`]; our addition,
//! none of the seeds has it: 001 flies craft that turn at once). A vehicle ahead of its node
//! is pulled back by the virtual leader; with eq. 12's pull twice the cruise goal-point's a
//! few metres off, the field reverses its velocity and a flat-fish (12 m turning radius at
//! 0.567 m/s) loops round on a 9 m lattice, the fleet weaving at a quarter of its cruise.
//! So for such a craft the leader may take back at most [`HOLD_BACK`] of the rest of the
//! field's pull towards the goal-point: a vehicle ahead of its node slows to half its speed
//! instead of turning, and the ones behind close up at cruise. Sideways and forwards the
//! leader pulls as the paper's. Flat-fish formations with its recipe (`cargo hil bench
//! --models flatfish --params hil/recipes/flatfish.toml --families formation --seeds 68`,
//! seeds 0–67 / 68–135): 39 → 61 and 37 → 63 of 68, spacing error 20 % → 22 % and 20 % → 21 %
//! (a quarter: 67 with a contact, spacing 25 %; all of it, 40). A VideoRay turns on the spot
//! and keeps the paper's field: with this, seeds 0–99, 100 of 100 either way, spacing 18 % →
//! 24 %.

use crate::field::GoalPdf;
use crate::math::{wrap_angle, Vec2, TAU};
pub use crate::types::formation::{Formation, FormationError};
use crate::world::Agent;

impl Formation {
    /// σ of the virtual leader's PDF: λ/3 (001 eq. 12).
    pub fn sigma(&self) -> f32 {
        self.lattice_m / 3.0
    }

    /// The first-ring node of `agent` in the bearing of the vehicle at `p` (Table 1,
    /// L1.1–L1.3, bearing taken from the agent), for agents whose node directions start at
    /// `orientation` (θ₀, or θ₀ + π for the honeycomb's other sublattice: [`Formation::agents_orientation`]).
    pub fn node_from(&self, agent: Vec2, p: Vec2, orientation: f32) -> Vec2 {
        let step = TAU / self.q as f32;
        let beta = wrap_angle((p - agent).angle() - orientation);
        let k = libm::roundf(beta / step);
        agent + Vec2::from_angle(orientation + k * step) * self.lattice_m
    }

    /// [`Formation::node_from`] with the node directions starting at θ₀.
    pub fn node(&self, agent: Vec2, p: Vec2) -> Vec2 {
        self.node_from(agent, p, self.orientation)
    }

    /// Where the node directions of the agents at `neighbours` start, seen by the vehicle at
    /// `p`: θ₀ for q = 4 and 6; for the honeycomb (q = 3) the opposite of the vehicle's own
    /// sublattice, θ₀ + π when the bearings to its neighbours fit the θ₀ set, else θ₀ (module
    /// notes).
    pub fn agents_orientation<'a>(
        &self,
        p: Vec2,
        neighbours: impl Iterator<Item = &'a Agent>,
    ) -> f32 {
        if self.q != 3 {
            return self.orientation;
        }
        let fit: f32 = neighbours
            .map(|a| crate::math::cos(3.0 * ((a.position - p).angle() - self.orientation)))
            .sum();
        if fit >= 0.0 {
            self.orientation + core::f32::consts::PI
        } else {
            self.orientation
        }
    }

    /// The virtual leader's goal-point PDF (Table 1, step 3; 000 eq. 13 with σ = λ/3, 001
    /// eq. 12) for the vehicle at `p` and the leader at `vl`.
    ///
    /// **Departure, and why.** Eq. 12's σ = λ/3 is chosen so that eq. 11's node wells "taper
    /// away" at the agent; its pull on a vehicle d from the well is A⁻·ε·d/σ²·e^{−d²/2σ²},
    /// nothing once d is a few σ (at 5 m with λ = 4 m, e⁻⁷ of its peak). A vehicle that has no
    /// neighbour yet — every vehicle of a fleet started more than a lattice length apart — then
    /// feels no formation at all, and the fleet transits in its starting arrangement. As for
    /// far goals (`vpf::goal_point`), a leader farther than 2σ is carried 2σ ahead on the line
    /// to it ("carrot on a stick", 000 §III), where it pulls with A⁻·ε·2e⁻²/σ; within 2σ it is
    /// the paper's.
    pub fn leader_pdf(&self, p: Vec2, vl: Vec2) -> GoalPdf {
        let sigma = self.sigma();
        let d = vl - p;
        let reach = LEADER_CARROT_SIGMAS * sigma;
        let n2 = d.norm2();
        let at = if n2 > reach * reach {
            p + d * (reach / crate::math::sqrt(n2))
        } else {
            vl
        };
        GoalPdf::new(at, self.attraction, sigma)
    }

    /// Radius of the first shell, m: agents inside it are neighbours.
    pub fn neighbour_shell(&self) -> f32 {
        let second_ring = if self.q == 4 { SQRT_2 } else { SQRT_3 };
        0.5 * (1.0 + second_ring) * self.lattice_m
    }

    /// The virtual leader (Table 1, step 2): the mean of the neighbours' first-ring nodes, or
    /// the nearest agent's when none is a neighbour; `None` with no agent in sight.
    pub fn virtual_leader(&self, p: Vec2, agents: &[Agent]) -> Option<Vec2> {
        let shell2 = self.neighbour_shell() * self.neighbour_shell();
        let neighbours = || {
            agents
                .iter()
                .filter(move |a| (a.position - p).norm2() <= shell2)
        };
        let theta = self.agents_orientation(p, neighbours());
        let (sum, n) = neighbours().fold((Vec2::ZERO, 0u32), |(s, n), a| {
            (s + self.node_from(a.position, p, theta), n + 1)
        });
        if n > 0 {
            return Some(sum * (1.0 / n as f32));
        }
        let nearest = agents.iter().min_by(|a, b| {
            (a.position - p)
                .norm2()
                .total_cmp(&(b.position - p).norm2())
        })?;
        let theta = self.agents_orientation(p, core::iter::once(nearest));
        Some(self.node_from(nearest.position, p, theta))
    }
}

/// The most of the rest of the field's pull towards the goal-point that the virtual leader may
/// take back from a craft that turns slowly ([`hold_back`]).
pub const HOLD_BACK: f32 = 0.5;

/// The whole field's force for a craft that turns slowly (module notes, "waits rather than
/// turns back"): `full` and `without_leader` are the sampled forces with and without the
/// virtual leader (their difference the leader's share), `to_goal` the way to the goal-point.
/// The leader's share along that way is kept above −[`HOLD_BACK`] times the rest's.
pub fn hold_back(full: Vec2, without_leader: Vec2, to_goal: Vec2) -> Vec2 {
    let Some(g) = to_goal.normalized(1e-6) else {
        return full;
    };
    let lead = full - without_leader;
    let along = lead.dot(g);
    let floor = -HOLD_BACK * crate::math::max(0.0, without_leader.dot(g));
    if along >= floor {
        return full;
    }
    full + g * (floor - along)
}

/// How far ahead a far virtual leader is carried, in σ ([`Formation::leader_pdf`]).
pub const LEADER_CARROT_SIGMAS: f32 = 2.0;

const SQRT_2: f32 = core::f32::consts::SQRT_2;
const SQRT_3: f32 = 1.732_050_8;

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Formation {
        Formation {
            q: 4,
            lattice_m: 2.0,
            orientation: 0.0,
            attraction: 10.0,
        }
    }

    #[test]
    fn node_is_on_this_vehicles_side_of_the_agent() {
        let f = square();
        // Vehicle north-north-east of the agent: the north node of the first ring (Table 1) ...
        let n = f.node(Vec2::new(5.0, 5.0), Vec2::new(5.5, 9.0));
        assert!((n - Vec2::new(5.0, 7.0)).norm() < 1e-5, "{n:?}");
        let hex = Formation { q: 6, ..f };
        let n = hex.node(Vec2::ZERO, Vec2::new(1.0, 1.9));
        assert!((n - Vec2::from_angle(TAU / 6.0) * 2.0).norm() < 1e-5);
    }

    #[test]
    fn a_slow_turning_craft_ahead_of_its_node_is_slowed_not_turned_back() {
        let to_goal = Vec2::new(10.0, 0.0);
        let rest = Vec2::new(1.0, 0.2);
        // The leader pulls back twice as hard as the goal: held to half the rest's pull.
        let held = hold_back(Vec2::new(-1.0, 0.5), rest, to_goal);
        assert!((held - Vec2::new(0.5, 0.5)).norm() < 1e-6, "{held:?}");
        // Pulling forwards or sideways, or back by less than half, it is the paper's.
        for full in [
            Vec2::new(2.0, 0.0),
            Vec2::new(1.0, -3.0),
            Vec2::new(0.6, 0.2),
        ] {
            assert_eq!(hold_back(full, rest, to_goal), full);
        }
        // With no way to the goal-point there is nothing to hold to.
        assert_eq!(
            hold_back(Vec2::new(-1.0, 0.0), rest, Vec2::ZERO),
            Vec2::new(-1.0, 0.0)
        );
    }

    #[test]
    fn a_finished_square_is_an_equilibrium() {
        let f = square();
        let corners = [
            Vec2::new(0.0, 0.0),
            Vec2::new(2.0, 0.0),
            Vec2::new(0.0, 2.0),
            Vec2::new(2.0, 2.0),
        ];
        for (i, &me) in corners.iter().enumerate() {
            let others: heapless::Vec<Agent, 4> = corners
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(j, &c)| Agent::new(j as u16, c, Vec2::ZERO, 0).unwrap())
                .collect();
            let vl = f.virtual_leader(me, &others).unwrap();
            assert!((vl - me).norm() < 1e-4, "corner {i}: leader at {vl:?}");
        }
    }

    /// The vertices of a honeycomb patch: a vertex at the origin on the θ₀ sublattice, its
    /// three neighbours, and theirs (10 vertices: two hexagons sharing an edge).
    fn honeycomb(f: &Formation) -> heapless::Vec<Vec2, 16> {
        let dir = |a: f32| Vec2::from_angle(f.orientation + a) * f.lattice_m;
        let mut v: heapless::Vec<Vec2, 16> = heapless::Vec::new();
        let add = |p: Vec2, v: &mut heapless::Vec<Vec2, 16>| {
            if v.iter().all(|q| (*q - p).norm() > 1e-3) {
                v.push(p).unwrap();
            }
        };
        add(Vec2::ZERO, &mut v);
        for k in 0..3 {
            let a = dir(TAU * k as f32 / 3.0);
            add(a, &mut v);
            // a is on the other sublattice: its directions are θ₀ + π + 2πj/3.
            for j in 0..3 {
                add(
                    a + dir(core::f32::consts::PI + TAU * j as f32 / 3.0),
                    &mut v,
                );
            }
        }
        v
    }

    #[test]
    fn a_finished_honeycomb_is_an_equilibrium_for_every_vertex() {
        for orientation in [0.0, 0.4, -2.0] {
            let f = Formation {
                q: 3,
                orientation,
                ..square()
            };
            let cells = honeycomb(&f);
            assert_eq!(cells.len(), 10);
            for (i, &me) in cells.iter().enumerate() {
                let others: heapless::Vec<Agent, 16> = cells
                    .iter()
                    .enumerate()
                    .filter(|&(j, _)| j != i)
                    .map(|(j, &c)| Agent::new(j as u16, c, Vec2::ZERO, 0).unwrap())
                    .collect();
                let vl = f.virtual_leader(me, &others).unwrap();
                assert!(
                    (vl - me).norm() < 1e-3,
                    "θ₀ {orientation}, vertex {i}: {vl:?}"
                );
            }
        }
    }

    #[test]
    fn a_honeycomb_pair_agrees_on_opposite_sublattices() {
        let f = Formation { q: 3, ..square() };
        // B on A's node at θ₀ (east of A): each one's leader is where it is ...
        let a = Agent::new(1, Vec2::ZERO, Vec2::ZERO, 0).unwrap();
        let b = Agent::new(2, Vec2::new(2.0, 0.0), Vec2::ZERO, 0).unwrap();
        assert!((f.virtual_leader(b.position, &[a]).unwrap() - b.position).norm() < 1e-5);
        assert!((f.virtual_leader(a.position, &[b]).unwrap() - a.position).norm() < 1e-5);
        // ... which the fixed bearings θ₀ + 2πk/3 round every agent cannot give: A's node
        // nearest B's bearing from B is a whole λ away from A.
        assert!((f.node(b.position, a.position) - a.position).norm() > 1.0);
        // And a three-vehicle triangle (60°) is not a honeycomb: one of them is moved.
        let c = Agent::new(3, Vec2::from_angle(TAU / 6.0) * 2.0, Vec2::ZERO, 0).unwrap();
        let moved = [(a, [b, c]), (b, [a, c]), (c, [a, b])]
            .iter()
            .filter(|(me, others)| {
                (f.virtual_leader(me.position, others).unwrap() - me.position).norm() > 0.1
            })
            .count();
        assert!(moved > 0);
    }

    #[test]
    fn a_lone_vehicle_joins_the_nearest_agents_first_ring() {
        let f = square();
        let agents = [
            Agent::new(1, Vec2::new(10.0, 0.0), Vec2::ZERO, 0).unwrap(),
            Agent::new(2, Vec2::new(30.0, 0.0), Vec2::ZERO, 0).unwrap(),
        ];
        let v = f.virtual_leader(Vec2::ZERO, &agents).unwrap();
        assert!((v - Vec2::new(8.0, 0.0)).norm() < 1e-5, "{v:?}");
    }

    #[test]
    fn leader_is_the_mean_of_the_proposals() {
        let f = square();
        let agents = [
            Agent::new(1, Vec2::new(0.0, 0.0), Vec2::ZERO, 0).unwrap(),
            Agent::new(2, Vec2::new(4.0, 0.0), Vec2::ZERO, 0).unwrap(),
        ];
        // From (2, 0.5): agent 1 offers (2, 0), agent 2 offers (2, 0).
        let v = f.virtual_leader(Vec2::new(2.0, 0.5), &agents).unwrap();
        assert!((v - Vec2::new(2.0, 0.0)).norm() < 1e-5);
        assert_eq!(f.virtual_leader(Vec2::ZERO, &[]), None);
    }

    #[test]
    fn bad_requests_are_refused() {
        assert_eq!(
            Formation { q: 5, ..square() }.validate(),
            Err(FormationError::Descriptor)
        );
        assert_eq!(
            Formation {
                lattice_m: f32::NAN,
                ..square()
            }
            .validate(),
            Err(FormationError::NonFinite)
        );
        assert_eq!(square().validate(), Ok(()));
    }
}
