//! `plot.svg`: the top view of a run, with equal scaling on both axes.
//!
//! Drawn from the bottom up: contours of the potential field E of the first vehicle (the
//! firmware's own PDFs: its goal-point attractor plus the stator of every obstacle at its t = 0
//! position; the rotor term is left out because it is defined relative to the vehicle's
//! position and changes every step), obstacles at t = 0 (filled) and, for moving ones, a dashed
//! outline at the end of the run with an arrow, the arrival-radius circles and goals, each
//! vehicle's trajectory in its own colour with start (dot) and end (heading triangle) markers,
//! ghost goal-points (hollow diamonds), and rings where a collision episode began.
//!
//! The contours of E are `contours.rs`'s.

use std::fmt::Write as _;

mod contours;

use super::svg::{self, finite, Frame, PathData, Svg};
use super::RunOutput;
use crate::types::{SimObstacle, SimShape, VehicleRecord, P2};
use contours::draw_contours;
pub use contours::{field_obstacles, marching_squares, potential};

/// Largest plot box, px.
const MAX_W: f64 = 780.0;
const MAX_H: f64 = 620.0;
/// Smallest plot box side, px (a long corridor still gets some height).
const MIN_SIDE: f64 = 260.0;
const LEFT: f64 = 80.0;
const TOP: f64 = 62.0;
const BOTTOM: f64 = 56.0;
const LEGEND_W: f64 = 250.0;

/// The plot as SVG text.
pub fn render(run: &RunOutput) -> String {
    let t_end = run
        .vehicles
        .iter()
        .flat_map(|v| v.samples.iter().map(|s| s.t))
        .filter(|t| t.is_finite())
        .fold(0.0f64, f64::max);
    let frame = layout(run, t_end);
    let width = frame.left + frame.width + LEGEND_W;
    let height = frame.top + frame.height + BOTTOM;
    let mut s = Svg::new(width, height);
    defs(&mut s, &frame);

    // Title.
    let title = if run.scenario_name.is_empty() {
        "(unnamed scenario)"
    } else {
        run.scenario_name.as_str()
    };
    s.text(
        frame.left,
        24.0,
        &format!("{title} — top view"),
        "font-size=\"17\" font-weight=\"bold\"",
    );
    let mut sub = format!("firmware: {}", run.firmware);
    if let Some(v) = run.vehicles.first() {
        let _ = write!(
            sub,
            "; contours: log-compressed potential E of {} (goal + obstacles at t = 0)",
            if v.name.is_empty() {
                "(unnamed)"
            } else {
                &v.name
            }
        );
    }
    s.text(frame.left, 43.0, &sub, "font-size=\"12\" fill=\"#555\"");

    let step = svg::nice_step((frame.x1 - frame.x0).max(frame.y1 - frame.y0), 8.0);
    frame.axes(&mut s, step, step, Some("x [m]"), "y [m]");

    if let Some(v) = run.vehicles.first() {
        draw_contours(&mut s, &frame, run, v.goal);
    }
    let believed = run.vehicles.iter().any(|v| !v.belief.ever.is_empty());
    for v in &run.vehicles {
        draw_belief(&mut s, &frame, &v.belief);
    }
    for o in &run.obstacles {
        draw_obstacle(&mut s, &frame, o, t_end);
    }
    let r_arr = run.arrival_radius_m;
    for (i, v) in run.vehicles.iter().enumerate() {
        if v.waypoints.is_empty() {
            draw_goal(&mut s, &frame, v.goal, r_arr, svg::colour(i));
        } else {
            draw_waypoints(&mut s, &frame, v, svg::colour(i));
        }
    }
    let mut any_collision = false;
    for (i, v) in run.vehicles.iter().enumerate() {
        any_collision |= draw_vehicle(&mut s, &frame, v, svg::colour(i));
    }
    if run.vehicles.iter().all(|v| v.samples.is_empty()) {
        s.text(
            frame.left + frame.width / 2.0,
            frame.top + 40.0,
            "no samples recorded",
            "text-anchor=\"middle\" font-size=\"16\" fill=\"#888\"",
        );
    }
    legend(&mut s, &frame, run, any_collision, believed);
    s.finish()
}

