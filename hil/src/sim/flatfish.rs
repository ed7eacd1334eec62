//! The flat-fish AUV of seed 003 (Saravanakumar, Thomas, Asokan, *Obstacle Avoidance Using
//! Multipoint Potential Field Approach for an Underactuated Flat-fish Type AUV in Dynamic
//! Environment*, CCIS 2012, §2): a 4.5 m, 1462 kg survey vehicle with two propulsion thrusters,
//! modelled in the horizontal plane (surge, sway, yaw) like the VideoRay: the same
//! [`TwinThruster`] dynamics, thruster allocation and PI-D autopilots, with the flat-fish's
//! [`FLATFISH`] parameters and [`FLATFISH_GAINS`].
//!
//! It is underactuated — nothing pushes it sideways; the two stern thrusters give a surge force
//! and, in differential, a yaw moment — and it is a much larger, slower-turning vehicle than
//! the VideoRay: it cruises at 1 m/s (the paper's constant forward speed) at about half thrust,
//! tops out at ≈ 1.42 m/s, and turns on a radius of ≈ 22 m (≈ 5 lengths) with its heading
//! autopilot at its limit, while the VideoRay turns on the spot.

use super::vehicle::{AutopilotGains, HullParams, ModelKind, PidGains, TwinThruster, VehicleModel};
use crate::types::{SetPoints, VehicleState, P2};

/// Length L of the flat-fish hull, m (seed 003 §2).
pub const FLATFISH_LENGTH_M: f64 = 4.5;
/// Width (beam) b of the flat-fish hull, m (seed 003 §2).
pub const FLATFISH_BEAM_M: f64 = 1.46;
/// Height h of the flat-fish hull, m (seed 003 §2).
pub const FLATFISH_HEIGHT_M: f64 = 0.634;
/// Its turning radius at the 1 m/s cruise with the heading autopilot at its yaw-moment limit,
/// m (≈ 0.046 rad/s; `it_turns_much_wider_and_slower_than_the_videoray` measures it). Its yaw
/// rate, not its radius, is what is bounded: at 0.5 m/s it turns on half of it.
pub const FLATFISH_TURN_RADIUS_M: f64 = 22.0;
/// Its largest steady yaw rate, rad/s: the yaw-moment limit (79 N·m) against N_r and N_r|r|.
pub const FLATFISH_TURN_RATE_RPS: f64 = 0.046;

