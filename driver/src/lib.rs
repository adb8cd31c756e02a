//! # lbdem
//!
//! The driver: owns buffers, builds scenes from TOML files, converts physical units to lattice units in one
//! place ([`units`]), runs the kernels of `lbdem-kernels`, and writes outputs.
