//! Scene files: TOML in physical units, one `[scene]` header and sections. This module holds the section types
//! and range checks shared by several kinds (`[scene]`, `[fluid]` (in [`crate::units`]), `[run]`, `[packing]`,
//! `[solid]`); each kind's own sections live in its folder under `crate::kinds`. Parsing rejects unknown keys,
//! missing fields and wrong types (serde with `deny_unknown_fields`); range checks name the field and the fix.
//!
//! Example (`scenes/poiseuille.toml`):
//! ```toml
//! [scene]
//! kind = "channel"
//! units = "cgs"
//! precision = "f64"
//! [fluid]
//! density = 1.0       # g/cm³
//! viscosity = 0.1     # kinematic, cm²/s
//! spacing = 0.011     # lattice spacing h, cm
//! tau = 0.875         # or `timestep` (s): give exactly one
//! [channel]
//! length = 0.55       # cm, along x
//! width = 0.22        # cm, walls at y = 0 and y = width
//! drive = "pressure"  # Zou–He inlet/outlet; or "body_force" (periodic along x)
//! pressure_drop = 0.5 # dyne/cm² over the length
//! [run]
//! steps = 20000
//! ```
use serde::{Deserialize, Serialize};

use crate::error::{LbdemError, Result};
use crate::run::interval::CheckpointInterval;

pub mod solid;

pub use crate::input::limits;

pub use crate::units::{FluidSection, UnitLabels, UnitSystem};

/// Implements [`crate::run::SceneFile`] for scene file types whose shared sections are the fields `scene`
/// ([`SceneHeader`]) and `run` ([`RunSection`] or [`CheckpointSection`]).
macro_rules! scene_file {
    ($($t:ty),+) => {$(
        impl $crate::run::SceneFile for $t {
            fn unit_system(&self) -> $crate::units::UnitSystem {
                self.scene.units
            }
            fn checkpoint_interval(&self) -> $crate::run::CheckpointInterval {
                self.run.checkpoint_interval
            }
        }
    )+};
}
pub(crate) use scene_file;

/// A grain radius (`field`) the fluid resolves: at least 2 lattice spacings once scaled by `fluid_radius`.
pub fn check_resolved(
    field: &str,
    radius: f64,
    fluid_radius: f64,
    units: &crate::units::LatticeUnits,
) -> Result<()> {
    if units.length_to_lattice(radius) * fluid_radius >= 2.0 {
        return Ok(());
    }
    Err(LbdemError::field(
        field,
        radius,
        "is seen by the fluid as fewer than 2 lattice spacings",
        "refine fluid.spacing",
    ))
}

/// The shared start of validating a kind that runs the lattice in f64 with a BGK default collision: refuse
/// f32 (`scene.precision`), validate `[fluid]` and its collision (`fluid.collision`, `fluid.magic`, `fluid.tau`
/// in both precisions), and return the lattice units.
pub fn f64_bgk_units(
    header: &SceneHeader,
    fluid: &FluidSection,
) -> Result<crate::units::LatticeUnits> {
    header.require_f64()?;
    let u = fluid.lattice_units()?;
    fluid.checked_collision(crate::units::CollisionName::Bgk, u.tau)?;
    Ok(u)
}

/// Refuse a pressure (`field`, `value`) that is a lattice density change above 1e-2 (the lattice fluid is
/// weakly compressible: its errors grow as Δρ²); `consequence` says what would go wrong, `fix` what to do.
pub fn density_change_within(
    field: &str,
    value: f64,
    units: &crate::units::LatticeUnits,
    consequence: &str,
    fix: &str,
) -> Result<()> {
    let drho = units.pressure_to_density_change(value);
    if drho > 0.01 {
        return Err(LbdemError::field(
            field,
            value,
            &format!("gives a lattice density change {drho:.3e} > 1e-2{consequence}"),
            fix,
        ));
    }
    Ok(())
}

/// Floating-point precision of the kernels.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// Single precision.
    F32,
    /// Double precision.
    #[default]
    F64,
}

impl Precision {
    /// Bytes per float.
    pub fn float_bytes(self) -> u64 {
        match self {
            Precision::F32 => 4,
            Precision::F64 => 8,
        }
    }
}

