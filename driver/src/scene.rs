//! Scene files: TOML in physical units. Parsing rejects unknown keys, missing fields and wrong types (serde
//! with `deny_unknown_fields`); [`Scene::validate`] checks ranges and names the field and the fix.
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

/// What a scene simulates.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum SceneKind {
    /// Plane Poiseuille flow between two walls (validation of the fluid kernels).
    Channel,
    /// Periodic square array of fixed cylinders, body-force driven (dissertation §5.4; [`crate::porous`]).
    CylinderArray,
    /// Fixed discs between pressure boundaries: Darcy and permeability (dissertation §5.5; [`crate::porous`]).
    PorousFlow,
    /// A bonded dry sample between platens (no fluid); read by [`crate::solid::scene::DryScene`].
    Dry,
    /// The fluid-driven fracture test (ch. 6); read by [`crate::fracture::FractureScene`].
    Fracture,
}

/// `[scene]`
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneHeader {
    /// What is simulated.
    pub kind: SceneKind,
    /// Unit system of every value in the file.
    pub units: UnitSystem,
    /// Kernel precision (default f64).
    #[serde(default)]
    pub precision: Precision,
    /// Optional free-text name.
    #[serde(default)]
    pub name: Option<String>,
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
}

/// How a channel flow is driven.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ChannelDrive {
    /// Zou–He pressure inlet (west) and outlet (east).
    Pressure,
    /// Uniform body force (acceleration) along x, periodic along x.
    BodyForce,
}

/// `[channel]`: plane Poiseuille flow.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelSection {
    /// Length along x.
    pub length: f64,
    /// Width between the walls.
    pub width: f64,
    /// Drive.
    pub drive: ChannelDrive,
    /// Pressure drop over the length (drive = "pressure").
    #[serde(default)]
    pub pressure_drop: Option<f64>,
    /// Acceleration along x (drive = "body_force").
    #[serde(default)]
    pub acceleration: Option<f64>,
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
}

/// A whole scene file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// `[scene]`
    pub scene: SceneHeader,
    /// `[fluid]`
    pub fluid: FluidSection,
    /// `[channel]` (kind = "channel")
    #[serde(default)]
    pub channel: Option<ChannelSection>,
    /// `[cylinder_array]` (kind = "cylinder_array")
    #[serde(default)]
    pub cylinder_array: Option<crate::porous::CylinderArraySection>,
    /// `[porous]` (kind = "porous_flow")
    #[serde(default)]
    pub porous: Option<crate::porous::PorousSection>,
    /// `[run]`
    pub run: RunSection,
}

/// Check that a scene value is finite and > 0, naming the field and giving a hint otherwise.
pub(crate) fn positive(field: &str, v: f64, hint: &str) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(LbdemError::field(
            field,
            v,
            "must be a finite number > 0",
            hint,
        ))
    }
}

impl Scene {
    /// Parse a scene from TOML text (`path` is used in messages only).
    pub fn from_toml(text: &str, path: &str) -> Result<Self> {
        toml::from_str(text).map_err(|e| LbdemError::ParseScene {
            path: path.to_string(),
            message: e.to_string(),
        })
    }

    /// Read and parse a scene file.
    pub fn load(path: &std::path::Path) -> Result<Self> {
        let text = read_scene_text(path)?;
        Self::from_toml(&text, &path.display().to_string())
    }

