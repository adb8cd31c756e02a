//! Runs: the [`Kind`] contract every scene kind implements, and the one long-run loop that drives every kind
//! ([`drive`]): progress bar (ETA, throughput), periodic checkpoints (every N steps or every N wall-clock
//! seconds), Ctrl-C/SIGTERM, health checks, outputs so far on divergence, the summary, and bitwise resume.
//!
//! * Before each chunk the loop checks the stop request ([`signal::Stop`], raised by the Ctrl-C/SIGTERM handler
//!   of the command line or by a caller); when raised it writes `DIR/checkpoint.bin` and the outputs so far and
//!   returns [`LbdemError::Interrupted`] (exit code 130 at the command line; `lbdem resume DIR` continues).
//! * After each chunk ([`Kind::advance`]) it runs the kind's health check ([`Kind::health`]: finite values,
//!   density band, DEM state); on divergence it writes the diverged state to `DIR/diverged_state.bin` (the last
//!   good `checkpoint.bin` is kept), writes the outputs so far, and returns the error.
//! * It writes a checkpoint when the [`CheckpointInterval`] is due.
//! * At the end it writes a final checkpoint, the final outputs, and `summary.json` last ([`summary`]).
//!
//! Checkpoints hold the whole state, so a resumed run produces outputs bitwise identical to an uninterrupted run
//! (tested for every kind).
use std::path::Path;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::engine::exec::{Exec, ExecTarget};
use crate::error::{LbdemError, Result};
use crate::input::limits::Budget;
use crate::output::summary::{Execution, Summary};
use crate::output::{
    read_scene_copy, start_run_dir, write_atomic, CHECKPOINT_FILE, DIVERGED_FILE, SCENE_COPY,
    SUMMARY_FILE,
};
use crate::units::{UnitLabels, UnitSystem};

pub mod cases;
pub mod checkpoint;
pub mod interval;
pub mod signal;

pub use checkpoint::{Checkpoint, Persist};
pub use interval::CheckpointInterval;
pub use signal::Stop;

/// Why [`Kind::write_outputs`] is called.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputStage {
    /// A periodic checkpoint was written (cheap outputs so far may be refreshed; optional).
    Checkpoint,
    /// The run was interrupted: write the outputs so far.
    Interrupted,
    /// The run diverged: write the outputs so far.
    Diverged,
    /// The run finished: write the final outputs (the loop writes `summary.json` after them).
    Finished,
}

/// A scene and what is derived from it before running: the pair every [`Kind`] method reads.
pub struct Case<K: Kind> {
    /// The scene file's content, parsed and range-checked.
    pub scene: K::Scene,
    /// Everything derived from it (lattice size, units, critical steps, …): what `lbdem check` prints.
    pub setup: K::Setup,
    /// The sizes and the memory the run needs, checked against the limits ([`crate::input::limits`]).
    pub budget: Budget,
}

impl<K: Kind> Case<K> {
    /// Parse scene text (`path` for messages), range-check it and derive its set-up.
    pub fn read(text: &str, path: &str) -> Result<Self> {
        let scene: K::Scene = crate::input::parse::parse_scene(text, path)?;
        Self::new(scene)
    }

    /// Range-check a scene, derive its set-up and check every size it implies and the memory it needs
    /// against the limits — all without allocating anything that grows with the scene. This is the whole
    /// validation of `lbdem run`; `lbdem check` is exactly this.
    pub fn new(scene: K::Scene) -> Result<Self> {
        K::validate(&scene)?;
        let setup = K::setup(&scene)?;
        let budget = K::budget(&scene, &setup)?;
        budget.check()?;
        Ok(Self {
            scene,
            setup,
            budget,
        })
    }

    /// What `lbdem check` prints: the derived figures and the warnings.
    pub fn describe(&self, path: &str) -> String {
        let mut s = format!("scene {path} is valid (kind = {})\n", K::NAME);
        s += &K::describe(self);
        s += &self.budget.describe();
        for w in self.setup.warnings() {
            s += &format!("  WARNING: {w}\n");
        }
        s
    }
}

/// The sections every scene file has, as the run loop and the summary read them: `[scene] units` and `[run]
/// checkpoint_interval`. `crate::scene::scene_file!` implements it for a scene type with the usual fields
/// `scene` (`SceneHeader`) and `run` (`RunSection` or `CheckpointSection`).
pub trait SceneFile: Serialize + DeserializeOwned + Sync {
    /// `[scene] units`: the unit system of the scene's values (labels of the outputs).
    fn unit_system(&self) -> UnitSystem;
    /// The labels of the units of the scene's values and outputs (`units` of the summary): those of
    /// [`SceneFile::unit_system`], unless the scene is in lattice units ([`UnitLabels::LATTICE`]).
    fn unit_labels(&self) -> UnitLabels {
        self.unit_system().labels()
    }
    /// `[run] checkpoint_interval`.
    fn checkpoint_interval(&self) -> CheckpointInterval;
}

