//! `lbdem study speed-vs-error`: what accuracy does a second of wall time buy, in f32 and in f64?
//!
//! Three validation problems are run over a ladder of resolutions in both precisions:
//!
//! * `poiseuille_pressure`: the channel of `scenes/poiseuille.toml` (Zou–He pressure inlet/outlet, H = 0.22 cm,
//!   L = 4H, τ = 0.875, ν = 0.1 cm²/s) with `ny` nodes across; error = relative L2 error of the mid-section
//!   velocity profile against the parabola.
//! * `poiseuille_body_force`: the periodic channel of `scenes/poiseuille_body_force.toml` (H = 0.176 cm, but
//!   L = H, so ny × ny nodes) but at the τ = 0.875 of table 4.1 rather than the "magic" τ = ½ + √(3/16), where half-way
//!   bounce-back is exact, so that the error shows the method's second-order convergence; same error measure.
//! * `cylinder_array`: the periodic square array of discs at solid fraction c = 0.4, cell side `l` nodes;
//!   error = |F/(μU) / Sangani–Acrivos − 1|. With a τ axis: every resolution is run with each
//!   [`ArrayMethod`] — the dissertation's Ω₁ with BGK and the τ-independent ΩΛ with TRT (Λ = 3/16) — at each τ
//!   of [`StudyPlan::array_variants`] ([`ArrayCase::stokes`], drive for U = 1e-3 whatever τ). A larger τ is a larger
//!   viscosity in lattice units: the flow settles in fewer steps (∝ 1/ν), which is cheaper, and with ΩΛ costs no
//!   accuracy; with Ω₁/BGK the drag moves with τ (README, "Results that do not depend on τ").
//!
//! Resolution changes h at fixed τ (so Δt ∝ h², diffusive scaling) and fixed physical size; the drive is
//! scaled to hold the lattice centreline speed at 0.01 (Mach 0.017), so the Stokes-flow relative error is
//! that of the physical problem and the compressibility error falls with h (pressure drop ∝ 1/ny in lattice
//! density). Work per run is fixed and identical for both precisions: channels run 25 e-foldings of the slowest
//! viscous mode (time constant H²/(π²ν), residual e⁻²⁵ ≈ 1e-11) plus 40 sound crossings of the length for the
//! pressure drive; the array runs to its steady criterion in f64, and the f32 run takes exactly as many steps
//! (f32 cannot meet a 1e-7 flux-change tolerance reliably). The f32 − f64 difference of the errors is
//! therefore roundoff alone.
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use lbdem_kernels::Real;
use serde::Serialize;

use crate::engine::exec::Exec;
use crate::error::{LbdemError, Result};
use crate::kinds::channel::{simulate, Channel, ChannelScene};
use crate::kinds::cylinder_array::{solve_array_with, ArrayCase};
use crate::output::plot::{loglog_png, LogLogPlot, Marker, Series};
use crate::output::write_atomic;
use crate::run::Case;
use crate::scene::Precision;
use lbdem_kernels::fluid::collide::{Collision, SolidOperator, Trt};

/// The problems of the study.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Problem {
    /// Pressure-driven channel (Zou–He).
    PoiseuillePressure,
    /// Body-force-driven periodic channel.
    PoiseuilleBodyForce,
    /// Periodic square cylinder array, c = 0.4.
    CylinderArray,
}

impl Problem {
    /// Name used in the CSV and tables.
    pub fn name(self) -> &'static str {
        match self {
            Self::PoiseuillePressure => "poiseuille_pressure",
            Self::PoiseuilleBodyForce => "poiseuille_body_force",
            Self::CylinderArray => "cylinder_array",
        }
    }

    /// What the resolution counts.
    pub fn resolution_meaning(self) -> &'static str {
        match self {
            Self::PoiseuillePressure | Self::PoiseuilleBodyForce => "nodes across the channel",
            Self::CylinderArray => "cell side l (nodes)",
        }
    }

    /// What the error measures.
    pub fn error_meaning(self) -> &'static str {
        match self {
            Self::PoiseuillePressure | Self::PoiseuilleBodyForce => {
                "relative L2 error of the velocity profile"
            }
            Self::CylinderArray => "relative drag error vs Sangani-Acrivos",
        }
    }
}

