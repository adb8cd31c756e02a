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
use super::staged::{BoundaryStressRun, CompressionRun};
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

/// Run a compression test on a bonded packing (its world is advanced in place). `on_record` sees each
/// recorded point (progress, output).
pub fn run_compression<T: Real>(
    packing: &mut Packing<T>,
    test: &CompressionTest<T>,
    mut on_record: impl FnMut(&DemWorld<T>, &CurvePoint),
) -> CompressionResult {
    let w = &mut packing.world;
    let mut run = CompressionRun::new(w, packing.sample_box, *test);
    while !run.finished {
        if let Some(point) = run.advance(w) {
            on_record(w, &point);
        }
    }
    run.result(w)
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

/// Run [`BoundaryStressTest`] on a packing: returns the record, with the axial strain measured from the mean
/// height of the loaded particles (compression positive) and the lateral strain from the lateral platens.
pub fn run_boundary_stress<T: Real>(
    packing: &mut Packing<T>,
    test: &BoundaryStressTest<T>,
    mut on_record: impl FnMut(&DemWorld<T>, &CurvePoint),
) -> Vec<CurvePoint> {
    let w = &mut packing.world;
    let mut run = BoundaryStressRun::new(w, packing.sample_box, *test);
    while let Some(point) = run.advance(w) {
        on_record(w, &point);
    }
    run.curve
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
