//! `kind = "coupled_demo"`: a few discs launched into a
//! fluid at rest in a periodic box (lattice units, [`LatticeMap::identity`]), run for `steps` coupled steps,
//! writing a time series. It exists to exercise checkpoints, Ctrl-C and `lbdem resume` on a
//! [`CoupledWorld`], and as the template for coupled scene kinds (see the [`Kind`] impl below).
//!
//! ```toml
//! [scene]
//! kind = "coupled_demo"
//! [demo]
//! nx = 48               # lattice nodes
//! ny = 48
//! tau = 0.8
//! discs = 4             # placed on a 2 x 2 grid, launched in alternating directions
//! radius = 5.0          # lattice units
//! speed = 0.01          # lattice units per step
//! steps = 400
//! record_interval = 10
//! [run]
//! checkpoint_interval = 100
//! ```
//!
//! Outputs: `series.csv` (step, fluid momentum x/y, grain momentum x/y, grain kinetic energy, fluid mass),
//! the VTK snapshot series `particles_NNNN.vtp` and `lattice_NNNN.vti` with their `.pvd` collections
//! (`[output] vtk`, `snapshot_interval` in steps; docs/outputs.md), `summary.json` (written last).
use std::path::Path;

use lbdem_kernels::dem::shape::Particle;
use lbdem_kernels::fluid::boundary::Boundaries;
use lbdem_kernels::fluid::collide::{Collision, SolidOperator, Trt};
use lbdem_kernels::fluid::step::FluidParams;
use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::engine::coupled::{CoupledWorld, LatticeMap};
use crate::engine::dem::elastic_contact;
use crate::engine::dem::DemWorld;
use crate::engine::exec::{Exec, ExecTarget};
use crate::engine::lattice::FluidLattice;
use crate::error::{LbdemError, Result};
use crate::input::limits::{self, Budget};
use crate::observe::health::coupled_health;
use crate::output::snapshots::{chunk_with_snapshots, write_coupled, SnapshotClock};
use crate::output::vtk::{LatticeFrame, Stamp, Units};
use crate::output::{csv, write_atomic};
use crate::run::{Case, CheckpointInterval, Kind, OutputStage, Persist};
use crate::scene::{free_grain_defaults, FreeGrains};
use crate::scene::{CheckpointSection, SnapshotSection, UnitSystem};
use crate::units::{CollisionName, UnitLabels, Warnings, TAU_REFUSE_HIGH};

/// `[scene]` of the demo (only `kind` and an optional name).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DemoHeader {
    /// Must be "coupled_demo".
    pub kind: String,
    /// Free-text name.
    #[serde(default)]
    pub name: Option<String>,
}

/// `[demo]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DemoSection {
    /// Lattice nodes along x.
    pub nx: usize,
    /// Lattice nodes along y.
    pub ny: usize,
    /// Relaxation time (TRT + ΩΛ up to τ = 2, BGK + Ω₁ₗ above: [`DemoScene::fluid_choice`]).
    pub tau: f64,
    /// Number of discs (1–4, on a 2 × 2 grid).
    pub discs: usize,
    /// Disc radius (lattice units).
    pub radius: f64,
    /// Launch speed (lattice units per step).
    pub speed: f64,
    /// Coupled steps to run.
    pub steps: u64,
    /// Steps between rows of series.csv.
    pub record_interval: u64,
}

impl crate::run::Derived for DemoSection {}

/// A whole demo scene file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DemoScene {
    /// `[scene]`.
    pub scene: DemoHeader,
    /// `[demo]`.
    pub demo: DemoSection,
    /// `[output]`: VTK snapshots (interval in steps).
    #[serde(default)]
    pub output: SnapshotSection,
    /// `[run]`.
    #[serde(default)]
    pub run: CheckpointSection,
}

impl crate::run::SceneFile for DemoScene {
    fn unit_system(&self) -> UnitSystem {
        // The scene has no `units` key; its values are in lattice units, labelled as such by `unit_labels`.
        UnitSystem::Cgs
    }
    fn unit_labels(&self) -> UnitLabels {
        UnitLabels::LATTICE
    }
    fn checkpoint_interval(&self) -> CheckpointInterval {
        self.run.checkpoint_interval
    }
}

/// Density of the demo's discs relative to the fluid.
const DISC_DENSITY: f64 = 2.0;

impl DemoScene {
    /// The fluid collision and solid operator ([`free_grain_defaults`] for discs twice as dense as the fluid):
    /// TRT + ΩΛ, whose drag does not move with τ, at τ ≤ 2 (measured stable there with such grains), Ω₁ₗ with
    /// BGK above.
    pub fn fluid_choice(&self) -> (Collision<f64>, SolidOperator) {
        let (name, op) = free_grain_defaults(
            self.demo.tau,
            FreeGrains::lone(DISC_DENSITY),
            &mut Warnings::default(),
        );
        let collision = match name {
            CollisionName::Trt => Collision::Trt(Trt::default()),
            CollisionName::Bgk => Collision::Bgk,
        };
        (collision, op)
    }

