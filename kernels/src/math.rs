//! The math module: the vector, point and rotation types of the DEM and coupling kernels, on nalgebra.
//!
//! Everything that has a direction goes through the aliases of this module, as in rapier's `dim2` math
//! module: a three-dimensional variant of the kernels swaps this module (`Vector3`, `Point3`, a quaternion,
//! an angular velocity that is a vector), not the code that uses it.
//!
//! * [`Vector`]: a displacement, velocity, force or normal (nalgebra's `Vector2`);
//! * [`Point`]: a position, as a vector from the origin (the same type as [`Vector`], so positions and
//!   displacements combine without conversion in the formulas);
//! * [`AngVector`]: an angular velocity, torque or angle — in 2-D the z-component, a scalar;
//! * [`Rotation`]: a rotation in the plane (nalgebra's `UnitComplex`, cos θ + i sin θ), built by [`rotation`]
//!   and applied by [`rotate_by`].
//!
//! **Same bits on every platform.** Only correctly rounded operations are used: nalgebra's `+`, `−`, scalar
//! `×`, negation and `dot` on 2-vectors are element-wise (`dot` is a₀b₀ + a₁b₁, `perp` is a₀b₁ − a₁b₀), so
//! they give the bits of the plain formulas written in the same order. What nalgebra would compute through
//! its float traits (`norm`, `normalize`, `UnitComplex::new`, `angle`) is not used: [`norm`] is `hypot`, and
//! [`rotation`] and [`unit`] take their sines and cosines from [`Real::portable_sin_cos`] (the `libm` crate),
//! never from the platform's C library.
use crate::Real;
use nalgebra::{Complex, Unit};

/// The dimension of the space (2: the kernels are planar).
pub const DIM: usize = 2;

/// A vector of the plane: displacement, velocity, force, unit normal.
pub type Vector<T> = nalgebra::Vector2<T>;

/// A position (vector from the origin; the same type as [`Vector`]).
pub type Point<T> = Vector<T>;

/// An angular quantity (angle, angular velocity, torque): the z-component in the plane.
pub type AngVector<T> = T;

/// A rotation of the plane: the unit complex number cos θ + i sin θ.
pub type Rotation<T> = nalgebra::UnitComplex<T>;

/// The vector (x, y).
#[inline(always)]
pub fn vector<T: Real>(x: T, y: T) -> Vector<T> {
    Vector::new(x, y)
}

/// The zero vector.
#[inline(always)]
pub fn zero<T: Real>() -> Vector<T> {
    Vector::new(T::zero(), T::zero())
}

/// z-component of a × b: a_x b_y − a_y b_x (nalgebra's `perp` product).
#[inline(always)]
pub fn cross<T: Real>(a: &Vector<T>, b: &Vector<T>) -> AngVector<T> {
    a.perp(b)
}

/// The vector rotated by +90°: (−a_y, a_x). For a unit normal n this is the contact tangent t.
#[inline(always)]
pub fn perp<T: Real>(a: &Vector<T>) -> Vector<T> {
    Vector::new(-a[1], a[0])
}

/// ω × r for a rotation ω about z: ω (−r_y, r_x).
#[inline(always)]
pub fn spin<T: Real>(omega: AngVector<T>, r: &Vector<T>) -> Vector<T> {
    Vector::new(-omega * r[1], omega * r[0])
}

/// Euclidean length, with `hypot` (no overflow for large components; the `libm` crate's bits).
#[inline(always)]
pub fn norm<T: Real>(a: &Vector<T>) -> T {
    a[0].portable_hypot(a[1])
}

/// The unit vector at angle θ: (cos θ, sin θ).
#[inline(always)]
pub fn unit<T: Real>(theta: AngVector<T>) -> Vector<T> {
    Vector::new(theta.portable_cos(), theta.portable_sin())
}

/// The rotation by `angle` (counter-clockwise), with the `libm` crate's cosine and sine.
#[inline(always)]
pub fn rotation<T: Real>(angle: AngVector<T>) -> Rotation<T> {
    rotation_from_cos_sin(angle.portable_cos(), angle.portable_sin())
}

/// The rotation whose cosine and sine are given (already computed, e.g. a placed shape's): [`rotation`] of θ is
/// `rotation_from_cos_sin(cos θ, sin θ)` with `libm`'s cosine and sine.
#[inline(always)]
pub(crate) fn rotation_from_cos_sin<T: Real>(cos: T, sin: T) -> Rotation<T> {
    Unit::new_unchecked(Complex::new(cos, sin))
}

/// `a` rotated by `r`: (c a_x − s a_y, s a_x + c a_y) with c + i s the rotation's unit complex number.
#[inline(always)]
pub fn rotate_by<T: Real>(r: &Rotation<T>, a: &Vector<T>) -> Vector<T> {
    let (c, s) = (r.re, r.im);
    Vector::new(c * a[0] - s * a[1], s * a[0] + c * a[1])
}

/// `a` rotated counter-clockwise by `angle` ([`rotate_by`] of [`rotation`]).
#[inline(always)]
pub fn rotate<T: Real>(a: &Vector<T>, angle: AngVector<T>) -> Vector<T> {
    rotate_by(&rotation(angle), a)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The nalgebra operations the kernels use give the bits of the plain formulas (same operations, same
    /// order): on values whose rounding differs with the order of operations.
    #[test]
    fn nalgebra_operations_are_the_plain_formulas() {
        let (a, b) = ([0.1f64, 1e16 + 3.0], [3.3, -0.7]);
        let (va, vb) = (vector(a[0], a[1]), vector(b[0], b[1]));
        let s = 1.0 / 3.0;
        assert_eq!((va + vb)[0].to_bits(), (a[0] + b[0]).to_bits());
        assert_eq!((va - vb)[1].to_bits(), (a[1] - b[1]).to_bits());
        assert_eq!((va * s)[1].to_bits(), (a[1] * s).to_bits());
        assert_eq!(va.dot(&vb).to_bits(), (a[0] * b[0] + a[1] * b[1]).to_bits());
        assert_eq!(
            cross(&va, &vb).to_bits(),
            (a[0] * b[1] - a[1] * b[0]).to_bits()
        );
        let (c, sn) = (0.3f64.portable_cos(), 0.3f64.portable_sin());
        let r = rotate(&va, 0.3);
        assert_eq!(r[0].to_bits(), (c * a[0] - sn * a[1]).to_bits());
        assert_eq!(r[1].to_bits(), (sn * a[0] + c * a[1]).to_bits());
        assert_eq!(norm(&va).to_bits(), libm::hypot(a[0], a[1]).to_bits());
        assert_eq!(perp(&va), vector(-a[1], a[0]));
        assert_eq!(spin(2.0, &va), vector(-2.0 * a[1], 2.0 * a[0]));
    }
}
