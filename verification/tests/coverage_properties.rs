//! Properties of the solid-fraction kernels (`lbdem_kernels::coverage`) for every input: against the quadrature
//! oracle `lbdem_reference::coverage` (a guaranteed enclosure of the exact area that shares no formula with the
//! kernels), against the exact areas πr² and πab, and against exact geometric facts (a cell clear of a body is
//! uncovered, bitwise 0; a cell inside an ellipse is covered, bitwise 1; whole-cell translations and 90°
//! rotations do not change a fraction).
//!
//! Inputs: centres anywhere in [−30, 30]² (near the origin, negative, on and across cell edges), disc radii and
//! semi-axes log-uniform from 0.05 (a twentieth of a cell) to 20 (forty cells across), aspect ratios
//! b/a ∈ [0.1, 1], any orientation; rectangles of any aspect from 0.01 to 40 cells.
//!
//! **Tolerances.** The kernels are exact up to roundoff; [`cell_roundoff`] bounds it per cell: the disc
//! formula sums a few primitives of size ≤ r² (≤ 10 ulp of scale² each), the ellipse formula works in the
//! unit-disc frame and scales by ab ≤ scale², and every corner coordinate x − c carries ≤ ½ ulp of |c| + |x|
//! (≤ 64 here), which moves the area by at most the cell perimeter (4) times that. 64 ε (1 + scale² + 4 · 64)
//! covers all of it with margin; sums over n cells allow n times that. The oracle's enclosure carries its own
//! quadrature error (≈ 1e-6 of a cell with the sample counts used here), so a formula error larger than that
//! is caught, and any error at all in the exact-value properties.
use lbdem_kernels::coverage::{
    disc_cell_fraction, disc_rectangle_area, disc_triangle_signed_area, ellipse_cell_fraction,
    ellipse_cell_fraction_oriented, ellipse_cell_grid, ellipse_grid_fractions,
    ellipse_rectangle_area, ellipse_rectangle_area_oriented,
};
use lbdem_kernels::math::{vector, Vector};
use lbdem_kernels::Real;
use lbdem_reference::coverage as oracle;
use lbdem_verification::proptest_cases;
use proptest::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

/// Quadrature intervals per oracle call: enclosure width ≈ 1e-6 of a cell for a unit cell.
const SAMPLES: usize = 2000;

/// Roundoff allowance of one kernel area evaluation for a body of size `scale` (see the module docs).
fn cell_roundoff(scale: f64) -> f64 {
    64.0 * f64::EPSILON * (1.0 + scale * scale + 4.0 * 64.0)
}

fn config(default: u32) -> ProptestConfig {
    ProptestConfig::with_cases(proptest_cases(default))
}

/// A length log-uniform in [lo, hi].
fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo.ln()..=hi.ln()).prop_map(f64::exp)
}

fn centre() -> impl Strategy<Value = [f64; 2]> {
    [-30.0f64..=30.0, -30.0f64..=30.0]
}

/// An ellipse (a ≥ b) anywhere, of any size and orientation.
fn ellipse() -> impl Strategy<Value = oracle::Ellipse> {
    (
        centre(),
        log_uniform(0.05, 20.0),
        0.1f64..=1.0,
        -2.0 * PI..=2.0 * PI,
    )
        .prop_map(|(centre, a, aspect, angle)| oracle::Ellipse {
            centre,
            a,
            b: a * aspect,
            angle,
        })
}

fn disc() -> impl Strategy<Value = oracle::Ellipse> {
    (centre(), log_uniform(0.05, 20.0)).prop_map(|(centre, r)| oracle::Ellipse {
        centre,
        a: r,
        b: r,
        angle: 0.0,
    })
}

/// The lattice nodes whose cells can meet the body: its bounding box, widened by a cell.
fn nodes_near(e: &oracle::Ellipse) -> impl Iterator<Item = (f64, f64)> {
    let reach = e.a.max(e.b) + 1.0;
    let (x0, x1) = (
        (e.centre[0] - reach).floor() as i64,
        (e.centre[0] + reach).ceil() as i64,
    );
    let (y0, y1) = (
        (e.centre[1] - reach).floor() as i64,
        (e.centre[1] + reach).ceil() as i64,
    );
    (y0..=y1).flat_map(move |y| (x0..=x1).map(move |x| (x as f64, y as f64)))
}

