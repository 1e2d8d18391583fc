//! The measuring chain (footage → vision → signal → energy) against the ground
//! truth of the rendered fixtures (`scripts/make-fixtures`), and its errors on bad
//! input. Tolerances carry their reasons; where one is wider than the issue asks,
//! the comment says so and the README lists it under known limits.

use std::path::Path;

use crate::util::{f, fixture, truth};
use eulerdisk::analyse::{AnalyseError, Experiment, analyse_clip};
use eulerdisk::config::ExperimentConfig;
use eulerdisk::vision::RimReading;
use serde_json::Value;

/// How close t_φ, where the laws place the halt (`analyse::law_halt`), comes to the
/// true halt: half a frame (measured 0.10 frames on the dark-plate fixture).
const HALT_PLACED_S: f64 = 0.5 / 480.0;

fn config(text: &str) -> ExperimentConfig {
    ExperimentConfig::parse(text, Path::new("test.toml")).unwrap()
}

/// The fixture NAME analysed with the config TEXT (once for all tests: `util`).
fn analyse(name: &str, text: &str) -> &'static Experiment {
    crate::util::analysed(name, text)
}

#[test]
fn dark_plate_clip_matches_its_ground_truth() {
    let truth = truth("side-dark-n050.truth.json");
    let e = analyse("side-dark-n050.mp4", "fps = 480\n[fit]\nhalt = \"free\"\n");
    // A clip under 8 s is decoded whole (issue 14 §3), as before spans.
    let decoded = e.plan.decoded.as_ref().unwrap();
    assert!(
        decoded.is_whole() && decoded.reason.contains("decoded whole"),
        "{decoded:?}"
    );
    assert_eq!(decoded.clip_frames, e.frames.len());
    let cal = &e.plan.calibration.calibration;
    let tc = &truth["calibration"];
    // The renderer puts pixel centres at integers, vision at c + ½: a truth
    // point p is p + ½ here. Ends of the disk: within 0.13 px (the shading falls
    // off towards the ends and pulls an edge inwards). 0.2 px.
    assert!(
        (cal.x_l - f(&tc["x_l"]) - 0.5).abs() < 0.2,
        "x_l {}",
        cal.x_l
    );
    assert!(
        (cal.x_r - f(&tc["x_r"]) - 0.5).abs() < 0.2,
        "x_r {}",
        cal.x_r
    );
    // The plate line, the disk → reflection step placed by its area: −0.01 px
    // (the linear half-level crossing read +0.07 px). 0.1 px.
    assert!(
        (cal.z_base - f(&tc["z_base"]) - 0.5).abs() < 0.1,
        "z_base {}",
        cal.z_base
    );
    // Scale from the diameter: 0.2 % (the ends to 0.5 px over 432 px).
    let delta = f(&truth["delta"]);
    assert!((e.plan.metres_per_px / delta - 1.0).abs() < 2e-3);

    // z_rim on every frame: within 0.3 px RMS of the ray-cast truth (issue §7).
    let frames = truth["frames"].as_array().unwrap();
    let (mut sum, mut count) = (0.0, 0);
    for (measured, t) in e.frames.iter().zip(frames) {
        if let Some(z) = measured.z_rim_px {
            sum += (z - f(&t["z_rim_px"])).powi(2);
            count += 1;
        }
    }
    assert!(count > 300, "{count} frames with an edge");
    let rms = (sum / count as f64).sqrt();
    assert!(rms < 0.3, "z_rim RMS error {rms} px");

    // Peak count in the last 0.5 s: exact (truth: local maxima above 0.2 px).
    let z: Vec<f64> = frames.iter().map(|t| f(&t["z_rim_px"])).collect();
    let t: Vec<f64> = frames.iter().map(|t| f(&t["t"])).collect();
    let true_peaks = (1..z.len() - 1)
        .filter(|&i| {
            z[i] > z[i - 1] && z[i] >= z[i + 1] && (-0.5..=0.0).contains(&t[i]) && z[i] > 0.2
        })
        .count();
    assert_eq!(e.series.peaks.peaks.len(), true_peaks);

    // Halt: the last frame with motion lies at most 2 frames (4.2 ms) before the
    // true halt — motion under 0.1 px (5 σ of the noise floor) is invisible, and
    // z_rim passes through zero once a turn.
    let true_halt = f(&truth["halt_time"]);
    let seen = e.frames[e.series.halt.index].t_capture;
    assert!(
        seen <= true_halt + 1e-9 && true_halt - seen < 2.5 / 480.0,
        "last motion seen at {seen}"
    );
    // t_φ where the laws place the halt (t0 and the turns' end): within half a frame.
    let t_phi = e.series.halt.t_phi;
    assert!((t_phi - true_halt).abs() < HALT_PLACED_S, "t_φ {t_phi}");
    // The placement is recorded on t_φ's clock: the last motion seen where the frames
    // put it, t0 and T either side of t_φ by the same amount (t_φ is their mean), and
    // a standard error the error lies within three of.
    let placed = e.halt_placement.expect("t_φ placed by the laws");
    assert!((placed.last_motion_seen_s - e.frames[e.series.halt.index].t).abs() < 1e-12);
    let turns_end = placed.turns_end_s.expect("the turns timed");
    assert!((placed.t0_s + turns_end).abs() < 1e-9, "{placed:?}");
    let se = placed.se_s.expect("t_φ's standard error");
    assert!((t_phi - true_halt).abs() < 3.0 * se, "t_φ {t_phi} ± {se}");
    // The fitted halts: within 6 ms. H.264 at OpenCV's fixed crf 23 reads the narrow
    // gaps of the last turns 0.1 px low (0.01 px on the same frames stored
    // losslessly, where the peaks' halt is within 2.5 ms: tests/power_law.rs), and
    // the encoder's choices move the halts: six renders of this clip that differ
    // only in the strip's angle on the top face (`--beta0` 0.3 to 2.6) gave −5.0 to
    // +0.5 ms per frame and −5.1 to −0.7 ms at the peaks.
    let per_frame = e.frames_fit.as_ref().expect("per-frame fit");
    let frames_halt = t_phi + per_frame.fit.t0;
    assert!(
        (frames_halt - true_halt).abs() < 6e-3,
        "per-frame halt {frames_halt}"
    );
    let peaks_halt = t_phi + e.peaks_fit.fit.t0;
    assert!(
        (peaks_halt - true_halt).abs() < 6e-3,
        "peaks' halt {peaks_halt}"
    );

    // n: 0.487 for the true 0.5 (issue: ±0.02), 0.491 per frame. Below 2 px the
    // rim height comes from the darkness of the gap (vision::gap). The six renders
    // above gave 0.487–0.507 at the peaks and 0.474–0.506 per frame: on H.264 at
    // crf 23 the ±0.02 holds at the peaks, and per frame on five of six.
    let n = e.peaks_fit.fit.n;
    let true_n = f(&truth["true_n"]);
    assert!((n - true_n).abs() < 0.02, "n = {n}");
    assert!(
        (per_frame.fit.n - true_n).abs() < 0.02,
        "per-frame n = {}",
        per_frame.fit.n
    );
    let (lo, hi) = e.peaks_fit.fit.ci95_n;
    assert!((lo..=hi).contains(&true_n), "95 % CI {lo}…{hi}");
}

