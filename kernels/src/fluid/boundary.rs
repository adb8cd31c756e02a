//! Boundary conditions of the rectangular lattice.
//!
//! Each side is periodic, a half-way bounce-back wall (the wall lies half a spacing outside the edge nodes, so
//! a channel of N edge-to-edge nodes has width H = N), at rest or sliding along itself, or a Zou & He (1997)
//! pressure (density) or velocity boundary applied on the edge nodes themselves, the velocity uniform or given
//! node by node ([`SideProfiles`]).
//!
//! **Moving wall** (Ladd 1994, J. Fluid Mech. 271:285, eq. 3.2): the population that re-enters through a wall
//! sliding at u_w is the one that left, plus 6 w_i ρ c_i·u_w (c_i its new direction, ρ the density of the node's
//! gathered populations before the correction). The wall velocity must lie along the wall, so no mass crosses
//! it (the corrections of the three re-entering directions sum to zero).
//!
//! **Zou–He closure** (Phys. Fluids 9, 1591): after streaming, the three populations entering from outside
//! the side are unknown. Mass and normal momentum fix ρ (velocity given) or the normal velocity (density
//! given); the unknowns follow from bouncing back the non-equilibrium part of the normal population plus a
//! transverse-momentum correction, so the node reproduces ρ and both velocity components exactly.
//!
//! **Corners** (documented treatment):
//! * A Zou–He side meeting a wall side: populations that would enter through the wall are bounced back first;
//!   then the Zou–He closure of the Zou–He side fills its three unknowns (overwriting the doubly-unknown
//!   diagonal). The corner node reproduces the prescribed density (pressure sides) or velocity exactly; the
//!   tangential velocity of a pressure side is prescribed as zero.
//! * Two Zou–He sides meeting: the corner rule of Hecht & Harting (2010) reduced to 2-D (see
//!   Hecht & Harting 2010, J. Stat. Mech. P01018): the axis and inward-diagonal unknowns by non-equilibrium bounce-back, the two
//!   "buried" diagonals share the mass that remains. The corner density is the prescribed density of a pressure
//!   side (the mean of both when both are pressure sides); for two velocity sides it is the density of the
//!   diagonal interior neighbour (extrapolation of order zero). The corner velocity is the prescribed velocity
//!   of a velocity side, else zero.
//! * A periodic axis has no corners.
use super::d2q9::{velocity, OPPOSITE, Q};
use super::lattice::Side;
use crate::Real;

/// What happens at one side of the lattice.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum SideCondition<T> {
    /// Periodic: the opposite side must be periodic too.
    Periodic,
    /// Half-way bounce-back no-slip wall at rest, half a lattice spacing outside the edge nodes.
    Wall,
    /// Zou–He pressure boundary: the edge nodes hold this density (p = ρ/3); tangential velocity zero.
    Pressure {
        /// Prescribed density (lattice units).
        density: T,
    },
    /// Zou–He velocity boundary: the edge nodes hold this velocity (lattice units).
    Velocity {
        /// Prescribed velocity (x, y).
        velocity: [T; 2],
    },
    /// Half-way bounce-back wall sliding along itself at this velocity (Ladd's correction; the component
    /// normal to the side must be zero).
    MovingWall {
        /// Wall velocity (x, y), lattice units.
        velocity: [T; 2],
    },
    /// Zou–He velocity boundary with a velocity per edge node: node k along the side (x for south and north,
    /// y for west and east) holds `profile[k]` of this side's entry in [`SideProfiles`].
    VelocityProfile,
}

/// The velocity profiles of [`SideCondition::VelocityProfile`] sides, one value per node along each side (empty
/// for the other sides). Caller-owned; checked by [`SideProfiles::validate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SideProfiles<'a, T> {
    /// x = 0, indexed by y.
    pub west: &'a [[T; 2]],
    /// x = nx − 1, indexed by y.
    pub east: &'a [[T; 2]],
    /// y = 0, indexed by x.
    pub south: &'a [[T; 2]],
    /// y = ny − 1, indexed by x.
    pub north: &'a [[T; 2]],
}

impl<'a, T: Real> SideProfiles<'a, T> {
    /// No profiles (for boundaries without [`SideCondition::VelocityProfile`] sides).
    pub fn none() -> Self {
        Self {
            west: &[],
            east: &[],
            south: &[],
            north: &[],
        }
    }

