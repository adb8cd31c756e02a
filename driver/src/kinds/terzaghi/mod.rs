//! `kind = "terzaghi"`: one-dimensional consolidation of a random pack of free grains against Terzaghi's
//! solution, with every parameter of the prediction measured independently first. See [`Terzaghi`].
use std::path::Path;

use lbdem_kernels::coupling::CoupledBody;
use lbdem_kernels::dem::assembly::ContactModel;
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::{LambdaTerms, SolidOperator};
use lbdem_kernels::fluid::lattice::Side;
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::math::{vector, Vector};
use lbdem_reference::poroelastic::{
    biot_modulus, consolidation_coefficient, constrained_modulus, loading_efficiency,
    storage_terms, terzaghi_pressure_ramped, terzaghi_settlement, uniaxial_storage,
};
use serde::{Deserialize, Serialize};

use crate::engine::coupled::{CoupledWorld, LatticeMap};
use crate::engine::dem::loading::{settle_loaded, uniaxial_strain_step, StepLoadResult};
use crate::engine::dem::packing::{generate_packing, hexagonal_packing, PackingSpec};
use crate::engine::dem::world::BondSpec;
use crate::engine::dem::{elastic_contact, DemWorld};
use crate::engine::exec::{Exec, ExecTarget};
use crate::engine::lattice::{FluidLattice, RadiatingSide};
use crate::error::{non_negative, positive, LbdemError, Result};
use crate::input::limits::{self, Budget};
use crate::observe::darcy::{permeability, SteadyFlow};
use crate::observe::fit::{fit_consolidation, linear_fit};
use crate::observe::flow::{dividing_surface_depth, fluid_row_means};
use crate::observe::health::{coupled_health, finite};
use crate::observe::steady::Steadiness;
use crate::output::snapshots::{chunk_with_snapshots, write_coupled_at_step, SnapshotClock};
use crate::output::{csv, write_atomic};
use crate::run::{run_in_memory, Case, Kind, OutputStage, Persist, RunOptions};
use crate::scene::{
    free_grain_choice, CheckpointSection, FreeGrains, SceneHeader, SnapshotSection, UnitsSetup,
};
use crate::units::{collision_of, CollisionName, FluidSection, Warnings, CS2};

/// Lattice density difference of the steady Darcy run (small: Mach ≪ 0.1 and a linear response).
const DARCY_DRHO: f64 = 1e-3;
/// Relative flux change per 200 steps below which the Darcy run is steady (with Ω₁ₗ a constant drift is
/// also accepted, [`Steadiness`]).
const DARCY_TOLERANCE: f64 = 1e-5;
/// DEM steps per block of the dry equilibrium checks.
const DRY_BLOCK: u64 = 500;
/// The loaded layer counts as settled when it moves less than this fraction of the settlement per block.
const DRY_TOLERANCE: f64 = 1e-3;
/// Step limit of each dry equilibrium.
const DRY_MAX_STEPS: u64 = 400_000;
/// Largest dry strain of the step load taken as an elastic strain of the skeleton (the bundled scene's is
/// 3.6e-3, the table-6.3 storage models' 1e-4); beyond it the pack rearranges (a loose pack collapsed by 43 %
/// under the bundled load with K_v then 120× too soft).
const MAX_DRY_STRAIN: f64 = 0.05;
/// Least fraction of the dry step's settlement the pack must give back when the step is taken off (less: the
/// step rearranged grains and is refused). Measured on 19 columns of the bundled grains and load (seeds 7–13 of
/// 1.2 × 2.4 and 2.4 × 2.4 cm, five of 2.4 × 4.8 cm; two more fell apart first): 14 gave back 0.998–1.0003, the
/// other five 0.19, 0.44, 0.80, 0.87 and 0.91 — and those five missed Terzaghi where they were run wet (RMS 33 %,
/// 4.3 %, 4.2 % and 3.7 % of γσ₀; free fits of c +13 % and −8 %): their K_v counts the rearrangement, which the
/// wet column does not repeat, so γ and c_v are predicted from a skeleton that is not the one loaded. The
/// bonded table-6.3 storage models give back 0.9996–1.0004.
const MIN_DRY_RECOVERY: f64 = 0.95;
/// Recovery below which the run warns that part of K_v may be rearrangement (no column measured fell in
/// [0.95, 0.99)).
const ELASTIC_DRY_RECOVERY: f64 = 0.99;
/// Diffusion time over sound-crossing time below which the run warns that the column is not
/// diffusion-dominated.
pub const DIFFUSION_DOMINATED: f64 = 20.0;
/// Column height, in diameters of the largest grains, below which the set-up warns that the pack's looser ends
/// weigh on the comparison: 1.6 cm columns of the bundled grains (6.7 diameters) relaxed 8–18 % slower than
/// predicted, sealed or drained, on every seed; 2.4 cm ones (10 diameters) fitted −12 … +6 % and 4.0–4.8 cm ones
/// −9 … +3 % over the seeds, i.e. as much faster as slower (README, *The sealed column*).
pub const SHORT_COLUMN_DIAMETERS: f64 = 10.0;
/// Start-up: records earlier than this many fluid sound-crossing times of the column are not compared.
pub const STARTUP_CROSSINGS: f64 = 3.0;

/// Span of the running mean of a radiating drained top (`drained_top = "radiating"`), in sound-crossing times of
/// the column: long against the column's undrained ringing (a quarter-wave period of about five crossings, so a
/// wave of it comes back with under 2 % of its amplitude, r/(2ω)), short against the diffusion time the scenes
/// are checked for (above 20 crossings; the back pressure of the slow outflow stays below 1 % of the load).
pub const RADIATING_CROSSINGS: f64 = 10.0;

const HINT: &str = "lower terzaghi.load or raise fluid.tau";
/// [`HINT`] when the grains are under ΩΛ, whose pack mode grows at high τ.
const HINT_LAMBDA: &str =
    "lower terzaghi.load, or lower fluid.tau (under solid_operator = \"lambda_consistent\" packs \
                           of free grains diverged at high tau, the sooner the lighter the grains), or use \
                           solid_operator = \"linearized_non_equilibrium_bounce_back\"";

/// What to change when the column of `world` diverges: [`HINT_LAMBDA`] under ΩΛ (raising τ is the wrong way
/// there), else [`HINT`].
fn divergence_hint(world: &CoupledWorld) -> &'static str {
    if world.fluid.solid_operator() == SolidOperator::LambdaConsistent {
        HINT_LAMBDA
    } else {
        HINT
    }
}

mod sealed;
pub use sealed::SealedMeasurement;
use sealed::{SealedRun, SEALED_FREE_ROWS};

/// The default fluid collision and the solid operator of a Terzaghi scene: without `terzaghi.solid_operator`,
/// Ω₁ₗ with BGK (the operator its README tables were measured with). TRT + ΩΛ, the free-grain kinds' default,
/// was tried on the bundled scene (issue 11): it first diverged inside the pack (rock grains, τ = 0.8, where
/// a single free disc was stable; cured by ΩΛ's full-cover gap, `LAMBDA_FULL_GAP`), and where it runs its
/// Terzaghi comparison lies further from theory than Ω₁ₗ's (README, *Poroelastic validation*), so it is
/// selectable here (`solid_operator = "lambda_consistent"`, then TRT), not the default. A given operator goes through
/// [`free_grain_choice`] (ΩΛ with TRT, the others with BGK); `[fluid] collision` overrides the collision.
pub fn fluid_choice(
    scene: &TerzaghiScene,
    tau: f64,
    warnings: &mut Warnings,
) -> (CollisionName, SolidOperator) {
    let c = &scene.terzaghi;
    match c.solid_operator {
        None => (
            CollisionName::Bgk,
            SolidOperator::LinearizedNonEquilibriumBounceBack,
        ),
        given => free_grain_choice(
            given,
            tau,
            FreeGrains::packed(c.grain_density / scene.fluid.density)
                .in_form(scene.fluid.lambda_form),
            warnings,
        ),
    }
}

