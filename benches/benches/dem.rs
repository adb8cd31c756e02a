//! DEM step throughput of `lbdem::engine::dem::DemWorld`: particle-steps per second and candidate contacts per
//! second for bonded assemblies of 1 000, 10 000 and 100 000 particles (discs, and ellipses of aspect 0.5),
//! on 1 and 2 threads.
//!
//! The assembly: a triangular lattice of touching particles (semi-major axis 0.09 cm, 2 % size jitter,
//! 2.65 g/cm³; ellipses squeezed along y), every touching pair joined by a parallel bond (k̄ = 2.8e5 dyne/cm³),
//! contacts k_n = k_s = 1e5 dyne/cm, μ = 0.5, between four platens with the top one moving in at 0.5 cm/s,
//! Δt = 2e-5 s. One iteration = one full step (broad phase, contacts, bonds, platens, integration).
//! Throughput is in particles per iteration (criterion's elements/s = particle-steps/s); the candidate pairs
//! per step are printed at setup so that contacts/s = pairs × steps/s.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use lbdem::engine::dem::{boxed_sample, hexagonal_packing, BondSpec, DemWorld, PlatenControl};
use lbdem_kernels::dem::assembly::ContactModel;

fn assembly(side: usize, aspect: f64) -> DemWorld<f64> {
    let particles = hexagonal_packing(side, side, 0.09, aspect, 0.02, 2.65, 1);
    let model = ContactModel {
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
        tensile_strength: 500.0,
        shear_strength: 500.0,
    };
    let mut p = boxed_sample(particles, model, 2e-5, Some(bonds), 0.005).expect("bench assembly");
    let top = p.sample_box.top;
    p.world.platens[top].control = PlatenControl::Speed(0.5);
    for _ in 0..5 {
        p.world.step();
    }
    p.world
}

fn dem_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("dem_step");
    group.sample_size(10);
    group.warm_up_time(std::time::Duration::from_millis(300));
    group.measurement_time(std::time::Duration::from_secs(2));
    for (shape, aspect) in [("disc", 1.0), ("ellipse", 0.5)] {
        for side in [32usize, 100, 316] {
            for threads in [1usize, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("thread pool");
                let mut world = pool.install(|| assembly(side, aspect));
                let n = world.particles.len();
                eprintln!(
                    "dem_step {shape} n={n} threads={threads}: {} candidate pairs, {} bonds per step",
                    world.candidate_pair_list().len(),
                    world.bonds.len()
                );
                group.throughput(Throughput::Elements(n as u64));
                group.bench_with_input(
                    BenchmarkId::new(format!("{shape}_{threads}t"), n),
                    &n,
                    |b, _| b.iter(|| pool.install(|| world.step())),
                );
            }
        }
    }
    group.finish();
}

criterion_group!(benches, dem_step);
criterion_main!(benches);
