//! The `kind = "dry"` scene: a bonded sample packed by the ch. 2 procedure and loaded between platens
//! (uniaxial or servo-confined biaxial compression at a constant platen speed; or, with
//! `test = "boundary_stress"`, the ch. 6.6 fracture test's dry control: axial stress through the top boundary
//! particles, lateral stress by servo platens), with no fluid (no lattice is allocated). Outputs: `stress_strain.csv`, `broken_bonds.csv`, `particles_NNNN.vtk` (legacy VTK), and
//! `summary.json` (written last).
//!
//! ```toml
//! [scene]
//! kind = "dry"
//! units = "cgs"            # every value below in cm, g, s, dyne (2-D: stresses in dyne/cm per unit thickness)
//! [packing]
//! width = 2.0              # box, cm
//! height = 4.0
//! radius_min = 0.07        # semi-major axes, cm (dissertation ch. 6.6)
//! radius_max = 0.11
//! aspect_ratio = 1.0       # b/a; 0.5 for the ch. 6.6 ellipses
//! solid_fraction = 0.82    # sets the particle count
//! density = 2.65           # g/cm^3 (unit thickness)
//! seed = 1
//! isotropic_stress = 50.0  # installed before bonding
//! [solid]
//! normal_stiffness = 1e5   # dyne/cm (table 6.1)
//! shear_stiffness = 1e5
//! friction = 0.5
//! local_damping = 0.7
//! timestep = 5e-5          # s; refused above 0.8 x the critical step
//! [solid.bonds]
//! kind = "parallel"        # or "point" with stiffness (dyne/cm) and strength (dyne)
//! radius_multiplier = 1.0
//! normal_stiffness = 2.8e5 # dyne/cm^3
//! shear_stiffness = 2.8e5
//! tensile_strength = 500.0 # dyne/cm^2
//! shear_strength = 500.0
//! [loading]
//! confining_stress = 0.0   # 0: uniaxial (lateral platens removed)
//! platen_speed = 0.02      # cm/s, each axial platen
//! max_strain = 0.05
//! ```
use std::path::Path;

use lbdem_kernels::dem::assembly::ContactModel;
use lbdem_kernels::Real;
use serde::{Deserialize, Serialize};

use super::packing::{hexagonal_packing, PackingSpec};
use super::world::{BondSpec, DemWorld, CRITICAL_STEP_SAFETY};
use crate::error::{LbdemError, Result};
use crate::longrun::LongRunSection;
use crate::scene::{positive, SceneHeader, SceneKind};

mod resumable;
pub use resumable::{resume_dry, DryRunOptions, DryState, DryTask, Stage, DRY_KIND};

/// `[packing]`: the box, the size distribution and the isotropic stress (see [`PackingSpec`]).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PackingSection {
    /// Box width (x).
    pub width: f64,
    /// Box height (y).
    pub height: f64,
    /// Smallest semi-major axis.
    pub radius_min: f64,
    /// Largest semi-major axis.
    pub radius_max: f64,
    /// b/a in (0, 1] (default 1: discs).
    #[serde(default = "one")]
    pub aspect_ratio: f64,
    /// Target solid fraction (default 0.82).
    #[serde(default = "default_solid_fraction")]
    pub solid_fraction: f64,
    /// Grain density (mass per volume; unit thickness).
    pub density: f64,
    /// RNG seed.
    pub seed: u64,
    /// Isotropic stress installed before bonding.
    pub isotropic_stress: f64,
    /// Relative tolerance on the wall stresses (default 0.2).
    #[serde(default = "default_stress_tolerance")]
    pub stress_tolerance: f64,
    /// Steps of the size growth (default 2000).
    #[serde(default = "default_growth_steps")]
    pub growth_steps: u64,
    /// Step limit of the stress installation (default 40000).
    #[serde(default = "default_adjust_steps")]
    pub max_adjust_steps: u64,
}

fn one() -> f64 {
    1.0
}
fn default_solid_fraction() -> f64 {
    0.82
}
fn default_stress_tolerance() -> f64 {
    0.2
}
fn default_growth_steps() -> u64 {
    2000
}
fn default_adjust_steps() -> u64 {
    40_000
}
fn default_damping() -> f64 {
    lbdem_kernels::dem::law::DEFAULT_LOCAL_DAMPING
}
fn default_bond_gap() -> f64 {
    1e-3
}
fn default_settle() -> u64 {
    1000
}
fn default_post_peak() -> f64 {
    0.7
}
fn default_record() -> u64 {
    50
}

