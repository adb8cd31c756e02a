//! Where ΩΛ (TRT, Λ = 3/16, B = ε) puts a wall that cuts cells, on plane channels with exact answers (README "What
//! κ compensates"): plane Poiseuille flow along x between solid slabs whose faces cut a row of cells, driven by a
//! body force, or over part of the columns only, fed by a wide channel with exact walls so that most of its drive
//! is a pressure gradient. The effective width comes from runs whose walls lie on cell faces (ε ∈ {0, 1}: half-way
//! bounce-back, exact at Λ = 3/16) at four integer widths: where the cubic through ln Q of those runs meets the
//! flux. Shared by `driver/tests/trt_psm.rs` and the example `driver/examples/wall_offsets.rs` (included with
//! `#[path]`).
#![allow(dead_code)]
use lbdem::engine::lattice::FluidLattice;
use lbdem_kernels::fluid::boundary::Boundaries;
use lbdem_kernels::fluid::collide::{Collision, LambdaTerms, SolidOperator, Trt, Weighting};
use lbdem_kernels::fluid::step::FluidParams;

/// Rows of the channel cases.
pub const NY: usize = 40;
/// Body force of the channel cases (lattice units): Stokes flow, density variation ≪ 1e-4.
pub const G: f64 = 1e-7;

/// A periodic lattice under TRT (Λ = 3/16) + ΩΛ with body force `force`, covered by `eps` (row-major) with
/// solid velocities `vel` and wall directions `normal` (a unit normal of the solid's surface at a node; its sign
/// does not matter to ΩΛ, which uses the surface's tangent), with ΩΛ's constants `terms`.
#[allow(clippy::too_many_arguments)]
pub fn lattice(
    nx: usize,
    ny: usize,
    tau: f64,
    force: [f64; 2],
    eps: &[f64],
    vel: impl Fn(usize, usize) -> [f64; 2],
    normal: impl Fn(usize, usize) -> [f64; 2],
    terms: LambdaTerms,
) -> FluidLattice<f64> {
    let params = FluidParams { tau, force };
    let mut l = FluidLattice::new(nx, ny, Boundaries::periodic(), params).expect("valid lattice");
    l.set_collision(Collision::Trt(Trt::new(3.0 / 16.0).expect("positive Λ")))
        .expect("valid rates");
    l.set_solid_operator(SolidOperator::LambdaConsistent);
    l.set_lambda_terms(terms).expect("valid constants");
    l.cover_with_field(|x, y| eps[y * nx + x], vel, Weighting::SolidFraction)
        .expect("fractions in [0, 1]");
    l.set_field_normals(normal).expect("unit normals");
    l
}

/// Step `l` until `measure` changes by less than `tol` (relative) over 500 steps (at most 2e6 steps).
pub fn steady(
    l: &mut FluidLattice<f64>,
    tol: f64,
    measure: impl Fn(&FluidLattice<f64>) -> f64,
) -> f64 {
    let mut last = f64::NAN;
    loop {
        for _ in 0..500 {
            l.step();
        }
        let q = measure(l);
        assert!(q.is_finite(), "non-finite result after {} steps", l.steps());
        if ((q - last) / q).abs() < tol || l.steps() >= 2_000_000 {
            return q;
        }
        last = q;
    }
}

/// Flux per unit depth along x, Σ (1 − ε) u_x / nx, of the channel with slab faces at `yb` (solid below) and
/// `yt` (solid above) over columns 0 … `ln` − 1 and exact walls at 2.5 and NY − 3.5 elsewhere, under ΩΛ with
/// `terms`.
pub fn channel_flux(
    yb: f64,
    yt: f64,
    ln: usize,
    lx: usize,
    tau: f64,
    tol: f64,
    terms: LambdaTerms,
) -> f64 {
    let eps: Vec<f64> = (0..lx * NY)
        .map(|i| {
            let (x, y) = (i % lx, (i / lx) as f64);
            let (b, t) = if x < ln {
                (yb, yt)
            } else {
                (2.5, NY as f64 - 3.5)
            };
            ((b - (y - 0.5)).clamp(0.0, 1.0) + ((y + 0.5) - t).clamp(0.0, 1.0)).min(1.0)
        })
        .collect();
    // The slabs' faces are planes y = const.
    let mut l = lattice(
        lx,
        NY,
        tau,
        [G, 0.0],
        &eps,
        |_, _| [0.0; 2],
        |_, _| [0.0, 1.0],
        terms,
    );
    steady(&mut l, tol, |l| {
        let (_, u) = l.moments();
        u.iter()
            .zip(&eps)
            .map(|(v, e)| (1.0 - e) * v[0])
            .sum::<f64>()
            / lx as f64
    })
}

/// Offset per wall of the channel with faces `yb`, `yt` (see [`channel_flux`]) against exact-wall runs, in
/// lattice spacings, + when the solid acts thicker; every run steady to `tol` (relative flux change per 500 steps).
pub fn channel_offset(
    yb: f64,
    yt: f64,
    ln: usize,
    lx: usize,
    tau: f64,
    tol: f64,
    terms: LambdaTerms,
) -> f64 {
    let h = yt - yb;
    let h0 = (h - 1.5).round();
    let refs: Vec<(f64, f64)> = (0..4)
        .map(|k| {
            let w = h0 + k as f64;
            (
                w,
                channel_flux(14.5, 14.5 + w, ln, lx, tau, tol, terms).ln(),
            )
        })
        .collect();
    let lagrange = |x: f64| {
        refs.iter()
            .enumerate()
            .map(|(i, &(xi, yi))| {
                refs.iter()
                    .enumerate()
                    .filter(|&(j, _)| j != i)
                    .fold(yi, |acc, (_, &(xj, _))| acc * (x - xj) / (xi - xj))
            })
            .sum::<f64>()
    };
    let target = channel_flux(yb, yt, ln, lx, tau, tol, terms).ln();
    // A flux that is not positive has no width: ln gives NaN, which the bisection would hide.
    assert!(
        target.is_finite() && refs.iter().all(|r| r.1.is_finite()),
        "a channel flux is not positive: {target} and references {refs:?}"
    );
    // ln Q rises with the width: bisection over the references' span.
    let (mut lo, mut hi) = (refs[0].0, refs[3].0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if lagrange(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (h - 0.5 * (lo + hi)) / 2.0
}
