//! `kind = "fluid_compressibility"`: a closed box of fluid compressed by a rigid piston (dissertation ch. 4.5.4,
//! fig. 4.8–4.10, table 4.1). See [`FluidCompressibility`] for the set-up and what is measured.
use std::path::Path;

use lbdem_kernels::coupling::{BodyShape, CoupledBody};
use lbdem_kernels::fluid::boundary::{Boundaries, SideCondition};
use lbdem_kernels::fluid::collide::SolidOperator;
use lbdem_kernels::fluid::step::FluidParams;
use serde::{Deserialize, Serialize};

use crate::engine::exec::{Exec, ExecTarget};
use crate::engine::lattice::FluidLattice;
use crate::error::{positive, LbdemError, Result};
use crate::input::limits::{self, Budget};
use crate::observe::health::fluid_health;
use crate::run::{run_in_memory, Case, Kind, OutputStage, Persist, RunOptions};
use crate::scene::{CheckpointSection, SceneHeader, UnitsSetup};
use crate::units::{FluidSection, CS2};

/// Half-thickness of the compressibility piston (nodes).
const PISTON_HALF_THICKNESS: f64 = 1.5;

/// `[fluid_compressibility]`
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CompressibilitySection {
    /// Box length along x (the piston moves along x from the east end).
    pub length: f64,
    /// Box height along y.
    pub height: f64,
    /// Piston speed (physical), towards −x.
    pub piston_speed: f64,
    /// Piston travel (physical).
    pub travel: f64,
    /// Relaxation time after the piston stops (physical).
    pub settle: f64,
    /// Solid operator of the piston: `"lambda_consistent"` (ΩΛ, default, with TRT) or
    /// `"moving_wall_bounce_back"` (Ω₃, with BGK); see [`piston_operator`].
    #[serde(default)]
    pub solid_operator: Option<SolidOperator>,
}

/// A fluid-compressibility scene file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CompressibilityScene {
    /// `[scene]`
    pub scene: SceneHeader,
    /// `[fluid]`
    pub fluid: FluidSection,
    /// `[fluid_compressibility]`
    pub fluid_compressibility: CompressibilitySection,
    /// `[run]`
    #[serde(default)]
    pub run: CheckpointSection,
}

crate::scene::scene_file!(CompressibilityScene);

/// Outcome of a fluid-compressibility run.
#[derive(Clone, Debug, Serialize)]
pub struct CompressibilityOutcome {
    /// Lattice size.
    pub nodes: [usize; 2],
    /// Piston travel (nodes).
    pub travel: f64,
    /// Steps (moving + settling).
    pub steps: u64,
    /// Free-fluid (ε = 0) mean density change in the front (compressed) chamber, averaged over the second half
    /// of the settling.
    pub front_density_change: f64,
    /// Same, behind the piston (expanded chamber).
    pub back_density_change: f64,
    /// Relative volume change of the front chamber (ΔV/V₁, V = Σ(1 − ε) in front of the piston's mid-plane).
    pub volume_strain: f64,
    /// Measured compressibility (ΔV/V)/Δp, Δp = c_s² Δρ_front (physical 1/pressure).
    pub measured: f64,
    /// 1/(ρ₀ c_s²) from the units (eq. 4.19).
    pub expected: f64,
    /// measured / expected − 1.
    pub error: f64,
    /// Mean exchange force on the piston over its height, ⟨F_x⟩/H (lattice), same window.
    pub piston_stress: f64,
    /// Compressibility from the piston force, (Δρ_front − Δρ_back)/(ρ₀ ⟨F_x⟩/H) (physical); see
    /// [`FluidCompressibility`].
    pub force_based: f64,
    /// force_based / expected − 1.
    pub force_based_error: f64,
    /// Relative amplitude (max − min over mean) of the piston force in the averaging window.
    pub stress_ripple: f64,
}

