//! The firmware built for a target: the host process, the emulated board's image, or nothing
//! for a real board (flashed by the user).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use super::Target;

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

/// Whether `qemu-system-arm` can be run here.
pub fn qemu_available() -> bool {
    Command::new("qemu-system-arm")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Builds the firmware for `target` (release) and returns the binary's path.
pub fn build(target: &Target) -> std::io::Result<PathBuf> {
    let root = workspace_root();
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(&root).args([
        "build",
        "--quiet",
        "--release",
        "-p",
        "vpf",
        "--bin",
        "vpf-firmware",
    ]);
    // Where cargo puts it: `CARGO_TARGET_DIR` if set (relative to the workspace), else target/.
    let target_dir = std::env::var_os("CARGO_TARGET_DIR")
        .filter(|d| !d.is_empty())
        .map_or_else(|| root.join("target"), |d| root.join(d));
    let path = match target {
        Target::Qemu | Target::QemuUart => {
            cmd.args(["--target", "thumbv7em-none-eabihf"]);
            target_dir.join("thumbv7em-none-eabihf/release/vpf-firmware")
        }
        Target::Host | Target::Port(..) => target_dir.join("release/vpf-firmware"),
    };
    if matches!(target, Target::Port(..)) {
        // A real board is flashed by the user; nothing to build here.
        return Ok(path);
    }
    let status = cmd.status()?;
    if !status.success() {
        return Err(std::io::Error::other("firmware build failed"));
    }
    Ok(path)
}
