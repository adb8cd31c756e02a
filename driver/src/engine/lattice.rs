//! The fluid lattice owned by the driver: the population buffer(s), node flags, the special-node list, and
//! the parallel step that hands row bands to the kernels through rayon.
//!
//! Two streaming schemes give bitwise the same populations ([`Streaming`]): the in-place AA pattern of
//! [`lbdem_kernels::fluid::aa`] (one buffer, the default) and the two-lattice pull of
//! [`lbdem_kernels::fluid::step`] (two buffers). In both, each node's update is independent of every other
//! node's, and special and covered nodes are computed in a fixed order, so the result is bitwise the same for
//! any number of threads or bands.
use lbdem_kernels::coupling::{
    body_cell_range, reduce_exchange, rigid_velocity, BodyShape, CoupledBody, PreparedBody,
};
use lbdem_kernels::coverage::{ellipse_cell_grid, ellipse_grid_fractions, CellGrid};
use lbdem_kernels::fluid::aa::{
    plane_row, store_post_collision_in_plane, to_collided, AaStep, Layout,
};
use lbdem_kernels::fluid::boundary::{
    radiating_density, zou_he_known_sum, Boundaries, SideCondition, SideProfiles,
};
use lbdem_kernels::fluid::collide::{
    psm_velocity, Collision, LambdaTerms, OpenLinks, PsmParams, SolidOperator, SolidShare,
    Weighting, ALL_LINKS_OPEN,
};
use lbdem_kernels::fluid::d2q9::{equilibrium, OPPOSITE, Q};
use lbdem_kernels::fluid::lattice::{LatticeShape, Side};
use lbdem_kernels::fluid::step::{
    classify_special_nodes, collide_covered_nodes, collide_planned_row, covered_node_value,
    fix_special_nodes, gather_node_in, gathered_densities, gathered_moments_in, nodes_in_rows,
    open_links, plan_covered_row, planes_mut, special_node_value, wall_gradients, CoveredNodes,
    Domain, FluidParams, FLUID, PLAN_GROUPS, SOLID,
};
use lbdem_kernels::math::{Point, Vector};
use lbdem_kernels::Real;
use rayon::prelude::*;
use std::borrow::Cow;
use std::sync::atomic::{AtomicU64, Ordering as AtomicOrdering};

pub use crate::engine::exec::Streaming;
use crate::engine::exec::{
    aa_bulk_exec, aa_bulk_keeping_exec, bulk_band_exec, with_simd, Exec, ExecTarget, SimdLevel,
};
use crate::error::{LbdemError, Result};

mod persist;

/// A fresh identity for a list a cache is keyed on (a coverage's node lists, the special-node list): never 0,
/// never handed out twice in a process, so a cache keyed on it cannot be taken for another list's.
fn next_list_id() -> u64 {
    static IDS: AtomicU64 = AtomicU64::new(1);
    IDS.fetch_add(1, AtomicOrdering::Relaxed)
}

/// The state of a radiating drained side ([`FluidLattice::radiate`]): the density slow flow sees, the rate r
/// of the running mean of the outward velocity (per step; the side reflects a wave of angular frequency ω per
/// step with amplitude r/√(4ω² + r²)) and that mean.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RadiatingSide {
    /// Density the side returns to (lattice units).
    pub density: f64,
    /// Rate of the running mean, in (0, 1] per step.
    pub rate: f64,
    /// Running mean of the outward velocity (lattice units; 0 at the start).
    pub mean: f64,
}

/// A D2Q9 lattice with its buffers.
pub struct FluidLattice<T: Real> {
    shape: LatticeShape,
    bc: Boundaries<T>,
    params: FluidParams<T>,
    flags: Vec<u8>,
    special: Vec<u32>,
    /// Whether each node is in `special`.
    special_mask: Vec<bool>,
    /// The population buffers in one allocation: `[first | gap | second]` (see [`buffer_gap`]) for the
    /// two-lattice scheme, `[first]` only for the in-place scheme.
    buffers: Vec<T>,
    /// Start of the second buffer in `buffers`.
    second: usize,
    /// Whether the current (post-collision) populations are in the first buffer.
    first_is_current: bool,
    band_rows: usize,
    steps: u64,
    coverage: Option<Coverage<T>>,
    cover_scratch: CoverScratch,
    /// How far (lattice spacings) any point of a body may move before [`FluidLattice::cover_with_bodies`]
    /// re-maps the bodies' cells (0: at every call). See [`FluidLattice::set_remap_tolerance`].
    remap_tolerance: f64,
    solid_operator: SolidOperator,
    /// ΩΛ's constants: friction κ and wall-pressure α ([`LambdaTerms`]).
    lambda_terms: LambdaTerms,
    /// The fluid collision (BGK unless [`FluidLattice::set_collision`] chose TRT).
    collision: Collision<T>,
    /// Velocity profiles of [`SideCondition::VelocityProfile`] sides (west, east, south, north; empty for other
    /// sides, zero velocity until [`FluidLattice::set_side_profile`]).
    profiles: [Vec<[T; 2]>; 4],
    simd: SimdLevel,
    streaming: Streaming,
    /// Layout of the current buffer (always [`Layout::Collided`] with the two-lattice scheme).
    layout: Layout,
    /// In-place scheme: new values of the special and covered nodes, computed before the bulk pass.
    aa_special: Vec<[T; Q]>,
    aa_covered: Vec<Option<[T; Q]>>,
    /// In-place scheme: the covered nodes that are special (indices into the covered list), those of
    /// `aa_covered`, and the identities (coverage layout, special list) they were found for: they are kept
    /// while both lists stand (between re-mappings under a remap tolerance, or with bodies that keep their
    /// nodes) instead of looked up again at every step.
    aa_covered_special: Vec<usize>,
    aa_covered_special_key: Option<(u64, u64)>,
    /// How many times `aa_covered_special` was found anew (for tests).
    aa_covered_special_found: u64,
    /// Identity of `special` ([`next_list_id`]), renewed whenever the list is.
    special_id: u64,
    /// In-place scheme: each band's covered rows planned for `collide_planned_row`, kept while the plans'
    /// key stands.
    covered_plans: Vec<CoveredPlan>,
    /// How many band plans were made (for tests).
    covered_plans_made: u64,
    /// ΩΛ's wall-pressure form: the gathered density of each node of the rows around covered nodes, filled
    /// before each step ([`gathered_densities`]; one entry per node, other rows stale).
    densities: Vec<T>,
}

/// What a band's covered-row plans depend on: the coverage's lists and fractions, the special-node list (the
/// nodes left out), the solid operator (the kernel of each node) and the band's rows.
type PlanKey = (u64, u64, u64, SolidOperator, usize);

/// The covered nodes of one band of rows planned row by row ([`plan_covered_row`]): the rows' plans one after
/// the other in `nodes` (indices into each row's covered nodes), each row's group sizes in `counts`.
#[derive(Default)]
struct CoveredPlan {
    key: Option<PlanKey>,
    counts: Vec<[u32; PLAN_GROUPS.len()]>,
    nodes: Vec<u32>,
}

/// Buffers kept between calls of [`FluidLattice::cover_with_bodies`]: the cells of each body, and per-node
/// counters that are all zero between calls.
#[derive(Default)]
struct CoverScratch {
    /// The bodies of the last [`FluidLattice::cover_with_bodies`] call: what the shares' wall normals are computed
    /// from when ΩΛ's wall-pressure form is switched on after the coverage was made.
    last_bodies: Vec<CoupledBody<f64>>,
    bodies: Vec<BodyCells>,
    /// One kernel scratch per chunk of [`BODY_CHUNK`] bodies.
    grids: Vec<GridScratch>,
    /// The bodies meeting each band of rows (increasing), and each band's plan.
    band_bodies: Vec<Vec<u32>>,
    plans: Vec<BandPlan>,
    /// For every share of the coverage the last call built, in the coverage's order: the index of its cell in
    /// its owner's [`BodyCells::fractions`]. Read by the in-place update.
    src: Vec<u32>,
    /// The number of bodies of the last call when that call built the coverage's lists (nodes, offsets, owners,
    /// share nodes); `None` when the coverage was not built here (none yet, a checkpoint, a field), so the next
    /// call rebuilds them.
    layout_bodies: Option<usize>,
    /// Re-mappings that updated the shares in place, and those that rebuilt the lists (counted for tests and
    /// profiles).
    in_place: u64,
    rebuilt: u64,
    /// ΩΛ's open links of every node, kept up to date between calls.
    links: LinkState,
}

/// Scratch of the whole-ellipse kernel (`ellipse_grid_fractions`): fractions and boundary marks of one body's
/// unclamped cell block. One per chunk of [`BODY_CHUNK`] bodies, reused body after body, so that the block
/// the kernel fills and the driver copies from stays in the core's cache (one buffer per body, as before,
/// spread 3.8 MB of zero-filling over memory at every call in the full-size fracture test).
#[derive(Default)]
struct GridScratch {
    fractions: Vec<f64>,
    boundary: Vec<bool>,
}

/// What the per-body pass of [`FluidLattice::cover_with_bodies`] needs besides the body: the lattice's shape and
/// sides, the kernel's SIMD level and the task's kernel scratch.
struct CellPass<'a, T> {
    shape: &'a LatticeShape,
    bc: &'a Boundaries<T>,
    simd: SimdLevel,
    grid: &'a mut GridScratch,
}

/// Bodies per task of the per-body pass of [`FluidLattice::cover_with_bodies`] (each task with its own
/// [`GridScratch`]).
const BODY_CHUNK: usize = 16;

/// One band's slices of the coverage arrays, written by [`BandPlan::write`].
struct BandOut<'a, T> {
    nodes: &'a mut [u32],
    offsets: &'a mut [u32],
    shares: &'a mut [SolidShare<T>],
    owners: &'a mut [u32],
    share_nodes: &'a mut [[f64; 2]],
    src: &'a mut [u32],
    /// Index of the band's first share in the whole list.
    first_share: u32,
}

impl<T: Real> BandOut<'_, T> {
    /// Share `slot` of the band: cell `i` (fraction `frac`) of body `owner`, at the node of coordinates `p`.
    #[inline(always)]
    fn put(
        &mut self,
        slot: usize,
        owner: u32,
        i: u32,
        frac: f64,
        p: [f64; 2],
        body: &CoupledBody<f64>,
    ) {
        let v = rigid_velocity(body, Vector::from(p));
        self.shares[slot] = SolidShare {
            fraction: T::lit(frac),
            velocity: [T::lit(v[0]), T::lit(v[1])],
            wall_gradient: [T::zero(); 2],
        };
        self.owners[slot] = owner;
        self.share_nodes[slot] = p;
        self.src[slot] = i;
    }
}

/// A body's cells in one lattice row: `key` = first node << 32 | body (so that sorting by key orders a band's
/// segments by row, then column, then body), the last node, and the cells `a..e` of the body's list.
#[derive(Clone, Copy)]
struct Seg {
    key: u64,
    last: u32,
    a: u32,
    e: u32,
}

impl Seg {
    fn first(&self) -> u32 {
        (self.key >> 32) as u32
    }
    fn body(&self) -> u32 {
        self.key as u32
    }
}

/// Count the shares of each column of a row (first node `base`) from its segments into `count`; the first and
/// last column counted (the row has at least one segment).
fn count_columns(
    count: &mut [u32],
    cells: &[BodyCells],
    row: &[Seg],
    base: usize,
) -> (usize, usize) {
    let (mut lo, mut hi) = (usize::MAX, 0);
    for seg in row {
        let c = &cells[seg.body() as usize];
        for &(node, _) in &c.fractions[seg.a as usize..seg.e as usize] {
            let x = node as usize - base;
            count[x] += 1;
            lo = lo.min(x);
            hi = hi.max(x);
        }
    }
    (lo, hi)
}

/// One band of rows of a re-mapping that builds the coverage's lists ([`FluidLattice::build_shares`]): its
/// row segments and scratch, kept between calls.
#[derive(Default)]
struct BandPlan {
    /// The band's row segments, row by row, and in each row by first node (then body).
    segs: Vec<Seg>,
    /// For each row of the band: the end of its segments in `segs`, and whether two of them overlap.
    rows: Vec<(u32, bool)>,
    /// Covered nodes and shares of the band.
    nodes: usize,
    shares: usize,
    /// Per-column counters for the rows whose segments overlap, all zero between uses.
    count: Vec<u32>,
    /// The segments of such a row in body order.
    by_body: Vec<Seg>,
    /// ΩΛ: the band's fully covered nodes, increasing.
    full: Vec<u32>,
}

impl BandPlan {
    /// The segments of rows `y0..y1` from the bodies `list` meeting them, and the band's counts.
    fn plan(&mut self, cells: &[BodyCells], list: &[u32], y0: usize, y1: usize, nx: usize) {
        self.segs.clear();
        self.rows.clear();
        self.count.resize(nx, 0);
        // Each body's segments in the band (one visit per body), then all of them in order of their keys.
        for &k in list {
            let c = &cells[k as usize];
            let Some([_, _, cy0, cy1]) = c.range else {
                continue;
            };
            for y in y0.max(cy0)..y1.min(cy1 + 1) {
                let (a, e) = (c.row_starts[y - cy0], c.row_starts[y - cy0 + 1]);
                if e > a {
                    self.segs.push(Seg {
                        key: (u64::from(c.fractions[a as usize].0) << 32) | u64::from(k),
                        last: c.fractions[e as usize - 1].0,
                        a,
                        e,
                    });
                }
            }
        }
        self.segs.sort_unstable_by_key(|s| s.key);
        let (mut nodes, mut shares) = (0, 0);
        let mut i = 0;
        for y in y0..y1 {
            let start = i;
            let row_end = ((y + 1) * nx) as u32;
            while i < self.segs.len() && self.segs[i].first() < row_end {
                i += 1;
            }
            let row = &self.segs[start..i];
            let overlap = row.windows(2).any(|w| w[0].last >= w[1].first());
            let m: usize = row.iter().map(|s| (s.e - s.a) as usize).sum();
            let n = if overlap {
                // Distinct nodes of the row, from per-column counters.
                let (lo, hi) = count_columns(&mut self.count, cells, row, y * nx);
                let n = self.count[lo..=hi].iter().filter(|&&c| c > 0).count();
                self.count[lo..=hi].fill(0);
                n
            } else {
                m
            };
            nodes += n;
            shares += m;
            self.rows.push((i as u32, overlap));
        }
        self.nodes = nodes;
        self.shares = shares;
    }

    /// Write the band planned by [`BandPlan::plan`] (first row `y0`) into `out`; ΩΛ's fully covered nodes into
    /// `full` (`lambda`).
    fn write<T: Real>(
        &mut self,
        cells: &[BodyCells],
        bodies: &[CoupledBody<f64>],
        y0: usize,
        nx: usize,
        lambda: bool,
        out: &mut BandOut<'_, T>,
    ) {
        self.full.clear();
        let (mut k, mut sh) = (0usize, 0usize);
        let mut start = 0;
        for (r, &(end, overlap)) in self.rows.iter().enumerate() {
            let y = y0 + r;
            let base = y * nx;
            let row = &self.segs[start..end as usize];
            start = end as usize;
            if !overlap {
                // One share per node: the segments one after the other.
                for seg in row {
                    let owner = seg.body();
                    let (c, body) = (&cells[owner as usize], &bodies[owner as usize]);
                    for i in seg.a..seg.e {
                        let cell = c.fractions[i as usize];
                        let p = [(cell.0 as usize - base) as f64, y as f64];
                        out.nodes[k] = cell.0;
                        out.offsets[k] = out.first_share + sh as u32;
                        out.put(sh, owner, i, cell.1, p, body);
                        if lambda && shares_are_full(&out.shares[sh..=sh]) {
                            self.full.push(cell.0);
                        }
                        k += 1;
                        sh += 1;
                    }
                }
                continue;
            }
            // Shared nodes: each column's shares counted, its counter replaced by the slot of its first share
            // in the row, the shares scattered in body order.
            let (lo, hi) = count_columns(&mut self.count, cells, row, base);
            let (row_share, row_node) = (sh, k);
            let mut at = 0u32;
            for x in lo..=hi {
                let c = self.count[x];
                if c > 0 {
                    out.nodes[k] = (base + x) as u32;
                    out.offsets[k] = out.first_share + (row_share as u32 + at);
                    self.count[x] = at;
                    at += c;
                    k += 1;
                }
            }
            self.by_body.clear();
            self.by_body.extend_from_slice(row);
            self.by_body.sort_unstable_by_key(|s| s.body());
            for seg in &self.by_body {
                let owner = seg.body();
                let (c, body) = (&cells[owner as usize], &bodies[owner as usize]);
                for i in seg.a..seg.e {
                    let cell = c.fractions[i as usize];
                    let x = cell.0 as usize - base;
                    let slot = row_share + self.count[x] as usize;
                    self.count[x] += 1;
                    out.put(slot, owner, i, cell.1, [x as f64, y as f64], body);
                }
            }
            self.count[lo..=hi].fill(0);
            sh += at as usize;
            if lambda {
                for j in row_node..k {
                    let a = (out.offsets[j] - out.first_share) as usize;
                    let b = if j + 1 < k {
                        (out.offsets[j + 1] - out.first_share) as usize
                    } else {
                        sh
                    };
                    if shares_are_full(&out.shares[a..b]) {
                        self.full.push(out.nodes[j]);
                    }
                }
            }
        }
    }
}