/// The flat-fish AUV of seed 003 §2.
///
/// **From the paper:** L = 4.5 m, b = 1.46 m, h = 0.634 m, **m = 1462 kg**, I_x = 498.63,
/// I_y = 1850.34, **I_z = 2348.97 N·m·s²** (= kg·m²), r_G = (−22, 0, 0) mm, r_B = (−22, 0, −15)
/// mm, buoyancy 14391 N, two propulsion thrusters and three vertical manoeuvring thrusters. In
/// the horizontal plane only m, I_z and the two propulsion thrusters enter. The paper's body
/// origin is at the centre of mass, so r_G's 22 mm (0.5 % of L) is the offset from the hull's
/// mid-length; the coupling it would add to the inertia (m·x_G = −32 kg·m against m₂₂, m₃₃ of
/// ≈ 2300 and ≈ 3000) is neglected. The buoyancy exceeds the weight (1462 · 9.81 = 14342 N) by
/// 49 N; with pitch and depth held (the paper's planar case) it plays no part. Its displaced
/// volume, 14391 / (1025 · 9.81) = 1.43 m³, gives the hull's block coefficient
/// C_B = 1.43 / (L·b·h) = 0.34.
///
/// The paper gives no hydrodynamic coefficients (they are in Asokan's 2007 IIT Madras report,
/// its reference \[10\], which is not public), nor thruster data. Ours are estimates from the
/// hull's dimensions, with ρ = 1025 kg/m³:
///
/// - **Added mass X_u̇ = 138 kg, Y_v̇ = 858 kg, N_ṙ = 609 kg·m²**: the hull as the ellipsoid
///   with semi-axes a = L/2 = 2.25 m, b/2 = 0.73 m, h/2 = 0.317 m (ρV = 2236 kg), with Lamb's
///   potential-flow coefficients α₀ = 0.1165, β₀ = 0.5549 (γ₀ = 1.3286; the three sum to 2):
///   X_u̇ = α₀/(2 − α₀)·ρV, Y_v̇ = β₀/(2 − β₀)·ρV, and N_ṙ = ⅕·(a² − b²)²(β₀ − α₀) /
///   (2(a² − b²) − (a² + b²)(β₀ − α₀))·ρV — the triaxial generalisation (Lamb, *Hydrodynamics*,
///   1932, §§ 114–115) of the prolate-spheroid formulas of Imlay (1961) that Fossen, *Guidance
///   and Control of Ocean Vehicles*, 1994, §2.4.1 gives, with α₀ = abc∫₀^∞ dλ / ((a² + λ)Δ),
///   Δ = √((a² + λ)(b² + λ)(c² + λ)) (β₀, γ₀ likewise) integrated numerically.
/// - **Quadratic damping** from drag coefficients on the ellipsoid's projected areas (Fossen
///   1994 §2.4.2, X_u|u| = −½ρC_D A): **X_u|u| = −111.8 N·s²/m²** with C_D = 0.3 on the frontal
///   area π/4·b·h = 0.727 m² (a streamlined body of fineness L/√(bh) ≈ 4.7 has C_D ≈ 0.1 bare,
///   Hoerner, *Fluid-Dynamic Drag*, 1965, ch. 6; tripled for the thruster housings, sensors and
///   the flat, unfaired section); **Y_v|v| = −1148 N·s²/m²** with the cross-flow C_D = 1.0 of a
///   long body of rounded section on the lateral area π/4·L·h = 2.24 m²; **N_r|r| = −2221
///   N·m·s²**, the same cross-flow drag integrated along the hull, ½ρC_D∫h(x)|x|³dx with the
///   elliptic height profile h(x) = h√(1 − (2x/L)²), i.e. ½ρC_D·h·(4/15)(L/2)⁴.
/// - **Linear damping**: **Y_v = −528 N·s/m, N_r = −1625 N·m·s** are Clarke's regressions for
///   the linear manoeuvring derivatives (Clarke, Gedling, Hine, *The application of manoeuvring
///   criteria in hull design using linear theory*, Trans. RINA 125, 1983; in Fossen's
///   *Handbook of Marine Craft Hydrodynamics and Motion Control*, 2011, §6.4):
///   Y_v' = −π(T/L)²(1 + 0.40·C_B·b/T), N_r' = −π(T/L)²(¼ + 0.039·b/T − 0.56·b/L), scaled by
///   ½ρL²U and ½ρL⁴U at the cruise speed U = 1 m/s (the paper holds u at 1 m/s), for a ship of
///   draught T = h/2 and doubled (a deeply submerged hull is the ship and its mirror image).
///   This is an extrapolation: b/T = 4.6 and L/b = 3.1 lie outside the ships Clarke fitted.
///   **X_u = −11.2 N·s/m**: assumption, 10 % of the quadratic drag at 1 m/s (skin friction's
///   share at low speed, where the quadratic term vanishes).
/// - **Sway–yaw coupling left out** (as in the VideoRay model): Clarke's cross derivatives
///   (N_v = −974 N·s, Y_r = +225 N·m·s) or the ellipsoid's Munk moment (Y_v̇ − X_u̇)·U =
///   720 N·m·s per m/s of sway make this bare hull directionally unstable — at 1 m/s it would
///   spiral on a ≈ 8 m radius from a 20 N·m yaw moment — which the stern thrusters' ducts and
///   housings (working as fins) counter on the real vehicle by amounts we cannot estimate.
///   Without it the hull is neutral in yaw and the turning radius follows the yaw damping.
/// - **thrust_max = 120 N per thruster**: assumption, so that cruise at 1 m/s takes
///   11.2 + 111.8 = 123 N, 51 % of the 240 N of both thrusters, and the top speed is
///   ≈ 1.42 m/s (2.8 kn), in line with survey AUVs of this size (1–2 m/s).
/// - **arm = 0.73 m**: assumption, half the beam — the two propulsion thrusters at the stern
///   corners of the 1.46 m wide hull. The largest yaw moment is 2·0.73·120 = 175 N·m.
/// - **yaw_share = 0.45**: the heading autopilot may use 45 % of that (79 N·m), which leaves
///   240 − 79/0.73 = 132 N of surge force, enough for 1 m/s (123 N) in a turn: like the paper's
///   vehicle, it turns at cruise speed instead of stopping to turn. At that limit the steady
///   turn at 1 m/s is r ≈ 0.046 rad/s, a radius of ≈ 22 m (the tests measure it).
pub const FLATFISH: HullParams = HullParams {
    mass: 1462.0,
    iz: 2348.97,
    x_udot: 138.0,
    y_vdot: 858.0,
    n_rdot: 609.0,
    x_u: -11.2,
    y_v: -528.0,
    n_r: -1625.0,
    x_uu: -111.8,
    y_vv: -1148.0,
    n_rr: -2221.0,
    thrust_max: 120.0,
    arm: 0.73,
    yaw_share: 0.45,
};

