//! Fluid–solid coupling of the partially-saturated method (dissertation eq. 4.4–4.8), in lattice units.
//!
//! * [`rigid_velocity`]: the solid velocity u_s = V + ω × (x − X) at a node (2-D: ω × r = (−ω r_y, ω r_x)).
//! * [`body_cell_fraction`] / [`body_cell_range`]: the solid fraction of a cell covered by a body (disc or
//!   ellipse, exact areas from [`crate::coverage`]) as the fluid sees it — scaled by the dissertation's "fluid
//!   radius" factor (ch. 5.3.4: the fluid interacts with only a fraction of each grain's radius so that a dense 2-D
//!   packing keeps connected pore space), and the range of cells it can touch.
//! * [`reduce_exchange`]: force F_p = Σ_n F_{n,p} and torque T_p = Σ_n (x_n − X_p) × F_{n,p} on each body from
//!   the per-share momentum exchange returned by the PSM collision (eq. 4.7–4.8; impulse per step = force in
//!   lattice units), summed sequentially in the order of the share list, so the result does not depend on how
//!   the collision was parallelised. On periodic axes, x_n − X_p is taken as the minimum image.
use crate::coverage::{disc_cell_fraction, ellipse_cell_fraction, ellipse_cell_fraction_oriented};
use crate::math::{Point, Vector};
use crate::Real;

/// The shape of a body as the fluid sees it (lattice units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BodyShape<T> {
    /// A disc.
    Disc {
        /// Radius.
        radius: T,
    },
    /// An ellipse.
    Ellipse {
        /// Semi-major axis a.
        semi_major: T,
        /// Semi-minor axis b.
        semi_minor: T,
        /// Orientation of the major axis from +x (radians).
        angle: T,
    },
}

/// A rigid body for the coupling: centre, velocity, angular velocity and shape (lattice units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoupledBody<T> {
    /// Centre of mass X (node coordinates).
    pub center: Point<T>,
    /// Translational velocity V.
    pub velocity: Vector<T>,
    /// Angular velocity ω (per step, counter-clockwise positive).
    pub spin: T,
    /// Shape as the fluid sees it (already scaled by the fluid-radius factor).
    pub shape: BodyShape<T>,
}

impl<T: Real> BodyShape<T> {
    /// The shape scaled by the fluid-radius factor (each semi-axis multiplied by `factor`).
    pub fn scaled(self, factor: T) -> Self {
        match self {
            BodyShape::Disc { radius } => BodyShape::Disc {
                radius: radius * factor,
            },
            BodyShape::Ellipse {
                semi_major,
                semi_minor,
                angle,
            } => BodyShape::Ellipse {
                semi_major: semi_major * factor,
                semi_minor: semi_minor * factor,
                angle,
            },
        }
    }

    /// Radius of the smallest centred circle containing the shape.
    pub fn reach(&self) -> T {
        match *self {
            BodyShape::Disc { radius } => radius,
            BodyShape::Ellipse {
                semi_major,
                semi_minor,
                ..
            } => semi_major.max(semi_minor),
        }
    }
}

/// Rigid-body velocity V + ω × (x − X) at point `x`.
#[inline]
pub fn rigid_velocity<T: Real>(body: &CoupledBody<T>, x: Point<T>) -> Vector<T> {
    let (rx, ry) = (x[0] - body.center[0], x[1] - body.center[1]);
    Vector::new(
        body.velocity[0] - body.spin * ry,
        body.velocity[1] + body.spin * rx,
    )
}

/// The unit outward normal of the body's boundary "at" point `x`: the gradient of the body's implicit function
/// there, normalised — for a disc the radial direction (x − X)/|x − X|, for an ellipse with semi-axes a, b
/// along the unit vectors e₁, e₂ the direction of (d·e₁/a²) e₁ + (d·e₂/b²) e₂, d = x − X (normal to the
/// confocal level curve through x, which is the boundary's normal where x lies on it). Zero at the centre
/// (no direction), and for a degenerate shape (a zero semi-axis). Used for the wall direction of the cells the
/// body cuts ([`crate::fluid::collide::wall_gradient`]).
#[inline]
pub fn surface_normal<T: Real>(body: &CoupledBody<T>, x: Point<T>) -> Vector<T> {
    PreparedBody::new(body).surface_normal(x)
}

