//! Whole-assembly passes over caller-owned slices: the contact forces of a pair list, the bond forces, the
//! particle–wall forces, and the integration of every particle. They loop over the per-contact kernels of
//! [`contact`](super::contact), [`law`](super::law), [`bond`](super::bond) and [`integrate`](super::integrate).
//!
//! **Chunks and summation order.** Each force comes in two passes:
//!
//! 1. an *evaluation* pass that computes every element (pair, bond, particle against the walls) into its own
//!    slot, touching nothing another element touches: [`pair_contacts`], [`bond_forces`],
//!    [`add_wall_contact_forces`] (chunked by particle: a particle's wall forces go to its own entries). The
//!    caller may split the slices into aligned chunks anywhere and run the chunks in any order or in parallel
//!    (rayon): every slot gets the same bits;
//! 2. a *summation* pass that adds the slots serially, in a fixed order — pairs in list order
//!    ([`add_pair_forces`]), bonds in slice order ([`add_bond_forces`]), particles in index order then walls in
//!    slice order ([`wall_loads`]).
//!
//! So the totals are bitwise the same whatever the chunking or the thread count. [`integrate_all`] is one pass,
//! element by element (chunkable likewise). The driver's DEM step calls exactly these passes.
//!
//! [`ContactModel`] holds the material parameters (k_n, k_s, μ, restitution e) and builds the
//! [`ContactLaw`] of each pair with its own effective mass m* (the dashpot c_n = 2ζ√(m* k_n) depends on it).
//! Velocities given to the laws are [`BodyState::synchronous`] estimates at the force time.
//!
//! Units: as the per-contact kernels (consistent, caller-chosen).
use super::bond::{Bond, BondForce};
use super::contact::{
    disc_disc, ellipse_contact_or_separation, ellipse_sample_separates, ellipse_separated_along,
    wall_contact,
};
use super::integrate::{central_difference_step, particle_critical_time_step};
use super::law::{effective_mass, linear_contact_force, BodyState, ContactForce, ContactLaw};
use super::shape::{Particle, Placed, Shape, Wall};
use crate::math::Vector;
use crate::Real;

/// Material parameters of the particle contacts.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(bound(
        serialize = "T: crate::Real + serde::Serialize",
        deserialize = "T: crate::Real + serde::Deserialize<'de>"
    ))
)]
pub struct ContactModel<T> {
    /// Normal stiffness k_n.
    pub normal_stiffness: T,
    /// Shear stiffness k_s.
    pub shear_stiffness: T,
    /// Friction coefficient μ.
    pub friction: T,
    /// Coefficient of restitution e in (0, 1]; 1 means no dashpot.
    pub restitution: T,
    /// Clip the normal force at zero.
    pub no_tension: bool,
}

impl<T: Real> ContactModel<T> {
    /// The law for a pair of masses (an infinite mass stands for a wall).
    pub fn law(&self, mass_i: T, mass_j: T) -> ContactLaw<T> {
        let base = ContactLaw {
            no_tension: self.no_tension,
            ..ContactLaw::elastic(self.normal_stiffness, self.shear_stiffness, self.friction)
        };
        if self.restitution >= T::one() {
            base
        } else {
            base.with_restitution(self.restitution, effective_mass(mass_i, mass_j))
        }
    }

    /// A-priori PFC critical step of an assembly (Itasca PFC2D manual) assuming every particle carries
    /// `coordination` contacts: per particle √(m/(z k)) for translation with k = max(k_n, k_s), and
    /// √(I/(z k_s R²)) for rotation with R the bounding radius (the largest lever arm); the minimum over the
    /// particles (+∞ for none). Multiply by a safety factor (PFC ≈ 0.8) before use.
    pub fn critical_time_step(&self, particles: &[Particle<T>], coordination: T) -> T {
        let k = self.normal_stiffness.max(self.shear_stiffness);
        particles
            .iter()
            .map(|p| {
                let r = p.shape.bounding_radius();
                particle_critical_time_step(
                    p.mass,
                    coordination * k,
                    p.moment_of_inertia,
                    coordination * self.shear_stiffness * r * r,
                )
            })
            .fold(T::infinity(), |a, b| a.min(b))
    }

