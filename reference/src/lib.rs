//! # lbdem-reference
//!
//! The test oracle: slow, obviously-correct `f64` versions of the lbdem kernels, written for reading rather
//! than speed (array-of-structs, one node at a time, push streaming), and the analytical or published
//! solutions the validation tests compare against.
pub mod analytic;
pub mod coverage;
pub mod dem;
pub mod lbm;
pub mod poroelastic;
