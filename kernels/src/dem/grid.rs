//! Broad phase: a uniform cell grid built by counting sort in caller-owned buffers.
//!
//! The grid covers the rectangle [origin, origin + (nx, ny)·cell_size]; positions outside it (or non-finite)
//! are clamped to the nearest border cell, which keeps every index in bounds and preserves the neighbour
//! relation (clamping is monotone and never increases the cell distance), so no pair is lost. With
//! `cell_size` at least the largest interaction distance (twice the largest bounding radius plus the margin),
//! every interacting pair lies in the same or adjacent cells.
//!
//! Build (O(N + cells)): `cell_start` (length cells + 1) receives the offsets, `cell_particles` (length N) the
//! particle indices sorted by cell, ascending index within a cell (a stable counting sort). Pairs (i < j) are
//! then found by visiting, for each i, the 3 × 3 neighbour cells, merging their ascending member lists so that
//! j comes out ascending (no sort: O(N) for a bounded number of particles per cell); a bounding-circle test
//! |c_j − c_i| < R_i + R_j + margin filters them. The pairs are therefore listed in lexicographic order, which
//! is deterministic, independent of the grid, and the order [`carry_contact_history`] needs. When the output
//! buffer is too small it holds the lexicographically first pairs.
//!
//! Contact history across steps: [`carry_contact_history`] merges last step's sorted pair list and its
//! per-pair values (the shear force of [`linear_contact_force`](super::law::linear_contact_force)) into this
//! step's list in O(N): a pair that persists keeps its value, a new pair starts from zero, and a pair that
//! disappeared is dropped.
//!
//! The index arithmetic (`cell_index`, `neighbour_span`, the counting sort, the history merge) is proved for all small
//! grids by the bounded-exhaustive harness in `verification/src/harness/dem.rs`.
use crate::math::Vector;
use crate::Real;

/// Geometry of a uniform cell grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellGrid<T> {
    /// Lower-left corner.
    pub origin: Vector<T>,
    /// Edge length of a square cell (> 0).
    pub cell_size: T,
    /// Cells along x (≥ 1).
    pub nx: usize,
    /// Cells along y (≥ 1).
    pub ny: usize,
}

/// Why the grid could not be built or used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridError {
    /// Zero cells along an axis, a cell count overflowing `usize`, or a non-positive / non-finite cell size.
    BadGeometry,
    /// A caller buffer has the wrong length: `cell_start` needs cells + 1, `cell_particles` and the radii N.
    BufferLength,
}

/// Pairs found by [`candidate_pairs`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PairCount {
    /// Number of candidate pairs that exist.
    pub found: usize,
    /// Number written to the output buffer (`found` when it was large enough; otherwise grow it and retry).
    pub stored: usize,
}

/// Row-major cell index ix + nx·iy. In bounds (< nx·ny) whenever ix < nx and iy < ny.
#[inline(always)]
pub fn cell_index(nx: usize, ix: usize, iy: usize) -> usize {
    ix + nx * iy
}

/// The cells adjacent to `i` along an axis of `n` cells, clamped: the inclusive range (i − 1 ..= i + 1) ∩ [0, n).
#[inline(always)]
pub fn neighbour_span(i: usize, n: usize) -> (usize, usize) {
    let lo = i.saturating_sub(1);
    let hi = if i + 1 < n {
        i + 1
    } else {
        n.saturating_sub(1)
    };
    (lo, hi)
}

impl<T: Real> CellGrid<T> {
    /// A grid, or `BadGeometry` when it cannot index (see [`GridError`]).
    pub fn new(origin: Vector<T>, cell_size: T, nx: usize, ny: usize) -> Result<Self, GridError> {
        let ok_size = cell_size > T::zero() && cell_size.is_finite();
        let cells = nx.checked_mul(ny).and_then(|c| c.checked_add(1));
        if !ok_size || nx == 0 || ny == 0 || cells.is_none() {
            return Err(GridError::BadGeometry);
        }
        Ok(CellGrid {
            origin,
            cell_size,
            nx,
            ny,
        })
    }

    /// A grid covering [lo, hi] with cells of at least `min_cell_size` (and at most `max_cells_per_axis`
    /// cells per axis, the cells growing to fit).
    pub fn covering(
        lo: Vector<T>,
        hi: Vector<T>,
        min_cell_size: T,
        max_cells_per_axis: usize,
    ) -> Result<Self, GridError> {
        let count = |extent: T| -> usize {
            let c = (extent / min_cell_size).floor();
            let max = max_cells_per_axis.max(1);
            match c.to_usize() {
                Some(v) => v.clamp(1, max),
                None => 1,
            }
        };
        let nx = count(hi[0] - lo[0]);
        let ny = count(hi[1] - lo[1]);
        let size = min_cell_size
            .max((hi[0] - lo[0]) / T::lit(nx as f64))
            .max((hi[1] - lo[1]) / T::lit(ny as f64));
        Self::new(lo, size, nx, ny)
    }

