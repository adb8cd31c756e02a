//! [`DemWorld`]: the dry discrete-element assembly the driver owns, and its step.
//!
//! One step (dissertation ch. 2 / ch. 6.6 solid half; order of calls as in `lbdem_kernels::dem`), every force
//! and the integration by the kernels' whole-assembly passes ([`lbdem_kernels::dem::assembly`]):
//!
//! 1. broad phase: [`candidate_pairs`] (bounding circles within `margin`), computed as
//!    [`filter_candidate_pairs`] of a Verlet list (the grid pass [`build_cell_grid`], [`candidate_pairs`] within
//!    `margin` + a skin of [`VERLET_SKIN`] × the smallest bounding radius, rebuilt once a particle has moved plus
//!    grown by [`VERLET_MOVE`] × the skin): the same pair list bit for bit, without a grid pass every step;
//!    [`carry_contact_history`] (shear forces of persisting contacts);
//! 2. contacts: [`pair_contacts_hinted`] (closest approach + linear contact law per pair, pairs that a kept
//!    direction still separates culled), [`add_pair_forces`];
//! 3. bonds: [`bond_forces_placed`] (point bond of eq. 6.13 or Potyondy & Cundall 2004 parallel bond per bond),
//!    [`add_bond_forces`]; each break recorded as a [`BreakRecord`] (step, position, mode, orientation, load);
//! 4. platens: [`add_wall_contact_forces`] with each platen's own velocity (a moving wall), [`wall_loads`];
//! 5. applied forces on chosen particles (`external_force`, `external_torque`);
//! 6. [`integrate_all`]: central difference with gravity and PFC local damping α (particles marked `held` are
//!    not moved);
//! 7. platens move: constant speed, or the PFC servo v = G (σ_target − σ_measured), G = λ L/(k_n N_c Δt)
//!    ([`ServoLaw`]).
//!
//! Determinism: the evaluation passes of steps 2–4 and the integration run in parallel chunks with rayon, but
//! every element is computed independently into its own slot, and the summation passes run serially in pair,
//! bond, then particle order (see the kernels' assembly module). The result is bitwise identical for any number
//! of threads (tested).
//!
//! Critical step (the PFC estimate: Itasca PFC2D manual; Cundall & Strack 1979): per particle √(m/Σk) for translation and √(I/Σk_rot) for rotation, with
//! Σk over an assumed coordination of [`ASSUMED_CONTACT_COORDINATION`] contacts (k = max(k_n, k_s),
//! k_rot = k_s R²) plus the particle's bonds (parallel: max(k̄_n, k̄_s)A, k̄_n I + k̄_s A R²; point: k_b,
//! k_b R²), and the minimum over particles; the world refuses a step above [`CRITICAL_STEP_SAFETY`] times it.
//!
//! Units: any consistent system (the dry scenes use cgs: cm, g, s, dyne; 2-D stresses are force per unit
//! length of a unit-thickness sample, dyne/cm ≡ dyne/cm² × 1 cm).
use lbdem_kernels::dem::assembly::{
    add_bond_forces, add_pair_forces, add_wall_contact_forces, bond_forces_placed, integrate_all,
    pair_contacts_hinted, wall_loads, ContactModel, WallBody, WallContactForce, WallLoad,
};
pub use lbdem_kernels::dem::bond::{Bond, BondLaw};
use lbdem_kernels::dem::bond::{BondForce, BreakMode, ParallelBond, PointBond};
use lbdem_kernels::dem::contact::closest_approach;
use lbdem_kernels::dem::grid::{
    build_cell_grid, candidate_pairs, carry_contact_history, filter_candidate_pairs, CellGrid,
};
use lbdem_kernels::dem::law::ContactForce;
use lbdem_kernels::dem::servo::ServoLaw;
use lbdem_kernels::dem::shape::{Particle, Placed, Wall};
use lbdem_kernels::math::Vector;
use lbdem_kernels::Real;
use rayon::prelude::*;

use serde::{Deserialize, Serialize};

use crate::engine::exec::{with_simd, SimdLevel};
use crate::error::{LbdemError, Result};

/// Contacts per particle assumed by the critical-step estimate (the hexagonal coordination of equal discs).
pub const ASSUMED_CONTACT_COORDINATION: f64 = 6.0;
/// Fraction of the critical step the world accepts (PFC's default safety factor).
pub const CRITICAL_STEP_SAFETY: f64 = 0.8;
/// Work items per rayon task (below this the parallel passes run on one thread).
const PARALLEL_CHUNK: usize = 512;
/// Largest number of broad-phase cells along an axis.
const MAX_CELLS_PER_AXIS: usize = 4096;
/// Verlet skin of the broad phase, as a fraction of the smallest bounding radius when the list is built: the
/// grid pass lists the pairs within `margin` + skin, and each step filters that list by the exact test.
/// A performance choice only (the filtered list is bitwise the grid pass's).
const VERLET_SKIN: f64 = 0.2;
/// A Verlet list is kept while every particle's displacement plus bounding-radius growth since it was built is
/// at most this fraction of the skin: a pair then needs at most 0.8 skin of the 1 skin allowed, the rest a
/// guard against rounding of the distance test far beyond its few ulp.
const VERLET_MOVE: f64 = 0.4;