/// ΩΛ's open links of **every** lattice node given the set of fully covered nodes, kept between re-mappings so that
/// a re-mapping updates only the links of the neighbours of nodes whose full cover changed (a handful per step:
/// grains move a thousandth of a spacing per step) instead of testing the eight neighbours of every covered node.
/// The masks are exactly what [`open_links`] gives with the current flags and full set (tested against a fresh
/// computation after every re-mapping of random moving bodies).
#[derive(Default)]
struct LinkState {
    /// Whether `dense` and `full_list` describe the lattice's current flags and sides. Cleared by every change
    /// that is not a re-mapping by [`FluidLattice::cover_with_bodies`] ([`compute_links`], new flags, a loaded
    /// checkpoint, a coverage given cell by cell, a cleared coverage).
    valid: bool,
    /// Open links of each node (bit q: neighbour x + c_q inside the lattice, not an obstacle, not fully covered).
    dense: Vec<OpenLinks>,
    /// The fully covered nodes the masks were computed for, increasing.
    full_list: Vec<u32>,
    /// The list before that (its allocation reused for the next one).
    spare: Vec<u32>,
    /// Per node scratch of [`compute_links`], all zero between calls.
    marks: Vec<u8>,
}

impl LinkState {
    /// Forget the masks (they are rebuilt at the next re-mapping).
    fn invalidate(&mut self) {
        self.valid = false;
    }

    /// Update the masks to the fully covered nodes `now` (increasing) and return them for the nodes `nodes`.
    fn update<T: Real>(
        &mut self,
        shape: &LatticeShape,
        bc: &Boundaries<T>,
        flags: &[u8],
        now: Vec<u32>,
        nodes: &[u32],
        out: &mut Vec<OpenLinks>,
    ) {
        let periodic = bc.periodic_axes();
        if !self.valid || self.dense.len() != shape.nodes() {
            // Every node's links with nothing fully covered; `now` is applied below as newly full.
            self.dense.clear();
            self.dense
                .par_extend((0..shape.nodes()).into_par_iter().map(|n| {
                    let (x, y) = shape.coords(n);
                    open_links(shape, bc, flags, x, y, |_| false)
                }));
            self.full_list.clear();
            self.valid = true;
        }
        // Link q of node m looks at m + c_q; the nodes whose link q looks at n are n − c_q (one node, or none
        // where that lies outside a side that is not periodic).
        let set = |dense: &mut [OpenLinks], n: u32, open: bool| {
            let (x, y) = shape.coords(n as usize);
            for (q, &back) in OPPOSITE.iter().enumerate().skip(1) {
                if let lbdem_kernels::fluid::lattice::Neighbour::Node(m) =
                    shape.neighbour(x, y, back, periodic)
                {
                    if open {
                        dense[m] |= 1 << q;
                    } else {
                        dense[m] &= !(1 << q);
                    }
                }
            }
        };
        // Both lists increase: one merge finds the nodes that left the set and those that joined it.
        let (old, mut i, mut j) = (&self.full_list, 0, 0);
        while i < old.len() || j < now.len() {
            match (old.get(i), now.get(j)) {
                (Some(&a), Some(&b)) if a == b => {
                    i += 1;
                    j += 1;
                }
                (Some(&a), b) if b.is_none_or(|&b| a < b) => {
                    // No longer fully covered: its neighbours' links to it open again, unless it is an
                    // obstacle.
                    if flags[a as usize] != SOLID {
                        set(&mut self.dense, a, true);
                    }
                    i += 1;
                }
                (_, Some(&b)) => {
                    set(&mut self.dense, b, false);
                    j += 1;
                }
                // (None, None): the loop condition excludes it.
                _ => break,
            }
        }
        self.spare = std::mem::replace(&mut self.full_list, now);
        let dense = &self.dense[..];
        out.clear();
        out.par_extend(nodes.par_iter().map(|&n| dense[n as usize]));
    }
}

/// The cells one body covers: its cell range and, for every cell with a positive fraction, in increasing node
/// order, the node and its fraction (for the geometry in `key`). The node's coordinates and the body's rigid
/// velocity there are evaluated where the shares are written (step 4 of [`FluidLattice::cover_with_bodies`]),
/// not stored here.
#[derive(Default)]
struct BodyCells {
    key: Option<[u64; 6]>,
    /// The geometry (centre and shape; the velocities are not used) the cells were last mapped for, kept for
    /// the remap tolerance ([`FluidLattice::set_remap_tolerance`]); set by every call, also when the cells
    /// were kept.
    anchor: Option<CoupledBody<f64>>,
    range: Option<[usize; 4]>,
    fractions: Vec<(u32, f64)>,
    /// The previous call's `fractions` and `row_starts` (their buffers are reused for the next ones).
    prev: Vec<(u32, f64)>,
    prev_row_starts: Vec<u32>,
    /// Whether the last call recomputed the cells (then `prev` and `prev_row_starts` hold the ones before,
    /// whose range started at row `prev_y0`).
    recomputed: bool,
    prev_y0: Option<usize>,
    /// With `range` = [x0, x1, y0, y1]: the index in `fractions` of the first cell of each row y0 ..= y1 + 1
    /// (the last entry is `fractions.len()`), so the cells of rows ya..yb are `fractions[row_starts[ya − y0] ..
    /// row_starts[yb − y0]]` without a search.
    row_starts: Vec<u32>,
}

impl BodyCells {
    /// Bit pattern of everything the cell fractions depend on: the kind of shape, centre and shape parameters.
    fn geometry_key(body: &CoupledBody<f64>) -> [u64; 6] {
        let [cx, cy] = [body.center[0].to_bits(), body.center[1].to_bits()];
        match body.shape {
            BodyShape::Disc { radius } => [0, cx, cy, radius.to_bits(), 0, 0],
            BodyShape::Ellipse {
                semi_major,
                semi_minor,
                angle,
            } => [
                1,
                cx,
                cy,
                semi_major.to_bits(),
                semi_minor.to_bits(),
                angle.to_bits(),
            ],
        }
    }

    /// Recompute the cells unless the geometry is bitwise unchanged (nodes on Zou–He sides are skipped), keeping
    /// the previous ones for [`BodyCells::kept_its_nodes`].
    fn update<T: Real>(&mut self, body: &CoupledBody<f64>, pass: &mut CellPass<'_, T>) {
        let key = Self::geometry_key(body);
        self.recomputed = self.key != Some(key);
        if self.recomputed {
            self.key = Some(key);
            std::mem::swap(&mut self.fractions, &mut self.prev);
            std::mem::swap(&mut self.row_starts, &mut self.prev_row_starts);
            self.prev_y0 = self.range.map(|r| r[2]);
            self.recompute(body, pass);
        }
    }

    /// Whether the last call left the body on the same nodes as the call before (asked only until one body
    /// answers no, so that a step where many grains change their cells pays for a few comparisons).
    fn kept_its_nodes(&self) -> bool {
        !self.recomputed || self.same_nodes_as_prev(self.prev_y0)
    }

    /// Whether `fractions` has exactly the nodes of `prev` (first row `prev_y0` of the previous range). Row by
    /// row where it can: two rows with the same count, first and last node, whose nodes are consecutive (count
    /// = last − first + 1), hold the same nodes; otherwise node by node. May answer `false` for equal lists
    /// (a range that moved by an empty row), never `true` for different ones.
    fn same_nodes_as_prev(&self, prev_y0: Option<usize>) -> bool {
        if self.fractions.len() != self.prev.len() {
            return false;
        }
        if self.fractions.is_empty() {
            return true;
        }
        if self.range.map(|r| r[2]) != prev_y0 || self.row_starts != self.prev_row_starts {
            return false;
        }
        let mut consecutive = true;
        for w in self.row_starts.windows(2) {
            let (a, e) = (w[0] as usize, w[1] as usize);
            if e == a {
                continue;
            }
            let (first, last) = (self.fractions[a].0, self.fractions[e - 1].0);
            if first != self.prev[a].0 || last != self.prev[e - 1].0 {
                return false;
            }
            consecutive &= (last - first) as usize + 1 == e - a;
        }
        consecutive
            || self
                .fractions
                .iter()
                .zip(&self.prev)
                .all(|(a, b)| a.0 == b.0)
    }

    fn recompute<T: Real>(&mut self, body: &CoupledBody<f64>, pass: &mut CellPass<'_, T>) {
        self.row_starts.clear();
        self.recompute_cells(body, pass);
        // Where each row's cells start: recorded row by row as the cells were pushed, completed here for rows
        // after the last one pushed (none when no row was).
        if let Some([_, _, y0, y1]) = self.range {
            let end = self.fractions.len() as u32;
            self.row_starts.resize(y1 - y0 + 2, end);
        }
    }

    /// The cells and their fractions (see [`BodyCells::recompute`]).
    fn recompute_cells<T: Real>(&mut self, body: &CoupledBody<f64>, pass: &mut CellPass<'_, T>) {
        self.fractions.clear();
        let (s, bc) = (pass.shape, pass.bc);
        self.range = body_cell_range(body, s.nx, s.ny);
        let Some([x0, x1, y0, y1]) = self.range else {
            return;
        };
        if self.recompute_ellipse(body, pass) {
            return;
        }
        let prepared = PreparedBody::new(body);
        let classify = EllipseCells::new(body);
        self.row_starts.clear();
        for y in y0..=y1 {
            self.row_starts.push(self.fractions.len() as u32);
            for x in x0..=x1 {
                if on_zou_he_side(s, bc, x, y) {
                    continue;
                }
                let (xf, yf) = (x as f64, y as f64);
                let frac = match classify.as_ref().map(|c| c.classify(xf, yf)) {
                    Some(CellClass::Inside) => 1.0,
                    Some(CellClass::Outside) => 0.0,
                    _ => prepared.cell_fraction(xf, yf),
                };
                if frac > 0.0 {
                    self.fractions.push((s.index(x, y) as u32, frac));
                }
            }
        }
    }
}

/// The largest remap tolerance [`FluidLattice::set_remap_tolerance`] takes, in lattice spacings: a quarter of a
/// cell, beyond which the lag would be a visible part of the partially covered cells it is meant to leave
/// alone.
pub const MAX_REMAP_TOLERANCE: f64 = 0.25;

/// Refuses a remap tolerance ([`FluidLattice::set_remap_tolerance`]) that is negative, not finite or above
/// [`MAX_REMAP_TOLERANCE`], naming `fluid.remap_tolerance`.
pub fn check_remap_tolerance(tolerance: f64) -> Result<()> {
    if tolerance.is_finite() && (0.0..=MAX_REMAP_TOLERANCE).contains(&tolerance) {
        return Ok(());
    }
    Err(LbdemError::field(
        "fluid.remap_tolerance",
        tolerance,
        &format!(
            "must lie in [0, {MAX_REMAP_TOLERANCE}] lattice spacings: how far a grain may move before it is \
             mapped onto the lattice again"
        ),
        "use 0 (re-map at every step, the default) or a few hundredths, e.g. 0.05",
    ))
}

/// Whether no point of body `b` lies farther than `tolerance` (lattice spacings) from where it lay as body `a`:
/// the same kind of shape with bitwise the same size, and |Δc| + r |Δθ| ≤ tolerance, with r the largest
/// distance of a point of the shape from its centre (a point at distance r moves by at most r |Δθ| under a
/// rotation by Δθ). False for anything not finite.
fn moved_at_most(a: &CoupledBody<f64>, b: &CoupledBody<f64>, tolerance: f64) -> bool {
    let turn = match (a.shape, b.shape) {
        (BodyShape::Disc { radius: ra }, BodyShape::Disc { radius: rb })
            if ra.to_bits() == rb.to_bits() =>
        {
            0.0
        }
        (
            BodyShape::Ellipse {
                semi_major: a1,
                semi_minor: b1,
                angle: t1,
            },
            BodyShape::Ellipse {
                semi_major: a2,
                semi_minor: b2,
                angle: t2,
            },
        ) if a1.to_bits() == a2.to_bits() && b1.to_bits() == b2.to_bits() => {
            a1.abs().max(b1.abs()) * (t2 - t1).abs()
        }
        _ => return false,
    };
    let d = b.center - a.center;
    let shift = d[0].hypot(d[1]) + turn;
    shift.is_finite() && shift <= tolerance
}

/// The unclamped cell block of an ellipse body, its cell count and the ellipse's (a, b, θ), when the
/// whole-ellipse kernel is to be used: not for discs, nor for blocks much larger than their part `range` on
/// the lattice (an ellipse mostly outside it).
fn ellipse_block(
    body: &CoupledBody<f64>,
    [x0, x1, y0, y1]: [usize; 4],
) -> Option<(CellGrid, usize, f64, f64, f64)> {
    let BodyShape::Ellipse {
        semi_major,
        semi_minor,
        angle,
    } = body.shape
    else {
        return None;
    };
    let grid = ellipse_cell_grid(body.center, semi_major, semi_minor)?;
    let on_lattice = (x1 - x0 + 1) * (y1 - y0 + 1);
    let n = grid.cells().filter(|&n| n <= 4 * on_lattice + 64)?;
    Some((grid, n, semi_major, semi_minor, angle))
}

impl BodyCells {
    /// The cells of an ellipse from the whole-ellipse kernel (one `atan2` per crossing of the ellipse with a
    /// lattice line, `ellipse_grid_fractions`); `false` (nothing pushed) for discs, for blocks much larger than
    /// their part on the lattice, and where the kernel refuses (a crossing within roundoff reach of a lattice
    /// vertex): the caller then takes the per-cell formula.
    fn recompute_ellipse<T: Real>(
        &mut self,
        body: &CoupledBody<f64>,
        pass: &mut CellPass<'_, T>,
    ) -> bool {
        let (s, bc, simd) = (pass.shape, pass.bc, pass.simd);
        let scratch = &mut *pass.grid;
        let Some([x0, x1, y0, y1]) = self.range else {
            return false;
        };
        let Some((grid, n, semi_major, semi_minor, angle)) = ellipse_block(body, [x0, x1, y0, y1])
        else {
            return false;
        };
        scratch.fractions.resize(n, 0.0);
        scratch.boundary.resize(n, false);
        // Compiled for the lattice's SIMD level: the kernel computes the crossings of eight lattice lines at a
        // time over lanes (same bits at every level).
        let sin_cos = angle.portable_sin_cos();
        let (fr, bd) = (&mut scratch.fractions, &mut scratch.boundary);
        if !with_simd(
            simd,
            #[inline(always)]
            || ellipse_grid_fractions(body.center, semi_major, semi_minor, sin_cos, grid, fr, bd),
        ) {
            return false;
        }
        // The lattice's part of the block (the same bounds, clamped), without the nodes on Zou–He sides.
        let (gx, gy) = (
            (x0 as i64 - grid.x0) as usize,
            (y0 as i64 - grid.y0) as usize,
        );
        // First and last node along an axis from `lo..=hi` without the lattice's first node (`low` side Zou–He)
        // and last node (`high` side Zou–He, `n` nodes); `None` when nothing is left.
        let trim = |lo: usize, hi: usize, n: usize, low: bool, high: bool| {
            let lo = if low && lo == 0 { 1 } else { lo };
            let hi = if high && hi + 1 == n {
                hi.checked_sub(1)?
            } else {
                hi
            };
            (lo <= hi).then_some((lo, hi))
        };
        let (Some((xa, xb)), Some((ya, yb))) = (
            trim(x0, x1, s.nx, bc.west.is_zou_he(), bc.east.is_zou_he()),
            trim(y0, y1, s.ny, bc.south.is_zou_he(), bc.north.is_zou_he()),
        ) else {
            return true;
        };
        // Row starts of rows y0..ya (none of their cells are kept), then each row's as it is reached.
        self.row_starts.resize(ya - y0, 0);
        for y in ya..=yb {
            self.row_starts.push(self.fractions.len() as u32);
            let row = (y - y0 + gy) * grid.w;
            // The lattice part's columns of the block row: every cell, each kept when its fraction is positive
            // (the kernel leaves the cells outside a row's span of boundary cells at exactly 0), written without
            // a branch and the list cut back to the kept ones.
            let (ka, kb) = (xa - x0 + gx, xb - x0 + gx);
            // Node of block column k: the row's node of column ka, plus k − ka.
            let node_ka = s.index(xa, y) as u32;
            let fr = &scratch.fractions[row + ka..=row + kb];
            let start = self.fractions.len();
            self.fractions.resize(start + fr.len(), (0, 0.0));
            let out = &mut self.fractions[start..];
            let mut kept = 0;
            for (k, &frac) in fr.iter().enumerate() {
                out[kept] = (node_ka + k as u32, frac);
                kept += usize::from(frac > 0.0);
            }
            self.fractions.truncate(start + kept);
        }
        true
    }
}

/// Where a cell lies relative to an ellipse, decided from its node alone where that is certain.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum CellClass {
    /// Every point of the cell is inside the ellipse by a margin: the exact area formula gives 1.
    Inside,
    /// Every point of the cell is outside the ellipse by a margin: the exact area formula gives 0.
    Outside,
    /// Near the boundary: the exact area formula decides.
    Boundary,
}

/// A cheap, conservative cell classifier for one ellipse, so that the exact area formula
/// (`ellipse_cell_fraction_oriented`) runs only on the cells near the boundary, bitwise as before.
///
/// In the frame where the ellipse is the unit disc, u = R(−θ)(p − c) / (a, b), the node of a cell lies at
/// normalised radius √q, and every point of the cell lies within √2/2 of the node, hence within
/// r = (√2/2) / min(a, b) of it in that frame (the map's largest stretch is 1/min(a, b)). So the whole cell is
/// inside the ellipse when √q + r < 1 and outside when √q − r > 1. A relative margin of 1e-6 on those
/// bounds covers the roundoff of q and of the formula's own corner tests (both ~1e-15 relative, or ~1e-13/min(a, b)
/// absolute for lattices of 10⁴ nodes a side): a cell called `Inside` has all four corners strictly inside as the
/// formula computes them, so it returns exactly the cell's area, 1; a cell called `Outside` misses the ellipse as
/// the formula's quadrilateral test computes it, so it returns exactly 0.
struct EllipseCells {
    center: [f64; 2],
    sin_cos: (f64, f64),
    inv_axes: [f64; 2],
    inside_q: f64,
    outside_q: f64,
}

impl EllipseCells {
    /// Relative margin on the inside/outside bounds (see the type's documentation).
    const MARGIN: f64 = 1e-6;

