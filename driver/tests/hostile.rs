//! Hostile input and faults (issue 15): every defect found by mutating scene files and by faults during runs
//! is a regression test here, and a property test mutates the bundled scenes (values, keys, structure) and
//! asserts that `check` never panics, that `check` and `run` reach the same verdict, and that every refusal
//! names a field or a line.
//!
//! The fuzzer runs `LBDEM_FUZZ_CASES` cases (default 256, a few seconds); for a long campaign:
//! `LBDEM_FUZZ_CASES=20000 cargo test -p lbdem --test integration hostile::fuzz -- --nocapture`.
use crate::common::scene_text;
use crate::common::tweaked_demo;
use scene_text::{scene, with, SCENES};
use std::path::{Path, PathBuf};
use tweaked_demo::{Tweak, Tweaked};

use lbdem::app;
use lbdem::error::LbdemError;
use lbdem::run::RunOptions;
use proptest::prelude::*;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lbdem-hostile-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn quiet() -> RunOptions {
    RunOptions {
        quiet: true,
        ..RunOptions::default()
    }
}

const DEMO: &str = r#"
[scene]
kind = "coupled_demo"
[demo]
nx = 32
ny = 32
tau = 0.8
discs = 2
radius = 4.0
speed = 0.01
steps = 40
record_interval = 10
[run]
checkpoint_interval = 20
"#;

/// `check` refuses `text` naming `field`, and `run` refuses it with the same message without creating its
/// output directory (one validation, before anything is allocated or written).
fn refused_by_both(text: &str, field: &str) -> String {
    let e = app::check_text(text, "t.toml").unwrap_err().to_string();
    assert!(
        e.contains(&format!("`{field}")),
        "expected `{field}` in: {e}"
    );
    let out = std::env::temp_dir().join(format!("lbdem-hostile-never-{}", std::process::id()));
    let r = app::run_text(text, "t.toml", &out, &quiet())
        .unwrap_err()
        .to_string();
    assert_eq!(e, r, "check and run disagree");
    assert!(!out.exists(), "run wrote {} before refusing", out.display());
    e
}

#[test]
fn sizes_that_panicked_aborted_or_hung_are_refused_by_check_and_run_naming_the_field() {
    let porous = scene("porous_darcy.toml");
    let cons = scene("consolidation.toml");
    // Was: `capacity overflow` panic.
    refused_by_both(
        &with(&porous, "columns", "9223372036854775807"),
        "porous.columns",
    );
    // Were: "memory allocation of … bytes failed" aborts, or minutes of allocation in `check`.
    refused_by_both(&with(&porous, "rows", "1000000000000000"), "porous.columns");
    refused_by_both(
        &with(&cons, "columns", "1000000000000000"),
        "consolidation.columns",
    );
    refused_by_both(&with(&cons, "columns", "10000000"), "consolidation.columns");
    let grid = with(&with(&porous, "columns", "10000"), "rows", "10000");
    refused_by_both(&grid, "porous.columns");
    // 10^6 discs on a lattice that fits in 32 bits: the pairwise narrowest-gap check would take hours.
    let grid = with(
        &with(&with(&porous, "columns", "1000"), "rows", "1000"),
        "pitch",
        "0.022",
    )
    .replace("[0.188404]", "[0.0132]");
    refused_by_both(&grid, "porous.columns");
    // Was: a DEM stiffness that implies ~3e5 sub-steps per fluid step passed check and ran without end.
    let e = refused_by_both(
        &with(&cons, "normal_stiffness", "1e15"),
        "consolidation.normal_stiffness",
    );
    assert!(e.contains("sub-steps"), "{e}");
}

#[test]
fn fuzzer_findings_are_refused_naming_the_field() {
    // A fluid margin of 1e300 in a fracture scene overflowed the lattice size (`attempt to add with
    // overflow`), found by the fuzzer at 5000 cases.
    let base = scene("fracture/base.toml");
    refused_by_both(&with(&base, "margin", "1e300"), "fluid.spacing");
    // A settling time of 1e300 s: ~1e307 settling steps (a loop without end).
    refused_by_both(&with(&base, "settle_time", "1e300"), "loading.settle_time");
}