/// How bonds are installed between touching particles (chosen by the caller).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum BondSpec<T> {
    /// Point bonds (eq. 6.13): stiffness k_b (force/length), strength F_crit (force).
    Point {
        /// k_b.
        stiffness: T,
        /// F_crit.
        strength: T,
    },
    /// Parallel bonds (P&C 2004): λ̄, k̄_n, k̄_s (stress/length), σ̄_c, τ̄_c (stress).
    Parallel {
        /// Radius multiplier λ̄.
        radius_multiplier: T,
        /// k̄_n.
        normal_stiffness: T,
        /// k̄_s.
        shear_stiffness: T,
        /// σ̄_c.
        tensile_strength: T,
        /// τ̄_c.
        shear_strength: T,
    },
}

/// One broken bond.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(bound(
    serialize = "T: Real + Serialize",
    deserialize = "T: Real + Deserialize<'de>"
))]
pub struct BreakRecord<T> {
    /// Step in which it broke (the world's step counter before the step).
    pub step: u64,
    /// The bonded pair.
    pub pair: [usize; 2],
    /// Where the bond was.
    pub position: Vector<T>,
    /// Tension, shear or compression.
    pub mode: BreakMode,
    /// Angle of the bond normal (radians from +x).
    pub orientation: T,
    /// The load that broke it (force for a point bond, peak stress for a parallel bond).
    pub load: T,
}

/// How a platen moves.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(bound(
    serialize = "T: Real + Serialize",
    deserialize = "T: Real + Deserialize<'de>"
))]
pub enum PlatenControl<T> {
    /// Moves at a constant speed along its normal (positive: into the sample). Zero holds it fixed.
    Speed(T),
    /// Servo-controlled to hold a stress by the kernels' [`ServoLaw`] (each step v = G (σ_target − σ),
    /// G = λ L/(k_n N_c Δt) (PFC), |v| ≤ v_max).
    Servo(ServoLaw<T>),
}

/// A straight rigid wall that may move along its normal.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(bound(
    serialize = "T: Real + Serialize",
    deserialize = "T: Real + Deserialize<'de>"
))]
pub struct Platen<T> {
    /// Position and unit normal (pointing into the sample).
    pub wall: Wall<T>,
    /// How it moves.
    pub control: PlatenControl<T>,
    /// Loaded length L (stress = normal force / L, unit thickness).
    pub length: T,
    /// Whether it interacts with the particles (a removed platen does nothing).
    pub active: bool,
    /// Normal speed used in the last step (positive into the sample).
    pub speed: T,
    /// Total force the particles exerted on the platen in the last step.
    pub reaction: Vector<T>,
    /// Active particle contacts in the last step.
    pub contacts: usize,
}

impl<T: Real> Platen<T> {
    /// A platen through `point` with inward normal `normal`, loaded length `length`.
    pub fn new(point: Vector<T>, normal: Vector<T>, length: T, control: PlatenControl<T>) -> Self {
        Platen {
            wall: Wall { point, normal },
            control,
            length,
            active: true,
            speed: T::zero(),
            reaction: Vector::zeros(),
            contacts: 0,
        }
    }

    /// Normal stress on the platen in the last step (compression positive).
    pub fn stress(&self) -> T {
        -(self.reaction[0] * self.wall.normal[0] + self.reaction[1] * self.wall.normal[1])
            / self.length
    }
}

/// The sample box: indices of the four platens in [`DemWorld::platens`] (left, right, bottom, top).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SampleBox {
    /// Platen at x = min (normal +x).
    pub left: usize,
    /// Platen at x = max (normal −x).
    pub right: usize,
    /// Platen at y = min (normal +y).
    pub bottom: usize,
    /// Platen at y = max (normal −y).
    pub top: usize,
}

