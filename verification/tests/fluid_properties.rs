//! Property tests of the D2Q9 fluid kernels (`lbdem_kernels::fluid`) over random input, and the optimized
//! kernels against the `f64` reference oracle (`lbdem_reference::lbm`).
//!
//! Inputs: populations near equilibrium, f_i = f_i^eq(ρ, u) (1 + δ_i) with ρ ∈ [0.5, 1.5], |u| ≤ 0.2 and
//! |δ_i| ≤ 0.05; τ ∈ [0.51, 2]; force densities |F_a| ≤ 1e-3; solid fractions in [0, 1] (sums may exceed 1,
//! to exercise the cap), solid velocities |u_s| ≤ 0.2; lattices from 1×1 to 12×12 with random obstacle
//! flags and random side conditions. Whole lattices are filled from a seeded SplitMix64 stream so a failing
//! case is reproduced by its seed.
//!
//! **Tolerances.** Every quantity is an O(1) combination of at most a few dozen correctly rounded operations
//! on values of the order of the node density ρ, so its roundoff is at most a few tens of ulp of ρ.
//! * [`ROUNDOFF`] = 64 ε ρ (ε = 2⁻⁵², i.e. ≈ 1.4e−14 ρ) for conservation laws and prescribed boundary values:
//!   a 9-term sum of populations each carrying ≤ 4 ulp of error gives ≤ 36 ulp; 64 leaves margin.
//! * [`ORACLE`] = 1e−12 ρ for kernel-versus-reference: the two evaluate the same formulas in different orders
//!   (and the reference's Zou–He is the transverse-momentum form), so they differ by roundoff only; 1e−12 is
//!   ~100× the worst roundoff seen and ~1e6 below the size of any formula error with these perturbations.
//!   Whole steps are single steps, so errors do not compound.
//! * Bitwise (`to_bits`) where the claim is exact: PSM with ε = 0 versus BGK, streaming as a permutation,
//!   band splitting.
use lbdem_kernels::fluid::aa::{load_from_rows, store_in_rows, AaStep, Layout};
use lbdem_kernels::fluid::boundary::{
    radiating_density, zou_he, zou_he_corner, zou_he_known_sum, Boundaries, SideCondition,
    SideProfiles,
};
use lbdem_kernels::fluid::collide::{
    bgk_collide, bgk_collide_forced, bgk_collide_slices, fluid_collide, lane_class, psm_collide,
    psm_collide_links, psm_velocity, trt_collide, trt_collide_forced, Collision, CollisionError,
    LambdaTerms, OpenLinks, PsmParams, SolidOperator, SolidShare, Trt, Weighting, ALL_LINKS_OPEN,
};
use lbdem_kernels::fluid::d2q9::{density, equilibrium, momentum, second_moment, OPPOSITE, Q};
use lbdem_kernels::fluid::lattice::{LatticeShape, Side};
use lbdem_kernels::fluid::step::{
    band_mut, classify_special_nodes, collide_covered_list, collide_covered_nodes,
    collide_planned_row, gather_node, gathered_densities, gathered_moments, nodes_in_rows,
    open_links, plan_covered_row, planes, planes_mut, step_band, stream_periodic, wall_gradients,
    CoveredNodes, Domain, FluidParams, FLUID, PLAN_GROUPS, SOLID,
};
use lbdem_kernels::Real;
use lbdem_reference::analytic;
use lbdem_reference::lbm as reference;
use proptest::prelude::*;

/// Roundoff allowance for conservation laws and prescribed values, relative to the node density.
const ROUNDOFF: f64 = 64.0 * f64::EPSILON;
/// Allowance for optimized kernel versus reference oracle, relative to the node density.
const ORACLE: f64 = 1e-12;
/// Allowance for the `f32` kernels versus the `f64` reference, relative to the node density: the inputs
/// are rounded to `f32` (½ ulp each) and a step is a few tens of `f32` operations on O(ρ) values, so
/// 64 ulp of `f32` (≈ 7.6e−6); Zou–He pressure sides recover u·n = 1 − S/ρ by cancellation, which the margin
/// covers.
const ORACLE_F32: f64 = 64.0 * f32::EPSILON as f64;

// ---------------------------------------------------------------------------------------------------------
// Input generation
// ---------------------------------------------------------------------------------------------------------

/// SplitMix64 (Steele, Lea & Flood 2014): a tiny seeded generator for filling whole lattices.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
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
    /// A velocity with |u| ≤ 0.2.
    fn velocity(&mut self) -> [f64; 2] {
        let (r, a) = (
            0.2 * self.unit().sqrt(),
            self.range(0.0, std::f64::consts::TAU),
        );
        [r * a.cos(), r * a.sin()]
    }
    /// Populations near equilibrium: f^eq(ρ, u)(1 + δ), ρ ∈ [0.5, 1.5], |u| ≤ 0.2, |δ_i| ≤ 0.05.
    fn populations(&mut self) -> [f64; Q] {
        let (rho, u) = (self.range(0.5, 1.5), self.velocity());
        let feq = reference::equilibrium(rho, u);
        core::array::from_fn(|i| feq[i] * (1.0 + self.range(-0.05, 0.05)))
    }
    /// A solid fraction in [0, 1], exactly 0 or 1 now and then.
    fn fraction(&mut self) -> f64 {
        match self.below(6) {
            0 => 0.0,
            1 => 1.0,
            _ => self.unit(),
        }
    }
}

fn node_populations() -> impl Strategy<Value = [f64; Q]> {
    any::<u64>().prop_map(|s| SplitMix(s).populations())
}

fn tau() -> impl Strategy<Value = f64> {
    0.51f64..=2.0
}

fn force() -> impl Strategy<Value = [f64; 2]> {
    [-1e-3f64..=1e-3, -1e-3f64..=1e-3]
}

fn velocity() -> impl Strategy<Value = [f64; 2]> {
    any::<u64>().prop_map(|s| SplitMix(s).velocity())
}

fn weighting() -> impl Strategy<Value = Weighting> {
    prop_oneof![
        Just(Weighting::NobleTorczynski),
        Just(Weighting::SolidFraction)
    ]
}

fn shares() -> impl Strategy<Value = Vec<SolidShare<f64>>> {
    (1usize..=3, any::<u64>()).prop_map(|(n, s)| {
        let mut rng = SplitMix(s);
        (0..n)
            .map(|_| SolidShare {
                fraction: rng.fraction(),
                velocity: rng.velocity(),
                // ΩΛ's wall-pressure input: none, or a density gradient of the size a pressure-driven pore flow
                // has (≤ 1e-2 per spacing).
                wall_gradient: if rng.chance(0.5) {
                    [rng.range(-1e-2, 1e-2), rng.range(-1e-2, 1e-2)]
                } else {
                    [0.0; 2]
                },
            })
            .collect()
    })
}

/// A wall direction for share `k` of covered node `node` in the lattice-step comparisons, the same for the
/// kernels and the reference: none for one share in four, otherwise a unit vector at an angle spread over the
/// circle by the indices.
fn test_normal(node: u32, k: usize) -> [f64; 2] {
    let h = (node as u64)
        .wrapping_mul(0x9e37_79b9_7f4a_7c15)
        .wrapping_add(k as u64 * 0x6a09_e667);
    if h.is_multiple_of(4) {
        return [0.0; 2];
    }
    let angle = (h >> 11) as f64 / (1u64 << 53) as f64 * std::f64::consts::TAU;
    [angle.cos(), angle.sin()]
}

fn to_reference_weighting(w: Weighting) -> reference::Weighting {
    match w {
        Weighting::NobleTorczynski => reference::Weighting::NobleTorczynski,
        Weighting::SolidFraction => reference::Weighting::SolidFraction,
    }
}

fn to_reference_solids(shares: &[SolidShare<f64>]) -> Vec<reference::Solid> {
    shares
        .iter()
        .map(|s| reference::Solid {
            fraction: s.fraction,
            velocity: s.velocity,
            normal: [0.0; 2],
            wall_gradient: s.wall_gradient,
        })
        .collect()
}

/// Σ|f_i|: the scale of a node's roundoff (≈ ρ near equilibrium).
fn scale(f: &[f64; Q]) -> f64 {
    f.iter().map(|v| v.abs()).sum()
}

/// The largest |a_i − b_i|; infinite if any difference is NaN (`f64::max` would silently drop it) or the
/// lengths differ.
fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    if a.len() != b.len() {
        return f64::INFINITY;
    }
    let mut m = 0.0f64;
    for (x, y) in a.iter().zip(b) {
        let d = (x - y).abs();
        if d.is_nan() {
            return f64::INFINITY;
        }
        m = m.max(d);
    }
    m
}

// ---------------------------------------------------------------------------------------------------------
// Collision operators
// ---------------------------------------------------------------------------------------------------------

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// f^eq(ρ, u) has moments ρ, ρu and Π = ρ/3 I + ρ u u.
    #[test]
    fn equilibrium_has_the_right_moments(rho in 0.5f64..=1.5, u in velocity()) {
        let feq = equilibrium(rho, u);
        let tol = ROUNDOFF * rho;
        prop_assert!((density(&feq) - rho).abs() <= tol);
        let j = momentum(&feq);
        prop_assert!((j[0] - rho * u[0]).abs() <= tol && (j[1] - rho * u[1]).abs() <= tol);
        let p = second_moment(&feq);
        let expected = [rho / 3.0 + rho * u[0] * u[0], rho * u[0] * u[1], rho / 3.0 + rho * u[1] * u[1]];
        for (got, want) in p.iter().zip(expected) {
            prop_assert!((got - want).abs() <= tol, "Π {got} vs {want}");
        }
    }

    /// BGK conserves mass and momentum to roundoff, and equals the reference BGK.
    #[test]
    fn bgk_conserves_mass_and_momentum(f in node_populations(), tau in tau()) {
        let mut g = f;
        bgk_collide(&mut g, 1.0 / tau);
        let tol = ROUNDOFF * scale(&f);
        prop_assert!((density(&g) - density(&f)).abs() <= tol);
        let (j0, j1) = (momentum(&f), momentum(&g));
        prop_assert!((j1[0] - j0[0]).abs() <= tol && (j1[1] - j0[1]).abs() <= tol);
        let r = reference::bgk(&f, tau);
        prop_assert!(max_abs_diff(&g, &r) <= ORACLE * scale(&f));
    }

    /// Guo-forced BGK adds no mass and exactly F of momentum; it equals the reference.
    #[test]
    fn forced_bgk_adds_exactly_the_force(f in node_populations(), tau in tau(), force in force()) {
        let mut g = f;
        bgk_collide_forced(&mut g, 1.0 / tau, force);
        let tol = ROUNDOFF * scale(&f);
        prop_assert!((density(&g) - density(&f)).abs() <= tol);
        let (j0, j1) = (momentum(&f), momentum(&g));
        for a in 0..2 {
            prop_assert!((j1[a] - j0[a] - force[a]).abs() <= tol, "axis {a}");
        }
        let r = reference::bgk_forced(&f, tau, force);
        prop_assert!(max_abs_diff(&g, &r) <= ORACLE * scale(&f));
    }

    /// PSM conserves mass; the fluid momentum change is (1 − B) F minus the momentum handed to the solids
    /// (Σ exchange), so with no body force momentum is exchanged, never created. Equals the reference,
    /// exchange included. All four solid operators (Ω₁ non-equilibrium bounce-back, Ω₂ superposition, Ω₃
    /// moving-wall bounce-back, Ω₁ₗ linearised Ω₁).
    #[test]
    fn psm_exchanges_momentum_with_the_solids(
        f in node_populations(), tau in tau(), shares in shares(), w in weighting(),
        forced in any::<bool>(), force in force(), op in 0usize..4,
    ) {
        let force = if forced { force } else { [0.0; 2] };
        let (solid, ref_op) = [
            (SolidOperator::NonEquilibriumBounceBack, reference::SolidOp::NonEquilibriumBounceBack),
            (SolidOperator::Superposition, reference::SolidOp::Superposition),
            (SolidOperator::MovingWallBounceBack, reference::SolidOp::MovingWallBounceBack),
            (SolidOperator::LinearizedNonEquilibriumBounceBack, reference::SolidOp::LinearizedNonEquilibriumBounceBack),
        ][op];
        let params = PsmParams { tau, weighting: w, force, solid, collision: Collision::Bgk, lambda: Default::default() };
        let mut g = f;
        let mut exchange = vec![[f64::NAN; 2]; shares.len()];
        let b = psm_collide(&mut g, &params, &shares, &mut exchange);
        prop_assert!((0.0..=1.0).contains(&b));
        let tol = ROUNDOFF * scale(&f);
        prop_assert!((density(&g) - density(&f)).abs() <= tol);
        let (j0, j1) = (momentum(&f), momentum(&g));
        for a in 0..2 {
            let handed: f64 = exchange.iter().map(|e| e[a]).sum();
            let expected = (1.0 - b) * force[a] - handed;
            prop_assert!((j1[a] - j0[a] - expected).abs() <= tol, "axis {a}");
        }
        if !forced {
            // docs/references.md §2.2–2.3: with Ω₁ or Ω₂ and no forcing, F_s = B_s ρ (u − u_s) for any populations;
            // Ω₃ hands over twice that; Ω₁ₗ exactly Ω₁'s.
            let factor = if solid == SolidOperator::MovingWallBounceBack { 2.0 } else { 1.0 };
            let (rho, j) = (density(&f), momentum(&f));
            let eps: f64 = shares.iter().map(|s| s.fraction).sum();
            for (s, e) in shares.iter().zip(&exchange) {
                let b_s = if eps > 0.0 { b * s.fraction / eps } else { 0.0 };
                for a in 0..2 {
                    let want = factor * b_s * (j[a] - rho * s.velocity[a]);
                    prop_assert!((e[a] - want).abs() <= tol, "F_s {e:?} axis {a} vs {want}");
                }
            }
        }
        let (r, ex) = reference::psm_with_operator(
            &f, tau, to_reference_weighting(w), ref_op, force, &to_reference_solids(&shares),
        );
        prop_assert!(max_abs_diff(&g, &r) <= ORACLE * scale(&f));
        for (k, e) in exchange.iter().zip(&ex) {
            prop_assert!(max_abs_diff(k, e) <= ORACLE * scale(&f));
        }
    }

    /// PSM with every solid fraction zero is bitwise the (forced) BGK collision and hands nothing over.
    #[test]
    fn psm_with_zero_solid_fraction_is_bitwise_bgk(
        f in node_populations(), tau in tau(), n in 0usize..=3, w in weighting(), u_s in velocity(),
        forced in any::<bool>(), force in force(),
    ) {
        let force = if forced { force } else { [0.0; 2] };
        let shares = vec![SolidShare { fraction: 0.0, velocity: u_s , wall_gradient: Default::default() }; n];
        let mut exchange = vec![[f64::NAN; 2]; n];
        let mut g = f;
        let b = psm_collide(&mut g, &PsmParams { tau, weighting: w, force, solid: SolidOperator::NonEquilibriumBounceBack, collision: Collision::Bgk, lambda: Default::default() }, &shares, &mut exchange);
        let mut h = f;
        if forced {
            bgk_collide_forced(&mut h, 1.0 / tau, force);
        } else {
            bgk_collide(&mut h, 1.0 / tau);
        }
        prop_assert_eq!(b, 0.0);
        prop_assert_eq!(g.map(f64::to_bits), h.map(f64::to_bits));
        prop_assert!(exchange.iter().all(|e| *e == [0.0, 0.0]));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// `bgk_collide_slices` applies the node collision (plain or forced) to every node of structure-of-arrays
    /// planes: equal to the reference node by node.
    #[test]
    fn bgk_collide_slices_matches_the_reference(
        n in 0usize..=40, seed in any::<u64>(), tau in tau(), forced in any::<bool>(), force in force(),
    ) {
        let force = if forced { force } else { [0.0; 2] };
        let mut rng = SplitMix(seed);
        let nodes: Vec<[f64; Q]> = (0..n).map(|_| rng.populations()).collect();
        let mut planes: Vec<Vec<f64>> = (0..Q).map(|q| nodes.iter().map(|f| f[q]).collect()).collect();
        {
            let mut it = planes.iter_mut();
            let slices: [&mut [f64]; Q] = core::array::from_fn(|_| it.next().map(|v| v.as_mut_slice()).unwrap_or_default());
            bgk_collide_slices(slices, 1.0 / tau, force);
        }
        for (k, f) in nodes.iter().enumerate() {
            let got: [f64; Q] = core::array::from_fn(|q| planes[q][k]);
            let want = reference::bgk_forced(f, tau, force);
            prop_assert!(max_abs_diff(&got, &want) <= ORACLE * scale(f), "node {k}");
        }
    }
}

