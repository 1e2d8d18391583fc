//! Closed loop of `compare` (issue 5 §1–§2): simulate a known model with a known η,
//! render the footage, analyse it like any clip (automatic rest-frame calibration),
//! and run `compare --fit` on the result. The fitted η must come back within 10 % of
//! the true one, and the true model must rank first among contour, classical rolling
//! and curvature-offset friction.

use std::path::Path;

use eulerdisk::analyse::{self, Experiment};
use eulerdisk::compare::{self, CompareOptions, EtaMethod};
use eulerdisk::config::ExperimentConfig;
use eulerdisk::model::closed_form::stationary_rolling;
use eulerdisk::model::dissipation::{Dissipation, ModelKind};
use eulerdisk::model::params::Preset;
use eulerdisk::model::simulate::{EndReason, SimulationSpec, simulate};
use eulerdisk::render::{GroundTruth, Plate, RenderSpec, Renderer, trajectory_motion, write_clip};
use eulerdisk::report::compare::{comparison_dir, write_comparison, write_ranking};
use eulerdisk::report::experiment::write_experiment;
use eulerdisk::vision::PointSource;

/// The true model and η: the thesis's contour run (§4.7).
const TRUE_MODEL: ModelKind = ModelKind::Contour;
const TRUE_ETA: f64 = 2.43e-4;
/// Initial nutation of the rendered run, eq. (4.43).
const PHI0: f64 = 0.0243;
/// Strip angle on the top face [rad].
const BETA0: f64 = 0.3;
/// Lead of the initial state before the measured halt [s]. The rendered motion lasts
/// 0.47 s and the small side views lose the rim about 0.06 s before the true halt
/// (the rim height falls below 5 noise σ of a 0.26–0.3 mm pixel), so 0.35 s keeps the
/// initial state inside the footage.
const LEAD_S: f64 = 0.35;

/// The rendered set-up.
struct Setup {
    /// Side view above, plan view with the strip below (fig. 3.19).
    two_view: bool,
    /// Start on the stationary-rolling manifold (eq. 4.40) rather than at eq. 4.43
    /// itself, whose θ̇ is off the manifold and makes the disk slip and nutate.
    stationary_start: bool,
}

/// Renders the true motion at 480 fps (320 × 240 px side view, or 320 × 480 px two
/// views) and analyses it as a user's clip: the calibration points come from the
/// automatic rest-frame calibration (§3.2.4), nothing from the renderer's truth.
/// Returns the experiment and the truth.
fn closed_loop_experiment(dir: &Path, setup: &Setup) -> (Experiment, GroundTruth) {
    let params = Preset::EulerDisk.params();
    let mut spec = SimulationSpec::thesis_default(params, Dissipation::new(TRUE_MODEL), TRUE_ETA);
    if setup.stationary_start {
        // On the stationary-rolling manifold in the sense of eq. 4.43 (ψ̇ < 0, θ̇ > 0).
        let (psi_dot, theta_dot) = stationary_rolling(&params, PHI0).expect("stationary rolling");
        spec.initial.phi = PHI0;
        spec.initial.psi_dot = -psi_dot.abs();
        spec.initial.theta_dot = theta_dot.abs();
    }
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
    let mut render = RenderSpec::thesis(Plate::Dark, setup.two_view);
    (render.width, render.height) = if setup.two_view {
        (320, 480)
    } else {
        (320, 240)
    };
    let renderer = Renderer::new(&render, &motion).expect("renderer");
    let clip = dir.join("contour.mp4");
    write_clip(&renderer, &clip, eulerdisk::render::DEFAULT_ENCODING).expect("write clip");
    let config = ExperimentConfig {
        material: Some("stainless steel".into()),
        two_view: Some(setup.two_view),
        fps: Some(480.0),
        ..ExperimentConfig::default()
    };
    let experiment = analyse::analyse_clip(&clip, &config, &|_, _| {}).expect("analyse");
    (experiment, renderer.truth().clone())
}

