//! Solid fraction of lattice cells covered by solids (input of the partially-saturated collision, eq. 4.4–4.5).
//!
//! The cell of node (x, y) is the unit square [x − ½, x + ½] × [y − ½, y + ½] (lattice units). For a disc the
//! covered area is computed **exactly** (up to roundoff): the area of disc ∩ rectangle is ∫ of the covered chord
//! length over x, split at the (at most four) abscissae where the circle crosses the rectangle's top and bottom
//! edges; on each piece the integrand is a constant or ±√(r² − t²), whose primitive is
//! ½ (t √(r² − t²) + r² asin(t/r)), evaluated as ½ (t s + r² atan2(t, s)) with the half chord s = √(r² − t²)
//! carried exactly (|v| at a crossing of the edge y = v) or computed as √((r − t)(r + t)), so that the formula stays
//! accurate to roundoff where a breakpoint lies near a tangent point t = ±r.
//!
//! For an **ellipse** (semi-axes a, b, orientation θ) the covered area is also exact: the affine map
//! u ↦ ((R(−θ)(u − c))ₓ/a, (R(−θ)(u − c))ᵧ/b) sends the ellipse to the unit disc and the cell to a parallelogram,
//! and multiplies areas by 1/(ab). The area of a disc ∩ convex polygon is the sum over the polygon's edges of the
//! signed area of disc ∩ triangle(centre, edge start, edge end), each of which is a triangle part plus circular
//! sectors (closed form). Error: roundoff only.
use crate::math::Point;
use crate::Real;

/// √(r² − t²) for |t| ≤ r, as √((r − t)(r + t)): relative error of a few ulp even where t is close to ±r, where
/// r² − t² would cancel (this is what keeps the disc formula well-conditioned at tangency).
#[inline]
fn half_chord<T: Real>(r: T, t: T) -> T {
    ((r - t) * (r + t)).max(T::zero()).sqrt()
}

/// ∫₀ᵗ √(r² − s²) ds = ½ (t √(r² − t²) + r² asin(t/r)) for |t| ≤ r, from the abscissa `t` and its half chord
/// `root` = √(r² − t²). The angle is taken as atan2(t, root), not asin(t/r): asin amplifies the roundoff of t/r
/// by 1/√(1 − (t/r)²) near the tangent points t = ±r, atan2 of an accurate pair does not.
#[inline]
fn half_chord_primitive<T: Real>(r: T, t: T, root: T) -> T {
    T::lit(0.5) * (t * root + r * r * t.portable_atan2(root))
}

/// Exact area of the intersection of the disc (centre `c`, radius `r`) with the axis-aligned rectangle
/// [x0, x1] × [y0, y1]. Returns 0 for empty rectangles or non-positive radii.
pub fn disc_rectangle_area<T: Real>(c: Point<T>, r: T, x0: T, x1: T, y0: T, y1: T) -> T {
    if !(r > T::zero()) || !(x1 > x0) || !(y1 > y0) {
        return T::zero();
    }
    // Coordinates relative to the centre.
    let (u0, u1, v0, v1) = (x0 - c[0], x1 - c[0], y0 - c[1], y1 - c[1]);
    let a = u0.max(-r);
    let b = u1.min(r);
    if !(b > a) || v0 >= r || v1 <= -r {
        return T::zero();
    }
    // Breakpoints: where ±√(r² − v²) = the horizontal edges. Each is carried with its half chord √(r² − t²):
    // at a crossing of the edge y = v that is |v| exactly, at the ends a, b it is computed without cancellation.
    let mut pts = [(T::zero(), T::zero()); 6];
    let mut n = 0;
    pts[n] = (a, half_chord(r, a));
    n += 1;
    for v in [v0, v1] {
        if v.abs() < r {
            let w = half_chord(r, v);
            for p in [-w, w] {
                if p > a && p < b {
                    pts[n] = (p, v.abs());
                    n += 1;
                }
            }
        }
    }
    pts[n] = (b, half_chord(r, b));
    n += 1;
    // Insertion sort of at most six values.
    for i in 1..n {
        let mut j = i;
        while j > 0 && pts[j - 1].0 > pts[j].0 {
            pts.swap(j - 1, j);
            j -= 1;
        }
    }
    let mut area = T::zero();
    for k in 0..n - 1 {
        let ((p, root_p), (q, root_q)) = (pts[k], pts[k + 1]);
        if !(q > p) {
            continue;
        }
        let m = T::lit(0.5) * (p + q);
        let s = half_chord(r, m);
        // On this piece the top of the covered chord is either the rectangle edge v1 or the circle +s(t), and the
        // bottom is either v0 or −s(t); the choice does not change inside a piece.
        let top_is_edge = v1 < s;
        let bottom_is_edge = v0 > -s;
        let top_mid = if top_is_edge { v1 } else { s };
        let bottom_mid = if bottom_is_edge { v0 } else { -s };
        if !(top_mid > bottom_mid) {
            continue;
        }
        let circle = half_chord_primitive(r, q, root_q) - half_chord_primitive(r, p, root_p);
        let top = if top_is_edge { v1 * (q - p) } else { circle };
        let bottom = if bottom_is_edge {
            v0 * (q - p)
        } else {
            -circle
        };
        area += top - bottom;
    }
    area.max(T::zero())
}

