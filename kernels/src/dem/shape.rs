//! Particle shapes, the particle state, and walls.
//!
//! * A disc of radius r; an ellipse with semi-axes a ≥ b > 0 whose major axis makes the angle `angle` with +x
//!   (the dissertation's ch. 6.6 assemblies use ellipses of aspect ratio b/a = 0.5).
//! * Mass and moment of inertia of a uniform lamina of unit thickness and areal density ρ:
//!   disc m = ρπr², I = m r²/2; ellipse m = ρπab, I = m(a² + b²)/4.
//! * Support function (the distance from the centre to the supporting line with outward normal n):
//!   h(n) = √(a²(n·u)² + b²(n·v)²) with u, v the body axes; the support point is c + (a²(n·u)u + b²(n·v)v)/h.
//!   Its radius of curvature there is ρ = a²b²/h³. For a disc h = ρ = r. Ellipses are centrally symmetric, so
//!   h(−n) = h(n).
//! * A wall is a half-plane {x : (x − p)·m ≤ 0} with a unit outward normal m pointing into the region where the
//!   particles live; it has infinite mass (a moving platen is a wall whose velocity the caller supplies to the
//!   contact law). A [`WallSegment`] is the same face limited to a stretch from `start` to `end`, with the
//!   outward normal on the left of start → end; its ends are not modelled (a particle whose deepest point is
//!   beyond an end does not touch it), which suits platens longer than the sample.
//!
//! Units: any consistent system (lengths, masses, times chosen by the caller). Support values use a plain
//! √(x² + y²) (not `hypot`, which is several times slower): lengths must stay below ~1e150 (f64) / 1e18 (f32).
use crate::math::Vector;
use crate::Real;

/// The shape of a particle, in its body frame.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(bound(
        serialize = "T: crate::Real + serde::Serialize",
        deserialize = "T: crate::Real + serde::Deserialize<'de>"
    ))
)]
pub enum Shape<T> {
    /// A disc of the given radius (> 0).
    Disc {
        /// Radius.
        radius: T,
    },
    /// An ellipse with semi-axes along the body x axis (`semi_major`) and y axis (`semi_minor`), both > 0.
    /// The support formulas hold for either order; `semi_major ≥ semi_minor` is the convention.
    Ellipse {
        /// Semi-axis a along the body x axis.
        semi_major: T,
        /// Semi-axis b along the body y axis.
        semi_minor: T,
    },
}

impl<T: Real> Shape<T> {
    /// The semi-axes (a, b); a disc is (r, r).
    #[inline(always)]
    pub fn semi_axes(&self) -> (T, T) {
        match *self {
            Shape::Disc { radius } => (radius, radius),
            Shape::Ellipse {
                semi_major,
                semi_minor,
            } => (semi_major, semi_minor),
        }
    }

    /// Radius of the smallest circle about the centre that contains the shape (the broad-phase radius).
    #[inline(always)]
    pub fn bounding_radius(&self) -> T {
        let (a, b) = self.semi_axes();
        a.max(b)
    }

    /// Area (per unit thickness): πab.
    #[inline(always)]
    pub fn area(&self) -> T {
        let (a, b) = self.semi_axes();
        T::PI() * a * b
    }

    /// Moment of inertia about the centre divided by the mass: (a² + b²)/4 (r²/2 for a disc).
    #[inline(always)]
    pub fn inertia_per_mass(&self) -> T {
        let (a, b) = self.semi_axes();
        (a * a + b * b) * T::lit(0.25)
    }
}

/// Plain-data state of one rigid particle.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(bound(
        serialize = "T: crate::Real + serde::Serialize",
        deserialize = "T: crate::Real + serde::Deserialize<'de>"
    ))
)]
pub struct Particle<T> {
    /// Centre of mass.
    pub position: Vector<T>,
    /// Orientation of the body x axis (radians, counter-clockwise from +x).
    pub angle: T,
    /// Translational velocity (in the central-difference scheme, the mid-step velocity v(t − Δt/2)).
    pub velocity: Vector<T>,
    /// Angular velocity (counter-clockwise positive; mid-step like `velocity`).
    pub angular_velocity: T,
    /// Mass (> 0).
    pub mass: T,
    /// Moment of inertia about the centre (> 0; +∞ locks the rotation).
    pub moment_of_inertia: T,
    /// Shape in the body frame.
    pub shape: Shape<T>,
    /// The translational acceleration applied by the last integration step (zero initially); used to
    /// estimate the velocity at the force time for velocity-dependent forces.
    pub acceleration: Vector<T>,
    /// The angular acceleration applied by the last integration step.
    pub angular_acceleration: T,
}

impl<T: Real> Particle<T> {
    /// A particle at rest with mass and inertia of a uniform lamina of areal density `density`.
    pub fn new(position: Vector<T>, angle: T, shape: Shape<T>, density: T) -> Self {
        let mass = density * shape.area();
        Particle {
            position,
            angle,
            velocity: Vector::zeros(),
            angular_velocity: T::zero(),
            mass,
            moment_of_inertia: mass * shape.inertia_per_mass(),
            shape,
            acceleration: Vector::zeros(),
            angular_acceleration: T::zero(),
        }
    }

    /// A disc at rest.
    pub fn disc(position: Vector<T>, radius: T, density: T) -> Self {
        Self::new(position, T::zero(), Shape::Disc { radius }, density)
    }

    /// An ellipse at rest with semi-axes `semi_major` (along the body x axis, at `angle`) and `semi_minor`.
    pub fn ellipse(
        position: Vector<T>,
        angle: T,
        semi_major: T,
        semi_minor: T,
        density: T,
    ) -> Self {
        Self::new(
            position,
            angle,
            Shape::Ellipse {
                semi_major,
                semi_minor,
            },
            density,
        )
    }

