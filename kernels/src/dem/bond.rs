//! Bonds between particles: the point bond of the dissertation (eq. 6.13) and the Potyondy & Cundall (2004)
//! parallel bond in 2-D.
//!
//! **Point bond** (dissertation ch. 6.6, eq. 6.13, table 6.1: k_b = 1e5 dyne/cm, F_crit = 700 dyne). At bonding
//! the closest surface points of the two particles (their support points along the contact normal, see
//! [`closest_approach`]) become material points fixed in each body, and the gap vector g₀ = p_j − p_i between
//! them is recorded. Later the spring force on j is F_j = −k_b Δx, with Δx = g − R(φ̄) g₀ the change of the gap
//! vector, where R(φ̄) rotates g₀ by the mean rotation of the two particles since bonding (so a rigid rotation
//! of the bonded pair stretches nothing). Both forces act at the midpoint of the material points, so force and
//! moment balance exactly. The bond breaks for good when |F| ≥ F_crit; as the dissertation notes it has no
//! separate shear strength. The break mode recorded is the dominant component of Δx along the bond normal:
//! tension (opening), compression (closing) or shear (sliding).
//!
//! **Parallel bond** (Potyondy & Cundall 2004, IJRMMS 41, 1329–1364), 2-D with unit thickness:
//! R̄ = λ̄ min(R_i, R_j), A = 2R̄, I = 2R̄³/3. The bond sits at the point of the centre line midway across the
//! gap between the two radii; with ΔU_n = −(v·n)Δt (> 0 approaching), ΔU_s = (v·t)Δt, Δθ = (ω_j − ω_i)Δt:
//! F̄_n += k̄_n A ΔU_n (compression positive), F̄_s −= k̄_s A ΔU_s, M̄ −= k̄_n I Δθ. The force on j is
//! F̄_n n + F̄_s t and the moment on j is M̄ (opposites on i). Peak stresses σ̄ = −F̄_n/A + |M̄|R̄/I and
//! τ̄ = |F̄_s|/A; the bond breaks in tension when σ̄ ≥ σ̄_c (checked first) or in shear when τ̄ ≥ τ̄_c, and then
//! carries nothing. In 2-D the shear force is a scalar along the current tangent, i.e. it rotates with the bond.
//!
//! **Stiffness calibration** (dissertation eq. 2.2, P&C 2004 eq. 18, unit thickness t = 1):
//! k_n = 2tE_c, k_s = k_n/(k_n/k_s), k̄_n = Ē_c/(R_A + R_B), k̄_s = k̄_n/(k̄_n/k̄_s); see
//! [`BondedParticleStiffness`].
//!
//! Units: k_b force/length; k̄_n, k̄_s stress/length (force per area per length, area per unit thickness);
//! strengths σ̄_c, τ̄_c stress; F_crit force.
use super::contact::closest_approach;
use super::law::BodyState;
use super::shape::{Particle, Placed};
use crate::math::{cross, norm, perp, rotate, rotate_by, rotation, rotation_from_cos_sin, Vector};
use crate::Real;

/// How a bond failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum BreakMode {
    /// Tensile failure (opening).
    Tension,
    /// Shear failure (sliding).
    Shear,
    /// Compressive overload (point bond only: its strength bounds |F| whatever the direction).
    Compression,
}

/// The record of a bond that just broke, returned to the caller.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BondBreak<T> {
    /// Failure mode.
    pub mode: BreakMode,
    /// Angle (radians, counter-clockwise from +x) of the bond normal (i → j) when it broke.
    pub orientation: T,
    /// Where the bond was (its force point).
    pub position: Vector<T>,
    /// The load that broke it: |F| for a point bond, the governing peak stress for a parallel bond.
    pub load: T,
}

/// Forces and torques of one bond over one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BondForce<T> {
    /// Force on particle i (= −`force_on_j`).
    pub force_on_i: Vector<T>,
    /// Force on particle j.
    pub force_on_j: Vector<T>,
    /// Torque on i about its centre.
    pub torque_on_i: T,
    /// Torque on j about its centre.
    pub torque_on_j: T,
    /// `Some` in the step the bond broke (then all forces are zero).
    pub broke: Option<BondBreak<T>>,
}

