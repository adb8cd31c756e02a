//! Properties of the public kernel functions that no other property file names (every public
//! function of `lbdem-kernels` appears in at least one property test; the guard `every_public_kernel_function_
//! is_named_by_a_property_test` below keeps it so). Each property checks the function against an independent
//! formula or oracle, not against its own code:
//!
//! * the eight one-sided Zou–He closures against `lbdem_reference::lbm::zou_he_pressure`/`zou_he_velocity`
//!   and against what a closure must do: after it, the node's density and momentum are the prescribed ones, and
//!   an equilibrium node is restored exactly;
//! * Guo's source against the reference's and against its moments (no mass, momentum (1 − ω/2) F);
//! * the TRT rates and τ⁻ against Λ = (τ⁺ − ½)(τ⁻ − ½); ΩΛ's weight B(ε) and full-cover test against their
//!   definitions; the solid operators' names and symbols are one-to-one and round-trip;
//! * `bulk_band` (with `fix_special_nodes`) against the reference step on periodic and walled lattices, split
//!   into random bands; `gather_node_in` on a buffer in the in-place scheme's streamed layout, built here from
//!   the layout's definition, against the two-lattice gather;
//! * the vector helpers (`perp`, `norm`, `rotate`, `rotate_by`) against their algebra; `wrap_row` against
//!   `rem_euclid`;
//! * shapes: semi-axes, inertia per mass (a² + b²)/4 against a direct quadrature of r² over the ellipse, the
//!   support point against a dense search of the boundary; disc–wall contact against the distance to the line;
//!   damping c_n = 2ζ√(m k) against the damped oscillator it is built for; a bond's peak shear stress; the
//!   scratch length of the bonded critical time step (accepted at that length, refused one shorter).
//!
//! **Tolerances.** Kernel-versus-reference and closure identities carry a few dozen roundings of O(1) values:
//! [`ORACLE`] = 1e-12 (as in `fluid_properties.rs`). Geometric identities of O(1) vectors: 64 ε relative. The
//! inertia quadrature (2000 × 2000 midpoint cells) is accurate to ~1e-6 relative; the support-point search over
//! 20 000 boundary samples to ~(2π/20 000)² a ≈ 1e-7 a.
use lbdem_kernels::dem::assembly::{
    bonded_critical_time_step_scratch_len, AssemblyError, ContactModel,
};
use lbdem_kernels::dem::bond::{Bond, BondLaw, BondedParticleStiffness, ParallelBond, PointBond};
use lbdem_kernels::dem::contact::disc_wall;
use lbdem_kernels::dem::integrate::{
    damped_stability_limit, exceeds_critical_time_step, particle_critical_time_step,
    single_dof_stability_limit,
};
use lbdem_kernels::dem::law::{
    contact_duration, damping_ratio_from_restitution, effective_mass, normal_damping_coefficient,
    ContactLaw,
};
use lbdem_kernels::dem::shape::{Particle, Placed, Shape, Wall};
use lbdem_kernels::fluid::aa::Layout;
use lbdem_kernels::fluid::boundary::{
    zou_he_pressure_east, zou_he_pressure_north, zou_he_pressure_south, zou_he_pressure_west,
    zou_he_velocity_east, zou_he_velocity_north, zou_he_velocity_south, zou_he_velocity_west,
    Boundaries, SideCondition, SideProfiles,
};
use lbdem_kernels::fluid::collide::{
    guo_source, lambda_fully_covered, lambda_weighting, lane_class, Collision, LaneClass,
    OpenLinks, PsmParams, Rates, SolidOperator, SolidShare, Trt, Weighting, LAMBDA_FULL_GAP,
};
use lbdem_kernels::fluid::d2q9::{density, equilibrium, momentum, velocity, Q};
use lbdem_kernels::fluid::lattice::{wrap_row, LatticeShape};
use lbdem_kernels::fluid::step::{
    band_mut, bulk_band, classify_special_nodes, fix_special_nodes, gather_node, gather_node_in,
    gathered_densities, nodes_in_rows, open_links, planes_mut, wall_gradients, Domain, FluidParams,
    FLUID, SOLID,
};
use lbdem_kernels::math::{norm, perp, rotate, rotate_by, rotation, vector};
use lbdem_reference::lbm as reference;
use lbdem_verification::proptest_cases;
use proptest::prelude::*;
use std::f64::consts::PI;

/// Kernel against reference and closure identities: a few dozen roundings of O(1) values (module notes).
const ORACLE: f64 = 1e-12;
/// Geometric identities of O(1) vectors: a handful of roundings.
const GEOMETRY: f64 = 64.0 * f64::EPSILON;

fn config(default: u32) -> ProptestConfig {
    ProptestConfig::with_cases(proptest_cases(default))
}

/// Populations near equilibrium: f^eq(ρ, u)(1 + δ), ρ ∈ [0.5, 1.5], |u| ≤ 0.2, |δ| ≤ 0.05.
fn near_equilibrium() -> impl Strategy<Value = [f64; Q]> {
    (
        0.5f64..1.5,
        -0.14f64..0.14,
        -0.14f64..0.14,
        proptest::array::uniform9(-0.05f64..0.05),
    )
        .prop_map(|(rho, ux, uy, d)| {
            let eq = equilibrium::<f64>(rho, [ux, uy]);
            core::array::from_fn(|i| eq[i] * (1.0 + d[i]))
        })
}

/// The kernel's closure of one side, by side index (west, east, south, north), pressure or velocity.
type PressureClosure = fn(&mut [f64; Q], f64, f64) -> f64;
type VelocityClosure = fn(&mut [f64; Q], [f64; 2]) -> f64;
const PRESSURE: [PressureClosure; 4] = [
    zou_he_pressure_west,
    zou_he_pressure_east,
    zou_he_pressure_south,
    zou_he_pressure_north,
];
const VELOCITY: [VelocityClosure; 4] = [
    zou_he_velocity_west,
    zou_he_velocity_east,
    zou_he_velocity_south,
    zou_he_velocity_north,
];
const SIDES: [reference::Side; 4] = [
    reference::Side::West,
    reference::Side::East,
    reference::Side::South,
    reference::Side::North,
];
/// Whether the side's normal is the x axis (west, east).
fn normal_is_x(side: usize) -> bool {
    side < 2
}

