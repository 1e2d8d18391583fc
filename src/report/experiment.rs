//! One experiment's outputs, in its own folder:
//!
//! | file | what |
//! |---|---|
//! | `index.html` | self-contained page: headline fit, diagnostics, plots, tables |
//! | `result.json` | everything: plan (provenance), per-frame and per-peak series, fits |
//! | `plan.json` | the resolved plan alone: fps and its source, γ, calibration, window |
//! | `frames.csv` | per frame: t, z_rim [px, m], β raw/unwrapped/smoothed, β̇ |
//! | `peaks.csv` | per peak: t, z, φ (eq. 3.9), ψ, ψ̇ (eq. 3.11 and central), E (eq. 3.8); then the crests the motion fit places after them (`source`) |
//! | `states.csv` | per frame in the window: φ, ψ, ψ̇ with standard errors, E |
//! | `flags.csv` | flagged frames (skips, jumps) with reasons |
//! | `series.svg/.png`, `states.svg/.png`, `energy.svg`, `timing.svg` | plots |
//! | `calibration.png`, `threshold.png` | diagnostic images (figs. 3.3, 3.7) |
//! | `overlay.mp4`, `overlay.json` | the measurements drawn on the frames around the halt ([`crate::overlay`]) |
//! | `last-turns.png` | the frames at the last peaks, in a grid |

use std::path::{Path, PathBuf};

use maud::html;
use plotters::prelude::*;
use serde::Serialize;

use super::ReportError;
use super::html::{page, png_figure, svg_figure, table, video_figure};
use super::plot::{Panel, time_panels};
use crate::analyse::{EnergyFit, Experiment, ExperimentPlan};
use crate::energy::{self, SightingUse};
use crate::motion_fit::MotionFit;
use crate::output::{write_atomic, write_csv, write_json};
use crate::overlay::{KeptFrames, OverlayIndex, OverlaySpec, write_measurement_overlays};
use crate::precession;
use crate::turn_timing::TurnTimingFit;

#[derive(Serialize, Default)]
struct FrameRow {
    index: usize,
    t_s: f64,
    t_capture_s: f64,
    container_time_s: Option<f64>,
    picture_type: Option<char>,
    z_rim_px: Option<f64>,
    z_rim_m: Option<f64>,
    beta_raw_rad: Option<f64>,
    beta_rad: Option<f64>,
    beta_smoothed_rad: Option<f64>,
    beta_dot_rad_s: Option<f64>,
    camera_shift_px: Option<f64>,
}

#[derive(Serialize, Default)]
struct PeakRow {
    t_s: f64,
    z_rim_m: f64,
    phi_rad: f64,
    sigma_phi_rad: Option<f64>,
    psi_rad: f64,
    psi_dot_eq_3_11_rad_s: Option<f64>,
    psi_dot_central_rad_s: Option<f64>,
    energy_eq_3_8_j: Option<f64>,
    /// `frames` for a crest found in the heights, `motion fit` for one the motion
    /// fitted to every frame places after the last of them.
    source: &'static str,
}

#[derive(Serialize, Default)]
struct StateRow {
    index: usize,
    t_s: f64,
    phi_rad: f64,
    sigma_phi_rad: f64,
    psi_rad: f64,
    sigma_psi_rad: f64,
    psi_dot_rad_s: f64,
    sigma_psi_dot_rad_s: f64,
    residual_rms_m: f64,
}

#[derive(Serialize, Default)]
struct FlagRow {
    index: usize,
    t_s: f64,
    kind: &'static str,
    reason: String,
}

fn plot_error(e: impl std::fmt::Display) -> ReportError {
    ReportError::Plot(e.to_string())
}

/// Write every output of an experiment into `dir` (created if missing).
///
/// # Errors
/// The clip whose analysis `dir` holds (from its `plan.json`), when that is another
/// clip than `clip`: a different real path and different bytes (the same file
/// reached another way, or an identical copy, is the same clip). One output folder
/// must not silently change from one clip's results to another's.
pub fn other_clip_in(dir: &Path, clip: &Path) -> Option<PathBuf> {
    let bytes = std::fs::read(dir.join("plan.json")).ok()?;
    let plan: serde_json::Value = serde_json::from_slice(&bytes).ok()?;
    let previous = PathBuf::from(plan.get("clip")?.as_str()?);
    let real = |p: &Path| p.canonicalize().unwrap_or_else(|_| p.to_path_buf());
    if real(&previous) == real(clip) {
        return None;
    }
    let same_bytes = plan
        .get("clip_hash")
        .and_then(|h| h.as_str())
        .is_some_and(|h| crate::analyse::clip_hash(clip).is_ok_and(|now| now == h));
    (!same_bytes).then_some(previous)
}

/// Writes every output of an experiment into `dir`, with the overlays of `overlay`
/// (`None`: none), drawn on the frames `kept` while it was analysed where they
/// cover them (else decoded again).
///
/// # Errors
/// A file cannot be written, a plot cannot be drawn, or the overlays cannot be
/// made (the clip cannot be decoded again).
pub fn write_experiment(
    dir: &Path,
    experiment: &Experiment,
    overlay: Option<&OverlaySpec>,
    kept: Option<&KeptFrames>,
) -> Result<(), ReportError> {
    let e = experiment;
    write_csv(&dir.join("frames.csv"), &frame_rows(e))?;
    write_csv(&dir.join("peaks.csv"), &peak_rows(e))?;
    write_csv(&dir.join("states.csv"), &state_rows(e))?;
    write_csv(&dir.join("flags.csv"), &flag_records(e))?;
    write_json(&dir.join("plan.json"), &e.plan)?;
    write_json(&dir.join("result.json"), e)?;
    write_atomic(&dir.join("calibration.png"), &e.diagnostics.calibration_png)?;
    write_atomic(&dir.join("threshold.png"), &e.diagnostics.threshold_png)?;
    write_series_plot(dir, e)?;
    write_states_plot(dir, e)?;
    let energy_svg = energy_plot_svg(&e.peaks_fit, e.plan.window_s).map_err(plot_error)?;
    write_atomic(&dir.join("energy.svg"), energy_svg.as_bytes())?;
    let timing_svg = write_timing_plot(dir, e)?;
    let overlay = overlay
        .map(|spec| write_measurement_overlays(dir, e, spec, kept))
        .transpose()?;
    write_atomic(
        &dir.join("index.html"),
        experiment_page(e, &energy_svg, timing_svg.as_deref(), dir, overlay.as_ref())?.as_bytes(),
    )?;
    Ok(())
}

