//! # vpf — virtual potential field guidance for AUVs
//!
//! A `#![no_std]`, heap-free, panic-free implementation of the virtual potential field (VPF)
//! trajectory planner of Barisic, Vukic and Miskovic (seed papers 000 and 001 in
//! `shared/seeds/`), for a Cortex-M4F and for host tests alike.
//!
//! Module map (one concept each):
//! - [`math`]: `Vec2`, angles, the hot-path `exp`, a seeded generator;
//! - [`params`]: the validated parameter set with the papers' names;
//! - [`field`]: potential distribution functions — obstacle shapes, stator, rotor, goal-point;
//! - [`types`]: the value types the planner, the link and the runtime share — navigation state,
//!   missions, the command, a scanline, the step error;
//! - [`world`]: fixed-capacity obstacle and agent tables, ageing, overflow policy;
//! - [`planner`]: the planner step — sampled gradient, friction, bounding, integration,
//!   PI-D set-points, ghost goal-points, virtual-leader formation;
//! - [`sonar`]: mechanically scanned sonar scanlines to obstacle features and the evidence map;
//!   the Ping360 driver (`sonar::ping360`);
//! - [`route`]: the background route layer — a wavefront over a coarse grid of what is
//!   believed, handing the planner its next intermediate goal-point;
//! - [`link`]: the serial link's wire format (coded and COBS frames, CRC, messages;
//!   `docs/protocol.md`),
//!   and Blue Robotics' Ping protocol (`link::ping`);
//! - [`guidance`]: the hardware-independent runtime — periodic task, background decoding and
//!   extraction, fail-safes, telemetry — that the firmware and the host process run.
//!
//! Time is always an argument (milliseconds since boot); nothing here reads a clock.

#![no_std]
#![deny(unsafe_code)]
// A full table hands the caller's value back in `Err` (the heapless convention); with no heap
// there is nothing to box it in, and the copy is a few hundred bytes at most.
#![allow(clippy::result_large_err)]
#![warn(missing_docs)]
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing,
        clippy::unreachable,
        clippy::todo,
        clippy::unimplemented,
    )
)]

pub mod field;
pub mod guidance;
pub mod link;
pub mod math;
pub mod params;
pub mod planner;
pub mod route;
pub mod sonar;
pub mod types;
pub mod world;

pub use math::Vec2;
pub use params::{Bounding, ParamError, Params, Strategy};
pub use planner::{Command, Mission, Mode, NavState, Planner, StepError};
pub use world::{Agent, Obstacle, Origin, World};
