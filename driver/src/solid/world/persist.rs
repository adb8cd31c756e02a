//! [`Persist`] for [`DemWorld`]: everything a future step reads — particles (position, angle, velocities,
//! accelerations, mass, inertia, shape), platens (wall, control, loaded length, activity, last speed, reaction
//! and contact count), the sample box, bonds with their law state (intact or broken), the break records,
//! contact material, damping, gravity, applied forces and torques, held flags, broad-phase margin, time step,
//! step counter, the last broad phase's pair list with its shear history, the wall shear history, and the
//! last step's force and torque sums and contact statistics (read by
//! [`DemWorld::unbalanced_force_ratio`]). The other buffers are scratch, rebuilt by every step.
use lbdem_kernels::Real;

use super::{Bond, BondLaw, BreakRecord, DemWorld, Platen, PlatenControl, SampleBox};
use crate::checkpoint::{Decoder, Encoder, Persist};
use crate::error::Result;

fn pair(e: &mut Encoder, p: [usize; 2]) {
    e.usize(p[0]);
    e.usize(p[1]);
}

fn get_pair(d: &mut Decoder<'_>) -> Result<[usize; 2]> {
    Ok([d.usize()?, d.usize()?])
}

impl<T: Real> Persist for PlatenControl<T> {
    fn save(&self, e: &mut Encoder) {
        match *self {
            PlatenControl::Speed(v) => {
                e.u8(0);
                e.real(v);
            }
            PlatenControl::Servo {
                target_stress,
                relaxation,
                max_speed,
            } => {
                e.u8(1);
                e.real(target_stress);
                e.real(relaxation);
                e.real(max_speed);
            }
        }
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        Ok(match d.tag("platen control", 2)? {
            0 => PlatenControl::Speed(d.real()?),
            _ => PlatenControl::Servo {
                target_stress: d.real()?,
                relaxation: d.real()?,
                max_speed: d.real()?,
            },
        })
    }
}

impl<T: Real> Persist for Platen<T> {
    fn save(&self, e: &mut Encoder) {
        e.put(&self.wall);
        e.put(&self.control);
        e.real(self.length);
        e.bool(self.active);
        e.real(self.speed);
        e.real2(self.reaction);
        e.usize(self.contacts);
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        Ok(Platen {
            wall: d.get()?,
            control: d.get()?,
            length: d.real()?,
            active: d.bool()?,
            speed: d.real()?,
            reaction: d.real2()?,
            contacts: d.usize()?,
        })
    }
}

impl<T: Real> Persist for Bond<T> {
    fn save(&self, e: &mut Encoder) {
        pair(e, self.pair);
        match &self.law {
            BondLaw::Point(b) => {
                e.u8(0);
                e.put(b);
            }
            BondLaw::Parallel { bond, radii } => {
                e.u8(1);
                e.put(bond);
                e.real2(*radii);
            }
        }
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        let pair = get_pair(d)?;
        let law = match d.tag("bond law", 2)? {
            0 => BondLaw::Point(d.get()?),
            _ => BondLaw::Parallel {
                bond: d.get()?,
                radii: d.real2()?,
            },
        };
        Ok(Bond { pair, law })
    }
}

impl<T: Real> Persist for BreakRecord<T> {
    fn save(&self, e: &mut Encoder) {
        e.u64(self.step);
        pair(e, self.pair);
        e.real2(self.position);
        e.put(&self.mode);
        e.real(self.orientation);
        e.real(self.load);
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        Ok(BreakRecord {
            step: d.u64()?,
            pair: get_pair(d)?,
            position: d.real2()?,
            mode: d.get()?,
            orientation: d.real()?,
            load: d.real()?,
        })
    }
}

fn real2s<T: Real>(e: &mut Encoder, v: &[[T; 2]]) {
    e.usize(v.len());
    v.iter().for_each(|x| e.real2(*x));
}

fn get_real2s<T: Real>(d: &mut Decoder<'_>) -> Result<Vec<[T; 2]>> {
    let n = d.len(2 * std::mem::size_of::<T>())?;
    (0..n).map(|_| d.real2()).collect()
}