/// The rows of `frames.csv`: each frame's number in the clip, times, picture type,
/// rim height and, for two-view clips, the strip angle and its rate.
fn frame_rows(e: &Experiment) -> Vec<FrameRow> {
    let strip = e.series.strip.as_ref().map(|s| &s.series);
    let at = |v: Option<&Vec<f64>>, i: usize| {
        v.and_then(|v| v.get(i).copied()).filter(|x| x.is_finite())
    };
    e.frames
        .iter()
        .enumerate()
        .map(|(i, f)| FrameRow {
            index: f.index,
            t_s: f.t,
            t_capture_s: f.t_capture,
            container_time_s: f.container_time_s,
            picture_type: f.picture_type,
            z_rim_px: f.z_rim_px,
            z_rim_m: f.z_rim_m,
            beta_raw_rad: f.beta_raw,
            beta_rad: at(strip.map(|s| &s.beta), i),
            beta_smoothed_rad: at(strip.map(|s| &s.beta_smoothed), i),
            beta_dot_rad_s: at(strip.map(|s| &s.beta_dot), i),
            camera_shift_px: f.camera_shift_px,
        })
        .collect()
}

/// The rows of `peaks.csv`: each peak's height, tilt and precession, and the energy
/// eq. (3.8) fitted there; then each crest the motion fit places after the last peak
/// (`crate::motion_fit::MotionFit::unresolved_crests`), one turn of ψ apart, with the
/// model's height and tilt and no rate or energy.
fn peak_rows(e: &Experiment) -> Vec<PeakRow> {
    let found = (e.series.peaks.peaks.iter())
        .zip(&e.series.peaks.precession)
        .map(|(p, q)| PeakRow {
            t_s: p.t,
            z_rim_m: p.z,
            phi_rad: p.phi,
            sigma_phi_rad: p.sigma_phi,
            psi_rad: q.psi,
            psi_dot_eq_3_11_rad_s: q.psi_dot_forward,
            psi_dot_central_rad_s: q.psi_dot_central,
            energy_eq_3_8_j: e
                .peaks_fit
                .samples
                .iter()
                .find(|s| s.t == p.t)
                .map(|s| s.energy),
            source: "frames",
        });
    let last_psi = e.series.peaks.precession.last().map_or(0.0, |q| q.psi);
    let placed = (e.motion_fit.iter())
        .flat_map(|m| &m.unresolved_crests)
        .enumerate()
        .map(|(k, c)| PeakRow {
            t_s: c.t,
            z_rim_m: c.z_m,
            phi_rad: c.phi,
            sigma_phi_rad: None,
            psi_rad: last_psi + std::f64::consts::TAU * (k + 1) as f64,
            psi_dot_eq_3_11_rad_s: None,
            psi_dot_central_rad_s: None,
            energy_eq_3_8_j: None,
            source: "motion fit",
        });
    found.chain(placed).collect()
}

/// The rows of `states.csv`: the per-frame states of the local fits.
fn state_rows(e: &Experiment) -> Vec<StateRow> {
    // The peaks and states count frames from the first decoded one (the flags
    // carry clip frame numbers already); the files give each frame's number in
    // the clip.
    let frame_number = |position: usize| e.frames.get(position).map_or(position, |f| f.index);
    e.series
        .states
        .iter()
        .map(|s| StateRow {
            index: frame_number(s.index),
            t_s: s.t,
            phi_rad: s.phi,
            sigma_phi_rad: s.sigma_phi,
            psi_rad: s.psi,
            sigma_psi_rad: s.sigma_psi,
            psi_dot_rad_s: s.psi_dot,
            sigma_psi_dot_rad_s: s.sigma_psi_dot,
            residual_rms_m: s.residual_rms,
        })
        .collect()
}

/// The rows of `flags.csv`: each flagged frame and why.
fn flag_records(e: &Experiment) -> Vec<FlagRow> {
    e.series
        .flags
        .iter()
        .map(|f| FlagRow {
            index: f.index,
            t_s: f.t,
            kind: f.reason.kind(),
            reason: f.reason.label(),
        })
        .collect()
}

/// `series.svg`/`.png`: the rim height per frame, the camera's shift where the
/// heights were corrected for it, and, for two-view clips, the strip angle and its
/// rate.
fn write_series_plot(dir: &Path, e: &Experiment) -> Result<(), ReportError> {
    let strip = e.series.strip.as_ref().map(|s| &s.series);
    let t: Vec<f64> = e.frames.iter().map(|f| f.t).collect();
    let z_mm: Vec<f64> = e
        .frames
        .iter()
        .map(|f| f.z_rim_m.map_or(f64::NAN, |z| z * 1e3))
        .collect();
    let shift: Vec<f64> = e
        .frames
        .iter()
        .map(|f| f.camera_shift_px.unwrap_or(f64::NAN))
        .collect();
    let mut panels = vec![Panel {
        label: "z_rim [mm]",
        values: &z_mm,
        log_y: false,
    }];
    if e.plan.registration.as_ref().is_some_and(|r| r.applied) {
        panels.push(Panel {
            label: "camera shift [px]",
            values: &shift,
            log_y: false,
        });
    }
    if let Some(s) = strip {
        panels.push(Panel {
            label: "β [rad]",
            values: &s.beta_smoothed,
            log_y: false,
        });
        panels.push(Panel {
            label: "β̇ [rad/s]",
            values: &s.beta_dot,
            log_y: false,
        });
    }
    let title = format!("{}: per-frame series", e.plan.clip.display());
    time_panels(
        &dir.join("series"),
        &title,
        "t − t_φ [s]",
        &t,
        &panels,
        &[],
        "",
    )
    .map_err(plot_error)?;
    Ok(())
}