    /// The initial coupled world.
    pub fn build_world(&self) -> Result<CoupledWorld> {
        let d = &self.demo;
        let (collision, op) = self.fluid_choice();
        let mut fluid = FluidLattice::new(
            d.nx,
            d.ny,
            Boundaries::periodic(),
            FluidParams {
                tau: d.tau,
                force: [0.0; 2],
            },
        )?;
        fluid.set_collision(collision)?;
        fluid.set_solid_operator(op);
        let (w, h) = (d.nx as f64, d.ny as f64);
        let spots = [
            [0.3 * w, 0.3 * h],
            [0.7 * w + 0.37, 0.3 * h + 0.21],
            [0.3 * w + 0.13, 0.7 * h - 0.29],
            [0.7 * w - 0.41, 0.7 * h + 0.17],
        ];
        let particles: Vec<Particle<f64>> = spots[..d.discs]
            .iter()
            .enumerate()
            .map(|(k, &c)| {
                let mut p =
                    Particle::disc(lbdem_kernels::math::Vector::from(c), d.radius, DISC_DENSITY);
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                p.velocity = lbdem_kernels::math::vector(sign * d.speed, 0.5 * d.speed);
                p.angular_velocity = sign * d.speed / d.radius;
                p
            })
            .collect();
        let model = elastic_contact(1.0, 1.0, 0.5);
        let mut dem = DemWorld::new(particles, model, 1.0)?;
        dem.local_damping = 0.0;
        CoupledWorld::new(fluid, dem, LatticeMap::identity(), 1.0, op.weighting(), 1)
    }
}

/// The demo's checkpointed state: the coupled world and the rows recorded so far.
#[derive(Serialize, Deserialize)]
pub struct DemoState {
    /// The coupled world.
    pub world: CoupledWorld,
    /// Rows of series.csv.
    pub rows: Vec<Vec<f64>>,
    /// The VTK snapshots written so far.
    pub snapshots: SnapshotClock,
}

const COLUMNS: [&str; 7] = [
    "step",
    "fluid_momentum_x",
    "fluid_momentum_y",
    "grain_momentum_x",
    "grain_momentum_y",
    "grain_kinetic_energy",
    "fluid_mass",
];

impl Persist for DemoState {}

impl DemoState {
    fn row(&self) -> Vec<f64> {
        let w = &self.world;
        let j = w.fluid.momentum();
        let mut p = [0.0; 2];
        for q in &w.dem.particles {
            p[0] += q.mass * q.velocity[0];
            p[1] += q.mass * q.velocity[1];
        }
        vec![
            w.steps() as f64,
            j[0],
            j[1],
            p[0],
            p[1],
            w.dem.kinetic_energy(),
            w.fluid.mass(),
        ]
    }
}

/// The coupled demo kind.
pub struct CoupledDemo;

impl Kind for CoupledDemo {
    const NAME: &'static str = "coupled_demo";
    const OWN_SECTION: Option<&'static str> = Some("demo");
    type Scene = DemoScene;
    type Setup = DemoSection;
    type State = DemoState;

    fn validate(s: &DemoScene) -> Result<()> {
        s.output.validate()?;
        let d = &s.demo;
        if !(1..=4).contains(&d.discs) {
            return Err(LbdemError::field(
                "demo.discs",
                d.discs,
                "must be 1 to 4",
                "the discs sit on a 2 x 2 grid",
            ));
        }
        if !(d.radius > 1.0 && 4.0 * d.radius + 8.0 <= d.nx.min(d.ny) as f64) {
            return Err(LbdemError::field(
                "demo.radius",
                d.radius,
                "must be > 1 and leave room for a 2 x 2 grid of discs",
                "use nx, ny >= 4 radius + 8",
            ));
        }
        if !(d.tau.is_finite() && d.tau > 0.5 && d.tau <= TAU_REFUSE_HIGH) {
            return Err(LbdemError::field(
                "demo.tau",
                d.tau,
                &format!(
                    "must lie in (0.5, {TAU_REFUSE_HIGH}]: BGK is unstable for tau <= 1/2 and meaningless far above 2"
                ),
                "use tau in (0.5, 2], e.g. 0.8",
            ));
        }
        limits::steps("demo.steps", d.steps)?;
        if !(d.speed.is_finite() && d.speed.abs() < 0.1) {
            return Err(LbdemError::field(
                "demo.speed",
                d.speed,
                "must be below 0.1 (lattice Mach number)",
                "e.g. 0.01",
            ));
        }
        if d.steps == 0 || d.record_interval == 0 {
            return Err(LbdemError::field(
                "demo.steps / demo.record_interval",
                format!("{} / {}", d.steps, d.record_interval),
                "must be at least 1",
                "e.g. steps = 400, record_interval = 10",
            ));
        }
        Ok(())
    }

