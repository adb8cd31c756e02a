//! Physical ⇄ lattice units: the one place where lattice quantities are derived.
//!
//! From the lattice spacing h, the kinematic viscosity ν and either the relaxation time τ or the time step Δt
//! (dissertation eq. 4.9 / 4.15):
//!
//! * τ = ½ + 3 ν Δt / h²  ⇔  Δt = (τ − ½) h² / (3 ν); lattice viscosity ν* = (τ − ½)/3 = ν Δt/h²
//! * lattice speed c = h/Δt (eq. 4.11), sound speed c_s = c/√3, fluid compressibility β = 1/(ρ₀ c_s²) (eq. 4.19)
//! * pressure p = c_s² ρ (eq. 4.3): a physical pressure p is p / (ρ₀ c²) in lattice units, i.e. a density
//!   change Δρ* = 3 p/(ρ₀ c²) of the lattice density (reference 1)
//! * velocity u* = u/c; acceleration g* = g Δt²/h; body-force density F* = ρ* g*
//! * forces on grains (2-D, per unit thickness): F = F* · ρ₀ h³/Δt²; torques T = T* · ρ₀ h⁴/Δt²
//!
//! The dissertation's parameter tables are not all self-consistent (e.g. table 6.2: h = 0.009 cm,
//! Δt = 1e−5 s, ν = 0.2 cm²/s give τ = 0.574, not the 0.625 listed). lbdem therefore takes h, ν and one of τ
//! or Δt, derives the other, and prints every derived figure at start-up.
use serde::{Deserialize, Serialize};

use lbdem_kernels::fluid::collide::{Collision, CollisionError, LambdaTerms, SolidOperator, Trt};
use lbdem_kernels::Real;

use crate::error::{positive, LbdemError, Result};

/// Unit system of a scene. All inputs of one scene are in the same system; formulas are unit-consistent, so
/// the choice only sets the labels of the outputs.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum UnitSystem {
    /// centimetre, gram, second (dyne, dyne/cm²) — the dissertation's units.
    Cgs,
    /// metre, kilogram, second (N, Pa).
    Si,
}

impl UnitSystem {
    /// Label of length, density, pressure, velocity units.
    pub fn labels(self) -> UnitLabels {
        match self {
            UnitSystem::Cgs => UnitLabels {
                length: "cm",
                time: "s",
                density: "g/cm^3",
                pressure: "dyne/cm^2",
                velocity: "cm/s",
                viscosity: "cm^2/s",
            },
            UnitSystem::Si => UnitLabels {
                length: "m",
                time: "s",
                density: "kg/m^3",
                pressure: "Pa",
                velocity: "m/s",
                viscosity: "m^2/s",
            },
        }
    }
}

/// Unit labels for printing.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct UnitLabels {
    /// Length unit.
    pub length: &'static str,
    /// Time unit.
    pub time: &'static str,
    /// Density unit.
    pub density: &'static str,
    /// Pressure unit.
    pub pressure: &'static str,
    /// Velocity unit.
    pub velocity: &'static str,
    /// Kinematic viscosity unit.
    pub viscosity: &'static str,
}

impl UnitLabels {
    /// Lattice units (spacing h, step dt, reference density rho0), for a scene simulated and written in them
    /// (`coupled_demo`).
    pub const LATTICE: UnitLabels = UnitLabels {
        length: "h",
        time: "dt",
        density: "rho0",
        pressure: "rho0*h^2/dt^2",
        velocity: "h/dt",
        viscosity: "h^2/dt",
    };
}

