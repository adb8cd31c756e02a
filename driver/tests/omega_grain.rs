//! ΩΛ with free grains whose coverage leaves a node almost, but not quite, fully covered
//! (the `terzaghi` column of free grains once diverged under ΩΛ at such a node, `examples/omega_probe.rs`).
use lbdem::engine::coupled::{CoupledWorld, LatticeMap};
use lbdem::engine::dem::DemWorld;
use lbdem::engine::lattice::FluidLattice;
use lbdem_kernels::dem::assembly::ContactModel;
use lbdem_kernels::dem::shape::Particle;
use lbdem_kernels::fluid::boundary::Boundaries;
use lbdem_kernels::fluid::collide::{Collision, SolidOperator, Trt};
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::math::vector;

/// The fluid radius factor of the terzaghi scene.
const FLUID_RADIUS: f64 = 0.8;

/// One free disc of the terzaghi scene's grain 48 (lattice units: DEM radius 5.178, fluid radius 4.1427,
/// density ratio 2.65), centred at `center` in a periodic `n × n` box of fluid at rest (τ = 0.8, TRT at
/// Λ = 3/16, ΩΛ), given a small initial velocity and spin.
fn grain_world(center: [f64; 2], n: usize, collision: Collision<f64>) -> CoupledWorld {
    let mut fluid = FluidLattice::new(
        n,
        n,
        Boundaries::periodic(),
        FluidParams {
            tau: 0.8,
            force: [0.0; 2],
        },
    )
    .unwrap();
    fluid.set_collision(collision).unwrap();
    fluid.set_solid_operator(SolidOperator::LambdaConsistent);
    let mut disc = Particle::disc(
        vector(center[0], center[1]),
        4.142714773241218 / FLUID_RADIUS,
        2.65,
    );
    disc.velocity = vector(1e-5, -2e-6);
    disc.angular_velocity = 1e-6;
    let model = ContactModel {
        normal_stiffness: 1.0,
        shear_stiffness: 1.0,
        friction: 0.0,
        restitution: 1.0,
        no_tension: true,
    };
    let mut dem = DemWorld::new(vec![disc], model, 1.0).unwrap();
    dem.local_damping = 0.0;
    CoupledWorld::new(
        fluid,
        dem,
        LatticeMap::identity(),
        FLUID_RADIUS,
        SolidOperator::LambdaConsistent.weighting(),
        1,
    )
    .unwrap()
}

/// Steps until the lattice density leaves [0.9, 1.1] (None: it stayed inside for `steps`).
fn steps_to_divergence(world: &mut CoupledWorld, steps: u64) -> Option<u64> {
    for s in 1..=steps {
        world.step();
        if let Some((node, rho)) = world.fluid.health_check(0.9, 1.1) {
            eprintln!("step {s}: density {rho} at node {node}");
            return Some(s);
        }
    }
    None
}