/// Solid fraction of the cylinder-array problem.
pub const ARRAY_SOLID_FRACTION: f64 = 0.4;
/// τ of the cylinder-array problem (inside the τ band 0.6–0.9 where the PSM drag of `driver/tests/porous.rs` was measured).
pub const ARRAY_TAU: f64 = 0.8;
/// τ of both channel problems (table 4.1).
pub const CHANNEL_TAU: f64 = 0.875;
/// Method column of the channel rows (BGK, no solids).
pub const CHANNEL_METHOD: &str = "bgk";
/// Lattice centreline speed the channel drives are scaled to.
pub const CHANNEL_LATTICE_SPEED: f64 = 0.01;
/// The fluid collision and solid operator of a cylinder-array run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ArrayMethod {
    /// BGK with Ω₁ (non-equilibrium bounce-back, Noble–Torczynski weighting): the dissertation's method.
    BgkOmega1,
    /// TRT (Λ = 3/16) with ΩΛ (B = ε): the τ-independent combination, the kind's default.
    TrtLambda,
}

impl ArrayMethod {
    /// Name used in the CSV and tables.
    pub fn name(self) -> &'static str {
        match self {
            Self::BgkOmega1 => "bgk_omega1",
            Self::TrtLambda => "trt_lambda",
        }
    }

    /// The array case at cell side `l` and relaxation time `tau` with this method.
    pub fn case(self, l: usize, tau: f64) -> ArrayCase {
        let mut case = ArrayCase::stokes(l, ARRAY_SOLID_FRACTION, tau);
        if self == Self::TrtLambda {
            case.collision = Collision::Trt(Trt::default());
            case.solid_operator = SolidOperator::LambdaConsistent;
        }
        case
    }
}

/// Error budgets the recommendations are given for.
pub const BUDGETS: [f64; 3] = [0.1, 0.01, 0.001];

/// The resolution ladder of each problem.
#[derive(Clone, Debug)]
pub struct StudyPlan {
    /// (problem, resolutions) in run order.
    pub ladders: Vec<(Problem, Vec<usize>)>,
    /// The (τ, method) variants the cylinder array's ladder is run with, in run order.
    pub array_variants: Vec<(f64, ArrayMethod)>,
}

impl StudyPlan {
    /// The full study: the channels and the array at τ = 0.8, 1.4 and 2 with both methods; about 20 minutes in
    /// release mode with one thread on the shared 2-core development machine (the l = 160 arrays at τ = 0.8
    /// are half of it).
    pub fn full() -> Self {
        Self {
            ladders: vec![
                (Problem::PoiseuillePressure, vec![5, 11, 21, 41]),
                (Problem::PoiseuilleBodyForce, vec![5, 11, 21, 41, 81]),
                (Problem::CylinderArray, vec![10, 20, 40, 80, 160]),
            ],
            array_variants: [ARRAY_TAU, 1.4, 2.0]
                .into_iter()
                .flat_map(|t| [(t, ArrayMethod::BgkOmega1), (t, ArrayMethod::TrtLambda)])
                .collect(),
        }
    }

    /// A few seconds: the coarse end of every ladder.
    pub fn quick() -> Self {
        Self {
            ladders: vec![
                (Problem::PoiseuillePressure, vec![5, 9]),
                (Problem::PoiseuilleBodyForce, vec![5, 9, 17]),
                (Problem::CylinderArray, vec![10, 20]),
            ],
            // The earlier study's array (τ = 0.8, Ω₁ with BGK) and the default one at τ = 2.
            array_variants: vec![
                (ARRAY_TAU, ArrayMethod::BgkOmega1),
                (2.0, ArrayMethod::TrtLambda),
            ],
        }
    }

