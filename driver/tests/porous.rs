//! Fixed-solid validation of the partially-saturated method (dissertation §5.4–5.5; `docs/references.md`
//! §1, §6.3, §6.4): Stokes drag of a periodic square array of cylinders against Sangani & Acrivos (S&A), the
//! pressure drop against Reynolds number, Darcy's law and permeability against porosity for a porous slab
//! between Zou–He pressure boundaries.
//!
//! These are the fast variants (each a few tenths of a second to ~2 s in the test profile). The
//! full-resolution variants (c = 0.2…0.6 at l = 20/40/80, Re up to ~100, 200-disc slabs) are printed by
//! `cargo run --release -p lbdem --example porous_validation -- --full`; the default example run prints the
//! table of exactly the cases asserted here.
use lbdem::kinds::cylinder_array::{solve_array, ArrayCase};
use lbdem::kinds::porous_flow::{darcy_fit, fitted_kozeny_constant, solve_porous, PorousCase};
use lbdem_kernels::fluid::collide::{Collision, LambdaTerms, SolidOperator};

/// The fast porous-slab case used below: `columns` × `rows` discs of diameter `d` at pitch `pitch`, τ = 0.8,
/// Ω₁, periodic north/south, half a pitch of free fluid before and after the array.
fn slab(columns: usize, rows: usize, pitch: usize, d: f64, density_drop: f64) -> PorousCase {
    PorousCase {
        columns,
        rows,
        pitch,
        diameter: d,
        buffer: pitch / 2,
        jitter: 0.0,
        seed: 1,
        walls: false,
        tau: 0.8,
        solid_operator: SolidOperator::NonEquilibriumBounceBack,
        lambda_terms: LambdaTerms::default(),
        collision: Collision::Bgk,
        density_drop,
        steady_tolerance: 1e-8,
        check_interval: 100,
        max_steps: 100_000,
    }
}

/// Diameter giving solid fraction c at pitch l: D = 2 l √(c/π).
fn diameter(pitch: usize, c: f64) -> f64 {
    2.0 * pitch as f64 * (c / std::f64::consts::PI).sqrt()
}

#[test]
fn periodic_array_drag_matches_sangani_acrivos_and_improves_with_resolution() {
    // τ = 0.8 is inside the [0.6, 0.9] band of docs/references.md §1.5, whose in-house PSM results (same method, Ω₁,
    // sub-cell fractions) give −5.0 %/−5.8 % at l = 20 and −1.1 %/−1.4 % at l = 40 for c = 0.2/0.4 (τ = 0.875).
    for c in [0.2, 0.4] {
        let mut errors = Vec::new();
        for l in [20usize, 40] {
            let case = ArrayCase::stokes(l, c, 0.8);
            let r = solve_array::<f64>(&case).expect("healthy run");
            assert!(
                r.steady,
                "c = {c}, l = {l}: not steady after {} steps",
                r.steps
            );
            let err = r.drag_error.expect("tabulated c");
            eprintln!(
                "c = {c}, l = {l} (D = {:.1}, gap {:.1}): F/(muU) = {:.2} vs S&A {:.2}: {:+.2} %, {} steps, \
                 drift {:.2e}/step",
                r.diameter,
                r.gap,
                r.drag,
                r.reference_drag.unwrap(),
                100.0 * err,
                r.steps,
                r.drift_per_step
            );
            // Tolerances (docs/references.md §1.5): ≤ 2 % at ≥ 10 gap nodes (l = 40: gaps 19.8 and 11.4 nodes); at
            // l = 20 the gaps are 9.9 (c = 0.2, but only D = 10 across the disc) and 5.7 nodes, the "≈ 5 gap
            // nodes" class with ≤ 6 %.
            let tol = if l >= 40 { 0.02 } else { 0.06 };
            assert!(
                err.abs() <= tol,
                "c = {c}, l = {l}: drag error {:+.2} % exceeds {:.0} %",
                100.0 * err,
                100.0 * tol
            );
            // Momentum balance: the disc receives the whole body force the fluid gets, G Σ (1 − B), and
            // B ≤ ε at partly covered nodes, so the PSM force over G l² is at least 1 − c; the excess comes
            // from the one-node perimeter band only (a few % at these sizes).
            assert!(
                r.solid_force_ratio >= 1.0 - c - 1e-9 && r.solid_force_ratio <= 1.0 - c + 0.05,
                "c = {c}, l = {l}: PSM force / (G l²) = {:.4}, expected just above 1 − c",
                r.solid_force_ratio
            );
            // Periodic, body-force driven: Ω₁ conserves mass to roundoff.
            assert!(
                r.mass_change.abs() < 1e-10,
                "mass change {:e}",
                r.mass_change
            );
            errors.push(err.abs());
        }
        // §1.5: doubling the resolution divides the error by 3–5; require at least 2.
        assert!(
            errors[1] < 0.5 * errors[0],
            "c = {c}: error did not fall with resolution: {errors:?}"
        );
    }
}

