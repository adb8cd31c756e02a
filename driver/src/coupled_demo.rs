//! `kind = "coupled_demo"`: a small generic coupled run loop on [`LongRun`] — a few discs launched into a
//! fluid at rest in a periodic box (lattice units, [`LatticeMap::identity`]), run for `steps` coupled steps,
//! writing a time series. It exists to exercise checkpoints, Ctrl-C and `lbdem resume` on a
//! [`CoupledWorld`], and as the template for coupled scene kinds (see the [`LongTask`] impl below).
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
//! `summary.json` (written last).
use std::path::Path;
use std::time::Instant;

use lbdem_kernels::dem::assembly::ContactModel;
use lbdem_kernels::dem::shape::Particle;
use lbdem_kernels::fluid::boundary::Boundaries;
use lbdem_kernels::fluid::collide::Weighting;
use lbdem_kernels::fluid::step::FluidParams;
use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::checkpoint::{Checkpoint, Decoder, Encoder, Persist, CHECKPOINT_FILE, SCENE_COPY};
use crate::coupled::{CoupledWorld, LatticeMap};
use crate::error::{LbdemError, Result};
use crate::lattice::FluidLattice;
use crate::longrun::{
    dem_health, read_scene_copy, start_run_dir, LongRun, LongRunSection, LongTask, OutputStage,
    RunEnd,
};
use crate::output::{csv, write_atomic};
use crate::solid::DemWorld;

/// Checkpoint kind tag of the coupled demo.
pub const DEMO_KIND: &str = "coupled_demo";

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
    /// BGK relaxation time.
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

/// A whole demo scene file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DemoScene {
    /// `[scene]`.
    pub scene: DemoHeader,
    /// `[demo]`.
    pub demo: DemoSection,
    /// `[run]`.
    #[serde(default)]
    pub run: LongRunSection,
}

impl DemoScene {
    /// Parse `text` when its `[scene] kind` is "coupled_demo"; `None` otherwise.
    pub fn parse_if_demo(text: &str, path: &str) -> Result<Option<Self>> {
        match crate::scene::peek_kind::<String>(text) {
            Some(kind) if kind == DEMO_KIND => Self::from_toml(text, path).map(Some),
            _ => Ok(None),
        }
    }

    /// Parse and range-check.
    pub fn from_toml(text: &str, path: &str) -> Result<Self> {
        let s: DemoScene = toml::from_str(text).map_err(|e| LbdemError::ParseScene {
            path: path.to_string(),
            message: e.to_string(),
        })?;
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
        Ok(s)
    }

    /// The initial coupled world.
    pub fn build_world(&self) -> Result<CoupledWorld> {
        let d = &self.demo;
        let fluid = FluidLattice::new(
            d.nx,
            d.ny,
            Boundaries::periodic(),
            FluidParams {
                tau: d.tau,
                force: [0.0; 2],
            },
        )?;
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
                let mut p = Particle::disc(c, d.radius, 2.0);
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                p.velocity = [sign * d.speed, 0.5 * d.speed];
                p.angular_velocity = sign * d.speed / d.radius;
                p
            })
            .collect();
        let model = ContactModel {
            normal_stiffness: 1.0,
            shear_stiffness: 1.0,
            friction: 0.5,
            restitution: 1.0,
            no_tension: true,
        };
        let mut dem = DemWorld::new(particles, model, 1.0)?;
        dem.local_damping = 0.0;
        CoupledWorld::new(
            fluid,
            dem,
            LatticeMap::identity(),
            1.0,
            Weighting::NobleTorczynski,
            1,
        )
    }
}

/// The demo's checkpointed state: the coupled world and the rows recorded so far.
pub struct DemoState {
    /// The coupled world.
    pub world: CoupledWorld,
    /// Rows of series.csv.
    pub rows: Vec<Vec<f64>>,
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

impl Persist for DemoState {
    fn save(&self, e: &mut Encoder) {
        e.put(&self.world);
        e.usize(self.rows.len());
        self.rows.iter().for_each(|r| e.f64s(r));
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        let world = d.get()?;
        let n = d.len(8)?;
        let rows = (0..n).map(|_| d.f64s()).collect::<Result<Vec<_>>>()?;
        d.ensure(rows.iter().all(|r| r.len() == COLUMNS.len()), || {
            "a series row of the wrong width".into()
        })?;
        Ok(DemoState { world, rows })
    }
}

/// The demo run as a [`LongTask`].
pub struct DemoTask<'a> {
    scene: &'a DemoScene,
    /// The state (public so that tests can perturb it).
    pub state: DemoState,
    started: Instant,
}

impl<'a> DemoTask<'a> {
    /// A task over `state` for `scene`.
    pub fn new(scene: &'a DemoScene, state: DemoState) -> Self {
        Self {
            scene,
            state,
            started: Instant::now(),
        }
    }