/// `[scene]`: what is simulated, in which units and precision.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneHeader {
    /// What is simulated: the name of a kind in the registry (`crate::kinds::REGISTRY`).
    pub kind: String,
    /// Unit system of every value in the file.
    pub units: UnitSystem,
    /// Kernel precision (default f64).
    #[serde(default)]
    pub precision: Precision,
    /// Optional free-text name.
    #[serde(default)]
    pub name: Option<String>,
}

impl SceneHeader {
    /// Refuse f32 for a kind implemented in f64 only.
    pub fn require_f64(&self) -> Result<()> {
        if self.precision == Precision::F32 {
            return Err(LbdemError::field(
                "scene.precision",
                "f32",
                &format!("kind = \"{}\" is implemented in f64 only", self.kind),
                "use precision = \"f64\" (channel, cylinder_array, porous_flow and dry run in f32 too)",
            ));
        }
        Ok(())
    }
}

/// `[run]`
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RunSection {
    /// Number of lattice steps. Give this or `duration`.
    #[serde(default)]
    pub steps: Option<u64>,
    /// Model time to simulate. Give this or `steps`.
    #[serde(default)]
    pub duration: Option<f64>,
    /// Stop early once the relative change of the flux over one check interval falls below this.
    #[serde(default)]
    pub steady_tolerance: Option<f64>,
    /// Steps between health and steadiness checks (default 200).
    #[serde(default)]
    pub check_interval: Option<u64>,
    /// Accept an expected Mach number above the refusal limit (0.35); the run is still warned about.
    #[serde(default)]
    pub allow_high_mach: bool,
    /// How often to write `DIR/checkpoint.bin` (default every 10 min of wall-clock time).
    #[serde(default)]
    pub checkpoint_interval: CheckpointInterval,
}

impl RunSection {
    /// Range checks of `[run]`.
    pub fn validate(&self) -> Result<()> {
        match (self.steps, self.duration) {
            (Some(_), Some(_)) => {
                return Err(LbdemError::field(
                    "run.steps",
                    "given together with run.duration",
                    "only one of run.steps and run.duration may be given",
                    "remove one of them",
                ))
            }
            (None, None) => {
                return Err(LbdemError::field(
                    "run.steps",
                    "missing",
                    "neither run.steps nor run.duration is given",
                    "add run.steps (number of lattice steps) or run.duration (model time)",
                ))
            }
            (Some(0), None) => {
                return Err(LbdemError::field(
                    "run.steps",
                    0,
                    "must be at least 1",
                    "give a positive step count",
                ))
            }
            (None, Some(d)) => positive("run.duration", d, "give the model time to simulate")?,
            _ => {}
        }
        if let Some(tol) = self.steady_tolerance {
            positive("run.steady_tolerance", tol, "e.g. 1e-9")?;
        }
        if self.check_interval == Some(0) {
            return Err(LbdemError::field(
                "run.check_interval",
                0,
                "must be at least 1",
                "e.g. 200",
            ));
        }
        Ok(())
    }

    /// Steps to run (an upper bound when a steady tolerance is set), from `steps` or `duration` / Δt, refused
    /// naming the field above [`limits::MAX_STEPS`].
    pub fn step_count(&self, timestep: f64) -> Result<u64> {
        match (self.steps, self.duration) {
            (Some(s), _) => limits::steps("run.steps", s),
            (None, Some(d)) => limits::steps_for("run.duration", d, timestep, true),
            _ => Ok(1),
        }
    }
}

/// `[run]` of the kinds whose length is set by their own sections: only the checkpoint interval.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CheckpointSection {
    /// How often to write `DIR/checkpoint.bin` (default every 10 min of wall-clock time).
    #[serde(default)]
    pub checkpoint_interval: CheckpointInterval,
}

/// `[output]` of the kinds with moving grains whose only outputs besides their tables are the VTK snapshots
/// (`coupled_demo`, `terminal_velocity`, `consolidation`, `terzaghi`): the particle (and bond) and lattice series
/// with their `.pvd` collections (docs/outputs.md).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SnapshotSection {
    /// Write VTK snapshots (default true).
    #[serde(default = "yes")]
    pub vtk: bool,
    /// Model time between snapshots (the kind's time unit: s, or steps for scenes in lattice units); default a
    /// tenth of the run (11 snapshots with the first and the last); 0: only the first and the last.
    #[serde(default)]
    pub snapshot_interval: Option<f64>,
}

