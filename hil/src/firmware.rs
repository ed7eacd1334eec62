//! One firmware instance and the serial link to it: QEMU's emulated board through its ethernet
//! controller (or its UART on a pty), the host-process firmware on a pty, or a real board on a
//! serial device.
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

/// The EtherType of the link's frames on QEMU's ethernet (IEEE 802 local experimental; the
/// firmware's `src/board/mps2_an386/eth.rs`).
const ETHERTYPE: u16 = 0x88B5;
/// A link frame's header: addresses, EtherType, and the 16-bit little-endian byte count.
const ETH_HEADER: usize = 16;
/// Link bytes per frame, at most: the firmware's receive queue (1024 slots) takes one whole.
const ETH_PAYLOAD: usize = 1000;
/// The largest frame the board sends (1514 bytes), rounded up.
const ETH_FRAME: usize = 2048;

/// Which firmware to run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Target {
    /// The release firmware on QEMU's emulated Cortex-M4 (`mps2-an386`), its link carried in
    /// ethernet frames through the board's LAN9118 (see [`Firmware::start`]).
    Qemu,
    /// The same, its link on UART0 through a pty: one byte per turn of QEMU's main loop, about
    /// ten times slower; the path a user's own host software takes (`cargo qemu`).
    QemuUart,
    /// The same runtime built for the host, as a process.
    Host,
    /// A real board on a serial device.
    Port(PathBuf),
}

impl std::fmt::Display for Target {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Target::Qemu => f.write_str("qemu"),
            Target::QemuUart => f.write_str("qemu-uart"),
            Target::Host => f.write_str("host"),
            Target::Port(p) => write!(f, "port:{}", p.display()),
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
    port: Port,
    decoder: Decoder,
    seq: u16,
    inbox: Vec<Reply>,
    /// Outgoing bytes held back until the next receive (see [`Firmware::set_batching`]).
    batch: Option<Vec<u8>>,
    /// The link's bytes travel in ethernet frames (QEMU's LAN9118) rather than as a stream.
    ethernet: bool,
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

/// Where the link's bytes go.
enum Port {
    /// A pty, socket, serial device or datagram socket.
    File(File),
    /// The firmware's runtime in this process ([`Firmware::in_process`]).
    InProcess(Box<InProcess>),
}

/// The host firmware's runtime (`vpf::guidance::SingleContext`, what the `vpf-firmware` process
/// runs) called directly: bytes in, a lockstep `Tick` runs its period at once, bytes out.
struct InProcess {
    runtime: vpf::guidance::SingleContext,
    /// What the runtime sent, not yet read.
    out: Vec<u8>,
    /// The step cost's clock (microseconds, as the host process reports them).
    start: Instant,
}

impl InProcess {
    fn feed(&mut self, bytes: &[u8]) {
        let start = self.start;
        let mut cost = || start.elapsed().as_micros() as u32;
        let out = &mut self.out;
        self.runtime.on_bytes(bytes, &mut cost, &mut |f: &[u8]| {
            out.extend_from_slice(f);
            true
        });
    }
}

impl Port {
    fn write_all(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        match self {
            Port::File(f) => f.write_all(bytes),
            Port::InProcess(p) => {
                p.feed(bytes);
                Ok(())
            }
        }
    }

    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        match self {
            Port::File(f) => f.read(buf),
            Port::InProcess(p) => {
                let n = p.out.len().min(buf.len());
                buf[..n].copy_from_slice(&p.out[..n]);
                p.out.drain(..n);
                Ok(n)
            }
        }
    }