/// Fill of a cell ever believed occupied, and of one still believed at the end.
const BELIEF_EVER: &str = "fill=\"#f0a030\" fill-opacity=\"0.25\"";
const BELIEF_NOW: &str = "fill=\"#e07000\" fill-opacity=\"0.75\"";

/// The firmware's evidence map under the truth: every cell ever believed faint, the cells
/// believed at the end strong. One rectangle per horizontal run of cells keeps the file small.
fn draw_belief(s: &mut Svg, f: &Frame, b: &super::belief::Belief) {
    if b.cell_m <= 0.0 {
        return;
    }
    for (cells, attrs) in [(&b.ever, BELIEF_EVER), (&b.cells, BELIEF_NOW)] {
        let mut rows: std::collections::BTreeMap<i32, Vec<i32>> = Default::default();
        for &(i, j) in cells {
            rows.entry(j).or_default().push(i);
        }
        for (j, mut is) in rows {
            is.sort_unstable();
            let mut k = 0;
            while k < is.len() {
                let start = is[k];
                let mut end = start;
                while k + 1 < is.len() && is[k + 1] == end + 1 {
                    k += 1;
                    end = is[k];
                }
                k += 1;
                let (x0, x1) = (f64::from(start) * b.cell_m, f64::from(end + 1) * b.cell_m);
                let (y0, y1) = (f64::from(j) * b.cell_m, f64::from(j + 1) * b.cell_m);
                // Only what lies inside the plot's frame.
                let (x0, x1) = (x0.max(f.x0), x1.min(f.x1));
                if x0 >= x1 || y0 < f.y0 || y1 > f.y1 {
                    continue;
                }
                let (px0, px1, py1, py0) = (f.px(x0), f.px(x1), f.py(y0), f.py(y1));
                s.rect(px0, py0, px1 - px0, py1 - py0, attrs);
            }
        }
    }
}

/// A data rectangle that holds everything, with equal scaling.
fn layout(run: &RunOutput, t_end: f64) -> Frame {
    let mut b = Bounds::default();
    for o in &run.obstacles {
        for shift in [P2::default(), o.velocity.scale(t_end)] {
            match outline(&o.shape, shift) {
                Outline::Circle(c, r) => b.circle(c, r),
                Outline::Poly(pts) => pts.iter().for_each(|&p| b.add(p)),
            }
        }
    }
    let r_arr = if run.arrival_radius_m.is_finite() {
        run.arrival_radius_m.max(0.0)
    } else {
        0.0
    };
    for v in &run.vehicles {
        b.circle(v.goal, r_arr);
        v.waypoints
            .iter()
            .for_each(|w| b.circle(w.position, w.radius_m));
        v.samples.iter().for_each(|s| b.add(s.state.position));
        v.ghosts.iter().for_each(|&g| b.add(g));
    }
    let (mut x0, mut x1, mut y0, mut y1) = b.get().unwrap_or((-10.0, 10.0, -10.0, 10.0));
    // Margin: 5 % of the larger side, at least 1 m.
    let pad = (0.05 * (x1 - x0).max(y1 - y0)).max(1.0);
    x0 -= pad;
    x1 += pad;
    y0 -= pad;
    y1 += pad;
    let scale = (MAX_W / (x1 - x0)).min(MAX_H / (y1 - y0));
    // Widen a thin side about its centre so the box keeps a readable size.
    let widen = |lo: &mut f64, hi: &mut f64| {
        let px = (*hi - *lo) * scale;
        if px < MIN_SIDE {
            let extra = (MIN_SIDE / scale - (*hi - *lo)) / 2.0;
            *lo -= extra;
            *hi += extra;
        }
    };
    widen(&mut x0, &mut x1);
    widen(&mut y0, &mut y1);
    Frame {
        left: LEFT,
        top: TOP,
        width: (x1 - x0) * scale,
        height: (y1 - y0) * scale,
        x0,
        x1,
        y0,
        y1,
    }
}

