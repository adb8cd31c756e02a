//! # lbdem
//!
//! The driver: owns buffers, builds scenes from TOML files, converts physical units to lattice units in one
//! place ([`units`]), runs the kernels of `lbdem-kernels`, and writes outputs.

pub mod channel;
pub mod coupled;
pub mod error;
pub mod lattice;
pub mod output;
pub mod poro;
pub mod porous;
pub mod run;
pub mod scene;
pub mod solid;
pub mod units;