/// Nodes to compare with the oracle: `k` whose cells the boundary crosses or grazes (a boundary point at
/// parameter φ, pushed in or out by up to 20 %, rounded to a node) and `k` anywhere in the bounding box.
fn probe_nodes(e: &oracle::Ellipse, picks: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let reach = e.a.max(e.b);
    let mut out = Vec::new();
    for &(phi, t) in picks {
        let p = e.boundary_point(phi);
        let push = 0.8 + 0.4 * t;
        let q = [
            e.centre[0] + push * (p[0] - e.centre[0]),
            e.centre[1] + push * (p[1] - e.centre[1]),
        ];
        out.push((q[0].round(), q[1].round()));
        let r = [
            e.centre[0] + (2.0 * t - 1.0) * (reach + 1.0),
            e.centre[1] + (phi / PI - 1.0) * (reach + 1.0),
        ];
        out.push((r[0].round(), r[1].round()));
    }
    out
}

fn picks() -> impl Strategy<Value = Vec<(f64, f64)>> {
    prop::collection::vec((0.0f64..2.0 * PI, 0.0f64..=1.0), 4)
}

fn kernel_ellipse_fraction(e: &oracle::Ellipse, x: f64, y: f64) -> f64 {
    ellipse_cell_fraction(Vector::from(e.centre), e.a, e.b, e.angle, x, y)
}

