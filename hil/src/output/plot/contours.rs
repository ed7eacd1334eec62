//! The contours of the potential field E under the plot: the firmware's own PDFs (its
//! goal-point attractor plus the stator of every obstacle at its t = 0 position; the rotor term
//! is left out because it is defined relative to the vehicle's position and changes every
//! step), traced by marching squares.
//!
//! E spans many decades near obstacles (the stator grows like e^{A⁺/r²}), so the contours are
//! drawn in log₁₀(E − E_min + δ), δ being the goal-point's potential rise over a short distance
//! (so the rings around the goal do not collapse to a point): 18 levels evenly spaced up to the
//! value exceeded on 10 % of the open water, then one level per decade of E above that (at most
//! 6), which shows the repulsion's walls as tight rings around the obstacles.

use super::ramp;
use crate::output::svg::{finite, Frame, PathData, Svg};
use crate::output::RunOutput;
use crate::types::{SimObstacle, P2};

/// Contour levels spaced evenly in log E over the open water.
const LEVELS: usize = 18;
/// At most this many more, one per decade of E, for the repulsion near obstacles.
const DECADES: usize = 6;
/// Contour grid cell, px.
const CELL_PX: f64 = 4.0;

/// The firmware's view of the scenario's obstacles (at t = 0, charted, with the run's A⁺);
/// shapes the firmware cannot represent (e.g. a polygon of more than 8 vertices) are skipped.
pub fn field_obstacles(obstacles: &[SimObstacle], a_plus: f32) -> Vec<vpf::Obstacle> {
    obstacles
        .iter()
        .enumerate()
        .filter_map(|(i, o)| {
            let shape = o.shape.to_vpf().ok()?;
            let id = u16::try_from(i).ok()?;
            vpf::Obstacle::new(id, shape, a_plus, vpf::Origin::Charted, 0).ok()
        })
        .collect()
}

/// E(p) without the rotor: goal-point attractor plus every obstacle's stator (as the
/// firmware's `planner::gradient::Field::potential` sums them).
pub fn potential(obstacles: &[vpf::Obstacle], goal: &vpf::field::GoalPdf, p: P2) -> f64 {
    let x = p.to_vpf();
    let mut e = goal.potential(x);
    for o in obstacles {
        e += o.stator().potential(o.shape.signed_distance(x));
    }
    f64::from(e)
}

pub(super) fn draw_contours(s: &mut Svg, f: &Frame, run: &RunOutput, goal: P2) {
    let p = &run.params;
    let obstacles = field_obstacles(&run.obstacles, p.a_plus);
    let gpdf = vpf::field::GoalPdf::new(goal.to_vpf(), p.a_minus, p.sigma_m);
    let nx = ((f.width / CELL_PX).round() as usize).clamp(8, 300);
    let ny = ((f.height / CELL_PX).round() as usize).clamp(8, 300);
    let (hx, hy) = ((f.x1 - f.x0) / nx as f64, (f.y1 - f.y0) / ny as f64);
    let at = |i: usize, j: usize| P2::new(f.x0 + i as f64 * hx, f.y0 + j as f64 * hy);
    let mut e = Vec::with_capacity((nx + 1) * (ny + 1));
    let mut outside = Vec::with_capacity(e.capacity());
    for j in 0..=ny {
        for i in 0..=nx {
            let q = at(i, j);
            e.push(potential(&obstacles, &gpdf, q));
            let qv = q.to_vpf();
            outside.push(obstacles.iter().all(|o| o.shape.signed_distance(qv) > 0.0));
        }
    }
    let Some(e_min) = e.iter().copied().filter(|x| x.is_finite()).reduce(f64::min) else {
        return;
    };
    // δ: the attractor's rise over d₀, a short distance from the goal.
    let diag = (f.x1 - f.x0).hypot(f.y1 - f.y0);
    let r_arr = run.arrival_radius_m;
    let d0 = if r_arr.is_finite() && r_arr > 0.0 {
        r_arr.max(diag / 30.0)
    } else {
        diag / 30.0
    };
    let sigma = f64::from(p.sigma_m);
    let mut delta = f64::from(p.a_minus) * (1.0 - (-d0 * d0 / (2.0 * sigma * sigma)).exp());
    if !(delta.is_finite() && delta > 0.0) {
        delta = 1e-3 * e_min.abs().max(1.0);
    }
    let v: Vec<f64> = e.iter().map(|&x| (x - e_min + delta).log10()).collect();
    let v_lo = delta.log10();
    // Levels: evenly in log over [v_lo, v_mid], where v_mid is exceeded on only 10 % of the
    // open water (mostly the obstacles' shells), then one per decade up to nearly the highest
    // value outside the obstacles (inside, the clamped stator would spend every level on the
    // surface). The attractor's basin gets most lines; the repulsion's decades show as rings.
    let mut out_vals: Vec<f64> = v
        .iter()
        .zip(&outside)
        .filter(|(x, o)| **o && x.is_finite())
        .map(|(x, _)| *x)
        .collect();
    out_vals.sort_by(f64::total_cmp);
    let quantile = |q: f64| {
        let i = ((out_vals.len().saturating_sub(1)) as f64 * q) as usize;
        out_vals.get(i).copied()
    };
    let (Some(v_mid), Some(v_top)) = (quantile(0.9), quantile(0.995)) else {
        return;
    };
    if v_mid.is_nan() || v_mid <= v_lo {
        return;
    }
    let mut levels: Vec<(f64, f64)> = (0..LEVELS)
        .map(|k| {
            let frac = (k as f64 + 0.5) / LEVELS as f64;
            (v_lo + frac * (v_mid - v_lo), 0.75 * frac)
        })
        .collect();
    let first_decade = (v_mid + 0.3).ceil();
    let decades = ((v_top - first_decade).floor().max(-1.0) + 1.0) as usize;
    for k in 0..decades.min(DECADES) {
        let frac = 0.8 + 0.2 * k as f64 / (DECADES - 1) as f64;
        levels.push((first_decade + k as f64, frac));
    }
    s.raw("<g clip-path=\"url(#plotbox)\" fill=\"none\" stroke-width=\"0.9\" stroke-opacity=\"0.7\" stroke-linecap=\"round\">\n");
    for (level, colour_frac) in levels {
        let mut d = PathData::with_decimals(1);
        marching_squares(&v, nx, ny, level, |a, b| {
            d.segment(
                (f.px(f.x0 + a.0 * hx), f.py(f.y0 + a.1 * hy)),
                (f.px(f.x0 + b.0 * hx), f.py(f.y0 + b.1 * hy)),
            );
        });
        s.path(&d, &format!("stroke=\"{}\"", ramp(colour_frac)));
    }
    s.raw("</g>\n");
}

