//! Long runs: a generic run loop with a progress bar (ETA, throughput), periodic checkpoints (every N steps or
//! every N wall-clock seconds), Ctrl-C handling, divergence stops, and resume.
//!
//! A scene kind plugs in by implementing [`LongTask`] (advance one chunk, report progress, write outputs) for
//! its run state, whose persistent part implements [`Persist`]; [`LongRun::run`] does the rest:
//!
//! * before each chunk it checks the process-wide interrupt flag ([`interrupt_requested`], set by the Ctrl-C
//!   handler of [`install_interrupt_handler`] or by [`request_interrupt`]); when set it writes
//!   `DIR/checkpoint.bin` and the outputs so far and returns [`RunEnd::Interrupted`]
//!   ([`RunEnd::into_result`] turns that into an [`LbdemError::Interrupted`] telling the user
//!   `lbdem resume DIR`);
//! * after each chunk it writes a checkpoint when the [`CheckpointInterval`] is due;
//! * when a chunk reports divergence ([`LbdemError::Diverged`] or [`LbdemError::DivergedParticle`]) it writes
//!   the diverged state to `DIR/diverged_state.bin` (the last good `checkpoint.bin` is kept), writes the
//!   outputs so far, and returns the error;
//! * at the end it writes a final checkpoint and the final outputs.
//!
//! Checkpoints hold the whole state, so a resumed run ([`LongRun::run`] on the state loaded with
//! [`Checkpoint::load`]) produces outputs bitwise identical to an uninterrupted run (tested).
//!
//! A run directory holds `scene.toml` (the scene text the run started from, written by [`start_run_dir`]),
//! `checkpoint.bin`, the outputs, and `summary.json` once finished.
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Once;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};

use crate::checkpoint::{Checkpoint, Persist, CHECKPOINT_FILE, DIVERGED_FILE, SCENE_COPY};
use crate::error::{LbdemError, Result};
use crate::output::{prepare_dir, write_atomic};

static INTERRUPTED: AtomicBool = AtomicBool::new(false);
static HANDLER: Once = Once::new();

/// Install the Ctrl-C (SIGINT/SIGTERM) handler once per process: the first Ctrl-C sets the interrupt flag
/// (run loops then checkpoint and stop), a second one exits at once. Failing to install it only loses the
/// graceful stop, so that is a warning, not an error.
pub fn install_interrupt_handler() {
    HANDLER.call_once(|| {
        let result = ctrlc::set_handler(|| {
            if INTERRUPTED.swap(true, Ordering::SeqCst) {
                eprintln!("\nlbdem: second interrupt, exiting without a checkpoint");
                std::process::exit(130);
            }
            eprintln!("\nlbdem: interrupt received, writing a checkpoint (Ctrl-C again to abort)…");
        });
        if let Err(e) = result {
            eprintln!("lbdem: warning: cannot install the Ctrl-C handler ({e}); Ctrl-C will stop without a checkpoint");
        }
    });
}

/// Whether an interrupt has been requested.
pub fn interrupt_requested() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// Request an interrupt (what Ctrl-C does; for embedding and tests).
pub fn request_interrupt() {
    INTERRUPTED.store(true, Ordering::SeqCst);
}

/// Clear the interrupt flag (after handling it, before starting another run in the same process).
pub fn clear_interrupt() {
    INTERRUPTED.store(false, Ordering::SeqCst);
}

/// How often a long run writes its checkpoint (scene key `[run] checkpoint_interval`): an integer is a number
/// of steps, a string a wall-clock duration (`"90 s"`, `"10 min"`, `"2 h"`), `"never"` (or 0) only at the end
/// and on interrupt. Default: every 10 minutes of wall-clock time.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "IntervalRepr", into = "IntervalRepr")]
pub enum CheckpointInterval {
    /// Every this many steps.
    Steps(u64),
    /// Every this many wall-clock seconds.
    WallSeconds(f64),
    /// Only at the end and on interrupt or divergence.
    Never,
}

impl Default for CheckpointInterval {
    fn default() -> Self {
        CheckpointInterval::WallSeconds(600.0)
    }
}

#[derive(Clone, Serialize, Deserialize)]
#[serde(untagged)]
enum IntervalRepr {
    Steps(u64),
    Text(String),
}

impl TryFrom<IntervalRepr> for CheckpointInterval {
    type Error = String;
    fn try_from(r: IntervalRepr) -> std::result::Result<Self, String> {
        match r {
            IntervalRepr::Steps(0) => Ok(CheckpointInterval::Never),
            IntervalRepr::Steps(n) => Ok(CheckpointInterval::Steps(n)),
            IntervalRepr::Text(t) => CheckpointInterval::parse(&t),
        }
    }
}

