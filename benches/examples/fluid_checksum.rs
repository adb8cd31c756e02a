//! Bitwise fingerprint of the fluid step: runs a few small lattices (periodic BGK; walls, Zou–He pressure sides,
//! obstacle nodes, body force and PSM-covered discs) for a fixed number of steps in f32 and f64 and prints an
//! FNV-1a hash of the population bits. A kernel optimisation that claims to keep the arithmetic unchanged must
//! print the same hashes before and after: `cargo run --release -p lbdem-benches --example fluid_checksum`.
use lbdem::engine::lattice::{FluidDisc, FluidLattice};
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::Weighting;
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::Real;

fn fnv1a(bits: impl Iterator<Item = u64>) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bits {
        for byte in b.to_le_bytes() {
            h ^= u64::from(byte);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

fn periodic<T: Real>() -> FluidLattice<T> {
    let params = FluidParams {
        tau: T::lit(0.8),
        force: [T::zero(); 2],
    };
    let mut l = FluidLattice::new(67, 45, Boundaries::periodic(), params).expect("lattice");
    l.fill_equilibrium(|x, y| {
        let (x, y) = (x as f64, y as f64);
        (
            T::lit(1.0 + 0.01 * (0.3 * x).cos()),
            [
                T::lit(0.02 * (0.2 * y).sin()),
                T::lit(0.015 * (0.17 * x + 0.1 * y).cos()),
            ],
        )
    });
    l
}

fn mixed<T: Real>(forced: bool) -> FluidLattice<T> {
    let bc = Boundaries {
        west: SideCondition::Pressure {
            density: T::lit(1.01),
        },
        east: SideCondition::Pressure {
            density: T::lit(0.99),
        },
        south: SideCondition::Wall,
        north: SideCondition::Wall,
    };
    let force = if forced {
        [T::lit(1e-6), T::lit(-2e-7)]
    } else {
        [T::zero(); 2]
    };
    let params = FluidParams {
        tau: T::lit(0.7),
        force,
    };
    let mut l = FluidLattice::new(48, 37, bc, params).expect("lattice");
    l.set_solid(|x, y| (x == 30 && (10..20).contains(&y)) || (x + y) % 23 == 0 && y > 30);
    l.cover_with_discs(
        &[
            FluidDisc {
                center: [12.3, 17.6],
                radius: 6.2,
                velocity: [0.01, 0.0],
                spin: 0.001,
            },
            FluidDisc {
                center: [20.1, 20.4],
                radius: 4.0,
                velocity: [0.0, -0.005],
                spin: 0.0,
            },
        ],
        Weighting::NobleTorczynski,
    );
    l
}

fn fingerprint<T: Real>(name: &str, mut l: FluidLattice<T>, discs: usize) {
    for _ in 0..200 {
        l.step();
    }
    let pops = fnv1a(l.populations().iter().map(|v| v.to_f64_exact().to_bits()));
    let forces = fnv1a(
        l.solid_forces(discs)
            .iter()
            .flat_map(|f| [f[0].to_bits(), f[1].to_bits()]),
    );
    println!(
        "{name:<16} {:<4} populations {pops:016x} forces {forces:016x}",
        T::NAME
    );
}

fn main() {
    fingerprint("periodic", periodic::<f64>(), 0);
    fingerprint("periodic", periodic::<f32>(), 0);
    fingerprint("mixed", mixed::<f64>(false), 2);
    fingerprint("mixed", mixed::<f32>(false), 2);
    fingerprint("mixed+force", mixed::<f64>(true), 2);
    fingerprint("mixed+force", mixed::<f32>(true), 2);
}
