//! DEM broad-phase index-arithmetic harness bodies (`lbdem_kernels::dem::grid`). Each is run exhaustively over
//! its bounded choices by `tests/dem_proofs.rs` and is a Kani proof under `cfg(kani)` (module `kani_proofs`
//! below).
//!
//! * [`cell_index_in_bounds`]: for every grid up to 6 × 6 and every cell, `cell_index` is < nx·ny and the
//!   clamped neighbour spans stay inside the grid and contain the cell. Bound: nx, ny ≤ 6. The exhaustive run
//!   covers that whole bounded domain; so does Kani.
//! * [`counting_sort_is_a_permutation`]: for every grid up to 3 × 3 (cell size 1, origin 0) and up to 3
//!   particles, `build_cell_grid` returns offsets that are monotone from 0 to N, a permutation of the
//!   particles, each particle in the cell an independent oracle gives it (the count of cell boundaries at or
//!   below the coordinate, clamped to the grid; NaN and −∞ in cell 0), ascending within a cell; and
//!   `candidate_pairs` with an unbounded reach lists exactly the pairs i < j in the same or adjacent oracle
//!   cells at a finite distance (NaN or infinite separations fail the bounding-circle test), each once,
//!   sorted. Bound: nx, ny ≤ 3, N ≤ 3. The exhaustive run does **not** cover every coordinate: it enumerates
//!   the table [`COORDINATES`] (inside, on a cell edge, on the far edge, far outside, NaN, ±∞) for each
//!   coordinate; under Kani every coordinate is any `f64` ([`Chooser::float_from`]).
//! * [`history_merge_is_exact`]: for every pair of subsets of a 5-pair universe (as sorted lists),
//!   `carry_contact_history` gives each persisting pair its old value, every new pair zero, and counts the
//!   carried pairs; it refuses short value buffers instead of indexing out of bounds. Bound: lists drawn from
//!   the 5-pair universe. The exhaustive run covers that whole bounded domain (all 32 × 32 subset pairs, full
//!   and short buffers); so does Kani.
use crate::Chooser;
use lbdem_kernels::dem::grid::{
    build_cell_grid, candidate_pairs, carry_contact_history, cell_index, neighbour_span, CellGrid,
    GridError, PairCount,
};

/// Coordinates a particle takes in the bounded-exhaustive run of the sort harness (cell size 1, origin 0).
pub const COORDINATES: [f64; 8] = [
    -1.0,
    0.0,
    0.999,
    1.0,
    2.5,
    1e300,
    f64::NAN,
    f64::NEG_INFINITY,
];

/// Body: every cell index and neighbour span of a grid up to 6 × 6 is in bounds.
pub fn cell_index_in_bounds(c: &mut dyn Chooser) {
    let nx = c.usize_in(1, 6);
    let ny = c.usize_in(1, 6);
    let ix = c.usize_in(0, nx - 1);
    let iy = c.usize_in(0, ny - 1);
    assert!(cell_index(nx, ix, iy) < nx * ny);
    let (xl, xh) = neighbour_span(ix, nx);
    let (yl, yh) = neighbour_span(iy, ny);
    assert!(xl <= ix && ix <= xh && xh < nx && xh - xl <= 2);
    assert!(yl <= iy && iy <= yh && yh < ny && yh - yl <= 2);
    assert!(cell_index(nx, xh, yh) < nx * ny);
}

/// The oracle cell of coordinate `x` along an axis of `n` unit cells from origin 0, written without `floor`:
/// the number of interior cell boundaries 1, 2, …, n − 1 at or below x (NaN and −∞ are below every boundary).
pub fn expected_cell(x: f64, n: usize) -> usize {
    (1..n).filter(|&b| b as f64 <= x).count()
}

