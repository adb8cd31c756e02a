//! `kind = "consolidation"`: free grains under a step load, drained at the top (Terzaghi-type consolidation,
//! dissertation §5.6.4, fig. 5.11–5.13). See [`Consolidation`].
use std::path::Path;

use lbdem_kernels::dem::assembly::ContactModel;
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::SolidOperator;
use lbdem_kernels::fluid::step::FluidParams;
use serde::{Deserialize, Serialize};

use crate::engine::coupled::{CoupledWorld, LatticeMap};
use crate::engine::dem::packing::{boxed_sample, hexagonal_packing};
use crate::engine::dem::{elastic_contact, DemWorld};
use crate::engine::exec::{Exec, ExecTarget};
use crate::engine::lattice::FluidLattice;
use crate::error::{non_negative, positive, LbdemError, Result};
use crate::input::limits::{self, Budget};
use crate::observe::health::{coupled_health, finite};
use crate::output::snapshots::{chunk_with_snapshots, write_coupled_at_step, SnapshotClock};
use crate::output::{csv, write_atomic};
use crate::run::{run_in_memory, Case, Kind, OutputStage, Persist, RunOptions};
use crate::scene::{
    free_grain_choice, CheckpointSection, FreeGrains, SceneHeader, SnapshotSection, UnitsSetup,
};
use crate::units::{collision_of, CollisionName, FluidSection, Warnings};

/// `[consolidation]`
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ConsolidationSection {
    /// Grains per row of the hexagonal pack.
    pub columns: usize,
    /// Rows of the pack.
    pub rows: usize,
    /// Grain radius.
    pub radius: f64,
    /// Relative radius jitter in [0, 0.5).
    pub jitter: f64,
    /// Packing seed.
    pub seed: u64,
    /// Grain density (unit thickness).
    pub grain_density: f64,
    /// Fraction of each radius the fluid sees.
    pub fluid_radius: f64,
    /// Contact normal (= shear) stiffness, force/length.
    pub normal_stiffness: f64,
    /// Contact friction.
    pub friction: f64,
    /// Step load on the top row of grains (force per unit length).
    pub load: f64,
    /// Model time simulated.
    pub duration: f64,
    /// Solid operator of the grains; absent: [`fluid_choice`].
    #[serde(default)]
    pub solid_operator: Option<SolidOperator>,
}

/// The default fluid collision and the solid operator of a consolidation scene at relaxation time `tau`
/// ([`free_grain_choice`]): without `consolidation.solid_operator`, TRT + ΩΛ where ΩΛ is stable with the
/// scene's grains (rock grains, ρs/ρf = 2.65, at every τ up to 2); else Ω₁ₗ with BGK, warned.
/// `[fluid] collision` overrides the collision.
pub fn fluid_choice(
    scene: &ConsolidationScene,
    tau: f64,
    warnings: &mut Warnings,
) -> (CollisionName, SolidOperator) {
    let c = &scene.consolidation;
    free_grain_choice(
        c.solid_operator,
        tau,
        FreeGrains::packed(c.grain_density / scene.fluid.density).in_form(scene.fluid.lambda_form),
        warnings,
    )
}

/// A consolidation scene file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ConsolidationScene {
    /// `[scene]`
    pub scene: SceneHeader,
    /// `[fluid]`
    pub fluid: FluidSection,
    /// `[consolidation]`
    pub consolidation: ConsolidationSection,
    /// `[output]`: VTK snapshots.
    #[serde(default)]
    pub output: SnapshotSection,
    /// `[run]`
    #[serde(default)]
    pub run: CheckpointSection,
}

crate::scene::scene_file!(ConsolidationScene);

/// Outcome of a consolidation run.
#[derive(Clone, Debug, Serialize)]
pub struct ConsolidationOutcome {
    /// Lattice size.
    pub nodes: [usize; 2],
    /// DEM sub-steps per fluid step.
    pub substeps: u32,
    /// Peak of the bottom pore pressure over the load.
    pub peak_pressure: f64,
    /// Time of the peak (physical).
    pub peak_time: f64,
    /// Bottom pore pressure over the load at the end.
    pub final_pressure: f64,
    /// (physical time, bottom pore pressure / load) every 10 fluid steps.
    pub series: Vec<[f64; 2]>,
}

/// The run: the coupled world, the probe and the series so far.
#[derive(Serialize, Deserialize)]
pub struct ConsolidationState {
    world: CoupledWorld,
    nx: usize,
    ny: usize,
    probe_rows: usize,
    substeps: u32,
    steps: u64,
    s: u64,
    series: Vec<[f64; 2]>,
    peak: (f64, f64),
    snapshots: SnapshotClock,
}

