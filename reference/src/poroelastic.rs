//! Linear poroelasticity in uniaxial strain (one-dimensional consolidation): the storage coefficient, the
//! loading efficiency, the consolidation coefficient and Terzaghi's pore-pressure series.
//!
//! Notation (Wang 2000, *Theory of Linear Poroelasticity*, ch. 2–3 and 6; Detournay & Cheng 1993,
//! *Fundamentals of poroelasticity*, §2): porosity n, fluid compressibility β_f = 1/K_f, grain compressibility
//! β_s = 1/K_s, drained bulk modulus K, drained **constrained** (uniaxial-strain, oedometric) modulus
//! K_v = K + 4G/3 in 3-D (in any dimension: the ratio of the axial stress step to the axial strain with the
//! lateral strain held at zero), Biot coefficient α = 1 − K/K_s (1 for incompressible grains).
//!
//! * Biot modulus M (storage at constant strain): 1/M = n β_f + (α − n) β_s (Detournay & Cheng 1993;
//!   Wang 2000, ch. 2).
//! * Uniaxial storage coefficient (storage at constant vertical stress and zero lateral strain):
//!   S = 1/M + α²/K_v (Wang 2000, ch. 3 and 6: S = S_ε + α²/K_v).
//! * Loading efficiency (the pore pressure raised by an undrained vertical stress step, per unit stress):
//!   γ = α/(K_v S) = α M/(K_v + α² M) (Wang 2000, ch. 6). γ → 1 for a soft skeleton and stiff fluid,
//!   γ → 0 for a stiff skeleton or a very compressible fluid.
//! * Consolidation coefficient (the hydraulic diffusivity of the pore-pressure equation
//!   ∂p/∂t = c_v ∂²p/∂z² under a constant load): c_v = k/(μ S) = k M K_v/(μ (K_v + α² M)) with k the
//!   permeability and μ the dynamic viscosity (Wang 2000, ch. 6; Terzaghi 1943 for the incompressible
//!   constituents, where S = 1/K_v and c_v = k K_v/μ).
//! * Terzaghi's solution (Terzaghi 1943; Wang 2000, ch. 6): a layer of thickness L drained at its top (depth 0) and
//!   impervious at its base (depth L), initial excess pressure γσ₀ after a step load σ₀:
//!   p/(γσ₀) = Σ_m (4/((2m+1)π)) sin((2m+1)π z/(2L)) exp(−(2m+1)²π² c_v t/(4L²)). The dissertation's
//!   eq. 5.13 writes the same solution as an image series of complementary error functions
//!   ([`terzaghi_pressure_images`]), which converges fast at small times; the two are checked against each
//!   other below, so either can serve as the other's oracle.
//!
//! Units: any consistent set. In 2-D (unit thickness) moduli and pressures are force per unit length of a unit
//! thickness (force/area), compressibilities their inverse, permeability an area.
use crate::analytic::slab_pressure;

/// Biot modulus M from porosity `n`, fluid compressibility `beta_f`, grain compressibility `beta_s` and Biot
/// coefficient `alpha`: 1/M = n β_f + (α − n) β_s (Detournay & Cheng 1993). Infinite when both
/// constituents are incompressible.
pub fn biot_modulus(n: f64, beta_f: f64, beta_s: f64, alpha: f64) -> f64 {
    1.0 / (n * beta_f + (alpha - n) * beta_s)
}

/// Biot coefficient α = 1 − K/K_s from the drained bulk modulus `k_drained` and the grain compressibility
/// `beta_s` = 1/K_s (α = 1 for incompressible grains, β_s = 0).
pub fn biot_coefficient(k_drained: f64, beta_s: f64) -> f64 {
    1.0 - k_drained * beta_s
}

/// Uniaxial storage coefficient S = 1/M + α²/K_v (Wang 2000, ch. 6) from the Biot modulus `m`, the Biot
/// coefficient `alpha` and the drained constrained modulus `k_v`.
pub fn uniaxial_storage(m: f64, alpha: f64, k_v: f64) -> f64 {
    1.0 / m + alpha * alpha / k_v
}

/// Loading efficiency γ = α/(K_v S) (Wang 2000, ch. 6): the undrained pore-pressure rise per unit vertical
/// stress step in uniaxial strain.
pub fn loading_efficiency(m: f64, alpha: f64, k_v: f64) -> f64 {
    alpha / (k_v * uniaxial_storage(m, alpha, k_v))
}