proptest! {
    #![proptest_config(config(256))]

    /// A pressure closure with zero tangential velocity gives the node the prescribed density, the returned
    /// normal velocity and no tangential momentum, whatever the unknown populations held before, and agrees
    /// with the reference closure.
    #[test]
    fn zou_he_pressure_closures_impose_density_and_match_the_reference(
        f in near_equilibrium(),
        side in 0usize..4,
        rho in 0.8f64..1.2,
        garbage in proptest::array::uniform9(-1.0f64..1.0),
    ) {
        // The unknown populations are overwritten: start them from garbage.
        let unknown = reference::incoming(SIDES[side]);
        let mut g = f;
        for &i in &unknown {
            g[i] = garbage[i];
        }
        let mut r = g;
        let un = PRESSURE[side](&mut g, rho, 0.0);
        let ur = reference::zou_he_pressure(&mut r, SIDES[side], rho);
        for i in 0..Q {
            prop_assert!((g[i] - r[i]).abs() <= ORACLE, "f_{i}: {} vs {}", g[i], r[i]);
        }
        let n = if normal_is_x(side) { 0 } else { 1 };
        prop_assert!((un - ur[n]).abs() <= ORACLE);
        prop_assert!((density(&g) - rho).abs() <= ORACLE);
        let j = momentum(&g);
        prop_assert!((j[n] - rho * un).abs() <= ORACLE);
        prop_assert!(j[1 - n].abs() <= ORACLE, "tangential momentum {}", j[1 - n]);
    }

    /// A pressure closure with a tangential velocity gives the node that tangential momentum too.
    #[test]
    fn zou_he_pressure_closures_impose_the_tangential_velocity(
        f in near_equilibrium(),
        side in 0usize..4,
        rho in 0.8f64..1.2,
        ut in -0.1f64..0.1,
    ) {
        let mut g = f;
        let un = PRESSURE[side](&mut g, rho, ut);
        let n = if normal_is_x(side) { 0 } else { 1 };
        let j = momentum(&g);
        prop_assert!((density(&g) - rho).abs() <= ORACLE);
        prop_assert!((j[n] - rho * un).abs() <= ORACLE);
        prop_assert!((j[1 - n] - rho * ut).abs() <= ORACLE);
    }

    /// A velocity closure gives the node the prescribed velocity, returns its density, and agrees with the
    /// reference; an equilibrium node at that velocity is restored exactly (to roundoff).
    #[test]
    fn zou_he_velocity_closures_impose_velocity_and_match_the_reference(
        f in near_equilibrium(),
        side in 0usize..4,
        ux in -0.1f64..0.1,
        uy in -0.1f64..0.1,
        rho_eq in 0.8f64..1.2,
    ) {
        let u = [ux, uy];
        let mut g = f;
        let mut r = f;
        let rho = VELOCITY[side](&mut g, u);
        let rr = reference::zou_he_velocity(&mut r, SIDES[side], u);
        prop_assert!((rho - rr).abs() <= ORACLE);
        for i in 0..Q {
            prop_assert!((g[i] - r[i]).abs() <= ORACLE, "f_{i}: {} vs {}", g[i], r[i]);
        }
        prop_assert!((density(&g) - rho).abs() <= ORACLE);
        let j = momentum(&g);
        prop_assert!((j[0] - rho * ux).abs() <= ORACLE && (j[1] - rho * uy).abs() <= ORACLE);
        // Equilibrium in, equilibrium out.
        let eq = equilibrium::<f64>(rho_eq, u);
        let mut e = eq;
        for &i in &reference::incoming(SIDES[side]) {
            e[i] = 0.0;
        }
        let re = VELOCITY[side](&mut e, u);
        prop_assert!((re - rho_eq).abs() <= ORACLE);
        for i in 0..Q {
            prop_assert!((e[i] - eq[i]).abs() <= ORACLE);
        }
        let mut p = eq;
        let tangential = if normal_is_x(side) { uy } else { ux };
        let normal = PRESSURE[side](&mut p, rho_eq, tangential);
        let normal_expected = if normal_is_x(side) { ux } else { uy };
        prop_assert!((normal - normal_expected).abs() <= ORACLE);
        for i in 0..Q {
            prop_assert!((p[i] - eq[i]).abs() <= ORACLE);
        }
    }

    /// Guo's source equals the reference's, carries no mass and (1 − ω/2) F of momentum.
    #[test]
    fn guo_source_matches_the_reference_and_its_moments(
        tau in 0.51f64..2.0,
        ux in -0.2f64..0.2,
        uy in -0.2f64..0.2,
        fx in -1e-3f64..1e-3,
        fy in -1e-3f64..1e-3,
    ) {
        let s = guo_source(1.0 / tau, [ux, uy], [fx, fy]);
        let r = reference::guo_source(tau, [ux, uy], [fx, fy]);
        for i in 0..Q {
            prop_assert!((s[i] - r[i]).abs() <= ORACLE * 1e-3);
        }
        let pre = 1.0 - 0.5 / tau;
        let mass: f64 = s.iter().sum();
        let mut j = [0.0; 2];
        for (i, si) in s.iter().enumerate() {
            let c = velocity::<f64>(i);
            j[0] += si * c[0];
            j[1] += si * c[1];
        }
        // Sums of nine terms of size ≤ 1e-3: roundoff ~1e-18.
        prop_assert!(mass.abs() <= 1e-17);
        prop_assert!((j[0] - pre * fx).abs() <= 1e-17 && (j[1] - pre * fy).abs() <= 1e-17);
    }

    /// TRT: τ⁻ satisfies Λ = (τ⁺ − ½)(τ⁻ − ½); the unchecked rates are the checked ones, bitwise, and are
    /// 1/τ⁺ and 1/τ⁻ (BGK: both 1/τ).
    #[test]
    fn trt_rates_and_tau_minus_follow_the_magic_parameter(
        tau in 0.5001f64..5.0,
        magic in 1e-3f64..2.0,
    ) {
        let trt = Trt::new(magic).unwrap();
        let tm = trt.tau_minus(tau);
        prop_assert!(((tau - 0.5) * (tm - 0.5) - magic).abs() <= 1e-12 * magic.max(1.0));
        prop_assert_eq!(tm.to_bits(), reference::tau_minus(tau, magic).to_bits());
        for c in [Collision::Bgk, Collision::Trt(trt)] {
            let unchecked = c.rates_unchecked(tau);
            if let Ok(checked) = c.rates(tau) {
                prop_assert_eq!(checked.plus.to_bits(), unchecked.plus.to_bits());
                prop_assert_eq!(checked.minus.to_bits(), unchecked.minus.to_bits());
            }
            prop_assert_eq!(unchecked.plus, 1.0 / tau);
            let expected_minus = match c {
                Collision::Bgk => 1.0 / tau,
                Collision::Trt(_) => 1.0 / tm,
            };
            prop_assert_eq!(unchecked.minus, expected_minus);
        }
    }

    /// ΩΛ's weight: ε for the solid-fraction weighting; for Noble–Torczynski eq. 4.5 with τ − ½ replaced by
    /// √Λ, hence τ-free at fixed Λ, in [0, 1], 0 at ε = 0 and 1 at ε = 1, increasing in ε, and equal to the
    /// BGK weight when τ⁻ = τ⁺.
    #[test]
    fn lambda_weighting_is_free_of_tau_at_fixed_magic(
        eps in 0.0f64..=1.0,
        eps2 in 0.0f64..=1.0,
        tau1 in 0.51f64..3.0,
        tau2 in 0.51f64..3.0,
        magic in 0.01f64..1.0,
    ) {
        let trt = Trt::new(magic).unwrap();
        let rates = |tau: f64| Collision::Trt(trt).rates_unchecked(tau);
        prop_assert_eq!(lambda_weighting(Weighting::SolidFraction, eps, rates(tau1)), eps);
        let b1 = lambda_weighting(Weighting::NobleTorczynski, eps, rates(tau1));
        let b2 = lambda_weighting(Weighting::NobleTorczynski, eps, rates(tau2));
        let a = magic.sqrt();
        let expected = eps * a / ((1.0 - eps) + a);
        prop_assert!((b1 - expected).abs() <= ORACLE && (b2 - expected).abs() <= ORACLE);
        prop_assert!((0.0..=1.0 + ORACLE).contains(&b1));
        let (lo, hi) = if eps <= eps2 { (eps, eps2) } else { (eps2, eps) };
        prop_assert!(
            lambda_weighting(Weighting::NobleTorczynski, lo, rates(tau1))
                <= lambda_weighting(Weighting::NobleTorczynski, hi, rates(tau1))
        );
        // BGK rates: √Λ = τ − ½, the weighting of eq. 4.5.
        let bgk = Rates { plus: 1.0 / tau1, minus: 1.0 / tau1 };
        let nt = eps * (tau1 - 0.5) / ((1.0 - eps) + (tau1 - 0.5));
        prop_assert!((lambda_weighting(Weighting::NobleTorczynski, eps, bgk) - nt).abs() <= ORACLE);
    }

    /// ΩΛ's full-cover test is ε ≥ 1 − LAMBDA_FULL_GAP, in both precisions.
    #[test]
    fn lambda_full_cover_is_a_threshold_at_the_gap(
        eps in (1.0 - 2.0 * LAMBDA_FULL_GAP)..1.01f64,
        far in 0.0f64..(1.0 - 1.5 * LAMBDA_FULL_GAP),
    ) {
        prop_assert_eq!(lambda_fully_covered(eps), eps >= 1.0 - LAMBDA_FULL_GAP);
        prop_assert!(!lambda_fully_covered(far));
        prop_assert_eq!(lambda_fully_covered(eps as f32), eps as f32 >= 1.0f32 - LAMBDA_FULL_GAP as f32);
    }
}

