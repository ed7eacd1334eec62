//! A minimal SVG writer shared by the plots: elements as text, coordinates checked for
//! finiteness (an element with a NaN coordinate is left out rather than written as "NaN"),
//! "nice" axis ticks, and plot frames that map data to pixels.

use std::fmt::Write as _;

/// Distinct colours for vehicles (Tableau 10, readable on white).
pub const PALETTE: [&str; 8] = [
    "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf",
];

/// The colour of vehicle `i`.
pub fn colour(i: usize) -> &'static str {
    PALETTE[i % PALETTE.len()]
}

/// XML text escaping for element content and attribute values.
pub fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            // Control characters are not allowed in XML 1.0.
            c if c.is_control() => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// Whether all numbers are finite.
pub fn finite(xs: &[f64]) -> bool {
    xs.iter().all(|x| x.is_finite())
}

/// An SVG document being written.
pub struct Svg {
    buf: String,
}

impl Svg {
    /// A `w` × `h` pixel document with a white background.
    pub fn new(w: f64, h: f64) -> Svg {
        let mut buf = String::new();
        let _ = write!(
            buf,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
             <svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w:.0}\" height=\"{h:.0}\" \
             viewBox=\"0 0 {w:.0} {h:.0}\" font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\" \
             font-size=\"12\">\n\
             <rect x=\"0\" y=\"0\" width=\"{w:.0}\" height=\"{h:.0}\" fill=\"white\"/>\n"
        );
        Svg { buf }
    }

    /// The finished document.
    pub fn finish(mut self) -> String {
        self.buf.push_str("</svg>\n");
        self.buf
    }

    /// Appends raw markup (the caller keeps it well-formed).
    pub fn raw(&mut self, s: &str) {
        self.buf.push_str(s);
    }

    /// A line segment.
    pub fn line(&mut self, x1: f64, y1: f64, x2: f64, y2: f64, attrs: &str) {
        if finite(&[x1, y1, x2, y2]) {
            let _ = writeln!(
                self.buf,
                "<line x1=\"{x1:.2}\" y1=\"{y1:.2}\" x2=\"{x2:.2}\" y2=\"{y2:.2}\" {attrs}/>"
            );
        }
    }

    /// A circle.
    pub fn circle(&mut self, cx: f64, cy: f64, r: f64, attrs: &str) {
        if finite(&[cx, cy, r]) && r >= 0.0 {
            let _ = writeln!(
                self.buf,
                "<circle cx=\"{cx:.2}\" cy=\"{cy:.2}\" r=\"{r:.2}\" {attrs}/>"
            );
        }
    }

    /// A rectangle.
    pub fn rect(&mut self, x: f64, y: f64, w: f64, h: f64, attrs: &str) {
        if finite(&[x, y, w, h]) && w >= 0.0 && h >= 0.0 {
            let _ = writeln!(
                self.buf,
                "<rect x=\"{x:.2}\" y=\"{y:.2}\" width=\"{w:.2}\" height=\"{h:.2}\" {attrs}/>"
            );
        }
    }

    /// A closed polygon (left out if any vertex is not finite).
    pub fn polygon(&mut self, pts: &[(f64, f64)], attrs: &str) {
        if pts.is_empty() || !pts.iter().all(|&(x, y)| finite(&[x, y])) {
            return;
        }
        let mut p = String::new();
        for (x, y) in pts {
            let _ = write!(p, "{x:.2},{y:.2} ");
        }
        let _ = writeln!(self.buf, "<polygon points=\"{}\" {attrs}/>", p.trim_end());
    }

    /// Text at (x, y); `s` is escaped.
    pub fn text(&mut self, x: f64, y: f64, s: &str, attrs: &str) {
        if finite(&[x, y]) {
            let _ = writeln!(
                self.buf,
                "<text x=\"{x:.1}\" y=\"{y:.1}\" {attrs}>{}</text>",
                esc(s)
            );
        }
    }

    /// A path with data `d` (from [`PathData`]); nothing if `d` is empty.
    pub fn path(&mut self, d: &PathData, attrs: &str) {
        if !d.is_empty() {
            let _ = writeln!(self.buf, "<path d=\"{}\" {attrs}/>", d.d);
        }
    }
}

/// Path data built point by point; a non-finite point lifts the pen, so a NaN in the data
/// leaves a gap instead of a broken document.
#[derive(Default)]
pub struct PathData {
    d: String,
    down: bool,
    decimals: usize,
}

impl PathData {
    /// Empty path data with 2 decimals.
    pub fn new() -> PathData {
        PathData {
            decimals: 2,
            ..PathData::default()
        }
    }

