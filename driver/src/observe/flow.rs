//! Flow measures over a lattice's moments.
use lbdem_kernels::Real;

/// Largest node Mach number |u| √3 (lattice units, c_s = 1/√3).
pub fn max_mach<T: Real>(u: &[[T; 2]]) -> f64 {
    u.iter()
        .map(|v| (v[0].to_f64_exact().powi(2) + v[1].to_f64_exact().powi(2)).sqrt() * 3f64.sqrt())
        .fold(0.0, f64::max)
}

/// Row means of the fluid-only (ε = 0) lattice density, rows `rows` (lattice row indices), as
/// (row, mean density, fluid-only nodes); rows without a fluid-only node are left out. The pore pressure of a
/// row is c_s² (mean − ρ₀).
pub fn fluid_row_means<T: Real>(
    rho: &[T],
    solid_fraction: &[f64],
    nx: usize,
    rows: std::ops::Range<usize>,
) -> Vec<(usize, f64, usize)> {
    rows.filter_map(|y| {
        let (mut s, mut n) = (0.0, 0usize);
        for x in 0..nx {
            let i = y * nx + x;
            if solid_fraction[i] == 0.0 {
                s += rho[i].to_f64_exact();
                n += 1;
            }
        }
        (n > 0).then(|| (y, s / n as f64, n))
    })
    .collect()
}
