//! Decomposition of the planned motion into set-points for parallel PI-D autopilots, seed 001
//! eq. 8–10 and the lines after them: surge (a_c, v_c, I_surge) and heading (α_c, ω_c, φ_c).
//!
//! Choices where the paper is ambiguous:
//! - **Body frame ê₁.** Eq. 9 builds ê₁ from the previous command, v̄_c(k−1)/|v̄_c(k−1)|; we
//!   do so (the measured direction of travel before the first command, or while the command
//!   is below [`V_EPS`]). §3.1's split bounding uses the *true* direction of travel instead,
//!   and `bound.rs` does. (An earlier version used the true direction here too: a command
//!   across the vehicle's travel then gave v_c ≈ 0 and one behind it a reverse-thrust v_c, and
//!   a VideoRay flying the decomposition did not arrive, `hil/tests/autopilot.rs`.)
//! - **a_c.** The paper writes a_c = |F̄(k)|. As a surge acceleration command we take its
//!   component along ê₁, ⟨F̄, ê₁⟩, which equals |F̄| when the force is along the travel direction
//!   and has the right sign when it brakes.
//! - **α_c.** The paper calls r = ω/v a turning radius (it is a curvature, κ) and writes
//!   α_c = (r·a_c − v_c·ṙ)/r², the derivative of v/r. With κ = ω/v, the same derivative of
//!   ω = κ·v is α = κ·a + v·κ̇, which needs no division by r² and is exact on straight lines
//!   (κ = 0). κ̇ is (κ_c(k) − κ(k−1))/T. Below [`V_EPS`] the curvature is undefined and α_c is
//!   the rate of change of ω: (ω_c(k) − ω(k−1))/T.
//!
//!   *The discrete rate term, kept on purpose.* Read with R = 1/κ, a true radius, the paper's
//!   formula α = (R_c·a_c − v_c·(R_c − R)/T)/R_c² gives κ_c·a_c + v_c·(κ_c − κ)/T·(κ_c/κ): its
//!   rate term is ours times κ_c/κ. Both are first-order differences of the same derivative
//!   and agree as κ_c → κ (the unit test below checks it), but the paper's divides by κ, the
//!   measured curvature, which is zero on every straight line: it is infinite at the onset of
//!   every turn (R = ∞) and changes sign with κ. Ours is finite there and exact in the limit.
//! - **ω_c** is the rate at which the planned velocity turns, ω_c = (v̄ × F̄)/|v̄|² — the exact
//!   derivative of φ_c = arg v̄ under eq. 6's integration, of which the paper's
//!   [φ_c(k) − φ_c(k−1)]/T is the one-period difference. *Departure:* the
//!   difference is taken of a heading that jumps — when v̄ is small its direction swings by
//!   up to π in a period, and a guard's turn or a hold is a step — and a 90° step in one 0.1 s
//!   period asks a heading loop's derivative channel for 15 rad/s (what made the decomposition
//!   track worse than plain set-points, `hil/tests/autopilot.rs`). The derivative is bounded
//!   by the planner's own force bound (|F̄| ≤ F_max, so |ω_c| ≤ F_max/|v̄|), is 0 below
//!   [`V_EPS`], and is kept within `turn_rate_rps` when the craft's rate is given.
//! - **I_surge** is the along-track component ⟨p_c(k) − p(k), ê₁⟩, with p_c the
//!   double-integrator position integrated from the bounded command like 000 eq. 8: positive
//!   when the vehicle lags the ideal position. *Departure:* the paper writes the magnitude
//!   ‖p(k) − p_c(k)‖, which cannot tell an integral channel whether to push or hold back (a
//!   vehicle ahead and one behind give the same value); its along-track part is the time
//!   integral of the surge speed error the channel stands for. It is anti-wound: p_c is kept
//!   within [`I_SURGE_LIMIT_M`] of the vehicle, and restarts at the vehicle whenever the
//!   runtime sends something other than the plan (the guard turned, slowed or stopped it; a
//!   hold): an integral that wound up while the vehicle was held back would otherwise drive it
//!   at full thrust once released ([`SetpointState::restart_integral`]).

use crate::math::{wrap_angle, Vec2};
pub use crate::types::PidSetpoints;

/// Speed below which curvature and course are not computed from velocity, m/s.
pub const V_EPS: f32 = 0.05;
/// Largest integral error I_surge, m: beyond it the idealised position is dragged along.
pub const I_SURGE_LIMIT_M: f32 = 10.0;

/// What the decomposition remembers between periods.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SetpointState {
    /// φ_c(k−1), ω(k−1)'s course φ(k−1), and the ideal position p_c(k−1); `None` after a reset.
    prev: Option<Prev>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Prev {
    phi_c: f32,
    course: f32,
    v_cmd: Vec2,
    p_c: Vec2,
    /// The command sent was not the plan: p_c restarts at the vehicle.
    restart: bool,
}

