//! Time split of the coupled step at the fracture test's size: fluid (collide + stream), coverage (re-mapping the
//! grains onto the lattice), coupling (force/torque reduction) and DEM, from [`CoupledWorld`]'s opt-in
//! [`StepTimings`], for f64 and f32 fluid and 1 and 2 threads. Same scene as the `coupled` bench.
//!
//! `cargo run --release -p lbdem-benches --example coupled_split -- [nx] [ny] [steps] [fluid_radius]`
//! (defaults 1000 500 10 0.7). Each configuration runs `steps` steps after 3 warm-up steps, repeated 3 times;
//! the repeat with the smallest total is printed (least disturbed by other processes on a shared machine).
//! `LBDEM_SOLID_OPERATOR=lambda` runs TRT (Λ = 3/16) + ΩΛ (`LambdaConsistent`, the fracture scenes' default, whose
//! re-mapping also computes the open-link masks) instead of the bench scene's BGK + Ω₁ₗ; with it,
//! `LBDEM_LAMBDA_TERMS=friction` turns ΩΛ's wall-pressure force off (`LambdaTerms::FRICTION_ONLY`).
#[path = "../src/coupled_scene.rs"]
mod coupled_scene;

use std::time::Duration;

use lbdem::engine::coupled::StepTimings;
use lbdem_kernels::fluid::collide::{Collision, LambdaTerms, SolidOperator, Trt};
use lbdem_kernels::Real;

/// Whether `LBDEM_SOLID_OPERATOR=lambda` asks for TRT + ΩΛ.
fn lambda() -> bool {
    std::env::var("LBDEM_SOLID_OPERATOR").is_ok_and(|v| v == "lambda")
}

/// Whether `LBDEM_LAMBDA_TERMS=friction` asks for ΩΛ without its wall-pressure force (the form before it became
/// the default), to price that force side by side in one binary.
fn friction_only() -> bool {
    std::env::var("LBDEM_LAMBDA_TERMS").is_ok_and(|v| v == "friction")
}

fn ms(d: Duration, steps: u64) -> f64 {
    d.as_secs_f64() * 1e3 / steps as f64
}

fn run<T: Real>(
    dem: &lbdem::engine::dem::DemWorld<f64>,
    nx: usize,
    ny: usize,
    steps: u64,
    radius: f64,
    precision: &str,
    threads: usize,
) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("rayon pool");
    let mut best: Option<StepTimings> = None;
    let mut covered = 0;
    let mut healthy = true;
    for _ in 0..3 {
        let mut w = coupled_scene::coupled_world::<T>(dem, nx, ny, radius);
        if lambda() {
            let trt = Trt::new(T::lit(Trt::<T>::DEFAULT_MAGIC)).expect("Λ = 3/16");
            w.fluid
                .set_collision(Collision::Trt(trt))
                .expect("TRT at τ = 0.8");
            w.fluid.set_solid_operator(SolidOperator::LambdaConsistent);
            if friction_only() {
                w.fluid
                    .set_lambda_terms(LambdaTerms::FRICTION_ONLY)
                    .expect("friction-only ΩΛ");
            }
        }
        let t = pool.install(|| {
            for _ in 0..3 {
                w.step();
            }
            w.enable_timings();
            for _ in 0..steps {
                w.step();
            }
            *w.timings().expect("timings enabled")
        });
        covered = w.fluid.covered_nodes();
        healthy &= w.fluid.health_check(0.9, 1.1).is_none();
        if best.is_none_or(|b| t.total() < b.total()) {
            best = Some(t);
        }
    }
    let t = best.expect("three repeats");
    let total = t.total();
    let pct = |d: Duration| 100.0 * d.as_secs_f64() / total.as_secs_f64();
    let mlups = (nx * ny) as f64 * steps as f64 / total.as_secs_f64() / 1e6;
    println!(
        "{} {precision} {threads}T r={radius}: {:.2} ms/step, {mlups:.1} MLUPS-eq | fluid {:.2} ms ({:.0} %) | \
         coverage {:.2} ms ({:.0} %) | coupling {:.2} ms ({:.0} %) | dem {:.2} ms ({:.0} %) | covered nodes {covered} | densities in [0.9, 1.1]: {healthy}",
        match (lambda(), friction_only()) {
            (true, true) => "TRT+ΩΛ(friction only)",
            (true, false) => "TRT+ΩΛ",
            _ => "BGK+Ω₁ₗ",
        },
        ms(total, steps),
        ms(t.fluid, steps),
        pct(t.fluid),
        ms(t.coverage, steps),
        pct(t.coverage),
        ms(t.coupling, steps),
        pct(t.coupling),
        ms(t.dem, steps),
        pct(t.dem),
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: f64| lbdem_benches::arg(&args, i, default);
    let (nx, ny) = (arg(0, 1000.0) as usize, arg(1, 500.0) as usize);
    let steps = arg(2, 10.0) as u64;
    let radius = arg(3, 0.7);
    let start = std::time::Instant::now();
    let dem = coupled_scene::packed_grains();
    println!(
        "{nx} x {ny} lattice, {} grains, {} bonds, packed in {:.1} s; load average {}",
        dem.particles.len(),
        dem.bonds.len(),
        start.elapsed().as_secs_f64(),
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
    for threads in [1, 2] {
        run::<f64>(&dem, nx, ny, steps, radius, "f64", threads);
        run::<f32>(&dem, nx, ny, steps, radius, "f32", threads);
    }
}
