//! Checkpoints and long runs: save → load → continue equals the uninterrupted run bitwise (fluid, DEM, coupled;
//! f32 and f64), interrupted-and-resumed runs write byte-identical outputs (dry scene, coupled demo, through the
//! library and through `lbdem resume`), damaged or mismatched checkpoints give clear errors, divergence stops
//! with a message and keeps the last good checkpoint, and `lbdem run` refuses a directory holding a run.
//!
//! Every comparison here is exact (bytes or bit patterns): checkpoints store raw IEEE bits and the steps are
//! deterministic, so no tolerance is needed or allowed.
use crate::common::tweaked_demo;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;
use tweaked_demo::{Tweak, Tweaked};

use lbdem::app::RunOptions;
use lbdem::engine::coupled::CoupledWorld;
use lbdem::engine::dem::{boxed_sample, hexagonal_packing, BondSpec, DemWorld, PlatenControl};
use lbdem::engine::lattice::{FluidDisc, FluidLattice};
use lbdem::error::LbdemError;
use lbdem::kinds::coupled_demo::{CoupledDemo, DemoScene, DemoState};
use lbdem::run::checkpoint::{Checkpoint, Persist, CHECKPOINT_FILE, DIVERGED_FILE, SCENE_COPY};
use lbdem::run::{Case, CheckpointInterval, Stop};
use lbdem_kernels::dem::assembly::ContactModel;
use lbdem_kernels::dem::servo::ServoLaw;
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::{SolidOperator, Weighting};
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::Real;

/// Tests that run the binary take this lock, so that they do not compete for the two cores with each other.
static LONG_RUNS: Mutex<()> = Mutex::new(());

fn lock() -> std::sync::MutexGuard<'static, ()> {
    LONG_RUNS.lock().unwrap_or_else(|e| e.into_inner())
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lbdem-ckpt-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const SCENE: &str = "any scene text";

/// Save → load through the on-disk format, then step both copies `more` times and compare the whole states.
fn assert_resumes_bitwise<S: Persist>(mut a: S, step: impl Fn(&mut S), more: usize) {
    let bytes = Checkpoint::to_bytes(SCENE, "test", 7, &a);
    let (header, mut b): (_, S) = Checkpoint::from_bytes(&bytes, SCENE, "test").unwrap();
    assert_eq!(header.step, 7);
    assert_eq!(header.precision, S::PRECISION);
    // The loaded state writes the same bytes back.
    assert_eq!(Checkpoint::to_bytes(SCENE, "test", 7, &b), bytes);
    for _ in 0..more {
        step(&mut a);
        step(&mut b);
    }
    assert_eq!(
        Checkpoint::to_bytes(SCENE, "test", 0, &a),
        Checkpoint::to_bytes(SCENE, "test", 0, &b),
        "continued states differ"
    );
}

fn fluid<T: Real>() -> FluidLattice<T> {
    // Pressure-driven channel with walls, a solid block (bounce-back nodes) and PSM discs (Ω₃): every kind of
    // node the step treats differently.
    let bc = Boundaries {
        west: SideCondition::Pressure {
            density: T::lit(1.01),
        },
        east: SideCondition::Pressure {
            density: T::lit(0.99),
        },
        south: SideCondition::Wall,
        north: SideCondition::Wall,
    };
    let mut l = FluidLattice::new(
        37,
        23,
        bc,
        FluidParams {
            tau: T::lit(0.7),
            force: [T::lit(1e-6), T::zero()],
        },
    )
    .unwrap();
    l.set_solid(|x, y| (16..19).contains(&x) && (2..5).contains(&y));
    l.set_solid_operator(SolidOperator::MovingWallBounceBack);
    l.cover_with_discs(
        &[
            FluidDisc {
                center: [9.3, 11.6],
                radius: 3.7,
                velocity: [0.01, -0.002],
                spin: 0.001,
            },
            FluidDisc {
                center: [26.1, 14.2],
                radius: 4.2,
                velocity: [0.0; 2],
                spin: 0.0,
            },
        ],
        Weighting::NobleTorczynski,
    );
    l
}