    /// The profile of one side.
    #[inline(always)]
    pub fn side(&self, side: Side) -> &'a [[T; 2]] {
        match side {
            Side::West => self.west,
            Side::East => self.east,
            Side::South => self.south,
            Side::North => self.north,
        }
    }

    /// Check that every [`SideCondition::VelocityProfile`] side of `bc` has one finite velocity below the lattice
    /// speed per node along it (`nx` nodes for south and north, `ny` for west and east).
    pub fn validate(&self, bc: &Boundaries<T>, nx: usize, ny: usize) -> Result<(), BoundaryError> {
        for side in [Side::West, Side::East, Side::South, Side::North] {
            if bc.side(side) != SideCondition::VelocityProfile {
                continue;
            }
            let p = self.side(side);
            let n = match side {
                Side::West | Side::East => ny,
                Side::South | Side::North => nx,
            };
            if p.len() != n {
                return Err(BoundaryError::ProfileLength(side));
            }
            if !p.iter().all(|v| velocity_ok(*v)) {
                return Err(BoundaryError::BadVelocity(side));
            }
        }
        Ok(())
    }
}

/// A prescribed velocity is finite and below the lattice speed 1 in both components.
#[inline]
fn velocity_ok<T: Real>(v: [T; 2]) -> bool {
    v[0].is_finite() && v[1].is_finite() && v[0].abs() < T::one() && v[1].abs() < T::one()
}

impl<T: Real> SideCondition<T> {
    /// Whether this side is a Zou–He side.
    #[inline(always)]
    pub fn is_zou_he(&self) -> bool {
        matches!(
            self,
            SideCondition::Pressure { .. }
                | SideCondition::Velocity { .. }
                | SideCondition::VelocityProfile
        )
    }
}

/// Conditions on the four sides.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Boundaries<T> {
    /// x = 0
    pub west: SideCondition<T>,
    /// x = nx − 1
    pub east: SideCondition<T>,
    /// y = 0
    pub south: SideCondition<T>,
    /// y = ny − 1
    pub north: SideCondition<T>,
}

/// Why a set of boundaries was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundaryError {
    /// One side of an axis is periodic and the other is not.
    UnpairedPeriodic(Side),
    /// A prescribed density is not finite and positive.
    BadDensity(Side),
    /// A prescribed velocity is not finite or not below the lattice speed 1.
    BadVelocity(Side),
    /// A moving wall's velocity has a component normal to its side.
    WallVelocityNotTangential(Side),
    /// A velocity profile does not have one value per node along its side.
    ProfileLength(Side),
}

impl<T: Real> Boundaries<T> {
    /// Fully periodic lattice.
    pub fn periodic() -> Self {
        Self {
            west: SideCondition::Periodic,
            east: SideCondition::Periodic,
            south: SideCondition::Periodic,
            north: SideCondition::Periodic,
        }
    }

    /// Condition of one side.
    #[inline(always)]
    pub fn side(&self, side: Side) -> SideCondition<T> {
        match side {
            Side::West => self.west,
            Side::East => self.east,
            Side::South => self.south,
            Side::North => self.north,
        }
    }

    /// Periodicity along [x, y].
    #[inline(always)]
    pub fn periodic_axes(&self) -> [bool; 2] {
        [
            matches!(self.west, SideCondition::Periodic),
            matches!(self.south, SideCondition::Periodic),
        ]
    }

    /// Check pairing of periodic sides and the prescribed values.
    pub fn validate(&self) -> Result<(), BoundaryError> {
        let pw = matches!(self.west, SideCondition::Periodic);
        let pe = matches!(self.east, SideCondition::Periodic);
        if pw != pe {
            return Err(BoundaryError::UnpairedPeriodic(if pw {
                Side::East
            } else {
                Side::West
            }));
        }
        let ps = matches!(self.south, SideCondition::Periodic);
        let pn = matches!(self.north, SideCondition::Periodic);
        if ps != pn {
            return Err(BoundaryError::UnpairedPeriodic(if ps {
                Side::North
            } else {
                Side::South
            }));
        }
        for side in [Side::West, Side::East, Side::South, Side::North] {
            match self.side(side) {
                SideCondition::Pressure { density }
                    if !(density.is_finite() && density > T::zero()) =>
                {
                    return Err(BoundaryError::BadDensity(side));
                }
                SideCondition::Velocity { velocity } if !velocity_ok(velocity) => {
                    return Err(BoundaryError::BadVelocity(side));
                }
                SideCondition::MovingWall { velocity } => {
                    if !velocity_ok(velocity) {
                        return Err(BoundaryError::BadVelocity(side));
                    }
                    let normal = match side {
                        Side::West | Side::East => velocity[0],
                        Side::South | Side::North => velocity[1],
                    };
                    if normal != T::zero() {
                        return Err(BoundaryError::WallVelocityNotTangential(side));
                    }
                }
                _ => {}
            }
        }
        Ok(())
    }
}

