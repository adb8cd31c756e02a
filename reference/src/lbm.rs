//! Reference (oracle) D2Q9 lattice Boltzmann: plain `f64`, array-of-structs (`Vec<[f64; 9]>`), one node at a
//! time, **push** streaming. Written to be read, not to be fast; the optimized kernels in `lbdem-kernels` are
//! tested against it.
//!
//! Lattice units throughout: Δx = Δt = 1, c_s² = 1/3, p = ρ/3, ν = (τ − ½)/3.
//!
//! * Velocity set (Qian, d'Humières & Lallemand 1992): c₀ = (0,0); c₁ = (1,0), c₂ = (0,1), c₃ = (−1,0),
//!   c₄ = (0,−1); c₅ = (1,1), c₆ = (−1,1), c₇ = (−1,−1), c₈ = (1,−1); w₀ = 4/9, w₁…₄ = 1/9, w₅…₈ = 1/36.
//!   The tables are written out here on purpose (not imported from the kernels).
//! * Equilibrium: f_i^eq(ρ, u) = w_i ρ [1 + 3 c_i·u + 9/2 (c_i·u)² − 3/2 u·u].
//! * BGK (dissertation eq. 4.1): f_i ← f_i − (f_i − f_i^eq(ρ, u))/τ.
//! * Guo, Zheng & Shi (2002) forcing with force density F: u = (Σ f_i c_i + F/2)/ρ and the source
//!   S_i = (1 − 1/(2τ)) w_i [3 (c_i − u) + 9 (c_i·u) c_i]·F.
//! * Two-relaxation-time collision (Ginzburg, Verhaeghe & d'Humières 2008, Commun. Comput. Phys. 3:427):
//!   f_i^± = ½(f_i ± f_ī), e_i^± = ½(f_i^eq ± f_ī^eq), f_i ← f_i − (f_i⁺ − e_i⁺)/τ⁺ − (f_i⁻ − e_i⁻)/τ⁻ with
//!   τ⁻ = ½ + Λ/(τ⁺ − ½); Guo's source split into its even and odd parts in c_i, each with its own prefactor:
//!   S_i = (1 − 1/(2τ⁺)) ½(G_i + G_ī) + (1 − 1/(2τ⁻)) ½(G_i − G_ī), G_i = w_i [3 (c_i − u) + 9 (c_i·u) c_i]·F.
//! * Noble–Torczynski PSM (dissertation eq. 4.4–4.8, docs/references.md §2):
//!   f_i ← f_i − (1 − B)(f_i − f_i^eq(ρ,u))/τ + Σ_s B_s Ω_{i,s} + (1 − B) S_i with
//!   Ω_{i,s} = f_ī − f_ī^eq(ρ,u) + f_i^eq(ρ,u_s) − f_i, B = B(min(Σ_s ε_s, 1)) shared as B_s = B ε_s / Σ ε,
//!   and the force (momentum per step) on solid s, F_s = −B_s Σ_i Ω_{i,s} c_i.
//! * Zou & He (1997) closures in the transverse-momentum form of Hecht & Harting (2010), written once for a
//!   side with inward normal n (docs/references.md §3), and the corner rule of §3.
//! * A full step in push form: stream (half-way bounce-back from obstacle nodes and wall sides), close the
//!   Zou–He nodes, collide. See [`step`] for how this lines up with the kernels' fused pull step.
/// Number of discrete velocities.
pub const Q: usize = 9;

/// Lattice velocities c_i as (x, y).
pub const C: [[i64; 2]; Q] = [
    [0, 0],
    [1, 0],
    [0, 1],
    [-1, 0],
    [0, -1],
    [1, 1],
    [-1, 1],
    [-1, -1],
    [1, -1],
];

/// Lattice weights w_i.
pub const W: [f64; Q] = [
    4.0 / 9.0,
    1.0 / 9.0,
    1.0 / 9.0,
    1.0 / 9.0,
    1.0 / 9.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
    1.0 / 36.0,
];

/// The opposite direction ī of each i: c_ī = −c_i.
pub const OPPOSITE: [usize; Q] = [0, 3, 4, 1, 2, 7, 8, 5, 6];

/// The populations of one node.
pub type Populations = [f64; Q];

/// c_i as floating point.
pub fn c(i: usize) -> [f64; 2] {
    [C[i][0] as f64, C[i][1] as f64]
}

/// Density ρ = Σ_i f_i.
pub fn density(f: &Populations) -> f64 {
    f.iter().sum()
}

/// Momentum j = Σ_i f_i c_i.
pub fn momentum(f: &Populations) -> [f64; 2] {
    let mut j = [0.0; 2];
    for (i, fi) in f.iter().enumerate() {
        j[0] += fi * c(i)[0];
        j[1] += fi * c(i)[1];
    }
    j
}

/// Second moment Π = Σ_i f_i c_i c_i as (xx, xy, yy).
pub fn second_moment(f: &Populations) -> [f64; 3] {
    let mut p = [0.0; 3];
    for (i, fi) in f.iter().enumerate() {
        let ci = c(i);
        p[0] += fi * ci[0] * ci[0];
        p[1] += fi * ci[0] * ci[1];
        p[2] += fi * ci[1] * ci[1];
    }
    p
}

/// Second-order equilibrium f_i^eq(ρ, u) = w_i ρ [1 + 3 c_i·u + 9/2 (c_i·u)² − 3/2 u·u].
pub fn equilibrium(rho: f64, u: [f64; 2]) -> Populations {
    let mut feq = [0.0; Q];
    let uu = u[0] * u[0] + u[1] * u[1];
    for (i, fi) in feq.iter_mut().enumerate() {
        let cu = c(i)[0] * u[0] + c(i)[1] * u[1];
        *fi = W[i] * rho * (1.0 + 3.0 * cu + 4.5 * cu * cu - 1.5 * uu);
    }
    feq
}

