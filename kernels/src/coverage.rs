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
//!
//! [`ellipse_grid_fractions`] gives the fractions of **all** cells an ellipse can touch at once, by Green's
//! theorem, with one transcendental per crossing of the ellipse with a lattice line (shared by the two cells the
//! crossing separates) instead of up to eight per boundary cell; also exact up to roundoff (not bitwise the
//! per-cell formula), and it refuses the rare ellipse with a crossing within roundoff reach of a lattice vertex.
//! It computes the crossings of eight lattice lines at a time over lanes (roots, positions and angles, the
//! angles by `Real::portable_atan2_lanes`), which the compiler vectorises; each lane gets the bits it would get
//! alone, so the fractions do not depend on the instruction set.
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

/// The block of cells an ellipse can touch: node columns `x0 .. x0 + w`, rows `y0 .. y0 + h` (cell of node
/// (x, y) = [x − ½, x + ½] × [y − ½, y + ½]), not clamped to any lattice. Cell (col k, row j) of the block is
/// entry `j * w + k` of the buffers of [`ellipse_grid_fractions`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CellGrid {
    /// First node column.
    pub x0: i64,
    /// First node row.
    pub y0: i64,
    /// Columns.
    pub w: usize,
    /// Rows.
    pub h: usize,
}

impl CellGrid {
    /// Number of cells, `None` on overflow.
    pub fn cells(&self) -> Option<usize> {
        self.w.checked_mul(self.h)
    }
}

/// The cells within the bounding circle (radius max(a, b)) of an ellipse centred at `c`: the same bounds as
/// `coupling::body_cell_range`, unclamped. `None` for non-positive or non-finite sizes or centres, or blocks
/// of more than 2³¹ cells a side.
pub fn ellipse_cell_grid<T: Real>(c: Point<T>, a: T, b: T) -> Option<CellGrid> {
    if !(a > T::zero()) || !(b > T::zero()) {
        return None;
    }
    let reach = a.max(b);
    let half = T::lit(0.5);
    let lo_x = (c[0] - reach - half).ceil();
    let hi_x = (c[0] + reach + half).floor();
    let lo_y = (c[1] - reach - half).ceil();
    let hi_y = (c[1] + reach + half).floor();
    let limit = 2_147_483_648.0_f64; // 2^31: lattice indices stay far inside i64 and usize
    let ok = |v: T| v.is_finite() && v.to_f64_exact().abs() < limit;
    if !(ok(lo_x) && ok(hi_x) && ok(lo_y) && ok(hi_y)) || hi_x < lo_x || hi_y < lo_y {
        return None;
    }
    let (x0, x1) = (lo_x.to_f64_exact() as i64, hi_x.to_f64_exact() as i64);
    let (y0, y1) = (lo_y.to_f64_exact() as i64, hi_y.to_f64_exact() as i64);
    Some(CellGrid {
        x0,
        y0,
        w: (x1 - x0 + 1) as usize,
        h: (y1 - y0 + 1) as usize,
    })
}

/// ⌊v⌋ without a library call: the truncation by an integer conversion, less one where that rounded up (v < 0
/// and not an integer). Exact, so bitwise `v.floor()`, which the baseline x86-64 build compiles to a call of the
/// C library's `floor` (1.5 % of the full-size fracture step, called at every crossing); values outside the
/// range where the conversion is exact, ±0 (whose sign the conversion would lose) and NaN go to `floor` itself.
#[inline]
fn floor_exact<T: Real>(v: T) -> T {
    let x = v.to_f64_exact();
    if x != 0.0 && x.abs() < 4_503_599_627_370_496.0 {
        // |x| < 2^52: every integer part is an f64 and an i64; the conversion truncates towards zero.
        let t = x as i64 as f64;
        T::lit(if t > x { t - 1.0 } else { t })
    } else {
        v.floor()
    }
}

/// Index of the unit interval [o + i, o + i + 1) containing `t`, clamped to `0 .. n`, and the distance from `t`
/// to the nearest integer offset o + i.
#[inline]
fn interval_and_gap<T: Real>(t: T, o: T, n: usize) -> (usize, T) {
    let v = t - o;
    let f = floor_exact(v);
    let frac = v - f;
    let gap = frac.min(T::one() - frac);
    (interval(f, n), gap)
}

