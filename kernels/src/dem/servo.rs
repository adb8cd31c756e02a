//! Servo-controlled walls (the PFC servo; Itasca, *PFC2D manual*, "servo-control of walls"): each step the wall
//! moves along its inward normal at the speed that drives the stress it measures towards a target,
//!
//!   v = G (σ_target − σ),   G = λ L/(k_n N_c Δt),   |v| ≤ v_max,
//!
//! with L the wall's loaded length, k_n the contact normal stiffness, N_c the wall's active contacts (at least 1)
//! and λ ∈ (0, 1] the relaxation factor: with G so chosen, one step of the wall changes the stress by λ times the
//! error (N_c contacts of stiffness k_n over the length L), so λ < 1 approaches the target without overshoot.
//!
//! Units: consistent (stress = force/length per unit thickness in 2-D; speed = length/time).
use crate::Real;

/// The servo law of one wall.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(bound(
        serialize = "T: crate::Real + serde::Serialize",
        deserialize = "T: crate::Real + serde::Deserialize<'de>"
    ))
)]
pub struct ServoLaw<T> {
    /// Stress to hold (compression positive).
    pub target_stress: T,
    /// Relaxation factor λ in (0, 1] (PFC uses ≈ 0.5).
    pub relaxation: T,
    /// Speed limit v_max.
    pub max_speed: T,
}

impl<T: Real> ServoLaw<T> {
    /// The wall speed (positive into the sample) for the measured `stress` on a wall of loaded `length` with
    /// `contacts` active contacts of normal stiffness `normal_stiffness`, over a step `dt`.
    pub fn speed(&self, stress: T, length: T, normal_stiffness: T, contacts: usize, dt: T) -> T {
        let contacts = T::lit(contacts.max(1) as f64);
        let gain = self.relaxation * length / (normal_stiffness * contacts * dt);
        let v = gain * (self.target_stress - stress);
        v.max(-self.max_speed).min(self.max_speed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_step_removes_lambda_of_the_stress_error_and_the_speed_is_capped() {
        let law = ServoLaw {
            target_stress: 50.0,
            relaxation: 0.5,
            max_speed: 1e3,
        };
        let (length, kn, contacts, dt) = (2.0, 1e5, 4, 1e-5);
        let stress = 30.0;
        let v = law.speed(stress, length, kn, contacts, dt);
        // The wall moves v dt into the sample; N_c springs of k_n over L raise the stress by N_c k_n v dt / L.
        let rise = contacts as f64 * kn * v * dt / length;
        assert!((rise - 0.5 * (50.0 - stress)).abs() < 1e-9, "{rise}");
        // Above the target it backs off; far from it the speed limit holds; no contact counts as one.
        assert!(law.speed(70.0, length, kn, contacts, dt) < 0.0);
        assert_eq!(law.speed(-1e9, length, kn, contacts, dt), 1e3);
        assert_eq!(
            law.speed(stress, length, kn, 0, dt),
            law.speed(stress, length, kn, 1, dt)
        );
    }
}
