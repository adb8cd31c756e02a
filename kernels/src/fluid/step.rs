//! The fused "pull" lattice update over a band of rows: streaming, boundary conditions and collision in one
//! pass from a source buffer to a destination buffer (two-lattice scheme, 144 bytes moved per f64 update).
//!
//! Both buffers hold **post-collision** populations. For each node x of the band:
//! 1. gather f_i(x) = src_i(x − c_i) (streaming; periodic wrap on periodic axes);
//! 2. where x − c_i is a solid obstacle node or lies outside a wall side, half-way bounce-back:
//!    f_i(x) = src_ī(x) (the population that left x towards the wall comes back reversed);
//! 3. on Zou–He sides, close the unknown incoming populations (see [`super::boundary`]);
//! 4. collide (BGK, forced BGK, or the partially-saturated operator on covered nodes) and store in dst.
//!
//! To keep the hot loop branch-free, the work is split in three passes per band:
//! * [`bulk_rows`] treats every node as an interior periodic node with one collision operator and no
//!   branches per node;
//! * [`fix_special_nodes`] redoes, with the general gather, the nodes listed by [`classify_special_nodes`]
//!   (edge nodes of non-periodic sides, fluid nodes next to solid obstacle nodes, and the obstacle nodes
//!   themselves, which are set to the rest equilibrium ρ = 1 so that no garbage is ever stored);
//! * [`collide_covered_nodes`] redoes the nodes covered by moving solids with the PSM operator and returns the
//!   momentum exchange per solid share.
//!
//! Each pass reads only `src` and writes only the band of `dst`, so bands are independent: splitting the
//! lattice into bands for threads gives bitwise the same result for any number of threads.
use super::aa::{
    load_from_rows, load_post_collision, scatter_column, store_in_rows, AaStep, Layout,
};
use super::boundary::{zou_he, zou_he_corner, Boundaries, SideCondition, SideProfiles};
use super::collide::{
    bgk_collide, bgk_collide_forced, fluid_collide, lane_class, psm_collide_lanes,
    psm_collide_links, trt_collide, trt_collide_forced, Collision, LaneClass, OpenLinks, PsmLanes,
    PsmParams, SolidShare, PSM_LANES,
};
use super::d2q9::{density, equilibrium, velocity, weights, OPPOSITE, Q, VELOCITIES};
use super::lattice::{wrap_row, LatticeShape, Neighbour, Side};
use crate::Real;

/// Node flag: an ordinary fluid node.
pub const FLUID: u8 = 0;
/// Node flag: a fixed solid obstacle node (half-way bounce-back from its fluid neighbours).
pub const SOLID: u8 = 1;

/// The nine planes of a population buffer as immutable slices, each exactly `shape.nodes()` long.
pub fn planes<'a, T>(shape: &LatticeShape, buf: &'a [T]) -> [&'a [T]; Q] {
    let n = shape.nodes();
    core::array::from_fn(|q| &buf[q * shape.stride..q * shape.stride + n])
}

/// The nine planes of a population buffer as mutable slices, each exactly `shape.nodes()` long.
pub fn planes_mut<'a, T>(shape: &LatticeShape, buf: &'a mut [T]) -> [&'a mut [T]; Q] {
    let n = shape.nodes();
    let mut rest = buf;
    let mut out: [&'a mut [T]; Q] = Default::default();
    for slot in out.iter_mut() {
        // The stride is ≥ n, and the buffer holds Q strides, so every split is in bounds.
        let (head, tail) = core::mem::take(&mut rest).split_at_mut(shape.stride);
        *slot = &mut head[..n];
        rest = tail;
    }
    out
}

/// The rows `y0..y1` of each plane of `planes`, as a band for [`step_band`].
pub fn band_mut<'a, T>(
    shape: &LatticeShape,
    planes: [&'a mut [T]; Q],
    y0: usize,
    y1: usize,
) -> [&'a mut [T]; Q] {
    let (a, b) = (y0 * shape.nx, y1 * shape.nx);
    planes.map(|p| &mut p[a..b])
}

/// Populations at node `index` of a buffer.
#[inline(always)]
pub fn load<T: Real>(shape: &LatticeShape, buf: &[T], index: usize) -> [T; Q] {
    core::array::from_fn(|q| buf[q * shape.stride + index])
}

/// Density and velocity (with the Guo half-force shift) of every node, from a post-collision buffer in the
/// two-lattice layout: the moments of the populations after streaming, which is what the next collision sees.
#[allow(clippy::too_many_arguments)]
pub fn gathered_moments<T: Real>(
    shape: &LatticeShape,
    src: &[T],
    bc: &Boundaries<T>,
    profiles: &SideProfiles<'_, T>,
    flags: &[u8],
    force: [T; 2],
    rho_out: &mut [T],
    u_out: &mut [[T; 2]],
) {
    gathered_moments_in(
        shape,
        src,
        Layout::Collided,
        bc,
        profiles,
        flags,
        force,
        rho_out,
        u_out,
    );
}

/// [`gathered_moments`] from a buffer in either layout of the in-place scheme (see [`super::aa`]).
#[allow(clippy::too_many_arguments)]
pub fn gathered_moments_in<T: Real>(
    shape: &LatticeShape,
    src: &[T],
    layout: Layout,
    bc: &Boundaries<T>,
    profiles: &SideProfiles<'_, T>,
    flags: &[u8],
    force: [T; 2],
    rho_out: &mut [T],
    u_out: &mut [[T; 2]],
) {
    for y in 0..shape.ny {
        for x in 0..shape.nx {
            let n = shape.index(x, y);
            if flags[n] == SOLID {
                rho_out[n] = T::one();
                u_out[n] = [T::zero(); 2];
                continue;
            }
            let f = gather_node_in(shape, src, layout, bc, profiles, flags, x, y);
            let (rho, u) = super::collide::macroscopic(&f, force);
            rho_out[n] = rho;
            u_out[n] = u;
        }
    }
}

/// [`gather_node`] from a buffer in either layout of the in-place scheme. In [`Layout::Streamed`] the
/// streamed populations (bounce-back included) already sit in the node's own reversed slots, so only the
/// Zou–He closures remain to be applied.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn gather_node_in<T: Real>(
    shape: &LatticeShape,
    src: &[T],
    layout: Layout,
    bc: &Boundaries<T>,
    profiles: &SideProfiles<'_, T>,
    flags: &[u8],
    x: usize,
    y: usize,
) -> [T; Q] {
    match layout {
        Layout::Collided => gather_node(shape, src, bc, profiles, flags, x, y),
        Layout::Streamed => {
            let here = shape.index(x, y);
            let mut f: [T; Q] = core::array::from_fn(|q| src[shape.offset(OPPOSITE[q], here)]);
            if !(x > 0 && y > 0 && x + 1 < shape.nx && y + 1 < shape.ny) {
                let periodic = bc.periodic_axes();
                let density_at = |j: usize| {
                    density(&load_post_collision(shape, periodic, flags, layout, src, j))
                };
                close_edges(shape, bc, profiles, flags, x, y, &mut f, density_at);
            }
            f
        }
    }
}

