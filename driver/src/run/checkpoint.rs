//! Checkpoints: bitwise-exact save and load of simulation state, for long runs that are interrupted and
//! resumed (`lbdem resume DIR`).
//!
//! # File format (version [`FORMAT_VERSION`])
//!
//! Everything little-endian; floats as their raw IEEE-754 bits, so a save → load round trip is bitwise exact
//! and a resumed run continues exactly as the uninterrupted one would have.
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `LBDEMCKP` |
//! | 4 | format version (u32) |
//! | 1 | precision: bytes per float of the state (4 = f32, 8 = f64, 0 = none) |
//! | 4 + n | kind tag (u32 length + UTF-8), e.g. `dry`; `lbdem resume` dispatches on it |
//! | 32 | SHA-256 of the scene file text the run started from |
//! | 8 | step (u64) the state is at |
//! | 8 | payload length (u64) |
//! | 32 | SHA-256 of everything before this field followed by the payload: the whole file is under the checksum |
//! | … | payload: the state in [`postcard`] encoding (serde; floats as their raw IEEE-754 bytes) |
//!
//! A truncated, corrupted, foreign or
//! mismatched file (other scene, kind, precision or version) is refused with an [`LbdemError::Checkpoint`]
//! that says what is wrong, never a panic.
//!
//! # Use
//!
//! ```no_run
//! # use lbdem::run::checkpoint::{Checkpoint, Persist};
//! # fn demo(world: &lbdem::engine::coupled::CoupledWorld, scene_text: &str) -> lbdem::error::Result<()> {
//! let path = std::path::Path::new("out/checkpoint.bin");
//! Checkpoint::save(path, scene_text, "my_kind", world.steps(), world)?;
//! let (header, again): (_, lbdem::engine::coupled::CoupledWorld) = Checkpoint::load(path, scene_text, "my_kind")?;
//! # Ok(()) }
//! ```
//!
//! Writes are atomic ([`crate::output::write_atomic`]): a checkpoint on disk is always a whole one.
use std::path::Path;

use lbdem_kernels::Real;
use serde::de::DeserializeOwned;
use serde::Serialize;
use sha2::{Digest, Sha256};

use crate::engine::coupled::CoupledWorld;
use crate::engine::dem::DemWorld;
use crate::engine::lattice::FluidLattice;
use crate::error::{LbdemError, Result};
use crate::output::write_atomic;
pub use crate::output::{CHECKPOINT_FILE, DIVERGED_FILE, SCENE_COPY};

/// First bytes of every checkpoint file.
pub const MAGIC: [u8; 8] = *b"LBDEMCKP";
/// Version of the layout; bumped whenever the header or the payload encoding changes. Version 1 (hand-written
/// payloads) was replaced by version 2 (serde + postcard payloads, the checksum over the payload only). Version 3
/// adds the lattice's side velocity profiles (issue 11) and puts the header under the checksum (in version 2 an
/// edited step or kind tag went unnoticed); version-2 files are refused with the version named. Version 4 adds
/// the fluid collision (TRT's magic parameter) to the cases of the cylinder-array, porous-flow and channel kinds
/// (issue 11, `[fluid] collision`); version-3 files are refused with the version named. Version 5: the
/// snapshot clocks of the kinds that gained VTK series (coupled_demo, terminal_velocity, consolidation,
/// terzaghi; issue 16), one state type for the two sweep kinds (issue 12) and the free-grain default operators
/// (issue 11) change those payloads; version-4 files are refused with the version named. Version 6: the lattice's
/// remap tolerance and the grain geometry its coverage was mapped for (issue 13, `fluid.remap_tolerance`);
/// version-5 files are refused with the version named. Version 7: the terzaghi kind's sealed column and dry
/// recovery (issue 14) and the fracture kind's count of grains outside the lattice change those payloads;
/// version-6 files are refused with the version named. Version 8: the lattice's coverage keeps each share's wall
/// normal and the lattice ΩΛ's constants (issue 11, ΩΛ's wall-pressure form); version-7 files are refused with
/// the version named.
pub const FORMAT_VERSION: u32 = 8;
/// SHA-256 of a scene text (stored in the header, checked on resume).
pub fn scene_hash(text: &str) -> [u8; 32] {
    Sha256::digest(text.as_bytes()).into()
}

/// Hex form of a hash (messages).
pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn corrupt(problem: String) -> LbdemError {
    LbdemError::Checkpoint {
        path: String::new(),
        problem,
        hint: "the file is damaged or was written by another lbdem version; resume from an earlier copy or start the run again (--overwrite)".into(),
    }
}

