//! Properties of the DEM broad phase (`lbdem_kernels::dem::grid`) against oracles written independently of
//! the kernel: the cell of a position is floor((x − origin)/h) clamped to the grid (NaN and −∞ to the first
//! cell), and, for exactly representable inputs, the cell's own interval [origin + i h, origin + (i + 1) h)
//! contains the position; the counting sort against a bucket list built from that oracle; the pair listing
//! against an O(N²) search, on grids with non-zero (negative and positive) origins and particles outside the
//! grid; `covering` for any box; and every error path of `CellGrid::new`, `build_cell_grid`,
//! `candidate_pairs` and `carry_contact_history` (including corrupted offset tables, which must yield no
//! pairs rather than a panic).
//!
//! Everything compared here is exact (integers, or dyadic rationals whose arithmetic does not round), so the
//! comparisons are exact.
use lbdem_kernels::dem::grid::{
    build_cell_grid, candidate_pairs, carry_contact_history, cell_grid_scratch_len, CellGrid,
    GridError, PairCount,
};
use lbdem_kernels::math::Vector;
use lbdem_verification::proptest_cases;
use proptest::prelude::*;

fn config(default: u32) -> ProptestConfig {
    ProptestConfig::with_cases(proptest_cases(default))
}

/// The oracle binning along one axis: floor((x − origin)/h), clamped to 0..n; NaN goes to cell 0.
fn oracle_axis(x: f64, origin: f64, h: f64, n: usize) -> usize {
    let f = ((x - origin) / h).floor();
    if f.is_nan() || f < 0.0 {
        0
    } else if f >= n as f64 {
        n - 1
    } else {
        f as usize
    }
}

fn oracle_cell(grid: &CellGrid<f64>, p: Vector<f64>) -> (usize, usize) {
    (
        oracle_axis(p[0], grid.origin[0], grid.cell_size, grid.nx),
        oracle_axis(p[1], grid.origin[1], grid.cell_size, grid.ny),
    )
}

/// A grid with an origin anywhere in [−50, 50]², a cell size from 0.1 to 10, 1 to 16 cells per axis.
fn grid() -> impl Strategy<Value = CellGrid<f64>> {
    (
        [-50.0f64..=50.0, -50.0f64..=50.0],
        (0.1f64.ln()..=10f64.ln()).prop_map(f64::exp),
        1usize..=16,
        1usize..=16,
    )
        .prop_map(|(origin, h, nx, ny)| {
            CellGrid::new(Vector::from(origin), h, nx, ny).expect("valid grid")
        })
}

/// A coordinate relative to the grid: mostly inside, some outside on either side, some non-finite.
fn coordinate(origin: f64, extent: f64) -> impl Strategy<Value = f64> {
    prop_oneof![
        8 => (-0.2f64..=1.2).prop_map(move |t| origin + t * extent),
        1 => Just(f64::NAN),
        1 => prop_oneof![Just(f64::INFINITY), Just(f64::NEG_INFINITY), Just(1e300), Just(-1e300)],
    ]
}

fn grid_and_positions(max: usize) -> impl Strategy<Value = (CellGrid<f64>, Vec<Vector<f64>>)> {
    grid().prop_flat_map(move |g| {
        let (ex, ey) = (g.nx as f64 * g.cell_size, g.ny as f64 * g.cell_size);
        let point = [coordinate(g.origin[0], ex), coordinate(g.origin[1], ey)];
        (
            Just(g),
            prop::collection::vec(point.prop_map(|[x, y]| Vector::new(x, y)), 0..max),
        )
    })
}

