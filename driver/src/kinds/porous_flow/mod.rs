//! `kind = "porous_flow"`: flow through fixed discs between pressure boundaries (dissertation §5.5): Darcy's law
//! and the permeability, on the fluid lattice alone.
//!
//! Discs on a (regular or seeded-jittered) square lattice of pitch l between Zou–He pressure boundaries at west
//! and east, periodic (or walled) north and south, with fluid buffers between the boundaries and the discs.
//! Darcy's law q = −(k/μ)∇p is checked by the linearity of the superficial flux q against the imposed gradient;
//! the permeability k = μ q/G uses the interior gradient G, fitted through the fluid-averaged pressure of whole
//! pitch-wide columns of the array (first and last column left out, so the entrance regions do not enter).
//! Kozeny–Carman for discs ([`lbdem_reference::analytic::kozeny_carman`]): k = n³D²/(16 c_K (1 − n)²); the
//! fitted c_K is reported.
//!
//! **Solid operator.** Default Ω₁ (eq. 4.6). Ω₁ never relaxes the rest population of fully covered nodes, which
//! keep gaining mass from the fluid; the check is `covered_density_excess` (mean density of covered minus free
//! nodes over the imposed drop: 6e-4 in the Darcy test); the runs stop at the end of the transient, long before
//! any accumulation matters. Ω₂ (`solid_operator = "superposition"`) is bounded but leaky: its permeabilities
//! are 15–36 % high at pitch 24.
//!
//! Everything here is in lattice units (h = Δt = 1, ρ₀ = 1); [`PorousSetup`] converts a scene in physical units
//! through [`crate::units`].
use std::path::Path;

use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::{Collision, LambdaTerms, SolidOperator};
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::Real;
use lbdem_reference::analytic::{kozeny_constant, sangani_acrivos_tabulated};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::engine::exec::Exec;
use crate::engine::lattice::{FluidDisc, FluidLattice};
use crate::error::{LbdemError, Result};
use crate::input::limits::{self, Budget};
use crate::observe::darcy::{permeability, SteadyFlow};
use crate::observe::fit::linear_fit;
use crate::observe::flow::max_mach;
use crate::observe::steady::Steadiness;
use crate::output::snapshots::{disc_grain, write_fixed, FixedSnapshots};
use crate::output::vtk::LatticeFrame;
use crate::output::{csv, write_atomic};
use crate::run::cases::{solve, CaseRun, Sweep, DRIVE_HINT};
use crate::run::{Case, Kind, OutputStage};
use crate::scene::{whole_spacings, Precision, RunSection, SceneHeader};
use crate::units::{
    check_density_drop, check_tau, collision_of, cs2_times, CollisionName, FluidSection,
    LatticeUnits, Warnings,
};

/// The fluid collision of porous-flow scenes without `[fluid] collision`: TRT, which with ΩΛ (the default
/// solid operator) gives a permeability that does not depend on τ (README, "Results that do not depend on τ").
pub const COLLISION: CollisionName = CollisionName::Trt;

/// The solid operator of porous-flow scenes without `solid_operator`: ΩΛ (bounded with pressure boundaries:
/// fully covered nodes are reset to the solid's equilibrium, so no mass accumulates inside solids).
pub fn default_operator() -> SolidOperator {
    SolidOperator::LambdaConsistent
}

/// One porous-slab run in lattice units.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PorousCase {
    /// Disc columns along x (≥ 4).
    pub columns: usize,
    /// Disc rows along y.
    pub rows: usize,
    /// Pitch l of the disc lattice (nodes).
    pub pitch: usize,
    /// Disc diameter D (nodes, < pitch).
    pub diameter: f64,
    /// Free fluid nodes between each Zou–He side and the array (≥ 1).
    pub buffer: usize,
    /// Random displacement of each disc, as a fraction of the half-gap (l − D)/2, in [0, 1).
    pub jitter: f64,
    /// Seed of the jitter.
    pub seed: u64,
    /// Walls at north and south (else periodic).
    pub walls: bool,
    /// Relaxation time τ.
    pub tau: f64,
    /// Solid operator of the PSM.
    pub solid_operator: SolidOperator,
    /// ΩΛ's constants (`[fluid] lambda_form`; read only when the solid operator is ΩΛ).
    #[serde(default)]
    pub lambda_terms: LambdaTerms,
    /// Fluid collision (BGK, or TRT with its magic parameter).
    #[serde(default)]
    pub collision: Collision<f64>,
    /// Inlet minus outlet lattice density (ρ_in, ρ_out = 1 ± Δρ/2).
    pub density_drop: f64,
    /// Stop once the relative change of the flux over one check interval is below this.
    pub steady_tolerance: f64,
    /// Steps between checks.
    pub check_interval: u64,
    /// Upper bound on the steps.
    pub max_steps: u64,
}

