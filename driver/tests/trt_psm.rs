//! Acceptance of the τ-independent partially saturated method: TRT (Λ = 3/16) with the
//! ΩΛ solid operator and B = ε, on the periodic square array of cylinders against Sangani & Acrivos (1982)
//! and on a random pack of 100 discs, at τ ∈ {0.55, 0.6, 0.8, 1.2, 2.0}.
//!
//! Fast variants run here; the full l = 40 grid over every τ and c is `#[ignore]`d (and printed, with every
//! other operator next to it, by `cargo run --release -p lbdem --example tau_table`).
use crate::common::psm_cases;
use crate::common::wall_cases::channel_offset;

use lbdem_kernels::fluid::collide::{LambdaTerms, Weighting};
use psm_cases::{pack_permeability, random_pack, square_array, square_array_at, Method, TAUS};

/// The spread (max − min) of a list.
fn spread(v: &[f64]) -> f64 {
    let lo = v.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = v.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    hi - lo
}

/// Drag errors of the square array at every τ of the table.
fn errors(cell: usize, c: f64, method: Method) -> Vec<f64> {
    TAUS.iter()
        .map(|&tau| {
            let r = square_array(cell, c, tau, method);
            assert!(r.steady, "l = {cell}, c = {c}, τ = {tau}: not steady");
            // The solid receives the body force of the fluid, G Σ (1 − B) with B = ε here, to the steady
            // tolerance: exactly the share counted from the coverage map. That share is 1 − c but for ΩΛ's
            // nodes covered to 95 % or more, which are fully covered and take no body force (measured: 1.6e-4
            // below 1 − c at l = 20, c = 0.2, i.e. 0.064 of a node; 1e-3 is 0.4 of a node at l = 20 and 1.6 at
            // l = 40, so a share miscounted by a whole node fails).
            assert!(
                (r.solid_force_ratio - r.fluid_force_share).abs() < 1e-6,
                "force ratio {} against the fluid's share {}",
                r.solid_force_ratio,
                r.fluid_force_share
            );
            assert!(
                r.fluid_force_share <= 1.0 - c + 1e-12 && r.fluid_force_share > 1.0 - c - 1e-3,
                "fluid share {} against 1 − c = {}",
                r.fluid_force_share,
                1.0 - c
            );
            r.error
        })
        .collect()
}

#[test]
fn square_array_drag_is_within_two_percent_at_l20_and_the_same_at_every_tau() {
    for c in [0.2, 0.4] {
        let e = errors(20, c, Method::LAMBDA);
        eprintln!(
            "l = 20, c = {c}: {:?} %",
            e.iter().map(|x| 100.0 * x).collect::<Vec<_>>()
        );
        // Issue 11: within 2 % of S&A at l = 20 for c ≤ 0.4. Held out of κ's calibration (l = 30, see
        // LAMBDA_FRICTION); measured −1.17 % and +0.63 %. Sangani & Acrivos's table is the independent oracle.
        for (tau, err) in TAUS.iter().zip(&e) {
            assert!(
                err.abs() <= 0.02,
                "c = {c}, τ = {tau}: {:+.2} %",
                100.0 * err
            );
        }
        // τ-independence: the steady TRT solution depends on τ only through ν and Λ; what remains is the
        // O(Re², δρ) part of a Stokes flow at Re ≤ 0.01, δρ ≤ 1e-5, and the 1e-9 steady tolerance: measured
        // spread < 1e-7. 2e-5 leaves room and is 700 times below the smallest BGK spread (1.4 %).
        assert!(spread(&e) < 2e-5, "c = {c}: spread {:.3e}", spread(&e));
    }
}

#[test]
fn square_array_drag_at_l40_is_within_two_percent() {
    // The l = 40 column of the issue at one τ (the spread over τ is asserted at l = 20 above and over the whole
    // grid in the ignored tests below). Held out of κ's calibration (l = 30); measured +0.65 / +1.46 / +1.28 %.
    // Tolerance 2 %: the error of a held-out resolution. At fixed κ the S&A error moves by up to 1.6 points
    // between l = 30 and l = 40 (c = 0.6: −0.28 → +1.28 %; 1.9 points with ΩΛ's earlier full-cover gap) with how the disc's edge cells fall on the
    // lattice, so 2 % is what a κ fitted at another resolution supports. The 1 % target at l = 40 is
    // NOT met for c ≥ 0.4 (the ignored test below states it and fails); it was met only while κ was fitted to
    // this very case.
    for c in [0.2, 0.4, 0.6] {
        let r = square_array(40, c, 0.8, Method::LAMBDA);
        assert!(r.steady);
        eprintln!("l = 40, c = {c}: {:+.3} %", 100.0 * r.error);
        assert!(r.error.abs() <= 0.02, "c = {c}: {:+.2} %", 100.0 * r.error);
    }
}

