//! Validation of the dry bonded-particle model orchestrated by `lbdem::engine::dem`: scaling of the
//! elastic modulus with the contact/bond stiffness, of the uniaxial strength with the bond strength, and the
//! rise of the failure-envelope slope with friction (docs/references.md §7.4, dissertation ch. 2); determinism; the
//! critical-step refusal.
//!
//! The sample: ≈ 250 discs (radius 0.07–0.11 cm, ch. 6.6 sizes) packed by the ch. 2 procedure in a 2 × 4 cm
//! box to the ch. 6.6 hydrostatic stress (50 dyne/cm), k_n = k_s = 1e5 dyne/cm, parallel bonds with
//! λ̄ = 1, k̄_n = k̄_s = 2.8e5 dyne/cm³ (Ē_c ≈ E_c = k_n/2 with eq. 2.2 for R_A + R_B ≈ 0.18 cm),
//! σ̄_c = τ̄_c = 500 dyne/cm², local damping 0.7, platens at 0.02 cm/s each (axial strain rate 0.01/s; halving it
//! changed the peak by 1.3 %, measured). One packing (seed 1) is shared by every test. Total ≈ 30 s.
//!
//! Direct tension by stress control through the boundary particles (the fracture test's loading path; the
//! Brazilian test itself is in `dem_brazilian.rs`): σ_t 371 → 778.5 dyne/cm² when σ̄_c, τ̄_c double (×2.10) in a
//! `-p lbdem` build, 229 → 420 (×1.83) in a workspace build (roundoff-sensitive, see the test); UCS/σ_t ≈ 2–3
//! (the BPM's known deficiency: too strong in tension, docs/references.md §7.4).
//!
//! Measured (f64; `cargo test --workspace`, in brackets `cargo test -p lbdem`, as first measured when the two
//! builds differed in the last bit of sin/cos/hypot through feature unification of num-traits — failure
//! amplifies such bits. The kernels now call `libm` through `Real::portable_*` in every build, so both builds
//! give the same bits; the bracketed libm figures are the ones that apply):
//! E = 9.13e4 [9.07e4] dyne/cm² at σ̄_c = 500; UCS 765.5 → 1540.8 [741.7 → 1505.8] dyne/cm² when σ̄_c, τ̄_c
//! double, ×2.013 [×2.030]; E ×1.988 [×1.992] when every stiffness doubles (unbreakable bonds); envelope slopes
//! dσ₁/dσ₃ = 1.29 [1.50] (μ = 0.1) and 3.09 [3.47] (μ = 1.0) between σ₃ = 25 and 150 dyne/cm.
use std::sync::OnceLock;

use lbdem::engine::dem::*;
use lbdem_kernels::dem::assembly::ContactModel;
use lbdem_kernels::dem::bond::BreakMode;
use lbdem_kernels::dem::servo::ServoLaw;

const BOND_STIFFNESS: f64 = 2.8e5;
const BOND_STRENGTH: f64 = 500.0;
const PLATEN_SPEED: f64 = 0.02;

fn packing() -> &'static Packing<f64> {
    static PACKING: OnceLock<Packing<f64>> = OnceLock::new();
    PACKING.get_or_init(|| {
        let spec = PackingSpec::dissertation(2.0, 4.0, 1.0, 1);
        let p = generate_packing(&spec, None).expect("packing");
        assert!(
            p.converged,
            "isotropic stress not reached: {:?}",
            p.wall_stresses
        );
        p
    })
}

fn parallel_bonds(stiffness: f64, strength: f64) -> BondSpec<f64> {
    BondSpec::Parallel {
        radius_multiplier: 1.0,
        normal_stiffness: stiffness,
        shear_stiffness: stiffness,
        tensile_strength: strength,
        shear_strength: strength,
    }
}

