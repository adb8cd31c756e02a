//! `kind = "pressure_diffusion"`: 1-D transient pressure diffusion through a packed slab (dissertation §5.6.2,
//! fig. 5.7–5.9, eq. 5.12).
//!
//! A slab of packed grains (the dissertation's packing procedure) between Zou–He pressure faces at x = 0 and
//! x = 2L (walls north and south), fluid at initial overpressure P₀, faces at P = 0. The grains are **held
//! fixed**: the fluid storage is then the LB fluid compressibility alone, so the continuum prediction has no
//! free parameter (the dissertation's grains were free but unbonded quartz, whose skeleton compliance is
//! negligible against the LB fluid's). Darcy + mass conservation with p = c_s²ρ and μ = ρν give
//! n ∂ρ/∂t = ∇·((k c_s²/ν)∇ρ), i.e. **c = k c_s²/(ν n)** (lattice units). k is measured first by a steady
//! Zou–He Darcy run on the same coverage ([`crate::observe::darcy`]), k = ν j 2L/(c_s² Δρ) with j the mass flux
//! per unit width; n is the effective storage porosity measured from the fluid mass the slab releases,
//! n = ΔM/(A P₀' (1 − P̄/P₀)) (A = 2L × width, P₀' the initial density excess, P̄/P₀ the analytic mean at the
//! last snapshot). The effective n differs from the geometric 1 − ⟨ε⟩ because fluid at fully covered nodes is
//! sealed in by the solid operator's bounce-back (ΩΛ, the default, and Ω₃: it never drains) while partially
//! covered nodes store fully: both porosities are reported. The diffusivity is fitted to cross-section averages over fluid-only nodes (ε = 0, as
//! the dissertation did) of P/P₀ at several times, by Gauss–Newton on ln c
//! ([`crate::observe::fit::fit_diffusivity`]), to the slab series
//! ([`lbdem_reference::analytic::slab_pressure`]).
use std::path::Path;

use lbdem_kernels::coupling::{BodyShape, CoupledBody};
use lbdem_kernels::dem::shape::Particle;
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::SolidOperator;
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_reference::analytic::{slab_mean_pressure, slab_pressure};
use serde::{Deserialize, Serialize};

use crate::engine::dem::packing::{
    check_packing_spec, generate_packing, hexagonal_packing, PackingSpec,
};
use crate::engine::dem::world::{DemWorld, CRITICAL_STEP_SAFETY};
use crate::engine::exec::{Exec, ExecTarget};
use crate::engine::lattice::FluidLattice;
use crate::error::{positive, LbdemError, Result};
use crate::input::limits::{self, Budget, GRAIN_BYTES};
use crate::observe::darcy::{permeability, SteadyFlow};
use crate::observe::fit::fit_diffusivity;
use crate::observe::health::fluid_health;
use crate::observe::steady::Steadiness;
use crate::output::snapshots::{write_fixed, FixedSnapshots};
use crate::output::vtk::LatticeFrame;
use crate::output::{csv, write_atomic};
use crate::run::{run_in_memory, Case, Kind, OutputStage, Persist, RunOptions};
use crate::scene::{CheckpointSection, SceneHeader, UnitsSetup};
use crate::units::{FluidSection, CS2};

/// Relative change of the outlet flux per 200 steps below which the Darcy run counts as steady. The slowest
/// mode of the approach decays over (2L)²/(π² c) steps (~2 000 in the fast scene), so the flux left to gain is
/// about this × (decay time / 200) ≈ 1e-4 relative: far below the other errors of the check.
const DARCY_TOLERANCE: f64 = 1e-5;

/// The Darcy run's step limit (it stops there steady or not; the permeability is then reported as not
/// converged).
const DARCY_MAX_STEPS: u64 = 400_000;

/// The largest Fourier number of a snapshot: at c t / L² = 10 the slab's mean overpressure is below 1e-10 P₀
/// (eq. 5.12, slowest mode e^{−π² Fo / 4}), so later snapshots measure nothing.
const MAX_FOURIER: f64 = 10.0;

const HINT: &str =
    "lower pressure_diffusion.overpressure or darcy_pressure_drop, or raise fluid.tau";

