//! [`Persist`] for [`CoupledWorld`]: the fluid lattice, the DEM world, the unit map, the fluid radius, the
//! PSM weighting, the DEM substeps, the applied loads, the per-grain fluid radii and the coupled
//! step counter.
use super::{CoupledWorld, LatticeMap};
use crate::checkpoint::{Decoder, Encoder, Persist};
use crate::error::Result;

impl Persist for LatticeMap {
    fn save(&self, e: &mut Encoder) {
        e.f64(self.spacing);
        e.f64(self.timestep);
        e.f64(self.density);
        e.f64(self.origin[0]);
        e.f64(self.origin[1]);
    }
    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        Ok(LatticeMap {
            spacing: d.f64()?,
            timestep: d.f64()?,
            density: d.f64()?,
            origin: [d.f64()?, d.f64()?],
        })
    }
}

impl Persist for CoupledWorld {
    const PRECISION: u8 = 8;

    fn save(&self, e: &mut Encoder) {
        e.put(&self.fluid);
        e.put(&self.dem);
        e.put(&self.map);
        e.f64(self.fluid_radius);
        e.put(&self.weighting);
        e.u32(self.substeps);
        e.usize(self.applied.len());
        for (f, t) in &self.applied {
            e.f64(f[0]);
            e.f64(f[1]);
            e.f64(*t);
        }
        e.f64s(&self.grain_fluid_radius);
        e.u64(self.steps);
    }

    fn load(d: &mut Decoder<'_>) -> Result<Self> {
        let fluid = d.get()?;
        let dem: crate::solid::DemWorld<f64> = d.get()?;
        let map = d.get()?;
        let fluid_radius = d.f64()?;
        let weighting = d.get()?;
        let substeps = d.u32()?;
        let n = d.len(24)?;
        let applied = (0..n)
            .map(|_| Ok(([d.f64()?, d.f64()?], d.f64()?)))
            .collect::<Result<Vec<_>>>()?;
        let grain_fluid_radius = d.f64s()?;
        let steps = d.u64()?;
        d.ensure(
            applied.len() == dem.particles.len() && substeps >= 1,
            || {
                format!(
                    "{} applied loads for {} grains, {substeps} substeps",
                    applied.len(),
                    dem.particles.len()
                )
            },
        )?;
        Ok(CoupledWorld {
            fluid,
            dem,
            map,
            fluid_radius,
            weighting,
            substeps,
            applied,
            grain_fluid_radius,
            steps,
            timings: None,
        })
    }
}
