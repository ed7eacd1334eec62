//! The harness's own limits (issue 11 §7): sweeps past a total of runs, scenarios past the
//! firmware's tables by more than a factor, names that cannot become directory names, frame
//! logs past their size, output directories that cannot be written, and `--help` everywhere.
//! Each is refused or capped at once, with a message naming the limit, never after a flight.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use hil::output::frames::{Dir, FrameLog};
use hil::scenario::{self, MAX_NAME_CHARS, MAX_OBSTACLES, MAX_SCENARIO_BYTES};
use hil::sweep::spec::{self, MAX_RUNS};

fn scratch(test: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../target/hil-tests/limits")
        .join(test);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn hil(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_hil"))
        .args(args)
        .output()
        .expect("hil runs")
}

// --- hil sweep: the product of the factors -----------------------------------------------------

/// A sweep of `sets` parameter sets (a grid over `a_rotor`) × `clutter` generated scenarios.
fn sweep_spec(sets: usize, clutter: usize) -> String {
    let values: Vec<String> = (0..sets)
        .map(|i| format!("{:.3}", i as f64 * 0.01))
        .collect();
    format!(
        r#"name = "big"
seed = 1

[craft]
model = "videoray"
margin_m = 0.4

[sweep]
params.a_rotor = [{}]

[scenarios]
clutter = {clutter}
"#,
        values.join(", ")
    )
}

#[test]
fn a_sweep_past_its_total_of_runs_is_refused_naming_the_product() {
    // Each factor is within its own cap; their product is one past the total.
    let (sets, clutter) = (400, MAX_RUNS / 400 + 1);
    let text = sweep_spec(sets, clutter);
    let e = spec::parse(&text, "big.toml").expect_err("a sweep past MAX_RUNS");
    let msg = e.to_string();
    let runs = sets * clutter;
    assert!(
        msg.contains(&format!(
            "{sets} parameter sets × {clutter} scenarios = {runs} runs"
        )),
        "{msg}"
    );
    assert!(msg.contains(&format!("at most {MAX_RUNS}")), "{msg}");
    assert_eq!(e.key, "scenarios");
    assert_eq!(
        e.line,
        1 + text[..text.find("[scenarios]").unwrap()]
            .matches('\n')
            .count()
    );

    // Exactly at the total, it is accepted (and nothing was generated to decide either way).
    let ok = spec::parse(&sweep_spec(sets, MAX_RUNS / 400), "big.toml").unwrap();
    assert_eq!(ok.sets.len() * ok.scenarios.count(), MAX_RUNS);
}

// --- scenarios ----------------------------------------------------------------------------------

fn scenario_text(name: &str, vehicle: &str, obstacles: usize) -> String {
    let mut t = format!(
        r#"name = "{name}"
duration_s = 10.0
dt_s = 0.1
seed = 7

[[vehicle]]
name = "{vehicle}"
model = "kinematic"
start = [0.0, 0.0]
goal = [10.0, 0.0]
"#
    );
    // Small rocks in rows far from the track.
    for i in 0..obstacles {
        let (x, y) = ((i % 40) as f64 * 3.0, 50.0 + (i / 40) as f64 * 3.0);
        write!(
            t,
            "\n[[obstacle]]\nshape = \"circle\"\ncenter = [{x:.1}, {y:.1}]\nradius = 0.5\n"
        )
        .unwrap();
    }
    t
}

#[test]
fn a_scenario_past_its_obstacle_factor_is_refused_at_the_first_one_too_many() {
    let ok = scenario::parse(&scenario_text("s", "a", MAX_OBSTACLES), "ok.toml").unwrap();
    assert_eq!(ok.obstacles.len(), MAX_OBSTACLES);

    let text = scenario_text("s", "a", MAX_OBSTACLES + 1);
    let e = scenario::parse(&text, "many.toml").expect_err("one obstacle too many");
    assert_eq!(e.key, format!("obstacle[{MAX_OBSTACLES}]"));
    let last_header = 1 + text[..text.rfind("[[obstacle]]").unwrap()]
        .matches('\n')
        .count();
    assert!(
        (last_header..last_header + 4).contains(&e.line),
        "line {}, the last obstacle starts at {last_header}",
        e.line
    );
    assert!(
        e.message.contains(&format!("at most {MAX_OBSTACLES}")),
        "{e}"
    );
    assert!(e.message.contains("16 × the firmware's table of 32"), "{e}");
}

#[test]
fn names_that_cannot_become_directory_names_are_refused() {
    let long = "n".repeat(MAX_NAME_CHARS);
    assert!(scenario::parse(&scenario_text(&long, "a", 0), "ok.toml").is_ok());
    assert!(scenario::parse(&scenario_text("s", &long, 0), "ok.toml").is_ok());

    let too_long = "é".repeat(MAX_NAME_CHARS + 1); // counted in characters, not bytes
    let e = scenario::parse(&scenario_text(&too_long, "a", 0), "name.toml").unwrap_err();
    assert_eq!((e.key.as_str(), e.line), ("name", 1));
    assert!(
        e.message.contains(&format!("at most {MAX_NAME_CHARS}")),
        "{e}"
    );
    let e = scenario::parse(&scenario_text("s", &too_long, 0), "name.toml").unwrap_err();
    assert_eq!((e.key.as_str(), e.line), ("vehicle[0].name", 7));

    let e = scenario::parse(&scenario_text(" \t", "a", 0), "name.toml").unwrap_err();
    assert_eq!(e.key, "name");
}

#[test]
fn a_scenario_file_past_its_size_is_refused_before_it_is_parsed() {
    // Valid TOML that would parse: padded with a comment past the size.
    let mut text = scenario_text("s", "a", 0);
    text.push_str(&format!("# {}\n", "x".repeat(MAX_SCENARIO_BYTES)));
    let e = scenario::parse(&text, "huge.toml").unwrap_err();
    assert!(
        e.message.contains(&format!("at most {MAX_SCENARIO_BYTES}")),
        "{e}"
    );

    let dir = scratch("huge");
    let path = dir.join("huge.toml");
    std::fs::write(&path, &text).unwrap();
    let e = scenario::load(&path).unwrap_err();
    assert!(e.message.contains(&format!("{} bytes", text.len())), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

// --- frame logs -----------------------------------------------------------------------------

#[test]
fn a_frame_log_stops_at_its_limit_says_so_and_still_replays() {
    let dir = scratch("frames");
    let limit = 1000;
    let chunk = [0xabu8; 20]; // a line of about 66 bytes
    {
        let mut log = FrameLog::create_with_limit(&dir, "v", limit).unwrap();
        for k in 0..100 {
            log.log(f64::from(k) * 0.1, Dir::ToFirmware, &chunk)
                .unwrap();
        }
        assert!(log.truncated());
        log.flush().unwrap();
    }
    let path = dir.join("frames_v.log");
    let text = std::fs::read_to_string(&path).unwrap();
    let last = text.lines().last().unwrap();
    assert!(
        last.starts_with("# truncated: this log reached its limit of 1000 bytes"),
        "{last}"
    );
    // The limit holds for the logged lines; the note is the only thing past it.
    assert!(text.len() as u64 - last.len() as u64 - 1 <= limit);
    let replayed = FrameLog::replay(&path).unwrap();
    assert!(!replayed.is_empty() && replayed.len() < 100);
    assert!(replayed
        .iter()
        .all(|(_, d, b)| *d == Dir::ToFirmware && b[..] == chunk));
    let _ = std::fs::remove_dir_all(&dir);
}

// --- hil run: the output directory, before the flight -----------------------------------------

#[test]
fn hil_run_refuses_an_output_directory_it_cannot_write_before_it_flies() {
    let dir = scratch("out");
    let file = dir.join("a-file");
    std::fs::write(&file, "not a directory").unwrap();
    let out_dir = file.join("run");
    let sc = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/narrow_gap.toml");
    let out = hil(&[
        "run",
        sc.to_str().unwrap(),
        "--firmware",
        "host",
        "--quiet",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!(
            "cannot write the outputs to {}",
            out_dir.display()
        )),
        "{err}"
    );
    // Nothing flew: no summary, no outputs.
    assert!(!String::from_utf8_lossy(&out.stdout).contains("outputs in"));
    let _ = std::fs::remove_dir_all(&dir);
}

// --- --help -----------------------------------------------------------------------------------

#[test]
fn every_subcommand_answers_help_with_its_usage() {
    for cmd in [
        "run",
        "check",
        "sweep",
        "merge",
        "compare",
        "bench",
        "faults",
        "sonar-replay",
        "ping360-raw",
    ] {
        for flag in ["--help", "-h"] {
            let out = hil(&[cmd, flag]);
            let stdout = String::from_utf8_lossy(&out.stdout);
            assert!(
                out.status.success(),
                "hil {cmd} {flag}: {:?}\n{}",
                out.status,
                String::from_utf8_lossy(&out.stderr)
            );
            assert!(stdout.contains("usage"), "hil {cmd} {flag}: {stdout}");
            assert!(
                stdout.contains(&format!("hil {cmd}")),
                "hil {cmd} {flag}: {stdout}"
            );
        }
    }
}

#[test]
fn a_bad_command_line_is_refused_with_status_2_naming_the_option() {
    for (args, names) in [
        (&["run", "a.toml", "--baud", "9600"][..], "--port"),
        (&["run", "a.toml", "--drop-rate", "2"][..], "--drop-rate"),
        (&["run", "a.toml", "--nav-loss", "80:60"][..], "FROM < TO"),
        (&["bench", "--seeds", "0"][..], "--seeds"),
        (&["sweep", "s.toml", "--shard", "3/2"][..], "1 <= K <= N"),
        (&["faults", "--kinds", "ber,eels"][..], "eels"),
        (&["compare", "--jobs", "0"][..], "--jobs"),
        (&["check"][..], "SCENARIO.toml"),
        (&["fly"][..], "fly"),
    ] {
        let out = hil(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "hil {args:?}: {err}");
        assert!(err.contains(names), "hil {args:?}: {err}");
    }
}
