//! Laboratory loading of a bonded sample between platens: uniaxial (unconfined) and biaxial (servo-confined)
//! compression at a constant platen speed (dissertation ch. 2: "servo controlled confining pressure, platen
//! velocity"; REFERENCE §7.4: quasi-static with local damping 0.7).
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
use super::world::{DemWorld, PlatenControl, SampleBox};

/// Parameters of a compression test.
#[derive(Clone, Copy, Debug, PartialEq)]
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
#[derive(Clone, Copy, Debug, PartialEq)]
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

fn axial_stress<T: Real>(w: &DemWorld<T>, b: &SampleBox) -> T {
    T::lit(0.5) * (w.platens[b.bottom].stress() + w.platens[b.top].stress())
}

/// Run a compression test on a bonded packing (its world is advanced in place). `on_record` sees each
/// recorded point (progress, output).
pub fn run_compression<T: Real>(
    packing: &mut Packing<T>,
    test: &CompressionTest<T>,
    mut on_record: impl FnMut(&DemWorld<T>, &CurvePoint),
) -> CompressionResult {
    let b = packing.sample_box;
    let w = &mut packing.world;
    let width0 = w.platens[b.right].wall.point[0] - w.platens[b.left].wall.point[0];
    let confined = test.confining_stress > T::zero();
    if confined {
        let servo = PlatenControl::Servo {
            target_stress: test.confining_stress,
            relaxation: T::lit(0.5),
            max_speed: T::lit(10.0) * test.platen_speed,
        };
        w.platens[b.left].control = servo;
        w.platens[b.right].control = servo;
    } else {
        w.platens[b.left].active = false;
        w.platens[b.right].active = false;
        w.sample_box = None;
        w.platens[b.bottom].length = width0;
        w.platens[b.top].length = width0;
    }
    w.platens[b.bottom].control = PlatenControl::Speed(T::zero());
    w.platens[b.top].control = PlatenControl::Speed(T::zero());
    for _ in 0..test.settle_steps {
        w.step();
    }
    let h0 = (w.platens[b.top].wall.point[1] - w.platens[b.bottom].wall.point[1]).to_f64_exact();
    let lateral0 = if confined {
        (w.platens[b.right].wall.point[0] - w.platens[b.left].wall.point[0]).to_f64_exact()
    } else {
        let (lo, hi) = w.bounds();
        (hi[0] - lo[0]).to_f64_exact()
    };
    let start_stress = axial_stress(w, &b).to_f64_exact();
    let reference = if confined {
        test.confining_stress.to_f64_exact()
    } else {
        start_stress
    };
    w.platens[b.bottom].control = PlatenControl::Speed(test.platen_speed);
    w.platens[b.top].control = PlatenControl::Speed(test.platen_speed);
    let mut curve = Vec::new();
    let mut peak = f64::NEG_INFINITY;
    let mut peak_at = 0;
    let start_step = w.step_count();
    let interval = test.record_interval.max(1);
    loop {
        for _ in 0..interval {
            w.step();
        }
        let h = (w.platens[b.top].wall.point[1] - w.platens[b.bottom].wall.point[1]).to_f64_exact();
        let lateral = if confined {
            (w.platens[b.right].wall.point[0] - w.platens[b.left].wall.point[0]).to_f64_exact()
        } else {
            let (lo, hi) = w.bounds();
            (hi[0] - lo[0]).to_f64_exact()
        };
        let sa = axial_stress(w, &b).to_f64_exact();
        let lateral_stress = if confined {
            0.5 * (w.platens[b.left].stress() + w.platens[b.right].stress()).to_f64_exact()
        } else {
            0.0
        };
        let point = CurvePoint {
            step: w.step_count(),
            axial_strain: (h0 - h) / h0,
            lateral_strain: (lateral - lateral0) / lateral0,
            axial_stress: sa,
            deviator_stress: sa - reference,
            lateral_stress,
            broken_bonds: w.breaks.len(),
        };
        on_record(w, &point);
        curve.push(point);
        if sa > peak {
            peak = sa;
            peak_at = curve.len() - 1;
        }
        // Failure: past the peak, bonds broken, and the deviator down to the given fraction of its peak.
        let q_peak = peak - reference;
        let past_peak = curve.len() - 1 > peak_at
            && !w.breaks.is_empty()
            && q_peak > 0.0
            && sa - reference < test.post_peak_fraction.to_f64_exact() * q_peak;
        if past_peak || point.axial_strain > test.max_strain.to_f64_exact() || !sa.is_finite() {
            break;
        }
    }
    let peak_point = curve[peak_at];
    let q_peak = peak_point.deviator_stress;
    let elastic: Vec<(f64, f64)> = curve[..=peak_at]
        .iter()
        .filter(|p| p.deviator_stress >= 0.1 * q_peak && p.deviator_stress <= 0.5 * q_peak)
        .map(|p| (p.axial_strain, p.deviator_stress))
        .collect();
    CompressionResult {
        youngs_modulus: slope(&elastic),
        peak_stress: peak,
        peak_deviator: q_peak,
        peak_strain: peak_point.axial_strain,
        steps: w.step_count() - start_step,
        curve,
    }
}

