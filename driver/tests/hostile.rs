//! Hostile input and faults (issue 15): every defect found by mutating scene files and by faults during runs
//! is a regression test here, and a property test mutates the bundled scenes (values, keys, structure) and
//! asserts that `check` never panics, that `check` and `run` reach the same verdict, and that every refusal
//! names a field or a line.
//!
//! The fuzzer runs `LBDEM_FUZZ_CASES` cases (default 256, about 15 s, most of it in the starts of the
//! accepted scenes it runs); for a long campaign:
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
    // Found by starting the scenes `check` accepts: the pressure-diffusion packing was checked only when
    // packed, naming `packing.*` (fields of another kind) or `solid.timestep` (fixed by the kind).
    let pd = scene("pressure_diffusion.toml");
    refused_by_both(
        &with(&pd, "radius_max", "0.011"),
        "pressure_diffusion.radius_max",
    );
    refused_by_both(&with(&pd, "width", "0.24"), "pressure_diffusion.width");
    refused_by_both(
        &with(&pd, "radius_min", "0.007"),
        "pressure_diffusion.radius_min",
    );
    // A bonding gap of 1e15 cm bonded every pair of grains: refused by the packing's DEM step only at start.
    let dry = with(&scene("uniaxial_compression.toml"), "gap", "1e15");
    refused_by_both(&dry, "solid.bonds.gap");
    refused_by_both(
        &with(&scene("uniaxial_compression.toml"), "gap", "0.0071"),
        "solid.bonds.gap",
    );
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

/// `text` with `[output] snapshot_interval = value` (added when the scene has no such key).
fn snapshot_interval(text: &str, value: &str) -> String {
    if text.contains("snapshot_interval") {
        with(text, "snapshot_interval", value)
    } else {
        assert!(
            !text.contains("[output]"),
            "add the key to the existing [output]"
        );
        format!("{text}\n[output]\nsnapshot_interval = {value}\n")
    }
}

