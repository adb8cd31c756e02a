//! Moving, overlapping solids through the coverage machinery: a stress case, not a validation. Which ingredient
//! makes a solid operator diverge: bodies sweeping through the lattice's wall or Zou–He sides, overlapping
//! bodies, obstacle nodes under bodies, a coupling velocity that disagrees with the displacement, or speed.
//!
//! ```text
//! cargo run --release -p lbdem --example moving_bodies_stress -- \
//!     OP FORM OVERLAP OBSTACLES VMAX VFIRST MISMATCH SEEDS [TAU] [INSIDE] [ONLY_SEED|x] [SIDES]
//! ```
//!
//! OP: `lambda` (ΩΛ on TRT, B = ε), `lin` (Ω₁ₗ on BGK) or `nt` (Ω₁ on BGK); FORM: `wall` or `friction` (ΩΛ's
//! form); OVERLAP, OBSTACLES, MISMATCH, INSIDE: 0 or 1; VMAX: the largest speed a body's random walk reaches and
//! VFIRST the largest first-step speed (lattice units per step); TAU: 0.9 by default. Thirty discs and ellipses
//! (radius 1–7) on a 61 × 47 lattice with a sheared initial flow, 2000 steps, re-mapped each step. Odd seeds are
//! periodic; even seeds have SIDES: `zh` (Zou–He pressure west/east, walls south/north, the default), `zhx`
//! (Zou–He west/east, periodic south/north), `walls` (four walls) or `wally` (walls south/north). Without INSIDE
//! bodies start anywhere from 3 nodes beyond the sides, so they cover side nodes; with INSIDE they start and stay
//! (reflected) at least 2 nodes inside. Prints, per seed, whether the populations stayed finite, then the count.
use lbdem::engine::lattice::FluidLattice;
use lbdem_kernels::coupling::{BodyShape, CoupledBody};
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::{Collision, LambdaTerms, SolidOperator, Trt, Weighting};
use lbdem_kernels::fluid::step::FluidParams;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
/// Print `msg` with the usage and exit with status 2 (bad arguments).
fn fail(msg: &str) -> ! {
    eprintln!(
        "moving_bodies_stress: {msg}\nusage: OP FORM OVERLAP OBSTACLES VMAX VFIRST MISMATCH SEEDS [TAU] [INSIDE] [ONLY_SEED|x] [SIDES] (see the file's doc)"
    );
    std::process::exit(2)
}

