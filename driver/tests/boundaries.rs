//! Boundaries through `FluidLattice`: a wall sliding along itself (half-way bounce-back with
//! Ladd's correction) against Couette flow, a Zou–He velocity side with a per-node profile against an imposed
//! parabola, the pressure–pressure channel at high τ (BGK's Λ-dependent error bounded, gone with TRT), bad
//! profiles refused, the new sides bitwise identical across streaming schemes, SIMD levels and threads, and a
//! radiating drained side that lets a sound pulse out where a pressure side sends it back.
use lbdem::engine::exec::SimdLevel;
use lbdem::engine::lattice::{FluidLattice, RadiatingSide, Streaming};
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::{Collision, Trt};
use lbdem_kernels::fluid::lattice::Side;
use lbdem_kernels::fluid::step::FluidParams;

fn trt() -> Collision<f64> {
    Collision::Trt(Trt::new(3.0 / 16.0).unwrap())
}

fn run(l: &mut FluidLattice<f64>, steps: u64) {
    for _ in 0..steps {
        l.step();
    }
}

#[test]
fn couette_between_a_moving_wall_and_a_wall_at_rest_is_linear_at_every_tau() {
    let (h, u_wall) = (12usize, 0.02);
    for tau in [0.6, 1.5] {
        for collision in [Collision::Bgk, trt()] {
            let bc = Boundaries {
                west: SideCondition::Periodic,
                east: SideCondition::Periodic,
                south: SideCondition::Wall,
                north: SideCondition::MovingWall {
                    velocity: [u_wall, 0.0],
                },
            };
            let mut l = FluidLattice::new(
                3,
                h,
                bc,
                FluidParams {
                    tau,
                    force: [0.0; 2],
                },
            )
            .unwrap();
            l.set_collision(collision).unwrap();
            let nu = (tau - 0.5) / 3.0;
            // 40 e-foldings of the slowest mode H²/(π²ν).
            run(&mut l, (40.0 * (h * h) as f64 / (9.87 * nu)) as u64);
            let (_, u) = l.moments();
            for y in 0..h {
                // Walls half a spacing outside the edge nodes: u = U (y + ½)/H, exact for half-way bounce-back
                // (a linear profile has no second derivative for the Λ-dependent slip to act on); left: the
                // e^{−40} transient and roundoff, so 1e-9 U.
                let exact = u_wall * (y as f64 + 0.5) / h as f64;
                let got = u[3 * y + 1];
                assert!(
                    (got[0] - exact).abs() < 1e-9 * u_wall && got[1].abs() < 1e-9 * u_wall,
                    "τ = {tau} {collision:?} y = {y}: {got:?} vs {exact}"
                );
            }
        }
    }
}

#[test]
fn a_parabolic_velocity_profile_at_the_inlet_gives_the_poiseuille_channel() {
    // West: Zou–He velocity with the Poiseuille parabola for walls half a spacing outside the edge nodes;
    // east: Zou–He pressure; walls north and south. With TRT at Λ = 3/16 the parabola with half-way walls is
    // the exact steady solution, so the channel must carry its shape all along.
    let (h, nx, tau) = (10usize, 61usize, 0.9);
    let u_max = 0.01 / 3f64.sqrt();
    let parabola = |y: usize| {
        let s = (y as f64 + 0.5) / h as f64;
        4.0 * u_max * s * (1.0 - s)
    };
    let bc = Boundaries {
        west: SideCondition::VelocityProfile,
        east: SideCondition::Pressure { density: 1.0 },
        south: SideCondition::Wall,
        north: SideCondition::Wall,
    };
    let mut l = FluidLattice::new(
        nx,
        h,
        bc,
        FluidParams {
            tau,
            force: [0.0; 2],
        },
    )
    .unwrap();
    l.set_collision(trt()).unwrap();
    let profile: Vec<[f64; 2]> = (0..h).map(|y| [parabola(y), 0.0]).collect();
    l.set_side_profile(Side::West, &profile).unwrap();
    let nu = (tau - 0.5) / 3.0;
    // Viscous modes (H²/(π²ν)) and the acoustic adjustment of the density along the channel (slowest; measured
    // mass-flux imbalance 6e-5 after 40 crossings, ≤ 1e-6 after 400).
    run(
        &mut l,
        (30.0 * (h * h) as f64 / (9.87 * nu)) as u64 + 400 * nx as u64,
    );
    let (rho, u) = l.moments();
    // The lattice fluid is weakly compressible: the pressure that drives the flow makes the density fall by
    // 3 G L ≈ 1.1 % from inlet to outlet, and the mass flux ρu, not u, is what the channel carries on. So the
    // check is on the shape of the profile, u(y)/u(centre), and on the mass flux ρu against the inlet's.
    let flux = |x: usize| {
        (0..h)
            .map(|y| rho[y * nx + x] * u[y * nx + x][0])
            .sum::<f64>()
    };
    // Measured shape deviations: 6.9e-5 next to the inlet, 5.5e-6 at the mid-section (Ma² = 1e-4 bounds both),
    // 4.7e-4 next to the pressure outlet (its closure imposes u_y = 0 and a uniform density on the last column):
    // bounds 1e-4, 1e-4, 1e-3.
    for (x, bound) in [(1, 1e-4), (nx / 2, 1e-4), (nx - 2, 1e-3)] {
        let c = u[(h / 2) * nx + x][0] / parabola(h / 2);
        let dev = (0..h)
            .map(|y| (u[y * nx + x][0] / c - parabola(y)).abs() / u_max)
            .fold(0.0, f64::max);
        assert!(dev < bound, "x = {x}: shape deviation {dev:e} u_max");
        let f = flux(x) / flux(0) - 1.0;
        // Steady to ≤ 1e-6 after the steps run (a wrong inlet closure would be off by ≥ 1e-3).
        assert!(f.abs() < 1e-5, "x = {x}: mass flux {f:e} off the inlet's");
    }
    // The inlet nodes hold their prescribed velocity exactly (Zou–He).
    for y in 1..h - 1 {
        assert!((u[y * nx][0] - parabola(y)).abs() < 1e-14);
    }
}

