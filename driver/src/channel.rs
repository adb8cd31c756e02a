//! Plane Poiseuille flow between half-way bounce-back walls (dissertation §4.5, fig. 4.4–4.7): driven by
//! Zou–He pressure boundaries at the inlet (west) and outlet (east), or by a uniform body force with periodic
//! ends. The steady solution is compared with the analytical parabola u(y) = G/(2μ) y (H − y), G the pressure
//! gradient (or ρ₀ g), μ = ρ₀ ν, H the distance between the walls.
//!
//! Geometry: the walls lie half a spacing outside the first and last row, so `ny` rows give H = ny·h and row j
//! sits at y = (j + ½) h. Pressure drive: Zou–He nodes at x = 0 and x = nx − 1, so the pressure drop acts over
//! L = (nx − 1) h; the inlet and outlet densities are 1 ± Δρ/2 with Δρ = 3 Δp/(ρ₀ c²).
use std::time::Instant;

use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::Real;
use serde::Serialize;

use crate::error::{LbdemError, Result};
use crate::lattice::FluidLattice;
use crate::scene::{ChannelDrive, ChannelSection, Scene};
use crate::units::{check_density_drop, check_mach, check_tau, LatticeUnits, Warnings};

/// Everything derived from a channel scene before running it.
#[derive(Clone, Debug, Serialize)]
pub struct ChannelSetup {
    /// Unit conversion.
    pub units: LatticeUnits,
    /// Nodes along x.
    pub nx: usize,
    /// Nodes across the channel (= H/h).
    pub ny: usize,
    /// Pressure gradient G driving the flow (physical).
    pub pressure_gradient: f64,
    /// Lattice inlet and outlet densities (pressure drive).
    pub densities: Option<[f64; 2]>,
    /// Lattice body-force density (body-force drive).
    pub lattice_force: Option<f64>,
    /// Analytical centreline speed G H²/(8 μ) (physical).
    pub max_velocity: f64,
    /// Expected Mach number u_max / c_s.
    pub mach: f64,
    /// Channel Reynolds number u_mean H / ν.
    pub reynolds: f64,
    /// Relative density drop along the channel.
    pub density_drop: f64,
    /// Viscous diffusion time across the channel H²/ν, in steps.
    pub diffusion_steps: f64,
    /// Steps to run (upper bound when a steady tolerance is set).
    pub steps: u64,
    /// Warnings about the settings.
    pub warnings: Warnings,
}

fn nodes_for(field: &str, length: f64, h: f64) -> Result<usize> {
    let n = (length / h).round();
    if n < 1.0 || (n * h - length).abs() > 0.01 * h {
        return Err(LbdemError::field(
            field,
            length,
            &format!(
                "is not a whole number of lattice spacings (length/h = {:.4})",
                length / h
            ),
            &format!(
                "use a multiple of fluid.spacing = {h}, e.g. {}",
                n.max(1.0) * h
            ),
        ));
    }
    Ok(n as usize)
}

impl ChannelSetup {
    /// Derive the lattice set-up of a channel scene, checking stability limits.
    pub fn new(scene: &Scene) -> Result<Self> {
        scene.validate()?;
        let units = LatticeUnits::from_fluid(&scene.fluid)?;
        let c: &ChannelSection = scene.channel.as_ref().expect("validated");
        let h = units.spacing;
        let ny = nodes_for("channel.width", c.width, h)?;
        let mut warnings = Warnings::default();
        check_tau(&units, &mut warnings);
        let mu = units.density * units.viscosity;
        let width = ny as f64 * h;
        let (nx, gradient, densities, force, drop) = match c.drive {
            ChannelDrive::Pressure => {
                let nx = nodes_for("channel.length", c.length, h)? + 1;
                if nx < 3 {
                    return Err(LbdemError::field(
                        "channel.length",
                        c.length,
                        "a pressure-driven channel needs at least 2 spacings between inlet and outlet",
                        "make the channel longer or refine fluid.spacing",
                    ));
                }
                let dp = c.pressure_drop.expect("validated");
                let drho = 3.0 * units.pressure_to_lattice(dp);
                let drop = drho;
                check_density_drop("channel.pressure_drop", drop, &mut warnings)?;
                let length = (nx - 1) as f64 * h;
                (
                    nx,
                    dp / length,
                    Some([1.0 + 0.5 * drho, 1.0 - 0.5 * drho]),
                    None,
                    drop,
                )
            }
            ChannelDrive::BodyForce => {
                let nx = nodes_for("channel.length", c.length, h)?;
                let g = c.acceleration.expect("validated");
                (
                    nx,
                    units.density * g,
                    None,
                    Some(units.acceleration_to_lattice(g)),
                    0.0,
                )
            }
        };
        let umax = gradient * width * width / (8.0 * mu);
        let mach = units.mach(umax);
        check_mach(mach, scene.run.allow_high_mach, &mut warnings)?;
        if ny < 3 {
            warnings.push(format!(
                "only {ny} node(s) across the channel: the half-way bounce-back error (16(tau-1/2)^2-3)/(3H^2) \
                 is large; the dissertation recommends at least 4-5 nodes per pore throat"
            ));
        }
        if let (crate::scene::Precision::F32, Some(tol)) =
            (scene.scene.precision, scene.run.steady_tolerance)
        {
            if tol < 1e-6 {
                warnings.push(format!(
                    "run.steady_tolerance = {tol:e} is below what f32 resolves (~1e-6 relative flux change): \
                     steadiness will not be detected and all steps will run; use precision = \"f64\" or a \
                     tolerance >= 1e-6"
                ));
            }
        }
        let steps = match (scene.run.steps, scene.run.duration) {
            (Some(s), _) => s,
            (None, Some(d)) => (d / units.timestep).ceil().max(1.0) as u64,
            _ => unreachable!("validated"),
        };
        Ok(Self {
            units,
            nx,
            ny,
            pressure_gradient: gradient,
            densities,
            lattice_force: force,
            max_velocity: umax,
            mach,
            reynolds: (2.0 / 3.0) * umax * width / units.viscosity,
            density_drop: drop,
            diffusion_steps: (ny as f64).powi(2) / units.lattice_viscosity,
            steps,
            warnings,
        })
    }

