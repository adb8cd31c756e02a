//! `kind = "terminal_velocity"`: a free disc under a constant force in a periodic box (dissertation §4.5.4;
//! the coupled step's momentum balance and the drag on a moving grain).
//!
//! One free disc (solid fraction c = πa²/l²) in a periodic l × l box is pushed along x by a constant applied
//! force F_a, and the fluid by the opposite body force −F_a spread over its nodes as the Guo force density g,
//! weighted by 1 − B at covered nodes like every PSM body force: g = −F_a/Σ_n(1 − B_n) at the initial coverage.
//! The net external impulse per step, F_a + g Σ_n (1 − B_n), is then ≈ 0 (exactly 0 at the initial coverage;
//! the coverage of a moving disc changes a little), so the system reaches a steady state in the lab frame
//! instead of accelerating for ever (a periodic box with a net force has no terminal velocity, only a terminal
//! slip). *Momentum*: the PSM hands the grain exactly what the fluid loses and the leapfrog turns it into m Δv,
//! so fluid + grain momentum changes each step by exactly the applied impulse F_a + g Σ_n (1 − B_n) (roundoff;
//! tested). *Terminal slip*: at steady state the disc moves at V relative to the fluid. A uniform force density
//! g on the fluid is a mean pressure gradient G = |g|, so Sangani & Acrivos's drag per cylinder is F = G l²
//! (not F_a = G Σ(1 − B) ≈ G(1 − c)l²: the difference is the "buoyancy" G πa² of the mean gradient, which the
//! held cylinder of S&A feels and the body-force-driven disc does not), and U is the **superficial** slip
//! velocity U = Σ_n (1 − ε_n)(u_x,n − V)/l². F/(μU) is compared with S&A's table
//! ([`lbdem_reference::analytic::SANGANI_ACRIVOS_SQUARE`]).
use std::path::Path;

use lbdem_kernels::coupling::{BodyShape, CoupledBody};
use lbdem_kernels::dem::shape::Particle;
use lbdem_kernels::fluid::boundary::Boundaries;
use lbdem_kernels::fluid::collide::{
    lambda_weighting, weighting, Collision, SolidOperator, Weighting,
};
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_reference::analytic::sangani_acrivos_drag;
use serde::{Deserialize, Serialize};

use crate::engine::coupled::{CoupledWorld, LatticeMap};
use crate::engine::dem::elastic_contact;
use crate::engine::dem::DemWorld;
use crate::engine::exec::{Exec, ExecTarget};
use crate::engine::lattice::FluidLattice;
use crate::error::{positive, LbdemError, Result};
use crate::input::limits::{self, Budget};
use crate::observe::health::coupled_health;
use crate::output::snapshots::{chunk_with_snapshots, write_coupled, SnapshotClock};
use crate::output::vtk::{LatticeFrame, Scale, Stamp};
use crate::output::{csv, write_atomic};
use crate::run::{run_in_memory, Case, Kind, OutputStage, Persist, RunOptions};
use crate::scene::{
    free_grain_choice, CheckpointSection, FreeGrains, SceneHeader, SnapshotSection, UnitsSetup,
};
use crate::units::{collision_of, CollisionName, FluidSection, Warnings};

/// The default fluid collision and the solid operator of a terminal-velocity scene at relaxation time `tau`
/// ([`free_grain_choice`]): without `solid_operator`, TRT + ΩΛ where ΩΛ is stable with the scene's grain (the
/// bundled scenes' rock grain, ρs/ρf = 2.65, at every τ up to 2), chosen because its free-disc drag does not move
/// with τ (README, "Moving solids, every operator": +0.45 / +0.45 / +0.44 / +0.42 % at τ = 0.55 / 0.8 / 1.2 / 2,
/// where Ω₁ with BGK, the earlier default, gives +0.49 / −1.20 / −3.86 / −10.41 %); else Ω₁ₗ with BGK, warned.
pub fn fluid_choice(
    scene: &TerminalVelocityScene,
    tau: f64,
    warnings: &mut Warnings,
) -> (CollisionName, SolidOperator) {
    let t = &scene.terminal_velocity;
    free_grain_choice(
        t.solid_operator,
        tau,
        FreeGrains::lone(t.grain_density / scene.fluid.density).in_form(scene.fluid.lambda_form),
        warnings,
    )
}

