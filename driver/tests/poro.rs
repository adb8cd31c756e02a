//! Coupled and transient validation cases: terminal slip of a free disc, 1-D pressure diffusion
//! through a slab of fixed grains. Each runs its bundled scene file.
use std::path::Path;

use lbdem::kinds::consolidation::{self, Consolidation};
use lbdem::kinds::fluid_compressibility::{self, FluidCompressibility};
use lbdem::kinds::pressure_diffusion::{self, PressureDiffusion};
use lbdem::kinds::terminal_velocity::{self, omega3_free_grain_growth, TerminalVelocity};
use lbdem::observe::fit::fit_diffusivity;
use lbdem::run::{Case, Kind};
use lbdem::scene::UnitsSetup;
use lbdem_kernels::fluid::collide::SolidOperator;
use lbdem_reference::analytic::{slab_mean_pressure, slab_pressure};

fn text(name: &str) -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(name);
    std::fs::read_to_string(p).unwrap()
}

fn scene<K: Kind>(name: &str) -> K::Scene {
    Case::<K>::read(&text(name), name).unwrap().scene
}

fn case<K: Kind>(name: &str) -> Case<K> {
    Case::<K>::read(&text(name), name).unwrap()
}

#[test]
fn free_disc_conserves_momentum_exactly_and_reaches_the_sangani_acrivos_slip() {
    let o =
        terminal_velocity::simulate(&case::<TerminalVelocity>("terminal_velocity.toml")).unwrap();
    // Total momentum = initial + Σ (F_a + g Σ_n (1 − B_n)) exactly: each step moves ~2e-3 between grain and fluid;
    // only roundoff of the sums over 1 600 nodes × 9 populations remains (~1e-13 absolute per step, measured
    // 1e-12 relative to F_a t over 5 000 steps). 1e-9 relative leaves room and still catches any missing impulse
    // (a single step's imbalance would be ≥ 2e-4 relative).
    assert!(
        o.momentum_error < 1e-9,
        "momentum error {}",
        o.momentum_error
    );
    // Steady: the window mean slip changes by < 0.1 % between its halves (12 e-folding times were run).
    assert!(o.slip_drift.abs() < 1e-3, "slip drift {}", o.slip_drift);
    // Stokes regime (Re_D ~ 0.1: inertial corrections O(Re²) < 0.1 %).
    assert!(o.reynolds < 0.2, "Re {}", o.reynolds);
    // F/(μU) against S&A 51.53 at c = 0.2: the fixed-disc PSM drag at l = 40 is +0.65 % with the default TRT + ΩΛ
    // (README, τ table); measured +0.44 % here (with Ω₁ and BGK, the earlier default: −1.2 % here, −0.25 % at
    // l = 80, scenes/terminal_velocity_full.toml). 3 % allows the coverage of
    // the moving disc to fluctuate and still fails on a missing (1 − c) buoyancy factor (20 %) or a
    // superficial/interstitial mix-up (25 %).
    assert!(
        o.drag_error.abs() < 0.03,
        "F/(mu U) = {} vs S&A {} ({:+.2} %)",
        o.drag,
        o.sangani_acrivos,
        100.0 * o.drag_error
    );
    // The disc moves in the direction of the applied force, the fluid the other way (zero net momentum).
    assert!(o.disc_velocity > 0.0 && o.slip > 0.0);
}

#[test]
fn omega3_is_refused_for_a_free_grain_because_it_is_unstable() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/terminal_velocity.toml"),
    )
    .unwrap()
    .replace(
        "duration = 0.605",
        "duration = 0.605\nsolid_operator = \"moving_wall_bounce_back\"",
    );
    let err = Case::<TerminalVelocity>::read(&text, "inline")
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("terminal_velocity.solid_operator"), "{err}");
    // And the refusal is needed: run anyway (bypassing validation) and the grain/interior-fluid mode blows up,
    // as the growth factor −(1 + 2 M_int/m) predicts (here M_int/m ≈ 0.35: ×1.7 per step).
    let mut s = scene::<TerminalVelocity>("terminal_velocity.toml");
    let t = &mut s.terminal_velocity;
    t.solid_operator = Some(SolidOperator::MovingWallBounceBack);
    t.duration = 0.605 / 5000.0 * 500.0;
    let bypass = Case::<TerminalVelocity> {
        setup: UnitsSetup::new(&s.fluid).unwrap(),
        scene: s,
        budget: Default::default(),
    };
    assert!(terminal_velocity::simulate(&bypass).is_err());
    assert!(omega3_free_grain_growth(0.35, 1.0).abs() > 1.0);
}