/// The dry assembly: particles, platens, bonds, contact history and the broad-phase buffers.
/// Checkpoints (serde) hold everything a future step reads: particles, platens, the sample box, bonds with their
/// law state, the break records, contact material, damping, gravity, applied loads, held flags, broad-phase
/// margin, time step, step counter, the last broad phase's pair list with its shear history, the wall shear
/// history, and the last step's force and torque sums and contact statistics (read by
/// [`DemWorld::unbalanced_force_ratio`]). The skipped buffers are scratch, rebuilt by every step.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(bound(
    serialize = "T: Real + Serialize",
    deserialize = "T: Real + Deserialize<'de>"
))]
pub struct DemWorld<T> {
    /// Particles.
    pub particles: Vec<Particle<T>>,
    /// Platens (walls).
    pub platens: Vec<Platen<T>>,
    /// When set, the platens' loaded lengths follow the box (L_left = L_right = y_top − y_bottom, …).
    pub sample_box: Option<SampleBox>,
    /// Bonds in creation order.
    pub bonds: Vec<Bond<T>>,
    /// Contact material.
    pub model: ContactModel<T>,
    /// PFC local damping α.
    pub local_damping: T,
    /// Gravity (acceleration).
    pub gravity: Vector<T>,
    /// Applied force per particle (e.g. the axial stress through boundary particles).
    pub external_force: Vec<Vector<T>>,
    /// Applied torque on each particle (e.g. the fluid torque of the coupling, eq. 4.8), added every step.
    pub external_torque: Vec<T>,
    /// Particles held in place (not integrated: zero velocity, fixed position and angle), e.g. supports.
    pub held: Vec<bool>,
    /// Every bond break so far, in order.
    pub breaks: Vec<BreakRecord<T>>,
    /// Broad-phase skin: pairs whose bounding circles are within it are tested.
    pub margin: T,
    /// Instruction set of the pair-contact pass (the widest the CPU has unless set; not saved: a resumed run
    /// takes the resuming CPU's, with the same bits).
    #[serde(skip, default = "SimdLevel::detect")]
    simd: SimdLevel,
    dt: T,
    step: u64,
    active_contacts: usize,
    contact_normal_sum: T,
    #[serde(skip)]
    radii: Vec<T>,
    #[serde(skip)]
    positions: Vec<Vector<T>>,
    #[serde(skip)]
    cell_start: Vec<usize>,
    #[serde(skip)]
    cell_particles: Vec<usize>,
    pairs: Vec<[usize; 2]>,
    shear: Vec<T>,
    /// Verlet list of the broad phase (scratch: rebuilt after a checkpoint is loaded): the pairs within
    /// `verlet_margin` + `verlet_skin` at `verlet_positions` and `verlet_radii`.
    #[serde(skip)]
    verlet_pairs: Vec<[usize; 2]>,
    #[serde(skip)]
    verlet_positions: Vec<Vector<T>>,
    #[serde(skip)]
    verlet_radii: Vec<T>,
    #[serde(skip)]
    verlet_margin: T,
    #[serde(skip)]
    verlet_skin: T,
    #[serde(skip)]
    verlet_valid: bool,
    #[serde(skip)]
    previous_pairs: Vec<[usize; 2]>,
    #[serde(skip)]
    previous_shear: Vec<T>,
    /// A direction that separated each pair of `pairs` at an earlier step, or zero (the pair pass's hints,
    /// `pair_contacts_hinted`): speed only, no result depends on them, so a checkpoint does not keep them.
    #[serde(skip)]
    hints: Vec<[T; 2]>,
    #[serde(skip)]
    previous_hints: Vec<[T; 2]>,
    /// Pairs culled by their hint since the world was made or loaded (for tests and profiles).
    #[serde(skip)]
    hint_culls: u64,
    #[serde(skip)]
    contact_forces: Vec<ContactForce<T>>,
    #[serde(skip)]
    bond_forces: Vec<BondForce<T>>,
    #[serde(skip)]
    wall_bodies: Vec<WallBody<T>>,
    #[serde(skip)]
    wall_forces: Vec<WallContactForce<T>>,
    #[serde(skip)]
    wall_loads: Vec<WallLoad<T>>,
    /// Whether `contact_forces` and `wall_forces` hold the last step's loads (false until this process steps
    /// the world, and after [`DemWorld::forget_contact_loads`]).
    #[serde(skip)]
    loads_known: bool,
    force: Vec<Vector<T>>,
    torque: Vec<T>,
    wall_shear: Vec<T>,
}

fn check_dt<T: Real>(dt: T, critical: T) -> Result<()> {
    let limit = T::lit(CRITICAL_STEP_SAFETY) * critical;
    if dt.is_finite() && dt > T::zero() && dt <= limit {
        return Ok(());
    }
    Err(LbdemError::field(
        "solid.timestep",
        format!("{:e}", dt.to_f64_exact()),
        &format!(
            "exceeds {CRITICAL_STEP_SAFETY} x the DEM critical step {:e} (min over particles of sqrt(m/sum k), sqrt(I/sum k_rot))",
            critical.to_f64_exact()
        ),
        &format!(
            "use solid.timestep <= {:e}, or soften the contacts/bonds, or make the particles heavier",
            limit.to_f64_exact()
        ),
    ))
}

impl<T: Real> DemWorld<T> {
    /// A world with the given particles, contact material and step; refuses a step above the critical one.
    pub fn new(particles: Vec<Particle<T>>, model: ContactModel<T>, dt: T) -> Result<Self> {
        let n = particles.len();
        let mut world = DemWorld {
            particles,
            platens: Vec::new(),
            sample_box: None,
            bonds: Vec::new(),
            model,
            local_damping: T::lit(lbdem_kernels::dem::law::DEFAULT_LOCAL_DAMPING),
            gravity: Vector::zeros(),
            external_force: vec![Vector::zeros(); n],
            external_torque: vec![T::zero(); n],
            held: vec![false; n],
            breaks: Vec::new(),
            margin: T::zero(),
            simd: SimdLevel::detect(),
            dt,
            step: 0,
            active_contacts: 0,
            contact_normal_sum: T::zero(),
            radii: Vec::new(),
            positions: Vec::new(),
            cell_start: Vec::new(),
            cell_particles: Vec::new(),
            pairs: Vec::new(),
            shear: Vec::new(),
            verlet_pairs: Vec::new(),
            verlet_positions: Vec::new(),
            verlet_radii: Vec::new(),
            verlet_margin: T::zero(),
            verlet_skin: T::zero(),
            verlet_valid: false,
            previous_pairs: Vec::new(),
            previous_shear: Vec::new(),
            hints: Vec::new(),
            previous_hints: Vec::new(),
            hint_culls: 0,
            contact_forces: Vec::new(),
            bond_forces: Vec::new(),
            wall_bodies: Vec::new(),
            wall_forces: Vec::new(),
            wall_loads: Vec::new(),
            loads_known: false,
            force: Vec::new(),
            torque: Vec::new(),
            wall_shear: Vec::new(),
        };
        let r_min = world
            .particles
            .iter()
            .map(|p| p.shape.bounding_radius())
            .fold(T::infinity(), |a, b| a.min(b));
        world.margin = if r_min.is_finite() {
            T::lit(0.05) * r_min
        } else {
            T::zero()
        };
        world.set_timestep(dt)?;
        Ok(world)
    }

