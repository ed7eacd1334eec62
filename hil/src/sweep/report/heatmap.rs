//! `heatmap_success.svg` and `heatmap_clearance.svg`: a metric over the two most influential
//! parameters, each cell the mean over the sets with that pair of values.

use std::collections::BTreeMap;

use super::{symbol, Binning, Report};
use crate::output::svg::{esc, Svg};
use crate::sweep::criterion::SetStats;
use crate::sweep::spec::Spec;

impl Report {
    /// The heat map of `metric` ("success" or "clearance").
    pub fn heatmap(&self, spec: &Spec, metric: Metric) -> String {
        let (px, py) = self.axes;
        let bx = Binning::new(spec, px);
        let by = py.map(|p| Binning::new(spec, p));
        let (nx, ny) = (bx.labels.len(), by.as_ref().map_or(1, |b| b.labels.len()));
        let stats: BTreeMap<usize, &SetStats> = self.ranked.iter().map(|s| (s.set, s)).collect();
        let mut cells = vec![(0.0, 0usize); nx * ny];
        for (i, set) in spec.sets.iter().enumerate() {
            let Some(st) = stats.get(&i) else { continue };
            if st.runs == 0 {
                continue;
            }
            let v = match metric {
                Metric::Success => st.success_rate(),
                Metric::Clearance => st.mean_clearance_m,
            };
            if !v.is_finite() {
                continue;
            }
            let x = bx.index(&set[px]);
            let y = by.as_ref().map_or(0, |b| b.index(&set[py.unwrap_or(0)]));
            cells[y * nx + x].0 += v;
            cells[y * nx + x].1 += 1;
        }
        let values: Vec<Option<f64>> = cells
            .iter()
            .map(|c| (c.1 > 0).then(|| c.0 / c.1 as f64))
            .collect();
        let (lo, hi) = match metric {
            Metric::Success => (0.0, 1.0),
            Metric::Clearance => {
                let xs = values.iter().flatten();
                let lo = xs.clone().copied().fold(f64::INFINITY, f64::min);
                let hi = xs.copied().fold(f64::NEG_INFINITY, f64::max);
                if lo.is_finite() && hi > lo {
                    (lo, hi)
                } else {
                    (0.0, lo.max(0.0) + 1.0)
                }
            }
        };
        let (cw, ch) = (78.0, 46.0);
        let (left, top) = (120.0, 70.0);
        let w = (left + cw * nx as f64 + 150.0).max(820.0);
        let h = top + ch * ny as f64 + 80.0;
        let mut svg = Svg::new(w, h);
        let pname = |p: usize| {
            let n = &spec.params[p].name;
            if symbol(n) == n.as_str() {
                n.clone()
            } else {
                format!("{} ({n})", symbol(n))
            }
        };
        let title = match metric {
            Metric::Success => "Success rate (reached the goal, no collision)",
            Metric::Clearance => "Mean minimum clearance, m",
        };
        svg.text(
            left,
            24.0,
            &format!("{title} — sweep \"{}\"", spec.name),
            "font-size=\"15\" font-weight=\"bold\"",
        );
        svg.text(
            left,
            44.0,
            "each cell: mean over the parameter sets with these two values (n = sets); outlined: the recommended set",
            "font-size=\"11\" fill=\"#555\"",
        );
        let best = self.best().map(|b| {
            let set = &spec.sets[b.set];
            (
                bx.index(&set[px]),
                by.as_ref().map_or(0, |bb| bb.index(&set[py.unwrap_or(0)])),
            )
        });
        for yi in 0..ny {
            for xi in 0..nx {
                // Row 0 at the bottom (y grows upwards).
                let x = left + cw * xi as f64;
                let y = top + ch * (ny - 1 - yi) as f64;
                let v = values[yi * nx + xi];
                let fill = v.map_or("#eeeeee".to_string(), |v| {
                    colour(metric, (v - lo) / (hi - lo))
                });
                svg.rect(
                    x,
                    y,
                    cw,
                    ch,
                    &format!("fill=\"{fill}\" stroke=\"white\" stroke-width=\"1\""),
                );
                if let Some(v) = v {
                    let label = match metric {
                        Metric::Success => format!("{:.0} %", 100.0 * v),
                        Metric::Clearance => format!("{v:.2}"),
                    };
                    let dark = (v - lo) / (hi - lo) > 0.6 && metric == Metric::Clearance;
                    let col = if dark { "white" } else { "#111" };
                    svg.text(
                        x + cw / 2.0,
                        y + ch / 2.0,
                        &label,
                        &format!("text-anchor=\"middle\" fill=\"{col}\" font-size=\"13\""),
                    );
                    svg.text(
                        x + cw / 2.0,
                        y + ch / 2.0 + 14.0,
                        &format!("n = {}", cells[yi * nx + xi].1),
                        &format!("text-anchor=\"middle\" fill=\"{col}\" font-size=\"9\""),
                    );
                }
            }
        }
        if let Some((bxi, byi)) = best {
            let x = left + cw * bxi as f64;
            let y = top + ch * (ny - 1 - byi) as f64;
            svg.rect(
                x + 1.5,
                y + 1.5,
                cw - 3.0,
                ch - 3.0,
                "fill=\"none\" stroke=\"#000\" stroke-width=\"3\"",
            );
        }
        for (xi, l) in bx.labels.iter().enumerate() {
            svg.text(
                left + cw * (xi as f64 + 0.5),
                top + ch * ny as f64 + 18.0,
                l,
                "text-anchor=\"middle\" fill=\"#333\"",
            );
        }
        svg.text(
            left + cw * nx as f64 / 2.0,
            top + ch * ny as f64 + 42.0,
            &pname(px),
            "text-anchor=\"middle\" font-size=\"13\"",
        );
        if let (Some(by), Some(py)) = (&by, py) {
            for (yi, l) in by.labels.iter().enumerate() {
                let y = top + ch * (ny - 1 - yi) as f64 + ch / 2.0 + 4.0;
                svg.text(left - 8.0, y, l, "text-anchor=\"end\" fill=\"#333\"");
            }
            let (cx, cy) = (left - 70.0, top + ch * ny as f64 / 2.0);
            svg.raw(&format!(
                "<text x=\"{cx:.1}\" y=\"{cy:.1}\" text-anchor=\"middle\" font-size=\"13\" \
                 transform=\"rotate(-90 {cx:.1} {cy:.1})\">{}</text>\n",
                esc(&pname(py))
            ));
        }
        // Colour scale.
        let sx = left + cw * nx as f64 + 30.0;
        let steps = 20;
        let bar_h = (ch * ny as f64).max(120.0);
        for i in 0..steps {
            let t = i as f64 / (steps - 1) as f64;
            let y = top + bar_h * (1.0 - (i + 1) as f64 / steps as f64);
            svg.rect(
                sx,
                y,
                18.0,
                bar_h / steps as f64 + 0.5,
                &format!("fill=\"{}\"", colour(metric, t)),
            );
        }
        let fmt = |v: f64| match metric {
            Metric::Success => format!("{:.0} %", 100.0 * v),
            Metric::Clearance => format!("{v:.2} m"),
        };
        svg.text(sx + 24.0, top + 10.0, &fmt(hi), "fill=\"#333\"");
        svg.text(sx + 24.0, top + bar_h, &fmt(lo), "fill=\"#333\"");
        if metric == Metric::Clearance {
            svg.text(
                sx,
                top + bar_h + 20.0,
                &format!("margin {} m", spec.craft.margin_m),
                "fill=\"#333\" font-size=\"11\"",
            );
        }
        svg.finish()
    }
}

