//! Checkpoints of a [`FluidLattice`] (serde): shape, side conditions, collision parameters, node flags, the
//! current populations (every plane in full, padding included), the step counter, the PSM coverage (covered
//! nodes, shares, owners, wall normals, the momentum exchanged at the last step, the weighting), the solid operator, ΩΛ's constants and the
//! fluid collision (BGK, or TRT with its magic parameter, checked again on load) and the velocity profiles of
//! profile sides (checked again on load), the remap tolerance and, with one, the geometry each body's cells were
//! last mapped for (so that a resumed run keeps the same cells until the bodies move beyond the tolerance, as
//! the saved run would have). The special-node list and ΩΛ's open-link masks are derived from the
//! flags and the coverage and rebuilt. The populations are saved in the two-lattice layout
//! whatever the streaming scheme and step parity (see [`FluidLattice::populations`]), and a loaded lattice starts
//! from that layout with the default scheme (a run sets its own afterwards): either continues bitwise as the
//! saved run would have. The two-lattice scheme's second buffer is scratch (every node of it is rewritten by the
//! next step before it is read); the band height only changes speed.
use std::borrow::Cow;

use lbdem_kernels::fluid::boundary::Boundaries;
use lbdem_kernels::fluid::collide::{Collision, LambdaTerms, SolidOperator};
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::Real;
use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use lbdem_kernels::coupling::{BodyShape, CoupledBody};

use super::{Coverage, FluidLattice};

/// What a checkpoint holds of a lattice.
#[derive(Serialize, Deserialize)]
#[serde(bound(serialize = "T: Serialize", deserialize = "T: Deserialize<'de>"))]
struct Record<'a, T: Real> {
    nx: usize,
    ny: usize,
    bc: Boundaries<T>,
    params: FluidParams<T>,
    flags: Cow<'a, [u8]>,
    populations: Cow<'a, [T]>,
    steps: u64,
    solid_operator: SolidOperator,
    /// ΩΛ's friction κ and wall-pressure α (checked again on load).
    lambda_terms: LambdaTerms,
    collision: Collision<T>,
    coverage: Option<Cow<'a, Coverage<T>>>,
    profiles: Cow<'a, [Vec<[T; 2]>; 4]>,
    remap_tolerance: f64,
    /// Per body: shape kind (0 disc, 1 ellipse), centre x and y, radius or semi-axes, angle (lattice units).
    mapped: Vec<[f64; 6]>,
}

fn encode(b: &CoupledBody<f64>) -> [f64; 6] {
    let [cx, cy] = [b.center[0], b.center[1]];
    match b.shape {
        BodyShape::Disc { radius } => [0.0, cx, cy, radius, 0.0, 0.0],
        BodyShape::Ellipse {
            semi_major,
            semi_minor,
            angle,
        } => [1.0, cx, cy, semi_major, semi_minor, angle],
    }
}

fn decode([kind, cx, cy, a, b, angle]: [f64; 6]) -> Option<CoupledBody<f64>> {
    if ![cx, cy, a, b, angle].iter().all(|v| v.is_finite()) {
        return None;
    }
    let shape = match kind {
        0.0 => BodyShape::Disc { radius: a },
        1.0 => BodyShape::Ellipse {
            semi_major: a,
            semi_minor: b,
            angle,
        },
        _ => return None,
    };
    Some(CoupledBody {
        center: lbdem_kernels::math::vector(cx, cy),
        velocity: lbdem_kernels::math::Vector::zeros(),
        spin: 0.0,
        shape,
    })
}

impl<T: Real + Serialize> Serialize for FluidLattice<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        Record {
            nx: self.shape.nx,
            ny: self.shape.ny,
            bc: self.bc,
            params: self.params,
            flags: Cow::Borrowed(&self.flags),
            populations: self.populations(),
            steps: self.steps,
            solid_operator: self.solid_operator,
            lambda_terms: self.lambda_terms,
            collision: self.collision,
            coverage: self.coverage.as_ref().map(Cow::Borrowed),
            profiles: Cow::Borrowed(&self.profiles),
            remap_tolerance: self.remap_tolerance,
            mapped: self.mapped_geometry().iter().map(encode).collect(),
        }
        .serialize(s)
    }
}