    /// The time step.
    pub fn timestep(&self) -> T {
        self.dt
    }

    /// Change the time step (refused above [`CRITICAL_STEP_SAFETY`] × the critical step).
    pub fn set_timestep(&mut self, dt: T) -> Result<()> {
        check_dt(dt, self.critical_time_step())?;
        self.dt = dt;
        Ok(())
    }

    /// Steps taken.
    pub fn step_count(&self) -> u64 {
        self.step
    }

    /// Ellipse pairs that a kept separating direction culled before the closest-approach search, since the
    /// world was made or read from a checkpoint (`pair_contacts_hinted`; speed only).
    pub fn hint_culls(&self) -> u64 {
        self.hint_culls
    }

    /// Active particle–particle contacts in the last step.
    pub fn active_contacts(&self) -> usize {
        self.active_contacts
    }

    /// Particle–particle contact loads of the last step, per particle: the summed contact force (walls and
    /// bonds not included) and the number of active contacts (those with a non-zero normal or shear force, as
    /// [`DemWorld::active_contacts`] counts them). Read-only; `None` before this process has stepped the world
    /// (the per-pair forces are not checkpointed, so a world just loaded from a checkpoint has none yet).
    pub fn contact_loads(&self) -> Option<(Vec<[T; 2]>, Vec<u32>)> {
        if !self.loads_known || self.contact_forces.len() != self.pairs.len() {
            return None;
        }
        let n = self.particles.len();
        let mut force = vec![[T::zero(); 2]; n];
        let mut count = vec![0u32; n];
        for (&[i, j], f) in self.pairs.iter().zip(&self.contact_forces) {
            if f.normal_force > T::zero() || f.shear_force != T::zero() {
                for (k, sum) in [(i, f.force_on_i), (j, f.force_on_j)] {
                    force[k][0] += sum[0];
                    force[k][1] += sum[1];
                }
                count[i] += 1;
                count[j] += 1;
            }
        }
        Some((force, count))
    }

    /// Platen (wall) contact loads of the last step, per particle: the summed force of every platen on the
    /// particle and the number of platens touching it (what the platens' `reaction`s are summed from, with the
    /// opposite sign). Read-only; `None` before this process has stepped the world (the per-contact wall forces
    /// are not checkpointed). A world without platens has zeros.
    pub fn wall_contact_loads(&self) -> Option<(Vec<[T; 2]>, Vec<u32>)> {
        let n = self.particles.len();
        let walls = self.platens.len();
        let mut force = vec![[T::zero(); 2]; n];
        let mut count = vec![0u32; n];
        if !self.loads_known {
            return None;
        }
        if walls == 0 {
            return Some((force, count));
        }
        if self.wall_forces.len() != n * walls {
            return None;
        }
        for (i, row) in self.wall_forces.chunks(walls).enumerate() {
            for slot in row.iter().filter(|s| s.touching) {
                force[i][0] += slot.force_on_particle[0];
                force[i][1] += slot.force_on_particle[1];
                count[i] += 1;
            }
        }
        Some((force, count))
    }

    /// Make [`DemWorld::contact_loads`] and [`DemWorld::wall_contact_loads`] answer `None` until the next step,
    /// as for a world just loaded from a checkpoint, so that what is written about a state does not depend on
    /// whether this process stepped the world before (e.g. the snapshot before a run's first step). The loads
    /// are scratch of the last step: nothing else changes.
    pub fn forget_contact_loads(&mut self) {
        self.loads_known = false;
    }

    /// Candidate pairs of the last broad phase (sorted).
    pub fn candidate_pair_list(&self) -> &[[usize; 2]] {
        &self.pairs
    }

    /// The critical step estimate of the module documentation (the kernel's
    /// [`ContactModel::bonded_critical_time_step`] with [`ASSUMED_CONTACT_COORDINATION`] contacts).
    pub fn critical_time_step(&self) -> T {
        let n = self.particles.len();
        let (mut kt, mut kr) = (vec![T::zero(); n], vec![T::zero(); n]);
        self.model
            .bonded_critical_time_step(
                &self.particles,
                &self.bonds,
                T::lit(ASSUMED_CONTACT_COORDINATION),
                &mut kt,
                &mut kr,
            )
            .expect("scratch sized to the particles; bonds join particles of the world")
    }

    /// Add a platen; returns its index.
    pub fn add_platen(&mut self, platen: Platen<T>) -> usize {
        self.platens.push(platen);
        self.wall_shear = vec![T::zero(); self.particles.len() * self.platens.len()];
        self.platens.len() - 1
    }