/// `[fluid]`: physical fluid properties and the lattice resolution.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FluidSection {
    /// Reference density ρ₀.
    pub density: f64,
    /// Kinematic viscosity ν.
    pub viscosity: f64,
    /// Lattice spacing h.
    pub spacing: f64,
    /// Relaxation time τ (dimensionless). Give this or `timestep`.
    #[serde(default)]
    pub tau: Option<f64>,
    /// Time step Δt. Give this or `tau`.
    #[serde(default)]
    pub timestep: Option<f64>,
    /// Fluid collision: `"bgk"` or `"trt"` (Ginzburg's two relaxation times). Absent: the scene kind's
    /// default ([`FluidSection::collision`]).
    #[serde(default)]
    pub collision: Option<CollisionName>,
    /// TRT's magic parameter Λ = (τ⁺ − ½)(τ⁻ − ½) (default 3/16: half-way walls exactly half-way at every τ).
    /// Only with `collision = "trt"` (or a kind whose default is TRT).
    #[serde(default)]
    pub magic: Option<f64>,
    /// ΩΛ's form: `"wall_pressure"` (the default) or `"friction_only"` ([`LambdaForm`]). Only with the solid
    /// operator `"lambda_consistent"` (ΩΛ); refused with any other.
    #[serde(default)]
    pub lambda_form: Option<LambdaForm>,
}

/// The form of ΩΛ (`SolidOperator::LambdaConsistent`) a scene asks for (`[fluid] lambda_form`): which of ΩΛ's
/// terms act at partly covered nodes ([`LambdaTerms`]).
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum LambdaForm {
    /// Friction κ = 0.5 plus the wall-pressure force along each solid's surface
    /// ([`LambdaTerms::WALL_PRESSURE`]): the default, the square arrays within 1 % of Sangani & Acrivos at
    /// l = 40 nodes and every τ.
    #[default]
    WallPressure,
    /// Friction κ = 1.21 alone ([`LambdaTerms::FRICTION_ONLY`]): ΩΛ's first form, the default until
    /// 2026-12-07; unstable in dense packs of partly covered throats (README, "ΩΛ's wall-pressure form").
    FrictionOnly,
}

impl LambdaForm {
    /// The constants of this form.
    pub fn terms(self) -> LambdaTerms {
        match self {
            LambdaForm::WallPressure => LambdaTerms::WALL_PRESSURE,
            LambdaForm::FrictionOnly => LambdaTerms::FRICTION_ONLY,
        }
    }

    /// The scene word of this form.
    pub fn name(self) -> &'static str {
        match self {
            LambdaForm::WallPressure => "wall_pressure",
            LambdaForm::FrictionOnly => "friction_only",
        }
    }
}

/// The solid operator `op` by its scene word, with ΩΛ's form and constants from `fluid` (e.g.
/// `lambda_consistent (wall_pressure: kappa 0.5, alpha 2)`), for the set-up a run prints. Refuses a form given
/// with another operator, as [`FluidSection::lambda_terms`].
pub fn describe_operator(op: SolidOperator, fluid: &FluidSection) -> Result<String> {
    let terms = fluid.lambda_terms(op)?;
    if op != SolidOperator::LambdaConsistent {
        return Ok(op.name().to_string());
    }
    let form = fluid.lambda_form.unwrap_or_default();
    Ok(format!(
        "{} ({}: kappa {}, alpha {})",
        op.name(),
        form.name(),
        terms.friction,
        terms.pressure
    ))
}

/// The fluid collision a scene asks for (`[fluid] collision`); its parameter is `[fluid] magic`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum CollisionName {
    /// Bhatnagar–Gross–Krook, one relaxation time (steady results move with τ).
    Bgk,
    /// Two relaxation times at fixed Λ (steady results independent of τ).
    Trt,
}