#[test]
fn lambda_full_cover_holds_at_its_edge_and_not_below() {
    assert!(lambda_fully_covered(1.0f64));
    assert!(lambda_fully_covered(1.0f64 - LAMBDA_FULL_GAP));
    assert!(!lambda_fully_covered(
        (1.0f64 - LAMBDA_FULL_GAP).next_down()
    ));
    assert!(lambda_fully_covered(1.0f32 - LAMBDA_FULL_GAP as f32));
}

/// Every solid operator has its own name and symbol; `from_name` inverts `name` and refuses anything else.
#[test]
fn solid_operator_names_and_symbols_are_one_to_one() {
    let names: Vec<&str> = SolidOperator::ALL.iter().map(|o| o.name()).collect();
    let symbols: Vec<&str> = SolidOperator::ALL.iter().map(|o| o.symbol()).collect();
    for (k, op) in SolidOperator::ALL.iter().enumerate() {
        assert_eq!(SolidOperator::from_name(op.name()), Ok(*op));
        assert!(!op.symbol().is_empty());
        for j in 0..k {
            assert_ne!(names[j], names[k]);
            assert_ne!(symbols[j], symbols[k]);
        }
    }
    assert!(SolidOperator::from_name("no_such_operator").is_err());
    assert!(SolidOperator::from_name("").is_err());
}

/// The words of earlier scene files are refused, each with a hint naming the word to write instead (the scene
/// reader passes the message on; `driver/tests/scene_collision.rs` checks it through a scene file), and an
/// unknown word is answered with the list of every name.
#[test]
fn old_solid_operator_words_are_refused_with_the_new_name() {
    for (old, new) in [
        ("bounce_back", "non_equilibrium_bounce_back"),
        ("moving_wall", "moving_wall_bounce_back"),
        ("linearized", "linearized_non_equilibrium_bounce_back"),
        ("lambda", "lambda_consistent"),
        ("omega_lambda", "lambda_consistent"),
    ] {
        let msg = SolidOperator::from_name(old).expect_err(old);
        assert!(msg.contains(&format!("\"{new}\"")), "{old}: {msg}");
        assert!(
            !msg.starts_with("unknown"),
            "{old} gets the generic answer: {msg}"
        );
    }
    let msg = SolidOperator::from_name("no_such_operator").expect_err("unknown word");
    for op in SolidOperator::ALL {
        assert!(msg.contains(op.name()), "{} missing from: {msg}", op.name());
    }
}

/// A random lattice for the bulk/special/gather properties: populations near equilibrium, obstacle flags,
/// sides periodic or walls.
struct Lattice {
    shape: LatticeShape,
    bc: Boundaries<f64>,
    flags: Vec<u8>,
    f: Vec<[f64; Q]>,
}

