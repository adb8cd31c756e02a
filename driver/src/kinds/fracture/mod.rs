//! The fluid-driven ("natural hydraulic") fracture test of the dissertation, ch. 6.4–6.8: `kind = "fracture"`.
//!
//! A bonded sample of ellipses is packed into a W × H box (x along the long axis) at a hydrostatic effective
//! stress, then the axial effective stress (along x, σ₃) is lowered while the lateral stress (along y, σ₁) is
//! held by servo platens on the long sides. The axial stress acts through the boundary particles at both ends
//! of the long axis, so fluid can leave there. The fluid lattice spans the sample between the platens and
//! extends beyond both ends (free fluid, Zou–He pressure sides at x = 0 and x = L). The pore fluid starts at a
//! uniform pressure P₀. At t = 0 the axial stress and the boundary fluid pressure drop together; the fluid
//! drains through both ends, and its pressure gradient pulls the sample apart (fractures perpendicular to σ₃).
//!
//! Stages: pack and bond (ch. 2 procedure, [`crate::engine::dem::packing`]) → settle dry under the pre-drop loads
//! (no fluid force acts while the pore pressure is uniform) → couple (grains mapped onto the lattice with the
//! fluid-radius factor; TRT + ΩΛ by default, whose results do not move with τ) → drop → run `duration` with records and snapshots.
//! Without a `[fluid]` section the same loading runs dry (the dry control). With `pressure_drop = 0` the
//! saturated sample sees only the axial stress drop (the no-drop control).
//!
//! Every run writes into its output directory: `history.csv` (time, strains, stresses, broken bonds, mean pore
//! pressure), `centerline_pressure.csv` and `centerline_speed.csv` (time × distance along the sample's centre
//! line, fig. 6.13–6.14), `breaks.csv` (every broken bond: time, position, bond-normal and crack-plane angles,
//! mode, load), `fractures.csv` (broken bonds clustered into fractures: size, centre, trace angle, length),
//! VTK snapshots (`lattice_NNNN.vti`, `particles_NNNN.vtp`, `bonds_NNNN.vtp`, grouped with their model times in
//! `lattice.pvd`, `particles.pvd`, `bonds.pvd`; docs/outputs.md), PNG figures (`snapshot_NNNN.png` like fig. 6.8,
//! `speed_NNNN.png` like fig. 6.9, `centerline_pressure.png`, `centerline_speed.png`, `rose.png` like fig.
//! 6.10/6.15, `breaks.png`) and `summary.json` (written last).
pub mod analysis;
pub mod figures;

use std::path::Path;
use std::time::Instant;

use lbdem_kernels::dem::servo::ServoLaw;
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::{SolidOperator, Weighting};
use lbdem_kernels::fluid::lattice::Side;
use lbdem_kernels::fluid::step::FluidParams;
use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::engine::coupled::{CoupledWorld, LatticeMap};
use crate::engine::dem::packing::{generate_packing, Packing};
use crate::engine::dem::world::{DemWorld, PlatenControl, SampleBox, CRITICAL_STEP_SAFETY};
use crate::engine::exec::{Exec, ExecTarget};
use crate::engine::lattice::{check_remap_tolerance, FluidLattice};
use crate::error::{positive, LbdemError, Result};
use crate::input::limits::{self, Budget};
use crate::observe::darcy::{permeability, SteadyFlow};
use crate::observe::fit::fit_diffusivity;
use crate::observe::health::dem_health;
use crate::observe::steady::Steadiness;
use crate::output::snapshots::write_series;
use crate::output::vtk::{lattice_field, BreakClock, LatticeFrame, Stamp, Units};
use crate::output::{csv, write_atomic, SCENE_COPY};
use crate::run::{Case, Kind, OutputStage, Persist, Stop};
use crate::scene::solid::packing_budget;
use crate::scene::solid::{
    bond_spec, critical_time_step, packing_spec, validate_packing_and_solid, PackingSection,
    SolidSection,
};
use crate::scene::{
    check_free_grain_fluid, free_grain_choice, CheckpointSection, FreeGrains, SceneHeader,
};
use crate::units::{
    check_density_drop, check_tau, collision_of, CollisionName, FluidSection, LatticeUnits,
    Warnings,
};

use analysis::{cluster_fractures, BreakRow, Fracture};

/// `[fluid]` of a fracture scene: the fluid and the lattice (table 6.2).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FractureFluid {
    /// Reference density ρ₀.
    pub density: f64,
    /// Kinematic viscosity ν.
    pub viscosity: f64,
    /// Lattice spacing h.
    pub spacing: f64,
    /// Relaxation time τ (give this or `timestep`).
    #[serde(default)]
    pub tau: Option<f64>,
    /// Fluid (and coupled DEM) time step Δt (give this or `tau`).
    #[serde(default)]
    pub timestep: Option<f64>,
    /// Fluid collision, "bgk" or "trt" (default: TRT with the default solid operator ΩΛ, see
    /// [`FractureScene::fluid_choice`]).
    #[serde(default)]
    pub collision: Option<CollisionName>,
    /// TRT's magic parameter Λ (default 3/16).
    #[serde(default)]
    pub magic: Option<f64>,
    /// ΩΛ's form, "wall_pressure" (the default) or "friction_only" ([`crate::units::LambdaForm`]); only with
    /// the solid operator ΩΛ.
    #[serde(default)]
    pub lambda_form: Option<crate::units::LambdaForm>,
    /// Fraction of each grain's size the fluid sees (table 6.2: 0.6; table 6.3: 0.6–0.95).
    pub fluid_radius: f64,
    /// Free fluid beyond each end of the sample along x (default 0.3 cm).
    #[serde(default = "default_margin")]
    pub margin: f64,
    /// PSM weighting B (default: the solid operator's, [`SolidOperator::weighting`]: B = ε for ΩΛ,
    /// "noble_torczynski" for the others): "noble_torczynski", B(ε, τ) = ε(τ − ½)/((1 − ε) + (τ − ½)) (eq. 4.5; near
    /// τ = ½ it makes partly covered cells almost fluid, so the fluid radius the flow feels is smaller than the
    /// one given), or "solid_fraction", B = ε.
    #[serde(default)]
    pub weighting: Option<Weighting>,
    /// PSM solid operator (default "lambda_consistent", ΩΛ with TRT, where it is stable with the scene's
    /// grains, else "linearized_non_equilibrium_bounce_back", Ω₁ₗ with BGK: [`FractureScene::fluid_choice`]).
    /// Ω₂ and Ω₃ are refused (free grains).
    #[serde(default)]
    pub solid_operator: Option<SolidOperator>,
    /// How far (lattice spacings) a grain may move before the grains are mapped onto the lattice again (default
    /// 0: at every step, exact). A few hundredths make the fluid see each grain up to that far from where it is,
    /// and save the re-mapping at most steps ([`FluidLattice::set_remap_tolerance`]; README, *Benchmarks*).
    #[serde(default)]
    pub remap_tolerance: f64,
}

fn default_margin() -> f64 {
    0.3
}
impl FractureFluid {
    /// The PSM weighting: `weighting` if given, else that of the solid operator `op`.
    pub fn weighting(&self, op: SolidOperator) -> Weighting {
        self.weighting.unwrap_or(op.weighting())
    }

    /// `[fluid]` as the shared section (units and collision).
    fn section(&self) -> FluidSection {
        FluidSection {
            density: self.density,
            viscosity: self.viscosity,
            spacing: self.spacing,
            tau: self.tau,
            timestep: self.timestep,
            collision: self.collision,
            magic: self.magic,
            lambda_form: self.lambda_form,
        }
    }
}

/// `[loading]` of a fracture scene (ch. 6.6).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FractureLoading {
    /// Lateral effective stress σ₁ held by the servo platens on the long sides (ch. 6.6: 50).
    pub lateral_stress: f64,
    /// Axial effective stress σ₃ through the end particles before the drop (ch. 6.6: 40).
    pub axial_stress: f64,
    /// Axial stress after the drop (ch. 6.6: 0.1).
    pub axial_stress_after: f64,
    /// Boundary fluid pressure drop P₀ − P at t = 0 (0: the no-drop control).
    pub pressure_drop: f64,
    /// Dry settling under the pre-drop loads before the drop (time).
    pub settle_time: f64,
    /// Model time after the drop (ch. 6.7: 2 s).
    pub duration: f64,
    /// Thickness of the end layers whose particles carry the axial stress (default: `packing.radius_max`).
    #[serde(default)]
    pub boundary_depth: Option<f64>,
    /// PFC local damping after the drop (default: `solid.local_damping`). The fluid damps the grains itself;
    /// local damping also scales down the fluid's drag on accelerating grains.
    #[serde(default)]
    pub local_damping: Option<f64>,
}

/// `[output]` of a fracture scene.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FractureOutput {
    /// Time between records of the history and the centre line (default 1e-3 s, as the dissertation's
    /// screenshots).
    #[serde(default = "default_record")]
    pub record_interval: f64,
    /// Time between VTK/PNG snapshots (default 0.05; 0: only the start and the end).
    #[serde(default = "default_snapshot")]
    pub snapshot_interval: f64,
    /// Write VTK snapshots (default true).
    #[serde(default = "yes")]
    pub vtk: bool,
    /// Draw PNG figures (default true).
    #[serde(default = "yes")]
    pub figures: bool,
    /// Measure the intact sample's permeability by steady Darcy flow before the drop (default false).
    #[serde(default)]
    pub permeability: bool,
}

impl Default for FractureOutput {
    fn default() -> Self {
        Self {
            record_interval: default_record(),
            snapshot_interval: default_snapshot(),
            vtk: true,
            figures: true,
            permeability: false,
        }
    }
}

