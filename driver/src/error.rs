//! Typed errors of the driver. Every variant names the offending field and says how to fix it.
use thiserror::Error;

/// Errors from reading, validating or running a scene.
#[derive(Debug, Error)]
pub enum LbdemError {
    /// The scene file could not be read.
    #[error("cannot read scene file {path}: {source}")]
    ReadScene {
        /// Path given.
        path: String,
        /// Underlying I/O error.
        source: std::io::Error,
    },
    /// The scene is not valid TOML or does not match the schema (unknown key, wrong type, missing field).
    #[error("scene {path} is not valid: {message}\n  hint: {hint}")]
    ParseScene {
        /// Path given.
        path: String,
        /// Dotted path of the key the parser stopped at (e.g. `solid.bonds.strength`), empty when the text is
        /// not TOML at all.
        key: String,
        /// What the parser said, with the line, column and the offending line (cut to a sensible length).
        message: String,
        /// How to fix it.
        hint: String,
    },
    /// A field has a value outside its valid range.
    #[error("scene field `{field}` = {value}: {problem}\n  hint: {hint}")]
    InvalidField {
        /// Dotted path of the field, e.g. `fluid.tau`.
        field: String,
        /// The value found.
        value: String,
        /// What is wrong with it.
        problem: String,
        /// How to fix it.
        hint: String,
    },
    /// The run produced a non-finite or out-of-band value and was stopped.
    #[error("run stopped at step {step}: {quantity} = {value}{}; outputs written so far are kept in {out}\n  hint: {hint}", at_node(*.x, *.y))]
    Diverged {
        /// Step at which the check failed.
        step: u64,
        /// The quantity that failed (density, velocity).
        quantity: String,
        /// Its value.
        value: String,
        /// Node x ([`NO_NODE`] for a quantity not of one node: a mean, a flux, a boundary's velocity).
        x: usize,
        /// Node y ([`NO_NODE`] likewise).
        y: usize,
        /// Output directory.
        out: String,
        /// What to change.
        hint: String,
    },
    /// The output directory holds a previous run.
    #[error("output directory {0} already holds a run (summary.json exists)\n  hint: choose another --out or pass --overwrite")]
    OutputExists(String),
    /// A checkpoint could not be read, is damaged, or belongs to another run.
    #[error("checkpoint {path} {problem}\n  hint: {hint}")]
    Checkpoint {
        /// The checkpoint file.
        path: String,
        /// What is wrong with it.
        problem: String,
        /// What to do.
        hint: String,
    },
    /// The run finished but some of its results are not finite numbers; `summary.json` lists them and records
    /// everything else that was measured.
    #[error("run finished but {count} result(s) are not finite: {list}; summary.json (written to {dir}) lists them under `non_finite`\n  hint: {hint}")]
    NonFiniteResult {
        /// How many results are not finite.
        count: usize,
        /// The first few, `results.key = value`.
        list: String,
        /// The run directory.
        dir: String,
        /// What to change.
        hint: String,
    },
    /// `lbdem resume` of a run that has finished: nothing was changed.
    #[error("the run in {dir} is already finished (summary.json, {steps} steps); nothing to resume and nothing was changed\n  hint: start a new run with `lbdem run SCENE --out DIR` (or --overwrite to replace it)")]
    AlreadyFinished {
        /// The run directory.
        dir: String,
        /// Steps of the finished run.
        steps: u64,
    },
    /// The output directory holds files lbdem did not write, and `--overwrite` would have to delete them.
    #[error("output directory {dir} holds files lbdem did not write ({files}); --overwrite only removes lbdem's own outputs\n  hint: move those files away, or choose another --out")]
    ForeignFiles {
        /// The directory.
        dir: String,
        /// The first few foreign files.
        files: String,
    },
    /// The run was interrupted (Ctrl-C) after writing a checkpoint and the outputs so far.
    #[error("interrupted at step {step}: checkpoint and outputs so far written to {dir}\n  hint: continue with `lbdem resume {dir}`")]
    Interrupted {
        /// Step of the checkpoint.
        step: u64,
        /// The run directory.
        dir: String,
    },
    /// A particle's state became non-finite and the run was stopped.
    #[error("run stopped at step {step}: {quantity} of particle {particle} = {value}; outputs written so far are kept in {out}\n  hint: {hint}")]
    DivergedParticle {
        /// Step at which the check failed.
        step: u64,
        /// Particle index.
        particle: usize,
        /// The quantity that failed (position, velocity, angular velocity).
        quantity: String,
        /// Its value.
        value: String,
        /// Output directory.
        out: String,
        /// What to change.
        hint: String,
    },
    /// The output directory holds an interrupted run.
    #[error("output directory {0} holds an interrupted run (checkpoint.bin exists)\n  hint: continue it with `lbdem resume {0}`, choose another --out, or pass --overwrite to start again")]
    InterruptedRunExists(String),
    /// Writing an output failed.
    #[error("cannot write {path}: {source}")]
    Write {
        /// File being written.
        path: String,
        /// Underlying I/O error.
        source: std::io::Error,
    },
}

