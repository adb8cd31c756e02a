//! The fluid lattice owned by the driver: the two population buffers, node flags, the special-node list, and
//! the parallel step that hands row bands to [`lbdem_kernels::fluid::step`] through rayon.
//!
//! Bands are independent (each reads only the source buffer and writes only its own rows of the destination),
//! so the result is bitwise the same for any number of threads or bands.
use lbdem_kernels::fluid::boundary::Boundaries;
use lbdem_kernels::fluid::d2q9::{equilibrium, Q};
use lbdem_kernels::fluid::lattice::LatticeShape;
use lbdem_kernels::fluid::step::{
    classify_special_nodes, gathered_moments, nodes_in_rows, planes_mut, step_band, Domain,
    FluidParams, FLUID, SOLID,
};
use lbdem_kernels::Real;
use rayon::prelude::*;

use crate::error::{LbdemError, Result};

/// A D2Q9 lattice with its buffers.
pub struct FluidLattice<T: Real> {
    shape: LatticeShape,
    bc: Boundaries<T>,
    params: FluidParams<T>,
    flags: Vec<u8>,
    special: Vec<u32>,
    src: Vec<T>,
    dst: Vec<T>,
    band_rows: usize,
    steps: u64,
}

impl<T: Real> FluidLattice<T> {
    /// An `nx × ny` lattice at rest with density 1, all nodes fluid.
    pub fn new(nx: usize, ny: usize, bc: Boundaries<T>, params: FluidParams<T>) -> Result<Self> {
        let shape = LatticeShape::for_type::<T>(nx, ny).map_err(|e| {
            LbdemError::field(
                "lattice size",
                format!("{nx} x {ny}"),
                &format!("cannot be allocated ({e:?})"),
                "every side needs at least one node and the node count must fit in 32 bits",
            )
        })?;
        bc.validate().map_err(|e| {
            LbdemError::field(
                "boundary conditions",
                format!("{e:?}"),
                "are inconsistent",
                "pair periodic sides",
            )
        })?;
        if params.tau.to_f64_exact().partial_cmp(&0.5) != Some(std::cmp::Ordering::Greater) {
            return Err(LbdemError::field(
                "fluid.tau",
                params.tau.to_f64_exact(),
                "BGK is unstable for tau <= 1/2",
                "use tau in (0.5, 2]",
            ));
        }
        let len = shape.buffer_len();
        let mut lattice = Self {
            shape,
            bc,
            params,
            flags: vec![FLUID; shape.nodes()],
            special: Vec::new(),
            src: vec![T::zero(); len],
            dst: vec![T::zero(); len],
            band_rows: 8,
            steps: 0,
        };
        lattice.reclassify();
        lattice.fill_equilibrium(|_, _| (T::one(), [T::zero(); 2]));
        Ok(lattice)
    }

    /// Shape of the lattice.
    pub fn shape(&self) -> &LatticeShape {
        &self.shape
    }

    /// Collision parameters.
    pub fn params(&self) -> &FluidParams<T> {
        &self.params
    }

    /// Side conditions.
    pub fn boundaries(&self) -> &Boundaries<T> {
        &self.bc
    }

