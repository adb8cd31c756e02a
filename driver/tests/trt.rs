//! The two-relaxation-time (TRT) fluid through `FluidLattice`: the same bitwise guarantees as
//! BGK (every SIMD level of the bulk pass, both streaming schemes, any thread count and band height, f32 and
//! f64), a checkpoint keeps the operator, and bad magic parameters are refused with the field named.
use lbdem::engine::exec::SimdLevel;
use lbdem::engine::lattice::{FluidDisc, FluidLattice, Streaming};
use lbdem::run::checkpoint::Checkpoint;
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::{Collision, LambdaTerms, SolidOperator, Trt, Weighting};
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::Real;

fn bits<T: Real>(v: &[T]) -> Vec<u64> {
    v.iter().map(|x| x.to_f64_exact().to_bits()).collect()
}

/// Populations (two-lattice layout), moments and the forces on the two discs, as bit patterns.
fn state<T: Real>(l: &FluidLattice<T>) -> Vec<u64> {
    let mut out = bits(&l.populations());
    let (rho, u) = l.moments();
    out.extend(bits(&rho));
    out.extend(u.iter().flat_map(|v| bits(v)));
    out.extend(
        l.solid_forces(2)
            .iter()
            .flat_map(|v| [v[0].to_bits(), v[1].to_bits()]),
    );
    out
}

fn trt<T: Real>(magic: f64) -> Collision<T> {
    Collision::Trt(Trt::new(T::lit(magic)).unwrap())
}

/// A channel with an odd width (67 = 8·8 + 3, so the vectorised loops have remainders at every width), a shear
/// wave, obstacle nodes and two moving PSM discs, relaxed by TRT.
fn busy<T: Real>(bc: Boundaries<T>, force: [f64; 2], magic: f64) -> FluidLattice<T> {
    let params = FluidParams {
        tau: T::lit(0.57),
        force: force.map(T::lit),
    };
    let mut l = FluidLattice::new(67, 23, bc, params).unwrap();
    l.set_collision(trt(magic)).unwrap();
    l.fill_equilibrium(|x, y| {
        let (x, y) = (x as f64, y as f64);
        (
            T::lit(1.0 + 0.004 * (0.3 * x).sin()),
            [
                T::lit(0.03 * (0.5 * y).cos()),
                T::lit(0.02 * (0.2 * x + 0.3 * y).sin()),
            ],
        )
    });
    l.set_solid(|x, y| (x == 30 && y < 6) || (x + 3 * y).is_multiple_of(29));
    l.set_solid_operator(SolidOperator::LinearizedNonEquilibriumBounceBack);
    l.cover_with_discs(&busy_discs(), Weighting::NobleTorczynski);
    l
}

/// The two moving discs of [`busy`].
fn busy_discs() -> [FluidDisc; 2] {
    [
        FluidDisc {
            center: [12.3, 11.6],
            radius: 4.7,
            velocity: [0.01, -0.002],
            spin: 0.001,
        },
        FluidDisc {
            center: [48.1, 9.2],
            radius: 3.2,
            velocity: [0.0, 0.004],
            spin: -0.002,
        },
    ]
}

fn channel<T: Real>() -> Boundaries<T> {
    Boundaries {
        west: SideCondition::Pressure {
            density: T::lit(1.01),
        },
        east: SideCondition::Pressure {
            density: T::lit(0.99),
        },
        south: SideCondition::Wall,
        north: SideCondition::Velocity {
            velocity: [T::lit(0.01), T::zero()],
        },
    }
}

/// Run `make()` `steps` steps with each configuration and require bitwise the state of the first one.
fn assert_all_agree<T: Real>(make: impl Fn() -> FluidLattice<T>, steps: usize, what: &str) {
    let levels: Vec<SimdLevel> = SimdLevel::ALL
        .into_iter()
        .filter(|l| l.available())
        .collect();
    let mut reference: Option<Vec<u64>> = None;
    for &level in &levels {
        for streaming in Streaming::ALL {
            for (threads, band) in [(1, 23), (2, 3), (3, 1)] {
                let mut l = make();
                l.set_simd(level).unwrap();
                l.set_streaming(streaming);
                l.set_band_rows(band);
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                for _ in 0..steps {
                    pool.install(|| l.step());
                }
                let s = state(&l);
                match &reference {
                    None => reference = Some(s),
                    Some(r) => assert!(
                        *r == s,
                        "{what}: {} / {} / {threads} threads differs",
                        level.name(),
                        streaming.name()
                    ),
                }
            }
        }
    }
    // The comparison compared numbers: the state is finite.
    let l = {
        let mut l = make();
        for _ in 0..steps {
            l.step();
        }
        l
    };
    assert!(l.populations().iter().all(|v| v.is_finite()), "{what}");
}