/// Longest piece of scene input quoted in a message (characters): a value, a key, a line of the file.
pub const QUOTE_CHARS: usize = 120;

/// `text` cut to at most `max` characters, saying how much was left out.
pub fn cut(text: &str, max: usize) -> String {
    let mut chars = text.char_indices();
    match chars.nth(max) {
        None => text.to_string(),
        Some((end, _)) => {
            let rest = text[end..].chars().count();
            format!("{}… ({rest} more characters)", &text[..end])
        }
    }
}

impl LbdemError {
    /// Shorthand for [`LbdemError::InvalidField`]; the value is quoted cut to [`QUOTE_CHARS`] characters.
    pub fn field(field: &str, value: impl ToString, problem: &str, hint: &str) -> Self {
        let mut value = value.to_string();
        // A huge float prints as hundreds of digits: show it in scientific notation.
        if value.len() > 24 {
            if let Ok(x) = value.parse::<f64>() {
                value = format!("{x:e}");
            }
        }
        Self::InvalidField {
            field: cut(field, QUOTE_CHARS),
            value: cut(&value, QUOTE_CHARS),
            problem: problem.to_string(),
            hint: hint.to_string(),
        }
    }
}

/// The node of a [`LbdemError::Diverged`] whose quantity belongs to no node (a mean pressure, a flux, the sealed
/// lid's velocity): its message then names no node.
pub const NO_NODE: usize = usize::MAX;

/// " at node (x, y)" for a [`LbdemError::Diverged`] message, nothing for [`NO_NODE`].
fn at_node(x: usize, y: usize) -> String {
    if x == NO_NODE || y == NO_NODE {
        String::new()
    } else {
        format!(" at node ({x}, {y})")
    }
}

/// Result alias of the driver.
pub type Result<T> = std::result::Result<T, LbdemError>;

/// Check that a scene value is finite and > 0, naming the field and giving a hint otherwise.
pub fn positive(field: &str, v: f64, hint: &str) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(LbdemError::field(
            field,
            v,
            "must be a finite number > 0",
            hint,
        ))
    }
}

/// Check that a scene value is finite and >= 0, naming the field and giving a hint otherwise.
pub fn non_negative(field: &str, v: f64, hint: &str) -> Result<()> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(LbdemError::field(
            field,
            v,
            "must be a finite number >= 0",
            hint,
        ))
    }
}

/// Check that a fraction lies in (0, 1] (e.g. `fluid_radius`, the fraction of a grain's radius the fluid sees,
/// dissertation ch. 5.3.4), naming the field; NaN refused.
pub fn fraction(field: &str, v: f64, hint: &str) -> Result<()> {
    if v > 0.0 && v <= 1.0 {
        Ok(())
    } else {
        Err(LbdemError::field(field, v, "must lie in (0, 1]", hint))
    }
}
