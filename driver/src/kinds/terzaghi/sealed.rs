//! The sealed column (`[terzaghi] sealed_check = true`): the undrained response of the pack measured with its
//! grains free, before the drained run (issue 14, item 1: the loading efficiency γ = Δp/Δσ of a sealed sample
//! under a step load).
//!
//! A copy of the coupled column whose top is a lid instead of the drained reservoir, [`SEALED_FREE_ROWS`]
//! above the pack: the lattice's north side is a Zou–He velocity side moving at the loaded layer's vertical velocity (as if a piston rested on the layer
//! and sealed the free fluid rows above it), and the lid's fluid pressure is taken off the load the layer
//! carries (the total stress σ₀ is shared by the lid, i.e. the fluid, and the grains). So no fluid leaves: the
//! lid injects what the layer's descent makes room for, which is what a piston following the layer would push
//! into the column. The step load then splits into a pore pressure p and an effective stress σ₀ − p, the
//! undrained response, held (nothing drains) until measured. The matched dashpot of `load_dashpot` (factor 1)
//! absorbs the undrained wave.
//!
//! Measured, averaged over the last [`SEALED_WINDOW`] of [`SEALED_CROSSINGS`] sound-crossing times: the mean
//! pore pressure p over the pack's fluid-only row means and the layer's settlement s. The lid fills a dead
//! volume d (the free fluid rows between the pack and the lid, per unit width) besides the pores, so with the lattice's
//! storage β_f (n_s L + d) of the sealed fluid:
//! * the storage porosity with the grains free, n_s' = (s/(β_f p) − d)/L (mass balance: the fluid the lid
//!   injected, ρ₀ W s, is stored at the pressure p by the pores and the dead volume) — against the Darcy run's
//!   n_s, measured with the grains held;
//! * the undrained skeleton modulus K_u' = (σ₀ − p)/(s/L) — against the dry K_v;
//! * the sample's loading efficiency without the dead volume, γ' = 1/(1 + K_u' β_f n_s') — against the
//!   predicted γ = 1/(1 + K_v β_f n_s) (Biot α = 1, incompressible grains; Wang 2000);
//! * and, directly, p/σ₀ against the prediction with the dead volume, 1/(1 + K_v β_f (n_s L + d)/L).
use serde::{Deserialize, Serialize};

use lbdem_kernels::fluid::lattice::Side;
use lbdem_reference::poroelastic::{biot_modulus, loading_efficiency};

use super::{layer_height, layer_mean, LoadDashpot};
use crate::engine::coupled::CoupledWorld;
use crate::error::{LbdemError, Result};
use crate::observe::flow::fluid_row_means;
use crate::observe::health::finite;
use crate::units::{LatticeUnits, CS2};

/// Rows of free fluid between the pack's top and the lid (the lid's dead volume d = 2 spacings). Few: the dead
/// volume fills from the pack by Darcy flow only, over the column's diffusion time. With the drained lattice's
/// free layer (2 `radius_max`, 12 rows on the bundled column, 12 % of its storage) that left the sealed
/// column's pressure 1.2 × its mean at the base and 0.6–0.7 × at the top for as long as the run (with the step
/// and with a load ramped over 12 sound-crossing times alike: quasi-static, not a wave), and its mean ≈ 1 %
/// short of settled.
pub const SEALED_FREE_ROWS: usize = 2;
/// Length of the sealed run in sound-crossing times of the column: the matched dashpot takes the undrained
/// wave out within a few crossings; the rest is the measurement window and a margin.
pub const SEALED_CROSSINGS: f64 = 20.0;
/// The measurement window: the last this many sound-crossing times of the sealed run.
pub const SEALED_WINDOW: f64 = 8.0;
/// Samples of the pore pressure per sound-crossing time in the window.
const SAMPLES_PER_CROSSING: f64 = 4.0;

/// The sealed lid's velocity `v` (lattice units, the loaded layer's mean vertical velocity at step `step`) as a
/// velocity profile takes it: finite and below the lattice speed 1. Anything else is the column diverging,
/// reported as [`LbdemError::Diverged`] with `hint` (the side's own check would name a scene field,
/// `boundary.north.profile`, that no scene has).
fn lid_speed(v: f64, step: u64, hint: &str) -> Result<f64> {
    if v.is_finite() && v.abs() < 1.0 {
        return Ok(v);
    }
    Err(LbdemError::Diverged {
        step,
        quantity: "sealed lid velocity (the loaded layer's mean vertical velocity, lattice units)"
            .into(),
        value: format!("{v}"),
        x: crate::error::NO_NODE,
        y: crate::error::NO_NODE,
        out: String::new(),
        hint: hint.into(),
    })
}

