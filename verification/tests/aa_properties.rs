//! The in-place AA streaming kernels (`lbdem_kernels::fluid::aa`) at kernel level, against the two-lattice pull
//! (`lbdem_kernels::fluid::step`, itself checked against the reference oracle in `fluid_properties.rs`):
//!
//! * a whole AA step assembled here from the kernel passes alone — the special and covered nodes' values from
//!   the untouched buffer (`special_node_value`, `covered_node_value`), the covered nodes that are not special
//!   gathered and stored inside their band (`load_from_rows`, `psm_collide`, `store_in_rows`), the bulk pass
//!   (`aa_bulk_rows` over the rows `plane_row` hands out), the special values stored at their places
//!   (`store_post_collision_in_plane`) — gives, after every step, bitwise the two-lattice buffer once
//!   rewritten by `to_collided`, bitwise the same momentum exchange, and bitwise the same gathered moments
//!   (`gathered_moments_in`), on random lattices (1×1 to 12×12, obstacles, every kind of side, covered nodes,
//!   any band split, no force or a force along x only, y only or both);
//! * the row passes that leave some nodes as they were (`scatter_row_keeping`, `local_row_keeping`) restore
//!   exactly the slots of the kept nodes and write every other slot as the plain passes do;
//! * `post_collision_offset` is a bijection from (node, direction) onto the buffer's node slots in both
//!   layouts (no two populations share a slot, none is lost);
//! * `store_post_collision_in_plane`, run for the nine planes, writes each P_i(n) exactly at
//!   `post_collision_offset` and nothing else, at interior and edge nodes;
//! * a uniform body force along one axis only is applied (the `forced` switches of the bulk passes and the
//!   collisions): the periodic lattice gains exactly N·F of momentum per step, in both schemes, and a
//!   partially-saturated node gains (1 − B) F minus what it hands to the solids.
//!
//! Exact claims are compared bitwise; momentum balances within 64 ε of Σ|f| per node (a 9-term sum of
//! populations, each with a few ulp of error).
use lbdem_kernels::fluid::aa::{
    aa_bulk_rows, aa_bulk_rows_keeping, load_from_rows, load_post_collision, local_row,
    local_row_keeping, plane_row, post_collision_offset, scatter_row, scatter_row_keeping,
    store_in_rows, store_post_collision_in_plane, to_collided, AaStep, Layout,
};
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition, SideProfiles};
use lbdem_kernels::fluid::collide::{
    bgk_collide_slices, psm_collide, Collision, PsmParams, SolidOperator, SolidShare, Trt,
    Weighting, ALL_LINKS_OPEN,
};
use lbdem_kernels::fluid::d2q9::{density, equilibrium, momentum, OPPOSITE, Q};
use lbdem_kernels::fluid::lattice::LatticeShape;
use lbdem_kernels::fluid::step::{
    band_mut, classify_special_nodes, collide_covered_nodes, covered_node_value, gathered_moments,
    gathered_moments_in, load, nodes_in_rows, planes, planes_mut, special_node_value, step_band,
    CoveredNodes, Domain, FluidParams, FLUID, SOLID,
};
use lbdem_verification::proptest_cases;
use proptest::prelude::*;

fn config(default: u32) -> ProptestConfig {
    ProptestConfig::with_cases(proptest_cases(default))
}

/// SplitMix64 (Steele, Lea & Flood 2014): fills whole lattices from one seed, so a failing case is
/// reproduced by its seed.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }
    fn velocity(&mut self, max: f64) -> [f64; 2] {
        [self.range(-max, max), self.range(-max, max)]
    }
    /// Populations near equilibrium: f^eq(ρ, u)(1 + δ), ρ ∈ [0.8, 1.2], |u_a| ≤ 0.1, |δ| ≤ 0.05.
    fn populations(&mut self) -> [f64; Q] {
        let (rho, u) = (self.range(0.8, 1.2), self.velocity(0.1));
        equilibrium(rho, u).map(|v| v * (1.0 + self.range(-0.05, 0.05)))
    }
}

/// A body force: none, along x only, along y only, or both (chosen by `kind` = 0..4).
fn force_of(kind: usize, rng: &mut SplitMix) -> [f64; 2] {
    let g = [rng.range(-1e-3, 1e-3), rng.range(-1e-3, 1e-3)];
    match kind {
        0 => [0.0, 0.0],
        1 => [g[0], 0.0],
        2 => [0.0, g[1]],
        _ => g,
    }
}