fn splitmix(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

fn random_lattice(nx: usize, ny: usize, seed: u64, walls: [bool; 2], p_solid: f64) -> Lattice {
    let mut s = seed;
    let shape = LatticeShape::for_type::<f64>(nx, ny).unwrap();
    let side = |wall: bool| {
        if wall {
            SideCondition::Wall
        } else {
            SideCondition::Periodic
        }
    };
    let bc = Boundaries {
        west: side(walls[0]),
        east: side(walls[0]),
        south: side(walls[1]),
        north: side(walls[1]),
    };
    let flags = (0..nx * ny)
        .map(|_| {
            if splitmix(&mut s) < p_solid {
                SOLID
            } else {
                FLUID
            }
        })
        .collect();
    let f = (0..nx * ny)
        .map(|_| {
            let rho = 0.9 + 0.2 * splitmix(&mut s);
            let u = [0.2 * splitmix(&mut s) - 0.1, 0.2 * splitmix(&mut s) - 0.1];
            let eq = equilibrium::<f64>(rho, u);
            core::array::from_fn(|i| eq[i] * (1.0 + 0.1 * splitmix(&mut s) - 0.05))
        })
        .collect();
    Lattice {
        shape,
        bc,
        flags,
        f,
    }
}

fn to_buffer(shape: &LatticeShape, f: &[[f64; Q]]) -> Vec<f64> {
    let mut buf = vec![f64::NAN; shape.buffer_len()];
    for (n, fi) in f.iter().enumerate() {
        for q in 0..Q {
            buf[shape.offset(q, n)] = fi[q];
        }
    }
    buf
}

fn to_reference(l: &Lattice) -> (reference::Lattice, reference::Sides) {
    let cond = |c: SideCondition<f64>| match c {
        SideCondition::Wall => reference::Condition::Wall,
        _ => reference::Condition::Periodic,
    };
    let (nx, ny) = (l.shape.nx, l.shape.ny);
    let lat = reference::Lattice {
        nx,
        ny,
        f: l.f.clone(),
        solid: l.flags.iter().map(|&g| g == SOLID).collect(),
    };
    let sides = reference::Sides {
        west: cond(l.bc.west),
        east: cond(l.bc.east),
        south: cond(l.bc.south),
        north: cond(l.bc.north),
    };
    (lat, sides)
}

/// The in-place scheme's streamed layout of `l`'s populations, from its definition: node x's post-collision
/// P_i sits at (ī, x + c_i), or at (i, x) where x + c_i is solid or outside a side that is not periodic
/// (`periodic` = [along x, along y]). Obstacle nodes hold nothing that streams (NaN where nothing lands).
fn streamed_buffer(l: &Lattice, periodic: [bool; 2]) -> Vec<f64> {
    let shape = l.shape;
    let (nx, ny) = (shape.nx, shape.ny);
    let mut streamed = vec![f64::NAN; shape.buffer_len()];
    for y in 0..ny {
        for x in 0..nx {
            let n = shape.index(x, y);
            if l.flags[n] == SOLID {
                continue;
            }
            for q in 0..Q {
                let c = velocity::<f64>(q);
                let (tx, ty) = (x as i64 + c[0] as i64, y as i64 + c[1] as i64);
                let outside_x = !(0..nx as i64).contains(&tx) && !periodic[0];
                let outside_y = !(0..ny as i64).contains(&ty) && !periodic[1];
                let target = if outside_x || outside_y {
                    None
                } else {
                    let t = shape.index(
                        tx.rem_euclid(nx as i64) as usize,
                        ty.rem_euclid(ny as i64) as usize,
                    );
                    (l.flags[t] != SOLID).then_some(t)
                };
                match target {
                    Some(t) => {
                        streamed[shape.offset(lbdem_kernels::fluid::d2q9::OPPOSITE[q], t)] =
                            l.f[n][q]
                    }
                    None => streamed[shape.offset(q, n)] = l.f[n][q],
                }
            }
        }
    }
    streamed
}

/// A side condition for a side that is not periodic: a wall at rest, a moving wall, or a Zou–He pressure or
/// velocity side (mild values, so the closures stay well inside their range).
fn random_closed_side(s: &mut u64) -> SideCondition<f64> {
    let u = [0.1 * splitmix(s) - 0.05, 0.1 * splitmix(s) - 0.05];
    match (4.0 * splitmix(s)) as usize {
        0 => SideCondition::Wall,
        1 => SideCondition::MovingWall { velocity: u },
        2 => SideCondition::Pressure {
            density: 0.95 + 0.1 * splitmix(s),
        },
        _ => SideCondition::Velocity { velocity: u },
    }
}

const NO_PROFILES: SideProfiles<'static, f64> = SideProfiles {
    west: &[],
    east: &[],
    south: &[],
    north: &[],
};