/// What every kind's set-up carries besides its own figures: warnings about the settings (printed at
/// start-up and by `lbdem check`, listed in the summary). None unless the set-up says otherwise.
pub trait Derived: Serialize + Sync {
    /// The warnings.
    fn warnings(&self) -> &[String] {
        &[]
    }
}

/// One scene kind. Each kind is one folder under `driver/src/kinds/` implementing this trait, plus one line in
/// the registry (`crate::kinds::REGISTRY`); kinds never import each other. The methods are called by [`drive`]
/// in this order: [`Kind::validate`], [`Kind::setup`], [`Kind::start`] (or [`Kind::resume`] on a checkpointed
/// state), then [`Kind::advance`] and [`Kind::health`] chunk after chunk until [`Kind::finished`], with
/// [`Kind::write_outputs`] at checkpoints, interrupts, divergence and the end, and [`Kind::results`] for the
/// summary.
pub trait Kind: Sized + 'static {
    /// `[scene] kind` of its scene files, and the kind tag of its checkpoints.
    const NAME: &'static str;
    /// The top-level section only this kind's scene files have (`[porous]` for `porous_flow`), if any: names
    /// the kind a scene file was probably meant to be when its `[scene] kind` does not match its sections.
    const OWN_SECTION: Option<&'static str> = None;
    /// The scene file (TOML, `deny_unknown_fields`).
    type Scene: SceneFile;
    /// What is derived from the scene before running (printed by `lbdem check`, `derived` in the summary).
    type Setup: Derived;
    /// Everything a run needs to continue bitwise exactly: what checkpoints hold.
    type State: Persist + Send;
    /// Names of result keys (the last segment of a `results` path) whose value may be `null` meaning "not
    /// applicable" or "not measured" (an `Option` that is `None`, or a documented NaN sentinel such as the
    /// drift of a run that never became steady). Every other `null` in the results is a non-finite number and
    /// fails the run ([`LbdemError::NonFiniteResult`]).
    const NOT_MEASURED: &'static [&'static str] = &[];

    /// Range checks naming the field and the fix.
    fn validate(scene: &Self::Scene) -> Result<()>;
    /// Derive the set-up (units, sizes, limits), refusing unstable settings.
    fn setup(scene: &Self::Scene) -> Result<Self::Setup>;
    /// The sizes a run of the scene implies (lattice nodes, grains, steps, records, snapshots, cases), each
    /// computed in checked arithmetic ([`crate::input::limits`]) and refused naming its field when above a
    /// limit, with the memory they take: checked against the machine's available memory before anything is
    /// allocated. Must not allocate anything that grows with the scene.
    fn budget(scene: &Self::Scene, setup: &Self::Setup) -> Result<Budget>;
    /// The derived figures, one per line, indented by two spaces.
    fn describe(case: &Case<Self>) -> String;
    /// Build the initial state (allocate, pack, settle: everything before the first chunk).
    fn start(case: &Case<Self>, exec: &Exec) -> Result<Self::State>;
    /// The fluid lattices of a state (none for a dry kind): [`Kind::resume`] applies this process's execution
    /// settings (SIMD level, streaming scheme) to them.
    fn lattices(_state: &mut Self::State) -> Vec<&mut dyn ExecTarget> {
        Vec::new()
    }
    /// Check that a state loaded from a checkpoint fits the scene (beyond what the checksum guarantees), with
    /// [`LbdemError::Checkpoint`] naming what does not. Nothing to check by default.
    fn check_resumed(_case: &Case<Self>, _state: &Self::State) -> Result<()> {
        Ok(())
    }
    /// Take over a state loaded from a checkpoint: [`Kind::check_resumed`], then this process's execution
    /// settings on [`Kind::lattices`].
    fn resume(case: &Case<Self>, state: &mut Self::State, exec: &Exec) -> Result<()> {
        Self::check_resumed(case, state)?;
        for lattice in Self::lattices(state) {
            lattice.take(exec);
        }
        Ok(())
    }
    /// Steps done so far (progress, checkpoint header).
    fn steps_done(state: &Self::State) -> u64;
    /// Expected total steps (progress bar, ETA), if known.
    fn total_steps(case: &Case<Self>, state: &Self::State) -> Option<u64>;
    /// Whether the run is complete.
    fn finished(case: &Case<Self>, state: &Self::State) -> bool;
    /// Advance by one chunk of at least one step (the unit between interrupt checks: keep it short). `dir` is
    /// the run directory (snapshots written during the run), `None` for runs kept in memory.
    fn advance(case: &Case<Self>, state: &mut Self::State, dir: Option<&Path>) -> Result<()>;
    /// [`Kind::advance`] as the run loop calls it, with the run's stop request: a kind whose chunk can be long
    /// (the fracture test's intact-sample measurements, up to 4·10⁵ fluid steps) abandons it when `stop` is
    /// raised and leaves the state exactly as it was before the chunk, which the loop then checkpoints; a
    /// resume redoes the chunk from that state, bitwise as an uninterrupted run would. Default: `advance`.
    fn advance_or_stop(
        case: &Case<Self>,
        state: &mut Self::State,
        dir: Option<&Path>,
        _stop: &Stop,
    ) -> Result<()> {
        Self::advance(case, state, dir)
    }
    /// Health of the state after a chunk: [`LbdemError::Diverged`] / [`LbdemError::DivergedParticle`] (with
    /// an empty `out`, filled in by the loop) when a value is non-finite or out of its band.
    fn health(case: &Case<Self>, state: &Self::State) -> Result<()>;
    /// Write the outputs (tables, VTK, figures) of the state so far; must not fail on partial records.
    fn write_outputs(
        case: &Case<Self>,
        state: &Self::State,
        dir: &Path,
        stage: OutputStage,
    ) -> Result<()>;
    /// The `results` part of the summary.
    fn results(case: &Case<Self>, state: &Self::State) -> Result<serde_json::Value>;
}

