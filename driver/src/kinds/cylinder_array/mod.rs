//! `kind = "cylinder_array"`: flow through a periodic square array of fixed cylinders (dissertation §5.4; the
//! fixed-solid validation of the partially-saturated coupling, on the fluid lattice alone).
//!
//! One disc of radius a in a periodic l × l cell, solid fraction c = πa²/l², driven by a uniform body force on
//! the fluid (Guo forcing, weighted by 1 − B at covered nodes). Following Sangani & Acrivos (1982, S&A), the
//! drag per cylinder is the force that balances the mean pressure gradient over the cell, F = G l² with
//! G = ρ₀ g (the force density), and U is the **superficial** velocity U = Σ_nodes (1 − ε) u_x / l². The
//! dimensionless drag is F/(μU), μ = ρ₀ ν. The force the PSM hands the disc is smaller, ≈ G(1 − c)l² (the
//! buoyancy G πa² of the mean gradient is not a drag); it is reported as a consistency figure
//! (`solid_force_ratio` ≈ 1 − c), never used for F. With Re = U D/ν the dimensionless pressure drop of fig. 5.4
//! is ∇P̄ = G l/(ρ₀ U²) (eq. 5.4), whose Stokes limit is ∇P̄·Re = F̄·D/l (S&A: 424.9 at c = 0.5).
//!
//! **Solid operator.** Default Ω₁ (the dissertation's non-equilibrium bounce-back, eq. 4.6). Ω₂ (superposition)
//! lets the discs leak: at c = 0.4 its drag is −23 % (l = 20) and −16 % (l = 40, τ = 1) against S&A where Ω₁
//! gives −5.7 % and −3.4 %. Ω₁ never relaxes the rest population of fully covered nodes, which keep gaining
//! mass from the fluid: the total mass is conserved, the mean fluid density ρ_f falls slowly (0.9994 → 0.9774
//! over 2 000 → 80 000 steps at c = 0.6, l = 20) and U rises as 1/ρ_f; F/(μU) is computed with μ = ρ_f ν and
//! is then invariant (6 digits, tested). The steady-state criterion accepts that constant drift
//! ([`crate::observe::steady`]).
//!
//! Everything here is in lattice units (h = Δt = 1, ρ₀ = 1); [`ArraySetup`] converts a scene in physical units
//! through [`crate::units`].
use std::path::Path;

use lbdem_kernels::fluid::boundary::Boundaries;
use lbdem_kernels::fluid::collide::{Collision, LambdaTerms, SolidOperator};
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::Real;
use lbdem_reference::analytic::{sangani_acrivos_drag, SANGANI_ACRIVOS_SQUARE};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::engine::exec::Exec;
use crate::engine::lattice::{FluidDisc, FluidLattice};
use crate::error::{LbdemError, Result};
use crate::input::limits::{self, Budget};
use crate::observe::darcy::SteadyFlow;
use crate::observe::flow::max_mach;
use crate::observe::steady::Steadiness;
use crate::output::snapshots::{disc_grain, write_fixed, FixedSnapshots};
use crate::output::vtk::LatticeFrame;
use crate::output::{csv, write_atomic};
use crate::run::cases::{solve, CaseRun, Sweep, DRIVE_HINT};
use crate::run::{Case, Kind, OutputStage};
use crate::scene::{whole_spacings, RunSection, SceneHeader};
use crate::units::{
    check_mach, check_tau, collision_of, CollisionName, FluidSection, LatticeUnits, Warnings,
};

/// The fluid collision of cylinder-array scenes without `[fluid] collision`: TRT, which with ΩΛ (the default
/// solid operator, [`default_operator`]) gives a drag that does not depend on τ (README, "Results that do not
/// depend on τ": spread over τ = 0.55…2 below 1e-7 against 11–39 % for Ω₁ with BGK at l = 40).
pub const COLLISION: CollisionName = CollisionName::Trt;

