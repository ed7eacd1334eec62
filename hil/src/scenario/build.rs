//! The file's tables built into a [`Scenario`]: required keys, every range and the cross-checks
//! (vehicles against obstacles, the Ping360 against what it can do), each refusal at its key.

use toml::Spanned;
use vpf::field::Shape;

use super::file::{
    CurrentFile, FaultsFile, NavigationFile, Opt, ScenarioFile, SonarFile, VehicleFile,
};
use super::values::{int_within, Num, Table};
use super::{
    obstacle, planner, vehicle, At, Current, Faults, ModelKind, Navigation, RunMode, Scenario,
    ScenarioError, Sonar, SonarInterface, SonarMode, Vehicle, MAX_DURATION_S, MAX_NAME_CHARS,
    MAX_OBSTACLES, MAX_VEHICLES, OBSTACLE_FACTOR,
};

pub(super) fn build(root: &At<'_>, f: &ScenarioFile) -> Result<Scenario, ScenarioError> {
    let name = root.req("name", &f.name)?;
    check_name(root, "name", name)?;
    let dt = root.req("dt_s", &f.dt_s)?;
    let dt_s = root.within("dt_s", dt, 0.02, 1.0, "s")?;
    let duration = root.req("duration_s", &f.duration_s)?;
    let duration_s = root.within(
        "duration_s",
        duration,
        dt_s,
        MAX_DURATION_S,
        "s (at least dt_s)",
    )?;
    let seed = root.req("seed", &f.seed)?;
    let seed_v = u64::try_from(seed.get_ref().0).map_err(|_| {
        root.fail(
            "seed",
            &seed.span(),
            format!("must be >= 0, got {}", seed.get_ref().0),
        )
    })?;
    let mode = match &f.mode {
        Some(m) => root.choose(
            "mode",
            m,
            &[
                ("lockstep", RunMode::Lockstep),
                ("realtime", RunMode::Realtime),
            ],
            "mode",
        )?,
        None => RunMode::Lockstep,
    };

    let params = planner::planner(root, &f.planner, dt_s, &dt.span())?;
    // The head its vehicles carry, unless `range_m` says otherwise: a flat-fish's when every
    // vehicle is one (a name not known here is refused with its vehicle below).
    let vehicle_tables = f.vehicle.as_ref().map_or(&[][..], |v| &v.get_ref().0[..]);
    let flatfish = |t: &Spanned<Table<VehicleFile>>| {
        let name = t.get_ref().model.as_ref();
        let known = vehicle::MODELS
            .iter()
            .find(|(n, _)| name.is_some_and(|m| m.get_ref() == n));
        known.is_some_and(|&(_, m)| m == ModelKind::FlatFish)
    };
    let range_m = if !vehicle_tables.is_empty() && vehicle_tables.iter().all(flatfish) {
        Sonar::FLATFISH_RANGE_M
    } else {
        Sonar::default().range_m
    };
    let sonar = sonar(root, &f.sonar, range_m)?;
    let navigation = navigation(root, &f.navigation, dt_s)?;
    let current = current(root, &f.current)?;
    let faults = faults(root, &f.faults)?;

    let tables = &f.obstacle.0;
    if let Some(t) = tables.get(MAX_OBSTACLES) {
        return Err(root
            .child(&format!("obstacle[{MAX_OBSTACLES}]"), t.span())
            .refuse(format!(
            "too many obstacles: {} of at most {MAX_OBSTACLES} ({OBSTACLE_FACTOR} × the firmware's \
             table of {})",
            tables.len(),
            vpf::world::MAX_OBSTACLES
        )));
    }
    let mut obstacles = Vec::new();
    let mut shapes: Vec<Shape> = Vec::new();
    for (i, t) in tables.iter().enumerate() {
        let at = root.child(&format!("obstacle[{i}]"), t.span());
        let (o, s) = obstacle::obstacle(&at, t.get_ref())?;
        obstacles.push(o);
        shapes.push(s);
    }

    let tables = vehicle_tables;
    if tables.is_empty() {
        let span = f.vehicle.as_ref().map_or(root.span.clone(), |v| v.span());
        return Err(root.fail(
            "vehicle",
            &span,
            "no vehicle: a scenario needs at least one [[vehicle]]",
        ));
    }
    if let Some(t) = tables.get(MAX_VEHICLES) {
        return Err(root
            .child(&format!("vehicle[{MAX_VEHICLES}]"), t.span())
            .refuse(format!(
                "too many vehicles: at most {MAX_VEHICLES} (the firmware tracks {} others)",
                MAX_VEHICLES - 1
            )));
    }
    let mut vehicles: Vec<Vehicle> = Vec::new();
    for (i, t) in tables.iter().enumerate() {
        let at = root.child(&format!("vehicle[{i}]"), t.span());
        let world = vehicle::World {
            sonar: &sonar,
            params: &params,
            obstacles: &obstacles,
            shapes: &shapes,
            earlier: &vehicles,
        };
        let v = vehicle::vehicle(&at, t.get_ref(), &world)?;
        vehicles.push(v);
    }

    Ok(Scenario {
        name: name.get_ref().clone(),
        duration_s,
        dt_s,
        seed: seed_v,
        mode,
        params,
        vehicles,
        obstacles,
        sonar,
        navigation,
        current,
        faults,
    })
}

