//! PNG plots with [`plotters`] that render the same on any machine.
//!
//! Text is drawn with a subset of DejaVu Sans embedded in the binary (`driver/assets/DejaVuSans-subset.ttf`:
//! printable ASCII plus ° · × – — − τ ² ³ ₀…₉; licence beside it), registered with plotters' `ab_glyph`
//! backend as the `sans-serif` family. So no system font, fontconfig or freetype is needed at build or run
//! time, and a fresh CI machine draws the same picture. Use `("sans-serif", size)` fonts only.
use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

use crate::error::{LbdemError, Result};

/// The embedded font (see the module documentation).
const FONT: &[u8] = include_bytes!("../../assets/DejaVuSans-subset.ttf");

/// Register the embedded font as `sans-serif` (idempotent; call before drawing any text).
pub fn register_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        for style in [FontStyle::Normal, FontStyle::Bold] {
            // The font is a fixed, known-good file: failing to parse it is a build defect, and text would
            // then fail to draw with a clear plotters error rather than a panic here.
            let _ = register_font("sans-serif", style, FONT);
        }
    });
}

/// Point marker of a series.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// Filled circle.
    Circle,
    /// Hollow triangle.
    Triangle,
    /// Filled square.
    Square,
}

/// One series of a log–log plot: a polyline through labelled points.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// Colour (RGB).
    pub color: (u8, u8, u8),
    /// Dashed instead of solid line.
    pub dashed: bool,
    /// Marker at every point.
    pub marker: Marker,
    /// (x, y, label) in drawing order; points with a non-positive or non-finite coordinate are skipped.
    pub points: Vec<(f64, f64, String)>,
    /// Pixel offset of the point labels' top-left corner from their point (e.g. (6, -18) above right,
    /// (6, 4) below right), so that the labels of series that share points stay apart.
    pub label_offset: (i32, i32),
}

/// Axes and size of a log–log plot.
#[derive(Clone, Debug)]
pub struct LogLogPlot {
    /// Caption above the chart.
    pub title: String,
    /// x-axis description.
    pub x_label: String,
    /// y-axis description.
    pub y_label: String,
    /// Width and height in pixels.
    pub size: (u32, u32),
    /// Where the legend goes.
    pub legend: SeriesLabelPosition,
    /// Horizontal reference lines (y, label), drawn light grey and dashed, e.g. error budgets.
    pub h_lines: Vec<(f64, String)>,
}

fn plot_error(path: &Path, e: impl std::fmt::Display) -> LbdemError {
    LbdemError::Write {
        path: path.display().to_string(),
        source: std::io::Error::other(format!("plotting failed: {e}")),
    }
}

/// Log-scale range covering `values` with a margin of a fraction of a decade on both sides.
fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if !lo.is_finite() || hi <= 0.0 {
        return 0.1..10.0;
    }
    let (lo, hi) = if hi / lo < 10.0 {
        let mid = (lo * hi).sqrt();
        (mid / 4.0, mid * 4.0)
    } else {
        (lo, hi)
    };
    lo / 10f64.powf(0.15)..hi * 10f64.powf(0.25)
}

