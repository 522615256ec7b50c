//! `--plot FILE.svg`: the columns against time (or one against another with
//! `--phase X,Y`) as a small self-contained SVG — axes with round ticks, a
//! legend, one polyline per column.

use std::fmt::Write as _;

/// What to draw.
#[derive(Clone, Debug, PartialEq)]
pub struct PlotRequest {
    pub file: String,
    /// `(x, y)` column names for a phase plot.
    pub phase: Option<(String, String)>,
}

const WIDTH: f64 = 860.0;
const HEIGHT: f64 = 520.0;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 180.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 60.0;
const COLOURS: [&str; 10] = [
    "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
    "#bcbd22", "#17becf",
];

/// Round tick values covering `[lo, hi]`.
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let span = hi - lo;
    if !(span > 0.0) || !span.is_finite() {
        return vec![lo];
    }
    let raw = span / 6.0;
    let magnitude = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * magnitude)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * magnitude);
    let start = (lo / step).ceil() * step;
    let mut out = Vec::new();
    let mut v = start;
    while v <= hi + 1e-9 * step && out.len() < 20 {
        out.push(if v.abs() < 1e-12 * step { 0.0 } else { v });
        v += step;
    }
    out
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo <= 1e-300 {
        let pad = lo.abs().max(1.0) * 0.5;
        return (lo - pad, hi + pad);
    }
    let pad = 0.04 * (hi - lo);
    (lo - pad, hi + pad)
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The SVG of `rows` (`(t, columns)`, the columns named `names[1..]`,
/// `names[0] = "t"`).
pub fn render(
    request: &PlotRequest,
    title: &str,
    names: &[&str],
    rows: &[(f64, Vec<f64>)],
) -> String {
    let column = |name: &str| names.iter().position(|n| *n == name);
    let value = |row: &(f64, Vec<f64>), c: usize| if c == 0 { row.0 } else { row.1[c - 1] };
    let series: Vec<(usize, usize)> = match &request.phase {
        Some((x, y)) => match (column(x), column(y)) {
            (Some(cx), Some(cy)) => vec![(cx, cy)],
            _ => Vec::new(),
        },
        None => (1..names.len()).map(|c| (0, c)).collect(),
    };
    let (x_lo, x_hi) = range(
        series
            .iter()
            .flat_map(|&(cx, _)| rows.iter().map(move |r| value(r, cx))),
    );
    let (y_lo, y_hi) = range(
        series
            .iter()
            .flat_map(|&(_, cy)| rows.iter().map(move |r| value(r, cy))),
    );
    let plot_w = WIDTH - LEFT - RIGHT;
    let plot_h = HEIGHT - TOP - BOTTOM;
    let sx = |v: f64| LEFT + (v - x_lo) / (x_hi - x_lo) * plot_w;
    let sy = |v: f64| TOP + plot_h - (v - y_lo) / (y_hi - y_lo) * plot_h;
    let mut svg = String::new();
    let _ = write!(
        svg,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{WIDTH}\" height=\"{HEIGHT}\" \
         viewBox=\"0 0 {WIDTH} {HEIGHT}\" font-family=\"sans-serif\" font-size=\"13\">\n\
         <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    );
    let _ = writeln!(
        svg,
        "<text x=\"{}\" y=\"24\" text-anchor=\"middle\" font-size=\"16\">{}</text>",
        LEFT + plot_w / 2.0,
        escape(title)
    );
    for t in ticks(x_lo, x_hi) {
        let x = sx(t);
        let _ = writeln!(
            svg,
            "<line x1=\"{x:.1}\" y1=\"{TOP}\" x2=\"{x:.1}\" y2=\"{:.1}\" stroke=\"#e6e6e6\"/>\
             <text x=\"{x:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>",
            TOP + plot_h,
            TOP + plot_h + 18.0,
            format_tick(t)
        );
    }
    for t in ticks(y_lo, y_hi) {
        let y = sy(t);
        let _ = writeln!(
            svg,
            "<line x1=\"{LEFT}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\" stroke=\"#e6e6e6\"/>\
             <text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
            LEFT + plot_w,
            LEFT - 6.0,
            y + 4.0,
            format_tick(t)
        );
    }
    let _ = writeln!(
        svg,
        "<rect x=\"{LEFT}\" y=\"{TOP}\" width=\"{plot_w}\" height=\"{plot_h}\" fill=\"none\" \
         stroke=\"#333\"/>"
    );
    let x_label = series.first().map_or("t", |&(cx, _)| names[cx]);
    let _ = writeln!(
        svg,
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>",
        LEFT + plot_w / 2.0,
        HEIGHT - 16.0,
        escape(x_label)
    );
    for (i, &(cx, cy)) in series.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let mut points = String::new();
        for row in rows {
            let (x, y) = (value(row, cx), value(row, cy));
            if x.is_finite() && y.is_finite() {
                let _ = write!(points, "{:.2},{:.2} ", sx(x), sy(y));
            }
        }
        let _ = writeln!(
            svg,
            "<polyline fill=\"none\" stroke=\"{colour}\" stroke-width=\"1.6\" points=\"{}\"/>",
            points.trim_end()
        );
        let ly = TOP + 10.0 + 20.0 * i as f64;
        let lx = LEFT + plot_w + 16.0;
        let _ = writeln!(
            svg,
            "<line x1=\"{lx}\" y1=\"{ly}\" x2=\"{}\" y2=\"{ly}\" stroke=\"{colour}\" \
             stroke-width=\"2\"/><text x=\"{}\" y=\"{}\">{}</text>",
            lx + 22.0,
            lx + 28.0,
            ly + 4.0,
            escape(names[cy])
        );
    }
    svg.push_str("</svg>\n");
    svg
}

fn format_tick(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || (1e-3..1e5).contains(&a) {
        let s = format!("{v:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s == "-0" {
            "0".to_string()
        } else {
            s.to_string()
        }
    } else {
        format!("{v:.2e}")
    }
}

/// Writes the plot to `request.file`.
pub fn write_plot(
    request: &PlotRequest,
    title: &str,
    names: &[&str],
    rows: &[(f64, Vec<f64>)],
) -> std::io::Result<()> {
    std::fs::write(&request.file, render(request, title, names, rows))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_cover_the_range() {
        assert_eq!(ticks(0.0, 10.0), vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        let t = ticks(-0.33, 0.71);
        assert!(t.first().unwrap() >= &-0.33 && t.last().unwrap() <= &0.71);
    }

    #[test]
    fn renders_every_series_and_a_phase_plot() {
        let rows: Vec<(f64, Vec<f64>)> = (0..50)
            .map(|i| {
                let t = i as f64 * 0.1;
                (t, vec![t.sin(), t.cos()])
            })
            .collect();
        let names = ["t", "x", "x'"];
        let svg = render(
            &PlotRequest {
                file: String::new(),
                phase: None,
            },
            "m",
            &names,
            &rows,
        );
        assert_eq!(svg.matches("<polyline").count(), 2);
        let phase = PlotRequest {
            file: String::new(),
            phase: Some(("x".into(), "x'".into())),
        };
        let svg = render(&phase, "m", &names, &rows);
        assert_eq!(svg.matches("<polyline").count(), 1);
    }
}