/// How `lbdem run` / `lbdem resume` drive a run (everything but the scene).
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Replace a previous run in the output directory.
    pub overwrite: bool,
    /// Hide the progress bar and the start-up description.
    pub quiet: bool,
    /// Threads, SIMD level, streaming scheme: speed only, never a bit of the results.
    pub exec: Exec,
    /// The stop request (Ctrl-C/SIGTERM at the command line).
    pub stop: Stop,
    /// Stop as if interrupted once at least this many steps are done (batch slicing and tests).
    pub stop_after: Option<u64>,
    /// Testing aid: once this many steps are done, create the file given and wait (at most two minutes) for a
    /// stop request, so that a test can deliver a real signal mid-run (`LBDEM_TEST_HOLD=STEP:FILE` at the
    /// command line).
    pub hold_at: Option<(u64, std::path::PathBuf)>,
}

/// `lbdem check`: parse, validate and describe scene text of kind `K`.
pub fn check<K: Kind>(text: &str, path: &str) -> Result<String> {
    Ok(Case::<K>::read(text, path)?.describe(path))
}

/// `lbdem run`: start a run of scene text `text` (kind `K`) in `out` and drive it to its end. Returns the
/// summary.
pub fn run<K: Kind>(
    text: &str,
    path: &str,
    out: &Path,
    opts: &RunOptions,
) -> Result<serde_json::Value> {
    run_from::<K>(text, path, out, opts, K::start)
}

/// [`run`] with the initial state built by `start` instead of [`Kind::start`] (e.g. from a packing made once
/// for several scenes of the same sample).
pub fn run_from<K: Kind>(
    text: &str,
    path: &str,
    out: &Path,
    opts: &RunOptions,
    start: impl FnOnce(&Case<K>, &Exec) -> Result<K::State> + Send,
) -> Result<serde_json::Value> {
    let case = Case::<K>::read(text, path)?;
    start_run_dir(out, text, opts.overwrite)?;
    if !opts.quiet {
        eprint!("lbdem: {}", case.describe(path));
    }
    opts.exec.install(|| {
        let started = Instant::now();
        let state = start(&case, &opts.exec)?;
        let segment = Segment {
            path,
            text,
            started,
            first_step: 0,
        };
        drive(&case, state, Some(out), &segment, opts)
    })?
}