/// The loading of the dissertation's fracture test (ch. 6.6) without fluid, its dry control: the lateral
/// stress is held by servo platens on the left and right, the axial stress (along y, the sample's short axis)
/// is applied as forces on the particles along the top boundary (the top platen is removed, so fluid could
/// pass), and the bottom platen is fixed.
#[derive(Clone, Copy, Debug, PartialEq)]
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
    let b = packing.sample_box;
    let w = &mut packing.world;
    w.platens[b.top].active = false;
    w.sample_box = None;
    let width = w.platens[b.right].wall.point[0] - w.platens[b.left].wall.point[0];
    let height = w.platens[b.top].wall.point[1] - w.platens[b.bottom].wall.point[1];
    w.platens[b.bottom].length = width;
    w.platens[b.bottom].control = PlatenControl::Speed(T::zero());
    for side in [b.left, b.right] {
        w.platens[side].length = height;
        w.platens[side].control = PlatenControl::Servo {
            target_stress: test.lateral_stress,
            relaxation: T::lit(0.5),
            max_speed: T::lit(1e-3) * height / w.timestep(),
        };
    }
    let top = w.boundary_particles(3, test.boundary_depth);
    w.apply_boundary_stress(&top, [T::zero(), -T::one()], test.axial_stress, width);
    let mean_top = |w: &DemWorld<T>| {
        top.iter()
            .map(|&i| w.particles[i].position[1].to_f64_exact())
            .sum::<f64>()
            / top.len().max(1) as f64
    };
    let (y0, h0) = (mean_top(w), height.to_f64_exact());
    let lateral0 = width.to_f64_exact();
    let mut curve = Vec::new();
    let interval = test.record_interval.max(1);
    let mut done = 0;
    while done < test.steps {
        for _ in 0..interval.min(test.steps - done) {
            w.step();
        }
        done += interval.min(test.steps - done);
        let lateral =
            (w.platens[b.right].wall.point[0] - w.platens[b.left].wall.point[0]).to_f64_exact();
        let axial = w.platens[b.bottom].stress().to_f64_exact();
        let point = CurvePoint {
            step: w.step_count(),
            axial_strain: (y0 - mean_top(w)) / h0,
            lateral_strain: (lateral - lateral0) / lateral0,
            axial_stress: axial,
            deviator_stress: axial
                - 0.5 * (w.platens[b.left].stress() + w.platens[b.right].stress()).to_f64_exact(),
            lateral_stress: 0.5
                * (w.platens[b.left].stress() + w.platens[b.right].stress()).to_f64_exact(),
            broken_bonds: w.breaks.len(),
        };
        on_record(w, &point);
        curve.push(point);
    }
    curve
}

/// Parameters of a Brazilian (diametral compression) test of a bonded disc (REFERENCE §7.4): two flat rigid
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
            p.velocity = [T::zero(); 2];
            p.angular_velocity = T::zero();
            p.acceleration = [T::zero(); 2];
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
    let bottom = world.add_platen(super::world::Platen::new(lo, [o, l], width, fixed));
    let top = world.add_platen(super::world::Platen::new(hi, [o, -l], width, fixed));
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
