//! The in-place "AA pattern" update (Bailey et al. 2009): one population buffer instead of two, each step
//! reading and writing the same nine values per node. A two-lattice update moves 9 reads + 9 writes + 9
//! write-allocate reads per node; this one moves 9 reads + 9 writes, and needs half the memory.
//!
//! Steps alternate between two storage layouts of the same buffer. Writing P_i(x) for the post-collision
//! population of direction i at node x (what the two-lattice scheme of [`super::step`] stores at `(i, x)`):
//!
//! * [`Layout::Collided`]: `(i, x)` holds P_i(x): exactly the two-lattice buffer.
//! * [`Layout::Streamed`]: P_i(x) has already been moved to the node it streams to, x + c_i, and is kept there
//!   in the reversed slot: `(ī, x + c_i)` holds P_i(x). Where x + c_i is a solid obstacle node or lies outside a
//!   non-periodic side, P_i(x) stays at home in `(i, x)`, which is exactly where the half-way bounce-back of the
//!   next step looks for it. Solid obstacle nodes keep the rest equilibrium in their own slots.
//!
//! A step from `Collided` ([`AaStep::Scatter`]) gathers at x the values `(i, x − c_i)` (the pull of the
//! two-lattice scheme), collides, and writes P'_ī(x) back into `(i, x − c_i)`: each node reads and writes the
//! same nine locations, and no two nodes share one, so the step is in place and order-free. The result is in
//! `Streamed` layout. A step from `Streamed` ([`AaStep::Local`]) gathers at x the values `(ī, x)`, which are
//! the streamed populations arriving at x (bounce-back included), collides and writes P'_i(x) into `(i, x)`:
//! purely local, and the result is in `Collided` layout again.
//!
//! Every node sees bitwise the same gathered populations and collision as in the two-lattice scheme, so the
//! buffer after an even number of steps is bitwise the two-lattice buffer, and after an odd number it holds the
//! same values at other places ([`post_collision_offset`] says where).
//!
//! As in [`super::step`], the bulk kernels here treat every node as an interior periodic node; nodes on
//! non-periodic sides, next to obstacles, solid or covered by moving solids are computed separately by the
//! caller from the untouched buffer *before* the bulk pass and stored *after* it at the places
//! [`post_collision_offset`] gives (the bulk pass writes garbage only into places that belong to such nodes).
use super::collide::{bgk_collide, bgk_collide_forced, trt_collide, trt_collide_forced, Collision};
use super::d2q9::{OPPOSITE, Q, VELOCITIES};
use super::lattice::{LatticeShape, Neighbour};
use super::step::{FluidParams, SOLID};
use crate::Real;

/// Where the post-collision populations of the single AA buffer are stored (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Layout {
    /// `(i, x)` holds P_i(x), as in the two-lattice scheme.
    Collided,
    /// `(ī, x + c_i)` holds P_i(x) (or `(i, x)` where x + c_i is solid or outside).
    Streamed,
}

impl Layout {
    /// The layout the next step leaves behind.
    #[inline]
    pub fn next(self) -> Self {
        match self {
            Layout::Collided => Layout::Streamed,
            Layout::Streamed => Layout::Collided,
        }
    }
}

/// Which of the two AA steps a bulk pass performs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AaStep {
    /// From [`Layout::Collided`] to [`Layout::Streamed`]: gather from and scatter to the neighbours.
    Scatter,
    /// From [`Layout::Streamed`] to [`Layout::Collided`]: read and write the node's own slots.
    Local,
}

impl AaStep {
    /// The step that starts from `layout`.
    #[inline]
    pub fn from(layout: Layout) -> Self {
        match layout {
            Layout::Collided => AaStep::Scatter,
            Layout::Streamed => AaStep::Local,
        }
    }
}

/// Offset in the buffer of P_i at node `n` (the post-collision population of direction `i`) in `layout`.
/// `periodic` = [along x, along y]. Solid obstacle nodes keep theirs at home.
#[inline]
pub fn post_collision_offset(
    shape: &LatticeShape,
    periodic: [bool; 2],
    flags: &[u8],
    layout: Layout,
    n: usize,
    i: usize,
) -> usize {
    if layout == Layout::Collided || flags[n] == SOLID {
        return shape.offset(i, n);
    }
    let (x, y) = shape.coords(n);
    match shape.neighbour(x, y, i, periodic) {
        Neighbour::Node(j) if flags[j] != SOLID => shape.offset(OPPOSITE[i], j),
        _ => shape.offset(i, n),
    }
}

