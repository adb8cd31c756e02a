//! Flow measures over a lattice's moments.
use lbdem_kernels::Real;

/// Largest node Mach number |u| √3 (lattice units, c_s = 1/√3).
pub fn max_mach<T: Real>(u: &[[T; 2]]) -> f64 {
    u.iter()
        .map(|v| (v[0].to_f64_exact().powi(2) + v[1].to_f64_exact().powi(2)).sqrt() * 3f64.sqrt())
        .fold(0.0, f64::max)
}
