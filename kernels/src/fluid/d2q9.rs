//! The D2Q9 velocity set (Qian, d'Humières & Lallemand 1992) and its second-order equilibrium.
//!
//! Directions: c₀ = (0,0); c₁ = (1,0), c₂ = (0,1), c₃ = (−1,0), c₄ = (0,−1); c₅ = (1,1), c₆ = (−1,1),
//! c₇ = (−1,−1), c₈ = (1,−1). Weights w₀ = 4/9, w₁…₄ = 1/9, w₅…₈ = 1/36.
//!
//! Equilibrium (lattice units, c_s² = 1/3):
//! f_i^eq(ρ, u) = w_i ρ [1 + 3 c_i·u + 9/2 (c_i·u)² − 3/2 u·u].
//! Its moments are Σ f^eq = ρ, Σ f^eq c = ρu, Σ f^eq c c = ρ(c_s² I + u u) exactly.
use crate::Real;

/// Number of discrete velocities.
pub const Q: usize = 9;

/// Lattice velocities c_i (x, y components).
pub const VELOCITIES: [[i32; 2]; Q] = [
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

/// Opposite direction: c_{OPPOSITE[i]} = −c_i.
pub const OPPOSITE: [usize; Q] = [0, 3, 4, 1, 2, 7, 8, 5, 6];

/// Lattice weights as `f64` (convert with [`weights`]).
pub const WEIGHTS_F64: [f64; Q] = [
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

/// Lattice weights in precision `T`.
#[inline(always)]
pub fn weights<T: Real>() -> [T; Q] {
    let mut w = [T::zero(); Q];
    for (wi, &v) in w.iter_mut().zip(WEIGHTS_F64.iter()) {
        *wi = T::lit(v);
    }
    w
}

/// c_i as `T`.
#[inline(always)]
pub fn velocity<T: Real>(i: usize) -> [T; 2] {
    let c = VELOCITIES[i % Q];
    [T::lit(c[0] as f64), T::lit(c[1] as f64)]
}

/// Density ρ = Σ f_i.
#[inline(always)]
pub fn density<T: Real>(f: &[T; Q]) -> T {
    // Fixed summation order (rest, axes, diagonals) so every kernel reproduces the same roundoff.
    f[0] + ((f[1] + f[2]) + (f[3] + f[4])) + ((f[5] + f[6]) + (f[7] + f[8]))
}

/// Momentum j = Σ f_i c_i.
#[inline(always)]
pub fn momentum<T: Real>(f: &[T; Q]) -> [T; 2] {
    [
        (f[1] - f[3]) + ((f[5] - f[7]) + (f[8] - f[6])),
        (f[2] - f[4]) + ((f[5] - f[7]) + (f[6] - f[8])),
    ]
}

/// Second-order equilibrium f^eq(ρ, u) for all nine directions.
///
/// Written out per direction so that no multiplication by a zero velocity component is evaluated (the compiler
/// may not drop `0 · u`, which is NaN for infinite u), and opposite directions share c·u, 3 c·u and 9/2 (c·u)².
/// For finite ρ and u this is bitwise the textbook loop
/// `w_i ρ (((1 + 3 c_i·u) + 9/2 (c_i·u)²) − 3/2 u·u)` with c_i·u = c_ix u_x + c_iy u_y evaluated left to right:
/// `1·u = u`, `(−1)·u = −u`, `3(−a) = −(3a)`, `(9/2)(−a)(−a) = (9/2)a·a` and `a + (−b) = a − b` are exact in
/// IEEE arithmetic, and an added `0 · u` (±0) can only flip the sign of a zero c·u, which `1 + 3 c·u` absorbs.
#[inline(always)]
pub fn equilibrium<T: Real>(rho: T, u: [T; 2]) -> [T; Q] {
    let w = weights::<T>();
    let one = T::one();
    let three = T::lit(3.0);
    let four_half = T::lit(4.5);
    let [ux, uy] = u;
    let usq = T::lit(1.5) * (ux * ux + uy * uy);
    let (w0, w1, w5) = (w[0] * rho, w[1] * rho, w[5] * rho);
    // For a pair of opposite directions with c·u = ±cu: (w ρ [1 + 3cu + q − usq], w ρ [1 − 3cu + q − usq]).
    let pair = |wr: T, cu: T| {
        let a = three * cu;
        let q = four_half * cu * cu;
        (wr * (((one + a) + q) - usq), wr * (((one - a) + q) - usq))
    };
    let (f1, f3) = pair(w1, ux);
    let (f2, f4) = pair(w1, uy);
    let (f5, f7) = pair(w5, ux + uy);
    let (f8, f6) = pair(w5, ux - uy);
    [w0 * (one - usq), f1, f2, f3, f4, f5, f6, f7, f8]
}

/// Second moment Π_ab = Σ f_i c_ia c_ib as (xx, xy, yy).
#[inline(always)]
pub fn second_moment<T: Real>(f: &[T; Q]) -> [T; 3] {
    let diag = f[5] + f[6] + f[7] + f[8];
    [
        f[1] + f[3] + diag,
        (f[5] + f[7]) - (f[6] + f[8]),
        f[2] + f[4] + diag,
    ]
}