/// `states.svg`/`.png`, where there are states: φ, ψ, ψ̇ and the precession check
/// per state.
fn write_states_plot(dir: &Path, e: &Experiment) -> Result<(), ReportError> {
    let st: Vec<f64> = e.series.states.iter().map(|s| s.t).collect();
    let phi: Vec<f64> = e.series.states.iter().map(|s| s.phi).collect();
    let psi: Vec<f64> = e.series.states.iter().map(|s| s.psi).collect();
    let psi_dot: Vec<f64> = e.series.states.iter().map(|s| s.psi_dot).collect();
    let against_precession = against_precession(e);
    let state_panels = [
        Panel {
            label: "φ [rad]",
            values: &phi,
            log_y: false,
        },
        Panel {
            label: "ψ [rad]",
            values: &psi,
            log_y: false,
        },
        Panel {
            label: "ψ̇ [rad/s]",
            values: &psi_dot,
            log_y: false,
        },
        Panel {
            label: "φ/φ(ψ̇) − 1 [%]",
            values: &against_precession,
            log_y: false,
        },
    ];
    let states_drawn = !st.is_empty();
    if states_drawn {
        let title = format!(
            "{}: per-frame states (local rim fits)",
            e.plan.clip.display()
        );
        time_panels(
            &dir.join("states"),
            &title,
            "t − t_φ [s]",
            &st,
            &state_panels,
            &[],
            "",
        )
        .map_err(plot_error)?;
    }
    Ok(())
}

/// The precession check per state: φ from the heights over the φ that stationary
/// rolling gives its ψ̇ (eq. 2.29), − 1; where that φ is known to better than the
/// check's reach (2σ_ψ̇/ψ̇ below precession::AGREEMENT; the last turns' ψ̇ is not).
fn against_precession(e: &Experiment) -> Vec<f64> {
    e.series
        .states
        .iter()
        .map(|s| {
            let known = 2.0 * s.sigma_psi_dot < precession::AGREEMENT * s.psi_dot.abs();
            precession::stationary_sin_phi(&e.plan.disk, s.psi_dot)
                .filter(|_| known)
                .map_or(f64::NAN, |x| 100.0 * (s.phi.sin() / x - 1.0))
        })
        .collect()
}

/// `timing.svg`, where the turns' timing was fitted; the SVG for the page.
fn write_timing_plot(dir: &Path, e: &Experiment) -> Result<Option<String>, ReportError> {
    Ok(match &e.turn_timing {
        Some(Ok(t)) => {
            let svg = turn_timing_plot_svg(t).map_err(plot_error)?;
            write_atomic(&dir.join("timing.svg"), svg.as_bytes())?;
            Some(svg)
        }
        _ => None,
    })
}

fn fit_row(f: &EnergyFit) -> Vec<String> {
    let fit = &f.fit;
    vec![
        f.method.clone(),
        format!("{:.4}", fit.n),
        format!("{:.4} … {:.4}", fit.ci95_n.0, fit.ci95_n.1),
        format!("{:.4}", 1.96 * fit.se_n_zero),
        format!("{:.3e}", fit.a_e),
        match fit.ci95_t0 {
            Some((lo, hi)) => format!("{:.4} ({:.4} … {:.4})", fit.t0, lo, hi),
            None => format!("{:.4} (fixed)", fit.t0),
        },
        format!("{:.5}", fit.r_squared),
        fit.points.to_string(),
    ]
}

/// Where the zero and its uncertainty came from: the config, the motion, or the
/// value measured for how the rim was read.
fn zero_source(plan: &ExperimentPlan) -> String {
    let px = |m: f64| m / plan.metres_per_px;
    match (
        plan.config.rim_zero_uncertainty_px().is_some(),
        plan.rim_zero_from_motion,
        plan.rim_reading,
    ) {
        (true, _, _) => " (set in the config)".into(),
        (false, Some(z), _) => format!(
            " (placed by the motion: the rim's profile at ε = {:.2}° fitted with one offset to \
             {} heights between {} turning points, {:.3} ± {:.3} px {} the still disk's edge; that and the \
             profile's own {} px in quadrature)",
            plan.scale
                .near_rim_elevation_rad
                .unwrap_or(0.0)
                .to_degrees(),
            z.zero.points,
            z.zero.turning_points,
            px(z.shift_m).abs(),
            px(z.zero.se),
            if z.shift_m >= 0.0 { "above" } else { "below" },
            crate::vision::MOTION_ZERO_PROFILE_PX
        ),
        (false, None, Some(reading)) => format!(" (as measured for {})", reading.describe()),
        (false, None, None) => String::new(),
    }
}

/// n from the turns' timing alone beside the peaks fit's (crate::turn_timing).
fn turn_timing_sentence(
    timing: &Result<TurnTimingFit, String>,
    peaks: &energy::PowerLawFit,
) -> String {
    match timing {
        Ok(t) => format!(
            "From the turns' timing alone (the times of z_rim's peaks and troughs at their \
             counted ψ, t_k = T − c (ψ_end − ψ_k)^q with q = 1/(1 − n/2), which stationary \
             rolling near the halt gives; no height, scale or zero of z_rim enters it): \
             n = {:.3} (95 % CI {:.3} … {:.3}) from {} turning points, {:+.3} from the \
             energies at the peaks; the turns end {:+.2} ms from t_φ, the points' times lie \
             {:.2} ms RMS about the law. A check of the heights, not combined with them.",
            t.n,
            t.ci95_n.0,
            t.ci95_n.1,
            t.points,
            t.n - peaks.n,
            1e3 * t.t_end,
            1e3 * t.residual_rms_s
        ),
        Err(reason) => format!("n from the turns' timing alone: not fitted ({reason})."),
    }
}

/// The motion fitted to every frame beside the peaks fit (crate::motion_fit).
fn motion_fit_sentence(m: &MotionFit, peaks: &energy::PowerLawFit) -> String {
    let placed = match m.unresolved_crests.len() {
        0 => String::new(),
        k => format!(
            " It places {k} crest(s) after the last peak found, above the motion threshold, \
             which peaks.csv lists as its own."
        ),
    };
    let smoothing = m
        .codec_smoothing
        .map_or("the codec's smoothing not fitted".to_string(), |alpha| {
            format!("the codec's smoothing α = {alpha:.3} frame²")
        });
    format!(
        "Fitted to every height of the window at once (φ = Φ τ^n, the turns' timing law, \
         the camera's profile and the codec's smoothing over time; no peak, threshold or \
         halt rule enters it): n = {:.3} ({:+.3} from the energies at the peaks), the motion \
         ending {:+.2} ms from t_φ (the peaks fit's t0: {:+.2} ms), {smoothing}; the \
         heights lie {:.3} px RMS about it over {} frames. Its \
         standard errors take the frames as independent, too small for an interval: a \
         check, not combined with the fits.{placed}",
        m.n,
        m.n - peaks.n,
        1e3 * m.t0,
        1e3 * peaks.t0,
        m.residual_rms_px,
        m.frames,
    )
}

