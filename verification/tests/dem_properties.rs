//! Properties of the DEM kernels that must hold for every input: contact geometry against the brute-force
//! oracle, symmetry, Newton's third law and moment balance at contacts and bonds, the Coulomb bound, no force
//! without overlap, bond breakage exactly at the threshold, no NaN in degenerate configurations, and the broad
//! phase against an O(N²) search.
use lbdem_kernels::dem::bond::{
    parallel_bond_force, point_bond_force, BreakMode, ParallelBond, PointBond,
};
use lbdem_kernels::dem::contact::{
    closest_approach, disc_disc, ellipse_disc, ellipse_ellipse, ellipse_wall, particle_contact,
    Contact,
};
use lbdem_kernels::dem::grid::{
    build_cell_grid, candidate_pairs, carry_contact_history, cell_grid_scratch_len,
    filter_candidate_pairs, CellGrid,
};
use lbdem_kernels::dem::law::{linear_contact_force, BodyState, ContactLaw};
use lbdem_kernels::dem::shape::{Particle, Placed, Wall};
use lbdem_kernels::math::{cross, Vector};
use lbdem_reference::dem as oracle;
use proptest::prelude::*;

/// Oracle resolution: 2048 boundary points and 2048 directions. With a = 1 and b ≥ 0.4 the oracle's own
/// error is ≤ a(2π/n)²/8 + ½(2a²/b + |δ|)(π/m)² ≈ 1.2e-6 + 1.3e-5 (see `lbdem_reference::dem`; the inscribed
/// polygon underestimates the overlap, the direction search overestimates it). The kernel converges to
/// rounding, so 2e-5 of the semi-major axis is the oracle's bound plus headroom. Measured: the largest
/// difference is 2.5e-6 at n = m = 2048 and 1.1e-7 at 8192 (it falls as 1/n², so it is the oracle's error).
const ORACLE_SAMPLES: usize = 2048;
const ORACLE_TOLERANCE: f64 = 2e-5;

fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        ..ProptestConfig::default()
    }
}

/// Two ellipses with a = 1 for the first, semi-axes in [0.4, 1], arbitrary orientations, centres apart by a
/// distance that ranges from deep overlap to a clear gap.
fn ellipse_pair() -> impl Strategy<Value = (oracle::Ellipse, oracle::Ellipse)> {
    (
        0.4f64..1.0,
        0.5f64..1.0,
        0.4f64..1.0,
        0.0f64..std::f64::consts::TAU,
        0.0f64..std::f64::consts::TAU,
        0.0f64..std::f64::consts::TAU,
        0.5f64..2.2,
    )
        .prop_map(|(b1, a2, r2, t1, t2, phi, dist)| {
            let e1 = oracle::Ellipse {
                centre: [0.3, -0.2],
                a: 1.0,
                b: b1,
                angle: t1,
            };
            let e2 = oracle::Ellipse {
                centre: [0.3 + dist * phi.cos(), -0.2 + dist * phi.sin()],
                a: a2,
                b: a2 * r2.max(0.4),
                angle: t2,
            };
            (e1, e2)
        })
}

fn placed(e: &oracle::Ellipse) -> Placed<f64> {
    Placed::new(
        lbdem_kernels::math::Vector::from(e.centre),
        e.angle,
        e.a,
        e.b,
    )
}