    /// The (τ, method) variants of `problem`: `array_variants` for the array, the one BGK variant at
    /// [`CHANNEL_TAU`] for the channels.
    pub fn variants(&self, problem: Problem) -> Vec<(f64, &'static str)> {
        match problem {
            Problem::CylinderArray => self
                .array_variants
                .iter()
                .map(|&(t, m)| (t, m.name()))
                .collect(),
            _ => vec![(CHANNEL_TAU, CHANNEL_METHOD)],
        }
    }
}

/// One run of the study.
#[derive(Clone, Debug, Serialize)]
pub struct StudyRow {
    /// Problem.
    pub problem: Problem,
    /// "f32" or "f64".
    pub precision: &'static str,
    /// Nodes across the channel, or the cell side of the array.
    pub resolution: usize,
    /// Relaxation time τ.
    pub tau: f64,
    /// Collision and solid operator ([`ArrayMethod::name`], or "bgk" for the channels).
    pub method: &'static str,
    /// Lattice nodes.
    pub nodes: usize,
    /// Steps run.
    pub steps: u64,
    /// Wall-clock seconds of the stepping (std::time::Instant).
    pub wall_seconds: f64,
    /// Million lattice-node updates per second.
    pub mlups: f64,
    /// |relative error| (see [`Problem::error_meaning`]).
    pub relative_error: f64,
    /// The error with its sign (simulated − reference for the drag; the L2 error is ≥ 0).
    pub signed_error: f64,
    /// Rayon worker threads.
    pub threads: usize,
}

impl StudyRow {
    /// Lattice-node updates (machine-independent cost).
    pub fn node_updates(&self) -> f64 {
        self.nodes as f64 * self.steps as f64
    }
}

const POISEUILLE_PRESSURE: &str = include_str!("../../scenes/poiseuille.toml");
const POISEUILLE_BODY_FORCE: &str = include_str!("../../scenes/poiseuille_body_force.toml");

/// The channel scene of `problem` at `ny` nodes across, in precision `precision`.
pub fn channel_scene(problem: Problem, ny: usize, precision: Precision) -> Result<ChannelScene> {
    let (text, path) = match problem {
        Problem::PoiseuillePressure => (POISEUILLE_PRESSURE, "scenes/poiseuille.toml"),
        Problem::PoiseuilleBodyForce => {
            (POISEUILLE_BODY_FORCE, "scenes/poiseuille_body_force.toml")
        }
        Problem::CylinderArray => {
            return Err(LbdemError::field(
                "problem",
                problem.name(),
                "is not a channel problem",
                "use solve_array for the cylinder array",
            ))
        }
    };
    if ny < 2 {
        return Err(LbdemError::field(
            "resolution",
            ny,
            "a channel needs at least 2 nodes across",
            "use 5 or more nodes across the channel",
        ));
    }
    let mut scene = ChannelScene::from_toml(text, path)?;
    scene.scene.precision = precision;
    scene.fluid.tau = Some(CHANNEL_TAU);
    scene.fluid.timestep = None;
    let c = scene
        .channel
        .as_mut()
        .expect("channel scene files have [channel]");
    let width = c.width;
    let h = width / ny as f64;
    scene.fluid.spacing = h;
    let nu = scene.fluid.viscosity;
    let mu = scene.fluid.density * nu;
    let nu_lattice = crate::units::lattice_viscosity(CHANNEL_TAU);
    let dt = nu_lattice * h * h / nu;
    // Physical centreline speed that is CHANNEL_LATTICE_SPEED in lattice units, and the gradient giving it.
    let u_max = CHANNEL_LATTICE_SPEED * h / dt;
    let gradient = 8.0 * mu * u_max / (width * width);
    let slowest_mode = (ny * ny) as f64 / (std::f64::consts::PI.powi(2) * nu_lattice);
    let mut steps = (25.0 * slowest_mode).ceil() as u64;
    match problem {
        Problem::PoiseuillePressure => {
            let length = 4.0 * width;
            c.length = length;
            c.pressure_drop = Some(gradient * length);
            // 40 sound crossings of the 4·ny spacings of the channel (c_s = 1/√3) for the acoustic transient.
            steps += (40.0 * 4.0 * ny as f64 * 3f64.sqrt()).ceil() as u64;
        }
        _ => {
            // A square periodic box (the flow is uniform along x, so nx only sets the work): nx = ny gives a
            // lattice big enough for the throughput to be that of the stepping, not of per-step overheads.
            c.length = width;
            c.acceleration = Some(gradient / scene.fluid.density);
        }
    }
    scene.run.steps = Some(steps);
    scene.run.duration = None;
    scene.run.steady_tolerance = None;
    scene.run.check_interval = Some(1000);
    Ok(scene)
}