impl FractureOutput {
    /// Steps of `dt` between records (at least 1) and between snapshots (at least 1; 0: only at the drop and
    /// at the end). The casts saturate: an interval beyond `u64` steps records only at the drop and the end.
    pub fn intervals(&self, dt: f64) -> (u64, u64) {
        let record_every = ((self.record_interval / dt).round() as u64).max(1);
        let snapshot_every = if self.snapshot_interval > 0.0 {
            ((self.snapshot_interval / dt).round() as u64).max(1)
        } else {
            0
        };
        (record_every, snapshot_every)
    }
}

fn default_record() -> f64 {
    1e-3
}
fn default_snapshot() -> f64 {
    0.05
}
fn yes() -> bool {
    true
}

/// `[[heterogeneity]]`: a band of grains whose fluid radius differs from the matrix (ch. 6.8.1).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Band {
    /// Fluid radius factor of the grains in the band.
    pub fluid_radius: f64,
    /// x of the band's centre line at mid-height, measured from the sample's left end.
    pub center: f64,
    /// Band width (perpendicular to its centre line).
    pub width: f64,
    /// Angle of the centre line from the vertical (degrees; positive leans right at the top).
    #[serde(default)]
    pub angle: f64,
}

/// A whole fracture scene file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FractureScene {
    /// `[scene]` (kind = "fracture").
    pub scene: SceneHeader,
    /// `[packing]`: the sample (width along x is the long axis).
    pub packing: PackingSection,
    /// `[solid]`: grains and bonds (table 6.1).
    pub solid: SolidSection,
    /// `[fluid]`: absent for the dry control.
    #[serde(default)]
    pub fluid: Option<FractureFluid>,
    /// `[loading]`.
    pub loading: FractureLoading,
    /// `[output]`.
    #[serde(default)]
    pub output: FractureOutput,
    /// `[[heterogeneity]]` bands.
    #[serde(default)]
    pub heterogeneity: Vec<Band>,
    /// `[run]`: checkpoint interval.
    #[serde(default)]
    pub run: CheckpointSection,
}

crate::scene::scene_file!(FractureScene);

/// Kind tag of fracture checkpoints.
pub const FRACTURE_KIND: &str = "fracture";

/// Derived fluid set-up: units, lattice size, densities.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FluidSetup {
    /// The unit conversion.
    pub units: LatticeUnits,
    /// Nodes along x and y.
    pub nodes: [usize; 2],
    /// Lattice density of the pore fluid before the drop.
    pub density_high: f64,
    /// Lattice density imposed on both ends after the drop.
    pub density_low: f64,
    /// Expected Mach number of the drainage flow (Darcy estimate in the pore throats).
    pub expected_mach: f64,
    /// Lattice nodes across the smallest grain's minor axis as the fluid sees it.
    pub nodes_per_grain: f64,
    /// The collision used where `[fluid] collision` is not given ([`FractureScene::fluid_choice`]).
    pub collision_default: CollisionName,
    /// The PSM solid operator ([`FractureScene::fluid_choice`]).
    pub solid_operator: SolidOperator,
}

impl FractureScene {
    /// The default fluid collision and the solid operator of `[fluid]` `f` at relaxation time `tau`
    /// ([`free_grain_choice`]): without `solid_operator`, TRT + ΩΛ where ΩΛ is stable with the scene's grains
    /// (rock grains, ρs/ρf = 2.65: at every τ the DEM step allows), chosen because it is the combination whose
    /// intact-sample permeability does not move with τ (quick base scene, τ = 0.537 / 0.648 / 0.870 / 1.426:
    /// k = 1.968e-4 cm² at each, where Ω₁ₗ with BGK gives 1.627e-4 / 1.948e-4 / 2.555e-4 / …; README, "Results
    /// that do not depend on τ").
    pub fn fluid_choice(
        &self,
        f: &FractureFluid,
        tau: f64,
        warnings: &mut Warnings,
    ) -> (CollisionName, SolidOperator) {
        free_grain_choice(
            f.solid_operator,
            tau,
            FreeGrains::packed(self.packing.density / f.density).in_form(f.section().lambda_form),
            warnings,
        )
    }

    /// Parse from TOML text and check ranges (`path` for messages).
    pub fn from_toml(text: &str, path: &str) -> Result<Self> {
        let s: FractureScene = crate::scene::parse_scene(text, path)?;
        s.validate()?;
        Ok(s)
    }

    /// Range checks naming the field.
    pub fn validate(&self) -> Result<()> {
        self.scene.require_f64()?;
        validate_packing_and_solid(&self.packing, &self.solid)?;
        let l = &self.loading;
        positive(
            "loading.lateral_stress",
            l.lateral_stress,
            "ch. 6.6: 50 dyne/cm^2",
        )?;
        positive("loading.axial_stress", l.axial_stress, "ch. 6.6: 40")?;
        positive(
            "loading.axial_stress_after",
            l.axial_stress_after,
            "ch. 6.6: 0.1",
        )?;
        if !(l.pressure_drop.is_finite() && l.pressure_drop >= 0.0) {
            return Err(LbdemError::field(
                "loading.pressure_drop",
                l.pressure_drop,
                "must be finite and >= 0",
                "0 for the no-drop control",
            ));
        }
        if !(l.settle_time.is_finite() && l.settle_time >= 0.0) {
            return Err(LbdemError::field(
                "loading.settle_time",
                l.settle_time,
                "must be finite and >= 0",
                "e.g. 0.02 s",
            ));
        }
        positive("loading.duration", l.duration, "ch. 6.7: 2 s")?;
        if let Some(d) = l.boundary_depth {
            positive("loading.boundary_depth", d, "about one grain radius")?;
        }
        if let Some(a) = l.local_damping {
            if !(0.0..1.0).contains(&a) {
                return Err(LbdemError::field(
                    "loading.local_damping",
                    a,
                    "must be in [0, 1)",
                    "0 leaves the damping to the fluid; PFC uses 0.7 for quasi-static loading",
                ));
            }
        }
        let o = &self.output;
        positive("output.record_interval", o.record_interval, "e.g. 1e-3 s")?;
        if !(o.snapshot_interval.is_finite() && o.snapshot_interval >= 0.0) {
            return Err(LbdemError::field(
                "output.snapshot_interval",
                o.snapshot_interval,
                "must be finite and >= 0",
                "0 writes only the first and last snapshot",
            ));
        }
        for (k, b) in self.heterogeneity.iter().enumerate() {
            crate::error::fraction(
                &format!("heterogeneity[{k}].fluid_radius"),
                b.fluid_radius,
                "ch. 6.8.1 uses 0.6 and 0.95",
            )?;
            positive(
                &format!("heterogeneity[{k}].width"),
                b.width,
                "band width, e.g. 0.5 cm",
            )?;
            if !(b.center.is_finite() && b.angle.is_finite() && b.angle.abs() < 90.0) {
                return Err(LbdemError::field(
                    &format!("heterogeneity[{k}].angle"),
                    b.angle,
                    "center must be finite and angle within (-90, 90) degrees of the vertical",
                    "0 for a vertical band",
                ));
            }
        }
        if !self.heterogeneity.is_empty() && self.fluid.is_none() {
            return Err(LbdemError::field(
                "heterogeneity",
                "given",
                "bands change the fluid radius, but the scene has no [fluid]",
                "add [fluid] or remove the [[heterogeneity]] bands",
            ));
        }
        if let Some(f) = &self.fluid {
            crate::error::fraction("fluid.fluid_radius", f.fluid_radius, "table 6.2: 0.6")?;
            positive("fluid.margin", f.margin, "e.g. 0.3 cm of free fluid")?;
            check_remap_tolerance(f.remap_tolerance)?;
            self.fluid_setup(f, &mut Warnings::default())?;
        } else if l.pressure_drop > 0.0 {
            return Err(LbdemError::field(
                "loading.pressure_drop",
                l.pressure_drop,
                "a dry scene (no [fluid]) cannot drop a fluid pressure",
                "set pressure_drop = 0 for the dry control, or add [fluid]",
            ));
        }
        self.timesteps().map(|_| ())
    }