/// Bond the shared packing with the given stiffness multiplier (contacts and bonds), bond strength and
/// friction, then load it.
fn compression(
    stiffness_factor: f64,
    strength: f64,
    friction: f64,
    confining_stress: f64,
    max_strain: f64,
) -> (CompressionResult, Packing<f64>) {
    let mut p = packing().clone();
    p.world.model.normal_stiffness *= stiffness_factor;
    p.world.model.shear_stiffness *= stiffness_factor;
    p.world.model.friction = friction;
    p.world
        .bond_touching_pairs(
            parallel_bonds(BOND_STIFFNESS * stiffness_factor, strength),
            1e-3,
        )
        .expect("bonding keeps the step below critical");
    let test = CompressionTest {
        confining_stress,
        platen_speed: PLATEN_SPEED,
        settle_steps: 1000,
        max_strain,
        post_peak_fraction: 0.7,
        record_interval: 50,
    };
    let r = run_compression(&mut p, &test, |_, _| {});
    (r, p)
}

#[test]
fn youngs_modulus_doubles_with_contact_and_bond_stiffness() {
    // Unbreakable bonds, elastic range only (axial strain ≤ 0.2 %).
    let (soft, _) = compression(1.0, 1e12, 0.5, 0.0, 2e-3);
    let (stiff, _) = compression(2.0, 1e12, 0.5, 0.0, 2e-3);
    let ratio = stiff.youngs_modulus / soft.youngs_modulus;
    println!(
        "E = {:.4e} -> {:.4e} dyne/cm^2, ratio {ratio:.4}",
        soft.youngs_modulus, stiff.youngs_modulus
    );
    // 5 %: the quasi-static bonded model is linear in the stiffnesses (E ∝ E_c, docs/references.md §7.4), but the
    // installed isotropic stress (fixed contact overlaps) becomes a doubled pre-stress, and at the same platen
    // speed the stiffer sample is loaded relatively faster (its wave crossing time falls by √2).
    assert!((ratio - 2.0).abs() < 0.1, "E ratio {ratio}");
}

#[test]
fn uniaxial_strength_doubles_with_bond_strength_and_bonds_break() {
    let (weak, sample) = compression(1.0, BOND_STRENGTH, 0.5, 0.0, 0.05);
    let (strong, _) = compression(1.0, 2.0 * BOND_STRENGTH, 0.5, 0.0, 0.05);
    let ratio = strong.peak_stress / weak.peak_stress;
    println!(
        "UCS = {:.2} -> {:.2} dyne/cm^2 (ratio {ratio:.4}); E = {:.4e}; peak strain {:.4e}; UCS/sigma_c = {:.3}",
        weak.peak_stress,
        strong.peak_stress,
        weak.youngs_modulus,
        weak.peak_strain,
        weak.peak_stress / BOND_STRENGTH
    );
    // 5 %: UCS ∝ σ̄_c at fixed packing and τ̄_c/σ̄_c when E_c/σ̄_c ≫ 1 (docs/references.md §7.4); here E_c/σ̄_c = 100, the
    // installed hydrostatic stress (50 dyne/cm, ≈ 7 % of the UCS) does not scale with the bond strength, and
    // failure strains of 0.8–1.8 % add geometric non-linearity.
    assert!((ratio - 2.0).abs() < 0.1, "UCS ratio {ratio}");
    // The test ran past the peak (the stress fell to 70 % of it) and bonds broke, each recorded.
    let last = weak.curve.last().expect("curve");
    assert!(last.axial_strain > weak.peak_strain);
    let breaks = &sample.world.breaks;
    assert!(!breaks.is_empty());
    assert_eq!(
        breaks.len(),
        sample.world.bonds.len() - sample.world.intact_bonds()
    );
    assert!(breaks.windows(2).all(|w| w[0].step <= w[1].step));
    for b in breaks {
        let [i, j] = b.pair;
        assert!(i < j && j < sample.world.particles.len());
        assert!(b.orientation.is_finite() && b.position.iter().all(|x| x.is_finite()));
        assert!(matches!(b.mode, BreakMode::Tension | BreakMode::Shear));
    }
}

