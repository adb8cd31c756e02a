//! The whole-assembly DEM passes (`lbdem_kernels::dem::assembly`, the passes the driver's DEM step calls) for
//! every input, on random clusters of overlapping discs and ellipses with random velocities:
//!
//! * the pair passes add internal forces only (they sum to zero and their moments about any point balance),
//!   count exactly the active contacts (overlap > 0 by the exact geometry) and the loaded ones (those whose
//!   per-contact law gives a force), and add to what the buffers held;
//! * the bond passes add internal forces only, count the breaks, and a broken bond adds nothing;
//! * the wall passes' loads are the opposite of the forces the walls put on the particles, they count the
//!   contacts, zero the history of the pairs that are apart, ignore inactive walls, and use each wall's own
//!   velocity (a wall moving with a particle exerts the elastic force only);
//! * `integrate_all` is the per-particle step, and leaves held particles alone;
//! * **chunking**: every pass split into random aligned chunks, the chunks run in reverse order (as threads may
//!   finish in any order), gives bitwise the slots, sums, loads and states of the unsplit pass — so the driver's
//!   parallel step is bitwise the same for any thread count;
//! * every buffer that is too short, and every pair or bond naming a bad index, is refused (never a panic)
//!   before anything is written, while exact and longer buffers are accepted.
//!
//! **Tolerances.** Sums of n contact forces of size ≤ F carry at most n ulp of n F, so balances are checked
//! within 64 n ε Σ|term| (Σ|term| the sum of the magnitudes added). Chunked against unsplit: bitwise.
use lbdem_kernels::dem::assembly::{
    add_bond_forces, add_pair_forces, add_wall_contact_forces, bond_forces, bond_forces_placed,
    integrate_all, pair_contacts, pair_contacts_hinted, pair_contacts_placed,
    wall_contacts_scratch_len, wall_loads, AssemblyError, ContactModel, ContactSums, WallBody,
    WallContactForce, WallLoad,
};
use lbdem_kernels::dem::bond::{Bond, BondForce, BondLaw, ParallelBond, PointBond};
use lbdem_kernels::dem::contact::{
    closest_approach, ellipse_ellipse, ellipse_ellipse_if_touching, ellipse_sample_separates,
    ellipse_separated_along, wall_contact, ELLIPSE_SAMPLES,
};
use lbdem_kernels::dem::integrate::central_difference_step;
use lbdem_kernels::dem::law::{linear_contact_force, BodyState, ContactForce};
use lbdem_kernels::dem::shape::{Particle, Wall};
use lbdem_verification::proptest_cases;
use proptest::prelude::*;

type V = lbdem_kernels::math::Vector<f64>;

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
                Particle::disc(lbdem_kernels::math::Vector::from(x), a, 2.5)
            } else {
                Particle::ellipse(
                    lbdem_kernels::math::Vector::from(x),
                    angle,
                    a,
                    a * aspect,
                    2.5,
                )
            };
            p.velocity = lbdem_kernels::math::Vector::from(v);
            p.angular_velocity = w;
            p
        })
}

/// The particles with their positions scaled by `factor`: from mostly overlapping (< 1) to mostly apart.
fn spread_out(ps: Vec<Particle<f64>>, factor: f64) -> Vec<Particle<f64>> {
    ps.into_iter()
        .map(|mut p| {
            p.position *= factor;
            p
        })
        .collect()
}

