//! `lbdem run` and `lbdem check`: load a scene, print the derived parameters, run it with a progress bar, and
//! write `summary.json` and the CSV outputs.
use std::path::Path;

use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;

use crate::channel::{run_channel, ChannelOutcome, ChannelSetup};
use crate::error::Result;
use crate::output::{csv, prepare_dir, write_atomic};
use crate::scene::{Precision, Scene, SceneKind};

/// Options of `lbdem run`.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Replace a previous run in the output directory.
    pub overwrite: bool,
    /// Hide the progress bar (tests, CI logs).
    pub quiet: bool,
}

/// Validate a scene and print its derived parameters without running it.
pub fn check(scene_path: &Path) -> Result<String> {
    if let Some(f) = crate::fracture::FractureScene::load_if_fracture(scene_path)? {
        return f.check(scene_path);
    }
    if let Some(poro) = crate::poro::PoroScene::load_if_poro(scene_path)? {
        return poro.check(scene_path);
    }
    if let Some(dry) = crate::solid::scene::DryScene::load_if_dry(scene_path)? {
        return dry.check(scene_path);
    }
    if let Some(s) = crate::coupled_demo::check_if_demo(scene_path)? {
        return Ok(s);
    }
    let scene = Scene::load(scene_path)?;
    let labels = scene.scene.units.labels();
    match scene.scene.kind {
        SceneKind::Dry => crate::solid::scene::check_file(scene_path),
        SceneKind::Fracture => unreachable!("fracture scenes are handled above"),
        SceneKind::Channel => {
            let setup = ChannelSetup::new(&scene)?;
            let mut s = format!("scene {} is valid (kind = channel)\n", scene_path.display());
            s += &setup.describe(labels);
            for w in &setup.warnings.0 {
                s += &format!("  warning: {w}\n");
            }
            Ok(s)
        }
        SceneKind::CylinderArray | SceneKind::PorousFlow => {
            crate::porous::check(&scene, scene_path)
        }
    }
}

/// Run a scene, writing outputs into `out`. Returns the summary as JSON.
pub fn run(scene_path: &Path, out: &Path, opts: &RunOptions) -> Result<serde_json::Value> {
    if let Some(f) = crate::fracture::FractureScene::load_if_fracture(scene_path)? {
        return f.run(scene_path, out, opts.overwrite, opts.quiet);
    }
    if let Some(poro) = crate::poro::PoroScene::load_if_poro(scene_path)? {
        return poro.run(scene_path, out, opts);
    }
    if let Some(dry) = crate::solid::scene::DryScene::load_if_dry(scene_path)? {
        let opts = crate::solid::scene::DryRunOptions {
            overwrite: opts.overwrite,
            quiet: opts.quiet,
            stop_after: None,
        };
        return dry.run_resumable(scene_path, out, &opts);
    }
    if let Some(v) = crate::coupled_demo::run_if_demo(scene_path, out, opts.overwrite, opts.quiet)?
    {
        return Ok(v);
    }
    let scene = Scene::load(scene_path)?;
    let labels = scene.scene.units.labels();
    match scene.scene.kind {
        SceneKind::Dry => crate::solid::scene::run_file(scene_path, out, opts.overwrite),
        SceneKind::Fracture => unreachable!("fracture scenes are handled above"),
        SceneKind::Channel => {
            let setup = ChannelSetup::new(&scene)?;
            prepare_dir(out, opts.overwrite)?;
            eprintln!("lbdem: channel scene {}", scene_path.display());
            eprint!("{}", setup.describe(labels));
            for w in &setup.warnings.0 {
                eprintln!("  WARNING: {w}");
            }
            let bar = if opts.quiet {
                ProgressBar::hidden()
            } else {
                ProgressBar::new(setup.steps)
            };
            bar.set_style(
                ProgressStyle::with_template("{bar:40} {pos}/{len} steps  {per_sec}  eta {eta}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            let interval = scene.run.check_interval.unwrap_or(200);
            let out_name = out.display().to_string();
            let outcome: ChannelOutcome = match scene.scene.precision {
                Precision::F64 => run_channel::<f64>(
                    &setup,
                    scene.run.steady_tolerance,
                    interval,
                    &out_name,
                    |s| bar.set_position(s),
                ),
                Precision::F32 => run_channel::<f32>(
                    &setup,
                    scene.run.steady_tolerance,
                    interval,
                    &out_name,
                    |s| bar.set_position(s),
                ),
            }?;
            bar.finish_and_clear();
            let profile = csv(
                &["y", "u_simulated", "u_analytical", "lattice_density"],
                outcome.profile.iter().map(|r| r.to_vec()),
            );
            write_atomic(&out.join("profile.csv"), profile.as_bytes())?;
            let summary = json!({
                "lbdem_version": env!("CARGO_PKG_VERSION"),
                "scene_file": scene_path.display().to_string(),
                "scene": scene,
                "units": labels,
                "derived": setup,
                "steps": outcome.steps,
                "steady": outcome.steady,
                "wall_seconds": outcome.wall_seconds,
                "mlups": outcome.mlups,
                "threads": rayon::current_num_threads(),
                "simd": crate::exec::default_level().name(),
                "streaming": crate::lattice::default_streaming().name(),
                "error_vs_analytical": {
                    "l2_relative": outcome.l2_error,
                    "flux_relative": outcome.flux_error,
                    "centre_velocity_relative": outcome.centre_velocity_error,
                },
                "measured_mach": outcome.measured_mach,
                "relative_mass_change": outcome.mass_change,
            });
            let text = serde_json::to_string_pretty(&summary).unwrap_or_default();
            write_atomic(&out.join("summary.json"), text.as_bytes())?;
            eprintln!(
                "lbdem: {} steps in {:.2} s ({:.1} MLUPS); L2 error {:.3e}, flux error {:.3e}; outputs in {}",
                outcome.steps,
                outcome.wall_seconds,
                outcome.mlups,
                outcome.l2_error,
                outcome.flux_error,
                out.display()
            );
            Ok(summary)
        }
        SceneKind::CylinderArray | SceneKind::PorousFlow => {
            crate::porous::run(&scene, scene_path, out, opts)
        }
    }
}
