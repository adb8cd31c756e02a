//! Properties of the fluid–solid coupling kernels (`lbdem_kernels::coupling`) for every input: the rigid-body
//! velocity against V + ω × r written out and against rigidity; the fluid-radius scaling and the bounding
//! reach against the shape's own boundary; the per-body cell fraction against the coverage kernels (which
//! `coverage_properties.rs` checks against the quadrature oracle) and, for the prepared form, bitwise; the
//! cell range against an enumeration of the cells that meet the body's bounding square; and the force and
//! torque reduction against a direct sum with the minimum image written as d − L·round(d/L), with forces
//! along x only, y only and both, under whole-cell translation and under a quarter turn.
//!
//! **Tolerances.** Sums of n products carry at most n ulp of Σ|term| (recursive summation), so the reduction is
//! compared within 4 n ε Σ|term|; where the claim is exact (the dispatch of `body_cell_fraction`, the prepared
//! body, the reach of a scaled body, a quarter turn, which permutes and negates exactly) it is compared
//! bitwise.
use lbdem_kernels::coupling::{
    body_cell_fraction, body_cell_range, reduce_exchange, rigid_velocity, surface_normal,
    BodyShape, CoupledBody, PreparedBody,
};
use lbdem_kernels::coverage::{disc_cell_fraction, ellipse_cell_fraction};
use lbdem_kernels::math::{Point, Vector};
use lbdem_reference::coverage as oracle;
use lbdem_verification::proptest_cases;
use proptest::prelude::*;
use std::f64::consts::PI;

fn config(default: u32) -> ProptestConfig {
    ProptestConfig::with_cases(proptest_cases(default))
}

fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo.ln()..=hi.ln()).prop_map(f64::exp)
}

fn shape() -> impl Strategy<Value = BodyShape<f64>> {
    prop_oneof![
        log_uniform(0.05, 20.0).prop_map(|radius| BodyShape::Disc { radius }),
        (log_uniform(0.05, 20.0), 0.1f64..=1.0, -2.0 * PI..=2.0 * PI).prop_map(
            |(a, aspect, angle)| BodyShape::Ellipse {
                semi_major: a,
                semi_minor: a * aspect,
                angle,
            }
        ),
    ]
}

fn body() -> impl Strategy<Value = CoupledBody<f64>> {
    (
        [-30.0f64..=30.0, -30.0f64..=30.0],
        [-0.2f64..=0.2, -0.2f64..=0.2],
        -0.05f64..=0.05,
        shape(),
    )
        .prop_map(|(center, velocity, spin, shape)| CoupledBody {
            center: Vector::from(center),
            velocity: Vector::from(velocity),
            spin,
            shape,
        })
}

/// The oracle's description of a body's shape.
fn as_ellipse(b: &CoupledBody<f64>) -> oracle::Ellipse {
    match b.shape {
        BodyShape::Disc { radius } => oracle::Ellipse {
            centre: b.center.into(),
            a: radius,
            b: radius,
            angle: 0.0,
        },
        BodyShape::Ellipse {
            semi_major,
            semi_minor,
            angle,
        } => oracle::Ellipse {
            centre: b.center.into(),
            a: semi_major,
            b: semi_minor,
            angle,
        },
    }
}

/// The cell range by enumeration: the nodes x ∈ 0..n whose cell [x − ½, x + ½] meets [c − reach, c + reach]
/// (first and last), or `None`.
fn cells_meeting(c: f64, reach: f64, n: usize) -> Option<(usize, usize)> {
    let meets = |x: usize| x as f64 - 0.5 <= c + reach && x as f64 + 0.5 >= c - reach;
    let first = (0..n).find(|&x| meets(x))?;
    let last = (0..n).rev().find(|&x| meets(x))?;
    Some((first, last))
}

/// Minimum image of d on an axis of length l (|d| < 3l/2 here), written differently from the kernel.
fn min_image(d: f64, period: Option<f64>) -> f64 {
    match period {
        Some(l) => d - l * (d / l).round(),
        None => d,
    }
}

/// Shares of momentum exchange: node, owner (some out of range: ignored), exchange.
type Shares = Vec<([f64; 2], u32, [f64; 2])>;

