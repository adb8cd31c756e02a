//! Where ΩΛ (TRT, Λ = 3/16, B = ε) puts a wall that cuts cells, on cases with exact answers: how far the
//! effective wall sits from the geometric one, in lattice spacings, **positive when the solid acts thicker** (the
//! fluid region narrower). It shows what ΩΛ's friction constant κ (`LAMBDA_FRICTION`) does and what it
//! compensates (README, "What κ compensates").
//!
//! ```text
//! cargo run --release -p lbdem --example wall_offsets [-- 0.8]
//! ```
//! (the optional argument is τ; the offsets do not depend on it). About two minutes; each case in both forms of ΩΛ
//! (friction only, `LambdaTerms::FRICTION_ONLY`, and the wall-pressure form, `LambdaTerms::WALL_PRESSURE`, the default). Cases, all periodic, τ = 0.8:
//! * **body-force channel**: plane Poiseuille flow along x between two solid slabs whose faces cut cell rows
//!   (solid fractions ε of the cut cells given), driven by a uniform body force;
//! * **pressure-driven section**: the same narrow channel over 80 of 320 columns, the rest a wide channel with
//!   exact walls, so that three quarters of the narrow section's drive is a pressure gradient (the wide part is
//!   nearly free of resistance). Both channel cases compare the flux with runs whose walls lie on cell faces
//!   (ε ∈ {0, 1}: half-way bounce-back, exact at Λ = 3/16) at four integer widths; the effective width is where
//!   the cubic through ln Q of those runs meets the flux;
//! * **inclined channel**: the body-force channel at an angle atan(b/a) to the lattice (cell fractions of the
//!   slabs by polygon clipping), against plane Poiseuille's flux G H³/(12ν);
//! * **circular Couette**: a disc of radius R₁ turning inside a fixed circular hole of radius R₂ (the solid
//!   outside it); u_θ = A r + B/r fitted to the fluid nodes away from both walls gives the effective radii.
#[path = "../tests/common/wall_cases.rs"]
mod wall_cases;

use lbdem::engine::lattice::FluidLattice;
use lbdem_kernels::coverage::disc_cell_fraction;
use lbdem_kernels::fluid::collide::LambdaTerms;
use lbdem_kernels::math::Point;
use wall_cases::{channel_offset, lattice, steady, G};

/// Area of the convex polygon `poly` on the side n·p ≤ c of a line.
fn clipped_area(poly: &[[f64; 2]], n: [f64; 2], c: f64) -> f64 {
    let mut out: Vec<[f64; 2]> = Vec::new();
    for (i, &p) in poly.iter().enumerate() {
        let q = poly[(i + 1) % poly.len()];
        let (sp, sq) = (n[0] * p[0] + n[1] * p[1] - c, n[0] * q[0] + n[1] * q[1] - c);
        if sp <= 0.0 {
            out.push(p);
        }
        if (sp < 0.0 && sq > 0.0) || (sp > 0.0 && sq < 0.0) {
            let t = sp / (sp - sq);
            out.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
        }
    }
    let twice: f64 = (0..out.len())
        .map(|i| {
            let (p, q) = (out[i], out[(i + 1) % out.len()]);
            p[0] * q[1] - q[0] * p[1]
        })
        .sum();
    0.5 * twice.abs()
}

/// Offset per wall of a body-force channel along the lattice direction (a, b) on an n × n periodic lattice:
/// solid slabs of thickness `w` whose lower faces sit at s0 + k P along the normal (P = n/√(a² + b²)).
fn inclined_offset(a: i64, b: i64, n: usize, w: f64, s0: f64, tau: f64, terms: LambdaTerms) -> f64 {
    let len = ((a * a + b * b) as f64).sqrt();
    let d = [a as f64 / len, b as f64 / len];
    let normal = [-d[1], d[0]];
    let period = n as f64 / len;
    let eps: Vec<f64> = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f64, (i / n) as f64);
            let cell = [
                [x - 0.5, y - 0.5],
                [x + 0.5, y - 0.5],
                [x + 0.5, y + 0.5],
                [x - 0.5, y + 0.5],
            ];
            let k0 = ((normal[0] * x + normal[1] * y - s0) / period).floor() as i64;
            let e: f64 = (k0 - 2..=k0 + 2)
                .map(|k| {
                    let lo = s0 + k as f64 * period;
                    clipped_area(&cell, normal, lo + w) - clipped_area(&cell, normal, lo)
                })
                .sum();
            e.clamp(0.0, 1.0)
        })
        .collect();
    let nu = (tau - 0.5) / 3.0;
    let mut l = lattice(
        n,
        n,
        tau,
        [G * d[0], G * d[1]],
        &eps,
        |_, _| [0.0; 2],
        |_, _| normal,
        terms,
    );
    let q = steady(&mut l, 1e-10, |l| {
        let (_, u) = l.moments();
        u.iter()
            .zip(&eps)
            .map(|(v, e)| (1.0 - e) * (v[0] * d[0] + v[1] * d[1]))
            .sum::<f64>()
            / (n * n) as f64
    });
    let h_eff = (12.0 * nu * period * q / G).cbrt();
    ((period - w) - h_eff) / 2.0
}

