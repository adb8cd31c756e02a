//! Cost of a TRT node over a BGK node, measured on a shared machine by interleaving: two lattices (the `fluid`
//! bench's periodic shear wave, τ = 0.8, one BGK, one TRT with Λ = 3/16) are stepped in alternating blocks of
//! steps, `rounds` times, and the ratio of each TRT block's time to the mean of the BGK blocks around it is
//! recorded; the median ratio is printed with its interquartile range and the load average.
//!
//! `cargo run --release -p lbdem-benches --example trt_ratio -- [n] [f32|f64] [threads] [rounds]`
//! (defaults 256 f64 1 41). 256² (9 MB of f64 populations) sits in the last-level cache, where the collision's
//! arithmetic, not memory, sets the time: the harder case for TRT.
use std::time::Instant;

use lbdem::engine::lattice::FluidLattice;
use lbdem_kernels::fluid::boundary::Boundaries;
use lbdem_kernels::fluid::collide::{Collision, Trt};
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::Real;

fn lattice<T: Real>(n: usize, collision: Collision<T>) -> FluidLattice<T> {
    let params = FluidParams {
        tau: T::lit(0.8),
        force: [T::zero(); 2],
    };
    let mut l = FluidLattice::<T>::new(n, n, Boundaries::periodic(), params).expect("lattice");
    l.set_collision(collision).expect("valid rates");
    let k = 2.0 * std::f64::consts::PI / n as f64;
    l.fill_equilibrium(|_, y| (T::one(), [T::lit(0.01 * (k * y as f64).sin()), T::zero()]));
    l
}

fn block<T: Real>(l: &mut FluidLattice<T>, steps: usize) -> f64 {
    let t = Instant::now();
    for _ in 0..steps {
        l.step();
    }
    t.elapsed().as_secs_f64()
}

fn run<T: Real>(n: usize, threads: usize, rounds: usize) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    pool.install(|| {
        let mut bgk = lattice::<T>(n, Collision::Bgk);
        let mut trt = lattice::<T>(n, Collision::Trt(Trt::default()));
        // About 0.1 s per block.
        let steps = (2e7 / (n * n) as f64).ceil() as usize;
        block(&mut bgk, steps);
        block(&mut trt, steps);
        let mut b_prev = block(&mut bgk, steps);
        let mut ratios = Vec::with_capacity(rounds);
        for _ in 0..rounds {
            let t = block(&mut trt, steps);
            let b_next = block(&mut bgk, steps);
            ratios.push(t / (0.5 * (b_prev + b_next)));
            b_prev = b_next;
        }
        ratios.sort_by(f64::total_cmp);
        let q = |p: f64| ratios[((ratios.len() - 1) as f64 * p).round() as usize];
        println!(
            "TRT / BGK node time, {n}², {}, {threads} thread(s), {rounds} interleaved blocks of {steps} steps: \
             median {:.3} (quartiles {:.3} – {:.3})",
            T::NAME,
            q(0.5),
            q(0.25),
            q(0.75)
        );
    });
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(256, |v| v.parse().expect("n"));
    let prec = args.get(2).map_or("f64", |s| s.as_str());
    let threads: usize = args.get(3).map_or(1, |v| v.parse().expect("threads"));
    let rounds: usize = args.get(4).map_or(41, |v| v.parse().expect("rounds"));
    let load = || std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    println!("load average before: {}", load().trim());
    match prec {
        "f32" => run::<f32>(n, threads, rounds),
        _ => run::<f64>(n, threads, rounds),
    }
    println!("load average after: {}", load().trim());
}