fn threads() -> usize {
    rayon::current_num_threads()
}

fn run_channel_case<T: Real>(problem: Problem, ny: usize, exec: &Exec) -> Result<StudyRow> {
    let precision = if T::NAME == "f32" {
        Precision::F32
    } else {
        Precision::F64
    };
    let case = Case::<Channel>::new(channel_scene(problem, ny, precision)?)?;
    let setup = &case.setup;
    let out = simulate(&case, exec)?;
    Ok(StudyRow {
        problem,
        precision: T::NAME,
        resolution: ny,
        tau: CHANNEL_TAU,
        method: CHANNEL_METHOD,
        nodes: setup.nx * setup.ny,
        steps: out.steps,
        wall_seconds: out.wall_seconds,
        mlups: out.mlups,
        relative_error: out.l2_error.abs(),
        signed_error: out.l2_error,
        threads: threads(),
    })
}

fn array_row<T: Real>(case: &ArrayCase, method: ArrayMethod, exec: &Exec) -> Result<StudyRow> {
    let r = solve_array_with::<T>(case, exec)?;
    let err = r.drag_error.ok_or_else(|| {
        LbdemError::field(
            "solid_fraction",
            case.solid_fraction,
            "has no tabulated Sangani-Acrivos drag",
            "use a tabulated c (0.05, 0.1, ..., 0.75)",
        )
    })?;
    let nodes = case.cell * case.cell;
    Ok(StudyRow {
        problem: Problem::CylinderArray,
        precision: T::NAME,
        resolution: case.cell,
        tau: case.tau,
        method: method.name(),
        nodes,
        steps: r.steps,
        wall_seconds: r.wall_seconds,
        mlups: nodes as f64 * r.steps as f64 / r.wall_seconds.max(1e-12) / 1e6,
        relative_error: err.abs(),
        signed_error: err,
        threads: threads(),
    })
}

/// Run the cylinder array at cell side `l`, relaxation time `tau`, with `method`: f64 to its steady criterion,
/// then f32 for exactly as many steps.
fn run_array_pair(l: usize, tau: f64, method: ArrayMethod, exec: &Exec) -> Result<[StudyRow; 2]> {
    let case = method.case(l, tau);
    let r64 = array_row::<f64>(&case, method, exec)?;
    let mut fixed = case.clone();
    fixed.max_steps = r64.steps;
    // A zero tolerance is never met: the f32 run takes exactly max_steps (a multiple of the check interval).
    fixed.steady_tolerance = 0.0;
    let r32 = array_row::<f32>(&fixed, method, exec)?;
    Ok([r32, r64])
}