/// docs/references.md §2.3 sign test: with Ω₁ and no forcing, a fully covered node (B = 1, ε = 1) at equilibrium
/// with velocity u hands the solid F = ρ (u − u_s): the fluid drags the solid along.
#[test]
fn psm_force_on_a_fully_covered_node_drags_the_solid_along() {
    let (rho, u, u_s): (f64, [f64; 2], [f64; 2]) = (1.1, [0.05, -0.02], [-0.01, 0.03]);
    let mut f = equilibrium(rho, u);
    let mut ex = [[0.0; 2]; 1];
    let shares = [SolidShare {
        fraction: 1.0,
        velocity: u_s,
        wall_gradient: Default::default(),
    }];
    let params = PsmParams {
        tau: 0.8,
        weighting: Weighting::NobleTorczynski,
        force: [0.0; 2],
        solid: SolidOperator::NonEquilibriumBounceBack,
        collision: Collision::Bgk,
        lambda: Default::default(),
    };
    let b = psm_collide(&mut f, &params, &shares, &mut ex);
    assert_eq!(b, 1.0);
    for a in 0..2 {
        assert!((ex[0][a] - rho * (u[a] - u_s[a])).abs() <= ROUNDOFF * rho);
    }
}

/// Ω₃ at a fully covered node is the classic moving-wall bounce-back, f_i ← f_ī + 6 w_i ρ c_i·u_s, for any
/// populations: the rest population is untouched (so covered regions cannot pile up mass in it, unlike Ω₁,
/// whose rest population gains (2/3)ρ(u² − u_s²) per step), and with u_s = 0 it is a pure permutation.
#[test]
fn psm_bounce_back_operator_at_full_cover_is_moving_wall_bounce_back() {
    let f0: [f64; 9] = [0.41, 0.12, 0.09, 0.13, 0.1, 0.031, 0.027, 0.022, 0.029];
    for u_s in [[0.0, 0.0], [0.03, -0.02]] {
        let mut f = f0;
        let mut ex = [[0.0; 2]; 1];
        let shares = [SolidShare {
            fraction: 1.0,
            velocity: u_s,
            wall_gradient: Default::default(),
        }];
        let params = PsmParams {
            tau: 0.7,
            weighting: Weighting::NobleTorczynski,
            force: [0.0; 2],
            solid: SolidOperator::MovingWallBounceBack,
            collision: Collision::Bgk,
            lambda: Default::default(),
        };
        psm_collide(&mut f, &params, &shares, &mut ex);
        let rho = density(&f0);
        let w = [
            4.0 / 9.0,
            1.0 / 9.0,
            1.0 / 9.0,
            1.0 / 9.0,
            1.0 / 9.0,
            1.0 / 36.0,
            1.0 / 36.0,
            1.0 / 36.0,
            1.0 / 36.0,
        ];
        let c: [[f64; 2]; 9] = [
            [0.0, 0.0],
            [1.0, 0.0],
            [0.0, 1.0],
            [-1.0, 0.0],
            [0.0, -1.0],
            [1.0, 1.0],
            [-1.0, 1.0],
            [-1.0, -1.0],
            [1.0, -1.0],
        ];
        let opp = [0, 3, 4, 1, 2, 7, 8, 5, 6];
        assert_eq!(f[0], f0[0], "rest population must be untouched");
        for i in 1..9 {
            let want = f0[opp[i]] + 6.0 * w[i] * rho * (c[i][0] * u_s[0] + c[i][1] * u_s[1]);
            // Roundoff: a handful of operations on O(0.1) numbers.
            assert!(
                (f[i] - want).abs() <= 1e-15,
                "direction {i}: {} vs {want}",
                f[i]
            );
        }
    }
}