/// `[terzaghi]`
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TerzaghiSection {
    /// Packing box width (x).
    pub width: f64,
    /// Packing box height (y): the column, drained at its top.
    pub height: f64,
    /// Smallest grain radius.
    pub radius_min: f64,
    /// Largest grain radius.
    pub radius_max: f64,
    /// Packing seed.
    pub seed: u64,
    /// Grain density (unit thickness).
    pub grain_density: f64,
    /// Fraction of each radius the fluid sees.
    pub fluid_radius: f64,
    /// Contact normal (= shear) stiffness, force/length.
    pub normal_stiffness: f64,
    /// Contact friction.
    pub friction: f64,
    /// Isotropic stress the pack is made at (and the vertical stress before the step).
    pub isotropic_stress: f64,
    /// Step load σ₀ added to the vertical stress at t = 0 (stress).
    pub load: f64,
    /// Model time after the step.
    pub duration: f64,
    /// Time between pore-pressure profile records.
    pub record_interval: f64,
    /// Free fluid above the pack (the drained boundary), length; default 2 `radius_max`.
    #[serde(default)]
    pub free_layer: Option<f64>,
    /// b/a of the grains (1: discs; below 1: ellipses of random orientation, as in the fracture test).
    #[serde(default)]
    pub aspect_ratio: Option<f64>,
    /// Point-bond stiffness k_b (force/length; eq. 6.13): bond every touching pair after packing (with
    /// `bond_strength`); absent: unbonded.
    #[serde(default)]
    pub bond_stiffness: Option<f64>,
    /// Point-bond strength F_crit (force).
    #[serde(default)]
    pub bond_strength: Option<f64>,
    /// Which porosity multiplies β_f in the storage S: false (default), the geometric n = 1 − ⟨ε⟩; true, the
    /// storage porosity of the lattice measured in the Darcy run ([`Prediction::storage_porosity`]): in the
    /// partially-saturated method every node, covered or not, holds a full node of fluid whose density
    /// follows the pore pressure (covered nodes with a lag), so the lattice stores more than n β_f.
    #[serde(default)]
    pub storage_porosity_measured: bool,
    /// Solid operator of the grains (coupled and Darcy lattices); absent: [`fluid_choice`].
    #[serde(default)]
    pub solid_operator: Option<SolidOperator>,
    /// Time over which the load rises, σ₀ sin²(π t/(2 t_r)) (absent: a step). The comparison then uses
    /// Terzaghi's solution for that loading ([`terzaghi_pressure_ramped`]) from the end of the ramp on.
    #[serde(default)]
    pub load_ramp: Option<f64>,
    /// Where Terzaghi's solution puts the drained surface: absent or `"pack_top"`, at the top of the pack
    /// (the top platen the pack was made against); `"dividing_surface"`, at the Gibbs dividing surface of the
    /// pack's top layer measured at t = 0 ([`crate::observe::flow::dividing_surface_depth`]), the column
    /// then being L − δ long.
    #[serde(default)]
    pub drained_surface: Option<DrainedSurface>,
    /// What the lattice's top side is: absent or `"pressure"`, a Zou–He side held at the reservoir pressure (for
    /// sound a pressure-release mirror: the undrained wave of the step rings between it and the sealed base);
    /// `"radiating"`, a radiating drained side ([`FluidLattice::radiate`]): the same pressure for slow flow, but
    /// sound leaves through it as into a large reservoir (running mean over [`RADIATING_CROSSINGS`]
    /// sound-crossing times of the column).
    #[serde(default)]
    pub drained_top: Option<DrainedTop>,
    /// An absorbing load (a matched dashpot on the loaded layer, after Lysmer & Kuhlemeyer 1969): the loaded
    /// layer also feels −c v on its vertical velocity v (the loaded grains' mean, weighted by their shares of the
    /// load), shared among its grains as the load is, with c = this factor × Z W, Z = √(M_u ρ_m) the column's
    /// undrained impedance (M_u = K_v/(1 − γ) from the measured K_v and the predicted γ, ρ_m the mixture density
    /// of the column) and W the width. The undrained wave of the step then leaves through the loaded surface
    /// instead of ringing between it and the sealed base; the settlement, far slower, is resisted by Z v (about
    /// 1 % of the bundled scene's load at 1 s). 1 is the matched dashpot; absent: none.
    #[serde(default)]
    pub load_dashpot: Option<f64>,
    /// Measure the undrained response of the column sealed, with its grains free, before the drained run
    /// (`prediction.sealed`; [`SealedMeasurement`]): a copy of the column whose top is a lid moving with the
    /// loaded layer takes the step load for 20 sound-crossing times. Default false.
    #[serde(default)]
    pub sealed_check: bool,
}

/// The lattice's top side above the free fluid layer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DrainedTop {
    /// Zou–He pressure side at the reservoir pressure.
    #[default]
    Pressure,
    /// Radiating drained side.
    Radiating,
}

/// Position of the drained surface in the comparison with Terzaghi's solution.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DrainedSurface {
    /// At the top of the pack.
    #[default]
    PackTop,
    /// At the measured Gibbs dividing surface of the top layer.
    DividingSurface,
}

/// A Terzaghi scene file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TerzaghiScene {
    /// `[scene]`
    pub scene: SceneHeader,
    /// `[fluid]`
    pub fluid: FluidSection,
    /// `[terzaghi]`
    pub terzaghi: TerzaghiSection,
    /// `[output]`: VTK snapshots.
    #[serde(default)]
    pub output: SnapshotSection,
    /// `[run]`
    #[serde(default)]
    pub run: CheckpointSection,
}

crate::scene::scene_file!(TerzaghiScene);

/// The independent measurements and the prediction they give (physical units).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Prediction {
    /// Column thickness L (bottom wall to the top of the pack).
    pub thickness: f64,
    /// Drained constrained modulus K_v from the dry step load.
    pub drained_modulus: f64,
    /// Vertical strain of the dry step.
    pub dry_strain: f64,
    /// DEM steps of the dry step to equilibrium, and whether it converged.
    pub dry_steps: u64,
    /// Whether the dry step met its equilibrium criterion.
    pub dry_converged: bool,
    /// Fraction of the dry step's settlement the pack gives back when the step is taken off again (the dry copy
    /// unloaded to the isotropic stress and settled): 1 for an elastic skeleton, less where the step rearranged
    /// grains (then K_v describes the rearrangement, not the skeleton the wet column loads).
    #[serde(default = "nan")]
    pub dry_recovery: f64,
    /// The sealed column's undrained response (`sealed_check = true`), else absent (left out of
    /// `summary.json`; kept in checkpoints, whose binary format needs every field).
    #[serde(default)]
    pub sealed: Option<SealedMeasurement>,
    /// Porosity the fluid sees, 1 − ⟨ε⟩ over the column.
    pub porosity: f64,
    /// Storage porosity of the lattice: the fraction of the column's nodes whose fluid stores at the pore
    /// pressure, measured at the steady state of the Darcy run (grains held; see
    /// [`TerzaghiSection::storage_porosity_measured`]).
    pub storage_porosity: f64,
    /// Permeability along the column by steady Darcy flow, grains fixed.
    pub permeability: f64,
    /// Steps of the Darcy run.
    pub darcy_steps: u64,
    /// Fluid compressibility 1/(ρ₀c_s²).
    pub fluid_compressibility: f64,
    /// Storage terms: n β_f and 1/K_v, and their sum S.
    pub storage_fluid: f64,
    /// 1/K_v.
    pub storage_skeleton: f64,
    /// S = n β_f + 1/K_v.
    pub storage: f64,
    /// Loading efficiency γ = 1/(K_v S).
    pub loading_efficiency: f64,
    /// Consolidation coefficient c_v = k/(μ S).
    pub consolidation_coefficient: f64,
    /// Fluid sound-crossing time of the column L/c_s.
    pub sound_crossing_time: f64,
    /// Diffusion time L²/c_v.
    pub diffusion_time: f64,
    /// Depth δ below the pack top of the Gibbs dividing surface of its top layer, measured on the coupled
    /// lattice's coverage at t = 0 ([`crate::observe::flow::dividing_surface_depth`]).
    #[serde(default)]
    pub dividing_surface_depth: f64,
    /// Depth of the drained surface in the comparison: δ with `drained_surface = "dividing_surface"`, else 0.
    #[serde(default)]
    pub drained_depth: f64,
    /// Mixture density ρ_m of the column (fluid plus the grains' excess mass over the column's area).
    #[serde(default)]
    pub mixture_density: f64,
    /// Undrained constrained modulus M_u = K_v/(1 − γ).
    #[serde(default)]
    pub undrained_modulus: f64,
    /// Undrained impedance Z = √(M_u ρ_m) (stress per velocity).
    #[serde(default)]
    pub undrained_impedance: f64,
    /// Grains wholly above the pack top at the step (they left the pack while it settled).
    #[serde(default)]
    pub escaped_grains: usize,
    /// Permeability of the lower half of the pack in the Darcy run: ν q over the least-squares pressure
    /// gradient of its fluid-only row means (the column's heterogeneity; the prediction uses `permeability`).
    #[serde(default)]
    pub permeability_lower_half: f64,
    /// The same for the upper half.
    #[serde(default)]
    pub permeability_upper_half: f64,
}

/// Serde default of measurements missing from an older checkpoint: not measured.
fn nan() -> f64 {
    f64::NAN
}

/// Largest fraction of the grains that may leave the pack when its top platen is removed (more: refused).
const MAX_ESCAPED: f64 = 0.05;

/// Whether a grain lies wholly above height `top`.
fn above(g: &lbdem_kernels::dem::shape::Particle<f64>, top: f64) -> bool {
    g.position[1] - g.shape.bounding_radius() > top
}

/// Grains wholly above height `top` (they left the pack).
fn escaped_grains(dem: &DemWorld<f64>, top: f64) -> usize {
    dem.particles.iter().filter(|g| above(g, top)).count()
}

impl Prediction {
    /// Terzaghi's settlement of the column at `time` after a step `load`: the undrained part (1 − γ)σ₀L/K_v at
    /// once, then γσ₀L/K_v × U(c_v t/L²) ([`degree_of_consolidation`]). NaN for a drained depth or a ramp (not
    /// derived here).
    pub fn settlement(&self, load: f64, time: f64, ramp: f64) -> f64 {
        if self.drained_depth != 0.0 || ramp > 0.0 {
            return f64::NAN;
        }
        terzaghi_settlement(
            load,
            self.thickness,
            self.drained_modulus,
            self.loading_efficiency,
            self.consolidation_coefficient,
            time,
        )
    }

    /// γ × Terzaghi's solution (for the loading of the scene: a step, or the ramp `ramp`) at `depth` below
    /// the pack top and time `time`: a column of length L − d drained at depth d (zero pressure above it).
    pub fn pressure_over_load(&self, depth: f64, time: f64, ramp: f64) -> f64 {
        let d = self.drained_depth;
        if depth <= d {
            return 0.0;
        }
        self.loading_efficiency
            * terzaghi_pressure_ramped(
                depth - d,
                time,
                self.consolidation_coefficient,
                self.thickness - d,
                ramp,
            )
    }
}

