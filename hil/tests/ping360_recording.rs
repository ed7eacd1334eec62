//! A real Ping360 recording through the firmware's Ping360 parser, driver, feature extractor
//! and evidence map.
//!
//! The data: `shared/data/ping360/` beside the repository (101 `device_data` messages from a
//! Blue Robotics Ping360 in a test tank, dumped as text by Blue Robotics' `brping` decoder with
//! the checksum it logged; see that folder's README). It stays outside the repository. The test
//! looks for it in `$VPF_PING360_DATA`, else in `shared/data/ping360` beside the repository
//! root or beside any folder above it (a worktree sits deeper). Where it is absent the test
//! says SKIPPED in one line and passes; under `CI=true` it must be there.
//!
//! What the data shows (read from the raw samples, `first sample ≥ 100` of a 4-sample mean,
//! printed by this test): the sonar looks down a narrow channel. At angles 150–170 the nearest
//! echo is a wall whose perpendicular distance `r·|sin(θ − θ₂₀₀)|` is 0.19–0.22 m; at angles
//! 197–215 the end wall at 1.42–1.45 m; at angles 225–250 the other side wall at 0.28–0.33 m.
//! Between them (≈190 and ≈220) the corners, where the beam grazes and the echo is weak.

use std::path::PathBuf;

use hil::ping360::dump::{self, DumpMessage};
use vpf::link::ping::{checksum, Decoder, Event, Frame, Message};
use vpf::math::Vec2;
use vpf::sonar::detect::detect;
use vpf::sonar::ping360::{Ping360, Ping360Config};
use vpf::sonar::{EvidenceConfig, EvidenceMap, Extractor, ExtractorConfig, Feature, Pose};

const FILE: &str = "2024-03-13_15-50-16_gain0_device_data.txt";

/// Where the recording is, if anywhere.
fn recording() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os("VPF_PING360_DATA") {
        return Some(PathBuf::from(dir).join(FILE)).filter(|p| p.is_file());
    }
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    // hil/ → the repository root → its parent, and on up.
    root.ancestors()
        .skip(2)
        .map(|a| a.join("shared/data/ping360").join(FILE))
        .find(|p| p.is_file())
}

/// The detection settings for this tank, from the data (see the module notes): raw
/// intensities (gain setting 0; no range compensation over 2 m), threshold 100 between the
/// background (median 26–55 per ping past the ringdown) and the walls' peaks (114–176), echoes
/// ≥ 120 at their peak, blanking 0.15 m past the transducer's ringing (it ends by 0.135 m, checked below), runs
/// broken by gaps over 2 cm, the nearest run per beam, clusters of hits within 10 cm.
fn tank() -> ExtractorConfig {
    ExtractorConfig {
        threshold: 100.0,
        peak_min: 120.0,
        gain_per_m: 0.0,
        gain_max: 1.0,
        blanking_m: 0.15,
        run_gap_m: 0.02,
        min_run_bins: 2,
        runs_per_beam: 1,
        cluster_gap_m: 0.1,
        max_missed_beams: 1,
        min_beams: 3,
        min_confidence: 0.3,
        wall_half_thickness_m: 0.05,
        min_radius_m: 0.02,
        ..ExtractorConfig::default()
    }
}

/// The nearest detection of each ping: (head angle, bow-relative bearing, range).
type Detection = (u16, f32, f32);