/// A random lattice problem.
struct Problem {
    shape: LatticeShape,
    bc: Boundaries<f64>,
    flags: Vec<u8>,
    params: FluidParams<f64>,
    psm: PsmParams<f64>,
    /// The fluid collision, BGK or TRT with a random magic parameter (the same for the bulk, special and
    /// covered nodes).
    collision: Collision<f64>,
    /// Covered nodes (increasing), share offsets (nodes + 1) and shares.
    covered: Vec<u32>,
    offsets: Vec<u32>,
    shares: Vec<SolidShare<f64>>,
    /// The initial post-collision buffer (two-lattice layout); obstacle nodes hold NaN so any read shows.
    initial: Vec<f64>,
}

fn random_side(rng: &mut SplitMix) -> SideCondition<f64> {
    match rng.below(3) {
        0 => SideCondition::Wall,
        1 => SideCondition::Pressure {
            density: rng.range(0.95, 1.05),
        },
        _ => SideCondition::Velocity {
            velocity: rng.velocity(0.05),
        },
    }
}

fn random_problem(nx: usize, ny: usize, seed: u64, force_kind: usize) -> Problem {
    let mut rng = SplitMix(seed);
    let shape = LatticeShape::for_type::<f64>(nx, ny).expect("small lattice");
    let n = shape.nodes();
    let flags: Vec<u8> = (0..n)
        .map(|_| if rng.chance(0.1) { SOLID } else { FLUID })
        .collect();
    let axis = |rng: &mut SplitMix| {
        if rng.chance(0.4) {
            (SideCondition::Periodic, SideCondition::Periodic)
        } else {
            (random_side(rng), random_side(rng))
        }
    };
    let (west, east) = axis(&mut rng);
    let (south, north) = axis(&mut rng);
    let bc = Boundaries {
        west,
        east,
        south,
        north,
    };
    assert_eq!(bc.validate(), Ok(()));
    let tau = rng.range(0.55, 1.8);
    let collision = if rng.chance(0.5) {
        Collision::Bgk
    } else {
        // Any Λ > 0 gives τ⁻ > ½; the range spans the usual choices (1/12, 3/16, 1/4, 1/2).
        Collision::Trt(Trt::new(rng.range(0.05, 0.6)).expect("positive magic parameter"))
    };
    let force = force_of(force_kind, &mut rng);
    let solid = [
        SolidOperator::NonEquilibriumBounceBack,
        SolidOperator::Superposition,
        SolidOperator::MovingWallBounceBack,
        SolidOperator::LinearizedNonEquilibriumBounceBack,
    ][rng.below(4)];
    let weighting = if rng.chance(0.5) {
        Weighting::NobleTorczynski
    } else {
        Weighting::SolidFraction
    };
    let (mut covered, mut offsets, mut shares) = (Vec::new(), vec![0u32], Vec::new());
    for node in 0..n {
        if rng.chance(0.3) {
            for _ in 0..1 + rng.below(2) {
                shares.push(SolidShare {
                    fraction: rng.unit(),
                    velocity: rng.velocity(0.05),
                    wall_gradient: Default::default(),
                });
            }
            covered.push(node as u32);
            offsets.push(shares.len() as u32);
        }
    }
    let mut initial = vec![f64::NAN; shape.buffer_len()];
    let nodes: Vec<[f64; Q]> = (0..n)
        .map(|k| {
            if flags[k] == SOLID {
                [f64::NAN; Q]
            } else {
                rng.populations()
            }
        })
        .collect();
    for (q, plane) in planes_mut(&shape, &mut initial).into_iter().enumerate() {
        for (k, v) in plane.iter_mut().enumerate() {
            *v = nodes[k][q];
        }
    }
    Problem {
        shape,
        bc,
        flags,
        params: FluidParams { tau, force },
        psm: PsmParams {
            tau,
            weighting,
            force,
            solid,
            collision,
            lambda: Default::default(),
        },
        collision,
        covered,
        offsets,
        shares,
        initial,
    }
}

fn special_nodes(p: &Problem) -> Vec<u32> {
    let mut special = vec![0u32; p.shape.nodes()];
    let count = classify_special_nodes(&p.shape, &p.bc, &p.flags, &mut special);
    special.truncate(count);
    special
}

