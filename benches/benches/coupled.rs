//! Coupled LB–DEM step at the fracture test's size: [`CoupledWorld::step`] (grains → PSM coverage → fluid step →
//! force/torque → DEM) on a 1000 × 500 lattice (500 000 nodes) with ~1000 bonded ellipse grains (aspect 0.5,
//! packed by `generate_packing`, see `src/coupled_scene.rs`), fluid radius 0.7, solid operator Ω₁ₗ
//! (`LinearizedNonEquilibriumBounceBack`, the fracture scenes' default), a small pressure drop west → east, f64 and f32 fluid
//! (the DEM is f64), 1 and 2 threads.
//!
//! Prints, per case, the median time per step over the criterion samples, the MLUPS-equivalent (lattice nodes ×
//! steps / time) and the split of the step between fluid (collide + stream), coverage (re-mapping the grains),
//! coupling (force/torque reduction) and DEM from [`CoupledWorld`]'s opt-in [`StepTimings`] (summed over every
//! step the case ran, warm-up included).
//!
//! Each sample runs blocks of at most `BLOCK` steps, each on a fresh copy of the scene (two untimed warm-up
//! steps), and the summary says whether every block ended with all fluid densities in [0.9, 1.1]. (The blocks
//! were introduced when this bench used Ω₃, which is unstable with free grains: see the kernel's `SolidOperator`
//! documentation.) Regenerate with `cargo bench -p lbdem-benches --bench coupled`; the
//! packing takes ~20 s before the first case. `examples/coupled_split.rs` prints the same split without criterion.
//! The fluid streams in place (AA) unless `LBDEM_STREAMING=two-lattice` is set; the title line names the scheme.
#[path = "../src/coupled_scene.rs"]
mod coupled_scene;

use lbdem_benches::load_average;
use std::collections::BTreeMap;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput};
use lbdem::engine::coupled::{CoupledWorld, StepTimings};
use lbdem::engine::dem::DemWorld;
use lbdem_kernels::Real;

/// Steps timed on one world before a fresh one is built (the first two steps of each world are not timed).
const BLOCK: u64 = 50;
/// Criterion samples per case.
const SAMPLES: usize = 10;
/// Thread counts benchmarked.
const THREADS: [usize; 2] = [1, 2];
/// Lattice size (the fracture test's order of magnitude: 500 000 nodes).
const NX: usize = 1000;
/// Lattice height.
const NY: usize = 500;
/// Fraction of each grain's size the fluid sees (the dissertation's permeability study: 0.6 … 0.95).
const FLUID_RADIUS: f64 = 0.7;

/// Per-step durations of each criterion call, keyed by case.
static SAMPLES_BY_CASE: Mutex<BTreeMap<String, Vec<Duration>>> = Mutex::new(BTreeMap::new());
/// Stage split, covered nodes and whether the fluid stayed within density [0.9, 1.1], keyed by case.
static SPLIT_BY_CASE: Mutex<BTreeMap<String, (StepTimings, usize, bool)>> =
    Mutex::new(BTreeMap::new());

fn record(case: &str, per_step: Duration) {
    if let Ok(mut map) = SAMPLES_BY_CASE.lock() {
        map.entry(case.to_string()).or_default().push(per_step);
    }
}

/// Median time per step (s) over the last `SAMPLES` calls (criterion's measurement samples follow its warm-up).
fn median_step(case: &str) -> Option<f64> {
    let map = SAMPLES_BY_CASE.lock().ok()?;
    let all = map.get(case)?;
    let mut secs: Vec<f64> = all[all.len().saturating_sub(SAMPLES)..]
        .iter()
        .map(Duration::as_secs_f64)
        .collect();
    secs.sort_by(f64::total_cmp);
    let m = secs.len();
    match m {
        0 => None,
        _ if m % 2 == 1 => Some(secs[m / 2]),
        _ => Some(0.5 * (secs[m / 2 - 1] + secs[m / 2])),
    }
}

fn case_name(prec: &str, threads: usize) -> String {
    format!("coupled/{prec}/{threads}t")
}