/// A name that will become a directory or file name: not blank, at most [`MAX_NAME_CHARS`].
pub(super) fn check_name(
    at: &At<'_>,
    key: &str,
    name: &Spanned<String>,
) -> Result<(), ScenarioError> {
    let fail = |m: String| at.fail(key, &name.span(), m);
    if name.get_ref().trim().is_empty() {
        return Err(fail("must not be empty".into()));
    }
    let n = name.get_ref().chars().count();
    if n > MAX_NAME_CHARS {
        return Err(fail(format!(
            "{n} characters; at most {MAX_NAME_CHARS} (names become directory and file names)"
        )));
    }
    Ok(())
}

/// `key`'s number within `lo ..= hi` (unit `unit`), or `default` when absent.
fn or(
    at: &At<'_>,
    key: &str,
    v: &Option<Spanned<Num>>,
    (lo, hi, unit): (f64, f64, &str),
    default: f64,
) -> Result<f64, ScenarioError> {
    match v {
        Some(v) => at.within(key, v, lo, hi, unit),
        None => Ok(default),
    }
}

// --- [sonar], [navigation], [current], [faults] ----------------------------------------------

fn sonar(root: &At<'_>, t: &Opt<Table<SonarFile>>, range_m: f64) -> Result<Sonar, ScenarioError> {
    let d = Sonar {
        range_m,
        ..Sonar::default()
    };
    let Some(t) = t else {
        return Ok(d);
    };
    let (at, f) = (root.child("sonar", t.span()), t.get_ref());
    let interface = match &f.interface {
        Some(i) => at.choose(
            "interface",
            i,
            &[
                ("link", SonarInterface::Link),
                ("ping360", SonarInterface::Ping360),
            ],
            "sonar interface",
        )?,
        None => SonarInterface::Link,
    };
    let mode = match &f.mode {
        Some(m) => at.choose(
            "mode",
            m,
            &[
                ("scanlines", SonarMode::Scanlines),
                ("contacts", SonarMode::Contacts),
            ],
            "sonar mode",
        )?,
        None => d.mode,
    };
    let range = (
        f64::from(vpf::sonar::MIN_RANGE_M),
        f64::from(vpf::sonar::MAX_RANGE_M),
        "m",
    );
    let lo = f64::from(vpf::sonar::MIN_STEP_RAD).to_degrees();
    let hi = f64::from(vpf::sonar::MAX_STEP_RAD).to_degrees();
    // Rounded inward so the printed range is safe to use.
    let step = (
        (lo * 100.0).ceil() / 100.0,
        (hi * 100.0).floor() / 100.0,
        "degrees",
    );
    let unit = (0.0, 1.0, "");
    let s = Sonar {
        mode,
        range_m: or(&at, "range_m", &f.range_m, range, d.range_m)?,
        bins: match &f.bins {
            Some(b) => int_within(&at, "bins", b, 1, vpf::sonar::MAX_BINS as i64)? as u16,
            None => d.bins,
        },
        step: match &f.step_deg {
            Some(_) => or(&at, "step_deg", &f.step_deg, step, 0.0)?.to_radians(),
            None => d.step,
        },
        noise: or(&at, "noise", &f.noise, unit, d.noise)?,
        speckle: or(&at, "speckle", &f.speckle, unit, d.speckle)?,
        beam_rays: match &f.beam_rays {
            Some(b) => int_within(&at, "beam_rays", b, 1, 32)? as usize,
            None => d.beam_rays,
        },
        false_echoes: or(&at, "false_echoes", &f.false_echoes, unit, d.false_echoes)?,
        vehicle_contacts: f
            .vehicle_contacts
            .as_ref()
            .map_or(d.vehicle_contacts, |b| *b.get_ref()),
        interface,
    };
    if interface == SonarInterface::Ping360 {
        crate::ping360::sim::firmware_config(&s).map_err(|(key, msg)| {
            let span = match key {
                "step_deg" => f.step_deg.as_ref().map(|v| v.span()),
                "bins" => f.bins.as_ref().map(|v| v.span()),
                "range_m" => f.range_m.as_ref().map(|v| v.span()),
                _ => None,
            };
            at.fail(key, &span.unwrap_or(at.span.clone()), msg)
        })?;
    }
    Ok(s)
}