proptest! {
    #![proptest_config(config(128))]

    /// Disc: every cell fraction is in [0, 1], the fractions over the plane sum to πr², and sampled cells
    /// (boundary and interior) agree with the oracle.
    #[test]
    fn disc_fractions_sum_to_pi_r_squared_and_match_the_oracle(d in disc(), picks in picks()) {
        let (c, r) = (d.centre, d.a);
        let (mut sum, mut touched) = (0.0, 0usize);
        for (x, y) in nodes_near(&d) {
            let f = disc_cell_fraction(Vector::from(c), r, x, y);
            prop_assert!((0.0..=1.0).contains(&f), "cell ({x}, {y}): {f}");
            sum += f;
            touched += usize::from(f > 0.0);
        }
        let tol = cell_roundoff(r) * touched as f64;
        prop_assert!((sum - PI * r * r).abs() <= tol, "sum {sum} vs {} over {touched} cells", PI * r * r);
        for (x, y) in probe_nodes(&d, &picks) {
            let f = disc_cell_fraction(Vector::from(c), r, x, y);
            let want = oracle::ellipse_rectangle_area(&d, oracle::cell(x, y), SAMPLES);
            let slack = cell_roundoff(r);
            prop_assert!(f >= want.lo - slack && f <= want.hi + slack, "cell ({x}, {y}): {f} vs {want:?}");
        }
    }

    /// Ellipse: fractions in [0, 1], summing to πab over the plane, agreeing with the oracle on sampled cells,
    /// and the `_oriented` variant is bitwise the same for θ's portable sine and cosine.
    #[test]
    fn ellipse_fractions_sum_to_pi_a_b_and_match_the_oracle(e in ellipse(), picks in picks()) {
        let sin_cos = e.angle.portable_sin_cos();
        let (mut sum, mut touched) = (0.0, 0usize);
        for (x, y) in nodes_near(&e) {
            let f = kernel_ellipse_fraction(&e, x, y);
            prop_assert!((0.0..=1.0).contains(&f), "cell ({x}, {y}): {f}");
            let g = ellipse_cell_fraction_oriented(Vector::from(e.centre), e.a, e.b, sin_cos, x, y);
            prop_assert_eq!(f.to_bits(), g.to_bits());
            sum += f;
            touched += usize::from(f > 0.0);
        }
        let tol = cell_roundoff(e.a) * touched as f64;
        prop_assert!((sum - PI * e.a * e.b).abs() <= tol, "sum {sum} vs {}", PI * e.a * e.b);
        for (x, y) in probe_nodes(&e, &picks) {
            let f = kernel_ellipse_fraction(&e, x, y);
            let want = oracle::ellipse_rectangle_area(&e, oracle::cell(x, y), SAMPLES);
            let slack = cell_roundoff(e.a);
            prop_assert!(f >= want.lo - slack && f <= want.hi + slack, "cell ({x}, {y}): {f} vs {want:?}");
        }
    }

    /// The whole-ellipse kernel (Green's theorem, one angle per crossing with a lattice line): every cell of
    /// its block in [0, 1], bitwise 0 or 1 wherever the per-cell formula gives exactly 0 or 1, otherwise within
    /// two cells' roundoff of it (both are exact), sampled cells within the oracle's enclosure, and the sum πab
    /// to roundoff. A refusal (a crossing within the kernel's margin of a lattice vertex) is rare: counted, and
    /// the vertex-crossing case is pinned in the kernel's unit tests. Centres also exactly on cell edges and
    /// nodes (`snap`), where tangencies and crossings at vertices occur.
    #[test]
    fn grid_fractions_match_the_per_cell_formula_and_the_oracle(
        e in ellipse(), picks in picks(), snap in 0u8..4,
    ) {
        let mut e = e;
        match snap {
            1 => e.centre = e.centre.map(|v| v.round()),
            2 => e.centre = e.centre.map(|v| v.round() + 0.5),
            _ => {}
        }
        let c = Vector::from(e.centre);
        let sin_cos = e.angle.portable_sin_cos();
        let g = ellipse_cell_grid(c, e.a, e.b).expect("a valid ellipse");
        let n = g.cells().expect("a small block");
        let (mut fr, mut bd) = (vec![0.0; n], vec![false; n]);
        if !ellipse_grid_fractions(c, e.a, e.b, sin_cos, g, &mut fr, &mut bd) {
            // Refusals are the caller's cue to use the per-cell formula; nothing else to check.
            return Ok(());
        }
        let at = |x: f64, y: f64| {
            let (i, j) = (x as i64 - g.x0, y as i64 - g.y0);
            (i >= 0 && j >= 0 && (i as usize) < g.w && (j as usize) < g.h)
                .then(|| fr[j as usize * g.w + i as usize])
        };
        let mut sum = 0.0;
        for (x, y) in nodes_near(&e) {
            let want = ellipse_cell_fraction_oriented(c, e.a, e.b, sin_cos, x, y);
            // Cells outside the block are outside the bounding circle: the formula gives 0 there.
            let f = at(x, y).unwrap_or(0.0);
            prop_assert!((0.0..=1.0).contains(&f), "cell ({x}, {y}): {f}");
            if want == 0.0 || want == 1.0 {
                prop_assert_eq!(f, want, "cell ({}, {})", x, y);
            } else {
                prop_assert!((f - want).abs() <= 2.0 * cell_roundoff(e.a), "cell ({x}, {y}): {f} vs {want}");
            }
            sum += f;
        }
        let touched = fr.iter().filter(|&&f| f > 0.0).count();
        let tol = cell_roundoff(e.a) * touched as f64;
        prop_assert!((sum - PI * e.a * e.b).abs() <= tol, "sum {sum} vs {}", PI * e.a * e.b);
        for (x, y) in probe_nodes(&e, &picks) {
            let f = at(x, y).unwrap_or(0.0);
            let want = oracle::ellipse_rectangle_area(&e, oracle::cell(x, y), SAMPLES);
            let slack = cell_roundoff(e.a);
            prop_assert!(f >= want.lo - slack && f <= want.hi + slack, "cell ({x}, {y}): {f} vs {want:?}");
        }
    }

    /// Any rectangle (empty, thin, larger than the body, partly or wholly outside it): the disc and ellipse
    /// areas agree with the oracle; an empty rectangle has area 0; the oriented ellipse variant is bitwise the
    /// same.
    #[test]
    fn rectangle_areas_match_the_oracle(
        e in ellipse(), d in disc(), corner in centre(), w in log_uniform(0.01, 40.0),
        h in log_uniform(0.01, 40.0), flip in any::<bool>(),
    ) {
        let rect = [corner[0], corner[0] + w, corner[1], corner[1] + h];
        // An empty rectangle (x1 ≤ x0) covers nothing.
        if flip {
            prop_assert_eq!(disc_rectangle_area(Vector::from(d.centre), d.a, rect[1], rect[0], rect[2], rect[3]), 0.0);
            prop_assert_eq!(ellipse_rectangle_area(Vector::from(e.centre), e.a, e.b, e.angle, [rect[0], rect[1], rect[3], rect[2]]), 0.0);
        }
        let samples = 2 * SAMPLES;
        let got = disc_rectangle_area(Vector::from(d.centre), d.a, rect[0], rect[1], rect[2], rect[3]);
        let want = oracle::ellipse_rectangle_area(&d, rect, samples);
        // Each cell-sized piece of the rectangle carries the per-cell roundoff.
        let pieces = (w.max(1.0) * h.max(1.0)).min(PI * (d.a + 1.0) * (d.a + 1.0));
        let slack = cell_roundoff(d.a) * pieces;
        prop_assert!(got >= want.lo - slack && got <= want.hi + slack, "disc {got} vs {want:?}");
        let got = ellipse_rectangle_area(Vector::from(e.centre), e.a, e.b, e.angle, rect);
        let oriented = ellipse_rectangle_area_oriented(Vector::from(e.centre), e.a, e.b, e.angle.portable_sin_cos(), rect);
        prop_assert_eq!(got.to_bits(), oriented.to_bits());
        let want = oracle::ellipse_rectangle_area(&e, rect, samples);
        let pieces = (w.max(1.0) * h.max(1.0)).min(PI * (e.a + 1.0) * (e.a + 1.0));
        let slack = cell_roundoff(e.a) * pieces;
        prop_assert!(got >= want.lo - slack && got <= want.hi + slack, "ellipse {got} vs {want:?}");
    }

    /// A body at or across the edges of an nx × ny lattice: the fractions of the lattice's cells sum to the
    /// area of the body inside the lattice's domain [−½, nx − ½] × [−½, ny − ½] (oracle).
    #[test]
    fn fractions_on_a_lattice_sum_to_the_area_inside_it(
        nx in 1usize..=24, ny in 1usize..=24, e in ellipse(), at in [0.0f64..=1.0, 0.0f64..=1.0],
        is_disc in any::<bool>(),
    ) {
        let reach = e.a.max(e.b);
        // Centre anywhere from one reach outside the west/south edges to one reach outside the east/north ones.
        let mut e = e;
        e.centre = [
            -0.5 - reach + at[0] * (nx as f64 + 2.0 * reach),
            -0.5 - reach + at[1] * (ny as f64 + 2.0 * reach),
        ];
        if is_disc {
            e.b = e.a;
        }
        let (mut sum, mut touched) = (0.0, 0usize);
        for y in 0..ny {
            for x in 0..nx {
                let (x, y) = (x as f64, y as f64);
                let f = if is_disc {
                    disc_cell_fraction(Vector::from(e.centre), e.a, x, y)
                } else {
                    kernel_ellipse_fraction(&e, x, y)
                };
                sum += f;
                touched += usize::from(f > 0.0);
            }
        }
        let domain = [-0.5, nx as f64 - 0.5, -0.5, ny as f64 - 0.5];
        let want = oracle::ellipse_rectangle_area(&e, domain, 8 * SAMPLES);
        let slack = cell_roundoff(reach) * (touched as f64 + 1.0);
        prop_assert!(sum >= want.lo - slack && sum <= want.hi + slack, "sum {sum} vs {want:?} ({touched} cells)");
    }

    /// Exactness at the edges of a body: a cell clear of the body (even when widened by 1e-9 on every side,
    /// per the oracle) has fraction bitwise 0; a cell whose four corners lie inside an ellipse (by more than
    /// roundoff) has fraction bitwise 1. Bodies from sub-cell to many cells, so a cell can also contain a whole
    /// body.
    #[test]
    fn clear_cells_are_exactly_empty_and_inner_cells_exactly_full(e in ellipse(), is_disc in any::<bool>()) {
        let mut e = e;
        if is_disc {
            e.b = e.a;
        }
        let (s, c) = e.angle.sin_cos();
        let level = |x: f64, y: f64| {
            let (dx, dy) = (x - e.centre[0], y - e.centre[1]);
            let (u, v) = ((c * dx + s * dy) / e.a, (-s * dx + c * dy) / e.b);
            u * u + v * v
        };
        let (mut empty, mut full) = (0, 0);
        for (x, y) in nodes_near(&e) {
            let f = if is_disc {
                disc_cell_fraction(Vector::from(e.centre), e.a, x, y)
            } else {
                kernel_ellipse_fraction(&e, x, y)
            };
            let widened = [x - 0.5 - 1e-9, x + 0.5 + 1e-9, y - 0.5 - 1e-9, y + 0.5 + 1e-9];
            if oracle::ellipse_rectangle_area(&e, widened, 64).hi == 0.0 {
                prop_assert_eq!(f, 0.0, "cell ({}, {}) is clear of the body", x, y);
                empty += 1;
            }
            let corners = [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)];
            if !is_disc && corners.iter().all(|(dx, dy)| level(x + dx, y + dy) < 1.0 - 1e-9) {
                prop_assert_eq!(f, 1.0, "cell ({}, {}) is inside the ellipse", x, y);
                full += 1;
            }
        }
        // The bounding box widened by a cell always has clear cells (its corners).
        prop_assert!(empty >= 4, "only {empty} clear cells");
        let _ = full;
    }

    /// Translating the body and the cell by the same whole number of cells leaves the fraction unchanged (to
    /// the roundoff of the shifted coordinates), for discs and ellipses.
    #[test]
    fn whole_cell_translation_leaves_fractions_unchanged(
        e in ellipse(), picks in picks(), shift in [-20i32..=20, -20i32..=20],
    ) {
        let (sx, sy) = (shift[0] as f64, shift[1] as f64);
        let moved = oracle::Ellipse { centre: [e.centre[0] + sx, e.centre[1] + sy], ..e };
        for (x, y) in probe_nodes(&e, &picks) {
            let (a, b) = (kernel_ellipse_fraction(&e, x, y), kernel_ellipse_fraction(&moved, x + sx, y + sy));
            prop_assert!((a - b).abs() <= 2.0 * cell_roundoff(e.a), "ellipse cell ({x}, {y}): {a} vs {b}");
        }
    }

    /// Rotating the body and the cell by 90° about the origin, (x, y) → (−y, x) (and θ → θ + π/2 for an
    /// ellipse), leaves the fraction unchanged: the rotation is exact on the coordinates, and the rounding of
    /// θ + π/2 (½ ulp of 2π) turns the boundary by at most a·1e-15, far below the per-cell roundoff.
    #[test]
    fn quarter_turn_leaves_fractions_unchanged(e in ellipse(), picks in picks()) {
        let turned = oracle::Ellipse { centre: [-e.centre[1], e.centre[0]], angle: e.angle + FRAC_PI_2, ..e };
        for (x, y) in probe_nodes(&e, &picks) {
            let (a, b) = (kernel_ellipse_fraction(&e, x, y), kernel_ellipse_fraction(&turned, -y, x));
            prop_assert!((a - b).abs() <= 2.0 * cell_roundoff(e.a), "ellipse cell ({x}, {y}): {a} vs {b}");
        }
    }

    /// An ellipse with equal semi-axes is the disc, at any orientation; and the disc path is as exact as the
    /// ellipse path under whole-cell translations, quarter turns and in `f32`.
    ///
    /// This caught an ill-conditioning of the disc formula where a breakpoint lies near a tangent point of the
    /// circle (the half chord √(r² − t²) → 0; with r² − t² and asin(t/r) the error grew like ε r³/√(r² − t²)):
    /// 2.6e-11 of a cell in f64 at r = 16.26 (a 40-digit quadrature gives 0.25754737820635497, the ellipse path
    /// 0.2575473782063564, the old disc path 0.2575473782320282) and 5.7e-3 of a cell in f32. The kernel now
    /// carries each breakpoint with its half chord and uses atan2; [`disc_near_tangency_regression`] keeps that
    /// case.
    #[test]
    fn disc_path_is_as_exact_as_the_ellipse_path(
        d in disc(), angle in -PI..=PI, picks in picks(), shift in [-20i32..=20, -20i32..=20],
    ) {
        let tol = 2.0 * cell_roundoff(d.a);
        let (sx, sy) = (shift[0] as f64, shift[1] as f64);
        for (x, y) in probe_nodes(&d, &picks) {
            let a = disc_cell_fraction(Vector::from(d.centre), d.a, x, y);
            let b = ellipse_cell_fraction(Vector::from(d.centre), d.a, d.a, angle, x, y);
            prop_assert!((a - b).abs() <= tol, "cell ({x}, {y}): {a} vs {b}");
            let moved = disc_cell_fraction(Vector::from([d.centre[0] + sx, d.centre[1] + sy]), d.a, x + sx, y + sy);
            prop_assert!((a - moved).abs() <= tol, "translated cell ({x}, {y}): {a} vs {moved}");
            let turned = disc_cell_fraction(Vector::from([-d.centre[1], d.centre[0]]), d.a, -y, x);
            prop_assert!((a - turned).abs() <= tol, "turned cell ({x}, {y}): {a} vs {turned}");
            let (c32, r32) = ([d.centre[0] as f32, d.centre[1] as f32], d.a as f32);
            let f = disc_cell_fraction(Vector::from(c32), r32, x as f32, y as f32) as f64;
            let g = disc_cell_fraction(Vector::from([c32[0] as f64, c32[1] as f64]), r32 as f64, x, y);
            let tol32 = tol * (f32::EPSILON as f64 / f64::EPSILON);
            prop_assert!((f - g).abs() <= tol32, "f32 cell ({x}, {y}): f32 {f} vs f64 {g}");
        }
    }

    /// disc ∩ triangle(origin, p, q) for any radius (not only the unit disc the ellipse formula uses): the
    /// signed area agrees with the oracle, changes sign with the orientation, and is zero for p = q.
    #[test]
    fn disc_triangle_signed_area_matches_the_oracle(
        r in log_uniform(0.05, 20.0), p in [-3.0f64..=3.0, -3.0f64..=3.0], q in [-3.0f64..=3.0, -3.0f64..=3.0],
    ) {
        // Vertices within three radii of the centre: from triangles inside the disc to ones far beyond it.
        let (p, q) = ([p[0] * r, p[1] * r], [q[0] * r, q[1] * r]);
        let got = disc_triangle_signed_area(r, p, q);
        let want = oracle::disc_triangle_signed_area(r, p, q, SAMPLES);
        let slack = cell_roundoff(r);
        prop_assert!(got >= want.lo - slack && got <= want.hi + slack, "{got} vs {want:?}");
        let back = disc_triangle_signed_area(r, q, p);
        prop_assert!((got + back).abs() <= 2.0 * slack, "{got} vs reversed {back}");
        prop_assert_eq!(disc_triangle_signed_area(r, p, p), 0.0);
    }

    /// The `f32` instantiations agree with the `f64` ones on the same (f32-representable) inputs, within the
    /// per-cell roundoff bound of `f32`.
    #[test]
    fn f32_fractions_match_f64(e in ellipse(), picks in picks()) {
        let r32 = |v: f64| v as f32;
        let c32 = [r32(e.centre[0]), r32(e.centre[1])];
        let (a32, b32, t32) = (r32(e.a), r32(e.b), r32(e.angle));
        let c64 = [c32[0] as f64, c32[1] as f64];
        let (a64, b64, t64) = (a32 as f64, b32 as f64, t32 as f64);
        // cell_roundoff scaled from f64's ε to f32's.
        let tol = cell_roundoff(e.a) * (f32::EPSILON as f64 / f64::EPSILON);
        for (x, y) in probe_nodes(&e, &picks) {
            let f = ellipse_cell_fraction(Vector::from(c32), a32, b32, t32, x as f32, y as f32) as f64;
            let g = ellipse_cell_fraction(Vector::from(c64), a64, b64, t64, x, y);
            prop_assert!((f - g).abs() <= tol, "ellipse cell ({x}, {y}): f32 {f} vs f64 {g}");
        }
    }
}

