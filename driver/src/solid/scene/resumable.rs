//! The dry scene's run as a [`LongTask`]: packing and bonding (not checkpointed: seeded and short), then the
//! loading stage one record interval at a time through [`CompressionRun`] / [`BoundaryStressRun`], with
//! checkpoints, Ctrl-C and `lbdem resume DIR`. Outputs are the same files, byte for byte, whether the run was
//! interrupted and resumed or not (`summary.json` aside from its wall-clock and thread-count fields).
use std::path::Path;
use std::time::Instant;

use lbdem_kernels::dem::bond::BreakMode;
use lbdem_kernels::Real;
use serde_json::json;

use super::{DryScene, LoadingKind};
use crate::checkpoint::{Checkpoint, Decoder, Encoder, Persist, CHECKPOINT_FILE};
use crate::error::Result;
use crate::longrun::{
    dem_health, read_scene_copy, start_run_dir, LongRun, LongTask, OutputStage, RunEnd,
};
use crate::output::{csv, write_atomic};
use crate::scene::Precision;
use crate::solid::loading::{BoundaryStressTest, CompressionTest};
use crate::solid::packing::generate_packing;
use crate::solid::staged::{BoundaryStressRun, CompressionRun};
use crate::solid::vtk::particles_vtk;
use crate::solid::world::DemWorld;

/// Checkpoint kind tag of dry scenes.
pub const DRY_KIND: &str = "dry";

/// How a dry run is driven (besides the scene's own `[run] checkpoint_interval`).
#[derive(Clone, Debug, Default)]
pub struct DryRunOptions {
    /// Replace a previous run in the directory.
    pub overwrite: bool,
    /// No progress bar.
    pub quiet: bool,
    /// Stop (as if interrupted, with a checkpoint) once this many loading steps are done.
    pub stop_after: Option<u64>,
}

/// The loading stage in progress.
#[derive(Clone, Debug)]
pub enum Stage<T> {
    /// Uniaxial or biaxial compression.
    Compression(CompressionRun<T>),
    /// The fracture test's dry control.
    BoundaryStress(BoundaryStressRun<T>),
}

/// What a dry run checkpoints: the world, the loading stage, the packing facts for the summary, the output
/// counters and the wall time so far.
#[derive(Clone, Debug)]
pub struct DryState<T> {
    /// The assembly.
    pub world: DemWorld<T>,
    /// The loading stage.
    pub stage: Stage<T>,
    scene_file: String,
    particles: usize,
    bonds: usize,
    packing_steps: u64,
    packing_converged: bool,
    size_factor: f64,
    wall_stresses: [f64; 4],
    critical: f64,
    records: u64,
    snapshots: u64,
    loading_steps_done: u64,
    wall_seconds: f64,
}

/// The dry run driven by [`LongRun`].
pub struct DryTask<'a, T> {
    scene: &'a DryScene,
    state: DryState<T>,
    started: Instant,
    total: Option<u64>,
}

impl<T: Real> Persist for DryState<T> {
    const PRECISION: u8 = std::mem::size_of::<T>() as u8;
    fn save(&self, e: &mut Encoder) {
        e.put(&self.world);
        match &self.stage {
            Stage::Compression(r) => {
                e.u8(0);
                e.put(r);
            }
            Stage::BoundaryStress(r) => {
                e.u8(1);
                e.put(r);
            }
        }
        e.str(&self.scene_file);
        e.usize(self.particles);
        e.usize(self.bonds);
        e.u64(self.packing_steps);
        e.bool(self.packing_converged);
        e.f64(self.size_factor);
        self.wall_stresses.iter().for_each(|&s| e.f64(s));
        e.f64(self.critical);
        e.u64(self.records);
        e.u64(self.snapshots);
        e.u64(self.loading_steps_done);
        e.f64(self.wall_seconds);
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        let world: DemWorld<T> = d.get()?;
        let stage = match d.tag("dry loading stage", 2)? {
            0 => Stage::Compression(d.get()?),
            _ => Stage::BoundaryStress(d.get()?),
        };
        let n = world.particles.len();
        let b = match &stage {
            Stage::Compression(r) => r.sample_box,
            Stage::BoundaryStress(r) => r.sample_box,
        };
        d.ensure(
            [b.left, b.right, b.bottom, b.top]
                .iter()
                .all(|&i| i < world.platens.len()),
            || {
                format!(
                    "sample box names platens beyond the {}",
                    world.platens.len()
                )
            },
        )?;
        Ok(DryState {
            world,
            stage,
            scene_file: d.str()?,
            particles: d.usize()?,
            bonds: d.usize()?,
            packing_steps: d.u64()?,
            packing_converged: d.bool()?,
            size_factor: d.f64()?,
            wall_stresses: [d.f64()?, d.f64()?, d.f64()?, d.f64()?],
            critical: d.f64()?,
            records: d.u64()?,
            snapshots: d.u64()?,
            loading_steps_done: d.u64()?,
            wall_seconds: d.f64()?,
        })
        .and_then(|s| {
            d.ensure(s.particles == n, || {
                format!("{} particles in the world, {} recorded", n, s.particles)
            })?;
            Ok(s)
        })
    }
}