    /// Empty path data with `decimals` decimals (fewer for dense contours).
    pub fn with_decimals(decimals: usize) -> PathData {
        PathData {
            decimals,
            ..PathData::default()
        }
    }

    /// Continues the line to (x, y), or starts one if the pen is up.
    pub fn to(&mut self, x: f64, y: f64) {
        if !finite(&[x, y]) {
            self.down = false;
            return;
        }
        let cmd = if self.down { 'L' } else { 'M' };
        let n = self.decimals;
        let _ = write!(self.d, "{cmd}{x:.n$} {y:.n$}");
        self.down = true;
    }

    /// Lifts the pen: the next point starts a new sub-path.
    pub fn lift(&mut self) {
        self.down = false;
    }

    /// A separate segment.
    pub fn segment(&mut self, a: (f64, f64), b: (f64, f64)) {
        self.lift();
        self.to(a.0, a.1);
        self.to(b.0, b.1);
        self.lift();
    }

    /// Whether nothing was drawn.
    pub fn is_empty(&self) -> bool {
        self.d.is_empty()
    }
}

/// A "nice" tick step (1, 2 or 5 × 10ⁿ) giving about `n` intervals over `span`.
pub fn nice_step(span: f64, n: f64) -> f64 {
    if !(span.is_finite() && span > 0.0 && n > 0.0) {
        return 1.0;
    }
    let raw = span / n;
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    let m = if f < 1.5 {
        1.0
    } else if f < 3.5 {
        2.0
    } else if f < 7.5 {
        5.0
    } else {
        10.0
    };
    m * mag
}