/// `[terminal_velocity]`
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TerminalVelocitySection {
    /// Side l of the periodic box.
    pub cell: f64,
    /// Solid fraction c = πa²/l² (sets the disc radius).
    pub solid_fraction: f64,
    /// Grain density (mass per area of the unit-thickness disc).
    pub grain_density: f64,
    /// Force per unit thickness applied to the disc along x.
    pub applied_force: f64,
    /// Model time simulated.
    pub duration: f64,
    /// Fraction of the run (at its end) over which the slip is averaged (default 0.2).
    #[serde(default)]
    pub average_fraction: Option<f64>,
    /// Solid operator: "lambda_consistent" (ΩΛ, B = ε, with TRT: the default where it is stable, see
    /// [`fluid_choice`]), "non_equilibrium_bounce_back" (Ω₁) or "linearized_non_equilibrium_bounce_back" (Ω₁ₗ;
    /// with BGK unless `[fluid] collision` says otherwise). Ω₃ ("moving_wall_bounce_back", see
    /// [`omega3_free_grain_growth`]) and Ω₂ ("superposition", leaks through moving solids) are refused for a free
    /// grain, and ΩΛ for light grains at high τ ([`check_free_grain_operator`]).
    #[serde(default)]
    pub solid_operator: Option<SolidOperator>,
}

/// A terminal-velocity scene file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TerminalVelocityScene {
    /// `[scene]`
    pub scene: SceneHeader,
    /// `[fluid]`
    pub fluid: FluidSection,
    /// `[terminal_velocity]`
    pub terminal_velocity: TerminalVelocitySection,
    /// `[output]`: VTK snapshots.
    #[serde(default)]
    pub output: SnapshotSection,
    /// `[run]`
    #[serde(default)]
    pub run: CheckpointSection,
}

crate::scene::scene_file!(TerminalVelocityScene);

/// Outcome of a terminal-velocity run (lattice units unless said).
#[derive(Clone, Debug, Serialize)]
pub struct TerminalOutcome {
    /// Box side (nodes).
    pub cell: usize,
    /// Disc radius (nodes).
    pub radius: f64,
    /// Solid fraction πa²/l².
    pub solid_fraction: f64,
    /// Applied force on the disc.
    pub applied_force: f64,
    /// Body-force density on the fluid (negative: opposes the disc's force).
    pub fluid_force_density: f64,
    /// Steps run.
    pub steps: u64,
    /// Mean superficial slip over the averaging window.
    pub slip: f64,
    /// Relative change of the window-mean slip between the two halves of the window (steadiness).
    pub slip_drift: f64,
    /// Disc velocity at the end.
    pub disc_velocity: f64,
    /// F/(μU) with F = |g| l², μ = ρ₀ν, U the superficial slip.
    pub drag: f64,
    /// S&A's F/(μU) at this solid fraction.
    pub sangani_acrivos: f64,
    /// drag / S&A − 1.
    pub drag_error: f64,
    /// Largest |total momentum − initial − accumulated applied impulse| over the run, relative to the
    /// accumulated |F_a| t.
    pub momentum_error: f64,
    /// Slip Reynolds number U·2a/ν.
    pub reynolds: f64,
    /// Terminal disc velocity in physical units.
    pub disc_velocity_physical: f64,
    /// (step, disc velocity, superficial slip, total momentum x, accumulated applied impulse x).
    pub records: Vec<[f64; 5]>,
}

/// The run: the coupled world and what is accumulated step by step.
#[derive(Serialize, Deserialize)]
pub struct TerminalState {
    world: CoupledWorld,
    cell: usize,
    radius: f64,
    force: f64,
    g: f64,
    steps: u64,
    p0: f64,
    impulse: f64,
    momentum_error: f64,
    record_every: u64,
    window_start: u64,
    records: Vec<[f64; 5]>,
    window: Vec<f64>,
    done: u64,
    snapshots: SnapshotClock,
}

impl Persist for TerminalState {}

/// Σ_n (1 − B_n): the weight of the fluid's body force over the nodes (Guo forcing scaled by 1 − B), B the
/// weighting `wf` of the solid operator `op` (ΩΛ's in its τ-free form).
pub fn fluid_weight(
    eps: &[f64],
    tau: f64,
    op: SolidOperator,
    wf: Weighting,
    collision: Collision<f64>,
) -> f64 {
    match (op, collision.rates(tau)) {
        (SolidOperator::LambdaConsistent, Ok(rates)) => eps
            .iter()
            .map(|&e| {
                // ΩΛ's fully covered nodes (ε ≥ 1 − LAMBDA_FULL_GAP) take no body force.
                if lbdem_kernels::fluid::collide::lambda_fully_covered(e) {
                    0.0
                } else {
                    1.0 - lambda_weighting(wf, e, rates)
                }
            })
            .sum(),
        _ => eps.iter().map(|&e| 1.0 - weighting(wf, e, tau)).sum(),
    }
}

