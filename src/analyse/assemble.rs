//! Assemble: the diagnostic images, the plan (every decision, recorded as the
//! result's provenance) and the [`Experiment`].

use std::path::Path;

use super::calibrate::RestCalibration;
use super::checks::Fitted;
use super::diagnostics;
use super::open::OpenedClip;
use super::{AnalyseError, DecodedSpan, Diagnostics, Experiment, ExperimentPlan, clip_hash};
use crate::config::ExperimentConfig;
use crate::model::params::DiskParams;
use crate::vision::{self, CalibrationReport};

/// The [`Experiment`] of `clip` from the stages' results.
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
        zero_px,
    } = fitted;
    let calibration = rest.calibration;
    let threshold_png = span.highest.map_or_else(Vec::new, |(_, edge_row, frame)| {
        png(&diagnostics::threshold_image(
            &frame.view(),
            calibration.threshold.gamma,
            calibration.calibration.x_centre(),
            rest.side_config.half_width_px,
            Some(edge_row),
        ))
    });
    // The calibration as the scale used it: z_t the leaning frames' when read.
    let calibration = CalibrationReport {
        calibration: vision::Calibration {
            z_t: span
                .top_rim_leaning
                .map_or(calibration.calibration.z_t, |l| l.reading.z_t),
            ..calibration.calibration
        },
        ..calibration
    };
    let calibration_png = png(&diagnostics::calibration_image(
        &rest.rest_side.view(),
        &calibration.calibration,
    ));
    let plan = ExperimentPlan {
        clip: clip.to_path_buf(),
        clip_hash: clip_hash(clip)?,
        crate_version: env!("CARGO_PKG_VERSION").into(),
        config: config.clone(),
        fps: span.fps,
        frame_times: Some(span.frame_times),
        frames: span.frames.len(),
        decoded: Some(decoded),
        width: rest.width,
        height: rest.height,
        orientation: opened.source.orientation(),
        video_signal: opened.source.video_signal(),
        disk: params,
        layout: rest.layout,
        plate: rest.plate,
        split_row: rest.split_row,
        calibration,
        top_rim_leaning: span.top_rim_leaning,
        metres_per_px: span.metres_per_px,
        scale: span.scale,
        band_half_width_px: rest.side_config.half_width_px,
        rim: span.rim,
        rim_zero_row_px: Some(span.rim_zero_row_px),
        rim_zero_from_motion: span.zero,
        rim_zero_uncertainty_px: zero_px,
        rim_reading: Some(span.reading),
        colour_thresholds: rest.colour_thresholds,
        window_s: config.window_s(),
        halt: config.fit.as_ref().and_then(|f| f.halt).unwrap_or_default(),
    };
    Ok(Experiment {
        plan,
        frames: span.frames,
        series: span.series,
        peaks_fit: fits.peaks,
        frames_fit: fits.frames,
        full_state_fit: fits.full_state,
        skips_in_window,
        precession,
        turn_timing: Some(fits.turns),
        halt_placement,
        warnings: span.warnings,
        diagnostics: Diagnostics {
            calibration_png,
            threshold_png,
        },
    })
}

/// PNG bytes of a diagnostic image; empty if encoding fails (the images are for
/// looking at, never an input to a number).
fn png(image: &image::RgbImage) -> Vec<u8> {
    crate::output::png_bytes(image).unwrap_or_default()
}