    /// The classifier of an ellipse body with finite positive semi-axes (`None` for discs and degenerate
    /// ellipses: every cell then goes to the exact formula).
    fn new(body: &CoupledBody<f64>) -> Option<Self> {
        let BodyShape::Ellipse {
            semi_major: a,
            semi_minor: b,
            angle,
        } = body.shape
        else {
            return None;
        };
        if !(a > 0.0 && b > 0.0 && a.is_finite() && b.is_finite() && angle.is_finite()) {
            return None;
        }
        let r = std::f64::consts::FRAC_1_SQRT_2 / a.min(b);
        let inner = (1.0 - r) * (1.0 - Self::MARGIN);
        let outer = (1.0 + r) * (1.0 + Self::MARGIN);
        Some(Self {
            center: [body.center[0], body.center[1]],
            sin_cos: angle.portable_sin_cos(),
            inv_axes: [1.0 / a, 1.0 / b],
            // No cell is certainly inside when r ≥ 1 (q ≥ 0 is never below −1).
            inside_q: if inner > 0.0 { inner * inner } else { -1.0 },
            outside_q: outer * outer,
        })
    }

    #[inline]
    fn classify(&self, x: f64, y: f64) -> CellClass {
        let (sin, cos) = self.sin_cos;
        let (dx, dy) = (x - self.center[0], y - self.center[1]);
        let u = (cos * dx + sin * dy) * self.inv_axes[0];
        let v = (cos * dy - sin * dx) * self.inv_axes[1];
        let q = u * u + v * v;
        if q < self.inside_q {
            CellClass::Inside
        } else if q > self.outside_q {
            CellClass::Outside
        } else {
            CellClass::Boundary
        }
    }
}

/// The kernel's view of the lattice's side profiles.
fn side_profiles<T: Real>(p: &[Vec<[T; 2]>; 4]) -> SideProfiles<'_, T> {
    SideProfiles {
        west: &p[0],
        east: &p[1],
        south: &p[2],
        north: &p[3],
    }
}

/// Whether node (x, y) lies on a Zou–He (pressure or velocity) side.
fn on_zou_he_side<T: Real>(s: &LatticeShape, bc: &Boundaries<T>, x: usize, y: usize) -> bool {
    (x == 0 && bc.west.is_zou_he())
        || (x + 1 == s.nx && bc.east.is_zou_he())
        || (y == 0 && bc.south.is_zou_he())
        || (y + 1 == s.ny && bc.north.is_zou_he())
}

/// Rows per parallel task when the shares of the bodies are gathered node by node ([`FluidLattice::cover_with_bodies`]).
const COVER_BAND_ROWS: usize = 16;

/// Special nodes per parallel task in phase 1 of the in-place step.
const SPECIAL_CHUNK: usize = 1024;

/// The covered nodes of one band of rows in the in-place step: index range in the covered list, their exchange
/// entries.
type CoveredBand<'a, T> = (usize, usize, &'a mut [[T; 2]]);

/// Nodes covered by solids (compressed rows), the solid each share belongs to, and the momentum handed to
/// each share at the last step.
#[derive(Clone, serde::Serialize, serde::Deserialize)]
#[serde(bound(
    serialize = "T: serde::Serialize",
    deserialize = "T: serde::Deserialize<'de> + Default"
))]
struct Coverage<T> {
    /// Identity of the lists (nodes, offsets, owners, share nodes) for caches keyed on them
    /// ([`next_list_id`]; renewed whenever they are built, 0 until then for a coverage read from a checkpoint).
    #[serde(skip)]
    layout: u64,
    /// Identity of the fractions (renewed with `layout` and whenever the shares' fractions are rewritten; 0
    /// until the first step for a coverage read from a checkpoint): what the covered rows' plans are kept for.
    #[serde(skip)]
    fractions: u64,
    nodes: Vec<u32>,
    offsets: Vec<u32>,
    shares: Vec<SolidShare<T>>,
    owners: Vec<u32>,
    share_nodes: Vec<[f64; 2]>,
    /// The unit outward normal of each share's solid at its node ([`surface_normal`]; zero for a solid given
    /// cell by cell unless [`FluidLattice::set_field_normals`] gave them): the wall direction of ΩΛ's
    /// wall-pressure force ([`wall_gradients`]). Empty for bodies while that form is off (nothing reads them).
    normals: Vec<[T; 2]>,
    exchange: Vec<[T; 2]>,
    weighting: Weighting,
    /// Links of each covered node to nodes that are not fully covered (read by ΩΛ only). Derived from the
    /// rest of the coverage, the side conditions and the flags: not saved, recomputed on load.
    #[serde(skip)]
    links: Vec<OpenLinks>,
}

/// Whether covered node `k` of `cov` is fully covered for ΩΛ: the sum the collision forms (same order),
/// compared as the collision compares it.
fn node_is_full<T: Real>(cov: &Coverage<T>, k: usize) -> bool {
    shares_are_full(&cov.shares[cov.offsets[k] as usize..cov.offsets[k + 1] as usize])
}

/// Whether a node with these shares is fully covered for ΩΛ: their fractions summed in the collision's order,
/// compared as the collision compares them.
fn shares_are_full<T: Real>(shares: &[SolidShare<T>]) -> bool {
    let mut eps = T::zero();
    for s in shares {
        eps += s.fraction;
    }
    lbdem_kernels::fluid::collide::lambda_fully_covered(eps)
}

/// Fill `cov.links` from the coverage, the side conditions and the obstacle flags, from scratch (every covered
/// node's eight neighbours tested). `state`'s per-node scratch is used and left all zero; its kept masks are
/// invalidated (the caller may have changed what they depend on).
fn compute_links<T: Real>(
    cov: &mut Coverage<T>,
    shape: &LatticeShape,
    bc: &Boundaries<T>,
    flags: &[u8],
    state: &mut LinkState,
    operator: SolidOperator,
) {
    state.invalidate();
    if operator != SolidOperator::LambdaConsistent {
        // Only ΩΛ reads the masks: the other operators get "every link open" without the per-node pass, which
        // would otherwise run at every re-mapping of a coupled step.
        cov.links.clear();
        cov.links.resize(cov.nodes.len(), ALL_LINKS_OPEN);
        return;
    }
    let full = &mut state.marks;
    full.resize(shape.nodes(), 0);
    // Each node's test in parallel, the per-node map filled in node order, then each node's links in parallel
    // (each depends on the map only).
    let node_full: Vec<bool> = (0..cov.nodes.len())
        .into_par_iter()
        .map(|k| node_is_full(cov, k))
        .collect();
    for (&n, &f) in cov.nodes.iter().zip(&node_full) {
        full[n as usize] = u8::from(f);
    }
    cov.links.clear();
    let full_map = &full[..];
    cov.links.par_extend(cov.nodes.par_iter().map(|&n| {
        let (x, y) = shape.coords(n as usize);
        open_links(shape, bc, flags, x, y, |j| full_map[j] != 0)
    }));
    for &n in &cov.nodes {
        full[n as usize] = 0;
    }
}

/// A disc as the fluid sees it: centre and radius (lattice units), rigid-body velocity and angular velocity.
#[derive(Clone, Copy, Debug)]
pub struct FluidDisc {
    /// Centre (lattice units, node coordinates).
    pub center: [f64; 2],
    /// Radius the fluid sees (lattice units).
    pub radius: f64,
    /// Translational velocity (lattice units).
    pub velocity: [f64; 2],
    /// Angular velocity (rad per step).
    pub spin: f64,
}

impl<T: Real> FluidLattice<T> {
    /// An `nx × ny` lattice at rest with density 1, all nodes fluid.
    pub fn new(nx: usize, ny: usize, bc: Boundaries<T>, params: FluidParams<T>) -> Result<Self> {
        let shape = LatticeShape::for_type::<T>(nx, ny).map_err(|e| {
            LbdemError::field(
                "lattice size",
                format!("{nx} x {ny}"),
                &format!("cannot be allocated ({e:?})"),
                "every side needs at least one node and the node count must fit in 32 bits",
            )
        })?;
        bc.validate().map_err(|e| {
            LbdemError::field(
                "boundary conditions",
                format!("{e:?}"),
                "are inconsistent",
                "pair periodic sides",
            )
        })?;
        if params.tau.to_f64_exact().partial_cmp(&0.5) != Some(std::cmp::Ordering::Greater) {
            return Err(LbdemError::field(
                "fluid.tau",
                params.tau.to_f64_exact(),
                "BGK is unstable for tau <= 1/2",
                "use tau in (0.5, 2]",
            ));
        }
        let len = shape.buffer_len();
        let streaming = Streaming::default();
        let mut lattice = Self {
            shape,
            bc,
            params,
            flags: vec![FLUID; shape.nodes()],
            special: Vec::new(),
            special_mask: Vec::new(),
            buffers: vec![T::zero(); buffers_len::<T>(len, streaming)],
            second: len + buffer_gap::<T>(len),
            first_is_current: true,
            band_rows: 8,
            steps: 0,
            coverage: None,
            cover_scratch: CoverScratch::default(),
            remap_tolerance: 0.0,
            solid_operator: SolidOperator::default(),
            lambda_terms: LambdaTerms::default(),
            collision: Collision::Bgk,
            profiles: [Side::West, Side::East, Side::South, Side::North].map(|side| {
                match (bc.side(side), side) {
                    (SideCondition::VelocityProfile, Side::West | Side::East) => {
                        vec![[T::zero(); 2]; ny]
                    }
                    (SideCondition::VelocityProfile, _) => vec![[T::zero(); 2]; nx],
                    _ => Vec::new(),
                }
            }),
            simd: SimdLevel::detect(),
            streaming,
            layout: Layout::Collided,
            aa_special: Vec::new(),
            aa_covered: Vec::new(),
            aa_covered_special: Vec::new(),
            aa_covered_special_key: None,
            aa_covered_special_found: 0,
            special_id: 0,
            covered_plans: Vec::new(),
            covered_plans_made: 0,
            densities: Vec::new(),
        };
        lattice.reclassify();
        lattice.fill_equilibrium(|_, _| (T::one(), [T::zero(); 2]));
        Ok(lattice)
    }

    /// Shape of the lattice.
    pub fn shape(&self) -> &LatticeShape {
        &self.shape
    }

    /// Collision parameters.
    pub fn params(&self) -> &FluidParams<T> {
        &self.params
    }

    /// Side conditions.
    pub fn boundaries(&self) -> &Boundaries<T> {
        &self.bc
    }

    /// Node flags.
    pub fn flags(&self) -> &[u8] {
        &self.flags
    }

    /// The fluid collision operator (BGK unless [`FluidLattice::set_collision`] chose TRT).
    pub fn collision(&self) -> Collision<T> {
        self.collision
    }

    /// Choose the fluid collision operator: BGK (the default) or two-relaxation-time with magic parameter Λ
    /// (see [`Collision`]). The same operator relaxes the fluid part of partially covered nodes. Refused, with
    /// the lattice unchanged, when τ⁻ = ½ + Λ/(τ − ½) is not finite and above ½ (a [`lbdem_kernels::fluid::
    /// collide::Trt`] already has Λ > 0).
    pub fn set_collision(&mut self, collision: Collision<T>) -> Result<()> {
        collision.rates(self.params.tau).map_err(|e| {
            let magic = match collision {
                Collision::Trt(t) => t.magic().to_f64_exact(),
                Collision::Bgk => f64::NAN,
            };
            LbdemError::field(
                "fluid.magic",
                magic,
                &format!("gives no usable two-relaxation-time rates with tau = {} ({e:?})", {
                    self.params.tau.to_f64_exact()
                }),
                "use a magic parameter Lambda > 0 such that tau_minus = 1/2 + Lambda/(tau - 1/2) is finite \
                 (3/16 is the default)",
            )
        })?;
        self.collision = collision;
        Ok(())
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Instruction set of the bulk pass (the widest this CPU has unless set).
    pub fn simd(&self) -> SimdLevel {
        self.simd
    }

    /// Choose the instruction set of the bulk pass. Results are bitwise the same at every level; only speed
    /// changes. Refuses a level this CPU lacks.
    pub fn set_simd(&mut self, simd: SimdLevel) -> Result<()> {
        simd.check_available()?;
        self.simd = simd;
        Ok(())
    }

    /// The streaming scheme.
    pub fn streaming(&self) -> Streaming {
        self.streaming
    }

    /// Choose the streaming scheme. Results are bitwise the same with either; memory and speed change.
    pub fn set_streaming(&mut self, streaming: Streaming) {
        if streaming == self.streaming {
            return;
        }
        self.normalize();
        let len = self.shape.buffer_len();
        if !self.first_is_current {
            self.buffers.copy_within(self.second..self.second + len, 0);
            self.first_is_current = true;
        }
        self.buffers
            .resize(buffers_len::<T>(len, streaming), T::zero());
        self.buffers.shrink_to_fit();
        self.streaming = streaming;
    }

    /// Bring the current buffer into the two-lattice layout (a no-op unless the in-place scheme left it in
    /// its streamed layout after an odd step).
    fn normalize(&mut self) {
        if self.layout == Layout::Collided {
            return;
        }
        let collided = self.populations().into_owned();
        self.layout = Layout::Collided;
        self.current_mut().copy_from_slice(&collided);
    }

    /// Rows per parallel band (default 8; results do not depend on it, only speed does).
    pub fn set_band_rows(&mut self, rows: usize) {
        self.band_rows = rows.max(1);
    }

    /// Mark nodes as solid obstacles (half-way bounce-back) according to `solid(x, y)`.
    pub fn set_solid(&mut self, solid: impl Fn(usize, usize) -> bool) {
        // Where the in-place scheme keeps a population depends on the flags: store it plainly first.
        self.normalize();
        for y in 0..self.shape.ny {
            for x in 0..self.shape.nx {
                let n = self.shape.index(x, y);
                self.flags[n] = if solid(x, y) { SOLID } else { FLUID };
            }
        }
        self.reclassify();
    }

    /// Recompute the open links of the covered nodes (they depend on the coverage and the obstacle flags).
    fn refresh_links(&mut self) {
        if let Some(cov) = self.coverage.as_mut() {
            compute_links(
                cov,
                &self.shape,
                &self.bc,
                &self.flags,
                &mut self.cover_scratch.links,
                self.solid_operator,
            );
        } else {
            self.cover_scratch.links.invalidate();
        }
    }

    fn reclassify(&mut self) {
        self.refresh_links();
        let mut list = vec![0u32; self.shape.nodes()];
        let count = classify_special_nodes(&self.shape, &self.bc, &self.flags, &mut list);
        list.truncate(count);
        self.special_mask = vec![false; self.shape.nodes()];
        for &n in &list {
            self.special_mask[n as usize] = true;
        }
        self.special = list;
        self.special_id = next_list_id();
    }

    /// Set every node to the equilibrium of `state(x, y) = (ρ, u)` (stored as post-collision populations).
    pub fn fill_equilibrium(&mut self, state: impl Fn(usize, usize) -> (T, [T; 2])) {
        // Every node's nine slots are rewritten below, in the two-lattice layout.
        self.layout = Layout::Collided;
        let stride = self.shape.stride;
        for y in 0..self.shape.ny {
            for x in 0..self.shape.nx {
                let n = self.shape.index(x, y);
                let (rho, u) = state(x, y);
                let f = equilibrium(rho, u);
                for (q, fq) in f.iter().enumerate() {
                    self.current_mut()[q * stride + n] = *fq;
                }
            }
        }
    }

    /// The current post-collision populations in the two-lattice layout (direction q of node n at
    /// `q * stride + n`, padding included). Borrowed, except after an odd step of the in-place scheme, when
    /// they are gathered from where that scheme keeps them.
    pub fn populations(&self) -> Cow<'_, [T]> {
        let current = self.current();
        match self.layout {
            Layout::Collided => Cow::Borrowed(current),
            Layout::Streamed => {
                let mut out = vec![T::zero(); current.len()];
                let periodic = self.bc.periodic_axes();
                to_collided(
                    &self.shape,
                    periodic,
                    &self.flags,
                    self.layout,
                    current,
                    &mut out,
                );
                Cow::Owned(out)
            }
        }
    }

    /// Mutable access to the current population buffer in the two-lattice layout (for initial conditions and
    /// tests).
    pub fn populations_mut(&mut self) -> &mut [T] {
        self.normalize();
        self.current_mut()
    }

    fn current(&self) -> &[T] {
        &self.buffers[self.current_range()]
    }

    /// Where the current buffer lies in `buffers`.
    fn current_range(&self) -> std::ops::Range<usize> {
        let len = self.shape.buffer_len();
        if self.first_is_current {
            0..len
        } else {
            self.second..self.second + len
        }
    }

    fn current_mut(&mut self) -> &mut [T] {
        let range = self.current_range();
        &mut self.buffers[range]
    }

    /// Cover the lattice with discs (exact cell fractions, several discs per cell add up, capped at 1 by the
    /// collision) using the partially-saturated collision with weighting `weighting`. Replaces any previous
    /// coverage. See [`FluidLattice::cover_with_bodies`].
    pub fn cover_with_discs(&mut self, discs: &[FluidDisc], weighting: Weighting) {
        let bodies: Vec<CoupledBody<f64>> = discs
            .iter()
            .map(|d| CoupledBody {
                center: lbdem_kernels::math::Vector::from(d.center),
                velocity: lbdem_kernels::math::Vector::from(d.velocity),
                spin: d.spin,
                shape: BodyShape::Disc { radius: d.radius },
            })
            .collect();
        self.cover_with_bodies(&bodies, weighting);
    }

