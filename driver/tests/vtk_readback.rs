//! Every VTK output of a tiny run of every kind that writes snapshots (`fracture` with a fluid, `dry`,
//! `coupled_demo`, `terminal_velocity`, `consolidation`, `terzaghi`), read back twice: by the Rust-side parser
//! (`lbdem::output::vtk::parse_vtk_xml`), and by the real VTK library from Python
//! (`driver/tests/vtk_readback.py`, the `vtk` package of PyPI), each checking array names, sizes, finiteness
//! and values against `summary.json` and the CSV tables of the same run.
//!
//! Without `python3` and its `vtk` package the Python half is skipped with a loud message on a developer
//! machine, and fails with `LBDEM_REQUIRE_VTK=1` (what `.ci/run` sets, after installing `vtk`) or with `CI` set
//! to a true value. Install: `python3 -m pip install vtk==9.7.1`.
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use lbdem::output::pvd;
use lbdem::output::vtk::{parse_vtk_xml, ParsedVtk};

fn bundled(rel: &str) -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../scenes")
            .join(rel),
    )
    .unwrap()
}

fn edit(text: &str, edits: &[(&str, &str)]) -> String {
    let mut t = text.to_string();
    for (from, to) in edits {
        assert!(t.contains(from), "`{from}` not in the scene");
        t = t.replacen(from, to, 1);
    }
    t
}

