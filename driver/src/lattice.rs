//! The fluid lattice owned by the driver: the two population buffers, node flags, the special-node list, and
//! the parallel step that hands row bands to [`lbdem_kernels::fluid::step`] through rayon.
//!
//! Bands are independent (each reads only the source buffer and writes only its own rows of the destination),
//! so the result is bitwise the same for any number of threads or bands.
use lbdem_kernels::coupling::{
    body_cell_fraction, body_cell_range, reduce_exchange, rigid_velocity, BodyShape, CoupledBody,
};
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::{PsmParams, SolidOperator, SolidShare, Weighting};
use lbdem_kernels::fluid::d2q9::{equilibrium, Q};
use lbdem_kernels::fluid::lattice::{LatticeShape, Side};
use lbdem_kernels::fluid::step::{
    classify_special_nodes, collide_covered_nodes, gathered_moments, nodes_in_rows, planes_mut,
    step_band, CoveredNodes, Domain, FluidParams, FLUID, SOLID,
};
use lbdem_kernels::Real;
use rayon::prelude::*;

use crate::error::{LbdemError, Result};

mod persist;

/// A D2Q9 lattice with its buffers.
pub struct FluidLattice<T: Real> {
    shape: LatticeShape,
    bc: Boundaries<T>,
    params: FluidParams<T>,
    flags: Vec<u8>,
    special: Vec<u32>,
    /// Both population buffers in one allocation: `[first | gap | second]`, see [`buffer_gap`].
    buffers: Vec<T>,
    /// Start of the second buffer in `buffers`.
    second: usize,
    /// Whether the current (post-collision) populations are in the first buffer.
    first_is_current: bool,
    band_rows: usize,
    steps: u64,
    coverage: Option<Coverage<T>>,
    solid_operator: SolidOperator,
}

/// Nodes covered by solids (compressed rows), the solid each share belongs to, and the momentum handed to
/// each share at the last step.
struct Coverage<T> {
    nodes: Vec<u32>,
    offsets: Vec<u32>,
    shares: Vec<SolidShare<T>>,
    owners: Vec<u32>,
    share_nodes: Vec<[f64; 2]>,
    exchange: Vec<[T; 2]>,
    weighting: Weighting,
}

