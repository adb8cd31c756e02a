//! Brazilian (diametral compression) test of a bonded 2-D disc assembly (docs/references.md §7.4: σ_t = 2P/(πD) per unit
//! thickness; the bonded-particle model's known excess tensile strength, UCS/σ_t ≈ 4–8 against ≈ 20 in rock).
//!
//! The sample: the ch. 6.6 discs (radius 0.07–0.11 cm, seed 1) packed by the ch. 2 procedure in a 3 × 3 cm box
//! to the 50 dyne/cm hydrostatic stress (285 discs), as in `dem_validation.rs`. The discs whose bounding circles
//! lie inside the centred circle of diameter D = 2.8 cm are kept (178 discs) and their touching pairs bonded with
//! the same parallel bonds as the uniaxial tests (λ̄ = 1, k̄_n = k̄_s = 2.8e5 dyne/cm³, σ̄_c = τ̄_c = 500
//! dyne/cm², 324 bonds), contacts k_n = k_s = 1e5 dyne/cm, μ = 0.5, local damping 0.7, Δt = 5e-5 s. The disc
//! settles for 2000 steps without platens (releasing the installed stress into the bonds), then two flat rigid
//! platens touching it below and above close at 0.02 cm/s each (the uniaxial tests' speed). The load P is the
//! mean normal force on the two platens; the test stops when P falls below half its peak.
//!
//! Measured (f64, `cargo test -p lbdem --test integration dem_brazilian::`, ≈ 10 s in all): peak P = 581.5 dyne/cm at a closure
//! of 0.044 cm, σ_t = 132.2 dyne/cm²; 32 bonds broken, 28 in tension. With σ̄_c = τ̄_c = 1000: P = 1203.8,
//! σ_t = 273.7 (×2.070). All 32 breaks lie within D/4 of the loaded diameter (a central splitting crack);
//! 10 of them before the peak (local breakage at the platen contacts). Halving the platen speed changed the
//! peak by 0.8 % (576.7, measured once; not asserted, to keep the test fast). UCS of the bonded 3 × 3 cm square
//! (same packing, same bonds, `run_compression` as in `dem_validation.rs`) = 729.9 dyne/cm², so
//! UCS/σ_t = 5.52, inside the BPM's 4–8 (docs/references.md §7.4), far below rock's ≈ 20.
use std::sync::OnceLock;

use lbdem::engine::dem::*;
use lbdem_kernels::dem::bond::BreakMode;

const BOND_STIFFNESS: f64 = 2.8e5;
const BOND_STRENGTH: f64 = 500.0;
const PLATEN_SPEED: f64 = 0.02;
const SIDE: f64 = 3.0;
const DIAMETER: f64 = 2.8;

fn packing() -> &'static Packing<f64> {
    static PACKING: OnceLock<Packing<f64>> = OnceLock::new();
    PACKING.get_or_init(|| {
        let spec = PackingSpec::dissertation(SIDE, SIDE, 1.0, 1);
        let p = generate_packing(&spec, None).expect("packing");
        assert!(
            p.converged,
            "isotropic stress not reached: {:?}",
            p.wall_stresses
        );
        p
    })
}

fn parallel_bonds(strength: f64) -> BondSpec<f64> {
    BondSpec::Parallel {
        radius_multiplier: 1.0,
        normal_stiffness: BOND_STIFFNESS,
        shear_stiffness: BOND_STIFFNESS,
        tensile_strength: strength,
        shear_strength: strength,
    }
}

/// Carve the bonded disc from the shared packing and crush it; returns the record and the final world.
fn brazilian(strength: f64) -> (BrazilianResult, DemWorld<f64>) {
    let mut w = carve_disc(packing(), DIAMETER, parallel_bonds(strength), 1e-3).expect("disc");
    let test = BrazilianTest {
        diameter: DIAMETER,
        platen_speed: PLATEN_SPEED,
        settle_steps: 2000,
        max_closure: 0.2,
        post_peak_fraction: 0.5,
        record_interval: 50,
    };
    let r = run_brazilian(&mut w, &test, |_, _| {});
    let tension = w
        .breaks
        .iter()
        .filter(|b| b.mode == BreakMode::Tension)
        .count();
    eprintln!(
        "Brazilian, sigma_c = tau_c = {strength}: {} discs, {} bonds; peak P = {:.2} dyne/cm at closure {:.4e} cm, \
         sigma_t = 2P/(pi D) = {:.2} dyne/cm^2; {} bonds broken ({tension} in tension); {} loading steps",
        w.particles.len(),
        w.bonds.len(),
        r.peak_load,
        r.curve[r.peak_index].closure,
        r.tensile_strength,
        w.breaks.len(),
        r.steps
    );
    (r, w)
}