    /// Cover the lattice with rigid bodies (discs or ellipses as the fluid sees them, lattice units): exact cell
    /// fractions from the coupling kernels, several bodies per cell add up (capped at 1 by the collision), each
    /// share carrying the body's rigid velocity at the node. Replaces any previous coverage. Bodies must lie
    /// inside the lattice (no periodic images are taken).
    ///
    /// Nodes on Zou–He sides are never covered: the closure re-imposes the boundary density there every step,
    /// and a fully covered (B = 1) Zou–He node leaves its rest population unrelaxed; the verification suite found
    /// such nodes diverging within a few steps on small random lattices. Solids that reach a pressure or
    /// velocity boundary are therefore seen by the fluid only inside it.
    pub fn cover_with_bodies(&mut self, bodies: &[CoupledBody<f64>], weighting: Weighting) {
        let s = self.shape;
        let bc = self.bc;
        // 1. Each body's cells (row-major, so in increasing node order), in
        //    parallel over bodies: only the cells of its bounding box are visited. An ellipse's fractions come
        //    from one pass over the lattice lines crossing it (`ellipse_grid_fractions`: one angle per crossing,
        //    shared by the two cells it separates); discs, and the rare ellipse the pass refuses, take the
        //    per-cell exact formula on the cells near their boundary. A body whose geometry is bitwise unchanged
        //    since the last call keeps its cell fractions. The rigid velocities are evaluated in step 4.
        let simd = self.simd;
        let tolerance = self.remap_tolerance;
        let wall_form = self.wall_form_active();
        let scratch = &mut self.cover_scratch;
        // With a remap tolerance, every body keeps the cells it was last mapped with while no point of any
        // body has moved farther than the tolerance from where it was then (one decision for all bodies, so
        // that between re-mappings no body changes its nodes and the lists are only rewritten).
        let lag = tolerance > 0.0
            && scratch.bodies.len() == bodies.len()
            && scratch
                .bodies
                .par_iter()
                .zip(bodies.par_iter())
                .all(|(c, b)| c.anchor.is_some_and(|a| moved_at_most(&a, b, tolerance)));
        scratch.bodies.resize_with(bodies.len(), BodyCells::default);
        scratch
            .grids
            .resize_with(bodies.len().div_ceil(BODY_CHUNK), GridScratch::default);
        scratch
            .bodies
            .par_chunks_mut(BODY_CHUNK)
            .zip(bodies.par_chunks(BODY_CHUNK))
            .zip(scratch.grids.par_iter_mut())
            .for_each(|((cells, bodies), grid)| {
                let mut pass = CellPass {
                    shape: &s,
                    bc: &bc,
                    simd,
                    grid,
                };
                for (cells, body) in cells.iter_mut().zip(bodies) {
                    let mapped = match cells.anchor {
                        Some(a) if lag => a,
                        _ => *body,
                    };
                    cells.anchor = Some(mapped);
                    cells.update(&mapped, &mut pass);
                }
            });
        // 2.–4. The coverage's lists: rewritten in place when every body covers the same nodes as at the last
        //    call and that call built them, otherwise built anew.
        let lambda = self.solid_operator == SolidOperator::LambdaConsistent;
        // ΩΛ's fully covered nodes, into the buffer the previous call's list left (no fresh allocation per call).
        let mut full_now = std::mem::take(&mut scratch.links.spare);
        full_now.clear();
        let same_layout = scratch.layout_bodies == Some(bodies.len())
            && self
                .coverage
                .as_ref()
                .is_some_and(|c| c.shares.len() == scratch.src.len())
            && scratch.bodies.iter().all(BodyCells::kept_its_nodes);
        // No body recomputed its cells: the fractions, and so ΩΛ's fully covered nodes and open links, are
        // those of the last call.
        let kept = same_layout && scratch.bodies.iter().all(|c| !c.recomputed);
        let links_kept = lambda && kept && scratch.links.valid;
        let mut cov = match self.coverage.take() {
            Some(mut cov) if same_layout => {
                Self::update_shares_in_place(
                    scratch,
                    &mut cov,
                    bodies,
                    kept,
                    lambda && !links_kept,
                    &mut full_now,
                );
                cov.weighting = weighting;
                cov
            }
            previous => Self::build_shares(
                scratch,
                &s,
                previous,
                bodies,
                weighting,
                lambda,
                &mut full_now,
            ),
        };
        let total = cov.shares.len();
        // The wall normals only where something reads them (computing them for every re-mapping cost 13–18 % of
        // `cover_remap` under ΩΛ with the form off).
        if wall_form {
            Self::write_normals(&mut cov, bodies);
        } else {
            cov.normals.clear();
        }
        scratch.last_bodies.clear();
        scratch.last_bodies.extend_from_slice(bodies);
        // Zeroed in parallel (2 MB in the full-size fracture test: serial, it was 1 % of the two-thread step).
        cov.exchange.resize(total, [T::zero(); 2]);
        cov.exchange
            .par_chunks_mut(1 << 14)
            .for_each(|c| c.fill([T::zero(); 2]));
        if links_kept {
            // The masks of the last call (`cov.links`) stand; the spare list goes back.
            scratch.links.spare = full_now;
        } else if lambda {
            // Only the neighbours of nodes whose full cover changed since the last call get new masks.
            let mut links = std::mem::take(&mut cov.links);
            scratch
                .links
                .update(&s, &bc, &self.flags, full_now, &cov.nodes, &mut links);
            cov.links = links;
        } else {
            compute_links(
                &mut cov,
                &s,
                &bc,
                &self.flags,
                &mut scratch.links,
                self.solid_operator,
            );
        }
        self.coverage = Some(cov);
    }

    /// Each share's wall direction: the outward normal of its body at its node ([`surface_normal`]), in
    /// parallel over chunks of shares, each body's orientation taken once. A share that covers its node fully
    /// by itself (ΩΛ then treats the node as fully covered, where no wall force acts) gets zero, which saves
    /// most of the work in a dense pack.
    fn write_normals(cov: &mut Coverage<T>, bodies: &[CoupledBody<f64>]) {
        const CHUNK: usize = 4096;
        let prepared: Vec<PreparedBody<f64>> = bodies.par_iter().map(PreparedBody::new).collect();
        cov.normals.resize(cov.shares.len(), [T::zero(); 2]);
        cov.normals
            .par_chunks_mut(CHUNK)
            .zip(cov.shares.par_chunks(CHUNK))
            .zip(cov.owners.par_chunks(CHUNK))
            .zip(cov.share_nodes.par_chunks(CHUNK))
            .for_each(|(((normals, shares), owners), nodes)| {
                for (((n, share), &owner), &p) in
                    normals.iter_mut().zip(shares).zip(owners).zip(nodes)
                {
                    *n = if lbdem_kernels::fluid::collide::lambda_fully_covered(share.fraction) {
                        [T::zero(); 2]
                    } else {
                        let v = prepared[owner as usize].surface_normal(Point::from(p));
                        [T::lit(v[0]), T::lit(v[1])]
                    };
                }
            });
    }

    /// Steps 2–4 of [`FluidLattice::cover_with_bodies`] from the bodies' cells: the coverage's lists built anew
    /// (into the buffers of `coverage`, if any), ΩΛ's fully covered nodes appended to `full_now` (`lambda`).
    ///
    /// Row by row: a body's cells in a lattice row (its row segment, read from its row starts) lie between the
    /// segment's first and last node, so a row whose segments' spans do not overlap is the concatenation of its
    /// segments ordered by first node, one share per node, written in one sequential pass. A row where spans
    /// overlap (bodies sharing nodes) takes the general path: per-column counters, then the shares scattered
    /// in body order. Both give the shares of each node in increasing body order, so the lists do not depend
    /// on the band size or the thread count. (In the full-size fracture run no two grains share a node, and
    /// 10–20 % of the grains change their set of cells at each step, so nearly every call builds the lists;
    /// building the rows this way instead of with per-node counters over whole bands, with the changes that
    /// went with it, took 7–10 % off the coupled step there; README, *Benchmarks*.)
    fn build_shares(
        scratch: &mut CoverScratch,
        shape: &LatticeShape,
        coverage: Option<Coverage<T>>,
        bodies: &[CoupledBody<f64>],
        weighting: Weighting,
        lambda: bool,
        full_now: &mut Vec<u32>,
    ) -> Coverage<T> {
        let s = *shape;
        let nx = s.nx;
        let band_rows = COVER_BAND_ROWS;
        let bands = s.ny.div_ceil(band_rows);
        let cells = &scratch.bodies;
        // 2. The bodies meeting each band, in increasing order (a body meets the bands its rows cross).
        let band_bodies = &mut scratch.band_bodies;
        band_bodies.resize_with(bands, Vec::new);
        band_bodies.iter_mut().for_each(Vec::clear);
        for (k, c) in cells.iter().enumerate() {
            let Some([_, _, cy0, cy1]) = c.range else {
                continue;
            };
            if c.fractions.is_empty() {
                continue;
            }
            for list in &mut band_bodies[cy0 / band_rows..(cy1 / band_rows + 1).min(bands)] {
                list.push(k as u32);
            }
        }
        let band_bodies = &scratch.band_bodies;
        // 3. In parallel over bands: each row's segments sorted by first node, whether any two overlap, and
        //    the row's covered nodes (counted with per-column counters where segments overlap).
        scratch.plans.resize_with(bands, BandPlan::default);
        scratch
            .plans
            .par_iter_mut()
            .zip(band_bodies.par_iter())
            .enumerate()
            .for_each(|(b, (plan, list))| {
                plan.plan(
                    cells,
                    list,
                    b * band_rows,
                    ((b + 1) * band_rows).min(s.ny),
                    nx,
                )
            });
        let plans = &mut scratch.plans;
        let total_nodes: usize = plans.iter().map(|p| p.nodes).sum();
        let total: usize = plans.iter().map(|p| p.shares).sum();
        let mut cov = coverage.unwrap_or_else(|| Coverage {
            layout: 0,
            fractions: 0,
            nodes: Vec::new(),
            offsets: Vec::new(),
            shares: Vec::new(),
            owners: Vec::new(),
            share_nodes: Vec::new(),
            normals: Vec::new(),
            exchange: Vec::new(),
            weighting,
            links: Vec::new(),
        });
        cov.weighting = weighting;
        cov.layout = next_list_id();
        cov.fractions = next_list_id();
        scratch.src.resize(total, 0);
        // Every entry below is overwritten by its band.
        let zero = SolidShare::default();
        cov.nodes.resize(total_nodes, 0);
        cov.offsets.resize(total_nodes + 1, 0);
        cov.shares.resize(total, zero);
        cov.owners.resize(total, 0);
        cov.share_nodes.resize(total, [0.0; 2]);
        cov.offsets[total_nodes] = total as u32;
        // Each band's slices of the coverage arrays (bands in order: nodes and shares stay in node order).
        let mut outs: Vec<BandOut<'_, T>> = Vec::with_capacity(bands);
        {
            let (mut nodes, mut offsets) = (&mut cov.nodes[..], &mut cov.offsets[..total_nodes]);
            let (mut shares, mut owners, mut share_nodes) = (
                &mut cov.shares[..],
                &mut cov.owners[..],
                &mut cov.share_nodes[..],
            );
            let mut src = &mut scratch.src[..];
            let mut first_share = 0u32;
            for plan in plans.iter() {
                let (n, m) = (plan.nodes, plan.shares);
                let (a, rest) = std::mem::take(&mut nodes).split_at_mut(n);
                nodes = rest;
                let (o, rest) = std::mem::take(&mut offsets).split_at_mut(n);
                offsets = rest;
                let (sh, rest) = std::mem::take(&mut shares).split_at_mut(m);
                shares = rest;
                let (ow, rest) = std::mem::take(&mut owners).split_at_mut(m);
                owners = rest;
                let (sn, rest) = std::mem::take(&mut share_nodes).split_at_mut(m);
                share_nodes = rest;
                let (sr, rest) = std::mem::take(&mut src).split_at_mut(m);
                src = rest;
                outs.push(BandOut {
                    nodes: a,
                    offsets: o,
                    shares: sh,
                    owners: ow,
                    share_nodes: sn,
                    src: sr,
                    first_share,
                });
                first_share += m as u32;
            }
        }
        // 4. In parallel over bands: the band's nodes, offsets and shares (fraction, rigid velocity at the node,
        //    owner, node, index of the cell in its body's list for the in-place update), row by row; ΩΛ's
        //    fully covered nodes of the band.
        plans
            .par_iter_mut()
            .zip(outs.par_iter_mut())
            .enumerate()
            .for_each(|(b, (plan, out))| plan.write(cells, bodies, b * band_rows, nx, lambda, out));
        drop(outs);
        for plan in plans.iter() {
            full_now.extend_from_slice(&plan.full);
        }
        scratch.layout_bodies = Some(bodies.len());
        scratch.rebuilt += 1;
        cov
    }

    /// The shares of a coverage whose lists the last call built, when every body covers the same nodes as then
    /// (the common case: grains move a thousandth of a spacing per step, and a body's set of cells changes only
    /// when its outline crosses a lattice vertex): each share's fraction and rigid velocity rewritten in place,
    /// from the cell it was built from, in parallel over chunks of shares (only the velocity where no body
    /// recomputed its cells since the last call, `fractions_kept`: between re-mappings under a remap
    /// tolerance, or with bodies at rest); ΩΛ's fully covered nodes appended to `full_now` (`lambda`). The lists
    /// themselves (nodes, offsets, owners, share nodes) are what [`FluidLattice::build_shares`] would build from
    /// the same cells, so the result is bitwise the same.
    fn update_shares_in_place(
        scratch: &mut CoverScratch,
        cov: &mut Coverage<T>,
        bodies: &[CoupledBody<f64>],
        fractions_kept: bool,
        lambda: bool,
        full_now: &mut Vec<u32>,
    ) {
        const CHUNK: usize = 4096;
        let cells = &scratch.bodies;
        if fractions_kept {
            // No body recomputed its cells since the last call wrote these shares: only the rigid velocities
            // change (each body's fractions, read back from its list, would be the same values).
            cov.shares
                .par_chunks_mut(CHUNK)
                .zip(cov.owners.par_chunks(CHUNK))
                .zip(cov.share_nodes.par_chunks(CHUNK))
                .for_each(|((shares, owners), nodes)| {
                    for ((share, &owner), &p) in shares.iter_mut().zip(owners).zip(nodes) {
                        let v = rigid_velocity(&bodies[owner as usize], Vector::from(p));
                        share.velocity = [T::lit(v[0]), T::lit(v[1])];
                    }
                });
        } else {
            Self::rewrite_shares(cov, cells, &scratch.src, bodies);
            cov.fractions = next_list_id();
        }
        if lambda {
            let cov = &*cov;
            full_now.par_extend(
                (0..cov.nodes.len())
                    .into_par_iter()
                    .filter(|&k| node_is_full(cov, k))
                    .map(|k| cov.nodes[k]),
            );
        }
        scratch.in_place += 1;
    }

    /// Each share's fraction (from the cell it was built from) and rigid velocity rewritten in place.
    fn rewrite_shares(
        cov: &mut Coverage<T>,
        cells: &[BodyCells],
        src: &[u32],
        bodies: &[CoupledBody<f64>],
    ) {
        const CHUNK: usize = 4096;
        cov.shares
            .par_chunks_mut(CHUNK)
            .zip(cov.owners.par_chunks(CHUNK))
            .zip(cov.share_nodes.par_chunks(CHUNK))
            .zip(src.par_chunks(CHUNK))
            .for_each(|(((shares, owners), nodes), src)| {
                for (((share, &owner), &p), &i) in shares.iter_mut().zip(owners).zip(nodes).zip(src)
                {
                    let frac = cells[owner as usize].fractions[i as usize].1;
                    let v = rigid_velocity(&bodies[owner as usize], Vector::from(p));
                    *share = SolidShare {
                        fraction: T::lit(frac),
                        velocity: [T::lit(v[0]), T::lit(v[1])],
                        wall_gradient: [T::zero(); 2],
                    };
                }
            });
    }

    /// Cover the lattice with one solid (body 0) given cell by cell: the fraction `fraction(x, y)` of each cell it
    /// covers and its velocity `velocity(x, y)` there (lattice units), for solids that are not discs or ellipses
    /// (a slab, a half-space). Replaces any previous coverage; cells with a zero fraction and nodes on Zou–He
    /// sides are not covered (as in [`FluidLattice::cover_with_bodies`]). Its force and torque are body 0's in
    /// [`FluidLattice::solid_forces_and_torques`]. Refuses a fraction outside [0, 1] or a velocity that is not
    /// finite or not below the lattice speed, naming the cell.
    pub fn cover_with_field(
        &mut self,
        fraction: impl Fn(usize, usize) -> f64,
        velocity: impl Fn(usize, usize) -> [f64; 2],
        weighting: Weighting,
    ) -> Result<()> {
        let s = self.shape;
        let mut cov = Coverage {
            layout: next_list_id(),
            fractions: next_list_id(),
            nodes: Vec::new(),
            offsets: vec![0],
            shares: Vec::new(),
            owners: Vec::new(),
            share_nodes: Vec::new(),
            normals: Vec::new(),
            exchange: Vec::new(),
            weighting,
            links: Vec::new(),
        };
        for y in 0..s.ny {
            for x in 0..s.nx {
                let e = fraction(x, y);
                if !(0.0..=1.0).contains(&e) {
                    return Err(LbdemError::field(
                        "solid fraction",
                        format!("{e} at node ({x}, {y})"),
                        "must lie in [0, 1]",
                        "give the fraction of the cell the solid covers",
                    ));
                }
                let v = velocity(x, y);
                if !(v[0].is_finite() && v[1].is_finite() && v[0].abs() < 1.0 && v[1].abs() < 1.0) {
                    return Err(LbdemError::field(
                        "solid velocity",
                        format!("{v:?} at node ({x}, {y})"),
                        "must be finite and below the lattice speed 1",
                        "convert the velocity to lattice units (u dt/h)",
                    ));
                }
                if e == 0.0 || on_zou_he_side(&s, &self.bc, x, y) {
                    continue;
                }
                cov.nodes.push(s.index(x, y) as u32);
                cov.shares.push(SolidShare {
                    fraction: T::lit(e),
                    velocity: [T::lit(v[0]), T::lit(v[1])],
                    wall_gradient: [T::zero(); 2],
                });
                cov.offsets.push(cov.shares.len() as u32);
                cov.owners.push(0);
                cov.share_nodes.push([x as f64, y as f64]);
                // A solid given cell by cell has no surface direction: no wall-pressure force (ΩΛ).
                cov.normals.push([T::zero(); 2]);
            }
        }
        cov.exchange = vec![[T::zero(); 2]; cov.shares.len()];
        self.cover_scratch = CoverScratch::default();
        compute_links(
            &mut cov,
            &s,
            &self.bc,
            &self.flags,
            &mut self.cover_scratch.links,
            self.solid_operator,
        );
        self.coverage = Some(cov);
        Ok(())
    }

