//! # lbdem-kernels
//!
//! All the physics of lbdem, as `#![no_std]`, allocation-free kernels over caller-owned slices, generic over
//! [`Real`] (`f32` or `f64`). Kernels work in lattice units only (Δx = Δt = 1, c_s² = 1/3); the driver converts
//! physical scenes to lattice units in one place.
//!
//! * [`fluid`]: the D2Q9 lattice-Boltzmann method of the dissertation's ch. 4 / appendix 5.A: descriptor and
//!   equilibrium, BGK collision (eq. 4.1), the Noble–Torczynski partially-saturated collision (eq. 4.4–4.8),
//!   Guo forcing, fused pull streaming with half-way bounce-back, Zou–He boundaries.
//! * [`math`]: the vector, point and rotation types (nalgebra) of the DEM and the coupling.
//! * [`dem`]: discrete elements (discs, ellipses, walls), contact detection, contact and bond laws, integration.
//!
//! No kernel panics on valid input; where a kernel needs scratch memory it takes it from the caller and a
//! sibling `*_scratch_len` function says how much.
#![no_std]
#![forbid(unsafe_code)]
// `!(a > b)` is the NaN-rejecting form of a range check (a NaN fails it); the kernels use it on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod coupling;
pub mod coverage;
pub mod dem;
pub mod fluid;
mod lanes;
pub mod math;
mod real;

pub use real::Real;