/// The piston as the fluid sees it: a very flat ellipse (semi-minor axis `half_thickness`, spanning 100× the
/// box height `ny`) whose west face is at `face`, moving at `v` (lattice units). The kind uses
/// [`PISTON_HALF_THICKNESS`]; the `piston_probe` example varies it.
pub fn piston_body(face: f64, v: f64, ny: usize, half_thickness: f64) -> CoupledBody<f64> {
    CoupledBody {
        center: lbdem_kernels::math::vector(face + half_thickness, 0.5 * (ny - 1) as f64),
        velocity: lbdem_kernels::math::vector(v, 0.0),
        spin: 0.0,
        shape: BodyShape::Ellipse {
            semi_major: 50.0 * ny as f64,
            semi_minor: half_thickness,
            angle: 0.5 * std::f64::consts::PI,
        },
    }
}

fn piston(face: f64, v: f64, ny: usize) -> CoupledBody<f64> {
    piston_body(face, v, ny, PISTON_HALF_THICKNESS)
}

/// The fluid volume Σ(1 − ε) of the nodes west of `mid`.
fn front_volume(eps: &[f64], nx: usize, mid: f64) -> f64 {
    eps.iter()
        .enumerate()
        .filter(|(i, _)| ((i % nx) as f64) < mid)
        .map(|(_, e)| 1.0 - e)
        .sum::<f64>()
}

/// The run: the lattice, the piston's position and the sums of the averaging window.
#[derive(Serialize, Deserialize)]
pub struct CompressibilityState {
    fluid: FluidLattice<f64>,
    nx: usize,
    ny: usize,
    speed: f64,
    move_steps: u64,
    settle_steps: u64,
    face: f64,
    v0: f64,
    v1: f64,
    f_sum: f64,
    f_min: f64,
    f_max: f64,
    fcount: u64,
    front_sum: f64,
    back_sum: f64,
    count: u64,
    s: u64,
}

impl Persist for CompressibilityState {}

impl CompressibilityState {
    fn new(case: &Case<FluidCompressibility>, exec: &Exec) -> Result<Self> {
        let c = &case.scene.fluid_compressibility;
        let u = &case.setup.units;
        let nx = u.length_to_lattice(c.length).round() as usize + 1;
        let ny = u.length_to_lattice(c.height).round() as usize + 1;
        let travel = u.length_to_lattice(c.travel);
        let speed = u.velocity_to_lattice(c.piston_speed);
        let move_steps = (2.0 * travel / speed).round().max(1.0) as u64;
        let settle_steps = u.time_to_steps(c.settle).round().max(2.0) as u64;
        let mut fluid = FluidLattice::<f64>::new(
            nx,
            ny,
            Boundaries {
                west: SideCondition::Wall,
                east: SideCondition::Wall,
                south: SideCondition::Wall,
                north: SideCondition::Wall,
            },
            FluidParams {
                tau: u.tau,
                force: [0.0; 2],
            },
        )?;
        exec.apply(&mut fluid);
        let (collision, op) = piston_operator(c)?;
        fluid.set_collision(crate::units::collision_of(
            case.scene.fluid.checked_collision(collision, u.tau)?,
        )?)?;
        fluid.set_solid_operator(op);
        fluid.set_lambda_terms(case.scene.fluid.lambda_terms(op)?)?;
        // The piston: an ellipse 2b = 3 nodes thick with its major axis along y, 50 × the box height long, so
        // its faces are flat to (H/2)²/(2a) · b/a ≈ 1e-5 nodes across the box. Fluid fills the chamber behind
        // it.
        let face = 0.6 * (nx - 1) as f64;
        fluid.cover_with_bodies(&[piston(face, 0.0, ny)], op.weighting());
        let v0 = front_volume(
            &fluid.solid_fraction_map(),
            nx,
            face + PISTON_HALF_THICKNESS,
        );
        Ok(Self {
            fluid,
            nx,
            ny,
            speed,
            move_steps,
            settle_steps,
            face,
            v0,
            v1: v0,
            f_sum: 0.0,
            f_min: f64::INFINITY,
            f_max: f64::NEG_INFINITY,
            fcount: 0,
            front_sum: 0.0,
            back_sum: 0.0,
            count: 0,
            s: 0,
        })
    }

    fn total(&self) -> u64 {
        self.move_steps + self.settle_steps
    }