/// Largest deviation, relative to the centreline parabola velocity, of the mid-section of a pressure–pressure
/// channel (`h` nodes wide, 8h + 1 long, centreline Mach 0.01) from parabola + Λ-slip with the imposed
/// gradient; and the mid-section gradient over the imposed one.
fn pressure_channel(tau: f64, collision: Collision<f64>, h: usize) -> (f64, f64) {
    let nx = 8 * h + 1;
    let nu = (tau - 0.5) / 3.0;
    let umax = 0.01 / 3f64.sqrt();
    let dp = 8.0 * nu * umax / (h * h) as f64 * (nx - 1) as f64;
    let drho = 3.0 * dp;
    let bc = Boundaries {
        west: SideCondition::Pressure {
            density: 1.0 + drho / 2.0,
        },
        east: SideCondition::Pressure {
            density: 1.0 - drho / 2.0,
        },
        south: SideCondition::Wall,
        north: SideCondition::Wall,
    };
    let mut l = FluidLattice::new(
        nx,
        h,
        bc,
        FluidParams {
            tau,
            force: [0.0; 2],
        },
    )
    .unwrap();
    l.set_collision(collision).unwrap();
    l.fill_equilibrium(|x, _| {
        (
            1.0 + drho / 2.0 - drho * x as f64 / (nx - 1) as f64,
            [0.0; 2],
        )
    });
    run(
        &mut l,
        (35.0 * (h * h) as f64 / (9.87 * nu)) as u64 + 40 * nx as u64 + 2000,
    );
    let (rho, u) = l.moments();
    let xm = nx / 2;
    let g = dp / (nx - 1) as f64;
    let lambda = match collision {
        Collision::Bgk => (tau - 0.5) * (tau - 0.5),
        Collision::Trt(t) => t.magic(),
    };
    let slip = g / nu * (16.0 * lambda - 3.0) / 24.0;
    let centre = g / (2.0 * nu) * (h as f64 / 2.0).powi(2);
    let worst = (0..h)
        .map(|y| {
            let s = y as f64 + 0.5;
            (u[y * nx + xm][0] - (g / (2.0 * nu) * s * (h as f64 - s) + slip)).abs() / centre
        })
        .fold(0.0, f64::max);
    let mean_p = |x: usize| (0..h).map(|y| rho[y * nx + x]).sum::<f64>() / (3.0 * h as f64);
    let local = -(mean_p(xm + 1) - mean_p(xm - 1)) / 2.0;
    (worst, local / g)
}

#[test]
fn the_pressure_channel_error_at_high_tau_is_bgks_and_trt_removes_it() {
    // Cause (measured): with BGK at Λ = (τ − ½)² ≠ 3/16 the bounce-back walls slip by (16Λ − 3)/24 g/ν, and at
    // the two Zou–He pressure ends the wall nodes' slip changes the pressure drop the ends take: the interior
    // gradient falls short of the imposed one by a relative 1.2e-3 at τ = 1.37, H = 9 (1.8e-4 at H = 17, ∝ 1/H²),
    // and the mid-section profile with it. With TRT at Λ = 3/16 the walls do not slip, the ends take the drop
    // they should (gradient within 1e-4 of the imposed one) and the profile is parabola + slip to 1e-5.
    let (bgk, bgk_g) = pressure_channel(1.37, Collision::Bgk, 9);
    let (trt_dev, trt_g) = pressure_channel(1.37, trt(), 9);
    eprintln!(
        "τ = 1.37, H = 9: BGK {bgk:.3e} (gradient ×{bgk_g:.5}), TRT {trt_dev:.3e} (×{trt_g:.5})"
    );
    // Bound on BGK's error (measured 1.30e-3): fails if it grows.
    assert!(bgk < 2e-3, "BGK {bgk:e}");
    assert!((bgk_g - 1.0).abs() < 2e-3, "BGK gradient ×{bgk_g}");
    // TRT: measured 6e-6 (the velocity-inlet level of the issue, 7e-6).
    assert!(trt_dev < 3e-5, "TRT {trt_dev:e}");
    assert!((trt_g - 1.0).abs() < 2e-4, "TRT gradient ×{trt_g}");
}

