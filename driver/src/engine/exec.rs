//! Which instruction set the fluid's bulk pass runs in. The choice changes speed, never a single bit of the
//! results.
//!
//! The workspace builds for the baseline x86-64 target (SSE2, two f64 lanes), so a binary runs on any x86-64
//! machine. The bulk pass (pull streaming + the fluid collision, BGK or TRT, for every node: the loop that
//! dominates a fluid step) is also compiled for AVX2 and for AVX-512: [`bulk_band_exec`] calls the kernel from
//! a function carrying `#[target_feature]`, the kernel is inlined into it, and the compiler vectorises the loop
//! with the wider registers. [`SimdLevel::detect`] picks the widest level the CPU has, at run time.
//!
//! Results are bitwise identical at every level: the kernels use only IEEE-754 correctly rounded operations
//! (+, −, ×, ÷), Rust never fuses a·b + c into an FMA on its own (no fast-math flags), and the per-node
//! arithmetic has no reduction whose order vectorisation could change. `driver/tests/exec.rs` asserts it at
//! every level the CPU running the tests has.
//!
//! This module holds the driver's only `unsafe` code: the calls of the `#[target_feature]` functions, each
//! made after checking that the CPU has the features. The same holds for the bulk pass of the in-place (AA)
//! scheme, [`aa_bulk_exec`].
use lbdem_kernels::fluid::aa::{aa_bulk_rows, aa_bulk_rows_keeping, AaStep};
use lbdem_kernels::fluid::collide::Collision;
use lbdem_kernels::fluid::d2q9::Q;
use lbdem_kernels::fluid::lattice::LatticeShape;
use lbdem_kernels::fluid::step::{bulk_band, FluidParams};
use lbdem_kernels::Real;

/// Instruction-set level the bulk pass is compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SimdLevel {
    /// The build target's own instruction set (SSE2 on x86-64); every CPU.
    Baseline,
    /// AVX2 (256-bit vectors).
    Avx2,
    /// AVX-512 F/VL/DQ/BW (512-bit vectors).
    Avx512,
}

impl SimdLevel {
    /// Every level, narrowest first.
    pub const ALL: [SimdLevel; 3] = [SimdLevel::Baseline, SimdLevel::Avx2, SimdLevel::Avx512];

    /// Whether the CPU running this program can execute code of this level.
    pub fn available(self) -> bool {
        match self {
            SimdLevel::Baseline => true,
            #[cfg(target_arch = "x86_64")]
            SimdLevel::Avx2 => std::arch::is_x86_feature_detected!("avx2"),
            #[cfg(target_arch = "x86_64")]
            SimdLevel::Avx512 => {
                std::arch::is_x86_feature_detected!("avx512f")
                    && std::arch::is_x86_feature_detected!("avx512vl")
                    && std::arch::is_x86_feature_detected!("avx512dq")
                    && std::arch::is_x86_feature_detected!("avx512bw")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// `Ok` when this CPU can run the level; otherwise the error naming the `simd` option and the widest level
    /// it has.
    pub fn check_available(self) -> crate::error::Result<()> {
        if self.available() {
            return Ok(());
        }
        Err(crate::error::LbdemError::field(
            "simd",
            self.name(),
            "is not supported by this CPU",
            &format!("use {} or a narrower level", SimdLevel::detect().name()),
        ))
    }

    /// The widest level this CPU has.
    pub fn detect() -> Self {
        Self::ALL
            .into_iter()
            .rev()
            .find(|l| l.available())
            .unwrap_or(SimdLevel::Baseline)
    }

    /// Name for reports and scene files: "baseline", "avx2", "avx512".
    pub fn name(self) -> &'static str {
        match self {
            SimdLevel::Baseline => "baseline",
            SimdLevel::Avx2 => "avx2",
            SimdLevel::Avx512 => "avx512",
        }
    }

    /// The level named `name` ("baseline", "avx2", "avx512"), or `None`.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|l| l.name() == name)
    }
}

/// How populations are streamed. Both schemes give bitwise the same populations after every step; they
/// differ in memory and speed only.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum Streaming {
    /// In place, AA pattern: one buffer, 2/3 of the memory traffic of the two-lattice scheme.
    #[default]
    Aa,
    /// Two-lattice pull: read one buffer, write the other.
    TwoLattice,
}

