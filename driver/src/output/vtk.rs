//! Snapshots for ParaView/VisIt as VTK XML files with raw binary appended data: grains and bonds as PolyData
//! (`.vtp`), the lattice as ImageData (`.vti`). Every file is grouped by [`super::pvd`] into a `.pvd` collection
//! per series, so that ParaView's time runs in model seconds.
//!
//! Why XML and not the legacy `.vtk` format: ParaView's `.pvd` reader opens XML VTK files only (it picks the
//! reader by extension: `vtp`, `vti`, ...). Why hand-written: the subset needed (one piece, `Float64`/`Float32`/
//! `Int64`/`Int32`/`UInt8` arrays, raw appended data with `UInt64` block headers, ascii field data) is small; the
//! Rust VTK crate's last stable release is years old and its release candidate pulls compression C libraries.
//! What this module writes is read back with the real VTK library in the tests (`driver/tests/vtk_readback.rs`),
//! and by [`parse_vtk_xml`] (the subset parser used by the Rust-side tests).
//!
//! Every file carries, as field data, `TIME` (the model time of the snapshot, s), `units` (one string
//! `array=unit` per physical array; the unit system is the scene's `[scene] units`) and `source`. The arrays,
//! their meaning and units are listed in `docs/outputs.md`.
use std::collections::HashMap;
use std::fmt::Write;

use lbdem_kernels::dem::bond::BreakMode;
use lbdem_kernels::dem::shape::Particle;
use lbdem_kernels::fluid::step::SOLID;
use lbdem_kernels::Real;

use crate::engine::dem::world::BondLaw;
use crate::engine::dem::DemWorld;
use crate::engine::lattice::FluidLattice;
use crate::units::UnitSystem;

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
    /// Node kind ([`NODE_FLUID`], [`NODE_COVERED`], [`NODE_WALL`], [`NODE_OPEN_BOUNDARY`]).
    pub node_kind: Vec<u8>,
}

/// Node kind: free fluid.
pub const NODE_FLUID: u8 = 0;
/// Node kind: fluid node partly or wholly covered by grains (ε > 0; the partially-saturated collision).
pub const NODE_COVERED: u8 = 1;
/// Node kind: solid wall node (bounce-back).
pub const NODE_WALL: u8 = 2;
/// Node kind: node on a Zou–He pressure or velocity side.
pub const NODE_OPEN_BOUNDARY: u8 = 3;

/// Values of one data array.
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    /// `Float64`.
    F64(Vec<f64>),
    /// `Float32`.
    F32(Vec<f32>),
    /// `Int64`.
    I64(Vec<i64>),
    /// `UInt8`.
    U8(Vec<u8>),
}