/// Where t_φ lies: placed by the laws (`analyse::law_halt`), or the last frame of
/// motion seen.
fn halt_sentence(e: &Experiment) -> String {
    let halt = &e.series.halt;
    let Some(seen) = e.frames.get(halt.index) else {
        return String::new();
    };
    let threshold_px = halt.threshold / e.plan.metres_per_px;
    let Some(placed) = e.halt_placement else {
        return format!(
            "The halt t_φ is the last frame of motion seen, frame {} (a rise of more than \
             {threshold_px:.2} px above the rest).",
            seen.index
        );
    };
    let se = placed
        .se_s
        .map_or(String::new(), |se| format!(" ± {:.2} ms", 1e3 * se));
    let from = match placed.turns_end_s {
        Some(end) => format!(
            "the mean of the energy law's t0 at the peaks and the end T of the turns' timing \
             law, fitted before it was placed, which lie at {:+.2} and {:+.2} ms on its clock",
            1e3 * placed.t0_s,
            1e3 * end
        ),
        None => "the energy law's t0 at the peaks (the turns could not be timed)".into(),
    };
    let seen_s = placed.last_motion_seen_s;
    let why = if seen_s < 0.0 {
        "before it: the final rises fall below that, and an encoder holds pictures whose \
         change is below its quantiser"
    } else if placed.se_s.is_some_and(|se| seen_s > 2.0 * se) {
        "after it by more than twice its standard error: a picture the encoder shows after \
         the halt"
    } else {
        "after it, within twice its standard error"
    };
    format!(
        "The halt t_φ (t = 0{se}) is where the laws of the motion place it: {from}. The halt \
         detector last saw the rim move at {:+.2} ms, frame {} (a rise of more than \
         {threshold_px:.2} px above the rest), {why}.",
        1e3 * placed.last_motion_seen_s,
        seen.index,
    )
}

/// How the halt seen in the footage entered the peaks fit's t0 (times from t_φ, the
/// sighting's from the last frame of motion seen).
fn sighting_sentence(s: &SightingUse, t0: f64) -> String {
    let seen = format!(
        "The halt seen in the footage puts t0 at {:+.2} ± {:.2} ms (after the last motion \
         seen: one frame, and {:.2} ms of motion below the least rise the halt detector \
         sees, {:.1} μm above the heights' zero: its threshold above the still disk's rest \
         level, which lies {:+.1} μm above that zero); the energy alone at {:+.2} ± {:.2} ms",
        1e3 * s.t0_seen,
        1e3 * s.se_t0_seen,
        1e3 * s.unseen_s,
        1e6 * s.visible_rise_m,
        1e6 * s.rest_above_zero_m,
        1e3 * s.t0_fitted,
        1e3 * s.se_t0_fitted
    );
    if s.combined {
        format!(
            "{seen}. Combined: t0 = {:+.2} ms, and n and A_e those of the law fitted with t0 \
             held there.",
            1e3 * t0
        )
    } else if let Some(turns) = s.turns_end.filter(|_| s.disagrees_with_turns) {
        format!(
            "{seen}. The turns' end T, from the times of the turns alone, puts it at {:+.2} ± \
             {:.2} ms: the halt seen disagrees with it by more than 3 standard deviations \
             (held pictures end the motion seen early), so t0 is the energy's alone.",
            1e3 * turns.t_end,
            1e3 * turns.se
        )
    } else {
        format!(
            "{seen}. They disagree by more than 3 standard deviations, so t0 is the energy's \
             alone: check the halt frame."
        )
    }
}

/// β̇ at the last frame of motion seen (at t_φ or a few frames from it) and the
/// energy eq. (3.6) keeps there, at φ = 0 with θ̇ = β̇ (eq. 3.22):
/// C/2 β̇² + m/2 (R β̇)² \[J\].
fn carried_spin_energy(e: &Experiment) -> Option<(f64, f64)> {
    let strip = e.series.strip.as_ref()?;
    let beta_dot = *strip.series.beta_dot.get(e.series.halt.index)?;
    let disk = &e.plan.disk;
    let energy = energy::rolling_energy(disk, 0.0, 0.0, 0.0, beta_dot);
    beta_dot.is_finite().then_some((beta_dot, energy))
}

fn experiment_page(
    e: &Experiment,
    energy_svg: &str,
    timing_svg: Option<&str>,
    dir: &Path,
    overlay: Option<&OverlayIndex>,
) -> Result<String, ReportError> {
    let plan = &e.plan;
    let body = html! {
        (summary_section(e))
        (power_law_section(e, energy_svg, timing_svg))
        (series_section(e, dir, overlay))
        (diagnostics_section(e))
    };
    let title = format!(
        "eulerdisk: {}",
        plan.clip
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
    );
    Ok(page(&title, body))
}

/// The result in sentences: n and its interval, the halt, the sighting, the strip
/// stop, and the warnings.
fn summary_section(e: &Experiment) -> maud::Markup {
    let plan = &e.plan;
    let strip = e.series.strip.as_ref();
    html! {
        p {
            "Energy exponent "
            strong { (format!("n = {:.3}", e.peaks_fit.fit.n)) }
            (format!(" (95 % CI {:.3} … {:.3}) from {} peaks in the last {} s before the halt; \
                the interval includes ± {:.3} from the zero of z_rim, known to {:.3} px{} (the fits \
                made again with it moved by that much).",
                e.peaks_fit.fit.ci95_n.0, e.peaks_fit.fit.ci95_n.1, e.peaks_fit.fit.points, plan.window_s,
                1.96 * e.peaks_fit.fit.se_n_zero, plan.rim_zero_uncertainty_px, zero_source(plan)))
        }
        p { (halt_sentence(e)) }
        @if let Some(s) = e.peaks_fit.fit.halt_sighting {
            p { (sighting_sentence(&s, e.peaks_fit.fit.t0)) }
        }
        @if let Some(s) = strip {
            p { (format!("Strip stop t_β − t_φ = {:.4} s ({}).", s.rotation_after_flat,
                if s.stop.fit.is_some() { "fit of the friction stop, eq. 4.112" } else { "band method, fig. 3.22" })) }
        }
        @if !e.warnings.is_empty() {
            h2 { "Warnings" }
            ul { @for w in &e.warnings { li class="bad" { (w) } } }
        }
    }
}