impl Streaming {
    /// Both schemes.
    pub const ALL: [Streaming; 2] = [Streaming::Aa, Streaming::TwoLattice];

    /// Name for reports and the command line: "aa", "two-lattice".
    pub fn name(self) -> &'static str {
        match self {
            Streaming::Aa => "aa",
            Streaming::TwoLattice => "two-lattice",
        }
    }

    /// The scheme named `name`, or `None`.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.name() == name)
    }
}

/// How the work is executed: worker threads, the instruction set of the fluid's bulk pass, the fluid's
/// streaming scheme. None of these changes a single bit of the results, only speed and memory. Passed down from
/// the command line to every lattice a run creates (no process-wide settings).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Exec {
    /// Worker threads (0: all cores).
    pub threads: usize,
    /// Instruction set of the bulk pass.
    pub simd: SimdLevel,
    /// Streaming scheme.
    pub streaming: Streaming,
}

impl Default for Exec {
    /// All cores, the widest instruction set this CPU has, in-place (AA) streaming.
    fn default() -> Self {
        Self {
            threads: 0,
            simd: SimdLevel::detect(),
            streaming: Streaming::default(),
        }
    }
}

impl Exec {
    /// Settings from the command-line names (`None`: the default); refuses an unknown name or a SIMD level this
    /// CPU lacks, naming the option.
    pub fn from_names(
        threads: Option<usize>,
        simd: Option<&str>,
        streaming: Option<&str>,
    ) -> crate::error::Result<Self> {
        let mut exec = Self::default();
        if let Some(n) = threads {
            exec.threads = n.max(1);
        }
        if let Some(name) = simd {
            let level = SimdLevel::from_name(name).ok_or_else(|| {
                crate::error::LbdemError::field(
                    "--simd",
                    name,
                    "is not a known instruction-set level",
                    "use baseline, avx2 or avx512",
                )
            })?;
            if !level.available() {
                return Err(crate::error::LbdemError::field(
                    "--simd",
                    name,
                    "this CPU cannot run it",
                    &format!(
                        "use {} or a narrower level (baseline, avx2, avx512)",
                        SimdLevel::detect().name()
                    ),
                ));
            }
            exec.simd = level;
        }
        if let Some(name) = streaming {
            exec.streaming = Streaming::from_name(name).ok_or_else(|| {
                crate::error::LbdemError::field(
                    "--streaming",
                    name,
                    "is not a known streaming scheme",
                    "use aa or two-lattice",
                )
            })?;
        }
        Ok(exec)
    }