    /// [`ContactModel::critical_time_step`] of a bonded assembly: each particle's stiffness sums are the
    /// `coordination` contacts' (z k, z k_s R²) plus those of each of its intact bonds ([`Bond::stiffness`] with
    /// the particle's bounding radius as lever arm, added in bond order). `translational` and `rotational` are
    /// scratch, at least [`bonded_critical_time_step_scratch_len`] long; on return they hold the sums.
    pub fn bonded_critical_time_step(
        &self,
        particles: &[Particle<T>],
        bonds: &[Bond<T>],
        coordination: T,
        translational: &mut [T],
        rotational: &mut [T],
    ) -> Result<T, AssemblyError> {
        let n = particles.len();
        if translational.len() < n || rotational.len() < n {
            return Err(AssemblyError::BufferLength);
        }
        check_bonds(bonds, n)?;
        let k = self.normal_stiffness.max(self.shear_stiffness);
        for ((kt, kr), p) in translational
            .iter_mut()
            .zip(rotational.iter_mut())
            .zip(particles)
        {
            let r = p.shape.bounding_radius();
            *kt = coordination * k;
            *kr = coordination * self.shear_stiffness * r * r;
        }
        for b in bonds.iter().filter(|b| b.intact()) {
            for &i in &b.pair {
                let (t, r) = b.stiffness(particles[i].shape.bounding_radius());
                translational[i] += t;
                rotational[i] += r;
            }
        }
        Ok(particles
            .iter()
            .zip(translational.iter().zip(rotational.iter()))
            .map(|(p, (&t, &r))| particle_critical_time_step(p.mass, t, p.moment_of_inertia, r))
            .fold(T::infinity(), |a, b| a.min(b)))
    }
}

/// Length of each scratch slice of [`ContactModel::bonded_critical_time_step`]: one entry per particle.
pub fn bonded_critical_time_step_scratch_len(particles: usize) -> usize {
    particles
}

/// Why an assembly pass refused its input (nothing is written then).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AssemblyError {
    /// A slice is shorter than it must be (see the function's documentation).
    BufferLength,
    /// A pair or bond names a particle index out of range, or a particle with itself.
    BadPair,
}

/// Contact statistics of a pair list, counted and summed in pair order by [`add_pair_forces`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(bound(
        serialize = "T: crate::Real + serde::Serialize",
        deserialize = "T: crate::Real + serde::Deserialize<'de>"
    ))
)]
pub struct ContactSums<T> {
    /// Active contacts: pairs whose bodies interpenetrate (overlap δ > 0), the same test as
    /// [`Contact::is_active`](super::contact::Contact::is_active).
    pub active: usize,
    /// Loaded contacts: pairs that carry a force (F_n > 0 or F_s ≠ 0). An active contact whose dashpot cancels
    /// its spring (no-tension clip) is active but not loaded.
    pub loaded: usize,
    /// Σ F_n over the loaded contacts (pair order).
    pub normal_force: T,
}

fn check_pairs(pairs: &[[usize; 2]], n: usize) -> Result<(), AssemblyError> {
    if pairs.iter().any(|&[i, j]| i >= n || j >= n || i == j) {
        return Err(AssemblyError::BadPair);
    }
    Ok(())
}

fn check_bonds<T>(bonds: &[Bond<T>], n: usize) -> Result<(), AssemblyError> {
    if bonds
        .iter()
        .any(|b| b.pair[0] >= n || b.pair[1] >= n || b.pair[0] == b.pair[1])
    {
        return Err(AssemblyError::BadPair);
    }
    Ok(())
}

/// Evaluation pass of the pair contacts: the contact of every pair (exact geometry by
/// [`closest_approach`](super::contact::closest_approach), the pair's law from `model`, synchronous velocities) into its own slot of `out`,
/// updating the pair's shear history in `shear` (aligned with `pairs`). `shear` and `out` need one entry per
/// pair. Chunkable: any aligned split of `pairs`, `shear` and `out` gives the same slots.
///
/// Pairs with an ellipse that one sample of the closest-approach search already separates
/// ([`ellipse_sample_separates`], the direction nearest to the line of centres, then any of the search's samples,
/// [`ellipse_ellipse_if_touching`](super::contact::ellipse_ellipse_if_touching)) skip the search or its
/// refinements: their slot is the inactive contact's, exactly what the search would have given.
pub fn pair_contacts<T: Real>(
    model: &ContactModel<T>,
    particles: &[Particle<T>],
    pairs: &[[usize; 2]],
    shear: &mut [T],
    dt: T,
    out: &mut [ContactForce<T>],
) -> Result<(), AssemblyError> {
    pair_contacts_with(
        model,
        particles,
        |i| particles[i].placed(),
        pairs,
        shear,
        None,
        dt,
        out,
    )
    .map(|_| ())
}