fn yes() -> bool {
    true
}

impl Default for SnapshotSection {
    fn default() -> Self {
        Self {
            vtk: true,
            snapshot_interval: None,
        }
    }
}

impl SnapshotSection {
    /// Snapshots a run writes by default: one every tenth of the run, plus the first.
    pub const DEFAULT_PER_RUN: u64 = 10;

    /// Range check naming `output.snapshot_interval`.
    pub fn validate(&self) -> Result<()> {
        match self.snapshot_interval {
            Some(t) if !(t.is_finite() && t >= 0.0) => Err(LbdemError::field(
                "output.snapshot_interval",
                t,
                "must be finite and >= 0",
                "0 writes only the first and last snapshot; leave it out for one every tenth of the run",
            )),
            _ => Ok(()),
        }
    }

    /// Steps between snapshots for a run of `total` steps of `dt` (0: only the first and the last); `None`
    /// when `vtk = false`.
    pub fn every(&self, dt: f64, total: u64) -> Option<u64> {
        if !self.vtk {
            return None;
        }
        Some(match self.snapshot_interval {
            None => total.div_ceil(Self::DEFAULT_PER_RUN).max(1),
            Some(t) if t > 0.0 => ((t / dt).round() as u64).max(1),
            Some(_) => 0,
        })
    }

    /// The snapshots a run of `total` steps of `dt` writes ([`Self::every`]), refused above
    /// [`limits::MAX_SNAPSHOTS`] naming `output.snapshot_interval` (0 when `vtk = false`).
    pub fn budget(&self, dt: f64, total: u64) -> Result<u64> {
        match self.every(dt, total) {
            Some(every) => limits::snapshots_every("output.snapshot_interval", total, every),
            None => Ok(0),
        }
    }
}

pub(crate) use crate::error::positive;

/// The derived set-up of a scene whose lattice is sized by the kind at start: the lattice units and the
/// warnings about them.
#[derive(Clone, Debug, Serialize)]
pub struct UnitsSetup {
    /// The conversion between physical and lattice units.
    pub units: crate::units::LatticeUnits,
    /// Warnings about the relaxation time.
    pub warnings: Vec<String>,
}

impl crate::run::Derived for UnitsSetup {
    fn warnings(&self) -> &[String] {
        &self.warnings
    }
}

impl UnitsSetup {
    /// Validate `[fluid]` and derive its units, with the relaxation-time warnings.
    pub fn new(fluid: &FluidSection) -> Result<Self> {
        let units = fluid.lattice_units()?;
        let mut w = crate::units::Warnings::default();
        crate::units::check_tau(&units, &mut w);
        Ok(Self {
            units,
            warnings: w.0,
        })
    }

    /// [`UnitsSetup::new`] for a kind with free grains: the kind's `choose` (default collision and solid
    /// operator at τ) checked by [`check_free_grain_fluid`] against the scene's `grains`, its warnings
    /// kept; `field` names the scene's solid-operator key.
    pub fn with_free_grains(
        fluid: &FluidSection,
        field: &str,
        grains: FreeGrains,
        choose: impl FnOnce(
            f64,
            &mut crate::units::Warnings,
        ) -> (
            crate::units::CollisionName,
            lbdem_kernels::fluid::collide::SolidOperator,
        ),
    ) -> Result<Self> {
        let mut s = Self::new(fluid)?;
        let mut w = crate::units::Warnings(std::mem::take(&mut s.warnings));
        let tau = s.units.tau;
        let choice = choose(tau, &mut w);
        check_free_grain_fluid(field, fluid, choice, tau, grains, &mut w)?;
        s.warnings = w.0;
        Ok(s)
    }

    /// The units' derived figures, labelled.
    pub fn describe(&self, labels: UnitLabels) -> String {
        self.units
            .describe(labels.length, labels.time, labels.pressure)
    }
}