    /// Run `op` on a rayon pool with [`Exec::threads`] workers (the current pool when 0).
    pub fn install<R: Send>(&self, op: impl FnOnce() -> R + Send) -> crate::error::Result<R> {
        if self.threads == 0 {
            return Ok(op());
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(self.threads)
            .build()
            .map_err(|e| {
                crate::error::LbdemError::field(
                    "--threads",
                    self.threads,
                    &format!("cannot start the worker threads ({e})"),
                    "use fewer threads",
                )
            })?;
        Ok(pool.install(op))
    }
}

/// The bulk pass of rows `y0..y1` ([`bulk_band`]) into the band `dst`, compiled for `simd`. Falls back to
/// the baseline level if `simd` is not available on this CPU.
#[allow(clippy::too_many_arguments)]
pub fn bulk_band_exec<T: Real>(
    simd: SimdLevel,
    shape: &LatticeShape,
    src: &[T],
    dst: &mut [&mut [T]; Q],
    y0: usize,
    y1: usize,
    params: &FluidParams<T>,
    collision: &Collision<T>,
) {
    #[cfg(target_arch = "x86_64")]
    {
        if simd == SimdLevel::Avx512 && SimdLevel::Avx512.available() {
            // SAFETY: the CPU has AVX-512 F/VL/DQ/BW (checked just above).
            unsafe { x86::bulk_avx512(shape, src, dst, y0, y1, params, collision) };
            return;
        }
        if simd == SimdLevel::Avx2 && SimdLevel::Avx2.available() {
            // SAFETY: the CPU has AVX2 (checked just above).
            unsafe { x86::bulk_avx2(shape, src, dst, y0, y1, params, collision) };
            return;
        }
    }
    let _ = simd;
    bulk_band(shape, src, dst, y0, y1, params, collision);
}

/// The bulk pass of one in-place (AA) step over a band of rows ([`aa_bulk_rows`]), compiled for `simd`.
/// Falls back to the baseline level if `simd` is not available on this CPU.
pub fn aa_bulk_exec<T: Real>(
    simd: SimdLevel,
    rows: &mut [[&mut [T]; Q]],
    step: AaStep,
    params: &FluidParams<T>,
    collision: &Collision<T>,
) {
    #[cfg(target_arch = "x86_64")]
    {
        if simd == SimdLevel::Avx512 && SimdLevel::Avx512.available() {
            // SAFETY: the CPU has AVX-512 F/VL/DQ/BW (checked just above).
            unsafe { x86::aa_avx512(rows, step, params, collision) };
            return;
        }
        if simd == SimdLevel::Avx2 && SimdLevel::Avx2.available() {
            // SAFETY: the CPU has AVX2 (checked just above).
            unsafe { x86::aa_avx2(rows, step, params, collision) };
            return;
        }
    }
    let _ = simd;
    aa_bulk_rows(rows, step, params, collision);
}

/// [`aa_bulk_rows_keeping`] (the in-place bulk pass that leaves the nodes marked in `keep` as they were),
/// compiled for `simd`; bitwise the same at every level.
pub fn aa_bulk_keeping_exec<T: Real>(
    simd: SimdLevel,
    rows: &mut [[&mut [T]; Q]],
    keep: &[bool],
    step: AaStep,
    params: &FluidParams<T>,
    collision: &Collision<T>,
) {
    #[cfg(target_arch = "x86_64")]
    {
        if simd == SimdLevel::Avx512 && SimdLevel::Avx512.available() {
            // SAFETY: the CPU has AVX-512 F/VL/DQ/BW (checked just above).
            unsafe { x86::aa_keeping_avx512(rows, keep, step, params, collision) };
            return;
        }
        if simd == SimdLevel::Avx2 && SimdLevel::Avx2.available() {
            // SAFETY: the CPU has AVX2 (checked just above).
            unsafe { x86::aa_keeping_avx2(rows, keep, step, params, collision) };
            return;
        }
    }
    let _ = simd;
    aa_bulk_rows_keeping(rows, keep, step, params, collision);
}

/// Run `op` compiled for `simd`: `op` is inlined into a function carrying the level's `#[target_feature]`, so
/// the kernels it calls (inlined in turn) are compiled with the level's vector instructions. Used for the
/// partially-saturated collision of the covered nodes, whose batches of [`PSM_LANES`] nodes the compiler
/// vectorises across the lanes. Same bits at every level (see the module documentation). Falls back to the
/// baseline level if `simd` is not available on this CPU.
///
/// **`op` must be an `#[inline(always)]` closure** (`with_simd(simd, #[inline(always)] || …)`): a large closure
/// is otherwise left out of line, compiled once for the baseline level, and the `#[target_feature]` function
/// only calls it (measured: until 2026-12-04 the covered nodes' collision ran in SSE2 at every level).
///
/// [`PSM_LANES`]: lbdem_kernels::fluid::collide::PSM_LANES
#[inline(always)]
pub fn with_simd<R>(simd: SimdLevel, op: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    {
        if simd == SimdLevel::Avx512 && SimdLevel::Avx512.available() {
            // SAFETY: the CPU has AVX-512 F/VL/DQ/BW (checked just above).
            return unsafe { x86::run_avx512(op) };
        }
        if simd == SimdLevel::Avx2 && SimdLevel::Avx2.available() {
            // SAFETY: the CPU has AVX2 (checked just above).
            return unsafe { x86::run_avx2(op) };
        }
    }
    let _ = simd;
    op()
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::*;

    /// `op` compiled for AVX2 ([`with_simd`]).
    #[target_feature(enable = "avx2")]
    pub(super) fn run_avx2<R>(op: impl FnOnce() -> R) -> R {
        op()
    }

    /// `op` compiled for AVX-512 ([`with_simd`]).
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw")]
    pub(super) fn run_avx512<R>(op: impl FnOnce() -> R) -> R {
        op()
    }

    /// [`aa_bulk_rows`] compiled for AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) fn aa_avx2<T: Real>(
        rows: &mut [[&mut [T]; Q]],
        step: AaStep,
        params: &FluidParams<T>,
        collision: &Collision<T>,
    ) {
        aa_bulk_rows(rows, step, params, collision);
    }

