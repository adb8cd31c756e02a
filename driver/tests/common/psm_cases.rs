//! Fixed-solid cases of the partially saturated method driven through the `FluidLattice` API with the collision
//! and solid operator chosen per run: the periodic square array of cylinders against Sangani &
//! Acrivos (1982) and the permeability of a random pack of discs. Shared by `driver/tests/trt_psm.rs` and the
//! example `driver/examples/tau_table.rs` (included with `#[path]`).
//!
//! Both are driven by a uniform body force G on the fluid (Guo forcing, weighted by 1 − B at covered nodes) in a
//! periodic box, sized so that the flow is Stokes flow of an incompressible fluid at every τ: Re = U D/ν ≤ 0.01
//! (inertia changes the drag by O(Re²)) and G l ≤ 1e-5/3 (the density varies by at most ~3 G l ≤ 1e-5 over the
//! box; at Re = 0.01 alone the drive grows as ν², and at τ = 2 the density of a random pack varied by 3 %, which
//! moved its permeability by 0.17 %). As in `lbdem::kinds::cylinder_array::solve_array`, the drag is
//! F/(μU) with F = G l² (S&A's definition) and U the superficial velocity Σ (1 − ε) u_x / l²; μ = ρ_f ν with the
//! mean fluid density ρ_f. u is what `FluidLattice::moments` reports: the velocity the collision uses (for ΩΛ
//! the trapezoidal velocity with the solids' friction, see `lbdem_kernels::fluid::collide::psm_velocity`).
#![allow(dead_code)]
use lbdem::engine::lattice::{FluidDisc, FluidLattice};
use lbdem_kernels::fluid::boundary::Boundaries;
use lbdem_kernels::fluid::collide::{Collision, LambdaTerms, SolidOperator, Trt, Weighting};
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_reference::analytic::sangani_acrivos_drag;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The relaxation times of the τ table.
pub const TAUS: [f64; 5] = [0.55, 0.6, 0.8, 1.2, 2.0];

/// Largest Reynolds number U D/ν of a run.
pub const REYNOLDS: f64 = 0.01;

/// Largest density variation 3 G l of a run.
pub const DENSITY_VARIATION: f64 = 1e-5;

/// The body force for a Stokes estimate `g_for(u)` (force giving superficial velocity u): the smaller of the
/// forces for Re = [`REYNOLDS`] and for a density variation [`DENSITY_VARIATION`] over the box side `l`.
fn drive(nu: f64, diameter: f64, l: usize, g_for: impl Fn(f64) -> f64) -> f64 {
    g_for(REYNOLDS * nu / diameter).min(DENSITY_VARIATION / (3.0 * l as f64))
}

/// The fluid collision of a case: BGK, or TRT with magic parameter Λ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fluid {
    /// BGK.
    Bgk,
    /// TRT with this Λ.
    Trt(f64),
}

impl Fluid {
    /// The kernel's collision.
    pub fn collision(self) -> Collision<f64> {
        match self {
            Fluid::Bgk => Collision::Bgk,
            Fluid::Trt(m) => Collision::Trt(Trt::new(m).expect("positive magic parameter")),
        }
    }

    /// Short name for tables.
    pub fn name(self) -> String {
        match self {
            Fluid::Bgk => "BGK".into(),
            Fluid::Trt(m) => format!("TRT Λ={m:.4}"),
        }
    }
}

/// How a case is run: fluid collision, solid operator, weighting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Method {
    /// Fluid collision.
    pub fluid: Fluid,
    /// Solid operator.
    pub solid: SolidOperator,
    /// Weighting B.
    pub weighting: Weighting,
    /// ΩΛ's constants (read under ΩΛ only).
    pub lambda: LambdaTerms,
}

impl Method {
    /// TRT (Λ = 3/16) with ΩΛ and B = ε, ΩΛ in its friction-only form (`LambdaTerms::FRICTION_ONLY`, the
    /// default until 2026-12-07): the τ-independent method the earlier tests were written for.
    pub const LAMBDA: Method = Method {
        fluid: Fluid::Trt(3.0 / 16.0),
        solid: SolidOperator::LambdaConsistent,
        weighting: Weighting::SolidFraction,
        lambda: LambdaTerms::FRICTION_ONLY,
    };
    /// [`Method::LAMBDA`] in ΩΛ's wall-pressure form ([`LambdaTerms::WALL_PRESSURE`], the default).
    pub const LAMBDA_WALL: Method = Method {
        lambda: LambdaTerms::WALL_PRESSURE,
        ..Method::LAMBDA
    };
}