fn navigation(
    root: &At<'_>,
    t: &Opt<Table<NavigationFile>>,
    dt_s: f64,
) -> Result<Navigation, ScenarioError> {
    let rate_hz = 1.0 / dt_s;
    let Some(t) = t else {
        return Ok(Navigation {
            rate_hz,
            ..Navigation::default()
        });
    };
    let (at, f) = (root.child("navigation", t.span()), t.get_ref());
    Ok(Navigation {
        position_sigma_m: or(
            &at,
            "position_sigma_m",
            &f.position_sigma_m,
            (0.0, 100.0, "m"),
            0.0,
        )?,
        heading_sigma: or(
            &at,
            "heading_sigma_deg",
            &f.heading_sigma_deg,
            (0.0, 180.0, "degrees"),
            0.0,
        )?
        .to_radians(),
        rate_hz: or(&at, "rate_hz", &f.rate_hz, (0.1, 1000.0, "Hz"), rate_hz)?,
    })
}

fn current(root: &At<'_>, t: &Opt<Table<CurrentFile>>) -> Result<Current, ScenarioError> {
    let Some(t) = t else {
        return Ok(Current::default());
    };
    let at = root.child("current", t.span());
    Ok(Current {
        velocity: at.velocity("velocity", &t.get_ref().velocity, 5.0)?,
    })
}

fn faults(root: &At<'_>, t: &Opt<Table<FaultsFile>>) -> Result<Faults, ScenarioError> {
    let Some(t) = t else {
        return Ok(Faults::default());
    };
    let (at, f) = (root.child("faults", t.span()), t.get_ref());
    let (ber, rate) = ((0.0, 0.01, ""), (0.0, 1.0, ""));
    Ok(Faults {
        bit_error_rate: or(&at, "bit_error_rate", &f.bit_error_rate, ber, 0.0)?,
        drop_rate: or(&at, "drop_rate", &f.drop_rate, rate, 0.0)?,
        nav_delay_ms: or(
            &at,
            "nav_delay_ms",
            &f.nav_delay_ms,
            (0.0, 10_000.0, "ms"),
            0.0,
        )?,
        nav_freeze: at.window("nav_freeze", &f.nav_freeze)?,
        nav_loss: at.window("nav_loss", &f.nav_loss)?,
        sonar_dropout: at.window("sonar_dropout", &f.sonar_dropout)?,
        ping360_bit_error_rate: or(
            &at,
            "ping360_bit_error_rate",
            &f.ping360_bit_error_rate,
            ber,
            0.0,
        )?,
        ping360_drop_rate: or(&at, "ping360_drop_rate", &f.ping360_drop_rate, rate, 0.0)?,
    })
}