/// Density and velocity seen by the collision: ρ = Σ f, u = (Σ f c + F/2)/ρ (Guo's half-force shift; with
/// F = 0 the plain velocity).
pub fn macroscopic(f: &Populations, force: [f64; 2]) -> (f64, [f64; 2]) {
    let rho = density(f);
    let j = momentum(f);
    (
        rho,
        [(j[0] + 0.5 * force[0]) / rho, (j[1] + 0.5 * force[1]) / rho],
    )
}

/// Guo source S_i = (1 − 1/(2τ)) w_i [3 (c_i − u) + 9 (c_i·u) c_i]·F.
pub fn guo_source(tau: f64, u: [f64; 2], force: [f64; 2]) -> Populations {
    let mut s = [0.0; Q];
    for (i, si) in s.iter_mut().enumerate() {
        let ci = c(i);
        let cu = ci[0] * u[0] + ci[1] * u[1];
        let ax = 3.0 * (ci[0] - u[0]) + 9.0 * cu * ci[0];
        let ay = 3.0 * (ci[1] - u[1]) + 9.0 * cu * ci[1];
        *si = (1.0 - 0.5 / tau) * W[i] * (ax * force[0] + ay * force[1]);
    }
    s
}

/// BGK collision (dissertation eq. 4.1), no body force: f_i − (f_i − f_i^eq(ρ, u))/τ.
pub fn bgk(f: &Populations, tau: f64) -> Populations {
    bgk_forced(f, tau, [0.0, 0.0])
}

/// BGK collision with Guo forcing: f_i − (f_i − f_i^eq(ρ, u))/τ + S_i, u with the half-force shift.
pub fn bgk_forced(f: &Populations, tau: f64, force: [f64; 2]) -> Populations {
    let (rho, u) = macroscopic(f, force);
    let feq = equilibrium(rho, u);
    let s = guo_source(tau, u, force);
    let mut out = [0.0; Q];
    for i in 0..Q {
        out[i] = f[i] - (f[i] - feq[i]) / tau + s[i];
    }
    out
}

/// The relaxation time τ⁻ = ½ + Λ/(τ⁺ − ½) of the antisymmetric parts for magic parameter Λ.
pub fn tau_minus(tau_plus: f64, magic: f64) -> f64 {
    0.5 + magic / (tau_plus - 0.5)
}

/// Two-relaxation-time collision, no body force (see the module notes).
pub fn trt(f: &Populations, tau_plus: f64, magic: f64) -> Populations {
    trt_forced(f, tau_plus, magic, [0.0, 0.0])
}

/// Two-relaxation-time collision with Guo's source split into even and odd parts, u with the half-force
/// shift: f_i − (f_i⁺ − e_i⁺)/τ⁺ − (f_i⁻ − e_i⁻)/τ⁻ + (1 − 1/(2τ⁺)) G_i⁺ + (1 − 1/(2τ⁻)) G_i⁻.
pub fn trt_forced(f: &Populations, tau_plus: f64, magic: f64, force: [f64; 2]) -> Populations {
    trt_forced_times(f, tau_plus, tau_minus(tau_plus, magic), force)
}

/// [`trt_forced`] with the two relaxation times given directly.
pub fn trt_forced_times(
    f: &Populations,
    tau_plus: f64,
    tau_m: f64,
    force: [f64; 2],
) -> Populations {
    let (rho, u) = macroscopic(f, force);
    let feq = equilibrium(rho, u);
    // Guo's source without its prefactor: G_i = w_i [3 (c_i − u) + 9 (c_i·u) c_i]·F.
    let g: Populations = {
        let mut g = [0.0; Q];
        for (i, gi) in g.iter_mut().enumerate() {
            let ci = c(i);
            let cu = ci[0] * u[0] + ci[1] * u[1];
            let ax = 3.0 * (ci[0] - u[0]) + 9.0 * cu * ci[0];
            let ay = 3.0 * (ci[1] - u[1]) + 9.0 * cu * ci[1];
            *gi = W[i] * (ax * force[0] + ay * force[1]);
        }
        g
    };
    let mut out = [0.0; Q];
    for i in 0..Q {
        let o = OPPOSITE[i];
        let (f_plus, f_minus) = (0.5 * (f[i] + f[o]), 0.5 * (f[i] - f[o]));
        let (e_plus, e_minus) = (0.5 * (feq[i] + feq[o]), 0.5 * (feq[i] - feq[o]));
        let (g_plus, g_minus) = (0.5 * (g[i] + g[o]), 0.5 * (g[i] - g[o]));
        out[i] = f[i] - (f_plus - e_plus) / tau_plus - (f_minus - e_minus) / tau_m
            + (1.0 - 0.5 / tau_plus) * g_plus
            + (1.0 - 0.5 / tau_m) * g_minus;
    }
    out
}

/// The fluid collision of a reference step: BGK (`magic` = `None`) or TRT with magic parameter Λ.
pub fn fluid_collision(
    f: &Populations,
    tau: f64,
    magic: Option<f64>,
    force: [f64; 2],
) -> Populations {
    match magic {
        None => bgk_forced(f, tau, force),
        Some(m) => trt_forced(f, tau, m, force),
    }
}

/// The PSM weighting function B(ε, τ).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weighting {
    /// Noble & Torczynski (dissertation eq. 4.5): B = ε(τ − ½)/((1 − ε) + (τ − ½)).
    NobleTorczynski,
    /// B = ε.
    SolidFraction,
}

/// B(ε, τ) for the chosen weighting.
pub fn weighting(kind: Weighting, eps: f64, tau: f64) -> f64 {
    match kind {
        Weighting::NobleTorczynski => eps * (tau - 0.5) / ((1.0 - eps) + (tau - 0.5)),
        Weighting::SolidFraction => eps,
    }
}