impl Persist for ConsolidationState {}

fn contact(c: &ConsolidationSection) -> ContactModel<f64> {
    elastic_contact(c.normal_stiffness, c.normal_stiffness, c.friction)
}

fn start(case: &Case<Consolidation>, exec: &Exec) -> Result<ConsolidationState> {
    let c = &case.scene.consolidation;
    let u = &case.setup.units;
    let h = u.spacing;
    let parts = hexagonal_packing(
        c.columns,
        c.rows,
        c.radius,
        1.0,
        c.jitter,
        c.grain_density,
        c.seed,
    );
    let model = contact(c);
    // Critical step first (with a tiny step that always passes), then the sub-step count.
    let probe = DemWorld::new(parts.clone(), model, 1e-300)?;
    let critical = probe.critical_time_step();
    // The rule (and the refusal) of the budget, which `check` printed.
    let substeps = limits::dem_substeps(
        "consolidation.normal_stiffness",
        "consolidation.duration",
        None,
        u.timestep,
        critical,
    )? as u32;
    let mut pk = boxed_sample(parts, model, u.timestep / substeps as f64, None, 0.0)?;
    let (lo, hi) = pk.world.bounds();
    pk.world.platens[pk.sample_box.top].active = false;
    let tops = pk.world.boundary_particles(3, 0.5 * c.radius);
    let width = hi[0] - lo[0];
    let total_r: f64 = tops
        .iter()
        .map(|&i| pk.world.particles[i].shape.bounding_radius())
        .sum();
    let nx = (width / h).round() as usize;
    let probe_rows = ((2.0 * c.radius / h).round() as usize).max(1);
    let ny = ((hi[1] - lo[1]) / h).round() as usize + probe_rows;
    let mut fluid = FluidLattice::<f64>::new(
        nx,
        ny,
        Boundaries {
            west: SideCondition::Wall,
            east: SideCondition::Wall,
            south: SideCondition::Wall,
            north: SideCondition::Pressure { density: 1.0 },
        },
        FluidParams {
            tau: u.tau,
            force: [0.0; 2],
        },
    )?;
    exec.apply(&mut fluid);
    let (default_collision, op) = fluid_choice(&case.scene, u.tau, &mut Warnings::default());
    fluid.set_collision(collision_of(
        case.scene
            .fluid
            .checked_collision(default_collision, u.tau)?,
    )?)?;
    fluid.set_solid_operator(op);
    fluid.set_lambda_terms(case.scene.fluid.lambda_terms(op)?)?;
    let map = LatticeMap::of(u, [lo[0] - 0.5 * h, lo[1] - 0.5 * h]);
    let mut world = CoupledWorld::new(
        fluid,
        pk.world,
        map,
        c.fluid_radius,
        op.weighting(),
        substeps,
    )?;
    for &i in &tops {
        let share = c.load * width * world.dem.particles[i].shape.bounding_radius() / total_r;
        world.applied[i] = (lbdem_kernels::math::vector(0.0, -share), 0.0);
    }
    let steps = u.time_to_steps(c.duration).round().max(10.0) as u64;
    Ok(ConsolidationState {
        world,
        nx,
        ny,
        probe_rows,
        substeps,
        steps,
        s: 0,
        series: Vec::new(),
        peak: (0.0, f64::NEG_INFINITY),
        snapshots: SnapshotClock::default(),
    })
}

impl ConsolidationState {
    /// Up to 500 steps, recording the bottom pore pressure every 10 steps.
    fn advance(&mut self, case: &Case<Consolidation>) -> Result<()> {
        let u = &case.setup.units;
        let load = u.pressure_to_density_change(case.scene.consolidation.load); // as a lattice density change
        let (nx, probe_rows) = (self.nx, self.probe_rows);
        let end = ((self.s / 500 + 1) * 500).min(self.steps);
        for s in self.s + 1..=end {
            self.world.step();
            if s.is_multiple_of(10) {
                let eps = self.world.fluid.solid_fraction_map();
                let (rho, _) = self.world.fluid.moments();
                let (mut sum, mut n) = (0.0, 0usize);
                for y in 0..probe_rows {
                    for x in 0..nx {
                        let i = y * nx + x;
                        if eps[i] == 0.0 {
                            sum += rho[i];
                            n += 1;
                        }
                    }
                }
                let p = finite(
                    "bottom pore pressure",
                    (sum / n.max(1) as f64 - 1.0) / load,
                    s,
                    "lower the load or the stiffness",
                )?;
                let t = s as f64 * u.timestep;
                if p > self.peak.1 {
                    self.peak = (t, p);
                }
                self.series.push([t, p]);
            }
        }
        self.s = end;
        Ok(())
    }