fn bench_coupled<T: Real>(c: &mut Criterion, dem: &DemWorld<f64>) {
    let mut group = c.benchmark_group(format!("coupled/{}", T::NAME));
    group
        .sample_size(SAMPLES)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5))
        .throughput(Throughput::Elements((NX * NY) as u64));
    for threads in THREADS {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("rayon pool");
        let case = case_name(T::NAME, threads);
        let mut split = StepTimings::default();
        let mut covered = 0;
        let mut healthy = true;
        group.bench_function(
            BenchmarkId::new(format!("{NX}x{NY}"), format!("{threads}t")),
            |b| {
                b.iter_custom(|iters| {
                    // Blocks of at most BLOCK steps, each from a fresh world (built outside the timing).
                    let mut elapsed = Duration::ZERO;
                    let mut left = iters;
                    while left > 0 {
                        let n = left.min(BLOCK);
                        left -= n;
                        let mut world: CoupledWorld<T> = pool.install(|| {
                            let mut w =
                                coupled_scene::coupled_world::<T>(dem, NX, NY, FLUID_RADIUS);
                            // First touch of the buffers by the pool that runs the steps.
                            w.step();
                            w.step();
                            w.enable_timings();
                            w
                        });
                        elapsed += pool.install(|| {
                            let start = Instant::now();
                            for _ in 0..n {
                                world.step();
                            }
                            start.elapsed()
                        });
                        if let Some(t) = world.timings() {
                            split.steps += t.steps;
                            split.fluid += t.fluid;
                            split.coverage += t.coverage;
                            split.coupling += t.coupling;
                            split.dem += t.dem;
                        }
                        covered = world.fluid.covered_nodes();
                        healthy &= world.fluid.health_check(0.9, 1.1).is_none();
                    }
                    record(&case, elapsed / iters.max(1) as u32);
                    elapsed
                })
            },
        );
        if let Ok(mut map) = SPLIT_BY_CASE.lock() {
            map.insert(case, (split, covered, healthy));
        }
    }
    group.finish();
}

fn print_summary(grains: usize, bonds: usize) {
    println!();
    println!(
        "=== coupled step, {NX} x {NY} lattice, {grains} ellipse grains (aspect 0.5), {bonds} bonds, fluid radius \
         {FLUID_RADIUS}, Ω₁ₗ, {} streaming (median of {SAMPLES} samples) ===",
        coupled_scene::streaming().name()
    );
    println!(
        "{:<4} {:>7} {:>9} {:>9} {:>8} {:>9} {:>9} {:>6} {:>8} {:>7}",
        "prec",
        "threads",
        "ms/step",
        "MLUPS-eq",
        "fluid",
        "coverage",
        "coupling",
        "dem",
        "covered",
        "healthy"
    );
    let splits = SPLIT_BY_CASE.lock().map(|m| m.clone()).unwrap_or_default();
    for prec in ["f64", "f32"] {
        for threads in THREADS {
            let case = case_name(prec, threads);
            let (Some(t), Some((split, covered, healthy))) =
                (median_step(&case), splits.get(&case))
            else {
                continue;
            };
            let total = split.total().as_secs_f64();
            let pct = |d: Duration| format!("{:.0} %", 100.0 * d.as_secs_f64() / total);
            println!(
                "{prec:<4} {threads:>7} {:>9.2} {:>9.1} {:>8} {:>9} {:>9} {:>6} {covered:>8} {healthy:>7}",
                t * 1e3,
                (NX * NY) as f64 / t / 1e6,
                pct(split.fluid),
                pct(split.coverage),
                pct(split.coupling),
                pct(split.dem),
            );
        }
    }
    println!("(split: share of the summed stage times over every step of the case, warm-up included; covered =");
    println!(" lattice nodes with a solid share; healthy = every fluid density in [0.9, 1.1] after the case)");
}

fn main() {
    let load_before = load_average();
    let start = Instant::now();
    let dem = coupled_scene::packed_grains();
    println!(
        "packed {} grains ({} bonds) in {:.1} s",
        dem.particles.len(),
        dem.bonds.len(),
        start.elapsed().as_secs_f64()
    );
    let mut c = Criterion::default().configure_from_args();
    bench_coupled::<f64>(&mut c, &dem);
    bench_coupled::<f32>(&mut c, &dem);
    c.final_summary();
    print_summary(dem.particles.len(), dem.bonds.len());
    println!(
        "load average before: {load_before}; after: {} ({} CPUs)",
        load_average(),
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
}
