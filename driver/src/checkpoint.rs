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
//! | 32 | SHA-256 of the payload |
//! | … | payload: the state, written by its [`Persist`] implementation |
//!
//! Lengths inside the payload are u64; booleans and enum tags one byte. A truncated, corrupted, foreign or
//! mismatched file (other scene, kind, precision or version) is refused with an [`LbdemError::Checkpoint`]
//! that says what is wrong, never a panic.
//!
//! # Use
//!
//! ```no_run
//! # use lbdem::checkpoint::{Checkpoint, Persist};
//! # fn demo(world: &lbdem::coupled::CoupledWorld, scene_text: &str) -> lbdem::error::Result<()> {
//! let path = std::path::Path::new("out/checkpoint.bin");
//! Checkpoint::save(path, scene_text, "my_kind", world.steps(), world)?;
//! let (header, again): (_, lbdem::coupled::CoupledWorld) = Checkpoint::load(path, scene_text, "my_kind")?;
//! # Ok(()) }
//! ```
//!
//! Writes are atomic ([`crate::output::write_atomic`]): a checkpoint on disk is always a whole one.
use std::path::Path;

use lbdem_kernels::dem::assembly::ContactModel;
use lbdem_kernels::dem::bond::{BreakMode, ParallelBond, PointBond};
use lbdem_kernels::dem::shape::{Particle, Shape, Wall};
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::{SolidOperator, SolidShare, Weighting};
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::Real;
use sha2::{Digest, Sha256};

use crate::error::{LbdemError, Result};
use crate::output::write_atomic;

/// First bytes of every checkpoint file.
pub const MAGIC: [u8; 8] = *b"LBDEMCKP";
/// Version of the layout; bumped whenever any [`Persist`] implementation changes what it writes.
pub const FORMAT_VERSION: u32 = 2;
/// Name of the checkpoint inside a run directory.
pub const CHECKPOINT_FILE: &str = "checkpoint.bin";
/// Name of the state written when a run diverges (for inspection; never resumed from).
pub const DIVERGED_FILE: &str = "diverged_state.bin";
/// Name of the scene copy a resumable run keeps in its directory.
pub const SCENE_COPY: &str = "scene.toml";

/// SHA-256 of a scene text (stored in the header, checked on resume).
pub fn scene_hash(text: &str) -> [u8; 32] {
    Sha256::digest(text.as_bytes()).into()
}

/// Hex form of a hash (messages).
pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Byte sink of a checkpoint payload.
#[derive(Default)]
pub struct Encoder {
    buf: Vec<u8>,
}

impl Encoder {
    /// An empty payload.
    pub fn new() -> Self {
        Self::default()
    }
    /// The bytes written.
    pub fn into_bytes(self) -> Vec<u8> {
        self.buf
    }
    /// One byte.
    pub fn u8(&mut self, v: u8) {
        self.buf.push(v);
    }
    /// A bool as one byte.
    pub fn bool(&mut self, v: bool) {
        self.buf.push(v as u8);
    }
    /// u32, little-endian.
    pub fn u32(&mut self, v: u32) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    /// u64, little-endian.
    pub fn u64(&mut self, v: u64) {
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    /// usize as u64.
    pub fn usize(&mut self, v: usize) {
        self.u64(v as u64);
    }
    /// f64, raw bits.
    pub fn f64(&mut self, v: f64) {
        self.buf.extend_from_slice(&v.to_bits().to_le_bytes());
    }
    /// A float of the state's precision: 4 bytes for f32, 8 for f64 (raw bits; exact).
    pub fn real<T: Real>(&mut self, v: T) {
        if std::mem::size_of::<T>() == 4 {
            // f32 → f64 → f32 is exact for every value (NaN payloads aside).
            let x = v.to_f64_exact() as f32;
            self.buf.extend_from_slice(&x.to_bits().to_le_bytes());
        } else {
            self.f64(v.to_f64_exact());
        }
    }
    /// A pair of floats.
    pub fn real2<T: Real>(&mut self, v: [T; 2]) {
        self.real(v[0]);
        self.real(v[1]);
    }
    /// A length-prefixed slice of floats.
    pub fn reals<T: Real>(&mut self, v: &[T]) {
        self.usize(v.len());
        self.buf.reserve(std::mem::size_of_val(v));
        for &x in v {
            self.real(x);
        }
    }
    /// A length-prefixed slice of f64.
    pub fn f64s(&mut self, v: &[f64]) {
        self.reals(v);
    }
    /// A length-prefixed byte string.
    pub fn bytes(&mut self, v: &[u8]) {
        self.usize(v.len());
        self.buf.extend_from_slice(v);
    }
    /// A length-prefixed UTF-8 string.
    pub fn str(&mut self, v: &str) {
        self.bytes(v.as_bytes());
    }
    /// A length-prefixed list of items.
    pub fn list<P: Persist>(&mut self, v: &[P]) {
        self.usize(v.len());
        for x in v {
            x.save(self);
        }
    }
    /// Anything [`Persist`].
    pub fn put<P: Persist>(&mut self, v: &P) {
        v.save(self);
    }
}

/// Byte source of a checkpoint payload; every read checks the remaining length.
pub struct Decoder<'a> {
    buf: &'a [u8],
    pos: usize,
}