impl From<CheckpointInterval> for IntervalRepr {
    fn from(c: CheckpointInterval) -> Self {
        match c {
            CheckpointInterval::Steps(n) => IntervalRepr::Steps(n),
            CheckpointInterval::WallSeconds(s) => IntervalRepr::Text(format!("{s} s")),
            CheckpointInterval::Never => IntervalRepr::Text("never".into()),
        }
    }
}

impl CheckpointInterval {
    /// Parse `"never"`, `"<n> steps"`, or a duration `"<x> s|min|h"`.
    pub fn parse(text: &str) -> std::result::Result<Self, String> {
        let t = text.trim();
        if t == "never" {
            return Ok(CheckpointInterval::Never);
        }
        let split = t
            .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == '+' || c == '-'))
            .unwrap_or(t.len());
        let (num, unit) = (t[..split].trim(), t[split..].trim());
        let bad = || {
            format!(
                "run.checkpoint_interval = {text:?} is not understood; use a step count (e.g. 5000), a wall-clock duration (\"90 s\", \"10 min\", \"2 h\") or \"never\""
            )
        };
        let x: f64 = num.parse().map_err(|_| bad())?;
        if !(x.is_finite() && x > 0.0) {
            return Err(bad());
        }
        let seconds = match unit {
            "s" | "sec" | "seconds" => x,
            "min" | "minutes" => 60.0 * x,
            "h" | "hours" => 3600.0 * x,
            "steps" | "step" if x.fract() == 0.0 => return Ok(CheckpointInterval::Steps(x as u64)),
            _ => return Err(bad()),
        };
        Ok(CheckpointInterval::WallSeconds(seconds))
    }
}

/// `[run]` keys of the long-run driver (scenes driven by [`LongRun`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LongRunSection {
    /// How often to write `DIR/checkpoint.bin` (default every 10 min of wall-clock time).
    #[serde(default)]
    pub checkpoint_interval: CheckpointInterval,
}

/// Why [`LongTask::write_outputs`] is called.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputStage {
    /// A periodic checkpoint was written (cheap outputs so far may be refreshed; optional).
    Checkpoint,
    /// The run was interrupted: write the outputs so far (no `summary.json`).
    Interrupted,
    /// The run diverged: write the outputs so far (no `summary.json`).
    Diverged,
    /// The run finished: write the final outputs, `summary.json` last.
    Finished,
}

/// A run loop that [`LongRun`] can drive, checkpoint and resume.
pub trait LongTask {
    /// The part written to checkpoints (the whole state that future chunks and outputs depend on).
    type State: Persist;
    /// Kind tag in the checkpoint header; `lbdem resume` dispatches on it (see [`crate::resume`]).
    const KIND: &'static str;
    /// The persistent state.
    fn state(&self) -> &Self::State;
    /// Steps done so far (the progress bar position and the checkpoint's step).
    fn steps_done(&self) -> u64;
    /// Expected total steps (progress bar length, ETA); `None` if unknown.
    fn total_steps(&self) -> Option<u64>;
    /// Whether the run is complete.
    fn finished(&self) -> bool;
    /// Advance by one chunk of at least one step (the unit between interrupt checks: keep it short, e.g. a
    /// record interval). Return [`LbdemError::Diverged`]/[`LbdemError::DivergedParticle`] (with an empty `out`,
    /// filled in by the run loop) when the state goes non-finite.
    fn advance(&mut self, dir: &Path) -> Result<()>;
    /// Write the outputs (see [`OutputStage`]); must not fail on a state with partial records.
    fn write_outputs(&mut self, dir: &Path, stage: OutputStage) -> Result<()>;
}

/// How a [`LongRun`] ended without error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunEnd {
    /// Ran to the end; final outputs written.
    Finished,
    /// Stopped on request (interrupt flag or `stop_after`) after writing a checkpoint at `step`.
    Interrupted {
        /// Step of the checkpoint.
        step: u64,
    },
}

impl RunEnd {
    /// `Ok(())` when finished; [`LbdemError::Interrupted`] (with the `lbdem resume DIR` hint) otherwise.
    pub fn into_result(self, dir: &Path) -> Result<()> {
        match self {
            RunEnd::Finished => Ok(()),
            RunEnd::Interrupted { step } => Err(LbdemError::Interrupted {
                step,
                dir: dir.display().to_string(),
            }),
        }
    }
}

/// The generic long-run driver.
#[derive(Clone, Debug)]
pub struct LongRun<'a> {
    /// Run directory (checkpoint, scene copy, outputs).
    pub dir: &'a Path,
    /// The scene text (its hash goes into every checkpoint).
    pub scene_text: &'a str,
    /// Checkpoint interval.
    pub interval: CheckpointInterval,
    /// Hide the progress bar.
    pub quiet: bool,
    /// Stop as if interrupted once at least this many steps are done (testing and batch slicing).
    pub stop_after: Option<u64>,
}

impl<'a> LongRun<'a> {
    /// A driver for `dir` with the default interval, progress bar shown.
    pub fn new(dir: &'a Path, scene_text: &'a str) -> Self {
        Self {
            dir,
            scene_text,
            interval: CheckpointInterval::default(),
            quiet: false,
            stop_after: None,
        }
    }

