//! Particle output as legacy ASCII VTK POLYDATA (`.vtk`, VTK file format 3.0), readable by ParaView/VisIt.
//!
//! One vertex per particle at its centre, with point data: `orientation` (radians, body x axis from +x),
//! `semi_axes` (a, b, 0), `velocity` (vx, vy, 0), `angular_velocity`, and `broken_bond_fraction` (broken /
//! total bonds of the particle, 0 without bonds). Glyph the ellipses with the semi-axes and orientation.
//! Units: those of the scene (cgs: cm, cm/s, rad/s).
//!
//! Also: bonds as lines (legacy ASCII POLYDATA, cell data `intact`) and a lattice field as legacy binary
//! STRUCTURED_POINTS (point data `pressure`, `velocity`, `solid_fraction`, physical units; pressure is the
//! excess over the drained boundary pressure), for ParaView.
use std::fmt::Write;

use lbdem_kernels::dem::shape::Particle;
use lbdem_kernels::Real;

use crate::engine::dem::DemWorld;

/// A lattice field in physical units, row-major (x fastest).
#[derive(Clone, Debug)]
pub struct Field {
    /// Nodes along x and y.
    pub nodes: [usize; 2],
    /// Position of node (0, 0).
    pub origin: [f64; 2],
    /// Node spacing.
    pub spacing: f64,
    /// Pressure (excess over the drained boundary).
    pub pressure: Vec<f64>,
    /// Velocity.
    pub velocity: Vec<[f64; 2]>,
    /// Solid fraction.
    pub solid_fraction: Vec<f64>,
}

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

/// Every bond as a line between the two grain centres, with `intact` (1/0) as cell data.
pub fn bonds_vtk(title: &str, w: &DemWorld<f64>) -> String {
    let n = w.particles.len();
    let m = w.bonds.len();
    let title: String = title.chars().filter(|c| *c != '\n').take(200).collect();
    let mut s = String::with_capacity(100 + n * 40 + m * 30);
    let _ = writeln!(
        s,
        "# vtk DataFile Version 3.0\n{title} bonds\nASCII\nDATASET POLYDATA"
    );
    let _ = writeln!(s, "POINTS {n} double");
    for p in &w.particles {
        let _ = writeln!(s, "{:.9e} {:.9e} 0", p.position[0], p.position[1]);
    }
    let _ = writeln!(s, "LINES {m} {}", 3 * m);
    for b in &w.bonds {
        let _ = writeln!(s, "2 {} {}", b.pair[0], b.pair[1]);
    }
    let _ = writeln!(
        s,
        "CELL_DATA {m}\nSCALARS intact int 1\nLOOKUP_TABLE default"
    );
    for b in &w.bonds {
        let _ = writeln!(s, "{}", u8::from(b.intact()));
    }
    s
}

/// The lattice fields as a legacy binary VTK structured-points file (big-endian f32 as the format requires).
pub fn lattice_vtk(title: &str, f: &Field) -> Vec<u8> {
    let [nx, ny] = f.nodes;
    let n = nx * ny;
    let title: String = title.chars().filter(|c| *c != '\n').take(200).collect();
    let mut out = format!(
        "# vtk DataFile Version 3.0\n{title} lattice\nBINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS {nx} {ny} 1\n\
         ORIGIN {:.9e} {:.9e} 0\nSPACING {:.9e} {:.9e} 1\nPOINT_DATA {n}\nSCALARS pressure float 1\nLOOKUP_TABLE default\n",
        f.origin[0], f.origin[1], f.spacing, f.spacing
    )
    .into_bytes();
    out.reserve(n * 24 + 200);
    for &p in &f.pressure {
        out.extend_from_slice(&(p as f32).to_be_bytes());
    }
    out.extend_from_slice(b"\nVECTORS velocity float\n");
    for v in &f.velocity {
        out.extend_from_slice(&(v[0] as f32).to_be_bytes());
        out.extend_from_slice(&(v[1] as f32).to_be_bytes());
        out.extend_from_slice(&0f32.to_be_bytes());
    }
    out.extend_from_slice(b"\nSCALARS solid_fraction float 1\nLOOKUP_TABLE default\n");
    for &e in &f.solid_fraction {
        out.extend_from_slice(&(e as f32).to_be_bytes());
    }
    out.push(b'\n');
    out
}