proptest! {
    #![proptest_config(config(256))]

    /// The cell of a position is the oracle's floor((x − origin)/h), clamped; `cell_of` is its row-major index.
    #[test]
    fn cell_coords_are_floor_of_offset_over_size((g, ps) in grid_and_positions(40)) {
        for p in ps {
            let (ix, iy) = oracle_cell(&g, p);
            prop_assert_eq!(g.cell_coords(p), (ix, iy), "position {:?}", p);
            prop_assert_eq!(g.cell_of(p), ix + g.nx * iy);
        }
    }

    /// With exactly representable inputs (origin and positions multiples of 1/1024, cell size a power of
    /// two), a position strictly inside the grid lies in its cell's half-open interval on both axes.
    #[test]
    fn a_position_lies_in_its_own_cell(
        ox in -51_200i64..=51_200, oy in -51_200i64..=51_200, k in -3i32..=3, nx in 1usize..=16, ny in 1usize..=16,
        ts in prop::collection::vec([0.0f64..1.0, 0.0f64..1.0], 1..40),
    ) {
        let h = 2f64.powi(k);
        let origin = [ox as f64 / 1024.0, oy as f64 / 1024.0];
        let g = CellGrid::new(Vector::from(origin), h, nx, ny).expect("valid grid");
        for t in ts {
            // A multiple of 1/1024 inside the grid.
            let p = [
                origin[0] + ((t[0] * nx as f64 * h) * 1024.0).floor() / 1024.0,
                origin[1] + ((t[1] * ny as f64 * h) * 1024.0).floor() / 1024.0,
            ];
            let (ix, iy) = g.cell_coords(Vector::from(p));
            prop_assert!(ix < nx && iy < ny);
            prop_assert!(origin[0] + ix as f64 * h <= p[0] && p[0] < origin[0] + (ix + 1) as f64 * h, "x {} in cell {}", p[0], ix);
            prop_assert!(origin[1] + iy as f64 * h <= p[1] && p[1] < origin[1] + (iy + 1) as f64 * h, "y {} in cell {}", p[1], iy);
        }
    }

    /// The counting sort puts exactly the particles of each oracle cell in that cell's range, ascending, and
    /// the offsets are the running counts.
    #[test]
    fn counting_sort_matches_the_oracle_buckets((g, ps) in grid_and_positions(60)) {
        let (start_len, order_len) = cell_grid_scratch_len(&g, ps.len());
        prop_assert_eq!(start_len, g.nx * g.ny + 1);
        prop_assert_eq!(order_len, ps.len());
        let mut start = vec![usize::MAX; start_len];
        let mut order = vec![usize::MAX; order_len];
        build_cell_grid(&g, &ps, &mut start, &mut order).expect("buffers");
        let mut buckets = vec![Vec::new(); g.nx * g.ny];
        for (i, &p) in ps.iter().enumerate() {
            let (ix, iy) = oracle_cell(&g, p);
            buckets[ix + g.nx * iy].push(i);
        }
        let mut offset = 0;
        for (c, bucket) in buckets.iter().enumerate() {
            prop_assert_eq!(start[c], offset, "start of cell {}", c);
            prop_assert_eq!(&order[start[c]..start[c + 1]], &bucket[..], "cell {}", c);
            offset += bucket.len();
        }
        prop_assert_eq!(start[g.nx * g.ny], ps.len());
    }

    /// With a cell size at least the largest interaction distance, the pairs listed are exactly those an
    /// O(N²) search finds, in lexicographic order, whatever the origin, with particles beyond the grid
    /// (clamped to border cells) included.
    #[test]
    fn pairs_match_an_all_pairs_search_for_any_origin(
        origin in [-50.0f64..=50.0, -50.0f64..=50.0], nx in 1usize..=8, ny in 1usize..=8,
        pts in prop::collection::vec(([-0.3f64..=1.3, -0.3f64..=1.3], 0.05f64..=0.25), 0..60),
        margin in 0.0f64..=0.05,
    ) {
        let h = 2.0 * 0.25 + margin;
        let g = CellGrid::new(Vector::from(origin), h, nx, ny).expect("valid grid");
        let positions: Vec<Vector<f64>> = pts
            .iter()
            .map(|(t, _)| Vector::new(origin[0] + t[0] * nx as f64 * h, origin[1] + t[1] * ny as f64 * h))
            .collect();
        let radii: Vec<f64> = pts.iter().map(|p| p.1).collect();
        let mut start = vec![0; g.nx * g.ny + 1];
        let mut order = vec![0; positions.len()];
        build_cell_grid(&g, &positions, &mut start, &mut order).expect("buffers");
        let mut pairs = vec![[0, 0]; 2000];
        let count = candidate_pairs(&g, &positions, &radii, margin, &start, &order, &mut pairs).expect("buffers");
        let mut expected = Vec::new();
        for i in 0..positions.len() {
            for j in i + 1..positions.len() {
                let d = [positions[j][0] - positions[i][0], positions[j][1] - positions[i][1]];
                let reach = radii[i] + radii[j] + margin;
                if d[0] * d[0] + d[1] * d[1] < reach * reach {
                    expected.push([i, j]);
                }
            }
        }
        prop_assert_eq!(count, PairCount { found: expected.len(), stored: expected.len() });
        prop_assert_eq!(&pairs[..count.stored], &expected[..]);
    }

    /// `covering` gives a valid grid whose origin is the box's low corner, with cells at least the minimum
    /// size, at most the cap per axis, as many as fit (⌊extent / min size⌋, clamped to 1..=cap), together at
    /// least as long as the box on each axis, and no larger than that needs: the minimum size, or, where the
    /// cap forced fewer cells, the extent over the cell count of the axis that needs the most.
    #[test]
    fn covering_covers_the_box_from_its_low_corner(
        lo in [-100.0f64..=100.0, -100.0f64..=100.0], extent in [0.0f64..=50.0, 0.0f64..=50.0],
        min_size in 0.05f64..=5.0, cap in 0usize..=40,
    ) {
        let hi = [lo[0] + extent[0], lo[1] + extent[1]];
        let g = CellGrid::covering(Vector::from(lo), Vector::from(hi), min_size, cap).expect("a valid box");
        prop_assert!(g.is_valid());
        prop_assert_eq!(g.origin, Vector::from(lo));
        prop_assert!(g.cell_size >= min_size);
        for (n, e) in [(g.nx, hi[0] - lo[0]), (g.ny, hi[1] - lo[1])] {
            let fit = ((e / min_size).floor() as usize).clamp(1, cap.max(1));
            prop_assert_eq!(n, fit, "extent {} min size {} cap {}", e, min_size, cap);
            // n · size ≥ extent, up to the rounding of extent / n (one ulp).
            prop_assert!(n as f64 * g.cell_size >= e * (1.0 - 4.0 * f64::EPSILON), "{} cells of {} for {}", n, g.cell_size, e);
        }
        let needed = min_size
            .max((hi[0] - lo[0]) / g.nx as f64)
            .max((hi[1] - lo[1]) / g.ny as f64);
        prop_assert!(g.cell_size <= needed * (1.0 + 4.0 * f64::EPSILON), "cell {} where {} suffices", g.cell_size, needed);
    }
}