#[test]
fn snapshot_counts_are_limited_naming_the_interval() {
    // Were: a snapshot every step (1e-300 s between snapshots rounds to one step), unbudgeted. Each scene
    // lengthened to more than 10^4 steps (so one snapshot per step is more than the limit).
    for (name, text, (key, longer)) in [
        ("coupled_demo", DEMO.to_string(), ("steps", "20000")),
        (
            "terminal_velocity",
            scene("terminal_velocity.toml"),
            ("duration", "1.5"), // 12 397 steps
        ),
        (
            "consolidation",
            scene("consolidation.toml"),
            ("duration", "5.0"), // 12 500 steps
        ),
        ("terzaghi", scene("terzaghi.toml"), ("duration", "10.0")), // 25 000 steps
        (
            "fracture",
            scene("fracture/quick/base.toml"),
            ("duration", "0.25"), // 12 500 steps
        ),
    ] {
        let e = refused_by_both(
            &snapshot_interval(&with(&text, key, longer), "1e-300"),
            "output.snapshot_interval",
        );
        assert!(
            e.contains("snapshot files") && e.contains("raise output.snapshot_interval"),
            "{name}: {e}"
        );
        // 0 (only the first and the last) and the default stay valid.
        app::check_text(&snapshot_interval(&text, "0"), "t.toml")
            .unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    // A dry compression's snapshots are counted in records: one every record (of one step) is one per step.
    let dry = with(
        &with(&scene("uniaxial_compression.toml"), "record_interval", "1"),
        "vtk_interval",
        "1",
    );
    refused_by_both(&dry, "loading.vtk_interval");
}

/// The memory `lbdem check` estimates for `text` (its "memory: about 1.2 MB" line), in bytes.
fn estimated_bytes(description: &str) -> Option<f64> {
    let rest = description.split("memory: about ").nth(1)?;
    let mut words = rest.split_whitespace();
    let x: f64 = words.next()?.parse().ok()?;
    let scale = match words.next()? {
        "B" => 1.0,
        "kB" => 1e3,
        "MB" => 1e6,
        "GB" => 1e9,
        _ => return None,
    };
    Some(x * scale)
}

#[test]
fn records_are_budgeted_naming_the_interval() {
    // A record every step (1e-300 s between records) now shows in the memory estimate, as the part of the
    // interval that sets it; before, records were not counted at all.
    for (text, part, field) in [
        (
            with(
                &scene("fracture/quick/base.toml"),
                "record_interval",
                "1e-300",
            ),
            "records",
            "output.record_interval",
        ),
        (
            with(&scene("terzaghi.toml"), "record_interval", "1e-300"),
            "pore-pressure profiles",
            "terzaghi.record_interval",
        ),
    ] {
        let steps_of_records = match app::check_text(&text, "t.toml") {
            Ok(d) => {
                assert!(d.contains(&format!("{part}: ")), "{d}");
                estimated_bytes(&d).unwrap()
            }
            // On a machine with less memory than the records take: refused naming the interval.
            Err(e) => {
                assert!(e.to_string().contains(&format!("`{field}`")), "{e}");
                continue;
            }
        };
        // The same scene with the bundled interval needs less.
        let base = if field.starts_with("output") {
            scene("fracture/quick/base.toml")
        } else {
            scene("terzaghi.toml")
        };
        let bundled = estimated_bytes(&app::check_text(&base, "t.toml").unwrap()).unwrap();
        assert!(
            steps_of_records > bundled,
            "{steps_of_records} vs {bundled}"
        );
    }
    // With the memory available injected (so that the test does not depend on the machine), the records are
    // what is refused, with the field.
    let dir = scratch("records");
    let path = dir.join("fracture.toml");
    std::fs::write(
        &path,
        with(
            &scene("fracture/quick/base.toml"),
            "record_interval",
            "1e-300",
        ),
    )
    .unwrap();
    let limit = {
        // The bundled scene's estimate plus 10 %: enough for everything but the extra records.
        let d = app::check_text(&scene("fracture/quick/base.toml"), "t.toml").unwrap();
        (estimated_bytes(&d).unwrap() * 1.1) as u64
    };
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_lbdem"))
        .args(["check", path.to_str().unwrap()])
        .env("LBDEM_MEMORY_LIMIT", limit.to_string())
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success(),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(e.contains("`output.record_interval`"), "{e}");
}

#[test]
fn dry_step_counts_are_limited_naming_the_field() {
    let dry = scene("uniaxial_compression.toml");
    // Were: accepted, with ~1e304 loading steps (a run without end) or an overflowing step count.
    refused_by_both(
        &with(&dry, "platen_speed", "1e-300"),
        "loading.platen_speed",
    );
    let e = refused_by_both(&with(&dry, "platen_speed", "1e-6"), "loading.platen_speed");
    assert!(e.contains("above the limit"), "{e}");
    let settle = dry.replace(
        "[loading]\n",
        "[loading]\nsettle_steps = 9223372036854775807\n",
    );
    refused_by_both(&settle, "loading.settle_steps");
    // The loading runs in whole record intervals: one of 2^62 steps is a run without end.
    refused_by_both(
        &with(&dry, "record_interval", "4611686018427387904"),
        "loading.record_interval",
    );
    let boundary = dry.replace(
        "[loading]\n",
        "[loading]\ntest = \"boundary_stress\"\naxial_stress = 40.0\nlateral_stress = 50.0\n\
         steps = 9223372036854775807\n",
    );
    refused_by_both(&boundary, "loading.steps");
    // The bundled scene stays valid.
    app::check_text(&dry, "t.toml").unwrap();
}

#[test]
fn mach_refusals_name_the_driving_input() {
    // Were: "`expected Mach number`", which is no field of the scene.
    let body = with(&scene("poiseuille_body_force.toml"), "acceleration", "1e3");
    let e = refused_by_both(&body, "channel.acceleration");
    assert!(e.contains("Mach") && e.contains("allow_high_mach"), "{e}");
    let cyl = with(&scene("cylinder_array_reynolds.toml"), "reynolds", "[1e6]");
    let e = refused_by_both(&cyl, "cylinder_array.reynolds");
    assert!(e.contains("Mach"), "{e}");
}

/// A porous scene of `columns × rows` discs of the given diameters (cm, at a spacing of 0.011 cm) and pressure
/// drops.
fn porous_scene(columns: u64, rows: u64, pitch: f64, diameters: &[f64], drops: usize) -> String {
    let list = |v: Vec<String>| v.join(", ");
    format!(
        "[scene]\nkind = \"porous_flow\"\nunits = \"cgs\"\n[fluid]\ndensity = 1.0\nviscosity = 0.1\n\
         spacing = 0.011\ntau = 0.8\n[porous]\ncolumns = {columns}\nrows = {rows}\npitch = {pitch}\n\
         diameters = [{}]\npressure_drops = [{}]\njitter = 0.5\n[run]\nsteps = 1000\n",
        list(diameters.iter().map(|d| d.to_string()).collect()),
        list((1..=drops).map(|k| format!("{:e}", k as f64 * 1e-4)).collect()),
    )
}

/// The narrowest gap of `case` by comparing every pair of discs (the definition; O(n²)).
fn every_pair_gap(case: &lbdem::kinds::porous_flow::PorousCase) -> f64 {
    let discs = case.discs();
    let ny = case.size().1 as f64;
    let mut gap = f64::INFINITY;
    for (a, da) in discs.iter().enumerate() {
        for db in discs.iter().skip(a + 1) {
            let mut dy = (da.center[1] - db.center[1]).abs();
            if !case.walls {
                dy = dy.min(ny - dy);
            }
            let dx = da.center[0] - db.center[0];
            gap = gap.min((dx * dx + dy * dy).sqrt() - da.radius - db.radius);
        }
        if case.walls {
            gap = gap.min(da.center[1] + 0.5 - da.radius);
            gap = gap.min(ny - 0.5 - da.center[1] - da.radius);
        }
        if !case.walls && case.rows == 1 {
            gap = gap.min(ny - 2.0 * da.radius);
        }
    }
    gap
}

#[test]
fn the_porous_narrowest_gap_is_exact_and_linear_in_the_discs() {
    use lbdem::kinds::porous_flow::{PorousFlowScene, PorousSetup};
    let parse = |text: &str| -> PorousFlowScene {
        lbdem::input::parse::parse_scene(text, "t.toml").unwrap()
    };
    let template = PorousSetup::new(&parse(&scene("porous_darcy.toml")))
        .unwrap()
        .cases[0]
        .clone();
    // Exactly the pairwise minimum (same bits), over lattices of every shape, jitter up to its limit, walls
    // or periodic, thin and fat discs.
    let mut compared = 0;
    for columns in [4, 5, 7] {
        for rows in [1, 2, 3, 6] {
            for walls in [false, true] {
                for jitter in [0.0, 0.3, 0.9, 0.999] {
                    for fraction in [0.1, 0.5, 0.95] {
                        for seed in [1, 2] {
                            let mut c = template.clone();
                            c.columns = columns;
                            c.rows = rows;
                            c.walls = walls;
                            c.jitter = jitter;
                            c.diameter = fraction * c.pitch as f64;
                            c.seed = seed;
                            let (gap, _) = c.min_gap_counted();
                            assert_eq!(gap, every_pair_gap(&c), "{c:?}");
                            compared += 1;
                        }
                    }
                }
            }
        }
    }
    assert_eq!(compared, 3 * 4 * 2 * 4 * 3 * 2);
    // The largest slab allowed (2 x 10^4 discs): a few pairs per disc (each disc and its 8 neighbour cells,
    // each pair once: 4 per disc), where the pairwise search measured 2 x 10^8.
    let mut big = template.clone();
    big.columns = 200;
    big.rows = 100;
    big.jitter = 0.5;
    let (gap, pairs) = big.min_gap_counted();
    assert!(pairs <= 4 * 20_000, "{pairs} pairs measured");
    assert!(gap > 0.0 && gap < big.pitch as f64 - big.diameter, "{gap}");
    // Measured once per diameter, not once per case: 2 diameters x 5000 pressure drops.
    let setup = PorousSetup::new(&parse(&porous_scene(4, 1, 0.264, &[0.1, 0.15], 5000))).unwrap();
    assert_eq!(setup.cases.len(), 10_000);
    assert_eq!(setup.narrowest_gaps.len(), 10_000);
    assert_eq!(setup.narrowest_gaps[0], setup.cases[0].min_gap());
    assert_eq!(setup.narrowest_gaps[9_999], setup.cases[9_999].min_gap());
}

#[test]
fn check_of_the_largest_porous_scene_allowed_returns() {
    // 2 x 10^4 discs (pitch 3 nodes: a lattice of 608 x 300 nodes) and 10^4 cases, both at their limits.
    // Before, the narrowest gap compared every pair of discs for every case, twice: ~4 x 10^12 pair
    // measurements, days of `check`. Now a fraction of a second; the bound is generous (a debug build on a
    // loaded 2-core machine) and only there so that a regression fails instead of hanging.
    let text = porous_scene(200, 100, 0.033, &[0.0165, 0.022], 5000);
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(app::check_text(&text, "t.toml").map_err(|e| e.to_string()));
    });
    let bound = std::time::Duration::from_secs(120);
    let described = rx
        .recv_timeout(bound)
        .expect("check of the porous scene did not return within two minutes");
    match described {
        Ok(d) => {
            assert!(d.contains("20000 discs"), "{}", &d[..d.len().min(2000)]);
            // One line per case.
            assert_eq!(d.matches(" discs, D = ").count(), 10_000);
        }
        // Only on a machine with less than the ~70 MB the lattice needs.
        Err(e) => assert!(e.contains("this machine has"), "{e}"),
    }
}

