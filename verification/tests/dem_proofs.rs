//! Bounded-exhaustive runs of the DEM proof harness bodies (`src/harness/dem.rs`): over the stated finite
//! domains these tests are proofs.
use lbdem_verification::{for_all, harness::dem};

#[test]
fn cell_index_in_bounds_for_every_grid_up_to_6x6() {
    let runs = for_all(dem::cell_index_in_bounds);
    // Σ_{nx,ny ≤ 6} nx·ny = 21² combinations.
    assert_eq!(runs, 441);
}

#[test]
fn counting_sort_is_a_permutation_for_every_small_placement() {
    let runs = for_all(dem::counting_sort_is_a_permutation);
    // 9 grids × Σ_{n=0..3} 64ⁿ placements.
    assert_eq!(runs, 9 * (1 + 64 + 64 * 64 + 64 * 64 * 64));
}

#[test]
fn history_merge_is_exact_for_every_pair_of_subsets() {
    let runs = for_all(dem::history_merge_is_exact);
    // 32 × 32 subset pairs × {full, short} buffers.
    assert_eq!(runs, 32 * 32 * 2);
}
