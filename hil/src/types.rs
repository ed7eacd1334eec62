//! Plain data shared by the harness's rooms. The harness is host code: it computes in `f64`
//! and converts to the firmware's `f32` at the wire.

/// A point or vector in the horizontal plane, metres (or m/s).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct P2 {
    /// x, m.
    pub x: f64,
    /// y, m.
    pub y: f64,
}

impl P2 {
    /// A point from its coordinates.
    pub const fn new(x: f64, y: f64) -> Self {
        P2 { x, y }
    }
    /// Length.
    pub fn norm(self) -> f64 {
        self.x.hypot(self.y)
    }
    /// Difference `self − o` (a plain method: no operator traits to import at every use).
    #[allow(clippy::should_implement_trait)]
    pub fn sub(self, o: P2) -> P2 {
        P2::new(self.x - o.x, self.y - o.y)
    }
    /// Sum.
    #[allow(clippy::should_implement_trait)]
    pub fn add(self, o: P2) -> P2 {
        P2::new(self.x + o.x, self.y + o.y)
    }
    /// Scaled by `k`.
    pub fn scale(self, k: f64) -> P2 {
        P2::new(self.x * k, self.y * k)
    }
    /// The firmware's `f32` vector.
    pub fn to_vpf(self) -> vpf::Vec2 {
        vpf::Vec2::new(self.x as f32, self.y as f32)
    }
}

/// The true state of a simulated vehicle in the Earth-fixed frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VehicleState {
    /// Position, m.
    pub position: P2,
    /// Heading ψ, rad (counter-clockwise from +x).
    pub heading: f64,
    /// Body-frame surge u and sway v, m/s (relative to the water).
    pub u: f64,
    /// Sway, m/s.
    pub v: f64,
    /// Yaw rate r, rad/s.
    pub r: f64,
    /// Velocity over ground (water-relative velocity rotated to Earth, plus current), m/s.
    pub velocity: P2,
    /// Magnitude of the thrust (or thrust-like effort) applied this step, N (an energy proxy).
    pub thrust: f64,
}

/// The set-points the firmware commands and the autopilots track.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SetPoints {
    /// Heading set-point ψ_set, rad.
    pub psi: f64,
    /// Speed set-point v_set, m/s.
    pub speed: f64,
    /// The planner's commanded velocity vector (for the kinematic model), m/s.
    pub velocity: P2,
    /// Seed 001's PI-D set-points, for autopilots in [`Autopilot::SetPoints`] mode
    /// (`crate::sim::vehicle`).
    ///
    /// [`Autopilot::SetPoints`]: crate::sim::vehicle::Autopilot::SetPoints
    pub pid: PidFeeds,
}

/// Seed 001 §2's set-point decomposition as the firmware sends it (`vpf::planner::PidSetpoints`),
/// in f64: surge (a_c, v_c, I_surge) and heading (α_c, ω_c, φ_c).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PidFeeds {
    /// a_c, surge acceleration command, m/s².
    pub a_c: f64,
    /// v_c, surge speed command, m/s.
    pub v_c: f64,
    /// I_surge, the integral channel: how far the vehicle lags the planner's ideal position
    /// along its travel, m.
    pub i_surge: f64,
    /// α_c, heading acceleration command, rad/s².
    pub alpha_c: f64,
    /// ω_c, heading rate command, rad/s.
    pub omega_c: f64,
    /// φ_c, heading command, rad.
    pub phi_c: f64,
}

/// Obstacle geometry in the simulation (world frame, at t = 0). The firmware sees only what the
/// sonar returns; the harness knows the truth.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub enum SimShape {
    /// Circle.
    Circle {
        /// Centre, m.
        center: P2,
        /// Radius, m.
        radius: f64,
    },
    /// Rectangle rotated by `angle` (rad, counter-clockwise) about its centre.
    Rectangle {
        /// Centre, m.
        center: P2,
        /// Half-sizes along its own axes, m.
        half_size: P2,
        /// Rotation, rad.
        angle: f64,
    },
    /// Convex polygon, vertices in order.
    Polygon {
        /// Vertices, m.
        points: Vec<P2>,
    },
}

/// An obstacle of the scenario: its shape at t = 0 and a constant velocity.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SimObstacle {
    /// Shape at t = 0.
    pub shape: SimShape,
    /// Velocity, m/s (zero for a static obstacle).
    pub velocity: P2,
}

/// One period of one vehicle, as recorded by the runner.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sample {
    /// Simulation time, s.
    pub t: f64,
    /// True state.
    pub state: VehicleState,
    /// Commanded heading, rad.
    pub psi_cmd: f64,
    /// Commanded speed, m/s.
    pub speed_cmd: f64,
    /// The firmware's mode, as text (e.g. "Transit", "Hold(StaleNav)").
    pub mode: String,
    /// Stacked ghost goal-points.
    pub ghost_depth: u8,
    /// The firmware's active target (goal or ghost), m.
    pub target: P2,
    /// True signed distance to the nearest obstacle surface or other vehicle hull, m.
    pub nearest_m: f64,
}

/// A waypoint of a vehicle's mission as the harness judges it: reached when the true position
/// comes within `radius_m` of it, in order.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct WaypointMark {
    /// Where, m.
    pub position: P2,
    /// The waypoint's arrival radius, m, plus the formation's lattice length when the vehicle
    /// keeps one (a fleet is judged at its centre: `vpf::planner` advances so).
    pub radius_m: f64,
}

/// The times (s) at which `samples` reached each of `marks`, in order: waypoint k counts only
/// after waypoint k − 1, one per sample.
pub fn waypoint_arrivals(marks: &[WaypointMark], samples: &[Sample]) -> Vec<Option<f64>> {
    let mut times = vec![None; marks.len()];
    let mut next = 0;
    for s in samples {
        if let (Some(m), Some(slot)) = (marks.get(next), times.get_mut(next)) {
            if s.t.is_finite() && s.state.position.sub(m.position).norm() <= m.radius_m {
                *slot = Some(s.t);
                next += 1;
            }
        }
    }
    times
}

/// Everything one run produced for one vehicle.
#[derive(Clone, Debug, Default)]
pub struct VehicleRecord {
    /// Vehicle name from the scenario.
    pub name: String,
    /// Its goal, m (the last waypoint of a waypoint mission).
    pub goal: P2,
    /// A waypoint mission's waypoints, in order (empty for a single goal).
    pub waypoints: Vec<WaypointMark>,
    /// Waypoints reached so far, in order (the runner's running count, for ending a run).
    pub waypoints_reached: usize,
    /// The samples, one per period.
    pub samples: Vec<Sample>,
    /// Ghost goal-points the firmware used (target positions that were not the goal), m.
    pub ghosts: Vec<P2>,
    /// The last telemetry the firmware sent.
    pub telemetry: Option<vpf::link::TelemetryRepr>,
    /// Step costs reported by the firmware, in `cost_unit`.
    pub step_costs: Vec<u32>,
    /// Unit of the step costs.
    pub cost_unit: Option<vpf::link::CostUnit>,
    /// What the firmware believed (its evidence map, from `Belief` messages).
    pub belief: crate::output::belief::Belief,
    /// Its sonar is a (simulated) Ping360 on a port of its own. Without one, the Ping360
    /// counters a board image reports are those of its unconnected sonar port (commands that
    /// time out), not shown.
    pub ping360: bool,
    /// Its hull radius, m (`crate::runner::hull_radius`): what the others' sonars see.
    pub hull_m: f64,
}