impl FluidSection {
    /// Range checks of `[fluid]` that do not need derived quantities (those are in [`LatticeUnits::from_fluid`]).
    pub fn validate(&self) -> Result<()> {
        positive(
            "fluid.density",
            self.density,
            "give the fluid density, e.g. 1.0 g/cm^3 for water in cgs",
        )?;
        positive(
            "fluid.viscosity",
            self.viscosity,
            "give the kinematic viscosity, e.g. 0.01 cm^2/s for water",
        )?;
        positive(
            "fluid.spacing",
            self.spacing,
            "give the lattice spacing h in length units",
        )?;
        match (self.tau, self.timestep) {
            (Some(_), Some(_)) => Err(LbdemError::field(
                "fluid.tau",
                "given together with fluid.timestep",
                "tau and timestep are tied by tau = 1/2 + 3 nu dt / h^2, so only one may be given",
                "remove one of fluid.tau or fluid.timestep",
            )),
            (None, None) => Err(LbdemError::field(
                "fluid.tau",
                "missing",
                "neither fluid.tau nor fluid.timestep is given",
                "add fluid.tau (e.g. 0.875) or fluid.timestep",
            )),
            (Some(t), None) if !(t.is_finite() && t > 0.5) => Err(LbdemError::field(
                "fluid.tau",
                t,
                "BGK is unstable for tau <= 1/2 (the viscosity (tau - 1/2)/3 would be <= 0)",
                "use tau in (0.5, 2], ideally 0.6-1.0",
            )),
            (None, Some(dt)) => positive("fluid.timestep", dt, "give the time step in seconds"),
            _ => Ok(()),
        }?;
        if let Some(m) = self.magic {
            if self.collision == Some(CollisionName::Bgk) {
                return Err(LbdemError::field(
                    "fluid.magic",
                    m,
                    "is given with fluid.collision = \"bgk\", which has one relaxation time and no magic parameter",
                    "remove fluid.magic, or set fluid.collision = \"trt\"",
                ));
            }
            if !(m.is_finite() && m > 0.0) {
                return Err(LbdemError::field(
                    "fluid.magic",
                    m,
                    "TRT's magic parameter Lambda = (tau+ - 1/2)(tau- - 1/2) must be a positive finite number \
                     (Lambda <= 0 puts tau- at or below 1/2: unstable)",
                    "use 0.1875 (3/16, the default: half-way walls exactly half-way at every tau)",
                ));
            }
        }
        Ok(())
    }

    /// The fluid collision of this scene (`default` the kind's), checked at relaxation time `tau` in both
    /// precisions (see [`FluidSection::collision`]); [`collision_of`] converts it to the run's precision.
    pub fn checked_collision(&self, default: CollisionName, tau: f64) -> Result<Collision<f64>> {
        let collision = self.collision::<f64>(default, tau)?;
        self.collision::<f32>(default, tau)?;
        Ok(collision)
    }

    /// The fluid collision of this scene at relaxation time `tau` (τ⁺): `[fluid] collision` if given, else
    /// `default` (the kind's), with `[fluid] magic` (default 3/16) for TRT. Refuses, naming the field, a TRT
    /// whose τ⁻ = ½ + Λ/(τ⁺ − ½) is not finite or not above ½.
    pub fn collision<T: Real>(&self, default: CollisionName, tau: f64) -> Result<Collision<T>> {
        self.validate()?;
        let collision = match self.collision.unwrap_or(default) {
            CollisionName::Bgk => Collision::Bgk,
            CollisionName::Trt => {
                let magic = self.magic.unwrap_or(Trt::<f64>::DEFAULT_MAGIC);
                Collision::Trt(Trt::new(T::lit(magic)).map_err(|_| {
                    LbdemError::field(
                        "fluid.magic",
                        magic,
                        "is not a positive finite number in this precision",
                        "use 0.1875 (3/16)",
                    )
                })?)
            }
        };
        match collision.rates(T::lit(tau)) {
            Ok(_) => Ok(collision),
            Err(CollisionError::Tau) => Err(LbdemError::field(
                "fluid.tau",
                tau,
                "is not above 1/2 in this precision",
                "use tau in (0.5, 2]",
            )),
            Err(_) => {
                let magic = self.magic.unwrap_or(Trt::<f64>::DEFAULT_MAGIC);
                Err(LbdemError::field(
                    "fluid.magic",
                    magic,
                    &format!(
                        "gives tau- = 1/2 + Lambda/(tau - 1/2) = {:e} at tau = {tau}, which must be finite and \
                         above 1/2",
                        0.5 + magic / (tau - 0.5)
                    ),
                    "use magic = 0.1875 (3/16), or a tau farther from 1/2",
                ))
            }
        }
    }