/// One pore-pressure profile: time since the step and (depth below the top, p/σ₀) per lattice row.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Profile {
    /// Time since the step.
    pub time: f64,
    /// (depth, p/σ₀).
    pub rows: Vec<[f64; 2]>,
    /// Σ over the column's nodes of the excess density / Σ over its rows of (nodes × the fluid-only excess):
    /// the fraction of the lattice that stores fluid at the pore pressure (diagnostic of the storage term).
    pub stored_fraction: f64,
    /// Settlement of the loaded layer since the step (its grains' mean height, weighted by their shares of the
    /// load, at the step minus now; positive downwards).
    #[serde(default)]
    pub settlement: f64,
}

impl Profile {
    /// The skeleton's constrained modulus in the wet column at this record: the effective stress σ₀ − p
    /// integrated over the column's rows (spacing `h`, p from this record) over the settlement, σ₀ = `load`.
    /// Under uniaxial strain the settlement is the integral of the strain (σ₀ − p)/K_v, so this is K_v where the
    /// skeleton is uniform; NaN before the layer has moved.
    pub fn wet_modulus(&self, load: f64, h: f64) -> f64 {
        let effective: f64 = self.rows.iter().map(|r| load * (1.0 - r[1]) * h).sum();
        if self.settlement > 0.0 {
            effective / self.settlement
        } else {
            f64::NAN
        }
    }
}

/// What the comparison with Terzaghi's solution gives.
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    /// Records compared (after the start-up).
    pub records: usize,
    /// Samples compared.
    pub samples: usize,
    /// RMS of measured − predicted p over γσ₀, after the start-up.
    pub rms_over_gamma_load: f64,
    /// Consolidation coefficient fitted freely to the same samples (p/(γσ₀) with the predicted γ).
    pub fitted_coefficient: f64,
    /// Fitted over predicted c_v.
    pub fitted_over_predicted: f64,
    /// RMS residual of the fit over γσ₀.
    pub fit_rms: f64,
    /// Largest mean p/σ₀ over the bottom grain diameter (the undrained plateau before drainage reaches the
    /// base; Terzaghi: γ).
    pub bottom_peak_over_load: f64,
    /// Time of that peak.
    pub bottom_peak_time: f64,
    /// Stored fraction ([`Profile::stored_fraction`]) at the first record after the start-up and at the last
    /// record whose mean pressure is still above γσ₀/10, against the porosity n = 1 − ⟨ε⟩ the prediction uses.
    pub stored_fraction_early: f64,
    /// At the last record.
    pub stored_fraction_late: f64,
    /// The wet skeleton's constrained modulus ([`Profile::wet_modulus`]) at the first record after the start-up,
    /// against the dry K_v the prediction uses.
    pub wet_modulus_early: f64,
    /// At the last record still holding a tenth of γσ₀ on average.
    pub wet_modulus_late: f64,
    /// RMS over the compared records of the loaded layer's settlement minus Terzaghi's
    /// ([`Prediction::settlement`]), over the final settlement σ₀L/K_v (NaN with a ramp or a drained depth).
    pub settlement_rms_over_final: f64,
}

/// The run state.
#[derive(Serialize, Deserialize)]
pub struct TerzaghiState {
    world: CoupledWorld,
    darcy: Option<FluidLattice<f64>>,
    flow: SteadyFlow,
    nx: usize,
    ny: usize,
    pack_rows: usize,
    free_rows: usize,
    grains: usize,
    loaded: Vec<usize>,
    after: Vec<(Vector<f64>, f64)>,
    prediction: Prediction,
    substeps: u32,
    steps: u64,
    record_every: u64,
    s: u64,
    profiles: Vec<Profile>,
    snapshots: SnapshotClock,
    /// The radiating top's state (`drained_top = "radiating"`).
    #[serde(default)]
    radiating: Option<RadiatingSide>,
    /// The absorbing load's state (`load_dashpot`).
    #[serde(default)]
    dashpot: Option<LoadDashpot>,
    /// Height of the loaded layer at the step (its grains' mean, weighted by their shares of the load).
    #[serde(default)]
    layer_start: Option<f64>,
    /// The sealed column (`sealed_check`), run after the Darcy run and before the drained one.
    #[serde(default)]
    sealed: Option<SealedRun>,
    /// The sealed column's pore pressure at its end: (depth, pressure) per fluid row of the pack (`sealed.csv`).
    #[serde(default)]
    sealed_profile: Vec<[f64; 2]>,
}

/// The loaded layer's mean of `of` over its grains, weighted by bounding radius (their shares of the load,
/// [`DemWorld::apply_boundary_stress`]).
fn layer_mean(
    dem: &DemWorld<f64>,
    loaded: &[usize],
    of: impl Fn(&lbdem_kernels::dem::shape::Particle<f64>) -> f64,
) -> f64 {
    let (mut sum, mut w) = (0.0, 0.0);
    for &i in loaded {
        let g = &dem.particles[i];
        let r = g.shape.bounding_radius();
        sum += r * of(g);
        w += r;
    }
    sum / w
}

/// Height of the loaded layer ([`layer_mean`] of the grains' heights).
fn layer_height(dem: &DemWorld<f64>, loaded: &[usize]) -> f64 {
    layer_mean(dem, loaded, |g| g.position[1])
}

/// The lattice of the column: walls west, east and south on the platens, `north` on top, the kind's collision
/// and solid operator (with ΩΛ's constants `lambda`).
fn column_lattice(
    nx: usize,
    ny: usize,
    north: SideCondition<f64>,
    params: FluidParams<f64>,
    exec: &Exec,
    collision: lbdem_kernels::fluid::collide::Collision<f64>,
    (op, lambda): (SolidOperator, LambdaTerms),
) -> Result<FluidLattice<f64>> {
    let mut fluid = FluidLattice::<f64>::new(
        nx,
        ny,
        Boundaries {
            west: SideCondition::Wall,
            east: SideCondition::Wall,
            south: SideCondition::Wall,
            north,
        },
        params,
    )?;
    exec.apply(&mut fluid);
    fluid.set_collision(collision_of(collision)?)?;
    fluid.set_solid_operator(op);
    fluid.set_lambda_terms(lambda)?;
    Ok(fluid)
}

/// A matched dashpot on the loaded layer ([`TerzaghiSection::load_dashpot`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
struct LoadDashpot {
    /// Each loaded grain's coefficient c_i (force per velocity), in the order of `loaded`: its share of c.
    coefficients: Vec<f64>,
}

impl LoadDashpot {
    /// The layer's vertical velocity v (the grains' mean weighted by their coefficients) and each loaded grain's
    /// dashpot force −c_i v.
    ///
    /// A dashpot against the velocity relative to a slow running mean (so as not to resist the settlement) was
    /// tried and not kept: the mean takes up part of the wave's velocity and then pushes the layer down by
    /// c v̄ after the wave has gone (a running mean over 10 crossings: 10 % of the load for about a second).
    fn forces<'a>(
        &'a self,
        dem: &DemWorld<f64>,
        loaded: &[usize],
    ) -> impl Iterator<Item = f64> + 'a {
        let total: f64 = self.coefficients.iter().sum();
        let v = loaded
            .iter()
            .zip(&self.coefficients)
            .map(|(&i, c)| c * dem.particles[i].velocity[1])
            .sum::<f64>()
            / total;
        self.coefficients.iter().map(move |c| -c * v)
    }
}

impl Persist for TerzaghiState {}

fn contact(c: &TerzaghiSection) -> ContactModel<f64> {
    elastic_contact(c.normal_stiffness, c.normal_stiffness, c.friction)
}

/// DEM critical step of the smallest grain with six contacts (a 2 × 2 hexagonal probe of `radius_min` and the
/// scene's aspect ratio).
fn critical_step(c: &TerzaghiSection) -> Result<f64> {
    let aspect = c.aspect_ratio.unwrap_or(1.0);
    let probe = hexagonal_packing(2, 2, c.radius_min, aspect, 0.0, c.grain_density, c.seed);
    Ok(DemWorld::new(probe, contact(c), 1e-300)?.critical_time_step())
}

