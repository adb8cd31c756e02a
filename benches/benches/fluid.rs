//! Fluid throughput benchmarks: D2Q9 collide + stream in MLUPS (million lattice-node updates per second) through
//! [`FluidLattice::step`], against the memory-bandwidth ceiling measured in the same run by a STREAM-style triad.
//!
//! * `triad`: a[i] = b[i] + s·c[i] over three f64 arrays of 128 MB each (far beyond the 32 MB L3), 1 and 2
//!   threads, rayon-chunked. Bytes are counted as STREAM counts them: 24 bytes per element (two reads, one write,
//!   no write-allocate).
//! * `bgk`: fully periodic lattice, BGK, no force, f32 and f64, 256², 1024², 2048², 1 and 2 threads.
//! * `psm`: the same with ~30 % of the area covered by a square grid of discs (Noble–Torczynski weighting),
//!   1024², f32 and f64, 1 and 2 threads.
//! * `trt`, `psm-trt`: the `bgk` and `psm` cases with the two-relaxation-time collision (Λ = 3/16), same
//!   sizes, run in the same process right after their BGK twins; `psm-lambda`: the `psm` case with TRT and the
//!   τ-independent solid operator ΩΛ (B = ε). The table ends with the time of a TRT node over a BGK node for
//!   every pair measured (target: ≤ 1.15).
//!
//! Both streaming schemes read 9 and write 9 populations per node update: 144 bytes per update in f64, 72 in
//! f32, counted as STREAM counts (no write-allocate), so the MLUPS ceiling is bandwidth / 144 B (f64) or / 72 B
//! (f32), with the bandwidth being the triad figure for the same thread count. The two-lattice scheme writes
//! into a second buffer, so the hardware also reads each destination line before writing it (write-allocate):
//! 216 B move per f64 update against the 144 counted, where the triad moves 32 B against 24. The in-place AA
//! scheme (the default, `lbdem::engine::lattice::Streaming`) writes the lines it has just read: 144 B move, so it can
//! exceed 100 % of this ceiling.
//!
//! Each case's time per iteration is the median of criterion's samples (taken through `iter_custom`); a table
//! with MLUPS, ceiling and ratio is printed at the end. Regenerate with
//! `cargo bench -p lbdem-benches --bench fluid` (a filter such as `-- bgk/f64` runs a subset; the table then
//! lists what ran). The load average is printed before and after: on a shared machine, other processes make the
//! 2-thread figures (triad and lattice alike) noisy, so repeat and compare runs with a low load.
//!
//! The workspace builds for the baseline x86-64 target (SSE2), and the bulk pass is also compiled for AVX2 and
//! AVX-512 and picked at run time (`lbdem::engine::exec`); results are bitwise identical at every level and with either
//! scheme. Every case runs in place (AA) at the widest level the CPU has; the 2048² BGK cases also run with the
//! two-lattice scheme and at the baseline level, and the PSM cases with the two-lattice scheme, so the table
//! shows what each gains.
use lbdem_benches::load_average;
use std::collections::BTreeMap;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput};
use lbdem::engine::exec::SimdLevel;
use lbdem::engine::lattice::{FluidDisc, FluidLattice, Streaming};
use lbdem_kernels::fluid::boundary::Boundaries;
use lbdem_kernels::fluid::collide::{Collision, SolidOperator, Trt, Weighting};
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::Real;
use rayon::prelude::*;

/// Criterion samples per case.
const SAMPLES: usize = 10;
/// Thread counts benchmarked.
const THREADS: [usize; 2] = [1, 2];
/// Elements per triad array: 16 Mi f64 = 128 MiB each.
const TRIAD_LEN: usize = 16 << 20;
/// Relaxation time of the benchmark fluid.
const TAU: f64 = 0.8;
/// Fraction of the lattice area covered by discs in the PSM case.
const PSM_COVER: f64 = 0.30;
/// Disc grid spacing (nodes) in the PSM case.
const PSM_SPACING: usize = 32;

/// Per-iteration durations recorded by `iter_custom`, keyed by case name, in call order.
static SAMPLES_BY_CASE: Mutex<BTreeMap<String, Vec<Duration>>> = Mutex::new(BTreeMap::new());

fn record(case: &str, per_iter: Duration) {
    if let Ok(mut map) = SAMPLES_BY_CASE.lock() {
        map.entry(case.to_string()).or_default().push(per_iter);
    }
}

