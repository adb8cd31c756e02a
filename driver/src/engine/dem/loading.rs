//! Laboratory loading of a bonded sample between platens: uniaxial (unconfined) and biaxial (servo-confined)
//! compression at a constant platen speed (dissertation ch. 2: "servo controlled confining pressure, platen
//! velocity"; quasi-static with local damping 0.7 as in Potyondy & Cundall 2004).
//!
//! * Axial strain ε = (h₀ − h)/h₀, h the distance between the bottom and top platens, h₀ at the start of
//!   loading; axial stress σ_a = mean of the two axial platens' normal stresses (force / loaded length; the
//!   loaded length is the initial sample width when unconfined, the current lateral platen distance when
//!   confined); deviator q = σ_a − σ_a(start) for an unconfined sample, σ_a − σ_confining when confined.
//! * Young's modulus E: least-squares slope of q against ε over the points with q between 10 % and 50 % of the
//!   peak (the elastic stretch before bond breakage grows).
//! * Peak strength: the largest σ_a. The test stops once σ_a has fallen below `post_peak_fraction` × peak after
//!   the peak, or at `max_strain`.
//!
//! Units: consistent (2-D stresses are force per unit length of a unit-thickness sample).
use lbdem_kernels::Real;

use super::packing::Packing;
use super::world::{DemWorld, PlatenControl};

/// Parameters of a compression test.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CompressionTest<T> {
    /// Confining stress (0: unconfined, the lateral platens are removed).
    pub confining_stress: T,
    /// Speed of each axial platen (length/time; the strain rate is 2 v/h₀).
    pub platen_speed: T,
    /// Steps with the axial platens fixed before loading (the sample settles after the lateral change).
    pub settle_steps: u64,
    /// Stop when the strain exceeds this.
    pub max_strain: T,
    /// Stop once the stress falls below this fraction of the peak after the peak.
    pub post_peak_fraction: T,
    /// Steps between recorded points.
    pub record_interval: u64,
}

/// One recorded point of a compression test.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CurvePoint {
    /// World step.
    pub step: u64,
    /// Axial strain ε.
    pub axial_strain: f64,
    /// Lateral strain: width change / width at the start of loading, extension positive (the width is the
    /// lateral platen distance when confined, the particles' bounding-box width when unconfined).
    pub lateral_strain: f64,
    /// Axial stress σ_a.
    pub axial_stress: f64,
    /// Deviator q.
    pub deviator_stress: f64,
    /// Lateral stress (mean of the lateral platens; 0 unconfined).
    pub lateral_stress: f64,
    /// Bonds broken so far.
    pub broken_bonds: usize,
}

/// What a compression test measured.
#[derive(Clone, Debug, PartialEq)]
pub struct CompressionResult {
    /// The stress–strain record.
    pub curve: Vec<CurvePoint>,
    /// Peak axial stress.
    pub peak_stress: f64,
    /// Peak deviator stress.
    pub peak_deviator: f64,
    /// Axial strain at the peak.
    pub peak_strain: f64,
    /// Young's modulus (slope of q against ε between 10 % and 50 % of the peak deviator).
    pub youngs_modulus: f64,
    /// Steps of the loading stage.
    pub steps: u64,
}

/// Least-squares slope of y against x.
pub fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    if points.len() < 2 {
        return f64::NAN;
    }
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = points.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    sxy / sxx
}

/// The loading of the dissertation's fracture test (ch. 6.6) without fluid, its dry control: the lateral
/// stress is held by servo platens on the left and right, the axial stress (along y, the sample's short axis)
/// is applied as forces on the particles along the top boundary (the top platen is removed, so fluid could
/// pass), and the bottom platen is fixed.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BoundaryStressTest<T> {
    /// Lateral stress held by the servo platens.
    pub lateral_stress: T,
    /// Axial stress applied through the top boundary particles.
    pub axial_stress: T,
    /// Particles whose bounding circle reaches within this of the top of the assembly carry the axial load.
    pub boundary_depth: T,
    /// Steps to run.
    pub steps: u64,
    /// Steps between recorded points.
    pub record_interval: u64,
}

