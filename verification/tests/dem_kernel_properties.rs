//! Precision properties of the DEM kernels that the dense-sampling oracle of `dem_properties.rs` (accurate to
//! ~1e-6) cannot see:
//!
//! * `ellipse_ellipse` returns the maximiser of the separating-axis gap s(θ) = n·d − h_A(n) − h_B(−n) to
//!   rounding, as its documentation claims: the overlap is −s at the returned normal, s is stationary there
//!   (a centred difference of s, written here from the ellipses' support function
//!   h(n) = √(a²(n·u)² + b²(n·v)²), vanishes), and no other direction has a larger gap; for two discs
//!   swept through every approach direction it is exact (normal d/|d|, overlap r_i + r_j − |d|);
//! * a parallel bond's first increment, for any orientation, relative motion and gap, against the
//!   incremental law written out (Potyondy & Cundall 2004): ΔF_n = −k̄_n A (v·n) Δt, ΔF_s = −k̄_s A (v·t) Δt,
//!   ΔM = −k̄_n I Δω Δt, v the relative velocity at the midpoint of the gap;
//! * the kinetic energy ½ m |v|² + ½ I ω², and PFC local damping −α |F| sign(v);
//! * `Placed::support_derivatives` (h, dh/dθ and the radius of curvature ρ = h + d²h/dθ², by centred
//!   differences of the support function written here) and `Placed::contains` (against the oracle's
//!   point-in-ellipse test, away from the boundary);
//! * `Wall::project` (the foot of the perpendicular: on the wall, reached along the normal) and
//!   `WallSegment::wall` (unit left normal, length, the documented zero-length case).
//!
//! **Tolerances.** s is a few dozen operations on lengths ≤ |d| + a + b ≤ 4, so it carries ≤ 64 ε of that
//! (3e-14); the centred difference over ±1e-6 rad then has roundoff ≤ 3e-14/1e-6 and truncation
//! s''' (1e-6)²/6 < 1e-11, while a maximiser off by δθ gives |s'| ≈ |s''| δθ with |s''| ≥ 0.1 here: the
//! bound 1e-7 on |s'| catches δθ ≥ 1e-6. Bond increments are a few products of O(1) values: 64 ε relative.
use lbdem_kernels::dem::bond::{parallel_bond_force, ParallelBond};
use lbdem_kernels::dem::contact::ellipse_ellipse;
use lbdem_kernels::dem::integrate::kinetic_energy;
use lbdem_kernels::dem::law::{local_damping, BodyState};
use lbdem_kernels::dem::shape::{Particle, Placed, Wall, WallSegment};
use lbdem_verification::proptest_cases;
use proptest::prelude::*;
use std::f64::consts::{PI, TAU};

fn config(default: u32) -> ProptestConfig {
    ProptestConfig::with_cases(proptest_cases(default))
}

/// An ellipse for the gap oracle: centre, semi-axes, orientation.
#[derive(Clone, Copy, Debug)]
struct E {
    c: [f64; 2],
    a: f64,
    b: f64,
    phi: f64,
}

impl E {
    fn placed(&self) -> Placed<f64> {
        Placed::new(
            lbdem_kernels::math::Vector::from(self.c),
            self.phi,
            self.a,
            self.b,
        )
    }
    /// Support function h(n) = max_{x ∈ E} n·(x − c).
    fn support(&self, n: [f64; 2]) -> f64 {
        let (u, v) = (
            [self.phi.cos(), self.phi.sin()],
            [-self.phi.sin(), self.phi.cos()],
        );
        let (nu, nv) = (n[0] * u[0] + n[1] * u[1], n[0] * v[0] + n[1] * v[1]);
        (self.a * self.a * nu * nu + self.b * self.b * nv * nv).sqrt()
    }
}

/// The separating-axis gap of (A, B) along the direction at angle θ.
fn gap(a: &E, b: &E, theta: f64) -> f64 {
    let n = [theta.cos(), theta.sin()];
    let d = [b.c[0] - a.c[0], b.c[1] - a.c[1]];
    n[0] * d[0] + n[1] * d[1] - a.support(n) - b.support([-n[0], -n[1]])
}

/// Two ellipses from overlapping to apart: the first at the origin with a = 1, the second anywhere within
/// reach; semi-axes in [0.4, 1].
fn pair() -> impl Strategy<Value = (E, E)> {
    (
        0.4f64..=1.0,
        0.4f64..=1.0,
        0.4f64..=1.0,
        -PI..PI,
        -PI..PI,
        0.0f64..TAU,
        0.3f64..2.6,
    )
        .prop_map(|(b1, a2, r2, p1, p2, dir, dist)| {
            let e1 = E {
                c: [0.0, 0.0],
                a: 1.0,
                b: b1,
                phi: p1,
            };
            let e2 = E {
                c: [dist * dir.cos(), dist * dir.sin()],
                a: a2,
                b: a2 * r2,
                phi: p2,
            };
            (e1, e2)
        })
}