/// (median, best) time per iteration over the last `SAMPLES` recorded calls (criterion's measurement samples
/// come after its warm-up calls).
fn sample_times(case: &str) -> Option<(f64, f64)> {
    let map = SAMPLES_BY_CASE.lock().ok()?;
    let all = map.get(case)?;
    let tail = &all[all.len().saturating_sub(SAMPLES)..];
    let mut secs: Vec<f64> = tail.iter().map(Duration::as_secs_f64).collect();
    secs.sort_by(f64::total_cmp);
    let m = secs.len();
    if m == 0 {
        return None;
    }
    let median = if m % 2 == 1 {
        secs[m / 2]
    } else {
        0.5 * (secs[m / 2 - 1] + secs[m / 2])
    };
    Some((median, secs[0]))
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("rayon pool")
}

/// Run `body(iters)` inside `pool`, time it, and record the time per iteration under `case`.
fn timed(
    pool: &rayon::ThreadPool,
    case: &str,
    iters: u64,
    body: impl FnOnce(u64) + Send,
) -> Duration {
    let elapsed = pool.install(|| {
        let start = Instant::now();
        body(iters);
        start.elapsed()
    });
    record(case, elapsed / iters.max(1) as u32);
    elapsed
}

fn triad_case(threads: usize) -> String {
    format!("triad/{threads}t")
}

/// Elements per rayon task of the triad (2 MiB per array): fine enough that a thread slowed down by another
/// process on the machine is balanced by work stealing, as the lattice's row bands are.
const TRIAD_CHUNK: usize = 1 << 18;

/// STREAM triad, a = b + s·c, chunked over the pool's threads.
fn triad(a: &mut [f64], b: &[f64], c: &[f64], s: f64) {
    let chunk = TRIAD_CHUNK;
    a.par_chunks_mut(chunk)
        .zip(b.par_chunks(chunk))
        .zip(c.par_chunks(chunk))
        .for_each(|((a, b), c)| {
            for ((a, &b), &c) in a.iter_mut().zip(b).zip(c) {
                *a = b + s * c;
            }
        });
}

fn bench_triad(c: &mut Criterion) {
    let mut group = c.benchmark_group("triad");
    group
        .sample_size(SAMPLES)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
        .throughput(Throughput::BytesDecimal(24 * TRIAD_LEN as u64));
    for threads in THREADS {
        let p = pool(threads);
        // Touch the pages from the pool that will use them.
        let (mut a, b, cc) = p.install(|| {
            let a = vec![0.0f64; TRIAD_LEN];
            let mut b = vec![0.0f64; TRIAD_LEN];
            let mut cc = vec![0.0f64; TRIAD_LEN];
            b.par_iter_mut()
                .enumerate()
                .for_each(|(i, v)| *v = i as f64);
            cc.par_iter_mut().for_each(|v| *v = 2.0);
            (a, b, cc)
        });
        let case = triad_case(threads);
        group.bench_function(
            BenchmarkId::from_parameter(format!("{threads}t")),
            |bench| {
                bench.iter_custom(|iters| {
                    timed(&p, &case, iters, |iters| {
                        for _ in 0..iters {
                            triad(&mut a, &b, &cc, 3.0);
                        }
                    })
                })
            },
        );
        std::hint::black_box(&a);
        a.clear();
    }
    group.finish();
}

/// A fully periodic BGK lattice with a gentle shear wave (so the collision has work to do).
fn periodic_lattice<T: Real>(n: usize) -> FluidLattice<T> {
    let params = FluidParams {
        tau: T::lit(TAU),
        force: [T::zero(); 2],
    };
    let mut lattice =
        FluidLattice::<T>::new(n, n, Boundaries::periodic(), params).expect("lattice");
    let k = 2.0 * std::f64::consts::PI / n as f64;
    lattice.fill_equilibrium(|_, y| (T::one(), [T::lit(0.01 * (k * y as f64).sin()), T::zero()]));
    lattice
}

/// A square grid of discs, one per `PSM_SPACING`² cell, of total area `PSM_COVER` of the lattice.
fn disc_grid(n: usize) -> Vec<FluidDisc> {
    let cells = n / PSM_SPACING;
    let h = PSM_SPACING as f64;
    let radius = h * (PSM_COVER / std::f64::consts::PI).sqrt();
    let mut discs = Vec::with_capacity(cells * cells);
    for j in 0..cells {
        for i in 0..cells {
            discs.push(FluidDisc {
                center: [(i as f64 + 0.5) * h - 0.5, (j as f64 + 0.5) * h - 0.5],
                radius,
                velocity: [0.001, -0.0005],
                spin: 1e-4,
            });
        }
    }
    discs
}