    /// Enclose the particles in four platens at x ∈ [x0, x1], y ∈ [y0, y1], all with the same control;
    /// returns the box (also stored in [`DemWorld::sample_box`]).
    pub fn add_box(
        &mut self,
        lo: Vector<T>,
        hi: Vector<T>,
        control: PlatenControl<T>,
    ) -> SampleBox {
        let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
        let (o, l) = (T::zero(), T::one());
        let b = SampleBox {
            left: self.add_platen(Platen::new(
                lo,
                lbdem_kernels::math::vector(l, o),
                h,
                control,
            )),
            right: self.add_platen(Platen::new(
                hi,
                lbdem_kernels::math::vector(-l, o),
                h,
                control,
            )),
            bottom: self.add_platen(Platen::new(
                lo,
                lbdem_kernels::math::vector(o, l),
                w,
                control,
            )),
            top: self.add_platen(Platen::new(
                hi,
                lbdem_kernels::math::vector(o, -l),
                w,
                control,
            )),
        };
        self.sample_box = Some(b);
        b
    }

    /// Bond every pair whose surfaces are closer than `gap` (overlapping pairs included) and that has no bond
    /// yet (intact or broken); returns the number of bonds added. Rechecks the time step against the stiffer
    /// assembly.
    pub fn bond_touching_pairs(&mut self, spec: BondSpec<T>, gap: T) -> Result<usize> {
        let saved = self.margin;
        self.margin = self.margin.max(gap);
        self.broad_phase();
        self.margin = saved;
        let existing: std::collections::HashSet<[usize; 2]> =
            self.bonds.iter().map(|b| b.pair).collect();
        let mut added = 0;
        for &[i, j] in &self.pairs {
            if existing.contains(&[i, j]) {
                continue;
            }
            let (pi, pj) = (&self.particles[i], &self.particles[j]);
            let c = closest_approach(pi, pj);
            if c.overlap <= -gap {
                continue;
            }
            let law = match spec {
                BondSpec::Point {
                    stiffness,
                    strength,
                } => BondLaw::Point(PointBond::between(pi, pj, stiffness, strength)),
                BondSpec::Parallel {
                    radius_multiplier,
                    normal_stiffness,
                    shear_stiffness,
                    tensile_strength,
                    shear_strength,
                } => {
                    let d = [
                        pj.position[0] - pi.position[0],
                        pj.position[1] - pi.position[1],
                    ];
                    let len = d[0].portable_hypot(d[1]);
                    let n = if len > T::zero() {
                        [d[0] / len, d[1] / len]
                    } else {
                        [T::one(), T::zero()]
                    };
                    let radii = [
                        pi.placed()
                            .support_value(lbdem_kernels::math::Vector::from(n)),
                        pj.placed()
                            .support_value(lbdem_kernels::math::Vector::from(n)),
                    ];
                    BondLaw::Parallel {
                        bond: ParallelBond::new(
                            radii[0],
                            radii[1],
                            radius_multiplier,
                            normal_stiffness,
                            shear_stiffness,
                            tensile_strength,
                            shear_strength,
                        ),
                        radii,
                    }
                }
            };
            self.bonds.push(Bond { pair: [i, j], law });
            added += 1;
        }
        check_dt(self.dt, self.critical_time_step())?;
        Ok(added)
    }

    /// Fraction of each particle's bonds that are broken (0 for a particle without bonds).
    pub fn broken_bond_fraction(&self) -> Vec<f64> {
        let n = self.particles.len();
        let mut total = vec![0u32; n];
        let mut broken = vec![0u32; n];
        for b in &self.bonds {
            for &i in &b.pair {
                total[i] += 1;
                if !b.intact() {
                    broken[i] += 1;
                }
            }
        }
        total
            .iter()
            .zip(&broken)
            .map(|(&t, &b)| if t == 0 { 0.0 } else { b as f64 / t as f64 })
            .collect()
    }

    /// Intact bonds.
    pub fn intact_bonds(&self) -> usize {
        self.bonds.iter().filter(|b| b.intact()).count()
    }

    /// Total kinetic energy.
    pub fn kinetic_energy(&self) -> T {
        self.particles
            .iter()
            .map(lbdem_kernels::dem::integrate::kinetic_energy)
            .fold(T::zero(), |a, b| a + b)
    }

    /// Axis-aligned bounding box of the particles (their bounding circles).
    pub fn bounds(&self) -> (Vector<T>, Vector<T>) {
        let mut lo = [T::infinity(); 2];
        let mut hi = [T::neg_infinity(); 2];
        for p in &self.particles {
            let r = p.shape.bounding_radius();
            for k in 0..2 {
                lo[k] = lo[k].min(p.position[k] - r);
                hi[k] = hi[k].max(p.position[k] + r);
            }
        }
        (
            lbdem_kernels::math::Vector::from(lo),
            lbdem_kernels::math::Vector::from(hi),
        )
    }