    /// ΩΛ's constants for a run whose solid operator is `op`: those of `[fluid] lambda_form` (default the
    /// wall-pressure form). Refuses, naming `fluid.lambda_form`, a form given with an operator other than ΩΛ
    /// (which has no such terms: the key would be silently ignored).
    pub fn lambda_terms(&self, op: SolidOperator) -> Result<LambdaTerms> {
        match self.lambda_form {
            Some(form) if op != SolidOperator::LambdaConsistent => Err(LbdemError::field(
                "fluid.lambda_form",
                form.name(),
                &format!(
                    "chooses a form of the solid operator \"lambda_consistent\" (OmegaLambda), but this run's \
                     solid operator is \"{}\", which has no such form",
                    op.name()
                ),
                "remove fluid.lambda_form, or set the scene's solid_operator = \"lambda_consistent\"",
            )),
            form => Ok(form.unwrap_or_default().terms()),
        }
    }

    /// Validate and derive the lattice units.
    pub fn lattice_units(&self) -> Result<LatticeUnits> {
        self.validate()?;
        LatticeUnits::from_fluid(self)
    }
}

/// A collision checked by [`FluidSection::checked_collision`] in precision `T` (refused, naming `fluid.magic`,
/// when Λ is not positive and finite in `T`).
pub fn collision_of<T: Real>(collision: Collision<f64>) -> Result<Collision<T>> {
    match collision {
        Collision::Bgk => Ok(Collision::Bgk),
        Collision::Trt(t) => Trt::new(T::lit(t.magic()))
            .map(Collision::Trt)
            .map_err(|_| {
                LbdemError::field(
                    "fluid.magic",
                    t.magic(),
                    "is not a positive finite number in this precision",
                    "use 0.1875 (3/16)",
                )
            }),
    }
}

/// Relaxation time below which BGK is close to its stability limit and a warning is printed.
pub const TAU_WARN_LOW: f64 = 0.51;
/// Relaxation time above which half-way bounce-back walls move noticeably (slip ∝ τ²) and a warning is printed.
pub const TAU_WARN_HIGH: f64 = 2.0;
/// Relaxation time above which a scene is refused: the half-way bounce-back wall moves by a distance that
/// grows as τ² (of the order of the channel width near τ ≈ 10 for a 20-node channel), so results are wrong by
/// orders of magnitude, not merely inaccurate.
pub const TAU_REFUSE_HIGH: f64 = 100.0;
/// Expected Mach number above which compressibility errors (∝ Ma²) exceed about 1 %: warning.
pub const MACH_WARN: f64 = 0.1;
/// Expected Mach number above which a run is refused unless `run.allow_high_mach = true`.
pub const MACH_REFUSE: f64 = 0.35;
/// Relative density variation across the domain above which a warning is printed.
pub const DENSITY_DROP_WARN: f64 = 0.05;
/// Relative density variation across the domain above which a run is refused.
pub const DENSITY_DROP_REFUSE: f64 = 0.2;

/// D2Q9's squared lattice speed of sound c_s² = 1/3 (lattice units, Δx = Δt = 1; Qian, d'Humières & Lallemand
/// 1992): the lattice equation of state p = c_s² ρ and the BGK viscosity ν = c_s²(τ − ½) both rest on it.
pub const CS2: f64 = 1.0 / 3.0;

/// c_s² x in lattice units, computed as x/3 (exactly rounded, unlike `CS2 * x`): a lattice density change →
/// a lattice pressure.
pub fn cs2_times(x: f64) -> f64 {
    x / 3.0
}

/// x / c_s² in lattice units, computed as 3x: a lattice pressure → a lattice density change.
pub fn over_cs2(x: f64) -> f64 {
    3.0 * x
}

/// BGK lattice viscosity ν* = c_s²(τ − ½) of the relaxation time τ.
pub fn lattice_viscosity(tau: f64) -> f64 {
    cs2_times(tau - 0.5)
}

/// The relaxation time τ = ½ + ν*/c_s² of the lattice viscosity ν*.
pub fn tau_of_lattice_viscosity(nu: f64) -> f64 {
    0.5 + over_cs2(nu)
}

