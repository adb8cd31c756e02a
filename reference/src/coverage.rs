//! Reference (oracle) areas for the solid-fraction kernels (`lbdem_kernels::coverage`): the area of an ellipse
//! (a disc when a = b) intersected with a convex polygon (a lattice cell, a rectangle, a triangle), returned as a
//! guaranteed enclosure [lo, hi] of the exact value.
//!
//! The method shares nothing with the kernels' closed forms (breakpoints and the arcsine primitive for discs; an
//! affine map to the unit disc and a triangle/sector decomposition for ellipses). It integrates, over x, the
//! length g(x) of the vertical section of the intersection:
//!
//! * the section of the ellipse at abscissa x is the interval of y where the point is inside, the roots of a
//!   quadratic in y; the section of a convex polygon is the intersection of its edges' half-planes, each a
//!   linear bound on y;
//! * g(x) = max(0, o(x)) with o(x) = min(upper bounds) − max(lower bounds). On the common x-extent of the two
//!   shapes o is concave (a minimum of concave functions minus a maximum of convex ones), so the support
//!   {o > 0} is one interval [s0, s1]: a golden-section search finds the maximum of o, bisection its zeros;
//! * the vertical section length of a convex set is a concave function of x on its support (Brunn–Minkowski in
//!   one dimension), so on [s0, s1] the composite trapezoid rule under-estimates and the composite midpoint rule
//!   over-estimates the integral: the exact area lies between the two. The enclosure is that interval widened by
//!   a roundoff allowance (see [`ellipse_polygon_area`]).
//!
//! The width of the enclosure is the quadrature error, O(h²) where g is smooth and O(h^{3/2}) at a vertical
//! tangent of the ellipse (g ~ √(x − s0) there): about 1e-6 of the section height for a unit cell and
//! `samples` = 2000.
pub use crate::dem::Ellipse;

/// An interval known to contain an exact value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Enclosure {
    /// Lower bound.
    pub lo: f64,
    /// Upper bound.
    pub hi: f64,
}

impl Enclosure {
    /// Whether `v` lies in [lo, hi].
    pub fn contains(&self, v: f64) -> bool {
        self.lo <= v && v <= self.hi
    }

    /// hi − lo.
    pub fn width(&self) -> f64 {
        self.hi - self.lo
    }

    /// The midpoint, a point estimate.
    pub fn mid(&self) -> f64 {
        0.5 * (self.lo + self.hi)
    }

    /// The enclosure of −value.
    pub fn negated(self) -> Self {
        Enclosure {
            lo: -self.hi,
            hi: -self.lo,
        }
    }
}

/// The interval of y where (x, y) lies in the ellipse, or `None` when the vertical line at x misses it.
pub fn ellipse_section(e: &Ellipse, x: f64) -> Option<(f64, f64)> {
    section_with(e, e.angle.sin_cos(), x)
}

/// [`ellipse_section`] with (sin θ, cos θ) given.
fn section_with(e: &Ellipse, (s, c): (f64, f64), x: f64) -> Option<(f64, f64)> {
    let dx = x - e.centre[0];
    // Body coordinates u = c dx + s dy, v = −s dx + c dy; (u/a)² + (v/b)² ≤ 1 is A dy² + B dy + C ≤ 0.
    let (a2, b2) = (e.a * e.a, e.b * e.b);
    let qa = s * s / a2 + c * c / b2;
    let qb = 2.0 * s * c * dx * (1.0 / a2 - 1.0 / b2);
    let qc = c * c * dx * dx / a2 + s * s * dx * dx / b2 - 1.0;
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        return None;
    }
    let root = disc.sqrt();
    let lo = (-qb - root) / (2.0 * qa);
    let hi = (-qb + root) / (2.0 * qa);
    Some((e.centre[1] + lo, e.centre[1] + hi))
}

/// Half-width of the ellipse's extent along x: √(a² cos² θ + b² sin² θ).
pub fn ellipse_half_width(e: &Ellipse) -> f64 {
    let (s, c) = e.angle.sin_cos();
    (e.a * e.a * c * c + e.b * e.b * s * s).sqrt()
}

