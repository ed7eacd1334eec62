//! Terminals and waits: ptys, a real serial port, raw mode, the ptys QEMU names, and a read
//! wait bounded by `poll` — without unsafe blocks but one (the serial port's descriptor).

use std::fs::File;
use std::os::fd::{AsFd, FromRawFd};
use std::path::{Path, PathBuf};
use std::time::Duration;

use nix::errno::Errno;
use nix::poll::{poll, PollFd, PollFlags, PollTimeout};
use nix::sys::termios;

/// Whether `f` has something to read within `ms` (negative: no limit); an interrupted wait
/// counts as nothing yet.
pub fn readable(f: &impl AsFd, ms: i32) -> std::io::Result<bool> {
    let mut fds = [PollFd::new(f.as_fd(), PollFlags::POLLIN)];
    let timeout = PollTimeout::try_from(ms).unwrap_or(PollTimeout::NONE);
    match poll(&mut fds, timeout) {
        Ok(n) => Ok(n > 0),
        Err(Errno::EINTR) => Ok(false),
        Err(e) => Err(e.into()),
    }
}

/// Puts a terminal in raw mode (no echo, no line discipline). Reads block until a byte comes
/// (VMIN = 1): the firmware reading the slave side must not mistake a quiet line for the end of
/// input; this side bounds its own waits with `poll`.
fn make_raw(f: &impl AsFd) -> std::io::Result<()> {
    let mut t = termios::tcgetattr(f)?;
    termios::cfmakeraw(&mut t);
    termios::cfsetspeed(&mut t, termios::BaudRate::B115200)?;
    t.control_chars[termios::SpecialCharacterIndices::VMIN as usize] = 1;
    t.control_chars[termios::SpecialCharacterIndices::VTIME as usize] = 0;
    termios::tcsetattr(f, termios::SetArg::TCSANOW, &t)?;
    Ok(())
}

/// A real serial port at `baud`, 8N1, raw, through `serialport` (exclusive, as a real port
/// should be), as a plain file: reads are bounded by `poll` like a pty's.
pub fn open_serial(path: &Path, baud: u32) -> std::io::Result<File> {
    use std::os::fd::IntoRawFd;
    let port = serialport::new(path.to_string_lossy(), baud)
        .timeout(Duration::from_millis(10))
        .open_native()
        .map_err(|e| std::io::Error::other(format!("{}: {e}", path.display())))?;
    // SAFETY: the descriptor was just released by its owner, the serial port, and is ours.
    Ok(unsafe { File::from_raw_fd(port.into_raw_fd()) })
}

/// The next pty QEMU names on its monitor ("char device redirected to /dev/pts/N (label
/// serialK)", in the order of the `-serial`s that are ptys); lines before it are skipped.
pub(super) fn qemu_pty(
    lines: &mut impl Iterator<Item = std::io::Result<String>>,
) -> std::io::Result<String> {
    loop {
        let Some(line) = lines.next() else {
            return Err(std::io::Error::other("qemu exited before naming its ptys"));
        };
        let line = line?;
        if let Some(i) = line.find("/dev/pts/") {
            let path = line[i..].split_whitespace().next().unwrap_or_default();
            return Ok(path.to_string());
        }
    }
}

/// A pty (or device) opened for reading and writing, raw.
pub(super) fn open_raw(path: &str) -> std::io::Result<File> {
    let port = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)?;
    make_raw(&port)?;
    Ok(port)
}

/// A new pseudo-terminal pair: (master, slave path). The slave stays open (leaked) so that no
/// byte written before its user opens it is lost.
pub fn open_pty() -> std::io::Result<(File, PathBuf)> {
    let pty = nix::pty::openpty(None, None)?;
    make_raw(&pty.slave)?;
    make_raw(&pty.master)?;
    let path = nix::unistd::ttyname(&pty.slave)?;
    // The slave stays open here until the firmware has it, so no byte is lost meanwhile.
    std::mem::forget(pty.slave);
    Ok((File::from(pty.master), path))
}
