//! The floating-point abstraction every kernel is generic over.
//!
//! `Real` is [`num_traits::Float`] (with `libm` behind it, so it works without `std`) plus the compound
//! assignment operators and a lossless-enough conversion from `f64` literals. Only IEEE-754 correctly rounded
//! operations (+, −, ×, ÷, sqrt) and software `libm` functions are used, so results are identical on every
//! platform and independent of the thread count.
use core::fmt::Debug;
use core::iter::Sum;
use core::ops::{AddAssign, DivAssign, MulAssign, SubAssign};

/// A floating-point scalar the kernels can be instantiated with: `f32` or `f64`.
pub trait Real:
    num_traits::Float
    + num_traits::FloatConst
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
    + Sum
    + Default
    + Debug
    + Send
    + Sync
    + 'static
{
    /// Machine name of the precision, for reports ("f32" / "f64").
    const NAME: &'static str;
    /// Convert an `f64` constant (rounding to nearest for `f32`).
    fn lit(x: f64) -> Self;
    /// Widen to `f64` (exact for both precisions).
    fn to_f64_exact(self) -> f64;
}

impl Real for f64 {
    const NAME: &'static str = "f64";
    #[inline(always)]
    fn lit(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn to_f64_exact(self) -> f64 {
        self
    }
}

impl Real for f32 {
    const NAME: &'static str = "f32";
    #[inline(always)]
    fn lit(x: f64) -> Self {
        x as f32
    }
    #[inline(always)]
    fn to_f64_exact(self) -> f64 {
        self as f64
    }
}
