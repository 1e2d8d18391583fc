//! Vision against the renderer's ray-cast ground truth (`scripts/make-fixtures`):
//! the light plate of fig. 3.9 with camera artefacts, and the rim-edge bias on
//! the dark plate.
//!
//! Coordinates: the renderer puts pixel centres at integers, vision at c + ½
//! (`vision` module docs), so a truth point p is p + ½ in vision's coordinates.
//! z_rim is a difference of rows and needs no shift.

use crate::util::{f, truth};
use eulerdisk::analyse::Experiment;
use serde_json::Value;

/// Renderer → vision coordinates.
const HALF: f64 = 0.5;

/// The fixture NAME analysed with the config TOML (once for all tests: `util`).
fn analyse(name: &str, toml: &str) -> &'static Experiment {
    crate::util::analysed(name, toml)
}

/// Errors measured − truth of z_rim on every frame with an edge, and at the
/// truth's peaks (local maxima above 0.2 px).
fn z_rim_errors(e: &Experiment, truth: &Value) -> (Vec<f64>, Vec<f64>) {
    let frames = truth["frames"].as_array().unwrap();
    assert_eq!(e.frames.len(), frames.len());
    let z: Vec<f64> = frames.iter().map(|t| f(&t["z_rim_px"])).collect();
    let (mut all, mut peaks) = (Vec::new(), Vec::new());
    for (i, (m, t)) in e.frames.iter().zip(frames).enumerate() {
        assert_eq!(m.index, t["file_index"].as_u64().unwrap() as usize);
        let Some(zm) = m.z_rim_px else { continue };
        let err = zm - z[i];
        all.push(err);
        let peak = i > 0 && i + 1 < z.len() && z[i] > z[i - 1] && z[i] >= z[i + 1] && z[i] > 0.2;
        if peak {
            peaks.push(err);
        }
    }
    (all, peaks)
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

#[test]
fn light_plate_clip_calibrates_on_the_shadow_and_tracks_the_rim() {
    let name = "side-light-n067-artefacts";
    let truth = truth(&format!("{name}.truth.json"));
    let e = analyse(&format!("{name}.mp4"), "fps = 480\nplate = \"light\"\n");
    let cal = &e.plan.calibration.calibration;
    let tc = &truth["calibration"];
    // Ends of the disk, found by their edges (the light plate needs no threshold):
    // the median over the side's rows of each row's steepest step, by its area,
    // averaged over the rest frames. The side's shading falls off towards the
    // ends (grazing light) and the step's run takes part of it: measured +0.24 px
    // at x_r, −0.16 px at x_l (outwards both). The ends place the centre line (the band is ±2 px)
    // and the perspective factor (0.24 px of 440 is 0.05 %), not the scale: 0.3 px.
    for (name, got) in [("x_l", cal.x_l), ("x_r", cal.x_r)] {
        let want = f(&tc[name]) + HALF;
        assert!((got - want).abs() < 0.3, "{name}: {got} vs {want}");
    }
    // Plate line: the rim above the shadow (the second edge from the bottom).
    // Rendered losslessly (PNG) it is within 0.01 px; MPEG-4 coding of the noisy,
    // blurred edge moves it by 0.12 px up on these rest frames (varying by
    // ±0.1 px between frames, hence the average over them): 0.2 px.
    let want = f(&tc["z_base"]) + HALF;
    assert!(
        (cal.z_base - want).abs() < 0.2,
        "z_base {} vs {want}",
        cal.z_base
    );
    // Dropped frames 40 and 171 are missing from the clip (313 captured); the
    // truth skips their capture indices, and the frames are compared in file order.
    assert_eq!(e.frames.len(), 311);
    let captured: Vec<u64> = truth["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["index"].as_u64().unwrap())
        .collect();
    assert!(!captured.contains(&40) && !captured.contains(&171));

    // z_rim on every frame: noise σ = 2, blur σ = 0.6 px, 5 % flicker, drift and
    // MPEG-4 coding. The same frames lossless give 0.015 px RMS; the coding adds
    // ≈ 0.10 px per frame and the plate line's 0.12 px: measured 0.14 px RMS on one
    // encode and 0.20 px on the next (the strip on the top face changed, and with
    // it the encoder's choices). 0.3 px, the figure for clean clips.
    let (all, peaks) = z_rim_errors(e, &truth);
    assert!(all.len() > 300, "{} frames with an edge", all.len());
    assert!(rms(&all) < 0.3, "z_rim RMS error {} px", rms(&all));
    assert!(peaks.len() > 25);
    assert!(
        rms(&peaks) < 0.25,
        "z_rim RMS error at peaks {}",
        rms(&peaks)
    );

    // n with the measured halt (t0 = 0): 0.680 for the true 0.667 (0.655 on the
    // previous encode). A lossless render of the same motion without artefacts
    // reads z_rim to 0.012 px RMS and still gave 0.628: the rest of the error is
    // sampling the peaks at 480 fps near the halt (signal stage), not vision. ±0.05.
    let n = e.peaks_fit.fit.n;
    assert!((n - f(&truth["true_n"])).abs() < 0.05, "n = {n}");
}

#[test]
fn dark_plate_rim_edge_has_no_bias_at_the_peaks() {
    let truth = truth("side-dark-n050.truth.json");
    // The edge as vision reads it, from its own zero (the rest edge): the motion's
    // zero (`signal::motion_zero`) moves every height by one offset, which is that
    // stage's business (here it is 0.055 px lower, the heights below 1 px then
    // within 0.005 px of the truth and the peaks 0.04 px low: the MPEG-4 coding
    // reads small lifts 0.04 px higher than large ones).
    let e = analyse(
        "side-dark-n050.mp4",
        "fps = 480\n[fit]\nhalt = \"free\"\nrim_zero = \"rest\"\n",
    );
    let cal = &e.plan.calibration.calibration;
    // Plate line: the disk → reflection step by its area, −0.01 px (the half-level
    // crossing read +0.07 px, a bias of every z_rim). 0.1 px.
    let want = f(&truth["calibration"]["z_base"]) + HALF;
    assert!(
        (cal.z_base - want).abs() < 0.1,
        "z_base {} vs {want}",
        cal.z_base
    );
    let (all, peaks) = z_rim_errors(e, &truth);
    // At the peaks (25): mean −0.019 px (+0.004 px from the area edge alone, +0.09
    // px from the half-level crossing), RMS 0.045 px, the spread being the MPEG-4
    // coding (lossless: RMS 0.03 px). A bias of 0.05 px is 5 σ of the mean of 25
    // peaks.
    assert_eq!(peaks.len(), 25);
    let bias = mean(&peaks);
    assert!(bias.abs() < 0.05, "z_rim bias at peaks {bias} px");
    assert!(rms(&peaks) < 0.1, "z_rim RMS at peaks {}", rms(&peaks));
    // Every frame: RMS 0.046 px read by the mirror-edge model (0.083 px from the
    // area edge alone, 0.126 px from the half-level crossing).
    assert!(rms(&all) < 0.12, "z_rim RMS {}", rms(&all));
}
