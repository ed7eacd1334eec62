//! The firmware on the emulated Cortex-M4 (QEMU `mps2-an386`):
//! - the on-target self-test: planner step cost in instructions at full capacity (checked
//!   full: 32 obstacles, 8 agents, 32 map cells, 4 ghost goal-points for the VPF), deadline
//!   overruns under a sonar flood, stack high-water;
//! - the serial link: boots the firmware, talks to its UART through a pty, sends navigation,
//!   a mission, scanlines and garbage, and checks the commands and counters that come back;
//! - the stack guard: an image that recurses until its stack overflows must end in the hard
//!   fault's report, with a failure exit status.
//!
//! The self-test's and the stack check's console output is compared line by line with
//! `tests/expected/*.run` (as RTIC's CI does): `#` there stands for a measured number (decimal
//! or hex digits), everything else must match exactly. A change that alters a line on purpose
//! edits that file in the same commit.
//!
//! Where `qemu-system-arm` is not installed these tests say so and pass; under CI (`CI=true`)
//! they fail instead, so CI cannot skip them.

use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use vpf::link::{
    CommandRepr, Decoder, Direction, Message, NavRepr, Outcome, ReplyStatus, TelemetryRepr,
    TickRepr, MAX_FRAME,
};
use vpf::planner::HoldReason;
use vpf::sonar::Scanline;
use vpf::{Mission, Mode, NavState, Vec2};

/// Serialises firmware builds: the two configurations share one output path.
static BUILD: Mutex<()> = Mutex::new(());

fn qemu_available() -> bool {
    let found = Command::new("qemu-system-arm")
        .arg("--version")
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !found {
        assert!(
            std::env::var("CI").map_or(true, |v| v != "true"),
            "CI=true but qemu-system-arm is not installed"
        );
        eprintln!("SKIPPED: qemu-system-arm is not installed (apt-get install qemu-system-arm)");
    }
    found
}

/// Builds the release firmware with `features` and copies it to a path of its own.
fn build_firmware(features: &[&str], name: &str) -> PathBuf {
    let _guard = BUILD.lock().unwrap_or_else(|e| e.into_inner());
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut cmd = Command::new(env!("CARGO"));
    // `-p vpf`: the firmware's features alone (the HIL harness turns on host-only ones).
    cmd.current_dir(root).args([
        "build",
        "-p",
        "vpf",
        "--release",
        "--target",
        "thumbv7em-none-eabihf",
        "--bin",
        "vpf-firmware",
    ]);
    if !features.is_empty() {
        cmd.args(["--features", &features.join(",")]);
    }
    let status = cmd.status().expect("cargo runs");
    let flip_link = Command::new("flip-link")
        .stderr(Stdio::null())
        .status()
        .is_ok();
    assert!(
        status.success(),
        "firmware build failed{}",
        if flip_link {
            ""
        } else {
            " (its linker, flip-link, is not installed: cargo install flip-link --locked)"
        }
    );
    let target_dir =
        std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), PathBuf::from);
    let built = target_dir.join("thumbv7em-none-eabihf/release/vpf-firmware");
    let dir = target_dir.join("qemu-tests");
    std::fs::create_dir_all(&dir).unwrap();
    let copy = dir.join(name);
    std::fs::copy(&built, &copy).unwrap();
    copy
}

/// Kills QEMU when a test ends, however it ends.
struct Qemu(Child);

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn number_after(line: &str, key: &str) -> u64 {
    let rest = &line[line
        .find(key)
        .unwrap_or_else(|| panic!("`{key}` in {line}"))
        + key.len()..];
    rest.trim_start()
        .split(|c: char| !c.is_ascii_digit())
        .next()
        .and_then(|d| d.parse().ok())
        .unwrap_or_else(|| panic!("a number after `{key}` in {line}"))
}

