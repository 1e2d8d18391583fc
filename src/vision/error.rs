//! Why a frame could not be measured.
//!
//! Variants carry the frame index (counted from the start of the clip, as the
//! caller numbers frames) and the physical context; the caller adds the file name.

/// A frame, or a sequence of frames, that `vision` could not measure.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VisionError {
    /// The view's buffer is shorter than its size and stride claim, or the view is empty.
    #[error("frame {frame}: malformed view ({width}×{height}, stride {stride}, {len} bytes)")]
    MalformedFrame {
        frame: usize,
        width: usize,
        height: usize,
        stride: usize,
        len: usize,
    },

    /// Frames of one clip with different sizes.
    #[error(
        "frame {frame}: size {width}×{height} differs from the calibration frame's {expected_width}×{expected_height}"
    )]
    SizeMismatch {
        frame: usize,
        width: usize,
        height: usize,
        expected_width: usize,
        expected_height: usize,
    },

    /// Nothing brighter than γ that could be the disk: the threshold finds no
    /// bright blob lying wholly inside the view.
    #[error(
        "frame {frame}: no disk in view (nothing brighter than γ = {gamma:.3} lies wholly \
         inside the frame); check the lighting, `vision.roi`, or set `vision.gamma` in the config"
    )]
    NoDisk { frame: usize, gamma: f64 },

    /// A calibration point could not be located on the rest frame.
    #[error(
        "frame {frame}: calibration point {point} not found on the rest frame; \
         give all four points in the config's [calibration] table (x_l, x_r, z_t, z_base [px])"
    )]
    CalibrationPointNotFound { frame: usize, point: &'static str },

    /// Calibration points that do not describe a disk in this frame
    /// (x_r ≤ x_l, z_base ≤ z_t, or outside the frame).
    #[error(
        "invalid calibration (x_l {x_l:.2}, x_r {x_r:.2}, z_t {z_t:.2}, z_base {z_base:.2} px \
         in a {width}×{height} frame): {reason}"
    )]
    InvalidCalibration {
        x_l: f64,
        x_r: f64,
        z_t: f64,
        z_base: f64,
        width: usize,
        height: usize,
        reason: &'static str,
    },

    /// The frames meant to show the disk at rest after the halt differ.
    #[error(
        "frame {frame}: the disk is not at rest: {point} lies {shift_px:.2} px from its median \
         over the rest frames {first}–{last} (tolerance {tolerance_px:.2} px); calibrate on \
         later frames"
    )]
    NotAtRest {
        frame: usize,
        first: usize,
        last: usize,
        point: &'static str,
        shift_px: f64,
        tolerance_px: f64,
    },

    /// Every plate kind's calibration reads the disk's side thicker, against its
    /// diameter, than any side view shows it (issue 72 §2).
    #[error(
        "the calibration reads the disk's side {factor:.2} times as thick, against its \
         diameter, as the disk's dimensions allow (at most {max} for a camera that close): \
         the reflection or the shadow below the disk was probably taken for part of it \
         ({tried}); check the disk's `half_thickness_m` and `radius_m` in `[disk]`, and \
         give `plate` (\"dark\" or \"light\") or the calibration points in \
         `[calibration]` in the config"
    )]
    ImpossibleScale {
        factor: f64,
        max: f64,
        tried: String,
    },

    /// Neither plate kind could be calibrated on the rest frames.
    #[error(
        "the plate's kind was not recognised: {tried}; if you know it, give `plate` \
         (\"dark\" or \"light\") in the config"
    )]
    PlateNotRecognised { tried: String },

    /// A rest check was asked for on no frames.
    #[error("no frames given for the calibration (at least one rest frame is needed)")]
    NoFrames,

    /// An invalid setting of a vision stage.
    #[error("invalid vision setting {name} = {value}: {reason}")]
    InvalidSetting {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },

    /// No row separates the mirror side view from the plan view.
    #[error(
        "frame {frame}: neither a dark band nor a band of uniform rows separates the side \
         view (top) from the plan view (bottom); give it as `vision.split_row` [px] in the \
         config"
    )]
    NoSplit { frame: usize },

    /// The colour thresholds (eq. 3.23) select too few pixels in the plan view.
    #[error(
        "frame {frame}: no strip found in the plan view ({pixels} pixels pass the colour \
         thresholds, at least {min_pixels} needed)"
    )]
    NoStrip {
        frame: usize,
        pixels: usize,
        min_pixels: usize,
    },
}
