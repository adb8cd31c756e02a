//! Limits checked before anything is allocated: every size a scene implies (lattice nodes, grains, steps,
//! records, snapshots, cases) is computed from the scene in checked integer arithmetic, the memory a run needs
//! is estimated part by part ([`Budget`]) and refused above the memory this machine has available, and step
//! counts above [`MAX_STEPS`] are refused. `lbdem check` and `lbdem run` share this code (it runs in
//! `Kind::budget`, after `Kind::validate` and `Kind::setup`; see `crate::run::Case::new`), so check refuses
//! exactly what run would refuse, without allocating anything that grows with the scene.
//!
//! Each refusal names the scene field that produced the size (`porous.rows`, `fluid.spacing`, …).
use serde::Serialize;

use crate::error::{LbdemError, Result};

/// Most steps (lattice steps, DEM steps, or both in a coupled run) one run may take: 10⁹. At the fastest a
/// tiny lattice steps ~10⁵ times per second, so 10⁹ steps are hours of compute; a scene asking for more is a
/// mistake (a duration or a rate off by orders of magnitude) rather than a plan.
pub const MAX_STEPS: u64 = 1_000_000_000;

/// Most DEM sub-steps per fluid step a coupled run may take: 10⁴. More means grains far stiffer than the fluid
/// step resolves; the run would spend all its time in the DEM (and [`MAX_STEPS`] would stop it anyway).
pub const MAX_SUBSTEPS: u64 = 10_000;

/// Most cases (solid fractions × drives, diameters × pressure drops) one scene may list: 10⁴.
pub const MAX_CASES: u64 = 10_000;

/// Most snapshot files (VTK, PNG) one run may write: 10⁴ per kind of file.
pub const MAX_SNAPSHOTS: u64 = 10_000;

/// Most lattice nodes along one side: 2³² − 1, as the kernels index nodes in 32 bits (so any side count below
/// it squares without overflowing 64 bits; the node count itself is checked by [`lattice`]).
pub const MAX_SIDE: u64 = u32::MAX as u64;

/// The refusal of a length of `n` lattice spacings (above [`MAX_SIDE`]), naming `field`.
pub fn side_too_long(field: &str, length: f64, n: f64) -> LbdemError {
    LbdemError::field(
        field,
        length,
        &format!("is {n:e} lattice spacings long, above the {MAX_SIDE} nodes a side may have"),
        "shrink the domain or coarsen fluid.spacing",
    )
}

/// Most grains (DEM particles) one run may hold: 10⁸ (the DEM world indexes grains in 32 bits, and at
/// [`GRAIN_BYTES`] each 10⁸ grains already take about 100 GB).
pub const MAX_GRAINS: u64 = 100_000_000;

/// Refuse more than [`MAX_GRAINS`] grains, naming `field`.
pub fn grains(field: &str, n: u64) -> Result<u64> {
    if n > MAX_GRAINS {
        return Err(LbdemError::field(
            field,
            format!("(gives {n} grains)"),
            &format!("gives {n} grains, above the limit of {MAX_GRAINS} per run"),
            "shrink the sample or use larger grains",
        ));
    }
    Ok(n)
}

/// Refuse more than [`MAX_SUBSTEPS`] DEM sub-steps per fluid step, naming `field` (the sub-step count is
/// Δt_fluid / (safety × DEM critical step)).
pub fn substeps(field: &str, n: f64) -> Result<u64> {
    let n = count_up(field, "the DEM sub-steps per fluid step", n)?;
    if n > MAX_SUBSTEPS {
        return Err(LbdemError::field(
            field,
            format!("(gives {n} DEM sub-steps per fluid step)"),
            &format!(
                "makes the grains so stiff that each fluid step needs {n} DEM sub-steps, above the limit of \
                 {MAX_SUBSTEPS}"
            ),
            "lower the stiffness, raise the grain density or size, or shorten fluid.timestep",
        ));
    }
    Ok(n.max(1))
}