proptest! {
    #![proptest_config(config(128))]

    /// `bulk_band` over random row bands, then `fix_special_nodes` with each band's special nodes, equals the
    /// reference step (push streaming with bounce-back, BGK or TRT with a body force) at every fluid node.
    #[test]
    fn bulk_band_with_fixed_special_nodes_matches_the_reference(
        nx in 1usize..=10,
        ny in 1usize..=10,
        seed in any::<u64>(),
        walls in any::<[bool; 2]>(),
        p_solid in prop_oneof![Just(0.0), 0.0f64..0.3],
        tau in 0.51f64..2.0,
        magic in prop_oneof![Just(None), (0.01f64..1.0).prop_map(Some)],
        force in prop_oneof![Just([0.0, 0.0]), [-1e-4f64..1e-4, -1e-4f64..1e-4]],
        cut in 0usize..=10,
    ) {
        let l = random_lattice(nx, ny, seed, walls, p_solid);
        let shape = l.shape;
        let src = to_buffer(&shape, &l.f);
        let collision = match magic {
            None => Collision::Bgk,
            Some(m) => Collision::Trt(Trt::new(m).unwrap()),
        };
        let params = FluidParams { tau, force };
        let domain = Domain { shape, bc: l.bc, profiles: NO_PROFILES, flags: &l.flags };
        let mut special = vec![0u32; shape.nodes()];
        let count = classify_special_nodes(&shape, &l.bc, &l.flags, &mut special);
        special.truncate(count);
        let cut = cut.min(ny);
        let mut dst = vec![f64::NAN; shape.buffer_len()];
        for (y0, y1) in [(0, cut), (cut, ny)] {
            if y0 == y1 {
                continue;
            }
            let mut band = band_mut(&shape, planes_mut(&shape, &mut dst), y0, y1);
            bulk_band(&shape, &src, &mut band, y0, y1, &params, &collision);
            fix_special_nodes(&domain, &src, &mut band, y0, &params, &collision,
                nodes_in_rows(&shape, &special, y0, y1));
        }
        let (lat, sides) = to_reference(&l);
        let rparams = reference::Params {
            tau,
            force,
            weighting: reference::Weighting::SolidFraction,
            magic,
            lambda_consistent: false,
            lambda_terms: (0.0, 0.0),
        };
        let (expected, _) = reference::step(&lat, &sides, &rparams, &[]);
        for n in 0..shape.nodes() {
            if l.flags[n] == SOLID {
                continue;
            }
            for q in 0..Q {
                let got = dst[shape.offset(q, n)];
                let want = expected.f[n][q];
                prop_assert!((got - want).abs() <= ORACLE, "node {n} q {q}: {got} vs {want}");
            }
        }
    }

    /// The in-place scheme's streamed layout: node x's post-collision P_i sits at (ī, x + c_i), or at (i, x)
    /// where x + c_i is solid or outside a wall side. Built here from that definition, `gather_node_in` on it
    /// gives, at every fluid node, bitwise what `gather_node_in` gives on the collided layout (the two-lattice
    /// gather, `gather_node`).
    #[test]
    fn gather_in_the_streamed_layout_is_the_collided_gather(
        nx in 1usize..=9,
        ny in 1usize..=9,
        seed in any::<u64>(),
        walls in any::<[bool; 2]>(),
        p_solid in prop_oneof![Just(0.0), 0.0f64..0.3],
    ) {
        let l = random_lattice(nx, ny, seed, walls, p_solid);
        let shape = l.shape;
        let collided = to_buffer(&shape, &l.f);
        let streamed = streamed_buffer(&l, [!walls[0], !walls[1]]);
        for y in 0..ny {
            for x in 0..nx {
                if l.flags[shape.index(x, y)] == SOLID {
                    continue;
                }
                let a = gather_node_in(&shape, &streamed, Layout::Streamed, &l.bc, &NO_PROFILES, &l.flags, x, y);
                let b = gather_node_in(&shape, &collided, Layout::Collided, &l.bc, &NO_PROFILES, &l.flags, x, y);
                let c = gather_node(&shape, &collided, &l.bc, &NO_PROFILES, &l.flags, x, y);
                for q in 0..Q {
                    prop_assert_eq!(a[q].to_bits(), b[q].to_bits(), "({}, {}) q {}", x, y, q);
                    prop_assert_eq!(b[q].to_bits(), c[q].to_bits());
                }
            }
        }
    }

    /// `gathered_densities` over any rows of a lattice with walls, moving walls, Zou–He sides and obstacles,
    /// in either layout of the in-place scheme: bitwise the density of `gather_node_in` (the general gather,
    /// itself checked against the reference above and in `fluid_properties.rs`) at every node that is not an
    /// obstacle, 1 at obstacles; and `wall_gradients` reading those densities gives bitwise what it gives
    /// gathering each node, for random covered nodes, shares, links and normals.
    #[test]
    fn gathered_densities_are_the_general_gathers_densities(
        nx in 1usize..=9,
        ny in 1usize..=9,
        seed in any::<u64>(),
        closed in any::<[bool; 2]>(),
        p_solid in prop_oneof![Just(0.0), 0.0f64..0.3],
        rows in any::<[usize; 2]>(),
    ) {
        let mut l = random_lattice(nx, ny, seed, [false; 2], p_solid);
        let mut s = seed ^ 0x5eed;
        let mut side = |c: bool| if c { random_closed_side(&mut s) } else { SideCondition::Periodic };
        l.bc = Boundaries { west: side(closed[0]), east: side(closed[0]), south: side(closed[1]), north: side(closed[1]) };
        // Opposite sides closed alike, each drawn on its own.
        let shape = l.shape;
        let collided = to_buffer(&shape, &l.f);
        let streamed = streamed_buffer(&l, [!closed[0], !closed[1]]);
        let mut special = vec![0u32; shape.nodes()];
        let count = classify_special_nodes(&shape, &l.bc, &l.flags, &mut special);
        special.truncate(count);
        let domain = Domain { shape, bc: l.bc, profiles: NO_PROFILES, flags: &l.flags };
        let (y0, y1) = {
            let (a, b) = (rows[0] % (ny + 1), rows[1] % (ny + 1));
            (a.min(b), a.max(b))
        };
        for (layout, buf) in [(Layout::Collided, &collided), (Layout::Streamed, &streamed)] {
            let mut out = vec![f64::NAN; (y1 - y0) * nx];
            gathered_densities(&domain, buf, layout, y0, y1, nodes_in_rows(&shape, &special, y0, y1), &mut out);
            for y in y0..y1 {
                for x in 0..nx {
                    let n = shape.index(x, y);
                    let want = if l.flags[n] == SOLID {
                        1.0
                    } else {
                        density(&gather_node_in(&shape, buf, layout, &l.bc, &NO_PROFILES, &l.flags, x, y))
                    };
                    prop_assert_eq!(out[(y - y0) * nx + x].to_bits(), want.to_bits(), "{:?} ({}, {})", layout, x, y);
                }
            }
            // The wall gradients from the whole lattice's densities against gathering node by node.
            let mut all = vec![f64::NAN; shape.nodes()];
            gathered_densities(&domain, buf, layout, 0, ny, &special, &mut all);
            let nodes: Vec<u32> = (0..shape.nodes() as u32).filter(|_| splitmix(&mut s) < 0.5).collect();
            let mut offsets = vec![0u32];
            let mut shares = Vec::new();
            let mut normals = Vec::new();
            for _ in &nodes {
                for _ in 0..1 + (2.0 * splitmix(&mut s)) as usize {
                    shares.push(SolidShare { fraction: 0.6 * splitmix(&mut s), velocity: [0.0; 2], wall_gradient: [f64::NAN; 2] });
                    let a = 2.0 * PI * splitmix(&mut s);
                    normals.push([a.cos(), a.sin()]);
                }
                offsets.push(shares.len() as u32);
            }
            // Open links as the driver finds them (obstacles and sides closed), some closed at random as full
            // cover would.
            let links: Vec<OpenLinks> = nodes
                .iter()
                .map(|&n| {
                    let (x, y) = shape.coords(n as usize);
                    open_links(&shape, &l.bc, &l.flags, x, y, |_| false) & (splitmix(&mut s) * 512.0) as OpenLinks
                })
                .collect();
            let mut by_buffer = shares.clone();
            wall_gradients(&domain, &nodes, &offsets, &links, &normals, &mut by_buffer, |n| all[n]);
            let mut by_gather = shares.clone();
            wall_gradients(&domain, &nodes, &offsets, &links, &normals, &mut by_gather, |n| {
                let (x, y) = shape.coords(n);
                density(&gather_node_in(&shape, buf, layout, &l.bc, &NO_PROFILES, &l.flags, x, y))
            });
            for (a, b) in by_buffer.iter().zip(&by_gather) {
                prop_assert_eq!(a.wall_gradient.map(f64::to_bits), b.wall_gradient.map(f64::to_bits));
                prop_assert!(a.wall_gradient.iter().all(|g| g.is_finite()));
            }
        }
    }

    /// `wrap_row(y, d, ny)` is (y + d) mod ny.
    #[test]
    fn wrap_row_is_periodic_addition(ny in 1usize..1000, y in 0usize..1000, d in -1i32..=1) {
        let y = y % ny;
        prop_assert_eq!(wrap_row(y, d, ny) as i64, (y as i64 + d as i64).rem_euclid(ny as i64));
    }

    /// perp turns by +90° (orthogonal, same length, positive cross product); norm is the Euclidean length
    /// without overflow; rotate_by(rotation(θ)) is rotate(θ), keeps lengths, turns by θ, and θ then −θ is the
    /// identity.
    #[test]
    fn vector_helpers_follow_their_algebra(
        ax in -10.0f64..10.0,
        ay in -10.0f64..10.0,
        theta in -7.0f64..7.0,
        huge in 1e200f64..1e300,
    ) {
        let a = vector(ax, ay);
        let p = perp(&a);
        let len = (ax * ax + ay * ay).sqrt();
        let tol = GEOMETRY * len.max(1e-300);
        prop_assert_eq!(p.dot(&a), ax * -ay + ay * ax);
        prop_assert!((norm(&p) - len).abs() <= tol);
        prop_assert!((norm(&a) - len).abs() <= tol);
        prop_assert!(a[0] * p[1] - a[1] * p[0] >= 0.0);
        // No overflow where the squares would.
        prop_assert!((norm(&vector(huge, huge)) / (huge * 2f64.sqrt()) - 1.0).abs() <= GEOMETRY);
        let r = rotate(&a, theta);
        let rb = rotate_by(&rotation(theta), &a);
        prop_assert_eq!(r[0].to_bits(), rb[0].to_bits());
        prop_assert_eq!(r[1].to_bits(), rb[1].to_bits());
        prop_assert!((norm(&r) - len).abs() <= 4.0 * tol);
        let expected = [ax * theta.cos() - ay * theta.sin(), ax * theta.sin() + ay * theta.cos()];
        prop_assert!((r[0] - expected[0]).abs() <= 4.0 * tol && (r[1] - expected[1]).abs() <= 4.0 * tol);
        let back = rotate(&r, -theta);
        prop_assert!((back[0] - ax).abs() <= 8.0 * tol && (back[1] - ay).abs() <= 8.0 * tol);
    }
}

