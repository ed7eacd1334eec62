//! The firmware entry point. Placeholder until the runtime issue: prints its version and exits.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod target {
    use cortex_m_rt::entry;
    use cortex_m_semihosting::{debug, hio};

    #[entry]
    fn main() -> ! {
        // Raw bytes, not `hprintln!`: core::fmt carries panicking paths the link check refuses.
        if let Ok(mut out) = hio::hstdout() {
            let _ =
                out.write_all(concat!("vpf-firmware ", env!("CARGO_PKG_VERSION"), "\n").as_bytes());
        }
        debug::exit(debug::EXIT_SUCCESS);
        loop {
            cortex_m::asm::wfi();
        }
    }

    /// Release builds link no panic handler body: any panic the optimiser could not prove
    /// unreachable leaves a call to this undefined symbol, and the link fails, naming it.
    #[cfg(not(debug_assertions))]
    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo) -> ! {
        extern "Rust" {
            fn firmware_has_a_reachable_panic() -> !;
        }
        // SAFETY: never linked; see above.
        #[allow(unsafe_code)]
        unsafe {
            firmware_has_a_reachable_panic()
        }
    }

    #[cfg(debug_assertions)]
    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo) -> ! {
        debug::exit(debug::EXIT_FAILURE);
        loop {
            cortex_m::asm::wfi();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    println!("vpf-firmware {} (host build)", env!("CARGO_PKG_VERSION"));
}
