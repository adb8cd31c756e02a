//! Particle output as legacy ASCII VTK POLYDATA (`.vtk`, VTK file format 3.0), readable by ParaView/VisIt.
//!
//! One vertex per particle at its centre, with point data: `orientation` (radians, body x axis from +x),
//! `semi_axes` (a, b, 0), `velocity` (vx, vy, 0), `angular_velocity`, and `broken_bond_fraction` (broken /
//! total bonds of the particle, 0 without bonds). Glyph the ellipses with the semi-axes and orientation.
//! Units: those of the scene (cgs: cm, cm/s, rad/s).
use lbdem_kernels::dem::shape::Particle;
use lbdem_kernels::Real;

/// Render the particles as a legacy VTK POLYDATA document.
pub fn particles_vtk<T: Real>(
    title: &str,
    particles: &[Particle<T>],
    broken_bond_fraction: &[f64],
) -> String {
    use std::fmt::Write;
    let n = particles.len();
    let f = |x: T| x.to_f64_exact();
    let mut s = String::with_capacity(200 + n * 160);
    let title: String = title.chars().filter(|c| *c != '\n').take(200).collect();
    let _ = writeln!(
        s,
        "# vtk DataFile Version 3.0\n{title}\nASCII\nDATASET POLYDATA"
    );
    let _ = writeln!(s, "POINTS {n} double");
    for p in particles {
        let _ = writeln!(s, "{:.9e} {:.9e} 0", f(p.position[0]), f(p.position[1]));
    }
    let _ = writeln!(s, "VERTICES {n} {}", 2 * n);
    for i in 0..n {
        let _ = writeln!(s, "1 {i}");
    }
    let _ = writeln!(s, "POINT_DATA {n}");
    let _ = writeln!(s, "SCALARS orientation double 1\nLOOKUP_TABLE default");
    for p in particles {
        let _ = writeln!(s, "{:.9e}", f(p.angle));
    }
    let _ = writeln!(s, "VECTORS semi_axes double");
    for p in particles {
        let (a, b) = p.shape.semi_axes();
        let _ = writeln!(s, "{:.9e} {:.9e} 0", f(a), f(b));
    }
    let _ = writeln!(s, "VECTORS velocity double");
    for p in particles {
        let _ = writeln!(s, "{:.9e} {:.9e} 0", f(p.velocity[0]), f(p.velocity[1]));
    }
    let _ = writeln!(s, "SCALARS angular_velocity double 1\nLOOKUP_TABLE default");
    for p in particles {
        let _ = writeln!(s, "{:.9e}", f(p.angular_velocity));
    }
    let _ = writeln!(
        s,
        "SCALARS broken_bond_fraction double 1\nLOOKUP_TABLE default"
    );
    for i in 0..n {
        let _ = writeln!(
            s,
            "{:.6}",
            broken_bond_fraction.get(i).copied().unwrap_or(0.0)
        );
    }
    s
}

/// A parsed legacy VTK particle file (what [`particles_vtk`] writes): point coordinates and the named
/// point-data arrays (flattened). For tests and post-processing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParsedVtk {
    /// Points (x, y, z).
    pub points: Vec<[f64; 3]>,
    /// Vertex cells (point index of each).
    pub vertices: Vec<usize>,
    /// Point-data arrays by name, in file order: (name, components, values).
    pub arrays: Vec<(String, usize, Vec<f64>)>,
}

/// Parse the subset of legacy ASCII VTK POLYDATA written by [`particles_vtk`]; `None` on any mismatch
/// (wrong header, counts that do not add up, unparsable numbers).
pub fn parse_particles_vtk(text: &str) -> Option<ParsedVtk> {
    let mut lines = text.lines();
    if !lines.next()?.starts_with("# vtk DataFile Version") {
        return None;
    }
    lines.next()?;
    if lines.next()?.trim() != "ASCII" || lines.next()?.trim() != "DATASET POLYDATA" {
        return None;
    }
    let nums = |l: &str| -> Option<Vec<f64>> {
        l.split_whitespace()
            .map(|t| t.parse::<f64>().ok())
            .collect()
    };
    let mut out = ParsedVtk::default();
    let header: Vec<&str> = lines.next()?.split_whitespace().collect();
    if header.first() != Some(&"POINTS") {
        return None;
    }
    let n: usize = header.get(1)?.parse().ok()?;
    for _ in 0..n {
        let v = nums(lines.next()?)?;
        if v.len() != 3 {
            return None;
        }
        out.points.push([v[0], v[1], v[2]]);
    }
    let header: Vec<&str> = lines.next()?.split_whitespace().collect();
    if header.first() != Some(&"VERTICES") || header.get(1)?.parse::<usize>().ok()? != n {
        return None;
    }
    for _ in 0..n {
        let v = nums(lines.next()?)?;
        if v.len() != 2 || v[0] != 1.0 {
            return None;
        }
        out.vertices.push(v[1] as usize);
    }
    let header: Vec<&str> = lines.next()?.split_whitespace().collect();
    if header.first() != Some(&"POINT_DATA") || header.get(1)?.parse::<usize>().ok()? != n {
        return None;
    }
    while let Some(line) = lines.next() {
        let h: Vec<&str> = line.split_whitespace().collect();
        if h.is_empty() {
            continue;
        }
        let (name, comps) = match h[0] {
            "SCALARS" => {
                let c = h.get(3).and_then(|c| c.parse().ok()).unwrap_or(1);
                if lines.next()?.trim() != "LOOKUP_TABLE default" {
                    return None;
                }
                (h.get(1)?.to_string(), c)
            }
            "VECTORS" => (h.get(1)?.to_string(), 3),
            _ => return None,
        };
        let mut values = Vec::with_capacity(n * comps);
        for _ in 0..n {
            let v = nums(lines.next()?)?;
            if v.len() != comps {
                return None;
            }
            values.extend(v);
        }
        out.arrays.push((name, comps, values));
    }
    Some(out)
}
