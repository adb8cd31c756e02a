//! Fluid index-arithmetic harness bodies: the lattice layout ([`LatticeShape`]), neighbour arithmetic, the
//! branch-free bulk passes ([`bulk_rows`], and [`scatter_row`] / [`local_row`] of the in-place scheme) and band
//! splitting ([`nodes_in_rows`], [`band_mut`]).
//!
//! Each body takes its inputs from a [`Chooser`] and a size bound `max` (nx, ny ∈ 1..=max) and asserts that
//! every index the kernel computes is in bounds and has the expected value. Overflow freedom comes from
//! running the kernels with overflow checks on (the test profile, and Kani's own checks): any overflow panics
//! and fails the run. Under `for_all` each body is enumerated exhaustively over its bounded choices; under
//! Kani the same body is a proof over all values in the same ranges.
//!
//! Each body's documentation ends with its **bound** (what `max` and the other choices range over), its
//! **coverage** (whether the bounded-exhaustive run covers that whole bounded domain, or enumerates a table of
//! values standing for a larger one) and its **Kani** side (the wrapper in `tests/proofs.rs`, or why there is
//! none).
use crate::{Chooser, INTERESTING_F64};
use lbdem_kernels::fluid::aa::{
    local_row, plane_row, post_collision_offset, scatter_row, AaStep, Layout,
};
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition, SideProfiles};
use lbdem_kernels::fluid::collide::{
    Collision, PsmParams, SolidOperator, SolidShare, Weighting, ALL_LINKS_OPEN,
};
use lbdem_kernels::fluid::d2q9::equilibrium;
use lbdem_kernels::fluid::d2q9::{OPPOSITE, Q, VELOCITIES};
use lbdem_kernels::fluid::lattice::{LatticeShape, Neighbour, ShapeError, Side};
use lbdem_kernels::fluid::step::{
    band_mut, bulk_rows, classify_special_nodes, collide_covered_nodes, nodes_in_rows, planes,
    planes_mut, step_band, CoveredNodes, Domain, FluidParams, FLUID, SOLID,
};

/// Element sizes the layout is used with (f32, f64).
pub const ELEMENT_BYTES: [usize; 2] = [4, 8];

fn choose_shape(c: &mut dyn Chooser, max: usize) -> LatticeShape {
    let nx = c.usize_in(1, max);
    let ny = c.usize_in(1, max);
    let eb = ELEMENT_BYTES[c.usize_in(0, ELEMENT_BYTES.len() - 1)];
    let shape = LatticeShape::new(nx, ny, eb);
    assert!(shape.is_ok(), "small shapes are accepted");
    shape.unwrap_or(LatticeShape {
        nx: 1,
        ny: 1,
        stride: 1,
    })
}

/// `LatticeShape::new` accepts every nx, ny ∈ 1..=max for both element sizes, refuses empty lattices, and its
/// padded stride holds a whole plane and puts plane q at q × 320 bytes modulo 4 KiB (distinct for all nine).
/// Choices: nx, ny, element size. Runs: max² × 2.
/// Bound: nx, ny ≤ max (12 in the tests), element sizes 4 and 8 (the only two the kernels use).
/// Coverage: the whole bounded domain. Kani: same bound.
pub fn shape_layout(c: &mut dyn Chooser, max: usize) {
    let nx = c.usize_in(1, max);
    let ny = c.usize_in(1, max);
    let eb = ELEMENT_BYTES[c.usize_in(0, ELEMENT_BYTES.len() - 1)];
    assert_eq!(LatticeShape::new(0, ny, eb), Err(ShapeError::Empty));
    assert_eq!(LatticeShape::new(nx, 0, eb), Err(ShapeError::Empty));
    let shape = LatticeShape::new(nx, ny, eb).expect("small shapes are accepted");
    assert_eq!((shape.nx, shape.ny), (nx, ny));
    assert_eq!(shape.nodes(), nx * ny);
    assert!(shape.stride >= shape.nodes(), "a plane fits in its stride");
    assert_eq!(shape.buffer_len(), Q * shape.stride);
    let stride_bytes = shape.stride.checked_mul(eb).expect("no overflow");
    assert_eq!(
        stride_bytes % 4096,
        320,
        "planes are offset by 320 bytes modulo 4 KiB"
    );
}

