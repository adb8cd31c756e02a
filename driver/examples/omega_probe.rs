//! Why ΩΛ diverges in the `terzaghi` column of free grains: runs a terzaghi scene (its Darcy measurement and
//! the step load as the kind does), then steps the coupled world directly and records, at a watched node and
//! over the whole lattice, what the run needs to explain a blow-up.
//!
//! ```text
//! cargo run --release -p lbdem --example omega_probe -- SCENE.toml STEPS [X Y] [EVERY]
//! ```
//!
//! Per `EVERY` steps (and every step once the density leaves [0.9, 1.1]): the lattice's extreme densities and
//! where, the watched node's ε, shares (owner, fraction, solid velocity), ΩΛ open-link mask, ρ, u and Mach
//! |u|/c_s, the ε of its eight neighbours; the owners' lattice positions, velocities and the closest grain
//! contacts (DEM overlap, relative normal velocity) and distance to the side/bottom platens.
use lbdem::engine::exec::Exec;
use lbdem::kinds::terzaghi::Terzaghi;
use lbdem::run::{Case, Kind};

/// Print `msg` and exit with status 2 (bad arguments or scene).
fn fail(msg: &str) -> ! {
    eprintln!("omega_probe: {msg}");
    std::process::exit(2)
}

/// `args[i]` parsed, or `default` when absent; [`fail`] when it does not parse.
fn arg<T: std::str::FromStr>(args: &[String], i: usize, name: &str, default: T) -> T {
    match args.get(i) {
        None => default,
        Some(s) => s
            .parse()
            .unwrap_or_else(|_| fail(&format!("{name} `{s}` is not a valid value"))),
    }
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let Some(path) = a.get(1) else {
        fail("give the scene path first (see the usage in the file header)")
    };
    let steps: u64 = arg(&a, 2, "STEPS", 6000);
    let wx: usize = arg(&a, 3, "X", 27);
    let wy: usize = arg(&a, 4, "Y", 14);
    let every: u64 = arg(&a, 5, "EVERY", 100);
    // "free" (default), "hold" (every grain held from the step load on), or a grain index to hold alone.
    let hold = a.get(6).cloned().unwrap_or_else(|| "free".into());
    // The step (after the load) from which the grains named by `hold` are held.
    let hold_from: u64 = arg(&a, 7, "FROM", 0);
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| fail(&format!("cannot read the scene `{path}`: {e}")));
    let case = Case::<Terzaghi>::read(&text, path).unwrap_or_else(|e| fail(&e.to_string()));
    let exec = Exec {
        threads: 1,
        ..Exec::default()
    };
    let mut state = Terzaghi::start(&case, &exec).unwrap_or_else(|e| fail(&e.to_string()));
    while !state.loaded() {
        Terzaghi::advance(&case, &mut state, None).unwrap_or_else(|e| fail(&e.to_string()));
    }
    let world = state.world_mut();
    let cs = (1.0f64 / 3.0).sqrt();
    let nx = world.fluid.shape().nx;
    let ny = world.fluid.shape().ny;
    if wx >= nx || wy >= ny {
        fail(&format!(
            "the node ({wx}, {wy}) lies outside the {nx} x {ny} lattice"
        ));
    }
    eprintln!(
        "probe: lattice {nx} x {ny}, operator {:?}, collision {:?}, {} grains; watching ({wx}, {wy})",
        world.fluid.solid_operator(),
        world.fluid.collision(),
        world.dem.particles.len()
    );
    for p in &world.dem.platens {
        eprintln!(
            "platen at ({:.4}, {:.4}) normal ({:.2}, {:.2}) active {}",
            p.wall.point[0], p.wall.point[1], p.wall.normal[0], p.wall.normal[1], p.active
        );
    }
    let n = world.dem.particles.len();
    world.dem.held.resize(n, false);
    let h = world.map.spacing;
    let vscale = world.map.velocity_scale();
    let mut detailed = false;
    for s in 1..=steps {
        if s == hold_from + 1 {
            match hold.as_str() {
                "free" => {}
                "hold" => world.dem.held.iter_mut().for_each(|x| *x = true),
                g => {
                    let count = world.dem.held.len();
                    match g.parse::<usize>() {
                        Ok(i) if i < count => world.dem.held[i] = true,
                        _ => fail(&format!(
                            "HOLD `{g}` is neither free, hold nor a grain index below {count}"
                        )),
                    }
                }
            }
            eprintln!(
                "probe: from step {s} held grains: {}",
                world.dem.held.iter().filter(|&&x| x).count()
            );
        }
        world.step();
        let (rho, vel) = world.fluid.moments();
        let (mut lo, mut hi) = ((f64::INFINITY, 0usize), (f64::NEG_INFINITY, 0usize));
        let mut umax = (0.0f64, 0usize);
        for (k, (&r, v)) in rho.iter().zip(&vel).enumerate() {
            if r < lo.0 {
                lo = (r, k);
            }
            if r > hi.0 {
                hi = (r, k);
            }
            let m = (v[0] * v[0] + v[1] * v[1]).sqrt();
            if m > umax.0 {
                umax = (m, k);
            }
        }
        if !detailed && (hi.0 > 1.1 || lo.0 < 0.9 || !hi.0.is_finite()) {
            detailed = true;
        }
        if !(s % every == 0 || detailed) {
            continue;
        }
        let k = wy * nx + wx;
        let (shares, open) = world.fluid.node_shares(wx, wy);
        let eps = world.fluid.solid_fraction_map();
        let u = vel[k];
        println!(
            "step {s}: rho [{:.6} at ({}, {}), {:.6} at ({}, {})], max |u|/c_s {:.4} at ({}, {}); node rho {:.6} u ({:.3e}, {:.3e}) Ma {:.4} 1-eps {:.3e} open {:09b}",
            lo.0,
            lo.1 % nx,
            lo.1 / nx,
            hi.0,
            hi.1 % nx,
            hi.1 / nx,
            umax.0 / cs,
            umax.1 % nx,
            umax.1 / nx,
            rho[k],
            u[0],
            u[1],
            (u[0] * u[0] + u[1] * u[1]).sqrt() / cs,
            1.0 - eps[k],
            open >> 1
        );
        let mut nb = String::new();
        for dy in [1i64, 0, -1] {
            for dx in [-1i64, 0, 1] {
                let (x, y) = (wx as i64 + dx, wy as i64 + dy);
                if x >= 0 && y >= 0 && (x as usize) < nx && (y as usize) < ny {
                    let j = y as usize * nx + x as usize;
                    nb += &format!(" {:.2e}/{:.4}", 1.0 - eps[j], rho[j]);
                }
            }
            nb += " |";
        }
        println!("  neighbours 1-eps/rho (rows y+1, y, y-1):{nb}");
        let bodies = world.bodies();
        for &(owner, frac, sv) in &shares {
            let o = owner as usize;
            let p = &world.dem.particles[o];
            let b = &bodies[o];
            println!(
                "  share: grain {o} fraction {frac:.4} solid u ({:.3e}, {:.3e}); grain centre ({:.3}, {:.3}) lattice, v ({:.3e}, {:.3e}) lattice, spin {:.3e}/step, shape {:?}",
                sv[0], sv[1], b.center[0], b.center[1], b.velocity[0], b.velocity[1], b.spin, b.shape
            );
            for (j, q) in world.dem.particles.iter().enumerate() {
                if j == o {
                    continue;
                }
                let d = p.position - q.position;
                let dist = d.norm();
                let rsum = p.shape.bounding_radius() + q.shape.bounding_radius();
                if dist < rsum + 0.5 * h {
                    let n = d / dist;
                    let vn = (p.velocity - q.velocity).dot(&n) * vscale;
                    let vt = ((p.velocity - q.velocity) - n * (p.velocity - q.velocity).dot(&n))
                        .norm()
                        * vscale;
                    println!(
                        "    neighbour grain {j}: gap {:.4} nodes (negative: overlap), rel. normal v {:.3e}, tangential {:.3e} lattice",
                        (dist - rsum) / h,
                        vn,
                        vt
                    );
                }
            }
            for (w, pl) in world.dem.platens.iter().enumerate() {
                let g =
                    (p.position - pl.wall.point).dot(&pl.wall.normal) - p.shape.bounding_radius();
                if g < h {
                    println!(
                        "    platen {w} (active {}): gap {:.4} nodes, v_n {:.3e} lattice",
                        pl.active,
                        g / h,
                        p.velocity.dot(&pl.wall.normal) * vscale
                    );
                }
            }
        }
        if !hi.0.is_finite() || hi.0 > 5.0 || lo.0 < 0.0 {
            println!("stopped at step {s}");
            break;
        }
    }
}