#[derive(Default)]
struct Bounds(Option<(f64, f64, f64, f64)>);

impl Bounds {
    fn add(&mut self, p: P2) {
        // Far-out values (a diverged simulation) would squash the plot to nothing.
        if !(p.x.is_finite() && p.y.is_finite()) || p.x.abs() > 1e6 || p.y.abs() > 1e6 {
            return;
        }
        self.0 = Some(match self.0 {
            None => (p.x, p.x, p.y, p.y),
            Some((a, b, c, d)) => (a.min(p.x), b.max(p.x), c.min(p.y), d.max(p.y)),
        });
    }
    fn circle(&mut self, c: P2, r: f64) {
        let r = if r.is_finite() { r.abs() } else { 0.0 };
        self.add(c.sub(P2::new(r, r)));
        self.add(c.add(P2::new(r, r)));
    }
    fn get(&self) -> Option<(f64, f64, f64, f64)> {
        self.0
    }
}

/// An obstacle's outline in the world frame.
enum Outline {
    Circle(P2, f64),
    Poly(Vec<P2>),
}

fn outline(shape: &SimShape, shift: P2) -> Outline {
    match shape {
        SimShape::Circle { center, radius } => Outline::Circle(center.add(shift), *radius),
        SimShape::Rectangle {
            center,
            half_size,
            angle,
        } => {
            let (sn, cs) = angle.sin_cos();
            let corners = [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)];
            Outline::Poly(
                corners
                    .iter()
                    .map(|&(a, b)| {
                        let (lx, ly) = (a * half_size.x, b * half_size.y);
                        P2::new(
                            center.x + shift.x + cs * lx - sn * ly,
                            center.y + shift.y + sn * lx + cs * ly,
                        )
                    })
                    .collect(),
            )
        }
        SimShape::Polygon { points } => {
            Outline::Poly(points.iter().map(|p| p.add(shift)).collect())
        }
    }
}

fn shape_center(shape: &SimShape) -> P2 {
    match shape {
        SimShape::Circle { center, .. } | SimShape::Rectangle { center, .. } => *center,
        SimShape::Polygon { points } if !points.is_empty() => points
            .iter()
            .fold(P2::default(), |a, &p| a.add(p))
            .scale(1.0 / points.len() as f64),
        SimShape::Polygon { .. } => P2::new(f64::NAN, f64::NAN),
    }
}

fn defs(s: &mut Svg, f: &Frame) {
    s.raw(&format!(
        "<defs>\n\
         <marker id=\"arrow\" viewBox=\"0 0 10 10\" refX=\"9\" refY=\"5\" markerWidth=\"7\" \
         markerHeight=\"7\" orient=\"auto\"><path d=\"M0 0L10 5L0 10z\" fill=\"#555\"/></marker>\n\
         <linearGradient id=\"fieldramp\" x1=\"0\" y1=\"0\" x2=\"1\" y2=\"0\">\
         <stop offset=\"0\" stop-color=\"{}\"/><stop offset=\"0.5\" stop-color=\"{}\"/>\
         <stop offset=\"1\" stop-color=\"{}\"/></linearGradient>\n\
         <clipPath id=\"plotbox\"><rect x=\"{:.2}\" y=\"{:.2}\" width=\"{:.2}\" height=\"{:.2}\"/></clipPath>\n\
         </defs>\n",
        ramp(0.0),
        ramp(0.5),
        ramp(1.0),
        f.left,
        f.top,
        f.width,
        f.height
    ));
}

/// Contour colour for a level fraction in [0, 1]: blue (low, the goal's basin) through violet
/// to orange (high, near obstacles).
pub(super) fn ramp(t: f64) -> String {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let stops = [
        (40.0, 100.0, 190.0),
        (140.0, 90.0, 170.0),
        (225.0, 120.0, 30.0),
    ];
    let (a, b, u) = if t < 0.5 {
        (stops[0], stops[1], t * 2.0)
    } else {
        (stops[1], stops[2], t * 2.0 - 1.0)
    };
    let mix = |x: f64, y: f64| (x + (y - x) * u).round() as u8;
    format!(
        "#{:02x}{:02x}{:02x}",
        mix(a.0, b.0),
        mix(a.1, b.1),
        mix(a.2, b.2)
    )
}

