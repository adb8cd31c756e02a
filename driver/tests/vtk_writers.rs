//! The snapshot writers (`lbdem::output::vtk`, `lbdem::output::pvd`) against the engine state, without Python:
//! what they write is parsed back (`parse_vtk_xml`) and compared with the world's own numbers and with
//! independent physics (a point bond stretched by a known amount, the ellipse a shape tensor stands for,
//! Newton's third law on the contact forces). The real VTK library reads the same files in `vtk_readback.rs`.
use lbdem::engine::dem::*;
use lbdem::output::pvd;
use lbdem::output::vtk::*;
use lbdem::units::UnitSystem;
use lbdem_kernels::dem::assembly::ContactModel;
use lbdem_kernels::dem::shape::Particle;
use lbdem_kernels::math::vector;

fn model() -> ContactModel<f64> {
    ContactModel {
        normal_stiffness: 1e5,
        shear_stiffness: 1e5,
        friction: 0.5,
        restitution: 1.0,
        no_tension: true,
    }
}

fn stamp(time: f64) -> Stamp {
    Stamp {
        time,
        title: "writer test <&>".into(),
        units: Units::of(UnitSystem::Cgs),
    }
}

/// A squeezed, bonded block of discs after some steps: contacts, bonds carrying load, some broken.
fn loaded_block() -> Packing<f64> {
    let particles = hexagonal_packing(8, 8, 0.09, 1.0, 0.02, 2.65, 7);
    let mut p = boxed_sample(
        particles,
        model(),
        5e-5,
        Some(BondSpec::Point {
            stiffness: 1e5,
            strength: 40.0,
        }),
        0.005,
    )
    .unwrap();
    let b = p.sample_box;
    p.world.platens[b.top].control = PlatenControl::Speed(2.0);
    p.world.platens[b.bottom].control = PlatenControl::Speed(2.0);
    for _ in 0..300 {
        p.world.step();
    }
    p
}

fn values<'a>(v: &'a ParsedVtk, name: &str) -> &'a [f64] {
    &v.point(name)
        .or_else(|| v.cell(name))
        .unwrap_or_else(|| panic!("array {name} missing"))
        .values
}