/// Which exchange components a share set carries: 0 = x only, 1 = y only, 2 = both.
fn shares(bodies: usize) -> impl Strategy<Value = Shares> {
    (
        prop::collection::vec(
            (
                [0.0f64..40.0, 0.0f64..40.0],
                0u32..=(bodies as u32 + 1),
                [-1e-2f64..=1e-2, -1e-2f64..=1e-2],
            ),
            0..60,
        ),
        0usize..3,
    )
        .prop_map(|(mut s, axes)| {
            for (_, _, e) in s.iter_mut() {
                match axes {
                    0 => e[1] = 0.0,
                    1 => e[0] = 0.0,
                    _ => {}
                }
            }
            s
        })
}

/// Direct sums: F_p = Σ e, T_p = Σ (r_x e_y − r_y e_x) over the shares of body p, with the bound
/// Σ|term| for each, per body.
fn direct_sums(
    s: &Shares,
    centers: &[[f64; 2]],
    periods: [Option<f64>; 2],
) -> (Vec<[f64; 2]>, Vec<f64>, Vec<f64>) {
    let n = centers.len();
    let (mut f, mut t, mut size) = (vec![[0.0; 2]; n], vec![0.0; n], vec![0.0; n]);
    for &(node, owner, e) in s {
        let p = owner as usize;
        if p >= n {
            continue;
        }
        let rx = min_image(node[0] - centers[p][0], periods[0]);
        let ry = min_image(node[1] - centers[p][1], periods[1]);
        f[p][0] += e[0];
        f[p][1] += e[1];
        t[p] += rx * e[1] - ry * e[0];
        size[p] += e[0].abs() + e[1].abs() + (rx * e[1]).abs() + (ry * e[0]).abs();
    }
    (f, t, size)
}

/// The kernel's reduction with the bodies' centres and forces as `math` vectors, converted from and to the
/// plain arrays of these tests.
fn kernel_reduce(
    s: &Shares,
    centers: &[[f64; 2]],
    periods: [Option<f64>; 2],
) -> (Vec<[f64; 2]>, Vec<f64>) {
    let nodes: Vec<[f64; 2]> = s.iter().map(|x| x.0).collect();
    let owners: Vec<u32> = s.iter().map(|x| x.1).collect();
    let ex: Vec<[f64; 2]> = s.iter().map(|x| x.2).collect();
    let centers: Vec<Point<f64>> = centers.iter().map(|&c| Point::from(c)).collect();
    // Garbage in the outputs: they must be overwritten.
    let mut f = vec![Vector::new(f64::NAN, f64::NAN); centers.len()];
    let mut t = vec![f64::NAN; centers.len()];
    reduce_exchange(&nodes, &owners, &ex, &centers, periods, &mut f, &mut t);
    (f.into_iter().map(|v| v.into()).collect(), t)
}