proptest! {
    #![proptest_config(config(256))]

    /// The returned normal maximises s to rounding: the overlap is −s there, s is stationary there (where s
    /// is concave: overlaps below half the smallest radius of curvature), and no direction of a 1440-point
    /// sweep has a larger gap.
    #[test]
    fn ellipse_contact_is_the_gap_maximiser((e1, e2) in pair()) {
        let c = ellipse_ellipse(&e1.placed(), &e2.placed());
        let theta = c.normal[1].atan2(c.normal[0]);
        let s = gap(&e1, &e2, theta);
        prop_assert!((c.overlap + s).abs() <= 1e-13, "overlap {} vs −s = {}", c.overlap, -s);
        let best = (0..1440).map(|k| gap(&e1, &e2, TAU * k as f64 / 1440.0)).fold(f64::NEG_INFINITY, f64::max);
        prop_assert!(s >= best - 1e-13, "s(θ*) = {s} below the sweep's {best}");
        let min_curvature = [e1, e2].iter().map(|e| e.b * e.b / e.a).fold(f64::INFINITY, f64::min);
        if c.overlap < 0.5 * min_curvature {
            let h = 1e-6;
            let slope = (gap(&e1, &e2, theta + h) - gap(&e1, &e2, theta - h)) / (2.0 * h);
            prop_assert!(slope.abs() <= 1e-7, "s'(θ*) = {slope:e}: not the maximiser");
        }
    }
}

/// Two discs (as ellipses with a = b, through the general maximiser) approached from 4096 directions, at
/// overlaps and gaps: the normal is d/|d| and the overlap r_i + r_j − |d|, to rounding.
#[test]
fn disc_pairs_from_every_direction_are_exact() {
    for k in 0..4096 {
        let dir = TAU * (k as f64 + 0.37) / 4096.0;
        let (ri, rj) = (0.7, 0.45 + 0.1 * (k % 5) as f64);
        let dist = ri + rj + [-0.2, -0.01, 0.0, 0.05, 0.8][k % 5];
        let cj = [0.3 + dist * dir.cos(), -0.1 + dist * dir.sin()];
        let c = ellipse_ellipse(
            &Placed::new(lbdem_kernels::math::vector(0.3, -0.1), 0.0, ri, ri),
            &Placed::new(lbdem_kernels::math::Vector::from(cj), 1.1, rj, rj),
        );
        let want = [dir.cos(), dir.sin()];
        assert!(
            (c.normal[0] - want[0]).abs() < 1e-12 && (c.normal[1] - want[1]).abs() < 1e-12,
            "direction {k}: normal {:?} vs {want:?}",
            c.normal
        );
        assert!(
            (c.overlap - (ri + rj - dist)).abs() < 1e-13,
            "direction {k}: overlap {} vs {}",
            c.overlap,
            ri + rj - dist
        );
    }
}

