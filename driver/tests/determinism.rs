//! Same scene ⇒ bitwise-identical results whatever the number of threads or the band size (DESIGN §4).
use lbdem::lattice::{FluidDisc, FluidLattice};
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::Weighting;
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::Real;

fn scene<T: Real>(band_rows: usize) -> FluidLattice<T> {
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
    let params = FluidParams {
        tau: T::lit(0.8),
        force: [T::lit(1e-6), T::lit(-2e-7)],
    };
    let mut lattice = FluidLattice::new(48, 37, bc, params).unwrap();
    lattice.set_solid(|x, y| (x == 30 && (10..20).contains(&y)) || (x + y) % 23 == 0 && y > 30);
    lattice.cover_with_discs(
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
    lattice.set_band_rows(band_rows);
    lattice
}

fn run<T: Real>(threads: usize, band_rows: usize) -> (Vec<T>, Vec<[f64; 2]>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut lattice = scene::<T>(band_rows);
        for _ in 0..150 {
            lattice.step();
        }
        (lattice.populations().to_vec(), lattice.solid_forces(2))
    })
}

fn bitwise_equal<T: Real>(a: &[T], b: &[T]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| x.to_f64_exact().to_bits() == y.to_f64_exact().to_bits())
}

#[test]
fn one_and_two_threads_and_any_band_size_give_bitwise_identical_results_f64() {
    let (reference, forces) = run::<f64>(1, 37);
    assert!(forces.iter().all(|f| f[0].is_finite() && f[1].is_finite()));
    assert!(
        forces[0][0].abs() > 0.0,
        "the moving disc must feel the fluid"
    );
    for (threads, band) in [(2, 8), (2, 1), (1, 5), (2, 13)] {
        let (pops, f) = run::<f64>(threads, band);
        assert!(
            bitwise_equal(&reference, &pops),
            "threads {threads}, band {band}: populations differ"
        );
        assert_eq!(forces, f, "threads {threads}, band {band}: forces differ");
    }
}

#[test]
fn one_and_two_threads_give_bitwise_identical_results_f32() {
    let (a, fa) = run::<f32>(1, 37);
    let (b, fb) = run::<f32>(2, 4);
    assert!(bitwise_equal(&a, &b));
    assert_eq!(fa, fb);
}
