//! `.pvd` collections: one per snapshot series (`particles.pvd`, `bonds.pvd`, `lattice.pvd`), listing each
//! snapshot file with its model time, so that ParaView opens the series as one time-dependent source whose time
//! is the model time in seconds.
//!
//! [`record`] is called right after snapshot `index` of a series is written: it keeps the first `index` entries
//! of the collection already in the directory and appends this one. So the collection always lists exactly the
//! snapshots written so far, in order, and a resumed run (which rewrites the snapshots after its checkpoint, with
//! the same indices and times) rewrites the collection exactly as the uninterrupted run would have.
use std::path::Path;

use super::write_atomic;
use crate::error::Result;

/// One entry of a collection: model time and file name (relative to the collection).
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// Model time (s).
    pub time: f64,
    /// File name, relative to the collection's directory.
    pub file: String,
}

/// The collection document.
pub fn collection(entries: &[Entry]) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for e in entries {
        s += &format!(
            "    <DataSet timestep=\"{:e}\" group=\"\" part=\"0\" file=\"{}\"/>\n",
            e.time, e.file
        );
    }
    s += "  </Collection>\n</VTKFile>\n";
    s
}

/// The entries of a collection written by [`collection`] (`None` when the text is not one).
pub fn parse(text: &str) -> Option<Vec<Entry>> {
    if !text.contains("<VTKFile type=\"Collection\"") {
        return None;
    }
    let mut out = Vec::new();
    for line in text
        .lines()
        .filter(|l| l.trim_start().starts_with("<DataSet "))
    {
        let attr = |key: &str| -> Option<String> {
            let k = format!(" {key}=\"");
            let start = line.find(&k)? + k.len();
            let end = line[start..].find('"')? + start;
            Some(line[start..end].to_string())
        };
        out.push(Entry {
            time: attr("timestep")?.parse().ok()?,
            file: attr("file")?,
        });
    }
    Some(out)
}

/// Record snapshot `index` of series `series` (file `file` at model time `time`) in `DIR/series.pvd`.
pub fn record(dir: &Path, series: &str, index: usize, time: f64, file: &str) -> Result<()> {
    let path = dir.join(format!("{series}.pvd"));
    let mut entries = std::fs::read_to_string(&path)
        .ok()
        .and_then(|t| parse(&t))
        .unwrap_or_default();
    if entries.len() < index {
        eprintln!(
            "lbdem: WARNING: {} lists {} snapshots, fewer than the {index} written before this one (a file was removed?)",
            path.display(),
            entries.len()
        );
    }
    entries.truncate(index);
    entries.push(Entry {
        time,
        file: file.to_string(),
    });
    write_atomic(&path, collection(&entries).as_bytes())
}

/// Write snapshot `index` of `series` as `DIR/series_NNNN.ext` (atomically) and record it in `series.pvd`.
pub fn write_snapshot(
    dir: &Path,
    series: &str,
    index: usize,
    time: f64,
    ext: &str,
    bytes: &[u8],
) -> Result<()> {
    let file = format!("{series}_{index:04}.{ext}");
    write_atomic(&dir.join(&file), bytes)?;
    record(dir, series, index, time, &file)
}