/// The DEM sub-steps per fluid step of a coupled run whose DEM step is at most half its critical step:
/// Δt_fluid / (½ Δt_critical) rounded up (at least 1), refused above [`MAX_SUBSTEPS`] naming
/// `stiffness_field`; with `fluid_steps`, the DEM step count of the run refused above [`MAX_STEPS`] too
/// (naming `stiffness_field`; an overflow names `duration_field`).
pub fn dem_substeps(
    stiffness_field: &str,
    duration_field: &str,
    fluid_steps: Option<u64>,
    timestep: f64,
    critical: f64,
) -> Result<u64> {
    let n = substeps(stiffness_field, timestep / (0.5 * critical))?;
    if let Some(fluid_steps) = fluid_steps {
        steps(
            stiffness_field,
            mul(duration_field, "the DEM step count", fluid_steps, n)?,
        )?;
    }
    Ok(n)
}

/// Largest scene file read: 1 MiB. Scene files hold parameters, not data; reading stops here, so neither a
/// huge file nor an endless one (`/dev/zero`) is read into memory.
pub const MAX_SCENE_BYTES: u64 = 1 << 20;

/// Largest count taken from a floating-point figure (length / spacing, duration / step): 2⁵³, the largest
/// integer every f64 below it represents exactly. Anything larger is refused before it is cast.
pub const MAX_COUNT: f64 = 9_007_199_254_740_992.0;

/// Bytes per lattice node besides the populations (which [`lattice`] takes from the lattice shape, padding
/// included, for the two-lattice scheme: the larger of the two schemes): node flags (1), density and velocity
/// of the health and measurement passes (3 floats), a solid-fraction map (8), and the checkpoint payload written
/// at every checkpoint (9 floats + 1).
fn node_extra_bytes(float_bytes: u64) -> u64 {
    1 + 3 * float_bytes + 8 + 9 * float_bytes + 1
}

/// Bytes per lattice node of the partially-saturated coupling (the coverage lists: node, offset, share,
/// owner, share position, exchanged momentum), counted for every node (an upper bound: only covered nodes hold
/// them), and once more in the checkpoint payload.
fn coverage_bytes(float_bytes: u64) -> u64 {
    2 * (4 + 4 + 4 * float_bytes + 4 + 16 + 2 * float_bytes)
}

/// Bytes per grain of a DEM world: the particle, its applied loads, broad-phase and contact lists (about three
/// contacts and three bonds per grain), forces, platen shear and the checkpoint payload (an estimate, rounded
/// up).
pub const GRAIN_BYTES: u64 = 1024;

/// One part of the memory a run needs.
#[derive(Clone, Debug, Serialize)]
pub struct Part {
    /// What it is ("fluid lattice 170 x 48 nodes (f64)").
    pub what: String,
    /// The scene field that sets its size.
    pub field: String,
    /// Estimated bytes.
    pub bytes: u64,
}

/// The memory a run needs, part by part (an estimate of the peak: everything the run holds at once, plus one
/// checkpoint payload).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Budget {
    /// The parts.
    pub parts: Vec<Part>,
    /// Derived figures behind the limits, printed by `lbdem check` (e.g. the DEM sub-steps per fluid step).
    pub notes: Vec<String>,
}

/// Bytes for humans.
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1e9 {
        format!("{:.1} GB", b / 1e9)
    } else if b >= 1e6 {
        format!("{:.1} MB", b / 1e6)
    } else if b >= 1e3 {
        format!("{:.1} kB", b / 1e3)
    } else {
        format!("{bytes} B")
    }
}

fn too_large(field: &str, value: impl ToString, what: &str) -> LbdemError {
    LbdemError::field(
        field,
        value,
        &format!("makes {what} too large to count (64-bit overflow)"),
        "use a size of the order of the bundled scenes (scenes/)",
    )
}

impl Budget {
    /// An empty budget.
    pub fn new() -> Self {
        Self::default()
    }

    /// Add a part of `bytes` (`None`: the size overflowed, refused naming `field`).
    pub fn add(&mut self, what: impl Into<String>, field: &str, bytes: Option<u64>) -> Result<()> {
        let what = what.into();
        let bytes = bytes.ok_or_else(|| too_large(field, "(see the sizes above)", &what))?;
        self.parts.push(Part {
            what,
            field: field.to_string(),
            bytes,
        });
        Ok(())
    }