/// The solid operator of cylinder-array scenes without `solid_operator`: ΩΛ.
pub fn default_operator() -> SolidOperator {
    SolidOperator::LambdaConsistent
}

/// One periodic-array run in lattice units.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ArrayCase {
    /// Side l of the periodic cell (nodes).
    pub cell: usize,
    /// Solid area fraction c = πa²/l².
    pub solid_fraction: f64,
    /// Relaxation time τ.
    pub tau: f64,
    /// Body-force density G along x (lattice units).
    pub force: f64,
    /// Solid operator of the PSM.
    pub solid_operator: SolidOperator,
    /// ΩΛ's constants (`[fluid] lambda_form`; read only when the solid operator is ΩΛ).
    #[serde(default)]
    pub lambda_terms: LambdaTerms,
    /// Fluid collision (BGK, or TRT with its magic parameter).
    #[serde(default)]
    pub collision: Collision<f64>,
    /// Stop once the relative change of U over one check interval is below this.
    pub steady_tolerance: f64,
    /// Steps between checks.
    pub check_interval: u64,
    /// Upper bound on the steps.
    pub max_steps: u64,
}

impl ArrayCase {
    /// A Stokes-regime case: tolerance 1e-8 per 200 steps, force sized for U ≈ 1e-3 (Ma ≈ 0.002 superficial).
    pub fn stokes(cell: usize, solid_fraction: f64, tau: f64) -> Self {
        let mut case = Self {
            cell,
            solid_fraction,
            tau,
            force: 0.0,
            solid_operator: SolidOperator::NonEquilibriumBounceBack,
            lambda_terms: LambdaTerms::default(),
            collision: Collision::Bgk,
            steady_tolerance: 1e-7,
            check_interval: 100,
            max_steps: 200_000,
        };
        case.force = case.force_for_velocity(1e-3);
        case
    }

    /// A case at target Reynolds number `re` (Stokes estimate of the drive): τ = ½ + 3ν with the largest ν in
    /// [ν(τ = 0.51), ν(τ = `tau_max`)] that keeps the superficial velocity at or below `u_max`, so high-Re
    /// points run at small τ and low-Re points at `tau_max`.
    pub fn at_reynolds(
        cell: usize,
        solid_fraction: f64,
        re: f64,
        u_max: f64,
        tau_max: f64,
    ) -> Self {
        let mut case = Self::stokes(cell, solid_fraction, tau_max);
        let nu = u_max * 2.0 * case.radius() / re;
        case.tau = crate::units::tau_of_lattice_viscosity(nu).clamp(0.51, tau_max);
        case.force = case.force_for_reynolds(re);
        case
    }

    /// Disc radius a = l √(c/π) (lattice units).
    pub fn radius(&self) -> f64 {
        self.cell as f64 * (self.solid_fraction / std::f64::consts::PI).sqrt()
    }

    /// The disc, at the centre of the cell (lattice units).
    pub fn disc(&self) -> FluidDisc {
        let mid = 0.5 * (self.cell as f64 - 1.0);
        FluidDisc {
            center: [mid, mid],
            radius: self.radius(),
            velocity: [0.0; 2],
            spin: 0.0,
        }
    }

    /// Nodes across the narrowest gap, l − 2a.
    pub fn gap(&self) -> f64 {
        self.cell as f64 - 2.0 * self.radius()
    }

    /// Lattice viscosity (τ − ½)/3.
    pub fn viscosity(&self) -> f64 {
        crate::units::lattice_viscosity(self.tau)
    }

    /// Force density giving superficial velocity ≈ `u` in the Stokes regime (S&A drag, interpolated).
    pub fn force_for_velocity(&self, u: f64) -> f64 {
        let fbar = sangani_acrivos_drag(self.solid_fraction).unwrap_or(100.0);
        fbar * self.viscosity() * u / (self.cell * self.cell) as f64
    }