/// Result of one periodic-array run.
#[derive(Clone, Copy, Debug)]
pub struct ArrayRun {
    /// F/(μU).
    pub drag: f64,
    /// Relative error against S&A.
    pub error: f64,
    /// Force the solid received over G l² (≈ 1 − c: the rest is the buoyancy of the mean gradient).
    pub solid_force_ratio: f64,
    /// The body force the fluid receives over G l², Σ (1 − ε)/l² over the nodes, counted from the coverage
    /// map, not from the run: ΩΛ's fully covered nodes (ε ≥ 1 − `LAMBDA_FULL_GAP`) take none. Meaningful for
    /// B = ε, where the solid must receive exactly this in the steady state.
    pub fluid_force_share: f64,
    /// Steps run.
    pub steps: u64,
    /// Whether the steady criterion was met.
    pub steady: bool,
}

/// Run `lattice` until the superficial velocity `flux(lattice)` changes by less than `tol` (relative) over
/// `interval` steps, or `max_steps`; returns (flux, steady).
fn run_to_steady(
    lattice: &mut FluidLattice<f64>,
    flux: impl Fn(&FluidLattice<f64>) -> f64,
    tol: f64,
    interval: u64,
    max_steps: u64,
) -> (f64, bool) {
    let mut last = f64::NAN;
    while lattice.steps() < max_steps {
        for _ in 0..interval {
            lattice.step();
        }
        let q = flux(lattice);
        assert!(
            q.is_finite(),
            "non-finite flux after {} steps",
            lattice.steps()
        );
        if ((q - last) / q).abs() < tol {
            return (q, true);
        }
        last = q;
    }
    (last, false)
}

/// Superficial velocity Σ (1 − ε) u_x over the lattice area, and the mean fluid density.
fn superficial(lattice: &FluidLattice<f64>, eps: &[f64]) -> (f64, f64) {
    let (rho, u) = lattice.moments();
    let n = eps.len() as f64;
    let q: f64 = u
        .iter()
        .zip(eps)
        .map(|(v, e)| (1.0 - e) * v[0])
        .sum::<f64>()
        / n;
    let (mut rw, mut w) = (0.0, 0.0);
    for (r, e) in rho.iter().zip(eps) {
        rw += (1.0 - e) * r;
        w += 1.0 - e;
    }
    (q, rw / w)
}

/// The periodic l × l cell with one cylinder of solid fraction `c` at relaxation time `tau`, run with
/// `method` to a relative flux change below 1e-9 per 200 steps. The cylinder's centre is the cell's centre,
/// ((l − 1)/2, (l − 1)/2) in node coordinates.
pub fn square_array(cell: usize, c: f64, tau: f64, method: Method) -> ArrayRun {
    square_array_at(cell, c, tau, method, [0.0; 2])
}

/// [`square_array`] with the cylinder's centre moved by `offset` (nodes) from the cell's centre: the same
/// periodic array placed differently on the lattice (the exact drag does not change).
pub fn square_array_at(
    cell: usize,
    c: f64,
    tau: f64,
    method: Method,
    offset: [f64; 2],
) -> ArrayRun {
    let nu = (tau - 0.5) / 3.0;
    let radius = cell as f64 * (c / std::f64::consts::PI).sqrt();
    let fbar = sangani_acrivos_drag(c).expect("tabulated solid fraction");
    // G for a superficial velocity U from S&A's drag.
    let g = drive(nu, 2.0 * radius, cell, |u| {
        fbar * nu * u / (cell * cell) as f64
    });
    let params = FluidParams {
        tau,
        force: [g, 0.0],
    };
    let mut lattice = FluidLattice::new(cell, cell, Boundaries::periodic(), params).unwrap();
    lattice.set_collision(method.fluid.collision()).unwrap();
    lattice.set_solid_operator(method.solid);
    lattice.set_lambda_terms(method.lambda).unwrap();
    lattice.set_band_rows(cell.div_ceil(2));
    let mid = 0.5 * (cell as f64 - 1.0);
    lattice.cover_with_discs(
        &[FluidDisc {
            center: [mid + offset[0], mid + offset[1]],
            radius,
            velocity: [0.0; 2],
            spin: 0.0,
        }],
        method.weighting,
    );
    let eps = lattice.solid_fraction_map();
    let (u_s, steady) = run_to_steady(
        &mut lattice,
        |l| superficial(l, &eps).0,
        1e-9,
        200,
        2_000_000,
    );
    let (_, rho_f) = superficial(&lattice, &eps);
    let ll = (cell * cell) as f64;
    let fluid_force_share = eps
        .iter()
        .map(|&e| {
            let full = method.solid == SolidOperator::LambdaConsistent
                && lbdem_kernels::fluid::collide::lambda_fully_covered(e);
            if full {
                0.0
            } else {
                1.0 - e
            }
        })
        .sum::<f64>()
        / ll;
    let drag = g * ll / (rho_f * nu * u_s);
    ArrayRun {
        drag,
        error: drag / fbar - 1.0,
        solid_force_ratio: lattice.solid_forces(1)[0][0] / (g * ll),
        fluid_force_share,
        steps: lattice.steps(),
        steady,
    }
}