    /// Number of cells, nx·ny (saturating; a grid from [`CellGrid::new`] never saturates).
    #[inline(always)]
    pub fn cell_count(&self) -> usize {
        self.nx.saturating_mul(self.ny)
    }

    /// Whether the fields describe a usable grid (the checks of [`CellGrid::new`]; the fields are public).
    pub fn is_valid(&self) -> bool {
        Self::new(self.origin, self.cell_size, self.nx, self.ny).is_ok()
    }

    /// Required length of the `cell_start` buffer: cells + 1.
    #[inline(always)]
    pub fn cell_start_len(&self) -> usize {
        self.cell_count().saturating_add(1)
    }

    #[inline(always)]
    fn axis(&self, x: T, origin: T, n: usize) -> usize {
        let f = ((x - origin) / self.cell_size).floor();
        if f.is_nan() || f < T::zero() {
            return 0; // below the grid, or NaN
        }
        match f.to_usize() {
            Some(v) if v < n => v,
            _ => n.saturating_sub(1),
        }
    }

    /// Cell coordinates (ix, iy) of a position, clamped to the grid.
    #[inline(always)]
    pub fn cell_coords(&self, p: Vector<T>) -> (usize, usize) {
        (
            self.axis(p[0], self.origin[0], self.nx),
            self.axis(p[1], self.origin[1], self.ny),
        )
    }

    /// Row-major cell index of a position, clamped to the grid.
    #[inline(always)]
    pub fn cell_of(&self, p: Vector<T>) -> usize {
        let (ix, iy) = self.cell_coords(p);
        cell_index(self.nx, ix, iy)
    }
}

/// Lengths of the two caller buffers of [`build_cell_grid`] (the `*_scratch_len` convention):
/// (`cell_start`: cells + 1, `cell_particles`: the particle count).
pub fn cell_grid_scratch_len<T: Real>(grid: &CellGrid<T>, particles: usize) -> (usize, usize) {
    (grid.cell_start_len(), particles)
}

/// Bin the particles into the grid by counting sort. After the call the particles of cell c are
/// `cell_particles[cell_start[c]..cell_start[c + 1]]`, in ascending index order.
pub fn build_cell_grid<T: Real>(
    grid: &CellGrid<T>,
    positions: &[Vector<T>],
    cell_start: &mut [usize],
    cell_particles: &mut [usize],
) -> Result<(), GridError> {
    if !grid.is_valid() {
        return Err(GridError::BadGeometry);
    }
    let cells = grid.cell_count();
    if cell_start.len() != cells + 1 || cell_particles.len() != positions.len() {
        return Err(GridError::BufferLength);
    }
    cell_start.fill(0);
    for p in positions {
        cell_start[grid.cell_of(*p)] += 1;
    }
    // Exclusive prefix sum: cell_start[c] = first slot of cell c.
    let mut total = 0;
    for slot in cell_start.iter_mut() {
        let count = *slot;
        *slot = total;
        total += count;
    }
    // Scatter, using cell_start[c] as the cursor of cell c (it ends at the first slot of cell c + 1) ...
    for (i, p) in positions.iter().enumerate() {
        let c = grid.cell_of(*p);
        cell_particles[cell_start[c]] = i;
        cell_start[c] += 1;
    }
    // ... then shift the cursors back by one cell to recover the starts.
    for c in (1..=cells).rev() {
        cell_start[c] = cell_start[c - 1];
    }
    cell_start[0] = 0;
    Ok(())
}

