//! The measured exponent against the truth (issue 4 §6): on rendered clips with
//! known n ∈ {0.45, 0.5, 0.67} the power-law fit E = A_e (t0 − t)^n with t0 free
//! recovers n within ±0.02 and the halt within 2 ms, and its 95 % interval covers
//! the true n.
//!
//! The clips are rendered here as PNG folders, losslessly: what is measured is the
//! chain from frames to n. The MP4 fixtures of tests/analyse.rs add H.264's own
//! errors (OpenCV encodes at a fixed crf 23, which reads the sub-pixel gap under
//! the rim up to 0.3 px off near the halt); the README lists that under filming
//! advice.

use std::path::Path;

use eulerdisk::analyse::{EnergyFit, Experiment, analyse_clip};
use eulerdisk::config::ExperimentConfig;
use serde_json::Value;

/// How close t_φ, where the laws place the halt (`analyse::law_halt`), comes to the
/// true halt on the lossless renders: half a frame (measured 0.03–0.14 frames).
const HALT_PLACED_S: f64 = 0.5 / 480.0;

/// Renders a dark-plate side view of a power law with exponent `n` (halt 0.5 s into
/// the clip, 480 × 320 px, 480 fps) and analyses it with t0 free.
fn render_and_analyse(dir: &Path, n: f64) -> (Experiment, Value) {
    let name = format!("n{:03.0}", n * 100.0);
    let out = crate::util::eulerdisk(
        dir,
        &[
            "render",
            "--n",
            &n.to_string(),
            "--halt",
            "0.5",
            "--size",
            "480x320",
            "-o",
            &name,
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let truth: Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join(format!("{name}.truth.json"))).unwrap(),
    )
    .unwrap();
    let config =
        ExperimentConfig::parse("fps = 480\n[fit]\nhalt = \"free\"\n", Path::new("t.toml"))
            .unwrap();
    let experiment = analyse_clip(&dir.join(&name), &config, &|_, _| {}).expect("analyse");
    (experiment, truth)
}

/// n within 0.02 of the truth and inside the 95 % interval, and the fitted halt
/// within `halt_tolerance` [s] of the truth (clip time).
fn check(label: &str, fit: &EnergyFit, t_phi: f64, truth: (f64, f64), halt_tolerance: f64) {
    let (true_n, true_halt) = truth;
    let f = &fit.fit;
    assert!(
        (f.n - true_n).abs() < 0.02,
        "{label}: n = {} for {true_n}",
        f.n
    );
    let (lo, hi) = f.ci95_n;
    assert!((lo..=hi).contains(&true_n), "{label}: 95 % CI {lo}…{hi}");
    let halt = t_phi + f.t0;
    assert!(
        (halt - true_halt).abs() < halt_tolerance,
        "{label}: fitted halt {halt} s for {true_halt} s"
    );
}

#[test]
fn power_law_exponent_and_halt_come_back_from_lossless_clips() {
    let dir = tempfile::tempdir().unwrap();
    for n in [0.45, 0.5, 0.67] {
        let (e, truth) = render_and_analyse(dir.path(), n);
        let true_n = truth["true_n"].as_f64().unwrap();
        let true_halt = truth["halt_time"].as_f64().unwrap();
        let t_phi = e.series.halt.t_phi;
        eprintln!(
            "n = {n}: t_φ {t_phi:.5}, peaks n {:.4} [{:.4}, {:.4}] t0 {:+.5}, frames n {:.4} t0 {:+.5}",
            e.peaks_fit.fit.n,
            e.peaks_fit.fit.ci95_n.0,
            e.peaks_fit.fit.ci95_n.1,
            e.peaks_fit.fit.t0,
            e.frames_fit.as_ref().unwrap().fit.n,
            e.frames_fit.as_ref().unwrap().fit.t0,
        );
        // The last frame with motion: at most two frames before the halt (the rim
        // height oscillates through zero once a turn, so the last frames before the
        // halt can show less than the 0.1 px motion threshold), never after.
        let seen = e.frames[e.series.halt.index].t_capture;
        assert!(
            seen <= true_halt && true_halt - seen < 2.5 / 480.0,
            "n = {n}: last motion seen at {seen}"
        );
        // t_φ where the laws place the halt (t0 and the turns' end): within half a frame.
        assert!(
            (t_phi - true_halt).abs() < HALT_PLACED_S,
            "n = {n}: t_φ {t_phi}"
        );
        // Per-frame states (local fits at every frame): n within 0.02, its interval
        // covering the truth, the halt within 2 ms (issue 4 §6).
        let frames = e.frames_fit.as_ref().expect("per-frame fit");
        check(
            &format!("n = {n}, per frame"),
            frames,
            t_phi,
            (true_n, true_halt),
            2e-3,
        );
        // The thesis's estimate, eq. 3.8 at the peaks with ψ̇ by central differences:
        // n and its interval as well; its halt within 2.5 ms, as the peak fits of the
        // last turns carry the local model's error (module docs of `signal`): the
        // halt comes 1.9 ms early at n = 0.67.
        check(
            &format!("n = {n}, peaks"),
            &e.peaks_fit,
            t_phi,
            (true_n, true_halt),
            2.5e-3,
        );
    }
}