impl<T: Real> BondForce<T> {
    /// No force and no break (a broken bond's contribution; also the initial value of a slot).
    pub fn zero() -> Self {
        Self::idle(None)
    }

    fn idle(broke: Option<BondBreak<T>>) -> Self {
        BondForce {
            force_on_i: Vector::zeros(),
            force_on_j: Vector::zeros(),
            torque_on_i: T::zero(),
            torque_on_j: T::zero(),
            broke,
        }
    }
}

/// The point bond of eq. 6.13.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(bound(
        serialize = "T: crate::Real + serde::Serialize",
        deserialize = "T: crate::Real + serde::Deserialize<'de>"
    ))
)]
pub struct PointBond<T> {
    /// Material point on i, in i's body frame (offset from its centre at zero angle).
    pub anchor_i: Vector<T>,
    /// Material point on j, in j's body frame.
    pub anchor_j: Vector<T>,
    /// Gap vector p_j − p_i at bonding (world frame).
    pub rest_gap: Vector<T>,
    /// Bond normal (i → j) at bonding.
    pub rest_normal: Vector<T>,
    /// Angles of i and j at bonding.
    pub rest_angles: [T; 2],
    /// Stiffness k_b.
    pub stiffness: T,
    /// Strength F_crit: the bond breaks when |F| ≥ F_crit.
    pub strength: T,
    /// False once broken (for good).
    pub intact: bool,
}

impl<T: Real> PointBond<T> {
    /// Bond two particles at their closest surface points.
    pub fn between(i: &Particle<T>, j: &Particle<T>, stiffness: T, strength: T) -> Self {
        let c = closest_approach(i, j);
        PointBond {
            anchor_i: rotate(&(c.point_i - i.position), -i.angle),
            anchor_j: rotate(&(c.point_j - j.position), -j.angle),
            rest_gap: (c.point_j - c.point_i),
            rest_normal: c.normal,
            rest_angles: [i.angle, j.angle],
            stiffness,
            strength,
            intact: true,
        }
    }

    /// Current world positions of the two material points.
    pub fn material_points(&self, i: &Particle<T>, j: &Particle<T>) -> (Vector<T>, Vector<T>) {
        self.material_points_placed(&i.placed(), &j.placed())
    }

    /// [`PointBond::material_points`] from the particles' placed shapes ([`Particle::placed`]: their centres and
    /// the cosine and sine of their orientations), so that a pass over many bonds takes each particle's sine and
    /// cosine once per step instead of twice per bond. Bitwise the same: a rotation by θ is the unit complex
    /// number (cos θ, sin θ) with `libm`'s cosine and sine either way ([`crate::math::rotation`]).
    #[inline]
    pub(crate) fn material_points_placed(
        &self,
        i: &Placed<T>,
        j: &Placed<T>,
    ) -> (Vector<T>, Vector<T>) {
        let (ri, rj) = (
            rotation_from_cos_sin(i.cos, i.sin),
            rotation_from_cos_sin(j.cos, j.sin),
        );
        (
            (i.centre + rotate_by(&ri, &self.anchor_i)),
            (j.centre + rotate_by(&rj, &self.anchor_j)),
        )
    }

    /// Δx = g − R(φ̄) g₀ and the rotated bond normal R(φ̄) n₀.
    pub fn stretch(&self, i: &Particle<T>, j: &Particle<T>) -> (Vector<T>, Vector<T>) {
        self.stretch_from(self.material_points(i, j), i.angle, j.angle)
    }

    /// [`PointBond::stretch`] from the current material points `(p_i, p_j)` and angles of the two particles.
    #[inline]
    fn stretch_from(
        &self,
        (pi, pj): (Vector<T>, Vector<T>),
        angle_i: T,
        angle_j: T,
    ) -> (Vector<T>, Vector<T>) {
        let mean =
            T::lit(0.5) * ((angle_i - self.rest_angles[0]) + (angle_j - self.rest_angles[1]));
        let r = rotation(mean);
        (
            (pj - pi) - rotate_by(&r, &self.rest_gap),
            rotate_by(&r, &self.rest_normal),
        )
    }
}

