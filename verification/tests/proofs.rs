//! Bounded-exhaustive proofs of the fluid index arithmetic: every harness body of
//! `lbdem_verification::harness::fluid` run through the [`for_all`] odometer over all its choices with
//! nx, ny ∈ 1..=[`MAX`], asserting the number of runs so the enumeration cannot silently shrink. Under
//! `cfg(kani)` the same bodies are Kani proofs (`cargo kani -p lbdem-verification --tests`).
//!
//! Overflow freedom rests on overflow checks being on in the profile the kernels are built with;
//! [`overflow_checks_are_on`] makes sure they are, so a run in a profile without them fails loudly instead of
//! proving less than it says.
use lbdem_verification::for_all;
use lbdem_verification::harness::fluid;

/// Largest nx and ny enumerated.
const MAX: usize = 12;
/// Number of D2Q9 directions.
const Q: u64 = 9;

/// Σ_{n=1..MAX} n.
fn triangle(max: usize) -> u64 {
    (max * (max + 1) / 2) as u64
}

/// The number of k-element non-decreasing tuples from 0..=n: C(n + k, k).
fn multichoose(n: usize, k: usize) -> u64 {
    let mut r = 1u64;
    for i in 1..=k as u64 {
        r = r * (n as u64 + i) / i;
    }
    r
}

#[test]
fn overflow_checks_are_on() {
    let r = std::panic::catch_unwind(|| {
        std::hint::black_box(usize::MAX) + std::hint::black_box(1usize)
    });
    assert!(
        r.is_err(),
        "the proofs need overflow checks (run them in the test or dev profile)"
    );
}

#[test]
fn shape_layout_for_all_small_lattices() {
    let runs = for_all(|c| fluid::shape_layout(c, MAX));
    assert_eq!(runs, (MAX * MAX * fluid::ELEMENT_BYTES.len()) as u64);
}

#[test]
fn shape_new_at_the_size_limits() {
    let runs = for_all(|c| fluid::shape_new_any_size(c, Some(&fluid::EDGE_SIZES)));
    let k = fluid::EDGE_SIZES.len() as u64;
    assert_eq!(runs, k * k * fluid::ELEMENT_BYTES.len() as u64);
}

#[test]
fn index_coords_offset_for_all_nodes_and_directions() {
    let runs = for_all(|c| fluid::index_coords_offset(c, MAX));
    assert_eq!(runs, 2 * Q * triangle(MAX) * triangle(MAX));
}

#[test]
fn neighbour_and_upstream_for_all_nodes_directions_and_periodicities() {
    let runs = for_all(|c| fluid::neighbour_and_upstream(c, MAX));
    assert_eq!(runs, 2 * 4 * Q * triangle(MAX) * triangle(MAX));
}

#[test]
fn bulk_rows_band_for_all_lattices_and_bands() {
    let runs = for_all(|c| fluid::bulk_rows_band(c, MAX));
    // y0 ≤ y1 in 0..=ny: C(ny + 2, 2) bands per lattice.
    let bands: u64 = (1..=MAX).map(|ny| multichoose(ny, 2)).sum();
    assert_eq!(runs, MAX as u64 * bands);
}

#[test]
fn aa_bulk_rows_for_all_lattices_and_band_splits() {
    let runs = for_all(|c| fluid::aa_bulk_rows_band(c, MAX));
    assert_eq!(
        runs,
        MAX as u64 * (1..=MAX as u64).map(|ny| ny + 1).sum::<u64>()
    );
}

#[test]
fn nodes_in_rows_split_for_all_lattices_and_band_pairs() {
    let runs = for_all(|c| fluid::nodes_in_rows_split(c, MAX));
    // step ∈ 1..=3 with `step` choices of `first` (6 in all); y0 ≤ ym ≤ y1 in 0..=ny: C(ny + 3, 3).
    let bands: u64 = (1..=MAX).map(|ny| multichoose(ny, 3)).sum();
    assert_eq!(runs, MAX as u64 * 6 * bands);
}

#[test]
fn fix_passes_in_bounds_for_all_side_conditions_obstacles_and_bands() {
    const FIX_MAX: usize = 6;
    let runs = for_all(|c| fluid::fix_passes_in_bounds(c, FIX_MAX));
    let per_side = fluid::AXIS_CONDITIONS as u64;
    let shapes: u64 = (1..=FIX_MAX)
        .flat_map(|nx| (1..=FIX_MAX).map(move |ny| ((nx * ny + 1) * (ny + 1)) as u64))
        .sum();
    assert_eq!(runs, per_side * per_side * shapes);
}

#[test]
fn boundary_validation_for_all_interesting_values() {
    let runs = for_all(fluid::boundary_validation);
    let k = lbdem_verification::INTERESTING_F64.len() as u64;
    assert_eq!(runs, 4 * (k + k * k) + 16);
}

/// Kani proofs of the same bodies (not run here: Kani cannot be installed on these machines). The layout and
/// neighbour bodies are loop-free and proved for the same bound (`shape_new_any_size` for every `usize`);
/// `nodes_in_rows_split` loops over at most `LOOPING_MAX`² nodes and is proved for that smaller bound;
/// `boundary_validation` is proved for every `f64` value (the bounded-exhaustive run above enumerates only
/// the interesting-value table).
/// `bulk_rows_band`, `aa_bulk_rows_band` and `fix_passes_in_bounds` have no Kani wrapper: they fill page-padded
/// population buffers (≥ 9 × 552 elements even for one node), far beyond practical loop unwinding, so their
/// bounded proof is the exhaustive `for_all` run above.
#[cfg(kani)]
mod kani_proofs {
    use super::MAX;
    use lbdem_verification::harness::fluid;
    use lbdem_verification::KaniChooser;

    /// Bound for the body that loops over every node.
    const LOOPING_MAX: usize = 4;

    #[kani::proof]
    fn shape_layout() {
        fluid::shape_layout(&mut KaniChooser, MAX);
    }

    /// Every nx, ny ∈ 1..=usize::MAX.
    #[kani::proof]
    #[kani::unwind(10)]
    fn shape_new_any_size() {
        fluid::shape_new_any_size(&mut KaniChooser, None);
    }

    #[kani::proof]
    fn index_coords_offset() {
        fluid::index_coords_offset(&mut KaniChooser, MAX);
    }

    #[kani::proof]
    fn neighbour_and_upstream() {
        fluid::neighbour_and_upstream(&mut KaniChooser, MAX);
    }

    #[kani::proof]
    #[kani::unwind(18)]
    fn nodes_in_rows_split() {
        fluid::nodes_in_rows_split(&mut KaniChooser, LOOPING_MAX);
    }

    /// Every side, kind and `f64` value.
    #[kani::proof]
    #[kani::unwind(5)]
    fn boundary_validation() {
        fluid::boundary_validation(&mut KaniChooser);
    }
}
