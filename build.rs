//! Puts `memory.x` where cortex-m-rt's `link.x` finds it, and links with it, for the embedded
//! target only: host builds (tests, benches, the host-process firmware) are untouched.
use std::{env, fs, path::PathBuf};

fn main() {
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rerun-if-changed=build.rs");
    let target = env::var("TARGET").unwrap_or_default();
    if !target.starts_with("thumbv") {
        return;
    }
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    fs::copy("memory.x", out.join("memory.x")).expect("memory.x is at the package root");
    // cortex-m-rt's `device` feature includes device.x; the MPS2 board's interrupt vector is
    // defined in Rust (src/firmware/mps2), so its device.x only names the handlers.
    if env::var_os("CARGO_FEATURE_MPS2_AN386").is_some() {
        fs::write(
            out.join("device.x"),
            "PROVIDE(UART0RX = DefaultHandler);\nPROVIDE(UART0TX = DefaultHandler);\n",
        )
        .expect("OUT_DIR is writable");
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
}
