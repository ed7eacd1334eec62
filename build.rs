//! Puts the board's memory layout where the linker finds it, and links with cortex-m-rt's
//! `link.x`, for the embedded target only: host builds (tests, benches, the host-process
//! firmware) are untouched.
//!
//! `link.x` includes `memory.x`, and the linker resolves that in the package root first: the
//! top-level `memory.x` is therefore only `INCLUDE board-memory.x`, and this script copies the
//! chosen board's layout into OUT_DIR (on the search path) as `board-memory.x` (and as
//! `memory.x`, used when the linker runs elsewhere than the package root).
//! - `mps2-an386` (default): `boards/mps2-an386/memory.x`, and a `device.x` naming the handlers
//!   of the interrupt vector that `src/board/mps2_an386/device.rs` defines (RTIC defines the
//!   bound ones; the rest fall to cortex-m-rt's `DefaultHandler`).
//! - `stm32f4`: `boards/stm32f446re/memory.x`; the PAC (`stm32f4`, feature `rt`) supplies the
//!   interrupt vector and its own `device.x`, and defmt's `defmt.x` is linked.
use std::{env, fs, path::PathBuf};

const MEMORY: &str = "memory.x";
const MPS2_MEMORY: &str = "boards/mps2-an386/memory.x";
const STM32F446RE_MEMORY: &str = "boards/stm32f446re/memory.x";

fn main() {
    println!("cargo:rerun-if-changed={MEMORY}");
    println!("cargo:rerun-if-changed={MPS2_MEMORY}");
    println!("cargo:rerun-if-changed={STM32F446RE_MEMORY}");
    println!("cargo:rerun-if-changed=build.rs");
    let target = env::var("TARGET").unwrap_or_default();
    if !target.starts_with("thumbv") {
        return;
    }
    let stm32f4 = env::var_os("CARGO_FEATURE_STM32F4").is_some();
    let mps2 = env::var_os("CARGO_FEATURE_MPS2_AN386").is_some();
    // Both boards at once is a compile_error! in src/board/mod.rs; link nothing board-specific.
    if stm32f4 && mps2 {
        return;
    }
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let memory = if stm32f4 {
        STM32F446RE_MEMORY
    } else {
        MPS2_MEMORY
    };
    let mut layout = fs::read_to_string(memory).expect("the board's memory.x is in the package");
    // The self-test image carries its instrumentation and full-table loads on top of the flown
    // firmware; it runs only on the emulated board, whose code SSRAM is 4 MiB. The 128 KiB budget
    // is the flown image's, which `cargo fw` / `cargo fw-nucleo` (and .ci/sizes) still link at 128 KiB.
    if mps2 && env::var_os("CARGO_FEATURE_SELFTEST").is_some() {
        layout = layout.replace(
            "FLASH : ORIGIN = 0x00000000, LENGTH = 128K",
            "FLASH : ORIGIN = 0x00000000, LENGTH = 4M",
        );
    }
    // Also as OUT_DIR/memory.x, for a link whose working directory is not this package's root.
    for name in ["board-memory.x", "memory.x"] {
        fs::write(out.join(name), &layout).expect("OUT_DIR is writable");
    }
    // cortex-m-rt's `device` feature includes device.x; the MPS2 board's interrupt vector is
    // defined in Rust (src/board/mps2_an386/device.rs), so its device.x only names the handlers.
    if mps2 {
        fs::write(
            out.join("device.x"),
            "PROVIDE(UART0RX = DefaultHandler);\nPROVIDE(UART0TX = DefaultHandler);\n\
             PROVIDE(UART1RX = DefaultHandler);\nPROVIDE(UART1TX = DefaultHandler);\n\
             PROVIDE(UART2RX = DefaultHandler);\nPROVIDE(UART2TX = DefaultHandler);\nPROVIDE(ETHERNET = DefaultHandler);\n",
        )
        .expect("OUT_DIR is writable");
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    if stm32f4 {
        // defmt's log-string table (the linker script ships with the defmt crate).
        println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
    }
}
