//! The Blue Robotics Ping360 scanning sonar: a driver that steps its head and turns its
//! answers into the sonar module's [`Scanline`](super::Scanline)s.
//!
//! - [`config`]: [`Ping360Config`], what is asked of the sonar and how it is mounted;
//! - [`pool`]: samples to scanline bins as they stream in (no ping is ever buffered whole);
//! - [`driver`]: [`Ping360`], the command cycle, timeouts and counters.
//!
//! The wire format is [`crate::link::ping`]. The driver runs wherever bytes from the sonar's
//! serial port are read (the background context); the host-process firmware runs it
//! (`src/host.rs`, `--ping360 DEVICE`), and `OneThreadRuntime::with_ping360` wires it to the
//! extractor and the evidence map.

pub mod config;
pub mod driver;
pub mod pool;

pub use config::{ConfigError, Ping360Config, RAD_PER_GRAD};
pub use driver::{Ping360, Ping360Counters};
pub use pool::POOL_BINS;