    /// The next VTK snapshot (grains, lattice with the pore pressure above the drained top).
    fn snapshot(&mut self, case: &Case<Consolidation>, dir: &Path, every: u64) -> Result<()> {
        let h = &case.scene.scene;
        write_coupled_at_step(
            dir,
            &mut self.snapshots,
            every,
            self.s,
            (h.name.as_deref(), &h.kind, h.units),
            &case.setup.units,
            &mut self.world,
        )
    }

    fn outcome(&self) -> ConsolidationOutcome {
        ConsolidationOutcome {
            nodes: [self.nx, self.ny],
            substeps: self.substeps,
            peak_pressure: self.peak.1,
            peak_time: self.peak.0,
            final_pressure: self.series.last().map_or(f64::NAN, |r| r[1]),
            series: self.series.clone(),
        }
    }
}

/// Run a consolidation case in memory to its end.
pub fn simulate(case: &Case<Consolidation>) -> Result<ConsolidationOutcome> {
    let (state, _) = run_in_memory(case, &RunOptions::default())?;
    Ok(state.outcome())
}

/// The consolidation kind (dissertation §5.6.4, fig. 5.11–5.13): a hexagonal pack of free grains in a box
/// of DEM platens with the top platen removed, a step load on the top row of grains (as forces, so the load is
/// applied at once whatever the stiffness; a servo platen's loading rate ∝ 1/k_n would bias the trend), fluid
/// walls west/east/south and a drained top (Zou–He P = 0) above the grains. Solid operator **Ω₁ₗ** (the
/// linearised Ω₁): Ω₃ is unstable for free grains (`crate::kinds::terminal_velocity::omega3_free_grain_growth`) and Ω₁ accumulates mass inside
/// the grains with a pressure boundary; Ω₁ₗ keeps Ω₁'s exchange without either problem. The pore pressure is the fluid-only (ε = 0) mean
/// in the bottom grain-diameter of the pack. The DEM is sub-stepped to stay below its critical step.
pub struct Consolidation;

impl Kind for Consolidation {
    const NAME: &'static str = "consolidation";
    const OWN_SECTION: Option<&'static str> = Some("consolidation");
    type Scene = ConsolidationScene;
    type Setup = UnitsSetup;
    type State = ConsolidationState;

    fn validate(scene: &ConsolidationScene) -> Result<()> {
        let u = crate::scene::f64_bgk_units(&scene.scene, &scene.fluid)?;
        scene.output.validate()?;

        let c = &scene.consolidation;
        positive("consolidation.radius", c.radius, "grain radius")?;
        positive("consolidation.grain_density", c.grain_density, "e.g. 2.65")?;
        positive(
            "consolidation.normal_stiffness",
            c.normal_stiffness,
            "contact stiffness, force/length",
        )?;
        positive("consolidation.load", c.load, "step load")?;
        positive("consolidation.duration", c.duration, "model time")?;
        if c.columns < 2 || c.rows < 2 {
            return Err(LbdemError::field(
                "consolidation.columns/rows",
                format!("{} x {}", c.columns, c.rows),
                "need at least 2 x 2 grains",
                "e.g. 10 x 8",
            ));
        }
        if !(c.jitter >= 0.0 && c.jitter < 0.5) {
            return Err(LbdemError::field(
                "consolidation.jitter",
                c.jitter,
                "must lie in [0, 0.5)",
                "e.g. 0.05",
            ));
        }
        crate::error::fraction(
            "consolidation.fluid_radius",
            c.fluid_radius,
            "the dissertation uses 0.6-0.95",
        )?;
        non_negative("consolidation.friction", c.friction, "e.g. 0.5")?;
        crate::scene::density_change_within(
            "consolidation.load",
            c.load,
            &u,
            " if the fluid carries it",
            "lower the load, or shorten fluid.timestep",
        )?;
        crate::scene::check_resolved("consolidation.radius", c.radius, c.fluid_radius, &u)?;
        Ok(())
    }

