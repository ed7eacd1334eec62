//! `hil echoes`: what the sonar heard towards another vehicle (or a point) during a run.
//!
//! `hil beliefs` shows what the firmware made of its sonar; this shows what it was given. It
//! reads the scanlines a run's frame log says went to the firmware, keeps the pings whose beam
//! pointed within `--within` degrees of the target — another vehicle where its
//! `trajectory_*.csv` says it truly was at the ping, or a fixed point — and runs the
//! firmware's own detection (`vpf::sonar::detect`, default configuration) on each. Every echo
//! run is printed with its range, peak and mean intensity, and what one beam of it would be
//! to the extractor: a glimpse (mean ≥ `GLIMPSE_INTENSITY`), a faint sighting (≥
//! `FAINT_INTENSITY`, or `FAINT_AHEAD_INTENSITY` within `FAINT_AHEAD_RAD` of the bow), or
//! weak. The ping's pose is the vehicle's true one from its own
//! trajectory (the simulated sonar rendered it so).
//!
//! That is how the bench's head-on contacts were read (VPF 1111, 1154, 6155; multipoint 59,
//! 6067; navfn 1071, 1098; re-flown at 8fab619): each VideoRay heard the other on one beam a
//! sweep, at about 16, 10 and 4 m, with means of 100–200, most of them under the faint floor
//! then (150), so neither believed the other until it was on two beams, 3–4 m off. Hence the
//! lower floor ahead (`vpf::sonar::FAINT_AHEAD_INTENSITY`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use vpf::link::{Direction, Message};
use vpf::sonar::{
    detect, ExtractorConfig, FAINT_AHEAD_INTENSITY, FAINT_AHEAD_RAD, FAINT_INTENSITY,
    GLIMPSE_INTENSITY,
};

use crate::output::frames::{Dir, FrameLog};

/// `hil echoes`'s arguments.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A run's output directory (`hil run --out`): its `frames_V.log` and `trajectory_*.csv`.
    pub run: PathBuf,
    /// The vehicle whose sonar is read.
    #[arg(long, default_value = "v0")]
    pub vehicle: String,
    /// The other vehicle to look for (its `trajectory_V.csv` gives where it was).
    #[arg(long, value_name = "V", conflicts_with = "point")]
    pub towards: Option<String>,
    /// Or a fixed point to look for, world frame, m.
    #[arg(long, value_name = "X,Y", value_delimiter = ',')]
    pub point: Option<Vec<f64>>,
    /// Run times to read between, s.
    #[arg(long, value_name = "T0,T1", value_delimiter = ',', required = true)]
    pub between: Vec<f64>,
    /// Pings whose beam points within this many degrees of the target are shown.
    #[arg(long, default_value_t = 6.0)]
    pub within: f64,
    /// Also the pings towards the target that detected nothing.
    #[arg(long)]
    pub all: bool,
}

