//! The firmware binary.
//!
//! - On `thumbv7em-none-eabihf` it is the board image: the guidance runtime on a Cortex-M4F
//!   (`firmware` module), with the board chosen by a cargo feature (`mps2-an386`, QEMU's
//!   emulated board, by default).
//! - On the host it is the same runtime as a process (`host` module), speaking the same serial
//!   protocol over stdio or a serial device / pty: what the HIL harness runs when there is no
//!   QEMU, and a way to try the firmware without any embedded tooling.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod board;
#[cfg(target_os = "none")]
mod firmware;
#[cfg(not(target_os = "none"))]
mod host;

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    use board::active as board;
    board::log(concat!("vpf-firmware ", env!("CARGO_PKG_VERSION"), "\n").as_bytes());
    let Some(cp) = cortex_m::Peripherals::take() else {
        board::exit(false)
    };
    let Some(mut idle) = firmware::init(vpf::Params::default()) else {
        board::exit(false)
    };
    board::init(cp);
    firmware::start();
    #[cfg(feature = "selftest")]
    firmware::selftest::run(&mut idle, vpf::Params::default());
    #[cfg(not(feature = "selftest"))]
    loop {
        if !idle.poll() {
            cortex_m::asm::wfi();
        }
    }
}

/// Release builds link no panic handler body: any panic the optimiser could not prove
/// unreachable leaves a call to this undefined symbol, and the link fails, naming it.
#[cfg(all(target_os = "none", not(debug_assertions)))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    extern "Rust" {
        fn firmware_has_a_reachable_panic() -> !;
    }
    // SAFETY: never linked; see above.
    unsafe { firmware_has_a_reachable_panic() }
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