/// [`pair_contacts`] with each particle's placed shape (centre, semi-axes, cosine and sine of its orientation)
/// given: `placed[i]` must be `particles[i].placed()` (computed once per step instead of once per pair; same
/// bits). `placed` needs an entry for every index the pairs name. Inlined into its caller, so a caller compiled
/// with wider vector instructions (`#[target_feature]`) gets the closest-approach samples in those instructions.
#[inline(always)]
pub fn pair_contacts_placed<T: Real>(
    model: &ContactModel<T>,
    particles: &[Particle<T>],
    placed: &[Placed<T>],
    pairs: &[[usize; 2]],
    shear: &mut [T],
    dt: T,
    out: &mut [ContactForce<T>],
) -> Result<(), AssemblyError> {
    if placed.len() < particles.len() {
        return Err(AssemblyError::BufferLength);
    }
    pair_contacts_with(model, particles, |i| placed[i], pairs, shear, None, dt, out).map(|_| ())
}

/// [`pair_contacts_placed`] with a separating direction kept per pair (`hints`, aligned with `pairs`; the zero
/// vector for none): an ellipse pair whose hint still separates it with room to spare
/// ([`ellipse_separated_along`]) gets the slot and history of an inactive contact without the closest-approach
/// search. The pass writes each hint as it leaves the pair: the sample direction that separated it, or the
/// normal of a search that found it apart; zero where the pair interpenetrates; unchanged where a hint or the
/// sample nearest to the line of centres culled it. Returns the number of pairs a hint culled.
///
/// Where the search finds the largest gap (every shape its domain admits, to its last bits), the slots and
/// histories are bitwise those of [`pair_contacts_placed`] whatever the hints: a hint only culls pairs that
/// are apart by more than the roundoff of a gap, which the search reports as inactive. So hints may be lost
/// (a checkpoint does not keep them) or carried from any earlier step without changing a result. `hints`
/// needs an entry per pair.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn pair_contacts_hinted<T: Real>(
    model: &ContactModel<T>,
    particles: &[Particle<T>],
    placed: &[Placed<T>],
    pairs: &[[usize; 2]],
    shear: &mut [T],
    hints: &mut [[T; 2]],
    dt: T,
    out: &mut [ContactForce<T>],
) -> Result<usize, AssemblyError> {
    if placed.len() < particles.len() {
        return Err(AssemblyError::BufferLength);
    }
    pair_contacts_with(
        model,
        particles,
        |i| placed[i],
        pairs,
        shear,
        Some(hints),
        dt,
        out,
    )
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn pair_contacts_with<T: Real>(
    model: &ContactModel<T>,
    particles: &[Particle<T>],
    placed: impl Fn(usize) -> Placed<T>,
    pairs: &[[usize; 2]],
    shear: &mut [T],
    mut hints: Option<&mut [[T; 2]]>,
    dt: T,
    out: &mut [ContactForce<T>],
) -> Result<usize, AssemblyError> {
    if shear.len() < pairs.len()
        || out.len() < pairs.len()
        || hints.as_ref().is_some_and(|h| h.len() < pairs.len())
    {
        return Err(AssemblyError::BufferLength);
    }
    check_pairs(pairs, particles.len())?;
    let mut culled = 0;
    for (k, ((&[i, j], history), slot)) in pairs
        .iter()
        .zip(shear.iter_mut())
        .zip(out.iter_mut())
        .enumerate()
    {
        let (pi, pj) = (&particles[i], &particles[j]);
        let hint = hints.as_deref_mut().map(|h| &mut h[k]);
        // The branches of `closest_approach`, with the placed shapes given.
        let c = match (pi.shape, pj.shape) {
            (Shape::Disc { radius: ri }, Shape::Disc { radius: rj }) => {
                disc_disc(pi.position, ri, pj.position, rj)
            }
            _ => {
                let (a, b) = (placed(i), placed(j));
                // Culls that never change a slot: the pair's hint, the sample nearest to the line of
                // centres, then all the search's samples (the refinements are skipped where any separates).
                let apart = hint
                    .as_deref()
                    .is_some_and(|h| ellipse_separated_along(&a, &b, Vector::new(h[0], h[1])));
                if apart {
                    culled += 1;
                }
                let touching = if apart || ellipse_sample_separates(&a, &b) {
                    None
                } else {
                    let (found, separating) = match ellipse_contact_or_separation(&a, &b) {
                        Err(n) => (None, n),
                        Ok(c) if c.is_active() => (Some(c), Vector::zeros()),
                        Ok(c) => (Some(c), c.normal),
                    };
                    if let Some(h) = hint {
                        *h = [separating[0], separating[1]];
                    }
                    found
                };
                let Some(c) = touching else {
                    // What `linear_contact_force` does with an inactive contact.
                    *history = T::zero();
                    *slot = ContactForce::zero();
                    continue;
                };
                c
            }
        };
        let law = model.law(pi.mass, pj.mass);
        *slot = linear_contact_force(
            &law,
            &c,
            &BodyState::synchronous(pi, dt),
            &BodyState::synchronous(pj, dt),
            history,
            dt,
        );
    }
    Ok(culled)
}

/// Summation pass of the pair contacts: add the forces and torques of `contacts` (aligned with `pairs`, from
/// [`pair_contacts`]; an inactive contact's slot is zero) to `force` and `torque` (indexed by particle),
/// serially in pair order, and return their statistics. `force` and `torque` need an entry for every index the pairs
/// name.
pub fn add_pair_forces<T: Real>(
    pairs: &[[usize; 2]],
    contacts: &[ContactForce<T>],
    force: &mut [Vector<T>],
    torque: &mut [T],
) -> Result<ContactSums<T>, AssemblyError> {
    if contacts.len() < pairs.len() {
        return Err(AssemblyError::BufferLength);
    }
    if pairs.iter().any(|&[i, j]| i == j) {
        return Err(AssemblyError::BadPair);
    }
    let n = force.len().min(torque.len());
    if pairs.iter().any(|&[i, j]| i >= n || j >= n) {
        return Err(AssemblyError::BufferLength);
    }
    let mut sums = ContactSums::default();
    for (&[i, j], f) in pairs.iter().zip(contacts) {
        if f.normal_force > T::zero() || f.shear_force != T::zero() {
            sums.loaded += 1;
            sums.normal_force += f.normal_force;
        }
        if f.active {
            sums.active += 1;
        }
        // An inactive contact's slot holds zeros: adding it changes no sum but the sign of a zero one; it is
        // added all the same, so that the totals are those of adding every pair's slot in pair order.
        force[i] += f.force_on_i;
        force[j] += f.force_on_j;
        torque[i] += f.torque_on_i;
        torque[j] += f.torque_on_j;
    }
    Ok(sums)
}

/// Evaluation pass of the bonds: every bond's force ([`Bond::force`]) into its own slot of `out`, updating
/// its state (a bond that breaks is marked broken and its slot records the break). `out` needs one entry per
/// bond. Chunkable: any aligned split of `bonds` and `out` gives the same slots.
pub fn bond_forces<T: Real>(
    particles: &[Particle<T>],
    bonds: &mut [Bond<T>],
    dt: T,
    out: &mut [BondForce<T>],
) -> Result<(), AssemblyError> {
    bond_pass(particles, None, bonds, dt, out)
}

/// [`bond_forces`] with every particle's placed shape given (`placed[k] = particles[k].placed()`, the pass over
/// the particles the contact pass makes anyway): bitwise the same slots, without a sine or cosine of a
/// particle's angle per point bond (`Bond::force_placed`). `placed` needs an entry per particle.
pub fn bond_forces_placed<T: Real>(
    particles: &[Particle<T>],
    placed: &[Placed<T>],
    bonds: &mut [Bond<T>],
    dt: T,
    out: &mut [BondForce<T>],
) -> Result<(), AssemblyError> {
    if placed.len() < particles.len() {
        return Err(AssemblyError::BufferLength);
    }
    bond_pass(particles, Some(placed), bonds, dt, out)
}

/// The loop of [`bond_forces`] and [`bond_forces_placed`]: buffer and index checks, then each bond's force into
/// its slot, from the placed shapes when given.
fn bond_pass<T: Real>(
    particles: &[Particle<T>],
    placed: Option<&[Placed<T>]>,
    bonds: &mut [Bond<T>],
    dt: T,
    out: &mut [BondForce<T>],
) -> Result<(), AssemblyError> {
    if out.len() < bonds.len() {
        return Err(AssemblyError::BufferLength);
    }
    check_bonds(bonds, particles.len())?;
    for (b, slot) in bonds.iter_mut().zip(out.iter_mut()) {
        let [i, j] = b.pair;
        *slot = b.force_placed(
            &particles[i],
            &particles[j],
            placed.map(|p| (&p[i], &p[j])),
            dt,
        );
    }
    Ok(())
}

/// Summation pass of the bonds: add the forces and torques of `forces` (aligned with `bonds`, from
/// [`bond_forces`]) to `force` and `torque`, serially in bond order; a bond that broke in this step adds
/// nothing. Returns the number of bonds that broke. `force` and `torque` need an entry for every index the
/// bonds name.
pub fn add_bond_forces<T: Real>(
    bonds: &[Bond<T>],
    forces: &[BondForce<T>],
    force: &mut [Vector<T>],
    torque: &mut [T],
) -> Result<usize, AssemblyError> {
    if forces.len() < bonds.len() {
        return Err(AssemblyError::BufferLength);
    }
    if bonds.iter().any(|b| b.pair[0] == b.pair[1]) {
        return Err(AssemblyError::BadPair);
    }
    let n = force.len().min(torque.len());
    if bonds.iter().any(|b| b.pair[0] >= n || b.pair[1] >= n) {
        return Err(AssemblyError::BufferLength);
    }
    let mut broke = 0;
    for (b, f) in bonds.iter().zip(forces) {
        if f.broke.is_some() {
            broke += 1;
            continue;
        }
        let [i, j] = b.pair;
        force[i] += f.force_on_i;
        force[j] += f.force_on_j;
        torque[i] += f.torque_on_i;
        torque[j] += f.torque_on_j;
    }
    Ok(broke)
}

/// A wall as a body of the assembly: its half-plane, its velocity (a platen moving along its normal; zero for
/// a fixed wall), and whether it takes part (an inactive wall touches nothing).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallBody<T> {
    /// Position and outward normal.
    pub wall: Wall<T>,
    /// Velocity of the wall (rigid translation).
    pub velocity: Vector<T>,
    /// Whether the wall interacts with the particles.
    pub active: bool,
}

