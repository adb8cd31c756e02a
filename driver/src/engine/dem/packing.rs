//! Packing generation: the fill-and-expand procedure of the dissertation's ch. 2 (after Potyondy & Cundall
//! 2004's material genesis), and a regular hexagonal packing for benchmarks and snapshots.
//!
//! [`generate_packing`]:
//!
//! 1. **Sizes.** Draw semi-major axes a uniform in [r_min, r_max] (b = (b/a) a; discs when b/a = 1; random
//!    orientation in [0, π) for ellipses) until their area Σπab reaches `solid_fraction` × W H.
//! 2. **Fill.** Place them one by one at random in the W × H box, shrunk by s = √(0.3 (b/a)/solid_fraction) so
//!    their bounding circles cover 0.3 of it (random sequential addition jams only near 0.55), rejecting
//!    positions whose bounding circles overlap a placed particle or a wall (up to [`PLACEMENT_ATTEMPTS`] per
//!    particle; more fails with a typed error naming `packing.solid_fraction`).
//! 3. **Expand.** Grow every size from s towards 1 (at most (1 − s)/`growth_steps` per step, slowing as the
//!    least wall stress approaches the target) between fixed walls, with PFC local damping α = 0.7, until the
//!    least of the four wall stresses reaches `isotropic_stress`; masses stay those of the drawn size, so the
//!    critical step is constant.
//! 4. **Isotropic stress** (P&C's radius adjustment, walls fixed): relax [`RELAX_STEPS`] steps, measure the
//!    mean wall stress σ̄, rescale every size by f (first Δf/f = ½(σ_target − σ̄)/k_n, then the secant through
//!    the last two (f, σ̄); +0.5 % while the walls carry under a tenth of the target; at most ±0.1 % once
//!    loaded), until every wall stress is within `stress_tolerance` of the target and the mean unbalanced
//!    force is below [`UNBALANCED_TOLERANCE`] of the mean contact force, or `max_servo_steps` pass (then
//!    [`Packing::converged`] is false). A last relaxation follows. The sizes end at f × the drawn ones
//!    ([`Packing::size_factor`]).
//! 5. **Bond** (optional, the caller's choice of point or parallel bonds): every pair whose gap is below
//!    `bond_gap`, after the friction of `contact` is restored and the velocities are zeroed.
//!
//! While packing the contacts are frictionless (P&C's material genesis: a dense, isotropic assembly) and have
//! a normal dashpot of restitution [`PACKING_RESTITUTION`]. Measured on 250 discs, and why: (a) with
//! restitution 1 the energy stored by the growth is released as a rattling gas (local damping does not act on
//! particles in free flight); (b) servo-controlled walls (PFC gain λL/(k_n N_c Δt)) oscillate and pump energy
//! in, so the walls stay fixed and the sizes are adjusted instead; (c) with periodic "calm" (zeroing every
//! velocity) the walls reach the target but the assembly is far from equilibrium (unbalanced ratio ≈ 0.3)
//! and unjams when released; (d) at σ/k_n ≈ 1e-5 (5 dyne/cm with k_n = 1e5) the assembly hardly jams, so the
//! defaults use the ch. 6.6 hydrostatic stress of 50 dyne/cm (σ/k_n = 5e-4).
//!
//! Determinism: the only randomness is one `ChaCha8Rng` seeded from `seed`, drawn in a fixed order; the
//! world's step is bitwise deterministic, so a seed gives a bitwise-identical packing on any machine and any
//! number of threads.
//!
//! Units: consistent (cgs in the scenes: cm, g/cm² areal density, dyne/cm stress per unit thickness).
use lbdem_kernels::dem::assembly::ContactModel;
use lbdem_kernels::dem::contact::ELLIPSE_MIN_ASPECT_RATIO;
use lbdem_kernels::dem::shape::{Particle, Shape};
use lbdem_kernels::math::Vector;
use lbdem_kernels::Real;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::world::{BondSpec, DemWorld, PlatenControl, SampleBox};
use crate::error::{LbdemError, Result};