impl Values {
    fn type_name(&self) -> &'static str {
        match self {
            Values::F64(_) => "Float64",
            Values::F32(_) => "Float32",
            Values::I64(_) => "Int64",
            Values::U8(_) => "UInt8",
        }
    }

    fn append_le(&self, out: &mut Vec<u8>) {
        match self {
            Values::F64(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            Values::F32(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            Values::I64(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            Values::U8(v) => out.extend_from_slice(v),
        }
    }
}

/// A named data array with `components` values per tuple and, for the `units` field data, its unit.
#[derive(Clone, Debug, PartialEq)]
pub struct Array {
    /// Array name (what ParaView lists).
    pub name: String,
    /// Components per tuple (1 scalar, 3 vector, 9 tensor).
    pub components: usize,
    /// Unit label ("1" for a dimensionless number, "" for an index or code).
    pub unit: String,
    /// The values, tuple after tuple.
    pub values: Values,
}

impl Array {
    fn new(name: &str, components: usize, unit: &str, values: Values) -> Self {
        Array {
            name: name.into(),
            components,
            unit: unit.into(),
            values,
        }
    }
}

/// Factors turning the world's numbers into the labelled units: a world simulated in lattice units (h = Δt = ρ₀ =
/// 1, e.g. `terminal_velocity`) is written in physical units with the lattice spacing, step and ρ₀ h² (mass per
/// unit thickness). Every factor is 1 for a world in physical units, and multiplying by 1 is exact: the files
/// then hold bitwise the simulation's numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scale {
    /// Length of one world length unit.
    pub length: f64,
    /// Duration of one world time unit.
    pub time: f64,
    /// Mass of one world mass unit.
    pub mass: f64,
}

impl Scale {
    /// The world is in the labelled units already.
    pub const ONE: Scale = Scale {
        length: 1.0,
        time: 1.0,
        mass: 1.0,
    };

    /// The world is in the lattice units of `units` (h = Δt = ρ₀ = 1): length h, time Δt, mass ρ₀ h².
    pub fn lattice(units: &crate::units::LatticeUnits) -> Self {
        Scale {
            length: units.spacing,
            time: units.timestep,
            mass: units.density * units.spacing * units.spacing,
        }
    }

    fn velocity(&self) -> f64 {
        self.length / self.time
    }
    fn rate(&self) -> f64 {
        1.0 / self.time
    }
    fn force(&self) -> f64 {
        self.mass * self.length / (self.time * self.time)
    }
    fn torque(&self) -> f64 {
        self.force() * self.length
    }
    fn inertia(&self) -> f64 {
        self.mass * self.length * self.length
    }
}

/// Labels of the units of the arrays (2-D, unit thickness: mass, force and torque per unit thickness), and the
/// factors from the world's numbers to them.
#[derive(Clone, Copy, Debug)]
pub struct Units {
    /// Length.
    pub length: &'static str,
    /// Velocity.
    pub velocity: &'static str,
    /// Mass.
    pub mass: &'static str,
    /// Force.
    pub force: &'static str,
    /// Torque.
    pub torque: &'static str,
    /// Moment of inertia.
    pub inertia: &'static str,
    /// Pressure.
    pub pressure: &'static str,
    /// Time (of `break_time`, and the `1/time` of `angular_velocity`).
    pub time: &'static str,
    /// Angular velocity.
    pub angular_velocity: &'static str,
    /// From the world's numbers to these units ([`Scale::ONE`] from [`Units::of`]).
    pub scale: Scale,
}

impl Units {
    /// The labels of a unit system.
    pub fn of(system: UnitSystem) -> Self {
        let l = system.labels();
        let (mass, force, torque, inertia) = match system {
            UnitSystem::Cgs => ("g", "dyne", "dyne*cm", "g*cm^2"),
            UnitSystem::Si => ("kg", "N", "N*m", "kg*m^2"),
        };
        Units {
            length: l.length,
            velocity: l.velocity,
            mass,
            force,
            torque,
            inertia,
            pressure: l.pressure,
            time: l.time,
            angular_velocity: "rad/s",
            scale: Scale::ONE,
        }
    }

    /// Lattice units (spacing h, step dt, reference density rho0 all 1; 2-D, per unit thickness), named as
    /// such: for a world simulated and written in lattice units (`coupled_demo`), whose numbers are then not
    /// in any physical system.
    pub fn lattice() -> Self {
        Units {
            length: "h",
            velocity: "h/dt",
            mass: "rho0*h^2",
            force: "rho0*h^3/dt^2",
            torque: "rho0*h^4/dt^2",
            inertia: "rho0*h^4",
            pressure: "rho0*h^2/dt^2",
            time: "dt",
            angular_velocity: "rad/dt",
            scale: Scale::ONE,
        }
    }

    /// The same labels for a world whose numbers are turned into them by `scale`.
    pub fn scaled(self, scale: Scale) -> Self {
        Units { scale, ..self }
    }
}

/// What a snapshot file says about itself: model time, a title, and the unit system.
#[derive(Clone, Debug)]
pub struct Stamp {
    /// Model time of the snapshot (s).
    pub time: f64,
    /// Title (the scene name), stored as the `source` field-data string.
    pub title: String,
    /// Unit labels.
    pub units: Units,
}

impl Stamp {
    /// The stamp of a snapshot at model time `time` of a scene named `name` (`lbdem KIND` when unnamed), with the
    /// unit labels of `system`.
    pub fn titled(time: f64, name: Option<&str>, kind: &str, system: UnitSystem) -> Self {
        Stamp {
            time,
            title: name.map_or_else(|| format!("lbdem {kind}"), str::to_owned),
            units: Units::of(system),
        }
    }
}

fn escape(s: &str) -> String {
    s.chars()
        .filter(|c| !c.is_control())
        .map(|c| match c {
            '&' => "&amp;".to_string(),
            '<' => "&lt;".to_string(),
            '>' => "&gt;".to_string(),
            '"' => "&quot;".to_string(),
            c => c.to_string(),
        })
        .collect()
}

/// One XML VTK document being written: the XML text and the appended binary blocks.
struct Doc {
    xml: String,
    appended: Vec<u8>,
}

impl Doc {
    fn new(kind: &str) -> Self {
        let mut xml = String::with_capacity(4096);
        let _ = writeln!(
            xml,
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"{kind}\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
        );
        Doc {
            xml,
            appended: Vec::new(),
        }
    }

    /// A data array whose values go into the appended block (UInt64 byte count, then the little-endian values).
    fn array(&mut self, a: &Array, indent: &str) {
        let offset = self.appended.len();
        let bytes_before = self.appended.len();
        self.appended.extend_from_slice(&0u64.to_le_bytes());
        a.values.append_le(&mut self.appended);
        let size = (self.appended.len() - bytes_before - 8) as u64;
        self.appended[bytes_before..bytes_before + 8].copy_from_slice(&size.to_le_bytes());
        let _ = writeln!(
            self.xml,
            "{indent}<DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"appended\" offset=\"{offset}\"/>",
            a.values.type_name(),
            escape(&a.name),
            a.components
        );
    }

    /// Field data: `TIME`, `source` and `units` (ascii; strings as character codes, each closed by 0, as VTK
    /// writes them).
    fn field_data(&mut self, stamp: &Stamp, arrays: &[&[Array]]) {
        let strings = |list: &[String]| -> String {
            let mut s = String::new();
            for item in list {
                for b in item.bytes() {
                    let _ = write!(s, "{b} ");
                }
                s.push('0');
                s.push(' ');
            }
            s.trim_end().to_string()
        };
        let units: Vec<String> = arrays
            .iter()
            .flat_map(|list| list.iter())
            .filter(|a| !a.unit.is_empty())
            .map(|a| format!("{}={}", a.name, a.unit))
            .collect();
        let title: String = stamp
            .title
            .chars()
            .filter(|c| c.is_ascii())
            .take(200)
            .collect();
        let _ = writeln!(
            self.xml,
            "    <FieldData>\n      <DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\" format=\"ascii\">{:e}</DataArray>\n      \
             <DataArray type=\"String\" Name=\"source\" NumberOfTuples=\"1\" format=\"ascii\">{}</DataArray>\n      \
             <DataArray type=\"String\" Name=\"units\" NumberOfTuples=\"{}\" format=\"ascii\">{}</DataArray>\n    </FieldData>",
            stamp.time,
            strings(&[title]),
            units.len(),
            strings(&units)
        );
    }

    /// Point or cell data: the first 1-, 3- and 9-component arrays become the active scalars, vectors, tensors.
    fn attributes(&mut self, tag: &str, arrays: &[Array]) {
        let first = |c: usize| {
            arrays
                .iter()
                .find(|a| a.components == c)
                .map(|a| a.name.clone())
        };
        let mut open = format!("      <{tag}");
        for (attr, c) in [("Scalars", 1), ("Vectors", 3), ("Tensors", 9)] {
            if let Some(n) = first(c) {
                let _ = write!(open, " {attr}=\"{}\"", escape(&n));
            }
        }
        let _ = writeln!(self.xml, "{open}>");
        for a in arrays {
            self.array(a, "        ");
        }
        let _ = writeln!(self.xml, "      </{tag}>");
    }

    fn finish(mut self, kind: &str) -> Vec<u8> {
        let _ = writeln!(self.xml, "  </{kind}>\n  <AppendedData encoding=\"raw\">");
        let mut out = self.xml.into_bytes();
        out.reserve(self.appended.len() + 40);
        out.extend_from_slice(b"   _");
        out.extend_from_slice(&self.appended);
        out.extend_from_slice(b"\n  </AppendedData>\n</VTKFile>\n");
        out
    }
}

/// A PolyData document: points (x, y, 0), `verts` (one vertex cell per point) or `lines` (two-point cells).
fn polydata(
    stamp: &Stamp,
    points: &[[f64; 2]],
    lines: Option<&[[usize; 2]]>,
    point_data: &[Array],
    cell_data: &[Array],
) -> Vec<u8> {
    let mut d = Doc::new("PolyData");
    let _ = writeln!(d.xml, "  <PolyData>");
    d.field_data(stamp, &[point_data, cell_data]);
    let n = points.len();
    let (verts, nlines) = match lines {
        Some(l) => (0, l.len()),
        None => (n, 0),
    };
    let _ = writeln!(
        d.xml,
        "    <Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"{verts}\" NumberOfLines=\"{nlines}\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">"
    );
    d.attributes("PointData", point_data);
    d.attributes("CellData", cell_data);
    let _ = writeln!(d.xml, "      <Points>");
    let xyz: Vec<f64> = points.iter().flat_map(|p| [p[0], p[1], 0.0]).collect();
    d.array(&Array::new("Points", 3, "", Values::F64(xyz)), "        ");
    let _ = writeln!(d.xml, "      </Points>");
    let (tag, connectivity, per) = match lines {
        Some(l) => (
            "Lines",
            l.iter()
                .flat_map(|p| [p[0] as i64, p[1] as i64])
                .collect::<Vec<_>>(),
            2,
        ),
        None => ("Verts", (0..n as i64).collect(), 1),
    };
    let cells = connectivity.len() / per;
    let _ = writeln!(d.xml, "      <{tag}>");
    d.array(
        &Array::new("connectivity", 1, "", Values::I64(connectivity)),
        "        ",
    );
    d.array(
        &Array::new(
            "offsets",
            1,
            "",
            Values::I64((1..=cells as i64).map(|k| k * per as i64).collect()),
        ),
        "        ",
    );
    let _ = writeln!(d.xml, "      </{tag}>\n    </Piece>");
    d.finish("PolyData")
}

/// The arrays of every grain (see `docs/outputs.md`). `fluid`: the fluid's force and torque on each grain
/// (coupled runs, in the world's units like everything else; `units.scale` turns them into the labelled ones);
/// the contact loads: [`DemWorld::contact_loads`] (grain–grain) plus [`DemWorld::wall_contact_loads`]
/// (platens) of the last step, or of the next step when the world has not been stepped in this process.
pub fn particle_arrays<T: Real>(
    w: &DemWorld<T>,
    fluid: Option<&[([f64; 2], f64)]>,
    units: &Units,
) -> Vec<Array> {
    let f = |x: T| x.to_f64_exact();
    let force_s = units.scale.force();
    let n = w.particles.len();
    // The contact forces of the last step; before the first step in this process (at the start of a run, or
    // right after a resume: they are not checkpointed) those the next step will apply, from a copy of the world
    // stepped once (the copy is dropped; the world is not touched).
    let loads = |w: &DemWorld<T>| w.contact_loads().zip(w.wall_contact_loads());
    let ((gf, gc), (wf, wc)) = loads(w).unwrap_or_else(|| {
        let mut probe = w.clone();
        probe.step();
        loads(&probe).expect("a stepped world knows its contact loads")
    });
    let to = |v: &[T; 2]| [f(v[0]) * force_s, f(v[1]) * force_s];
    let grain_force: Vec<[f64; 2]> = gf.iter().map(to).collect();
    let wall_force: Vec<[f64; 2]> = wf.iter().map(to).collect();
    let contact_count: Vec<u32> = gc.iter().zip(&wc).map(|(a, b)| a + b).collect();
    let broken = w.broken_bond_fraction();
    let mut bonds = vec![0i64; n];
    for b in &w.bonds {
        for &i in &b.pair {
            bonds[i] += 1;
        }
    }
    let loads = Loads {
        grain_force,
        wall_force,
        contact_count,
        bonds,
        broken,
        held: false,
    };
    grain_arrays(&w.particles, &loads, fluid, units)
}

/// What [`grain_arrays`] writes besides the particles themselves: the contact loads (in the labelled units),
/// the bonds of each grain, and whether the grains are held fixed.
struct Loads {
    grain_force: Vec<[f64; 2]>,
    wall_force: Vec<[f64; 2]>,
    contact_count: Vec<u32>,
    bonds: Vec<i64>,
    broken: Vec<f64>,
    /// Held fixed (not a DEM world: mass and moment of inertia written as −1, i.e. +∞).
    held: bool,
}

/// The arrays of grains `p` with their `loads` and the fluid's loads `fluid`.
fn grain_arrays<T: Real>(
    p: &[Particle<T>],
    loads: &Loads,
    fluid: Option<&[([f64; 2], f64)]>,
    units: &Units,
) -> Vec<Array> {
    let f = |x: T| x.to_f64_exact();
    let sc = units.scale;
    let (len, vel, rate, mass_s, force_s, torque_s, inertia_s) = (
        sc.length,
        sc.velocity(),
        sc.rate(),
        sc.mass,
        sc.force(),
        sc.torque(),
        sc.inertia(),
    );
    let n = p.len();
    let (grain_force, wall_force, contact_count) =
        (&loads.grain_force, &loads.wall_force, &loads.contact_count);
    let v3 = |g: &dyn Fn(usize) -> [f64; 2]| -> Values {
        Values::F64(
            (0..n)
                .flat_map(|i| {
                    let v = g(i);
                    [v[0], v[1], 0.0]
                })
                .collect(),
        )
    };
    let s1 = |g: &dyn Fn(usize) -> f64| -> Values { Values::F64((0..n).map(g).collect()) };
    let axes: Vec<(f64, f64)> = p
        .iter()
        .map(|q| {
            let (a, b) = q.shape.semi_axes();
            (f(a) * len, f(b) * len)
        })
        .collect();
    let velocity: Vec<[f64; 2]> = p
        .iter()
        .map(|q| [f(q.velocity[0]) * vel, f(q.velocity[1]) * vel])
        .collect();
    // The glyph shape tensor R diag(2a, 2b, 2b) Rᵀ (R: rotation by the orientation θ): ParaView's Tensor Glyph
    // with its default unit-diameter sphere and scale factor 1 draws the true ellipse (semi-axes a, b); the
    // out-of-plane axis 2b makes it an ellipsoid whose outline seen along z is the grain.
    let tensor: Vec<f64> = p
        .iter()
        .zip(&axes)
        .flat_map(|(q, &(a, b))| {
            let (s, c) = f(q.angle).sin_cos();
            let (l1, l2) = (2.0 * a, 2.0 * b);
            let xx = l1 * c * c + l2 * s * s;
            let yy = l1 * s * s + l2 * c * c;
            let xy = (l1 - l2) * s * c;
            [xx, xy, 0.0, xy, yy, 0.0, 0.0, 0.0, l2]
        })
        .collect();
    let mut out = vec![
        Array::new(
            "speed",
            1,
            units.velocity,
            s1(&|i| velocity[i][0].hypot(velocity[i][1])),
        ),
        Array::new("velocity", 3, units.velocity, v3(&|i| velocity[i])),
        Array::new("shape_tensor", 9, units.length, Values::F64(tensor)),
        Array::new("id", 1, "", Values::I64((0..n as i64).collect())),
        Array::new(
            "angular_velocity",
            1,
            units.angular_velocity,
            s1(&|i| f(p[i].angular_velocity) * rate),
        ),
        Array::new("orientation", 1, "rad", s1(&|i| f(p[i].angle))),
        Array::new(
            "major_axis",
            3,
            "1",
            v3(&|i| {
                let (s, c) = f(p[i].angle).sin_cos();
                [c, s]
            }),
        ),
        Array::new(
            "semi_axes",
            3,
            units.length,
            v3(&|i| [axes[i].0, axes[i].1]),
        ),
        Array::new(
            "glyph_scale",
            3,
            units.length,
            Values::F64(
                axes.iter()
                    .flat_map(|&(a, b)| [2.0 * a, 2.0 * b, 2.0 * b])
                    .collect(),
            ),
        ),
        // Held fixed: m = +∞, written as −1 (the files hold finite numbers only).
        Array::new(
            "mass",
            1,
            units.mass,
            s1(&|i| {
                if loads.held {
                    -1.0
                } else {
                    f(p[i].mass) * mass_s
                }
            }),
        ),
        // +∞ (rotation locked, or the grain held fixed) is written as −1.
        Array::new(
            "moment_of_inertia",
            1,
            units.inertia,
            s1(&|i| {
                let j = f(p[i].moment_of_inertia);
                if j.is_finite() && !loads.held {
                    j * inertia_s
                } else {
                    -1.0
                }
            }),
        ),
        // Every contact force on the grain: grain–grain plus platen (what balances the bonds', the fluid's and
        // the applied loads); the platen part alone is `wall_force`.
        Array::new(
            "contact_force",
            3,
            units.force,
            v3(&|i| {
                [
                    grain_force[i][0] + wall_force[i][0],
                    grain_force[i][1] + wall_force[i][1],
                ]
            }),
        ),
        Array::new("wall_force", 3, units.force, v3(&|i| wall_force[i])),
        Array::new(
            "contact_count",
            1,
            "",
            Values::I64(contact_count.iter().map(|&c| c as i64).collect()),
        ),
        Array::new("bonds", 1, "", Values::I64(loads.bonds.clone())),
        Array::new(
            "broken_bond_fraction",
            1,
            "1",
            Values::F64(loads.broken.clone()),
        ),
    ];
    if let Some(fl) = fluid {
        out.push(Array::new(
            "fluid_force",
            3,
            units.force,
            v3(&|i| [fl[i].0[0] * force_s, fl[i].0[1] * force_s]),
        ));
        out.push(Array::new(
            "fluid_torque",
            1,
            units.torque,
            s1(&|i| fl[i].1 * torque_s),
        ));
    }
    out
}

/// The grains' centres in the stamp's length unit (the points of the particle and bond files).
fn particle_points<T: Real>(stamp: &Stamp, p: &[Particle<T>]) -> Vec<[f64; 2]> {
    p.iter()
        .map(|p| {
            [
                p.position[0].to_f64_exact() * stamp.units.scale.length,
                p.position[1].to_f64_exact() * stamp.units.scale.length,
            ]
        })
        .collect()
}

/// The grains as a `.vtp` document: one vertex per grain at its centre, with [`particle_arrays`] as point data.
pub fn particles_vtp<T: Real>(
    stamp: &Stamp,
    w: &DemWorld<T>,
    fluid: Option<&[([f64; 2], f64)]>,
) -> Vec<u8> {
    let points = particle_points(stamp, &w.particles);
    polydata(
        stamp,
        &points,
        None,
        &particle_arrays(w, fluid, &stamp.units),
        &[],
    )
}

/// The arrays of grains `p` held fixed in a fluid (the fixed-solid kinds: `pressure_diffusion`, `porous_flow`,
/// `cylinder_array`), the same arrays as [`particle_arrays`]: the velocities the particles hold (0 for grains
/// held fixed), mass and moment of inertia −1 (held: +∞, as for a locked rotation), no contact load (the grains
/// are no DEM world: no contact is computed), no bond; `fluid` as there.
pub fn fixed_particle_arrays<T: Real>(
    p: &[Particle<T>],
    fluid: Option<&[([f64; 2], f64)]>,
    units: &Units,
) -> Vec<Array> {
    let n = p.len();
    let loads = Loads {
        grain_force: vec![[0.0; 2]; n],
        wall_force: vec![[0.0; 2]; n],
        contact_count: vec![0; n],
        bonds: vec![0; n],
        broken: vec![0.0; n],
        held: true,
    };
    grain_arrays(p, &loads, fluid, units)
}

/// Grains held fixed as a `.vtp` document: one vertex per grain at its centre, with [`fixed_particle_arrays`]
/// as point data.
pub fn fixed_particles_vtp<T: Real>(
    stamp: &Stamp,
    p: &[Particle<T>],
    fluid: Option<&[([f64; 2], f64)]>,
) -> Vec<u8> {
    let points = particle_points(stamp, p);
    polydata(
        stamp,
        &points,
        None,
        &fixed_particle_arrays(p, fluid, &stamp.units),
        &[],
    )
}

/// How break records map to times: a record's time is `(step − origin_step) · dt` (0 for a break before
/// `origin_step`).
#[derive(Clone, Copy, Debug)]
pub struct BreakClock {
    /// DEM step count at time 0.
    pub origin_step: u64,
    /// DEM step.
    pub dt: f64,
}

/// Bond break mode codes of the `break_mode` array.
pub fn break_mode_code(mode: BreakMode) -> u8 {
    match mode {
        BreakMode::Tension => 1,
        BreakMode::Shear => 2,
        BreakMode::Compression => 3,
    }
}

/// `break_mode` of a bond broken without a break record (before the run's records started, e.g. while settling).
pub const BREAK_UNRECORDED: u8 = 4;

/// The arrays of every bond (cell data; see `docs/outputs.md`).
pub fn bond_arrays<T: Real>(w: &DemWorld<T>, clock: BreakClock, units: &Units) -> Vec<Array> {
    let f = |x: T| x.to_f64_exact();
    let force_s = units.scale.force();
    let m = w.bonds.len();
    let records: HashMap<[usize; 2], (u64, BreakMode)> = w
        .breaks
        .iter()
        .map(|b| (b.pair, (b.step, b.mode)))
        .collect();
    let mut normal = Vec::with_capacity(m);
    let mut shear = Vec::with_capacity(m);
    let mut stretch = Vec::with_capacity(m);
    let mut ratio = Vec::with_capacity(m);
    let mut mode = Vec::with_capacity(m);
    let mut time = Vec::with_capacity(m);
    for b in &w.bonds {
        let intact = b.intact();
        let (fnorm, fshear, ext, r) = if !intact {
            (0.0, 0.0, 0.0, 0.0)
        } else {
            match &b.law {
                BondLaw::Point(pb) => {
                    let (pi, pj) = (&w.particles[b.pair[0]], &w.particles[b.pair[1]]);
                    let (dx, nrm) = pb.stretch(pi, pj);
                    let (dx, nrm) = ([f(dx[0]), f(dx[1])], [f(nrm[0]), f(nrm[1])]);
                    let k = f(pb.stiffness);
                    // Force on j is −k Δx (eq. 6.13); its components along the bond normal and the tangent.
                    let fj = [-k * dx[0], -k * dx[1]];
                    let fnorm = fj[0] * nrm[0] + fj[1] * nrm[1];
                    let fshear = -fj[0] * nrm[1] + fj[1] * nrm[0];
                    let strength = f(pb.strength);
                    let r = if strength > 0.0 {
                        fj[0].hypot(fj[1]) / strength
                    } else {
                        0.0
                    };
                    (fnorm, fshear, dx[0] * nrm[0] + dx[1] * nrm[1], r)
                }
                BondLaw::Parallel { bond, .. } => {
                    let ka = f(bond.normal_stiffness) * f(bond.area());
                    let ext = if ka > 0.0 {
                        -f(bond.normal_force) / ka
                    } else {
                        0.0
                    };
                    let (sc, tc) = (f(bond.tensile_strength), f(bond.shear_strength));
                    let rs = if sc > 0.0 {
                        f(bond.max_tensile_stress()) / sc
                    } else {
                        0.0
                    };
                    let rt = if tc > 0.0 {
                        f(bond.max_shear_stress()) / tc
                    } else {
                        0.0
                    };
                    (f(bond.normal_force), f(bond.shear_force), ext, rs.max(rt))
                }
            }
        };
        normal.push(fnorm * force_s);
        shear.push(fshear * force_s);
        stretch.push(ext * units.scale.length);
        ratio.push(r);
        match (intact, records.get(&b.pair)) {
            (true, _) => {
                mode.push(0);
                time.push(-1.0);
            }
            (false, Some(&(step, md))) => {
                mode.push(break_mode_code(md));
                time.push(step.saturating_sub(clock.origin_step) as f64 * clock.dt);
            }
            (false, None) => {
                mode.push(BREAK_UNRECORDED);
                time.push(-1.0);
            }
        }
    }
    vec![
        Array::new(
            "intact",
            1,
            "",
            Values::U8(w.bonds.iter().map(|b| u8::from(b.intact())).collect()),
        ),
        Array::new("id", 1, "", Values::I64((0..m as i64).collect())),
        Array::new(
            "pair",
            2,
            "",
            Values::I64(
                w.bonds
                    .iter()
                    .flat_map(|b| [b.pair[0] as i64, b.pair[1] as i64])
                    .collect(),
            ),
        ),
        Array::new("break_mode", 1, "", Values::U8(mode)),
        Array::new("break_time", 1, units.time, Values::F64(time)),
        Array::new("normal_force", 1, units.force, Values::F64(normal)),
        Array::new("shear_force", 1, units.force, Values::F64(shear)),
        Array::new("stretch", 1, units.length, Values::F64(stretch)),
        Array::new("strength_ratio", 1, "1", Values::F64(ratio)),
    ]
}

/// Every bond as a line between its two grain centres (`.vtp`), [`bond_arrays`] as cell data, the grain `id`
/// as point data.
pub fn bonds_vtp<T: Real>(stamp: &Stamp, w: &DemWorld<T>, clock: BreakClock) -> Vec<u8> {
    let points = particle_points(stamp, &w.particles);
    let pairs: Vec<[usize; 2]> = w.bonds.iter().map(|b| b.pair).collect();
    let ids = Array::new("id", 1, "", Values::I64((0..points.len() as i64).collect()));
    polydata(
        stamp,
        &points,
        Some(&pairs),
        &[ids],
        &bond_arrays(w, clock, &stamp.units),
    )
}

/// The [`Field::node_kind`] of every node (row-major) of a lattice whose solid fractions are `solid_fraction`.
pub fn node_kinds<T: Real>(lattice: &FluidLattice<T>, solid_fraction: &[f64]) -> Vec<u8> {
    let nx = lattice.shape().nx;
    lattice
        .flags()
        .iter()
        .zip(solid_fraction)
        .enumerate()
        .map(|(k, (&flag, &eps))| {
            if flag == SOLID {
                NODE_WALL
            } else if lattice.on_zou_he_side(k % nx, k / nx) {
                NODE_OPEN_BOUNDARY
            } else if eps > 0.0 {
                NODE_COVERED
            } else {
                NODE_FLUID
            }
        })
        .collect()
}

/// Where a lattice lies and how its numbers turn into physical ones, for [`lattice_field`].
#[derive(Clone, Copy, Debug)]
pub struct LatticeFrame {
    /// Physical position of node (0, 0).
    pub origin: [f64; 2],
    /// Node spacing h (physical length).
    pub spacing: f64,
    /// Physical velocity of a lattice velocity of 1 (c = h/Δt).
    pub velocity: f64,
    /// Physical pressure of a lattice density change of 1 (ρ₀ c_s²).
    pub pressure: f64,
    /// Lattice density whose pressure is written as 0 (the drained boundary's, or the initial one).
    pub reference_density: f64,
}

impl LatticeFrame {
    /// The frame of `units` with node (0, 0) at `origin` and pressure 0 at `reference_density`.
    pub fn of(
        units: &crate::units::LatticeUnits,
        origin: [f64; 2],
        reference_density: f64,
    ) -> Self {
        LatticeFrame {
            origin,
            spacing: units.spacing,
            velocity: units.lattice_speed,
            pressure: units.density * units.sound_speed * units.sound_speed,
            reference_density,
        }
    }

    /// Lattice units (h = Δt = ρ₀ = 1, c_s² = 1/3), node (0, 0) at the origin, pressure 0 at density 1.
    pub fn lattice_units() -> Self {
        LatticeFrame {
            origin: [0.0; 2],
            spacing: 1.0,
            velocity: 1.0,
            pressure: crate::units::CS2,
            reference_density: 1.0,
        }
    }
}

/// The [`Field`] of a lattice in the physical units of `frame`: pressure `frame.pressure · (ρ − ρ_ref)`,
/// velocity, the solid fraction of its current coverage, and the node kinds.
pub fn lattice_field<T: Real>(lattice: &FluidLattice<T>, frame: &LatticeFrame) -> Field {
    let (rho, u) = lattice.moments();
    let pressure: Vec<f64> = rho
        .iter()
        .map(|r| frame.pressure * (r.to_f64_exact() - frame.reference_density))
        .collect();
    let velocity: Vec<[f64; 2]> = u
        .iter()
        .map(|v| {
            [
                v[0].to_f64_exact() * frame.velocity,
                v[1].to_f64_exact() * frame.velocity,
            ]
        })
        .collect();
    let solid_fraction = lattice.solid_fraction_map();
    let node_kind = node_kinds(lattice, &solid_fraction);
    let shape = lattice.shape();
    Field {
        nodes: [shape.nx, shape.ny],
        origin: frame.origin,
        spacing: frame.spacing,
        pressure,
        velocity,
        solid_fraction,
        node_kind,
    }
}

/// The lattice arrays (point data; `Float32` except the node kind).
pub fn lattice_arrays(f: &Field, units: &Units) -> Vec<Array> {
    vec![
        Array::new(
            "pressure",
            1,
            units.pressure,
            Values::F32(f.pressure.iter().map(|&p| p as f32).collect()),
        ),
        Array::new(
            "velocity",
            3,
            units.velocity,
            Values::F32(
                f.velocity
                    .iter()
                    .flat_map(|v| [v[0] as f32, v[1] as f32, 0.0])
                    .collect(),
            ),
        ),
        Array::new(
            "solid_fraction",
            1,
            "1",
            Values::F32(f.solid_fraction.iter().map(|&e| e as f32).collect()),
        ),
        Array::new("node_kind", 1, "", Values::U8(f.node_kind.clone())),
    ]
}

/// The lattice as a `.vti` document (ImageData: nodes at `origin + (i, j) · spacing`).
pub fn lattice_vti(stamp: &Stamp, f: &Field) -> Vec<u8> {
    let [nx, ny] = f.nodes;
    let mut d = Doc::new("ImageData");
    let extent = format!("0 {} 0 {} 0 0", nx.saturating_sub(1), ny.saturating_sub(1));
    let _ = writeln!(
        d.xml,
        "  <ImageData WholeExtent=\"{extent}\" Origin=\"{:e} {:e} 0\" Spacing=\"{:e} {:e} 1\">",
        f.origin[0], f.origin[1], f.spacing, f.spacing
    );
    let arrays = lattice_arrays(f, &stamp.units);
    d.field_data(stamp, &[&arrays]);
    let _ = writeln!(d.xml, "    <Piece Extent=\"{extent}\">");
    d.attributes("PointData", &arrays);
    d.attributes("CellData", &[]);
    let _ = writeln!(d.xml, "    </Piece>");
    d.finish("ImageData")
}

/// One array read back by [`parse_vtk_xml`]: numbers as `f64` (exact for every type written here), strings
/// for `String` arrays.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParsedArray {
    /// Name.
    pub name: String,
    /// VTK type name (`Float64`, `UInt8`, `String`, ...).
    pub kind: String,
    /// Components per tuple.
    pub components: usize,
    /// Numeric values.
    pub values: Vec<f64>,
    /// String values (`String` arrays).
    pub strings: Vec<String>,
}

