//! The floating-point abstraction every kernel is generic over.
//!
//! `Real` is [`num_traits::Float`] plus the compound assignment operators and a conversion from `f64`
//! literals. Only IEEE-754 correctly rounded operations (+, −, ×, ÷, sqrt) and the software `libm` crate are
//! used, so results are identical on every platform, in every build, and for any thread count.
//!
//! **Transcendental functions go through the `portable_*` methods below, never through `Float::sin` & co.**
//! `num_traits::Float` forwards those to the platform's C library when any crate in the build enables
//! num-traits' `std` feature (criterion and proptest do), and to the `libm` crate otherwise, so the same
//! kernel could give different last bits in a workspace build and a single-crate build. The portable methods
//! always call `libm`. `clippy.toml` disallows the `Float` versions.
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
    /// sin, from the `libm` crate (the same bits in every build).
    fn portable_sin(self) -> Self;
    /// cos, from the `libm` crate.
    fn portable_cos(self) -> Self;
    /// (sin, cos), from the `libm` crate.
    fn portable_sin_cos(self) -> (Self, Self) {
        (self.portable_sin(), self.portable_cos())
    }
    /// atan2(self, x), from the `libm` crate.
    fn portable_atan2(self, x: Self) -> Self;
    /// [`Real::portable_atan2`] of every lane, `y[l].portable_atan2(x[l])`: the same bits, computed a batch at a
    /// time (f64: `libm`'s algorithm written over the lanes so that the compiler vectorises it; f32: lane by
    /// lane).
    #[inline(always)]
    fn portable_atan2_lanes<const L: usize>(y: &[Self; L], x: &[Self; L]) -> [Self; L] {
        core::array::from_fn(|l| y[l].portable_atan2(x[l]))
    }
    /// hypot(self, y), from the `libm` crate.
    fn portable_hypot(self, y: Self) -> Self;
    /// Natural logarithm, from the `libm` crate.
    fn portable_ln(self) -> Self;
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
    #[inline]
    fn portable_sin(self) -> Self {
        libm::sin(self)
    }
    #[inline]
    fn portable_cos(self) -> Self {
        libm::cos(self)
    }
    #[inline]
    fn portable_atan2(self, x: Self) -> Self {
        libm::atan2(self, x)
    }
    #[inline(always)]
    fn portable_atan2_lanes<const L: usize>(y: &[Self; L], x: &[Self; L]) -> [Self; L] {
        crate::lanes::atan2_f64(y, x)
    }
    #[inline]
    fn portable_hypot(self, y: Self) -> Self {
        libm::hypot(self, y)
    }
    #[inline]
    fn portable_ln(self) -> Self {
        libm::log(self)
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
    #[inline]
    fn portable_sin(self) -> Self {
        libm::sinf(self)
    }
    #[inline]
    fn portable_cos(self) -> Self {
        libm::cosf(self)
    }
    #[inline]
    fn portable_atan2(self, x: Self) -> Self {
        libm::atan2f(self, x)
    }
    #[inline]
    fn portable_hypot(self, y: Self) -> Self {
        libm::hypotf(self, y)
    }
    #[inline]
    fn portable_ln(self) -> Self {
        libm::logf(self)
    }
}
