//! Every VTK output of two tiny runs (a coupled fracture scene and a dry one), read back twice: by the Rust-side
//! parser (`lbdem::output::vtk::parse_vtk_xml`), and by the real VTK library from Python
//! (`driver/tests/vtk_readback.py`, the `vtk` package of PyPI), each checking array names, sizes, finiteness
//! and values against `summary.json` and the CSV tables of the same run.
//!
//! Without `python3` and its `vtk` package the Python half is skipped with a loud message on a developer
//! machine, and fails under CI (`CI` set, as `.ci/run` runs, which installs `vtk`) or with
//! `LBDEM_REQUIRE_VTK=1`. Install: `python3 -m pip install vtk==9.7.1`.
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

/// The two tiny runs, made once for both tests of this file.
fn runs() -> &'static [(&'static str, PathBuf); 2] {
    static RUNS: OnceLock<[(&'static str, PathBuf); 2]> = OnceLock::new();
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
        [("fracture", run("fracture", &fracture)), ("dry", run("dry", &dry))]
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

#[test]
fn every_output_parses_and_agrees_with_the_tables() {
    for (kind, dir) in runs() {
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                .unwrap();
        let r = &s["results"];
        let coupled = *kind == "fracture";
        let (particles, bonds) = if coupled {
            (
                r["packing"]["particles"].as_u64().unwrap(),
                r["total_bonds"].as_u64().unwrap(),
            )
        } else {
            (
                r["particles"].as_u64().unwrap(),
                r["bonds"].as_u64().unwrap(),
            )
        };
        let (particles, bonds) = (particles as usize, bonds as usize);
        let grains = series(dir, "particles");
        if !coupled {
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
        // The fluid pushes the grains in the coupled run: fluid forces are not all zero after the drop.
        if coupled {
            let ff = &grains
                .last()
                .unwrap()
                .1
                .point("fluid_force")
                .unwrap()
                .values;
            assert!(ff.iter().any(|&f| f != 0.0), "fluid forces on the grains");
        }
        let links = series(dir, "bonds");
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
        let table = csv(&dir.join(if coupled {
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
        if coupled {
            // Kinetic energy of the last grain snapshot = the last history row (same time).
            let history = csv(&dir.join("history.csv"));
            let t_last: f64 = column(&history, "time").last().unwrap().parse().unwrap();
            let ke_table: f64 = column(&history, "kinetic_energy")
                .last()
                .unwrap()
                .parse()
                .unwrap();
            let (t, g) = grains.last().unwrap();
            assert!(
                (t - t_last).abs() <= 1e-12,
                "last snapshot at {t}, last record at {t_last}"
            );
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
            // The same f64 values summed in the same order (bitwise the engine's sum) and printed in history.csv
            // with 11 significant digits.
            assert!(
                (ke - ke_table).abs() <= 1e-9 * ke_table.abs(),
                "kinetic energy {ke} vs history.csv {ke_table}"
            );
            // The lattice: the summary's size, every array finite, ε in [0, 1].
            let nodes = &r["fluid"]["nodes"];
            let (nx, ny) = (
                nodes[0].as_u64().unwrap() as usize,
                nodes[1].as_u64().unwrap() as usize,
            );
            let lattice = series(dir, "lattice");
            assert_eq!(lattice.len(), grains.len());
            for (t, v) in &lattice {
                let file = format!("lattice at {t}");
                assert_eq!(
                    v.attributes["WholeExtent"],
                    format!("0 {} 0 {} 0 0", nx - 1, ny - 1)
                );
                finite_and_sized(&file, &v.point_data, nx * ny, v);
                let eps = &v.point("solid_fraction").unwrap().values;
                assert!(eps.iter().all(|e| (0.0..=1.0).contains(e)), "{file}");
                // The grains are mapped onto the lattice in the first coupled step: the t = 0 snapshot (before
                // it) has ε = 0 (docs/outputs.md), every later one shows them.
                assert_eq!(
                    eps.iter().any(|&e| e > 0.0),
                    *t > 0.0,
                    "{file}: grains cover the lattice"
                );
            }
            // Max fluid speed of the last snapshot (nodes with ε < 1) = history.csv's.
            let v = &lattice.last().unwrap().1;
            let (u, eps) = (
                &v.point("velocity").unwrap().values,
                &v.point("solid_fraction").unwrap().values,
            );
            let vmax = (0..nx * ny)
                .filter(|&k| eps[k] < 1.0)
                .map(|k| u[3 * k].hypot(u[3 * k + 1]))
                .fold(0.0, f64::max);
            let table: f64 = column(&history, "max_fluid_speed")
                .last()
                .unwrap()
                .parse()
                .unwrap();
            // float32 velocity components in the file: 2^-24 relative rounding, and ε rounded to f32 too.
            assert!(
                (vmax - table).abs() <= 1e-6 * table,
                "max fluid speed {vmax} vs history.csv {table}"
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