/// Every frame carries the codec's picture type, as libavcodec decoded it: the MP4's
/// own list of key frames (its sync samples, read without decoding) are I pictures,
/// the fixture's x264 stream also holds P and B pictures, and a frame folder has
/// none.
#[test]
fn frames_carry_their_picture_type() {
    let e = analyse("side-dark-n050.mp4", "fps = 480\n");
    let index = eulerdisk::footage::FrameSource::open(&fixture("side-dark-n050.mp4"))
        .unwrap()
        .stream_index()
        .unwrap()
        .expect("an MP4's index");
    assert!(!index.key_frames.is_empty());
    for &k in &index.key_frames {
        assert_eq!(e.frames[k].picture_type, Some('I'), "key frame {k}");
    }
    let count = |kind: char| {
        e.frames
            .iter()
            .filter(|f| f.picture_type == Some(kind))
            .count()
    };
    assert_eq!(
        count('I') + count('P') + count('B'),
        e.frames.len(),
        "every frame I, P or B"
    );
    assert!(
        count('P') > 0 && count('B') > 0,
        "P {} B {}",
        count('P'),
        count('B')
    );
    let mut folder = eulerdisk::footage::FrameSource::open(&fixture("side-dark-png")).unwrap();
    let first = folder.next_frame().unwrap().expect("a frame");
    assert_eq!(first.picture_type, None);
}