#[test]
fn fluid_lattice_resumes_bitwise_f64_and_f32() {
    let mut a = fluid::<f64>();
    for _ in 0..53 {
        a.step();
    }
    let populations = a.populations().to_vec();
    assert_resumes_bitwise(a, |l| l.step(), 41);
    assert!(populations.iter().all(|p| p.is_finite()));

    let mut a = fluid::<f32>();
    for _ in 0..53 {
        a.step();
    }
    let bytes = Checkpoint::to_bytes(SCENE, "fluid", 53, &a);
    let (_, mut b): (_, FluidLattice<f32>) =
        Checkpoint::from_bytes(&bytes, SCENE, "fluid").unwrap();
    for _ in 0..41 {
        a.step();
        b.step();
    }
    let bits = |l: &FluidLattice<f32>| {
        l.populations()
            .iter()
            .map(|v| v.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(a.steps(), b.steps());
    assert_eq!(a.solid_forces(2), b.solid_forces(2));
    // An f32 checkpoint is not an f64 one.
    let err = Checkpoint::from_bytes::<FluidLattice<f64>>(&bytes, SCENE, "fluid")
        .err()
        .expect("precision mismatch refused")
        .to_string();
    assert!(
        err.contains("4-byte floats") && err.contains("8-byte"),
        "{err}"
    );
}

fn bonded_world() -> DemWorld<f64> {
    let particles = hexagonal_packing(8, 6, 0.1, 1.0, 0.01, 2.65, 3);
    let contact = ContactModel {
        normal_stiffness: 1e5,
        shear_stiffness: 1e5,
        friction: 0.5,
        restitution: 1.0,
        no_tension: true,
    };
    let bonds = BondSpec::Parallel {
        radius_multiplier: 1.0,
        normal_stiffness: 2.8e5,
        shear_stiffness: 2.8e5,
        tensile_strength: 300.0,
        shear_strength: 300.0,
    };
    let mut p = boxed_sample(particles, contact, 5e-5, Some(bonds), 5e-3).unwrap();
    let b = p.sample_box;
    // Squeeze fast from top and bottom, servo the sides: contacts, bond breaks, moving platens.
    p.world.platens[b.top].control = PlatenControl::Speed(2.0);
    p.world.platens[b.bottom].control = PlatenControl::Speed(2.0);
    let servo = PlatenControl::Servo(ServoLaw {
        target_stress: 50.0,
        relaxation: 0.5,
        max_speed: 1.0,
    });
    p.world.platens[b.left].control = servo;
    p.world.platens[b.right].control = servo;
    p.world.gravity = lbdem_kernels::math::vector(0.0, -981.0);
    p.world
}

/// The pair pass's hints (a separating direction kept per pair, which culls ellipse pairs before the
/// closest-approach search) are not saved: a bonded ellipse packing under a moving platen, read back from a
/// checkpoint without them, continues bitwise as the world that kept them, and the hints did cull pairs.
#[test]
fn ellipse_world_resumes_bitwise_without_its_separation_hints() {
    let mut p = crate::common::bonded_ellipse_packing();
    let b = p.sample_box;
    p.world.platens[b.top].control = PlatenControl::Speed(0.5);
    let mut a = p.world;
    let mut active = 0;
    for _ in 0..100 {
        a.step();
        active = active.max(a.active_contacts());
    }
    let before = a.hint_culls();
    assert!(active > 10, "the check needs ellipse contacts ({active})");
    let bytes = Checkpoint::to_bytes(SCENE, "test", 7, &a);
    let (_, mut r): (_, DemWorld<f64>) = Checkpoint::from_bytes(&bytes, SCENE, "test").unwrap();
    assert_eq!(r.hint_culls(), 0, "hints are not saved");
    for _ in 0..200 {
        a.step();
        r.step();
    }
    // The hints carried from before the checkpoint culled pairs in the first step after it, where the
    // restored world had none yet.
    assert!(a.hint_culls() > before, "no pair culled by a hint");
    assert!(r.hint_culls() > 0);
    assert_eq!(
        Checkpoint::to_bytes(SCENE, "test", 0, &a),
        Checkpoint::to_bytes(SCENE, "test", 0, &r),
        "continued states differ"
    );
}

#[test]
fn dem_world_resumes_bitwise_with_contacts_bonds_breaks_and_servo_platens() {
    let mut a = bonded_world();
    assert!(!a.bonds.is_empty());
    for _ in 0..1500 {
        a.step();
    }
    assert!(a.active_contacts() > 0, "the check needs live contacts");
    let breaks_before = a.breaks.len();
    let mut b = a.clone();
    for _ in 0..1500 {
        b.step();
    }
    assert!(
        b.breaks.len() > breaks_before,
        "the continuation should break bonds ({breaks_before} before)"
    );
    assert_resumes_bitwise(a, |w| w.step(), 1500);
}

fn demo_scene(steps: u64, interval: &str) -> String {
    format!(
        r#"
[scene]
kind = "coupled_demo"
[demo]
nx = 40
ny = 36
tau = 0.8
discs = 4
radius = 5.0
speed = 0.01
steps = {steps}
record_interval = 10
[run]
checkpoint_interval = {interval}
"#
    )
}

/// The coupled world of the demo scene (four discs).
fn demo_world() -> CoupledWorld {
    let scene: DemoScene = Case::<CoupledDemo>::read(&demo_scene(100, "0"), "demo")
        .unwrap()
        .scene;
    scene.build_world().unwrap()
}

#[test]
fn coupled_world_resumes_bitwise() {
    let mut a = demo_world();
    a.applied[1] = (lbdem_kernels::math::vector(1e-4, -2e-4), 1e-3);
    a.grain_fluid_radius = vec![1.0, 0.9, 0.8, 0.95];
    for _ in 0..60 {
        a.step();
    }
    assert!(a.fluid.covered_nodes() > 0);
    assert_resumes_bitwise(a, |w| w.step(), 60);
}

/// With a remap tolerance the grains keep their mapped cells between re-mappings: a checkpoint taken between two
/// re-mappings keeps the mapped geometry, and the resumed world maps the same cells.
#[test]
fn coupled_world_with_a_remap_tolerance_resumes_bitwise() {
    let mut a = demo_world();
    a.fluid.set_remap_tolerance(0.05).unwrap();
    for _ in 0..61 {
        a.step();
    }
    assert!(a.fluid.covered_nodes() > 0);
    assert_resumes_bitwise(a, |w| w.step(), 60);
}

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
        .filter(|(n, _)| n != "summary.json" && n != CHECKPOINT_FILE)
        .collect();
    v.sort();
    v
}

fn summary_without_timing(dir: &Path) -> serde_json::Value {
    let mut s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let o = s.as_object_mut().unwrap();
    for timing in [
        "wall_seconds",
        "execution",
        "segment_first_step",
        "scene_file",
    ] {
        o.remove(timing);
    }
    s
}

fn assert_same_outputs(a: &Path, b: &Path) {
    let (fa, fb) = (files(a), files(b));
    assert_eq!(
        fa.iter().map(|f| &f.0).collect::<Vec<_>>(),
        fb.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    for ((name, x), (_, y)) in fa.iter().zip(&fb) {
        assert!(x == y, "{name} differs between the runs");
    }
    assert_eq!(summary_without_timing(a), summary_without_timing(b));
}

const BUNDLED: &str = include_str!("../../scenes/uniaxial_compression.toml");

#[test]
fn dry_scene_interrupted_and_resumed_writes_identical_outputs() {
    let _guard = lock();
    // The small sample of tests/dem_scene.rs, with snapshots often enough that some fall after the resume.
    let text = BUNDLED
        .replacen("width = 2.0", "width = 1.2", 1)
        .replacen("height = 4.0", "height = 2.4", 1)
        .replacen("vtk_interval = 40", "vtk_interval = 25", 1)
        + "\n[run]\ncheckpoint_interval = 2000\n";
    let root = scratch("dry");
    let path = root.join("input.toml");
    std::fs::write(&path, &text).unwrap();
    let quiet = |stop_after| RunOptions {
        quiet: true,
        stop_after,
        ..Default::default()
    };
    let whole = root.join("whole");
    lbdem::app::run(&path, &whole, &quiet(None)).unwrap();
    let cut = root.join("cut");
    let err = lbdem::app::run(&path, &cut, &quiet(Some(2600))).unwrap_err();
    match &err {
        LbdemError::Interrupted { step, .. } => assert_eq!(*step, 2600),
        e => panic!("expected an interruption, got {e}"),
    }
    assert!(err.to_string().contains("lbdem resume"), "{err}");
    assert!(cut.join(CHECKPOINT_FILE).exists() && cut.join(SCENE_COPY).exists());
    assert!(!cut.join("summary.json").exists());
    let partial = std::fs::read_to_string(cut.join("stress_strain.csv")).unwrap();
    assert_eq!(
        partial.lines().count(),
        1 + (2600 - 1000) / 50,
        "records so far"
    );
    // A second slice, then to the end.
    assert!(matches!(
        lbdem::app::resume(&cut, &quiet(Some(4000))),
        Err(LbdemError::Interrupted { step: 4000, .. })
    ));
    lbdem::app::resume(&cut, &quiet(None)).unwrap();
    assert_same_outputs(&whole, &cut);
    // `lbdem run` refuses both directories without --overwrite…
    for dir in [&whole, &cut] {
        let e = lbdem::app::run(&path, dir, &quiet(None))
            .unwrap_err()
            .to_string();
        assert!(e.contains("already holds a run"), "{e}");
    }
}

/// Raise `stop` once the run holding at the marker file (RunOptions::hold_at) has created it.
fn stop_when_held(marker: &Path, stop: &Stop) -> std::thread::JoinHandle<()> {
    let (marker, stop) = (marker.to_path_buf(), stop.clone());
    std::thread::spawn(move || {
        let t0 = std::time::Instant::now();
        while !marker.exists() && t0.elapsed().as_secs() < 120 {
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        stop.request();
    })
}

#[test]
fn coupled_demo_interrupted_by_the_flag_resumes_to_identical_outputs() {
    let text = demo_scene(300, "\"never\"");
    let root = scratch("demo");
    let path = root.join("demo.toml");
    std::fs::write(&path, &text).unwrap();
    let quiet = RunOptions {
        quiet: true,
        ..Default::default()
    };
    let whole = root.join("whole");
    lbdem::app::run(&path, &whole, &quiet).unwrap();

    // The stop request (what Ctrl-C raises) arrives while the run holds at step 130.
    let cut = root.join("cut");
    let marker = root.join("held");
    let stop = Stop::new();
    let opts = RunOptions {
        quiet: true,
        stop: stop.clone(),
        hold_at: Some((130, marker.clone())),
        ..Default::default()
    };
    let raiser = stop_when_held(&marker, &stop);
    let end = lbdem::app::run(&path, &cut, &opts);
    raiser.join().unwrap();
    assert!(
        matches!(end, Err(LbdemError::Interrupted { step: 130, .. })),
        "{end:?}"
    );
    let rows = std::fs::read_to_string(cut.join("series.csv")).unwrap();
    assert_eq!(
        rows.lines().count(),
        1 + 13,
        "outputs so far written on interrupt"
    );
    lbdem::app::resume(&cut, &quiet).unwrap();
    assert_same_outputs(&whole, &cut);
}

#[test]
fn damaged_or_mismatched_checkpoints_are_refused_with_clear_errors() {
    let text = demo_scene(60, "20");
    let dir = scratch("damaged");
    let path = dir.join("demo.toml");
    std::fs::write(&path, &text).unwrap();
    let opts = RunOptions {
        quiet: true,
        stop_after: Some(40),
        ..Default::default()
    };
    assert!(matches!(
        lbdem::app::run(&path, &dir, &opts),
        Err(LbdemError::Interrupted { step: 40, .. })
    ));
    let ckpt = dir.join(CHECKPOINT_FILE);
    let good = std::fs::read(&ckpt).unwrap();
    let quiet = RunOptions {
        quiet: true,
        ..Default::default()
    };
    let resume_err = |bytes: &[u8]| {
        std::fs::write(&ckpt, bytes).unwrap();
        let e = lbdem::app::resume(&dir, &quiet).unwrap_err();
        assert!(matches!(e, LbdemError::Checkpoint { .. }), "{e}");
        e.to_string()
    };
    // A flipped bit in the payload.
    let mut flipped = good.clone();
    let k = flipped.len() - 100;
    flipped[k] ^= 0x10;
    let e = resume_err(&flipped);
    assert!(
        e.contains("corrupted") && e.contains("checkpoint.bin"),
        "{e}"
    );
    // A truncated file.
    let e = resume_err(&good[..good.len() / 2]);
    assert!(e.contains("truncated"), "{e}");
    // Not a checkpoint at all.
    let e = resume_err(b"hello, this is not a checkpoint file at all");
    assert!(e.contains("not an lbdem checkpoint"), "{e}");
    // Another format version.
    let mut v2 = good.clone();
    v2[8] = 99;
    let e = resume_err(&v2);
    assert!(e.contains("format version 99"), "{e}");
    // An edited scene copy.
    std::fs::write(&ckpt, &good).unwrap();
    std::fs::write(dir.join(SCENE_COPY), text.replace("tau = 0.8", "tau = 0.9")).unwrap();
    let e = lbdem::app::resume(&dir, &quiet).unwrap_err().to_string();
    assert!(
        e.contains("another scene") && e.contains("scene.toml"),
        "{e}"
    );
    // A checkpoint of another run loop (dry) is not a demo checkpoint.
    let e = Checkpoint::from_bytes::<DemoState>(&good, &text, "dry")
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("`coupled_demo` run, not a `dry` run"), "{e}");
    // A missing checkpoint.
    std::fs::remove_file(&ckpt).unwrap();
    let e = lbdem::app::resume(&dir, &quiet).unwrap_err().to_string();
    assert!(e.contains("does not exist"), "{e}");
}

/// The coupled demo, with one fluid population poisoned once 70 steps are done.
struct Poison;

impl Tweak for Poison {
    fn before_chunk(s: &mut DemoState) {
        if s.world.steps() == 70 {
            s.world.fluid.populations_mut()[5 * 40 + 3] = f64::NAN;
        }
    }
}

type PoisonedDemo = Tweaked<Poison>;

#[test]
fn a_diverging_run_stops_with_a_message_and_keeps_the_last_good_checkpoint() {
    let text = demo_scene(200, "30");
    let dir = scratch("diverge");
    let quiet = RunOptions {
        quiet: true,
        ..Default::default()
    };
    let e = lbdem::run::run::<PoisonedDemo>(&text, "demo.toml", &dir, &quiet).unwrap_err();
    let msg = e.to_string();
    match e {
        LbdemError::Diverged { step, x, y, .. } => {
            assert_eq!(step, 80);
            // The NaN spreads to the neighbours of node (3, 5) in one step; the first bad node is nearby.
            assert!(x.abs_diff(3) <= 10 && y.abs_diff(5) <= 10, "({x}, {y})");
        }
        other => panic!("expected divergence, got {other}"),
    }
    assert!(
        msg.contains("density") && msg.contains("diverged_state.bin"),
        "{msg}"
    );
    let header = Checkpoint::read_header(&dir.join(CHECKPOINT_FILE)).unwrap();
    assert_eq!(header.step, 60, "the last good checkpoint is kept");
    assert_eq!(
        Checkpoint::read_header(&dir.join(DIVERGED_FILE))
            .unwrap()
            .step,
        80
    );
    let rows = std::fs::read_to_string(dir.join("series.csv")).unwrap();
    assert_eq!(rows.lines().count(), 1 + 7, "rows up to step 70 are kept");
    // Resuming from the last good checkpoint finishes (the poison was not in it).
    lbdem::app::resume(&dir, &quiet).unwrap();
    assert!(dir.join("summary.json").exists());
}

#[test]
fn checkpoint_interval_parses_steps_durations_and_never() {
    use CheckpointInterval::*;
    let parse = |s: &str| CheckpointInterval::parse(s);
    assert_eq!(parse("10 min"), Ok(WallSeconds(600.0)));
    assert_eq!(parse("90 s"), Ok(WallSeconds(90.0)));
    assert_eq!(parse("2h"), Ok(WallSeconds(7200.0)));
    assert_eq!(parse("500 steps"), Ok(Steps(500)));
    assert_eq!(parse("never"), Ok(Never));
    let e = parse("soon").unwrap_err();
    assert!(e.contains("run.checkpoint_interval"), "{e}");
    let e = Case::<CoupledDemo>::read(&demo_scene(10, "\"often\""), "demo.toml")
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("checkpoint_interval"), "{e}");
}

fn lbdem() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lbdem"))
}