/// The general gather at node (x, y): streaming with periodic wrap, half-way bounce-back from solid obstacle
/// nodes and wall sides (with Ladd's correction at moving walls), and the Zou–He closures of Zou–He sides
/// (including corners; velocities of profile sides from `profiles`).
#[inline]
pub fn gather_node<T: Real>(
    shape: &LatticeShape,
    src: &[T],
    bc: &Boundaries<T>,
    profiles: &SideProfiles<'_, T>,
    flags: &[u8],
    x: usize,
    y: usize,
) -> [T; Q] {
    let here = shape.index(x, y);
    let mut f = [T::zero(); Q];
    if x > 0 && y > 0 && x + 1 < shape.nx && y + 1 < shape.ny {
        // Interior node: no side is crossed (so no wrap and no Zou–He closure) and the upstream node of
        // direction q is here − c_q; only obstacle neighbours bounce back. Same values as the general path.
        let nx = shape.nx;
        for (q, fq) in f.iter_mut().enumerate() {
            let c = VELOCITIES[q];
            // here − c_x − c_y nx, written with non-negative terms: x ≥ 1 and y ≥ 1.
            let j = here + nx + 1 - (1 + c[0]) as usize - (1 + c[1]) as usize * nx;
            *fq = if flags[j] == SOLID {
                src[shape.offset(OPPOSITE[q], here)]
            } else {
                src[shape.offset(q, j)]
            };
        }
        return f;
    }
    let periodic = bc.periodic_axes();
    for (q, fq) in f.iter_mut().enumerate() {
        match shape.upstream(x, y, q, periodic) {
            Neighbour::Node(j) => {
                *fq = if flags[j] == SOLID {
                    src[shape.offset(OPPOSITE[q], here)]
                } else {
                    src[shape.offset(q, j)]
                };
            }
            Neighbour::Outside { .. } => {
                // Through a wall side: half-way bounce-back. Through a Zou–He side the population is unknown;
                // it is provisionally bounced back too and the closure below overwrites it.
                *fq = src[shape.offset(OPPOSITE[q], here)];
            }
        }
    }
    close_edges(shape, bc, profiles, flags, x, y, &mut f, |j| {
        density(&load(shape, src, j))
    });
    f
}

/// Apply Ladd's moving-wall correction and the Zou–He closures to the gathered populations of an edge node.
/// `density_at(j)` is the density (sum of the post-collision populations) of fluid node j, needed by corners
/// between two velocity sides.
#[inline]
#[allow(clippy::too_many_arguments)]
fn close_edges<T: Real>(
    shape: &LatticeShape,
    bc: &Boundaries<T>,
    profiles: &SideProfiles<'_, T>,
    flags: &[u8],
    x: usize,
    y: usize,
    f: &mut [T; Q],
    density_at: impl Fn(usize) -> T,
) {
    moving_wall_correction(shape, bc, x, y, f);
    // The velocity a (profile) velocity side prescribes at this node.
    let side_condition = |side: Side| -> SideCondition<T> {
        match bc.side(side) {
            SideCondition::VelocityProfile => {
                let k = match side {
                    Side::West | Side::East => y,
                    Side::South | Side::North => x,
                };
                SideCondition::Velocity {
                    velocity: profiles
                        .side(side)
                        .get(k)
                        .copied()
                        .unwrap_or([T::zero(); 2]),
                }
            }
            c => c,
        }
    };
    let xs = if x == 0 && bc.west.is_zou_he() {
        Some(Side::West)
    } else if x + 1 == shape.nx && bc.east.is_zou_he() {
        Some(Side::East)
    } else {
        None
    };
    let ys = if y == 0 && bc.south.is_zou_he() {
        Some(Side::South)
    } else if y + 1 == shape.ny && bc.north.is_zou_he() {
        Some(Side::North)
    } else {
        None
    };
    match (xs, ys) {
        (Some(s), None) => zou_he(f, s, side_condition(s)),
        (None, Some(s)) => zou_he(f, s, side_condition(s)),
        (Some(sx), Some(sy)) => {
            let (cx, cy) = (side_condition(sx), side_condition(sy));
            let rho = match (cx, cy) {
                (
                    SideCondition::Pressure { density: a },
                    SideCondition::Pressure { density: b },
                ) => T::lit(0.5) * (a + b),
                (SideCondition::Pressure { density }, _)
                | (_, SideCondition::Pressure { density }) => density,
                _ => {
                    // Two velocity sides: density of the diagonal interior neighbour (post-collision sum).
                    let ix = if sx == Side::West {
                        x + 1
                    } else {
                        x.saturating_sub(1)
                    };
                    let iy = if sy == Side::South {
                        y + 1
                    } else {
                        y.saturating_sub(1)
                    };
                    let (ix, iy) = (ix.min(shape.nx - 1), iy.min(shape.ny - 1));
                    let j = shape.index(ix, iy);
                    if flags[j] == SOLID {
                        T::one()
                    } else {
                        density_at(j)
                    }
                }
            };
            let u = match (cx, cy) {
                (SideCondition::Velocity { velocity }, _)
                | (_, SideCondition::Velocity { velocity }) => velocity,
                _ => [T::zero(); 2],
            };
            zou_he_corner(f, sx, sy, rho, u);
        }
        (None, None) => {}
    }
}