#[test]
fn what_check_called_valid_and_run_refused_is_now_refused_by_both() {
    refused_by_both(&with(DEMO, "tau", "0.5"), "demo.tau");
    refused_by_both(&with(DEMO, "tau", "nan"), "demo.tau");
    let big = with(&with(DEMO, "nx", "1000000"), "ny", "1000000");
    refused_by_both(&big, "demo.nx");
    // A cell count that saturated to 18446744073709551615 nodes (then overflowed).
    refused_by_both(
        &with(&scene("cylinder_array.toml"), "cell", "1e300"),
        "cylinder_array.cell",
    );
    // About 4e10 grains.
    let dry = with(
        &with(&scene("uniaxial_compression.toml"), "width", "20000.0"),
        "height",
        "40000.0",
    );
    refused_by_both(&dry, "packing.width");
    // A 300-digit step count.
    let e = refused_by_both(
        &with(&scene("poiseuille.toml"), "duration", "1e300"),
        "run.duration",
    );
    assert!(e.len() < 600, "{e}");
}

#[test]
fn settings_that_gave_non_finite_results_are_refused_naming_the_input() {
    let tv = scene("terminal_velocity.toml");
    // F/(mu U) = -inf before.
    let e = refused_by_both(&with(&tv, "tau", "1e300"), "fluid.tau");
    assert!(
        e.contains("1e300"),
        "the value is quoted in scientific notation: {e}"
    );
    refused_by_both(&with(&tv, "viscosity", "1e-300"), "fluid.viscosity");
    // NaN before.
    refused_by_both(
        &with(&scene("fluid_compressibility.toml"), "settle", "1e300"),
        "fluid_compressibility.settle",
    );
    // Ran with tau = 3e302 before.
    let visc = with(
        &with(&scene("poiseuille.toml"), "viscosity", "1e300"),
        "tau",
        "0.875",
    );
    // The lattice speed squared overflows.
    refused_by_both(&visc, "fluid.viscosity");
    let visc = scene("poiseuille.toml")
        .replace("viscosity = 0.1 ", "viscosity = 1e300 ")
        .replace("tau = 0.875 ", "timestep = 1e-4 ");
    refused_by_both(&visc, "fluid.timestep");
}

#[test]
fn checkpoint_intervals_that_would_overflow_are_refused_or_saturate() {
    // Duration::from_secs_f64(3.6e303) panicked in the run loop.
    let e = refused_by_both(&with(DEMO, "checkpoint_interval", "\"1e300 h\""), "run");
    assert!(e.contains("checkpoint_interval"), "{e}");
    // u64::MAX steps: the due-check saturates instead of overflowing.
    let out = scratch("interval").join("out");
    let text = with(DEMO, "checkpoint_interval", "18446744073709551615");
    app::run_text(&text, "demo.toml", &out, &quiet()).unwrap();
}

#[test]
fn messages_name_the_kind_problem_and_the_full_key_path() {
    let pd = scene("pressure_diffusion.toml");
    let missing: String = pd
        .lines()
        .filter(|l| !l.starts_with("kind"))
        .map(|l| format!("{l}\n"))
        .collect();
    let e = refused_by_both(&missing, "scene.kind");
    assert!(
        e.contains("pressure_diffusion, fluid_compressibility"),
        "{e}"
    );
    assert!(!e.contains("unknown field"), "{e}");
    let e = refused_by_both(&with(&pd, "kind", "\"presure_diffusion\""), "scene.kind");
    assert!(e.contains("use one of: channel"), "{e}");
    let e = refused_by_both(&with(&pd, "kind", "3"), "scene.kind");
    assert!(e.contains("an integer"), "{e}");
    // Inside [solid.bonds] (an internally tagged table): the key, not only the table.
    let dry = scene("uniaxial_compression.toml");
    refused_by_both(
        &with(&dry, "tensile_strength", "\"strong\""),
        "solid.bonds.tensile_strength",
    );
    let typo = dry.replace("tensile_strength =", "tensile_strenght =");
    refused_by_both(&typo, "solid.bonds.tensile_strenght");
    // A 10 MB line is quoted cut to a sensible length.
    let long = scene("poiseuille.toml").replace(
        "name = \"poiseuille, pressure driven\"",
        &format!("name = \"{}\" oops", "x".repeat(10_000_000)),
    );
    let e = app::check_text(&long, "t.toml").unwrap_err().to_string();
    assert!(e.len() < 2000, "{} characters", e.len());
    assert!(e.contains("line "), "{e}");
}

