//! PNG figures drawn by the fracture run itself (plotters, bitmap backend): a snapshot of the grains coloured by
//! their fraction of broken bonds over the pore-pressure field (fig. 6.8), the grains coloured by speed (fig. 6.9), time–distance plots of pressure and
//! speed along the centre line (fig. 6.13–6.14), a rose diagram of crack-plane orientations (fig. 6.10/6.15) and
//! broken bonds against time for one or several runs. A figure that cannot be drawn (e.g. no font on the
//! machine) is reported as a warning by the caller; the run's data files do not depend on it.
//! Each figure is drawn to a temporary name and renamed ([`crate::output::plot::atomic_png`]): a reader never sees a
//! half-drawn PNG.
use std::error::Error;
use std::path::Path;

use plotters::prelude::*;

use super::analysis::BreakRow;
use crate::engine::dem::DemWorld;
use crate::output::vtk::Field;

/// Result of drawing a figure.
pub type FigureResult = std::result::Result<(), Box<dyn Error>>;

/// A perceptually ordered colour map (viridis anchors, linear between them); `t` is clamped to [0, 1].
pub fn colormap(t: f64) -> RGBColor {
    const ANCHORS: [(f64, f64, f64); 6] = [
        (68.0, 1.0, 84.0),
        (65.0, 68.0, 135.0),
        (42.0, 120.0, 142.0),
        (34.0, 168.0, 132.0),
        (122.0, 209.0, 81.0),
        (253.0, 231.0, 37.0),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = t * (ANCHORS.len() - 1) as f64;
    let k = (s.floor() as usize).min(ANCHORS.len() - 2);
    let f = s - k as f64;
    let (a, b) = (ANCHORS[k], ANCHORS[k + 1]);
    RGBColor(
        (a.0 + f * (b.0 - a.0)) as u8,
        (a.1 + f * (b.1 - a.1)) as u8,
        (a.2 + f * (b.2 - a.2)) as u8,
    )
}

/// Colour of a grain with broken-bond fraction `f`: light grey (intact) to red (all broken).
fn damage_colour(f: f64) -> RGBColor {
    let f = if f.is_finite() {
        f.clamp(0.0, 1.0)
    } else {
        0.0
    };
    RGBColor(
        (215.0 + 40.0 * f) as u8,
        (215.0 * (1.0 - f)) as u8,
        (215.0 * (1.0 - f)) as u8,
    )
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    if hi - lo <= 1e-300 {
        (lo - 0.5, hi + 0.5)
    } else {
        (lo, hi)
    }
}

/// Grains (ellipses as polygons) coloured by broken-bond fraction over the pressure field, broken bonds as
/// short black crack segments, at model time `time`.
pub fn snapshot_png(
    path: &Path,
    w: &DemWorld<f64>,
    broken_fraction: &[f64],
    field: Option<&Field>,
    time: f64,
) -> FigureResult {
    crate::output::plot::atomic_png(path, |path: &Path| -> FigureResult {
        let (lo, hi) = w.bounds();
        let (x0, x1, y0, y1) = match field {
            Some(f) => (
                f.origin[0],
                f.origin[0] + (f.nodes[0] - 1) as f64 * f.spacing,
                f.origin[1] - 0.5 * f.spacing,
                f.origin[1] + (f.nodes[1] as f64 - 0.5) * f.spacing,
            ),
            None => (lo[0], hi[0], lo[1], hi[1]),
        };
        let width = 1400u32;
        let plot_h = ((width - 120) as f64 * (y1 - y0) / (x1 - x0)).clamp(100.0, 2000.0) as u32;
        crate::output::plot::register_fonts();
        let root = BitMapBackend::new(path, (width, plot_h + 90)).into_drawing_area();
        root.fill(&WHITE)?;
        // Colour range over the pore fluid only (the fluid inside grains takes no part in the flow).
        let (plo, phi) = field
            .map(|f| {
                range(
                    f.pressure
                        .iter()
                        .zip(&f.solid_fraction)
                        .filter(|(_, e)| **e < 0.5)
                        .map(|(p, _)| *p),
                )
            })
            .unwrap_or((0.0, 1.0));
        let mut chart = ChartBuilder::on(&root)
        .caption(
            match field {
                Some(_) => format!(
                    "t = {time:.4}: grains coloured by broken bonds (grey intact, red all broken) over pore pressure {plo:.3e} (purple) .. {phi:.3e} (yellow)"
                ),
                None => format!("t = {time:.4}: grains coloured by broken bonds (grey intact, red all broken)"),
            },
            ("sans-serif", 16),
        )
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(50)
        .build_cartesian_2d(x0..x1, y0..y1)?;
        chart.configure_mesh().disable_mesh().draw()?;
        if let Some(f) = field {
            // Down-sample the field to about one cell per 2 pixels.
            let [nx, ny] = f.nodes;
            let step = ((nx as f64 / 700.0).ceil() as usize).max(1);
            let mut cells = Vec::new();
            for j in (0..ny).step_by(step) {
                for i in (0..nx).step_by(step) {
                    let p = f.pressure[j * nx + i];
                    let xa = f.origin[0] + (i as f64 - 0.5) * f.spacing;
                    let ya = f.origin[1] + (j as f64 - 0.5) * f.spacing;
                    let s = step as f64 * f.spacing;
                    cells.push(Rectangle::new(
                        [(xa, ya), (xa + s, ya + s)],
                        colormap((p - plo) / (phi - plo)).filled(),
                    ));
                }
            }
            chart.draw_series(cells)?;
        }
        let polygons = w.particles.iter().enumerate().map(|(k, p)| {
            let pts = outline(p, 20);
            Polygon::new(
                pts,
                damage_colour(broken_fraction.get(k).copied().unwrap_or(0.0)).filled(),
            )
        });
        chart.draw_series(polygons)?;
        // Broken bonds: a crack segment across each (perpendicular to the bond normal).
        let half = 0.5
            * w.particles
                .iter()
                .map(|p| p.shape.semi_axes().1)
                .fold(f64::INFINITY, f64::min);
        let cracks = w.breaks.iter().map(|b| {
            let t = b.orientation + std::f64::consts::FRAC_PI_2;
            let (dx, dy) = (half * t.cos(), half * t.sin());
            PathElement::new(
                vec![
                    (b.position[0] - dx, b.position[1] - dy),
                    (b.position[0] + dx, b.position[1] + dy),
                ],
                BLACK.stroke_width(2),
            )
        });
        chart.draw_series(cracks)?;
        root.present()?;
        Ok(())
    })
}

/// Grains (ellipses as polygons) coloured by their speed (fig. 6.9), viridis from 0 (purple) to the largest
/// speed (yellow), at model time `time`: what ParaView shows of `particles_NNNN.vtp` coloured by `speed`.
pub fn speed_png(path: &Path, w: &DemWorld<f64>, time: f64, velocity_unit: &str) -> FigureResult {
    crate::output::plot::atomic_png(path, |path: &Path| -> FigureResult {
        let (lo, hi) = w.bounds();
        let (x0, x1, y0, y1) = (lo[0], hi[0], lo[1], hi[1]);
        let width = 1400u32;
        let plot_h = ((width - 120) as f64 * (y1 - y0) / (x1 - x0)).clamp(100.0, 2000.0) as u32;
        crate::output::plot::register_fonts();
        let root = BitMapBackend::new(path, (width, plot_h + 90)).into_drawing_area();
        root.fill(&WHITE)?;
        let speed: Vec<f64> = w
            .particles
            .iter()
            .map(|p| p.velocity[0].hypot(p.velocity[1]))
            .collect();
        let vmax = speed
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max);
        let scale = if vmax > 0.0 { vmax } else { 1.0 };
        let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("t = {time:.4}: grains coloured by speed, 0 (purple) .. {vmax:.3e} {velocity_unit} (yellow)"),
            ("sans-serif", 16),
        )
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(50)
        .build_cartesian_2d(x0..x1, y0..y1)?;
        chart.configure_mesh().disable_mesh().draw()?;
        let polygons = w.particles.iter().zip(&speed).map(|(p, &v)| {
            let pts = outline(p, 24);
            Polygon::new(pts, colormap(v / scale).filled())
        });
        chart.draw_series(polygons)?;
        root.present()?;
        Ok(())
    })
}