/// What the sealed column measured (`prediction.sealed` in `summary.json`). Stresses and lengths physical.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SealedMeasurement {
    /// Mean pore pressure over the pack over the step load, p/σ₀ (the dead volume included).
    pub loading_efficiency: f64,
    /// Its prediction from K_v and the Darcy run's n_s with the dead volume, 1/(1 + K_v β_f (n_s L + d)/L).
    pub loading_efficiency_predicted: f64,
    /// The dead volume d the lid seals besides the pores: the free fluid rows' height.
    pub dead_volume: f64,
    /// Settlement of the loaded layer over the window (mean), s.
    pub settlement: f64,
    /// Storage porosity with the grains free, n_s' = (s/(β_f p) − d)/L (L: the pack's rows).
    pub storage_porosity: f64,
    /// Undrained skeleton modulus, (σ₀ − p)/(s/L).
    pub skeleton_modulus: f64,
    /// The sample's loading efficiency without the dead volume, 1/(1 + K_u' β_f n_s').
    pub sample_loading_efficiency: f64,
    /// Spread of the pack's row-mean pressures (max − min) at the end, over p: a sealed column at rest has one
    /// pressure; what is left after 20 crossings is the tail of the column's first pressure mode, set up by the
    /// step and relaxing by Darcy flow over about L²/(π² c_v) (README, *The sealed column*; see
    /// [`SEALED_FREE_ROWS`] for what a larger dead volume does to it).
    pub pressure_spread: f64,
    /// Change of the mean pressure from the window's first half to its second, over p (drift: a leak or a
    /// creeping skeleton).
    pub pressure_drift: f64,
    /// Coupled steps of the sealed run.
    pub steps: u64,
}

/// The sealed copy of the column and its sums.
#[derive(Serialize, Deserialize)]
pub(super) struct SealedRun {
    pub(super) world: CoupledWorld,
    dashpot: Option<LoadDashpot>,
    steps: u64,
    pub(super) s: u64,
    window_start: u64,
    sample_every: u64,
    layer_start: f64,
    /// Sums over the window's first and second halves: pressure, settlement, samples.
    halves: [(f64, f64, u64); 2],
    spread: f64,
    /// The last sample's row means: (row, pressure) (`sealed.csv`).
    #[serde(default)]
    pub(super) last: Vec<(usize, f64)>,
}

impl SealedRun {
    /// A sealed run of `world` (its north side a velocity profile at rest) lasting [`SEALED_CROSSINGS`] sound
    /// crossings of the column (`crossing_steps` fluid steps each).
    pub(super) fn new(world: CoupledWorld, crossing_steps: f64) -> Self {
        let steps = (SEALED_CROSSINGS * crossing_steps).ceil().max(40.0) as u64;
        let window = (SEALED_WINDOW * crossing_steps).ceil().max(20.0) as u64;
        let sample_every = ((crossing_steps / SAMPLES_PER_CROSSING).floor() as u64).max(1);
        Self {
            world,
            dashpot: None,
            steps,
            s: 0,
            window_start: steps.saturating_sub(window),
            sample_every,
            layer_start: f64::NAN,
            halves: [(0.0, 0.0, 0); 2],
            spread: 0.0,
            last: Vec::new(),
        }
    }

    /// Whether the run has taken all its steps.
    pub(super) fn done(&self) -> bool {
        self.s >= self.steps
    }

    /// Load the sealed column (the loaded layer's forces `after`, with the matched dashpot) at its first step.
    pub(super) fn load(&mut self, dashpot: LoadDashpot, loaded: &[usize]) {
        self.dashpot = Some(dashpot);
        self.layer_start = layer_height(&self.world.dem, loaded);
    }