/// A seeded random pack of `count` non-overlapping discs of diameter `diameter` in a periodic `size` × `size`
/// box, at least `gap` nodes apart (surface to surface, periodic images included). Placement by random
/// sequential addition.
pub fn random_pack(
    count: usize,
    diameter: f64,
    size: usize,
    gap: f64,
    seed: u64,
) -> Vec<FluidDisc> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let l = size as f64;
    let mut discs: Vec<FluidDisc> = Vec::with_capacity(count);
    let mut tries = 0usize;
    while discs.len() < count {
        tries += 1;
        assert!(tries < 1_000_000, "cannot place {count} discs");
        let p = [rng.random_range(0.0..l), rng.random_range(0.0..l)];
        let clear = discs.iter().all(|d| {
            let mut dx = (p[0] - d.center[0]).abs();
            let mut dy = (p[1] - d.center[1]).abs();
            dx = dx.min(l - dx);
            dy = dy.min(l - dy);
            (dx * dx + dy * dy).sqrt() >= diameter + gap
        });
        if clear {
            discs.push(FluidDisc {
                center: p,
                radius: 0.5 * diameter,
                velocity: [0.0; 2],
                spin: 0.0,
            });
        }
    }
    discs
}

/// Discs, with the periodic images of those that cross a side (the lattice takes no periodic images itself).
pub fn with_periodic_images(discs: &[FluidDisc], size: usize) -> Vec<FluidDisc> {
    let l = size as f64;
    let mut out = Vec::new();
    for d in discs {
        for sx in [-1.0, 0.0, 1.0] {
            for sy in [-1.0, 0.0, 1.0] {
                let c = [d.center[0] + sx * l, d.center[1] + sy * l];
                let r = d.radius + 1.0;
                if c[0] + r >= -0.5
                    && c[0] - r <= l - 0.5
                    && c[1] + r >= -0.5
                    && c[1] - r <= l - 0.5
                {
                    out.push(FluidDisc { center: c, ..*d });
                }
            }
        }
    }
    out
}

/// Permeability k = μ U / G (lattice units) of `discs` in a periodic `size` × `size` box, driven along x at
/// Re = 0.01 (on the disc diameter), run to a relative flux change below 1e-8 per 200 steps (the flux then
/// sits within ~1e-6 of its limit: a factor 1000 below the 1 % the pack is judged by). Returns
/// (k, porosity, steady, steps).
pub fn pack_permeability(
    discs: &[FluidDisc],
    size: usize,
    tau: f64,
    method: Method,
) -> (f64, f64, bool, u64) {
    let nu = (tau - 0.5) / 3.0;
    let diameter = 2.0 * discs[0].radius;
    // A guess of k (a third of the Kozeny–Carman scale: U is at most 3 times the target) sizes the drive.
    let g = drive(nu, diameter, size, |u| {
        nu * u / (0.01 * diameter * diameter)
    });
    let params = FluidParams {
        tau,
        force: [g, 0.0],
    };
    let mut lattice = FluidLattice::new(size, size, Boundaries::periodic(), params).unwrap();
    lattice.set_collision(method.fluid.collision()).unwrap();
    lattice.set_solid_operator(method.solid);
    lattice.set_lambda_terms(method.lambda).unwrap();
    lattice.cover_with_discs(&with_periodic_images(discs, size), method.weighting);
    let eps = lattice.solid_fraction_map();
    let porosity = 1.0 - eps.iter().sum::<f64>() / eps.len() as f64;
    let (u, steady) = run_to_steady(
        &mut lattice,
        |l| superficial(l, &eps).0,
        1e-8,
        200,
        2_000_000,
    );
    let (_, rho_f) = superficial(&lattice, &eps);
    (rho_f * nu * u / g, porosity, steady, lattice.steps())
}