/// `[pressure_diffusion]`
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PressureDiffusionSection {
    /// Width of the packing box along x (the drained direction).
    pub width: f64,
    /// Height of the packing box along y.
    pub height: f64,
    /// Smallest grain radius.
    pub radius_min: f64,
    /// Largest grain radius.
    pub radius_max: f64,
    /// Packing seed.
    pub seed: u64,
    /// Fraction of each grain's radius the fluid sees (dissertation 0.6–0.95).
    pub fluid_radius: f64,
    /// Initial overpressure P₀.
    pub overpressure: f64,
    /// Pressure drop of the steady Darcy run that measures k.
    pub darcy_pressure_drop: f64,
    /// Snapshot times as Fourier numbers c_pred t/L² (c_pred from the measured k and geometric porosity).
    pub fourier_times: Vec<f64>,
    /// Solid operator of the fixed grains; absent: ΩΛ ([`fluid_choice`]).
    #[serde(default)]
    pub solid_operator: Option<SolidOperator>,
}

/// The default fluid collision and the solid operator of the (fixed) grains: ΩΛ with TRT unless
/// `solid_operator` names another operator (then BGK, the dissertation's); `[fluid] collision` overrides the
/// collision. ΩΛ's permeability does not move with τ (README, issue 11).
pub fn fluid_choice(
    scene: &PressureDiffusionScene,
) -> (crate::units::CollisionName, SolidOperator) {
    use crate::units::CollisionName;
    match scene.pressure_diffusion.solid_operator {
        None | Some(SolidOperator::LambdaConsistent) => {
            (CollisionName::Trt, SolidOperator::LambdaConsistent)
        }
        Some(op) => (CollisionName::Bgk, op),
    }
}

/// A pressure-diffusion scene file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PressureDiffusionScene {
    /// `[scene]`
    pub scene: SceneHeader,
    /// `[fluid]`
    pub fluid: FluidSection,
    /// `[pressure_diffusion]`
    pub pressure_diffusion: PressureDiffusionSection,
    /// `[run]`
    #[serde(default)]
    pub run: CheckpointSection,
}

crate::scene::scene_file!(PressureDiffusionScene);

/// One recorded cross-section-averaged profile.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Profile {
    /// Step of the snapshot.
    pub step: u64,
    /// Fourier number c_fit t/L².
    pub fourier: f64,
    /// (distance from the west face in nodes, measured P/P₀, fitted P/P₀).
    pub points: Vec<(f64, f64, f64)>,
}

/// Outcome of a pressure-diffusion run (lattice units unless said).
#[derive(Clone, Debug, Serialize)]
pub struct DiffusionOutcome {
    /// Lattice size.
    pub nodes: [usize; 2],
    /// Grains in the slab.
    pub grains: usize,
    /// Half-length L of the slab (nodes): faces at x = 0 and 2L.
    pub half_length: f64,
    /// Geometric porosity 1 − ⟨ε⟩ over the interior.
    pub geometric_porosity: f64,
    /// Storage porosity measured from the mass released.
    pub storage_porosity: f64,
    /// Darcy permeability k (nodes²).
    pub permeability: f64,
    /// k in physical units.
    pub permeability_physical: f64,
    /// Steps of the Darcy run.
    pub darcy_steps: u64,
    /// Predicted c = k c_s²/(ν n_storage).
    pub predicted_diffusivity: f64,
    /// Predicted c with the geometric porosity.
    pub predicted_diffusivity_geometric: f64,
    /// Fitted c (nodes²/step).
    pub fitted_diffusivity: f64,
    /// Fitted c in physical units.
    pub fitted_diffusivity_physical: f64,
    /// fitted / predicted − 1.
    pub diffusivity_error: f64,
    /// RMS of P/P₀ − fit over all samples.
    pub rms_residual: f64,
    /// Gauss–Newton iterations.
    pub fit_iterations: usize,
    /// Samples fitted.
    pub samples: usize,
    /// The snapshots.
    pub profiles: Vec<Profile>,
}

/// The run: the Darcy lattice until its flow is steady, then the drainage of the overpressured slab.
#[derive(Serialize, Deserialize)]
pub struct DiffusionState {
    grains: usize,
    nx: usize,
    ny: usize,
    darcy: Option<FluidLattice<f64>>,
    flow: SteadyFlow,
    drho_d: f64,
    permeability: f64,
    geometric_porosity: f64,
    c_geo: f64,
    fluid: FluidLattice<f64>,
    drho: f64,
    m0: f64,
    times: Vec<u64>,
    columns: Vec<(usize, Vec<usize>)>,
    raw: Vec<(u64, Vec<(f64, f64)>)>,
    step: u64,
    /// The grains as the fluid holds them (fixed, at rest; physical units), for the snapshots.
    solids: Vec<Particle<f64>>,
    /// Physical position of lattice node (0, 0).
    origin: [f64; 2],
    /// Snapshots of the drainage written so far.
    snapshots: usize,
}