/// Ladd's correction of the populations of edge node (x, y) that re-entered through a moving wall side:
/// f_q += 6 w_q ρ c_q·u_w, ρ the density of the gathered populations (see [`super::boundary`]). A population
/// that crossed two sides (a corner) takes the velocity of the side it crossed along y if that side is a
/// moving wall, else that of the side along x.
#[inline]
fn moving_wall_correction<T: Real>(
    shape: &LatticeShape,
    bc: &Boundaries<T>,
    x: usize,
    y: usize,
    f: &mut [T; Q],
) {
    let wall_velocity = |side: Option<Side>| match side.map(|s| bc.side(s)) {
        Some(SideCondition::MovingWall { velocity }) => Some(velocity),
        _ => None,
    };
    let periodic = bc.periodic_axes();
    let mut rho = None;
    let w = weights::<T>();
    for q in 1..Q {
        if let Neighbour::Outside { x: sx, y: sy } = shape.upstream(x, y, q, periodic) {
            if let Some(u) = wall_velocity(sy).or_else(|| wall_velocity(sx)) {
                let r = *rho.get_or_insert_with(|| density(f));
                let c = velocity::<T>(q);
                f[q] += T::lit(6.0) * w[q] * r * (c[0] * u[0] + c[1] * u[1]);
            }
        }
    }
}

/// List, in increasing order, the nodes that the branch-free bulk pass gets wrong and [`fix_special_nodes`]
/// must redo: solid obstacle nodes, nodes on non-periodic sides, and fluid nodes with a solid upstream
/// neighbour. Writes into `out` (at most `shape.nodes()` entries are needed) and returns the count written;
/// stops early (returning `out.len()`) if `out` is too short.
pub fn classify_special_nodes<T: Real>(
    shape: &LatticeShape,
    bc: &Boundaries<T>,
    flags: &[u8],
    out: &mut [u32],
) -> usize {
    let periodic = bc.periodic_axes();
    let mut count = 0;
    for y in 0..shape.ny {
        for x in 0..shape.nx {
            let n = shape.index(x, y);
            let mut special = flags[n] == SOLID
                || (!periodic[0] && (x == 0 || x + 1 == shape.nx))
                || (!periodic[1] && (y == 0 || y + 1 == shape.ny));
            if !special {
                for q in 1..Q {
                    if let Neighbour::Node(j) = shape.upstream(x, y, q, periodic) {
                        if flags[j] == SOLID {
                            special = true;
                            break;
                        }
                    }
                }
            }
            if special {
                if count >= out.len() {
                    return count;
                }
                out[count] = n as u32;
                count += 1;
            }
        }
    }
    count
}

/// Pull one node from `src` assuming a fully periodic lattice (used for the first and last column of the bulk).
#[inline(always)]
fn pull_periodic<T: Real>(shape: &LatticeShape, src: &[&[T]; Q], x: usize, y: usize) -> [T; Q] {
    let nx = shape.nx;
    let xm = if x == 0 { nx - 1 } else { x - 1 };
    let xp = if x + 1 >= nx { 0 } else { x + 1 };
    let ym = wrap_row(y, -1, shape.ny) * nx;
    let yp = wrap_row(y, 1, shape.ny) * nx;
    let y0 = y * nx;
    [
        src[0][y0 + x],
        src[1][y0 + xm],
        src[2][ym + x],
        src[3][y0 + xp],
        src[4][yp + x],
        src[5][ym + xm],
        src[6][ym + xp],
        src[7][yp + xp],
        src[8][yp + xm],
    ]
}

/// The source slices of row y's interior nodes under the periodic pull, each exactly nx − 2 long: element k of
/// slice i is src_i(x − c_i) at x = k + 1 (the bulk pass's streaming; requires nx ≥ 3).
#[inline(always)]
fn pull_row<'a, T>(shape: &LatticeShape, s: &[&'a [T]; Q], y: usize) -> [&'a [T]; Q] {
    let nx = shape.nx;
    let n = nx - 2;
    let r0 = y * nx;
    let rm = wrap_row(y, -1, shape.ny) * nx;
    let rp = wrap_row(y, 1, shape.ny) * nx;
    [
        &s[0][r0 + 1..r0 + 1 + n],
        &s[1][r0..r0 + n],
        &s[2][rm + 1..rm + 1 + n],
        &s[3][r0 + 2..r0 + 2 + n],
        &s[4][rp + 1..rp + 1 + n],
        &s[5][rm..rm + n],
        &s[6][rm + 2..rm + 2 + n],
        &s[7][rp + 2..rp + 2 + n],
        &s[8][rp..rp + n],
    ]
}

/// The branch-free bulk pass over rows `y0..y1`: periodic pull + `collide` for every node, written into the
/// band `dst` (each plane slice holds rows y0..y1). `collide` is applied in place to the gathered populations.
#[inline(always)]
pub fn bulk_rows<T: Real, C: Fn(&mut [T; Q])>(
    shape: &LatticeShape,
    src: &[T],
    dst: &mut [&mut [T]; Q],
    y0: usize,
    y1: usize,
    collide: C,
) {
    let s = planes(shape, src);
    let nx = shape.nx;
    for y in y0..y1 {
        let row = (y - y0) * nx;
        // Edge columns (x = 0, x = nx − 1) with wrap.
        for x in [0, nx - 1] {
            let mut f = pull_periodic(shape, &s, x, y);
            collide(&mut f);
            for q in 0..Q {
                dst[q][row + x] = f[q];
            }
            if nx == 1 {
                break;
            }
        }
        if nx < 3 {
            continue;
        }
        let n = nx - 2;
        let [s0, s1, s2, s3, s4, s5, s6, s7, s8] = pull_row(shape, &s, y);
        let [d0, d1, d2, d3, d4, d5, d6, d7, d8] = dst;
        let d0 = &mut d0[row + 1..row + 1 + n];
        let d1 = &mut d1[row + 1..row + 1 + n];
        let d2 = &mut d2[row + 1..row + 1 + n];
        let d3 = &mut d3[row + 1..row + 1 + n];
        let d4 = &mut d4[row + 1..row + 1 + n];
        let d5 = &mut d5[row + 1..row + 1 + n];
        let d6 = &mut d6[row + 1..row + 1 + n];
        let d7 = &mut d7[row + 1..row + 1 + n];
        let d8 = &mut d8[row + 1..row + 1 + n];
        for k in 0..n {
            let mut f = [
                s0[k], s1[k], s2[k], s3[k], s4[k], s5[k], s6[k], s7[k], s8[k],
            ];
            collide(&mut f);
            d0[k] = f[0];
            d1[k] = f[1];
            d2[k] = f[2];
            d3[k] = f[3];
            d4[k] = f[4];
            d5[k] = f[5];
            d6[k] = f[6];
            d7[k] = f[7];
            d8[k] = f[8];
        }
    }
}

