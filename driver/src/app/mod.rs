//! What the command line does: read a scene file once, look its kind up in the registry
//! ([`crate::kinds::REGISTRY`]) and dispatch `check`, `run` and `resume` to it, with the execution settings
//! passed down ([`RunOptions`]).
//!
//! `check` and `run` share one code path up to the allocation of the run: both parse the scene, range-check
//! it, derive its set-up and check its sizes and memory against the limits (`crate::input::limits`), in
//! `run::Case::read`; `check` then describes the set-up, `run` starts it.
use std::path::Path;

use crate::error::{LbdemError, Result};
use crate::input::parse::backticked;
use crate::kinds::{self, Entry};
use crate::output::{CHECKPOINT_FILE, SUMMARY_FILE};
use crate::run::checkpoint::Checkpoint;
pub use crate::run::RunOptions;
use crate::scene::{kind_field, read_scene_text, KindField};

/// The scene text of `path` and the registry entry of its `[scene] kind`.
fn read(path: &Path) -> Result<(String, &'static Entry)> {
    let text = read_scene_text(path)?;
    let entry = entry_of(&text, &path.display().to_string())?;
    Ok((text, entry))
}

/// The registry entry of the `[scene] kind` of scene text (`path` for messages).
pub fn entry_of(text: &str, path: &str) -> Result<&'static Entry> {
    let kinds_list = || kinds::names();
    match kind_field(text) {
        // Not TOML at all: the parser says where.
        Err(e) => Err(crate::input::parse::parse_error(text, path, &e, None)),
        Ok(KindField::Name(name)) => kinds::find(&name).ok_or_else(|| {
            LbdemError::field(
                "scene.kind",
                format!("\"{name}\""),
                "is not a scene kind this lbdem knows",
                &format!("use one of: {}", kinds_list()),
            )
        }),
        Ok(KindField::Missing) => Err(LbdemError::field(
            "scene.kind",
            "missing",
            "the scene has no [scene] section with a kind",
            &format!("add [scene] with kind = one of: {}", kinds_list()),
        )),
        Ok(KindField::WrongType(t)) => Err(LbdemError::field(
            "scene.kind",
            t,
            "must be a string naming the scene kind",
            &format!("write kind = \"...\" with one of: {}", kinds_list()),
        )),
    }
}

/// A parse error about a top-level section that belongs to another kind gets a hint saying whose it is.
fn with_kind_hint(e: LbdemError, kind: &str) -> LbdemError {
    match e {
        LbdemError::ParseScene {
            path,
            key,
            message,
            hint,
        } if !key.contains('.') && !key.contains('[') => {
            let section = backticked(&message, "unknown field `");
            let hint = match section.as_deref().and_then(kinds::owner_of_section) {
                Some(owner) if owner != kind => format!(
                    "[{}] is a section of kind = \"{owner}\", but this scene says kind = \"{kind}\": fix [scene] \
                     kind, or remove the section",
                    section.unwrap_or_default()
                ),
                _ => hint,
            };
            LbdemError::ParseScene {
                path,
                key,
                message,
                hint,
            }
        }
        other => other,
    }
}

/// `lbdem check` of scene text (`path` for messages).
pub fn check_text(text: &str, path: &str) -> Result<String> {
    let entry = entry_of(text, path)?;
    (entry.check)(text, path).map_err(|e| with_kind_hint(e, entry.name))
}

/// `lbdem check SCENE`: validate a scene and describe its derived parameters without running it (exactly the
/// validation of `lbdem run`, without allocating the run).
pub fn check(path: &Path) -> Result<String> {
    let (text, entry) = read(path)?;
    (entry.check)(&text, &path.display().to_string()).map_err(|e| with_kind_hint(e, entry.name))
}

/// `lbdem run SCENE --out DIR`: run a scene to its end, writing its outputs and `summary.json` into `out`.
/// Returns the summary.
pub fn run(path: &Path, out: &Path, opts: &RunOptions) -> Result<serde_json::Value> {
    let (text, entry) = read(path)?;
    run_text(&text, &path.display().to_string(), out, opts)
        .map_err(|e| with_kind_hint(e, entry.name))
}

/// `lbdem run` of scene text (`path` for messages).
pub fn run_text(
    text: &str,
    path: &str,
    out: &Path,
    opts: &RunOptions,
) -> Result<serde_json::Value> {
    let entry = entry_of(text, path)?;
    (entry.run)(text, path, out, opts).map_err(|e| with_kind_hint(e, entry.name))
}

/// `lbdem resume DIR`: continue the interrupted run in `dir` to its end (the checkpoint header names its kind).
pub fn resume(dir: &Path, opts: &RunOptions) -> Result<serde_json::Value> {
    let path = dir.join(CHECKPOINT_FILE);
    if !path.exists() {
        let hint = if dir.join(SUMMARY_FILE).exists() {
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
    // The scene copy must be of the checkpoint's kind: say so rather than parse it as the wrong kind.
    let copy = dir.join(crate::output::SCENE_COPY);
    if let Ok(text) = std::fs::read_to_string(&copy) {
        if let Ok(crate::scene::KindField::Name(kind)) = kind_field(&text) {
            if kind != header.kind {
                return Err(LbdemError::Checkpoint {
                    path: path.display().to_string(),
                    problem: format!(
                        "checkpoint kind does not match: it was written by a `{}` run, but {} is a `{kind}` \
                         scene",
                        header.kind,
                        copy.display()
                    ),
                    hint: "the checkpoint and scene.toml come from different runs; restore the scene.toml of \
                           the run that wrote the checkpoint, or start a new run"
                        .into(),
                });
            }
        }
    }
    (entry.resume)(dir, opts)
}