#[test]
fn particle_file_holds_the_engine_state_exactly() {
    let p = loaded_block();
    let w = &p.world;
    let n = w.particles.len();
    let fluid: Vec<([f64; 2], f64)> = (0..n)
        .map(|i| ([i as f64 * 0.5, -(i as f64)], 0.25 * i as f64))
        .collect();
    let bytes = particles_vtp(&stamp(0.125), w, Some(&fluid));
    let v = parse_vtk_xml(&bytes).expect("parses");
    assert_eq!(v.kind, "PolyData");
    assert_eq!(v.time(), Some(0.125));
    assert_eq!(v.field("source").unwrap().strings, ["writer test <&>"]);
    assert_eq!(v.points.len(), n);
    assert_eq!(v.cells, (0..n).map(|i| vec![i]).collect::<Vec<_>>());
    // Every array: n tuples, finite, and a unit for each physical one.
    for a in &v.point_data {
        assert_eq!(a.values.len(), n * a.components, "{}", a.name);
        assert!(a.values.iter().all(|x| x.is_finite()), "{}", a.name);
    }
    assert_eq!(v.unit("velocity"), Some("cm/s"));
    assert_eq!(v.unit("contact_force"), Some("dyne"));
    assert_eq!(v.unit("fluid_torque"), Some("dyne*cm"));
    assert_eq!(v.unit("mass"), Some("g"));
    assert_eq!(v.unit("moment_of_inertia"), Some("g*cm^2"));
    assert_eq!(v.unit("id"), None);
    // Raw little-endian f64: bitwise the engine's numbers.
    let vel = values(&v, "velocity");
    let ang = values(&v, "angular_velocity");
    let theta = values(&v, "orientation");
    let mass = values(&v, "mass");
    let ff = values(&v, "fluid_force");
    let ft = values(&v, "fluid_torque");
    for (i, q) in w.particles.iter().enumerate() {
        assert_eq!(v.points[i], [q.position[0], q.position[1], 0.0]);
        assert_eq!(&vel[3 * i..3 * i + 3], &[q.velocity[0], q.velocity[1], 0.0]);
        assert_eq!(ang[i], q.angular_velocity);
        assert_eq!(theta[i], q.angle);
        assert_eq!(mass[i], q.mass);
        assert_eq!(values(&v, "moment_of_inertia")[i], q.moment_of_inertia);
        assert_eq!(&ff[3 * i..3 * i + 2], &fluid[i].0);
        assert_eq!(ft[i], fluid[i].1);
    }
    let speed = values(&v, "speed");
    assert!(speed.iter().any(|&s| s > 0.0), "the block moves");
    // Contacts: each grain–grain contact counted once per grain, each platen contact once.
    let count: f64 = values(&v, "contact_count").iter().sum();
    let platen_contacts: usize = w.platens.iter().map(|p| p.contacts).sum();
    assert!(w.active_contacts() > 0 && platen_contacts > 0);
    assert_eq!(count as usize, 2 * w.active_contacts() + platen_contacts);
    // Force balance of the contacts: grain–grain forces are equal and opposite (third law), so the contact
    // forces on all grains sum to what the platens push with, minus the reactions the run reports for them
    // (the platens' stresses); and the platen part alone (`wall_force`) sums to the same.
    let (cf, wf) = (values(&v, "contact_force"), values(&v, "wall_force"));
    let sum = |a: &[f64]| (0..n).fold([0.0, 0.0], |s, i| [s[0] + a[3 * i], s[1] + a[3 * i + 1]]);
    let reaction = w.platens.iter().fold([0.0, 0.0], |s, p| {
        [s[0] - p.reaction[0], s[1] - p.reaction[1]]
    });
    let scale: f64 = (0..n).map(|i| cf[3 * i].hypot(cf[3 * i + 1])).sum();
    let platen_scale: f64 = w
        .platens
        .iter()
        .map(|p| p.reaction[0].hypot(p.reaction[1]))
        .sum();
    assert!(scale > 0.0 && platen_scale > 0.0);
    // Summing ~200 pair forces and ~30 platen forces in another order: roundoff of a few ulps of the total
    // magnitude.
    for (what, s) in [("contact_force", sum(cf)), ("wall_force", sum(wf))] {
        assert!(
            (s[0] - reaction[0]).hypot(s[1] - reaction[1]) <= 1e-12 * scale,
            "{what} sums to {s:?}, the platens' reactions to {reaction:?}"
        );
    }
    // Grain by grain: the platen part is that of the grains touching a platen only, and the grain–grain part
    // (contact − wall) matches the world's own per-grain sums.
    let (grain, _) = w.contact_loads().unwrap();
    let (wall, wall_count) = w.wall_contact_loads().unwrap();
    for i in 0..n {
        assert_eq!(&wf[3 * i..3 * i + 2], &wall[i]);
        assert_eq!(cf[3 * i], grain[i][0] + wall[i][0]);
        assert_eq!(cf[3 * i + 1], grain[i][1] + wall[i][1]);
        if wall_count[i] == 0 {
            assert_eq!(&wf[3 * i..3 * i + 2], &[0.0, 0.0]);
        }
    }
    assert!(wall_count.iter().any(|&c| c > 0));
    // Bonds per grain and the broken fraction agree with the bond list.
    let bonds = values(&v, "bonds");
    assert_eq!(bonds.iter().sum::<f64>() as usize, 2 * w.bonds.len());
    assert_eq!(values(&v, "broken_bond_fraction"), w.broken_bond_fraction());
}

#[test]
fn a_grain_resting_on_a_platen_carries_its_weight_as_wall_force() {
    // One disc on a fixed horizontal platen under gravity, damped to rest: statics says the platen pushes it
    // up with its weight m g, and nothing else touches it. The file's `wall_force` and `contact_force` must
    // both say so (grain–grain contacts alone would leave the grain unbalanced), and the platen's reaction is
    // the opposite.
    let (r, g) = (0.1, 981.0);
    let disc = Particle::disc(vector(0.0, r), r, 2.65);
    let mut w = DemWorld::new(vec![disc], model(), 1e-5).unwrap();
    w.gravity = vector(0.0, -g);
    w.local_damping = 0.7;
    w.platens.push(Platen::new(
        vector(0.0, 0.0),
        vector(0.0, 1.0),
        1.0,
        PlatenControl::Speed(0.0),
    ));
    for _ in 0..20_000 {
        w.step();
    }
    let weight = w.particles[0].mass * g;
    let v = parse_vtk_xml(&particles_vtp(&stamp(0.2), &w, None)).unwrap();
    let (wf, cf) = (values(&v, "wall_force"), values(&v, "contact_force"));
    assert_eq!(values(&v, "contact_count"), [1.0]);
    assert_eq!(
        wf, cf,
        "no grain–grain contact: the contact force is the platen's"
    );
    // At rest after 20 000 damped steps (period of the contact oscillation ~ 2π√(m/k) ≈ 30 steps): the
    // residual acceleration is below 1e-9 of g.
    assert!(
        (wf[1] - weight).abs() <= 1e-9 * weight && wf[0].abs() <= 1e-9 * weight,
        "wall force {wf:?}, weight {weight}"
    );
    let reaction = w.platens[0].reaction;
    assert_eq!([-reaction[0], -reaction[1]], [wf[0], wf[1]]);
}