/// Pure streaming of a fully periodic lattice (no collision): a permutation of the populations.
pub fn stream_periodic<T: Real>(shape: &LatticeShape, src: &[T], dst: &mut [&mut [T]; Q]) {
    bulk_rows(shape, src, dst, 0, shape.ny, |_f: &mut [T; Q]| {});
}

/// The static description of a lattice a step works on: its shape, side conditions (with the velocity
/// profiles of profile sides) and node flags ([`FLUID`] / [`SOLID`], one per node).
#[derive(Clone, Copy, Debug)]
pub struct Domain<'a, T> {
    /// Size and layout.
    pub shape: LatticeShape,
    /// Side conditions.
    pub bc: Boundaries<T>,
    /// Velocity profiles of [`SideCondition::VelocityProfile`] sides.
    pub profiles: SideProfiles<'a, T>,
    /// One flag per node.
    pub flags: &'a [u8],
}

/// Collision parameters of the fluid away from moving solids.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FluidParams<T> {
    /// Relaxation time τ (> ½); ω = 1/τ.
    pub tau: T,
    /// Uniform body-force density (lattice units, Guo forcing); zero for none.
    pub force: [T; 2],
}

impl<T: Real> FluidParams<T> {
    /// Whether a body force is applied.
    #[inline(always)]
    pub fn forced(&self) -> bool {
        self.force[0] != T::zero() || self.force[1] != T::zero()
    }
}

/// The new post-collision populations of special node `n` (see [`classify_special_nodes`]) from `src` in
/// `layout`: the general gather and the fluid collision `collision`, or the rest equilibrium (ρ = 1, u = 0) for a
/// solid obstacle node.
#[inline]
pub fn special_node_value<T: Real>(
    domain: &Domain<'_, T>,
    src: &[T],
    layout: Layout,
    params: &FluidParams<T>,
    collision: &Collision<T>,
    n: usize,
) -> [T; Q] {
    let (shape, bc, flags) = (&domain.shape, &domain.bc, domain.flags);
    if flags[n] == SOLID {
        return equilibrium(T::one(), [T::zero(); 2]);
    }
    let (x, y) = shape.coords(n);
    let mut f = gather_node_in(shape, src, layout, bc, &domain.profiles, flags, x, y);
    fluid_collide(
        &mut f,
        collision,
        collision.rates_unchecked(params.tau),
        params.force,
    );
    f
}

/// Redo the special nodes listed in `special` (sorted, all within rows y0..y1) with the general gather and
/// the fluid collision; solid obstacle nodes are set to the rest equilibrium (ρ = 1, u = 0).
pub fn fix_special_nodes<T: Real>(
    domain: &Domain<'_, T>,
    src: &[T],
    dst: &mut [&mut [T]; Q],
    y0: usize,
    params: &FluidParams<T>,
    collision: &Collision<T>,
    special: &[u32],
) {
    let base = y0 * domain.shape.nx;
    for &node in special {
        let n = node as usize;
        let f = special_node_value(domain, src, Layout::Collided, params, collision, n);
        for q in 0..Q {
            dst[q][n - base] = f[q];
        }
    }
}

/// Nodes covered by moving solids, in compressed-row form: node `nodes[k]` is covered by the shares
/// `shares[offsets[k] as usize .. offsets[k + 1] as usize]`, and its links to nodes that are not fully covered
/// are `links[k]` (read by the ΩΛ operator only; see [`OpenLinks`]).
#[derive(Clone, Copy, Debug)]
pub struct CoveredNodes<'a, T> {
    /// Covered node indices, increasing.
    pub nodes: &'a [u32],
    /// Share ranges, `nodes.len() + 1` entries, absolute indices into `shares`.
    pub offsets: &'a [u32],
    /// Every share of the lattice.
    pub shares: &'a [SolidShare<T>],
    /// Open links of each covered node (same length as `nodes`).
    pub links: &'a [OpenLinks],
}

/// The new post-collision populations of covered node `n` from `src` in `layout`: the general gather and the
/// partially-saturated collision with `shares` (and the node's open links `open`), the momentum handed to each
/// share written to `exchange`. A covered solid obstacle node is left alone (`None`, zero exchange).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn covered_node_value<T: Real>(
    domain: &Domain<'_, T>,
    src: &[T],
    layout: Layout,
    params: &PsmParams<T>,
    n: usize,
    shares: &[SolidShare<T>],
    open: OpenLinks,
    exchange: &mut [[T; 2]],
) -> Option<[T; Q]> {
    let (shape, bc, flags) = (&domain.shape, &domain.bc, domain.flags);
    if flags[n] == SOLID {
        for e in exchange.iter_mut() {
            *e = [T::zero(); 2];
        }
        return None;
    }
    let (x, y) = shape.coords(n);
    let mut f = gather_node_in(shape, src, layout, bc, &domain.profiles, flags, x, y);
    psm_collide_links(&mut f, params, shares, open, exchange);
    Some(f)
}

/// Redo the covered nodes of a band with the partially-saturated collision. `exchange` receives the momentum
/// handed to each share (force on the solid, lattice units); it covers the shares from
/// `covered.offsets[0]` on. Covered nodes that are solid obstacle nodes are skipped (zero exchange).
pub fn collide_covered_nodes<T: Real>(
    domain: &Domain<'_, T>,
    src: &[T],
    dst: &mut [&mut [T]; Q],
    y0: usize,
    params: &PsmParams<T>,
    covered: CoveredNodes<'_, T>,
    exchange: &mut [[T; 2]],
) {
    let (shape, bc, flags) = (&domain.shape, &domain.bc, domain.flags);
    let base = y0 * shape.nx;
    let nodes = covered.nodes;
    collide_covered_list(
        params,
        covered.offsets,
        covered.shares,
        covered.links,
        exchange,
        dst,
        |_, k| {
            let n = nodes[k] as usize;
            (flags[n] != SOLID).then(|| {
                let (x, y) = shape.coords(n);
                gather_node_in(
                    shape,
                    src,
                    Layout::Collided,
                    bc,
                    &domain.profiles,
                    flags,
                    x,
                    y,
                )
            })
        },
        |dst, k, f| {
            let n = nodes[k] as usize;
            for q in 0..Q {
                dst[q][n - base] = f[q];
            }
        },
    );
    // A covered solid obstacle node hands nothing to its solids (as [`covered_node_value`]).
    let first = covered.offsets.first().copied().unwrap_or(0) as usize;
    for (k, &node) in nodes.iter().enumerate() {
        if flags[node as usize] == SOLID {
            let (a, b) = (covered.offsets[k] as usize, covered.offsets[k + 1] as usize);
            for e in &mut exchange[a - first..b - first] {
                *e = [T::zero(); 2];
            }
        }
    }
}

