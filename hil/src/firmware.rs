//! One firmware instance and the serial link to it: QEMU's emulated board on a pty, the
//! host-process firmware on a pty, or a real board on a serial device.
//!
//! Frames go out whole (`send`); what comes back is decoded with the firmware's own stream
//! decoder and kept as owned [`Reply`]s. A [`Tap`] sees every chunk both ways (the frame log)
//! and may corrupt or drop outgoing frames (fault injection).

use std::fs::File;
use std::io::{BufRead, BufReader, Read, Write};
use std::os::fd::{AsRawFd, FromRawFd};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use vpf::link::{
    CommandRepr, Decoder, Direction, Message, Outcome, ReplyRepr, TelemetryRepr, MAX_FRAME,
};

/// Which firmware to run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Target {
    /// The release firmware on QEMU's emulated Cortex-M4 (`mps2-an386`).
    Qemu,
    /// The same runtime built for the host, as a process.
    Host,
    /// A real board on a serial device, at a baud rate.
    Port(PathBuf, u32),
}

/// The boards' control link's baud rate (`--port`'s default).
pub const PORT_BAUD: u32 = 115_200;

impl std::fmt::Display for Target {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Target::Qemu => f.write_str("qemu"),
            Target::Host => f.write_str("host"),
            Target::Port(p, baud) => write!(f, "port:{} ({baud} baud)", p.display()),
        }
    }
}

/// Something the firmware sent, owned.
#[derive(Clone, Debug, PartialEq)]
pub enum Reply {
    /// A period's command.
    Command(CommandRepr),
    /// Telemetry.
    Telemetry(TelemetryRepr),
    /// A reply to a request.
    Reply(ReplyRepr),
    /// A log line.
    Log(String),
    /// A chunk of the evidence map.
    Belief(crate::output::belief::Chunk),
}

/// Sees the traffic: logs it, and may alter outgoing frames (faults).
pub trait Tap {
    /// An outgoing frame; return what to actually send (possibly corrupted), or `None` to drop.
    fn outgoing(&mut self, frame: &[u8]) -> Option<Vec<u8>>;
    /// Bytes that came back.
    fn incoming(&mut self, bytes: &[u8]);
}

/// A tap that changes nothing and logs nothing.
pub struct NoTap;

impl Tap for NoTap {
    fn outgoing(&mut self, frame: &[u8]) -> Option<Vec<u8>> {
        Some(frame.to_vec())
    }
    fn incoming(&mut self, _: &[u8]) {}
}

/// A running firmware and its link.
pub struct Firmware {
    child: Option<Child>,
    port: File,
    decoder: Decoder,
    seq: u16,
    inbox: Vec<Reply>,
    /// Outgoing bytes held back until the next receive (see [`Firmware::set_batching`]).
    batch: Option<Vec<u8>>,
    /// QEMU's second serial port (the board's Ping360 UART), opened raw, until taken.
    sonar_port: Option<File>,
    /// What runs.
    pub target: Target,
}