/// The conversion between physical and lattice units of one scene.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct LatticeUnits {
    /// Lattice spacing h (physical length).
    pub spacing: f64,
    /// Time step Δt (physical time).
    pub timestep: f64,
    /// Reference density ρ₀ (physical).
    pub density: f64,
    /// Kinematic viscosity ν (physical).
    pub viscosity: f64,
    /// Relaxation time τ.
    pub tau: f64,
    /// Lattice viscosity ν* = (τ − ½)/3.
    pub lattice_viscosity: f64,
    /// Lattice speed c = h/Δt (physical velocity).
    pub lattice_speed: f64,
    /// Speed of sound c_s = c/√3 (physical velocity).
    pub sound_speed: f64,
    /// Fluid compressibility β = 1/(ρ₀ c_s²) (physical 1/pressure).
    pub compressibility: f64,
}

impl LatticeUnits {
    /// Derive the units from the `[fluid]` section (validated ranges are re-checked here).
    pub fn from_fluid(f: &FluidSection) -> Result<Self> {
        let (h, nu) = (f.spacing, f.viscosity);
        let (tau, dt) = match (f.tau, f.timestep) {
            (Some(tau), None) => (tau, (tau - 0.5) * h * h / (3.0 * nu)),
            (None, Some(dt)) => (0.5 + 3.0 * nu * dt / (h * h), dt),
            _ => {
                return Err(LbdemError::field(
                    "fluid.tau",
                    "missing or doubly given",
                    "give exactly one of fluid.tau and fluid.timestep",
                    "e.g. tau = 0.875",
                ))
            }
        };
        if !(tau.is_finite() && tau > 0.5) {
            return Err(LbdemError::field(
                "fluid.timestep",
                dt,
                &format!(
                    "gives tau = 1/2 + 3 nu dt/h^2 = {tau:.6}, and BGK is unstable for tau <= 1/2"
                ),
                "increase the time step or the viscosity, or refine less",
            ));
        }
        if tau > TAU_REFUSE_HIGH {
            let field = if f.tau.is_some() {
                "fluid.tau"
            } else {
                "fluid.timestep"
            };
            return Err(LbdemError::field(
                field,
                f.tau.unwrap_or(dt),
                &format!(
                    "gives tau = {tau:.6e}, above {TAU_REFUSE_HIGH}: the wall slip grows as tau^2 and the \
                     results would be wrong by orders of magnitude"
                ),
                "use tau in (0.5, 2] (shorter fluid.timestep, coarser fluid.spacing, or check fluid.viscosity)",
            ));
        }
        let c = h / dt;
        let cs = c / 3f64.sqrt();
        let compressibility = 1.0 / (f.density * cs * cs);
        // Every derived figure must be a positive finite number: extreme but individually valid inputs
        // (ν = 1e-300, h = 1e300) can overflow or underflow them.
        for (name, value) in [
            ("the time step dt", dt),
            ("the lattice speed c = h/dt", c),
            ("the sound speed c_s", cs),
            ("the fluid compressibility 1/(rho0 c_s^2)", compressibility),
            ("the lattice speed squared c^2", c * c),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(LbdemError::field(
                    "fluid.viscosity",
                    format!("{nu:e} (with fluid.spacing = {h:e}, fluid.density = {:e})", f.density),
                    &format!("gives {name} = {value:e}, which is not a positive finite number"),
                    "check the units and magnitudes of fluid.viscosity, fluid.spacing and fluid.density",
                ));
            }
        }
        Ok(Self {
            spacing: h,
            timestep: dt,
            density: f.density,
            viscosity: nu,
            tau,
            lattice_viscosity: lattice_viscosity(tau),
            lattice_speed: c,
            sound_speed: cs,
            compressibility,
        })
    }

    /// Physical pressure → lattice pressure p* = p/(ρ₀ c²) (lattice density change is 3 p*).
    pub fn pressure_to_lattice(&self, p: f64) -> f64 {
        p / (self.density * self.lattice_speed * self.lattice_speed)
    }

    /// Lattice pressure → physical pressure.
    pub fn pressure_to_physical(&self, p: f64) -> f64 {
        p * self.density * self.lattice_speed * self.lattice_speed
    }

    /// Physical velocity → lattice velocity.
    pub fn velocity_to_lattice(&self, u: f64) -> f64 {
        u / self.lattice_speed
    }

    /// Lattice velocity → physical velocity.
    pub fn velocity_to_physical(&self, u: f64) -> f64 {
        u * self.lattice_speed
    }

    /// Physical acceleration → lattice acceleration g Δt²/h.
    pub fn acceleration_to_lattice(&self, g: f64) -> f64 {
        g * self.timestep * self.timestep / self.spacing
    }

    /// Lattice force (2-D, per unit thickness) → physical force per unit thickness.
    pub fn force_to_physical(&self, f: f64) -> f64 {
        f * self.density * self.spacing.powi(3) / (self.timestep * self.timestep)
    }

    /// Physical length → lattice lengths (nodes): l / h.
    pub fn length_to_lattice(&self, l: f64) -> f64 {
        l / self.spacing
    }

    /// Physical time → lattice steps: t / Δt.
    pub fn time_to_steps(&self, t: f64) -> f64 {
        t / self.timestep
    }

    /// Physical force per unit thickness → lattice force F Δt²/(ρ₀ h³) (inverse of [`Self::force_to_physical`]).
    pub fn force_to_lattice(&self, f: f64) -> f64 {
        f * self.timestep * self.timestep / (self.density * self.spacing.powi(3))
    }

    /// Physical mass per unit thickness → lattice mass m/(ρ₀ h²).
    pub fn mass_to_lattice(&self, m: f64) -> f64 {
        m / (self.density * self.spacing * self.spacing)
    }

    /// Lattice diffusivity (nodes²/step) → physical diffusivity c* h²/Δt.
    pub fn diffusivity_to_physical(&self, c: f64) -> f64 {
        c * self.spacing * self.spacing / self.timestep
    }

    /// Lattice permeability (nodes²) → physical permeability k* h².
    pub fn permeability_to_physical(&self, k: f64) -> f64 {
        k * self.spacing * self.spacing
    }

    /// Physical pressure → lattice density change Δρ* = p/(ρ₀ c_s²) (p = c_s² ρ, eq. 4.3).
    pub fn pressure_to_density_change(&self, p: f64) -> f64 {
        over_cs2(self.pressure_to_lattice(p))
    }

    /// Every derived figure, one per line, for `check`/`run` start-up output.
    pub fn describe(&self, length: &str, time: &str, pressure: &str) -> String {
        format!(
            "  lattice spacing h = {:e} {length}, time step dt = {:e} {time}, tau = {:.6}\n  \
             lattice viscosity nu* = {:.6}, lattice speed c = h/dt = {:e} {length}/{time}, sound speed c_s = {:e} \
             {length}/{time}\n  fluid compressibility beta = 1/(rho0 c_s^2) = {:e} 1/({pressure})\n",
            self.spacing,
            self.timestep,
            self.tau,
            self.lattice_viscosity,
            self.lattice_speed,
            self.sound_speed,
            self.compressibility
        )
    }

    /// One line of the figures a sweep of lattice cases shares: h, Δt, τ and the lattice viscosity.
    pub fn brief(&self) -> String {
        format!(
            "  spacing h {:.6e}, time step {:.6e}, tau {:.6}, lattice viscosity {:.6}\n",
            self.spacing, self.timestep, self.tau, self.lattice_viscosity
        )
    }

    /// Mach number of a physical speed: u / c_s.
    pub fn mach(&self, u: f64) -> f64 {
        u / self.sound_speed
    }
}