/// A solid covering part of a cell: fraction ε_s and velocity u_s at the node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solid {
    /// Solid fraction ε_s of the cell.
    pub fraction: f64,
    /// Rigid-body velocity of the solid at the node.
    pub velocity: [f64; 2],
    /// Unit outward normal of the solid's surface at the node (zero: no direction): [`step`] derives
    /// `wall_gradient` from it for ΩΛ.
    pub normal: [f64; 2],
    /// The density gradient along the solid's surface at the node, read by [`psm_lambda`] at partly covered
    /// nodes (its wall-pressure force); [`step`] overwrites it from the streamed densities and `normal`.
    pub wall_gradient: [f64; 2],
}

/// Noble–Torczynski partially-saturated collision of one node with solids `solids` (non-equilibrium
/// bounce-back Ω₁) and Guo force `force` weighted by (1 − B). Returns the post-collision populations and the
/// force on each solid, F_s = −B_s Σ_i Ω_{i,s} c_i. With Σ ε_s = 0 it is the BGK collision.
pub fn psm(
    f: &Populations,
    tau: f64,
    kind: Weighting,
    force: [f64; 2],
    solids: &[Solid],
) -> (Populations, Vec<[f64; 2]>) {
    psm_with_operator(
        f,
        tau,
        kind,
        SolidOp::NonEquilibriumBounceBack,
        force,
        solids,
    )
}

/// The solid collision operator Ω^S (Owen, Leonardi & Feng 2011 numbering).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolidOp {
    /// Ω₁: f_ī − f_ī^eq(ρ,u) + f_i^eq(ρ,u_s) − f_i (Noble–Torczynski, dissertation eq. 4.6).
    NonEquilibriumBounceBack,
    /// Ω₂: f_i^eq(ρ,u_s) − f_i + (1 − 1/τ)(f_i − f_i^eq(ρ,u)) (Holdych's superposition).
    Superposition,
    /// Ω₃: f_ī − f_ī^eq(ρ,u_s) + f_i^eq(ρ,u_s) − f_i (Owen et al. eq. 33, moving-wall bounce-back).
    MovingWallBounceBack,
    /// Ω₁ₗ: f_ī − f_i + 3 w_i ρ c_i·(u + u_s) (Ω₁ without the even part of its equilibrium difference).
    LinearizedNonEquilibriumBounceBack,
}

/// As [`psm`], with the solid operator chosen (see [`SolidOp`]).
pub fn psm_with_operator(
    f: &Populations,
    tau: f64,
    kind: Weighting,
    op: SolidOp,
    force: [f64; 2],
    solids: &[Solid],
) -> (Populations, Vec<[f64; 2]>) {
    psm_with_collision(f, tau, None, kind, op, force, solids)
}

/// As [`psm_with_operator`], with the fluid part relaxed by BGK (`magic` = `None`) or by TRT with magic
/// parameter Λ: f_i + (1 − B)(C_i(f) − f_i) + Σ_s B_s Ω_{i,s}, C the fluid collision with its forcing. For TRT,
/// Ω₂'s post-collision non-equilibrium (1 − 1/τ)(f_i − f_i^eq) becomes (1 − 1/τ⁺) n_i⁺ + (1 − 1/τ⁻) n_i⁻,
/// n^± = f^± − e^±.
pub fn psm_with_collision(
    f: &Populations,
    tau: f64,
    magic: Option<f64>,
    kind: Weighting,
    op: SolidOp,
    force: [f64; 2],
    solids: &[Solid],
) -> (Populations, Vec<[f64; 2]>) {
    let eps_sum: f64 = solids.iter().map(|s| s.fraction).sum();
    if eps_sum <= 0.0 {
        return (
            fluid_collision(f, tau, magic, force),
            vec![[0.0, 0.0]; solids.len()],
        );
    }
    let b = weighting(kind, eps_sum.min(1.0), tau);
    let (rho, u) = macroscopic(f, force);
    let feq = equilibrium(rho, u);
    let mut out = [0.0; Q];
    match magic {
        None => {
            let s = guo_source(tau, u, force);
            for i in 0..Q {
                out[i] = f[i] - (1.0 - b) * (f[i] - feq[i]) / tau + (1.0 - b) * s[i];
            }
        }
        Some(m) => {
            let fluid = trt_forced(f, tau, m, force);
            for i in 0..Q {
                out[i] = f[i] + (1.0 - b) * (fluid[i] - f[i]);
            }
        }
    }
    // The fluid's post-collision non-equilibrium (Ω₂).
    let post_non_equilibrium = |i: usize| -> f64 {
        match magic {
            None => (1.0 - 1.0 / tau) * (f[i] - feq[i]),
            Some(m) => {
                let o = OPPOSITE[i];
                let n_plus = 0.5 * (f[i] + f[o]) - 0.5 * (feq[i] + feq[o]);
                let n_minus = 0.5 * (f[i] - f[o]) - 0.5 * (feq[i] - feq[o]);
                (1.0 - 1.0 / tau) * n_plus + (1.0 - 1.0 / tau_minus(tau, m)) * n_minus
            }
        }
    };
    let mut exchange = Vec::with_capacity(solids.len());
    for solid in solids {
        let b_s = b * solid.fraction / eps_sum;
        let feq_s = equilibrium(rho, solid.velocity);
        let mut given_to_fluid = [0.0; 2];
        for i in 0..Q {
            let o = OPPOSITE[i];
            let omega_s = match op {
                SolidOp::Superposition => feq_s[i] - f[i] + post_non_equilibrium(i),
                SolidOp::NonEquilibriumBounceBack => f[o] - feq[o] + feq_s[i] - f[i],
                SolidOp::MovingWallBounceBack => f[o] - feq_s[o] + feq_s[i] - f[i],
                SolidOp::LinearizedNonEquilibriumBounceBack => {
                    let cv =
                        c(i)[0] * (u[0] + solid.velocity[0]) + c(i)[1] * (u[1] + solid.velocity[1]);
                    f[o] - f[i] + 3.0 * W[i] * rho * cv
                }
            };
            out[i] += b_s * omega_s;
            given_to_fluid[0] += b_s * omega_s * c(i)[0];
            given_to_fluid[1] += b_s * omega_s * c(i)[1];
        }
        exchange.push([-given_to_fluid[0], -given_to_fluid[1]]);
    }
    (out, exchange)
}