proptest! {
    #![proptest_config(config(256))]

    /// u_s(x) = V + ω (−r_y, r_x) with r = x − X, written out; at the centre it is V; and the relative velocity
    /// of two points is perpendicular to their separation (a rigid motion keeps distances).
    #[test]
    fn rigid_velocity_is_v_plus_omega_cross_r(b in body(), p in [-40.0f64..40.0, -40.0f64..40.0], q in [-40.0f64..40.0, -40.0f64..40.0]) {
        let v = rigid_velocity(&b, Vector::from(p));
        let (rx, ry) = (p[0] - b.center[0], p[1] - b.center[1]);
        // a − s·r_y and a + s·r_x: the same correctly rounded operations as the formula, so bitwise.
        prop_assert_eq!(v, Vector::new(b.velocity[0] - b.spin * ry, b.velocity[1] + b.spin * rx));
        prop_assert_eq!(rigid_velocity(&b, b.center), b.velocity);
        let w = rigid_velocity(&b, Vector::from(q));
        let (dv, dx) = ([v[0] - w[0], v[1] - w[1]], [p[0] - q[0], p[1] - q[1]]);
        let dot = dv[0] * dx[0] + dv[1] * dx[1];
        // |ω| ≤ 0.05 and |x| ≤ 70: each term ≤ 0.05 · 140², with a few ulp of roundoff each.
        prop_assert!(dot.abs() <= 1e-12, "(v(p) − v(q))·(p − q) = {dot}");
    }

    /// Scaling by the fluid-radius factor multiplies each semi-axis (so the reach, bitwise) and keeps the
    /// orientation; the reach is the largest distance from the centre to the boundary.
    #[test]
    fn scaled_shape_and_reach(b in body(), factor in 0.1f64..=1.5, phis in prop::collection::vec(0.0f64..2.0 * PI, 16)) {
        let s = b.shape.scaled(factor);
        prop_assert_eq!(s.reach(), b.shape.reach() * factor);
        match (b.shape, s) {
            (BodyShape::Disc { radius }, BodyShape::Disc { radius: r2 }) => prop_assert_eq!(r2, radius * factor),
            (
                BodyShape::Ellipse { semi_major, semi_minor, angle },
                BodyShape::Ellipse { semi_major: a2, semi_minor: b2, angle: t2 },
            ) => {
                prop_assert_eq!(a2, semi_major * factor);
                prop_assert_eq!(b2, semi_minor * factor);
                prop_assert_eq!(t2, angle);
            }
            _ => prop_assert!(false, "scaling changed the kind of shape"),
        }
        // Every boundary point lies within the reach; the end of the major axis lies on it.
        let e = as_ellipse(&b);
        let reach = b.shape.reach();
        for phi in phis {
            let p = e.boundary_point(phi);
            let d = (p[0] - e.centre[0]).hypot(p[1] - e.centre[1]);
            prop_assert!(d <= reach * (1.0 + 1e-12), "boundary point at {d} beyond reach {reach}");
        }
        let tip = e.boundary_point(0.0);
        let d = (tip[0] - e.centre[0]).hypot(tip[1] - e.centre[1]);
        prop_assert!((d - reach).abs() <= 1e-12 * reach, "major-axis tip at {d}, reach {reach}");
    }

    /// `body_cell_fraction` is the coverage kernel of the body's shape (bitwise), `PreparedBody::cell_fraction`
    /// is bitwise `body_cell_fraction`, and the fractions of the cells in `body_cell_range` sum to the body's
    /// area inside the lattice (oracle), with no covered cell outside the range.
    #[test]
    fn body_fractions_within_the_cell_range(b in body(), nx in 1usize..=30, ny in 1usize..=30, at in [0.0f64..=1.0, 0.0f64..=1.0]) {
        let mut b = b;
        let reach = b.shape.reach();
        b.center = lbdem_kernels::math::vector(-0.5 - reach + at[0] * (nx as f64 + 2.0 * reach), -0.5 - reach + at[1] * (ny as f64 + 2.0 * reach));
        let prepared = PreparedBody::new(&b);
        let range = body_cell_range(&b, nx, ny);
        let (mut sum, mut touched) = (0.0, 0usize);
        for y in 0..ny {
            for x in 0..nx {
                let (xf, yf) = (x as f64, y as f64);
                let f = body_cell_fraction(&b, xf, yf);
                let direct = match b.shape {
                    BodyShape::Disc { radius } => disc_cell_fraction(b.center, radius, xf, yf),
                    BodyShape::Ellipse { semi_major, semi_minor, angle } => {
                        ellipse_cell_fraction(b.center, semi_major, semi_minor, angle, xf, yf)
                    }
                };
                prop_assert_eq!(f.to_bits(), direct.to_bits());
                prop_assert_eq!(prepared.cell_fraction(xf, yf).to_bits(), f.to_bits());
                if f > 0.0 {
                    let inside = range.is_some_and(|[x0, x1, y0, y1]| (x0..=x1).contains(&x) && (y0..=y1).contains(&y));
                    prop_assert!(inside, "cell ({x}, {y}) covered {f} outside the range {range:?}");
                    sum += f;
                    touched += 1;
                }
            }
        }
        let domain = [-0.5, nx as f64 - 0.5, -0.5, ny as f64 - 0.5];
        let want = oracle::ellipse_rectangle_area(&as_ellipse(&b), domain, 16_000);
        // Per-cell roundoff of the coverage kernels (see coverage_properties.rs): 64 ε (1 + reach² + 256).
        let slack = 64.0 * f64::EPSILON * (1.0 + reach * reach + 256.0) * (touched as f64 + 1.0);
        prop_assert!(sum >= want.lo - slack && sum <= want.hi + slack, "sum {sum} vs {want:?}");
    }

    /// `body_cell_range` is exactly the nodes whose cells meet the body's bounding square, clamped to the
    /// lattice on all four sides, or `None` when there are none. Centres and sizes are multiples of 1/64 so
    /// that every comparison is exact and the enumeration and the kernel cannot round differently.
    #[test]
    fn cell_range_is_the_clamped_bounding_square(
        cx in -2560i32..=5120, cy in -2560i32..=5120, r in 1i32..=1280, nx in 1usize..=60, ny in 1usize..=60,
        is_disc in any::<bool>(), angle in -PI..=PI,
    ) {
        let (cx, cy, r) = (cx as f64 / 64.0, cy as f64 / 64.0, r as f64 / 64.0);
        let shape = if is_disc {
            BodyShape::Disc { radius: r }
        } else {
            BodyShape::Ellipse { semi_major: r, semi_minor: 0.5 * r, angle }
        };
        let b = CoupledBody { center: lbdem_kernels::math::vector(cx, cy), velocity: lbdem_kernels::math::Vector::zeros(), spin: 0.0, shape };
        let want = match (cells_meeting(cx, r, nx), cells_meeting(cy, r, ny)) {
            (Some((x0, x1)), Some((y0, y1))) => Some([x0, x1, y0, y1]),
            _ => None,
        };
        prop_assert_eq!(body_cell_range(&b, nx, ny), want);
    }

    /// The force and torque on each body are the direct sums over its shares (forces along x only, y only,
    /// or both; lever arms along both axes; minimum image on periodic axes); shares of bodies out of range
    /// are ignored and the outputs are overwritten.
    #[test]
    fn reduction_is_the_direct_sum(
        centers in prop::collection::vec([0.0f64..40.0, 0.0f64..40.0], 1..5),
        s in shares(4),
        periodic in [any::<bool>(), any::<bool>()],
    ) {
        let periods = [periodic[0].then_some(40.0), periodic[1].then_some(40.0)];
        let (f, t) = kernel_reduce(&s, &centers, periods);
        let (wf, wt, size) = direct_sums(&s, &centers, periods);
        let tol = |p: usize| 4.0 * s.len() as f64 * f64::EPSILON * size[p];
        for p in 0..centers.len() {
            for a in 0..2 {
                prop_assert!((f[p][a] - wf[p][a]).abs() <= tol(p), "body {p} force {a}: {} vs {}", f[p][a], wf[p][a]);
            }
            prop_assert!((t[p] - wt[p]).abs() <= tol(p), "body {p} torque: {} vs {}", t[p], wt[p]);
        }
    }

    /// The reduction is bitwise the direct sum in share order (each body's additions one after the other, as
    /// `direct_sums` writes them), whether the shares of different bodies interleave share by share or come
    /// in runs of one body (the coverage's lists: a body's cells along a row), including runs of bodies out of
    /// range between them.
    #[test]
    fn reduction_is_bitwise_the_sum_in_share_order(
        centers in prop::collection::vec([0.0f64..40.0, 0.0f64..40.0], 1..5),
        s in shares(4),
        runs in prop::collection::vec(1usize..9, 0..60),
        periodic in [any::<bool>(), any::<bool>()],
    ) {
        let periods = [periodic[0].then_some(40.0), periodic[1].then_some(40.0)];
        // The same shares with each one's owner repeated over the next `runs[i]` shares: runs of one body.
        let mut in_runs = s.clone();
        let mut k = 0;
        for (i, &r) in runs.iter().enumerate() {
            let owner = s.get(i).map_or(0, |x| x.1);
            for x in in_runs.iter_mut().skip(k).take(r) {
                x.1 = owner;
            }
            k += r;
        }
        for shares in [&s, &in_runs] {
            let (f, t) = kernel_reduce(shares, &centers, periods);
            let (wf, wt, _) = direct_sums(shares, &centers, periods);
            for p in 0..centers.len() {
                prop_assert_eq!(f[p][0].to_bits(), wf[p][0].to_bits(), "body {} force x", p);
                prop_assert_eq!(f[p][1].to_bits(), wf[p][1].to_bits(), "body {} force y", p);
                prop_assert_eq!(t[p].to_bits(), wt[p].to_bits(), "body {} torque", p);
            }
        }
    }

    /// Translating every node and centre by whole cells (wrapped on periodic axes) leaves forces and torques
    /// unchanged to roundoff; a quarter turn (x, y) → (−y, x) of nodes, centres and exchanges turns each force
    /// the same way and keeps each torque, bitwise (the turn only permutes and negates).
    #[test]
    fn reduction_is_invariant_under_translation_and_quarter_turns(
        centers in prop::collection::vec([0.0f64..40.0, 0.0f64..40.0], 1..5),
        s in shares(4),
        shift in [-40i32..=40, -40i32..=40],
        periodic in [any::<bool>(), any::<bool>()],
    ) {
        let periods = [periodic[0].then_some(40.0), periodic[1].then_some(40.0)];
        let (f, t) = kernel_reduce(&s, &centers, periods);
        let (_, _, size) = direct_sums(&s, &centers, periods);
        let sh = [shift[0] as f64, shift[1] as f64];
        let moved: Shares = s.iter().map(|&(n, o, e)| ([n[0] + sh[0], n[1] + sh[1]], o, e)).collect();
        let moved_centers: Vec<[f64; 2]> = centers.iter().map(|c| [c[0] + sh[0], c[1] + sh[1]]).collect();
        let (mf, mt) = kernel_reduce(&moved, &moved_centers, periods);
        // Forces are the same sums of the same values; lever arms change by the rounding of the shifted
        // coordinates (≤ 1 ulp of 80 each), torques by that times |e|.
        let tol = |p: usize| 4.0 * s.len() as f64 * f64::EPSILON * size[p] + 1e-12;
        for p in 0..centers.len() {
            prop_assert_eq!(mf[p], f[p]);
            prop_assert!((mt[p] - t[p]).abs() <= tol(p), "body {p}: torque {} vs {}", mt[p], t[p]);
        }
        let turn = |v: [f64; 2]| [-v[1], v[0]];
        let turned: Shares = s.iter().map(|&(n, o, e)| (turn(n), o, turn(e))).collect();
        let turned_centers: Vec<[f64; 2]> = centers.iter().map(|&c| turn(c)).collect();
        let (tf, tt) = kernel_reduce(&turned, &turned_centers, [periods[1], periods[0]]);
        for p in 0..centers.len() {
            prop_assert_eq!(tf[p], turn(f[p]));
            prop_assert_eq!(tt[p].to_bits(), t[p].to_bits(), "body {}", p);
        }
    }
}