/// The power law fitted to each energy, the turns' timing, the spin carried into
/// the flat, the energy figure and the window sensitivity.
fn power_law_section(e: &Experiment, energy_svg: &str, timing_svg: Option<&str>) -> maud::Markup {
    let fit_rows: Vec<Vec<String>> = fits(e).iter().map(|f| fit_row(f)).collect();
    let window_rows = window_rows(e);
    html! {
        h2 { "Power law E = A_e (t0 − t)^n" }
        (table(&["energy", "n", "95 % CI of n", "of it ± from z_rim's zero", "A_e [J s^-n]", "t0 [s]", "R²", "points"], &fit_rows, |_, _| false))
        @if let Some(timing) = &e.turn_timing {
            p { (turn_timing_sentence(timing, &e.peaks_fit.fit)) }
        }
        @if let Some(svg) = timing_svg {
            (svg_figure(svg, "The times of z_rim's peaks and troughs against the turns still to go (log–log), with the turns' timing law: its slope is q = 1/(1 − n/2)."))
        }
        @if let Some(motion) = &e.motion_fit {
            p { (motion_fit_sentence(motion, &e.peaks_fit.fit)) }
        }
        @if let Some(spin) = e.full_state_fit.as_ref().and(carried_spin_energy(e)) {
            p { (format!("Eq. 3.6 keeps the spin the disk carries into the flat: with β̇ = {:.2} rad/s at t_φ, \
                C/2 β̇² + m/2 (R β̇)² = {:.2e} J remain at the halt, which a power law to zero does not describe. \
                Eq. 3.8, the thesis's energy, is the one to compare.", spin.0, spin.1)) }
        }
        (svg_figure(energy_svg, "Energy at the peaks (eq. 3.8) with the fitted power law; the band spans n over its 95 % interval."))
        h2 { "Window sensitivity (eq. 3.8 at peaks)" }
        (table(&["window", "n", "95 % CI (statistical only)", "points"], &window_rows, |_, _| false))
    }
}

/// The series plots, linked to the overlay video's frames, and the footage.
fn series_section(e: &Experiment, dir: &Path, overlay: Option<&OverlayIndex>) -> maud::Markup {
    let read_svg = |name: &str| std::fs::read_to_string(dir.join(name)).ok();
    let series_svg = read_svg("series.svg");
    let states_svg = read_svg("states.svg");
    let frame_times: Vec<f64> = e.frames.iter().map(|f| f.t).collect();
    let state_times: Vec<f64> = e.series.states.iter().map(|s| s.t).collect();
    html! {
        h2 { "Series" }
        @if overlay.is_some() {
            p class="note" { "Click a series plot at an instant inside the overlay video's span: the video below stops at the frame nearest it." }
        }
        @if let Some(svg) = &series_svg {
            (frame_linked(svg, &frame_times, overlay, "Rim height and, for two-view clips, the strip angle and its rate."))
        }
        @if let Some(svg) = &states_svg {
            (frame_linked(svg, &state_times, overlay, "Per-frame φ, ψ, ψ̇ from local fits of the rim-height model, and φ against the φ that stationary rolling gives ψ̇ (eq. 2.29, the precession check)."))
        }
        @if let Some(overlay) = overlay {
            (footage_section(e, overlay, dir))
        }
    }
}

/// The diagnostic frames, the flagged frames, and the plan and provenance.
fn diagnostics_section(e: &Experiment) -> maud::Markup {
    let flag_rows = flag_rows(e);
    let plan_rows = plan_rows(e);
    html! {
        h2 { "Diagnostics" }
        (png_figure(&e.diagnostics.calibration_png, "Rest frame: x_l, x_r (green), z_t (yellow), z_base (red), centre line (blue)."))
        (png_figure(&e.diagnostics.threshold_png, "Highest-rim frame thresholded at γ: measuring band (blue) and the rim edge found (red)."))
        h2 { "Flagged frames" }
        @if flag_rows.is_empty() { p { "None." } } @else {
            (table(&["frame", "t [s]", "reason"], &flag_rows, |_, _| false))
        }
        h2 { "Plan and provenance" }
        (table(&["", ""], &plan_rows, |_, _| false))
        p class="note" { "Data: frames.csv, peaks.csv, states.csv, flags.csv, result.json, plan.json in this folder." }
    }
}

/// The energy fits made: at the peaks, and per frame and of the full state where made.
fn fits(e: &Experiment) -> Vec<&EnergyFit> {
    std::iter::once(&e.peaks_fit)
        .chain(e.frames_fit.as_ref())
        .chain(e.full_state_fit.as_ref())
        .collect()
}

/// The plan and provenance table: the clip and how it was read, the calibration and
/// scale, and the checks, fit window and disk.
fn plan_rows(e: &Experiment) -> Vec<Vec<String>> {
    let mut rows = clip_rows(&e.plan);
    rows.extend(calibration_rows(&e.plan));
    rows.extend(fit_setup_rows(e));
    rows
}

/// The clip, its hash, the version that read it, and how its frames were decoded,
/// oriented, converted and timed.
fn clip_rows(plan: &ExperimentPlan) -> Vec<Vec<String>> {
    vec![
        vec!["clip".into(), plan.clip.display().to_string()],
        vec!["BLAKE3 of the clip".into(), plan.clip_hash.clone()],
        vec!["eulerdisk version".into(), plan.crate_version.clone()],
        vec![
            "frames".into(),
            format!("{} ({} × {} px)", plan.frames, plan.width, plan.height),
        ],
        vec![
            "decoded".into(),
            plan.decoded.as_ref().map_or_else(
                || "the whole clip (not recorded)".into(),
                crate::analyse::DecodedSpan::summary,
            ),
        ],
        vec![
            "orientation".into(),
            format!(
                "{} (the container's display matrix, applied to every frame)",
                plan.orientation
            ),
        ],
        vec![
            "video signal".into(),
            plan.video_signal.as_ref().map_or_else(
                || "frame images (8-bit), or not recorded".into(),
                |v| format!("{v}; converted to 8-bit full-range colour before thresholds"),
            ),
        ],
        vec![
            "capture fps".into(),
            format!("{} ({:?})", plan.fps.fps, plan.fps.source),
        ],
        vec!["frame times".into(), frame_times_text(plan)],
    ]
}