/// `[solid.bonds]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum BondsSection {
    /// Point bonds (eq. 6.13).
    Point {
        /// k_b (force/length).
        stiffness: f64,
        /// F_crit (force).
        strength: f64,
        /// Bond pairs closer than this (default 1e-3).
        #[serde(default = "default_bond_gap")]
        gap: f64,
    },
    /// Parallel bonds (Potyondy & Cundall 2004).
    Parallel {
        /// λ̄ (default 1).
        #[serde(default = "one")]
        radius_multiplier: f64,
        /// k̄_n (stress/length).
        normal_stiffness: f64,
        /// k̄_s (stress/length).
        shear_stiffness: f64,
        /// σ̄_c (stress).
        tensile_strength: f64,
        /// τ̄_c (stress).
        shear_strength: f64,
        /// Bond pairs closer than this (default 1e-3).
        #[serde(default = "default_bond_gap")]
        gap: f64,
    },
}

/// `[solid]`: contact material, damping, time step, bonds.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SolidSection {
    /// k_n (force/length).
    pub normal_stiffness: f64,
    /// k_s (force/length).
    pub shear_stiffness: f64,
    /// μ.
    pub friction: f64,
    /// PFC local damping α (default 0.7).
    #[serde(default = "default_damping")]
    pub local_damping: f64,
    /// DEM time step.
    pub timestep: f64,
    /// Bonds (none: a cohesionless sample).
    #[serde(default)]
    pub bonds: Option<BondsSection>,
}

/// Which loading a dry scene runs.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum LoadingKind {
    /// Uniaxial or biaxial compression between platens at a constant speed.
    #[default]
    Compression,
    /// The fracture test's dry control (ch. 6.6): lateral stress by servo platens, axial stress through the
    /// top boundary particles, for a number of steps.
    BoundaryStress,
}

/// `[loading]`: the test.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LoadingSection {
    /// Which test (default "compression").
    #[serde(default)]
    pub test: LoadingKind,
    /// Confining stress (compression; 0: uniaxial).
    #[serde(default)]
    pub confining_stress: f64,
    /// Speed of each axial platen (compression).
    #[serde(default)]
    pub platen_speed: f64,
    /// Steps before loading (compression; default 1000).
    #[serde(default = "default_settle")]
    pub settle_steps: u64,
    /// Stop at this axial strain (compression).
    #[serde(default)]
    pub max_strain: f64,
    /// Axial stress through the top boundary particles (boundary_stress).
    #[serde(default)]
    pub axial_stress: f64,
    /// Lateral stress held by the servo platens (boundary_stress).
    #[serde(default)]
    pub lateral_stress: f64,
    /// Steps to run (boundary_stress).
    #[serde(default)]
    pub steps: u64,
    /// Stop when the deviator falls to this fraction of its peak (default 0.7).
    #[serde(default = "default_post_peak")]
    pub post_peak_fraction: f64,
    /// Steps between stress–strain records (default 50).
    #[serde(default = "default_record")]
    pub record_interval: u64,
    /// Records between VTK snapshots (0: only the first and last).
    #[serde(default)]
    pub vtk_interval: u64,
}

/// A whole dry scene file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DryScene {
    /// `[scene]` (kind = "dry").
    pub scene: SceneHeader,
    /// `[packing]`.
    pub packing: PackingSection,
    /// `[solid]`.
    pub solid: SolidSection,
    /// `[loading]`.
    pub loading: LoadingSection,
    /// `[run]` (optional): `checkpoint_interval` of the long-run driver.
    #[serde(default)]
    pub run: LongRunSection,
}

/// `lbdem check` of a dry scene file.
pub fn check_file(path: &Path) -> Result<String> {
    let p = path.display().to_string();
    let text = crate::scene::read_scene_text(path)?;
    DryScene::from_toml(&text, &p)?.check(path)
}

/// `lbdem run` of a dry scene file.
pub fn run_file(path: &Path, out: &Path, overwrite: bool) -> Result<serde_json::Value> {
    let p = path.display().to_string();
    let text = crate::scene::read_scene_text(path)?;
    DryScene::from_toml(&text, &p)?.run(path, out, overwrite)
}