/// The map between the DEM's physical frame and a lattice (the coupled step's conversion): lattice node
/// (0, 0) at the physical point `origin`; x* = (x − origin)/h, u* = u Δt/h, ω* = ω Δt, and lattice forces and
/// torques back to physical ones, F = F* ρ₀ h³/Δt², T = T* ρ₀ h⁴/Δt² (2-D, per unit thickness).
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct LatticeMap {
    /// Lattice spacing h (physical length).
    pub spacing: f64,
    /// Fluid time step Δt (physical time).
    pub timestep: f64,
    /// Reference fluid density ρ₀ (physical).
    pub density: f64,
    /// Physical position of lattice node (0, 0).
    pub origin: [f64; 2],
}

impl LatticeMap {
    /// Lattice units as physical units (h = Δt = ρ₀ = 1, origin 0): for scenes written in lattice units.
    pub fn identity() -> Self {
        Self {
            spacing: 1.0,
            timestep: 1.0,
            density: 1.0,
            origin: [0.0; 2],
        }
    }

    /// The map of `units` with lattice node (0, 0) at `origin`.
    pub fn of(units: &LatticeUnits, origin: [f64; 2]) -> Self {
        Self {
            spacing: units.spacing,
            timestep: units.timestep,
            density: units.density,
            origin,
        }
    }

