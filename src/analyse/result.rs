//! What an analysis returns: the plan (its provenance), the frames' measurements,
//! the series, the fits and the checks.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::{DecodedSpan, ScaleReport};
use crate::config::{ExperimentConfig, HaltChoice};
use crate::energy::PowerLawFit;
use crate::footage::{self, CaptureFps, FrameTiming};
use crate::model::params::DiskParams;
use crate::precession::PrecessionCheck;
use crate::signal::{self, StateSeries};
use crate::turn_timing::TurnTimingFit;
use crate::vision::{
    self, CalibrationReport, ColourThresholds, Registration, RimReading, ThresholdSource,
};

/// The zero of z_rim as the motion places it ([`signal::motion_zero`]), and how far it
/// moved every height.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ZeroFromMotion {
    /// The motion's offset c above the rest tail's level, and its standard error \[m\].
    pub zero: signal::MotionZero,
    /// How far every height moved down: the rest tail's level plus c \[m\]. The
    /// profile fitted is the camera's at [`ScaleReport::near_rim_elevation_rad`].
    pub shift_m: f64,
}

/// Where the laws placed the halt t_φ ([`law_halt`](super::halt::law_halt)): the estimates it is the mean of,
/// from the fits before it was placed, and the halt detector's last frame of motion,
/// all on the clock that starts at t_φ \[s\].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HaltPlacement {
    /// The peaks fit's t0.
    pub t0_s: f64,
    /// The end T of the turns' timing law; `None` when the turns could not be timed
    /// (t_φ is then t0).
    pub turns_end_s: Option<f64>,
    /// Standard error of t_φ: half the standard errors of t0 and T in quadrature (T's
    /// from the timing law's jackknife), or t0's alone; `None` when t0's is unknown.
    pub se_s: Option<f64>,
    /// The halt detector's last frame of motion.
    pub last_motion_seen_s: f64,
}

impl HaltPlacement {
    /// The same placement on a clock that starts `offset` \[s\] later.
    pub(super) fn shifted(self, offset: f64) -> Self {
        HaltPlacement {
            t0_s: self.t0_s - offset,
            turns_end_s: self.turns_end_s.map(|t| t - offset),
            last_motion_seen_s: self.last_motion_seen_s - offset,
            ..self
        }
    }
}