#[test]
fn failure_envelope_slope_rises_with_friction() {
    let confinements = [25.0, 150.0];
    let slope = |friction: f64| {
        let peaks: Vec<f64> = confinements
            .iter()
            .map(|&c| {
                compression(1.0, BOND_STRENGTH, friction, c, 0.05)
                    .0
                    .peak_stress
            })
            .collect();
        println!("friction {friction}: peak axial stress {peaks:?} at confining {confinements:?}");
        (peaks[1] - peaks[0]) / (confinements[1] - confinements[0])
    };
    let (low, high) = (slope(0.1), slope(1.0));
    println!("envelope slope d(sigma_1)/d(sigma_3): {low:.3} (mu = 0.1), {high:.3} (mu = 1.0)");
    // Qualitative (dissertation ch. 2: friction raises the slope of the compressive failure envelope);
    // measured 1.29 and 3.09 (1.50 and 3.47 in a `-p lbdem` build). Both must rise with confinement, and the high-friction slope by at least 50 %
    // more, far beyond the run-to-run change from the loading rate (1.3 % of the peak).
    assert!(low > 0.0 && high > 1.5 * low, "slopes {low} {high}");
}

#[test]
fn packing_is_bitwise_deterministic_for_a_seed() {
    let spec = |seed| {
        let mut s = PackingSpec::dissertation(1.2, 1.2, 0.5, seed);
        s.max_servo_steps = 3000;
        s
    };
    let bonds = Some(BondSpec::Point {
        stiffness: 1e5,
        strength: 700.0,
    });
    let a = generate_packing(&spec(7), bonds).unwrap();
    let b = generate_packing(&spec(7), bonds).unwrap();
    let c = generate_packing(&spec(8), bonds).unwrap();
    assert!(a.world.particles.len() > 20);
    assert_eq!(a.world.particles, b.world.particles);
    assert_eq!(a.world.bonds, b.world.bonds);
    assert_ne!(a.world.particles, c.world.particles);
    // Ellipses of aspect 0.5 with orientations in [0, π).
    assert!(a.world.particles.iter().any(|p| p.angle > 1.0));
}

/// The pair-contact pass runs at the widest instruction set the CPU has (`DemWorld::set_simd`): stepping a
/// bonded ellipse packing under a platen load at every available level gives bitwise the baseline's particles,
/// bonds and breaks (IEEE arithmetic rounds the same in every vector width; no fused multiply-add).
#[test]
fn ellipse_contacts_are_bitwise_the_same_at_every_instruction_set() {
    use lbdem::engine::exec::SimdLevel;
    let packed = crate::common::bonded_ellipse_packing();
    let run = |level: SimdLevel| {
        let mut p = packed.clone();
        p.world.set_simd(level).unwrap();
        let b = p.sample_box;
        p.world.platens[b.top].control = PlatenControl::Speed(0.5);
        let mut active = 0;
        for _ in 0..200 {
            p.world.step();
            active = active.max(p.world.active_contacts());
        }
        (p.world, active)
    };
    let (base, active) = run(SimdLevel::Baseline);
    // Ellipse pairs in contact: the closest-approach search really runs.
    assert!(active > 20, "{active} active contacts");
    assert!(base.particles.iter().any(|p| p.angle > 1.0));
    for level in SimdLevel::ALL.into_iter().filter(|l| l.available()) {
        let (w, _) = run(level);
        assert_eq!(w.particles, base.particles, "{level:?}");
        assert_eq!(w.bonds, base.bonds, "{level:?}");
        assert_eq!(w.breaks, base.breaks, "{level:?}");
        assert_eq!(w.platens, base.platens, "{level:?}");
    }
}

fn bonded_hexagonal_block(side: usize) -> Packing<f64> {
    let particles = hexagonal_packing(side, side, 0.09, 1.0, 0.02, 2.65, 3);
    let model = ContactModel {
        normal_stiffness: 1e5,
        shear_stiffness: 1e5,
        friction: 0.5,
        restitution: 1.0,
        no_tension: true,
    };
    boxed_sample(
        particles,
        model,
        5e-5,
        Some(parallel_bonds(BOND_STIFFNESS, BOND_STRENGTH)),
        0.005,
    )
    .unwrap()
}