/// ΩΛ's friction constant κ (`lbdem_kernels::fluid::collide::LAMBDA_FRICTION`, restated).
pub const LAMBDA_FRICTION: f64 = 1.21;

/// ΩΛ's wall-pressure constant α (`lbdem_kernels::fluid::collide::LAMBDA_PRESSURE`, restated): a partly
/// covered node's fluid gets (ε_s/Σε) α B (1 − B/2) c_s² ∇ₜρ_s from each solid s, which takes the opposite.
pub const LAMBDA_PRESSURE: f64 = 2.0;

/// ΩΛ's friction constant in its wall-pressure form (`lbdem_kernels::fluid::collide::LAMBDA_WALL_FRICTION`,
/// restated).
pub const LAMBDA_WALL_FRICTION: f64 = 0.45;

/// ΩΛ's full-cover threshold: a node whose fractions sum to at least 1 − this gap takes the fully covered rule
/// (the operator's definition, fixed at 0.05 where the partly covered rule was measured to destabilise free
/// grains and packs of them: lbdem-kernels `fluid::collide::LAMBDA_FULL_GAP`, whose doc gives the measurements).
pub const LAMBDA_FULL_GAP: f64 = 0.05;

/// The magic-parameter-consistent partially saturated collision ΩΛ of one node (see the kernels'
/// `lambda_collide` for the derivation), written from its definition. `magic` = `None` is BGK (Λ⁻ = Λ⁺);
/// `open[i]` tells whether the neighbour x + c_i is not fully covered (read at fully covered nodes only).
///
/// * Σ ε_s ≤ 0: the fluid collision.
/// * Σ ε_s ≥ 1 − [`LAMBDA_FULL_GAP`]: for each solid s, P_i = f_ī + 6 w_i ρ c_i·u_s on open links; the other directions (the rest
///   direction among them) get the remaining mass ρ − Σ_open P_i in proportion to f^eq(1, u_s); the node takes
///   Σ_s (ε_s/Σε) P_s and solid s receives −(ε_s/Σε) Σ_i c_i (P_{s,i} − f_i).
/// * otherwise (0 < Σ ε_s < 1 − [`LAMBDA_FULL_GAP`]), with Λ⁺ = τ − ½, Λ⁻ = τ⁻ − ½, B = ε (or ε√(Λ⁺Λ⁻)/((1 − ε) + √(Λ⁺Λ⁻)) for the NT weighting):
///   TRT with τ⁺_loc = ½ + Λ⁺/(1 − B), τ⁻_loc = ½ + Λ⁻(1 − B) and the force F = F_e + Σ_s F_s, where
///   F_e = (1 − B) F_body + Σ_s P_s with the wall-pressure forces P_s = (ε_s/Σε) α B (2 − B) ∇ₜρ_s / 6
///   (α and κ the last argument, ∇ₜρ_s = `wall_gradient`), and the frictions
///   F_s = −κ Λ⁺ B (ε_s/Σε) ρ (u − u_s), u the velocity of that forced collision, u = (Σ f c + F/2)/ρ (solved:
///   u (1 + κΛ⁺B/2) = (Σ f c + F_e/2)/ρ + Σ_s κΛ⁺B (ε_s/Σε) u_s/2); solid s receives −(F_s + P_s).
#[allow(clippy::too_many_arguments)]
pub fn psm_lambda(
    f: &Populations,
    tau: f64,
    magic: Option<f64>,
    kind: Weighting,
    force: [f64; 2],
    solids: &[Solid],
    open: [bool; Q],
    (kappa, alpha): (f64, f64),
) -> (Populations, Vec<[f64; 2]>) {
    let eps: f64 = solids.iter().map(|s| s.fraction).sum();
    if eps <= 0.0 {
        return (
            fluid_collision(f, tau, magic, force),
            vec![[0.0, 0.0]; solids.len()],
        );
    }
    let rho = density(f);
    if eps >= 1.0 - LAMBDA_FULL_GAP {
        let mut out = [0.0; Q];
        let mut exchange = Vec::new();
        for s in solids {
            let share = s.fraction / eps;
            let shape = equilibrium(1.0, s.velocity);
            let mut p = [0.0; Q];
            let is_open = |i: usize| i != 0 && open[i];
            for i in (0..Q).filter(|&i| is_open(i)) {
                let cu = c(i)[0] * s.velocity[0] + c(i)[1] * s.velocity[1];
                p[i] = f[OPPOSITE[i]] + 6.0 * W[i] * rho * cu;
            }
            let reflected: f64 = (0..Q).filter(|&i| is_open(i)).map(|i| p[i]).sum();
            let closed_weight: f64 = (0..Q).filter(|&i| !is_open(i)).map(|i| shape[i]).sum();
            for i in (0..Q).filter(|&i| !is_open(i)) {
                p[i] = (rho - reflected) * shape[i] / closed_weight;
            }
            let mut handed = [0.0; 2];
            for i in 0..Q {
                out[i] += share * p[i];
                handed[0] -= share * (p[i] - f[i]) * c(i)[0];
                handed[1] -= share * (p[i] - f[i]) * c(i)[1];
            }
            exchange.push(handed);
        }
        return (out, exchange);
    }
    let lambda_plus = tau - 0.5;
    let lambda_minus = match magic {
        None => lambda_plus,
        Some(m) => tau_minus(tau, m) - 0.5,
    };
    let b = match kind {
        Weighting::SolidFraction => eps,
        Weighting::NobleTorczynski => {
            let a = (lambda_plus * lambda_minus).sqrt();
            eps * a / ((1.0 - eps) + a)
        }
    };
    let beta = kappa * lambda_plus * b;
    let push = |s: &Solid| {
        let k = s.fraction / eps * alpha * b * (2.0 - b) / 6.0;
        [k * s.wall_gradient[0], k * s.wall_gradient[1]]
    };
    let mut body = [(1.0 - b) * force[0], (1.0 - b) * force[1]];
    for s in solids {
        let p = push(s);
        body[0] += p[0];
        body[1] += p[1];
    }
    let j = momentum(f);
    let mut u = [0.0; 2];
    for a in 0..2 {
        let pull: f64 = solids
            .iter()
            .map(|s| beta * s.fraction / eps * s.velocity[a] / 2.0)
            .sum();
        u[a] = ((j[a] + body[a] / 2.0) / rho + pull) / (1.0 + beta / 2.0);
    }
    let mut total = body;
    let mut exchange = Vec::new();
    for s in solids {
        let fs = [
            -beta * s.fraction / eps * rho * (u[0] - s.velocity[0]),
            -beta * s.fraction / eps * rho * (u[1] - s.velocity[1]),
        ];
        total[0] += fs[0];
        total[1] += fs[1];
        let p = push(s);
        exchange.push([-(fs[0] + p[0]), -(fs[1] + p[1])]);
    }
    let post = trt_forced_times(
        f,
        0.5 + lambda_plus / (1.0 - b),
        0.5 + lambda_minus * (1.0 - b),
        total,
    );
    (post, exchange)
}