/// `index`, `coords` and `offset` for every node and direction: index < nodes, coords inverts index, and the
/// offset lies inside plane q (q·stride ≤ offset < q·stride + nodes ≤ buffer_len).
/// Choices: nx, ny, element size, x, y, q. Runs: 2 Q (Σ_{n=1..max} n)².
/// Bound: nx, ny ≤ max. Coverage: the whole bounded domain (every node and direction). Kani: same bound.
pub fn index_coords_offset(c: &mut dyn Chooser, max: usize) {
    let shape = choose_shape(c, max);
    let x = c.usize_in(0, shape.nx - 1);
    let y = c.usize_in(0, shape.ny - 1);
    let q = c.usize_in(0, Q - 1);
    let index = shape.index(x, y);
    assert!(index < shape.nodes());
    assert_eq!(shape.coords(index), (x, y));
    let offset = shape.offset(q, index);
    assert!(offset >= q * shape.stride && offset < q * shape.stride + shape.nodes());
    assert!(offset < shape.buffer_len());
}

/// The expected neighbour along one axis: `v + d` wrapped if periodic, else the side crossed.
fn expected_axis(
    v: usize,
    d: i32,
    n: usize,
    periodic: bool,
    low: Side,
    high: Side,
) -> Result<usize, Side> {
    let t = v as i64 + d as i64;
    if (0..n as i64).contains(&t) {
        Ok(t as usize)
    } else if periodic {
        Ok(t.rem_euclid(n as i64) as usize)
    } else if t < 0 {
        Err(low)
    } else {
        Err(high)
    }
}

/// `neighbour` and `upstream` for every node, direction and periodicity: the neighbour is (x, y) + c_q wrapped
/// on periodic axes and in bounds, or `Outside` naming exactly the non-periodic sides crossed; `upstream` is
/// the neighbour along −c_q. Choices: nx, ny, element size, x, y, q, periodic x, periodic y.
/// Runs: 8 Q (Σ_{n=1..max} n)².
/// Bound: nx, ny ≤ max. Coverage: the whole bounded domain (every node, direction and periodicity). Kani: same
/// bound.
pub fn neighbour_and_upstream(c: &mut dyn Chooser, max: usize) {
    let shape = choose_shape(c, max);
    let x = c.usize_in(0, shape.nx - 1);
    let y = c.usize_in(0, shape.ny - 1);
    let q = c.usize_in(0, Q - 1);
    let periodic = [c.boolean(), c.boolean()];
    let v = VELOCITIES[q];
    let ex = expected_axis(x, v[0], shape.nx, periodic[0], Side::West, Side::East);
    let ey = expected_axis(y, v[1], shape.ny, periodic[1], Side::South, Side::North);
    let got = shape.neighbour(x, y, q, periodic);
    match (ex, ey) {
        (Ok(a), Ok(b)) => {
            assert_eq!(got, Neighbour::Node(shape.index(a, b)));
            assert!(shape.index(a, b) < shape.nodes());
        }
        (ex, ey) => assert_eq!(
            got,
            Neighbour::Outside {
                x: ex.err(),
                y: ey.err()
            }
        ),
    }
    assert_eq!(
        shape.upstream(x, y, q, periodic),
        shape.neighbour(x, y, OPPOSITE[q], periodic)
    );
}

/// The value stored at (q, node) of the test buffer: unique and exact in f64.
fn tag(q: usize, node: usize) -> f64 {
    (q * 100_000 + node) as f64
}