/// Twice the signed area of a polygon (positive when counter-clockwise).
fn twice_signed_area(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    (0..n)
        .map(|k| {
            let (a, b) = (p[k], p[(k + 1) % n]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum()
}

/// The bounds on y of a convex polygon's section at x: (max of the lower bounds, min of the upper bounds).
/// Vertical edges bound x only and are skipped (inside the polygon's x-extent they hold).
fn polygon_bounds(ccw: &[[f64; 2]], x: f64) -> (f64, f64) {
    let n = ccw.len();
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for k in 0..n {
        let (p, q) = (ccw[k], ccw[(k + 1) % n]);
        let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
        // The inside is on the left: dx (y − p_y) − dy (x − p_x) ≥ 0.
        if dx > 0.0 {
            lo = lo.max(p[1] + dy * (x - p[0]) / dx);
        } else if dx < 0.0 {
            hi = hi.min(p[1] + dy * (x - p[0]) / dx);
        }
    }
    (lo, hi)
}

/// Area of the ellipse `e` ∩ the convex polygon `polygon` (vertices in order, either orientation), as an
/// enclosure: exact ∈ [lo, hi]. `samples` is the number of quadrature intervals (≥ 1).
///
/// The enclosure is [trapezoid, midpoint] (see the module documentation) widened by a roundoff allowance:
/// each section is a few dozen operations on coordinates of magnitude ≤ `scale` (the largest coordinate),
/// so its error is below 1e-13 (1 + scale), and the integral's below that times s1 − s0.
pub fn ellipse_polygon_area(e: &Ellipse, polygon: &[[f64; 2]], samples: usize) -> Enclosure {
    let zero = Enclosure { lo: 0.0, hi: 0.0 };
    let signed = twice_signed_area(polygon);
    if polygon.len() < 3 || signed == 0.0 || !(e.a > 0.0 && e.b > 0.0) {
        return zero;
    }
    let mut ccw = polygon.to_vec();
    if signed < 0.0 {
        ccw.reverse();
    }
    let w = ellipse_half_width(e);
    let px_lo = ccw.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
    let px_hi = ccw.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max);
    let (x0, x1) = (px_lo.max(e.centre[0] - w), px_hi.min(e.centre[0] + w));
    // (Written so that NaN extents also give an empty intersection.)
    if x1.partial_cmp(&x0) != Some(std::cmp::Ordering::Greater) {
        return zero;
    }
    // o(x): the (possibly negative) length of the common section; concave on [x0, x1].
    let sin_cos = e.angle.sin_cos();
    let o = |x: f64| -> f64 {
        let (plo, phi) = polygon_bounds(&ccw, x);
        match section_with(e, sin_cos, x) {
            Some((elo, ehi)) => phi.min(ehi) - plo.max(elo),
            // Only at the very ends of the ellipse's extent, by roundoff: a point section.
            None => {
                let y = e.centre[1];
                phi.min(y) - plo.max(y)
            }
        }
    };
    // Golden-section search for the maximum of the concave o.
    let ratio = 0.5 * (5f64.sqrt() - 1.0);
    let (mut a, mut b) = (x0, x1);
    for _ in 0..200 {
        if b - a <= 1e-15 * (1.0 + a.abs().max(b.abs())) {
            break;
        }
        let m1 = b - ratio * (b - a);
        let m2 = a + ratio * (b - a);
        if o(m1) < o(m2) {
            a = m1;
        } else {
            b = m2;
        }
    }
    let peak = 0.5 * (a + b);
    if o(peak).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return zero;
    }
    // Zeros of o on each side of the peak (the support's ends), by bisection on the sign.
    let bisect = |mut inside: f64, mut outside: f64| -> f64 {
        for _ in 0..200 {
            let mid = 0.5 * (inside + outside);
            if mid == inside || mid == outside {
                break;
            }
            if o(mid) > 0.0 {
                inside = mid;
            } else {
                outside = mid;
            }
        }
        inside
    };
    let s0 = if o(x0) > 0.0 { x0 } else { bisect(peak, x0) };
    let s1 = if o(x1) > 0.0 { x1 } else { bisect(peak, x1) };
    let g = |x: f64| o(x).max(0.0);
    let n = samples.max(1);
    let h = (s1 - s0) / n as f64;
    let mut trapezoid = 0.5 * (g(s0) + g(s1));
    let mut midpoint = 0.0;
    for k in 0..n {
        if k > 0 {
            trapezoid += g(s0 + k as f64 * h);
        }
        midpoint += g(s0 + (k as f64 + 0.5) * h);
    }
    let (trapezoid, midpoint) = (trapezoid * h, midpoint * h);
    let scale = ccw
        .iter()
        .flat_map(|p| p.iter())
        .chain(e.centre.iter())
        .fold(e.a.max(e.b), |m, v| m.max(v.abs()));
    // The bisection leaves each end within one ulp of the true zero of the computed o, and the section there
    // is below the roundoff allowance itself: both are covered by the allowance.
    let roundoff = 1e-13 * (1.0 + scale) * (s1 - s0 + 1e-300);
    Enclosure {
        lo: (trapezoid.min(midpoint) - roundoff).max(0.0),
        hi: trapezoid.max(midpoint) + roundoff,
    }
}

/// Area of the ellipse ∩ the axis-aligned rectangle [x0, x1] × [y0, y1] (`rect` = [x0, x1, y0, y1]).
pub fn ellipse_rectangle_area(e: &Ellipse, rect: [f64; 4], samples: usize) -> Enclosure {
    let [x0, x1, y0, y1] = rect;
    if !(x1 > x0 && y1 > y0) {
        return Enclosure { lo: 0.0, hi: 0.0 };
    }
    ellipse_polygon_area(e, &[[x0, y0], [x1, y0], [x1, y1], [x0, y1]], samples)
}

/// The unit lattice cell of node (x, y): [x − ½, x + ½] × [y − ½, y + ½] as [x0, x1, y0, y1].
pub fn cell(x: f64, y: f64) -> [f64; 4] {
    [x - 0.5, x + 0.5, y - 0.5, y + 0.5]
}

/// Signed area of (disc of radius r at the origin) ∩ triangle(origin, p, q): positive when p → q turns
/// counter-clockwise about the origin, negative when clockwise, zero for a degenerate triangle.
pub fn disc_triangle_signed_area(r: f64, p: [f64; 2], q: [f64; 2], samples: usize) -> Enclosure {
    let disc = Ellipse {
        centre: [0.0, 0.0],
        a: r,
        b: r,
        angle: 0.0,
    };
    let area = ellipse_polygon_area(&disc, &[[0.0, 0.0], p, q], samples);
    let turn = p[0] * q[1] - p[1] * q[0];
    if turn < 0.0 {
        area.negated()
    } else {
        area
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn disc(c: [f64; 2], r: f64) -> Ellipse {
        Ellipse {
            centre: c,
            a: r,
            b: r,
            angle: 0.0,
        }
    }

    #[test]
    fn whole_ellipses_half_and_quarter_discs() {
        for (k, &(a, b)) in [(1.0, 1.0), (3.0, 1.2), (0.2, 0.05), (7.5, 7.5)]
            .iter()
            .enumerate()
        {
            let e = Ellipse {
                centre: [0.3, -1.7],
                a,
                b,
                angle: 0.4 * k as f64,
            };
            let whole = ellipse_rectangle_area(&e, [-50.0, 50.0, -50.0, 50.0], 4000);
            assert!(whole.contains(PI * a * b), "{whole:?} vs {}", PI * a * b);
            // The quadrature error at the four vertical tangents, O(h^{3/2}) (module documentation).
            assert!(whole.width() < 1e-4 * a * b, "{whole:?}");
        }
        let r = 1.5;
        let half = ellipse_rectangle_area(&disc([0.0, 0.0], r), [0.0, 5.0, -5.0, 5.0], 4000);
        let quarter = ellipse_rectangle_area(&disc([0.0, 0.0], r), [-5.0, 0.0, 0.0, 5.0], 4000);
        assert!(half.contains(PI * r * r / 2.0), "{half:?}");
        assert!(quarter.contains(PI * r * r / 4.0), "{quarter:?}");
    }

    #[test]
    fn a_cell_inside_is_covered_and_a_cell_outside_is_not() {
        let e = Ellipse {
            centre: [2.0, 3.0],
            a: 4.0,
            b: 2.5,
            angle: 0.3,
        };
        let inside = ellipse_rectangle_area(&e, cell(2.0, 3.0), 2000);
        // A constant section: the rules are exact, the width is the roundoff allowance.
        assert!(inside.contains(1.0) && inside.width() < 1e-11, "{inside:?}");
        let outside = ellipse_rectangle_area(&e, cell(12.0, 3.0), 2000);
        assert_eq!(outside, Enclosure { lo: 0.0, hi: 0.0 });
    }

    #[test]
    fn triangle_inside_a_large_disc_is_the_triangle_and_orientation_gives_the_sign() {
        let (p, q) = ([1.0, 0.2], [0.3, 0.9]);
        let tri = 0.5 * (p[0] * q[1] - p[1] * q[0]);
        let a = disc_triangle_signed_area(10.0, p, q, 2000);
        // Linear sections: the rules are exact, the width is the roundoff allowance.
        assert!(a.contains(tri) && a.width() < 1e-11, "{a:?} vs {tri}");
        let b = disc_triangle_signed_area(10.0, q, p, 2000);
        assert!(b.contains(-tri), "{b:?}");
        // A sector: the triangle reaches far beyond a unit disc, spanning 90°.
        let s = disc_triangle_signed_area(1.0, [100.0, 0.0], [0.0, 100.0], 4000);
        assert!(s.contains(PI / 4.0) && s.width() < 1e-5, "{s:?}");
    }
}