    /// The placed shape (centre, semi-axes, body axis direction) used by the contact routines.
    #[inline(always)]
    pub fn placed(&self) -> Placed<T> {
        let (a, b) = self.shape.semi_axes();
        Placed::new(self.position, self.angle, a, b)
    }
}

/// A shape placed in the world: centre, semi-axes and the cosine/sine of its orientation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placed<T> {
    /// Centre.
    pub centre: Vector<T>,
    /// Semi-axis along the body x axis.
    pub a: T,
    /// Semi-axis along the body y axis.
    pub b: T,
    /// cos of the orientation.
    pub cos: T,
    /// sin of the orientation.
    pub sin: T,
}

impl<T: Real> Placed<T> {
    /// Place an ellipse (a disc when a = b).
    #[inline(always)]
    pub fn new(centre: Vector<T>, angle: T, a: T, b: T) -> Self {
        Placed {
            centre,
            a,
            b,
            cos: angle.portable_cos(),
            sin: angle.portable_sin(),
        }
    }

    /// Components (n·u, n·v) of a direction in the body axes.
    #[inline(always)]
    fn body(&self, n: Vector<T>) -> (T, T) {
        (
            self.cos * n[0] + self.sin * n[1],
            -self.sin * n[0] + self.cos * n[1],
        )
    }

    /// Support value h(n) for a unit direction n.
    #[inline(always)]
    pub fn support_value(&self, n: Vector<T>) -> T {
        let (p, q) = self.body(n);
        ((self.a * p) * (self.a * p) + (self.b * q) * (self.b * q)).sqrt()
    }

    /// Support value h, its derivative dh/dθ and the radius of curvature a²b²/h³ for n = (cos θ, sin θ).
    #[inline(always)]
    pub fn support_derivatives(&self, n: Vector<T>) -> (T, T, T) {
        let (p, q) = self.body(n);
        let h = ((self.a * p) * (self.a * p) + (self.b * q) * (self.b * q)).sqrt();
        let (a2, b2) = (self.a * self.a, self.b * self.b);
        // h > 0 for positive semi-axes and a unit n (h ≥ min(a, b)).
        let dh = (b2 - a2) * p * q / h;
        let rho = a2 * b2 / (h * h * h);
        (h, dh, rho)
    }

    /// The support point (world coordinates) in the unit direction n: the boundary point with outward normal n.
    #[inline(always)]
    pub fn support_point(&self, n: Vector<T>) -> Vector<T> {
        let (p, q) = self.body(n);
        let (a2, b2) = (self.a * self.a, self.b * self.b);
        let h = ((self.a * p) * (self.a * p) + (self.b * q) * (self.b * q)).sqrt();
        let (x, y) = (a2 * p / h, b2 * q / h);
        // back to world axes: x u + y v
        let off = Vector::new(self.cos * x - self.sin * y, self.sin * x + self.cos * y);
        self.centre + off
    }

    /// Whether a world point lies inside or on the shape: (x·u/a)² + (x·v/b)² ≤ 1.
    #[inline(always)]
    pub fn contains(&self, x: Vector<T>) -> bool {
        let d = x - self.centre;
        let (p, q) = self.body(d);
        let (p, q) = (p / self.a, q / self.b);
        p * p + q * q <= T::one()
    }
}

/// A fixed straight wall: the half-plane behind the line through `point` with unit outward normal `normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(bound(
        serialize = "T: crate::Real + serde::Serialize",
        deserialize = "T: crate::Real + serde::Deserialize<'de>"
    ))
)]
pub struct Wall<T> {
    /// A point on the wall surface.
    pub point: Vector<T>,
    /// Unit outward normal (pointing from the wall into the particle region).
    pub normal: Vector<T>,
}

impl<T: Real> Wall<T> {
    /// A wall through `point` with the outward normal at `angle` (radians).
    pub fn from_angle(point: Vector<T>, angle: T) -> Self {
        Wall {
            point,
            normal: Vector::new(angle.portable_cos(), angle.portable_sin()),
        }
    }

    /// Signed distance of `x` from the wall surface (positive on the particle side).
    #[inline(always)]
    pub fn signed_distance(&self, x: Vector<T>) -> T {
        (x - self.point).dot(&self.normal)
    }

    /// The foot of the perpendicular from `x` onto the wall surface.
    #[inline(always)]
    pub fn project(&self, x: Vector<T>) -> Vector<T> {
        let s = self.signed_distance(x);
        x + (self.normal * (-s))
    }
}

/// A finite straight wall face from `start` to `end`; the particles live on its left (outward normal =
/// (end − start) rotated by +90°, normalised). The ends are open: see the module documentation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallSegment<T> {
    /// First end point.
    pub start: Vector<T>,
    /// Second end point.
    pub end: Vector<T>,
}

impl<T: Real> WallSegment<T> {
    /// The supporting half-plane (its wall) and the segment length. A zero-length segment gives the normal
    /// (0, 1) and length 0.
    pub fn wall(&self) -> (Wall<T>, T) {
        let e = self.end - self.start;
        let length = e[0].portable_hypot(e[1]);
        let normal = if length > T::zero() {
            Vector::new(-e[1] / length, e[0] / length)
        } else {
            Vector::new(T::zero(), T::one())
        };
        (
            Wall {
                point: self.start,
                normal,
            },
            length,
        )
    }

    /// Position of the projection of `x` along the segment, from 0 at `start` to the length at `end`.
    pub fn abscissa(&self, x: Vector<T>) -> T {
        let (wall, _) = self.wall();
        let tangent = Vector::new(wall.normal[1], -wall.normal[0]);
        (x - self.start).dot(&tangent)
    }
}
