//! The page of a clip the chain refused (issue 72 §6): the reason in words, what to
//! try, and the evidence the stages before the refusal found: the rest frame with
//! its calibration points, and the rim heights as measured.
//!
//! | file | content |
//! |---|---|
//! | `index.html` | the reason, what to try, the pictures |
//! | `failure.json` | the clip, the stage that refused it, the reason and the suggestions |
//! | `calibration.png` | the rest frame with x_l, x_r, z_t, z_base (once calibrated) |
//! | `heights.svg`, `heights.png` | z_rim against the capture time (once measured) |

use std::path::{Path, PathBuf};

use maud::html;
use serde::{Deserialize, Serialize};

use super::ReportError;
use super::html::{page, png_figure, svg_figure};
use super::plot::{Panel, time_panels};
use crate::analyse::{AnalyseError, Failure};
use crate::output::{write_atomic, write_json};

/// The file a failure page's record is written to.
pub const FAILURE_FILE: &str = "failure.json";

/// What `failure.json` holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FailureRecord {
    /// The clip, as given.
    pub clip: PathBuf,
    /// The stage that refused it: "opening and calibration", "measuring the frames" or
    /// "the signal stage and the fits".
    pub stage: String,
    /// The refusal, as the chain gave it.
    pub reason: String,
    /// The plate kind the calibration took and how it was told, once calibrated.
    pub plate: Option<String>,
    /// What to try, most likely first.
    pub try_next: Vec<String>,
    /// The crate version that refused it.
    pub crate_version: String,
}

impl FailureRecord {
    /// The record of `failure` of `clip`.
    pub fn new(clip: &Path, failure: &Failure) -> Self {
        let stage = match (&failure.partial.calibration_png, &failure.partial.heights) {
            (_, Some(_)) => "the signal stage and the fits",
            (Some(_), None) => "measuring the frames",
            (None, None) => "opening and calibration",
        };
        FailureRecord {
            clip: clip.to_path_buf(),
            stage: stage.into(),
            reason: failure.error.to_string(),
            plate: failure.partial.plate.clone(),
            try_next: try_next(&failure.error),
            crate_version: env!("CARGO_PKG_VERSION").into(),
        }
    }
}

/// What a user can change for each kind of refusal (docs/config.md names the keys).
fn try_next(error: &AnalyseError) -> Vec<String> {
    let tips: &[&str] = match error {
        AnalyseError::Footage(_) | AnalyseError::Clip { .. } => &[
            "check that the file plays to its end in a video player; re-encode it if not",
            "check that the path names a video file or a folder of frames",
        ],
        AnalyseError::Fps { .. } => &["give the camera's frame rate as `fps` in the config"],
        AnalyseError::Setting { .. } => &["change the setting the reason names"],
        AnalyseError::Vision { .. } => &[
            "check the rest frame below: the disk must lie at rest, whole and in view, at \
             the clip's end",
            "give the plate (`plate = \"dark\"` or `\"light\"`), the threshold `gamma`, or \
             the calibration points (`[calibration]` x_l, x_r, z_t, z_base) in the config",
        ],
        AnalyseError::Signal { .. } | AnalyseError::Fit { .. } => &[
            "check the rim heights below: the rim should rise and fall once a turn and come \
             to rest before the clip ends",
            "check the rest frame and the plate kind below: a mirror image taken for the \
             disk, or the wrong kind of plate, puts the rim's edge elsewhere; give `plate` \
             (\"dark\" or \"light\") or the calibration points in the config",
            "check the frame rate (`fps`): too few frames a turn hide the peaks",
            "lengthen the fit window (`fit.window_s`) when too few peaks lie in it",
        ],
        AnalyseError::AcrossSections { .. } => &[
            "the frame interval changes inside the fit window: shorten `fit.window_s`, or \
             give `fps` if the timestamps are wrong",
        ],
    };
    tips.iter().map(|t| t.to_string()).collect()
}

/// Writes the failure page of `clip` into `dir` (created if missing).
///
/// # Errors
/// A file cannot be written or the heights cannot be drawn.
pub fn write_failure(dir: &Path, clip: &Path, failure: &Failure) -> Result<(), ReportError> {
    crate::output::create_folder(dir)?;
    let record = FailureRecord::new(clip, failure);
    write_json(&dir.join(FAILURE_FILE), &record)?;
    let calibration = failure.partial.calibration_png.as_deref();
    if let Some(png) = calibration {
        write_atomic(&dir.join("calibration.png"), png)?;
    }
    let heights_svg = match &failure.partial.heights {
        Some((t, z)) => Some(heights_plot(dir, t, z)?),
        None => None,
    };
    let body = html! {
        p { "This clip was not measured. The stage that refused it: " (record.stage) "." }
        h2 { "Why" }
        p { code { (record.reason) } }
        h2 { "What to try" }
        ul { @for tip in &record.try_next { li { (tip) } } }
        @if let Some(svg) = &heights_svg {
            h2 { "The rim heights as measured" }
            (svg_figure(svg, "z_rim on the centre line against the capture time; gaps: frames with no edge found."))
        }
        @if let Some(png) = calibration {
            h2 { "The rest frame" }
            @if let Some(plate) = &record.plate { p { "Plate: " (plate) } }
            (png_figure(png, "Rest frame: x_l, x_r (green), z_t (yellow), z_base (red), centre line (blue)."))
        }
        p.note { "eulerdisk " (record.crate_version) "; " (FAILURE_FILE) " holds this in JSON." }
    };
    let title = format!(
        "{}: not measured",
        clip.file_name().map_or_else(
            || clip.display().to_string(),
            |n| n.to_string_lossy().into_owned()
        )
    );
    write_atomic(&dir.join("index.html"), page(&title, body).as_bytes())?;
    Ok(())
}

/// z_rim against the capture time, as `heights.svg` and `.png` in `dir`; returns the SVG.
fn heights_plot(dir: &Path, t: &[f64], z_rim_px: &[f64]) -> Result<String, ReportError> {
    let [svg, _png] = time_panels(
        &dir.join("heights"),
        "Rim heights as measured",
        "capture time [s]",
        t,
        &[Panel {
            label: "z_rim [px]",
            values: z_rim_px,
            log_y: false,
        }],
        &[],
        "",
    )
    .map_err(|e| ReportError::Plot(e.to_string()))?;
    std::fs::read_to_string(&svg).map_err(|e| ReportError::Plot(format!("{}: {e}", svg.display())))
}
