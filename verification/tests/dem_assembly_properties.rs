//! The whole-assembly DEM passes (`lbdem_kernels::dem::assembly`) for every input: on random clusters of
//! overlapping discs and ellipses with random velocities, the pair pass adds internal forces only (they sum to
//! zero and their moments about any point balance), counts exactly the active contacts, and adds to what the
//! buffers held; the wall pass's reactions are the forces the walls put on the particles, it counts the
//! contacts and zeroes the history of the pairs that are apart; `integrate_all` is the per-particle step; and
//! every buffer that is too short is refused (never a panic), while exact and longer buffers are accepted.
//!
//! **Tolerances.** Sums of n contact forces of size ≤ F carry at most n ulp of n F, so balances are checked
//! within 64 n ε Σ|term| (Σ|term| the sum of the magnitudes added).
use lbdem_kernels::dem::assembly::{
    add_pair_contact_forces, add_wall_contact_forces, integrate_all, AssemblyError, ContactModel,
};
use lbdem_kernels::dem::contact::{closest_approach, wall_contact};
use lbdem_kernels::dem::integrate::central_difference_step;
use lbdem_kernels::dem::shape::{Particle, Wall};
use lbdem_verification::proptest_cases;
use proptest::prelude::*;

fn config(default: u32) -> ProptestConfig {
    ProptestConfig::with_cases(proptest_cases(default))
}

fn model(restitution: f64) -> ContactModel<f64> {
    ContactModel {
        normal_stiffness: 1e5,
        shear_stiffness: 4e4,
        friction: 0.5,
        restitution,
        no_tension: true,
    }
}