/// ΩΛ's density gradient along a wall at node (x, y) with unit normal `normal`: (t·g) t, t = (−n_y, n_x), g the
/// gradient of the streamed densities `rho` by central differences along each axis where both axis neighbours'
/// links are `open`, one-sided where one is, zero where neither.
pub fn wall_gradient(
    lat: &Lattice,
    sides: &Sides,
    rho: &[f64],
    open: &[bool; Q],
    x: usize,
    y: usize,
    normal: [f64; 2],
) -> [f64; 2] {
    let here = rho[lat.index(x, y)];
    let at = |q: usize| {
        if open[q] {
            lat.destination(x, y, q, sides).map(|j| rho[j])
        } else {
            None
        }
    };
    let axis = |plus: Option<f64>, minus: Option<f64>| match (plus, minus) {
        (Some(p), Some(m)) => (p - m) / 2.0,
        (Some(p), None) => p - here,
        (None, Some(m)) => here - m,
        (None, None) => 0.0,
    };
    // D2Q9 directions 1–4: +x, +y, −x, −y.
    let g = [axis(at(1), at(3)), axis(at(2), at(4))];
    let t = [-normal[1], normal[0]];
    let along = t[0] * g[0] + t[1] * g[1];
    [along * t[0], along * t[1]]
}

/// The open links of node (x, y) for ΩΛ: `open[i]` when x + c_i is inside the lattice (wrapping across
/// periodic sides), not an obstacle node and not fully covered (`full[node]`). Links leaving through a
/// non-periodic side are closed.
pub fn open_links(lat: &Lattice, sides: &Sides, full: &[bool], x: usize, y: usize) -> [bool; Q] {
    let mut open = [false; Q];
    for (q, o) in open.iter_mut().enumerate().skip(1) {
        if let Some(j) = lat.destination(x, y, q, sides) {
            *o = !lat.solid[j] && !full[j];
        }
    }
    open
}

/// The sides of the rectangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// x = 0
    West,
    /// x = nx − 1
    East,
    /// y = 0
    South,
    /// y = ny − 1
    North,
}

impl Side {
    /// Unit normal pointing into the lattice.
    pub fn inward(self) -> [i64; 2] {
        match self {
            Side::West => [1, 0],
            Side::East => [-1, 0],
            Side::South => [0, 1],
            Side::North => [0, -1],
        }
    }
}

/// What happens at a side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Condition {
    /// Periodic (the opposite side must be periodic too).
    Periodic,
    /// Half-way bounce-back wall at rest.
    Wall,
    /// Zou–He pressure: prescribed density, zero tangential velocity.
    Pressure(f64),
    /// Zou–He velocity: prescribed velocity (or, where [`Profiles`] has values for the side, one per node).
    Velocity([f64; 2]),
    /// Half-way bounce-back wall sliding along itself at this velocity: a population re-entering through it
    /// gains 6 w_i ρ c_i·u_w (Ladd 1994), ρ the density of the node's streamed populations.
    MovingWall([f64; 2]),
}

/// Per-node velocities of velocity sides (empty: the side's uniform velocity): node k along the side, x for
/// south and north, y for west and east.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Profiles {
    /// x = 0.
    pub west: Vec<[f64; 2]>,
    /// x = nx − 1.
    pub east: Vec<[f64; 2]>,
    /// y = 0.
    pub south: Vec<[f64; 2]>,
    /// y = ny − 1.
    pub north: Vec<[f64; 2]>,
}

impl Profiles {
    fn of(&self, side: Side) -> &[[f64; 2]] {
        match side {
            Side::West => &self.west,
            Side::East => &self.east,
            Side::South => &self.south,
            Side::North => &self.north,
        }
    }
}

impl Condition {
    fn is_zou_he(self) -> bool {
        matches!(self, Condition::Pressure(_) | Condition::Velocity(_))
    }
}

/// Conditions on the four sides.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sides {
    /// x = 0
    pub west: Condition,
    /// x = nx − 1
    pub east: Condition,
    /// y = 0
    pub south: Condition,
    /// y = ny − 1
    pub north: Condition,
}

impl Sides {
    /// Condition of one side.
    pub fn of(&self, side: Side) -> Condition {
        match side {
            Side::West => self.west,
            Side::East => self.east,
            Side::South => self.south,
            Side::North => self.north,
        }
    }
}