impl<'a, T: Real> DryTask<'a, T> {
    fn new(scene: &'a DryScene, state: DryState<T>) -> Self {
        let l = &scene.loading;
        let total = match l.test {
            LoadingKind::BoundaryStress => Some(l.steps),
            LoadingKind::Compression => {
                // Steps to reach max_strain at the platen speed (the test usually stops earlier, at failure).
                let h = scene.packing.height;
                let per_step = 2.0 * l.platen_speed * scene.solid.timestep / h;
                Some(l.settle_steps + (l.max_strain / per_step).ceil().max(1.0) as u64)
            }
        };
        DryTask {
            scene,
            state,
            started: Instant::now(),
            total,
        }
    }

    fn title(&self) -> String {
        self.scene
            .scene
            .name
            .clone()
            .unwrap_or_else(|| "lbdem dry scene".into())
    }

    fn snapshot(&mut self, dir: &Path) -> Result<()> {
        let w = &self.state.world;
        let text = particles_vtk(&self.title(), &w.particles, &w.broken_bond_fraction());
        let file = dir.join(format!("particles_{:04}.vtk", self.state.snapshots));
        write_atomic(&file, text.as_bytes())?;
        self.state.snapshots += 1;
        Ok(())
    }

    fn curve(&self) -> &[crate::solid::CurvePoint] {
        match &self.state.stage {
            Stage::Compression(r) => &r.curve,
            Stage::BoundaryStress(r) => &r.curve,
        }
    }

    fn write_tables(&self, dir: &Path) -> Result<()> {
        let w = &self.state.world;
        let dt = w.timestep().to_f64_exact();
        let curve = csv(
            &[
                "step",
                "axial_strain",
                "lateral_strain",
                "axial_stress",
                "deviator_stress",
                "lateral_stress",
                "broken_bonds",
            ],
            self.curve().iter().map(|c| {
                vec![
                    c.step as f64,
                    c.axial_strain,
                    c.lateral_strain,
                    c.axial_stress,
                    c.deviator_stress,
                    c.lateral_stress,
                    c.broken_bonds as f64,
                ]
            }),
        );
        write_atomic(&dir.join("stress_strain.csv"), curve.as_bytes())?;
        let mut broken =
            String::from("step,time,particle_i,particle_j,x,y,mode,orientation,load\n");
        for b in &w.breaks {
            broken += &format!(
                "{},{:.10e},{},{},{:.10e},{:.10e},{},{:.10e},{:.10e}\n",
                b.step,
                b.step as f64 * dt,
                b.pair[0],
                b.pair[1],
                b.position[0].to_f64_exact(),
                b.position[1].to_f64_exact(),
                mode_name(b.mode),
                b.orientation.to_f64_exact(),
                b.load.to_f64_exact()
            );
        }
        write_atomic(&dir.join("broken_bonds.csv"), broken.as_bytes())
    }

