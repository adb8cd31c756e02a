//! Every scene kind of the registry, through the command line, on a tiny scene: a real signal (SIGINT or
//! SIGTERM) in the middle of a run writes a checkpoint and exits with code 130; `lbdem resume` then finishes the
//! run with outputs byte-identical to an uninterrupted run's; and every `summary.json` validates against the one
//! summary schema, `docs/summary.schema.json`.
//!
//! The signal lands at a known step: the run is started with `LBDEM_TEST_HOLD=STEP:FILE`, so it creates FILE
//! and waits once STEP steps are done; the test sends the signal when FILE appears. Every comparison is exact.
#![cfg(unix)]
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use lbdem::kinds::REGISTRY;

fn lbdem() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lbdem"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lbdem-kinds-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn bundled(name: &str) -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../scenes")
            .join(name),
    )
    .unwrap()
}

/// Replace `from` by `to` in `text`, insisting that `from` is there (so a changed bundled scene fails loudly).
fn edit(text: &str, edits: &[(&str, &str)]) -> String {
    let mut t = text.to_string();
    for (from, to) in edits {
        assert!(t.contains(from), "`{from}` not in the scene");
        t = t.replacen(from, to, 1);
    }
    t
}

/// A tiny scene of every kind, and the step to interrupt it at.
pub(crate) fn tiny_scenes() -> Vec<(&'static str, String, u64)> {
    let channel = r#"
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
pressure_drop = 0.05
[run]
steps = 300
check_interval = 50
checkpoint_interval = 100
"#
    .to_string();
    let cylinder_array = r#"
[scene]
kind = "cylinder_array"
units = "cgs"
[fluid]
density = 1.0
viscosity = 0.1
spacing = 0.01
tau = 0.8
[cylinder_array]
cell = 0.16
solid_fractions = [0.2, 0.4]
acceleration = 0.5
[run]
steps = 400
steady_tolerance = 1e-14
check_interval = 100
"#
    .to_string();
    let porous_flow = r#"
[scene]
kind = "porous_flow"
units = "cgs"
[fluid]
density = 1.0
viscosity = 0.1
spacing = 0.01
tau = 0.8
[porous]
columns = 4
rows = 1
pitch = 0.1
diameters = [0.06]
pressure_drops = [0.005, 0.01]
[run]
steps = 300
steady_tolerance = 1e-14
check_interval = 100
"#
    .to_string();
    let terminal = edit(
        &bundled("terminal_velocity.toml"),
        &[
            ("cell = 0.44 ", "cell = 0.198 "),
            ("duration = 0.605", "duration = 0.1452"),
        ],
    );
    let diffusion = edit(
        &bundled("pressure_diffusion.toml"),
        &[
            ("width = 2.4 ", "width = 1.0 "),
            ("height = 0.8 ", "height = 0.5 "),
            (
                "fourier_times = [0.05, 0.1, 0.2, 0.35, 0.6, 1.0, 1.6]",
                "fourier_times = [0.05, 0.2]",
            ),
        ],
    );
    let compressibility = edit(
        &bundled("fluid_compressibility.toml"),
        &[
            ("length = 1.1 ", "length = 0.33 "),
            ("height = 1.1 ", "height = 0.22 "),
            ("travel = 0.011 ", "travel = 0.0022 "),
            ("settle = 0.605 ", "settle = 0.2 "),
        ],
    );
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
    let fracture = edit(
        &std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/fracture/quick/base.toml"),
        )
        .unwrap(),
        &[
            ("duration = 0.05 ", "duration = 0.002 "),
            ("record_interval = 5e-4 ", "record_interval = 2e-4 "),
            ("snapshot_interval = 0.025", "snapshot_interval = 1e-3"),
        ],
    );
    let demo = r#"