    /// Give the solid of a coverage set cell by cell ([`FluidLattice::cover_with_field`]) its wall direction:
    /// `normal(x, y)` is the unit outward normal of the solid's surface at covered node (x, y), or zero where it
    /// has none. ΩΛ's wall-pressure force ([`wall_gradients`]) acts along the surface, so a solid without a
    /// direction gets none (bodies get theirs from their shape in [`FluidLattice::cover_with_bodies`]).
    /// Refused, with the lattice unchanged, without a coverage, or for a normal that is not finite or neither
    /// of unit length (to 1e-9) nor zero, naming the node.
    pub fn set_field_normals(&mut self, normal: impl Fn(usize, usize) -> [f64; 2]) -> Result<()> {
        let s = self.shape;
        let Some(cov) = self.coverage.as_mut() else {
            return Err(LbdemError::field(
                "solid normals",
                "no coverage",
                "need a solid covering the lattice",
                "call cover_with_field first",
            ));
        };
        let mut normals = Vec::with_capacity(cov.shares.len());
        for (k, &node) in cov.nodes.iter().enumerate() {
            let (x, y) = s.coords(node as usize);
            let n = normal(x, y);
            let len = n[0].hypot(n[1]);
            if !(len.is_finite() && (len == 0.0 || (len - 1.0).abs() <= 1e-9)) {
                return Err(LbdemError::field(
                    "solid normal",
                    format!("{n:?} at node ({x}, {y})"),
                    "must be finite and of unit length, or zero for no direction",
                    "normalise the surface normal",
                ));
            }
            let count = (cov.offsets[k + 1] - cov.offsets[k]) as usize;
            normals.extend(std::iter::repeat_n([T::lit(n[0]), T::lit(n[1])], count));
        }
        cov.normals = normals;
        Ok(())
    }

    /// Set the velocity profile of a [`SideCondition::VelocityProfile`] side: one velocity (lattice units) per
    /// node along it, in order of x (south, north) or y (west, east). Refused, with the lattice unchanged, for a
    /// side that is not a profile side, a profile of the wrong length, or a velocity that is not finite or not
    /// below the lattice speed.
    pub fn set_side_profile(&mut self, side: Side, profile: &[[f64; 2]]) -> Result<()> {
        let k = match side {
            Side::West => 0,
            Side::East => 1,
            Side::South => 2,
            Side::North => 3,
        };
        let field = format!("boundary.{side:?}.profile").to_lowercase();
        if self.bc.side(side) != SideCondition::VelocityProfile {
            return Err(LbdemError::field(
                &field,
                format!("{side:?}"),
                "is not a velocity-profile side",
                "declare the side as SideCondition::VelocityProfile when building the lattice",
            ));
        }
        let values: Vec<[T; 2]> = profile.iter().map(|v| v.map(T::lit)).collect();
        let mut candidate = self.profiles.clone();
        candidate[k] = values;
        side_profiles(&candidate)
            .validate(&self.bc, self.shape.nx, self.shape.ny)
            .map_err(|e| {
                let n = match side {
                    Side::West | Side::East => self.shape.ny,
                    Side::South | Side::North => self.shape.nx,
                };
                LbdemError::field(
                    &field,
                    format!("{} values", profile.len()),
                    &format!("is refused ({e:?})"),
                    &format!(
                        "give {n} finite velocities below the lattice speed, one per node along the side"
                    ),
                )
            })?;
        self.profiles = candidate;
        Ok(())
    }

    /// Change the prescribed density of a Zou–He pressure side (e.g. the boundary pressure drop of the fracture
    /// test at t = 0). The side must already be a pressure side: its node classification does not change.
    pub fn set_side_density(&mut self, side: Side, density: T) -> Result<()> {
        let slot = match side {
            Side::West => &mut self.bc.west,
            Side::East => &mut self.bc.east,
            Side::South => &mut self.bc.south,
            Side::North => &mut self.bc.north,
        };
        match slot {
            SideCondition::Pressure { density: d } => {
                *d = density;
                Ok(())
            }
            _ => Err(LbdemError::field(
                "boundary side",
                format!("{side:?}"),
                "is not a pressure side, so its density cannot be set",
                "declare the side as a pressure boundary when building the lattice",
            )),
        }
    }

    /// The mean over the nodes of pressure side `side` of the populations its Zou–He closure keeps, tangential
    /// once and outgoing twice ([`zou_he_known_sum`]: ρ(1 + u_n) at each node), as the next step gathers them.
    /// The corner nodes are left out where the neighbouring side is not periodic. `None` without such a node.
    pub fn side_known_sum(&self, side: Side) -> Option<f64> {
        let (nx, ny) = (self.shape.nx, self.shape.ny);
        let periodic = self.bc.periodic_axes();
        let along = |n: usize, periodic: bool| {
            if periodic {
                0..n
            } else {
                1..n.saturating_sub(1)
            }
        };
        // Node k along the side (no list: this runs at every step of a radiating side).
        let range = match side {
            Side::North | Side::South => along(nx, periodic[0]),
            Side::East | Side::West => along(ny, periodic[1]),
        };
        let node = |k: usize| match side {
            Side::North => (k, ny - 1),
            Side::South => (k, 0),
            Side::East => (nx - 1, k),
            Side::West => (0, k),
        };
        let profiles = side_profiles(&self.profiles);
        let (mut sum, mut count) = (0.0, 0usize);
        for (x, y) in range.map(node) {
            if self.flags[self.shape.index(x, y)] == SOLID {
                continue;
            }
            let f = gather_node_in(
                &self.shape,
                self.current(),
                self.layout,
                &self.bc,
                &profiles,
                &self.flags,
                x,
                y,
            );
            sum += zou_he_known_sum(&f, side).to_f64_exact();
            count += 1;
        }
        (count > 0).then(|| sum / count as f64)
    }

    /// Hold the pressure side `side` for the next step as a radiating drained side
    /// ([`lbdem_kernels::fluid::boundary::radiating_density`]): its density solved with the Zou–He relation of
    /// its own nodes ([`FluidLattice::side_known_sum`]) and the running mean in `state`, so that sound leaves
    /// through it while slow flow still sees `state.density`. Call before every [`FluidLattice::step`]. A side
    /// that is not a pressure side is refused (as by [`FluidLattice::set_side_density`]).
    pub fn radiate(&mut self, side: Side, state: &mut RadiatingSide) -> Result<()> {
        if !matches!(self.bc.side(side), SideCondition::Pressure { .. }) {
            return self.set_side_density(side, T::one());
        }
        if !(state.density.is_finite() && state.density > 0.0 && (0.0..=1.0).contains(&state.rate))
        {
            return Err(LbdemError::field(
                "radiating side",
                format!("density {:e}, rate {:e}", state.density, state.rate),
                "needs a finite positive density and a running-mean rate in [0, 1]",
                "rate = 1/(steps the running mean spans), e.g. ten sound-crossing times",
            ));
        }
        let Some(known) = self.side_known_sum(side) else {
            return Ok(());
        };
        let rho = radiating_density(state.density, known, &mut state.mean, state.rate);
        if !(rho.is_finite() && rho > 0.0) {
            return Err(LbdemError::field(
                "boundary side",
                format!("{side:?}"),
                &format!("a radiating side came to density {rho:e} (known sum {known:e})"),
                "the flow through the side is not a small acoustic perturbation: lower the load or the drive",
            ));
        }
        self.set_side_density(side, T::lit(rho))
    }

    /// Let [`FluidLattice::cover_with_bodies`] keep every body's cells (nodes and fractions) while no point of
    /// any body has moved farther than `tolerance` lattice spacings from where it was when they were last mapped,
    /// and re-map all bodies at the call where one has; the rigid velocities at the covered nodes follow the
    /// bodies at every call, and the momentum handed to them stays exact. So the solid the fluid sees lags the
    /// bodies by at most `tolerance` (an approximation, bounded; the default 0 re-maps at every call, bitwise the
    /// result without this option). Between re-mappings no body changes its nodes, so a call only rewrites the
    /// rigid velocities: grains that vibrate by a thousandth of a spacing per step no longer rebuild the
    /// coverage's lists at every step (README, *Benchmarks*, for the speed and the error measured in the
    /// fracture test). Refuses a tolerance that is negative, not finite or above [`MAX_REMAP_TOLERANCE`].
    pub fn set_remap_tolerance(&mut self, tolerance: f64) -> Result<()> {
        check_remap_tolerance(tolerance)?;
        self.remap_tolerance = tolerance;
        Ok(())
    }

    /// See [`FluidLattice::set_remap_tolerance`] (lattice spacings; 0 by default).
    pub fn remap_tolerance(&self) -> f64 {
        self.remap_tolerance
    }

    /// The geometry each body's cells were last mapped for (lattice units; velocities zero), when a remap
    /// tolerance is set: what a checkpoint keeps so that a resumed run maps the same cells.
    fn mapped_geometry(&self) -> Vec<CoupledBody<f64>> {
        if self.remap_tolerance == 0.0 {
            return Vec::new();
        }
        let zero = lbdem_kernels::math::Vector::zeros();
        self.cover_scratch
            .bodies
            .iter()
            .map_while(|c| c.anchor)
            .map(|a| CoupledBody {
                velocity: zero,
                spin: 0.0,
                ..a
            })
            .collect()
    }

    /// Restore [`FluidLattice::mapped_geometry`] from a checkpoint: the next call of
    /// [`FluidLattice::cover_with_bodies`] maps these geometries where the bodies are still within the tolerance
    /// of them, as the saved run would have.
    fn restore_mapped_geometry(&mut self, mapped: Vec<CoupledBody<f64>>) {
        self.cover_scratch.bodies = mapped
            .into_iter()
            .map(|a| BodyCells {
                anchor: Some(a),
                ..BodyCells::default()
            })
            .collect();
    }

    /// Drop the coverage and the buffers kept between calls of [`FluidLattice::cover_with_bodies`]: the next
    /// call re-maps every body from scratch (same result, bitwise, without a remap tolerance; with one, the bodies
    /// are mapped where they are at that call; for tests and to release memory).
    pub fn clear_coverage(&mut self) {
        self.coverage = None;
        self.cover_scratch = CoverScratch::default();
    }

    /// Whether node (x, y) lies on a Zou–He (pressure or velocity) side.
    pub fn on_zou_he_side(&self, x: usize, y: usize) -> bool {
        on_zou_he_side(&self.shape, &self.bc, x, y)
    }

    /// Choose the solid collision operator of covered nodes (default: the dissertation's Ω₁). See
    /// [`SolidOperator`]: Ω₁ lets mass accumulate inside fully covered regions of open systems; prefer Ω₂
    /// (`Superposition`) for long runs with pressure boundaries.
    pub fn set_solid_operator(&mut self, op: SolidOperator) {
        self.solid_operator = op;
        // ΩΛ's open-link masks are only computed while ΩΛ is the operator.
        self.refresh_links();
        self.refresh_normals();
    }

