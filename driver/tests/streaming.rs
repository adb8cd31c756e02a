//! The in-place (AA) scheme and the two-lattice scheme give bitwise the same populations, moments and forces on
//! solids after every step, on every kind of node: periodic seams, walls, Zou–He pressure and velocity sides and
//! their corners, obstacle nodes, and nodes covered by moving solids. The AA buffer holds the values at other
//! places after odd steps; `populations()` gathers them back, and that too is compared.
use lbdem::engine::lattice::{FluidDisc, FluidLattice, Streaming};
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::{SolidOperator, Weighting};
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::Real;
use proptest::prelude::*;

fn bits<T: Real>(v: &[T]) -> Vec<u64> {
    v.iter().map(|x| x.to_f64_exact().to_bits()).collect()
}

/// Everything a step produces, as bit patterns: populations (two-lattice layout), density and velocity of
/// every node, mass, momentum, and the force and torque on each covering body.
fn state<T: Real>(l: &FluidLattice<T>, bodies: usize) -> Vec<u64> {
    let mut out = bits(&l.populations());
    let (rho, u) = l.moments();
    out.extend(bits(&rho));
    out.extend(u.iter().flat_map(|v| bits(v)));
    out.push(l.mass().to_bits());
    out.extend(l.momentum().map(f64::to_bits));
    let centers = vec![lbdem_kernels::math::vector(3.0, 2.0); bodies];
    let (f, t) = l.solid_forces_and_torques(&centers);
    out.extend(f.iter().flat_map(|v| [v[0].to_bits(), v[1].to_bits()]));
    out.extend(t.iter().map(|v| v.to_bits()));
    out
}

/// Step `make()` with both schemes (AA on `threads` threads with bands of `band` rows, two-lattice on one
/// thread) and compare the states after every step; returns the number of steps compared.
fn assert_schemes_agree<T: Real>(
    make: impl Fn() -> FluidLattice<T>,
    bodies: usize,
    steps: usize,
    threads: usize,
    band: usize,
) -> Result<(), String> {
    let mut aa = make();
    let mut two = make();
    aa.set_streaming(Streaming::Aa);
    two.set_streaming(Streaming::TwoLattice);
    aa.set_band_rows(band);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    if state(&aa, bodies) != state(&two, bodies) {
        return Err("initial states differ".into());
    }
    for step in 1..=steps {
        pool.install(|| aa.step());
        one.install(|| two.step());
        if state(&aa, bodies) != state(&two, bodies) {
            return Err(format!("states differ after step {step}"));
        }
    }
    Ok(())
}

fn params<T: Real>(tau: f64, force: [f64; 2]) -> FluidParams<T> {
    FluidParams {
        tau: T::lit(tau),
        force: force.map(T::lit),
    }
}

fn pressure<T: Real>(d: f64) -> SideCondition<T> {
    SideCondition::Pressure { density: T::lit(d) }
}

fn velocity<T: Real>(u: [f64; 2]) -> SideCondition<T> {
    SideCondition::Velocity {
        velocity: u.map(T::lit),
    }
}

fn discs() -> Vec<FluidDisc> {
    vec![
        FluidDisc {
            center: [9.3, 8.6],
            radius: 4.2,
            velocity: [0.01, -0.003],
            spin: 0.002,
        },
        FluidDisc {
            center: [17.1, 11.4],
            radius: 3.1,
            velocity: [0.0, 0.004],
            spin: -0.001,
        },
    ]
}

/// A lattice with a shear wave, obstacle nodes (some touching the sides) and two moving discs.
fn busy<T: Real>(nx: usize, ny: usize, bc: Boundaries<T>, force: [f64; 2]) -> FluidLattice<T> {
    let mut l = FluidLattice::new(nx, ny, bc, params(0.62, force)).unwrap();
    l.fill_equilibrium(|x, y| {
        let (x, y) = (x as f64, y as f64);
        (
            T::lit(1.0 + 0.004 * (0.7 * x).sin()),
            [
                T::lit(0.03 * (0.5 * y).cos()),
                T::lit(0.02 * (0.3 * x + 0.2 * y).sin()),
            ],
        )
    });
    l.set_solid(|x, y| {
        (x == 5 && y < 4) || (x + 2 * y).is_multiple_of(17) || (x == nx - 1 && y == 3)
    });
    l.set_solid_operator(SolidOperator::LinearizedNonEquilibriumBounceBack);
    l.cover_with_discs(&discs(), Weighting::NobleTorczynski);
    l
}