/// `bulk_rows` over a band y0..y1 of every lattice up to `max`: all its slice arithmetic stays in bounds (a
/// violation panics), and every stored population is the periodic pull src_q((x, y) − c_q) (checked with a
/// buffer whose entries name their own plane and node, and an identity collision).
/// Choices: nx, ny, y0 ∈ 0..=ny, y1 ∈ y0..=ny (f64 only). Runs: max Σ_{n=1..max} (n+1)(n+2)/2.
/// Bound: nx, ny ≤ max, every band. Coverage: the whole bounded domain of sizes and bands; the populations are
/// tags and the collision is the identity, so this proves the index arithmetic and the pull, not the collision
/// (the property tests check that). Kani: none (see `tests/proofs.rs`: page-padded buffers are far beyond
/// practical unwinding).
pub fn bulk_rows_band(c: &mut dyn Chooser, max: usize) {
    let nx = c.usize_in(1, max);
    let ny = c.usize_in(1, max);
    let shape = LatticeShape::for_type::<f64>(nx, ny).expect("small shapes are accepted");
    let y0 = c.usize_in(0, ny);
    let y1 = c.usize_in(y0, ny);
    let mut src = vec![f64::NAN; shape.buffer_len()];
    for (q, plane) in planes_mut(&shape, &mut src).into_iter().enumerate() {
        for (node, v) in plane.iter_mut().enumerate() {
            *v = tag(q, node);
        }
    }
    let mut dst = vec![f64::NAN; shape.buffer_len()];
    let mut band = band_mut(&shape, planes_mut(&shape, &mut dst), y0, y1);
    for plane in band.iter() {
        assert_eq!(plane.len(), (y1 - y0) * nx);
    }
    bulk_rows(&shape, &src, &mut band, y0, y1, |_f: &mut [f64; Q]| {});
    let out = planes(&shape, &dst);
    for y in 0..ny {
        for x in 0..nx {
            let node = shape.index(x, y);
            for (q, plane) in out.iter().enumerate() {
                if (y0..y1).contains(&y) {
                    let Neighbour::Node(from) = shape.upstream(x, y, q, [true, true]) else {
                        panic!("a periodic lattice has no outside");
                    };
                    assert_eq!(plane[node], tag(q, from), "pull of q={q} at ({x},{y})");
                } else {
                    assert!(plane[node].is_nan(), "rows outside the band are untouched");
                }
            }
        }
    }
}

