//! Linear spring–dashpot contact law with Coulomb friction (Cundall & Strack 1979), and PFC local damping.
//!
//! For an active contact (overlap δ > 0) with unit normal n from i to j and tangent t = n rotated by +90°, the
//! relative velocity of j with respect to i at the contact point x_c is
//! v = (v_j + ω_j × r_j) − (v_i + ω_i × r_i), r_k = x_c − c_k. The force on j is F = F_n n + F_s t with
//!
//! * F_n = k_n δ − c_n (v·n), clipped to F_n ≥ 0 when `no_tension` is set (the usual choice; without it the
//!   dashpot pulls at the end of a damped collision, which is what the classical restitution formula assumes);
//! * F_s ← F_s − k_s (v·t) Δt (incremental shear spring), then |F_s| ≤ μ max(F_n, 0) (Coulomb: a trial force
//!   above the cap is scaled back to it and the contact is sliding).
//!
//! The force on i is −F, and the torques are r_i × (−F) and r_j × F, so force and moment about the contact
//! point balance exactly. The shear history F_s is one signed scalar per contact along the current tangent: in
//! 2-D this *is* the shear force carried with the rotating contact frame. The caller keeps it while the contact
//! lives and drops it when it ends (the kernel zeroes it for an inactive contact).
//!
//! Restitution (Ting & Corkum 1992; Schäfer, Dippel & Wolf 1996, J. Phys. I France 6, 5–20): c_n = 2ζ√(m* k_n), ζ = −ln e/√(π² + ln² e), m* = m_i m_j/(m_i + m_j),
//! contact duration t_c = π/(ω₀√(1 − ζ²)), ω₀ = √(k_n/m*). The formula assumes the dashpot acts until δ = 0;
//! with the no-tension clip the restitution comes out higher (measured at Δt = t_c/50: 0.40, 0.55, 0.72, 0.90
//! for e = 0.3, 0.5, 0.7, 0.9; without the clip within 0.25 % of e, see `verification/tests/dem_validation.rs`).
//! Feed the dashpot the velocity at the force time ([`BodyState::synchronous`]); the lagged mid-step velocity
//! of the central-difference scheme costs O(ζω₀Δt) in e.
//!
//! PFC local non-viscous damping (Cundall 1987; Itasca PFC2D manual), per degree of freedom: F_d = −α |F_unbal| sign(v), α = 0.7 by
//! default in PFC and in the dissertation.
//!
//! Units: k_n, k_s force/length; c_n force·time/length; μ dimensionless; consistent otherwise.
use super::contact::Contact;
use super::shape::Particle;
use crate::math::{cross, perp, spin, Vector};
use crate::Real;

/// PFC's default local-damping coefficient α.
pub const DEFAULT_LOCAL_DAMPING: f64 = 0.7;

/// Parameters of the linear contact law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactLaw<T> {
    /// Normal stiffness k_n.
    pub normal_stiffness: T,
    /// Shear stiffness k_s.
    pub shear_stiffness: T,
    /// Coulomb friction coefficient μ.
    pub friction: T,
    /// Viscous normal damping coefficient c_n (0: elastic).
    pub normal_damping: T,
    /// Clip the normal force at zero (no attraction from the dashpot).
    pub no_tension: bool,
}

impl<T: Real> ContactLaw<T> {
    /// An undamped law with the no-tension clip.
    pub fn elastic(normal_stiffness: T, shear_stiffness: T, friction: T) -> Self {
        ContactLaw {
            normal_stiffness,
            shear_stiffness,
            friction,
            normal_damping: T::zero(),
            no_tension: true,
        }
    }

    /// The same law with the normal dashpot that gives restitution `e` for a pair of effective mass `m*`.
    pub fn with_restitution(self, restitution: T, effective_mass: T) -> Self {
        let zeta = damping_ratio_from_restitution(restitution);
        ContactLaw {
            normal_damping: normal_damping_coefficient(zeta, effective_mass, self.normal_stiffness),
            ..self
        }
    }
}

/// ζ = −ln e/√(π² + ln² e), for e in (0, 1]; e ≥ 1 gives 0 and e ≤ 0 (or NaN) gives 1 (critical damping).
pub fn damping_ratio_from_restitution<T: Real>(restitution: T) -> T {
    if restitution >= T::one() {
        return T::zero();
    }
    if restitution.is_nan() || restitution <= T::zero() {
        return T::one();
    }
    let l = restitution.portable_ln();
    -l / (T::PI() * T::PI() + l * l).sqrt()
}

/// c_n = 2ζ√(m* k_n).
pub fn normal_damping_coefficient<T: Real>(
    damping_ratio: T,
    effective_mass: T,
    normal_stiffness: T,
) -> T {
    T::lit(2.0) * damping_ratio * (effective_mass * normal_stiffness).sqrt()
}

/// m* = m_i m_j/(m_i + m_j); an infinite mass (a wall) gives m* = the other mass.
pub fn effective_mass<T: Real>(mass_i: T, mass_j: T) -> T {
    if mass_i.is_infinite() {
        return mass_j;
    }
    if mass_j.is_infinite() {
        return mass_i;
    }
    mass_i * mass_j / (mass_i + mass_j)
}

