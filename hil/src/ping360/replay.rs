//! `hil sonar-replay --ping360 FILE`: raw Ping protocol bytes (a stream of frames as a Ping360
//! sends them) through the firmware's own Ping360 driver and feature extractor, and what they
//! found: frames accepted, checksum errors, bytes skipped, each ping's nearest echo, the
//! features with bearing and range; optionally an SVG plot (pings as seen from above).
//!
//! The sonar is taken to be still at the origin, its bow along +x (no navigation in a raw
//! recording). `hil ping360-raw DUMP.txt OUT.bin` makes such a file from a `brping` text dump
//! (each frame rebuilt and checked against the checksum the dump logged).

use std::fmt::Write as _;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use vpf::math::Vec2;
use vpf::sonar::detect::detect;
use vpf::sonar::ping360::{Ping360, Ping360Config, Ping360Counters};
use vpf::sonar::{Extractor, ExtractorConfig, Feature, FeatureKind, Pose};

use crate::output::svg::{Frame, Svg};

/// Largest file read, bytes (a 360° sweep of 1200-sample pings is under 0.5 MB).
pub const MAX_REPLAY_BYTES: u64 = 256 << 20;

/// `hil sonar-replay`'s command line.
#[derive(Clone, Debug, clap::Parser)]
#[command(
    name = "hil sonar-replay",
    long_about = "Raw Ping360 bytes through the firmware's parser and extractor.",
    after_help = "The other extractor settings are the firmware's defaults. For the tank \
                  recording in shared/data/ping360/ (2 m range, gain 0): --threshold 100 --peak \
                  120 --blanking-m 0.15 --gain-per-m 0 --cluster-gap-m 0.1. Making such a file \
                  from a brping text dump: hil ping360-raw --help."
)]
pub struct Args {
    /// the raw Ping bytes
    #[arg(long, value_name = "FILE")]
    ping360: PathBuf,
    /// draw the pings' echoes and the features, seen from above
    #[arg(long, value_name = "FILE.svg")]
    plot: Option<PathBuf>,
    /// head step the sweep used, gradians (default 1)
    #[arg(long, value_name = "G")]
    step: Option<u16>,
    /// m/s (default 1500)
    #[arg(long, value_name = "C")]
    sound_speed: Option<f32>,
    /// bearing of head angle 0 from the bow, degrees counter-clockwise (default 180)
    #[arg(long, value_name = "DEG[:ccw]", value_parser = mount)]
    mount: Option<(f32, bool)>,
    /// detection threshold on the (gain-compensated) intensity (default 90)
    #[arg(long, value_name = "X")]
    threshold: Option<f32>,
    /// least peak of an echo run (default 120, at least the threshold)
    #[arg(long, value_name = "X")]
    peak: Option<f32>,
    /// ignore echoes nearer than this, m (default 1.0)
    #[arg(long, value_name = "M")]
    blanking_m: Option<f32>,
    /// range compensation slope, per m (default 0.04)
    #[arg(long, value_name = "K")]
    gain_per_m: Option<f32>,
    /// largest range step between beams of one feature, m (default 1.0)
    #[arg(long, value_name = "M")]
    cluster_gap_m: Option<f32>,
}

/// `DEG[:ccw]` → (zero bearing in rad, clockwise).
fn mount(v: &str) -> Result<(f32, bool), String> {
    let (deg, sense) = v.split_once(':').unwrap_or((v, "cw"));
    let deg: f32 = deg
        .parse()
        .map_err(|_| format!("`{deg}` is not a number"))?;
    Ok((deg.to_radians(), sense != "ccw"))
}

/// `hil ping360-raw`'s command line.
#[derive(Clone, Debug, clap::Parser)]
#[command(
    name = "hil ping360-raw",
    long_about = "A brping text dump of device_data messages as raw Ping bytes (each frame rebuilt and \
             checked against the checksum the dump logged), for hil sonar-replay."
)]
pub struct RawArgs {
    /// the brping text dump
    #[arg(value_name = "DUMP.txt")]
    dump: PathBuf,
    /// the raw bytes written
    #[arg(value_name = "OUT.bin")]
    out: PathBuf,
}