/// Random positions tried per particle before the fill gives up.
pub const PLACEMENT_ATTEMPTS: usize = 20_000;
/// Area fraction of the shrunk particles during the fill.
pub const FILL_FRACTION: f64 = 0.3;

/// Zero every velocity and stored acceleration (PFC's "calm").
fn calm<T: Real>(world: &mut DemWorld<T>) {
    for p in world.particles.iter_mut() {
        p.velocity = lbdem_kernels::math::Vector::from([T::zero(); 2]);
        p.angular_velocity = T::zero();
        p.acceleration = lbdem_kernels::math::Vector::from([T::zero(); 2]);
        p.angular_acceleration = T::zero();
    }
}

/// Relative size increase per adjustment while the relaxed walls carry no load (and the largest relative
/// change of any adjustment).
pub const UNLOADED_GROWTH: f64 = 5e-3;
/// Largest relative size change of an adjustment once the walls are loaded.
pub const LOADED_ADJUSTMENT: f64 = 1e-3;
/// Steps of relaxation between two size adjustments.
pub const RELAX_STEPS: u64 = 1000;
/// Restitution of the contacts while packing (a normal dashpot drains the energy stored by the growth).
pub const PACKING_RESTITUTION: f64 = 0.1;
/// Mean unbalanced force / mean contact force below which the packed assembly counts as in equilibrium.
pub const UNBALANCED_TOLERANCE: f64 = 2e-2;

/// What to pack.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PackingSpec<T> {
    /// Box width W (x).
    pub width: T,
    /// Box height H (y).
    pub height: T,
    /// Smallest semi-major axis (radius of a disc).
    pub radius_min: T,
    /// Largest semi-major axis.
    pub radius_max: T,
    /// b/a in (0, 1]; 1 gives discs.
    pub aspect_ratio: T,
    /// Target Σ particle area / (W H), which sets the particle count.
    pub solid_fraction: T,
    /// Areal density (mass per area, unit thickness).
    pub density: T,
    /// RNG seed.
    pub seed: u64,
    /// Contact material used while packing (and kept by the world).
    pub contact: ContactModel<T>,
    /// Time step.
    pub timestep: T,
    /// Steps over which the sizes grow to full size.
    pub growth_steps: u64,
    /// Isotropic stress to install (compression positive).
    pub isotropic_stress: T,
    /// Relative tolerance on each wall stress.
    pub stress_tolerance: T,
    /// Step limit of the servo stage.
    pub max_servo_steps: u64,
    /// Pairs closer than this are bonded.
    pub bond_gap: T,
}

impl PackingSpec<f64> {
    /// The dissertation's ch. 6.6 grains (radius 0.07–0.11 cm, density 2.65 g/cm³ × 1 cm) in a W × H box, with
    /// table 6.1's contact stiffness k_n = 1e5 dyne/cm and friction 0.5 (k_s = k_n here: table 6.1's
    /// k_s = 6e5 > k_n is kept out of the default), the ch. 6.6 hydrostatic stress of 50 dyne/cm², and a
    /// step of 5e-5 s (about a third of the critical step of the smallest disc with six contacts).
    pub fn dissertation(width: f64, height: f64, aspect_ratio: f64, seed: u64) -> Self {
        PackingSpec {
            width,
            height,
            radius_min: 0.07,
            radius_max: 0.11,
            aspect_ratio,
            solid_fraction: 0.82,
            density: 2.65,
            seed,
            contact: super::elastic_contact(1e5, 1e5, 0.5),
            timestep: 5e-5,
            growth_steps: 2000,
            isotropic_stress: 50.0,
            stress_tolerance: 0.2,
            max_servo_steps: 40_000,
            bond_gap: 1e-3,
        }
    }
}