/// A particle in the unit box: a disc or an ellipse of size 0.1–0.3, moving and spinning.
fn particle() -> impl Strategy<Value = Particle<f64>> {
    (
        [0.0f64..1.0, 0.0f64..1.0],
        0.1f64..0.3,
        0.4f64..=1.0,
        -3.2f64..3.2,
        any::<bool>(),
        [-1.0f64..1.0, -1.0f64..1.0],
        -5.0f64..5.0,
    )
        .prop_map(|(x, a, aspect, angle, disc, v, w)| {
            let mut p = if disc {
                Particle::disc(x, a, 2.5)
            } else {
                Particle::ellipse(x, angle, a, a * aspect, 2.5)
            };
            p.velocity = v;
            p.angular_velocity = w;
            p
        })
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

proptest! {
    #![proptest_config(config(128))]

    /// Pair pass: the forces and torques added are internal (Σ F = 0, Σ (τ + x × F) = 0), the count is the
    /// number of active contacts, the buffers are added to, and a pair list given in another order gives the
    /// same totals.
    #[test]
    fn pair_forces_are_internal_and_counted(
        ps in prop::collection::vec(particle(), 2..8),
        start in prop::collection::vec(([-1.0f64..1.0, -1.0f64..1.0], -1.0f64..1.0), 8),
        restitution in prop_oneof![Just(1.0), 0.2f64..0.9],
    ) {
        let n = ps.len();
        let pairs: Vec<[usize; 2]> = (0..n).flat_map(|i| (i + 1..n).map(move |j| [i, j])).collect();
        let f0: Vec<[f64; 2]> = start[..n].iter().map(|s| s.0).collect();
        let t0: Vec<f64> = start[..n].iter().map(|s| s.1).collect();
        let (mut f, mut t) = (f0.clone(), t0.clone());
        let mut shear = vec![0.0; pairs.len()];
        let dt = 1e-5;
        let active = add_pair_contact_forces(&model(restitution), &ps, &pairs, &mut shear, dt, &mut f, &mut t)
            .expect("valid input");
        let expected = pairs.iter().filter(|&&[i, j]| closest_approach(&ps[i], &ps[j]).is_active()).count();
        prop_assert_eq!(active, expected);
        let (mut sum, mut moment, mut size) = ([0.0; 2], 0.0, 0.0);
        for k in 0..n {
            let df = [f[k][0] - f0[k][0], f[k][1] - f0[k][1]];
            let dt_k = t[k] - t0[k];
            sum[0] += df[0];
            sum[1] += df[1];
            moment += dt_k + cross(ps[k].position, df);
            size += df[0].abs() + df[1].abs() + dt_k.abs() + cross(ps[k].position, df).abs();
        }
        let tol = 64.0 * (n * n) as f64 * f64::EPSILON * size + 1e-300;
        prop_assert!(sum[0].abs() <= tol && sum[1].abs() <= tol, "Σ F = {sum:?} (tol {tol:e})");
        prop_assert!(moment.abs() <= tol, "Σ (τ + x × F) = {moment:e} (tol {tol:e})");
        if active == 0 {
            prop_assert_eq!((&f, &t), (&f0, &t0));
        }
        // The same pairs in reverse order: the same totals, to roundoff.
        let reversed: Vec<[usize; 2]> = pairs.iter().rev().copied().collect();
        let (mut f2, mut t2) = (f0.clone(), t0.clone());
        let mut shear2 = vec![0.0; pairs.len()];
        add_pair_contact_forces(&model(restitution), &ps, &reversed, &mut shear2, dt, &mut f2, &mut t2)
            .expect("valid input");
        for k in 0..n {
            prop_assert!((f2[k][0] - f[k][0]).abs() <= tol && (f2[k][1] - f[k][1]).abs() <= tol && (t2[k] - t[k]).abs() <= tol);
        }
        for (a, b) in shear.iter().zip(shear2.iter().rev()) {
            prop_assert_eq!(a.to_bits(), b.to_bits());
        }
    }

    /// Wall pass: the reaction of each wall is the force it puts on the particles, the count is the number of
    /// touching (particle, wall) pairs, and the history of every pair that does not touch is zeroed.
    #[test]
    fn wall_reactions_balance_the_wall_forces(
        ps in prop::collection::vec(particle(), 1..8),
        tilt in -0.3f64..0.3,
    ) {
        let walls = [
            Wall::from_angle([0.0, 0.15], std::f64::consts::FRAC_PI_2 + tilt),
            Wall::from_angle([0.15, 0.0], tilt),
            Wall::from_angle([0.85, 1.0], -std::f64::consts::FRAC_PI_2 + tilt),
        ];
        let n = ps.len();
        let (mut f, mut t) = (vec![[0.0; 2]; n], vec![0.0; n]);
        let mut shear = vec![7.0; n * walls.len()];
        let mut reaction = vec![[0.0; 2]; walls.len()];
        let active = add_wall_contact_forces(&model(0.5), &ps, &walls, &mut shear, 1e-5, &mut f, &mut t, &mut reaction)
            .expect("valid input");
        let mut touching = 0;
        for (i, p) in ps.iter().enumerate() {
            for (w, wall) in walls.iter().enumerate() {
                if wall_contact(p, wall).is_some() {
                    touching += 1;
                } else {
                    prop_assert_eq!(shear[i * walls.len() + w], 0.0, "history of apart pair ({}, {})", i, w);
                }
            }
        }
        prop_assert_eq!(active, touching);
        let total: [f64; 2] = f.iter().fold([0.0; 2], |s, v| [s[0] + v[0], s[1] + v[1]]);
        let reacted: [f64; 2] = reaction.iter().fold([0.0; 2], |s, v| [s[0] + v[0], s[1] + v[1]]);
        let size: f64 = f.iter().map(|v| v[0].abs() + v[1].abs()).sum();
        let tol = 64.0 * (n * walls.len()) as f64 * f64::EPSILON * size + 1e-300;
        for a in 0..2 {
            prop_assert!((total[a] - reacted[a]).abs() <= tol, "axis {a}: particles {total:?}, reactions {reacted:?}");
        }
    }

    /// `integrate_all` is the per-particle central-difference step (bitwise), with gravity and damping.
    #[test]
    fn integrate_all_is_the_particle_step(
        ps in prop::collection::vec(particle(), 0..6),
        loads in prop::collection::vec(([-10.0f64..10.0, -10.0f64..10.0], -1.0f64..1.0), 6),
        alpha in 0.0f64..0.8,
    ) {
        let n = ps.len();
        let f: Vec<[f64; 2]> = loads[..n].iter().map(|l| l.0).collect();
        let t: Vec<f64> = loads[..n].iter().map(|l| l.1).collect();
        let (g, dt) = ([0.0, -9.81], 1e-4);
        let mut all = ps.clone();
        integrate_all(&mut all, &f, &t, g, alpha, dt).expect("valid input");
        for (k, mut p) in ps.into_iter().enumerate() {
            central_difference_step(&mut p, f[k], t[k], g, alpha, dt);
            prop_assert_eq!(p, all[k]);
        }
    }
}

/// Every buffer one entry too short is refused with `BufferLength` (or `BadPair` for a bad index) before
/// anything is written; buffers of the exact length or longer are accepted.
#[test]
fn every_short_buffer_is_refused() {
    let ps = [
        Particle::disc([0.0, 0.0], 0.1, 1.0),
        Particle::disc([0.15, 0.0], 0.1, 1.0),
        Particle::disc([0.3, 0.0], 0.1, 1.0),
    ];
    let pairs = [[0, 1], [1, 2]];
    let m = model(0.5);
    let dt = 1e-5;
    let pair = |shear: usize, force: usize, torque: usize| {
        let (mut s, mut f, mut t) = (vec![0.0; shear], vec![[0.0; 2]; force], vec![0.0; torque]);
        let r = add_pair_contact_forces(&m, &ps, &pairs, &mut s, dt, &mut f, &mut t);
        (
            r,
            f.iter().all(|v| *v == [0.0; 2]) && t.iter().all(|v| *v == 0.0),
        )
    };
    for (s, f, t) in [(1, 3, 3), (2, 2, 3), (2, 3, 2)] {
        assert_eq!(
            pair(s, f, t),
            (Err(AssemblyError::BufferLength), true),
            "{s} {f} {t}"
        );
    }
    assert_eq!(pair(2, 3, 3).0, Ok(2));
    assert_eq!(pair(3, 4, 4).0, Ok(2));
    for bad in [[0, 3], [3, 0], [2, 2]] {
        let (mut s, mut f, mut t) = (vec![0.0; 1], vec![[0.0; 2]; 3], vec![0.0; 3]);
        assert_eq!(
            add_pair_contact_forces(&m, &ps, &[bad], &mut s, dt, &mut f, &mut t),
            Err(AssemblyError::BadPair)
        );
    }

    let walls = [
        Wall::from_angle([0.0, -0.05], std::f64::consts::FRAC_PI_2),
        Wall::from_angle([-0.05, 0.0], 0.0),
    ];
    let wall = |shear: usize, force: usize, torque: usize, reaction: usize| {
        let (mut s, mut f, mut t, mut r) = (
            vec![0.0; shear],
            vec![[0.0; 2]; force],
            vec![0.0; torque],
            vec![[0.0; 2]; reaction],
        );
        let out = add_wall_contact_forces(&m, &ps, &walls, &mut s, dt, &mut f, &mut t, &mut r);
        (
            out,
            f.iter().all(|v| *v == [0.0; 2]) && r.iter().all(|v| *v == [0.0; 2]),
        )
    };
    for (s, f, t, r) in [(5, 3, 3, 2), (6, 2, 3, 2), (6, 3, 2, 2), (6, 3, 3, 1)] {
        assert_eq!(
            wall(s, f, t, r),
            (Err(AssemblyError::BufferLength), true),
            "{s} {f} {t} {r}"
        );
    }
    // Particle 0 touches both walls, particles 1 and 2 the floor: four contacts.
    assert_eq!(wall(6, 3, 3, 2).0, Ok(4));
    assert_eq!(wall(7, 4, 4, 3).0, Ok(4));

    let mut moved = ps;
    let (f, t) = ([[1.0, 0.0]; 3], [0.5; 3]);
    assert_eq!(
        integrate_all(&mut moved, &f[..2], &t, [0.0; 2], 0.0, dt),
        Err(AssemblyError::BufferLength)
    );
    assert_eq!(
        integrate_all(&mut moved, &f, &t[..2], [0.0; 2], 0.0, dt),
        Err(AssemblyError::BufferLength)
    );
    assert_eq!(moved, ps, "nothing moved on error");
    assert_eq!(integrate_all(&mut moved, &f, &t, [0.0; 2], 0.0, dt), Ok(()));
    assert_ne!(moved, ps);
}