/// Offsets (inner, outer) of circular Couette flow: a disc of radius `r1` spinning at Ω inside a fixed hole of
/// radius `r2`, centre moved by `off` from the lattice's centre.
fn couette_offsets(r1: f64, r2: f64, off: f64, tau: f64, terms: LambdaTerms) -> (f64, f64) {
    let n = (2.0 * r2).ceil() as usize + 6;
    let c = [
        0.5 * (n as f64 - 1.0) + off,
        0.5 * (n as f64 - 1.0) + 0.37 * off,
    ];
    let omega = 1e-4;
    let centre = Point::new(c[0], c[1]);
    let inner = |x: usize, y: usize| disc_cell_fraction(centre, r1, x as f64, y as f64);
    let eps: Vec<f64> = (0..n * n)
        .map(|i| {
            let (x, y) = (i % n, i / n);
            (inner(x, y) + 1.0 - disc_cell_fraction(centre, r2, x as f64, y as f64)).clamp(0.0, 1.0)
        })
        .collect();
    // Both walls are circles about `c`: the radial direction is their normal.
    let radial = |x: usize, y: usize| {
        let (dx, dy) = (x as f64 - c[0], y as f64 - c[1]);
        let r = dx.hypot(dy);
        if r > 0.0 {
            [dx / r, dy / r]
        } else {
            [0.0; 2]
        }
    };
    let mut l = lattice(
        n,
        n,
        tau,
        [0.0; 2],
        &eps,
        |x, y| {
            if inner(x, y) > 0.0 {
                [-omega * (y as f64 - c[1]), omega * (x as f64 - c[0])]
            } else {
                [0.0; 2]
            }
        },
        radial,
        terms,
    );
    // Least squares of u_θ = A r + B/r over the nodes 1.5 spacings or more from both walls.
    let fit = |l: &FluidLattice<f64>| {
        let (_, u) = l.moments();
        let mut s = [0.0; 5];
        for (i, v) in u.iter().enumerate() {
            let (dx, dy) = ((i % n) as f64 - c[0], (i / n) as f64 - c[1]);
            let r = dx.hypot(dy);
            if r < r1 + 1.5 || r > r2 - 1.5 {
                continue;
            }
            let ut = (-dy * v[0] + dx * v[1]) / r;
            s[0] += r * r;
            s[1] += 1.0;
            s[2] += 1.0 / (r * r);
            s[3] += r * ut;
            s[4] += ut / r;
        }
        let det = s[0] * s[2] - s[1] * s[1];
        (
            (s[3] * s[2] - s[4] * s[1]) / det,
            (s[0] * s[4] - s[1] * s[3]) / det,
        )
    };
    // The fit's B settles to roundoff noise of about 1e-9 (relative) per 500 steps: 1e-8 is steady.
    steady(&mut l, 1e-8, |l| fit(l).1);
    let (a, b) = fit(&l);
    let r1_eff = (b / (omega - a)).sqrt();
    let r2_eff = (-b / a).sqrt();
    let offsets = (r1_eff - r1, r2 - r2_eff);
    if !(offsets.0.is_finite() && offsets.1.is_finite()) {
        // A fit with A ≥ 0 or B ≤ 0 has no effective radii: not a Couette profile.
        eprintln!(
            "wall_offsets: circular Couette fit A = {a:e}, B = {b:e} gives no effective radii"
        );
        std::process::exit(1);
    }
    offsets
}

fn main() {
    // One thread: the lattices are small, and the pool's wake-ups would cost more than the steps.
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a thread pool")
        .install(run);
}

fn run() {
    let tau: f64 = match std::env::args().nth(1).map(|s| s.parse::<f64>()) {
        None => 0.8,
        Some(Ok(t)) if t > 0.5 && t.is_finite() => t,
        Some(_) => {
            eprintln!("wall_offsets: the argument is τ, a number above 0.5 (e.g. 0.8)");
            std::process::exit(2);
        }
    };
    let forms = [LambdaTerms::FRICTION_ONLY, LambdaTerms::WALL_PRESSURE];
    println!(
        "ΩΛ + TRT (Λ = 3/16), B = ε, τ = {tau}; offset per wall in lattice spacings, + = the solid acts thicker; \
         friction only (κ = {}) and the wall-pressure form (κ = {}, α = {})",
        forms[0].friction, forms[1].friction, forms[1].pressure
    );
    println!();
    println!("| case | cut cells | friction only | wall-pressure form |");
    println!("|---|---|---|---|");
    for (yb, yt) in [(14.8f64, 25.1f64), (15.2, 25.9)] {
        let eb = yb - (yb.round() - 0.5);
        let et = yt.round() + 0.5 - yt;
        let cut = format!("ε = {eb:.1} / {et:.1}");
        let body = forms.map(|t| channel_offset(yb, yt, 320, 320, tau, 1e-10, t));
        println!(
            "| body-force channel along x, H = {:.1} | {cut} | {:+.4} | {:+.4} |",
            yt - yb,
            body[0],
            body[1]
        );
        let pressure = forms.map(|t| channel_offset(yb, yt, 80, 320, tau, 1e-10, t));
        println!(
            "| pressure-driven section (80 of 320 columns), H = {:.1} | {cut} | {:+.4} | {:+.4} |",
            yt - yb,
            pressure[0],
            pressure[1]
        );
    }
    for (a, b, n) in [(2, 1, 45), (1, 1, 30)] {
        for s0 in [0.0, 0.3] {
            let off = forms.map(|t| inclined_offset(a, b, n, 4.1, s0, tau, t));
            let h = n as f64 / ((a * a + b * b) as f64).sqrt() - 4.1;
            println!(
                "| body-force channel along ({a}, {b}), H = {h:.1} | slab face at s₀ = {s0} | {:+.4} | {:+.4} |",
                off[0], off[1]
            );
        }
    }
    for off in [0.0, 0.41] {
        let [(i0, o0), (i1, o1)] = forms.map(|t| couette_offsets(10.3, 20.3, off, tau, t));
        println!("| circular Couette, convex wall R₁ = 10.3 (turning) | centre moved {off} | {i0:+.4} | {i1:+.4} |");
        println!("| circular Couette, concave wall R₂ = 20.3 (fixed) | centre moved {off} | {o0:+.4} | {o1:+.4} |");
    }
}