/// A generated sample.
#[derive(Clone, Debug)]
pub struct Packing<T> {
    /// The world: particles, the four servo walls (stopped), bonds.
    pub world: DemWorld<T>,
    /// The walls.
    pub sample_box: SampleBox,
    /// Whether the isotropic stress was reached within the tolerance.
    pub converged: bool,
    /// Steps used (growth + size adjustment + final relaxation).
    pub steps: u64,
    /// Mean unbalanced force / mean contact force at the end of the isotropic stage.
    pub unbalanced_force_ratio: T,
    /// Final size factor f ≤ 1: every semi-axis is f × its drawn value (growth stops at the isotropic stress).
    pub size_factor: T,
    /// Wall stresses at the end (left, right, bottom, top).
    pub wall_stresses: [T; 4],
}

/// Refuse a grain aspect ratio b/a (`field`) outside [[`ELLIPSE_MIN_ASPECT_RATIO`], 1]: the ellipse contact
/// kernel finds the gap's maximum from 32 sampled directions, checked down to b/a = 0.05; a thinner needle's
/// sharp gap peak can fall between the samples and give a phantom overlap (see
/// `lbdem_kernels::dem::contact::ellipse_ellipse`). NaN refused.
pub fn check_aspect_ratio(field: &str, value: f64) -> Result<()> {
    if (ELLIPSE_MIN_ASPECT_RATIO..=1.0).contains(&value) {
        return Ok(());
    }
    Err(LbdemError::field(
        field,
        value,
        &format!(
            "must be in [{ELLIPSE_MIN_ASPECT_RATIO}, 1] (b/a; 1 = discs): below {ELLIPSE_MIN_ASPECT_RATIO} the \
             ellipse contact can miss the sharp gap peak of a needle and report a phantom overlap"
        ),
        "e.g. 0.5 for the dissertation's ellipses, 1 for discs",
    ))
}

/// The range checks of a [`PackingSpec`], naming the `packing.*` field.
pub fn check_packing_spec<T: Real>(s: &PackingSpec<T>) -> Result<()> {
    let pos = |field: &str, v: T| -> Result<()> {
        if v.is_finite() && v > T::zero() {
            Ok(())
        } else {
            Err(LbdemError::field(
                field,
                v.to_f64_exact(),
                "must be a finite number > 0",
                "see the documentation of lbdem::engine::dem::PackingSpec",
            ))
        }
    };
    pos("packing.width", s.width)?;
    pos("packing.height", s.height)?;
    pos("packing.radius_min", s.radius_min)?;
    pos("packing.radius_max", s.radius_max)?;
    pos("packing.density", s.density)?;
    pos("packing.isotropic_stress", s.isotropic_stress)?;
    pos("packing.stress_tolerance", s.stress_tolerance)?;
    if s.radius_max < s.radius_min {
        return Err(LbdemError::field(
            "packing.radius_max",
            s.radius_max.to_f64_exact(),
            "is smaller than packing.radius_min",
            "give radius_min <= radius_max",
        ));
    }
    check_aspect_ratio("packing.aspect_ratio", s.aspect_ratio.to_f64_exact())?;
    if !(s.solid_fraction > T::lit(FILL_FRACTION) && s.solid_fraction < T::lit(0.95)) {
        return Err(LbdemError::field(
            "packing.solid_fraction",
            s.solid_fraction.to_f64_exact(),
            "must be in (0.3, 0.95)",
            "dense 2-D packings reach 0.80-0.86",
        ));
    }
    if s.width < T::lit(4.0) * s.radius_max || s.height < T::lit(4.0) * s.radius_max {
        return Err(LbdemError::field(
            "packing.width",
            s.width.to_f64_exact(),
            "the box must be at least 4 largest radii wide and high",
            "enlarge the box or use smaller particles",
        ));
    }
    Ok(())
}