/// `lbdem resume DIR` of a run of kind `K`: continue from `DIR/checkpoint.bin` with the scene copy saved at its
/// start.
pub fn resume<K: Kind>(dir: &Path, opts: &RunOptions) -> Result<serde_json::Value> {
    let text = read_scene_copy(dir)?;
    let copy = dir.join(SCENE_COPY).display().to_string();
    let case = Case::<K>::read(&text, &copy)?;
    let (header, mut state) =
        Checkpoint::load::<K::State>(&dir.join(CHECKPOINT_FILE), &text, K::NAME)?;
    if K::steps_done(&state) != header.step {
        return Err(LbdemError::Checkpoint {
            path: dir.join(CHECKPOINT_FILE).display().to_string(),
            problem: format!(
                "says step {} in its header but its state is at step {}",
                header.step,
                K::steps_done(&state)
            ),
            hint: "the file is damaged; resume from an earlier copy or start the run again (--overwrite)".into(),
        });
    }
    if K::finished(&case, &state) && dir.join(SUMMARY_FILE).exists() {
        return Err(LbdemError::AlreadyFinished {
            dir: dir.display().to_string(),
            steps: header.step,
        });
    }
    if !opts.quiet {
        eprintln!(
            "lbdem: resuming {} run in {} at step {}",
            K::NAME,
            dir.display(),
            header.step
        );
    }
    opts.exec.install(|| {
        let started = Instant::now();
        K::resume(&case, &mut state, &opts.exec)?;
        let segment = Segment {
            path: &copy,
            text: &text,
            started,
            first_step: header.step,
        };
        drive(&case, state, Some(dir), &segment, opts)
    })?
}

/// Drive a case to its end in memory (no directory, no checkpoints; the stop request is still honoured):
/// for studies and tests. Returns the final state and the results.
pub fn run_in_memory<K: Kind>(
    case: &Case<K>,
    opts: &RunOptions,
) -> Result<(K::State, serde_json::Value)> {
    opts.exec.install(|| {
        let mut state = K::start(case, &opts.exec)?;
        let segment = Segment {
            path: "",
            text: "",
            started: Instant::now(),
            first_step: 0,
        };
        let mut local = opts.clone();
        local.quiet = true;
        drive_loop(case, &mut state, None, &segment, &local)?;
        let results = K::results(case, &state)?;
        Ok((state, results))
    })?
}

/// The part of a run this process does.
struct Segment<'a> {
    path: &'a str,
    text: &'a str,
    started: Instant,
    first_step: u64,
}

/// How [`drive_loop`] ended without error.
enum End {
    Finished,
    Interrupted(u64),
}

/// The one long-run loop (see the module documentation), then the summary.
fn drive<K: Kind>(
    case: &Case<K>,
    mut state: K::State,
    dir: Option<&Path>,
    segment: &Segment<'_>,
    opts: &RunOptions,
) -> Result<serde_json::Value> {
    match drive_loop(case, &mut state, dir, segment, opts)? {
        End::Interrupted(step) => Err(LbdemError::Interrupted {
            step,
            dir: dir.map(|d| d.display().to_string()).unwrap_or_default(),
        }),
        End::Finished => {
            let results = K::results(case, &state)?;
            let non_finite = crate::output::summary::non_finite(&results, K::NOT_MEASURED);
            let summary = Summary {
                schema_version: crate::output::summary::SCHEMA_VERSION,
                lbdem_version: env!("CARGO_PKG_VERSION"),
                kind: K::NAME,
                scene_file: segment.path.to_string(),
                scene: serde_json::to_value(&case.scene).unwrap_or_default(),
                units: case.scene.unit_labels(),
                derived: serde_json::to_value(&case.setup).unwrap_or_default(),
                warnings: case.setup.warnings().to_vec(),
                execution: Execution::of(&opts.exec),
                steps: K::steps_done(&state),
                segment_first_step: segment.first_step,
                wall_seconds: segment.started.elapsed().as_secs_f64(),
                results,
                non_finite,
            };
            let value = serde_json::to_value(&summary).unwrap_or_default();
            if let Some(dir) = dir {
                let text = serde_json::to_string_pretty(&value).unwrap_or_default();
                write_atomic(&dir.join(SUMMARY_FILE), text.as_bytes())?;
                if !opts.quiet {
                    eprintln!(
                        "lbdem: {} run finished after {} steps; outputs in {}",
                        K::NAME,
                        summary.steps,
                        dir.display()
                    );
                }
            }
            if !summary.non_finite.is_empty() {
                let list = summary
                    .non_finite
                    .iter()
                    .take(5)
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", ");
                return Err(LbdemError::NonFiniteResult {
                    count: summary.non_finite.len(),
                    list,
                    dir: dir.map(|d| d.display().to_string()).unwrap_or_default(),
                    hint: "the settings are outside what the method resolves (look at the warnings and derived \
                           figures printed by `lbdem check`); summary.json records everything that was measured"
                        .into(),
                });
            }
            Ok(value)
        }
    }
}