#[test]
fn a_world_in_lattice_units_is_written_in_physical_units() {
    // A world whose numbers are lattice units with h = 0.5 cm, Δt = 0.25 s and a mass unit of 3 g: by
    // dimensional analysis lengths are × 0.5, velocities × 2 (h/Δt), spins × 4 (1/Δt), masses × 3, moments of
    // inertia × 0.75 (m h²), forces × 24 (m h/Δt²), torques × 12 (m h²/Δt²).
    let p = loaded_block();
    let w = &p.world;
    let n = w.particles.len();
    let fluid: Vec<([f64; 2], f64)> = (0..n).map(|i| ([1.0, -2.0], i as f64)).collect();
    let scale = Scale {
        length: 0.5,
        time: 0.25,
        mass: 3.0,
    };
    let st = Stamp {
        units: Units::of(UnitSystem::Cgs).scaled(scale),
        ..stamp(1.0)
    };
    let v = parse_vtk_xml(&particles_vtp(&st, w, Some(&fluid))).unwrap();
    let one = parse_vtk_xml(&particles_vtp(&stamp(1.0), w, Some(&fluid))).unwrap();
    // Scaling by powers of two is exact, by 3, 0.75, 24 and 12 one rounding; contact_force scales its grain and
    // platen parts before adding them, so it differs from the scaled sum by a few ulps of those parts (of the
    // size of the array's largest value).
    for (name, factor) in [
        ("velocity", 2.0),
        ("speed", 2.0),
        ("angular_velocity", 4.0),
        ("semi_axes", 0.5),
        ("glyph_scale", 0.5),
        ("shape_tensor", 0.5),
        ("mass", 3.0),
        ("moment_of_inertia", 0.75),
        ("contact_force", 24.0),
        ("wall_force", 24.0),
        ("fluid_force", 24.0),
        ("fluid_torque", 12.0),
        ("orientation", 1.0),
        ("contact_count", 1.0),
    ] {
        let (a, b) = (values(&v, name), values(&one, name));
        let largest = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for (x, y) in a.iter().zip(b) {
            assert!(
                (x - factor * y).abs() <= 1e-14 * largest,
                "{name}: {x} vs {factor} × {y}"
            );
        }
    }
    for (a, b) in v.points.iter().zip(&one.points) {
        assert_eq!(*a, [0.5 * b[0], 0.5 * b[1], 0.0]);
    }
    assert_eq!(v.unit("velocity"), Some("cm/s"));
}

#[test]
fn shape_tensor_and_glyph_scale_describe_the_true_ellipse() {
    // An ellipse at 30°: the tensor's eigenvectors are the body axes, its eigenvalues the full axes 2a, 2b
    // (ParaView's Tensor Glyph scales a unit-diameter sphere by them), and the out-of-plane one 2b.
    let q = Particle::ellipse(vector(1.0, 2.0), 30f64.to_radians(), 0.3, 0.1, 2.65);
    let w = DemWorld::new(vec![q], model(), 1e-5).unwrap();
    let v = parse_vtk_xml(&particles_vtp(&stamp(0.0), &w, None)).unwrap();
    let t = values(&v, "shape_tensor");
    let (s, c) = 30f64.to_radians().sin_cos();
    let apply = |x: [f64; 3]| -> [f64; 3] {
        [
            t[0] * x[0] + t[1] * x[1] + t[2] * x[2],
            t[3] * x[0] + t[4] * x[1] + t[5] * x[2],
            t[6] * x[0] + t[7] * x[1] + t[8] * x[2],
        ]
    };
    for (axis, lambda) in [
        ([c, s, 0.0], 0.6),
        ([-s, c, 0.0], 0.2),
        ([0.0, 0.0, 1.0], 0.2),
    ] {
        let y = apply(axis);
        for k in 0..3 {
            // Products of O(1) numbers: roundoff only.
            assert!(
                (y[k] - lambda * axis[k]).abs() < 1e-14,
                "T·e = {y:?}, λ = {lambda}"
            );
        }
    }
    assert_eq!(values(&v, "glyph_scale"), [0.6, 0.2, 0.2]);
    assert_eq!(values(&v, "semi_axes"), [0.3, 0.1, 0.0]);
    let m = values(&v, "major_axis");
    assert!((m[0] - c).abs() < 1e-15 && (m[1] - s).abs() < 1e-15);
    // No fluid: no fluid arrays; a lone grain touches nothing (its contact loads, those of the next step, are 0).
    assert!(v.point("fluid_force").is_none());
    assert_eq!(values(&v, "contact_count"), [0.0]);
}

