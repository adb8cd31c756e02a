//! The coupled LB–DEM step (dissertation ch. 4.2.2, fig. 4.1; appendix 5.A): each step the grains are mapped
//! onto the lattice as partially-saturated cells with their rigid-body velocities (eq. 4.4–4.6), the fluid is
//! advanced, the momentum exchanged at covered nodes is reduced to a force and torque per grain (eq. 4.7–4.8),
//! and the DEM is advanced with those as applied loads. One DEM step per fluid step by default (as in the
//! dissertation); `substeps` DEM steps of Δt/substeps per fluid step as an option.
//!
//! Units: the DEM works in physical units, the fluid in lattice units. [`LatticeMap`] (in [`crate::units`], the
//! one converter) maps between them: x* = (x − origin)/h, u* = u Δt/h, ω* = ω Δt, F = F* ρ₀ h³/Δt² and
//! T = T* ρ₀ h⁴/Δt² (2-D, per unit thickness). The fluid sees each grain scaled by the "fluid radius" factor
//! (ch. 5.3.4).
//!
//! Momentum: the PSM collision hands each grain exactly the momentum the fluid loses at its covered nodes, and
//! the leapfrog integrator turns a force into exactly that momentum, so fluid + grains conserve momentum to
//! roundoff when nothing else acts (tested).
use lbdem_kernels::coupling::{BodyShape, CoupledBody};
use lbdem_kernels::dem::shape::Shape;
use lbdem_kernels::fluid::collide::Weighting;
use lbdem_kernels::math::{Point, Vector};
use lbdem_kernels::Real;
use std::time::{Duration, Instant};

use crate::engine::dem::world::DemWorld;
use crate::engine::lattice::FluidLattice;
use crate::error::{LbdemError, Result};
pub use crate::units::LatticeMap;

/// Wall-clock time spent in each stage of [`CoupledWorld::step`], accumulated over the steps taken while
/// enabled (see [`CoupledWorld::enable_timings`]). For benchmarks; results never depend on it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepTimings {
    /// Steps accumulated.
    pub steps: u64,
    /// Grains to lattice units and re-mapping them onto the lattice (`cover_with_bodies`).
    pub coverage: Duration,
    /// Fluid step: collide (BGK and PSM at covered nodes) and stream.
    pub fluid: Duration,
    /// Reduction of the exchanged momentum to a force and torque per grain, and their conversion to DEM loads.
    pub coupling: Duration,
    /// DEM step(s).
    pub dem: Duration,
}

impl StepTimings {
    /// Sum of the stages.
    pub fn total(&self) -> Duration {
        self.coverage + self.fluid + self.coupling + self.dem
    }
}

/// A fluid lattice (precision `T`, f64 by default) and a DEM world advanced together. Checkpoints (serde) hold
/// the fluid, the DEM world, the unit map, the fluid radius, the PSM weighting, the DEM substeps, the applied
/// loads, the per-grain fluid radii and the coupled step counter.
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(bound(
    serialize = "T: serde::Serialize",
    deserialize = "T: serde::de::DeserializeOwned"
))]
pub struct CoupledWorld<T: Real = f64> {
    /// The fluid.
    pub fluid: FluidLattice<T>,
    /// The grains, platens and bonds.
    pub dem: DemWorld<f64>,
    /// Unit conversion.
    pub map: LatticeMap,
    /// Fraction of each grain's size the fluid sees (dissertation: 0.6–0.95).
    pub fluid_radius: f64,
    /// PSM weighting.
    pub weighting: Weighting,
    /// DEM steps per fluid step.
    pub substeps: u32,
    /// Loads applied to each grain besides the fluid's (physical units): force and torque.
    pub applied: Vec<(Vector<f64>, f64)>,
    /// Per-grain fluid radius factors overriding `fluid_radius` (empty: every grain uses `fluid_radius`);
    /// used for bands of changed pore-throat size (dissertation §6.8.1).
    pub grain_fluid_radius: Vec<f64>,
    steps: u64,
    #[serde(skip)]
    timings: Option<StepTimings>,
}

impl<T: Real> CoupledWorld<T> {
    /// Couple a fluid and a DEM world. The DEM step must be the fluid step divided by `substeps`.
    pub fn new(
        fluid: FluidLattice<T>,
        mut dem: DemWorld<f64>,
        map: LatticeMap,
        fluid_radius: f64,
        weighting: Weighting,
        substeps: u32,
    ) -> Result<Self> {
        if !(fluid_radius > 0.0 && fluid_radius <= 1.0) {
            return Err(LbdemError::field(
                "coupling.fluid_radius",
                fluid_radius,
                "must lie in (0, 1]: the fraction of each grain's size the fluid sees",
                "the dissertation uses 0.6 (base fracture test) to 0.95",
            ));
        }
        if substeps == 0 {
            return Err(LbdemError::field(
                "coupling.substeps",
                0,
                "must be at least 1",
                "use 1 (the dissertation's 1:1)",
            ));
        }
        dem.set_timestep(map.timestep / substeps as f64)?;
        let n = dem.particles.len();
        dem.external_force = vec![lbdem_kernels::math::Vector::from([0.0; 2]); n];
        dem.external_torque = vec![0.0; n];
        Ok(Self {
            fluid,
            dem,
            map,
            fluid_radius,
            weighting,
            substeps,
            applied: vec![(Vector::zeros(), 0.0); n],
            grain_fluid_radius: Vec::new(),
            steps: 0,
            timings: None,
        })
    }

