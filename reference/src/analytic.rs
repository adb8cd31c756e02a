//! Analytical solutions the lattice-Boltzmann tests compare against (lattice or physical units alike, as long
//! as they are consistent).
//!
//! * Plane Poiseuille flow between walls at y = 0 and y = H driven by a pressure gradient (or body-force
//!   density) G = −dp/dx: u(y) = G/(2μ) · y (H − y), flux Q = G H³/(12 μ), mean velocity ū = G H²/(12 μ),
//!   maximum u(H/2) = G H²/(8 μ).
//! * The half-way bounce-back slip of the BGK lattice Boltzmann solution (He, Zou, Luo &
//!   Dembo 1997; Ginzburg & d'Humières 2003): with body force per unit mass g, kinematic viscosity
//!   ν = (τ − ½)/3 and Λ = (τ − ½)², the D2Q9 solution on a channel of N nodes (H = N, walls half a spacing
//!   outside the edge nodes) is **exactly** u_LB(y) = g/(2ν) · y (H − y) + u_slip with
//!   u_slip = (g/ν)(16Λ − 3)/24, where y is the distance from the wall (node j at y = j + ½).
//! * Plane Couette flow between a wall at rest (y = 0) and a wall sliding at U (y = H): u(y) = U y/H.
//! * Stokes' first problem (Stokes 1851; e.g. Batchelor 1967, §4.3): a plane wall started impulsively at
//!   speed U under a fluid at rest drags it as u(d, t) = U erfc(d/(2√(νt))), d the distance from the wall.
//! * Published figures: Sangani & Acrivos's drag of square cylinder arrays; Kozeny–Carman for discs.
//! * Diffusion: the slab drained at both faces (pressure diffusion, eq. 5.12) and Terzaghi's consolidation.

/// Poiseuille velocity u(y) = G/(2μ) · y (H − y) at distance `y` from the wall of a channel of width `h`,
/// driven by the pressure gradient (or body-force density) `g` = −dp/dx, dynamic viscosity `mu`.
pub fn poiseuille_velocity(g: f64, mu: f64, h: f64, y: f64) -> f64 {
    g / (2.0 * mu) * y * (h - y)
}

/// Poiseuille flux per unit depth, Q = ∫₀^H u dy = G H³/(12 μ).
pub fn poiseuille_flux(g: f64, mu: f64, h: f64) -> f64 {
    g * h * h * h / (12.0 * mu)
}

/// Poiseuille mean velocity ū = Q/H = G H²/(12 μ).
pub fn poiseuille_mean_velocity(g: f64, mu: f64, h: f64) -> f64 {
    g * h * h / (12.0 * mu)
}

/// Poiseuille centreline (maximum) velocity u(H/2) = G H²/(8 μ).
pub fn poiseuille_max_velocity(g: f64, mu: f64, h: f64) -> f64 {
    g * h * h / (8.0 * mu)
}

/// Lattice kinematic viscosity ν = (τ − ½)/3 of the BGK operator with relaxation time `tau`.
pub fn lattice_viscosity(tau: f64) -> f64 {
    (tau - 0.5) / 3.0
}

/// The BGK magic parameter Λ = (τ − ½)².
pub fn bgk_lambda(tau: f64) -> f64 {
    (tau - 0.5) * (tau - 0.5)
}

/// Half-way bounce-back slip velocity u_slip = (g/ν)(16Λ − 3)/24 for body force per unit mass `g`, lattice
/// viscosity `nu` and magic parameter `lambda` (Λ = (τ − ½)² for BGK). Zero at τ = ½ + √(3/16).
pub fn bounce_back_slip(g: f64, nu: f64, lambda: f64) -> f64 {
    g / nu * (16.0 * lambda - 3.0) / 24.0
}

/// The exact steady BGK lattice-Boltzmann velocity of body-force-driven Poiseuille flow with half-way
/// bounce-back walls at node `j` (0-based) of a channel of `n` nodes: the parabola at y = j + ½ plus the slip.
/// `g` is the force per unit mass, `tau` the relaxation time.
pub fn lattice_poiseuille_velocity(g: f64, tau: f64, n: usize, j: usize) -> f64 {
    let nu = lattice_viscosity(tau);
    let y = j as f64 + 0.5;
    poiseuille_velocity(g, nu, n as f64, y) + bounce_back_slip(g, nu, bgk_lambda(tau))
}

/// Plane Couette velocity u(y) = U y/H between a wall at rest at y = 0 and a wall sliding at `u_wall` at y = `h`.
pub fn couette_velocity(u_wall: f64, h: f64, y: f64) -> f64 {
    u_wall * y / h
}