#[test]
fn moving_wall_operator_drag_matches_sangani_acrivos() {
    // Ω₃ (Owen et al. 2011 eq. 33) is the operator the coupled scenes use: it is bounce-back at full cover, so
    // it stays bounded in open systems (driver/tests/determinism.rs) where Ω₁ piles up mass. Measured at
    // τ = 0.8: +0.18 %/+1.29 % (l = 20) and +0.78 %/+1.98 % (l = 40) for c = 0.2/0.4: it sits slightly above
    // S&A (its effective solid edge lies a little further out than Ω₁'s) and does not converge further
    // between l = 20 and 40, so one tolerance for both: the ≤ 2 % class of docs/references.md §1.5 plus 0.5 % margin
    // for that offset.
    for c in [0.2, 0.4] {
        for l in [20usize, 40] {
            let mut case = ArrayCase::stokes(l, c, 0.8);
            case.solid_operator = SolidOperator::MovingWallBounceBack;
            let r = solve_array::<f64>(&case).expect("healthy run");
            assert!(r.steady, "c = {c}, l = {l}: not steady");
            let err = r.drag_error.expect("tabulated c");
            eprintln!(
                "Ω₃ c = {c}, l = {l}: F/(muU) = {:.2}: {:+.2} %",
                r.drag,
                100.0 * err
            );
            assert!(
                err.abs() <= 0.025,
                "Ω₃ c = {c}, l = {l}: drag error {:+.2} %",
                100.0 * err
            );
            assert!(
                r.mass_change.abs() < 1e-10,
                "mass change {:e}",
                r.mass_change
            );
        }
    }
}

#[test]
fn linearized_operator_drag_matches_sangani_acrivos_like_omega_1() {
    // Ω₁ₗ (the fracture scenes' operator) differs from Ω₁ only by O(Ma²) terms that carry no momentum, so in
    // Stokes flow its drag must meet Ω₁'s tolerance classes of docs/references.md §1.5 (≤ 6 % at l = 20, ≤ 2 % at
    // l = 40) and stay within 0.5 % of Ω₁'s drag (Ma ≈ 1e-3 here: the Ma² terms are ~1e-6 of the drag; 0.5 %
    // leaves room for their effect on the steady-state criterion).
    for c in [0.2, 0.4] {
        for l in [20usize, 40] {
            let mut case = ArrayCase::stokes(l, c, 0.8);
            case.solid_operator = SolidOperator::LinearizedNonEquilibriumBounceBack;
            let r = solve_array::<f64>(&case).expect("healthy run");
            let reference = solve_array::<f64>(&ArrayCase::stokes(l, c, 0.8)).expect("healthy run");
            assert!(r.steady, "c = {c}, l = {l}: not steady");
            let err = r.drag_error.expect("tabulated c");
            eprintln!(
                "Ω₁ₗ c = {c}, l = {l}: F/(muU) = {:.2}: {:+.2} % (Ω₁ {:.2})",
                r.drag,
                100.0 * err,
                reference.drag
            );
            let tol = if l >= 40 { 0.02 } else { 0.06 };
            assert!(
                err.abs() <= tol,
                "Ω₁ₗ c = {c}, l = {l}: drag error {:+.2} %",
                100.0 * err
            );
            assert!(
                (r.drag / reference.drag - 1.0).abs() < 0.005,
                "Ω₁ₗ {} vs Ω₁ {}",
                r.drag,
                reference.drag
            );
            assert!(
                r.mass_change.abs() < 1e-10,
                "mass change {:e}",
                r.mass_change
            );
        }
    }
}

