//! The `kind = "dry"` scene: a bonded sample packed by the ch. 2 procedure and loaded between platens
//! (uniaxial or servo-confined biaxial compression at a constant platen speed; or, with
//! `test = "boundary_stress"`, the ch. 6.6 fracture test's dry control: axial stress through the top boundary
//! particles, lateral stress by servo platens), with no fluid (no lattice is allocated). Outputs: `stress_strain.csv`, `broken_bonds.csv`, `particles_NNNN.vtp` and `bonds_NNNN.vtp` with their
//! `.pvd` collections (docs/outputs.md), and
//! `summary.json` (written last).
//!
//! ```toml
//! [scene]
//! kind = "dry"
//! units = "cgs"            # every value below in cm, g, s, dyne (2-D: stresses in dyne/cm per unit thickness)
//! [packing]
//! width = 2.0              # box, cm
//! height = 4.0
//! radius_min = 0.07        # semi-major axes, cm (dissertation ch. 6.6)
//! radius_max = 0.11
//! aspect_ratio = 1.0       # b/a; 0.5 for the ch. 6.6 ellipses
//! solid_fraction = 0.82    # sets the particle count
//! density = 2.65           # g/cm^3 (unit thickness)
//! seed = 1
//! isotropic_stress = 50.0  # installed before bonding
//! [solid]
//! normal_stiffness = 1e5   # dyne/cm (table 6.1)
//! shear_stiffness = 1e5
//! friction = 0.5
//! local_damping = 0.7
//! timestep = 5e-5          # s; refused above 0.8 x the critical step
//! [solid.bonds]
//! kind = "parallel"        # or "point" with stiffness (dyne/cm) and strength (dyne)
//! radius_multiplier = 1.0
//! normal_stiffness = 2.8e5 # dyne/cm^3
//! shear_stiffness = 2.8e5
//! tensile_strength = 500.0 # dyne/cm^2
//! shear_strength = 500.0
//! [loading]
//! confining_stress = 0.0   # 0: uniaxial (lateral platens removed)
//! platen_speed = 0.02      # cm/s, each axial platen
//! max_strain = 0.05
//! ```
use std::path::Path;

use lbdem_kernels::dem::bond::BreakMode;
use lbdem_kernels::Real;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::engine::dem::loading::{BoundaryStressTest, CompressionTest, CurvePoint};
use crate::engine::dem::packing::generate_packing;
use crate::engine::dem::staged::{BoundaryStressRun, CompressionRun};
use crate::engine::dem::world::{DemWorld, CRITICAL_STEP_SAFETY};
use crate::engine::exec::Exec;
use crate::error::{non_negative, positive, LbdemError, Result};
use crate::input::limits::{self, Budget};
use crate::observe::health::dem_health;
use crate::output::snapshots::write_series;
use crate::output::vtk::{BreakClock, Stamp, Units};
use crate::output::{csv, write_atomic};
use crate::run::{Case, Kind, OutputStage, Persist};
use crate::scene::solid::packing_budget;
use crate::scene::solid::{
    bond_spec, critical_time_step, packing_spec, validate_packing_and_solid, PackingSection,
    SolidSection,
};
use crate::scene::{CheckpointSection, Precision, SceneHeader};

fn default_settle() -> u64 {
    1000
}
fn default_post_peak() -> f64 {
    0.7
}
fn default_record() -> u64 {
    50
}

/// Which loading a dry scene runs.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum LoadingKind {
    /// Uniaxial or biaxial compression between platens at a constant speed.
    #[default]
    Compression,
    /// The fracture test's dry control (ch. 6.6): lateral stress by servo platens, axial stress through the
    /// top boundary particles, for a number of steps.
    BoundaryStress,
}

/// `[loading]`: the test.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LoadingSection {
    /// Which test (default "compression").
    #[serde(default)]
    pub test: LoadingKind,
    /// Confining stress (compression; 0: uniaxial).
    #[serde(default)]
    pub confining_stress: f64,
    /// Speed of each axial platen (compression).
    #[serde(default)]
    pub platen_speed: f64,
    /// Steps before loading (compression; default 1000).
    #[serde(default = "default_settle")]
    pub settle_steps: u64,
    /// Stop at this axial strain (compression).
    #[serde(default)]
    pub max_strain: f64,
    /// Axial stress through the top boundary particles (boundary_stress).
    #[serde(default)]
    pub axial_stress: f64,
    /// Lateral stress held by the servo platens (boundary_stress).
    #[serde(default)]
    pub lateral_stress: f64,
    /// Steps to run (boundary_stress).
    #[serde(default)]
    pub steps: u64,
    /// Stop when the deviator falls to this fraction of its peak (default 0.7).
    #[serde(default = "default_post_peak")]
    pub post_peak_fraction: f64,
    /// Steps between stress–strain records (default 50).
    #[serde(default = "default_record")]
    pub record_interval: u64,
    /// Records between VTK snapshots (0: only the first and last).
    #[serde(default)]
    pub vtk_interval: u64,
}