/// Argument `i` as a finite number, or exit naming it.
fn number<N: std::str::FromStr>(a: &[String], i: usize, name: &str) -> N {
    a[i].parse()
        .unwrap_or_else(|_| fail(&format!("{name} = {:?} is not a number", a[i])))
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 9 {
        fail("too few arguments");
    }
    let op = match a[1].as_str() {
        "lambda" => SolidOperator::LambdaConsistent,
        "lin" => SolidOperator::LinearizedNonEquilibriumBounceBack,
        _ => SolidOperator::NonEquilibriumBounceBack,
    };
    let terms = if a[2] == "wall" {
        LambdaTerms::WALL_PRESSURE
    } else {
        LambdaTerms::FRICTION_ONLY
    };
    let overlap = a[3] == "1";
    let obstacles = a[4] == "1";
    let vmax: f64 = number(&a, 5, "VMAX");
    let vfirst: f64 = number(&a, 6, "VFIRST");
    let mismatch = a[7] == "1";
    let seeds: u64 = number(&a, 8, "SEEDS");
    let tau: f64 = if a.len() > 9 {
        number(&a, 9, "TAU")
    } else {
        0.9
    };
    if !(vmax.is_finite()
        && vmax >= 0.0
        && vfirst.is_finite()
        && vfirst >= 0.0
        && tau > 0.5
        && tau.is_finite())
    {
        fail("VMAX and VFIRST must be finite and >= 0, TAU finite and > 0.5");
    }
    let inside = a.get(10).is_some_and(|s| s == "1");
    let only: Option<u64> = a.get(11).and_then(|s| s.parse().ok());
    let bcmode = a.get(12).cloned().unwrap_or_else(|| "zh".into());
    let wf = if op == SolidOperator::LambdaConsistent {
        Weighting::SolidFraction
    } else {
        Weighting::NobleTorczynski
    };
    let (nx, ny) = (61usize, 47usize);
    let mut blown = 0;
    for seed in 0..seeds {
        if only.is_some_and(|o| o != seed) {
            continue;
        }
        let pressure = seed % 2 == 0;
        let bc = if pressure {
            match bcmode.as_str() {
                "walls" => Boundaries {
                    west: SideCondition::Wall,
                    east: SideCondition::Wall,
                    south: SideCondition::Wall,
                    north: SideCondition::Wall,
                },
                "zhx" => Boundaries {
                    west: SideCondition::Pressure { density: 1.01 },
                    east: SideCondition::Pressure { density: 1.0 },
                    south: SideCondition::Periodic,
                    north: SideCondition::Periodic,
                },
                "wally" => Boundaries {
                    west: SideCondition::Periodic,
                    east: SideCondition::Periodic,
                    south: SideCondition::Wall,
                    north: SideCondition::Wall,
                },
                _ => Boundaries {
                    west: SideCondition::Pressure { density: 1.01 },
                    east: SideCondition::Pressure { density: 1.0 },
                    south: SideCondition::Wall,
                    north: SideCondition::Wall,
                },
            }
        } else {
            Boundaries::periodic()
        };
        let mut l = FluidLattice::<f64>::new(
            nx,
            ny,
            bc,
            FluidParams {
                tau,
                force: [0.0; 2],
            },
        )
        .unwrap();
        let trt = op == SolidOperator::LambdaConsistent;
        if trt {
            l.set_collision(Collision::Trt(Trt::new(3.0 / 16.0).unwrap()))
                .unwrap();
        }
        if obstacles {
            l.set_solid(|x, y| (x * 7 + y * 3) % 97 == 0);
        }
        l.set_solid_operator(op);
        l.set_lambda_terms(terms).unwrap();
        l.fill_equilibrium(|x, y| {
            (
                1.0,
                [0.02 * (0.2 * y as f64).sin(), 0.01 * (0.3 * x as f64).cos()],
            )
        });
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut bodies: Vec<CoupledBody<f64>> = Vec::new();
        let mut tries = 0;
        while bodies.len() < 30 && tries < 100000 {
            tries += 1;
            let k = bodies.len();
            let r = rng.random_range(1.0..7.0);
            let shape = if k.is_multiple_of(3) {
                BodyShape::Disc { radius: r }
            } else {
                BodyShape::Ellipse {
                    semi_major: r,
                    semi_minor: r * rng.random_range(0.3..1.0),
                    angle: rng.random_range(-3.2..3.2),
                }
            };
            let c = if inside {
                let m = r + 3.0;
                lbdem_kernels::math::vector(
                    rng.random_range(m..nx as f64 - m),
                    rng.random_range(m..ny as f64 - m),
                )
            } else {
                lbdem_kernels::math::vector(
                    rng.random_range(-3.0..nx as f64 + 3.0),
                    rng.random_range(-3.0..ny as f64 + 3.0),
                )
            };
            let v = lbdem_kernels::math::vector(
                rng.random_range(-vfirst..vfirst.max(1e-300)),
                rng.random_range(-vfirst..vfirst.max(1e-300)),
            );
            let b = CoupledBody {
                center: c,
                velocity: v,
                spin: rng.random_range(-0.01..0.01) * (vfirst / 0.05),
                shape,
            };
            if !overlap {
                // bounding circles apart by 2 nodes (periodic distance ignored)
                let rb = |b: &CoupledBody<f64>| match b.shape {
                    BodyShape::Disc { radius } => radius,
                    BodyShape::Ellipse { semi_major, .. } => semi_major,
                };
                if bodies
                    .iter()
                    .any(|o: &CoupledBody<f64>| (o.center - b.center).norm() < rb(o) + rb(&b) + 2.0)
                {
                    continue;
                }
            }
            bodies.push(b);
        }
        let mut blew = None;
        for step in 0..2000 {
            l.cover_with_bodies(&bodies, wf);
            l.step();
            if step % 50 == 0 && !l.populations().iter().all(|v| v.is_finite()) {
                blew = Some(step);
                break;
            }
            for (k, b) in bodies.iter_mut().enumerate() {
                b.velocity = lbdem_kernels::math::vector(
                    (b.velocity[0] + rng.random_range(-0.0005..0.0005)).clamp(-vmax, vmax),
                    (b.velocity[1] + rng.random_range(-0.0005..0.0005)).clamp(-vmax, vmax),
                );
                if inside {
                    let r = match b.shape {
                        BodyShape::Disc { radius } => radius,
                        BodyShape::Ellipse { semi_major, .. } => semi_major,
                    };
                    if b.center[0] < r + 2.0 || b.center[0] > nx as f64 - r - 2.0 {
                        b.velocity[0] = -b.velocity[0];
                    }
                    if b.center[1] < r + 2.0 || b.center[1] > ny as f64 - r - 2.0 {
                        b.velocity[1] = -b.velocity[1];
                    }
                }
                if mismatch {
                    if k % 5 == 0 {
                        continue;
                    }
                    b.center[0] += 0.1 * b.velocity[0];
                    b.center[1] += 0.1 * b.velocity[1];
                } else {
                    b.center[0] += b.velocity[0];
                    b.center[1] += b.velocity[1];
                }
            }
        }
        if blew.is_some() {
            blown += 1;
        }
        println!(
            "seed {seed} bodies {} pressure {pressure}: {}",
            bodies.len(),
            match blew {
                Some(s) => format!("NON-FINITE by step {s}"),
                None => "finite after 2000".into(),
            }
        );
    }
    println!("{} {} overlap {overlap} obstacles {obstacles} vmax {vmax} vfirst {vfirst} mismatch {mismatch} tau {tau}: {blown}/{seeds} diverged", a[1], a[2]);
}