impl<T: Real> Persist for DemWorld<T> {
    const PRECISION: u8 = std::mem::size_of::<T>() as u8;

    fn save(&self, e: &mut Encoder) {
        e.list(&self.particles);
        e.list(&self.platens);
        match self.sample_box {
            None => e.u8(0),
            Some(b) => {
                e.u8(1);
                for i in [b.left, b.right, b.bottom, b.top] {
                    e.usize(i);
                }
            }
        }
        e.list(&self.bonds);
        e.put(&self.model);
        e.real(self.local_damping);
        e.real2(self.gravity);
        real2s(e, &self.external_force);
        e.reals(&self.external_torque);
        e.usize(self.held.len());
        self.held.iter().for_each(|&h| e.bool(h));
        e.list(&self.breaks);
        e.real(self.margin);
        e.real(self.dt);
        e.u64(self.step);
        e.usize(self.active_contacts);
        e.real(self.contact_normal_sum);
        e.usize(self.pairs.len());
        self.pairs.iter().for_each(|&p| pair(e, p));
        e.reals(&self.shear);
        real2s(e, &self.force);
        e.reals(&self.torque);
        e.reals(&self.wall_shear);
    }

    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        let particles: Vec<_> = d.list()?;
        let platens: Vec<Platen<T>> = d.list()?;
        let sample_box = match d.tag("sample box", 2)? {
            0 => None,
            _ => Some(SampleBox {
                left: d.usize()?,
                right: d.usize()?,
                bottom: d.usize()?,
                top: d.usize()?,
            }),
        };
        let bonds: Vec<Bond<T>> = d.list()?;
        let model = d.get()?;
        let local_damping = d.real()?;
        let gravity = d.real2()?;
        let external_force = get_real2s(d)?;
        let external_torque = d.reals()?;
        let n_held = d.len(1)?;
        let held = (0..n_held).map(|_| d.bool()).collect::<Result<Vec<_>>>()?;
        let breaks = d.list()?;
        let margin = d.real()?;
        let dt = d.real()?;
        let step = d.u64()?;
        let active_contacts = d.usize()?;
        let contact_normal_sum = d.real()?;
        let n_pairs = d.len(16)?;
        let pairs = (0..n_pairs)
            .map(|_| get_pair(d))
            .collect::<Result<Vec<_>>>()?;
        let shear = d.reals()?;
        let force = get_real2s(d)?;
        let torque = d.reals()?;
        let wall_shear = d.reals()?;
        let n = particles.len();
        let w = platens.len();
        d.ensure(
            external_force.len() == n && external_torque.len() == n && held.len() == n,
            || format!("{n} particles but applied loads or held flags of another length"),
        )?;
        d.ensure(
            bonds.iter().all(|b| b.pair[0] < n && b.pair[1] < n)
                && pairs.iter().all(|p| p[0] < n && p[1] < n)
                && shear.len() == pairs.len(),
            || "a bond or contact names a particle that does not exist".into(),
        )?;
        d.ensure(
            sample_box.is_none_or(|b| [b.left, b.right, b.bottom, b.top].iter().all(|&i| i < w))
                && (wall_shear.is_empty() || wall_shear.len() == n * w)
                && (force.is_empty() || force.len() == n)
                && (torque.is_empty() || torque.len() == n),
            || "platen or force buffers do not match the particle and platen counts".into(),
        )?;
        Ok(DemWorld {
            particles,
            platens,
            sample_box,
            bonds,
            model,
            local_damping,
            gravity,
            external_force,
            external_torque,
            held,
            breaks,
            margin,
            dt,
            step,
            active_contacts,
            contact_normal_sum,
            radii: Vec::new(),
            positions: Vec::new(),
            cell_start: Vec::new(),
            cell_particles: Vec::new(),
            pairs,
            shear,
            previous_pairs: Vec::new(),
            previous_shear: Vec::new(),
            contact_forces: Vec::new(),
            bond_forces: Vec::new(),
            force,
            torque,
            wall_shear,
        })
    }
}