/// Non-positive or NaN sizes and empty rectangles give 0, never NaN, for both shapes: for rectangles inside
/// the body, crossing its boundary and containing it (a negative semi-axis must not be taken as a mirror
/// image), and for rectangles of zero width or height crossing the boundary (exactly 0, not a sum of sector
/// terms that cancels to roundoff).
#[test]
fn degenerate_bodies_and_rectangles_cover_nothing() {
    let rects = [
        [-0.5, 0.5, -0.5, 0.5],
        [0.2, 2.0, -0.3, 1.7],
        [-3.0, 3.0, -3.0, 3.0],
    ];
    for rect in rects {
        let [x0, x1, y0, y1] = rect;
        for bad in [0.0, -1.0, -2.5, f64::NAN] {
            assert_eq!(
                disc_rectangle_area(vector(0.0, 0.0), bad, x0, x1, y0, y1),
                0.0
            );
            for theta in [0.0, 0.3, 2.0] {
                assert_eq!(
                    ellipse_rectangle_area(vector(0.0, 0.0), bad, 1.0, theta, rect),
                    0.0
                );
                assert_eq!(
                    ellipse_rectangle_area(vector(0.0, 0.0), 1.0, bad, theta, rect),
                    0.0
                );
                assert_eq!(
                    ellipse_rectangle_area(vector(0.0, 0.0), bad, bad, theta, rect),
                    0.0
                );
            }
        }
    }
    for (x0, x1, y0, y1) in [
        (1.0, 1.0, -1.0, 1.0),
        (-1.0, 1.0, 1.0, -1.0),
        (f64::NAN, 1.0, -1.0, 1.0),
    ] {
        assert_eq!(
            disc_rectangle_area(vector(0.0, 0.0), 1.0, x0, x1, y0, y1),
            0.0
        );
        assert_eq!(
            ellipse_rectangle_area(vector(0.0, 0.0), 2.0, 1.0, 0.3, [x0, x1, y0, y1]),
            0.0
        );
    }
    // Zero-width and zero-height rectangles through the boundary of a tilted ellipse and of a disc.
    for k in 0..400 {
        let t = k as f64 * 0.0137;
        let (x, y) = (
            -2.5 + 5.0 * (t * 7.3).fract(),
            -2.5 + 5.0 * (t * 3.1).fract(),
        );
        let theta = t * 5.0;
        for rect in [[x, x, y - 3.0, y + 3.0], [x - 3.0, x + 3.0, y, y]] {
            assert_eq!(
                ellipse_rectangle_area(vector(0.1, -0.2), 2.0, 0.7, theta, rect),
                0.0,
                "{rect:?}"
            );
            assert_eq!(
                disc_rectangle_area(vector(0.1, -0.2), 1.3, rect[0], rect[1], rect[2], rect[3]),
                0.0
            );
        }
    }
}

