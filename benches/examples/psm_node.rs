//! The cost of a covered (partially-saturated) node in units of a plain fluid node (target: a covered
//! node ≤ 3× a BGK node). The coupled bench's grains (`benches/src/coupled_scene.rs`, ~1000 bonded ellipses,
//! fluid radius 0.7) are mapped once onto an `nx × ny` lattice, which then steps with the coverage frozen (the
//! fluid step alone: no re-mapping, no DEM), interleaved block by block with a lattice without grains (same
//! sides, τ, precision, streaming). One thread; process CPU time per block (`/proc/self/stat`, 10 ms ticks, so
//! blocks of a few hundred ms). With N nodes of which N_c are covered, t the covered lattice's time per step and
//! t_0 the plain one's (mean of the blocks on either side), a covered node costs
//! 1 + (t/t_0 − 1) · N/N_c plain nodes. Two pairs: Ω₁ₗ + BGK (the benches' operator) against BGK, and ΩΛ + TRT
//! (the fracture scenes' default) against TRT and against BGK.
//!
//! `cargo run --release -p lbdem-benches --example psm_node -- [nx] [ny] [block] [rounds] [f32|f64]`
//! (defaults 1000 500 10 9 f64). `LBDEM_STREAMING=two-lattice` selects the two-lattice scheme for all.
#[path = "../src/coupled_scene.rs"]
mod coupled_scene;

use lbdem::engine::lattice::FluidLattice;
use lbdem_benches::{arg, cpu_seconds, load_average, quartiles};
use lbdem_kernels::fluid::collide::{Collision, SolidOperator, Trt};
use lbdem_kernels::Real;

/// The coupled scene's lattice without grains, with `collision`.
fn plain<T: Real>(nx: usize, ny: usize, collision: Collision<T>) -> FluidLattice<T> {
    let mut l = coupled_scene::plain_lattice::<T>(nx, ny);
    l.set_collision(collision).expect("valid rates");
    l
}

/// CPU seconds per step of `block` steps.
fn time<T: Real>(l: &mut FluidLattice<T>, block: usize) -> f64 {
    let cpu = cpu_seconds();
    for _ in 0..block {
        l.step();
    }
    (cpu_seconds() - cpu) / block as f64
}

fn run<T: Real>(nx: usize, ny: usize, block: usize, rounds: usize) {
    let dem = coupled_scene::packed_grains();
    let nodes = (nx * ny) as f64;
    let trt = Collision::Trt(Trt::default());
    let cases: [(&str, SolidOperator, Collision<T>); 2] = [
        (
            "Ω₁ₗ + BGK",
            SolidOperator::LinearizedNonEquilibriumBounceBack,
            Collision::Bgk,
        ),
        ("ΩΛ + TRT", SolidOperator::LambdaConsistent, trt),
    ];
    let mut bgk = plain::<T>(nx, ny, Collision::Bgk);
    let mut trt_plain = plain::<T>(nx, ny, trt);
    for (name, op, collision) in cases {
        let mut world = coupled_scene::coupled_world::<T>(&dem, nx, ny, 0.7);
        world.map_grains();
        let mut psm = world.fluid;
        psm.set_collision(collision).expect("valid rates");
        psm.set_solid_operator(op);
        let covered = psm.covered_nodes() as f64;
        for _ in 0..3 {
            psm.step();
            bgk.step();
            trt_plain.step();
        }
        let mut prev = (time(&mut bgk, block), time(&mut trt_plain, block));
        let (mut vs_bgk, mut vs_trt, mut t_psm) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..rounds {
            let t = time(&mut psm, block);
            let next = (time(&mut bgk, block), time(&mut trt_plain, block));
            let (b, r) = (0.5 * (prev.0 + next.0), 0.5 * (prev.1 + next.1));
            vs_bgk.push(1.0 + (t / b - 1.0) * nodes / covered);
            vs_trt.push(1.0 + (t / r - 1.0) * nodes / covered);
            t_psm.push(t);
            prev = next;
        }
        let [_, t, _] = quartiles(t_psm);
        let [a1, a2, a3] = quartiles(vs_bgk);
        let [c1, c2, c3] = quartiles(vs_trt);
        println!(
            "{} {name}: {:.0} covered nodes of {nodes:.0}; fluid step {:.2} ms CPU; a covered node = {a2:.2} \
             BGK nodes (quartiles {a1:.2} – {a3:.2}) = {c2:.2} TRT nodes ({c1:.2} – {c3:.2}); ns per covered \
             node above a BGK node: {:.1}; healthy: {}",
            T::NAME,
            covered,
            t * 1e3,
            (a2 - 1.0) * t * 1e9 / (nodes - covered + a2 * covered),
            psm.health_check(0.9, 1.1).is_none(),
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let num = |i: usize, default: usize| arg(&args, i, default);
    let (nx, ny, block, rounds) = (num(0, 1000), num(1, 500), num(2, 10), num(3, 9));
    let load_before = load_average();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("rayon pool");
    pool.install(|| match args.get(4).map_or("f64", |s| s.as_str()) {
        "f32" => run::<f32>(nx, ny, block, rounds),
        _ => run::<f64>(nx, ny, block, rounds),
    });
    println!(
        "{nx} x {ny}, {} streaming, 1 thread, {rounds} interleaved blocks of {block} steps; load average before: \
         {load_before}; after: {}",
        coupled_scene::streaming().name(),
        load_average()
    );
}