#[test]
fn point_bond_stretched_by_a_known_amount() {
    // Two discs bonded at touch, then j moved 1e-3 cm away along the bond: eq. 6.13 gives a tensile force
    // k_b δ on each (normal force −k_b δ, compression positive), no shear, stretch δ.
    let (r, k, strength) = (0.1, 1e5, 700.0);
    let a = Particle::disc(vector(0.0, 0.0), r, 2.65);
    let b = Particle::disc(vector(2.0 * r, 0.0), r, 2.65);
    let mut w = DemWorld::new(vec![a, b], model(), 1e-5).unwrap();
    w.bond_touching_pairs(
        BondSpec::Point {
            stiffness: k,
            strength,
        },
        1e-6,
    )
    .unwrap();
    assert_eq!(w.bonds.len(), 1);
    let delta = 1e-3;
    w.particles[1].position[0] += delta;
    let clock = BreakClock {
        origin_step: 0,
        dt: 1e-5,
    };
    let v = parse_vtk_xml(&bonds_vtp(&stamp(0.5), &w, clock)).unwrap();
    assert_eq!(v.cells, vec![vec![0, 1]]);
    assert_eq!(values(&v, "pair"), [0.0, 1.0]);
    assert_eq!(values(&v, "intact"), [1.0]);
    assert_eq!(values(&v, "break_mode"), [0.0]);
    assert_eq!(values(&v, "break_time"), [-1.0]);
    // Differences of positions of size 0.2 cm: roundoff of ~1e-16 cm on δ = 1e-3 cm, i.e. ~1e-13 relative.
    let rel = |x: f64, y: f64| (x - y).abs() <= 1e-10 * y.abs();
    assert!(
        rel(values(&v, "stretch")[0], delta),
        "{:?}",
        values(&v, "stretch")
    );
    assert!(rel(values(&v, "normal_force")[0], -k * delta));
    assert!(values(&v, "shear_force")[0].abs() < 1e-9);
    assert!(rel(values(&v, "strength_ratio")[0], k * delta / strength));
    assert_eq!(v.unit("normal_force"), Some("dyne"));
    assert_eq!(v.unit("stretch"), Some("cm"));
    assert_eq!(v.unit("break_time"), Some("s"));
}

#[test]
fn broken_bonds_carry_their_break_time_and_mode() {
    let p = loaded_block();
    let w = &p.world;
    assert!(!w.breaks.is_empty(), "the squeeze breaks bonds");
    let clock = BreakClock {
        origin_step: 100,
        dt: 5e-5,
    };
    let v = parse_vtk_xml(&bonds_vtp(&stamp(1.0), w, clock)).unwrap();
    let m = w.bonds.len();
    assert_eq!(v.cells.len(), m);
    for a in &v.cell_data {
        assert_eq!(a.values.len(), m * a.components, "{}", a.name);
        assert!(a.values.iter().all(|x| x.is_finite()), "{}", a.name);
    }
    let (mode, time, intact) = (
        values(&v, "break_mode"),
        values(&v, "break_time"),
        values(&v, "intact"),
    );
    for rec in &w.breaks {
        let k = w.bonds.iter().position(|b| b.pair == rec.pair).unwrap();
        assert_eq!(intact[k], 0.0);
        assert_eq!(mode[k], break_mode_code(rec.mode) as f64);
        assert_eq!(time[k], rec.step.saturating_sub(100) as f64 * 5e-5);
        // A broken bond carries nothing.
        assert_eq!(values(&v, "normal_force")[k], 0.0);
    }
    let broken = intact.iter().filter(|&&x| x == 0.0).count();
    assert_eq!(broken, w.bonds.len() - w.intact_bonds());
    // Intact bonds are loaded; broken ones have ratio 0.
    let ratio = values(&v, "strength_ratio");
    assert!(ratio.iter().zip(intact).any(|(&r, &i)| i == 1.0 && r > 0.0));
    assert!(ratio
        .iter()
        .zip(intact)
        .all(|(&r, &i)| i == 1.0 || r == 0.0));
}