/// Why `hil sonar-replay` or `hil ping360-raw` stopped.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The driver's settings are refused by the firmware's driver.
    #[error("the Ping360 settings: {0}")]
    Driver(#[from] vpf::sonar::ping360::ConfigError),
    /// The extractor's settings are refused by the firmware's extractor.
    #[error("the extractor settings: {0}")]
    Extractor(vpf::sonar::ConfigError),
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The recording is larger than [`MAX_REPLAY_BYTES`].
    #[error("{}: larger than {MAX_REPLAY_BYTES} bytes", path.display())]
    TooLarge {
        /// The recording.
        path: PathBuf,
    },
    /// The text dump does not read, or a message does not rebuild.
    #[error(transparent)]
    Dump(#[from] super::dump::DumpError),
    /// A rebuilt frame's checksum is not the one the dump logged.
    #[error("message {message}: rebuilt checksum {rebuilt}, the dump logged {logged}")]
    Checksum {
        /// Which message.
        message: usize,
        /// The rebuilt frame's.
        rebuilt: u16,
        /// The dump's.
        logged: u16,
    },
}

impl ReplayError {
    /// For `map_err`: reading or writing `path` failed.
    fn io(path: &Path) -> impl Fn(std::io::Error) -> ReplayError + '_ {
        move |source| ReplayError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// One ping as replayed: head angle, bow-relative bearing (rad), range (m), the nearest echo's
/// range if any, and the scanline's bins.
#[derive(Clone, Debug, PartialEq)]
pub struct Ping {
    /// Head angle, gradians.
    pub angle: u16,
    /// Bearing from the bow, counter-clockwise, rad.
    pub bearing: f32,
    /// Range of the scanline, m.
    pub range_m: f32,
    /// Nearest echo's leading edge, m.
    pub echo_m: Option<f32>,
}

/// What a replay found.
#[derive(Clone, Debug, Default)]
pub struct Replay {
    /// The driver's counters (frames accepted = `data`).
    pub counters: Ping360Counters,
    /// Each ping.
    pub pings: Vec<Ping>,
    /// The features extracted.
    pub features: Vec<Feature>,
}

/// Replays `bytes` with the driver set by `cfg` and the extractor by `ex`.
pub fn replay(
    bytes: &[u8],
    cfg: Ping360Config,
    ex: ExtractorConfig,
) -> Result<Replay, ReplayError> {
    let mut driver = Ping360::new(cfg)?;
    let mut extractor = Extractor::new(ex).map_err(ReplayError::Extractor)?;
    let pose = Pose {
        position: Vec2::ZERO,
        heading: 0.0,
    };
    let mut out = Replay::default();
    // Fed as a UART would deliver it, 64 bytes at a time, 10 ms of firmware time per chunk.
    for (i, chunk) in bytes.chunks(64).enumerate() {
        driver.on_bytes(
            chunk,
            10 * i as u64,
            Some(pose),
            &mut |_| true,
            &mut |scan, _| {
                // The head angle back from the bearing (the mounting's inverse).
                let sense = if cfg.clockwise { 1.0 } else { -1.0 };
                let angle = ((cfg.zero_bearing_rad - scan.bearing_rad) * sense
                    / vpf::sonar::ping360::RAD_PER_GRAD)
                    .round()
                    .rem_euclid(400.0) as u16;
                out.pings.push(Ping {
                    angle,
                    bearing: scan.bearing_rad,
                    range_m: scan.range_m,
                    echo_m: detect(scan, &ex).first().map(|e| e.range_m),
                });
                let _ = extractor.push_scanline(scan, pose, &mut |f| {
                    out.features.push(f);
                    true
                });
            },
        );
    }
    extractor.flush(&mut |f| {
        out.features.push(f);
        true
    });
    out.counters = driver.counters();
    Ok(out)
}

/// The SVG of a replay, seen from above with the bow along +x (to the right): each ping's
/// beam (grey) and nearest echo (red dot), the features (blue).
pub fn plot(r: &Replay) -> String {
    let reach = r
        .pings
        .iter()
        .map(|p| p.range_m)
        .fold(0.5f32, f32::max)
        .min(200.0) as f64;
    let (w, h) = (720.0, 720.0);
    let f = Frame {
        left: 70.0,
        top: 30.0,
        width: 620.0,
        height: 620.0,
        x0: -reach,
        x1: reach,
        y0: -reach,
        y1: reach,
    };
    let mut svg = Svg::new(w, h);
    let step = crate::output::svg::nice_step(2.0 * reach, 8.0);
    f.axes(&mut svg, step, step, Some("x (ahead), m"), "y (to port), m");
    for p in &r.pings {
        let (c, s) = (f64::from(p.bearing).cos(), f64::from(p.bearing).sin());
        let end = f64::from(p.range_m);
        svg.line(
            f.px(0.0),
            f.py(0.0),
            f.px(c * end),
            f.py(s * end),
            "stroke=\"#ccc\" stroke-width=\"0.6\"",
        );
        if let Some(e) = p.echo_m.map(f64::from) {
            svg.circle(f.px(c * e), f.py(s * e), 2.5, "fill=\"#c0392b\"");
        }
    }
    for feat in &r.features {
        let (cx, cy) = (f64::from(feat.center.x), f64::from(feat.center.y));
        match feat.kind {
            FeatureKind::Circle { radius } => svg.circle(
                f.px(cx),
                f.py(cy),
                f64::from(radius) * f.sx(),
                "fill=\"none\" stroke=\"#1f5fbf\" stroke-width=\"1.5\"",
            ),
            FeatureKind::Rectangle { half, angle } => {
                let (c, s) = (f64::from(angle).cos(), f64::from(angle).sin());
                let (a, b) = (f64::from(half.x), f64::from(half.y));
                let pts: Vec<(f64, f64)> = [(a, b), (-a, b), (-a, -b), (a, -b)]
                    .iter()
                    .map(|(u, v)| (f.px(cx + c * u - s * v), f.py(cy + s * u + c * v)))
                    .collect();
                svg.polygon(
                    &pts,
                    "fill=\"none\" stroke=\"#1f5fbf\" stroke-width=\"1.5\"",
                );
            }
        }
    }
    svg.circle(f.px(0.0), f.py(0.0), 4.0, "fill=\"#333\"");
    svg.text(
        f.left,
        18.0,
        &format!(
            "{} pings: echoes (red), features (blue); sonar at the origin",
            r.pings.len()
        ),
        "font-size=\"13\"",
    );
    svg.finish()
}

fn read_bounded(path: &Path) -> Result<Vec<u8>, ReplayError> {
    let f = std::fs::File::open(path).map_err(ReplayError::io(path))?;
    let mut bytes = Vec::new();
    f.take(MAX_REPLAY_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(ReplayError::io(path))?;
    if bytes.len() as u64 > MAX_REPLAY_BYTES {
        return Err(ReplayError::TooLarge {
            path: path.to_path_buf(),
        });
    }
    Ok(bytes)
}

/// `hil sonar-replay`.
pub fn cli(args: Args) -> ExitCode {
    let mut cfg = Ping360Config {
        step_grad: 1,
        samples: 1200,
        sample_period: 80,
        ..Ping360Config::default()
    };
    let mut ex = ExtractorConfig::default();
    let set = |to: &mut f32, v: Option<f32>| *to = v.unwrap_or(*to);
    cfg.step_grad = args.step.unwrap_or(cfg.step_grad);
    set(&mut cfg.sound_speed, args.sound_speed);
    if let Some((zero, clockwise)) = args.mount {
        (cfg.zero_bearing_rad, cfg.clockwise) = (zero, clockwise);
    }
    set(&mut ex.threshold, args.threshold);
    set(&mut ex.peak_min, args.peak);
    set(&mut ex.blanking_m, args.blanking_m);
    set(&mut ex.gain_per_m, args.gain_per_m);
    set(&mut ex.cluster_gap_m, args.cluster_gap_m);
    let (file, plot_to) = (args.ping360, args.plot);
    let run = || -> Result<(), ReplayError> {
        let bytes = read_bounded(&file)?;
        let r = replay(&bytes, cfg, ex)?;
        let c = r.counters;
        let mut text = String::new();
        let _ = writeln!(
            text,
            "{}: {} bytes; {} device_data frames accepted, {} checksum errors, {} malformed, {} bytes skipped (resyncs on 'B' 'R')",
            file.display(),
            bytes.len(),
            c.data,
            c.checksum_errors,
            c.malformed,
            c.bytes_skipped
        );
        for p in &r.pings {
            let _ = writeln!(
                text,
                "  angle {:3} grad, bearing {:+7.1} deg, range {:6.3} m: {}",
                p.angle,
                p.bearing.to_degrees(),
                p.range_m,
                p.echo_m.map_or("no echo".to_string(), |e| format!(
                    "nearest echo at {e:.3} m"
                ))
            );
        }
        let _ = writeln!(text, "{} features:", r.features.len());
        for f in &r.features {
            let _ = writeln!(
                text,
                "  {} at bearing {:+6.1} deg, range {:.3} m (centre ({:.3}, {:.3}) m, radius {:.3} m), {} beams, confidence {:.2}",
                match f.kind {
                    FeatureKind::Circle { .. } => "circle",
                    _ => "rectangle",
                },
                f.center.y.atan2(f.center.x).to_degrees(),
                f.center.norm(),
                f.center.x,
                f.center.y,
                f.radius,
                f.beams,
                f.confidence
            );
        }
        if let Some(p) = &plot_to {
            std::fs::write(p, plot(&r)).map_err(ReplayError::io(p))?;
            let _ = writeln!(text, "plot: {}", p.display());
        }
        crate::output::stdout::print(&text)
            .map_err(ReplayError::io(Path::new("standard output")))?;
        Ok(())
    };
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("hil sonar-replay: {e}");
            ExitCode::FAILURE
        }
    }
}

/// `hil ping360-raw DUMP.txt OUT.bin`.
pub fn cli_raw(args: RawArgs) -> ExitCode {
    let (dump_path, out) = (args.dump, args.out);
    let run = || -> Result<String, ReplayError> {
        let msgs = super::dump::read(&dump_path)?;
        let mut bytes = Vec::new();
        for (i, m) in msgs.iter().enumerate() {
            let f = m.frame()?;
            let sum = u16::from_le_bytes([f[f.len() - 2], f[f.len() - 1]]);
            if sum != m.checksum {
                return Err(ReplayError::Checksum {
                    message: i,
                    rebuilt: sum,
                    logged: m.checksum,
                });
            }
            bytes.extend_from_slice(&f);
        }
        std::fs::write(&out, &bytes).map_err(ReplayError::io(&out))?;
        Ok(format!(
            "{}: {} frames, {} bytes, every checksum as the dump logged",
            out.display(),
            msgs.len(),
            bytes.len()
        ))
    };
    match run() {
        Ok(m) => {
            println!("{m}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("hil ping360-raw: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpf::link::ping::{emit_frame, DeviceDataRepr, Message, PingSettings};

    fn frame(angle: u16, echo: usize) -> Vec<u8> {
        let mut data = vec![5u8; 1200];
        for d in data.iter_mut().skip(echo).take(40) {
            *d = 200;
        }
        let m = Message::DeviceData(DeviceDataRepr {
            settings: PingSettings {
                mode: 0,
                gain_setting: 0,
                angle,
                transmit_duration: 16,
                sample_period: 90,
                transmit_frequency: 1000,
                number_of_samples: 1200,
            },
            data: &data,
        });
        let mut buf = vec![0u8; 1300];
        let n = emit_frame(&m, 2, 0, &mut buf).unwrap();
        buf.truncate(n);
        buf
    }

    #[test]
    fn a_stream_with_noise_and_a_bad_frame_is_replayed_and_counted() {
        let mut bytes = b"noise".to_vec();
        for a in 190..=210u16 {
            let mut f = frame(a, 600);
            if a == 200 {
                f[500] ^= 1;
            }
            bytes.extend_from_slice(&f);
        }
        let ex = ExtractorConfig {
            threshold: 100.0,
            peak_min: 120.0,
            gain_per_m: 0.0,
            blanking_m: 0.15,
            cluster_gap_m: 0.1,
            ..ExtractorConfig::default()
        };
        let cfg = Ping360Config {
            step_grad: 1,
            ..Ping360Config::default()
        };
        let r = replay(&bytes, cfg, ex).unwrap();
        assert_eq!(r.counters.data, 20);
        assert_eq!(r.counters.checksum_errors, 1);
        assert_eq!(r.counters.bytes_skipped, 5);
        assert_eq!(r.pings.len(), 20);
        assert_eq!(r.pings[0].angle, 190);
        // Sample 600 of 1200, 90 × 25 ns at 1500 m/s: 1.0125 m (bin 150 of 300, read at its
        // centre: + half a bin of 6.75 mm).
        for p in &r.pings {
            let e = p.echo_m.unwrap();
            assert!((e - 1.016).abs() < 0.004, "{e}");
        }
        assert!(!r.features.is_empty());
        crate::output::svg::check::well_formed(&plot(&r));
    }
}
