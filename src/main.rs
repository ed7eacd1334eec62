//! The firmware binary.
//!
//! - On `thumbv7em-none-eabihf` it is the board image: the guidance runtime on a Cortex-M4F
//!   (`firmware` module), with the board chosen by a cargo feature (`mps2-an386`, QEMU's
//!   emulated board, by default).
//! - On the host it is the same runtime as a process (`host` module), speaking the same serial
//!   protocol over stdio or a serial device / pty: what the HIL harness runs when there is no
//!   QEMU, and a way to try the firmware without any embedded tooling.
//!
//! The board image's entry point is the RTIC application in `firmware::app` (RTIC generates
//! `main`: start-up, then idle).
#![cfg_attr(target_os = "none", no_std, no_main)]
// Every `unsafe` in the firmware is an item that allows it, with its `# Safety` argument.
#![deny(unsafe_code)]

// The reset handler, vector table and linker script (RTIC's `main` is what it starts).
#[cfg(target_os = "none")]
use cortex_m_rt as _;

#[cfg(target_os = "none")]
mod board;
#[cfg(target_os = "none")]
mod firmware;
#[cfg(not(target_os = "none"))]
mod host;

/// Release builds link no panic handler body: any panic the optimiser could not prove
/// unreachable leaves a call to this undefined symbol, and the link fails, naming it.
#[cfg(all(target_os = "none", not(debug_assertions)))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    extern "Rust" {
        fn firmware_has_a_reachable_panic() -> !;
    }
    // # Safety
    // Never runs: the symbol is defined nowhere, so an image that could call it does not link.
    #[allow(unsafe_code)]
    unsafe {
        firmware_has_a_reachable_panic()
    }
}

/// Debug builds (never flashed for a mission): stop the board with a failure status.
#[cfg(all(target_os = "none", debug_assertions))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    board::active::exit(false)
}

#[cfg(not(target_os = "none"))]
fn main() -> std::process::ExitCode {
    host::main()
}