/// Draw the sizes and fill the box (steps 1–2). Returns full-size particles at their fill positions and the
/// shrink factor s.
pub fn fill_box<T: Real>(spec: &PackingSpec<T>) -> Result<(Vec<Particle<T>>, T)> {
    check_packing_spec(spec)?;
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let target = spec.solid_fraction * spec.width * spec.height;
    let mut area = T::zero();
    let mut sizes: Vec<(T, T, T)> = Vec::new();
    while area < target {
        let u: f64 = rng.random();
        let a = spec.radius_min + (spec.radius_max - spec.radius_min) * T::lit(u);
        let b = a * spec.aspect_ratio;
        let angle = if spec.aspect_ratio < T::one() {
            let v: f64 = rng.random();
            T::lit(v * std::f64::consts::PI)
        } else {
            T::zero()
        };
        area += T::PI() * a * b;
        sizes.push((a, b, angle));
    }
    // The fill tests bounding circles, whose area is πa² = (particle area)/(b/a).
    let s = (T::lit(FILL_FRACTION) * spec.aspect_ratio / spec.solid_fraction).sqrt();
    let cell = T::lit(2.0) * spec.radius_max * s;
    let nx = (spec.width / cell).ceil().to_usize().unwrap_or(1).max(1);
    let ny = (spec.height / cell).ceil().to_usize().unwrap_or(1).max(1);
    let mut cells: Vec<Vec<usize>> = vec![Vec::new(); nx * ny];
    let mut placed: Vec<([T; 2], T)> = Vec::with_capacity(sizes.len());
    let mut particles = Vec::with_capacity(sizes.len());
    for &(a, b, angle) in &sizes {
        let r = a * s;
        let mut ok = None;
        for _ in 0..PLACEMENT_ATTEMPTS {
            let (u, v): (f64, f64) = (rng.random(), rng.random());
            let x = r + (spec.width - T::lit(2.0) * r) * T::lit(u);
            let y = r + (spec.height - T::lit(2.0) * r) * T::lit(v);
            let cx = (x / cell).floor().to_usize().unwrap_or(0).min(nx - 1);
            let cy = (y / cell).floor().to_usize().unwrap_or(0).min(ny - 1);
            let mut free = true;
            'search: for gy in cy.saturating_sub(1)..=(cy + 1).min(ny - 1) {
                for gx in cx.saturating_sub(1)..=(cx + 1).min(nx - 1) {
                    for &k in &cells[gx + nx * gy] {
                        let (p, rk) = placed[k];
                        let (dx, dy) = (p[0] - x, p[1] - y);
                        if dx * dx + dy * dy < (r + rk) * (r + rk) {
                            free = false;
                            break 'search;
                        }
                    }
                }
            }
            if free {
                ok = Some(([x, y], cx + nx * cy));
                break;
            }
        }
        let Some((pos, c)) = ok else {
            return Err(LbdemError::field(
                "packing.solid_fraction",
                spec.solid_fraction.to_f64_exact(),
                &format!(
                    "could not place particle {} of {} in the box",
                    placed.len() + 1,
                    sizes.len()
                ),
                "lower the solid fraction or enlarge the box relative to the particles",
            ));
        };
        cells[c].push(placed.len());
        placed.push((pos, r));
        let shape = if spec.aspect_ratio < T::one() {
            Shape::Ellipse {
                semi_major: a,
                semi_minor: b,
            }
        } else {
            Shape::Disc { radius: a }
        };
        particles.push(Particle::new(
            lbdem_kernels::math::Vector::from(pos),
            angle,
            shape,
            spec.density,
        ));
    }
    Ok((particles, s))
}

fn scaled<T: Real>(shape: Shape<T>, f: T) -> Shape<T> {
    match shape {
        Shape::Disc { radius } => Shape::Disc { radius: radius * f },
        Shape::Ellipse {
            semi_major,
            semi_minor,
        } => Shape::Ellipse {
            semi_major: semi_major * f,
            semi_minor: semi_minor * f,
        },
    }
}