/// A heat map's quantity.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// Success rate.
    Success,
    /// Mean minimum clearance.
    Clearance,
}

/// Red–yellow–green for success, white–blue for clearance; `t` in 0..=1.
fn colour(metric: Metric, t: f64) -> String {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let stops: &[(f64, [f64; 3])] = match metric {
        Metric::Success => &[
            (0.0, [215.0, 48.0, 39.0]),
            (0.5, [254.0, 224.0, 139.0]),
            (1.0, [26.0, 152.0, 80.0]),
        ],
        Metric::Clearance => &[(0.0, [247.0, 251.0, 255.0]), (1.0, [8.0, 81.0, 156.0])],
    };
    let i = stops
        .windows(2)
        .position(|w| t <= w[1].0)
        .unwrap_or(stops.len() - 2);
    let (a, b) = (stops[i], stops[i + 1]);
    let u = (t - a.0) / (b.0 - a.0);
    let c: Vec<u8> = (0..3)
        .map(|k| (a.1[k] + u * (b.1[k] - a.1[k])).round() as u8)
        .collect();
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_span_the_scale() {
        assert_eq!(colour(Metric::Success, 0.0), "#d73027");
        assert_eq!(colour(Metric::Success, 1.0), "#1a9850");
        assert_eq!(colour(Metric::Clearance, f64::NAN), "#f7fbff");
    }
}