fn dot(a: [i64; 2], u: [f64; 2]) -> f64 {
    a[0] as f64 * u[0] + a[1] as f64 * u[1]
}

/// The directions entering the lattice through `side` (c_i·n > 0): unknown after streaming.
pub fn incoming(side: Side) -> Vec<usize> {
    let n = side.inward();
    (0..Q)
        .filter(|&i| C[i][0] * n[0] + C[i][1] * n[1] > 0)
        .collect()
}

/// S_∥ + 2 S_out: the populations along the side plus twice those leaving through it; equals ρ(1 − u·n).
fn known_mass_flux(f: &Populations, side: Side) -> f64 {
    let n = side.inward();
    let mut s = 0.0;
    for (i, fi) in f.iter().enumerate() {
        match C[i][0] * n[0] + C[i][1] * n[1] {
            0 => s += fi,
            k if k < 0 => s += 2.0 * fi,
            _ => {}
        }
    }
    s
}

/// Fill the three incoming populations so the node carries density `rho` and velocity `u` (Hecht & Harting's
/// form): axis f_a = f_ā + (2/3) ρ c_a·u; diagonals f_d = f_d̄ + (1/6) ρ c_d·u − (c_d·t) N_t with t the tangent
/// and N_t = ½ Σ_{c_j·n = 0} f_j c_j·t − (1/3) ρ u·t, the transverse-momentum correction.
fn close(f: &mut Populations, side: Side, rho: f64, u: [f64; 2]) {
    let n = side.inward();
    let t = [n[1].abs(), n[0].abs()]; // (0,1) for west/east, (1,0) for south/north
    let mut tangential = 0.0;
    for (j, fj) in f.iter().enumerate() {
        if C[j][0] * n[0] + C[j][1] * n[1] == 0 {
            tangential += fj * (C[j][0] * t[0] + C[j][1] * t[1]) as f64;
        }
    }
    let n_t = 0.5 * tangential - rho * dot(t, u) / 3.0;
    for i in incoming(side) {
        let cu = dot(C[i], u);
        let ct = (C[i][0] * t[0] + C[i][1] * t[1]) as f64;
        f[i] = if ct == 0.0 {
            f[OPPOSITE[i]] + 2.0 / 3.0 * rho * cu
        } else {
            f[OPPOSITE[i]] + rho * cu / 6.0 - ct * n_t
        };
    }
}

/// Zou–He pressure closure on `side`: the node gets density `rho`, zero tangential velocity, and the normal
/// velocity u·n = 1 − (S_∥ + 2 S_out)/ρ. Returns the velocity.
pub fn zou_he_pressure(f: &mut Populations, side: Side, rho: f64) -> [f64; 2] {
    let n = side.inward();
    let un = 1.0 - known_mass_flux(f, side) / rho;
    let u = [un * n[0] as f64, un * n[1] as f64];
    close(f, side, rho, u);
    u
}

/// Zou–He velocity closure on `side`: the node gets velocity `u` and density ρ = (S_∥ + 2 S_out)/(1 − u·n).
/// Returns the density.
pub fn zou_he_velocity(f: &mut Populations, side: Side, u: [f64; 2]) -> f64 {
    let rho = known_mass_flux(f, side) / (1.0 - dot(side.inward(), u));
    close(f, side, rho, u);
    rho
}

/// Corner where two Zou–He sides meet (docs/references.md §3): with inward normals n_x, n_y and inward diagonal
/// d = n_x + n_y, f_a = f_ā + (2/3)ρ c_a·u for the two axes, f_d = f_d̄ + (1/6)ρ c_d·u, and the two buried
/// diagonals e (c_e·n_x and c_e·n_y of opposite signs) share what mass remains:
/// f_e = ½[ρ − Σ_{others} f] + (1/12) ρ c_e·u.
pub fn zou_he_corner(f: &mut Populations, x_side: Side, y_side: Side, rho: f64, u: [f64; 2]) {
    let (nx, ny) = (x_side.inward(), y_side.inward());
    let d = [nx[0] + ny[0], nx[1] + ny[1]];
    let dir = |v: [i64; 2]| (0..Q).find(|&i| C[i] == v).expect("a lattice direction");
    for a in [dir(nx), dir(ny)] {
        f[a] = f[OPPOSITE[a]] + 2.0 / 3.0 * rho * dot(C[a], u);
    }
    let di = dir(d);
    f[di] = f[OPPOSITE[di]] + rho * dot(C[di], u) / 6.0;
    let buried: Vec<usize> = (5..Q).filter(|&i| i != di && i != OPPOSITE[di]).collect();
    let others: f64 = (0..Q).filter(|i| !buried.contains(i)).map(|i| f[i]).sum();
    let x = 0.5 * (rho - others);
    for e in buried {
        f[e] = x + rho * dot(C[e], u) / 12.0;
    }
}

/// A lattice state: post-collision populations of every node (node (x, y) at `y * nx + x`) and the obstacle
/// flags (`true` = fixed solid obstacle node).
#[derive(Clone, Debug, PartialEq)]
pub struct Lattice {
    /// Nodes along x.
    pub nx: usize,
    /// Nodes along y.
    pub ny: usize,
    /// Populations per node.
    pub f: Vec<Populations>,
    /// Obstacle flag per node.
    pub solid: Vec<bool>,
}

/// Moving-solid coverage of one node for the reference step: node index and the solids covering it.
#[derive(Clone, Debug, PartialEq)]
pub struct Covered {
    /// Node index y * nx + x.
    pub node: usize,
    /// Solids covering the node.
    pub solids: Vec<Solid>,
}