/// Evaluate a point bond (eq. 6.13); breaks it when |F| ≥ F_crit. A broken bond exerts nothing.
pub fn point_bond_force<T: Real>(
    bond: &mut PointBond<T>,
    i: &Particle<T>,
    j: &Particle<T>,
) -> BondForce<T> {
    point_bond_force_placed(bond, i, j, &i.placed(), &j.placed())
}

/// [`point_bond_force`] with the particles' placed shapes given (`placed_i = i.placed()`,
/// `placed_j = j.placed()`), computed once per particle by a pass over many bonds: bitwise the same.
pub(crate) fn point_bond_force_placed<T: Real>(
    bond: &mut PointBond<T>,
    i: &Particle<T>,
    j: &Particle<T>,
    placed_i: &Placed<T>,
    placed_j: &Placed<T>,
) -> BondForce<T> {
    if !bond.intact {
        return BondForce::idle(None);
    }
    let (pi, pj) = bond.material_points_placed(placed_i, placed_j);
    let x = (pi + pj) * T::lit(0.5);
    let (dx, n) = bond.stretch_from((pi, pj), i.angle, j.angle);
    let force_on_j = dx * (-bond.stiffness);
    let magnitude = norm(&force_on_j);
    if magnitude >= bond.strength {
        bond.intact = false;
        let normal_part = dx.dot(&n);
        let shear_part = dx.dot(&perp(&n)).abs();
        let mode = if shear_part > normal_part.abs() {
            BreakMode::Shear
        } else if normal_part >= T::zero() {
            BreakMode::Tension
        } else {
            BreakMode::Compression
        };
        return BondForce::idle(Some(BondBreak {
            mode,
            orientation: n[1].portable_atan2(n[0]),
            position: x,
            load: magnitude,
        }));
    }
    let force_on_i = -force_on_j;
    BondForce {
        force_on_i,
        force_on_j,
        torque_on_i: cross(&(x - i.position), &force_on_i),
        torque_on_j: cross(&(x - j.position), &force_on_j),
        broke: None,
    }
}

/// The Potyondy–Cundall parallel bond, 2-D, unit thickness.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(bound(
        serialize = "T: crate::Real + serde::Serialize",
        deserialize = "T: crate::Real + serde::Deserialize<'de>"
    ))
)]
pub struct ParallelBond<T> {
    /// Bond radius R̄ = λ̄ min(R_i, R_j).
    pub radius: T,
    /// Normal stiffness per unit area k̄_n.
    pub normal_stiffness: T,
    /// Shear stiffness per unit area k̄_s.
    pub shear_stiffness: T,
    /// Tensile strength σ̄_c.
    pub tensile_strength: T,
    /// Shear strength τ̄_c.
    pub shear_strength: T,
    /// Normal force F̄_n (compression positive).
    pub normal_force: T,
    /// Shear force F̄_s on j along the tangent t = n rotated by +90°.
    pub shear_force: T,
    /// Bending moment M̄ on j.
    pub moment: T,
    /// False once broken.
    pub intact: bool,
}

impl<T: Real> ParallelBond<T> {
    /// A fresh (unloaded) bond between particles of radii `radius_i`, `radius_j` with multiplier λ̄.
    pub fn new(
        radius_i: T,
        radius_j: T,
        multiplier: T,
        normal_stiffness: T,
        shear_stiffness: T,
        tensile_strength: T,
        shear_strength: T,
    ) -> Self {
        ParallelBond {
            radius: multiplier * radius_i.min(radius_j),
            normal_stiffness,
            shear_stiffness,
            tensile_strength,
            shear_strength,
            normal_force: T::zero(),
            shear_force: T::zero(),
            moment: T::zero(),
            intact: true,
        }
    }