/// Whether both particles of a pair are discs (the pair passes take the closed form for them).
fn both_discs(ps: &[Particle<f64>], [i, j]: [usize; 2]) -> bool {
    use lbdem_kernels::dem::shape::Shape;
    matches!(ps[i].shape, Shape::Disc { .. }) && matches!(ps[j].shape, Shape::Disc { .. })
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn all_pairs(n: usize) -> Vec<[usize; 2]> {
    (0..n)
        .flat_map(|i| (i + 1..n).map(move |j| [i, j]))
        .collect()
}

/// Split `0..len` into chunks of at most `size` (≥ 1), listed last chunk first.
fn chunks_reversed(len: usize, size: usize) -> Vec<std::ops::Range<usize>> {
    let size = size.max(1);
    let mut out: Vec<_> = (0..len)
        .step_by(size)
        .map(|a| a..(a + size).min(len))
        .collect();
    out.reverse();
    out
}

/// Bit patterns of force and torque buffers (bitwise comparison, NaN-safe).
fn bits(f: &[V], t: &[f64]) -> Vec<u64> {
    f.iter()
        .flat_map(|v| [v[0].to_bits(), v[1].to_bits()])
        .chain(t.iter().map(|x| x.to_bits()))
        .collect()
}

/// Σ F and Σ (τ + x × F) of the increments from (f0, t0) to (f, t), and the size Σ|term| of what was added.
fn balance(ps: &[Particle<f64>], f0: &[V], t0: &[f64], f: &[V], t: &[f64]) -> ([f64; 2], f64, f64) {
    let (mut sum, mut moment, mut size) = ([0.0; 2], 0.0, 0.0);
    for k in 0..ps.len() {
        let df = [f[k][0] - f0[k][0], f[k][1] - f0[k][1]];
        let dt_k = t[k] - t0[k];
        sum[0] += df[0];
        sum[1] += df[1];
        moment += dt_k + cross(ps[k].position.into(), df);
        size += df[0].abs() + df[1].abs() + dt_k.abs() + cross(ps[k].position.into(), df).abs();
    }
    (sum, moment, size)
}

/// Bonds between random pairs of `ps` (point or parallel), created at the current state.
fn make_bonds(ps: &[Particle<f64>], picks: &[(usize, usize, bool, f64)]) -> Vec<Bond<f64>> {
    let n = ps.len();
    picks
        .iter()
        .filter_map(|&(a, b, point, strength)| {
            let (i, j) = (a % n, b % n);
            if i == j {
                return None;
            }
            let (i, j) = (i.min(j), i.max(j));
            let law = if point {
                BondLaw::Point(PointBond::between(&ps[i], &ps[j], 1e5, strength))
            } else {
                let (ri, rj) = (ps[i].shape.bounding_radius(), ps[j].shape.bounding_radius());
                BondLaw::Parallel {
                    bond: ParallelBond::new(ri, rj, 1.0, 2.8e5, 2.8e5, strength, strength),
                    radii: [ri, rj],
                }
            };
            Some(Bond { pair: [i, j], law })
        })
        .collect()
}

/// Move every particle a little (a step of its velocity and spin), so that bonds stretch.
fn moved(ps: &[Particle<f64>], dt: f64) -> Vec<Particle<f64>> {
    ps.iter()
        .map(|p| {
            let mut q = *p;
            q.position = lbdem_kernels::math::vector(
                p.position[0] + p.velocity[0] * dt,
                p.position[1] + p.velocity[1] * dt,
            );
            q.angle += p.angular_velocity * dt;
            q
        })
        .collect()
}

fn walls(tilt: f64, speed: [f64; 3], active: [bool; 3]) -> [WallBody<f64>; 3] {
    let w = [
        Wall::from_angle(
            lbdem_kernels::math::vector(0.0, 0.15),
            std::f64::consts::FRAC_PI_2 + tilt,
        ),
        Wall::from_angle(lbdem_kernels::math::vector(0.15, 0.0), tilt),
        Wall::from_angle(
            lbdem_kernels::math::vector(0.85, 1.0),
            -std::f64::consts::FRAC_PI_2 + tilt,
        ),
    ];
    std::array::from_fn(|k| WallBody {
        wall: w[k],
        velocity: lbdem_kernels::math::vector(w[k].normal[0] * speed[k], w[k].normal[1] * speed[k]),
        active: active[k],
    })
}

/// The bits of a bond slot (forces, torques, break record).
fn slot_bits(s: &BondForce<f64>) -> Vec<u64> {
    let mut v = vec![
        s.force_on_i[0].to_bits(),
        s.force_on_i[1].to_bits(),
        s.force_on_j[0].to_bits(),
        s.force_on_j[1].to_bits(),
        s.torque_on_i.to_bits(),
        s.torque_on_j.to_bits(),
    ];
    if let Some(b) = &s.broke {
        v.extend([
            b.mode as u64,
            b.orientation.to_bits(),
            b.position[0].to_bits(),
            b.position[1].to_bits(),
            b.load.to_bits(),
        ]);
    }
    v
}

/// Eq. 6.13 written out (an independent statement of the point bond): material points p = c + R(θ) g,
/// Δx = (p_j − p_i) − R(φ̄) g₀ with φ̄ the mean rotation since bonding, F_j = −k_b Δx at x = (p_i + p_j)/2;
/// broken when |F| ≥ F_crit (tension, compression or shear by the larger part of Δx along R(φ̄) n₀).
fn point_bond_by_formula(
    b: &PointBond<f64>,
    i: &Particle<f64>,
    j: &Particle<f64>,
) -> BondForce<f64> {
    use lbdem_kernels::dem::bond::{BondBreak, BreakMode};
    use lbdem_kernels::math::{cross, norm, perp, rotate, rotate_by, rotation};
    if !b.intact {
        return BondForce::zero();
    }
    let pi = i.position + rotate(&b.anchor_i, i.angle);
    let pj = j.position + rotate(&b.anchor_j, j.angle);
    let x = (pi + pj) * 0.5;
    let r = rotation(0.5 * ((i.angle - b.rest_angles[0]) + (j.angle - b.rest_angles[1])));
    let dx = (pj - pi) - rotate_by(&r, &b.rest_gap);
    let n = rotate_by(&r, &b.rest_normal);
    let force_on_j = dx * (-b.stiffness);
    let magnitude = norm(&force_on_j);
    if magnitude >= b.strength {
        let (normal, shear) = (dx.dot(&n), dx.dot(&perp(&n)).abs());
        let mode = if shear > normal.abs() {
            BreakMode::Shear
        } else if normal >= 0.0 {
            BreakMode::Tension
        } else {
            BreakMode::Compression
        };
        let mut s = BondForce::zero();
        s.broke = Some(BondBreak {
            mode,
            orientation: lbdem_kernels::Real::portable_atan2(n[1], n[0]),
            position: x,
            load: magnitude,
        });
        return s;
    }
    BondForce {
        force_on_i: -force_on_j,
        force_on_j,
        torque_on_i: cross(&(x - i.position), &(-force_on_j)),
        torque_on_j: cross(&(x - j.position), &force_on_j),
        broke: None,
    }
}

proptest! {
    #![proptest_config(config(128))]

    /// Pair passes: the forces and torques added are internal (Σ F = 0, Σ (τ + x × F) = 0), the counts are the
    /// active contacts (exact geometry) and the loaded ones (per-contact law), the normal-force sum is theirs in
    /// pair order, the buffers are added to, and a pair list given in another order gives the same totals.
    #[test]
    fn pair_forces_are_internal_and_counted(
        ps in prop::collection::vec(particle(), 2..8),
        start in prop::collection::vec(([-1.0f64..1.0, -1.0f64..1.0], -1.0f64..1.0), 8),
        restitution in prop_oneof![Just(1.0), 0.2f64..0.9],
    ) {
        let n = ps.len();
        let m = model(restitution);
        let pairs = all_pairs(n);
        let f0: Vec<V> = start[..n].iter().map(|s| V::from(s.0)).collect();
        let t0: Vec<f64> = start[..n].iter().map(|s| s.1).collect();
        let (mut f, mut t) = (f0.clone(), t0.clone());
        let mut shear = vec![0.0; pairs.len()];
        let mut slots = vec![ContactForce::zero(); pairs.len()];
        let dt = 1e-5;
        pair_contacts(&m, &ps, &pairs, &mut shear, dt, &mut slots).expect("valid input");
        let sums = add_pair_forces(&pairs, &slots, &mut f, &mut t).expect("valid input");
        let active = pairs.iter().filter(|&&[i, j]| closest_approach(&ps[i], &ps[j]).is_active()).count();
        prop_assert_eq!(sums.active, active);
        // Loaded: the per-contact law, applied pair by pair by hand.
        let (mut loaded, mut normal) = (0, 0.0);
        for &[i, j] in &pairs {
            let c = closest_approach(&ps[i], &ps[j]);
            let mut history = 0.0;
            let one = linear_contact_force(
                &m.law(ps[i].mass, ps[j].mass), &c,
                &BodyState::synchronous(&ps[i], dt), &BodyState::synchronous(&ps[j], dt), &mut history, dt,
            );
            if one.normal_force > 0.0 || one.shear_force != 0.0 {
                loaded += 1;
                normal += one.normal_force;
            }
        }
        prop_assert_eq!(sums.loaded, loaded);
        prop_assert!(sums.loaded <= sums.active);
        prop_assert_eq!(sums.normal_force.to_bits(), normal.to_bits());
        let (sum, moment, size) = balance(&ps, &f0, &t0, &f, &t);
        let tol = 64.0 * (n * n) as f64 * f64::EPSILON * size + 1e-300;
        prop_assert!(sum[0].abs() <= tol && sum[1].abs() <= tol, "Σ F = {sum:?} (tol {tol:e})");
        prop_assert!(moment.abs() <= tol, "Σ (τ + x × F) = {moment:e} (tol {tol:e})");
        if active == 0 {
            prop_assert_eq!((&f, &t), (&f0, &t0));
        }
        // The same pairs in reverse order: the same totals, to roundoff, and the same per-pair histories.
        let reversed: Vec<[usize; 2]> = pairs.iter().rev().copied().collect();
        let (mut f2, mut t2) = (f0.clone(), t0.clone());
        let mut shear2 = vec![0.0; pairs.len()];
        pair_contacts(&m, &ps, &reversed, &mut shear2, dt, &mut slots).expect("valid input");
        add_pair_forces(&reversed, &slots, &mut f2, &mut t2).expect("valid input");
        for k in 0..n {
            prop_assert!((f2[k][0] - f[k][0]).abs() <= tol && (f2[k][1] - f[k][1]).abs() <= tol && (t2[k] - t[k]).abs() <= tol);
        }
        for (a, b) in shear.iter().zip(shear2.iter().rev()) {
            prop_assert_eq!(a.to_bits(), b.to_bits());
        }
    }

    /// The bond pass the driver runs (`bond_forces_placed`, each particle's sine and cosine taken once from
    /// its placed shape) gives bitwise the slots and bond states of `bond_forces`, and a point bond's slot is
    /// bitwise eq. 6.13 written out with rotations by the particles' angles (the formula before placed
    /// shapes were passed in), breaks included.
    #[test]
    fn the_placed_bond_pass_is_bitwise_the_bond_pass_and_the_formula(
        ps in prop::collection::vec(particle(), 2..8),
        picks in prop::collection::vec((0usize..8, 0usize..8, any::<bool>(), prop_oneof![Just(1e9), 1.0f64..400.0]), 0..12),
        dt in 1e-4f64..5e-2,
    ) {
        let bonds0 = make_bonds(&ps, &picks);
        let now = moved(&ps, dt);
        let placed: Vec<_> = now.iter().map(Particle::placed).collect();
        let (mut a, mut b) = (bonds0.clone(), bonds0.clone());
        let mut sa = vec![BondForce::zero(); a.len()];
        let mut sb = vec![BondForce::zero(); b.len()];
        bond_forces(&now, &mut a, 1e-3, &mut sa).expect("valid input");
        bond_forces_placed(&now, &placed, &mut b, 1e-3, &mut sb).expect("valid input");
        for (k, ((x, y), bond)) in sa.iter().zip(&sb).zip(&bonds0).enumerate() {
            prop_assert_eq!(slot_bits(x), slot_bits(y), "bond {}", k);
            prop_assert_eq!(a[k].intact(), b[k].intact());
            if let BondLaw::Point(pb) = &bond.law {
                let [i, j] = bond.pair;
                prop_assert_eq!(slot_bits(x), slot_bits(&point_bond_by_formula(pb, &now[i], &now[j])), "bond {}", k);
            }
        }
        // A placed list shorter than the particles is refused before anything is written.
        if !b.is_empty() {
            prop_assert_eq!(
                bond_forces_placed(&now, &placed[..now.len() - 1], &mut b, 1e-3, &mut sb),
                Err(AssemblyError::BufferLength)
            );
        }
    }

    /// Bond passes: the forces added are internal, the count is the number of bonds that broke (each marked
    /// broken, with its slot recording the break), and a bond that broke adds nothing.
    #[test]
    fn bond_forces_are_internal_and_breaks_counted(
        ps in prop::collection::vec(particle(), 2..8),
        picks in prop::collection::vec((0usize..8, 0usize..8, any::<bool>(), prop_oneof![Just(1e9), 1.0f64..400.0]), 0..12),
    ) {
        let n = ps.len();
        let mut bonds = make_bonds(&ps, &picks);
        let now = moved(&ps, 2e-3);
        let (mut f, mut t) = (vec![lbdem_kernels::math::Vector::<f64>::zeros(); n], vec![0.0; n]);
        let mut slots = vec![BondForce::zero(); bonds.len()];
        bond_forces(&now, &mut bonds, 1e-3, &mut slots).expect("valid input");
        let broke = add_bond_forces(&bonds, &slots, &mut f, &mut t).expect("valid input");
        prop_assert_eq!(broke, slots.iter().filter(|s| s.broke.is_some()).count());
        for (b, s) in bonds.iter().zip(&slots) {
            if s.broke.is_some() {
                prop_assert!(!b.intact());
            }
        }
        // Only the bonds that did not break: their forces by hand, in bond order.
        let (mut fh, mut th) = (vec![lbdem_kernels::math::Vector::<f64>::zeros(); n], vec![0.0; n]);
        for (b, s) in bonds.iter().zip(&slots) {
            if s.broke.is_none() {
                let [i, j] = b.pair;
                fh[i] = lbdem_kernels::math::vector(fh[i][0] + s.force_on_i[0], fh[i][1] + s.force_on_i[1]);
                fh[j] = lbdem_kernels::math::vector(fh[j][0] + s.force_on_j[0], fh[j][1] + s.force_on_j[1]);
                th[i] += s.torque_on_i;
                th[j] += s.torque_on_j;
            }
        }
        prop_assert_eq!(bits(&f, &t), bits(&fh, &th));
        let zero = (vec![lbdem_kernels::math::Vector::<f64>::zeros(); n], vec![0.0; n]);
        let (sum, moment, size) = balance(&now, &zero.0, &zero.1, &f, &t);
        let tol = 64.0 * (n * n + bonds.len()) as f64 * f64::EPSILON * size + 1e-300;
        prop_assert!(sum[0].abs() <= tol && sum[1].abs() <= tol, "Σ F = {sum:?} (tol {tol:e})");
        prop_assert!(moment.abs() <= tol, "Σ (τ + x × F) = {moment:e} (tol {tol:e})");
    }

    /// Wall passes: each wall's load is minus the sum of the forces it put on the particles, its contact count
    /// is the number of particles touching it, the history of every pair that does not touch is zeroed, and an
    /// inactive wall touches nothing.
    #[test]
    fn wall_loads_balance_the_wall_forces(
        ps in prop::collection::vec(particle(), 1..8),
        tilt in -0.3f64..0.3,
        speed in [-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0],
        active in [any::<bool>(), any::<bool>(), any::<bool>()],
    ) {
        let ws = walls(tilt, speed, active);
        let n = ps.len();
        let len = wall_contacts_scratch_len(n, ws.len()).unwrap();
        let (mut f, mut t) = (vec![lbdem_kernels::math::Vector::<f64>::zeros(); n], vec![0.0; n]);
        let mut shear = vec![7.0; len];
        let mut slots = vec![WallContactForce::none(); len];
        let mut loads = vec![WallLoad { force: lbdem_kernels::math::vector(3.0, 3.0), contacts: 9 }; ws.len()];
        add_wall_contact_forces(&model(0.5), &ps, &ws, &mut shear, 1e-5, &mut f, &mut t, &mut slots)
            .expect("valid input");
        wall_loads(&slots, &mut loads).expect("valid input");
        let mut touching = [0usize; 3];
        for (i, p) in ps.iter().enumerate() {
            for (w, wall) in ws.iter().enumerate() {
                if wall.active && wall_contact(p, &wall.wall).is_some() {
                    touching[w] += 1;
                } else {
                    prop_assert_eq!(shear[i * ws.len() + w], 0.0, "history of apart pair ({}, {})", i, w);
                    prop_assert!(!slots[i * ws.len() + w].touching);
                }
            }
        }
        for w in 0..ws.len() {
            prop_assert_eq!(loads[w].contacts, touching[w]);
            if !ws[w].active {
                prop_assert_eq!(loads[w].force, V::zeros());
            }
        }
        let total: [f64; 2] = f.iter().fold([0.0; 2], |s, v| [s[0] + v[0], s[1] + v[1]]);
        let on_walls: [f64; 2] = loads.iter().fold([0.0; 2], |s, l| [s[0] + l.force[0], s[1] + l.force[1]]);
        let size: f64 = f.iter().map(|v| v[0].abs() + v[1].abs()).sum();
        let tol = 64.0 * (n * ws.len()) as f64 * f64::EPSILON * size + 1e-300;
        for a in 0..2 {
            prop_assert!((total[a] + on_walls[a]).abs() <= tol, "axis {a}: particles {total:?}, walls {on_walls:?}");
        }
    }

    /// A wall moving with a particle (same velocity, no spin, no acceleration) has no relative velocity at
    /// the contact: only the elastic normal force k_n δ acts (no dashpot, no shear increment).
    #[test]
    fn a_wall_moving_with_the_particle_exerts_the_elastic_force_only(
        p in particle(),
        angle in -3.2f64..3.2,
        depth in 1e-4f64..0.05,
    ) {
        let mut p = p;
        p.angular_velocity = 0.0;
        let normal = [angle.cos(), angle.sin()];
        // The wall surface cuts the particle `depth` deep along −normal.
        let probe = Wall { point: p.position, normal: lbdem_kernels::math::Vector::from(normal) };
        let h = lbdem_kernels::dem::contact::placed_wall(&p.placed(), &probe).overlap;
        let point = [
            p.position[0] - normal[0] * (h - depth),
            p.position[1] - normal[1] * (h - depth),
        ];
        let wall = WallBody { wall: Wall { point: lbdem_kernels::math::Vector::from(point), normal: lbdem_kernels::math::Vector::from(normal) }, velocity: p.velocity, active: true };
        let c = wall_contact(&p, &wall.wall).expect("the wall cuts the particle");
        let (mut f, mut t) = (vec![lbdem_kernels::math::Vector::<f64>::zeros(); 1], vec![0.0; 1]);
        let (mut shear, mut slots) = (vec![0.0; 1], vec![WallContactForce::none(); 1]);
        add_wall_contact_forces(&model(0.3), &[p], &[wall], &mut shear, 1e-4, &mut f, &mut t, &mut slots)
            .expect("valid input");
        prop_assert_eq!(shear[0], 0.0);
        // Force on the particle: k_n δ along the wall's normal (the contact normal is −normal, from i to j). The
        // relative velocity is exactly zero (the same numbers subtracted), so the only roundoff is that of the
        // products, a few ulp of k_n δ.
        let expected = [1e5 * c.overlap * normal[0], 1e5 * c.overlap * normal[1]];
        let tol = 8.0 * f64::EPSILON * 1e5 * c.overlap;
        prop_assert!((f[0][0] - expected[0]).abs() <= tol && (f[0][1] - expected[1]).abs() <= tol,
            "{:?} against {:?}", f[0], expected);
    }

    /// `integrate_all` is the per-particle central-difference step (bitwise), with gravity and damping, and
    /// does not move held particles.
    #[test]
    fn integrate_all_is_the_particle_step(
        ps in prop::collection::vec(particle(), 0..6),
        loads in prop::collection::vec(([-10.0f64..10.0, -10.0f64..10.0], -1.0f64..1.0, any::<bool>()), 6),
        alpha in 0.0f64..0.8,
    ) {
        let n = ps.len();
        let f: Vec<V> = loads[..n].iter().map(|l| V::from(l.0)).collect();
        let t: Vec<f64> = loads[..n].iter().map(|l| l.1).collect();
        let held: Vec<bool> = loads[..n].iter().map(|l| l.2).collect();
        let (g, dt) = ([0.0, -9.81], 1e-4);
        let mut all = ps.clone();
        integrate_all(&mut all, &f, &t, &held, lbdem_kernels::math::Vector::from(g), alpha, dt).expect("valid input");
        for (k, mut p) in ps.into_iter().enumerate() {
            if !held[k] {
                central_difference_step(&mut p, lbdem_kernels::math::Vector::from(f[k]), t[k], lbdem_kernels::math::Vector::from(g), alpha, dt);
            }
            prop_assert_eq!(p, all[k]);
        }
    }
}

proptest! {
    #![proptest_config(config(96))]

    /// Every pass split into random aligned chunks, run last chunk first, gives bitwise what the unsplit pass
    /// gives: pair slots, histories, sums, forces; bond slots, states, forces; wall slots, histories, loads,
    /// forces; integrated states. (Rayon runs chunks like these on any number of threads.)
    #[test]
    fn chunked_passes_are_bitwise_the_whole_passes(
        ps in prop::collection::vec(particle(), 2..9),
        picks in prop::collection::vec((0usize..9, 0usize..9, any::<bool>(), prop_oneof![Just(1e9), 1.0f64..400.0]), 0..14),
        sizes in [1usize..12, 1usize..12, 1usize..12, 1usize..12],
        restitution in prop_oneof![Just(1.0), 0.2f64..0.9],
        speed in [-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0],
        active in [any::<bool>(), any::<bool>(), any::<bool>()],
        held in prop::collection::vec(any::<bool>(), 9),
    ) {
        let n = ps.len();
        let m = model(restitution);
        let dt = 1e-5;
        let pairs = all_pairs(n);
        let history: Vec<f64> = (0..pairs.len()).map(|k| 0.3 * k as f64 - 1.0).collect();
        let ws = walls(0.1, speed, active);
        let wl = ws.len();
        let held = &held[..n];

        // Unsplit.
        let run = |sizes: Option<[usize; 4]>| {
            let (mut f, mut t) = (vec![lbdem_kernels::math::Vector::<f64>::zeros(); n], vec![0.0; n]);
            let mut shear = history.clone();
            let mut slots = vec![ContactForce::zero(); pairs.len()];
            let ranges = |len: usize, k: usize| match sizes {
                Some(s) => chunks_reversed(len, s[k]),
                None => chunks_reversed(len, len.max(1)),
            };
            for r in ranges(pairs.len(), 0) {
                pair_contacts(&m, &ps, &pairs[r.clone()], &mut shear[r.clone()], dt, &mut slots[r]).unwrap();
            }
            let sums: ContactSums<f64> = add_pair_forces(&pairs, &slots, &mut f, &mut t).unwrap();
            let mut bonds = make_bonds(&ps, &picks);
            let mut bslots = vec![BondForce::zero(); bonds.len()];
            let now = moved(&ps, 2e-3);
            for r in ranges(bonds.len(), 1) {
                bond_forces(&now, &mut bonds[r.clone()], 1e-3, &mut bslots[r]).unwrap();
            }
            let broke = add_bond_forces(&bonds, &bslots, &mut f, &mut t).unwrap();
            let mut wshear = vec![0.5; n * wl];
            let mut wslots = vec![WallContactForce::none(); n * wl];
            for r in ranges(n, 2) {
                let (a, b) = (r.start * wl, r.end * wl);
                add_wall_contact_forces(&m, &ps[r.clone()], &ws, &mut wshear[a..b], dt, &mut f[r.clone()],
                    &mut t[r], &mut wslots[a..b]).unwrap();
            }
            let mut loads = vec![WallLoad::default(); wl];
            wall_loads(&wslots, &mut loads).unwrap();
            let mut moved_ps = ps.clone();
            for r in ranges(n, 3) {
                integrate_all(&mut moved_ps[r.clone()], &f[r.clone()], &t[r.clone()], &held[r], lbdem_kernels::math::vector(0.0, -9.81), 0.7, dt).unwrap();
            }
            (slots, shear, sums, bonds, bslots, broke, wslots, wshear, loads, bits(&f, &t), moved_ps)
        };
        let whole = run(None);
        let split = run(Some(sizes));
        prop_assert_eq!(format!("{:?}", whole.0), format!("{:?}", split.0));
        prop_assert_eq!(bits(&[], &whole.1), bits(&[], &split.1));
        prop_assert_eq!(whole.2.active, split.2.active);
        prop_assert_eq!(whole.2.loaded, split.2.loaded);
        prop_assert_eq!(whole.2.normal_force.to_bits(), split.2.normal_force.to_bits());
        prop_assert_eq!(format!("{:?}", whole.3), format!("{:?}", split.3));
        prop_assert_eq!(format!("{:?}", whole.4), format!("{:?}", split.4));
        prop_assert_eq!(whole.5, split.5);
        prop_assert_eq!(format!("{:?}", whole.6), format!("{:?}", split.6));
        prop_assert_eq!(bits(&[], &whole.7), bits(&[], &split.7));
        prop_assert_eq!(format!("{:?}", whole.8), format!("{:?}", split.8));
        prop_assert_eq!(whole.9, split.9);
        prop_assert_eq!(format!("{:?}", whole.10), format!("{:?}", split.10));
    }
}

/// Every buffer one entry too short is refused with `BufferLength` (or `BadPair` for a bad index) before
/// anything is written; buffers of the exact length or longer are accepted.
#[test]
fn every_short_buffer_is_refused() {
    let ps = [
        Particle::disc(lbdem_kernels::math::vector(0.0, 0.0), 0.1, 1.0),
        Particle::disc(lbdem_kernels::math::vector(0.15, 0.0), 0.1, 1.0),
        Particle::disc(lbdem_kernels::math::vector(0.3, 0.0), 0.1, 1.0),
    ];
    let pairs = [[0, 1], [1, 2]];
    let m = model(0.5);
    let dt = 1e-5;

    // Pair evaluation: histories and slots one per pair.
    let eval = |shear: usize, out: usize| {
        let (mut s, mut o) = (vec![0.0; shear], vec![ContactForce::zero(); out]);
        let r = pair_contacts(&m, &ps, &pairs, &mut s, dt, &mut o);
        (r, o.iter().all(|c| *c == ContactForce::zero()))
    };
    for (s, o) in [(1, 2), (2, 1)] {
        assert_eq!(
            eval(s, o),
            (Err(AssemblyError::BufferLength), true),
            "{s} {o}"
        );
    }
    assert_eq!(eval(2, 2).0, Ok(()));
    assert_eq!(eval(3, 3).0, Ok(()));
    for bad in [[0, 3], [3, 0], [2, 2]] {
        let (mut s, mut o) = (vec![0.0; 1], vec![ContactForce::zero(); 1]);
        assert_eq!(
            pair_contacts(&m, &ps, &[bad], &mut s, dt, &mut o),
            Err(AssemblyError::BadPair)
        );
    }
    // Pair summation: slots one per pair, force and torque an entry for every index named.
    let mut slots = vec![ContactForce::zero(); 2];
    pair_contacts(&m, &ps, &pairs, &mut [0.0; 2], dt, &mut slots).unwrap();
    let sum = |contacts: usize, force: usize, torque: usize| {
        let (mut f, mut t) = (
            vec![lbdem_kernels::math::Vector::<f64>::zeros(); force],
            vec![0.0; torque],
        );
        let r = add_pair_forces(&pairs, &slots[..contacts], &mut f, &mut t);
        (
            r.map(|s| s.active),
            f.iter().all(|v| *v == lbdem_kernels::math::Vector::zeros())
                && t.iter().all(|v| *v == 0.0),
        )
    };
    for (c, f, t) in [(1, 3, 3), (2, 2, 3), (2, 3, 2)] {
        assert_eq!(
            sum(c, f, t),
            (Err(AssemblyError::BufferLength), true),
            "{c} {f} {t}"
        );
    }
    assert_eq!(sum(2, 3, 3).0, Ok(2));
    assert_eq!(sum(2, 4, 4).0, Ok(2));
    assert_eq!(
        add_pair_forces(
            &[[1, 1]],
            &slots,
            &mut [lbdem_kernels::math::Vector::<f64>::zeros(); 3],
            &mut [0.0; 3]
        ),
        Err(AssemblyError::BadPair)
    );

    // Bonds.
    let bonds = vec![
        Bond {
            pair: [0, 1],
            law: BondLaw::Point(PointBond::between(&ps[0], &ps[1], 1e5, 700.0)),
        },
        Bond {
            pair: [1, 2],
            law: BondLaw::Point(PointBond::between(&ps[1], &ps[2], 1e5, 700.0)),
        },
    ];
    let mut b = bonds.clone();
    assert_eq!(
        bond_forces(&ps, &mut b, dt, &mut [BondForce::zero(); 1]),
        Err(AssemblyError::BufferLength)
    );
    for bad in [[0, 3], [2, 2]] {
        let mut one = [Bond {
            pair: bad,
            law: bonds[0].law,
        }];
        assert_eq!(
            bond_forces(&ps, &mut one, dt, &mut [BondForce::zero(); 1]),
            Err(AssemblyError::BadPair)
        );
    }
    let mut bslots = [BondForce::zero(); 2];
    assert_eq!(bond_forces(&ps, &mut b, dt, &mut bslots), Ok(()));
    assert_eq!(b, bonds, "unstretched bonds keep their state");
    let mut f = vec![lbdem_kernels::math::Vector::<f64>::zeros(); 2];
    assert_eq!(
        add_bond_forces(&bonds, &bslots, &mut f, &mut [0.0; 3]),
        Err(AssemblyError::BufferLength)
    );
    assert_eq!(
        add_bond_forces(
            &bonds,
            &bslots[..1],
            &mut [lbdem_kernels::math::Vector::<f64>::zeros(); 3],
            &mut [0.0; 3]
        ),
        Err(AssemblyError::BufferLength)
    );
    assert_eq!(
        add_bond_forces(
            &bonds,
            &bslots,
            &mut [lbdem_kernels::math::Vector::<f64>::zeros(); 3],
            &mut [0.0; 3]
        ),
        Ok(0)
    );

    // Walls.
    let walls = [
        WallBody::fixed(Wall::from_angle(
            lbdem_kernels::math::vector(0.0, -0.05),
            std::f64::consts::FRAC_PI_2,
        )),
        WallBody::fixed(Wall::from_angle(
            lbdem_kernels::math::vector(-0.05, 0.0),
            0.0,
        )),
    ];
    let wall = |shear: usize, force: usize, torque: usize, out: usize| {
        let (mut s, mut f, mut t, mut o) = (
            vec![0.0; shear],
            vec![lbdem_kernels::math::Vector::<f64>::zeros(); force],
            vec![0.0; torque],
            vec![WallContactForce::none(); out],
        );
        let r = add_wall_contact_forces(&m, &ps, &walls, &mut s, dt, &mut f, &mut t, &mut o);
        let mut loads = [WallLoad::default(); 2];
        let counted = r.and_then(|()| wall_loads(&o[..6], &mut loads));
        (
            counted.map(|()| loads[0].contacts + loads[1].contacts),
            f.iter().all(|v| *v == lbdem_kernels::math::Vector::zeros())
                && o.iter().all(|v| !v.touching),
        )
    };
    for (s, f, t, o) in [(5, 3, 3, 6), (6, 2, 3, 6), (6, 3, 2, 6), (6, 3, 3, 5)] {
        assert_eq!(
            wall(s, f, t, o),
            (Err(AssemblyError::BufferLength), true),
            "{s} {f} {t} {o}"
        );
    }
    // Particle 0 touches both walls, particles 1 and 2 the floor: four contacts.
    assert_eq!(wall(6, 3, 3, 6).0, Ok(4));
    assert_eq!(wall(7, 4, 4, 7).0, Ok(4));
    assert_eq!(wall_contacts_scratch_len(usize::MAX, 2), None);
    let mut loads = [WallLoad::<f64>::default(); 2];
    assert_eq!(
        wall_loads(&[WallContactForce::none(); 5], &mut loads),
        Err(AssemblyError::BufferLength)
    );
    assert_eq!(
        wall_loads::<f64>(&[WallContactForce::none(); 1], &mut []),
        Err(AssemblyError::BufferLength)
    );
    assert_eq!(wall_loads::<f64>(&[], &mut []), Ok(()));

    // Integration.
    let mut moved = ps;
    let (f, t, held) = ([V::new(1.0, 0.0); 3], [0.5; 3], [false; 3]);
    assert_eq!(
        integrate_all(
            &mut moved,
            &f[..2],
            &t,
            &held,
            lbdem_kernels::math::Vector::zeros(),
            0.0,
            dt
        ),
        Err(AssemblyError::BufferLength)
    );
    assert_eq!(
        integrate_all(
            &mut moved,
            &f,
            &t[..2],
            &held,
            lbdem_kernels::math::Vector::zeros(),
            0.0,
            dt
        ),
        Err(AssemblyError::BufferLength)
    );
    assert_eq!(
        integrate_all(
            &mut moved,
            &f,
            &t,
            &held[..2],
            lbdem_kernels::math::Vector::zeros(),
            0.0,
            dt
        ),
        Err(AssemblyError::BufferLength)
    );
    assert_eq!(moved, ps, "nothing moved on error");
    assert_eq!(
        integrate_all(
            &mut moved,
            &f,
            &t,
            &held,
            lbdem_kernels::math::Vector::zeros(),
            0.0,
            dt
        ),
        Ok(())
    );
    assert_ne!(moved, ps);
}

/// The bonded critical step: without bonds it is the contact-only estimate (bitwise); a point bond of
/// stiffness k_b adds k_b and k_b R² to each of its particles (by hand for one pair); scratch and bond indices
/// are checked.
#[test]
fn bonded_critical_step_adds_the_bond_stiffness() {
    let m = ContactModel {
        normal_stiffness: 1e5f64,
        shear_stiffness: 6e4,
        friction: 0.5,
        restitution: 1.0,
        no_tension: true,
    };
    let ps = [
        Particle::disc(lbdem_kernels::math::vector(0.0, 0.0), 0.1, 2.0),
        Particle::disc(lbdem_kernels::math::vector(0.2, 0.0), 0.1, 2.0),
        // The largest body: its own step is the longest, so the two small discs (bonded below) set the step.
        Particle::ellipse(lbdem_kernels::math::vector(0.8, 0.0), 0.4, 0.3, 0.2, 2.0),
    ];
    let (mut kt, mut kr) = ([0.0; 3], [0.0; 3]);
    let alone = m
        .bonded_critical_time_step(&ps, &[], 6.0, &mut kt, &mut kr)
        .unwrap();
    assert_eq!(alone.to_bits(), m.critical_time_step(&ps, 6.0).to_bits());
    let kb = 3e5;
    let bond = Bond {
        pair: [0, 1],
        law: BondLaw::Point(PointBond::between(&ps[0], &ps[1], kb, 700.0)),
    };
    let bonded = m
        .bonded_critical_time_step(&ps, &[bond], 6.0, &mut kt, &mut kr)
        .unwrap();
    let (mass, inertia, r) = (ps[0].mass, ps[0].moment_of_inertia, 0.1);
    let by_hand = (mass / (6.0 * 1e5 + kb))
        .sqrt()
        .min((inertia / (6.0 * 6e4 * r * r + kb * r * r)).sqrt())
        .min(alone);
    assert!(
        (bonded - by_hand).abs() <= 1e-14 * by_hand,
        "{bonded} {by_hand}"
    );
    assert!(bonded < alone);
    assert_eq!(
        kt[2],
        6.0 * 1e5,
        "the unbonded ellipse keeps its contact stiffness"
    );
    // A broken bond adds nothing.
    let mut broken = bond;
    if let BondLaw::Point(p) = &mut broken.law {
        p.intact = false;
    }
    assert_eq!(
        m.bonded_critical_time_step(&ps, &[broken], 6.0, &mut kt, &mut kr),
        Ok(alone)
    );
    assert_eq!(
        m.bonded_critical_time_step(&ps, &[bond], 6.0, &mut kt[..2], &mut kr),
        Err(AssemblyError::BufferLength)
    );
    // Either scratch too short is refused; scratch longer than the particles is accepted, with the same step.
    assert_eq!(
        m.bonded_critical_time_step(&ps, &[bond], 6.0, &mut kt, &mut kr[..2]),
        Err(AssemblyError::BufferLength)
    );
    let (mut kt_long, mut kr_long) = ([0.0; 5], [0.0; 5]);
    assert_eq!(
        m.bonded_critical_time_step(&ps, &[bond], 6.0, &mut kt_long, &mut kr_long),
        Ok(bonded)
    );
    let far = Bond {
        pair: [0, 3],
        law: bond.law,
    };
    assert_eq!(
        m.bonded_critical_time_step(&ps, &[far], 6.0, &mut kt, &mut kr),
        Err(AssemblyError::BadPair)
    );
}

proptest! {
    #![proptest_config(config(256))]

    /// The pair pass skips the closest-approach search where one of its samples already separates the pair
    /// (`ellipse_sample_separates`), and can take the placed shapes precomputed: neither changes a bit. Each
    /// slot and history, from random histories, is bitwise the per-contact law applied to `closest_approach`
    /// (the uncut search), with and without the placed shapes; pairs from touching to well apart.
    #[test]
    fn the_separating_sample_cull_and_placed_shapes_change_no_bit(
        ps in prop::collection::vec(particle(), 2..8),
        histories in prop::collection::vec(-1.0f64..1.0, 28),
        spread in prop_oneof![Just(0.3), Just(1.0), Just(2.0)],
    ) {
        // Spread the particles out by a random factor: from mostly overlapping to mostly apart.
        let ps = spread_out(ps, spread);
        let m = model(0.5);
        let pairs = all_pairs(ps.len());
        let dt = 1e-5;
        let mut shear = histories[..pairs.len()].to_vec();
        let mut slots = vec![ContactForce::zero(); pairs.len()];
        pair_contacts(&m, &ps, &pairs, &mut shear, dt, &mut slots).expect("valid input");
        let placed: Vec<_> = ps.iter().map(Particle::placed).collect();
        let mut shear_p = histories[..pairs.len()].to_vec();
        let mut slots_p = vec![ContactForce::zero(); pairs.len()];
        pair_contacts_placed(&m, &ps, &placed, &pairs, &mut shear_p, dt, &mut slots_p).expect("valid input");
        for (k, &[i, j]) in pairs.iter().enumerate() {
            let c = closest_approach(&ps[i], &ps[j]);
            let mut history = histories[k];
            let one = linear_contact_force(
                &m.law(ps[i].mass, ps[j].mass), &c,
                &BodyState::synchronous(&ps[i], dt), &BodyState::synchronous(&ps[j], dt), &mut history, dt,
            );
            prop_assert_eq!(format!("{:?}", slots[k]), format!("{:?}", one), "pair {:?}", [i, j]);
            prop_assert_eq!(format!("{:?}", slots_p[k]), format!("{:?}", one), "pair {:?} (placed)", [i, j]);
            prop_assert_eq!(shear[k].to_bits(), history.to_bits());
            prop_assert_eq!(shear_p[k].to_bits(), history.to_bits());
        }
        // A placed list shorter than the particles is refused.
        prop_assert!(pair_contacts_placed(&m, &ps, &placed[..1], &pairs, &mut shear_p, dt, &mut slots_p).is_err());
    }
}

proptest! {
    #![proptest_config(config(512))]

    /// `ellipse_ellipse_if_touching` (the pair pass's second cull) is the full search bit for bit where it
    /// answers, and answers `None` only for pairs the full search finds not interpenetrating: random ellipses
    /// and discs, from overlapping to apart, through their placed shapes as the pair pass gives them.
    #[test]
    fn ellipse_ellipse_if_touching_is_the_search_or_a_certain_miss(
        a in particle(),
        b in particle(),
        spread in prop_oneof![Just(0.3), Just(1.0), Just(2.0)],
    ) {
        let (mut a, mut b) = (a, b);
        a.position *= spread;
        b.position *= spread;
        let (pa, pb) = (a.placed(), b.placed());
        let full = ellipse_ellipse(&pa, &pb);
        match ellipse_ellipse_if_touching(&pa, &pb) {
            Some(c) => {
                prop_assert_eq!(format!("{c:?}"), format!("{full:?}"));
                for (x, y) in [(c.overlap, full.overlap), (c.normal[0], full.normal[0]), (c.normal[1], full.normal[1])] {
                    prop_assert_eq!(x.to_bits(), y.to_bits());
                }
            }
            None => prop_assert!(!full.is_active(), "culled an active pair: overlap {}", full.overlap),
        }
    }
}

proptest! {
    #![proptest_config(config(256))]

    /// The hinted pair pass (`pair_contacts_hinted`, the driver's) is bitwise the placed pass whatever the
    /// hints: random directions (unit, zero, or the exact normals of the particles' own contacts, which touch),
    /// then, after every particle moved a step, the hints the first pass left. It leaves a zero hint at every
    /// interpenetrating ellipse pair; run again at the same positions, it culls exactly the pairs whose hints
    /// pass `ellipse_separated_along`; a hint buffer shorter than the pairs is refused.
    #[test]
    fn hints_change_no_bit_and_are_left_where_they_separate(
        ps in prop::collection::vec(particle(), 2..8),
        histories in prop::collection::vec(-1.0f64..1.0, 28),
        spread in prop_oneof![Just(0.3), Just(1.0), Just(2.0)],
        angles in prop::collection::vec(prop_oneof![Just(f64::NAN), -3.2f64..3.2], 28),
        dt in prop_oneof![Just(1e-3), Just(1e-2)],
    ) {
        let ps = spread_out(ps, spread);
        let m = model(0.5);
        let pairs = all_pairs(ps.len());
        let n = pairs.len();
        // Initial hints: none (NaN angle), a random unit direction, or the pair's own contact normal (a
        // direction of largest gap).
        let mut hints: Vec<[f64; 2]> = (0..n)
            .map(|k| {
                let [i, j] = pairs[k];
                match angles[k] {
                    t if t.is_nan() => [0.0, 0.0],
                    t if t > 1.6 => {
                        let c = closest_approach(&ps[i], &ps[j]);
                        [c.normal[0], c.normal[1]]
                    }
                    t => [t.cos(), t.sin()],
                }
            })
            .collect();
        let mut now = ps.clone();
        let mut shear = histories[..n].to_vec();
        let mut shear_p = shear.clone();
        for round in 0..2 {
            let placed: Vec<_> = now.iter().map(Particle::placed).collect();
            let mut slots = vec![ContactForce::zero(); n];
            let mut slots_p = vec![ContactForce::zero(); n];
            pair_contacts_hinted(&m, &now, &placed, &pairs, &mut shear, &mut hints, dt, &mut slots)
                .expect("valid input");
            pair_contacts_placed(&m, &now, &placed, &pairs, &mut shear_p, dt, &mut slots_p)
                .expect("valid input");
            for k in 0..n {
                prop_assert_eq!(format!("{:?}", slots[k]), format!("{:?}", slots_p[k]), "round {} pair {:?}", round, pairs[k]);
                prop_assert_eq!(shear[k].to_bits(), shear_p[k].to_bits());
                let [i, j] = pairs[k];
                let (a, b) = (&placed[i], &placed[j]);
                if both_discs(&now, pairs[k]) {
                    continue;
                }
                if ellipse_ellipse(a, b).is_active() {
                    prop_assert_eq!(hints[k], [0.0, 0.0], "round {} pair {:?}: a hint left at a contact", round, pairs[k]);
                }
            }
            // Run again at the same positions: every pair is culled before the search, or searched and found
            // interpenetrating (its hint zero).
            let mut again = hints.clone();
            let culled = pair_contacts_hinted(&m, &now, &placed, &pairs, &mut shear.clone(), &mut again, dt, &mut vec![ContactForce::zero(); n])
                .expect("valid input");
            // (Disc pairs take the closed form: their hints are not read.)
            let hinted = hints.iter().zip(&pairs).filter(|(h, &[i, j])| {
                !both_discs(&now, [i, j])
                    && ellipse_separated_along(&placed[i], &placed[j], lbdem_kernels::math::vector(h[0], h[1]))
            }).count();
            prop_assert_eq!(culled, hinted);
            now = moved(&now, dt);
        }
        let placed: Vec<_> = now.iter().map(Particle::placed).collect();
        prop_assert!(pair_contacts_hinted(&m, &now, &placed, &pairs, &mut shear, &mut hints[..n - 1], dt, &mut vec![ContactForce::zero(); n]).is_err());
    }

    /// `ellipse_separated_along` is a certain cull: wherever a direction passes it, the full search finds the
    /// pair apart (not active); and it passes the search's own normal of a pair apart by more than 1e-9 of its
    /// size, and never the zero vector. Random ellipses and discs from overlapping to apart, random directions.
    #[test]
    fn a_separating_direction_is_certain_and_found(
        a in particle(),
        b in particle(),
        spread in prop_oneof![Just(0.3), Just(1.0), Just(2.0)],
        theta in -3.2f64..3.2,
    ) {
        let (mut a, mut b) = (a, b);
        a.position *= spread;
        b.position *= spread;
        let (pa, pb) = (a.placed(), b.placed());
        let full = ellipse_ellipse(&pa, &pb);
        let n = lbdem_kernels::math::vector(theta.cos(), theta.sin());
        if ellipse_separated_along(&pa, &pb, n) {
            prop_assert!(!full.is_active(), "a direction passed at a contact: overlap {}", full.overlap);
        }
        let size = pa.a.max(pa.b) + pb.a.max(pb.b);
        if full.overlap < -1e-9 * size {
            prop_assert!(ellipse_separated_along(&pa, &pb, full.normal), "the search's normal of a pair apart by {}", -full.overlap);
        }
        prop_assert!(!ellipse_separated_along(&pa, &pb, lbdem_kernels::math::vector(0.0, 0.0)));
    }
}

/// The stiffness a parallel bond adds for the critical step (Potyondy & Cundall 2004, eq. 6 per unit
/// thickness in 2-D): translational max(k̄_n, k̄_s) A with A = 2R̄, rotational k̄_n I + k̄_s A R² with
/// I = 2R̄³/3 and R the particle's lever arm — evaluated here by hand for one bond, term by term.
#[test]
fn parallel_bond_stiffness_is_the_area_and_inertia_formula() {
    let bond = Bond {
        pair: [0, 1],
        law: BondLaw::Parallel {
            bond: ParallelBond {
                radius: 0.05f64,
                normal_stiffness: 2e6,
                shear_stiffness: 1e6,
                tensile_strength: 1e3,
                shear_strength: 1e3,
                normal_force: 0.0,
                shear_force: 0.0,
                moment: 0.0,
                intact: true,
            },
            radii: [0.1, 0.1],
        },
    };
    let (kt, kr) = bond.stiffness(0.1);
    // A = 0.1, I = 2 × 1.25e-4 / 3; k̄_n I = 2e6 × 8.333…e-5 = 166.666…, k̄_s A R² = 1e6 × 0.1 × 0.01 = 1000.
    // Tolerance: roundoff of a few products.
    assert!((kt - 2e5).abs() < 1e-9 * 2e5, "{kt}");
    assert!((kr - (500.0 / 3.0 + 1000.0)).abs() < 1e-9 * 1200.0, "{kr}");
    // The shear term takes over the translational stiffness when it is the larger.
    let Bond {
        law: BondLaw::Parallel { mut bond, radii },
        pair,
    } = bond
    else {
        unreachable!()
    };
    bond.shear_stiffness = 3e6;
    let (kt, _) = Bond {
        pair,
        law: BondLaw::Parallel { bond, radii },
    }
    .stiffness(0.1);
    assert!((kt - 3e5).abs() < 1e-9 * 3e5, "{kt}");
}

/// The cull is effective as well as sound (above): it takes the sample direction nearest to the line of centres,
/// so two equal discs apart by more than 2r / cos(π/ELLIPSE_SAMPLES) (the worst angle between that line and the
/// nearest of the 32 directions, 5.6°: 2.0097 r) are culled whatever the direction of the line of centres.
/// Checked at 2.02 r, every half degree round the circle; a wrong choice of direction (e.g. the one nearest to
/// the mirror image of the line) gives a sampled gap below zero there and is caught.
#[test]
fn the_separating_sample_cull_catches_separated_discs_in_every_direction() {
    assert_eq!(
        ELLIPSE_SAMPLES, 32,
        "the 2.02 r margin below assumes 32 directions"
    );
    let r = 0.2;
    let c = [0.3, 0.4];
    for k in 0..720 {
        let theta = k as f64 * std::f64::consts::PI / 360.0;
        let d = 2.02 * r;
        let a = Particle::disc(lbdem_kernels::math::Vector::from(c), r, 2.5);
        let b = Particle::disc(
            lbdem_kernels::math::Vector::from([c[0] + d * theta.cos(), c[1] + d * theta.sin()]),
            r,
            2.5,
        );
        assert!(
            ellipse_sample_separates(&a.placed(), &b.placed()),
            "discs 2.02 r apart at {:.1}° not culled",
            theta.to_degrees()
        );
    }
}