/// The whole procedure (steps 1–5): a packed sample at the isotropic stress, bonded with `bonds` if given.
pub fn generate_packing<T: Real>(
    spec: &PackingSpec<T>,
    bonds: Option<BondSpec<T>>,
) -> Result<Packing<T>> {
    let (full, s) = fill_box(spec)?;
    let shapes: Vec<Shape<T>> = full.iter().map(|p| p.shape).collect();
    // Frictionless while packing (P&C 2004 material genesis), so the assembly densifies; μ is restored below.
    // A normal dashpot (restitution PACKING_RESTITUTION) drains the energy the growth stores, which local
    // damping alone does not do for particles in free flight.
    let packing_contact = ContactModel {
        friction: T::zero(),
        restitution: T::lit(PACKING_RESTITUTION),
        ..spec.contact
    };
    let mut world = DemWorld::new(full, packing_contact, spec.timestep)?;
    let sample_box = world.add_box(
        Vector::zeros(),
        Vector::new(spec.width, spec.height),
        PlatenControl::Speed(T::zero()),
    );
    // Grow until the mean wall stress reaches the target (or full size); the rate slows as the stress
    // approaches it, Δf = (1 − s)/growth_steps × max(1 − σ_min/σ_target, 1e-3) with σ_min the least wall stress (all four walls loaded: a jammed, percolating assembly, not a few particles grown into a wall), so the jamming point is not
    // overshot (stored energy would later be released as a rattling gas).
    let growth = spec.growth_steps.max(1);
    let base_rate = (T::one() - s) / T::lit(growth as f64);
    let mut f = s;
    let mut grown = 0u64;
    let mean_stress = |w: &DemWorld<T>| -> T {
        w.platens
            .iter()
            .fold(T::infinity(), |a, p| a.min(p.stress()))
    };
    while f < T::one() && grown < 20 * growth {
        let sigma = mean_stress(&world);
        if sigma >= spec.isotropic_stress {
            break;
        }
        let slow = (T::one() - sigma / spec.isotropic_stress).max(T::lit(1e-3));
        f = (f + base_rate * slow).min(T::one());
        for (p, &shape) in world.particles.iter_mut().zip(&shapes) {
            p.shape = scaled(shape, f);
        }
        world.step();
        grown += 1;
    }
    let stresses = |w: &DemWorld<T>| -> [T; 4] {
        [
            w.platens[sample_box.left].stress(),
            w.platens[sample_box.right].stress(),
            w.platens[sample_box.bottom].stress(),
            w.platens[sample_box.top].stress(),
        ]
    };
    let within = |w: &DemWorld<T>| {
        stresses(w).iter().all(|&x| {
            (x - spec.isotropic_stress).abs() <= spec.stress_tolerance * spec.isotropic_stress
        })
    };
    // Radius adjustment between the fixed walls (P&C's isotropic-stress installation): relax, measure the
    // mean wall stress σ̄, rescale every size. First step Δf/f = ½(σ_target − σ̄)/k_n (a contact overlap
    // changes by 2Δr, so σ̄ changes by about k_n Δr/R), later steps by the secant through the last two
    // (f, σ̄), +0.5 % while the relaxed walls carry less than a tenth of the target, otherwise the relative change
    // clamped to ±0.1 %. Measured: servo-controlled walls (PFC gain) oscillate
    // here and pump energy into the assembly, so the walls stay fixed while packing.
    let mut converged = false;
    let mut servo_steps = 0;
    let mut previous: Option<(T, T)> = None;
    let kn = spec.contact.normal_stiffness;
    while servo_steps < spec.max_servo_steps {
        for _ in 0..RELAX_STEPS {
            world.step();
        }
        servo_steps += RELAX_STEPS;
        let st = stresses(&world);
        let sigma = (st[0] + st[1] + st[2] + st[3]) / T::lit(4.0);
        let settled = world.unbalanced_force_ratio() <= T::lit(UNBALANCED_TOLERANCE);
        if within(&world) && settled {
            converged = true;
            break;
        }
        let error = spec.isotropic_stress - sigma;
        let mut relative = T::lit(0.5) * error / kn;
        if sigma <= T::lit(0.1) * spec.isotropic_stress {
            relative = T::lit(UNLOADED_GROWTH);
        } else if let Some((f0, s0)) = previous {
            if s0 > T::zero() && sigma != s0 && f != f0 {
                relative = (error * (f - f0) / (sigma - s0)) / f;
            }
        }
        let limit = T::lit(LOADED_ADJUSTMENT);
        let relative = if sigma <= T::lit(0.1) * spec.isotropic_stress {
            relative
        } else {
            relative.max(-limit).min(limit)
        };
        previous = Some((f, sigma));
        f *= T::one() + relative;
        for (p, &shape) in world.particles.iter_mut().zip(&shapes) {
            p.shape = scaled(shape, f);
        }
    }
    // Final relaxation at the last size (static equilibrium for the bonds to start from).
    for _ in 0..RELAX_STEPS {
        world.step();
    }
    servo_steps += RELAX_STEPS;
    world.model = spec.contact;
    calm(&mut world);
    if let Some(b) = bonds {
        world.bond_touching_pairs(b, spec.bond_gap)?;
    }
    let wall_stresses = stresses(&world);
    let unbalanced_force_ratio = world.unbalanced_force_ratio();
    Ok(Packing {
        world,
        sample_box,
        converged,
        steps: grown + servo_steps,
        size_factor: f,
        unbalanced_force_ratio,
        wall_stresses,
    })
}