/// The in-place (AA) bulk pass over every lattice up to `max`, split into two bands of rows at `ym` and run
/// band by band: the rows handed to the kernel by [`plane_row`] cover each plane row exactly once, all slice
/// arithmetic stays in bounds (a violation panics), and with an identity collision the scatter step leaves
/// P_i(x) = src_i(x − c_i) (one periodic pull) where [`post_collision_offset`] says the streamed layout keeps
/// it, and the local step after it leaves src_i(x − 2 c_i) (two pulls) in the plain layout.
/// Choices: nx, ny, ym ∈ 0..=ny (f64 only). Runs: max Σ_{n=1..max} (n + 1).
/// Bound: nx, ny ≤ max, every split into two bands. Coverage: the whole bounded domain (splits into more bands
/// are unions of two-band splits row-wise; the pass treats each band independently). Identity collision, as
/// above. Kani: none (same reason as `bulk_rows_band`).
pub fn aa_bulk_rows_band(c: &mut dyn Chooser, max: usize) {
    let nx = c.usize_in(1, max);
    let ny = c.usize_in(1, max);
    let ym = c.usize_in(0, ny);
    let shape = LatticeShape::for_type::<f64>(nx, ny).expect("small shapes are accepted");
    let mut buf = vec![f64::NAN; shape.buffer_len()];
    for (q, plane) in planes_mut(&shape, &mut buf).into_iter().enumerate() {
        for (node, v) in plane.iter_mut().enumerate() {
            *v = tag(q, node);
        }
    }
    let flags = vec![FLUID; shape.nodes()];
    let pull = |x: usize, y: usize, q: usize, times: usize| {
        let v = VELOCITIES[q];
        let fx = (x as i64 - times as i64 * v[0] as i64).rem_euclid(nx as i64) as usize;
        let fy = (y as i64 - times as i64 * v[1] as i64).rem_euclid(ny as i64) as usize;
        shape.index(fx, fy)
    };
    for step in [AaStep::Scatter, AaStep::Local] {
        {
            let mut rows: Vec<Vec<Option<&mut [f64]>>> = planes_mut(&shape, &mut buf)
                .into_iter()
                .map(|plane| plane.chunks_mut(nx).map(Some).collect())
                .collect();
            let mut table: Vec<[&mut [f64]; Q]> = (0..ny)
                .map(|y| {
                    core::array::from_fn(|p| {
                        let r = plane_row(step, p, y, ny);
                        assert!(r < ny);
                        rows[p][r]
                            .take()
                            .expect("each plane row is handed out once")
                    })
                })
                .collect();
            assert!(
                rows.iter().flatten().all(Option::is_none),
                "every plane row is handed out"
            );
            let (lower, upper) = table.split_at_mut(ym);
            let identity = |_f: &mut [f64; Q]| {};
            for rows in [lower, upper] {
                for r in rows.iter_mut() {
                    assert!(r.iter().all(|row| row.len() == nx));
                    match step {
                        AaStep::Scatter => scatter_row(r, &identity),
                        AaStep::Local => local_row(r, &identity),
                    }
                }
            }
        }
        for y in 0..ny {
            for x in 0..nx {
                let node = shape.index(x, y);
                for q in 0..Q {
                    let (layout, times) = match step {
                        AaStep::Scatter => (Layout::Streamed, 1),
                        AaStep::Local => (Layout::Collided, 2),
                    };
                    let at = post_collision_offset(&shape, [true, true], &flags, layout, node, q);
                    assert!(at < shape.buffer_len());
                    assert_eq!(buf[at], tag(q, pull(x, y, q, times)), "q={q} at ({x},{y})");
                }
            }
        }
    }
}

/// `nodes_in_rows`: for a sorted node list (every `step`-th node from `first`), the sub-list of a band holds
/// exactly the listed nodes of rows y0..y1, and the sub-lists of two adjacent bands y0..ym, ym..y1 concatenate
/// to the sub-list of y0..y1 (band splitting loses and duplicates nothing).
/// Choices: nx, ny, step ∈ 1..=3, first ∈ 0..step, y0, ym ∈ y0..=ny, y1 ∈ ym..=ny.
/// Bound: nx, ny ≤ max. Coverage: every band triple, but not every sorted list: the lists are the arithmetic
/// progressions above (all nodes, every second, every third, from each start), a family standing for sorted
/// lists. Kani: the same body with nx, ny ≤ 4 (it loops over every node).
pub fn nodes_in_rows_split(c: &mut dyn Chooser, max: usize) {
    let nx = c.usize_in(1, max);
    let ny = c.usize_in(1, max);
    let shape = LatticeShape::for_type::<f64>(nx, ny).expect("small shapes are accepted");
    let step = c.usize_in(1, 3);
    let first = c.usize_in(0, step - 1);
    let y0 = c.usize_in(0, ny);
    let ym = c.usize_in(y0, ny);
    let y1 = c.usize_in(ym, ny);
    let list: Vec<u32> = (first..shape.nodes())
        .step_by(step)
        .map(|n| n as u32)
        .collect();
    let whole = nodes_in_rows(&shape, &list, y0, y1);
    let expected: Vec<u32> = list
        .iter()
        .copied()
        .filter(|&n| (y0 * nx..y1 * nx).contains(&(n as usize)))
        .collect();
    assert_eq!(whole, &expected[..]);
    let lower = nodes_in_rows(&shape, &list, y0, ym);
    let upper = nodes_in_rows(&shape, &list, ym, y1);
    assert_eq!(lower.len() + upper.len(), whole.len());
    assert_eq!(lower, &whole[..lower.len()]);
    assert_eq!(upper, &whole[lower.len()..]);
}