proptest! {
    #![proptest_config(config(32))]

    /// Semi-axes of discs and ellipses; inertia per mass (a² + b²)/4 against a midpoint quadrature of r² over
    /// the ellipse (r²/2 for a disc).
    #[test]
    fn shape_inertia_per_mass_is_the_second_moment_of_area(a in 0.1f64..3.0, ratio in 0.1f64..=1.0) {
        let b = a * ratio;
        let ellipse = Shape::Ellipse { semi_major: a, semi_minor: b };
        prop_assert_eq!(ellipse.semi_axes(), (a, b));
        prop_assert_eq!(Shape::Disc { radius: a }.semi_axes(), (a, a));
        let n = 2000;
        let (hx, hy) = (2.0 * a / n as f64, 2.0 * b / n as f64);
        let (mut area, mut second) = (0.0, 0.0);
        for i in 0..n {
            let x = -a + (i as f64 + 0.5) * hx;
            for j in 0..n {
                let y = -b + (j as f64 + 0.5) * hy;
                if (x / a).powi(2) + (y / b).powi(2) <= 1.0 {
                    area += 1.0;
                    second += x * x + y * y;
                }
            }
        }
        // Midpoint rule on the indicator: the boundary cells (~4n of n²) bias both sums by O(1/n) = 5e-4.
        let quadrature = second / area;
        prop_assert!((ellipse.inertia_per_mass() / quadrature - 1.0).abs() <= 2e-3);
        let disc = Shape::Disc { radius: a };
        prop_assert!((disc.inertia_per_mass() - a * a / 2.0).abs() <= GEOMETRY * a * a);
    }

    /// The support point in direction n is the boundary point maximising n·x (dense search over the
    /// boundary), lies on the ellipse, and its outward normal there is n.
    #[test]
    fn support_point_maximises_the_projection(
        cx in -5.0f64..5.0,
        cy in -5.0f64..5.0,
        angle in -PI..PI,
        a in 0.1f64..3.0,
        ratio in 0.05f64..=1.0,
        dir in -PI..PI,
    ) {
        let b = a * ratio;
        let e = Placed::new(vector(cx, cy), angle, a, b);
        let n = vector(dir.cos(), dir.sin());
        let s = e.support_point(n);
        let (c, sn) = (angle.cos(), angle.sin());
        let point = |t: f64| {
            let (x, y) = (a * t.cos(), b * t.sin());
            vector(cx + c * x - sn * y, cy + sn * x + c * y)
        };
        let samples = 20_000;
        let best = (0..samples)
            .map(|k| point(2.0 * PI * k as f64 / samples as f64).dot(&n))
            .fold(f64::NEG_INFINITY, f64::max);
        // The search misses the maximum by at most a (Δt)²/2 with Δt = 2π/20 000.
        prop_assert!(s.dot(&n) >= best - 1e-9 * (1.0 + cx.abs() + cy.abs()));
        prop_assert!(s.dot(&n) <= best + a * (2.0 * PI / samples as f64).powi(2));
        let d = s - vector(cx, cy);
        let (u, v) = (c * d[0] + sn * d[1], -sn * d[0] + c * d[1]);
        prop_assert!(((u / a).powi(2) + (v / b).powi(2) - 1.0).abs() <= 1e-12);
    }

    /// Disc–wall contact: the overlap is r minus the centre's distance to the wall line, the normal points from
    /// the disc into the wall, and the two surface points lie on the disc and on the wall.
    #[test]
    fn disc_wall_contact_is_radius_minus_distance(
        cx in -5.0f64..5.0,
        cy in -5.0f64..5.0,
        r in 0.01f64..2.0,
        px in -5.0f64..5.0,
        py in -5.0f64..5.0,
        angle in -PI..PI,
    ) {
        let wall = Wall::from_angle(vector(px, py), angle);
        let nrm = vector(angle.cos(), angle.sin());
        let distance = (cx - px) * nrm[0] + (cy - py) * nrm[1];
        let c = disc_wall(vector(cx, cy), r, &wall);
        let tol = 1e-12 * (1.0 + distance.abs() + r);
        prop_assert!((c.overlap - (r - distance)).abs() <= tol);
        prop_assert!((c.normal[0] + nrm[0]).abs() <= 1e-15 && (c.normal[1] + nrm[1]).abs() <= 1e-15);
        prop_assert!((norm(&(c.point_i - vector(cx, cy))) - r).abs() <= tol);
        prop_assert!(wall.signed_distance(c.point_j).abs() <= tol);
        prop_assert_eq!(c.is_active(), r - distance > 0.0 || c.overlap > 0.0);
    }

    /// c_n = 2ζ√(m k) damps a linear oscillator m ẍ + c ẋ + k x = 0 at the ratio ζ: its free decay over one
    /// period (integrated here by RK4) is exp(−2πζ/√(1 − ζ²)).
    #[test]
    fn normal_damping_gives_the_damping_ratio(zeta in 0.01f64..0.7, m in 0.1f64..10.0, k in 1.0f64..1e4) {
        let c = normal_damping_coefficient(zeta, m, k);
        prop_assert!((c - 2.0 * zeta * (m * k).sqrt()).abs() <= GEOMETRY * c);
        let wd = (k / m).sqrt() * (1.0 - zeta * zeta).sqrt();
        let period = 2.0 * PI / wd;
        let steps = 20_000;
        let h = period / steps as f64;
        let acc = |x: f64, v: f64| -(c * v + k * x) / m;
        // Start at a maximum of the envelope-scaled solution: x = 1, v = −ζω₀ (so x(t) = e^{−ζω₀t} cos(ω_d t)).
        let (mut x, mut v) = (1.0, -zeta * (k / m).sqrt());
        for _ in 0..steps {
            let (k1x, k1v) = (v, acc(x, v));
            let (k2x, k2v) = (v + 0.5 * h * k1v, acc(x + 0.5 * h * k1x, v + 0.5 * h * k1v));
            let (k3x, k3v) = (v + 0.5 * h * k2v, acc(x + 0.5 * h * k2x, v + 0.5 * h * k2v));
            let (k4x, k4v) = (v + h * k3v, acc(x + h * k3x, v + h * k3v));
            x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
            v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        }
        let expected = (-2.0 * PI * zeta / (1.0 - zeta * zeta).sqrt()).exp();
        // RK4 with 20 000 steps per period: error ~ (h ω)⁴ ≈ 1e-14 per step, far below 1e-8.
        prop_assert!((x - expected).abs() <= 1e-8, "{x} vs {expected}");
    }

    /// A parallel bond's peak shear stress is |F̄_s| over its area 2R̄ (per unit thickness), whatever the sign.
    #[test]
    fn bond_peak_shear_stress_is_force_over_area(
        ri in 0.1f64..2.0,
        rj in 0.1f64..2.0,
        lambda in 0.1f64..1.0,
        fs in -1e3f64..1e3,
    ) {
        let mut bond = ParallelBond::new(ri, rj, lambda, 1e6, 4e5, 1e3, 1e3);
        bond.shear_force = fs;
        let area = 2.0 * lambda * ri.min(rj);
        prop_assert!((bond.max_shear_stress() - fs.abs() / area).abs() <= GEOMETRY * fs.abs() / area + 1e-300);
        bond.shear_force = -fs;
        prop_assert!((bond.max_shear_stress() - fs.abs() / area).abs() <= GEOMETRY * fs.abs() / area + 1e-300);
    }

    /// The bonded critical step accepts scratch of exactly `bonded_critical_time_step_scratch_len` and refuses
    /// one entry less (nothing else is needed, nothing less will do).
    #[test]
    fn bonded_critical_step_scratch_length_is_exact(n in 1usize..40, seed in any::<u64>()) {
        let mut s = seed;
        let model = ContactModel {
            normal_stiffness: 1e5f64,
            shear_stiffness: 4e4,
            friction: 0.5,
            restitution: 0.5,
            no_tension: true,
        };
        let particles: Vec<Particle<f64>> = (0..n)
            .map(|i| Particle::disc(vector(i as f64, splitmix(&mut s)), 0.3 + 0.2 * splitmix(&mut s), 2.0))
            .collect();
        let bonds: Vec<Bond<f64>> = (1..n)
            .map(|j| Bond {
                pair: [j - 1, j],
                law: BondLaw::Point(PointBond::between(&particles[j - 1], &particles[j], 1e5, 50.0)),
            })
            .collect();
        let len = bonded_critical_time_step_scratch_len(n);
        let (mut kt, mut kr) = (vec![0.0; len], vec![0.0; len]);
        let dt = model.bonded_critical_time_step(&particles, &bonds, 4.0, &mut kt, &mut kr);
        prop_assert!(matches!(dt, Ok(t) if t.is_finite() && t > 0.0));
        let short = model.bonded_critical_time_step(&particles, &bonds, 4.0, &mut kt[..len - 1], &mut kr);
        prop_assert_eq!(short, Err(AssemblyError::BufferLength));
    }
}