/// Sum of the populations listed.
#[inline(always)]
fn sum<T: Real>(f: &[T; Q], idx: [usize; 3]) -> T {
    f[idx[0]] + f[idx[1]] + f[idx[2]]
}

/// Zou–He pressure boundary on the west side: given ρ₀ (and u_y), fills f₁, f₅, f₈. Returns u_x.
#[inline]
pub fn zou_he_pressure_west<T: Real>(f: &mut [T; Q], rho: T, uy: T) -> T {
    let ux = T::one() - (sum(f, [0, 2, 4]) + T::lit(2.0) * sum(f, [3, 6, 7])) / rho;
    close_west(f, rho, [ux, uy]);
    ux
}

/// Zou–He velocity boundary on the west side: fills f₁, f₅, f₈ and returns ρ.
#[inline]
pub fn zou_he_velocity_west<T: Real>(f: &mut [T; Q], u: [T; 2]) -> T {
    let rho = (sum(f, [0, 2, 4]) + T::lit(2.0) * sum(f, [3, 6, 7])) / (T::one() - u[0]);
    close_west(f, rho, u);
    rho
}

#[inline(always)]
fn close_west<T: Real>(f: &mut [T; Q], rho: T, u: [T; 2]) {
    let (two3, six, half) = (T::lit(2.0 / 3.0), T::lit(1.0 / 6.0), T::lit(0.5));
    let t = half * (f[2] - f[4]);
    f[1] = f[3] + two3 * rho * u[0];
    f[5] = f[7] - t + six * rho * u[0] + half * rho * u[1];
    f[8] = f[6] + t + six * rho * u[0] - half * rho * u[1];
}

/// Zou–He pressure boundary on the east side: fills f₃, f₆, f₇. Returns u_x.
#[inline]
pub fn zou_he_pressure_east<T: Real>(f: &mut [T; Q], rho: T, uy: T) -> T {
    let ux = -T::one() + (sum(f, [0, 2, 4]) + T::lit(2.0) * sum(f, [1, 5, 8])) / rho;
    close_east(f, rho, [ux, uy]);
    ux
}

/// Zou–He velocity boundary on the east side: fills f₃, f₆, f₇ and returns ρ.
#[inline]
pub fn zou_he_velocity_east<T: Real>(f: &mut [T; Q], u: [T; 2]) -> T {
    let rho = (sum(f, [0, 2, 4]) + T::lit(2.0) * sum(f, [1, 5, 8])) / (T::one() + u[0]);
    close_east(f, rho, u);
    rho
}

#[inline(always)]
fn close_east<T: Real>(f: &mut [T; Q], rho: T, u: [T; 2]) {
    let (two3, six, half) = (T::lit(2.0 / 3.0), T::lit(1.0 / 6.0), T::lit(0.5));
    let t = half * (f[2] - f[4]);
    f[3] = f[1] - two3 * rho * u[0];
    f[7] = f[5] + t - six * rho * u[0] - half * rho * u[1];
    f[6] = f[8] - t - six * rho * u[0] + half * rho * u[1];
}

/// Zou–He pressure boundary on the south side: fills f₂, f₅, f₆. Returns u_y.
#[inline]
pub fn zou_he_pressure_south<T: Real>(f: &mut [T; Q], rho: T, ux: T) -> T {
    let uy = T::one() - (sum(f, [0, 1, 3]) + T::lit(2.0) * sum(f, [4, 7, 8])) / rho;
    close_south(f, rho, [ux, uy]);
    uy
}

/// Zou–He velocity boundary on the south side: fills f₂, f₅, f₆ and returns ρ.
#[inline]
pub fn zou_he_velocity_south<T: Real>(f: &mut [T; Q], u: [T; 2]) -> T {
    let rho = (sum(f, [0, 1, 3]) + T::lit(2.0) * sum(f, [4, 7, 8])) / (T::one() - u[1]);
    close_south(f, rho, u);
    rho
}