#[test]
fn selftest_meets_the_budgets_on_the_emulated_cortex_m4() {
    if !qemu_available() {
        return;
    }
    let elf = build_firmware(&["selftest"], "vpf-selftest.elf");
    let out = Command::new("qemu-system-arm")
        .args(["-machine", "mps2-an386", "-cpu", "cortex-m4", "-nographic"])
        .args(["-serial", "null", "-monitor", "none", "-icount", "shift=0"])
        .args(["-semihosting-config", "enable=on,target=native", "-kernel"])
        .arg(&elf)
        .output()
        .expect("qemu runs");
    let text = String::from_utf8_lossy(&out.stdout);
    println!("{text}");
    assert_matches_expected(&text, "selftest.run");
    // One report line per strategy, each within the budget.
    // Each strategy in the spread world and in clutter (every obstacle near: the worst case),
    // and a flat-fish in traffic (the guard's worst case).
    for strategy in [
        "vpf",
        "multipoint",
        "navfn",
        "vpf in clutter",
        "multipoint in clutter",
        "navfn in clutter",
        "vpf, a flat-fish in traffic",
    ] {
        let report = text
            .lines()
            .find(|l| l.contains(&format!("selftest: {strategy} periods")))
            .unwrap_or_else(|| panic!("no report for {strategy}"));
        let max = number_after(report, "step cost max");
        let mean = number_after(report, "mean");
        let overruns = number_after(report, "overruns");
        let scanlines = number_after(report, "scanlines extracted");
        // The tables were full in every measured period (the least fill over them).
        let fill = text
            .lines()
            .find(|l| l.contains(&format!("selftest: {strategy} least table fill")))
            .unwrap_or_else(|| panic!("no table fill for {strategy}"));
        let ghosts = if strategy.starts_with("vpf") { 4 } else { 0 };
        for (table, full) in [
            ("obstacles", 32),
            ("agents", 8),
            ("map cells", 32),
            ("ghost goal-points", ghosts),
        ] {
            assert_eq!(
                number_after(fill, table),
                full,
                "{strategy}: the {table} table was not full: {fill}"
            );
        }
        assert!(
            max <= 100_000,
            "{strategy}: step cost {max} instructions over budget"
        );
        assert!(
            mean > 1_000 && mean <= max,
            "{strategy}: implausible mean {mean}"
        );
        assert_eq!(overruns, 0, "{strategy}");
        assert!(
            scanlines > 1_000,
            "{strategy}: the background was not flooded: {scanlines}"
        );
    }
    // The guard's worst case, a VideoRay among sonar contacts seen once, with the evidence
    // map empty and full: the planner's step within the budget, the guard's whole period
    // reported (the record above holds the contacts and the overruns).
    let contacts: Vec<&str> = text
        .lines()
        .filter(|l| l.contains("sonar contacts seen once ahead periods"))
        .collect();
    assert_eq!(contacts.len(), 2, "{contacts:?}");
    for line in contacts {
        let max = number_after(line, "step cost max");
        let whole = number_after(line, "whole period max");
        assert!(max <= 100_000, "{line}");
        assert!(whole > max, "{line}");
    }
    // The stack on top of the larger image's static RAM (the NUCLEO's, as recorded by
    // `.ci/sizes`) stays within the 32 KiB budget.
    let stack = number_after(&text, "stack high-water");
    let record = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("boards/stm32f446re/vpf-firmware.size"),
    )
    .expect("the NUCLEO image's size record");
    let ram: u64 = ["data", "bss"]
        .iter()
        .map(|k| number_after(&record, k))
        .sum();
    assert!(
        ram + stack <= 32 * 1024,
        "static RAM {ram} + stack high-water {stack} B over 32 KiB"
    );
    assert!(text.contains("selftest: PASS"));
    assert!(out.status.success());
}

/// Whether `line` matches `pattern`, where each `#` in the pattern stands for one or more
/// decimal or hex digits.
fn line_matches(pattern: &str, line: &str) -> bool {
    let mut l = line.chars().peekable();
    for p in pattern.chars() {
        if p == '#' {
            let mut n = 0;
            while l.next_if(|c| c.is_ascii_hexdigit()).is_some() {
                n += 1;
            }
            if n == 0 {
                return false;
            }
        } else if l.next() != Some(p) {
            return false;
        }
    }
    l.next().is_none()
}

/// Compares the console output with `tests/expected/NAME`, line by line.
fn assert_matches_expected(text: &str, name: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/expected")
        .join(name);
    let expected = std::fs::read_to_string(&path).unwrap();
    let want: Vec<&str> = expected.lines().collect();
    let got: Vec<&str> = text.lines().collect();
    for (i, (w, g)) in want.iter().zip(&got).enumerate() {
        assert!(
            line_matches(w, g),
            "{}:{}: the firmware printed\n  {g}\nwhere the record has\n  {w}\n(edit the record if \
             the change is intended)",
            path.display(),
            i + 1
        );
    }
    assert_eq!(
        got.len(),
        want.len(),
        "{}: {} lines printed, {} recorded",
        path.display(),
        got.len(),
        want.len()
    );
}