/// Every `pub fn` of `kernels/src` is named in at least one property file of this crate
/// (`verification/tests/*_properties.rs`) or proof harness (`verification/src/harness/`): a new public
/// kernel function without a property test fails here.
#[test]
fn every_public_kernel_function_is_named_by_a_property_test() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    fn rust_files(dir: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() {
                rust_files(&p, out);
            } else if p.extension().is_some_and(|e| e == "rs") {
                out.push(p);
            }
        }
    }
    let mut kernel_files = Vec::new();
    rust_files(&root.join("../kernels/src"), &mut kernel_files);
    let mut names = std::collections::BTreeSet::new();
    for file in &kernel_files {
        let text = std::fs::read_to_string(file).unwrap();
        // Only the library's own code, not its `#[cfg(test)] mod tests`.
        let code = text.split("#[cfg(test)]").next().unwrap_or("");
        for line in code.lines() {
            let t = line.trim_start();
            let rest = t
                .strip_prefix("pub fn ")
                .or_else(|| t.strip_prefix("pub const fn "))
                .or_else(|| t.strip_prefix("pub unsafe fn "));
            if let Some(rest) = rest {
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                names.insert((name, file.clone()));
            }
        }
    }
    assert!(
        names.len() > 100,
        "found only {} public functions: parser broken?",
        names.len()
    );
    let mut property_text = String::new();
    let mut test_files = Vec::new();
    rust_files(&root.join("tests"), &mut test_files);
    rust_files(&root.join("src/harness"), &mut test_files);
    for f in test_files {
        let name = f.file_name().unwrap().to_string_lossy().to_string();
        if name.ends_with("_properties.rs") || f.to_string_lossy().contains("harness") {
            property_text.push_str(&std::fs::read_to_string(&f).unwrap());
            property_text.push('\n');
        }
    }
    let is_word = |c: char| c.is_alphanumeric() || c == '_';
    let named = |name: &str| {
        property_text.match_indices(name).any(|(i, _)| {
            let before = property_text[..i].chars().next_back();
            let after = property_text[i + name.len()..].chars().next();
            !before.is_some_and(is_word) && !after.is_some_and(is_word)
        })
    };
    let missing: Vec<String> = names
        .iter()
        .filter(|(n, _)| !named(n))
        .map(|(n, f)| format!("{n} ({})", f.display()))
        .collect();
    assert!(
        missing.is_empty(),
        "public kernel functions named by no property test: {missing:?}"
    );
}

/// Spectral radius of the central-difference amplification matrix of m ẍ = −k x − c ẋ with the dashpot on
/// the lagged half-step velocity (v⁺ = v + h(−k x − c v)/m, x⁺ = x + h v⁺): the stability oracle for the
/// limits below, written from the scheme, not from the closed form.
fn central_difference_radius(omega: f64, zeta: f64, h: f64) -> f64 {
    let (k, c) = (omega * omega, 2.0 * zeta * omega); // per unit mass
    let a = [[1.0 - h * h * k, h * (1.0 - h * c)], [-h * k, 1.0 - h * c]];
    let (tr, det) = (a[0][0] + a[1][1], a[0][0] * a[1][1] - a[0][1] * a[1][0]);
    let disc = tr * tr / 4.0 - det;
    if disc >= 0.0 {
        let r = disc.sqrt();
        (tr / 2.0 + r).abs().max((tr / 2.0 - r).abs())
    } else {
        det.abs().sqrt()
    }
}