/// Lattice lines whose crossings [`ellipse_grid_fractions`] computes together, over lanes (the compiler
/// vectorises the lane loops; every lane gets the bits the line would get alone).
const LINE_LANES: usize = 8;

/// The crossings of up to [`LINE_LANES`] parallel lattice lines with the unit disc, in the ellipse's frame
/// ([`line_crossings`]); lane l is line `first + l`.
struct LineCrossings<T> {
    /// The line meets the open disc (the other entries of a lane that does not are unspecified).
    meets: [bool; LINE_LANES],
    /// ⌊(t − o)⌋ of the lower and upper crossing, t its coordinate along the line in lattice units and o the
    /// block's first lattice line across it, and the distance of t − o to the nearest integer (to the nearest
    /// lattice line across).
    lo: [T; LINE_LANES],
    gap_lo: [T; LINE_LANES],
    hi: [T; LINE_LANES],
    gap_hi: [T; LINE_LANES],
    /// The crossings in the ellipse's frame, and half their angle from the reference direction.
    p_lo: [[T; 2]; LINE_LANES],
    p_hi: [[T; 2]; LINE_LANES],
    f_lo: [T; LINE_LANES],
    f_hi: [T; LINE_LANES],
}

/// The crossings with the unit disc of the lines `first .. first + count` (count ≤ [`LINE_LANES`]), line i
/// being base(i) + s d (s in lattice units along the line, whose coordinate is `along.0 + s`; `along.1` is
/// the block's first line across it), angles measured from `r`. The same operations as for one line at a time
/// (the roots of |base + s d|² = 1 without cancellation, ⌊·⌋ and the gap to the nearest line, the points, and
/// their angles by [`Real::portable_atan2_lanes`], bitwise `portable_atan2`), each lane on its own values;
/// lanes past `count` repeat line `first`, and a line that misses the disc gets harmless angle arguments.
#[inline(always)]
fn line_crossings<T: Real>(
    base: impl Fn(usize) -> [T; 2],
    d: [T; 2],
    first: usize,
    count: usize,
    (along, o): (T, T),
    r: [T; 2],
) -> LineCrossings<T> {
    let zero = T::zero();
    let mut out = LineCrossings {
        meets: [false; LINE_LANES],
        lo: [zero; LINE_LANES],
        gap_lo: [zero; LINE_LANES],
        hi: [zero; LINE_LANES],
        gap_hi: [zero; LINE_LANES],
        p_lo: [[zero; 2]; LINE_LANES],
        p_hi: [[zero; 2]; LINE_LANES],
        f_lo: [zero; LINE_LANES],
        f_hi: [zero; LINE_LANES],
    };
    let (mut y, mut x) = ([zero; 2 * LINE_LANES], [zero; 2 * LINE_LANES]);
    let qa = dot(d, d);
    let (half, one) = (T::lit(0.5), T::one());
    for l in 0..LINE_LANES {
        let b = base(first + if l < count { l } else { 0 });
        // Roots s_lo ≤ s_hi of |b + s d|² = 1, the stable pair (no cancellation in either).
        let qb = dot(b, d);
        let qc = dot(b, b) - one;
        let disc = qb * qb - qa * qc;
        let q = -(qb + disc.sqrt().copysign(qb));
        let meets = disc > zero && qa > zero && q != zero;
        let (s1, s2) = (q / qa, qc / q);
        let (s_lo, s_hi) = (s1.min(s2), s1.max(s2));
        let (fl, gl) = floor_and_gap(along + s_lo - o);
        let (fh, gh) = floor_and_gap(along + s_hi - o);
        let p_lo = [b[0] + s_lo * d[0], b[1] + s_lo * d[1]];
        let p_hi = [b[0] + s_hi * d[0], b[1] + s_hi * d[1]];
        out.meets[l] = meets;
        (out.lo[l], out.gap_lo[l], out.hi[l], out.gap_hi[l]) = (fl, gl, fh, gh);
        (out.p_lo[l], out.p_hi[l]) = (p_lo, p_hi);
        // Where the line misses the disc, the angle of (2, ½) (any ordinary pair would do).
        let (a_lo, a_hi) = if meets {
            (
                [cross(r, p_lo), dot(r, p_lo)],
                [cross(r, p_hi), dot(r, p_hi)],
            )
        } else {
            ([half, one + one], [half, one + one])
        };
        (y[l], x[l]) = (a_lo[0], a_lo[1]);
        (y[LINE_LANES + l], x[LINE_LANES + l]) = (a_hi[0], a_hi[1]);
    }
    let angle = T::portable_atan2_lanes(&y, &x);
    for l in 0..LINE_LANES {
        out.f_lo[l] = half * angle[l];
        out.f_hi[l] = half * angle[LINE_LANES + l];
    }
    out
}

