//! The simulated world: vehicles, the water they move in, and what their sensors report.
//!
//! - [`geometry`]: ground truth of the obstacles — position at time t (moving obstacles
//!   translate with their velocity), signed distance, ray casting, and the firmware's `f32`
//!   [`Shape`](vpf::field::Shape);
//! - [`vehicle`]: the [`VehicleModel`] trait and its models, chosen by [`ModelKind`]: the
//!   kinematic vehicle of seed 000 (eq. 8) and the 3-DOF twin-thruster model with PI-D
//!   surge-speed and heading autopilots ([`TwinThruster`]), as a VideoRay Pro III (Wang's
//!   identified coefficients);
//! - [`flatfish`]: the same twin-thruster model as seed 003's 4.5 m flat-fish AUV (its mass and
//!   inertia, estimated hydrodynamics);
//! - [`current`]: the ocean current the models drift in;
//! - [`nav`]: the navigation sensor — the firmware's `NavState` from the truth, with seeded
//!   Gaussian noise at a fixed rate, sample-and-hold;
//! - [`sonar`]: a Tritech Micron-like mechanically scanned sonar producing the firmware's
//!   scanlines ([`Ping`]);
//! - [`contacts`]: pre-extracted contacts for scenarios that bypass the sonar;
//! - [`rng`]: the seeded generator behind every noise source.
//!
//! Everything is deterministic: the same configuration, seeds and call sequence give the same
//! output, bit for bit. No function panics on odd input (NaN, infinities, negative sizes,
//! empty polygons): each documents how it validates or clamps.
//!
//! A runner's period, per vehicle, is typically:
//!
//! ```
//! use hil::sim::{new_model, Autopilot, Current, ModelKind, NavConfig, NavSensor, Sonar, SonarConfig};
//! use hil::types::{SetPoints, P2};
//!
//! let mut vehicle = new_model(ModelKind::VideoRay, P2::new(0.0, 0.0), 0.0, Autopilot::Plain);
//! let mut nav = NavSensor::new(NavConfig { rate_hz: 5.0, ..NavConfig::default() });
//! let mut sonar = Sonar::new(SonarConfig::default());
//! let current = Current::steady(P2::new(0.1, 0.0));
//! let set_points = SetPoints { psi: 0.5, speed: 1.0, ..SetPoints::default() };
//! let (mut t, dt) = (0.0, 0.1);
//! for _ in 0..10 {
//!     let state = vehicle.step(dt, &set_points, current.at(t));
//!     t += dt;
//!     let fix = nav.sample(t, &state); // → the firmware's NavState
//!     let pings = sonar.poll(t, &state, &[], &[]); // → scanlines
//!     assert!(fix.validate().is_ok() && pings.iter().all(|p| p.as_scanline().validate().is_ok()));
//! }
//! ```

pub mod contacts;
pub mod current;
pub mod flatfish;
pub mod geometry;
pub mod nav;
pub mod rng;
pub mod sonar;
pub mod vehicle;

pub use contacts::{contacts, OtherVehicle};
pub use current::Current;
pub use flatfish::{FlatFish, FLATFISH, FLATFISH_GAINS};
pub use nav::{NavConfig, NavSensor};
pub use rng::Rng;
pub use sonar::{relative_bearing, Ping, Sector, Sonar, SonarConfig, SonarConfigError};
pub use vehicle::{
    new_model, wrap_pi, Autopilot, AutopilotGains, HullParams, Kinematic, ModelKind, PidGains,
    TwinThruster, UnknownModel, VehicleModel, VideoRay, VideoRayParams, VIDEORAY_PRO3,
    VIDEORAY_PRO3_GAINS,
};
