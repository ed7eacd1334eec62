//! `hil`: the host-side hardware-in-the-loop harness.
//!
//! This crate is a placeholder until the HIL issue lands: it links the planner library and says
//! what it will do, so the workspace layout is fixed from the start.

fn main() {
    println!(
        "hil {}: the HIL harness is not built yet; run `cargo test` for the planner's experiments",
        env!("CARGO_PKG_VERSION")
    );
}
