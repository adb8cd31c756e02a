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

/// Depth below the top of a granular column of its **Gibbs dividing surface**: the position of the sharp
/// interface that holds the same solid as the measured top layer, whose solid fraction falls from the column's
/// mean to zero over about a grain radius. With ε_y the mean solid fraction of row y (`solid_fraction`, rows
/// `0..rows`, row `rows − 1` at the top) and ε̄ the mean over the rows,
/// δ = h Σ (1 − ε_y/ε̄), summed from the top row down to (not including) the first row whose ε_y reaches ε̄.
/// The surface a drained porous layer presents to the free fluid above it sits at this depth, not at the
/// tops of the highest grains (the rows above it hold mostly free fluid). 0 when the top row is already as
/// dense as the mean, or when the column holds no solid.
pub fn dividing_surface_depth(solid_fraction: &[f64], nx: usize, rows: usize, spacing: f64) -> f64 {
    // Only whole rows that the slice holds (a short slice is not indexed past its end).
    let rows = rows.min(solid_fraction.len().checked_div(nx).unwrap_or(0));
    if rows == 0 {
        return 0.0;
    }
    let row_mean = |y: usize| solid_fraction[y * nx..(y + 1) * nx].iter().sum::<f64>() / nx as f64;
    let mean = (0..rows).map(row_mean).sum::<f64>() / rows as f64;
    if mean <= 0.0 {
        return 0.0;
    }
    let mut depth = 0.0;
    for y in (0..rows).rev() {
        let e = row_mean(y);
        if e >= mean {
            break;
        }
        depth += spacing * (1.0 - e / mean);
    }
    depth
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sharp interface: a column of B rows at solid fraction e under T rows of free fluid (inside the counted
    /// rows) has its dividing surface exactly at the interface, T h below the top.
    #[test]
    fn dividing_surface_of_a_sharp_interface_is_the_interface() {
        let (nx, b, t, h, e) = (4, 30, 5, 0.02, 0.55);
        let mut eps = vec![0.0; nx * (b + t)];
        eps[..nx * b].fill(e);
        let d = dividing_surface_depth(&eps, nx, b + t, h);
        // Sum of T terms h (1 − 0): roundoff of T additions.
        assert!((d - t as f64 * h).abs() < 1e-14, "{d}");
    }

    /// B rows at e under a top layer whose fraction falls linearly from e to 0 over m rows (row centres at
    /// (k + ½)/m of the ramp). The column mean is ε̄ = e (B + m/2)/(B + m); with B ≫ m every ramp row lies
    /// below it, and the sum has the closed form m h (1 − e/(2ε̄)) (the ramp's mean fraction is e/2 by the
    /// midpoint rule of a linear function) — the middle of the ramp, m h/2, as B → ∞.
    #[test]
    fn dividing_surface_of_a_linear_top_layer_is_near_its_middle() {
        let (nx, b, m, h, e) = (3, 400, 8, 0.05, 0.6);
        let rows = b + m;
        let mut eps = vec![e; nx * rows];
        for k in 0..m {
            let f = e * (1.0 - (k as f64 + 0.5) / m as f64);
            eps[(b + k) * nx..(b + k + 1) * nx].fill(f);
        }
        let mean = e * (b as f64 + 0.5 * m as f64) / rows as f64;
        let expected = m as f64 * h * (1.0 - e / (2.0 * mean));
        let d = dividing_surface_depth(&eps, nx, rows, h);
        // Roundoff of sums over ~10³ terms.
        assert!((d - expected).abs() < 1e-12, "{d} vs {expected}");
        assert!((d - 0.5 * m as f64 * h).abs() < 0.01 * m as f64 * h, "{d}");
    }

    #[test]
    fn a_uniform_or_empty_column_has_its_dividing_surface_at_the_top() {
        assert_eq!(dividing_surface_depth(&[0.5; 12], 3, 4, 0.1), 0.0);
        assert_eq!(dividing_surface_depth(&[0.0; 12], 3, 4, 0.1), 0.0);
        assert_eq!(dividing_surface_depth(&[], 0, 0, 0.1), 0.0);
        // More rows asked than the slice holds: only its whole rows count (here the step case's answer).
        let mut eps = vec![0.0; 4 * 35];
        eps[..4 * 30].fill(0.55);
        assert!((dividing_surface_depth(&eps, 4, 99, 0.02) - 0.1).abs() < 1e-14);
    }
}