/// Fluid + grain momentum along x.
pub fn total_momentum(w: &CoupledWorld) -> f64 {
    w.fluid.momentum()[0] + w.dem.particles[0].mass * w.dem.particles[0].velocity[0]
}

/// This kind's world in lattice units: a free disc of radius `radius` and areal density `density` (relative to
/// ρ₀) slightly off the centre of a periodic `n` × `n` lattice at relaxation time `tau`, pushed along x by
/// `force`, the fluid driven by the body force g that balances `force` at the initial coverage (so that the
/// total momentum changes only through the exchange). Public so that tests run the same set-up with other
/// collision and solid operators. Returns the world and g.
#[allow(clippy::too_many_arguments)]
pub fn free_disc_world(
    n: usize,
    radius: f64,
    density: f64,
    tau: f64,
    force: f64,
    collision: Collision<f64>,
    op: SolidOperator,
    wf: Weighting,
) -> Result<(CoupledWorld, f64)> {
    let l = n as f64;
    // The disc in lattice coordinates (the DEM runs in lattice units through LatticeMap::identity).
    let center = [0.5 * l - 0.25, 0.5 * l + 0.15];
    let disc = Particle::disc(lbdem_kernels::math::Vector::from(center), radius, density);
    let mass = disc.mass;
    // No contacts exist; the stiffness only enters the DEM's critical-step check, kept far above Δt = 1.
    let model = elastic_contact(1e-6 * mass, 1e-6 * mass, 0.0);
    // Body-force density balancing the applied force at the initial coverage.
    let body = CoupledBody {
        center: lbdem_kernels::math::Vector::from(center),
        velocity: lbdem_kernels::math::Vector::zeros(),
        spin: 0.0,
        shape: BodyShape::Disc { radius },
    };
    let mut probe = FluidLattice::<f64>::new(
        n,
        n,
        Boundaries::periodic(),
        FluidParams {
            tau,
            force: [0.0; 2],
        },
    )?;
    probe.cover_with_bodies(&[body], wf);
    let g = -force / fluid_weight(&probe.solid_fraction_map(), tau, op, wf, collision);
    let mut fluid = FluidLattice::<f64>::new(
        n,
        n,
        Boundaries::periodic(),
        FluidParams {
            tau,
            force: [g, 0.0],
        },
    )?;
    fluid.set_collision(collision)?;
    fluid.set_solid_operator(op);
    let mut dem = DemWorld::new(vec![disc], model, 1.0)?;
    dem.local_damping = 0.0; // local damping is an external momentum sink (it removes momentum from the system: Cundall 1987)
    let mut world = CoupledWorld::new(fluid, dem, LatticeMap::identity(), 1.0, wf, 1)?;
    world.applied[0] = (lbdem_kernels::math::vector(force, 0.0), 0.0);
    Ok((world, g))
}

fn start(case: &Case<TerminalVelocity>, exec: &Exec) -> Result<TerminalState> {
    let t = &case.scene.terminal_velocity;
    let u = &case.setup.units;
    let n = u.length_to_lattice(t.cell).round() as usize;
    let l = n as f64;
    let radius = l * (t.solid_fraction / std::f64::consts::PI).sqrt();
    let tau = u.tau;
    let force = u.force_to_lattice(t.applied_force);
    let steps = u.time_to_steps(t.duration).round().max(1.0) as u64;
    let (default_collision, op) = fluid_choice(&case.scene, tau, &mut Warnings::default());
    let collision = collision_of(case.scene.fluid.checked_collision(default_collision, tau)?)?;
    let density = t.grain_density / case.scene.fluid.density; // areal density relative to ρ₀ (lattice mass / node)
    let (mut world, g) = free_disc_world(
        n,
        radius,
        density,
        tau,
        force,
        collision,
        op,
        op.weighting(),
    )?;
    exec.apply(&mut world.fluid);
    world
        .fluid
        .set_lambda_terms(case.scene.fluid.lambda_terms(op)?)?;
    let p0 = total_momentum(&world);
    Ok(TerminalState {
        world,
        cell: n,
        radius,
        force,
        g,
        steps,
        p0,
        impulse: 0.0,
        momentum_error: 0.0,
        record_every: (steps / 400).max(1),
        window_start: steps - ((steps as f64 * t.average_fraction.unwrap_or(0.2)) as u64).max(2),
        records: Vec::new(),
        window: Vec::new(),
        done: 0,
        snapshots: SnapshotClock::default(),
    })
}