/// Rows of a cell block for which [`ellipse_grid_fractions`] records each row's first and last boundary cell
/// as it marks them (larger blocks scan their rows for them).
const SPAN_ROWS: usize = 64;

/// Widen row `row`'s span of boundary cells ([`SPAN_ROWS`]) to columns `lo..=hi`.
#[inline(always)]
fn widen(spans: &mut [(usize, usize); SPAN_ROWS], row: usize, lo: usize, hi: usize) {
    if let Some(s) = spans.get_mut(row) {
        *s = (s.0.min(lo), s.1.max(hi));
    }
}

/// The edge pieces ½ P × Q of up to [`LINE_LANES`] consecutive cells along a lattice line, over lanes: the
/// pieces run from `from` through the vertices `vertex(0)`, `vertex(1)`, … (the lattice lines across), the
/// piece of lane `left` (the last cell before the line's second crossing) ending at `end` instead. Returns the
/// pieces (lanes past `left` unspecified) and where the last lane's piece ends.
#[inline(always)]
fn edge_pieces<T: Real>(
    from: [T; 2],
    end: [T; 2],
    left: usize,
    vertex: impl Fn(usize) -> [T; 2],
) -> ([T; LINE_LANES], [T; 2]) {
    let half = T::lit(0.5);
    let (mut u, mut v) = ([T::zero(); LINE_LANES], [T::zero(); LINE_LANES]);
    for l in 0..LINE_LANES {
        let q = vertex(l);
        (u[l], v[l]) = if l == left {
            (end[0], end[1])
        } else {
            (q[0], q[1])
        };
    }
    let mut pieces = [T::zero(); LINE_LANES];
    for l in 0..LINE_LANES {
        let start = if l == 0 { from } else { [u[l - 1], v[l - 1]] };
        pieces[l] = half * cross(start, [u[l], v[l]]);
    }
    let last = left.min(LINE_LANES - 1);
    (pieces, [u[last], v[last]])
}

/// ⌊v⌋ and the distance from v to the nearest integer, without a library call or a branch (so that it
/// vectorises): v rounded to an integer by adding and subtracting 1/ε (ε the machine epsilon; the sum's ulp
/// is 1), less one where that rounded up. Bitwise `v.floor()` for |v| < 1/(2ε) except at v = −0 (which gives
/// +0; the gap is the same). Outside that range the gap is NaN, which every caller's `gap > margin` refuses.
#[inline(always)]
fn floor_and_gap<T: Real>(v: T) -> (T, T) {
    let big = T::one() / T::epsilon();
    let m = big.copysign(v);
    let r = (v + m) - m;
    let f = if r > v { r - T::one() } else { r };
    let frac = v - f;
    let gap = frac.min(T::one() - frac);
    let gap = if v.abs() < T::lit(0.5) * big {
        gap
    } else {
        T::nan()
    };
    (f, gap)
}

/// The index of the unit interval a floored coordinate `f` ([`floor_and_gap`]) falls in, clamped to `0 .. n`.
#[inline(always)]
fn interval<T: Real>(f: T, n: usize) -> usize {
    let i = f.to_f64_exact();
    if i > 0.0 {
        (i as usize).min(n - 1)
    } else {
        0
    }
}

