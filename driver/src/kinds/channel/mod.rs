//! Plane Poiseuille flow between half-way bounce-back walls (dissertation §4.5, fig. 4.4–4.7): driven by
//! Zou–He pressure boundaries at the inlet (west) and outlet (east), or by a uniform body force with periodic
//! ends. The steady solution is compared with the analytical parabola u(y) = G/(2μ) y (H − y), G the pressure
//! gradient (or ρ₀ g), μ = ρ₀ ν, H the distance between the walls.
//!
//! Geometry: the walls lie half a spacing outside the first and last row, so `ny` rows give H = ny·h and row j
//! sits at y = (j + ½) h. Pressure drive: Zou–He nodes at x = 0 and x = nx − 1, so the pressure drop acts over
//! L = (nx − 1) h; the inlet and outlet densities are 1 ± Δρ/2 with Δρ = 3 Δp/(ρ₀ c²).
use std::path::Path;
use std::time::Instant;

use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::Collision;
use lbdem_kernels::fluid::step::FluidParams;
use lbdem_kernels::Real;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::engine::exec::{Exec, ExecTarget};
use crate::engine::lattice::FluidLattice;
use crate::error::{positive, LbdemError, Result};
use crate::input::limits::{self, Budget};
use crate::observe::flow::max_mach;
use crate::observe::health::fluid_health;
use crate::observe::steady::Steadiness;
use crate::output::{csv, write_atomic};
use crate::run::{run_in_memory, Case, Kind, OutputStage, Persist, RunOptions};
use crate::scene::{Precision, RunSection, SceneHeader, UnitLabels};
use crate::units::{
    check_density_drop, check_mach, check_tau, collision_of, CollisionName, FluidSection,
    LatticeUnits, Warnings,
};

/// The fluid collision of channel scenes without `[fluid] collision` (no solids: BGK, the dissertation's).
pub const COLLISION: CollisionName = CollisionName::Bgk;

/// How a channel flow is driven.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ChannelDrive {
    /// Zou–He pressure inlet (west) and outlet (east).
    Pressure,
    /// Uniform body force (acceleration) along x, periodic along x.
    BodyForce,
}

/// `[channel]`: plane Poiseuille flow.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelSection {
    /// Length along x.
    pub length: f64,
    /// Width between the walls.
    pub width: f64,
    /// Drive.
    pub drive: ChannelDrive,
    /// Pressure drop over the length (drive = "pressure").
    #[serde(default)]
    pub pressure_drop: Option<f64>,
    /// Acceleration along x (drive = "body_force").
    #[serde(default)]
    pub acceleration: Option<f64>,
}

/// A channel scene file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelScene {
    /// `[scene]`
    pub scene: SceneHeader,
    /// `[fluid]`
    pub fluid: FluidSection,
    /// `[channel]`
    #[serde(default)]
    pub channel: Option<ChannelSection>,
    /// `[run]`
    pub run: RunSection,
}

crate::scene::scene_file!(ChannelScene);

impl ChannelScene {
    /// Parse a channel scene from TOML text (`path` for messages; ranges are checked by [`ChannelSetup::new`]).
    pub fn from_toml(text: &str, path: &str) -> Result<Self> {
        crate::scene::parse_scene(text, path)
    }
}

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
    /// Fluid collision (`[fluid] collision`, default [`COLLISION`]).
    pub collision: Collision<f64>,
}

impl crate::run::Derived for ChannelSetup {
    fn warnings(&self) -> &[String] {
        &self.warnings.0
    }
}

