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
//!
//! Input is bounded like the board's UART: a reader thread queues at most 1 MiB for the event
//! loop and drops (and counts, on stderr) what comes past it; a period that is due runs before
//! more input is taken, so a flood neither grows memory nor stops the periods.

use std::io::{Read, Write};
use std::process::ExitCode;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{mpsc, Arc};
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

/// Most bytes one read takes from the input (one queued chunk).
const READ_CHUNK: usize = 4096;

/// Chunks the reader may queue for the event loop: at most `RX_CHUNKS × READ_CHUNK` = 1 MiB
/// waits (90 s of 115 200 baud; the harness's heaviest period is a few KiB). Past it the reader
/// drops what it read and counts it, as the board's UART interrupt drops bytes when its receive
/// queue is full (`rx_bytes_dropped`, `vpf::guidance::RX_QUEUE`): memory stays bounded however
/// fast the input comes, and the decoder resyncs on the next frame delimiter.
const RX_CHUNKS: usize = 256;

/// How often, at most, the event loop logs that input was dropped.
const DROP_LOG_EVERY: Duration = Duration::from_secs(1);

/// What the reader thread did with the input; shared with the event loop.
#[derive(Default)]
struct RxStats {
    /// Bytes read from the input.
    read: AtomicU64,
    /// Bytes read but dropped because the queue was full.
    dropped: AtomicU64,
}

/// The reader thread: reads `reader` until its end and queues what it reads without ever
/// blocking on the queue (a full queue drops the chunk and counts it), so a flood costs CPU,
/// never memory.
fn pump(mut reader: impl Read, tx: &mpsc::SyncSender<Vec<u8>>, stats: &RxStats, is_device: bool) {
    let mut buf = [0u8; READ_CHUNK];
    loop {
        match reader.read(&mut buf) {
            // A serial line set to time out reads returns 0 when quiet: not the end.
            Ok(0) if is_device => std::thread::sleep(Duration::from_millis(5)),
            Ok(0) | Err(_) => return,
            Ok(n) => {
                stats.read.fetch_add(n as u64, Ordering::Relaxed);
                match tx.try_send(buf[..n].to_vec()) {
                    Ok(()) => {}
                    Err(mpsc::TrySendError::Full(_)) => {
                        stats.dropped.fetch_add(n as u64, Ordering::Relaxed);
                    }
                    Err(mpsc::TrySendError::Disconnected(_)) => return,
                }
            }
        }
    }
}

/// The event loop: bytes from a reader thread, periods from the clock (until lockstep).
///
/// A period that is due runs before the next chunk of input is taken, so input that never
/// pauses (a flood) delays a period by at most one chunk's decoding, never starves it.
fn run(
    reader: Box<dyn Read + Send>,
    mut writer: Box<dyn Write>,
    is_device: bool,
) -> std::io::Result<()> {
    let mut fw = SingleContext::new(
        Params::default(),
        RuntimeConfig::default(),
        CostUnit::Microseconds,
    )
    .map_err(|e| std::io::Error::other(e.to_string()))?;

    let (tx, rx) = mpsc::sync_channel::<Vec<u8>>(RX_CHUNKS);
    let stats = Arc::new(RxStats::default());
    let pump_stats = Arc::clone(&stats);
    std::thread::spawn(move || pump(reader, &tx, &pump_stats, is_device));

    let start = Instant::now();
    let mut cost = || start.elapsed().as_micros() as u32;
    let mut out: Vec<u8> = Vec::with_capacity(4096);
    let mut next = Duration::from_millis(u64::from(fw.periodic().period_ms()));
    let mut drops_logged = (0u64, start);
    let mut drops_counted = 0u64;
    loop {
        if !fw.lockstep() && start.elapsed() >= next {
            let now = next.as_millis() as u64;
            fw.on_tick(now, &mut cost, &mut |f: &[u8]| {
                out.extend_from_slice(f);
                true
            });
            // Absolute schedule: the next period is one period after this one was due.
            next += Duration::from_millis(u64::from(fw.periodic().period_ms()));
        } else {
            let wait = if fw.lockstep() {
                Duration::from_secs(3600)
            } else {
                next.saturating_sub(start.elapsed())
            };
            match rx.recv_timeout(wait) {
                Ok(bytes) => {
                    fw.on_bytes(&bytes, &mut cost, &mut |f: &[u8]| {
                        out.extend_from_slice(f);
                        true
                    });
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    eprintln!(
                        "vpf-firmware: input closed after {} bytes ({} dropped, queue full), exiting",
                        stats.read.load(Ordering::Relaxed),
                        stats.dropped.load(Ordering::Relaxed)
                    );
                    writer.write_all(&out)?;
                    writer.flush()?;
                    return Ok(());
                }
            }
        }
        let dropped = stats.dropped.load(Ordering::Relaxed);
        if dropped > drops_counted {
            let n = u32::try_from(dropped - drops_counted).unwrap_or(u32::MAX);
            fw.count_rx_dropped(n);
            drops_counted = dropped;
        }
        if dropped > drops_logged.0 && drops_logged.1.elapsed() >= DROP_LOG_EVERY {
            eprintln!("vpf-firmware: input queue full: {dropped} bytes dropped so far");
            drops_logged = (dropped, Instant::now());
        }
        if !out.is_empty() {
            writer.write_all(&out)?;
            writer.flush()?;
            out.clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_queue_drops_and_counts_instead_of_growing() {
        // 10 MiB of input and an event loop that never drains: the queue holds its capacity,
        // the rest is dropped and counted, every byte accounted for.
        let total = 10 << 20;
        let input = std::io::Cursor::new(vec![0x55u8; total]);
        let (tx, rx) = mpsc::sync_channel(RX_CHUNKS);
        let stats = RxStats::default();
        pump(input, &tx, &stats, false);
        drop(tx);
        let queued: usize = rx.iter().map(|c| c.len()).sum();
        assert_eq!(queued, RX_CHUNKS * READ_CHUNK);
        assert_eq!(stats.read.load(Ordering::Relaxed), total as u64);
        assert_eq!(
            stats.dropped.load(Ordering::Relaxed),
            (total - queued) as u64
        );
    }

    #[test]
    fn input_that_fits_is_queued_whole_and_in_order() {
        let input: Vec<u8> = (0..100_000u32).map(|i| (i % 251) as u8).collect();
        let (tx, rx) = mpsc::sync_channel(RX_CHUNKS);
        let stats = RxStats::default();
        pump(std::io::Cursor::new(input.clone()), &tx, &stats, false);
        drop(tx);
        let got: Vec<u8> = rx.iter().flatten().collect();
        assert_eq!(got, input);
        assert_eq!(stats.dropped.load(Ordering::Relaxed), 0);
    }
}