fn non_negative(field: &str, v: f64, hint: &str) -> Result<()> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(LbdemError::field(
            field,
            v,
            "must be a finite number >= 0",
            hint,
        ))
    }
}

/// Range checks of `[packing]` and `[solid]`, naming the field (shared by every scene that packs grains).
pub(crate) fn validate_packing_and_solid(p: &PackingSection, s: &SolidSection) -> Result<()> {
    positive("packing.width", p.width, "box width along x")?;
    positive("packing.height", p.height, "box height along y")?;
    positive("packing.radius_min", p.radius_min, "e.g. 0.07 cm")?;
    positive("packing.radius_max", p.radius_max, "e.g. 0.11 cm")?;
    positive("packing.density", p.density, "e.g. 2.65 g/cm^3")?;
    positive("packing.isotropic_stress", p.isotropic_stress, "e.g. 50")?;
    positive("packing.stress_tolerance", p.stress_tolerance, "e.g. 0.2")?;
    positive(
        "solid.normal_stiffness",
        s.normal_stiffness,
        "e.g. 1e5 dyne/cm (table 6.1)",
    )?;
    positive(
        "solid.shear_stiffness",
        s.shear_stiffness,
        "e.g. 1e5 dyne/cm",
    )?;
    non_negative("solid.friction", s.friction, "e.g. 0.5 (table 6.1)")?;
    if !(s.local_damping >= 0.0 && s.local_damping < 1.0) {
        return Err(LbdemError::field(
            "solid.local_damping",
            s.local_damping,
            "must be in [0, 1)",
            "PFC and the dissertation use 0.7",
        ));
    }
    positive(
        "solid.timestep",
        s.timestep,
        "run `lbdem check` for the critical step",
    )?;
    match s.bonds {
        Some(BondsSection::Point {
            stiffness,
            strength,
            gap,
        }) => {
            positive(
                "solid.bonds.stiffness",
                stiffness,
                "e.g. 1e5 dyne/cm (table 6.1)",
            )?;
            positive(
                "solid.bonds.strength",
                strength,
                "e.g. 700 dyne (table 6.1)",
            )?;
            non_negative("solid.bonds.gap", gap, "e.g. 1e-3 cm")?;
        }
        Some(BondsSection::Parallel {
            radius_multiplier,
            normal_stiffness,
            shear_stiffness,
            tensile_strength,
            shear_strength,
            gap,
        }) => {
            positive(
                "solid.bonds.radius_multiplier",
                radius_multiplier,
                "usually 1",
            )?;
            positive(
                "solid.bonds.normal_stiffness",
                normal_stiffness,
                "k̄_n = Ē_c/(R_A + R_B)",
            )?;
            positive(
                "solid.bonds.shear_stiffness",
                shear_stiffness,
                "k̄_s = k̄_n/(k̄_n/k̄_s)",
            )?;
            positive("solid.bonds.tensile_strength", tensile_strength, "σ̄_c")?;
            positive("solid.bonds.shear_strength", shear_strength, "τ̄_c")?;
            non_negative("solid.bonds.gap", gap, "e.g. 1e-3 cm")?;
        }
        None => {}
    }
    let spec = packing_spec::<f64>(p, s);
    super::packing::check_packing_spec(&spec)
}

/// The packing procedure's parameters from `[packing]` and `[solid]`.
pub(crate) fn packing_spec<T: Real>(p: &PackingSection, s: &SolidSection) -> PackingSpec<T> {
    PackingSpec {
        width: T::lit(p.width),
        height: T::lit(p.height),
        radius_min: T::lit(p.radius_min),
        radius_max: T::lit(p.radius_max),
        aspect_ratio: T::lit(p.aspect_ratio),
        solid_fraction: T::lit(p.solid_fraction),
        density: T::lit(p.density),
        seed: p.seed,
        contact: ContactModel {
            normal_stiffness: T::lit(s.normal_stiffness),
            shear_stiffness: T::lit(s.shear_stiffness),
            friction: T::lit(s.friction),
            restitution: T::one(),
            no_tension: true,
        },
        timestep: T::lit(s.timestep),
        growth_steps: p.growth_steps,
        isotropic_stress: T::lit(p.isotropic_stress),
        stress_tolerance: T::lit(p.stress_tolerance),
        max_servo_steps: p.max_adjust_steps,
        bond_gap: T::lit(bond_gap(s)),
    }
}