/// State that can be written into and read back from a checkpoint payload, bitwise exactly: any serde type
/// (the payload is [`postcard`], which stores every float as its raw IEEE-754 bytes). Derive
/// `Serialize`/`Deserialize` for a scene's run state (world + whatever the run loop keeps: records so far,
/// phase, counters) and implement this trait with its precision.
pub trait Persist: Serialize + DeserializeOwned {
    /// Bytes per float of the state (header field "precision"); 0 for a state that holds either precision (an
    /// enum over both: then [`Persist::precision`] tells, and loading does not check it before decoding).
    const PRECISION: u8 = 8;
    /// Bytes per float of this value.
    fn precision(&self) -> u8 {
        Self::PRECISION
    }
}

impl<T: Real + Serialize + DeserializeOwned> Persist for FluidLattice<T> {
    const PRECISION: u8 = std::mem::size_of::<T>() as u8;
}

impl<T: Real + Serialize + DeserializeOwned> Persist for DemWorld<T> {
    const PRECISION: u8 = std::mem::size_of::<T>() as u8;
}

impl Persist for CoupledWorld {}

/// What a checkpoint's header says.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CheckpointHeader {
    /// Format version.
    pub version: u32,
    /// Bytes per float.
    pub precision: u8,
    /// Kind tag (which run loop wrote it).
    pub kind: String,
    /// SHA-256 of the scene text.
    pub scene_hash: [u8; 32],
    /// Step of the saved state.
    pub step: u64,
}

/// Save and load checkpoint files.
pub struct Checkpoint;

impl Checkpoint {
    /// Write `state` to `path` atomically, tagged with `kind`, the hash of `scene_text` and `step`.
    pub fn save<S: Persist>(
        path: &Path,
        scene_text: &str,
        kind: &str,
        step: u64,
        state: &S,
    ) -> Result<()> {
        let bytes = Self::to_bytes(scene_text, kind, step, state);
        write_atomic(path, &bytes)
    }

    /// The bytes [`Checkpoint::save`] writes.
    pub fn to_bytes<S: Persist>(scene_text: &str, kind: &str, step: u64, state: &S) -> Vec<u8> {
        // Serializing plain data into memory cannot fail (no map keys other than strings, no I/O).
        let payload = postcard::to_allocvec(state).unwrap_or_default();
        let mut out = Vec::with_capacity(payload.len() + 128);
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.push(state.precision());
        out.extend_from_slice(&(kind.len() as u32).to_le_bytes());
        out.extend_from_slice(kind.as_bytes());
        out.extend_from_slice(&scene_hash(scene_text));
        out.extend_from_slice(&step.to_le_bytes());
        out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        let digest = digest(&out, &payload);
        out.extend_from_slice(&digest);
        out.extend_from_slice(&payload);
        out
    }

    /// Read only the header of `path` (which run loop wrote it, at which step).
    pub fn read_header(path: &Path) -> Result<CheckpointHeader> {
        let bytes = read(path)?;
        parse(&bytes).map(|(h, _)| h).map_err(|e| at(e, path))
    }

    /// Load a checkpoint written by [`Checkpoint::save`], refusing one whose kind, precision or scene hash
    /// differs from the expected ones, or whose payload is damaged.
    pub fn load<S: Persist>(
        path: &Path,
        scene_text: &str,
        kind: &str,
    ) -> Result<(CheckpointHeader, S)> {
        let bytes = read(path)?;
        Self::from_bytes(&bytes, scene_text, kind).map_err(|e| at(e, path))
    }

    /// Decode the bytes of a checkpoint (see [`Checkpoint::load`]).
    pub fn from_bytes<S: Persist>(
        bytes: &[u8],
        scene_text: &str,
        kind: &str,
    ) -> Result<(CheckpointHeader, S)> {
        let (header, payload) = parse(bytes)?;
        let mismatch = |problem: String, hint: &str| LbdemError::Checkpoint {
            path: String::new(),
            problem,
            hint: hint.into(),
        };
        if header.kind != kind {
            return Err(mismatch(
                format!("was written by a `{}` run, not a `{kind}` run", header.kind),
                "resume it with the run loop that wrote it (`lbdem resume DIR` picks it from the header)",
            ));
        }
        if S::PRECISION != 0 && header.precision != S::PRECISION {
            return Err(mismatch(
                format!(
                    "holds {}-byte floats but the run expects {}-byte floats",
                    header.precision,
                    S::PRECISION
                ),
                "the scene's precision must not change between the run and its resume",
            ));
        }
        let expected = scene_hash(scene_text);
        if header.scene_hash != expected {
            return Err(mismatch(
                format!(
                    "belongs to another scene (scene hash {} in the checkpoint, {} for the scene text given)",
                    hex(&header.scene_hash[..8]),
                    hex(&expected[..8])
                ),
                "resume with the scene.toml saved in the run directory, unchanged; to run an edited scene start a new run",
            ));
        }
        let (state, rest) = postcard::take_from_bytes::<S>(payload)
            .map_err(|e| corrupt(format!("holds a state this lbdem cannot decode ({e})")))?;
        if !rest.is_empty() {
            return Err(corrupt(format!(
                "{} bytes left over after the state",
                rest.len()
            )));
        }
        Ok((header, state))
    }
}