/// Solid fraction of the unit cell centred on lattice point (x, y) covered by the disc (centre `c`, radius `r`,
/// lattice units), in [0, 1].
pub fn disc_cell_fraction<T: Real>(c: Point<T>, r: T, x: T, y: T) -> T {
    let h = T::lit(0.5);
    disc_rectangle_area(c, r, x - h, x + h, y - h, y + h).min(T::one())
}

#[inline(always)]
fn cross<T: Real>(u: [T; 2], v: [T; 2]) -> T {
    u[0] * v[1] - u[1] * v[0]
}

#[inline(always)]
fn dot<T: Real>(u: [T; 2], v: [T; 2]) -> T {
    u[0] * v[0] + u[1] * v[1]
}

/// Signed area of (disc of radius `r` at the origin) ∩ triangle(origin, p, q); positive when p → q turns
/// counter-clockwise about the origin.
pub fn disc_triangle_signed_area<T: Real>(r: T, p: [T; 2], q: [T; 2]) -> T {
    let half = T::lit(0.5);
    let sector = |u: [T; 2], v: [T; 2]| half * r * r * cross(u, v).portable_atan2(dot(u, v));
    let d = [q[0] - p[0], q[1] - p[1]];
    let a = dot(d, d);
    if !(a > T::zero()) {
        return T::zero();
    }
    let b = T::lit(2.0) * dot(p, d);
    let c = dot(p, p) - r * r;
    let disc = b * b - T::lit(4.0) * a * c;
    if !(disc > T::zero()) {
        // The edge's line misses (or touches) the circle: the triangle part inside the disc is a sector.
        return sector(p, q);
    }
    let root = disc.sqrt();
    let clamp = |t: T| t.max(T::zero()).min(T::one());
    let s1 = clamp((-b - root) / (T::lit(2.0) * a));
    let s2 = clamp((-b + root) / (T::lit(2.0) * a));
    let at = |s: T| [p[0] + s * d[0], p[1] + s * d[1]];
    let (ea, eb) = (at(s1), at(s2));
    sector(p, ea) + half * cross(ea, eb) + sector(eb, q)
}

/// Exact area of the ellipse (centre `c`, semi-axes `a`, `b`, orientation `theta` of the `a` axis from x)
/// intersected with the axis-aligned rectangle `rect` = [x0, x1, y0, y1] (i.e. [x0, x1] × [y0, y1]).
pub fn ellipse_rectangle_area<T: Real>(c: Point<T>, a: T, b: T, theta: T, rect: [T; 4]) -> T {
    ellipse_rectangle_area_oriented(c, a, b, theta.portable_sin_cos(), rect)
}

/// [`ellipse_rectangle_area`] with the orientation given as `(sin θ, cos θ)` (evaluate them once for many
/// cells); bitwise the same result for `theta.portable_sin_cos()`.
pub fn ellipse_rectangle_area_oriented<T: Real>(
    c: Point<T>,
    a: T,
    b: T,
    (sin, cos): (T, T),
    rect: [T; 4],
) -> T {
    let [x0, x1, y0, y1] = rect;
    if !(a > T::zero()) || !(b > T::zero()) || !(x1 > x0) || !(y1 > y0) {
        return T::zero();
    }
    // Quick rejection with the bounding circle.
    let reach = a.max(b);
    if x0 > c[0] + reach || x1 < c[0] - reach || y0 > c[1] + reach || y1 < c[1] - reach {
        return T::zero();
    }
    // Rectangle corners, counter-clockwise, mapped to the unit-disc frame (the map has positive determinant, so
    // the orientation is kept).
    let map = |x: T, y: T| {
        let (dx, dy) = (x - c[0], y - c[1]);
        [(cos * dx + sin * dy) / a, (-sin * dx + cos * dy) / b]
    };
    let corners = [map(x0, y0), map(x1, y0), map(x1, y1), map(x0, y1)];
    // A rectangle that misses the ellipse covers exactly nothing. Without this test the four sectors below
    // cancel only to roundoff, leaving areas of ~1e-17 on about a third of the cells of an ellipse's bounding
    // box, each of which would then run the partially-saturated collision for nothing.
    if !parallelogram_meets_unit_disc(&corners) {
        return T::zero();
    }
    // Likewise a rectangle whose corners all lie inside the ellipse (which is convex) is covered exactly: its
    // own area, where the sum below leaves ~1e-16 of roundoff and costs eight atan2.
    if corners.iter().all(|p| dot(*p, *p) < T::one()) {
        return (x1 - x0) * (y1 - y0);
    }
    let mut area = T::zero();
    for k in 0..4 {
        area += disc_triangle_signed_area(T::one(), corners[k], corners[(k + 1) % 4]);
    }
    (area * a * b).max(T::zero())
}

