//! The coupled step against the plain BGK step at the same size, in one run (ratio target:
//! coupled ≥ 0.35× BGK). Two lattices of the coupled bench's size (default 1000 × 500, the fracture test's order
//! of magnitude): the coupled world of `benches/coupled.rs` (~1000 bonded ellipse grains, Ω₁ₗ, fluid radius 0.7,
//! pressure drop west → east, walls north and south) and a plain BGK lattice with the same sides, τ, precision and
//! streaming scheme but no grains. They are stepped in alternating blocks of `block` steps, `rounds` times; each
//! coupled block's time is divided by the mean of the BGK blocks on either side of it, so the ratio is measured
//! side by side on a shared machine. Prints, per thread count, the median MLUPS (million node updates per second;
//! for the coupled step, lattice nodes × steps / time: "MLUPS-equivalent") of each, the median ratio with its
//! quartiles, the coupled step's split (fluid / re-mapping / coupling / DEM, from `StepTimings` summed over the
//! coupled blocks) and the load average before and after. On a machine shared with other jobs the wall times
//! swing with the load; the process CPU time of each block (from `/proc/self/stat`, 10 ms ticks, so blocks of a
//! few hundred ms) swings much less, and on one thread it measures the work itself: the one-thread line also
//! gives the ratio of the CPU times ("CPU ratio").
//!
//! `cargo run --release -p lbdem-benches --example coupled_ratio -- [nx] [ny] [block] [rounds] [f32|f64]`
//! (defaults 1000 500 20 15 f64). `LBDEM_STREAMING=two-lattice` selects the two-lattice scheme for both.
#[path = "../src/coupled_scene.rs"]
mod coupled_scene;

use lbdem_benches::{arg, cpu_seconds, load_average, quartiles};
use std::time::Instant;

use lbdem::engine::coupled::CoupledWorld;
use lbdem::engine::lattice::FluidLattice;
use lbdem_kernels::Real;

fn run<T: Real>(
    dem: &lbdem::engine::dem::DemWorld<f64>,
    nx: usize,
    ny: usize,
    block: usize,
    rounds: usize,
    threads: usize,
) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("rayon pool");
    pool.install(|| {
        let mut coupled: CoupledWorld<T> =
            coupled_scene::coupled_world::<T>(dem, nx, ny, 0.7);
        let mut bgk = coupled_scene::plain_lattice::<T>(nx, ny);
        // Warm-up (first touch by this pool).
        for _ in 0..3 {
            coupled.step();
            bgk.step();
        }
        coupled.enable_timings();
        // (wall, CPU) seconds of a block.
        let time_bgk = |l: &mut FluidLattice<T>| {
            let (t, cpu) = (Instant::now(), cpu_seconds());
            for _ in 0..block {
                l.step();
            }
            (t.elapsed().as_secs_f64(), cpu_seconds() - cpu)
        };
        let mut b_prev = time_bgk(&mut bgk);
        let (mut c_times, mut b_times, mut ratios) = (Vec::new(), vec![b_prev.0], Vec::new());
        let (mut c_cpu, mut b_cpu, mut cpu_ratios) = (Vec::new(), vec![b_prev.1], Vec::new());
        for _ in 0..rounds {
            let (t, cpu) = (Instant::now(), cpu_seconds());
            for _ in 0..block {
                coupled.step();
            }
            let (c, cc) = (t.elapsed().as_secs_f64(), cpu_seconds() - cpu);
            let b_next = time_bgk(&mut bgk);
            ratios.push(0.5 * (b_prev.0 + b_next.0) / c);
            cpu_ratios.push(0.5 * (b_prev.1 + b_next.1) / cc);
            c_times.push(c);
            b_times.push(b_next.0);
            c_cpu.push(cc);
            b_cpu.push(b_next.1);
            b_prev = b_next;
        }
        let mlups = |secs: f64| (nx * ny * block) as f64 / secs / 1e6;
        let [_, c_med, _] = quartiles(c_times);
        let [_, b_med, _] = quartiles(b_times);
        let [r1, r2, r3] = quartiles(ratios);
        let [_, cc_med, _] = quartiles(c_cpu);
        let [_, bc_med, _] = quartiles(b_cpu);
        let [q1, q2, q3] = quartiles(cpu_ratios);
        let cpu_line = format!(
            " | CPU: coupled {:.2} ms/step, BGK {:.2} ms/step, CPU ratio {q2:.3} (quartiles {q1:.3} – {q3:.3})",
            cc_med * 1e3 / block as f64,
            bc_med * 1e3 / block as f64,
        );
        let split = *coupled.timings().expect("timings enabled");
        let total = split.total().as_secs_f64();
        let pct = |d: std::time::Duration| 100.0 * d.as_secs_f64() / total;
        let healthy = coupled.fluid.health_check(0.9, 1.1).is_none();
        println!(
            "{} {threads}T: coupled {:.2} ms/step = {:.1} MLUPS-eq | BGK {:.2} ms/step = {:.1} MLUPS | \
             coupled/BGK {r2:.3} (quartiles {r1:.3} – {r3:.3}) | split fluid {:.0} %, re-mapping {:.0} %, \
             coupling {:.0} %, DEM {:.0} % | covered nodes {} | densities in [0.9, 1.1]: {healthy}{}",
            T::NAME,
            c_med * 1e3 / block as f64,
            mlups(c_med),
            b_med * 1e3 / block as f64,
            mlups(b_med),
            pct(split.fluid),
            pct(split.coverage),
            pct(split.coupling),
            pct(split.dem),
            coupled.fluid.covered_nodes(),
            if threads == 1 { cpu_line.as_str() } else { "" },
        );
    });
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let num = |i: usize, default: usize| arg(&args, i, default);
    let (nx, ny, block, rounds) = (num(0, 1000), num(1, 500), num(2, 20), num(3, 15));
    let prec = args.get(4).map_or("f64", |s| s.as_str());
    let load_before = load_average();
    let start = Instant::now();
    let dem = coupled_scene::packed_grains();
    println!(
        "{nx} x {ny} lattice, {} grains, {} bonds (packed in {:.1} s), {} streaming, {rounds} interleaved blocks \
         of {block} steps per thread count",
        dem.particles.len(),
        dem.bonds.len(),
        start.elapsed().as_secs_f64(),
        coupled_scene::streaming().name()
    );
    for threads in [1, 2] {
        match prec {
            "f32" => run::<f32>(&dem, nx, ny, block, rounds, threads),
            _ => run::<f64>(&dem, nx, ny, block, rounds, threads),
        }
    }
    println!(
        "load average before: {load_before}; after: {} ({} CPUs)",
        load_average(),
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
}