/// A time × distance colour plot of `data[time][x]` (fig. 6.13–6.14), down-sampled to the pixel grid.
pub fn time_distance_png(
    path: &Path,
    times: &[f64],
    xs: &[f64],
    data: &[Vec<f64>],
    what: &str,
) -> FigureResult {
    crate::output::plot::atomic_png(path, |path: &Path| -> FigureResult {
        if times.len() < 2 || xs.len() < 2 {
            return Err("fewer than two records: nothing to plot".into());
        }
        crate::output::plot::register_fonts();
        let root = BitMapBackend::new(path, (1000, 700)).into_drawing_area();
        root.fill(&WHITE)?;
        let (vlo, vhi) = range(data.iter().flatten().copied());
        let (t0, t1) = (times[0], *times.last().unwrap_or(&1.0));
        let (x0, x1) = (xs[0], *xs.last().unwrap_or(&1.0));
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("{what} along the centre line: {vlo:.3e} (purple) .. {vhi:.3e} (yellow)"),
                ("sans-serif", 18),
            )
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, t0..t1)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("distance along the long axis")
            .y_desc("time since the drop")
            .draw()?;
        let rows = times.len().min(350);
        let cols = xs.len().min(450);
        let mut cells = Vec::with_capacity(rows * cols);
        for r in 0..rows {
            let ta = r * times.len() / rows;
            let tb = ((r + 1) * times.len() / rows).max(ta + 1);
            for c in 0..cols {
                let xa = c * xs.len() / cols;
                let xb = ((c + 1) * xs.len() / cols).max(xa + 1);
                let mut s = 0.0;
                let mut n = 0.0;
                for row in &data[ta..tb.min(data.len())] {
                    for v in &row[xa..xb.min(row.len())] {
                        if v.is_finite() {
                            s += v;
                            n += 1.0;
                        }
                    }
                }
                let v = if n > 0.0 { s / n } else { vlo };
                let ya = times[ta];
                let yb = if tb < times.len() { times[tb] } else { t1 };
                let xe = if xb < xs.len() { xs[xb] } else { x1 };
                cells.push(Rectangle::new(
                    [(xs[xa], ya), (xe, yb)],
                    colormap((v - vlo) / (vhi - vlo)).filled(),
                ));
            }
        }
        chart.draw_series(cells)?;
        root.present()?;
        Ok(())
    })
}

