//! The Ping360 on the harness side: text dumps of real recordings (`dump`), the replay of raw
//! Ping bytes through the firmware's parser and extractor (`replay`, `hil sonar-replay`), and
//! the simulated Ping360 the runner puts on its own pty (`sim`).

pub mod dump;
pub mod replay;
pub mod sim;