    /// Start (or restart from zero) accumulating the time spent in each stage of [`CoupledWorld::step`].
    pub fn enable_timings(&mut self) {
        self.timings = Some(StepTimings::default());
    }

    /// Time accumulated per stage since [`CoupledWorld::enable_timings`] (`None` when not enabled).
    pub fn timings(&self) -> Option<&StepTimings> {
        self.timings.as_ref()
    }

    /// Coupled steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The fluid's force and torque on each grain from the last coupled step (physical units), read back from
    /// the loads handed to the DEM minus [`CoupledWorld::applied`] (exact where nothing else is applied; else
    /// to the rounding of that sum); zeros before the first coupled step (no fluid has acted yet). Read-only.
    pub fn fluid_loads(&self) -> Vec<([f64; 2], f64)> {
        if self.steps == 0 {
            return vec![([0.0; 2], 0.0); self.dem.particles.len()];
        }
        self.dem
            .external_force
            .iter()
            .zip(&self.dem.external_torque)
            .zip(&self.applied)
            .map(|((f, t), (af, at))| ([f[0] - af[0], f[1] - af[1]], t - at))
            .collect()
    }

    /// The grains as the fluid sees them (lattice units).
    pub fn bodies(&self) -> Vec<CoupledBody<f64>> {
        let m = &self.map;
        let to_lattice_velocity = m.velocity_scale();
        self.dem
            .particles
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let factor = self
                    .grain_fluid_radius
                    .get(i)
                    .copied()
                    .unwrap_or(self.fluid_radius);
                let shape = match p.shape {
                    Shape::Disc { radius } => BodyShape::Disc {
                        radius: m.length_to_lattice(radius),
                    },
                    Shape::Ellipse {
                        semi_major,
                        semi_minor,
                    } => BodyShape::Ellipse {
                        semi_major: m.length_to_lattice(semi_major),
                        semi_minor: m.length_to_lattice(semi_minor),
                        angle: p.angle,
                    },
                };
                CoupledBody {
                    center: lbdem_kernels::math::Vector::from(
                        m.position_to_lattice(p.position.into()),
                    ),
                    velocity: lbdem_kernels::math::vector(
                        p.velocity[0] * to_lattice_velocity,
                        p.velocity[1] * to_lattice_velocity,
                    ),
                    spin: m.spin_to_lattice(p.angular_velocity),
                    shape: shape.scaled(factor),
                }
            })
            .collect()
    }

    /// Map the grains onto the lattice as they are now (coverage ε and rigid velocities at the nodes), as the
    /// next [`CoupledWorld::step`] does first: for looking at the lattice before the first step (a snapshot at
    /// t = 0). The next step maps the same grains again, which gives bitwise the same coverage (the coverage is a
    /// function of the grains only), so calling this never changes a result.
    pub fn map_grains(&mut self) {
        let bodies = self.bodies();
        self.fluid.cover_with_bodies(&bodies, self.weighting);
    }

    /// One coupled step: map grains → fluid step → fluid loads → DEM step(s).
    pub fn step(&mut self) {
        let timed = self.timings.is_some();
        let clock = || timed.then(Instant::now);
        let lap = |start: Option<Instant>| start.map_or(Duration::ZERO, |t| t.elapsed());
        let t0 = clock();
        let bodies = self.bodies();
        self.fluid.cover_with_bodies(&bodies, self.weighting);
        let coverage = lap(t0);
        let t0 = clock();
        self.fluid.step();
        let fluid = lap(t0);
        let t0 = clock();
        let centers: Vec<Point<f64>> = bodies.iter().map(|b| b.center).collect();
        // The fluid's forces on the grains are reduced (serially, in share order) while the first DEM
        // step's contact, bond and platen forces, which do not read them, are computed beside (rayon's
        // join: the second thread no longer waits through the reduction). Timed steps keep the two apart so
        // that each stage's time is its own. The same operations on the same values either way.
        let (lattice, dem) = (&self.fluid, &mut self.dem);
        let mut dem_forces = Duration::ZERO;
        let (forces, torques) = if timed {
            let reduced = lattice.solid_forces_and_torques(&centers);
            let t1 = clock();
            dem.contact_and_bond_forces();
            dem_forces = lap(t1);
            reduced
        } else {
            rayon::join(
                || lattice.solid_forces_and_torques(&centers),
                || dem.contact_and_bond_forces(),
            )
            .0
        };
        let (force_scale, torque_scale) = (self.map.force_scale(), self.map.torque_scale());
        for (i, ((f, t), (af, at))) in forces.iter().zip(&torques).zip(&self.applied).enumerate() {
            self.dem.external_force[i] =
                lbdem_kernels::math::vector(f[0] * force_scale + af[0], f[1] * force_scale + af[1]);
            self.dem.external_torque[i] = t * torque_scale + at;
        }
        let coupling = lap(t0).saturating_sub(dem_forces);
        let t0 = clock();
        self.dem.finish_step();
        for _ in 1..self.substeps {
            self.dem.step();
        }
        let dem = lap(t0) + dem_forces;
        if let Some(t) = &mut self.timings {
            t.steps += 1;
            t.coverage += coverage;
            t.fluid += fluid;
            t.coupling += coupling;
            t.dem += dem;
        }
        self.steps += 1;
    }
}