/// Body: the counting sort and pair listing over small grids (see the module documentation).
pub fn counting_sort_is_a_permutation(c: &mut dyn Chooser) {
    const MAX_N: usize = 3;
    let nx = c.usize_in(1, 3);
    let ny = c.usize_in(1, 3);
    let n = c.usize_in(0, MAX_N);
    let mut positions = [lbdem_kernels::math::vector(0.0f64, 0.0); MAX_N];
    for p in positions.iter_mut().take(n) {
        p[0] = c.float_from(&COORDINATES);
        p[1] = c.float_from(&COORDINATES);
    }
    let positions = &positions[..n];
    let grid =
        CellGrid::new(lbdem_kernels::math::vector(0.0, 0.0), 1.0, nx, ny).expect("valid grid");
    let oracle =
        |p: lbdem_kernels::math::Vector<f64>| (expected_cell(p[0], nx), expected_cell(p[1], ny));
    let cells = grid.cell_count();
    let mut start = [0usize; 10];
    let mut order = [usize::MAX; MAX_N];
    build_cell_grid(&grid, positions, &mut start[..cells + 1], &mut order[..n]).expect("buffers");
    let start = &start[..cells + 1];
    let order = &order[..n];
    assert_eq!(start[0], 0);
    assert_eq!(start[cells], n);
    assert!(start.windows(2).all(|w| w[0] <= w[1]));
    let mut seen = [false; MAX_N];
    for cell in 0..cells {
        let members = &order[start[cell]..start[cell + 1]];
        assert!(members.windows(2).all(|w| w[0] < w[1]));
        for &i in members {
            assert!(i < n && !seen[i]);
            seen[i] = true;
            let (ix, iy) = oracle(positions[i]);
            assert_eq!(cell, ix + nx * iy, "particle {i} in the wrong cell");
        }
    }
    assert!(seen[..n].iter().all(|&s| s));

    let radii = [f64::INFINITY; MAX_N];
    let mut pairs = [[0usize; 2]; 3];
    let PairCount { found, stored } =
        candidate_pairs(&grid, positions, &radii[..n], 0.0, start, order, &mut pairs)
            .expect("buffers");
    assert_eq!(found, stored);
    let mut expected = 0;
    for i in 0..n {
        for j in i + 1..n {
            let (a, b) = (oracle(positions[i]), oracle(positions[j]));
            let d = [
                positions[j][0] - positions[i][0],
                positions[j][1] - positions[i][1],
            ];
            // The bounding-circle filter with an unbounded reach keeps every pair at a finite distance.
            let finite = (d[0] * d[0] + d[1] * d[1]).is_finite();
            if finite && a.0.abs_diff(b.0) <= 1 && a.1.abs_diff(b.1) <= 1 {
                assert!(pairs[..stored].contains(&[i, j]), "pair {i},{j} missed");
                expected += 1;
            }
        }
    }
    assert_eq!(stored, expected);
    assert!(pairs[..stored].iter().all(|p| p[0] < p[1]));
    assert!(pairs[..stored].windows(2).all(|w| w[0] < w[1]));
}

/// Body: the O(N) history merge over all subsets of a small universe of sorted pairs.
pub fn history_merge_is_exact(c: &mut dyn Chooser) {
    const UNIVERSE: [[usize; 2]; 5] = [[0, 1], [0, 2], [1, 2], [1, 3], [2, 3]];
    let before = c.usize_in(0, 31);
    let after = c.usize_in(0, 31);
    let short = c.boolean();
    let pick = |mask: usize, out: &mut [[usize; 2]; 5]| {
        let mut len = 0;
        for (bit, pair) in UNIVERSE.iter().enumerate() {
            if mask & (1 << bit) != 0 {
                out[len] = *pair;
                len += 1;
            }
        }
        len
    };
    let mut prev = [[0usize; 2]; 5];
    let mut next = [[0usize; 2]; 5];
    let np = pick(before, &mut prev);
    let nn = pick(after, &mut next);
    let prev_values = [10.0f64, 11.0, 12.0, 13.0, 14.0];
    let mut values = [f64::NAN; 5];
    if short && nn > 0 {
        let r = carry_contact_history(
            &prev[..np],
            &prev_values[..np],
            &next[..nn],
            &mut values[..nn - 1],
        );
        assert_eq!(r, Err(GridError::BufferLength));
        return;
    }
    let carried = carry_contact_history(
        &prev[..np],
        &prev_values[..np],
        &next[..nn],
        &mut values[..nn],
    )
    .expect("buffers");
    let mut expected = 0;
    for (pair, v) in next[..nn].iter().zip(&values[..nn]) {
        match prev[..np].iter().position(|p| p == pair) {
            Some(k) => {
                assert_eq!(*v, prev_values[k]);
                expected += 1;
            }
            None => assert_eq!(*v, 0.0),
        }
    }
    assert_eq!(carried, expected);
}

#[cfg(kani)]
mod kani_proofs {
    use crate::KaniChooser;

    #[kani::proof]
    #[kani::unwind(8)]
    fn history_merge_is_exact() {
        super::history_merge_is_exact(&mut KaniChooser);
    }

    #[kani::proof]
    fn cell_index_in_bounds() {
        super::cell_index_in_bounds(&mut KaniChooser);
    }

    #[kani::proof]
    #[kani::unwind(12)]
    fn counting_sort_is_a_permutation() {
        super::counting_sort_is_a_permutation(&mut KaniChooser);
    }
}