    /// Force density giving Re = U D/ν ≈ `re` if the drag kept its Stokes value (inertia lowers the actual Re).
    pub fn force_for_reynolds(&self, re: f64) -> f64 {
        self.force_for_velocity(re * self.viscosity() / (2.0 * self.radius()))
    }
}

/// Result of a periodic-array run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ArrayOutcome {
    /// The case run.
    pub case: ArrayCase,
    /// Disc diameter D (nodes).
    pub diameter: f64,
    /// Nodes across the narrowest gap l − D.
    pub gap: f64,
    /// Superficial velocity U (lattice units).
    pub superficial_velocity: f64,
    /// F/(μU) with F = G l², μ = ρ_f ν.
    pub drag: f64,
    /// Mean fluid density ρ_f = Σ (1 − ε) ρ / Σ (1 − ε) (starts at 1; Ω₁ slowly moves mass into covered nodes).
    pub fluid_density: f64,
    /// S&A's value at this c (when tabulated).
    pub reference_drag: Option<f64>,
    /// Relative error of `drag` against S&A.
    pub drag_error: Option<f64>,
    /// Re = U D/ν.
    pub reynolds: f64,
    /// ∇P̄ = G l/(ρ_f U²) (eq. 5.4).
    pub pressure_drop: f64,
    /// ∇P̄·Re (Stokes limit F̄ D/l).
    pub pressure_drop_times_reynolds: f64,
    /// Force the PSM hands the disc over G l² (≈ 1 − c; the rest is the buoyancy of the mean gradient).
    pub solid_force_ratio: f64,
    /// Steps taken.
    pub steps: u64,
    /// Whether the steady tolerance was met.
    pub steady: bool,
    /// Largest node Mach number |u|√3.
    pub max_mach: f64,
    /// Relative change of the total mass (periodic: roundoff).
    pub mass_change: f64,
    /// Relative change of U per step when steadiness was declared (the secular drift of Ω₁, see
    /// `Steadiness`; NaN if not steady).
    pub drift_per_step: f64,
    /// Wall-clock seconds (not in summaries or checkpoints: they are the same bytes whatever the machine).
    #[serde(skip)]
    pub wall_seconds: f64,
}

/// One periodic cell in precision `T`, on its way to steady state.
#[derive(Serialize, Deserialize)]
#[serde(bound(serialize = "T: Serialize", deserialize = "T: DeserializeOwned"))]
pub struct ArrayRun<T: Real> {
    lattice: FluidLattice<T>,
    eps: Vec<f64>,
    mass0: f64,
    flow: SteadyFlow,
}

impl<T: Real> CaseRun for ArrayRun<T> {
    type Case = ArrayCase;
    type Outcome = ArrayOutcome;
    type Float = T;

    /// The cell of `case`, at rest.
    fn start(case: &ArrayCase, exec: &Exec) -> Result<Self> {
        let l = case.cell;
        let bc = Boundaries::<T>::periodic();
        let params = FluidParams {
            tau: T::lit(case.tau),
            force: [T::lit(case.force), T::zero()],
        };
        let mut lattice = FluidLattice::new(l, l, bc, params)?;
        exec.apply(&mut lattice);
        lattice.set_band_rows(l.div_ceil(2).max(1));
        lattice.set_collision(collision_of(case.collision)?)?;
        lattice.set_solid_operator(case.solid_operator);
        lattice.set_lambda_terms(case.lambda_terms)?;
        lattice.cover_with_discs(&[case.disc()], case.solid_operator.weighting());
        let eps = lattice.solid_fraction_map();
        let mass0 = lattice.mass();
        Ok(Self {
            lattice,
            eps,
            mass0,
            flow: SteadyFlow::new(
                Steadiness::new(case.steady_tolerance).accepting_drift(),
                case.check_interval,
                case.max_steps,
            ),
        })
    }