    /// [`aa_bulk_rows`] compiled for AVX-512.
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw")]
    pub(super) fn aa_avx512<T: Real>(
        rows: &mut [[&mut [T]; Q]],
        step: AaStep,
        params: &FluidParams<T>,
        collision: &Collision<T>,
    ) {
        aa_bulk_rows(rows, step, params, collision);
    }

    /// [`aa_bulk_rows_keeping`] compiled for AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) fn aa_keeping_avx2<T: Real>(
        rows: &mut [[&mut [T]; Q]],
        keep: &[bool],
        step: AaStep,
        params: &FluidParams<T>,
        collision: &Collision<T>,
    ) {
        aa_bulk_rows_keeping(rows, keep, step, params, collision);
    }

    /// [`aa_bulk_rows_keeping`] compiled for AVX-512.
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw")]
    pub(super) fn aa_keeping_avx512<T: Real>(
        rows: &mut [[&mut [T]; Q]],
        keep: &[bool],
        step: AaStep,
        params: &FluidParams<T>,
        collision: &Collision<T>,
    ) {
        aa_bulk_rows_keeping(rows, keep, step, params, collision);
    }

    /// [`bulk_band`] compiled for AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) fn bulk_avx2<T: Real>(
        shape: &LatticeShape,
        src: &[T],
        dst: &mut [&mut [T]; Q],
        y0: usize,
        y1: usize,
        params: &FluidParams<T>,
        collision: &Collision<T>,
    ) {
        bulk_band(shape, src, dst, y0, y1, params, collision);
    }

    /// [`bulk_band`] compiled for AVX-512.
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw")]
    pub(super) fn bulk_avx512<T: Real>(
        shape: &LatticeShape,
        src: &[T],
        dst: &mut [&mut [T]; Q],
        y0: usize,
        y1: usize,
        params: &FluidParams<T>,
        collision: &Collision<T>,
    ) {
        bulk_band(shape, src, dst, y0, y1, params, collision);
    }
}

/// What this process's execution settings apply to (a fluid lattice of any precision): what a kind lists in
/// `run::Kind::lattices` so that a resumed state runs with this process's SIMD level and streaming scheme.
pub trait ExecTarget {
    /// Use `exec`'s settings.
    fn take(&mut self, exec: &Exec);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_baseline_is_always_there() {
        for l in SimdLevel::ALL {
            assert_eq!(SimdLevel::from_name(l.name()), Some(l));
        }
        assert_eq!(SimdLevel::from_name("sse9"), None);
        assert!(SimdLevel::Baseline.available());
        assert!(SimdLevel::detect().available());
    }
}