[scene]
kind = "coupled_demo"
[demo]
nx = 32
ny = 32
tau = 0.8
discs = 3
radius = 4.0
speed = 0.01
steps = 200
record_interval = 10
[run]
checkpoint_interval = 50
"#
    .to_string();
    vec![
        ("channel", channel, 150),
        ("cylinder_array", cylinder_array, 500),
        ("porous_flow", porous_flow, 400),
        ("terminal_velocity", terminal, 500),
        ("pressure_diffusion", diffusion, 200),
        ("fluid_compressibility", compressibility, 1000),
        ("consolidation", consolidation, 500),
        ("terzaghi", terzaghi, 3000),
        ("dry", dry, 300),
        ("fracture", fracture, 40),
        ("coupled_demo", demo, 100),
    ]
}

/// The tables of the tiny scenes with no data row yet at the hold (only the header), each with its reason;
/// every other table must hold a data row there.
const HEADER_ONLY_AT_THE_HOLD: &[(&str, &str)] = &[
    // Profiles are recorded at the Fourier times of the drainage, after the Darcy run, which step 200 is in.
    ("pressure_diffusion", "profiles.csv"),
    // Profiles are recorded from the load step on, after the Darcy run, which step 3000 is in.
    ("terzaghi", "profiles.csv"),
    // Its settlement is recorded with the profiles.
    ("terzaghi", "settlement.csv"),
    // The sealed column runs after the Darcy run too.
    ("terzaghi", "sealed.csv"),
    // Events: a row per broken bond; none has broken by the hold.
    ("dry", "broken_bonds.csv"),
    ("fracture", "breaks.csv"),
    // The fracture traces, found from the broken bonds: none yet.
    ("fracture", "fractures.csv"),
];

/// The scene with a periodic checkpoint after every chunk (`[run] checkpoint_interval = 1` step), so that a run
/// held at any step has written at least one periodic checkpoint.
fn checkpoint_every_chunk(text: &str) -> String {
    let mut lines: Vec<String> = text
        .lines()
        .filter(|l| !l.trim_start().starts_with("checkpoint_interval"))
        .map(String::from)
        .collect();
    match lines
        .iter()
        .position(|l| l.trim_start().starts_with("[run]"))
    {
        Some(i) => lines.insert(i + 1, "checkpoint_interval = 1".into()),
        None => lines.extend(["[run]".into(), "checkpoint_interval = 1".into()]),
    }
    lines.join("\n") + "\n"
}

/// Names of the files of `dir` whose name ends with `suffix`.
fn named(dir: &Path, suffix: &str) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(suffix))
        .collect();
    v.sort();
    v
}

/// Files of a run directory (name, bytes), without the checkpoint and the summary.
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .filter(|(n, _)| n != "summary.json" && n != "checkpoint.bin")
        .collect();
    v.sort();
    v
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// The summary without what depends on the machine, the moment or the scene file's path.
fn deterministic_part(mut s: serde_json::Value) -> serde_json::Value {
    let o = s.as_object_mut().unwrap();
    for key in [
        "wall_seconds",
        "execution",
        "segment_first_step",
        "scene_file",
    ] {
        o.remove(key);
    }
    s
}

fn schema() -> jsonschema::Validator {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/summary.schema.json"),
    )
    .unwrap();
    let schema: serde_json::Value = serde_json::from_str(&text).unwrap();
    jsonschema::validator_for(&schema).expect("docs/summary.schema.json is a valid JSON Schema")
}

