//! One firmware instance and the serial link to it: QEMU's emulated board through its ethernet
//! controller (or its UART on a pty), the host-process firmware on a pty, or a real board on a
//! serial device.
//!
//! Frames go out whole (`send`); what comes back is decoded with the firmware's own stream
//! decoder and kept as owned [`Reply`]s. A [`Tap`] sees every chunk both ways (the frame log)
//! and may corrupt or drop outgoing frames (fault injection).
//!
//! - `build.rs`: building the firmware for a target; `tty.rs`: ptys, serial ports, raw mode
//!   and bounded waits.

use std::fs::File;
use std::io::{BufRead, BufReader, Read, Write};

use nix::errno::Errno;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

mod build;
mod tty;

pub use build::{build, qemu_available};
pub use tty::{open_pty, open_serial, readable};
use tty::{open_raw, qemu_pty};

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
    /// A real board on a serial device, at a baud rate.
    Port(PathBuf, u32),
}

/// The boards' control link's baud rate (`--port`'s default).
pub const PORT_BAUD: u32 = 115_200;

impl std::fmt::Display for Target {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Target::Qemu => f.write_str("qemu"),
            Target::QemuUart => f.write_str("qemu-uart"),
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
    port: Port,
    decoder: Decoder,
    seq: u16,
    inbox: Vec<Reply>,
    /// Outgoing bytes held back until the next receive (see [`Firmware::set_batching`]).
    batch: Option<Vec<u8>>,
    /// The link's bytes travel in ethernet frames (QEMU's LAN9118) rather than as a stream.
    ethernet: bool,
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

/// Where the link's bytes go.
enum Port {
    /// A pty, socket, serial device or datagram socket.
    File(File),
    /// The firmware's runtime in this process ([`Firmware::in_process`]).
    InProcess(Box<InProcess>),
}

/// The host firmware's runtime (`vpf::guidance::OneThreadRuntime`, what the `vpf-firmware` process
/// runs) called directly: bytes in, a lockstep `Tick` runs its period at once, bytes out.
struct InProcess {
    runtime: vpf::guidance::OneThreadRuntime,
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
        readable(f, ms)
    }
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
            Target::Qemu => Self::start_qemu_ethernet(binary, lockstep, false),
            Target::QemuUart => Self::start_qemu(binary, lockstep, false),
            Target::Host => Self::start_host(binary, extra),
            Target::Port(path, baud) => {
                let port = Port::File(open_serial(path, *baud)?);
                Ok(Self::new(None, port, target.clone()))
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
            sonar_port: None,
            target,
        }
    }

    /// The board's Ping360 port (QEMU's second serial port, when started with one), once.
    pub fn take_sonar_port(&mut self) -> Option<File> {
        self.sonar_port.take()
    }

    /// The arguments that start QEMU's emulated board paused (`-S`), its monitor on stdio, and
    /// `serials` as its `-serial`s (UART0, UART1, ...). `-icount shift=0` makes the firmware's
    /// step costs instruction counts; in lockstep, `sleep=off` lets the virtual clock jump over
    /// the firmware's idle waits instead of sleeping them out in real time.
    fn qemu_command(elf: &Path, lockstep: bool, serials: &[&str]) -> Command {
        let icount = if lockstep {
            "shift=0,sleep=off"
        } else {
            "shift=0"
        };
        let mut cmd = Command::new("qemu-system-arm");
        cmd.args(["-machine", "mps2-an386", "-cpu", "cortex-m4", "-nographic"])
            .args(serials)
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
    ///
    /// With `sonar`, the board's UART1 (its Ping360 port) is a pty
    /// ([`Firmware::take_sonar_port`]).
    pub fn start_qemu_ethernet(elf: &Path, lockstep: bool, sonar: bool) -> std::io::Result<Self> {
        use command_fds::{CommandFdExt, FdMapping};
        let (ours, theirs) = std::os::unix::net::UnixDatagram::pair()?;
        let serials: &[&str] = if sonar {
            &["-serial", "null", "-serial", "pty"]
        } else {
            &["-serial", "null"]
        };
        let mut cmd = Self::qemu_command(elf, lockstep, serials);
        cmd.args(["-nic", "socket,fd=3,model=lan9118"]);
        // The child's descriptor 3 is the socket's other end (dup2'd between fork and exec).
        cmd.fd_mappings(vec![FdMapping {
            parent_fd: theirs.into(),
            child_fd: 3,
        }])
        .map_err(std::io::Error::other)?;
        let mut child = cmd.spawn()?;
        // The command holds the other end; this side keeps only its own.
        drop(cmd);
        let stdout = child
            .stdout
            .take()
            .ok_or_else(|| std::io::Error::other("no qemu stdout"))?;
        let mut lines = BufReader::new(stdout).lines();
        let sonar_port = if sonar {
            let path = qemu_pty(&mut lines)?;
            Some(open_raw(&path)?)
        } else {
            None
        };
        std::thread::spawn(move || for _ in lines.map_while(Result::ok) {});
        resume(&mut child)?;
        let port = Port::File(File::from(std::os::fd::OwnedFd::from(ours)));
        let mut fw = Self::new(Some(child), port, Target::Qemu);
        fw.ethernet = true;
        fw.sonar_port = sonar_port;
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
    /// sent before would be lost). With `sonar`, the board's UART1 (its Ping360 port) is a
    /// second pty ([`Firmware::take_sonar_port`]).
    pub fn start_qemu(elf: &Path, lockstep: bool, sonar: bool) -> std::io::Result<Self> {
        let serials: &[&str] = if sonar {
            &["-serial", "pty", "-serial", "pty"]
        } else {
            &["-serial", "pty"]
        };
        let mut child = Self::qemu_command(elf, lockstep, serials).spawn()?;
        let stdout = child
            .stdout
            .take()
            .ok_or_else(|| std::io::Error::other("no qemu stdout"))?;
        let mut lines = BufReader::new(stdout).lines();
        let mut paths = Vec::new();
        while paths.len() < serials.len() / 2 {
            paths.push(qemu_pty(&mut lines)?);
        }
        std::thread::spawn(move || for _ in lines.map_while(Result::ok) {});
        let port = Port::File(open_raw(&paths[0])?);
        let sonar_port = match paths.get(1) {
            Some(p) => Some(open_raw(p)?),
            None => None,
        };
        resume(&mut child)?;
        let mut fw = Self::new(Some(child), port, Target::QemuUart);
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
        let port = Port::File(File::from(std::os::fd::OwnedFd::from(ours)));
        Ok(Self::new(Some(child), port, Target::Host))
    }

    /// The host firmware's runtime in this process: the same code the `vpf-firmware` process
    /// runs on its input (`vpf::guidance::OneThreadRuntime`), called directly, so a lockstep
    /// period costs no process wake-up and no system call (the sweep's, the benchmark's and the
    /// fault campaign's runs: see `hil/sweeps/README.md`). Only for lockstep: it has no clock
    /// of its own.
    pub fn in_process() -> std::io::Result<Self> {
        let runtime = vpf::guidance::OneThreadRuntime::new(
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
            Err(e) if e.raw_os_error() == Some(Errno::EIO as i32) => {
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

/// Lets a QEMU started stopped (`-S`) run: `cont` on its monitor (stdin), which stays open
/// while QEMU runs.
fn resume(child: &mut Child) -> std::io::Result<()> {
    let mut stdin = child
        .stdin
        .take()
        .ok_or_else(|| std::io::Error::other("no qemu stdin"))?;
    stdin.write_all(b"cont\n")?;
    stdin.flush()?;
    std::mem::forget(stdin);
    Ok(())
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