/// Whether the convex quadrilateral `p` (counter-clockwise) and the open unit disc at the origin intersect: an
/// edge passes closer than 1 to the origin, or the origin lies inside.
fn parallelogram_meets_unit_disc<T: Real>(p: &[[T; 2]; 4]) -> bool {
    let mut origin_inside = true;
    for k in 0..4 {
        let (a, b) = (p[k], p[(k + 1) % 4]);
        let d = [b[0] - a[0], b[1] - a[1]];
        let dd = dot(d, d);
        let t = if dd > T::zero() {
            (-dot(a, d) / dd).max(T::zero()).min(T::one())
        } else {
            T::zero()
        };
        let closest = [a[0] + t * d[0], a[1] + t * d[1]];
        if dot(closest, closest) < T::one() {
            return true;
        }
        // The origin is on the inner (left) side of a counter-clockwise edge a → b iff a × b ≥ 0.
        if cross(a, b) < T::zero() {
            origin_inside = false;
        }
    }
    origin_inside
}

/// Solid fraction of the unit cell centred on lattice point (x, y) covered by an ellipse, in [0, 1].
pub fn ellipse_cell_fraction<T: Real>(c: Point<T>, a: T, b: T, theta: T, x: T, y: T) -> T {
    ellipse_cell_fraction_oriented(c, a, b, theta.portable_sin_cos(), x, y)
}