/// The layout and plate, the threshold, the calibration in pixels, and the scale.
fn calibration_rows(plan: &ExperimentPlan) -> Vec<Vec<String>> {
    let c = &plan.calibration.calibration;
    vec![
        vec!["layout".into(), plan.layout.clone()],
        vec!["plate".into(), plan.plate.clone()],
        vec![
            "threshold γ".into(),
            format!(
                "{:.1} ({:?})",
                plan.calibration.threshold.gamma, plan.calibration.threshold.source
            ),
        ],
        vec![
            "calibration [px]".into(),
            format!(
                "x_l = {:.2}, x_r = {:.2}, z_t = {:.2}, z_base = {:.2} ({:?})",
                c.x_l, c.x_r, c.z_t, c.z_base, plan.calibration.sources
            ),
        ],
        vec!["near top rim z_t".into(), near_top_rim_text(plan)],
        vec!["camera motion".into(), camera_motion_text(plan)],
        vec![
            "scale δ at the near rim".into(),
            format!(
                "{:.4e} m/px from the {}{}",
                plan.metres_per_px,
                plan.scale.used,
                plan.scale
                    .near_rim_local_factor
                    .map(|f| format!(", × {f:.4} for the near bottom rim (see perspective)"))
                    .unwrap_or_default()
            ),
        ],
        vec!["perspective".into(), perspective_text(plan)],
    ]
}

/// The precession check, the measuring band, the fit window and the disk.
fn fit_setup_rows(e: &Experiment) -> Vec<Vec<String>> {
    let plan = &e.plan;
    let c = &plan.calibration.calibration;
    vec![
        vec!["precession check".into(), precession_check_text(e)],
        vec![
            "band".into(),
            format!(
                "±{} px around x_centre = {:.2} px",
                plan.band_half_width_px,
                c.x_centre()
            ),
        ],
        vec![
            "fit window".into(),
            format!(
                "the {} s up to the last frame of motion seen, the last sample; t0: {:?}",
                plan.window_s, plan.halt
            ),
        ],
        vec![
            "disk".into(),
            format!(
                "m = {} kg, R = {} m, H = {} m, A = {:.3e}, C = {:.3e} kg m²",
                plan.disk.mass,
                plan.disk.radius,
                plan.disk.half_thickness,
                plan.disk.inertia_a,
                plan.disk.inertia_c
            ),
        ],
    ]
}

/// How the frame times were read, and their intervals' median, spread and range.
fn frame_times_text(plan: &ExperimentPlan) -> String {
    plan.frame_times.as_ref().map_or_else(
        || "not recorded".into(),
        |f| {
            let sections = if f.sections.len() > 1 {
                format!("; sections: {}", f.sections_text())
            } else {
                String::new()
            };
            format!(
                "{}: {}; frame interval median {:.4} ms, spread {:.4} ms \
                 (1.4826 × MAD), {:.4}–{:.4} ms{sections}",
                f.source.label(),
                f.detail,
                1e3 * f.median_interval_s,
                1e3 * f.interval_spread_s,
                1e3 * f.min_interval_s,
                1e3 * f.max_interval_s
            )
        },
    )
}

/// The camera's vertical motion against the scene beside the disk, and whether
/// the heights were corrected for it (vision::registration).
fn camera_motion_text(plan: &ExperimentPlan) -> String {
    plan.registration.as_ref().map_or_else(
        || "not measured: no strip of the scene beside the disk".into(),
        |r| {
            let size = format!(
                "{:.3} px RMS, {:.2} px at most, at the centre line against the rest tail \
                 (strips {} of the disk; σ {:.3} px a frame)",
                r.rms_px, r.peak_px, r.strips, r.sigma_px
            );
            if r.applied {
                format!("{size}; every rim height corrected for it (frames.csv camera_shift_px)")
            } else {
                format!("{size}: too little in the strips to register on, heights not corrected")
            }
        },
    )
}

/// Where the near top rim z_t was read: on the rest frames, or on the frames in
/// which the disk leans towards the camera.
fn near_top_rim_text(plan: &ExperimentPlan) -> String {
    plan.top_rim_leaning.map_or_else(
        || "read on the rest frames".into(),
        |l| {
            format!(
                "{:.2} ± {:.2} px from {} frames{} in which the disk leans towards \
                 the camera (the face up to {:.1} px tall there); the rest frames, \
                 which saw no face or one under {:.0} px tall above a sharp edge, \
                 read {:.2} px",
                l.reading.z_t,
                l.reading.se,
                l.reading.frames,
                if l.reading.b_pictures_left_out {
                    " (P and I pictures; the B pictures left out)"
                } else {
                    ""
                },
                l.reading.tallest_face_px,
                crate::vision::THIN_AT_REST_PX,
                l.rest_z_t
            )
        },
    )
}

/// The diameter scale at the disk's centre, the perspective factor, the camera
/// distance and the near rim's local factor for eq. 3.10's δ.
fn perspective_text(plan: &ExperimentPlan) -> String {
    format!(
        "diameter scale 2R/(x_r − x_l) = {:.4e} m/px at the disk's centre; factor {:.3}{}{}",
        plan.scale.diameter_metres_per_px,
        plan.scale.perspective_factor,
        plan.scale
            .camera_distance_m
            .map(|d| if plan.scale.camera_distance_from_config {
                format!(", camera {d:.3} m from the near rim (config)")
            } else {
                format!(", camera ≈ {d:.2} m from the near rim")
            })
            .unwrap_or_default(),
        match (
            plan.scale.near_rim_local_factor,
            plan.scale.principal_row_px
        ) {
            (Some(f), Some(row)) => format!(
                "; eq. 3.10's δ (the mean over the thickness) × {f:.4} for the scale at \
                 the near bottom rim (principal point taken at row {row:.0})"
            ),
            _ => String::new(),
        }
    )
}

/// The precession check (a check of the scale and the zero, not applied), or why
/// it was not made.
fn precession_check_text(e: &Experiment) -> String {
    e.precession.as_ref().map_or_else(
        || "not made (fewer than 10 states with a precession rate)".into(),
        |check| {
            format!(
                "{} ({}; a check of the scale and the zero, not applied)",
                check.describe(),
                if check.agrees() {
                    format!("within ±{:.0} %", 100.0 * precession::AGREEMENT)
                } else {
                    format!(
                        "beyond ±{:.0} %: see the warnings",
                        100.0 * precession::AGREEMENT
                    )
                }
            )
        },
    )
}

