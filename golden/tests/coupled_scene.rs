//! Golden snapshot of a tiny coupled scene with moving grains: the safety net for moving the driver's code
//! around. Six bonded ellipses and two free discs in a periodic 56 × 44 lattice under a body force (lattice
//! units); the grains are pushed towards each other so that they collide (contacts), pull bonds until some
//! break, and drag and are dragged by the fluid through the partially-saturated coupling (Ω₁ₗ, B of eq. 4.5).
//! 300 coupled steps.
//!
//! The snapshot holds the bit patterns of the whole state, hashed (FNV-1a over the IEEE-754 bits of every
//! grain's position, angle, velocities and accelerations, of every population, and of every bond's state),
//! and a few values printed in full precision (shortest round-trip form). Any change of a single bit anywhere
//! in the coupled step (coverage, collision, streaming, momentum exchange, contacts, bonds, integration, and
//! their summation orders) changes it. The step is bitwise deterministic for any thread count, SIMD level and
//! streaming scheme, and in every build (transcendental functions go through `libm`), so the snapshot holds
//! across all of them. A changed snapshot is reviewed, never blindly accepted.
use lbdem::engine::coupled::{CoupledWorld, LatticeMap};
use lbdem::engine::dem::world::{BondLaw, BondSpec};
use lbdem::engine::dem::DemWorld;
use lbdem::engine::lattice::FluidLattice;
use lbdem_kernels::dem::assembly::ContactModel;
use lbdem_kernels::dem::shape::Particle;
use lbdem_kernels::fluid::boundary::Boundaries;
use lbdem_kernels::fluid::collide::{SolidOperator, Weighting};
use lbdem_kernels::fluid::step::FluidParams;

/// FNV-1a, 64 bits, over a stream of 64-bit words.
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn word(&mut self, w: u64) {
        for b in w.to_le_bytes() {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    fn f(&mut self, v: f64) {
        self.word(v.to_bits());
    }
}

fn scene() -> CoupledWorld {
    let fluid = FluidLattice::new(
        56,
        44,
        Boundaries::periodic(),
        FluidParams {
            tau: 0.8,
            force: [2e-6, -1e-6],
        },
    )
    .unwrap();
    // A bonded cluster of 3 × 2 ellipses (aspect 0.6, semi-major 3.5) near the left, two free discs to its right.
    let mut grains: Vec<Particle<f64>> =
        lbdem::engine::dem::hexagonal_packing(3, 2, 3.5, 0.6, 0.0, 2.0, 0)
            .into_iter()
            .map(|mut p| {
                p.position = lbdem_kernels::math::vector(p.position[0] + 8.3, p.position[1] + 14.1);
                p.velocity = lbdem_kernels::math::vector(0.004, 0.0005);
                p
            })
            .collect();
    let mut a = Particle::disc(lbdem_kernels::math::vector(36.4, 18.7), 3.2, 2.0);
    a.velocity = lbdem_kernels::math::vector(-0.012, 0.001);
    a.angular_velocity = 2e-3;
    let mut b = Particle::disc(lbdem_kernels::math::vector(44.9, 21.2), 2.8, 2.5);
    b.velocity = lbdem_kernels::math::vector(-0.01, -0.0015);
    grains.push(a);
    grains.push(b);
    let model = ContactModel {
        normal_stiffness: 0.5,
        shear_stiffness: 0.4,
        friction: 0.5,
        restitution: 0.8,
        no_tension: true,
    };
    let mut dem = DemWorld::new(grains, model, 1.0).unwrap();
    dem.local_damping = 0.0;
    // Bond the cluster (the discs are far away), weak enough that the collision breaks some bonds.
    let bonds = dem
        .bond_touching_pairs(
            BondSpec::Point {
                stiffness: 0.3,
                strength: 2e-3,
            },
            0.05,
        )
        .unwrap();
    assert!(bonds >= 5, "the cluster is bonded ({bonds} bonds)");
    let mut world = CoupledWorld::new(
        fluid,
        dem,
        LatticeMap::identity(),
        0.9,
        Weighting::NobleTorczynski,
        1,
    )
    .unwrap();
    world
        .fluid
        .set_solid_operator(SolidOperator::LinearizedNonEquilibriumBounceBack);
    world
}

#[test]
fn coupled_grains_collide_break_bonds_and_drag_the_fluid() {
    let mut world = scene();
    let mut max_contacts = 0;
    for _ in 0..300 {
        world.step();
        max_contacts = max_contacts.max(world.dem.active_contacts());
    }
    let dem = &world.dem;
    let mut grains = Fnv::new();
    for p in &dem.particles {
        for v in [
            p.position[0],
            p.position[1],
            p.angle,
            p.velocity[0],
            p.velocity[1],
            p.angular_velocity,
            p.acceleration[0],
            p.acceleration[1],
            p.angular_acceleration,
        ] {
            grains.f(v);
        }
    }
    let mut bonds = Fnv::new();
    for b in &dem.bonds {
        bonds.word(b.intact() as u64);
        if let BondLaw::Point(p) = &b.law {
            for v in [
                p.rest_gap[0],
                p.rest_gap[1],
                p.rest_angles[0],
                p.rest_angles[1],
            ] {
                bonds.f(v);
            }
        }
    }
    let mut populations = Fnv::new();
    for &f in world.fluid.populations().iter() {
        populations.f(f);
    }
    let j = world.fluid.momentum();
    let mut out = format!(
        "steps {}, covered nodes {}, most contacts at once {max_contacts}, bonds {} intact of {}, breaks {}\n",
        world.steps(),
        world.fluid.covered_nodes(),
        dem.intact_bonds(),
        dem.bonds.len(),
        dem.breaks.len()
    );
    out += &format!(
        "hash of grain states {:016x}\nhash of populations {:016x}\nhash of bonds {:016x}\n",
        grains.0, populations.0, bonds.0
    );
    out += &format!(
        "fluid mass {:?}\nfluid momentum {:?} {:?}\n",
        world.fluid.mass(),
        j[0],
        j[1]
    );
    for (i, p) in dem.particles.iter().enumerate() {
        out += &format!(
            "grain {i}: x {:?} {:?} angle {:?} v {:?} {:?} w {:?}\n",
            p.position[0], p.position[1], p.angle, p.velocity[0], p.velocity[1], p.angular_velocity
        );
    }
    for b in &dem.breaks {
        out += &format!(
            "break at step {} of pair {:?}, load {:?}\n",
            b.step, b.pair, b.load
        );
    }
    // The scene does what it is for: grains touch, bonds break, the fluid moves.
    assert!(max_contacts > 0, "no contact in the scene:\n{out}");
    assert!(!dem.breaks.is_empty(), "no bond broke:\n{out}");
    insta::assert_snapshot!(out);
}
