//! Moving-solid cases for every solid operator, through the `FluidLattice` and
//! `CoupledWorld` APIs with the collision and operator chosen per run. Shared by `driver/tests/moving_solids.rs`
//! and the example `driver/examples/moving_table.rs` (included with `#[path]`).
//!
//! * [`couette`]: a solid slab (rows covered by `FluidLattice::cover_with_field`) sliding at U between two fluid
//!   layers of H rows, each closed by a half-way bounce-back wall at rest (the slab touches nothing); steady state
//!   against the linear profile (`lbdem_reference::analytic::couette_velocity`), the effective slab surface
//!   from a line fitted through the lower layer.
//! * [`stokes_first_problem`]: the same slab started impulsively at U in fluid at rest, against
//!   U erfc(d/(2√(νt))) at the time the diffusion length 2√(νt) reaches [`STOKES_LENGTH`] nodes.
//! * [`touching_wall`]: the slab sliding on a wall at rest (no fluid between them) under a fluid layer closed by a
//!   wall at rest: Couette above the slab, and nothing may grow at the contact.
//! * [`free_disc`]: the terminal-velocity case of `scenes/terminal_velocity.toml` in lattice units (a free disc,
//!   c = 0.2 in a periodic 40 × 40 box, pushed by a constant force, the fluid by the opposite body force) through
//!   `CoupledWorld`, with the drive scaled so that Re stays at the scene's ≈ 0.1 at every τ and the run long
//!   enough for 12 e-foldings of the slowest viscous mode.
#![allow(dead_code)]
use lbdem::engine::lattice::FluidLattice;
use lbdem::kinds::terminal_velocity::{fluid_weight, free_disc_world, total_momentum};
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::{Collision, SolidOperator, Trt, Weighting};
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_reference::analytic;
use lbdem_reference::analytic::sangani_acrivos_drag;

/// Slab speed (lattice units).
pub const SLAB_SPEED: f64 = 0.01;
/// Fluid rows of the Couette cases.
pub const COUETTE_ROWS: usize = 16;
/// Slab rows.
pub const SLAB_ROWS: usize = 4;
/// Diffusion length 2√(νt) (nodes) at which Stokes' first problem is compared.
pub const STOKES_LENGTH: f64 = 16.0;

/// A fluid collision and solid operator (with its weighting).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Method {
    /// `None`: BGK; `Some(Λ)`: TRT.
    pub magic: Option<f64>,
    /// Solid operator.
    pub solid: SolidOperator,
    /// Weighting.
    pub weighting: Weighting,
}

impl Method {
    /// The operators of the table: Ω₁, Ω₂, Ω₃, Ω₁ₗ with BGK and NT's weighting (today's), ΩΛ with TRT
    /// (Λ = 3/16) and B = ε.
    pub fn table() -> Vec<Method> {
        let mut v: Vec<Method> = [
            SolidOperator::NonEquilibriumBounceBack,
            SolidOperator::Superposition,
            SolidOperator::MovingWallBounceBack,
            SolidOperator::LinearizedNonEquilibriumBounceBack,
        ]
        .into_iter()
        .map(|solid| Method {
            magic: None,
            solid,
            weighting: Weighting::NobleTorczynski,
        })
        .collect();
        v.push(Method::LAMBDA);
        v
    }

    /// TRT (Λ = 3/16), ΩΛ, B = ε.
    pub const LAMBDA: Method = Method {
        magic: Some(3.0 / 16.0),
        solid: SolidOperator::LambdaConsistent,
        weighting: Weighting::SolidFraction,
    };

    fn collision(&self) -> Collision<f64> {
        self.magic.map_or(Collision::Bgk, |m| {
            Collision::Trt(Trt::new(m).expect("positive magic parameter"))
        })
    }