/// The number of lattice spacings in `length` when it is a positive whole number of them (within 1 %).
pub(crate) fn whole_spacings(field: &str, length: f64, h: f64) -> Result<usize> {
    let n = (length / h).round();
    if n > limits::MAX_SIDE as f64 {
        return Err(limits::side_too_long(field, length, n));
    }
    if !(length.is_finite() && length > 0.0) || n < 1.0 || (n * h - length).abs() > 0.01 * h {
        return Err(LbdemError::field(
            field,
            length,
            &format!(
                "is not a positive whole number of lattice spacings (length/h = {:.4})",
                length / h
            ),
            &format!(
                "use a multiple of fluid.spacing = {h}, e.g. {}",
                n.max(1.0) * h
            ),
        ));
    }
    Ok(n as usize)
}

pub use crate::input::parse::{kind_field, parse_scene, peek_kind, read_scene_text, KindField};

/// Where ΩΛ **in its friction-only form** (`fluid.lambda_form = "friction_only"`) with a free grain was measured
/// stable and where it diverged (κ = 1.21, full-cover gap 0.05; the free disc of `scenes/terminal_velocity.toml`,
/// radius 10 nodes, Re ≈ 0.1; `cargo run --release -p lbdem --example moving_table -- --stability
/// 1,1.25,1.5,2,2.65`): (lowest grain/fluid density ratio of the row, largest τ measured stable, smallest τ
/// measured to diverge). ρs/ρf = 1: stable to τ = 0.8, diverged from 1.2; 1.25: stable to 1.2, diverged at 2;
/// 1.5, 2 and 2.65: stable to 2 (the largest τ measured). (With the earlier full-cover gap of 1e-3: ρs/ρf = 1
/// diverged from 0.8 and 1.5 at 2.) The wall-pressure form's map: [`LAMBDA_WALL_FREE_GRAIN_STABILITY`].
pub const LAMBDA_FREE_GRAIN_STABILITY: [(f64, f64, f64); 3] =
    [(0.0, 0.8, 1.2), (1.25, 1.2, 2.0), (1.5, 2.0, f64::INFINITY)];

/// As [`LAMBDA_FREE_GRAIN_STABILITY`] (the friction-only form) for grains **packed** against each other (the
/// kinds that make a pack: `fracture`, `consolidation`, `terzaghi`). Measured with TRT + ΩΛ on
/// `scenes/terzaghi.toml` shortened to 5 s (77 free discs of 3.2–4.8 fluid nodes in radius in contact; τ
/// changed through the viscosity; the grains' density changed; a run is stable when it reaches its end):
/// ρs/ρf = 1 stable to τ = 0.6, diverged at 0.8; 1.25 stable to 0.8, diverged at 1; 1.5 stable to 1.2, diverged
/// at 1.6; 2 stable to 1.6, diverged at 2; 2.65 (rock) stable at 0.8, 1.2, 1.4 and 2 (three seeds at 2), as was
/// the quick fracture scene's bonded ellipse pack at τ = 2. A pack is less stable than a lone grain of the same
/// density: with the earlier full-cover gap of 1e-3 a rock pack diverged from τ = 1.25 (`LAMBDA_FULL_GAP` gives
/// the mode). The wall-pressure form's map: [`LAMBDA_WALL_PACKED_GRAIN_STABILITY`].
pub const LAMBDA_PACKED_GRAIN_STABILITY: [(f64, f64, f64); 5] = [
    (0.0, 0.6, 0.8),
    (1.25, 0.8, 1.0),
    (1.5, 1.2, 1.6),
    (2.0, 1.6, 2.0),
    (2.65, 2.0, f64::INFINITY),
];

/// As [`LAMBDA_FREE_GRAIN_STABILITY`] for ΩΛ's **wall-pressure form** (the default; κ = 0.5, α = 2), measured
/// the same way (`moving_table -- --stability 1,1.25,1.5,2,2.65`, 2026-12-07): ρs/ρf = 1 stable to τ = 0.8,
/// diverged at 1.2 and 2; 1.25, 1.5, 2 and 2.65 stable at every τ measured (0.55, 0.8, 1.2, 2), where the
/// friction-only form diverged with 1.25 at τ = 2.
pub const LAMBDA_WALL_FREE_GRAIN_STABILITY: [(f64, f64, f64); 2] =
    [(0.0, 0.8, 1.2), (1.25, 2.0, f64::INFINITY)];

