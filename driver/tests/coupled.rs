//! The coupled LB–DEM step: momentum balance of the partially-saturated coupling with a moving grain.
use lbdem::engine::coupled::{CoupledWorld, LatticeMap};
use lbdem::engine::dem::DemWorld;
use lbdem::engine::lattice::FluidLattice;
use lbdem_kernels::dem::assembly::ContactModel;
use lbdem_kernels::dem::shape::Particle;
use lbdem_kernels::fluid::boundary::Boundaries;
use lbdem_kernels::fluid::collide::Weighting;
use lbdem_kernels::fluid::step::FluidParams;

/// A free disc (radius 6, density 2 in lattice units) launched at `speed` along x (and spinning) into a fluid at
/// rest in a periodic 40 × 40 box.
fn launched_disc(speed: f64) -> CoupledWorld {
    let fluid = FluidLattice::new(
        40,
        40,
        Boundaries::periodic(),
        FluidParams {
            tau: 0.8,
            force: [0.0; 2],
        },
    )
    .unwrap();
    let mut disc = Particle::disc(lbdem_kernels::math::vector(19.6, 20.3), 6.0, 2.0);
    disc.velocity = lbdem_kernels::math::vector(speed, 0.3 * speed);
    disc.angular_velocity = 1e-3;
    let model = ContactModel {
        normal_stiffness: 1.0,
        shear_stiffness: 1.0,
        friction: 0.5,
        restitution: 1.0,
        no_tension: true,
    };
    let mut dem = DemWorld::new(vec![disc], model, 1.0).unwrap();
    dem.local_damping = 0.0; // local damping removes momentum on its own (docs/references.md §7.3): off for this check
    CoupledWorld::new(
        fluid,
        dem,
        LatticeMap::identity(),
        1.0,
        Weighting::NobleTorczynski,
        1,
    )
    .unwrap()
}

fn total_momentum(w: &CoupledWorld) -> [f64; 2] {
    let j = w.fluid.momentum();
    let p = &w.dem.particles[0];
    [j[0] + p.mass * p.velocity[0], j[1] + p.mass * p.velocity[1]]
}

#[test]
fn a_free_disc_and_the_fluid_conserve_total_momentum_to_roundoff() {
    let mut world = launched_disc(0.01);
    let p0 = total_momentum(&world);
    let v0 = world.dem.particles[0].velocity[0];
    let mass = world.dem.particles[0].mass;
    for step in 0..400 {
        world.step();
        let p = total_momentum(&world);
        // Each step moves ~1e-3 of momentum between fluid and grain; PSM hands over exactly what the fluid loses
        // and the leapfrog turns it into exactly m Δv, so only roundoff of sums over 1600 nodes remains
        // (~1e-16 × 1600 × |f| ≈ 1e-13 per step); 1e-11 bounds 400 steps.
        for a in 0..2 {
            assert!(
                (p[a] - p0[a]).abs() < 1e-11,
                "step {step}: momentum {p:?} vs {p0:?}"
            );
        }
    }
    // The fluid drags the disc: it slows down, and the fluid picks up the momentum it lost.
    let v = world.dem.particles[0].velocity[0];
    assert!(
        v < 0.9 * v0 && v > 0.0,
        "disc velocity {v} (started at {v0})"
    );
    let j = world.fluid.momentum();
    assert!((j[0] - mass * (v0 - v)).abs() < 1e-11);
    // The spinning disc feels a resisting torque.
    assert!(world.dem.particles[0].angular_velocity < 1e-3);
}

/// Eight ellipse grains (two of them overlapping, some crossing the pressure sides) drifting and spinning
/// through a fluid with a pressure drop, f64 or f32 fluid. Solid operator Ω₁ₗ (linearised Ω₁, the fracture scenes' default): with Ω₃
/// (`MovingWallBounceBack`) this scene diverges after ~70 steps (the density inside grain 0 leaves [0.9, 1.1] at step 70
/// and the grains fly off at step 140), a stability question of Ω₃ with moving grains, not of the re-mapping.
fn drifting_ellipses<T: lbdem_kernels::Real>() -> CoupledWorld<T> {
    use lbdem_kernels::fluid::boundary::SideCondition;
    use lbdem_kernels::fluid::collide::SolidOperator;
    let bc = Boundaries {
        west: SideCondition::Pressure {
            density: T::lit(1.002),
        },
        east: SideCondition::Pressure { density: T::one() },
        south: SideCondition::Wall,
        north: SideCondition::Wall,
    };
    let params = FluidParams {
        tau: T::lit(0.8),
        force: [T::zero(); 2],
    };
    let mut fluid = FluidLattice::<T>::new(64, 40, bc, params).unwrap();
    fluid.set_solid_operator(SolidOperator::LinearizedNonEquilibriumBounceBack);
    let grains = (0..8)
        .map(|k| {
            let t = k as f64;
            // Two rows of four, 12 apart (semi-major 5: no contacts at first); grain 7 straddles the west side.
            let x = if k == 7 {
                1.5
            } else {
                8.0 + 12.0 * (k % 4) as f64
            };
            let y = 11.0 + 16.0 * (k / 4) as f64 + 0.3 * t;
            let mut p =
                Particle::ellipse(lbdem_kernels::math::vector(x, y), 0.4 * t, 5.0, 2.5, 20.0);
            p.velocity = lbdem_kernels::math::vector(0.02 - 0.004 * t, 0.01 * (t - 3.5) / 3.5);
            p.angular_velocity = 0.004 * (t - 4.0);
            p
        })
        .collect();
    let model = ContactModel {
        normal_stiffness: 0.5,
        shear_stiffness: 0.5,
        friction: 0.5,
        restitution: 0.5,
        no_tension: true,
    };
    let dem = DemWorld::new(grains, model, 1.0).unwrap();
    CoupledWorld::new(
        fluid,
        dem,
        LatticeMap::identity(),
        0.8,
        Weighting::NobleTorczynski,
        1,
    )
    .unwrap()
}