/// Fraction of the unit cell centred on node (x, y) covered by the body, in [0, 1] (exact area).
#[inline]
pub fn body_cell_fraction<T: Real>(body: &CoupledBody<T>, x: T, y: T) -> T {
    match body.shape {
        BodyShape::Disc { radius } => disc_cell_fraction(body.center, radius, x, y),
        BodyShape::Ellipse {
            semi_major,
            semi_minor,
            angle,
        } => ellipse_cell_fraction(body.center, semi_major, semi_minor, angle, x, y),
    }
}

/// A body prepared for evaluating the fractions of many cells: the orientation's sine and cosine are taken
/// once. [`PreparedBody::cell_fraction`] is bitwise [`body_cell_fraction`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreparedBody<T> {
    body: CoupledBody<T>,
    sin_cos: (T, T),
}

impl<T: Real> PreparedBody<T> {
    /// Prepare `body`.
    pub fn new(body: &CoupledBody<T>) -> Self {
        let sin_cos = match body.shape {
            BodyShape::Disc { .. } => (T::zero(), T::one()),
            BodyShape::Ellipse { angle, .. } => angle.portable_sin_cos(),
        };
        Self {
            body: *body,
            sin_cos,
        }
    }

    /// The unit outward normal of the body at point `x` (= [`surface_normal`]).
    #[inline]
    pub fn surface_normal(&self, x: Point<T>) -> Vector<T> {
        let b = &self.body;
        let d = [x[0] - b.center[0], x[1] - b.center[1]];
        let g = match b.shape {
            BodyShape::Disc { .. } => d,
            BodyShape::Ellipse {
                semi_major,
                semi_minor,
                ..
            } => {
                let (sin, cos) = self.sin_cos;
                let (q1, q2) = (d[0] * cos + d[1] * sin, -d[0] * sin + d[1] * cos);
                let (a2, b2) = (semi_major * semi_major, semi_minor * semi_minor);
                if !(a2 > T::zero() && b2 > T::zero()) {
                    return Vector::zeros();
                }
                let (g1, g2) = (q1 / a2, q2 / b2);
                [g1 * cos - g2 * sin, g1 * sin + g2 * cos]
            }
        };
        let norm = (g[0] * g[0] + g[1] * g[1]).sqrt();
        if norm > T::zero() && norm.is_finite() {
            Vector::new(g[0] / norm, g[1] / norm)
        } else {
            Vector::zeros()
        }
    }

    /// Fraction of the unit cell centred on node (x, y) covered by the body (= [`body_cell_fraction`]).
    #[inline]
    pub fn cell_fraction(&self, x: T, y: T) -> T {
        let b = &self.body;
        match b.shape {
            BodyShape::Disc { radius } => disc_cell_fraction(b.center, radius, x, y),
            BodyShape::Ellipse {
                semi_major,
                semi_minor,
                ..
            } => {
                ellipse_cell_fraction_oriented(b.center, semi_major, semi_minor, self.sin_cos, x, y)
            }
        }
    }
}

