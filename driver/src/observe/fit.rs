//! Least-squares fits of measured series: a straight line, and the diffusivity of the slab solution.
use lbdem_reference::analytic::slab_pressure;

/// Least-squares line y = a x + b through the points: (slope a, intercept b, R²).
pub fn linear_fit(points: &[(f64, f64)]) -> (f64, f64, f64) {
    let m = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / m;
    let my = points.iter().map(|p| p.1).sum::<f64>() / m;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for &(x, y) in points {
        sxy += (x - mx) * (y - my);
        sxx += (x - mx) * (x - mx);
        syy += (y - my) * (y - my);
    }
    let a = sxy / sxx;
    let b = my - a * mx;
    let r2 = if syy > 0.0 {
        sxy * sxy / (sxx * syy)
    } else {
        1.0
    };
    (a, b, r2)
}

/// Least-squares fit of the diffusivity c to samples (x, t, P/P₀) of the slab solution
/// ([`lbdem_reference::analytic::slab_pressure`], eq. 5.12): Gauss–Newton on ln c, each linearised problem
/// J δ = r solved in least squares. The unknown is one number, so the least-squares step is the normal
/// equation δ = Σ J r / Σ J², summed in sample order: a dense QR (faer's) gives the same step to rounding but
/// its SIMD reductions start at the allocation's alignment, so its last bits vary from process to process —
/// and a resumed run must reproduce an uninterrupted one bitwise. Returns (c, rms residual, iterations).
pub fn fit_diffusivity(
    samples: &[(f64, f64, f64)],
    half_length: f64,
    c0: f64,
) -> (f64, f64, usize) {
    let mut lnc = c0.ln();
    let rms = |lnc: f64| -> f64 {
        let c = lnc.exp();
        (samples
            .iter()
            .map(|&(x, t, p)| (p - slab_pressure(x, t, c, half_length).0).powi(2))
            .sum::<f64>()
            / samples.len() as f64)
            .sqrt()
    };
    let mut iterations = 0;
    for it in 0..50 {
        iterations = it + 1;
        let c = lnc.exp();
        let eval: Vec<(f64, f64)> = samples
            .iter()
            .map(|&(x, t, _)| slab_pressure(x, t, c, half_length))
            .collect();
        // d model / d ln c = c d model / d c
        let (mut jr, mut jj) = (0.0, 0.0);
        for (s, e) in samples.iter().zip(&eval) {
            let j = c * e.1;
            jr += j * (s.2 - e.0);
            jj += j * j;
        }
        let delta = if jj > 0.0 { jr / jj } else { 0.0 };
        let mut step = delta.clamp(-1.0, 1.0);
        // Backtrack so the sum of squares never rises.
        let r0 = rms(lnc);
        while rms(lnc + step) > r0 && step.abs() > 1e-12 {
            step *= 0.5;
        }
        lnc += step;
        if step.abs() < 1e-10 {
            break;
        }
    }
    (lnc.exp(), rms(lnc), iterations)
}

/// Least-squares fit of the consolidation coefficient to samples (depth below the drained top, t, p/(γσ₀)) of
/// Terzaghi's solution for a layer of `thickness` L drained at the top and sealed at the base
/// ([`lbdem_reference::poroelastic::terzaghi_pressure`]): the layer is half of the slab of half-length L
/// drained at both faces, so this is [`fit_diffusivity`] at x = L − depth. Returns (c, rms residual,
/// iterations).
pub fn fit_consolidation(
    samples: &[(f64, f64, f64)],
    thickness: f64,
    c0: f64,
) -> (f64, f64, usize) {
    let slab: Vec<(f64, f64, f64)> = samples
        .iter()
        .map(|&(depth, t, p)| (thickness - depth, t, p))
        .collect();
    fit_diffusivity(&slab, thickness, c0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_fit_recovers_a_line() {
        let pts: Vec<(f64, f64)> = (0..5).map(|i| (i as f64, 2.0 * i as f64 + 1.0)).collect();
        let (a, b, r2) = linear_fit(&pts);
        assert!((a - 2.0).abs() < 1e-12 && (b - 1.0).abs() < 1e-12 && (r2 - 1.0).abs() < 1e-12);
    }

    #[test]
    fn diffusivity_fit_recovers_the_diffusivity_of_exact_samples() {
        let c = 0.37;
        let samples: Vec<(f64, f64, f64)> = [5.0, 20.0, 60.0]
            .iter()
            .flat_map(|&t| {
                (0..9).map(move |k| {
                    let x = -8.0 + 2.0 * k as f64;
                    (x, t, slab_pressure(x, t, c, 10.0).0)
                })
            })
            .collect();
        let (fit, rms, _) = fit_diffusivity(&samples, 10.0, 1.0);
        // Exact samples: Gauss–Newton converges to c up to its 1e-10 step criterion.
        assert!((fit / c - 1.0).abs() < 1e-8 && rms < 1e-10, "{fit} {rms}");
    }

    #[test]
    fn consolidation_fit_recovers_the_coefficient_of_exact_terzaghi_samples() {
        let (c, l) = (0.61, 2.4);
        let samples: Vec<(f64, f64, f64)> = [0.5, 2.0, 6.0]
            .iter()
            .flat_map(|&t| {
                (0..12).map(move |k| {
                    let z = 0.1 + 0.2 * k as f64;
                    (
                        z,
                        t,
                        lbdem_reference::poroelastic::terzaghi_pressure(z, t, c, l),
                    )
                })
            })
            .collect();
        let (fit, rms, _) = fit_consolidation(&samples, l, 1.0);
        // Exact samples: the fit converges to c up to Gauss–Newton's 1e-10 step criterion.
        assert!((fit / c - 1.0).abs() < 1e-8 && rms < 1e-10, "{fit} {rms}");
    }
}
