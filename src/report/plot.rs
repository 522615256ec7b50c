//! The work-precision plot: largest error against run time, log-log, one
//! line per method (SVG through plotters' SVG backend, which needs no
//! system library; text metrics are plotters' built-in estimate, so no
//! font is read either).

use super::{Method, Outcome, Report};
use plotters::prelude::*;

/// Errors at or below this are drawn at it: an error of exactly 0 (the
/// run agrees with the truth to the last bit) has no place on a log axis.
const ERROR_FLOOR: f64 = 1e-17;

/// One colour per method, fixed so that plots of different models compare.
fn colour(method: Method) -> RGBColor {
    match method {
        Method::Field => RGBColor(0xd6, 0x27, 0x28),
        Method::Explicit => RGBColor(0x1f, 0x77, 0xb4),
        Method::Stiff => RGBColor(0x2c, 0xa0, 0x2c),
    }
}

/// The points `(time, error)` of `method`, in ladder order.
fn points(report: &Report, method: Method) -> Vec<(f64, f64)> {
    report
        .measurements
        .iter()
        .filter(|m| m.method == method)
        .filter_map(|m| match &m.outcome {
            Outcome::Solved {
                summary,
                error: Some(error),
            } if summary.wall_time_s > 0.0 && error.is_finite() => {
                Some((summary.wall_time_s, error.max(ERROR_FLOOR)))
            }
            _ => None,
        })
        .collect()
}

/// `[lo/2, hi·2]` around the values (a decade around one value).
fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values.fold((f64::INFINITY, 0.0_f64), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if lo.is_finite() && hi > 0.0 {
        lo / 2.0..hi * 2.0
    } else {
        1e-6..1.0
    }
}

/// The SVG text of the plot: one line (a `<polyline>`) with its points
/// marked for each method that solved at least once; methods that never
/// solved appear in the legend as "(failed)".
pub fn work_precision_svg(report: &Report) -> Result<String, String> {
    let series: Vec<(Method, Vec<(f64, f64)>)> = Method::ALL
        .iter()
        .map(|&m| (m, points(report, m)))
        .collect();
    let all = || series.iter().flat_map(|(_, p)| p.iter().copied());
    let x_range = log_range(all().map(|(t, _)| t));
    let y_range = log_range(all().map(|(_, e)| e));
    let mut svg = String::new();
    draw(&mut svg, report, &series, x_range, y_range).map_err(|e| e.to_string())?;
    Ok(svg)
}

fn draw(
    svg: &mut String,
    report: &Report,
    series: &[(Method, Vec<(f64, f64)>)],
    x_range: std::ops::Range<f64>,
    y_range: std::ops::Range<f64>,
) -> Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::with_string(svg, (800, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let title = format!("work-precision: {}", report.model);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d(x_range.log_scale(), y_range.log_scale())?;
    chart
        .configure_mesh()
        .x_desc(format!("run time [s] (smallest of {} solves)", report.runs))
        .y_desc("largest error over the samples")
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 15))
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()?;
    for (method, points) in series {
        let colour = colour(*method);
        if points.is_empty() {
            // Keep the method in the legend without drawing a line.
            chart
                .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
                .label(format!("{} (failed)", method.label()))
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 4), (x + 16, y + 4)], colour.filled())
                });
            continue;
        }
        chart
            .draw_series(LineSeries::new(
                points.iter().copied(),
                colour.stroke_width(2),
            ))?
            .label(method.label())
            .legend(move |(x, y)| Rectangle::new([(x, y - 4), (x + 16, y + 4)], colour.filled()));
        chart.draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 15))
        .draw()?;
    root.present()?;
    Ok(())
}