/// [`ellipse_cell_fraction`] with the orientation given as `(sin θ, cos θ)`; bitwise the same result for
/// `theta.portable_sin_cos()`.
pub fn ellipse_cell_fraction_oriented<T: Real>(
    c: Point<T>,
    a: T,
    b: T,
    sin_cos: (T, T),
    x: T,
    y: T,
) -> T {
    let h = T::lit(0.5);
    ellipse_rectangle_area_oriented(c, a, b, sin_cos, [x - h, x + h, y - h, y + h]).min(T::one())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ellipse_with_equal_axes_matches_the_disc_formula() {
        for &(cx, cy, r) in &[(0.3f64, 0.1, 0.7), (2.2, -1.4, 2.5), (0.0, 0.0, 0.5)] {
            for &(x0, x1, y0, y1) in &[
                (-0.5, 0.5, -0.5, 0.5),
                (0.0, 1.0, 0.2, 1.2),
                (1.0, 3.0, -2.0, 0.0),
            ] {
                let d: f64 = disc_rectangle_area(crate::math::vector(cx, cy), r, x0, x1, y0, y1);
                let e: f64 = ellipse_rectangle_area(
                    crate::math::vector(cx, cy),
                    r,
                    r,
                    0.37,
                    [x0, x1, y0, y1],
                );
                assert!((d - e).abs() < 1e-12, "disc {d} vs ellipse {e}");
            }
        }
    }

    #[test]
    fn ellipse_fractions_sum_to_pi_a_b_at_any_orientation() {
        let (a, b) = (4.1f64, 2.05); // aspect ratio 0.5, as in the fracture test
        for k in 0..12 {
            let theta = k as f64 * 0.29;
            let c = crate::math::vector(10.31, 9.77);
            let mut sum = 0.0;
            for y in 0..21 {
                for x in 0..21 {
                    let f = ellipse_cell_fraction(c, a, b, theta, x as f64, y as f64);
                    assert!((0.0..=1.0).contains(&f));
                    sum += f;
                }
            }
            assert!(
                (sum - core::f64::consts::PI * a * b).abs() < 1e-10,
                "theta {theta}: {sum}"
            );
        }
    }

    #[test]
    fn cells_outside_an_ellipse_are_exactly_uncovered() {
        // Every cell of the bounding box whose corners and edges all stay outside the ellipse (checked by dense
        // sampling of its boundary at 1e-3 spacing, far coarser than any roundoff) has fraction exactly 0.
        let (c, a, b) = (crate::math::vector(10.31f64, 9.77), 6.1, 3.05);
        let mut zero = 0;
        for k in 0..8 {
            let theta = k as f64 * 0.41 - 1.3;
            let (s, co) = (theta.sin(), theta.cos());
            let inside = |x: f64, y: f64| {
                let (dx, dy) = (x - c[0], y - c[1]);
                let (u, v) = ((co * dx + s * dy) / a, (-s * dx + co * dy) / b);
                u * u + v * v < 1.0 + 1e-9
            };
            for y in 2..19 {
                for x in 2..19 {
                    let (xf, yf) = (x as f64, y as f64);
                    let touches = (0..=1000).any(|i| {
                        let t = i as f64 / 1000.0 - 0.5;
                        inside(xf + t, yf - 0.5)
                            || inside(xf + t, yf + 0.5)
                            || inside(xf - 0.5, yf + t)
                            || inside(xf + 0.5, yf + t)
                    });
                    if !touches {
                        let f = ellipse_cell_fraction(c, a, b, theta, xf, yf);
                        assert!(f == 0.0, "cell ({x}, {y}) at theta {theta}: {f:e}");
                        zero += 1;
                    }
                }
            }
        }
        assert!(zero > 8 * 100, "only {zero} outside cells checked");
    }

    #[test]
    fn cells_inside_an_ellipse_are_exactly_covered_and_border_cells_are_partial() {
        let (c, a, b) = (crate::math::vector(10.31f64, 9.77), 6.1, 3.05);
        let (mut full, mut partial) = (0, 0);
        for k in 0..8 {
            let theta = k as f64 * 0.41 - 1.3;
            let (s, co) = (theta.sin(), theta.cos());
            let radius2 = |x: f64, y: f64| {
                let (dx, dy) = (x - c[0], y - c[1]);
                let (u, v) = ((co * dx + s * dy) / a, (-s * dx + co * dy) / b);
                u * u + v * v
            };
            for y in 2..19 {
                for x in 2..19 {
                    let (xf, yf) = (x as f64, y as f64);
                    let corners = [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)]
                        .map(|(dx, dy)| radius2(xf + dx, yf + dy));
                    let f = ellipse_cell_fraction(c, a, b, theta, xf, yf);
                    // Corners inside by more than roundoff: the whole (convex) cell is inside.
                    if corners.iter().all(|&r| r < 1.0 - 1e-9) {
                        assert!(f == 1.0, "cell ({x}, {y}) at theta {theta}: {f}");
                        full += 1;
                    } else if corners.iter().any(|&r| r < 1.0 - 1e-9)
                        && corners.iter().any(|&r| r > 1.0 + 1e-9)
                    {
                        // A corner on each side: the boundary crosses the cell.
                        assert!(f > 0.0 && f < 1.0, "cell ({x}, {y}) at theta {theta}: {f}");
                        partial += 1;
                    }
                }
            }
        }
        assert!(
            full > 8 * 20 && partial > 8 * 20,
            "{full} full and {partial} partial cells"
        );
    }

    #[test]
    fn whole_disc_inside_a_large_rectangle_has_area_pi_r_squared() {
        let a: f64 = disc_rectangle_area(
            crate::math::vector(0.3, -0.2),
            2.0,
            -10.0,
            10.0,
            -10.0,
            10.0,
        );
        assert!((a - core::f64::consts::PI * 4.0).abs() < 1e-12);
    }

    #[test]
    fn half_and_quarter_discs() {
        let r = 1.5f64;
        let full = core::f64::consts::PI * r * r;
        let half = disc_rectangle_area(crate::math::vector(0.0, 0.0), r, 0.0, 5.0, -5.0, 5.0);
        let quarter = disc_rectangle_area(crate::math::vector(0.0, 0.0), r, 0.0, 5.0, 0.0, 5.0);
        assert!((half - full / 2.0).abs() < 1e-12);
        assert!((quarter - full / 4.0).abs() < 1e-12);
    }

    #[test]
    fn fractions_of_all_cells_sum_to_the_disc_area() {
        // A disc of radius 3.3 at an off-grid centre: the exact cell fractions must add up to πr² (roundoff).
        let (c, r) = (crate::math::vector(10.37f64, 9.81), 3.3);
        let mut sum = 0.0;
        for y in 0..21 {
            for x in 0..21 {
                let f = disc_cell_fraction(c, r, x as f64, y as f64);
                assert!((0.0..=1.0).contains(&f));
                sum += f;
            }
        }
        assert!((sum - core::f64::consts::PI * r * r).abs() < 1e-11, "{sum}");
    }

    #[test]
    fn degenerate_inputs_give_zero_not_nan() {
        assert_eq!(
            disc_rectangle_area(crate::math::vector(0.0f64, 0.0), 0.0, -1.0, 1.0, -1.0, 1.0),
            0.0
        );
        assert_eq!(
            disc_rectangle_area(crate::math::vector(0.0f64, 0.0), 1.0, 1.0, 1.0, -1.0, 1.0),
            0.0
        );
        assert_eq!(
            disc_rectangle_area(
                crate::math::vector(0.0f64, 0.0),
                f64::NAN,
                -1.0,
                1.0,
                -1.0,
                1.0
            ),
            0.0
        );
    }
}