/// Collision parameters of a reference step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Relaxation time τ.
    pub tau: f64,
    /// Body-force density (Guo).
    pub force: [f64; 2],
    /// PSM weighting for covered nodes.
    pub weighting: Weighting,
    /// Fluid collision: BGK (`None`) or TRT with this magic parameter Λ.
    pub magic: Option<f64>,
    /// Covered nodes use ΩΛ ([`psm_lambda`]) instead of Ω₁.
    pub lambda_consistent: bool,
    /// ΩΛ's (κ, α): ([`LAMBDA_FRICTION`], 0) or ([`LAMBDA_WALL_FRICTION`], [`LAMBDA_PRESSURE`]).
    pub lambda_terms: (f64, f64),
}

impl Lattice {
    /// Node index of (x, y).
    pub fn index(&self, x: usize, y: usize) -> usize {
        y * self.nx + x
    }

    /// Where a population pushed from (x, y) along c_q lands: `Some(node)` inside (wrapping across periodic
    /// sides), `None` if it leaves through a non-periodic side.
    pub fn destination(&self, x: usize, y: usize, q: usize, sides: &Sides) -> Option<usize> {
        let tx = x as i64 + C[q][0];
        let ty = y as i64 + C[q][1];
        let (nx, ny) = (self.nx as i64, self.ny as i64);
        let tx = if (0..nx).contains(&tx) {
            tx
        } else if sides.west == Condition::Periodic {
            tx.rem_euclid(nx)
        } else {
            return None;
        };
        let ty = if (0..ny).contains(&ty) {
            ty
        } else if sides.south == Condition::Periodic {
            ty.rem_euclid(ny)
        } else {
            return None;
        };
        Some(self.index(tx as usize, ty as usize))
    }
}

/// Push streaming with half-way bounce-back. Every fluid node pushes each population f_q to its neighbour
/// x + c_q; if that neighbour is an obstacle node, or the population leaves through a non-periodic side, it
/// comes back reversed at the same node: f_q̄(x) ← f_q(x). (Through a Zou–He side the reversed population is
/// unknown; it is filled with the bounce-back value here and overwritten by the closure in [`close_zou_he`].)
/// Obstacle nodes push nothing and are left as NaN (the caller overwrites them).
pub fn stream(lat: &Lattice, sides: &Sides) -> Vec<Populations> {
    let mut out = vec![[f64::NAN; Q]; lat.nx * lat.ny];
    for y in 0..lat.ny {
        for x in 0..lat.nx {
            let here = lat.index(x, y);
            if lat.solid[here] {
                continue;
            }
            for q in 0..Q {
                match lat.destination(x, y, q, sides) {
                    Some(there) if !lat.solid[there] => out[there][q] = lat.f[here][q],
                    _ => out[here][OPPOSITE[q]] = lat.f[here][q],
                }
            }
        }
    }
    out
}

/// The Zou–He side of node (x, y) along x and along y, if any. A node on both opposite sides (a lattice one
/// node wide) takes West (resp. South), as the kernels do.
fn zou_he_sides(lat: &Lattice, x: usize, y: usize, sides: &Sides) -> (Option<Side>, Option<Side>) {
    let xs = if x == 0 && sides.west.is_zou_he() {
        Some(Side::West)
    } else if x == lat.nx - 1 && sides.east.is_zou_he() {
        Some(Side::East)
    } else {
        None
    };
    let ys = if y == 0 && sides.south.is_zou_he() {
        Some(Side::South)
    } else if y == lat.ny - 1 && sides.north.is_zou_he() {
        Some(Side::North)
    } else {
        None
    };
    (xs, ys)
}

/// Close the Zou–He nodes of the streamed populations `streamed` (from state `before`, needed for the corner
/// density between two velocity sides). Obstacle nodes are skipped.
///
/// Corner conventions (documented in the kernels' `boundary` module): a Zou–He side meeting a wall keeps the
/// wall's bounce-back and applies the Zou–He side's closure; two Zou–He sides use [`zou_he_corner`] with
/// ρ = the prescribed density (mean of two pressure sides) or, for two velocity sides, the density of the
/// diagonal interior neighbour in `before` (1 if it is an obstacle node), and u = the prescribed velocity of a
/// velocity side, else 0.
pub fn close_zou_he(before: &Lattice, streamed: &mut [Populations], sides: &Sides) {
    close_zou_he_profiles(before, streamed, sides, &Profiles::default());
}

/// [`close_zou_he`] with per-node velocities for the velocity sides that have a profile.
pub fn close_zou_he_profiles(
    before: &Lattice,
    streamed: &mut [Populations],
    sides: &Sides,
    profiles: &Profiles,
) {
    // The condition of `side` at node (x, y): a profile replaces a velocity side's uniform velocity.
    let at = |side: Side, x: usize, y: usize| -> Condition {
        let p = profiles.of(side);
        match sides.of(side) {
            Condition::Velocity(_) if !p.is_empty() => Condition::Velocity(match side {
                Side::West | Side::East => p[y],
                Side::South | Side::North => p[x],
            }),
            c => c,
        }
    };
    for y in 0..before.ny {
        for x in 0..before.nx {
            let here = before.index(x, y);
            if before.solid[here] {
                continue;
            }
            let f = &mut streamed[here];
            match zou_he_sides(before, x, y, sides) {
                (None, None) => {}
                (Some(s), None) | (None, Some(s)) => match at(s, x, y) {
                    Condition::Pressure(rho) => {
                        zou_he_pressure(f, s, rho);
                    }
                    Condition::Velocity(u) => {
                        zou_he_velocity(f, s, u);
                    }
                    _ => unreachable!("only Zou–He sides are returned"),
                },
                (Some(sx), Some(sy)) => {
                    let rho = match (at(sx, x, y), at(sy, x, y)) {
                        (Condition::Pressure(a), Condition::Pressure(b)) => 0.5 * (a + b),
                        (Condition::Pressure(a), _) | (_, Condition::Pressure(a)) => a,
                        _ => {
                            let n = [sx.inward(), sy.inward()];
                            let ix = (x as i64 + n[0][0]).clamp(0, before.nx as i64 - 1) as usize;
                            let iy = (y as i64 + n[1][1]).clamp(0, before.ny as i64 - 1) as usize;
                            let j = before.index(ix, iy);
                            if before.solid[j] {
                                1.0
                            } else {
                                density(&before.f[j])
                            }
                        }
                    };
                    let u = match (at(sx, x, y), at(sy, x, y)) {
                        (Condition::Velocity(u), _) | (_, Condition::Velocity(u)) => u,
                        _ => [0.0, 0.0],
                    };
                    zou_he_corner(f, sx, sy, rho, u);
                }
            }
        }
    }
}