#[test]
fn a_non_finite_result_exits_non_zero_from_the_command_line_with_the_summary() {
    // A compression test that ends at its first record (max_strain below one record's strain): Young's
    // modulus, a slope, needs two points of the elastic part, so it is NaN.
    let text = with(
        &with(
            &with(
                &with(&scene("uniaxial_compression.toml"), "max_strain", "1e-6"),
                "width",
                "1.0",
            ),
            "height",
            "2.0",
        ),
        "record_interval",
        "10",
    )
    .replace("[loading]\n", "[loading]\nsettle_steps = 10\n");
    let dir = scratch("nonfinite-cli");
    let path = dir.join("dry.toml");
    std::fs::write(&path, text).unwrap();
    let out = dir.join("out");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_lbdem"))
        .args(["run", path.to_str().unwrap(), "--out"])
        .arg(&out)
        .arg("--quiet")
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("results.test.youngs_modulus"), "{e}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(
        summary["non_finite"],
        serde_json::json!(["results.test.youngs_modulus"])
    );
    // What was measured is there.
    assert!(summary["results"]["particles"].as_u64().unwrap() > 0);
}

// ---------------------------------------------------------------------------------------------------------
// The fuzzer.

/// The seeds of the mutations: the bundled scenes (every folder under `scenes/`, recursively) and the demo,
/// grouped by kind (sorted by kind name), so that a case picks a kind uniformly, then a scene of that kind
/// (there are 25 fracture scenes and one dry scene).
fn seeds() -> &'static [Vec<String>] {
    static SEEDS: std::sync::OnceLock<Vec<Vec<String>>> = std::sync::OnceLock::new();
    SEEDS.get_or_init(|| {
        let files = crate::common::files_with_extension(Path::new(SCENES), "toml");
        let mut by_kind: std::collections::BTreeMap<String, Vec<String>> = Default::default();
        let texts = files
            .iter()
            .map(|p| std::fs::read_to_string(p).unwrap())
            .chain([DEMO.to_string()]);
        for text in texts {
            let kind = text
                .lines()
                .find_map(|l| l.trim().strip_prefix("kind = \""))
                .and_then(|k| k.split('"').next())
                .expect("every scene names its kind")
                .to_string();
            by_kind.entry(kind).or_default().push(text);
        }
        by_kind.into_values().collect()
    })
}

