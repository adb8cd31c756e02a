//! The one Darcy measurement: a lattice driven to a steady flow by its boundaries or body force, stepped one
//! check interval at a time (so a run can be interrupted and resumed in the middle) until the monitored flux is
//! steady ([`Steadiness`]) or a step limit is reached, with the health check after every interval: a diverging
//! lattice or a non-finite flux stops the measurement with an error instead of running to the limit and
//! reporting a NaN permeability. Then Darcy's law gives the permeability, k = μ q L/Δp (lattice units:
//! μ = ν for ρ₀ = 1).
use lbdem_kernels::Real;
use serde::{Deserialize, Serialize};

use super::health::{finite, fluid_health};
use super::steady::Steadiness;
use crate::engine::lattice::FluidLattice;
use crate::error::Result;

/// A steady-flow measurement in progress.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SteadyFlow {
    /// The criterion.
    pub criterion: Steadiness,
    /// Steps between checks.
    pub interval: u64,
    /// Step limit.
    pub max_steps: u64,
    /// Steps done.
    pub steps: u64,
    /// The flux at the last check.
    pub flux: f64,
    /// Whether the criterion was met (false: the limit was reached first).
    pub steady: bool,
    /// Relative change of the flux per step when steadiness was declared (NaN before).
    pub drift_per_step: f64,
}

impl SteadyFlow {
    /// A measurement with the criterion, checking every `interval` steps, for at most `max_steps` steps.
    pub fn new(criterion: Steadiness, interval: u64, max_steps: u64) -> Self {
        Self {
            criterion,
            interval: interval.max(1),
            max_steps,
            steps: 0,
            flux: f64::NAN,
            steady: false,
            drift_per_step: f64::NAN,
        }
    }

    /// Whether the measurement is over (steady, or at the step limit).
    pub fn done(&self) -> bool {
        self.steady || self.steps >= self.max_steps
    }

    /// Step `lattice` one interval, check its health (`hint` says what to change when it diverged), then feed
    /// the flux `flux(lattice)`. Returns whether the measurement is over.
    pub fn advance<T: Real>(
        &mut self,
        lattice: &mut FluidLattice<T>,
        flux: impl Fn(&FluidLattice<T>) -> f64,
        hint: &str,
    ) -> Result<bool> {
        if self.done() {
            return Ok(true);
        }
        for _ in 0..self.interval {
            lattice.step();
        }
        self.steps += self.interval;
        fluid_health(lattice, hint)?;
        self.flux = finite("flux", flux(lattice), lattice.steps(), hint)?;
        if let Some(change) = self.criterion.update(self.flux) {
            self.steady = true;
            self.drift_per_step = change / self.interval as f64;
        }
        Ok(self.done())
    }
}

/// Darcy's law for the permeability: k = μ q L/Δp with q the superficial flux (volume per unit area and time),
/// L the length over which the pressure falls by Δp, μ the dynamic viscosity (any consistent units; in lattice
/// units μ = ν ρ₀ and Δp = c_s² Δρ = Δρ/3).
pub fn permeability(viscosity: f64, flux: f64, length: f64, pressure_drop: f64) -> f64 {
    viscosity * flux * length / pressure_drop
}