    /// Units, lattice size and densities; refuses τ ≤ ½, a density drop above 20 %, high Mach.
    pub fn fluid_setup(&self, f: &FractureFluid, warnings: &mut Warnings) -> Result<FluidSetup> {
        positive("fluid.density", f.density, "e.g. 1 g/cm^3")?;
        positive("fluid.viscosity", f.viscosity, "table 6.2: 0.2 cm^2/s")?;
        positive("fluid.spacing", f.spacing, "table 6.2: 0.009 cm")?;
        let units = LatticeUnits::from_fluid(&f.section())?;
        check_tau(&units, warnings);
        let choice = self.fluid_choice(f, units.tau, warnings);
        check_free_grain_fluid(
            "fluid.solid_operator",
            &f.section(),
            choice,
            units.tau,
            FreeGrains::packed(self.packing.density / f.density).in_form(f.section().lambda_form),
            warnings,
        )?;
        let h = f.spacing;
        let lx = self.packing.width + 2.0 * f.margin;
        let nodes = [
            limits::count(
                "fluid.spacing",
                "the lattice width in nodes",
                (lx / h).round() + 1.0,
            )? as usize,
            limits::count(
                "fluid.spacing",
                "the lattice height in nodes",
                (self.packing.height / h).round(),
            )? as usize,
        ];
        if nodes[0] < 8 || nodes[1] < 8 || nodes[0].saturating_mul(nodes[1]) > 200_000_000 {
            return Err(LbdemError::field(
                "fluid.spacing",
                h,
                &format!("gives a {} x {} lattice", nodes[0], nodes[1]),
                "choose a spacing giving at least 8 and at most ~10^8 nodes",
            ));
        }
        // Pressure drop as a lattice density difference Δρ = Δp/(ρ₀ c_s²), split about 1.
        let drop = self.loading.pressure_drop / (f.density * units.sound_speed.powi(2));
        check_density_drop("loading.pressure_drop", drop, warnings)?;
        // Darcy estimate of the drainage speed over the first grain layers: u ≈ (k/μ) Δp / ℓ with
        // ℓ ≈ 2 grain sizes and k from the Kozeny–Carman form for discs, k = n³ D²/(80 (1 − n)²), i.e. a
        // Kozeny constant of 5 (Carman 1937), with n the porosity the fluid sees.
        let n = 1.0 - self.packing.solid_fraction * f.fluid_radius.powi(2);
        let d = 2.0 * self.packing.radius_min * self.packing.aspect_ratio * f.fluid_radius;
        let k = lbdem_reference::analytic::kozeny_carman(n, d, 5.0);
        let u = k / (f.viscosity * f.density) * self.loading.pressure_drop
            / (4.0 * self.packing.radius_max)
            / n;
        let expected_mach = u / units.sound_speed;
        crate::units::check_mach("loading.pressure_drop", expected_mach, None, warnings)?;
        Ok(FluidSetup {
            units,
            nodes,
            density_high: 1.0 + 0.5 * drop,
            density_low: 1.0 - 0.5 * drop,
            expected_mach,
            nodes_per_grain: d / h,
            collision_default: choice.0,
            solid_operator: choice.1,
        })
    }

    /// The DEM critical step of the grains and bonds, and the step the post-drop phase uses.
    fn timesteps(&self) -> Result<(f64, f64)> {
        let critical = critical_time_step(&self.packing, &self.solid);
        let limit = CRITICAL_STEP_SAFETY * critical;
        if self.solid.timestep > limit {
            return Err(LbdemError::field(
                "solid.timestep",
                self.solid.timestep,
                &format!("exceeds {CRITICAL_STEP_SAFETY} x the DEM critical step {critical:.3e}"),
                &format!("use solid.timestep <= {limit:.3e}"),
            ));
        }
        let coupled = match &self.fluid {
            Some(f) => {
                let u = self.fluid_setup(f, &mut Warnings::default())?.units;
                if u.timestep > limit {
                    return Err(LbdemError::field(
                        "fluid.timestep",
                        u.timestep,
                        &format!(
                            "the coupled DEM steps with the fluid step, which exceeds {CRITICAL_STEP_SAFETY} x the DEM critical step {critical:.3e}"
                        ),
                        "refine the fluid time step (smaller dt or tau) or soften the grains",
                    ));
                }
                u.timestep
            }
            None => self.solid.timestep,
        };
        Ok((critical, coupled))
    }

    /// Human-readable derived parameters.
    pub fn describe(&self) -> Result<String> {
        let (critical, dt) = self.timesteps()?;
        let labels = self.scene.units.labels();
        let l = &self.loading;
        let mut s = format!(
            "  sample {w} x {h} {len} (long axis x), grains {rmin}-{rmax} {len}, aspect {a}, solid fraction {sf}\n  \
             DEM critical step {critical:.3e} {t}; settling step {sdt:.3e} {t}; post-drop step {dt:.3e} {t} ({steps} steps over {dur} {t})\n  \
             loads: lateral (platens) {lat} {pr}; axial (end particles) {ax} -> {axa} {pr}; boundary pressure drop {dp} {pr}\n",
            w = self.packing.width,
            h = self.packing.height,
            len = labels.length,
            rmin = self.packing.radius_min,
            rmax = self.packing.radius_max,
            a = self.packing.aspect_ratio,
            sf = self.packing.solid_fraction,
            sdt = self.solid.timestep,
            steps = (l.duration / dt).round() as u64,
            dur = l.duration,
            t = labels.time,
            lat = l.lateral_stress,
            ax = l.axial_stress,
            axa = l.axial_stress_after,
            dp = l.pressure_drop,
            pr = labels.pressure,
        );
        match &self.fluid {
            None => s += "  no fluid: the dry control (no lattice is allocated)\n",
            Some(f) => {
                let mut w = Warnings::default();
                let fs = self.fluid_setup(f, &mut w)?;
                let u = fs.units;
                s += &format!(
                    "  fluid: h = {h} {len}, dt = {dt:.4e} {t}, nu = {nu} {vi}, tau = {tau:.4}, c = {c:.4e} {v}, c_s = {cs:.4e} {v}, \
                     compressibility 1/(rho c_s^2) = {beta:.3e} 1/({pr})\n  \
                     lattice {nx} x {ny} = {nodes} nodes; fluid radius {fr}; {npg:.1} nodes across the smallest grain's minor axis as the fluid sees it\n  \
                     pore density {hi:.5} -> ends {lo:.5} (lattice), expected Mach {ma:.3}; solid operator {op}, weighting {wt:?}\n",
                    h = u.spacing,
                    dt = u.timestep,
                    nu = u.viscosity,
                    tau = u.tau,
                    c = u.lattice_speed,
                    cs = u.sound_speed,
                    beta = u.compressibility,
                    nx = fs.nodes[0],
                    ny = fs.nodes[1],
                    nodes = fs.nodes[0] * fs.nodes[1],
                    fr = f.fluid_radius,
                    npg = fs.nodes_per_grain,
                    hi = fs.density_high,
                    lo = fs.density_low,
                    ma = fs.expected_mach,
                    op = crate::units::describe_operator(fs.solid_operator, &f.section())?,
                    wt = f.weighting(fs.solid_operator),
                    len = labels.length,
                    t = labels.time,
                    v = labels.velocity,
                    vi = labels.viscosity,
                    pr = labels.pressure,
                );
                for b in &self.heterogeneity {
                    s += &format!(
                        "  band: fluid radius {} at x = {} {len} from the left end, width {}, {} deg from vertical\n",
                        b.fluid_radius,
                        b.center,
                        b.width,
                        b.angle,
                        len = labels.length
                    );
                }
                for warning in w.0 {
                    s += &format!("  WARNING: {warning}\n");
                }
            }
        }
        Ok(s)
    }

    /// Which grains lie in a heterogeneity band: the band's fluid radius, or `None`.
    fn band_radius(&self, x: f64, y: f64, left: f64, bottom: f64) -> Option<f64> {
        let ymid = bottom + 0.5 * self.packing.height;
        // Later bands win where bands overlap.
        self.heterogeneity.iter().rev().find_map(|b| {
            let th = b.angle.to_radians();
            let (cx, cy) = (left + b.center, ymid);
            // Centre line direction (sin θ, cos θ); its normal (cos θ, −sin θ).
            let d = (x - cx) * th.cos() - (y - cy) * th.sin();
            (d.abs() <= 0.5 * b.width).then_some(b.fluid_radius)
        })
    }
}

/// The fluid part of a run.
struct FluidView<'b> {
    world: &'b CoupledWorld,
    setup: FluidSetup,
    /// Row of the centre line.
    center_row: usize,
}

/// One record of the run's history.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct HistoryRow {
    /// Time since the drop.
    pub time: f64,
    /// Axial strain along x from the end particles (extension negative).
    pub axial_strain: f64,
    /// Lateral strain along y from the platens (extension negative).
    pub lateral_strain: f64,
    /// Mean stress on the two lateral platens.
    pub lateral_stress: f64,
    /// Axial stress applied through the end particles.
    pub axial_stress: f64,
    /// Bonds broken so far.
    pub broken_bonds: usize,
    /// Mean pore-pressure excess over the drained boundary, over the sample's fluid nodes.
    pub mean_pore_pressure: f64,
    /// Largest fluid speed on the lattice.
    pub max_speed: f64,
    /// Kinetic energy of the grains.
    pub kinetic_energy: f64,
}

/// A fracture run: its scene and its state (owned or borrowed, `S` derefs to [`FractureState`]).
pub struct FractureRun<'a, S> {
    scene: &'a FractureScene,
    state: S,
}

/// The state of a fracture run: the packed, bonded and settled sample, the lattice if any, and everything
/// measured so far. All of it goes into checkpoints.
#[derive(Serialize, Deserialize)]
pub struct FractureState {
    coupled: Option<CoupledWorld>,
    dry: Option<DemWorld<f64>>,
    sample: SampleBox,
    ends: [Vec<usize>; 2],
    /// Initial axial length (mean x distance between the end particles) and lateral height (platens).
    reference: [f64; 2],
    packed: String,
    permeability: String,
    dt: f64,
    steps_done: u64,
    dropped: bool,
    /// DEM step count at the drop (break records count from it).
    drop_step: u64,
    history: Vec<HistoryRow>,
    center_pressure: Vec<Vec<f64>>,
    center_speed: Vec<Vec<f64>>,
    center_x: Vec<f64>,
    snapshots: usize,
    prep_seconds: f64,
    /// Grains whose centre lay outside the fluid lattice at the latest record, and the time of the first record
    /// that found one (see [`MAX_OUTSIDE_FRACTION`]).
    outside: usize,
    first_outside: Option<f64>,
}

impl Persist for FractureState {}

/// Largest fraction of the grains whose centres may lie outside the fluid lattice (beyond `fluid.margin` at the
/// sample's ends) before the run is stopped: such grains feel no fluid, so once the sample has come apart that
/// far the coupled run no longer says what the scene asks (the first one is warned).
pub const MAX_OUTSIDE_FRACTION: f64 = 0.05;