/// A body wholly inside one cell covers its own area, wherever in the cell it sits (the cell contains the
/// origin of the unit-disc frame; the quick rejection and the early outs must not drop it).
#[test]
fn a_body_inside_one_cell_covers_its_own_area() {
    for k in 0..50 {
        let t = k as f64;
        let (a, b) = (0.02 + 0.004 * t, 0.01 + 0.002 * t);
        // |c| + a ≤ 0.25 + 0.216 < ½ on each axis: the body stays inside the cell.
        let c = [0.25 * (t * 0.37).sin(), 0.25 * (t * 0.61).cos()];
        let theta = 0.7 * t;
        let f = ellipse_cell_fraction(Vector::from(c), a, b, theta, 0.0, 0.0);
        assert!(
            (f - PI * a * b).abs() <= cell_roundoff(1.0),
            "{f} vs {}",
            PI * a * b
        );
        let g = disc_cell_fraction(Vector::from(c), a, 0.0, 0.0);
        assert!((g - PI * a * a).abs() <= cell_roundoff(1.0), "{g}");
    }
}

/// The case that exposed the disc formula's ill-conditioning near tangency (r = 16.26: the horizontal edges of
/// the cells at the disc's height cross the circle next to its leftmost and rightmost points): every cell of the
/// bounding box agrees with the ellipse path (sectors by atan2) within roundoff, in f64 and in f32. Before the fix
/// one cell was off by 2.6e-11 in f64 (≈ 200 × the bound) and 5.7e-3 in f32.
#[test]
fn disc_near_tangency_regression() {
    let d = oracle::Ellipse {
        centre: [6.5060620186448315, 2.4946140745030694],
        a: 16.261575424519968,
        b: 16.261575424519968,
        angle: 0.0,
    };
    let tol = 2.0 * cell_roundoff(d.a);
    let tol32 = tol * (f32::EPSILON as f64 / f64::EPSILON);
    let (c32, r32) = ([d.centre[0] as f32, d.centre[1] as f32], d.a as f32);
    let mut cells = 0;
    for (x, y) in nodes_near(&d) {
        let a = disc_cell_fraction(Vector::from(d.centre), d.a, x, y);
        let b = kernel_ellipse_fraction(&d, x, y);
        assert!(
            (a - b).abs() <= tol,
            "cell ({x}, {y}): disc {a} vs ellipse {b}"
        );
        let f = disc_cell_fraction(Vector::from(c32), r32, x as f32, y as f32) as f64;
        let g = disc_cell_fraction(
            Vector::from([c32[0] as f64, c32[1] as f64]),
            r32 as f64,
            x,
            y,
        );
        assert!(
            (f - g).abs() <= tol32,
            "f32 cell ({x}, {y}): f32 {f} vs f64 {g}"
        );
        cells += usize::from(a > 0.0 && a < 1.0);
    }
    // The circle crosses about 4 · 2r ≈ 130 cells; a scan that saw none would prove nothing.
    assert!(cells > 100, "only {cells} boundary cells");
}