    /// Analytical velocity (physical) at row j.
    pub fn analytic_velocity(&self, j: usize) -> f64 {
        let h = self.units.spacing;
        let width = self.ny as f64 * h;
        let y = (j as f64 + 0.5) * h;
        let mu = self.units.density * self.units.viscosity;
        self.pressure_gradient / (2.0 * mu) * y * (width - y)
    }

    /// Human-readable table of the derived parameters.
    pub fn describe(&self, labels: crate::scene::UnitLabels) -> String {
        let u = &self.units;
        let mut s = String::new();
        s += &format!(
            "  lattice            {} x {} nodes ({} nodes across the channel)\n",
            self.nx, self.ny, self.ny
        );
        s += &format!("  spacing h          {:.6e} {}\n", u.spacing, labels.length);
        s += &format!("  time step dt       {:.6e} {}\n", u.timestep, labels.time);
        s += &format!("  tau                {:.6}\n", u.tau);
        s += &format!("  lattice viscosity  {:.6}\n", u.lattice_viscosity);
        s += &format!(
            "  lattice speed h/dt {:.6e} {}\n",
            u.lattice_speed, labels.velocity
        );
        s += &format!(
            "  sound speed c_s    {:.6e} {}\n",
            u.sound_speed, labels.velocity
        );
        s += &format!(
            "  compressibility    {:.6e} 1/({})\n",
            u.compressibility, labels.pressure
        );
        s += &format!(
            "  pressure gradient  {:.6e} {}/{}\n",
            self.pressure_gradient, labels.pressure, labels.length
        );
        s += &format!(
            "  max velocity       {:.6e} {} (analytical)\n",
            self.max_velocity, labels.velocity
        );
        s += &format!("  expected Mach      {:.4}\n", self.mach);
        s += &format!("  Reynolds (mean,H)  {:.4}\n", self.reynolds);
        s += &format!("  density drop       {:.4} %\n", 100.0 * self.density_drop);
        s += &format!(
            "  diffusion time     {:.0} steps (H^2/nu)\n",
            self.diffusion_steps
        );
        s += &format!("  steps              {}\n", self.steps);
        s
    }
}

/// Result of a channel run.
#[derive(Clone, Debug, Serialize)]
pub struct ChannelOutcome {
    /// Steps taken.
    pub steps: u64,
    /// Whether the steady tolerance was met.
    pub steady: bool,
    /// Wall-clock seconds of the stepping loop.
    pub wall_seconds: f64,
    /// Million lattice-node updates per second.
    pub mlups: f64,
    /// y (physical), simulated u, analytical u (physical), lattice density, at the mid cross-section.
    pub profile: Vec<[f64; 4]>,
    /// Relative L2 error of the velocity profile against the analytical parabola.
    pub l2_error: f64,
    /// Relative error of the flux through the mid cross-section, Σ_j u_j against Σ_j u_analytical(y_j) (the
    /// sampled analytical profile, so the midpoint-quadrature error of Σ u h against G H³/(12 μ), which is
    /// h²/(2H²), does not pollute the comparison).
    pub flux_error: f64,
    /// Relative error of the velocity on the middle row (j = ny/2) against the analytical value there.
    pub centre_velocity_error: f64,
    /// Largest measured Mach number.
    pub measured_mach: f64,
    /// Relative change of total mass over the run (periodic drive: roundoff only).
    pub mass_change: f64,
}