impl Persist for DiffusionState {}

/// The packing of the slab (physical units), by the dissertation's procedure: what `start` packs.
fn slab_packing(d: &PressureDiffusionSection) -> PackingSpec<f64> {
    let mut spec = PackingSpec::dissertation(d.width, d.height, 1.0, d.seed);
    spec.radius_min = d.radius_min;
    spec.radius_max = d.radius_max;
    spec
}

/// What the packing of `start` refuses, checked before it (so that `check` refuses it too), naming this kind's
/// fields: the slab's size against the grains ([`check_packing_spec`]), and the packing's DEM step (the
/// dissertation's, 5e-5 s) against the critical step of the lightest grain, of radius `radius_min` (a 2 x 2
/// probe of them: the critical step takes an assumed coordination, not the actual contacts; the packed grains
/// are no lighter, so this refuses all that the packing refuses).
fn check_slab_packing(d: &PressureDiffusionSection) -> Result<()> {
    let spec = slab_packing(d);
    check_packing_spec(&spec).map_err(|e| match e {
        LbdemError::InvalidField {
            field,
            value,
            problem,
            hint,
        } => LbdemError::InvalidField {
            field: field.replacen("packing.", "pressure_diffusion.", 1),
            value,
            problem,
            hint,
        },
        e => e,
    })?;
    let probe = hexagonal_packing(2, 2, d.radius_min, 1.0, 0.0, spec.density, 0);
    if DemWorld::new(probe, spec.contact, spec.timestep).is_err() {
        return Err(LbdemError::field(
            "pressure_diffusion.radius_min",
            d.radius_min,
            &format!(
                "gives grains so light that the packing's DEM step ({:e}, the dissertation's, with its contact \
                 stiffness) exceeds {CRITICAL_STEP_SAFETY} x their critical step",
                spec.timestep
            ),
            "use larger grains (the dissertation's radii are 0.07-0.11 cm)",
        ));
    }
    Ok(())
}

