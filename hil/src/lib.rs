//! `hil`: the host-side hardware-in-the-loop harness for the VPF guidance firmware.
//!
//! It simulates one or more vehicles and their sonars, connects to one firmware instance per
//! vehicle over a serial link (a pty to QEMU or to the host-process firmware, or a real serial
//! port), runs a scenario, and leaves a trajectory log, metrics and a plot.
//!
//! Rooms:
//! - [`types`]: the plain data shared by the rooms (poses, vehicle states, time);
//! - [`scenario`]: the TOML scenario schema, validated with file/line/key errors;
//! - [`sim`]: vehicle models (kinematic, VideoRay Pro 3-DOF) with autopilots, ocean current,
//!   navigation noise, and the mechanically scanned sonar;
//! - [`output`]: trajectory CSV, metrics JSON, SVG plots, the frame log;
//! - [`firmware`]: building, starting and talking to a firmware (QEMU, host process, board);
//! - [`faults`]: link faults (bit errors, dropped frames) and the frame-log tap;
//! - [`runner`]: the lockstep / real-time loop that ties the rest together;
//! - [`error`]: the commands' errors;
//! - [`compare`]: the same scenarios flown with each guidance strategy, side by side;
//! - [`sweep`]: parameter tuning sweeps over scenario batches, and their recipes (seed 002);
//! - [`beliefs`]: what the firmware believed at given moments of a run, from its frame log.

pub mod beliefs;
pub mod bench;
pub mod campaign;
pub mod compare;
pub mod echoes;
pub mod error;
pub mod faults;
pub mod firmware;
pub mod output;
pub mod ping360;
pub mod runner;
pub mod scenario;
pub mod sim;
pub mod sweep;
pub mod types;
pub mod upload;