/// The precession check (`eulerdisk::precession`) reads the scale through a relation
/// that shares nothing with it. The fixture's disk rolls by eq. 2.29 (corrected), so
/// the check's ratio of the heights' φ to the precession's is the states' own error
/// against the truth (measured −1.3 %, both), and within the check's reach no warning
/// is raised. With z_t set in the config 6 % of the side's height too high, eq.
/// 3.10's scale is 1/1.06 of the right one: the check reads the heights' φ that much
/// lower and warns.
#[test]
fn the_precession_rate_checks_the_scale() {
    let truth = truth("side-dark-n050.truth.json");
    let e = analyse("side-dark-n050.mp4", "fps = 480\n");
    let check = e.precession.expect("a precession check");
    let frames = truth["frames"].as_array().unwrap();
    let mut errors: Vec<f64> = e
        .series
        .states
        .iter()
        .filter(|s| s.t >= -e.plan.window_s)
        .map(|s| s.phi / f(&frames[s.index]["phi"]) - 1.0)
        .collect();
    errors.sort_by(f64::total_cmp);
    let states_error = errors[errors.len() / 2];
    assert!(
        (check.agreement() - 1.0 - states_error).abs() < 0.005,
        "states' φ {:+.2} % from the truth; {}",
        100.0 * states_error,
        check.describe()
    );
    let warned = |e: &Experiment| {
        e.warnings
            .iter()
            .any(|w| w.contains("precession's disagree"))
    };
    assert!(!warned(e), "{:?}", e.warnings);
    let moved = analyse("side-dark-n050.mp4", &top_rim_misread(e, 0.06));
    assert!(moved.plan.scale.at_near_rim(), "{}", moved.plan.scale.used);
    let scale = moved.plan.metres_per_px / e.plan.metres_per_px;
    assert!((scale * 1.06 - 1.0).abs() < 0.005, "scale ×{scale}");
    let misread = moved.precession.expect("a precession check");
    let ratio = misread.agreement() / check.agreement();
    assert!(
        (ratio - scale).abs() < 0.01,
        "×{ratio}: {}",
        misread.describe()
    );
    assert!(warned(moved), "{:?}", moved.warnings);
}

/// A config (480 fps) with `e`'s calibration but the near top rim z_t moved up by
/// `share` of the side's height, which makes the scale that much too small.
fn top_rim_misread(e: &Experiment, share: f64) -> String {
    let c = &e.plan.calibration.calibration;
    format!(
        "fps = 480\n[calibration]\nx_l = {}\nx_r = {}\nz_t = {}\nz_base = {}\n",
        c.x_l,
        c.x_r,
        c.z_t - share * (c.z_base - c.z_t),
        c.z_base
    )
}

/// n from the turns' timing alone (eulerdisk::turn_timing) recovers the fixture's n
/// within its interval, and neither the zero of z_rim nor the scale moves it: the
/// zero taken from the still disk's edge instead of the motion (about 0.09 px apart
/// here) moves the peaks fit's n by 0.007 and the timing's by 0.0003; the scale
/// misread by 6 % (z_t moved) moves the timing's by 0.0002.
#[test]
fn the_turns_timing_gives_n_without_the_heights() {
    let true_n = f(&truth("side-dark-n050.truth.json")["true_n"]);
    let timing = |e: &Experiment| {
        e.turn_timing
            .clone()
            .expect("recorded")
            .expect("a timing fit")
    };
    let e = analyse("side-dark-n050.mp4", "fps = 480\n");
    let fit = timing(e);
    assert!((fit.n - true_n).abs() < 0.01, "n = {}", fit.n);
    assert!(
        (fit.ci95_n.0..=fit.ci95_n.1).contains(&true_n),
        "{:?}",
        fit.ci95_n
    );
    assert!(fit.points >= 40, "{} turning points", fit.points);

    let rest = analyse(
        "side-dark-n050.mp4",
        "fps = 480\n[fit]\nrim_zero = \"rest\"\n",
    );
    assert!(rest.plan.rim_zero_from_motion.is_none());
    let heights_moved = (rest.peaks_fit.fit.n - e.peaks_fit.fit.n).abs();
    let timing_moved = (timing(rest).n - fit.n).abs();
    assert!(
        heights_moved > 0.004 && timing_moved < 0.1 * heights_moved,
        "the zero moved the heights' n by {heights_moved}, the timing's by {timing_moved}"
    );

    let misread = analyse("side-dark-n050.mp4", &top_rim_misread(e, 0.06));
    assert!((misread.plan.metres_per_px / e.plan.metres_per_px * 1.06 - 1.0).abs() < 0.005);
    assert!((timing(misread).n - fit.n).abs() < 0.001);
}

