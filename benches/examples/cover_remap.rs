//! Time `FluidLattice::cover_with_bodies` alone (the coupled step's re-mapping of the grains onto the lattice) on
//! the coupled bench's scale: a 1000 × 500 lattice and 1000 ellipses (aspect 0.5, semi-major axes 8.6–13.5
//! nodes as the fluid sees the ch. 6.6 grains at fluid radius 0.7), every body moved by ~1e-3 nodes and turned
//! by ~1e-3 rad between calls (so no cell fraction can be reused), like grains in a coupled run. Uses only API
//! that predates the incremental re-mapping, so the same file measures an older commit for an A/B comparison.
//!
//! `cargo run --release -p lbdem-benches --example cover_remap -- [calls] [threads]` (defaults 30, 1);
//! `LBDEM_SOLID_OPERATOR=lambda` re-maps under ΩΛ (`LambdaConsistent`, the fracture scenes' default: the
//! re-mapping then also computes the open-link masks), otherwise under Ω₁ₗ as the coupled bench. Prints
//! wall time and process CPU time per call (the CPU time is less disturbed by other processes on a shared
//! machine), a checksum of the solid-fraction map (equal across versions with the same coverage kernel: the
//! re-mapping itself is bitwise the same), the solid area, and the number of nodes with a roundoff-level
//! (0 < ε < 1e-9) or an exactly full (ε = 1) solid fraction.
use lbdem_benches::cpu_seconds;
use std::time::Instant;

use lbdem::engine::lattice::FluidLattice;
use lbdem_kernels::coupling::{BodyShape, CoupledBody};
use lbdem_kernels::fluid::boundary::Boundaries;
use lbdem_kernels::fluid::collide::{SolidOperator, Weighting};
use lbdem_kernels::fluid::step::FluidParams;

/// Deterministic pseudo-random number in [0, 1) from an integer (SplitMix64 finaliser).
fn unit(k: u64) -> f64 {
    let mut z = k.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    (z ^ (z >> 31)) as f64 / 2f64.powi(64)
}

fn bodies(call: u64) -> Vec<CoupledBody<f64>> {
    (0..1000u64)
        .map(|k| {
            let (i, j) = ((k % 40) as f64, (k / 40) as f64);
            let a = 8.6 + 4.9 * unit(3 * k);
            let drift = 1e-3 * call as f64;
            CoupledBody {
                center: lbdem_kernels::math::vector(
                    12.5 + 25.0 * i + drift,
                    10.0 + 20.0 * j - 0.5 * drift,
                ),
                velocity: lbdem_kernels::math::vector(1e-3, -5e-4),
                spin: 1e-4,
                shape: BodyShape::Ellipse {
                    semi_major: a,
                    semi_minor: 0.5 * a,
                    angle: std::f64::consts::TAU * unit(3 * k + 1) + drift,
                },
            }
        })
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let calls: u64 = args.first().map_or(30, |s| s.parse().expect("calls"));
    let threads: usize = args.get(1).map_or(1, |s| s.parse().expect("threads"));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("rayon pool");
    let params = FluidParams {
        tau: 0.8,
        force: [0.0; 2],
    };
    let mut lattice =
        FluidLattice::<f64>::new(1000, 500, Boundaries::periodic(), params).expect("lattice");
    let lambda = std::env::var("LBDEM_SOLID_OPERATOR").is_ok_and(|v| v == "lambda");
    lattice.set_solid_operator(if lambda {
        SolidOperator::LambdaConsistent
    } else {
        SolidOperator::LinearizedNonEquilibriumBounceBack
    });
    let sets: Vec<_> = (0..=calls).map(bodies).collect();
    pool.install(|| lattice.cover_with_bodies(&sets[0], Weighting::NobleTorczynski));
    let (cpu0, wall0) = (cpu_seconds(), Instant::now());
    pool.install(|| {
        for set in &sets[1..] {
            lattice.cover_with_bodies(set, Weighting::NobleTorczynski);
        }
    });
    let wall = wall0.elapsed().as_secs_f64();
    let cpu = cpu_seconds() - cpu0;
    let eps = lattice.solid_fraction_map();
    let checksum = eps.iter().fold(0u64, |h, v| h.rotate_left(5) ^ v.to_bits());
    let tiny = eps.iter().filter(|&&v| v > 0.0 && v < 1e-9).count();
    let full = eps.iter().filter(|&&v| v == 1.0).count();
    println!(
        "{} {threads} thread(s): {:.2} ms wall, {:.2} ms CPU per call; {} covered nodes, solid area {:.6}, checksum {checksum:016x}; {tiny} nodes with 0 < ε < 1e-9 (roundoff), {full} with ε = 1",
        if lambda { "ΩΛ" } else { "Ω₁ₗ" },
        1e3 * wall / calls as f64,
        1e3 * cpu / calls as f64,
        lattice.covered_nodes(),
        eps.iter().sum::<f64>()
    );
}
