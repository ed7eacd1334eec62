//! Board support: what differs between the emulated board and a real one. Target-only.
//!
//! A board provides the UART, the period timer, a cost counter for the planner step, a
//! watchdog, and a log channel; [`crate::firmware`] does the rest the same way on every board.

#[cfg(feature = "mps2-an386")]
pub mod mps2_an386;
#[cfg(feature = "mps2-an386")]
pub use mps2_an386 as active;