/// A body whose geometry is not finite, or a lattice without nodes, has no cell range.
#[test]
fn cell_range_refuses_non_finite_bodies_and_empty_lattices() {
    let body = |center: [f64; 2], radius: f64| CoupledBody {
        center: Vector::from(center),
        velocity: lbdem_kernels::math::Vector::zeros(),
        spin: 0.0,
        shape: BodyShape::Disc { radius },
    };
    assert!(body_cell_range(&body([5.0, 5.0], 1.0), 10, 10).is_some());
    for b in [
        body([f64::NAN, 5.0], 1.0),
        body([5.0, f64::NAN], 1.0),
        body([5.0, f64::INFINITY], 1.0),
        body([f64::NEG_INFINITY, 5.0], 1.0),
        body([5.0, 5.0], f64::NAN),
        body([5.0, 5.0], f64::INFINITY),
    ] {
        assert_eq!(body_cell_range(&b, 10, 10), None, "{b:?}");
    }
    assert_eq!(body_cell_range(&body([5.0, 5.0], 1.0), 0, 10), None);
    assert_eq!(body_cell_range(&body([5.0, 5.0], 1.0), 10, 0), None);
}

/// Output buffers of different lengths: shares are reduced only for bodies that have a centre, a force slot
/// and a torque slot.
#[test]
fn reduction_ignores_bodies_without_every_slot() {
    let nodes = [[1.0, 0.0], [0.0, 1.0], [2.0, 2.0]];
    let owners = [0u32, 1, 2];
    let ex = [[0.0, 1.0], [1.0, 0.0], [1.0, 1.0]];
    let centers = [Point::<f64>::zeros(); 3];
    for (nf, nt) in [(3, 1), (1, 3), (2, 2)] {
        let mut f = vec![Vector::new(f64::NAN, f64::NAN); nf];
        let mut t = vec![f64::NAN; nt];
        reduce_exchange(&nodes, &owners, &ex, &centers, [None, None], &mut f, &mut t);
        let n = nf.min(nt);
        // Body 0: lever (1, 0), force (0, 1): torque +1. Body 1: lever (0, 1), force (1, 0): torque −1.
        let want_f = [[0.0, 1.0], [1.0, 0.0]];
        let want_t = [1.0, -1.0];
        for p in 0..nf {
            assert_eq!(
                f[p],
                Vector::from(if p < n { want_f[p] } else { [0.0; 2] }),
                "force {p} of {nf}/{nt}"
            );
        }
        for p in 0..nt {
            assert_eq!(
                t[p],
                if p < n { want_t[p] } else { 0.0 },
                "torque {p} of {nf}/{nt}"
            );
        }
    }
    // Fewer centres than slots: shares of bodies without a centre are dropped.
    let mut f = vec![Vector::new(f64::NAN, f64::NAN); 3];
    let mut t = vec![f64::NAN; 3];
    reduce_exchange(
        &nodes,
        &owners,
        &ex,
        &centers[..1],
        [None, None],
        &mut f,
        &mut t,
    );
    assert_eq!(
        (f, t),
        (
            vec![Vector::new(0.0, 1.0), Vector::zeros(), Vector::zeros()],
            vec![1.0, 0.0, 0.0]
        )
    );
}