#[test]
fn overwrite_empties_lbdems_previous_outputs_and_refuses_foreign_files() {
    let dir = scratch("overwrite");
    let out = dir.join("out");
    app::run_text(DEMO, "demo.toml", &out, &quiet()).unwrap();
    // What the run wrote is listed in its manifest.
    let manifest = std::fs::read_to_string(out.join(lbdem::output::MANIFEST_FILE)).unwrap();
    for name in ["scene.toml", "checkpoint.bin", "series.csv", "summary.json"] {
        assert!(manifest.lines().any(|l| l == name), "{name}: {manifest}");
    }
    // An output of an earlier, different run (e.g. more snapshots), written (and so listed) by lbdem: it must
    // not survive the new run.
    lbdem::output::write_atomic(&out.join("snapshot_0099.png"), b"old").unwrap();
    let mut o = quiet();
    o.overwrite = true;
    app::run_text(DEMO, "demo.toml", &out, &o).unwrap();
    assert!(!out.join("snapshot_0099.png").exists());
    assert!(out.join("summary.json").exists());
    // The user's own files, even with the extensions of lbdem's outputs: refused naming them, nothing removed.
    for mine in ["my_measurements.csv", "figure.png", "notes.txt"] {
        std::fs::write(out.join(mine), b"mine").unwrap();
        let e = app::run_text(DEMO, "demo.toml", &out, &o).unwrap_err();
        assert!(matches!(e, LbdemError::ForeignFiles { .. }), "{e}");
        assert!(e.to_string().contains(mine), "{e}");
        assert!(out.join(mine).exists() && out.join("summary.json").exists());
        std::fs::remove_file(out.join(mine)).unwrap();
    }
    // A directory lbdem wrote, without its manifest (e.g. deleted by hand): nothing is known to be lbdem's,
    // so everything is refused rather than guessed at.
    std::fs::remove_file(out.join(lbdem::output::MANIFEST_FILE)).unwrap();
    let e = app::run_text(DEMO, "demo.toml", &out, &o).unwrap_err();
    assert!(matches!(e, LbdemError::ForeignFiles { .. }), "{e}");
    // The message names the first files in sorted order (checkpoint.bin comes first of the demo's outputs).
    assert!(e.to_string().contains("checkpoint.bin"), "{e}");
    assert!(out.join("series.csv").exists() && out.join("checkpoint.bin").exists());
}

#[test]
fn resume_of_a_finished_run_says_so_and_changes_nothing() {
    let dir = scratch("finished");
    let out = dir.join("out");
    app::run_text(DEMO, "demo.toml", &out, &quiet()).unwrap();
    let before = std::fs::read(out.join("summary.json")).unwrap();
    let e = app::resume(&out, &quiet()).unwrap_err();
    assert!(matches!(e, LbdemError::AlreadyFinished { .. }), "{e}");
    assert!(e.to_string().contains("already finished"), "{e}");
    assert_eq!(std::fs::read(out.join("summary.json")).unwrap(), before);
}

/// An interrupted demo run (stopped at step 20) in a fresh directory.
fn interrupted(name: &str) -> PathBuf {
    let out = scratch(name).join("out");
    let mut o = quiet();
    o.stop_after = Some(20);
    let e = app::run_text(DEMO, "demo.toml", &out, &o).unwrap_err();
    assert!(matches!(e, LbdemError::Interrupted { .. }), "{e}");
    out
}

#[test]
fn the_checkpoint_header_is_under_the_checksum() {
    let out = interrupted("header");
    let path = out.join("checkpoint.bin");
    let mut bytes = std::fs::read(&path).unwrap();
    // magic 8, version 4, precision 1, kind length 4, kind, scene hash 32: then the step (u64).
    let at = 8 + 4 + 1 + 4 + "coupled_demo".len() + 32;
    assert_eq!(
        u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()),
        20
    );
    bytes[at + 7] ^= 0x80; // step 9223372036854775828
    std::fs::write(&path, &bytes).unwrap();
    let e = app::resume(&out, &quiet()).unwrap_err().to_string();
    assert!(e.contains("checksum"), "{e}");
    // Every single flipped byte of the header is caught.
    let good = {
        let out = interrupted("header2");
        std::fs::read(out.join("checkpoint.bin")).unwrap()
    };
    for i in 0..at + 8 + 8 {
        let mut b = good.clone();
        b[i] ^= 0x01;
        let r = lbdem::run::checkpoint::Checkpoint::from_bytes::<
            lbdem::kinds::coupled_demo::DemoState,
        >(&b, DEMO, "coupled_demo");
        assert!(r.is_err(), "flipping header byte {i} went unnoticed");
    }
}

