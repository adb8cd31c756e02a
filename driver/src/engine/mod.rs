//! The engine: orchestration of the kernels over buffers the driver owns — the fluid lattice ([`lattice`], with
//! the run-time instruction-set dispatch of [`exec`]), the DEM world ([`dem`]) and the coupled step
//! ([`coupled`]). No scenes and no files here: kinds build engines from their scenes, runs drive them.
pub mod coupled;
pub mod dem;
pub mod exec;
pub mod lattice;