fn corrupt(problem: String) -> LbdemError {
    LbdemError::Checkpoint {
        path: String::new(),
        problem,
        hint: "the file is damaged or was written by another lbdem version; resume from an earlier copy or start the run again (--overwrite)".into(),
    }
}

impl<'a> Decoder<'a> {
    /// Read from `buf`.
    pub fn new(buf: &'a [u8]) -> Self {
        Self { buf, pos: 0 }
    }
    /// Bytes not yet read.
    pub fn remaining(&self) -> usize {
        self.buf.len() - self.pos
    }
    fn take(&mut self, n: usize) -> Result<&'a [u8]> {
        if n > self.remaining() {
            return Err(corrupt(format!(
                "payload ends at byte {} but {n} more bytes are needed at byte {}",
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
    /// One byte.
    pub fn u8(&mut self) -> Result<u8> {
        Ok(self.take(1)?[0])
    }
    /// A bool (byte 0 or 1).
    pub fn bool(&mut self) -> Result<bool> {
        match self.u8()? {
            0 => Ok(false),
            1 => Ok(true),
            v => Err(corrupt(format!(
                "byte {} should be a boolean (0 or 1) but is {v}",
                self.pos - 1
            ))),
        }
    }
    /// u32.
    pub fn u32(&mut self) -> Result<u32> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    /// u64.
    pub fn u64(&mut self) -> Result<u64> {
        Ok(u64::from_le_bytes(self.array()?))
    }
    /// usize (stored as u64).
    pub fn usize(&mut self) -> Result<usize> {
        let v = self.u64()?;
        usize::try_from(v).map_err(|_| corrupt(format!("length {v} does not fit in memory")))
    }
    /// A length that must fit in the rest of the payload at `item` bytes per element.
    pub fn len(&mut self, item: usize) -> Result<usize> {
        let n = self.usize()?;
        if n.saturating_mul(item.max(1)) > self.remaining() {
            return Err(corrupt(format!(
                "a list of {n} items at byte {} runs past the end of the payload",
                self.pos
            )));
        }
        Ok(n)
    }
    /// f64.
    pub fn f64(&mut self) -> Result<f64> {
        Ok(f64::from_bits(self.u64()?))
    }
    /// A float of the state's precision.
    pub fn real<T: Real>(&mut self) -> Result<T> {
        if std::mem::size_of::<T>() == 4 {
            Ok(T::lit(f32::from_bits(self.u32()?) as f64))
        } else {
            Ok(T::lit(self.f64()?))
        }
    }
    /// A pair of floats.
    pub fn real2<T: Real>(&mut self) -> Result<[T; 2]> {
        Ok([self.real()?, self.real()?])
    }
    /// A length-prefixed slice of floats.
    pub fn reals<T: Real>(&mut self) -> Result<Vec<T>> {
        let n = self.len(std::mem::size_of::<T>())?;
        (0..n).map(|_| self.real()).collect()
    }
    /// A length-prefixed slice of f64.
    pub fn f64s(&mut self) -> Result<Vec<f64>> {
        self.reals()
    }
    /// A length-prefixed byte string.
    pub fn bytes(&mut self) -> Result<Vec<u8>> {
        let n = self.len(1)?;
        Ok(self.take(n)?.to_vec())
    }
    /// A length-prefixed UTF-8 string.
    pub fn str(&mut self) -> Result<String> {
        String::from_utf8(self.bytes()?).map_err(|_| corrupt("a text field is not UTF-8".into()))
    }
    /// A length-prefixed list of items.
    pub fn list<P: Persist>(&mut self) -> Result<Vec<P>> {
        let n = self.len(1)?;
        (0..n).map(|_| P::load(self)).collect()
    }
    /// Anything [`Persist`].
    pub fn get<P: Persist>(&mut self) -> Result<P> {
        P::load(self)
    }
    /// An enum tag that must be below `count`.
    pub fn tag(&mut self, what: &str, count: u8) -> Result<u8> {
        let t = self.u8()?;
        if t >= count {
            return Err(corrupt(format!(
                "{what} tag {t} at byte {} is not one of 0..{count}",
                self.pos - 1
            )));
        }
        Ok(t)
    }
    /// Fail unless a condition about the decoded data holds (consistency of lengths and indices).
    pub fn ensure(&self, ok: bool, what: impl FnOnce() -> String) -> Result<()> {
        if ok {
            Ok(())
        } else {
            Err(corrupt(format!("inconsistent state: {}", what())))
        }
    }
}

/// State that can be written into and read back from a checkpoint payload, bitwise exactly.
///
/// Implement it for a scene's run state (world + whatever the run loop keeps: records so far, phase,
/// counters) by writing the fields in a fixed order with [`Encoder`] and reading them back in the same order
/// with [`Decoder`]. [`FluidLattice`](crate::lattice::FluidLattice), [`DemWorld`](crate::solid::DemWorld) and
/// [`CoupledWorld`](crate::coupled::CoupledWorld) implement it.
pub trait Persist: Sized {
    /// Bytes per float of the state (header field "precision"; 0 if not applicable).
    const PRECISION: u8 = 8;
    /// Append the state.
    fn save(&self, e: &mut Encoder);
    /// Read the state back.
    fn load(d: &mut Decoder<'_>) -> Result<Self>;
}

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
        let mut payload = Encoder::new();
        state.save(&mut payload);
        let payload = payload.into_bytes();
        let mut out = Vec::with_capacity(payload.len() + 128);
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.push(S::PRECISION);
        out.extend_from_slice(&(kind.len() as u32).to_le_bytes());
        out.extend_from_slice(kind.as_bytes());
        out.extend_from_slice(&scene_hash(scene_text));
        out.extend_from_slice(&step.to_le_bytes());
        out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
        out.extend_from_slice(&Sha256::digest(&payload));
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
        if header.precision != S::PRECISION {
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
        let mut d = Decoder::new(payload);
        let state = S::load(&mut d)?;
        if d.remaining() != 0 {
            return Err(corrupt(format!(
                "{} bytes left over after the state",
                d.remaining()
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

fn parse(bytes: &[u8]) -> Result<(CheckpointHeader, &[u8])> {
    let mut d = Decoder::new(bytes);
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
                "has format version {version}; this lbdem reads version {FORMAT_VERSION}"
            ),
            hint: "resume with the lbdem version that wrote it, or start the run again".into(),
        });
    }
    let precision = d.u8()?;
    let kind_len = d.u32()? as usize;
    if kind_len > 256 {
        return Err(corrupt(format!("kind tag of {kind_len} bytes")));
    }
    let kind = String::from_utf8(d.take(kind_len)?.to_vec())
        .map_err(|_| corrupt("the kind tag is not UTF-8".into()))?;
    let scene_hash: [u8; 32] = d.array()?;
    let step = d.u64()?;
    let len = d.u64()?;
    let digest: [u8; 32] = d.array()?;
    let payload = &bytes[d.pos..];
    if payload.len() as u64 != len {
        return Err(corrupt(format!(
            "payload should be {len} bytes but {} are present (truncated file?)",
            payload.len()
        )));
    }
    let actual: [u8; 32] = Sha256::digest(payload).into();
    if actual != digest {
        return Err(corrupt(
            "payload checksum (SHA-256) does not match: the file is corrupted".into(),
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

// ---- kernel types ----------------------------------------------------------------------------------------

impl Persist for f64 {
    fn save(&self, e: &mut Encoder) {
        e.f64(*self);
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        d.f64()
    }
}

impl Persist for u64 {
    fn save(&self, e: &mut Encoder) {
        e.u64(*self);
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        d.u64()
    }
}

impl<T: Real> Persist for Particle<T> {
    fn save(&self, e: &mut Encoder) {
        e.real2(self.position);
        e.real(self.angle);
        e.real2(self.velocity);
        e.real(self.angular_velocity);
        e.real(self.mass);
        e.real(self.moment_of_inertia);
        match self.shape {
            Shape::Disc { radius } => {
                e.u8(0);
                e.real(radius);
            }
            Shape::Ellipse {
                semi_major,
                semi_minor,
            } => {
                e.u8(1);
                e.real(semi_major);
                e.real(semi_minor);
            }
        }
        e.real2(self.acceleration);
        e.real(self.angular_acceleration);
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        let position = d.real2()?;
        let angle = d.real()?;
        let velocity = d.real2()?;
        let angular_velocity = d.real()?;
        let mass = d.real()?;
        let moment_of_inertia = d.real()?;
        let shape = match d.tag("particle shape", 2)? {
            0 => Shape::Disc { radius: d.real()? },
            _ => Shape::Ellipse {
                semi_major: d.real()?,
                semi_minor: d.real()?,
            },
        };
        Ok(Particle {
            position,
            angle,
            velocity,
            angular_velocity,
            mass,
            moment_of_inertia,
            shape,
            acceleration: d.real2()?,
            angular_acceleration: d.real()?,
        })
    }
}

impl<T: Real> Persist for ContactModel<T> {
    fn save(&self, e: &mut Encoder) {
        e.real(self.normal_stiffness);
        e.real(self.shear_stiffness);
        e.real(self.friction);
        e.real(self.restitution);
        e.bool(self.no_tension);
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        Ok(ContactModel {
            normal_stiffness: d.real()?,
            shear_stiffness: d.real()?,
            friction: d.real()?,
            restitution: d.real()?,
            no_tension: d.bool()?,
        })
    }
}

impl<T: Real> Persist for Wall<T> {
    fn save(&self, e: &mut Encoder) {
        e.real2(self.point);
        e.real2(self.normal);
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        Ok(Wall {
            point: d.real2()?,
            normal: d.real2()?,
        })
    }
}

impl<T: Real> Persist for PointBond<T> {
    fn save(&self, e: &mut Encoder) {
        e.real2(self.anchor_i);
        e.real2(self.anchor_j);
        e.real2(self.rest_gap);
        e.real2(self.rest_normal);
        e.real2(self.rest_angles);
        e.real(self.stiffness);
        e.real(self.strength);
        e.bool(self.intact);
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        Ok(PointBond {
            anchor_i: d.real2()?,
            anchor_j: d.real2()?,
            rest_gap: d.real2()?,
            rest_normal: d.real2()?,
            rest_angles: d.real2()?,
            stiffness: d.real()?,
            strength: d.real()?,
            intact: d.bool()?,
        })
    }
}

impl<T: Real> Persist for ParallelBond<T> {
    fn save(&self, e: &mut Encoder) {
        e.real(self.radius);
        e.real(self.normal_stiffness);
        e.real(self.shear_stiffness);
        e.real(self.tensile_strength);
        e.real(self.shear_strength);
        e.real(self.normal_force);
        e.real(self.shear_force);
        e.real(self.moment);
        e.bool(self.intact);
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        Ok(ParallelBond {
            radius: d.real()?,
            normal_stiffness: d.real()?,
            shear_stiffness: d.real()?,
            tensile_strength: d.real()?,
            shear_strength: d.real()?,
            normal_force: d.real()?,
            shear_force: d.real()?,
            moment: d.real()?,
            intact: d.bool()?,
        })
    }
}

impl Persist for BreakMode {
    fn save(&self, e: &mut Encoder) {
        e.u8(match self {
            BreakMode::Tension => 0,
            BreakMode::Shear => 1,
            BreakMode::Compression => 2,
        });
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        Ok(match d.tag("bond break mode", 3)? {
            0 => BreakMode::Tension,
            1 => BreakMode::Shear,
            _ => BreakMode::Compression,
        })
    }
}

impl<T: Real> Persist for SideCondition<T> {
    fn save(&self, e: &mut Encoder) {
        match *self {
            SideCondition::Periodic => e.u8(0),
            SideCondition::Wall => e.u8(1),
            SideCondition::Pressure { density } => {
                e.u8(2);
                e.real(density);
            }
            SideCondition::Velocity { velocity } => {
                e.u8(3);
                e.real2(velocity);
            }
            SideCondition::MovingWall { velocity } => {
                e.u8(4);
                e.real2(velocity);
            }
            SideCondition::VelocityProfile => e.u8(5),
        }
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        Ok(match d.tag("side condition", 6)? {
            0 => SideCondition::Periodic,
            1 => SideCondition::Wall,
            2 => SideCondition::Pressure { density: d.real()? },
            3 => SideCondition::Velocity {
                velocity: d.real2()?,
            },
            4 => SideCondition::MovingWall {
                velocity: d.real2()?,
            },
            _ => SideCondition::VelocityProfile,
        })
    }
}

impl<T: Real> Persist for Boundaries<T> {
    fn save(&self, e: &mut Encoder) {
        for s in [&self.west, &self.east, &self.south, &self.north] {
            s.save(e);
        }
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        Ok(Boundaries {
            west: d.get()?,
            east: d.get()?,
            south: d.get()?,
            north: d.get()?,
        })
    }
}

impl<T: Real> Persist for FluidParams<T> {
    fn save(&self, e: &mut Encoder) {
        e.real(self.tau);
        e.real2(self.force);
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        Ok(FluidParams {
            tau: d.real()?,
            force: d.real2()?,
        })
    }
}

impl<T: Real> Persist for SolidShare<T> {
    fn save(&self, e: &mut Encoder) {
        e.real(self.fraction);
        e.real2(self.velocity);
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        Ok(SolidShare {
            fraction: d.real()?,
            velocity: d.real2()?,
        })
    }
}

impl Persist for Weighting {
    fn save(&self, e: &mut Encoder) {
        e.u8(match self {
            Weighting::NobleTorczynski => 0,
            Weighting::SolidFraction => 1,
        });
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        Ok(match d.tag("PSM weighting", 2)? {
            0 => Weighting::NobleTorczynski,
            _ => Weighting::SolidFraction,
        })
    }
}

impl Persist for SolidOperator {
    fn save(&self, e: &mut Encoder) {
        e.u8(match self {
            SolidOperator::NonEquilibriumBounceBack => 0,
            SolidOperator::Superposition => 1,
            SolidOperator::MovingWallBounceBack => 2,
            SolidOperator::LinearizedNonEquilibriumBounceBack => 3,
            SolidOperator::LambdaConsistent => 4,
        });
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        Ok(match d.tag("PSM solid operator", 5)? {
            0 => SolidOperator::NonEquilibriumBounceBack,
            1 => SolidOperator::Superposition,
            2 => SolidOperator::MovingWallBounceBack,
            3 => SolidOperator::LinearizedNonEquilibriumBounceBack,
            _ => SolidOperator::LambdaConsistent,
        })
    }
}