#[test]
fn a_checkpoint_of_another_kind_is_reported_as_such() {
    let out = interrupted("mismatch");
    std::fs::write(out.join("scene.toml"), scene("poiseuille.toml")).unwrap();
    let e = app::resume(&out, &quiet()).unwrap_err().to_string();
    assert!(e.contains("checkpoint kind does not match"), "{e}");
    assert!(
        e.contains("`coupled_demo`") && e.contains("`channel`"),
        "{e}"
    );
}

#[test]
fn periodic_checkpoints_flush_the_tables() {
    // A consolidation run (chunks of 500 steps) with a periodic checkpoint every 500 steps, held at step 1000
    // before anything else is written: its series.csv is on disk although the run has neither finished nor
    // been interrupted, as it would be after a SIGKILL. (Before, checkpoints skipped the tables.)
    let text = with(
        &with(&scene("consolidation.toml"), "duration", "0.8"),
        "columns",
        "4",
    )
    .replace("rows = 8", "rows = 3")
        + "[run]\ncheckpoint_interval = 500\n";
    let dir = scratch("flush");
    let out = dir.join("out");
    let marker = dir.join("holding");
    let mut o = quiet();
    o.hold_at = Some((1000, marker.clone()));
    let stop = o.stop.clone();
    let runner = {
        let out = out.clone();
        std::thread::spawn(move || app::run_text(&text, "c.toml", &out, &o))
    };
    let t0 = std::time::Instant::now();
    while !marker.exists() && t0.elapsed() < std::time::Duration::from_secs(300) {
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    let held = marker.exists();
    let series = std::fs::read_to_string(out.join("series.csv"));
    stop.request();
    let end = runner.join().unwrap();
    assert!(held, "the run never reached step 1000: {end:?}");
    assert!(
        matches!(end, Err(LbdemError::Interrupted { step: 1000, .. })),
        "{end:?}"
    );
    let series = series.expect("series.csv written at the periodic checkpoint");
    // One row per 10 steps up to the checkpoint at step 1000 (header + 100 rows; the chunk that ended at
    // 1000 is included because the checkpoint follows it).
    assert_eq!(series.lines().count(), 101, "{series}");
}

// ---------------------------------------------------------------------------------------------------------
// The fuzzer.

/// The bundled scenes and the demo: the seeds of the mutations.
fn seeds() -> Vec<String> {
    let mut out = vec![DEMO.to_string()];
    for dir in [PathBuf::from(SCENES), Path::new(SCENES).join("fracture")] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .collect();
        files.sort();
        out.extend(files.iter().map(|p| std::fs::read_to_string(p).unwrap()));
    }
    out
}

const HOSTILE: &[&str] = &[
    "0",
    "-1",
    "1",
    "2",
    "0.5",
    "1e300",
    "-1e300",
    "1e-300",
    "nan",
    "inf",
    "-inf",
    "9223372036854775807",
    "-9223372036854775808",
    "1000000000000000",
    "10000000",
    "4294967296",
    "1e15",
    "\"x\"",
    "\"\"",
    "true",
    "[]",
    "[1e300, -1]",
    "{}",
    "\"never\"",
    "\"1e300 s\"",
    "\"-5 min\"",
    "1979-05-27",
];

const SECTIONS: &[&str] = &[
    "[scene]",
    "[fluid]",
    "[run]",
    "[packing]",
    "[solid]",
    "[solid.bonds]",
    "[loading]",
    "[porous]",
    "[demo]",
    "[[heterogeneity]]",
    "[consolidation]",
];