proptest! {
    #![proptest_config(config(64))]

    /// Contact history: persisting pairs keep their values, new ones start at zero, for any sorted lists; short
    /// value buffers on either side are refused.
    #[test]
    fn history_merge_and_its_buffer_checks(
        before in prop::collection::btree_set((0usize..10, 0usize..10), 0..25),
        after in prop::collection::btree_set((0usize..10, 0usize..10), 1..25),
    ) {
        let prev: Vec<[usize; 2]> = before.iter().map(|&(a, b)| [a, b]).collect();
        let next: Vec<[usize; 2]> = after.iter().map(|&(a, b)| [a, b]).collect();
        let prev_values: Vec<f64> = (0..prev.len()).map(|k| k as f64 + 0.5).collect();
        let mut values = vec![f64::NAN; next.len()];
        let carried = carry_contact_history(&prev, &prev_values, &next, &mut values).expect("buffers");
        let mut expected = 0;
        for (pair, v) in next.iter().zip(&values) {
            match prev.iter().position(|p| p == pair) {
                Some(k) => {
                    prop_assert_eq!(*v, prev_values[k]);
                    expected += 1;
                }
                None => prop_assert_eq!(*v, 0.0),
            }
        }
        prop_assert_eq!(carried, expected);
        prop_assert_eq!(
            carry_contact_history(&prev, &prev_values, &next, &mut values[..next.len() - 1]),
            Err(GridError::BufferLength)
        );
        if !prev.is_empty() {
            prop_assert_eq!(
                carry_contact_history(&prev, &prev_values[..prev.len() - 1], &next, &mut values),
                Err(GridError::BufferLength)
            );
        }
    }
}

/// `CellGrid::new` refuses every geometry it cannot index with, and a grid whose public fields were set to
/// such a geometry is refused by both passes.
#[test]
fn bad_geometry_is_refused_everywhere() {
    let bad = [
        ([0.0, 0.0], 0.0, 2, 2),
        ([0.0, 0.0], -1.0, 2, 2),
        ([0.0, 0.0], f64::NAN, 2, 2),
        ([0.0, 0.0], f64::INFINITY, 2, 2),
        ([0.0, 0.0], 1.0, 0, 2),
        ([0.0, 0.0], 1.0, 2, 0),
        ([0.0, 0.0], 1.0, usize::MAX, 2),
        ([0.0, 0.0], 1.0, usize::MAX, 1),
    ];
    let positions = [Vector::new(0.5, 0.5), Vector::new(0.7, 0.5)];
    let radii = [0.2, 0.2];
    for (origin, size, nx, ny) in bad {
        assert_eq!(
            CellGrid::new(Vector::from(origin), size, nx, ny),
            Err(GridError::BadGeometry),
            "size {size}, {nx} × {ny}"
        );
        let g = CellGrid {
            origin: Vector::from(origin),
            cell_size: size,
            nx,
            ny,
        };
        assert!(!g.is_valid());
        let mut start = [0usize; 5];
        let mut order = [0usize; 2];
        assert_eq!(
            build_cell_grid(&g, &positions, &mut start, &mut order),
            Err(GridError::BadGeometry)
        );
        let mut pairs = [[0usize; 2]; 4];
        assert_eq!(
            candidate_pairs(&g, &positions, &radii, 0.0, &start, &order, &mut pairs),
            Err(GridError::BadGeometry)
        );
    }
    // Counts saturate instead of overflowing for such field values.
    let huge = CellGrid {
        origin: Vector::new(0.0, 0.0),
        cell_size: 1.0,
        nx: usize::MAX,
        ny: 2,
    };
    assert_eq!(huge.cell_count(), usize::MAX);
    assert_eq!(huge.cell_start_len(), usize::MAX);
    let edge = CellGrid { ny: 1, ..huge };
    assert_eq!(edge.cell_count(), usize::MAX);
    assert_eq!(edge.cell_start_len(), usize::MAX);
}