/// How a case is executed: instruction set of the bulk pass and streaming scheme.
type Variant = (SimdLevel, Streaming);

fn lattice_case(kind: &str, prec: &str, n: usize, threads: usize, v: Variant) -> String {
    format!("{kind}/{prec}/{n}/{threads}t/{}/{}", v.0.name(), v.1.name())
}

fn bench_lattice<T: Real>(c: &mut Criterion, kind: &str, sizes: &[usize], variant: Variant) {
    let (level, streaming) = variant;
    let mut suffix = String::new();
    if level != SimdLevel::detect() {
        suffix += &format!("/{}", level.name());
    }
    if streaming != Streaming::Aa {
        suffix += &format!("/{}", streaming.name());
    }
    let mut group = c.benchmark_group(format!("{kind}/{}{suffix}", T::NAME));
    group
        .sample_size(SAMPLES)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    for &n in sizes {
        group.throughput(Throughput::Elements((n * n) as u64));
        for threads in THREADS {
            let p = pool(threads);
            let mut lattice = p.install(|| {
                let mut l = periodic_lattice::<T>(n);
                l.set_simd(level).expect("level available");
                l.set_streaming(streaming);
                if kind.ends_with("trt") || kind == "psm-lambda" {
                    l.set_collision(Collision::Trt(Trt::default()))
                        .expect("valid TRT rates");
                }
                if kind == "psm-lambda" {
                    l.set_solid_operator(SolidOperator::LambdaConsistent);
                    l.cover_with_discs(&disc_grid(n), Weighting::SolidFraction);
                } else if kind.starts_with("psm") {
                    l.cover_with_discs(&disc_grid(n), Weighting::NobleTorczynski);
                }
                // First touch of the buffer(s) by the pool that will run the steps.
                l.step();
                l.step();
                l
            });
            if kind.starts_with("psm") {
                let covered = lattice.covered_nodes() as f64 / (n * n) as f64;
                println!(
                    "{kind}/{}/{n}: {:.1} % of nodes covered",
                    T::NAME,
                    100.0 * covered
                );
            }
            let case = lattice_case(kind, T::NAME, n, threads, variant);
            group.bench_function(
                BenchmarkId::new(format!("{n}"), format!("{threads}t")),
                |bench| {
                    bench.iter_custom(|iters| {
                        timed(&p, &case, iters, |iters| {
                            for _ in 0..iters {
                                lattice.step();
                            }
                        })
                    })
                },
            );
            std::hint::black_box(lattice.populations().first());
        }
    }
    group.finish();
}