const HISTORY_COLUMNS: [&str; 9] = [
    "time",
    "axial_strain",
    "lateral_strain",
    "lateral_stress",
    "axial_stress",
    "broken_bonds",
    "mean_pore_pressure",
    "max_fluid_speed",
    "kinetic_energy",
];

impl HistoryRow {
    fn to_row(self) -> Vec<f64> {
        vec![
            self.time,
            self.axial_strain,
            self.lateral_strain,
            self.lateral_stress,
            self.axial_stress,
            self.broken_bonds as f64,
            self.mean_pore_pressure,
            self.max_speed,
            self.kinetic_energy,
        ]
    }
}

/// Pack and bond the sample of `scene` (the ch. 2 procedure): the slow part of the preparation, the same
/// for every scene with the same `[packing]` and `[solid]` sections.
pub fn pack(scene: &FractureScene) -> Result<Packing<f64>> {
    let spec = packing_spec::<f64>(&scene.packing, &scene.solid);
    generate_packing(&spec, bond_spec::<f64>(&scene.solid))
}

/// Pack, bond, settle and (with fluid) couple: everything before t = 0.
pub fn prepare(scene: &FractureScene) -> Result<FractureState> {
    prepare_packed(scene, pack(scene)?)
}

/// As [`prepare`] from a packing made by [`pack`] for a scene with the same
/// `[packing]` and `[solid]` sections (e.g. the controls and variants of one sample).
pub fn prepare_packed(scene: &FractureScene, packing: Packing<f64>) -> Result<FractureState> {
    let start = Instant::now();
    let (_critical, dt) = scene.timesteps()?;
    let Packing {
        mut world,
        sample_box,
        converged,
        steps,
        wall_stresses,
        ..
    } = packing;
    world.local_damping = scene.solid.local_damping;
    if !converged {
        eprintln!(
            "lbdem: WARNING: the packing did not reach packing.isotropic_stress in equilibrium within {steps} DEM \
             steps (wall stresses {:.3e} / {:.3e} / {:.3e} / {:.3e}): the sample starts off its stated stress; \
             change packing.seed, or raise solid.normal_stiffness or packing.isotropic_stress",
            wall_stresses[0], wall_stresses[1], wall_stresses[2], wall_stresses[3]
        );
    }
    let packed = json!({
        "particles": world.particles.len(),
        "bonds": world.bonds.len(),
        "packing_steps": steps,
        "packing_converged": converged,
        "wall_stresses": wall_stresses,
    });
    eprintln!(
        "lbdem: packed {} grains, {} bonds ({} steps, converged {converged})",
        world.particles.len(),
        world.bonds.len(),
        steps
    );
    // Loads before the drop: lateral servo platens (bottom, top), axial stress through the end particles.
    let b = sample_box;
    let width = world.platens[b.right].wall.point[0] - world.platens[b.left].wall.point[0];
    let height = world.platens[b.top].wall.point[1] - world.platens[b.bottom].wall.point[1];
    world.platens[b.left].active = false;
    world.platens[b.right].active = false;
    world.sample_box = None;
    for side in [b.bottom, b.top] {
        world.platens[side].length = width;
        world.platens[side].control = PlatenControl::Servo(ServoLaw {
            target_stress: scene.loading.lateral_stress,
            relaxation: 0.5,
            max_speed: 1e-3 * height / world.timestep(),
        });
    }
    let depth = scene
        .loading
        .boundary_depth
        .unwrap_or(scene.packing.radius_max);
    let ends = [
        world.boundary_particles(0, depth),
        world.boundary_particles(1, depth),
    ];
    apply_axial(&mut world, &ends, scene.loading.axial_stress, height);
    let settle = (scene.loading.settle_time / world.timestep()).round() as u64;
    for _ in 0..settle {
        world.step();
    }
    let breaks_settling = world.breaks.len();
    world.breaks.clear();
    eprintln!(
        "lbdem: settled {settle} steps under lateral {} / axial {} ({breaks_settling} bonds broke while settling)",
        scene.loading.lateral_stress, scene.loading.axial_stress
    );
    let reference = [
        end_distance(&world, &ends),
        world.platens[b.top].wall.point[1] - world.platens[b.bottom].wall.point[1],
    ];
    let mut state = FractureState {
        coupled: None,
        dry: None,
        sample: sample_box,
        ends,
        reference,
        packed: packed.to_string(),
        permeability: String::new(),
        dt,
        steps_done: 0,
        dropped: false,
        drop_step: 0,
        history: Vec::new(),
        center_pressure: Vec::new(),
        center_speed: Vec::new(),
        center_x: Vec::new(),
        snapshots: 0,
        prep_seconds: 0.0,
        outside: 0,
        first_outside: None,
    };
    match &scene.fluid {
        None => {
            world.set_timestep(dt)?;
            state.dry = Some(world);
        }
        Some(f) => {
            let mut warnings = Warnings::default();
            let setup = scene.fluid_setup(f, &mut warnings)?;
            let u = setup.units;
            let [nx, ny] = setup.nodes;
            // Lattice: x from the left end minus the margin; y between the platens' inner faces, the
            // half-way bounce-back walls half a spacing outside the edge nodes lying on the platens.
            let (lo, _) = world.bounds();
            let left = lo[0] - f.margin;
            let bottom = world.platens[b.bottom].wall.point[1];
            let bc = Boundaries {
                west: SideCondition::Pressure {
                    density: setup.density_high,
                },
                east: SideCondition::Pressure {
                    density: setup.density_high,
                },
                south: SideCondition::Wall,
                north: SideCondition::Wall,
            };
            let mut lattice = FluidLattice::new(
                nx,
                ny,
                bc,
                FluidParams {
                    tau: u.tau,
                    force: [0.0; 2],
                },
            )?;
            lattice.fill_equilibrium(|_, _| (setup.density_high, [0.0; 2]));
            lattice.set_collision(collision_of(
                f.section()
                    .checked_collision(setup.collision_default, u.tau)?,
            )?)?;
            lattice.set_solid_operator(setup.solid_operator);
            lattice.set_lambda_terms(f.section().lambda_terms(setup.solid_operator)?)?;
            lattice.set_remap_tolerance(f.remap_tolerance)?;
            let map = LatticeMap {
                spacing: u.spacing,
                timestep: u.timestep,
                density: u.density,
                origin: [left, bottom + 0.5 * u.spacing],
            };
            let sample_left = lo[0];
            let grain_radius: Vec<f64> = world
                .particles
                .iter()
                .map(|p| {
                    scene
                        .band_radius(p.position[0], p.position[1], sample_left, bottom)
                        .unwrap_or(f.fluid_radius)
                })
                .collect();
            let applied_before = world.external_force.clone();
            let mut coupled = CoupledWorld::new(
                lattice,
                world,
                map,
                f.fluid_radius,
                f.weighting(setup.solid_operator),
                1,
            )?;
            if !scene.heterogeneity.is_empty() {
                coupled.grain_fluid_radius = grain_radius;
            }
            for (a, f) in coupled.applied.iter_mut().zip(applied_before) {
                a.0 = f;
            }
            let center_row = ny / 2;
            state.center_x = (0..nx).map(|i| left + i as f64 * u.spacing).collect();
            let _ = (setup, center_row);
            state.coupled = Some(coupled);
        }
    }
    state.prep_seconds = start.elapsed().as_secs_f64();
    Ok(state)
}

impl<'a, S: std::ops::Deref<Target = FractureState>> FractureRun<'a, S> {
    fn dem(&self) -> &DemWorld<f64> {
        match (&self.state.coupled, &self.state.dry) {
            (Some(w), _) => &w.dem,
            (None, Some(d)) => d,
            (None, None) => unreachable!("a run holds either a coupled or a dry world"),
        }
    }