#[test]
fn expected_output_patterns_match_only_what_they_say() {
    assert!(line_matches("sp 0x#)", "sp 0x1fffffa0)"));
    assert!(line_matches("max # mean", "max 80320 mean"));
    assert!(!line_matches("max # mean", "max  mean"));
    assert!(!line_matches("overruns 0", "overruns 1"));
    assert!(!line_matches("PASS", "PASSED"));
}

#[test]
fn a_stack_overflow_ends_in_the_hard_fault_report() {
    if !qemu_available() {
        return;
    }
    let elf = build_firmware(&["stackcheck"], "vpf-stackcheck.elf");
    let out = Command::new("qemu-system-arm")
        .args(["-machine", "mps2-an386", "-cpu", "cortex-m4", "-nographic"])
        .args(["-serial", "null", "-monitor", "none", "-icount", "shift=0"])
        .args(["-semihosting-config", "enable=on,target=native", "-kernel"])
        .arg(&elf)
        .output()
        .expect("qemu runs");
    let text = String::from_utf8_lossy(&out.stdout);
    println!("{text}");
    // The guard sits below RAM (0x2000_0000); the report names a stack pointer inside it.
    assert_matches_expected(&text, "stackcheck.run");
    let sp = text
        .lines()
        .find_map(|l| l.split("(sp 0x").nth(1))
        .and_then(|h| u32::from_str_radix(h.trim_end_matches(')'), 16).ok())
        .expect("the report names the stack pointer");
    assert!(
        (0x1fff_e000..0x2000_0000).contains(&sp),
        "sp {sp:#x} is not in the guard"
    );
    assert_eq!(
        out.status.code(),
        Some(1),
        "the hard fault exits with failure"
    );
}

/// QEMU with its UART on a pty, paused until the pty is open (bytes sent before would be lost).
fn boot_on_pty(elf: &Path) -> (Qemu, std::fs::File) {
    let mut child = Command::new("qemu-system-arm")
        .args(["-machine", "mps2-an386", "-cpu", "cortex-m4", "-nographic"])
        .args(["-serial", "pty", "-monitor", "stdio", "-S"])
        .args(["-semihosting-config", "enable=on,target=native", "-kernel"])
        .arg(elf)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("qemu starts");
    // QEMU 7.2 names the pty on the monitor (stdout, with `-monitor stdio`):
    // "char device redirected to /dev/pts/N (label serial0)". (`-chardev pty,path=` is ignored.)
    let stdout = child.stdout.take().unwrap();
    let mut lines = BufReader::new(stdout).lines();
    let path = loop {
        let line = lines.next().expect("qemu names its pty").unwrap();
        if let Some(i) = line.find("/dev/pts/") {
            break line[i..].split_whitespace().next().unwrap().to_string();
        }
    };
    // Keep draining the monitor and the semihosting log, echoing the log lines.
    std::thread::spawn(move || {
        for line in lines.map_while(Result::ok) {
            if line.contains("vpf-firmware") {
                println!("firmware: {line}");
            }
        }
    });
    let pty = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(&path)
        .unwrap();
    // Raw mode: no echo, no line discipline between the test and the UART; a read returns
    // after 0.1 s without bytes.
    raw(&pty, Some((0, 1)));
    let mut stdin = child.stdin.take().unwrap();
    stdin.write_all(b"cont\n").unwrap();
    stdin.flush().unwrap();
    std::mem::forget(stdin); // keep the monitor open for the life of QEMU
    (Qemu(child), pty)
}

/// Puts a pty in raw mode (no echo, no line discipline); `(VMIN, VTIME)` if given, else
/// cfmakeraw's (a read waits for one byte).
fn raw(f: &std::fs::File, min_time: Option<(u8, u8)>) {
    use nix::sys::termios::{self, SetArg, SpecialCharacterIndices as Cc};
    let mut t = termios::tcgetattr(f).expect("tcgetattr on the pty");
    termios::cfmakeraw(&mut t);
    if let Some((min, time)) = min_time {
        t.control_chars[Cc::VMIN as usize] = min;
        t.control_chars[Cc::VTIME as usize] = time;
    }
    termios::tcsetattr(f, SetArg::TCSANOW, &t).expect("tcsetattr on the pty");
}

/// What came back from the firmware.
#[derive(Default)]
struct Received {
    decoder: Option<Decoder>,
    commands: Vec<CommandRepr>,
    telemetry: Vec<TelemetryRepr>,
    replies: Vec<vpf::link::ReplyRepr>,
}