#[test]
fn square_array_drag_at_l40_moves_less_than_two_points_with_the_placement() {
    // The same array (c = 0.6, l = 40, the narrowest gaps: 5 nodes) with the cylinder's centre moved along the
    // diagonal by 0, ¼ and ½ node: the exact drag is unchanged, only how the disc's edge falls on the lattice
    // moves. ΩΛ's partly covered cells carry the fraction ε only, not the shape of the cut, so the drag moves:
    // measured +1.28 / +0.60 / +0.41 % (0.87 points; over five placements +0.04 … +1.51 %, 1.47 points,
    // `kappa_calibration -- --scatter`; with ΩΛ's earlier full-cover gap of 1e-3: +1.57 / +0.70 / −0.86 %,
    // 2.43 points). Bound 2 points: the five placements' span with a third of margin; it fails if the
    // partial-cell rule grows more placement-sensitive (as it was with the earlier gap). Each placement stays within the 2 % of the held-out test above.
    let errors: Vec<f64> = [0.0, 0.25, 0.5]
        .iter()
        .map(|&o| {
            let r = square_array_at(40, 0.6, 0.8, Method::LAMBDA, [o, o]);
            assert!(r.steady, "offset {o}: not steady");
            r.error
        })
        .collect();
    eprintln!("c = 0.6, l = 40, offsets 0 / ¼ / ½: {errors:.4?}");
    assert!(
        spread(&errors) <= 0.02,
        "span {:.2} points",
        100.0 * spread(&errors)
    );
    assert!(
        spread(&errors) >= 1e-3,
        "placement has no effect: the offset is not applied"
    );
    for e in &errors {
        assert!(e.abs() <= 0.02, "{:+.2} %", 100.0 * e);
    }
}

#[test]
fn cut_walls_sit_within_a_tenth_of_a_spacing_under_a_body_force_and_under_a_pressure_gradient() {
    // Plane channels whose slab faces cut a row of cells at ε = 0.7 (below) and 0.6 (above), H = 10.7, τ = 1.5:
    // driven by a body force along the whole channel, and over 80 of 320 columns fed by an exact-walled wide
    // channel (three quarters of the drive a pressure gradient). Against runs with walls on cell faces, which
    // half-way bounce-back puts exactly at Λ = 3/16 (`common::wall_cases`). Measured at κ = 1.21 (the example
    // `wall_offsets` at τ = 0.8, and here at 1.5: the same to 1e-4): +0.054 (body force) and +0.018 (pressure)
    // spacing; the friction κ thickens every cut wall, and under a pressure gradient the cut cells pass too much fluid
    // (+0.0005 and −0.047 with κ = 0, README "What κ compensates"). Bound 0.1 spacing: issue 11's tolerance for
    // where a solid's effective surface may sit; it fails if κ doubles or the cut cells' answer to pressure gets
    // twice as bad. The drives must differ by 0.01 at least (measured 0.036): otherwise the section is not
    // pressure-driven and the test tests nothing. Steady to 1e-7 per 500 steps: the flux to ~1e-5, the offset to
    // ~1e-4 spacing (ΔQ/Q = 3 ΔH/H).
    let tau = 1.5;
    let body = channel_offset(15.2, 25.9, 320, 320, tau, 1e-7, LambdaTerms::FRICTION_ONLY);
    let pressure = channel_offset(15.2, 25.9, 80, 320, tau, 1e-7, LambdaTerms::FRICTION_ONLY);
    eprintln!("offset per wall: body force {body:+.4}, pressure-driven {pressure:+.4}");
    for (name, o) in [("body-force", body), ("pressure-driven", pressure)] {
        assert!(o.abs() <= 0.1, "{name} channel: wall {o:+.4} spacing off");
    }
    assert!(
        (body - pressure).abs() >= 0.01,
        "the two drives give the same wall ({body:+.4}, {pressure:+.4}): is the section pressure-driven?"
    );
}