/// The minimum-image convention on a periodic axis of length L: a lever arm of exactly ±L/2 is kept as it is
/// (|d| ≤ L/2 is not wrapped; only |d| > L/2 is), so a node half a period away always gets the same arm; and
/// a non-positive period means no wrap.
#[test]
fn minimum_image_keeps_half_a_period_and_ignores_non_positive_periods() {
    let torque = |node: [f64; 2], period: Option<f64>| {
        let (mut f, mut t) = ([lbdem_kernels::math::Vector::<f64>::zeros(); 1], [0.0; 1]);
        // Force (0, 1) at lever (d, 0): torque d.
        reduce_exchange(
            &[node],
            &[0],
            &[[0.0, 1.0]],
            &[lbdem_kernels::math::vector(10.0, 0.0)],
            [period, None],
            &mut f,
            &mut t,
        );
        t[0]
    };
    assert_eq!(torque([30.0, 0.0], Some(40.0)), 20.0, "d = +L/2 kept");
    assert_eq!(torque([-10.0, 0.0], Some(40.0)), -20.0, "d = −L/2 kept");
    assert_eq!(torque([30.5, 0.0], Some(40.0)), -19.5, "d > L/2 wrapped");
    assert_eq!(torque([-10.5, 0.0], Some(40.0)), 19.5, "d < −L/2 wrapped");
    for bad in [0.0, -40.0, f64::NAN] {
        assert_eq!(
            torque([35.0, 0.0], Some(bad)),
            25.0,
            "period {bad}: no wrap"
        );
        assert_eq!(
            torque([-15.0, 0.0], Some(bad)),
            -25.0,
            "period {bad}: no wrap"
        );
    }
}

