//! The coupled benchmark scene (shared by `benches/coupled.rs` and `examples/coupled_split.rs` through
//! `#[path]`): the fracture test's size, ~1000 bonded ellipse grains (aspect 0.5, the dissertation's ch. 6.6
//! sizes) packed by [`generate_packing`] in a 2:1 box, mapped onto an `nx × ny` lattice spanning the box, a small
//! pressure drop west → east (Zou–He), walls north and south, the Ω₁ₗ solid operator (`LinearizedNonEquilibriumBounceBack`).
use lbdem::engine::coupled::{CoupledWorld, LatticeMap};
use lbdem::engine::dem::packing::{generate_packing, PackingSpec};
use lbdem::engine::dem::world::{BondSpec, DemWorld};
use lbdem::engine::lattice::FluidLattice;
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::{SolidOperator, Weighting};
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::Real;

/// Box width (cm): with the ch. 6.6 sizes (semi-major axis 0.07–0.11 cm, aspect 0.5) and a solid fraction of
/// 0.82, a 5.6 × 2.8 cm box holds about 1000 grains.
pub const WIDTH: f64 = 5.6;
/// Box height (cm).
pub const HEIGHT: f64 = 2.8;

/// The bonded packing (f64 DEM), generated once per process (a few seconds).
/// The streaming scheme of the benchmark lattices: `LBDEM_STREAMING` (aa or two-lattice), default aa.
pub fn streaming() -> lbdem::engine::lattice::Streaming {
    std::env::var("LBDEM_STREAMING")
        .ok()
        .and_then(|v| lbdem::engine::lattice::Streaming::from_name(&v))
        .unwrap_or_default()
}

pub fn packed_grains() -> DemWorld<f64> {
    let mut spec = PackingSpec::dissertation(WIDTH, HEIGHT, 0.5, 7);
    // A looser stress tolerance and fewer servo steps keep the setup short; the bench measures the step, not
    // the quality of the packing.
    spec.growth_steps = 1000;
    spec.max_servo_steps = 6000;
    spec.stress_tolerance = 0.5;
    // Bond pairs closer than a tenth of the smallest semi-major axis (the loose packing leaves small gaps).
    spec.bond_gap = 7e-3;
    let bonds = BondSpec::Point {
        stiffness: 1e5,
        strength: 1e3,
    };
    generate_packing(&spec, Some(bonds))
        .expect("packing the benchmark grains")
        .world
}

/// The benchmark lattice without grains (BGK, τ = 0.8): a small pressure drop west → east (Zou–He), walls
/// north and south, the streaming scheme of [`streaming`]. The coupled world's fluid, and the plain lattice the
/// examples compare it with.
pub fn plain_lattice<T: Real>(nx: usize, ny: usize) -> FluidLattice<T> {
    let bc = Boundaries {
        west: SideCondition::Pressure {
            density: T::lit(1.001),
        },
        east: SideCondition::Pressure {
            density: T::lit(1.0),
        },
        south: SideCondition::Wall,
        north: SideCondition::Wall,
    };
    let params = FluidParams {
        tau: T::lit(0.8),
        force: [T::zero(); 2],
    };
    let mut fluid = FluidLattice::<T>::new(nx, ny, bc, params).expect("benchmark lattice");
    fluid.set_streaming(streaming());
    fluid
}

/// A coupled world on an `nx × ny` lattice (precision `T`) over the packing `dem`, fluid radius
/// `fluid_radius`, solid operator Ω₁ₗ.
pub fn coupled_world<T: Real>(
    dem: &DemWorld<f64>,
    nx: usize,
    ny: usize,
    fluid_radius: f64,
) -> CoupledWorld<T> {
    let mut fluid = plain_lattice::<T>(nx, ny);
    fluid.set_solid_operator(SolidOperator::LinearizedNonEquilibriumBounceBack);
    // Lattice nodes span the box: node (0, 0) at (0, 0), node (nx − 1, ny − 1) at (W, H) (h from the width).
    let map = LatticeMap {
        spacing: WIDTH / (nx - 1) as f64,
        timestep: dem.timestep(),
        density: 1.0,
        origin: [0.0; 2],
    };
    CoupledWorld::new(
        fluid,
        dem.clone(),
        map,
        fluid_radius,
        Weighting::NobleTorczynski,
        1,
    )
    .expect("benchmark coupled world")
}
