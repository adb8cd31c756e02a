//! Exploratory probe for case 3 of issue 4 item 3 (Terzaghi consolidation, dissertation §5.6.3–5.6.4,
//! fig. 5.10–5.13). **Not a validated case**: it prints what the coupled model does, so the next step (a scene
//! kind and a test) can be designed. See /work/reports/poro.md.
//!
//! A hexagonal pack of 10 × 8 free discs (radius 5 nodes, the fluid sees 0.8 of it) in a box of DEM platens,
//! top platen removed, step load σ applied to the top row of grains as forces; fluid walls west/east/south,
//! Zou–He P = 0 at the north, 12 rows of fluid above the grains (drained top). Lattice units throughout
//! (`LatticeMap::identity`-like map). Prints the fluid-only mean pore pressure of the bottom 12 rows over σ and
//! the time of its peak.
//!
//! `cargo run --release -p lbdem --example terzaghi_probe -- K_N SIGMA TAU STEPS OMEGA3(0|1)`
//! e.g. `-- 1.0 2e-3 0.8 8000 0`.
use lbdem::coupled::{CoupledWorld, LatticeMap};
use lbdem::lattice::FluidLattice;
use lbdem::solid::{boxed_sample, hexagonal_packing};
use lbdem_kernels::dem::assembly::ContactModel;
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::{SolidOperator, Weighting};
use lbdem_kernels::fluid::step::FluidParams;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse::<f64>())
        .collect::<Result<_, _>>()?;
    if args.len() != 5 {
        return Err("usage: terzaghi_probe K_N SIGMA TAU STEPS OMEGA3(0|1)".into());
    }
    let (kn, sigma, tau, steps) = (args[0], args[1], args[2], args[3] as u64);
    let r = 5.0;
    let parts = hexagonal_packing(10, 8, r, 1.0, 0.05, 2.65, 3);
    let model = ContactModel {
        normal_stiffness: kn,
        shear_stiffness: kn,
        friction: 0.5,
        restitution: 1.0,
        no_tension: true,
    };
    // DEM sub-steps so that Δt/substeps stays below the critical step for stiff contacts.
    let substeps = (kn / 2.0).sqrt().ceil().max(1.0) as u32;
    let mut pk = boxed_sample(parts, model, 1.0 / substeps as f64, None, 0.0)?;
    let (lo, hi) = pk.world.bounds();
    pk.world.platens[pk.sample_box.top].active = false;
    let tops = pk.world.boundary_particles(3, 0.5 * r);
    let width = hi[0] - lo[0];
    let total_r: f64 = tops
        .iter()
        .map(|&i| pk.world.particles[i].shape.bounding_radius())
        .sum();
    let nx = width.round() as usize;
    let ny = (hi[1] - lo[1]).round() as usize + 12;
    let w = SideCondition::Wall;
    let mut fluid = FluidLattice::<f64>::new(
        nx,
        ny,
        Boundaries {
            west: w,
            east: w,
            south: w,
            north: SideCondition::Pressure { density: 1.0 },
        },
        FluidParams {
            tau,
            force: [0.0; 2],
        },
    )?;
    fluid.set_solid_operator(if args[4] > 0.0 {
        SolidOperator::BounceBack
    } else {
        SolidOperator::NonEquilibriumBounceBack
    });
    let map = LatticeMap {
        spacing: 1.0,
        timestep: 1.0,
        density: 1.0,
        origin: [lo[0] - 0.5, lo[1] - 0.5],
    };
    let mut world = CoupledWorld::new(
        fluid,
        pk.world,
        map,
        0.8,
        Weighting::NobleTorczynski,
        substeps,
    )?;
    for &i in &tops {
        let share = sigma * width * world.dem.particles[i].shape.bounding_radius() / total_r;
        world.applied[i] = ([0.0, -share], 0.0);
    }
    let mut peak = (0u64, f64::MIN);
    for s in 1..=steps {
        world.step();
        if s.is_multiple_of(10) {
            let eps = world.fluid.solid_fraction_map();
            let (rho, _) = world.fluid.moments();
            let (mut sum, mut n) = (0.0, 0usize);
            for y in 0..12 {
                for x in 0..nx {
                    let i = y * nx + x;
                    if eps[i] == 0.0 {
                        sum += rho[i];
                        n += 1;
                    }
                }
            }
            let p = (sum / n as f64 - 1.0) / 3.0;
            if p > peak.1 {
                peak = (s, p);
            }
            if s.is_multiple_of(1000) {
                println!(
                    "step {s}: bottom pore pressure / sigma {:.4}, fluid mass {:.3}",
                    p / sigma,
                    world.fluid.mass()
                );
            }
        }
    }
    println!(
        "peak bottom pore pressure {:.4} sigma at step {}",
        peak.1 / sigma,
        peak.0
    );
    Ok(())
}