/// Run a plan; `progress(row)` is called after every run.
pub fn run_study(
    plan: &StudyPlan,
    exec: &Exec,
    mut progress: impl FnMut(&StudyRow),
) -> Result<Vec<StudyRow>> {
    let mut rows = Vec::new();
    for (problem, ladder) in &plan.ladders {
        match problem {
            Problem::CylinderArray => {
                for &(tau, method) in &plan.array_variants {
                    for &n in ladder {
                        for r in run_array_pair(n, tau, method, exec)? {
                            progress(&r);
                            rows.push(r);
                        }
                    }
                }
            }
            p => {
                for &n in ladder {
                    for r in [
                        run_channel_case::<f32>(*p, n, exec)?,
                        run_channel_case::<f64>(*p, n, exec)?,
                    ] {
                        progress(&r);
                        rows.push(r);
                    }
                }
            }
        }
    }
    Ok(rows)
}

/// The CSV of the study (one row per run).
pub fn csv(rows: &[StudyRow]) -> String {
    let mut s = String::from(
        "problem,precision,resolution,tau,method,nodes,steps,wall_seconds,mlups,relative_error,signed_error,threads\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{:.6e},{:.4},{:.6e},{:.6e},{}",
            r.problem.name(),
            r.precision,
            r.resolution,
            r.tau,
            r.method,
            r.nodes,
            r.steps,
            r.wall_seconds,
            r.mlups,
            r.relative_error,
            r.signed_error,
            r.threads
        );
    }
    s
}

fn percent(e: f64) -> String {
    format!("{e:.2e}")
}

/// Wall times closer than this ratio are not told apart in the recommendations (timing noise on a shared
/// machine is of this order; the two precisions run the same steps).
pub const TIMING_NOISE: f64 = 1.2;

/// Markdown table of all runs.
pub fn markdown_table(rows: &[StudyRow]) -> String {
    let mut s = String::from(
        "| problem | precision | resolution | τ | method | nodes | steps | wall [s] | MLUPS | relative error |\n\
         |---|---|---:|---:|---|---:|---:|---:|---:|---:|\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {:.3} | {:.1} | {} |",
            r.problem.name(),
            r.precision,
            r.resolution,
            r.tau,
            r.method,
            r.nodes,
            r.steps,
            r.wall_seconds,
            r.mlups,
            percent(r.relative_error)
        );
    }
    s
}

/// The cheapest run (least wall time) of `problem` whose error is within `budget`, if any.
pub fn cheapest(rows: &[StudyRow], problem: Problem, budget: f64) -> Option<&StudyRow> {
    rows.iter()
        .filter(|r| r.problem == problem && r.relative_error <= budget)
        .min_by(|a, b| a.wall_seconds.total_cmp(&b.wall_seconds))
}

fn budget_label(b: f64) -> String {
    let p = 100.0 * b;
    if p >= 1.0 {
        format!("{p:.0} %")
    } else {
        format!("{p} %")
    }
}

/// Recommendations per problem and budget, as markdown bullet points.
pub fn recommendations(rows: &[StudyRow]) -> String {
    let mut s = String::new();
    let mut problems: Vec<Problem> = Vec::new();
    for r in rows {
        if !problems.contains(&r.problem) {
            problems.push(r.problem);
        }
    }
    for p in problems {
        let _ = writeln!(
            s,
            "- **{}** (resolution = {}; error = {}):",
            p.name(),
            p.resolution_meaning(),
            p.error_meaning()
        );
        for b in BUDGETS {
            match cheapest(rows, p, b) {
                Some(r) => {
                    // The other precision at the same resolution, if it also meets the budget at about the
                    // same wall time: then the choice of precision does not matter for this budget.
                    let twin = rows.iter().find(|o| {
                        o.problem == p
                            && o.resolution == r.resolution
                            && o.tau == r.tau
                            && o.method == r.method
                            && o.precision != r.precision
                            && o.relative_error <= b
                            && o.wall_seconds <= TIMING_NOISE * r.wall_seconds
                    });
                    let precision = match twin {
                        Some(_) => "f32 or f64 (same wall time within timing noise)".to_string(),
                        None => r.precision.to_string(),
                    };
                    let _ = writeln!(
                        s,
                        "  - {} budget: {} at resolution {}, τ = {}, {} ({} steps, {:.3} s, error {})",
                        budget_label(b),
                        precision,
                        r.resolution,
                        r.tau,
                        r.method,
                        r.steps,
                        r.wall_seconds,
                        percent(r.relative_error)
                    );
                }
                None => {
                    let best = rows
                        .iter()
                        .filter(|r| r.problem == p)
                        .min_by(|a, b| a.relative_error.total_cmp(&b.relative_error));
                    let _ = writeln!(
                        s,
                        "  - {} budget: not reached by any run (best {}), refine further",
                        budget_label(b),
                        best.map(|r| format!(
                            "{} at {}, τ = {}, {}: {}",
                            r.precision,
                            r.resolution,
                            r.tau,
                            r.method,
                            percent(r.relative_error)
                        ))
                        .unwrap_or_else(|| "none".into())
                    );
                }
            }
        }
    }
    s
}