impl<'de, T: Real + Deserialize<'de>> Deserialize<'de> for FluidLattice<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let r = Record::<T>::deserialize(d)?;
        let (nx, ny) = (r.nx, r.ny);
        let mut lattice = FluidLattice::<T>::new(nx, ny, r.bc, r.params)
            .map_err(|e| D::Error::custom(e.to_string()))?;
        if r.flags.len() != lattice.shape.nodes() {
            return Err(D::Error::custom(format!(
                "{} node flags for a {nx} x {ny} lattice",
                r.flags.len()
            )));
        }
        if r.populations.len() != lattice.shape.buffer_len() {
            return Err(D::Error::custom(format!(
                "{} populations for a {nx} x {ny} lattice",
                r.populations.len()
            )));
        }
        lattice.flags = r.flags.into_owned();
        lattice.reclassify();
        lattice.first_is_current = true;
        lattice.populations_mut().copy_from_slice(&r.populations);
        lattice.steps = r.steps;
        lattice.solid_operator = r.solid_operator;
        lattice
            .set_lambda_terms(r.lambda_terms)
            .map_err(D::Error::custom)?;
        lattice
            .set_collision(r.collision)
            .map_err(|e| D::Error::custom(e.to_string()))?;
        if let Some(c) = r.coverage {
            let c = c.into_owned();
            let n = c.shares.len();
            let consistent = c.offsets.len() == c.nodes.len() + 1
                && c.offsets.first() == Some(&0)
                && c.offsets.last().map(|&o| o as usize) == Some(n)
                && c.offsets.windows(2).all(|w| w[0] <= w[1])
                && c.nodes
                    .iter()
                    .all(|&k| (k as usize) < lattice.shape.nodes())
                && c.nodes.windows(2).all(|w| w[0] < w[1])
                && c.owners.len() == n
                && c.share_nodes.len() == n
                && (c.normals.len() == n || c.normals.is_empty())
                && c.normals.iter().all(|v| {
                    // A wall normal is of unit length, or zero where there is no direction.
                    let len = (v[0] * v[0] + v[1] * v[1]).to_f64_exact();
                    len.is_finite() && (len == 0.0 || (len - 1.0).abs() <= 1e-5)
                })
                && c.exchange.len() == n;
            if !consistent {
                return Err(D::Error::custom(
                    "PSM coverage lists do not match each other or the lattice",
                ));
            }
            lattice.coverage = Some(c);
            lattice.refresh_links();
        }
        let profiles = r.profiles.into_owned();
        for (k, p) in profiles.iter().enumerate() {
            if p.len() != lattice.profiles[k].len() {
                return Err(D::Error::custom(format!(
                    "side profile {k} (west, east, south, north) of {} values for a {nx} x {ny} lattice \
                     that expects {}",
                    p.len(),
                    lattice.profiles[k].len()
                )));
            }
        }
        super::side_profiles(&profiles)
            .validate(&lattice.bc, nx, ny)
            .map_err(|e| D::Error::custom(format!("side profiles refused: {e:?}")))?;
        lattice.profiles = profiles;
        lattice
            .set_remap_tolerance(r.remap_tolerance)
            .map_err(|e| D::Error::custom(e.to_string()))?;
        let mapped: Option<Vec<CoupledBody<f64>>> = r.mapped.into_iter().map(decode).collect();
        let Some(mapped) = mapped else {
            return Err(D::Error::custom(
                "the mapped grain geometry is not finite or names an unknown shape",
            ));
        };
        lattice.restore_mapped_geometry(mapped);
        Ok(lattice)
    }
}