/// A whole dry scene file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DryScene {
    /// `[scene]` (kind = "dry").
    pub scene: SceneHeader,
    /// `[packing]`.
    pub packing: PackingSection,
    /// `[solid]`.
    pub solid: SolidSection,
    /// `[loading]`.
    pub loading: LoadingSection,
    /// `[run]` (optional): `checkpoint_interval`.
    #[serde(default)]
    pub run: CheckpointSection,
}

crate::scene::scene_file!(DryScene);

impl DryScene {
    /// Range checks naming the field.
    pub fn validate(&self) -> Result<()> {
        validate_packing_and_solid(&self.packing, &self.solid)?;
        let l = &self.loading;
        match l.test {
            LoadingKind::Compression => {
                non_negative(
                    "loading.confining_stress",
                    l.confining_stress,
                    "0 for uniaxial",
                )?;
                positive(
                    "loading.platen_speed",
                    l.platen_speed,
                    "slow: quasi-static (Potyondy & Cundall 2004)",
                )?;
                positive("loading.max_strain", l.max_strain, "e.g. 0.05")?;
            }
            LoadingKind::BoundaryStress => {
                positive(
                    "loading.axial_stress",
                    l.axial_stress,
                    "ch. 6.6: 40 dyne/cm^2",
                )?;
                positive(
                    "loading.lateral_stress",
                    l.lateral_stress,
                    "ch. 6.6: 50 dyne/cm^2",
                )?;
                if l.steps == 0 {
                    return Err(LbdemError::field(
                        "loading.steps",
                        0,
                        "test = \"boundary_stress\" needs a number of steps >= 1",
                        "e.g. 20000",
                    ));
                }
            }
        }
        if !(l.post_peak_fraction > 0.0 && l.post_peak_fraction < 1.0) {
            return Err(LbdemError::field(
                "loading.post_peak_fraction",
                l.post_peak_fraction,
                "must be in (0, 1)",
                "e.g. 0.7",
            ));
        }
        if l.record_interval == 0 {
            return Err(LbdemError::field(
                "loading.record_interval",
                0,
                "must be at least 1",
                "e.g. 50",
            ));
        }
        // The packing spec re-checks sizes, aspect ratio and solid fraction with field names.
        let spec = packing_spec::<f64>(&self.packing, &self.solid);
        crate::engine::dem::packing::check_packing_spec(&spec)?;
        Ok(())
    }
}

/// What `lbdem check` prints of a dry scene.
#[derive(Clone, Debug, Serialize)]
pub struct DrySetup {
    /// A-priori DEM critical step (smallest particle, six contacts and six bonds).
    pub critical_time_step: f64,
    /// The DEM step.
    pub timestep: f64,
}

impl crate::run::Derived for DrySetup {}

/// The loading stage in progress.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound(
    serialize = "T: lbdem_kernels::Real + Serialize",
    deserialize = "T: lbdem_kernels::Real + Deserialize<'de>"
))]
pub enum Stage<T> {
    /// Uniaxial or biaxial compression.
    Compression(CompressionRun<T>),
    /// The fracture test's dry control.
    BoundaryStress(BoundaryStressRun<T>),
}

/// A dry run in precision `T`: the world, the loading stage, the packing facts for the summary and the output
/// counters.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound(
    serialize = "T: lbdem_kernels::Real + Serialize",
    deserialize = "T: lbdem_kernels::Real + Deserialize<'de>"
))]
pub struct DryRun<T> {
    /// The assembly.
    pub world: DemWorld<T>,
    /// The loading stage.
    pub stage: Stage<T>,
    particles: usize,
    bonds: usize,
    packing_steps: u64,
    packing_converged: bool,
    size_factor: f64,
    wall_stresses: [f64; 4],
    records: u64,
    snapshots: u64,
    loading_steps_done: u64,
}