fn start(case: &Case<PressureDiffusion>, exec: &Exec) -> Result<DiffusionState> {
    let d = &case.scene.pressure_diffusion;
    let u = &case.setup.units;
    let h = u.spacing;
    let packing = generate_packing(&slab_packing(d), None)?;
    let world = packing.world;
    let (lo, hi) = world.bounds();
    // Lattice: Zou–He faces at the slab faces x = lo, hi; walls half a spacing outside the first/last rows.
    let nx = ((hi[0] - lo[0]) / h).round() as usize + 1;
    let ny = ((hi[1] - lo[1]) / h).round().max(1.0) as usize;
    let map_x = |x: f64| (x - lo[0]) / h;
    let map_y = |y: f64| (y - lo[1]) / h - 0.5;
    let bodies: Vec<CoupledBody<f64>> = world
        .particles
        .iter()
        .map(|p| CoupledBody {
            center: lbdem_kernels::math::vector(map_x(p.position[0]), map_y(p.position[1])),
            velocity: lbdem_kernels::math::Vector::from([0.0; 2]),
            spin: 0.0,
            shape: BodyShape::Disc {
                radius: p.shape.bounding_radius() / h * d.fluid_radius,
            },
        })
        .collect();
    let tau = u.tau;
    let (default_collision, op) = fluid_choice(&case.scene);
    let wf = op.weighting();
    let make = |west: f64, east: f64| -> Result<FluidLattice<f64>> {
        let mut f = FluidLattice::new(
            nx,
            ny,
            Boundaries {
                west: SideCondition::Pressure { density: west },
                east: SideCondition::Pressure { density: east },
                south: SideCondition::Wall,
                north: SideCondition::Wall,
            },
            FluidParams {
                tau,
                force: [0.0; 2],
            },
        )?;
        exec.apply(&mut f);
        f.set_collision(crate::units::collision_of(
            case.scene.fluid.checked_collision(default_collision, tau)?,
        )?)?;
        f.set_solid_operator(op);
        f.set_lambda_terms(case.scene.fluid.lambda_terms(op)?)?;
        f.cover_with_bodies(&bodies, wf);
        Ok(f)
    };
    let two_l = (nx - 1) as f64;
    // 1. Steady Darcy run: k = ν j 2L/(c_s² Δρ).
    let drho_d = u.pressure_to_density_change(d.darcy_pressure_drop);
    let mut darcy = make(1.0 + drho_d, 1.0)?;
    darcy.fill_equilibrium(|x, _| (1.0 + drho_d * (1.0 - x as f64 / two_l), [0.0; 2]));
    // 2. Transient drainage from P₀ (stepped once the Darcy run is steady).
    let drho = u.pressure_to_density_change(d.overpressure);
    let mut fluid = make(1.0, 1.0)?;
    fluid.fill_equilibrium(|x, _| {
        if x == 0 || x + 1 == nx {
            (1.0, [0.0; 2])
        } else {
            (1.0 + drho, [0.0; 2])
        }
    });
    let m0 = fluid.mass();
    // The grains as the fluid holds them: fixed, at rest (the packing's settling velocities do not enter).
    let solids = world
        .particles
        .iter()
        .map(|p| {
            let mut q = *p;
            q.velocity = lbdem_kernels::math::Vector::zeros();
            q.angular_velocity = 0.0;
            q
        })
        .collect();
    Ok(DiffusionState {
        grains: world.particles.len(),
        nx,
        ny,
        darcy: Some(darcy),
        flow: SteadyFlow::new(Steadiness::new(DARCY_TOLERANCE), 200, DARCY_MAX_STEPS),
        drho_d,
        permeability: f64::NAN,
        geometric_porosity: f64::NAN,
        c_geo: f64::NAN,
        fluid,
        drho,
        m0,
        times: Vec::new(),
        columns: Vec::new(),
        raw: Vec::new(),
        step: 0,
        solids,
        // Node (i, j) is at x = lo + i h, y = lo + (j + ½) h (the inverse of `map_x`, `map_y`).
        origin: [lo[0], lo[1] + 0.5 * h],
        snapshots: 0,
    })
}

/// The drainage's snapshot steps, sorted and without repeats: Fo L²/c rounded (at least 1) for each Fourier
/// number Fo of `fourier_times`, with L the slab's half-length (nodes) and c the diffusivity the Darcy run
/// measured (nodes²/step). The step count follows from that measurement, so it is refused here, at run time,
/// above [`limits::MAX_STEPS`], naming `pressure_diffusion.fourier_times` (a scene cannot reach this in a short
/// run: the Darcy run before it needs of the order of L²/c steps to become steady, and is capped at
/// `DARCY_MAX_STEPS`, while the refusal needs Fo L²/c > 10⁹ with Fo ≤ 10).
fn drainage_steps(fourier_times: &[f64], half_length: f64, c_geo: f64) -> Result<Vec<u64>> {
    // A diffusivity that is not a positive finite number (a pack that blocks the flow, a reversed or non-finite
    // flux) would turn every drainage time into 1 step (NaN and negative products clamp to 1) and the run would
    // report a fit of nothing: refused here, before any drainage step.
    if !(c_geo.is_finite() && c_geo > 0.0) {
        return Err(LbdemError::field(
            "pressure_diffusion",
            format!("{c_geo:e}"),
            "the Darcy run measured a diffusivity k c_s^2/(nu n) that is not a positive finite number (nodes^2/step), \
             so the drainage times cannot be set",
            "the pack must leave a connected path for the fluid between the two faces: lower \
             pressure_diffusion.fluid_radius (or fewer, smaller grains)",
        ));
    }
    let fourier_unit = half_length * half_length / c_geo;
    let mut times: Vec<u64> = fourier_times
        .iter()
        .map(|f| (f * fourier_unit).round().max(1.0) as u64)
        .collect();
    times.sort_unstable();
    times.dedup();
    if let Some(&last) = times.last() {
        if last > limits::MAX_STEPS {
            return Err(LbdemError::field(
                "pressure_diffusion.fourier_times",
                format!("{fourier_times:?}"),
                &format!(
                    "with the diffusivity the Darcy run measured ({c_geo:.3e} nodes^2/step: one Fourier unit \
                     L^2/c is {fourier_unit:.3e} steps) the drainage needs {last} steps, above the limit of {} \
                     steps per run",
                    limits::MAX_STEPS
                ),
                "use smaller Fourier times, a shorter slab (pressure_diffusion.width) or a coarser fluid.spacing",
            ));
        }
    }
    Ok(times)
}