/// A VTK XML file read back by [`parse_vtk_xml`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParsedVtk {
    /// `PolyData` or `ImageData`.
    pub kind: String,
    /// Attributes of the dataset element (`WholeExtent`, `Origin`, `Spacing`) and of the piece.
    pub attributes: HashMap<String, String>,
    /// Field data.
    pub field: Vec<ParsedArray>,
    /// Point data.
    pub point_data: Vec<ParsedArray>,
    /// Cell data.
    pub cell_data: Vec<ParsedArray>,
    /// Points (PolyData).
    pub points: Vec<[f64; 3]>,
    /// Cells: vertices or lines, as point-index lists.
    pub cells: Vec<Vec<usize>>,
}

impl ParsedVtk {
    /// A point-data array by name.
    pub fn point(&self, name: &str) -> Option<&ParsedArray> {
        self.point_data.iter().find(|a| a.name == name)
    }
    /// A cell-data array by name.
    pub fn cell(&self, name: &str) -> Option<&ParsedArray> {
        self.cell_data.iter().find(|a| a.name == name)
    }
    /// A field-data array by name.
    pub fn field(&self, name: &str) -> Option<&ParsedArray> {
        self.field.iter().find(|a| a.name == name)
    }
    /// The model time (`TIME` field data).
    pub fn time(&self) -> Option<f64> {
        self.field("TIME")?.values.first().copied()
    }
    /// The unit of an array from the `units` field data.
    pub fn unit(&self, array: &str) -> Option<&str> {
        self.field("units")?
            .strings
            .iter()
            .find_map(|s| s.strip_prefix(array)?.strip_prefix('='))
    }
}