    /// Whether the Verlet list still holds every pair the grid pass would list now: same particle count and
    /// margin, and every particle moved plus grew by at most [`VERLET_MOVE`] × skin since it was built (so a
    /// pair within `margin` now was within `margin` + skin then). Non-finite values fail the test.
    fn verlet_list_holds(&self) -> bool {
        let n = self.positions.len();
        if !self.verlet_valid
            || self.verlet_positions.len() != n
            || self.verlet_radii.len() != n
            || self.radii.len() != n
            || self.verlet_margin != self.margin
        {
            return false;
        }
        let limit = T::lit(VERLET_MOVE) * self.verlet_skin;
        let mut scale = T::zero();
        for ((p, q), (&r, &r0)) in self
            .positions
            .iter()
            .zip(&self.verlet_positions)
            .zip(self.radii.iter().zip(&self.verlet_radii))
        {
            let d = [p[0] - q[0], p[1] - q[1]];
            let moved = (d[0] * d[0] + d[1] * d[1]).sqrt() + (r - r0).max(T::zero());
            // Not (moved ≤ limit): NaN fails too.
            if !matches!(
                moved.partial_cmp(&limit),
                Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
            ) {
                return false;
            }
            scale = scale.max(p[0].abs()).max(p[1].abs()).max(r);
        }
        // The rounding of the distance test is a few ulp of the coordinates; the unused skin must dwarf it.
        (T::one() - T::lit(2.0 * VERLET_MOVE)) * self.verlet_skin > T::lit(1e-9) * scale
    }

    /// Rebuild the Verlet list: the grid pass with `margin` + skin.
    fn rebuild_verlet_list(&mut self) {
        let n = self.positions.len();
        let r_max = self.radii.iter().fold(T::zero(), |a, &b| a.max(b));
        let r_min = self.radii.iter().fold(T::infinity(), |a, &b| a.min(b));
        let skin = if r_min.is_finite() && r_min > T::zero() {
            T::lit(VERLET_SKIN) * r_min
        } else {
            T::zero()
        };
        let reach = self.margin + skin;
        let (lo, hi) = self.bounds();
        let cell = T::lit(2.0) * r_max + reach;
        // Bounds are finite for finite positions; a non-finite grid falls back to one cell (the kernel clamps).
        let grid = CellGrid::covering(lo, hi, cell, MAX_CELLS_PER_AXIS)
            .or_else(|_| CellGrid::new(Vector::zeros(), T::one(), 1, 1))
            .expect("a 1 x 1 grid of unit cells is valid");
        self.cell_start.resize(grid.cell_start_len(), 0);
        self.cell_particles.resize(n, 0);
        build_cell_grid(
            &grid,
            &self.positions,
            &mut self.cell_start,
            &mut self.cell_particles,
        )
        .expect("buffers sized to the grid");
        loop {
            let cap = self.verlet_pairs.capacity().max(4 * n);
            self.verlet_pairs.resize(cap, [0, 0]);
            let count = candidate_pairs(
                &grid,
                &self.positions,
                &self.radii,
                reach,
                &self.cell_start,
                &self.cell_particles,
                &mut self.verlet_pairs,
            )
            .expect("buffers sized to the grid");
            if count.stored == count.found {
                self.verlet_pairs.truncate(count.found);
                break;
            }
            self.verlet_pairs.clear();
            self.verlet_pairs.reserve(count.found);
        }
        self.verlet_positions.clone_from(&self.positions);
        self.verlet_radii.clone_from(&self.radii);
        self.verlet_margin = self.margin;
        self.verlet_skin = skin;
        self.verlet_valid = true;
    }

    /// The candidate pairs of this step: the kernel's grid pass ([`candidate_pairs`]) within `margin`, computed
    /// as the kernel's [`filter_candidate_pairs`] of a Verlet list (the grid pass within `margin` + skin, rebuilt
    /// when a particle has moved plus grown too far): bitwise the same pair list, without a grid pass per step.
    fn broad_phase(&mut self) {
        let n = self.particles.len();
        self.positions.clear();
        self.positions
            .extend(self.particles.iter().map(|p| p.position));
        self.radii.clear();
        self.radii
            .extend(self.particles.iter().map(|p| p.shape.bounding_radius()));
        std::mem::swap(&mut self.pairs, &mut self.previous_pairs);
        std::mem::swap(&mut self.shear, &mut self.previous_shear);
        std::mem::swap(&mut self.hints, &mut self.previous_hints);
        // A world read from a checkpoint has pairs but no hints: none for them.
        self.previous_hints
            .resize(self.previous_pairs.len(), [T::zero(); 2]);
        self.pairs.clear();
        if n < 2 {
            self.shear.clear();
            self.hints.clear();
            self.verlet_valid = false;
            return;
        }
        if !self.verlet_list_holds() {
            self.rebuild_verlet_list();
        }
        loop {
            let cap = self
                .pairs
                .capacity()
                .max(self.verlet_pairs.len().min(4 * n));
            self.pairs.resize(cap, [0, 0]);
            let count = filter_candidate_pairs(
                &self.positions,
                &self.radii,
                self.margin,
                &self.verlet_pairs,
                &mut self.pairs,
            )
            .expect("radii sized to the positions");
            if count.stored == count.found {
                self.pairs.truncate(count.found);
                break;
            }
            self.pairs.clear();
            self.pairs.reserve(count.found);
        }
        self.shear.resize(self.pairs.len(), T::zero());
        carry_contact_history(
            &self.previous_pairs,
            &self.previous_shear,
            &self.pairs,
            &mut self.shear,
        )
        .expect("history buffers sized to their pair lists");
        self.hints.resize(self.pairs.len(), [T::zero(); 2]);
        carry_contact_history(
            &self.previous_pairs,
            &self.previous_hints,
            &self.pairs,
            &mut self.hints,
        )
        .expect("hint buffers sized to their pair lists");
    }