/// The partially-saturated collision of a list of covered nodes, batched: node k (0 ≤ k < `links.len()`) has
/// the shares `shares[offsets[k] .. offsets[k + 1]]` (absolute indices) and open links `links[k]`;
/// `load(state, k)` gives its gathered populations (`None`: the node is left alone, its exchange entries
/// untouched), `store(state, k, f)` receives its post-collision populations, and `exchange` (entries from
/// `offsets[0]` on) the momentum handed to each share. Both closures reach the caller's `state` (e.g. the rows
/// the nodes are gathered from and stored into, in place): a node's store may come before a later node's load,
/// so in-place use needs nodes whose places are their own.
///
/// The nodes with one share and ε > 0 (the common case: [`lane_class`]) are queued by kernel and collided
/// [`PSM_LANES`] at a time by [`psm_collide_lanes`]; the others node by node by [`psm_collide_links`]. Every
/// node gets bitwise what [`psm_collide_links`] gives it (the batch kernel runs the same functions on the same
/// values); only the order in which `store` is called differs.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn collide_covered_list<T: Real, S: ?Sized>(
    params: &PsmParams<T>,
    offsets: &[u32],
    shares: &[SolidShare<T>],
    links: &[OpenLinks],
    exchange: &mut [[T; 2]],
    state: &mut S,
    mut load: impl FnMut(&S, usize) -> Option<[T; Q]>,
    mut store: impl FnMut(&mut S, usize, [T; Q]),
) {
    let mut queues: [LaneQueue<T>; 3] = core::array::from_fn(|_| LaneQueue {
        lanes: PsmLanes::default(),
        nodes: [0; PSM_LANES],
        len: 0,
    });
    for k in 0..links.len() {
        let Some(f) = load(state, k) else {
            continue;
        };
        push_node(
            &mut queues,
            k,
            f,
            params,
            offsets,
            shares,
            links,
            exchange,
            state,
            &mut store,
        );
    }
    for (q, class) in queues.iter_mut().zip(QUEUE_CLASSES) {
        if q.len > 0 {
            q.flush(class, params, offsets, exchange, state, &mut store);
        }
    }
}

/// The groups of a covered-row plan ([`plan_covered_row`]), in the order a plan lists them: the nodes of each
/// batch kernel ([`lane_class`]: ΩΛ partly covered, ΩΛ fully covered, the other operators), then the nodes that
/// take the node kernel ([`psm_collide_links`]: several shares, or a fraction that is not positive).
pub const PLAN_GROUPS: [Option<LaneClass>; 4] = [
    Some(LaneClass::LambdaPartial),
    Some(LaneClass::LambdaFull),
    Some(LaneClass::Operator),
    None,
];

/// The group of [`PLAN_GROUPS`] a node covered by `shares` belongs to.
#[inline(always)]
fn plan_group<T: Real>(params: &PsmParams<T>, shares: &[SolidShare<T>]) -> usize {
    match lane_class(params, shares) {
        Some(LaneClass::LambdaPartial) => 0,
        Some(LaneClass::LambdaFull) => 1,
        Some(LaneClass::Operator) => 2,
        None => 3,
    }
}

/// Plan the covered nodes of one pass row for [`collide_planned_row`]: node k (0 ≤ k < `offsets.len()` − 1) has
/// the shares `shares[offsets[k] .. offsets[k + 1]]` and is left out when `own(k)` is false (a special node,
/// computed elsewhere). Writes the indices k of the other nodes into `plan` grouped as [`PLAN_GROUPS`] lists
/// them, each group in increasing k, and returns the size of each group. `plan` needs room for every node of
/// the row (`offsets.len()` − 1 entries); indices that do not fit are not written, but still counted.
///
/// A plan depends only on the fractions (through [`lane_class`]), the operator and `own`: a caller may keep it
/// while those stand (between re-mappings, the fluid step's plans are reused at every step).
pub fn plan_covered_row<T: Real>(
    params: &PsmParams<T>,
    own: impl Fn(usize) -> bool,
    offsets: &[u32],
    shares: &[SolidShare<T>],
    plan: &mut [u32],
) -> [u32; PLAN_GROUPS.len()] {
    let n = offsets.len().saturating_sub(1);
    let group = |k: usize| {
        own(k).then(|| {
            plan_group(
                params,
                &shares[offsets[k] as usize..offsets[k + 1] as usize],
            )
        })
    };
    let mut counts = [0u32; PLAN_GROUPS.len()];
    for k in 0..n {
        if let Some(g) = group(k) {
            counts[g] += 1;
        }
    }
    let mut next = [0usize; PLAN_GROUPS.len()];
    for g in 1..next.len() {
        next[g] = next[g - 1] + counts[g - 1] as usize;
    }
    for k in 0..n {
        if let Some(g) = group(k) {
            if let Some(slot) = plan.get_mut(next[g]) {
                *slot = k as u32;
            }
            next[g] += 1;
        }
    }
    counts
}