    /// Physical position → lattice coordinates (x − origin)/h.
    pub fn position_to_lattice(&self, x: [f64; 2]) -> [f64; 2] {
        [
            (x[0] - self.origin[0]) / self.spacing,
            (x[1] - self.origin[1]) / self.spacing,
        ]
    }

    /// Physical length → lattice length l/h.
    pub fn length_to_lattice(&self, l: f64) -> f64 {
        l / self.spacing
    }

    /// Factor turning a physical velocity into a lattice one, Δt/h.
    pub fn velocity_scale(&self) -> f64 {
        self.timestep / self.spacing
    }

    /// Physical angular velocity → radians per step, ω Δt.
    pub fn spin_to_lattice(&self, omega: f64) -> f64 {
        omega * self.timestep
    }

    /// Factor turning a lattice force into a physical one, ρ₀ h³/Δt².
    pub fn force_scale(&self) -> f64 {
        self.density * self.spacing.powi(3) / (self.timestep * self.timestep)
    }

    /// Factor turning a lattice torque into a physical one, ρ₀ h⁴/Δt².
    pub fn torque_scale(&self) -> f64 {
        self.force_scale() * self.spacing
    }
}

/// Warnings collected while deriving parameters; printed at start-up and written to the summary.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Warnings(pub Vec<String>);

impl Warnings {
    /// Add a warning.
    pub fn push(&mut self, w: impl Into<String>) {
        self.0.push(w.into());
    }
}

/// Check the relaxation time against the warning thresholds.
pub fn check_tau(units: &LatticeUnits, warnings: &mut Warnings) {
    if units.tau < TAU_WARN_LOW {
        warnings.push(format!(
            "tau = {:.5} is within {:.3} of the BGK stability limit 1/2: expect instability at any \
             appreciable grid Reynolds number; raise tau (coarser h or larger dt) if the run diverges",
            units.tau,
            units.tau - 0.5
        ));
    }
    if units.tau > TAU_WARN_HIGH {
        warnings.push(format!(
            "tau = {:.3} > {TAU_WARN_HIGH}: half-way bounce-back walls move by (16(tau-1/2)^2-3)/(3H^2) \
             relative; use tau <= 1 for accuracy",
            units.tau
        ));
    }
}