    /// The fluid part: the coupled world, the derived set-up, the centre row.
    fn fluid(&self) -> Option<FluidView<'_>> {
        let world = self.state.coupled.as_ref()?;
        let f = self.scene.fluid.as_ref()?;
        let setup = self.scene.fluid_setup(f, &mut Warnings::default()).ok()?;
        Some(FluidView {
            world,
            setup,
            center_row: setup.nodes[1] / 2,
        })
    }

    fn total(&self) -> u64 {
        (self.scene.loading.duration / self.state.dt)
            .round()
            .max(1.0) as u64
    }

    /// Steps between records and between snapshots.
    fn intervals(&self) -> (u64, u64) {
        let (record_every, snapshot_every) = self.scene.output.intervals(self.state.dt);
        // 0: only the snapshots at the drop and at the end.
        (
            record_every,
            if snapshot_every == 0 {
                u64::MAX
            } else {
                snapshot_every
            },
        )
    }

    fn lateral_height(&self) -> f64 {
        let d = self.dem();
        d.platens[self.state.sample.top].wall.point[1]
            - d.platens[self.state.sample.bottom].wall.point[1]
    }

    /// A lattice of the run's size and τ with Zou–He densities `west`, `east` at the ends, walls on the platens,
    /// and the run's solid operator (for the intact-sample measurements, which cover it with fixed grains).
    fn fixed_grain_lattice(&self, west: f64, east: f64) -> Result<FluidLattice<f64>> {
        let fp = self.fluid().expect("fluid");
        let [nx, ny] = fp.setup.nodes;
        let bc = Boundaries {
            west: SideCondition::Pressure { density: west },
            east: SideCondition::Pressure { density: east },
            south: SideCondition::Wall,
            north: SideCondition::Wall,
        };
        let params = FluidParams {
            tau: fp.setup.units.tau,
            force: [0.0; 2],
        };
        let mut lattice = FluidLattice::new(nx, ny, bc, params)?;
        lattice.set_collision(fp.world.fluid.collision())?;
        lattice.set_solid_operator(fp.world.fluid.solid_operator());
        lattice.set_lambda_terms(fp.world.fluid.lambda_terms())?;
        Ok(lattice)
    }

    /// Steady Darcy flow through the intact sample (table 6.3's method): grains fixed, a small pressure
    /// difference across the ends, run until the flux settles; k = μ q L/Δp with q the superficial flux.
    /// `Ok(None)`: abandoned on a stop request (nothing of the state changed).
    fn measure_permeability(&self, stop: &Stop) -> Result<Option<serde_json::Value>> {
        let fp = self.fluid().expect("fluid");
        let setup = fp.setup;
        let [nx, ny] = setup.nodes;
        let units = setup.units;
        let drho = 1e-3;
        let mut lattice = self.fixed_grain_lattice(1.0 + 0.5 * drho, 1.0 - 0.5 * drho)?;
        let mut bodies = fp.world.bodies();
        for b in &mut bodies {
            b.velocity = lbdem_kernels::math::Vector::from([0.0; 2]);
            b.spin = 0.0;
        }
        lattice.cover_with_bodies(&bodies, fp.world.weighting);
        let flux = |l: &FluidLattice<f64>| -> f64 {
            // Mean superficial x-velocity over the whole lattice = volume flux per unit height / ... in lattice
            // units: Σ u_x (1 − ε) / (nx ny) times ny gives the flux per column.
            let (rho, u) = l.moments();
            let eps = l.solid_fraction_map();
            let mut s = 0.0;
            for k in 0..rho.len() {
                s += u[k][0] * (1.0 - eps[k]);
            }
            s / (nx as f64)
        };
        // Steady when the flux changes by less than 1e-5 relative over 500 steps (at most 400 000 steps).
        let mut flow = SteadyFlow::new(Steadiness::new(1e-5), 500, 400_000);
        let hint = "the intact-sample permeability run diverged: lower tau's distance to 1/2 or the grains' fluid radius";
        while !flow.advance(&mut lattice, flux, hint)? {
            if stop.requested() {
                return Ok(None);
            }
        }
        let (q, steps) = (flow.flux, flow.steps);
        // Darcy: q = (k/μ) Δp/L with q the flux per unit height (= Σ u over a column / ny × ny h …): in
        // lattice units k* = ν* q* L*/(Δp*) with Δp* = Δρ/3 over L* = nx − 1, q* = flux per unit height.
        let q_per_height = q / ((ny) as f64);
        let length = (nx - 1) as f64;
        let k_lattice = permeability(
            units.lattice_viscosity,
            q_per_height,
            length,
            crate::units::cs2_times(drho),
        );
        let k = k_lattice * units.spacing * units.spacing;
        let n_fluid = 1.0 - lattice.solid_fraction_map().iter().sum::<f64>() / (nx * ny) as f64;
        eprintln!(
            "lbdem: intact-sample permeability k = {k:.3e} (lattice {k_lattice:.3e}), fluid porosity {n_fluid:.3} ({steps} steps)"
        );
        let Some(transient) = self.measure_diffusivity(&bodies, k_lattice, n_fluid, stop)? else {
            return Ok(None);
        };
        Ok(Some(json!({
            "permeability": k,
            "fluid_porosity_of_lattice": n_fluid,
            "steps": steps,
            "converged": flow.steady,
            "note": "over the whole lattice including the free fluid beyond the ends (a series correction is not applied)",
            "transient": transient,
        })))
    }

    /// Hydraulic diffusivity and storage of the intact sample by the transient method of ch. 5.6 (table 6.3's
    /// "storage"): grains fixed, the pore fluid raised by a small overpressure P₀ and drained through both ends;
    /// fluid-fraction-weighted column means of P/P₀ inside the sample, sampled between Fourier numbers 0.02 and
    /// 0.5, are fitted by least squares (Gauss–Newton, [`fit_diffusivity`]) to the slab
    /// solution of eq. 5.12 with faces at the sample's ends. Storage S = k/(μ c) (here with the grains held, so it
    /// is the fluid's own compressibility times the pore fraction that stores: 1/(ρ₀c_s²) × n).
    fn measure_diffusivity(
        &self,
        bodies: &[lbdem_kernels::coupling::CoupledBody<f64>],
        k_lattice: f64,
        n_fluid: f64,
        stop: &Stop,
    ) -> Result<Option<serde_json::Value>> {
        let fp = self.fluid().expect("fluid");
        let [nx, ny] = fp.setup.nodes;
        let units = fp.setup.units;
        let p0 = 1e-3;
        let mut lattice = self.fixed_grain_lattice(1.0, 1.0)?;
        lattice.fill_equilibrium(|_, _| (1.0 + p0, [0.0; 2]));
        lattice.cover_with_bodies(bodies, fp.world.weighting);
        let eps = lattice.solid_fraction_map();
        // The sample's ends in lattice x.
        let (lo, hi) = self.dem().bounds();
        let origin = fp.world.map.origin[0];
        let xa = ((lo[0] - origin) / units.spacing).ceil().max(1.0) as usize;
        let xb = (((hi[0] - origin) / units.spacing).floor() as usize).min(nx - 2);
        let half = 0.5 * (xb - xa) as f64;
        let center = 0.5 * (xa + xb) as f64;
        // Guess: the rigid-skeleton LB diffusivity k c_s²/(ν n) (lattice units, c_s² = 1/3).
        let guess =
            k_lattice / (crate::units::over_cs2(units.lattice_viscosity) * n_fluid.max(1e-3));
        let t_end = (0.5 * half * half / guess).ceil().max(20.0) as u64;
        let t_start = (0.02 * half * half / guess).ceil().max(1.0) as u64;
        let snapshots = 12u64;
        let mut samples = Vec::new();
        let mut t = 0u64;
        for k in 0..snapshots {
            let target = t_start + (t_end - t_start) * k / (snapshots - 1);
            while t < target {
                if stop.requested() {
                    return Ok(None);
                }
                lattice.step();
                t += 1;
            }
            let (rho, _) = lattice.moments();
            for x in (xa..=xb).step_by(((xb - xa) / 40).max(1)) {
                let (mut s, mut w) = (0.0, 0.0);
                for y in 0..ny {
                    let i = y * nx + x;
                    s += (1.0 - eps[i]) * (rho[i] - 1.0);
                    w += 1.0 - eps[i];
                }
                if w > 0.0 {
                    samples.push((x as f64 - center, t as f64, s / w / p0));
                }
            }
        }
        let (c, rms, iterations) = fit_diffusivity(&samples, half, guess);
        let c_phys = c * units.spacing * units.spacing / units.timestep;
        let k_phys = k_lattice * units.spacing * units.spacing;
        let storage = k_phys / (units.density * units.viscosity * c_phys);
        let half_phys = half * units.spacing;
        // Diffusion describes the drainage only when sound crosses the sample much faster than pressure diffuses.
        let regime = (half * half / c) / (half * 3f64.sqrt());
        if rms > 0.05 || regime < 5.0 {
            eprintln!(
                "lbdem: WARNING: the intact-sample transient is not diffusion-dominated (diffusion time / sound crossing \
                 time = {regime:.1}, RMS residual {rms:.3} P0): the fitted diffusivity is only indicative"
            );
        }
        eprintln!(
            "lbdem: intact-sample diffusivity c = {c_phys:.3e} (rigid-skeleton prediction k c_s^2/(nu n) = {:.3e}), storage {storage:.3e}, \
             time constant L^2/c = {:.3e} (RMS residual {rms:.3} P0)",
            guess * units.spacing * units.spacing / units.timestep,
            half_phys * half_phys / c_phys
        );
        Ok(Some(json!({
            "diffusivity": c_phys,
            "rigid_skeleton_prediction": guess * units.spacing * units.spacing / units.timestep,
            "storage": storage,
            "half_length": half_phys,
            "time_constant": half_phys * half_phys / c_phys,
            "rms_residual": rms,
            "diffusion_over_sound_crossing_time": regime,
            "iterations": iterations,
            "samples": samples.len(),
            "steps": t,
            "note": "grains held fixed: the storage is that of the LB fluid in the pores (1/(rho c_s^2) per unit pore volume)",
        })))
    }

    /// The tables so far, and the figures when `figures` (and the scene's `output.figures`).
    fn write_tables(&self, out: &Path, figures: bool) -> Result<()> {
        let figures = figures && self.scene.output.figures;
        let history = csv(
            &HISTORY_COLUMNS,
            self.state.history.iter().map(|h| h.to_row()),
        );
        write_atomic(&out.join("history.csv"), history.as_bytes())?;
        let (rows, fractures) = self.fractures();
        write_atomic(
            &out.join("breaks.csv"),
            analysis::breaks_csv(&rows).as_bytes(),
        )?;
        write_atomic(
            &out.join("fractures.csv"),
            analysis::fractures_csv(&fractures).as_bytes(),
        )?;
        if self.state.coupled.is_some() {
            let times: Vec<f64> = self.state.history.iter().map(|h| h.time).collect();
            write_atomic(
                &out.join("centerline_pressure.csv"),
                analysis::matrix_csv(&times, &self.state.center_x, &self.state.center_pressure)
                    .as_bytes(),
            )?;
            write_atomic(
                &out.join("centerline_speed.csv"),
                analysis::matrix_csv(&times, &self.state.center_x, &self.state.center_speed)
                    .as_bytes(),
            )?;
            if figures {
                let labels = self.scene.scene.units.labels();
                for (name, data, what) in [
                    (
                        "centerline_pressure.png",
                        &self.state.center_pressure,
                        format!("pore pressure above the drained ends ({})", labels.pressure),
                    ),
                    (
                        "centerline_speed.png",
                        &self.state.center_speed,
                        format!("fluid speed ({})", labels.velocity),
                    ),
                ] {
                    let path = out.join(name);
                    if let Err(e) =
                        figures::time_distance_png(&path, &times, &self.state.center_x, data, &what)
                    {
                        eprintln!("lbdem: WARNING: figure {} not drawn: {e}", path.display());
                    }
                }
            }
        }
        if figures {
            let path = out.join("rose.png");
            if let Err(e) = figures::rose_png(&path, &rows) {
                eprintln!("lbdem: WARNING: figure {} not drawn: {e}", path.display());
            }
            let path = out.join("breaks.png");
            let label = self
                .scene
                .scene
                .name
                .clone()
                .unwrap_or_else(|| "run".into());
            let series = vec![(
                label,
                self.state
                    .history
                    .iter()
                    .map(|h| (h.time, h.broken_bonds as f64))
                    .collect::<Vec<_>>(),
            )];
            if let Err(e) = figures::breaks_png(&path, &series) {
                eprintln!("lbdem: WARNING: figure {} not drawn: {e}", path.display());
            }
        }
        Ok(())
    }

    /// The breaks so far as rows, clustered into fractures.
    fn fractures(&self) -> (Vec<BreakRow>, Vec<Fracture>) {
        let rows: Vec<BreakRow> = self
            .dem()
            .breaks
            .iter()
            .map(|b| BreakRow::from_record(b, self.state.drop_step, self.state.dt))
            .collect();
        let link = 2.5 * self.scene.packing.radius_max;
        let fractures = cluster_fractures(&rows, link, 3);
        (rows, fractures)
    }

    /// The `results` of the summary.
    fn results(&self) -> serde_json::Value {
        let d = self.dem();
        let (rows, fractures) = self.fractures();
        let orientation = analysis::orientation_summary(&rows, &fractures);
        let permeability: Option<serde_json::Value> =
            serde_json::from_str(&self.state.permeability).ok();
        let packed: Option<serde_json::Value> = serde_json::from_str(&self.state.packed).ok();
        let last = self.state.history.last();
        let fluid = self.fluid().map(|fp| {
            json!({
                "nodes": fp.setup.nodes,
                "density_high": fp.setup.density_high,
                "density_low": fp.setup.density_low,
                "expected_mach": fp.setup.expected_mach,
                "nodes_per_grain": fp.setup.nodes_per_grain,
                "fluid_mass": fp.world.fluid.mass(),
            })
        });
        let mut v = json!({
            "packing": packed,
            "fluid": fluid,
            "model_time": self.state.steps_done as f64 * self.state.dt,
            "timestep": self.state.dt,
            "broken_bonds": d.breaks.len(),
            "total_bonds": d.bonds.len(),
            "final_axial_strain": last.map(|h| h.axial_strain),
            "final_lateral_strain": last.map(|h| h.lateral_strain),
            "fractures": fractures.len(),
            "orientation": orientation,
            "permeability": permeability,
            "grains_outside_lattice": self.state.outside,
        });
        // Present once a grain has left the lattice (a null would read as a non-finite result).
        if let (Some(t), Some(map)) = (self.state.first_outside, v.as_object_mut()) {
            map.insert("first_outside_time".into(), json!(t));
        }
        v
    }
}