impl TerminalState {
    /// Up to 500 steps, accumulating the impulse, the momentum error, the records and the averaging window.
    fn advance(&mut self, case: &Case<TerminalVelocity>) {
        let tau = case.setup.units.tau;
        let op = self.world.fluid.solid_operator();
        let collision = self.world.fluid.collision();
        let l = self.cell as f64;
        let (force, g) = (self.force, self.g);
        let end = ((self.done / 500 + 1) * 500).min(self.steps);
        let world = &mut self.world;
        for s in self.done + 1..=end {
            let (p0, window_start, record_every) = (self.p0, self.window_start, self.record_every);
            let impulse = &mut self.impulse;
            let momentum_error = &mut self.momentum_error;
            let (records, window) = (&mut self.records, &mut self.window);
            world.step();
            let eps = world.fluid.solid_fraction_map();
            *impulse += force + g * fluid_weight(&eps, tau, op, op.weighting(), collision);
            let p = total_momentum(world);
            *momentum_error = momentum_error.max((p - p0 - *impulse).abs());
            let in_window = s > window_start;
            if s.is_multiple_of(record_every) || in_window {
                let v = world.dem.particles[0].velocity[0];
                let (_, vel) = world.fluid.moments();
                let slip: f64 = eps
                    .iter()
                    .zip(&vel)
                    .map(|(e, u)| (1.0 - e) * (u[0] - v))
                    .sum::<f64>()
                    / (l * l);
                if in_window {
                    window.push(-slip);
                }
                if s.is_multiple_of(record_every) {
                    records.push([s as f64, v, -slip, p, *impulse]);
                }
            }
        }
        self.done = end;
    }

    fn outcome(&self, case: &Case<TerminalVelocity>) -> TerminalOutcome {
        let t = &case.scene.terminal_velocity;
        let nu = case.setup.units.lattice_viscosity;
        let (n, radius, force, g, steps) = (self.cell, self.radius, self.force, self.g, self.steps);
        let l = n as f64;
        let (window, momentum_error, world) = (&self.window, self.momentum_error, &self.world);
        let records = self.records.clone();
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
        let slip = mean(window);
        let half = window.len() / 2;
        let slip_drift = (mean(&window[half..]) - mean(&window[..half])) / slip;
        let drag = g.abs() * l * l / (nu * slip);
        // validate() keeps the solid fraction inside the S&A table.
        let sa = sangani_acrivos_drag(t.solid_fraction).unwrap_or(f64::NAN);
        let v_end = world.dem.particles[0].velocity[0];
        TerminalOutcome {
            cell: n,
            radius,
            solid_fraction: std::f64::consts::PI * radius * radius / (l * l),
            applied_force: force,
            fluid_force_density: g,
            steps,
            slip,
            slip_drift,
            disc_velocity: v_end,
            drag,
            sangani_acrivos: sa,
            drag_error: drag / sa - 1.0,
            momentum_error: momentum_error / (force * steps as f64),
            reynolds: slip * 2.0 * radius / nu,
            disc_velocity_physical: case.setup.units.velocity_to_physical(v_end),
            records,
        }
    }
}

/// Growth factor per step of the grain/interior-fluid mode of a free grain under Ω₃ in the explicit coupled
/// step, for interior (fully covered) fluid mass `interior_mass` and grain mass `grain_mass`.
///
/// With B = 1, Ω₃ turns the interior momentum j into −j + 2M V (moving-wall bounce-back of every population)
/// and hands the grain 2(j − M V); the grain then moves by that over m. The linear map (j, V) →
/// (−j + 2MV, V + 2(j − MV)/m) has eigenvalues 1 (common motion) and −(1 + 2M/m), unstable for any M > 0.
/// Ω₁ sets j to M V and hands over j − MV: eigenvalues 1 and −M/m, stable while the grain outweighs the fluid
/// it covers.
pub fn omega3_free_grain_growth(interior_mass: f64, grain_mass: f64) -> f64 {
    -(1.0 + 2.0 * interior_mass / grain_mass)
}