/// What a dry run checkpoints: the run in the scene's precision.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub enum DryState {
    /// precision = "f32".
    F32(DryRun<f32>),
    /// precision = "f64".
    F64(DryRun<f64>),
}

impl Persist for DryState {
    const PRECISION: u8 = 0;
    fn precision(&self) -> u8 {
        match self {
            DryState::F32(_) => 4,
            DryState::F64(_) => 8,
        }
    }
}

/// `match` over the precision of a [`DryState`], binding the run to `$r`.
macro_rules! each {
    ($state:expr, $r:ident => $body:expr) => {
        match $state {
            DryState::F32($r) => $body,
            DryState::F64($r) => $body,
        }
    };
}

fn start_run<T: Real + Serialize + DeserializeOwned>(scene: &DryScene) -> Result<DryRun<T>> {
    let spec = packing_spec::<T>(&scene.packing, &scene.solid);
    let mut packing = generate_packing(&spec, bond_spec::<T>(&scene.solid))?;
    packing.world.local_damping = T::lit(scene.solid.local_damping);
    eprintln!(
        "lbdem: packed {} particles, {} bonds in {} steps (converged: {}; wall stresses {:?})",
        packing.world.particles.len(),
        packing.world.bonds.len(),
        packing.steps,
        packing.converged,
        packing.wall_stresses.map(|x| x.to_f64_exact())
    );
    let l = &scene.loading;
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
                boundary_depth: T::lit(0.5 * scene.packing.radius_min),
                steps: l.steps,
                record_interval: l.record_interval,
            },
        )),
    };
    Ok(DryRun {
        particles: world.particles.len(),
        bonds: world.bonds.len(),
        world,
        stage,
        packing_steps: packing.steps,
        packing_converged: packing.converged,
        size_factor: packing.size_factor.to_f64_exact(),
        wall_stresses: packing.wall_stresses.map(|x| x.to_f64_exact()),
        records: 0,
        snapshots: 0,
        loading_steps_done: 0,
    })
}

impl<T: Real> DryRun<T> {
    fn finished(&self) -> bool {
        match &self.stage {
            Stage::Compression(r) => r.finished,
            Stage::BoundaryStress(r) => r.finished(),
        }
    }

    fn curve(&self) -> &[CurvePoint] {
        match &self.stage {
            Stage::Compression(r) => &r.curve,
            Stage::BoundaryStress(r) => &r.curve,
        }
    }

    fn snapshot(&mut self, scene: &DryScene, dir: &Path) -> Result<()> {
        let title = scene
            .scene
            .name
            .clone()
            .unwrap_or_else(|| "lbdem dry scene".into());
        let w = &self.world;
        let dt = w.timestep().to_f64_exact();
        let stamp = Stamp {
            time: self.loading_steps_done as f64 * dt,
            title,
            units: Units::of(scene.scene.units),
        };
        let index = self.snapshots as usize;
        // Break times as in broken_bonds.csv: the world's step count times the step.
        let clock = BreakClock { origin_step: 0, dt };
        write_series(dir, index, &stamp, w, None, clock, None)?;
        self.snapshots += 1;
        Ok(())
    }

    fn advance(&mut self, scene: &DryScene, dir: Option<&Path>) -> Result<()> {
        if self.records == 0 && self.snapshots == 0 && self.loading_steps_done == 0 {
            if let Some(d) = dir {
                self.snapshot(scene, d)?;
            }
        }
        let before = self.world.step_count();
        let point = match &mut self.stage {
            Stage::Compression(r) => r.advance(&mut self.world),
            Stage::BoundaryStress(r) => r.advance(&mut self.world),
        };
        self.loading_steps_done += self.world.step_count() - before;
        if point.is_some() {
            self.records += 1;
        }
        let every = scene.loading.vtk_interval;
        let periodic = point.is_some() && every > 0 && self.records.is_multiple_of(every);
        // The last snapshot shows the final state.
        if periodic || self.finished() {
            if let Some(d) = dir {
                self.snapshot(scene, d)?;
            }
        }
        Ok(())
    }

