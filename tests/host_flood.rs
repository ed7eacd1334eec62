//! The host-process firmware under an input flood: tens of MB of garbage on stdin, as fast as
//! a pipe takes it, then valid traffic. Its input queue is bounded (it drops and counts past
//! it, like the board's UART queue), its periods keep running through the flood, and it
//! answers what comes after.

use std::io::{Read, Write};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use vpf::link::{Decoder, Direction, Message, Outcome, TelemetryCounters, MAX_FRAME};
use vpf::{Mission, Vec2};

/// One garbage frame: two bytes (a coded frame's key and one byte), a length no encoder
/// produces, so the decoder refuses it as a framing error and it can never be taken for a
/// message.
const GARBAGE_FRAME: [u8; 3] = [0x02, 0x41, 0x00];
/// Least garbage to send, bytes, and least time to keep sending it.
const FLOOD_BYTES: usize = 32 << 20;
const FLOOD_TIME: Duration = Duration::from_millis(1500);

enum Event {
    Command(Instant),
    Reply,
    Telemetry(TelemetryCounters),
}

fn frame(seq: u16, m: Message<'_>) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME];
    let n = m.emit_frame(seq, &mut buf).unwrap();
    buf[..n].to_vec()
}

/// Decodes the firmware's output on a thread, stamping each command with when it came.
fn watch(mut out: impl Read + Send + 'static) -> mpsc::Receiver<Event> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut d = Decoder::accepting(Direction::ToHost);
        let mut buf = [0u8; 4096];
        while let Ok(n @ 1..) = out.read(&mut buf) {
            for &b in &buf[..n] {
                let ev = match d.push(b) {
                    Outcome::Frame(_, Message::Command(_)) => Event::Command(Instant::now()),
                    Outcome::Frame(_, Message::Reply(_)) => Event::Reply,
                    Outcome::Frame(_, Message::Telemetry(t)) => Event::Telemetry(t.counters),
                    _ => continue,
                };
                if tx.send(ev).is_err() {
                    return;
                }
            }
        }
    });
    rx
}

#[test]
fn host_process_stays_bounded_and_periodic_under_an_input_flood() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_vpf-firmware"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the host firmware starts");
    let events = watch(child.stdout.take().unwrap());
    let mut stderr = child.stderr.take().unwrap();
    let log = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stderr.read_to_string(&mut s);
        s
    });
    let mut stdin = child.stdin.take().unwrap();

    // The flood: real time (no Tick), so the firmware's own clock runs a period every 100 ms.
    let block: Vec<u8> = GARBAGE_FRAME.repeat(21_845); // 65 535 bytes, whole frames
    let started = Instant::now();
    let mut sent = 0usize;
    while sent < FLOOD_BYTES || started.elapsed() < FLOOD_TIME {
        stdin.write_all(&block).unwrap();
        sent += block.len();
    }
    let flood = started.elapsed();

    // Then valid traffic: a mission, sent again until it is answered (what the flood left in
    // the queue may still crowd it out), as a host would.
    let mission = frame(
        1,
        Message::Mission(Mission {
            goal: Vec2::new(10.0, 0.0),
            formation: None,
        }),
    );
    let mut commands_in_flood = 0;
    let mut replied = false;
    let mut written = sent;
    let mut last = None;
    let deadline = Instant::now() + Duration::from_secs(20);
    while !replied && Instant::now() < deadline {
        stdin.write_all(&[0]).unwrap();
        stdin.write_all(&mission).unwrap();
        stdin.flush().unwrap();
        written += 1 + mission.len();
        let until = Instant::now() + Duration::from_millis(300);
        while let Ok(ev) = events.recv_timeout(until.saturating_duration_since(Instant::now())) {
            match ev {
                Event::Command(at) if at <= started + flood => commands_in_flood += 1,
                Event::Reply => replied = true,
                _ => {}
            }
        }
    }
    assert!(
        replied,
        "the mission sent after the flood was never answered"
    );
    // Two more periods, so that the last telemetry counts everything sent before the mission.
    let mut periods = 0;
    while periods < 2 {
        match events.recv_timeout(Duration::from_secs(5)) {
            Ok(Event::Telemetry(c)) => {
                periods += 1;
                last = Some(c);
            }
            Ok(_) => {}
            Err(e) => panic!("no telemetry after the flood: {e}"),
        }
    }
    drop(stdin);
    assert!(child.wait().unwrap().success());
    let log = log.join().unwrap();

    eprintln!("{sent} bytes of garbage in {flood:?}: {commands_in_flood} periods ran; {log}");
    // Periods ran during the flood: 10 Hz over at least 1.5 s would be 15 or more.
    assert!(
        commands_in_flood >= 3,
        "{commands_in_flood} commands in {flood:?} of flood"
    );
    // Every byte read is accounted for: the exit line names what was read and what dropped.
    let line = log
        .lines()
        .find(|l| l.contains("input closed after"))
        .unwrap_or_else(|| panic!("no closing line in the log:\n{log}"));
    let numbers: Vec<u64> = line
        .split(|c: char| !c.is_ascii_digit())
        .filter_map(|w| w.parse().ok())
        .collect();
    let [read, dropped] = numbers[..] else {
        panic!("expected `after N bytes (M dropped...`: {line}")
    };
    assert_eq!(read, written as u64, "bytes read of those written");
    assert!(dropped <= read);
    // What was not dropped was decoded: each garbage frame refused once, none accepted.
    let c = last.unwrap();
    // The drops reach telemetry, as the board's UART queue's do.
    assert_eq!(
        u64::from(c.rx_bytes_dropped),
        dropped.min(u64::from(u32::MAX))
    );
    let garbage_frames = (sent / GARBAGE_FRAME.len()) as u64;
    let framing = u64::from(c.rx_framing_errors);
    if dropped == 0 {
        assert_eq!(framing, garbage_frames);
    } else {
        assert!(
            framing < garbage_frames && framing > 0,
            "{framing} framing errors"
        );
    }
    // A chunk dropped mid-frame can leave the ends of two frames that decode as one with a
    // bad CRC; without drops there is none.
    if dropped == 0 {
        assert_eq!(c.rx_crc_errors, 0);
    } else {
        assert!(u64::from(c.rx_crc_errors) + framing < garbage_frames);
    }
}