proptest! {
    #![proptest_config(config(48))]

    /// Ellipse–ellipse signed overlap agrees with the brute-force oracle, the point-inclusion test agrees on
    /// whether they touch, and the returned surface points are on the boundaries.
    #[test]
    fn ellipse_ellipse_matches_brute_force((e1, e2) in ellipse_pair()) {
        let c = ellipse_ellipse(&placed(&e1), &placed(&e2));
        let (reference, _) = oracle::ellipse_ellipse_overlap(&e1, &e2, ORACLE_SAMPLES, ORACLE_SAMPLES);
        prop_assert!((c.overlap - reference).abs() <= ORACLE_TOLERANCE,
            "kernel {} oracle {}", c.overlap, reference);
        if c.overlap > 1e-3 {
            prop_assert!(oracle::boundaries_intersect(&e1, &e2, ORACLE_SAMPLES));
        }
        if c.overlap < -1e-3 {
            prop_assert!(!oracle::boundaries_intersect(&e1, &e2, ORACLE_SAMPLES));
        }
        for (p, e) in [(c.point_i, &e1), (c.point_j, &e2)] {
            let grown = oracle::Ellipse { a: e.a * (1.0 + 1e-9), b: e.b * (1.0 + 1e-9), ..*e };
            let shrunk = oracle::Ellipse { a: e.a * (1.0 - 1e-9), b: e.b * (1.0 - 1e-9), ..*e };
            prop_assert!(grown.contains(p.into()) && !shrunk.contains(p.into()));
        }
        prop_assert!((c.normal[0].hypot(c.normal[1]) - 1.0).abs() < 1e-12);
    }

    /// Swapping the pair gives the same overlap and the opposite normal; f32 agrees with f64.
    #[test]
    fn ellipse_ellipse_is_symmetric((e1, e2) in ellipse_pair()) {
        let c12 = ellipse_ellipse(&placed(&e1), &placed(&e2));
        let c21 = ellipse_ellipse(&placed(&e2), &placed(&e1));
        prop_assert!((c12.overlap - c21.overlap).abs() <= 1e-12, "{} vs {}", c12.overlap, c21.overlap);
        // The maximiser is isolated when overlaps are small against the curvature radii (≥ 0.16 here): its
        // angle is then determined to ~√ε at worst.
        if c12.overlap > -0.5 && c12.overlap < 0.1 {
            prop_assert!((c12.normal[0] + c21.normal[0]).abs() < 1e-6);
            prop_assert!((c12.normal[1] + c21.normal[1]).abs() < 1e-6);
        }
        let p32 = |e: &oracle::Ellipse| Placed::<f32>::new(
            lbdem_kernels::math::vector(e.centre[0] as f32, e.centre[1] as f32), e.angle as f32, e.a as f32, e.b as f32);
        let c32 = ellipse_ellipse(&p32(&e1), &p32(&e2));
        // f32 inputs are rounded by ~6e-8 relative; the overlap inherits a few times that of |d| + a + b ≲ 4.
        prop_assert!((c32.overlap as f64 - c12.overlap).abs() < 5e-6, "{} vs {}", c32.overlap, c12.overlap);
    }

    /// Ellipse–wall overlap against the oracle's deepest sampled point; disc–disc against its closed form.
    #[test]
    fn ellipse_wall_matches_brute_force(
        b in 0.4f64..1.0, angle in 0.0f64..6.3, wall_angle in 0.0f64..6.3, height in -1.5f64..1.5,
    ) {
        let e = oracle::Ellipse { centre: [0.1, 0.2], a: 1.0, b, angle };
        let normal = [wall_angle.cos(), wall_angle.sin()];
        let point = [0.1 - height * normal[0], 0.2 - height * normal[1]];
        let c = ellipse_wall(&placed(&e), &Wall { point: lbdem_kernels::math::Vector::from(point), normal: lbdem_kernels::math::Vector::from(normal) });
        let reference = oracle::ellipse_wall_overlap(&e, point, normal, ORACLE_SAMPLES);
        // Only the sagitta error a(2π/n)²/8 ≈ 1.2e-6 applies here.
        prop_assert!((c.overlap - reference).abs() < 2e-6, "{} vs {}", c.overlap, reference);
        prop_assert!((c.normal[0] + normal[0]).abs() < 1e-15 && (c.normal[1] + normal[1]).abs() < 1e-15);
    }

    /// Newton's third law, moment balance about the contact point, the Coulomb bound, and agreement with the
    /// term-by-term oracle law, for random particles, velocities and shear histories.
    #[test]
    fn contact_force_balances_and_obeys_coulomb(
        kind in 0usize..3, b in 0.4f64..1.0, t1 in 0.0f64..6.3, t2 in 0.0f64..6.3,
        phi in 0.0f64..6.3, dist in 0.5f64..1.9,
        v in prop::array::uniform4(-2.0f64..2.0), w in prop::array::uniform2(-3.0f64..3.0),
        shear in -50.0f64..50.0, mu in 0.0f64..1.0, cn in 0.0f64..5.0,
    ) {
        let pj_pos = [dist * phi.cos(), dist * phi.sin()];
        let (pi, pj) = match kind {
            0 => (Particle::disc(lbdem_kernels::math::vector(0.0, 0.0), 0.5, 1.0), Particle::disc(lbdem_kernels::math::Vector::from(pj_pos), 0.5, 1.0)),
            1 => (Particle::ellipse(lbdem_kernels::math::vector(0.0, 0.0), t1, 1.0, b, 1.0), Particle::disc(lbdem_kernels::math::Vector::from(pj_pos), 0.5, 1.0)),
            _ => (Particle::ellipse(lbdem_kernels::math::vector(0.0, 0.0), t1, 1.0, b, 1.0), Particle::ellipse(lbdem_kernels::math::Vector::from(pj_pos), t2, 0.8, 0.8 * b, 1.0)),
        };
        let mut pi = pi;
        let mut pj = pj;
        pi.velocity = lbdem_kernels::math::vector(v[0], v[1]);
        pj.velocity = lbdem_kernels::math::vector(v[2], v[3]);
        pi.angular_velocity = w[0];
        pj.angular_velocity = w[1];
        let law = ContactLaw { normal_damping: cn, ..ContactLaw::elastic(1e3, 6e2, mu) };
        let c = closest_approach(&pi, &pj);
        let (bi, bj) = (BodyState::of(&pi), BodyState::of(&pj));
        let mut history = shear;
        let dt = 1e-3;
        let f = linear_contact_force(&law, &c, &bi, &bj, &mut history, dt);
        prop_assert_eq!(f.force_on_i, -f.force_on_j);
        // Net moment about the contact point x: τ_i + τ_j + (c_i − x) × F_i + (c_j − x) × F_j = 0.
        let m = f.torque_on_i + f.torque_on_j
            + cross(&(pi.position - c.point), &f.force_on_i)
            + cross(&(pj.position - c.point), &f.force_on_j);
        let scale = 1.0 + f.force_on_j[0].abs() + f.force_on_j[1].abs();
        prop_assert!(m.abs() <= 1e-12 * scale * 4.0, "moment residual {m}");
        prop_assert!(f.normal_force >= 0.0);
        prop_assert!(f.shear_force.abs() <= mu * f.normal_force * (1.0 + 1e-15));
        prop_assert_eq!(history, f.shear_force);
        if !c.is_active() {
            prop_assert_eq!(f.force_on_j, Vector::zeros());
            prop_assert_eq!(f.torque_on_i, 0.0);
            prop_assert_eq!(history, 0.0);
            prop_assert!(particle_contact(&pi, &pj).is_none());
        } else {
            let rel = bj.velocity_at(c.point) - bi.velocity_at(c.point);
            let (fr, sr) = oracle::linear_contact_force(c.overlap, c.normal.into(), rel.into(), shear, 1e3, 6e2, mu, cn, dt);
            prop_assert!((fr[0] - f.force_on_j[0]).abs() <= 1e-12 * scale);
            prop_assert!((fr[1] - f.force_on_j[1]).abs() <= 1e-12 * scale);
            prop_assert!((sr - f.shear_force).abs() <= 1e-12 * scale);
            prop_assert!(particle_contact(&pi, &pj).is_some());
        }
    }

    /// Point bond: equal and opposite, moment-balanced, and it breaks exactly when |F| reaches F_crit and
    /// exerts nothing afterwards.
    #[test]
    fn point_bond_balances_and_breaks_at_threshold(
        t1 in 0.0f64..6.3, t2 in 0.0f64..6.3, phi in 0.0f64..6.3, gap in -0.05f64..0.05,
        dx in prop::array::uniform2(-0.01f64..0.01), dth in prop::array::uniform2(-0.1f64..0.1),
    ) {
        let pi = Particle::ellipse(lbdem_kernels::math::vector(0.0, 0.0), t1, 0.11, 0.055, 2.6);
        let mut pj = Particle::ellipse(lbdem_kernels::math::vector(0.0, 0.0), t2, 0.09, 0.045, 2.6);
        // place j along phi so that its closest-approach gap is about `gap`
        let mut r = 0.0;
        for _ in 0..4 {
            pj.position = lbdem_kernels::math::vector(r * phi.cos(), r * phi.sin());
            let c = closest_approach(&pi, &pj);
            r += gap - (-c.overlap) + if r == 0.0 { 0.1 } else { 0.0 };
        }
        pj.position = lbdem_kernels::math::vector(r * phi.cos(), r * phi.sin());
        let mut bond = PointBond::between(&pi, &pj, 1e5, f64::INFINITY);
        let unloaded = point_bond_force(&mut bond, &pi, &pj);
        prop_assert!(unloaded.force_on_j.iter().all(|f| f.abs() < 1e-9), "{:?}", unloaded.force_on_j);
        // A rigid rotation of the whole pair about the origin stretches nothing.
        let rot = 0.3f64;
        let rotp = |p: [f64; 2]| [rot.cos() * p[0] - rot.sin() * p[1], rot.sin() * p[0] + rot.cos() * p[1]];
        let (mut qi, mut qj) = (pi, pj);
        qi.position = lbdem_kernels::math::Vector::from(rotp(pi.position.into()));
        qj.position = lbdem_kernels::math::Vector::from(rotp(pj.position.into()));
        qi.angle += rot;
        qj.angle += rot;
        let rigid = point_bond_force(&mut bond, &qi, &qj);
        prop_assert!(rigid.force_on_j.iter().all(|f| f.abs() < 1e-7), "{:?}", rigid.force_on_j);
        // Deform.
        let mut mj = pj;
        mj.position[0] += dx[0];
        mj.position[1] += dx[1];
        mj.angle += dth[0];
        let mut mi = pi;
        mi.angle += dth[1];
        let f = point_bond_force(&mut bond, &mi, &mj);
        prop_assert!(f.broke.is_none());
        prop_assert_eq!(f.force_on_i, -f.force_on_j);
        let (a, b) = bond.material_points(&mi, &mj);
        let x = Vector::new((a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0);
        let m = f.torque_on_i + f.torque_on_j
            + cross(&(mi.position - x), &f.force_on_i) + cross(&(mj.position - x), &f.force_on_j);
        prop_assert!(m.abs() < 1e-9, "moment residual {m}");
        // The same |F| the kernel compares with the strength (libm's hypot, the same bits in every build).
        let magnitude = lbdem_kernels::Real::portable_hypot(f.force_on_j[0], f.force_on_j[1]);
        prop_assume!(magnitude > 0.0);
        // Just above the load: intact. Exactly at it: broken, zero force, and zero ever after.
        let mut above = PointBond { strength: magnitude * (1.0 + 1e-15) + f64::MIN_POSITIVE, ..bond };
        let mut above_next = above;
        above_next.strength = f64::from_bits(magnitude.to_bits() + 1);
        prop_assert!(point_bond_force(&mut above, &mi, &mj).broke.is_none());
        prop_assert!(point_bond_force(&mut above_next, &mi, &mj).broke.is_none());
        let mut at = PointBond { strength: magnitude, ..bond };
        let broke = point_bond_force(&mut at, &mi, &mj);
        let record = broke.broke.expect("breaks at |F| = F_crit");
        prop_assert_eq!(record.load, magnitude);
        prop_assert_eq!(broke.force_on_j, Vector::zeros());
        prop_assert!(!at.intact);
        let after = point_bond_force(&mut at, &pi, &pj);
        prop_assert!(after.broke.is_none() && after.force_on_j == lbdem_kernels::math::vector(0.0, 0.0) && after.torque_on_j == 0.0);
    }

    /// Parallel bond: equal and opposite forces, moments balanced about the bond point, stresses from the
    /// formulas of P&C 2004.
    #[test]
    fn parallel_bond_balances(
        v in prop::array::uniform4(-1.0f64..1.0), w in prop::array::uniform2(-1.0f64..1.0),
        phi in 0.0f64..6.3, steps in 1usize..5,
    ) {
        let mut bond = ParallelBond::new(0.1, 0.08, 1.0, 1e6, 4e5, f64::INFINITY, f64::INFINITY);
        let d = 0.18;
        let bi = BodyState { position: lbdem_kernels::math::vector(0.0, 0.0), velocity: lbdem_kernels::math::vector(v[0], v[1]), angular_velocity: w[0] };
        let bj = BodyState { position: lbdem_kernels::math::vector(d * phi.cos(), d * phi.sin()), velocity: lbdem_kernels::math::vector(v[2], v[3]), angular_velocity: w[1] };
        let mut f = parallel_bond_force(&mut bond, &bi, 0.1, &bj, 0.08, 1e-4);
        for _ in 1..steps {
            f = parallel_bond_force(&mut bond, &bi, 0.1, &bj, 0.08, 1e-4);
        }
        prop_assert!(f.broke.is_none());
        prop_assert_eq!(f.force_on_i, -f.force_on_j);
        let n = [phi.cos(), phi.sin()];
        let x = Vector::new(0.1 * n[0], 0.1 * n[1]);
        let m = f.torque_on_i + f.torque_on_j
            + cross(&(bi.position - x), &f.force_on_i) + cross(&(bj.position - x), &f.force_on_j);
        prop_assert!(m.abs() < 1e-9, "moment residual {m}");
        // R̄ = 0.08, A = 0.16, I = 2·0.08³/3
        prop_assert!((bond.area() - 0.16).abs() < 1e-15);
        let expected_sigma = -bond.normal_force / 0.16 + bond.moment.abs() * 0.08 / (2.0 * 0.08f64.powi(3) / 3.0);
        prop_assert!((bond.max_tensile_stress() - expected_sigma).abs() <= 1e-9 * (1.0 + expected_sigma.abs()));
    }

    /// The cell-grid broad phase finds exactly the pairs an O(N²) search finds, in a deterministic order.
    #[test]
    fn broad_phase_matches_all_pairs(
        pts in prop::collection::vec((0.0f64..5.0, 0.0f64..3.0, 0.05f64..0.25), 0..60),
    ) {
        let positions: Vec<Vector<f64>> = pts.iter().map(|p| Vector::new(p.0, p.1)).collect();
        let radii: Vec<f64> = pts.iter().map(|p| p.2).collect();
        let margin = 0.01;
        let grid = CellGrid::covering(lbdem_kernels::math::vector(0.0, 0.0), lbdem_kernels::math::vector(5.0, 3.0), 2.0 * 0.25 + margin, 64).unwrap();
        let (start_len, order_len) = cell_grid_scratch_len(&grid, positions.len());
        let mut start = vec![0; start_len];
        let mut order = vec![0; order_len];
        build_cell_grid(&grid, &positions, &mut start, &mut order).unwrap();
        let mut pairs = vec![[0, 0]; 4000];
        let count = candidate_pairs(&grid, &positions, &radii, margin, &start, &order, &mut pairs).unwrap();
        prop_assert_eq!(count.found, count.stored);
        let got = pairs[..count.stored].to_vec();
        let mut again = vec![[0, 0]; 4000];
        let count2 = candidate_pairs(&grid, &positions, &radii, margin, &start, &order, &mut again).unwrap();
        prop_assert_eq!(&again[..count2.stored], &got[..]);
        prop_assert!(got.windows(2).all(|w| w[0] < w[1]), "sorted, no duplicates");
        let mut expected = Vec::new();
        for i in 0..positions.len() {
            for j in i + 1..positions.len() {
                let d = positions[j] - positions[i];
                let reach = radii[i] + radii[j] + margin;
                if d[0] * d[0] + d[1] * d[1] < reach * reach {
                    expected.push([i, j]);
                }
            }
        }
        prop_assert_eq!(&got, &expected);
        // A too-small output buffer still counts every pair.
        let mut small = [[0, 0]; 1];
        let c3 = candidate_pairs(&grid, &positions, &radii, margin, &start, &order, &mut small).unwrap();
        prop_assert_eq!(c3.found, count.found);
        prop_assert_eq!(c3.stored, count.found.min(1));
        if c3.stored == 1 {
            prop_assert_eq!(small[0], got[0], "a short buffer keeps the lexicographically first pairs");
        }
    }
}

/// The grid pass of `candidate_pairs` over a grid covering [0, 6] × [0, 4] (positions outside are clamped).
fn grid_pass(positions: &[Vector<f64>], radii: &[f64], margin: f64) -> Vec<[usize; 2]> {
    let r_max = radii.iter().fold(0.0f64, |a, &b| a.max(b));
    let grid = CellGrid::covering(
        lbdem_kernels::math::vector(0.0, 0.0),
        lbdem_kernels::math::vector(6.0, 4.0),
        2.0 * r_max + margin,
        64,
    )
    .unwrap();
    let (start_len, order_len) = cell_grid_scratch_len(&grid, positions.len());
    let mut start = vec![0; start_len];
    let mut order = vec![0; order_len];
    build_cell_grid(&grid, positions, &mut start, &mut order).unwrap();
    let mut pairs = vec![[0, 0]; 4000];
    let count =
        candidate_pairs(&grid, positions, radii, margin, &start, &order, &mut pairs).unwrap();
    assert_eq!(count.found, count.stored);
    pairs.truncate(count.stored);
    pairs
}

proptest! {
    #![proptest_config(config(256))]

    /// The driver's Verlet list: the grid pass within margin + skin, later filtered by `filter_candidate_pairs`
    /// after every particle moved by up to `move` and grew by up to `grow` with move + grow ≤ 0.4 skin (the
    /// driver's `VERLET_MOVE`), gives exactly the grid pass at the new positions and radii, in the same order.
    /// Moves are drawn in direction and length, so pairs cross the margin in both directions.
    #[test]
    fn verlet_filter_equals_the_grid_pass(
        pts in prop::collection::vec(
            (0.5f64..5.5, 0.5f64..3.5, 0.05f64..0.25, 0.0f64..std::f64::consts::TAU, 0.0f64..1.0, 0.0f64..1.0),
            0..70,
        ),
        skin_fraction in 0.05f64..1.0,
    ) {
        let margin = 0.01;
        let positions: Vec<Vector<f64>> = pts.iter().map(|p| Vector::new(p.0, p.1)).collect();
        let radii: Vec<f64> = pts.iter().map(|p| p.2).collect();
        let skin = skin_fraction * 0.05;
        let verlet = grid_pass(&positions, &radii, margin + skin);
        let limit = 0.4 * skin;
        let moved: Vec<Vector<f64>> = pts.iter().map(|p| {
            let r = limit * p.4 * (1.0 - p.5);
            Vector::new(p.0 + r * p.3.cos(), p.1 + r * p.3.sin())
        }).collect();
        let grown: Vec<f64> = pts.iter().map(|p| p.2 + limit * p.4 * p.5).collect();
        let expected = grid_pass(&moved, &grown, margin);
        let mut got = vec![[0, 0]; 4000];
        let count = filter_candidate_pairs(&moved, &grown, margin, &verlet, &mut got).unwrap();
        prop_assert_eq!(count.found, count.stored);
        prop_assert_eq!(&got[..count.stored], &expected[..]);
        // A too-small output buffer still counts every pair and keeps the first.
        let mut small = [[0, 0]; 1];
        let c = filter_candidate_pairs(&moved, &grown, margin, &verlet, &mut small).unwrap();
        prop_assert_eq!(c.found, expected.len());
        prop_assert_eq!(c.stored, expected.len().min(1));
        if c.stored == 1 {
            prop_assert_eq!(small[0], expected[0]);
        }
        // Mismatched radii are refused.
        prop_assert!(filter_candidate_pairs(&moved, &grown[..grown.len().saturating_sub(1)], margin, &verlet, &mut small).is_err() || grown.is_empty());
    }
}

proptest! {
    #![proptest_config(config(64))]

    /// Contact history survives exactly for the pairs present in both steps; new pairs start at zero.
    #[test]
    fn contact_history_is_carried_for_persisting_pairs(
        before in prop::collection::btree_set((0usize..8, 0usize..8), 0..20),
        after in prop::collection::btree_set((0usize..8, 0usize..8), 0..20),
    ) {
        let prev: Vec<[usize; 2]> = before.iter().map(|&(a, b)| [a, b]).collect();
        let next: Vec<[usize; 2]> = after.iter().map(|&(a, b)| [a, b]).collect();
        let prev_values: Vec<f64> = (0..prev.len()).map(|k| k as f64 + 1.5).collect();
        let mut values = vec![f64::NAN; next.len()];
        let carried = carry_contact_history(&prev, &prev_values, &next, &mut values).unwrap();
        let mut expected_carried = 0;
        for (pair, v) in next.iter().zip(&values) {
            match prev.iter().position(|p| p == pair) {
                Some(k) => {
                    prop_assert_eq!(*v, prev_values[k]);
                    expected_carried += 1;
                }
                None => prop_assert_eq!(*v, 0.0),
            }
        }
        prop_assert_eq!(carried, expected_carried);
    }
}

fn finite(c: &Contact<f64>) -> bool {
    c.overlap.is_finite()
        && c.normal
            .iter()
            .chain(&c.point)
            .chain(&c.point_i)
            .chain(&c.point_j)
            .all(|x| x.is_finite())
        && (c.normal[0].hypot(c.normal[1]) - 1.0).abs() < 1e-12
}

#[test]
fn no_nan_for_coincident_centres() {
    for k in 0..16 {
        let t = k as f64 * 0.4;
        let a = Placed::new(lbdem_kernels::math::vector(1.0, 2.0), t, 1.0, 0.5);
        let b = Placed::new(lbdem_kernels::math::vector(1.0, 2.0), -t, 0.7, 0.35);
        let c = ellipse_ellipse(&a, &b);
        assert!(finite(&c));
        // With coincident centres the least translation is along the smaller total support: at least the sum
        // of the minor semi-axes, at most the sum of the major ones.
        assert!(
            c.overlap >= 0.85 - 1e-12 && c.overlap <= 1.7 + 1e-12,
            "{}",
            c.overlap
        );
        let d = ellipse_disc(&a, lbdem_kernels::math::vector(1.0, 2.0), 0.3);
        assert!(
            finite(&d) && (d.overlap - 0.8).abs() < 1e-12,
            "{}",
            d.overlap
        );
        // Coaxial equal ellipses: exactly 2b.
        let e = ellipse_ellipse(
            &a,
            &Placed::new(lbdem_kernels::math::vector(1.0, 2.0), t, 1.0, 0.5),
        );
        assert!((e.overlap - 1.0).abs() < 1e-12, "{}", e.overlap);
    }
    let c = disc_disc(
        lbdem_kernels::math::vector(0.0, 0.0),
        1.0,
        lbdem_kernels::math::vector(0.0, 0.0),
        0.5,
    );
    assert!(finite(&c) && c.overlap == 1.5 && c.normal == lbdem_kernels::math::vector(1.0, 0.0));
    let e = ellipse_ellipse(
        &Placed::new(lbdem_kernels::math::Vector::zeros(), 0.0, 0.5, 0.5),
        &Placed::new(lbdem_kernels::math::Vector::zeros(), 0.0, 0.5, 0.5),
    );
    assert!(finite(&e) && (e.overlap - 1.0).abs() < 1e-15);
    // The force law stays finite too.
    let law = ContactLaw::elastic(1e5, 6e5, 0.5);
    let mut s = 0.0;
    let p = BodyState::fixed(lbdem_kernels::math::vector(0.0, 0.0));
    let f = linear_contact_force(&law, &c, &p, &p, &mut s, 1e-5);
    assert!(f.force_on_j.iter().all(|x| x.is_finite()) && f.force_on_j[0] > 0.0);
}

#[test]
fn touching_exactly_gives_no_force() {
    let law = ContactLaw::elastic(1e5, 6e5, 0.5);
    // Discs at exactly r1 + r2 (representable: 0.5 + 0.25 = 0.75).
    let pi = Particle::disc(lbdem_kernels::math::vector(0.0, 0.0), 0.5, 1.0);
    let mut pj = Particle::disc(lbdem_kernels::math::vector(0.75, 0.0), 0.25, 1.0);
    pj.velocity = lbdem_kernels::math::vector(-1.0, 3.0);
    let c = closest_approach(&pi, &pj);
    assert_eq!(c.overlap, 0.0);
    assert!(!c.is_active() && particle_contact(&pi, &pj).is_none());
    let mut shear = 7.0;
    let f = linear_contact_force(
        &law,
        &c,
        &BodyState::of(&pi),
        &BodyState::of(&pj),
        &mut shear,
        1e-5,
    );
    assert_eq!(f.force_on_j, lbdem_kernels::math::vector(0.0, 0.0));
    assert_eq!(shear, 0.0, "the history of an ended contact is dropped");
    // An ellipse resting exactly on a wall: overlap 0 up to rounding, finite.
    let e = Placed::new(lbdem_kernels::math::vector(0.0, 0.5), 0.0, 1.0, 0.5);
    let w = Wall {
        point: lbdem_kernels::math::vector(0.0, 0.0),
        normal: lbdem_kernels::math::vector(0.0, 1.0),
    };
    let c = ellipse_wall(&e, &w);
    assert!(finite(&c) && c.overlap.abs() < 1e-15);
    // Two ellipses tip to tip along x: a1 + a2 apart.
    let c = ellipse_ellipse(
        &Placed::new(lbdem_kernels::math::vector(0.0, 0.0), 0.0, 1.0, 0.5),
        &Placed::new(lbdem_kernels::math::vector(1.75, 0.0), 0.0, 0.75, 0.5),
    );
    assert!(finite(&c) && c.overlap.abs() < 1e-12, "{}", c.overlap);
}

#[test]
fn parallel_bond_breaks_exactly_at_strength() {
    // R̄ = 0.5 ⇒ A = 1, so σ̄ = −F̄_n exactly when M̄ = 0 and τ̄ = |F̄_s|.
    let fresh = ParallelBond::new(0.5, 0.5, 1.0, 1.0, 1.0, 10.0, 20.0);
    assert_eq!(fresh.area(), 1.0);
    let i = BodyState::fixed(lbdem_kernels::math::vector(0.0, 0.0));
    let j = BodyState::fixed(lbdem_kernels::math::vector(1.0, 0.0));
    for (fnormal, fshear, expect) in [
        (-10.0, 0.0, Some(BreakMode::Tension)),
        (-9.999999999999998, 0.0, None),
        (0.0, 20.0, Some(BreakMode::Shear)),
        (0.0, -19.999999999999996, None),
        (5.0, -20.0, Some(BreakMode::Shear)),
    ] {
        let mut bond = ParallelBond {
            normal_force: fnormal,
            shear_force: fshear,
            ..fresh
        };
        let f = parallel_bond_force(&mut bond, &i, 0.5, &j, 0.5, 0.0);
        assert_eq!(
            f.broke.map(|b| b.mode),
            expect,
            "F_n = {fnormal}, F_s = {fshear}"
        );
        if expect.is_some() {
            assert_eq!(f.force_on_j, lbdem_kernels::math::vector(0.0, 0.0));
            assert!(!bond.intact);
            let r = f.broke.unwrap();
            assert_eq!(r.position, lbdem_kernels::math::vector(0.5, 0.0));
            assert_eq!(r.orientation, 0.0);
            let after = parallel_bond_force(
                &mut bond,
                &i,
                0.5,
                &BodyState {
                    velocity: lbdem_kernels::math::vector(5.0, 1.0),
                    ..j
                },
                0.5,
                1.0,
            );
            assert!(
                after.broke.is_none()
                    && after.force_on_j == lbdem_kernels::math::vector(0.0, 0.0)
                    && after.torque_on_j == 0.0
            );
        } else {
            assert_eq!(f.force_on_j, lbdem_kernels::math::vector(fnormal, fshear));
        }
    }
    // Bending: σ̄ = |M̄| R̄/I = |M̄|·0.5/(1/12) = 6|M̄|: breaks in tension at |M̄| = 10/6.
    let mut bent = ParallelBond {
        moment: 10.0 / 6.0 * 1.0000001,
        ..fresh
    };
    assert_eq!(
        parallel_bond_force(&mut bent, &i, 0.5, &j, 0.5, 0.0)
            .broke
            .map(|b| b.mode),
        Some(BreakMode::Tension)
    );
    // Opening the bond at speed v for a time t builds F̄_n = −k̄_n A v t.
    let mut bond = fresh;
    let opening = BodyState {
        velocity: lbdem_kernels::math::vector(2.0, 0.0),
        ..j
    };
    let f = parallel_bond_force(&mut bond, &i, 0.5, &opening, 0.5, 0.25);
    assert_eq!(bond.normal_force, -0.5);
    assert_eq!(f.force_on_j, lbdem_kernels::math::vector(-0.5, 0.0));
}

/// No missed and no phantom contacts, at any orientation: for ellipses of aspect ratio 0.5 (ch. 6.6) at 8 × 8
/// orientations and 16 approach directions, find by bisection the centre distance r* where the kernel's
/// overlap changes sign, then check with the independent point-inclusion oracle that the boundaries intersect
/// at r*(1 − 1e-4) and are apart at r*(1 + 1e-4). A relative change of 1e-4 in r* ≥ 0.9 moves the surfaces
/// by Δr (n·dir) along the normal, and the test asserts n·dir > 0.5 at first touch (so ≥ 4.5e-5), over thirty
/// times the oracle's sampling error (1.2e-6 at n = 2048); the overlap lens (chord ≈ 2√(2ρδ) ≥ 0.01) spans
/// several sample spacings (2π/2048 ≈ 3e-3).
#[test]
fn ellipse_contacts_are_neither_missed_nor_phantom() {
    let n = 2048;
    let mut checked = 0;
    let mut min_approach: f64 = 1.0;
    for i in 0..8 {
        for j in 0..8 {
            for k in 0..16 {
                let (t1, t2) = (i as f64 * 0.39, j as f64 * 0.41 + 0.1);
                let phi = k as f64 * std::f64::consts::TAU / 16.0 + 0.05;
                let dir = [phi.cos(), phi.sin()];
                let at = |r: f64| {
                    let e1 = oracle::Ellipse {
                        centre: [0.0, 0.0],
                        a: 1.0,
                        b: 0.5,
                        angle: t1,
                    };
                    let e2 = oracle::Ellipse {
                        centre: [r * dir[0], r * dir[1]],
                        a: 0.8,
                        b: 0.4,
                        angle: t2,
                    };
                    (e1, e2)
                };
                let overlap = |r: f64| {
                    let (e1, e2) = at(r);
                    ellipse_ellipse(&placed(&e1), &placed(&e2)).overlap
                };
                // The touching distance lies between b1 + b2 = 0.9 and a1 + a2 = 1.8.
                let (mut lo, mut hi) = (0.85, 1.85);
                assert!(overlap(lo) > 0.0 && overlap(hi) < 0.0);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if overlap(mid) > 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                let r_star = 0.5 * (lo + hi);
                let (e1, e2) = at(r_star);
                let c = ellipse_ellipse(&placed(&e1), &placed(&e2));
                // d(overlap)/dr = −n·dir: the surfaces move by Δr (n·dir) along the normal.
                let approach = c.normal[0] * dir[0] + c.normal[1] * dir[1];
                assert!(approach > 0.5, "grazing approach {approach}");
                min_approach = min_approach.min(approach);
                let (a_in, b_in) = at(r_star * (1.0 - 1e-4));
                let (a_out, b_out) = at(r_star * (1.0 + 1e-4));
                assert!(
                    oracle::boundaries_intersect(&a_in, &b_in, n),
                    "missed contact at {t1}, {t2}, {phi}"
                );
                assert!(
                    !oracle::boundaries_intersect(&a_out, &b_out, n),
                    "phantom contact at {t1}, {t2}, {phi}"
                );
                // Symmetry of detection: the swapped pair agrees on the sign just inside and just outside.
                assert!(ellipse_ellipse(&placed(&b_in), &placed(&a_in)).overlap > 0.0);
                assert!(ellipse_ellipse(&placed(&b_out), &placed(&a_out)).overlap < 0.0);
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 1024);
    eprintln!("smallest n·dir at first touch: {min_approach:.3}");
}

#[test]
fn wall_segment_is_its_half_plane_within_its_extent() {
    use lbdem_kernels::dem::contact::{wall_contact, wall_segment_contact};
    use lbdem_kernels::dem::shape::WallSegment;
    // A platen face from (2, 1) to (0, 1): the particles live below it (normal (0, −1)).
    let seg = WallSegment {
        start: lbdem_kernels::math::vector(2.0, 1.0),
        end: lbdem_kernels::math::vector(0.0, 1.0),
    };
    let (wall, length) = seg.wall();
    assert_eq!(wall.normal, lbdem_kernels::math::vector(0.0, -1.0));
    assert_eq!(length, 2.0);
    for (x, inside) in [
        (-0.05, false),
        (0.0, true),
        (0.7, true),
        (1.99, true),
        (2.0, true),
        (2.01, false),
    ] {
        let e = Particle::<f64>::ellipse(
            lbdem_kernels::math::vector(x, 1.0 - 0.05 + 1e-3),
            0.0,
            0.1,
            0.05,
            1.0,
        );
        let full = wall_contact(&e, &wall).expect("overlaps the supporting line");
        assert!((full.overlap - 1e-3).abs() < 1e-12);
        match wall_segment_contact(&e, &seg) {
            Some(c) => {
                assert!(inside, "x = {x}: contact beyond the end");
                assert_eq!(c, full);
            }
            None => assert!(!inside, "x = {x}: contact missed on the face"),
        }
    }
    // Apart from the face: nothing, wherever along it.
    let far = Particle::disc(lbdem_kernels::math::vector(1.0, 0.5), 0.1, 1.0);
    assert!(wall_segment_contact(&far, &seg).is_none());
    // A degenerate (zero-length) segment never panics.
    let point = WallSegment {
        start: lbdem_kernels::math::vector(0.0, 0.0),
        end: lbdem_kernels::math::vector(0.0, 0.0),
    };
    let _ = wall_segment_contact(&far, &point);
}

proptest! {
    #![proptest_config(config(64))]

    /// Rigid-body motion of a bonded pair (translation U plus rotation Ω about any point) loads neither bond
    /// nor contact: the relative velocity at the bond point and the relative rotation vanish.
    #[test]
    fn rigid_motion_loads_no_parallel_bond_or_contact(
        u in prop::array::uniform2(-2.0f64..2.0), omega in -10.0f64..10.0, phi in 0.0f64..6.3,
        pivot in prop::array::uniform2(-1.0f64..1.0),
    ) {
        let ci = [0.2, -0.1];
        let cj = [0.2 + 0.19 * phi.cos(), -0.1 + 0.19 * phi.sin()];
        let rigid = |c: [f64; 2]| BodyState {
            position: lbdem_kernels::math::Vector::from(c),
            velocity: lbdem_kernels::math::vector(u[0] - omega * (c[1] - pivot[1]), u[1] + omega * (c[0] - pivot[0])),
            angular_velocity: omega,
        };
        let mut bond = ParallelBond::new(0.1, 0.1, 1.0, 1e6, 4e5, 1e9, 1e9);
        for _ in 0..10 {
            let f = parallel_bond_force(&mut bond, &rigid(ci), 0.1, &rigid(cj), 0.1, 1e-3);
            prop_assert!(f.force_on_j.iter().all(|x| x.abs() < 1e-9) && f.torque_on_j.abs() < 1e-9);
        }
        let law = ContactLaw::elastic(1e3, 6e2, 0.5);
        let c = disc_disc(lbdem_kernels::math::Vector::from(ci), 0.1, lbdem_kernels::math::Vector::from(cj), 0.1);
        let mut shear = 0.0;
        let f = linear_contact_force(&law, &c, &rigid(ci), &rigid(cj), &mut shear, 1e-3);
        prop_assert!(shear.abs() < 1e-12);
        // Only the elastic normal force k_n δ remains.
        prop_assert!((f.normal_force - 1e3 * 0.01).abs() < 1e-9);
    }
}

#[test]
fn assembly_passes_refuse_bad_input_without_panicking() {
    use lbdem_kernels::dem::assembly::{
        add_pair_forces, add_wall_contact_forces, integrate_all, pair_contacts, wall_loads,
        AssemblyError, ContactModel, WallBody, WallContactForce, WallLoad,
    };
    use lbdem_kernels::dem::law::ContactForce;
    let model = ContactModel {
        normal_stiffness: 1e5,
        shear_stiffness: 6e5,
        friction: 0.5,
        restitution: 1.0,
        no_tension: true,
    };
    let mut ps = [
        Particle::disc(lbdem_kernels::math::vector(0.0, 0.0), 0.1, 1.0),
        Particle::disc(lbdem_kernels::math::vector(0.15, 0.0), 0.1, 1.0),
    ];
    let (mut f, mut t) = ([Vector::<f64>::zeros(); 2], [0.0f64; 2]);
    let mut shear = [0.0; 1];
    let mut slots = [ContactForce::zero(); 1];
    for bad in [[0, 2], [1, 1]] {
        assert_eq!(
            pair_contacts(&model, &ps, &[bad], &mut shear, 1e-5, &mut slots),
            Err(AssemblyError::BadPair)
        );
    }
    assert_eq!(
        pair_contacts(&model, &ps, &[[0, 1]], &mut [], 1e-5, &mut slots),
        Err(AssemblyError::BufferLength)
    );
    assert_eq!(
        pair_contacts(&model, &ps, &[[0, 1]], &mut shear, 1e-5, &mut slots),
        Ok(())
    );
    assert_eq!(
        add_pair_forces(&[[0, 1]], &slots, &mut f, &mut t).map(|s| (s.active, s.loaded)),
        Ok((1, 1))
    );
    // Newton's third law survives the accumulation; the overlap 0.05 gives k_n δ = 5000.
    assert_eq!(f[0], lbdem_kernels::math::vector(-f[1][0], -f[1][1]));
    assert!((f[1][0] - 5000.0).abs() < 1e-9 && f[1][1] == 0.0);
    let walls = [WallBody::fixed(Wall {
        point: lbdem_kernels::math::vector(0.0, -0.05),
        normal: lbdem_kernels::math::vector(0.0, 1.0),
    })];
    let mut on_walls = [WallContactForce::none(); 2];
    assert_eq!(
        add_wall_contact_forces(
            &model,
            &ps,
            &walls,
            &mut [0.0; 1],
            1e-5,
            &mut f,
            &mut t,
            &mut on_walls
        ),
        Err(AssemblyError::BufferLength)
    );
    let mut wall_shear = [0.0; 2];
    assert_eq!(
        add_wall_contact_forces(
            &model,
            &ps,
            &walls,
            &mut wall_shear,
            1e-5,
            &mut f,
            &mut t,
            &mut on_walls
        ),
        Ok(())
    );
    let mut loads = [WallLoad::default(); 1];
    assert_eq!(wall_loads(&on_walls, &mut loads), Ok(()));
    assert_eq!(loads[0].contacts, 2);
    // The particles push the floor down with 2 k_n δ.
    assert!((loads[0].force[1] + 2.0 * 1e5 * 0.05).abs() < 1e-9);
    assert_eq!(
        integrate_all(
            &mut ps,
            &f[..1],
            &t,
            &[false; 2],
            lbdem_kernels::math::Vector::zeros(),
            0.0,
            1e-5
        ),
        Err(AssemblyError::BufferLength)
    );
}

#[test]
fn contact_model_critical_step_is_the_pfc_estimate() {
    use lbdem_kernels::dem::assembly::ContactModel;
    let model = ContactModel {
        normal_stiffness: 1e5f64,
        shear_stiffness: 6e5,
        friction: 0.5,
        restitution: 0.5,
        no_tension: true,
    };
    let small = Particle::disc(lbdem_kernels::math::vector(0.0, 0.0), 0.07, 2.6);
    let large = Particle::ellipse(lbdem_kernels::math::vector(0.0, 0.0), 0.3, 0.11, 0.055, 2.6);
    let dt = model.critical_time_step(&[large, small], 4.0);
    // k = max(k_n, k_s) = 6e5, z = 4. Disc: rotation √(I/(z k_s r²)) = √(m/(2 z k_s)), below its translation
    // √(m/(z k)). Ellipse (a = 0.11, b/a = 0.5): I = m(a² + b²)/4 = 0.3125 m a² with lever arm a, so its rotation
    // limit √(0.3125 m/(z k_s)) is the smallest (8.02e-5 s against 9.13e-5 s for the disc).
    let disc_rot = (small.mass / (2.0 * 4.0 * 6e5)).sqrt();
    let ellipse_rot = (large.moment_of_inertia / (4.0 * 6e5 * 0.11 * 0.11)).sqrt();
    assert!(ellipse_rot < disc_rot);
    let expected = ellipse_rot;
    assert!(
        (dt - expected).abs() < 1e-12 * expected,
        "{dt} vs {expected}"
    );
    assert_eq!(model.critical_time_step(&[], 4.0), f64::INFINITY);
    // A soft shear spring makes translation the limit: √(m/(z k)) with k = max(k_n, k_s) = k_n, below the disc's
    // rotation limit √(m/(2 z k_s)).
    let soft_shear = ContactModel {
        shear_stiffness: 1e3,
        ..model
    };
    let dt = soft_shear.critical_time_step(&[small], 4.0);
    let translation = (small.mass / (4.0 * 1e5)).sqrt();
    assert!((small.mass / (2.0 * 4.0 * 1e3)).sqrt() > translation);
    assert!(
        (dt - translation).abs() < 1e-12 * translation,
        "{dt} vs {translation}"
    );
}

/// The separating-axis gap s(θ) = n·d − h₁(n) − h₂(n) along n = (cos θ, sin θ), d = c₂ − c₁, with the textbook
/// support function of an ellipse, h(n) = √(a²(n·u)² + b²(n·v)²) (u, v its axes): independent of the kernel's.
fn textbook_gap(e1: &oracle::Ellipse, e2: &oracle::Ellipse, theta: f64) -> f64 {
    let n = [theta.cos(), theta.sin()];
    let h = |e: &oracle::Ellipse| {
        let (s, c) = e.angle.sin_cos();
        let (nu, nv) = (n[0] * c + n[1] * s, -n[0] * s + n[1] * c);
        ((e.a * nu).powi(2) + (e.b * nv).powi(2)).sqrt()
    };
    let d = [e2.centre[0] - e1.centre[0], e2.centre[1] - e1.centre[1]];
    n[0] * d[0] + n[1] * d[1] - h(e1) - h(e2)
}

proptest! {
    #![proptest_config(config(256))]

    /// Elongated pairs (aspect down to 1/20, where the gap s(θ) has sharp peaks between the 32 samples and an
    /// unsafeguarded Newton step leaves its bracket): the kernel's overlap is −max s(θ). Checked against a dense
    /// scan of 8192 directions of the textbook gap: the kernel's maximum is at least the scan's (to roundoff) and
    /// above it by no more than the scan's own error, ½ max|s''| (π/8192)², with |s''| ≤ |d| + Σ (a²/b + a) (the
    /// support function's h + h'' is the radius of curvature, at most a²/b).
    #[test]
    fn ellipse_ellipse_finds_the_maximum_gap_of_elongated_pairs(
        b1 in 0.05f64..0.4, a2 in 0.3f64..1.0, r2 in 0.05f64..0.4,
        t1 in 0.0f64..std::f64::consts::TAU, t2 in 0.0f64..std::f64::consts::TAU,
        phi in 0.0f64..std::f64::consts::TAU, dist in 0.0f64..2.5,
    ) {
        let e1 = oracle::Ellipse { centre: [0.3, -0.2], a: 1.0, b: b1, angle: t1 };
        let e2 = oracle::Ellipse {
            centre: [0.3 + dist * phi.cos(), -0.2 + dist * phi.sin()],
            a: a2,
            b: a2 * r2,
            angle: t2,
        };
        let c = ellipse_ellipse(&placed(&e1), &placed(&e2));
        let kernel_max = -c.overlap;
        let n = 8192;
        let scan = (0..n)
            .map(|k| textbook_gap(&e1, &e2, std::f64::consts::TAU * k as f64 / n as f64))
            .fold(f64::NEG_INFINITY, f64::max);
        // Roundoff: a few ulp of the terms (|d| + a₁ + a₂ ≤ 4.5).
        prop_assert!(kernel_max >= scan - 1e-13, "kernel max {kernel_max} below the scan's {scan}");
        let curvature = dist + (1.0 / b1 + 1.0) + (a2 / r2 + a2);
        let bound = 0.5 * curvature * (std::f64::consts::PI / n as f64).powi(2);
        prop_assert!(kernel_max <= scan + bound, "kernel max {kernel_max} above the scan's {scan} + {bound}");
        // The normal it reports is where the gap takes that value.
        let theta = c.normal[1].atan2(c.normal[0]);
        prop_assert!((textbook_gap(&e1, &e2, theta) - kernel_max).abs() <= 1e-12);
    }
}

/// `ContactModel::law` hands every setting of the model to the pair's law: stiffnesses, friction, the no-tension
/// switch either way, and the dashpot of restitution e for the pair's effective mass (a wall, infinite mass,
/// leaves the grain's own mass).
#[test]
fn contact_model_law_carries_every_setting() {
    use lbdem_kernels::dem::assembly::ContactModel;
    use lbdem_kernels::dem::law::damping_ratio_from_restitution;
    for no_tension in [false, true] {
        let model = ContactModel {
            normal_stiffness: 1e5f64,
            shear_stiffness: 2e5,
            friction: 0.3,
            restitution: 0.5,
            no_tension,
        };
        let law = model.law(2.0, f64::INFINITY);
        assert_eq!(law.no_tension, no_tension);
        assert_eq!(
            (law.normal_stiffness, law.shear_stiffness, law.friction),
            (1e5, 2e5, 0.3)
        );
        let c = 2.0 * damping_ratio_from_restitution(0.5) * (2.0f64 * 1e5).sqrt();
        assert!(
            (law.normal_damping - c).abs() <= 1e-12 * c,
            "{} vs {c}",
            law.normal_damping
        );
    }
}