#[test]
fn two_view_clip_gives_the_strip_angle_and_its_stop() {
    let truth = truth("two-view-n045.truth.json");
    let e = analyse(
        "two-view-n045.mp4",
        "fps = 480\ntwo_view = true\n[fit]\nhalt = \"free\"\n",
    );
    let frames = truth["frames"].as_array().unwrap();
    let mut worst: f64 = 0.0;
    for (measured, t) in e.frames.iter().zip(frames) {
        let beta = measured.beta_raw.expect("strip found on every frame");
        let d = (beta - f(&t["beta"])).rem_euclid(std::f64::consts::PI);
        worst = worst.max(d.min(std::f64::consts::PI - d));
    }
    // PCA on a clean strip of a few hundred pixels (issue §7: 0.005 rad).
    assert!(worst < 0.005, "worst β error {worst} rad");
    let strip = e.series.strip.as_ref().unwrap();
    let t_beta_clip = e.series.halt.t_phi + strip.rotation_after_flat;
    let true_t_beta = f(&truth["halt_time"]) + f(&truth["t_beta"]);
    // t_β from the Coulomb stop fitted to β (eq. 4.112): −0.05 frame here, and within
    // 0.22 frame on eight renders made before the renderer kept β̇ through the halt
    // (n 0.35–0.65, sub-frame halts, β̇₀ −2 to −4 rad/s, noise 0–2). The band of
    // fig. 3.22 read +2.5
    // frames here (H.264 codes the still frames exactly, a band of zero width, while
    // the last moving frames carry 3e-4 rad of coding error) and −4.3 to +3.7 frames on
    // those renders. Issue §7: two frames.
    assert!(
        (t_beta_clip - true_t_beta).abs() < 2.0 / 480.0,
        "t_β {t_beta_clip} vs {true_t_beta}"
    );
    // The fitted deceleration is the rim friction's, μ m g R / C (eq. 4.112 as in
    // ERRATA, with the renderer's μ = 0.134 of Table 3.1): 69.6 against 68.9 rad/s².
    // 3 %.
    let disk = &truth["disk"];
    let friction =
        0.134 * f(&disk["mass"]) * f(&disk["gravity"]) * f(&disk["radius"]) / f(&disk["inertia_c"]);
    let fit = strip.stop.fit.as_ref().expect("Coulomb stop fit");
    assert!(
        (fit.deceleration / friction - 1.0).abs() < 0.03,
        "deceleration {} vs {friction} rad/s²",
        fit.deceleration
    );
    // θ̇ from the strip (θ̇ = β̇ − ψ̇, eq. 3.22): the full-state energy of eq. (3.6)
    // on the measured states matches eq. (3.6) on the true φ, ψ̇, θ̇ of the same
    // frames. The disk carries its spin into the flat (β̇ → β̇₀ = −2.8 rad/s at the
    // halt), so eq. (3.6) keeps C/2 β̇₀² + m/2 (R β̇₀)² there and its power law is not
    // the prescribed one; eq. (3.8) is.
    let full = e.full_state_fit.as_ref().expect("eq. 3.6 fit");
    let disk: eulerdisk::model::params::DiskParams =
        serde_json::from_value(truth["disk"].clone()).unwrap();
    let clip_halt = f(&truth["halt_time"]);
    let mut errors: Vec<f64> = full
        .samples
        .iter()
        .filter(|s| s.t < -0.05)
        .map(|s| {
            let clip_t = s.t + e.series.halt.t_phi;
            let k = ((clip_t * 480.0).round() as usize).min(frames.len() - 1);
            let t = &frames[k];
            let true_energy = eulerdisk::energy::rolling_energy(
                &disk,
                f(&t["phi"]),
                0.0,
                f(&t["psi_dot"]),
                f(&t["theta_dot"]),
            );
            assert!((f(&t["t"]) + clip_halt - clip_t).abs() < 1e-6);
            (s.energy / true_energy - 1.0).abs()
        })
        .collect();
    assert!(errors.len() > 100, "{} states", errors.len());
    errors.sort_by(f64::total_cmp);
    // 1.3 % here; per-frame φ carries ~2 % (issue §7 at the peaks), and E ∝ φ near
    // the flat.
    let median = errors[errors.len() / 2];
    assert!(median < 0.02, "median |ΔE/E| of eq. 3.6 = {median}");
    // The prescribed motion has n = 0.45: within 0.02 (issue §6), inside the CI,
    // and the per-frame fit agrees.
    let true_n = f(&truth["true_n"]);
    let fit = &e.peaks_fit.fit;
    assert!((fit.n - true_n).abs() < 0.02, "n = {}", fit.n);
    assert!(
        (fit.ci95_n.0..=fit.ci95_n.1).contains(&true_n),
        "CI {:?}",
        fit.ci95_n
    );
    let per_frame = &e.frames_fit.as_ref().expect("per-frame fit").fit;
    assert!(
        (per_frame.n - true_n).abs() < 0.02,
        "per-frame n = {}",
        per_frame.n
    );
}