proptest! {
    #![proptest_config(config(256))]

    /// The first increment of a parallel bond, for any orientation, gap, relative velocity and spins, is the
    /// incremental law written out; the forces on i and j are opposite and the torques balance about the bond.
    #[test]
    fn parallel_bond_increment_is_the_incremental_law(
        dir in -PI..PI, dist in 0.5f64..1.5, ri in 0.2f64..0.6, rj in 0.2f64..0.6,
        vi in [-1.0f64..1.0, -1.0f64..1.0], vj in [-1.0f64..1.0, -1.0f64..1.0],
        wi in -3.0f64..3.0, wj in -3.0f64..3.0, origin in [-2.0f64..2.0, -2.0f64..2.0],
    ) {
        let (kn, ks, dt) = (2e4, 8e3, 1e-3);
        let mut bond = ParallelBond::new(ri, rj, 0.8, kn, ks, 1e12, 1e12);
        let xi = origin;
        let n = [dir.cos(), dir.sin()];
        let xj = [xi[0] + dist * n[0], xi[1] + dist * n[1]];
        let bi = BodyState { position: lbdem_kernels::math::Vector::from(xi), velocity: lbdem_kernels::math::Vector::from(vi), angular_velocity: wi };
        let bj = BodyState { position: lbdem_kernels::math::Vector::from(xj), velocity: lbdem_kernels::math::Vector::from(vj), angular_velocity: wj };
        let f = parallel_bond_force(&mut bond, &bi, ri, &bj, rj, dt);
        // The midpoint of the gap between the two surfaces along the centre line.
        let surface_i = [xi[0] + ri * n[0], xi[1] + ri * n[1]];
        let surface_j = [xj[0] - rj * n[0], xj[1] - rj * n[1]];
        let x = [0.5 * (surface_i[0] + surface_j[0]), 0.5 * (surface_i[1] + surface_j[1])];
        let at = |v: [f64; 2], w: f64, c: [f64; 2]| [v[0] - w * (x[1] - c[1]), v[1] + w * (x[0] - c[0])];
        let (ui, uj) = (at(vi, wi, xi), at(vj, wj, xj));
        let v = [uj[0] - ui[0], uj[1] - ui[1]];
        let t = [-n[1], n[0]];
        let r = 0.8 * ri.min(rj);
        let (area, inertia) = (2.0 * r, 2.0 * r * r * r / 3.0);
        let want_n = -kn * area * (v[0] * n[0] + v[1] * n[1]) * dt;
        let want_s = -ks * area * (v[0] * t[0] + v[1] * t[1]) * dt;
        let want_m = -kn * inertia * (wj - wi) * dt;
        let tol = |w: f64| 64.0 * f64::EPSILON * (1.0 + w.abs()) * 10.0;
        prop_assert!((bond.normal_force - want_n).abs() <= tol(kn * area * dt * 4.0), "F_n {} vs {}", bond.normal_force, want_n);
        prop_assert!((bond.shear_force - want_s).abs() <= tol(ks * area * dt * 4.0), "F_s {} vs {}", bond.shear_force, want_s);
        prop_assert!((bond.moment - want_m).abs() <= tol(kn * inertia * dt * 6.0), "M {} vs {}", bond.moment, want_m);
        let want_j = [want_n * n[0] + want_s * t[0], want_n * n[1] + want_s * t[1]];
        let scale = kn * area * dt * 8.0;
        prop_assert!((f.force_on_j[0] - want_j[0]).abs() <= tol(scale) && (f.force_on_j[1] - want_j[1]).abs() <= tol(scale));
        prop_assert_eq!(f.force_on_i, -f.force_on_j);
        // Moment balance about the origin: τ_i + τ_j + x_i × F_i + x_j × F_j = 0 (the bond is internal).
        let cross = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - a[1] * b[0];
        let m = f.torque_on_i + f.torque_on_j + cross(xi, f.force_on_i.into()) + cross(xj, f.force_on_j.into());
        prop_assert!(m.abs() <= tol(scale * 8.0), "moment residual {m:e}");
    }

    /// ½ m |v|² + ½ I ω², for motion along each axis and rotation.
    #[test]
    fn kinetic_energy_is_half_m_v_squared_plus_half_i_omega_squared(
        v in [-3.0f64..3.0, -3.0f64..3.0], w in -10.0f64..10.0, r in 0.05f64..1.0, disc in any::<bool>(),
    ) {
        let mut p = if disc { Particle::disc(lbdem_kernels::math::vector(0.0, 0.0), r, 2.0) } else { Particle::ellipse(lbdem_kernels::math::vector(0.0, 0.0), 0.4, r, 0.5 * r, 2.0) };
        p.velocity = lbdem_kernels::math::Vector::from(v);
        p.angular_velocity = w;
        let want = 0.5 * p.mass * (v[0] * v[0] + v[1] * v[1]) + 0.5 * p.moment_of_inertia * w * w;
        prop_assert!((kinetic_energy(&p) - want).abs() <= 8.0 * f64::EPSILON * want, "{} vs {want}", kinetic_energy(&p));
    }
}

