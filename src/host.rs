//! The firmware as a host process: the same guidance runtime (`vpf::guidance::OneThreadRuntime`)
//! and the same serial protocol, over stdio or a serial device (a pty from the HIL harness, or a
//! USB serial adapter).
//!
//! ```text
//! vpf-firmware                      # protocol on stdin/stdout, log on stderr
//! vpf-firmware --device /dev/ttyUSB0 [--baud 115200]   # protocol on a serial device or pty
//! vpf-firmware --ping360 /dev/ttyUSB0 [--ping360-range 30 ...]   # and a Ping360 on its own port
//! ```
//!
//! With `--ping360 DEVICE` the firmware drives a Blue Robotics Ping360 on that serial port
//! (`vpf::sonar::ping360`): its pings become scanlines like those of the `Scanline` message, its
//! counters are `Telemetry` rows 31–36. Bytes for the Ping360 are written before the main
//! link's of the same event, so a `transducer` sent in a period precedes that period's
//! `Command` (the HIL harness relies on it in lockstep).
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

use vpf::guidance::mavlink::MavConfig;
use vpf::guidance::{OneThreadRuntime, RuntimeConfig};
use vpf::link::CostUnit;
use vpf::sonar::ping360::Ping360Config;
use vpf::Params;

const USAGE: &str =
    "usage: vpf-firmware [--device PATH [--baud N]] [--ping360 DEVICE [Ping360 options]]

The VPF guidance firmware as a host process. Speaks the serial protocol of docs/protocol.md
on stdin/stdout, or on the serial device or pty at PATH. Logs go to stderr.

  --device PATH                the protocol on this serial device or pty (raw, 8N1)
  --baud N                     its baud rate (default 115200)
  --mavlink DEVICE             MAVLink 2 to an ArduSub autopilot and QGroundControl on this
                               serial device or pty: navigation in, velocity set-points,
                               status, obstacle distances out, missions uploaded
  --mavlink-baud N             its baud rate (default 115200)
  --mavlink-ids SYS:COMP:ASYS:ACOMP  this firmware's and the autopilot's MAVLink ids
                               (default 1:191:1:1)

  --ping360 DEVICE             drive a Blue Robotics Ping360 on this serial device or pty
  --ping360-baud N             its baud rate (default 115200)
  --ping360-sector START:WIDTH head angles scanned, gradians (default 0:400, a full circle;
                               less goes back and forth from START to START+WIDTH)
  --ping360-step G             head step, gradians, 1..=12 (default 2, i.e. 1.8 degrees)
  --ping360-range M            range, m (sets the sample period; default 30)
  --ping360-samples N          samples per ping, 200..=1200 (default 600)
  --ping360-gain 0|1|2         low, normal (default), high
  --ping360-frequency KHZ      transmit frequency, 500..=1000 (default 750)
  --ping360-pulse US           transmit duration, microseconds, 1..=1000 (default 100)
  --ping360-mount DEG[:ccw]    bearing of head angle 0 from the bow, degrees counter-clockwise
                               (default 180: angle 200 ahead); `:ccw` if the angle grows
                               counter-clockwise seen from above (the sonar upside down)
  --ping360-timeout-ms T       a ping unanswered this long is counted and skipped (default 500)
  --sound-speed C              speed of sound, m/s (default 1500)";

/// Where the protocol flows.
enum Port {
    Stdio,
    /// A serial device (or pty) and its baud rate.
    Device(String, u32),
}

/// The command line.
struct Args {
    port: Port,
    /// The Ping360's device, baud rate and settings.
    ping360: Option<(String, u32, Ping360Config)>,
    /// The MAVLink line's device, baud rate and ids.
    mavlink: Option<(String, u32, MavConfig)>,
}

fn number<T: std::str::FromStr>(flag: &str, v: Option<String>) -> Result<T, String> {
    let v = v.ok_or(format!("{flag} needs a value"))?;
    v.parse().map_err(|_| format!("{flag} {v}: not a number"))
}