/// List the candidate pairs (i < j) whose bounding circles come within `margin` of each other, in the
/// deterministic order described in the module documentation. Writes as many as fit in `pairs`.
pub fn candidate_pairs<T: Real>(
    grid: &CellGrid<T>,
    positions: &[Vector<T>],
    bounding_radii: &[T],
    margin: T,
    cell_start: &[usize],
    cell_particles: &[usize],
    pairs: &mut [[usize; 2]],
) -> Result<PairCount, GridError> {
    if !grid.is_valid() {
        return Err(GridError::BadGeometry);
    }
    let n = positions.len();
    if cell_start.len() != grid.cell_count() + 1
        || cell_particles.len() != n
        || bounding_radii.len() != n
    {
        return Err(GridError::BufferLength);
    }
    let mut found = 0;
    let mut stored = 0;
    for i in 0..n {
        let pi = positions[i];
        let (ix, iy) = grid.cell_coords(pi);
        let (x_lo, x_hi) = neighbour_span(ix, grid.nx);
        let (y_lo, y_hi) = neighbour_span(iy, grid.ny);
        // Cursors (next slot, end slot) into the neighbour cells' ascending member lists.
        let mut heads = [(0usize, 0usize); 9];
        let mut cells = 0;
        for cy in y_lo..=y_hi {
            for cx in x_lo..=x_hi {
                let c = cell_index(grid.nx, cx, cy);
                let (s, e) = (cell_start[c], cell_start[c + 1]);
                // A corrupted offset table yields no pairs rather than a panic.
                if s <= e && e <= cell_particles.len() && cells < heads.len() {
                    heads[cells] = (s, e);
                    cells += 1;
                }
            }
        }
        // Merge the lists: j comes out ascending, so the pairs are listed in lexicographic order.
        loop {
            let mut best: Option<(usize, usize)> = None; // (j, cursor)
            for (h, &(next, end)) in heads[..cells].iter().enumerate() {
                if next < end {
                    let j = cell_particles[next];
                    if best.is_none_or(|(bj, _)| j < bj) {
                        best = Some((j, h));
                    }
                }
            }
            let Some((j, h)) = best else {
                break;
            };
            heads[h].0 += 1;
            if j <= i || j >= n {
                continue;
            }
            if within_reach(positions, bounding_radii, margin, i, j) {
                if let Some(slot) = pairs.get_mut(stored) {
                    *slot = [i, j];
                    stored += 1;
                }
                found += 1;
            }
        }
    }
    Ok(PairCount { found, stored })
}

/// The pair test of [`candidate_pairs`] and [`filter_candidate_pairs`] (one expression, so the two list
/// bitwise the same pairs): the bounding circles of i and j come within `margin` of each other.
#[inline(always)]
fn within_reach<T: Real>(
    positions: &[Vector<T>],
    bounding_radii: &[T],
    margin: T,
    i: usize,
    j: usize,
) -> bool {
    let (pi, pj) = (positions[i], positions[j]);
    let d = [pj[0] - pi[0], pj[1] - pi[1]];
    let reach = bounding_radii[i] + bounding_radii[j] + margin;
    d[0] * d[0] + d[1] * d[1] < reach * reach
}

/// Copy per-pair values (e.g. the shear history) from `previous_pairs` to `pairs`, both sorted ascending
/// without duplicates (as [`candidate_pairs`] returns them); pairs not present before get the default value
/// (zero for numbers, a zero vector for `[T; 2]`). Returns the number of values carried over, or `BufferLength`
/// if a value slice is shorter than its pair list.
pub fn carry_contact_history<V: Copy + Default>(
    previous_pairs: &[[usize; 2]],
    previous_values: &[V],
    pairs: &[[usize; 2]],
    values: &mut [V],
) -> Result<usize, GridError> {
    if previous_values.len() < previous_pairs.len() || values.len() < pairs.len() {
        return Err(GridError::BufferLength);
    }
    let mut k = 0;
    let mut carried = 0;
    for (pair, value) in pairs.iter().zip(values.iter_mut()) {
        while k < previous_pairs.len() && previous_pairs[k] < *pair {
            k += 1;
        }
        if k < previous_pairs.len() && previous_pairs[k] == *pair {
            *value = previous_values[k];
            carried += 1;
        } else {
            *value = V::default();
        }
    }
    Ok(carried)
}

/// The pairs of `superset` (sorted, as [`candidate_pairs`] lists them) whose bounding circles come within
/// `margin` of each other, written in order to `pairs` (as many as fit; the count returned as by
/// [`candidate_pairs`]). The test is [`candidate_pairs`]' own expression, operation for operation, so when
/// `superset` holds every pair [`candidate_pairs`] would list for these positions, radii and margin (a Verlet
/// list: pairs within `margin + skin` when built, kept while no particle has moved plus grown by more than
/// half the skin), the output is bitwise the same list in the same order. O(superset) instead of a grid pass.
/// Pairs naming an index out of range are skipped.
pub fn filter_candidate_pairs<T: Real>(
    positions: &[Vector<T>],
    bounding_radii: &[T],
    margin: T,
    superset: &[[usize; 2]],
    pairs: &mut [[usize; 2]],
) -> Result<PairCount, GridError> {
    let n = positions.len();
    if bounding_radii.len() != n {
        return Err(GridError::BufferLength);
    }
    let mut found = 0;
    let mut stored = 0;
    for &[i, j] in superset {
        if i >= n || j >= n || j <= i {
            continue;
        }
        if within_reach(positions, bounding_radii, margin, i, j) {
            if let Some(slot) = pairs.get_mut(stored) {
                *slot = [i, j];
                stored += 1;
            }
            found += 1;
        }
    }
    Ok(PairCount { found, stored })
}
