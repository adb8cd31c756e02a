//! Whole-assembly passes over caller-owned slices: contact forces of a pair list, particle–wall forces, and
//! the integration of every particle. They only loop over the per-contact kernels of [`contact`](super::contact),
//! [`law`](super::law) and [`integrate`](super::integrate), in a fixed order (pairs in list order, then
//! particles in index order, walls in slice order), so the sums are deterministic.
//!
//! [`ContactModel`] holds the material parameters (k_n, k_s, μ, restitution e) and builds the
//! [`ContactLaw`] of each pair with its own effective mass m* (the dashpot c_n = 2ζ√(m* k_n) depends on it).
//! Velocities given to the laws are [`BodyState::synchronous`] estimates at the force time.
//!
//! Units: as the per-contact kernels (consistent, caller-chosen).
use super::contact::{closest_approach, wall_contact};
use super::integrate::{central_difference_step, particle_critical_time_step};
use super::law::{effective_mass, linear_contact_force, BodyState, ContactLaw};
use super::shape::{Particle, Wall};
use super::vector::add;
use crate::Real;

/// Material parameters of the particle contacts.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ContactModel<T> {
    /// Normal stiffness k_n.
    pub normal_stiffness: T,
    /// Shear stiffness k_s.
    pub shear_stiffness: T,
    /// Friction coefficient μ.
    pub friction: T,
    /// Coefficient of restitution e in (0, 1]; 1 means no dashpot.
    pub restitution: T,
    /// Clip the normal force at zero.
    pub no_tension: bool,
}

impl<T: Real> ContactModel<T> {
    /// The law for a pair of masses (an infinite mass stands for a wall).
    pub fn law(&self, mass_i: T, mass_j: T) -> ContactLaw<T> {
        let base = ContactLaw {
            no_tension: self.no_tension,
            ..ContactLaw::elastic(self.normal_stiffness, self.shear_stiffness, self.friction)
        };
        if self.restitution >= T::one() {
            base
        } else {
            base.with_restitution(self.restitution, effective_mass(mass_i, mass_j))
        }
    }

    /// A-priori PFC critical step of an assembly (Itasca PFC2D manual) assuming every particle carries
    /// `coordination` contacts: per particle √(m/(z k)) for translation with k = max(k_n, k_s), and
    /// √(I/(z k_s R²)) for rotation with R the bounding radius (the largest lever arm); the minimum over the
    /// particles (+∞ for none). Multiply by a safety factor (PFC ≈ 0.8) before use.
    pub fn critical_time_step(&self, particles: &[Particle<T>], coordination: T) -> T {
        let k = self.normal_stiffness.max(self.shear_stiffness);
        particles
            .iter()
            .map(|p| {
                let r = p.shape.bounding_radius();
                particle_critical_time_step(
                    p.mass,
                    coordination * k,
                    p.moment_of_inertia,
                    coordination * self.shear_stiffness * r * r,
                )
            })
            .fold(T::infinity(), |a, b| a.min(b))
    }
}

/// Why an assembly pass refused its input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AssemblyError {
    /// A slice is shorter than it must be (see the function's documentation).
    BufferLength,
    /// A pair names a particle index out of range, or a particle with itself.
    BadPair,
}

/// Add the contact forces and torques of every pair to `force` and `torque` (indexed by particle), updating
/// the per-pair shear histories `shear` (aligned with `pairs`). Returns the number of active contacts.
/// `force` and `torque` need one entry per particle, `shear` one per pair.
pub fn add_pair_contact_forces<T: Real>(
    model: &ContactModel<T>,
    particles: &[Particle<T>],
    pairs: &[[usize; 2]],
    shear: &mut [T],
    dt: T,
    force: &mut [[T; 2]],
    torque: &mut [T],
) -> Result<usize, AssemblyError> {
    let n = particles.len();
    if shear.len() < pairs.len() || force.len() < n || torque.len() < n {
        return Err(AssemblyError::BufferLength);
    }
    if pairs.iter().any(|&[i, j]| i >= n || j >= n || i == j) {
        return Err(AssemblyError::BadPair);
    }
    let mut active = 0;
    for (&[i, j], history) in pairs.iter().zip(shear.iter_mut()) {
        let (pi, pj) = (&particles[i], &particles[j]);
        let c = closest_approach(pi, pj);
        let law = model.law(pi.mass, pj.mass);
        let f = linear_contact_force(
            &law,
            &c,
            &BodyState::synchronous(pi, dt),
            &BodyState::synchronous(pj, dt),
            history,
            dt,
        );
        if c.is_active() {
            active += 1;
            force[i] = add(force[i], f.force_on_i);
            force[j] = add(force[j], f.force_on_j);
            torque[i] += f.torque_on_i;
            torque[j] += f.torque_on_j;
        }
    }
    Ok(active)
}

/// Add the forces of fixed walls on every particle, updating the shear histories `wall_shear`
/// (index particle × walls.len() + wall; zeroed when a contact ends), and accumulate the force each wall
/// exerts on the particles in `wall_reaction` (one entry per wall; the wall feels the opposite). Returns the
/// number of active contacts.
#[allow(clippy::too_many_arguments)]
pub fn add_wall_contact_forces<T: Real>(
    model: &ContactModel<T>,
    particles: &[Particle<T>],
    walls: &[Wall<T>],
    wall_shear: &mut [T],
    dt: T,
    force: &mut [[T; 2]],
    torque: &mut [T],
    wall_reaction: &mut [[T; 2]],
) -> Result<usize, AssemblyError> {
    let n = particles.len();
    let needed = n
        .checked_mul(walls.len())
        .ok_or(AssemblyError::BufferLength)?;
    if wall_shear.len() < needed
        || force.len() < n
        || torque.len() < n
        || wall_reaction.len() < walls.len()
    {
        return Err(AssemblyError::BufferLength);
    }
    let mut active = 0;
    for (i, p) in particles.iter().enumerate() {
        for (w, wall) in walls.iter().enumerate() {
            let history = &mut wall_shear[i * walls.len() + w];
            let Some(c) = wall_contact(p, wall) else {
                *history = T::zero();
                continue;
            };
            let law = model.law(p.mass, T::infinity());
            let f = linear_contact_force(
                &law,
                &c,
                &BodyState::synchronous(p, dt),
                &BodyState::fixed(c.point_j),
                history,
                dt,
            );
            active += 1;
            force[i] = add(force[i], f.force_on_i);
            torque[i] += f.torque_on_i;
            wall_reaction[w] = add(wall_reaction[w], f.force_on_i);
        }
    }
    Ok(active)
}

/// One central-difference step of every particle with its total `force` and `torque` (see
/// [`central_difference_step`]).
pub fn integrate_all<T: Real>(
    particles: &mut [Particle<T>],
    force: &[[T; 2]],
    torque: &[T],
    gravity: [T; 2],
    alpha: T,
    dt: T,
) -> Result<(), AssemblyError> {
    if force.len() < particles.len() || torque.len() < particles.len() {
        return Err(AssemblyError::BufferLength);
    }
    for ((p, f), t) in particles.iter_mut().zip(force).zip(torque) {
        central_difference_step(p, *f, *t, gravity, alpha, dt);
    }
    Ok(())
}
