//! The `kind = "dry"` scene: parsing with field-naming errors, the critical-step refusal, and a small run
//! writing stress_strain.csv, broken_bonds.csv, VTK snapshots and summary.json.
use std::path::PathBuf;

use lbdem::app::{check, run, RunOptions};
use lbdem::kinds::dry::Dry;
use lbdem::output::vtk::parse_vtk_xml;
use lbdem::run::Case;

const BUNDLED: &str = include_str!("../../scenes/uniaxial_compression.toml");

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lbdem-dry-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write_scene(name: &str, text: &str) -> PathBuf {
    let path = scratch(name).join("scene.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn bundled_scene_checks_and_prints_the_critical_step() {
    let path = write_scene("bundled", BUNDLED);
    let text = check(&path).unwrap();
    assert!(text.contains("kind = dry"), "{text}");
    assert!(text.contains("DEM critical step"), "{text}");
}

#[test]
fn bad_fields_are_named() {
    let cases = [
        ("timestep = 5e-5", "timestep = 5e-3", "solid.timestep"),
        ("friction = 0.5 ", "friction = -0.5 ", "solid.friction"),
        (
            "aspect_ratio = 1.0",
            "aspect_ratio = 1.5",
            "packing.aspect_ratio",
        ),
        (
            "platen_speed = 0.02",
            "platen_speed = 0.0",
            "loading.platen_speed",
        ),
        (
            "tensile_strength = 500.0",
            "tensile_strength = 500.0\nbogus = 1",
            "bogus",
        ),
    ];
    for (from, to, field) in cases {
        assert!(BUNDLED.contains(from), "{from}");
        let text = BUNDLED.replacen(from, to, 1);
        let err = Case::<Dry>::read(&text, "test.toml")
            .err()
            .expect("refused")
            .to_string();
        assert!(err.contains(field), "{field}: {err}");
    }
}

/// Needle-like grains are refused naming `packing.aspect_ratio` (the ellipse contact kernel is checked down to
/// b/a = 0.05; below, a sharp gap peak can fall between its sampled directions and give a phantom overlap),
/// with the reason; the limit itself and the dissertation's 0.5 are not refused for their aspect ratio.
#[test]
fn needle_grains_are_refused_naming_packing_aspect_ratio() {
    let read = |value: &str| {
        let text = BUNDLED.replacen("aspect_ratio = 1.0", &format!("aspect_ratio = {value}"), 1);
        assert_ne!(text, BUNDLED);
        Case::<Dry>::read(&text, "test.toml")
            .err()
            .map(|e| e.to_string())
    };
    for value in ["0.0499", "0.02", "0.0", "-0.5", "nan"] {
        let err = read(value).expect("refused");
        assert!(err.contains("packing.aspect_ratio"), "{value}: {err}");
        assert!(err.contains("phantom overlap"), "{value}: {err}");
    }
    for value in ["0.05", "0.5"] {
        // Thinner grains are lighter: another limit (the critical step) may still refuse the scene, but
        // not its aspect ratio.
        if let Some(err) = read(value) {
            assert!(!err.contains("aspect_ratio"), "{value}: {err}");
        }
    }
}

#[test]
fn small_dry_run_writes_its_outputs() {
    let text = BUNDLED
        .replacen("width = 2.0", "width = 1.2", 1)
        .replacen("height = 4.0", "height = 2.4", 1)
        .replacen("vtk_interval = 40", "vtk_interval = 100", 1);
    let path = write_scene("small", &text);
    let out = scratch("small").join("out");
    let summary = run(
        &path,
        &out,
        &RunOptions {
            overwrite: true,
            quiet: true,
            ..Default::default()
        },
    )
    .unwrap();
    let results = &summary["results"];
    let peak = results["test"]["peak_axial_stress"].as_f64().unwrap();
    assert!(peak > 100.0 && peak.is_finite(), "{summary}");
    let broken = results["broken_bonds"].as_u64().unwrap() as usize;
    assert!(broken > 0);
    let curve = std::fs::read_to_string(out.join("stress_strain.csv")).unwrap();
    assert!(curve.starts_with("step,axial_strain"));
    assert!(curve.lines().count() > 10);
    let breaks = std::fs::read_to_string(out.join("broken_bonds.csv")).unwrap();
    assert_eq!(breaks.lines().count(), broken + 1);
    let particles = results["particles"].as_u64().unwrap() as usize;
    let snapshots = results["vtk_snapshots"].as_u64().unwrap() as usize;
    assert!(snapshots >= 2);
    let last = std::fs::read(out.join(format!("particles_{:04}.vtp", snapshots - 1))).unwrap();
    let vtk = parse_vtk_xml(&last).expect("VTK parses");
    assert_eq!(vtk.points.len(), particles);
    let fraction = &vtk.point("broken_bond_fraction").unwrap().values;
    assert!(fraction.iter().any(|&f| f > 0.0));
    assert!(out.join("summary.json").exists());
    // A second run into the same directory is refused without --overwrite.
    let again = run(
        &path,
        &out,
        &RunOptions {
            overwrite: false,
            quiet: true,
            ..Default::default()
        },
    );
    assert!(again.is_err());
}

#[test]
fn fracture_test_dry_control_breaks_no_bonds() {
    // Dissertation ch. 6.6, without fluid: hydrostatic 50, then the axial stress (through the top boundary
    // particles) dropped to 40 with the lateral platens holding 50. A bonded sample must not fracture.
    let text = BUNDLED
        .replacen("width = 2.0", "width = 2.4", 1)
        .replacen("height = 4.0", "height = 1.2", 1)
        .replacen("vtk_interval = 40", "vtk_interval = 0", 1)
        .replacen(
            "confining_stress = 0.0   # uniaxial",
            "test = \"boundary_stress\"\naxial_stress = 40.0\nlateral_stress = 50.0\nsteps = 4000",
            1,
        )
        .replacen("platen_speed = 0.02      # cm/s each\n", "", 1)
        .replacen("max_strain = 0.05\n", "", 1);
    let path = write_scene("control", &text);
    let out = scratch("control").join("out");
    let summary = run(
        &path,
        &out,
        &RunOptions {
            overwrite: true,
            quiet: true,
            ..Default::default()
        },
    )
    .unwrap();
    let results = &summary["results"];
    assert_eq!(results["broken_bonds"].as_u64(), Some(0), "{summary}");
    let lateral = results["test"]["final_lateral_stress"].as_f64().unwrap();
    assert!((lateral - 50.0).abs() < 5.0, "lateral {lateral}");
    let curve = std::fs::read_to_string(out.join("stress_strain.csv")).unwrap();
    assert_eq!(curve.lines().count(), 1 + 4000 / 50);
}
