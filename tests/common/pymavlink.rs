//! The pymavlink script (`tests/pymavlink/autopilot_gcs.py`: an ArduSub autopilot and
//! QGroundControl) against a firmware's MAVLink line, and what its report must show. Shared by
//! tests/mavlink.rs (the host-process firmware) and tests/qemu.rs (the board image on QEMU).
#![allow(dead_code)]

use std::io::{BufRead, BufReader, Lines};
use std::process::{Child, ChildStdout, Command, Stdio};

use vpf::field::Shape;
use vpf::link::{ChartObstacleRepr, Message, MAX_FRAME};
use vpf::Vec2;

/// Whether Python with pymavlink is here. Where it is not, says so in one line (the caller
/// returns); under CI (`CI=true`, whose script installs it) it fails instead.
pub fn available() -> bool {
    let found = Command::new("python3")
        .args(["-c", "import pymavlink"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !found {
        assert!(
            std::env::var("CI").map_or(true, |v| v != "true"),
            "CI=true but Python with pymavlink is not installed (.ci/run installs it)"
        );
        eprintln!("SKIPPED: python3 with pymavlink is not installed (pip install pymavlink)");
    }
    found
}

/// The running script, the pty it made (for the firmware's MAVLink port), and its output.
pub fn start() -> (Child, String, Lines<BufReader<ChildStdout>>) {
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/pymavlink/autopilot_gcs.py"
    );
    let mut py = Command::new("python3")
        .arg(script)
        .env("RUN_S", "14")
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("python3 starts");
    let mut lines = BufReader::new(py.stdout.take().unwrap()).lines();
    let first = lines.next().expect("the script names its pty").unwrap();
    let pty = first.strip_prefix("PTY ").expect("PTY line").to_string();
    (py, pty, lines)
}

/// A charted rock 5 m to the east (starboard of a vehicle heading north), radius 1 m, as a
/// frame for the firmware's own link (x east, y north).
pub fn rock() -> Vec<u8> {
    let rock = Message::ChartObstacle(ChartObstacleRepr {
        id: 7,
        a_plus: 2.5,
        shape: Shape::circle(Vec2::new(5.0, 0.0), 1.0).unwrap(),
    });
    let mut buf = [0u8; MAX_FRAME];
    let n = rock.emit_frame(1, &mut buf).unwrap();
    buf[..n].to_vec()
}

/// What the script's report must show: the mission uploaded and accepted, set-points at the
/// period heading for each waypoint in turn (the second given in latitude and longitude),
/// status texts, heartbeats, and the rock in OBSTACLE_DISTANCE.
pub fn check(report: &str) {
    let seen: serde_json::Value = serde_json::from_str(report).expect("JSON");

    // The mission protocol: both items requested, the upload accepted.
    assert_eq!(
        seen["mission_requests"],
        serde_json::json!([0, 1]),
        "{seen}"
    );
    assert_eq!(seen["mission_ack"], 0, "MAV_MISSION_ACCEPTED");
    // Set-points at the period (≥ 5 Hz over 14 s), velocity and yaw, local NED.
    let setpoints = seen["setpoints"].as_u64().unwrap();
    assert!(setpoints >= 70, "{setpoints} set-points in 14 s");
    for m in seen["type_masks"].as_array().unwrap() {
        assert_eq!(
            m.as_u64(),
            Some(u64::from(vpf::guidance::mavlink::SETPOINT_TYPE_MASK))
        );
    }
    assert!(seen["frames"].as_array().unwrap().iter().all(|f| f == 1));
    assert!(seen["heartbeats"].as_u64().unwrap() >= 10);
    // Before the mission a hold, and STATUSTEXT saying so; then transit.
    let texts: Vec<String> = seen["statustext"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_str().unwrap_or("").to_string())
        .collect();
    assert!(texts.iter().any(|t| t.contains("no mission")), "{texts:?}");
    assert!(
        texts.iter().any(|t| t.contains("mission accepted")),
        "{texts:?}"
    );
    assert!(texts.iter().any(|t| t.contains("transit")), "{texts:?}");
    // The velocity targets head for the first waypoint (8 m north): the first moving one
    // points north within 30°, and the simulated vehicle that followed them got closer.
    let first = &seen["first_moving_setpoint"];
    let (vn, ve) = (first[0].as_f64().unwrap(), first[1].as_f64().unwrap());
    let off = ve.atan2(vn).to_degrees();
    assert!(
        off.abs() < 30.0,
        "first velocity target {vn:.2} N {ve:.2} E, {off:.0}° off north"
    );
    let fin = &seen["final"];
    let (n, e) = (fin[0].as_f64().unwrap(), fin[1].as_f64().unwrap());
    let to_wp1 = (8.0 - n).hypot(0.0 - e);
    assert!(
        to_wp1 < 6.0,
        "still {to_wp1:.1} m from the first waypoint at ({n:.1}, {e:.1})"
    );
    // Past the first, the targets head for the second waypoint, given in latitude and
    // longitude (20 m north, 10 m east of the origin): the firmware converted it with the
    // autopilot's GPS_GLOBAL_ORIGIN.
    let last = &seen["last_setpoint"];
    let (lvn, lve, lyaw) = (
        last[0].as_f64().unwrap(),
        last[1].as_f64().unwrap(),
        last[2].as_f64().unwrap(),
    );
    let (ln, le) = (last[3].as_f64().unwrap(), last[4].as_f64().unwrap());
    let bearing = (10.0 - le).atan2(20.0 - ln);
    let course = lve.atan2(lvn);
    let diff = |a: f64, b: f64| {
        (a - b + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
    };
    assert!(
        lvn.hypot(lve) > 0.1 && diff(course, bearing).abs() < 0.5 && diff(lyaw, bearing).abs() < 0.5,
        "last target {lvn:.2} N {lve:.2} E yaw {lyaw:.2} at ({ln:.1}, {le:.1}): the second waypoint bears {bearing:.2}"
    );
    // OBSTACLE_DISTANCE shows the charted rock (5 m east of the origin, radius 1 m): in the
    // sector of its bearing from where the vehicle was (body frame: clockwise from the bow),
    // at its surface distance; the opposite sector believes nothing.
    let od = &seen["obstacle_distance"];
    assert_eq!(od["frame"], 12, "MAV_FRAME_BODY_FRD");
    assert_eq!(od["increment"], 5);
    let d: Vec<u64> = od["distances"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect();
    assert_eq!(d.len(), 72);
    let max = od["max"].as_u64().unwrap();
    let (an, ae) = (od["at"][0].as_f64().unwrap(), od["at"][1].as_f64().unwrap());
    let yaw = od["yaw"].as_f64().unwrap();
    let (dn, de) = (0.0 - an, 5.0 - ae);
    let cw = (de.atan2(dn) - yaw).to_degrees().rem_euclid(360.0);
    let sector = ((cw / 5.0).round() as usize) % 72;
    let near = [(sector + 71) % 72, sector, (sector + 1) % 72]
        .iter()
        .map(|&i| d[i])
        .min()
        .unwrap();
    let expected_cm = (dn.hypot(de) - 1.0) * 100.0;
    println!("rock at {cw:.0}° clockwise (sector {sector}): {near} cm, expected {expected_cm:.0}");
    assert!(
        (near as f64 - expected_cm).abs() < 60.0,
        "sector {sector}: {near} cm, expected {expected_cm:.0} cm: {d:?}"
    );
    assert_eq!(
        d[(sector + 36) % 72],
        max + 1,
        "something believed opposite: {d:?}"
    );
}