/// Frame skips (issue §5, §7): the light fixture lost captures 40 and 171, so file
/// frames 40 and 170 follow a skip; the timestamps are renumbered, so only the rim's
/// phase shows them. The dark and two-view fixtures have no drops and no flags.
#[test]
fn light_plate_drops_are_flagged_and_clean_clips_are_not() {
    let truth = truth("side-light-n067-artefacts.truth.json");
    assert_eq!(truth["dropped"], serde_json::json!([40, 171]));
    let e = analyse(
        "side-light-n067-artefacts.mp4",
        "fps = 480\nplate = \"light\"\n",
    );
    let flagged: Vec<usize> = e.series.flags.iter().map(|f| f.index).collect();
    // Capture 171 lies 69 frames before the halt (capture 240): peaks of 3 px at 8
    // frames per period, through sensor noise, blur, flicker and H.264. Its
    // phase-step statistic is F = 21 on file frames 170 and 171 alike (threshold 10;
    // frames more than three from a skip give F ≤ 0), so the flag may land one frame
    // late; on
    // five renders with other seeds it landed on 170 four times. Frame 40: F = 141.
    assert_eq!(flagged.len(), 2, "{:?}", e.series.flags);
    assert_eq!(flagged[0], 40);
    assert!((170..=171).contains(&flagged[1]), "{:?}", e.series.flags);
    assert!(
        e.series
            .flags
            .iter()
            .all(|f| matches!(f.reason, eulerdisk::signal::SkipReason::RimPhaseStep { .. }))
    );
    let dark = analyse("side-dark-n050.mp4", "fps = 480\n");
    assert!(dark.series.flags.is_empty(), "{:?}", dark.series.flags);
    // The two-view fixture has no drops either. H.264 leaves a frame's small strip
    // turn behind and catches up later (raw β̇ spikes, which the thesis's spike test
    // flagged); the angle-step test does not flag them.
    let two_view = analyse("two-view-n045.mp4", "fps = 480\ntwo_view = true\n");
    assert!(
        two_view.series.flags.is_empty(),
        "{:?}",
        two_view.series.flags
    );
}