fn parse_args() -> Result<Args, String> {
    let mut args = std::env::args().skip(1);
    let mut port = Port::Stdio;
    let mut main_baud = 115_200u32;
    let mut device = None;
    let mut baud = 115_200u32;
    let mut cfg = Ping360Config::default();
    let mut range_m: Option<f32> = None;
    let mut mavlink: Option<String> = None;
    let mut mav_baud = 115_200u32;
    let mut mav_cfg = MavConfig::default();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--device" => {
                port = Port::Device(args.next().ok_or("--device needs a path")?, 0);
            }
            "--baud" => main_baud = number(&a, args.next())?,
            "--mavlink" => mavlink = Some(args.next().ok_or("--mavlink needs a device")?),
            "--mavlink-baud" => mav_baud = number(&a, args.next())?,
            "--mavlink-ids" => {
                let v = args
                    .next()
                    .ok_or("--mavlink-ids needs SYS:COMP:ASYS:ACOMP")?;
                let ids: Vec<u8> = v.split(':').filter_map(|x| x.parse().ok()).collect();
                let [sys, comp, asys, acomp] = ids[..] else {
                    return Err(format!(
                        "--mavlink-ids {v}: expected four ids 0..=255, SYS:COMP:ASYS:ACOMP"
                    ));
                };
                mav_cfg.sysid = sys;
                mav_cfg.compid = comp;
                mav_cfg.autopilot = (asys, acomp);
            }
            "--ping360" => device = Some(args.next().ok_or("--ping360 needs a device")?),
            "--ping360-baud" => baud = number(&a, args.next())?,
            "--ping360-sector" => {
                let v = args.next().ok_or("--ping360-sector needs START:WIDTH")?;
                let (s, w) = v
                    .split_once(':')
                    .ok_or(format!("--ping360-sector {v}: expected START:WIDTH"))?;
                cfg.start_grad = number(&a, Some(s.to_string()))?;
                cfg.width_grad = number(&a, Some(w.to_string()))?;
            }
            "--ping360-step" => cfg.step_grad = number(&a, args.next())?,
            "--ping360-range" => range_m = Some(number(&a, args.next())?),
            "--ping360-samples" => cfg.samples = number(&a, args.next())?,
            "--ping360-gain" => cfg.gain = number(&a, args.next())?,
            "--ping360-frequency" => cfg.frequency_khz = number(&a, args.next())?,
            "--ping360-pulse" => cfg.transmit_duration_us = number(&a, args.next())?,
            "--ping360-timeout-ms" => cfg.timeout_ms = number(&a, args.next())?,
            "--sound-speed" => cfg.sound_speed = number(&a, args.next())?,
            "--ping360-mount" => {
                let v = args.next().ok_or("--ping360-mount needs DEG[:ccw]")?;
                let (deg, sense) = v.split_once(':').unwrap_or((&v, "cw"));
                let deg: f32 = number(&a, Some(deg.to_string()))?;
                cfg.zero_bearing_rad = deg.to_radians();
                cfg.clockwise = match sense {
                    "cw" => true,
                    "ccw" => false,
                    other => return Err(format!("--ping360-mount: `{other}`: expected cw or ccw")),
                };
            }
            "-h" | "--help" => return Err(String::new()),
            other => return Err(format!("unknown argument `{other}`")),
        }
    }
    if let Port::Device(_, b) = &mut port {
        *b = main_baud;
    }
    let range_m = range_m.unwrap_or(cfg.range_m());
    cfg.sample_period = Ping360Config::sample_period_for(range_m, cfg.samples, cfg.sound_speed)
        .ok_or(format!(
            "--ping360-range {range_m}: no sample period reaches it with {} samples",
            cfg.samples
        ))?;
    let ping360 = match device {
        Some(d) => {
            cfg.validate().map_err(|e| e.to_string())?;
            Some((d, baud, cfg))
        }
        None => None,
    };
    let mavlink = mavlink.map(|d| (d, mav_baud, mav_cfg));
    Ok(Args {
        port,
        ping360,
        mavlink,
    })
}