#[test]
fn a_real_ping360_recording_through_the_firmware() {
    let Some(path) = recording() else {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true but the Ping360 recording is missing: set VPF_PING360_DATA or put \
             shared/data/ping360/ beside the repository"
        );
        println!(
            "SKIPPED: no Ping360 recording (shared/data/ping360/{FILE}; or set VPF_PING360_DATA)"
        );
        return;
    };
    let msgs: Vec<DumpMessage> = dump::read(&path).unwrap();
    assert_eq!(msgs.len(), 101, "messages in the dump");

    // 1. Every binary frame rebuilt by the firmware's encoder has the logged checksum, and the
    //    fields the dump logged: an oracle no one here wrote.
    let mut stream = Vec::new();
    for (i, m) in msgs.iter().enumerate() {
        assert!(m.pass, "message {i}: the dump's decoder did not pass it");
        assert_eq!((m.message_id, m.src, m.dst), (2300, 2, 0));
        assert_eq!(usize::from(m.payload_length), 14 + m.data.len());
        assert_eq!(usize::from(m.data_length), m.data.len());
        let f = m.frame().unwrap();
        assert_eq!(f.len(), 8 + usize::from(m.payload_length) + 2);
        let frame = Frame::new_checked(&f[..]).unwrap();
        assert_eq!(frame.checksum(), m.checksum, "message {i}: checksum");
        assert_eq!(checksum(&f[..f.len() - 2]), m.checksum);
        stream.extend_from_slice(&f);
    }
    let angles: Vec<u16> = msgs.iter().map(|m| m.settings.angle).collect();
    assert_eq!(angles, (150..=250).collect::<Vec<u16>>());
    println!(
        "recording: {} frames, {} bytes, every checksum as logged",
        msgs.len(),
        stream.len()
    );

    // 2. The stream decoder, fed the frames back to back in UART-sized pieces, gives every
    //    field and every sample as dumped.
    let mut dec = Decoder::new();
    let (mut heads, mut samples, mut ends) = (Vec::new(), Vec::<Vec<u8>>::new(), 0);
    for piece in stream.chunks(61) {
        let mut rest = piece;
        while !rest.is_empty() {
            let (n, ev) = dec.feed(rest);
            match ev {
                Event::DataHead(_, h) => {
                    heads.push(h);
                    samples.push(Vec::new());
                }
                Event::Data(k) => samples
                    .last_mut()
                    .unwrap()
                    .extend_from_slice(&rest[n - k..n]),
                Event::DataEnd(_) => ends += 1,
                other => assert_eq!(other, Event::Nothing),
            }
            rest = &rest[n..];
        }
    }
    assert_eq!((heads.len(), ends), (101, 101));
    assert_eq!(dec.counters().frames, 101);
    assert_eq!(
        (dec.counters().checksum, dec.counters().skipped),
        (0, 0),
        "nothing dropped"
    );
    for (i, m) in msgs.iter().enumerate() {
        assert_eq!(heads[i].settings, m.settings, "message {i}: fields");
        assert_eq!(heads[i].data_len, m.data_length);
        assert_eq!(samples[i], m.data, "message {i}: samples");
        let bytes = m.frame().unwrap();
        let frame = Frame::new_checked(&bytes[..]).unwrap();
        assert!(matches!(frame.message(), Ok(Message::DeviceData(d))
            if d.settings == m.settings && d.data == &m.data[..]));
    }

    // The transducer's ringing (a 4-sample mean ≥ 100) ends before the blanking distance of
    // 0.15 m in every ping.
    let sample_m = 90.0 * 25e-9 * 1500.0 / 2.0;
    let mut worst_ring = 0.0f64;
    for m in &msgs {
        let ring_end = (0..300)
            .map(|b| b * 4)
            .find(|&i| m.data[i..i + 4].iter().map(|&v| u32::from(v)).sum::<u32>() < 400)
            .unwrap();
        assert!(
            (ring_end as f64) * sample_m < 0.15,
            "angle {}: ringing to {:.3} m",
            m.settings.angle,
            ring_end as f64 * sample_m
        );
        worst_ring = worst_ring.max(ring_end as f64 * sample_m);
    }
    println!("transducer ringing ends by {worst_ring:.3} m in every ping (blanking 0.15 m)");

    // 3. The driver turns the same stream into scanlines for the extractor and the evidence
    //    map, as the firmware runs it (the sonar still, at the origin, bow along +x).
    let cfg = Ping360Config {
        start_grad: 150,
        width_grad: 100,
        step_grad: 1,
        samples: 1200,
        sample_period: 90,
        transmit_duration_us: 16,
        frequency_khz: 1000,
        gain: 0,
        ..Ping360Config::default()
    };
    let mut driver = Ping360::new(cfg).unwrap();
    let mut extractor = Extractor::new(tank()).unwrap();
    let map = EvidenceMap::new(EvidenceConfig {
        cell_m: 0.1,
        stop_short_m: 0.05,
        ..EvidenceConfig::default()
    })
    .unwrap();
    let pose = Pose {
        position: Vec2::ZERO,
        heading: 0.0,
    };
    let mut detections: Vec<Detection> = Vec::new();
    let mut features: Vec<Feature> = Vec::new();
    let mut ranges = Vec::new();
    for (i, f) in stream.chunks(1224).enumerate() {
        let angle_of = msgs[i].settings.angle;
        driver.on_bytes(
            f,
            50 * i as u64,
            Some(pose),
            &mut |_| true,
            &mut |scan, p| {
                assert_eq!(p, Some(pose));
                ranges.push((scan.range_m, scan.bins.len()));
                if let Some(e) = detect(scan, &tank()).first() {
                    detections.push((angle_of, scan.bearing_rad, e.range_m));
                }
                extractor
                    .push_scanline_mapped(scan, pose, Some(&map), &mut |f| {
                        features.push(f);
                        true
                    })
                    .unwrap();
            },
        );
    }
    extractor.flush(&mut |f| {
        features.push(f);
        true
    });
    let c = driver.counters();
    assert_eq!(
        (c.data, c.checksum_errors, c.malformed, c.bytes_skipped),
        (101, 0, 0, 0)
    );
    // Range from the sample period: 300 bins of 4 samples × 90 × 25 ns × 1500 m/s ÷ 2.
    for &(r, n) in &ranges {
        assert_eq!(n, 300);
        assert!((r - 2.025).abs() < 1e-4, "range {r}");
    }

    // 4. Detections at the tank's walls, angle by angle. Tolerances: the spread the raw data
    //    shows (module notes) widened by one bin (4 samples, 6.75 mm) for the pooling.
    let bin = 4.0 * sample_m as f32;
    let perp = |b: f32, r: f32| r * b.sin().abs();
    let check =
        |lo: u16, hi: u16, what: &str, value: &dyn Fn(f32, f32) -> f32, (a, b): (f32, f32)| {
            let got: Vec<(u16, f32)> = detections
                .iter()
                .filter(|d| (lo..=hi).contains(&d.0))
                .map(|d| (d.0, value(d.1, d.2)))
                .collect();
            assert!(
                got.len() as u16 >= hi - lo,
                "{what}: detections on only {} of {} pings",
                got.len(),
                hi - lo + 1
            );
            for (angle, v) in &got {
                assert!(
                    (a - bin..=b + bin).contains(v),
                    "{what}, angle {angle}: {v:.3} m outside {a}–{b} m (± one bin)"
                );
            }
            let mut vs: Vec<f32> = got.iter().map(|g| g.1).collect();
            vs.sort_by(f32::total_cmp);
            println!(
                "{what} (angles {lo}–{hi}): {} detections, {:.3}–{:.3} m, median {:.3} m",
                vs.len(),
                vs[0],
                vs[vs.len() - 1],
                vs[vs.len() / 2]
            );
        };
    check(
        150,
        170,
        "side wall, angles below 200: distance abeam",
        &perp,
        (0.19, 0.22),
    );
    check(197, 215, "end wall: range", &|_, r| r, (1.42, 1.45));
    check(
        225,
        250,
        "side wall, angles above 200: distance abeam",
        &perp,
        (0.28, 0.33),
    );

    // 5. The evidence map (0.1 m cells here) believes the walls and not the water between.
    let w = map.window().unwrap();
    let occupied =
        |x: f32, y: f32| map.is_occupied(w, (x / 0.1).floor() as i32, (y / 0.1).floor() as i32);
    let believed: Vec<(i32, i32)> = (-10..20)
        .flat_map(|i| (-10..10).map(move |j| (i, j)))
        .filter(|&(i, j)| map.is_occupied(w, i, j))
        .collect();
    println!(
        "evidence map: {} cells of 0.1 m believed occupied",
        believed.len()
    );
    assert!(occupied(1.43, 0.0), "the end wall ahead");
    for x in [0.3, 0.6, 0.9, 1.2] {
        assert!(!occupied(x, 0.0), "open water ahead at {x} m");
    }
    // Every believed cell is on a wall: near the end wall's range, or beyond one of the side
    // walls' distances abeam (their cells, 0.1 m wide, may reach a cell past the wall).
    for (i, j) in &believed {
        let (x, y) = ((*i as f32 + 0.5) * 0.1, (*j as f32 + 0.5) * 0.1);
        let r = x.hypot(y);
        let on_end = (1.30..=1.60).contains(&r);
        let on_side = y.abs() >= 0.1;
        assert!(on_end || on_side, "cell ({x:.2}, {y:.2}) is in open water");
    }

    // 6. The extractor's features: each lies on the walls, none in the open water ahead.
    println!("extractor: {} features", features.len());
    assert!(!features.is_empty());
    for f in &features {
        let shape = f.to_shape().unwrap();
        let d = shape.signed_distance(Vec2::ZERO);
        assert!(d > 0.1, "a feature within 0.1 m of the sonar: {f:?}");
        assert!(
            shape.signed_distance(Vec2::new(0.7, -0.05)) > 0.0,
            "a feature covers the open water ahead: {f:?}"
        );
    }
}