/// Cell fractions of **all** cells of `grid` covered by the ellipse (centre `c`, semi-axes `a`, `b`, orientation
/// given as `(sin θ, cos θ)`), each transcendental evaluated once per crossing of the ellipse with a lattice
/// line instead of up to eight times per cell ([`ellipse_cell_fraction_oriented`]). Writes the fraction of
/// cell (col k, row j) to `fractions[j * grid.w + k]` (in [0, 1]); `boundary` is scratch of the same length.
///
/// **Method (exact up to roundoff).** In the frame u = R(−θ)(p − c) / (a, b) the ellipse is the unit disc and
/// areas are divided by ab. By Green's theorem the area of a region is ½ ∮ u × du along its counter-clockwise
/// boundary; the boundary of cell ∩ disc consists of straight pieces of the cell's edges inside the disc, each
/// contributing ½ P × Q (from P to Q), and arcs of the unit circle inside the cell, each contributing
/// ½ (φ_out − φ_in). Every lattice-edge piece is computed once and added to the cell on one side and
/// subtracted from the cell on the other (its two traversals are opposite; the negation is exact). Every
/// crossing of the circle with a lattice line is where the counter-clockwise boundary leaves one cell for the
/// next (which one follows from convexity: on a vertical line the lower crossing moves right and the upper one
/// left, on a horizontal line the left crossing moves down and the right one up), so its angle φ is added
/// (½ φ) to the cell it leaves and subtracted from the cell it enters; the one arc that passes the branch cut
/// of the angle gets the missing ½ · 2π. Angles are measured from a reference direction chosen so that the
/// cut lies clear of every lattice line. Cells that no crossing touches are entirely inside (fraction exactly 1)
/// or outside (exactly 0), decided by their node.
///
/// Returns `false` (buffers unspecified) when this cannot be decided safely — a crossing lies within a small
/// margin (≈ 1.5e-6 (1 + max(a, b)) in f64) of a lattice vertex, where roundoff could order the crossings
/// wrongly, or every candidate cut does — or when the sizes are invalid or the buffers shorter than the grid:
/// the caller then uses the per-cell formula [`ellipse_cell_fraction_oriented`].
#[inline(always)]
pub fn ellipse_grid_fractions<T: Real>(
    c: Point<T>,
    a: T,
    b: T,
    (sin, cos): (T, T),
    grid: CellGrid,
    fractions: &mut [T],
    boundary: &mut [bool],
) -> bool {
    let Some(n) = grid.cells() else {
        return false;
    };
    if !(a > T::zero()) || !(b > T::zero()) || !(a * b).is_finite() || grid.w == 0 || grid.h == 0 {
        return false;
    }
    let (Some(fr), Some(bd)) = (fractions.get_mut(..n), boundary.get_mut(..n)) else {
        return false;
    };
    fr.fill(T::zero());
    bd.fill(false);
    // First and last boundary cell of each row (empty: first > last), for blocks of up to SPAN_ROWS rows.
    let mut spans = [(usize::MAX, 0usize); SPAN_ROWS];
    let (w, h) = (grid.w, grid.h);
    let half = T::lit(0.5);
    // Lattice lines: x = xl + i (i = 0..=w), y = yl + j (j = 0..=h).
    let xl = T::lit(grid.x0 as f64) - half;
    let yl = T::lit(grid.y0 as f64) - half;
    let (ia, ib) = (T::one() / a, T::one() / b);
    let map = |x: T, y: T| {
        let (dx, dy) = (x - c[0], y - c[1]);
        [(cos * dx + sin * dy) * ia, (cos * dy - sin * dx) * ib]
    };
    // Crossings closer than this to a perpendicular lattice line (lattice units) are refused: near a vertex the
    // two crossings' order could be wrong by roundoff; near tangency a root carries an error of ≈ √ε · max(a, b).
    let margin = T::epsilon().sqrt() * T::lit(100.0) * (T::one() + a.max(b));
    // The branch cut: the first candidate point of the circle whose image lies clear of every lattice line.
    let s2 = T::FRAC_1_SQRT_2();
    let candidates = [
        [-T::one(), T::zero()],
        [T::zero(), -T::one()],
        [T::one(), T::zero()],
        [T::zero(), T::one()],
        [-s2, -s2],
        [s2, -s2],
        [s2, s2],
        [-s2, s2],
    ];
    let mut cut = None;
    for u in candidates {
        let (pa, pb) = (a * u[0], b * u[1]);
        let (px, py) = (c[0] + cos * pa - sin * pb, c[1] + sin * pa + cos * pb);
        let (col, gx) = interval_and_gap(px, xl, w);
        let (row, gy) = interval_and_gap(py, yl, h);
        if gx > margin && gy > margin {
            cut = Some((u, row * w + col));
            break;
        }
    }
    let Some((u_cut, cut_cell)) = cut else {
        return false;
    };
    // Angles of points P are measured from the reference direction r = −u_cut, in (−π, π]: discontinuous only
    // at u_cut.
    let r = [-u_cut[0], -u_cut[1]];
    // Vertical lines (the outermost two lie strictly outside the bounding circle), LINE_LANES at a time: their
    // crossings computed over lanes, then added to the cells line by line, in order.
    let dv = [sin * ia, cos * ib];
    let mut i0 = 1;
    while i0 < w {
        let count = (w - i0).min(LINE_LANES);
        let x_of = |i: usize| xl + T::lit(i as f64);
        let lines = line_crossings(
            |i| {
                let dx = x_of(i) - c[0];
                [cos * dx * ia, -(sin * dx) * ib]
            },
            dv,
            i0,
            count,
            (c[1], yl),
            r,
        );
        for l in 0..count {
            if !lines.meets[l] {
                continue;
            }
            if !(lines.gap_lo[l] > margin && lines.gap_hi[l] > margin) {
                return false;
            }
            let (i, x) = (i0 + l, x_of(i0 + l));
            let (row_lo, row_hi) = (interval(lines.lo[l], h), interval(lines.hi[l], h));
            let (p_lo, p_hi) = (lines.p_lo[l], lines.p_hi[l]);
            let (f_lo, f_hi) = (lines.f_lo[l], lines.f_hi[l]);
            // Lower crossing: from the left column to the right one; upper crossing: back.
            let (left_lo, right_lo) = (row_lo * w + i - 1, row_lo * w + i);
            fr[left_lo] += f_lo;
            fr[right_lo] -= f_lo;
            let (left_hi, right_hi) = (row_hi * w + i - 1, row_hi * w + i);
            fr[right_hi] += f_hi;
            fr[left_hi] -= f_hi;
            for k in [left_lo, right_lo, left_hi, right_hi] {
                bd[k] = true;
            }
            widen(&mut spans, row_lo, i - 1, i);
            widen(&mut spans, row_hi, i - 1, i);
            // Upward pieces: the right edge of the left cell (+), the left edge of the right cell (−); the piece
            // of row j ends at the vertex (x, row j's top line), or at the upper crossing in row `row_hi`.
            let mut from = p_lo;
            let mut j = row_lo;
            while j <= row_hi {
                let pieces = edge_pieces(from, p_hi, row_hi - j, |l| {
                    map(x, yl + T::lit((j + l + 1) as f64))
                });
                let m = (row_hi + 1 - j).min(LINE_LANES);
                for (l, &piece) in pieces.0.iter().enumerate().take(m) {
                    fr[(j + l) * w + i - 1] += piece;
                    fr[(j + l) * w + i] -= piece;
                }
                from = pieces.1;
                j += m;
            }
        }
        i0 += LINE_LANES;
    }
    // Horizontal lines, the same way.
    let dh = [cos * ia, -(sin * ib)];
    let mut j0 = 1;
    while j0 < h {
        let count = (h - j0).min(LINE_LANES);
        let y_of = |j: usize| yl + T::lit(j as f64);
        let lines = line_crossings(
            |j| {
                let dy = y_of(j) - c[1];
                [sin * dy * ia, cos * dy * ib]
            },
            dh,
            j0,
            count,
            (c[0], xl),
            r,
        );
        for l in 0..count {
            if !lines.meets[l] {
                continue;
            }
            if !(lines.gap_lo[l] > margin && lines.gap_hi[l] > margin) {
                return false;
            }
            let (j, y) = (j0 + l, y_of(j0 + l));
            let (col_lo, col_hi) = (interval(lines.lo[l], w), interval(lines.hi[l], w));
            let (p_lo, p_hi) = (lines.p_lo[l], lines.p_hi[l]);
            let (f_lo, f_hi) = (lines.f_lo[l], lines.f_hi[l]);
            // Left crossing: from the row above to the row below; right crossing: back.
            let (above_lo, below_lo) = (j * w + col_lo, (j - 1) * w + col_lo);
            fr[above_lo] += f_lo;
            fr[below_lo] -= f_lo;
            let (above_hi, below_hi) = (j * w + col_hi, (j - 1) * w + col_hi);
            fr[below_hi] += f_hi;
            fr[above_hi] -= f_hi;
            for k in [above_lo, below_lo, above_hi, below_hi] {
                bd[k] = true;
            }
            widen(&mut spans, j, col_lo, col_hi);
            widen(&mut spans, j - 1, col_lo, col_hi);
            // Rightward pieces: the bottom edge of the cell above (+), the top edge of the cell below (−).
            let mut from = p_lo;
            let mut k = col_lo;
            while k <= col_hi {
                let pieces = edge_pieces(from, p_hi, col_hi - k, |l| {
                    map(xl + T::lit((k + l + 1) as f64), y)
                });
                let m = (col_hi + 1 - k).min(LINE_LANES);
                for (l, &piece) in pieces.0.iter().enumerate().take(m) {
                    fr[j * w + k + l] += piece;
                    fr[(j - 1) * w + k + l] -= piece;
                }
                from = pieces.1;
                k += m;
            }
        }
        j0 += LINE_LANES;
    }
    fr[cut_cell] += T::PI();
    bd[cut_cell] = true;
    widen(&mut spans, cut_cell / w, cut_cell % w, cut_cell % w);
    let ab = a * b;
    for j in 0..h {
        // Only the cells from the row's first boundary cell to its last can be covered: a cell no crossing
        // touches lies entirely on one side of the ellipse, and so does a run of such cells (their shared edges
        // are not crossed either); the run at either end of a row reaches the block's outermost lattice lines,
        // which lie outside the bounding circle, so it is outside (fraction 0, as filled above). A row without
        // boundary cells is outside altogether.
        // (Where the block has at most SPAN_ROWS rows the span was recorded as the cells were marked.)
        let row = &bd[j * w..(j + 1) * w];
        let span = if h <= SPAN_ROWS {
            let (first, last) = spans[j];
            (first <= last).then_some((first, last))
        } else {
            row.iter()
                .position(|&m| m)
                .zip(row.iter().rposition(|&m| m))
        };
        let Some((first, last)) = span else {
            continue;
        };
        // A boundary cell's sum times ab, clamped; any other cell 1 or 0 as its node is inside or not (LINE_LANES
        // cells at a time where the row has them, so that the loop vectorises).
        let cell = |k: usize, f: T, boundary: bool| {
            if boundary {
                (f * ab).max(T::zero()).min(T::one())
            } else {
                let p = map(xl + T::lit(k as f64) + half, yl + T::lit(j as f64) + half);
                if dot(p, p) < T::one() {
                    T::one()
                } else {
                    T::zero()
                }
            }
        };
        let (fr_row, bd_row) = (&mut fr[j * w..(j + 1) * w], &bd[j * w..(j + 1) * w]);
        let mut k = first;
        while k + LINE_LANES <= last + 1 {
            let (Ok(f), Ok(m)) = (
                <&mut [T; LINE_LANES]>::try_from(&mut fr_row[k..k + LINE_LANES]),
                <&[bool; LINE_LANES]>::try_from(&bd_row[k..k + LINE_LANES]),
            ) else {
                break;
            };
            for l in 0..LINE_LANES {
                f[l] = cell(k + l, f[l], m[l]);
            }
            k += LINE_LANES;
        }
        for k in k..=last {
            fr_row[k] = cell(k, fr_row[k], bd_row[k]);
        }
    }
    true
}

