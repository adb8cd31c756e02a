//! What the command line does: read a scene file once, look its kind up in the registry
//! ([`crate::kinds::REGISTRY`]) and dispatch `check`, `run` and `resume` to it, with the execution settings
//! passed down ([`RunOptions`]).
use std::path::Path;

use crate::error::{LbdemError, Result};
use crate::kinds::{self, Entry};
use crate::output::CHECKPOINT_FILE;
use crate::run::checkpoint::Checkpoint;
pub use crate::run::RunOptions;
use crate::scene::{peek_kind, read_scene_text};

/// The scene text of `path` and the registry entry of its `[scene] kind`.
fn read(path: &Path) -> Result<(String, &'static Entry)> {
    let text = read_scene_text(path)?;
    let entry = entry_of(&text, &path.display().to_string())?;
    Ok((text, entry))
}

/// The registry entry of the `[scene] kind` of scene text (`path` for messages).
fn entry_of(text: &str, path: &str) -> Result<&'static Entry> {
    let entry = match peek_kind::<String>(text) {
        Some(name) => kinds::find(&name).ok_or_else(|| {
            LbdemError::field(
                "scene.kind",
                &name,
                "is not a scene kind this lbdem knows",
                &format!("use one of: {}", kinds::names()),
            )
        })?,
        None => {
            // Let the TOML parser say what is wrong when the header itself does not parse.
            if let Err(e) = toml::from_str::<toml::Value>(text) {
                return Err(LbdemError::ParseScene {
                    path: path.to_string(),
                    message: e.to_string(),
                });
            }
            return Err(LbdemError::field(
                "scene.kind",
                "missing",
                "the scene has no [scene] section with a kind",
                &format!("add [scene] with kind = one of: {}", kinds::names()),
            ));
        }
    };
    Ok(entry)
}

/// `lbdem check` of scene text (`path` for messages).
pub fn check_text(text: &str, path: &str) -> Result<String> {
    (entry_of(text, path)?.check)(text, path)
}

/// `lbdem check SCENE`: validate a scene and describe its derived parameters without running it.
pub fn check(path: &Path) -> Result<String> {
    let (text, entry) = read(path)?;
    (entry.check)(&text, &path.display().to_string())
}

/// `lbdem run SCENE --out DIR`: run a scene to its end, writing its outputs and `summary.json` into `out`.
/// Returns the summary.
pub fn run(path: &Path, out: &Path, opts: &RunOptions) -> Result<serde_json::Value> {
    let (text, entry) = read(path)?;
    (entry.run)(&text, &path.display().to_string(), out, opts)
}

/// `lbdem resume DIR`: continue the interrupted run in `dir` to its end (the checkpoint header names its kind).
pub fn resume(dir: &Path, opts: &RunOptions) -> Result<serde_json::Value> {
    let path = dir.join(CHECKPOINT_FILE);
    if !path.exists() {
        let hint = if dir.join(crate::output::SUMMARY_FILE).exists() {
            "this directory holds a finished run from before checkpoints were written; nothing to resume"
        } else {
            "give the output directory of a run started with `lbdem run SCENE --out DIR`"
        };
        return Err(LbdemError::Checkpoint {
            path: path.display().to_string(),
            problem: "does not exist".into(),
            hint: hint.into(),
        });
    }
    let header = Checkpoint::read_header(&path)?;
    let entry = kinds::find(&header.kind).ok_or_else(|| LbdemError::Checkpoint {
        path: path.display().to_string(),
        problem: format!(
            "was written by a `{}` run, which this lbdem cannot resume",
            header.kind
        ),
        hint: "resume it with the lbdem version that wrote it".into(),
    })?;
    (entry.resume)(dir, opts)
}