/// The covered nodes of one pass row of an in-place (AA) step collided in place, from a plan
/// ([`plan_covered_row`], its group sizes `counts`): node k sits in column `columns[k]` of the row `row` (the
/// nine plane rows [`super::aa::plane_row`] hands out for it, after a bulk pass that left these nodes as they
/// were: [`super::aa::aa_bulk_rows_keeping`]), has the shares `shares[offsets[k] .. offsets[k + 1]]` and open
/// links `links[k]`; `exchange` starts at the row's first share (`offsets[0]`). Every planned node gets bitwise
/// what [`psm_collide_links`] gives it, stored where [`super::aa::store_in_rows`] stores it; nodes the plan
/// leaves out are not touched.
///
/// The nodes of each batch kernel are taken [`PSM_LANES`] at a time in the plan's order, their populations
/// gathered plane by plane (one loop over the lanes per plane, no branch on the node), collided by
/// [`psm_collide_lanes`] and scattered back plane by plane; a last batch that is not full repeats its first
/// node in the unused lanes, whose results are dropped. Each node reads and writes only places of its own, so
/// the order does not change any bit. The nodes of the last group take [`psm_collide_links`] one by one.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn collide_planned_row<T: Real>(
    params: &PsmParams<T>,
    row: &mut [&mut [T]; Q],
    step: AaStep,
    columns: &[u32],
    plan: &[u32],
    counts: [u32; PLAN_GROUPS.len()],
    offsets: &[u32],
    shares: &[SolidShare<T>],
    links: &[OpenLinks],
    exchange: &mut [[T; 2]],
) {
    let first = offsets.first().copied().unwrap_or(0) as usize;
    let mut lanes = PsmLanes::<T>::default();
    let rows = core::slice::from_mut(row);
    let mut store = RowStore { columns, step };
    let mut start = 0;
    for (group, count) in PLAN_GROUPS.iter().zip(counts) {
        let end = (start + count as usize).min(plan.len());
        let nodes = &plan[start..end];
        start = end;
        match *group {
            Some(class) => {
                for chunk in nodes.chunks(PSM_LANES) {
                    let k: [usize; PSM_LANES] = core::array::from_fn(|l| {
                        chunk.get(l).copied().unwrap_or(chunk[0]) as usize
                    });
                    let x: [usize; PSM_LANES] = core::array::from_fn(|l| columns[k[l]] as usize);
                    gather_lanes(&rows[0], step, &x, &mut lanes.f);
                    for l in 0..PSM_LANES {
                        lanes.share[l] = shares[offsets[k[l]] as usize];
                        lanes.open[l] = links[k[l]];
                    }
                    psm_collide_lanes(&mut lanes, PSM_LANES, params, class);
                    scatter_lanes(&mut rows[0], step, &x[..chunk.len()], &lanes.f);
                    for l in 0..chunk.len() {
                        exchange[offsets[k[l]] as usize - first] = lanes.exchange[l];
                    }
                }
            }
            None => {
                for &k in nodes {
                    let k = k as usize;
                    let f = load_from_rows(rows, step, 0, columns[k] as usize, 0);
                    collide_alone(
                        k, f, params, offsets, shares, links, exchange, rows, &mut store,
                    );
                }
            }
        }
    }
}

/// The lanes of the nodes in columns `x` of a pass row, plane by plane: `f[p][l]` where
/// [`super::aa::load_from_rows`] reads population p of node `x[l]`.
#[inline(always)]
fn gather_lanes<T: Real>(
    row: &[&mut [T]; Q],
    step: AaStep,
    x: &[usize; PSM_LANES],
    f: &mut [[T; PSM_LANES]; Q],
) {
    let nx = row[0].len();
    for (p, fp) in f.iter_mut().enumerate() {
        match step {
            AaStep::Local => {
                let plane = &row[OPPOSITE[p]];
                for (v, &x) in fp.iter_mut().zip(x) {
                    *v = plane[x];
                }
            }
            AaStep::Scatter => {
                let plane = &row[p];
                for (v, &x) in fp.iter_mut().zip(x) {
                    *v = plane[scatter_column(p, x, nx)];
                }
            }
        }
    }
}

/// Lanes gathered by [`gather_lanes`] stored back, plane by plane, where [`super::aa::store_in_rows`] stores
/// each node: the first `x.len()` lanes only.
#[inline(always)]
fn scatter_lanes<T: Real>(
    row: &mut [&mut [T]; Q],
    step: AaStep,
    x: &[usize],
    f: &[[T; PSM_LANES]; Q],
) {
    let nx = row[0].len();
    for (p, plane) in row.iter_mut().enumerate() {
        match step {
            AaStep::Local => {
                for (&v, &x) in f[p].iter().zip(x) {
                    plane[x] = v;
                }
            }
            AaStep::Scatter => {
                for (&v, &x) in f[OPPOSITE[p]].iter().zip(x) {
                    plane[scatter_column(p, x, nx)] = v;
                }
            }
        }
    }
}

/// Where the post-collision populations of a batched node go ([`push_node`], [`LaneQueue::flush`]): a closure
/// `(state, k, f)`, or the in-place row of [`collide_planned_row`]. A trait with an `#[inline(always)]` method
/// rather than a closure, which the compiler left out of line (a call per node).
trait NodeStore<T, S: ?Sized> {
    fn put(&mut self, state: &mut S, k: usize, f: [T; Q]);
}

impl<T, S: ?Sized, F: FnMut(&mut S, usize, [T; Q])> NodeStore<T, S> for F {
    #[inline(always)]
    fn put(&mut self, state: &mut S, k: usize, f: [T; Q]) {
        self(state, k, f)
    }
}

/// [`collide_planned_row`]'s store: node k at column `columns[k]` of the single pass row.
struct RowStore<'a> {
    columns: &'a [u32],
    step: AaStep,
}

impl<T: Real> NodeStore<T, [[&mut [T]; Q]]> for RowStore<'_> {
    #[inline(always)]
    fn put(&mut self, rows: &mut [[&mut [T]; Q]], k: usize, f: [T; Q]) {
        store_in_rows(rows, self.step, 0, self.columns[k] as usize, 0, &f);
    }
}

/// The lane kernels in the order of the queues of [`collide_covered_list`] ([`queue_slot`]).
const QUEUE_CLASSES: [LaneClass; 3] = [
    LaneClass::Operator,
    LaneClass::LambdaPartial,
    LaneClass::LambdaFull,
];

/// The queue of [`QUEUE_CLASSES`] a lane kernel uses.
#[inline(always)]
fn queue_slot(c: LaneClass) -> usize {
    match c {
        LaneClass::Operator => 0,
        LaneClass::LambdaPartial => 1,
        LaneClass::LambdaFull => 2,
    }
}

/// Node k with gathered populations `f`: queued for its batch kernel (flushed when the queue is full), or
/// collided alone by [`psm_collide_links`] and stored.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn push_node<T: Real, S: ?Sized>(
    queues: &mut [LaneQueue<T>; 3],
    k: usize,
    f: [T; Q],
    params: &PsmParams<T>,
    offsets: &[u32],
    shares: &[SolidShare<T>],
    links: &[OpenLinks],
    exchange: &mut [[T; 2]],
    state: &mut S,
    store: &mut impl NodeStore<T, S>,
) {
    let (a, b) = (offsets[k] as usize, offsets[k + 1] as usize);
    match lane_class(params, &shares[a..b]) {
        Some(class) => push_lane(
            queues, class, k, f, params, offsets, shares, links, exchange, state, store,
        ),
        None => collide_alone(k, f, params, offsets, shares, links, exchange, state, store),
    }
}