    fn write_summary(&self, dir: &Path) -> Result<serde_json::Value> {
        let s = &self.state;
        let w = &s.world;
        let results = match &s.stage {
            Stage::Compression(r) => {
                let r = r.result(w);
                json!({
                    "youngs_modulus": r.youngs_modulus,
                    "peak_axial_stress": r.peak_stress,
                    "peak_deviator_stress": r.peak_deviator,
                    "peak_axial_strain": r.peak_strain,
                    "loading_steps": r.steps,
                })
            }
            Stage::BoundaryStress(r) => {
                let last = r.curve.last().copied();
                json!({
                    "final_axial_strain": last.map(|c| c.axial_strain),
                    "final_lateral_strain": last.map(|c| c.lateral_strain),
                    "final_bottom_platen_stress": last.map(|c| c.axial_stress),
                    "final_lateral_stress": last.map(|c| c.lateral_stress),
                    "loading_steps": r.test.steps,
                })
            }
        };
        let count = |m: BreakMode| w.breaks.iter().filter(|b| b.mode == m).count();
        let summary = json!({
            "lbdem_version": env!("CARGO_PKG_VERSION"),
            "scene_file": s.scene_file,
            "scene": self.scene,
            "units": self.scene.scene.units.labels(),
            "derived": {
                "particles": s.particles,
                "bonds": s.bonds,
                "packing_steps": s.packing_steps,
                "packing_converged": s.packing_converged,
                "size_factor": s.size_factor,
                "isotropic_wall_stresses": s.wall_stresses,
                "critical_time_step": s.critical,
                "timestep": w.timestep().to_f64_exact(),
            },
            "results": {
                "test": results,
                "broken_bonds": w.breaks.len(),
                "broken_in_tension": count(BreakMode::Tension),
                "broken_in_shear": count(BreakMode::Shear),
                "broken_in_compression": count(BreakMode::Compression),
                "vtk_snapshots": s.snapshots,
            },
            "wall_seconds": s.wall_seconds + self.started.elapsed().as_secs_f64(),
            "threads": rayon::current_num_threads(),
        });
        let text = serde_json::to_string_pretty(&summary).unwrap_or_default();
        write_atomic(&dir.join("summary.json"), text.as_bytes())?;
        eprintln!(
            "lbdem: {results}; {} bonds broken; outputs in {}",
            w.breaks.len(),
            dir.display()
        );
        Ok(summary)
    }
}

fn mode_name(m: BreakMode) -> &'static str {
    match m {
        BreakMode::Tension => "tension",
        BreakMode::Shear => "shear",
        BreakMode::Compression => "compression",
    }
}

impl<T: Real> LongTask for DryTask<'_, T> {
    type State = DryState<T>;
    const KIND: &'static str = DRY_KIND;

    fn state(&self) -> &DryState<T> {
        &self.state
    }
    fn steps_done(&self) -> u64 {
        self.state.loading_steps_done
    }
    fn total_steps(&self) -> Option<u64> {
        self.total
    }
    fn finished(&self) -> bool {
        match &self.state.stage {
            Stage::Compression(r) => r.finished,
            Stage::BoundaryStress(r) => r.finished(),
        }
    }

    fn advance(&mut self, dir: &Path) -> Result<()> {
        let before = self.state.world.step_count();
        let point = match &mut self.state.stage {
            Stage::Compression(r) => r.advance(&mut self.state.world),
            Stage::BoundaryStress(r) => r.advance(&mut self.state.world),
        };
        self.state.loading_steps_done += self.state.world.step_count() - before;
        dem_health(&self.state.world)?;
        if point.is_some() {
            self.state.records += 1;
            let every = self.scene.loading.vtk_interval;
            if every > 0 && self.state.records.is_multiple_of(every) {
                self.snapshot(dir)?;
            }
        }
        Ok(())
    }

    fn write_outputs(&mut self, dir: &Path, stage: OutputStage) -> Result<()> {
        match stage {
            OutputStage::Checkpoint => Ok(()),
            OutputStage::Interrupted | OutputStage::Diverged => self.write_tables(dir),
            OutputStage::Finished => {
                self.snapshot(dir)?;
                self.write_tables(dir)
            }
        }
    }
}

impl DryScene {
    /// `lbdem run` of a dry scene through the long-run driver: pack, bond, then load with checkpoints in
    /// `out` (interval `[run] checkpoint_interval`), Ctrl-C handling and `lbdem resume` support.
    pub fn run_resumable(
        &self,
        path: &Path,
        out: &Path,
        opts: &DryRunOptions,
    ) -> Result<serde_json::Value> {
        let p = path.display().to_string();
        let text = crate::scene::read_scene_text(path)?;
        let critical = self.critical_time_step();
        self.check_timestep(critical)?;
        start_run_dir(out, &text, opts.overwrite)?;
        eprintln!("lbdem: dry scene {}", path.display());
        eprint!("{}", self.describe(critical));
        match self.scene.precision {
            Precision::F64 => self.start_with::<f64>(&p, &text, out, critical, opts),
            Precision::F32 => self.start_with::<f32>(&p, &text, out, critical, opts),
        }
    }