fn start(case: &Case<Terzaghi>, exec: &Exec) -> Result<TerzaghiState> {
    let c = &case.scene.terzaghi;
    let u = &case.setup.units;
    let h = u.spacing;
    let critical = critical_step(c)?;
    // 1. The random pack (the dissertation's procedure) at the isotropic stress.
    let mut spec =
        PackingSpec::dissertation(c.width, c.height, c.aspect_ratio.unwrap_or(1.0), c.seed);
    spec.radius_min = c.radius_min;
    spec.radius_max = c.radius_max;
    spec.density = c.grain_density;
    spec.contact = contact(c);
    spec.isotropic_stress = c.isotropic_stress;
    spec.timestep = 0.5 * critical;
    let bonds = match (c.bond_stiffness, c.bond_strength) {
        (Some(stiffness), Some(strength)) => Some(BondSpec::Point {
            stiffness,
            strength,
        }),
        _ => None,
    };
    let pk = generate_packing(&spec, bonds)?;
    if !pk.converged {
        // A pack short of the isotropic stress, or not in equilibrium, collapses under the step: the drained
        // modulus, and everything predicted from it, would describe a rearrangement.
        return Err(LbdemError::field(
            "terzaghi.isotropic_stress",
            c.isotropic_stress,
            &format!(
                "the random pack did not reach it in equilibrium within {} DEM steps (wall stresses {:.3e} / \
                 {:.3e} / {:.3e} / {:.3e}, unbalanced force ratio {:.1e})",
                pk.steps,
                pk.wall_stresses[0],
                pk.wall_stresses[1],
                pk.wall_stresses[2],
                pk.wall_stresses[3],
                pk.unbalanced_force_ratio
            ),
            "change terzaghi.seed, or pack a shorter column (terzaghi.height) or larger grains (terzaghi.radius_min, \
             radius_max)",
        ));
    }
    let mut dem = pk.world;
    // Bonds stiffen the grains' springs: the step follows the bonded world's critical step.
    let critical = critical.min(dem.critical_time_step());
    dem.set_timestep(0.5 * critical)?;
    let top = pk.sample_box.top;
    // 2. Top platen off; the vertical stress through the particles of the top layer; settle (dry).
    dem.platens[top].active = false;
    let loaded = dem.boundary_particles(3, c.radius_max);
    dem.external_force = vec![Vector::zeros(); dem.particles.len()];
    dem.apply_boundary_stress(&loaded, vector(0.0, -1.0), c.isotropic_stress, c.width);
    let (_, settled) = settle_loaded(
        &mut dem,
        &loaded,
        DRY_BLOCK,
        c.radius_min,
        1e-4,
        DRY_MAX_STEPS,
    );
    if !settled {
        return Err(LbdemError::field(
            "terzaghi.isotropic_stress",
            c.isotropic_stress,
            "the pack did not settle under it with the top platen removed",
            "raise the stress (σ/k_n ≳ 1e-4) or the packing size",
        ));
    }
    // Grains that left the pack when its top platen went: a few (the bundled pack loses two) are reported at
    // the step; a pack that does not hold together is refused here, before the Darcy run.
    let gone = escaped_grains(&dem, dem.platens[top].wall.point[1]);
    if gone as f64 > MAX_ESCAPED * dem.particles.len() as f64 {
        return Err(LbdemError::field(
            "terzaghi.seed",
            c.seed,
            &format!(
                "packs a column that does not hold together: {gone} of {} grains left it when its top platen was \
                 removed (more than {:.0} %)",
                dem.particles.len(),
                100.0 * MAX_ESCAPED
            ),
            "change terzaghi.seed, or pack a shorter column (terzaghi.height) or larger grains (terzaghi.radius_min, \
             radius_max)",
        ));
    }
    let before: Vec<Vector<f64>> = dem.external_force.clone();
    // 3. Drained constrained modulus: the same step load on a dry copy.
    // The column: bottom platen (y = 0) to the top platen the pack was made against.
    let thickness = dem.platens[top].wall.point[1];
    let mut dry = dem.clone();
    let step: StepLoadResult = uniaxial_strain_step(
        &mut dry,
        &loaded,
        c.isotropic_stress + c.load,
        c.width,
        DRY_BLOCK,
        DRY_TOLERANCE,
        DRY_MAX_STEPS,
    );
    let after_forces = dry.external_force.clone();
    let dry_strain = step.settlement / thickness;
    if !(step.converged && dry_strain > 0.0 && dry_strain <= MAX_DRY_STRAIN) {
        return Err(LbdemError::field(
            "terzaghi.load",
            c.load,
            &format!(
                "the dry step load {} (strain {dry_strain:.3e} after {} DEM steps): not a small elastic strain of the \
                 skeleton, so no drained modulus can be measured",
                if step.converged {
                    "rearranged the pack"
                } else {
                    "did not settle"
                },
                step.steps
            ),
            &format!(
                "keep the dry strain within {MAX_DRY_STRAIN}: lower terzaghi.load, or raise terzaghi.isotropic_stress \
                 or terzaghi.normal_stiffness"
            ),
        ));
    }
    let drained_modulus = constrained_modulus(c.load, dry_strain);
    // The same copy unloaded again: an elastic skeleton gives its settlement back.
    let mut unloaded = dry.clone();
    let back = uniaxial_strain_step(
        &mut unloaded,
        &loaded,
        c.isotropic_stress,
        c.width,
        DRY_BLOCK,
        DRY_TOLERANCE,
        DRY_MAX_STEPS,
    );
    let dry_recovery = -back.settlement / step.settlement;
    if !(back.converged && dry_recovery >= MIN_DRY_RECOVERY) {
        return Err(LbdemError::field(
            "terzaghi.load",
            c.load,
            &format!(
                "the dry step load rearranged the pack: taken off again it gave back {:.0} % of its settlement{} \
                 (strain {dry_strain:.3e}; an elastic skeleton gives back all of it), so the drained modulus it \
                 measures ({drained_modulus:.4e}) is not the skeleton's",
                100.0 * dry_recovery,
                if back.converged {
                    ""
                } else {
                    " and had not settled"
                }
            ),
            "lower terzaghi.load, raise terzaghi.isotropic_stress, or pack another column (terzaghi.seed)",
        ));
    }
    if dry_recovery < ELASTIC_DRY_RECOVERY {
        eprintln!(
            "lbdem: WARNING: terzaghi: the dry step load gave back only {:.1} % of its settlement when taken off: part \
             of the drained modulus K_v is a rearrangement of the pack; another terzaghi.seed or a smaller \
             terzaghi.load measures the skeleton alone",
            100.0 * dry_recovery
        );
    }
    // 4. The coupled lattice: walls W/E/S on the platens, Zou–He P = 0 at the top of a free layer.
    let nx = (c.width / h).round() as usize;
    let pack_rows = (thickness / h).round() as usize;
    let free_rows = ((c.free_layer.unwrap_or(2.0 * c.radius_max) / h).round() as usize).max(2);
    let ny = pack_rows + free_rows;
    let params = FluidParams {
        tau: u.tau,
        force: [0.0; 2],
    };
    let (default_collision, op) = fluid_choice(&case.scene, u.tau, &mut Warnings::default());
    let collision = case
        .scene
        .fluid
        .checked_collision(default_collision, u.tau)?;
    let lambda = case.scene.fluid.lambda_terms(op)?;
    let fluid = column_lattice(
        nx,
        ny,
        SideCondition::Pressure { density: 1.0 },
        params,
        exec,
        collision,
        (op, lambda),
    )?;
    // The rule (and the refusal) of the budget, which `check` printed.
    let substeps = limits::dem_substeps(
        "terzaghi.normal_stiffness",
        "terzaghi.duration",
        None,
        u.timestep,
        critical,
    )? as u32;
    let map = LatticeMap::of(u, [0.5 * h, 0.5 * h]);
    // The sealed copy (`sealed_check`): the same grains and fluid, its top a lid (a velocity side) just above
    // the pack.
    let sealed = if c.sealed_check {
        let mut lid = column_lattice(
            nx,
            pack_rows + SEALED_FREE_ROWS,
            SideCondition::VelocityProfile,
            params,
            exec,
            collision,
            (op, lambda),
        )?;
        lid.set_side_profile(Side::North, &vec![[0.0; 2]; nx])?;
        let mut w = CoupledWorld::new(
            lid,
            dem.clone(),
            map,
            c.fluid_radius,
            op.weighting(),
            substeps,
        )?;
        for (i, f) in before.iter().enumerate() {
            w.applied[i] = (*f, 0.0);
        }
        Some(SealedRun::new(w, thickness / u.sound_speed / u.timestep))
    } else {
        None
    };
    let mut world = CoupledWorld::new(fluid, dem, map, c.fluid_radius, op.weighting(), substeps)?;
    for (i, f) in before.iter().enumerate() {
        world.applied[i] = (*f, 0.0);
    }
    let after: Vec<(Vector<f64>, f64)> = after_forces.iter().map(|f| (*f, 0.0)).collect();
    // 5. The Darcy lattice: the same grains, held, with free layers below and above and Zou–He faces.
    let bodies: Vec<CoupledBody<f64>> = world
        .bodies()
        .into_iter()
        .map(|b| CoupledBody {
            center: b.center + vector(0.0, free_rows as f64),
            velocity: Vector::zeros(),
            spin: 0.0,
            ..b
        })
        .collect();
    let ny_d = pack_rows + 2 * free_rows;
    let mut darcy = FluidLattice::<f64>::new(
        nx,
        ny_d,
        Boundaries {
            west: SideCondition::Wall,
            east: SideCondition::Wall,
            south: SideCondition::Pressure {
                density: 1.0 + DARCY_DRHO,
            },
            north: SideCondition::Pressure { density: 1.0 },
        },
        params,
    )?;
    exec.apply(&mut darcy);
    darcy.set_collision(collision_of(collision)?)?;
    darcy.set_solid_operator(op);
    darcy.set_lambda_terms(lambda)?;
    darcy.cover_with_bodies(&bodies, op.weighting());
    // Fluid-only nodes start on the linear profile, covered ones at ρ₀: the storage fraction measured at the
    // steady state is then what the covered nodes took up during the run, not an initial condition.
    let eps_d = darcy.solid_fraction_map();
    darcy.fill_equilibrium(|x, y| {
        let f = (y as f64 / (ny_d - 1) as f64).clamp(0.0, 1.0);
        if eps_d[y * nx + x] == 0.0 {
            (1.0 + DARCY_DRHO * (1.0 - f), [0.0; 2])
        } else {
            (1.0, [0.0; 2])
        }
    });
    // Porosity the fluid sees over the column (the coupled lattice's coverage at t = 0).
    world
        .fluid
        .cover_with_bodies(&world.bodies(), world.weighting);
    let eps = world.fluid.solid_fraction_map();
    let porosity = 1.0 - eps[..pack_rows * nx].iter().sum::<f64>() / (pack_rows * nx) as f64;
    let dividing = dividing_surface_depth(&eps, nx, pack_rows, h);
    let drained_depth = match c.drained_surface.unwrap_or_default() {
        DrainedSurface::PackTop => 0.0,
        DrainedSurface::DividingSurface => dividing,
    };
    if drained_depth >= 0.5 * thickness {
        return Err(LbdemError::field(
            "terzaghi.drained_surface",
            format!("{dividing:.4e}"),
            "the measured dividing surface lies in the lower half of the column: its top layer is not a surface",
            "use \"pack_top\", or a taller column of smaller grains",
        ));
    }
    let steps = u.time_to_steps(c.duration).round().max(10.0) as u64;
    let record_every = (u.time_to_steps(c.record_interval).round() as u64).max(1);
    let prediction = Prediction {
        thickness,
        drained_modulus,
        dry_strain,
        dry_steps: step.steps,
        dry_converged: step.converged,
        dry_recovery,
        sealed: None,
        porosity,
        storage_porosity: f64::NAN,
        permeability: f64::NAN,
        darcy_steps: 0,
        fluid_compressibility: u.compressibility,
        storage_fluid: f64::NAN,
        storage_skeleton: f64::NAN,
        storage: f64::NAN,
        loading_efficiency: f64::NAN,
        consolidation_coefficient: f64::NAN,
        sound_crossing_time: thickness / u.sound_speed,
        diffusion_time: f64::NAN,
        dividing_surface_depth: dividing,
        drained_depth,
        mixture_density: f64::NAN,
        undrained_modulus: f64::NAN,
        undrained_impedance: f64::NAN,
        escaped_grains: 0,
        permeability_lower_half: f64::NAN,
        permeability_upper_half: f64::NAN,
    };
    let grains = world.dem.particles.len();
    let radiating = (c.drained_top.unwrap_or_default() == DrainedTop::Radiating).then(|| {
        let crossing_steps = c.height / u.sound_speed / u.timestep;
        RadiatingSide {
            density: 1.0,
            rate: (1.0 / (RADIATING_CROSSINGS * crossing_steps)).min(1.0),
            mean: 0.0,
        }
    });
    Ok(TerzaghiState {
        world,
        darcy: Some(darcy),
        flow: SteadyFlow::new(
            Steadiness::new(DARCY_TOLERANCE).accepting_drift(),
            200,
            400_000,
        ),
        nx,
        ny,
        pack_rows,
        free_rows,
        grains,
        loaded,
        after,
        prediction,
        substeps,
        steps,
        record_every,
        s: 0,
        profiles: Vec::new(),
        snapshots: SnapshotClock::default(),
        radiating,
        dashpot: None,
        layer_start: None,
        sealed,
        sealed_profile: Vec::new(),
    })
}