    /// Short name for tables.
    pub fn name(&self) -> String {
        let op = self.solid.symbol();
        match self.magic {
            None => format!("{op} (BGK)"),
            Some(m) => format!("{op} (TRT Λ={m})"),
        }
    }
}

fn lattice(
    nx: usize,
    ny: usize,
    bc: Boundaries<f64>,
    tau: f64,
    force: [f64; 2],
    m: Method,
) -> FluidLattice<f64> {
    let mut l = FluidLattice::new(nx, ny, bc, FluidParams { tau, force }).unwrap();
    l.set_collision(m.collision()).unwrap();
    l.set_solid_operator(m.solid);
    l
}

fn channel_sides() -> Boundaries<f64> {
    Boundaries {
        west: SideCondition::Periodic,
        east: SideCondition::Periodic,
        south: SideCondition::Wall,
        north: SideCondition::Wall,
    }
}

/// Least-squares line u = a + b y through (y, u).
fn line(points: &[(f64, f64)]) -> (f64, f64) {
    let m = points.len() as f64;
    let my = points.iter().map(|p| p.0).sum::<f64>() / m;
    let mu = points.iter().map(|p| p.1).sum::<f64>() / m;
    let (mut syu, mut syy) = (0.0, 0.0);
    for &(y, u) in points {
        syu += (y - my) * (u - mu);
        syy += (y - my) * (y - my);
    }
    let b = syu / syy;
    (mu - b * my, b)
}

/// What a moving-solid case found.
#[derive(Clone, Copy, Debug)]
pub struct Outcome {
    /// The run stayed finite and every fluid velocity within 2 U (for the free disc: the health check passed).
    pub bounded: bool,
    /// Case-specific error (see each case).
    pub error: f64,
    /// Second case-specific figure (see each case).
    pub other: f64,
}

/// x-velocity of every row (the two columns are identical), or `None` if anything is not finite.
fn rows(l: &FluidLattice<f64>) -> Option<Vec<f64>> {
    let (rho, u) = l.moments();
    let nx = l.shape().nx;
    if rho.iter().any(|r| !r.is_finite()) {
        return None;
    }
    Some((0..l.shape().ny).map(|y| u[y * nx][0]).collect())
}

/// Couette flow under a slab whose lower surface lies `phi` of a cell below the face between fluid row H − 1
/// and the first slab row (φ = 0: on the cell face); the slab's upper surface mirrors it. Runs the larger of
/// 30 000 steps and 25 e-foldings of the slowest mode, H²/(π²ν). `error` = effective slab surface minus
/// geometric (nodes); `other` = effective position of the wall at rest minus its half-way position (nodes).
pub fn couette(m: Method, tau: f64, phi: f64) -> Outcome {
    let (h, s) = (COUETTE_ROWS, SLAB_ROWS);
    let ny = 2 * h + s;
    let nu = lbdem::units::lattice_viscosity(tau);
    let mut l = lattice(2, ny, channel_sides(), tau, [0.0; 2], m);
    l.cover_with_field(
        |_, y| {
            if (h..h + s).contains(&y) {
                1.0
            } else if y + 1 == h || y == h + s {
                phi
            } else {
                0.0
            }
        },
        |_, _| [SLAB_SPEED, 0.0],
        m.weighting,
    )
    .unwrap();
    let steps = (25.0 * (h * h) as f64 / (std::f64::consts::PI.powi(2) * nu)).max(30_000.0) as u64;
    let Some(u) = run_bounded(&mut l, steps, |y| y + 1 < h || y > h + s) else {
        return Outcome {
            bounded: false,
            error: f64::NAN,
            other: f64::NAN,
        };
    };
    // Fluid rows of the lower layer not covered at all.
    let fluid = if phi > 0.0 { h - 1 } else { h };
    let pts: Vec<(f64, f64)> = (0..fluid).map(|y| (y as f64, u[y])).collect();
    let (a, b) = line(&pts);
    let surface = (SLAB_SPEED - a) / b;
    let geometric = h as f64 - 0.5 - phi;
    Outcome {
        bounded: true,
        error: surface - geometric,
        other: -a / b + 0.5,
    }
}

