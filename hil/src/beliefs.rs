//! `hil beliefs`: what the firmware believed at chosen moments of a run, from its frame log.
//!
//! The plot shows the evidence map. This prints the rest of what the planner and the guard
//! worked from:
//! - the obstacle table: charted, sensed and sonar-tracked, with each track's velocity and how
//!   long ago it was last seen;
//! - the other vehicles;
//! - the believed map cells near the vehicle;
//! - the route's aim.
//!
//! It feeds the bytes the log says went to the firmware (its `>` lines, set-up requests
//! included) to the host build of the firmware — the same `OneThreadRuntime`, with the same
//! defaults, as `--firmware host` — and stops at each requested time. The host firmware is
//! deterministic, so for a `--firmware host` run this is exactly the state the run had. For a
//! QEMU run it is the state the host build reaches on the same input (the two agreed bit for
//! bit where compared: `u_trap`, `random_clutter`, the Ping360 run). Only the main link is in
//! the frame log, so a run fed by a Ping360 or MAVLink port is not reproduced.
//!
//! That is how the causes of the bench's remaining collisions were found: a crossing target
//! seen once, 7 s before contact, believed still.

use std::fmt::{self, Write as _};
use std::path::{Path, PathBuf};

use vpf::guidance::tracks::Track;
use vpf::guidance::{OneThreadRuntime, RuntimeConfig};
use vpf::link::CostUnit;
use vpf::math::Vec2;
use vpf::route::Route;
use vpf::world::{Agent, Obstacle, Origin};
use vpf::Params;

use crate::output::frames::{Dir, FrameLog};

/// `hil beliefs`'s arguments.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A run's frame log (`frames_v0.log` in `hil run`'s output directory).
    pub frames: PathBuf,
    /// Run times to stop at, s, comma-separated and increasing.
    #[arg(long, value_delimiter = ',', required = true, value_name = "T1,T2,...")]
    pub at: Vec<f64>,
    /// Map cells within this distance of the vehicle are counted, m.
    #[arg(long, default_value_t = 10.0)]
    pub radius: f32,
    /// List every one of those cells' centres (one `cell X Y` line each), not only the nearest:
    /// to lay what was believed over the world file's true surfaces.
    #[arg(long)]
    pub cells: bool,
    /// Also each sonar track's filter: velocity, sightings, how many in a row landed where it
    /// predicted, and how far it has moved from its first sighting (why a mover was believed
    /// still).
    #[arg(long)]
    pub tracks: bool,
}