/// The automatic calibration against the renderer's truth (vision coordinates are the
/// renderer's + ½ px). Seen from the 3° elevation the top face shows above the side,
/// lit more dimly: z_t is where they meet, the near top rim the truth records, not
/// the silhouette's top (the top face's far rim, 2R sin ε, 15 px, higher); on the
/// two-view render the strip's line across the top face must not move it. The scale
/// is then eq. 3.10's 2H/(z_base − z_t) = s/cos ε at the near rim, and the
/// orthographic camera shows no perspective (factor 1 against the diameter's).
fn check_calibration(experiment: &Experiment, truth: &GroundTruth) {
    let report = &experiment.plan.calibration;
    assert!(
        report.sources.iter().all(|s| *s == PointSource::Detected),
        "{:?}",
        report.sources
    );
    let (cal, t) = (&report.calibration, &truth.calibration);
    assert!(
        (experiment.plan.metres_per_px / truth.delta - 1.0).abs() < 0.005,
        "scale {} m/px, truth {} m/px",
        experiment.plan.metres_per_px,
        truth.delta
    );
    assert!(
        (experiment.plan.scale.perspective_factor - 1.0).abs() < 0.01,
        "{:?}",
        experiment.plan.scale
    );
    assert!(
        (cal.z_base - (t.z_base + 0.5)).abs() < 0.1,
        "z_base {cal:?} vs {t:?}"
    );
    assert!(
        (cal.z_t - (t.z_t + 0.5)).abs() < 0.3,
        "z_t {} vs near rim {}",
        cal.z_t,
        t.z_t + 0.5
    );
    assert!(
        !experiment.warnings.iter().any(|w| w.contains("eq. 3.10")),
        "eq. 3.10 warning: {:?}",
        experiment.warnings
    );
}

/// Side view only, 320 × 240 px, started on the stationary-rolling manifold: θ̇ of
/// the initial state from eq. 3.7, misfit on φ and ψ̇ at the peaks.
#[test]
fn compare_fit_side_view_recovers_eta_and_ranks_contour_first() {
    closed_loop(&Setup {
        two_view: false,
        stationary_start: true,
    });
}

/// Two views, 320 × 480 px, started on the stationary-rolling manifold: θ̇ of the
/// initial state from the strip by eq. 3.22, β̇ per frame in the misfit.
///
/// Started at eq. 4.43 itself (slip and nutation as in the thesis's fig. 4.12) the same
/// chain still recovers η (−0.9 % at lead 0.33 s, +6.9 % at 0.35 s), but the ranking
/// is a near-tie: the initial state falls in the fast correction after the start,
/// nutation the model does not have dominates the misfit, and classical rolling comes
/// out 1.28× worse than contour at lead 0.33 s and 1e-4 relative better at 0.35 s.
/// The ranking needs footage of a settled motion; this test uses one.
#[test]
fn compare_fit_two_view_recovers_eta_and_ranks_contour_first() {
    closed_loop(&Setup {
        two_view: true,
        stationary_start: true,
    });
}