/// Duration of a linear spring–dashpot collision: π/(ω₀√(1 − ζ²)), ω₀ = √(k_n/m*) (ζ < 1).
pub fn contact_duration<T: Real>(normal_stiffness: T, effective_mass: T, damping_ratio: T) -> T {
    let omega0 = (normal_stiffness / effective_mass).sqrt();
    T::PI() / (omega0 * (T::one() - damping_ratio * damping_ratio).sqrt())
}

/// The kinematic state of a body at a contact: centre, velocity, angular velocity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyState<T> {
    /// Centre (reference point of the angular velocity).
    pub position: Vector<T>,
    /// Velocity of the centre.
    pub velocity: Vector<T>,
    /// Angular velocity (counter-clockwise positive).
    pub angular_velocity: T,
}

impl<T: Real> BodyState<T> {
    /// The state of a particle.
    pub fn of(p: &Particle<T>) -> Self {
        BodyState {
            position: p.position,
            velocity: p.velocity,
            angular_velocity: p.angular_velocity,
        }
    }

    /// The state of a particle advanced by the central-difference scheme, with the velocity estimated at the
    /// force time t: v(t − Δt/2) + a(t − Δt) Δt/2 (second order; the particle stores a(t − Δt)).
    pub fn synchronous(p: &Particle<T>, dt: T) -> Self {
        let half = T::lit(0.5) * dt;
        BodyState {
            position: p.position,
            velocity: (p.velocity + (p.acceleration * half)),
            angular_velocity: p.angular_velocity + p.angular_acceleration * half,
        }
    }

    /// A fixed body (a wall) with reference point `position`.
    pub fn fixed(position: Vector<T>) -> Self {
        BodyState {
            position,
            velocity: Vector::zeros(),
            angular_velocity: T::zero(),
        }
    }

    /// Velocity of the material point at `x`: v + ω × (x − c).
    #[inline(always)]
    pub fn velocity_at(&self, x: Vector<T>) -> Vector<T> {
        self.velocity + (spin(self.angular_velocity, &(x - self.position)))
    }
}

/// Forces and torques of one contact (all zero for an inactive one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactForce<T> {
    /// Force on body i (= −`force_on_j`).
    pub force_on_i: Vector<T>,
    /// Force on body j.
    pub force_on_j: Vector<T>,
    /// Torque on body i about its centre.
    pub torque_on_i: T,
    /// Torque on body j about its centre.
    pub torque_on_j: T,
    /// Normal force F_n on j along the normal (≥ 0 with `no_tension`).
    pub normal_force: T,
    /// Shear force F_s on j along the tangent.
    pub shear_force: T,
    /// Whether the Coulomb cap was reached (sliding).
    pub sliding: bool,
    /// Whether the contact was active (overlap δ > 0): the law was applied. An active contact may still carry
    /// no force (a dashpot cancelling the spring under the no-tension clip).
    pub active: bool,
}

impl<T: Real> ContactForce<T> {
    /// No force.
    pub fn zero() -> Self {
        ContactForce {
            force_on_i: Vector::zeros(),
            force_on_j: Vector::zeros(),
            torque_on_i: T::zero(),
            torque_on_j: T::zero(),
            normal_force: T::zero(),
            shear_force: T::zero(),
            sliding: false,
            active: false,
        }
    }
}

/// Apply the linear contact law to one contact over a step `dt`, updating the shear history `shear`
/// (the shear force of the previous step; 0 for a new contact). An inactive contact (δ ≤ 0) gives no force
/// and resets `shear` to 0.
pub fn linear_contact_force<T: Real>(
    law: &ContactLaw<T>,
    contact: &Contact<T>,
    body_i: &BodyState<T>,
    body_j: &BodyState<T>,
    shear: &mut T,
    dt: T,
) -> ContactForce<T> {
    if !contact.is_active() {
        *shear = T::zero();
        return ContactForce::zero();
    }
    let n = contact.normal;
    let t = perp(&n);
    let x = contact.point;
    let v = body_j.velocity_at(x) - body_i.velocity_at(x);
    let mut normal_force = law.normal_stiffness * contact.overlap - law.normal_damping * v.dot(&n);
    if law.no_tension && (normal_force.is_nan() || normal_force <= T::zero()) {
        normal_force = T::zero();
    }
    let trial = *shear - law.shear_stiffness * v.dot(&t) * dt;
    let cap = law.friction * normal_force.max(T::zero());
    let (shear_force, sliding) = if trial.abs() > cap {
        (cap.copysign(trial), true)
    } else {
        (trial, false)
    };
    *shear = shear_force;
    let force_on_j = (n * normal_force) + (t * shear_force);
    let force_on_i = -force_on_j;
    ContactForce {
        force_on_i,
        force_on_j,
        torque_on_i: cross(&(x - body_i.position), &force_on_i),
        torque_on_j: cross(&(x - body_j.position), &force_on_j),
        normal_force,
        shear_force,
        sliding,
        active: true,
    }
}

/// PFC local damping force for one degree of freedom: −α |F_unbal| sign(v), zero when v = 0.
#[inline(always)]
pub fn local_damping<T: Real>(unbalanced: T, velocity: T, alpha: T) -> T {
    if velocity > T::zero() {
        -alpha * unbalanced.abs()
    } else if velocity < T::zero() {
        alpha * unbalanced.abs()
    } else {
        T::zero()
    }
}
