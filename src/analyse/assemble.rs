//! Assemble: the diagnostic images, the plan (every decision, recorded as the
//! result's provenance) and the [`Experiment`].

use std::path::Path;

use super::calibrate::RestCalibration;
use super::checks::Fitted;
use super::diagnostics;
use super::measure::MeasuredFrames;
use super::open::OpenedClip;
use super::views::OwnedFrame;
use super::{
    AnalyseError, DecodedSpan, Diagnostics, Experiment, ExperimentPlan, TopRimLeaning,
    ZeroFromMotion, clip_hash,
};
use crate::config::ExperimentConfig;
use crate::model::params::DiskParams;
use crate::vision::{self, CalibrationReport};

/// The [`Experiment`] of `clip` from the stages' results: the plan
/// ([`experiment_plan`]), the frames, series and fits, the warnings, and the
/// diagnostic images ([`diagnostics`]).
///
/// # Errors
/// The clip cannot be read again for its hash.
pub(super) fn experiment(
    clip: &Path,
    config: &ExperimentConfig,
    params: DiskParams,
    opened: &OpenedClip,
    rest: RestCalibration,
    decoded: DecodedSpan,
    fitted: Fitted,
) -> Result<Experiment, AnalyseError> {
    let Fitted {
        span,
        fits,
        halt_placement,
        skips_in_window,
        precession,
        motion,
        zero_px,
    } = fitted;
    let mut measured = span.measured;
    let frames = std::mem::take(&mut measured.frames);
    let warnings = std::mem::take(&mut measured.warnings);
    let calibration = as_scaled(&rest.calibration, measured.top_rim_leaning.as_ref());
    let diagnostics = diagnostics(&rest, &calibration, measured.highest.take());
    let plan = experiment_plan(
        clip,
        config,
        params,
        opened,
        &rest,
        decoded,
        calibration,
        measured,
        frames.len(),
        span.zero,
        zero_px,
    )?;
    Ok(Experiment {
        plan,
        frames,
        series: span.series,
        peaks_fit: fits.peaks,
        frames_fit: fits.frames,
        full_state_fit: fits.full_state,
        skips_in_window,
        precession,
        turn_timing: Some(fits.turns),
        motion_fit: motion,
        halt_placement,
        warnings,
        diagnostics,
    })
}

/// The calibration as the scale used it: z_t the leaning frames' near top rim when
/// read, for the plan and the calibration diagnostic.
fn as_scaled(
    calibration: &CalibrationReport,
    top_rim_leaning: Option<&TopRimLeaning>,
) -> CalibrationReport {
    CalibrationReport {
        calibration: vision::Calibration {
            z_t: top_rim_leaning.map_or(calibration.calibration.z_t, |l| l.reading.z_t),
            ..calibration.calibration
        },
        ..calibration.clone()
    }
}

/// The diagnostic images: the calibration as the scale used it (`calibration`) on
/// the last rest frame, and the threshold γ on the frame with the highest rim, with
/// its edge (`highest`: height, edge row, side view; empty when none had an edge).
fn diagnostics(
    rest: &RestCalibration,
    calibration: &CalibrationReport,
    highest: Option<(f64, f64, OwnedFrame)>,
) -> Diagnostics {
    let at_rest = &rest.calibration;
    let threshold_png = highest.map_or_else(Vec::new, |(_, edge_row, frame)| {
        png(&diagnostics::threshold_image(
            &frame.view(),
            at_rest.threshold.gamma,
            at_rest.calibration.x_centre(),
            rest.side_config.half_width_px,
            Some(edge_row),
        ))
    });
    let calibration_png = png(&diagnostics::calibration_image(
        &rest.rest_side.view(),
        &calibration.calibration,
    ));
    Diagnostics {
        calibration_png,
        threshold_png,
    }
}

/// The plan: every decision of the analysis, recorded as the result's provenance
/// (the clip and its hash, the config, the footage's timing and decoding, the
/// layout, plate and calibration, the scale, and how z_rim and its zero were read).
/// `measured` is the span without its frames, which number `frames`; `zero` the zero
/// the motion placed and `zero_px` the zero's 1σ uncertainty \[px\].
///
/// # Errors
/// The clip cannot be read again for its hash.
#[allow(clippy::too_many_arguments)]
fn experiment_plan(
    clip: &Path,
    config: &ExperimentConfig,
    params: DiskParams,
    opened: &OpenedClip,
    rest: &RestCalibration,
    decoded: DecodedSpan,
    calibration: CalibrationReport,
    measured: MeasuredFrames,
    frames: usize,
    zero: Option<ZeroFromMotion>,
    zero_px: f64,
) -> Result<ExperimentPlan, AnalyseError> {
    Ok(ExperimentPlan {
        clip: clip.to_path_buf(),
        clip_hash: clip_hash(clip)?,
        crate_version: env!("CARGO_PKG_VERSION").into(),
        config: config.clone(),
        fps: measured.fps,
        frame_times: Some(measured.frame_times),
        frames,
        decoded: Some(decoded),
        width: rest.width,
        height: rest.height,
        orientation: opened.source.orientation(),
        video_signal: opened.source.video_signal(),
        disk: params,
        layout: rest.layout.clone(),
        plate: rest.plate.clone(),
        split_row: rest.split_row,
        calibration,
        top_rim_leaning: measured.top_rim_leaning,
        metres_per_px: measured.metres_per_px,
        scale: measured.scale,
        band_half_width_px: rest.side_config.half_width_px,
        rim: measured.rim.description,
        rim_zero_row_px: Some(measured.rim.zero_row_px),
        rim_zero_from_motion: zero,
        rim_zero_uncertainty_px: zero_px,
        rim_reading: Some(measured.rim.reading),
        registration: measured.registration,
        colour_thresholds: rest.colour_thresholds,
        window_s: config.window_s(),
        halt: config.fit.as_ref().and_then(|f| f.halt).unwrap_or_default(),
    })
}

/// PNG bytes of a diagnostic image; empty if encoding fails (the images are for
/// looking at, never an input to a number).
/// The rest frame with the points the rest frames found (fig. 3.3), as PNG: for a
/// failure page, before the scale's own calibration report exists.
pub(super) fn calibration_png(rest: &RestCalibration) -> Vec<u8> {
    png(&diagnostics::calibration_image(
        &rest.rest_side.view(),
        &rest.calibration.calibration,
    ))
}

fn png(image: &image::RgbImage) -> Vec<u8> {
    crate::output::png_bytes(image).unwrap_or_default()
}