/// Parameters of a Brazilian (diametral compression) test of a bonded disc (Potyondy & Cundall 2004): two flat rigid
/// platens, below and above the disc, move towards each other at a constant speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BrazilianTest<T> {
    /// Disc diameter D used in σ_t = 2P/(πD) (unit thickness).
    pub diameter: T,
    /// Speed of each platen (length/time; the closure rate is twice it).
    pub platen_speed: T,
    /// Steps without platens before loading (the carved disc releases the packing's installed stress).
    pub settle_steps: u64,
    /// Stop when the platen closure exceeds this.
    pub max_closure: T,
    /// Stop once the load falls below this fraction of the peak after the peak (with bonds broken).
    pub post_peak_fraction: T,
    /// Steps between recorded points.
    pub record_interval: u64,
}

/// One recorded point of a Brazilian test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BrazilianPoint {
    /// World step.
    pub step: u64,
    /// Platen closure (decrease of the platen distance since the start of loading).
    pub closure: f64,
    /// Diametral load P: mean of the two platens' normal forces (compression positive, per unit thickness).
    pub load: f64,
    /// Bonds broken so far.
    pub broken_bonds: usize,
}

/// What a Brazilian test measured.
#[derive(Clone, Debug, PartialEq)]
pub struct BrazilianResult {
    /// The load–closure record.
    pub curve: Vec<BrazilianPoint>,
    /// Peak load P.
    pub peak_load: f64,
    /// Index of the peak in `curve`.
    pub peak_index: usize,
    /// Tensile strength σ_t = 2P/(πD).
    pub tensile_strength: f64,
    /// Steps of the loading stage.
    pub steps: u64,
}

/// Keep the particles of a packing whose bounding circles lie inside the circle of diameter `diameter`
/// centred in the sample box, in a new world (same contact model and step, no platens), and bond the touching
/// pairs.
pub fn carve_disc<T: Real>(
    packing: &Packing<T>,
    diameter: T,
    bonds: super::world::BondSpec<T>,
    bond_gap: T,
) -> crate::error::Result<DemWorld<T>> {
    let b = packing.sample_box;
    let w = &packing.world;
    let half = T::lit(0.5);
    let centre = [
        half * (w.platens[b.left].wall.point[0] + w.platens[b.right].wall.point[0]),
        half * (w.platens[b.bottom].wall.point[1] + w.platens[b.top].wall.point[1]),
    ];
    let particles: Vec<_> = w
        .particles
        .iter()
        .filter(|p| {
            let d = [p.position[0] - centre[0], p.position[1] - centre[1]];
            d[0].portable_hypot(d[1]) + p.shape.bounding_radius() <= half * diameter
        })
        .map(|p| {
            let mut p = *p;
            p.velocity = lbdem_kernels::math::Vector::from([T::zero(); 2]);
            p.angular_velocity = T::zero();
            p.acceleration = lbdem_kernels::math::Vector::from([T::zero(); 2]);
            p.angular_acceleration = T::zero();
            p
        })
        .collect();
    let mut world = DemWorld::new(particles, w.model, w.timestep())?;
    world.local_damping = w.local_damping;
    world.bond_touching_pairs(bonds, bond_gap)?;
    Ok(world)
}

/// Run a Brazilian test on a bonded disc without platens (the world is advanced in place): settle, add a
/// bottom and a top platen touching the disc, move them together at `platen_speed` each, and record the load.
pub fn run_brazilian<T: Real>(
    world: &mut DemWorld<T>,
    test: &BrazilianTest<T>,
    mut on_record: impl FnMut(&DemWorld<T>, &BrazilianPoint),
) -> BrazilianResult {
    for _ in 0..test.settle_steps {
        world.step();
    }
    let (lo, hi) = world.bounds();
    let width = hi[0] - lo[0];
    let (o, l) = (T::zero(), T::one());
    let fixed = PlatenControl::Speed(T::zero());
    let bottom = world.add_platen(super::world::Platen::new(
        lo,
        lbdem_kernels::math::vector(o, l),
        width,
        fixed,
    ));
    let top = world.add_platen(super::world::Platen::new(
        hi,
        lbdem_kernels::math::vector(o, -l),
        width,
        fixed,
    ));
    world.platens[bottom].control = PlatenControl::Speed(test.platen_speed);
    world.platens[top].control = PlatenControl::Speed(test.platen_speed);
    let gap = |w: &DemWorld<T>| {
        (w.platens[top].wall.point[1] - w.platens[bottom].wall.point[1]).to_f64_exact()
    };
    let normal_force =
        |w: &DemWorld<T>, k: usize| (w.platens[k].stress() * w.platens[k].length).to_f64_exact();
    let h0 = gap(world);
    let start_step = world.step_count();
    let interval = test.record_interval.max(1);
    let mut curve: Vec<BrazilianPoint> = Vec::new();
    let mut peak = f64::NEG_INFINITY;
    let mut peak_index = 0;
    loop {
        for _ in 0..interval {
            world.step();
        }
        let load = 0.5 * (normal_force(world, bottom) + normal_force(world, top));
        let point = BrazilianPoint {
            step: world.step_count(),
            closure: h0 - gap(world),
            load,
            broken_bonds: world.breaks.len(),
        };
        on_record(world, &point);
        curve.push(point);
        if load > peak {
            peak = load;
            peak_index = curve.len() - 1;
        }
        let failed = curve.len() - 1 > peak_index
            && !world.breaks.is_empty()
            && peak > 0.0
            && load < test.post_peak_fraction.to_f64_exact() * peak;
        if failed || point.closure > test.max_closure.to_f64_exact() || !load.is_finite() {
            break;
        }
    }
    BrazilianResult {
        tensile_strength: 2.0 * peak / (std::f64::consts::PI * test.diameter.to_f64_exact()),
        peak_load: peak,
        peak_index,
        steps: world.step_count() - start_step,
        curve,
    }
}

