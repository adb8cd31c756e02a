//! The snapshot series of a run with grains: when a snapshot is due ([`SnapshotClock`], checkpointed with the
//! run's state so that a resumed run writes the same snapshots with the same indices), and one snapshot of every
//! series at once ([`write_series`]: grains, bonds when the world has any, the lattice when there is one), each
//! file written atomically and recorded in its `.pvd` collection ([`super::pvd::write_snapshot`]). The files'
//! contents are the writers of [`super::vtk`].
//!
//! Snapshots are taken between chunks of the run loop, never inside a step: a kind calls
//! [`SnapshotClock::first_due`] before its first chunk and [`SnapshotClock::due`] after each one.
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::pvd::write_snapshot;
use super::vtk::{
    bonds_vtp, lattice_field, lattice_vti, particles_vtp, BreakClock, LatticeFrame, Stamp,
};
use crate::engine::coupled::CoupledWorld;
use crate::engine::dem::DemWorld;
use crate::error::Result;
use crate::units::{LatticeUnits, UnitSystem};

/// Which snapshots a run has written: checkpointed with the run's state.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SnapshotClock {
    written: usize,
    next_step: u64,
}

impl SnapshotClock {
    /// Snapshots written so far (the index of the next one).
    pub fn written(&self) -> usize {
        self.written
    }

    /// Whether the first snapshot (before the first step) is still to be written.
    pub fn first_due(&self) -> bool {
        self.written == 0
    }

    /// Whether a snapshot is due after a chunk that ended at step `step`, with one every `every` steps
    /// (0: only the first and the last): at the first chunk end at or after each multiple of `every`, and at
    /// the end of the run (`finished`).
    pub fn due(&self, step: u64, every: u64, finished: bool) -> bool {
        finished || (every > 0 && self.written > 0 && step >= self.next_step)
    }

    /// Record that snapshot [`Self::written`] was written at step `step`.
    pub fn mark(&mut self, step: u64, every: u64) {
        self.written += 1;
        self.next_step = step
            .checked_div(every)
            .map_or(u64::MAX, |k| k.saturating_add(1).saturating_mul(every));
    }
}

/// One chunk of a run with snapshots, in the cadence every such kind follows: the first snapshot before the
/// first chunk, then one after any chunk at whose end [`SnapshotClock::due`]. `at`: the run directory and the
/// steps between snapshots (`None`: the chunk only); `clock`: the state's clock, the step reached and whether
/// the run is finished; `snapshot`: write one (and [`SnapshotClock::mark`] it).
pub fn chunk_with_snapshots<S>(
    state: &mut S,
    at: Option<(&Path, u64)>,
    clock: impl Fn(&S) -> (&SnapshotClock, u64, bool),
    advance: impl FnOnce(&mut S) -> Result<()>,
    mut snapshot: impl FnMut(&mut S, &Path, u64) -> Result<()>,
) -> Result<()> {
    let Some((dir, every)) = at else {
        return advance(state);
    };
    if clock(state).0.first_due() {
        snapshot(state, dir, every)?;
    }
    advance(state)?;
    let (c, step, finished) = clock(state);
    if c.due(step, every, finished) {
        snapshot(state, dir, every)?;
    }
    Ok(())
}

/// Snapshot `index` of every series of a run: `particles` (with the fluid's loads on the grains when given),
/// `bonds` (when the world has bonds) and `lattice` (when given), all at `stamp.time`.
pub fn write_series<T: lbdem_kernels::Real>(
    dir: &Path,
    index: usize,
    stamp: &Stamp,
    dem: &DemWorld<T>,
    fluid: Option<&[([f64; 2], f64)]>,
    clock: BreakClock,
    lattice: Option<&super::vtk::Field>,
) -> Result<()> {
    let bytes = particles_vtp(stamp, dem, fluid);
    write_snapshot(dir, "particles", index, stamp.time, "vtp", &bytes)?;
    if !dem.bonds.is_empty() {
        let bytes = bonds_vtp(stamp, dem, clock);
        write_snapshot(dir, "bonds", index, stamp.time, "vtp", &bytes)?;
    }
    if let Some(f) = lattice {
        let bytes = lattice_vti(stamp, f);
        write_snapshot(dir, "lattice", index, stamp.time, "vti", &bytes)?;
    }
    Ok(())
}

/// Snapshot [`SnapshotClock::written`] of a coupled run (grains with the fluid's loads, bonds, lattice in
/// `frame`), then [`SnapshotClock::mark`]. Before the first coupled step the grains are mapped onto the lattice
/// first ([`CoupledWorld::map_grains`]; no result changes), so that the lattice's solid fraction shows them, and
/// the grains' contact loads are those the first step applies.
/// Break times count from the coupled world's first step.
pub fn write_coupled(
    dir: &Path,
    clock: &mut SnapshotClock,
    every: u64,
    step: u64,
    stamp: &Stamp,
    world: &mut CoupledWorld,
    frame: &LatticeFrame,
) -> Result<()> {
    if world.steps() == 0 {
        world.map_grains();
        // The contact loads the first step applies, whether or not this process stepped the DEM before (a
        // settling in the kind's start, absent after a resume): the snapshot is a function of the state.
        world.dem.forget_contact_loads();
    }
    let fluid = world.fluid_loads();
    let field = lattice_field(&world.fluid, frame);
    // Break times count from the coupled run's first step.
    let origin_step = world
        .dem
        .step_count()
        .saturating_sub(world.steps().saturating_mul(u64::from(world.substeps)));
    let breaks = BreakClock {
        origin_step,
        dt: world.dem.timestep() * stamp.units.scale.time,
    };
    write_series(
        dir,
        clock.written(),
        stamp,
        &world.dem,
        Some(&fluid),
        breaks,
        Some(&field),
    )?;
    clock.mark(step, every);
    Ok(())
}

/// [`write_coupled`] for a kind that runs in the scene's lattice units with pressure 0 at ρ₀ = 1: the snapshot
/// at `step` (model time `step` Δt), titled by the scene's `name` (`lbdem KIND` without one).
#[allow(clippy::too_many_arguments)]
pub fn write_coupled_at_step(
    dir: &Path,
    clock: &mut SnapshotClock,
    every: u64,
    step: u64,
    (name, kind, system): (Option<&str>, &str, UnitSystem),
    units: &LatticeUnits,
    world: &mut CoupledWorld,
) -> Result<()> {
    let stamp = Stamp::titled(step as f64 * units.timestep, name, kind, system);
    let frame = LatticeFrame::of(units, world.map.origin, 1.0);
    write_coupled(dir, clock, every, step, &stamp, world, &frame)
}