/// As [`LAMBDA_PACKED_GRAIN_STABILITY`] for ΩΛ's **wall-pressure form** (the default), measured the same way
/// (the Terzaghi column shortened to 5 s, seed 7 unless said; README, *The pack map in the wall-pressure
/// form*): ρs/ρf = 1 stable at τ = 0.6 and 0.7, diverged at 0.8 and 1; 1.25 stable to 1.0 (seeds 7, 8, 9),
/// diverged at 1.2; 1.5 stable at 1.2 and 1.4, diverged at 1.6 and 2; 2 stable at 1.6, 1.8 and 2 (seeds 7,
/// 8, 9); rock stable at 0.8, 1.4 and 2 (seeds 7 and 9). Where the two forms differ the wall-pressure form is
/// the more stable (1.25 at τ = 1, 2 at τ = 2: both diverged in the friction-only form).
pub const LAMBDA_WALL_PACKED_GRAIN_STABILITY: [(f64, f64, f64); 4] = [
    (0.0, 0.7, 0.8),
    (1.25, 1.0, 1.2),
    (1.5, 1.4, 1.6),
    (2.0, 2.0, f64::INFINITY),
];

/// The free grains of a scene, for the choice and the check of its solid operator: the lightest grain's
/// density over the fluid's, and whether the grains are packed against each other (a pack) or lone (a few
/// grains in fluid): ΩΛ's stability map differs ([`LAMBDA_FREE_GRAIN_STABILITY`],
/// [`LAMBDA_PACKED_GRAIN_STABILITY`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreeGrains {
    /// Lightest grain density / fluid density.
    pub density_ratio: f64,
    /// Grains packed in contact (true) or lone in fluid (false).
    pub packed: bool,
    /// ΩΛ's form the scene runs (`[fluid] lambda_form`; the wall-pressure form when absent): each form has its
    /// own stability maps.
    pub form: crate::units::LambdaForm,
}

impl FreeGrains {
    /// Lone grains in fluid (`terminal_velocity`, `coupled_demo`).
    pub fn lone(density_ratio: f64) -> Self {
        Self {
            density_ratio,
            packed: false,
            form: crate::units::LambdaForm::default(),
        }
    }

    /// A pack of grains in contact (`fracture`, `consolidation`, `terzaghi`).
    pub fn packed(density_ratio: f64) -> Self {
        Self {
            density_ratio,
            packed: true,
            form: crate::units::LambdaForm::default(),
        }
    }

    /// These grains in ΩΛ's form `form` (a scene's `[fluid] lambda_form`; `None` = the wall-pressure form, the
    /// default).
    pub fn in_form(self, form: Option<crate::units::LambdaForm>) -> Self {
        Self {
            form: form.unwrap_or_default(),
            ..self
        }
    }

    /// The stability map of these grains (lone or packed) in their form, and what it was measured on.
    fn lambda_map(&self) -> (&'static [(f64, f64, f64)], &'static str) {
        use crate::units::LambdaForm;
        match (self.form, self.packed) {
            (LambdaForm::WallPressure, true) => (
                &LAMBDA_WALL_PACKED_GRAIN_STABILITY,
                "measured in packs of free discs in the wall-pressure form (README, *The pack map in the \
                 wall-pressure form*: scenes/terzaghi.toml with TRT + Omega_Lambda)",
            ),
            (LambdaForm::WallPressure, false) => (
                &LAMBDA_WALL_FREE_GRAIN_STABILITY,
                "measured with a free disc in the wall-pressure form (README, moving solids)",
            ),
            (LambdaForm::FrictionOnly, true) => (
                &LAMBDA_PACKED_GRAIN_STABILITY,
                "measured in packs of free discs in the friction-only form (README, *A pack is less stable \
                 than a lone disc*: scenes/terzaghi.toml with TRT + Omega_Lambda)",
            ),
            (LambdaForm::FrictionOnly, false) => (
                &LAMBDA_FREE_GRAIN_STABILITY,
                "measured with a free disc in the friction-only form (README, moving solids)",
            ),
        }
    }

    /// The row of ΩΛ's stability map for these grains: (lowest density ratio of the row, largest τ measured
    /// stable, smallest τ measured to diverge).
    fn lambda_row(&self) -> (f64, f64, f64) {
        let (map, _) = self.lambda_map();
        map.iter()
            .rev()
            .find(|r| self.density_ratio >= r.0)
            .copied()
            .unwrap_or(map[0])
    }