/// Check an expected Mach number: warn above [`MACH_WARN`], refuse above [`MACH_REFUSE`] unless allowed,
/// naming `field`, the input that drives the flow (e.g. `channel.pressure_drop`). `allow_high`: the scene's
/// `run.allow_high_mach` (`None` for a kind without it).
pub fn check_mach(
    field: &str,
    mach: f64,
    allow_high: Option<bool>,
    warnings: &mut Warnings,
) -> Result<()> {
    if !mach.is_finite() || (mach > MACH_REFUSE && allow_high != Some(true)) {
        let allow = if allow_high == Some(false) {
            "; set run.allow_high_mach = true to run anyway"
        } else {
            ""
        };
        return Err(LbdemError::field(
            field,
            format!("(gives an expected Mach number of {mach:.3})"),
            &format!(
                "gives an expected Mach number of {mach:.3}: the lattice-Boltzmann compressibility error grows \
                 like Ma^2 and BGK loses stability near Ma ~ 0.4; lbdem refuses Ma > {MACH_REFUSE}"
            ),
            &format!(
                "lower {field}, or shorten the time step (smaller dt raises the lattice sound speed){allow}"
            ),
        ));
    }
    if mach > MACH_WARN {
        warnings.push(format!(
            "expected Mach number {mach:.3} > {MACH_WARN}: compressibility error ~ Ma^2 = {:.1} %",
            100.0 * mach * mach
        ));
    }
    Ok(())
}

/// Check a relative density variation across the domain.
pub fn check_density_drop(field: &str, drop: f64, warnings: &mut Warnings) -> Result<()> {
    if !drop.is_finite() || drop > DENSITY_DROP_REFUSE {
        return Err(LbdemError::field(
            field,
            format!("relative lattice density drop {drop:.3}"),
            &format!(
                "the lattice fluid is compressible (p = c_s^2 rho); density variations above {:.0} % make the \
                 incompressible flow it approximates meaningless",
                DENSITY_DROP_REFUSE * 100.0
            ),
            "lower the pressure drop, or shorten the time step (raising the lattice sound speed)",
        ));
    }
    if drop > DENSITY_DROP_WARN {
        warnings.push(format!(
            "relative density drop {:.1} % > {:.0} %: compressibility errors of order (drop)^2/8",
            drop * 100.0,
            DENSITY_DROP_WARN * 100.0
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fluid(tau: Option<f64>, dt: Option<f64>) -> FluidSection {
        FluidSection {
            density: 1.0,
            viscosity: 0.2,
            spacing: 0.009,
            tau,
            timestep: dt,
            collision: None,
            magic: None,
            lambda_form: None,
        }
    }

    #[test]
    fn tau_and_timestep_are_inverse() {
        let a = LatticeUnits::from_fluid(&fluid(Some(0.625), None)).unwrap();
        let b = LatticeUnits::from_fluid(&fluid(None, Some(a.timestep))).unwrap();
        assert!((b.tau - 0.625).abs() < 1e-12);
        assert!((a.lattice_viscosity - 0.125 / 3.0).abs() < 1e-15);
    }

    #[test]
    fn dissertation_table_6_2_is_inconsistent_and_we_say_which_tau_it_implies() {
        // h = 0.009 cm, dt = 1e-5 s, nu = 0.2 cm^2/s => tau = 0.5 + 3*0.2*1e-5/0.009^2 = 0.5741
        let u = LatticeUnits::from_fluid(&fluid(None, Some(1e-5))).unwrap();
        assert!((u.tau - (0.5 + 6e-6 / 8.1e-5)).abs() < 1e-12);
        assert!((u.lattice_speed - 900.0).abs() < 1e-9);
    }

    #[test]
    fn tau_at_or_below_half_is_refused() {
        let mut f = fluid(None, Some(1e-30));
        f.viscosity = 0.0;
        assert!(LatticeUnits::from_fluid(&f).is_err());
    }

    #[test]
    fn high_mach_is_refused_unless_allowed() {
        let mut w = Warnings::default();
        let e = check_mach("channel.acceleration", 0.5, Some(false), &mut w).unwrap_err();
        assert!(e.to_string().contains("`channel.acceleration`"), "{e}");
        assert!(e.to_string().contains("allow_high_mach"), "{e}");
        let e = check_mach("loading.pressure_drop", 0.5, None, &mut w).unwrap_err();
        assert!(!e.to_string().contains("allow_high_mach"), "{e}");
        assert!(check_mach("channel.acceleration", 0.5, Some(true), &mut w).is_ok());
        assert!(check_mach("channel.acceleration", 0.05, Some(false), &mut w).is_ok());
        assert_eq!(w.0.len(), 1, "only the Ma = 0.5 run is warned about");
    }
}