#[test]
fn bad_profiles_are_refused_with_the_field_named() {
    let bc = Boundaries {
        west: SideCondition::VelocityProfile,
        east: SideCondition::Pressure { density: 1.0 },
        south: SideCondition::Wall,
        north: SideCondition::Wall,
    };
    let mut l = FluidLattice::new(
        8,
        5,
        bc,
        FluidParams {
            tau: 0.8,
            force: [0.0; 2],
        },
    )
    .unwrap();
    let e = l
        .set_side_profile(Side::West, &[[0.0; 2]; 4])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("boundary.west.profile") && e.contains("give 5"),
        "{e}"
    );
    let e = l
        .set_side_profile(Side::West, &[[0.0, f64::NAN]; 5])
        .unwrap_err()
        .to_string();
    assert!(e.contains("boundary.west.profile"), "{e}");
    let e = l
        .set_side_profile(Side::East, &[[0.0; 2]; 5])
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a velocity-profile side"), "{e}");
    l.set_side_profile(Side::West, &[[0.01, 0.0]; 5]).unwrap();
    // A wall moving through itself is refused when the lattice is built.
    let normal = Boundaries {
        north: SideCondition::MovingWall {
            velocity: [0.0, 0.01],
        },
        ..bc
    };
    assert!(FluidLattice::new(
        8,
        5,
        normal,
        FluidParams {
            tau: 0.8,
            force: [0.0; 2]
        }
    )
    .is_err());
}

#[test]
fn moving_walls_and_profiles_are_bitwise_identical_across_schemes_levels_and_threads() {
    let make = || {
        let bc = Boundaries {
            west: SideCondition::VelocityProfile,
            east: SideCondition::Pressure { density: 0.995 },
            south: SideCondition::MovingWall {
                velocity: [0.01, 0.0],
            },
            north: SideCondition::Wall,
        };
        let mut l = FluidLattice::new(
            67,
            13,
            bc,
            FluidParams {
                tau: 0.7,
                force: [1e-6, 0.0],
            },
        )
        .unwrap();
        l.set_collision(trt()).unwrap();
        let p: Vec<[f64; 2]> = (0..13).map(|y| [0.001 * y as f64, 0.0005]).collect();
        l.set_side_profile(Side::West, &p).unwrap();
        l.set_solid(|x, y| (x + 2 * y).is_multiple_of(23));
        l
    };
    let mut reference: Option<Vec<u64>> = None;
    for level in SimdLevel::ALL.into_iter().filter(|l| l.available()) {
        for streaming in Streaming::ALL {
            for (threads, band) in [(1, 13), (2, 3)] {
                let mut l = make();
                l.set_simd(level).unwrap();
                l.set_streaming(streaming);
                l.set_band_rows(band);
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                for _ in 0..23 {
                    pool.install(|| l.step());
                }
                let s: Vec<u64> = l.populations().iter().map(|v| v.to_bits()).collect();
                assert!(s.iter().all(|b| f64::from_bits(*b).is_finite()));
                match &reference {
                    None => reference = Some(s),
                    Some(r) => assert!(*r == s, "{level:?} {streaming:?} {threads}"),
                }
            }
        }
    }
}

/// A column periodic in x with a wall at the south and a pressure side (ρ = 1) at the north, held as a radiating
/// side with running-mean rate `rate` when given.
fn column(ny: usize, south: SideCondition<f64>) -> FluidLattice<f64> {
    let mut l = FluidLattice::new(
        4,
        ny,
        Boundaries {
            west: SideCondition::Periodic,
            east: SideCondition::Periodic,
            south,
            north: SideCondition::Pressure { density: 1.0 },
        },
        FluidParams {
            tau: 0.51,
            force: [0.0; 2],
        },
    )
    .unwrap();
    l.set_collision(trt()).unwrap();
    l
}

fn step_column(l: &mut FluidLattice<f64>, radiating: &mut Option<RadiatingSide>, steps: u64) {
    for _ in 0..steps {
        if let Some(r) = radiating {
            l.radiate(Side::North, r).unwrap();
        }
        l.step();
    }
}