/// Most discs of one slab: 2 × 10⁴ (the validation's slabs hold tens to hundreds). The narrowest gap ([`PorousCase::min_gap`], printed by `lbdem check`) is found in
/// O(discs) once per diameter.
pub const MAX_DISCS: u64 = 20_000;

/// Lattice size (nx, ny) of `columns × rows` discs at `pitch` nodes with `buffer` free nodes at each end
/// ([`PorousCase::size`] in checked arithmetic), refused naming the field that overflows.
fn lattice_size(columns: u64, rows: u64, pitch: u64, buffer: u64) -> Result<(u64, u64)> {
    let what = "the lattice length";
    let nx = limits::mul("porous.columns", what, columns, pitch)?;
    let nx = limits::add(
        "porous.buffer",
        what,
        nx,
        limits::mul("porous.buffer", what, 2, buffer)?,
    )?;
    let nx = limits::add("porous.columns", what, nx, 2)?;
    let ny = limits::mul("porous.rows", "the lattice height", rows, pitch)?;
    Ok((nx, ny))
}

impl PorousCase {
    /// Lattice size (nx, ny): Zou–He nodes at x = 0 and x = nx − 1.
    pub fn size(&self) -> (usize, usize) {
        (
            2 * self.buffer + self.columns * self.pitch + 2,
            self.rows * self.pitch,
        )
    }

    /// First node column of the array.
    fn array_start(&self) -> usize {
        1 + self.buffer
    }

    /// Lattice viscosity (τ − ½)/3.
    pub fn viscosity(&self) -> f64 {
        crate::units::lattice_viscosity(self.tau)
    }

    /// Porosity of the array region, 1 − πD²/(4 l²).
    pub fn porosity(&self) -> f64 {
        1.0 - std::f64::consts::PI * self.diameter * self.diameter
            / (4.0 * (self.pitch * self.pitch) as f64)
    }

    /// The discs (row-major), jittered deterministically from the seed.
    pub fn discs(&self) -> Vec<FluidDisc> {
        let l = self.pitch as f64;
        let half_gap = 0.5 * (l - self.diameter);
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let x0 = self.array_start() as f64 - 0.5;
        let mut out = Vec::with_capacity(self.rows * self.columns);
        for j in 0..self.rows {
            for i in 0..self.columns {
                let (dx, dy) = if self.jitter > 0.0 {
                    (
                        self.jitter * half_gap * rng.random_range(-1.0..1.0),
                        self.jitter * half_gap * rng.random_range(-1.0..1.0),
                    )
                } else {
                    (0.0, 0.0)
                };
                out.push(FluidDisc {
                    center: [
                        x0 + (i as f64 + 0.5) * l + dx,
                        (j as f64 + 0.5) * l - 0.5 + dy,
                    ],
                    radius: 0.5 * self.diameter,
                    velocity: [0.0; 2],
                    spin: 0.0,
                });
            }
        }
        out
    }

    /// Narrowest gap between neighbouring discs (or a disc and a wall), in nodes.
    pub fn min_gap(&self) -> f64 {
        self.min_gap_counted().0
    }