fn closed_loop(setup: &Setup) {
    let dir = tempfile::tempdir().expect("tempdir");
    let experiment_dir = dir.path().join("contour");
    let (analysed, truth) = closed_loop_experiment(dir.path(), setup);
    check_calibration(&analysed, &truth);
    write_experiment(&experiment_dir, &analysed, None, None).expect("write experiment");
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
            "{:?}: η = {:?}, misfit = {:?}, n = {:?}, end − halt = {:?}, observable end = {:?}, {:?}",
            r.model,
            r.eta,
            r.misfit,
            r.energy_exponent,
            r.end_time_error_s,
            r.outcome.as_ref().ok().and_then(|c| c.observable_end_s),
            r.error
        );
    }
    let contour = ranked
        .iter()
        .find(|r| r.model == ModelKind::Contour)
        .expect("contour ranked");
    let comparison = contour.outcome.as_ref().expect("contour comparison");
    write_comparison(
        &comparison_dir(&experiment_dir, ModelKind::Contour),
        comparison,
        None,
    )
    .expect("write comparison");
    write_ranking(
        &experiment_dir.join("compare-all"),
        &experiment_dir,
        options.method,
        &ranked,
        None,
    )
    .expect("write ranking");
    for file in [
        "summary.json",
        "model.csv",
        "overlay.svg",
        "overlay.png",
        "index.html",
    ] {
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
    assert_eq!(
        misfit(ModelKind::CurvatureOffset),
        misfit(ModelKind::Contour)
    );
    assert!(
        misfit(ModelKind::ClassicalRolling) > misfit(ModelKind::Contour),
        "classical rolling fits better than the true model"
    );

    // Every model is fitted among those still moving at the measured halt (compare's
    // fit domain): none ends more than a frame before it.
    let frame = 1.0 / 480.0;
    for r in &ranked {
        let late = r.end_time_error_s.expect("compared");
        assert!(
            late >= -frame,
            "{:?} ends {late} s from the measured halt",
            r.model
        );
    }

    // The fitted model's rim falls below the footage's halt threshold close to the
    // measured halt (the footage loses the last turns, 15 ms each near the end;
    // classical rolling's is > 0.1 s late).
    let observable = comparison.observable_end_s.expect("observable end");
    assert!(
        (observable - LEAD_S).abs() < 0.03,
        "model rim below the threshold at {observable} s, measured halt at {LEAD_S} s"
    );

    // The model halts on the discontinuity set θ̇ = 0 (eq. 4.60) with a small residual
    // spin, as the thesis's contour run (ψ̇ = −0.051 rad/s, §4.7).
    assert_eq!(comparison.residual.end_reason, EndReason::DiscontinuitySet);
    assert!(comparison.residual.psi_dot.abs() < 1.0);
}

/// The lead of the initial state (issue 72 §6). The two-view fixture's peaks begin
/// within 0.5 s of the halt. Without a lead given (`lead_falls_back`), the comparison
/// starts from the earliest measured state, the first peak, and its warning names the
/// lead used; the same 0.5 s given is refused, naming the longest lead that fits, and
/// the lead named is accepted.
#[test]
fn compare_default_lead_falls_back_to_the_first_peak_and_a_given_one_is_refused() {
    let experiment = crate::util::analysed("two-view-n045.mp4", "fps = 480\ntwo_view = true\n");
    let dir = Path::new("two-view-n045");
    let first_lead = -experiment.series.peaks.peaks[0].t;
    assert!(
        first_lead < compare::DEFAULT_LEAD_S,
        "first peak {first_lead} s before"
    );
    let default = CompareOptions::new(ModelKind::AugmentedContour);

    let c = compare::compare(experiment, dir, &default).expect("the default lead");
    assert_eq!(c.options.lead_s, first_lead);
    let said = format!("earliest measured state, the first peak, with a lead of {first_lead:.4} s");
    assert!(
        c.warnings.iter().any(|w| w.contains(&said)),
        "{:?}",
        c.warnings
    );

    let given = CompareOptions {
        lead_falls_back: false,
        ..default
    };
    let refused = compare::compare(experiment, dir, &given)
        .expect_err("a given lead out of reach")
        .to_string();
    let longest: f64 = refused
        .split_once("the longest lead that fits is ")
        .and_then(|(_, rest)| rest.split_once(" s")?.0.parse().ok())
        .unwrap_or_else(|| panic!("no longest lead named: {refused}"));
    assert!(
        (first_lead..compare::DEFAULT_LEAD_S).contains(&longest),
        "{refused}"
    );
    let longest = CompareOptions {
        lead_s: longest,
        ..given
    };
    let c = compare::compare(experiment, dir, &longest).expect("the longest lead named");
    assert!(
        c.warnings
            .iter()
            .all(|w| !w.contains("earliest measured state"))
    );
}