/// The bonding gap of `[solid.bonds]` (0 without bonds).
pub(crate) fn bond_gap(s: &SolidSection) -> f64 {
    match s.bonds {
        Some(BondsSection::Point { gap, .. }) | Some(BondsSection::Parallel { gap, .. }) => gap,
        None => 0.0,
    }
}

/// The bond law of `[solid.bonds]`.
pub(crate) fn bond_spec<T: Real>(s: &SolidSection) -> Option<BondSpec<T>> {
    match s.bonds {
        Some(BondsSection::Point {
            stiffness,
            strength,
            ..
        }) => Some(BondSpec::Point {
            stiffness: T::lit(stiffness),
            strength: T::lit(strength),
        }),
        Some(BondsSection::Parallel {
            radius_multiplier,
            normal_stiffness,
            shear_stiffness,
            tensile_strength,
            shear_strength,
            ..
        }) => Some(BondSpec::Parallel {
            radius_multiplier: T::lit(radius_multiplier),
            normal_stiffness: T::lit(normal_stiffness),
            shear_stiffness: T::lit(shear_stiffness),
            tensile_strength: T::lit(tensile_strength),
            shear_strength: T::lit(shear_strength),
        }),
        None => None,
    }
}

/// A-priori critical step: a hexagonal block of the smallest particles, fully bonded (six contacts and
/// six bonds in its interior), through [`DemWorld::critical_time_step`].
pub(crate) fn critical_time_step(p: &PackingSection, s: &SolidSection) -> f64 {
    let particles = hexagonal_packing(3, 3, p.radius_min, p.aspect_ratio, 0.0, p.density, 0);
    let spec = packing_spec::<f64>(p, s);
    let Ok(mut world) = DemWorld::new(particles, spec.contact, f64::MIN_POSITIVE) else {
        return f64::NAN;
    };
    if let Some(b) = bond_spec::<f64>(s) {
        if world.bond_touching_pairs(b, 1e-9 * p.radius_min).is_err() {
            return f64::NAN;
        }
    }
    world.critical_time_step()
}

impl DryScene {
    /// Parse `path` as a dry scene when its `[scene] kind` is "dry"; `None` for any other kind (and for files
    /// whose header does not parse: the caller's own parser reports those).
    pub fn load_if_dry(path: &Path) -> Result<Option<Self>> {
        let p = path.display().to_string();
        let text = crate::scene::read_scene_text(path)?;
        match crate::scene::peek_kind::<SceneKind>(&text) {
            Some(SceneKind::Dry) => Self::from_toml(&text, &p).map(Some),
            _ => Ok(None),
        }
    }

    /// Parse a dry scene from TOML text and check its ranges (`path` only for messages).
    pub fn from_toml(text: &str, path: &str) -> Result<Self> {
        let s: DryScene = toml::from_str(text).map_err(|e| LbdemError::ParseScene {
            path: path.to_string(),
            message: e.to_string(),
        })?;
        s.validate()?;
        Ok(s)
    }

    /// Range checks naming the field.
    pub fn validate(&self) -> Result<()> {
        validate_packing_and_solid(&self.packing, &self.solid)?;
        let l = &self.loading;
        match l.test {
            LoadingKind::Compression => {
                non_negative(
                    "loading.confining_stress",
                    l.confining_stress,
                    "0 for uniaxial",
                )?;
                positive(
                    "loading.platen_speed",
                    l.platen_speed,
                    "slow: quasi-static (REFERENCE §7.4)",
                )?;
                positive("loading.max_strain", l.max_strain, "e.g. 0.05")?;
            }
            LoadingKind::BoundaryStress => {
                positive(
                    "loading.axial_stress",
                    l.axial_stress,
                    "ch. 6.6: 40 dyne/cm^2",
                )?;
                positive(
                    "loading.lateral_stress",
                    l.lateral_stress,
                    "ch. 6.6: 50 dyne/cm^2",
                )?;
                if l.steps == 0 {
                    return Err(LbdemError::field(
                        "loading.steps",
                        0,
                        "test = \"boundary_stress\" needs a number of steps >= 1",
                        "e.g. 20000",
                    ));
                }
            }
        }
        if !(l.post_peak_fraction > 0.0 && l.post_peak_fraction < 1.0) {
            return Err(LbdemError::field(
                "loading.post_peak_fraction",
                l.post_peak_fraction,
                "must be in (0, 1)",
                "e.g. 0.7",
            ));
        }
        if l.record_interval == 0 {
            return Err(LbdemError::field(
                "loading.record_interval",
                0,
                "must be at least 1",
                "e.g. 50",
            ));
        }
        // The packing spec re-checks sizes, aspect ratio and solid fraction with field names.
        let spec = self.packing_spec::<f64>();
        super::packing::check_packing_spec(&spec)?;
        Ok(())
    }