fn nodes_for(field: &str, length: f64, h: f64) -> Result<usize> {
    let n = (length / h).round();
    if n > crate::input::limits::MAX_SIDE as f64 {
        return Err(crate::input::limits::side_too_long(field, length, n));
    }
    if n.is_nan() || n < 1.0 || (n * h - length).abs() > 0.01 * h {
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
    pub fn new(scene: &ChannelScene) -> Result<Self> {
        Channel::validate(scene)?;
        let units = scene.fluid.lattice_units()?;
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
                let drho = units.pressure_to_density_change(dp);
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
        let driving = match c.drive {
            ChannelDrive::Pressure => "channel.pressure_drop",
            ChannelDrive::BodyForce => "channel.acceleration",
        };
        check_mach(
            driving,
            mach,
            Some(scene.run.allow_high_mach),
            &mut warnings,
        )?;
        if ny < 3 {
            warnings.push(format!(
                "only {ny} node(s) across the channel: the half-way bounce-back error (16(tau-1/2)^2-3)/(3H^2) \
                 is large; the dissertation recommends at least 4-5 nodes per pore throat"
            ));
        }
        if let (Precision::F32, Some(tol)) = (scene.scene.precision, scene.run.steady_tolerance) {
            if tol < 1e-6 {
                warnings.push(format!(
                    "run.steady_tolerance = {tol:e} is below what f32 resolves (~1e-6 relative flux change): \
                     steadiness will not be detected and all steps will run; use precision = \"f64\" or a \
                     tolerance >= 1e-6"
                ));
            }
        }
        let steps = scene.run.step_count(units.timestep)?;
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
            collision: scene.fluid.checked_collision(COLLISION, units.tau)?,
        })
    }

    /// Analytical velocity (physical) at row j.
    pub fn analytic_velocity(&self, j: usize) -> f64 {
        let h = self.units.spacing;
        let width = self.ny as f64 * h;
        let y = (j as f64 + 0.5) * h;
        let mu = self.units.density * self.units.viscosity;
        lbdem_reference::analytic::poiseuille_velocity(self.pressure_gradient, mu, width, y)
    }

    /// Human-readable table of the derived parameters.
    pub fn describe(&self, labels: UnitLabels) -> String {
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
    /// Lattice nodes.
    pub nodes: f64,
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
        // A pressure drive has densities, a body-force drive a force (ChannelSetup::new).
        _ => (Boundaries::periodic(), [T::zero(); 2]),
    };
    let params = FluidParams {
        tau: T::lit(setup.units.tau),
        force,
    };
    let mut lattice = FluidLattice::new(setup.nx, setup.ny, bc, params)?;
    lattice.set_collision(collision_of(setup.collision)?)?;
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

/// A channel run in precision `T`.
#[derive(Serialize, Deserialize)]
#[serde(bound(serialize = "T: Serialize", deserialize = "T: DeserializeOwned"))]
pub struct ChannelRun<T: Real> {
    lattice: FluidLattice<T>,
    criterion: Steadiness,
    steady: bool,
    mass0: f64,
}

/// What a channel run checkpoints: the run in the scene's precision.
#[derive(Serialize, Deserialize)]
pub enum ChannelState {
    /// precision = "f32".
    F32(ChannelRun<f32>),
    /// precision = "f64".
    F64(ChannelRun<f64>),
}

impl Persist for ChannelState {
    const PRECISION: u8 = 0;
    fn precision(&self) -> u8 {
        match self {
            ChannelState::F32(_) => 4,
            ChannelState::F64(_) => 8,
        }
    }
}

macro_rules! each {
    ($state:expr, $r:ident => $body:expr) => {
        match $state {
            ChannelState::F32($r) => $body,
            ChannelState::F64($r) => $body,
        }
    };
}

impl<T: Real> ChannelRun<T> {
    fn new(case: &Case<Channel>, exec: &Exec) -> Result<Self> {
        let mut lattice = build_lattice::<T>(&case.setup)?;
        exec.apply(&mut lattice);
        let mass0 = lattice.mass();
        Ok(Self {
            lattice,
            criterion: Steadiness::new(case.scene.run.steady_tolerance.unwrap_or(0.0)),
            steady: false,
            mass0,
        })
    }

    fn finished(&self, setup: &ChannelSetup) -> bool {
        self.steady || self.lattice.steps() >= setup.steps
    }

