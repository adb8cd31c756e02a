//! The coupled LB–DEM step: momentum balance of the partially-saturated coupling with a moving grain.
use lbdem::coupled::{CoupledWorld, LatticeMap};
use lbdem::lattice::FluidLattice;
use lbdem::solid::DemWorld;
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
    let mut disc = Particle::disc([19.6, 20.3], 6.0, 2.0);
    disc.velocity = [speed, 0.3 * speed];
    disc.angular_velocity = 1e-3;
    let model = ContactModel {
        normal_stiffness: 1.0,
        shear_stiffness: 1.0,
        friction: 0.5,
        restitution: 1.0,
        no_tension: true,
    };
    let mut dem = DemWorld::new(vec![disc], model, 1.0).unwrap();
    dem.local_damping = 0.0; // local damping removes momentum on its own (REFERENCE §7.3): off for this check
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