/// Lattice sizes at the edges of what [`LatticeShape::new`] must accept or refuse (page and `u32` limits),
/// for the bounded-exhaustive run of [`shape_new_any_size`]; under Kani every size is taken instead.
pub const EDGE_SIZES: [usize; 10] = [
    1,
    2,
    511,
    4096,
    65_535,
    65_536,
    u32::MAX as usize,
    u32::MAX as usize + 1,
    usize::MAX / 2,
    usize::MAX,
];

/// `LatticeShape::new` for nx, ny anywhere in 1..=usize::MAX (`sizes = None`, for Kani) or from a table
/// (`sizes = Some(..)`): it never panics or overflows; it accepts exactly the sizes whose node count fits `u32`
/// and whose padded buffer length fits `usize` (checked independently in `u128`), with the stride
/// ⌈n/page⌉·page + pad (page = 4096 B, pad = 320 B, in elements); for accepted sizes the far-corner node's
/// index, coordinates, last offset and neighbours in every direction are computed in bounds.
/// Bound: none under Kani (every nx, ny ∈ 1..=usize::MAX). Coverage of the bounded-exhaustive run: the table
/// [`EDGE_SIZES`] only (every pair of its sizes), standing for the whole range. Kani: every size.
pub fn shape_new_any_size(c: &mut dyn Chooser, sizes: Option<&[usize]>) {
    let size = |c: &mut dyn Chooser| match sizes {
        Some(table) => table[c.usize_in(0, table.len() - 1)],
        None => c.usize_in(1, usize::MAX),
    };
    let nx = size(c);
    let ny = size(c);
    let eb = ELEMENT_BYTES[c.usize_in(0, ELEMENT_BYTES.len() - 1)];
    let n = nx as u128 * ny as u128;
    let (page, pad) = ((4096 / eb) as u128, (320 / eb) as u128);
    let stride = n.div_ceil(page) * page + pad;
    let fits = n <= u32::MAX as u128 && stride * Q as u128 <= usize::MAX as u128;
    match LatticeShape::new(nx, ny, eb) {
        Ok(shape) => {
            assert!(fits, "accepted a size that does not fit");
            assert_eq!(shape.stride as u128, stride);
            assert_eq!(shape.nodes() as u128, n);
            assert_eq!(shape.buffer_len() as u128, stride * Q as u128);
            let last = shape.index(nx - 1, ny - 1);
            assert_eq!(last as u128, n - 1);
            assert_eq!(shape.coords(last), (nx - 1, ny - 1));
            assert!(shape.offset(Q - 1, last) < shape.buffer_len());
            for q in 0..Q {
                for periodic in [[false, false], [true, true]] {
                    if let Neighbour::Node(j) = shape.neighbour(nx - 1, ny - 1, q, periodic) {
                        assert!(j < shape.nodes());
                    }
                }
            }
        }
        Err(e) => {
            assert_eq!(e, ShapeError::TooLarge);
            assert!(!fits, "refused a size that fits");
        }
    }
}

/// The side conditions of one axis, by index: 0 is a periodic pair; 1..=9 are the (low, high) pairs of
/// wall, pressure and velocity sides.
pub const AXIS_CONDITIONS: usize = 10;

fn axis_conditions(k: usize) -> (SideCondition<f64>, SideCondition<f64>) {
    let one = |k: usize| match k {
        0 => SideCondition::Wall,
        1 => SideCondition::Pressure { density: 1.01 },
        _ => SideCondition::Velocity {
            velocity: [0.02, -0.01],
        },
    };
    if k == 0 {
        (SideCondition::Periodic, SideCondition::Periodic)
    } else {
        (one((k - 1) / 3), one((k - 1) % 3))
    }
}