    /// Up to 1000 steps: move the piston (sin² velocity profile), then let the fluid settle, summing the
    /// piston force and the chamber densities over the second half of the settling.
    fn advance(&mut self) {
        let (nx, ny, speed, move_steps) = (self.nx, self.ny, self.speed, self.move_steps);
        let total = self.total();
        let window = total - self.settle_steps / 2;
        let end = ((self.s / 1000 + 1) * 1000).min(total);
        for s in self.s..end {
            let v = if s < move_steps {
                let a = std::f64::consts::PI * (s as f64 + 0.5) / move_steps as f64;
                -speed * a.sin() * a.sin()
            } else {
                0.0
            };
            let wf = self.fluid.solid_operator().weighting();
            self.fluid
                .cover_with_bodies(&[piston(self.face, v, ny)], wf);
            self.fluid.step();
            self.face += v;
            if s >= window {
                let fx = self.fluid.solid_forces(1)[0][0];
                self.f_sum += fx;
                self.f_min = self.f_min.min(fx);
                self.f_max = self.f_max.max(fx);
                self.fcount += 1;
            }
            // Densities every 7th step of the window (both parities of any period-2 mode are sampled).
            if s >= window && (s - window).is_multiple_of(7) {
                let eps = self.fluid.solid_fraction_map();
                self.v1 = front_volume(&eps, nx, self.face + PISTON_HALF_THICKNESS);
                let (rho, _) = self.fluid.moments();
                // Free-fluid (ε = 0) mean density in front of the piston minus behind it.
                let mean = |front: bool| {
                    let (sum, n) = rho
                        .iter()
                        .zip(&eps)
                        .enumerate()
                        .filter(|(i, (_, e))| {
                            **e == 0.0 && (((i % nx) as f64) < self.face) == front
                        })
                        .fold((0.0, 0usize), |(a, n), (_, (r, _))| (a + r, n + 1));
                    sum / n.max(1) as f64
                };
                self.front_sum += mean(true);
                self.back_sum += mean(false);
                self.count += 1;
            }
        }
        self.s = end;
    }

    fn outcome(&self, case: &Case<FluidCompressibility>) -> CompressibilityOutcome {
        let units = &case.setup.units;
        let (nx, ny, face, total) = (self.nx, self.ny, self.face, self.total());
        let (f_sum, fcount, front_sum, back_sum, count) = (
            self.f_sum,
            self.fcount,
            self.front_sum,
            self.back_sum,
            self.count,
        );
        let (v0, v1, f_min, f_max) = (self.v0, self.v1, self.f_min, self.f_max);
        let fx = f_sum / fcount as f64;
        let front = front_sum / count as f64 - 1.0;
        let back = back_sum / count as f64 - 1.0;
        // The wall rows are half a spacing inside the walls: the face the fluid presses on is ny spacings high.
        let piston_stress = fx / ny as f64;
        let volume_strain = (v0 - v1) / v1;
        let measured = volume_strain / units.pressure_to_physical(CS2 * front);
        let force_based = (front - back) / units.pressure_to_physical(piston_stress);
        let expected = units.compressibility;
        CompressibilityOutcome {
            nodes: [nx, ny],
            travel: (0.6 * (nx - 1) as f64) - face,
            steps: total,
            front_density_change: front,
            back_density_change: back,
            volume_strain,
            measured,
            expected,
            error: measured / expected - 1.0,
            piston_stress,
            force_based,
            force_based_error: force_based / expected - 1.0,
            stress_ripple: (f_max - f_min) / fx,
        }
    }
}

/// Run a fluid-compressibility case in memory to its end.
pub fn simulate(case: &Case<FluidCompressibility>) -> Result<CompressibilityOutcome> {
    let (state, _) = run_in_memory(case, &RunOptions::default())?;
    Ok(state.outcome(case))
}

/// The piston's solid operator and the collision that goes with it (`[fluid] collision` overrides): ΩΛ with
/// TRT unless `solid_operator` names Ω₃ (then BGK). The operators that let the fluid's pressure through a fully
/// covered body (Ω₁, Ω₁ₗ, Ω₂: the two chambers equalise, Δρ ≈ 1e-5 instead of 1.6e-2) are refused.
pub fn piston_operator(
    c: &CompressibilitySection,
) -> Result<(crate::units::CollisionName, SolidOperator)> {
    use crate::units::CollisionName;
    match c.solid_operator {
        None | Some(SolidOperator::LambdaConsistent) => {
            Ok((CollisionName::Trt, SolidOperator::LambdaConsistent))
        }
        Some(SolidOperator::MovingWallBounceBack) => {
            Ok((CollisionName::Bgk, SolidOperator::MovingWallBounceBack))
        }
        Some(op) => Err(LbdemError::field(
            "fluid_compressibility.solid_operator",
            op.name(),
            "lets the fluid's pressure through the fully covered piston (the two chambers equalise)",
            "use \"lambda_consistent\" (the default) or \"moving_wall_bounce_back\"",
        )),
    }
}