    /// [`Self::min_gap`] and the number of disc pairs it measured. Exactly the minimum over every pair (and
    /// wall), found in O(n) by searching each disc's neighbour cells only: disc (i, j) sits in cell (i, j) of
    /// the pitch lattice, displaced by at most `jitter × (l − D)/2` along each axis, so two discs whose cells
    /// are k cells apart (along x, or along y cyclically when periodic) have centres at least
    /// `k l − 2 jitter (l − D)/2` apart, and a gap at least that minus D. The search widens from the 8
    /// neighbour cells until the narrowest gap found is below that bound for the next ring (at once for a
    /// regular lattice, whose neighbours are l − D apart and the next ring at least 2l − D).
    pub fn min_gap_counted(&self) -> (f64, u64) {
        let discs = self.discs();
        let (_, ny) = self.size();
        let ny = ny as f64;
        let (columns, rows) = (self.columns, self.rows);
        let l = self.pitch as f64;
        let drift = 2.0 * self.jitter * (0.5 * (l - self.diameter)).abs();
        let mut gap = f64::INFINITY;
        for da in &discs {
            if self.walls {
                gap = gap.min(da.center[1] + 0.5 - da.radius);
                gap = gap.min(ny - 0.5 - da.center[1] - da.radius);
            }
            if !self.walls && rows == 1 {
                gap = gap.min(ny - 2.0 * da.radius);
            }
        }
        let pair = |a: &FluidDisc, b: &FluidDisc| {
            let mut dy = (a.center[1] - b.center[1]).abs();
            if !self.walls {
                dy = dy.min(ny - dy);
            }
            let dx = a.center[0] - b.center[0];
            (dx * dx + dy * dy).sqrt() - a.radius - b.radius
        };
        // The cells within `reach` of cell `c` of `n` along one axis, each once.
        let near = |c: usize, n: usize, reach: usize, cyclic: bool| -> Vec<usize> {
            let (lo, hi) = (c as i64 - reach as i64, c as i64 + reach as i64);
            let mut v: Vec<usize> = if cyclic {
                (lo..=hi.min(lo + n as i64 - 1))
                    .map(|k| k.rem_euclid(n as i64) as usize)
                    .collect()
            } else {
                (lo.max(0)..=hi.min(n as i64 - 1))
                    .map(|k| k as usize)
                    .collect()
            };
            v.sort_unstable();
            v
        };
        let mut pairs = 0u64;
        // Beyond `columns.max(rows)` cells there is no other disc: the search is then the exhaustive one.
        for reach in 1..=columns.max(rows) {
            for j in 0..rows {
                let near_rows = near(j, rows, reach, !self.walls);
                for i in 0..columns {
                    let near_columns = near(i, columns, reach, false);
                    let a = j * columns + i;
                    for &jb in &near_rows {
                        for &ib in &near_columns {
                            // Each unordered pair once.
                            let b = jb * columns + ib;
                            if b > a {
                                gap = gap.min(pair(&discs[a], &discs[b]));
                                pairs += 1;
                            }
                        }
                    }
                }
            }
            // Every pair more than `reach` cells apart has a gap of at least this; less a relative 1e-9 for the
            // rounding of the computed gaps (~1e-16 relative), so that a near tie is searched, not assumed.
            let beyond = (reach + 1) as f64 * l - drift - self.diameter;
            if gap < beyond - 1e-9 * beyond.abs().max(l) {
                break;
            }
        }
        (gap, pairs)
    }
}

/// Result of a porous-slab run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PorousOutcome {
    /// The case run.
    pub case: PorousCase,
    /// Number of discs.
    pub discs: usize,
    /// Lattice size.
    pub size: (usize, usize),
    /// Porosity n of the array region.
    pub porosity: f64,
    /// Narrowest gap (nodes).
    pub min_gap: f64,
    /// Imposed gradient Δp/(nx − 1) (lattice pressure per node, p = ρ/3).
    pub imposed_gradient: f64,
    /// Mean pressure gradient inside the array (fit through whole-pitch column averages).
    pub interior_gradient: f64,
    /// Superficial velocity q, Σ (1 − ε) u_x over the array region / its area.
    pub superficial_velocity: f64,
    /// Permeability k = μ q / G_interior (lattice units, nodes²).
    pub permeability: f64,
    /// k/D².
    pub permeability_over_d2: f64,
    /// Kozeny constant implied by k ([`lbdem_reference::analytic::kozeny_constant`]).
    pub kozeny_constant: f64,
    /// For regular arrays: k l⁻² F̄_S&A − 1 (relative error against S&A, when c is tabulated).
    pub sangani_acrivos_error: Option<f64>,
    /// Re = q D/ν.
    pub reynolds: f64,
    /// Mean density of fully covered nodes minus that of uncovered array nodes, over the imposed density drop:
    /// the check on mass accumulating inside solids (Ω₁ in open systems; see the module docs).
    pub covered_density_excess: f64,
    /// Relative change of q per step when steadiness was declared (NaN if not steady).
    pub drift_per_step: f64,
    /// Steps taken.
    pub steps: u64,
    /// Whether the steady tolerance was met.
    pub steady: bool,
    /// Largest node Mach number.
    pub max_mach: f64,
    /// Wall-clock seconds (not in summaries or checkpoints: they are the same bytes whatever the machine).
    #[serde(skip)]
    pub wall_seconds: f64,
}

/// One porous slab in precision `T`, on its way to steady state.
#[derive(Serialize, Deserialize)]
#[serde(bound(serialize = "T: Serialize", deserialize = "T: DeserializeOwned"))]
pub struct PorousRun<T: Real> {
    lattice: FluidLattice<T>,
    eps: Vec<f64>,
    flow: SteadyFlow,
}