/// Why `hil beliefs` stopped.
#[derive(Debug, thiserror::Error)]
pub enum BeliefsError {
    /// The frame log could not be read or parsed.
    #[error("{0}")]
    Log(#[from] std::io::Error),
    /// A requested time is not finite, negative, or not after the previous one.
    #[error("--at times must be finite, non-negative and increasing (got {0:?})")]
    Times(Vec<f64>),
    /// The firmware refused its default configuration (a build error, not an input error).
    #[error("host firmware: {0}")]
    Firmware(String),
}

/// What the firmware believed at one moment.
#[derive(Clone, Debug)]
pub struct Belief {
    /// The run's time asked for, s.
    pub at_s: f64,
    /// The firmware's time then, ms (the last period before `at_s`).
    pub now_ms: u64,
    /// Its navigation: position, m, and heading, rad.
    pub pose: Option<(Vec2, f32)>,
    /// Its obstacle table.
    pub obstacles: Vec<Obstacle>,
    /// Each sonar obstacle's track: its filter state, and how many sightings it has had
    /// (`hits`; 1: seen once, with no velocity yet: the guard's head-on hypothesis may apply).
    pub tracks: Vec<Track>,
    /// The slow velocity each still sonar track's sightings suggest but no third has borne out
    /// yet (`Tracks::tentative`: the guard may meet it on it), by obstacle id. A track that has
    /// drifted is listed as if it stood alone, as a slow-turning craft's guard would meet it.
    pub tentative: Vec<(u16, Vec2)>,
    /// The other vehicles it knew of.
    pub agents: Vec<Agent>,
    /// Centres of the believed map cells within the asked radius of the vehicle, m.
    pub cells: Vec<Vec2>,
    /// The radius, m.
    pub radius_m: f32,
    /// The route it held.
    pub route: Option<Route>,
    /// Where the sonar's lookout last saw clear along the vehicle's heading: the kept beam's
    /// end (`vpf::sonar::lookout`), or `None` if it never looked that way.
    pub lookout_end: Option<Vec2>,
    /// The hull's radius, m (how far to the side a beam may run and still vouch for the way).
    pub hull_m: f32,
}

/// Runs `hil beliefs`: prints what was believed at each time; exit status 2 on an error.
pub fn cli(a: &Args) -> std::process::ExitCode {
    match beliefs(&a.frames, &a.at, a.radius) {
        Ok(all) => {
            let mut text = String::new();
            for b in all {
                let _ = write!(text, "{b}");
                if a.cells {
                    for c in &b.cells {
                        let _ = writeln!(text, "    cell {:.2} {:.2}", c.x, c.y);
                    }
                }
                if a.tracks {
                    for t in &b.tracks {
                        let _ = writeln!(text, "{}", TrackLine(t));
                    }
                }
            }
            crate::output::stdout::print_report("hil beliefs", &text)
        }
        Err(e) => {
            eprintln!("hil beliefs: {e}");
            std::process::ExitCode::from(2)
        }
    }
}

/// What the firmware of the run logged in `frames` believed at each of `times` (s, increasing),
/// with the map cells within `radius` m. Times after the log's end are left out.
pub fn beliefs(frames: &Path, times: &[f64], radius: f32) -> Result<Vec<Belief>, BeliefsError> {
    let increasing = times.windows(2).all(|w| w[0] < w[1]);
    if !increasing || times.iter().any(|t| !t.is_finite() || *t < 0.0) {
        return Err(BeliefsError::Times(times.to_vec()));
    }
    let log = FrameLog::replay(frames)?;
    let mut fw = OneThreadRuntime::new(
        Params::default(),
        RuntimeConfig::default(),
        CostUnit::Microseconds,
    )
    .map_err(|e| BeliefsError::Firmware(e.to_string()))?;
    let mut out = Vec::new();
    let mut next = times.iter().copied().peekable();
    for (t, dir, bytes) in log {
        while let Some(at) = next.next_if(|&at| t >= at) {
            out.push(belief(&fw, at, radius));
        }
        if dir == Dir::ToFirmware {
            fw.on_bytes(&bytes, &mut || 0, &mut |_| true);
        }
    }
    Ok(out)
}

/// What `fw` believes now (the run's time `at_s`).
fn belief(fw: &OneThreadRuntime, at_s: f64, radius_m: f32) -> Belief {
    let p = fw.periodic();
    let pose = p.nav().map(|n| (n.nav.position, n.nav.heading));
    Belief {
        at_s,
        now_ms: fw.now_ms(),
        pose,
        obstacles: p.world().obstacles().to_vec(),
        tracks: p.tracks().tracks().to_vec(),
        tentative: (p.world().obstacles().iter())
            .filter_map(|o| Some((o.id, p.tracks().tentative(o.id, || true)?)))
            .collect(),
        agents: p.world().agents().to_vec(),
        cells: pose.map_or(Vec::new(), |(h, _)| believed_cells(fw, h, radius_m)),
        radius_m,
        route: p.route().copied(),
        lookout_end: pose.and_then(|(h, heading)| {
            let map = fw.map();
            map.lookout().end(h, heading, map.cell_m())
        }),
        hull_m: p.planner().params().agent_radius_m,
    }
}

/// Centres of the believed cells within `radius` of `p`.
fn believed_cells(fw: &OneThreadRuntime, p: Vec2, radius: f32) -> Vec<Vec2> {
    let map = fw.map();
    let Some(w) = map.window() else {
        return Vec::new();
    };
    let cell = map.cell_m();
    let reach = (radius / cell).ceil() as i32;
    let (ci, cj) = ((p.x / cell).floor() as i32, (p.y / cell).floor() as i32);
    let mut cells = Vec::new();
    for j in cj - reach..=cj + reach {
        for i in ci - reach..=ci + reach {
            let c = Vec2::new((i as f32 + 0.5) * cell, (j as f32 + 0.5) * cell);
            if map.is_occupied(w, i, j) && (c - p).norm() <= radius {
                cells.push(c);
            }
        }
    }
    cells
}

impl Belief {
    /// Seconds since `seen_ms`.
    fn ago(&self, seen_ms: u64) -> f32 {
        self.now_ms.saturating_sub(seen_ms) as f32 / 1000.0
    }
}

impl fmt::Display for Belief {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "t = {:.1} s (firmware {} ms)", self.at_s, self.now_ms)?;
        match self.pose {
            Some((p, heading)) => writeln!(
                f,
                ": vehicle at {}, heading {:.0}°",
                Xy(p),
                heading.to_degrees()
            )?,
            None => writeln!(f, ": no navigation yet")?,
        }
        writeln!(f, "  obstacles: {}", self.obstacles.len())?;
        for o in &self.obstacles {
            let origin = match o.origin {
                Origin::Charted => "charted",
                Origin::Sensed => "sensed",
                Origin::Sonar => "sonar",
            };
            write!(
                f,
                "    #{:04x} {origin}: centre {}, radius {:.2} m, ",
                o.id,
                Xy(o.shape.center()),
                o.shape.bounding_radius()
            )?;
            if o.velocity == Vec2::ZERO {
                write!(f, "still")?;
                if let Some((_, v)) = self.tentative.iter().find(|(id, _)| *id == o.id) {
                    write!(f, " (tentatively {})", Xy(*v))?;
                }
            } else {
                write!(f, "moving {}", Xy(o.velocity))?;
            }
            let ago = self.ago(o.seen_ms);
            match self.tracks.iter().find(|t| t.id == o.id).map(|t| t.hits) {
                Some(1) => write!(f, ", seen once, {ago:.1} s ago")?,
                Some(n) => write!(f, ", seen {n} times, last {ago:.1} s ago")?,
                None => write!(f, ", seen {ago:.1} s ago")?,
            }
            if let Some((p, _)) = self.pose {
                write!(f, ", {:.1} m away", o.shape.signed_distance(p))?;
            }
            writeln!(f)?;
        }
        writeln!(f, "  other vehicles: {}", self.agents.len())?;
        for a in &self.agents {
            writeln!(
                f,
                "    #{:04x}: at {}, velocity {}, seen {:.1} s ago",
                a.id,
                Xy(a.position),
                Xy(a.velocity),
                self.ago(a.seen_ms)
            )?;
        }
        if let Some((p, _)) = self.pose {
            write!(
                f,
                "  map: {} cells believed within {} m",
                self.cells.len(),
                self.radius_m
            )?;
            let nearest = self.cells.iter().map(|c| (*c, (*c - p).norm()));
            match nearest.min_by(|a, b| a.1.total_cmp(&b.1)) {
                Some((c, d)) => writeln!(f, ", nearest at {} ({d:.1} m)", Xy(c))?,
                None => writeln!(f)?,
            }
        }
        if let Some((p, heading)) = self.pose {
            match self.lookout_end {
                Some(q) => writeln!(
                    f,
                    "  lookout ahead: the kept beam ended at {}, clear {:.1} m for the hull",
                    Xy(q),
                    vpf::sonar::lookout::clear_ahead(q, p, heading, self.hull_m)
                )?,
                None => writeln!(f, "  lookout ahead: never looked this way")?,
            }
        }
        match &self.route {
            Some(r) => writeln!(
                f,
                "  route: {:?} towards {}, {:.1} s old",
                r.status,
                Xy(r.aim),
                self.ago(r.time_ms)
            ),
            None => writeln!(f, "  route: none"),
        }
    }
}

/// One sonar track's filter state, as `hil beliefs --tracks` lists it.
struct TrackLine<'a>(&'a Track);

impl fmt::Display for TrackLine<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let t = self.0;
        write!(
            f,
            "    track #{:04x}: centre {}, filter velocity {} ({:.2} m/s), sightings {}, {} in a row \
             where predicted, {:.1} m from its first at {}",
            t.id,
            Xy(t.center),
            Xy(t.velocity),
            t.velocity.norm(),
            t.hits,
            t.steady,
            (t.center - t.first).norm(),
            Xy(t.first)
        )?;
        if !t.rated {
            write!(f, ", unrated")?;
        }
        match t.largest_dm {
            0 => write!(f, ", never sized as a mover")?,
            dm => write!(f, ", largest sighting {:.1} m", f32::from(dm) * 0.1)?,
        }
        if t.borne {
            write!(f, ", once a mover")?;
        }
        Ok(())
    }
}

/// A position or velocity as `(x, y)` with two decimals.
struct Xy(Vec2);

impl fmt::Display for Xy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "({:.2}, {:.2})", self.0.x, self.0.y)
    }
}