/// Autopilot gains for [`FLATFISH`], tuned on this model (the tests below measure the step
/// responses).
///
/// Surge: m₁₁ = 1600 kg and a drag slope of ≈ 235 N·s/m at 1 m/s (open-loop time constant
/// ≈ 7 s); kp = 1000 N per m/s puts the linear closed-loop pole at ≈ 0.77 rad/s, ki = 150
/// removes the drag offset (ki/kp = 0.15 s⁻¹) without overshoot. From rest the thrust saturates
/// (240 N accelerate 1600 kg at 0.15 m/s²): 0 → 1 m/s rises (10–90 %) in ≈ 7.4 s and is within
/// 2 % after ≈ 15 s, without overshoot.
///
/// Heading: m₃₃ = 2958 kg·m², N_r = −1625 N·m·s; kp = 3000 N·m/rad and kd = 3000 N·m·s/rad give
/// ω ≈ 1.0 rad/s, ζ ≈ 0.78 in the linear range. The yaw moment saturates (79 N·m) above ≈ 1.5°
/// of error, so larger turns run at the steady turn rate (≈ 2.6 °/s at 1 m/s) and the
/// derivative term brakes them when kp·e falls below kd·r: a 90° turn at cruise overshoots by
/// ≈ 0.15°. ki = 20 trims the last hundredths of a degree (there is no steady yaw disturbance
/// in the model; a larger ki only adds overshoot).
pub const FLATFISH_GAINS: AutopilotGains = AutopilotGains {
    surge: PidGains {
        kp: 1000.0,
        ki: 150.0,
        kd: 0.0,
    },
    heading: PidGains {
        kp: 3000.0,
        ki: 20.0,
        kd: 3000.0,
    },
};

/// The flat-fish AUV: a [`TwinThruster`] with [`FLATFISH`] and [`FLATFISH_GAINS`].
#[derive(Clone, Debug)]
pub struct FlatFish(TwinThruster);

impl FlatFish {
    /// The flat-fish at rest at `start`, heading `heading` (rad).
    pub fn new(start: P2, heading: f64) -> Self {
        FlatFish::with_params(FLATFISH, FLATFISH_GAINS, start, heading)
    }

    /// A flat-fish with other parameters or gains (experiments), sanitised as
    /// [`TwinThruster::new`] says.
    pub fn with_params(params: HullParams, gains: AutopilotGains, start: P2, heading: f64) -> Self {
        FlatFish(TwinThruster::new(
            ModelKind::FlatFish,
            params,
            gains,
            start,
            heading,
        ))
    }

    /// Its parameters.
    pub fn params(&self) -> &HullParams {
        self.0.params()
    }

    /// Selects what its autopilots track ([`TwinThruster::set_autopilot`]).
    pub fn set_autopilot(&mut self, autopilot: crate::sim::vehicle::Autopilot) {
        self.0.set_autopilot(autopilot);
    }
}

