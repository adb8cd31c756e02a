//! VTK outputs of the fracture run for ParaView: bonds as lines (legacy ASCII POLYDATA, cell data `intact`)
//! and the lattice as legacy binary STRUCTURED_POINTS (point data `pressure`, `velocity`, `solid_fraction`,
//! physical units; pressure is the excess over the drained boundary pressure).
use std::fmt::Write;

use super::figures::Field;
use crate::solid::world::DemWorld;

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