    fn budget(scene: &ConsolidationScene, setup: &UnitsSetup) -> Result<Budget> {
        let c = &scene.consolidation;
        let u = &setup.units;
        let grains = limits::mul(
            "consolidation.columns",
            "the grain count",
            c.columns as u64,
            c.rows as u64,
        )?;
        let grains = limits::grains("consolidation.columns", grains)?;
        let steps = limits::steps_for("consolidation.duration", c.duration, u.timestep, false)?;
        // The DEM sub-steps per fluid step, from the critical step of the same grains as the run's (all of
        // one radius: a 2 x 2 probe has the run's critical step).
        let probe = hexagonal_packing(2, 2, c.radius, 1.0, 0.0, c.grain_density, c.seed);
        let model = contact(c);
        let critical = DemWorld::new(probe, model, 1e-300)?.critical_time_step();
        let substeps = limits::dem_substeps(
            "consolidation.normal_stiffness",
            "consolidation.duration",
            Some(steps),
            u.timestep,
            critical,
        )?;
        let side = |n: u64| (n as f64 * 2.0 * c.radius / u.spacing).ceil();
        let nx = limits::count(
            "consolidation.columns",
            "the lattice width",
            side(c.columns as u64) + 2.0,
        )?;
        let ny = limits::count(
            "consolidation.rows",
            "the lattice height",
            side(c.rows as u64 + 1) + 2.0,
        )?;
        // The run takes at least 10 fluid steps (`start`).
        scene.output.budget(u.timestep, steps.max(10))?;
        let mut b = Budget::new();
        b.note(format!(
            "DEM critical step {critical:.4e} (time units of the scene): {substeps} DEM sub-step(s) per fluid step \
             (limit {}), {} DEM steps in all",
            limits::MAX_SUBSTEPS,
            steps.saturating_mul(substeps)
        ));
        limits::lattice(
            &mut b,
            "consolidation.columns",
            "lattice",
            nx,
            ny,
            8,
            limits::Solids::Covered,
        )?;
        b.add_items(
            "grains",
            "consolidation.columns",
            grains,
            limits::GRAIN_BYTES,
        )?;
        // The bottom pore pressure, (time, p) every 10 fluid steps (`ConsolidationState::advance`).
        b.add_items(
            "pore-pressure records",
            "consolidation.duration",
            limits::records_every(steps.max(10), 10),
            16,
        )?;
        Ok(b)
    }

    fn setup(scene: &ConsolidationScene) -> Result<UnitsSetup> {
        UnitsSetup::with_free_grains(
            &scene.fluid,
            "consolidation.solid_operator",
            FreeGrains::packed(scene.consolidation.grain_density / scene.fluid.density)
                .in_form(scene.fluid.lambda_form),
            |tau, w| fluid_choice(scene, tau, w),
        )
    }

    fn describe(case: &Case<Self>) -> String {
        let labels = case.scene.scene.units.labels();
        let c = &case.scene.consolidation;
        let u = &case.setup.units;
        case.setup.describe(labels)
            + &format!(
                "  {} x {} grains of radius {:.2} nodes; stiffness {:.4e}, load {:.4e} (lattice); {} steps\n",
                c.columns,
                c.rows,
                u.length_to_lattice(c.radius),
                u.force_to_lattice(c.normal_stiffness) * u.spacing,
                u.force_to_lattice(c.load) * u.spacing,
                u.time_to_steps(c.duration).round()
            )
    }

    fn start(case: &Case<Self>, exec: &Exec) -> Result<ConsolidationState> {
        start(case, exec)
    }

    fn lattices(state: &mut ConsolidationState) -> Vec<&mut dyn ExecTarget> {
        vec![&mut state.world.fluid]
    }

    fn steps_done(state: &ConsolidationState) -> u64 {
        state.s
    }

    fn total_steps(_case: &Case<Self>, state: &ConsolidationState) -> Option<u64> {
        Some(state.steps)
    }

    fn finished(_case: &Case<Self>, state: &ConsolidationState) -> bool {
        state.s >= state.steps
    }

    fn advance(
        case: &Case<Self>,
        state: &mut ConsolidationState,
        dir: Option<&Path>,
    ) -> Result<()> {
        let every = case
            .scene
            .output
            .every(case.setup.units.timestep, state.steps);
        chunk_with_snapshots(
            state,
            dir.zip(every),
            |s| (&s.snapshots, s.s, s.s >= s.steps),
            |s| s.advance(case),
            |s, dir, every| s.snapshot(case, dir, every),
        )
    }

    fn health(_case: &Case<Self>, state: &ConsolidationState) -> Result<()> {
        coupled_health(&state.world, "lower the load or the stiffness")
    }

    fn write_outputs(
        _case: &Case<Self>,
        state: &ConsolidationState,
        dir: &Path,
        _stage: OutputStage,
    ) -> Result<()> {
        // Periodic checkpoints flush the tables too, so that a killed run keeps its records so far.
        let series = csv(
            &["time", "bottom_pressure_over_load"],
            state.series.iter().map(|r| r.to_vec()),
        );
        write_atomic(&dir.join("series.csv"), series.as_bytes())
    }

    fn results(_case: &Case<Self>, state: &ConsolidationState) -> Result<serde_json::Value> {
        let mut o = state.outcome();
        // The series is in series.csv.
        o.series.clear();
        Ok(serde_json::to_value(&o).unwrap_or_default())
    }
}