    fn packing_spec<T: Real>(&self) -> PackingSpec<T> {
        packing_spec(&self.packing, &self.solid)
    }

    fn bond_spec<T: Real>(&self) -> Option<BondSpec<T>> {
        bond_spec(&self.solid)
    }

    /// A-priori critical step (see [`critical_time_step`]).
    pub fn critical_time_step(&self) -> f64 {
        critical_time_step(&self.packing, &self.solid)
    }

    /// `lbdem check`: validate and describe, refusing a step above the critical one.
    pub fn check(&self, path: &Path) -> Result<String> {
        let critical = self.critical_time_step();
        self.check_timestep(critical)?;
        let mut s = format!("scene {} is valid (kind = dry)\n", path.display());
        s += &self.describe(critical);
        Ok(s)
    }

    fn check_timestep(&self, critical: f64) -> Result<()> {
        let dt = self.solid.timestep;
        if dt > CRITICAL_STEP_SAFETY * critical {
            return Err(LbdemError::field(
                "solid.timestep",
                format!("{dt:e}"),
                &format!(
                    "exceeds {CRITICAL_STEP_SAFETY} x the DEM critical step {critical:e} (smallest particle, six contacts and six bonds)"
                ),
                &format!("use solid.timestep <= {:e}", CRITICAL_STEP_SAFETY * critical),
            ));
        }
        Ok(())
    }

    fn describe(&self, critical: f64) -> String {
        let labels = self.scene.units.labels();
        let p = &self.packing;
        let mean_area = std::f64::consts::PI
            * p.aspect_ratio
            * (p.radius_min * p.radius_min
                + p.radius_min * p.radius_max
                + p.radius_max * p.radius_max)
            / 3.0;
        format!(
            "  packing: {} x {} {len} box, about {:.0} particles (solid fraction {}), seed {}, isotropic stress {} {pr}\n  DEM critical step {critical:.4e} {t} (x{CRITICAL_STEP_SAFETY} = {:.4e}); chosen step {:.4e} {t} ({:.2} of critical)\n  loading: {} at platen speed {} {v} each, up to axial strain {}\n",
            p.width,
            p.height,
            p.solid_fraction * p.width * p.height / mean_area,
            p.solid_fraction,
            p.seed,
            p.isotropic_stress,
            CRITICAL_STEP_SAFETY * critical,
            self.solid.timestep,
            self.solid.timestep / critical,
            match (self.loading.test, self.loading.confining_stress > 0.0) {
                (LoadingKind::BoundaryStress, _) => format!(
                    "boundary stress (fracture-test dry control): axial {} through the top particles, lateral {} by servo platens, {} steps;",
                    self.loading.axial_stress, self.loading.lateral_stress, self.loading.steps
                ),
                (_, true) => format!(
                    "biaxial compression, confining stress {}",
                    self.loading.confining_stress
                ),
                _ => "uniaxial compression".to_string(),
            },
            self.loading.platen_speed,
            self.loading.max_strain,
            len = labels.length,
            pr = labels.pressure,
            t = labels.time,
            v = labels.velocity,
        )
    }

    /// `lbdem run`: pack, bond, load, write the outputs into `out`. Returns the summary. Runs through the
    /// long-run driver ([`DryScene::run_resumable`]): checkpoints in `out`, Ctrl-C, `lbdem resume`.
    pub fn run(&self, path: &Path, out: &Path, overwrite: bool) -> Result<serde_json::Value> {
        self.run_resumable(
            path,
            out,
            &DryRunOptions {
                overwrite,
                quiet: true,
                stop_after: None,
            },
        )
    }
}