/// Everything an analysis decided before measuring: the resolved plan, recorded
/// beside every result as its provenance.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ExperimentPlan {
    pub clip: PathBuf,
    /// BLAKE3 hash of the clip's bytes (all frame files, in order, for a folder).
    pub clip_hash: String,
    pub crate_version: String,
    pub config: ExperimentConfig,
    pub fps: CaptureFps,
    /// Where the frame times came from (container pts or index / fps), with the
    /// sections of constant frame interval and the median and spread of the
    /// interval; `None` in results written before it was recorded.
    #[serde(default)]
    pub frame_times: Option<FrameTiming>,
    /// Frames measured: the decoded span's.
    pub frames: usize,
    /// Which frames were decoded and why (`None` in results written before spans
    /// were decoded: the whole clip).
    #[serde(default)]
    pub decoded: Option<DecodedSpan>,
    /// Displayed frame width \[px\] (after `orientation`).
    pub width: usize,
    /// Displayed frame height \[px\].
    pub height: usize,
    /// The display matrix's rotation and mirror, applied to every frame before it
    /// was measured (identity in results written before it was recorded).
    #[serde(default)]
    pub orientation: footage::Orientation,
    /// A video's pixel format, bit depth, range, YUV matrix and transfer function,
    /// from which frames were converted to 8-bit full-range colour before any
    /// threshold (`None`: a frame folder, or a result written before it was
    /// recorded).
    #[serde(default)]
    pub video_signal: Option<footage::VideoSignal>,
    pub disk: DiskParams,
    /// Side view or two-view, and whether the config said so or how it was detected.
    pub layout: String,
    /// Dark or light plate, and whether the config said so or how it was detected.
    pub plate: String,
    /// Two-view clips: the first row of the plan view \[px\] and whether it came from
    /// the config.
    pub split_row: Option<(usize, bool)>,
    /// The rest frames' calibration; its z_t is [`Self::top_rim_leaning`]'s when that
    /// was read.
    pub calibration: CalibrationReport,
    /// The near top rim z_t from the frames in which the disk leans towards the
    /// camera, which the scale uses; `None` when too few frames showed the top face
    /// resolved, when the config gives z_t, and in results written before it.
    #[serde(default)]
    pub top_rim_leaning: Option<TopRimLeaning>,
    /// Scale at the near bottom rim, where z_rim is read [m/px].
    pub metres_per_px: f64,
    /// How the scale was found: both estimates and the perspective they imply.
    pub scale: ScaleReport,
    pub band_half_width_px: usize,
    /// How z_rim was measured: the mirror-edge model with its fitted plate line,
    /// reflectivity and whether the rim is sharp, the light plate's shadow-edge
    /// contour, or the edge alone and why.
    #[serde(default)]
    pub rim: String,
    /// The side view's row where z_rim = 0 \[px\]: where the motion places it
    /// ([`Self::rim_zero_from_motion`]), else the rim edge at rest (the mirror-edge
    /// model's fitted e_rest on a dark plate, the shadow-edge contour's on a light
    /// one, else the plate line z_base). A frame's measured rim edge lies at this
    /// row − z_rim_px; `None` in results written before it was recorded (then
    /// z_base).
    #[serde(default)]
    pub rim_zero_row_px: Option<f64>,
    /// The zero the motion placed, and how far it moved the heights from the rest
    /// edge's; `None` when too few turns fitted or the camera's elevation is not
    /// known, with `fit.rim_zero = "rest"`, and in results written before it.
    #[serde(default)]
    pub rim_zero_from_motion: Option<ZeroFromMotion>,
    /// 1σ uncertainty of that zero \[px\], carried into the intervals of n
    /// (`PowerLawFit::se_n_zero`): the config's `fit.rim_zero_uncertainty_px`, else
    /// the motion's ([`vision::RimReading::motion_zero_uncertainty_px`]), else the
    /// one measured for [`Self::rim_reading`]; 0 in results written before it was.
    #[serde(default)]
    pub rim_zero_uncertainty_px: f64,
    /// How the rim's heights were read (vision::RimReading); `None` in results
    /// written before it was recorded.
    #[serde(default)]
    pub rim_reading: Option<RimReading>,
    /// The camera's motion against the scene beside the disk, by which every
    /// rim height was corrected when `applied` (vision::registration); `None` when
    /// no strip fits beside the disk, and in results written before it.
    #[serde(default)]
    pub registration: Option<Registration>,
    pub colour_thresholds: Option<(ColourThresholds, ThresholdSource)>,
    pub window_s: f64,
    pub halt: HaltChoice,
}

impl ExperimentPlan {
    /// The side view's row of the rim edge for a rim height `z_rim_px` \[px\]: the
    /// row where z_rim = 0 ([`Self::rim_zero_row_px`]) less the height.
    pub fn rim_edge_row(&self, z_rim_px: f64) -> f64 {
        self.rim_zero_row_px
            .unwrap_or(self.calibration.calibration.z_base)
            - z_rim_px
    }

    /// The side view's width \[px\]: the region of interest's, else the frame's.
    pub fn side_view_width(&self) -> usize {
        let roi = self.config.vision.as_ref().and_then(|v| v.roi);
        roi.map_or(self.width, |r| r[2] as usize)
    }

    /// Where the side view's pixel (0, 0) lies in the frame: the corner of the
    /// region of interest, else the frame's.
    pub fn side_view_origin(&self) -> (usize, usize) {
        let roi = self.config.vision.as_ref().and_then(|v| v.roi);
        roi.map_or((0, 0), |[x, y, _, _]| (x as usize, y as usize))
    }
}

/// The near top rim z_t read from the frames in which the rolling disk leans
/// towards the camera ([`vision::near_top_rim_leaning`]): there the top face is
/// several pixels tall even when, at rest, it is thinner than the blur and the
/// rest frame's readings cannot tell its near rim from its far one.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TopRimLeaning {
    pub reading: vision::LeaningTopRim,
    /// The rest frame's reading of z_t, which it replaced \[px\].
    pub rest_z_t: f64,
}