/// The inclusive node range `[x0, x1] × [y0, y1]` (clamped to an `nx × ny` lattice) of cells the body can
/// cover; `None` when the body lies entirely outside the lattice or its geometry is not finite.
pub fn body_cell_range<T: Real>(body: &CoupledBody<T>, nx: usize, ny: usize) -> Option<[usize; 4]> {
    let reach = body.shape.reach();
    let half = T::lit(0.5);
    let lo_x = (body.center[0] - reach - half).ceil();
    let hi_x = (body.center[0] + reach + half).floor();
    let lo_y = (body.center[1] - reach - half).ceil();
    let hi_y = (body.center[1] + reach + half).floor();
    if !(lo_x.is_finite() && hi_x.is_finite() && lo_y.is_finite() && hi_y.is_finite())
        || nx == 0
        || ny == 0
    {
        return None;
    }
    let max_x = T::lit((nx - 1) as f64);
    let max_y = T::lit((ny - 1) as f64);
    if hi_x < T::zero() || hi_y < T::zero() || lo_x > max_x || lo_y > max_y {
        return None;
    }
    let clamp = |v: T, max: T| v.max(T::zero()).min(max).to_f64_exact() as usize;
    Some([
        clamp(lo_x, max_x),
        clamp(hi_x, max_x),
        clamp(lo_y, max_y),
        clamp(hi_y, max_y),
    ])
}

/// Minimum-image difference a − b on an axis of length `period` (no wrap when `period` is `None`).
#[inline]
fn min_image<T: Real>(d: T, period: Option<T>) -> T {
    match period {
        Some(l) if l > T::zero() => {
            let half = T::lit(0.5) * l;
            if d > half {
                d - l
            } else if d < -half {
                d + l
            } else {
                d
            }
        }
        _ => d,
    }
}