/// Ω₁ₗ at a fully covered node: the rest population is untouched, the node leaves the collision moving with
/// the solid (as with Ω₁, which is what keeps free grains stable), and mass is unchanged; for any populations.
#[test]
fn linearized_operator_at_full_cover_moves_with_the_solid_and_keeps_the_rest_population() {
    let f0: [f64; 9] = [0.41, 0.12, 0.09, 0.13, 0.1, 0.031, 0.027, 0.022, 0.029];
    for u_s in [[0.0, 0.0], [0.03, -0.02]] {
        let mut f = f0;
        let mut ex = [[0.0; 2]; 1];
        let shares = [SolidShare {
            fraction: 1.0,
            velocity: u_s,
            wall_gradient: Default::default(),
        }];
        let params = PsmParams {
            tau: 0.7,
            weighting: Weighting::NobleTorczynski,
            force: [0.0; 2],
            solid: SolidOperator::LinearizedNonEquilibriumBounceBack,
            collision: Collision::Bgk,
            lambda: Default::default(),
        };
        psm_collide(&mut f, &params, &shares, &mut ex);
        assert_eq!(f[0], f0[0], "rest population must be untouched");
        let rho = density(&f0);
        // Roundoff: sums of nine O(0.1) numbers.
        assert!((density(&f) - rho).abs() <= 1e-15);
        let j = momentum(&f);
        for a in 0..2 {
            assert!(
                (j[a] - rho * u_s[a]).abs() <= 1e-15,
                "axis {a}: {} vs {}",
                j[a],
                rho * u_s[a]
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------------------
// Lattices: conversion between the kernel layout and the reference
// ---------------------------------------------------------------------------------------------------------

/// A random lattice problem: reference state, kernel side conditions, and coverage.
#[derive(Debug, Clone)]
struct Problem {
    lattice: reference::Lattice,
    bc: Boundaries<f64>,
    tau: f64,
    force: [f64; 2],
    weighting: Weighting,
    /// Covered nodes, increasing, with their shares.
    covered: Vec<(u32, Vec<SolidShare<f64>>)>,
    /// Fluid collision: BGK (`None`) or TRT with this magic parameter Λ.
    magic: Option<f64>,
    /// Covered nodes use ΩΛ (else Ω₁).
    lambda: bool,
    /// Per-node velocities of `VelocityProfile` sides.
    profiles: reference::Profiles,
}

fn random_side(rng: &mut SplitMix) -> SideCondition<f64> {
    match rng.below(3) {
        0 => SideCondition::Wall,
        1 => SideCondition::Pressure {
            density: rng.range(0.8, 1.2),
        },
        _ => SideCondition::Velocity {
            velocity: rng.velocity(),
        },
    }
}

/// A random problem on an nx × ny lattice: obstacle nodes with probability `p_solid` (their populations NaN,
/// so any read of them shows), each axis periodic or with independent wall / pressure / velocity sides,
/// coverage with probability `p_covered`.
fn random_problem(nx: usize, ny: usize, seed: u64, p_solid: f64, p_covered: f64) -> Problem {
    let mut rng = SplitMix(seed);
    let n = nx * ny;
    let solid: Vec<bool> = (0..n).map(|_| rng.chance(p_solid)).collect();
    let f = solid
        .iter()
        .map(|&s| if s { [f64::NAN; Q] } else { rng.populations() })
        .collect();
    let (west, east) = if rng.chance(0.3) {
        (SideCondition::Periodic, SideCondition::Periodic)
    } else {
        (random_side(&mut rng), random_side(&mut rng))
    };
    let (south, north) = if rng.chance(0.3) {
        (SideCondition::Periodic, SideCondition::Periodic)
    } else {
        (random_side(&mut rng), random_side(&mut rng))
    };
    let bc = Boundaries {
        west,
        east,
        south,
        north,
    };
    assert_eq!(bc.validate(), Ok(()));
    let tau = rng.range(0.51, 2.0);
    let force = if rng.chance(0.5) {
        [rng.range(-1e-3, 1e-3), rng.range(-1e-3, 1e-3)]
    } else {
        [0.0; 2]
    };
    let weighting = if rng.chance(0.5) {
        Weighting::NobleTorczynski
    } else {
        Weighting::SolidFraction
    };
    let mut covered = Vec::new();
    for node in 0..n {
        if rng.chance(p_covered) {
            let k = 1 + rng.below(3);
            let shares = (0..k)
                .map(|_| SolidShare {
                    fraction: rng.fraction(),
                    velocity: rng.velocity(),
                    wall_gradient: Default::default(),
                })
                .collect();
            covered.push((node as u32, shares));
        }
    }
    Problem {
        lattice: reference::Lattice { nx, ny, f, solid },
        bc,
        tau,
        force,
        weighting,
        covered,
        magic: None,
        lambda: false,
        profiles: reference::Profiles::default(),
    }
}

fn to_reference_condition(c: SideCondition<f64>) -> reference::Condition {
    match c {
        SideCondition::Periodic => reference::Condition::Periodic,
        SideCondition::Wall => reference::Condition::Wall,
        SideCondition::Pressure { density } => reference::Condition::Pressure(density),
        SideCondition::Velocity { velocity } => reference::Condition::Velocity(velocity),
        SideCondition::MovingWall { velocity } => reference::Condition::MovingWall(velocity),
        // The per-node values are in the problem's `profiles`.
        SideCondition::VelocityProfile => reference::Condition::Velocity([0.0; 2]),
    }
}

fn to_reference_sides(bc: &Boundaries<f64>) -> reference::Sides {
    reference::Sides {
        west: to_reference_condition(bc.west),
        east: to_reference_condition(bc.east),
        south: to_reference_condition(bc.south),
        north: to_reference_condition(bc.north),
    }
}

/// The kernel population buffer of a reference state (padding NaN).
fn to_buffer<T: Real>(shape: &LatticeShape, f: &[[f64; Q]]) -> Vec<T> {
    let mut buf = vec![T::nan(); shape.buffer_len()];
    for (q, plane) in planes_mut(shape, &mut buf).into_iter().enumerate() {
        for (node, v) in plane.iter_mut().enumerate() {
            *v = T::lit(f[node][q]);
        }
    }
    buf
}

fn from_buffer<T: Real>(shape: &LatticeShape, buf: &[T]) -> Vec<[f64; Q]> {
    let p = planes(shape, buf);
    (0..shape.nodes())
        .map(|node| core::array::from_fn(|q| p[q][node].to_f64_exact()))
        .collect()
}

fn side_in<T: Real>(c: SideCondition<f64>) -> SideCondition<T> {
    match c {
        SideCondition::Periodic => SideCondition::Periodic,
        SideCondition::Wall => SideCondition::Wall,
        SideCondition::Pressure { density } => SideCondition::Pressure {
            density: T::lit(density),
        },
        SideCondition::Velocity { velocity } => SideCondition::Velocity {
            velocity: velocity.map(T::lit),
        },
        SideCondition::MovingWall { velocity } => SideCondition::MovingWall {
            velocity: velocity.map(T::lit),
        },
        SideCondition::VelocityProfile => SideCondition::VelocityProfile,
    }
}

/// The kernel step of a problem with the rows split at `cuts` (a band per consecutive pair; 0 and ny are
/// added): per band, `step_band` with that band's special nodes, then, if `with_coverage`,
/// `collide_covered_nodes` with that band's covered nodes and exchange entries. Returns the new populations
/// and the exchange per share.
fn kernel_step<T: Real>(
    p: &Problem,
    cuts: &[usize],
    with_coverage: bool,
) -> (Vec<[f64; Q]>, Vec<[f64; 2]>) {
    let (nx, ny) = (p.lattice.nx, p.lattice.ny);
    let shape = LatticeShape::for_type::<T>(nx, ny).expect("small lattice");
    let bc = Boundaries {
        west: side_in::<T>(p.bc.west),
        east: side_in::<T>(p.bc.east),
        south: side_in::<T>(p.bc.south),
        north: side_in::<T>(p.bc.north),
    };
    let (tau, force) = (T::lit(p.tau), p.force.map(T::lit));
    let flags: Vec<u8> = p
        .lattice
        .solid
        .iter()
        .map(|&s| if s { SOLID } else { FLUID })
        .collect();
    let profile = |v: &[[f64; 2]]| -> Vec<[T; 2]> { v.iter().map(|u| u.map(T::lit)).collect() };
    let (pw, pe, ps, pn) = (
        profile(&p.profiles.west),
        profile(&p.profiles.east),
        profile(&p.profiles.south),
        profile(&p.profiles.north),
    );
    let domain = Domain {
        shape,
        bc,
        profiles: SideProfiles {
            west: &pw,
            east: &pe,
            south: &ps,
            north: &pn,
        },
        flags: &flags,
    };
    let src = to_buffer::<T>(&shape, &p.lattice.f);
    let mut special = vec![0u32; shape.nodes()];
    let count = classify_special_nodes(&shape, &bc, &flags, &mut special);
    special.truncate(count);
    let fluid = FluidParams { tau, force };
    let collision = match p.magic {
        None => Collision::Bgk,
        Some(m) => Collision::Trt(Trt::new(T::lit(m)).expect("positive magic parameter")),
    };
    let psm = PsmParams {
        tau,
        weighting: p.weighting,
        force,
        solid: if p.lambda {
            SolidOperator::LambdaConsistent
        } else {
            SolidOperator::NonEquilibriumBounceBack
        },
        collision,
        lambda: lambda_terms_of(p),
    };
    // Compressed-row coverage.
    let nodes: Vec<u32> = p.covered.iter().map(|(n, _)| *n).collect();
    let mut offsets = vec![0u32];
    let mut shares = Vec::new();
    for (_, s) in &p.covered {
        shares.extend(s.iter().map(|s| SolidShare {
            fraction: T::lit(s.fraction),
            velocity: s.velocity.map(T::lit),
            wall_gradient: Default::default(),
        }));
        offsets.push(shares.len() as u32);
    }
    // Open links (ΩΛ): fully covered = the shares' fractions, summed in the collision's order, reach 1 − the
    // full-cover gap (the operator's definition; the reference's constant).
    let mut full = vec![false; shape.nodes()];
    for (k, &n) in nodes.iter().enumerate() {
        let mut eps = T::zero();
        for s in &shares[offsets[k] as usize..offsets[k + 1] as usize] {
            eps += s.fraction;
        }
        full[n as usize] = eps >= T::one() - T::lit(lbdem_reference::lbm::LAMBDA_FULL_GAP);
    }
    let links: Vec<OpenLinks> = nodes
        .iter()
        .map(|&n| {
            let (x, y) = shape.coords(n as usize);
            open_links(&shape, &bc, &flags, x, y, |j| full[j])
        })
        .collect();
    if p.lambda && with_coverage && psm.lambda.pressure != 0.0 {
        // ΩΛ's wall gradients from the state the step gathers (what the driver does before each step).
        let mut normals = Vec::with_capacity(shares.len());
        for (k, &n) in nodes.iter().enumerate() {
            let count = (offsets[k + 1] - offsets[k]) as usize;
            normals.extend((0..count).map(|j| test_normal(n, j).map(T::lit)));
        }
        // The densities as the driver takes them: gathered row by row, the special nodes one by one.
        let mut rho = vec![T::nan(); shape.nodes()];
        gathered_densities(&domain, &src, Layout::Collided, 0, ny, &special, &mut rho);
        wall_gradients(
            &domain,
            &nodes,
            &offsets,
            &links,
            &normals,
            &mut shares,
            |n| rho[n],
        );
    }
    let mut exchange = vec![[T::nan(); 2]; shares.len()];
    let mut rows = vec![0];
    rows.extend_from_slice(cuts);
    rows.push(ny);
    let mut dst = vec![T::nan(); shape.buffer_len()];
    for w in rows.windows(2) {
        let (y0, y1) = (w[0], w[1]);
        let mut band = band_mut(&shape, planes_mut(&shape, &mut dst), y0, y1);
        step_band(
            &domain,
            &src,
            &mut band,
            y0,
            y1,
            &fluid,
            &collision,
            nodes_in_rows(&shape, &special, y0, y1),
        );
        if with_coverage {
            let lo = nodes.partition_point(|&n| (n as usize) < y0 * nx);
            let hi = nodes.partition_point(|&n| (n as usize) < y1 * nx);
            let covered = CoveredNodes {
                nodes: &nodes[lo..hi],
                offsets: &offsets[lo..=hi],
                shares: &shares,
                links: &links[lo..hi],
            };
            let (a, b) = (offsets[lo] as usize, offsets[hi] as usize);
            collide_covered_nodes(
                &domain,
                &src,
                &mut band,
                y0,
                &psm,
                covered,
                &mut exchange[a..b],
            );
        }
    }
    let exchange = exchange
        .iter()
        .map(|e| e.map(|v| v.to_f64_exact()))
        .collect();
    (from_buffer(&shape, &dst), exchange)
}

fn reference_step(p: &Problem, with_coverage: bool) -> (reference::Lattice, Vec<Vec<[f64; 2]>>) {
    let params = reference::Params {
        tau: p.tau,
        force: p.force,
        weighting: to_reference_weighting(p.weighting),
        magic: p.magic,
        lambda_consistent: p.lambda,
        lambda_terms: {
            let t = lambda_terms_of(p);
            (t.friction, t.pressure)
        },
    };
    let covered: Vec<reference::Covered> = if with_coverage {
        p.covered
            .iter()
            .map(|(n, s)| reference::Covered {
                node: *n as usize,
                solids: to_reference_solids(s)
                    .into_iter()
                    .enumerate()
                    .map(|(k, s)| reference::Solid {
                        normal: test_normal(*n, k),
                        ..s
                    })
                    .collect(),
            })
            .collect()
    } else {
        Vec::new()
    };
    reference::step_with_profiles(
        &p.lattice,
        &to_reference_sides(&p.bc),
        &p.profiles,
        &params,
        &covered,
    )
}

/// Kernel step in precision `T` versus reference step, node by node, within `tol` relative to the reference
/// node's Σ|f| (≈ ρ). The exchange is compared within `tol` × 2.5, a bound on the density of any node
/// (ρ ≤ 1.5 · 1.05 inside; up to (1.5 · 1.05)/(1 − 0.2) at velocity sides).
fn compare_steps<T: Real>(p: &Problem, with_coverage: bool, tol: f64) -> Result<(), TestCaseError> {
    let (kf, kex) = kernel_step::<T>(p, &[], with_coverage);
    let (r, rex) = reference_step(p, with_coverage);
    for (node, (k, rf)) in kf.iter().zip(&r.f).enumerate() {
        let (x, y) = (node % p.lattice.nx, node / p.lattice.nx);
        let err = max_abs_diff(k, rf);
        prop_assert!(
            err <= tol * scale(rf),
            "node ({x},{y}) solid={} err={err:e}\nkernel {k:?}\nreference {rf:?}",
            p.lattice.solid[node]
        );
    }
    let rex: Vec<[f64; 2]> = rex.into_iter().flatten().collect();
    prop_assert_eq!(kex.len(), rex.len());
    for (k, e) in kex.iter().zip(&rex) {
        prop_assert!(max_abs_diff(k, e) <= tol * 2.5, "exchange {k:?} vs {e:?}");
    }
    Ok(())
}

/// What a node on Zou–He sides must hold after the gather: density and velocity components, where
/// prescribed.
struct EdgeState {
    density: Option<f64>,
    velocity: [Option<f64>; 2],
}

/// The prescribed state of node (x, y), or `None` if it lies on no Zou–He side. One Zou–He side (possibly
/// meeting a wall): a pressure side fixes ρ and a zero tangential velocity, a velocity side fixes u. Two
/// Zou–He sides (the corner rule): ρ is the prescribed density (the mean of two pressures; not fixed
/// for two velocity sides), u the velocity of a velocity side, else zero. On a lattice one node wide the
/// West (South) side is the node's side, as in the kernels.
fn expected_edge_state(
    bc: &Boundaries<f64>,
    nx: usize,
    ny: usize,
    x: usize,
    y: usize,
) -> Option<EdgeState> {
    let zou_he = |c: SideCondition<f64>| c.is_zou_he().then_some(c);
    let xs = if x == 0 && bc.west.is_zou_he() {
        zou_he(bc.west)
    } else if x + 1 == nx {
        zou_he(bc.east)
    } else {
        None
    };
    let ys = if y == 0 && bc.south.is_zou_he() {
        zou_he(bc.south)
    } else if y + 1 == ny {
        zou_he(bc.north)
    } else {
        None
    };
    let state = match (xs, ys) {
        (None, None) => return None,
        (Some(c), None) | (None, Some(c)) => {
            let normal = usize::from(xs.is_none()); // 0 (x) for West/East, 1 (y) for South/North
            match c {
                SideCondition::Pressure { density } => {
                    let mut velocity = [None; 2];
                    velocity[1 - normal] = Some(0.0); // zero tangential velocity
                    EdgeState {
                        density: Some(density),
                        velocity,
                    }
                }
                SideCondition::Velocity { velocity } => EdgeState {
                    density: None,
                    velocity: velocity.map(Some),
                },
                _ => unreachable!("only Zou–He sides"),
            }
        }
        (Some(a), Some(b)) => {
            use SideCondition::{Pressure, Velocity};
            let density = match (a, b) {
                (Pressure { density: d1 }, Pressure { density: d2 }) => Some(0.5 * (d1 + d2)),
                (Pressure { density }, _) | (_, Pressure { density }) => Some(density),
                _ => None,
            };
            let u = match (a, b) {
                (Velocity { velocity }, _) | (_, Velocity { velocity }) => velocity,
                _ => [0.0; 2],
            };
            EdgeState {
                density,
                velocity: u.map(Some),
            }
        }
    };
    Some(state)
}

// ---------------------------------------------------------------------------------------------------------
// Streaming, boundaries, whole steps
// ---------------------------------------------------------------------------------------------------------

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Periodic streaming is a permutation within each population plane (the sorted bit patterns of every
    /// plane are unchanged, so its sum is too), and streaming with the directions reversed undoes it bitwise.
    #[test]
    fn periodic_streaming_is_a_reversible_permutation(nx in 1usize..=12, ny in 1usize..=12, seed in any::<u64>()) {
        let shape = LatticeShape::for_type::<f64>(nx, ny).expect("small lattice");
        let mut rng = SplitMix(seed);
        let state: Vec<[f64; Q]> = (0..nx * ny).map(|_| rng.populations()).collect();
        let src = to_buffer::<f64>(&shape, &state);
        let mut dst = vec![f64::NAN; shape.buffer_len()];
        stream_periodic(&shape, &src, &mut planes_mut(&shape, &mut dst));
        let (before, after) = (planes(&shape, &src), planes(&shape, &dst));
        for q in 0..Q {
            let mut a: Vec<u64> = before[q].iter().map(|v| v.to_bits()).collect();
            let mut b: Vec<u64> = after[q].iter().map(|v| v.to_bits()).collect();
            a.sort_unstable();
            b.sort_unstable();
            prop_assert_eq!(a, b, "plane {} is not a permutation", q);
        }
        // Reverse: plane q of the streamed state moved by c_q; putting it in plane q̄ moves it by −c_q.
        let streamed = from_buffer(&shape, &dst);
        let swapped: Vec<[f64; Q]> = streamed.iter().map(|f| core::array::from_fn(|q| f[OPPOSITE[q]])).collect();
        let src2 = to_buffer::<f64>(&shape, &swapped);
        let mut back = vec![f64::NAN; shape.buffer_len()];
        stream_periodic(&shape, &src2, &mut planes_mut(&shape, &mut back));
        let restored: Vec<[f64; Q]> =
            from_buffer(&shape, &back).iter().map(|f| core::array::from_fn(|q| f[OPPOSITE[q]])).collect();
        for (r, s) in restored.iter().zip(&state) {
            prop_assert_eq!(r.map(f64::to_bits), s.map(f64::to_bits));
        }
    }

    /// Zou–He on each side: the node ends at exactly the prescribed density (pressure: with zero tangential
    /// velocity) or velocity, the populations not entering through the side are untouched bitwise, and the
    /// kernel closure equals the reference's transverse-momentum form.
    #[test]
    fn zou_he_side_imposes_the_prescribed_state(
        f in node_populations(), side in 0usize..4, pressure in any::<bool>(),
        rho0 in 0.5f64..=1.5, u0 in velocity(),
    ) {
        let (side, rside) = [
            (Side::West, reference::Side::West),
            (Side::East, reference::Side::East),
            (Side::South, reference::Side::South),
            (Side::North, reference::Side::North),
        ][side];
        let mut g = f;
        let mut r = f;
        if pressure {
            zou_he(&mut g, side, SideCondition::Pressure { density: rho0 });
            reference::zou_he_pressure(&mut r, rside, rho0);
        } else {
            zou_he(&mut g, side, SideCondition::Velocity { velocity: u0 });
            reference::zou_he_velocity(&mut r, rside, u0);
        }
        let unknown = reference::incoming(rside);
        prop_assert_eq!(unknown.len(), 3);
        for i in (0..Q).filter(|i| !unknown.contains(i)) {
            prop_assert_eq!(g[i].to_bits(), f[i].to_bits(), "known f_{} changed", i);
        }
        let rho = density(&g);
        let j = momentum(&g);
        let tol = ROUNDOFF * scale(&g);
        if pressure {
            prop_assert!((rho - rho0).abs() <= tol, "density {rho} vs {rho0}");
            let tangential = if matches!(side, Side::West | Side::East) { j[1] } else { j[0] };
            prop_assert!(tangential.abs() <= tol, "tangential momentum {tangential}");
        } else {
            for a in 0..2 {
                prop_assert!((j[a] - rho * u0[a]).abs() <= tol, "momentum {j:?} vs ρu {rho} {u0:?}");
            }
        }
        prop_assert!(max_abs_diff(&g, &r) <= ORACLE * scale(&f));
    }

    /// The known sum of a Zou–He node reads only the populations the closure keeps (the reference's incoming
    /// set replaced by anything leaves it bitwise unchanged) and is ρ(1 + u_n) of the closed node, u_n the
    /// outward normal velocity.
    #[test]
    fn zou_he_known_sum_is_density_times_one_plus_outward_velocity(
        f in node_populations(), side in 0usize..4, rho0 in 0.5f64..=1.5, junk in -1.0f64..1.0,
    ) {
        let (side, rside, normal) = [
            (Side::West, reference::Side::West, [-1.0, 0.0]),
            (Side::East, reference::Side::East, [1.0, 0.0]),
            (Side::South, reference::Side::South, [0.0, -1.0]),
            (Side::North, reference::Side::North, [0.0, 1.0]),
        ][side];
        let known = zou_he_known_sum(&f, side);
        let mut h = f;
        for i in reference::incoming(rside) {
            h[i] = junk;
        }
        prop_assert_eq!(zou_he_known_sum(&h, side).to_bits(), known.to_bits());
        let mut g = f;
        zou_he(&mut g, side, SideCondition::Pressure { density: rho0 });
        let (rho, j) = (density(&g), momentum(&g));
        let outward = (j[0] * normal[0] + j[1] * normal[1]) / rho;
        prop_assert!((known - rho * (1.0 + outward)).abs() <= ROUNDOFF * scale(&g),
            "K = {known} against ρ(1 + u_n) = {}", rho * (1.0 + outward));
    }

    /// The radiating side's density solves its characteristic condition with the Zou–He relation,
    /// ρ = ρ₀(1 + √3(1 − r)(K/ρ − 1 − ū)), and the running mean moves by r(u_n − ū) with u_n = K/ρ − 1; r = 1
    /// holds ρ₀ exactly, a node at rest with ū = 0 holds ρ₀ at any r, and r = 0 passes the wave, ρ − ρ₀ = ρ₀√3 u_n.
    #[test]
    fn radiating_density_solves_the_characteristic_condition(
        rho0 in 0.5f64..=1.5, un in -0.05f64..0.05, mean in -0.05f64..0.05, rate in 0.0f64..=1.0,
        wave in -0.05f64..0.05,
    ) {
        // K of a node whose density is off ρ₀ by a wave and whose outward velocity is u_n.
        let known = rho0 * (1.0 + wave) * (1.0 + un);
        let mut m = mean;
        let rho = radiating_density(rho0, known, &mut m, rate);
        let u = known / rho - 1.0;
        let condition = rho0 * (1.0 + 3f64.sqrt() * (1.0 - rate) * (u - mean));
        prop_assert!((rho - condition).abs() <= ROUNDOFF, "ρ = {rho}, condition {condition}");
        prop_assert!((m - (mean + rate * (u - mean))).abs() <= ROUNDOFF, "mean {m}");
        let mut m1 = mean;
        prop_assert_eq!(radiating_density(rho0, known, &mut m1, 1.0).to_bits(), rho0.to_bits());
        let mut m0 = 0.0;
        let rest = radiating_density(rho0, rho0, &mut m0, rate);
        prop_assert!((rest - rho0).abs() <= ROUNDOFF, "at rest {rest}");
        let mut mp = 0.0;
        let passed = radiating_density(rho0, known, &mut mp, 0.0);
        let up = known / passed - 1.0;
        prop_assert!((passed - rho0 - rho0 * 3f64.sqrt() * up).abs() <= ROUNDOFF);
        // f32 agrees with f64 to its precision.
        let mut m32 = mean as f32;
        let r32 = radiating_density(rho0 as f32, known as f32, &mut m32, rate as f32);
        prop_assert!((f64::from(r32) - rho).abs() <= 64.0 * f64::from(f32::EPSILON), "f32 {r32} against {rho}");
    }

    /// Zou–He corners (two Zou–He sides): the node ends at exactly ρ and u, the four known populations (rest,
    /// and the three leaving through the sides) are untouched, and the kernel equals the reference rule.
    #[test]
    fn zou_he_corner_imposes_density_and_velocity(
        f in node_populations(), corner in 0usize..4, rho0 in 0.5f64..=1.5, u0 in velocity(),
    ) {
        let (sx, sy, rx, ry) = [
            (Side::West, Side::South, reference::Side::West, reference::Side::South),
            (Side::East, Side::South, reference::Side::East, reference::Side::South),
            (Side::West, Side::North, reference::Side::West, reference::Side::North),
            (Side::East, Side::North, reference::Side::East, reference::Side::North),
        ][corner];
        let mut g = f;
        zou_he_corner(&mut g, sx, sy, rho0, u0);
        let mut r = f;
        reference::zou_he_corner(&mut r, rx, ry, rho0, u0);
        // Known: the populations entering through neither side (rest, and the three leaving the corner).
        let (in_x, in_y) = (reference::incoming(rx), reference::incoming(ry));
        let known: Vec<usize> = (0..Q).filter(|i| !in_x.contains(i) && !in_y.contains(i)).collect();
        prop_assert_eq!(known.len(), 4);
        for &i in &known {
            prop_assert_eq!(g[i].to_bits(), f[i].to_bits(), "known f_{} changed", i);
        }
        let rho = density(&g);
        let j = momentum(&g);
        let tol = ROUNDOFF * scale(&g);
        prop_assert!((rho - rho0).abs() <= tol, "density {rho} vs {rho0}");
        for a in 0..2 {
            prop_assert!((j[a] - rho0 * u0[a]).abs() <= tol, "momentum {j:?} vs ρu");
        }
        prop_assert!(max_abs_diff(&g, &r) <= ORACLE * scale(&f));
    }

    /// On a whole lattice with Zou–He and wall sides, the general gather leaves every fluid node of a Zou–He
    /// side at its prescribed state (see [`expected_edge_state`]), including corners where a Zou–He side meets
    /// a wall or another Zou–He side.
    #[test]
    fn gather_node_closes_every_zou_he_node(nx in 1usize..=12, ny in 1usize..=12, seed in any::<u64>()) {
        let mut p = random_problem(nx, ny, seed, 0.15, 0.0);
        let mut rng = SplitMix(seed ^ 0x5EED);
        let mut side = || match rng.below(5) {
            0 => SideCondition::Wall,
            1 | 2 => SideCondition::Pressure { density: rng.range(0.8, 1.2) },
            _ => SideCondition::Velocity { velocity: rng.velocity() },
        };
        p.bc = Boundaries { west: side(), east: side(), south: side(), north: side() };
        let shape = LatticeShape::for_type::<f64>(nx, ny).expect("small lattice");
        let flags: Vec<u8> = p.lattice.solid.iter().map(|&s| if s { SOLID } else { FLUID }).collect();
        let src = to_buffer::<f64>(&shape, &p.lattice.f);
        for y in 0..ny {
            for x in 0..nx {
                if flags[shape.index(x, y)] == SOLID {
                    continue;
                }
                let Some(want) = expected_edge_state(&p.bc, nx, ny, x, y) else { continue };
                let g = gather_node(&shape, &src, &p.bc, &SideProfiles::none(), &flags, x, y);
                let (rho, j) = (density(&g), momentum(&g));
                let tol = ROUNDOFF * scale(&g);
                if let Some(rho0) = want.density {
                    prop_assert!((rho - rho0).abs() <= tol, "({x},{y}) density {rho} vs {rho0}");
                }
                for a in 0..2 {
                    if let Some(ua) = want.velocity[a] {
                        prop_assert!((j[a] - rho * ua).abs() <= tol, "({x},{y}) momentum {j:?} axis {a} vs ρ {ua}");
                    }
                }
            }
        }
    }

    /// `step_band` over the whole lattice equals the reference step (stream with bounce-back, Zou–He, BGK) on
    /// random lattices with obstacle nodes and random side conditions.
    #[test]
    fn step_band_matches_the_reference(nx in 1usize..=12, ny in 1usize..=12, seed in any::<u64>()) {
        let p = random_problem(nx, ny, seed, 0.15, 0.0);
        compare_steps::<f64>(&p, false, ORACLE)?;
    }

    /// `step_band` followed by `collide_covered_nodes` equals the reference step with PSM at the covered
    /// nodes, populations and momentum exchange per solid share.
    #[test]
    fn covered_nodes_match_the_reference(nx in 1usize..=12, ny in 1usize..=12, seed in any::<u64>()) {
        let p = random_problem(nx, ny, seed, 0.1, 0.3);
        compare_steps::<f64>(&p, true, ORACLE)?;
    }

    /// Updating the lattice as several bands (as threads do) gives bitwise the result of one band,
    /// populations and exchange, for any split of the rows (empty bands included).
    #[test]
    fn bands_are_independent(
        nx in 1usize..=12, ny in 1usize..=12, seed in any::<u64>(),
        cuts in prop::collection::vec(0usize..=12, 0..4),
    ) {
        let p = random_problem(nx, ny, seed, 0.1, 0.3);
        let mut cuts: Vec<usize> = cuts.into_iter().map(|c| c.min(ny)).collect();
        cuts.sort_unstable();
        let (one, ex1) = kernel_step::<f64>(&p, &[], true);
        let (many, ex2) = kernel_step::<f64>(&p, &cuts, true);
        for (a, b) in one.iter().zip(&many) {
            prop_assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
        }
        prop_assert_eq!(
            ex1.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>(),
            ex2.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// `gathered_moments` (the moments the next collision sees) equals ρ and the half-force-shifted u of the
    /// reference's streamed and closed populations; obstacle nodes report ρ = 1, u = 0.
    #[test]
    fn gathered_moments_match_the_reference(nx in 1usize..=12, ny in 1usize..=12, seed in any::<u64>()) {
        let p = random_problem(nx, ny, seed, 0.15, 0.0);
        let shape = LatticeShape::for_type::<f64>(nx, ny).expect("small lattice");
        let flags: Vec<u8> = p.lattice.solid.iter().map(|&s| if s { SOLID } else { FLUID }).collect();
        let src = to_buffer::<f64>(&shape, &p.lattice.f);
        let mut rho = vec![f64::NAN; shape.nodes()];
        let mut u = vec![[f64::NAN; 2]; shape.nodes()];
        gathered_moments(&shape, &src, &p.bc, &SideProfiles::none(), &flags, p.force, &mut rho, &mut u);
        let sides = to_reference_sides(&p.bc);
        let mut streamed = reference::stream(&p.lattice, &sides);
        reference::close_zou_he(&p.lattice, &mut streamed, &sides);
        for n in 0..shape.nodes() {
            let (r_rho, r_u) = if p.lattice.solid[n] {
                (1.0, [0.0; 2])
            } else {
                reference::macroscopic(&streamed[n], p.force)
            };
            prop_assert!(max_abs_diff(&[rho[n], u[n][0], u[n][1]], &[r_rho, r_u[0], r_u[1]]) <= ORACLE * r_rho.max(1.0), "node {n}");
        }
    }

    /// A whole step conserves the fluid mass of a lattice closed by walls, periodic sides and obstacle nodes
    /// (bounce-back returns every population), and on a fully periodic lattice without obstacles it adds
    /// exactly N F of momentum. Roundoff: each node contributes ≤ 64 ulp of its Σ|f| and the global sums add
    /// ≤ 9N ulp of the total, so 1e−12 of the total (N ≤ 144) is a safe bound.
    #[test]
    fn whole_step_conserves_mass_and_momentum(nx in 1usize..=12, ny in 1usize..=12, seed in any::<u64>(), periodic in any::<bool>()) {
        let mut p = random_problem(nx, ny, seed, if periodic { 0.0 } else { 0.15 }, 0.0);
        // Close the lattice: every side periodic, or Zou–He (open) sides replaced by walls.
        let close = |c: SideCondition<f64>| {
            if periodic {
                SideCondition::Periodic
            } else if c.is_zou_he() {
                SideCondition::Wall
            } else {
                c
            }
        };
        p.bc = Boundaries {
            west: close(p.bc.west),
            east: close(p.bc.east),
            south: close(p.bc.south),
            north: close(p.bc.north),
        };
        prop_assert_eq!(p.bc.validate(), Ok(()));
        let (after, _) = kernel_step::<f64>(&p, &[], false);
        let fluid = |f: &[[f64; Q]]| -> (f64, [f64; 2], f64) {
            let mut total = (0.0, [0.0; 2], 0.0);
            for (n, fi) in f.iter().enumerate() {
                if !p.lattice.solid[n] {
                    total.0 += density(fi);
                    let j = momentum(fi);
                    total.1[0] += j[0];
                    total.1[1] += j[1];
                    total.2 += scale(fi);
                }
            }
            total
        };
        let (m0, j0, s0) = fluid(&p.lattice.f);
        let (m1, j1, _) = fluid(&after);
        prop_assert!((m1 - m0).abs() <= 1e-12 * s0, "mass {m0} -> {m1}");
        if periodic {
            let nodes = (nx * ny) as f64;
            for a in 0..2 {
                prop_assert!((j1[a] - j0[a] - nodes * p.force[a]).abs() <= 1e-12 * s0, "momentum axis {a}");
            }
        }
    }

    /// The `f32` instantiation of the step (bulk, special and covered nodes) agrees with the `f64` reference
    /// within [`ORACLE_F32`].
    #[test]
    fn f32_step_matches_the_reference(nx in 1usize..=12, ny in 1usize..=12, seed in any::<u64>()) {
        let p = random_problem(nx, ny, seed, 0.1, 0.3);
        compare_steps::<f32>(&p, true, ORACLE_F32)?;
    }
}

/// Number of steps of [`several_steps_match_the_reference`].
const STEPS: usize = 8;
/// Allowance after [`STEPS`] steps: each step adds at most [`ORACLE`]-sized differences and propagates
/// earlier ones with a gain of order one (collision weights |1 − ω| ≤ 1; Zou–He closures at most a few), so
/// 10 × [`ORACLE`] per step is ample while any systematic error would be orders of magnitude larger.
const ORACLE_STEPS: f64 = 10.0 * STEPS as f64 * ORACLE;
/// The sane band of Σ|f| per node for the multi-step comparison (the inputs start below 1.6 · 1.05 inside
/// and ≈ 2.4 at velocity sides).
const SANE_SCALE: f64 = 4.0;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Several consecutive kernel steps (two-buffer scheme, covered nodes included) stay on the reference
    /// trajectory. Random, far-from-smooth initial data on tiny lattices can make the dynamics themselves
    /// unstable (seen: a Zou–He pressure node fully covered by PSM solids, B = 1, walled in by obstacle
    /// nodes, diverged in a few steps, kernel and reference alike, and was stable without the coverage;
    /// plausibly because f₀ is not relaxed at B = 1 while the closure keeps re-imposing ρ). Near a
    /// divergence roundoff is amplified without bound, so the
    /// comparison stops at the first step whose reference state leaves the sane band [`SANE_SCALE`].
    #[test]
    fn several_steps_match_the_reference(nx in 1usize..=12, ny in 1usize..=12, seed in any::<u64>()) {
        let mut kernel = random_problem(nx, ny, seed, 0.1, 0.3);
        let mut oracle = kernel.clone();
        for step in 0..STEPS {
            kernel.lattice.f = kernel_step::<f64>(&kernel, &[], true).0;
            oracle.lattice = reference_step(&oracle, true).0;
            let sane = |f: &[f64; Q]| scale(f).is_finite() && scale(f) <= SANE_SCALE;
            if !oracle.lattice.f.iter().all(sane) {
                break;
            }
            for (node, (k, r)) in kernel.lattice.f.iter().zip(&oracle.lattice.f).enumerate() {
                let err = max_abs_diff(k, r);
                prop_assert!(err <= ORACLE_STEPS * scale(r), "step {step} node {node}: err {err:e}");
            }
        }
    }
}

/// Body-force-driven Poiseuille flow between half-way bounce-back walls converges to the exact lattice
/// solution of docs/references.md §4.1 (parabola plus the slip (g/ν)(16Λ − 3)/24), for τ on both sides of the
/// slip-free τ = ½ + √(3/16). The steady LB solution is exact, so the only error is the residual transient
/// (e^{−νπ²t/H²} after t steps, < 1e−12 here) and roundoff: tolerance 1e−9 of the centreline velocity.
#[test]
fn body_force_poiseuille_matches_the_slip_formula() {
    let (nx, ny, g) = (1, 8, 1e-6);
    let shape = LatticeShape::for_type::<f64>(nx, ny).expect("small lattice");
    let bc = Boundaries {
        west: SideCondition::Periodic,
        east: SideCondition::Periodic,
        south: SideCondition::Wall,
        north: SideCondition::Wall,
    };
    let flags = vec![FLUID; shape.nodes()];
    let domain = Domain {
        shape,
        bc,
        profiles: SideProfiles::none(),
        flags: &flags,
    };
    let mut special = vec![0u32; shape.nodes()];
    let count = classify_special_nodes(&shape, &bc, &flags, &mut special);
    special.truncate(count);
    for tau in [0.6, 0.8, 1.0, 1.5] {
        let params = FluidParams {
            tau,
            force: [g, 0.0],
        };
        let rest = equilibrium(1.0, [0.0; 2]);
        let mut a = to_buffer::<f64>(&shape, &vec![rest; shape.nodes()]);
        let mut b = a.clone();
        for _ in 0..12_000 {
            step_band(
                &domain,
                &a,
                &mut planes_mut(&shape, &mut b),
                0,
                ny,
                &params,
                &Collision::Bgk,
                &special,
            );
            std::mem::swap(&mut a, &mut b);
        }
        let mut rho = vec![0.0; shape.nodes()];
        let mut u = vec![[0.0; 2]; shape.nodes()];
        gathered_moments(
            &shape,
            &a,
            &bc,
            &SideProfiles::none(),
            &flags,
            [g, 0.0],
            &mut rho,
            &mut u,
        );
        let u_max =
            analytic::poiseuille_max_velocity(g, analytic::lattice_viscosity(tau), ny as f64);
        for (j, uj) in u.iter().enumerate() {
            let exact = analytic::lattice_poiseuille_velocity(g, tau, ny, j);
            assert!(
                (uj[0] - exact).abs() <= 1e-9 * u_max,
                "τ={tau} node {j}: {} vs {exact}",
                uj[0]
            );
            assert!(uj[1].abs() <= 1e-9 * u_max);
        }
    }
}

// ---------------------------------------------------------------------------------------------------------
// Two-relaxation-time collision (TRT, Ginzburg, Verhaeghe & d'Humières 2008)
// ---------------------------------------------------------------------------------------------------------

/// Magic parameters Λ: the default 3/16, 1/4, and anything in [1e−3, 2] (with τ⁺ ∈ [0.51, 2] this gives
/// τ⁻ from just above ½ to 200).
fn magic() -> impl Strategy<Value = f64> {
    prop_oneof![Just(3.0 / 16.0), Just(0.25), 1e-3f64..=2.0]
}

fn trt(magic: f64) -> Collision<f64> {
    Collision::Trt(Trt::new(magic).expect("positive magic parameter"))
}

/// A random problem (as [`random_problem`]) relaxed by TRT with a magic parameter drawn from the seed.
fn random_trt_problem(nx: usize, ny: usize, seed: u64, p_solid: f64, p_covered: f64) -> Problem {
    let mut p = random_problem(nx, ny, seed, p_solid, p_covered);
    let mut rng = SplitMix(seed ^ 0x5452_545F_4D41_4749);
    p.magic = Some(match rng.below(3) {
        0 => 3.0 / 16.0,
        1 => 0.25,
        _ => rng.range(1e-3, 2.0),
    });
    p
}

proptest! {
    /// TRT conserves mass and momentum to roundoff and equals the reference TRT (written from the paper's
    /// formula: symmetric and antisymmetric parts relaxed at 1/τ⁺ and 1/τ⁻).
    #[test]
    fn trt_conserves_mass_and_momentum(f in node_populations(), tau in tau(), magic in magic()) {
        let c = trt(magic);
        let mut g = f;
        trt_collide(&mut g, c.rates(tau).expect("valid rates"));
        let tol = ROUNDOFF * scale(&f);
        prop_assert!((density(&g) - density(&f)).abs() <= tol);
        let (j0, j1) = (momentum(&f), momentum(&g));
        prop_assert!((j1[0] - j0[0]).abs() <= tol && (j1[1] - j0[1]).abs() <= tol);
        let r = reference::trt(&f, tau, magic);
        prop_assert!(max_abs_diff(&g, &r) <= ORACLE * scale(&f));
    }

    /// Guo-forced TRT (source split into even and odd parts) adds no mass and exactly F of momentum, whatever
    /// τ⁺ and τ⁻; it equals the reference.
    #[test]
    fn forced_trt_adds_exactly_the_force(
        f in node_populations(), tau in tau(), magic in magic(), force in force(),
    ) {
        let mut g = f;
        trt_collide_forced(&mut g, trt(magic).rates(tau).expect("valid rates"), force);
        let tol = ROUNDOFF * scale(&f);
        prop_assert!((density(&g) - density(&f)).abs() <= tol);
        let (j0, j1) = (momentum(&f), momentum(&g));
        for a in 0..2 {
            prop_assert!((j1[a] - j0[a] - force[a]).abs() <= tol, "axis {a}");
        }
        let r = reference::trt_forced(&f, tau, magic, force);
        prop_assert!(max_abs_diff(&g, &r) <= ORACLE * scale(&f));
    }

    /// With Λ = (τ − ½)², τ⁻ = τ⁺ and TRT is BGK: equal to roundoff, forced or not (the two differ only in
    /// the order of operations and in τ⁻ = ½ + Λ/(τ − ½) being τ to a few ulp).
    #[test]
    fn trt_with_the_bgk_magic_parameter_is_bgk(
        f in node_populations(), tau in tau(), forced in any::<bool>(), force in force(),
    ) {
        let force = if forced { force } else { [0.0; 2] };
        let c = trt((tau - 0.5) * (tau - 0.5));
        let mut g = f;
        trt_collide_forced(&mut g, c.rates(tau).expect("valid rates"), force);
        let mut h = f;
        bgk_collide_forced(&mut h, 1.0 / tau, force);
        prop_assert!(max_abs_diff(&g, &h) <= ROUNDOFF * scale(&f), "{g:?} vs {h:?}");
    }

    /// PSM on TRT: mass conserved; fluid momentum change = (1 − B) F − Σ exchange (momentum handed to the
    /// solids, exactly); equal to the reference, exchange included, for all four solid operators.
    #[test]
    fn psm_on_trt_exchanges_momentum_with_the_solids(
        f in node_populations(), tau in tau(), magic in magic(), shares in shares(), w in weighting(),
        forced in any::<bool>(), force in force(), op in 0usize..4,
    ) {
        let force = if forced { force } else { [0.0; 2] };
        let (solid, ref_op) = [
            (SolidOperator::NonEquilibriumBounceBack, reference::SolidOp::NonEquilibriumBounceBack),
            (SolidOperator::Superposition, reference::SolidOp::Superposition),
            (SolidOperator::MovingWallBounceBack, reference::SolidOp::MovingWallBounceBack),
            (SolidOperator::LinearizedNonEquilibriumBounceBack, reference::SolidOp::LinearizedNonEquilibriumBounceBack),
        ][op];
        let params = PsmParams { tau, weighting: w, force, solid, collision: trt(magic), lambda: Default::default() };
        let mut g = f;
        let mut exchange = vec![[f64::NAN; 2]; shares.len()];
        let b = psm_collide(&mut g, &params, &shares, &mut exchange);
        prop_assert!((0.0..=1.0).contains(&b));
        let tol = ROUNDOFF * scale(&f);
        prop_assert!((density(&g) - density(&f)).abs() <= tol);
        let (j0, j1) = (momentum(&f), momentum(&g));
        for a in 0..2 {
            let handed: f64 = exchange.iter().map(|e| e[a]).sum();
            prop_assert!((j1[a] - j0[a] - ((1.0 - b) * force[a] - handed)).abs() <= tol, "axis {a}");
        }
        let (r, ex) = reference::psm_with_collision(
            &f, tau, Some(magic), to_reference_weighting(w), ref_op, force, &to_reference_solids(&shares),
        );
        prop_assert!(max_abs_diff(&g, &r) <= ORACLE * scale(&f));
        for (k, e) in exchange.iter().zip(&ex) {
            prop_assert!(max_abs_diff(k, e) <= ORACLE * scale(&f));
        }
    }

    /// PSM on TRT with every solid fraction zero is bitwise the (forced) TRT collision.
    #[test]
    fn psm_on_trt_with_zero_solid_fraction_is_bitwise_trt(
        f in node_populations(), tau in tau(), magic in magic(), n in 0usize..=3, u_s in velocity(),
        forced in any::<bool>(), force in force(),
    ) {
        let force = if forced { force } else { [0.0; 2] };
        let c = trt(magic);
        let shares = vec![SolidShare { fraction: 0.0, velocity: u_s , wall_gradient: Default::default() }; n];
        let mut exchange = vec![[f64::NAN; 2]; n];
        let params = PsmParams {
            tau, weighting: Weighting::NobleTorczynski, force, solid: SolidOperator::NonEquilibriumBounceBack,
            collision: c,
            lambda: Default::default(),
        };
        let mut g = f;
        prop_assert_eq!(psm_collide(&mut g, &params, &shares, &mut exchange), 0.0);
        let mut h = f;
        let rates = c.rates(tau).expect("valid rates");
        if forced {
            trt_collide_forced(&mut h, rates, force);
        } else {
            trt_collide(&mut h, rates);
        }
        prop_assert_eq!(g.map(f64::to_bits), h.map(f64::to_bits));
        prop_assert!(exchange.iter().all(|e| *e == [0.0, 0.0]));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// A whole TRT step (bulk pass, special nodes, PSM on TRT at covered nodes) equals the reference step on
    /// random lattices with obstacle nodes, random wall / pressure / velocity sides and random coverage, in
    /// f64 and f32 (tolerances as for BGK: same formulas, different order of operations).
    #[test]
    fn trt_step_matches_the_reference(nx in 1usize..=12, ny in 1usize..=12, seed in any::<u64>()) {
        let p = random_trt_problem(nx, ny, seed, 0.1, 0.3);
        compare_steps::<f64>(&p, true, ORACLE)?;
        compare_steps::<f32>(&p, true, ORACLE_F32)?;
    }

    /// TRT updated as several bands (as threads do) is bitwise the one-band update, exchange included.
    #[test]
    fn trt_bands_are_independent(
        nx in 1usize..=12, ny in 1usize..=12, seed in any::<u64>(),
        cuts in prop::collection::vec(0usize..=12, 0..4),
    ) {
        let p = random_trt_problem(nx, ny, seed, 0.1, 0.3);
        let mut cuts: Vec<usize> = cuts.into_iter().map(|c| c.min(ny)).collect();
        cuts.sort_unstable();
        let (one, ex1) = kernel_step::<f64>(&p, &[], true);
        let (many, ex2) = kernel_step::<f64>(&p, &cuts, true);
        for (a, b) in one.iter().zip(&many) {
            prop_assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
        }
        prop_assert_eq!(
            ex1.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>(),
            ex2.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
    }
}

/// Bad TRT parameters are refused with a `Result`, never a panic: Λ ≤ 0 or not finite, τ⁺ ≤ ½, and a τ⁻ that
/// is not finite and above ½ (Λ so small that ½ + Λ/(τ − ½) rounds to ½, or so large it overflows).
#[test]
fn bad_trt_parameters_are_refused() {
    for bad in [0.0, -0.1, f64::NAN, f64::INFINITY, -0.0] {
        assert_eq!(Trt::new(bad), Err(CollisionError::Magic), "Λ = {bad}");
    }
    let good = trt(3.0 / 16.0);
    for bad_tau in [0.5, 0.3, f64::NAN, f64::INFINITY] {
        assert_eq!(
            good.rates(bad_tau),
            Err(CollisionError::Tau),
            "τ = {bad_tau}"
        );
        assert_eq!(
            Collision::<f64>::Bgk.rates(bad_tau),
            Err(CollisionError::Tau)
        );
    }
    assert_eq!(trt(1e-300).rates(1.0), Err(CollisionError::TauMinus));
    assert_eq!(trt(1e308).rates(0.5 + 1e-10), Err(CollisionError::TauMinus));
    assert_eq!(
        Trt::<f32>::new(1e-30)
            .map(|t| Collision::Trt(t).rates(1.0f32))
            .expect("positive"),
        Err(CollisionError::TauMinus)
    );
    let r = good.rates(1.0).expect("valid");
    assert_eq!(r.plus, 1.0);
    assert!((1.0 / r.minus - (0.5 + 0.375)).abs() < 1e-15);
    assert_eq!(Trt::<f64>::default().magic(), 3.0 / 16.0);
}

/// Body-force Poiseuille flow between half-way bounce-back walls with TRT: the steady solution is the parabola
/// plus the slip (g/ν)(16Λ − 3)/24, now with the TRT Λ (Ginzburg & d'Humières 2003; docs/references.md §4.1), so at
/// fixed Λ the relative error against the parabola is the same at every τ. At Λ = 3/16 the slip vanishes:
/// the error is zero up to the residual transient (e^{−νπ²t/H²} < 1e−13 after the steps run) and roundoff, so
/// 1e−10 of the centreline velocity (the issue's bound on τ-independence) at every τ of the acceptance set.
/// At Λ = 1/4 the profile matches parabola + slip to the same 1e−10 at every τ: the error is Λ's, not τ's.
#[test]
fn trt_poiseuille_error_does_not_depend_on_tau() {
    let (nx, ny, g) = (1, 8, 1e-6);
    let shape = LatticeShape::for_type::<f64>(nx, ny).expect("small lattice");
    let bc = Boundaries {
        west: SideCondition::Periodic,
        east: SideCondition::Periodic,
        south: SideCondition::Wall,
        north: SideCondition::Wall,
    };
    let flags = vec![FLUID; shape.nodes()];
    let domain = Domain {
        shape,
        bc,
        profiles: SideProfiles::none(),
        flags: &flags,
    };
    let mut special = vec![0u32; shape.nodes()];
    let count = classify_special_nodes(&shape, &bc, &flags, &mut special);
    special.truncate(count);
    for magic in [3.0 / 16.0, 0.25] {
        let mut errors = Vec::new();
        for tau in [0.55, 0.6, 0.8, 1.2, 2.0] {
            let params = FluidParams {
                tau,
                force: [g, 0.0],
            };
            let collision = trt(magic);
            let nu = analytic::lattice_viscosity(tau);
            let rest = equilibrium(1.0, [0.0; 2]);
            let mut a = to_buffer::<f64>(&shape, &vec![rest; shape.nodes()]);
            let mut b = a.clone();
            // Slowest mode e^{−νπ²t/H²}: at τ = 0.55, 40 000 steps leave e^{−104}.
            for _ in 0..40_000 {
                step_band(
                    &domain,
                    &a,
                    &mut planes_mut(&shape, &mut b),
                    0,
                    ny,
                    &params,
                    &collision,
                    &special,
                );
                std::mem::swap(&mut a, &mut b);
            }
            let mut rho = vec![0.0; shape.nodes()];
            let mut u = vec![[0.0; 2]; shape.nodes()];
            gathered_moments(
                &shape,
                &a,
                &bc,
                &SideProfiles::none(),
                &flags,
                [g, 0.0],
                &mut rho,
                &mut u,
            );
            let u_max = analytic::poiseuille_max_velocity(g, nu, ny as f64);
            let slip = analytic::bounce_back_slip(g, nu, magic);
            let mut worst = 0.0f64;
            for (j, uj) in u.iter().enumerate() {
                let y = j as f64 + 0.5;
                let parabola = analytic::poiseuille_velocity(g, nu, ny as f64, y);
                let relative = (uj[0] - parabola) / u_max;
                // Deviation from parabola + slip, and the relative error against the parabola alone.
                assert!(
                    (uj[0] - parabola - slip).abs() <= 1e-10 * u_max,
                    "Λ={magic} τ={tau} node {j}: {} vs {}",
                    uj[0],
                    parabola + slip
                );
                assert!(uj[1].abs() <= 1e-10 * u_max);
                worst = worst.max(relative.abs());
            }
            errors.push(worst);
        }
        let (lo, hi) = errors
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(l, h), &e| (l.min(e), h.max(e)));
        assert!(
            hi - lo <= 1e-10,
            "Λ={magic}: relative error varies with τ: {errors:?}"
        );
        if magic == 3.0 / 16.0 {
            assert!(hi <= 1e-10, "Λ = 3/16 must be exact: {errors:?}");
        } else {
            // (16Λ − 3)/24 · g/ν over g H²/(8ν) = (16Λ − 3)/(3H²): 1/192 at Λ = 1/4, H = 8.
            assert!((hi - 1.0 / 192.0).abs() <= 1e-10, "{errors:?}");
        }
    }
}

// ---------------------------------------------------------------------------------------------------------
// ΩΛ: the magic-parameter-consistent partially saturated operator
// ---------------------------------------------------------------------------------------------------------

fn open_mask() -> impl Strategy<Value = OpenLinks> {
    any::<u16>().prop_map(|m| m & ALL_LINKS_OPEN)
}

fn open_bools(m: OpenLinks) -> [bool; Q] {
    core::array::from_fn(|i| i != 0 && m & (1 << i) != 0)
}

fn fluid_choice() -> impl Strategy<Value = Option<f64>> {
    prop_oneof![Just(None), magic().prop_map(Some)]
}

fn collision_of(magic: Option<f64>) -> Collision<f64> {
    magic.map_or(Collision::Bgk, trt)
}

fn lambda_params(tau: f64, w: Weighting, force: [f64; 2], magic: Option<f64>) -> PsmParams<f64> {
    PsmParams {
        tau,
        weighting: w,
        force,
        solid: SolidOperator::LambdaConsistent,
        collision: collision_of(magic),
        // Both forms of ΩΛ over the cases: the wall-pressure one above τ = 1.25.
        lambda: if tau > 1.25 {
            LambdaTerms::WALL_PRESSURE
        } else {
            LambdaTerms::FRICTION_ONLY
        },
    }
}

/// ΩΛ's constants of a lattice-step problem, the same for the kernels and the reference: the wall-pressure form
/// above τ = 1.25, friction only below, so both are exercised.
fn lambda_terms_of(p: &Problem) -> LambdaTerms {
    if p.tau > 1.25 {
        LambdaTerms::WALL_PRESSURE
    } else {
        LambdaTerms::FRICTION_ONLY
    }
}

proptest! {
    /// ΩΛ conserves mass; the fluid's momentum changes by (1 − B) F minus what the solids receive (momentum is
    /// exchanged, never created); it equals the reference (written from the definition), exchange included,
    /// for BGK and TRT, both weightings, partly and fully covered nodes (shares summing past 1 included) and
    /// any set of open links.
    #[test]
    fn lambda_operator_exchanges_momentum_with_the_solids(
        f in node_populations(), tau in tau(), magic in fluid_choice(), shares in shares(), w in weighting(),
        forced in any::<bool>(), force in force(), open in open_mask(),
    ) {
        let force = if forced { force } else { [0.0; 2] };
        let params = lambda_params(tau, w, force, magic);
        let mut g = f;
        let mut exchange = vec![[f64::NAN; 2]; shares.len()];
        let b = psm_collide_links(&mut g, &params, &shares, open, &mut exchange);
        prop_assert!((0.0..=1.0).contains(&b));
        let tol = ROUNDOFF * scale(&f);
        prop_assert!((density(&g) - density(&f)).abs() <= tol);
        let (j0, j1) = (momentum(&f), momentum(&g));
        for a in 0..2 {
            let handed: f64 = exchange.iter().map(|e| e[a]).sum();
            prop_assert!((j1[a] - j0[a] - ((1.0 - b) * force[a] - handed)).abs() <= tol, "axis {a}");
        }
        let (r, ex) = reference::psm_lambda(
            &f, tau, magic, to_reference_weighting(w), force, &to_reference_solids(&shares), open_bools(open),
            (params.lambda.friction, params.lambda.pressure),
        );
        prop_assert!(max_abs_diff(&g, &r) <= ORACLE * scale(&f), "{g:?}\nvs {r:?}");
        for (k, e) in exchange.iter().zip(&ex) {
            prop_assert!(max_abs_diff(k, e) <= ORACLE * scale(&f));
        }
    }

    /// The velocity ΩΛ reports ([`psm_velocity`], what fluxes are measured with) is the trapezoidal velocity of
    /// its update at a partly covered node, (pre + post momentum)/(2ρ), and the solid's velocity at a fully
    /// covered one.
    #[test]
    fn lambda_velocity_is_the_velocity_of_the_update(
        f in node_populations(), tau in tau(), magic in fluid_choice(), shares in shares(), w in weighting(),
        forced in any::<bool>(), force in force(),
    ) {
        let force = if forced { force } else { [0.0; 2] };
        let params = lambda_params(tau, w, force, magic);
        let (rho, u) = psm_velocity(&f, &params, &shares);
        let mut g = f;
        let mut exchange = vec![[0.0; 2]; shares.len()];
        psm_collide(&mut g, &params, &shares, &mut exchange);
        let eps: f64 = shares.iter().map(|s| s.fraction).sum();
        prop_assert_eq!(rho, density(&f));
        let tol = ROUNDOFF * scale(&f);
        if eps >= 1.0 - lbdem_reference::lbm::LAMBDA_FULL_GAP {
            for (a, ua) in u.iter().enumerate() {
                let want: f64 = shares.iter().map(|s| s.fraction / eps * s.velocity[a]).sum();
                prop_assert!((ua - want).abs() <= tol);
            }
        } else if eps > 0.0 {
            let (j0, j1) = (momentum(&f), momentum(&g));
            for a in 0..2 {
                prop_assert!((u[a] - 0.5 * (j0[a] + j1[a]) / rho).abs() <= tol, "axis {a}");
            }
        }
    }

    /// ΩΛ with every solid fraction zero is bitwise the fluid collision and hands nothing over.
    #[test]
    fn lambda_operator_with_zero_solid_fraction_is_bitwise_the_fluid_collision(
        f in node_populations(), tau in tau(), magic in fluid_choice(), n in 0usize..=3, u_s in velocity(),
        forced in any::<bool>(), force in force(), open in open_mask(),
    ) {
        let force = if forced { force } else { [0.0; 2] };
        let params = lambda_params(tau, Weighting::SolidFraction, force, magic);
        let shares = vec![SolidShare { fraction: 0.0, velocity: u_s , wall_gradient: Default::default() }; n];
        let mut exchange = vec![[f64::NAN; 2]; n];
        let mut g = f;
        prop_assert_eq!(psm_collide_links(&mut g, &params, &shares, open, &mut exchange), 0.0);
        let mut h = f;
        let c = collision_of(magic);
        fluid_collide(&mut h, &c, c.rates(tau).expect("valid rates"), force);
        prop_assert_eq!(g.map(f64::to_bits), h.map(f64::to_bits));
        prop_assert!(exchange.iter().all(|e| *e == [0.0, 0.0]));
    }

    /// A fully covered ΩΛ node with no open link (inside a solid) leaves at the solid's equilibrium,
    /// f^eq(ρ, u_s): the fluid inside a solid moves with it (what keeps free grains stable). With every link open
    /// and the solid at rest it is pure bounce-back, f_i ← f_ī (the rest population kept), whatever τ.
    #[test]
    fn lambda_operator_at_full_cover_moves_with_the_solid_or_bounces_back(
        f in node_populations(), tau in tau(), magic in fluid_choice(), u_s in velocity(),
    ) {
        let params = lambda_params(tau, Weighting::SolidFraction, [0.0; 2], magic);
        let tol = ROUNDOFF * scale(&f);
        let mut g = f;
        let mut ex = [[0.0; 2]; 1];
        psm_collide_links(&mut g, &params, &[SolidShare { fraction: 1.0, velocity: u_s , wall_gradient: Default::default() }], 0, &mut ex);
        let want = equilibrium(density(&f), u_s);
        prop_assert!(max_abs_diff(&g, &want) <= tol, "{g:?} vs {want:?}");
        let mut h = f;
        psm_collide_links(&mut h, &params, &[SolidShare { fraction: 1.0, velocity: [0.0; 2], wall_gradient: Default::default() }], ALL_LINKS_OPEN, &mut ex);
        // The rest population gets the mass that remains, ρ − Σ_{i≠0} f_ī = f₀ up to roundoff.
        for i in 0..Q {
            prop_assert!((h[i] - f[OPPOSITE[i]]).abs() <= tol, "direction {i}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// A whole step with ΩΛ at the covered nodes (open links from the coverage, the obstacles and the sides)
    /// equals the reference step, in f64 and f32, on random lattices with random coverage (fractions often
    /// exactly 1, and sums past 1, so fully covered nodes with every mix of open links occur) and TRT or BGK.
    #[test]
    fn lambda_step_matches_the_reference(nx in 1usize..=12, ny in 1usize..=12, seed in any::<u64>(), bgk in any::<bool>()) {
        let mut p = random_trt_problem(nx, ny, seed, 0.1, 0.5);
        p.lambda = true;
        if bgk {
            p.magic = None;
        }
        compare_steps::<f64>(&p, true, ORACLE)?;
        compare_steps::<f32>(&p, true, ORACLE_F32)?;
    }

    /// ΩΛ updated as several bands (as threads do) is bitwise the one-band update, exchange included.
    #[test]
    fn lambda_bands_are_independent(
        nx in 1usize..=12, ny in 1usize..=12, seed in any::<u64>(),
        cuts in prop::collection::vec(0usize..=12, 0..4),
    ) {
        let mut p = random_trt_problem(nx, ny, seed, 0.1, 0.5);
        p.lambda = true;
        let mut cuts: Vec<usize> = cuts.into_iter().map(|c| c.min(ny)).collect();
        cuts.sort_unstable();
        let (one, ex1) = kernel_step::<f64>(&p, &[], true);
        let (many, ex2) = kernel_step::<f64>(&p, &cuts, true);
        for (a, b) in one.iter().zip(&many) {
            prop_assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits));
        }
        prop_assert_eq!(
            ex1.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>(),
            ex2.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
    }
}

// ---------------------------------------------------------------------------------------------------------
// Moving walls (Ladd's correction) and velocity profiles on Zou–He sides
// ---------------------------------------------------------------------------------------------------------

/// A random problem (TRT or BGK, coverage with ΩΛ or Ω₁) whose non-periodic sides are, at random, also moving
/// walls (tangential velocity) and velocity-profile sides (a random velocity per node).
fn random_problem_with_moving_walls(nx: usize, ny: usize, seed: u64) -> Problem {
    let mut p = random_trt_problem(nx, ny, seed, 0.1, 0.3);
    let mut rng = SplitMix(seed ^ 0x4D4F_5649_4E47);
    p.lambda = rng.chance(0.5);
    if rng.chance(0.3) {
        p.magic = None;
    }
    let mut profiles = reference::Profiles::default();
    for side in [Side::West, Side::East, Side::South, Side::North] {
        let cond = match side {
            Side::West => &mut p.bc.west,
            Side::East => &mut p.bc.east,
            Side::South => &mut p.bc.south,
            Side::North => &mut p.bc.north,
        };
        if *cond == SideCondition::Periodic {
            continue;
        }
        let along_y = matches!(side, Side::West | Side::East);
        match rng.below(3) {
            0 => {
                let v = rng.range(-0.1, 0.1);
                *cond = SideCondition::MovingWall {
                    velocity: if along_y { [0.0, v] } else { [v, 0.0] },
                };
            }
            1 => {
                *cond = SideCondition::VelocityProfile;
                let n = if along_y { ny } else { nx };
                let values: Vec<[f64; 2]> = (0..n).map(|_| rng.velocity()).collect();
                match side {
                    Side::West => profiles.west = values,
                    Side::East => profiles.east = values,
                    Side::South => profiles.south = values,
                    Side::North => profiles.north = values,
                }
            }
            _ => {}
        }
    }
    assert_eq!(p.bc.validate(), Ok(()));
    p.profiles = profiles;
    p
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Steps with moving walls and velocity-profile sides (and their corners with every other kind of side)
    /// equal the reference step, which applies Ladd's correction after plain bounce-back and closes profile
    /// sides with each node's own velocity; f64 and f32.
    #[test]
    fn moving_walls_and_velocity_profiles_match_the_reference(
        nx in 1usize..=12, ny in 1usize..=12, seed in any::<u64>(),
    ) {
        let p = random_problem_with_moving_walls(nx, ny, seed);
        compare_steps::<f64>(&p, true, ORACLE)?;
        compare_steps::<f32>(&p, true, ORACLE_F32)?;
    }

    /// Every fluid node of a profile side that is not a corner with another Zou–He side leaves the gather with
    /// exactly its own prescribed velocity, and the node next to a moving wall at rest gains nothing.
    #[test]
    fn a_profile_side_imposes_each_nodes_velocity(nx in 3usize..=12, ny in 3usize..=12, seed in any::<u64>()) {
        let mut rng = SplitMix(seed);
        let mut p = random_problem(nx, ny, seed, 0.0, 0.0);
        p.bc = Boundaries {
            west: SideCondition::VelocityProfile,
            east: SideCondition::Pressure { density: 1.0 },
            south: SideCondition::MovingWall { velocity: [0.0, 0.0] },
            north: SideCondition::Wall,
        };
        let profile: Vec<[f64; 2]> = (0..ny).map(|_| rng.velocity()).collect();
        let profiles = SideProfiles { west: &profile, east: &[], south: &[], north: &[] };
        prop_assert_eq!(profiles.validate(&p.bc, nx, ny), Ok(()));
        let shape = LatticeShape::for_type::<f64>(nx, ny).expect("small lattice");
        let flags = vec![FLUID; shape.nodes()];
        let src = to_buffer::<f64>(&shape, &p.lattice.f);
        for (y, want) in profile.iter().enumerate().take(ny - 1).skip(1) {
            let g = gather_node(&shape, &src, &p.bc, &profiles, &flags, 0, y);
            let (rho, j) = (density(&g), momentum(&g));
            for a in 0..2 {
                prop_assert!((j[a] - rho * want[a]).abs() <= ROUNDOFF * scale(&g), "y {y} axis {a}");
            }
        }
        // A moving wall at rest is a wall.
        for x in 1..nx - 1 {
            let g = gather_node(&shape, &src, &p.bc, &profiles, &flags, x, 0);
            let mut q = p.clone();
            q.bc.south = SideCondition::Wall;
            let h = gather_node(&shape, &src, &q.bc, &profiles, &flags, x, 0);
            prop_assert_eq!(g.map(f64::to_bits), h.map(f64::to_bits));
        }
    }
}

/// Profiles of the wrong length or with bad values, and moving walls with a normal velocity, are refused.
#[test]
fn bad_profiles_and_wall_velocities_are_refused() {
    use lbdem_kernels::fluid::boundary::BoundaryError;
    let bc = Boundaries {
        west: SideCondition::VelocityProfile,
        east: SideCondition::Pressure { density: 1.0 },
        south: SideCondition::Wall,
        north: SideCondition::MovingWall {
            velocity: [0.05, 0.0],
        },
    };
    assert_eq!(bc.validate(), Ok(()));
    let short = [[0.0; 2]; 3];
    let ok = [[0.01, 0.0]; 4];
    let nan = [[0.0, 0.0], [f64::NAN, 0.0], [0.0; 2], [0.0; 2]];
    let fast = [[0.0, 0.0], [1.0, 0.0], [0.0; 2], [0.0; 2]];
    fn with(w: &[[f64; 2]]) -> SideProfiles<'_, f64> {
        SideProfiles {
            west: w,
            east: &[],
            south: &[],
            north: &[],
        }
    }
    assert_eq!(
        with(&short).validate(&bc, 5, 4),
        Err(BoundaryError::ProfileLength(Side::West))
    );
    assert_eq!(with(&ok).validate(&bc, 5, 4), Ok(()));
    assert_eq!(
        with(&nan).validate(&bc, 5, 4),
        Err(BoundaryError::BadVelocity(Side::West))
    );
    assert_eq!(
        with(&fast).validate(&bc, 5, 4),
        Err(BoundaryError::BadVelocity(Side::West))
    );
    let normal = Boundaries {
        north: SideCondition::MovingWall {
            velocity: [0.0, 0.01],
        },
        ..bc
    };
    assert_eq!(
        normal.validate(),
        Err(BoundaryError::WallVelocityNotTangential(Side::North))
    );
}

// ---------------------------------------------------------------------------------------------------------
// The batched partially-saturated collision (issue 13)
// ---------------------------------------------------------------------------------------------------------

/// The solid operators, in the order `random_covered_list` draws them from.
const OPERATORS: [SolidOperator; 5] = [
    SolidOperator::NonEquilibriumBounceBack,
    SolidOperator::Superposition,
    SolidOperator::MovingWallBounceBack,
    SolidOperator::LinearizedNonEquilibriumBounceBack,
    SolidOperator::LambdaConsistent,
];

/// A random covered list: parameters (operator, BGK or TRT, forced or not, weighting, τ) and per node the
/// gathered populations (`None` for a node the caller skips), its shares (mostly one, as in the coupled
/// scenes; sometimes none, two or three; fractions exactly 0 or 1 now and then, within ΩΛ's full-cover gap,
/// or NaN) and its open links.
#[allow(clippy::type_complexity)]
fn random_covered_list(
    seed: u64,
) -> (
    PsmParams<f64>,
    Vec<Option<[f64; Q]>>,
    Vec<u32>,
    Vec<SolidShare<f64>>,
    Vec<OpenLinks>,
) {
    let mut rng = SplitMix(seed);
    let solid = OPERATORS[rng.below(OPERATORS.len())];
    let collision = if rng.chance(0.5) {
        Collision::Bgk
    } else {
        Collision::Trt(Trt::new(rng.range(0.05, 0.5)).expect("valid magic parameter"))
    };
    let force = if rng.chance(0.5) {
        [0.0; 2]
    } else {
        [rng.range(-1e-3, 1e-3), rng.range(-1e-3, 1e-3)]
    };
    let weighting = if rng.chance(0.5) {
        Weighting::NobleTorczynski
    } else {
        Weighting::SolidFraction
    };
    let params = PsmParams {
        tau: rng.range(0.51, 2.0),
        weighting,
        solid,
        force,
        collision,
        lambda: Default::default(),
    };
    let n = rng.below(60);
    let (mut f, mut offsets, mut shares, mut links) =
        (Vec::new(), vec![7u32], Vec::new(), Vec::new());
    // Absolute share indices start at 7 (a band's list starts in the middle of the lattice's).
    shares.extend((0..7).map(|_| SolidShare::default()));
    for _ in 0..n {
        f.push((!rng.chance(0.1)).then(|| rng.populations()));
        let count = match rng.below(10) {
            0 => 0,
            1 => 2,
            2 => 3,
            _ => 1,
        };
        for _ in 0..count {
            let fraction = match rng.below(12) {
                0 => 1.0 - rng.range(0.0, 2e-3),
                1 => f64::NAN,
                _ => rng.fraction(),
            };
            shares.push(SolidShare {
                fraction,
                velocity: rng.velocity(),
                wall_gradient: Default::default(),
            });
        }
        offsets.push(shares.len() as u32);
        links.push(if rng.chance(0.3) {
            ALL_LINKS_OPEN
        } else {
            (rng.next() as OpenLinks) & ALL_LINKS_OPEN
        });
    }
    (params, f, offsets, shares, links)
}

/// [`collide_covered_list`] (batched) against [`psm_collide_links`] node by node, in precision `T`: the same
/// bits for every population and every exchange entry, skipped nodes' entries untouched, each node stored once.
fn check_batched<T: Real>(seed: u64) -> Result<(), TestCaseError> {
    let (p, f, offsets, shares, links) = random_covered_list(seed);
    let params = PsmParams {
        tau: T::lit(p.tau),
        weighting: p.weighting,
        solid: p.solid,
        force: p.force.map(T::lit),
        collision: match p.collision {
            Collision::Bgk => Collision::Bgk,
            Collision::Trt(t) => Collision::Trt(Trt::new(T::lit(t.magic())).expect("valid")),
        },
        lambda: Default::default(),
    };
    let f: Vec<Option<[T; Q]>> = f.iter().map(|g| g.map(|g| g.map(T::lit))).collect();
    let shares: Vec<SolidShare<T>> = shares
        .iter()
        .map(|s| SolidShare {
            fraction: T::lit(s.fraction),
            velocity: s.velocity.map(T::lit),
            wall_gradient: Default::default(),
        })
        .collect();
    let first = offsets[0] as usize;
    let sentinel = [T::lit(123.0); 2];
    let total = shares.len() - first;
    // Node by node.
    let mut want_ex = vec![sentinel; total];
    let mut want: Vec<Option<[T; Q]>> = vec![None; f.len()];
    for k in 0..f.len() {
        if let Some(mut g) = f[k] {
            let (a, b) = (offsets[k] as usize, offsets[k + 1] as usize);
            psm_collide_links(
                &mut g,
                &params,
                &shares[a..b],
                links[k],
                &mut want_ex[a - first..b - first],
            );
            want[k] = Some(g);
        }
    }
    // Batched.
    let mut got_ex = vec![sentinel; total];
    let mut got: Vec<Option<[T; Q]>> = vec![None; f.len()];
    let mut stores = vec![0usize; f.len()];
    collide_covered_list(
        &params,
        &offsets,
        &shares,
        &links,
        &mut got_ex,
        &mut (),
        |_, k| f[k],
        |_, k, g| {
            got[k] = Some(g);
            stores[k] += 1;
        },
    );
    let bits = |v: &Option<[T; Q]>| v.map(|g| g.map(|x| x.to_f64_exact().to_bits()));
    for k in 0..f.len() {
        prop_assert_eq!(bits(&got[k]), bits(&want[k]), "node {} of {:?}", k, p.solid);
        prop_assert_eq!(stores[k], usize::from(f[k].is_some()));
    }
    let ex_bits = |v: &[[T; 2]]| {
        v.iter()
            .flatten()
            .map(|x| x.to_f64_exact().to_bits())
            .collect::<Vec<_>>()
    };
    prop_assert_eq!(ex_bits(&got_ex), ex_bits(&want_ex));
    Ok(())
}

/// [`plan_covered_row`] and [`collide_planned_row`] (the in-place covered nodes of one AA pass row, grouped by
/// kernel, gathered and scattered plane by plane in batches of eight) against node by node [`load_from_rows`],
/// [`psm_collide_links`], [`store_in_rows`], in precision `T`, either AA step: the same bits for every slot of
/// the row and every exchange entry; special nodes (`own` false) and their entries untouched. Half the cases
/// give long stretches of nodes of one batch kernel (fully covered, or one partial fraction) in consecutive
/// columns, with gaps, edge columns (where the scatter step wraps) and skipped nodes between them. Also: the
/// plan lists every node with `own(k)` once, grouped as [`PLAN_GROUPS`] says, each group increasing.
fn check_row<T: Real>(seed: u64) -> Result<(), TestCaseError> {
    let (p, _, offsets, mut shares, links) = random_covered_list(seed);
    let mut rng = SplitMix(seed ^ 0x5EED);
    let n = links.len();
    if rng.chance(0.5) {
        // Stretches of one kernel: every single share of a stretch fully covered, or one fraction.
        let mut k = 0;
        while k < n {
            let len = 1 + rng.below(20);
            let frac = if rng.chance(0.5) {
                1.0
            } else {
                rng.range(0.05, 0.95)
            };
            for j in k..(k + len).min(n) {
                let (a, b) = (offsets[j] as usize, offsets[j + 1] as usize);
                if b == a + 1 && !rng.chance(0.05) {
                    shares[a].fraction = frac;
                }
            }
            k += len;
        }
    }
    // Columns: increasing, mostly consecutive, from 0 or 1; the row one or two columns longer.
    let mut columns = Vec::with_capacity(n);
    let mut x = rng.below(2) as u32;
    for _ in 0..n {
        columns.push(x);
        x += if rng.chance(0.85) {
            1
        } else {
            2 + rng.below(3) as u32
        };
    }
    let nx = (x as usize + rng.below(2)).max(1);
    let own: Vec<bool> = (0..n).map(|_| !rng.chance(0.08)).collect();
    let step = if rng.chance(0.5) {
        AaStep::Local
    } else {
        AaStep::Scatter
    };
    let params = PsmParams {
        tau: T::lit(p.tau),
        weighting: p.weighting,
        solid: p.solid,
        force: p.force.map(T::lit),
        collision: match p.collision {
            Collision::Bgk => Collision::Bgk,
            Collision::Trt(t) => Collision::Trt(Trt::new(T::lit(t.magic())).expect("valid")),
        },
        lambda: Default::default(),
    };
    let shares: Vec<SolidShare<T>> = shares
        .iter()
        .map(|s| SolidShare {
            fraction: T::lit(s.fraction),
            velocity: s.velocity.map(T::lit),
            wall_gradient: Default::default(),
        })
        .collect();
    // A row of populations near equilibrium, plane by plane.
    let mut planes: Vec<Vec<T>> = (0..Q).map(|_| Vec::with_capacity(nx)).collect();
    for _ in 0..nx {
        let f = rng.populations();
        for q in 0..Q {
            planes[q].push(T::lit(f[q]));
        }
    }
    let first = offsets[0] as usize;
    let sentinel = [T::lit(123.0); 2];
    let total = shares.len() - first;
    fn as_row<T>(v: &mut [Vec<T>]) -> Vec<[&mut [T]; Q]> {
        let mut it = v.iter_mut();
        vec![std::array::from_fn(|_| {
            it.next().expect("nine planes").as_mut_slice()
        })]
    }
    // Node by node.
    let mut want = planes.clone();
    let mut want_ex = vec![sentinel; total];
    {
        let mut rows = as_row(&mut want);
        for k in 0..n {
            if !own[k] {
                continue;
            }
            let (a, b) = (offsets[k] as usize, offsets[k + 1] as usize);
            let mut f = load_from_rows(&rows, step, 0, columns[k] as usize, 0);
            psm_collide_links(
                &mut f,
                &params,
                &shares[a..b],
                links[k],
                &mut want_ex[a - first..b - first],
            );
            store_in_rows(&mut rows, step, 0, columns[k] as usize, 0, &f);
        }
    }
    // The plan.
    let mut plan = vec![u32::MAX; n];
    let counts = plan_covered_row(&params, |k| own[k], &offsets, &shares, &mut plan);
    let planned: usize = counts.iter().map(|&c| c as usize).sum();
    prop_assert_eq!(planned, own.iter().filter(|&&o| o).count());
    let mut listed = plan[..planned].to_vec();
    let mut at = 0;
    for (group, &count) in PLAN_GROUPS.iter().zip(&counts) {
        let nodes = &plan[at..at + count as usize];
        at += count as usize;
        prop_assert!(
            nodes.windows(2).all(|w| w[0] < w[1]),
            "each group increasing"
        );
        for &k in nodes {
            let (a, b) = (
                offsets[k as usize] as usize,
                offsets[k as usize + 1] as usize,
            );
            prop_assert_eq!(lane_class(&params, &shares[a..b]), *group);
        }
    }
    listed.sort_unstable();
    let own_nodes: Vec<u32> = (0..n as u32).filter(|&k| own[k as usize]).collect();
    prop_assert_eq!(listed, own_nodes);
    // The row pass.
    let mut got = planes.clone();
    let mut got_ex = vec![sentinel; total];
    {
        let mut rows = as_row(&mut got);
        collide_planned_row(
            &params,
            &mut rows[0],
            step,
            &columns,
            &plan[..planned],
            counts,
            &offsets,
            &shares,
            &links,
            &mut got_ex,
        );
    }
    let bits = |v: T| v.to_f64_exact().to_bits();
    for q in 0..Q {
        for x in 0..nx {
            prop_assert_eq!(
                bits(got[q][x]),
                bits(want[q][x]),
                "plane {} column {} ({:?}, {:?})",
                q,
                x,
                p.solid,
                step
            );
        }
    }
    for (g, w) in got_ex.iter().zip(&want_ex) {
        prop_assert_eq!(g.map(bits), w.map(bits));
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// The covered nodes of an in-place pass row planned by `plan_covered_row` and collided by
    /// `collide_planned_row` are bitwise the node kernel
    /// run node by node in place, for every operator, BGK and TRT, with and without force, both weightings,
    /// both AA steps, in f64 and f32 (exact claim: the same functions on the same values).
    #[test]
    fn covered_row_pass_is_bitwise_the_node_kernel_in_place(seed in any::<u64>()) {
        check_row::<f64>(seed)?;
        check_row::<f32>(seed)?;
    }

    /// The batched collision of a covered list (the lanes of `psm_collide_lanes` for the nodes with one
    /// share, the node kernel for the others) is bitwise the node kernel for every node, every operator, BGK
    /// and TRT, with and without force, both weightings, in f64 and f32. Exact claim: same functions on the
    /// same values in the same order; only the order in which nodes are handed back differs.
    #[test]
    fn batched_covered_collision_is_bitwise_the_node_kernel(seed in any::<u64>()) {
        check_batched::<f64>(seed)?;
        check_batched::<f32>(seed)?;
    }
}

proptest! {
    /// ΩΛ's wall gradient ([`lbdem_kernels::fluid::collide::wall_gradient`]) of a linear density field
    /// ρ = ρ₀ + g·(x − x₀) sampled at the axis neighbours that are given: along an axis with both neighbours or
    /// one, the difference is exact for a linear field, so the result is (t·g') t with g' the gradient whose
    /// components are zero along axes with no neighbour and t ⟂ the normal; it has no normal component; with
    /// no normal it is zero. Tolerance: ρ ≈ 1 and differences of a few such values carry a few ulp of 1,
    /// 1e-15.
    #[test]
    fn wall_gradient_is_the_tangential_part_of_a_linear_density_field(
        rho0 in 0.8f64..1.2, g in [-1e-2f64..1e-2, -1e-2f64..1e-2], angle in 0.0f64..std::f64::consts::TAU,
        mask in 0u8..16, no_normal in any::<bool>(),
    ) {
        use lbdem_kernels::fluid::collide::wall_gradient;
        let dirs = [[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]];
        let neighbours: [Option<f64>; 4] = std::array::from_fn(|i| {
            (mask & (1 << i) != 0).then(|| rho0 + g[0] * dirs[i][0] + g[1] * dirs[i][1])
        });
        let normal = if no_normal { [0.0; 2] } else { [angle.cos(), angle.sin()] };
        let got = wall_gradient(rho0, neighbours, normal);
        let seen = [
            if mask & 0b0101 != 0 { g[0] } else { 0.0 },
            if mask & 0b1010 != 0 { g[1] } else { 0.0 },
        ];
        let t = [-normal[1], normal[0]];
        let along = t[0] * seen[0] + t[1] * seen[1];
        let want = [along * t[0], along * t[1]];
        prop_assert!((got[0] - want[0]).abs() <= 1e-15 && (got[1] - want[1]).abs() <= 1e-15, "{got:?} vs {want:?}");
        prop_assert!((got[0] * normal[0] + got[1] * normal[1]).abs() <= 1e-15);
    }
}
