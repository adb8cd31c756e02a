//! `[packing]` and `[solid]`: the grains, their packing procedure (dissertation ch. 2), contact material and bonds,
//! shared by the kinds that pack a bonded sample (`dry`, `fracture`).
use lbdem_kernels::Real;
use serde::{Deserialize, Serialize};

use crate::engine::dem::elastic_contact;
use crate::engine::dem::packing::check_aspect_ratio;
use crate::engine::dem::packing::{hexagonal_packing, PackingSpec};
use crate::engine::dem::world::{BondSpec, DemWorld};
use crate::error::{non_negative, positive, LbdemError, Result};
use crate::input::limits;

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

/// An upper bound on the grains of a packing (box area × solid fraction over the area of the smallest grain),
/// computed before packing and refused above [`limits::MAX_GRAINS`] naming `packing.width`.
pub fn grain_count(p: &PackingSection) -> Result<u64> {
    let grain =
        std::f64::consts::PI * p.radius_min * p.radius_min * p.aspect_ratio.clamp(1e-3, 1.0);
    let n = limits::count_up(
        "packing.width",
        "the grain count",
        p.width * p.height * p.solid_fraction.clamp(0.0, 1.0) / grain,
    )?;
    limits::grains("packing.width", n)
}

/// The memory budget of a packing: its grains ([`grain_count`]), named `packing.width`.
pub fn packing_budget(p: &PackingSection) -> Result<limits::Budget> {
    let mut b = limits::Budget::new();
    b.add_items(
        "grains",
        "packing.width",
        grain_count(p)?,
        limits::GRAIN_BYTES,
    )?;
    Ok(b)
}

/// Range checks of `[packing]` and `[solid]`, naming the field (shared by every scene that packs grains).
pub fn validate_packing_and_solid(p: &PackingSection, s: &SolidSection) -> Result<()> {
    positive("packing.width", p.width, "box width along x")?;
    positive("packing.height", p.height, "box height along y")?;
    positive("packing.radius_min", p.radius_min, "e.g. 0.07 cm")?;
    check_aspect_ratio("packing.aspect_ratio", p.aspect_ratio)?;
    grain_count(p)?;
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
    // The bonding gap is a tolerance for touching grains: the a-priori critical step counts six bonds per
    // grain and the memory estimate a few, but a gap of a grain size bonds grains across their neighbours (up
    // to every pair: the packing then refuses its DEM step, or runs out of memory). A tenth of the smallest
    // radius still joins only neighbours.
    let gap = bond_gap(s);
    if s.bonds.is_some() && gap >= 0.1 * p.radius_min {
        return Err(LbdemError::field(
            "solid.bonds.gap",
            gap,
            &format!(
                "must be below a tenth of packing.radius_min ({:e}): bonds join touching neighbours only",
                0.1 * p.radius_min
            ),
            "e.g. 1e-3 cm for the dissertation's grains (radius 0.07-0.11 cm)",
        ));
    }
    let spec = packing_spec::<f64>(p, s);
    crate::engine::dem::packing::check_packing_spec(&spec)
}

/// The packing procedure's parameters from `[packing]` and `[solid]`.
pub fn packing_spec<T: Real>(p: &PackingSection, s: &SolidSection) -> PackingSpec<T> {
    PackingSpec {
        width: T::lit(p.width),
        height: T::lit(p.height),
        radius_min: T::lit(p.radius_min),
        radius_max: T::lit(p.radius_max),
        aspect_ratio: T::lit(p.aspect_ratio),
        solid_fraction: T::lit(p.solid_fraction),
        density: T::lit(p.density),
        seed: p.seed,
        contact: elastic_contact(
            T::lit(s.normal_stiffness),
            T::lit(s.shear_stiffness),
            T::lit(s.friction),
        ),
        timestep: T::lit(s.timestep),
        growth_steps: p.growth_steps,
        isotropic_stress: T::lit(p.isotropic_stress),
        stress_tolerance: T::lit(p.stress_tolerance),
        max_servo_steps: p.max_adjust_steps,
        bond_gap: T::lit(bond_gap(s)),
    }
}

/// The bonding gap of `[solid.bonds]` (0 without bonds).
pub fn bond_gap(s: &SolidSection) -> f64 {
    match s.bonds {
        Some(BondsSection::Point { gap, .. }) | Some(BondsSection::Parallel { gap, .. }) => gap,
        None => 0.0,
    }
}

/// The bond law of `[solid.bonds]`.
pub fn bond_spec<T: Real>(s: &SolidSection) -> Option<BondSpec<T>> {
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
pub fn critical_time_step(p: &PackingSection, s: &SolidSection) -> f64 {
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