#[inline(always)]
fn close_south<T: Real>(f: &mut [T; Q], rho: T, u: [T; 2]) {
    let (two3, six, half) = (T::lit(2.0 / 3.0), T::lit(1.0 / 6.0), T::lit(0.5));
    let t = half * (f[1] - f[3]);
    f[2] = f[4] + two3 * rho * u[1];
    f[5] = f[7] - t + half * rho * u[0] + six * rho * u[1];
    f[6] = f[8] + t - half * rho * u[0] + six * rho * u[1];
}

/// Zou–He pressure boundary on the north side: fills f₄, f₇, f₈. Returns u_y.
#[inline]
pub fn zou_he_pressure_north<T: Real>(f: &mut [T; Q], rho: T, ux: T) -> T {
    let uy = -T::one() + (sum(f, [0, 1, 3]) + T::lit(2.0) * sum(f, [2, 5, 6])) / rho;
    close_north(f, rho, [ux, uy]);
    uy
}

/// Zou–He velocity boundary on the north side: fills f₄, f₇, f₈ and returns ρ.
#[inline]
pub fn zou_he_velocity_north<T: Real>(f: &mut [T; Q], u: [T; 2]) -> T {
    let rho = (sum(f, [0, 1, 3]) + T::lit(2.0) * sum(f, [2, 5, 6])) / (T::one() + u[1]);
    close_north(f, rho, u);
    rho
}

#[inline(always)]
fn close_north<T: Real>(f: &mut [T; Q], rho: T, u: [T; 2]) {
    let (two3, six, half) = (T::lit(2.0 / 3.0), T::lit(1.0 / 6.0), T::lit(0.5));
    let t = half * (f[1] - f[3]);
    f[4] = f[2] - two3 * rho * u[1];
    f[7] = f[5] + t - half * rho * u[0] - six * rho * u[1];
    f[8] = f[6] - t + half * rho * u[0] - six * rho * u[1];
}

/// Apply the Zou–He closure of `side` with condition `cond` to the gathered populations of an edge node.
/// Conditions that are not Zou–He leave `f` unchanged.
#[inline]
pub fn zou_he<T: Real>(f: &mut [T; Q], side: Side, cond: SideCondition<T>) {
    match (side, cond) {
        (Side::West, SideCondition::Pressure { density }) => {
            zou_he_pressure_west(f, density, T::zero());
        }
        (Side::West, SideCondition::Velocity { velocity }) => {
            zou_he_velocity_west(f, velocity);
        }
        (Side::East, SideCondition::Pressure { density }) => {
            zou_he_pressure_east(f, density, T::zero());
        }
        (Side::East, SideCondition::Velocity { velocity }) => {
            zou_he_velocity_east(f, velocity);
        }
        (Side::South, SideCondition::Pressure { density }) => {
            zou_he_pressure_south(f, density, T::zero());
        }
        (Side::South, SideCondition::Velocity { velocity }) => {
            zou_he_velocity_south(f, velocity);
        }
        (Side::North, SideCondition::Pressure { density }) => {
            zou_he_pressure_north(f, density, T::zero());
        }
        (Side::North, SideCondition::Velocity { velocity }) => {
            zou_he_velocity_north(f, velocity);
        }
        _ => {}
    }
}

/// Corner closure where two Zou–He sides meet (`x_side` West/East, `y_side` South/North): fills the two axis
/// unknowns, the inward diagonal and the two buried diagonals so the node holds exactly `rho` and `u`.
#[inline]
pub fn zou_he_corner<T: Real>(f: &mut [T; Q], x_side: Side, y_side: Side, rho: T, u: [T; 2]) {
    // Inward directions along x and y, and the inward diagonal.
    let a = if x_side == Side::West { 1 } else { 3 };
    let b = if y_side == Side::South { 2 } else { 4 };
    let d = match (a, b) {
        (1, 2) => 5,
        (3, 2) => 6,
        (3, 4) => 7,
        _ => 8,
    };
    let (e1, e2) = match d {
        5 | 7 => (6, 8),
        _ => (5, 7),
    };
    let cu = |i: usize| {
        let c = velocity::<T>(i);
        c[0] * u[0] + c[1] * u[1]
    };
    f[a] = f[OPPOSITE[a]] + T::lit(2.0 / 3.0) * rho * cu(a);
    f[b] = f[OPPOSITE[b]] + T::lit(2.0 / 3.0) * rho * cu(b);
    f[d] = f[OPPOSITE[d]] + T::lit(1.0 / 6.0) * rho * cu(d);
    let mut known = T::zero();
    for (i, fi) in f.iter().enumerate() {
        if i != e1 && i != e2 {
            known += *fi;
        }
    }
    let x = T::lit(0.5) * (rho - known);
    f[e1] = x + T::lit(1.0 / 12.0) * rho * cu(e1);
    f[e2] = x + T::lit(1.0 / 12.0) * rho * cu(e2);
}