impl<T: Real> CaseRun for PorousRun<T> {
    type Case = PorousCase;
    type Outcome = PorousOutcome;
    type Float = T;

    /// The slab of `case`, starting from the linear pressure profile at rest.
    fn start(case: &PorousCase, exec: &Exec) -> Result<Self> {
        let (nx, ny) = case.size();
        let (rin, rout) = (1.0 + 0.5 * case.density_drop, 1.0 - 0.5 * case.density_drop);
        let ns = if case.walls {
            SideCondition::Wall
        } else {
            SideCondition::Periodic
        };
        let bc = Boundaries {
            west: SideCondition::Pressure {
                density: T::lit(rin),
            },
            east: SideCondition::Pressure {
                density: T::lit(rout),
            },
            south: ns,
            north: ns,
        };
        let params = FluidParams {
            tau: T::lit(case.tau),
            force: [T::zero(); 2],
        };
        let mut lattice = FluidLattice::new(nx, ny, bc, params)?;
        exec.apply(&mut lattice);
        lattice.set_collision(collision_of(case.collision)?)?;
        lattice.set_solid_operator(case.solid_operator);
        lattice.set_lambda_terms(case.lambda_terms)?;
        lattice.set_band_rows(ny.div_ceil(2).max(1));
        let discs = case.discs();
        lattice.cover_with_discs(&discs, case.solid_operator.weighting());
        let eps = lattice.solid_fraction_map();
        // Start from the linear pressure profile at rest (shortens the pressure-diffusion transient).
        lattice.fill_equilibrium(|x, _| {
            let t = x as f64 / (nx - 1) as f64;
            (T::lit(rin + (rout - rin) * t), [T::zero(); 2])
        });
        Ok(Self {
            lattice,
            eps,
            flow: SteadyFlow::new(
                Steadiness::new(case.steady_tolerance).accepting_drift(),
                case.check_interval,
                case.max_steps,
            ),
        })
    }

    /// One check interval towards steady state (superficial flux through the array); whether the case is over.
    fn advance(&mut self, case: &PorousCase) -> Result<bool> {
        let (nx, ny) = case.size();
        let (x_a, l) = (case.array_start(), case.pitch);
        let x_b = x_a + case.columns * l;
        let area = ((x_b - x_a) * ny) as f64;
        let eps = &self.eps;
        let flux = |lattice: &FluidLattice<T>| -> f64 {
            let (_, u) = lattice.moments();
            let mut q = 0.0;
            for y in 0..ny {
                for x in x_a..x_b {
                    let n = y * nx + x;
                    q += (1.0 - eps[n]) * u[n][0].to_f64_exact();
                }
            }
            q / area
        };
        self.flow.advance(&mut self.lattice, flux, DRIVE_HINT)
    }

    /// Permeability, Kozeny constant and the other figures of the steady flow.
    fn outcome(&self, case: &PorousCase) -> PorousOutcome {
        let lattice = &self.lattice;
        let eps = &self.eps;
        let q = self.flow.flux;
        let (nx, ny) = case.size();
        let (x_a, l) = (case.array_start(), case.pitch);
        let x_b = x_a + case.columns * l;
        let discs = case.discs();
        let (rho, u) = lattice.moments();
        // Fluid-averaged pressure of each pitch-wide column; the gradient is the slope through the interior ones.
        let mut columns = Vec::new();
        for k in 1..case.columns - 1 {
            let (mut pw, mut w) = (0.0, 0.0);
            for y in 0..ny {
                for x in x_a + k * l..x_a + (k + 1) * l {
                    let n = y * nx + x;
                    pw += cs2_times((1.0 - eps[n]) * rho[n].to_f64_exact());
                    w += 1.0 - eps[n];
                }
            }
            columns.push(((k * l) as f64, pw / w));
        }
        let (slope, _, _) = linear_fit(&columns);
        let (mut covered, mut nc, mut free, mut nf) = (0.0, 0.0, 0.0, 0.0);
        for y in 0..ny {
            for x in x_a..x_b {
                let n = y * nx + x;
                if eps[n] >= 1.0 {
                    covered += rho[n].to_f64_exact();
                    nc += 1.0;
                } else if eps[n] == 0.0 {
                    free += rho[n].to_f64_exact();
                    nf += 1.0;
                }
            }
        }
        let covered_density_excess = if nc > 0.0 && nf > 0.0 {
            (covered / nc - free / nf) / case.density_drop
        } else {
            0.0
        };
        let interior = -slope;
        let nu = case.viscosity();
        let k = permeability(nu, q, 1.0, interior);
        let n = case.porosity();
        let c = 1.0 - n;
        let reference = sangani_acrivos_tabulated(c);
        PorousOutcome {
            case: case.clone(),
            discs: discs.len(),
            size: (nx, ny),
            porosity: n,
            min_gap: case.min_gap(),
            imposed_gradient: cs2_times(case.density_drop) / (nx - 1) as f64,
            interior_gradient: interior,
            superficial_velocity: q,
            permeability: k,
            permeability_over_d2: k / (case.diameter * case.diameter),
            kozeny_constant: kozeny_constant(n, case.diameter, k),
            sangani_acrivos_error: reference
                .filter(|_| case.jitter == 0.0 && !case.walls)
                .map(|f| k / (l * l) as f64 * f - 1.0),
            reynolds: q * case.diameter / nu,
            covered_density_excess,
            drift_per_step: self.flow.drift_per_step,
            steps: lattice.steps(),
            steady: self.flow.steady,
            max_mach: max_mach(&u),
            wall_seconds: 0.0,
        }
    }