    /// One check interval towards steady state (superficial velocity); whether the case is over.
    fn advance(&mut self, case: &ArrayCase) -> Result<bool> {
        let (eps, l) = (&self.eps, case.cell);
        let superficial = |lattice: &FluidLattice<T>| -> f64 {
            let (_, u) = lattice.moments();
            u.iter()
                .zip(eps.iter())
                .map(|(v, e)| (1.0 - e) * v[0].to_f64_exact())
                .sum::<f64>()
                / (l * l) as f64
        };
        self.flow
            .advance(&mut self.lattice, superficial, DRIVE_HINT)
    }

    /// The measured drag and its comparison with S&A.
    fn outcome(&self, case: &ArrayCase) -> ArrayOutcome {
        let l = case.cell;
        let lattice = &self.lattice;
        let eps = &self.eps;
        let u_s = self.flow.flux;
        let (rho, u) = lattice.moments();
        let nu = case.viscosity();
        let g = case.force;
        let ll = (l * l) as f64;
        // μ = ρ ν with the fluid's mean density (1 up to the slow transfer of mass into covered nodes under Ω₁).
        let (mut rw, mut w) = (0.0, 0.0);
        for (r, e) in rho.iter().zip(eps.iter()) {
            rw += (1.0 - e) * r.to_f64_exact();
            w += 1.0 - e;
        }
        let fluid_density = rw / w;
        let drag = g * ll / (fluid_density * nu * u_s);
        let reference = sangani_acrivos_drag(case.solid_fraction).filter(|_| {
            SANGANI_ACRIVOS_SQUARE
                .iter()
                .any(|(c, _)| (c - case.solid_fraction).abs() < 1e-12)
        });
        let diameter = 2.0 * case.radius();
        let reynolds = u_s * diameter / nu;
        let pressure_drop = g * l as f64 / (fluid_density * u_s * u_s);
        ArrayOutcome {
            case: case.clone(),
            diameter,
            gap: case.gap(),
            superficial_velocity: u_s,
            drag,
            fluid_density,
            reference_drag: reference,
            drag_error: reference.map(|r| drag / r - 1.0),
            reynolds,
            pressure_drop,
            pressure_drop_times_reynolds: pressure_drop * reynolds,
            solid_force_ratio: lattice.solid_forces(1)[0][0] / (g * ll),
            steps: lattice.steps(),
            steady: self.flow.steady,
            max_mach: max_mach(&u),
            mass_change: (lattice.mass() - self.mass0) / self.mass0,
            drift_per_step: self.flow.drift_per_step,
            wall_seconds: 0.0,
        }
    }

    fn lattice(&self) -> &FluidLattice<T> {
        &self.lattice
    }

    fn lattice_mut(&mut self) -> &mut FluidLattice<T> {
        &mut self.lattice
    }

    /// The disc and the cell (pressure 0 at the initial density 1; model time steps × Δt).
    fn snapshot(&self, case: &ArrayCase, at: &FixedSnapshots, index: usize) -> Result<()> {
        let grain = disc_grain(&case.disc(), at.units.spacing);
        let frame = LatticeFrame::of(&at.units, [0.0; 2], 1.0);
        let time = self.lattice.steps() as f64 * at.units.timestep;
        write_fixed(at, index, time, &[grain], &self.lattice, &frame)
    }

    fn outcome_steps(o: &ArrayOutcome) -> u64 {
        o.steps
    }

    fn report(case: &ArrayCase, o: &ArrayOutcome) -> String {
        format!(
            "c = {} l = {}: F/(muU) = {:.3} (S&A {:?}), Re = {:.3e}, {} steps",
            case.solid_fraction, case.cell, o.drag, o.reference_drag, o.reynolds, o.steps
        )
    }
}

/// Run one periodic cell to steady state.
pub fn solve_array<T: Real>(case: &ArrayCase) -> Result<ArrayOutcome> {
    solve_array_with::<T>(case, &Exec::default())
}