/// Consolidation coefficient c_v = k/(μ S) (Wang 2000, ch. 6) from the permeability `k`, the dynamic
/// viscosity `mu` and the uniaxial storage coefficient `s` ([`uniaxial_storage`]).
pub fn consolidation_coefficient(k: f64, mu: f64, s: f64) -> f64 {
    k / (mu * s)
}

/// The contributions to the uniaxial storage S of a packing of incompressible grains (α = 1, β_s = 0):
/// (fluid term n β_f, skeleton term 1/K_v). Their sum is [`uniaxial_storage`].
pub fn storage_terms(n: f64, beta_f: f64, k_v: f64) -> (f64, f64) {
    (n * beta_f, 1.0 / k_v)
}

/// Drained constrained modulus from a uniaxial-strain step: the vertical stress change over the vertical
/// strain it caused (compression positive both).
pub fn constrained_modulus(stress_step: f64, strain: f64) -> f64 {
    stress_step / strain
}

/// Terzaghi's pore pressure p/(γσ₀) at `depth` below the drained top of a layer of `thickness` L, time `t`
/// after the load step, consolidation coefficient `c_v` (Fourier series; Wang 2000 §6.3). By symmetry the
/// layer is half of a slab of half-length L drained at both faces ([`slab_pressure`] at x = L − depth).
pub fn terzaghi_pressure(depth: f64, t: f64, c_v: f64, thickness: f64) -> f64 {
    slab_pressure(thickness - depth, t, c_v, thickness).0
}

/// The same pressure as the dissertation's eq. 5.13 writes it (Wang 2000): the image series
/// 1 − Σ_n (−1)ⁿ [erfc(((2n+1)L − (z − L))/(2√(c t))) + erfc(((2n+1)L + (z − L))/(2√(c t)))], summed until the
/// terms fall below 1e-17. At t = 0 the layer is at 1 inside (0 < z ≤ L).
pub fn terzaghi_pressure_images(depth: f64, t: f64, c_v: f64, thickness: f64) -> f64 {
    if t <= 0.0 {
        return if depth > 0.0 { 1.0 } else { 0.0 };
    }
    let l = thickness;
    let x = depth - l;
    let w = 2.0 * (c_v * t).sqrt();
    let mut sum = 0.0;
    for n in 0..100_000u32 {
        let a = (2 * n + 1) as f64 * l;
        let term = libm::erfc((a - x) / w) + libm::erfc((a + x) / w);
        sum += if n % 2 == 0 { term } else { -term };
        if term < 1e-17 && n > 0 {
            break;
        }
    }
    1.0 - sum
}

/// Terzaghi's pore pressure p/(γσ₀) under a load that rises smoothly from 0 to σ₀ over `ramp`,
/// σ(t) = σ₀ sin²(π t/(2 t_r)) for t < t_r, then σ₀ (a step has t_r = 0): by Duhamel's superposition of the
/// step response ([`terzaghi_pressure`]) over the loading rate, p = γ ∫₀^t σ'(s) T(z, t − s) ds (Wang 2000,
/// ch. 6: the pore-pressure equation ∂p/∂t = c_v ∂²p/∂z² + γ ∂σ/∂t is linear). Mode by mode, with
/// a_m = (2m+1)²π² c_v/(4L²) and ω = π/t_r, the factor that replaces e^{−a t} of the step is
/// (ω/2)(ω e^{−a t} − ω cos ωt + a sin ωt)/(a² + ω²) while loading and (ω²/2)(e^{−a t} + e^{−a (t − t_r)})/(a² + ω²)
/// after (both → e^{−a t} as t_r → 0). Long after the ramp the solution is the step's from the ramp's middle,
/// t − t_r/2, to O((a t_r)²).
pub fn terzaghi_pressure_ramped(depth: f64, t: f64, c_v: f64, thickness: f64, ramp: f64) -> f64 {
    if ramp <= 0.0 {
        return terzaghi_pressure(depth, t, c_v, thickness);
    }
    if t <= 0.0 {
        return 0.0;
    }
    let pi = std::f64::consts::PI;
    let w = pi / ramp;
    let mut p = 0.0;
    for m in 0..100_000u32 {
        let k = (2 * m + 1) as f64;
        let a = k * k * pi * pi * c_v / (4.0 * thickness * thickness);
        let factor = if t < ramp {
            0.5 * w * (w * (-a * t).exp() - w * (w * t).cos() + a * (w * t).sin()) / (a * a + w * w)
        } else {
            0.5 * w * w * ((-a * t).exp() + (-a * (t - ramp)).exp()) / (a * a + w * w)
        };
        let term = 4.0 / (k * pi) * (k * pi * depth / (2.0 * thickness)).sin() * factor;
        p += term;
        // After the ramp the terms fall as (ω/a)² e^{−a (t − t_r)}/k; while loading only as 1/k³ (the tail
        // from k on is below 16 t_d/(π³ t_r k²), t_d = L²/c_v: stopped at 1e-8).
        let done = if t < ramp {
            16.0 / (pi * pi * pi) * (thickness * thickness / c_v) / ramp / (k * k) < 1e-8
        } else {
            4.0 / (k * pi) * w * w / (a * a + w * w) * (-a * (t - ramp)).exp() < 1e-15
        };
        if done {
            break;
        }
    }
    p
}

