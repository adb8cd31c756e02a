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

use lbdem_kernels::dem::shape::Particle;
use lbdem_kernels::Real;

use super::pvd::write_snapshot;
use super::vtk::{
    bonds_vtp, fixed_particles_vtp, lattice_field, lattice_vti, particles_vtp, BreakClock,
    LatticeFrame, Stamp,
};
use crate::engine::coupled::CoupledWorld;
use crate::engine::dem::DemWorld;
use crate::engine::lattice::{FluidDisc, FluidLattice};
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
pub fn write_series<T: Real>(
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

/// Where and how a kind whose grains are held fixed in the fluid (`pressure_diffusion`, `porous_flow`,
/// `cylinder_array`) writes its snapshots ([`write_fixed`]): the run directory, the suffix of its series' names
/// (`""`: `particles.pvd`, `lattice.pvd`; `"_case3"`: `particles_case3.pvd`, … for case 3 of a sweep), the
/// title and unit system of the stamp, and the scene's lattice units (to turn the fluid's loads into them).
#[derive(Clone, Debug)]
pub struct FixedSnapshots<'a> {
    /// The run directory.
    pub dir: &'a Path,
    /// Appended to each series' name.
    pub suffix: String,
    /// The scene's name (`lbdem KIND` without one).
    pub name: Option<&'a str>,
    /// The kind.
    pub kind: &'a str,
    /// The scene's unit system (the labels).
    pub system: UnitSystem,
    /// The scene's lattice units.
    pub units: LatticeUnits,
}

impl<'a> FixedSnapshots<'a> {
    /// The snapshots of a run in `dir` of a scene of `kind` named `name`, in `system` and `units`.
    pub fn new(
        dir: &'a Path,
        (name, kind, system): (Option<&'a str>, &'a str, UnitSystem),
        units: LatticeUnits,
    ) -> Self {
        FixedSnapshots {
            dir,
            suffix: String::new(),
            name,
            kind,
            system,
            units,
        }
    }

    /// The series of case `k` of a sweep (`particles_caseK.pvd`, `lattice_caseK.pvd`; K from 0, the row of the
    /// kind's table).
    pub fn case(&self, k: usize) -> Self {
        FixedSnapshots {
            suffix: format!("_case{k}"),
            ..self.clone()
        }
    }
}

/// Snapshot `index` at model time `time` of `grains` held fixed (physical units; the velocities they hold) in
/// `lattice`, whose nodes lie as `frame` says: the grains with the fluid's force and torque on each of them from
/// the lattice's last step (0 before the first; [`FluidLattice::solid_forces_and_torques`], body k being grain
/// k, torques about the grains' centres) in the scene's units, and the lattice. Each file is written atomically
/// and recorded in its collection, as [`write_series`] does.
pub fn write_fixed<T: Real>(
    at: &FixedSnapshots,
    index: usize,
    time: f64,
    grains: &[Particle<f64>],
    lattice: &FluidLattice<T>,
    frame: &LatticeFrame,
) -> Result<()> {
    let stamp = Stamp::titled(time, at.name, at.kind, at.system);
    // The grains' centres in lattice coordinates (the inverse of the frame's node positions).
    let centers: Vec<_> = grains
        .iter()
        .map(|p| {
            lbdem_kernels::math::vector(
                (p.position[0] - frame.origin[0]) / frame.spacing,
                (p.position[1] - frame.origin[1]) / frame.spacing,
            )
        })
        .collect();
    let (forces, torques) = lattice.solid_forces_and_torques(&centers);
    let u = &at.units;
    let fluid: Vec<([f64; 2], f64)> = forces
        .iter()
        .zip(&torques)
        .map(|(f, &t)| {
            (
                [u.force_to_physical(f[0]), u.force_to_physical(f[1])],
                u.force_to_physical(t) * u.spacing,
            )
        })
        .collect();
    let bytes = fixed_particles_vtp(&stamp, grains, Some(&fluid));
    let particles = format!("particles{}", at.suffix);
    write_snapshot(at.dir, &particles, index, time, "vtp", &bytes)?;
    let field = lattice_field(lattice, frame);
    let bytes = lattice_vti(&stamp, &field);
    let series = format!("lattice{}", at.suffix);
    write_snapshot(at.dir, &series, index, time, "vti", &bytes)
}

/// A disc of the fluid lattice (lattice units) as a grain held fixed for [`write_fixed`]: centre and radius in
/// physical units (node (0, 0) at the origin, spacing `spacing`), at rest. Its mass is never written (a grain
/// held fixed has mass −1 in the files), so its density is a placeholder.
pub fn disc_grain(disc: &FluidDisc, spacing: f64) -> Particle<f64> {
    Particle::disc(
        lbdem_kernels::math::vector(disc.center[0] * spacing, disc.center[1] * spacing),
        disc.radius * spacing,
        1.0,
    )
}