#[test]
fn step_is_bitwise_identical_for_one_and_two_threads() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut p = bonded_hexagonal_block(30);
            let b = p.sample_box;
            p.world.platens[b.top].control = PlatenControl::Speed(0.5);
            p.world.platens[b.left].control = PlatenControl::Servo(ServoLaw {
                target_stress: 10.0,
                relaxation: 0.5,
                max_speed: 0.1,
            });
            for _ in 0..300 {
                p.world.step();
            }
            p.world
        })
    };
    let (one, two) = (run(1), run(2));
    // More than two rayon chunks of 512 pairs/bonds/particles: the parallel passes really split.
    assert!(
        one.candidate_pair_list().len() > 1024,
        "too few pairs to split"
    );
    assert!(one.bonds.len() > 1024 && one.particles.len() > 512);
    assert_eq!(one.particles, two.particles);
    assert_eq!(one.bonds, two.bonds);
    assert_eq!(one.breaks, two.breaks);
    assert_eq!(one.platens, two.platens);
}

#[test]
fn step_above_critical_is_refused_naming_the_field() {
    let particles = hexagonal_packing(4, 4, 0.09, 1.0, 0.0, 2.65, 1);
    let model = ContactModel {
        normal_stiffness: 1e5,
        shear_stiffness: 1e5,
        friction: 0.5,
        restitution: 1.0,
        no_tension: true,
    };
    let world = DemWorld::new(particles.clone(), model, 1e-5).unwrap();
    let critical = world.critical_time_step();
    // Disc r = 0.09, density 2.65: m = 0.0674 g; rotation governs: √(I/(6 k_s r²)) = √(m/12e5) = 2.37e-4 s.
    assert!(
        (critical - (0.5 * 2.65 * std::f64::consts::PI * 0.0081 / 6e5f64).sqrt()).abs() < 1e-12
    );
    let err = DemWorld::new(particles, model, critical)
        .unwrap_err()
        .to_string();
    assert!(err.contains("solid.timestep"), "{err}");
    assert!(err.contains("critical"), "{err}");
    // Bonding stiffens the assembly: the critical step falls.
    let mut p = bonded_hexagonal_block(30);
    let before = p.world.critical_time_step();
    // Bonding again adds nothing: every touching pair already has its bond.
    let again = p
        .world
        .bond_touching_pairs(parallel_bonds(BOND_STIFFNESS, BOND_STRENGTH), 0.005)
        .unwrap();
    assert_eq!(again, 0);
    p.world.bonds.clear();
    assert!(p.world.critical_time_step() > before);
}