/// A free rock grain (ρs/ρf = 2.65, τ = 0.8) placed so that one node of its cover is left 4.2e-5 (centre y =
/// 20.535) or 2.2e-5 (20.53) short of full cover, given 1e-5 of velocity in a periodic box: fluid and grain
/// must share that momentum and come to rest together. Before ΩΛ treated nodes this close to full cover as
/// fully covered (`LAMBDA_FULL_GAP`: 1e-3 first, 0.05 since packs needed it), such a node's partly-covered collision (local TRT rates
/// ω⁻ → 2 and ω⁺ → 0 as 1 − ε → 0, the node's fluid tied to the grain only by the bounded friction
/// β = κΛ⁺B) fed a period-2 oscillation of the grain (its velocity flipping sign every step) that grew
/// until the density left [0.9, 1.1] at step 5513 (resp. 4651): the grain 48 of the `terzaghi` column,
/// alone and without contacts (`examples/omega_probe.rs`).
#[test]
fn a_free_grain_with_a_nearly_full_node_is_stable_under_omega_lambda() {
    let trt = Collision::Trt(Trt::new(3.0 / 16.0).unwrap());
    for (y, gap) in [(20.535, 4.232e-5), (20.53, 2.225e-5)] {
        let mut w = grain_world([20.484, y], 40, trt);
        w.map_grains();
        // The placement is what the test is about: the smallest non-zero 1 − ε of the cover (4 digits, as
        // measured).
        let min_gap = w
            .fluid
            .solid_fraction_map()
            .iter()
            .filter(|&&e| e < 1.0)
            .map(|e| 1.0 - e)
            .fold(f64::INFINITY, f64::min);
        assert!(
            (min_gap - gap).abs() < 1e-3 * gap,
            "centre y = {y}: smallest gap {min_gap:e}, expected {gap:e}"
        );
        let p = &w.dem.particles[0];
        let (m, v0) = (p.mass, [p.velocity[0], p.velocity[1]]);
        let fluid_mass = w.fluid.mass();
        // 8000 steps: past both divergences (5513, 4651 steps) with margin.
        assert_eq!(
            steps_to_divergence(&mut w, 8000),
            None,
            "centre y = {y}: the density left [0.9, 1.1]"
        );
        // Momentum is shared: the coupling conserves fluid + grain momentum to roundoff, and after 8000 steps
        // the slowest shear mode of the box has decayed to e^(−8000 ν (2π/40)²) ≈ 3e-9 of its start, so grain
        // and fluid move together at m v0 / (m + M_fluid). Measured: 2e-7 relative off (the shear left and
        // roundoff of 8000 steps' sums over 1600 nodes); 1e-5 leaves a 50× margin and would still catch a
        // grain that kept any oscillation (the divergent one reached 1e-3, 1000× the shared velocity).
        let v = w.dem.particles[0].velocity;
        for a in 0..2 {
            let shared = m * v0[a] / (m + fluid_mass);
            assert!(
                (v[a] - shared).abs() < 1e-5 * shared.abs(),
                "centre y = {y}: grain velocity {} vs shared {shared:e}",
                v[a]
            );
        }
        assert!(
            w.dem.particles[0].angular_velocity.abs() < 1e-9,
            "centre y = {y}: spin {} (started at 1e-6; the fluid damps it)",
            w.dem.particles[0].angular_velocity
        );
    }
}

/// A **pack** of free rock grains under TRT + ΩΛ at τ = 2: the bundled Terzaghi column (seed 8, viscosity raised
/// to 0.5 cm²/s, i.e. τ = 0.5 + 3ν = 2), loaded and run 2 s past the step. With ΩΛ's full-cover gap at 1e-3
/// this column diverged at step 2500 (1 s after the step; seed 7 at step 6000, and a gap of 0.01 still diverged
/// there): nodes covered to 97–99.9 % took the partly covered rule, whose local ω⁻ tends to 2 as B → 1, the
/// sooner the larger τ. With the gap at 0.05 (`LAMBDA_FULL_GAP`) the column runs to its end at τ = 2 (measured
/// with seeds 7, 8 and 9, 5 s each), and its permeability is the column's at every τ (6.24e-5 cm² at τ = 0.8,
/// 1.4 and 2, seed 7; README). The run must finish, its prediction be finite and the pore pressure bounded by
/// the load (a diverging run stops with an error, and a mode growing without diverging would show in the
/// profiles).
#[test]
fn a_pack_of_free_rock_grains_runs_under_omega_lambda_at_tau_two() {
    use crate::common::scene_text::{scene, with};
    use lbdem::kinds::terzaghi::{self, Terzaghi};
    use lbdem::run::Case;
    let text = scene("terzaghi.toml").replace(
        "record_interval = 0.25   # s",
        "record_interval = 0.25   # s\nsolid_operator = \"lambda_consistent\"",
    );
    let text = with(
        &with(&with(&text, "viscosity", "0.5"), "seed", "8"),
        "duration",
        "2.0",
    );
    let case = Case::<Terzaghi>::read(&text, "t.toml").unwrap();
    assert!(
        (case.setup.units.tau - 2.0).abs() < 1e-9,
        "τ = {}",
        case.setup.units.tau
    );
    let (o, profiles) = terzaghi::simulate(&case).expect("the pack runs under ΩΛ at τ = 2");
    let p = &o.prediction;
    assert!(p.permeability.is_finite() && p.permeability > 0.0);
    assert!(p.consolidation_coefficient.is_finite());
    // p/σ₀ in every recorded row: Terzaghi's solution lies in [0, γ]; the start-up overshoots (the undrained
    // wave: base 0.63 against γ = 0.42 on the bundled scene, README), a growing period-2 mode would run far past
    // twice γ.
    for prof in &profiles {
        for r in &prof.rows {
            assert!(
                r[1].is_finite() && r[1].abs() < 2.0 * p.loading_efficiency,
                "pressure {} at depth {} (γ = {})",
                r[1],
                r[0],
                p.loading_efficiency
            );
        }
    }
}