/// The summary table: bandwidth, then every lattice case with its MLUPS, ceiling and ratio.
fn print_summary() {
    let mut bandwidth = BTreeMap::new();
    println!();
    println!("=== memory bandwidth (STREAM triad, 24 B/element; best and median of {SAMPLES} samples) ===");
    for threads in THREADS {
        if let Some((median, best)) = sample_times(&triad_case(threads)) {
            let gbs = 24.0 * TRIAD_LEN as f64 / best / 1e9;
            let gbs_median = 24.0 * TRIAD_LEN as f64 / median / 1e9;
            bandwidth.insert(threads, gbs);
            println!(
                "triad {threads} thread(s): best {gbs:6.2} GB/s (median {gbs_median:6.2})  -> ceiling f64 {:6.1} MLUPS \
                 (144 B), f32 {:6.1} MLUPS (72 B)",
                gbs * 1e3 / 144.0,
                gbs * 1e3 / 72.0
            );
        }
    }
    println!();
    println!("=== D2Q9 update (MLUPS: median and best of {SAMPLES} samples) ===");
    println!(
        "{:<10} {:<4} {:>6} {:>7} {:>9} {:>11} {:>10} {:>10} {:>10} {:>7}",
        "case", "prec", "size", "threads", "simd", "streaming", "MLUPS", "best", "ceiling", "ratio"
    );
    let mut variants = Vec::new();
    for level in [SimdLevel::detect(), SimdLevel::Baseline] {
        for streaming in Streaming::ALL {
            if !variants.contains(&(level, streaming)) {
                variants.push((level, streaming));
            }
        }
    }
    for kind in ["bgk", "trt", "psm", "psm-trt", "psm-lambda"] {
        for prec in ["f64", "f32"] {
            for n in [256, 1024, 2048] {
                for threads in THREADS {
                    for &variant in &variants {
                        let Some((t, best)) =
                            sample_times(&lattice_case(kind, prec, n, threads, variant))
                        else {
                            continue;
                        };
                        let mlups = (n * n) as f64 / t / 1e6;
                        let mlups_best = (n * n) as f64 / best / 1e6;
                        let bytes = if prec == "f64" { 144.0 } else { 72.0 };
                        let (ceiling, ratio) = match bandwidth.get(&threads) {
                            Some(gbs) => {
                                let ceil = gbs * 1e3 / bytes;
                                (
                                    format!("{ceil:10.1}"),
                                    format!("{:6.0}%", 100.0 * mlups / ceil),
                                )
                            }
                            None => ("         -".to_string(), "      -".to_string()),
                        };
                        println!(
                        "{kind:<10} {prec:<4} {:>6} {threads:>7} {:>9} {:>11} {mlups:>10.1} {mlups_best:>10.1} {ceiling} {ratio}",
                        format!("{n}²"),
                        variant.0.name(),
                        variant.1.name()
                    );
                    }
                }
            }
        }
    }
    println!("(ceiling = best triad bandwidth at the same thread count / bytes per update; ratio = median MLUPS /");
    println!(" ceiling; 256² (9 MB of f64 buffers) fits in the 32 MB L3, so it may exceed the memory ceiling)");
    println!();
    println!("=== TRT node / BGK node (median time per step, same size, threads and execution variant) ===");
    for (bgk, trt) in [("bgk", "trt"), ("psm", "psm-trt"), ("psm", "psm-lambda")] {
        for prec in ["f64", "f32"] {
            for n in [256, 1024, 2048] {
                for threads in THREADS {
                    for &variant in &variants {
                        let (Some((tb, _)), Some((tt, _))) = (
                            sample_times(&lattice_case(bgk, prec, n, threads, variant)),
                            sample_times(&lattice_case(trt, prec, n, threads, variant)),
                        ) else {
                            continue;
                        };
                        println!(
                            "{trt:<10} / {bgk:<4} {prec:<4} {:>6} {threads:>2}t {:>9} {:>11}: {:.3}",
                            format!("{n}²"),
                            variant.0.name(),
                            variant.1.name(),
                            tt / tb
                        );
                    }
                }
            }
        }
    }
}

fn main() {
    let load_before = load_average();
    let mut c = Criterion::default().configure_from_args();
    bench_triad(&mut c);
    let widest = (SimdLevel::detect(), Streaming::Aa);
    let two = (SimdLevel::detect(), Streaming::TwoLattice);
    bench_lattice::<f64>(&mut c, "bgk", &[256, 1024, 2048], widest);
    bench_lattice::<f64>(&mut c, "trt", &[256, 1024, 2048], widest);
    bench_lattice::<f32>(&mut c, "bgk", &[256, 1024, 2048], widest);
    bench_lattice::<f32>(&mut c, "trt", &[256, 1024, 2048], widest);
    bench_lattice::<f64>(&mut c, "bgk", &[2048], two);
    bench_lattice::<f32>(&mut c, "bgk", &[2048], two);
    if widest.0 != SimdLevel::Baseline {
        bench_lattice::<f64>(&mut c, "bgk", &[2048], (SimdLevel::Baseline, Streaming::Aa));
        bench_lattice::<f32>(&mut c, "bgk", &[2048], (SimdLevel::Baseline, Streaming::Aa));
    }
    bench_lattice::<f64>(&mut c, "psm", &[1024], widest);
    bench_lattice::<f64>(&mut c, "psm-trt", &[1024], widest);
    bench_lattice::<f64>(&mut c, "psm-lambda", &[1024], widest);
    bench_lattice::<f32>(&mut c, "psm", &[1024], widest);
    bench_lattice::<f32>(&mut c, "psm-trt", &[1024], widest);
    bench_lattice::<f32>(&mut c, "psm-lambda", &[1024], widest);
    bench_lattice::<f64>(&mut c, "psm", &[1024], two);
    bench_lattice::<f32>(&mut c, "psm", &[1024], two);
    c.final_summary();
    print_summary();
    println!(
        "load average before: {load_before}; after: {} ({} CPUs)",
        load_average(),
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
}
