//! Explicit time integration and the critical time step.
//!
//! **Central difference (leapfrog)**, the scheme of PFC and of Cundall & Strack (1979), for translation and
//! rotation of a rigid 2-D particle:
//!
//!   v(t + Δt/2) = v(t − Δt/2) + (F(t) + m g + F_d)/m Δt,   x(t + Δt) = x(t) + v(t + Δt/2) Δt,
//!   ω(t + Δt/2) = ω(t − Δt/2) + (M(t) + M_d)/I Δt,          θ(t + Δt) = θ(t) + ω(t + Δt/2) Δt,
//!
//! with F_d, M_d the PFC local damping of each degree of freedom (−α |unbalanced| sign(v), using the mid-step
//! velocity; α = 0 disables it). It is second order, symplectic without damping, and stable for one undamped
//! degree of freedom of stiffness k when Δt < 2√(m/k). The step stores the acceleration it applied, so that
//! velocity-dependent forces (the contact dashpot) can use the second-order estimate of the velocity at the
//! force time, v(t) ≈ v(t − Δt/2) + a(t − Δt) Δt/2 ([`BodyState::synchronous`](super::law::BodyState::synchronous));
//! with the lagged mid-step velocity instead the dashpot's restitution is off by O(ζ ω₀ Δt) (1.5 % for e = 0.5
//! at Δt = t_c/50, measured).
//!
//! **Critical time step** (the PFC estimate, Itasca PFC2D manual; Cundall & Strack 1979): per particle √(m/Σk_n) for translation and √(I/Σk_rot) for
//! rotation (Σ over the particle's contacts and bonds; for a disc contact k_rot = k_s r²), the minimum over the
//! particles; this is the PFC estimate for an assembly, where the highest frequency is about 2√(k/m). The
//! single-degree-of-freedom bound is 2√(m/k). Practice: a safety factor below 1 (PFC ≈ 0.8), and Δt ≲ t_c/20
//! to resolve each contact.
//!
//! Units: consistent (force = mass × length/time²).
use super::law::local_damping;
use super::shape::Particle;
use crate::math::Vector;
use crate::Real;

/// One central-difference step of a particle under the total contact/bond/fluid force `force` and torque
/// `torque`, gravity `gravity` (an acceleration, applied as m g) and local damping coefficient `alpha`.
pub fn central_difference_step<T: Real>(
    particle: &mut Particle<T>,
    force: Vector<T>,
    torque: T,
    gravity: Vector<T>,
    alpha: T,
    dt: T,
) {
    let m = particle.mass;
    let mut f = [force[0] + m * gravity[0], force[1] + m * gravity[1]];
    for (fk, vk) in f.iter_mut().zip(particle.velocity.iter()) {
        *fk += local_damping(*fk, *vk, alpha);
    }
    let torque = torque + local_damping(torque, particle.angular_velocity, alpha);
    let inv_m = T::one() / m;
    particle.acceleration = Vector::new(f[0] * inv_m, f[1] * inv_m);
    for ((v, x), a) in particle
        .velocity
        .iter_mut()
        .zip(particle.position.iter_mut())
        .zip(particle.acceleration.iter())
    {
        *v += *a * dt;
        *x += *v * dt;
    }
    particle.angular_acceleration = torque / particle.moment_of_inertia;
    particle.angular_velocity += particle.angular_acceleration * dt;
    particle.angle += particle.angular_velocity * dt;
}

/// Kinetic energy ½ m v² + ½ I ω².
pub fn kinetic_energy<T: Real>(particle: &Particle<T>) -> T {
    let v = particle.velocity;
    T::lit(0.5)
        * (particle.mass * (v[0] * v[0] + v[1] * v[1])
            + particle.moment_of_inertia * particle.angular_velocity * particle.angular_velocity)
}

/// The stability limit of one undamped degree of freedom: 2√(m/k).
pub fn single_dof_stability_limit<T: Real>(mass: T, stiffness: T) -> T {
    T::lit(2.0) * (mass / stiffness).sqrt()
}

/// The stability limit of one degree of freedom with viscous damping ratio ζ: 2(√(1 + ζ²) − ζ)/ω, ω = √(k/m)
/// (central difference with a dashpot, e.g. Belytschko et al., *Nonlinear Finite Elements*, §6.3; ζ = 0 gives
/// [`single_dof_stability_limit`]).
pub fn damped_stability_limit<T: Real>(mass: T, stiffness: T, damping_ratio: T) -> T {
    let z = damping_ratio;
    T::lit(2.0) * ((T::one() + z * z).sqrt() - z) * (mass / stiffness).sqrt()
}

/// PFC's per-particle critical step: min(√(m/Σk_tran), √(I/Σk_rot)); a zero stiffness sum imposes no limit
/// (+∞).
pub fn particle_critical_time_step<T: Real>(
    mass: T,
    translational_stiffness: T,
    moment_of_inertia: T,
    rotational_stiffness: T,
) -> T {
    let limit = |inertia: T, k: T| {
        if k > T::zero() {
            (inertia / k).sqrt()
        } else {
            T::infinity()
        }
    };
    limit(mass, translational_stiffness).min(limit(moment_of_inertia, rotational_stiffness))
}

/// The assembly's critical step: the minimum of [`particle_critical_time_step`] over the particles, with the
/// stiffness sums given per particle (pairs beyond the shortest slice are ignored; no particle gives +∞).
pub fn critical_time_step<T: Real>(
    particles: &[Particle<T>],
    translational_stiffness: &[T],
    rotational_stiffness: &[T],
) -> T {
    particles
        .iter()
        .zip(translational_stiffness)
        .zip(rotational_stiffness)
        .map(|((p, &kt), &kr)| particle_critical_time_step(p.mass, kt, p.moment_of_inertia, kr))
        .fold(T::infinity(), |a, b| a.min(b))
}

/// Whether `dt` exceeds `safety × critical` (a NaN or non-positive `dt` counts as exceeding).
pub fn exceeds_critical_time_step<T: Real>(dt: T, critical: T, safety: T) -> bool {
    !(dt > T::zero() && dt <= safety * critical)
}