/// Drops in a two-view clip (issue §5, §7): one before the halt, which the rim's
/// phase and the strip both show, and one 3 frames after it, where the rim is still
/// and only the strip turns (β̇ = −2.4 rad/s: a measured step of 3.7 mrad, 7.2 ×
/// the clip's 0.52 mrad spread of steps). The renderer's β̇ is continuous at the
/// halt, as on real footage (thesis fig. 3.28); with the jump it had before, this
/// drop went unflagged.
#[test]
fn two_view_drops_before_and_after_the_halt_are_flagged() {
    let dir = tempfile::tempdir().unwrap();
    let out = crate::util::eulerdisk(
        dir.path(),
        &[
            "render",
            "--two-view",
            "--n",
            "0.45",
            "--halt",
            "0.5",
            "--size",
            "320x480",
            "--drop",
            "150,243",
            "-o",
            "drops.mp4",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let config = config("fps = 480\ntwo_view = true\n");
    let e = analyse_clip(&dir.path().join("drops.mp4"), &config, &|_, _| {}).expect("analyse");
    // Captures 150 and 243 are missing: file frames 150 and 242 follow the skips.
    let mut flagged: Vec<usize> = e.series.flags.iter().map(|f| f.index).collect();
    flagged.dedup();
    assert_eq!(flagged, vec![150, 242], "{:?}", e.series.flags);
    let strip_only = e.series.flags.iter().filter(|f| f.index == 242);
    assert!(strip_only.into_iter().all(|f| matches!(
        f.reason,
        eulerdisk::signal::SkipReason::StripAngleStep { .. }
    )));
}

#[test]
fn bad_input_fails_with_the_file_and_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let quiet = |_: usize, _: Option<usize>| {};
    let cfg = config("fps = 480\n");

    // A truncated MP4.
    let bytes = std::fs::read(fixture("side-dark-n050.mp4")).unwrap();
    let cut = dir.path().join("cut.mp4");
    std::fs::write(&cut, &bytes[..bytes.len() / 3]).unwrap();
    let err = analyse_clip(&cut, &cfg, &quiet).unwrap_err().to_string();
    assert!(err.contains("cut.mp4"), "{err}");

    // No disk in view: black frames.
    let black = dir.path().join("black");
    std::fs::create_dir(&black).unwrap();
    for i in 0..20 {
        image::RgbImage::new(64, 48)
            .save(black.join(format!("f{i}.png")))
            .unwrap();
    }
    let err = analyse_clip(&black, &cfg, &quiet).unwrap_err();
    assert!(matches!(err, AnalyseError::Vision { .. }), "{err}");
    assert!(
        err.to_string().contains("black") && err.to_string().contains("no disk"),
        "{err}"
    );

    // A frame folder has no fps of its own.
    let err = analyse_clip(&black, &ExperimentConfig::default(), &quiet).unwrap_err();
    assert!(err.to_string().contains("fps"), "{err}");

    // Too few peaks: 19 frames at 60 fps around the halt.
    let err = analyse_clip(&fixture("side-dark-png"), &config("fps = 60\n"), &quiet).unwrap_err();
    assert!(matches!(err, AnalyseError::Signal { .. }), "{err}");
    assert!(err.to_string().contains("side-dark-png"), "{err}");
}

/// A rounded rim (issue 12 §4: the open footage's rims are rounded, and their
/// side fades out 1–2.6 px above the true rim). Rendered with `--edge-radius 0.6`
/// (3.3 px at this scale), the side's edge at rest lies 1.6 px above the rim, so
/// eq. 3.10 with z_base read the thickness 2.8 % short; the mirror-edge model finds
/// the rim rounded, and the plate line where the rim meets its mirror image gives
/// the scale: measured +0.25 %, and z_rim 0.09 px RMS from the truth.
#[test]
fn a_rounded_rim_is_scaled_from_the_plate_line() {
    let (e, truth) = render_and_analyse(&[
        "--n",
        "0.5",
        "--halt",
        "0.8",
        "--size",
        "480x270",
        "--edge-radius",
        "0.6",
        "--noise",
        "1",
    ]);
    let plan = &e.plan;
    assert!(plan.rim.starts_with("mirror-edge model"), "{}", plan.rim);
    // Rows: the truth's on pixel centres at integers, ours at half-integers.
    let rim_row = f(&truth["calibration"]["z_base"]) + 0.5;
    let cal = &plan.calibration.calibration;
    assert!(
        rim_row - cal.z_base > 1.0,
        "the side's edge at rest {} px, the rim {rim_row} px",
        cal.z_base
    );
    let bottom = plan.scale.bottom_rim_row_px.expect("z_b");
    assert!((bottom - rim_row).abs() < 0.4, "z_b {bottom} vs {rim_row}");
    let near_rim = f(&truth["camera"]["near_rim_metres_per_px"]);
    let error = plan.metres_per_px / near_rim - 1.0;
    assert!(error.abs() < 0.006, "scale error {:+.2} %", 100.0 * error);
    let frames = truth["frames"].as_array().unwrap();
    assert_eq!(e.frames.len(), frames.len());
    let squares: Vec<f64> = e
        .frames
        .iter()
        .zip(frames)
        .filter_map(|(m, t)| Some((m.z_rim_px? - f(&t["z_rim_px"])).powi(2)))
        .collect();
    let rms = (squares.iter().sum::<f64>() / squares.len() as f64).sqrt();
    assert!(rms < 0.15, "z_rim RMS error {rms} px");
}

/// A phone held close and a little above the plate: 0.25 m from the near rim, 3° up.
const CLOSE_CAMERA: [&str; 12] = [
    "--n",
    "0.5",
    "--halt",
    "0.8",
    "--size",
    "240x160",
    "--camera-distance",
    "0.25",
    "--elevation",
    "3",
    "--noise",
    "1",
];

/// A phone held close and a little above the plate (0.25 m, 3°) sees the top face
/// only 1–3 px tall above the side, too thin for the calibration's two plateaus; the
/// fitted three-level profile (`vision::calibration::thin_top_face`) finds the near
/// top rim z_t there, where the silhouette's top (the far rim, the fallback before)
/// lies 2–3 px higher, so eq. 3.10's scale at the near rim holds.
#[test]
fn a_thin_top_face_gives_the_near_top_rim() {
    let (e, truth) = render_and_analyse(&CLOSE_CAMERA);
    let (near, far) = assert_near_top_rim(&e, &truth, 0.5);
    assert!(near - far > 1.0, "the top face is {} px tall", near - far);
}

/// The same on a light plate lit from 60° above (a scene of an earlier robustness
/// draw): the top face, 4 px tall seen from 2.8° at 0.32 m under a 0.94 px blur and
/// crf 23, showed no plateau to the two-plateau readings, and the light plate's
/// calibration took the silhouette's top (the far rim) for z_t, 4.1 px high, the
/// scale 7 % small. The three-level fit, now tried on light plates too, reads the
/// near rim (−0.35 px).
#[test]
fn a_thin_top_face_on_a_light_plate_gives_the_near_top_rim() {
    let (e, truth) = render_and_analyse(&[
        "--n",
        "0.5146069",
        "--halt",
        "0.65",
        "--after-halt",
        "0.15",
        "--size",
        "320x180",
        "--plate",
        "light",
        "--paper-grey",
        "238",
        "--texture",
        "0.1336208",
        "--fill-elevation",
        "60",
        "--elevation",
        "2.841181",
        "--camera-distance",
        "0.31517475",
        "--blur",
        "0.93518455",
        "--noise",
        "1.7135416",
        "--shot-noise",
        "0.0378719",
        "--flicker",
        "0.03683777",
        "--flicker-50",
        "0.0087993",
        "--flicker-phase-100",
        "4.0455808",
        "--flicker-phase-50",
        "5.7794672",
        "--exposure",
        "0.0005",
        "--exposure-samples",
        "2",
        "--psi-halt",
        "2.9665177",
        "--beta0",
        "0.3",
        "--seed",
        "1003",
    ]);
    assert!(e.plan.plate.starts_with("light"), "{}", e.plan.plate);
    let (near, far) = assert_near_top_rim(&e, &truth, 0.5);
    assert!(near - far > 3.0, "the top face is {} px tall", near - far);
}

/// A light plate much brighter than the disk's side (grey 227 against 141, a
/// robustness draw's scene, seed 0's s21) seen from 0.39 m: the dark plate's
/// threshold splits the disk's side where its shading crosses γ, 12 px inside each
/// end, and that calibration implied a plausible camera (perspective factor 1.17
/// against 1.10), so the plate was taken for dark and the disk 8 % narrow. Its ends
/// show no edge; the light plate's calibration, whose ends do, is taken.
#[test]
fn a_light_plate_brighter_than_the_disk_is_detected_by_the_disk_ends() {
    let (e, truth) = render_and_analyse(&[
        "--n",
        "0.54",
        "--halt",
        "0.5",
        "--after-halt",
        "0.1",
        "--size",
        "320x180",
        "--plate",
        "light",
        "--plate-grey",
        "227",
        "--paper-grey",
        "141",
        "--camera-distance",
        "0.39",
        "--elevation",
        "2.8",
        "--blur",
        "0.8",
        "--noise",
        "1.2",
        "--seed",
        "21",
    ]);
    assert!(e.plan.plate.starts_with("light"), "{}", e.plan.plate);
    let cal = &e.plan.calibration.calibration;
    // Columns: the truth's on pixel centres at integers, ours at half-integers.
    for (x, name) in [(cal.x_l, "x_l"), (cal.x_r, "x_r")] {
        let true_x = f(&truth["calibration"][name]) + 0.5;
        assert!((x - true_x).abs() < 1.0, "{name} {x} px, truth {true_x}");
    }
    assert_near_top_rim(&e, &truth, 0.5);
}

/// The strip on the top face resting 82° from across the view (ψ_h + β0 = 1.43 rad),
/// nearly pointing at the camera, on a light plate seen from 1.6° above: on the
/// centre band it runs from the far top rim to 2 px above the near one, and its
/// edge was read as the rim (z_t 1.9 px high, scale −3.4 %). The bands across the
/// face read the near rim beside the strip (`vision::top_rim`).
#[test]
fn a_strip_pointing_at_the_camera_leaves_the_near_top_rim() {
    let (e, truth) = render_and_analyse(&[
        "--n",
        "0.5",
        "--halt",
        "0.6",
        "--after-halt",
        "0.15",
        "--size",
        "320x180",
        "--plate",
        "light",
        "--plate-grey",
        "207",
        "--paper-grey",
        "180",
        "--elevation",
        "1.6",
        "--blur",
        "0.6",
        "--noise",
        "1.7",
        "--psi-halt",
        "1.13",
        "--seed",
        "9",
    ]);
    assert_near_top_rim(&e, &truth, 0.3);
}

/// A camera distance measured with a tape and given in the config
/// (`camera_distance_m`) replaces the perspective factor's: the plan and the page say
/// so, and the camera's elevation at the near bottom rim follows from it. A camera
/// 0.25 m from the near rim, 3° up: the ray to the near bottom rim is 3.46° down
/// (the truth's camera position); from the config's distance ε is read within 0.3°.
/// Its error is the coding noise's on the thin top face's edge: over this scene's
/// seeds 1–8 it is −0.04 … +0.19° (0.07° RMS), and −0.08 … +0.25° (0.12° RMS)
/// with libswscale's exact conversions, which code and read the same frames with
/// other roundings (the history of 5374188's BENCHMARKS.md, "libswscale's rounding on every CPU").
#[test]
fn a_camera_distance_given_in_the_config_places_the_camera() {
    let (dir, truth) = render_clip(&CLOSE_CAMERA);
    let camera = &truth["camera"];
    let position = camera["position_m"].as_array().unwrap();
    let e = analyse_clip(
        &dir.path().join("clip.mp4"),
        &config("fps = 480\ncamera_distance_m = 0.25\n"),
        &|_, _| {},
    )
    .expect("analyse");
    // The near bottom rim at rest is R in front of the disk's centre, on the plate.
    let (behind, above) = (-f(&position[1]), f(&position[2]));
    let elevation = (above / (behind - e.plan.disk.radius)).atan();
    let scale = &e.plan.scale;
    assert!(scale.camera_distance_from_config);
    assert_eq!(scale.camera_distance_m, Some(0.25));
    let measured = scale.near_rim_elevation_rad.expect("ε");
    assert!(
        (measured - elevation).abs() < 0.3f64.to_radians(),
        "ε {:.3}° against the truth's {:.3}°",
        measured.to_degrees(),
        elevation.to_degrees()
    );
    let near = f(&camera["near_rim_metres_per_px"]);
    let error = e.plan.metres_per_px / near - 1.0;
    assert!(error.abs() < 0.01, "scale error {:+.2} %", 100.0 * error);
}

/// z_t within `tolerance` px of the truth's near top rim, and eq. 3.10's scale within
/// 2 % of the truth's at the near rim; returns the near and far top rims' rows.
fn assert_near_top_rim(e: &Experiment, truth: &Value, tolerance: f64) -> (f64, f64) {
    // Rows: the truth's on pixel centres at integers, ours at half-integers.
    let near = f(&truth["calibration"]["z_t"]) + 0.5;
    let far = f(&truth["camera"]["z_t_far"]) + 0.5;
    let z_t = e.plan.calibration.calibration.z_t;
    assert!(
        (z_t - near).abs() < tolerance,
        "z_t {z_t} px, near rim {near}, far {far}"
    );
    let scale = f(&truth["camera"]["near_rim_metres_per_px"]);
    let error = e.plan.metres_per_px / scale - 1.0;
    assert!(error.abs() < 0.02, "scale error {:+.2} %", 100.0 * error);
    (near, far)
}

/// A sharp rim under a 0.8 px blur: the rest frames alone put the plate line
/// 0.56 px below the edge, which took this rim for a rounded one, and the
/// mirror-edge model then read the lifted heights of the last 0.5 s 0.12 px high
/// (n −0.08 from the per-frame fit). The frames near contact put the plate line at
/// the edge (0.03 px), and the model is fitted there.
#[test]
fn a_blurred_sharp_rim_is_not_taken_for_a_rounded_one() {
    let (e, truth) = render_and_analyse(&[
        "--n",
        "0.6542",
        "--halt",
        "0.6",
        "--after-halt",
        "0.15",
        "--size",
        "320x240",
        "--seed",
        "51",
        "--plate",
        "dark",
        "--blur",
        "0.8",
        "--noise",
        "1",
    ]);
    assert!(e.plan.rim.contains("a sharp rim"), "{}", e.plan.rim);
    assert_eq!(e.plan.rim_reading, Some(RimReading::SharpMirrorEdge));
    // Frames lifted past 0.5 px in the last 0.5 s: their mean error is the zero's
    // (one draw of the codec's error of the still frames), within the 1σ uncertainty
    // measured for a sharp rim read by the model on other renders.
    let frames = truth["frames"].as_array().unwrap();
    let errors: Vec<f64> = e
        .frames
        .iter()
        .zip(frames)
        .filter(|(_, t)| (-0.5..0.0).contains(&f(&t["t"])) && f(&t["z_rim_px"]) > 0.5)
        .filter_map(|(m, t)| Some(m.z_rim_px? - f(&t["z_rim_px"])))
        .collect();
    assert!(errors.len() > 100, "{} lifted frames", errors.len());
    let mean = errors.iter().sum::<f64>() / errors.len() as f64;
    assert!(
        mean.abs() < e.plan.rim_zero_uncertainty_px,
        "lifted heights {mean:+.3} px off on average (1σ {} px)",
        e.plan.rim_zero_uncertainty_px
    );
}

/// Renders a clip with `eulerdisk render ARGS` and analyses it at 480 fps: the
/// experiment and the render's truth.
fn render_and_analyse(args: &[&str]) -> (Experiment, Value) {
    let (dir, truth) = render_clip(args);
    let e = analyse_clip(
        &dir.path().join("clip.mp4"),
        &config("fps = 480\n"),
        &|_, _| {},
    )
    .expect("analyse");
    (e, truth)
}

/// `eulerdisk render ARGS -o clip.mp4` into a new folder; the folder and the truth.
fn render_clip(args: &[&str]) -> (tempfile::TempDir, Value) {
    let dir = tempfile::tempdir().unwrap();
    let mut render = vec!["render"];
    render.extend_from_slice(args);
    render.extend_from_slice(&["-o", "clip.mp4"]);
    let out = crate::util::eulerdisk(dir.path(), &render);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let truth: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("clip.truth.json")).unwrap())
            .unwrap();
    (dir, truth)
}