impl<T: Real> WallBody<T> {
    /// A fixed, active wall.
    pub fn fixed(wall: Wall<T>) -> Self {
        WallBody {
            wall,
            velocity: Vector::zeros(),
            active: true,
        }
    }
}

/// The force one wall put on one particle in a step (slot of [`add_wall_contact_forces`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallContactForce<T> {
    /// Whether they touched (an active contact).
    pub touching: bool,
    /// Force of the wall on the particle (zero when not touching).
    pub force_on_particle: Vector<T>,
}

impl<T: Real> WallContactForce<T> {
    /// Not touching.
    pub fn none() -> Self {
        WallContactForce {
            touching: false,
            force_on_particle: Vector::zeros(),
        }
    }
}

/// What the particles did to one wall in a step ([`wall_loads`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallLoad<T> {
    /// Total force the particles exerted on the wall.
    pub force: Vector<T>,
    /// Active contacts with the wall.
    pub contacts: usize,
}

impl<T: Real> Default for WallLoad<T> {
    fn default() -> Self {
        WallLoad {
            force: Vector::zeros(),
            contacts: 0,
        }
    }
}

/// Length of the wall shear history and of the slot slice of [`add_wall_contact_forces`] for `particles`
/// particles and `walls` walls (particle-major, `None` on overflow).
pub fn wall_contacts_scratch_len(particles: usize, walls: usize) -> Option<usize> {
    particles.checked_mul(walls)
}

