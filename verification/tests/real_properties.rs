//! The `Real` scalar trait (`lbdem_kernels::Real`) for both precisions: the portable transcendental functions
//! (always the `libm` crate) agree with the platform's `f64` functions (an independent implementation), and the
//! conversions are what they say.
//!
//! **Tolerances.** Both implementations are faithfully rounded or better, so in `f64` they differ by at most
//! 2 ulp of the result (allowance 4 ulp, or 4 ulp of 1 near zero crossings, where a relative bound says
//! nothing); the `f32` functions are compared with the `f64` value of the same (exact) `f32` argument, within 2
//! ulp of `f32` (allowance 4).
use lbdem_kernels::Real;
use lbdem_verification::proptest_cases;
use proptest::prelude::*;

fn config(default: u32) -> ProptestConfig {
    ProptestConfig::with_cases(proptest_cases(default))
}

/// |got − want| within `ulps` units in the last place of max(|want|, `floor`) in precision `eps`.
fn close(got: f64, want: f64, eps: f64, ulps: f64, floor: f64) -> bool {
    (got - want).abs() <= ulps * eps * want.abs().max(floor)
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn f64_portable_functions_match_the_platform(x in -20.0f64..20.0, y in -20.0f64..20.0, p in 1e-6f64..1e6) {
        let e = f64::EPSILON;
        prop_assert!(close(x.portable_sin(), x.sin(), e, 4.0, 1.0));
        prop_assert!(close(x.portable_cos(), x.cos(), e, 4.0, 1.0));
        let (s, c) = x.portable_sin_cos();
        prop_assert_eq!((s.to_bits(), c.to_bits()), (x.portable_sin().to_bits(), x.portable_cos().to_bits()));
        prop_assert!(close(y.portable_atan2(x), y.atan2(x), e, 4.0, 1e-300));
        prop_assert!(close(x.portable_hypot(y), x.hypot(y), e, 4.0, 1e-300));
        prop_assert!(close(p.portable_ln(), p.ln(), e, 4.0, 1.0));
        prop_assert_eq!(<f64 as Real>::lit(x).to_bits(), x.to_bits());
        prop_assert_eq!(x.to_f64_exact().to_bits(), x.to_bits());
    }

    #[test]
    fn f32_portable_functions_match_f64(x in -20.0f32..20.0, y in -20.0f32..20.0, p in 1e-6f32..1e6) {
        let e = f32::EPSILON as f64;
        let (xd, yd, pd) = (x as f64, y as f64, p as f64);
        prop_assert!(close(x.portable_sin() as f64, xd.sin(), e, 4.0, 1.0));
        prop_assert!(close(x.portable_cos() as f64, xd.cos(), e, 4.0, 1.0));
        let (s, c) = x.portable_sin_cos();
        prop_assert_eq!((s.to_bits(), c.to_bits()), (x.portable_sin().to_bits(), x.portable_cos().to_bits()));
        prop_assert!(close(y.portable_atan2(x) as f64, yd.atan2(xd), e, 4.0, 1e-30));
        prop_assert!(close(x.portable_hypot(y) as f64, xd.hypot(yd), e, 4.0, 1e-30));
        prop_assert!(close(p.portable_ln() as f64, pd.ln(), e, 4.0, 1.0));
        // lit rounds to nearest; to_f64_exact widens exactly.
        prop_assert_eq!(<f32 as Real>::lit(xd + 1e-12).to_bits(), ((xd + 1e-12) as f32).to_bits());
        prop_assert_eq!(x.to_f64_exact().to_bits(), xd.to_bits());
    }
}

proptest! {
    #![proptest_config(config(512))]

    /// The batched atan2 is bitwise the scalar one in every lane, for any bit patterns (NaN, infinities, zeros,
    /// subnormals and huge or tiny ratios included) and for values near the unit circle, as the coverage
    /// kernel passes them; f64 runs `libm`'s algorithm over the lanes, f32 the scalar function per lane.
    #[test]
    fn batched_atan2_is_bitwise_the_scalar_one(
        yb in prop::array::uniform8(any::<u64>()),
        xb in prop::array::uniform8(any::<u64>()),
        yc in prop::array::uniform8(-1.5f64..1.5),
        xc in prop::array::uniform8(-1.5f64..1.5),
    ) {
        for (y, x) in [(yb.map(f64::from_bits), xb.map(f64::from_bits)), (yc, xc)] {
            let got = f64::portable_atan2_lanes(&y, &x);
            for l in 0..8 {
                let want = y[l].portable_atan2(x[l]);
                prop_assert!(got[l].to_bits() == want.to_bits() || (got[l].is_nan() && want.is_nan()),
                    "f64 atan2({:e}, {:e}) = {:e}, scalar {:e}", y[l], x[l], got[l], want);
            }
            let (yf, xf) = (y.map(|v| v as f32), x.map(|v| v as f32));
            let got = f32::portable_atan2_lanes(&yf, &xf);
            for l in 0..8 {
                let want = yf[l].portable_atan2(xf[l]);
                prop_assert!(got[l].to_bits() == want.to_bits() || (got[l].is_nan() && want.is_nan()));
            }
        }
    }
}

#[test]
fn precision_names() {
    assert_eq!(<f64 as Real>::NAME, "f64");
    assert_eq!(<f32 as Real>::NAME, "f32");
}