    /// Where ΩΛ's limits for these grains were measured, for messages: the rows of the map in use, written
    /// from the table itself (so the message cannot drift from what is enforced).
    fn lambda_measured(&self) -> String {
        let (map, what) = self.lambda_map();
        let rows: Vec<String> = map
            .iter()
            .map(|&(density, stable, diverged)| {
                let from = if density > 0.0 {
                    format!("grain/fluid density from {density}")
                } else {
                    "lighter grains".to_string()
                };
                if diverged.is_finite() {
                    format!("{from} stable to tau = {stable}, diverged at {diverged}")
                } else {
                    format!("{from} stable to tau = {stable} (the largest measured)")
                }
            })
            .collect();
        format!("{what}: {}", rows.join("; "))
    }
}

/// The fluid collision and solid operator of a scene with free grains that names neither, at relaxation time
/// `tau`, for the scene's free `grains` (lone or packed; the lightest grain's density over the fluid's).
///
/// The τ-independent combination, TRT + ΩΛ, where ΩΛ was measured stable with such grains
/// ([`LAMBDA_FREE_GRAIN_STABILITY`] for lone grains, [`LAMBDA_PACKED_GRAIN_STABILITY`] for packs: τ at or below
/// the row's last stable τ, grains at least as dense as the fluid): its drag does not move with τ (free disc +0.42…+0.44 % over τ = 0.55…2 where Ω₁ with BGK moves
/// from +0.49 to −10.4 %) and the fracture scenes' intact permeability is the same at every τ (README,
/// "Results that do not depend on τ"). Elsewhere the best operator that is stable there, Ω₁ₗ with BGK (the
/// dissertation's method; drag moves with τ), and `warnings` says so and what to change to get TRT + ΩΛ.
/// A scene that names `solid_operator` or `collision` keeps its choice for that key.
pub fn free_grain_defaults(
    tau: f64,
    grains: FreeGrains,
    warnings: &mut crate::units::Warnings,
) -> (
    crate::units::CollisionName,
    lbdem_kernels::fluid::collide::SolidOperator,
) {
    use crate::units::CollisionName;
    use lbdem_kernels::fluid::collide::SolidOperator as Op;
    let density_ratio = grains.density_ratio;
    let stable = grains.lambda_row().1;
    if density_ratio >= 1.0 && tau <= stable {
        (CollisionName::Trt, Op::LambdaConsistent)
    } else {
        warnings.push(format!(
            "solid_operator not given: the default, \"lambda_consistent\" with collision = \"trt\" (results \
             independent of tau), is outside the region measured stable for {} free grains {density_ratio:.3} \
             times as dense as the fluid at tau = {tau:.4}; using \"linearized_non_equilibrium_bounce_back\" \
             (Omega_1l) with collision = \"bgk\" instead, whose drag and permeability move with tau. For \
             results independent of tau lower fluid.tau to {stable} or below{}",
            if grains.packed { "packed" } else { "lone" },
            if density_ratio < 1.0 {
                " and use grains at least as dense as the fluid"
            } else {
                ""
            }
        ));
        (CollisionName::Bgk, Op::LinearizedNonEquilibriumBounceBack)
    }
}

/// The default fluid collision and the solid operator of a scene with free grains whose solid operator key
/// holds `given`: with an operator given, that operator and the collision that goes with it (TRT for ΩΛ, whose
/// τ-independence needs it; BGK for the others, the dissertation's method); without, [`free_grain_defaults`].
/// `[fluid] collision`, where given, overrides the collision returned here.
pub fn free_grain_choice(
    given: Option<lbdem_kernels::fluid::collide::SolidOperator>,
    tau: f64,
    grains: FreeGrains,
    warnings: &mut crate::units::Warnings,
) -> (
    crate::units::CollisionName,
    lbdem_kernels::fluid::collide::SolidOperator,
) {
    use crate::units::CollisionName;
    use lbdem_kernels::fluid::collide::SolidOperator as Op;
    match given {
        Some(Op::LambdaConsistent) => (CollisionName::Trt, Op::LambdaConsistent),
        Some(op) => (CollisionName::Bgk, op),
        None => free_grain_defaults(tau, grains, warnings),
    }
}