/// Stokes' first problem: velocity at distance `d` from a plane wall started impulsively at speed `u_wall` a
/// time `t` ago in a fluid of kinematic viscosity `nu` at rest, U erfc(d/(2√(νt))). `erfc` from the `libm` crate.
pub fn stokes_first_problem(u_wall: f64, nu: f64, t: f64, d: f64) -> f64 {
    u_wall * libm::erfc(d / (2.0 * (nu * t).sqrt()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flux_is_the_integral_of_the_profile() {
        // Simpson's rule is exact for the parabola.
        let (g, mu, h) = (2.0e-5, 0.1, 7.0);
        let simpson = h / 6.0
            * (poiseuille_velocity(g, mu, h, 0.0)
                + 4.0 * poiseuille_velocity(g, mu, h, h / 2.0)
                + poiseuille_velocity(g, mu, h, h));
        let q = poiseuille_flux(g, mu, h);
        assert!((simpson - q).abs() <= 1e-15 * q);
        assert!((poiseuille_mean_velocity(g, mu, h) * h - q).abs() <= 1e-15 * q);
        assert!(
            (poiseuille_max_velocity(g, mu, h) - poiseuille_velocity(g, mu, h, h / 2.0)).abs()
                <= 1e-18
        );
    }

    #[test]
    fn stokes_first_problem_limits() {
        // u = U at the wall, U/2 at d = 2√(νt)·0.476936 (erfc⁻¹(½)), → 0 far away; erfc(1) = 0.157299...
        let (u, nu, t) = (0.01, 0.1, 400.0);
        assert_eq!(stokes_first_problem(u, nu, t, 0.0), u);
        let half = 2.0 * (nu * t).sqrt() * 0.476_936_276_204_469_9;
        assert!((stokes_first_problem(u, nu, t, half) - 0.5 * u).abs() < 1e-15);
        let one = 2.0 * (nu * t).sqrt();
        assert!((stokes_first_problem(u, nu, t, one) / u - 0.157_299_207_050_285_1).abs() < 1e-15);
        // erfc(20) = 5.4e-176.
        assert!(stokes_first_problem(u, nu, t, 20.0 * one) < 1e-177);
        assert_eq!(couette_velocity(2.0, 4.0, 1.0), 0.5);
    }

    #[test]
    fn slip_vanishes_at_the_magic_tau() {
        let tau = 0.5 + (3.0f64 / 16.0).sqrt();
        let nu = lattice_viscosity(tau);
        assert!(bounce_back_slip(1e-6, nu, bgk_lambda(tau)).abs() < 1e-20);
        // The slip formula: relative centreline error (16Λ − 3)/(3H²); τ = 0.875, H = 8 gives −0.39 %.
        let (g, tau, h) = (1e-6, 0.875, 8.0);
        let nu = lattice_viscosity(tau);
        let err = bounce_back_slip(g, nu, bgk_lambda(tau)) / poiseuille_max_velocity(g, nu, h);
        assert!((err - (-0.25 / 64.0)).abs() < 1e-12);
    }
}

/// Sangani & Acrivos (1982, Int. J. Multiphase Flow 8, 193–206), table 1, square array of cylinders in Stokes
/// flow: (solid fraction c, dimensionless drag F/(μU)) with U the superficial velocity and F the drag per
/// cylinder (per unit length) balancing the mean pressure gradient over the cell, F = G l².
pub const SANGANI_ACRIVOS_SQUARE: [(f64, f64); 9] = [
    (0.05, 15.56),
    (0.10, 24.83),
    (0.20, 51.53),
    (0.30, 102.90),
    (0.40, 217.89),
    (0.50, 532.55),
    (0.60, 1.763e3),
    (0.70, 1.352e4),
    (0.75, 1.263e5),
];

/// Sangani & Acrivos's drag F/(μU) of the square array at solid fraction `c`: the table value at a tabulated
/// c, log-linear interpolation between them (an estimate only, e.g. to size a drive), `None` outside
/// 0.05 ≤ c ≤ 0.75.
pub fn sangani_acrivos_drag(c: f64) -> Option<f64> {
    let t = &SANGANI_ACRIVOS_SQUARE;
    for w in t.windows(2) {
        let ((c0, f0), (c1, f1)) = (w[0], w[1]);
        if (c - c0).abs() < 1e-12 {
            return Some(f0);
        }
        if c > c0 && c < c1 {
            let s = (c - c0) / (c1 - c0);
            return Some((f0.ln() + s * (f1.ln() - f0.ln())).exp());
        }
    }
    let (cl, fl) = t[t.len() - 1];
    ((c - cl).abs() < 1e-12).then_some(fl)
}

/// Sangani & Acrivos's tabulated drag at exactly a tabulated solid fraction (within 1e-9), else `None`.
pub fn sangani_acrivos_tabulated(c: f64) -> Option<f64> {
    SANGANI_ACRIVOS_SQUARE
        .iter()
        .find(|(cs, _)| (cs - c).abs() < 1e-9)
        .map(|(_, f)| *f)
}

/// Kozeny–Carman permeability of a bed of discs (2-D) of diameter `diameter` at porosity `porosity` with Kozeny
/// constant `c_k`: k = n³D²/(16 c_K (1 − n)²) (the dissertation's eq. 5.8 with its two slips corrected: the
/// specific surface of discs is 4(1 − n)/D).
pub fn kozeny_carman(porosity: f64, diameter: f64, c_k: f64) -> f64 {
    let n = porosity;
    n.powi(3) * diameter * diameter / (16.0 * c_k * (1.0 - n).powi(2))
}

/// The Kozeny constant implied by a permeability: [`kozeny_carman`] solved for c_K.
pub fn kozeny_constant(porosity: f64, diameter: f64, permeability: f64) -> f64 {
    let n = porosity;
    n.powi(3) * diameter * diameter / (16.0 * permeability * (1.0 - n).powi(2))
}

/// Pressure diffusion in a slab −L ≤ x ≤ L from a uniform initial overpressure P₀, both faces held at 0
/// (Carslaw & Jaeger 1959, §3.3; the dissertation's eq. 5.12): P/P₀ = Σ_m (4/π) (−1)^m/(2m+1)
/// cos((2m+1)πx/(2L)) exp(−(2m+1)²π² c t/(4L²)). Returns (P/P₀, ∂(P/P₀)/∂c).
pub fn slab_pressure(x: f64, t: f64, c: f64, half_length: f64) -> (f64, f64) {
    let pi = std::f64::consts::PI;
    let mut p = 0.0;
    let mut dp = 0.0;
    for m in 0..10_000 {
        let k = (2 * m + 1) as f64;
        let lam = k * k * pi * pi / (4.0 * half_length * half_length);
        let e = (-lam * c * t).exp();
        let sign = if m % 2 == 0 { 1.0 } else { -1.0 };
        let a = 4.0 / pi * sign / k * (k * pi * x / (2.0 * half_length)).cos();
        p += a * e;
        dp += -a * lam * t * e;
        if lam * c * t > 50.0 {
            break;
        }
    }
    (p, dp)
}

/// Mean of P/P₀ over the slab of [`slab_pressure`]: Σ_m 8/((2m+1)²π²) exp(−(2m+1)²π² c t/(4L²)).
pub fn slab_mean_pressure(t: f64, c: f64, half_length: f64) -> f64 {
    let pi = std::f64::consts::PI;
    let mut s = 0.0;
    for m in 0..10_000 {
        let k = (2 * m + 1) as f64;
        let arg = k * k * pi * pi * c * t / (4.0 * half_length * half_length);
        s += 8.0 / (k * k * pi * pi) * (-arg).exp();
        if arg > 50.0 {
            break;
        }
    }
    s
}

#[cfg(test)]
mod published {
    use super::*;

    #[test]
    fn sangani_acrivos_lookup_and_interpolation() {
        assert_eq!(sangani_acrivos_drag(0.5), Some(532.55));
        let f = sangani_acrivos_drag(0.45).unwrap();
        assert!(f > 217.89 && f < 532.55);
        assert_eq!(sangani_acrivos_drag(0.8), None);
    }

    #[test]
    fn kozeny_constant_inverts_kozeny_carman() {
        let k = kozeny_carman(0.6, 10.0, 9.4);
        assert!((kozeny_constant(0.6, 10.0, k) - 9.4).abs() < 1e-12);
        // c_K = 5 gives n³D²/(80(1 − n)²): 6.25e-3 D² at n = 0.5.
        assert!((kozeny_carman(0.5, 1.0, 5.0) - 6.25e-3).abs() < 1e-15);
    }

    #[test]
    fn slab_series_starts_at_one_and_drains_to_zero() {
        // Inside the slab at t → 0 the series sums to 1 (Fourier series of the constant); the faces are at 0.
        let (p, _) = slab_pressure(0.3, 1e-6, 1.0, 1.0);
        assert!((p - 1.0).abs() < 1e-3, "{p}");
        assert!(slab_pressure(1.0, 0.1, 1.0, 1.0).0.abs() < 1e-12);
        assert!((slab_mean_pressure(1e-8, 1.0, 1.0) - 1.0).abs() < 1e-3);
        // Late times: one mode, 8/π² exp(−π² c t/(4L²)).
        let t = 2.0;
        let one =
            8.0 / std::f64::consts::PI.powi(2) * (-std::f64::consts::PI.powi(2) * t / 4.0).exp();
        assert!((slab_mean_pressure(t, 1.0, 1.0) - one).abs() < 1e-12 * one.max(1e-300) + 1e-15);
    }
}