/// The post-collision populations P_0..P_8 of node `n` from a buffer in `layout`.
#[inline]
pub fn load_post_collision<T: Real>(
    shape: &LatticeShape,
    periodic: [bool; 2],
    flags: &[u8],
    layout: Layout,
    buf: &[T],
    n: usize,
) -> [T; Q] {
    core::array::from_fn(|i| buf[post_collision_offset(shape, periodic, flags, layout, n, i)])
}

/// Store into plane `p` (the slice of plane p, `shape.nodes()` long) those post-collision populations of node `n`
/// that `layout` keeps in plane p: P_p(n) where it stays at home, and P_p̄(n) where it has moved to n + c_p̄.
/// Running this for the nine planes stores each P_i(n) at [`post_collision_offset`], so the planes can be filled
/// independently (in parallel). `f_p` = P_p(n), `f_opp` = P_p̄(n).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn store_post_collision_in_plane<T: Real>(
    shape: &LatticeShape,
    periodic: [bool; 2],
    flags: &[u8],
    layout: Layout,
    p: usize,
    plane: &mut [T],
    n: usize,
    f_p: T,
    f_opp: T,
) {
    if layout == Layout::Collided || flags[n] == SOLID {
        plane[n] = f_p;
        return;
    }
    let (x, y) = shape.coords(n);
    let c = VELOCITIES[p];
    if x > 0 && y > 0 && x + 1 < shape.nx && y + 1 < shape.ny {
        // Interior node: n ± c_p are nodes, no wrap. n + c_p̄ = n − c_p, written with non-negative terms.
        let nx = shape.nx;
        let back = n + nx + 1 - (1 + c[0]) as usize - (1 + c[1]) as usize * nx;
        let ahead = n + (1 + c[0]) as usize + (1 + c[1]) as usize * nx - nx - 1;
        if flags[back] != SOLID {
            plane[back] = f_opp;
        }
        if flags[ahead] == SOLID {
            plane[n] = f_p;
        }
        return;
    }
    // P_p̄(n) moves to (p, n + c_p̄) when that node is fluid.
    if let Neighbour::Node(j) = shape.neighbour(x, y, OPPOSITE[p], periodic) {
        if flags[j] != SOLID {
            plane[j] = f_opp;
        }
    }
    // P_p(n) stays at (p, n) when n + c_p is solid or outside.
    match shape.neighbour(x, y, p, periodic) {
        Neighbour::Node(j) if flags[j] != SOLID => {}
        _ => plane[n] = f_p,
    }
}

/// Rewrite a buffer from layout `from` into the two-lattice layout ([`Layout::Collided`]), into `out` (same
/// length as `buf`; padding is copied as is).
pub fn to_collided<T: Real>(
    shape: &LatticeShape,
    periodic: [bool; 2],
    flags: &[u8],
    from: Layout,
    buf: &[T],
    out: &mut [T],
) {
    out.copy_from_slice(buf);
    if from == Layout::Collided {
        return;
    }
    for n in 0..shape.nodes() {
        let f = load_post_collision(shape, periodic, flags, from, buf, n);
        for (i, v) in f.iter().enumerate() {
            out[shape.offset(i, n)] = *v;
        }
    }
}

/// The rows one bulk pass works on for lattice row y: `rows[p]` is row `y − c_p,y` (wrapped) of plane p for
/// [`AaStep::Scatter`], row y of plane p for [`AaStep::Local`]; each exactly `nx` long.
pub fn plane_row(step: AaStep, p: usize, y: usize, ny: usize) -> usize {
    match step {
        AaStep::Local => y,
        AaStep::Scatter => super::lattice::wrap_row(y, -VELOCITIES[p][1], ny),
    }
}

/// Scatter step of one row, every node treated as an interior periodic node: node x gathers `rows[p][x − c_p,x]`
/// (wrapped), collides with `collide`, and writes its post-collision population of direction p̄ back there.
#[inline(always)]
pub fn scatter_row<T: Real, C: Fn(&mut [T; Q])>(rows: &mut [&mut [T]; Q], collide: &C) {
    scatter_row_with(rows, collide, |_| false);
}