    /// Add `count` items of `each` bytes.
    pub fn add_items(
        &mut self,
        what: impl Into<String>,
        field: &str,
        count: u64,
        each: u64,
    ) -> Result<()> {
        self.add(what, field, count.checked_mul(each))
    }

    /// Estimated total bytes.
    pub fn bytes(&self) -> u64 {
        self.parts
            .iter()
            .fold(0u64, |a, p| a.saturating_add(p.bytes))
    }

    /// Refuse a run that needs more than the memory available on this machine ([`available_memory`]), naming
    /// the field of the largest part.
    pub fn check(&self) -> Result<()> {
        let Some(available) = available_memory() else {
            return Ok(());
        };
        let total = self.bytes();
        if total <= available {
            return Ok(());
        }
        let largest = self
            .parts
            .iter()
            .max_by_key(|p| p.bytes)
            .cloned()
            .unwrap_or(Part {
                what: "the run".into(),
                field: "scene".into(),
                bytes: total,
            });
        Err(LbdemError::field(
            &largest.field,
            format!("(sets {}: {})", largest.what, human(largest.bytes)),
            &format!(
                "the run needs about {} of memory ({}) but this machine has {} available",
                human(total),
                self.summary(),
                human(available)
            ),
            "make the scene smaller (coarser spacing, fewer grains or cases, fewer records), or run it on a \
             machine with more memory",
        ))
    }

    /// The parts, largest first, for messages.
    pub fn summary(&self) -> String {
        let mut parts: Vec<&Part> = self.parts.iter().collect();
        parts.sort_by_key(|p| std::cmp::Reverse(p.bytes));
        parts
            .iter()
            .take(4)
            .map(|p| format!("{}: {}", p.what, human(p.bytes)))
            .collect::<Vec<_>>()
            .join("; ")
    }

    /// Add a note printed by `lbdem check`.
    pub fn note(&mut self, note: impl Into<String>) {
        self.notes.push(note.into());
    }

    /// The lines for `lbdem check`: the notes and the memory estimate.
    pub fn describe(&self) -> String {
        let mut s: String = self.notes.iter().map(|n| format!("  {n}\n")).collect();
        s += &format!(
            "  memory: about {} ({})\n",
            human(self.bytes()),
            self.summary()
        );
        s
    }
}