proptest! {
    #![proptest_config(config(256))]

    /// The stability limits 2√(m/k) and 2(√(1 + ζ²) − ζ)/ω bound the central-difference scheme: 1 % below,
    /// its amplification matrix has spectral radius ≤ 1; 1 % above, > 1. The PFC per-particle step is half the
    /// smaller single-degree-of-freedom limit (+∞ without stiffness); `exceeds_critical_time_step` is its
    /// definition, NaN and non-positive steps exceeding.
    #[test]
    fn stability_limits_bound_the_central_difference_scheme(
        m in 1e-3f64..1e3,
        k in 1e-2f64..1e6,
        zeta in 0.0f64..0.9,
        inertia in 1e-4f64..1e2,
        kr in prop_oneof![Just(0.0), 1e-2f64..1e4],
        kt in prop_oneof![Just(0.0), 1e-2f64..1e6],
        safety in 0.1f64..1.0,
    ) {
        let omega = (k / m).sqrt();
        let undamped = single_dof_stability_limit(m, k);
        let damped = damped_stability_limit(m, k, zeta);
        prop_assert!((damped_stability_limit(m, k, 0.0) - undamped).abs() <= GEOMETRY * undamped);
        for (limit, z) in [(undamped, 0.0), (damped, zeta)] {
            // Eigenvalues near −1 at the limit: 1 % off moves the radius by ~(1 % · hω)² ≥ 1e-6, far above
            // the 1e-12 roundoff of the 2 × 2 eigenvalues.
            prop_assert!(central_difference_radius(omega, z, 0.99 * limit) <= 1.0 + 1e-12);
            prop_assert!(central_difference_radius(omega, z, 1.01 * limit) > 1.0);
        }
        let critical = particle_critical_time_step(m, kt, inertia, kr);
        let half = |mass: f64, stiff: f64| {
            if stiff > 0.0 { single_dof_stability_limit(mass, stiff) / 2.0 } else { f64::INFINITY }
        };
        let expected = half(m, kt).min(half(inertia, kr));
        prop_assert!(critical == expected || (critical - expected).abs() <= GEOMETRY * expected);
        let dt = 0.5 * undamped;
        prop_assert_eq!(exceeds_critical_time_step(dt, undamped, safety), dt > safety * undamped);
        prop_assert!(exceeds_critical_time_step(f64::NAN, undamped, safety));
        prop_assert!(exceeds_critical_time_step(0.0, undamped, safety));
        prop_assert!(exceeds_critical_time_step(-dt, undamped, safety));
    }

    /// A head-on collision under the linear spring–dashpot law `with_restitution(e, m*)` (integrated here by
    /// RK4 in the relative coordinate of two masses m_i, m_j, reduced to m* = `effective_mass`) lasts
    /// `contact_duration` and leaves with e times the approach speed (no-tension clip off, so the dashpot's
    /// analytic solution holds to the end); m* is the two-body reduced mass, and a wall's infinite mass leaves
    /// the other.
    #[test]
    fn a_damped_collision_lasts_the_contact_duration_with_restitution_e(
        mi in 0.1f64..10.0,
        mj in 0.1f64..10.0,
        k in 1e2f64..1e5,
        e in 0.2f64..1.0,
        v0 in 0.1f64..10.0,
    ) {
        let m = effective_mass(mi, mj);
        prop_assert!((1.0 / m - (1.0 / mi + 1.0 / mj)).abs() <= GEOMETRY / m);
        prop_assert_eq!(effective_mass(f64::INFINITY, mj), mj);
        prop_assert_eq!(effective_mass(mi, f64::INFINITY), mi);
        let law = ContactLaw::elastic(k, 0.4 * k, 0.5).with_restitution(e, m);
        let zeta = damping_ratio_from_restitution(e);
        let duration = contact_duration(k, m, zeta);
        // Overlap δ(t): m δ'' = −k δ − c δ', δ(0) = 0, δ'(0) = v0; contact ends when δ returns to 0.
        let steps = 20_000;
        let h = 1.5 * duration / steps as f64;
        let acc = |x: f64, v: f64| -(k * x + law.normal_damping * v) / m;
        let (mut x, mut v, mut t) = (0.0f64, v0, 0.0);
        let mut ended = None;
        for _ in 0..steps {
            let (k1x, k1v) = (v, acc(x, v));
            let (k2x, k2v) = (v + 0.5 * h * k1v, acc(x + 0.5 * h * k1x, v + 0.5 * h * k1v));
            let (k3x, k3v) = (v + 0.5 * h * k2v, acc(x + 0.5 * h * k2x, v + 0.5 * h * k2v));
            let (k4x, k4v) = (v + h * k3v, acc(x + h * k3x, v + h * k3v));
            let (nx, nv) = (
                x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
                v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
            );
            if t > 0.0 && nx <= 0.0 {
                // Linear interpolation of the crossing: error O(h²) of a smooth δ.
                let s = x / (x - nx);
                ended = Some((t + s * h, v + s * (nv - v)));
                break;
            }
            (x, v, t) = (nx, nv, t + h);
        }
        let (t_end, v_end) = ended.expect("the contact ends within 1.5 contact durations");
        // Step 7.5e-5 of the duration: the crossing interpolation's O(h²) error is ~1e-8 relative.
        prop_assert!((t_end / duration - 1.0).abs() <= 1e-6, "{t_end} vs {duration}");
        prop_assert!((-v_end / v0 - e).abs() <= 1e-6, "restitution {} vs {e}", -v_end / v0);
    }

    /// Eq. 2.2's stiffnesses: the stiffness ratios are the given ones, the contact stiffness 2E_c does not
    /// depend on the radii, and a parallel bond stretched by δ across the distance R_a + R_b of its centres
    /// carries the stress k̄_n δ = Ē_c δ/(R_a + R_b): its modulus is the bond modulus.
    #[test]
    fn bonded_particle_stiffness_reproduces_the_moduli(
        ec in 1e3f64..1e10,
        ratio in 1.0f64..5.0,
        ebar in 1e3f64..1e10,
        ratio_bar in 1.0f64..5.0,
        ra in 0.01f64..1.0,
        rb in 0.01f64..1.0,
        delta in 1e-6f64..1e-3,
    ) {
        let s = BondedParticleStiffness::from_moduli(ec, ratio, ebar, ratio_bar, ra, rb);
        prop_assert!((s.normal / s.shear - ratio).abs() <= GEOMETRY * ratio);
        prop_assert!((s.bond_normal / s.bond_shear - ratio_bar).abs() <= GEOMETRY * ratio_bar);
        let other = BondedParticleStiffness::from_moduli(ec, ratio, ebar, ratio_bar, 2.0 * ra, 3.0 * rb);
        prop_assert_eq!(other.normal, s.normal);
        prop_assert!((s.normal - 2.0 * ec).abs() <= GEOMETRY * s.normal);
        let stress = s.bond_normal * delta;
        let strain = delta / (ra + rb);
        prop_assert!((stress / strain / ebar - 1.0).abs() <= GEOMETRY);
    }
}

proptest! {
    #![proptest_config(config(256))]

    /// The batch class of a covered node, against its definition: one share with ε > 0 (NaN and ε ≤ 0
    /// excluded), under ΩΛ split at 1 − LAMBDA_FULL_GAP, every other operator one class; several shares or
    /// none: no class.
    #[test]
    fn lane_class_follows_the_share_count_fraction_and_operator(
        eps in prop_oneof![Just(f64::NAN), Just(0.0), Just(-0.0), -0.5f64..1.5, 0.998f64..1.0],
        extra in 0usize..3,
        op in 0usize..5,
    ) {
        let solid = SolidOperator::ALL[op];
        let params = PsmParams {
            tau: 0.8,
            weighting: solid.weighting(),
            force: [0.0; 2],
            solid,
            collision: Collision::Bgk,
            lambda: Default::default(),
        };
        let share = SolidShare { fraction: eps, velocity: [0.01, -0.02], wall_gradient: Default::default() };
        let shares = vec![share; 1 + extra];
        let expected = if extra > 0 || eps.is_nan() || eps <= 0.0 {
            None
        } else if solid != SolidOperator::LambdaConsistent {
            Some(LaneClass::Operator)
        } else if eps >= 1.0 - LAMBDA_FULL_GAP {
            Some(LaneClass::LambdaFull)
        } else {
            Some(LaneClass::LambdaPartial)
        };
        prop_assert_eq!(lane_class(&params, &shares), expected);
        prop_assert_eq!(lane_class(&params, &[]), None);
    }
}
