//! The solid half orchestrated: a bonded discrete-element sample the driver owns and steps.
//!
//! Physics stays in `lbdem_kernels::dem`; this module owns the buffers and calls the kernels in the order of
//! the kernels' module guide (broad phase → contacts → bonds → platens → integrate), generates packings with
//! the dissertation's ch. 2 fill-and-expand procedure, runs laboratory loadings, and writes outputs.
//!
//! * [`world`]: [`world::DemWorld`] (particles, platens with constant-speed or servo control, bonds and their
//!   break records, contact history, broad-phase buffers), its deterministic [`world::DemWorld::step`], and the
//!   critical-step refusal.
//! * [`packing`]: seeded fill-and-expand packing to an isotropic stress, then bonding (point or parallel bonds);
//!   a regular hexagonal packing for benchmarks and snapshots.
//! * [`loading`]: uniaxial and biaxial (servo-confined) compression at a constant platen speed, with the
//!   stress–strain record, Young's modulus and peak strength; the Brazilian test of a carved bonded disc.
//! * [`staged`]: the loadings as resumable state machines (one record interval per call).
//!
//! Units: the kernels are unit-agnostic; dry scenes are in cgs or SI as declared, with 2-D stresses meaning
//! force per unit length of a unit-thickness sample.
pub mod loading;
pub mod packing;
pub mod staged;
pub mod world;

pub use loading::{
    carve_disc, run_brazilian, BoundaryStressTest, BrazilianPoint, BrazilianResult, BrazilianTest,
    CompressionResult, CompressionTest, CurvePoint,
};
pub use packing::{boxed_sample, generate_packing, hexagonal_packing, Packing, PackingSpec};
pub use staged::{run_boundary_stress, run_compression};
pub use world::{Bond, BondLaw, BondSpec, BreakRecord, DemWorld, Platen, PlatenControl, SampleBox};

use lbdem_kernels::dem::assembly::ContactModel;
use lbdem_kernels::Real;

/// The contact model of lbdem's grains: linear springs k_n, k_s with Coulomb friction μ, no dashpot
/// (restitution 1) and no tension (dissertation ch. 2, the PFC model of table 6.1).
pub fn elastic_contact<T: Real>(
    normal_stiffness: T,
    shear_stiffness: T,
    friction: T,
) -> ContactModel<T> {
    ContactModel {
        normal_stiffness,
        shear_stiffness,
        friction,
        restitution: T::one(),
        no_tension: true,
    }
}