/// The window-sensitivity table: n and its interval for each window, or why the
/// fit failed there.
fn window_rows(e: &Experiment) -> Vec<Vec<String>> {
    e.peaks_fit
        .windows
        .iter()
        .map(|(w, r)| match r {
            Ok(f) => vec![
                format!("{w} s"),
                format!("{:.4}", f.n),
                format!("{:.4} … {:.4}", f.ci95_n.0, f.ci95_n.1),
                f.points.to_string(),
            ],
            Err(reason) => vec![format!("{w} s"), "–".into(), reason.clone(), "0".into()],
        })
        .collect()
}

/// The flagged frames: index, time and reason.
fn flag_rows(e: &Experiment) -> Vec<Vec<String>> {
    e.series
        .flags
        .iter()
        .map(|f| {
            vec![
                f.index.to_string(),
                format!("{:.5}", f.t),
                format!("{:?}", f.reason),
            ]
        })
        .collect()
}

/// A series plot (SVG of [`time_panels`]) whose instants lead to the overlay
/// video's frames: with an overlay, the figure carries its time axis
/// (`data-t0`, `data-t1` at SVG x `data-x0`, `data-x1`) and a click seeks the
/// video to the frame nearest the clicked instant ([`SHOW_FRAME_JS`]).
fn frame_linked(
    svg: &str,
    t: &[f64],
    overlay: Option<&OverlayIndex>,
    caption: &str,
) -> maud::Markup {
    let (t0, t1, x0, x1) = super::plot::time_axis_px(t);
    maud::html! {
        @if overlay.is_some() {
            div class="to-frame" data-t0=(t0) data-t1=(t1) data-x0=(x0) data-x1=(x1) {
                (svg_figure(svg, caption))
            }
        } @else {
            (svg_figure(svg, caption))
        }
    }
}

/// Seeks the overlay video to its frame `k` and pauses there; records the
/// video's duration (`data-duration`) once it is known, or shows why it cannot
/// play (`data-error`, the MediaError code, and a note to open the file itself).
const SHOW_FRAME_JS: &str = "
function showFrame(k, fps) {
  const v = document.getElementById('overlay');
  v.pause();
  v.currentTime = (k + 0.5) / fps;
  v.scrollIntoView({block: 'center'});
}
function linkPlots(times, fps) {
  const step = times.length > 1 ? (times[times.length - 1] - times[0]) / (times.length - 1) : 1;
  for (const div of document.querySelectorAll('.to-frame')) {
    const svg = div.querySelector('svg');
    const d = div.dataset;
    svg.style.cursor = 'crosshair';
    svg.addEventListener('click', (ev) => {
      const p = svg.createSVGPoint();
      p.x = ev.clientX; p.y = ev.clientY;
      const x = p.matrixTransform(svg.getScreenCTM().inverse()).x;
      const t = +d.t0 + (x - d.x0) * (d.t1 - d.t0) / (d.x1 - d.x0);
      let k = 0;
      times.forEach((s, i) => { if (Math.abs(s - t) < Math.abs(times[k] - t)) k = i; });
      if (Math.abs(times[k] - t) <= step) { showFrame(k, fps); }
    });
  }
}
(function () {
  const v = document.getElementById('overlay');
  const known = () => { v.dataset.duration = v.duration; };
  const failed = () => {
    v.dataset.error = v.error ? v.error.code : 'unknown';
    document.getElementById('overlay-error').hidden = false;
  };
  if (v.readyState >= 1) { known(); } else { v.addEventListener('loadedmetadata', known); }
  if (v.error) { failed(); } else { v.addEventListener('error', failed); }
})();
";

/// "On the footage": the overlay video, the contact sheet, and the peaks with a
/// button that shows each one's frame in the video.
fn footage_section(e: &Experiment, overlay: &OverlayIndex, dir: &Path) -> maud::Markup {
    let sheet = overlay
        .last_turns
        .as_ref()
        .and_then(|(name, _)| std::fs::read(dir.join(name)).ok());
    let fps = overlay.playback_fps;
    // The clip instant (t − t_φ [s]) of each video frame, for the plots' links.
    let frame_times =
        serde_json::to_string(&overlay.frames.iter().map(|f| f.t).collect::<Vec<f64>>())
            .unwrap_or_else(|_| "[]".into());
    let metres_per_px = e.plan.metres_per_px;
    let rest = e.series.halt.rest_level;
    let peak_rows: Vec<(usize, f64, f64, f64, Option<usize>)> = e
        .series
        .peaks
        .peaks
        .iter()
        .enumerate()
        .map(|(n, p)| {
            let index = e.frames.get(p.index).map(|f| f.index);
            let k = overlay.frames.iter().position(|f| Some(f.index) == index);
            (n + 1, p.t, (p.z + rest) / metres_per_px, p.phi, k)
        })
        .collect();
    maud::html! {
        h2 { "On the footage" }
        (video_figure(&overlay.video, "overlay", &format!(
            "The measurements on the frames from t − t_φ = {} s to {} s, {:.0}× slower than filmed \
             ({} frames at {} frames/s). Left: the side view; right: the centre band enlarged. \
             Blue: the measuring band; red: the plate line z_base; green: the measured rim edge; \
             magenta: a detected peak; orange border: the last frame of motion seen; red border: a flagged \
             frame (reason in the header){}. overlay.json maps each video frame to its clip frame.",
            overlay.span_s.0, overlay.span_s.1, overlay.slow_down, overlay.frames.len(), fps,
            if e.series.strip.is_some() { "; below: the plan view with the strip's mask (cyan) and its principal axis (yellow)" } else { "" })))
        p id="overlay-error" class="note" hidden {
            "This browser cannot play the video (H.264 in MP4): open "
            a href=(overlay.video) { (overlay.video) }
            " in a video player."
        }
        @if let Some(png) = &sheet {
            (png_figure(png, "The last oscillations before the halt: the frame nearest each peak, with t − t_φ and z_rim in its header."))
        }
        h3 { "Peaks and their frames" }
        p class="note" { "Each peak of the rim-height series (plots above) comes from the frames around it; “show” stops the video at the frame nearest the peak." }
        table {
            tr { th { "peak" } th { "t − t_φ [s]" } th { "z_rim [px]" } th { "φ [°]" } th { "frame" } }
            @for (n, t, z, phi, k) in &peak_rows {
                tr {
                    td { (n) } td { (format!("{t:.5}")) } td { (format!("{z:.2}")) }
                    td { (format!("{:.3}", phi.to_degrees())) }
                    td { @if let Some(k) = k {
                        button class="frame" onclick=(format!("showFrame({k}, {fps})")) { "show" }
                    } @else { "outside the video" } }
                }
            }
        }
        script { (maud::PreEscaped(SHOW_FRAME_JS)) }
        script { (maud::PreEscaped(format!("linkPlots({}, {fps});", frame_times))) }
    }
}

