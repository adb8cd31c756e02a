//! Helpers shared by the driver's integration tests.
#![allow(dead_code)]
pub mod moving_cases;
pub mod psm_cases;
pub mod scene_text;
pub mod tweaked_demo;
pub mod wall_cases;
use lbdem::engine::exec::Exec;
use lbdem::kinds::channel::{simulate, Channel, ChannelOutcome, ChannelScene};
use lbdem::run::Case;
use std::path::{Path, PathBuf};

/// Every file under `dir` (recursively) whose extension is `ext`, sorted.
pub fn files_with_extension(dir: &Path, ext: &str) -> Vec<PathBuf> {
    fn walk(dir: &Path, ext: &str, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() {
                walk(&p, ext, out);
            } else if p.extension().is_some_and(|e| e == ext) {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, ext, &mut out);
    out.sort();
    out
}

/// A channel scene written directly in lattice units (h = 1, Δt = 1, ρ₀ = 1, so ν = (τ − ½)/3 and a pressure
/// of p is a lattice density change of 3p).
pub fn lattice_channel(
    ny: usize,
    nx: usize,
    tau: f64,
    drive: &str,
    strength: f64,
    steps: u64,
    tol: f64,
) -> ChannelScene {
    let nu = lbdem::units::lattice_viscosity(tau);
    let (length, key) = match drive {
        "pressure" => ((nx - 1) as f64, "pressure_drop"),
        _ => (nx as f64, "acceleration"),
    };
    let text = format!(
        r#"
[scene]
kind = "channel"
units = "cgs"
[fluid]
density = 1.0
viscosity = {nu:e}
spacing = 1.0
tau = {tau:e}
[channel]
length = {length:e}
width = {ny}.0
drive = "{drive}"
{key} = {strength:e}
[run]
steps = {steps}
steady_tolerance = {tol:e}
check_interval = 100
"#
    );
    ChannelScene::from_toml(&text, "test").expect("test scene parses")
}

/// Least-squares slope of log(err) against log(n).
pub fn loglog_slope(points: &[(f64, f64)]) -> f64 {
    let m = points.len() as f64;
    let (sx, sy) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), &(n, e)| (a + n.ln(), b + e.ln()));
    let (mx, my) = (sx / m, sy / m);
    let (mut num, mut den) = (0.0, 0.0);
    for &(n, e) in points {
        num += (n.ln() - mx) * (e.ln() - my);
        den += (n.ln() - mx).powi(2);
    }
    num / den
}

/// Run a channel scene in memory with the steady tolerance `tol` (`None`: every step) checked every `interval`
/// steps.
pub fn run_channel(
    scene: &ChannelScene,
    tol: Option<f64>,
    interval: u64,
) -> lbdem::error::Result<ChannelOutcome> {
    let mut scene = scene.clone();
    scene.run.steady_tolerance = tol;
    scene.run.check_interval = Some(interval);
    simulate(&Case::<Channel>::new(scene)?, &Exec::default())
}

/// A small bonded packing of the dissertation's ellipses (1.2 × 1.2 cm, aspect 0.5, point bonds of table 6.1,
/// seed 3): ellipse pairs in contact, for the tests of the pair pass.
pub fn bonded_ellipse_packing() -> lbdem::engine::dem::Packing<f64> {
    use lbdem::engine::dem::{generate_packing, BondSpec, PackingSpec};
    let mut spec = PackingSpec::dissertation(1.2, 1.2, 0.5, 3);
    spec.max_servo_steps = 2000;
    let bonds = Some(BondSpec::Point {
        stiffness: 1e5,
        strength: 700.0,
    });
    generate_packing(&spec, bonds).unwrap()
}
