//! `lbdem study speed-vs-error --quick`: the command writes a well-formed CSV (one row per problem ×
//! precision × resolution of the quick plan), a real PNG, and the f64 errors fall with resolution.
//! Wall times are never asserted (the machine is shared).
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::Command;

use lbdem::study::StudyPlan;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lbdem-study-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

const COLUMNS: [&str; 12] = [
    "problem",
    "precision",
    "resolution",
    "tau",
    "method",
    "nodes",
    "steps",
    "wall_seconds",
    "mlups",
    "relative_error",
    "signed_error",
    "threads",
];

#[test]
fn quick_study_writes_csv_and_png_and_f64_errors_fall_with_resolution() {
    let out = scratch("quick");
    let o = Command::new(env!("CARGO_BIN_EXE_lbdem"))
        .args([
            "study",
            "speed-vs-error",
            "--quick",
            "--threads",
            "1",
            "--out",
        ])
        .arg(&out)
        .output()
        .expect("lbdem runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "study failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );

    // CSV: header, then problem × precision × resolution rows of the quick plan.
    let text = std::fs::read_to_string(out.join("speed_vs_error.csv")).expect("CSV written");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    assert_eq!(header, COLUMNS);
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let plan = StudyPlan::quick();
    let expected: usize = plan
        .ladders
        .iter()
        .map(|(p, l)| 2 * l.len() * plan.variants(*p).len())
        .sum();
    assert_eq!(rows.len(), expected, "rows: {rows:?}");
    type Variant = (String, String, String, String);
    let mut errors: BTreeMap<Variant, Vec<(usize, f64)>> = BTreeMap::new();
    for r in &rows {
        assert_eq!(r.len(), COLUMNS.len(), "row {r:?}");
        assert!(r[1] == "f32" || r[1] == "f64", "precision in {r:?}");
        let resolution: usize = r[2].parse().expect("resolution is an integer");
        let tau: f64 = r[3].parse().expect("tau is a number");
        assert!(tau > 0.5, "{r:?}");
        let steps: u64 = r[6].parse().expect("steps is an integer");
        assert!(steps > 0, "{r:?}");
        for c in [7, 8, 9] {
            let v: f64 = r[c].parse().expect("numeric column");
            assert!(v.is_finite() && v >= 0.0, "column {} in {r:?}", COLUMNS[c]);
        }
        let err: f64 = r[9].parse().unwrap();
        // Every quick case is resolved well enough to be within 30 % (the coarsest array, l = 10 with 2.9
        // nodes across the gap, is the worst: docs/references.md §1.5 puts ≈ 3 gap nodes in the tens-of-percent class).
        assert!(err > 0.0 && err < 0.3, "error out of range in {r:?}");
        errors
            .entry((
                r[0].to_string(),
                r[3].to_string(),
                r[4].to_string(),
                r[1].to_string(),
            ))
            .or_default()
            .push((resolution, err));
    }
    for (problem, ladder) in &plan.ladders {
        for (tau, method) in plan.variants(*problem) {
            let key = |precision: &str| {
                (
                    problem.name().to_string(),
                    tau.to_string(),
                    method.to_string(),
                    precision.to_string(),
                )
            };
            for precision in ["f32", "f64"] {
                let got = &errors[&key(precision)];
                let resolutions: Vec<usize> = got.iter().map(|x| x.0).collect();
                assert_eq!(&resolutions, ladder, "{} {precision}", problem.name());
            }
            // f64: the error is discretisation error (second order for the channels, ≈ first order for the
            // staircase-free PSM array), so every refinement by ≥ 1.8× in resolution must cut it by at least
            // 1.5×.
            let f64s = &errors[&key("f64")];
            for w in f64s.windows(2) {
                assert!(
                    w[1].1 < w[0].1 / 1.5,
                    "{} τ = {tau} {method}: f64 error does not fall with resolution: {:?}",
                    problem.name(),
                    f64s
                );
            }
        }
    }

    // PNG: signature, IHDR with the plot's size, and more than a blank canvas (a white 1100 × 760 PNG
    // compresses to a few kB; lines, markers and text push it well past 20 kB).
    let png = std::fs::read(out.join("speed_vs_error.png")).expect("PNG written");
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&png[12..16], b"IHDR");
    let w = u32::from_be_bytes(png[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(png[20..24].try_into().unwrap());
    assert_eq!((w, h), (1100, 760));
    assert!(png.len() > 20_000, "PNG only {} bytes", png.len());
    assert_eq!(&png[png.len() - 8..png.len() - 4], b"IEND");

    // Stdout: the markdown table and a recommendation for every budget of every problem.
    assert!(
        stdout.contains("| problem | precision | resolution |"),
        "{stdout}"
    );
    for (problem, _) in &plan.ladders {
        assert!(
            stdout.contains(&format!("**{}**", problem.name())),
            "{stdout}"
        );
    }
    assert_eq!(stdout.matches(" budget: ").count(), 3 * plan.ladders.len());
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn study_refuses_an_output_path_that_is_a_file() {
    let dir = scratch("file");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("not_a_dir");
    std::fs::write(&file, "x").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_lbdem"))
        .args(["study", "speed-vs-error", "--quick", "--out"])
        .arg(&file)
        .output()
        .expect("lbdem runs");
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("not_a_dir"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn channel_scenes_of_the_study_hold_the_lattice_speed_and_geometry() {
    use lbdem::kinds::channel::ChannelSetup;
    use lbdem::scene::Precision;
    use lbdem::study::{channel_scene, Problem, CHANNEL_LATTICE_SPEED};
    for problem in [Problem::PoiseuillePressure, Problem::PoiseuilleBodyForce] {
        for ny in [5, 21, 81] {
            let scene = channel_scene(problem, ny, Precision::F32).expect("valid study scene");
            let setup = ChannelSetup::new(&scene).expect("valid setup");
            assert_eq!(setup.ny, ny);
            let nx = match problem {
                Problem::PoiseuillePressure => 4 * ny + 1,
                _ => ny,
            };
            assert_eq!(setup.nx, nx);
            // Expected Mach = u_max/c_s with u_max = 0.01 in lattice units (c_s = 1/√3), to roundoff of the
            // unit conversion.
            let mach = CHANNEL_LATTICE_SPEED * 3f64.sqrt();
            assert!((setup.mach / mach - 1.0).abs() < 1e-9, "{}", setup.mach);
        }
    }
    assert!(channel_scene(Problem::CylinderArray, 10, Precision::F64).is_err());
    assert!(channel_scene(Problem::PoiseuillePressure, 1, Precision::F64).is_err());
}