/// Outcome of [`uniaxial_strain_step`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StepLoadResult {
    /// Load-weighted mean vertical displacement of the loaded particles (downward positive).
    pub settlement: f64,
    /// Steps taken to equilibrium after the step.
    pub steps: u64,
    /// Whether the equilibrium criterion was met (false: the step limit was reached first).
    pub converged: bool,
}

/// Load-weighted mean height of `loaded` (weights: bounding radii, the shares of
/// [`DemWorld::apply_boundary_stress`]), i.e. the displacement work-conjugate to the applied stress.
pub fn loaded_height<T: Real>(w: &DemWorld<T>, loaded: &[usize]) -> f64 {
    let (mut s, mut ws) = (0.0, 0.0);
    for &i in loaded {
        let r = w.particles[i].shape.bounding_radius().to_f64_exact();
        s += r * w.particles[i].position[1].to_f64_exact();
        ws += r;
    }
    s / ws
}

/// Step `w` in blocks of `block` steps until the loaded layer stops moving: the change of
/// [`loaded_height`] over a block below `tolerance` × `scale` (a length) and the unbalanced-force ratio below
/// 1e-2, or `max_steps`. Returns (steps, converged).
pub fn settle_loaded<T: Real>(
    w: &mut DemWorld<T>,
    loaded: &[usize],
    block: u64,
    scale: f64,
    tolerance: f64,
    max_steps: u64,
) -> (u64, bool) {
    let mut steps = 0;
    let mut last = loaded_height(w, loaded);
    while steps < max_steps {
        for _ in 0..block {
            w.step();
        }
        steps += block;
        let now = loaded_height(w, loaded);
        let quiet = (now - last).abs() <= tolerance * scale
            && w.unbalanced_force_ratio().to_f64_exact() < 1e-2;
        last = now;
        if quiet {
            return (steps, true);
        }
    }
    (steps, false)
}

/// The drained (dry) uniaxial-strain step load: with the lateral and bottom platens fixed and a vertical
/// stress already applied through the `loaded` particles (top platen removed) and settled, set it to
/// `target_stress` over the loaded length `length` and settle again ([`settle_loaded`] with the given
/// block, tolerance relative to the settlement so far and limit). The constrained modulus is then
/// `(target − previous stress) / (settlement / height)` ([`lbdem_reference::poroelastic::constrained_modulus`]).
pub fn uniaxial_strain_step<T: Real>(
    w: &mut DemWorld<T>,
    loaded: &[usize],
    target_stress: T,
    length: T,
    block: u64,
    tolerance: f64,
    max_steps: u64,
) -> StepLoadResult {
    let y0 = loaded_height(w, loaded);
    w.apply_boundary_stress(
        loaded,
        lbdem_kernels::math::vector(T::zero(), -T::one()),
        target_stress,
        length,
    );
    let mut steps = 0;
    let mut converged = false;
    let mut last = y0;
    while steps < max_steps {
        for _ in 0..block {
            w.step();
        }
        steps += block;
        let now = loaded_height(w, loaded);
        let moved = y0 - now;
        if (now - last).abs() <= tolerance * moved.abs()
            && w.unbalanced_force_ratio().to_f64_exact() < 1e-2
        {
            converged = true;
            last = now;
            break;
        }
        last = now;
    }
    StepLoadResult {
        settlement: y0 - last,
        steps,
        converged,
    }
}