#[test]
fn boundary_particle_stress_and_servo_platens_hold_their_targets() {
    // The fracture test's loading (dissertation ch. 6.6): the axial stress enters through the particles along
    // the top boundary (no top platen, so fluid could pass), the lateral stress is held by servo platens.
    let mut p = bonded_hexagonal_block(16);
    let b = p.sample_box;
    let w = &mut p.world;
    let width = w.platens[b.right].wall.point[0] - w.platens[b.left].wall.point[0];
    w.platens[b.top].active = false;
    w.sample_box = None;
    w.platens[b.bottom].length = width;
    let height = w.platens[b.top].wall.point[1] - w.platens[b.bottom].wall.point[1];
    for side in [b.left, b.right] {
        w.platens[side].length = height;
        w.platens[side].control = PlatenControl::Servo(ServoLaw {
            target_stress: 20.0,
            relaxation: 0.5,
            max_speed: 0.05,
        });
    }
    let top = w.boundary_particles(3, 0.05);
    assert!(top.len() >= 12 && top.len() <= 20, "{}", top.len());
    w.apply_boundary_stress(&top, lbdem_kernels::math::vector(0.0, -1.0), 40.0, width);
    let total: f64 = w.external_force.iter().map(|f| f[1]).sum();
    assert!((total + 40.0 * width).abs() < 1e-9 * 40.0 * width);
    for _ in 0..8000 {
        w.step();
    }
    let bottom = w.platens[b.bottom].stress();
    let lateral = [w.platens[b.left].stress(), w.platens[b.right].stress()];
    let carried: f64 = w.platens.iter().map(|pl| pl.reaction[1]).sum();
    println!(
        "bottom platen {bottom:.3}, vertical load on all platens {:.3} (applied {:.3}), lateral {lateral:?} (servo target 20)",
        -carried,
        40.0 * width
    );
    // Static equilibrium (no gravity): the platens together carry the applied load, the bottom one in
    // compression and the lateral ones by wall friction (μ = 0.5: the bottom platen sees about half); 2 % for
    // the residual motion after 6000 steps. The servo holds its target to 5 %.
    assert!(
        (-carried - 40.0 * width).abs() < 0.02 * 40.0 * width,
        "carried {carried}"
    );
    assert!(bottom > 10.0, "bottom {bottom}");
    for s in lateral {
        assert!((s - 20.0).abs() < 1.0, "lateral {s}");
    }
}

/// Direct tension by stress control: the bottom boundary particles are held, the top ones pulled up by a
/// stress rising at `rate` per step (no platens). Returns (tensile strength, broken bonds at the end): the
/// applied stress when the broken bonds first exceed 5 % of all bonds. Measured: the sample parts along one
/// crack of ≈ 43 bonds (9.5 %), and under stress control that crack runs once started, so 5 % is mid-rupture.
fn direct_tension(strength: f64, rate: f64) -> (f64, usize) {
    let mut p = packing().clone();
    p.world
        .bond_touching_pairs(parallel_bonds(BOND_STIFFNESS, strength), 1e-3)
        .unwrap();
    let w = &mut p.world;
    let (lo, hi) = w.bounds();
    let width = hi[0] - lo[0];
    for pl in w.platens.iter_mut() {
        pl.active = false;
        pl.control = PlatenControl::Speed(0.0);
    }
    w.sample_box = None;
    for i in w.boundary_particles(2, 0.05) {
        w.held[i] = true;
    }
    let top = w.boundary_particles(3, 0.05);
    let threshold = w.bonds.len() / 20;
    let mut stress = 0.0;
    for _ in 0..4000 {
        for _ in 0..10 {
            w.step();
        }
        if w.breaks.len() > threshold {
            return (stress, w.breaks.len());
        }
        stress += 10.0 * rate;
        w.apply_boundary_stress(&top, lbdem_kernels::math::vector(0.0, 1.0), stress, width);
    }
    (f64::NAN, w.breaks.len())
}

#[test]
fn direct_tensile_strength_doubles_with_bond_strength() {
    let rate = BOND_STRENGTH / 40_000.0;
    let (weak, broken) = direct_tension(BOND_STRENGTH, rate);
    let (strong, _) = direct_tension(2.0 * BOND_STRENGTH, 2.0 * rate);
    let ratio = strong / weak;
    println!(
        "tensile strength {weak:.3} -> {strong:.3} dyne/cm^2 (ratio {ratio:.4}), {broken} bonds broken; sigma_t/sigma_c = {:.3}",
        weak / BOND_STRENGTH
    );
    assert!(weak > 0.0 && weak.is_finite());
    // Qualitative only. The stress-controlled rupture is sensitive to roundoff: the same test gives
    // 371 -> 778.5 (x2.10) when `lbdem` is built alone and 229 -> 420 (x1.83) in a workspace build (feature
    // unification switches num-traits' float functions between libm and std, changing sin/cos/atan2 in the
    // last bit, and the first crack then starts elsewhere). So only "stronger bonds, clearly stronger
    // sample" is asserted here; the quantitative strength scaling is the uniaxial test's.
    assert!(ratio > 1.5, "ratio {ratio}");
}