/// Node k with gathered populations `f` collided alone by [`psm_collide_links`] (its exchange written) and
/// stored.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn collide_alone<T: Real, S: ?Sized>(
    k: usize,
    mut f: [T; Q],
    params: &PsmParams<T>,
    offsets: &[u32],
    shares: &[SolidShare<T>],
    links: &[OpenLinks],
    exchange: &mut [[T; 2]],
    state: &mut S,
    store: &mut impl NodeStore<T, S>,
) {
    let first = offsets.first().copied().unwrap_or(0) as usize;
    let (a, b) = (offsets[k] as usize, offsets[k + 1] as usize);
    psm_collide_links(
        &mut f,
        params,
        &shares[a..b],
        links[k],
        &mut exchange[a - first..b - first],
    );
    store.put(state, k, f);
}

/// Node k, whose batch kernel is `class` ([`lane_class`]), with gathered populations `f`: queued, the queue
/// flushed when full.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn push_lane<T: Real, S: ?Sized>(
    queues: &mut [LaneQueue<T>; 3],
    class: LaneClass,
    k: usize,
    f: [T; Q],
    params: &PsmParams<T>,
    offsets: &[u32],
    shares: &[SolidShare<T>],
    links: &[OpenLinks],
    exchange: &mut [[T; 2]],
    state: &mut S,
    store: &mut impl NodeStore<T, S>,
) {
    let q = &mut queues[queue_slot(class)];
    let l = q.len;
    for (p, fp) in f.iter().enumerate() {
        q.lanes.f[p][l] = *fp;
    }
    q.lanes.share[l] = shares[offsets[k] as usize];
    q.lanes.open[l] = links[k];
    q.nodes[l] = k;
    q.len += 1;
    if q.len == PSM_LANES {
        q.flush(class, params, offsets, exchange, state, store);
    }
}

/// A batch being filled by [`collide_covered_list`]: the lanes, the list index of each lane's node, the fill.
struct LaneQueue<T> {
    lanes: PsmLanes<T>,
    nodes: [usize; PSM_LANES],
    len: usize,
}

impl<T: Real> LaneQueue<T> {
    /// Collide the first `len` lanes with the batch kernel `class` and hand the results out; empties the queue.
    #[inline(always)]
    fn flush<S: ?Sized>(
        &mut self,
        class: LaneClass,
        params: &PsmParams<T>,
        offsets: &[u32],
        exchange: &mut [[T; 2]],
        state: &mut S,
        store: &mut impl NodeStore<T, S>,
    ) {
        let first = offsets.first().copied().unwrap_or(0) as usize;
        // Unused lanes repeat lane 0 (finite values; their results are dropped).
        for l in self.len..PSM_LANES {
            for p in 0..Q {
                self.lanes.f[p][l] = self.lanes.f[p][0];
            }
            self.lanes.share[l] = self.lanes.share[0];
            self.lanes.open[l] = self.lanes.open[0];
        }
        psm_collide_lanes(&mut self.lanes, PSM_LANES, params, class);
        for l in 0..self.len {
            let k = self.nodes[l];
            store.put(state, k, core::array::from_fn(|p| self.lanes.f[p][l]));
            exchange[offsets[k] as usize - first] = self.lanes.exchange[l];
        }
        self.len = 0;
    }
}

/// The bulk pass of a band with the fluid's collision (BGK or TRT, with Guo forcing when a force is set):
/// [`bulk_rows`] with the collision chosen from `params` and `collision`. Each of the four variants is its own
/// branch-free loop. Inlined into its caller, so a caller compiled with wider vector instructions
/// (`#[target_feature]`) gets the whole loop in those instructions.
#[inline(always)]
pub fn bulk_band<T: Real>(
    shape: &LatticeShape,
    src: &[T],
    dst: &mut [&mut [T]; Q],
    y0: usize,
    y1: usize,
    params: &FluidParams<T>,
    collision: &Collision<T>,
) {
    let rates = collision.rates_unchecked(params.tau);
    let omega = rates.plus;
    let force = params.force;
    match (collision, params.forced()) {
        (Collision::Bgk, true) => bulk_rows(shape, src, dst, y0, y1, |f: &mut [T; Q]| {
            bgk_collide_forced(f, omega, force)
        }),
        (Collision::Bgk, false) => bulk_rows(shape, src, dst, y0, y1, |f: &mut [T; Q]| {
            bgk_collide(f, omega)
        }),
        (Collision::Trt(_), true) => bulk_rows(shape, src, dst, y0, y1, |f: &mut [T; Q]| {
            trt_collide_forced(f, rates, force)
        }),
        (Collision::Trt(_), false) => bulk_rows(shape, src, dst, y0, y1, |f: &mut [T; Q]| {
            trt_collide(f, rates)
        }),
    }
}

/// One complete update of the rows y0..y1 (bulk, special nodes, covered nodes), for a lattice without moving
/// solids. `special` must be the part of the [`classify_special_nodes`] list that lies in the band.
#[allow(clippy::too_many_arguments)]
pub fn step_band<T: Real>(
    domain: &Domain<'_, T>,
    src: &[T],
    dst: &mut [&mut [T]; Q],
    y0: usize,
    y1: usize,
    params: &FluidParams<T>,
    collision: &Collision<T>,
    special: &[u32],
) {
    bulk_band(&domain.shape, src, dst, y0, y1, params, collision);
    fix_special_nodes(domain, src, dst, y0, params, collision, special);
}

/// The sub-slice of a sorted node list lying in rows y0..y1.
pub fn nodes_in_rows<'a>(
    shape: &LatticeShape,
    nodes: &'a [u32],
    y0: usize,
    y1: usize,
) -> &'a [u32] {
    let (a, b) = ((y0 * shape.nx) as u32, (y1 * shape.nx) as u32);
    let lo = nodes.partition_point(|&n| n < a);
    let hi = nodes.partition_point(|&n| n < b);
    &nodes[lo..hi]
}

