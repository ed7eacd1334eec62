//! `hil beliefs` on a real run: the frame log replayed through the host firmware gives back
//! what the firmware believed — the mission's route (so the log holds the set-up requests), a
//! rock where it is, and a crossing target moving the way it moves.

use std::path::{Path, PathBuf};

use hil::beliefs::{beliefs, BeliefsError};
use hil::firmware::Target;
use hil::runner::{run, RunConfig};
use vpf::world::Origin;
use vpf::Vec2;

const SCENARIO: &str = r#"
name = "beliefs"
duration_s = 40.0
dt_s = 0.1
seed = 2

[sonar]
mode = "scanlines"

[[vehicle]]
name = "v0"
model = "videoray"
start = [0.0, 0.0]
heading_deg = 0.0
goal = [1.0, 0.0]
sensing = "sonar"

[[obstacle]]
shape = "circle"
center = [-12.0, 6.0]
radius = 2.0

[[obstacle]]
shape = "circle"
center = [8.0, -20.0]
radius = 1.5
velocity = [0.0, 0.8]
"#;

fn out_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/hil-tests/beliefs")
}

#[test]
fn a_replayed_frame_log_gives_back_the_route_the_rock_and_the_mover() {
    let _ = std::fs::remove_dir_all(out_dir());
    std::fs::create_dir_all(out_dir()).unwrap();
    let file = out_dir().join("beliefs.toml");
    std::fs::write(&file, SCENARIO).unwrap();
    let sc = hil::scenario::load(&file).unwrap_or_else(|e| panic!("{e}"));
    let cfg = RunConfig {
        target: Target::Host,
        out_dir: out_dir(),
        progress: false,
    };
    run(&sc, &cfg).unwrap_or_else(|e| panic!("run failed: {e}"));
    let frames = out_dir().join("frames_v0.log");

    let all = beliefs(&frames, &[5.0, 39.0, 1e6], 10.0).unwrap();
    // The time after the log's end is left out.
    assert_eq!(all.len(), 2);
    let end = &all[1];
    print!("{end}");
    assert!(
        end.now_ms > 38_000 && end.now_ms <= 39_000,
        "{}",
        end.now_ms
    );
    // The mission went out before the first period: without it in the log there is no goal
    // and no route.
    assert!(
        all[0].route.is_some(),
        "no route at 5 s: the set-up is not in the log"
    );
    let sonar = || end.obstacles.iter().filter(|o| o.origin == Origin::Sonar);
    let rock = Vec2::new(-12.0, 6.0);
    let still = sonar()
        .find(|o| (o.shape.center() - rock).norm() < 1.5 && o.velocity == Vec2::ZERO)
        .unwrap_or_else(|| panic!("no still track at the rock"));
    // A sweep takes about 9 s: by 39 s the rock has been seen on several of them, and the
    // printout says how often.
    let rock_track = end.tracks.iter().find(|t| t.id == still.id).unwrap();
    assert!(rock_track.hits >= 3, "{rock_track:?}");
    assert!(end.to_string().contains(" times, last "), "{end}");
    // By then the head has looked along every bearing: the lookout vouches for the way ahead
    // as far as the kept beam ran.
    assert!(end.lookout_end.is_some());
    assert!(end
        .to_string()
        .contains("lookout ahead: the kept beam ended at"));
    // The target moves north at 0.8 m/s: its track, seen at least twice by now, says so.
    assert!(
        sonar().any(|o| o.velocity.y > 0.5 && o.velocity.x.abs() < 0.3),
        "no track moving north"
    );

    // `--tracks` lists each sonar track's filter: the rock's is borne out where it stands.
    assert!(
        rock_track.steady >= 1 && rock_track.velocity.norm() < 0.3,
        "{rock_track:?}"
    );
    let listed = std::process::Command::new(env!("CARGO_BIN_EXE_hil"))
        .arg("beliefs")
        .arg(&frames)
        .args(["--tracks", "--at", "39"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&listed.stdout);
    assert!(listed.status.success(), "{text}");
    let line = format!("    track #{:04x}: centre ", still.id);
    assert!(
        text.lines()
            .any(|l| l.starts_with(&line) && l.contains(" in a row where predicted")),
        "{text}"
    );

    // `hil beliefs … | head`: a reader that goes away early ends the command quietly. Every
    // second with its cells is more than a pipe holds, so the write meets the closed pipe.
    let times: Vec<String> = (1..40).map(|t| t.to_string()).collect();
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_hil"))
        .arg("beliefs")
        .arg(&frames)
        .args(["--radius", "20", "--cells", "--at", &times.join(",")])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{:?}: {stderr}", out.status);
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn times_out_of_order_and_a_missing_log_are_refused() {
    let missing = out_dir().join("no_such_frames.log");
    assert!(matches!(
        beliefs(&missing, &[3.0, 2.0], 10.0),
        Err(BeliefsError::Times(_))
    ));
    assert!(matches!(
        beliefs(&missing, &[f64::NAN], 10.0),
        Err(BeliefsError::Times(_))
    ));
    assert!(matches!(
        beliefs(&missing, &[1.0], 10.0),
        Err(BeliefsError::Log(_))
    ));
}