    fn lattice(&self) -> &FluidLattice<T> {
        &self.lattice
    }

    fn lattice_mut(&mut self) -> &mut FluidLattice<T> {
        &mut self.lattice
    }

    /// The discs and the slab (pressure 0 at the outlet density 1 − Δρ/2; model time steps × Δt).
    fn snapshot(&self, case: &PorousCase, at: &FixedSnapshots, index: usize) -> Result<()> {
        let h = at.units.spacing;
        let grains: Vec<_> = case.discs().iter().map(|d| disc_grain(d, h)).collect();
        let frame = LatticeFrame::of(&at.units, [0.0; 2], 1.0 - 0.5 * case.density_drop);
        let time = self.lattice.steps() as f64 * at.units.timestep;
        write_fixed(at, index, time, &grains, &self.lattice, &frame)
    }

    fn outcome_steps(o: &PorousOutcome) -> u64 {
        o.steps
    }

    fn report(case: &PorousCase, o: &PorousOutcome) -> String {
        format!(
            "D = {:.2} drho = {:.2e}: q = {:.4e}, k = {:.4e}, c_K = {:.2}, {} steps",
            case.diameter,
            case.density_drop,
            o.superficial_velocity,
            o.permeability,
            o.kozeny_constant,
            o.steps
        )
    }
}

/// Run one porous slab to steady state.
pub fn solve_porous<T: Real>(case: &PorousCase) -> Result<PorousOutcome> {
    let (mut outcome, seconds) = solve::<PorousRun<T>>(case, &Exec::default())?;
    outcome.wall_seconds = seconds;
    Ok(outcome)
}

/// Darcy fit of flux against imposed gradient: (slope, intercept, R², intercept relative to the largest flux).
pub fn darcy_fit(runs: &[PorousOutcome]) -> (f64, f64, f64, f64) {
    let pts: Vec<(f64, f64)> = runs
        .iter()
        .map(|r| (r.imposed_gradient, r.superficial_velocity))
        .collect();
    let (a, b, r2) = linear_fit(&pts);
    let qmax = pts.iter().map(|p| p.1.abs()).fold(0.0, f64::max);
    (a, b, r2, b / qmax)
}

/// Least-squares Kozeny constant over several runs: ln k = ln(n³D²/(16(1 − n)²)) − ln c_K fitted in the log,
/// which makes the fitted c_K the geometric mean of the per-run constants.
pub fn fitted_kozeny_constant(runs: &[PorousOutcome]) -> f64 {
    let m = runs.len() as f64;
    (runs.iter().map(|r| r.kozeny_constant.ln()).sum::<f64>() / m).exp()
}

/// North/south sides of a porous slab.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum NorthSouth {
    /// Periodic.
    #[default]
    Periodic,
    /// Half-way bounce-back walls.
    Walls,
}

