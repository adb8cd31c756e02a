//! Analytical solutions the lattice-Boltzmann tests compare against (lattice or physical units alike, as long
//! as they are consistent).
//!
//! * Plane Poiseuille flow between walls at y = 0 and y = H driven by a pressure gradient (or body-force
//!   density) G = −dp/dx: u(y) = G/(2μ) · y (H − y), flux Q = G H³/(12 μ), mean velocity ū = G H²/(12 μ),
//!   maximum u(H/2) = G H²/(8 μ).
//! * The half-way bounce-back slip of the BGK lattice Boltzmann solution (`REFERENCE.md` §4.1; He, Zou, Luo &
//!   Dembo 1997; Ginzburg & d'Humières 2003): with body force per unit mass g, kinematic viscosity
//!   ν = (τ − ½)/3 and Λ = (τ − ½)², the D2Q9 solution on a channel of N nodes (H = N, walls half a spacing
//!   outside the edge nodes) is **exactly** u_LB(y) = g/(2ν) · y (H − y) + u_slip with
//!   u_slip = (g/ν)(16Λ − 3)/24, where y is the distance from the wall (node j at y = j + ½).
//! * Plane Couette flow between a wall at rest (y = 0) and a wall sliding at U (y = H): u(y) = U y/H.
//! * Stokes' first problem (Stokes 1851; e.g. Batchelor 1967, §4.3): a plane wall started impulsively at
//!   speed U under a fluid at rest drags it as u(d, t) = U erfc(d/(2√(νt))), d the distance from the wall.

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
        // REFERENCE.md §4.1: relative centreline error (16Λ − 3)/(3H²); τ = 0.875, H = 8 gives −0.39 %.
        let (g, tau, h) = (1e-6, 0.875, 8.0);
        let nu = lattice_viscosity(tau);
        let err = bounce_back_slip(g, nu, bgk_lambda(tau)) / poiseuille_max_velocity(g, nu, h);
        assert!((err - (-0.25 / 64.0)).abs() < 1e-12);
    }
}