/// Draw a PNG file atomically: `draw` renders it onto the temporary name it is given (`STEM.tmp.png`, in the
/// same directory: the bitmap encoder picks the format from the extension, so ".png" stays at the end), which
/// is then renamed onto `path` and recorded in the manifest ([`crate::output::record_output`]). A reader never
/// sees a half-drawn figure; a temporary file left by an interrupted drawing is recognised by `--overwrite`
/// (`STEM.tmp.png` of a listed `STEM.png`), and one left by a failed drawing is removed.
pub fn atomic_png<E: From<LbdemError>>(
    path: &Path,
    draw: impl FnOnce(&Path) -> std::result::Result<(), E>,
) -> std::result::Result<(), E> {
    let tmp = path.with_extension("tmp.png");
    if let Err(e) = draw(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    std::fs::rename(&tmp, path).map_err(|e| LbdemError::Write {
        path: path.display().to_string(),
        source: e,
    })?;
    crate::output::record_output(path)?;
    Ok(())
}

/// Draw `series` on log–log axes into the PNG file `path` (written to a temporary name and renamed:
/// [`atomic_png`]).
pub fn loglog_png(path: &Path, plot: &LogLogPlot, series: &[Series]) -> Result<()> {
    atomic_png(path, |tmp| loglog_draw(tmp, path, plot, series))
}

/// [`loglog_png`]'s drawing onto `tmp` (errors name `path`).
fn loglog_draw(tmp: &Path, path: &Path, plot: &LogLogPlot, series: &[Series]) -> Result<()> {
    register_fonts();
    let ok = |x: f64, y: f64| x.is_finite() && y.is_finite() && x > 0.0 && y > 0.0;
    let pts = || {
        series
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|p| ok(p.0, p.1))
    };
    let xr = log_range(pts().map(|p| p.0));
    let yr = log_range(
        pts()
            .map(|p| p.1)
            .chain(plot.h_lines.iter().map(|l| l.0).filter(|y| *y > 0.0)),
    );
    {
        let root = BitMapBackend::new(tmp, plot.size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_error(path, e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&plot.title, ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(72)
            .build_cartesian_2d(xr.clone().log_scale(), yr.log_scale())
            .map_err(|e| plot_error(path, e))?;
        chart
            .configure_mesh()
            .x_desc(plot.x_label.as_str())
            .y_desc(plot.y_label.as_str())
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 17))
            .light_line_style(RGBColor(235, 235, 235))
            .bold_line_style(RGBColor(200, 200, 200))
            .x_label_formatter(&|v| format_tick(*v))
            .y_label_formatter(&|v| format_tick(*v))
            .draw()
            .map_err(|e| plot_error(path, e))?;
        let grey = RGBColor(120, 120, 120);
        for (y, label) in &plot.h_lines {
            if !(*y > 0.0 && y.is_finite()) {
                continue;
            }
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(xr.start, *y), (xr.end, *y)],
                    4,
                    4,
                    grey.stroke_width(1),
                ))
                .map_err(|e| plot_error(path, e))?;
            let style = ("sans-serif", 13).into_font().color(&grey);
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at((xr.start, *y)) + Text::new(label.clone(), (4, -16), style),
                ))
                .map_err(|e| plot_error(path, e))?;
        }
        for s in series {
            let color = RGBColor(s.color.0, s.color.1, s.color.2);
            let line = color.stroke_width(2);
            let data: Vec<(f64, f64)> = s
                .points
                .iter()
                .filter(|p| ok(p.0, p.1))
                .map(|p| (p.0, p.1))
                .collect();
            let anno = if s.dashed {
                chart
                    .draw_series(DashedLineSeries::new(data.clone(), 8, 5, line))
                    .map_err(|e| plot_error(path, e))?
            } else {
                chart
                    .draw_series(LineSeries::new(data.clone(), line))
                    .map_err(|e| plot_error(path, e))?
            };
            let dashed = s.dashed;
            let seg = move |x: i32, y: i32| {
                if dashed {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (9, 0)], line)
                        + PathElement::new(vec![(14, 0), (22, 0)], line)
                } else {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (11, 0)], line)
                        + PathElement::new(vec![(11, 0), (22, 0)], line)
                }
            };
            let anno = anno.label(s.name.as_str());
            // One arm per marker type: the element types differ, so each needs its own closure and series.
            let drawn = match s.marker {
                Marker::Circle => {
                    anno.legend(move |(x, y)| seg(x, y) + Circle::new((11, 0), 4, color.filled()));
                    chart.draw_series(data.iter().map(|&p| Circle::new(p, 4, color.filled())))
                }
                Marker::Triangle => {
                    anno.legend(move |(x, y)| {
                        seg(x, y) + TriangleMarker::new((11, 0), 6, color.stroke_width(2))
                    });
                    chart.draw_series(
                        data.iter()
                            .map(|&p| TriangleMarker::new(p, 6, color.stroke_width(2))),
                    )
                }
                Marker::Square => {
                    let sq = move |x: i32, y: i32| {
                        Rectangle::new([(x - 4, y - 4), (x + 4, y + 4)], color.filled())
                    };
                    anno.legend(move |(x, y)| seg(x, y) + sq(11, 0));
                    chart.draw_series(data.iter().map(|&p| EmptyElement::at(p) + sq(0, 0)))
                }
            };
            drawn.map_err(|e| plot_error(path, e))?;
            let text = ("sans-serif", 13).into_font().color(&color);
            chart
                .draw_series(s.points.iter().filter(|p| ok(p.0, p.1)).map(|(x, y, l)| {
                    EmptyElement::at((*x, *y)) + Text::new(l.clone(), s.label_offset, text.clone())
                }))
                .map_err(|e| plot_error(path, e))?;
        }
        chart
            .configure_series_labels()
            .position(plot.legend.clone())
            .label_font(("sans-serif", 14))
            .background_style(WHITE.mix(0.9))
            .border_style(RGBColor(160, 160, 160))
            .draw()
            .map_err(|e| plot_error(path, e))?;
        root.present().map_err(|e| plot_error(path, e))?;
    }
    Ok(())
}

/// Tick label of a log axis: plain decimals between 1e-3 and 1e4, scientific notation outside.
fn format_tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if (1e-3..1e4).contains(&a) {
        let s = format!("{v:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{v:.0e}")
    }
}