/// Largest c Δt / m of the absorbing load's dashpot (the loaded layer's total coefficient, fluid step and mass)
/// accepted: an explicit dashpot is stable and first-order accurate well below 1.
const DASHPOT_MAX_STEP: f64 = 0.5;

/// The absorbing load of `factor` × the matched dashpot Z W on the layer `loaded` (shares by bounding radius,
/// as [`DemWorld::apply_boundary_stress`] shares the load), its running mean at rest. Refused (naming
/// `terzaghi.load_dashpot`) when the impedance is not finite and positive or the dashpot would be too stiff for
/// the fluid step.
fn load_dashpot(
    factor: f64,
    p: &Prediction,
    dem: &DemWorld<f64>,
    loaded: &[usize],
    c: &TerzaghiSection,
    u: &crate::units::LatticeUnits,
) -> Result<LoadDashpot> {
    let total = factor * p.undrained_impedance * c.width;
    let mass: f64 = loaded.iter().map(|&i| dem.particles[i].mass).sum();
    let stiffness = total * u.timestep / mass;
    if !(total.is_finite() && total > 0.0 && stiffness <= DASHPOT_MAX_STEP) {
        return Err(LbdemError::field(
            "terzaghi.load_dashpot",
            factor,
            &format!(
                "gives a dashpot c = {total:.4e} on the loaded layer (undrained impedance {:.4e}, M_u {:.4e}, mixture                  density {:.4e}) with c dt/m = {stiffness:.3e}: not a stable explicit dashpot (at most                  {DASHPOT_MAX_STEP})",
                p.undrained_impedance, p.undrained_modulus, p.mixture_density
            ),
            "lower terzaghi.load_dashpot (1 is the matched dashpot), or shorten fluid.timestep",
        ));
    }
    let radii: Vec<f64> = loaded
        .iter()
        .map(|&i| dem.particles[i].shape.bounding_radius())
        .collect();
    let sum: f64 = radii.iter().sum();
    Ok(LoadDashpot {
        coefficients: radii.iter().map(|r| total * r / sum).collect(),
    })
}

impl TerzaghiState {
    /// The coupled world, for diagnostics (`examples/omega_probe.rs`): stepping it directly bypasses the
    /// kind's records.
    #[doc(hidden)]
    pub fn world_mut(&mut self) -> &mut CoupledWorld {
        &mut self.world
    }

    /// Whether the Darcy measurement is over and the step load is on (the coupled consolidation has begun).
    #[doc(hidden)]
    pub fn loaded(&self) -> bool {
        self.darcy.is_none()
    }

    /// The next VTK snapshot (grains, bonds if any, lattice with the pore pressure above the drained top).
    fn snapshot(&mut self, case: &Case<Terzaghi>, dir: &Path, every: u64) -> Result<()> {
        let h = &case.scene.scene;
        write_coupled_at_step(
            dir,
            &mut self.snapshots,
            every,
            self.s,
            (h.name.as_deref(), &h.kind, h.units),
            &case.setup.units,
            &mut self.world,
        )
    }