/// Rose diagram of crack-plane orientations (10° bins, mirrored: an axis has no sign), radius ∝ count.
pub fn rose_png(path: &Path, rows: &[BreakRow]) -> FigureResult {
    crate::output::plot::atomic_png(path, |path: &Path| -> FigureResult {
        crate::output::plot::register_fonts();
        let root = BitMapBackend::new(path, (700, 740)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut bins = [0usize; 18];
        for r in rows {
            let k = ((r.crack_deg / 10.0).floor() as usize).min(17);
            bins[k] += 1;
        }
        let max = bins.iter().copied().max().unwrap_or(0).max(1) as f64;
        let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "crack-plane orientations of {} broken bonds (0° = long axis = least stress; 90° = perpendicular to it)",
                rows.len()
            ),
            ("sans-serif", 15),
        )
        .margin(10)
        .build_cartesian_2d(-1.15f64..1.15, -1.15f64..1.15)?;
        for ring in [0.25, 0.5, 0.75, 1.0] {
            let pts: Vec<(f64, f64)> = (0..=72)
                .map(|m| {
                    let t = m as f64 * std::f64::consts::TAU / 72.0;
                    (ring * t.cos(), ring * t.sin())
                })
                .collect();
            chart.draw_series(std::iter::once(PathElement::new(
                pts,
                RGBColor(190, 190, 190),
            )))?;
        }
        for (k, &n) in bins.iter().enumerate() {
            let r = n as f64 / max;
            if r <= 0.0 {
                continue;
            }
            for base in [0.0, 180.0] {
                let a0 = (base + 10.0 * k as f64).to_radians();
                let a1 = (base + 10.0 * (k + 1) as f64).to_radians();
                let mut pts = vec![(0.0, 0.0)];
                for m in 0..=6 {
                    let t = a0 + (a1 - a0) * m as f64 / 6.0;
                    pts.push((r * t.cos(), r * t.sin()));
                }
                chart.draw_series(std::iter::once(Polygon::new(
                    pts,
                    RGBColor(200, 60, 50).mix(0.85).filled(),
                )))?;
            }
        }
        chart.draw_series([0.0f64, 90.0].iter().map(|&deg| {
            let t = deg.to_radians();
            PathElement::new(
                vec![
                    (-1.1 * t.cos(), -1.1 * t.sin()),
                    (1.1 * t.cos(), 1.1 * t.sin()),
                ],
                BLACK,
            )
        }))?;
        root.present()?;
        Ok(())
    })
}

/// Broken bonds against time for one or several runs, overlaid.
pub fn breaks_png(path: &Path, series: &[(String, Vec<(f64, f64)>)]) -> FigureResult {
    crate::output::plot::atomic_png(path, |path: &Path| -> FigureResult {
        crate::output::plot::register_fonts();
        let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
        root.fill(&WHITE)?;
        let t1 = series
            .iter()
            .flat_map(|s| s.1.iter().map(|p| p.0))
            .fold(0.0f64, f64::max)
            .max(1e-12);
        let n1 = series
            .iter()
            .flat_map(|s| s.1.iter().map(|p| p.1))
            .fold(0.0f64, f64::max)
            .max(1.0);
        let mut chart = ChartBuilder::on(&root)
            .caption("broken bonds against time", ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..t1, 0.0..1.05 * n1)?;
        chart
            .configure_mesh()
            .x_desc("time since the drop")
            .y_desc("broken bonds")
            .draw()?;
        for (k, (label, pts)) in series.iter().enumerate() {
            let colour = Palette99::pick(k).to_rgba();
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), colour.stroke_width(2)))?
                .label(label.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperLeft)
            .draw()?;
        root.present()?;
        Ok(())
    })
}

/// `n` points on the boundary of grain `p` (an ellipse of its semi-axes at its angle), for drawing.
fn outline(p: &lbdem_kernels::dem::shape::Particle<f64>, n: usize) -> Vec<(f64, f64)> {
    let (a, b) = p.shape.semi_axes();
    let (c, s) = (p.angle.cos(), p.angle.sin());
    (0..n)
        .map(|m| {
            let t = m as f64 * std::f64::consts::TAU / n as f64;
            let (u, v) = (a * t.cos(), b * t.sin());
            (p.position[0] + u * c - v * s, p.position[1] + u * s + v * c)
        })
        .collect()
}