#[test]
fn lattice_file_holds_the_field() {
    let (nx, ny) = (5, 3);
    let f = Field {
        nodes: [nx, ny],
        origin: [-0.5, 0.25],
        spacing: 0.01,
        pressure: (0..nx * ny).map(|k| k as f64 * 1.5).collect(),
        velocity: (0..nx * ny).map(|k| [k as f64, -(k as f64)]).collect(),
        solid_fraction: (0..nx * ny).map(|k| (k % 3) as f64 * 0.5).collect(),
        node_kind: (0..nx * ny).map(|k| (k % 4) as u8).collect(),
    };
    let v = parse_vtk_xml(&lattice_vti(&stamp(2.5), &f)).unwrap();
    assert_eq!(v.kind, "ImageData");
    assert_eq!(v.attributes["WholeExtent"], "0 4 0 2 0 0");
    let origin: Vec<f64> = v.attributes["Origin"]
        .split(' ')
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(origin, [-0.5, 0.25, 0.0]);
    assert_eq!(v.time(), Some(2.5));
    // Float32 in the file: these small integers and halves are exact in f32.
    assert_eq!(values(&v, "pressure"), f.pressure);
    let vel: Vec<f64> = f.velocity.iter().flat_map(|u| [u[0], u[1], 0.0]).collect();
    assert_eq!(values(&v, "velocity"), vel);
    assert_eq!(values(&v, "solid_fraction"), f.solid_fraction);
    let kinds: Vec<f64> = f.node_kind.iter().map(|&k| k as f64).collect();
    assert_eq!(values(&v, "node_kind"), kinds);
    assert_eq!(v.unit("pressure"), Some("dyne/cm^2"));
    assert_eq!(v.unit("solid_fraction"), Some("1"));
}

