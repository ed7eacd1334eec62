//! `hil sweep`: the spec's errors, the generated scenarios, resuming, sharding and merging, and
//! the criterion. The sweeps here are tiny (8 short runs on the host-process firmware).

use std::path::{Path, PathBuf};

use hil::sweep::generate::{self, Kind};
use hil::sweep::measure::RunRow;
use hil::sweep::spec::{self, Value};
use hil::sweep::{criterion, merge, sweep, Options};

fn scratch(test: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../target/hil-tests/sweep")
        .join(test);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// 2 parameter sets × (1 file + 2 clutter + 1 passage) = 8 runs.
fn tiny_spec(dir: &Path) -> PathBuf {
    let gap = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/narrow_gap.toml");
    let text = format!(
        r#"name = "tiny"
seed = 11

[craft]
model = "videoray"
margin_m = 0.4

[planner]
max_ghosts = 4

[sweep]
params.a_rotor = [0.0, 5.0]

[scenarios]
files = ["{}"]
duration_cap_s = 40.0
clutter = 2
passage = 1
length_m = [20.0, 25.0]
speed_mps = 1.0
time_factor = 1.5
"#,
        gap.display()
    );
    let p = dir.join("tiny.toml");
    std::fs::write(&p, text).unwrap();
    p
}

fn opts(out: &Path) -> Options {
    Options {
        out: Some(out.to_path_buf()),
        jobs: Some(2),
        quiet: true,
        ..Options::default()
    }
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The error message for `text` as a sweep file.
fn refusal(text: &str) -> String {
    match spec::parse(text, "bad.toml") {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

const GOOD: &str = r#"name = "ok"
seed = 1

[craft]
model = "videoray"
margin_m = 0.5

[planner]
mu = 0.4

[sweep]
mode = "grid"

[sweep.params]
a_rotor = [0.0, 5.0]
v_max = [0.5, 1.0]

[scenarios]
clutter = 1
"#;

#[test]
fn spec_errors_name_file_line_and_key() {
    let s = spec::parse(GOOD, "good.toml").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.sets.len(), 4);
    assert_eq!(s.sets[1], [Value::Float(0.0), Value::Float(1.0)]);

    let cases = [
        // (replace, with, expected message start)
        ("a_rotor = [0.0, 5.0]", "a_rotr = [0.0, 5.0]", "bad.toml:15: key `sweep.params.a_rotr`: not a [planner] parameter"),
        ("mu = 0.4", "mu = 40.0", "bad.toml:9: key `planner.mu`: must be in 0 ..= 10"),
        ("margin_m = 0.5", "margin_m = -1", "bad.toml:6: key `craft.margin_m`: must be in 0 ..= 100, got -1"),
        ("model = \"videoray\"", "model = \"submarine\"", "bad.toml:5: key `craft.model`: unknown vehicle model"),
        ("v_max = [0.5, 1.0]", "v_max = [0.5, 30.0]", "bad.toml:16: key `sweep.params.v_max`: parameter set 1 (a_rotor = 0.0, v_max = 30.0) is refused"),
        ("v_max = [0.5, 1.0]", "v_max = { min = 0.5, max = 1.0 }", "bad.toml:16: key `sweep.params.v_max`: a range { min, max } needs mode = \"random\""),
        ("v_max = [0.5, 1.0]", "v_max = [0.5, 0.5]", "bad.toml:16: key `sweep.params.v_max[1]`: value 0.5 is listed twice"),
        ("clutter = 1", "clutter = 0", "bad.toml:18: key `scenarios`: no scenario"),
        ("clutter = 1", "cluter = 1", "bad.toml:19: key `scenarios.cluter`: unknown key in [scenarios]"),
        ("mu = 0.4", "a_rotor = 1.0", "bad.toml:15: key `sweep.params.a_rotor`: is also fixed in [planner]"),
        ("seed = 1\n", "", "bad.toml:1: key `seed`: missing required key"),
    ];
    for (from, to, want) in cases {
        assert!(GOOD.contains(from), "{from}");
        let msg = refusal(&GOOD.replacen(from, to, 1));
        assert!(msg.starts_with(want), "got:  {msg}\nwant: {want}");
    }
    let random = GOOD
        .replace("mode = \"grid\"", "mode = \"random\"\nsamples = 5")
        .replace(
            "v_max = [0.5, 1.0]",
            "v_max = { min = 0.3, max = 2.0, log = true }",
        );
    let s = spec::parse(&random, "random.toml").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.sets.len(), 5);
    for set in &s.sets {
        let v = set[1].number().unwrap();
        assert!((0.3..=2.0).contains(&v), "{v}");
    }
    assert_eq!(
        spec::parse(&random, "random.toml").unwrap().sets,
        s.sets,
        "random draws are seeded"
    );
}

#[test]
fn generated_scenarios_are_deterministic_and_valid() {
    let text = GOOD.replace(
        "clutter = 1",
        "clutter = 6\npassage = 6\nutrap = 6\nmin_gap_m = 3.0\npassage_gap_m = [2.5, 4.0]",
    );
    let s = spec::parse(&text, "gen.toml").unwrap();
    for kind in [Kind::Clutter, Kind::Passage, Kind::UTrap] {
        for i in 0..6 {
            let a = generate::generate(&s, kind, i);
            let b = generate::generate(&s, kind, i);
            assert_eq!(a.text, b.text, "{} is not deterministic", a.id);
            let sc = hil::scenario::parse(&a.text, &a.id).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(sc.vehicles.len(), 1);
            let length = a.goal.sub(a.start).norm();
            assert!((20.0..=90.0).contains(&length), "{}: {length} m", a.id);
            assert!(!a.obstacles.is_empty(), "{}", a.id);
            let clear = |p: hil::types::P2| {
                a.obstacles
                    .iter()
                    .map(|o| o.signed_distance(p))
                    .fold(f64::INFINITY, f64::min)
            };
            assert!(clear(a.start) >= 3.0, "{}: start not free", a.id);
            assert!(clear(a.goal) >= 3.0, "{}: goal not free", a.id);
            match kind {
                Kind::Passage => {
                    let (c, w) = a.opening.expect("a passage has an opening");
                    assert!((2.5..=4.0).contains(&w));
                    // Nothing closer to the opening's centre than its half-width (3 decimals
                    // in the file).
                    assert!(clear(c) >= w / 2.0 - 0.01, "{}: opening closed", a.id);
                }
                Kind::Clutter => {
                    // The straight line is blocked, and the obstacles keep their gaps.
                    let blocked = (0..=100).any(|k| {
                        let t = f64::from(k) / 100.0;
                        clear(a.start.add(a.goal.sub(a.start).scale(t))) < 0.5
                    });
                    assert!(blocked, "{}: straight line free", a.id);
                    for (j, o) in a.obstacles.iter().enumerate() {
                        for q in &a.obstacles[j + 1..] {
                            let gap = o.center().sub(q.center()).norm()
                                - o.bounding_radius()
                                - q.bounding_radius();
                            assert!(gap >= 3.0 - 0.01, "{}: gap {gap}", a.id);
                        }
                    }
                }
                Kind::UTrap => assert_eq!(a.obstacles.len(), 3),
            }
        }
    }
    // Another spec seed, other scenarios.
    let other = spec::parse(&text.replace("seed = 1", "seed = 2"), "gen.toml").unwrap();
    assert_ne!(
        generate::generate(&s, Kind::Clutter, 0).text,
        generate::generate(&other, Kind::Clutter, 0).text
    );
}

#[test]
fn a_sweep_resumes_and_its_shards_merge_to_the_same_result() {
    let dir = scratch("resume_shard");
    let spec_path = tiny_spec(&dir);

    // Unsharded, all 8 runs.
    let full = dir.join("full");
    let o = sweep(&spec_path, &opts(&full)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((o.ran, o.skipped, o.report.runs), (8, 0, 8));
    let runs = read(&full.join("runs.csv"));
    assert_eq!(runs.lines().count(), 9);
    for f in [
        "sets.csv",
        "ranking.md",
        "heatmap_success.svg",
        "heatmap_clearance.svg",
        "recipe.toml",
    ] {
        assert!(full.join(f).is_file(), "{f} missing");
    }
    let recipe = read(&full.join("recipe.toml"));
    let params = hil::scenario::parse_planner(&recipe, "recipe.toml", 0.1)
        .unwrap_or_else(|e| panic!("the recipe is not a [planner] table: {e}"));
    assert_eq!(params.max_ghosts, 4);

    // Again: nothing to do.
    let o = sweep(&spec_path, &opts(&full)).unwrap();
    assert_eq!((o.ran, o.skipped), (0, 8));

    // Interrupted: the last three rows lost and the one before cut off mid-line.
    let lines: Vec<&str> = runs.lines().collect();
    let kept = lines[..5].join("\n") + "\n" + &lines[5][..lines[5].len() / 2];
    std::fs::write(full.join("runs.csv"), kept).unwrap();
    let o = sweep(&spec_path, &opts(&full)).unwrap();
    assert_eq!((o.ran, o.skipped), (4, 4), "resumed the missing runs only");
    assert_eq!(
        read(&full.join("runs.csv")),
        runs,
        "the resumed sweep differs"
    );

    // A changed spec is refused in the same directory.
    let changed = read(&spec_path).replace("seed = 11", "seed = 12");
    let changed_path = dir.join("changed.toml");
    std::fs::write(&changed_path, changed).unwrap();
    let err = sweep(&changed_path, &opts(&full)).err().expect("refused");
    assert!(
        matches!(err, hil::error::Error::Mismatch(_))
            && err.to_string().contains("holds another sweep"),
        "{err}"
    );

    // Shards 1/2 and 2/2, merged: the same files as unsharded.
    let shard = |k: usize| {
        let out = dir.join(format!("shard{k}"));
        let o = sweep(
            &spec_path,
            &Options {
                shard: Some((k, 2)),
                ..opts(&out)
            },
        )
        .unwrap();
        assert_eq!(o.ran, 4);
        out
    };
    let (a, b) = (shard(1), shard(2));
    let merged = dir.join("merged");
    let (report, _, total) = merge(&[a.clone(), b], &merged).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((report.runs, total), (8, 8));
    for f in [
        "runs.csv",
        "sets.csv",
        "ranking.md",
        "heatmap_success.svg",
        "heatmap_clearance.svg",
        "recipe.toml",
    ] {
        // The report's date is the only line allowed to differ (a run over midnight).
        let strip = |p: PathBuf| {
            read(&p)
                .lines()
                .filter(|l| !l.starts_with("# date") && !l.starts_with("- date"))
                .collect::<Vec<_>>()
                .join("\n")
        };
        assert_eq!(strip(merged.join(f)), strip(full.join(f)), "{f} differs");
    }
    // A shard of another sweep is not merged in.
    let err = merge(&[a, dir.join("nonexistent")], &dir.join("m2")).err();
    assert!(err.is_some());
}

#[test]
fn the_criterion_ranks_a_collision_below_any_collision_free_set() {
    let row = |set: usize, success: bool, collided: bool, clearance: f64| RunRow {
        run: 0,
        set,
        scenario: "s".into(),
        success,
        collided,
        min_clearance_m: clearance,
        path_ratio: 1.0,
        time_s: 10.0,
        energy: 10.0,
        oscillation: 0.0,
        ghosts: 0,
        sim_time_s: 10.0,
        error: String::new(),
    };
    // Set 0 succeeds 9 times in 10 and grazes a rock once; set 1 never arrives, safely.
    let mut rows: Vec<RunRow> = (0..9).map(|_| row(0, true, false, 2.0)).collect();
    rows.push(row(0, false, true, -0.01));
    rows.extend((0..10).map(|_| row(1, false, false, 3.0)));
    let ranked = criterion::rank(&rows, 2, 0.5, &Default::default());
    assert_eq!(ranked[0].set, 1);
    assert_eq!(ranked[1].collided, 1);
}

#[test]
fn a_sweep_batch_takes_the_benchmarks_worlds() {
    let text = GOOD.replace(
        "clutter = 1",
        "clutter = 1\nbench_families = [\"harbour\", \"serpentine\"]\nbench_count = 2",
    );
    let s = spec::parse(&text, "bench.toml").unwrap_or_else(|e| panic!("{e}"));
    let batch = generate::batch(&s, Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"))
        .scenarios;
    let ids: Vec<&str> = batch.iter().map(|b| b.id.as_str()).collect();
    for id in [
        "bench:harbour:0",
        "bench:harbour:1",
        "bench:serpentine:0",
        "bench:serpentine:1",
    ] {
        assert!(ids.contains(&id), "{id} missing from {ids:?}");
    }
    // The same world the benchmark flies (same obstacles).
    let b = batch.iter().find(|b| b.id == "bench:harbour:1").unwrap();
    let w = hil::bench::worlds::generate(hil::bench::worlds::Family::Harbour, 1, 0, 0.2);
    assert_eq!(b.scenario.obstacles.len(), w.obstacles.len());
    // Other seeds: `bench_first_seed`.
    let later = spec::parse(
        &text.replace("bench_count = 2", "bench_count = 2\nbench_first_seed = 100"),
        "bench.toml",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let batch = generate::batch(&later, Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"))
        .scenarios;
    assert!(batch.iter().any(|b| b.id == "bench:harbour:101"));
    assert!(!batch.iter().any(|b| b.id == "bench:harbour:1"));
    let bad = refusal(&GOOD.replace(
        "clutter = 1",
        "clutter = 1\nbench_families = [\"reef\"]\nbench_count = 1",
    ));
    assert!(
        bad.contains("reef") || bad.contains("bench family"),
        "{bad}"
    );
}

/// A bench world with no draw the craft can fly is left out of the batch, as `hil bench`
/// leaves it unflown, and named; the rest of the batch stands.
#[test]
fn a_sweep_leaves_out_a_bench_world_the_craft_cannot_fly() {
    let text = GOOD.replace("model = \"videoray\"", "model = \"flatfish\"").replace(
        "clutter = 1",
        "clutter = 1\nbench_families = [\"serpentine\"]\nbench_count = 2\nbench_first_seed = 102",
    );
    let s = spec::parse(&text, "flatfish.toml").unwrap_or_else(|e| panic!("{e}"));
    let batch = generate::batch(&s, Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
    let ids: Vec<&str> = batch.scenarios.iter().map(|b| b.id.as_str()).collect();
    assert_eq!(ids, ["clutter:0", "bench:serpentine:102"]);
    assert_eq!(batch.left_out.len(), 1);
    assert_eq!(batch.left_out[0].0, "bench:serpentine:103");
    assert!(
        batch.left_out[0].1.contains("no draw fits"),
        "{:?}",
        batch.left_out
    );
    // Nothing left to fly is refused.
    let none = text.replace("clutter = 1\n", "clutter = 0\n").replace(
        "bench_count = 2\nbench_first_seed = 102",
        "bench_count = 1\nbench_first_seed = 103",
    );
    let s = spec::parse(&none, "flatfish.toml").unwrap_or_else(|e| panic!("{e}"));
    let e = generate::batch(&s, Path::new("."))
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no scenario to fly") && e.contains("serpentine:103"),
        "{e}"
    );
}