proptest! {
    #![proptest_config(config(512))]

    /// `surface_normal` at a point of the body's boundary, written as the centre plus R(θ)(a cos φ, b sin φ), is the
    /// unit outward normal there: of unit length, perpendicular to the boundary's tangent R(θ)(−a sin φ, b cos φ)
    /// (the derivative of that parametrisation, written independently of the kernel's implicit-function gradient),
    /// pointing away from the centre; the prepared form gives the same bits; at the centre it is zero.
    ///
    /// Tolerance: the point is formed from coordinates up to 50 and the kernel subtracts the centre again, so the
    /// offset carries up to 50·2⁻⁵² ≈ 1e-14 absolute error on a semi-axis as small as 0.005, 2e-12 relative, and
    /// the gradient scales its components by up to (a/b)² = 100: 1e-8 covers that with room.
    #[test]
    fn surface_normal_is_the_unit_outward_normal_of_the_boundary(b in body(), phi in 0.0f64..(2.0 * PI)) {
        let (a, bb, angle) = match b.shape {
            BodyShape::Disc { radius } => (radius, radius, 0.0),
            BodyShape::Ellipse { semi_major, semi_minor, angle } => (semi_major, semi_minor, angle),
        };
        let (sin, cos) = angle.sin_cos();
        let rot = |v: [f64; 2]| [v[0] * cos - v[1] * sin, v[0] * sin + v[1] * cos];
        let offset = rot([a * phi.cos(), bb * phi.sin()]);
        let tangent = rot([-a * phi.sin(), bb * phi.cos()]);
        let point = Point::new(b.center[0] + offset[0], b.center[1] + offset[1]);
        let n = surface_normal(&b, point);
        prop_assert!((n.norm() - 1.0).abs() <= 1e-12, "length {}", n.norm());
        let t_len = tangent[0].hypot(tangent[1]);
        let along = (n[0] * tangent[0] + n[1] * tangent[1]) / t_len;
        prop_assert!(along.abs() <= 1e-8, "normal {n:?} against tangent {tangent:?}: {along}");
        prop_assert!(n[0] * offset[0] + n[1] * offset[1] > 0.0, "points inwards");
        let prepared = PreparedBody::new(&b).surface_normal(point);
        prop_assert_eq!(prepared[0].to_bits(), n[0].to_bits());
        prop_assert_eq!(prepared[1].to_bits(), n[1].to_bits());
        prop_assert_eq!(surface_normal(&b, b.center), Vector::zeros());
    }
}