/// Why `hil echoes` stopped.
#[derive(Debug, thiserror::Error)]
pub enum EchoesError {
    /// A file could not be read or parsed.
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// A trajectory file is not what `hil run` writes.
    #[error("{path}: {what}")]
    Trajectory {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
    /// Neither `--towards` nor `--point`, or times out of order.
    #[error("{0}")]
    Usage(String),
}

/// A pose sampled from a trajectory: time, s; x, y, m; heading, rad.
type Sample = (f64, f64, f64, f64);

/// One ping towards the target.
#[derive(Clone, Debug, PartialEq)]
pub struct Ping {
    /// Its time, s.
    pub t_s: f64,
    /// Its bearing from the bow, degrees.
    pub bearing_deg: f64,
    /// How far the beam pointed from the target, degrees (positive: to port of it).
    pub off_deg: f64,
    /// The target's true distance, m.
    pub distance_m: f64,
    /// Its echo runs: range, m; peak and mean intensity (gain-compensated).
    pub echoes: Vec<(f32, f32, f32)>,
}

/// The largest trajectory file read, bytes (a 2-hour run at 10 Hz is about 15 MB).
const MAX_TRAJECTORY_BYTES: u64 = 64 << 20;

/// Reads `t_s, x_m, y_m, heading_rad` from a `hil run` trajectory file.
fn trajectory(path: &Path) -> Result<Vec<Sample>, EchoesError> {
    let bad = |what: String| EchoesError::Trajectory {
        path: path.to_path_buf(),
        what,
    };
    if std::fs::metadata(path)?.len() > MAX_TRAJECTORY_BYTES {
        return Err(bad(format!("longer than {MAX_TRAJECTORY_BYTES} bytes")));
    }
    let text = std::fs::read_to_string(path)?;
    let mut lines = text.lines();
    let header = lines.next().unwrap_or_default();
    if !header.starts_with("t_s,x_m,y_m,heading_rad") {
        return Err(bad(format!("unexpected header {header:?}")));
    }
    lines
        .enumerate()
        .map(|(i, l)| {
            let f: Vec<f64> = (l.split(',').take(4))
                .map(|w| w.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|e| bad(format!("line {}: {e}", i + 2)))?;
            match f[..] {
                [t, x, y, h] if f.iter().all(|v| v.is_finite()) => Ok((t, x, y, h)),
                _ => Err(bad(format!("line {}: expected four finite numbers", i + 2))),
            }
        })
        .collect()
}

/// The sample nearest `t` (samples in time order).
fn at(samples: &[Sample], t: f64) -> Option<Sample> {
    let i = samples.partition_point(|s| s.0 < t);
    let after = samples.get(i);
    let before = i.checked_sub(1).and_then(|k| samples.get(k));
    match (before, after) {
        (Some(b), Some(a)) => Some(if t - b.0 <= a.0 - t { *b } else { *a }),
        (b, a) => b.or(a).copied(),
    }
}

/// Angle wrapped to (−π, π].
fn wrap(a: f64) -> f64 {
    let w = a.rem_euclid(std::f64::consts::TAU);
    if w > std::f64::consts::PI {
        w - std::f64::consts::TAU
    } else {
        w
    }
}

/// The pings of `a.vehicle` towards the target, in time order.
pub fn echoes(a: &Args) -> Result<Vec<Ping>, EchoesError> {
    let [t0, t1] = a.between[..] else {
        return Err(EchoesError::Usage("--between takes T0,T1".into()));
    };
    if !(t0.is_finite() && t1.is_finite() && t0 <= t1) {
        return Err(EchoesError::Usage(format!("--between {t0},{t1}: T0 ≤ T1")));
    }
    let point = match (&a.towards, &a.point) {
        (Some(_), _) => None,
        (None, Some(p)) => match p[..] {
            [x, y] if x.is_finite() && y.is_finite() => Some((x, y)),
            _ => return Err(EchoesError::Usage("--point takes X,Y".into())),
        },
        (None, None) => return Err(EchoesError::Usage("give --towards V or --point X,Y".into())),
    };
    let own = trajectory(&a.run.join(format!("trajectory_{}.csv", a.vehicle)))?;
    let other = match &a.towards {
        Some(v) => trajectory(&a.run.join(format!("trajectory_{v}.csv")))?,
        None => Vec::new(),
    };
    let target = |t: f64| match point {
        Some(p) => Some(p),
        None => at(&other, t).map(|s| (s.1, s.2)),
    };
    let within = a.within.to_radians();
    let cfg = ExtractorConfig::default();
    let log = FrameLog::replay(&a.run.join(format!("frames_{}.log", a.vehicle)))?;
    let mut out = Vec::new();
    for (t, dir, mut bytes) in log {
        if dir != Dir::ToFirmware || t < t0 - 1.0 || t > t1 + 1.0 {
            continue;
        }
        let Ok((_, Message::Scanline(s))) =
            Message::decode_frame(&mut bytes, Direction::ToFirmware)
        else {
            continue;
        };
        let ts = s.time_ms as f64 * 1e-3;
        let (Some((_, x, y, heading)), Some((tx, ty))) = (at(&own, ts), target(ts)) else {
            continue;
        };
        if !(t0..=t1).contains(&ts) {
            continue;
        }
        let towards = wrap((ty - y).atan2(tx - x) - heading);
        let off = wrap(f64::from(s.bearing_rad) - towards);
        if off.abs() > within {
            continue;
        }
        let echoes: Vec<_> = (detect::detect(&s, &cfg).iter())
            .map(|e| (e.range_m, e.peak, e.mean))
            .collect();
        if echoes.is_empty() && !a.all {
            continue;
        }
        out.push(Ping {
            t_s: ts,
            bearing_deg: f64::from(s.bearing_rad).to_degrees(),
            off_deg: off.to_degrees(),
            distance_m: (tx - x).hypot(ty - y),
            echoes,
        });
    }
    Ok(out)
}

/// What one beam of an echo of mean `mean`, `bearing_deg` from the bow, is to the extractor.
fn verdict(mean: f32, bearing_deg: f64) -> &'static str {
    let ahead = bearing_deg.abs().to_radians() <= f64::from(FAINT_AHEAD_RAD);
    if mean >= GLIMPSE_INTENSITY {
        "glimpse"
    } else if mean >= FAINT_INTENSITY || (ahead && mean >= FAINT_AHEAD_INTENSITY) {
        "faint"
    } else {
        "weak"
    }
}

/// Runs `hil echoes`: one line a ping; exit status 2 on an error.
pub fn cli(a: &Args) -> std::process::ExitCode {
    match echoes(a) {
        Ok(pings) => {
            let mut text = String::new();
            for p in pings {
                let _ = write!(
                    text,
                    "t = {:.2} s  beam {:+.1}° ({:+.1}° off the target, {:.2} m away):",
                    p.t_s, p.bearing_deg, p.off_deg, p.distance_m
                );
                if p.echoes.is_empty() {
                    text.push_str(" nothing");
                }
                for (r, peak, mean) in p.echoes {
                    let _ = write!(
                        text,
                        "  {r:.2} m peak {peak:.0} mean {mean:.0} ({})",
                        verdict(mean, p.bearing_deg)
                    );
                }
                text.push('\n');
            }
            crate::output::stdout::print_report("hil echoes", &text)
        }
        Err(e) => {
            eprintln!("hil echoes: {e}");
            std::process::ExitCode::from(2)
        }
    }
}