#[test]
fn slab_series_reproduces_the_reference_table() {
    // docs/references.md §6.2 table: L = 4.5 cm, c = 7.9 cm²/s; the values are given to 4 digits.
    let l = 4.5;
    for (t, centre, half, near_face) in [
        (0.5, 0.7813, 0.5603, 0.1394),
        (1.0, 0.4862, 0.3439, 0.0845),
        (2.0, 0.1857, 0.1313, 0.0323),
    ] {
        // x measured from the centre; "0.5 cm from the face" is x = 4.0.
        for (x, want) in [(0.0, centre), (l / 2.0, half), (4.0, near_face)] {
            let got = slab_pressure(x, t, 7.9, l).0;
            assert!((got - want).abs() < 6e-5, "t {t} x {x}: {got} vs {want}");
        }
    }
    // The mean is the integral of the profile (Simpson, 200 panels: error ~1e-9).
    let n = 200;
    let mut s = 0.0;
    for i in 0..=n {
        let x = -l + 2.0 * l * i as f64 / n as f64;
        let w = if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        s += w * slab_pressure(x, 1.0, 7.9, l).0;
    }
    let mean = s * (2.0 * l / n as f64) / 3.0 / (2.0 * l);
    assert!((mean - slab_mean_pressure(1.0, 7.9, l)).abs() < 1e-6);
}

#[test]
fn gauss_newton_recovers_a_known_diffusivity() {
    let l = 30.0;
    let c = 0.37;
    let samples: Vec<(f64, f64, f64)> = [100.0, 400.0, 1500.0]
        .iter()
        .flat_map(|&t| {
            (1..60).map(move |i| (i as f64 - l, t, slab_pressure(i as f64 - l, t, c, l).0))
        })
        .collect();
    // Start 3× off: Gauss–Newton on ln c converges to the exact value (residual roundoff only).
    let (fit, rms, _) = fit_diffusivity(&samples, l, 3.0 * c);
    assert!((fit / c - 1.0).abs() < 1e-8, "{fit}");
    assert!(rms < 1e-10);
}

#[test]
fn pressure_diffusion_matches_darcy_permeability_over_storage() {
    let o = pressure_diffusion::simulate(&case::<PressureDiffusion>("pressure_diffusion.toml"))
        .unwrap();
    // Storage porosity from the released mass lies between the geometric porosity 1 − ⟨ε⟩ (the PSM nodes with
    // 0 < ε < 1 store fully, not as 1 − ε) and 1 (fluid on links between two fully covered nodes never drains).
    assert!(
        o.storage_porosity > o.geometric_porosity && o.storage_porosity < 1.0,
        "n_storage {} n_geo {}",
        o.storage_porosity,
        o.geometric_porosity
    );
    // c = k c_s²/(ν n) with k from the steady Darcy run and n the storage porosity. Measured +8.8 %. Tolerance
    // 15 %: partially covered nodes with B → 1 trade fluid with the pores at a rate (1 − B)/τ per step, a slow
    // (dual-porosity) storage, so the best-fit c of single snapshots falls from +20 % (early, c t/L² = 0.05)
    // to +4 % (late) against the end-of-run storage; and the 67-grain slab is only ~6 grains high, so its
    // cross-section averages scatter (rms 0.007 at late times, where the fit is no longer time-biased).
    assert!(
        o.diffusivity_error.abs() < 0.15,
        "fitted c {} vs predicted {} ({:+.1} %)",
        o.fitted_diffusivity,
        o.predicted_diffusivity,
        100.0 * o.diffusivity_error
    );
    // The least-squares residual of the fit (P/P0 units) stays at the few-percent level of fig. 5.9.
    assert!(o.rms_residual < 0.04, "rms {}", o.rms_residual);
    // The profiles decay: centre pressure falls monotonically between snapshots.
    let centre: Vec<f64> = o
        .profiles
        .iter()
        .map(|p| {
            let pts: Vec<f64> = p
                .points
                .iter()
                .filter(|(x, _, _)| (x - o.half_length).abs() < 5.0)
                .map(|(_, v, _)| *v)
                .collect();
            pts.iter().sum::<f64>() / pts.len() as f64
        })
        .collect();
    assert!(centre.windows(2).all(|w| w[1] < w[0]), "{centre:?}");
}