impl<'a, S: std::ops::DerefMut<Target = FractureState>> FractureRun<'a, S> {
    /// One chunk: before the drop, the intact-sample measurements (when asked for), the first record and
    /// snapshot and the drop itself; after it, one record interval (with a snapshot when due, and the last one
    /// at the end). A stop request during the measurements abandons the chunk with the state untouched.
    fn advance(&mut self, dir: Option<&Path>, stop: &Stop) -> Result<()> {
        if !self.state.dropped {
            if self.state.coupled.is_some() && self.scene.output.permeability {
                match self.measure_permeability(stop)? {
                    Some(v) => self.state.permeability = v.to_string(),
                    None => return Ok(()),
                }
            }
            self.record()?;
            if let Some(d) = dir {
                self.snapshot(d)?;
            }
            self.drop_loads()?;
            self.state.drop_step = self.dem().step_count();
            self.state.dropped = true;
            return Ok(());
        }
        let (record_every, snapshot_every) = self.intervals();
        let total = self.total();
        let next_record = (self.state.steps_done / record_every + 1) * record_every;
        let target = next_record.min(total);
        while self.state.steps_done < target {
            self.step();
        }
        self.record()?;
        let due = self.state.steps_done.is_multiple_of(snapshot_every);
        if let Some(d) = dir {
            if due || self.state.steps_done >= total {
                self.snapshot(d)?;
            }
        }
        Ok(())
    }

    /// The drop at t = 0: axial stress and boundary fluid pressure.
    fn drop_loads(&mut self) -> Result<()> {
        let l = &self.scene.loading;
        let height = self.lateral_height();
        let damping = l.local_damping.unwrap_or(self.scene.solid.local_damping);
        let state: &mut FractureState = &mut self.state;
        match (&mut state.coupled, &mut state.dry) {
            (Some(w), _) => w.dem.local_damping = damping,
            (None, Some(d)) => d.local_damping = damping,
            _ => {}
        }
        let density_low = self.fluid().map(|f| f.setup.density_low);
        let state: &mut FractureState = &mut self.state;
        let ends = &state.ends;
        match &mut state.coupled {
            Some(w) => {
                // The applied loads live in `applied` for the coupled world.
                let mut scratch = vec![lbdem_kernels::math::Vector::zeros(); w.dem.particles.len()];
                spread_axial(&w.dem, ends, l.axial_stress_after, height, &mut scratch);
                for (a, f) in w.applied.iter_mut().zip(scratch) {
                    a.0 = f;
                }
                let lo = density_low.expect("fluid set-up");
                w.fluid.set_side_density(Side::West, lo)?;
                w.fluid.set_side_density(Side::East, lo)?;
            }
            None => {
                if let Some(d) = state.dry.as_mut() {
                    apply_axial(d, ends, l.axial_stress_after, height);
                }
            }
        }
        Ok(())
    }

    fn step(&mut self) {
        let state: &mut FractureState = &mut self.state;
        match (&mut state.coupled, &mut state.dry) {
            (Some(w), _) => w.step(),
            (None, Some(d)) => d.step(),
            (None, None) => {}
        }
        state.steps_done += 1;
    }