fn run(scene: &Path, out: &Path, hold: Option<(u64, &Path)>) -> std::process::Child {
    let mut c = lbdem();
    c.args([
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    if let Some((step, marker)) = hold {
        c.env("LBDEM_TEST_HOLD", format!("{step}:{}", marker.display()));
    }
    c.stderr(std::process::Stdio::piped()).spawn().unwrap()
}

#[test]
fn every_kind_stops_on_a_signal_and_resumes_to_identical_outputs() {
    let schema = schema();
    let scenes = tiny_scenes();
    // One tiny scene per kind of the registry, no more, no less.
    let mut names: Vec<&str> = scenes.iter().map(|s| s.0).collect();
    names.sort_unstable();
    let mut registry: Vec<&str> = REGISTRY.iter().map(|e| e.name).collect();
    registry.sort_unstable();
    assert_eq!(names, registry);
    for (k, (kind, text, at)) in scenes.into_iter().enumerate() {
        let dir = scratch(kind);
        let scene = dir.join("scene.toml");
        std::fs::write(&scene, checkpoint_every_chunk(&text)).unwrap();
        // Uninterrupted.
        let whole = dir.join("whole");
        let o = run(&scene, &whole, None).wait_with_output().unwrap();
        assert!(
            o.status.success(),
            "{kind}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        // Interrupted at step `at` by SIGINT (even kinds) or SIGTERM (odd kinds).
        let cut = dir.join("cut");
        let marker = dir.join("held");
        let child = run(&scene, &cut, Some((at, &marker)));
        let t0 = Instant::now();
        while !marker.exists() && t0.elapsed() < Duration::from_secs(300) {
            std::thread::sleep(Duration::from_millis(5));
        }
        assert!(marker.exists(), "{kind}: never reached step {at}");
        // Held after periodic checkpoints (one per chunk), as a SIGKILL could find it: every table the whole
        // run writes is on disk with its rows so far, and no figure has been drawn (figures are drawn at the
        // end, on an interrupt and on divergence, not in the stepping loop; snapshots are not figures).
        let tables = named(&cut, ".csv");
        assert_eq!(tables, named(&whole, ".csv"), "{kind}: tables at the hold");
        for t in &tables {
            let text = std::fs::read_to_string(cut.join(t)).unwrap();
            // A header, and a data row for every table that has one by the hold.
            let header_only = HEADER_ONLY_AT_THE_HOLD.contains(&(kind, t.as_str()));
            let least = if header_only { 1 } else { 2 };
            assert!(
                text.lines().count() >= least,
                "{kind}: {t} has {} line(s) at the hold, at least {least} expected:\n{text}",
                text.lines().count()
            );
        }
        let figures: Vec<String> = named(&cut, ".png")
            .into_iter()
            .filter(|n| !n.starts_with("snapshot_") && !n.starts_with("speed_"))
            .collect();
        assert!(
            figures.is_empty(),
            "{kind}: figures drawn at a checkpoint: {figures:?}"
        );
        let signal = if k % 2 == 0 { "-INT" } else { "-TERM" };
        let killed = Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status()
            .unwrap();
        assert!(killed.success());
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(130), "{kind} ({signal}): {err}");
        assert!(
            err.contains("interrupted at step") && err.contains("lbdem resume"),
            "{kind}: {err}"
        );
        assert!(cut.join("checkpoint.bin").exists(), "{kind}: no checkpoint");
        assert!(!cut.join("summary.json").exists(), "{kind}: finished early");
        // Resumed.
        let o = lbdem()
            .args(["resume", cut.to_str().unwrap(), "--quiet"])
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{kind}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let (fa, fb) = (files(&whole), files(&cut));
        assert_eq!(
            fa.iter().map(|f| &f.0).collect::<Vec<_>>(),
            fb.iter().map(|f| &f.0).collect::<Vec<_>>(),
            "{kind}: different files"
        );
        for ((name, a), (_, b)) in fa.iter().zip(&fb) {
            assert!(a == b, "{kind}: {name} differs after the resume");
        }
        let (sa, sb) = (summary(&whole), summary(&cut));
        for s in [&sa, &sb] {
            let errors: Vec<String> = schema.iter_errors(s).map(|e| e.to_string()).collect();
            assert!(errors.is_empty(), "{kind}: summary.json: {errors:?}");
            assert_eq!(s["kind"], kind);
        }
        assert!(sb["segment_first_step"].as_u64().unwrap() >= at, "{kind}");
        assert_eq!(deterministic_part(sa), deterministic_part(sb), "{kind}");
        // `--overwrite` into the finished run's directory: accepted (every file a run writes is recognised as
        // an output), and afterwards the directory holds exactly a fresh run's files, byte for byte.
        let o = lbdem()
            .args([
                "run",
                scene.to_str().unwrap(),
                "--out",
                whole.to_str().unwrap(),
            ])
            .args(["--quiet", "--overwrite"])
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{kind}: --overwrite: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(
            files(&whole) == fa,
            "{kind}: --overwrite left a different set of files"
        );
    }
}