/// Every buffer of the wrong length is refused with `BufferLength`, by both passes, without writing pairs.
#[test]
fn wrong_buffer_lengths_are_refused() {
    let g = CellGrid::new(Vector::new(-1.0, 2.0), 1.0, 3, 2).expect("valid grid");
    let positions = [
        Vector::new(-0.5, 2.5),
        Vector::new(0.2, 2.5),
        Vector::new(1.5, 3.5),
    ];
    let radii = [0.6; 3];
    let (sl, ol) = cell_grid_scratch_len(&g, positions.len());
    assert_eq!((sl, ol), (7, 3));
    let mut start = vec![0; sl];
    let mut order = vec![0; ol];
    for (s, o) in [(sl - 1, ol), (sl + 1, ol), (sl, ol - 1), (sl, ol + 1)] {
        let (mut s2, mut o2) = (vec![0; s], vec![0; o]);
        assert_eq!(
            build_cell_grid(&g, &positions, &mut s2, &mut o2),
            Err(GridError::BufferLength),
            "{s}, {o}"
        );
    }
    build_cell_grid(&g, &positions, &mut start, &mut order).expect("buffers");
    let mut pairs = [[9usize; 2]; 4];
    let ok = candidate_pairs(&g, &positions, &radii, 0.0, &start, &order, &mut pairs);
    assert_eq!(
        ok,
        Ok(PairCount {
            found: 1,
            stored: 1
        })
    );
    assert_eq!(pairs[0], [0, 1]);
    let mut untouched = [[9usize; 2]; 4];
    for (s, o, r) in [
        (&start[..sl - 1], &order[..], &radii[..]),
        (&start[..], &order[..ol - 1], &radii[..]),
        (&start[..], &order[..], &radii[..2]),
    ] {
        assert_eq!(
            candidate_pairs(&g, &positions, r, 0.0, s, o, &mut untouched),
            Err(GridError::BufferLength)
        );
    }
    let mut longer = start.clone();
    longer.push(3);
    assert_eq!(
        candidate_pairs(&g, &positions, &radii, 0.0, &longer, &order, &mut untouched),
        Err(GridError::BufferLength)
    );
    assert_eq!(untouched, [[9usize; 2]; 4], "nothing written on error");
}

/// A corrupted offset table (decreasing offsets, or offsets past the end) yields no pairs from the corrupted
/// cells and no panic; entries that name particles out of range are skipped.
#[test]
fn corrupted_offset_tables_yield_no_pairs_instead_of_a_panic() {
    let g = CellGrid::new(Vector::new(0.0, 0.0), 1.0, 2, 1).expect("valid grid");
    let positions = [
        Vector::new(0.2, 0.5),
        Vector::new(0.4, 0.5),
        Vector::new(1.5, 0.5),
    ];
    let radii = [1.0; 3];
    let mut pairs = [[0usize; 2]; 8];
    // Decreasing: cell 0 = 2..1, cell 1 = 1..3.
    let r = candidate_pairs(
        &g,
        &positions,
        &radii,
        0.0,
        &[2, 1, 3],
        &[0, 1, 2],
        &mut pairs,
    )
    .expect("lengths are right");
    assert_eq!(r.found, r.stored);
    assert!(pairs[..r.stored].iter().all(|p| p[0] < p[1] && p[1] < 3));
    // Past the end: cell 1 = 1..9 is dropped, cell 0 = 0..1 holds particle 0 alone.
    let r = candidate_pairs(
        &g,
        &positions,
        &radii,
        0.0,
        &[0, 1, 9],
        &[0, 1, 2],
        &mut pairs,
    )
    .expect("lengths are right");
    assert_eq!(r.found, 0);
    // Particle indices out of range in the member list are skipped.
    let r = candidate_pairs(
        &g,
        &positions,
        &radii,
        0.0,
        &[0, 2, 3],
        &[0, 7, 1],
        &mut pairs,
    )
    .expect("lengths are right");
    assert_eq!(
        (r.found, &pairs[..r.stored]),
        (1, &[[0usize, 1]][..]),
        "only the valid members pair up"
    );
}
