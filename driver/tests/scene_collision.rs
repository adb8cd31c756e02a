//! The scene keys of the fluid collision (`[fluid] collision`, `magic`) and of the PSM solid
//! operator (`solid_operator`, named by the literature), and their refusals: the words of earlier scene files
//! are refused naming the new word, Λ ≤ 0 / non-finite Λ / τ⁻ ≤ ½ / `magic` with BGK name `fluid.magic`, and an
//! operator that is not valid for free grains is refused naming the key and the operator to use. Each refusal is
//! reached by `check` and by `run` with the same message, before anything is written (the pattern of
//! `hostile.rs`).
use crate::common::scene_text;
use scene_text::{scene, with};

use lbdem::app;
use lbdem::kinds::channel::Channel;
use lbdem::kinds::cylinder_array::CylinderArray;
use lbdem::run::{Case, RunOptions};
use lbdem_kernels::fluid::collide::{Collision, SolidOperator};

/// `text` with `line` added right after the line `after` (which must exist).
fn adding(text: &str, after: &str, line: &str) -> String {
    assert!(text.lines().any(|l| l == after), "no line {after}");
    text.lines()
        .flat_map(|l| {
            if l == after {
                vec![l.to_string(), line.to_string()]
            } else {
                vec![l.to_string()]
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

/// `check` refuses `text` naming `field`; `run` refuses it with the same message and writes nothing.
fn refused_by_both(text: &str, field: &str) -> String {
    let e = app::check_text(text, "t.toml").unwrap_err().to_string();
    assert!(
        e.contains(&format!("`{field}")),
        "expected `{field}` in: {e}"
    );
    let out = std::env::temp_dir().join(format!(
        "lbdem-scene-collision-never-{}",
        std::process::id()
    ));
    let quiet = RunOptions {
        quiet: true,
        ..RunOptions::default()
    };
    let r = app::run_text(text, "t.toml", &out, &quiet)
        .unwrap_err()
        .to_string();
    assert_eq!(e, r, "check and run disagree");
    assert!(!out.exists(), "run wrote {} before refusing", out.display());
    e
}

#[test]
fn every_operator_is_read_by_its_literature_name_and_written_back_the_same() {
    let base = scene("cylinder_array.toml");
    for op in SolidOperator::ALL {
        let text = with(&base, "solid_operator", &format!("\"{}\"", op.name()));
        let case = Case::<CylinderArray>::read(&text, "t.toml").unwrap();
        let section = case.scene.cylinder_array.as_ref().unwrap();
        assert_eq!(section.solid_operator, op);
        assert!(case.setup.cases.iter().all(|c| c.solid_operator == op));
        // The scene copy a run writes names it the same way.
        let copy = toml::to_string(&case.scene).unwrap();
        assert!(
            copy.contains(&format!("solid_operator = \"{}\"", op.name())),
            "{copy}"
        );
    }
}

#[test]
fn old_operator_words_are_refused_naming_the_new_word() {
    let array = scene("cylinder_array.toml");
    for (old, new) in [
        ("bounce_back", "non_equilibrium_bounce_back"),
        ("moving_wall", "moving_wall_bounce_back"),
        ("linearized", "linearized_non_equilibrium_bounce_back"),
    ] {
        let e = refused_by_both(
            &with(&array, "solid_operator", &format!("\"{old}\"")),
            "cylinder_array.solid_operator",
        );
        assert!(e.contains(&format!("\"{new}\"")), "{old}: {e}");
    }
    // `bounce_back` meant Ω₁ in scenes; the message says so, so that nobody reads it as Ω₃.
    let e = app::check_text(&with(&array, "solid_operator", "\"bounce_back\""), "t.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("Omega_1"), "{e}");
    // An unknown word lists every name.
    let e = refused_by_both(
        &with(&array, "solid_operator", "\"mrt\""),
        "cylinder_array.solid_operator",
    );
    for op in SolidOperator::ALL {
        assert!(e.contains(op.name()), "{e}");
    }
    // Other sections that take the key: [porous] and a fracture scene's [fluid].
    let porous = scene("porous_darcy.toml");
    let e = refused_by_both(
        &with(&porous, "solid_operator", "\"bounce_back\""),
        "porous.solid_operator",
    );
    assert!(e.contains("non_equilibrium_bounce_back"), "{e}");
    let fracture = adding(
        &scene("fracture/quick/base.toml"),
        "margin = 0.2             # cm of free fluid beyond each end",
        "solid_operator = \"linearized\"",
    );
    let e = refused_by_both(&fracture, "fluid.solid_operator");
    assert!(e.contains("linearized_non_equilibrium_bounce_back"), "{e}");
}

#[test]
fn collision_and_magic_are_read_and_bad_values_refused_naming_the_field() {
    let base = scene("poiseuille.toml");
    let line = base
        .lines()
        .find(|l| l.starts_with("tau"))
        .expect("tau line")
        .to_string();
    // Default of a channel: BGK; "trt" gives Λ = 3/16 unless `magic` says otherwise.
    let read = |text: &str| {
        Case::<Channel>::read(text, "t.toml").map(|c| match c.setup.collision {
            Collision::Bgk => None,
            Collision::Trt(t) => Some(t.magic()),
        })
    };
    assert_eq!(read(&base).unwrap(), None);
    let trt = adding(&base, &line, "collision = \"trt\"");
    assert_eq!(read(&trt).unwrap(), Some(0.1875));
    let trt_quarter = adding(&trt, "collision = \"trt\"", "magic = 0.25");
    assert_eq!(read(&trt_quarter).unwrap(), Some(0.25));
    assert_eq!(
        read(&adding(&base, &line, "collision = \"bgk\"")).unwrap(),
        None
    );
    // Refusals.
    refused_by_both(
        &adding(&base, &line, "collision = \"mrt\""),
        "fluid.collision",
    );
    for bad in ["0.0", "-0.1875", "nan", "inf"] {
        let e = refused_by_both(&with(&trt_quarter, "magic", bad), "fluid.magic");
        assert!(e.contains("positive finite"), "{bad}: {e}");
    }
    // τ⁻ = ½ + Λ/(τ − ½) rounds to ½ in f64 for Λ = 1e-300: refused, naming the field and τ⁻.
    let e = refused_by_both(&with(&trt_quarter, "magic", "1e-300"), "fluid.magic");
    assert!(e.contains("tau-"), "{e}");
    // In f32, Λ = 1e-50 is 0: refused even for an f64 scene (checked in both precisions).
    refused_by_both(&with(&trt_quarter, "magic", "1e-50"), "fluid.magic");
    // `magic` with BGK is refused rather than ignored.
    let e = refused_by_both(
        &adding(
            &adding(&base, &line, "collision = \"bgk\""),
            "collision = \"bgk\"",
            "magic = 0.25",
        ),
        "fluid.magic",
    );
    assert!(
        e.contains("collision = \\\"trt\\\"") || e.contains("\"trt\""),
        "{e}"
    );
}

#[test]
fn operators_invalid_for_free_grains_are_refused_naming_the_key_and_the_operator_to_use() {
    let tv = scene("terminal_velocity.toml");
    let with_op = |op: &str| {
        adding(
            &tv,
            "duration = 0.605       # s = 5000 steps (12 e-folding times of the slowest viscous mode l^2/(4 pi^2 nu))",
            &format!("solid_operator = \"{op}\""),
        )
    };
    for op in ["moving_wall_bounce_back", "superposition"] {
        let e = refused_by_both(&with_op(op), "terminal_velocity.solid_operator");
        assert!(e.contains("lambda_consistent"), "{op}: {e}");
    }
    for op in [
        "non_equilibrium_bounce_back",
        "linearized_non_equilibrium_bounce_back",
        "lambda_consistent",
    ] {
        app::check_text(&with_op(op), "t.toml").unwrap_or_else(|e| panic!("{op}: {e}"));
    }
    // The fracture scenes (free grains): the same two refused, in [fluid].
    for op in ["moving_wall_bounce_back", "superposition"] {
        let fracture = adding(
            &scene("fracture/quick/base.toml"),
            "margin = 0.2             # cm of free fluid beyond each end",
            &format!("solid_operator = \"{op}\""),
        );
        let e = refused_by_both(&fracture, "fluid.solid_operator");
        assert!(e.contains("lambda_consistent"), "{op}: {e}");
    }
}

#[test]
fn lambda_consistent_with_light_free_grains_at_high_tau_is_refused_and_near_the_edge_warned() {
    let tv = adding(
        &scene("terminal_velocity.toml"),
        "duration = 0.605       # s = 5000 steps (12 e-folding times of the slowest viscous mode l^2/(4 pi^2 nu))",
        "solid_operator = \"lambda_consistent\"",
    );
    let warnings = |text: &str| {
        lbdem::run::Case::<lbdem::kinds::terminal_velocity::TerminalVelocity>::read(text, "t.toml")
            .unwrap()
            .setup
            .warnings
    };
    let warned = |w: &[String]| {
        w.iter()
            .any(|w| w.contains("outside the region measured stable"))
    };
    // Neutrally buoyant grains (measured: stable to τ = 0.8, diverged from 1.2): refused at 1.2 and 2,
    // warned at 1.0, accepted silently at 0.8.
    let light = with(&tv, "grain_density", "1.0");
    for tau in ["1.2", "2.0"] {
        let e = refused_by_both(
            &with(&light, "tau", tau),
            "terminal_velocity.solid_operator",
        );
        assert!(e.contains("fluid.tau"), "{e}");
    }
    assert!(warned(&warnings(&with(&light, "tau", "1.0"))));
    assert!(!warned(&warnings(&with(&light, "tau", "0.8"))));
    // 1.4 × the fluid in the friction-only form (measured for 1.25: stable to 1.2, diverged at 2): refused at
    // 2, warned at 1.5, silent at 1.2. In the wall-pressure form (the default) a lone grain of 1.25 was stable
    // at every τ measured: silent at 2.
    let mid = with(&tv, "grain_density", "1.4");
    let mid_friction = with_form(&mid, "friction_only");
    refused_by_both(
        &with(&mid_friction, "tau", "2.0"),
        "terminal_velocity.solid_operator",
    );
    assert!(warned(&warnings(&with(&mid_friction, "tau", "1.5"))));
    assert!(!warned(&warnings(&with(&mid_friction, "tau", "1.2"))));
    assert!(!warned(&warnings(&with(&mid, "tau", "2.0"))));
    // Neutrally buoyant grains diverged at 1.2 in both forms.
    refused_by_both(
        &with(&with_form(&light, "friction_only"), "tau", "1.2"),
        "terminal_velocity.solid_operator",
    );
    // Rock grains (2.65) at τ = 2: no warning.
    assert!(!warned(&warnings(&with(&tv, "tau", "2.0"))));
}

#[test]
fn free_grain_kinds_default_to_trt_and_lambda_consistent_where_stable_and_fall_back_with_a_warning()
{
    use lbdem::kinds::terminal_velocity::{self, TerminalVelocity};
    let read = |text: &str| Case::<TerminalVelocity>::read(text, "t.toml").unwrap();
    let choice = |case: &Case<TerminalVelocity>| {
        terminal_velocity::fluid_choice(
            &case.scene,
            case.setup.units.tau,
            &mut lbdem::units::Warnings::default(),
        )
    };
    // The bundled scene (rock grain, τ = 0.8) names neither key: TRT + ΩΛ, no warning.
    let tv = scene("terminal_velocity.toml");
    let case = read(&tv);
    assert_eq!(
        choice(&case),
        (
            lbdem::units::CollisionName::Trt,
            SolidOperator::LambdaConsistent
        )
    );
    assert!(case
        .setup
        .warnings
        .iter()
        .all(|w| !w.contains("solid_operator not given")));
    // A neutrally buoyant grain at τ = 1.2, where ΩΛ diverged: not refused (the scene did not ask for ΩΛ) but
    // Ω₁ₗ with BGK, and a warning naming what to change.
    let light = read(&with(&with(&tv, "grain_density", "1.0"), "tau", "1.2"));
    assert_eq!(
        choice(&light),
        (
            lbdem::units::CollisionName::Bgk,
            SolidOperator::LinearizedNonEquilibriumBounceBack
        )
    );
    assert!(
        light
            .setup
            .warnings
            .iter()
            .any(|w| w.contains("solid_operator not given") && w.contains("fluid.tau to 0.8")),
        "{:?}",
        light.setup.warnings
    );
    // Naming ΩΛ there is still refused (the stability map).
    refused_by_both(
        &adding(
            &with(&with(&tv, "grain_density", "1.0"), "tau", "1.2"),
            "duration = 0.605       # s = 5000 steps (12 e-folding times of the slowest viscous mode l^2/(4 pi^2 nu))",
            "solid_operator = \"lambda_consistent\"",
        ),
        "terminal_velocity.solid_operator",
    );
    // The fracture scenes (rock grains) default to TRT + ΩΛ as well.
    let fracture = scene("fracture/quick/base.toml");
    let case = Case::<lbdem::kinds::fracture::FractureTest>::read(&fracture, "f.toml").unwrap();
    let f = case.scene.fluid.as_ref().unwrap();
    let fs = case
        .scene
        .fluid_setup(f, &mut lbdem::units::Warnings::default())
        .unwrap();
    assert_eq!(fs.solid_operator, SolidOperator::LambdaConsistent);
    assert_eq!(fs.collision_default, lbdem::units::CollisionName::Trt);
}

/// ΩΛ with a **pack** of free grains has its own stability map, one per form. In the Terzaghi column (free discs
/// in contact), friction-only form (`LAMBDA_PACKED_GRAIN_STABILITY`): grains twice as dense as the fluid stable
/// at τ = 1.6, diverged at 2, where a lone disc of that density is stable to τ = 2. Wall-pressure form, the
/// default (`LAMBDA_WALL_PACKED_GRAIN_STABILITY`): those grains stable at τ = 2 (three seeds), grains 1.5 × the
/// fluid stable at 1.4 and diverged at 1.6. Rock grains (2.65) were stable to 2 in both. So for the kinds that
/// make a pack, ΩΛ named is refused from the map's first diverged τ and warned above its last stable one, and the
/// default falls back to Ω₁ₗ + BGK above the last stable τ with a warning; a lone grain keeps its map, and a
/// rock pack takes ΩΛ at every τ measured.
#[test]
fn lambda_consistent_with_packed_grains_follows_the_pack_map() {
    use lbdem::kinds::consolidation::{self, Consolidation};
    use lbdem::kinds::terzaghi::Terzaghi;
    let warned = |w: &[String]| {
        w.iter()
            .any(|w| w.contains("outside the region measured stable"))
    };
    // τ = 0.5 + 3ν in these scenes (h = 0.02 cm, Δt = 4e-4 s).
    let tz = adding(
        &scene("terzaghi.toml"),
        "record_interval = 0.25   # s",
        "solid_operator = \"lambda_consistent\"",
    );
    let warnings = |text: &str| {
        Case::<Terzaghi>::read(text, "t.toml")
            .unwrap()
            .setup
            .warnings
    };
    // Friction-only form, grains 2 × the fluid: refused at τ = 2, warned at 1.7, silent at 1.55.
    let tz2 = with(&tz, "grain_density", "2.0");
    let tz2_friction = with_form(&tz2, "friction_only");
    let e = refused_by_both(
        &with(&tz2_friction, "viscosity", "0.5"),
        "terzaghi.solid_operator",
    );
    assert!(
        e.contains("pack") && e.contains("friction-only") && e.contains("fluid.tau"),
        "{e}"
    );
    assert!(warned(&warnings(&with(&tz2_friction, "viscosity", "0.4"))));
    assert!(!warned(&warnings(&with(
        &tz2_friction,
        "viscosity",
        "0.35"
    ))));
    // Wall-pressure form (the default): the same grains silent at τ = 2; grains 1.5 × the fluid refused at
    // τ = 1.6, warned at 1.5, silent at 1.37.
    assert!(!warned(&warnings(&with(&tz2, "viscosity", "0.5"))));
    let tz15 = with(&tz, "grain_density", "1.5");
    let e = refused_by_both(
        &with(&tz15, "viscosity", "0.36666667"),
        "terzaghi.solid_operator",
    );
    assert!(
        e.contains("pack") && e.contains("wall-pressure") && e.contains("fluid.tau"),
        "{e}"
    );
    assert!(warned(&warnings(&with(&tz15, "viscosity", "0.33333333"))));
    assert!(!warned(&warnings(&with(&tz15, "viscosity", "0.29"))));
    // Rock grains: ΩΛ at τ = 2 without a warning, in both forms.
    assert!(!warned(&warnings(&with(&tz, "viscosity", "0.5"))));
    assert!(!warned(&warnings(&with(
        &with_form(&tz, "friction_only"),
        "viscosity",
        "0.5"
    ))));
    // Consolidation names no operator: TRT + ΩΛ at τ = 0.8 (the bundled scene) and, with rock grains, at
    // τ = 2; with grains 1.5 × the fluid Ω₁ₗ + BGK with a warning at τ = 1.7 (wall-pressure form), where a lone
    // grain of that density would still get ΩΛ; with grains twice as dense ΩΛ at 1.7 in the wall-pressure form,
    // Ω₁ₗ + BGK in the friction-only form (whose form key is then refused).
    let choice = |text: &str| {
        let case = Case::<Consolidation>::read(text, "c.toml").unwrap();
        let mut w = lbdem::units::Warnings::default();
        let c = consolidation::fluid_choice(&case.scene, case.setup.units.tau, &mut w);
        (c, w.0)
    };
    let cs = scene("consolidation.toml");
    let lambda = (
        lbdem::units::CollisionName::Trt,
        SolidOperator::LambdaConsistent,
    );
    assert_eq!(choice(&cs).0, lambda);
    assert_eq!(choice(&with(&cs, "viscosity", "0.5")).0, lambda);
    let cs2 = with(&with(&cs, "grain_density", "2.0"), "viscosity", "0.4");
    assert_eq!(choice(&cs2), (lambda, vec![]));
    // In the friction-only form the default there is Ω₁ₗ + BGK, which has no form: the form key is refused.
    refused_by_both(&with_form(&cs2, "friction_only"), "fluid.lambda_form");
    let (c, w) = choice(&with(
        &with(&cs, "grain_density", "1.5"),
        "viscosity",
        "0.4",
    ));
    assert_eq!(
        c,
        (
            lbdem::units::CollisionName::Bgk,
            SolidOperator::LinearizedNonEquilibriumBounceBack
        )
    );
    assert!(
        w.iter()
            .any(|w| w.contains("solid_operator not given") && w.contains("packed")),
        "{w:?}"
    );
    // A lone grain of that density at the same τ: ΩΛ, no warning (the free-disc map).
    let tv = with(
        &with(&scene("terminal_velocity.toml"), "grain_density", "1.5"),
        "tau",
        "1.7",
    );
    let case =
        Case::<lbdem::kinds::terminal_velocity::TerminalVelocity>::read(&tv, "t.toml").unwrap();
    assert!(case
        .setup
        .warnings
        .iter()
        .all(|w| !w.contains("solid_operator not given")));
}

/// `text` (a scene with a `[fluid]` section) with `lambda_form = "{form}"` as the section's first key.
fn with_form(text: &str, form: &str) -> String {
    adding(text, "[fluid]", &format!("lambda_form = \"{form}\""))
}

#[test]
fn lambda_form_is_read_applied_and_refused_with_other_operators() {
    use lbdem::kinds::cylinder_array::solve_array;
    use lbdem_kernels::fluid::collide::LambdaTerms;
    let array = scene("cylinder_array.toml");
    let terms = |text: &str| {
        let case = Case::<CylinderArray>::read(text, "t.toml").unwrap();
        let t: Vec<LambdaTerms> = case.setup.cases.iter().map(|c| c.lambda_terms).collect();
        assert!(t.windows(2).all(|w| w[0] == w[1]), "{t:?}");
        (t[0], case.setup.cases[2].clone())
    };
    // Default: the wall-pressure form; each word gives its constants.
    let (default, _) = terms(&array);
    assert_eq!(default, LambdaTerms::WALL_PRESSURE);
    let (wall, wall_case) = terms(&with_form(&array, "wall_pressure"));
    assert_eq!(wall, LambdaTerms::WALL_PRESSURE);
    let (friction, friction_case) = terms(&with_form(&array, "friction_only"));
    assert_eq!(friction, LambdaTerms::FRICTION_ONLY);
    // The form reaches the lattice: at l = 20, c = 0.4 the two forms' drags differ by 1.3 % (measured: −0.65 %
    // and +0.63 % from Sangani & Acrivos; README *ΩΛ's wall-pressure form*), far above what the 1e-7 steady
    // tolerance leaves (~1e-5).
    let a = solve_array::<f64>(&wall_case).unwrap();
    let b = solve_array::<f64>(&friction_case).unwrap();
    let gap = (a.drag - b.drag).abs() / a.drag;
    assert!(gap > 5e-3, "forms give drags {} and {}", a.drag, b.drag);
    // The copy of the scene a run writes keeps the word.
    let case = Case::<CylinderArray>::read(&with_form(&array, "friction_only"), "t.toml").unwrap();
    let copy = toml::to_string(&case.scene).unwrap();
    assert!(copy.contains("lambda_form = \"friction_only\""), "{copy}");

    // Refused: an unknown word, and a form with an operator that has none (given, or the kind's default).
    refused_by_both(&with_form(&array, "unshaped"), "fluid.lambda_form");
    let e = refused_by_both(
        &with_form(
            &with(
                &array,
                "solid_operator",
                "\"linearized_non_equilibrium_bounce_back\"",
            ),
            "friction_only",
        ),
        "fluid.lambda_form",
    );
    assert!(e.contains("lambda_consistent"), "{e}");
    let porous = with(
        &scene("porous_darcy.toml"),
        "solid_operator",
        "\"moving_wall_bounce_back\"",
    );
    refused_by_both(&with_form(&porous, "wall_pressure"), "fluid.lambda_form");
    // Terzaghi's default operator is Ω₁ₗ: a form there is refused until ΩΛ is asked for.
    let terzaghi = scene("terzaghi.toml");
    refused_by_both(&with_form(&terzaghi, "friction_only"), "fluid.lambda_form");
    let tv = adding(
        &scene("terminal_velocity.toml"),
        "duration = 0.605       # s = 5000 steps (12 e-folding times of the slowest viscous mode l^2/(4 pi^2 nu))",
        "solid_operator = \"non_equilibrium_bounce_back\"",
    );
    refused_by_both(&with_form(&tv, "friction_only"), "fluid.lambda_form");

    // A fracture scene: its set-up names the form and its constants; with Ω₁ₗ the form is refused.
    let fracture = scene("fracture/quick/base.toml");
    let d = app::check_text(&with_form(&fracture, "friction_only"), "t.toml").unwrap();
    assert!(
        d.contains("lambda_consistent (friction_only: kappa 1.21, alpha 0)"),
        "{d}"
    );
    let d = app::check_text(&fracture, "t.toml").unwrap();
    assert!(
        d.contains("lambda_consistent (wall_pressure: kappa 0.5, alpha 2)"),
        "{d}"
    );
    let e = refused_by_both(
        &with_form(
            &adding(
                &fracture,
                "margin = 0.2             # cm of free fluid beyond each end",
                "solid_operator = \"linearized_non_equilibrium_bounce_back\"",
            ),
            "wall_pressure",
        ),
        "fluid.lambda_form",
    );
    assert!(e.contains("linearized_non_equilibrium_bounce_back"), "{e}");
}