    /// One check interval: step, then (with a tolerance) test steadiness of the mid cross-section flux.
    fn advance(&mut self, case: &Case<Channel>) {
        let interval = case.scene.run.check_interval.unwrap_or(200).max(1);
        let todo = interval.min(case.setup.steps - self.lattice.steps());
        for _ in 0..todo {
            self.lattice.step();
        }
        if case.scene.run.steady_tolerance.is_some()
            && self.criterion.update(mid_flux(&self.lattice)).is_some()
        {
            self.steady = true;
        }
    }

    /// The comparison with the analytical profile.
    fn outcome(&self, setup: &ChannelSetup) -> ChannelOutcome {
        let lattice = &self.lattice;
        let steady = self.steady;
        let mass0 = self.mass0;
        let (rho, u) = lattice.moments();
        let s = *lattice.shape();
        let xm = s.nx / 2;
        let units = &setup.units;
        let mut profile = Vec::with_capacity(s.ny);
        let (mut num, mut den, mut flux, mut flux_analytic) = (0.0, 0.0, 0.0, 0.0);
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
        let measured_mach = max_mach(&u);
        let nodes = (s.nx * s.ny) as f64;
        let centre_error = {
            let [_, us, ua, _] = profile[s.ny / 2];
            (us - ua) / ua
        };
        ChannelOutcome {
            steps: lattice.steps(),
            steady,
            wall_seconds: 0.0,
            mlups: 0.0,
            nodes,
            profile,
            l2_error: (num / den).sqrt(),
            flux_error: (flux - flux_analytic) / flux_analytic,
            centre_velocity_error: centre_error,
            measured_mach,
            mass_change: (lattice.mass() - mass0) / mass0,
        }
    }
}

fn profile_csv(o: &ChannelOutcome) -> String {
    csv(
        &["y", "u_simulated", "u_analytical", "lattice_density"],
        o.profile.iter().map(|r| r.to_vec()),
    )
}

/// Run a channel case in memory to its end (no directory); the outcome's wall time and MLUPS are those of the
/// whole run.
pub fn simulate(case: &Case<Channel>, exec: &Exec) -> Result<ChannelOutcome> {
    let start = Instant::now();
    let opts = RunOptions {
        exec: *exec,
        ..Default::default()
    };
    let (state, _) = run_in_memory(case, &opts)?;
    let wall = start.elapsed().as_secs_f64();
    let mut o = each!(&state, r => r.outcome(&case.setup));
    o.wall_seconds = wall;
    o.mlups = o.nodes * o.steps as f64 / wall.max(1e-12) / 1e6;
    Ok(o)
}

/// The channel kind: plane Poiseuille flow.
pub struct Channel;

impl Kind for Channel {
    const NAME: &'static str = "channel";
    const OWN_SECTION: Option<&'static str> = Some("channel");
    type Scene = ChannelScene;
    type Setup = ChannelSetup;
    type State = ChannelState;