    /// Choose the instruction set of the pair-contact pass (the ellipse searches' samples vectorise). Results
    /// are bitwise the same at every level; only speed changes. Refuses a level this CPU lacks.
    pub fn set_simd(&mut self, simd: SimdLevel) -> Result<()> {
        simd.check_available()?;
        self.simd = simd;
        Ok(())
    }

    /// Advance one step (see the module documentation for the order): [`DemWorld::contact_and_bond_forces`],
    /// then [`DemWorld::finish_step`].
    pub fn step(&mut self) {
        self.contact_and_bond_forces();
        self.finish_step();
    }

    /// The first part of [`DemWorld::step`]: broad phase, contact, bond and platen forces (and the breaks and
    /// platen loads), which do not read the external forces, so that a coupled step can compute them while it
    /// reduces the fluid's forces into the external ones. [`DemWorld::finish_step`] must follow before anything
    /// else changes the world.
    pub fn contact_and_bond_forces(&mut self) {
        let n = self.particles.len();
        let dt = self.dt;
        self.broad_phase();
        self.force.clear();
        self.force.resize(n, Vector::zeros());
        self.torque.clear();
        self.torque.resize(n, T::zero());
        let model = self.model;
        let particles = &self.particles;
        let simd = self.simd;
        const INVALID: &str = "the broad phase's pairs and the bonds join particles of the world";

        // Contacts: the kernel's pair passes, evaluated in parallel chunks, summed in pair order; each
        // particle's placed shape (the sine and cosine of its orientation) once per step, not once per pair.
        let placed: Vec<Placed<T>> = particles.par_iter().map(Particle::placed).collect();
        self.contact_forces
            .resize(self.pairs.len(), ContactForce::zero());
        let culled: usize = self
            .pairs
            .par_chunks(PARALLEL_CHUNK)
            .zip(self.shear.par_chunks_mut(PARALLEL_CHUNK))
            .zip(self.hints.par_chunks_mut(PARALLEL_CHUNK))
            .zip(self.contact_forces.par_chunks_mut(PARALLEL_CHUNK))
            .map(|(((pairs, shear), hints), out)| {
                // At the widest vector level of the CPU (the 32 samples of each ellipse search are
                // independent; IEEE arithmetic gives the same bits at every level).
                with_simd(
                    simd,
                    #[inline(always)]
                    || {
                        pair_contacts_hinted(
                            &model, particles, &placed, pairs, shear, hints, dt, out,
                        )
                    },
                )
            })
            .try_reduce(|| 0, |a, b| Ok(a + b))
            .expect(INVALID);
        self.hint_culls += culled as u64;
        let sums = add_pair_forces(
            &self.pairs,
            &self.contact_forces,
            &mut self.force,
            &mut self.torque,
        )
        .expect(INVALID);
        self.active_contacts = sums.loaded;
        self.contact_normal_sum = sums.normal_force;

        // Bonds: the kernel's bond passes, evaluated in parallel chunks, summed in bond order; breaks recorded in
        // bond order.
        if !self.bonds.is_empty() {
            self.bond_forces.resize(self.bonds.len(), BondForce::zero());
            self.bonds
                .par_chunks_mut(PARALLEL_CHUNK)
                .zip(self.bond_forces.par_chunks_mut(PARALLEL_CHUNK))
                .try_for_each(|(bonds, out)| bond_forces_placed(particles, &placed, bonds, dt, out))
                .expect(INVALID);
            add_bond_forces(
                &self.bonds,
                &self.bond_forces,
                &mut self.force,
                &mut self.torque,
            )
            .expect(INVALID);
            for (b, f) in self.bonds.iter().zip(&self.bond_forces) {
                if let Some(br) = f.broke {
                    self.breaks.push(BreakRecord {
                        step: self.step,
                        pair: b.pair,
                        position: br.position,
                        mode: br.mode,
                        orientation: br.orientation,
                        load: br.load,
                    });
                }
            }
        }

        // Platens: the kernel's wall passes, by particle in parallel chunks (each particle's own entries), then
        // the platen loads summed over the particles in index order.
        let walls = self.platens.len();
        if self.wall_shear.len() != n * walls {
            self.wall_shear = vec![T::zero(); n * walls];
        }
        if walls > 0 {
            self.wall_bodies.clear();
            self.wall_bodies
                .extend(self.platens.iter().map(|pl| WallBody {
                    wall: pl.wall,
                    velocity: lbdem_kernels::math::vector(
                        pl.wall.normal[0] * pl.speed,
                        pl.wall.normal[1] * pl.speed,
                    ),
                    active: pl.active,
                }));
            self.wall_forces.resize(n * walls, WallContactForce::none());
            let wall_bodies = &self.wall_bodies;
            self.particles
                .par_chunks(PARALLEL_CHUNK)
                .zip(self.force.par_chunks_mut(PARALLEL_CHUNK))
                .zip(self.torque.par_chunks_mut(PARALLEL_CHUNK))
                .zip(self.wall_shear.par_chunks_mut(PARALLEL_CHUNK * walls))
                .zip(self.wall_forces.par_chunks_mut(PARALLEL_CHUNK * walls))
                .try_for_each(|((((ps, f), t), shear), out)| {
                    add_wall_contact_forces(&model, ps, wall_bodies, shear, dt, f, t, out)
                })
                .expect("wall buffers sized to the particles and platens");
            self.wall_loads.resize(walls, WallLoad::default());
            wall_loads(&self.wall_forces, &mut self.wall_loads).expect("one load per platen");
            for (pl, load) in self.platens.iter_mut().zip(&self.wall_loads) {
                pl.reaction = load.force;
                pl.contacts = load.contacts;
            }
        }
    }

