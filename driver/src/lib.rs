//! # lbdem
//!
//! The driver: scenes, units, orchestration of the kernels of `lbdem-kernels`, runs and outputs. Thin in physics.
//!
//! * [`app`]: what the command line does — read the scene once, look its kind up in the registry, dispatch.
//! * [`scene`]: the section types shared by several kinds (`[scene]`, `[run]`, `[packing]`, `[solid]`).
//! * [`input`]: reading scene text, parse errors that name the full key path, and the limits (sizes, memory,
//!   steps) checked before anything is allocated.
//! * [`units`]: the only physical ↔ lattice converter (`[fluid]` → τ, Δt, c_s, …; the DEM ↔ lattice map).
//! * [`engine`]: the fluid lattice, the DEM world and the coupled step (orchestration of kernels; no scenes, no
//!   files).
//! * [`run`]: the [`run::Kind`] contract and the one long-run loop (progress, checkpoints, signals, health).
//! * [`observe`]: measurements shared by kinds (health, steady state, Darcy, fits, flow measures).
//! * [`output`]: run directory, atomic writes, CSV, VTK, plots, the one summary schema.
//! * [`kinds`]: one folder per scene kind, and the registry.
//! * [`study`]: the speed-versus-error study.
//!
//! Module dependencies point one way, lowest first (checked by `driver/tests/architecture.rs`): `error` →
//! `input` → `units` → `engine` → `observe`, `output` → `run` → `scene` → `kinds` → `app`, `study`. See
//! `docs/architecture.md` for the data flow of a coupled step and how to add a kind.
pub mod app;
pub mod engine;
pub mod error;
pub mod input;
pub mod kinds;
pub mod observe;
pub mod output;
pub mod run;
pub mod scene;
pub mod study;
pub mod units;