/// A hexagonal packing of `columns` × `rows` particles (benchmarks, snapshots): discs of radius
/// r (1 − `jitter` u), u uniform in [0, 1) from `seed`, on a triangular lattice of spacing 2r; with
/// `aspect_ratio` < 1 the lattice and the particles are squeezed along y (ellipses of semi-axes (r, (b/a) r),
/// aligned with x, still touching: an affine map keeps tangency). The lower-left particle is centred at (r, r).
pub fn hexagonal_packing<T: Real>(
    columns: usize,
    rows: usize,
    radius: T,
    aspect_ratio: T,
    jitter: T,
    density: T,
    seed: u64,
) -> Vec<Particle<T>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let dy = radius * T::lit(3f64.sqrt()) * aspect_ratio;
    let mut out = Vec::with_capacity(columns * rows);
    for row in 0..rows {
        let shift = if row % 2 == 1 { radius } else { T::zero() };
        for col in 0..columns {
            let u: f64 = rng.random();
            let a = radius * (T::one() - jitter * T::lit(u));
            let pos = [
                radius + shift + T::lit(2.0 * col as f64) * radius,
                radius * aspect_ratio + T::lit(row as f64) * dy,
            ];
            out.push(if aspect_ratio < T::one() {
                Particle::ellipse(
                    lbdem_kernels::math::Vector::from(pos),
                    T::zero(),
                    a,
                    a * aspect_ratio,
                    density,
                )
            } else {
                Particle::disc(lbdem_kernels::math::Vector::from(pos), a, density)
            });
        }
    }
    out
}

/// Put given particles in a box of four fixed platens touching their bounding box, and bond every pair
/// closer than `bond_gap` (when `bonds` is given). For regular packings ([`hexagonal_packing`]).
pub fn boxed_sample<T: Real>(
    particles: Vec<Particle<T>>,
    contact: ContactModel<T>,
    timestep: T,
    bonds: Option<BondSpec<T>>,
    bond_gap: T,
) -> Result<Packing<T>> {
    let mut world = DemWorld::new(particles, contact, timestep)?;
    let (lo, hi) = world.bounds();
    let sample_box = world.add_box(lo, hi, PlatenControl::Speed(T::zero()));
    if let Some(b) = bonds {
        world.bond_touching_pairs(b, bond_gap)?;
    }
    Ok(Packing {
        world,
        sample_box,
        converged: true,
        steps: 0,
        unbalanced_force_ratio: T::zero(),
        size_factor: T::one(),
        wall_stresses: [T::zero(); 4],
    })
}