/// One reference step from the post-collision state `lat`: stream (push, with bounce-back), close the
/// Zou–He nodes, collide (BGK or TRT, forced or not; PSM at the `covered` nodes). Obstacle nodes end at the rest
/// equilibrium f^eq(1, 0) (the kernels' convention, so no garbage is ever stored). Returns the new state and,
/// per entry of `covered`, the force on each of its solids (zero at obstacle nodes).
///
/// This is the kernels' fused pull step in a different order of operations: pulling f_q(x) = f_q(x − c_q)
/// gives the same streamed populations as pushing f_q(x − c_q) to x, and bounce-back reads the same value,
/// so "reference `step` on S" and "kernel step on S" must agree to roundoff.
pub fn step(
    lat: &Lattice,
    sides: &Sides,
    params: &Params,
    covered: &[Covered],
) -> (Lattice, Vec<Vec<[f64; 2]>>) {
    step_with_profiles(lat, sides, &Profiles::default(), params, covered)
}

/// Ladd's correction at moving walls: every population of the streamed state that re-entered node (x, y)
/// through a [`Condition::MovingWall`] side gains 6 w_i ρ c_i·u_w, ρ the node's streamed density before the
/// corrections. A population that crossed two sides takes the velocity of the side crossed along y if it is a
/// moving wall, else that of the side crossed along x.
pub fn correct_moving_walls(lat: &Lattice, streamed: &mut [Populations], sides: &Sides) {
    let moving = |c: Condition| match c {
        Condition::MovingWall(u) => Some(u),
        _ => None,
    };
    for y in 0..lat.ny {
        for x in 0..lat.nx {
            let here = lat.index(x, y);
            if lat.solid[here] {
                continue;
            }
            let rho = density(&streamed[here]);
            for q in 1..Q {
                // The population now moving along c_q came from (x, y) − c_q.
                let sx = x as i64 - C[q][0];
                let sy = y as i64 - C[q][1];
                let x_side = if sx < 0 {
                    Some(Side::West)
                } else if sx >= lat.nx as i64 {
                    Some(Side::East)
                } else {
                    None
                };
                let y_side = if sy < 0 {
                    Some(Side::South)
                } else if sy >= lat.ny as i64 {
                    Some(Side::North)
                } else {
                    None
                };
                let crossed = |s: Option<Side>| s.filter(|&s| sides.of(s) != Condition::Periodic);
                let (x_side, y_side) = (crossed(x_side), crossed(y_side));
                if x_side.is_none() && y_side.is_none() {
                    continue;
                }
                let u = y_side
                    .and_then(|s| moving(sides.of(s)))
                    .or_else(|| x_side.and_then(|s| moving(sides.of(s))));
                if let Some(u) = u {
                    streamed[here][q] += 6.0 * W[q] * rho * (c(q)[0] * u[0] + c(q)[1] * u[1]);
                }
            }
        }
    }
}

/// [`step`] with per-node velocities on the velocity sides that have a profile.
pub fn step_with_profiles(
    lat: &Lattice,
    sides: &Sides,
    profiles: &Profiles,
    params: &Params,
    covered: &[Covered],
) -> (Lattice, Vec<Vec<[f64; 2]>>) {
    let mut streamed = stream(lat, sides);
    correct_moving_walls(lat, &mut streamed, sides);
    close_zou_he_profiles(lat, &mut streamed, sides, profiles);
    let mut next = lat.clone();
    for (n, f) in streamed.iter().enumerate() {
        next.f[n] = if lat.solid[n] {
            equilibrium(1.0, [0.0, 0.0])
        } else {
            fluid_collision(f, params.tau, params.magic, params.force)
        };
    }
    let mut forces = Vec::with_capacity(covered.len());
    let mut full = vec![false; lat.f.len()];
    for cov in covered {
        full[cov.node] =
            cov.solids.iter().map(|s| s.fraction).sum::<f64>() >= 1.0 - LAMBDA_FULL_GAP;
    }
    let rho: Vec<f64> = streamed.iter().map(density).collect();
    for cov in covered {
        if lat.solid[cov.node] {
            forces.push(vec![[0.0, 0.0]; cov.solids.len()]);
            continue;
        }
        if params.lambda_consistent {
            let (x, y) = (cov.node % lat.nx, cov.node / lat.nx);
            let open = open_links(lat, sides, &full, x, y);
            let solids: Vec<Solid> = cov
                .solids
                .iter()
                .map(|s| Solid {
                    wall_gradient: wall_gradient(lat, sides, &rho, &open, x, y, s.normal),
                    ..*s
                })
                .collect();
            let (f, ex) = psm_lambda(
                &streamed[cov.node],
                params.tau,
                params.magic,
                params.weighting,
                params.force,
                &solids,
                open,
                params.lambda_terms,
            );
            next.f[cov.node] = f;
            forces.push(ex);
            continue;
        }
        let (f, ex) = psm_with_collision(
            &streamed[cov.node],
            params.tau,
            params.magic,
            params.weighting,
            SolidOp::NonEquilibriumBounceBack,
            params.force,
            &cov.solids,
        );
        next.f[cov.node] = f;
        forces.push(ex);
    }
    (next, forces)
}