#[cfg(test)]
mod tests {
    /// The floor without a library call is bitwise the library's, in both precisions: integers, values just
    /// off them, halves, ±0, subnormals, the ends of the exact range, huge values, infinities and NaN.
    #[test]
    fn floor_without_a_call_is_bitwise_floor() {
        let check = |v: f64| {
            let (a, b) = (floor_exact(v), num_traits::Float::floor(v));
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "f64 {v:e}"
            );
            let v = v as f32;
            let (a, b) = (floor_exact(v), num_traits::Float::floor(v));
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "f32 {v:e}"
            );
        };
        for v in [
            0.0,
            -0.0,
            f64::MIN_POSITIVE / 4.0,
            -f64::MIN_POSITIVE / 4.0,
            4_503_599_627_370_495.5,
            -4_503_599_627_370_495.5,
            4_503_599_627_370_496.0,
            -4_503_599_627_370_497.0,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ] {
            check(v);
        }
        for k in -2000..=2000 {
            let x = k as f64 * 0.25;
            for v in [x, x.next_up(), x.next_down(), x * 1e7, x * 1e-9] {
                check(v);
            }
        }
    }

    /// The branch-free floor of the lane loops is bitwise `floor` (up to the sign of a zero) over its range, its
    /// gap is the distance to the nearest integer as [`interval_and_gap`] computes it, and outside the range the
    /// gap is NaN (refused by every caller's `gap > margin`).
    #[test]
    fn branch_free_floor_is_floor_and_its_gap_the_distance_to_an_integer() {
        fn check<T: Real>(v: T) {
            let (f, gap) = floor_and_gap(v);
            let want = v.floor();
            assert!(f == want, "{v:?}: {f:?} against {want:?}");
            let frac = v - want;
            assert!(
                gap.to_f64_exact().to_bits() == frac.min(T::one() - frac).to_f64_exact().to_bits()
                    || (gap == T::zero() && frac == T::zero()),
                "{v:?}"
            );
            let (i, g) = interval_and_gap(v, T::zero(), usize::MAX);
            assert_eq!(g, gap, "{v:?}");
            assert_eq!(interval(f, usize::MAX), i, "{v:?}");
        }
        for k in -4000..=4000 {
            let x = k as f64 * 0.125;
            for v in [x, x.next_up(), x.next_down(), x * 1e5 + 0.5, x * 1e-9] {
                check(v);
                if v.abs() < 4.0e6 {
                    // f32's range ends at 2^22.
                    check(v as f32);
                }
            }
        }
        for v in [0.0, -0.0, 2.0e15 + 0.5, -2.0e15 - 0.5, 2.25e15 - 1.0] {
            check(v);
        }
        for v in [4.0e6f32 + 0.5, -4.0e6 - 0.5] {
            check(v);
        }
        for v in [2.26e15, -2.26e15, -1e300, f64::INFINITY, f64::NAN] {
            assert!(floor_and_gap(v).1.is_nan(), "{v:e}");
        }
        for v in [4.2e6f32, -1e30] {
            assert!(floor_and_gap(v).1.is_nan(), "{v:e}");
        }
    }

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

    /// The grid kernel against the per-cell formula, cell by cell (both exact: roundoff apart), over many
    /// ellipses; and its sum against πab.
    #[test]
    fn grid_fractions_match_the_per_cell_formula() {
        let mut checked = 0;
        let mut fallbacks = 0;
        for k in 0..400 {
            let kf = k as f64;
            let c = crate::math::vector(10.0 + 0.731 * kf % 1.0, -3.0 + 0.377 * kf % 1.0);
            let a = 0.07 + (kf * 0.618) % 1.0 * 6.0;
            let b = a * (0.1 + (kf * 0.414) % 0.9);
            let theta = kf * 0.1234 - 2.0;
            let sc = theta.portable_sin_cos();
            let g = ellipse_cell_grid(c, a, b).expect("a valid ellipse");
            let n = g.cells().unwrap();
            let (mut fr, mut bd) = ([0.0f64; 1024], [false; 1024]);
            let (fr, bd) = (&mut fr[..n], &mut bd[..n]);
            if !ellipse_grid_fractions(c, a, b, sc, g, fr, bd) {
                fallbacks += 1;
                continue;
            }
            let mut sum = 0.0;
            for j in 0..g.h {
                for i in 0..g.w {
                    let (x, y) = ((g.x0 + i as i64) as f64, (g.y0 + j as i64) as f64);
                    let want = ellipse_cell_fraction_oriented(c, a, b, sc, x, y);
                    let got = fr[j * g.w + i];
                    assert!((0.0..=1.0).contains(&got));
                    // Both exact; roundoff of sums of terms up to π·ab (see coverage_properties' cell_roundoff).
                    assert!(
                        (got - want).abs() < 64.0 * f64::EPSILON * (1.0 + a * b + 64.0),
                        "k {k} cell ({x}, {y}): {got} vs {want}"
                    );
                    if want == 0.0 || want == 1.0 {
                        assert_eq!(got, want, "k {k} cell ({x}, {y})");
                    }
                    sum += got;
                    checked += 1;
                }
            }
            let exact = core::f64::consts::PI * a * b;
            assert!(
                (sum - exact).abs() < 1e-12 * (1.0 + exact),
                "k {k}: {sum} vs {exact}"
            );
        }
        assert!(
            fallbacks < 4 && checked > 10_000,
            "{fallbacks} fallbacks, {checked} cells"
        );
    }

    #[test]
    fn grid_fractions_refuse_a_crossing_at_a_lattice_vertex() {
        // The circle of radius 5 centred on the vertex (0.5, 0.5) passes through the vertex (3.5, 4.5).
        let c = crate::math::vector(0.5f64, 0.5);
        let g = ellipse_cell_grid(c, 5.0, 5.0).unwrap();
        let n = g.cells().unwrap();
        let (mut fr, mut bd) = ([0.0f64; 1024], [false; 1024]);
        let (fr, bd) = (&mut fr[..n], &mut bd[..n]);
        assert!(!ellipse_grid_fractions(c, 5.0, 5.0, (0.0, 1.0), g, fr, bd));
        // Buffers shorter than the grid are refused, not indexed out of bounds.
        let c = crate::math::vector(0.3f64, 0.2);
        let g = ellipse_cell_grid(c, 2.0, 1.0).unwrap();
        let (mut fr, mut bd) = ([0.0f64; 3], [false; 3]);
        assert!(!ellipse_grid_fractions(
            c,
            2.0,
            1.0,
            (0.0, 1.0),
            g,
            &mut fr,
            &mut bd
        ));
    }

    #[test]
    fn grid_fractions_move_the_cut_off_a_lattice_line_and_cover_a_tiny_ellipse() {
        // Axis-aligned ellipse whose leftmost point (the first cut candidate) lies on the line x = −0.5 and
        // whose lowest point (the second) on y = −0.5 (both tangent, away from any vertex): the cut moves to the
        // third candidate, and every cell still matches the per-cell formula.
        let (c, a, b) = (crate::math::vector(1.7f64, 0.7), 2.2, 1.2);
        let g = ellipse_cell_grid(c, a, b).unwrap();
        let n = g.cells().unwrap();
        let (mut fr, mut bd) = ([0.0f64; 1024], [false; 1024]);
        let (fr, bd) = (&mut fr[..n], &mut bd[..n]);
        assert!(ellipse_grid_fractions(c, a, b, (0.0, 1.0), g, fr, bd));
        for j in 0..g.h {
            for i in 0..g.w {
                let (x, y) = ((g.x0 + i as i64) as f64, (g.y0 + j as i64) as f64);
                let want = ellipse_cell_fraction(c, a, b, 0.0, x, y);
                // Roundoff only (see grid_fractions_match_the_per_cell_formula).
                assert!((fr[j * g.w + i] - want).abs() < 1e-13, "({x}, {y})");
            }
        }
        // A tangent point exactly at the vertex (1.5, −0.5) is refused.
        let (c, a, b) = (crate::math::vector(1.5f64, 0.7), 2.0, 1.2);
        let g = ellipse_cell_grid(c, a, b).unwrap();
        let n = g.cells().unwrap();
        let (mut fr, mut bd) = ([0.0f64; 1024], [false; 1024]);
        let (fr, bd) = (&mut fr[..n], &mut bd[..n]);
        assert!(!ellipse_grid_fractions(c, a, b, (0.0, 1.0), g, fr, bd));
        // An ellipse inside one cell: no crossing, only the cut's 2π.
        let (c, a, b) = (crate::math::vector(3.1f64, 4.2), 0.2, 0.1);
        let g = ellipse_cell_grid(c, a, b).unwrap();
        let n = g.cells().unwrap();
        let (mut fr, mut bd) = ([0.0f64; 1024], [false; 1024]);
        let (fr, bd) = (&mut fr[..n], &mut bd[..n]);
        assert!(ellipse_grid_fractions(
            c,
            a,
            b,
            0.4f64.portable_sin_cos(),
            g,
            fr,
            bd
        ));
        let sum: f64 = fr.iter().sum();
        assert!((sum - core::f64::consts::PI * a * b).abs() < 1e-15);
        assert_eq!(fr.iter().filter(|&&f| f > 0.0).count(), 1);
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