    /// Node flags.
    pub fn flags(&self) -> &[u8] {
        &self.flags
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Rows per parallel band (results do not depend on it; only speed does).
    pub fn set_band_rows(&mut self, rows: usize) {
        self.band_rows = rows.max(1);
    }

    /// Mark nodes as solid obstacles (half-way bounce-back) according to `solid(x, y)`.
    pub fn set_solid(&mut self, solid: impl Fn(usize, usize) -> bool) {
        for y in 0..self.shape.ny {
            for x in 0..self.shape.nx {
                let n = self.shape.index(x, y);
                self.flags[n] = if solid(x, y) { SOLID } else { FLUID };
            }
        }
        self.reclassify();
    }

    fn reclassify(&mut self) {
        let mut list = vec![0u32; self.shape.nodes()];
        let count = classify_special_nodes(&self.shape, &self.bc, &self.flags, &mut list);
        list.truncate(count);
        self.special = list;
    }

    /// Set every node to the equilibrium of `state(x, y) = (ρ, u)` (stored as post-collision populations).
    pub fn fill_equilibrium(&mut self, state: impl Fn(usize, usize) -> (T, [T; 2])) {
        let stride = self.shape.stride;
        for y in 0..self.shape.ny {
            for x in 0..self.shape.nx {
                let n = self.shape.index(x, y);
                let (rho, u) = state(x, y);
                let f = equilibrium(rho, u);
                for (q, fq) in f.iter().enumerate() {
                    self.src[q * stride + n] = *fq;
                }
            }
        }
    }

    /// The current (post-collision) population buffer.
    pub fn populations(&self) -> &[T] {
        &self.src
    }

    /// Mutable access to the current population buffer (for initial conditions and tests).
    pub fn populations_mut(&mut self) -> &mut [T] {
        &mut self.src
    }

    /// Advance one lattice step, in parallel over row bands on the current rayon pool.
    pub fn step(&mut self) {
        let shape = self.shape;
        let domain = Domain {
            shape,
            bc: self.bc,
            flags: &self.flags,
        };
        let params = self.params;
        let special = &self.special;
        let src = &self.src;
        let band_rows = self.band_rows;
        let band_len = band_rows * shape.nx;
        // Split the nine destination planes into row bands.
        let planes = planes_mut(&shape, &mut self.dst);
        let mut chunked: Vec<std::slice::ChunksMut<'_, T>> =
            planes.into_iter().map(|p| p.chunks_mut(band_len)).collect();
        let bands = shape.ny.div_ceil(band_rows);
        let mut work: Vec<(usize, [&mut [T]; Q])> = Vec::with_capacity(bands);
        for b in 0..bands {
            let band: [&mut [T]; Q] =
                std::array::from_fn(|q| chunked[q].next().unwrap_or_default());
            work.push((b * band_rows, band));
        }
        work.into_par_iter().for_each(|(y0, mut band)| {
            let y1 = (y0 + band_rows).min(shape.ny);
            let sp = nodes_in_rows(&shape, special, y0, y1);
            step_band(&domain, src, &mut band, y0, y1, &params, sp);
        });
        std::mem::swap(&mut self.src, &mut self.dst);
        self.steps += 1;
    }

    /// Density and velocity of every node (row-major), as the next collision sees them.
    pub fn moments(&self) -> (Vec<T>, Vec<[T; 2]>) {
        let n = self.shape.nodes();
        let mut rho = vec![T::zero(); n];
        let mut u = vec![[T::zero(); 2]; n];
        gathered_moments(
            &self.shape,
            &self.src,
            &self.bc,
            &self.flags,
            self.params.force,
            &mut rho,
            &mut u,
        );
        (rho, u)
    }

    /// Total fluid mass (sum of populations over fluid nodes), in f64.
    pub fn mass(&self) -> f64 {
        let mut m = 0.0;
        for q in 0..Q {
            let plane =
                &self.src[q * self.shape.stride..q * self.shape.stride + self.shape.nodes()];
            for (v, &flag) in plane.iter().zip(self.flags.iter()) {
                if flag != SOLID {
                    m += v.to_f64_exact();
                }
            }
        }
        m
    }

    /// First non-finite or out-of-band density, as (node, value), checking densities in [lo, hi].
    pub fn health_check(&self, lo: f64, hi: f64) -> Option<(usize, f64)> {
        let (rho, u) = self.moments();
        for (n, (r, v)) in rho.iter().zip(u.iter()).enumerate() {
            if self.flags[n] == SOLID {
                continue;
            }
            let r = r.to_f64_exact();
            if !r.is_finite() || r < lo || r > hi || !v[0].is_finite() || !v[1].is_finite() {
                return Some((n, r));
            }
        }
        None
    }
}