/// Sum of the populations of a Zou–He node on `side` that the closure does not replace, the tangential ones
/// once and the outgoing ones twice: ρ(1 + u_n) for the node's density ρ and outward normal velocity u_n
/// (north: f₀ + f₁ + f₃ + 2(f₂ + f₅ + f₆)).
#[inline]
pub fn zou_he_known_sum<T: Real>(f: &[T; Q], side: Side) -> T {
    let (tangential, outgoing) = match side {
        Side::North => ([0, 1, 3], [2, 5, 6]),
        Side::South => ([0, 1, 3], [4, 7, 8]),
        Side::East => ([0, 2, 4], [1, 5, 8]),
        Side::West => ([0, 2, 4], [3, 6, 7]),
    };
    sum(f, tangential) + T::lit(2.0) * sum(f, outgoing)
}

/// The density a Zou–He pressure side holds to let sound out: a **radiating drained side**.
///
/// A pressure side that holds ρ₀ is a pressure-release mirror: a plane sound wave that reaches it goes back into
/// the lattice whole, inverted. A side that drains into a large reservoir should hold ρ₀ for slow flow but pass
/// sound on (the reservoir carries it away). In linear acoustics (p′ = c_s²ρ′, impedance Z = ρ₀c_s) a plane wave
/// leaving through the side carries p′ = Z u_n, u_n the outward normal velocity, and the wave coming in is
/// w⁻ = p′ − Z u_n. The characteristic non-reflecting condition (Thompson 1987, J. Comput. Phys. 68:1; Poinsot
/// & Lele 1992, J. Comput. Phys. 101:104; for lattice Boltzmann, Izquierdo & Fueyo 2008, Phys. Rev. E 78:046707)
/// sets w⁻ = 0 for what changes fast and lets the side return to ρ₀ for what changes slowly:
///
/// ρ = ρ₀ (1 + √3 (u_n − ū_n)),   ū_n ← ū_n + r (u_n − ū_n)   (ρ₀/c_s = ρ₀√3),
///
/// ū_n (`mean`, held by the caller, 0 at the start) a running mean of the outward velocity over about 1/r steps.
/// It is solved at the side's own nodes, together with the Zou–He relation ρ(1 + u_n) = K (`known`, the
/// [`zou_he_known_sum`] of the side, its mean along the side for one density per side), so that the density
/// and the velocity it is computed from belong to the same step (a velocity read one node inside, one step
/// late, feeds back and oscillates): as u_n − ū_n after the update is (1 − r)(u_n − ū_n) before it, with
/// s = √3 (1 − r) and ū_n before the update, ρ² − ρ₀(1 − s(1 + ū_n))ρ − sρ₀K = 0, its positive root. With the continuous form of the running mean, a plane
/// wave of angular frequency ω per step comes back with the amplitude r/√(4ω² + r²) of the one that arrived:
/// r = 0 passes every wave (and holds the back pressure Z u_n of a steady outflow), r = 1 holds ρ₀ exactly
/// (the mirror). Returns ρ and updates `mean` with u_n = K/ρ − 1.
#[inline]
pub fn radiating_density<T: Real>(rho0: T, known: T, mean: &mut T, rate: T) -> T {
    let one = T::one();
    let s = T::lit(3.0).sqrt() * (one - rate);
    let b = rho0 * (one - s * (one + *mean));
    let root = (b * b + T::lit(4.0) * s * rho0 * known).sqrt();
    // The root's two forms, each free of cancellation on its side of b = 0.
    let rho = if b >= T::zero() {
        T::lit(0.5) * (b + root)
    } else {
        T::lit(2.0) * s * rho0 * known / (root - b)
    };
    let u = known / rho - one;
    *mean += rate * (u - *mean);
    rho
}
