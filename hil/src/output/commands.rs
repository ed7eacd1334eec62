//! `commands.svg`: the firmware's set-points over time for every vehicle, as in the formation
//! paper's Fig. 4 and 6: commanded speed v_set (top) and commanded heading ψ_set in degrees
//! (bottom) on a shared time axis. The vehicle's own surge speed u and heading ψ are drawn
//! thin and dashed in the same colour, to show how well the autopilots track.
//!
//! Heading is wrapped to (−180°, 180°]; the line is broken where it wraps instead of drawing a
//! vertical stroke across the panel.

use super::svg::{self, Frame, PathData, Svg};
use super::RunOutput;
use crate::types::Sample;

const LEFT: f64 = 80.0;
const TOP: f64 = 62.0;
const PANEL_W: f64 = 760.0;
const PANEL_H: f64 = 230.0;
const GAP: f64 = 26.0;
const BOTTOM: f64 = 56.0;
const LEGEND_W: f64 = 190.0;

/// The plot as SVG text.
pub fn render(run: &RunOutput) -> String {
    let all = || run.vehicles.iter().flat_map(|v| v.samples.iter());
    let finite_t = all().map(|s| s.t).filter(|t| t.is_finite());
    let (t0, t1) = finite_t.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
        (a.min(t), b.max(t))
    });
    let (t0, t1) = if t0 < t1 {
        (t0, t1)
    } else if t0.is_finite() {
        (t0 - 1.0, t0 + 1.0)
    } else {
        (0.0, 1.0)
    };
    let v_max = all()
        .flat_map(|s| [s.speed_cmd, s.state.u])
        .filter(|x| x.is_finite() && x.abs() < 1e3)
        .fold(f64::from(run.params.v_max), f64::max);
    let v_min = all()
        .flat_map(|s| [s.speed_cmd, s.state.u])
        .filter(|x| x.is_finite() && x.abs() < 1e3)
        .fold(0.0f64, f64::min);
    let v_hi = if v_max.is_finite() && v_max > v_min {
        v_max * 1.08
    } else {
        1.0
    };
    let v_lo = if v_min < 0.0 { v_min * 1.08 } else { 0.0 };

    let speed = Frame {
        left: LEFT,
        top: TOP,
        width: PANEL_W,
        height: PANEL_H,
        x0: t0,
        x1: t1,
        y0: v_lo,
        y1: v_hi,
    };
    let heading = Frame {
        top: TOP + PANEL_H + GAP,
        y0: -180.0,
        y1: 180.0,
        ..speed
    };
    let width = LEFT + PANEL_W + LEGEND_W;
    let height = heading.top + PANEL_H + BOTTOM;
    let mut s = Svg::new(width, height);
    let title = if run.scenario_name.is_empty() {
        "(unnamed scenario)"
    } else {
        run.scenario_name.as_str()
    };
    s.text(
        LEFT,
        24.0,
        &format!("{title} — commanded speed and heading"),
        "font-size=\"17\" font-weight=\"bold\"",
    );
    s.text(
        LEFT,
        43.0,
        &format!(
            "firmware: {}; solid: set-points from the firmware, dashed: vehicle (u, ψ)",
            run.firmware
        ),
        "font-size=\"12\" fill=\"#555\"",
    );
    let tstep = svg::nice_step(t1 - t0, 10.0);
    speed.axes(
        &mut s,
        tstep,
        svg::nice_step(v_hi - v_lo, 5.0),
        None,
        "speed [m/s]",
    );
    heading.axes(&mut s, tstep, 90.0, Some("time [s]"), "heading [deg]");

    for (i, v) in run.vehicles.iter().enumerate() {
        let c = svg::colour(i);
        let measured = format!(
            "fill=\"none\" stroke=\"{c}\" stroke-width=\"1\" stroke-dasharray=\"4 3\" opacity=\"0.7\""
        );
        let command = format!("fill=\"none\" stroke=\"{c}\" stroke-width=\"1.8\"");
        s.path(&series(&speed, &v.samples, |x| x.state.u, false), &measured);
        s.path(
            &series(&speed, &v.samples, |x| x.speed_cmd, false),
            &command,
        );
        s.path(
            &series(&heading, &v.samples, |x| x.state.heading.to_degrees(), true),
            &measured,
        );
        s.path(
            &series(&heading, &v.samples, |x| x.psi_cmd.to_degrees(), true),
            &command,
        );
    }
    if run.vehicles.iter().all(|v| v.samples.is_empty()) {
        s.text(
            LEFT + PANEL_W / 2.0,
            TOP + PANEL_H / 2.0,
            "no samples recorded",
            "text-anchor=\"middle\" font-size=\"16\" fill=\"#888\"",
        );
    }

    // Legend.
    let x = LEFT + PANEL_W + 20.0;
    let mut y = svg::vehicle_legend(&mut s, x, TOP + 8.0, &run.vehicles, 2.5);
    s.line(x, y, x + 24.0, y, "stroke=\"#555\" stroke-width=\"1.8\"");
    s.text(x + 32.0, y + 4.0, "set-point", "fill=\"#222\"");
    y += 18.0;
    s.line(
        x,
        y,
        x + 24.0,
        y,
        "stroke=\"#555\" stroke-width=\"1\" stroke-dasharray=\"4 3\"",
    );
    s.text(x + 32.0, y + 4.0, "vehicle", "fill=\"#222\"");
    s.finish()
}

/// Path data of one quantity over time; `wrapped` angles in degrees are wrapped to
/// (−180, 180] and the pen is lifted across a wrap.
fn series(f: &Frame, samples: &[Sample], get: impl Fn(&Sample) -> f64, wrapped: bool) -> PathData {
    let mut d = PathData::new();
    let mut last: Option<f64> = None;
    for smp in samples {
        let mut y = get(smp);
        if wrapped && y.is_finite() {
            y = wrap_deg(y);
            if last.is_some_and(|l| (y - l).abs() > 180.0) {
                d.lift();
            }
        }
        d.to(f.px(smp.t), f.py(y));
        last = y.is_finite().then_some(y);
    }
    d
}

/// An angle in degrees wrapped to (−180, 180].
fn wrap_deg(a: f64) -> f64 {
    let w = a.rem_euclid(360.0);
    if w > 180.0 {
        w - 360.0
    } else {
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::svg::check::well_formed;
    use crate::output::test_support;

    #[test]
    fn wrap() {
        assert_eq!(wrap_deg(190.0), -170.0);
        assert_eq!(wrap_deg(-180.0), 180.0);
        assert_eq!(wrap_deg(720.0 + 45.0), 45.0);
    }

    #[test]
    fn commands_plot_is_well_formed() {
        let run = test_support::run();
        let svg = render(&run);
        well_formed(&svg);
        // Two vehicles × (speed, heading) × (set-point, vehicle).
        assert_eq!(svg.matches("<path d=").count(), 8);
        assert!(svg.contains("heading [deg]") && svg.contains("time [s]"));
    }

    #[test]
    fn commands_plot_survives_empty_and_nan_input() {
        let mut run = test_support::run();
        run.vehicles[0].samples[3].t = f64::NAN;
        run.vehicles[0].samples[4].psi_cmd = f64::INFINITY;
        run.vehicles[1].samples[2].speed_cmd = f64::NAN;
        well_formed(&render(&run));
        run.vehicles.iter_mut().for_each(|v| v.samples.truncate(1));
        well_formed(&render(&run));
        run.vehicles.clear();
        let svg = render(&run);
        well_formed(&svg);
        assert!(svg.contains("no samples recorded"));
    }
}