/// Run `scene` into a fresh directory and return it.
fn run(name: &str, scene: &str) -> PathBuf {
    let root = std::env::temp_dir().join(format!("lbdem-vtk-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    let path = root.join("scene.toml");
    std::fs::write(&path, scene).unwrap();
    let out = root.join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_lbdem"))
        .args([
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{name} run failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

/// The tiny runs, made once for both tests of this file.
fn runs() -> &'static [(&'static str, PathBuf)] {
    static RUNS: OnceLock<Vec<(&'static str, PathBuf)>> = OnceLock::new();
    RUNS.get_or_init(|| {
        // The quick fracture scene for 2 ms of model time, with a snapshot every 1 ms (3 snapshots).
        let fracture = edit(
            &bundled("fracture/quick/base.toml"),
            &[
                ("duration = 0.05 ", "duration = 0.002 "),
                ("record_interval = 5e-4 ", "record_interval = 2e-4 "),
                ("snapshot_interval = 0.025", "snapshot_interval = 1e-3"),
                ("permeability = true", "permeability = false"),
            ],
        );
        let dry = edit(
            &bundled("uniaxial_compression.toml"),
            &[
                ("width = 2.0", "width = 0.8"),
                ("height = 4.0", "height = 0.8"),
                ("vtk_interval = 40", "vtk_interval = 4"),
                (
                    "confining_stress = 0.0   # uniaxial",
                    "test = \"boundary_stress\"\naxial_stress = 40.0\nlateral_stress = 50.0\nsteps = 600",
                ),
                ("platen_speed = 0.02      # cm/s each\n", ""),
                ("max_strain = 0.05\n", ""),
            ],
        );
        // The other kinds with grains: the tiny scenes of `every_kind.rs`, with their default snapshot interval
        // (a tenth of the run).
        // The demo at τ = 2.2, above the ΩΛ stability bound for its grains, so it runs BGK + Ω₁ₗ: there the file's
        // velocity is (Σ f c + F/2)/ρ at every node and Σ ρu must equal series.csv's fluid momentum. Under ΩΛ (the
        // default below τ = 2) the velocity at covered nodes is the one its collision uses, with the solids'
        // friction (docs/outputs.md), so that identity does not hold there by design; the fracture run above
        // covers the ΩΛ files.
        let demo = "[scene]\nkind = \"coupled_demo\"\n[demo]\nnx = 32\nny = 32\ntau = 2.2\ndiscs = 3\n\
                    radius = 4.0\nspeed = 0.01\nsteps = 200\nrecord_interval = 10\n";
        // The tiny scenes of `every_kind.rs` where the two tests need the same ones.
        let tiny = crate::every_kind::tiny_scenes();
        let tiny = |kind: &str| {
            tiny.iter()
                .find(|t| t.0 == kind)
                .map(|t| t.1.clone())
                .unwrap_or_else(|| panic!("every_kind has no tiny {kind} scene"))
        };
        let terminal = tiny("terminal_velocity");
        let consolidation = edit(
            &bundled("consolidation.toml"),
            &[
                ("columns = 10", "columns = 4"),
                ("rows = 8", "rows = 3"),
                ("duration = 1.0 ", "duration = 0.4 "),
            ],
        );
        let terzaghi = edit(
            &bundled("terzaghi.toml"),
            &[
                ("height = 2.4 ", "height = 1.0 "),
                ("duration = 10.0 ", "duration = 0.6 "),
                ("record_interval = 0.25 ", "record_interval = 0.1 "),
            ],
        );
        // The kinds whose grains are held fixed in the fluid: the tiny scenes of `every_kind.rs` (two cases of a
        // sweep each; the drainage's two profiles).
        let cylinder_array = tiny("cylinder_array");
        let porous_flow = tiny("porous_flow");
        let diffusion = tiny("pressure_diffusion");
        vec![
            ("cylinder_array", run("cylinder_array", &cylinder_array)),
            ("porous_flow", run("porous_flow", &porous_flow)),
            ("pressure_diffusion", run("pressure_diffusion", &diffusion)),
            ("fracture", run("fracture", &fracture)),
            ("dry", run("dry", &dry)),
            ("coupled_demo", run("coupled_demo", demo)),
            ("terminal_velocity", run("terminal_velocity", &terminal)),
            ("consolidation", run("consolidation", &consolidation)),
            ("terzaghi", run("terzaghi", &terzaghi)),
        ]
    })
}

fn csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    (header, rows)
}

fn column(table: &(Vec<String>, Vec<Vec<String>>), name: &str) -> Vec<String> {
    let k = table.0.iter().position(|h| h == name).unwrap();
    table.1.iter().map(|r| r[k].clone()).collect()
}

/// The snapshots of a series: (time, parsed file), checking the collection against the files on disk.
fn series(dir: &Path, name: &str) -> Vec<(f64, ParsedVtk)> {
    let text = std::fs::read_to_string(dir.join(format!("{name}.pvd"))).unwrap();
    let entries = pvd::parse(&text).expect("a .pvd collection");
    let mut on_disk: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|f| {
            f.starts_with(&format!("{name}_")) && (f.ends_with(".vtp") || f.ends_with(".vti"))
        })
        .collect();
    on_disk.sort();
    let listed: Vec<String> = entries.iter().map(|e| e.file.clone()).collect();
    assert_eq!(
        listed, on_disk,
        "{name}.pvd lists every snapshot file, in order"
    );
    assert!(
        entries.len() >= 2,
        "{name}: at least the first and last snapshot"
    );
    assert!(
        entries.windows(2).all(|w| w[1].time > w[0].time),
        "{name}: times increase"
    );
    entries
        .iter()
        .map(|e| {
            let v = parse_vtk_xml(&std::fs::read(dir.join(&e.file)).unwrap())
                .unwrap_or_else(|err| panic!("{}: {err}", e.file));
            assert_eq!(
                v.time(),
                Some(e.time),
                "{}: TIME = the collection's time",
                e.file
            );
            (e.time, v)
        })
        .collect()
}

fn finite_and_sized(
    file: &str,
    arrays: &[lbdem::output::vtk::ParsedArray],
    tuples: usize,
    v: &ParsedVtk,
) {
    for a in arrays {
        assert_eq!(a.values.len(), tuples * a.components, "{file}: {}", a.name);
        assert!(
            a.values.iter().all(|x| x.is_finite()),
            "{file}: {} not finite",
            a.name
        );
        let unitless = [
            "id",
            "contact_count",
            "bonds",
            "intact",
            "pair",
            "break_mode",
            "node_kind",
        ];
        if !unitless.contains(&a.name.as_str()) {
            assert!(
                v.unit(&a.name).is_some_and(|u| !u.is_empty()),
                "{file}: no unit for {}",
                a.name
            );
        }
    }
}

/// What a run of a kind must have written, from its `summary.json`.
struct Expect {
    grains: usize,
    /// Bonds (`None`: no bond series).
    bonds: Option<usize>,
    /// Lattice nodes (`None`: no lattice series, no fluid arrays on the grains).
    nodes: Option<[usize; 2]>,
    /// Fraction of each grain's size the fluid sees.
    fluid_radius: f64,
    /// Grains held fixed in the fluid (mass −1, at rest, no contact).
    fixed: bool,
}

fn expect(kind: &str, s: &serde_json::Value) -> Expect {
    let (r, sc) = (&s["results"], &s["scene"]);
    let n = |v: &serde_json::Value| v.as_u64().unwrap() as usize;
    let nodes = |v: &serde_json::Value| Some([n(&v[0]), n(&v[1])]);
    match kind {
        "fracture" => Expect {
            grains: n(&r["packing"]["particles"]),
            bonds: Some(n(&r["total_bonds"])),
            nodes: nodes(&r["fluid"]["nodes"]),
            fluid_radius: sc["fluid"]["fluid_radius"].as_f64().unwrap(),
            fixed: false,
        },
        "dry" => Expect {
            grains: n(&r["particles"]),
            bonds: Some(n(&r["bonds"])),
            nodes: None,
            fluid_radius: 1.0,
            fixed: false,
        },
        "coupled_demo" => Expect {
            grains: n(&sc["demo"]["discs"]),
            bonds: None,
            nodes: Some([n(&sc["demo"]["nx"]), n(&sc["demo"]["ny"])]),
            fluid_radius: 1.0,
            fixed: false,
        },
        "terminal_velocity" => Expect {
            grains: 1,
            bonds: None,
            nodes: Some([n(&r["cell"]); 2]),
            fluid_radius: 1.0,
            fixed: false,
        },
        // A hexagonal pack of `columns` × `rows` grains.
        "consolidation" => Expect {
            grains: n(&sc["consolidation"]["columns"]) * n(&sc["consolidation"]["rows"]),
            bonds: None,
            nodes: nodes(&r["nodes"]),
            fluid_radius: sc["consolidation"]["fluid_radius"].as_f64().unwrap(),
            fixed: false,
        },
        "terzaghi" => Expect {
            grains: n(&r["grains"]),
            bonds: None,
            nodes: nodes(&r["nodes"]),
            fluid_radius: sc["terzaghi"]["fluid_radius"].as_f64().unwrap(),
            fixed: false,
        },
        "pressure_diffusion" => Expect {
            grains: n(&r["grains"]),
            bonds: None,
            nodes: nodes(&r["nodes"]),
            fluid_radius: sc["pressure_diffusion"]["fluid_radius"].as_f64().unwrap(),
            fixed: true,
        },
        other => panic!("no expectations for kind {other}"),
    }
}

/// The snapshot groups of a run: `""` (`particles.pvd`, ...), or one per case of a sweep (`"_case0"`, ...:
/// `particles_case0.pvd`, ...) with what case k must have written, from `summary.json`.
fn groups(kind: &str, s: &serde_json::Value) -> Vec<(String, Expect)> {
    let n = |v: &serde_json::Value| v.as_u64().unwrap() as usize;
    let cases = s["results"]["cases"].as_array();
    match kind {
        // One disc in a periodic cell of `cell` nodes.
        "cylinder_array" => cases
            .unwrap()
            .iter()
            .enumerate()
            .map(|(k, c)| {
                let cell = n(&c["case"]["cell"]);
                let e = Expect {
                    grains: 1,
                    bonds: None,
                    nodes: Some([cell, cell]),
                    fluid_radius: 1.0,
                    fixed: true,
                };
                (format!("_case{k}"), e)
            })
            .collect(),
        "porous_flow" => cases
            .unwrap()
            .iter()
            .enumerate()
            .map(|(k, c)| {
                let e = Expect {
                    grains: n(&c["discs"]),
                    bonds: None,
                    nodes: Some([n(&c["size"][0]), n(&c["size"][1])]),
                    fluid_radius: 1.0,
                    fixed: true,
                };
                (format!("_case{k}"), e)
            })
            .collect(),
        _ => vec![(String::new(), expect(kind, s))],
    }
}

fn last_row(table: &(Vec<String>, Vec<Vec<String>>), name: &str) -> f64 {
    column(table, name).last().unwrap().parse().unwrap()
}

#[test]
fn every_output_parses_and_agrees_with_the_tables() {
    for (kind, dir) in runs() {
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                .unwrap();
        let groups = groups(kind, &s);
        assert!(!groups.is_empty(), "{kind}: no snapshot group");
        if groups[0].0.is_empty() {
            assert!(dir.join("particles.pvd").exists(), "{kind}: particles.pvd");
        } else {
            // A sweep writes one group per case and no other.
            assert!(!dir.join("particles.pvd").exists(), "{kind}: particles.pvd");
            let k = groups.len();
            assert!(
                !dir.join(format!("particles_case{k}.pvd")).exists(),
                "{kind}: a group beyond the {k} cases"
            );
        }
        for (suffix, e) in &groups {
            check_group(kind, dir, &s, suffix, e);
        }
    }
}

/// Every check of one snapshot group (`suffix`, see [`groups`]) of the run of `kind` in `dir`.
fn check_group(kind: &str, dir: &Path, s: &serde_json::Value, suffix: &str, e: &Expect) {
    let r = &s["results"];
    let kind = &kind;
    {
        let particles = e.grains;
        let coupled = e.nodes.is_some();
        let grains = series(dir, &format!("particles{suffix}"));
        if *kind == "dry" {
            assert_eq!(grains.len() as u64, r["vtk_snapshots"].as_u64().unwrap());
        }
        let mut names = vec![
            "speed",
            "velocity",
            "shape_tensor",
            "id",
            "angular_velocity",
            "orientation",
            "major_axis",
            "semi_axes",
            "glyph_scale",
            "mass",
            "moment_of_inertia",
            "contact_force",
            "wall_force",
            "contact_count",
            "bonds",
            "broken_bond_fraction",
        ];
        if coupled {
            names.extend(["fluid_force", "fluid_torque"]);
        }
        for (t, v) in &grains {
            let file = format!("{kind} particles at {t}");
            assert_eq!(v.points.len(), particles, "{file}");
            let got: Vec<&str> = v.point_data.iter().map(|a| a.name.as_str()).collect();
            assert_eq!(got, names, "{file}");
            finite_and_sized(&file, &v.point_data, particles, v);
        }
        if e.fixed {
            // Grains held fixed: at rest, mass and moment of inertia −1 (held: +∞), no contact, no bond.
            for (t, v) in &grains {
                for (name, want) in [
                    ("velocity", 0.0),
                    ("angular_velocity", 0.0),
                    ("mass", -1.0),
                    ("moment_of_inertia", -1.0),
                    ("contact_force", 0.0),
                    ("contact_count", 0.0),
                    ("bonds", 0.0),
                ] {
                    assert!(
                        v.point(name).unwrap().values.iter().all(|&x| x == want),
                        "{kind}{suffix} at {t}: {name} of grains held fixed"
                    );
                }
            }
        }
        // The fluid pushes the grains in a coupled run: fluid forces are not all zero at the end; before the
        // first coupled step no fluid has acted yet.
        if coupled {
            let ff = |k: usize| &grains[k].1.point("fluid_force").unwrap().values;
            assert!(
                ff(grains.len() - 1).iter().any(|&f| f != 0.0),
                "{kind}: fluid forces on the grains"
            );
            assert!(
                ff(0).iter().all(|&f| f == 0.0),
                "{kind}: fluid forces at t = 0"
            );
        }
        match e.bonds {
            None => assert!(
                !dir.join("bonds.pvd").exists(),
                "{kind}: bonds without bonds"
            ),
            Some(bonds) => {
                let links = series(dir, "bonds");
                assert_eq!(links.len(), grains.len(), "{kind}");
                for (t, v) in &links {
                    let file = format!("{kind} bonds at {t}");
                    assert_eq!(v.cells.len(), bonds, "{file}");
                    finite_and_sized(&file, &v.cell_data, bonds, v);
                }
                // Recorded breaks of the last snapshot: the break table's times and modes.
                let last = &links.last().unwrap().1;
                let (mode, time) = (
                    &last.cell("break_mode").unwrap().values,
                    &last.cell("break_time").unwrap().values,
                );
                let names = ["", "tension", "shear", "compression"];
                let mut ours: Vec<(f64, &str)> = mode
                    .iter()
                    .zip(time)
                    .filter(|(m, _)| (1.0..=3.0).contains(*m))
                    .map(|(&m, &t)| (t, names[m as usize]))
                    .collect();
                let table = csv(&dir.join(if *kind == "fracture" {
                    "breaks.csv"
                } else {
                    "broken_bonds.csv"
                }));
                let mut theirs: Vec<(f64, String)> = column(&table, "time")
                    .iter()
                    .zip(column(&table, "mode"))
                    .map(|(t, m)| (t.parse().unwrap(), m))
                    .collect();
                ours.sort_by(|a, b| a.partial_cmp(b).unwrap());
                theirs.sort_by(|a, b| a.partial_cmp(b).unwrap());
                assert_eq!(
                    ours.len(),
                    theirs.len(),
                    "{kind}: recorded breaks vs the table"
                );
                assert_eq!(ours.len() as u64, r["broken_bonds"].as_u64().unwrap());
                for ((ta, ma), (tb, mb)) in ours.iter().zip(&theirs) {
                    // The table prints 10 significant digits.
                    assert!(
                        *ma == mb && (ta - tb).abs() <= 1e-9 * tb.abs().max(1e-12),
                        "{kind}: break ({ta}, {ma}) vs ({tb}, {mb})"
                    );
                }
            }
        }
        let (t_last, g) = grains.last().unwrap();
        let (m, v, w, inertia) = (
            &g.point("mass").unwrap().values,
            &g.point("velocity").unwrap().values,
            &g.point("angular_velocity").unwrap().values,
            &g.point("moment_of_inertia").unwrap().values,
        );
        let ke: f64 = (0..particles)
            .map(|i| {
                let spin = if inertia[i] < 0.0 {
                    0.0
                } else {
                    inertia[i] * w[i] * w[i]
                };
                0.5 * (m[i] * (v[3 * i] * v[3 * i] + v[3 * i + 1] * v[3 * i + 1]) + spin)
            })
            .sum();
        if *kind == "fracture" {
            // Kinetic energy of the last grain snapshot = the last history row (same time).
            let history = csv(&dir.join("history.csv"));
            let t_table = last_row(&history, "time");
            let ke_table = last_row(&history, "kinetic_energy");
            assert!(
                (t_last - t_table).abs() <= 1e-12,
                "last snapshot at {t_last}, last record at {t_table}"
            );
            // The same f64 values summed in the same order (bitwise the engine's sum) and printed in history.csv
            // with 11 significant digits.
            assert!(
                (ke - ke_table).abs() <= 1e-9 * ke_table.abs(),
                "kinetic energy {ke} vs history.csv {ke_table}"
            );
        }
        // The unit labels: the scene's system (cgs) for the physical kinds; lattice units, named as such, for
        // coupled_demo (simulated in them), in the files and in summary.json alike.
        let lattice_units = *kind == "coupled_demo";
        let want = if lattice_units {
            [
                ("velocity", "h/dt"),
                ("mass", "rho0*h^2"),
                ("angular_velocity", "rad/dt"),
            ]
        } else {
            [
                ("velocity", "cm/s"),
                ("mass", "g"),
                ("angular_velocity", "rad/s"),
            ]
        };
        for (array, unit) in want {
            assert_eq!(
                grains[0].1.unit(array),
                Some(unit),
                "{kind}: unit of {array}"
            );
        }
        let length = if lattice_units { "h" } else { "cm" };
        assert_eq!(s["units"]["length"], length, "{kind}: summary.json units");
        if *kind == "coupled_demo" {
            // The last row of series.csv (step 200) is the last snapshot: grain momentum and kinetic energy.
            let table = csv(&dir.join("series.csv"));
            assert_eq!(*t_last, last_row(&table, "step"));
            let p = (0..particles).fold([0.0, 0.0], |p, i| {
                [p[0] + m[i] * v[3 * i], p[1] + m[i] * v[3 * i + 1]]
            });
            // f64 values, the same sums; the table prints 11 significant digits.
            for (got, col) in [
                (p[0], "grain_momentum_x"),
                (p[1], "grain_momentum_y"),
                (ke, "grain_kinetic_energy"),
            ] {
                let want = last_row(&table, col);
                assert!(
                    (got - want).abs() <= 1e-9 * want.abs(),
                    "{kind}: {col} {got} vs series.csv {want}"
                );
            }
        }
        let derived = &s["derived"]["units"];
        let dt = derived["timestep"].as_f64().unwrap_or(f64::NAN);
        if *kind == "cylinder_array" {
            let k: usize = suffix.trim_start_matches("_case").parse().unwrap();
            let c = &r["cases"][k];
            // The last snapshot is the case's end, at its steps × Δt (the writer's product, exactly).
            assert_eq!(*t_last, c["steps"].as_f64().unwrap() * dt, "{kind}{suffix}");
            // The fluid's force on the disc: the PSM force the summary reports as solid_force_ratio × G l²
            // (lattice units), in dyne per unit thickness (× ρ₀ h³/Δt²).
            let (h, rho) = (
                derived["spacing"].as_f64().unwrap(),
                derived["density"].as_f64().unwrap(),
            );
            let l = c["case"]["cell"].as_f64().unwrap();
            let want = c["solid_force_ratio"].as_f64().unwrap()
                * c["case"]["force"].as_f64().unwrap()
                * l
                * l
                * rho
                * h.powi(3)
                / (dt * dt);
            let got = g.point("fluid_force").unwrap().values[0];
            // The same lattice force through other products (and the ratio's division): a few ulps.
            assert!(
                (got - want).abs() <= 1e-12 * want.abs(),
                "{kind}{suffix}: fluid force on the disc {got} vs summary {want}"
            );
        }
        if *kind == "pressure_diffusion" {
            // One snapshot before the drainage, then one at each profile of profiles.csv, at step × Δt.
            let table = csv(&dir.join("profiles.csv"));
            let mut steps: Vec<f64> = column(&table, "step")
                .iter()
                .map(|x| x.parse().unwrap())
                .collect();
            steps.dedup();
            let want: Vec<f64> = std::iter::once(0.0)
                .chain(steps.iter().map(|k| k * dt))
                .collect();
            let got: Vec<f64> = grains.iter().map(|(t, _)| *t).collect();
            assert_eq!(got, want, "{kind}: snapshot times vs profiles.csv");
        }
        if *kind == "terminal_velocity" {
            // The disc's final velocity, converted from lattice units by the writer: the summary's.
            let want = r["disc_velocity_physical"].as_f64().unwrap();
            // One product (lattice speed h/Δt) in the writer, another in the summary: a few ulps.
            assert!(
                (v[0] - want).abs() <= 1e-12 * want.abs() && v[1].abs() <= 1e-3 * want.abs(),
                "{kind}: disc velocity {:?} vs summary {want}",
                &v[..2]
            );
        }
        let Some([nx, ny]) = e.nodes else {
            assert!(
                !dir.join("lattice.pvd").exists(),
                "{kind}: a lattice without a fluid"
            );
            return;
        };
        // The lattice: the summary's size, every array finite, ε in [0, 1], the grains on it in every
        // snapshot (at t = 0 too: they are mapped before it is written).
        let lattice = series(dir, &format!("lattice{suffix}"));
        assert_eq!(lattice.len(), grains.len(), "{kind}");
        for (t, v) in &lattice {
            let file = format!("{kind} lattice at {t}");
            assert_eq!(
                v.attributes["WholeExtent"],
                format!("0 {} 0 {} 0 0", nx - 1, ny - 1),
                "{file}"
            );
            finite_and_sized(&file, &v.point_data, nx * ny, v);
            let eps = &v.point("solid_fraction").unwrap().values;
            assert!(eps.iter().all(|e| (0.0..=1.0).contains(e)), "{file}");
            assert!(
                eps.iter().any(|&e| e > 0.0),
                "{file}: grains cover the lattice"
            );
        }
        // t = 0: the grains as the fluid sees them cover Σ π a b f² of area (eq. 4.4's exact cell areas, the
        // grains apart and inside the lattice), from the particle file's semi-axes and the lattice spacing.
        let (t0, l0) = &lattice[0];
        assert_eq!(*t0, 0.0);
        let spacing: f64 = l0.attributes["Spacing"]
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let axes = &grains[0].1.point("semi_axes").unwrap().values;
        let area: f64 = (0..particles)
            .map(|i| std::f64::consts::PI * axes[3 * i] * axes[3 * i + 1])
            .sum::<f64>()
            * e.fluid_radius
            * e.fluid_radius
            / (spacing * spacing);
        let covered: f64 = l0.point("solid_fraction").unwrap().values.iter().sum();
        // ε stored as f32 (2^-24 relative each), summed over the covered nodes.
        assert!(
            (covered - area).abs() <= 1e-6 * area,
            "{kind}: the t = 0 lattice covers {covered} nodes, the grains {area}"
        );
        let pressure_unit = if lattice_units {
            "rho0*h^2/dt^2"
        } else {
            "dyne/cm^2"
        };
        assert_eq!(
            l0.unit("pressure"),
            Some(pressure_unit),
            "{kind}: pressure unit"
        );
        let (u, eps, pressure) = {
            let v = &lattice.last().unwrap().1;
            (
                v.point("velocity").unwrap().values.clone(),
                v.point("solid_fraction").unwrap().values.clone(),
                v.point("pressure").unwrap().values.clone(),
            )
        };
        if *kind == "fracture" {
            // Max fluid speed of the last snapshot (nodes with ε < 1) = history.csv's.
            let vmax = (0..nx * ny)
                .filter(|&k| eps[k] < 1.0)
                .map(|k| u[3 * k].hypot(u[3 * k + 1]))
                .fold(0.0, f64::max);
            let table = last_row(&csv(&dir.join("history.csv")), "max_fluid_speed");
            // float32 velocity components in the file: 2^-24 relative rounding, and ε rounded to f32 too.
            assert!(
                (vmax - table).abs() <= 1e-6 * table,
                "max fluid speed {vmax} vs history.csv {table}"
            );
        }
        if *kind == "coupled_demo" {
            // Lattice units: pressure (ρ − 1)/3, so the fluid mass is Σ (1 + 3p) and its momentum Σ (1 + 3p) u.
            let table = csv(&dir.join("series.csv"));
            let rho: Vec<f64> = pressure.iter().map(|p| 1.0 + 3.0 * p).collect();
            let mass: f64 = rho.iter().sum();
            let j = (0..nx * ny).fold([0.0, 0.0], |j, k| {
                [j[0] + rho[k] * u[3 * k], j[1] + rho[k] * u[3 * k + 1]]
            });
            let speed_sum: f64 = (0..nx * ny)
                .map(|k| u[3 * k].abs() + u[3 * k + 1].abs())
                .sum();
            // f32 pressure and velocity in the file: each term off by 2^-24 of itself.
            let want = last_row(&table, "fluid_mass");
            assert!(
                (mass - want).abs() <= 1e-6 * want,
                "{kind}: fluid mass {mass} vs {want}"
            );
            for (got, col) in [(j[0], "fluid_momentum_x"), (j[1], "fluid_momentum_y")] {
                let want = last_row(&table, col);
                assert!(
                    (got - want).abs() <= 1e-6 * speed_sum,
                    "{kind}: {col} {got} vs series.csv {want}"
                );
            }
        }
        if *kind == "consolidation" {
            // The last series row is the last step: its bottom pore pressure over the load is the mean pressure
            // of the fluid-only nodes (ε = 0) of the bottom grain diameter, over the load.
            let table = csv(&dir.join("series.csv"));
            assert!((t_last - last_row(&table, "time")).abs() <= 1e-12 * t_last);
            let sc = &s["scene"]["consolidation"];
            let (radius, load) = (sc["radius"].as_f64().unwrap(), sc["load"].as_f64().unwrap());
            let rows = ((2.0 * radius / spacing).round() as usize).max(1);
            let probe: Vec<f64> = (0..rows * nx)
                .filter(|&k| eps[k] == 0.0)
                .map(|k| pressure[k])
                .collect();
            let got = probe.iter().sum::<f64>() / probe.len() as f64 / load;
            let want = last_row(&table, "bottom_pressure_over_load");
            // f32 pressures (2^-24 relative) against the table's 11 digits.
            assert!(
                (got - want).abs() <= 1e-6 * want.abs().max(1e-3),
                "{kind}: bottom pressure / load {got} vs series.csv {want}"
            );
        }
    }
}

/// Whether `python3` can import `vtk` and `numpy`; the reason when not.
fn python_vtk() -> Result<String, String> {
    let o = Command::new("python3")
        .args([
            "-c",
            "import vtk, numpy; print(vtk.vtkVersion.GetVTKVersion())",
        ])
        .output()
        .map_err(|e| format!("python3 cannot be started ({e})"))?;
    if o.status.success() {
        Ok(String::from_utf8_lossy(&o.stdout).trim().to_string())
    } else {
        Err(String::from_utf8_lossy(&o.stderr).trim().to_string())
    }
}

#[test]
fn the_vtk_library_reads_every_output() {
    let required = std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false" && v != "0")
        || std::env::var("LBDEM_REQUIRE_VTK").is_ok_and(|v| v == "1");
    let version = match python_vtk() {
        Ok(v) => v,
        Err(why) if required => panic!(
            "the VTK read-back test needs python3 with the vtk package (CI or LBDEM_REQUIRE_VTK=1): {why}\n\
             install it with: python3 -m pip install vtk==9.7.1"
        ),
        Err(why) => {
            eprintln!(
                "\n==========================================================================\n\
                 SKIPPED: the_vtk_library_reads_every_output: python3 with the vtk package is\n\
                 not available ({why}).\n\
                 Install it with `python3 -m pip install vtk==9.7.1`; CI installs it and fails\n\
                 instead of skipping (as does LBDEM_REQUIRE_VTK=1).\n\
                 ==========================================================================\n"
            );
            return;
        }
    };
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/vtk_readback.py");
    for (kind, dir) in runs() {
        let o = Command::new("python3")
            .arg(&script)
            .arg(dir)
            .output()
            .unwrap();
        let out = String::from_utf8_lossy(&o.stdout);
        eprintln!("VTK {version}, {kind}:\n{out}");
        assert!(
            o.status.success(),
            "VTK read-back of the {kind} run failed:\n{out}\n{}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(
            out.contains("vtk_readback: OK"),
            "{kind}: the script did not finish"
        );
    }
}