fn page_points(f: &Frame, pts: &[P2]) -> Vec<(f64, f64)> {
    pts.iter().map(|p| (f.px(p.x), f.py(p.y))).collect()
}

fn draw_obstacle(s: &mut Svg, f: &Frame, o: &SimObstacle, t_end: f64) {
    let fill = "fill=\"#b8b8b8\" stroke=\"#444\" stroke-width=\"1.2\"";
    let ghost =
        "fill=\"none\" stroke=\"#666\" stroke-width=\"1\" stroke-dasharray=\"4 3\" opacity=\"0.8\"";
    let shift = o.velocity.scale(t_end);
    let moving = shift.norm() > 1e-9;
    let shapes: &[(P2, &str)] = if moving {
        &[(shift, ghost), (P2::default(), fill)]
    } else {
        &[(P2::default(), fill)]
    };
    for &(d, style) in shapes {
        match outline(&o.shape, d) {
            Outline::Circle(c, r) => s.circle(f.px(c.x), f.py(c.y), r.abs() * f.sx(), style),
            Outline::Poly(pts) => s.polygon(&page_points(f, &pts), style),
        }
    }
    if moving {
        let c0 = shape_center(&o.shape);
        let c1 = c0.add(shift);
        s.line(
            f.px(c0.x),
            f.py(c0.y),
            f.px(c1.x),
            f.py(c1.y),
            "stroke=\"#555\" stroke-width=\"1.3\" marker-end=\"url(#arrow)\"",
        );
    }
}

fn draw_goal(s: &mut Svg, f: &Frame, g: P2, r: f64, colour: &str) {
    let (x, y) = (f.px(g.x), f.py(g.y));
    if r.is_finite() && r > 0.0 {
        s.circle(
            x,
            y,
            r * f.sx(),
            &format!("fill=\"{colour}\" fill-opacity=\"0.08\" stroke=\"{colour}\" stroke-dasharray=\"3 3\""),
        );
    }
    let k = 6.0;
    let st = format!("stroke=\"{colour}\" stroke-width=\"2.2\"");
    s.line(x - k, y - k, x + k, y + k, &st);
    s.line(x - k, y + k, x + k, y - k, &st);
}

