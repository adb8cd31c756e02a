//! Writing outputs safely: every file is written to a temporary name in the same directory and renamed, so
//! nothing already written is ever truncated or half-written.
use std::path::{Path, PathBuf};

use crate::error::{LbdemError, Result};

/// Write `bytes` to `path` atomically (temporary file + rename).
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
    std::fs::rename(&tmp, path).map_err(err)
}

/// Prepare an output directory: create it, and refuse one that holds a previous run (finished:
/// `summary.json`; interrupted: `checkpoint.bin`) unless `overwrite`.
pub fn prepare_dir(dir: &Path, overwrite: bool) -> Result<()> {
    if dir.join("summary.json").exists() && !overwrite {
        return Err(LbdemError::OutputExists(dir.display().to_string()));
    }
    if dir.join(crate::checkpoint::CHECKPOINT_FILE).exists() && !overwrite {
        return Err(LbdemError::InterruptedRunExists(dir.display().to_string()));
    }
    std::fs::create_dir_all(dir).map_err(|e| LbdemError::Write {
        path: dir.display().to_string(),
        source: e,
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