/// Run a terminal-velocity case in memory to its end.
pub fn simulate(case: &Case<TerminalVelocity>) -> Result<TerminalOutcome> {
    let (state, _) = run_in_memory(case, &RunOptions::default())?;
    Ok(state.outcome(case))
}

const SERIES: [&str; 5] = [
    "step",
    "disc_velocity",
    "superficial_slip",
    "total_momentum_x",
    "applied_impulse_x",
];

/// The terminal-velocity kind.
pub struct TerminalVelocity;

impl Kind for TerminalVelocity {
    const NAME: &'static str = "terminal_velocity";
    const OWN_SECTION: Option<&'static str> = Some("terminal_velocity");
    type Scene = TerminalVelocityScene;
    type Setup = UnitsSetup;
    type State = TerminalState;

    fn validate(scene: &TerminalVelocityScene) -> Result<()> {
        scene.scene.require_f64()?;
        scene.output.validate()?;
        let u = scene.fluid.lattice_units()?;

        let t = &scene.terminal_velocity;
        positive("terminal_velocity.cell", t.cell, "box side l")?;
        positive(
            "terminal_velocity.grain_density",
            t.grain_density,
            "e.g. 2.65 g/cm^3",
        )?;
        positive(
            "terminal_velocity.applied_force",
            t.applied_force,
            "force per unit thickness along x",
        )?;
        positive("terminal_velocity.duration", t.duration, "model time")?;
        if !(t.solid_fraction > 0.0 && t.solid_fraction < 0.6) {
            return Err(LbdemError::field(
                "terminal_velocity.solid_fraction",
                t.solid_fraction,
                "must lie in (0, 0.6): the disc must fit its periodic box with a resolved gap",
                "the S&A table covers 0.05 ... 0.75; 0.2 is a good test",
            ));
        }
        if u.length_to_lattice(t.cell) < 16.0 {
            return Err(LbdemError::field(
                "terminal_velocity.cell",
                t.cell,
                "is fewer than 16 lattice spacings",
                "refine fluid.spacing or enlarge the box",
            ));
        }
        if let Some(f) = t.average_fraction {
            if !(f > 0.0 && f <= 0.5) {
                return Err(LbdemError::field(
                    "terminal_velocity.average_fraction",
                    f,
                    "must lie in (0, 0.5]",
                    "e.g. 0.2",
                ));
            }
        }
        Ok(())
    }

    fn budget(scene: &TerminalVelocityScene, setup: &UnitsSetup) -> Result<Budget> {
        let t = &scene.terminal_velocity;
        let u = &setup.units;
        let n = limits::count(
            "terminal_velocity.cell",
            "the box side in nodes",
            u.length_to_lattice(t.cell),
        )?;
        let steps = limits::steps_for("terminal_velocity.duration", t.duration, u.timestep, false)?;
        if steps < 10 {
            return Err(LbdemError::field(
                "terminal_velocity.duration",
                t.duration,
                &format!("is only {steps} fluid step(s) of {:e}", u.timestep),
                "run for many viscous times of the box (thousands of steps)",
            ));
        }
        scene.output.budget(u.timestep, steps)?;
        let mut b = Budget::new();
        limits::lattice(
            &mut b,
            "terminal_velocity.cell",
            "periodic lattice",
            n,
            n,
            8,
            limits::Solids::Covered,
        )?;
        // The probe lattice of the start-up, and the records of the averaging window (one per step at most).
        limits::lattice(
            &mut b,
            "terminal_velocity.cell",
            "start-up probe lattice",
            n,
            n,
            8,
            limits::Solids::Covered,
        )?;
        b.add_items("records", "terminal_velocity.duration", steps, 64)?;
        Ok(b)
    }

    fn setup(scene: &TerminalVelocityScene) -> Result<UnitsSetup> {
        UnitsSetup::with_free_grains(
            &scene.fluid,
            "terminal_velocity.solid_operator",
            FreeGrains::lone(scene.terminal_velocity.grain_density / scene.fluid.density)
                .in_form(scene.fluid.lambda_form),
            |tau, w| fluid_choice(scene, tau, w),
        )
    }

