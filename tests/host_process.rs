//! The firmware as a host process (`vpf-firmware` built for the host), over stdin/stdout in
//! lockstep: the same protocol and runtime as on the board.

use std::io::{Read, Write};
use std::process::{Command, Stdio};

use vpf::link::{Decoder, Direction, Message, NavRepr, Outcome, TickRepr, MAX_FRAME};
use vpf::{Mission, Mode, NavState, Vec2};

fn frame(seq: u16, m: Message<'_>) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME];
    let n = m.emit_frame(seq, &mut buf).unwrap();
    buf[..n].to_vec()
}

#[test]
fn host_process_plans_in_lockstep_over_stdio() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_vpf-firmware"))
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the host firmware starts");
    let mut input = Vec::new();
    input.extend(frame(
        1,
        Message::Mission(Mission {
            goal: Vec2::new(10.0, 0.0),
            formation: None,
        }),
    ));
    for k in 0..20u64 {
        // A fix that changes (the same fix over and over while commanded to move is frozen
        // navigation, and the firmware holds).
        let nav = NavState {
            position: Vec2::new(0.001 * k as f32, 0.0),
            heading: 0.0,
            velocity: Vec2::ZERO,
        };
        let t = k * 100;
        input.extend(frame(
            2,
            Message::Nav(NavRepr {
                time_ms: t,
                nav,
                body: None,
            }),
        ));
        input.extend(frame(3, Message::Tick(TickRepr { time_ms: t })));
    }
    let mut stdin = child.stdin.take().unwrap();
    stdin.write_all(&input).unwrap();
    drop(stdin); // end of input: the process drains and exits
    let mut out = Vec::new();
    child.stdout.take().unwrap().read_to_end(&mut out).unwrap();
    let status = child.wait().unwrap();
    assert!(status.success());

    let mut d = Decoder::accepting(Direction::ToHost);
    let mut commands = Vec::new();
    let mut replies = 0;
    for b in out {
        match d.push(b) {
            Outcome::Frame(_, Message::Command(c)) => commands.push(c),
            Outcome::Frame(_, Message::Reply(_)) => replies += 1,
            _ => {}
        }
    }
    assert_eq!(replies, 1);
    let lockstep: Vec<_> = commands.iter().filter(|c| c.time_ms < 2000).collect();
    assert!(lockstep.len() >= 20, "{} commands", lockstep.len());
    let last = lockstep.last().unwrap().command;
    assert_eq!(last.mode, Mode::Transit);
    assert!(last.velocity.x > 0.0 && last.velocity.y.abs() < 1e-3);
}

#[test]
fn host_process_refuses_bad_arguments() {
    let out = Command::new(env!("CARGO_BIN_EXE_vpf-firmware"))
        .arg("--bogus")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown argument `--bogus`"));
}