impl DiffusionState {
    fn finished(&self) -> bool {
        self.darcy.is_none() && self.raw.len() >= self.times.len()
    }

    /// The next snapshot of the drainage: the grains (held fixed) and the lattice, pressure 0 at the faces'
    /// density 1, at model time steps × Δt since the drainage began.
    fn snapshot(&mut self, case: &Case<PressureDiffusion>, at: &FixedSnapshots) -> Result<()> {
        let u = &case.setup.units;
        let frame = LatticeFrame::of(u, self.origin, 1.0);
        let time = self.step as f64 * u.timestep;
        write_fixed(at, self.snapshots, time, &self.solids, &self.fluid, &frame)?;
        self.snapshots += 1;
        Ok(())
    }

    fn advance(
        &mut self,
        case: &Case<PressureDiffusion>,
        at: Option<&FixedSnapshots>,
    ) -> Result<()> {
        let (nx, ny) = (self.nx, self.ny);
        let nu = case.setup.units.lattice_viscosity;
        let two_l = (nx - 1) as f64;
        let half_length = 0.5 * two_l;
        if let Some(darcy) = &mut self.darcy {
            let outlet_flux = |f: &FluidLattice<f64>| -> f64 {
                let (rho, vel) = f.moments();
                (0..ny)
                    .map(|y| {
                        let i = y * nx + (nx - 1);
                        rho[i] * vel[i][0]
                    })
                    .sum::<f64>()
                    / ny as f64
            };
            if !self.flow.advance(darcy, outlet_flux, HINT)? {
                return Ok(());
            }
            let k = permeability(nu, self.flow.flux, two_l, CS2 * self.drho_d);
            let eps = darcy.solid_fraction_map();
            let interior = |i: usize| {
                let x = i % nx;
                x > 0 && x + 1 < nx
            };
            let geometric_porosity = 1.0
                - eps
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| interior(*i))
                    .map(|(_, e)| e)
                    .sum::<f64>()
                    / ((nx - 2) * ny) as f64;
            let c_geo = k * CS2 / (nu * geometric_porosity);
            let times = drainage_steps(
                &case.scene.pressure_diffusion.fourier_times,
                half_length,
                c_geo,
            )?;
            // Columns with fluid-only nodes, and those nodes.
            self.columns = (1..nx - 1)
                .map(|x| {
                    (
                        x,
                        (0..ny)
                            .map(|y| y * nx + x)
                            .filter(|&i| eps[i] == 0.0)
                            .collect::<Vec<_>>(),
                    )
                })
                .filter(|(_, v)| !v.is_empty())
                .collect();
            self.permeability = k;
            self.geometric_porosity = geometric_porosity;
            self.c_geo = c_geo;
            self.times = times;
            self.darcy = None;
            return Ok(());
        }
        let Some(&target) = self.times.get(self.raw.len()) else {
            return Ok(());
        };
        // Snapshot 0 before the first drainage step, then one at each profile (the last at the end).
        if let Some(at) = at.filter(|_| self.snapshots == 0) {
            self.snapshot(case, at)?;
        }
        // Up to the next snapshot, at most 1000 steps at a time.
        let end = target.min((self.step / 1000 + 1) * 1000);
        while self.step < end {
            self.fluid.step();
            self.step += 1;
        }
        if self.step == target {
            let (rho, _) = self.fluid.moments();
            let drho = self.drho;
            let prof = self
                .columns
                .iter()
                .map(|(x, nodes)| {
                    let mean = nodes.iter().map(|&i| rho[i]).sum::<f64>() / nodes.len() as f64;
                    (*x as f64, (mean - 1.0) / drho)
                })
                .collect();
            self.raw.push((self.step, prof));
            if let Some(at) = at {
                self.snapshot(case, at)?;
            }
        }
        Ok(())
    }

    fn outcome(&self, case: &Case<PressureDiffusion>) -> DiffusionOutcome {
        let (nx, ny) = (self.nx, self.ny);
        let nu = case.setup.units.lattice_viscosity;
        let two_l = (nx - 1) as f64;
        let half_length = 0.5 * two_l;
        let (fluid, m0, drho, raw, times) =
            (&self.fluid, self.m0, self.drho, &self.raw, &self.times);
        let (k, geometric_porosity, c_geo) =
            (self.permeability, self.geometric_porosity, self.c_geo);
        let darcy_steps = self.flow.steps;
        let released = m0 - fluid.mass();
        // 3. Fit c.
        let samples: Vec<(f64, f64, f64)> = raw
            .iter()
            .flat_map(|(s, prof)| {
                prof.iter()
                    .map(move |&(x, p)| (x - half_length, *s as f64, p))
            })
            .collect();
        let (c_fit, rms, iterations) = fit_diffusivity(&samples, half_length, c_geo);
        let t_end = *times.last().unwrap_or(&1) as f64;
        let storage_porosity = released
            / (two_l * ny as f64 * drho * (1.0 - slab_mean_pressure(t_end, c_fit, half_length)));
        let c_pred = k * CS2 / (nu * storage_porosity);
        let profiles = raw
            .iter()
            .map(|(s, prof)| Profile {
                step: *s,
                fourier: c_fit * *s as f64 / (half_length * half_length),
                points: prof
                    .iter()
                    .map(|&(x, p)| {
                        (
                            x,
                            p,
                            slab_pressure(x - half_length, *s as f64, c_fit, half_length).0,
                        )
                    })
                    .collect(),
            })
            .collect();
        DiffusionOutcome {
            nodes: [nx, ny],
            grains: self.grains,
            half_length,
            geometric_porosity,
            storage_porosity,
            permeability: k,
            permeability_physical: case.setup.units.permeability_to_physical(k),
            darcy_steps,
            predicted_diffusivity: c_pred,
            predicted_diffusivity_geometric: c_geo,
            fitted_diffusivity: c_fit,
            fitted_diffusivity_physical: case.setup.units.diffusivity_to_physical(c_fit),
            diffusivity_error: c_fit / c_pred - 1.0,
            rms_residual: rms,
            fit_iterations: iterations,
            samples: samples.len(),
            profiles,
        }
    }
}