impl Drop for Firmware {
    fn drop(&mut self) {
        if let Some(c) = self.child.as_mut() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

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
        Target::Qemu => {
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

/// Puts a terminal in raw mode (no echo, no line discipline). Reads block until a byte comes
/// (VMIN = 1): the firmware reading the slave side must not mistake a quiet line for the end of
/// input; this side bounds its own waits with `poll`.
fn make_raw(f: &File) -> std::io::Result<()> {
    // SAFETY: termios calls on a descriptor we own.
    unsafe {
        let mut t: libc::termios = std::mem::zeroed();
        if libc::tcgetattr(f.as_raw_fd(), &mut t) != 0 {
            return Err(std::io::Error::last_os_error());
        }
        libc::cfmakeraw(&mut t);
        libc::cfsetispeed(&mut t, libc::B115200);
        libc::cfsetospeed(&mut t, libc::B115200);
        t.c_cc[libc::VMIN] = 1;
        t.c_cc[libc::VTIME] = 0;
        if libc::tcsetattr(f.as_raw_fd(), libc::TCSANOW, &t) != 0 {
            return Err(std::io::Error::last_os_error());
        }
    }
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

/// A new pseudo-terminal pair: (master, slave path). The slave stays open (leaked) so that no
/// byte written before its user opens it is lost.
pub fn open_pty() -> std::io::Result<(File, PathBuf)> {
    let (mut master, mut slave) = (0, 0);
    // SAFETY: openpty writes two descriptors we then own; the name buffer is large enough.
    let mut name = [0 as libc::c_char; 128];
    let rc = unsafe {
        libc::openpty(
            &mut master,
            &mut slave,
            name.as_mut_ptr(),
            std::ptr::null(),
            std::ptr::null(),
        )
    };
    if rc != 0 {
        return Err(std::io::Error::last_os_error());
    }
    // SAFETY: both descriptors are fresh and ours.
    let (master, slave) = unsafe { (File::from_raw_fd(master), File::from_raw_fd(slave)) };
    make_raw(&slave)?;
    make_raw(&master)?;
    // SAFETY: openpty wrote a NUL-terminated name.
    let path = unsafe { std::ffi::CStr::from_ptr(name.as_ptr()) }
        .to_string_lossy()
        .into_owned();
    // The slave stays open here until the firmware has it, so no byte is lost meanwhile.
    std::mem::forget(slave);
    Ok((master, PathBuf::from(path)))
}

impl Firmware {
    /// Starts `target` (built binary at `binary` for QEMU and host) and connects to it.
    /// `lockstep`: the host will drive time with `Tick`s (QEMU then need not pace its virtual
    /// clock with the wall clock while the firmware waits).
    /// `extra`: more arguments for the host-process firmware (its Ping360 port); refused for
    /// the others, which take none.
    pub fn start(
        target: &Target,
        binary: &Path,
        lockstep: bool,
        extra: &[std::ffi::OsString],
    ) -> std::io::Result<Self> {
        if !extra.is_empty() && *target != Target::Host {
            return Err(std::io::Error::other(format!(
                "the {target} firmware takes no arguments (QEMU's Ping360 port is its second serial port: `Firmware::start_qemu`)"
            )));
        }
        match target {
            Target::Qemu => Self::start_qemu(binary, lockstep, false),
            Target::Host => Self::start_host(binary, extra),
            Target::Port(path, baud) => {
                let port = open_serial(path, *baud)?;
                Ok(Self::new(None, port, target.clone()))
            }
        }
    }

    fn new(child: Option<Child>, port: File, target: Target) -> Self {
        Firmware {
            child,
            port,
            decoder: Decoder::accepting(Direction::ToHost),
            seq: 0,
            inbox: Vec::new(),
            batch: None,
            sonar_port: None,
            target,
        }
    }

    /// The board's Ping360 port (QEMU's second serial port, when started with one), once.
    pub fn take_sonar_port(&mut self) -> Option<File> {
        self.sonar_port.take()
    }

    /// QEMU, paused with `-S` until the pty is open (bytes sent before would be lost), with
    /// `-icount shift=0` so the firmware's step costs are instruction counts. In lockstep,
    /// `sleep=off` lets the virtual clock jump over the firmware's idle waits instead of
    /// sleeping them out in real time (a period's round trip drops from ~19 ms to ~5 ms).
    /// With `sonar`, the board's UART1 (its Ping360 port) is a second pty
    /// ([`Firmware::take_sonar_port`]).
    pub fn start_qemu(elf: &Path, lockstep: bool, sonar: bool) -> std::io::Result<Self> {
        let icount = if lockstep {
            "shift=0,sleep=off"
        } else {
            "shift=0"
        };
        let serials: &[&str] = if sonar {
            &["-serial", "pty", "-serial", "pty"]
        } else {
            &["-serial", "pty"]
        };
        let mut child = Command::new("qemu-system-arm")
            .args(["-machine", "mps2-an386", "-cpu", "cortex-m4", "-nographic"])
            .args(serials)
            .args(["-monitor", "stdio", "-S", "-icount", icount])
            .args(["-semihosting-config", "enable=on,target=native", "-kernel"])
            .arg(elf)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()?;
        let stdout = child
            .stdout
            .take()
            .ok_or_else(|| std::io::Error::other("no qemu stdout"))?;
        let mut lines = BufReader::new(stdout).lines();
        // QEMU names each pty on its monitor, in the order of the `-serial`s:
        // "char device redirected to /dev/pts/N (label serial0)", then serial1.
        let mut paths = Vec::new();
        while paths.len() < serials.len() / 2 {
            let Some(line) = lines.next() else {
                return Err(std::io::Error::other("qemu exited before naming its ptys"));
            };
            let line = line?;
            if let Some(i) = line.find("/dev/pts/") {
                // At most two lines are kept: a bounded read of QEMU's output.
                paths.push(
                    line[i..]
                        .split_whitespace()
                        .next()
                        .unwrap_or_default()
                        .to_string(),
                );
            }
        }
        std::thread::spawn(move || for _ in lines.map_while(Result::ok) {});
        let open_raw = |path: &str| -> std::io::Result<File> {
            let port = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .open(path)?;
            make_raw(&port)?;
            Ok(port)
        };
        let port = open_raw(&paths[0])?;
        let sonar_port = match paths.get(1) {
            Some(p) => Some(open_raw(p)?),
            None => None,
        };
        let mut stdin = child
            .stdin
            .take()
            .ok_or_else(|| std::io::Error::other("no qemu stdin"))?;
        stdin.write_all(b"cont\n")?;
        stdin.flush()?;
        std::mem::forget(stdin); // the monitor stays open while QEMU runs
        let mut fw = Self::new(Some(child), port, Target::Qemu);
        fw.sonar_port = sonar_port;
        Ok(fw)
    }

    /// The host-process firmware speaking on its stdin/stdout, both one end of a Unix socket
    /// pair whose other end is the link: no pty and no line discipline in between (the sweep's
    /// link: a period's round trip is faster than through a pty, see `hil/sweeps/README.md`).
    pub fn start_host_socket(bin: &Path, extra: &[std::ffi::OsString]) -> std::io::Result<Self> {
        let (ours, theirs) = std::os::unix::net::UnixStream::pair()?;
        let theirs_out = theirs.try_clone()?;
        let child = Command::new(bin)
            .args(extra)
            .stdin(Stdio::from(std::os::fd::OwnedFd::from(theirs)))
            .stdout(Stdio::from(std::os::fd::OwnedFd::from(theirs_out)))
            .stderr(Stdio::null())
            .spawn()?;
        let port = File::from(std::os::fd::OwnedFd::from(ours));
        Ok(Self::new(Some(child), port, Target::Host))
    }

    /// The host-process firmware on the slave side of a fresh pty.
    fn start_host(bin: &Path, extra: &[std::ffi::OsString]) -> std::io::Result<Self> {
        let (master, slave) = open_pty()?;
        let child = Command::new(bin)
            .arg("--device")
            .arg(&slave)
            .args(extra)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()?;
        Ok(Self::new(Some(child), master, Target::Host))
    }

    /// Sequence number of the last frame sent (a request's reply names it).
    pub fn last_seq(&self) -> u16 {
        self.seq
    }

    /// Sends one message as a frame, through the tap.
    pub fn send(&mut self, m: &Message<'_>, tap: &mut dyn Tap) -> std::io::Result<()> {
        let mut buf = [0u8; MAX_FRAME];
        self.seq = self.seq.wrapping_add(1);
        let n = m
            .emit_frame(self.seq, &mut buf)
            .map_err(|e| std::io::Error::other(e.to_string()))?;
        if let Some(bytes) = tap.outgoing(&buf[..n]) {
            match self.batch.as_mut() {
                Some(b) => b.extend_from_slice(&bytes),
                None => self.port.write_all(&bytes)?,
            }
        }
        Ok(())
    }

    /// With batching on, [`Firmware::send`] holds frames back and the next receive writes them
    /// in one go: one wake-up of the firmware per period instead of one per frame. Only for
    /// lockstep, where nothing depends on when within a period the bytes arrive.
    pub fn set_batching(&mut self, on: bool) -> std::io::Result<()> {
        self.flush()?;
        self.batch = on.then(Vec::new);
        Ok(())
    }

    /// Writes the frames held back by batching.
    fn flush(&mut self) -> std::io::Result<()> {
        if let Some(b) = self.batch.as_mut() {
            if !b.is_empty() {
                self.port.write_all(b)?;
                b.clear();
            }
        }
        Ok(())
    }

    /// Sends raw bytes (line noise for tests), through the tap's log only.
    pub fn send_raw(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.flush()?;
        self.port.write_all(bytes)
    }

    /// Reads and decodes what has arrived (waits at most 10 ms for the first bytes: termios
    /// timeouts do not apply to a pty's master side, so `poll` bounds the wait).
    fn pump(&mut self, tap: &mut dyn Tap) -> std::io::Result<()> {
        let mut pfd = libc::pollfd {
            fd: self.port.as_raw_fd(),
            events: libc::POLLIN,
            revents: 0,
        };
        // SAFETY: one valid pollfd for a descriptor we own.
        let ready = unsafe { libc::poll(&mut pfd, 1, 10) };
        if ready <= 0 {
            return Ok(());
        }
        let mut buf = [0u8; 4096];
        let n = match self.port.read(&mut buf) {
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => 0,
            // A pty whose other side has not opened yet reads EIO: nothing yet.
            Err(e) if e.raw_os_error() == Some(libc::EIO) => {
                std::thread::sleep(Duration::from_millis(10));
                0
            }
            Err(e) => return Err(e),
        };
        if n > 0 {
            tap.incoming(&buf[..n]);
        }
        for &b in &buf[..n] {
            if let Outcome::Frame(_, m) = self.decoder.push(b) {
                let r = match m {
                    Message::Command(c) => Reply::Command(c),
                    Message::Telemetry(t) => Reply::Telemetry(t),
                    Message::Reply(r) => Reply::Reply(r),
                    Message::Log(l) => Reply::Log(l.text.to_string()),
                    Message::Belief(b) => Reply::Belief(crate::output::belief::Chunk::of(&b)),
                    _ => continue,
                };
                self.inbox.push(r);
            }
        }
        Ok(())
    }

    /// Reads until `done(inbox)` holds or `timeout` passes; returns and clears the inbox.
    pub fn receive_until(
        &mut self,
        timeout: Duration,
        tap: &mut dyn Tap,
        done: impl Fn(&[Reply]) -> bool,
    ) -> std::io::Result<Vec<Reply>> {
        self.flush()?;
        let start = Instant::now();
        while !done(&self.inbox) {
            if start.elapsed() > timeout {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::TimedOut,
                    format!("no answer from the {} firmware in {timeout:?}", self.target),
                ));
            }
            if let Some(c) = self.child.as_mut() {
                if let Ok(Some(status)) = c.try_wait() {
                    return Err(std::io::Error::other(format!(
                        "the {} firmware exited ({status})",
                        self.target
                    )));
                }
            }
            self.pump(tap)?;
        }
        Ok(std::mem::take(&mut self.inbox))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_serial_port_opens_raw_at_a_baud_rate_and_carries_bytes_both_ways() {
        // A pty's slave stands in for a board's serial adapter (`--port`).
        let (mut master, slave) = open_pty().unwrap();
        let mut port = open_serial(&slave, 57_600).unwrap();
        // Raw: a 0x00 frame delimiter and a line feed pass unchanged.
        master.write_all(b"\x00ab\ncd\x00").unwrap();
        let mut got = Vec::new();
        let start = Instant::now();
        while got.len() < 7 && start.elapsed() < Duration::from_secs(5) {
            let mut buf = [0u8; 16];
            match port.read(&mut buf) {
                Ok(n) => got.extend_from_slice(&buf[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
                Err(e) => panic!("{e}"),
            }
        }
        assert_eq!(got, b"\x00ab\ncd\x00");
        port.write_all(b"\x01\x02").unwrap();
        let mut back = [0u8; 2];
        master.read_exact(&mut back).unwrap();
        assert_eq!(back, [1, 2]);
        assert!(open_serial(Path::new("/dev/no-such-port"), 115_200).is_err());
    }
}
