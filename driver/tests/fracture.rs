//! The fluid-driven fracture test (dissertation ch. 6.6–6.8) on the quick scenes of `scenes/fracture/quick/`:
//! the controls, the orientation of the base test's fractures, the permeability study's trends, bitwise resume
//! after an interruption, thread-count independence, the outputs a user looks at, and bad input.
//!
//! Every quick scene shares `[packing]` and `[solid]`, so the sample is packed once (the slow part) and each
//! run starts from a copy of it, as `lbdem run` would after packing the same seed.
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use lbdem::app::RunOptions;
use lbdem::engine::dem::packing::Packing;
use lbdem::kinds::fracture::{pack, start_packed, FractureScene, FractureTest};
use lbdem::run::Case;
use serde_json::Value;

fn quick(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes/fracture/quick")
        .join(format!("{name}.toml"))
}

fn load(path: &Path) -> FractureScene {
    let text = std::fs::read_to_string(path).expect("scene file");
    Case::<FractureTest>::read(&text, &path.display().to_string())
        .expect("valid scene")
        .scene
}

/// `lbdem run` of the scene file `path` into `out`, starting from the shared packing; stopped (as if
/// interrupted) after `stop_after` steps when given.
fn run_with(path: &Path, out: &Path, stop_after: Option<u64>) -> lbdem::error::Result<Value> {
    let text = std::fs::read_to_string(path).expect("scene file");
    let opts = RunOptions {
        overwrite: true,
        quiet: true,
        stop_after,
        ..Default::default()
    };
    lbdem::run::run_from::<FractureTest>(
        &text,
        &path.display().to_string(),
        out,
        &opts,
        |case, exec| start_packed(case, exec, packing()),
    )
}

fn out_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lbdem-fracture-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The quick sample, packed once.
fn packing() -> Packing<f64> {
    static P: OnceLock<Packing<f64>> = OnceLock::new();
    P.get_or_init(|| pack(&load(&quick("base"))).expect("packing"))
        .clone()
}

fn run_scene(path: &Path, name: &str) -> (PathBuf, Value) {
    let scene = load(path);
    let base = load(&quick("base"));
    // The shared packing is only valid for scenes with the same sample.
    assert_eq!(
        serde_json::to_string(&(&scene.packing, &scene.solid)).unwrap(),
        serde_json::to_string(&(&base.packing, &base.solid)).unwrap(),
        "{name}: [packing]/[solid] differ from quick/base.toml"
    );
    let out = out_dir(name);
    let summary = run_with(path, &out, None).expect("run");
    (out, summary)
}

fn run(name: &str) -> (PathBuf, Value) {
    run_scene(&quick(name), name)
}

fn broken(s: &Value) -> (u64, u64) {
    (
        s["results"]["broken_bonds"].as_u64().unwrap(),
        s["results"]["total_bonds"].as_u64().unwrap(),
    )
}

/// The trace of the fractures at the grain scale: the axial mean direction of the vectors joining every two
/// broken bonds closer than `link` (cm; 0.15 ≈ the distance between breaks on neighbouring bonds of the quick
/// sample's grains, radii 0.07–0.11), as its deviation from perpendicular to σ₃ (x) in degrees, with the
/// resultant length (0: no common direction, 1: all pairs parallel). Independent of how the breaks are grouped
/// into fractures.
fn local_trace(out: &Path, link: f64) -> (f64, f64) {
    let text = std::fs::read_to_string(out.join("breaks.csv")).unwrap();
    let p: Vec<[f64; 2]> = text
        .lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l
                .split(',')
                .skip(1)
                .take(2)
                .map(|v| v.parse().unwrap())
                .collect();
            [v[0], v[1]]
        })
        .collect();
    let (mut c, mut s, mut n) = (0.0f64, 0.0f64, 0usize);
    for (i, a) in p.iter().enumerate() {
        for b in &p[i + 1..] {
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            if dx.hypot(dy) < link {
                let doubled = 2.0 * dy.atan2(dx);
                c += doubled.cos();
                s += doubled.sin();
                n += 1;
            }
        }
    }
    assert!(n >= 10, "only {n} pairs of neighbouring breaks");
    let mean = (0.5 * s.atan2(c).to_degrees()).rem_euclid(180.0);
    ((mean - 90.0).abs(), c.hypot(s) / n as f64)
}