/// Acoustic energy of the column, Σ (c_s² ρ′² + u²)/2 (ρ₀ = 1).
fn acoustic_energy(l: &FluidLattice<f64>) -> f64 {
    let (rho, u) = l.moments();
    rho.iter()
        .zip(&u)
        .map(|(r, v)| ((r - 1.0) * (r - 1.0) / 3.0 + v[0] * v[0] + v[1] * v[1]) / 2.0)
        .sum()
}

/// Energy left in the column, over the initial energy, once a plane pulse travelling north from the middle
/// has had time to reach the north side and come back to the middle.
fn pulse_round_trip(rate: Option<f64>) -> f64 {
    let ny = 240;
    let mut l = column(ny, SideCondition::Wall);
    let (amplitude, width, cs) = (1e-4, 8.0, 1.0 / 3f64.sqrt());
    // A pure northward wave: p′ = Z u, i.e. u = c_s ρ′/ρ₀.
    l.fill_equilibrium(|_, y| {
        let d = amplitude * (-((y as f64 - 120.0) / width).powi(2) / 2.0).exp();
        (1.0 + d, [0.0, cs * d])
    });
    let e0 = acoustic_energy(&l);
    let mut radiating = rate.map(|rate| RadiatingSide {
        density: 1.0,
        rate,
        mean: 0.0,
    });
    // 120 nodes up and 120 back at c_s.
    step_column(&mut l, &mut radiating, (240.0 / cs) as u64);
    acoustic_energy(&l) / e0
}

#[test]
fn a_radiating_side_lets_a_sound_pulse_out_where_a_pressure_side_sends_it_back() {
    let mirror = pulse_round_trip(None);
    let radiating = pulse_round_trip(Some(1e-3));
    let steady = pulse_round_trip(Some(0.0));
    eprintln!("energy after the round trip: pressure side {mirror:.4}, radiating {radiating:.2e} (r = 1e-3), {steady:.2e} (r = 0)");
    // The pressure side reflects the whole pulse (inverted): only viscous attenuation of a σ = 8 pulse at
    // ν = 1/300 over 416 steps, a few per cent, is lost.
    assert!(mirror > 0.9, "pressure side kept {mirror}");
    // The characteristic condition passes a plane wave; what comes back is the running mean's share
    // r/(2ω) (ω ≈ c_s/σ ≈ 0.07 per step: 0.7 % in amplitude at r = 1e-3) and the one-step lag of the
    // velocity it reads; 1 % of the energy is 10 % in amplitude.
    assert!(radiating < 0.01, "radiating side kept {radiating}");
    assert!(steady < 0.01, "radiating side at r = 0 kept {steady}");
}

#[test]
fn a_radiating_side_holds_its_density_for_slow_flow_and_the_back_pressure_without_the_running_mean()
{
    // A steady plug flow north through the column from a Zou–He velocity side at the south.
    let u_in = 1e-4;
    let side_density = |rate: f64| {
        let mut l = column(
            60,
            SideCondition::Velocity {
                velocity: [0.0, u_in],
            },
        );
        l.fill_equilibrium(|_, _| (1.0, [0.0, 0.0]));
        let mut r = Some(RadiatingSide {
            density: 1.0,
            rate,
            mean: 0.0,
        });
        step_column(&mut l, &mut r, 6000);
        match l.boundaries().north {
            SideCondition::Pressure { density } => density,
            other => panic!("north side became {other:?}"),
        }
    };
    // A running-mean rate outside [0, 1] (or a bad density) is refused naming the radiating side.
    let mut l = column(8, SideCondition::Wall);
    for bad in [2.0, -0.1, f64::NAN] {
        let mut r = RadiatingSide {
            density: 1.0,
            rate: bad,
            mean: 0.0,
        };
        let e = l.radiate(Side::North, &mut r).unwrap_err().to_string();
        assert!(e.contains("radiating side"), "{e}");
    }
    let drained = side_density(0.01);
    let held = side_density(0.0);
    let back = 3f64.sqrt() * u_in;
    eprintln!(
        "side density: r = 0.01 {drained:.15}, r = 0 {held:.15} (1 + u/c_s = {:.15})",
        1.0 + back
    );
    // r = 0.01: the running mean has caught up with the steady outflow (to e^(−60) after 6000 steps); what is
    // left is the column's last acoustic transient, below 1e-6 of the back pressure ρ₀u/c_s it would hold at
    // r = 0.
    assert!(
        (drained - 1.0).abs() < 1e-6 * back,
        "drained side at {drained}"
    );
    // r = 0: the side holds the back pressure of a steady outflow into an acoustic half-space, ρ₀ u/c_s (to the
    // same last transient).
    assert!(
        ((held - 1.0) / back - 1.0).abs() < 1e-6,
        "side at {held}, expected 1 + {back}"
    );
}
