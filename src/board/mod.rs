//! Board support: what differs between the emulated board and a real one. Target-only.
//!
//! A board provides RTIC's `device` (interrupt numbers and priority bits), its UART as
//! `embedded-io` byte streams, the period timer ([`systick::PeriodTimer`]), a cost counter for
//! the planner step, a watchdog, and a log channel; [`crate::firmware`] does the rest the same
//! way on every board.
//!
//! Exactly one board feature is on: `mps2-an386` (QEMU, the default) or `stm32f4` (the
//! NUCLEO-F446RE; build with `--no-default-features --features stm32f4`).

#[cfg(all(feature = "mps2-an386", feature = "stm32f4"))]
compile_error!(
    "features `mps2-an386` and `stm32f4` both select a board: build the NUCLEO-F446RE image with \
     `--no-default-features --features stm32f4` (or `cargo fw-nucleo`)"
);
#[cfg(not(any(feature = "mps2-an386", feature = "stm32f4")))]
compile_error!(
    "no board selected: enable feature `mps2-an386` (the default) or `stm32f4` for the firmware"
);

pub mod systick;

// With both on, only the compile_error! above is reported (stm32f4 stands in as `active`).
#[cfg(all(feature = "mps2-an386", not(feature = "stm32f4")))]
pub mod mps2_an386;
#[cfg(all(feature = "mps2-an386", not(feature = "stm32f4")))]
pub use mps2_an386 as active;

#[cfg(feature = "stm32f4")]
pub mod stm32f4;
#[cfg(feature = "stm32f4")]
pub use stm32f4 as active;
