//! The firmware as a host process: the same guidance runtime (`vpf::guidance::SingleContext`)
//! and the same serial protocol, over stdio or a serial device (a pty from the HIL harness, or a
//! USB serial adapter).
//!
//! ```text
//! vpf-firmware                      # protocol on stdin/stdout, log on stderr
//! vpf-firmware --device /dev/pts/7  # protocol on a serial device or pty (set raw by its opener)
//! ```
//!
//! Time: in real time the periods run on an absolute schedule from the process clock; once the
//! host sends a `Tick`, the process switches to lockstep and runs a period per `Tick`, at the
//! host's time. Step costs are reported in microseconds.

use std::io::{Read, Write};
use std::process::ExitCode;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use vpf::guidance::{RuntimeConfig, SingleContext};
use vpf::link::CostUnit;
use vpf::Params;

const USAGE: &str = "usage: vpf-firmware [--device PATH]

The VPF guidance firmware as a host process. Speaks the serial protocol of docs/protocol.md
on stdin/stdout, or on the serial device or pty at PATH. Logs go to stderr.";

/// Where the protocol flows.
enum Port {
    Stdio,
    Device(String),
}

fn parse_args() -> Result<Port, String> {
    let mut args = std::env::args().skip(1);
    let mut port = Port::Stdio;
    while let Some(a) = args.next() {
        match a.as_str() {
            "--device" => {
                port = Port::Device(args.next().ok_or("--device needs a path")?);
            }
            "-h" | "--help" => return Err(String::new()),
            other => return Err(format!("unknown argument `{other}`")),
        }
    }
    Ok(port)
}

pub fn main() -> ExitCode {
    let port = match parse_args() {
        Ok(p) => p,
        Err(e) => {
            if !e.is_empty() {
                eprintln!("vpf-firmware: {e}");
            }
            eprintln!("{USAGE}");
            return if e.is_empty() {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(2)
            };
        }
    };
    let is_device = matches!(port, Port::Device(_));
    let (reader, writer): (Box<dyn Read + Send>, Box<dyn Write>) = match &port {
        Port::Stdio => (Box::new(std::io::stdin()), Box::new(std::io::stdout())),
        Port::Device(path) => {
            let open = || {
                std::fs::OpenOptions::new()
                    .read(true)
                    .write(true)
                    .open(path)
            };
            match (open(), open()) {
                (Ok(r), Ok(w)) => (Box::new(r), Box::new(w)),
                (Err(e), _) | (_, Err(e)) => {
                    eprintln!("vpf-firmware: cannot open {path}: {e}");
                    return ExitCode::FAILURE;
                }
            }
        }
    };
    eprintln!(
        "vpf-firmware {} (host process, {})",
        env!("CARGO_PKG_VERSION"),
        match &port {
            Port::Stdio => "stdio".to_string(),
            Port::Device(p) => p.clone(),
        }
    );
    match run(reader, writer, is_device) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("vpf-firmware: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The event loop: bytes from a reader thread, periods from the clock (until lockstep).
fn run(
    mut reader: Box<dyn Read + Send>,
    mut writer: Box<dyn Write>,
    is_device: bool,
) -> std::io::Result<()> {
    let mut fw = SingleContext::new(
        Params::default(),
        RuntimeConfig::default(),
        CostUnit::Microseconds,
    )
    .map_err(|e| std::io::Error::other(e.to_string()))?;

    let (tx, rx) = mpsc::channel::<Vec<u8>>();
    std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        loop {
            match reader.read(&mut buf) {
                // A serial line set to time out reads returns 0 when quiet: not the end.
                Ok(0) if is_device => std::thread::sleep(Duration::from_millis(5)),
                Ok(0) | Err(_) => break,
                Ok(n) => {
                    if tx.send(buf[..n].to_vec()).is_err() {
                        break;
                    }
                }
            }
        }
    });

    let start = Instant::now();
    let mut cost = || start.elapsed().as_micros() as u32;
    let mut out: Vec<u8> = Vec::with_capacity(4096);
    let mut next = Duration::from_millis(u64::from(fw.periodic().period_ms()));
    loop {
        let timeout = next.saturating_sub(start.elapsed());
        match rx.recv_timeout(if fw.lockstep() {
            Duration::from_secs(3600)
        } else {
            timeout
        }) {
            Ok(bytes) => {
                fw.on_bytes(&bytes, &mut cost, &mut |f: &[u8]| {
                    out.extend_from_slice(f);
                    true
                });
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {
                if !fw.lockstep() {
                    let now = next.as_millis() as u64;
                    fw.on_tick(now, &mut cost, &mut |f: &[u8]| {
                        out.extend_from_slice(f);
                        true
                    });
                    // Absolute schedule: the next period is one period after this one was due.
                    next += Duration::from_millis(u64::from(fw.periodic().period_ms()));
                }
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                eprintln!("vpf-firmware: input closed, exiting");
                writer.write_all(&out)?;
                writer.flush()?;
                return Ok(());
            }
        }
        if !out.is_empty() {
            writer.write_all(&out)?;
            writer.flush()?;
            out.clear();
        }
    }
}
