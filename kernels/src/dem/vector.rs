//! Two-dimensional vector helpers on plain `[T; 2]` arrays.
//!
//! The cross product of two plane vectors is the scalar z-component a_x b_y − a_y b_x; the cross product of a
//! z-axis rotation ω with a plane vector r is ω × r = ω (−r_y, r_x).
use crate::Real;

/// a + b
#[inline(always)]
pub fn add<T: Real>(a: [T; 2], b: [T; 2]) -> [T; 2] {
    [a[0] + b[0], a[1] + b[1]]
}

/// a − b
#[inline(always)]
pub fn sub<T: Real>(a: [T; 2], b: [T; 2]) -> [T; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

/// s a
#[inline(always)]
pub fn scale<T: Real>(a: [T; 2], s: T) -> [T; 2] {
    [a[0] * s, a[1] * s]
}

/// a · b
#[inline(always)]
pub fn dot<T: Real>(a: [T; 2], b: [T; 2]) -> T {
    a[0] * b[0] + a[1] * b[1]
}

/// z-component of a × b.
#[inline(always)]
pub fn cross<T: Real>(a: [T; 2], b: [T; 2]) -> T {
    a[0] * b[1] - a[1] * b[0]
}

/// The vector rotated by +90°: (−a_y, a_x). For a unit normal n this is the contact tangent t.
#[inline(always)]
pub fn perp<T: Real>(a: [T; 2]) -> [T; 2] {
    [-a[1], a[0]]
}

/// ω × r for a rotation ω about z.
#[inline(always)]
pub fn spin<T: Real>(omega: T, r: [T; 2]) -> [T; 2] {
    [-omega * r[1], omega * r[0]]
}

/// Euclidean length (with `hypot`, so no overflow for large components).
#[inline(always)]
pub fn norm<T: Real>(a: [T; 2]) -> T {
    a[0].portable_hypot(a[1])
}

/// The unit vector at angle θ: (cos θ, sin θ).
#[inline(always)]
pub fn unit<T: Real>(theta: T) -> [T; 2] {
    [theta.portable_cos(), theta.portable_sin()]
}

/// Rotate `a` counter-clockwise by the angle whose cosine and sine are given.
#[inline(always)]
pub fn rotate_cs<T: Real>(a: [T; 2], c: T, s: T) -> [T; 2] {
    [c * a[0] - s * a[1], s * a[0] + c * a[1]]
}

/// Rotate `a` counter-clockwise by `angle`.
#[inline(always)]
pub fn rotate<T: Real>(a: [T; 2], angle: T) -> [T; 2] {
    rotate_cs(a, angle.portable_cos(), angle.portable_sin())
}
