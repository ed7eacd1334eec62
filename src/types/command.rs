//! One period's output: the set-points for the autopilots, the planner's mode and why it holds.

use crate::math::Vec2;

/// Why the planner holds instead of planning.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HoldReason {
    /// No mission has been given.
    NoMission,
    /// Navigation is older than the runtime's timeout.
    StaleNav,
    /// The vehicle is inside an obstacle's surface.
    InsideObstacle,
    /// A collision cannot be avoided at the current speed.
    CollisionImminent,
    /// Navigation fixes keep coming but do not change while the vehicle is commanded to move:
    /// the navigation source has frozen (`crate::guidance::failsafe::FreezeDetector`).
    FrozenNav,
    /// The sonar has not yet swept once round the vehicle since it started, or it has gone
    /// quiet and the vehicle has gone as far as the map it has can be trusted
    /// (`crate::guidance::failsafe::SonarWatch`).
    SonarBlind,
}

impl HoldReason {
    /// Whether the hold keeps station over ground in a current the vehicle has estimated
    /// (`crate::guidance::drift`; a craft that turns at once): for an obstacle too close or a
    /// sonar that cannot see, where drifting carries the hull into what is there. The others —
    /// no mission, navigation stale or frozen — send zero speed through the water: with no
    /// mission nothing should turn a thruster, and without trustworthy navigation there is no
    /// current to take out.
    pub fn keeps_station(self) -> bool {
        matches!(
            self,
            HoldReason::InsideObstacle | HoldReason::CollisionImminent | HoldReason::SonarBlind
        )
    }
}

/// What the planner is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Mode {
    /// Zero velocity over ground, for the reason given: zero set-points, or, where the reason
    /// [keeps station](HoldReason::keeps_station) in an estimated current, head to it at its speed.
    Hold(HoldReason),
    /// Following the field to the mission goal.
    Transit,
    /// Following the field to a ghost goal-point (000 §III).
    Escape,
    /// Within the arrival radius of the goal, or held there since it came within it (released
    /// four arrival radii out): the planner keeps station on the goal.
    Arrived,
    /// The waypoint mission is complete and the vehicle circles its last waypoint
    /// ([`MissionEnd::Loiter`]).
    Loiter,
    /// The planner's command was turned, slowed or stopped by the guard, because it would have
    /// driven into something believed (`crate::guidance::guard`).
    Guarded,
}

/// One period's output: set-points for the autopilots, and what produced them.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Command {
    /// ψ_set, heading set-point, rad in (−π, π] (000 eq. 6).
    pub psi_set: f32,
    /// v_set, speed set-point, m/s, 0 ..= v_max (000 eq. 7).
    pub v_set: f32,
    /// PI-D set-points (001 §2).
    pub setpoints: PidSetpoints,
    /// Mode.
    pub mode: Mode,
    /// F̄, the bounded controlling force, m/s².
    pub force: Vec2,
    /// v̄_c, the bounded commanded velocity, m/s.
    pub velocity: Vec2,
    /// The active goal-point (mission goal or top ghost), m.
    pub target: Vec2,
    /// Number of stacked ghost goal-points.
    pub ghost_depth: u8,
    /// Signed distance to the nearest obstacle or vehicle circle, m (negative: inside).
    pub clearance_m: f32,
}

impl Command {
    /// A hold: zero speed, heading kept at `heading`.
    pub fn hold(reason: HoldReason, heading: f32) -> Command {
        Command {
            psi_set: crate::math::wrap_angle(heading),
            v_set: 0.0,
            setpoints: PidSetpoints {
                phi_c: crate::math::wrap_angle(heading),
                ..PidSetpoints::default()
            },
            mode: Mode::Hold(reason),
            force: Vec2::ZERO,
            velocity: Vec2::ZERO,
            target: Vec2::ZERO,
            ghost_depth: 0,
            clearance_m: f32::INFINITY,
        }
    }

    /// Every number finite (clearance may be +∞ in an empty world).
    pub fn is_finite(&self) -> bool {
        let s = &self.setpoints;
        [
            self.psi_set,
            self.v_set,
            s.a_c,
            s.v_c,
            s.i_surge,
            s.alpha_c,
            s.omega_c,
            s.phi_c,
        ]
        .iter()
        .all(|x| x.is_finite())
            && self.force.is_finite()
            && self.velocity.is_finite()
            && self.target.is_finite()
            && !self.clearance_m.is_nan()
    }
}

/// Set-points for parallel PI-D surge and heading autopilots (001 §2).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PidSetpoints {
    /// a_c, surge acceleration command (derivative channel), m/s².
    pub a_c: f32,
    /// v_c, surge speed command, m/s (⟨v̄_c, ê₁⟩: negative means back up).
    pub v_c: f32,
    /// I_surge, integral channel: how far the idealised position is ahead of the vehicle along
    /// its travel, m (negative: the vehicle is ahead).
    pub i_surge: f32,
    /// α_c, heading acceleration command (derivative channel), rad/s².
    pub alpha_c: f32,
    /// ω_c, heading rate command, rad/s.
    pub omega_c: f32,
    /// φ_c, heading command, rad in (−π, π].
    pub phi_c: f32,
}