    /// The rest of [`DemWorld::step`] after [`DemWorld::contact_and_bond_forces`]: the external forces added,
    /// the particles integrated, the platens moved.
    pub fn finish_step(&mut self) {
        let n = self.particles.len();
        let dt = self.dt;
        for (f, e) in self.force.iter_mut().zip(&self.external_force) {
            *f += *e;
        }
        for (t, e) in self.torque.iter_mut().zip(&self.external_torque) {
            *t += *e;
        }
        self.loads_known = true;

        // Integrate (the kernel's pass, in parallel chunks); held particles stay where they are.
        let (gravity, alpha) = (self.gravity, self.local_damping);
        if self.held.len() != n {
            self.held.resize(n, false);
        }
        self.particles
            .par_chunks_mut(PARALLEL_CHUNK)
            .zip(self.force.par_chunks(PARALLEL_CHUNK))
            .zip(self.torque.par_chunks(PARALLEL_CHUNK))
            .zip(self.held.par_chunks(PARALLEL_CHUNK))
            .try_for_each(|(((ps, f), t), held)| integrate_all(ps, f, t, held, gravity, alpha, dt))
            .expect("force, torque and held sized to the particles");

        // Platen motion: servo speeds from this step's stresses, then move.
        if let Some(b) = self.sample_box {
            let w = self.platens[b.right].wall.point[0] - self.platens[b.left].wall.point[0];
            let h = self.platens[b.top].wall.point[1] - self.platens[b.bottom].wall.point[1];
            self.platens[b.left].length = h;
            self.platens[b.right].length = h;
            self.platens[b.bottom].length = w;
            self.platens[b.top].length = w;
        }
        let kn = self.model.normal_stiffness;
        for pl in self.platens.iter_mut() {
            pl.speed = match pl.control {
                PlatenControl::Speed(v) => v,
                PlatenControl::Servo(law) => law.speed(pl.stress(), pl.length, kn, pl.contacts, dt),
            };
            if pl.active {
                pl.wall.point[0] += pl.wall.normal[0] * pl.speed * dt;
                pl.wall.point[1] += pl.wall.normal[1] * pl.speed * dt;
            }
        }
        self.step += 1;
    }

    /// Mean unbalanced force over the mean contact normal force of the last step (PFC's equilibrium ratio):
    /// (Σ|F_i|/N)/(ΣF_n/N_c); 0 without contacts or particles.
    pub fn unbalanced_force_ratio(&self) -> T {
        if self.force.is_empty()
            || self.active_contacts == 0
            || self.contact_normal_sum <= T::zero()
        {
            return T::zero();
        }
        let s = self
            .force
            .iter()
            .fold(T::zero(), |a, f| a + f[0].portable_hypot(f[1]));
        (s / T::lit(self.force.len() as f64))
            / (self.contact_normal_sum / T::lit(self.active_contacts as f64))
    }

    /// Spread a stress `stress` (compression positive) over the particles `indices` as applied forces along
    /// `direction` (unit), over the loaded length `length`: particle k gets σ L w_k/Σw with w_k its
    /// bounding diameter. Replaces their previous applied force.
    pub fn apply_boundary_stress(
        &mut self,
        indices: &[usize],
        direction: Vector<T>,
        stress: T,
        length: T,
    ) {
        let total: T = indices
            .iter()
            .map(|&i| self.particles[i].shape.bounding_radius())
            .fold(T::zero(), |a, b| a + b);
        if total <= T::zero() {
            return;
        }
        for &i in indices {
            let share = stress * length * self.particles[i].shape.bounding_radius() / total;
            self.external_force[i] =
                lbdem_kernels::math::vector(direction[0] * share, direction[1] * share);
        }
    }

    /// Indices of the particles whose bounding circle reaches within `depth` of the given side of the
    /// particles' bounding box (side: 0 = left, 1 = right, 2 = bottom, 3 = top), ascending.
    pub fn boundary_particles(&self, side: usize, depth: T) -> Vec<usize> {
        let (lo, hi) = self.bounds();
        self.particles
            .iter()
            .enumerate()
            .filter(|(_, p)| {
                let r = p.shape.bounding_radius();
                match side {
                    0 => p.position[0] - r <= lo[0] + depth,
                    1 => p.position[0] + r >= hi[0] - depth,
                    2 => p.position[1] - r <= lo[1] + depth,
                    _ => p.position[1] + r >= hi[1] - depth,
                }
            })
            .map(|(i, _)| i)
            .collect()
    }
}
