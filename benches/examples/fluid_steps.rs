//! Run a fixed number of steps of one fluid benchmark case, for profilers (`perf record`, `valgrind
//! --tool=callgrind`, whose instruction counts are a noise-free A/B measure on a shared machine):
//! `cargo run --release -p lbdem-benches --example fluid_steps -- <bgk|psm> <f32|f64> <n> <steps>
//! [baseline|avx2|avx512]` (the last chooses the bulk pass's instruction set, see `lbdem::engine::exec`; default: the
//! widest the CPU has). `LBDEM_BAND_ROWS=k` sets the rows per parallel band; `LBDEM_STREAMING=two-lattice`
//! chooses the two-lattice scheme (default: in place, AA).
//! Same lattices as the `fluid` bench: fully periodic n × n, BGK, τ = 0.8, a gentle shear wave; `psm` covers
//! 30 % of the area with a square grid of discs (Noble–Torczynski weighting).
use std::time::Instant;

use lbdem::engine::exec::SimdLevel;
use lbdem::engine::lattice::{FluidDisc, FluidLattice, Streaming};
use lbdem_kernels::fluid::boundary::Boundaries;
use lbdem_kernels::fluid::collide::Weighting;
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::Real;

fn run<T: Real>(kind: &str, n: usize, steps: usize, simd: &str) {
    let params = FluidParams {
        tau: T::lit(0.8),
        force: [T::zero(); 2],
    };
    let mut l = FluidLattice::<T>::new(n, n, Boundaries::periodic(), params).expect("lattice");
    let k = 2.0 * std::f64::consts::PI / n as f64;
    l.fill_equilibrium(|_, y| (T::one(), [T::lit(0.01 * (k * y as f64).sin()), T::zero()]));
    if kind == "psm" {
        let spacing = 32usize;
        let h = spacing as f64;
        let radius = h * (0.30 / std::f64::consts::PI).sqrt();
        let cells = n / spacing;
        let discs: Vec<FluidDisc> = (0..cells * cells)
            .map(|c| FluidDisc {
                center: [
                    ((c % cells) as f64 + 0.5) * h - 0.5,
                    ((c / cells) as f64 + 0.5) * h - 0.5,
                ],
                radius,
                velocity: [0.001, -0.0005],
                spin: 1e-4,
            })
            .collect();
        l.cover_with_discs(&discs, Weighting::NobleTorczynski);
    }
    if let Some(level) = SimdLevel::from_name(simd) {
        l.set_simd(level)
            .expect("instruction set available on this CPU");
    }
    if let Some(rows) = std::env::var("LBDEM_BAND_ROWS")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        l.set_band_rows(rows);
    }
    if let Some(s) = std::env::var("LBDEM_STREAMING")
        .ok()
        .and_then(|v| Streaming::from_name(&v))
    {
        l.set_streaming(s);
    }
    let start = Instant::now();
    for _ in 0..steps {
        l.step();
    }
    let t = start.elapsed().as_secs_f64();
    println!(
        "{kind} {} {n}² {steps} steps ({}, {}): {:.1} MLUPS",
        T::NAME,
        l.simd().name(),
        l.streaming().name(),
        (n * n * steps) as f64 / t / 1e6
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let kind = args.get(1).map_or("bgk", String::as_str);
    let prec = args.get(2).map_or("f64", String::as_str);
    let n = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(256);
    let steps = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(10);
    let simd = args.get(5).map_or("auto", String::as_str);
    if prec == "f32" {
        run::<f32>(kind, n, steps, simd);
    } else {
        run::<f64>(kind, n, steps, simd);
    }
}