#[test]
fn pressure_drop_falls_with_reynolds_and_meets_the_stokes_limit() {
    // Fig. 5.4 at c = 0.5: ∇P̄ = G l/(ρU²). One τ = 0.6 for all three points (the PSM drag depends on τ, so a
    // τ change would masquerade as inertia); U ≤ 0.011 keeps the gap Mach number near 0.1 at Re = 10. l = 40
    // gives 8.1 nodes across the gap.
    let (l, c) = (40usize, 0.5);
    let stokes = 532.55 * 2.0 * (c / std::f64::consts::PI).sqrt(); // F̄ D/l = 424.9 (docs/references.md §1.3)
    let mut last = f64::INFINITY;
    let mut products = Vec::new();
    for re in [0.01, 1.0, 10.0] {
        let case = ArrayCase::at_reynolds(l, c, re, 0.011, 0.6);
        let r = solve_array::<f64>(&case).expect("healthy run");
        assert!(r.steady, "Re = {re}: not steady after {} steps", r.steps);
        eprintln!(
            "Re target {re}: tau {:.4}, Re {:.4e}, grad P = {:.4e}, grad P * Re = {:.2} (Stokes {stokes:.1}), Ma {:.3}, \
             {} steps, drift {:.2e}/step",
            case.tau, r.reynolds, r.pressure_drop, r.pressure_drop_times_reynolds, r.max_mach, r.steps, r.drift_per_step
        );
        assert!(r.pressure_drop < last, "∇P̄ must fall as Re rises");
        last = r.pressure_drop;
        products.push(r.pressure_drop_times_reynolds);
    }
    // Stokes limit at Re ≤ 1: 8 gap nodes lies between the "≈ 5 nodes, ≤ 6 %" and "≥ 10 nodes, ≤ 2 %" classes
    // of docs/references.md §1.5; assert the 6 % bound.
    for p in &products[..2] {
        assert!(
            (p / stokes - 1.0).abs() < 0.06,
            "∇P̄·Re = {p:.2} vs Stokes limit {stokes:.1}"
        );
    }
    // The product is F̄ D/l: linear (Stokes) response makes it the same at Re = 0.01 and 1 up to the O(Re²)
    // inertial correction of a symmetric array (here < 0.5 %); at Re = 10 inertia raises the drag.
    assert!(
        (products[1] / products[0] - 1.0).abs() < 0.005,
        "{products:?}"
    );
    assert!(
        products[2] > products[1],
        "inertia must raise the drag: {products:?}"
    );
}

#[test]
fn darcy_flux_is_linear_in_the_pressure_gradient() {
    // 5 × 2 discs, c = 0.4 at pitch 24 (gap 6.9 nodes), four pressure drops with lattice density drops
    // 0.5–4 ‰.
    let d = diameter(24, 0.4);
    let runs: Vec<_> = [0.5e-3, 1e-3, 2e-3, 4e-3]
        .iter()
        .map(|&drho| {
            let r = solve_porous::<f64>(&slab(5, 2, 24, d, drho)).expect("healthy run");
            assert!(r.steady, "density drop {drho}: not steady");
            r
        })
        .collect();
    let (slope, intercept, r2, rel) = darcy_fit(&runs);
    eprintln!(
        "Darcy: slope {slope:.5e}, intercept {intercept:.3e} ({:.3e} of the largest flux), R² = {r2:.12}, Re ≤ {:.3e}, \
         covered density excess {:.3e}",
        rel,
        runs.last().unwrap().reynolds,
        runs.last().unwrap().covered_density_excess
    );
    // Deviations from Darcy come from inertia (relative size ~ Re ≤ 2e-2 here, and only at second order in a
    // symmetric array) and compressibility (~ Δρ ≤ 4e-3): the fitted line misses each point by ≲ 1e-2
    // relative, so 1 − R² ≲ 1e-4. R² ≥ 0.999 leaves a 10× margin; the intercept must be within 1 % of the
    // largest flux.
    assert!(r2 >= 0.999, "R² = {r2}");
    assert!(rel.abs() < 0.01, "intercept {rel:e} of the largest flux");
    // The permeability does not depend on the drive while Re ≪ 1 (docs/references.md §6.4).
    let k0 = runs[0].permeability;
    for r in &runs {
        assert!((r.permeability / k0 - 1.0).abs() < 0.01);
    }
    // Ω₁ in an open system: the density inside the discs must stay with the surrounding fluid (no
    // accumulation over these runs: within a tenth of the imposed drop).
    for r in &runs {
        assert!(
            r.covered_density_excess.abs() < 0.1,
            "{}",
            r.covered_density_excess
        );
    }
}