    fn advance(&mut self, case: &Case<Terzaghi>) -> Result<()> {
        let u = &case.setup.units;
        let c = &case.scene.terzaghi;
        let nx = self.nx;
        if let Some(darcy) = &mut self.darcy {
            let (fr, pr) = (self.free_rows, self.pack_rows);
            let ny_d = pr + 2 * fr;
            let row = fr / 2;
            let flux = move |f: &FluidLattice<f64>| -> f64 {
                let (rho, vel) = f.moments();
                (0..nx)
                    .map(|x| rho[row * nx + x] * vel[row * nx + x][1])
                    .sum::<f64>()
                    / nx as f64
            };
            if !self.flow.advance(darcy, flux, HINT)? {
                return Ok(());
            }
            let (rho, _) = darcy.moments();
            let mean = |y: usize| (0..nx).map(|x| rho[y * nx + x]).sum::<f64>() / nx as f64;
            let drop = CS2 * (mean(row) - mean(ny_d - 1 - row));
            // The storage porosity of the lattice at the steady state: excess density of every node of the
            // column over that of its fluid-only nodes, row by row (see `Profile::stored_fraction`).
            let eps = darcy.solid_fraction_map();
            let rows = fluid_row_means(&rho, &eps, nx, fr..fr + pr);
            let (mut all, mut pore) = (0.0, 0.0);
            for &(y, m, _) in &rows {
                all += rho[y * nx..(y + 1) * nx]
                    .iter()
                    .map(|r| r - 1.0)
                    .sum::<f64>();
                pore += nx as f64 * (m - 1.0);
            }
            let storage_porosity = all / pore;
            let k = permeability(u.lattice_viscosity, self.flow.flux, pr as f64, drop);
            // The column's heterogeneity: the permeability of each half of the pack from the least-squares
            // gradient of its fluid-only row means (Darcy's law locally), against the end-to-end k.
            let half = |lo: usize, hi: usize| {
                let pts: Vec<(f64, f64)> = rows
                    .iter()
                    .filter(|r| r.0 >= lo && r.0 < hi)
                    .map(|r| (r.0 as f64, CS2 * r.1))
                    .collect();
                let (slope, _, _) = linear_fit(&pts);
                u.permeability_to_physical(u.lattice_viscosity * self.flow.flux / -slope)
            };
            let (k_lower, k_upper) = (half(fr, fr + pr / 2), half(fr + pr / 2, fr + pr));
            let p = &mut self.prediction;
            p.permeability = u.permeability_to_physical(k);
            p.permeability_lower_half = k_lower;
            p.permeability_upper_half = k_upper;
            p.darcy_steps = self.flow.steps;
            p.storage_porosity = storage_porosity;
            let n = if c.storage_porosity_measured {
                storage_porosity
            } else {
                p.porosity
            };
            let (sf, ss) = storage_terms(n, p.fluid_compressibility, p.drained_modulus);
            let m = biot_modulus(n, p.fluid_compressibility, 0.0, 1.0);
            p.storage_fluid = sf;
            p.storage_skeleton = ss;
            p.storage = uniaxial_storage(m, 1.0, p.drained_modulus);
            p.loading_efficiency = loading_efficiency(m, 1.0, p.drained_modulus);
            p.consolidation_coefficient =
                consolidation_coefficient(p.permeability, u.density * u.viscosity, p.storage);
            p.diffusion_time = p.thickness * p.thickness / p.consolidation_coefficient;
            // The column's undrained impedance: fluid everywhere plus the excess mass of the grains in it (a
            // grain wholly above the pack top left it while it settled: not part of the column).
            let top = p.thickness;
            let excess: f64 = self
                .world
                .dem
                .particles
                .iter()
                .filter(|g| !above(g, top))
                .map(|g| g.mass - u.density * g.shape.area())
                .sum();
            let escaped = escaped_grains(&self.world.dem, top);
            p.escaped_grains = escaped;
            if escaped > 0 {
                eprintln!(
                    "lbdem: WARNING: terzaghi: {escaped} grain(s) left the pack while it settled (wholly above its top \
                     at the step): they are not part of the column and drift off in the snapshots; another \
                     terzaghi.seed packs a column without"
                );
            }
            p.mixture_density = u.density + excess / (c.width * p.thickness);
            p.undrained_modulus = p.drained_modulus / (1.0 - p.loading_efficiency);
            p.undrained_impedance = (p.undrained_modulus * p.mixture_density).sqrt();
            // Terzaghi's diffusion describes the column only when sound crosses it much faster than pressure
            // diffuses (the model: the fracture kind's warning).
            let regime = p.diffusion_time / p.sound_crossing_time;
            if regime < DIFFUSION_DOMINATED {
                eprintln!(
                    "lbdem: WARNING: terzaghi: the column is not diffusion-dominated (diffusion time L^2/c_v / sound \
                     crossing time L/c_s = {regime:.1} < {DIFFUSION_DOMINATED}): the start-up overlaps the \
                     dissipation and the comparison is only indicative; lengthen terzaghi.height, or shorten \
                     fluid.timestep (faster sound)"
                );
            }
            if let Some(r) = c.load_ramp {
                if r > 0.05 * p.diffusion_time {
                    eprintln!(
                        "lbdem: WARNING: terzaghi: load_ramp = {r:.4e} is {:.1} % of the diffusion time L^2/c_v: \
                         the column drains while it is loaded; shorten terzaghi.load_ramp",
                        100.0 * r / p.diffusion_time
                    );
                }
            }
            eprintln!(
                "lbdem: terzaghi: K_v = {:.4e} (dry recovery {:.4}), k = {:.4e}, n = {:.4}, storage porosity {:.4}: S = {:.4e} (fluid \
                 {:.4e}, skeleton {:.4e}), gamma = {:.4}, c_v = {:.4e}; dividing surface {:.4e} below the pack \
                 top, drained surface at {:.4e}",
                p.drained_modulus,
                p.dry_recovery,
                p.permeability,
                p.porosity,
                p.storage_porosity,
                p.storage,
                p.storage_fluid,
                p.storage_skeleton,
                p.loading_efficiency,
                p.consolidation_coefficient,
                p.dividing_surface_depth,
                p.drained_depth
            );
            self.darcy = None;
            // The step load.
            for &i in &self.loaded {
                self.world.applied[i] = self.after[i];
            }
            self.layer_start = Some(layer_height(&self.world.dem, &self.loaded));
            if let Some(factor) = c.load_dashpot {
                self.dashpot = Some(load_dashpot(
                    factor,
                    &self.prediction,
                    &self.world.dem,
                    &self.loaded,
                    c,
                    u,
                )?);
            }
            if let Some(run) = &mut self.sealed {
                let d = load_dashpot(1.0, &self.prediction, &run.world.dem, &self.loaded, c, u)?;
                run.load(d, &self.loaded);
            }
            return Ok(());
        }
        if let Some(run) = &mut self.sealed {
            run.advance(
                u,
                &self.loaded,
                &self.after,
                c.isotropic_stress + c.load,
                nx,
                self.pack_rows,
                divergence_hint(&run.world),
            )?;
            if run.done() {
                let p = &self.prediction;
                let m = run.measurement(
                    c.load,
                    p.thickness,
                    self.pack_rows as f64 * u.spacing,
                    p.fluid_compressibility,
                    SEALED_FREE_ROWS as f64 * u.spacing,
                    p.drained_modulus,
                    p.storage_porosity,
                );
                eprintln!(
                    "lbdem: terzaghi: sealed column: p/sigma_0 = {:.4} (predicted {:.4} with the lid's dead volume \
                     {:.3e}); with the grains free: storage porosity {:.4} (Darcy, grains held: {:.4}), \
                     undrained skeleton modulus {:.4e} (dry K_v {:.4e}); the sample's gamma {:.4} (predicted \
                     {:.4}); pressure spread {:.1e}, drift {:.1e}",
                    m.loading_efficiency,
                    m.loading_efficiency_predicted,
                    m.dead_volume,
                    m.storage_porosity,
                    p.storage_porosity,
                    m.skeleton_modulus,
                    p.drained_modulus,
                    m.sample_loading_efficiency,
                    p.loading_efficiency,
                    m.pressure_spread,
                    m.pressure_drift
                );
                let l = self.prediction.thickness;
                self.sealed_profile = run
                    .last
                    .iter()
                    .map(|&(y, p)| [l - (y as f64 + 0.5) * u.spacing, p])
                    .collect();
                self.prediction.sealed = Some(m);
                self.sealed = None;
            }
            return Ok(());
        }
        let end = ((self.s / 500 + 1) * 500).min(self.steps);
        let load = c.load;
        let ramp = c.load_ramp.unwrap_or(0.0);
        for s in self.s + 1..=end {
            // A ramped load: the forces on the loaded layer scale with the vertical stress (they are its
            // shares by radius, `DemWorld::apply_boundary_stress`), evaluated at the middle of the step.
            let t_mid = (s as f64 - 0.5) * u.timestep;
            let scale = if ramp > 0.0 && t_mid < ramp + u.timestep {
                let r = (0.5 * std::f64::consts::PI * (t_mid / ramp).min(1.0))
                    .sin()
                    .powi(2);
                Some((c.isotropic_stress + load * r) / (c.isotropic_stress + load))
            } else {
                None
            };
            if let Some(d) = &self.dashpot {
                // The load (ramped or not) plus the dashpot, from the velocities at the start of the step.
                let scale = scale.unwrap_or(1.0);
                for (&i, f) in self
                    .loaded
                    .iter()
                    .zip(d.forces(&self.world.dem, &self.loaded))
                {
                    let (base, m) = self.after[i];
                    self.world.applied[i] = (base * scale + vector(0.0, f), m);
                }
            } else if let Some(scale) = scale {
                for &i in &self.loaded {
                    let (f, m) = self.after[i];
                    self.world.applied[i] = (f * scale, m);
                }
            }
            if let Some(r) = &mut self.radiating {
                self.world.fluid.radiate(Side::North, r)?;
            }
            self.world.step();
            if s.is_multiple_of(self.record_every) {
                let eps = self.world.fluid.solid_fraction_map();
                let (rho, _) = self.world.fluid.moments();
                let rows = fluid_row_means(&rho, &eps, nx, 0..self.pack_rows);
                let mut out = Vec::with_capacity(rows.len());
                // Stored fraction: the excess density of every node of the rows over that of their
                // fluid-only nodes (1: every node stores at the pore pressure; the fluid-only fraction: only
                // those do).
                let (mut all, mut pore) = (0.0, 0.0);
                for &(y, mean, _) in &rows {
                    all += rho[y * nx..(y + 1) * nx]
                        .iter()
                        .map(|r| r - 1.0)
                        .sum::<f64>();
                    pore += nx as f64 * (mean - 1.0);
                }
                for (y, mean, _) in rows {
                    let p = u.pressure_to_physical(CS2 * (mean - 1.0)) / load;
                    let depth = self.prediction.thickness - (y as f64 + 0.5) * u.spacing;
                    out.push([
                        depth,
                        finite("pore pressure", p, s, divergence_hint(&self.world))?,
                    ]);
                }
                let settlement = self.layer_start.map_or(f64::NAN, |y0| {
                    y0 - layer_height(&self.world.dem, &self.loaded)
                });
                self.profiles.push(Profile {
                    time: s as f64 * u.timestep,
                    rows: out,
                    stored_fraction: all / pore,
                    settlement,
                });
            }
        }
        self.s = end;
        Ok(())
    }

