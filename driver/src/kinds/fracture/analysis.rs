//! Fracture analysis of broken bonds: one row per break, single-linkage clustering of breaks into fractures,
//! principal-axis trace orientation of each fracture, and axial (direction-free) orientation statistics.
//!
//! Angles are in degrees in [0, 180), measured from +x (the sample's long axis, the σ₃ direction). A bond
//! normal is the line joining the two grains; the crack it opens lies perpendicular to it. A fracture
//! perpendicular to σ₃ therefore has a trace at 90° and its broken bonds have normals near 0°.
use lbdem_kernels::dem::bond::BreakMode;
use serde::Serialize;

use crate::engine::dem::world::BreakRecord;

/// One broken bond.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct BreakRow {
    /// Time of the break since the drop.
    pub time: f64,
    /// Position of the bond.
    pub position: [f64; 2],
    /// Bond-normal angle in [0, 180).
    pub normal_deg: f64,
    /// Crack-plane angle (normal + 90°) in [0, 180).
    pub crack_deg: f64,
    /// 0 tension, 1 shear, 2 compression.
    pub mode: u8,
    /// Load at failure.
    pub load: f64,
}

/// An angle folded into [0, 180).
pub fn axial_deg(deg: f64) -> f64 {
    let a = deg.rem_euclid(180.0);
    if a >= 180.0 {
        0.0
    } else {
        a
    }
}

impl BreakRow {
    /// From a DEM break record, with `drop_step` the DEM step count at the drop and `dt` its step.
    pub fn from_record(b: &BreakRecord<f64>, drop_step: u64, dt: f64) -> Self {
        let normal = axial_deg(b.orientation.to_degrees());
        Self {
            time: b.step.saturating_sub(drop_step) as f64 * dt,
            position: b.position.into(),
            normal_deg: normal,
            crack_deg: axial_deg(normal + 90.0),
            mode: match b.mode {
                BreakMode::Tension => 0,
                BreakMode::Shear => 1,
                BreakMode::Compression => 2,
            },
            load: b.load,
        }
    }
}

/// Broken bonds as CSV.
pub fn breaks_csv(rows: &[BreakRow]) -> String {
    let mut s = String::from("time,x,y,normal_deg,crack_deg,mode,load\n");
    for r in rows {
        let mode = ["tension", "shear", "compression"][r.mode.min(2) as usize];
        s += &format!(
            "{:.9e},{:.9e},{:.9e},{:.4},{:.4},{mode},{:.9e}\n",
            r.time, r.position[0], r.position[1], r.normal_deg, r.crack_deg, r.load
        );
    }
    s
}

/// Broken bonds grouped into one fracture.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct Fracture {
    /// Broken bonds in it.
    pub breaks: usize,
    /// Centroid.
    pub center: [f64; 2],
    /// Principal-axis (trace) angle in [0, 180).
    pub trace_deg: f64,
    /// Extent along the trace.
    pub length: f64,
    /// Spread across the trace over spread along it (0: a line, 1: a round cloud).
    pub elongation: f64,
    /// Time of its first break.
    pub first_break: f64,
}

/// Single-linkage clusters of breaks closer than `link`, kept when they hold at least `min_breaks`, largest
/// first (ties by centroid x then y, so the order is deterministic).
pub fn cluster_fractures(rows: &[BreakRow], link: f64, min_breaks: usize) -> Vec<Fracture> {
    let n = rows.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let l2 = link * link;
    for i in 0..n {
        for j in (i + 1)..n {
            let dx = rows[i].position[0] - rows[j].position[0];
            let dy = rows[i].position[1] - rows[j].position[1];
            if dx * dx + dy * dy <= l2 {
                let (a, b) = (find(&mut parent, i), find(&mut parent, j));
                if a != b {
                    parent[a.max(b)] = a.min(b);
                }
            }
        }
    }
    let mut groups: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for i in 0..n {
        let r = find(&mut parent, i);
        groups.entry(r).or_default().push(i);
    }
    let mut out: Vec<Fracture> = groups
        .values()
        .filter(|g| g.len() >= min_breaks.max(1))
        .map(|g| {
            let m = g.len() as f64;
            let cx = g.iter().map(|&i| rows[i].position[0]).sum::<f64>() / m;
            let cy = g.iter().map(|&i| rows[i].position[1]).sum::<f64>() / m;
            let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
            for &i in g {
                let dx = rows[i].position[0] - cx;
                let dy = rows[i].position[1] - cy;
                sxx += dx * dx;
                syy += dy * dy;
                sxy += dx * dy;
            }
            // Principal axis of the 2×2 covariance.
            let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
            let (c, s) = (theta.cos(), theta.sin());
            let (mut lo, mut hi, mut across) = (f64::INFINITY, f64::NEG_INFINITY, 0.0);
            for &i in g {
                let dx = rows[i].position[0] - cx;
                let dy = rows[i].position[1] - cy;
                let along = dx * c + dy * s;
                lo = lo.min(along);
                hi = hi.max(along);
                across += (-dx * s + dy * c).powi(2);
            }
            let along_var = (sxx + syy - across).max(0.0);
            Fracture {
                breaks: g.len(),
                center: [cx, cy],
                trace_deg: axial_deg(theta.to_degrees()),
                length: hi - lo,
                elongation: if along_var > 0.0 {
                    (across / along_var).sqrt()
                } else {
                    1.0
                },
                first_break: g
                    .iter()
                    .map(|&i| rows[i].time)
                    .fold(f64::INFINITY, f64::min),
            }
        })
        .collect();
    out.sort_by(|a, b| {
        b.breaks
            .cmp(&a.breaks)
            .then(a.center[0].total_cmp(&b.center[0]))
            .then(a.center[1].total_cmp(&b.center[1]))
    });
    out
}