    fn write_tables(&self, dir: &Path) -> Result<()> {
        let w = &self.world;
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

    fn results(&self) -> serde_json::Value {
        let w = &self.world;
        let test = match &self.stage {
            Stage::Compression(r) if !r.curve.is_empty() => {
                let r = r.result(w);
                json!({
                    "youngs_modulus": r.youngs_modulus,
                    "peak_axial_stress": r.peak_stress,
                    "peak_deviator_stress": r.peak_deviator,
                    "peak_axial_strain": r.peak_strain,
                    "loading_steps": r.steps,
                })
            }
            Stage::Compression(_) => json!({}),
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
        json!({
            "particles": self.particles,
            "bonds": self.bonds,
            "packing_steps": self.packing_steps,
            "packing_converged": self.packing_converged,
            "size_factor": self.size_factor,
            "isotropic_wall_stresses": self.wall_stresses,
            "test": test,
            "broken_bonds": w.breaks.len(),
            "broken_in_tension": count(BreakMode::Tension),
            "broken_in_shear": count(BreakMode::Shear),
            "broken_in_compression": count(BreakMode::Compression),
            "vtk_snapshots": self.snapshots,
        })
    }
}

fn mode_name(m: BreakMode) -> &'static str {
    match m {
        BreakMode::Tension => "tension",
        BreakMode::Shear => "shear",
        BreakMode::Compression => "compression",
    }
}

/// The dry kind.
pub struct Dry;

impl Kind for Dry {
    const NAME: &'static str = "dry";
    const NOT_MEASURED: &'static [&'static str] = &[
        "final_axial_strain",
        "final_lateral_strain",
        "final_bottom_platen_stress",
        "final_lateral_stress",
    ];
    type Scene = DryScene;
    type Setup = DrySetup;
    type State = DryState;

    fn validate(scene: &DryScene) -> Result<()> {
        scene.validate()
    }

    fn budget(scene: &DryScene, setup: &DrySetup) -> Result<Budget> {
        let l = &scene.loading;
        let steps = dry_steps(scene, setup.timestep)?;
        // One stress-strain record per record interval (none while settling), plus the last.
        let records = limits::records_every(steps, l.record_interval);
        if l.vtk_interval > 0 {
            limits::snapshots_every("loading.vtk_interval", records, l.vtk_interval)?;
        }
        let mut b = packing_budget(&scene.packing)?;
        b.add_items(
            "stress-strain records",
            "loading.record_interval",
            records,
            std::mem::size_of::<CurvePoint>() as u64,
        )?;
        Ok(b)
    }

    fn setup(scene: &DryScene) -> Result<DrySetup> {
        let critical = critical_time_step(&scene.packing, &scene.solid);
        let dt = scene.solid.timestep;
        if !(critical.is_finite() && critical > 0.0) {
            return Err(LbdemError::field(
                "solid.normal_stiffness",
                format!("{:e}", scene.solid.normal_stiffness),
                &format!("gives a DEM critical step of {critical:e}, not a positive finite time"),
                "check the magnitudes of the stiffnesses, packing.radius_min and packing.density",
            ));
        }
        if dt.is_nan() || dt > CRITICAL_STEP_SAFETY * critical {
            return Err(LbdemError::field(
                "solid.timestep",
                format!("{dt:e}"),
                &format!(
                    "exceeds {CRITICAL_STEP_SAFETY} x the DEM critical step {critical:e} (smallest particle, six contacts and six bonds)"
                ),
                &format!("use solid.timestep <= {:e}", CRITICAL_STEP_SAFETY * critical),
            ));
        }
        Ok(DrySetup {
            critical_time_step: critical,
            timestep: dt,
        })
    }

    fn describe(case: &Case<Self>) -> String {
        describe(&case.scene, case.setup.critical_time_step)
    }

    fn start(case: &Case<Self>, _exec: &Exec) -> Result<DryState> {
        Ok(match case.scene.scene.precision {
            Precision::F32 => DryState::F32(start_run(&case.scene)?),
            Precision::F64 => DryState::F64(start_run(&case.scene)?),
        })
    }

    fn check_resumed(case: &Case<Self>, state: &DryState) -> Result<()> {
        let same = matches!(
            (state, case.scene.scene.precision),
            (DryState::F32(_), Precision::F32) | (DryState::F64(_), Precision::F64)
        );
        if same {
            Ok(())
        } else {
            Err(LbdemError::Checkpoint {
                path: String::new(),
                problem: "holds a state of the other precision than the scene's".into(),
                hint: "the scene's precision must not change between the run and its resume".into(),
            })
        }
    }

    fn steps_done(state: &DryState) -> u64 {
        each!(state, r => r.loading_steps_done)
    }