    /// The comparison of the profiles after the start-up with Terzaghi's solution (γ and c_v predicted).
    pub fn comparison(&self, radius_max: f64, ramp: f64, load: f64, h: f64) -> Comparison {
        let p = &self.prediction;
        let (gamma, cv, l, d0) = (
            p.loading_efficiency,
            p.consolidation_coefficient,
            p.thickness,
            p.drained_depth,
        );
        // After the start-up, and not before the load is fully on.
        let t0 = (STARTUP_CROSSINGS * p.sound_crossing_time).max(ramp);
        let mut samples = Vec::new();
        let mut sq = 0.0;
        let mut records = 0;
        let mut bottom = (f64::NEG_INFINITY, f64::NAN);
        for r in &self.profiles {
            let base: Vec<f64> = r
                .rows
                .iter()
                .filter(|d| d[0] >= l - 2.0 * radius_max)
                .map(|d| d[1])
                .collect();
            if !base.is_empty() {
                let m = base.iter().sum::<f64>() / base.len() as f64;
                if m > bottom.0 {
                    bottom = (m, r.time);
                }
            }
            if r.time <= t0 {
                continue;
            }
            records += 1;
            for d in &r.rows {
                let theory = p.pressure_over_load(d[0], r.time, ramp);
                sq += (d[1] - theory).powi(2);
                // The free fit uses the step solution: from the ramp's middle, its equivalent step (exact to
                // O((c_v t_r/L²)²), [`terzaghi_pressure_ramped`]); depths from the drained surface.
                samples.push(((d[0] - d0).max(0.0), r.time - 0.5 * ramp, d[1] / gamma));
            }
        }
        let n = samples.len();
        let rms = (sq / n.max(1) as f64).sqrt() / gamma;
        let (fit, fit_rms, _) = if n > 0 {
            fit_consolidation(&samples, l - d0, cv)
        } else {
            (f64::NAN, f64::NAN, 0)
        };
        let first = self.profiles.iter().find(|r| r.time > t0);
        // The last record still holding a tenth of γσ₀ on average (later, the ratio of two vanishing
        // excesses means nothing).
        let late = self.profiles.iter().rfind(|r| {
            let m = r.rows.iter().map(|d| d[1]).sum::<f64>() / r.rows.len().max(1) as f64;
            m > 0.1 * gamma
        });
        // The settlement against Terzaghi's over the same records, over the final settlement σ₀L/K_v.
        let final_settlement = load * l / p.drained_modulus;
        let after: Vec<&Profile> = self.profiles.iter().filter(|r| r.time > t0).collect();
        let settlement_rms = (after
            .iter()
            .map(|r| ((r.settlement - p.settlement(load, r.time, ramp)) / final_settlement).powi(2))
            .sum::<f64>()
            / after.len().max(1) as f64)
            .sqrt();
        Comparison {
            stored_fraction_early: first.map_or(f64::NAN, |r| r.stored_fraction),
            stored_fraction_late: late.map_or(f64::NAN, |r| r.stored_fraction),
            wet_modulus_early: first.map_or(f64::NAN, |r| r.wet_modulus(load, h)),
            wet_modulus_late: late.map_or(f64::NAN, |r| r.wet_modulus(load, h)),
            settlement_rms_over_final: settlement_rms,
            records,
            samples: n,
            rms_over_gamma_load: rms,
            fitted_coefficient: fit,
            fitted_over_predicted: fit / cv,
            fit_rms,
            bottom_peak_over_load: bottom.0,
            bottom_peak_time: bottom.1,
        }
    }
}

/// Outcome of a Terzaghi run.
#[derive(Clone, Debug, Serialize)]
pub struct TerzaghiOutcome {
    /// Grains.
    pub grains: usize,
    /// Lattice of the consolidation.
    pub nodes: [usize; 2],
    /// DEM sub-steps per fluid step.
    pub substeps: u32,
    /// The independent measurements and the prediction.
    pub prediction: Prediction,
    /// The comparison.
    pub comparison: Comparison,
}

/// Run a Terzaghi case in memory to its end; also returns the profiles.
pub fn simulate(case: &Case<Terzaghi>) -> Result<(TerzaghiOutcome, Vec<Profile>)> {
    let (state, _) = run_in_memory(case, &RunOptions::default())?;
    Ok((outcome(case, &state), state.profiles.clone()))
}

fn outcome(case: &Case<Terzaghi>, state: &TerzaghiState) -> TerzaghiOutcome {
    TerzaghiOutcome {
        grains: state.grains,
        nodes: [state.nx, state.ny],
        substeps: state.substeps,
        prediction: state.prediction.clone(),
        comparison: state.comparison(
            case.scene.terzaghi.radius_max,
            case.scene.terzaghi.load_ramp.unwrap_or(0.0),
            case.scene.terzaghi.load,
            case.setup.units.spacing,
        ),
    }
}

/// The Terzaghi kind: one-dimensional consolidation of a **random** pack of free, unbonded grains (the
/// dissertation's packing procedure at `isotropic_stress`) in a box of fixed DEM platens, the top platen
/// replaced by the vertical stress applied through the particles of the top layer (so the fluid drains
/// freely upward), fluid walls west/east/south and a free fluid layer at Zou–He P = 0 above the pack; solid
/// operator Ω₁ₗ. Before the step, the run measures independently (all with the grains of the run):
/// 1. the **drained constrained modulus** K_v: a dry copy of the settled pack takes the same step σ₀ through
///    the same particles; K_v = σ₀/(settlement/L) (uniaxial strain: the lateral and bottom platens are fixed);
/// 2. the **permeability** k along the column: steady Darcy flow through the same grains held fixed, on a
///    lattice with free layers below and above and Zou–He faces ([`crate::observe::darcy`]);
/// 3. the **porosity** the fluid sees, n = 1 − ⟨ε⟩ over the column, and the LB fluid's compressibility
///    β_f = 1/(ρ₀c_s²);
///
/// then predicts γ = 1/(K_v S) and c_v = k/(μ S) with S = n β_f + 1/K_v (incompressible grains:
/// [`lbdem_reference::poroelastic`]). At t = 0 the vertical stress rises by σ₀; the row means of the
/// fluid-only pore pressure are recorded every `record_interval` and compared, after
/// [`STARTUP_CROSSINGS`] sound-crossing times, with γσ₀ × Terzaghi's series (no parameter fitted), and c is
/// also fitted freely ([`crate::observe::fit::fit_consolidation`]).
pub struct Terzaghi;