    fn record(&mut self) -> Result<()> {
        let time = self.state.steps_done as f64 * self.state.dt;
        let d = self.dem();
        let axial_strain =
            (self.state.reference[0] - end_distance(d, &self.state.ends)) / self.state.reference[0];
        let lateral_strain =
            (self.state.reference[1] - self.lateral_height()) / self.state.reference[1];
        let lateral_stress = 0.5
            * (d.platens[self.state.sample.bottom].stress()
                + d.platens[self.state.sample.top].stress());
        let broken = d.breaks.len();
        let ke = d.kinetic_energy();
        let band = self.scene.packing.radius_max;
        let mut lines = None;
        let (mean_p, max_speed) = match self.fluid() {
            Some(fp) => {
                let (rho, u) = fp.world.fluid.moments();
                let eps = fp.world.fluid.solid_fraction_map();
                let units = fp.setup.units;
                let p_scale = units.density * units.sound_speed * units.sound_speed;
                let c = units.lattice_speed;
                let [nx, ny] = fp.setup.nodes;
                let (lo, hi) = d.bounds();
                let x0 = ((lo[0] - self.state.center_x[0]) / units.spacing)
                    .ceil()
                    .max(0.0) as usize;
                let x1 = (((hi[0] - self.state.center_x[0]) / units.spacing).floor() as usize)
                    .min(nx - 1);
                let mut sum = 0.0;
                let mut weight = 0.0;
                let mut vmax: f64 = 0.0;
                for y in 0..ny {
                    for x in 0..nx {
                        let k = y * nx + x;
                        let r = rho[k];
                        let bad_velocity = !(u[k][0].is_finite() && u[k][1].is_finite());
                        if !(r.is_finite() && r > 0.5 && r < 1.5) || bad_velocity {
                            return Err(LbdemError::Diverged {
                                step: fp.world.steps(),
                                quantity: if bad_velocity { "velocity".into() } else { "lattice density".into() },
                                value: if bad_velocity { format!("{:?}", u[k]) } else { format!("{r}") },
                                x,
                                y,
                                out: String::new(),
                                hint: format!(
                                    "lower loading.pressure_drop, or refine fluid.timestep (a higher sound speed lowers the lattice density drop){}",
                                    crate::observe::health::side_crossings(fp.world)
                                ),
                            });
                        }
                        // Pore fluid only: fully covered nodes hold the fluid inside grains, which takes no part
                        // in the flow; partly covered ones count with their fluid fraction.
                        let wgt = 1.0 - eps[k];
                        if x >= x0 && x <= x1 {
                            sum += wgt * r;
                            weight += wgt;
                        }
                        if wgt > 0.0 {
                            vmax = vmax.max(u[k][0].hypot(u[k][1]));
                        }
                    }
                }
                // The centre line: at each x, the fluid-fraction-weighted mean over rows within one largest
                // grain radius of the centre row (a single row would mostly sample grain interiors).
                let row = fp.center_row;
                let half = ((band / units.spacing).round() as usize).max(1);
                let (ya, yb) = (row.saturating_sub(half), (row + half).min(ny - 1));
                let mut pline = vec![0.0; nx];
                let mut sline = vec![0.0; nx];
                for x in 0..nx {
                    let (mut sp, mut ss, mut sw) = (0.0, 0.0, 0.0);
                    for y in ya..=yb {
                        let k = y * nx + x;
                        let wgt = 1.0 - eps[k];
                        sp += wgt * rho[k];
                        ss += wgt * u[k][0].hypot(u[k][1]);
                        sw += wgt;
                    }
                    if sw > 0.0 {
                        pline[x] = p_scale * (sp / sw - fp.setup.density_low);
                        sline[x] = c * ss / sw;
                    } else {
                        pline[x] = f64::NAN;
                        sline[x] = f64::NAN;
                    }
                }
                lines = Some((pline, sline));
                let mean = sum / weight.max(1e-300);
                (p_scale * (mean - fp.setup.density_low), c * vmax)
            }
            None => (0.0, 0.0),
        };
        // Grains whose centre has left the fluid lattice (through the ends: beyond `fluid.margin`).
        let outside = self.fluid().map(|fp| {
            let h = fp.setup.units.spacing;
            let xs = &self.state.center_x;
            let (xa, xb) = (xs[0] - 0.5 * h, xs[xs.len() - 1] + 0.5 * h);
            let gone: Vec<usize> = d
                .particles
                .iter()
                .enumerate()
                .filter(|(_, g)| {
                    let x = g.position[0];
                    x.is_finite() && !(xa..=xb).contains(&x)
                })
                .map(|(i, _)| i)
                .collect();
            (gone, xa, xb, fp.world.steps())
        });
        let grains = d.particles.len();
        if let Some((pline, sline)) = lines {
            self.state.center_pressure.push(pline);
            self.state.center_speed.push(sline);
        }
        let axial_stress = if time > 0.0 || self.state.steps_done > 0 {
            self.scene.loading.axial_stress_after
        } else {
            self.scene.loading.axial_stress
        };
        self.state.history.push(HistoryRow {
            time,
            axial_strain,
            lateral_strain,
            lateral_stress,
            axial_stress,
            broken_bonds: broken,
            mean_pore_pressure: mean_p,
            max_speed,
            kinetic_energy: ke,
        });
        let Some((gone, xa, xb, step)) = outside else {
            return Ok(());
        };
        self.state.outside = gone.len();
        if gone.is_empty() {
            return Ok(());
        }
        if self.state.first_outside.is_none() {
            self.state.first_outside = Some(time);
            eprintln!(
                "lbdem: WARNING: fracture: {} of the {grains} grains left the fluid lattice ({xa:.4} to {xb:.4} cm along \
                 x) by t = {time:.4} s: beyond fluid.margin they feel no fluid; the run stops once more than {:.0} % \
                 have left",
                gone.len(),
                100.0 * MAX_OUTSIDE_FRACTION
            );
        }
        if gone.len() as f64 > MAX_OUTSIDE_FRACTION * grains as f64 {
            let first = gone[0];
            return Err(LbdemError::DivergedParticle {
                step,
                particle: first,
                quantity: "x position".into(),
                value: format!(
                    "{:.4} cm, outside the fluid lattice ({xa:.4} to {xb:.4} cm) with {} of the {grains} grains \
                     ({:.1} %) at t = {time:.4} s",
                    self.dem().particles[first].position[0],
                    gone.len(),
                    100.0 * gone.len() as f64 / grains as f64
                ),
                out: String::new(),
                hint: "the sample came apart and its grains left the lattice, where they feel no fluid: a larger \
                       loading.axial_stress_after holds the ends, a smaller loading.pressure_drop pushes the grains \
                       less, a wider fluid.margin only lets the run go on longer"
                    .into(),
            });
        }
        Ok(())
    }

    fn snapshot(&mut self, out: &Path) -> Result<()> {
        let n = self.state.snapshots;
        self.state.snapshots += 1;
        // Before the first coupled step the grains are not on the lattice yet: map them (the first step maps
        // the same grains again, bitwise the same coverage), so that the t = 0 lattice shows them.
        if let Some(w) = self.state.coupled.as_mut() {
            if w.steps() == 0 {
                w.map_grains();
            }
        }
        let d = self.dem();
        let title = self
            .scene
            .scene
            .name
            .clone()
            .unwrap_or_else(|| "lbdem fracture".into());
        let broken = d.broken_bond_fraction();
        let stamp = Stamp {
            time: self.state.steps_done as f64 * self.state.dt,
            title,
            units: Units::of(self.scene.scene.units),
        };
        // The pore pressure above the drained ends.
        let field = self.fluid().map(|fp| {
            let frame =
                LatticeFrame::of(&fp.setup.units, fp.world.map.origin, fp.setup.density_low);
            lattice_field(&fp.world.fluid, &frame)
        });
        if self.scene.output.vtk {
            let fluid = self.state.coupled.as_ref().map(|w| w.fluid_loads());
            let clock = BreakClock {
                origin_step: self.state.drop_step,
                dt: self.state.dt,
            };
            write_series(out, n, &stamp, d, fluid.as_deref(), clock, field.as_ref())?;
        }
        if self.scene.output.figures {
            let time = self.state.steps_done as f64 * self.state.dt;
            let png = out.join(format!("snapshot_{n:04}.png"));
            if let Err(e) = figures::snapshot_png(&png, d, &broken, field.as_ref(), time) {
                eprintln!("lbdem: WARNING: figure {} not drawn: {e}", png.display());
            }
            let png = out.join(format!("speed_{n:04}.png"));
            let unit = self.scene.scene.units.labels().velocity;
            if let Err(e) = figures::speed_png(&png, d, time, unit) {
                eprintln!("lbdem: WARNING: figure {} not drawn: {e}", png.display());
            }
        }
        Ok(())
    }
}

/// What `lbdem check` prints of a fracture scene: the DEM steps and, with a fluid, the lattice set-up.
#[derive(Clone, Debug, Serialize)]
pub struct FractureSetup {
    /// DEM critical step of the grains and bonds.
    pub critical_time_step: f64,
    /// Step of the run after the drop (the fluid's, or the DEM's without a fluid).
    pub timestep: f64,
    /// Steps after the drop.
    pub steps: u64,
    /// The fluid set-up (none for the dry control).
    pub fluid: Option<FluidSetup>,
    /// Warnings about the settings.
    pub warnings: Vec<String>,
}

impl crate::run::Derived for FractureSetup {
    fn warnings(&self) -> &[String] {
        &self.warnings
    }
}

/// The initial state of a fracture run from a packing made by [`pack`] for a scene with the same `[packing]`
/// and `[solid]` sections (e.g. the controls and variants of one sample, packed once).
pub fn start_packed(
    case: &Case<FractureTest>,
    exec: &Exec,
    packing: Packing<f64>,
) -> Result<FractureState> {
    let mut state = prepare_packed(&case.scene, packing)?;
    if let Some(w) = &mut state.coupled {
        exec.apply(&mut w.fluid);
    }
    Ok(state)
}

/// The fracture kind (dissertation ch. 6).
pub struct FractureTest;

