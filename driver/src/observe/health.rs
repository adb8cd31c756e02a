//! Health of a running state: the first non-finite or out-of-band value, as the error that stops a run (the
//! run loop then writes the diverged state and the outputs so far).
use lbdem_kernels::coupling::{BodyShape, CoupledBody};
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::lattice::Side;
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

/// The health of a coupled world: its fluid ([`fluid_health`], with `hint` and, when grains reach past the
/// lattice's sides, [`side_crossings`]' note), then its grains ([`dem_health`]).
pub fn coupled_health<T: Real>(world: &CoupledWorld<T>, hint: &str) -> Result<()> {
    fluid_health(&world.fluid, hint).map_err(|e| with_side_crossings(e, world))?;
    dem_health(&world.dem)
}

/// `e` with [`side_crossings`]' note for `world` added to its hint, when `e` is a divergence (the note is made
/// only then: a healthy check costs nothing more).
pub fn with_side_crossings<T: Real>(mut e: LbdemError, world: &CoupledWorld<T>) -> LbdemError {
    if let LbdemError::Diverged { hint, .. } = &mut e {
        hint.push_str(&side_crossings(world));
    }
    e
}

/// How far past the edge of a non-periodic side's cells (half a spacing outside its edge nodes) a grain must
/// reach, as the fluid sees it, to count as crossing that side, in lattice spacings: half a spacing more, i.e.
/// beyond the centres of the nodes outside the lattice. A grain resting on a wall at the lattice's side
/// reaches past it by its contact overlap only, far less.
pub const SIDE_CROSSING_MARGIN: f64 = 0.5;

/// The grains of `bodies` (lattice units, as the fluid sees them) that reach more than [`SIDE_CROSSING_MARGIN`]
/// past a non-periodic side of an `nx` × `ny` lattice with sides `bc`: (grain, the first such side in the order
/// west, east, south, north).
pub fn grains_past_sides<T: Real>(
    bodies: &[CoupledBody<f64>],
    bc: &Boundaries<T>,
    nx: usize,
    ny: usize,
) -> Vec<(usize, Side)> {
    let edge = 0.5 + SIDE_CROSSING_MARGIN;
    let open = |side| bc.side(side) != SideCondition::Periodic;
    bodies
        .iter()
        .enumerate()
        .filter_map(|(i, b)| {
            // Half-extents of the shape along x and y (exact for an ellipse at its angle).
            let (hx, hy) = match b.shape {
                BodyShape::Disc { radius } => (radius, radius),
                BodyShape::Ellipse {
                    semi_major: a,
                    semi_minor: c,
                    angle,
                } => {
                    let (sin, cos) = angle.sin_cos();
                    (
                        ((a * cos).powi(2) + (c * sin).powi(2)).sqrt(),
                        ((a * sin).powi(2) + (c * cos).powi(2)).sqrt(),
                    )
                }
            };
            let (x, y) = (b.center[0], b.center[1]);
            [
                (Side::West, x - hx < -edge),
                (Side::East, x + hx > (nx - 1) as f64 + edge),
                (Side::South, y - hy < -edge),
                (Side::North, y + hy > (ny - 1) as f64 + edge),
            ]
            .into_iter()
            .find(|&(side, past)| past && open(side))
            .map(|(side, _)| (i, side))
        })
        .collect()
}

/// The side condition `c` in words, for messages.
fn side_words<T>(c: SideCondition<T>) -> &'static str {
    match c {
        SideCondition::Periodic => "periodic",
        SideCondition::Wall => "wall",
        SideCondition::MovingWall { .. } => "moving wall",
        SideCondition::Pressure { .. } => "Zou-He pressure",
        SideCondition::Velocity { .. } | SideCondition::VelocityProfile => "Zou-He velocity",
    }
}

/// A note for a divergence hint when grains of `world` reach past the lattice's non-periodic sides
/// ([`grains_past_sides`]), else nothing: with solids sweeping through a wall or Zou–He side every solid
/// operator was measured to diverge (README, *ΩΛ's wall-pressure form*, the moving-bodies stress case).
pub fn side_crossings<T: Real>(world: &CoupledWorld<T>) -> String {
    let shape = world.fluid.shape();
    let bc = world.fluid.boundaries();
    let past = grains_past_sides(&world.bodies(), bc, shape.nx, shape.ny);
    let Some(&(first, side)) = past.first() else {
        return String::new();
    };
    format!(
        "; {} grain(s) reach past the lattice's sides (first: grain {first} past the {} side ({})), and \
         solids crossing a wall or Zou-He side were measured to diverge under every solid operator: keep the \
         grains inside the lattice (DEM walls or platens at its sides, or more fluid margin) or make that axis \
         periodic",
        past.len(),
        format!("{side:?}").to_lowercase(),
        side_words(bc.side(side)),
    )
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