fn attrs(tag: &str) -> HashMap<String, String> {
    let mut out = HashMap::new();
    let mut rest = tag;
    while let Some(eq) = rest.find("=\"") {
        let key = rest[..eq]
            .split_whitespace()
            .last()
            .unwrap_or("")
            .to_string();
        let after = &rest[eq + 2..];
        let Some(end) = after.find('"') else { break };
        out.insert(key, after[..end].to_string());
        rest = &after[end + 1..];
    }
    out
}

fn decode(kind: &str, bytes: &[u8]) -> Result<Vec<f64>, String> {
    let size = match kind {
        "Float64" | "Int64" | "UInt64" => 8,
        "Float32" | "Int32" | "UInt32" => 4,
        "UInt8" | "Int8" => 1,
        other => return Err(format!("unsupported array type {other}")),
    };
    if !bytes.len().is_multiple_of(size) {
        return Err(format!("{} bytes of {kind}", bytes.len()));
    }
    Ok(bytes
        .chunks_exact(size)
        .map(|c| match kind {
            "Float64" => f64::from_le_bytes(c.try_into().unwrap()),
            "Int64" => i64::from_le_bytes(c.try_into().unwrap()) as f64,
            "UInt64" => u64::from_le_bytes(c.try_into().unwrap()) as f64,
            "Float32" => f32::from_le_bytes(c.try_into().unwrap()) as f64,
            "Int32" => i32::from_le_bytes(c.try_into().unwrap()) as f64,
            "UInt32" => u32::from_le_bytes(c.try_into().unwrap()) as f64,
            "Int8" => c[0] as i8 as f64,
            _ => c[0] as f64,
        })
        .collect())
}