/// Memory this process may still use: the smaller of the system's available memory (`MemAvailable` of
/// `/proc/meminfo`) and what its cgroup still allows (`memory.max − memory.current`, cgroup v2); the
/// environment variable `LBDEM_MEMORY_LIMIT` (bytes) overrides both (for tests, or to keep a run below a share
/// of a shared machine). `None` where none of these can be read (no limit is then applied).
pub fn available_memory() -> Option<u64> {
    if let Ok(v) = std::env::var("LBDEM_MEMORY_LIMIT") {
        if let Ok(b) = v.trim().parse::<u64>() {
            return Some(b);
        }
    }
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|t| {
        t.lines()
            .find_map(|l| l.strip_prefix("MemAvailable:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
            .map(|kb| kb.saturating_mul(1024))
    });
    let read = |p: &str| {
        std::fs::read_to_string(p)
            .ok()
            .and_then(|t| t.trim().parse::<u64>().ok())
    };
    let cgroup = match (
        read("/sys/fs/cgroup/memory.max"),
        read("/sys/fs/cgroup/memory.current"),
    ) {
        (Some(max), Some(cur)) => Some(max.saturating_sub(cur)),
        _ => None,
    };
    match (meminfo, cgroup) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// `a × b`, refused naming `field` on overflow.
pub fn mul(field: &str, what: &str, a: u64, b: u64) -> Result<u64> {
    a.checked_mul(b)
        .ok_or_else(|| too_large(field, format!("{a} x {b}"), what))
}

/// `a + b`, refused naming `field` on overflow.
pub fn add(field: &str, what: &str, a: u64, b: u64) -> Result<u64> {
    a.checked_add(b)
        .ok_or_else(|| too_large(field, format!("{a} + {b}"), what))
}

/// A count (nodes, steps, records) from a floating-point figure `x` (e.g. length / spacing), rounded to the
/// nearest whole number; refused naming `field` when `x` is not finite, negative or above [`MAX_COUNT`].
pub fn count(field: &str, what: &str, x: f64) -> Result<u64> {
    if x.is_finite() && (0.0..=MAX_COUNT).contains(&x) {
        Ok(x.round() as u64)
    } else {
        Err(LbdemError::field(
            field,
            format!("(gives {what} = {x:e})"),
            &format!("gives {what} = {x:e}, which is not a finite count below 2^53"),
            "check the units and magnitudes of this field and of fluid.spacing / the time steps",
        ))
    }
}

/// [`count`] rounded up.
pub fn count_up(field: &str, what: &str, x: f64) -> Result<u64> {
    count(field, what, x.ceil())
}

/// Refuse a step count above [`MAX_STEPS`] (or 0), naming `field`.
pub fn steps(field: &str, n: u64) -> Result<u64> {
    if n == 0 {
        return Err(LbdemError::field(
            field,
            0,
            "gives no step to run",
            "give a positive duration or step count",
        ));
    }
    if n > MAX_STEPS {
        return Err(LbdemError::field(
            field,
            format!("(gives {n} steps)"),
            &format!("gives {n} steps, above the limit of {MAX_STEPS} steps per run"),
            "shorten the run, or coarsen the time step (a duration or rate off by orders of magnitude?)",
        ));
    }
    Ok(n)
}

/// Steps to cover `duration` at `timestep` (rounded as `rule` does: up, or to nearest), refused above
/// [`MAX_STEPS`], naming `field`.
pub fn steps_for(field: &str, duration: f64, timestep: f64, round_up: bool) -> Result<u64> {
    let x = duration / timestep;
    let n = if round_up {
        count_up(field, "the step count", x)?
    } else {
        count(field, "the step count", x)?
    };
    steps(field, n.max(1))
}

/// Refuse more than [`MAX_CASES`] cases, naming `field`.
pub fn cases(field: &str, n: u64) -> Result<u64> {
    if n > MAX_CASES {
        return Err(LbdemError::field(
            field,
            format!("(gives {n} cases)"),
            &format!("gives {n} cases, above the limit of {MAX_CASES} per scene"),
            "split the study into several scenes",
        ));
    }
    Ok(n)
}

/// Refuse more than [`MAX_SNAPSHOTS`] snapshot files, naming `field` (the interval that sets their number).
pub fn snapshots(field: &str, n: u64) -> Result<u64> {
    if n > MAX_SNAPSHOTS {
        return Err(LbdemError::field(
            field,
            format!("(gives {n} snapshots)"),
            &format!("gives {n} snapshot files, above the limit of {MAX_SNAPSHOTS} per run"),
            &format!("raise {field} to snapshot less often (0 writes only the first and the last snapshot)"),
        ));
    }
    Ok(n)
}

/// The snapshots of a run of `total` steps (or records) with one every `every` (0: only the first and the
/// last): at most one per multiple of `every`, plus the first and the last (saturating: a count beyond `u64`
/// is refused anyway). Refused above [`MAX_SNAPSHOTS`] naming `field`.
pub fn snapshots_every(field: &str, total: u64, every: u64) -> Result<u64> {
    snapshots(
        field,
        total.checked_div(every).unwrap_or(0).saturating_add(2),
    )
}

/// The records (table rows) of a run of `total` steps with one every `every` steps (at least 1): one per
/// multiple of `every`, plus the first and the last (saturating: the memory check refuses such a count).
pub fn records_every(total: u64, every: u64) -> u64 {
    (total / every.max(1)).saturating_add(2)
}

/// Whether a fluid lattice carries the coverage of solids (the partially-saturated coupling's per-node data).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Solids {
    /// Plain fluid.
    None,
    /// Nodes covered by solids (discs, grains).
    Covered,
}

/// Add a fluid lattice of `nx × ny` nodes in precision `float_bytes` (4 or 8) to `budget`, refusing a lattice
/// whose node count does not fit the kernels' 32-bit node indices; `solids` tells whether it carries the
/// coverage of the partially-saturated coupling.
pub fn lattice(
    budget: &mut Budget,
    field: &str,
    what: &str,
    nx: u64,
    ny: u64,
    float_bytes: u64,
    solids: Solids,
) -> Result<()> {
    let shape = usize::try_from(nx)
        .ok()
        .zip(usize::try_from(ny).ok())
        .and_then(|(x, y)| {
            lbdem_kernels::fluid::lattice::LatticeShape::new(x, y, float_bytes as usize).ok()
        })
        .ok_or_else(|| {
            LbdemError::field(
                field,
                format!("(gives a {nx} x {ny} lattice)"),
                &format!(
                    "gives a {what} of {nx} x {ny} nodes: every side needs at least one node and the node \
                     count must fit in 32 bits (at most {} nodes)",
                    u32::MAX
                ),
                "coarsen fluid.spacing or shrink the domain",
            )
        })?;
    let populations = (shape.buffer_len() as u64)
        .checked_mul(2 * float_bytes)
        .and_then(|b| b.checked_add(2 * 4096));
    let per_node = node_extra_bytes(float_bytes)
        + match solids {
            Solids::Covered => coverage_bytes(float_bytes),
            Solids::None => 0,
        };
    let bytes = nx
        .checked_mul(ny)
        .and_then(|n| n.checked_mul(per_node))
        .zip(populations)
        .and_then(|(a, b)| a.checked_add(b));
    let precision = if float_bytes == 4 { "f32" } else { "f64" };
    budget.add(
        format!("{what} {nx} x {ny} nodes ({precision})"),
        field,
        bytes,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_refuse_non_finite_negative_and_huge_figures_naming_the_field() {
        assert_eq!(count("a.b", "nodes", 12.4).unwrap(), 12);
        assert_eq!(count_up("a.b", "nodes", 12.01).unwrap(), 13);
        for bad in [f64::NAN, f64::INFINITY, -1.0, 1e300, MAX_COUNT * 2.0] {
            let e = count("a.b", "nodes", bad).unwrap_err().to_string();
            assert!(e.contains("`a.b`"), "{e}");
        }
        assert!(mul("x.y", "nodes", u64::MAX, 2).is_err());
        assert!(add("x.y", "nodes", u64::MAX, 1).is_err());
        assert_eq!(steps("run.steps", MAX_STEPS).unwrap(), MAX_STEPS);
        assert!(steps("run.steps", MAX_STEPS + 1).is_err());
        assert!(steps("run.steps", 0).is_err());
        assert!(steps_for("run.duration", 1e300, 1e-4, true).is_err());
        assert_eq!(steps_for("run.duration", 1.0, 0.25, true).unwrap(), 4);
    }

    #[test]
    fn a_lattice_beyond_32_bit_node_indices_is_refused_and_the_budget_names_the_largest_part() {
        let mut b = Budget::new();
        let e = lattice(
            &mut b,
            "demo.nx",
            "lattice",
            1 << 20,
            1 << 20,
            8,
            Solids::None,
        )
        .unwrap_err();
        assert!(e.to_string().contains("`demo.nx`"), "{e}");
        let e = lattice(&mut b, "demo.nx", "lattice", 0, 5, 8, Solids::None).unwrap_err();
        assert!(e.to_string().contains("at least one node"), "{e}");
        lattice(&mut b, "demo.nx", "lattice", 100, 100, 8, Solids::Covered).unwrap();
        // Two-lattice populations (2 × 9 × 8 bytes per node, padded) and the per-node extras.
        assert!(b.bytes() > 100 * 100 * 144, "{}", b.bytes());
        b.add_items("grains", "packing.width", 1000, GRAIN_BYTES)
            .unwrap();
        assert!(b.add_items("grains", "packing.width", u64::MAX, 2).is_err());
        assert!(b.describe().contains("memory: about"));
    }
}
