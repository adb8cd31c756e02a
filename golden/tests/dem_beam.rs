//! Golden snapshot of a small bonded beam (dissertation ch. 6.6 point bonds, eq. 6.13, table 6.1 values) in
//! three-point bending, run through `lbdem::engine::dem::DemWorld`: 12 × 3 discs (radius 0.1 cm, 2.65 g/cm³) on a
//! triangular lattice, every touching pair bonded (k_b = 1e5 dyne/cm, F_crit = 700 dyne), contacts
//! k_n = 1e5, k_s = 6e5 dyne/cm, frictionless; the two bottom corner discs are held (`DemWorld::held`) and
//! the middle disc of the top row carries 200 dyne downwards; 10 000 steps of 5e-5 s with local damping 0.7
//! bring it to static equilibrium. Values are rounded to 6 significant digits. The step is bitwise
//! deterministic for any thread count, but not across builds: `cargo test -p lbdem-golden` and
//! `cargo test --workspace` unify num-traits' features differently (libm or std sin/cos/hypot, last-bit
//! differences), and a ringing or frictional (path-dependent) state amplifies those to the 4th digit
//! (measured). So the snapshot is taken at rest and without friction, where the state is the unique elastic
//! equilibrium. A changed snapshot is reviewed, never blindly accepted.
use lbdem::engine::dem::{hexagonal_packing, BondSpec, DemWorld};
use lbdem_kernels::dem::assembly::ContactModel;

fn sig6(v: f64) -> String {
    format!("{v:.5e}")
}

#[test]
fn bonded_beam_in_three_point_bending() {
    let (columns, rows) = (12, 3);
    let particles = hexagonal_packing(columns, rows, 0.1, 1.0, 0.0, 2.65, 0);
    let model = ContactModel {
        normal_stiffness: 1e5,
        shear_stiffness: 6e5,
        friction: 0.0,
        restitution: 1.0,
        no_tension: true,
    };
    let mut world = DemWorld::new(particles, model, 5e-5).unwrap();
    world.held[0] = true;
    world.held[columns - 1] = true;
    let bonds = world
        .bond_touching_pairs(
            BondSpec::Point {
                stiffness: 1e5,
                strength: 700.0,
            },
            1e-6,
        )
        .unwrap();
    let loaded = (rows - 1) * columns + columns / 2;
    world.external_force[loaded] = lbdem_kernels::math::vector(0.0, -200.0);
    let start: Vec<lbdem_kernels::math::Vector<f64>> =
        world.particles.iter().map(|p| p.position).collect();
    for _ in 0..10_000 {
        world.step();
    }
    let mut out = format!(
        "bonds {bonds}, intact {}, breaks {}, critical step {}\n",
        world.intact_bonds(),
        world.breaks.len(),
        sig6(world.critical_time_step())
    );
    out += "bottom row: column, displacement x, displacement y (cm)\n";
    for (c, (p, s)) in world.particles.iter().zip(&start).take(columns).enumerate() {
        out += &format!(
            "{c:2} {} {}\n",
            sig6(p.position[0] - s[0]),
            sig6(p.position[1] - s[1])
        );
    }
    let p = &world.particles[loaded];
    out += &format!(
        "loaded disc: displacement y {}, rotation {}\n",
        sig6(p.position[1] - start[loaded][1]),
        sig6(p.angle)
    );
    out += &format!("active contacts {}\n", world.active_contacts());
    insta::assert_snapshot!(out);
}