/// Evaluation pass of the wall contacts, by particle: for each particle, walls in slice order, the contact
/// force of each touching wall (the wall's velocity at the contact point is its own; infinite mass) is added
/// to the particle's `force` and `torque` entries and recorded in `on_walls`; the shear histories
/// `wall_shear` are updated (zeroed for a pair that does not touch). `wall_shear` and `on_walls` are
/// particle-major (index i × walls.len() + w), [`wall_contacts_scratch_len`] long; `force` and `torque` need
/// one entry per particle. Chunkable by particle: any split of `particles`, `force` and `torque` into chunks,
/// with `wall_shear` and `on_walls` split at the same particles, gives the same bits.
#[allow(clippy::too_many_arguments)]
pub fn add_wall_contact_forces<T: Real>(
    model: &ContactModel<T>,
    particles: &[Particle<T>],
    walls: &[WallBody<T>],
    wall_shear: &mut [T],
    dt: T,
    force: &mut [Vector<T>],
    torque: &mut [T],
    on_walls: &mut [WallContactForce<T>],
) -> Result<(), AssemblyError> {
    let n = particles.len();
    let needed = wall_contacts_scratch_len(n, walls.len()).ok_or(AssemblyError::BufferLength)?;
    if wall_shear.len() < needed || on_walls.len() < needed || force.len() < n || torque.len() < n {
        return Err(AssemblyError::BufferLength);
    }
    if walls.is_empty() {
        return Ok(());
    }
    let rows = wall_shear
        .chunks_mut(walls.len())
        .zip(on_walls.chunks_mut(walls.len()));
    for (((p, f), t), (histories, slots)) in particles.iter().zip(force).zip(torque).zip(rows) {
        for ((w, history), slot) in walls.iter().zip(histories).zip(slots) {
            let contact = if w.active {
                wall_contact(p, &w.wall)
            } else {
                None
            };
            let Some(c) = contact else {
                *history = T::zero();
                *slot = WallContactForce::none();
                continue;
            };
            let law = model.law(p.mass, T::infinity());
            let wall_body = BodyState {
                position: c.point_j,
                velocity: w.velocity,
                angular_velocity: T::zero(),
            };
            let cf = linear_contact_force(
                &law,
                &c,
                &BodyState::synchronous(p, dt),
                &wall_body,
                history,
                dt,
            );
            *f += cf.force_on_i;
            *t += cf.torque_on_i;
            *slot = WallContactForce {
                touching: true,
                force_on_particle: cf.force_on_i,
            };
        }
    }
    Ok(())
}