#[test]
fn collection_lists_the_snapshots_so_far_and_a_resume_rewrites_it() {
    let dir = std::env::temp_dir().join(format!("lbdem-pvd-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (i, t) in [0.0, 0.05, 0.1].into_iter().enumerate() {
        pvd::write_snapshot(&dir, "particles", i, t, "vtp", b"x").unwrap();
    }
    let read = || pvd::parse(&std::fs::read_to_string(dir.join("particles.pvd")).unwrap()).unwrap();
    let e = read();
    assert_eq!(
        e.iter()
            .map(|e| (e.time, e.file.as_str()))
            .collect::<Vec<_>>(),
        [
            (0.0, "particles_0000.vtp"),
            (0.05, "particles_0001.vtp"),
            (0.1, "particles_0002.vtp")
        ]
    );
    // A run resumed from a checkpoint taken after snapshot 0 writes snapshot 1 again: the collection then
    // lists 0 and 1 only, until the resumed run writes 2.
    pvd::record(&dir, "particles", 1, 0.05, "particles_0001.vtp").unwrap();
    assert_eq!(read().len(), 2);
    assert_eq!(read()[1].time, 0.05);
    assert!(
        !dir.join("particles.pvd.tmp").exists(),
        "written atomically"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn parser_refuses_damaged_files() {
    let p = loaded_block();
    let bytes = particles_vtp(&stamp(0.0), &p.world, None);
    // Truncated: the last arrays run past the end.
    assert!(parse_vtk_xml(&bytes[..bytes.len() - 100]).is_err());
    // Not a VTK XML file with appended data.
    assert!(parse_vtk_xml(b"# vtk DataFile Version 3.0\n").is_err());
}

#[test]
fn grains_held_fixed_are_written_at_rest_with_the_lattice_force_on_them() {
    use lbdem::engine::lattice::{FluidDisc, FluidLattice};
    use lbdem::output::snapshots::{disc_grain, write_fixed, FixedSnapshots};
    use lbdem_kernels::fluid::boundary::Boundaries;
    use lbdem_kernels::fluid::collide::SolidOperator;
    use lbdem_kernels::fluid::step::FluidParams;
    // A disc held fixed in a periodic cell of 20 nodes (h = 0.01 cm, Δt = 1e-4 s), the fluid driven past it.
    let section: lbdem::units::FluidSection =
        toml::from_str("density = 1.0\nviscosity = 0.1\nspacing = 0.01\ntau = 0.8\n").unwrap();
    let units = section.lattice_units().unwrap();
    let mut lattice = FluidLattice::<f64>::new(
        20,
        20,
        Boundaries::periodic(),
        FluidParams {
            tau: 0.8,
            force: [1e-5, 0.0],
        },
    )
    .unwrap();
    let disc = FluidDisc {
        center: [9.5, 9.5],
        radius: 4.0,
        velocity: [0.0; 2],
        spin: 0.0,
    };
    let op = SolidOperator::NonEquilibriumBounceBack;
    lattice.set_solid_operator(op);
    lattice.cover_with_discs(&[disc], op.weighting());
    for _ in 0..50 {
        lattice.step();
    }
    let dir = std::env::temp_dir().join(format!("lbdem-fixed-writer-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let at = FixedSnapshots::new(
        &dir,
        (Some("fixed"), "cylinder_array", UnitSystem::Cgs),
        units,
    );
    let grain = disc_grain(&disc, units.spacing);
    let frame = LatticeFrame::of(&units, [0.0; 2], 1.0);
    write_fixed(&at.case(2), 0, 0.005, &[grain], &lattice, &frame).unwrap();
    // Case 2's group: its own collections, nothing else.
    for f in ["particles_case2.pvd", "lattice_case2.pvd"] {
        let entries = pvd::parse(&std::fs::read_to_string(dir.join(f)).unwrap()).unwrap();
        assert_eq!(entries.len(), 1, "{f}");
        assert_eq!(entries[0].time, 0.005, "{f}");
    }
    assert!(!dir.join("particles.pvd").exists());
    let v = parse_vtk_xml(&std::fs::read(dir.join("particles_case2_0000.vtp")).unwrap()).unwrap();
    let values = |name: &str| v.point(name).unwrap().values.clone();
    // The disc in cm: centre 9.5 h, semi-axes 4 h (one product each, as the writer's).
    assert_eq!(v.points, vec![[9.5 * 0.01, 9.5 * 0.01, 0.0]]);
    assert_eq!(values("semi_axes"), vec![4.0 * 0.01, 4.0 * 0.01, 0.0]);
    // Held fixed: at rest, m = I = +∞ written as −1, no contact, no bond.
    assert_eq!(values("velocity"), vec![0.0; 3]);
    assert_eq!(values("angular_velocity"), vec![0.0]);
    assert_eq!(values("mass"), vec![-1.0]);
    assert_eq!(values("moment_of_inertia"), vec![-1.0]);
    assert_eq!(values("contact_force"), vec![0.0; 3]);
    assert_eq!(values("contact_count"), vec![0.0]);
    assert_eq!(values("bonds"), vec![0.0]);
    // The fluid's force: the lattice's own PSM force on the disc in dyne per unit thickness (the same
    // conversion, bitwise), pushed along the drive.
    let f = lattice.solid_forces(1)[0];
    let want = [units.force_to_physical(f[0]), units.force_to_physical(f[1])];
    let got = values("fluid_force");
    assert_eq!(got, vec![want[0], want[1], 0.0]);
    assert!(got[0] > 0.0, "the fluid drags the disc along +x: {got:?}");
    assert_eq!(v.unit("fluid_force"), Some("dyne"));
    // The lattice: the cell's nodes, the disc covering its area π r² (ε in f32: 2^-24 relative each, summed).
    let l = parse_vtk_xml(&std::fs::read(dir.join("lattice_case2_0000.vti")).unwrap()).unwrap();
    assert_eq!(l.attributes["WholeExtent"], "0 19 0 19 0 0");
    let eps = &l.point("solid_fraction").unwrap().values;
    assert!(eps.iter().all(|e| (0.0..=1.0).contains(e)));
    let area = std::f64::consts::PI * 16.0;
    let covered: f64 = eps.iter().sum();
    assert!(
        (covered - area).abs() <= 1e-6 * area,
        "covered {covered} nodes, the disc {area}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