/// [`solve_array`] with the given execution settings (speed only).
pub fn solve_array_with<T: Real>(case: &ArrayCase, exec: &Exec) -> Result<ArrayOutcome> {
    let (mut outcome, seconds) = solve::<ArrayRun<T>>(case, exec)?;
    outcome.wall_seconds = seconds;
    Ok(outcome)
}

/// `[cylinder_array]`: periodic square array of cylinders, one per cell (kind = "cylinder_array").
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CylinderArraySection {
    /// Side l of the periodic cell (length; a whole number of spacings).
    pub cell: f64,
    /// Solid fractions c = πa²/l² to run (each in (0, π/4)).
    pub solid_fractions: Vec<f64>,
    /// Body-force acceleration along x (length/time²). Give this or `reynolds`.
    #[serde(default)]
    pub acceleration: Option<f64>,
    /// Target Reynolds numbers U D/ν; the drive is sized from S&A's Stokes drag, so inertia lowers the
    /// measured Re. Give this or `acceleration`.
    #[serde(default)]
    pub reynolds: Option<Vec<f64>>,
    /// Solid operator (`SolidOperator`'s scene names): "non_equilibrium_bounce_back" (Ω₁),
    /// "superposition" (Ω₂), "moving_wall_bounce_back" (Ω₃), "linearized_non_equilibrium_bounce_back" (Ω₁ₗ) or
    /// "lambda_consistent" (ΩΛ, with B = ε; the default, with `[fluid] collision` defaulting to TRT).
    #[serde(default = "default_operator")]
    pub solid_operator: SolidOperator,
}

/// A cylinder-array scene file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CylinderArrayScene {
    /// `[scene]`
    pub scene: SceneHeader,
    /// `[fluid]`
    pub fluid: FluidSection,
    /// `[cylinder_array]`
    #[serde(default)]
    pub cylinder_array: Option<CylinderArraySection>,
    /// `[run]`
    pub run: RunSection,
}

crate::scene::scene_file!(CylinderArrayScene);

/// Everything derived from a cylinder-array scene.
#[derive(Clone, Debug, Serialize)]
pub struct ArraySetup {
    /// Unit conversion.
    pub units: LatticeUnits,
    /// Cases in lattice units.
    pub cases: Vec<ArrayCase>,
    /// Warnings.
    pub warnings: Warnings,
}

impl crate::run::Derived for ArraySetup {
    fn warnings(&self) -> &[String] {
        &self.warnings.0
    }
}