/// One frame's measurements.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FrameRecord {
    pub index: usize,
    /// Capture time from the first frame \[s\]: the container's timestamp mapped to
    /// the capture clock, or index / fps without timestamps (see
    /// [`ExperimentPlan::frame_times`]), one frame later for each frame the rim's
    /// phase shows missing before it where the timestamps show no gap
    /// ([`signal::missing_frames`]).
    pub t_capture: f64,
    /// Time with the halt at 0 \[s\].
    pub t: f64,
    /// The container's presentation time [s, playback clock], when it has one.
    pub container_time_s: Option<f64>,
    /// How the codec coded the frame: 'I', 'P' or 'B' (libavutil's picture type);
    /// `None` for frame folders and in results written before it was recorded.
    #[serde(default)]
    pub picture_type: Option<char>,
    /// Rim height above the plate line \[px\]; 0 when the rim touches; `None`
    /// when no edge was found. Corrected for the camera's shift.
    pub z_rim_px: Option<f64>,
    /// The picture's vertical shift at the centre line against the rest tail
    /// \[px\], positive down (vision::registration), by which z_rim was corrected;
    /// `None` when not measured or not applied, and in results written before it.
    #[serde(default)]
    pub camera_shift_px: Option<f64>,
    /// The same in metres.
    pub z_rim_m: Option<f64>,
    /// Strip angle β from PCA, in (−π/2, π/2] (two-view clips).
    pub beta_raw: Option<f64>,
}

/// Energy at one instant, with the state it came from.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct EnergySample {
    /// Time, halt at 0 \[s\].
    pub t: f64,
    pub phi: f64,
    pub psi_dot: f64,
    /// θ̇ = β̇ − ψ̇ (eq. 3.22), for eq. 3.6.
    pub theta_dot: Option<f64>,
    /// Energy above the flat rest state \[J\].
    pub energy: f64,
}

/// A power-law fit of one energy series, with its window sensitivity.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct EnergyFit {
    /// What was fitted, e.g. "eq. 3.8 at peaks".
    pub method: String,
    pub samples: Vec<EnergySample>,
    pub fit: PowerLawFit,
    /// n over other windows: (window \[s\], fit or the reason it failed).
    pub windows: Vec<(f64, Result<PowerLawFit, String>)>,
}

/// The result of one clip.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Experiment {
    pub plan: ExperimentPlan,
    pub frames: Vec<FrameRecord>,
    /// The signal analysis of `frames`: its flags carry the clip's frame numbers
    /// ([`FrameRecord::index`], as flags.csv), its peaks, states and halt
    /// positions in `frames`.
    pub series: StateSeries,
    /// The headline fit: eq. 3.8 at the peaks (the thesis's method).
    pub peaks_fit: EnergyFit,
    /// Eq. 3.8 on the per-frame states.
    pub frames_fit: Option<EnergyFit>,
    /// Eq. 3.6 with θ̇ from the strip (two-view clips).
    pub full_state_fit: Option<EnergyFit>,
    /// Flagged frames inside the fit window.
    pub skips_in_window: usize,
    /// φ from the heights against φ from the precession rate over the fit window
    /// ([`crate::precession::precession_check`]); `None` with too few states, and in results
    /// written before it was recorded.
    #[serde(default)]
    pub precession: Option<PrecessionCheck>,
    /// n from the times of z_rim's peaks and troughs alone in the fit window ([`crate::turn_timing::fit_turn_timing`]),
    /// or why it could not be fitted; `None` in results written before it was recorded.
    #[serde(default)]
    pub turn_timing: Option<Result<TurnTimingFit, String>>,
    /// The motion fitted to every frame of the window ([`crate::motion_fit`]): n and
    /// the halt t0 from every height at once, for information; `None` when it could
    /// not be fitted, and in results written before it was recorded.
    #[serde(default)]
    pub motion_fit: Option<crate::motion_fit::MotionFit>,
    /// Where t_φ was placed by the laws ([`law_halt`](super::halt::law_halt)); `None` when it is the last
    /// frame of motion seen (`halt = "measured"`, or the placement failed) and in
    /// results written before it was recorded.
    #[serde(default)]
    pub halt_placement: Option<HaltPlacement>,
    pub warnings: Vec<String>,
    /// Diagnostic images (PNG): the calibration frame with its points, and the
    /// frame of the highest rim thresholded with the band and the edge found.
    #[serde(skip)]
    pub diagnostics: Diagnostics,
}

/// PNG images for a person checking the image stage.
#[derive(Debug, Clone, Default)]
pub struct Diagnostics {
    pub calibration_png: Vec<u8>,
    pub threshold_png: Vec<u8>,
}