/// The fluid-compressibility kind (ch. 4.5.4, fig. 4.8–4.10, table 4.1).
///
/// DEM platens do not act on the fluid in lbdem (the coupling sees particles only), so the platen is a rigid
/// body the PSM coverage supports: a very flat ellipse (3 nodes thick, 100 box heights long, major axis along
/// y) spanning every row of a walled box, so nothing leaks past it. Its solid operator is ΩΛ with TRT
/// ([`piston_operator`]; Ω₃ selectable): both seal the fully covered nodes (ΩΛ and Ω₃ bounce back what
/// arrives from outside the body; Ω₁ and Ω₁ₗ were tried and let the two chambers equalise through the
/// piston). It moves west with a smooth sin² velocity profile by `travel`, stops, and the fluid settles: the
/// west chamber is compressed, the east one (behind the piston) expanded. (A piston reaching the east wall
/// does not work: the fluid carried inside it moves with it and leaves a void at the wall, density 0.34 after
/// half a spacing of travel.)
///
/// **Measured**: (1) the compressibility of the front chamber, β = (ΔV/V)/Δp with ΔV/V from the piston's
/// coverage and Δp = c_s² Δρ of its free fluid, against 1/(ρ₀ c_s²) (eq. 4.19) in physical units through
/// [`LatticeUnits`]: this checks that the moving PSM piston is tight and that the lattice fluid's density
/// follows its volume as a fluid of that compressibility; (2) the dissertation's platen version,
/// β = Δρ/(ρ₀ σ) with σ the stress on the platen, here (Δρ_front − Δρ_back)/(ρ₀ ⟨F_x⟩/H). Under Ω₃ (2) is
/// 2.4× off at 3 nodes thickness and 8× at 10 (issue 14 item 4; `examples/piston_probe.rs` takes the exchange
/// apart node by node): every row of the piston carries its share c_s² Δρ of the pressure force to 1e-5
/// except the two rows that touch the north and south walls, which carry 70× it. While the piston moves, Ω₃'s
/// moving-wall term 6 w_i ρ c_i·u_s puts momentum into the diagonal populations of those rows; after it stops,
/// each such population is reversed by the piston's bounce-back and by the wall's half-way bounce-back in turn
/// and never relaxes (a fully covered Ω₃ node never collides): a standing loop that pushes the piston and the
/// walls apart for ever (fluid momentum −1.0 trapped there; with periodic north/south sides the force is
/// right to 1e-5). ΩΛ redistributes the populations that come from inside the body or from a wall to the
/// solid's equilibrium, so no loop survives: the force is right to 0.3 % (the two wall rows carry 5/6 of a
/// share) at 3 and at 10 nodes thickness.
///
/// [`LatticeUnits`]: crate::units::LatticeUnits
pub struct FluidCompressibility;

impl Kind for FluidCompressibility {
    const NAME: &'static str = "fluid_compressibility";
    const OWN_SECTION: Option<&'static str> = Some("fluid_compressibility");
    type Scene = CompressibilityScene;
    type Setup = UnitsSetup;
    type State = CompressibilityState;

    fn validate(scene: &CompressibilityScene) -> Result<()> {
        let u = crate::scene::f64_bgk_units(&scene.scene, &scene.fluid)?;
        let (collision, op) = piston_operator(&scene.fluid_compressibility)?;
        scene.fluid.checked_collision(collision, u.tau)?;
        scene.fluid.lambda_terms(op)?;

        let c = &scene.fluid_compressibility;
        positive("fluid_compressibility.length", c.length, "box length")?;
        positive("fluid_compressibility.height", c.height, "box height")?;
        positive(
            "fluid_compressibility.piston_speed",
            c.piston_speed,
            "piston speed",
        )?;
        positive("fluid_compressibility.travel", c.travel, "piston travel")?;
        positive("fluid_compressibility.settle", c.settle, "settling time")?;
        if c.travel > 0.1 * c.length {
            return Err(LbdemError::field(
                "fluid_compressibility.travel",
                c.travel,
                "exceeds 10 % of the box length: the lattice fluid is only weakly compressible",
                "use a travel of a few lattice spacings",
            ));
        }
        if u.mach(c.piston_speed) > 0.05 {
            return Err(LbdemError::field(
                "fluid_compressibility.piston_speed",
                c.piston_speed,
                "exceeds Mach 0.05",
                "slow the piston",
            ));
        }
        Ok(())
    }