    fn setup(scene: &DemoScene) -> Result<DemoSection> {
        Ok(scene.demo.clone())
    }

    fn budget(scene: &DemoScene, d: &DemoSection) -> Result<Budget> {
        // Lattice units: the model time is the step count.
        scene.output.budget(1.0, d.steps)?;
        let mut b = Budget::new();
        limits::lattice(
            &mut b,
            "demo.nx",
            "periodic lattice",
            d.nx as u64,
            d.ny as u64,
            8,
            limits::Solids::Covered,
        )?;
        // One row of series.csv per record interval, kept in the state.
        let rows = d.steps.div_ceil(d.record_interval);
        b.add_items("series rows", "demo.record_interval", rows, 8 * 7 + 24)?;
        Ok(b)
    }

    fn describe(case: &Case<Self>) -> String {
        let d = &case.setup;
        format!(
            "  {} x {} periodic lattice, tau {}, {} discs of radius {} at speed {}, {} steps (lattice units)\n",
            d.nx, d.ny, d.tau, d.discs, d.radius, d.speed, d.steps
        )
    }

    fn start(case: &Case<Self>, exec: &Exec) -> Result<DemoState> {
        let mut world = case.scene.build_world()?;
        exec.apply(&mut world.fluid);
        Ok(DemoState {
            world,
            rows: Vec::new(),
            snapshots: SnapshotClock::default(),
        })
    }

    fn lattices(state: &mut DemoState) -> Vec<&mut dyn ExecTarget> {
        vec![&mut state.world.fluid]
    }

    fn check_resumed(_case: &Case<Self>, state: &DemoState) -> Result<()> {
        if state.rows.iter().any(|r| r.len() != COLUMNS.len()) {
            return Err(LbdemError::Checkpoint {
                path: String::new(),
                problem: "holds a series row of the wrong width".into(),
                hint: "the file was written by another lbdem version; start the run again".into(),
            });
        }
        Ok(())
    }

    fn steps_done(state: &DemoState) -> u64 {
        state.world.steps()
    }

    fn total_steps(case: &Case<Self>, _state: &DemoState) -> Option<u64> {
        Some(case.setup.steps)
    }

    fn finished(case: &Case<Self>, state: &DemoState) -> bool {
        state.world.steps() >= case.setup.steps
    }

    fn advance(case: &Case<Self>, state: &mut DemoState, dir: Option<&Path>) -> Result<()> {
        let d = &case.setup;
        // Lattice units: the model time is the step count (unit dt).
        let every = case.scene.output.every(1.0, d.steps);
        let snapshot = |state: &mut DemoState, dir: &Path, every: u64| {
            let step = state.world.steps();
            let stamp = Stamp {
                time: step as f64,
                title: case
                    .scene
                    .scene
                    .name
                    .clone()
                    .unwrap_or_else(|| "lbdem coupled_demo".into()),
                units: Units::lattice(),
            };
            write_coupled(
                dir,
                &mut state.snapshots,
                every,
                step,
                &stamp,
                &mut state.world,
                &LatticeFrame::lattice_units(),
            )
        };
        chunk_with_snapshots(
            state,
            dir.zip(every),
            |s| (&s.snapshots, s.world.steps(), s.world.steps() >= d.steps),
            |state| {
                let n = d.record_interval.min(d.steps - state.world.steps());
                for _ in 0..n {
                    state.world.step();
                }
                // A diverged state is not recorded (the rows so far are the outputs of a diverged run).
                Self::health(case, state)?;
                let row = state.row();
                state.rows.push(row);
                Ok(())
            },
            snapshot,
        )
    }

    fn health(_case: &Case<Self>, state: &DemoState) -> Result<()> {
        coupled_health(&state.world, "lower demo.speed or raise demo.tau")
    }

    fn write_outputs(
        _case: &Case<Self>,
        state: &DemoState,
        dir: &Path,
        _stage: OutputStage,
    ) -> Result<()> {
        let text = csv(&COLUMNS, state.rows.iter().cloned());
        write_atomic(&dir.join("series.csv"), text.as_bytes())
    }

    fn results(_case: &Case<Self>, state: &DemoState) -> Result<serde_json::Value> {
        let last = state.rows.last().cloned().unwrap_or_default();
        Ok(json!({
            "final_row": COLUMNS
                .iter()
                .zip(&last)
                .map(|(c, v)| (c.to_string(), json!(v)))
                .collect::<serde_json::Map<_, _>>(),
        }))
    }
}
