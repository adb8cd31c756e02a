//! What the arithmetic of a covered node costs, apart from finding, gathering and storing it (issue 13, lever 2):
//! the partially-saturated collision of nodes whose populations are already in cache, by the node kernel
//! (`psm_collide_links`, one node per call) and by the batch kernel (`psm_collide_lanes`, [`PSM_LANES`] nodes
//! per call, the kernel of the in-place step), for each class of covered node, next to a plain BGK collision of
//! the same nodes. Each runs inside `lbdem::engine::exec::with_simd` at the CPU's widest level, as the fluid
//! step runs them. Compare with `psm_node`, which measures what a covered node costs in the whole step: the
//! difference is the per-node bookkeeping around the kernel.
//!
//! `cargo run --release -p lbdem-benches --example psm_lanes -- [reps] [rounds]` (defaults 400 5). One thread;
//! process CPU time per block of `reps` passes over 4096 nodes, the classes interleaved round by round; prints
//! the median ns per node of each.
use lbdem::engine::exec::{with_simd, SimdLevel};
use lbdem_benches::{arg, cpu_seconds, load_average, quartiles};
use lbdem_kernels::fluid::collide::{
    bgk_collide, lane_class, psm_collide_lanes, psm_collide_links, Collision, OpenLinks, PsmLanes,
    PsmParams, SolidOperator, SolidShare, Trt, Weighting, PSM_LANES,
};
use lbdem_kernels::fluid::d2q9::{equilibrium, Q};

/// One class of covered node: its operator, collision, weighting, solid fraction and open links.
struct Case {
    name: &'static str,
    solid: SolidOperator,
    collision: Collision<f64>,
    weighting: Weighting,
    fraction: f64,
    open: OpenLinks,
}

/// `n` nodes near equilibrium (densities 1 … 1.006, velocities up to 4e-3, one population per node nudged).
fn nodes(n: usize) -> Vec<[f64; Q]> {
    (0..n)
        .map(|k| {
            let mut f = equilibrium(
                1.0 + 1e-3 * (k % 7) as f64,
                [1e-3 * (k % 5) as f64, -2e-4 * (k % 3) as f64],
            );
            f[k % 8 + 1] += 1e-4;
            f
        })
        .collect()
}

