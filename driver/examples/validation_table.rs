//! Regenerates README's fluid validation table: `cargo run --release -p lbdem --example validation_table`.
//!
//! Runs the same cases as `driver/tests/poiseuille.rs` (which asserts the tolerances listed here) and prints
//! a markdown table: case, measured error, tolerance asserted by the test.
use lbdem::engine::exec::Exec;
use lbdem::kinds::channel::{simulate, Channel, ChannelOutcome, ChannelScene, ChannelSetup};
use lbdem::run::Case;

fn solve(
    ny: usize,
    nx: usize,
    tau: f64,
    drive: &str,
    strength: f64,
) -> (ChannelSetup, ChannelOutcome) {
    let nu = (tau - 0.5) / 3.0;
    let steps = (35.0 * (ny * ny) as f64 / (std::f64::consts::PI.powi(2) * nu)) as u64
        + 40 * nx as u64
        + 2000;
    let (length, key) = if drive == "pressure" {
        ((nx - 1) as f64, "pressure_drop")
    } else {
        (nx as f64, "acceleration")
    };
    let text = format!(
        "[scene]\nkind = \"channel\"\nunits = \"cgs\"\n[fluid]\ndensity = 1.0\nviscosity = {nu:e}\nspacing = 1.0\n\
         tau = {tau:e}\n[channel]\nlength = {length:e}\nwidth = {ny}.0\ndrive = \"{drive}\"\n{key} = {strength:e}\n\
         [run]\nsteps = {steps}\nsteady_tolerance = 1e-13\ncheck_interval = 100\n"
    );
    let case = Case::<Channel>::new(ChannelScene::from_toml(&text, "validation").expect("scene"))
        .expect("setup");
    let out = simulate(&case, &Exec::default()).expect("run");
    (case.setup, out)
}

fn slope(points: &[(f64, f64)]) -> f64 {
    let m = points.len() as f64;
    let mx = points.iter().map(|p| p.0.ln()).sum::<f64>() / m;
    let my = points.iter().map(|p| p.1.ln()).sum::<f64>() / m;
    let num: f64 = points
        .iter()
        .map(|p| (p.0.ln() - mx) * (p.1.ln() - my))
        .sum();
    let den: f64 = points.iter().map(|p| (p.0.ln() - mx).powi(2)).sum();
    num / den
}

fn main() {
    println!("| case | measured | tolerance (test) |");
    println!("|---|---|---|");
    let tau = 0.875;
    let nu = (tau - 0.5) / 3.0;
    let mut pts = Vec::new();
    for ny in [3usize, 4, 5, 7, 9, 13, 19, 27, 39] {
        let g = 8.0 * nu * (0.02 / 3f64.sqrt()) / (ny * ny) as f64;
        let (_, out) = solve(ny, 1, tau, "body_force", g);
        pts.push((ny as f64, out.l2_error));
        if [3, 9, 39].contains(&ny) {
            println!("| Poiseuille, body force, τ = 0.875, {ny} nodes across: L2 error | {:.3e} | = slip formula (16Λ−3)/(3H²) to 1e-9 |", out.l2_error);
        }
    }
    println!(
        "| Poiseuille, body force, 3…39 nodes: convergence order | {:.3} | 2 ± 0.1 |",
        -slope(&pts)
    );
    let ts = 0.5 + (3.0f64 / 16.0).sqrt();
    let (_, out) = solve(
        16,
        1,
        ts,
        "body_force",
        8.0 * (ts - 0.5) / 3.0 * 0.01 / 256.0,
    );
    println!(
        "| Poiseuille, body force, τ* = ½+√(3/16), 16 nodes: L2 error | {:.1e} | < 1e-9 |",
        out.l2_error
    );
    let mut pts = Vec::new();
    for ny in [3usize, 5, 9, 17] {
        let nx = 8 * ny + 1;
        let dp = 8.0 * nu * (0.01 / 3f64.sqrt()) / (ny * ny) as f64 * (nx - 1) as f64;
        let (_, out) = solve(ny, nx, tau, "pressure", dp);
        pts.push((ny as f64, out.l2_error));
        let predicted = (16.0 * (tau - 0.5f64).powi(2) - 3.0) / (3.0 * (ny * ny) as f64);
        if ny == 9 {
            println!(
                "| Poiseuille, Zou–He pressure, 9 nodes: centre error / slip prediction | {:.3} | 1 ± 0.1 |",
                out.centre_velocity_error / predicted
            );
        }
    }
    println!(
        "| Poiseuille, Zou–He pressure, 3…17 nodes: convergence order | {:.3} | 2 ± 0.15 |",
        -slope(&pts)
    );
    let mut pts = Vec::new();
    for drho in [0.02, 0.04, 0.08, 0.16] {
        let (setup, out) = solve(12, 49, ts, "pressure", drho / 3.0);
        pts.push((setup.mach, out.l2_error));
    }
    println!(
        "| Error vs Mach (τ*, 12 nodes, Ma 0.03–0.24): slope of log error vs log Ma | {:.3} | 2 ± 0.2 |",
        slope(&pts)
    );
    for drop in [0.01, 0.10, 0.20] {
        let (setup, out) = solve(10, 41, tau, "pressure", drop / 3.0);
        println!(
            "| Density drop {:.0} % along the channel (Ma {:.3}), 10 nodes: L2 error | {:.3e} | < 1.5·slip + Ma² = {:.2e} |",
            drop * 100.0,
            setup.mach,
            out.l2_error,
            1.5 * 0.25 / 100.0 + setup.mach.powi(2)
        );
    }
}