/// The covered entries k whose nodes lie in rows y0..y1.
fn covered_in_rows(p: &Problem, y0: usize, y1: usize) -> std::ops::Range<usize> {
    let (a, b) = ((y0 * p.shape.nx) as u32, (y1 * p.shape.nx) as u32);
    p.covered.partition_point(|&n| n < a)..p.covered.partition_point(|&n| n < b)
}

/// One two-lattice step from `src` into `dst`, band by band.
fn two_lattice_step(
    p: &Problem,
    src: &[f64],
    dst: &mut [f64],
    band_rows: usize,
    exchange: &mut [[f64; 2]],
) {
    let domain = Domain {
        shape: p.shape,
        bc: p.bc,
        flags: &p.flags,
        profiles: SideProfiles::none(),
    };
    let special = special_nodes(p);
    let ny = p.shape.ny;
    // Only ΩΛ reads the open links, and this file draws the other four operators (ΩΛ's streaming-scheme
    // agreement across streaming schemes, SIMD levels and threads is asserted in driver/tests/trt.rs).
    let all_open = vec![ALL_LINKS_OPEN; p.covered.len()];
    for y0 in (0..ny).step_by(band_rows) {
        let y1 = (y0 + band_rows).min(ny);
        let mut band = band_mut(&p.shape, planes_mut(&p.shape, dst), y0, y1);
        let sp = nodes_in_rows(&p.shape, &special, y0, y1);
        step_band(&domain, src, &mut band, y0, y1, &p.params, &p.collision, sp);
        let ks = covered_in_rows(p, y0, y1);
        let (a, b) = (p.offsets[ks.start] as usize, p.offsets[ks.end] as usize);
        let covered = CoveredNodes {
            nodes: &p.covered[ks.clone()],
            offsets: &p.offsets[ks.start..=ks.end],
            shares: &p.shares,
            links: &all_open[ks],
        };
        collide_covered_nodes(
            &domain,
            src,
            &mut band,
            y0,
            &p.psm,
            covered,
            &mut exchange[a..b],
        );
    }
}