/// Run a pressure-diffusion case in memory to its end.
pub fn simulate(case: &Case<PressureDiffusion>) -> Result<DiffusionOutcome> {
    let (state, _) = run_in_memory(case, &RunOptions::default())?;
    Ok(state.outcome(case))
}

fn profiles_csv(o: &DiffusionOutcome) -> String {
    let mut rows = Vec::new();
    for p in &o.profiles {
        for (x, v, m) in &p.points {
            rows.push(vec![p.step as f64, p.fourier, *x, *v, *m]);
        }
    }
    csv(
        &[
            "step",
            "fourier_number",
            "x_from_face",
            "p_over_p0",
            "fitted",
        ],
        rows,
    )
}

/// The pressure-diffusion kind.
pub struct PressureDiffusion;

impl Kind for PressureDiffusion {
    const NAME: &'static str = "pressure_diffusion";
    const OWN_SECTION: Option<&'static str> = Some("pressure_diffusion");
    type Scene = PressureDiffusionScene;
    type Setup = UnitsSetup;
    type State = DiffusionState;

    fn validate(scene: &PressureDiffusionScene) -> Result<()> {
        let u = crate::scene::f64_bgk_units(&scene.scene, &scene.fluid)?;
        let (collision, op) = fluid_choice(scene);
        scene.fluid.checked_collision(collision, u.tau)?;
        scene.fluid.lambda_terms(op)?;

        let d = &scene.pressure_diffusion;
        positive("pressure_diffusion.width", d.width, "slab width")?;
        positive("pressure_diffusion.height", d.height, "slab height")?;
        positive(
            "pressure_diffusion.radius_min",
            d.radius_min,
            "e.g. 0.07 cm",
        )?;
        positive(
            "pressure_diffusion.radius_max",
            d.radius_max,
            "e.g. 0.11 cm",
        )?;
        positive(
            "pressure_diffusion.overpressure",
            d.overpressure,
            "initial P0",
        )?;
        positive(
            "pressure_diffusion.darcy_pressure_drop",
            d.darcy_pressure_drop,
            "pressure drop of the permeability run",
        )?;
        crate::error::fraction(
            "pressure_diffusion.fluid_radius",
            d.fluid_radius,
            "the dissertation uses 0.6-0.95",
        )?;
        check_slab_packing(d)?;
        if d.fourier_times.is_empty()
            || d.fourier_times
                .iter()
                .any(|t| !(t.is_finite() && *t > 0.0 && *t <= MAX_FOURIER))
        {
            return Err(LbdemError::field(
                "pressure_diffusion.fourier_times",
                format!("{:?}", d.fourier_times),
                &format!(
                    "must be a non-empty list of positive Fourier numbers c t / L^2, each at most \
                     {MAX_FOURIER} (the slab is drained to 1e-10 of the overpressure by then)"
                ),
                "e.g. [0.05, 0.1, 0.2, 0.4, 0.8, 1.5]",
            ));
        }
        for (field, p) in [
            ("pressure_diffusion.overpressure", d.overpressure),
            (
                "pressure_diffusion.darcy_pressure_drop",
                d.darcy_pressure_drop,
            ),
        ] {
            crate::scene::density_change_within(
                field,
                p,
                &u,
                ": Darcy's law would pick up compressibility and inertia errors",
                "lower it, or shorten fluid.timestep (raising the lattice sound speed)",
            )?;
        }
        Ok(())
    }