impl Kind for Terzaghi {
    const NAME: &'static str = "terzaghi";
    const OWN_SECTION: Option<&'static str> = Some("terzaghi");
    const NOT_MEASURED: &'static [&'static str] = &[
        "stored_fraction_early",
        "stored_fraction_late",
        "bottom_peak_time",
        "fitted_coefficient",
        "fitted_over_predicted",
        "fit_rms",
    ];
    type Scene = TerzaghiScene;
    type Setup = UnitsSetup;
    type State = TerzaghiState;

    fn validate(scene: &TerzaghiScene) -> Result<()> {
        let u = crate::scene::f64_bgk_units(&scene.scene, &scene.fluid)?;
        scene.output.validate()?;
        let c = &scene.terzaghi;
        for (field, v, hint) in [
            ("terzaghi.width", c.width, "packing box width"),
            ("terzaghi.height", c.height, "column height"),
            ("terzaghi.radius_min", c.radius_min, "smallest grain radius"),
            ("terzaghi.radius_max", c.radius_max, "largest grain radius"),
            ("terzaghi.grain_density", c.grain_density, "e.g. 2.65"),
            (
                "terzaghi.normal_stiffness",
                c.normal_stiffness,
                "contact stiffness, force/length",
            ),
            (
                "terzaghi.isotropic_stress",
                c.isotropic_stress,
                "packing stress",
            ),
            ("terzaghi.load", c.load, "the step load"),
            ("terzaghi.duration", c.duration, "model time"),
            (
                "terzaghi.record_interval",
                c.record_interval,
                "time between profiles",
            ),
        ] {
            positive(field, v, hint)?;
        }
        if c.radius_min > c.radius_max {
            return Err(LbdemError::field(
                "terzaghi.radius_min",
                c.radius_min,
                "exceeds terzaghi.radius_max",
                "swap them",
            ));
        }
        if c.height < 8.0 * c.radius_max || c.width < 8.0 * c.radius_max {
            return Err(LbdemError::field(
                "terzaghi.height",
                format!("{} x {}", c.width, c.height),
                "the column is shorter or narrower than four grain diameters: no continuum profile to compare",
                "make width and height at least 8 radius_max",
            ));
        }
        crate::error::fraction(
            "terzaghi.fluid_radius",
            c.fluid_radius,
            "0.8 keeps the 2-D pore space connected",
        )?;
        non_negative("terzaghi.friction", c.friction, "e.g. 0.5")?;
        if let Some(a) = c.aspect_ratio {
            crate::engine::dem::packing::check_aspect_ratio("terzaghi.aspect_ratio", a)?;
        }
        match (c.bond_stiffness, c.bond_strength) {
            (None, None) => {}
            (Some(k), Some(f)) => {
                positive(
                    "terzaghi.bond_stiffness",
                    k,
                    "point-bond stiffness, force/length",
                )?;
                positive("terzaghi.bond_strength", f, "point-bond strength, force")?;
                // The step's share on one grain of the loaded layer is about (σ_iso + σ₀) × its diameter; a
                // bond that could break under it would turn the consolidation into a fracture test.
                let share = (c.isotropic_stress + c.load) * 2.0 * c.radius_max;
                if share >= f {
                    return Err(LbdemError::field(
                        "terzaghi.load",
                        c.load,
                        &format!(
                            "with isotropic_stress gives about {share:.3e} per loaded grain, not below the bond \
                             strength {f:.3e}: bonds could break"
                        ),
                        "lower the load and the packing stress, or raise terzaghi.bond_strength",
                    ));
                }
            }
            _ => {
                return Err(LbdemError::field(
                    "terzaghi.bond_stiffness",
                    format!("{:?} / {:?}", c.bond_stiffness, c.bond_strength),
                    "bond_stiffness and bond_strength go together",
                    "give both (bonded pack) or neither (unbonded)",
                ))
            }
        }
        if let Some(f) = c.free_layer {
            positive("terzaghi.free_layer", f, "free fluid above the pack")?;
        }
        if let Some(f) = c.load_dashpot {
            positive(
                "terzaghi.load_dashpot",
                f,
                "multiple of the matched dashpot",
            )?;
            if f > 10.0 {
                return Err(LbdemError::field(
                    "terzaghi.load_dashpot",
                    f,
                    "is more than 10 times the matched dashpot: the loaded surface would be all but held",
                    "use 1 (the matched dashpot, which absorbs the undrained wave) or leave it out",
                ));
            }
        }
        if let Some(r) = c.load_ramp {
            positive("terzaghi.load_ramp", r, "time over which the load rises")?;
            if r >= 0.5 * c.duration {
                return Err(LbdemError::field(
                    "terzaghi.load_ramp",
                    r,
                    "is not short against terzaghi.duration (at least half of it)",
                    "ramp over a few sound-crossing times of the column, a small part of the diffusion time",
                ));
            }
        }
        crate::scene::density_change_within(
            "terzaghi.load",
            c.load,
            &u,
            " if the fluid carries it",
            "lower the load, or shorten fluid.timestep",
        )?;
        if c.load > c.isotropic_stress {
            return Err(LbdemError::field(
                "terzaghi.load",
                c.load,
                "exceeds terzaghi.isotropic_stress: the step would rearrange the pack, not strain it elastically",
                "keep the step a fraction of the packing stress",
            ));
        }
        crate::scene::check_resolved("terzaghi.radius_min", c.radius_min, c.fluid_radius, &u)?;
        Ok(())
    }

    fn budget(scene: &TerzaghiScene, setup: &UnitsSetup) -> Result<Budget> {
        let c = &scene.terzaghi;
        let u = &setup.units;
        let grains = limits::count(
            "terzaghi.radius_min",
            "the grain count",
            (c.width * c.height / (std::f64::consts::PI * c.radius_min * c.radius_min)).ceil(),
        )?;
        let grains = limits::grains("terzaghi.radius_min", grains)?;
        let steps = limits::steps_for("terzaghi.duration", c.duration, u.timestep, false)?;
        let critical = critical_step(c)?;
        let substeps = limits::dem_substeps(
            "terzaghi.normal_stiffness",
            "terzaghi.duration",
            Some(steps),
            u.timestep,
            critical,
        )?;
        let nx = limits::count(
            "terzaghi.width",
            "the lattice width",
            (c.width / u.spacing).ceil(),
        )?;
        let free = c.free_layer.unwrap_or(2.0 * c.radius_max);
        let ny = limits::count(
            "terzaghi.height",
            "the lattice height",
            ((c.height + 2.0 * free) / u.spacing).ceil() + 2.0,
        )?;
        // The run takes at least 10 fluid steps (`start`), and records a profile every `record_every` of them.
        let steps = steps.max(10);
        scene.output.budget(u.timestep, steps)?;
        let record_every = (u.time_to_steps(c.record_interval).round() as u64).max(1);
        let mut b = Budget::new();
        b.note(format!(
            "DEM critical step {critical:.4e}: {substeps} DEM sub-step(s) per fluid step"
        ));
        // Two lattices: the Darcy run's and the consolidation's (three with the sealed column's, at most as
        // tall).
        let lattices = if c.sealed_check { 3 } else { 2 };
        limits::lattice(
            &mut b,
            "terzaghi.width",
            "lattices",
            nx,
            lattices * ny,
            8,
            limits::Solids::Covered,
        )?;
        b.add_items("grains", "terzaghi.width", grains, limits::GRAIN_BYTES)?;
        // A pore-pressure profile per record: (depth, p) per lattice row (at most `ny`) and its header.
        b.add_items(
            "pore-pressure profiles",
            "terzaghi.record_interval",
            limits::records_every(steps, record_every),
            limits::mul("terzaghi.height", "a profile's size", ny, 16)?.saturating_add(64),
        )?;
        Ok(b)
    }

    fn setup(scene: &TerzaghiScene) -> Result<UnitsSetup> {
        let mut setup = UnitsSetup::with_free_grains(
            &scene.fluid,
            "terzaghi.solid_operator",
            FreeGrains::packed(scene.terzaghi.grain_density / scene.fluid.density)
                .in_form(scene.fluid.lambda_form),
            |tau, w| fluid_choice(scene, tau, w),
        )?;
        let c = &scene.terzaghi;
        let diameters = c.height / (2.0 * c.radius_max);
        if diameters < SHORT_COLUMN_DIAMETERS {
            setup.warnings.push(format!(
                "terzaghi.height = {}: the column is {diameters:.1} largest-grain diameters tall (< \
                 {SHORT_COLUMN_DIAMETERS}); a pack is looser next to the platens it was made against, and columns of \
                 6.7 diameters relaxed 8-18 % slower than predicted, sealed or drained (README, The sealed column): a \
                 taller column compares the pack's interior",
                c.height
            ));
        }
        Ok(setup)
    }

    fn describe(case: &Case<Self>) -> String {
        let labels = case.scene.scene.units.labels();
        let c = &case.scene.terzaghi;
        let u = &case.setup.units;
        case.setup.describe(labels)
            + &format!(
                "  column {:.1} x {:.1} nodes, grain radii {:.2}-{:.2} nodes; load {:.4e} = lattice density {:.3e}; \
                 sound-crossing time of the column {:.4e} s ({:.0} steps); {} steps\n  \
                 K_v, k and n are measured at the start of the run; gamma and c_v follow (summary.json)\n",
                c.width / u.spacing,
                c.height / u.spacing,
                c.radius_min / u.spacing,
                c.radius_max / u.spacing,
                c.load,
                u.pressure_to_density_change(c.load),
                c.height / u.sound_speed,
                c.height / u.sound_speed / u.timestep,
                u.time_to_steps(c.duration).round()
            )
    }

    fn start(case: &Case<Self>, exec: &Exec) -> Result<TerzaghiState> {
        start(case, exec)
    }

    fn lattices(state: &mut TerzaghiState) -> Vec<&mut dyn ExecTarget> {
        let mut all: Vec<&mut dyn ExecTarget> = vec![&mut state.world.fluid];
        all.extend(state.darcy.as_mut().map(|d| d as &mut dyn ExecTarget));
        all
    }

    fn steps_done(state: &TerzaghiState) -> u64 {
        state.s + state.flow.steps
    }

    fn total_steps(_case: &Case<Self>, state: &TerzaghiState) -> Option<u64> {
        Some(state.steps + state.flow.steps)
    }

    fn finished(_case: &Case<Self>, state: &TerzaghiState) -> bool {
        state.darcy.is_none() && state.s >= state.steps
    }

    fn advance(case: &Case<Self>, state: &mut TerzaghiState, dir: Option<&Path>) -> Result<()> {
        // Snapshots of the coupled run after the step load (none during the Darcy measurement before it).
        let every = case
            .scene
            .output
            .every(case.setup.units.timestep, state.steps);
        let at = dir.zip(every).filter(|_| state.darcy.is_none());
        chunk_with_snapshots(
            state,
            at,
            |s| (&s.snapshots, s.s, s.s >= s.steps),
            |s| s.advance(case),
            |s, dir, every| s.snapshot(case, dir, every),
        )
    }

    fn health(_case: &Case<Self>, state: &TerzaghiState) -> Result<()> {
        // Under ΩΛ a pack of free grains diverges at high τ (README, *A pack is less stable than a lone disc*):
        // there raising τ is the wrong way.
        coupled_health(&state.world, divergence_hint(&state.world))
    }

    fn write_outputs(
        case: &Case<Self>,
        state: &TerzaghiState,
        dir: &Path,
        _stage: OutputStage,
    ) -> Result<()> {
        let p = &state.prediction;
        let ramp = case.scene.terzaghi.load_ramp.unwrap_or(0.0);
        let rows = state.profiles.iter().flat_map(|r| {
            r.rows.iter().map(move |d| {
                let theory = if p.consolidation_coefficient.is_finite() {
                    p.pressure_over_load(d[0], r.time, ramp)
                } else {
                    f64::NAN
                };
                vec![r.time, d[0], d[1], theory]
            })
        });
        let table = csv(
            &["time", "depth", "pressure_over_load", "terzaghi_over_load"],
            rows,
        );
        write_atomic(&dir.join("profiles.csv"), table.as_bytes())?;
        let (load, h) = (case.scene.terzaghi.load, case.setup.units.spacing);
        let rows = state.profiles.iter().map(|r| {
            let theory = if p.consolidation_coefficient.is_finite() {
                p.settlement(load, r.time, ramp)
            } else {
                f64::NAN
            };
            vec![r.time, r.settlement, theory, r.wet_modulus(load, h)]
        });
        let table = csv(
            &["time", "settlement", "terzaghi_settlement", "wet_modulus"],
            rows,
        );
        write_atomic(&dir.join("settlement.csv"), table.as_bytes())?;
        if !case.scene.terzaghi.sealed_check {
            return Ok(());
        }
        // The sealed column's pressure profile at its end (header only until it has run).
        let mean = p
            .sealed
            .as_ref()
            .map_or(f64::NAN, |m| m.loading_efficiency * load);
        let rows = state
            .sealed_profile
            .iter()
            .map(|d| vec![d[0], d[1] / load, d[1] / mean]);
        let table = csv(&["depth", "pressure_over_load", "pressure_over_mean"], rows);
        write_atomic(&dir.join("sealed.csv"), table.as_bytes())
    }

    fn results(case: &Case<Self>, state: &TerzaghiState) -> Result<serde_json::Value> {
        let mut v = serde_json::to_value(outcome(case, state)).unwrap_or_default();
        // No sealed column: no `prediction.sealed` (a null would read as a result that is not finite).
        if let Some(p) = v.get_mut("prediction").and_then(|p| p.as_object_mut()) {
            if p.get("sealed").is_some_and(|s| s.is_null()) {
                p.remove("sealed");
            }
        }
        Ok(v)
    }
}