/// Parse the VTK XML subset that this module writes (one piece, appended raw data with `UInt64` headers, ascii
/// field data), checking that every block lies inside the file and holds a whole number of tuples.
pub fn parse_vtk_xml(bytes: &[u8]) -> Result<ParsedVtk, String> {
    let marker = b"<AppendedData encoding=\"raw\">";
    let at = bytes
        .windows(marker.len())
        .position(|w| w == marker)
        .ok_or("no raw AppendedData section")?;
    let head = std::str::from_utf8(&bytes[..at]).map_err(|e| format!("XML part not UTF-8: {e}"))?;
    let underscore = bytes[at + marker.len()..]
        .iter()
        .position(|&b| b == b'_')
        .ok_or("no '_' opening the appended data")?;
    let data = &bytes[at + marker.len() + underscore + 1..];
    let mut out = ParsedVtk::default();
    let mut section = String::new();
    let mut rest = head;
    let mut points_raw: Vec<f64> = Vec::new();
    let mut connectivity: Vec<f64> = Vec::new();
    let mut offsets: Vec<f64> = Vec::new();
    while let Some(open) = rest.find('<') {
        let close = rest[open..].find('>').ok_or("unclosed tag")? + open;
        let tag = &rest[open + 1..close];
        let after = &rest[close + 1..];
        let name = tag
            .split_whitespace()
            .next()
            .unwrap_or("")
            .trim_end_matches('/');
        match name {
            "VTKFile" => {
                let a = attrs(tag);
                if a.get("byte_order").map(String::as_str) != Some("LittleEndian")
                    || a.get("header_type").map(String::as_str) != Some("UInt64")
                {
                    return Err(format!("unsupported VTKFile attributes {a:?}"));
                }
                out.kind = a.get("type").cloned().unwrap_or_default();
            }
            "PolyData" | "ImageData" | "Piece" => out.attributes.extend(attrs(tag)),
            "FieldData" | "PointData" | "CellData" | "Points" | "Verts" | "Lines" => {
                section = name.to_string()
            }
            "DataArray" => {
                let a = attrs(tag);
                let kind = a.get("type").cloned().ok_or("DataArray without type")?;
                let mut arr = ParsedArray {
                    name: a.get("Name").cloned().unwrap_or_default(),
                    kind: kind.clone(),
                    components: a
                        .get("NumberOfComponents")
                        .map_or(Ok(1), |c| c.parse())
                        .map_err(|e| format!("NumberOfComponents: {e}"))?,
                    ..Default::default()
                };
                match a.get("format").map(String::as_str) {
                    Some("appended") => {
                        let offset: usize = a
                            .get("offset")
                            .ok_or("appended DataArray without offset")?
                            .parse()
                            .map_err(|e| format!("offset: {e}"))?;
                        let header = data
                            .get(offset..offset + 8)
                            .ok_or(format!("array {} beyond the end of the file", arr.name))?;
                        let size = u64::from_le_bytes(header.try_into().unwrap()) as usize;
                        let block = data
                            .get(offset + 8..offset + 8 + size)
                            .ok_or(format!("array {} runs past the end of the file", arr.name))?;
                        arr.values = decode(&kind, block)?;
                        if arr.components == 0 || !arr.values.len().is_multiple_of(arr.components) {
                            return Err(format!(
                                "array {}: {} values for {} components",
                                arr.name,
                                arr.values.len(),
                                arr.components
                            ));
                        }
                    }
                    Some("ascii") => {
                        let end = after
                            .find("</DataArray>")
                            .ok_or("unclosed ascii DataArray")?;
                        let text = &after[..end];
                        let nums: Vec<f64> = text
                            .split_whitespace()
                            .map(|t| t.parse::<f64>().map_err(|e| format!("{t}: {e}")))
                            .collect::<Result<_, _>>()?;
                        if kind == "String" {
                            let mut cur = Vec::new();
                            for c in nums {
                                if c == 0.0 {
                                    arr.strings.push(String::from_utf8_lossy(&cur).into_owned());
                                    cur.clear();
                                } else {
                                    cur.push(c as u8);
                                }
                            }
                        } else {
                            arr.values = nums;
                        }
                    }
                    other => return Err(format!("unsupported DataArray format {other:?}")),
                }
                match section.as_str() {
                    "FieldData" => out.field.push(arr),
                    "PointData" => out.point_data.push(arr),
                    "CellData" => out.cell_data.push(arr),
                    "Points" => points_raw = arr.values,
                    "Verts" | "Lines" if arr.name == "connectivity" => connectivity = arr.values,
                    "Verts" | "Lines" if arr.name == "offsets" => offsets = arr.values,
                    s => return Err(format!("DataArray {} in unexpected section {s}", arr.name)),
                }
            }
            _ => {}
        }
        rest = after;
    }
    if !points_raw.len().is_multiple_of(3) {
        return Err("points are not triples".into());
    }
    out.points = points_raw
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let mut start = 0usize;
    for &end in &offsets {
        let end = end as usize;
        let cell = connectivity
            .get(start..end)
            .ok_or("cell offsets beyond the connectivity")?;
        out.cells.push(cell.iter().map(|&i| i as usize).collect());
        start = end;
    }
    Ok(out)
}