    /// Write the checkpoint of `task` to `DIR/checkpoint.bin`.
    pub fn save<T: LongTask>(&self, task: &T) -> Result<()> {
        Checkpoint::save(
            &self.dir.join(CHECKPOINT_FILE),
            self.scene_text,
            T::KIND,
            task.steps_done(),
            task.state(),
        )
    }

    /// Drive `task` to the end (or to an interrupt), checkpointing as configured.
    pub fn run<T: LongTask>(&self, task: &mut T) -> Result<RunEnd> {
        let bar = if self.quiet {
            ProgressBar::hidden()
        } else {
            match task.total_steps() {
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
        bar.set_position(task.steps_done());
        bar.reset_eta();
        let mut last_step = task.steps_done();
        let mut last_time = Instant::now();
        while !task.finished() {
            let stop = self.stop_after.is_some_and(|n| task.steps_done() >= n);
            if interrupt_requested() || stop {
                bar.finish_and_clear();
                self.save(task)?;
                task.write_outputs(self.dir, OutputStage::Interrupted)?;
                return Ok(RunEnd::Interrupted {
                    step: task.steps_done(),
                });
            }
            if let Err(e) = task.advance(self.dir) {
                bar.finish_and_clear();
                let e = self.with_dir(e);
                if matches!(
                    e,
                    LbdemError::Diverged { .. } | LbdemError::DivergedParticle { .. }
                ) {
                    Checkpoint::save(
                        &self.dir.join(DIVERGED_FILE),
                        self.scene_text,
                        T::KIND,
                        task.steps_done(),
                        task.state(),
                    )?;
                    task.write_outputs(self.dir, OutputStage::Diverged)?;
                }
                return Err(e);
            }
            let step = task.steps_done();
            bar.set_position(step);
            if let Some(n) = task.total_steps() {
                if n < step {
                    bar.set_length(step);
                }
            }
            let due = match self.interval {
                CheckpointInterval::Steps(n) => step >= last_step + n,
                CheckpointInterval::WallSeconds(s) => {
                    last_time.elapsed() >= Duration::from_secs_f64(s)
                }
                CheckpointInterval::Never => false,
            };
            if due && !task.finished() {
                self.save(task)?;
                task.write_outputs(self.dir, OutputStage::Checkpoint)?;
                last_step = step;
                last_time = Instant::now();
            }
        }
        bar.finish_and_clear();
        self.save(task)?;
        task.write_outputs(self.dir, OutputStage::Finished)?;
        Ok(RunEnd::Finished)
    }

    fn with_dir(&self, e: LbdemError) -> LbdemError {
        let dir = self.dir.display().to_string();
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
                out: if out.is_empty() { dir } else { out },
                hint: format!("{hint}; the last good checkpoint is {CHECKPOINT_FILE}, the diverged state {DIVERGED_FILE}"),
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
                out: if out.is_empty() { dir } else { out },
                hint: format!("{hint}; the last good checkpoint is {CHECKPOINT_FILE}, the diverged state {DIVERGED_FILE}"),
            },
            other => other,
        }
    }
}

/// Prepare the directory of a new resumable run: refuse one holding a previous run (finished or
/// interrupted) unless `overwrite`, remove a previous run's checkpoints when overwriting, and save the scene
/// text as `DIR/scene.toml` (what `lbdem resume DIR` reads).
pub fn start_run_dir(dir: &Path, scene_text: &str, overwrite: bool) -> Result<()> {
    prepare_dir(dir, overwrite)?;
    for stale in [CHECKPOINT_FILE, DIVERGED_FILE] {
        let p = dir.join(stale);
        if p.exists() {
            std::fs::remove_file(&p).map_err(|e| LbdemError::Write {
                path: p.display().to_string(),
                source: e,
            })?;
        }
    }
    write_atomic(&dir.join(SCENE_COPY), scene_text.as_bytes())
}

/// The scene text saved in a run directory.
pub fn read_scene_copy(dir: &Path) -> Result<String> {
    let p = dir.join(SCENE_COPY);
    std::fs::read_to_string(&p).map_err(|e| LbdemError::Checkpoint {
        path: dir.join(CHECKPOINT_FILE).display().to_string(),
        problem: format!(
            "cannot be resumed: the scene copy {} cannot be read ({e})",
            p.display()
        ),
        hint: "a resumable run keeps scene.toml next to checkpoint.bin; restore it unchanged"
            .into(),
    })
}

/// First particle whose position, angle, velocity or angular velocity is not finite, as
/// [`LbdemError::DivergedParticle`] (for [`LongTask::advance`] implementations).
pub fn dem_health<T: lbdem_kernels::Real>(
    world: &crate::solid::DemWorld<T>,
) -> std::result::Result<(), LbdemError> {
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