#[test]
fn both_schemes_agree_bitwise_on_every_kind_of_side_and_node() {
    let sides: Vec<(&str, Boundaries<f64>)> = vec![
        ("periodic", Boundaries::periodic()),
        (
            "pressure channel",
            Boundaries {
                west: pressure(1.01),
                east: pressure(0.99),
                south: SideCondition::Wall,
                north: SideCondition::Wall,
            },
        ),
        (
            "walls all round",
            Boundaries {
                west: SideCondition::Wall,
                east: SideCondition::Wall,
                south: SideCondition::Wall,
                north: SideCondition::Wall,
            },
        ),
        (
            "velocity sides, velocity-velocity corners",
            Boundaries {
                west: velocity([0.02, 0.0]),
                east: velocity([0.02, 0.001]),
                south: velocity([0.0, 0.01]),
                north: velocity([0.01, 0.0]),
            },
        ),
        (
            "pressure on all four sides",
            Boundaries {
                west: pressure(1.02),
                east: pressure(1.0),
                south: pressure(1.01),
                north: pressure(0.995),
            },
        ),
        (
            "periodic x, velocity and pressure in y",
            Boundaries {
                west: SideCondition::Periodic,
                east: SideCondition::Periodic,
                south: velocity([0.01, 0.005]),
                north: pressure(1.0),
            },
        ),
    ];
    for (name, bc) in sides {
        for force in [[0.0, 0.0], [2e-6, -1e-6]] {
            assert_schemes_agree(|| busy::<f64>(29, 21, bc, force), 2, 25, 2, 3)
                .unwrap_or_else(|e| panic!("{name}, force {force:?}: {e}"));
        }
    }
    let bc32 = Boundaries {
        west: pressure(1.01),
        east: pressure(0.99),
        south: SideCondition::Wall,
        north: velocity([0.01, 0.0]),
    };
    assert_schemes_agree(|| busy::<f32>(31, 20, bc32, [1e-6, 0.0]), 2, 25, 2, 4)
        .unwrap_or_else(|e| panic!("f32 channel: {e}"));
}

#[test]
fn switching_scheme_or_geometry_after_an_odd_step_changes_nothing() {
    let bc = Boundaries {
        west: pressure(1.01),
        east: pressure(0.99),
        south: SideCondition::Wall,
        north: SideCondition::Wall,
    };
    let make = || busy::<f64>(29, 21, bc, [1e-6, 0.0]);
    let (mut a, mut b) = (make(), make());
    a.set_streaming(Streaming::TwoLattice);
    b.set_streaming(Streaming::Aa);
    for _ in 0..7 {
        a.step();
        b.step();
    }
    // b is in the streamed layout now; switch it to two-lattice and a to AA, change the obstacles of both.
    b.set_streaming(Streaming::TwoLattice);
    a.set_streaming(Streaming::Aa);
    assert_eq!(state(&a, 2), state(&b, 2));
    for _ in 0..3 {
        a.step();
        b.step();
    }
    let more = |x: usize, y: usize| {
        (x == 5 && y < 4) || (x + 2 * y).is_multiple_of(17) || x == 20 && y > 12
    };
    a.set_solid(more);
    b.set_solid(more);
    a.populations_mut()[100] += 1e-4;
    b.populations_mut()[100] += 1e-4;
    for _ in 0..9 {
        a.step();
        b.step();
        assert_eq!(state(&a, 2), state(&b, 2));
    }
    assert_eq!(a.steps(), 19);
    assert_eq!(a.streaming(), Streaming::Aa);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// Random small lattices (down to 1 × 1), random sides, obstacles, discs, force and τ.
    #[test]
    fn both_schemes_agree_bitwise_on_random_lattices(
        nx in 1usize..=11,
        ny in 1usize..=11,
        sides in proptest::array::uniform4(0u8..4),
        px in any::<bool>(),
        py in any::<bool>(),
        solid_seed in any::<u64>(),
        tau in 0.51f64..2.0,
        fx in -1e-5f64..1e-5,
        disc in (0.0f64..11.0, 0.0f64..11.0, 0.5f64..4.0),
        steps in 1usize..=9,
        band in 1usize..=4,
    ) {
        let side = |k: u8, periodic: bool, d: f64| -> SideCondition<f64> {
            if periodic {
                return SideCondition::Periodic;
            }
            match k {
                0 | 1 => SideCondition::Wall,
                2 => pressure(d),
                _ => velocity([0.01 * d, -0.005]),
            }
        };
        let bc = Boundaries {
            west: side(sides[0], px, 1.01),
            east: side(sides[1], px, 0.99),
            south: side(sides[2], py, 1.0),
            north: side(sides[3], py, 1.02),
        };
        let make = || {
            let mut l = FluidLattice::<f64>::new(nx, ny, bc, params(tau, [fx, 0.5 * fx])).unwrap();
            l.fill_equilibrium(|x, y| {
                (1.0 + 0.002 * (x as f64 - y as f64), [0.01 * (y as f64).sin(), 0.02 * (x as f64).cos()])
            });
            l.set_solid(|x, y| {
                let h = (solid_seed ^ ((x as u64) << 20 | y as u64)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
                (h >> 60) < 3
            });
            l.cover_with_discs(
                &[FluidDisc { center: [disc.0, disc.1], radius: disc.2, velocity: [0.01, 0.0], spin: 0.003 }],
                Weighting::NobleTorczynski,
            );
            l
        };
        prop_assert_eq!(assert_schemes_agree(make, 1, steps, 2, band), Ok(()));
    }
}