#[derive(Clone, Debug)]
enum Mutation {
    /// Replace the value of line `line` (mod the line count) by `HOSTILE[value]`.
    Value { line: usize, value: usize },
    /// Scale a numeric value by 10^power.
    Scale { line: usize, power: i32 },
    /// Delete a line.
    Delete { line: usize },
    /// Duplicate a line.
    Duplicate { line: usize },
    /// Misspell a key.
    Rename { line: usize },
    /// Replace a line by a section header.
    Header { line: usize, section: usize },
    /// Cut the text at a fraction of its length.
    Truncate { permille: usize },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        4 => (any::<usize>(), 0..HOSTILE.len()).prop_map(|(line, value)| Mutation::Value { line, value }),
        3 => (any::<usize>(), -320i32..320).prop_map(|(line, power)| Mutation::Scale { line, power }),
        1 => any::<usize>().prop_map(|line| Mutation::Delete { line }),
        1 => any::<usize>().prop_map(|line| Mutation::Duplicate { line }),
        1 => any::<usize>().prop_map(|line| Mutation::Rename { line }),
        1 => (any::<usize>(), 0..SECTIONS.len()).prop_map(|(line, section)| Mutation::Header { line, section }),
        1 => (0usize..1000).prop_map(|permille| Mutation::Truncate { permille }),
    ]
}

fn apply(text: &str, m: &Mutation) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    if lines.is_empty() {
        return text.to_string();
    }
    let n = lines.len();
    // Lines holding `key = value` (mutations of values aim at them).
    let assignments: Vec<usize> = (0..n).filter(|&i| lines[i].contains('=')).collect();
    let pick = |line: usize| {
        if assignments.is_empty() {
            line % n
        } else {
            assignments[line % assignments.len()]
        }
    };
    match *m {
        Mutation::Value { line, value } => {
            let i = pick(line);
            let key = lines[i].split('=').next().unwrap_or_default().to_string();
            lines[i] = format!("{key}= {}", HOSTILE[value]);
        }
        Mutation::Scale { line, power } => {
            let i = pick(line);
            let mut parts = lines[i].splitn(2, '=');
            let key = parts.next().unwrap_or_default().to_string();
            let value = parts.next().unwrap_or_default();
            let value = value.split('#').next().unwrap_or_default().trim();
            if let Ok(x) = value.parse::<f64>() {
                lines[i] = format!("{key}= {:e}", x * 10f64.powi(power));
            }
        }
        Mutation::Delete { line } => {
            lines.remove(line % n);
        }
        Mutation::Duplicate { line } => {
            let l = lines[line % n].clone();
            lines.insert(line % n, l);
        }
        Mutation::Rename { line } => {
            let i = pick(line);
            lines[i] = lines[i].replacen(" =", "x =", 1);
        }
        Mutation::Header { line, section } => lines[line % n] = SECTIONS[section].to_string(),
        Mutation::Truncate { permille } => {
            let s = lines.join("\n");
            let mut cut = s.len() * permille / 1000;
            while !s.is_char_boundary(cut) {
                cut -= 1;
            }
            return s[..cut].to_string();
        }
    }
    lines.join("\n") + "\n"
}

fn fuzz_cases() -> u32 {
    std::env::var("LBDEM_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(256)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: fuzz_cases(), failure_persistence: None, ..ProptestConfig::default() })]

    /// Mutated bundled scenes: `check` never panics; a refusal names a field (`…`) or a line; `run` gives
    /// exactly the same refusal without writing anything. (A scene `check` accepts is not run here: that would
    /// be a whole simulation per case; `run` reaches the same verdict through the same `Case::read`.)
    #[test]
    fn fuzz_mutated_scenes_never_panic_and_check_agrees_with_run(
        seed in 0usize..64,
        mutations in proptest::collection::vec(mutation(), 1..4),
    ) {
        let seeds = seeds();
        let mut text = seeds[seed % seeds.len()].clone();
        for m in &mutations {
            text = apply(&text, m);
        }
        match app::check_text(&text, "fuzz.toml") {
            Ok(description) => prop_assert!(description.contains("is valid")),
            Err(e) => {
                let msg = e.to_string();
                prop_assert!(msg.contains('`') || msg.contains("line "), "names no field: {msg}");
                prop_assert!(msg.len() < 4000, "message of {} characters", msg.len());
                let out = std::env::temp_dir().join(format!("lbdem-fuzz-never-{}", std::process::id()));
                let r = app::run_text(&text, "fuzz.toml", &out, &quiet()).unwrap_err().to_string();
                prop_assert_eq!(&msg, &r);
                prop_assert!(!out.exists());
            }
        }
    }

    /// Damaged checkpoints (any byte flipped, truncated, extended) are refused without a panic.
    #[test]
    fn fuzz_damaged_checkpoints_are_refused(
        at in any::<usize>(),
        flip in 1u8..=255,
        cut in any::<bool>(),
    ) {
        let good = checkpoint_bytes();
        let mut b = good.to_vec();
        if cut {
            b.truncate(at % b.len());
        } else {
            let i = at % b.len();
            b[i] ^= flip;
        }
        let r = lbdem::run::checkpoint::Checkpoint::from_bytes::<lbdem::kinds::coupled_demo::DemoState>(
            &b, DEMO, "coupled_demo",
        );
        prop_assert!(r.is_err());
    }
}

/// The bytes of a demo checkpoint at step 20 (made once).
fn checkpoint_bytes() -> &'static [u8] {
    static BYTES: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    BYTES.get_or_init(|| {
        let out = interrupted("fuzz-checkpoint");
        std::fs::read(out.join("checkpoint.bin")).unwrap()
    })
}