#[test]
fn trt_is_bitwise_identical_across_simd_levels_streaming_schemes_and_threads() {
    for force in [[0.0, 0.0], [2e-6, -1e-6]] {
        assert_all_agree(
            || busy::<f64>(channel(), force, 3.0 / 16.0),
            17,
            "f64 channel",
        );
        assert_all_agree(
            || busy::<f64>(Boundaries::periodic(), force, 0.01),
            17,
            "f64 periodic",
        );
    }
    assert_all_agree(
        || busy::<f32>(channel(), [1e-6, 0.0], 3.0 / 16.0),
        17,
        "f32 channel",
    );
    // ΩΛ at the covered nodes (fully covered nodes with open and closed links, obstacles next to the discs).
    for force in [[0.0, 0.0], [2e-6, -1e-6]] {
        assert_all_agree(
            || {
                let mut l = busy::<f64>(channel(), force, 3.0 / 16.0);
                l.set_solid_operator(SolidOperator::LambdaConsistent);
                l
            },
            17,
            "f64 channel, ΩΛ",
        );
    }
    assert_all_agree(
        || {
            let mut l = busy::<f32>(Boundaries::periodic(), [1e-6, 0.0], 0.1);
            l.set_solid_operator(SolidOperator::LambdaConsistent);
            l
        },
        17,
        "f32 periodic, ΩΛ",
    );
    // ΩΛ's wall-pressure form: the gradient pass before each step reads the buffer in either streaming layout.
    assert_all_agree(
        || {
            let mut l = busy::<f64>(channel(), [2e-6, -1e-6], 3.0 / 16.0);
            l.set_solid_operator(SolidOperator::LambdaConsistent);
            l.set_lambda_terms(LambdaTerms::WALL_PRESSURE).unwrap();
            l
        },
        17,
        "f64 channel, ΩΛ wall-pressure form",
    );
    assert_all_agree(
        || {
            let mut l = busy::<f32>(Boundaries::periodic(), [1e-6, 0.0], 0.1);
            l.set_solid_operator(SolidOperator::LambdaConsistent);
            l.set_lambda_terms(LambdaTerms::WALL_PRESSURE).unwrap();
            l
        },
        17,
        "f32 periodic, ΩΛ wall-pressure form",
    );
}

#[test]
fn trt_with_the_bgk_magic_parameter_stays_on_the_bgk_trajectory() {
    // Λ = (τ − ½)² makes τ⁻ = τ⁺: the two operators differ by roundoff per step (bitwise identity is not
    // claimed: the TRT pair formulas round differently). 40 steps of a busy lattice stay within 1e-12 of ρ.
    let tau: f64 = 0.57;
    let make = |c: Collision<f64>| {
        let mut l = busy::<f64>(channel(), [1e-6, 0.0], 3.0 / 16.0);
        l.set_collision(c).unwrap();
        l
    };
    let (mut a, mut b) = (make(Collision::Bgk), make(trt((tau - 0.5) * (tau - 0.5))));
    for _ in 0..40 {
        a.step();
        b.step();
    }
    let worst = a
        .populations()
        .iter()
        .zip(b.populations().iter())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-12, "BGK vs TRT(Λ = (τ − ½)²): {worst:e}");
}

#[test]
fn a_checkpoint_keeps_the_collision_operator() {
    let mut a = busy::<f64>(channel(), [1e-6, 0.0], 0.1);
    a.set_solid_operator(SolidOperator::LambdaConsistent);
    for _ in 0..7 {
        a.step();
    }
    let bytes = Checkpoint::to_bytes("scene", "fluid", 7, &a);
    let (_, mut b): (_, FluidLattice<f64>) =
        Checkpoint::from_bytes(&bytes, "scene", "fluid").unwrap();
    assert_eq!(b.collision(), a.collision());
    for _ in 0..9 {
        a.step();
        b.step();
    }
    assert_eq!(state(&a), state(&b));
}

#[test]
fn a_checkpoint_keeps_the_wall_pressure_form_and_resumes_bitwise() {
    // The wall gradients are not saved (each step derives them from the populations it gathers); the normals
    // and ΩΛ's constants are: the resumed run is the uninterrupted one, bit for bit, and differs from the
    // friction-only run (so the form is on after loading).
    let make = |terms: LambdaTerms| {
        let mut l = busy::<f64>(channel(), [1e-6, 0.0], 3.0 / 16.0);
        l.set_solid_operator(SolidOperator::LambdaConsistent);
        l.set_lambda_terms(terms).unwrap();
        l
    };
    let mut a = make(LambdaTerms::WALL_PRESSURE);
    for _ in 0..7 {
        a.step();
    }
    let bytes = Checkpoint::to_bytes("scene", "fluid", 7, &a);
    let (_, mut b): (_, FluidLattice<f64>) =
        Checkpoint::from_bytes(&bytes, "scene", "fluid").unwrap();
    assert_eq!(b.lambda_terms(), LambdaTerms::WALL_PRESSURE);
    let mut c = make(LambdaTerms::FRICTION_ONLY);
    for _ in 0..7 {
        c.step();
    }
    for _ in 0..9 {
        a.step();
        b.step();
        c.step();
    }
    assert_eq!(state(&a), state(&b));
    assert_ne!(state(&a), state(&c));
}