/// The open links ([`OpenLinks`]) of node (x, y): bit i set when the neighbour x + c_i is inside the lattice
/// (periodic wrap where the axis is periodic), not a solid obstacle node and not fully covered by the moving
/// solids (`full(j)` false). Neighbours outside the lattice lie behind a wall (a covered node is never on a
/// Zou–He side), so their links are closed.
pub fn open_links<T: Real>(
    shape: &LatticeShape,
    bc: &Boundaries<T>,
    flags: &[u8],
    x: usize,
    y: usize,
    full: impl Fn(usize) -> bool,
) -> OpenLinks {
    let periodic = bc.periodic_axes();
    let mut open: OpenLinks = 0;
    for q in 1..Q {
        if let Neighbour::Node(j) = shape.neighbour(x, y, q, periodic) {
            if flags[j] != SOLID && !full(j) {
                open |= 1 << q;
            }
        }
    }
    open
}

/// The density of every node of rows `y0..y1` as the step about to run gathers it from `src` in `layout`:
/// `out[(y − y0) nx + x]` = [`density`] of [`gather_node_in`] at (x, y), bitwise, for every node that is not
/// a solid obstacle (which gets 1, like [`gathered_moments_in`]). `special` must be the part of the
/// [`classify_special_nodes`] list that lies in the rows (sorted), and `out` at least `(y1 − y0) nx` long.
///
/// The rows are summed branch-free, as the bulk pass streams them (periodic pull in [`Layout::Collided`], the
/// node's own reversed slots in [`Layout::Streamed`]); only the special nodes, where that differs from the
/// general gather, are gathered one by one. So a whole band costs about a read-only sweep of its rows, where
/// gathering node by node costs nine scattered loads (and nine flag checks) per node. Reads only `src`.
pub fn gathered_densities<T: Real>(
    domain: &Domain<'_, T>,
    src: &[T],
    layout: Layout,
    y0: usize,
    y1: usize,
    special: &[u32],
    out: &mut [T],
) {
    let shape = &domain.shape;
    let nx = shape.nx;
    let s = planes(shape, src);
    for y in y0..y1 {
        let row = &mut out[(y - y0) * nx..(y - y0 + 1) * nx];
        match layout {
            Layout::Collided => {
                for x in [0, nx - 1] {
                    row[x] = density(&pull_periodic(shape, &s, x, y));
                }
                if nx < 3 {
                    continue;
                }
                let n = nx - 2;
                // The bulk pass's pull ([`pull_row`]).
                let [s0, s1, s2, s3, s4, s5, s6, s7, s8] = pull_row(shape, &s, y);
                for (k, r) in row[1..1 + n].iter_mut().enumerate() {
                    *r = density(&[
                        s0[k], s1[k], s2[k], s3[k], s4[k], s5[k], s6[k], s7[k], s8[k],
                    ]);
                }
            }
            Layout::Streamed => {
                // f_q(x) sits in slot q̄ of x itself (see [`gather_node_in`]).
                let r0 = y * nx;
                let p: [&[T]; Q] = core::array::from_fn(|q| &s[OPPOSITE[q]][r0..r0 + nx]);
                for (k, r) in row.iter_mut().enumerate() {
                    *r = density(&[
                        p[0][k], p[1][k], p[2][k], p[3][k], p[4][k], p[5][k], p[6][k], p[7][k],
                        p[8][k],
                    ]);
                }
            }
        }
    }
    for &n in special {
        let n = n as usize;
        let (x, y) = shape.coords(n);
        out[(y - y0) * nx + x] = if domain.flags[n] == SOLID {
            T::one()
        } else {
            density(&gather_node_in(
                shape,
                src,
                layout,
                &domain.bc,
                &domain.profiles,
                domain.flags,
                x,
                y,
            ))
        };
    }
}

/// ΩΛ's wall gradients ([`SolidShare::wall_gradient`]) of the covered nodes `nodes` (node k has the shares
/// `shares[offsets[k] − offsets[0] .. offsets[k + 1] − offsets[0]]`, the open links `links[k]`, and each
/// share s the unit normal `normals[s − offsets[0]]` of its solid's surface), from `rho_at(n)`, the density
/// of node n as the step about to run gathers it ([`gathered_densities`], or the density of
/// [`gather_node_in`]): at a partly covered node (0 < Σε < 1 − [`super::collide::LAMBDA_FULL_GAP`], not an
/// obstacle) each share gets [`super::collide::wall_gradient`] of the node's density and of the densities of
/// its axis neighbours whose links are open (not fully covered, not obstacles, not beyond a wall); every
/// other share gets zero. `rho_at` is asked only for those nodes. Any split of the nodes gives the same
/// values.
#[allow(clippy::too_many_arguments)]
pub fn wall_gradients<T: Real>(
    domain: &Domain<'_, T>,
    nodes: &[u32],
    offsets: &[u32],
    links: &[OpenLinks],
    normals: &[[T; 2]],
    shares: &mut [SolidShare<T>],
    rho_at: impl Fn(usize) -> T,
) {
    let (shape, bc, flags) = (&domain.shape, &domain.bc, domain.flags);
    let periodic = bc.periodic_axes();
    let first = offsets.first().copied().unwrap_or(0) as usize;
    for (k, &node) in nodes.iter().enumerate() {
        let (a, b) = (offsets[k] as usize - first, offsets[k + 1] as usize - first);
        let n = node as usize;
        let mut eps_sum = T::zero();
        for s in &shares[a..b] {
            eps_sum += s.fraction;
        }
        let partial = flags[n] != SOLID
            && eps_sum > T::zero()
            && !super::collide::lambda_fully_covered(eps_sum);
        if !partial {
            for s in &mut shares[a..b] {
                s.wall_gradient = [T::zero(); 2];
            }
            continue;
        }
        let (x, y) = shape.coords(n);
        let rho = rho_at(n);
        let neighbours: [Option<T>; 4] = core::array::from_fn(|i| {
            let q = i + 1;
            if links[k] & (1 << q) == 0 {
                return None;
            }
            match shape.neighbour(x, y, q, periodic) {
                Neighbour::Node(j) => Some(rho_at(j)),
                _ => None,
            }
        });
        for (s, normal) in shares[a..b].iter_mut().zip(&normals[a..b]) {
            s.wall_gradient = super::collide::wall_gradient(rho, neighbours, *normal);
        }
    }
}
