//! Health of a running state: the first non-finite or out-of-band value, as the error that stops a run (the
//! run loop then writes the diverged state and the outputs so far).
use lbdem_kernels::Real;

use crate::engine::coupled::CoupledWorld;
use crate::engine::dem::DemWorld;
use crate::engine::lattice::FluidLattice;
use crate::error::{LbdemError, Result};

/// Lattice densities a healthy run stays within (the lattice fluid is weakly compressible: a density off by
/// 50 % is far outside the flows it approximates).
pub const DENSITY_BAND: (f64, f64) = (0.5, 1.5);

/// The first fluid node whose density is non-finite or outside [`DENSITY_BAND`], or whose velocity is not
/// finite, as [`LbdemError::Diverged`] (the run loop fills in the directory); `hint` says what to change.
pub fn fluid_health<T: Real>(lattice: &FluidLattice<T>, hint: &str) -> Result<()> {
    match lattice.health_check(DENSITY_BAND.0, DENSITY_BAND.1) {
        None => Ok(()),
        Some((n, rho)) => {
            let (x, y) = lattice.shape().coords(n);
            Err(LbdemError::Diverged {
                step: lattice.steps(),
                quantity: "lattice density".into(),
                value: format!("{rho}"),
                x,
                y,
                out: String::new(),
                hint: hint.into(),
            })
        }
    }
}

/// First particle whose position, angle, velocity or angular velocity is not finite, as
/// [`LbdemError::DivergedParticle`].
pub fn dem_health<T: Real>(world: &DemWorld<T>) -> Result<()> {
    for (i, p) in world.particles.iter().enumerate() {
        let checks = [
            ("x position", p.position[0]),
            ("y position", p.position[1]),
            ("angle", p.angle),
            ("x velocity", p.velocity[0]),
            ("y velocity", p.velocity[1]),
            ("angular velocity", p.angular_velocity),
        ];
        if let Some((q, v)) = checks.iter().find(|(_, v)| !v.is_finite()) {
            return Err(LbdemError::DivergedParticle {
                step: world.step_count(),
                particle: i,
                quantity: q.to_string(),
                value: format!("{}", v.to_f64_exact()),
                out: String::new(),
                hint: "reduce the time step (see `lbdem check` for the critical step) or the loading rate"
                    .into(),
            });
        }
    }
    Ok(())
}

/// The health of a coupled world: its fluid ([`fluid_health`], with `hint`), then its grains
/// ([`dem_health`]).
pub fn coupled_health<T: Real>(world: &CoupledWorld<T>, hint: &str) -> Result<()> {
    fluid_health(&world.fluid, hint)?;
    dem_health(&world.dem)
}

/// A measured value that must be finite (a flux, a mean pressure), as [`LbdemError::Diverged`] otherwise.
pub fn finite(quantity: &str, value: f64, step: u64, hint: &str) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(LbdemError::Diverged {
            step,
            quantity: quantity.into(),
            value: format!("{value}"),
            x: crate::error::NO_NODE,
            y: crate::error::NO_NODE,
            out: String::new(),
            hint: hint.into(),
        })
    }
}