/// CPU ns per node of `reps` passes of `pass` over `n` nodes; `pass` returns a checksum (kept, so that
/// nothing is optimised away).
fn time(n: usize, reps: usize, sum: &mut f64, mut pass: impl FnMut() -> f64) -> f64 {
    let cpu = cpu_seconds();
    for _ in 0..reps {
        *sum += pass();
    }
    (cpu_seconds() - cpu) / (reps * n) as f64 * 1e9
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let num = |i: usize, default: usize| arg(&args, i, default);
    let (reps, rounds) = (num(0, 400), num(1, 5));
    let load_before = load_average();
    let simd = SimdLevel::detect();
    let trt = Collision::Trt(Trt::new(Trt::<f64>::DEFAULT_MAGIC).expect("Λ = 3/16"));
    let cases = [
        Case {
            name: "ΩΛ + TRT, fully covered, no open link (inside a grain)",
            solid: SolidOperator::LambdaConsistent,
            collision: trt,
            weighting: Weighting::SolidFraction,
            fraction: 1.0,
            open: 0,
        },
        Case {
            name: "ΩΛ + TRT, fully covered, three open links (a grain's rim)",
            solid: SolidOperator::LambdaConsistent,
            collision: trt,
            weighting: Weighting::SolidFraction,
            fraction: 1.0,
            open: (1 << 1) | (1 << 5) | (1 << 8),
        },
        Case {
            name: "ΩΛ + TRT, partly covered (ε = 0.4)",
            solid: SolidOperator::LambdaConsistent,
            collision: trt,
            weighting: Weighting::SolidFraction,
            fraction: 0.4,
            open: 0,
        },
        Case {
            name: "Ω₁ₗ + BGK (NT weighting), partly covered (ε = 0.4)",
            solid: SolidOperator::LinearizedNonEquilibriumBounceBack,
            collision: Collision::Bgk,
            weighting: Weighting::NobleTorczynski,
            fraction: 0.4,
            open: 0,
        },
        Case {
            name: "Ω₁ₗ + BGK (NT weighting), fully covered",
            solid: SolidOperator::LinearizedNonEquilibriumBounceBack,
            collision: Collision::Bgk,
            weighting: Weighting::NobleTorczynski,
            fraction: 1.0,
            open: 0,
        },
    ];
    let f0 = nodes(4096);
    let n = f0.len();
    let tau = 0.574; // the fracture scenes' τ (table 6.2's h, Δt and ν)
    let mut sum = 0.0;
    // Per round: BGK, then per case the node kernel and the batch kernel.
    let mut bgk = Vec::new();
    let mut node = vec![Vec::new(); cases.len()];
    let mut batch = vec![Vec::new(); cases.len()];
    for _ in 0..rounds {
        bgk.push(time(n, reps, &mut sum, || {
            with_simd(
                simd,
                #[inline(always)]
                || {
                    let mut s = 0.0;
                    for f in &f0 {
                        let mut g = *f;
                        bgk_collide(&mut g, 1.0 / tau);
                        s += g[3];
                    }
                    s
                },
            )
        }));
        for (c, case) in cases.iter().enumerate() {
            let params = PsmParams {
                tau,
                weighting: case.weighting,
                solid: case.solid,
                force: [0.0; 2],
                collision: case.collision,
                lambda: Default::default(),
            };
            let share = SolidShare {
                fraction: case.fraction,
                velocity: [1e-3, 2e-4],
                wall_gradient: Default::default(),
            };
            let class = lane_class(&params, &[share]).expect("one share, ε > 0");
            let open = case.open;
            node[c].push(time(n, reps, &mut sum, || {
                with_simd(
                    simd,
                    #[inline(always)]
                    || {
                        let mut s = 0.0;
                        for f in &f0 {
                            let mut g = *f;
                            let mut ex = [[0.0; 2]];
                            psm_collide_links(&mut g, &params, &[share], open, &mut ex);
                            s += g[3] + ex[0][0];
                        }
                        s
                    },
                )
            }));
            batch[c].push(time(n, reps, &mut sum, || {
                with_simd(
                    simd,
                    #[inline(always)]
                    || {
                        let mut s = 0.0;
                        let mut lanes = PsmLanes::<f64>::default();
                        for chunk in f0.chunks_exact(PSM_LANES) {
                            for (l, f) in chunk.iter().enumerate() {
                                for (plane, fq) in lanes.f.iter_mut().zip(f) {
                                    plane[l] = *fq;
                                }
                                lanes.share[l] = share;
                                lanes.open[l] = open;
                            }
                            psm_collide_lanes(&mut lanes, PSM_LANES, &params, class);
                            s += lanes.f[3][2] + lanes.exchange[1][0];
                        }
                        s
                    },
                )
            }));
        }
    }
    let [_, b, _] = quartiles(bgk);
    println!("BGK collision of a node in cache: {b:.2} ns");
    for (c, case) in cases.iter().enumerate() {
        let [_, t1, _] = quartiles(node[c].clone());
        let [_, t8, _] = quartiles(batch[c].clone());
        println!(
            "{}: node kernel {t1:.2} ns per node ({:.1} BGK), batch kernel {t8:.2} ns per node ({:.1} BGK)",
            case.name,
            t1 / b,
            t8 / b,
        );
    }
    println!(
        "f64, SIMD level {}, 1 thread, {rounds} interleaved rounds of {reps} passes over {n} nodes (checksum \
         {sum:.6e}); load average before: {load_before}; after: {}",
        simd.name(),
        load_average()
    );
}