/// Reduce per-share momentum exchange to force and torque on each body.
///
/// `share_nodes[k]` is the node coordinate of share k, `share_owner[k]` its body, `exchange[k]` the force the
/// share received (PSM output). `centers[p]` are the body centres; `forces` and `torques` (one per body) are
/// overwritten. Shares whose owner is out of range are ignored. `periods` gives the lattice length of each
/// periodic axis (for the minimum-image lever arm). The per-share data (`share_nodes`, `exchange`) are the
/// lattice's own arrays, plain `[T; 2]` like the rest of the fluid side; the bodies' quantities are
/// [`math`](crate::math) vectors.
///
/// Each body's sums are accumulated in share order, one share after the other (F_p ← F_p + e_k,
/// T_p ← T_p + (r_x e_y − r_y e_x)), so the result does not depend on how the shares of different bodies
/// interleave, nor on the thread count. (Summing a run of one body's shares in registers was tried: no faster
/// at the fracture size, where the pass streams ~36 bytes per share from memory.)
pub fn reduce_exchange<T: Real>(
    share_nodes: &[[T; 2]],
    share_owner: &[u32],
    exchange: &[[T; 2]],
    centers: &[Point<T>],
    periods: [Option<T>; 2],
    forces: &mut [Vector<T>],
    torques: &mut [T],
) {
    for f in forces.iter_mut() {
        *f = Vector::zeros();
    }
    for t in torques.iter_mut() {
        *t = T::zero();
    }
    for ((node, &owner), ex) in share_nodes.iter().zip(share_owner).zip(exchange) {
        let p = owner as usize;
        if p >= forces.len() || p >= torques.len() || p >= centers.len() {
            continue;
        }
        forces[p][0] += ex[0];
        forces[p][1] += ex[1];
        let rx = min_image(node[0] - centers[p][0], periods[0]);
        let ry = min_image(node[1] - centers[p][1], periods[1]);
        torques[p] += rx * ex[1] - ry * ex[0];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rigid_velocity_of_a_spinning_body() {
        let b = CoupledBody {
            center: crate::math::vector(1.0f64, 2.0),
            velocity: crate::math::vector(0.1, -0.2),
            spin: 0.5,
            shape: BodyShape::Disc { radius: 1.0 },
        };
        let v = rigid_velocity(&b, crate::math::vector(1.0, 3.0)); // r = (0, 1): ω × r = (−0.5, 0)
        assert_eq!(v, crate::math::vector(0.1 - 0.5, -0.2));
    }

    #[test]
    fn torque_of_a_couple_and_minimum_image() {
        // Two equal and opposite forces on either side of the centre: zero force, torque 2 r F.
        let nodes = [[6.0f64, 5.0], [4.0, 5.0]];
        let owner = [0u32, 0];
        let ex = [[0.0, 1.0], [0.0, -1.0]];
        let (mut f, mut t) = ([crate::math::vector(9.0, 9.0); 1], [9.0; 1]);
        reduce_exchange(
            &nodes,
            &owner,
            &ex,
            &[crate::math::vector(5.0, 5.0)],
            [None, None],
            &mut f,
            &mut t,
        );
        assert_eq!(f[0], crate::math::vector(0.0, 0.0));
        assert_eq!(t[0], 2.0);
        // Across a periodic boundary of length 10, the node at x = 9 is one to the left of a body at x = 0.
        reduce_exchange(
            &[[9.0f64, 0.0]],
            &[0],
            &[[0.0, 1.0]],
            &[crate::math::vector(0.0, 0.0)],
            [Some(10.0), None],
            &mut f,
            &mut t,
        );
        assert_eq!(t[0], -1.0);
    }

    #[test]
    fn cell_range_covers_every_cell_with_nonzero_fraction() {
        let shapes = [
            BodyShape::Disc { radius: 2.3f64 },
            BodyShape::Ellipse {
                semi_major: 3.1,
                semi_minor: 1.55,
                angle: 0.7,
            },
        ];
        for shape in shapes {
            let b = CoupledBody {
                center: crate::math::vector(5.4, 6.2),
                velocity: crate::math::Vector::from([0.0; 2]),
                spin: 0.0,
                shape,
            };
            let [x0, x1, y0, y1] = body_cell_range(&b, 20, 20).unwrap();
            for y in 0..20 {
                for x in 0..20 {
                    let f = body_cell_fraction(&b, x as f64, y as f64);
                    let inside = (x0..=x1).contains(&x) && (y0..=y1).contains(&y);
                    assert!(
                        inside || f == 0.0,
                        "cell ({x},{y}) covered {f} outside the range"
                    );
                }
            }
        }
        let far = CoupledBody {
            center: crate::math::vector(-50.0f64, 5.0),
            velocity: crate::math::Vector::from([0.0; 2]),
            spin: 0.0,
            shape: BodyShape::Disc { radius: 1.0 },
        };
        assert!(body_cell_range(&far, 20, 20).is_none());
    }

    /// A prepared body (sine and cosine taken once) gives bitwise the per-cell fractions, in f64 and f32.
    fn prepared_matches<T: Real>() {
        let mut checked = 0;
        for k in 0..24 {
            let t = k as f64;
            let shape = if k % 3 == 0 {
                BodyShape::Disc {
                    radius: T::lit(1.3 + 0.37 * t),
                }
            } else {
                BodyShape::Ellipse {
                    semi_major: T::lit(2.0 + 0.41 * t),
                    semi_minor: T::lit(1.0 + 0.19 * t),
                    angle: T::lit(-3.0 + 0.29 * t),
                }
            };
            let b = CoupledBody {
                center: crate::math::vector(T::lit(10.0 + 0.123 * t), T::lit(9.5 - 0.071 * t)),
                velocity: crate::math::Vector::from([T::zero(); 2]),
                spin: T::zero(),
                shape,
            };
            let p = PreparedBody::new(&b);
            for y in 0..20 {
                for x in 0..20 {
                    let (x, y) = (T::lit(x as f64), T::lit(y as f64));
                    let (a, e) = (p.cell_fraction(x, y), body_cell_fraction(&b, x, y));
                    assert_eq!(a.to_f64_exact().to_bits(), e.to_f64_exact().to_bits());
                    checked += usize::from(e > T::zero());
                }
            }
        }
        assert!(checked > 1000, "only {checked} covered cells compared");
    }

    #[test]
    fn prepared_body_gives_bitwise_the_cell_fractions() {
        prepared_matches::<f64>();
        prepared_matches::<f32>();
    }
}