/// The light fixture's two lost captures (40 and 171) leave no gap in its timestamps
/// (`fps = 480` times the frames by their index): the rim's phase steps show them, and
/// every frame from each step on is counted one frame later. The capture clock is
/// then the truth's on every frame but the one between a step's two candidate frames
/// (F = 21 on 170 and 171 alike, see above); on the file clock every frame after the
/// first loss read one frame early, after the second two.
#[test]
fn frames_the_rim_shows_missing_are_counted_on_the_capture_clock() {
    let truth = truth("side-light-n067-artefacts.truth.json");
    let e = analyse(
        "side-light-n067-artefacts.mp4",
        "fps = 480\nplate = \"light\"\n",
    );
    let true_t: Vec<f64> = truth["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| f(&t["t"]))
        .collect();
    assert_eq!(true_t.len(), e.frames.len());
    let off: Vec<usize> = (0..e.frames.len())
        .filter(|&i| {
            let measured = e.frames[i].t_capture - e.frames[0].t_capture;
            (measured - (true_t[i] - true_t[0])).abs() > 1e-9
        })
        .collect();
    assert!(off.len() <= 1 && off.iter().all(|&i| i == 170), "{off:?}");
    assert!(
        e.warnings
            .iter()
            .any(|w| w.contains("counted one frame later")),
        "{:?}",
        e.warnings
    );
}