/// [`scatter_row`] that leaves the nodes x with `keep[x]` as they were: such a node writes back the nine values
/// it gathered (so its slots still hold them after the pass, for a later pass to gather), every other node
/// exactly what [`scatter_row`] writes. `keep` is `nx` long (a shorter mask is misuse: the pass then panics).
#[inline(always)]
pub fn scatter_row_keeping<T: Real, C: Fn(&mut [T; Q])>(
    rows: &mut [&mut [T]; Q],
    keep: &[bool],
    collide: &C,
) {
    let nx = rows[0].len();
    let keep = &keep[..nx];
    scatter_row_with(rows, collide, |x| keep[x]);
}

/// The body of [`scatter_row`] and [`scatter_row_keeping`]: `kept(x)` says whether node x writes back what it
/// gathered.
#[inline(always)]
fn scatter_row_with<T: Real, C: Fn(&mut [T; Q]), K: Fn(usize) -> bool>(
    rows: &mut [&mut [T]; Q],
    collide: &C,
    kept: K,
) {
    let nx = rows[0].len();
    if nx == 0 {
        return;
    }
    // Edge columns with wrap (for nx ≤ 2 every column is an edge column).
    let edges: [usize; 2] = [0, nx - 1];
    for (e, &x) in edges.iter().enumerate() {
        if e == 1 && nx == 1 {
            break;
        }
        let at: [usize; Q] = core::array::from_fn(|p| scatter_column(p, x, nx));
        let mut f: [T; Q] = core::array::from_fn(|p| rows[p][at[p]]);
        let gathered = f;
        collide(&mut f);
        if kept(x) {
            f = gathered;
            for p in 0..Q {
                rows[p][at[p]] = f[p];
            }
            continue;
        }
        for p in 0..Q {
            rows[p][at[p]] = f[OPPOSITE[p]];
        }
    }
    if nx < 3 {
        return;
    }
    let n = nx - 2;
    let [r0, r1, r2, r3, r4, r5, r6, r7, r8] = rows;
    // Plane p of interior node x = 1 + k lives at index 1 + k − c_p,x.
    let s0 = &mut r0[1..1 + n];
    let s1 = &mut r1[..n];
    let s2 = &mut r2[1..1 + n];
    let s3 = &mut r3[2..2 + n];
    let s4 = &mut r4[1..1 + n];
    let s5 = &mut r5[..n];
    let s6 = &mut r6[2..2 + n];
    let s7 = &mut r7[2..2 + n];
    let s8 = &mut r8[..n];
    for k in 0..n {
        let g = [
            s0[k], s1[k], s2[k], s3[k], s4[k], s5[k], s6[k], s7[k], s8[k],
        ];
        let mut f = g;
        collide(&mut f);
        // A kept node writes its gathered values back where it read them (slot p holds its population p);
        // the others write population p̄ into slot p.
        let out = if kept(1 + k) {
            g
        } else {
            [f[0], f[3], f[4], f[1], f[2], f[7], f[8], f[5], f[6]]
        };
        s0[k] = out[0];
        s1[k] = out[1];
        s2[k] = out[2];
        s3[k] = out[3];
        s4[k] = out[4];
        s5[k] = out[5];
        s6[k] = out[6];
        s7[k] = out[7];
        s8[k] = out[8];
    }
}

/// Local step of one row: node x gathers `rows[p̄][x]` as its population p, collides with `collide`, and writes
/// population p into `rows[p][x]`.
#[inline(always)]
pub fn local_row<T: Real, C: Fn(&mut [T; Q])>(rows: &mut [&mut [T]; Q], collide: &C) {
    local_row_with(rows, collide, |_| false);
}

/// [`local_row`] that leaves the nodes x with `keep[x]` as they were (see [`scatter_row_keeping`]). `keep` is
/// `nx` long.
#[inline(always)]
pub fn local_row_keeping<T: Real, C: Fn(&mut [T; Q])>(
    rows: &mut [&mut [T]; Q],
    keep: &[bool],
    collide: &C,
) {
    let nx = rows[0].len();
    let keep = &keep[..nx];
    local_row_with(rows, collide, |x| keep[x]);
}

