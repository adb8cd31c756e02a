//! Stability on hard settings and clear refusals: τ → ½⁺, large density drops, Mach up to 0.3 and beyond.
//! Every case either runs and stays finite within a stated error, or is refused with a message that names
//! the field — never silent garbage.
use crate::common;

use common::{lattice_channel, run_channel};
use lbdem::error::LbdemError;
use lbdem::kinds::channel::ChannelSetup;

fn field_of(err: LbdemError) -> String {
    match err {
        LbdemError::InvalidField { field, .. } => field,
        other => panic!("expected a field error, got {other}"),
    }
}

#[test]
fn tau_at_one_half_is_refused_naming_the_field() {
    let mut scene = lattice_channel(8, 1, 0.6, "body_force", 1e-6, 10, 1e-9);
    scene.fluid.tau = Some(0.5);
    let err = ChannelSetup::new(&scene).expect_err("tau = 1/2 must be refused");
    assert_eq!(field_of(err), "fluid.tau");
    // Given as a time step instead, a tau <= 1/2 is impossible (nu > 0), but a vanishing step is refused too.
    scene.fluid.tau = None;
    scene.fluid.timestep = Some(0.0);
    assert_eq!(
        field_of(ChannelSetup::new(&scene).unwrap_err()),
        "fluid.timestep"
    );
}

#[test]
fn tau_just_above_one_half_runs_finite_and_is_warned() {
    // τ = 0.505: viscosity 1.7e-3, grid Reynolds number u_max H / ν = 0.0058·8/1.7e-3 ≈ 28. The periodic
    // channel must stay finite and move towards the parabola (it cannot converge in a short test: H²/ν ≈ 4e4
    // steps), and the driver must warn about the marginal τ.
    let tau = 0.505;
    let nu = (tau - 0.5) / 3.0;
    let ny = 8;
    let g = 8.0 * nu * 0.01 / (ny * ny) as f64;
    let scene = lattice_channel(ny, 1, tau, "body_force", g, 20_000, 1e-12);
    let setup = ChannelSetup::new(&scene).expect("valid");
    assert!(
        setup
            .warnings
            .0
            .iter()
            .any(|w| w.contains("stability limit")),
        "{:?}",
        setup.warnings
    );
    let out = run_channel(&scene, None, 1000).expect("stays healthy");
    assert!(out.profile.iter().all(|r| r[1].is_finite()));
    // After 20 000 steps (half a diffusion time) the flow has developed partially: between 20 % and 100 % of
    // the analytical flux. Anything outside would mean blow-up or a broken forcing.
    let frac = 1.0 + out.flux_error;
    assert!(frac > 0.2 && frac < 1.0 + 1e-3, "developed fraction {frac}");
}

#[test]
fn mach_0_3_body_force_channel_runs_and_matches_the_slip_solution() {
    // Ma = 0.3 is warned (compressibility error ~Ma²) but runs: a unidirectional periodic channel has no
    // convective term, so even at Ma = 0.3 BGK reproduces parabola + slip; we bound the L2 error by the slip
    // (16Λ−3)/(3H²) relative at the centreline, times 1.5 for the norm, plus 1e-6.
    let tau = 0.8;
    let nu = (tau - 0.5) / 3.0;
    let ny = 16;
    let g = 8.0 * nu * (0.3 / 3f64.sqrt()) / (ny * ny) as f64;
    let scene = lattice_channel(ny, 1, tau, "body_force", g, 200_000, 1e-13);
    let setup = ChannelSetup::new(&scene).expect("valid");
    assert!((setup.mach - 0.3).abs() < 1e-9);
    assert!(
        setup.warnings.0.iter().any(|w| w.contains("Mach")),
        "Ma 0.3 must be warned about"
    );
    let out = run_channel(&scene, Some(1e-13), 100).expect("stays healthy");
    let slip = (16.0 * (tau - 0.5f64).powi(2) - 3.0).abs() / (3.0 * (ny * ny) as f64);
    assert!(
        out.l2_error < 1.5 * slip + 1e-6,
        "L2 error {:e}",
        out.l2_error
    );
}

#[test]
fn mach_above_limit_is_refused_unless_allowed() {
    let tau = 0.8;
    let nu = (tau - 0.5) / 3.0;
    let g = 8.0 * nu * (0.5 / 3f64.sqrt()) / 64.0;
    let mut scene = lattice_channel(8, 1, tau, "body_force", g, 100, 1e-9);
    let err = ChannelSetup::new(&scene).expect_err("Ma = 0.5 must be refused");
    assert_eq!(field_of(err), "channel.acceleration");
    scene.run.allow_high_mach = true;
    let setup = ChannelSetup::new(&scene).expect("allowed explicitly");
    assert!(setup.warnings.0.iter().any(|w| w.contains("Mach")));
}

#[test]
fn density_drop_above_twenty_percent_is_refused() {
    let scene = lattice_channel(8, 33, 0.8, "pressure", 0.3 / 3.0, 100, 1e-9);
    let err = ChannelSetup::new(&scene).expect_err("30 % density drop must be refused");
    assert_eq!(field_of(err), "channel.pressure_drop");
}

#[test]
fn a_diverging_run_stops_with_step_location_and_quantity() {
    // Ma = 1.2 with allow_high_mach: the driver warns, runs, and the health check stops the run with a
    // Diverged error (step, node, quantity) instead of writing garbage.
    let tau = 0.52;
    let nu = (tau - 0.5) / 3.0;
    let ny = 16;
    let g = 8.0 * nu * (1.2 / 3f64.sqrt()) / (ny * ny) as f64;
    let mut scene = lattice_channel(ny, 33, tau, "pressure", g * 32.0, 50_000, 1e-12);
    scene.run.allow_high_mach = true;
    match ChannelSetup::new(&scene) {
        // Refusing on density drop is also a clear, correct outcome.
        Err(e) => assert_eq!(field_of(e), "channel.pressure_drop"),
        Ok(_) => match run_channel(&scene, None, 100) {
            Err(LbdemError::Diverged { step, quantity, .. }) => {
                assert!(step > 0);
                assert!(quantity.contains("density"));
            }
            Err(other) => panic!("unexpected error {other}"),
            Ok(out) => assert!(out.l2_error.is_finite(), "if it survives it must be finite"),
        },
    }
}