#[test]
fn the_wall_pressure_form_switched_on_after_covering_equals_covering_with_it_on() {
    // The normals are computed at re-mapping only while the form is on; switched on later, they come from the
    // last re-mapping's bodies. Both orders give the same run, bit for bit.
    let mut a = busy::<f64>(channel(), [1e-6, 0.0], 3.0 / 16.0);
    a.set_solid_operator(SolidOperator::LambdaConsistent);
    a.set_lambda_terms(LambdaTerms::WALL_PRESSURE).unwrap();
    let mut b = busy::<f64>(channel(), [1e-6, 0.0], 3.0 / 16.0);
    b.set_lambda_terms(LambdaTerms::WALL_PRESSURE).unwrap();
    b.set_solid_operator(SolidOperator::LambdaConsistent);
    b.cover_with_discs(&busy_discs(), Weighting::NobleTorczynski);
    // And the form is on in both: the friction-only run differs.
    let mut c = busy::<f64>(channel(), [1e-6, 0.0], 3.0 / 16.0);
    c.set_solid_operator(SolidOperator::LambdaConsistent);
    c.set_lambda_terms(LambdaTerms::FRICTION_ONLY).unwrap();
    for _ in 0..9 {
        a.step();
        b.step();
        c.step();
    }
    assert_eq!(state(&a), state(&b));
    assert_ne!(state(&a), state(&c));
}

#[test]
fn bad_wall_pressure_settings_are_refused_naming_the_field() {
    let mut l = busy::<f64>(channel(), [0.0, 0.0], 3.0 / 16.0);
    for bad in [f64::NAN, -1.0, f64::INFINITY] {
        let err = l
            .set_lambda_terms(LambdaTerms {
                friction: 0.45,
                pressure: bad,
            })
            .unwrap_err()
            .to_string();
        assert!(err.contains("lambda wall pressure"), "{err}");
        let err = l
            .set_lambda_terms(LambdaTerms {
                friction: bad,
                pressure: 2.0,
            })
            .unwrap_err()
            .to_string();
        assert!(err.contains("lambda friction"), "{err}");
    }
    // The lattice keeps its constants (the default, the wall-pressure form).
    assert_eq!(l.lambda_terms(), LambdaTerms::WALL_PRESSURE);
    // Normals for a solid given cell by cell: unit or zero, finite; the node is named.
    let mut f = FluidLattice::<f64>::new(
        8,
        8,
        Boundaries::periodic(),
        FluidParams {
            tau: 0.8,
            force: [0.0; 2],
        },
    )
    .unwrap();
    let none = f
        .set_field_normals(|_, _| [0.0, 1.0])
        .unwrap_err()
        .to_string();
    assert!(none.contains("no coverage"), "{none}");
    f.cover_with_field(
        |_, y| if y == 2 { 0.5 } else { 0.0 },
        |_, _| [0.0; 2],
        Weighting::SolidFraction,
    )
    .unwrap();
    for bad in [[0.5, 0.0], [f64::NAN, 1.0], [1.0, 1.0]] {
        let err = f.set_field_normals(|_, _| bad).unwrap_err().to_string();
        assert!(
            err.contains("solid normal") && err.contains("at node (0, 2)"),
            "{err}"
        );
    }
    f.set_field_normals(|_, _| [0.0, 1.0]).unwrap();
    f.set_field_normals(|_, _| [0.0; 2]).unwrap();
}

#[test]
fn magic_parameters_without_usable_rates_are_refused() {
    let mut l = busy::<f64>(channel(), [0.0, 0.0], 3.0 / 16.0);
    // Λ = 1e-300 at τ = 0.57: τ⁻ = ½ + 1.4e-299 rounds to ½.
    let err = l.set_collision(trt(1e-300)).unwrap_err().to_string();
    assert!(err.contains("fluid.magic"), "{err}");
    assert!(err.contains("3/16"), "{err}");
    // The lattice keeps its operator.
    assert_eq!(l.collision(), trt(3.0 / 16.0));
    assert!(Trt::new(0.0f64).is_err() && Trt::new(-1.0f64).is_err() && Trt::new(f64::NAN).is_err());
}
