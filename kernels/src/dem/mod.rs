//! Discrete-element kernels: shapes, contact detection, contact and bond laws, integration.
//!
//! The solid half of the coupled model of the dissertation (ch. 2, ch. 4.2.1, ch. 6.6): rigid two-dimensional
//! particles (discs and ellipses) and straight walls, a soft-contact law (linear spring–dashpot with Coulomb
//! friction, Cundall & Strack 1979), bonds (the point bond of eq. 6.13 and the Potyondy & Cundall 2004 parallel
//! bond) and an explicit central-difference integrator with PFC local damping.
//!
//! Vectors, positions and rotations are those of the kernels' [`math`](crate::math) module (nalgebra).
//! * [`shape`]: [`shape::Shape`] (disc, ellipse), [`shape::Wall`] (half-plane), [`shape::Particle`].
//! * [`contact`]: narrow-phase detection returning contact point, unit normal (from i to j) and signed overlap;
//!   ellipse pairs by maximising the separating-axis gap over the normal angle (exact support functions).
//! * [`grid`]: the broad phase, a uniform cell grid built by counting sort in caller-owned buffers.
//! * [`law`]: the linear contact law with incremental shear history, restitution → damping, local damping.
//! * [`bond`]: [`bond::PointBond`] (eq. 6.13) and [`bond::ParallelBond`] (Potyondy & Cundall 2004, 2-D).
//! * [`integrate`]: central-difference update and critical time-step estimates.
//! * [`assembly`]: whole-assembly passes (pair contacts, wall contacts, integration) over caller slices.
//! * [`servo`]: the servo law of stress-controlled walls (platens).
//!
//! A typical dry step (the driver owns every buffer):
//!
//! 1. [`grid::build_cell_grid`] then [`grid::candidate_pairs`] (sorted pairs, bounding circles + margin);
//!    [`grid::carry_contact_history`] moves last step's shear histories onto the new pair list.
//! 2. For each pair [`contact::closest_approach`] and [`law::linear_contact_force`] (with
//!    [`law::BodyState::synchronous`] velocities); for each particle and wall [`contact::wall_contact`]; for
//!    each intact bond [`bond::point_bond_force`] or [`bond::parallel_bond_force`], recording any
//!    [`bond::BondBreak`]. Sum forces and torques per particle in a fixed order (determinism).
//! 3. [`integrate::central_difference_step`] for every particle (gravity, local damping α), with a step
//!    checked once against [`integrate::critical_time_step`].
//!
//! Units: the kernels are unit-agnostic; the caller picks one consistent system (the driver uses lattice units,
//! the dissertation's tables are cgs: cm, g, s, dyne). Angles are in radians, counter-clockwise; torques and
//! angular velocities are the z-components of the 3-D vectors (positive counter-clockwise). Particles have unit
//! thickness, so "mass" and "stiffness" are per unit thickness where a 2-D reading needs it.
pub mod assembly;
pub mod bond;
pub mod contact;
pub mod grid;
pub mod integrate;
pub mod law;
pub mod servo;
pub mod shape;