    fn describe(case: &Case<Self>) -> String {
        let labels = case.scene.scene.units.labels();
        case.setup.describe(labels)
            + &{
                let t = &case.scene.terminal_velocity;
                let u = &case.setup.units;
                let mut s = String::new();
                let n = u.length_to_lattice(t.cell).round();
                s += &format!(
                "  box {n} x {n} nodes (periodic), disc radius {:.3} nodes, applied force {:.4e} (lattice), {} steps\n",
                n * (t.solid_fraction / std::f64::consts::PI).sqrt(),
                u.force_to_lattice(t.applied_force),
                u.time_to_steps(t.duration).round()
            );
                s
            }
    }

    fn start(case: &Case<Self>, exec: &Exec) -> Result<TerminalState> {
        start(case, exec)
    }

    fn lattices(state: &mut TerminalState) -> Vec<&mut dyn ExecTarget> {
        vec![&mut state.world.fluid]
    }

    fn steps_done(state: &TerminalState) -> u64 {
        state.done
    }

    fn total_steps(_case: &Case<Self>, state: &TerminalState) -> Option<u64> {
        Some(state.steps)
    }

    fn finished(_case: &Case<Self>, state: &TerminalState) -> bool {
        state.done >= state.steps
    }

    fn advance(case: &Case<Self>, state: &mut TerminalState, dir: Option<&Path>) -> Result<()> {
        let u = case.setup.units;
        let every = case.scene.output.every(u.timestep, state.steps);
        // The disc and the fluid are simulated in lattice units: the files are in the scene's units.
        let snapshot = |state: &mut TerminalState, dir: &Path, every: u64| {
            let h = &case.scene.scene;
            let stamp = Stamp::titled(
                state.done as f64 * u.timestep,
                h.name.as_deref(),
                &h.kind,
                h.units,
            );
            let stamp = Stamp {
                units: stamp.units.scaled(Scale::lattice(&u)),
                ..stamp
            };
            write_coupled(
                dir,
                &mut state.snapshots,
                every,
                state.done,
                &stamp,
                &mut state.world,
                &LatticeFrame::of(&u, [0.0; 2], 1.0),
            )
        };
        chunk_with_snapshots(
            state,
            dir.zip(every),
            |s| (&s.snapshots, s.done, s.done >= s.steps),
            |s| {
                s.advance(case);
                Ok(())
            },
            snapshot,
        )
    }

    fn health(_case: &Case<Self>, state: &TerminalState) -> Result<()> {
        coupled_health(&state.world, "lower terminal_velocity.applied_force")
    }

    fn write_outputs(
        _case: &Case<Self>,
        state: &TerminalState,
        dir: &Path,
        _stage: OutputStage,
    ) -> Result<()> {
        // Periodic checkpoints flush the tables too, so that a killed run keeps its records so far.
        let series = csv(&SERIES, state.records.iter().map(|r| r.to_vec()));
        write_atomic(&dir.join("series.csv"), series.as_bytes())
    }

    fn results(case: &Case<Self>, state: &TerminalState) -> Result<serde_json::Value> {
        let mut o = state.outcome(case);
        // The series is in series.csv.
        o.records.clear();
        Ok(serde_json::to_value(&o).unwrap_or_default())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lbdem_kernels::fluid::collide::LambdaTerms;

    /// The bundled scene with `[fluid] lambda_form = form` (none for `None`).
    fn scene_with(form: Option<&str>) -> String {
        let text = include_str!("../../../../scenes/terminal_velocity.toml");
        match form {
            None => text.to_string(),
            Some(f) => text.replace("[fluid]\n", &format!("[fluid]\nlambda_form = \"{f}\"\n")),
        }
    }

    #[test]
    fn the_started_world_runs_the_form_the_scene_names() {
        for (form, terms) in [
            (None, LambdaTerms::WALL_PRESSURE),
            (Some("wall_pressure"), LambdaTerms::WALL_PRESSURE),
            (Some("friction_only"), LambdaTerms::FRICTION_ONLY),
        ] {
            let case = Case::<TerminalVelocity>::read(&scene_with(form), "t.toml").unwrap();
            let state = TerminalVelocity::start(&case, &Exec::default()).unwrap();
            assert_eq!(
                state.world.fluid.solid_operator(),
                SolidOperator::LambdaConsistent
            );
            assert_eq!(state.world.fluid.lambda_terms(), terms, "{form:?}");
        }
    }
}