/// The measured state the decomposition needs.
#[derive(Clone, Copy, Debug)]
pub struct Measured {
    /// Position p(k), m.
    pub position: Vec2,
    /// Velocity over ground v(k−1), m/s.
    pub velocity: Vec2,
    /// Compass heading, rad (the course when nearly stopped).
    pub heading: f32,
}

impl Measured {
    /// ê₁: the direction of travel, or the heading when nearly stopped.
    pub fn e1(&self) -> Vec2 {
        self.velocity
            .normalized(V_EPS)
            .unwrap_or_else(|| Vec2::from_angle(self.heading))
    }

    /// φ: the course over ground, or the heading when nearly stopped.
    fn course(&self) -> f32 {
        if self.velocity.norm2() > V_EPS * V_EPS {
            self.velocity.angle()
        } else {
            wrap_angle(self.heading)
        }
    }
}

impl SetpointState {
    /// Forgets the history (new mission, hold): the next step starts from the measured state.
    pub fn reset(&mut self) {
        self.prev = None;
    }

    /// The command that went out was not the plan (the guard changed it, or the speed was
    /// bounded): the idealised position restarts at the vehicle next step, so I_surge does not
    /// wind up while the vehicle is held back. The heading history is kept.
    pub fn restart_integral(&mut self) {
        if let Some(p) = &mut self.prev {
            p.restart = true;
        }
    }

    /// One period of the decomposition for the bounded force `f` and bounded velocity command
    /// `v_cmd` over period `t` s; `turn_rate_max` (rad/s, 0: none) bounds ω_c.
    pub fn decompose(
        &mut self,
        t: f32,
        f: Vec2,
        v_cmd: Vec2,
        m: &Measured,
        turn_rate_max: f32,
    ) -> PidSetpoints {
        let course = m.course();
        let prev = self.prev.unwrap_or(Prev {
            phi_c: course,
            course,
            v_cmd: m.velocity,
            p_c: m.position,
            restart: false,
        });
        // ê₁ of eq. 9: the previous command's direction (the measured one before there is
        // any, or while it is too slow to have one).
        let e1 = prev.v_cmd.normalized(V_EPS).unwrap_or_else(|| m.e1());
        let a_c = f.dot(e1);
        let v_c = v_cmd.dot(e1);
        // Heading command: keep the last one while the command has no direction.
        let phi_c = if v_cmd.norm2() > V_EPS * V_EPS {
            v_cmd.angle()
        } else {
            prev.phi_c
        };
        let omega_c = turn_rate(f, v_cmd, turn_rate_max);
        let omega = wrap_angle(course - prev.course) / t;
        let speed = m.velocity.norm();
        let alpha_c = if v_c.abs() > V_EPS && speed > V_EPS {
            let kappa_c = omega_c / v_c;
            let kappa = omega / speed;
            kappa_c * a_c + v_c * (kappa_c - kappa) / t
        } else {
            (omega_c - omega) / t
        };
        // Double integrator, bilinear like 000 eq. 8, held within the anti-windup limit.
        let start = if prev.restart { m.position } else { prev.p_c };
        let mut p_c = start + (v_cmd + prev.v_cmd) * (0.5 * t);
        let lag = p_c - m.position;
        p_c = m.position + lag.bounded(I_SURGE_LIMIT_M);
        self.prev = Some(Prev {
            phi_c,
            course,
            v_cmd,
            p_c,
            restart: false,
        });
        PidSetpoints {
            a_c,
            v_c,
            i_surge: (p_c - m.position).dot(e1),
            alpha_c,
            omega_c,
            phi_c,
        }
    }
}