/// The fluid of a kind with free grains, checked in one place: the collision the scene asks for
/// (`[fluid] collision`, else the kind's default `choice.0`) in both precisions at `tau`, and the solid operator
/// `choice.1` against the scene's `grains` ([`check_free_grain_operator`], `field` naming the scene's
/// operator key). Kinds call it once, from their set-up.
pub fn check_free_grain_fluid(
    field: &str,
    fluid: &crate::units::FluidSection,
    choice: (
        crate::units::CollisionName,
        lbdem_kernels::fluid::collide::SolidOperator,
    ),
    tau: f64,
    grains: FreeGrains,
    warnings: &mut crate::units::Warnings,
) -> Result<()> {
    fluid.checked_collision(choice.0, tau)?;
    fluid.lambda_terms(choice.1)?;
    check_free_grain_operator(field, choice.1, tau, grains, warnings)
}

/// Check the PSM solid operator `op` (read from `field`) of a scene whose grains move freely under the fluid's
/// force, at relaxation time `tau`, for the scene's free `grains` (lone or packed; the lightest grain's density
/// over the fluid's).
///
/// Refused (the moving-solid table of issue 11, README "Moving solids, every operator"): Ω₃ (moving-wall
/// bounce-back; at full cover it reverses the fluid's velocity relative to the grain and the coupled mode grows
/// by 1 + 2 m_fluid/m_grain per step: divergence within ~100 steps), Ω₂ (superposition: fluid seeps through
/// moving solids, effective surface 0.15–1.4 spacings off and a free disc's drag −3 % to −21 %), and ΩΛ with
/// a τ where it was measured to diverge with such grains ([`LAMBDA_FREE_GRAIN_STABILITY`] for lone grains,
/// [`LAMBDA_PACKED_GRAIN_STABILITY`] for packs; warned between the last τ measured stable and the first
/// measured to diverge, and for grains lighter than the fluid). Ω₁ and
/// Ω₁ₗ pass (τ-dependent drag; see README).
pub fn check_free_grain_operator(
    field: &str,
    op: lbdem_kernels::fluid::collide::SolidOperator,
    tau: f64,
    grains: FreeGrains,
    warnings: &mut crate::units::Warnings,
) -> Result<()> {
    use lbdem_kernels::fluid::collide::SolidOperator as Op;
    let fix = "use solid_operator = \"lambda_consistent\" (Omega_Lambda, the default: stable with free rock grains to tau = 2, \
               drag independent of tau with collision = \"trt\"), or \"linearized_non_equilibrium_bounce_back\" \
               (Omega_1l)";
    match op {
        Op::MovingWallBounceBack => Err(LbdemError::field(
            field,
            op.name(),
            "Omega_3 is unstable for free grains: at full cover it reverses the velocity of the fluid inside a \
             grain relative to the grain, and with the grain's reaction that mode grows by 1 + 2 m_fluid/m_grain \
             per step (divergence within ~100 steps)",
            fix,
        )),
        Op::Superposition => Err(LbdemError::field(
            field,
            op.name(),
            "Omega_2 lets fluid seep through moving solids: the effective surface of a sliding slab is 0.15-1.4 \
             spacings off and a free grain's drag is 3-21 % low, growing with tau",
            fix,
        )),
        Op::LambdaConsistent => {
            let (_, stable, diverged) = grains.lambda_row();
            let density_ratio = grains.density_ratio;
            let measured = grains.lambda_measured();
            if tau >= diverged {
                return Err(LbdemError::field(
                    field,
                    op.name(),
                    &format!(
                        "Omega_Lambda with free grains {density_ratio:.3} times as dense as the fluid diverges at \
                         tau = {tau:.4} ({measured})"
                    ),
                    &format!(
                        "lower fluid.tau to {stable} or below (a smaller time step), or use solid_operator = \
                         \"linearized_non_equilibrium_bounce_back\" (Omega_1l)"
                    ),
                ));
            }
            if tau > stable || density_ratio < 1.0 {
                warnings.push(format!(
                    "{field} = \"lambda_consistent\" with free grains {density_ratio:.3} times as dense as the \
                     fluid at tau = {tau:.4}: outside the region measured stable, expect divergence ({measured}); \
                     lower tau to {stable} if the run diverges"
                ));
            }
            Ok(())
        }
        _ => Ok(()),
    }
}