#[test]
fn a_piston_compresses_the_lattice_fluid_with_compressibility_one_over_rho_cs2() {
    let o = fluid_compressibility::simulate(&case::<FluidCompressibility>(
        "fluid_compressibility.toml",
    ))
    .unwrap();
    // The piston moved by one spacing (the sin² profile integrates to the travel up to rounding of the steps).
    assert!((o.travel - 1.0).abs() < 1e-2, "travel {}", o.travel);
    // (ΔV/V)/Δp against 1/(ρ₀ c_s²): measured +1.8 %. Tolerance 5 %: the partially covered face nodes store
    // fluid as whole nodes but count as 1 − ε of the volume, and the face layer trades fluid with the piston's
    // interior (~1/2 node of a 60-node chamber, ~1 % each); a leaking piston (Ω₁: the chambers equalise, error
    // −100 %) or a wrong sound speed in the units (factor 3) fails by far.
    assert!(
        o.error.abs() < 0.05,
        "beta {} vs {} ({:+.2} %)",
        o.measured,
        o.expected,
        100.0 * o.error
    );
    // The expected value is the units' β = 1/(ρ₀ c_s²) with c_s = h/(√3 Δt) of table 4.1.
    let dt = 0.375 * 0.011f64.powi(2) / 0.3;
    let cs = 0.011 / dt / 3f64.sqrt();
    assert!((o.expected * cs * cs - 1.0).abs() < 1e-12);
    // Settled: the piston force is steady to < 1e-3 over the averaging window.
    assert!(o.stress_ripple.abs() < 1e-3, "ripple {}", o.stress_ripple);
    // The dissertation's definition, from the stress on the piston: (Δρ_front − Δρ_back)/(ρ₀ σ) against
    // 1/(ρ₀ c_s²) (issue 14 item 4). Measured +0.33 % under the default ΩΛ (the two rows touching the walls
    // carry 5/6 of a row's share of the force: 1/3 of a row in 101). Tolerance 5 % (the issue's): Ω₃'s
    // standing loop at the wall rows (−58.9 %, force 2.4× too large) fails by far, and so would a force
    // counted on one chamber only (−60 %) or a face height off by the piston's thickness.
    assert!(
        o.force_based_error.abs() < 0.05,
        "piston-stress beta {} vs {} ({:+.2} %)",
        o.force_based,
        o.expected,
        100.0 * o.force_based_error
    );
}

#[test]
fn a_leaky_piston_operator_is_refused_naming_the_key() {
    let mut s = scene::<FluidCompressibility>("fluid_compressibility.toml");
    s.fluid_compressibility.solid_operator =
        Some(SolidOperator::LinearizedNonEquilibriumBounceBack);
    let e = Case::<FluidCompressibility>::new(s)
        .err()
        .expect("refused")
        .to_string();
    assert!(e.contains("fluid_compressibility.solid_operator"), "{e}");
    assert!(e.contains("lambda_consistent"), "{e}");
}

fn consolidation_peak(stiffness_factor: f64, timestep_factor: f64) -> (f64, f64, f64) {
    let mut s = scene::<Consolidation>("consolidation.toml");
    s.fluid.timestep = s.fluid.timestep.map(|dt| dt * timestep_factor);
    let c = &mut s.consolidation;
    c.normal_stiffness *= stiffness_factor;
    c.duration = 0.35; // s: every peak below comes before 0.25 s
    let o = consolidation::simulate(&Case::<Consolidation>::new(s).unwrap()).unwrap();
    (o.peak_time, o.peak_pressure, o.final_pressure)
}

#[test]
fn consolidation_peak_pressure_comes_sooner_with_stiffer_grains_and_a_faster_fluid() {
    // Stiffness 1, 16, 64 (lattice units at the scene's Δt): measured peaks at 0.212, 0.164, 0.164 s. Softer
    // skeletons take longer to pass the load to the fluid (dissertation fig. 5.12: ~6 s soft to ~0.03 s stiff);
    // above k_n ~ 16 the fluid's own (inertial/drainage) time dominates, so only non-increase is asserted there,
    // with an overall drop of at least 15 %: measured 23 % (the peak time is sampled every 10 steps = 4 ms, so
    // 12 samples apart). With ΩΛ's friction-only form (the default before 2026-12-07) the peaks were 0.224,
    // 0.156, 0.156 s (30 %) and the bound 25 %: under the wall-pressure form the stiff skeleton's
    // drainage-dominated peak comes later, as from a less permeable pack (the form lowers the quick fracture
    // pack's permeability by 60 %; README, "ΩΛ's wall-pressure form"). The bound was lowered with that change,
    // and says so; it still fails if stiffness stops mattering.
    let soft = consolidation_peak(1.0 / 16.0, 1.0);
    let base = consolidation_peak(1.0, 1.0);
    let stiff = consolidation_peak(4.0, 1.0);
    eprintln!(
        "peak (time, pressure, final) at stiffness x1/16, x1, x4: {soft:?} {base:?} {stiff:?}"
    );
    assert!(
        soft.0 > base.0 && base.0 >= stiff.0 && stiff.0 < 0.85 * soft.0,
        "peak times {soft:?} {base:?} {stiff:?}"
    );
    // The fluid carries the step load (loading efficiency ~1; the LB fluid is much stiffer than the pack) and
    // overshoots it acoustically; then the drained top lets it dissipate.
    for (t, peak, end) in [soft, base, stiff] {
        assert!(peak > 0.9 && peak < 2.0, "peak {peak} at {t}");
        assert!(end < peak, "no dissipation: {end} vs {peak}");
    }
    // Fluid sound speed ×2 and ×4 (time step /2 and /4 at the same physical viscosity, stiffness and load; τ
    // 0.8 → 0.65 → 0.575): measured peaks 0.16, 0.124, 0.058 s. Each doubling must shorten it by ≥ 15 %.
    let fast = consolidation_peak(1.0, 0.5);
    let faster = consolidation_peak(1.0, 0.25);
    assert!(
        fast.0 < 0.85 * base.0 && faster.0 < 0.85 * fast.0,
        "peak times {base:?} {fast:?} {faster:?}"
    );
}