    fn budget(scene: &CompressibilityScene, setup: &UnitsSetup) -> Result<Budget> {
        let c = &scene.fluid_compressibility;
        let u = &setup.units;
        let nx = limits::add(
            "fluid_compressibility.length",
            "the box length in nodes",
            limits::count(
                "fluid_compressibility.length",
                "the box length in nodes",
                u.length_to_lattice(c.length),
            )?,
            1,
        )?;
        let ny = limits::add(
            "fluid_compressibility.height",
            "the box height in nodes",
            limits::count(
                "fluid_compressibility.height",
                "the box height in nodes",
                u.length_to_lattice(c.height),
            )?,
            1,
        )?;
        let travel = u.length_to_lattice(c.travel);
        let speed = u.velocity_to_lattice(c.piston_speed);
        let moving = limits::count(
            "fluid_compressibility.piston_speed",
            "the piston steps",
            2.0 * travel / speed,
        )?;
        let settle = limits::count(
            "fluid_compressibility.settle",
            "the settling steps",
            u.time_to_steps(c.settle),
        )?;
        limits::steps(
            "fluid_compressibility.settle",
            limits::add(
                "fluid_compressibility.settle",
                "the step count",
                moving,
                settle,
            )?
            .max(1),
        )?;
        let mut b = Budget::new();
        limits::lattice(
            &mut b,
            "fluid_compressibility.length",
            "box lattice",
            nx,
            ny,
            8,
            limits::Solids::Covered,
        )?;
        Ok(b)
    }

    fn setup(scene: &CompressibilityScene) -> Result<UnitsSetup> {
        UnitsSetup::new(&scene.fluid)
    }

    fn describe(case: &Case<Self>) -> String {
        let labels = case.scene.scene.units.labels();
        let c = &case.scene.fluid_compressibility;
        let u = &case.setup.units;
        case.setup.describe(labels)
            + &format!(
                "  box {:.0} x {:.0} nodes; piston speed {:.3e} (lattice, Mach {:.3e}), travel {:.2} nodes\n",
                u.length_to_lattice(c.length),
                u.length_to_lattice(c.height),
                u.velocity_to_lattice(c.piston_speed),
                u.mach(c.piston_speed),
                u.length_to_lattice(c.travel)
            )
    }

    fn start(case: &Case<Self>, exec: &Exec) -> Result<CompressibilityState> {
        CompressibilityState::new(case, exec)
    }

    fn lattices(state: &mut CompressibilityState) -> Vec<&mut dyn ExecTarget> {
        vec![&mut state.fluid]
    }

    fn steps_done(state: &CompressibilityState) -> u64 {
        state.s
    }

    fn total_steps(_case: &Case<Self>, state: &CompressibilityState) -> Option<u64> {
        Some(state.total())
    }

    fn finished(_case: &Case<Self>, state: &CompressibilityState) -> bool {
        state.s >= state.total()
    }

    fn advance(
        _case: &Case<Self>,
        state: &mut CompressibilityState,
        _dir: Option<&Path>,
    ) -> Result<()> {
        state.advance();
        Ok(())
    }

    fn health(_case: &Case<Self>, state: &CompressibilityState) -> Result<()> {
        fluid_health(&state.fluid, "slow the piston or shorten its travel")
    }

    fn write_outputs(
        _case: &Case<Self>,
        _state: &CompressibilityState,
        _dir: &Path,
        _stage: OutputStage,
    ) -> Result<()> {
        // Everything it measures is in the summary.
        Ok(())
    }

    fn results(case: &Case<Self>, state: &CompressibilityState) -> Result<serde_json::Value> {
        Ok(serde_json::to_value(state.outcome(case)).unwrap_or_default())
    }
}
