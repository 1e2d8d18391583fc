//! Overlays: the measurements, and the model, drawn on the footage itself
//! (issue 15), so that a person can see on the frames what was measured and
//! what the simulator predicts, as in Tracker.
//!
//! ```text
//! Experiment (plan, per-frame z_rim, peaks, halt, flags) ─┐
//! kept frames (keep.rs), else the clip's span decoded ───┴► canvas: windows of
//!         the frame enlarged, marks at their sub-pixel rows, a header of text
//!   ├─► on 4:2:0 samples → render::H264Writer → overlay.mp4 (slowed down),
//!   │   overlay.json (frame map)
//!   └─► in RGB, the frames at the last peaks → last-turns.png
//! compare's Comparison (trajectory) + pose from the calibration (pose.rs)
//!   └─► the model's outline on the same frames → model-overlay.mp4,
//!       model-last-turns.png, model-overlay.csv (rim-edge distance per frame)
//! ```
//!
//! `analyse` keeps the overlay's pictures of the frames near the last motion
//! while it reads the clip (keep.rs: reduced side and plan views and the centre
//! band, in YUV, with the strip measured, a bounded ring), and the measurement
//! overlay is drawn from them once the halt is known; where it kept none
//! (`compare`, some formats) the overlays read the span a third time, one
//! decoded frame at a time.

mod canvas;
mod keep;
mod last_turns;
mod measured;
mod model;
mod pose;

use std::path::PathBuf;

pub use canvas::{FONT_BYTES, Window};
pub use keep::{FrameKeeper, KeptFrames, MOVING_PX};
pub use measured::{
    LAST_TURNS_IMAGE, OVERLAY_H264, OVERLAY_INDEX, OVERLAY_VIDEO, OverlayFrame, OverlayIndex,
    OverlaySpec, write_measurement_overlays,
};
pub use model::{
    EdgeError, MODEL_LAST_TURNS_IMAGE, MODEL_OVERLAY_ERRORS, MODEL_OVERLAY_VIDEO, ModelOverlay,
    write_model_overlay,
};
pub use pose::CameraPose;

use crate::footage::FootageError;
use crate::output::OutputError;

/// Why an overlay could not be written; each names the clip or the file.
#[derive(Debug, thiserror::Error)]
pub enum OverlayError {
    #[error(transparent)]
    Footage(#[from] FootageError),
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error(
        "{}: no frame lies between t − t_φ = {from} s and {to} s, the overlay's span",
        clip.display()
    )]
    EmptySpan { clip: PathBuf, from: f64, to: f64 },
    #[error("{}: the clip changed since it was analysed: {reason}", clip.display())]
    Changed { clip: PathBuf, reason: String },
    #[error("{}: frame {frame}: cannot draw the overlay: {reason}", clip.display())]
    Draw {
        clip: PathBuf,
        frame: usize,
        reason: String,
    },
    #[error("cannot write {}: {reason} (--no-overlay skips the overlays)", path.display())]
    Encode { path: PathBuf, reason: String },
}