fn incremental_remapping_leaves_the_coupled_step_unchanged<T: lbdem_kernels::Real>() {
    let mut incremental = drifting_ellipses::<T>();
    let mut scratch = drifting_ellipses::<T>();
    incremental.enable_timings();
    for step in 0..150 {
        incremental.step();
        // Re-map every grain from scratch (no buffers kept from the last step).
        scratch.fluid.clear_coverage();
        scratch.step();
        let same_grains = incremental
            .dem
            .particles
            .iter()
            .zip(&scratch.dem.particles)
            .all(|(a, b)| {
                a.position == b.position
                    && a.velocity == b.velocity
                    && a.angle.to_bits() == b.angle.to_bits()
                    && a.angular_velocity.to_bits() == b.angular_velocity.to_bits()
            });
        assert!(same_grains, "step {step}: grains differ");
        let same_fluid = incremental
            .fluid
            .populations()
            .iter()
            .zip(scratch.fluid.populations().iter())
            .all(|(a, b)| a.to_f64_exact().to_bits() == b.to_f64_exact().to_bits());
        assert!(same_fluid, "step {step}: populations differ");
    }
    // The grains moved (the comparison covered re-mapping onto new cells) and the fluid pushed them.
    let moved = incremental.dem.particles[0].position[0] - 8.0;
    assert!(moved > 0.5 && moved < 10.0, "grain 0 moved by {moved}");
    assert!(incremental.fluid.covered_nodes() > 200);
    let t = incremental.timings().unwrap();
    assert_eq!(t.steps, 150);
    assert!(t.total() > std::time::Duration::ZERO);
    assert!(scratch.timings().is_none());
}

#[test]
fn incremental_remapping_is_bitwise_a_full_remapping_in_the_coupled_step() {
    incremental_remapping_leaves_the_coupled_step_unchanged::<f64>();
    incremental_remapping_leaves_the_coupled_step_unchanged::<f32>();
}

/// A fluid divergence with grains reaching past the lattice's non-periodic sides says so in its hint (every
/// solid operator was measured to diverge where solids sweep through a wall or Zou–He side: README, *ΩΛ's
/// wall-pressure form*); without such grains the hint is the kind's alone. `drifting_ellipses`' grain 7
/// straddles the west (Zou–He pressure) side: centre x = 1.5, semi-major 5 × 0.8 at 2.8 rad, so it reaches
/// about 2.3 spacings past x = 0.
#[test]
fn a_divergence_names_grains_that_cross_the_lattices_sides() {
    use lbdem::error::LbdemError;
    use lbdem::observe::health::{coupled_health, grains_past_sides, SIDE_CROSSING_MARGIN};
    use lbdem_kernels::fluid::lattice::Side;
    let hint_of = |world: &mut CoupledWorld| {
        world.map_grains();
        assert!(coupled_health(world, "kind's hint").is_ok());
        world.fluid.populations_mut()[5 * 9] = f64::NAN;
        match coupled_health(world, "kind's hint") {
            Err(LbdemError::Diverged { hint, .. }) => hint,
            other => panic!("{other:?}"),
        }
    };
    let mut world = drifting_ellipses::<f64>();
    let hint = hint_of(&mut world);
    assert!(
        hint.starts_with("kind's hint; 1 grain(s) reach past the lattice's sides")
            && hint.contains("grain 7 past the west side (Zou-He pressure)"),
        "{hint}"
    );
    // Grain 7 moved inside: the kind's hint alone.
    let mut inside = drifting_ellipses::<f64>();
    inside.dem.particles[7].position[0] = 20.0;
    inside.dem.particles[7].position[1] = 20.0;
    assert_eq!(hint_of(&mut inside), "kind's hint");
    // The margin: a disc of radius 3 whose edge lies just inside / just beyond SIDE_CROSSING_MARGIN past the
    // edge of the cells (x = −0.5) of a walled south side and a periodic west side.
    use lbdem_kernels::coupling::{BodyShape, CoupledBody};
    use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
    let bc = Boundaries::<f64> {
        west: SideCondition::Periodic,
        east: SideCondition::Periodic,
        south: SideCondition::Wall,
        north: SideCondition::Wall,
    };
    let disc = |x: f64, y: f64| CoupledBody {
        center: lbdem_kernels::math::vector(x, y),
        velocity: lbdem_kernels::math::vector(0.0, 0.0),
        spin: 0.0,
        shape: BodyShape::Disc { radius: 3.0 },
    };
    let edge = 3.0 - 0.5 - SIDE_CROSSING_MARGIN;
    let bodies = [
        disc(10.0, edge + 1e-9),
        disc(10.0, edge - 1e-9),
        disc(-5.0, 10.0),
        disc(10.0, 39.0 - edge + 1e-9),
        disc(10.0, 39.0 - edge - 1e-9),
    ];
    assert_eq!(
        grains_past_sides(&bodies, &bc, 20, 40),
        vec![(1, Side::South), (3, Side::North)]
    );
}
