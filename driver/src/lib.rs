//! # lbdem
//!
//! The driver: owns buffers, builds scenes from TOML files, converts physical units to lattice units in one
//! place ([`units`]), runs the kernels of `lbdem-kernels`, and writes outputs.

pub mod channel;
pub mod checkpoint;
pub mod coupled;
pub mod coupled_demo;
pub mod error;
pub mod exec;
pub mod fracture;
pub mod lattice;
pub mod longrun;
pub mod output;
pub mod plot;
pub mod poro;
pub mod porous;
pub mod resume;
pub mod run;
pub mod scene;
pub mod solid;
pub mod study;
pub mod units;