/// Step `l` `steps` times, checking every 500 steps that the run stays finite with |u| ≤ 2U in the rows that
/// are not covered (`fluid(y)`); the final row velocities if it did. (Inside a solid Ω₃ reverses the fluid's
/// velocity relative to the solid every step, so covered rows may hold 0 and 2U in turn without anything
/// growing.)
fn run_bounded(
    l: &mut FluidLattice<f64>,
    steps: u64,
    fluid: impl Fn(usize) -> bool,
) -> Option<Vec<f64>> {
    let ok = |u: &Option<Vec<f64>>| {
        u.as_ref().is_some_and(|u| {
            u.iter()
                .enumerate()
                .all(|(y, v)| v.is_finite() && (!fluid(y) || v.abs() <= 2.0 * SLAB_SPEED))
        })
    };
    for k in 0..steps {
        l.step();
        if k % 500 == 0 && !ok(&rows(l)) {
            return None;
        }
    }
    let u = rows(l);
    ok(&u).then_some(u?)
}

/// Stokes' first problem: the slab of [`couette`] (surfaces on cell faces) starts at U in fluid at rest, walls
/// 5 diffusion lengths away; compared with U erfc(d/(2√(νt))) (d from the lower slab surface) when
/// 2√(νt) = [`STOKES_LENGTH`]. `error` = the largest deviation over the lower fluid layer over U; `other` = the
/// surface offset (nodes) that best fits the erfc profile (least squares, offsets in steps of 0.01 node).
pub fn stokes_first_problem(m: Method, tau: f64) -> Outcome {
    let s = SLAB_ROWS;
    let h = (5.0 * STOKES_LENGTH) as usize;
    let ny = 2 * h + s;
    let nu = lbdem::units::lattice_viscosity(tau);
    let mut l = lattice(2, ny, channel_sides(), tau, [0.0; 2], m);
    l.cover_with_field(
        |_, y| if (h..h + s).contains(&y) { 1.0 } else { 0.0 },
        |_, _| [SLAB_SPEED, 0.0],
        m.weighting,
    )
    .unwrap();
    let steps = ((STOKES_LENGTH / 2.0).powi(2) / nu).round() as u64;
    let Some(u) = run_bounded(&mut l, steps, |y| !(h..h + s).contains(&y)) else {
        return Outcome {
            bounded: false,
            error: f64::NAN,
            other: f64::NAN,
        };
    };
    let t = steps as f64;
    let surface = h as f64 - 0.5;
    let exact = |y: usize, offset: f64| {
        analytic::stokes_first_problem(SLAB_SPEED, nu, t, surface + offset - y as f64)
    };
    let error = (0..h)
        .map(|y| (u[y] - exact(y, 0.0)).abs() / SLAB_SPEED)
        .fold(0.0, f64::max);
    let mut best = (f64::INFINITY, 0.0);
    for k in -100..=100 {
        let offset = 0.01 * k as f64;
        let r: f64 = (0..h).map(|y| (u[y] - exact(y, offset)).powi(2)).sum();
        if r < best.0 {
            best = (r, offset);
        }
    }
    Outcome {
        bounded: true,
        error,
        other: best.1,
    }
}