    fn budget(scene: &PressureDiffusionScene, setup: &UnitsSetup) -> Result<Budget> {
        let d = &scene.pressure_diffusion;
        let u = &setup.units;
        let nx = limits::count(
            "pressure_diffusion.width",
            "the slab length in nodes",
            u.length_to_lattice(d.width),
        )?;
        let ny = limits::count(
            "pressure_diffusion.height",
            "the slab height in nodes",
            u.length_to_lattice(d.height),
        )?;
        // At most the box area over the smallest grain's area.
        let grains = limits::count_up(
            "pressure_diffusion.width",
            "the grain count",
            d.width * d.height / (std::f64::consts::PI * d.radius_min * d.radius_min),
        )?;
        let grains = limits::grains("pressure_diffusion.width", grains)?;
        let mut b = Budget::new();
        // Two lattices (the Darcy run and the diffusion run).
        limits::lattice(
            &mut b,
            "pressure_diffusion.width",
            "slab lattice",
            nx.saturating_add(1),
            ny.max(1),
            8,
            limits::Solids::Covered,
        )?;
        limits::lattice(
            &mut b,
            "pressure_diffusion.width",
            "Darcy lattice",
            nx.saturating_add(1),
            ny.max(1),
            8,
            limits::Solids::Covered,
        )?;
        b.add_items("grains", "pressure_diffusion.width", grains, GRAIN_BYTES)?;
        let fo_max = d.fourier_times.iter().copied().fold(0.0, f64::max);
        b.note(format!(
            "steps: the Darcy run at most {DARCY_MAX_STEPS}, then the drainage to Fourier number {fo_max} (its \
             step count follows from the measured diffusivity; refused above {} steps, naming \
             pressure_diffusion.fourier_times)",
            limits::MAX_STEPS
        ));
        Ok(b)
    }

    fn setup(scene: &PressureDiffusionScene) -> Result<UnitsSetup> {
        UnitsSetup::new(&scene.fluid)
    }

    fn describe(case: &Case<Self>) -> String {
        let labels = case.scene.scene.units.labels();
        let d = &case.scene.pressure_diffusion;
        let u = &case.setup.units;
        case.setup.describe(labels)
            + &format!(
                "  packing box {} x {} {}, about {:.0} x {:.0} nodes; overpressure -> lattice density excess {:.3e}; Darcy drop -> {:.3e}\n",
                d.width,
                d.height,
                labels.length,
                u.length_to_lattice(d.width),
                u.length_to_lattice(d.height),
                u.pressure_to_density_change(d.overpressure),
                u.pressure_to_density_change(d.darcy_pressure_drop)
            )
    }

    fn start(case: &Case<Self>, exec: &Exec) -> Result<DiffusionState> {
        start(case, exec)
    }

    fn lattices(state: &mut DiffusionState) -> Vec<&mut dyn ExecTarget> {
        let mut all: Vec<&mut dyn ExecTarget> = vec![&mut state.fluid];
        all.extend(state.darcy.as_mut().map(|d| d as &mut dyn ExecTarget));
        all
    }

    fn steps_done(state: &DiffusionState) -> u64 {
        state.flow.steps + state.step
    }

    fn total_steps(_case: &Case<Self>, state: &DiffusionState) -> Option<u64> {
        state.times.last().map(|t| state.flow.steps + t)
    }

