//! The kernels' property tests and proof harnesses, one module per file of this directory, compiled into one
//! test binary (one crate linked once instead of one per file). Run one file's tests with
//! `cargo test -p lbdem-verification --test properties <file>::`.
mod aa_properties;
mod broad_phase_properties;
mod coupling_properties;
mod coverage_properties;
mod dem_assembly_properties;
mod dem_kernel_properties;
mod dem_proofs;
mod dem_properties;
mod dem_validation;
mod fluid_properties;
mod kernel_api_properties;
mod proofs;
mod real_properties;
mod serde_names;