/// Where f32 stops following f64: for every problem, the resolutions at which the f32 error exceeds the f64
/// error by more than 50 % (roundoff dominating), as markdown bullet points.
pub fn f32_floors(rows: &[StudyRow]) -> String {
    let mut s = String::new();
    let mut seen: Vec<Problem> = Vec::new();
    for r in rows {
        if seen.contains(&r.problem) {
            continue;
        }
        seen.push(r.problem);
        let p = r.problem;
        let mut pairs: Vec<(usize, f64, f64)> = Vec::new();
        // The f32 floor is a property of the precision, so only the variant run first (the channels' one; the
        // array's first τ and method: τ = 0.8, Ω₁ with BGK, as before the τ axis) is compared.
        let first = (r.tau, r.method);
        for a in rows
            .iter()
            .filter(|x| x.problem == p && x.precision == "f32" && (x.tau, x.method) == first)
        {
            if let Some(b) = rows.iter().find(|x| {
                x.problem == p
                    && x.precision == "f64"
                    && x.resolution == a.resolution
                    && (x.tau, x.method) == first
            }) {
                pairs.push((a.resolution, a.relative_error, b.relative_error));
            }
        }
        pairs.sort_by_key(|x| x.0);
        let off: Vec<&(usize, f64, f64)> = pairs
            .iter()
            .filter(|(_, e32, e64)| *e32 > 1.5 * e64)
            .collect();
        let best32 = pairs.iter().map(|x| x.1).fold(f64::INFINITY, f64::min);
        if off.is_empty() {
            let _ = writeln!(
                s,
                "- {}: f32 follows f64 within 50 % at every resolution (smallest f32 error {}): no roundoff floor \
                 reached",
                p.name(),
                percent(best32)
            );
        } else {
            let list: Vec<String> = off
                .iter()
                .map(|(n, e32, e64)| format!("{n}: f32 {} vs f64 {}", percent(*e32), percent(*e64)))
                .collect();
            let _ = writeln!(
                s,
                "- {}: f32 roundoff floor, smallest f32 error {}; f32 exceeds f64 by > 50 % at resolution {}",
                p.name(),
                percent(best32),
                list.join("; ")
            );
        }
    }
    s
}

