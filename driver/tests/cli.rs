//! The command line: bad scenes give clear errors (never a panic), a good scene writes its outputs, and a
//! previous run is not overwritten without --overwrite.
use std::path::{Path, PathBuf};
use std::process::Command;

fn lbdem() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lbdem"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lbdem-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const GOOD: &str = r#"
[scene]
kind = "channel"
units = "cgs"
[fluid]
density = 1.0
viscosity = 0.1
spacing = 0.011
tau = 0.875
[channel]
length = 0.176
width = 0.088
drive = "pressure"
pressure_drop = 1.0
[run]
steps = 300
"#;

fn run_scene(text: &str, name: &str) -> (bool, String, PathBuf) {
    let dir = scratch(name);
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    let o = lbdem()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .output()
        .unwrap();
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
        out,
    )
}

#[test]
fn good_scene_writes_summary_and_profile_and_refuses_to_overwrite() {
    let (ok, err, out) = run_scene(GOOD, "good");
    assert!(ok, "run failed: {err}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["steps"], 300);
    assert!(summary["derived"]["units"]["tau"].as_f64().unwrap() == 0.875);
    assert!(summary["results"]["error_vs_analytical"]["l2_relative"]
        .as_f64()
        .unwrap()
        .is_finite());
    let profile = std::fs::read_to_string(out.join("profile.csv")).unwrap();
    assert_eq!(
        profile.lines().count(),
        1 + 8,
        "header + 8 rows across the channel"
    );
    // A second run into the same directory is refused…
    let scene = out.parent().unwrap().join("scene.toml");
    let again = lbdem()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .output()
        .unwrap();
    assert!(!again.status.success());
    assert!(String::from_utf8_lossy(&again.stderr).contains("--overwrite"));
    // …unless told to overwrite.
    let third = lbdem()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
            "--overwrite",
        ])
        .output()
        .unwrap();
    assert!(third.status.success());
}

#[test]
fn bad_scenes_are_refused_with_the_field_named() {
    let cases = [
        (GOOD.replace("tau = 0.875", "tau = 0.875\ntua = 1.0"), "tua"),
        (GOOD.replace("tau = 0.875", "tau = 0.5"), "fluid.tau"),
        (
            GOOD.replace("width = 0.088", "width = 0.0"),
            "channel.width",
        ),
        (
            GOOD.replace("width = 0.088", "width = 0.09"),
            "channel.width",
        ),
        (
            GOOD.replace("pressure_drop = 1.0", ""),
            "channel.pressure_drop",
        ),
        (GOOD.replace("steps = 300", "steps = 0"), "run.steps"),
        (
            GOOD.replace("tau = 0.875", "tau = 0.875\ntimestep = 1e-4"),
            "fluid.tau",
        ),
        (
            GOOD.replace("units = \"cgs\"", "units = \"furlongs\""),
            "units",
        ),
        ("this is not toml [".to_string(), "not valid"),
    ];
    for (i, (text, needle)) in cases.iter().enumerate() {
        let (ok, err, _) = run_scene(text, &format!("bad{i}"));
        assert!(!ok, "case {i} should fail");
        assert!(
            err.contains(needle),
            "case {i}: message should name `{needle}`:\n{err}"
        );
        assert!(!err.contains("panicked"), "case {i} panicked:\n{err}");
    }
}

#[test]
fn check_prints_derived_parameters_without_running() {
    let dir = scratch("check");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, GOOD).unwrap();
    let o = lbdem()
        .args(["check", scene.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    for needle in ["tau", "sound speed", "expected Mach", "time step"] {
        assert!(text.contains(needle), "missing {needle} in:\n{text}");
    }
}

/// `lbdem run SCENE --out OUT --quiet EXTRA…`.
fn run_quietly(scene: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    lbdem()
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn every_simd_level_the_cpu_has_writes_the_same_profile_and_unknown_levels_are_refused() {
    let dir = scratch("simd");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, GOOD).unwrap();
    let mut profiles = Vec::new();
    for level in ["baseline", "avx2", "avx512"] {
        let out = dir.join(level);
        let o = run_quietly(&scene, &out, &["--simd", level]);
        let err = String::from_utf8_lossy(&o.stderr);
        let available =
            lbdem::engine::exec::SimdLevel::from_name(level).is_some_and(|l| l.available());
        if available {
            assert!(o.status.success(), "--simd {level} failed: {err}");
            profiles.push(std::fs::read(out.join("profile.csv")).unwrap());
        } else {
            // A level the CPU lacks is refused with the option named, not run.
            assert!(!o.status.success());
            assert!(err.contains("--simd") && err.contains(level), "{err}");
        }
    }
    assert!(!profiles.is_empty());
    assert!(
        profiles.windows(2).all(|w| w[0] == w[1]),
        "profiles differ between instruction-set levels"
    );
    let o = lbdem()
        .args(["run", scene.to_str().unwrap(), "--out"])
        .arg(dir.join("bad"))
        .args(["--simd", "sse9"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("sse9"));
}

#[test]
fn both_streaming_schemes_write_the_same_profile_and_say_which_ran() {
    let dir = scratch("streaming");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, GOOD).unwrap();
    let mut profiles = Vec::new();
    for scheme in ["aa", "two-lattice"] {
        let out = dir.join(scheme);
        let o = run_quietly(&scene, &out, &["--streaming", scheme]);
        assert!(
            o.status.success(),
            "--streaming {scheme} failed: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        profiles.push(std::fs::read(out.join("profile.csv")).unwrap());
        let summary: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
        assert_eq!(summary["execution"]["streaming"], scheme);
    }
    assert_eq!(profiles[0], profiles[1], "profiles differ between schemes");
    let o = lbdem()
        .args(["run", scene.to_str().unwrap(), "--out"])
        .arg(dir.join("bad"))
        .args(["--streaming", "esoteric"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("esoteric"));
}