    /// Set ΩΛ's constants ([`LambdaTerms::WALL_PRESSURE`], the default, or [`LambdaTerms::FRICTION_ONLY`]).
    /// Refused for a friction or wall-pressure constant that is negative or not finite. Switching the
    /// wall-pressure form on computes the wall normals of a coverage made by [`FluidLattice::cover_with_bodies`]
    /// from that call's bodies; a body coverage read from a checkpoint saved with the form off has none until
    /// the next `cover_with_bodies` call, and gets no wall force until then.
    pub fn set_lambda_terms(&mut self, terms: LambdaTerms) -> Result<()> {
        for (field, v) in [
            ("lambda friction", terms.friction),
            ("lambda wall pressure", terms.pressure),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(LbdemError::field(
                    field,
                    v,
                    "must be finite and not negative",
                    "use LambdaTerms::FRICTION_ONLY or LambdaTerms::WALL_PRESSURE",
                ));
            }
        }
        self.lambda_terms = terms;
        self.refresh_normals();
        Ok(())
    }

    /// ΩΛ's constants.
    pub fn lambda_terms(&self) -> LambdaTerms {
        self.lambda_terms
    }

    /// Whether ΩΛ's wall-pressure form is on (ΩΛ the operator, α ≠ 0): the only reader of the wall normals.
    fn wall_form_active(&self) -> bool {
        self.solid_operator == SolidOperator::LambdaConsistent && self.lambda_terms.pressure != 0.0
    }

    /// The wall normals of a coverage made by [`FluidLattice::cover_with_bodies`] while the wall-pressure form
    /// was off, computed from that call's bodies once the form is on.
    fn refresh_normals(&mut self) {
        if !self.wall_form_active() {
            return;
        }
        let bodies = &self.cover_scratch.last_bodies;
        if let Some(cov) = self.coverage.as_mut() {
            let owned = cov.owners.iter().all(|&o| (o as usize) < bodies.len());
            if cov.normals.len() != cov.shares.len() && owned && !bodies.is_empty() {
                Self::write_normals(cov, bodies);
            }
        }
    }

    /// The solid collision operator of covered nodes.
    pub fn solid_operator(&self) -> SolidOperator {
        self.solid_operator
    }

    /// Solid fraction ε of every node (row-major) from the current coverage: the fractions of the bodies covering
    /// a node added and capped at 1, as the collision uses them (0 for uncovered nodes, including Zou–He nodes).
    pub fn solid_fraction_map(&self) -> Vec<f64> {
        let mut eps = vec![0.0; self.shape.nodes()];
        if let Some(c) = &self.coverage {
            for (k, &node) in c.nodes.iter().enumerate() {
                let shares = &c.shares[c.offsets[k] as usize..c.offsets[k + 1] as usize];
                let sum: f64 = shares.iter().map(|s| s.fraction.to_f64_exact()).sum();
                eps[node as usize] = sum.min(1.0);
            }
        }
        eps
    }

    /// The shares of node (x, y) from the current coverage, in the order the collision takes them: the owning
    /// body's index, its cell fraction and its rigid velocity at the node (lattice units), with the node's ΩΛ
    /// open-link mask (bits 1–8; [`lbdem_kernels::fluid::collide::ALL_LINKS_OPEN`] under the other operators).
    /// Empty for an uncovered node. For diagnostics (`examples/omega_probe.rs`); read-only.
    pub fn node_shares(&self, x: usize, y: usize) -> (Vec<(u32, f64, [f64; 2])>, u16) {
        let Some(c) = &self.coverage else {
            return (Vec::new(), 0);
        };
        let node = (y * self.shape.nx + x) as u32;
        let Some(k) = c.nodes.iter().position(|&n| n == node) else {
            return (Vec::new(), 0);
        };
        let (a, b) = (c.offsets[k] as usize, c.offsets[k + 1] as usize);
        let shares = (a..b)
            .map(|j| {
                let s = &c.shares[j];
                (
                    c.owners[j],
                    s.fraction.to_f64_exact(),
                    [s.velocity[0].to_f64_exact(), s.velocity[1].to_f64_exact()],
                )
            })
            .collect();
        (shares, c.links.get(k).copied().unwrap_or(0))
    }

    /// Number of nodes covered (partly or wholly) by solids.
    pub fn covered_nodes(&self) -> usize {
        self.coverage.as_ref().map_or(0, |c| c.nodes.len())
    }

    /// Force on each of `count` solids from the last step (lattice units), summed in a fixed order.
    pub fn solid_forces(&self, count: usize) -> Vec<Vector<f64>> {
        self.solid_forces_and_torques(&vec![Vector::zeros(); count])
            .0
    }

    /// Force and torque (about `centers[p]`, lattice units) on each solid from the last step (eq. 4.7–4.8),
    /// reduced by the coupling kernel in the fixed order of the share list.
    pub fn solid_forces_and_torques(&self, centers: &[Point<f64>]) -> (Vec<Vector<f64>>, Vec<f64>) {
        let mut forces = vec![Vector::zeros(); centers.len()];
        let mut torques = vec![0.0; centers.len()];
        if let Some(c) = &self.coverage {
            // An f64 lattice's exchange as it is; an f32 one's widened (exactly) into a copy.
            let exchange: Cow<'_, [[f64; 2]]> =
                match (&c.exchange as &dyn std::any::Any).downcast_ref::<Vec<[f64; 2]>>() {
                    Some(e) => Cow::Borrowed(e),
                    None => Cow::Owned(
                        c.exchange
                            .iter()
                            .map(|e| [e[0].to_f64_exact(), e[1].to_f64_exact()])
                            .collect(),
                    ),
                };
            let periodic = self.bc.periodic_axes();
            let periods = [
                periodic[0].then_some(self.shape.nx as f64),
                periodic[1].then_some(self.shape.ny as f64),
            ];
            reduce_exchange(
                &c.share_nodes,
                &c.owners,
                &exchange,
                centers,
                periods,
                &mut forces,
                &mut torques,
            );
        }
        (forces, torques)
    }

    /// Advance one lattice step, in parallel over row bands on the current rayon pool.
    pub fn step(&mut self) {
        self.update_wall_gradients();
        match self.streaming {
            Streaming::Aa => self.step_in_place(),
            Streaming::TwoLattice => self.step_two_lattice(),
        }
        self.steps += 1;
    }

    /// ΩΛ's wall gradients of the covered nodes ([`wall_gradients`]) from the populations the step about to run
    /// gathers: first the gathered densities of the rows from one above the first covered node's row to one
    /// below the last's (every row when that range wraps a periodic axis), in parallel over bands of rows
    /// ([`gathered_densities`]), then the gradients in parallel over chunks of covered nodes, reading those
    /// densities. Each value depends only on the buffer, so nothing depends on the bands, chunks or thread
    /// count. Nothing for the other operators, which do not read them.
    fn update_wall_gradients(&mut self) {
        const CHUNK: usize = 1024;
        if self.solid_operator != SolidOperator::LambdaConsistent
            || self.lambda_terms.pressure == 0.0
        {
            return;
        }
        let range = self.current_range();
        let Some(cov) = self.coverage.as_mut() else {
            return;
        };
        let domain = Domain {
            shape: self.shape,
            bc: self.bc,
            profiles: side_profiles(&self.profiles),
            flags: &self.flags,
        };
        let (src, layout) = (&self.buffers[range], self.layout);
        if cov.normals.len() != cov.shares.len() {
            // No wall directions (a coverage read from a checkpoint made with the form off, until the next
            // re-mapping): no wall force.
            cov.shares
                .par_iter_mut()
                .for_each(|s| s.wall_gradient = [T::zero(); 2]);
            return;
        }
        let (Some(&first), Some(&last)) = (cov.nodes.first(), cov.nodes.last()) else {
            return;
        };
        let (nx, ny) = (self.shape.nx, self.shape.ny);
        let (top, bottom) = (first as usize / nx, last as usize / nx);
        // Rows whose densities a gradient may read: the covered rows and one on each side (a neighbour across
        // a periodic side wraps to the far row: then all rows).
        let (y0, y1) = if (top == 0 || bottom + 1 == ny) && self.bc.periodic_axes()[1] {
            (0, ny)
        } else {
            (top.saturating_sub(1), (bottom + 2).min(ny))
        };
        self.densities.resize(self.shape.nodes(), T::zero());
        let (shape, special) = (self.shape, &self.special);
        let band = self.band_rows.max(1) * nx;
        self.densities[y0 * nx..y1 * nx]
            .par_chunks_mut(band)
            .enumerate()
            .for_each(|(b, out)| {
                let r0 = y0 + b * self.band_rows.max(1);
                let r1 = r0 + out.len() / nx;
                gathered_densities(
                    &domain,
                    src,
                    layout,
                    r0,
                    r1,
                    nodes_in_rows(&shape, special, r0, r1),
                    out,
                );
            });
        let densities = &self.densities;
        let (nodes, offsets, links, normals) = (&cov.nodes, &cov.offsets, &cov.links, &cov.normals);
        let mut work = Vec::with_capacity(nodes.len().div_ceil(CHUNK));
        let mut rest = &mut cov.shares[..];
        for k0 in (0..nodes.len()).step_by(CHUNK) {
            let k1 = (k0 + CHUNK).min(nodes.len());
            let len = (offsets[k1] - offsets[k0]) as usize;
            let (mine, more) = std::mem::take(&mut rest).split_at_mut(len);
            rest = more;
            work.push((k0, k1, mine));
        }
        work.into_par_iter().for_each(|(k0, k1, shares)| {
            let (a, b) = (offsets[k0] as usize, offsets[k1] as usize);
            wall_gradients(
                &domain,
                &nodes[k0..k1],
                &offsets[k0..=k1],
                &links[k0..k1],
                &normals[a..b],
                shares,
                |n| densities[n],
            );
        });
    }

    /// One step of the in-place (AA) scheme, in three phases:
    /// 1. read only: the new values of the special nodes (in parallel), then of the covered ones among them with
    ///    their momentum exchange (found by looking each special node up in the covered list), gathered from the
    ///    buffer as it is;
    /// 2. in parallel over bands of rows, in place, row by row: the row's covered nodes that are not special
    ///    gathered from the row and collided with the partially-saturated operator, the branch-free bulk pass
    ///    over every node of the row, then the covered nodes' values stored over what the bulk pass wrote for
    ///    them (a node that is not special reads and writes only places of its own pass row; row by row keeps
    ///    the held values in cache);
    /// 3. in parallel over the nine planes: the values of phase 1 stored at their places.
    fn step_in_place(&mut self) {
        let shape = self.shape;
        let nx = shape.nx;
        let periodic = self.bc.periodic_axes();
        let (params, simd, band_rows) = (self.params, self.simd, self.band_rows);
        let collision = self.collision;
        let layout = self.layout;
        let after = layout.next();
        let kind = AaStep::from(layout);
        let mut special_vals = std::mem::take(&mut self.aa_special);
        let mut covered_vals = std::mem::take(&mut self.aa_covered);
        let range = self.current_range();
        let domain = Domain {
            shape,
            bc: self.bc,
            profiles: side_profiles(&self.profiles),
            flags: &self.flags,
        };
        let mask = &self.special_mask;
        // The identities of the coverage's lists and of the special list, which the covered special nodes
        // found at an earlier step are kept for (a coverage read from a checkpoint gets its identity here).
        let special_key = self.coverage.as_mut().map(|c| {
            if c.layout == 0 {
                c.layout = next_list_id();
            }
            if c.fractions == 0 {
                c.fractions = next_list_id();
            }
            (c.layout, self.special_id)
        });
        let plan_key: Option<PlanKey> = self.coverage.as_ref().map(|c| {
            (
                c.layout,
                c.fractions,
                self.special_id,
                self.solid_operator,
                band_rows,
            )
        });
        let psm = self.coverage.as_ref().map(|c| PsmParams {
            tau: params.tau,
            weighting: c.weighting,
            force: params.force,
            solid: self.solid_operator,
            collision: self.collision,
            lambda: self.lambda_terms,
        });
        type Lists<'a, T> = (
            &'a [u32],
            &'a [u32],
            &'a [SolidShare<T>],
            &'a [OpenLinks],
            &'a mut [[T; 2]],
        );
        let (covered, offsets, shares, links, exchange): Lists<'_, T> = match &mut self.coverage {
            Some(c) => (
                &c.nodes[..],
                &c.offsets[..],
                &c.shares[..],
                &c.links[..],
                &mut c.exchange[..],
            ),
            None => (&[], &[0], &[], &[], &mut [][..]),
        };
        // The covered nodes that are special, as indices into the covered list, increasing: each special node
        // looked up in the covered list (both are in increasing node order), so the cost is that of the special
        // nodes, not of a scan of every covered node; kept from the last step while both lists are the same
        // lists (1–2 % of the full-size fracture step, serial, when looked up at every step).
        let mut covered_special = std::mem::take(&mut self.aa_covered_special);
        if special_key.is_none() || special_key != self.aa_covered_special_key {
            covered_special.clear();
            if !covered.is_empty() {
                covered_special.extend(
                    self.special
                        .iter()
                        .filter_map(|n| covered.binary_search(n).ok()),
                );
            }
            self.aa_covered_special_key = special_key;
            self.aa_covered_special_found += 1;
        }
        // Phase 1: the special nodes, then the covered ones among them with their exchange (a few per
        // thousand of the covered nodes: serial).
        {
            let buf = &self.buffers[range.clone()];
            special_vals.resize(self.special.len(), [T::zero(); Q]);
            self.special
                .par_chunks(SPECIAL_CHUNK)
                .zip(special_vals.par_chunks_mut(SPECIAL_CHUNK))
                .for_each(|(nodes, vals)| {
                    for (&n, v) in nodes.iter().zip(vals.iter_mut()) {
                        *v = special_node_value(
                            &domain, buf, layout, &params, &collision, n as usize,
                        );
                    }
                });
            covered_vals.clear();
            if let Some(psm) = &psm {
                let exchange = &mut *exchange;
                with_simd(
                    simd,
                    #[inline(always)]
                    || {
                        for &k in covered_special.iter() {
                            let (a, b) = (offsets[k] as usize, offsets[k + 1] as usize);
                            covered_vals.push(covered_node_value(
                                &domain,
                                buf,
                                layout,
                                psm,
                                covered[k] as usize,
                                &shares[a..b],
                                links[k],
                                &mut exchange[a..b],
                            ));
                        }
                    },
                );
            }
        }
        // The covered nodes and their exchange entries, split along the bands of rows.
        let bands = shape.ny.div_ceil(band_rows);
        let mut plans = std::mem::take(&mut self.covered_plans);
        plans.resize_with(bands, CoveredPlan::default);
        let mut work: Vec<CoveredBand<'_, T>> = Vec::with_capacity(bands);
        {
            let mut ex_rest = exchange;
            let mut lo = 0;
            for b in 0..bands {
                let end = (((b + 1) * band_rows).min(shape.ny) * nx) as u32;
                let hi = lo + covered[lo..].partition_point(|&n| n < end);
                let len = (offsets[hi] - offsets[lo]) as usize;
                let (ex, rest) = std::mem::take(&mut ex_rest).split_at_mut(len);
                ex_rest = rest;
                work.push((lo, hi, ex));
                lo = hi;
            }
        }
        // Phase 2: row y of the pass needs row `plane_row(kind, p, y)` of each plane p; every plane row is
        // handed out exactly once.
        {
            let buf = &mut self.buffers[range.clone()];
            let mut plane_rows: Vec<Vec<Option<&mut [T]>>> = planes_mut(&shape, buf)
                .into_iter()
                .map(|plane| plane.chunks_mut(nx).map(Some).collect())
                .collect();
            let mut rows: Vec<[&mut [T]; Q]> = (0..shape.ny)
                .map(|y| {
                    std::array::from_fn(|p| {
                        plane_rows[p][plane_row(kind, p, y, shape.ny)]
                            .take()
                            .unwrap_or_default()
                    })
                })
                .collect();
            let made = rows
                .par_chunks_mut(band_rows)
                .zip(work.par_iter_mut())
                .zip(plans.par_iter_mut())
                .enumerate()
                .map(|(b, ((band, (lo, hi, ex)), plan))| {
                    let y0 = b * band_rows;
                    let own = |k: usize| !mask[covered[k] as usize];
                    let (lo, hi) = (*lo, *hi);
                    let first = offsets[lo] as usize;
                    // The band's rows planned anew when what the plans depend on changed (at every re-mapping
                    // that moves a fraction; between re-mappings under a remap tolerance they are reused).
                    let fresh = psm.is_some() && plan.key != plan_key;
                    if let (true, Some(psm)) = (fresh, &psm) {
                        plan.counts.clear();
                        plan.nodes.clear();
                        let mut k0 = lo;
                        for r in 0..band.len() {
                            let row_end = ((y0 + r + 1) * nx) as u32;
                            let k1 = k0 + covered[k0..hi].partition_point(|&n| n < row_end);
                            let at = plan.nodes.len();
                            plan.nodes.resize(at + (k1 - k0), 0);
                            let counts = plan_covered_row(
                                psm,
                                |j| own(k0 + j),
                                &offsets[k0..=k1],
                                shares,
                                &mut plan.nodes[at..],
                            );
                            plan.nodes
                                .truncate(at + counts.iter().map(|&c| c as usize).sum::<usize>());
                            plan.counts.push(counts);
                            k0 = k1;
                        }
                        plan.key = plan_key;
                    }
                    // Row by row: the bulk pass over the row leaving its planned covered nodes as they were
                    // (`keep`), then those nodes gathered from the row the pass has just brought into cache,
                    // collided with the partially-saturated operator and stored in place (each such node
                    // reads and writes only places of its own).
                    let mut keep = vec![false; nx];
                    // Columns of the row's covered nodes.
                    let mut columns: Vec<u32> = Vec::with_capacity(nx);
                    let mut k0 = lo;
                    let mut at = 0;
                    for r in 0..band.len() {
                        let y = y0 + r;
                        let row_end = ((y + 1) * nx) as u32;
                        let mut k1 = k0;
                        while k1 < hi && covered[k1] < row_end {
                            k1 += 1;
                        }
                        let row = &mut band[r..r + 1];
                        match &psm {
                            Some(psm) if k1 > k0 => {
                                let counts = plan.counts[r];
                                let len: usize = counts.iter().map(|&c| c as usize).sum();
                                let planned = &plan.nodes[at..at + len];
                                at += len;
                                columns.clear();
                                columns
                                    .extend(covered[k0..k1].iter().map(|&n| n - (y * nx) as u32));
                                let columns = &columns[..];
                                for &j in planned {
                                    keep[columns[j as usize] as usize] = true;
                                }
                                aa_bulk_keeping_exec(simd, row, &keep, kind, &params, &collision);
                                let ex = &mut ex[offsets[k0] as usize - first..];
                                with_simd(
                                    simd,
                                    #[inline(always)]
                                    || {
                                        collide_planned_row(
                                            psm,
                                            &mut row[0],
                                            kind,
                                            columns,
                                            planned,
                                            counts,
                                            &offsets[k0..=k1],
                                            shares,
                                            &links[k0..k1],
                                            ex,
                                        )
                                    },
                                );
                                for &j in planned {
                                    keep[columns[j as usize] as usize] = false;
                                }
                            }
                            _ => aa_bulk_exec(simd, row, kind, &params, &collision),
                        }
                        k0 = k1;
                    }
                    u64::from(fresh)
                })
                .sum::<u64>();
            self.covered_plans_made += made;
        }
        drop(work);
        // Phase 3: special nodes, then the covered ones among them (whose values win, as in the two-lattice
        // scheme).
        {
            let flags = &self.flags[..];
            let buf = &mut self.buffers[range];
            let (special, sv, cv) = (&self.special[..], &special_vals, &covered_vals);
            let cs = &covered_special;
            planes_mut(&shape, buf)
                .into_par_iter()
                .enumerate()
                .for_each(|(p, plane)| {
                    let store = |plane: &mut [T], n: u32, f: &[T; Q]| {
                        let (fp, fo) = (f[p], f[OPPOSITE[p]]);
                        store_post_collision_in_plane(
                            &shape, periodic, flags, after, p, plane, n as usize, fp, fo,
                        );
                    };
                    for (&n, f) in special.iter().zip(sv) {
                        store(plane, n, f);
                    }
                    for (&k, f) in cs.iter().zip(cv) {
                        if let Some(f) = f {
                            store(plane, covered[k], f);
                        }
                    }
                });
        }
        self.layout = after;
        self.aa_special = special_vals;
        self.aa_covered = covered_vals;
        self.aa_covered_special = covered_special;
        self.covered_plans = plans;
    }

    /// One step of the two-lattice scheme: bulk pass, special nodes and covered nodes per band of rows, from the
    /// current buffer into the other.
    fn step_two_lattice(&mut self) {
        let shape = self.shape;
        let domain = Domain {
            shape,
            bc: self.bc,
            profiles: side_profiles(&self.profiles),
            flags: &self.flags,
        };
        let params = self.params;
        let collision = self.collision;
        let special = &self.special;
        let band_rows = self.band_rows;
        let simd = self.simd;
        let band_len = band_rows * shape.nx;
        let bands = shape.ny.div_ceil(band_rows);
        // Split the nine destination planes into row bands.
        let (src, dst) = {
            let len = shape.buffer_len();
            let (first, rest) = self.buffers.split_at_mut(self.second);
            let (first, second) = (&mut first[..len], &mut rest[..len]);
            if self.first_is_current {
                (&*first, second)
            } else {
                (&*second, first)
            }
        };
        let planes = planes_mut(&shape, dst);
        let mut chunked: Vec<std::slice::ChunksMut<'_, T>> =
            planes.into_iter().map(|p| p.chunks_mut(band_len)).collect();
        // Split the covered nodes and their exchange buffer along the same bands.
        type Band<'a, T> = (usize, [&'a mut [T]; Q], (usize, usize), &'a mut [[T; 2]]);
        let mut work: Vec<Band<'_, T>> = Vec::with_capacity(bands);
        type Static<'a, T> = (
            &'a [u32],
            &'a [u32],
            &'a [SolidShare<T>],
            Weighting,
            &'a [OpenLinks],
        );
        let (cov, mut exchange_rest): (Option<Static<'_, T>>, &mut [[T; 2]]) =
            match &mut self.coverage {
                Some(Coverage {
                    nodes,
                    offsets,
                    shares,
                    exchange,
                    weighting,
                    links,
                    ..
                }) => (
                    Some((
                        &nodes[..],
                        &offsets[..],
                        &shares[..],
                        *weighting,
                        &links[..],
                    )),
                    &mut exchange[..],
                ),
                None => (None, &mut []),
            };
        let (cov_nodes, offsets): (&[u32], &[u32]) = match cov {
            Some((n, o, _, _, _)) => (n, o),
            None => (&[], &[0]),
        };
        let mut lo = 0usize;
        for b in 0..bands {
            let y0 = b * band_rows;
            let y1 = (y0 + band_rows).min(shape.ny);
            let band: [&mut [T]; Q] =
                std::array::from_fn(|q| chunked[q].next().unwrap_or_default());
            let end = (y1 * shape.nx) as u32;
            let hi = lo + cov_nodes[lo..].partition_point(|&n| n < end);
            let len = (offsets[hi] - offsets[lo]) as usize;
            let (mine, rest) = std::mem::take(&mut exchange_rest).split_at_mut(len);
            exchange_rest = rest;
            work.push((y0, band, (lo, hi), mine));
            lo = hi;
        }
        let psm = cov.map(|c| PsmParams {
            tau: params.tau,
            weighting: c.3,
            force: params.force,
            solid: self.solid_operator,
            collision: self.collision,
            lambda: self.lambda_terms,
        });
        work.into_par_iter()
            .for_each(|(y0, mut band, (lo, hi), exchange)| {
                let y1 = (y0 + band_rows).min(shape.ny);
                let sp = nodes_in_rows(&shape, special, y0, y1);
                bulk_band_exec(simd, &shape, src, &mut band, y0, y1, &params, &collision);
                fix_special_nodes(&domain, src, &mut band, y0, &params, &collision, sp);
                if let (Some((nodes, offsets, shares, _, links)), Some(psm)) = (cov, psm.as_ref()) {
                    if hi > lo {
                        let covered = CoveredNodes {
                            nodes: &nodes[lo..hi],
                            offsets: &offsets[lo..=hi],
                            shares,
                            links: &links[lo..hi],
                        };
                        with_simd(
                            simd,
                            #[inline(always)]
                            || {
                                collide_covered_nodes(
                                    &domain, src, &mut band, y0, psm, covered, exchange,
                                )
                            },
                        );
                    }
                }
            });
        self.first_is_current = !self.first_is_current;
    }

    /// Density and velocity of every node (row-major), as the next collision sees them: (Σ f c + F/2)/ρ, and at
    /// nodes covered under ΩΛ ([`SolidOperator::LambdaConsistent`]) the velocity its collision uses, with the
    /// solids' friction (the velocity that makes measured fluxes independent of τ; the solid velocity at fully
    /// covered nodes).
    pub fn moments(&self) -> (Vec<T>, Vec<[T; 2]>) {
        let n = self.shape.nodes();
        let mut rho = vec![T::zero(); n];
        let mut u = vec![[T::zero(); 2]; n];
        gathered_moments_in(
            &self.shape,
            self.current(),
            self.layout,
            &self.bc,
            &side_profiles(&self.profiles),
            &self.flags,
            self.params.force,
            &mut rho,
            &mut u,
        );
        if let (Some(c), SolidOperator::LambdaConsistent) = (&self.coverage, self.solid_operator) {
            let psm = PsmParams {
                tau: self.params.tau,
                weighting: c.weighting,
                force: self.params.force,
                solid: self.solid_operator,
                collision: self.collision,
                lambda: self.lambda_terms,
            };
            for (k, &node) in c.nodes.iter().enumerate() {
                let node = node as usize;
                if self.flags[node] == SOLID {
                    continue;
                }
                let (x, y) = self.shape.coords(node);
                let f = gather_node_in(
                    &self.shape,
                    self.current(),
                    self.layout,
                    &self.bc,
                    &side_profiles(&self.profiles),
                    &self.flags,
                    x,
                    y,
                );
                let shares = &c.shares[c.offsets[k] as usize..c.offsets[k + 1] as usize];
                u[node] = psm_velocity(&f, &psm, shares).1;
            }
        }
        (rho, u)
    }

    /// Total fluid mass (sum of populations over fluid nodes), in f64.
    pub fn mass(&self) -> f64 {
        let mut m = 0.0;
        for q in 0..Q {
            let plane = &self.populations()
                [q * self.shape.stride..q * self.shape.stride + self.shape.nodes()];
            for (v, &flag) in plane.iter().zip(self.flags.iter()) {
                if flag != SOLID {
                    m += v.to_f64_exact();
                }
            }
        }
        m
    }

    /// Total fluid momentum Σ f_i c_i over fluid nodes (post-collision populations), in f64, lattice units.
    pub fn momentum(&self) -> [f64; 2] {
        let mut j = [0.0; 2];
        for (q, c) in lbdem_kernels::fluid::d2q9::VELOCITIES.iter().enumerate() {
            if c[0] == 0 && c[1] == 0 {
                continue;
            }
            let plane = &self.populations()
                [q * self.shape.stride..q * self.shape.stride + self.shape.nodes()];
            let mut sum = 0.0;
            for (v, &flag) in plane.iter().zip(self.flags.iter()) {
                if flag != SOLID {
                    sum += v.to_f64_exact();
                }
            }
            j[0] += c[0] as f64 * sum;
            j[1] += c[1] as f64 * sum;
        }
        j
    }

    /// First non-finite or out-of-band density, as (node, value), checking densities in [lo, hi].
    pub fn health_check(&self, lo: f64, hi: f64) -> Option<(usize, f64)> {
        let (rho, u) = self.moments();
        for (n, (r, v)) in rho.iter().zip(u.iter()).enumerate() {
            if self.flags[n] == SOLID {
                continue;
            }
            let r = r.to_f64_exact();
            if !r.is_finite() || r < lo || r > hi || !v[0].is_finite() || !v[1].is_finite() {
                return Some((n, r));
            }
        }
        None
    }
}