/// Build the lattice of a channel set-up.
pub fn build_lattice<T: Real>(setup: &ChannelSetup) -> Result<FluidLattice<T>> {
    let (bc, force) = match (setup.densities, setup.lattice_force) {
        (Some([rin, rout]), _) => (
            Boundaries {
                west: SideCondition::Pressure {
                    density: T::lit(rin),
                },
                east: SideCondition::Pressure {
                    density: T::lit(rout),
                },
                south: SideCondition::Wall,
                north: SideCondition::Wall,
            },
            [T::zero(); 2],
        ),
        (None, Some(g)) => (
            Boundaries {
                west: SideCondition::Periodic,
                east: SideCondition::Periodic,
                south: SideCondition::Wall,
                north: SideCondition::Wall,
            },
            [T::lit(g), T::zero()],
        ),
        _ => unreachable!("a channel is driven by pressure or body force"),
    };
    let params = FluidParams {
        tau: T::lit(setup.units.tau),
        force,
    };
    let mut lattice = FluidLattice::new(setup.nx, setup.ny, bc, params)?;
    if let Some([rin, rout]) = setup.densities {
        // Start from the linear pressure profile at rest: shortens the acoustic transient.
        let nx = setup.nx;
        lattice.fill_equilibrium(|x, _| {
            let t = if nx > 1 {
                x as f64 / (nx - 1) as f64
            } else {
                0.0
            };
            (T::lit(rin + (rout - rin) * t), [T::zero(); 2])
        });
    }
    Ok(lattice)
}

/// Mid cross-section flux (lattice units) for steadiness checks.
fn mid_flux<T: Real>(lattice: &FluidLattice<T>) -> f64 {
    let (_, u) = lattice.moments();
    let s = lattice.shape();
    let x = s.nx / 2;
    (0..s.ny).map(|y| u[s.index(x, y)][0].to_f64_exact()).sum()
}

/// Run a channel set-up; `progress(step)` is called every check interval. `out_dir` only names the place in
/// error messages.
pub fn run_channel<T: Real>(
    setup: &ChannelSetup,
    steady_tolerance: Option<f64>,
    check_interval: u64,
    out_dir: &str,
    mut progress: impl FnMut(u64),
) -> Result<ChannelOutcome> {
    let mut lattice = build_lattice::<T>(setup)?;
    let mass0 = lattice.mass();
    let start = Instant::now();
    let mut last_flux = f64::NAN;
    let mut steady = false;
    let interval = check_interval.max(1);
    while lattice.steps() < setup.steps {
        let todo = interval.min(setup.steps - lattice.steps());
        for _ in 0..todo {
            lattice.step();
        }
        progress(lattice.steps());
        if let Some((n, rho)) = lattice.health_check(0.5, 1.5) {
            let (x, y) = lattice.shape().coords(n);
            return Err(LbdemError::Diverged {
                step: lattice.steps(),
                quantity: "lattice density".into(),
                value: format!("{rho}"),
                x,
                y,
                out: out_dir.to_string(),
                hint: "raise tau, lower the driving pressure/acceleration, or refine the time step"
                    .into(),
            });
        }
        let flux = mid_flux(&lattice);
        if let Some(tol) = steady_tolerance {
            if last_flux.is_finite() && ((flux - last_flux) / flux).abs() < tol {
                steady = true;
                break;
            }
        }
        last_flux = flux;
    }
    let wall = start.elapsed().as_secs_f64();
    let (rho, u) = lattice.moments();
    let s = *lattice.shape();
    let xm = s.nx / 2;
    let units = &setup.units;
    let mut profile = Vec::with_capacity(s.ny);
    let (mut num, mut den, mut flux, mut flux_analytic) = (0.0, 0.0, 0.0, 0.0);
    let mut measured_mach: f64 = 0.0;
    for y in 0..s.ny {
        let n = s.index(xm, y);
        let us = units.velocity_to_physical(u[n][0].to_f64_exact());
        let ua = setup.analytic_velocity(y);
        num += (us - ua).powi(2);
        den += ua * ua;
        flux += us;
        flux_analytic += ua;
        profile.push([
            (y as f64 + 0.5) * units.spacing,
            us,
            ua,
            rho[n].to_f64_exact(),
        ]);
    }
    for v in &u {
        let speed = (v[0].to_f64_exact().powi(2) + v[1].to_f64_exact().powi(2)).sqrt();
        measured_mach = measured_mach.max(speed * 3f64.sqrt());
    }
    let nodes = (s.nx * s.ny) as f64;
    let centre_error = {
        let [_, us, ua, _] = profile[s.ny / 2];
        (us - ua) / ua
    };
    Ok(ChannelOutcome {
        steps: lattice.steps(),
        steady,
        wall_seconds: wall,
        mlups: nodes * lattice.steps() as f64 / wall.max(1e-12) / 1e6,
        profile,
        l2_error: (num / den).sqrt(),
        flux_error: (flux - flux_analytic) / flux_analytic,
        centre_velocity_error: centre_error,
        measured_mach,
        mass_change: (lattice.mass() - mass0) / mass0,
    })
}