/// The error-versus-wall-time plot.
pub fn plot(rows: &[StudyRow], path: &Path) -> Result<()> {
    let colors = [
        (31, 119, 180),
        (214, 39, 40),
        (44, 160, 44),
        (148, 103, 189),
        (255, 127, 14),
        (140, 86, 75),
        (227, 119, 194),
        (127, 127, 127),
        (188, 189, 34),
        (23, 190, 207),
    ];
    let mut series = Vec::new();
    let mut variants: Vec<(Problem, f64, &'static str)> = Vec::new();
    for r in rows {
        if !variants.contains(&(r.problem, r.tau, r.method)) {
            variants.push((r.problem, r.tau, r.method));
        }
    }
    for (i, &(p, tau, method)) in variants.iter().enumerate() {
        for precision in ["f64", "f32"] {
            let points: Vec<(f64, f64, String)> = rows
                .iter()
                .filter(|r| {
                    r.problem == p && r.precision == precision && r.tau == tau && r.method == method
                })
                .map(|r| (r.wall_seconds, r.relative_error, r.resolution.to_string()))
                .collect();
            if points.is_empty() {
                continue;
            }
            let name = if p == Problem::CylinderArray {
                format!("{} τ={tau} {method} {precision}", p.name())
            } else {
                format!("{} {precision}", p.name())
            };
            series.push(Series {
                name,
                color: colors[i % colors.len()],
                dashed: precision == "f32",
                marker: if precision == "f32" {
                    Marker::Triangle
                } else {
                    Marker::Circle
                },
                points,
                label_offset: if precision == "f32" {
                    (6, 3)
                } else {
                    (-14, -20)
                },
            });
        }
    }
    loglog_png(
        path,
        &LogLogPlot {
            title: "lbdem speed vs error: solid f64, dashed f32; labels = nodes across channel / cell side l"
                .into(),
            x_label: "wall time of the stepping loop [s]".into(),
            y_label: "relative error".into(),
            size: (1100, 760),
            legend: plotters::chart::SeriesLabelPosition::LowerLeft,
            h_lines: BUDGETS
                .iter()
                .map(|b| (*b, format!("{} budget", budget_label(*b))))
                .collect(),
        },
        &series,
    )
}

/// Run the study of `plan` and write `speed_vs_error.csv`, `speed_vs_error.png` and `speed_vs_error.md` into
/// `out`; `progress` sees each finished run (see [`progress_line`]). Returns the markdown report (table,
/// recommendations, f32 notes).
pub fn speed_vs_error(
    out: &Path,
    plan: &StudyPlan,
    exec: &Exec,
    progress: impl FnMut(&StudyRow) + Send,
) -> Result<String> {
    exec.install(|| speed_vs_error_in_pool(out, plan, exec, progress))?
}

/// One line of progress for a finished run: problem, precision, resolution, τ, method, steps, time, MLUPS, error.
pub fn progress_line(r: &StudyRow) -> String {
    format!(
        "  {:<22} {} {:>3} τ {:<4} {:<10}: {:>8} steps {:>8.3} s {:>7.1} MLUPS  error {:.3e}",
        r.problem.name(),
        r.precision,
        r.resolution,
        r.tau,
        r.method,
        r.steps,
        r.wall_seconds,
        r.mlups,
        r.relative_error
    )
}

fn speed_vs_error_in_pool(
    out: &Path,
    plan: &StudyPlan,
    exec: &Exec,
    progress: impl FnMut(&StudyRow),
) -> Result<String> {
    std::fs::create_dir_all(out).map_err(|e| LbdemError::Write {
        path: out.display().to_string(),
        source: e,
    })?;
    let start = Instant::now();
    let rows = run_study(plan, exec, progress)?;
    write_atomic(&out.join("speed_vs_error.csv"), csv(&rows).as_bytes())?;
    plot(&rows, &out.join("speed_vs_error.png"))?;
    let mut md = String::new();
    let _ = writeln!(
        md,
        "Speed versus error ({} runs, {:.0} s in all, {} thread(s)).\n",
        rows.len(),
        start.elapsed().as_secs_f64(),
        threads()
    );
    md += &markdown_table(&rows);
    md += "\nCheapest run (least wall time) meeting each error budget:\n\n";
    md += &recommendations(&rows);
    md += "\nf32 against f64 (same steps, so the difference is roundoff):\n\n";
    md += &f32_floors(&rows);
    write_atomic(&out.join("speed_vs_error.md"), md.as_bytes())?;
    Ok(md)
}