/// Elements between the two population buffers, so that each plane of the second buffer starts 160 bytes (mod
/// 4 KiB) after the same plane of the first. Planes within a buffer are 320 bytes apart (mod 4 KiB, see
/// [`LatticeShape`]); with both buffers at the same offset, the store to plane q of the destination would hit
/// the same 4 KiB offset as the load from plane q of the source a few elements before it ("4K aliasing": the
/// load waits for the store). 160 bytes is as far as possible from every multiple of 320 bytes mod 4 KiB.
/// Length of the buffer allocation for buffers of `len` elements and scheme `streaming`.
fn buffers_len<T>(len: usize, streaming: Streaming) -> usize {
    match streaming {
        Streaming::Aa => len,
        Streaming::TwoLattice => 2 * len + buffer_gap::<T>(len),
    }
}

fn buffer_gap<T>(len: usize) -> usize {
    let size = std::mem::size_of::<T>().max(1);
    let end = (len * size) % 4096;
    (160 + 4096 - end) % 4096 / size
}

/// The execution settings applied to a lattice (defined here, beside the lattice, so that `exec` does not
/// depend on `lattice`).
impl Exec {
    /// Use these settings on a lattice (instruction set and streaming scheme).
    pub fn apply<T: Real>(&self, lattice: &mut FluidLattice<T>) {
        // A level this CPU lacks cannot be constructed through `from_names`; fall back to the detected one.
        if lattice.set_simd(self.simd).is_err() {
            let _ = lattice.set_simd(SimdLevel::detect());
        }
        lattice.set_streaming(self.streaming);
    }
}