pub fn main() -> ExitCode {
    let Args {
        port,
        ping360,
        mavlink,
    } = match parse_args() {
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
    let is_device = matches!(port, Port::Device(..));
    let sonar = match &ping360 {
        Some((path, baud, cfg)) => match open_ping360(path, *baud) {
            Ok((r, w)) => {
                eprintln!(
                    "vpf-firmware: Ping360 on {path} at {baud} baud: angles {}+{} gradians in steps of {}, {:.1} m over {} samples",
                    cfg.start_grad,
                    cfg.width_grad,
                    cfg.step_grad,
                    cfg.range_m(),
                    cfg.samples
                );
                Some(((r, w), *cfg))
            }
            Err(e) => {
                eprintln!("vpf-firmware: cannot open the Ping360 port {path}: {e}");
                return ExitCode::FAILURE;
            }
        },
        None => None,
    };
    let mav = match &mavlink {
        Some((path, baud, cfg)) => match open_serial(path, *baud) {
            Ok(rw) => {
                eprintln!(
                    "vpf-firmware: MAVLink 2 on {path} at {baud} baud, as {}:{} beside the autopilot {}:{}",
                    cfg.sysid, cfg.compid, cfg.autopilot.0, cfg.autopilot.1
                );
                Some((rw, *cfg))
            }
            Err(e) => {
                eprintln!("vpf-firmware: cannot open the MAVLink port {path}: {e}");
                return ExitCode::FAILURE;
            }
        },
        None => None,
    };
    let (reader, writer): (Box<dyn Read + Send>, Box<dyn Write>) = match &port {
        Port::Stdio => (Box::new(std::io::stdin()), Box::new(std::io::stdout())),
        Port::Device(path, baud) => match open_serial(path, *baud) {
            Ok(rw) => rw,
            Err(e) => {
                eprintln!("vpf-firmware: cannot open {path}: {e}");
                return ExitCode::FAILURE;
            }
        },
    };
    eprintln!(
        "vpf-firmware {} (host process, {})",
        env!("CARGO_PKG_VERSION"),
        match &port {
            Port::Stdio => "stdio".to_string(),
            Port::Device(p, baud) => format!("{p} at {baud} baud"),
        }
    );
    match run(reader, writer, is_device, sonar, mav) {
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
/// drops what it read and counts it, as a board's UART loses bytes when its receive queue stays
/// full (`rx_bytes_dropped`, `vpf::guidance::RX_QUEUE`): memory stays bounded however
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

/// The Ping360's serial port, raw, opened twice over (reads in a thread, writes in the loop).
type SonarPort = (Box<dyn Read + Send>, Box<dyn Write>);

/// Opens a serial port (or pty) at `baud`, 8N1, raw, with reads that time out when it is
/// quiet: a reader and a writer.
fn open_serial(path: &str, baud: u32) -> Result<SonarPort, serialport::Error> {
    let port = serialport::new(path, baud)
        .timeout(Duration::from_millis(20))
        .open()?;
    let writer = port.try_clone()?;
    Ok((Box::new(port), Box::new(writer)))
}

/// Opens the Ping360's port.
fn open_ping360(path: &str, baud: u32) -> Result<SonarPort, serialport::Error> {
    open_serial(path, baud)
}

/// Where a chunk of input came from.
enum Input {
    /// The main link.
    Main(Vec<u8>),
    /// The Ping360's port.
    Sonar(Vec<u8>),
    /// The MAVLink line.
    Mavlink(Vec<u8>),
}

/// The reader thread: reads `reader` until its end and queues what it reads without ever
/// blocking on the queue (a full queue drops the chunk and counts it), so a flood costs CPU,
/// never memory. `wrap` tags the chunks with their port.
fn pump(
    mut reader: impl Read,
    tx: &mpsc::SyncSender<Input>,
    stats: &RxStats,
    is_device: bool,
    wrap: fn(Vec<u8>) -> Input,
) {
    let mut buf = [0u8; READ_CHUNK];
    loop {
        match reader.read(&mut buf) {
            // A serial line set to time out reads returns 0 when quiet: not the end.
            Ok(0) if is_device => std::thread::sleep(Duration::from_millis(5)),
            Err(e) if is_device && e.kind() == std::io::ErrorKind::TimedOut => {}
            Ok(0) | Err(_) => return,
            Ok(n) => {
                stats.read.fetch_add(n as u64, Ordering::Relaxed);
                match tx.try_send(wrap(buf[..n].to_vec())) {
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
    sonar: Option<(SonarPort, Ping360Config)>,
    mav: Option<(SonarPort, MavConfig)>,
) -> std::io::Result<()> {
    let mut fw = OneThreadRuntime::new(
        Params::default(),
        RuntimeConfig::default(),
        CostUnit::Microseconds,
    )
    .map_err(|e| std::io::Error::other(e.to_string()))?;

    let (tx, rx) = mpsc::sync_channel::<Input>(RX_CHUNKS);
    let stats = Arc::new(RxStats::default());
    let sonar_stats = Arc::new(RxStats::default());
    let mut sonar_writer = None;
    if let Some(((sonar_reader, w), cfg)) = sonar {
        fw.set_ping360(cfg)
            .map_err(|e| std::io::Error::other(e.to_string()))?;
        sonar_writer = Some(w);
        let (tx, st) = (tx.clone(), Arc::clone(&sonar_stats));
        std::thread::spawn(move || pump(sonar_reader, &tx, &st, true, Input::Sonar));
    }
    let mav_stats = Arc::new(RxStats::default());
    let mut mav_writer = None;
    if let Some(((mav_reader, w), cfg)) = mav {
        fw.set_mavlink(cfg);
        mav_writer = Some(w);
        let (tx, st) = (tx.clone(), Arc::clone(&mav_stats));
        std::thread::spawn(move || pump(mav_reader, &tx, &st, true, Input::Mavlink));
    }
    let pump_stats = Arc::clone(&stats);
    std::thread::spawn(move || pump(reader, &tx, &pump_stats, is_device, Input::Main));

    let start = Instant::now();
    let mut cost = || start.elapsed().as_micros() as u32;
    let mut out: Vec<u8> = Vec::with_capacity(4096);
    let mut next = Duration::from_millis(u64::from(fw.periodic().period_ms()));
    let mut drops_logged = (0u64, start, 0u64);
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
                Ok(Input::Main(bytes)) => {
                    fw.on_bytes(&bytes, &mut cost, &mut |f: &[u8]| {
                        out.extend_from_slice(f);
                        true
                    });
                }
                Ok(Input::Sonar(bytes)) => fw.on_ping360_bytes(&bytes),
                Ok(Input::Mavlink(bytes)) => fw.on_mavlink_bytes(&bytes),
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    if let Some((c, dropped, missions)) = fw.mavlink_counters() {
                        eprintln!(
                            "vpf-firmware: MAVLink: {c:?}, {dropped} frames dropped on a full outbox, {missions} upload steps on a full queue"
                        );
                    }
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
        let sonar_dropped = sonar_stats.dropped.load(Ordering::Relaxed);
        if (dropped > drops_logged.0 || sonar_dropped > drops_logged.2)
            && drops_logged.1.elapsed() >= DROP_LOG_EVERY
        {
            eprintln!(
                "vpf-firmware: input queue full: {dropped} bytes of the main link and \
                 {sonar_dropped} of the Ping360's dropped so far"
            );
            drops_logged = (dropped, Instant::now(), sonar_dropped);
        }
        // The Ping360's bytes first: a command sent in a period precedes its Command frame.
        if let Some(w) = sonar_writer.as_mut() {
            let bytes = fw.take_ping360_output();
            if !bytes.is_empty() {
                w.write_all(&bytes)?;
                w.flush()?;
            }
        }
        if let Some(w) = mav_writer.as_mut() {
            let bytes = fw.take_mavlink_output();
            if !bytes.is_empty() {
                w.write_all(&bytes)?;
                w.flush()?;
            }
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

    fn chunk(i: Input) -> Vec<u8> {
        match i {
            Input::Main(b) | Input::Sonar(b) | Input::Mavlink(b) => b,
        }
    }

    #[test]
    fn a_full_queue_drops_and_counts_instead_of_growing() {
        // 10 MiB of input and an event loop that never drains: the queue holds its capacity,
        // the rest is dropped and counted, every byte accounted for.
        let total = 10 << 20;
        let input = std::io::Cursor::new(vec![0x55u8; total]);
        let (tx, rx) = mpsc::sync_channel(RX_CHUNKS);
        let stats = RxStats::default();
        pump(input, &tx, &stats, false, Input::Main);
        drop(tx);
        let queued: usize = rx.iter().map(|c| chunk(c).len()).sum();
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
        pump(
            std::io::Cursor::new(input.clone()),
            &tx,
            &stats,
            false,
            Input::Main,
        );
        drop(tx);
        let got: Vec<u8> = rx.iter().flat_map(chunk).collect();
        assert_eq!(got, input);
        assert_eq!(stats.dropped.load(Ordering::Relaxed), 0);
    }
}