/// Iso-line segments of `level` over a grid of (nx + 1) × (ny + 1) values (row-major, x fastest),
/// in grid coordinates (i, j). Cells with a non-finite corner are skipped; saddles are resolved
/// by the cell's mean.
pub fn marching_squares(
    values: &[f64],
    nx: usize,
    ny: usize,
    level: f64,
    mut emit: impl FnMut((f64, f64), (f64, f64)),
) {
    if values.len() != (nx + 1) * (ny + 1) || !level.is_finite() {
        return;
    }
    let val = |i: usize, j: usize| values.get(j * (nx + 1) + i).copied().unwrap_or(f64::NAN);
    // Where the level crosses the edge from p (value a) to q (value b).
    let cross = |p: (f64, f64), a: f64, q: (f64, f64), b: f64| {
        let t = if b != a {
            ((level - a) / (b - a)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        (p.0 + t * (q.0 - p.0), p.1 + t * (q.1 - p.1))
    };
    for j in 0..ny {
        for i in 0..nx {
            // Corners counter-clockwise from bottom-left.
            let (a, b, c, d) = (val(i, j), val(i + 1, j), val(i + 1, j + 1), val(i, j + 1));
            if !finite(&[a, b, c, d]) {
                continue;
            }
            let idx = usize::from(a >= level)
                | usize::from(b >= level) << 1
                | usize::from(c >= level) << 2
                | usize::from(d >= level) << 3;
            if idx == 0 || idx == 15 {
                continue;
            }
            let (x, y) = (i as f64, j as f64);
            let pa = (x, y);
            let pb = (x + 1.0, y);
            let pc = (x + 1.0, y + 1.0);
            let pd = (x, y + 1.0);
            let bottom = || cross(pa, a, pb, b);
            let right = || cross(pb, b, pc, c);
            let top = || cross(pd, d, pc, c);
            let left = || cross(pa, a, pd, d);
            let centre_high = (a + b + c + d) / 4.0 >= level;
            match idx {
                1 | 14 => emit(left(), bottom()),
                2 | 13 => emit(bottom(), right()),
                3 | 12 => emit(left(), right()),
                4 | 11 => emit(right(), top()),
                6 | 9 => emit(bottom(), top()),
                7 | 8 => emit(left(), top()),
                // Saddles: a and c high (5) or b and d high (10). The segments cut off the
                // two corners that are not connected through the centre.
                5 | 10 => {
                    let cut_b_and_d = (idx == 5) == centre_high;
                    if cut_b_and_d {
                        emit(bottom(), right());
                        emit(top(), left());
                    } else {
                        emit(left(), bottom());
                        emit(right(), top());
                    }
                }
                _ => {}
            }
        }
    }
}
