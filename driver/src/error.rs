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
    #[error("scene {path} is not valid: {message}\n  hint: see docs/scenes.md for every key, its unit and range")]
    ParseScene {
        /// Path given.
        path: String,
        /// What the parser said (names the key and line).
        message: String,
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
    #[error("run stopped at step {step}: {quantity} = {value} at node ({x}, {y}); outputs written so far are kept in {out}\n  hint: {hint}")]
    Diverged {
        /// Step at which the check failed.
        step: u64,
        /// The quantity that failed (density, velocity).
        quantity: String,
        /// Its value.
        value: String,
        /// Node x.
        x: usize,
        /// Node y.
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

impl LbdemError {
    /// Shorthand for [`LbdemError::InvalidField`].
    pub fn field(field: &str, value: impl ToString, problem: &str, hint: &str) -> Self {
        Self::InvalidField {
            field: field.to_string(),
            value: value.to_string(),
            problem: problem.to_string(),
            hint: hint.to_string(),
        }
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

/// Check that a fraction lies in (0, 1], naming the field.
pub fn fraction(field: &str, v: f64, hint: &str) -> Result<()> {
    if v > 0.0 && v <= 1.0 {
        Ok(())
    } else {
        Err(LbdemError::field(field, v, "must lie in (0, 1]", hint))
    }
}