/// Fractures as CSV.
pub fn fractures_csv(f: &[Fracture]) -> String {
    let mut s = String::from("breaks,center_x,center_y,trace_deg,length,elongation,first_break\n");
    for x in f {
        s += &format!(
            "{},{:.6e},{:.6e},{:.3},{:.6e},{:.4},{:.6e}\n",
            x.breaks, x.center[0], x.center[1], x.trace_deg, x.length, x.elongation, x.first_break
        );
    }
    s
}

/// Axial mean of angles (degrees, weights) by doubled-angle averaging: (mean in [0, 180), resultant length R
/// in [0, 1]; R = 1 when all agree, 0 for a uniform spread).
pub fn axial_mean(angles: &[(f64, f64)]) -> (f64, f64) {
    let (mut c, mut s, mut w) = (0.0, 0.0, 0.0);
    for &(a, weight) in angles {
        let t = 2.0 * a.to_radians();
        c += weight * t.cos();
        s += weight * t.sin();
        w += weight;
    }
    if w <= 0.0 {
        return (f64::NAN, 0.0);
    }
    (
        axial_deg(0.5 * s.atan2(c).to_degrees()),
        (c * c + s * s).sqrt() / w,
    )
}

/// Smallest angle between an axial angle and the vertical (90°), in [0, 90].
pub fn deviation_from_vertical(deg: f64) -> f64 {
    (axial_deg(deg) - 90.0).abs()
}

/// Orientation statistics for the summary: the crack planes of all breaks, and the fracture traces weighted by
/// length × (1 − elongation) (a round cloud of breaks has no trace direction), each as mean angle, resultant
/// length and deviation from perpendicular to σ₃ (vertical).
pub fn orientation_summary(rows: &[BreakRow], fractures: &[Fracture]) -> serde_json::Value {
    let cracks: Vec<(f64, f64)> = rows.iter().map(|r| (r.crack_deg, 1.0)).collect();
    let (crack_mean, crack_r) = axial_mean(&cracks);
    let traces: Vec<(f64, f64)> = fractures
        .iter()
        .map(|f| (f.trace_deg, f.length * (1.0 - f.elongation).max(0.0)))
        .collect();
    let (trace_mean, trace_r) = axial_mean(&traces);
    let tension = rows.iter().filter(|r| r.mode == 0).count();
    serde_json::json!({
        "breaks": rows.len(),
        "tensile_breaks": tension,
        "crack_plane_mean_deg": crack_mean,
        "crack_plane_resultant": crack_r,
        "crack_plane_deviation_from_perpendicular_to_sigma3_deg": deviation_from_vertical(crack_mean),
        "fracture_trace_mean_deg": trace_mean,
        "fracture_trace_resultant": trace_r,
        "fracture_trace_deviation_from_perpendicular_to_sigma3_deg": deviation_from_vertical(trace_mean),
    })
}

/// A time × distance matrix as CSV: first row the distances, then one row per time.
pub fn matrix_csv(times: &[f64], xs: &[f64], rows: &[Vec<f64>]) -> String {
    let mut s = String::from("time");
    for x in xs {
        s += &format!(",{x:.6e}");
    }
    s.push('\n');
    for (t, r) in times.iter().zip(rows) {
        s += &format!("{t:.6e}");
        for v in r {
            s += &format!(",{v:.6e}");
        }
        s.push('\n');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(x: f64, y: f64, normal: f64) -> BreakRow {
        BreakRow {
            time: 0.0,
            position: [x, y],
            normal_deg: normal,
            crack_deg: axial_deg(normal + 90.0),
            mode: 0,
            load: 1.0,
        }
    }

    #[test]
    fn a_vertical_line_of_breaks_is_one_vertical_fracture() {
        let mut rows: Vec<BreakRow> = (0..10).map(|k| row(1.0, 0.1 * k as f64, 0.0)).collect();
        // A far-away pair below the size threshold.
        rows.push(row(5.0, 0.0, 45.0));
        rows.push(row(5.05, 0.0, 45.0));
        let f = cluster_fractures(&rows, 0.15, 3);
        assert_eq!(f.len(), 1);
        assert_eq!(f[0].breaks, 10);
        assert!((f[0].trace_deg - 90.0).abs() < 1e-9, "{}", f[0].trace_deg);
        assert!((f[0].length - 0.9).abs() < 1e-12);
        assert!(f[0].elongation < 1e-9);
        let s = orientation_summary(&rows[..10], &f);
        assert!(
            s["fracture_trace_deviation_from_perpendicular_to_sigma3_deg"]
                .as_f64()
                .unwrap()
                < 1e-9
        );
    }

    #[test]
    fn axial_mean_treats_opposite_directions_as_one_axis() {
        // 10° and 170° are 20° apart as axes; their axial mean is 0°, not 90°.
        let (m, r) = axial_mean(&[(10.0, 1.0), (170.0, 1.0)]);
        assert!(m.min(180.0 - m) < 1e-9, "{m}");
        assert!((r - 20f64.to_radians().cos()).abs() < 1e-12);
        // Uniform spread: R ≈ 0.
        let spread: Vec<(f64, f64)> = (0..36).map(|k| (5.0 * k as f64, 1.0)).collect();
        assert!(axial_mean(&spread).1 < 1e-12);
        assert_eq!(deviation_from_vertical(100.0), 10.0);
        assert_eq!(deviation_from_vertical(0.0), 90.0);
    }
}