    /// Waits at most `ms` for something to read.
    fn wait_readable(&self, ms: i32) -> std::io::Result<bool> {
        let f = match self {
            Port::File(f) => f,
            Port::InProcess(p) => return Ok(!p.out.is_empty()),
        };
        let mut pfd = libc::pollfd {
            fd: f.as_raw_fd(),
            events: libc::POLLIN,
            revents: 0,
        };
        // SAFETY: one valid pollfd for a descriptor we own.
        let ready = unsafe { libc::poll(&mut pfd, 1, ms) };
        if ready < 0 {
            let e = std::io::Error::last_os_error();
            if e.kind() != std::io::ErrorKind::Interrupted {
                return Err(e);
            }
        }
        Ok(ready > 0)
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
        Target::Qemu | Target::QemuUart => {
            cmd.args(["--target", "thumbv7em-none-eabihf"]);
            target_dir.join("thumbv7em-none-eabihf/release/vpf-firmware")
        }
        Target::Host | Target::Port(_) => target_dir.join("release/vpf-firmware"),
    };
    if matches!(target, Target::Port(_)) {
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
                "the {target} firmware drives no Ping360 (the board images do not yet): use --firmware host"
            )));
        }
        match target {
            Target::Qemu => Self::start_qemu_ethernet(binary, lockstep),
            Target::QemuUart => Self::start_qemu(binary, lockstep),
            Target::Host => Self::start_host(binary, extra),
            Target::Port(path) => {
                let port = std::fs::OpenOptions::new()
                    .read(true)
                    .write(true)
                    .open(path)?;
                make_raw(&port)?;
                Ok(Self::new(None, Port::File(port), target.clone()))
            }
        }
    }

    fn new(child: Option<Child>, port: Port, target: Target) -> Self {
        Firmware {
            child,
            port,
            decoder: Decoder::accepting(Direction::ToHost),
            seq: 0,
            inbox: Vec::new(),
            batch: None,
            ethernet: false,
            target,
        }
    }

    /// The arguments that start QEMU's emulated board paused (`-S`), its monitor on stdio.
    /// `-icount shift=0` makes the firmware's step costs instruction counts; in lockstep,
    /// `sleep=off` lets the virtual clock jump over the firmware's idle waits instead of
    /// sleeping them out in real time.
    fn qemu_command(elf: &Path, lockstep: bool) -> Command {
        let icount = if lockstep {
            "shift=0,sleep=off"
        } else {
            "shift=0"
        };
        let mut cmd = Command::new("qemu-system-arm");
        cmd.args(["-machine", "mps2-an386", "-cpu", "cortex-m4", "-nographic"])
            .args(["-monitor", "stdio", "-S", "-icount", icount])
            .args(["-semihosting-config", "enable=on,target=native", "-kernel"])
            .arg(elf)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null());
        cmd
    }

    /// QEMU with the link in ethernet frames: the board's LAN9118 on one end of a datagram
    /// socket pair (`-nic socket,fd=3`), this side on the other, UART0 unconnected. A frame
    /// carries up to [`ETH_PAYLOAD`] link bytes and a period's traffic moves in one or two
    /// frames each way, where QEMU's CMSDK UART takes one byte per turn of its main loop (the
    /// firmware's side: `src/board/mps2_an386/eth.rs`). Returns once the firmware's first,
    /// empty frame says its controller is up (a frame sent earlier could be lost).
    fn start_qemu_ethernet(elf: &Path, lockstep: bool) -> std::io::Result<Self> {
        use std::os::unix::process::CommandExt;
        let (ours, theirs) = std::os::unix::net::UnixDatagram::pair()?;
        let fd = theirs.as_raw_fd();
        let mut cmd = Self::qemu_command(elf, lockstep);
        cmd.args(["-serial", "null", "-nic", "socket,fd=3,model=lan9118"]);
        // SAFETY: between fork and exec only async-signal-safe calls (dup2, fcntl) on
        // descriptors this process owns; the child's descriptor 3 is the socket's other end.
        unsafe {
            cmd.pre_exec(move || {
                let rc = if fd == 3 {
                    libc::fcntl(3, libc::F_SETFD, 0)
                } else {
                    libc::dup2(fd, 3)
                };
                if rc < 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
        let mut child = cmd.spawn()?;
        drop(theirs);
        let stdout = child
            .stdout
            .take()
            .ok_or_else(|| std::io::Error::other("no qemu stdout"))?;
        std::thread::spawn(
            move || for _ in BufReader::new(stdout).lines().map_while(Result::ok) {},
        );
        let mut stdin = child
            .stdin
            .take()
            .ok_or_else(|| std::io::Error::other("no qemu stdin"))?;
        stdin.write_all(b"cont\n")?;
        stdin.flush()?;
        std::mem::forget(stdin); // the monitor stays open while QEMU runs
        let port = Port::File(File::from(std::os::fd::OwnedFd::from(ours)));
        let mut fw = Self::new(Some(child), port, Target::Qemu);
        fw.ethernet = true;
        if lockstep {
            // Nothing depends on when within a period the bytes arrive: one frame a period.
            fw.batch = Some(Vec::new());
        }
        let start = Instant::now();
        while !fw.wait_readable(100)? {
            if start.elapsed() > Duration::from_secs(10) {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::TimedOut,
                    "the qemu firmware's ethernet controller did not come up in 10 s",
                ));
            }
            if let Some(c) = fw.child.as_mut() {
                if let Ok(Some(status)) = c.try_wait() {
                    return Err(std::io::Error::other(format!(
                        "the qemu firmware exited ({status})"
                    )));
                }
            }
        }
        // The empty frame carries no link bytes: read and dropped.
        let mut hello = [0u8; ETH_FRAME];
        let _ = fw.port.read(&mut hello)?;
        Ok(fw)
    }

    /// Waits at most `ms` for something to read.
    fn wait_readable(&self, ms: i32) -> std::io::Result<bool> {
        self.port.wait_readable(ms)
    }

    /// Writes link bytes: as they are on a stream, in frames on ethernet.
    fn write_link(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        if !self.ethernet {
            return self.port.write_all(bytes);
        }
        for chunk in bytes.chunks(ETH_PAYLOAD) {
            let mut frame = Vec::with_capacity(ETH_HEADER + chunk.len());
            frame.extend_from_slice(&[0xff; 6]); // to the board (the only one on the link)
            frame.extend_from_slice(&[0x02, 0, 0x48, 0x49, 0x4c, 0x01]); // from "HIL"
            frame.extend_from_slice(&ETHERTYPE.to_be_bytes());
            frame.extend_from_slice(&(chunk.len() as u16).to_le_bytes());
            frame.extend_from_slice(chunk);
            self.port.write_all(&frame)?;
        }
        Ok(())
    }

    /// QEMU with the link on UART0 through a pty, paused with `-S` until the pty is open (bytes
    /// sent before would be lost).
    fn start_qemu(elf: &Path, lockstep: bool) -> std::io::Result<Self> {
        let mut child = Self::qemu_command(elf, lockstep)
            .args(["-serial", "pty"])
            .spawn()?;
        let stdout = child
            .stdout
            .take()
            .ok_or_else(|| std::io::Error::other("no qemu stdout"))?;
        let mut lines = BufReader::new(stdout).lines();
        // QEMU 7.2 names the pty on its monitor: "char device redirected to /dev/pts/N".
        let path = loop {
            let Some(line) = lines.next() else {
                return Err(std::io::Error::other("qemu exited before naming its pty"));
            };
            let line = line?;
            if let Some(i) = line.find("/dev/pts/") {
                break line[i..]
                    .split_whitespace()
                    .next()
                    .unwrap_or_default()
                    .to_string();
            }
        };
        std::thread::spawn(move || for _ in lines.map_while(Result::ok) {});
        let port = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&path)?;
        make_raw(&port)?;
        let port = Port::File(port);
        let mut stdin = child
            .stdin
            .take()
            .ok_or_else(|| std::io::Error::other("no qemu stdin"))?;
        stdin.write_all(b"cont\n")?;
        stdin.flush()?;
        std::mem::forget(stdin); // the monitor stays open while QEMU runs
        Ok(Self::new(Some(child), port, Target::QemuUart))
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
        let port = Port::File(File::from(std::os::fd::OwnedFd::from(ours)));
        Ok(Self::new(Some(child), port, Target::Host))
    }

    /// The host firmware's runtime in this process: the same code the `vpf-firmware` process
    /// runs on its input (`vpf::guidance::SingleContext`), called directly, so a lockstep
    /// period costs no process wake-up and no system call (the sweep's, the benchmark's and the
    /// fault campaign's runs: see `hil/sweeps/README.md`). Only for lockstep: it has no clock
    /// of its own.
    pub fn in_process() -> std::io::Result<Self> {
        let runtime = vpf::guidance::SingleContext::new(
            vpf::Params::default(),
            vpf::guidance::RuntimeConfig::default(),
            vpf::link::CostUnit::Microseconds,
        )
        .map_err(|e| std::io::Error::other(e.to_string()))?;
        let port = Port::InProcess(Box::new(InProcess {
            runtime,
            out: Vec::new(),
            start: Instant::now(),
        }));
        Ok(Self::new(None, port, Target::Host))
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
        Ok(Self::new(Some(child), Port::File(master), Target::Host))
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
                None => self.write_link(&bytes)?,
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
        if let Some(b) = self.batch.take() {
            let sent = if b.is_empty() {
                Ok(())
            } else {
                self.write_link(&b)
            };
            self.batch = Some(Vec::with_capacity(b.capacity()));
            sent?;
        }
        Ok(())
    }

    /// Sends raw bytes (line noise for tests), through the tap's log only.
    pub fn send_raw(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.flush()?;
        self.write_link(bytes)
    }

    /// Reads and decodes what has arrived (waits at most 10 ms for the first bytes: termios
    /// timeouts do not apply to a pty's master side, so `poll` bounds the wait).
    fn pump(&mut self, tap: &mut dyn Tap) -> std::io::Result<()> {
        if !self.wait_readable(10)? {
            return Ok(());
        }
        let mut buf = [0u8; 4096];
        let mut n = match self.port.read(&mut buf) {
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => 0,
            // A pty whose other side has not opened yet reads EIO: nothing yet.
            Err(e) if e.raw_os_error() == Some(libc::EIO) => {
                std::thread::sleep(Duration::from_millis(10));
                0
            }
            Err(e) => return Err(e),
        };
        let mut from = 0;
        if self.ethernet {
            // A frame: the link bytes after the header, as many as its length says (a frame
            // of another type, or too short for its length, carries none).
            let len = buf
                .get(ETH_HEADER - 2..ETH_HEADER)
                .map_or(0, |l| usize::from(u16::from_le_bytes([l[0], l[1]])));
            let ours = buf.get(12..14) == Some(&ETHERTYPE.to_be_bytes()[..]);
            (from, n) = if ours && ETH_HEADER + len <= n {
                (ETH_HEADER, ETH_HEADER + len)
            } else {
                (0, 0)
            };
        }
        if n > from {
            tap.incoming(&buf[from..n]);
        }
        for &b in &buf[from..n] {
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