/// Degree of consolidation U = 1 − ⟨p⟩/(γσ₀) = 1 − Σ_m 2/M_m² exp(−M_m² T) with M_m = (2m+1)π/2 and the time
/// factor T = c_v t/L² (Terzaghi 1943).
pub fn degree_of_consolidation(time_factor: f64) -> f64 {
    let pi = std::f64::consts::PI;
    let mut s = 0.0;
    for m in 0..100_000u32 {
        let mm = (2 * m + 1) as f64 * pi / 2.0;
        let e = (-mm * mm * time_factor).exp();
        s += 2.0 / (mm * mm) * e;
        if mm * mm * time_factor > 60.0 {
            break;
        }
    }
    1.0 - s
}

/// Terzaghi's settlement of a column of thickness `l` (drained modulus `k_v`, loading efficiency `gamma`,
/// consolidation coefficient `c_v`) at time `t` after a step `load` σ₀ (Terzaghi 1943; Wang 2000 §6.2): the
/// undrained part (1 − γ)σ₀L/K_v at once, then the drained rest γσ₀L/K_v in proportion to the degree of
/// consolidation U(c_v t/L²) ([`degree_of_consolidation`]); σ₀L/K_v at the end.
pub fn terzaghi_settlement(load: f64, l: f64, k_v: f64, gamma: f64, c_v: f64, t: f64) -> f64 {
    let final_settlement = load * l / k_v;
    let u = degree_of_consolidation(c_v * t / (l * l));
    final_settlement * ((1.0 - gamma) + gamma * u)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settlement_goes_from_the_undrained_to_the_drained_strain() {
        let (load, l, kv, gamma, cv) = (5.0, 2.4, 1392.0, 0.42, 0.6);
        let drained = load * l / kv;
        // At the step: the skeleton's share (1 − γ) of the load, its strain over the column.
        assert!(
            (terzaghi_settlement(load, l, kv, gamma, cv, 0.0) / drained - (1.0 - gamma)).abs()
                < 2e-3
        );
        // Late: the whole load on the skeleton.
        assert!(
            (terzaghi_settlement(load, l, kv, gamma, cv, 50.0 * l * l / cv) / drained - 1.0).abs()
                < 1e-12
        );
        // Early: U = 2√(T/π) (the semi-infinite column; Terzaghi 1943), to O(T) corrections only exponentially small.
        let t = 0.01 * l * l / cv;
        let u = (terzaghi_settlement(load, l, kv, gamma, cv, t) / drained - (1.0 - gamma)) / gamma;
        assert!(
            (u - 2.0 * (0.01f64 / std::f64::consts::PI).sqrt()).abs() < 1e-6,
            "{u}"
        );
        // Monotone in time.
        let s: Vec<f64> = (0..50)
            .map(|k| terzaghi_settlement(load, l, kv, gamma, cv, 0.1 * k as f64))
            .collect();
        assert!(s.windows(2).all(|w| w[1] >= w[0]));
    }

    #[test]
    fn incompressible_constituents_reduce_to_terzaghi() {
        // β_f = β_s = 0: M infinite, S = 1/K_v, γ = 1, c_v = k K_v/μ (Terzaghi 1943).
        let m = biot_modulus(0.3, 0.0, 0.0, 1.0);
        assert!(m.is_infinite());
        let kv = 2.5e4;
        assert_eq!(uniaxial_storage(m, 1.0, kv), 1.0 / kv);
        assert_eq!(loading_efficiency(m, 1.0, kv), 1.0);
        let (k, mu) = (1e-4, 0.01);
        assert!((consolidation_coefficient(k, mu, 1.0 / kv) - k * kv / mu).abs() < 1e-12);
    }

    #[test]
    fn hand_values_of_storage_and_loading_efficiency() {
        // n = 0.25, β_f = 4e-3, incompressible grains: 1/M = 1e-3. K_v = 1000: 1/K_v = 1e-3, so S = 2e-3 and
        // γ = 1e-3/2e-3 = 0.5 (equal fluid and skeleton compliance share the load equally).
        let m = biot_modulus(0.25, 4e-3, 0.0, 1.0);
        assert!((m - 1000.0).abs() < 1e-9);
        assert!((uniaxial_storage(m, 1.0, 1000.0) - 2e-3).abs() < 1e-15);
        assert!((loading_efficiency(m, 1.0, 1000.0) - 0.5).abs() < 1e-12);
        let (f, s) = storage_terms(0.25, 4e-3, 1000.0);
        assert!((f + s - uniaxial_storage(m, 1.0, 1000.0)).abs() < 1e-18);
        // Compressible grains (Detournay & Cheng 1993): K = 500, K_s = 2000: α = 0.75; 1/M =
        // 0.25·4e-3 + 0.5·5e-4 = 1.25e-3.
        let a = biot_coefficient(500.0, 5e-4);
        assert!((a - 0.75).abs() < 1e-15);
        assert!((1.0 / biot_modulus(0.25, 4e-3, 5e-4, a) - 1.25e-3).abs() < 1e-15);
        // The two forms of γ agree: α/(K_v S) = α M/(K_v + α² M).
        let m = biot_modulus(0.25, 4e-3, 5e-4, a);
        let kv = 800.0;
        assert!(
            (loading_efficiency(m, a, kv) - a * m / (kv + a * a * m)).abs() < 1e-14,
            "γ forms"
        );
        assert!((constrained_modulus(5.0, 2e-3) - 2500.0).abs() < 1e-9);
    }

    #[test]
    fn consolidation_coefficient_scales_as_k_over_mu_s() {
        let base = consolidation_coefficient(1e-4, 0.01, 2e-3);
        assert!((base - 5.0).abs() < 1e-12);
        assert!((consolidation_coefficient(2e-4, 0.01, 2e-3) / base - 2.0).abs() < 1e-12);
        assert!((consolidation_coefficient(1e-4, 0.02, 2e-3) / base - 0.5).abs() < 1e-12);
        assert!((consolidation_coefficient(1e-4, 0.01, 4e-3) / base - 0.5).abs() < 1e-12);
    }

    #[test]
    fn terzaghi_fourier_series_agrees_with_the_image_series_of_eq_5_13() {
        // Two independent forms of the same solution; the Fourier form converges slowly at small t, the image
        // form at large t, both to far better than 1e-9 here.
        for &t in &[1e-3, 0.01, 0.05, 0.2, 0.5, 1.0, 3.0] {
            for k in 0..=20 {
                let z = k as f64 / 20.0 * 2.0;
                let a = terzaghi_pressure(z, t, 1.3, 2.0);
                let b = terzaghi_pressure_images(z, t, 1.3, 2.0);
                assert!((a - b).abs() < 1e-9, "t {t} z {z}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn terzaghi_limits_and_hand_values() {
        // t → 0: the whole layer at γσ₀ (series of the constant), the drained top at 0.
        assert!((terzaghi_pressure(1.0, 1e-4, 1.0, 2.0) - 1.0).abs() < 1e-9);
        assert!((terzaghi_pressure_images(0.5, 1e-9, 1.0, 2.0) - 1.0).abs() < 1e-12);
        assert!(terzaghi_pressure(0.0, 0.3, 1.0, 2.0).abs() < 1e-12);
        // Late: one mode, (4/π) sin(πz/2L) exp(−π²T/4); the base (z = L) at T = 1: (4/π) e^{−π²/4} = 0.10798.
        let one = 4.0 / std::f64::consts::PI * (-std::f64::consts::PI.powi(2) / 4.0).exp();
        assert!((terzaghi_pressure(2.0, 4.0, 1.0, 2.0) - one).abs() < 1e-6);
        assert!((one - 0.10798).abs() < 1e-5);
        // Hand check of one profile value from the leading two modes at T = 0.2, z/L = 0.5:
        // (4/π)[sin(π/4) e^{−0.2π²/4} + (1/3) sin(3π/4) e^{−1.8π²/4}] + (≈ −0.0018 from m = 2, 3) = 0.553.
        assert!((terzaghi_pressure(1.0, 0.2 * 4.0, 1.0, 2.0) - 0.553).abs() < 5e-4);
        // Scaling: the solution depends on c_v t/L² only.
        let a = terzaghi_pressure(0.7, 0.3, 2.0, 1.5);
        let b = terzaghi_pressure(1.4, 0.3, 8.0, 3.0);
        assert!((a - b).abs() < 1e-12, "{a} {b}");
    }

    #[test]
    fn ramped_load_is_the_duhamel_superposition_of_the_step() {
        // Independent oracle: Duhamel's integral of the step solution over the sin² loading rate by the
        // midpoint rule (20 000 slices of the ramp; its error ~1e-8 here), at times during and after the ramp.
        let (l, c, tr) = (2.0, 0.5, 0.4);
        let duhamel = |z: f64, t: f64| {
            let n = 20_000;
            let end = t.min(tr);
            let ds = end / n as f64;
            (0..n)
                .map(|i| {
                    let s = (i as f64 + 0.5) * ds;
                    let rate =
                        std::f64::consts::PI / (2.0 * tr) * (std::f64::consts::PI * s / tr).sin();
                    rate * terzaghi_pressure(z, t - s, c, l) * ds
                })
                .sum::<f64>()
        };
        for &t in &[0.1, 0.25, 0.4, 0.5, 1.0, 3.0] {
            for &z in &[0.1, 0.7, 1.5, 2.0] {
                let a = terzaghi_pressure_ramped(z, t, c, l, tr);
                let b = duhamel(z, t);
                assert!((a - b).abs() < 2e-6, "z {z} t {t}: {a} vs {b}");
            }
        }
        // A vanishing ramp is the step; long after the ramp the step from its middle (to O((a t_r)²)).
        for &z in &[0.3, 1.0, 2.0] {
            let a = terzaghi_pressure_ramped(z, 0.8, c, l, 1e-9);
            assert!((a - terzaghi_pressure(z, 0.8, c, l)).abs() < 1e-9);
            let late = terzaghi_pressure_ramped(z, 6.0, c, l, tr);
            let shifted = terzaghi_pressure(z, 6.0 - 0.5 * tr, c, l);
            assert!(
                (late - shifted).abs() < 2e-3 * shifted,
                "{late} vs {shifted}"
            );
        }
        // The load is fully on at the end of the ramp: nothing has drained at the sealed base of a thick layer.
        assert!((terzaghi_pressure_ramped(2.0, tr, 1e-4, l, tr) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn degree_of_consolidation_matches_the_mean_of_the_profile() {
        // U(T) = 1 − mean of p/(γσ₀) over the layer; midpoint rule over 2000 slices.
        for &tf in &[0.01, 0.1, 0.197, 0.5, 1.0, 2.0] {
            let n = 2000;
            let mean = (0..n)
                .map(|i| terzaghi_pressure((i as f64 + 0.5) / n as f64, tf, 1.0, 1.0))
                .sum::<f64>()
                / n as f64;
            let u = degree_of_consolidation(tf);
            assert!(
                (1.0 - mean - u).abs() < 1e-6,
                "T {tf}: {u} vs {}",
                1.0 - mean
            );
        }
        // Terzaghi's classical U = 50 % at T = 0.197 and U ≈ √(4T/π) for U < 0.6.
        assert!((degree_of_consolidation(0.197) - 0.5).abs() < 1e-3);
        let t = 0.05;
        assert!(
            (degree_of_consolidation(t) - (4.0 * t / std::f64::consts::PI).sqrt()).abs() < 1e-6
        );
    }
}