/// The body of [`local_row`] and [`local_row_keeping`].
#[inline(always)]
fn local_row_with<T: Real, C: Fn(&mut [T; Q]), K: Fn(usize) -> bool>(
    rows: &mut [&mut [T]; Q],
    collide: &C,
    kept: K,
) {
    let nx = rows[0].len();
    let [r0, r1, r2, r3, r4, r5, r6, r7, r8] = rows;
    let (r1, r2, r3, r4) = (&mut r1[..nx], &mut r2[..nx], &mut r3[..nx], &mut r4[..nx]);
    let (r5, r6, r7, r8) = (&mut r5[..nx], &mut r6[..nx], &mut r7[..nx], &mut r8[..nx]);
    let r0 = &mut r0[..nx];
    for k in 0..nx {
        let g = [
            r0[k], r3[k], r4[k], r1[k], r2[k], r7[k], r8[k], r5[k], r6[k],
        ];
        let mut f = g;
        collide(&mut f);
        // A kept node writes back slot by slot what it read there (slot p held its population p̄).
        let out = if kept(k) {
            [g[0], g[3], g[4], g[1], g[2], g[7], g[8], g[5], g[6]]
        } else {
            f
        };
        r0[k] = out[0];
        r1[k] = out[1];
        r2[k] = out[2];
        r3[k] = out[3];
        r4[k] = out[4];
        r5[k] = out[5];
        r6[k] = out[6];
        r7[k] = out[7];
        r8[k] = out[8];
    }
}

/// Column of plane p read and written by node x in a scatter step: x − c_p,x, wrapped.
#[inline(always)]
pub(super) fn scatter_column(p: usize, x: usize, nx: usize) -> usize {
    let cx = VELOCITIES[p][0];
    if cx > 0 {
        if x == 0 {
            nx - 1
        } else {
            x - 1
        }
    } else if cx < 0 {
        if x + 1 == nx {
            0
        } else {
            x + 1
        }
    } else {
        x
    }
}

/// The populations node (x, y) gathers in the bulk pass of `step`, from a band of rows as [`plane_row`]
/// describes it (`rows[y − y0]`). Right for every node that is not special: such a node's gather is the bulk
/// pass's.
#[inline(always)]
pub fn load_from_rows<T: Real>(
    rows: &[[&mut [T]; Q]],
    step: AaStep,
    y0: usize,
    x: usize,
    y: usize,
) -> [T; Q] {
    let r = &rows[y - y0];
    let nx = r[0].len();
    // Written out (not `core::array::from_fn`, which the compiler left out of line in the covered nodes' pass).
    match step {
        AaStep::Local => [
            r[0][x], r[3][x], r[4][x], r[1][x], r[2][x], r[7][x], r[8][x], r[5][x], r[6][x],
        ],
        AaStep::Scatter => {
            let at = |p: usize| scatter_column(p, x, nx);
            [
                r[0][at(0)],
                r[1][at(1)],
                r[2][at(2)],
                r[3][at(3)],
                r[4][at(4)],
                r[5][at(5)],
                r[6][at(6)],
                r[7][at(7)],
                r[8][at(8)],
            ]
        }
    }
}

/// Store the post-collision populations `f` of node (x, y) at the places the bulk pass of `step` writes them,
/// in a band of rows as [`plane_row`] describes it (`rows[y − y0]`). Right for every node that is not special
/// (see [`super::step::classify_special_nodes`]): such a node's places are the bulk pass's.
#[inline(always)]
pub fn store_in_rows<T: Real>(
    rows: &mut [[&mut [T]; Q]],
    step: AaStep,
    y0: usize,
    x: usize,
    y: usize,
    f: &[T; Q],
) {
    let r = &mut rows[y - y0];
    let nx = r[0].len();
    for p in 0..Q {
        match step {
            AaStep::Local => r[p][x] = f[p],
            // Node x gathered plane p at x − c_p,x and writes P_p̄ back there.
            AaStep::Scatter => r[p][scatter_column(p, x, nx)] = f[OPPOSITE[p]],
        }
    }
}