    fn row(&self) -> Vec<f64> {
        let w = &self.state.world;
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

impl LongTask for DemoTask<'_> {
    type State = DemoState;
    const KIND: &'static str = DEMO_KIND;

    fn state(&self) -> &DemoState {
        &self.state
    }
    fn steps_done(&self) -> u64 {
        self.state.world.steps()
    }
    fn total_steps(&self) -> Option<u64> {
        Some(self.scene.demo.steps)
    }
    fn finished(&self) -> bool {
        self.state.world.steps() >= self.scene.demo.steps
    }
    fn advance(&mut self, _dir: &Path) -> Result<()> {
        let d = &self.scene.demo;
        let w = &mut self.state.world;
        let n = d.record_interval.min(d.steps - w.steps());
        for _ in 0..n {
            w.step();
        }
        if let Some((node, value)) = w.fluid.health_check(0.0, 10.0) {
            let (x, y) = w.fluid.shape().coords(node);
            return Err(LbdemError::Diverged {
                step: w.steps(),
                quantity: "fluid density".into(),
                value: format!("{value}"),
                x,
                y,
                out: String::new(),
                hint: "lower demo.speed or raise demo.tau".into(),
            });
        }
        dem_health(&w.dem)?;
        let row = self.row();
        self.state.rows.push(row);
        Ok(())
    }
    fn write_outputs(&mut self, dir: &Path, stage: OutputStage) -> Result<()> {
        let text = csv(&COLUMNS, self.state.rows.iter().cloned());
        write_atomic(&dir.join("series.csv"), text.as_bytes())?;
        if stage == OutputStage::Finished {
            let last = self.state.rows.last().cloned().unwrap_or_default();
            let summary = json!({
                "lbdem_version": env!("CARGO_PKG_VERSION"),
                "scene": self.scene,
                "steps": self.state.world.steps(),
                "final_row": COLUMNS.iter().zip(&last).map(|(c, v)| (c.to_string(), json!(v))).collect::<serde_json::Map<_, _>>(),
                "wall_seconds": self.started.elapsed().as_secs_f64(),
                "threads": rayon::current_num_threads(),
            });
            let text = serde_json::to_string_pretty(&summary).unwrap_or_default();
            write_atomic(&dir.join("summary.json"), text.as_bytes())?;
        }
        Ok(())
    }
}

/// Options of a demo run.
#[derive(Clone, Debug, Default)]
pub struct DemoOptions {
    /// Replace a previous run.
    pub overwrite: bool,
    /// No progress bar.
    pub quiet: bool,
    /// Stop (with a checkpoint) once this many steps are done.
    pub stop_after: Option<u64>,
}

fn drive(
    scene: &DemoScene,
    text: &str,
    dir: &Path,
    state: DemoState,
    opts: &DemoOptions,
) -> Result<()> {
    let mut task = DemoTask::new(scene, state);
    let driver = LongRun {
        dir,
        scene_text: text,
        interval: scene.run.checkpoint_interval,
        quiet: opts.quiet,
        stop_after: opts.stop_after,
    };
    let end = driver.run(&mut task)?;
    if end == RunEnd::Finished {
        eprintln!(
            "lbdem: coupled demo finished {} steps; outputs in {}",
            task.steps_done(),
            dir.display()
        );
    }
    end.into_result(dir)
}

/// Start a demo run of the scene text `text` in `dir`.
pub fn run_demo(text: &str, path: &str, dir: &Path, opts: &DemoOptions) -> Result<()> {
    let scene = DemoScene::from_toml(text, path)?;
    start_run_dir(dir, text, opts.overwrite)?;
    let world = scene.build_world()?;
    let mut state = DemoState {
        world,
        rows: Vec::new(),
    };
    state.rows.clear();
    drive(&scene, text, dir, state, opts)
}

/// Continue the demo run in `dir` from its checkpoint (`lbdem resume DIR`).
pub fn resume_demo(dir: &Path, opts: &DemoOptions) -> Result<()> {
    let text = read_scene_copy(dir)?;
    let scene = DemoScene::from_toml(&text, &dir.join(SCENE_COPY).display().to_string())?;
    let (h, state) = Checkpoint::load::<DemoState>(&dir.join(CHECKPOINT_FILE), &text, DEMO_KIND)?;
    eprintln!("lbdem: resuming coupled demo at step {}", h.step);
    drive(&scene, &text, dir, state, opts)
}

/// `lbdem run` of a file whose `[scene] kind` is "coupled_demo" (`None` for any other kind).
pub fn run_if_demo(
    path: &Path,
    out: &Path,
    overwrite: bool,
    quiet: bool,
) -> Result<Option<serde_json::Value>> {
    let p = path.display().to_string();
    let text = crate::scene::read_scene_text(path)?;
    if DemoScene::parse_if_demo(&text, &p)?.is_none() {
        return Ok(None);
    }
    let opts = DemoOptions {
        overwrite,
        quiet,
        stop_after: None,
    };
    run_demo(&text, &p, out, &opts)?;
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap_or_default();
    Ok(Some(serde_json::from_str(&summary).unwrap_or_default()))
}

/// `lbdem check` of a "coupled_demo" file (`None` for any other kind).
pub fn check_if_demo(path: &Path) -> Result<Option<String>> {
    let p = path.display().to_string();
    let text = crate::scene::read_scene_text(path)?;
    Ok(DemoScene::parse_if_demo(&text, &p)?.map(|s| {
        let d = &s.demo;
        format!(
            "scene {p} is valid (kind = coupled_demo)\n  {} x {} periodic lattice, tau {}, {} discs of radius {} at speed {}, {} steps\n",
            d.nx, d.ny, d.tau, d.discs, d.radius, d.speed, d.steps
        )
    }))
}