/// One in-place AA step of `buf` (in `layout`), assembled from the kernel passes only, serial. With `keeping`,
/// in the driver's order (the bulk pass of a band leaves its covered nodes that are not special as they were,
/// `aa_bulk_rows_keeping`, and those are then gathered, collided and stored in place); without, in the earlier
/// order (gathered and collided before the bulk pass, stored after it). Returns the layout it leaves.
fn aa_step(
    p: &Problem,
    buf: &mut [f64],
    layout: Layout,
    band_rows: usize,
    keeping: bool,
    exchange: &mut [[f64; 2]],
) -> Layout {
    let shape = p.shape;
    let (nx, ny) = (shape.nx, shape.ny);
    let domain = Domain {
        shape,
        bc: p.bc,
        flags: &p.flags,
        profiles: SideProfiles::none(),
    };
    let periodic = p.bc.periodic_axes();
    let kind = AaStep::from(layout);
    let after = layout.next();
    let special = special_nodes(p);
    let mut mask = vec![false; shape.nodes()];
    for &n in &special {
        mask[n as usize] = true;
    }
    // 1. Special nodes (and the covered ones among them) from the untouched buffer.
    let special_vals: Vec<[f64; Q]> = special
        .iter()
        .map(|&n| special_node_value(&domain, buf, layout, &p.params, &p.collision, n as usize))
        .collect();
    let mut covered_vals: Vec<Option<[f64; Q]>> = vec![None; p.covered.len()];
    for (k, &n) in p.covered.iter().enumerate() {
        if mask[n as usize] {
            let (a, b) = (p.offsets[k] as usize, p.offsets[k + 1] as usize);
            covered_vals[k] = covered_node_value(
                &domain,
                buf,
                layout,
                &p.psm,
                n as usize,
                &p.shares[a..b],
                ALL_LINKS_OPEN,
                &mut exchange[a..b],
            );
        }
    }
    // 2. Band by band: covered nodes that are not special, the bulk pass, then their values stored back.
    {
        let mut plane_rows: Vec<Vec<Option<&mut [f64]>>> = planes_mut(&shape, buf)
            .into_iter()
            .map(|plane| plane.chunks_mut(nx).map(Some).collect())
            .collect();
        let mut rows: Vec<[&mut [f64]; Q]> = (0..ny)
            .map(|y| {
                std::array::from_fn(|q| {
                    plane_rows[q][plane_row(kind, q, y, ny)]
                        .take()
                        .expect("each plane row is handed out once")
                })
            })
            .collect();
        for (b, band) in rows.chunks_mut(band_rows).enumerate() {
            let y0 = b * band_rows;
            let ks: Vec<usize> = covered_in_rows(p, y0, y0 + band.len())
                .filter(|&k| !mask[p.covered[k] as usize])
                .collect();
            if keeping {
                // The driver's order: the bulk pass leaving these nodes as they were, then each of them
                // gathered from the rows the pass wrote, collided and stored in place.
                let mut keep = vec![false; band.len() * nx];
                for &k in &ks {
                    keep[p.covered[k] as usize - y0 * nx] = true;
                }
                aa_bulk_rows_keeping(band, &keep, kind, &p.params, &p.collision);
                for &k in &ks {
                    let n = p.covered[k] as usize;
                    let (a, b) = (p.offsets[k] as usize, p.offsets[k + 1] as usize);
                    let mut f = load_from_rows(band, kind, y0, n % nx, n / nx);
                    psm_collide(&mut f, &p.psm, &p.shares[a..b], &mut exchange[a..b]);
                    store_in_rows(band, kind, y0, n % nx, n / nx, &f);
                }
                continue;
            }
            for &k in &ks {
                let n = p.covered[k] as usize;
                let (a, b) = (p.offsets[k] as usize, p.offsets[k + 1] as usize);
                let mut f = load_from_rows(band, kind, y0, n % nx, n / nx);
                psm_collide(&mut f, &p.psm, &p.shares[a..b], &mut exchange[a..b]);
                covered_vals[k] = Some(f);
            }
            aa_bulk_rows(band, kind, &p.params, &p.collision);
            for &k in &ks {
                let n = p.covered[k] as usize;
                let f = covered_vals[k].expect("collided above");
                store_in_rows(band, kind, y0, n % nx, n / nx, &f);
            }
        }
    }
    // 3. The special values at their places, then the covered special ones (which win).
    for (q, plane) in planes_mut(&shape, buf).into_iter().enumerate() {
        let mut store = |n: u32, f: &[f64; Q]| {
            store_post_collision_in_plane(
                &shape,
                periodic,
                &p.flags,
                after,
                q,
                plane,
                n as usize,
                f[q],
                f[OPPOSITE[q]],
            );
        };
        for (&n, f) in special.iter().zip(&special_vals) {
            store(n, f);
        }
        for (k, &n) in p.covered.iter().enumerate() {
            if mask[n as usize] {
                if let Some(f) = &covered_vals[k] {
                    store(n, f);
                }
            }
        }
    }
    after
}

