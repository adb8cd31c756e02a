//! [`Persist`] for [`FluidLattice`]: shape, side conditions, collision parameters, node flags, the current
//! population buffer (every plane in full, padding included), the step counter, the PSM coverage (covered
//! nodes, shares, owners, the momentum exchanged at the last step, the weighting), the solid operator and the
//! fluid collision (BGK, or TRT with its magic parameter) and the velocity profiles of profile sides. The
//! special-node list is derived from the flags and rebuilt. The populations are saved in the two-lattice layout
//! whatever the streaming scheme and step parity (see [`FluidLattice::populations`]), and a loaded lattice starts
//! from that layout with the scheme chosen for the new process: either continues bitwise as the saved run would
//! have. The two-lattice scheme's second buffer is scratch (every node of it is rewritten by the next step before
//! it is read); the band height only changes speed.
use lbdem_kernels::fluid::collide::{Collision, Trt};
use lbdem_kernels::fluid::lattice::LatticeShape;
use lbdem_kernels::Real;

use super::{Coverage, FluidLattice};
use crate::checkpoint::{Decoder, Encoder, Persist};
use crate::error::Result;

impl<T: Real> Persist for FluidLattice<T> {
    const PRECISION: u8 = std::mem::size_of::<T>() as u8;

    fn save(&self, e: &mut Encoder) {
        e.usize(self.shape.nx);
        e.usize(self.shape.ny);
        e.put(&self.bc);
        e.put(&self.params);
        e.bytes(&self.flags);
        e.reals(&self.populations());
        e.u64(self.steps);
        e.put(&self.solid_operator);
        match &self.coverage {
            None => e.u8(0),
            Some(c) => {
                e.u8(1);
                e.usize(c.nodes.len());
                c.nodes.iter().for_each(|&n| e.u32(n));
                e.usize(c.offsets.len());
                c.offsets.iter().for_each(|&n| e.u32(n));
                e.list(&c.shares);
                e.usize(c.owners.len());
                c.owners.iter().for_each(|&n| e.u32(n));
                e.usize(c.share_nodes.len());
                c.share_nodes.iter().for_each(|p| e.real2(*p));
                e.usize(c.exchange.len());
                c.exchange.iter().for_each(|p| e.real2(*p));
                e.put(&c.weighting);
            }
        }
        match self.collision {
            Collision::Bgk => e.u8(0),
            Collision::Trt(t) => {
                e.u8(1);
                e.real(t.magic());
            }
        }
        for p in &self.profiles {
            e.usize(p.len());
            p.iter().for_each(|v| e.real2(*v));
        }
    }

    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        let (nx, ny) = (d.usize()?, d.usize()?);
        let bc = d.get()?;
        let params = d.get()?;
        let mut lattice = FluidLattice::<T>::new(nx, ny, bc, params)?;
        let flags = d.bytes()?;
        d.ensure(flags.len() == lattice.shape.nodes(), || {
            format!("{} node flags for a {nx} x {ny} lattice", flags.len())
        })?;
        lattice.flags = flags;
        lattice.reclassify();
        let pops: Vec<T> = d.reals()?;
        d.ensure(pops.len() == lattice.shape.buffer_len(), || {
            format!("{} populations for a {nx} x {ny} lattice", pops.len())
        })?;
        lattice.first_is_current = true;
        lattice.populations_mut().copy_from_slice(&pops);
        lattice.steps = d.u64()?;
        lattice.solid_operator = d.get()?;
        lattice.coverage = match d.tag("coverage", 2)? {
            0 => None,
            _ => Some(load_coverage(d, &lattice.shape)?),
        };
        lattice.refresh_links();
        let collision = match d.tag("fluid collision", 2)? {
            0 => Collision::Bgk,
            _ => {
                let magic: T = d.real()?;
                let trt = Trt::new(magic);
                d.ensure(trt.is_ok(), || {
                    format!("TRT magic parameter {}", magic.to_f64_exact())
                })?;
                Collision::Trt(trt.unwrap_or_default())
            }
        };
        lattice.set_collision(collision)?;
        for k in 0..4 {
            let p = pairs::<T>(d)?;
            d.ensure(p.len() == lattice.profiles[k].len(), || {
                format!("a side profile of {} values", p.len())
            })?;
            lattice.profiles[k] = p;
        }
        Ok(lattice)
    }
}

fn u32s(d: &mut Decoder<'_>) -> Result<Vec<u32>> {
    let n = d.len(4)?;
    (0..n).map(|_| d.u32()).collect()
}

fn pairs<T: Real>(d: &mut Decoder<'_>) -> Result<Vec<[T; 2]>> {
    let n = d.len(2 * std::mem::size_of::<T>())?;
    (0..n).map(|_| d.real2()).collect()
}

fn load_coverage<T: Real>(d: &mut Decoder<'_>, shape: &LatticeShape) -> Result<Coverage<T>> {
    let nodes = u32s(d)?;
    let offsets = u32s(d)?;
    let shares = d.list()?;
    let owners = u32s(d)?;
    let share_nodes = pairs::<f64>(d)?;
    let exchange = pairs::<T>(d)?;
    let weighting = d.get()?;
    let n = shares.len();
    d.ensure(
        offsets.len() == nodes.len() + 1
            && offsets.first() == Some(&0)
            && offsets.last().map(|&o| o as usize) == Some(n)
            && offsets.windows(2).all(|w| w[0] <= w[1])
            && nodes.iter().all(|&k| (k as usize) < shape.nodes())
            && nodes.windows(2).all(|w| w[0] < w[1])
            && owners.len() == n
            && share_nodes.len() == n
            && exchange.len() == n,
        || "PSM coverage lists do not match each other or the lattice".into(),
    )?;
    Ok(Coverage {
        nodes,
        offsets,
        shares,
        owners,
        share_nodes,
        exchange,
        weighting,
        links: Vec::new(),
    })
}