    /// Cross-section area A = 2R̄ (unit thickness).
    pub fn area(&self) -> T {
        T::lit(2.0) * self.radius
    }

    /// Second moment of area I = 2R̄³/3.
    pub fn inertia(&self) -> T {
        T::lit(2.0 / 3.0) * self.radius * self.radius * self.radius
    }

    /// Peak tensile stress σ̄ = −F̄_n/A + |M̄|R̄/I.
    pub fn max_tensile_stress(&self) -> T {
        -self.normal_force / self.area() + self.moment.abs() * self.radius / self.inertia()
    }

    /// Peak shear stress τ̄ = |F̄_s|/A.
    pub fn max_shear_stress(&self) -> T {
        self.shear_force.abs() / self.area()
    }
}

/// Update a parallel bond over a step `dt` (incremental forces from the relative motion), check its strength,
/// and return its forces. `radius_i`, `radius_j` place the bond on the centre line (for ellipses pass the
/// radii used to build it). A broken bond exerts nothing.
pub fn parallel_bond_force<T: Real>(
    bond: &mut ParallelBond<T>,
    body_i: &BodyState<T>,
    radius_i: T,
    body_j: &BodyState<T>,
    radius_j: T,
    dt: T,
) -> BondForce<T> {
    if !bond.intact {
        return BondForce::idle(None);
    }
    let d = body_j.position - body_i.position;
    let dist = norm(&d);
    let n = if dist > T::zero() {
        d * (T::one() / dist)
    } else {
        Vector::new(T::one(), T::zero())
    };
    let t = perp(&n);
    let x = body_i.position + (n * (radius_i + T::lit(0.5) * (dist - radius_i - radius_j)));
    let v = body_j.velocity_at(x) - body_i.velocity_at(x);
    let (area, inertia) = (bond.area(), bond.inertia());
    let du_n = -v.dot(&n) * dt;
    let du_s = v.dot(&t) * dt;
    let dtheta = (body_j.angular_velocity - body_i.angular_velocity) * dt;
    bond.normal_force += bond.normal_stiffness * area * du_n;
    bond.shear_force -= bond.shear_stiffness * area * du_s;
    bond.moment -= bond.normal_stiffness * inertia * dtheta;
    let sigma = bond.max_tensile_stress();
    let tau = bond.max_shear_stress();
    let mode = if sigma >= bond.tensile_strength {
        Some((BreakMode::Tension, sigma))
    } else if tau >= bond.shear_strength {
        Some((BreakMode::Shear, tau))
    } else {
        None
    };
    if let Some((mode, load)) = mode {
        bond.intact = false;
        bond.normal_force = T::zero();
        bond.shear_force = T::zero();
        bond.moment = T::zero();
        return BondForce::idle(Some(BondBreak {
            mode,
            orientation: n[1].portable_atan2(n[0]),
            position: x,
            load,
        }));
    }
    let force_on_j = (n * bond.normal_force) + (t * bond.shear_force);
    let force_on_i = -force_on_j;
    BondForce {
        force_on_i,
        force_on_j,
        torque_on_i: cross(&(x - body_i.position), &force_on_i) - bond.moment,
        torque_on_j: cross(&(x - body_j.position), &force_on_j) + bond.moment,
        broke: None,
    }
}

/// A bond of an assembly: the particles it joins and its law with its state.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(bound(
        serialize = "T: crate::Real + serde::Serialize",
        deserialize = "T: crate::Real + serde::Deserialize<'de>"
    ))
)]
pub struct Bond<T> {
    /// Particle indices (i < j by convention; i ≠ j).
    pub pair: [usize; 2],
    /// Bond law and state.
    pub law: BondLaw<T>,
}

/// The two bond laws.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(bound(
        serialize = "T: crate::Real + serde::Serialize",
        deserialize = "T: crate::Real + serde::Deserialize<'de>"
    ))
)]
pub enum BondLaw<T> {
    /// Point bond of eq. 6.13.
    Point(PointBond<T>),
    /// Potyondy–Cundall parallel bond; `radii` place it on the centre line (support values at bonding).
    Parallel {
        /// Bond state.
        bond: ParallelBond<T>,
        /// Radii of i and j along the bond normal at bonding.
        radii: [T; 2],
    },
}