#[test]
fn permeability_rises_with_porosity_and_fits_kozeny_carman() {
    // Four disc sizes at pitch 30: n = 0.5, 0.6, 0.7, 0.8 (narrowest gaps 6.1–15.1 nodes), 6 × 1 discs
    // (periodic north/south), one small pressure drop.
    let pitch = 30;
    let runs: Vec<_> = [0.5, 0.4, 0.3, 0.2]
        .iter()
        .map(|&c| {
            let r = solve_porous::<f64>(&slab(6, 1, pitch, diameter(pitch, c), 1e-3))
                .expect("healthy run");
            assert!(r.steady);
            eprintln!(
                "n = {:.2}: D = {:.2}, gap {:.2}, k = {:.4e} (k/D² = {:.4e}), c_K = {:.3}, k vs S&A {:+.2} %",
                r.porosity,
                r.case.diameter,
                r.min_gap,
                r.permeability,
                r.permeability_over_d2,
                r.kozeny_constant,
                100.0 * r.sangani_acrivos_error.unwrap_or(f64::NAN)
            );
            // Regular array, periodic across: the interior is exactly S&A's square array; at ≥ 6 gap nodes and
            // τ = 0.8 the §1.5 class is ≤ 6 %; entrance regions are excluded by the interior-gradient fit.
            let e = r.sangani_acrivos_error.expect("tabulated c");
            assert!(e.abs() < 0.06, "n = {:.2}: k differs from S&A by {e:+.3}", r.porosity);
            r
        })
        .collect();
    for w in runs.windows(2) {
        assert!(
            w[1].permeability > w[0].permeability,
            "k must rise with porosity"
        );
    }
    let ck = fitted_kozeny_constant(&runs);
    eprintln!("fitted Kozeny constant c_K = {ck:.3}");
    // For square arrays S&A imply c_K = 10.6, 9.4, 9.4, 10.5 at n = 0.5, 0.6, 0.7, 0.8 (docs/references.md §6.3), i.e. a
    // geometric mean of 9.96; with the ≤ 6 % permeability error above the fit must lie within [8.8, 11.3].
    // (Carman's packed-bed value 5, or the dissertation's eq. 5.8 as printed, would be outside.)
    assert!((8.8..=11.3).contains(&ck), "fitted c_K = {ck}");
}

#[test]
fn omega1_mass_creep_into_covered_nodes_leaves_the_drag_unchanged() {
    // Ω₁ never relaxes the rest population of fully covered nodes, which keep gaining mass from the fluid
    // (total mass is conserved): the mean fluid density ρ_f falls slowly and U rises as 1/ρ_f. With μ = ρ_f ν the
    // dimensionless drag does not move. c = 0.6, l = 20 has the largest drift of the cases here.
    let mut case = ArrayCase::stokes(20, 0.6, 0.8);
    case.steady_tolerance = 1e-30; // run the step budget
    case.max_steps = 2_000;
    let early = solve_array::<f64>(&case).expect("healthy run");
    case.max_steps = 20_000;
    let late = solve_array::<f64>(&case).expect("healthy run");
    eprintln!(
        "rho_f {:.6} -> {:.6}, U {:.6e} -> {:.6e}, drag {:.4} -> {:.4}",
        early.fluid_density,
        late.fluid_density,
        early.superficial_velocity,
        late.superficial_velocity,
        early.drag,
        late.drag
    );
    // Measured: ρ_f 0.99944 → 0.99431, drag equal to 6 digits.
    assert!(late.fluid_density < early.fluid_density - 1e-3);
    assert!(late.mass_change.abs() < 1e-10);
    assert!((late.drag / early.drag - 1.0).abs() < 1e-4);
}

/// Full resolution (about 45 s in the test profile): `cargo test -p lbdem --test integration porous:: -- --ignored`.
#[test]
#[ignore]
fn full_resolution_drag_for_c_0_2_to_0_6() {
    // l = 80 puts ≥ 10 nodes across every gap (10.1 at c = 0.6): the ≤ 2 % class of docs/references.md §1.5. Measured
    // −0.16, −0.26, −0.21, −0.63, −1.41 % for c = 0.2…0.6; from l = 40 to 80 the error falls 4.3–6.4×.
    for c in [0.2, 0.3, 0.4, 0.5, 0.6] {
        let coarse = solve_array::<f64>(&ArrayCase::stokes(40, c, 0.8)).expect("healthy run");
        let fine = solve_array::<f64>(&ArrayCase::stokes(80, c, 0.8)).expect("healthy run");
        let (ec, ef) = (coarse.drag_error.unwrap(), fine.drag_error.unwrap());
        eprintln!(
            "c = {c}: l = 40 {:+.2} %, l = 80 {:+.2} %",
            100.0 * ec,
            100.0 * ef
        );
        assert!(fine.steady && coarse.steady);
        assert!(ef.abs() <= 0.02, "c = {c}: {ef}");
        assert!(ef.abs() < 0.5 * ec.abs(), "c = {c}: {ec} -> {ef}");
    }
}