impl VehicleModel for FlatFish {
    fn kind(&self) -> ModelKind {
        self.0.kind()
    }

    fn state(&self) -> VehicleState {
        self.0.state()
    }

    fn step(&mut self, dt: f64, sp: &SetPoints, current: P2) -> VehicleState {
        self.0.step(dt, sp, current)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::vehicle::{new_model, wrap_pi, VideoRay};
    use std::f64::consts::{FRAC_PI_2, PI};

    fn sp(psi: f64, speed: f64) -> SetPoints {
        SetPoints {
            psi,
            speed,
            velocity: P2::new(speed * psi.cos(), speed * psi.sin()),
            ..SetPoints::default()
        }
    }

    /// A flat-fish cruising at `speed` on heading 0 after `secs` seconds from rest.
    fn cruising(speed: f64, secs: f64) -> FlatFish {
        let mut m = FlatFish::new(P2::default(), 0.0);
        for _ in 0..(secs / 0.1).round() as usize {
            m.step(0.1, &sp(0.0, speed), P2::default());
        }
        m
    }

    #[test]
    fn parses_prints_and_builds() {
        for s in ["flatfish", "Flat-Fish", " flat_fish "] {
            assert_eq!(s.parse::<ModelKind>(), Ok(ModelKind::FlatFish), "{s}");
        }
        assert!("flat fish".parse::<ModelKind>().is_err());
        assert_eq!(ModelKind::FlatFish.to_string(), "flatfish");
        let m = new_model(
            ModelKind::FlatFish,
            P2::new(30.0, 20.0),
            0.5,
            Default::default(),
        );
        assert_eq!(m.kind(), ModelKind::FlatFish);
        assert_eq!(m.state().position, P2::new(30.0, 20.0));
        assert_eq!(m.state().heading, 0.5);
        assert_eq!(FlatFish::new(P2::default(), 0.0).params(), &FLATFISH);
    }

    #[test]
    fn reaches_and_holds_one_metre_per_second_at_about_half_thrust() {
        let mut m = FlatFish::new(P2::default(), 0.0);
        let dt = 0.1;
        let us: Vec<VehicleState> = (0..1200)
            .map(|_| m.step(dt, &sp(0.0, 1.0), P2::default()))
            .collect();
        // 10–90 % rise and the first time within 2 %.
        let t_at = |f: &dyn Fn(f64) -> bool| us.iter().position(|s| f(s.u)).unwrap() as f64 * dt;
        let rise = t_at(&|u| u >= 0.9) - t_at(&|u| u >= 0.1);
        let settle = us
            .iter()
            .rposition(|s| (s.u - 1.0).abs() > 0.02)
            .map_or(0.0, |i| (i + 1) as f64 * dt);
        let peak = us.iter().map(|s| s.u).fold(f64::MIN, f64::max);
        let last = us.last().unwrap();
        eprintln!(
            "flat-fish surge 0→1 m/s: rise {rise:.1} s, within 2 % after {settle:.1} s, peak \
             {peak:.4}, thrust {:.1} N",
            last.thrust
        );
        assert!(rise > 3.0 && rise < 12.0, "rise {rise}");
        assert!(settle < 20.0, "settle {settle}");
        assert!(peak < 1.02, "overshoot: {peak}");
        // Holds it: the last 60 s all within 0.5 %, straight ahead.
        for s in &us[600..] {
            assert!((s.u - 1.0).abs() < 0.005, "{s:?}");
            assert!(s.v.abs() < 1e-9 && s.position.y.abs() < 1e-6);
        }
        // Cruise thrust: the drag at 1 m/s, about half of the two thrusters' 240 N.
        let share = last.thrust / (2.0 * FLATFISH.thrust_max);
        assert!((last.thrust - 123.0).abs() < 1.0, "{}", last.thrust);
        assert!((0.45..=0.6).contains(&share), "{share}");
    }

    #[test]
    fn top_speed_is_about_1_4_m_s_at_full_thrust() {
        let s = cruising(3.0, 120.0).state();
        eprintln!("flat-fish top speed {:.3} m/s", s.u);
        assert!((s.u - 1.416).abs() < 0.01, "top speed {}", s.u);
        assert!((1.3..=2.0).contains(&s.u));
        assert!((s.thrust - 240.0).abs() < 1e-9, "full thrust {}", s.thrust);
    }

    #[test]
    fn heading_steps_settle_with_little_overshoot() {
        for (cruise, deg) in [
            (1.0, 90.0),
            (1.0, 20.0),
            (1.0, 170.0),
            (1.0, -45.0),
            (0.0, 90.0),
        ] {
            let mut m = cruising(cruise, 60.0);
            let start = m.state();
            let target = f64::to_radians(deg);
            let dt = 0.1;
            let psis: Vec<f64> = (0..1500)
                .map(|_| m.step(dt, &sp(target, cruise), P2::default()).heading)
                .collect();
            // Progress towards the target as a fraction of the step (1 = there).
            let frac = |p: f64| wrap_pi(p - start.heading) / target;
            let overshoot = psis.iter().map(|&p| frac(p)).fold(f64::MIN, f64::max) - 1.0;
            let settle = psis
                .iter()
                .rposition(|&p| (frac(p) - 1.0).abs() > 0.02)
                .map_or(0.0, |i| (i + 1) as f64 * dt);
            let last = *psis.last().unwrap();
            let min_u = m.state().u;
            eprintln!(
                "flat-fish heading 0→{deg}° at {cruise} m/s: overshoot {:.2} % ({:.2}°), within \
                 2 % after {settle:.1} s, final error {:.3}°, u at the end {min_u:.3}",
                overshoot.max(0.0) * 100.0,
                overshoot.max(0.0) * deg.abs(),
                wrap_pi(last - target).to_degrees()
            );
            assert!(overshoot < 0.10, "{deg}°: overshoot {overshoot}");
            // Slow (≈ 2.6 °/s at the limit) but it gets there and stays.
            assert!(settle < 100.0, "{deg}°: settle {settle}");
            assert!(
                wrap_pi(last - target).abs() < 0.2f64.to_radians(),
                "{deg}°: {last}"
            );
            if cruise > 0.0 {
                assert!((m.state().u - cruise).abs() < 0.01, "{:?}", m.state());
            }
        }
    }

    #[test]
    fn it_turns_much_wider_and_slower_than_the_videoray() {
        // Full "rudder": the heading set-point kept 1 rad ahead, so the heading autopilot sits
        // at its yaw-moment limit, at the 1 m/s cruise set-point.
        let mut m = cruising(1.0, 60.0);
        let (mut xs, mut ys) = (vec![], vec![]);
        let mut s = m.state();
        for k in 0..6000 {
            s = m.step(0.1, &sp(s.heading + 1.0, 1.0), P2::default());
            // After 200 s the turn is steady; the track from there is the turning circle.
            if k >= 2000 {
                xs.push(s.position.x);
                ys.push(s.position.y);
            }
        }
        let span = |v: &[f64]| {
            v.iter().copied().fold(f64::MIN, f64::max) - v.iter().copied().fold(f64::MAX, f64::min)
        };
        let radius = s.velocity.norm() / s.r;
        let (dx, dy) = (span(&xs), span(&ys));
        eprintln!(
            "flat-fish full turn at 1 m/s: u {:.3}, v {:.3}, r {:.4} rad/s ({:.2} °/s), radius \
             {radius:.1} m = {:.1} L; circle spans {dx:.1} × {dy:.1} m",
            s.u,
            s.v,
            s.r,
            s.r.to_degrees(),
            radius / FLATFISH_LENGTH_M
        );
        // Left turn (r > 0), skidding outward (v < 0), near cruise speed.
        assert!(s.r > 0.0 && s.v < 0.0, "{s:?}");
        assert!(s.u > 0.95, "slows too much: {s:?}");
        // A few vehicle lengths: 3.3 to 6.7 L; the constants the bench and the recipe use.
        assert!((15.0..=30.0).contains(&radius), "radius {radius}");
        assert!(
            (radius / FLATFISH_TURN_RADIUS_M - 1.0).abs() < 0.05,
            "{radius}"
        );
        assert!((s.r / FLATFISH_TURN_RATE_RPS - 1.0).abs() < 0.05, "{}", s.r);
        // The track agrees: 400 s at ≈ 0.046 rad/s is ≈ 3 full circles of diameter 2R.
        for d in [dx, dy] {
            assert!(
                (d - 2.0 * radius).abs() < 0.05 * 2.0 * radius,
                "{d} vs {radius}"
            );
        }

        // The VideoRay, under the same command, turns on a sub-metre radius.
        let mut v = VideoRay::new(P2::default(), 0.0);
        let mut sv = v.state();
        for _ in 0..600 {
            sv = v.step(0.1, &sp(sv.heading + 1.0, 1.0), P2::default());
        }
        assert!(sv.r > 5.0 * s.r, "VideoRay r {} vs flat-fish {}", sv.r, s.r);
    }

    #[test]
    fn turns_the_short_way_across_pi() {
        let mut m = FlatFish::new(P2::default(), 3.0);
        let mut min_abs = f64::MAX;
        for _ in 0..1000 {
            let s = m.step(0.1, &sp(-3.0, 1.0), P2::default());
            min_abs = min_abs.min(s.heading.abs());
        }
        assert!(min_abs > 2.9, "{min_abs}");
        assert!((m.state().heading + 3.0).abs() < 0.01, "{:?}", m.state());
    }

    #[test]
    fn odd_inputs_never_give_nan_and_stay_bounded() {
        let mut m = cruising(1.0, 20.0);
        let wild = [
            SetPoints {
                psi: f64::NAN,
                speed: f64::INFINITY,
                velocity: P2::new(f64::NAN, 0.0),
                pid: crate::types::PidFeeds {
                    a_c: f64::NAN,
                    v_c: f64::INFINITY,
                    i_surge: -1e30,
                    alpha_c: f64::NAN,
                    omega_c: f64::NEG_INFINITY,
                    phi_c: f64::NAN,
                },
            },
            sp(1e30, -1e30),
            sp(-PI, f64::NAN),
            sp(f64::NEG_INFINITY, 1e-300),
            sp(FRAC_PI_2, 20.0),
        ];
        for k in 0..500 {
            let dt = [0.1, 1e-9, 7.3, 0.0, f64::NAN][k % 5];
            let c = [P2::new(f64::NAN, 0.5), P2::new(1e9, -1e9), P2::default()][k % 3];
            let s = m.step(dt, &wild[k % wild.len()], c);
            for x in [
                s.position.x,
                s.position.y,
                s.heading,
                s.u,
                s.v,
                s.r,
                s.thrust,
            ] {
                assert!(x.is_finite(), "step {k}: {s:?}");
            }
            // Never faster through the water than full thrust allows (reverse included).
            assert!(
                s.u.abs() <= 1.42 && s.v.abs() < 1.0 && s.r.abs() < 0.2,
                "{s:?}"
            );
            assert!(s.thrust <= 240.0 + 1e-9);
        }
        // A NaN heading set-point holds the heading it has.
        let mut m = cruising(1.0, 30.0);
        let h0 = m.state().heading;
        for _ in 0..100 {
            m.step(0.1, &sp(f64::NAN, 1.0), P2::default());
        }
        assert!((m.state().heading - h0).abs() < 1e-6, "{:?}", m.state());
        // Garbage parameters are sanitised, not propagated.
        let bad = HullParams {
            mass: f64::NAN,
            iz: -5.0,
            x_uu: f64::INFINITY,
            yaw_share: f64::NAN,
            ..FLATFISH
        };
        let mut g = FlatFish::with_params(bad, FLATFISH_GAINS, P2::default(), 0.0);
        assert_eq!(g.params().yaw_share, 1.0);
        assert_eq!(g.params().iz, 5.0);
        assert_eq!(g.params().x_uu, 0.0);
        for _ in 0..100 {
            let s = g.step(0.1, &sp(1.0, 1.0), P2::default());
            assert!(s.position.x.is_finite() && s.heading.is_finite(), "{s:?}");
        }
    }
}
