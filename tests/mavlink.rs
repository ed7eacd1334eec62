//! The MAVLink line against an implementation no one here wrote: pymavlink plays an ArduSub
//! autopilot and QGroundControl (`tests/pymavlink/autopilot_gcs.py`) against the host-process
//! firmware's `--mavlink` port, in real time. Where Python with pymavlink is missing the test
//! says so in one line and passes; under CI (`CI=true`, which installs it) it must run. The
//! board image on QEMU meets the same script in tests/qemu.rs.

use std::io::{Read, Write};
use std::process::{Command, Stdio};

#[path = "common/pymavlink.rs"]
mod pymavlink;

#[test]
fn pymavlink_autopilot_and_ground_station_fly_a_mission_and_see_a_charted_obstacle() {
    if !pymavlink::available() {
        return;
    }
    let (mut py, pty, mut lines) = pymavlink::start();
    let mut fw = Command::new(env!("CARGO_BIN_EXE_vpf-firmware"))
        .args(["--mavlink", &pty])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the host firmware starts");
    let mut stdin = fw.stdin.take().unwrap();
    stdin.write_all(&pymavlink::rock()).unwrap();
    stdin.flush().unwrap();
    let mut out = fw.stdout.take().unwrap();
    let drain = std::thread::spawn(move || {
        let mut sink = Vec::new();
        let _ = out.read_to_end(&mut sink);
    });
    let report = lines.next().expect("the script reports").unwrap();
    let status = py.wait().unwrap();
    drop(stdin);
    let _ = fw.kill();
    let _ = fw.wait();
    let _ = drain.join();
    let mut err = String::new();
    let _ = fw.stderr.take().unwrap().read_to_string(&mut err);
    eprintln!("{err}");
    println!("{report}");
    assert!(status.success(), "the pymavlink script failed");
    pymavlink::check(&report);
}