// ---------------------------------------------------------------------------------------------------------
// A non-finite result: the coupled demo with one result forced to NaN (no valid scene is known to produce one
// since the settings above are refused; the run loop must still catch it).

/// The coupled demo with its drag ratio forced to −∞.
struct NegInfDrag;

impl Tweak for NegInfDrag {
    fn results(mut r: serde_json::Value) -> serde_json::Value {
        r["drag_ratio"] = serde_json::json!(f64::NEG_INFINITY);
        r
    }
}

type NanDemo = Tweaked<NegInfDrag>;

#[test]
fn a_non_finite_result_fails_the_run_and_the_summary_still_records_what_was_measured() {
    let out = scratch("nonfinite").join("out");
    let e = lbdem::run::run::<NanDemo>(DEMO, "demo.toml", &out, &quiet()).unwrap_err();
    assert!(
        matches!(e, LbdemError::NonFiniteResult { count: 1, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("results.drag_ratio"), "{e}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(
        summary["non_finite"],
        serde_json::json!(["results.drag_ratio"])
    );
    // The finite results are all there.
    assert!(
        summary["results"]["final_row"]["fluid_mass"]
            .as_f64()
            .unwrap()
            > 0.0
    );
    assert!(summary["results"]["drag_ratio"].is_null());
}

#[test]
fn a_scene_needing_more_memory_than_available_is_refused_by_check_and_run_with_the_figure_and_the_field(
) {
    // The available memory is injected (`LBDEM_MEMORY_LIMIT`, bytes) so that the test does not depend on the
    // machine; the child processes read it, this process's environment is left alone.
    let dir = scratch("memory");
    let path = dir.join("poiseuille.toml");
    std::fs::write(&path, scene("poiseuille.toml")).unwrap();
    let out = dir.join("out");
    let lbdem = |limit: &str, args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_lbdem"))
            .args(args)
            .env("LBDEM_MEMORY_LIMIT", limit)
            .output()
            .unwrap()
    };
    let (p, o) = (path.to_str().unwrap(), out.to_str().unwrap());
    // 100 kB available: the 81 x 20 f64 channel lattice needs 480.6 kB.
    let check = lbdem("100000", &["check", p]);
    let run = lbdem("100000", &["run", p, "--out", o, "--quiet"]);
    for o in [&check, &run] {
        assert!(!o.status.success());
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains("channel.length"), "the field: {e}");
        assert!(
            e.contains("480.6 kB") && e.contains("100.0 kB available"),
            "the figures: {e}"
        );
    }
    assert_eq!(check.stderr, run.stderr, "check and run disagree");
    assert!(!out.exists(), "run wrote {} before refusing", out.display());
    // 10 MB available: accepted, and `check` prints the estimate.
    let check = lbdem("10000000", &["check", p]);
    assert!(
        check.status.success(),
        "{}",
        String::from_utf8_lossy(&check.stderr)
    );
    assert!(
        String::from_utf8_lossy(&check.stdout).contains("480.6 kB"),
        "{}",
        String::from_utf8_lossy(&check.stdout)
    );
}