impl Kind for FractureTest {
    const NAME: &'static str = "fracture";
    const NOT_MEASURED: &'static [&'static str] = &[
        "fluid",
        "permeability",
        "final_axial_strain",
        "final_lateral_strain",
        "crack_plane_mean_deg",
        "crack_plane_deviation_from_perpendicular_to_sigma3_deg",
        "fracture_trace_mean_deg",
        "fracture_trace_deviation_from_perpendicular_to_sigma3_deg",
    ];
    type Scene = FractureScene;
    type Setup = FractureSetup;
    type State = FractureState;

    fn validate(scene: &FractureScene) -> Result<()> {
        scene.validate()
    }

    fn budget(scene: &FractureScene, setup: &FractureSetup) -> Result<Budget> {
        let mut b = packing_budget(&scene.packing)?;
        // Settling steps before the loading (the loading steps are checked in `setup`).
        let settle = limits::count(
            "loading.settle_time",
            "the settling steps",
            scene.loading.settle_time / setup.timestep,
        )?;
        if settle > limits::MAX_STEPS {
            limits::steps("loading.settle_time", settle)?;
        }
        if let Some(f) = &setup.fluid {
            limits::lattice(
                &mut b,
                "fluid.spacing",
                "fluid lattice",
                f.nodes[0] as u64,
                f.nodes[1] as u64,
                8,
                limits::Solids::Covered,
            )?;
        }
        // Records and snapshots after the drop, at the steps of `FractureRun::intervals` (plus those at the drop
        // and at the end).
        let (record_every, snapshot_every) = scene.output.intervals(setup.timestep);
        let o = &scene.output;
        if o.vtk || o.figures {
            limits::snapshots_every("output.snapshot_interval", setup.steps, snapshot_every)?;
        }
        // A record is a history row (9 values) and, with a fluid, the pressure and the speed along the centre
        // line (at most one value per lattice column each).
        let columns = setup.fluid.as_ref().map_or(0, |f| f.nodes[0] as u64);
        b.add_items(
            "records",
            "output.record_interval",
            limits::records_every(setup.steps, record_every),
            limits::mul("fluid.spacing", "a record's size", columns, 16)?
                .saturating_add(9 * 8 + 3 * 24),
        )?;
        Ok(b)
    }

    fn setup(scene: &FractureScene) -> Result<FractureSetup> {
        let (critical, dt) = scene.timesteps()?;
        let mut warnings = Warnings::default();
        let fluid = match &scene.fluid {
            Some(f) => Some(scene.fluid_setup(f, &mut warnings)?),
            None => None,
        };
        Ok(FractureSetup {
            critical_time_step: critical,
            timestep: dt,
            steps: limits::steps_for("loading.duration", scene.loading.duration, dt, false)?,
            fluid,
            warnings: warnings.0,
        })
    }

    fn describe(case: &Case<Self>) -> String {
        case.scene
            .describe()
            .unwrap_or_else(|e| format!("  (not described: {e})\n"))
    }

    fn start(case: &Case<Self>, exec: &Exec) -> Result<FractureState> {
        start_packed(case, exec, pack(&case.scene)?)
    }

    fn lattices(state: &mut FractureState) -> Vec<&mut dyn ExecTarget> {
        state
            .coupled
            .as_mut()
            .map(|w| &mut w.fluid as &mut dyn ExecTarget)
            .into_iter()
            .collect()
    }

    fn check_resumed(_case: &Case<Self>, state: &FractureState) -> Result<()> {
        if state.coupled.is_some() == state.dry.is_some() {
            return Err(LbdemError::Checkpoint {
                path: String::new(),
                problem: "holds a fracture state without exactly one world".into(),
                hint: "the file was written by another lbdem version; start the run again".into(),
            });
        }
        Ok(())
    }

    fn steps_done(state: &FractureState) -> u64 {
        state.steps_done
    }

    fn total_steps(case: &Case<Self>, _state: &FractureState) -> Option<u64> {
        Some(case.setup.steps)
    }

    fn finished(case: &Case<Self>, state: &FractureState) -> bool {
        state.dropped && state.steps_done >= case.setup.steps
    }

    fn advance(case: &Case<Self>, state: &mut FractureState, dir: Option<&Path>) -> Result<()> {
        Self::advance_or_stop(case, state, dir, &Stop::new())
    }

    fn advance_or_stop(
        case: &Case<Self>,
        state: &mut FractureState,
        dir: Option<&Path>,
        stop: &Stop,
    ) -> Result<()> {
        FractureRun {
            scene: &case.scene,
            state,
        }
        .advance(dir, stop)
    }

    fn health(case: &Case<Self>, state: &FractureState) -> Result<()> {
        // The fluid's density band is checked by every record (which reads every node anyway).
        dem_health(
            FractureRun {
                scene: &case.scene,
                state,
            }
            .dem(),
        )
    }

    fn write_outputs(
        case: &Case<Self>,
        state: &FractureState,
        dir: &Path,
        stage: OutputStage,
    ) -> Result<()> {
        // Periodic checkpoints flush the tables too, so that a killed run keeps its records so far; the
        // figures (PNG, slow to draw) only at the end, on an interrupt and on divergence, never in the
        // stepping loop.
        FractureRun {
            scene: &case.scene,
            state,
        }
        .write_tables(dir, stage != OutputStage::Checkpoint)
    }

    fn results(case: &Case<Self>, state: &FractureState) -> Result<serde_json::Value> {
        Ok(FractureRun {
            scene: &case.scene,
            state,
        }
        .results())
    }
}

/// `lbdem compare-breaks`: the broken bonds against time of several fracture runs, overlaid in one PNG, each
/// labelled with its scene's name (from `DIR/scene.toml`) or its directory.
pub fn compare_breaks(dirs: &[std::path::PathBuf], out: &Path) -> Result<()> {
    if dirs.is_empty() {
        return Err(LbdemError::field(
            "dirs",
            "none",
            "no run directories given",
            "pass the output directories of one or more fracture runs",
        ));
    }
    let mut series = Vec::new();
    for dir in dirs {
        let path = dir.join("history.csv");
        let text = std::fs::read_to_string(&path).map_err(|e| LbdemError::ReadScene {
            path: path.display().to_string(),
            source: e,
        })?;
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
        let (Some(t), Some(b)) = (
            header.iter().position(|h| *h == "time"),
            header.iter().position(|h| *h == "broken_bonds"),
        ) else {
            return Err(LbdemError::field(
                "history.csv",
                path.display(),
                "has no time/broken_bonds columns",
                "give the output directory of a fracture run",
            ));
        };
        let pts: Vec<(f64, f64)> = lines
            .filter_map(|l| {
                let v: Vec<f64> = l.split(',').filter_map(|x| x.parse().ok()).collect();
                Some((*v.get(t)?, *v.get(b)?))
            })
            .collect();
        let label = std::fs::read_to_string(dir.join(SCENE_COPY))
            .ok()
            .and_then(|s| toml::from_str::<toml::Value>(&s).ok())
            .and_then(|v| v.get("scene")?.get("name")?.as_str().map(String::from))
            .unwrap_or_else(|| dir.display().to_string());
        series.push((label, pts));
    }
    figures::breaks_png(out, &series).map_err(|e| LbdemError::Write {
        path: out.display().to_string(),
        source: std::io::Error::other(e.to_string()),
    })?;
    eprintln!("lbdem: wrote {}", out.display());
    Ok(())
}

/// Mean x of the right end particles minus that of the left ones.
fn end_distance(w: &DemWorld<f64>, ends: &[Vec<usize>; 2]) -> f64 {
    let mean = |ids: &[usize]| {
        ids.iter().map(|&i| w.particles[i].position[0]).sum::<f64>() / ids.len().max(1) as f64
    };
    mean(&ends[1]) - mean(&ends[0])
}

/// The axial stress as forces on the end particles (pushing inwards), into `forces`.
fn spread_axial(
    w: &DemWorld<f64>,
    ends: &[Vec<usize>; 2],
    stress: f64,
    height: f64,
    forces: &mut [lbdem_kernels::math::Vector<f64>],
) {
    for (side, dir) in [(0usize, 1.0), (1, -1.0)] {
        let ids = &ends[side];
        let total: f64 = ids
            .iter()
            .map(|&i| w.particles[i].shape.bounding_radius())
            .sum();
        if total <= 0.0 {
            continue;
        }
        for &i in ids {
            let share = stress * height * w.particles[i].shape.bounding_radius() / total;
            forces[i] = lbdem_kernels::math::vector(dir * share, 0.0);
        }
    }
}

fn apply_axial(w: &mut DemWorld<f64>, ends: &[Vec<usize>; 2], stress: f64, height: f64) {
    let mut forces = vec![lbdem_kernels::math::Vector::zeros(); w.particles.len()];
    spread_axial(w, ends, stress, height, &mut forces);
    w.external_force = forces;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene_with_bands(bands: &str) -> FractureScene {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/fracture/quick/base.toml");
        let text = std::fs::read_to_string(path).unwrap() + bands;
        FractureScene::from_toml(&text, "test.toml").expect("valid scene")
    }

    #[test]
    fn heterogeneity_bands_select_the_grains_within_half_a_width_of_their_centre_line() {
        // Sample from x = 0 (left end) with its bottom at y = 0: mid-height y = 0.6 for the 1.2 cm quick sample.
        let s = scene_with_bands(
            "\n[[heterogeneity]]\nfluid_radius = 0.95\ncenter = 1.2\nwidth = 0.4\n\
             \n[[heterogeneity]]\nfluid_radius = 0.7\ncenter = 0.5\nwidth = 0.2\nangle = 45.0\n",
        );
        // Vertical band: |x − 1.2| ≤ 0.2 at any height.
        assert_eq!(s.band_radius(1.2, 0.0, 0.0, 0.0), Some(0.95));
        assert_eq!(s.band_radius(1.39, 1.1, 0.0, 0.0), Some(0.95));
        assert_eq!(s.band_radius(1.41, 0.6, 0.0, 0.0), None);
        // 45° band through (0.5, 0.6): its centre line passes (0.5 + d, 0.6 + d); half-width 0.1 across it.
        assert_eq!(s.band_radius(0.8, 0.9, 0.0, 0.0), Some(0.7));
        assert_eq!(
            s.band_radius(0.5, 0.9, 0.0, 0.0),
            None,
            "0.21 across the band"
        );
        // Offsets of the sample's left end and bottom shift the bands with it.
        assert_eq!(s.band_radius(11.2, 5.0, 10.0, 5.0), Some(0.95));
    }

    #[test]
    fn bands_need_a_fluid_and_a_radius_in_range() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/fracture/quick/dry.toml");
        let text = std::fs::read_to_string(path).unwrap()
            + "\n[[heterogeneity]]\nfluid_radius = 0.95\ncenter = 1.2\nwidth = 0.4\n";
        let err = FractureScene::from_toml(&text, "t.toml")
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("heterogeneity"), "{err}");
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/fracture/quick/base.toml");
        let text = std::fs::read_to_string(path).unwrap()
            + "\n[[heterogeneity]]\nfluid_radius = 0.0\ncenter = 1.2\nwidth = 0.4\n";
        let err = FractureScene::from_toml(&text, "t.toml")
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("heterogeneity[0].fluid_radius"), "{err}");
    }

    #[test]
    fn a_remap_tolerance_is_read_and_refused_outside_its_range() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/fracture/quick/base.toml");
        let base = std::fs::read_to_string(path).unwrap();
        let with = |value: &str| {
            base.replace(
                "\nfluid_radius =",
                &format!("\nremap_tolerance = {value}\nfluid_radius ="),
            )
        };
        let scene = FractureScene::from_toml(&with("0.05"), "t.toml").unwrap();
        assert_eq!(scene.fluid.as_ref().unwrap().remap_tolerance, 0.05);
        let scene = FractureScene::from_toml(&base, "t.toml").unwrap();
        assert_eq!(scene.fluid.as_ref().unwrap().remap_tolerance, 0.0);
        for bad in ["-0.01", "0.3", "nan"] {
            let err = FractureScene::from_toml(&with(bad), "t.toml")
                .err()
                .unwrap()
                .to_string();
            assert!(err.contains("fluid.remap_tolerance"), "{bad}: {err}");
        }
    }
}
