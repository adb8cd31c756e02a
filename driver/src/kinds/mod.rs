//! The scene kinds, one folder each, and the one registry that lists them. Each kind implements
//! [`crate::run::Kind`] (its scene file type, derived set-up, resumable state, chunked advance, outputs and
//! results); `lbdem check`, `run` and `resume` look the kind up here by name (the `[scene] kind` of a scene
//! file, or the kind tag of a checkpoint). Adding a kind is one folder and one line in [`REGISTRY`]. Kinds never
//! import each other: what two kinds share lives in `engine`, `observe`, `output`, `scene` or `units`.
use std::path::Path;

use crate::error::Result;
use crate::run::{self, Kind, RunOptions};

pub mod channel;
pub mod consolidation;
pub mod coupled_demo;
pub mod cylinder_array;
pub mod dry;
pub mod fluid_compressibility;
pub mod fracture;
pub mod porous_flow;
pub mod pressure_diffusion;
pub mod terminal_velocity;
pub mod terzaghi;

/// A kind's entry points, monomorphised.
pub struct Entry {
    /// `[scene] kind` of its scene files and kind tag of its checkpoints.
    pub name: &'static str,
    /// The top-level section only its scene files have ([`Kind::OWN_SECTION`]).
    pub own_section: Option<&'static str>,
    /// `lbdem check`: (scene text, path) → the description.
    pub check: fn(&str, &str) -> Result<String>,
    /// `lbdem run`: (scene text, path, output directory, options) → the summary.
    pub run: fn(&str, &str, &Path, &RunOptions) -> Result<serde_json::Value>,
    /// `lbdem resume`: (run directory, options) → the summary.
    pub resume: fn(&Path, &RunOptions) -> Result<serde_json::Value>,
}

const fn entry<K: Kind>() -> Entry {
    Entry {
        name: K::NAME,
        own_section: K::OWN_SECTION,
        check: run::check::<K>,
        run: run::run::<K>,
        resume: run::resume::<K>,
    }
}

/// Every scene kind.
pub const REGISTRY: &[Entry] = &[
    entry::<channel::Channel>(),
    entry::<cylinder_array::CylinderArray>(),
    entry::<porous_flow::PorousFlow>(),
    entry::<terminal_velocity::TerminalVelocity>(),
    entry::<pressure_diffusion::PressureDiffusion>(),
    entry::<fluid_compressibility::FluidCompressibility>(),
    entry::<consolidation::Consolidation>(),
    entry::<terzaghi::Terzaghi>(),
    entry::<dry::Dry>(),
    entry::<fracture::FractureTest>(),
    entry::<coupled_demo::CoupledDemo>(),
];

/// The registry entry of kind `name`.
pub fn find(name: &str) -> Option<&'static Entry> {
    REGISTRY.iter().find(|e| e.name == name)
}

/// The names of every kind, for messages.
pub fn names() -> String {
    REGISTRY
        .iter()
        .map(|e| e.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The kind whose scene files have the top-level section `section` (its own section, not one shared by several
/// kinds), for the hint of a scene whose `[scene] kind` does not match its sections.
pub fn owner_of_section(section: &str) -> Option<&'static str> {
    REGISTRY
        .iter()
        .find(|e| e.own_section == Some(section))
        .map(|e| e.name)
}