    fn validate(scene: &ChannelScene) -> Result<()> {
        scene.fluid.validate()?;
        scene.run.validate()?;
        let c = scene.channel.as_ref().ok_or_else(|| {
            LbdemError::field(
                "channel",
                "missing",
                "scene.kind = \"channel\" needs a [channel] section",
                "add [channel] with length, width, drive and pressure_drop or acceleration",
            )
        })?;
        positive(
            "channel.length",
            c.length,
            "give the channel length along x",
        )?;
        positive(
            "channel.width",
            c.width,
            "give the channel width between the walls",
        )?;
        match c.drive {
            ChannelDrive::Pressure => {
                let dp = c.pressure_drop.ok_or_else(|| {
                    LbdemError::field(
                        "channel.pressure_drop",
                        "missing",
                        "drive = \"pressure\" needs the pressure drop over the length",
                        "add channel.pressure_drop",
                    )
                })?;
                positive(
                    "channel.pressure_drop",
                    dp,
                    "a positive drop drives flow along +x",
                )?;
                if c.acceleration.is_some() {
                    return Err(LbdemError::field(
                        "channel.acceleration",
                        "given",
                        "drive = \"pressure\" does not use an acceleration",
                        "remove channel.acceleration or set drive = \"body_force\"",
                    ));
                }
            }
            ChannelDrive::BodyForce => {
                let g = c.acceleration.ok_or_else(|| {
                    LbdemError::field(
                        "channel.acceleration",
                        "missing",
                        "drive = \"body_force\" needs the acceleration along x",
                        "add channel.acceleration",
                    )
                })?;
                positive(
                    "channel.acceleration",
                    g,
                    "a positive acceleration drives flow along +x",
                )?;
                if c.pressure_drop.is_some() {
                    return Err(LbdemError::field(
                        "channel.pressure_drop",
                        "given",
                        "drive = \"body_force\" does not use a pressure drop",
                        "remove channel.pressure_drop or set drive = \"pressure\"",
                    ));
                }
            }
        }
        Ok(())
    }

    fn setup(scene: &ChannelScene) -> Result<ChannelSetup> {
        ChannelSetup::new(scene)
    }

    fn budget(scene: &ChannelScene, setup: &ChannelSetup) -> Result<Budget> {
        let mut b = Budget::new();
        limits::lattice(
            &mut b,
            "channel.length",
            "channel lattice",
            setup.nx as u64,
            setup.ny as u64,
            scene.scene.precision.float_bytes(),
            limits::Solids::None,
        )?;
        Ok(b)
    }

    fn describe(case: &Case<Self>) -> String {
        case.setup.describe(case.scene.scene.units.labels())
    }

    fn start(case: &Case<Self>, exec: &Exec) -> Result<ChannelState> {
        Ok(match case.scene.scene.precision {
            Precision::F32 => ChannelState::F32(ChannelRun::new(case, exec)?),
            Precision::F64 => ChannelState::F64(ChannelRun::new(case, exec)?),
        })
    }

    fn lattices(state: &mut ChannelState) -> Vec<&mut dyn ExecTarget> {
        each!(state, r => vec![&mut r.lattice as &mut dyn ExecTarget])
    }

    fn steps_done(state: &ChannelState) -> u64 {
        each!(state, r => r.lattice.steps())
    }

    fn total_steps(case: &Case<Self>, _state: &ChannelState) -> Option<u64> {
        Some(case.setup.steps)
    }

    fn finished(case: &Case<Self>, state: &ChannelState) -> bool {
        each!(state, r => r.finished(&case.setup))
    }

    fn advance(case: &Case<Self>, state: &mut ChannelState, _dir: Option<&Path>) -> Result<()> {
        each!(state, r => r.advance(case));
        Ok(())
    }

    fn health(_case: &Case<Self>, state: &ChannelState) -> Result<()> {
        let hint = "raise tau, lower the driving pressure/acceleration, or refine the time step";
        each!(state, r => fluid_health(&r.lattice, hint))
    }

    fn write_outputs(
        case: &Case<Self>,
        state: &ChannelState,
        dir: &Path,
        _stage: OutputStage,
    ) -> Result<()> {
        // Periodic checkpoints flush the tables too, so that a killed run keeps its records so far.
        let o = each!(state, r => r.outcome(&case.setup));
        write_atomic(&dir.join("profile.csv"), profile_csv(&o).as_bytes())
    }

    fn results(case: &Case<Self>, state: &ChannelState) -> Result<serde_json::Value> {
        let o = each!(state, r => r.outcome(&case.setup));
        Ok(serde_json::json!({
            "steps": o.steps,
            "steady": o.steady,
            "error_vs_analytical": {
                "l2_relative": o.l2_error,
                "flux_relative": o.flux_error,
                "centre_velocity_relative": o.centre_velocity_error,
            },
            "measured_mach": o.measured_mach,
            "relative_mass_change": o.mass_change,
        }))
    }
}