/// The slab (rows below `SLAB_ROWS`) slides at U on the south wall at rest, with H fluid rows above it closed by
/// the north wall at rest. Runs as [`couette`]; `error` = effective slab surface minus the cell face (nodes),
/// `other` = the x-momentum of the fluid rows over its steady Couette value (1 when nothing is injected at the
/// contact).
pub fn touching_wall(m: Method, tau: f64) -> Outcome {
    let (h, s) = (COUETTE_ROWS, SLAB_ROWS);
    let ny = h + s;
    let nu = lbdem::units::lattice_viscosity(tau);
    let mut l = lattice(2, ny, channel_sides(), tau, [0.0; 2], m);
    l.cover_with_field(
        |_, y| if y < s { 1.0 } else { 0.0 },
        |_, _| [SLAB_SPEED, 0.0],
        m.weighting,
    )
    .unwrap();
    let steps = (25.0 * (h * h) as f64 / (std::f64::consts::PI.powi(2) * nu)).max(30_000.0) as u64;
    let Some(u) = run_bounded(&mut l, steps, |y| y >= s) else {
        return Outcome {
            bounded: false,
            error: f64::NAN,
            other: f64::NAN,
        };
    };
    let pts: Vec<(f64, f64)> = (s..ny).map(|y| (y as f64, u[y])).collect();
    let (a, b) = line(&pts);
    let surface = (SLAB_SPEED - a) / b;
    let momentum: f64 = (s..ny).map(|y| u[y]).sum();
    let steady = SLAB_SPEED * h as f64 / 2.0;
    Outcome {
        bounded: true,
        error: surface - (s as f64 - 0.5),
        other: momentum / steady,
    }
}

/// The free disc of `scenes/terminal_velocity.toml` in lattice units at relaxation time `tau` and grain/fluid
/// density ratio `density`: c = 0.2 in a periodic 40 × 40 box, applied force 2.1e-3 (ν/0.1)² (Re ≈ 0.1 at every
/// τ), 12 e-foldings of l²/(4π²ν), mean slip over the last 20 %. `error` = F/(μU) against S&A (relative);
/// `other` = the largest total-momentum error over the run relative to the applied impulse (exact exchange).
pub fn free_disc(m: Method, tau: f64, density: f64) -> Outcome {
    let n = 40usize;
    let l = n as f64;
    let c = 0.2;
    let radius = l * (c / std::f64::consts::PI).sqrt();
    let nu = lbdem::units::lattice_viscosity(tau);
    let force = 2.1e-3 * (nu / 0.1).powi(2);
    let steps = (12.0 * l * l / (4.0 * std::f64::consts::PI.powi(2) * nu)).round() as u64;
    let (mut world, g) = free_disc_world(
        n,
        radius,
        density,
        tau,
        force,
        m.collision(),
        m.solid,
        m.weighting,
    )
    .unwrap();
    let fluid_weight =
        |eps: &[f64]| -> f64 { fluid_weight(eps, tau, m.solid, m.weighting, m.collision()) };
    let total = total_momentum;
    let p0 = total(&world);
    let (mut impulse, mut momentum_error) = (0.0, 0.0f64);
    let window_start = steps - steps / 5;
    let mut window = Vec::new();
    for s in 1..=steps {
        world.step();
        let eps = world.fluid.solid_fraction_map();
        impulse += force + g * fluid_weight(&eps);
        momentum_error = momentum_error.max((total(&world) - p0 - impulse).abs());
        if s > window_start {
            let v = world.dem.particles[0].velocity[0];
            let (_, vel) = world.fluid.moments();
            let slip: f64 = eps
                .iter()
                .zip(&vel)
                .map(|(e, u)| (1.0 - e) * (u[0] - v))
                .sum::<f64>()
                / (l * l);
            window.push(-slip);
        }
        if s % 250 == 0 && world.fluid.health_check(0.5, 1.5).is_some()
            || !world.dem.particles[0].velocity[0].is_finite()
        {
            return Outcome {
                bounded: false,
                error: f64::NAN,
                other: f64::NAN,
            };
        }
    }
    let slip = window.iter().sum::<f64>() / window.len() as f64;
    let drag = g.abs() * l * l / (nu * slip);
    let sa = sangani_acrivos_drag(c).expect("tabulated");
    Outcome {
        bounded: true,
        error: drag / sa - 1.0,
        other: momentum_error / (force * steps as f64),
    }
}
