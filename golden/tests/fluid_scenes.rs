//! Golden snapshots of two tiny deterministic fluid scenes. Values are printed to 9 significant digits: the
//! kernels use only correctly rounded IEEE operations (Rust never contracts to FMA), so results are bitwise
//! reproducible across platforms and thread counts; 9 digits keep the snapshots readable while any change to
//! a kernel's arithmetic beyond roundoff-level reordering shows up. A changed snapshot is reviewed, never
//! blindly accepted (CI runs insta with CI=true, which fails on a changed or missing snapshot).
use lbdem::engine::lattice::{FluidDisc, FluidLattice};
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::Weighting;
use lbdem_kernels::fluid::step::FluidParams;

fn sig9(v: f64) -> String {
    format!("{v:.8e}")
}

#[test]
fn pressure_driven_channel_64x32_after_400_steps() {
    let bc = Boundaries {
        west: SideCondition::Pressure { density: 1.005 },
        east: SideCondition::Pressure { density: 0.995 },
        south: SideCondition::Wall,
        north: SideCondition::Wall,
    };
    let mut lattice = FluidLattice::<f64>::new(
        64,
        32,
        bc,
        FluidParams {
            tau: 0.8,
            force: [0.0; 2],
        },
    )
    .unwrap();
    for _ in 0..400 {
        lattice.step();
    }
    let (rho, u) = lattice.moments();
    let s = *lattice.shape();
    let mut out = String::from("mid cross-section x = 32: y, rho, ux, uy\n");
    for y in 0..s.ny {
        let n = s.index(32, y);
        out += &format!(
            "{y:2} {} {} {}\n",
            sig9(rho[n]),
            sig9(u[n][0]),
            sig9(u[n][1])
        );
    }
    out += "centreline y = 16: x, rho, ux\n";
    for x in (0..s.nx).step_by(7) {
        let n = s.index(x, 16);
        out += &format!("{x:2} {} {}\n", sig9(rho[n]), sig9(u[n][0]));
    }
    out += &format!("total mass {}\n", sig9(lattice.mass()));
    insta::assert_snapshot!(out);
}

#[test]
fn periodic_box_with_one_fixed_psm_disc_under_body_force() {
    let mut lattice = FluidLattice::<f64>::new(
        40,
        40,
        Boundaries::periodic(),
        FluidParams {
            tau: 0.875,
            force: [2e-6, 0.0],
        },
    )
    .unwrap();
    let disc = FluidDisc {
        center: [19.7, 20.2],
        radius: 8.4,
        velocity: [0.0; 2],
        spin: 0.0,
    };
    lattice.cover_with_discs(&[disc], Weighting::NobleTorczynski);
    for _ in 0..300 {
        lattice.step();
    }
    let (rho, u) = lattice.moments();
    let s = *lattice.shape();
    let force = lattice.solid_forces(1)[0];
    let mut out = format!(
        "covered nodes {}\nforce on disc {} {}\ntotal mass {}\nline x = 3: y, rho, ux, uy\n",
        lattice.covered_nodes(),
        sig9(force[0]),
        sig9(force[1]),
        sig9(lattice.mass())
    );
    for y in (0..s.ny).step_by(3) {
        let n = s.index(3, y);
        out += &format!(
            "{y:2} {} {} {}\n",
            sig9(rho[n]),
            sig9(u[n][0]),
            sig9(u[n][1])
        );
    }
    insta::assert_snapshot!(out);
}