    /// Range checks that do not need derived quantities (those are in [`crate::units`]).
    pub fn validate(&self) -> Result<()> {
        let f = &self.fluid;
        positive(
            "fluid.density",
            f.density,
            "give the fluid density, e.g. 1.0 g/cm^3 for water in cgs",
        )?;
        positive(
            "fluid.viscosity",
            f.viscosity,
            "give the kinematic viscosity, e.g. 0.01 cm^2/s for water",
        )?;
        positive(
            "fluid.spacing",
            f.spacing,
            "give the lattice spacing h in length units",
        )?;
        match (f.tau, f.timestep) {
            (Some(_), Some(_)) => return Err(LbdemError::field(
                "fluid.tau",
                "given together with fluid.timestep",
                "tau and timestep are tied by tau = 1/2 + 3 nu dt / h^2, so only one may be given",
                "remove one of fluid.tau or fluid.timestep",
            )),
            (None, None) => {
                return Err(LbdemError::field(
                    "fluid.tau",
                    "missing",
                    "neither fluid.tau nor fluid.timestep is given",
                    "add fluid.tau (e.g. 0.875) or fluid.timestep",
                ))
            }
            (Some(t), None) => {
                if !(t.is_finite() && t > 0.5) {
                    return Err(LbdemError::field(
                        "fluid.tau",
                        t,
                        "BGK is unstable for tau <= 1/2 (the viscosity (tau - 1/2)/3 would be <= 0)",
                        "use tau in (0.5, 2], ideally 0.6-1.0",
                    ));
                }
            }
            (None, Some(dt)) => positive("fluid.timestep", dt, "give the time step in seconds")?,
        }
        match (self.run.steps, self.run.duration) {
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
        if let Some(tol) = self.run.steady_tolerance {
            positive("run.steady_tolerance", tol, "e.g. 1e-9")?;
        }
        if self.run.check_interval == Some(0) {
            return Err(LbdemError::field(
                "run.check_interval",
                0,
                "must be at least 1",
                "e.g. 200",
            ));
        }
        match self.scene.kind {
            SceneKind::Dry => {}      // validated by crate::solid::scene::DryScene
            SceneKind::Fracture => {} // validated by crate::fracture::FractureScene
            SceneKind::Channel => {
                let c = self.channel.as_ref().ok_or_else(|| {
                    LbdemError::field(
                        "channel",
                        "missing",
                        "scene.kind = \"channel\" needs a [channel] section",
                        "add [channel] with length, width, drive and pressure_drop or acceleration",
                    )
                })?;
                positive(
                    "channel.length",
                    c.length,
                    "give the channel length along x",
                )?;
                positive(
                    "channel.width",
                    c.width,
                    "give the channel width between the walls",
                )?;
                match c.drive {
                    ChannelDrive::Pressure => {
                        let dp = c.pressure_drop.ok_or_else(|| {
                            LbdemError::field(
                                "channel.pressure_drop",
                                "missing",
                                "drive = \"pressure\" needs the pressure drop over the length",
                                "add channel.pressure_drop",
                            )
                        })?;
                        positive(
                            "channel.pressure_drop",
                            dp,
                            "a positive drop drives flow along +x",
                        )?;
                        if c.acceleration.is_some() {
                            return Err(LbdemError::field(
                                "channel.acceleration",
                                "given",
                                "drive = \"pressure\" does not use an acceleration",
                                "remove channel.acceleration or set drive = \"body_force\"",
                            ));
                        }
                    }
                    ChannelDrive::BodyForce => {
                        let g = c.acceleration.ok_or_else(|| {
                            LbdemError::field(
                                "channel.acceleration",
                                "missing",
                                "drive = \"body_force\" needs the acceleration along x",
                                "add channel.acceleration",
                            )
                        })?;
                        positive(
                            "channel.acceleration",
                            g,
                            "a positive acceleration drives flow along +x",
                        )?;
                        if c.pressure_drop.is_some() {
                            return Err(LbdemError::field(
                                "channel.pressure_drop",
                                "given",
                                "drive = \"body_force\" does not use a pressure drop",
                                "remove channel.pressure_drop or set drive = \"pressure\"",
                            ));
                        }
                    }
                }
            }
            SceneKind::CylinderArray | SceneKind::PorousFlow => {
                crate::porous::validate_sections(self)?
            }
        }
        Ok(())
    }
}

/// Read a scene file; the error names the path.
pub fn read_scene_text(path: &std::path::Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| LbdemError::ReadScene {
        path: path.display().to_string(),
        source: e,
    })
}

/// The `[scene] kind` of a scene's TOML text as `K` (a kind enum, or `String`); `None` if the header does not
/// parse as `K` (the scene's own parser then reports the problem).
pub fn peek_kind<K: serde::de::DeserializeOwned>(text: &str) -> Option<K> {
    #[derive(Deserialize)]
    struct Header<K> {
        scene: KindField<K>,
    }
    #[derive(Deserialize)]
    struct KindField<K> {
        kind: K,
    }
    toml::from_str::<Header<K>>(text).ok().map(|h| h.scene.kind)
}
