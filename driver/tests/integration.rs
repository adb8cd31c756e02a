//! The driver's integration tests, one module per file of this directory, compiled into one test binary: one
//! crate linked once instead of one per file (the test build was most of CI's time). Run one file's tests with
//! `cargo test -p lbdem --test integration <file>::`, e.g. `cargo test -p lbdem --test integration terzaghi::`.
mod architecture;
mod boundaries;
mod checkpoint;
mod cli;
mod common;
mod coupled;
mod dem_brazilian;
mod dem_scene;
mod dem_validation;
mod determinism;
mod every_kind;
mod fracture;
mod hard_cases;
mod hostile;
mod moving_solids;
mod omega_grain;
mod poiseuille;
mod poro;
mod porous;
mod porous_scenes;
mod scene_collision;
mod streaming;
mod study;
mod terzaghi;
mod trt;
mod trt_psm;
mod vtk_readback;
mod vtk_writers;