#[test]
fn the_wall_pressure_form_answers_a_pressure_gradient_nearly_as_a_body_force() {
    // The channels of the test above under ΩΛ's wall-pressure form (the default: α = 2, κ = 0.5; the slabs'
    // normals given) and, at the same κ, without the force (α = 0): the force (ε_s/Σε) α B (1 − B/2) c_s² ∇ₜρ
    // at the cut cells closes half the gap between the two drives. Measured at τ = 1.5 (release): α = 0:
    // body force +0.0261, pressure-driven −0.0161 spacing, 0.042 apart; α = 2: +0.0261 / +0.0055, 0.021 apart
    // (ratio 0.49); α = 1 (half strength): 0.032 apart (0.75). What is left is the section's entrance (over 80
    // columns the α of the unshaped force that closes it is 2.42, over 320 it is 2.05) and the shape's weaker
    // correction at ε = 0.6–0.7 (LAMBDA_PRESSURE). Bounds: every offset within issue 11's 0.1 spacing, and
    // the gap at most 0.6 of the gap without the force: it fails if the force is not applied or applied at
    // half strength.
    let tau = 1.5;
    let gap = |terms: LambdaTerms| {
        let body = channel_offset(15.2, 25.9, 320, 320, tau, 1e-7, terms);
        let pressure = channel_offset(15.2, 25.9, 80, 320, tau, 1e-7, terms);
        eprintln!(
            "{terms:?}, offset per wall: body force {body:+.4}, pressure-driven {pressure:+.4}"
        );
        for (name, o) in [("body-force", body), ("pressure-driven", pressure)] {
            assert!(o.abs() <= 0.1, "{name} channel: wall {o:+.4} spacing off");
        }
        (body - pressure).abs()
    };
    let with = gap(LambdaTerms::WALL_PRESSURE);
    let without = gap(LambdaTerms {
        pressure: 0.0,
        ..LambdaTerms::WALL_PRESSURE
    });
    assert!(
        with <= 0.6 * without,
        "the drives differ by {with:.4} spacing with the wall force, {without:.4} without"
    );
}

#[test]
fn the_wall_pressure_form_puts_the_arrays_within_one_percent_at_l40_and_two_at_l20() {
    // ΩΛ's wall-pressure form, the default (α = 2, κ = 0.5: LambdaTerms::WALL_PRESSURE). Issue 11's targets:
    // within 1 % of Sangani & Acrivos at l = 40 for c = 0.2 / 0.4 / 0.6, within 2 % at l = 20 for c ≤ 0.4, at
    // every τ. κ was set against these very cases (between the bound each of them sets, LAMBDA_WALL_FRICTION
    // says how), so this is an acceptance test, not a held-out one; α = 2 comes from plane channels
    // (LAMBDA_PRESSURE). Measured (`tau_table -- --only lambda`, release, every τ the same to the digits
    // shown): l = 40 +0.12 / +0.27 / +0.01 %, l = 20 −1.84 / −0.65 % (c = 0.6: −8.68 %, 2–4 nodes across the
    // gap, not a target). Here: l = 40 at
    // τ = 0.8 and 2.0 (the spread over τ, as in the tests above), l = 20 at every τ; the full l = 40 grid is the
    // ignored test below.
    for c in [0.2, 0.4, 0.6] {
        let e: Vec<f64> = [0.8, 2.0]
            .iter()
            .map(|&tau| {
                let r = square_array(40, c, tau, Method::LAMBDA_WALL);
                assert!(r.steady, "l = 40, c = {c}, τ = {tau}: not steady");
                r.error
            })
            .collect();
        eprintln!(
            "wall-pressure form, l = 40, c = {c}: {:+.3?} %",
            e.iter().map(|x| 100.0 * x).collect::<Vec<_>>()
        );
        for err in &e {
            assert!(err.abs() <= 0.01, "l = 40, c = {c}: {:+.2} %", 100.0 * err);
        }
        assert!(
            spread(&e) < 2e-5,
            "l = 40, c = {c}: spread {:.3e}",
            spread(&e)
        );
    }
    for c in [0.2, 0.4] {
        let e = errors(20, c, Method::LAMBDA_WALL);
        eprintln!(
            "wall-pressure form, l = 20, c = {c}: {:+.3?} %",
            e.iter().map(|x| 100.0 * x).collect::<Vec<_>>()
        );
        for (tau, err) in TAUS.iter().zip(&e) {
            assert!(
                err.abs() <= 0.02,
                "l = 20, c = {c}, τ = {tau}: {:+.2} %",
                100.0 * err
            );
        }
        assert!(
            spread(&e) < 2e-5,
            "l = 20, c = {c}: spread {:.3e}",
            spread(&e)
        );
    }
}