/// The grid kernel's branch cut when its first candidate points are unusable: the ellipse's extreme points
/// along its axes are put exactly on lattice lines (x = k + ½ or y = k + ½), so the kernel must take a later
/// candidate (the bottom point, the right point, a diagonal one) for the cut of its angles. Every cell must
/// still match the per-cell formula within two cells' roundoff (both are exact): an angle reference that is not
/// the chosen cut's opposite puts the arc's missing 2π into the wrong cell, a change of ≈ π of a cell.
#[test]
fn grid_fractions_take_a_later_branch_cut_when_the_first_lies_on_a_lattice_line() {
    // (centre, a, b, angle): the left point on x = 7.5 (cut → bottom point); the left and bottom points on
    // lines (cut → right point); the left and right points on x = 7.5 and 13.5 and the top and bottom points on
    // x = 10.5 (cut → a diagonal point; no crossing at a vertex); a rotated ellipse whose left point
    // (c − a (cos θ, sin θ)) sits on x = −2.5.
    let theta: f64 = 0.4;
    let cases = [
        ([10.25, 20.27], 2.75, 1.9, 0.0),
        ([10.25, 20.4], 2.75, 1.9, 0.0),
        ([10.5, 20.27], 3.0, 1.9, 0.0),
        (
            [-2.5 + 4.0 * theta.cos(), 1.13 + 4.0 * theta.sin()],
            4.0,
            1.5,
            theta,
        ),
    ];
    for (centre, a, b, angle) in cases {
        let c = Vector::from(centre);
        let sin_cos = angle.portable_sin_cos();
        let g = ellipse_cell_grid(c, a, b).expect("a valid ellipse");
        let n = g.cells().expect("a small block");
        let (mut fr, mut bd) = (vec![0.0; n], vec![false; n]);
        assert!(
            ellipse_grid_fractions(c, a, b, sin_cos, g, &mut fr, &mut bd),
            "{centre:?}: no crossing is near a lattice vertex, the kernel must not refuse"
        );
        let (mut sum, mut touched) = (0.0, 0);
        for j in 0..g.h {
            for i in 0..g.w {
                let (x, y) = ((g.x0 + i as i64) as f64, (g.y0 + j as i64) as f64);
                let want = ellipse_cell_fraction_oriented(c, a, b, sin_cos, x, y);
                let f = fr[j * g.w + i];
                assert!(
                    (f - want).abs() <= 2.0 * cell_roundoff(a),
                    "{centre:?}, cell ({x}, {y}): {f} vs {want}"
                );
                sum += f;
                touched += usize::from(f > 0.0);
            }
        }
        // The sum of exact fractions is πab up to one cell's roundoff per covered cell (as in the property test
        // above); the mutant's misplaced 2π moves area between cells, so the per-cell check is the one that bites.
        let tol = cell_roundoff(a) * touched as f64;
        assert!((sum - PI * a * b).abs() <= tol, "{centre:?}: sum {sum}");
    }
}

/// The grid of an ellipse is refused when either axis of its centre is not finite or out of the index range,
/// the other being fine (each bound is checked, not only one axis's pair).
#[test]
fn ellipse_cell_grid_refuses_a_bad_centre_on_either_axis() {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e12, -1e12] {
        assert!(
            ellipse_cell_grid(vector(bad, 3.2), 2.0, 1.0).is_none(),
            "x = {bad}"
        );
        assert!(
            ellipse_cell_grid(vector(3.2, bad), 2.0, 1.0).is_none(),
            "y = {bad}"
        );
    }
    assert!(ellipse_cell_grid(vector(3.2, 3.2), 2.0, 1.0).is_some());
}
