//! D2Q9 lattice-Boltzmann kernels (dissertation ch. 4.2.2 and appendix 5.A).
//!
//! * [`d2q9`]: velocity set, weights, opposites, second-order equilibrium, moments.
//! * [`collide`]: BGK (eq. 4.1), Guo et al. (2002) forcing, Noble–Torczynski PSM (eq. 4.4–4.6) with the
//!   per-node momentum exchange of eq. 4.7–4.8 returned to the caller.
//! * [`lattice`]: the structure-of-arrays layout (padded planes) and neighbour index arithmetic.
//! * [`boundary`]: boundary specifications per side, half-way bounce-back, Zou–He (1997) closures and corners.
//! * [`step`]: the fused pull "stream + collide" update over row bands, with fix-up passes for boundary and
//!   partially-saturated nodes (two-lattice scheme).
//! * [`aa`]: the in-place AA-pattern update (one buffer), bitwise the same results as [`step`].
//!
//! Everything is in lattice units: Δx = Δt = 1, c_s² = 1/3, p = ρ/3, ν = (τ − ½)/3.
pub mod aa;
pub mod boundary;
pub mod collide;
pub mod d2q9;
pub mod lattice;
pub mod step;
