//! `hil echoes` on a real run: the pings one VideoRay's sonar aimed at another, and at a rock,
//! detected where their near faces truly were.

use std::path::{Path, PathBuf};

use hil::echoes::{echoes, Args, EchoesError};
use hil::firmware::Target;
use hil::runner::{hull_radius, run, RunConfig};
use hil::scenario::ModelKind;

/// Both hold station: v1 12 m east of v0, a rock 10 m north of it.
const SCENARIO: &str = r#"
name = "echoes"
duration_s = 12.0
dt_s = 0.1
seed = 5

[sonar]
mode = "scanlines"

[[vehicle]]
name = "v0"
model = "videoray"
start = [0.0, 0.0]
heading_deg = 0.0
goal = [0.0, 0.0]
sensing = "sonar"

[[vehicle]]
name = "v1"
model = "videoray"
start = [12.0, 0.0]
heading_deg = 180.0
goal = [12.0, 0.0]
sensing = "sonar"

[[obstacle]]
shape = "circle"
center = [0.0, 10.0]
radius = 1.5
"#;

fn out_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/hil-tests/echoes")
}

fn args(towards: Option<&str>, point: Option<[f64; 2]>) -> Args {
    Args {
        run: out_dir(),
        vehicle: "v0".into(),
        towards: towards.map(String::from),
        point: point.map(|p| p.to_vec()),
        between: vec![0.0, 12.0],
        within: 6.0,
        all: false,
    }
}

#[test]
fn the_pings_towards_a_vehicle_and_a_rock_hear_their_near_faces() {
    let _ = std::fs::remove_dir_all(out_dir());
    std::fs::create_dir_all(out_dir()).unwrap();
    let file = out_dir().join("echoes.toml");
    std::fs::write(&file, SCENARIO).unwrap();
    let sc = hil::scenario::load(&file).unwrap_or_else(|e| panic!("{e}"));
    let cfg = RunConfig {
        target: Target::Host,
        out_dir: out_dir(),
        progress: false,
    };
    run(&sc, &cfg).unwrap_or_else(|e| panic!("run failed: {e}"));

    // The head turns in 3.2 s: three sweeps or more, each with a ping or two at the target.
    let near = |pings: &[hil::echoes::Ping], face: f64| {
        (pings.iter())
            .filter(|p| p.echoes.iter().any(|e| (f64::from(e.0) - face).abs() < 0.5))
            .count()
    };
    let vehicle = echoes(&args(Some("v1"), None)).unwrap();
    let face = 12.0 - hull_radius(ModelKind::VideoRay);
    assert!(vehicle
        .iter()
        .all(|p| p.off_deg.abs() <= 6.0 && (p.distance_m - 12.0).abs() < 0.5));
    assert!(near(&vehicle, face) >= 3, "{vehicle:#?}");
    let rock = echoes(&args(None, Some([0.0, 10.0]))).unwrap();
    assert!(near(&rock, 8.5) >= 3, "{rock:#?}");
    // Looking the other way finds neither.
    let nothing = echoes(&args(None, Some([0.0, -10.0]))).unwrap();
    assert_eq!(
        near(&nothing, 8.5) + near(&nothing, face),
        0,
        "{nothing:#?}"
    );

    // The command line says what each echo would be to the extractor.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_hil"))
        .arg("echoes")
        .arg(out_dir())
        .args(["--towards", "v1", "--between", "0,12"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(
        text.lines()
            .any(|l| l.contains("off the target") && l.contains(" mean ")),
        "{text}"
    );
}

#[test]
fn a_missing_target_or_run_is_refused() {
    assert!(matches!(
        echoes(&args(None, None)),
        Err(EchoesError::Usage(_))
    ));
    let mut a = args(Some("v1"), None);
    a.run = out_dir().join("no_such_run");
    assert!(matches!(echoes(&a), Err(EchoesError::Io(_))));
    let mut a = args(Some("v1"), None);
    a.between = vec![5.0, 1.0];
    assert!(matches!(echoes(&a), Err(EchoesError::Usage(_))));
}
