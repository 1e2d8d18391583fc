//! Closed loop of `compare` (issue 5 §1–§2): simulate a known model with a known η,
//! render the footage, analyse it like any clip, and run `compare --fit` on the
//! result. The fitted η must come back within 10 % of the true one, and the true
//! model must rank first among contour, classical rolling and curvature-offset
//! friction.

use std::path::Path;

use eulerdisk::analyse::{self, Experiment};
use eulerdisk::compare::{self, CompareOptions, EtaMethod};
use eulerdisk::config::{CalibrationConfig, ExperimentConfig};
use eulerdisk::model::closed_form::stationary_rolling;
use eulerdisk::model::dissipation::{Dissipation, ModelKind};
use eulerdisk::model::params::Preset;
use eulerdisk::model::simulate::{EndReason, SimulationSpec, simulate};
use eulerdisk::render::{Plate, RenderSpec, Renderer, trajectory_motion, write_clip};
use eulerdisk::report::compare::{comparison_dir, write_comparison, write_ranking};
use eulerdisk::report::experiment::write_experiment;

/// The true model and η: the thesis's contour run (§4.7).
const TRUE_MODEL: ModelKind = ModelKind::Contour;
const TRUE_ETA: f64 = 2.43e-4;
/// Initial nutation of the rendered run, eq. (4.43).
const PHI0: f64 = 0.0243;
/// Strip angle on the top face [rad].
const BETA0: f64 = 0.3;
/// Lead of the initial state before the measured halt [s]. The rendered motion lasts
/// 0.47 s and the 320 × 240 side view loses the rim about 0.06 s before the true
/// halt (the rim height falls below 5 noise σ of a ~0.26 mm pixel), so 0.35 s keeps
/// the initial state inside the footage.
const LEAD_S: f64 = 0.35;

/// Renders the true motion at 320 × 240 px, 480 fps, and analyses it. The
/// calibration points are the renderer's (as a user would click them, §3.2.4): the
/// automatic rest-frame calibration of this branch misplaces z_t on these small
/// frames (δ about 24 % low), which scales every φ (see the report of this test).
fn closed_loop_experiment(dir: &Path) -> Experiment {
    let params = Preset::EulerDisk.params();
    let mut spec = SimulationSpec::thesis_default(params, Dissipation::new(TRUE_MODEL), TRUE_ETA);
    // Start on the stationary-rolling manifold (eq. 4.40) in the sense of eq. 4.43.
    let (psi_dot, theta_dot) = stationary_rolling(&params, PHI0).expect("stationary rolling");
    spec.initial.phi = PHI0;
    spec.initial.psi_dot = -psi_dot.abs();
    spec.initial.theta_dot = theta_dot.abs();
    spec.t_end = 2.0;
    spec.beta0 = BETA0;
    let trajectory = simulate(&spec).expect("true simulation");
    assert_eq!(trajectory.end_reason, EndReason::DiscontinuitySet);
    let motion = trajectory_motion(
        &params,
        &trajectory,
        BETA0,
        spec.mu,
        480.0,
        0.15,
        Dissipation::new(TRUE_MODEL).analytic_exponent(),
    )
    .expect("motion");
    let mut render = RenderSpec::thesis(Plate::Dark, false);
    (render.width, render.height) = (320, 240);
    let renderer = Renderer::new(&render, &motion).expect("renderer");
    let clip = dir.join("contour.mp4");
    write_clip(&renderer, &clip).expect("write clip");
    let c = renderer.truth().calibration;
    let config = ExperimentConfig {
        material: Some("stainless steel".into()),
        calibration: Some(CalibrationConfig {
            x_l: c.x_l,
            x_r: c.x_r,
            z_t: c.z_t,
            z_base: c.z_base,
        }),
        ..ExperimentConfig::default()
    };
    analyse::analyse_clip(&clip, &config, &|_, _| {}).expect("analyse")
}

#[test]
fn compare_fit_recovers_eta_and_ranks_the_true_model_first() {
    let dir = tempfile::tempdir().expect("tempdir");
    let experiment_dir = dir.path().join("contour");
    let analysed = closed_loop_experiment(dir.path());
    write_experiment(&experiment_dir, &analysed).expect("write experiment");
    // The CLI's path: result.json read back.
    let experiment = compare::load_experiment(&experiment_dir).expect("result.json round trip");

    let options = CompareOptions {
        method: EtaMethod::LeastSquares,
        lead_s: LEAD_S,
        ..CompareOptions::new(TRUE_MODEL)
    };
    let models = [
        ModelKind::Contour,
        ModelKind::ClassicalRolling,
        ModelKind::CurvatureOffset,
    ];
    let ranked = compare::rank_models(&experiment, &experiment_dir, &options, &models);
    for r in &ranked {
        eprintln!(
            "{:?}: η = {:?}, misfit = {:?}, n = {:?}, end − halt = {:?}, {:?}",
            r.model, r.eta, r.misfit, r.energy_exponent, r.end_time_error_s, r.error
        );
    }
    let contour = ranked
        .iter()
        .find(|r| r.model == ModelKind::Contour)
        .expect("contour ranked");
    let comparison = contour.outcome.as_ref().expect("contour comparison");
    write_comparison(&comparison_dir(&experiment_dir, ModelKind::Contour), comparison)
        .expect("write comparison");
    write_ranking(
        &experiment_dir.join("compare-all"),
        &experiment_dir,
        options.method,
        &ranked,
    )
    .expect("write ranking");
    for file in ["summary.json", "model.csv", "overlay.svg", "overlay.png", "index.html"] {
        assert!(
            experiment_dir.join("compare-contour").join(file).is_file(),
            "{file} missing"
        );
    }

    // The fitted η within 10 % of the truth (issue 5 §2).
    let eta = comparison.eta;
    assert!(
        (eta / TRUE_ETA - 1.0).abs() < 0.10,
        "fitted η = {eta:.4e}, true {TRUE_ETA:.4e}"
    );

    // The true model first. Curvature-dependent offset with k_u = 0 (eq. 4.69) is the
    // same moment as contour friction (eq. 4.59): it must tie exactly, and it is
    // listed after contour so that the stable sort keeps contour first.
    let misfit = |m: ModelKind| {
        ranked
            .iter()
            .find(|r| r.model == m)
            .and_then(|r| r.misfit)
            .expect("misfit")
    };
    assert_eq!(ranked[0].model, ModelKind::Contour);
    assert_eq!(misfit(ModelKind::CurvatureOffset), misfit(ModelKind::Contour));
    assert!(
        misfit(ModelKind::ClassicalRolling) > misfit(ModelKind::Contour),
        "classical rolling fits better than the true model"
    );

    // The model halts on the discontinuity set θ̇ = 0 (eq. 4.60) with a small residual
    // spin, as the thesis's contour run (ψ̇ = −0.051 rad/s, §4.7).
    assert_eq!(comparison.residual.end_reason, EndReason::DiscontinuitySet);
    assert!(comparison.residual.psi_dot.abs() < 1.0);
}
