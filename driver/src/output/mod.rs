//! Outputs: the run directory, atomic writes, CSV tables, VTK XML snapshots with `.pvd` collections, PNG plots
//! and the one summary schema. Every file and column is described in `docs/outputs.md`.
//!
//! Every file is written to a temporary name in the same directory and renamed, so nothing already written is
//! ever truncated or half-written. A run directory holds `scene.toml` (the scene text the run started from,
//! written by [`start_run_dir`]), `checkpoint.bin` (see `crate::run::checkpoint`), the kind's outputs, and
//! `summary.json` ([`summary`]) once finished.
use std::path::{Path, PathBuf};

use crate::error::{LbdemError, Result};

pub mod plot;
pub mod pvd;
pub mod snapshots;
pub mod summary;
pub mod vtk;

/// Name of the checkpoint inside a run directory.
pub const CHECKPOINT_FILE: &str = "checkpoint.bin";
/// Name of the state written when a run diverges (for inspection; never resumed from).
pub const DIVERGED_FILE: &str = "diverged_state.bin";
/// Name of the scene copy a run keeps in its directory (what `lbdem resume DIR` reads).
pub const SCENE_COPY: &str = "scene.toml";
/// Name of the summary a finished run writes last.
pub const SUMMARY_FILE: &str = "summary.json";

/// Name of the manifest of a directory lbdem writes into: the names of the files it wrote there, one per line,
/// sorted. `--overwrite` removes exactly these (and their temporary files), nothing else.
pub const MANIFEST_FILE: &str = "lbdem-outputs.txt";

/// One manifest update at a time within this process.
static MANIFEST_LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Record `path`, a file lbdem has just written, in its directory's manifest ([`MANIFEST_FILE`]). Every
/// writer of outputs calls it ([`write_atomic`] does).
pub fn record_output(path: &Path) -> Result<()> {
    let (Some(dir), Some(name)) = (path.parent(), path.file_name()) else {
        return Ok(());
    };
    let name = name.to_string_lossy();
    if name == MANIFEST_FILE {
        return Ok(());
    }
    let _one = MANIFEST_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let manifest = dir.join(MANIFEST_FILE);
    let text = std::fs::read_to_string(&manifest).unwrap_or_default();
    let mut names: std::collections::BTreeSet<&str> = text.lines().collect();
    if !names.insert(&name) {
        return Ok(());
    }
    let listed: String = names.iter().map(|n| format!("{n}\n")).collect();
    let tmp = dir.join(format!("{MANIFEST_FILE}.tmp"));
    let err = |e| LbdemError::Write {
        path: manifest.display().to_string(),
        source: e,
    };
    std::fs::write(&tmp, listed).map_err(err)?;
    std::fs::rename(&tmp, &manifest).map_err(err)
}

/// Write `bytes` to `path` atomically (temporary file + rename), and record it in the directory's manifest.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp: PathBuf = {
        let mut name = path
            .file_name()
            .map(|n| n.to_os_string())
            .unwrap_or_default();
        name.push(".tmp");
        path.with_file_name(name)
    };
    let err = |e| LbdemError::Write {
        path: path.display().to_string(),
        source: e,
    };
    std::fs::write(&tmp, bytes).map_err(err)?;
    std::fs::rename(&tmp, path).map_err(err)?;
    record_output(path)
}

/// Prepare an output directory: create it, and refuse one that holds a previous run (finished:
/// `summary.json`; interrupted: `checkpoint.bin`) unless `overwrite`.
pub fn prepare_dir(dir: &Path, overwrite: bool) -> Result<()> {
    if dir.join(SUMMARY_FILE).exists() && !overwrite {
        return Err(LbdemError::OutputExists(dir.display().to_string()));
    }
    if dir.join(CHECKPOINT_FILE).exists() && !overwrite {
        return Err(LbdemError::InterruptedRunExists(dir.display().to_string()));
    }
    std::fs::create_dir_all(dir).map_err(|e| LbdemError::Write {
        path: dir.display().to_string(),
        source: e,
    })
}

/// Prepare the directory of a new run: refuse one holding a previous run (finished or interrupted) unless
/// `overwrite`, remove a previous run's checkpoints and summary when overwriting, and save the scene text as
/// `DIR/scene.toml` (what `lbdem resume DIR` reads).
pub fn start_run_dir(dir: &Path, scene_text: &str, overwrite: bool) -> Result<()> {
    prepare_dir(dir, overwrite)?;
    if overwrite {
        empty_run_dir(dir)?;
    }
    write_atomic(&dir.join(SCENE_COPY), scene_text.as_bytes())
}

/// Whether the directory entry `name` is one lbdem wrote according to the manifest `listed`: a listed file, the
/// manifest itself, or the temporary file of one of them (`NAME.tmp`, or `STEM.tmp.png` for figures) left by
/// an interrupted write.
fn is_listed(name: &str, listed: &std::collections::BTreeSet<&str>) -> bool {
    if name == MANIFEST_FILE || listed.contains(name) {
        return true;
    }
    let of_tmp = name
        .strip_suffix(".tmp")
        .map(str::to_string)
        .or_else(|| name.strip_suffix(".tmp.png").map(|s| format!("{s}.png")));
    of_tmp.is_some_and(|n| n == MANIFEST_FILE || listed.contains(n.as_str()))
}

/// `--overwrite`: remove a previous run's outputs from `dir` (the files its manifest, [`MANIFEST_FILE`], lists),
/// refusing (and removing nothing) when the directory holds anything else: files lbdem did not write, whatever
/// their extension, and subdirectories.
fn empty_run_dir(dir: &Path) -> Result<()> {
    let err = |e| LbdemError::Write {
        path: dir.display().to_string(),
        source: e,
    };
    let entries: Vec<std::fs::DirEntry> = std::fs::read_dir(dir)
        .map_err(err)?
        .collect::<std::io::Result<_>>()
        .map_err(err)?;
    let manifest = std::fs::read_to_string(dir.join(MANIFEST_FILE)).unwrap_or_default();
    let listed: std::collections::BTreeSet<&str> = manifest.lines().collect();
    let mut foreign: Vec<String> = entries
        .iter()
        .filter(|e| {
            let is_file = e.file_type().is_ok_and(|t| t.is_file());
            !(is_file && is_listed(&e.file_name().to_string_lossy(), &listed))
        })
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    if !foreign.is_empty() {
        // Sorted, so that the message names the same files whatever order the directory lists them in.
        foreign.sort();
        let mut files = foreign
            .iter()
            .take(5)
            .cloned()
            .collect::<Vec<_>>()
            .join(", ");
        if foreign.len() > 5 {
            files += &format!(" and {} more", foreign.len() - 5);
        }
        return Err(LbdemError::ForeignFiles {
            dir: dir.display().to_string(),
            files,
        });
    }
    for e in entries {
        std::fs::remove_file(e.path()).map_err(|source| LbdemError::Write {
            path: e.path().display().to_string(),
            source,
        })?;
    }
    Ok(())
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

/// Render rows as CSV with a header line.
pub fn csv(header: &[&str], rows: impl IntoIterator<Item = Vec<f64>>) -> String {
    let mut s = header.join(",");
    s.push('\n');
    for row in rows {
        let cells: Vec<String> = row.iter().map(|v| format!("{v:.10e}")).collect();
        s += &cells.join(",");
        s.push('\n');
    }
    s
}