/// A disc as the fluid sees it: centre and radius (lattice units), rigid-body velocity and angular velocity.
#[derive(Clone, Copy, Debug)]
pub struct FluidDisc {
    /// Centre (lattice units, node coordinates).
    pub center: [f64; 2],
    /// Radius the fluid sees (lattice units).
    pub radius: f64,
    /// Translational velocity (lattice units).
    pub velocity: [f64; 2],
    /// Angular velocity (rad per step).
    pub spin: f64,
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
            buffers: vec![T::zero(); 2 * len + buffer_gap::<T>(len)],
            second: len + buffer_gap::<T>(len),
            first_is_current: true,
            band_rows: 8,
            steps: 0,
            coverage: None,
            solid_operator: SolidOperator::default(),
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
                    self.current_mut()[q * stride + n] = *fq;
                }
            }
        }
    }

    /// The current (post-collision) population buffer.
    pub fn populations(&self) -> &[T] {
        let len = self.shape.buffer_len();
        if self.first_is_current {
            &self.buffers[..len]
        } else {
            &self.buffers[self.second..self.second + len]
        }
    }

    /// Mutable access to the current population buffer (for initial conditions and tests).
    pub fn populations_mut(&mut self) -> &mut [T] {
        self.current_mut()
    }

    fn current_mut(&mut self) -> &mut [T] {
        let len = self.shape.buffer_len();
        if self.first_is_current {
            &mut self.buffers[..len]
        } else {
            &mut self.buffers[self.second..self.second + len]
        }
    }

    /// Cover the lattice with discs (exact cell fractions, several discs per cell add up, capped at 1 by the
    /// collision) using the partially-saturated collision with weighting `weighting`. Replaces any previous
    /// coverage. See [`FluidLattice::cover_with_bodies`].
    pub fn cover_with_discs(&mut self, discs: &[FluidDisc], weighting: Weighting) {
        let bodies: Vec<CoupledBody<f64>> = discs
            .iter()
            .map(|d| CoupledBody {
                center: d.center,
                velocity: d.velocity,
                spin: d.spin,
                shape: BodyShape::Disc { radius: d.radius },
            })
            .collect();
        self.cover_with_bodies(&bodies, weighting);
    }

    /// Cover the lattice with rigid bodies (discs or ellipses as the fluid sees them, lattice units): exact cell
    /// fractions from the coupling kernels, several bodies per cell add up (capped at 1 by the collision), each
    /// share carrying the body's rigid velocity at the node. Replaces any previous coverage. Bodies must lie
    /// inside the lattice (no periodic images are taken).
    ///
    /// Nodes on Zou–He sides are never covered: the closure re-imposes the boundary density there every step,
    /// and a fully covered (B = 1) Zou–He node leaves its rest population unrelaxed; the verification suite found
    /// such nodes diverging within a few steps on small random lattices. Solids that reach a pressure or
    /// velocity boundary are therefore seen by the fluid only inside it.
    pub fn cover_with_bodies(&mut self, bodies: &[CoupledBody<f64>], weighting: Weighting) {
        let s = self.shape;
        let mut entries: Vec<(u32, u32, SolidShare<T>)> = Vec::new();
        for (k, body) in bodies.iter().enumerate() {
            let Some([x0, x1, y0, y1]) = body_cell_range(body, s.nx, s.ny) else {
                continue;
            };
            for y in y0..=y1 {
                for x in x0..=x1 {
                    if self.on_zou_he_side(x, y) {
                        continue;
                    }
                    let (px, py) = (x as f64, y as f64);
                    let frac = body_cell_fraction(body, px, py);
                    if frac > 0.0 {
                        let v = rigid_velocity(body, [px, py]);
                        let share = SolidShare {
                            fraction: T::lit(frac),
                            velocity: [T::lit(v[0]), T::lit(v[1])],
                        };
                        entries.push((s.index(x, y) as u32, k as u32, share));
                    }
                }
            }
        }
        // Deterministic order: by node, then by body.
        entries.sort_by_key(|e| (e.0, e.1));
        let mut cov = Coverage {
            nodes: Vec::new(),
            offsets: vec![0],
            shares: Vec::with_capacity(entries.len()),
            owners: Vec::with_capacity(entries.len()),
            share_nodes: Vec::with_capacity(entries.len()),
            exchange: vec![[T::zero(); 2]; entries.len()],
            weighting,
        };
        for (node, owner, share) in entries {
            if cov.nodes.last() != Some(&node) {
                if !cov.nodes.is_empty() {
                    cov.offsets.push(cov.shares.len() as u32);
                }
                cov.nodes.push(node);
            }
            let (x, y) = s.coords(node as usize);
            cov.shares.push(share);
            cov.owners.push(owner);
            cov.share_nodes.push([x as f64, y as f64]);
        }
        cov.offsets.push(cov.shares.len() as u32);
        if cov.nodes.is_empty() {
            cov.offsets = vec![0];
        }
        self.coverage = Some(cov);
    }

    /// Change the prescribed density of a Zou–He pressure side (e.g. the boundary pressure drop of the fracture
    /// test at t = 0). The side must already be a pressure side: its node classification does not change.
    pub fn set_side_density(&mut self, side: Side, density: T) -> Result<()> {
        let slot = match side {
            Side::West => &mut self.bc.west,
            Side::East => &mut self.bc.east,
            Side::South => &mut self.bc.south,
            Side::North => &mut self.bc.north,
        };
        match slot {
            SideCondition::Pressure { density: d } => {
                *d = density;
                Ok(())
            }
            _ => Err(LbdemError::field(
                "boundary side",
                format!("{side:?}"),
                "is not a pressure side, so its density cannot be set",
                "declare the side as a pressure boundary when building the lattice",
            )),
        }
    }

    /// Whether node (x, y) lies on a Zou–He (pressure or velocity) side.
    pub fn on_zou_he_side(&self, x: usize, y: usize) -> bool {
        (x == 0 && self.bc.west.is_zou_he())
            || (x + 1 == self.shape.nx && self.bc.east.is_zou_he())
            || (y == 0 && self.bc.south.is_zou_he())
            || (y + 1 == self.shape.ny && self.bc.north.is_zou_he())
    }

    /// Choose the solid collision operator of covered nodes (default: the dissertation's Ω₁). See
    /// [`SolidOperator`]: Ω₁ lets mass accumulate inside fully covered regions of open systems; prefer Ω₂
    /// (`Superposition`) for long runs with pressure boundaries.
    pub fn set_solid_operator(&mut self, op: SolidOperator) {
        self.solid_operator = op;
    }

    /// The solid collision operator of covered nodes.
    pub fn solid_operator(&self) -> SolidOperator {
        self.solid_operator
    }

    /// Solid fraction ε of every node (row-major) from the current coverage: the fractions of the bodies covering
    /// a node added and capped at 1, as the collision uses them (0 for uncovered nodes, including Zou–He nodes).
    pub fn solid_fraction_map(&self) -> Vec<f64> {
        let mut eps = vec![0.0; self.shape.nodes()];
        if let Some(c) = &self.coverage {
            for (k, &node) in c.nodes.iter().enumerate() {
                let shares = &c.shares[c.offsets[k] as usize..c.offsets[k + 1] as usize];
                let sum: f64 = shares.iter().map(|s| s.fraction.to_f64_exact()).sum();
                eps[node as usize] = sum.min(1.0);
            }
        }
        eps
    }

    /// Number of nodes covered (partly or wholly) by solids.
    pub fn covered_nodes(&self) -> usize {
        self.coverage.as_ref().map_or(0, |c| c.nodes.len())
    }

    /// Force on each of `count` solids from the last step (lattice units), summed in a fixed order.
    pub fn solid_forces(&self, count: usize) -> Vec<[f64; 2]> {
        self.solid_forces_and_torques(&vec![[0.0; 2]; count]).0
    }

    /// Force and torque (about `centers[p]`, lattice units) on each solid from the last step (eq. 4.7–4.8),
    /// reduced by the coupling kernel in the fixed order of the share list.
    pub fn solid_forces_and_torques(&self, centers: &[[f64; 2]]) -> (Vec<[f64; 2]>, Vec<f64>) {
        let mut forces = vec![[0.0; 2]; centers.len()];
        let mut torques = vec![0.0; centers.len()];
        if let Some(c) = &self.coverage {
            let exchange: Vec<[f64; 2]> = c
                .exchange
                .iter()
                .map(|e| [e[0].to_f64_exact(), e[1].to_f64_exact()])
                .collect();
            let periodic = self.bc.periodic_axes();
            let periods = [
                periodic[0].then_some(self.shape.nx as f64),
                periodic[1].then_some(self.shape.ny as f64),
            ];
            reduce_exchange(
                &c.share_nodes,
                &c.owners,
                &exchange,
                centers,
                periods,
                &mut forces,
                &mut torques,
            );
        }
        (forces, torques)
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
        let band_rows = self.band_rows;
        let band_len = band_rows * shape.nx;
        let bands = shape.ny.div_ceil(band_rows);
        // Split the nine destination planes into row bands.
        let (src, dst) = {
            let len = shape.buffer_len();
            let (first, rest) = self.buffers.split_at_mut(self.second);
            let (first, second) = (&mut first[..len], &mut rest[..len]);
            if self.first_is_current {
                (&*first, second)
            } else {
                (&*second, first)
            }
        };
        let planes = planes_mut(&shape, dst);
        let mut chunked: Vec<std::slice::ChunksMut<'_, T>> =
            planes.into_iter().map(|p| p.chunks_mut(band_len)).collect();
        // Split the covered nodes and their exchange buffer along the same bands.
        type Band<'a, T> = (usize, [&'a mut [T]; Q], (usize, usize), &'a mut [[T; 2]]);
        let mut work: Vec<Band<'_, T>> = Vec::with_capacity(bands);
        type Static<'a, T> = (&'a [u32], &'a [u32], &'a [SolidShare<T>], Weighting);
        let (cov, mut exchange_rest): (Option<Static<'_, T>>, &mut [[T; 2]]) =
            match &mut self.coverage {
                Some(Coverage {
                    nodes,
                    offsets,
                    shares,
                    exchange,
                    weighting,
                    ..
                }) => (
                    Some((&nodes[..], &offsets[..], &shares[..], *weighting)),
                    &mut exchange[..],
                ),
                None => (None, &mut []),
            };
        let (cov_nodes, offsets): (&[u32], &[u32]) = match cov {
            Some((n, o, _, _)) => (n, o),
            None => (&[], &[0]),
        };
        let mut lo = 0usize;
        for b in 0..bands {
            let y0 = b * band_rows;
            let y1 = (y0 + band_rows).min(shape.ny);
            let band: [&mut [T]; Q] =
                std::array::from_fn(|q| chunked[q].next().unwrap_or_default());
            let end = (y1 * shape.nx) as u32;
            let hi = lo + cov_nodes[lo..].partition_point(|&n| n < end);
            let len = (offsets[hi] - offsets[lo]) as usize;
            let (mine, rest) = std::mem::take(&mut exchange_rest).split_at_mut(len);
            exchange_rest = rest;
            work.push((y0, band, (lo, hi), mine));
            lo = hi;
        }
        let psm = cov.map(|c| PsmParams {
            tau: params.tau,
            weighting: c.3,
            force: params.force,
            solid: self.solid_operator,
        });
        work.into_par_iter()
            .for_each(|(y0, mut band, (lo, hi), exchange)| {
                let y1 = (y0 + band_rows).min(shape.ny);
                let sp = nodes_in_rows(&shape, special, y0, y1);
                step_band(&domain, src, &mut band, y0, y1, &params, sp);
                if let (Some((nodes, offsets, shares, _)), Some(psm)) = (cov, psm.as_ref()) {
                    if hi > lo {
                        let covered = CoveredNodes {
                            nodes: &nodes[lo..hi],
                            offsets: &offsets[lo..=hi],
                            shares,
                        };
                        collide_covered_nodes(&domain, src, &mut band, y0, psm, covered, exchange);
                    }
                }
            });
        self.first_is_current = !self.first_is_current;
        self.steps += 1;
    }

    /// Density and velocity of every node (row-major), as the next collision sees them.
    pub fn moments(&self) -> (Vec<T>, Vec<[T; 2]>) {
        let n = self.shape.nodes();
        let mut rho = vec![T::zero(); n];
        let mut u = vec![[T::zero(); 2]; n];
        gathered_moments(
            &self.shape,
            self.populations(),
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
            let plane = &self.populations()
                [q * self.shape.stride..q * self.shape.stride + self.shape.nodes()];
            for (v, &flag) in plane.iter().zip(self.flags.iter()) {
                if flag != SOLID {
                    m += v.to_f64_exact();
                }
            }
        }
        m
    }

    /// Total fluid momentum Σ f_i c_i over fluid nodes (post-collision populations), in f64, lattice units.
    pub fn momentum(&self) -> [f64; 2] {
        let mut j = [0.0; 2];
        for (q, c) in lbdem_kernels::fluid::d2q9::VELOCITIES.iter().enumerate() {
            if c[0] == 0 && c[1] == 0 {
                continue;
            }
            let plane = &self.populations()
                [q * self.shape.stride..q * self.shape.stride + self.shape.nodes()];
            let mut sum = 0.0;
            for (v, &flag) in plane.iter().zip(self.flags.iter()) {
                if flag != SOLID {
                    sum += v.to_f64_exact();
                }
            }
            j[0] += c[0] as f64 * sum;
            j[1] += c[1] as f64 * sum;
        }
        j
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

/// Elements between the two population buffers, so that each plane of the second buffer starts 160 bytes (mod
/// 4 KiB) after the same plane of the first. Planes within a buffer are 320 bytes apart (mod 4 KiB, see
/// [`LatticeShape`]); with both buffers at the same offset, the store to plane q of the destination would hit
/// the same 4 KiB offset as the load from plane q of the source a few elements before it ("4K aliasing": the
/// load waits for the store). 160 bytes is as far as possible from every multiple of 320 bytes mod 4 KiB.
fn buffer_gap<T>(len: usize) -> usize {
    let size = std::mem::size_of::<T>().max(1);
    let end = (len * size) % 4096;
    (160 + 4096 - end) % 4096 / size
}