    fn total_steps(case: &Case<Self>, _state: &DryState) -> Option<u64> {
        // Checked by `budget`: the loading steps to reach max_strain at the platen speed (the test usually
        // stops earlier, at failure).
        dry_steps(&case.scene, case.setup.timestep).ok()
    }

    fn finished(_case: &Case<Self>, state: &DryState) -> bool {
        each!(state, r => r.finished())
    }

    fn advance(case: &Case<Self>, state: &mut DryState, dir: Option<&Path>) -> Result<()> {
        each!(state, r => r.advance(&case.scene, dir))
    }

    fn health(_case: &Case<Self>, state: &DryState) -> Result<()> {
        each!(state, r => dem_health(&r.world))
    }

    fn write_outputs(
        _case: &Case<Self>,
        state: &DryState,
        dir: &Path,
        _stage: OutputStage,
    ) -> Result<()> {
        // Periodic checkpoints flush the tables too, so that a killed run keeps its records so far.
        each!(state, r => r.write_tables(dir))
    }

    fn results(_case: &Case<Self>, state: &DryState) -> Result<serde_json::Value> {
        Ok(each!(state, r => r.results()))
    }
}

/// The steps of a dry run after packing, refused above [`limits::MAX_STEPS`] naming the field that sets them:
/// `loading.steps` (boundary stress); the settling steps and the loading steps to reach `loading.max_strain`
/// at `loading.platen_speed` (compression), the loading in whole record intervals (the test stops at the end of
/// one).
fn dry_steps(scene: &DryScene, dt: f64) -> Result<u64> {
    let l = &scene.loading;
    match l.test {
        LoadingKind::BoundaryStress => limits::steps("loading.steps", l.steps),
        LoadingKind::Compression => {
            if l.settle_steps > limits::MAX_STEPS {
                limits::steps("loading.settle_steps", l.settle_steps)?;
            }
            // Both platens move: the axial strain grows by 2 v dt / height per step.
            let per_step = 2.0 * l.platen_speed * dt / scene.packing.height;
            let loading = limits::steps_for("loading.platen_speed", l.max_strain, per_step, true)?;
            let interval = l.record_interval.max(1);
            let field = if interval > loading {
                "loading.record_interval"
            } else {
                "loading.platen_speed"
            };
            let loading = limits::mul(
                field,
                "the loading steps",
                loading.div_ceil(interval),
                interval,
            )?;
            let loading = limits::steps(field, loading)?;
            let field = if l.settle_steps > loading {
                "loading.settle_steps"
            } else {
                field
            };
            limits::steps(
                field,
                limits::add(field, "the step count", l.settle_steps, loading)?,
            )
        }
    }
}

fn describe(scene: &DryScene, critical: f64) -> String {
    let labels = scene.scene.units.labels();
    let p = &scene.packing;
    let mean_area = std::f64::consts::PI
        * p.aspect_ratio
        * (p.radius_min * p.radius_min + p.radius_min * p.radius_max + p.radius_max * p.radius_max)
        / 3.0;
    format!(
            "  packing: {} x {} {len} box, about {:.0} particles (solid fraction {}), seed {}, isotropic stress {} {pr}\n  DEM critical step {critical:.4e} {t} (x{CRITICAL_STEP_SAFETY} = {:.4e}); chosen step {:.4e} {t} ({:.2} of critical)\n  loading: {} at platen speed {} {v} each, up to axial strain {}\n",
            p.width,
            p.height,
            p.solid_fraction * p.width * p.height / mean_area,
            p.solid_fraction,
            p.seed,
            p.isotropic_stress,
            CRITICAL_STEP_SAFETY * critical,
            scene.solid.timestep,
            scene.solid.timestep / critical,
            match (scene.loading.test, scene.loading.confining_stress > 0.0) {
                (LoadingKind::BoundaryStress, _) => format!(
                    "boundary stress (fracture-test dry control): axial {} through the top particles, lateral {} by servo platens, {} steps;",
                    scene.loading.axial_stress, scene.loading.lateral_stress, scene.loading.steps
                ),
                (_, true) => format!(
                    "biaxial compression, confining stress {}",
                    scene.loading.confining_stress
                ),
                _ => "uniaxial compression".to_string(),
            },
            scene.loading.platen_speed,
            scene.loading.max_strain,
            len = labels.length,
            pr = labels.pressure,
            t = labels.time,
            v = labels.velocity,
        )
}