impl<T: Real> Bond<T> {
    /// Whether the bond still carries load.
    pub fn intact(&self) -> bool {
        match &self.law {
            BondLaw::Point(b) => b.intact,
            BondLaw::Parallel { bond, .. } => bond.intact,
        }
    }

    /// Translational and rotational stiffness the bond adds to one of its particles, whose largest lever arm
    /// is `lever` (the critical-step estimate): point bond k_b and k_b R²; parallel bond max(k̄_n, k̄_s) A and
    /// k̄_n I + k̄_s A R².
    pub fn stiffness(&self, lever: T) -> (T, T) {
        match &self.law {
            BondLaw::Point(b) => (b.stiffness, b.stiffness * lever * lever),
            BondLaw::Parallel { bond, .. } => {
                let a = bond.area();
                (
                    bond.normal_stiffness.max(bond.shear_stiffness) * a,
                    bond.normal_stiffness * bond.inertia()
                        + bond.shear_stiffness * a * lever * lever,
                )
            }
        }
    }

    /// Evaluate the bond between its particles `i` and `j` over a step `dt` ([`point_bond_force`] or
    /// [`parallel_bond_force`] with the particles' current states), updating its state.
    pub fn force(&mut self, i: &Particle<T>, j: &Particle<T>, dt: T) -> BondForce<T> {
        self.force_placed(i, j, None, dt)
    }

    /// [`Bond::force`] with the particles' placed shapes (`Some((i.placed(), j.placed()))`, computed once per
    /// particle by a pass over many bonds; a point bond then takes no sine or cosine of the particles' angles):
    /// bitwise the same.
    pub(crate) fn force_placed(
        &mut self,
        i: &Particle<T>,
        j: &Particle<T>,
        placed: Option<(&Placed<T>, &Placed<T>)>,
        dt: T,
    ) -> BondForce<T> {
        match &mut self.law {
            BondLaw::Point(bond) => match placed {
                Some((pi, pj)) => point_bond_force_placed(bond, i, j, pi, pj),
                None => point_bond_force(bond, i, j),
            },
            BondLaw::Parallel { bond, radii } => parallel_bond_force(
                bond,
                &BodyState::of(i),
                radii[0],
                &BodyState::of(j),
                radii[1],
                dt,
            ),
        }
    }
}

/// Contact and parallel-bond stiffnesses of a bonded-particle model from its moduli (dissertation eq. 2.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BondedParticleStiffness<T> {
    /// Contact normal stiffness k_n = 2tE_c (t = 1).
    pub normal: T,
    /// Contact shear stiffness k_s = k_n/(k_n/k_s).
    pub shear: T,
    /// Parallel-bond normal stiffness per unit area k̄_n = Ē_c/(R_A + R_B).
    pub bond_normal: T,
    /// Parallel-bond shear stiffness per unit area k̄_s = k̄_n/(k̄_n/k̄_s).
    pub bond_shear: T,
}

impl<T: Real> BondedParticleStiffness<T> {
    /// Eq. 2.2 for a pair of radii `radius_a`, `radius_b`: contact modulus E_c and ratio k_n/k_s, bond modulus
    /// Ē_c and ratio k̄_n/k̄_s.
    pub fn from_moduli(
        contact_modulus: T,
        contact_stiffness_ratio: T,
        bond_modulus: T,
        bond_stiffness_ratio: T,
        radius_a: T,
        radius_b: T,
    ) -> Self {
        let normal = T::lit(2.0) * contact_modulus;
        let bond_normal = bond_modulus / (radius_a + radius_b);
        BondedParticleStiffness {
            normal,
            shear: normal / contact_stiffness_ratio,
            bond_normal,
            bond_shear: bond_normal / bond_stiffness_ratio,
        }
    }
}