fn history(out: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(out.join("history.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect()
}

#[test]
fn dry_and_no_drop_controls_break_almost_no_bonds() {
    // Ch. 6.7: "Test runs of dry models with identical boundary and initial conditions were performed with no
    // resulting fractures but with less than 1% axial strain. Saturated models with no fluid pressure drop on
    // the boundaries, but with a drop in the axial stress, also did not form fractures." "Almost no": at most
    // 1 % of the bonds (a few grains at the free ends may lose a bond when the axial stress is released).
    for name in ["dry", "no_drop"] {
        let (_, s) = run(name);
        let (b, total) = broken(&s);
        eprintln!("{name}: {b} of {total} bonds broken");
        assert!(
            (b as f64) <= 0.01 * total as f64,
            "{name}: {b} of {total} bonds broke"
        );
        let strain = s["results"]["final_axial_strain"].as_f64().unwrap();
        assert!(strain.abs() < 0.01, "{name}: axial strain {strain}");
    }
}

#[test]
fn base_test_breaks_bonds_into_fractures_perpendicular_to_the_least_stress() {
    let (out, s) = run("base");
    let (b, total) = broken(&s);
    let o = &s["results"]["orientation"];
    eprintln!("base: {b} of {total} bonds broken; orientation {o}");
    // Every grain stays on the fluid lattice (none crosses the 0.2 cm margin at the ends).
    assert_eq!(s["results"]["grains_outside_lattice"], 0);
    assert!(s["results"].get("first_outside_time").is_none());
    // The pressure drop (2.4 × the bonds' tensile strength, as ch. 6.6 states) breaks a clear share of the
    // bonds where the controls break none: measured 8.1 % (38 of 467; 8.8 % on the packing before b898dc9);
    // require 3 %.
    assert!(
        b as f64 >= 0.03 * total as f64,
        "only {b} of {total} bonds broke"
    );
    // The breaks coalesce: at least one cluster of ≥ 5 broken bonds (single-linkage at 2.5 grain radii).
    let fractures = std::fs::read_to_string(out.join("fractures.csv")).unwrap();
    let largest: usize = fractures
        .lines()
        .nth(1)
        .and_then(|l| l.split(',').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    assert!(largest >= 5, "largest fracture has {largest} breaks");
    // Orientation (ch. 6.7: "roughly perpendicular to the minimum stress direction"): σ₃ acts along x, so the
    // fracture traces and the crack planes of the broken bonds should be near vertical. The grains are
    // randomly oriented ellipses about 5 bond lengths across the quick sample, so a fracture zigzags along
    // grain boundaries; 30° allows that grain-scale tortuosity and still excludes the shear (≈ 45° ± friction
    // angle) and bedding-parallel (0°) alternatives.
    // The trace is taken from neighbouring breaks (`local_trace`), not from the principal axis of the
    // single-linkage clusters of `fractures.csv`: when two near-vertical bands of breaks 0.5 cm apart are joined
    // by one bridging break, their cluster is a round cloud (elongation 0.94) whose principal axis carries no
    // direction. That happened when the default fluid became TRT + ΩΛ: the breaks lie where they lay under
    // BGK + Ω₁ₗ (the first 8 at the same bonds, 41 against 42 in all), yet the clusters went from 2 (traces 2°
    // off) to 1 (axis 74° off). Measured, local trace / crack planes from vertical: TRT + ΩΛ 0.5° / 3.0°
    // (resultant 0.52), BGK + Ω₁ₗ 7.1° / 10.6° (0.46).
    let (trace, resultant) = local_trace(&out, 0.15);
    let crack = o["crack_plane_deviation_from_perpendicular_to_sigma3_deg"]
        .as_f64()
        .unwrap();
    // Resultant: 1 for breaks stacked on one line, about 1/√pairs (≈ 0.14 for the ~50 pairs here) for a
    // direction-free cloud; 0.3 asks for a clear common direction.
    assert!(
        trace <= 30.0 && resultant >= 0.3,
        "local fracture trace {trace}° from perpendicular to σ3 (resultant {resultant})"
    );
    assert!(
        crack <= 30.0,
        "crack planes {crack}° from perpendicular to σ3"
    );
    // Point bonds fail in tension here (fluid drag pulls the sample apart).
    let tensile = o["tensile_breaks"].as_u64().unwrap();
    assert!(tensile * 2 >= b, "{tensile} of {b} breaks tensile");
    // The pore fluid drains: the last record's mean pore pressure is far below the initial drop.
    let h = history(&out);
    let (p0, p1) = (h[0][6], h.last().unwrap()[6]);
    assert!((p0 - 1.7e4).abs() < 1.0, "initial pore pressure {p0}");
    assert!(p1.abs() < 0.1 * p0, "pore pressure {p1} after the run");

    // Outputs a user looks at: every file, PNGs that are PNGs, VTK headers, CSV shapes.
    for f in [
        "summary.json",
        "scene.toml",
        "history.csv",
        "breaks.csv",
        "fractures.csv",
        "centerline_pressure.csv",
        "centerline_speed.csv",
        "particles_0000.vtp",
        "bonds_0000.vtp",
        "lattice_0000.vti",
        "particles.pvd",
        "bonds.pvd",
        "lattice.pvd",
    ] {
        assert!(out.join(f).exists(), "missing {f}");
    }
    for f in [
        "snapshot_0000.png",
        "snapshot_0002.png",
        "centerline_pressure.png",
        "centerline_speed.png",
        "rose.png",
        "breaks.png",
    ] {
        let bytes = std::fs::read(out.join(f)).unwrap_or_default();
        assert!(
            bytes.len() > 5000 && bytes.starts_with(b"\x89PNG\r\n\x1a\n"),
            "{f} is not a drawn PNG ({} bytes)",
            bytes.len()
        );
    }
    let lattice = std::fs::read(out.join("lattice_0000.vti")).unwrap();
    assert!(lattice.starts_with(b"<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\""));
    let nodes = s["results"]["fluid"]["nodes"].as_array().unwrap();
    let n = nodes[0].as_u64().unwrap() * nodes[1].as_u64().unwrap();
    // Per node 1 + 3 + 1 floats of 4 bytes and a 1-byte node kind (docs/outputs.md), plus the XML text and
    // 8-byte block headers.
    assert!(lattice.len() as u64 > 21 * n && (lattice.len() as u64) < 21 * n + 4000);
    let cp = std::fs::read_to_string(out.join("centerline_pressure.csv")).unwrap();
    let rows: Vec<&str> = cp.lines().collect();
    assert_eq!(rows.len(), h.len() + 1, "one centre-line row per record");
    assert_eq!(
        rows[0].split(',').count() as u64,
        nodes[0].as_u64().unwrap() + 1
    );
    let breaks = std::fs::read_to_string(out.join("breaks.csv")).unwrap();
    assert_eq!(breaks.lines().count() as u64, b + 1);
}

#[test]
fn permeability_study_follows_the_dissertations_trends() {
    // Table 6.3: the fluid radius 0.6 → 0.725 → 0.8 → 0.95 lowers the intact sample's permeability over two
    // orders of magnitude (1.2e-4, 7e-5, 2.39e-5, 1e-6 cm²), measured the same way here (steady Darcy flow
    // through the intact sample before the drop). Asserted: k falls monotonically, and each k at fluid radius
    // 0.6–0.8 is within a factor 4 of table 6.3's. Why so loose: the sample is not the dissertation's (1560
    // randomly oriented grains per 7 × 3.5 cm against its ~1000, here a 2.4 × 1.2 cm cut of it) and the quick
    // lattice is twice as coarse (2–5 nodes across a grain's minor axis), so only the order of magnitude carries
    // over. Measured with the default TRT + ΩΛ: 1.93e-4 / 7.24e-5 / 3.47e-5 / 3.83e-6 (with ΩΛ's earlier
    // full-cover gap of 1e-3 and κ = 1.27: 1.97e-4 / 7.39e-5 / 3.57e-5 / 4.07e-6; BGK + Ω₁ₗ, the earlier
    // default, at this τ = 0.537: 1.63e-4 / 5.24e-5 / 2.03e-5 / 2.26e-6). At fluid radius 0.95 the throats are
    // far below one spacing and the quick lattice does not resolve them: TRT + ΩΛ gives 3.83e-6 here (×3.83 of
    // table 6.3, inside the factor 4 only since ΩΛ's full-cover gap is 0.05; ×4.07 before) against 1.39e-6
    // at the dissertation's spacing h = 0.009 cm (same grains, earlier gap), so that point is the one nearest
    // the bound; `quick_permeability_at_fluid_radius_095_is_within_4x_of_table_6_3` runs it alone.
    // Damage (ch. 6.8): "as the diffusivity decreases, fluid pressure within the pore spaces is higher for a
    // longer duration, providing more opportunity for fracture growth", and deformation becomes less localized.
    // Asserted: the least permeable model breaks at least 20 % more bonds than the most permeable one
    // (measured 55 against 38; 63 against 33 with ΩΛ's earlier full-cover gap), and in every model the broken
    // bonds' crack planes lie within 30° of perpendicular to σ₃ (as in the base test; measured 1.0–7.3°).
    let table = [1.2e-4, 7e-5, 2.39e-5, 1e-6];
    let mut k = Vec::new();
    let mut breaks = Vec::new();
    let mut dirs = Vec::new();
    for ((name, fr), k_table) in [
        ("base", 0.6),
        ("permeability_2", 0.725),
        ("permeability_3", 0.8),
        ("permeability_4", 0.95),
    ]
    .into_iter()
    .zip(table)
    {
        // Own output directories: the base test runs "base" at the same time.
        let (out, s) = run_scene(&quick(name), &format!("study-{name}"));
        let perm = s["results"]["permeability"]["permeability"]
            .as_f64()
            .expect("the quick permeability scenes measure k");
        let (b, total) = broken(&s);
        let o = &s["results"]["orientation"];
        eprintln!(
            "fluid radius {fr}: k = {perm:.3e} cm² (table 6.3: {k_table:.2e}), {b} of {total} bonds broken, {o}"
        );
        if fr < 0.9 {
            assert!(
                perm < 4.0 * k_table && perm > k_table / 4.0,
                "fluid radius {fr}: k = {perm:.3e}, table 6.3 {k_table:.2e}"
            );
        }
        // Crack planes of the broken bonds (the quick sample often holds a single, roundish damage zone whose
        // principal axis says little; the base test checks the traces too).
        let crack = o["crack_plane_deviation_from_perpendicular_to_sigma3_deg"]
            .as_f64()
            .unwrap_or(90.0);
        assert!(
            crack <= 30.0,
            "fluid radius {fr}: crack planes {crack}° off"
        );
        k.push(perm);
        breaks.push(b);
        dirs.push(out);
    }
    for w in k.windows(2) {
        assert!(
            w[1] < w[0],
            "permeability did not fall with the fluid radius: {k:?}"
        );
    }
    assert!(
        breaks[3] as f64 >= 1.2 * breaks[0] as f64,
        "damage did not grow as the permeability fell: {breaks:?}"
    );
    // The runs overlaid, as `lbdem compare-breaks` draws them.
    let png = out_dir("compare").with_extension("png");
    lbdem::kinds::fracture::compare_breaks(&dirs, &png).expect("comparison figure");
    let bytes = std::fs::read(&png).unwrap();
    assert!(bytes.starts_with(b"\x89PNG") && bytes.len() > 5000);
}

#[test]
fn quick_permeability_at_fluid_radius_095_is_within_4x_of_table_6_3() {
    // The factor-4 check of `permeability_study_follows_the_dissertations_trends` (reasons there) at the point
    // the quick lattice resolves least (sub-spacing throats): measured 3.83e-6 cm², ×3.83 of table 6.3 (it failed
    // at ×4.07 with ΩΛ's earlier full-cover gap of 1e-3; README).
    let (_, s) = run_scene(&quick("permeability_4"), "k095");
    let perm = s["results"]["permeability"]["permeability"]
        .as_f64()
        .expect("the quick permeability scenes measure k");
    let k_table = 1e-6;
    assert!(
        perm < 4.0 * k_table && perm > k_table / 4.0,
        "fluid radius 0.95: k = {perm:.3e}, table 6.3 {k_table:.2e}"
    );
}

/// The quick base scene with the lines starting with each given prefix replaced, written to a scene file.
fn edited_scene(name: &str, edits: &[(&str, &str)]) -> PathBuf {
    let text = std::fs::read_to_string(quick("base")).unwrap();
    let text = text
        .lines()
        .map(|l| {
            edits
                .iter()
                .find(|(prefix, _)| l.starts_with(prefix))
                .map_or(l.to_string(), |(_, line)| line.to_string())
        })
        .collect::<Vec<_>>()
        .join("\n");
    let path =
        std::env::temp_dir().join(format!("lbdem-fracture-{}-{name}.toml", std::process::id()));
    std::fs::write(&path, text).unwrap();
    path
}

/// A sample that comes apart until its grains leave the fluid lattice is stopped with the loads named, its
/// outputs kept, instead of running on with grains that feel no fluid (found on the full-size sample with a
/// lattice sound speed of 208 cm/s: pushed for longer by its pore pressure it broke 930 bonds, 290 grains flew
/// beyond the ends and the run went on silently for 50 ms until the outflow boundary diverged). Here the quick
/// sample with that sound speed, half the drop (the largest the lattice takes there) and a 0.005 cm margin:
/// measured 11 of 184 grains outside at 15 ms; the same with the scene's 0.2 cm margin keeps all of them.
#[test]
fn a_sample_whose_grains_leave_the_lattice_is_stopped_naming_the_loads() {
    let edits = |margin: &'static str| {
        [
            ("margin", margin),
            ("timestep = 2e-5", "timestep = 5e-5"),
            ("pressure_drop", "pressure_drop = 8.5e3"),
            ("duration", "duration = 0.05"),
            ("permeability", "permeability = false"),
            ("snapshot_interval", "snapshot_interval = 0.0"),
        ]
    };
    let path = edited_scene("outside", &edits("margin = 0.005"));
    let out = out_dir("outside");
    let e = run_with(&path, &out, None).unwrap_err().to_string();
    eprintln!("{e}");
    assert!(e.contains("outside the fluid lattice"), "{e}");
    assert!(e.contains("loading.axial_stress_after"), "{e}");
    assert!(e.contains("loading.pressure_drop"), "{e}");
    // Stopped once more than 5 % had left, not at the first one.
    let share: f64 = e
        .split(" grains (")
        .nth(1)
        .and_then(|r| r.split(" %)").next())
        .and_then(|v| v.parse().ok())
        .unwrap();
    assert!(share > 5.0 && share < 10.0, "{share} % outside");
    // The records up to the stop are kept.
    let h = history(&out);
    assert!(h.len() > 10, "{} records", h.len());
    // The same drop with the scene's margin: nobody leaves, the run ends normally.
    let path = edited_scene("inside", &edits("margin = 0.2"));
    let out = out_dir("inside");
    let s = run_with(&path, &out, None).expect("run");
    assert_eq!(s["results"]["grains_outside_lattice"], 0);
}

/// The quick base scene shortened to `duration`, written to a scene file of its own.
fn short_scene(name: &str, duration: f64) -> PathBuf {
    let duration = format!("duration = {duration}");
    edited_scene(
        name,
        &[
            ("duration", &duration),
            ("snapshot_interval", "snapshot_interval = 0.0"),
            ("permeability", "permeability = false"),
        ],
    )
}

fn same_files(a: &Path, b: &Path) {
    for f in [
        "history.csv",
        "breaks.csv",
        "fractures.csv",
        "centerline_pressure.csv",
        "centerline_speed.csv",
        "particles_0001.vtp",
        "bonds_0001.vtp",
        "lattice_0001.vti",
        "particles.pvd",
        "lattice.pvd",
    ] {
        let (x, y) = (std::fs::read(a.join(f)), std::fs::read(b.join(f)));
        assert!(x.is_ok(), "{f} missing in {}", a.display());
        assert!(x.unwrap() == y.unwrap_or_default(), "{f} differs");
    }
}

#[test]
fn an_interrupted_run_resumes_bitwise_identically() {
    // 0.004 s = 200 coupled steps, records every 25 steps; stopped after 100 and resumed.
    let path = short_scene("resume", 0.004);
    let whole = out_dir("resume-whole");
    run_with(&path, &whole, None).expect("uninterrupted run");
    let cut = out_dir("resume-cut");
    let stopped = run_with(&path, &cut, Some(100));
    assert!(stopped.is_err(), "a stopped run reports the interruption");
    assert!(cut.join("checkpoint.bin").exists());
    assert!(!cut.join("summary.json").exists());
    let quiet = RunOptions {
        quiet: true,
        ..Default::default()
    };
    lbdem::app::resume(&cut, &quiet).expect("resume");
    same_files(&whole, &cut);
}

/// The first chunk of a fracture run measures the intact sample's permeability and diffusivity (up to 4·10⁵
/// fluid steps at full size) before the loads drop. A stop request (Ctrl-C, SIGTERM) raised during it abandons
/// the measurements and leaves the state exactly as it was, so the run loop checkpoints at once and a resume
/// redoes them; without the request the same chunk measures and drops the loads.
#[test]
fn a_stop_request_cuts_the_intact_sample_measurements_short_with_the_state_untouched() {
    use lbdem::engine::exec::Exec;
    use lbdem::run::{Checkpoint, Kind, Stop};
    let text = std::fs::read_to_string(quick("base")).expect("scene file");
    let case = Case::<FractureTest>::read(&text, "base.toml").expect("valid scene");
    assert!(
        case.scene.output.permeability,
        "the quick base scene measures the intact sample (else this test checks nothing)"
    );
    let exec = Exec::default();
    let mut state = start_packed(&case, &exec, packing()).expect("state");
    let bytes = |s: &lbdem::kinds::fracture::FractureState| {
        Checkpoint::to_bytes(&text, "fracture", FractureTest::steps_done(s), s)
    };
    let before = bytes(&state);
    let stop = Stop::new();
    stop.request();
    FractureTest::advance_or_stop(&case, &mut state, None, &stop).expect("abandoned chunk");
    assert!(
        bytes(&state) == before,
        "an abandoned chunk changed the state"
    );
    stop.clear();
    FractureTest::advance_or_stop(&case, &mut state, None, &stop).expect("measured chunk");
    assert!(
        bytes(&state) != before,
        "the chunk without a stop request did nothing"
    );
    let results = FractureTest::results(&case, &state).expect("results");
    let k = results["permeability"]["permeability"].as_f64();
    assert!(
        k.is_some_and(|k| k > 0.0 && k.is_finite()),
        "the intact-sample permeability was not measured: {}",
        results["permeability"]
    );
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let path = short_scene("threads", 0.002);
    let mut dirs = Vec::new();
    for threads in [1, 2] {
        let dir = out_dir(&format!("threads-{threads}"));
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| run_with(&path, &dir, None).expect("run"));
        dirs.push(dir);
    }
    same_files(&dirs[0], &dirs[1]);
}

#[test]
fn bad_fracture_scenes_are_refused_naming_the_field() {
    let base = std::fs::read_to_string(quick("base")).unwrap();
    let cases: [(&str, &str, &str); 6] = [
        (
            "precision = \"f64\"",
            "precision = \"f32\"",
            "scene.precision",
        ),
        (
            "fluid_radius = 0.6 ",
            "fluid_radius = 1.5 ",
            "fluid.fluid_radius",
        ),
        ("duration = 0.05 ", "duration = 0.0 ", "loading.duration"),
        (
            "pressure_drop = 1.7e4 ",
            "pressure_drop = 1.0e6 ",
            "loading.pressure_drop",
        ),
        ("margin = 0.2 ", "margin = -1.0 ", "fluid.margin"),
        // Needles below b/a = 0.05: the ellipse contact kernel can miss their gap peak (phantom overlap).
        (
            "aspect_ratio = 0.5 ",
            "aspect_ratio = 0.04 ",
            "packing.aspect_ratio",
        ),
    ];
    for (from, to, field) in cases {
        assert!(base.contains(from), "the quick scene lost `{from}`");
        let text = base.replacen(from, to, 1);
        let err = FractureScene::from_toml(&text, "bad.toml")
            .err()
            .unwrap_or_else(|| panic!("`{to}` was accepted"))
            .to_string();
        assert!(
            err.contains(field),
            "`{to}`: error does not name {field}: {err}"
        );
    }
    // A fluid step above the DEM's critical step (the coupled DEM steps with the fluid) is refused.
    let no_drop = std::fs::read_to_string(quick("no_drop")).unwrap();
    let text = no_drop.replacen("timestep = 2e-5 ", "timestep = 1e-4 ", 1);
    let err = FractureScene::from_toml(&text, "bad.toml")
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("fluid.timestep") && err.contains("critical"),
        "{err}"
    );
    // A dry scene cannot drop a fluid pressure.
    let dry = std::fs::read_to_string(quick("dry")).unwrap();
    let text = dry.replacen("pressure_drop = 0.0", "pressure_drop = 10.0", 1);
    let err = FractureScene::from_toml(&text, "bad.toml")
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("loading.pressure_drop"), "{err}");
    // Unknown keys are named.
    let text = base.replacen("[loading]", "[loading]\npresure_drop = 1.0", 1);
    let err = FractureScene::from_toml(&text, "bad.toml")
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("presure_drop"), "{err}");
}
