//! A small SVG plot writer: world coordinates in metres mapped to pixels with
//! the y axis up, axes with metre ticks, and a legend.

use std::fmt::Write;

/// An SVG plot of a rectangle of data coordinates, y up, with the legend to
/// the right of the frame.
pub struct Plot {
    min: [f64; 2],
    max: [f64; 2],
    scale: [f64; 2],
    margin: f64,
    width: f64,
    height: f64,
    labels: [String; 2],
    body: String,
    legend: Vec<(String, String, Mark)>,
}

/// How a legend entry is drawn: the same mark as the data it names, so a
/// dashed line has a dashed swatch and rings have a ring.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mark {
    /// A solid line this wide, pixels.
    Line(f64),
    /// A dashed line this wide, pixels ([`Plot::polyline`] with `dashed`).
    Dashed(f64),
    /// A filled dot ([`Plot::dots`]).
    Dot,
    /// An open ring ([`Plot::rings`]).
    Ring,
    /// The sensor's triangle ([`Plot::sensor`]).
    Sensor,
}

/// Width of the legend column, pixels.
const LEGEND_W: f64 = 250.0;

impl Plot {
    /// A plot of the box `min`..`max` (metres) about `width_px` wide.
    pub fn new(mut min: [f64; 2], mut max: [f64; 2], width_px: f64) -> Self {
        for k in 0..2 {
            let span = max[k] - min[k];
            if !span.is_finite() {
                // Bounds that overflow (1e308 apart) cannot be drawn to scale.
                (min[k], max[k]) = (-1.0, 1.0);
            } else if span <= 1e-6 {
                min[k] -= 1.0;
                max[k] += 1.0;
            }
        }
        let pad = 0.03 * (max[0] - min[0]).max(max[1] - min[1]);
        let (min, max) = ([min[0] - pad, min[1] - pad], [max[0] + pad, max[1] + pad]);
        let margin = 60.0;
        let scale = (width_px - 2.0 * margin) / (max[0] - min[0]);
        let height = (max[1] - min[1]) * scale + 2.0 * margin;
        Plot {
            min,
            max,
            scale: [scale, scale],
            margin,
            width: width_px + LEGEND_W,
            height,
            labels: ["x (m)".into(), "y (m)".into()],
            body: String::new(),
            legend: Vec::new(),
        }
    }

    /// A chart with independent axis scales (a time series), plot area
    /// `width_px` x `height_px`.
    pub fn chart(
        min: [f64; 2],
        max: [f64; 2],
        width_px: f64,
        height_px: f64,
        labels: [&str; 2],
    ) -> Self {
        let mut plot = Plot::new(min, max, width_px);
        let margin = plot.margin;
        let (min, max) = (plot.min, plot.max);
        plot.scale = [
            (width_px - 2.0 * margin) / (max[0] - min[0]),
            (height_px - 2.0 * margin) / (max[1] - min[1]),
        ];
        plot.height = height_px;
        plot.labels = [labels[0].to_string(), labels[1].to_string()];
        plot
    }

    fn px(&self, p: [f64; 2]) -> (f64, f64) {
        (
            self.margin + (p[0] - self.min[0]) * self.scale[0],
            self.height - self.margin - (p[1] - self.min[1]) * self.scale[1],
        )
    }

    /// A straight segment.
    pub fn line(&mut self, a: [f64; 2], b: [f64; 2], color: &str, width: f64) {
        let ((x1, y1), (x2, y2)) = (self.px(a), self.px(b));
        let _ = writeln!(
            self.body,
            r#"<line x1="{x1:.1}" y1="{y1:.1}" x2="{x2:.1}" y2="{y2:.1}" stroke="{color}" stroke-width="{width}" stroke-linecap="round"/>"#
        );
    }

