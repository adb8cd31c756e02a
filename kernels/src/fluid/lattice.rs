//! Lattice geometry: the structure-of-arrays layout and neighbour index arithmetic.
//!
//! Populations live in one caller-owned buffer of `Q * stride` values: direction `q` occupies
//! `buf[q * stride .. q * stride + nx * ny]`, node (x, y) at offset `y * nx + x`. The plane stride is padded so
//! that the nine planes do not all start at the same address modulo 4 KiB (18 streams at identical 4 KiB
//! offsets alias in the L1 cache and were measured 10× slower on the project machines): the stride is the node
//! count rounded up to a whole 4 KiB page plus 320 bytes, so plane q starts at q × 320 bytes (mod 4096).
//!
//! Index arithmetic is checked: [`LatticeShape::new`] refuses sizes whose buffer length would overflow `usize`
//! or whose node count does not fit `u32` (node lists are `u32`), so every index computed by the functions below
//! is in bounds and free of overflow. The Kani harnesses in `verification/` prove this for all sizes up to a bound.
use super::d2q9::{Q, VELOCITIES};

/// The four sides of the rectangular lattice.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Side {
    /// x = 0
    West,
    /// x = nx − 1
    East,
    /// y = 0
    South,
    /// y = ny − 1
    North,
}

/// Size and memory layout of a lattice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LatticeShape {
    /// Nodes along x.
    pub nx: usize,
    /// Nodes along y.
    pub ny: usize,
    /// Distance, in elements, between the starts of consecutive direction planes.
    pub stride: usize,
}

/// Why a lattice shape was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShapeError {
    /// nx or ny is zero.
    Empty,
    /// The node count or buffer length overflows (node indices must fit in `u32`).
    TooLarge,
}

/// Where the neighbour of a node in some direction is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Neighbour {
    /// Inside the lattice at this node index (after periodic wrap where the side is periodic).
    Node(usize),
    /// Outside the lattice across this side (the first side crossed in x, then y, when a corner is crossed).
    Outside {
        /// Side crossed in x, if any.
        x: Option<Side>,
        /// Side crossed in y, if any.
        y: Option<Side>,
    },
}

impl LatticeShape {
    /// Shape for an `nx × ny` lattice of elements of `elem_bytes` bytes (4 or 8).
    pub fn new(nx: usize, ny: usize, elem_bytes: usize) -> Result<Self, ShapeError> {
        if nx == 0 || ny == 0 {
            return Err(ShapeError::Empty);
        }
        let n = nx.checked_mul(ny).ok_or(ShapeError::TooLarge)?;
        if n > u32::MAX as usize {
            return Err(ShapeError::TooLarge);
        }
        let eb = if elem_bytes == 0 { 1 } else { elem_bytes };
        let page = (4096 / eb).max(1);
        let pad = (320 / eb).max(1);
        let rounded = n.checked_add(page - 1).ok_or(ShapeError::TooLarge)? / page * page;
        let stride = rounded.checked_add(pad).ok_or(ShapeError::TooLarge)?;
        stride.checked_mul(Q).ok_or(ShapeError::TooLarge)?;
        Ok(Self { nx, ny, stride })
    }

    /// Shape for element type `T`.
    pub fn for_type<T>(nx: usize, ny: usize) -> Result<Self, ShapeError> {
        Self::new(nx, ny, core::mem::size_of::<T>())
    }

    /// Number of nodes.
    #[inline(always)]
    pub fn nodes(&self) -> usize {
        self.nx * self.ny
    }

    /// Length of a population buffer (all nine planes with padding).
    #[inline(always)]
    pub fn buffer_len(&self) -> usize {
        self.stride * Q
    }

    /// Node index of (x, y); requires x < nx, y < ny.
    #[inline(always)]
    pub fn index(&self, x: usize, y: usize) -> usize {
        y * self.nx + x
    }

    /// (x, y) of a node index; requires index < nodes().
    #[inline(always)]
    pub fn coords(&self, index: usize) -> (usize, usize) {
        (index % self.nx, index / self.nx)
    }

    /// Offset in the population buffer of direction `q` at node `index`.
    #[inline(always)]
    pub fn offset(&self, q: usize, index: usize) -> usize {
        q * self.stride + index
    }

    /// The node at (x, y) + c_q, wrapping across periodic axes; `None` sides are not periodic.
    /// `periodic = [along x, along y]`.
    #[inline]
    pub fn neighbour(&self, x: usize, y: usize, q: usize, periodic: [bool; 2]) -> Neighbour {
        let c = VELOCITIES[q % Q];
        let (nxx, sx) = step_axis(x, c[0], self.nx, periodic[0], Side::West, Side::East);
        let (nyy, sy) = step_axis(y, c[1], self.ny, periodic[1], Side::South, Side::North);
        match (nxx, nyy) {
            (Some(a), Some(b)) => Neighbour::Node(b * self.nx + a),
            _ => Neighbour::Outside { x: sx, y: sy },
        }
    }

    /// The node a population moving along c_q arrives from: (x, y) − c_q (the pull source).
    #[inline]
    pub fn upstream(&self, x: usize, y: usize, q: usize, periodic: [bool; 2]) -> Neighbour {
        self.neighbour(x, y, super::d2q9::OPPOSITE[q % Q], periodic)
    }
}

/// One coordinate step of `d` ∈ {−1, 0, 1} from `v` < `n`. Returns the new coordinate, or the side crossed.
#[inline(always)]
fn step_axis(
    v: usize,
    d: i32,
    n: usize,
    periodic: bool,
    low: Side,
    high: Side,
) -> (Option<usize>, Option<Side>) {
    if d < 0 {
        if v == 0 {
            if periodic {
                (Some(n - 1), None)
            } else {
                (None, Some(low))
            }
        } else {
            (Some(v - 1), None)
        }
    } else if d > 0 {
        if v + 1 >= n {
            if periodic {
                (Some(0), None)
            } else {
                (None, Some(high))
            }
        } else {
            (Some(v + 1), None)
        }
    } else {
        (Some(v), None)
    }
}

/// Wrap a row index y + d (d ∈ {−1, 0, 1}) periodically.
#[inline(always)]
pub fn wrap_row(y: usize, d: i32, ny: usize) -> usize {
    if d < 0 {
        if y == 0 {
            ny - 1
        } else {
            y - 1
        }
    } else if d > 0 {
        if y + 1 >= ny {
            0
        } else {
            y + 1
        }
    } else {
        y
    }
}