/// `[porous]`: discs on a square lattice between Zou–He pressure boundaries (kind = "porous_flow").
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PorousSection {
    /// Disc columns along the flow (x), at least 4.
    pub columns: usize,
    /// Disc rows across the flow (y), at least 1.
    pub rows: usize,
    /// Pitch of the disc lattice (length; a whole number of spacings).
    pub pitch: f64,
    /// Disc diameters to run (length, each below the pitch).
    pub diameters: Vec<f64>,
    /// Pressure drops from west to east to run (pressure units).
    pub pressure_drops: Vec<f64>,
    /// Free fluid between each pressure boundary and the array (length, default one pitch).
    #[serde(default)]
    pub buffer: Option<f64>,
    /// Random displacement of each disc as a fraction of the half-gap, in [0, 1) (default 0).
    #[serde(default)]
    pub jitter: f64,
    /// Seed of the jitter (default 1).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// North/south sides (default "periodic").
    #[serde(default)]
    pub north_south: NorthSouth,
    /// Solid operator (default "lambda_consistent", ΩΛ with B = ε; see the module docs on open systems).
    #[serde(default = "default_operator")]
    pub solid_operator: SolidOperator,
}

fn default_seed() -> u64 {
    1
}

/// A porous-flow scene file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PorousFlowScene {
    /// `[scene]`
    pub scene: SceneHeader,
    /// `[fluid]`
    pub fluid: FluidSection,
    /// `[porous]`
    #[serde(default)]
    pub porous: Option<PorousSection>,
    /// `[run]`
    pub run: RunSection,
}

crate::scene::scene_file!(PorousFlowScene);

/// Everything derived from a porous-flow scene.
#[derive(Clone, Debug, Serialize)]
pub struct PorousSetup {
    /// Unit conversion.
    pub units: LatticeUnits,
    /// Cases in lattice units (every diameter with every pressure drop).
    pub cases: Vec<PorousCase>,
    /// The narrowest gap of each case ([`PorousCase::min_gap`], nodes), measured once per diameter.
    #[serde(skip)]
    pub narrowest_gaps: Vec<f64>,
    /// Warnings.
    pub warnings: Warnings,
}

impl crate::run::Derived for PorousSetup {
    fn warnings(&self) -> &[String] {
        &self.warnings.0
    }
}

impl PorousSetup {
    /// The memory of the largest case (cases run one after the other).
    fn budget(&self, precision: Precision) -> Result<Budget> {
        let mut b = Budget::new();
        if let Some(c) = self.cases.first() {
            let (nx, ny) = c.size();
            limits::lattice(
                &mut b,
                "porous.columns",
                "lattice",
                nx as u64,
                ny as u64,
                precision.float_bytes(),
                limits::Solids::Covered,
            )?;
            b.add_items(
                "discs",
                "porous.rows",
                (c.columns as u64).saturating_mul(c.rows as u64),
                std::mem::size_of::<FluidDisc>() as u64,
            )?;
        }
        Ok(b)
    }

    /// Derive the lattice cases from a scene.
    pub fn new(scene: &PorousFlowScene) -> Result<Self> {
        PorousFlow::validate(scene)?;
        let units = scene.fluid.lattice_units()?;
        let p = scene.porous.as_ref().ok_or_else(|| {
            LbdemError::field(
                "porous",
                "missing",
                "the scene needs a [porous] section",
                "add it",
            )
        })?;
        let h = units.spacing;
        let pitch = whole_spacings("porous.pitch", p.pitch, h)?;
        let buffer = whole_spacings("porous.buffer", p.buffer.unwrap_or(p.pitch), h)?;
        // Every size in checked arithmetic before anything is built (the discs of `min_gap` included).
        limits::cases(
            "porous.pressure_drops",
            limits::mul(
                "porous.pressure_drops",
                "the case count",
                p.diameters.len() as u64,
                p.pressure_drops.len() as u64,
            )?,
        )?;
        let discs = limits::mul(
            "porous.columns",
            "the disc count",
            p.columns as u64,
            p.rows as u64,
        )?;
        if discs > MAX_DISCS {
            return Err(LbdemError::field(
                "porous.columns",
                format!("{} x {} (porous.rows)", p.columns, p.rows),
                &format!("gives {discs} discs, above the limit of {MAX_DISCS} per slab"),
                "use fewer columns or rows (the validation's slabs hold tens of discs)",
            ));
        }
        let (nx, ny) = lattice_size(p.columns as u64, p.rows as u64, pitch as u64, buffer as u64)?;
        let mut probe = Budget::new();
        limits::lattice(
            &mut probe,
            "porous.columns",
            "lattice",
            nx,
            ny,
            8,
            limits::Solids::Covered,
        )?;
        let mut warnings = Warnings::default();
        check_tau(&units, &mut warnings);
        let mut cases = Vec::new();
        let mut narrowest_gaps = Vec::new();
        for &d in &p.diameters {
            // The discs, and so the narrowest gap, are the same for every pressure drop.
            let mut gap = None;
            for &dp in &p.pressure_drops {
                let drho = units.pressure_to_density_change(dp);
                check_density_drop("porous.pressure_drops", drho, &mut warnings)?;
                let case = PorousCase {
                    columns: p.columns,
                    rows: p.rows,
                    pitch,
                    diameter: d / h,
                    buffer,
                    jitter: p.jitter,
                    seed: p.seed,
                    walls: p.north_south == NorthSouth::Walls,
                    tau: units.tau,
                    solid_operator: p.solid_operator,
                    lambda_terms: scene.fluid.lambda_terms(p.solid_operator)?,
                    collision: scene.fluid.checked_collision(COLLISION, units.tau)?,
                    density_drop: drho,
                    steady_tolerance: scene.run.steady_tolerance.unwrap_or(1e-8),
                    check_interval: scene.run.check_interval.unwrap_or(200),
                    max_steps: scene.run.step_count(units.timestep)?,
                };
                let gap = *gap.get_or_insert_with(|| case.min_gap());
                narrowest_gaps.push(gap);
                if gap < 5.0 {
                    warnings.push(format!(
                        "diameter {d}: narrowest gap {gap:.1} nodes < 5 (the dissertation's minimum per pore \
                         throat; the drag of a cylinder array is ~5 % off at 5 nodes per gap, measured in `driver/tests/porous.rs`)"
                    ));
                }
                cases.push(case);
            }
        }
        Ok(Self {
            units,
            cases,
            narrowest_gaps,
            warnings,
        })
    }
}