/// The turning points' times against the turns still to go, log–log, with the timing law
/// T − t = c (ψ_end − ψ)^q: a straight line of slope q = 1/(1 − n/2) (crate::turn_timing).
fn turn_timing_plot_svg(t: &TurnTimingFit) -> Result<String, String> {
    let turns = std::f64::consts::TAU;
    let go = t.psi_to_go();
    let points: Vec<(f64, f64)> = go
        .iter()
        .zip(&t.times)
        .map(|(&g, &tk)| (g / turns, (t.t_end - tk) * 1e3))
        .filter(|&(x, y)| x > 0.0 && y > 0.0)
        .collect();
    let (x_lo, x_hi) = points.iter().fold((f64::INFINITY, 0.0_f64), |(a, b), p| {
        (a.min(p.0), b.max(p.0))
    });
    let (x_lo, x_hi) = (x_lo * 0.8, x_hi * 1.2);
    let law: Vec<(f64, f64)> = (0..=200)
        .map(|i| {
            let x = x_lo * (x_hi / x_lo).powf(f64::from(i) / 200.0);
            (x, t.time_to_go(x * turns) * 1e3)
        })
        .collect();
    let y_of =
        |f: fn(f64, f64) -> f64, start: f64| points.iter().chain(&law).map(|p| p.1).fold(start, f);
    let (y_lo, y_hi) = (
        y_of(f64::min, f64::INFINITY) * 0.8,
        y_of(f64::max, 0.0) * 1.2,
    );
    let caption = format!(
        "T − t = c (ψ_end − ψ)^q: q = {:.3}, n = 2 (1 − 1/q) = {:.3} ({:.3} … {:.3})",
        t.q(),
        t.n,
        t.ci95_n.0,
        t.ci95_n.1
    );
    svg_chart(caption, |mut builder| {
        let mut chart = builder
            .build_cartesian_2d((x_lo..x_hi).log_scale(), (y_lo..y_hi).log_scale())
            .map_err(|e| e.to_string())?;
        let sig = |v: &f64| super::plot::fmt_sig(*v, 2);
        chart
            .configure_mesh()
            .x_labels(8)
            .y_labels(6)
            .x_label_formatter(&sig)
            .y_label_formatter(&sig)
            .bold_line_style(RGBColor(215, 215, 215))
            .light_line_style(RGBColor(245, 245, 245))
            .x_desc("turns still to go, (ψ_end − ψ)/2π")
            .y_desc("T − t [ms]")
            .label_style(("sans-serif", 15))
            .draw()
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(LineSeries::new(law, RGBColor(220, 60, 0).stroke_width(2)))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(points.iter().map(|&p| Circle::new(p, 3, BLUE.filled())))
            .map_err(|e| e.to_string())?;
        Ok(())
    })
}

/// A titled 900 × 520 chart on white, drawn by `draw` from its builder (caption,
/// margin and label areas set), as SVG text: what the energy and the timing plots
/// share.
fn svg_chart(
    caption: String,
    draw: impl FnOnce(ChartBuilder<'_, '_, SVGBackend<'_>>) -> Result<(), String>,
) -> Result<String, String> {
    super::plot::ensure_font()?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 520)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut builder = ChartBuilder::on(&root);
        builder
            .caption(caption, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(72);
        draw(builder)?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

/// Energy samples with the fitted power law and a band of the curves whose n
/// spans its 95 % interval (A_e re-projected for each), on linear axes.
fn energy_plot_svg(f: &EnergyFit, window_s: f64) -> Result<String, String> {
    let fit = &f.fit;
    let in_window: Vec<(f64, f64)> = f
        .samples
        .iter()
        .filter(|s| s.t >= -window_s && s.t <= fit.t0)
        .map(|s| (s.t, s.energy * 1e3))
        .collect();
    let t_min = -window_s;
    let t_max = fit.t0.max(0.0);
    let e_max = in_window.iter().map(|p| p.1).fold(0.0, f64::max) * 1.1;
    let curve = |n: f64, a_e: f64| -> Vec<(f64, f64)> {
        (0..=400)
            .map(|i| {
                let t = t_min + (t_max - t_min) * f64::from(i) / 400.0;
                (t, a_e * (fit.t0 - t).max(0.0).powf(n) * 1e3)
            })
            .collect()
    };
    // A_e that best fits the window's samples for a given n (linear projection).
    let project = |n: f64| {
        let (num, den) = in_window.iter().fold((0.0, 0.0), |(a, b), &(t, e)| {
            let g = (fit.t0 - t).max(0.0).powf(n);
            (a + e * 1e-3 * g, b + g * g)
        });
        if den > 0.0 { num / den } else { fit.a_e }
    };
    let low = curve(fit.ci95_n.0, project(fit.ci95_n.0));
    let high = curve(fit.ci95_n.1, project(fit.ci95_n.1));
    let caption = format!(
        "E = A_e (t0 − t)^n: n = {:.3} ({:.3} … {:.3})",
        fit.n, fit.ci95_n.0, fit.ci95_n.1
    );
    svg_chart(caption, |mut builder| {
        let mut chart = builder
            .build_cartesian_2d(t_min..t_max, 0.0..e_max.max(1e-12))
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("t − t_φ [s]")
            .y_desc("E [mJ]")
            .label_style(("sans-serif", 15))
            .draw()
            .map_err(|e| e.to_string())?;
        let band: Vec<(f64, f64)> = low
            .iter()
            .copied()
            .chain(high.iter().rev().copied())
            .collect();
        chart
            .draw_series(std::iter::once(Polygon::new(
                band,
                RGBColor(255, 170, 120).mix(0.35),
            )))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(LineSeries::new(
                curve(fit.n, fit.a_e),
                RGBColor(220, 60, 0).stroke_width(2),
            ))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(in_window.iter().map(|&p| Circle::new(p, 3, BLUE.filled())))
            .map_err(|e| e.to_string())?;
        Ok(())
    })
}