#[test]
#[ignore = "full grid: 15 runs at l = 40 (about a minute in release)"]
fn square_array_drag_is_within_one_percent_at_l40_for_every_tau() {
    // ΩΛ's wall-pressure form (the default); with friction only the 1 % is not met for c ≥ 0.4 (+1.46 / +1.28 %).
    for c in [0.2, 0.4, 0.6] {
        let e = errors(40, c, Method::LAMBDA_WALL);
        eprintln!(
            "l = 40, c = {c}: {:?} %",
            e.iter().map(|x| 100.0 * x).collect::<Vec<_>>()
        );
        for (tau, err) in TAUS.iter().zip(&e) {
            assert!(
                err.abs() <= 0.01,
                "c = {c}, τ = {tau}: {:+.2} %",
                100.0 * err
            );
        }
        assert!(spread(&e) < 2e-5, "c = {c}: spread {:.3e}", spread(&e));
    }
}

#[test]
#[ignore = "full grid: 15 runs at l = 40 (about a minute in release)"]
fn square_array_drag_is_within_two_percent_at_l40_and_the_same_at_every_tau() {
    for c in [0.2, 0.4, 0.6] {
        let e = errors(40, c, Method::LAMBDA);
        for (tau, err) in TAUS.iter().zip(&e) {
            // As in square_array_drag_at_l40_is_within_two_percent.
            assert!(
                err.abs() <= 0.02,
                "c = {c}, τ = {tau}: {:+.2} %",
                100.0 * err
            );
        }
        assert!(spread(&e) < 2e-5, "c = {c}: spread {:.3e}", spread(&e));
    }
}

#[test]
fn the_noble_torczynski_weighting_is_tau_independent_too() {
    // ΩΛ with B₂ in its Λ form (τ − ½ → √Λ) is τ-independent as well; it under-weights partly covered cells
    // (its friction already carries B₂'s (τ − ½)), so its drag is lower (−8.8 % here): B = ε is ΩΛ's weighting.
    let m = Method {
        weighting: Weighting::NobleTorczynski,
        ..Method::LAMBDA
    };
    let e: Vec<f64> = TAUS
        .iter()
        .map(|&tau| square_array(20, 0.2, tau, m).error)
        .collect();
    assert!(spread(&e) < 2e-5, "spread {:.3e}", spread(&e));
}

#[test]
fn random_pack_permeability_is_the_same_at_every_tau() {
    // 100 discs of diameter 5 at least 1 node apart in a periodic 80 × 80 box (porosity ≈ 0.69), ΩΛ in its
    // default, wall-pressure form (the friction-only form was measured the same way before it: spread 7e-7).
    let (size, d) = (80, 5.0);
    let discs = random_pack(100, d, size, 1.0, 7);
    let runs: Vec<(f64, f64)> = TAUS
        .iter()
        .map(|&tau| {
            let (k, porosity, steady, steps) =
                pack_permeability(&discs, size, tau, Method::LAMBDA_WALL);
            assert!(steady, "τ = {tau}: not steady after {steps} steps");
            eprintln!(
                "τ = {tau}: k = {k:.6e} (k/D² = {:.5}), porosity {porosity:.4}, {steps} steps",
                k / (d * d)
            );
            (k, porosity)
        })
        .collect();
    let k: Vec<f64> = runs.iter().map(|r| r.0).collect();
    let mean = k.iter().sum::<f64>() / k.len() as f64;
    // Issue 11: permeability varies by < 1 % over the τ set. Measured spread 7e-7 relative (Stokes flow at
    // Re ≤ 0.01, δρ ≤ 1e-5, steady to 1e-8 per 200 steps); 2e-5 leaves room for the steady tolerance.
    assert!(spread(&k) / mean < 2e-5, "permeabilities {k:?}");
}