#[test]
fn cli_resume_and_overwrite() {
    let _guard = lock();
    let text = demo_scene(400, "100");
    let root = scratch("cli");
    let scene = root.join("demo.toml");
    std::fs::write(&scene, &text).unwrap();
    let run = |out: &Path, extra: &[&str]| {
        let mut c = lbdem();
        c.args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ]);
        c.args(extra);
        c.output().unwrap()
    };
    let whole = root.join("whole");
    let o = run(&whole, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    // An interrupted run (written through the library), finished by the binary.
    let cut = root.join("cut");
    let opts = RunOptions {
        quiet: true,
        stop_after: Some(170),
        ..Default::default()
    };
    assert!(lbdem::app::run(&scene, &cut, &opts).is_err());
    let o = run(&cut, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("lbdem resume"), "{err}");
    let o = lbdem()
        .args(["resume", cut.to_str().unwrap(), "--quiet", "--threads", "1"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_same_outputs(&whole, &cut);

    // --overwrite starts again and removes the old checkpoint first.
    let o = run(&cut, &["--overwrite"]);
    assert!(o.status.success());
    assert_same_outputs(&whole, &cut);

    // resume of a directory without a run
    let o = lbdem()
        .args(["resume", root.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("checkpoint.bin") && !err.contains("panicked"),
        "{err}"
    );
}

#[cfg(unix)]
#[test]
fn cli_ctrl_c_writes_a_checkpoint_and_resume_finishes_identically() {
    let _guard = lock();
    // Long enough that the interrupt lands mid-run; the step it lands at does not matter.
    let text = demo_scene(20000, "\"never\"");
    let root = scratch("sigint");
    let scene = root.join("demo.toml");
    std::fs::write(&scene, &text).unwrap();
    let out = root.join("out");
    let child = lbdem()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // scene.toml appears once the run has started (after the handler is installed).
    let t0 = std::time::Instant::now();
    while !out.join(SCENE_COPY).exists() && t0.elapsed().as_secs() < 20 {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    std::thread::sleep(std::time::Duration::from_millis(50));
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    // The whole run takes seconds; the signal lands within ~0.1 s of its start.
    assert!(
        !out.join("summary.json").exists(),
        "the run finished before the interrupt: {err}"
    );
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(
        err.contains("interrupted at step") && err.contains("lbdem resume"),
        "{err}"
    );
    let o = lbdem()
        .args(["resume", out.to_str().unwrap(), "--quiet"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let whole = root.join("whole");
    let quiet = RunOptions {
        quiet: true,
        ..Default::default()
    };
    lbdem::app::run(&scene, &whole, &quiet).unwrap();
    assert_same_outputs(&whole, &out);
}

#[test]
fn dry_boundary_stress_test_in_f32_resumes_to_identical_outputs() {
    let _guard = lock();
    let text = BUNDLED
        .replacen("precision = \"f64\"", "precision = \"f32\"", 1)
        .replacen("width = 2.0", "width = 1.6", 1)
        .replacen("height = 4.0", "height = 1.0", 1)
        .replacen("vtk_interval = 40", "vtk_interval = 6", 1)
        .replacen(
            "confining_stress = 0.0   # uniaxial",
            "test = \"boundary_stress\"\naxial_stress = 40.0\nlateral_stress = 50.0\nsteps = 1500",
            1,
        )
        .replacen("platen_speed = 0.02      # cm/s each\n", "", 1)
        .replacen("max_strain = 0.05\n", "", 1);
    let root = scratch("dry32");
    let path = root.join("input.toml");
    std::fs::write(&path, &text).unwrap();
    let opts = |stop_after| RunOptions {
        quiet: true,
        stop_after,
        ..Default::default()
    };
    let whole = root.join("whole");
    lbdem::app::run(&path, &whole, &opts(None)).unwrap();
    let cut = root.join("cut");
    assert!(matches!(
        lbdem::app::run(&path, &cut, &opts(Some(700))),
        Err(LbdemError::Interrupted { step: 700, .. })
    ));
    assert_eq!(
        Checkpoint::read_header(&cut.join(CHECKPOINT_FILE))
            .unwrap()
            .precision,
        4
    );
    lbdem::app::resume(&cut, &opts(None)).unwrap();
    assert_same_outputs(&whole, &cut);
}