/// The weak (σ̄_c = 500) disc, shared by the tests.
fn weak() -> &'static (BrazilianResult, DemWorld<f64>) {
    static WEAK: OnceLock<(BrazilianResult, DemWorld<f64>)> = OnceLock::new();
    WEAK.get_or_init(|| brazilian(BOND_STRENGTH))
}

#[test]
fn disc_fails_at_a_clear_peak_with_bonds_broken_mostly_in_tension() {
    let (r, w) = weak();
    assert!(w.particles.len() > 150 && w.bonds.len() > 250);
    assert!(r.peak_load > 0.0 && r.tensile_strength.is_finite());
    // A clear peak: the test ran past it and the load fell below half of it (the stop criterion), with most
    // of the bond breakage at or after the peak (the splitting crack), not before.
    let last = r.curve.last().expect("curve");
    assert!(r.peak_index + 1 < r.curve.len(), "no point after the peak");
    assert!(
        last.load < 0.5 * r.peak_load,
        "load {} after peak {}",
        last.load,
        r.peak_load
    );
    let before = r.curve[r.peak_index].broken_bonds;
    assert!(
        last.broken_bonds >= 2 * before.max(1),
        "breaks before the peak {before}, at the end {}",
        last.broken_bonds
    );
    // Diametral compression splits the disc in tension: most bonds break in tension (measured 28 of 32).
    let tension = w
        .breaks
        .iter()
        .filter(|b| b.mode == BreakMode::Tension)
        .count();
    let centre_x = 0.5 * SIDE;
    let central = w
        .breaks
        .iter()
        .filter(|b| (b.position[0] - centre_x).abs() < 0.25 * DIAMETER)
        .count();
    eprintln!(
        "{tension} of {} breaks in tension; {central} within D/4 of the loaded diameter",
        w.breaks.len()
    );
    assert!(
        tension as f64 >= 0.7 * w.breaks.len() as f64,
        "{tension} tension of {}",
        w.breaks.len()
    );
    // The crack runs along the loaded (vertical) diameter (measured: all 32 breaks within D/4 of it).
    assert!(
        central as f64 >= 0.7 * w.breaks.len() as f64,
        "{central} central of {}",
        w.breaks.len()
    );
}

#[test]
fn tensile_strength_doubles_with_bond_strength() {
    let (weak, _) = weak();
    let (strong, _) = brazilian(2.0 * BOND_STRENGTH);
    let ratio = strong.tensile_strength / weak.tensile_strength;
    eprintln!(
        "sigma_t = {:.2} -> {:.2} dyne/cm^2 when sigma_c, tau_c double: ratio {ratio:.4}; sigma_t/sigma_c = {:.3}",
        weak.tensile_strength,
        strong.tensile_strength,
        weak.tensile_strength / BOND_STRENGTH
    );
    // σ_t ∝ σ̄_c at fixed packing (docs/references.md §7.4 scaling), to ±12.5 %, wider than the uniaxial test's 5 %:
    // (a) the installed stress released on carving leaves a locked-in bond pre-stress that does not scale
    // with the bond strength (it weakens the weak disc relatively more, pushing the ratio above 2);
    // (b) the peak follows a few local breaks at the platen contacts and the splitting crack's start, so
    // roundoff-level differences in which bond goes first are amplified (the direct-tension test saw ±10 %);
    // (c) failure closures of 0.04–0.07 cm (1.5–2.5 % of D) add geometric non-linearity. Measured ×2.070.
    assert!((ratio - 2.0).abs() < 0.25, "sigma_t ratio {ratio}");
}

#[test]
fn ucs_over_brazilian_strength_is_in_the_bpm_range() {
    let (weak, _) = weak();
    let mut p = packing().clone();
    p.world
        .bond_touching_pairs(parallel_bonds(BOND_STRENGTH), 1e-3)
        .expect("bonding");
    let test = CompressionTest {
        confining_stress: 0.0,
        platen_speed: PLATEN_SPEED,
        settle_steps: 1000,
        max_strain: 0.05,
        post_peak_fraction: 0.7,
        record_interval: 50,
    };
    let ucs = run_compression(&mut p, &test, |_, _| {}).peak_stress;
    let ratio = ucs / weak.tensile_strength;
    eprintln!(
        "UCS = {ucs:.2} dyne/cm^2 (square {SIDE} x {SIDE} cm, same packing and bonds), sigma_t = {:.2}: \
         UCS/sigma_t = {ratio:.3}",
        weak.tensile_strength
    );
    // The BPM is too strong in tension: UCS/σ_t ≈ 4–8 in P&C 2004 (≈ 20 for rock); 2–8 allowed here (the
    // direct-tension test of `dem_validation.rs` gave 2–3), and above all σ_t < UCS.
    assert!((2.0..=8.0).contains(&ratio), "UCS/sigma_t {ratio}");
}