impl Received {
    fn take(&mut self, bytes: &[u8]) {
        let d = self
            .decoder
            .get_or_insert_with(|| Decoder::accepting(Direction::ToHost));
        for &b in bytes {
            if let Outcome::Frame(_, m) = d.push(b) {
                match m {
                    Message::Command(c) => self.commands.push(c),
                    Message::Telemetry(t) => self.telemetry.push(t),
                    Message::Reply(r) => self.replies.push(r),
                    _ => {}
                }
            }
        }
    }
}

fn send(pty: &mut std::fs::File, seq: &mut u16, m: Message<'_>) {
    let mut buf = [0u8; MAX_FRAME];
    *seq = seq.wrapping_add(1);
    let n = m.emit_frame(*seq, &mut buf).unwrap();
    pty.write_all(&buf[..n]).unwrap();
}

/// Reads until `done` holds or `timeout` passes.
fn read_until(
    pty: &mut std::fs::File,
    rx: &mut Received,
    timeout: Duration,
    done: impl Fn(&Received) -> bool,
) {
    let start = Instant::now();
    let mut buf = [0u8; 4096];
    while !done(rx) && start.elapsed() < timeout {
        match pty.read(&mut buf) {
            Ok(n) => rx.take(&buf[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(e) => panic!("pty read: {e}"),
        }
    }
}

#[test]
fn firmware_answers_over_its_uart() {
    if !qemu_available() {
        return;
    }
    let elf = build_firmware(&[], "vpf-firmware.elf");
    let (_qemu, mut pty) = boot_on_pty(&elf);
    let mut rx = Received::default();
    let mut seq = 0u16;

    // Real time first: no navigation yet, so the periodic task holds, at 10 Hz.
    read_until(&mut pty, &mut rx, Duration::from_secs(20), |r| {
        r.commands.len() >= 3
    });
    assert!(rx.commands.len() >= 3, "no commands from the firmware");
    let c = rx.commands.last().unwrap().command;
    assert_eq!(c.mode, Mode::Hold(HoldReason::StaleNav));

    // Then lockstep: mission, garbage, scanlines and navigation, one Tick per period.
    send(
        &mut pty,
        &mut seq,
        Message::Mission(Mission {
            goal: Vec2::new(40.0, 10.0),
            formation: None,
        }),
    );
    pty.write_all(&[0x11, 0x22, 0x00, 0x7E, 0x00, 0x01, 0x02, 0x03])
        .unwrap();
    let mut bins = [0u8; 200];
    bins[80..84].fill(220);
    let (mut p, mut v) = (Vec2::ZERO, Vec2::ZERO);
    let first_lockstep = rx.commands.len();
    for k in 0..30u64 {
        let t = 100_000 + k * 100;
        let nav = NavState {
            position: p,
            heading: 0.0,
            velocity: v,
        };
        send(
            &mut pty,
            &mut seq,
            Message::Nav(NavRepr {
                time_ms: t,
                nav,
                body: None,
            }),
        );
        let scan = Scanline {
            time_ms: t,
            bearing_rad: -0.5 + 0.03 * k as f32,
            step_rad: 0.03,
            range_m: 20.0,
            bins: &bins,
        };
        send(&mut pty, &mut seq, Message::Scanline(scan));
        // The rest of the sweep, behind the vehicle and empty, 0.4 rad a period: the firmware
        // holds until its sonar has looked once all round (hold reason 6), about 15 periods.
        for b in 0..2u64 {
            let quiet = [0u8; 200];
            let back = Scanline {
                time_ms: t,
                bearing_rad: (0.2 * (2 * k + b) as f32) % std::f32::consts::TAU
                    - std::f32::consts::PI,
                step_rad: 0.2,
                range_m: 20.0,
                bins: &quiet,
            };
            send(&mut pty, &mut seq, Message::Scanline(back));
        }
        send(&mut pty, &mut seq, Message::Tick(TickRepr { time_ms: t }));
        let want = first_lockstep + k as usize + 1;
        // The period's command and its telemetry (a frame after it).
        read_until(&mut pty, &mut rx, Duration::from_secs(10), |r| {
            r.commands.iter().any(|c| c.time_ms == t)
                && r.commands.len() >= want
                && r.telemetry.iter().any(|tl| tl.time_ms == t)
        });
        let cmd = rx
            .commands
            .iter()
            .rev()
            .find(|c| c.time_ms == t)
            .unwrap_or_else(|| panic!("no command for tick {t}"))
            .command;
        v = cmd.velocity;
        p += v * 0.1;
    }
    let last = rx.commands.last().unwrap().command;
    let tel = rx.telemetry.last().unwrap();
    println!(
        "after 30 lockstep periods: {p:?}, v_set {:.2}, psi {:.2}, mode {:?}, counters {:?}",
        last.v_set, last.psi_set, last.mode, tel.counters
    );
    assert_eq!(
        rx.replies.first().map(|r| r.status),
        Some(ReplyStatus::Accepted)
    );
    assert_eq!(last.mode, Mode::Transit);
    assert!(last.v_set > 0.1, "not moving");
    // Heading for the active goal-point: the goal (40, 10), about 0.24 rad from near the
    // origin, or — the scanlines showed an arc of echoes 8 m ahead across that bearing — the
    // route layer's way round it (the planned velocity turns onto it at bounded force, so it
    // may still lag a little).
    let to = last.target - p;
    assert!(
        (last.psi_set - to.y.atan2(to.x)).abs() < 0.5,
        "psi {} towards {:?}",
        last.psi_set,
        last.target
    );
    assert!(
        last.psi_set > 0.0 && last.psi_set < 1.3,
        "psi {}",
        last.psi_set
    );
    assert!(tel.counters.rx_framing_errors + tel.counters.rx_crc_errors >= 1);
    // 151 frames sent; the background publishes its counters after the chunk that held the
    // Tick, so the last telemetry is up to a period's frames (five) and a few more behind.
    assert!(tel.counters.rx_frames >= 140, "{}", tel.counters.rx_frames);
    assert_eq!(tel.counters.deadline_overruns, 0);
    assert_eq!(tel.cost_unit, vpf::link::CostUnit::Instructions);
    // A step's cost is reported; not necessarily the last one's: without `-icount`, under a
    // busy host the paused SysTick may reload late and one period's cost read 0
    // (`PeriodTimer::count`; seen once in CI, the last telemetry's step_cost 0).
    assert!(
        rx.telemetry.iter().any(|t| t.step_cost > 0),
        "no step cost in any telemetry"
    );
}

#[path = "common/pymavlink.rs"]
mod pymavlink;

/// The board image's MAVLink UART (UART2, QEMU's third serial port) against pymavlink as the
/// autopilot and the ground station (`tests/common/pymavlink.rs`), in real time: the same
/// script and the same checks as the host-process firmware's test (tests/mavlink.rs).
#[test]
fn the_board_image_speaks_mavlink_to_a_pymavlink_autopilot_and_ground_station() {
    if !qemu_available() || !pymavlink::available() {
        return;
    }
    let elf = build_firmware(&[], "vpf-firmware-mavlink");
    let (mut py, pty, mut lines) = pymavlink::start();
    // UART0 on a pty of its own (the rock goes there), UART1 unconnected, UART2 on the
    // script's pty.
    let mut child = Command::new("qemu-system-arm")
        .args(["-machine", "mps2-an386", "-cpu", "cortex-m4", "-nographic"])
        .args(["-serial", "pty", "-serial", "null", "-serial", &pty])
        .args(["-monitor", "stdio", "-S"])
        .args(["-semihosting-config", "enable=on,target=native", "-kernel"])
        .arg(&elf)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("qemu starts");
    let stdout = child.stdout.take().unwrap();
    let mut monitor = BufReader::new(stdout).lines();
    let path = loop {
        let line = monitor.next().expect("qemu names its pty").unwrap();
        if let Some(i) = line.find("/dev/pts/") {
            break line[i..].split_whitespace().next().unwrap().to_string();
        }
    };
    std::thread::spawn(move || for _ in monitor.map_while(Result::ok) {});
    let mut stdin = child.stdin.take().unwrap();
    let qemu = Qemu(child);
    let mut uart0 = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(&path)
        .unwrap();
    raw(&uart0, None);
    stdin.write_all(b"cont\n").unwrap();
    stdin.flush().unwrap();
    uart0.write_all(&pymavlink::rock()).unwrap();
    // Drain the control link (command, telemetry) so its transmit queue never fills.
    let mut drain = uart0.try_clone().unwrap();
    std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        while drain.read(&mut buf).is_ok_and(|n| n > 0) {}
    });
    let report = lines.next().expect("the script reports").unwrap();
    let status = py.wait().unwrap();
    drop(qemu);
    println!("{report}");
    assert!(status.success(), "the pymavlink script failed");
    pymavlink::check(&report);
}