/// ω_c: the rate at which the planned velocity `v` turns under the force `f`, (v × f)/|v|²
/// (module notes), 0 below [`V_EPS`], within ±`limit` when `limit` > 0.
fn turn_rate(f: Vec2, v: Vec2, limit: f32) -> f32 {
    let v2 = v.norm2();
    if v2 <= V_EPS * V_EPS {
        return 0.0;
    }
    let w = (v.x * f.y - v.y * f.x) / v2;
    if limit > 0.0 {
        crate::math::max(-limit, crate::math::min(w, limit))
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn straight_cruise_gives_no_turn_commands() {
        let mut s = SetpointState::default();
        let m = Measured {
            position: Vec2::ZERO,
            velocity: Vec2::new(1.0, 0.0),
            heading: 0.0,
        };
        for _ in 0..3 {
            let sp = s.decompose(0.1, Vec2::new(0.2, 0.0), Vec2::new(1.0, 0.0), &m, 0.0);
            assert_eq!((sp.omega_c, sp.alpha_c, sp.phi_c), (0.0, 0.0, 0.0));
            assert!((sp.v_c - 1.0).abs() < 1e-6 && (sp.a_c - 0.2).abs() < 1e-6);
        }
    }

    #[test]
    fn turning_command_gives_rate_and_acceleration() {
        let mut s = SetpointState::default();
        let m = Measured {
            position: Vec2::ZERO,
            velocity: Vec2::new(1.0, 0.0),
            heading: 0.0,
        };
        // Planned 1 m/s at 0.1 rad, pushed to port at 0.5 m/s²: it turns at 0.5 rad/s.
        let v = Vec2::from_angle(0.1);
        let f = Vec2::from_angle(0.1 + core::f32::consts::FRAC_PI_2) * 0.5;
        let sp = s.decompose(0.1, f, v, &m, 0.0);
        assert!((sp.omega_c - 0.5).abs() < 1e-4, "{sp:?}");
        assert!((sp.phi_c - 0.1).abs() < 1e-6);
        // κ_c = ω_c/v_c = 0.5, κ = 0, a_c ≈ 0: α_c = v_c·κ_c/T ≈ 5 rad/s².
        assert!((sp.alpha_c - 5.0).abs() < 0.1, "{sp:?}");
        // A heading step with no force behind it (the guard turned, v̄ swung) asks no rate;
        // a craft's rate bounds it.
        let mut s = SetpointState::default();
        let sp = s.decompose(0.1, Vec2::ZERO, Vec2::from_angle(1.5), &m, 0.0);
        assert_eq!(sp.omega_c, 0.0);
        let sp = s.decompose(0.1, f * 10.0, v, &m, 0.2);
        assert!((sp.omega_c - 0.2).abs() < 1e-6, "{sp:?}");
    }

    #[test]
    fn stopped_vehicle_has_finite_setpoints() {
        let mut s = SetpointState::default();
        let m = Measured {
            position: Vec2::ZERO,
            velocity: Vec2::ZERO,
            heading: 3.0,
        };
        let sp = s.decompose(0.1, Vec2::ZERO, Vec2::ZERO, &m, 0.0);
        assert!(
            [sp.a_c, sp.v_c, sp.i_surge, sp.alpha_c, sp.omega_c, sp.phi_c]
                .iter()
                .all(|x| x.is_finite())
        );
        assert!((sp.phi_c - 3.0).abs() < 1e-6);
    }

    #[test]
    fn integral_channel_is_anti_wound() {
        let mut s = SetpointState::default();
        let m = Measured {
            position: Vec2::ZERO,
            velocity: Vec2::ZERO,
            heading: 0.0,
        };
        let mut last = 0.0;
        for _ in 0..1000 {
            last = s
                .decompose(0.1, Vec2::ZERO, Vec2::new(1.0, 0.0), &m, 0.0)
                .i_surge;
        }
        assert!((last - I_SURGE_LIMIT_M).abs() < 1e-3);
        // Ahead of the ideal position (it stays behind at the start): negative.
        let mut s = SetpointState::default();
        let ahead = Measured {
            velocity: Vec2::new(1.0, 0.0),
            ..m
        };
        s.decompose(0.1, Vec2::ZERO, Vec2::ZERO, &ahead, 0.0);
        let moved = Measured {
            position: Vec2::new(0.5, 0.0),
            ..ahead
        };
        let sp = s.decompose(0.1, Vec2::ZERO, Vec2::ZERO, &moved, 0.0);
        // p_c moved 0.05 m (half a period at the initial 1 m/s), the vehicle 0.5 m.
        assert!((sp.i_surge + 0.45).abs() < 1e-5, "{sp:?}");
    }

    #[test]
    fn alpha_rate_term_agrees_with_the_papers_as_the_curvatures_meet() {
        // The paper's form with radii R = 1/κ against ours, for κ_c → κ (module notes).
        let (t, v_c, a_c, kappa) = (0.1f32, 1.0f32, 0.2f32, 0.05f32);
        for dk in [0.01f32, 0.001, 0.0001] {
            let kappa_c = kappa + dk;
            let ours = kappa_c * a_c + v_c * (kappa_c - kappa) / t;
            let (r_c, r) = (1.0 / kappa_c, 1.0 / kappa);
            let paper = (r_c * a_c - v_c * (r_c - r) / t) / (r_c * r_c);
            assert!(
                (ours - paper).abs() <= 1.5 * dk / kappa * ours.abs(),
                "{dk}"
            );
        }
        // On a straight line (κ = 0) the paper's form divides by zero; ours is finite.
        let mut s = SetpointState::default();
        let m = Measured {
            position: Vec2::ZERO,
            velocity: Vec2::new(1.0, 0.0),
            heading: 0.0,
        };
        let f = Vec2::new(0.0, 0.2);
        let sp = s.decompose(0.1, f, Vec2::from_angle(0.05), &m, 0.0);
        assert!(sp.alpha_c.is_finite() && sp.alpha_c > 0.0);
    }
}