fn same_bits(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// Steps compared per case.
const STEPS: usize = 4;

proptest! {
    #![proptest_config(config(128))]

    /// After every step the AA buffer, rewritten to the two-lattice layout, is bitwise the two-lattice buffer;
    /// the exchange and the gathered moments are bitwise the same. Both orders of the covered nodes' pass
    /// (`keeping`: after a bulk pass that leaves them as they were, as the driver runs it; or around the bulk
    /// pass, as before).
    #[test]
    fn aa_steps_are_bitwise_the_two_lattice_steps(
        nx in 1usize..=12, ny in 1usize..=12, seed in any::<u64>(), force_kind in 0usize..4, bands in 1usize..=4,
        keeping in any::<bool>(),
    ) {
        let p = random_problem(nx, ny, seed, force_kind);
        let band_rows = ny.div_ceil(bands);
        let shape = p.shape;
        let periodic = p.bc.periodic_axes();
        let (mut two, mut next) = (p.initial.clone(), vec![f64::NAN; shape.buffer_len()]);
        let mut aa = p.initial.clone();
        let mut layout = Layout::Collided;
        let (mut ex_two, mut ex_aa) = (vec![[f64::NAN; 2]; p.shares.len()], vec![[f64::NAN; 2]; p.shares.len()]);
        let mut rewritten = vec![f64::NAN; shape.buffer_len()];
        for step in 0..STEPS {
            two_lattice_step(&p, &two, &mut next, band_rows, &mut ex_two);
            std::mem::swap(&mut two, &mut next);
            layout = aa_step(&p, &mut aa, layout, band_rows, keeping, &mut ex_aa);
            prop_assert_eq!(layout, if step % 2 == 0 { Layout::Streamed } else { Layout::Collided });
            to_collided(&shape, periodic, &p.flags, layout, &aa, &mut rewritten);
            for (q, (a, b)) in planes(&shape, &rewritten).iter().zip(planes(&shape, &two)).enumerate() {
                for (n, (x, y)) in a.iter().zip(b.iter()).enumerate() {
                    prop_assert!(same_bits(*x, *y), "step {step} q {q} node {n}: AA {x} vs two-lattice {y}");
                }
            }
            for n in 0..shape.nodes() {
                let f = load_post_collision(&shape, periodic, &p.flags, layout, &aa, n);
                let g: [f64; Q] = std::array::from_fn(|q| two[shape.offset(q, n)]);
                prop_assert!(f.iter().zip(&g).all(|(x, y)| same_bits(*x, *y)), "step {step} node {n}");
            }
            for (k, (x, y)) in ex_aa.iter().zip(&ex_two).enumerate() {
                prop_assert!(same_bits(x[0], y[0]) && same_bits(x[1], y[1]), "step {step} share {k}: {x:?} vs {y:?}");
            }
            let n = shape.nodes();
            let (mut r1, mut u1, mut r2, mut u2) = (vec![0.0; n], vec![[0.0; 2]; n], vec![0.0; n], vec![[0.0; 2]; n]);
            gathered_moments_in(&shape, &aa, layout, &p.bc, &SideProfiles::none(), &p.flags, p.params.force, &mut r1, &mut u1);
            gathered_moments(&shape, &two, &p.bc, &SideProfiles::none(), &p.flags, p.params.force, &mut r2, &mut u2);
            for k in 0..n {
                prop_assert!(same_bits(r1[k], r2[k]) && same_bits(u1[k][0], u2[k][0]) && same_bits(u1[k][1], u2[k][1]), "step {step} node {k}: moments");
            }
        }
    }

    /// In either layout, (node, direction) ↦ `post_collision_offset` is one-to-one onto the node slots of the
    /// nine planes: no two populations share a slot and none is lost.
    #[test]
    fn post_collision_offsets_are_a_bijection(
        nx in 1usize..=12, ny in 1usize..=12, seed in any::<u64>(), periodic in [any::<bool>(), any::<bool>()],
    ) {
        let mut rng = SplitMix(seed);
        let shape = LatticeShape::for_type::<f64>(nx, ny).expect("small lattice");
        let flags: Vec<u8> = (0..shape.nodes()).map(|_| if rng.chance(0.2) { SOLID } else { FLUID }).collect();
        for layout in [Layout::Collided, Layout::Streamed] {
            let mut owner = vec![None; shape.buffer_len()];
            for n in 0..shape.nodes() {
                for i in 0..Q {
                    let at = post_collision_offset(&shape, periodic, &flags, layout, n, i);
                    let q = at / shape.stride;
                    prop_assert!(q < Q && at % shape.stride < shape.nodes(), "slot {at} is padding");
                    prop_assert!(owner[at].is_none(), "{layout:?}: ({n}, {i}) and {:?} share slot {at}", owner[at]);
                    owner[at] = Some((n, i));
                }
            }
        }
    }

    /// `store_post_collision_in_plane` over the nine planes stores each P_i(n) at its `post_collision_offset`
    /// and writes no other slot, at every node (interior and edge) of lattices with obstacles.
    #[test]
    fn plane_stores_write_exactly_the_post_collision_slots(
        nx in 1usize..=9, ny in 1usize..=9, seed in any::<u64>(), periodic in [any::<bool>(), any::<bool>()],
    ) {
        let mut rng = SplitMix(seed);
        let shape = LatticeShape::for_type::<f64>(nx, ny).expect("small lattice");
        let flags: Vec<u8> = (0..shape.nodes()).map(|_| if rng.chance(0.25) { SOLID } else { FLUID }).collect();
        for layout in [Layout::Collided, Layout::Streamed] {
            for n in 0..shape.nodes() {
                let f: [f64; Q] = std::array::from_fn(|i| 1.0 + i as f64 + 0.01 * n as f64);
                let mut buf = vec![f64::NAN; shape.buffer_len()];
                for (q, plane) in planes_mut(&shape, &mut buf).into_iter().enumerate() {
                    store_post_collision_in_plane(&shape, periodic, &flags, layout, q, plane, n, f[q], f[OPPOSITE[q]]);
                }
                let mut expected = vec![f64::NAN; shape.buffer_len()];
                for (i, v) in f.iter().enumerate() {
                    expected[post_collision_offset(&shape, periodic, &flags, layout, n, i)] = *v;
                }
                for (k, (a, b)) in buf.iter().zip(&expected).enumerate() {
                    prop_assert!(same_bits(*a, *b), "{layout:?} node {n}: slot {k} holds {a}, expected {b}");
                }
            }
        }
    }

    /// A uniform force along one axis (or both) on a fully periodic, fully fluid lattice: each step adds
    /// exactly N·F of momentum and no mass, in the two-lattice and the AA schemes (the bulk passes' `forced`
    /// switch), and `bgk_collide_slices` adds F per node.
    #[test]
    fn a_force_along_one_axis_is_applied(
        nx in 1usize..=10, ny in 1usize..=10, seed in any::<u64>(), force_kind in 1usize..4,
    ) {
        let mut p = random_problem(nx, ny, seed, force_kind);
        p.bc = Boundaries::periodic();
        p.flags = vec![FLUID; p.shape.nodes()];
        let mut rng = SplitMix(seed ^ 1);
        for (q, plane) in planes_mut(&p.shape, &mut p.initial).into_iter().enumerate() {
            for v in plane.iter_mut() {
                *v = equilibrium(1.0, [0.0; 2])[q] * (1.0 + rng.range(-0.05, 0.05));
            }
        }
        p.covered.clear();
        p.offsets = vec![0];
        p.shares.clear();
        let shape = p.shape;
        let n = shape.nodes() as f64;
        let totals = |buf: &[f64]| {
            let (mut m, mut j, mut s) = (0.0, [0.0; 2], 0.0);
            for k in 0..shape.nodes() {
                let f = load(&shape, buf, k);
                m += density(&f);
                let jk = momentum(&f);
                j[0] += jk[0];
                j[1] += jk[1];
                s += f.iter().map(|v| v.abs()).sum::<f64>();
            }
            (m, j, s)
        };
        let force = p.params.force;
        let (m0, j0, s0) = totals(&p.initial);
        // 64 ε per node of Σ|f| (see the module documentation).
        let tol = 64.0 * f64::EPSILON * s0;
        let mut two = vec![f64::NAN; shape.buffer_len()];
        two_lattice_step(&p, &p.initial, &mut two, ny, &mut []);
        let mut aa = p.initial.clone();
        let layout = aa_step(&p, &mut aa, Layout::Collided, ny, true, &mut []);
        let mut rewritten = vec![f64::NAN; shape.buffer_len()];
        to_collided(&shape, [true, true], &p.flags, layout, &aa, &mut rewritten);
        let mut sliced = p.initial.clone();
        bgk_collide_slices(planes_mut(&shape, &mut sliced), 1.0 / p.params.tau, force);
        for (name, buf) in [("two-lattice", &two), ("AA", &rewritten), ("bgk_collide_slices", &sliced)] {
            let (m1, j1, _) = totals(buf);
            prop_assert!((m1 - m0).abs() <= tol, "{name}: mass {m0} -> {m1}");
            for a in 0..2 {
                prop_assert!((j1[a] - j0[a] - n * force[a]).abs() <= tol, "{name}: momentum axis {a} gained {} not {}", j1[a] - j0[a], n * force[a]);
            }
        }
    }

    /// The partially-saturated collision with a force along one axis: the node's momentum changes by
    /// (1 − B) F minus the momentum handed to the solids, for every solid operator.
    #[test]
    fn psm_applies_a_force_along_one_axis(seed in any::<u64>(), force_kind in 1usize..3, op in 0usize..4, shares in 1usize..=3) {
        let mut rng = SplitMix(seed);
        let f0 = rng.populations();
        let force = force_of(force_kind, &mut rng);
        let params = PsmParams {
            tau: rng.range(0.55, 1.8),
            weighting: if rng.chance(0.5) { Weighting::NobleTorczynski } else { Weighting::SolidFraction },
            force,
            solid: [
                SolidOperator::NonEquilibriumBounceBack,
                SolidOperator::Superposition,
                SolidOperator::MovingWallBounceBack,
                SolidOperator::LinearizedNonEquilibriumBounceBack,
            ][op],
            collision: if rng.chance(0.5) {
                Collision::Bgk
            } else {
                Collision::Trt(Trt::new(rng.range(0.05, 0.6)).expect("positive magic parameter"))
            },
            lambda: Default::default(),
        };
        let shares: Vec<SolidShare<f64>> = (0..shares)
            .map(|_| SolidShare { fraction: rng.unit(), velocity: rng.velocity(0.05) , wall_gradient: Default::default() })
            .collect();
        let mut f = f0;
        let mut exchange = vec![[f64::NAN; 2]; shares.len()];
        let b = psm_collide(&mut f, &params, &shares, &mut exchange);
        let tol = 64.0 * f64::EPSILON * f0.iter().map(|v| v.abs()).sum::<f64>();
        prop_assert!((density(&f) - density(&f0)).abs() <= tol);
        let (j0, j1) = (momentum(&f0), momentum(&f));
        for a in 0..2 {
            let handed: f64 = exchange.iter().map(|e| e[a]).sum();
            let want = (1.0 - b) * force[a] - handed;
            prop_assert!((j1[a] - j0[a] - want).abs() <= tol, "axis {a}: gained {} expected {want}", j1[a] - j0[a]);
        }
    }
}

/// The layouts alternate and each step kind starts from its layout.
#[test]
fn layouts_alternate_and_steps_start_from_them() {
    assert_eq!(Layout::Collided.next(), Layout::Streamed);
    assert_eq!(Layout::Streamed.next(), Layout::Collided);
    assert_eq!(AaStep::from(Layout::Collided), AaStep::Scatter);
    assert_eq!(AaStep::from(Layout::Streamed), AaStep::Local);
}

proptest! {
    #![proptest_config(config(256))]

    /// `scatter_row_keeping` and `local_row_keeping` on one row with a random mask: every slot a kept node reads
    /// (plane p at x − c_p,x, wrapped, in a scatter step; at x in a local step) holds what it held before the
    /// pass, every other slot bitwise what `scatter_row` / `local_row` write there; an empty mask is the plain
    /// pass. A mask shorter than the row is misuse (slicing panics) and is not tried.
    #[test]
    fn keeping_row_passes_leave_the_kept_nodes_alone(
        nx in 1usize..=12, seed in any::<u64>(), scatter in any::<bool>(), density_of_keep in 0.0f64..1.0,
    ) {
        let mut rng = SplitMix(seed);
        let before: Vec<Vec<f64>> = (0..Q).map(|_| (0..nx).map(|_| rng.range(0.01, 0.3)).collect()).collect();
        let keep: Vec<bool> = (0..nx).map(|_| rng.chance(density_of_keep)).collect();
        let omega = 1.0 / rng.range(0.55, 2.0);
        let collide = |f: &mut [f64; Q]| lbdem_kernels::fluid::collide::bgk_collide(f, omega);
        let run = |mask: Option<&[bool]>| -> Vec<Vec<f64>> {
            let mut rows = before.clone();
            {
                let mut it = rows.iter_mut();
                let mut r: [&mut [f64]; Q] = std::array::from_fn(|_| it.next().expect("nine rows").as_mut_slice());
                match (scatter, mask) {
                    (true, None) => scatter_row(&mut r, &collide),
                    (true, Some(m)) => scatter_row_keeping(&mut r, m, &collide),
                    (false, None) => local_row(&mut r, &collide),
                    (false, Some(m)) => local_row_keeping(&mut r, m, &collide),
                }
            }
            rows
        };
        let plain = run(None);
        let kept = run(Some(&keep));
        let none = run(Some(&vec![false; nx]));
        for p in 0..Q {
            let cx = lbdem_kernels::fluid::d2q9::VELOCITIES[p][0];
            for j in 0..nx {
                // The node that reads and writes slot (p, j).
                let owner = if scatter { (j as i64 + cx as i64).rem_euclid(nx as i64) as usize } else { j };
                let want = if keep[owner] { before[p][j] } else { plain[p][j] };
                prop_assert!(same_bits(kept[p][j], want), "plane {p} column {j} (node {owner}, kept {})", keep[owner]);
                prop_assert!(same_bits(none[p][j], plain[p][j]));
            }
        }
    }
}