/// A waypoint mission: the route as a dashed line, each waypoint's arrival circle, its number
/// and when it was reached (`types::waypoint_arrivals`), the last one as a goal.
fn draw_waypoints(s: &mut Svg, f: &Frame, v: &VehicleRecord, colour: &str) {
    let pts: Vec<(f64, f64)> = v
        .waypoints
        .iter()
        .map(|w| (f.px(w.position.x), f.py(w.position.y)))
        .collect();
    let mut d = PathData::new();
    pts.iter().for_each(|&(x, y)| d.to(x, y));
    s.path(
        &d,
        &format!(r#"fill="none" stroke="{colour}" stroke-width="1" stroke-dasharray="6 4" stroke-opacity="0.6""#),
    );
    let times = crate::types::waypoint_arrivals(&v.waypoints, &v.samples);
    for (k, (w, t)) in v.waypoints.iter().zip(times).enumerate() {
        let (x, y) = (f.px(w.position.x), f.py(w.position.y));
        if k + 1 == v.waypoints.len() {
            draw_goal(s, f, w.position, w.radius_m, colour);
        } else if w.radius_m.is_finite() && w.radius_m > 0.0 {
            s.circle(
                x,
                y,
                w.radius_m * f.sx(),
                &format!(r#"fill="{colour}" fill-opacity="0.08" stroke="{colour}""#),
            );
            s.circle(x, y, 2.5, &format!(r#"fill="{colour}""#));
        }
        let label = match t {
            Some(t) => format!("{} ({t:.0} s)", k + 1),
            None => format!("{} (–)", k + 1),
        };
        s.text(
            x + 6.0,
            y - 6.0,
            &label,
            &format!(r#"font-size="11" fill="{colour}""#),
        );
    }
}

fn diamond(s: &mut Svg, x: f64, y: f64, k: f64, attrs: &str) {
    s.polygon(&[(x, y - k), (x + k, y), (x, y + k), (x - k, y)], attrs);
}

fn heading_triangle(s: &mut Svg, x: f64, y: f64, psi: f64, attrs: &str) {
    // Page y points down, so the heading's page direction is (cos ψ, −sin ψ).
    let (sn, cs) = psi.sin_cos();
    let (dx, dy) = (cs, -sn);
    let (nx, ny) = (-dy, dx);
    s.polygon(
        &[
            (x + 11.0 * dx, y + 11.0 * dy),
            (x - 5.0 * dx + 5.0 * nx, y - 5.0 * dy + 5.0 * ny),
            (x - 5.0 * dx - 5.0 * nx, y - 5.0 * dy - 5.0 * ny),
        ],
        attrs,
    );
}

/// Draws a vehicle; returns whether it had a collision.
fn draw_vehicle(s: &mut Svg, f: &Frame, v: &VehicleRecord, colour: &str) -> bool {
    let mut d = PathData::new();
    for smp in &v.samples {
        let p = smp.state.position;
        d.to(f.px(p.x), f.py(p.y));
    }
    s.path(
        &d,
        &format!("fill=\"none\" stroke=\"{colour}\" stroke-width=\"2\" stroke-linejoin=\"round\""),
    );
    for g in &v.ghosts {
        diamond(
            s,
            f.px(g.x),
            f.py(g.y),
            6.0,
            &format!(
                "fill=\"white\" fill-opacity=\"0.6\" stroke=\"{colour}\" stroke-width=\"1.8\""
            ),
        );
    }
    let pos_ok = |p: P2| finite(&[p.x, p.y]);
    if let Some(first) = v.samples.iter().find(|x| pos_ok(x.state.position)) {
        let p = first.state.position;
        s.circle(
            f.px(p.x),
            f.py(p.y),
            5.0,
            &format!("fill=\"{colour}\" stroke=\"white\" stroke-width=\"1.5\""),
        );
    }
    if let Some(last) = v.samples.iter().rev().find(|x| pos_ok(x.state.position)) {
        let p = last.state.position;
        let psi = if last.state.heading.is_finite() {
            last.state.heading
        } else {
            0.0
        };
        heading_triangle(
            s,
            f.px(p.x),
            f.py(p.y),
            psi,
            &format!("fill=\"{colour}\" stroke=\"white\" stroke-width=\"1\""),
        );
    }
    // A ring where each collision episode began.
    let mut colliding = false;
    let mut any = false;
    for smp in &v.samples {
        let c = smp.nearest_m;
        if c.is_nan() {
            continue;
        }
        if c < 0.0 && !colliding {
            let p = smp.state.position;
            s.circle(
                f.px(p.x),
                f.py(p.y),
                8.0,
                "fill=\"none\" stroke=\"#e00000\" stroke-width=\"2.5\"",
            );
            any = true;
        }
        colliding = c < 0.0;
    }
    any
}

fn legend(s: &mut Svg, f: &Frame, run: &RunOutput, any_collision: bool, believed: bool) {
    let x = f.left + f.width + 22.0;
    let tx = x + 34.0;
    let text = |s: &mut Svg, y: f64, t: &str| s.text(tx, y + 4.0, t, "fill=\"#222\"");
    let mut y = svg::vehicle_legend(s, x, f.top + 8.0, &run.vehicles, 3.0);
    let grey = "#555";
    s.circle(
        x + 12.0,
        y,
        5.0,
        &format!("fill=\"{grey}\" stroke=\"white\" stroke-width=\"1.5\""),
    );
    text(s, y, "start");
    y += 18.0;
    heading_triangle(s, x + 10.0, y, 0.0, &format!("fill=\"{grey}\""));
    text(s, y, "end, pointing along heading");
    y += 18.0;
    draw_legend_goal(s, x + 12.0, y);
    let arr = run.arrival_radius_m;
    if arr.is_finite() {
        text(s, y, &format!("goal, arrival radius {arr} m"));
    } else {
        text(s, y, "goal");
    }
    y += 18.0;
    diamond(
        s,
        x + 12.0,
        y,
        6.0,
        &format!("fill=\"white\" stroke=\"{grey}\" stroke-width=\"1.8\""),
    );
    text(s, y, "ghost goal-point");
    y += 18.0;
    // An area's swatch and its label.
    let swatch = |s: &mut Svg, y: f64, style: &str, label: &str| {
        s.rect(x + 2.0, y - 7.0, 20.0, 14.0, style);
        text(s, y, label);
    };
    swatch(
        s,
        y,
        "fill=\"#b8b8b8\" stroke=\"#444\" stroke-width=\"1.2\"",
        "obstacle at t = 0",
    );
    y += 18.0;
    swatch(
        s,
        y,
        "fill=\"none\" stroke=\"#666\" stroke-dasharray=\"4 3\"",
        "moving obstacle at the end",
    );
    y += 18.0;
    if believed {
        swatch(s, y, BELIEF_EVER, "believed by the firmware (sonar map)");
        y += 18.0;
        swatch(s, y, BELIEF_NOW, "... and still believed at the end");
        y += 18.0;
    }
    if any_collision {
        s.circle(
            x + 12.0,
            y,
            7.0,
            "fill=\"none\" stroke=\"#e00000\" stroke-width=\"2.5\"",
        );
        text(s, y, "collision");
        y += 18.0;
    }
    y = legend_current(s, x, y, run);
    if !run.vehicles.is_empty() {
        y += 8.0;
        s.text(x, y, "potential field contours", "fill=\"#222\"");
        y += 10.0;
        s.rect(x, y, 150.0, 10.0, "fill=\"url(#fieldramp)\"");
        y += 24.0;
        s.text(x, y, "low (goal)", "font-size=\"11\" fill=\"#555\"");
        s.text(
            x + 150.0,
            y,
            "high (obstacles)",
            "font-size=\"11\" fill=\"#555\" text-anchor=\"end\"",
        );
        y += 16.0;
        for line in [
            "levels: even in log₁₀(E − E_min + δ),",
            "then one per decade of E",
        ] {
            s.text(x, y, line, "font-size=\"11\" fill=\"#555\"");
            y += 14.0;
        }
    }
}

/// The current, true and as each vehicle's firmware believed it at its last telemetry: an arrow
/// along each (north up), its speed in the label. Nothing in still water with nothing believed.
fn legend_current(s: &mut Svg, x: f64, y: f64, run: &RunOutput) -> f64 {
    let believed = run.vehicles.iter().enumerate().filter_map(|(i, v)| {
        let c = v.telemetry?.current;
        let c = P2::new(f64::from(c.x), f64::from(c.y));
        (c.norm() >= 0.005).then(|| (svg::colour(i), format!("believed by {}", v.name), c))
    });
    let truth = (run.current.norm() > 0.0).then(|| ("#555", "current".to_string(), run.current));
    let mut y = y;
    for (colour, label, c) in truth.into_iter().chain(believed) {
        let u = c.scale(1.0 / c.norm());
        let (x0, y0) = (x + 12.0 - 8.0 * u.x, y + 8.0 * u.y);
        let (x1, y1) = (x + 12.0 + 8.0 * u.x, y - 8.0 * u.y);
        let style = format!("stroke=\"{colour}\" stroke-width=\"2\" marker-end=\"url(#arrow)\"");
        s.line(x0, y0, x1, y1, &style);
        let label = format!("{label} {:.2} m/s", c.norm());
        s.text(x + 34.0, y + 4.0, &label, "fill=\"#222\"");
        y += 18.0;
    }
    y
}

fn draw_legend_goal(s: &mut Svg, x: f64, y: f64) {
    s.circle(
        x,
        y,
        8.0,
        "fill=\"#555\" fill-opacity=\"0.08\" stroke=\"#555\" stroke-dasharray=\"3 3\"",
    );
    let st = "stroke=\"#555\" stroke-width=\"2.2\"";
    s.line(x - 5.0, y - 5.0, x + 5.0, y + 5.0, st);
    s.line(x - 5.0, y + 5.0, x + 5.0, y - 5.0, st);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::svg::check::well_formed;
    use crate::output::test_support;
    use crate::types::VehicleRecord;

    #[test]
    fn marching_squares_traces_a_circle() {
        // Cone |p − (10, 10)| on a 20 × 20 grid: the level-5 line is a circle of radius 5.
        let n = 20;
        let v: Vec<f64> = (0..=n)
            .flat_map(|j| (0..=n).map(move |i| (i as f64 - 10.0).hypot(j as f64 - 10.0)))
            .collect();
        let mut segs = 0;
        marching_squares(&v, n, n, 5.0, |a, b| {
            segs += 1;
            for p in [a, b] {
                let r = (p.0 - 10.0).hypot(p.1 - 10.0);
                assert!((r - 5.0).abs() < 0.15, "{p:?} at r = {r}");
            }
        });
        assert!(segs > 20, "{segs}");
        // A wrong length or a NaN level draws nothing rather than panicking.
        marching_squares(&v[1..], n, n, 5.0, |_, _| panic!("drew"));
        marching_squares(&v, n, n, f64::NAN, |_, _| panic!("drew"));
    }

    #[test]
    fn field_matches_the_firmware_pdfs() {
        let run = test_support::run();
        let obs = field_obstacles(&run.obstacles, run.params.a_plus);
        assert_eq!(obs.len(), 3);
        let g = vpf::field::GoalPdf::new(vpf::Vec2::new(10.0, 0.0), 50.0, 40.0);
        // At the goal: −A⁻ plus a little repulsion; near the circle: large.
        let at_goal = potential(&obs, &g, P2::new(10.0, 0.0));
        assert!((-50.0..-45.0).contains(&at_goal), "{at_goal}");
        let near = potential(&obs, &g, P2::new(6.1, 0.5));
        assert!(near > 100.0, "{near}");
    }

    #[test]
    fn plot_is_well_formed_and_has_its_parts() {
        let svg = render(&test_support::run());
        well_formed(&svg);
        assert!(svg.contains("two &lt;vehicles&gt; &amp; rocks"));
        assert!(
            svg.contains("marker-end=\"url(#arrow)\""),
            "moving obstacle arrow"
        );
        assert!(
            svg.matches("<path d=").count() > 10,
            "contours and trajectories"
        );
        assert!(svg.contains(">alpha<") && svg.contains(">beta<"));
        assert!(svg.contains(">current 0.20 m/s<"), "the current's arrow");
    }

    #[test]
    fn plot_survives_empty_and_nan_input() {
        let mut run = test_support::run();
        run.vehicles[0].samples[5].state.position = P2::new(f64::NAN, 1.0);
        run.vehicles[0].samples[6].nearest_m = f64::NAN;
        run.vehicles[1].samples[0].state.heading = f64::NAN;
        run.vehicles[1].ghosts.push(P2::new(f64::INFINITY, 0.0));
        run.obstacles.push(SimObstacle {
            shape: SimShape::Polygon { points: vec![] },
            velocity: P2::new(1.0, 0.0),
        });
        run.arrival_radius_m = f64::NAN;
        well_formed(&render(&run));

        run.vehicles.clear();
        run.obstacles.clear();
        well_formed(&render(&run));

        run.vehicles.push(VehicleRecord::default());
        run.params.sigma_m = 0.0;
        let svg = render(&run);
        well_formed(&svg);
        assert!(svg.contains("no samples recorded"));
    }
}