proptest! {
    #![proptest_config(config(256))]

    /// PFC local damping opposes the velocity with magnitude α |F|, and vanishes at rest.
    #[test]
    fn local_damping_opposes_the_velocity(f in -10.0f64..10.0, v in -2.0f64..2.0, alpha in 0.0f64..1.0, at_rest in any::<bool>()) {
        let v = if at_rest { 0.0 } else { v };
        let sign = if v > 0.0 { 1.0 } else if v < 0.0 { -1.0 } else { 0.0 };
        prop_assert_eq!(local_damping(f, v, alpha), -alpha * f.abs() * sign);
    }

    /// The support value, its angular derivative and the radius of curvature, against centred differences of
    /// h(θ) over ±1e-4 rad (truncation ≈ h‴·1e-8/6 ≤ 1e-7 for these shapes; roundoff 1e-16/1e-8 = 1e-8): the
    /// allowance 1e-5 of the semi-major axis (over aspect³ for ρ) is far below the size of a formula error.
    #[test]
    fn support_derivatives_match_differences_of_the_support_function(
        a in 0.2f64..2.0, aspect in 0.3f64..=1.0, phi in -PI..PI, theta in -PI..PI, c in [-5.0f64..5.0, -5.0f64..5.0],
    ) {
        let e = E { c, a, b: a * aspect, phi };
        let p = e.placed();
        let at = |t: f64| e.support([t.cos(), t.sin()]);
        let n = [theta.cos(), theta.sin()];
        let (h, dh, rho) = p.support_derivatives(lbdem_kernels::math::Vector::from(n));
        let step = 1e-4;
        let d1 = (at(theta + step) - at(theta - step)) / (2.0 * step);
        let d2 = (at(theta + step) - 2.0 * at(theta) + at(theta - step)) / (step * step);
        prop_assert!((h - at(theta)).abs() <= 1e-13 * a, "h {h} vs {}", at(theta));
        prop_assert!((p.support_value(lbdem_kernels::math::Vector::from(n)) - h).abs() <= 1e-13 * a);
        prop_assert!((dh - d1).abs() <= 1e-5 * a, "h' {dh} vs {d1}");
        prop_assert!((rho - (h + d2)).abs() <= 1e-5 * a / aspect.powi(3), "ρ {rho} vs {}", h + d2);
    }

    /// `contains` agrees with the oracle's point-in-ellipse test for points not within 1e-9 (relative) of the
    /// boundary.
    #[test]
    fn contains_matches_the_oracle(
        a in 0.2f64..2.0, aspect in 0.3f64..=1.0, phi in -PI..PI, c in [-5.0f64..5.0, -5.0f64..5.0],
        pts in prop::collection::vec([-2.5f64..2.5, -2.5f64..2.5], 32),
    ) {
        let e = E { c, a, b: a * aspect, phi };
        let o = lbdem_reference::dem::Ellipse { centre: c, a, b: a * aspect, angle: phi };
        let grown = lbdem_reference::dem::Ellipse { a: o.a * (1.0 + 1e-9), b: o.b * (1.0 + 1e-9), ..o };
        let shrunk = lbdem_reference::dem::Ellipse { a: o.a * (1.0 - 1e-9), b: o.b * (1.0 - 1e-9), ..o };
        let mut compared = 0;
        for q in pts {
            let x = [c[0] + q[0], c[1] + q[1]];
            if grown.contains(x) == shrunk.contains(x) {
                prop_assert_eq!(e.placed().contains(lbdem_kernels::math::Vector::from(x)), o.contains(x), "point {:?}", x);
                compared += 1;
            }
        }
        prop_assert!(compared > 0);
    }
}

proptest! {
    #![proptest_config(config(256))]

    /// The projection of x onto a wall lies on the wall, and x is reached from it along the normal by the
    /// signed distance; a segment's wall has the unit left normal of start → end and its length.
    #[test]
    fn wall_projection_and_segment_geometry(
        p in [-5.0f64..5.0, -5.0f64..5.0], angle in -PI..PI, x in [-5.0f64..5.0, -5.0f64..5.0],
        e in [-3.0f64..3.0, -3.0f64..3.0],
    ) {
        let wall = Wall::from_angle(lbdem_kernels::math::Vector::from(p), angle);
        let f = wall.project(lbdem_kernels::math::Vector::from(x));
        let s = wall.signed_distance(lbdem_kernels::math::Vector::from(x));
        prop_assert!(wall.signed_distance(f).abs() <= 1e-14, "foot {f:?} off the wall");
        for k in 0..2 {
            prop_assert!((f[k] + s * wall.normal[k] - x[k]).abs() <= 1e-14, "axis {k}");
        }
        let seg = WallSegment { start: lbdem_kernels::math::Vector::from(p), end: lbdem_kernels::math::vector(p[0] + e[0], p[1] + e[1]) };
        let (w, length) = seg.wall();
        // The segment as stored (end − start carries the rounding of start + e).
        let e = [seg.end[0] - p[0], seg.end[1] - p[1]];
        let len = e[0].hypot(e[1]);
        prop_assume!(len > 1e-3);
        prop_assert!((length - len).abs() <= 4.0 * f64::EPSILON * len, "length {length} vs {len}");
        prop_assert_eq!(w.point, lbdem_kernels::math::Vector::from(p));
        prop_assert!((w.normal[0] + e[1] / len).abs() <= 1e-15 && (w.normal[1] - e[0] / len).abs() <= 1e-15, "normal {:?}", w.normal);
        prop_assert!((seg.abscissa(seg.end) - len).abs() <= 1e-13 && seg.abscissa(seg.start).abs() <= 1e-15, "abscissae {} {}", seg.abscissa(seg.start), seg.abscissa(seg.end));
    }
}

/// A zero-length segment: normal (0, 1), length 0 (documented), not NaN.
#[test]
fn zero_length_segment_has_the_documented_wall() {
    let seg = WallSegment {
        start: lbdem_kernels::math::vector(1.5, -2.0),
        end: lbdem_kernels::math::vector(1.5, -2.0),
    };
    let (w, length) = seg.wall();
    assert_eq!(
        (w.normal, length, w.point),
        (
            lbdem_kernels::math::vector(0.0, 1.0),
            0.0,
            lbdem_kernels::math::vector(1.5, -2.0)
        )
    );
}