/// Summation pass of the wall contacts: each wall's load (the force the particles exert on it, −Σ of the
/// forces it put on them, and its active contacts) from the slots of [`add_wall_contact_forces`], particles in
/// index order. `loads` (one per wall) is overwritten; `on_walls` holds a whole number of particles' rows.
pub fn wall_loads<T: Real>(
    on_walls: &[WallContactForce<T>],
    loads: &mut [WallLoad<T>],
) -> Result<(), AssemblyError> {
    let walls = loads.len();
    if walls == 0 {
        return if on_walls.is_empty() {
            Ok(())
        } else {
            Err(AssemblyError::BufferLength)
        };
    }
    if !on_walls.len().is_multiple_of(walls) {
        return Err(AssemblyError::BufferLength);
    }
    for l in loads.iter_mut() {
        *l = WallLoad {
            force: Vector::zeros(),
            contacts: 0,
        };
    }
    for row in on_walls.chunks(walls) {
        for (load, slot) in loads.iter_mut().zip(row) {
            if slot.touching {
                load.force[0] -= slot.force_on_particle[0];
                load.force[1] -= slot.force_on_particle[1];
                load.contacts += 1;
            }
        }
    }
    Ok(())
}

/// One central-difference step of every particle with its total `force` and `torque` (see
/// [`central_difference_step`]); particles marked in `held` are not moved. `force`, `torque` and `held` need
/// one entry per particle. Chunkable: element by element.
pub fn integrate_all<T: Real>(
    particles: &mut [Particle<T>],
    force: &[Vector<T>],
    torque: &[T],
    held: &[bool],
    gravity: Vector<T>,
    alpha: T,
    dt: T,
) -> Result<(), AssemblyError> {
    let n = particles.len();
    if force.len() < n || torque.len() < n || held.len() < n {
        return Err(AssemblyError::BufferLength);
    }
    for (((p, f), t), &h) in particles.iter_mut().zip(force).zip(torque).zip(held) {
        if !h {
            central_difference_step(p, *f, *t, gravity, alpha, dt);
        }
    }
    Ok(())
}