fn save<K: Kind>(dir: Option<&Path>, file: &str, text: &str, state: &K::State) -> Result<()> {
    match dir {
        Some(d) => Checkpoint::save(&d.join(file), text, K::NAME, K::steps_done(state), state),
        None => Ok(()),
    }
}

fn outputs<K: Kind>(
    case: &Case<K>,
    state: &K::State,
    dir: Option<&Path>,
    stage: OutputStage,
) -> Result<()> {
    match dir {
        Some(d) => K::write_outputs(case, state, d, stage),
        None => Ok(()),
    }
}

fn drive_loop<K: Kind>(
    case: &Case<K>,
    state: &mut K::State,
    dir: Option<&Path>,
    segment: &Segment<'_>,
    opts: &RunOptions,
) -> Result<End> {
    let bar = if opts.quiet {
        ProgressBar::hidden()
    } else {
        match K::total_steps(case, state) {
            Some(n) => ProgressBar::new(n),
            None => ProgressBar::new_spinner(),
        }
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:40} {pos}/{len} steps  {per_sec}  elapsed {elapsed}  eta {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_position(K::steps_done(state));
    bar.reset_eta();
    let interval = case.scene.checkpoint_interval();
    let mut last_step = K::steps_done(state);
    let mut last_time = Instant::now();
    let mut held = false;
    while !K::finished(case, state) {
        let step = K::steps_done(state);
        if let Some((at, marker)) = &opts.hold_at {
            if !held && step >= *at {
                held = true;
                hold(marker, &opts.stop);
            }
        }
        let sliced = opts.stop_after.is_some_and(|n| step >= n);
        if opts.stop.requested() || sliced {
            bar.finish_and_clear();
            save::<K>(dir, CHECKPOINT_FILE, segment.text, state)?;
            outputs(case, state, dir, OutputStage::Interrupted)?;
            return Ok(End::Interrupted(step));
        }
        let chunk =
            K::advance_or_stop(case, state, dir, &opts.stop).and_then(|()| K::health(case, state));
        if let Err(e) = chunk {
            bar.finish_and_clear();
            let e = with_dir(e, dir);
            if matches!(
                e,
                LbdemError::Diverged { .. } | LbdemError::DivergedParticle { .. }
            ) {
                save::<K>(dir, DIVERGED_FILE, segment.text, state)?;
                outputs(case, state, dir, OutputStage::Diverged)?;
            }
            return Err(e);
        }
        let step = K::steps_done(state);
        bar.set_position(step);
        if K::total_steps(case, state).is_some_and(|n| n < step) {
            bar.set_length(step);
        }
        let due = match interval {
            CheckpointInterval::Steps(n) => step >= last_step.saturating_add(n),
            CheckpointInterval::WallSeconds(s) => last_time.elapsed() >= Duration::from_secs_f64(s),
            CheckpointInterval::Never => false,
        };
        if due && dir.is_some() && !K::finished(case, state) {
            save::<K>(dir, CHECKPOINT_FILE, segment.text, state)?;
            outputs(case, state, dir, OutputStage::Checkpoint)?;
            last_step = step;
            last_time = Instant::now();
        }
    }
    bar.finish_and_clear();
    save::<K>(dir, CHECKPOINT_FILE, segment.text, state)?;
    outputs(case, state, dir, OutputStage::Finished)?;
    Ok(End::Finished)
}

/// The testing aid of [`RunOptions::hold_at`].
fn hold(marker: &Path, stop: &Stop) {
    let _ = std::fs::write(marker, b"holding\n");
    let t0 = Instant::now();
    while !stop.requested() && t0.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Fill the run directory into a divergence error raised by a chunk, and name the checkpoint files.
fn with_dir(e: LbdemError, dir: Option<&Path>) -> LbdemError {
    let d = dir.map(|d| d.display().to_string()).unwrap_or_default();
    let files = if dir.is_some() {
        format!(
            "; the last good checkpoint is {CHECKPOINT_FILE}, the diverged state {DIVERGED_FILE}"
        )
    } else {
        String::new()
    };
    match e {
        LbdemError::Diverged {
            step,
            quantity,
            value,
            x,
            y,
            out,
            hint,
        } => LbdemError::Diverged {
            step,
            quantity,
            value,
            x,
            y,
            out: if out.is_empty() { d } else { out },
            hint: format!("{hint}{files}"),
        },
        LbdemError::DivergedParticle {
            step,
            particle,
            quantity,
            value,
            out,
            hint,
        } => LbdemError::DivergedParticle {
            step,
            particle,
            quantity,
            value,
            out: if out.is_empty() { d } else { out },
            hint: format!("{hint}{files}"),
        },
        other => other,
    }
}