fn read(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| LbdemError::Checkpoint {
        path: path.display().to_string(),
        problem: format!("cannot be read: {e}"),
        hint: "give the directory of a run started by `lbdem run` (it holds checkpoint.bin)".into(),
    })
}

fn at(e: LbdemError, path: &Path) -> LbdemError {
    match e {
        LbdemError::Checkpoint {
            path: p,
            problem,
            hint,
        } if p.is_empty() => LbdemError::Checkpoint {
            path: path.display().to_string(),
            problem,
            hint,
        },
        other => other,
    }
}

/// A cursor over the header bytes; every read checks the remaining length.
struct Cursor<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8]> {
        if n > self.buf.len() - self.pos {
            return Err(corrupt(format!(
                "ends at byte {} but {n} more bytes are needed at byte {} (truncated file?)",
                self.buf.len(),
                self.pos
            )));
        }
        let s = &self.buf[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    fn array<const N: usize>(&mut self) -> Result<[u8; N]> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.take(N)?);
        Ok(a)
    }
    fn u32(&mut self) -> Result<u32> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    fn u64(&mut self) -> Result<u64> {
        Ok(u64::from_le_bytes(self.array()?))
    }
}

/// The checksum of a checkpoint: SHA-256 of the header bytes before it, then the payload.
fn digest(header: &[u8], payload: &[u8]) -> [u8; 32] {
    let mut h = Sha256::new();
    h.update(header);
    h.update(payload);
    h.finalize().into()
}

fn parse(bytes: &[u8]) -> Result<(CheckpointHeader, &[u8])> {
    let mut d = Cursor { buf: bytes, pos: 0 };
    let not_ours = || LbdemError::Checkpoint {
        path: String::new(),
        problem: "is not an lbdem checkpoint (no LBDEMCKP magic at its start)".into(),
        hint: "give the directory of a run started by `lbdem run`".into(),
    };
    let magic: [u8; 8] = d.array().map_err(|_| not_ours())?;
    if magic != MAGIC {
        return Err(not_ours());
    }
    let version = d.u32()?;
    if version != FORMAT_VERSION {
        return Err(LbdemError::Checkpoint {
            path: String::new(),
            problem: format!(
                "has format version {version}; this lbdem reads version {FORMAT_VERSION} only{}",
                if version < FORMAT_VERSION {
                    " (it was written by an older lbdem)"
                } else {
                    " (it was written by a newer lbdem)"
                }
            ),
            hint:
                "resume with the lbdem version that wrote it, or start the run again (--overwrite)"
                    .into(),
        });
    }
    let precision = d.array::<1>()?[0];
    let kind_len = d.u32()? as usize;
    if kind_len > 256 {
        return Err(corrupt(format!("kind tag of {kind_len} bytes")));
    }
    let kind = String::from_utf8(d.take(kind_len)?.to_vec())
        .map_err(|_| corrupt("the kind tag is not UTF-8".into()))?;
    let scene_hash: [u8; 32] = d.array()?;
    let step = d.u64()?;
    let len = d.u64()?;
    let header_bytes = &bytes[..d.pos];
    let stored: [u8; 32] = d.array()?;
    let payload = &bytes[d.pos..];
    if payload.len() as u64 != len {
        return Err(corrupt(format!(
            "payload should be {len} bytes but {} are present (truncated file?)",
            payload.len()
        )));
    }
    if digest(header_bytes, payload) != stored {
        return Err(corrupt(
            "checksum (SHA-256 of the header and the payload) does not match: the file is corrupted or \
             was edited"
                .into(),
        ));
    }
    Ok((
        CheckpointHeader {
            version,
            precision,
            kind,
            scene_hash,
            step,
        },
        payload,
    ))
}