#[test]
fn the_fuzzer_seeds_are_every_bundled_scene_by_kind() {
    let seeds = seeds();
    // Every kind of the registry has seeds.
    assert_eq!(seeds.len(), lbdem::kinds::REGISTRY.len());
    let all: usize = seeds.iter().map(Vec::len).sum();
    let files = crate::common::files_with_extension(Path::new(SCENES), "toml").len();
    // The scenes of the subfolders (scenes/fracture/quick/, scenes/fracture/storage/) included, and the demo.
    assert_eq!(all, files + 1);
    assert!(seeds
        .iter()
        .flatten()
        .any(|t| t.contains("kind = \"terzaghi\"") && t.contains("storage")));
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
    /// exactly the same refusal without writing anything. A scene `check` accepts whose memory estimate is small
    /// is started (packed, settled, lattices built: the scenes' starts take up to a few seconds) and stopped
    /// before its first chunk: `run` must not refuse it (a validation `check` missed) nor panic.
    #[test]
    fn fuzz_mutated_scenes_never_panic_and_check_agrees_with_run(
        kind in any::<usize>(),
        seed in any::<usize>(),
        mutations in proptest::collection::vec(mutation(), 1..4),
    ) {
        let seeds = seeds();
        let of_kind = &seeds[kind % seeds.len()];
        let mut text = of_kind[seed % of_kind.len()].clone();
        for m in &mutations {
            text = apply(&text, m);
        }
        match app::check_text(&text, "fuzz.toml") {
            Ok(description) => {
                prop_assert!(description.contains("is valid"));
                // Small: at most 2 MB, so that a start stays short (about one accepted case in two; ~5 % of the
                // cases, ~10 s per 256 cases in the test build).
                let small = estimated_bytes(&description).is_some_and(|b| b <= 2e6);
                if small {
                    started_and_stopped(&text)?;
                }
            }
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

/// Start a run of `text` (accepted by `check`) in a fresh directory and stop it before its first chunk: it must
/// end interrupted (or, for a start that already steps, diverged or with a non-finite result: physics, not
/// validation), never refused.
fn started_and_stopped(text: &str) -> Result<(), TestCaseError> {
    static RUNS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("lbdem-fuzz-run-{}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut o = quiet();
    o.stop_after = Some(0);
    let r = app::run_text(text, "fuzz.toml", &dir, &o);
    let _ = std::fs::remove_dir_all(&dir);
    match r {
        Err(LbdemError::Interrupted { .. })
        | Err(LbdemError::Diverged { .. })
        | Err(LbdemError::DivergedParticle { .. })
        | Err(LbdemError::NonFiniteResult { .. })
        | Ok(_) => Ok(()),
        Err(e) => Err(TestCaseError::fail(format!(
            "check accepted the scene, run refused it: {e}\n--- scene ---\n{text}"
        ))),
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