/// What the run checkpoints: the cases in the scene's precision.
pub type PorousState = Sweep<PorousRun<f32>, PorousRun<f64>>;

fn runs_csv(outcomes: &[PorousOutcome], spacing: f64) -> String {
    csv(
        &[
            "diameter_nodes",
            "porosity",
            "min_gap_nodes",
            "density_drop",
            "imposed_gradient",
            "interior_gradient",
            "superficial_velocity",
            "permeability_nodes2",
            "permeability_physical",
            "k_over_d2",
            "kozeny_constant",
            "reynolds",
            "steps",
        ],
        outcomes.iter().map(|r| {
            vec![
                r.case.diameter,
                r.porosity,
                r.min_gap,
                r.case.density_drop,
                r.imposed_gradient,
                r.interior_gradient,
                r.superficial_velocity,
                r.permeability,
                r.permeability * spacing * spacing,
                r.permeability_over_d2,
                r.kozeny_constant,
                r.reynolds,
                r.steps as f64,
            ]
        }),
    )
}

/// The porous-flow kind.
pub struct PorousFlow;

impl Kind for PorousFlow {
    const NAME: &'static str = "porous_flow";
    const OWN_SECTION: Option<&'static str> = Some("porous");
    const NOT_MEASURED: &'static [&'static str] = &[
        "drift_per_step",
        "sangani_acrivos_error",
        "fitted_kozeny_constant",
    ];
    type Scene = PorousFlowScene;
    type Setup = PorousSetup;
    type State = PorousState;

    fn validate(scene: &PorousFlowScene) -> Result<()> {
        scene.fluid.validate()?;
        scene.run.validate()?;
        let p = scene.porous.as_ref().ok_or_else(|| {
            LbdemError::field(
                "porous",
                "missing",
                "scene.kind = \"porous_flow\" needs a [porous] section",
                "add [porous] with columns, rows, pitch, diameters and pressure_drops",
            )
        })?;
        if p.columns < 4 {
            return Err(LbdemError::field(
                "porous.columns",
                p.columns,
                "must be at least 4 (the interior gradient is fitted without the first and last column)",
                "use 4 or more columns",
            ));
        }
        if p.rows < 1 {
            return Err(LbdemError::field(
                "porous.rows",
                p.rows,
                "must be at least 1",
                "use 1 or more rows",
            ));
        }
        if !(p.pitch.is_finite() && p.pitch > 0.0) {
            return Err(LbdemError::field(
                "porous.pitch",
                p.pitch,
                "must be > 0",
                "give the disc spacing",
            ));
        }
        if p.diameters.is_empty() || p.diameters.iter().any(|d| !(*d > 0.0 && *d < p.pitch)) {
            return Err(LbdemError::field(
                "porous.diameters",
                format!("{:?}", p.diameters),
                "must be a non-empty list of diameters in (0, pitch)",
                "discs must not touch; e.g. diameters = [0.8 * pitch]",
            ));
        }
        if p.pressure_drops.is_empty()
            || p.pressure_drops
                .iter()
                .any(|d| !(d.is_finite() && *d > 0.0))
        {
            return Err(LbdemError::field(
                "porous.pressure_drops",
                format!("{:?}", p.pressure_drops),
                "must be a non-empty list of pressure drops > 0",
                "e.g. pressure_drops = [0.1, 0.2, 0.3]",
            ));
        }
        if !(p.jitter >= 0.0 && p.jitter < 1.0) {
            return Err(LbdemError::field(
                "porous.jitter",
                p.jitter,
                "must lie in [0, 1) (a fraction of the half-gap, so discs never touch)",
                "use 0 for a regular lattice, e.g. 0.5 for a disordered one",
            ));
        }
        if let Some(b) = p.buffer {
            if !(b.is_finite() && b > 0.0) {
                return Err(LbdemError::field(
                    "porous.buffer",
                    b,
                    "must be > 0",
                    "e.g. one pitch",
                ));
            }
        }
        Ok(())
    }

    fn setup(scene: &PorousFlowScene) -> Result<PorousSetup> {
        PorousSetup::new(scene)
    }

    fn budget(scene: &PorousFlowScene, setup: &PorousSetup) -> Result<Budget> {
        setup.budget(scene.scene.precision)
    }

    fn describe(case: &Case<Self>) -> String {
        let u = &case.setup.units;
        let mut s = u.brief();
        for (c, gap) in case.setup.cases.iter().zip(&case.setup.narrowest_gaps) {
            let (nx, ny) = c.size();
            s += &format!(
                "  {nx} x {ny} nodes, {} discs, D = {:.2}, n = {:.3}, narrowest gap {:.2}, density drop {:.3e}\n",
                c.columns * c.rows,
                c.diameter,
                c.porosity(),
                gap,
                c.density_drop
            );
        }
        s
    }

    crate::run::cases::sweep_kind_methods!();

    fn write_outputs(
        case: &Case<Self>,
        state: &PorousState,
        dir: &Path,
        _stage: OutputStage,
    ) -> Result<()> {
        // Periodic checkpoints flush the tables too, so that a killed run keeps its records so far.
        let table = runs_csv(state.done(), case.setup.units.spacing);
        write_atomic(&dir.join("runs.csv"), table.as_bytes())
    }

    fn results(case: &Case<Self>, state: &PorousState) -> Result<serde_json::Value> {
        let results = state.done();
        // Darcy fit per diameter (when it has ≥ 2 pressure drops); Kozeny fit over one run per diameter.
        let mut darcy = Vec::new();
        let mut per_diameter = Vec::new();
        let m = case
            .scene
            .porous
            .as_ref()
            .map_or(1, |p| p.pressure_drops.len())
            .max(1);
        for chunk in results.chunks(m) {
            per_diameter.push(chunk[0].clone());
            if m >= 2 && chunk.len() == m {
                let (slope, intercept, r2, rel) = darcy_fit(chunk);
                darcy.push(json!({
                    "diameter_nodes": chunk[0].case.diameter,
                    "slope": slope,
                    "intercept": intercept,
                    "intercept_relative": rel,
                    "r_squared": r2,
                }));
            }
        }
        let kc = if per_diameter.is_empty() {
            f64::NAN
        } else {
            fitted_kozeny_constant(&per_diameter)
        };
        Ok(json!({
            "cases": results,
            "darcy_fits": darcy,
            "fitted_kozeny_constant": kc,
            "all_steady": results.iter().all(|r| r.steady),
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jittered_discs_keep_their_cells_and_are_seeded() {
        let case = PorousCase {
            columns: 5,
            rows: 4,
            pitch: 20,
            diameter: 12.0,
            buffer: 5,
            jitter: 0.9,
            seed: 7,
            walls: false,
            tau: 0.8,
            solid_operator: SolidOperator::NonEquilibriumBounceBack,
            lambda_terms: LambdaTerms::default(),
            collision: Collision::Bgk,
            density_drop: 1e-3,
            steady_tolerance: 1e-8,
            check_interval: 100,
            max_steps: 10,
        };
        let a = case.discs();
        assert_eq!(a.len(), 20);
        let b = case.discs();
        assert!(a.iter().zip(b.iter()).all(|(p, q)| p.center == q.center));
        // Jitter ≤ 0.9 half-gap per axis: the narrowest gap is at least 0.1 (l − D) = 0.8 nodes.
        assert!(case.min_gap() >= 0.1 * 8.0 - 1e-12);
        let regular = PorousCase {
            jitter: 0.0,
            ..case
        };
        assert!((regular.min_gap() - 8.0).abs() < 1e-12);
    }
}