    fn start_with<T: Real>(
        &self,
        path: &str,
        text: &str,
        out: &Path,
        critical: f64,
        opts: &DryRunOptions,
    ) -> Result<serde_json::Value> {
        let started = Instant::now();
        let spec = self.packing_spec::<T>();
        let mut packing = generate_packing(&spec, self.bond_spec::<T>())?;
        packing.world.local_damping = T::lit(self.solid.local_damping);
        eprintln!(
            "lbdem: packed {} particles, {} bonds in {} steps (converged: {}; wall stresses {:?})",
            packing.world.particles.len(),
            packing.world.bonds.len(),
            packing.steps,
            packing.converged,
            packing.wall_stresses.map(|x| x.to_f64_exact())
        );
        let l = &self.loading;
        let mut world = packing.world;
        let b = packing.sample_box;
        let stage = match l.test {
            LoadingKind::Compression => Stage::Compression(CompressionRun::new(
                &mut world,
                b,
                CompressionTest {
                    confining_stress: T::lit(l.confining_stress),
                    platen_speed: T::lit(l.platen_speed),
                    settle_steps: l.settle_steps,
                    max_strain: T::lit(l.max_strain),
                    post_peak_fraction: T::lit(l.post_peak_fraction),
                    record_interval: l.record_interval,
                },
            )),
            LoadingKind::BoundaryStress => Stage::BoundaryStress(BoundaryStressRun::new(
                &mut world,
                b,
                BoundaryStressTest {
                    lateral_stress: T::lit(l.lateral_stress),
                    axial_stress: T::lit(l.axial_stress),
                    boundary_depth: T::lit(0.5 * self.packing.radius_min),
                    steps: l.steps,
                    record_interval: l.record_interval,
                },
            )),
        };
        let state = DryState {
            particles: world.particles.len(),
            bonds: world.bonds.len(),
            world,
            stage,
            scene_file: path.to_string(),
            packing_steps: packing.steps,
            packing_converged: packing.converged,
            size_factor: packing.size_factor.to_f64_exact(),
            wall_stresses: packing.wall_stresses.map(|x| x.to_f64_exact()),
            critical,
            records: 0,
            snapshots: 0,
            loading_steps_done: 0,
            wall_seconds: 0.0,
        };
        let mut task = DryTask::new(self, state);
        task.started = started;
        task.snapshot(out)?;
        self.drive(task, text, out, opts.quiet, opts.stop_after)
    }

    fn drive<T: Real>(
        &self,
        mut task: DryTask<'_, T>,
        text: &str,
        out: &Path,
        quiet: bool,
        stop_after: Option<u64>,
    ) -> Result<serde_json::Value> {
        let driver = LongRun {
            dir: out,
            scene_text: text,
            interval: self.run.checkpoint_interval,
            quiet,
            stop_after,
        };
        match driver.run(&mut task)? {
            RunEnd::Finished => task.write_summary(out),
            end @ RunEnd::Interrupted { .. } => {
                task.state.wall_seconds += task.started.elapsed().as_secs_f64();
                task.started = Instant::now();
                // Keep the wall time in the checkpoint (the interrupted state is otherwise unchanged).
                driver.save(&task)?;
                end.into_result(out).map(|_| serde_json::Value::Null)
            }
        }
    }
}

/// Continue the dry run in `dir` from its checkpoint to the end (`lbdem resume DIR`), with the scene copy
/// saved at its start. `stop_after` as in [`DryRunOptions`].
pub fn resume_dry(dir: &Path, quiet: bool, stop_after: Option<u64>) -> Result<serde_json::Value> {
    let text = read_scene_copy(dir)?;
    let copy = dir.join(crate::checkpoint::SCENE_COPY);
    let scene = DryScene::from_toml(&text, &copy.display().to_string())?;
    let ckpt = dir.join(CHECKPOINT_FILE);
    eprintln!("lbdem: resuming dry scene from {}", ckpt.display());
    match scene.scene.precision {
        Precision::F64 => {
            let (h, state) = Checkpoint::load::<DryState<f64>>(&ckpt, &text, DRY_KIND)?;
            eprintln!("lbdem: checkpoint at loading step {}", h.step);
            scene.drive(DryTask::new(&scene, state), &text, dir, quiet, stop_after)
        }
        Precision::F32 => {
            let (h, state) = Checkpoint::load::<DryState<f32>>(&ckpt, &text, DRY_KIND)?;
            eprintln!("lbdem: checkpoint at loading step {}", h.step);
            scene.drive(DryTask::new(&scene, state), &text, dir, quiet, stop_after)
        }
    }
}