impl<T: Real> ExecTarget for FluidLattice<T> {
    fn take(&mut self, exec: &Exec) {
        exec.apply(self);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lbdem_kernels::coupling::body_cell_fraction;
    use lbdem_kernels::fluid::boundary::SideCondition;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Bit patterns of a coverage: nodes, offsets, (fraction, velocity) of each share, owners, share nodes.
    type Bits = (Vec<u32>, Vec<u32>, Vec<[u64; 3]>, Vec<u32>, Vec<[u64; 2]>);

    fn bits<T: Real>(c: &Coverage<T>) -> Bits {
        (
            c.nodes.clone(),
            c.offsets.clone(),
            c.shares
                .iter()
                .map(|s| {
                    [s.fraction, s.velocity[0], s.velocity[1]].map(|v| v.to_f64_exact().to_bits())
                })
                .collect(),
            c.owners.clone(),
            c.share_nodes.iter().map(|p| p.map(f64::to_bits)).collect(),
        )
    }

    /// The fractions of the cells of `body` (range `range` on the lattice): for an ellipse the whole-ellipse
    /// kernel over its unclamped block (fresh buffers), unless it refuses; otherwise the unprepared per-cell
    /// kernel.
    fn reference_fractions(
        body: &CoupledBody<f64>,
        range: [usize; 4],
    ) -> impl Fn(usize, usize) -> f64 {
        let mut grid = None;
        if let Some((g, n, a, b, angle)) = ellipse_block(body, range) {
            let (mut fr, mut bd) = (vec![0.0; n], vec![false; n]);
            let sc = angle.portable_sin_cos();
            if ellipse_grid_fractions(body.center, a, b, sc, g, &mut fr, &mut bd) {
                grid = Some((g, fr));
            }
        }
        let body = *body;
        move |x, y| match &grid {
            Some((g, fr)) => fr[(y as i64 - g.y0) as usize * g.w + (x as i64 - g.x0) as usize],
            None => body_cell_fraction(&body, x as f64, y as f64),
        }
    }

    /// The straightforward re-mapping (every body's cells from fresh kernel calls, all shares sorted by node
    /// then body): what `cover_with_bodies` must reproduce bitwise.
    fn reference<T: Real>(l: &FluidLattice<T>, bodies: &[CoupledBody<f64>]) -> Bits {
        reference_mapped(l, bodies, bodies)
    }

    /// [`reference`] with the cells of `mapped` (their geometry) and the rigid velocities of `bodies`.
    fn reference_mapped<T: Real>(
        l: &FluidLattice<T>,
        mapped: &[CoupledBody<f64>],
        bodies: &[CoupledBody<f64>],
    ) -> Bits {
        let s = l.shape;
        let mut entries = Vec::new();
        for (k, (body, moving)) in mapped.iter().zip(bodies).enumerate() {
            let Some([x0, x1, y0, y1]) = body_cell_range(body, s.nx, s.ny) else {
                continue;
            };
            let fraction = reference_fractions(body, [x0, x1, y0, y1]);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let frac = fraction(x, y);
                    if !l.on_zou_he_side(x, y) && frac > 0.0 {
                        let v =
                            rigid_velocity(moving, lbdem_kernels::math::vector(x as f64, y as f64));
                        let share = [frac, v[0], v[1]].map(|v| T::lit(v).to_f64_exact().to_bits());
                        entries.push((s.index(x, y) as u32, k as u32, share, [x as f64, y as f64]));
                    }
                }
            }
        }
        entries.sort_by_key(|e| (e.0, e.1));
        let mut b: Bits = Default::default();
        for (i, e) in entries.iter().enumerate() {
            if b.0.last() != Some(&e.0) {
                b.0.push(e.0);
                b.1.push(i as u32);
            }
            b.2.push(e.2);
            b.3.push(e.1);
            b.4.push(e.3.map(f64::to_bits));
        }
        b.1.push(entries.len() as u32);
        b
    }

    /// Whether two lattices hold bitwise the same populations.
    fn same_populations<T: Real>(a: &FluidLattice<T>, b: &FluidLattice<T>) -> bool {
        a.populations()
            .iter()
            .zip(b.populations().iter())
            .all(|(x, y)| x.to_f64_exact().to_bits() == y.to_f64_exact().to_bits())
    }

    /// Pressure sides west (ρ = 1.01) and east (ρ = 1), walls south and north, for the re-mapping tests.
    fn pressure_x<T: Real>() -> Boundaries<T> {
        Boundaries {
            west: SideCondition::Pressure {
                density: T::lit(1.01),
            },
            east: SideCondition::Pressure { density: T::one() },
            south: SideCondition::Wall,
            north: SideCondition::Wall,
        }
    }

    /// A lattice with a few obstacle nodes (so that the open links meet them too), solid operator `operator`,
    /// and a smooth flow, for the re-mapping tests.
    fn obstacle_lattice<T: Real>(
        nx: usize,
        ny: usize,
        bc: Boundaries<T>,
        params: FluidParams<T>,
        operator: SolidOperator,
    ) -> FluidLattice<T> {
        let mut l = FluidLattice::<T>::new(nx, ny, bc, params).unwrap();
        l.set_solid(|x, y| (x * 7 + y * 3) % 97 == 0);
        l.set_solid_operator(operator);
        l.fill_equilibrium(|x, y| {
            (
                T::one(),
                [
                    T::lit(0.02 * (0.2 * y as f64).sin()),
                    T::lit(0.01 * (0.3 * x as f64).cos()),
                ],
            )
        });
        l
    }

    /// Random discs and ellipses overlapping each other and the lattice sides.
    fn random_bodies(
        rng: &mut ChaCha8Rng,
        count: usize,
        nx: f64,
        ny: f64,
    ) -> Vec<CoupledBody<f64>> {
        (0..count)
            .map(|k| {
                let a = rng.random_range(1.0..7.0);
                let shape = if k % 3 == 0 {
                    BodyShape::Disc { radius: a }
                } else {
                    BodyShape::Ellipse {
                        semi_major: a,
                        semi_minor: a * rng.random_range(0.3..1.0),
                        angle: rng.random_range(-3.2..3.2),
                    }
                };
                CoupledBody {
                    center: lbdem_kernels::math::vector(
                        rng.random_range(-3.0..nx + 3.0),
                        rng.random_range(-3.0..ny + 3.0),
                    ),
                    velocity: lbdem_kernels::math::vector(
                        rng.random_range(-0.05..0.05),
                        rng.random_range(-0.05..0.05),
                    ),
                    spin: rng.random_range(-0.01..0.01),
                    shape,
                }
            })
            .collect()
    }

    /// Move every body but every fifth (which keep their geometry: the cached-cells path), change velocities.
    /// `jump` scales the displacement per velocity: 40 makes bodies leave cells and enter new ones at every
    /// call; 0.1 (with velocities then kept below 0.005) moves them by at most 5e-4 spacing, as grains move in a
    /// coupled run, so that most calls find every body on the same nodes (the in-place update: 99–103 of the
    /// 120 calls of each case).
    fn advance(rng: &mut ChaCha8Rng, bodies: &mut [CoupledBody<f64>], jump: f64) {
        // Bounded so that the fluid stays stable: slowly moving bodies stay on the lattice, overlapping, where
        // Ω₁ went unstable within 120 steps under velocities that change by 1e-3 a step up to 0.01 (f32, Zou–He
        // sides).
        let (dv, max) = if jump > 1.0 {
            (0.01, 0.05)
        } else {
            (0.0005, 0.005)
        };
        for (k, b) in bodies.iter_mut().enumerate() {
            b.velocity = lbdem_kernels::math::vector(
                (b.velocity[0] + rng.random_range(-dv..dv)).clamp(-max, max),
                (b.velocity[1] + rng.random_range(-dv..dv)).clamp(-max, max),
            );
            if k % 5 == 0 {
                continue;
            }
            b.center[0] += jump * b.velocity[0];
            b.center[1] += jump * b.velocity[1];
            if let BodyShape::Ellipse { angle, .. } = &mut b.shape {
                *angle += 0.75 * jump * b.spin;
            }
        }
    }

    /// ΩΛ's open links of the covered nodes computed here from nothing but the coverage (each node's fractions
    /// summed and compared as the collision does, then [`open_links`] on that full map).
    fn reference_links<T: Real>(l: &FluidLattice<T>) -> Vec<OpenLinks> {
        let c = l.coverage.as_ref().unwrap();
        let mut full = vec![false; l.shape.nodes()];
        for (k, &n) in c.nodes.iter().enumerate() {
            let eps = c.shares[c.offsets[k] as usize..c.offsets[k + 1] as usize]
                .iter()
                .fold(T::zero(), |e, s| e + s.fraction);
            full[n as usize] = lbdem_kernels::fluid::collide::lambda_fully_covered(eps);
        }
        c.nodes
            .iter()
            .map(|&n| {
                let (x, y) = l.shape.coords(n as usize);
                open_links(&l.shape, &l.bc, &l.flags, x, y, |j| full[j])
            })
            .collect()
    }

    fn incremental_matches_from_scratch<T: Real>(
        bc: Boundaries<T>,
        seed: u64,
        operator: SolidOperator,
        jump: f64,
    ) {
        let (nx, ny) = (61, 47);
        let params = FluidParams {
            tau: T::lit(0.9),
            force: [T::zero(); 2],
        };
        let mut incremental = obstacle_lattice(nx, ny, bc, params, operator);
        let mut scratch = obstacle_lattice(nx, ny, bc, params, operator);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut bodies = random_bodies(&mut rng, 30, nx as f64, ny as f64);
        let mut shares = 0;
        // Rows of the last build without and with overlapping segments, summed over the calls.
        let mut rows = [0; 2];
        // Steps at which some covered node was also special.
        let mut covered_special_steps = 0;
        for step in 0..120 {
            // Now and then the body list changes length (bodies removed, then new ones).
            if step == 40 {
                bodies.truncate(17);
            }
            if step == 80 {
                bodies.extend(random_bodies(&mut rng, 20, nx as f64, ny as f64));
            }
            incremental.cover_with_bodies(&bodies, Weighting::NobleTorczynski);
            scratch.clear_coverage();
            scratch.cover_with_bodies(&bodies, Weighting::NobleTorczynski);
            let (inc, fresh) = (
                incremental.coverage.as_ref().unwrap(),
                scratch.coverage.as_ref().unwrap(),
            );
            let expected = reference(&incremental, &bodies);
            assert!(
                bits(inc) == expected,
                "step {step}: incremental coverage differs from the reference"
            );
            assert!(
                bits(fresh) == expected,
                "step {step}: from-scratch coverage differs from the reference"
            );
            // ΩΛ's open links, kept up to date between calls, are those of a fresh computation.
            if operator == SolidOperator::LambdaConsistent {
                let want = reference_links(&incremental);
                assert!(
                    inc.links == want,
                    "step {step}: incremental open links differ"
                );
                assert!(
                    fresh.links == want,
                    "step {step}: from-scratch open links differ"
                );
                assert!(incremental
                    .cover_scratch
                    .links
                    .marks
                    .iter()
                    .all(|&m| m == 0));
            } else {
                assert!(inc.links.iter().all(|&m| m == ALL_LINKS_OPEN));
            }
            // Counters are back to zero between calls.
            assert!(incremental
                .cover_scratch
                .plans
                .iter()
                .all(|p| p.count.iter().all(|&c| c == 0)));
            shares += inc.shares.len();
            for p in &incremental.cover_scratch.plans {
                rows[0] += p.rows.iter().filter(|r| !r.1).count();
                rows[1] += p.rows.iter().filter(|r| r.1).count();
            }
            let eps = incremental.solid_fraction_map();
            assert!(eps
                .iter()
                .zip(scratch.solid_fraction_map())
                .all(|(a, b)| a.to_bits() == b.to_bits()));
            incremental.step();
            scratch.step();
            assert!(
                same_populations(&incremental, &scratch),
                "step {step}: populations differ"
            );
            covered_special_steps += usize::from(!incremental.aa_covered_special.is_empty());
            let centers: Vec<Point<f64>> = bodies.iter().map(|b| b.center).collect();
            let (fa, ta) = incremental.solid_forces_and_torques(&centers);
            let (fb, tb) = scratch.solid_forces_and_torques(&centers);
            assert!(
                fa.iter()
                    .zip(&fb)
                    .all(|(a, b)| a[0].to_bits() == b[0].to_bits()
                        && a[1].to_bits() == b[1].to_bits())
                    && ta.iter().zip(&tb).all(|(a, b)| a.to_bits() == b.to_bits()),
                "step {step}: forces or torques differ"
            );
            advance(&mut rng, &mut bodies, jump);
        }
        // Both lattices step the same populations above, bitwise: the incremental one with the covered special
        // nodes kept from the last step while the coverage's lists stood, the other finding them anew at every
        // step (its coverage is rebuilt from nothing every step).
        let found = incremental.aa_covered_special_found;
        assert!(
            covered_special_steps > 60,
            "covered special nodes at {covered_special_steps} steps"
        );
        assert_eq!(scratch.aa_covered_special_found, 120);
        if jump <= 1.0 {
            assert!(found < 100, "found anew at {found} of 120 steps");
        }
        // The comparison saw real coverage (about 30 bodies of ~50 cells each per step).
        assert!(shares > 120 * 300, "only {shares} shares in 120 steps");
        // Both ways of writing a row were taken (bodies overlap here far more than grains do).
        assert!(
            rows[0] > 500 && rows[1] > 500,
            "rows apart / overlapping: {rows:?}"
        );
        // Both ways of producing the lists were compared: large jumps rebuild them at every call, small moves
        // mostly update them in place, and rebuild them when a body's nodes change (and when bodies are removed
        // or added, at steps 40 and 80).
        let (in_place, rebuilt) = (
            incremental.cover_scratch.in_place,
            incremental.cover_scratch.rebuilt,
        );
        assert_eq!(in_place + rebuilt, 120);
        if jump > 1.0 {
            // (A call finds every body on its nodes when the moving ones have all left the lattice.)
            assert!(rebuilt >= 60, "rebuilt {rebuilt} of 120 calls");
        } else {
            assert!(
                in_place >= 30 && rebuilt >= 3,
                "in place {in_place}, rebuilt {rebuilt} of 120 calls"
            );
        }
        assert_eq!(scratch.cover_scratch.in_place, 0);
        // Bodies jump up to two cells a step, far from a physical motion: only ask for finite populations, so
        // that the bitwise comparison above compared numbers.
        assert!(incremental.populations().iter().all(|v| v.is_finite()));
    }

    /// The row-wise comparison of a body's nodes with the previous call's: equal lists are recognised (rows of
    /// consecutive nodes from their ends, rows with a gap node by node), and no different list is taken for
    /// an equal one, including lists that agree in every row's count, first and last node.
    #[test]
    fn a_bodys_nodes_are_compared_exactly_with_the_previous_calls() {
        let cells = |rows: &[&[u32]], y0: usize| {
            let mut c = BodyCells {
                range: Some([0, 9, y0, y0 + rows.len() - 1]),
                ..BodyCells::default()
            };
            for row in rows {
                c.row_starts.push(c.fractions.len() as u32);
                c.fractions.extend(row.iter().map(|&n| (n, 0.5)));
            }
            c.row_starts.push(c.fractions.len() as u32);
            c
        };
        let compare = |now: &[&[u32]], y0: usize, before: &[&[u32]], prev_y0: usize| {
            let mut c = cells(now, y0);
            let p = cells(before, prev_y0);
            c.prev = p.fractions;
            c.prev_row_starts = p.row_starts;
            c.same_nodes_as_prev(Some(prev_y0))
        };
        let runs: &[&[u32]] = &[&[12, 13, 14], &[], &[31, 32, 33, 34]];
        assert!(compare(runs, 1, runs, 1));
        // One node more, one less, a row shifted, another first row.
        assert!(!compare(
            &[&[12, 13, 14, 15], &[], &[31, 32, 33, 34]],
            1,
            runs,
            1
        ));
        assert!(!compare(&[&[12, 13], &[], &[31, 32, 33, 34]], 1, runs, 1));
        assert!(!compare(
            &[&[12, 13, 14], &[], &[32, 33, 34, 35]],
            1,
            runs,
            1
        ));
        assert!(!compare(runs, 2, runs, 1));
        // Rows with a gap (a cell whose fraction rounded to zero): same count, first and last node, other
        // nodes — decided node by node.
        let gap: &[&[u32]] = &[&[12, 14, 15], &[], &[31, 32, 33, 34]];
        let other_gap: &[&[u32]] = &[&[12, 13, 15], &[], &[31, 32, 33, 34]];
        assert!(compare(gap, 1, gap, 1));
        assert!(!compare(gap, 1, other_gap, 1));
        assert!(!compare(other_gap, 1, gap, 1));
        // Nothing before or now.
        assert!(compare(&[&[]], 1, &[&[]], 1));
        assert!(!compare(runs, 1, &[&[], &[], &[]], 1));
    }

    #[test]
    fn incremental_cover_is_bitwise_a_full_recover() {
        for op in [
            SolidOperator::MovingWallBounceBack,
            SolidOperator::LambdaConsistent,
        ] {
            for jump in [40.0, 0.1] {
                incremental_matches_from_scratch::<f64>(pressure_x(), 1, op, jump);
                incremental_matches_from_scratch::<f64>(Boundaries::periodic(), 2, op, jump);
                incremental_matches_from_scratch::<f32>(pressure_x(), 3, op, jump);
            }
        }
    }

    /// With a remap tolerance the coverage is, at every call, bitwise the reference coverage of the geometry
    /// the bodies were last mapped at, with the bodies' current rigid velocities; that geometry lies within the
    /// tolerance of the bodies (any point of them), the bodies are mapped again as soon as one would not, a
    /// lattice restored from a checkpoint taken between two re-mappings continues bitwise as the saved one, the
    /// covered rows' plans are made anew only after a re-mapping, and a tolerance of zero re-maps at every call.
    fn remap_tolerance_case<T>(bc: Boundaries<T>, seed: u64, operator: SolidOperator)
    where
        T: Real + serde::Serialize + serde::de::DeserializeOwned,
    {
        let (nx, ny) = (61, 47);
        let params = FluidParams {
            tau: T::lit(0.9),
            force: [T::zero(); 2],
        };
        let tolerance = 0.02;
        let mut lattice = obstacle_lattice(nx, ny, bc, params, operator);
        lattice.set_remap_tolerance(tolerance).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut bodies = random_bodies(&mut rng, 30, nx as f64, ny as f64);
        let mut restored: Option<FluidLattice<T>> = None;
        let (mut kept, mut mapped_again) = (0, 0);
        let mut previous: Vec<CoupledBody<f64>> = Vec::new();
        for step in 0..150 {
            lattice.cover_with_bodies(&bodies, Weighting::SolidFraction);
            let anchors: Vec<CoupledBody<f64>> = lattice
                .cover_scratch
                .bodies
                .iter()
                .map(|c| c.anchor.expect("every body has its mapped geometry"))
                .collect();
            for (a, b) in anchors.iter().zip(&bodies) {
                assert!(
                    moved_at_most(a, b, tolerance),
                    "step {step}: a body lies beyond the tolerance of its mapped geometry"
                );
            }
            let same = |a: &CoupledBody<f64>, b: &CoupledBody<f64>| {
                BodyCells::geometry_key(a) == BodyCells::geometry_key(b)
            };
            if step > 0 {
                let all_kept = anchors.iter().zip(&previous).all(|(a, p)| same(a, p));
                let all_new = anchors.iter().zip(&bodies).all(|(a, b)| same(a, b));
                // One decision for all bodies: either every one kept its geometry or every one was mapped
                // where it is now.
                assert!(all_kept || all_new, "step {step}: bodies mapped apart");
                if all_kept {
                    kept += 1;
                } else {
                    mapped_again += 1;
                }
            }
            previous = anchors.clone();
            let cov = lattice.coverage.as_ref().unwrap();
            assert!(
                bits(cov) == reference_mapped(&lattice, &anchors, &bodies),
                "step {step}: coverage is not that of the mapped geometry with the current velocities"
            );
            if operator == SolidOperator::LambdaConsistent {
                assert!(
                    cov.links == reference_links(&lattice),
                    "step {step}: open links differ"
                );
            }
            // A checkpoint between two re-mappings: the restored lattice continues bitwise.
            if step == 60 {
                let bytes = postcard::to_allocvec(&lattice).unwrap();
                let mut r: FluidLattice<T> = postcard::from_bytes(&bytes).unwrap();
                r.set_streaming(lattice.streaming());
                restored = Some(r);
            } else if let Some(r) = restored.as_mut() {
                r.cover_with_bodies(&bodies, Weighting::SolidFraction);
                assert!(
                    bits(r.coverage.as_ref().unwrap()) == bits(cov),
                    "step {step}: the restored lattice maps other cells"
                );
            }
            lattice.step();
            if let Some(r) = restored.as_mut() {
                r.step();
                assert!(
                    same_populations(r, &lattice),
                    "step {step}: the restored lattice's populations differ"
                );
            }
            advance(&mut rng, &mut bodies, 0.1);
        }
        assert!(
            kept >= 50 && mapped_again >= 5,
            "kept {kept}, mapped again {mapped_again} of 149 calls"
        );
        // The covered rows' plans are made anew after a re-mapping (and at the first step), not at the steps
        // between: at most one plan per band and re-mapping.
        let bands = ny.div_ceil(lattice.band_rows) as u64;
        let made = lattice.covered_plans_made;
        assert!(
            made >= bands && made <= (mapped_again as u64 + 1) * bands,
            "{made} band plans made over 150 steps ({bands} bands, {mapped_again} re-mappings)"
        );
        assert!(lattice.populations().iter().all(|v| v.is_finite()));
        // Zero tolerance: every body is mapped where it is at every call.
        lattice.set_remap_tolerance(0.0).unwrap();
        advance(&mut rng, &mut bodies, 0.1);
        lattice.cover_with_bodies(&bodies, Weighting::SolidFraction);
        assert!(bits(lattice.coverage.as_ref().unwrap()) == reference(&lattice, &bodies));
    }

    #[test]
    fn a_remap_tolerance_keeps_the_mapped_cells_within_it_and_resumes_bitwise() {
        for op in [
            SolidOperator::LinearizedNonEquilibriumBounceBack,
            SolidOperator::LambdaConsistent,
        ] {
            remap_tolerance_case::<f64>(pressure_x(), 5, op);
            remap_tolerance_case::<f32>(Boundaries::periodic(), 6, op);
        }
    }

    /// `moved_at_most` against the motion of the body's points themselves: no point of a body (outline and
    /// interior, in the body's frame) moves farther than the bound it tests, so a body it accepts lies within
    /// the tolerance; and it accepts every body whose farthest point moved by less than about half the
    /// tolerance (the largest displacement is at least max(|Δc|, 2r |sin(Δθ/2)|), so the bound |Δc| + r |Δθ|
    /// is at most about twice it).
    #[test]
    fn moved_at_most_bounds_the_motion_of_every_point() {
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let (mut accepted, mut refused) = (0, 0);
        for k in 0..4000 {
            let a_axis = rng.random_range(0.5..9.0);
            let b_axis = a_axis * rng.random_range(0.1..1.0);
            let angle = rng.random_range(-4.0..4.0);
            let shape = |angle| {
                if k % 4 == 0 {
                    BodyShape::Disc { radius: a_axis }
                } else {
                    BodyShape::Ellipse {
                        semi_major: a_axis,
                        semi_minor: b_axis,
                        angle,
                    }
                }
            };
            let body = |c: [f64; 2], angle| CoupledBody {
                center: lbdem_kernels::math::vector(c[0], c[1]),
                velocity: lbdem_kernels::math::Vector::zeros(),
                spin: 0.0,
                shape: shape(angle),
            };
            let c0 = [rng.random_range(0.0..50.0), rng.random_range(0.0..50.0)];
            let scale = 10f64.powf(rng.random_range(-4.0..-0.5));
            let c1 = [
                c0[0] + scale * rng.random_range(-1.0..1.0),
                c0[1] + scale * rng.random_range(-1.0..1.0),
            ];
            let turn = scale * rng.random_range(-1.0..1.0) / a_axis;
            let (a, b) = (body(c0, angle), body(c1, angle + turn));
            // The largest displacement of a point of the shape, over its outline and a few inner rings.
            let mut largest: f64 = 0.0;
            for i in 0..720 {
                let phi = i as f64 * std::f64::consts::TAU / 720.0;
                for ring in [1.0, 0.7, 0.3] {
                    let (u, v) = (ring * a_axis * phi.cos(), ring * b_axis * phi.sin());
                    let at = |c: [f64; 2], th: f64| {
                        let th = if k % 4 == 0 { 0.0 } else { th };
                        [
                            c[0] + u * th.cos() - v * th.sin(),
                            c[1] + u * th.sin() + v * th.cos(),
                        ]
                    };
                    let (p, q) = (at(c0, angle), at(c1, angle + turn));
                    largest = largest.max((q[0] - p[0]).hypot(q[1] - p[1]));
                }
            }
            let tolerance = scale * rng.random_range(0.2..3.0);
            if moved_at_most(&a, &b, tolerance) {
                accepted += 1;
                assert!(
                    largest <= tolerance * (1.0 + 1e-12),
                    "case {k}: a point moved {largest} > {tolerance}"
                );
            } else {
                refused += 1;
                // (0.49, not 0.5: 2 sin(Δθ/2) falls short of Δθ by Δθ³/24.)
                assert!(
                    largest > 0.49 * tolerance,
                    "case {k}: refused a body moved by {largest} <= 0.49 × {tolerance}"
                );
            }
        }
        assert!(
            accepted > 500 && refused > 500,
            "accepted {accepted}, refused {refused}"
        );
        // Another size, another kind of shape or anything not finite is never taken for the mapped body.
        let disc = CoupledBody {
            center: lbdem_kernels::math::vector(5.0, 5.0),
            velocity: lbdem_kernels::math::Vector::zeros(),
            spin: 0.0,
            shape: BodyShape::Disc { radius: 2.0 },
        };
        let grown = CoupledBody {
            shape: BodyShape::Disc {
                radius: 2.0 + 1e-12,
            },
            ..disc
        };
        let ellipse = CoupledBody {
            shape: BodyShape::Ellipse {
                semi_major: 2.0,
                semi_minor: 2.0,
                angle: 0.0,
            },
            ..disc
        };
        let lost = CoupledBody {
            center: lbdem_kernels::math::vector(f64::NAN, 5.0),
            ..disc
        };
        assert!(moved_at_most(&disc, &disc, 0.01));
        for other in [grown, ellipse, lost] {
            assert!(!moved_at_most(&disc, &other, 0.2));
        }
    }

    #[test]
    fn a_remap_tolerance_outside_its_range_is_refused_naming_the_key() {
        let mut l = FluidLattice::<f64>::new(
            8,
            8,
            Boundaries::periodic(),
            FluidParams {
                tau: 0.8,
                force: [0.0; 2],
            },
        )
        .unwrap();
        for bad in [
            -0.01,
            f64::NAN,
            f64::INFINITY,
            MAX_REMAP_TOLERANCE * 1.01,
            1.0,
        ] {
            let e = l.set_remap_tolerance(bad).unwrap_err().to_string();
            assert!(e.contains("fluid.remap_tolerance"), "{e}");
            assert_eq!(l.remap_tolerance(), 0.0);
        }
        for good in [0.0, 0.05, MAX_REMAP_TOLERANCE] {
            l.set_remap_tolerance(good).unwrap();
            assert_eq!(l.remap_tolerance(), good);
        }
    }

    /// The cell classifier that spares the exact area formula: every cell it calls inside gets exactly 1 from
    /// the formula and every cell it calls outside exactly 0, over random ellipses from sub-cell to large, thin
    /// to round, at random orientations and off-grid centres (bitwise agreement: the re-mapping must not change).
    #[test]
    fn ellipse_cell_classifier_agrees_with_the_exact_formula() {
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        let (mut inside, mut outside, mut boundary) = (0usize, 0usize, 0usize);
        for _ in 0..400 {
            let a = rng.random_range(0.3..30.0);
            let body = CoupledBody {
                center: lbdem_kernels::math::vector(
                    rng.random_range(100.0..900.0),
                    rng.random_range(100.0..400.0),
                ),
                velocity: lbdem_kernels::math::vector(0.0, 0.0),
                spin: 0.0,
                shape: BodyShape::Ellipse {
                    semi_major: a,
                    semi_minor: a * rng.random_range(0.1..1.0),
                    angle: rng.random_range(-7.0..7.0),
                },
            };
            let c = EllipseCells::new(&body).expect("a valid ellipse");
            let [x0, x1, y0, y1] = body_cell_range(&body, 1000, 500).expect("on the lattice");
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let (xf, yf) = (x as f64, y as f64);
                    let exact = body_cell_fraction(&body, xf, yf);
                    match c.classify(xf, yf) {
                        CellClass::Inside => {
                            assert!(exact == 1.0, "{body:?} cell ({x}, {y}): {exact}");
                            inside += 1;
                        }
                        CellClass::Outside => {
                            assert!(exact == 0.0, "{body:?} cell ({x}, {y}): {exact:e}");
                            outside += 1;
                        }
                        CellClass::Boundary => boundary += 1,
                    }
                }
            }
        }
        // The classifier decides most cells itself (else it would save nothing).
        assert!(
            inside + outside > 2 * boundary,
            "{inside} inside, {outside} outside, {boundary} left to the formula"
        );
        assert!(
            inside > 10_000 && outside > 10_000,
            "{inside} inside, {outside} outside"
        );
    }

    #[test]
    fn discs_and_degenerate_ellipses_are_left_to_the_exact_formula() {
        let body = |shape| CoupledBody {
            center: lbdem_kernels::math::vector(10.0, 10.0),
            velocity: lbdem_kernels::math::vector(0.0, 0.0),
            spin: 0.0,
            shape,
        };
        assert!(EllipseCells::new(&body(BodyShape::Disc { radius: 3.0 })).is_none());
        for (a, b, angle) in [
            (0.0, 1.0, 0.0),
            (2.0, -1.0, 0.0),
            (f64::NAN, 1.0, 0.0),
            (2.0, 1.0, f64::INFINITY),
        ] {
            let shape = BodyShape::Ellipse {
                semi_major: a,
                semi_minor: b,
                angle,
            };
            assert!(EllipseCells::new(&body(shape)).is_none(), "{a} {b} {angle}");
        }
    }
}