    /// Up to 500 coupled steps. `after`: the loaded grains' forces under the step (isotropic stress + load);
    /// `total`: that vertical stress, which the lid's pressure is a share of.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn advance(
        &mut self,
        u: &LatticeUnits,
        loaded: &[usize],
        after: &[(lbdem_kernels::math::Vector<f64>, f64)],
        total: f64,
        nx: usize,
        pack_rows: usize,
        hint: &str,
    ) -> Result<()> {
        let end = (self.s + 500).min(self.steps);
        let mut lid = vec![[0.0; 2]; nx];
        for s in self.s + 1..=end {
            // The lid moves with the layer; its pressure (the Zou–He density of the north side, from the
            // populations it keeps) is taken off the layer's load.
            // The loaded layer's vertical velocity, weighted as its height is.
            let v = u.velocity_to_lattice(layer_mean(&self.world.dem, loaded, |g| g.velocity[1]));
            // A lid at or above the lattice speed (or not finite) is the column diverging, not a bad profile:
            // say so (the side's own check would name a scene field the user never wrote).
            lid_speed(v, s, hint)?;
            lid.fill([0.0, v]);
            self.world.fluid.set_side_profile(Side::North, &lid)?;
            let known = self
                .world
                .fluid
                .side_known_sum(Side::North)
                .unwrap_or(1.0 + v);
            let p_lid = u.pressure_to_physical(CS2 * (known / (1.0 + v) - 1.0));
            let share = 1.0 - finite("sealed lid pressure", p_lid, s, hint)? / total;
            // The dashpot's forces (none before `load`), read from the grains before the step.
            let dashpot = self
                .dashpot
                .iter()
                .flat_map(|d| d.forces(&self.world.dem, loaded))
                .chain(std::iter::repeat(0.0));
            for (&i, f) in loaded.iter().zip(dashpot) {
                let (base, m) = after[i];
                self.world.applied[i] = (base * share + lbdem_kernels::math::vector(0.0, f), m);
            }
            self.world.step();
            if s > self.window_start && (s - self.window_start).is_multiple_of(self.sample_every) {
                let eps = self.world.fluid.solid_fraction_map();
                let (rho, _) = self.world.fluid.moments();
                let rows = fluid_row_means(&rho, &eps, nx, 0..pack_rows);
                let ps: Vec<f64> = rows
                    .iter()
                    .map(|r| u.pressure_to_physical(CS2 * (r.1 - 1.0)))
                    .collect();
                let mean = ps.iter().sum::<f64>() / ps.len().max(1) as f64;
                let (lo, hi) = ps
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &p| {
                        (a.min(p), b.max(p))
                    });
                self.spread = (hi - lo) / mean.abs();
                self.last = rows.iter().map(|r| r.0).zip(ps.iter().copied()).collect();
                let settlement = self.layer_start - layer_height(&self.world.dem, loaded);
                let half =
                    usize::from(2 * (s - self.window_start) > self.steps - self.window_start);
                let h = &mut self.halves[half];
                h.0 += finite("sealed pore pressure", mean, s, hint)?;
                h.1 += settlement;
                h.2 += 1;
            }
        }
        self.s = end;
        Ok(())
    }

    /// The measurement, from the window's sums: `load` σ₀, `thickness` L (the strain's), `pack` the height of
    /// the pack's rows (the Darcy run's n_s is theirs), `beta` β_f, `dead` d, the dry K_v and the Darcy run's n_s.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn measurement(
        &self,
        load: f64,
        thickness: f64,
        pack: f64,
        beta: f64,
        dead: f64,
        drained_modulus: f64,
        storage_porosity: f64,
    ) -> SealedMeasurement {
        let mean = |k: usize| {
            let n: u64 = self.halves.iter().map(|h| h.2).sum();
            let s: f64 = self
                .halves
                .iter()
                .map(|h| if k == 0 { h.0 } else { h.1 })
                .sum();
            s / n as f64
        };
        let (p, settlement) = (mean(0), mean(1));
        let half = |h: &(f64, f64, u64)| h.0 / h.2 as f64;
        let strain = settlement / thickness;
        let n_s = (settlement / (beta * p) - dead) / pack;
        let k_u = (load - p) / strain;
        SealedMeasurement {
            loading_efficiency: p / load,
            // The lid's dead volume stores like pore fluid: an effective storage porosity over the column.
            loading_efficiency_predicted: loading_efficiency(
                biot_modulus((storage_porosity * pack + dead) / thickness, beta, 0.0, 1.0),
                1.0,
                drained_modulus,
            ),
            dead_volume: dead,
            settlement,
            storage_porosity: n_s,
            skeleton_modulus: k_u,
            sample_loading_efficiency: loading_efficiency(
                biot_modulus(n_s, beta, 0.0, 1.0),
                1.0,
                k_u,
            ),
            pressure_spread: self.spread,
            pressure_drift: (half(&self.halves[1]) - half(&self.halves[0])) / p,
            steps: self.s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lid_at_the_lattice_speed_is_divergence_not_a_bad_scene_field() {
        assert_eq!(lid_speed(-0.25, 3, "h").unwrap(), -0.25);
        for v in [1.0, -1.5, f64::NAN, f64::INFINITY] {
            let e = lid_speed(v, 7, "lower fluid.tau");
            // A lid's velocity is no node's: the message names none.
            let text = e.as_ref().map_err(|e| e.to_string()).unwrap_err();
            assert!(
                text.contains("run stopped at step 7: sealed lid velocity")
                    && !text.contains("at node"),
                "{text}"
            );
            match e {
                Err(LbdemError::Diverged {
                    step,
                    quantity,
                    hint,
                    ..
                }) => {
                    assert_eq!(step, 7);
                    assert!(quantity.contains("sealed lid velocity"), "{quantity}");
                    assert_eq!(hint, "lower fluid.tau");
                }
                other => panic!("v = {v}: {other:?}"),
            }
        }
    }
}