impl ArraySetup {
    /// Derive the lattice cases from a scene.
    pub fn new(scene: &CylinderArrayScene) -> Result<Self> {
        CylinderArray::validate(scene)?;
        let units = scene.fluid.lattice_units()?;
        let a = scene.cylinder_array.as_ref().ok_or_else(|| {
            LbdemError::field(
                "cylinder_array",
                "missing",
                "the scene needs a [cylinder_array] section",
                "add it",
            )
        })?;
        let l = whole_spacings("cylinder_array.cell", a.cell, units.spacing)?;
        // Sizes in checked arithmetic before any case is derived.
        let drives = a.reynolds.as_ref().map_or(1, |r| r.len() as u64);
        limits::cases(
            "cylinder_array.solid_fractions",
            limits::mul(
                "cylinder_array.solid_fractions",
                "the case count",
                a.solid_fractions.len() as u64,
                drives,
            )?,
        )?;
        let mut probe = Budget::new();
        limits::lattice(
            &mut probe,
            "cylinder_array.cell",
            "cell lattice",
            l as u64,
            l as u64,
            8,
            limits::Solids::Covered,
        )?;
        let mut warnings = Warnings::default();
        check_tau(&units, &mut warnings);
        let template = ArrayCase {
            cell: l,
            solid_fraction: 0.0,
            tau: units.tau,
            force: 0.0,
            solid_operator: a.solid_operator,
            lambda_terms: scene.fluid.lambda_terms(a.solid_operator)?,
            collision: scene.fluid.checked_collision(COLLISION, units.tau)?,
            steady_tolerance: scene.run.steady_tolerance.unwrap_or(1e-8),
            check_interval: scene.run.check_interval.unwrap_or(200),
            max_steps: scene.run.step_count(units.timestep)?,
        };
        let mut cases = Vec::new();
        for &c in &a.solid_fractions {
            let mut case = ArrayCase {
                solid_fraction: c,
                ..template.clone()
            };
            if case.gap() < 2.0 {
                warnings.push(format!(
                    "c = {c}: only {:.1} nodes across the narrowest gap; expect errors far above 6 % \
                     (~5 % at 5 gap nodes, measured in driver/tests/porous.rs)",
                    case.gap()
                ));
            }
            let forces: Vec<f64> = match (&a.reynolds, a.acceleration) {
                (Some(re), _) => re.iter().map(|&r| case.force_for_reynolds(r)).collect(),
                (None, Some(g)) => vec![units.acceleration_to_lattice(g)],
                // validate() asks for exactly one of the two.
                _ => Vec::new(),
            };
            for f in forces {
                case.force = f;
                // Expected peak speed: Stokes U times the cell-to-gap contraction, times 1.5 for the profile.
                let fbar = sangani_acrivos_drag(c).unwrap_or(100.0);
                let u = f * (l * l) as f64 / (fbar * case.viscosity());
                let peak = 1.5 * u * l as f64 / case.gap().max(1.0);
                let driving = if a.reynolds.is_some() {
                    "cylinder_array.reynolds"
                } else {
                    "cylinder_array.acceleration"
                };
                check_mach(
                    driving,
                    peak * 3f64.sqrt(),
                    Some(scene.run.allow_high_mach),
                    &mut warnings,
                )?;
                cases.push(case.clone());
            }
        }
        Ok(Self {
            units,
            cases,
            warnings,
        })
    }
}

/// What the run checkpoints: the cases in the scene's precision.
pub type ArrayState = Sweep<ArrayRun<f32>, ArrayRun<f64>>;

fn drag_csv(outcomes: &[ArrayOutcome]) -> String {
    csv(
        &[
            "solid_fraction",
            "cell_nodes",
            "diameter_nodes",
            "gap_nodes",
            "tau",
            "force",
            "superficial_velocity",
            "drag_F_over_muU",
            "sangani_acrivos",
            "relative_error",
            "reynolds",
            "pressure_drop_dimensionless",
            "pressure_drop_times_reynolds",
            "solid_force_ratio",
            "steps",
        ],
        outcomes.iter().map(|r| {
            vec![
                r.case.solid_fraction,
                r.case.cell as f64,
                r.diameter,
                r.gap,
                r.case.tau,
                r.case.force,
                r.superficial_velocity,
                r.drag,
                r.reference_drag.unwrap_or(f64::NAN),
                r.drag_error.unwrap_or(f64::NAN),
                r.reynolds,
                r.pressure_drop,
                r.pressure_drop_times_reynolds,
                r.solid_force_ratio,
                r.steps as f64,
            ]
        }),
    )
}

/// The cylinder-array kind.
pub struct CylinderArray;