/// Multiples of `step` inside [lo, hi].
pub fn ticks(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    if !(finite(&[lo, hi, step]) && step > 0.0 && hi >= lo) || (hi - lo) / step > 1000.0 {
        return Vec::new();
    }
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// A tick label with as many decimals as the step needs.
pub fn tick_label(v: f64, step: f64) -> String {
    let decimals = if step > 0.0 && step < 1.0 {
        (-step.log10().floor()) as usize
    } else {
        0
    };
    let s = format!("{v:.decimals$}");
    // "-0" reads oddly on an axis.
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

/// A rectangle of the page that shows data range [x0, x1] × [y0, y1] (y up).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// Left edge, px.
    pub left: f64,
    /// Top edge, px.
    pub top: f64,
    /// Width, px.
    pub width: f64,
    /// Height, px.
    pub height: f64,
    /// Data range along x.
    pub x0: f64,
    /// Data range along x.
    pub x1: f64,
    /// Data range along y.
    pub y0: f64,
    /// Data range along y.
    pub y1: f64,
}

impl Frame {
    /// Pixel x of data x.
    pub fn px(&self, x: f64) -> f64 {
        self.left + (x - self.x0) / (self.x1 - self.x0) * self.width
    }

    /// Pixel y of data y (y grows upwards in the data, downwards on the page).
    pub fn py(&self, y: f64) -> f64 {
        self.top + (self.y1 - y) / (self.y1 - self.y0) * self.height
    }

    /// Pixels per data unit along x.
    pub fn sx(&self) -> f64 {
        self.width / (self.x1 - self.x0)
    }

    /// Draws the frame's box, grid lines, tick marks and labels, and axis titles.
    pub fn axes(&self, svg: &mut Svg, xstep: f64, ystep: f64, xlabel: Option<&str>, ylabel: &str) {
        let (l, t, r, b) = (
            self.left,
            self.top,
            self.left + self.width,
            self.top + self.height,
        );
        for x in ticks(self.x0, self.x1, xstep) {
            let px = self.px(x);
            svg.line(px, t, px, b, "stroke=\"#e4e4e4\" stroke-width=\"0.8\"");
            svg.line(px, b, px, b + 5.0, "stroke=\"#333\"");
            if xlabel.is_some() {
                svg.text(
                    px,
                    b + 18.0,
                    &tick_label(x, xstep),
                    "text-anchor=\"middle\" fill=\"#333\"",
                );
            }
        }
        for y in ticks(self.y0, self.y1, ystep) {
            let py = self.py(y);
            svg.line(l, py, r, py, "stroke=\"#e4e4e4\" stroke-width=\"0.8\"");
            svg.line(l - 5.0, py, l, py, "stroke=\"#333\"");
            svg.text(
                l - 8.0,
                py + 4.0,
                &tick_label(y, ystep),
                "text-anchor=\"end\" fill=\"#333\"",
            );
        }
        svg.rect(
            l,
            t,
            self.width,
            self.height,
            "fill=\"none\" stroke=\"#333\" stroke-width=\"1\"",
        );
        if let Some(xl) = xlabel {
            svg.text(
                l + self.width / 2.0,
                b + 38.0,
                xl,
                "text-anchor=\"middle\" font-size=\"13\"",
            );
        }
        let (cx, cy) = (l - 52.0, t + self.height / 2.0);
        if finite(&[cx, cy]) {
            svg.raw(&format!(
                "<text x=\"{cx:.1}\" y=\"{cy:.1}\" text-anchor=\"middle\" font-size=\"13\" \
                 transform=\"rotate(-90 {cx:.1} {cy:.1})\">{}</text>\n",
                esc(ylabel)
            ));
        }
    }
}

#[cfg(test)]
pub(crate) mod check {
    //! A superficial well-formedness check for the SVG tests: balanced tags, no NaN or inf in
    //! the markup, quoted attributes.

    /// Panics with a message if `svg` is not plausibly well-formed.
    pub fn well_formed(svg: &str) {
        assert!(svg.starts_with("<?xml"), "no XML declaration");
        assert!(svg.trim_end().ends_with("</svg>"), "no closing </svg>");
        for bad in [
            "NaN", "\"inf", "\"-inf", " inf", "-inf", ",inf", "Linf", "Minf",
        ] {
            assert!(!svg.contains(bad), "non-finite number ({bad})");
        }
        let mut stack: Vec<String> = Vec::new();
        let mut rest = svg;
        while let Some(i) = rest.find('<') {
            rest = &rest[i..];
            let end = rest.find('>').expect("unterminated tag");
            let tag = &rest[1..end];
            rest = &rest[end + 1..];
            if tag.starts_with('?') || tag.starts_with('!') {
                continue;
            }
            assert_eq!(
                tag.matches('"').count() % 2,
                0,
                "unbalanced quotes in <{tag}>"
            );
            if let Some(name) = tag.strip_prefix('/') {
                let open = stack.pop().expect("close without open");
                assert_eq!(open, name.trim(), "mismatched close tag");
            } else if !tag.ends_with('/') {
                let name = tag.split_whitespace().next().unwrap_or("").to_string();
                stack.push(name);
            }
        }
        assert!(stack.is_empty(), "unclosed tags: {stack:?}");
        // Text between tags must not hold a raw '&' that is not an entity.
        for (i, _) in svg.match_indices('&') {
            let tail = &svg[i..];
            let semi = tail.find(';').expect("bare &");
            assert!(semi < 8, "bare & at {i}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_steps_and_ticks() {
        assert_eq!(nice_step(10.0, 5.0), 2.0);
        assert_eq!(nice_step(100.0, 8.0), 10.0);
        assert_eq!(nice_step(0.3, 6.0), 0.05);
        assert_eq!(nice_step(f64::NAN, 5.0), 1.0);
        assert_eq!(ticks(-1.0, 3.0, 1.0), [-1.0, 0.0, 1.0, 2.0, 3.0]);
        assert!(ticks(0.0, f64::NAN, 1.0).is_empty());
        assert_eq!(tick_label(-0.0, 1.0), "0");
        assert_eq!(tick_label(0.25, 0.05), "0.25");
        assert_eq!(tick_label(20.0, 5.0), "20");
    }

    #[test]
    fn non_finite_points_leave_gaps_not_nan() {
        let mut d = PathData::new();
        d.to(0.0, 0.0);
        d.to(1.0, f64::NAN);
        d.to(2.0, 2.0);
        d.to(3.0, 3.0);
        assert_eq!(d.d, "M0.00 0.00M2.00 2.00L3.00 3.00");
        let mut s = Svg::new(10.0, 10.0);
        s.circle(f64::NAN, 1.0, 1.0, "");
        s.line(0.0, 0.0, f64::INFINITY, 1.0, "");
        s.text(1.0, 1.0, "a < b & \"c\"", "");
        let out = s.finish();
        check::well_formed(&out);
        assert!(out.contains("a &lt; b &amp; &quot;c&quot;"));
    }
}

/// The legend's title and one line of each vehicle's colour with its name; returns the y below.
pub fn vehicle_legend(
    s: &mut Svg,
    x: f64,
    y: f64,
    vehicles: &[crate::types::VehicleRecord],
    stroke_width: f64,
) -> f64 {
    let mut y = y;
    s.text(x, y, "Legend", "font-weight=\"bold\"");
    y += 20.0;
    for (i, v) in vehicles.iter().enumerate() {
        let c = colour(i);
        let style = format!("stroke=\"{c}\" stroke-width=\"{stroke_width}\"");
        s.line(x, y, x + 24.0, y, &style);
        let name = if v.name.is_empty() {
            "(unnamed)"
        } else {
            &v.name
        };
        s.text(x + 32.0, y + 4.0, name, "fill=\"#222\"");
        y += 18.0;
    }
    y + 6.0
}