/// The bulk pass of one AA step over a band of rows (each entry as [`plane_row`] describes), with the fluid's
/// collision (BGK or TRT, with Guo forcing when a force is set). Inlined into its caller, so a caller compiled
/// with wider vector instructions (`#[target_feature]`) gets the loops in those instructions.
#[inline(always)]
pub fn aa_bulk_rows<T: Real>(
    rows: &mut [[&mut [T]; Q]],
    step: AaStep,
    params: &FluidParams<T>,
    collision: &Collision<T>,
) {
    let rates = collision.rates_unchecked(params.tau);
    let omega = rates.plus;
    let force = params.force;
    match (collision, params.forced()) {
        (Collision::Bgk, true) => {
            let c = |f: &mut [T; Q]| bgk_collide_forced(f, omega, force);
            aa_rows_with(rows, step, &c);
        }
        (Collision::Bgk, false) => {
            let c = |f: &mut [T; Q]| bgk_collide(f, omega);
            aa_rows_with(rows, step, &c);
        }
        (Collision::Trt(_), true) => {
            let c = |f: &mut [T; Q]| trt_collide_forced(f, rates, force);
            aa_rows_with(rows, step, &c);
        }
        (Collision::Trt(_), false) => {
            let c = |f: &mut [T; Q]| trt_collide(f, rates);
            aa_rows_with(rows, step, &c);
        }
    }
}

/// [`aa_bulk_rows`] that leaves the nodes marked in `keep` as they were: `keep[r * nx + x]` for node x of row r
/// of the band (`rows.len() × nx` entries; shorter is misuse and panics). A kept node writes back the values it
/// gathered, so its slots hold after the pass what they held before it; every other node gets exactly what
/// [`aa_bulk_rows`] gives it. Lets a caller collide the kept (covered) nodes *after* the bulk pass from the rows
/// the pass has just brought into cache, and store them in place.
#[inline(always)]
pub fn aa_bulk_rows_keeping<T: Real>(
    rows: &mut [[&mut [T]; Q]],
    keep: &[bool],
    step: AaStep,
    params: &FluidParams<T>,
    collision: &Collision<T>,
) {
    let rates = collision.rates_unchecked(params.tau);
    let omega = rates.plus;
    let force = params.force;
    match (collision, params.forced()) {
        (Collision::Bgk, true) => {
            let c = |f: &mut [T; Q]| bgk_collide_forced(f, omega, force);
            aa_rows_keeping(rows, keep, step, &c);
        }
        (Collision::Bgk, false) => {
            let c = |f: &mut [T; Q]| bgk_collide(f, omega);
            aa_rows_keeping(rows, keep, step, &c);
        }
        (Collision::Trt(_), true) => {
            let c = |f: &mut [T; Q]| trt_collide_forced(f, rates, force);
            aa_rows_keeping(rows, keep, step, &c);
        }
        (Collision::Trt(_), false) => {
            let c = |f: &mut [T; Q]| trt_collide(f, rates);
            aa_rows_keeping(rows, keep, step, &c);
        }
    }
}

#[inline(always)]
fn aa_rows_keeping<T: Real, C: Fn(&mut [T; Q])>(
    rows: &mut [[&mut [T]; Q]],
    keep: &[bool],
    step: AaStep,
    c: &C,
) {
    let Some(nx) = rows.first().map(|r| r[0].len()) else {
        return;
    };
    match step {
        AaStep::Scatter => {
            for (r, row) in rows.iter_mut().enumerate() {
                scatter_row_keeping(row, &keep[r * nx..(r + 1) * nx], c);
            }
        }
        AaStep::Local => {
            for (r, row) in rows.iter_mut().enumerate() {
                local_row_keeping(row, &keep[r * nx..(r + 1) * nx], c);
            }
        }
    }
}

#[inline(always)]
fn aa_rows_with<T: Real, C: Fn(&mut [T; Q])>(rows: &mut [[&mut [T]; Q]], step: AaStep, c: &C) {
    // Plain loops (not `for_each`, which may be left out of line and so compiled without the caller's
    // `#[target_feature]`s).
    match step {
        AaStep::Scatter => {
            for r in rows.iter_mut() {
                scatter_row(r, c);
            }
        }
        AaStep::Local => {
            for r in rows.iter_mut() {
                local_row(r, c);
            }
        }
    }
}