    /// A polyline.
    pub fn polyline(&mut self, points: &[[f64; 2]], color: &str, width: f64, dashed: bool) {
        if points.len() < 2 {
            return;
        }
        let pts: Vec<String> = points
            .iter()
            .map(|p| {
                let (x, y) = self.px(*p);
                format!("{x:.1},{y:.1}")
            })
            .collect();
        let dash = if dashed { r#" stroke-dasharray="6,4""# } else { "" };
        let _ = writeln!(
            self.body,
            r#"<polyline points="{}" fill="none" stroke="{color}" stroke-width="{width}"{dash}/>"#,
            pts.join(" ")
        );
    }

    /// Filled dots.
    pub fn dots(&mut self, points: &[[f64; 2]], color: &str, radius: f64) {
        for p in points {
            let (x, y) = self.px(*p);
            let _ = writeln!(
                self.body,
                r#"<circle cx="{x:.1}" cy="{y:.1}" r="{radius}" fill="{color}"/>"#
            );
        }
    }

    /// Open rings (markers that leave the point visible).
    pub fn rings(&mut self, points: &[[f64; 2]], color: &str, radius: f64) {
        for p in points {
            let (x, y) = self.px(*p);
            let _ = writeln!(
                self.body,
                r#"<circle cx="{x:.1}" cy="{y:.1}" r="{radius}" fill="none" stroke="{color}" stroke-width="1.5"/>"#
            );
        }
    }

    /// The sensor at `at`, a triangle pointing along its heading
    /// (`heading_rad`, counter-clockwise from x): not a dot, so it cannot be
    /// taken for a point or a break-point.
    pub fn sensor(&mut self, at: [f64; 2], heading_rad: f64, color: &str) {
        let (x, y) = self.px(at);
        let _ = writeln!(self.body, "{}", triangle(x, y, heading_rad, 13.0, color));
    }

    /// Text at a world position.
    pub fn label(&mut self, at: [f64; 2], text: &str, color: &str) {
        let (x, y) = self.px(at);
        let _ = writeln!(
            self.body,
            r#"<text x="{x:.1}" y="{y:.1}" font-size="13" fill="{color}" font-family="sans-serif">{}</text>"#,
            escape(text)
        );
    }

    /// Adds a legend entry drawn with `mark`.
    pub fn legend(&mut self, text: &str, color: &str, mark: Mark) {
        self.legend.push((text.to_string(), color.to_string(), mark));
    }

    /// The finished document with a title, axes in metres and the legend.
    pub fn finish(self, title: &str) -> String {
        let mut out = String::new();
        let (w, h) = (self.width, self.height);
        let _ = writeln!(
            out,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0}" height="{h:.0}" viewBox="0 0 {w:.0} {h:.0}">"#
        );
        let _ = writeln!(out, r#"<rect width="100%" height="100%" fill="white"/>"#);
        let _ = writeln!(
            out,
            r#"<text x="{:.1}" y="30" font-size="18" font-family="sans-serif" text-anchor="middle">{}</text>"#,
            w / 2.0,
            escape(title)
        );
        // Axes with ticks at a round step per axis.
        let step_x = nice_step((self.max[0] - self.min[0]) / 8.0);
        let step_y = nice_step((self.max[1] - self.min[1]) / 8.0);
        let (x0, y0) = self.px(self.min);
        let (x1, y1) = self.px(self.max);
        let _ = writeln!(
            out,
            r##"<rect x="{x0:.1}" y="{y1:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="#999"/>"##,
            x1 - x0,
            y0 - y1
        );
        for t in ticks(self.min[0], self.max[0], step_x) {
            let (x, _) = self.px([t, self.min[1]]);
            let _ = writeln!(
                out,
                r##"<line x1="{x:.1}" y1="{y0:.1}" x2="{x:.1}" y2="{:.1}" stroke="#999"/><text x="{x:.1}" y="{:.1}" font-size="12" text-anchor="middle" font-family="sans-serif">{}</text>"##,
                y0 + 5.0,
                y0 + 19.0,
                fmt_tick(t)
            );
        }
        for t in ticks(self.min[1], self.max[1], step_y) {
            let (_, y) = self.px([self.min[0], t]);
            let _ = writeln!(
                out,
                r##"<line x1="{:.1}" y1="{y:.1}" x2="{x0:.1}" y2="{y:.1}" stroke="#999"/><text x="{:.1}" y="{:.1}" font-size="12" text-anchor="end" font-family="sans-serif">{}</text>"##,
                x0 - 5.0,
                x0 - 8.0,
                y + 4.0,
                fmt_tick(t)
            );
        }
        let _ = writeln!(
            out,
            r#"<text x="{:.1}" y="{:.1}" font-size="13" text-anchor="middle" font-family="sans-serif">{}</text>"#,
            (x0 + x1) / 2.0,
            h - 12.0,
            escape(&self.labels[0])
        );
        let _ = writeln!(
            out,
            r#"<text x="16" y="{:.1}" font-size="13" text-anchor="middle" font-family="sans-serif" transform="rotate(-90 16 {:.1})">{}</text>"#,
            (y0 + y1) / 2.0,
            (y0 + y1) / 2.0,
            escape(&self.labels[1])
        );
        out.push_str(&self.body);
        // Legend, right of the frame.
        let lx = x1 + 25.0;
        let mut ly = y1 + 18.0;
        for (text, color, mark) in &self.legend {
            let (cx, cy) = (lx + 11.0, ly - 4.0);
            let swatch = |width: f64, dash: &str| {
                format!(
                    r#"<line x1="{lx:.1}" y1="{cy:.1}" x2="{:.1}" y2="{cy:.1}" stroke="{color}" stroke-width="{:.1}"{dash}/>"#,
                    lx + 22.0,
                    width.clamp(1.5, 8.0)
                )
            };
            let sample = match mark {
                Mark::Line(w) => swatch(*w, ""),
                Mark::Dashed(w) => swatch(*w, r#" stroke-dasharray="6,4""#),
                Mark::Dot => format!(r#"<circle cx="{cx:.1}" cy="{cy:.1}" r="3" fill="{color}"/>"#),
                Mark::Ring => format!(
                    r#"<circle cx="{cx:.1}" cy="{cy:.1}" r="4" fill="none" stroke="{color}" stroke-width="1.5"/>"#
                ),
                Mark::Sensor => triangle(cx, cy, 0.0, 9.0, color),
            };
            let _ = writeln!(out, "{sample}");
            let _ = writeln!(
                out,
                r#"<text x="{:.1}" y="{ly:.1}" font-size="13" font-family="sans-serif">{}</text>"#,
                lx + 30.0,
                escape(text)
            );
            ly += 20.0;
        }
        out.push_str("</svg>\n");
        out
    }
}

/// A filled triangle centred at pixel (x, y), `size` long, pointing along
/// `heading_rad` (y up in the world, so down in pixels).
fn triangle(x: f64, y: f64, heading_rad: f64, size: f64, color: &str) -> String {
    let corner = |angle: f64, r: f64| {
        let a = heading_rad + angle;
        format!("{:.1},{:.1}", x + r * a.cos(), y - r * a.sin())
    };
    format!(
        r#"<polygon points="{} {} {}" fill="{color}" stroke="white" stroke-width="1"/>"#,
        corner(0.0, size),
        corner(2.5, 0.7 * size),
        corner(-2.5, 0.7 * size)
    )
}

/// The multiples of `step` in `min..=max`, computed from their index so a
/// step below the values' precision (coordinates of 1e16 m) cannot loop
/// forever; at most 100, none when the bounds are not finite.
fn ticks(min: f64, max: f64, step: f64) -> Vec<f64> {
    let (first, last) = ((min / step).ceil(), (max / step).floor());
    if !(first.is_finite() && last.is_finite() && step > 0.0) || last - first > 100.0 {
        return Vec::new();
    }
    (0..=(last - first) as i64).map(|k| (first + k as f64) * step).collect()
}

fn nice_step(raw: f64) -> f64 {
    let mag = 10f64.powf(raw.max(1e-9).log10().floor());
    let f = raw / mag;
    mag * if f < 1.5 {
        1.0
    } else if f < 3.5 {
        2.0
    } else if f < 7.5 {
        5.0
    } else {
        10.0
    }
}

fn fmt_tick(t: f64) -> String {
    let t = if t.abs() < 1e-9 { 0.0 } else { t };
    if (t - t.round()).abs() < 1e-9 { format!("{}", t.round()) } else { format!("{t:.1}") }
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plot_is_well_formed() {
        let mut p = Plot::chart([0.0, -1.0], [60.0, 1.0], 800.0, 300.0, ["t (s)", "heading (°)"]);
        p.polyline(&[[0.0, 0.0], [60.0, 0.5]], "red", 1.0, false);
        assert!(p.finish("c").contains("heading (°)"));
        let mut p = Plot::new([0.0, 0.0], [10.0, 5.0], 800.0);
        p.line([0.0, 0.0], [10.0, 5.0], "black", 2.0);
        p.legend("walls <true>", "black", Mark::Line(2.0));
        let s = p.finish("t & t");
        assert!(s.starts_with("<svg") && s.trim_end().ends_with("</svg>"));
        assert!(s.contains("walls &lt;true&gt;") && s.contains("t &amp; t"));
        assert_eq!(nice_step(1.3), 1.0);
        assert_eq!(nice_step(2.6), 2.0);
        assert_eq!(nice_step(0.06), 0.05);
    }

    #[test]
    fn legend_swatches_look_like_their_data() {
        let mut p = Plot::new([0.0, 0.0], [10.0, 5.0], 800.0);
        p.legend("odometry", "#1f77b4", Mark::Dashed(1.5));
        p.legend("truth", "#98df8a", Mark::Line(7.0));
        p.legend("break-points", "#d62728", Mark::Ring);
        p.legend("sensor", "#000", Mark::Sensor);
        let s = p.finish("legend");
        let dashed = s.lines().find(|l| l.contains("#1f77b4")).unwrap();
        assert!(dashed.contains("stroke-dasharray"), "{dashed}");
        let thick = s.lines().find(|l| l.contains("#98df8a")).unwrap();
        assert!(thick.contains(r#"stroke-width="7.0""#), "{thick}");
        let ring = s.lines().find(|l| l.contains("#d62728")).unwrap();
        assert!(ring.contains(r#"fill="none""#), "{ring}");
        assert!(s.lines().any(|l| l.starts_with("<polygon") && l.contains("#000")));
    }

    #[test]
    fn huge_coordinates_end_with_bounded_ticks() {
        assert_eq!(ticks(0.0, 10.0, 2.0), [0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        assert!(ticks(1e16, 1e16 + 8.0, 1.0).len() <= 100, "no endless loop at 1e16");
        assert!(ticks(-1e308, 1e308, 1e307).len() <= 100);
        let p = Plot::new([1e16, 1e16], [1e16 + 10.0, 1e16 + 10.0], 400.0);
        assert!(p.finish("far").contains("</svg>"));
        let p = Plot::new([-1e308, -1e308], [1e308, 1e308], 400.0);
        assert!(p.finish("overflow").contains("</svg>"));
    }

    #[test]
    fn degenerate_bounds_do_not_divide_by_zero() {
        let p = Plot::new([1.0, 1.0], [1.0, 1.0], 400.0);
        assert!(p.finish("x").contains("<svg"));
    }
}