/// The fix-up passes' index arithmetic: for every lattice up to `max`, every combination of side conditions
/// (periodic, wall, Zou–He pressure, Zou–He velocity on each side, so every corner rule), no obstacle or one
/// obstacle node anywhere, and every split of the rows into two bands y0..ym, ym..ny:
/// `classify_special_nodes` lists sorted in-range nodes, and `step_band` + `collide_covered_nodes` (every node
/// covered) over each band, with that band's `nodes_in_rows` lists, stay in bounds and store finite values.
/// `classify_special_nodes` is also checked against an independent classification (an obstacle node, a node on
/// a non-periodic side, or a node with an obstacle upstream along some direction, with wrap on periodic axes).
/// Choices: nx, ny, x-axis conditions, y-axis conditions, obstacle node (or none), ym.
/// Runs: 100 Σ_{nx, ny ≤ max} (nx ny + 1)(ny + 1).
/// Bound: nx, ny ≤ max (6 in the tests), at most one obstacle node, two bands. Coverage: the whole bounded
/// domain of sizes, side kinds, obstacle positions and splits, but one value per side kind (density 1.01,
/// velocity (0.02, −0.01)): the values do not enter the index arithmetic. Kani: none (same reason as
/// `bulk_rows_band`).
pub fn fix_passes_in_bounds(c: &mut dyn Chooser, max: usize) {
    let nx = c.usize_in(1, max);
    let ny = c.usize_in(1, max);
    let shape = LatticeShape::for_type::<f64>(nx, ny).expect("small shapes are accepted");
    let (west, east) = axis_conditions(c.usize_in(0, AXIS_CONDITIONS - 1));
    let (south, north) = axis_conditions(c.usize_in(0, AXIS_CONDITIONS - 1));
    let bc = Boundaries {
        west,
        east,
        south,
        north,
    };
    assert_eq!(bc.validate(), Ok(()));
    let obstacle = c.usize_in(0, shape.nodes()); // `nodes()` means none
    let ym = c.usize_in(0, ny);
    let flags: Vec<u8> = (0..shape.nodes())
        .map(|n| if n == obstacle { SOLID } else { FLUID })
        .collect();
    let domain = Domain {
        shape,
        bc,
        profiles: SideProfiles::none(),
        flags: &flags,
    };
    let mut special = vec![u32::MAX; shape.nodes()];
    let count = classify_special_nodes(&shape, &bc, &flags, &mut special);
    special.truncate(count);
    // The independent classification, in node order (so sorted, no repeats).
    let periodic = bc.periodic_axes();
    let expected: Vec<u32> = (0..shape.nodes())
        .filter(|&n| {
            let (x, y) = (n % nx, n / nx);
            let on_side = |v: usize, len: usize, p: bool| !p && (v == 0 || v + 1 == len);
            let obstacle_upstream = VELOCITIES.iter().any(|v| {
                let ux = expected_axis(x, -v[0], nx, periodic[0], Side::West, Side::East);
                let uy = expected_axis(y, -v[1], ny, periodic[1], Side::South, Side::North);
                matches!((ux, uy), (Ok(a), Ok(b)) if flags[a + nx * b] == SOLID)
            });
            flags[n] == SOLID
                || on_side(x, nx, periodic[0])
                || on_side(y, ny, periodic[1])
                || obstacle_upstream
        })
        .map(|n| n as u32)
        .collect();
    assert_eq!(special, expected, "special nodes");
    let mut src = vec![0.0; shape.buffer_len()];
    let feq = equilibrium(1.0, [0.05, 0.02]);
    for (q, plane) in planes_mut(&shape, &mut src).into_iter().enumerate() {
        plane.fill(feq[q]);
    }
    let nodes: Vec<u32> = (0..shape.nodes() as u32).collect();
    let offsets: Vec<u32> = (0..=shape.nodes() as u32).collect();
    let links = vec![ALL_LINKS_OPEN; shape.nodes()];
    let shares = vec![
        SolidShare {
            fraction: 0.5,
            velocity: [0.0, 0.01],
            wall_gradient: Default::default(),
        };
        shape.nodes()
    ];
    let mut exchange = vec![[f64::NAN; 2]; shape.nodes()];
    let fluid = FluidParams {
        tau: 0.8,
        force: [1e-4, 0.0],
    };
    let psm = PsmParams {
        tau: 0.8,
        weighting: Weighting::NobleTorczynski,
        force: [1e-4, 0.0],
        solid: SolidOperator::NonEquilibriumBounceBack,
        collision: Collision::Bgk,
        lambda: Default::default(),
    };
    let mut dst = vec![f64::NAN; shape.buffer_len()];
    for (y0, y1) in [(0, ym), (ym, ny)] {
        let mut band = band_mut(&shape, planes_mut(&shape, &mut dst), y0, y1);
        let in_band = nodes_in_rows(&shape, &special, y0, y1);
        step_band(
            &domain,
            &src,
            &mut band,
            y0,
            y1,
            &fluid,
            &Collision::Bgk,
            in_band,
        );
        let (lo, hi) = (y0 * nx, y1 * nx);
        let covered = CoveredNodes {
            nodes: &nodes[lo..hi],
            offsets: &offsets[lo..=hi],
            shares: &shares,
            links: &links[lo..hi],
        };
        collide_covered_nodes(
            &domain,
            &src,
            &mut band,
            y0,
            &psm,
            covered,
            &mut exchange[lo..hi],
        );
    }
    for plane in planes(&shape, &dst) {
        assert!(plane.iter().all(|v| v.is_finite()), "every node stored");
    }
    assert!(exchange
        .iter()
        .all(|e| e[0].is_finite() && e[1].is_finite()));
}