    fn finished(_case: &Case<Self>, state: &DiffusionState) -> bool {
        state.finished()
    }

    fn advance(case: &Case<Self>, state: &mut DiffusionState, dir: Option<&Path>) -> Result<()> {
        let h = &case.scene.scene;
        let at = dir.map(|d| {
            FixedSnapshots::new(
                d,
                (h.name.as_deref(), Self::NAME, h.units),
                case.setup.units,
            )
        });
        state.advance(case, at.as_ref())
    }

    fn health(_case: &Case<Self>, state: &DiffusionState) -> Result<()> {
        match &state.darcy {
            Some(d) => fluid_health(d, HINT),
            None => fluid_health(&state.fluid, HINT),
        }
    }

    fn write_outputs(
        case: &Case<Self>,
        state: &DiffusionState,
        dir: &Path,
        _stage: OutputStage,
    ) -> Result<()> {
        // Every stage, periodic checkpoints included, so that a killed run keeps the profiles so far (fitted
        // to the snapshots so far; the finished run rewrites them with the final fit).
        let o = state.outcome(case);
        write_atomic(&dir.join("profiles.csv"), profiles_csv(&o).as_bytes())
    }

    fn results(case: &Case<Self>, state: &DiffusionState) -> Result<serde_json::Value> {
        let mut o = state.outcome(case);
        // The profiles are in profiles.csv.
        o.profiles.clear();
        Ok(serde_json::to_value(&o).unwrap_or_default())
    }
}

#[cfg(test)]
mod tests {
    use super::drainage_steps;
    use crate::input::limits::MAX_STEPS;

    #[test]
    fn drainage_steps_are_fourier_times_over_the_measured_diffusivity() {
        // L = 60 nodes, c = 0.5 nodes^2/step: one Fourier unit L^2/c = 7200 steps (exact in binary).
        let t = drainage_steps(&[1.0, 0.05, 0.5, 0.5], 60.0, 0.5).unwrap();
        assert_eq!(t, vec![360, 3600, 7200]);
        // A Fourier time far below one step still takes one step.
        assert_eq!(drainage_steps(&[1e-9], 1.0, 1.0).unwrap(), vec![1]);
    }

    #[test]
    fn drainage_above_the_step_limit_is_refused_naming_fourier_times() {
        // L = 1, c = 1: the step count is the Fourier number itself, so the limit is met exactly.
        let at = MAX_STEPS as f64;
        assert_eq!(
            drainage_steps(&[0.5, at], 1.0, 1.0).unwrap(),
            vec![1, MAX_STEPS]
        );
        let over = drainage_steps(&[0.5, at + 1.0], 1.0, 1.0)
            .unwrap_err()
            .to_string();
        assert!(over.contains("pressure_diffusion.fourier_times"), "{over}");
        assert!(over.contains(&format!("{}", MAX_STEPS + 1)), "{over}");
        // The realistic case: a tight pack measured at c = 1e-7 nodes^2/step in a slab of half-length 60
        // nodes needs 10 x 3600 / 1e-7 = 3.6e11 steps to reach Fo = 10.
        let tight = drainage_steps(&[0.1, 10.0], 60.0, 1e-7)
            .unwrap_err()
            .to_string();
        assert!(
            tight.contains("pressure_diffusion.fourier_times"),
            "{tight}"
        );
        assert!(tight.contains("Darcy run measured"), "{tight}");
        // The message is prose (the hint's line is indented by two blanks; a broken line continuation once
        // left runs of twenty).
        assert!(
            !tight.contains("   "),
            "no run of blanks in the message: {tight}"
        );
        // A pack that blocks the flow (c = 0) needs unboundedly many steps: refused, not run for ever.
        assert!(drainage_steps(&[0.1], 60.0, 0.0).is_err());
    }

    #[test]
    fn a_diffusivity_that_is_not_positive_and_finite_is_refused_not_run_in_one_step() {
        // Negative, NaN and infinite diffusivities once each became one drainage step per time (the products clamp
        // to 1), and the run went on without an error.
        for c in [-0.5, f64::NAN, f64::INFINITY, 0.0] {
            let e = drainage_steps(&[0.1, 1.0], 60.0, c)
                .expect_err("refused")
                .to_string();
            assert!(e.contains("pressure_diffusion"), "c = {c}: {e}");
            assert!(e.contains("not a positive finite number"), "c = {c}: {e}");
        }
    }
}