impl Kind for CylinderArray {
    const NAME: &'static str = "cylinder_array";
    const OWN_SECTION: Option<&'static str> = Some("cylinder_array");
    const NOT_MEASURED: &'static [&'static str] =
        &["drift_per_step", "reference_drag", "drag_error"];
    type Scene = CylinderArrayScene;
    type Setup = ArraySetup;
    type State = ArrayState;

    fn validate(scene: &CylinderArrayScene) -> Result<()> {
        scene.fluid.validate()?;
        scene.run.validate()?;
        let a = scene.cylinder_array.as_ref().ok_or_else(|| {
            LbdemError::field(
                "cylinder_array",
                "missing",
                "scene.kind = \"cylinder_array\" needs a [cylinder_array] section",
                "add [cylinder_array] with cell, solid_fractions and acceleration or reynolds",
            )
        })?;
        if !(a.cell.is_finite() && a.cell > 0.0) {
            return Err(LbdemError::field(
                "cylinder_array.cell",
                a.cell,
                "must be > 0",
                "give the cell side",
            ));
        }
        if a.solid_fractions.is_empty() {
            return Err(LbdemError::field(
                "cylinder_array.solid_fractions",
                "[]",
                "is empty",
                "list at least one solid fraction, e.g. [0.2, 0.4]",
            ));
        }
        for &c in &a.solid_fractions {
            if !(c > 0.0 && c < 0.75) {
                return Err(LbdemError::field(
                    "cylinder_array.solid_fractions",
                    c,
                    "must lie in (0, 0.75): the cylinders touch at pi/4 and the gap must stay resolvable",
                    "use values such as 0.2-0.6",
                ));
            }
        }
        match (a.acceleration, &a.reynolds) {
            (Some(_), Some(_)) | (None, None) => Err(LbdemError::field(
                "cylinder_array.acceleration",
                if a.acceleration.is_some() {
                    "given with reynolds"
                } else {
                    "missing"
                },
                "give exactly one of cylinder_array.acceleration and cylinder_array.reynolds",
                "e.g. acceleration = 1.0, or reynolds = [0.01, 1.0, 10.0]",
            )),
            (Some(g), None) if !(g.is_finite() && g > 0.0) => Err(LbdemError::field(
                "cylinder_array.acceleration",
                g,
                "must be a finite number > 0",
                "a positive acceleration drives flow along +x",
            )),
            (None, Some(re))
                if re.is_empty() || re.iter().any(|r| !(r.is_finite() && *r > 0.0)) =>
            {
                Err(LbdemError::field(
                    "cylinder_array.reynolds",
                    format!("{re:?}"),
                    "must be a non-empty list of numbers > 0",
                    "e.g. reynolds = [0.01, 1.0, 10.0]",
                ))
            }
            _ => Ok(()),
        }
    }

    fn budget(scene: &CylinderArrayScene, setup: &ArraySetup) -> Result<Budget> {
        // The cases run one after the other on lattices of the same size.
        let mut b = Budget::new();
        if let Some(c) = setup.cases.first() {
            limits::lattice(
                &mut b,
                "cylinder_array.cell",
                "cell lattice",
                c.cell as u64,
                c.cell as u64,
                scene.scene.precision.float_bytes(),
                limits::Solids::Covered,
            )?;
        }
        Ok(b)
    }

    fn setup(scene: &CylinderArrayScene) -> Result<ArraySetup> {
        ArraySetup::new(scene)
    }

    fn describe(case: &Case<Self>) -> String {
        let u = &case.setup.units;
        let mut s = u.brief();
        for c in &case.setup.cases {
            s += &format!(
                "  cell {} nodes, c = {}, D = {:.2}, gap {:.2} nodes, tau {:.4}, force {:.4e}\n",
                c.cell,
                c.solid_fraction,
                2.0 * c.radius(),
                c.gap(),
                c.tau,
                c.force
            );
        }
        s
    }

    crate::run::cases::sweep_kind_methods!();

    fn write_outputs(
        _case: &Case<Self>,
        state: &ArrayState,
        dir: &Path,
        _stage: OutputStage,
    ) -> Result<()> {
        // Periodic checkpoints flush the tables too, so that a killed run keeps its records so far.
        let table = drag_csv(state.done());
        write_atomic(&dir.join("drag.csv"), table.as_bytes())
    }

    fn results(_case: &Case<Self>, state: &ArrayState) -> Result<serde_json::Value> {
        let done = state.done();
        Ok(json!({
            "cases": done,
            "all_steady": done.iter().all(|r| r.steady),
        }))
    }
}