/// `Boundaries::validate` over the interesting floats ([`INTERESTING_F64`]): one chosen side carries a
/// pressure (each interesting density) or velocity (each pair of interesting components) condition, the
/// others are walls; it is accepted exactly when the density is finite and positive, or both velocity
/// components are finite with magnitude below 1. Then periodic pairing: each side periodic or a wall, accepted
/// exactly when both sides of each axis agree.
/// Choices: side, kind, value(s) (4 × (10 + 100) runs), then 2⁴ pairing runs: 456 in all.
/// Bound: one non-wall side. Coverage: the bounded-exhaustive run enumerates the table [`INTERESTING_F64`]
/// for each value, not every `f64`. Kani: every value is any `f64` ([`Chooser::float_from`]).
pub fn boundary_validation(c: &mut dyn Chooser) {
    let v = |c: &mut dyn Chooser| c.float_from(&INTERESTING_F64);
    let mut sides = [SideCondition::<f64>::Wall; 4];
    let expected_ok;
    if c.boolean() {
        let side = c.usize_in(0, 3);
        if c.boolean() {
            let density = v(c);
            sides[side] = SideCondition::Pressure { density };
            expected_ok = density.is_finite() && density > 0.0;
        } else {
            let velocity = [v(c), v(c)];
            sides[side] = SideCondition::Velocity { velocity };
            expected_ok = velocity.iter().all(|u| u.is_finite() && u.abs() < 1.0);
        }
    } else {
        for s in sides.iter_mut() {
            if c.boolean() {
                *s = SideCondition::Periodic;
            }
        }
        let periodic = sides.map(|s| s == SideCondition::Periodic);
        expected_ok = periodic[0] == periodic[1] && periodic[2] == periodic[3];
    }
    let [west, east, south, north] = sides;
    let bc = Boundaries {
        west,
        east,
        south,
        north,
    };
    assert_eq!(bc.validate().is_ok(), expected_ok, "{bc:?}");
}
