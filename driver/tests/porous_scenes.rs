//! The bundled fixed-solid scenes (`scenes/cylinder_array*.toml`, `scenes/porous_*.toml`) check, run and write
//! their outputs; bad `[cylinder_array]` / `[porous]` sections are refused with the field named.
use std::path::{Path, PathBuf};

use lbdem::app::{check, check_text, run, RunOptions};

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("scenes")
        .join(name)
}

fn run_bundled(name: &str) -> (serde_json::Value, PathBuf) {
    let out = std::env::temp_dir().join(format!("lbdem-porous-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let text = check(&scene_path(name)).expect("bundled scene checks");
    assert!(text.contains("is valid"), "{text}");
    let summary = run(
        &scene_path(name),
        &out,
        &RunOptions {
            overwrite: true,
            quiet: true,
            ..Default::default()
        },
    )
    .expect("bundled scene runs");
    assert!(out.join("summary.json").exists());
    assert_eq!(
        summary["results"]["all_steady"], true,
        "{name}: not all cases steady"
    );
    (summary, out)
}

#[test]
fn bundled_cylinder_array_scenes_run() {
    let (summary, out) = run_bundled("cylinder_array.toml");
    assert!(out.join("drag.csv").exists());
    let results = summary["results"]["cases"].as_array().unwrap();
    assert_eq!(results.len(), 5);
    // The drag rises steeply with the solid fraction (S&A: 51.5 → 1763 from c = 0.2 to 0.6).
    let drags: Vec<f64> = results
        .iter()
        .map(|r| r["drag"].as_f64().unwrap())
        .collect();
    assert!(drags.windows(2).all(|w| w[1] > w[0]), "{drags:?}");
    // c = 0.2 and 0.4 at l = 20 are the ≤ 6 % class of docs/references.md §1.5 (gaps 9.9 and 5.7 nodes).
    for r in &results[..3] {
        let e = r["drag_error"].as_f64().unwrap();
        assert!(e.abs() < 0.06, "{e}");
    }
    let (summary, _) = run_bundled("cylinder_array_reynolds.toml");
    let p: Vec<f64> = summary["results"]["cases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["pressure_drop"].as_f64().unwrap())
        .collect();
    assert!(p.windows(2).all(|w| w[1] < w[0]), "{p:?}");
}

#[test]
fn bundled_porous_scenes_run() {
    let (summary, out) = run_bundled("porous_darcy.toml");
    assert!(out.join("runs.csv").exists());
    let fit = &summary["results"]["darcy_fits"][0];
    // See driver/tests/porous.rs for the R² ≥ 0.999 argument.
    assert!(fit["r_squared"].as_f64().unwrap() >= 0.999, "{fit}");
    assert!(fit["intercept_relative"].as_f64().unwrap().abs() < 0.01);
    let (summary, _) = run_bundled("porous_kozeny.toml");
    let ck = summary["results"]["fitted_kozeny_constant"]
        .as_f64()
        .unwrap();
    // Same geometry as the Kozeny test in driver/tests/porous.rs (diameters rounded to 1e-6 cm).
    assert!((8.8..=11.3).contains(&ck), "{ck}");
}

fn refused(text: &str, field: &str) {
    let err = check_text(text, "test")
        .err()
        .unwrap_or_else(|| panic!("scene with bad {field} accepted"));
    let msg = err.to_string();
    assert!(msg.contains(field), "error does not name {field}: {msg}");
}

const HEAD: &str = "[scene]\nunits = \"cgs\"\n[fluid]\ndensity = 1.0\nviscosity = 0.1\nspacing = 0.01\ntau = 0.8\n\
                    [run]\nsteps = 10\n";

#[test]
fn bad_sections_are_refused_with_the_field_named() {
    let a = |body: &str| {
        format!("{HEAD}[cylinder_array]\n{body}")
            .replace("[scene]\n", "[scene]\nkind = \"cylinder_array\"\n")
    };
    refused(
        &a("cell = 0.2\nsolid_fractions = [0.8]\nacceleration = 1.0\n"),
        "cylinder_array.solid_fractions",
    );
    refused(
        &a("cell = 0.2\nsolid_fractions = [0.4]\nacceleration = 1.0\nreynolds = [1.0]\n"),
        "cylinder_array.acceleration",
    );
    refused(
        &a("cell = 0.2\nsolid_fractions = [0.4]\nacceleration = 1.0\ncolour = 1\n"),
        "colour",
    );
    let p = |body: &str| {
        format!("{HEAD}[porous]\n{body}").replace("[scene]\n", "[scene]\nkind = \"porous_flow\"\n")
    };
    let ok = "rows = 1\npitch = 0.2\ndiameters = [0.1]\npressure_drops = [1.0]\n";
    refused(&p(&format!("columns = 3\n{ok}")), "porous.columns");
    refused(
        &p(&format!("columns = 4\n{ok}jitter = 1.0\n")),
        "porous.jitter",
    );
    refused(
        &p("columns = 4\nrows = 1\npitch = 0.2\ndiameters = [0.3]\npressure_drops = [1.0]\n"),
        "porous.diameters",
    );
    refused(
        &HEAD.replace("[scene]\n", "[scene]\nkind = \"porous_flow\"\n"),
        "porous",
    );
    // A valid section passes.
    let good = p(&format!("columns = 4\n{ok}"));
    check_text(&good, "test").unwrap();
}
