//! One clip from pixels to the energy exponent: the stages of DESIGN.md chained.
//!
//! ```text
//! footage::  probe, capture fps (config / container tag / container fps), FrameSource;
//!   │        after pass 2, frame times: container pts on the capture clock (or index / fps)
//!   │        pass 1: the last frames (rest after the halt)
//!   ▼
//! vision::   calibrate_at_rest → x_l, x_r, z_t, z_base, γ     (thesis §3.2.4)
//!   │        two-view: split row, colour thresholds             (§3.3.2)
//!   │        pass 2, streamed: RimGauge per frame → z_rim [px]; StripFinder → β
//!   │        dark plate: GapGauge per frame, then z_rim < 2 px from the gap's darkness
//!   │        scale [`scale`]: eq. 3.10 at the near rim, the camera's distance and
//!   │        elevation, the local scale at the near bottom rim  (§3.2.4, issue 12 §2)
//!   ▼
//! signal::   halt t_φ, peaks, φ (eq. 3.9), ψ, ψ̇ (eq. 3.11), per-frame states,
//!   │        β unwrapped and smoothed, t_β, frame-skip flags    (§3.2.5, §3.3.3)
//!   ▼
//! energy::   E at peaks by eq. 3.8, per frame by eq. 3.8, and by eq. 3.6 with
//!            θ̇ = β̇ − ψ̇ (eq. 3.22) for two-view clips; E = A_e (t0 − t)^n fitted
//!            over the window, and over 1, 0.5, 0.25, 0.1 s
//! ```
//!
//! [`analyse_clip`] reads the clip twice (the calibration must be known before the
//! rim can be measured) and keeps only scalars per frame, so memory does not grow
//! with frame size or, beyond a few numbers per frame, with clip length. A video
//! longer than [`WHOLE_CLIP_UP_TO_S`] is measured in pass 2 from a key frame near
//! its end ([`Decoding::NearTheEnd`], the span grown back until it holds the fits'
//! motion), so a minutes-long clip costs about what its last seconds cost.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::config::{ExperimentConfig, HaltChoice, Plate, RimZeroChoice};
use crate::energy::{self, FitError, HaltSighting, HaltTime, PowerLawFit, TurnsEnd};
use crate::footage::{self, CaptureFps, FootageError, FrameSource, FrameTiming, FrameView};
use crate::model::closed_form;
use crate::model::params::DiskParams;
use crate::overlay::{FrameKeeper, KeptFrames, LayoutGeometry, OverlaySpec};
use crate::precession::{self, PrecessionCheck};
use crate::report::diagnostics;
use crate::signal::{
    self, PeakSeries, RimModel, SideViewRim, SignalConfig, SignalError, StateSeries, ThesisRim,
};
use crate::turn_timing::{self, TurnTimingFit};
use crate::vision::{
    self, BandWindow, CalibrationOverride, CalibrationReport, ColourThresholds, GapGauge, RimGauge,
    RimHeight, RimReading, SideViewConfig, StripFinder, ThresholdSource, VisionError,
};

mod scale;
use scale::PERSPECTIVE_FACTOR_RANGE;
pub use scale::ScaleReport;

/// Frames at the end of a clip that must show the disk at rest (calibration).
pub const REST_FRAMES: usize = 5;

/// Every second pixel of every second row is compared with the neighbouring
/// frames' to find duplicated and interpolated frames (footage::RepeatGauge).
const REPEAT_SAMPLE_STEP: usize = 2;

/// The windows of the window-sensitivity table \[s\] (issue: 1, 0.5, 0.25, 0.1 s).
pub const SENSITIVITY_WINDOWS_S: [f64; 4] = [1.0, 0.5, 0.25, 0.1];

/// Clips up to this long [s, capture clock] are decoded whole: every clip the
/// thesis and our renders analyse (under 5 s) gives the same result as before
/// spans existed, and decoding a few seconds more costs little.
pub const WHOLE_CLIP_UP_TO_S: f64 = 8.0;

/// The first span decoded of a longer clip: its last this many seconds. With the
/// disk halting in the clip's last 2 s, it holds the rest tail, the 1 s of the
/// widest fit window and a margin.
pub const FIRST_SPAN_S: f64 = 4.0;

/// Turns of the rim's oscillation decoded before the widest fit window beyond the
/// local fits' own window ([`SignalConfig::state_window_periods`]): one for the
/// peak finder to see the first peak whole and the central difference of ψ̇ at
/// it, one more for the turn counting's median interval.
const LEAD_PERIODS: f64 = 2.0;

/// How much of a clip `analyse` decodes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Decoding {
    /// A span at the end of a video longer than [`WHOLE_CLIP_UP_TO_S`], found
    /// from the container's index and grown back by key frames until it holds
    /// the fits' motion and the rest tail; shorter clips and frame folders whole.
    #[default]
    NearTheEnd,
    /// Every frame (`analyse --whole`).
    Whole,
}

/// The frames an analysis decoded, and why those: recorded in the plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DecodedSpan {
    /// The first decoded frame's number in the clip (0: the whole clip).
    pub first_frame: usize,
    /// The last decoded frame's number.
    pub last_frame: usize,
    /// Frames in the clip.
    pub clip_frames: usize,
    /// Capture time of the first decoded frame from the clip's first \[s\].
    pub first_t_capture_s: f64,
    /// Spans decoded before the last one held the motion the fits need, plus one.
    pub attempts: usize,
    /// Why this span: the clip was short, `--whole`, or what the span holds.
    pub reason: String,
}

impl DecodedSpan {
    /// Whether every frame of the clip was decoded.
    pub fn is_whole(&self) -> bool {
        self.first_frame == 0
    }

    /// One line for the terminal and the report.
    pub fn summary(&self) -> String {
        if self.is_whole() {
            format!(
                "decoded the whole clip ({} frames): {}",
                self.clip_frames, self.reason
            )
        } else {
            format!(
                "decoded frames {}–{} of {} (from t = {:.3} s of the clip): {}; frame-skip \
                 flags, repeated frames and plots cover these frames only (analyse --whole \
                 for all)",
                self.first_frame,
                self.last_frame,
                self.clip_frames,
                self.first_t_capture_s,
                self.reason
            )
        }
    }
}

/// Where pass 2 starts: the container's index of a long video, read without
/// decoding, and the capture time of each of its frames.
struct SpanPlan {
    /// The index, when a span may be decoded (`None`: the whole clip is).
    index: Option<footage::StreamIndex>,
    /// Capture time of every frame from the clip's first \[s\] (empty without index).
    times: Vec<f64>,
    clip_frames: usize,
    /// Why the whole clip is decoded, when it is.
    whole_reason: String,
}

impl SpanPlan {
    /// Plan from the clip's `index` (the packets' timestamps, `None` for a frame
    /// folder or a video whose packets lack them): the whole clip when
    /// `decoding` is [`Decoding::Whole`], without an index, when the clip is at
    /// most [`WHOLE_CLIP_UP_TO_S`] long, or when the index does not list the
    /// `expected` frames.
    fn new(
        index: Option<footage::StreamIndex>,
        decoding: Decoding,
        expected: usize,
        fps: &footage::CaptureFps,
    ) -> Self {
        let whole = |reason: String| SpanPlan {
            index: None,
            times: Vec::new(),
            clip_frames: expected,
            whole_reason: reason,
        };
        if decoding == Decoding::Whole {
            return whole("--whole".into());
        }
        let Some(index) = index else {
            return whole("a frame folder, or a video whose packets carry no timestamps".into());
        };
        let listed = index.container_times_s.len();
        if listed != expected {
            return whole(format!(
                "the container's packets list {listed} frames, its frame count {expected}"
            ));
        }
        let stamps: Vec<Option<f64>> = index.container_times_s.iter().copied().map(Some).collect();
        let (times, _) = footage::frame_times(&stamps, &mut fps.clone());
        let duration = times.last().copied().unwrap_or(0.0);
        if duration <= WHOLE_CLIP_UP_TO_S {
            return whole(format!(
                "a {duration:.2} s clip (clips up to {WHOLE_CLIP_UP_TO_S} s are decoded whole)"
            ));
        }
        SpanPlan {
            index: Some(index),
            times,
            clip_frames: expected,
            whole_reason: String::new(),
        }
    }

    /// The key frame at or before the last frame at capture time `t` \[s\] (0
    /// before the clip's first key frame, or without an index).
    fn key_frame_at(&self, t: f64) -> usize {
        let frame = self.times.partition_point(|&x| x <= t).saturating_sub(1);
        self.key_frame_at_or_before(frame)
    }

    /// The first frame of the first span: the key frame before the clip's last
    /// [`FIRST_SPAN_S`], or 0 for a whole clip.
    fn first_span(&self) -> usize {
        match self.times.last() {
            Some(&end) if self.index.is_some() => self.key_frame_at(end - FIRST_SPAN_S),
            _ => 0,
        }
    }

    /// An earlier key frame to start from when the span from `first` may miss
    /// motion the fits need, else `None`. The fits need the wider of the
    /// analysis window (`window_s`) and the sensitivity table's 1 s before the
    /// halt, plus the local fits' window and [`LEAD_PERIODS`] turns of the rim
    /// before that, a turn measured between the span's first two peaks (the
    /// longest: turns slow away from the halt). A span that failed to analyse
    /// (`measured` is `None`: no halt, too few peaks) or that starts after that
    /// time is grown back to that time, and at least to twice its length.
    fn earlier_start(
        &self,
        first: usize,
        measured: Option<&MeasuredSpan>,
        window_s: f64,
    ) -> Option<usize> {
        let (Some(_), Some(&end)) = (&self.index, self.times.last()) else {
            return None;
        };
        if first == 0 {
            return None;
        }
        let doubled = end - 2.0 * (end - self.times[first]);
        let widest = SENSITIVITY_WINDOWS_S
            .iter()
            .copied()
            .fold(window_s, f64::max);
        let wanted = match measured {
            None => doubled,
            Some(m) => {
                let peaks = &m.series.peaks.peaks;
                let needed = match peaks.as_slice() {
                    [p0, p1, ..] => widest + (m.local_fit_periods + LEAD_PERIODS) * (p1.t - p0.t),
                    _ => f64::INFINITY,
                };
                let span_start = m.frames.first().map_or(f64::INFINITY, |f| f.t);
                if span_start <= -needed {
                    return None;
                }
                (m.series.halt.t_phi - needed).min(doubled)
            }
        };
        Some(self.key_frame_at_or_before(self.key_frame_at(wanted).min(first - 1)))
    }

    /// The key frame at or before frame `frame`.
    fn key_frame_at_or_before(&self, frame: usize) -> usize {
        self.index.as_ref().map_or(0, |index| {
            let k = index.key_frames.partition_point(|&key| key <= frame);
            k.checked_sub(1).map_or(0, |k| index.key_frames[k])
        })
    }

    /// Frame `index` of a span must carry the container time the index lists
    /// for it (`time_s`); otherwise the span's frames are not numbered as in
    /// the clip.
    fn check_frame(
        &self,
        clip: &Path,
        index: usize,
        time_s: Option<f64>,
    ) -> Result<(), AnalyseError> {
        let listed = self
            .index
            .as_ref()
            .and_then(|i| i.container_times_s.get(index));
        match (listed, time_s) {
            (Some(&listed), Some(t)) if (listed - t).abs() <= 1e-9 => Ok(()),
            _ => Err(AnalyseError::Clip {
                path: clip.to_path_buf(),
                reason: format!(
                    "decoded frame {index} has container time {time_s:?} s, the container's \
                     packets list {listed:?} s: its frames cannot be numbered from a seek \
                     (analyse --whole)"
                ),
            }),
        }
    }

    /// What was decoded: frames `first` to the end of the clip, after `attempts`
    /// spans, `decoded` frames in all.
    fn decoded(&self, first: usize, attempts: usize, decoded: usize) -> DecodedSpan {
        let reason = if first == 0 {
            if self.index.is_some() {
                "the spans at its end did not hold the fits' motion and rest tail".into()
            } else {
                self.whole_reason.clone()
            }
        } else {
            format!(
                "the last {:.2} s of a {:.2} s clip hold the analysis window, the \
                 sensitivity table's 1 s, the local fits' margin and the rest tail \
                 ({attempts} span(s) tried)",
                self.times[self.times.len() - 1] - self.times[first],
                self.times[self.times.len() - 1]
            )
        };
        DecodedSpan {
            first_frame: first,
            last_frame: (first + decoded).saturating_sub(1),
            clip_frames: if first == 0 {
                decoded
            } else {
                self.clip_frames
            },
            first_t_capture_s: self.times.get(first).copied().unwrap_or(0.0),
            attempts,
            reason,
        }
    }
}

/// Pass 2's measurements of one span, through the signal analysis.
struct MeasuredSpan {
    frames: Vec<FrameRecord>,
    series: StateSeries,
    fps: CaptureFps,
    frame_times: FrameTiming,
    warnings: Vec<String>,
    highest: Option<(f64, f64, OwnedFrame)>,
    rim: String,
    rim_zero_row_px: f64,
    /// How the rim's heights were read, which decides how well their zero is known
    /// when the motion does not place it.
    reading: RimReading,
    /// The zero the motion placed.
    zero: Option<ZeroFromMotion>,
    scale: ScaleReport,
    metres_per_px: f64,
    /// Width of the local fits' window [turns of the rim].
    local_fit_periods: f64,
    /// The rest tail's length \[s\] (SignalConfig::rest_tail_s).
    rest_tail_s: f64,
    /// The overlay's pictures of the frames near the last motion.
    kept: Option<KeptFrames>,
    /// Flags found before the signal stage ([`known_flags`]), positions in `frames`.
    known_flags: Vec<signal::FrameFlag>,
    /// The near top rim from the frames leaning towards the camera, when read.
    top_rim_leaning: Option<TopRimLeaning>,
}

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

/// Where the laws placed the halt t_φ ([`law_halt`]): the estimates it is the mean of,
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
    fn shifted(self, offset: f64) -> Self {
        HaltPlacement {
            t0_s: self.t0_s - offset,
            turns_end_s: self.turns_end_s.map(|t| t - offset),
            last_motion_seen_s: self.last_motion_seen_s - offset,
            ..self
        }
    }
}

/// Why a clip could not be analysed. Every message names the clip; vision errors
/// name the frame.
#[derive(Debug, thiserror::Error)]
pub enum AnalyseError {
    #[error(transparent)]
    Footage(#[from] FootageError),
    #[error("{}: {reason}", path.display())]
    Fps { path: PathBuf, reason: String },
    #[error("{}: {error}", path.display())]
    Vision { path: PathBuf, error: VisionError },
    #[error("{}: {error}", path.display())]
    Signal { path: PathBuf, error: SignalError },
    #[error("{}: energy fit: {error}", path.display())]
    Fit { path: PathBuf, error: FitError },
    #[error("{}: {reason}", path.display())]
    Clip { path: PathBuf, reason: String },
    /// The fit window or the rest tail crosses a change of the container's frame
    /// interval (a slowed section's start or end).
    #[error(
        "{}: the {span} (t = {start_s:.4}–{end_s:.4} s from the first frame, capture clock) \
         crosses a change of the frame rate: trim the clip, or shorten `window_s` in the \
         config's [fit] table, so that it lies inside one section. Sections: {sections}",
        path.display()
    )]
    AcrossSections {
        path: PathBuf,
        /// "fit window" or "rest tail".
        span: &'static str,
        /// The span's capture times from the clip's first frame \[s\].
        start_s: f64,
        end_s: f64,
        /// The clip's sections, as [`FrameTiming::sections_text`] lists them.
        sections: String,
    },
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
    /// when no edge was found.
    pub z_rim_px: Option<f64>,
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
    /// ([`precession::precession_check`]); `None` with too few states, and in results
    /// written before it was recorded.
    #[serde(default)]
    pub precession: Option<PrecessionCheck>,
    /// n from the times of z_rim's peaks and troughs alone in the fit window ([`turn_timing::fit_turn_timing`]),
    /// or why it could not be fitted; `None` in results written before it was recorded.
    #[serde(default)]
    pub turn_timing: Option<Result<TurnTimingFit, String>>,
    /// Where t_φ was placed by the laws ([`law_halt`]); `None` when it is the last
    /// frame of motion seen (`halt = "measured"`, or the placement failed) and in
    /// results written before it was recorded.
    #[serde(default)]
    pub halt_placement: Option<HaltPlacement>,
    pub warnings: Vec<String>,
    /// Diagnostic images (PNG): the calibration frame with its points, and the
    /// frame of the highest rim thresholded with the band and the edge found.
    #[serde(skip)]
    pub diagnostics: Diagnostics,
    /// The overlay's pictures kept while the clip was read
    /// ([`analyse_clip_keeping`]), so that the overlay need not decode it again.
    #[serde(skip)]
    pub kept: Option<KeptFrames>,
}

/// PNG images for a person checking the image stage.
#[derive(Debug, Clone, Default)]
pub struct Diagnostics {
    pub calibration_png: Vec<u8>,
    pub threshold_png: Vec<u8>,
}

/// BLAKE3 of a clip's bytes: the file, or every frame file of a folder in order.
///
/// # Errors
/// The file or a frame cannot be read.
pub fn clip_hash(clip: &Path) -> Result<String, FootageError> {
    let mut hasher = blake3::Hasher::new();
    let files = if clip.is_dir() {
        footage::frame_files(clip)?
    } else {
        vec![clip.to_path_buf()]
    };
    for file in files {
        let unreadable = |e: std::io::Error| FootageError::Unreadable {
            path: file.clone(),
            reason: e.to_string(),
        };
        let mut reader = std::fs::File::open(&file).map_err(unreadable)?;
        std::io::copy(&mut reader, &mut hasher).map_err(unreadable)?;
    }
    Ok(hasher.finalize().to_hex().to_string())
}

/// An owned copy of a frame (for the few rest frames kept in pass 1).
struct OwnedFrame {
    index: usize,
    width: usize,
    height: usize,
    order: footage::ChannelOrder,
    data: Vec<u8>,
}

impl OwnedFrame {
    fn copy(index: usize, view: &FrameView) -> Self {
        let mut data = Vec::with_capacity(3 * view.width * view.height);
        for y in 0..view.height {
            data.extend_from_slice(view.row(y));
        }
        Self {
            index,
            width: view.width,
            height: view.height,
            order: view.order,
            data,
        }
    }

    fn view(&self) -> FrameView<'_> {
        FrameView {
            width: self.width,
            height: self.height,
            stride: 3 * self.width,
            order: self.order,
            data: &self.data,
        }
    }
}

/// The side view of a frame: the region of interest (or the whole frame), or its
/// top part in a two-view clip; and the plan view below the split.
fn side_view<'a>(
    frame: &FrameView<'a>,
    roi: Option<[u32; 4]>,
    split: Option<usize>,
    index: usize,
) -> Result<(FrameView<'a>, Option<FrameView<'a>>), VisionError> {
    let frame = match roi {
        Some([x, y, w, h]) => frame
            .crop(x as usize, y as usize, w as usize, h as usize)
            .ok_or(VisionError::InvalidSetting {
                name: "roi",
                value: f64::from(x + w).max(f64::from(y + h)),
                reason: "the region of interest [x, y, width, height] reaches outside the frame",
            })?,
        None => *frame,
    };
    match split {
        Some(row) => {
            let (side, plan) = vision::split_views(&frame, row, index)?;
            Ok((side, Some(plan)))
        }
        None => Ok((frame, None)),
    }
}

fn plate_name(plate: Plate) -> &'static str {
    match plate {
        Plate::Dark => "dark plate",
        Plate::Light => "light plate",
    }
}

/// How many times more sharply a later plate kind's calibration must change across
/// the disk's ends ([`vision::Calibration::end_step`]) than an earlier plausible
/// one's to be taken instead: the same points step alike (a ratio near 1), while
/// points inside the disk step by its shading alone, a small part of its contrast.
const END_STEP_RATIO: f64 = 2.0;

/// Calibrates for the plate kind that describes the rest frames. Each kind's
/// calibration is tried, a dark plate's first. A calibration is plausible when it
/// finds a disk at rest whose two scales imply a camera a side view can have
/// (perspective factor within [`PERSPECTIVE_FACTOR_RANGE`]); of the plausible ones
/// the first is taken, unless a later one's ends are edges where its ends are not:
/// its points change more than [`END_STEP_RATIO`] times as sharply across x_l and
/// x_r on the last rest frame ([`vision::Calibration::end_step`]). Where neither
/// kind's ends step that much more sharply (the two found the same disk), the
/// plate under the disk decides ([`vision::Calibration::under_rim_light`]): darker
/// there than beside the disk is a light plate's shadow, brighter a dark plate's
/// mirror image. (o03 of the open footage under gamma 0.7: both kinds found the
/// same disk, ends 49.8 and 50.4; the dark plate's reading of that light plate read
/// n +0.022 and the heights 2.5 % low.)
///
/// A dark-plate calibration of a light plate finds a sliver of the plate, an
/// unsteady blob, or (on a plate brighter than the disk's side) a run that stops
/// inside the disk where its side's shading crosses γ, with a plausible camera;
/// a light-plate calibration of a dark plate takes the reflection for part of the
/// disk. With neither plausible, the first that calibrated at all is taken (its
/// scale then falls back to the diameter, with a warning), else the dark
/// plate's error is returned.
fn calibrate_detecting_plate(
    rest: &[FrameView],
    first_index: usize,
    side_config: &SideViewConfig,
    given: Option<&CalibrationOverride>,
    disk: &DiskParams,
) -> Result<(CalibrationReport, Plate, String), VisionError> {
    let (lo, hi) = PERSPECTIVE_FACTOR_RANGE;
    let last = rest.last().ok_or(VisionError::NoFrames)?;
    let mut taken: Option<(CalibrationReport, Plate, f64)> = None;
    let mut fallback = None;
    let mut tried = Vec::new();
    let mut errors = Vec::new();
    for plate in [Plate::Dark, Plate::Light] {
        let config = SideViewConfig {
            plate,
            ..*side_config
        };
        match vision::calibrate_at_rest(rest, first_index, &config, given) {
            Ok(report) => {
                let cal = &report.calibration;
                let factor = ScaleReport::new(cal, cal.z_base, disk).perspective_factor;
                if !(lo..=hi).contains(&factor) {
                    tried.push(format!(
                        "{}: perspective factor {factor:.3}, outside {lo}–{hi}",
                        plate_name(plate)
                    ));
                    fallback.get_or_insert((report, plate));
                    continue;
                }
                let step = cal.end_step(last);
                tried.push(format!(
                    "{}: perspective factor {factor:.3}, step at the ends {step:.1}",
                    plate_name(plate)
                ));
                let take = match &taken {
                    None => true,
                    Some((first, _, first_step)) => {
                        if step > END_STEP_RATIO * first_step {
                            true
                        } else if *first_step > END_STEP_RATIO * step {
                            false
                        } else {
                            // The ends alike: what the plate shows under the disk
                            // decides, a shadow the light plate.
                            let under = first.calibration.under_rim_light(last);
                            if let Some(light) = under {
                                tried.push(format!(
                                    "under the disk {light:+.1} of 255 against the plate beside it ({})",
                                    if light < 0.0 { "a shadow" } else { "a mirror image" }
                                ));
                            }
                            under.is_some_and(|light| light < 0.0)
                        }
                    }
                };
                if take {
                    taken = Some((report, plate, step));
                }
            }
            Err(e) => {
                tried.push(format!("{}: {e}", plate_name(plate)));
                errors.push(e);
            }
        }
    }
    match taken.map(|(report, plate, _)| (report, plate)).or(fallback) {
        Some((report, plate)) => Ok((report, plate, tried.join("; "))),
        // Every kind failed to calibrate. For the same reason (a disk not yet at rest,
        // say), that reason; for different ones, each kind's.
        None => match &errors[..] {
            [first, rest @ ..]
                if rest
                    .iter()
                    .all(|e| std::mem::discriminant(e) == std::mem::discriminant(first)) =>
            {
                Err(first.clone())
            }
            _ => Err(VisionError::PlateNotRecognised {
                tried: tried.join("; "),
            }),
        },
    }
}

fn layout_name(two_view: bool) -> &'static str {
    if two_view { "two-view" } else { "side view" }
}

/// Analyse one clip with its (merged) config. `progress(done, total)` is called
/// every few hundred frames of the measuring pass.
///
/// # Errors
/// See [`AnalyseError`]: unreadable or truncated footage, no usable fps, no disk in
/// view, a calibration frame not at rest, too few peaks, a failed energy fit.
pub fn analyse_clip(
    clip: &Path,
    config: &ExperimentConfig,
    progress: &dyn Fn(usize, Option<usize>),
) -> Result<Experiment, AnalyseError> {
    analyse_clip_decoding(clip, config, Decoding::NearTheEnd, progress)
}

/// [`analyse_clip`], decoding the whole clip or a span at its end (`decoding`).
///
/// # Errors
/// As [`analyse_clip`].
pub fn analyse_clip_decoding(
    clip: &Path,
    config: &ExperimentConfig,
    decoding: Decoding,
    progress: &dyn Fn(usize, Option<usize>),
) -> Result<Experiment, AnalyseError> {
    analyse_clip_keeping(clip, config, decoding, None, progress)
}

/// [`analyse_clip_decoding`], keeping the pictures that the measurement overlay
/// `overlay` will show while the frames are read ([`Experiment::kept`]), so that
/// [`crate::overlay::write_measurement_overlays`] need not decode them again.
///
/// # Errors
/// As [`analyse_clip`].
pub fn analyse_clip_keeping(
    clip: &Path,
    config: &ExperimentConfig,
    decoding: Decoding,
    overlay: Option<&OverlaySpec>,
    progress: &dyn Fn(usize, Option<usize>),
) -> Result<Experiment, AnalyseError> {
    let vision_err = |error| AnalyseError::Vision {
        path: clip.to_path_buf(),
        error,
    };
    // One source serves both passes: the rest frames at the end, then every
    // frame from the start.
    let mut source = FrameSource::open(clip)?;
    let fps = footage::resolve_capture_fps(
        config.fps,
        footage::container_capture_rate(clip),
        source.container_fps(),
    )
    .map_err(|reason| AnalyseError::Fps {
        path: clip.to_path_buf(),
        reason,
    })?;
    let params = config.disk_params();
    let vision_config = config.vision.clone().unwrap_or_default();
    let roi = vision_config.roi;

    // Pass 1: the rest frames at the end.
    let expected = match source.expected_frames() {
        Some(n) => n,
        None => {
            // No frame count stored: count by reading once.
            let mut n = 0;
            while source.next_frame()?.is_some() {
                n += 1;
            }
            n
        }
    };
    if expected < REST_FRAMES + 3 {
        return Err(AnalyseError::Clip {
            path: clip.to_path_buf(),
            reason: format!("only {expected} frames: too short to analyse"),
        });
    }
    // The container's index (packet timestamps, read without decoding): the rest
    // frames and a span near the end are sought by their listed times, which land
    // on the frame asked for in a variable-rate clip, where index / average fps
    // would not.
    let index = source.stream_index()?;
    match &index {
        Some(index) if index.container_times_s.len() == expected => {
            source.seek_frame(expected - REST_FRAMES, index)?
        }
        _ => source.seek(expected - REST_FRAMES)?,
    }
    let mut rest = Vec::new();
    while let Some(frame) = source.next_frame()? {
        rest.push(OwnedFrame::copy(frame.index, &frame.view));
    }
    if rest.len() < 2 {
        return Err(AnalyseError::Clip {
            path: clip.to_path_buf(),
            reason: "cannot read the last frames (needed for the rest-frame calibration)".into(),
        });
    }
    let last = &rest[rest.len() - 1];
    let last_view = side_view(&last.view(), roi, None, last.index)
        .map_err(vision_err)?
        .0;
    let (two_view, layout) = match config.two_view {
        Some(two_view) => (
            two_view,
            format!("{} (config `two_view`)", layout_name(two_view)),
        ),
        None => {
            let detected = vision::detect_two_view(&last_view, last.index);
            (
                detected.two_view,
                format!(
                    "{} (detected: {})",
                    layout_name(detected.two_view),
                    detected.evidence
                ),
            )
        }
    };
    let split_row = if two_view {
        Some(match vision_config.split_row {
            Some(row) => (row as usize, true),
            None => (
                vision::find_split_row(&last_view, last.index).map_err(vision_err)?,
                false,
            ),
        })
    } else {
        None
    };
    let split = split_row.map(|(row, _)| row);
    let mut side_config = SideViewConfig {
        gamma: vision_config.gamma,
        half_width_px: vision_config
            .band_half_width_px
            .map_or(SideViewConfig::default().half_width_px, |w| w as usize),
        plate: config.plate.unwrap_or_default(),
        ..SideViewConfig::default()
    };
    let given = config.calibration.map(|c| CalibrationOverride {
        x_l: Some(c.x_l),
        x_r: Some(c.x_r),
        z_t: Some(c.z_t),
        z_base: Some(c.z_base),
    });
    let mut rest_sides = Vec::new();
    for frame in &rest {
        rest_sides.push(
            side_view(&frame.view(), roi, split, frame.index)
                .map_err(vision_err)?
                .0,
        );
    }
    let (calibration, plate) = match config.plate {
        Some(plate) => (
            vision::calibrate_at_rest(&rest_sides, rest[0].index, &side_config, given.as_ref())
                .map_err(vision_err)?,
            format!("{} (config `plate`)", plate_name(plate)),
        ),
        None => {
            let (report, kind, evidence) = calibrate_detecting_plate(
                &rest_sides,
                rest[0].index,
                &side_config,
                given.as_ref(),
                &params,
            )
            .map_err(vision_err)?;
            side_config.plate = kind;
            (
                report,
                format!("{} (detected: {evidence})", plate_name(kind)),
            )
        }
    };
    // A band named in the config must fit on the disk; otherwise the band grows with
    // the disk (config::band_for_disk) and the rest frames are calibrated again on it.
    let disk_width = calibration.calibration.x_r - calibration.calibration.x_l;
    let calibration = match vision_config.band_half_width_px {
        Some(band) => {
            crate::config::band_fits_disk(band, disk_width).map_err(|reason| {
                AnalyseError::Clip {
                    path: clip.to_path_buf(),
                    reason,
                }
            })?;
            calibration
        }
        None => {
            let band = crate::config::band_for_disk(disk_width, side_config.half_width_px);
            if band == side_config.half_width_px {
                calibration
            } else {
                side_config.half_width_px = band;
                vision::calibrate_at_rest(&rest_sides, rest[0].index, &side_config, given.as_ref())
                    .map_err(vision_err)?
            }
        }
    };
    let cal = calibration.calibration;
    // The top face's far rim at rest, for the camera's elevation (ScaleReport).
    let silhouette_top = rest_sides
        .last()
        .and_then(|side| vision::silhouette_top(side, &cal));
    let side0 = &rest_sides[0];
    let gauge = RimGauge::new(
        &calibration.calibration,
        &calibration.threshold,
        &side_config,
        side0.width,
        side0.height,
    )
    .map_err(vision_err)?;
    // The profile across the disk's top on the centre line, read in every frame for
    // the near top rim of the frames that lean towards the camera
    // (vision::near_top_rim_leaning).
    let lean_gauge =
        vision::LeanGauge::new(&cal, silhouette_top, gauge.band_columns(), side0.height);
    // Dark plate: rim heights below 2 px from the darkness of the gap (vision::gap),
    // then, on either plate, every height re-measured with a model of the rim's
    // edge learned from the clip (vision::mirror_edge on a dark plate,
    // vision::shadow_edge on a light one), whose zero is the rest frames' band rows
    // about their edge: pass 1's five here, the whole rest tail's after pass 2
    // (`tail_rest_window` on a dark plate, `tail_median_shift` on a light one).
    let gap_gauge = match side_config.plate {
        Plate::Dark => GapGauge::new(&calibration.calibration, &side_config, &rest_sides)
            .map_err(vision_err)?,
        Plate::Light => None,
    };
    let rest_window = {
        let edge0 = match gauge.measure(&rest_sides[0], rest[0].index) {
            Ok(RimHeight::Edge { edge_row, .. }) => edge_row,
            _ => cal.z_base,
        };
        let columns = gauge.band_columns();
        let windows: Option<Vec<BandWindow>> = rest_sides
            .iter()
            .map(|f| BandWindow::read(f, &columns, edge0))
            .collect();
        windows
            .and_then(|w| BandWindow::mean(&w))
            .map(|w| (w, edge0))
    };
    let colour_thresholds = match split {
        Some(row) => {
            let (_, plan) = vision::split_views(&last_view, row, last.index).map_err(vision_err)?;
            let thresholds =
                vision::auto_colour_thresholds(&plan, last.index).map_err(vision_err)?;
            Some((thresholds, ThresholdSource::Automatic))
        }
        None => None,
    };
    let (width, height) = (last.width, last.height);
    // The rest frame's side view, kept for the calibration diagnostic, which shows
    // the z_t used (the leaning frames' when read).
    let rest_side = OwnedFrame::copy(last.index, &rest_sides[rest_sides.len() - 1]);
    drop(rest_sides);
    drop(rest);

    // Which frames pass 2 decodes: the whole clip, or a span at its end found
    // from the container's index (see `SpanPlan`).
    let window_s = config.window_s();
    let plan_span = SpanPlan::new(index, decoding, expected, &fps);

    // Pass 2: the span's frames, streamed. A side view reads only the band of
    // columns about the centre line, so only that band is converted to colour.
    // Measures the frames from `first` to the end: rim heights, strip angles,
    // frame times and the signal analysis.
    let mut measure_span = |first: usize| -> Result<MeasuredSpan, AnalyseError> {
        let mut warnings = Vec::new();
        let mut fps = fps.clone();
        match &plan_span.index {
            Some(index) if first > 0 => source.seek_frame(first, index)?,
            _ => source.seek(0)?,
        }
        if split.is_none() {
            let x = roi.map_or(0, |r| r[0] as usize);
            let mut band = gauge.band_columns();
            if let Some(gap) = &gap_gauge {
                let columns = gap.band_columns();
                band = band.start.min(columns.start)..band.end.max(columns.end);
            }
            source.convert_only_columns(Some(x + band.start..x + band.end))?;
        }
        let mut strip_finder = colour_thresholds
            .as_ref()
            .map(|(t, s)| StripFinder::new(*t, *s));
        let mut keeper = overlay.and_then(|spec| {
            let geometry = LayoutGeometry {
                calibration: cal,
                origin: roi.map_or((0, 0), |[x, y, _, _]| (x as usize, y as usize)),
                view: roi.map_or((width, height), |r| (r[2] as usize, r[3] as usize)),
                split_row: split,
                band_half_width_px: side_config.half_width_px,
                zero_row: cal.z_base,
            };
            FrameKeeper::new(&geometry, spec, fps.fps, &source)
        });
        let span_frames = expected - first;
        let mut frames = Vec::with_capacity(span_frames);
        let mut gaps = Vec::with_capacity(if gap_gauge.is_some() { span_frames } else { 0 });
        let mut profiles = Vec::with_capacity(if lean_gauge.is_some() { span_frames } else { 0 });
        let mut windows = Vec::with_capacity(if rest_window.is_some() {
            span_frames
        } else {
            0
        });
        let band_columns = gauge.band_columns();
        let mut repeats = footage::RepeatGauge::new();
        let mut no_edge = 0usize;
        // The frame with the highest rim so far, kept for the threshold diagnostic.
        let mut highest: Option<(f64, f64, OwnedFrame)> = None;
        while let Some(frame) = source.next_frame()? {
            let index = frame.index;
            if first > 0 {
                plan_span.check_frame(clip, index, frame.container_time_s)?;
            }
            let (side, plan) = side_view(&frame.view, roi, split, index).map_err(vision_err)?;
            let mut new_highest = None;
            let rim = gauge.measure(&side, index).map_err(vision_err)?;
            if rest_window.is_some() {
                let edge0 = match rim {
                    RimHeight::Edge { edge_row, .. } => Some(edge_row),
                    RimHeight::Contact => Some(cal.z_base),
                    RimHeight::NoEdge => None,
                };
                windows.push(edge0.and_then(|e| BandWindow::read(&side, &band_columns, e)));
            }
            let z_rim_px = match rim {
                RimHeight::Edge { z_rim_px, edge_row } => {
                    if highest.as_ref().is_none_or(|(z, _, _)| z_rim_px > *z) {
                        new_highest = Some((z_rim_px, edge_row));
                    }
                    Some(z_rim_px)
                }
                RimHeight::Contact => Some(0.0),
                RimHeight::NoEdge => {
                    no_edge += 1;
                    None
                }
            };
            if let Some(gauge) = &gap_gauge {
                gaps.push(gauge.measure(&side));
            }
            if let Some(gauge) = &lean_gauge {
                profiles.push(gauge.read(&side));
            }
            let strip = match (&mut strip_finder, plan) {
                (Some(finder), Some(plan)) => finder.measure(&plan, index).ok(),
                _ => None,
            };
            let beta_raw = strip.map(|s| s.beta);
            frames.push(FrameRecord {
                index,
                // Set from the container's timestamps once every frame is read.
                t_capture: f64::NAN,
                t: f64::NAN,
                container_time_s: frame.container_time_s,
                picture_type: frame.picture_type,
                z_rim_px,
                z_rim_m: None,
                beta_raw,
            });
            if index % 256 == 0 {
                progress(index - first, Some(span_frames));
            }
            repeats.push(source.brightness_samples(REPEAT_SAMPLE_STEP)?);
            if let Some(keeper) = &mut keeper {
                // The strip as measured, with its mask for the outline (made
                // only for the frames kept).
                let mark = || {
                    let finder = strip_finder.as_mut()?;
                    Some(crate::overlay::StripMark {
                        strip: strip?,
                        mask: finder.strip_mask(),
                    })
                };
                keeper.offer(frames.len() - 1, z_rim_px, &mut source, mark)?;
            }
            if let Some((z_rim_px, edge_row)) = new_highest {
                // The diagnostic shows the whole side view: convert the other columns.
                let whole = source.whole_frame()?;
                let side = side_view(&whole, roi, split, index).map_err(vision_err)?.0;
                highest = Some((z_rim_px, edge_row, OwnedFrame::copy(index, &side)));
            }
        }
        progress(frames.len(), Some(span_frames));
        if let Some(gauge) = &gap_gauge {
            let mut heights: Vec<Option<f64>> = frames.iter().map(|f| f.z_rim_px).collect();
            if gauge.resolve(&mut heights, &gaps).is_none() {
                warnings.push(
                "the rim never lifts 2.5–4.5 px, so the darkness of the gap per pixel is unknown: \
                 rim heights below 2 px come from the edge alone and read up to 0.2 px high"
                    .into(),
            );
            }
            for (record, z) in frames.iter_mut().zip(heights) {
                record.z_rim_px = z;
            }
        }
        let first_pass = match side_config.plate {
            Plate::Dark => "edge and gap darkness (vision::rim, vision::gap)",
            Plate::Light => "edge (vision::rim): the second edge from the bottom on a light plate",
        };
        let mut rim_zero_row_px = cal.z_base;
        // z_b of eq. 3.10: the plate line where the mirror-edge model finds the rim
        // meets its mirror image (ScaleReport), else z_base.
        let mut bottom_rim_row = cal.z_base;
        let mut reading = RimReading::FirstPass;
        let tail = rest_tail_frames(fps.fps);
        let rest_window = rest_window
            .as_ref()
            .map(|(pass1, edge0)| match side_config.plate {
                Plate::Dark => (tail_rest_window(&windows, pass1, tail), *edge0),
                Plate::Light => (pass1.clone(), *edge0),
            });
        let mut rim = match &rest_window {
            Some((rest_window, edge0)) => {
                let mut heights: Vec<Option<f64>> = frames.iter().map(|f| f.z_rim_px).collect();
                let refit = match side_config.plate {
                Plate::Dark => vision::remeasure_dark_rim(
                    &mut heights,
                    &windows,
                    cal.z_base,
                    rest_window,
                    *edge0,
                )
                .map(|model| {
                    let kind = if model.is_sharp() {
                        "a sharp rim (the plate line from the test)"
                    } else {
                        "a rounded rim (the plate line from the rest frames)"
                    };
                    let test = match model.near_contact_frames {
                        0 => "too few frames near contact: the rest frames alone put the plate \
                              line"
                            .to_string(),
                        frames => format!(
                            "the rest frames and {frames} frames near contact put the plate line"
                        ),
                    };
                    let description = format!(
                        "mirror-edge model (vision::mirror_edge): the rim's profile learned from \
                         the frames with an open gap; edge at rest {:.2} px, the zero of z_rim; \
                         plate line {:.2} px, where the rim meets its mirror image (z_b of eq. \
                         3.10's scale), reflectivity {:.2}, the reflection blurred by σ {:.2} \
                         px; rest fit RMS {:.1} % of the disk's level; {kind}: {test} {:+.2} px \
                         below the edge (sharp under {sharp} px)",
                        model.rest_edge,
                        model.plate_row,
                        model.reflectivity,
                        model.mirror_blur_px(),
                        100.0 * model.rest_rms,
                        model.plate_offset_test,
                        sharp = vision::SHARP_RIM_PX,
                    );
                    let reading = if model.is_sharp() {
                        RimReading::SharpMirrorEdge
                    } else {
                        RimReading::RoundedMirrorEdge
                    };
                    (description, model.rest_edge, Some(model.plate_row), reading)
                }),
                Plate::Light => {
                    vision::remeasure_light_rim(&mut heights, &windows, cal.z_base, rest_window)
                        .map(|model| {
                            let description = format!(
                                "shadow-edge contour (vision::shadow_edge): the edge where the \
                                 band falls to {:.3} of the disk's side, halfway to the shadow \
                                 under the lifted rim ({:.3}), placed by the pixel means of a \
                                 step blurred by σ = {:.2} px; edge at rest {:.2} px, the zero \
                                 of z_rim; {} frame(s) kept the first pass",
                                model.edge_level(),
                                model.shadow_ratio,
                                model.blur_px,
                                model.rest_edge,
                                model.kept_first_pass
                            );
                            (description, model.rest_edge, None, RimReading::ShadowEdge)
                        })
                        .map_err(String::from)
                }
            };
                match refit {
                    Ok((mut description, mut rest_edge, plate_row, how)) => {
                        if side_config.plate == Plate::Light {
                            let shift = tail_median_shift(&mut heights, tail);
                            rest_edge -= shift;
                            description += &format!(
                                "; the rest tail's median reading ({shift:+.3} px) moves the \
                                 zero to {rest_edge:.2} px"
                            );
                        }
                        for (record, z) in frames.iter_mut().zip(heights) {
                            record.z_rim_px = z;
                        }
                        rim_zero_row_px = rest_edge;
                        bottom_rim_row = plate_row.unwrap_or(bottom_rim_row);
                        reading = how;
                        description
                    }
                    Err(reason) => format!("{first_pass}: {reason}"),
                }
            }
            None => first_pass.into(),
        };
        // Duplicated and interpolated frames show no capture of their own: no rim
        // height or strip angle from them reaches the fits. Their readings are set
        // aside until the halt is known (below).
        let repeated = repeats.repeated(REST_FRAMES);
        drop(repeats);
        let set_aside: Vec<(Option<f64>, Option<f64>)> = repeated
            .iter()
            .map(|r| {
                let record = &mut frames[r.index];
                (record.z_rim_px.take(), record.beta_raw.take())
            })
            .collect();
        // The near top rim from the frames that lean towards the camera, unless the
        // config gives z_t (TopRimLeaning).
        let top_rim_leaning = lean_gauge
            .as_ref()
            .filter(|_| given.is_none_or(|g| g.z_t.is_none()))
            .and_then(|gauge| {
                let heights: Vec<Option<f64>> = frames.iter().map(|f| f.z_rim_px).collect();
                let kinds: Vec<Option<char>> = frames.iter().map(|f| f.picture_type).collect();
                vision::near_top_rim_leaning(gauge, &profiles, &heights, &kinds)
            })
            .map(|reading| TopRimLeaning {
                reading,
                rest_z_t: cal.z_t,
            });
        drop(profiles);
        let mut cal = cal;
        if let Some(leaning) = &top_rim_leaning {
            cal.z_t = leaning.reading.z_t;
        }
        // No face 1.5 px above the rest frames' z_t (vision::silhouette_top): their
        // z_t is then the silhouette's top, the far top rim, unless below the
        // leaning frames' near rim.
        let silhouette_top =
            silhouette_top.or_else(|| top_rim_leaning.map(|l| l.rest_z_t.min(l.reading.z_t)));
        // Scale at the near rim (eq. 3.10), checked against the diameter's (ScaleReport);
        // z_rim in metres once, after every correction of z_rim in px.
        // The principal point: the centre of the frame's side view (above the split
        // in a two-view clip), in the side view's rows.
        let roi_top = roi.map_or(0.0, |r| f64::from(r[1]));
        let side_rows = split.map_or(height as f64, |s| roi_top + s as f64);
        let scale = ScaleReport::new(&cal, bottom_rim_row, &params)
            .with_camera_distance(config.camera_distance_m)
            .with_near_rim_elevation(&cal, silhouette_top, &params)
            .with_local_scale_at_near_rim(0.5 * side_rows - roi_top, &params);
        let metres_per_px = scale.metres_per_px();
        if !scale.at_near_rim() {
            warnings.push(format!("scale from the {}", scale.used));
        }
        for record in &mut frames {
            record.z_rim_m = record.z_rim_px.map(|z| z * metres_per_px);
        }
        if no_edge == frames.len() {
            return Err(AnalyseError::Clip {
                path: clip.to_path_buf(),
                reason: format!(
                    "no rim edge found on the centre line in any of the {} frames (γ = {:.1})",
                    frames.len(),
                    calibration.threshold.gamma
                ),
            });
        }
        if no_edge > 0 {
            warnings.push(format!(
                "no rim edge found in {no_edge} of {} frames",
                frames.len()
            ));
        }

        // Frame times: the container's timestamps on the capture clock, else index /
        // fps; a span's from the timestamps of the whole clip (its index), so that
        // they count from the clip's first frame.
        let (t, frame_times) = match &plan_span.index {
            Some(index) if first > 0 => {
                let stamps: Vec<Option<f64>> =
                    index.container_times_s.iter().copied().map(Some).collect();
                let (mut t, timing) = footage::frame_times(&stamps, &mut fps);
                (t.split_off(first), timing)
            }
            _ => {
                let stamps: Vec<Option<f64>> = frames.iter().map(|f| f.container_time_s).collect();
                footage::frame_times(&stamps, &mut fps)
            }
        };
        for (record, &t) in frames.iter_mut().zip(&t) {
            record.t_capture = t;
        }
        warnings.splice(0..0, fps.warnings.iter().cloned());

        // Signal.
        let signal_config = signal_config(window_s, metres_per_px);
        let repeated = repeats_in_motion(
            &mut frames,
            repeated,
            set_aside,
            &signal_config,
            metres_per_px,
        );
        if !repeated.is_empty() {
            let count = |kind| repeated.iter().filter(|r| r.kind == kind).count();
            let list: Vec<String> = repeated
                .iter()
                .map(|r| frames[r.index].index.to_string())
                .collect();
            warnings.push(format!(
                "{} duplicated and {} interpolated frame(s) (frames {}) show no capture of \
             their own: left out of the fits",
                count(footage::RepeatKind::Duplicated),
                count(footage::RepeatKind::Interpolated),
                list.join(", ")
            ));
        }
        let profile = motion_profile(config.rim_zero(), &scale, &params);
        if config.rim_zero() == RimZeroChoice::Motion && profile.is_none() {
            warnings.push(
                "the camera's elevation is not known (the silhouette's top was not found above \
                 the top face): the zero of z_rim stays the still disk's edge"
                    .into(),
            );
        }
        let hidden = hidden_drops(
            &mut frames,
            &repeated,
            two_view,
            &signal_config,
            rim_model(&scale, &params).as_ref(),
            1.0 / fps.fps,
        );
        if !hidden.is_empty() {
            let at: Vec<String> = hidden
                .iter()
                .map(|f| {
                    format!(
                        "{} (t = {:.4} s)",
                        frames[f.index].index, frames[f.index].t_capture
                    )
                })
                .collect();
            warnings.push(format!(
                "the rim's phase steps by a frame's turn at frame(s) {} where the timestamps \
                 show no gap: a frame missing from the clip before each, so the capture times \
                 from there on are counted one frame later (signal::missing_frames)",
                at.join(", ")
            ));
        }
        let known_flags = known_flags(&repeated, hidden);
        let (series, zero) = signal_series(
            &mut frames,
            &known_flags,
            two_view,
            &signal_config,
            rim_model(&scale, &params).as_ref(),
            profile.as_ref(),
            metres_per_px,
        )
        .map_err(|error| signal_error(clip, &fps, error))?;
        if let Some(zero) = &zero {
            let shift_px = zero.shift_m / metres_per_px;
            rim_zero_row_px -= shift_px;
            rim += &format!(
                "; the motion places the zero of z_rim {:.3} ± {:.3} px {} the still disk's \
                 edge, at row {rim_zero_row_px:.2} px (signal::motion_zero, {} heights between {} \
                 turning points, the profile at ε = {:.2}°)",
                shift_px.abs(),
                zero.zero.se / metres_per_px,
                if shift_px >= 0.0 { "above" } else { "below" },
                zero.zero.points,
                zero.zero.turning_points,
                scale.near_rim_elevation_rad.unwrap_or(0.0).to_degrees()
            );
        }
        Ok(MeasuredSpan {
            frames,
            series,
            fps,
            frame_times,
            warnings,
            highest,
            rim,
            rim_zero_row_px,
            reading,
            zero,
            scale,
            metres_per_px,
            local_fit_periods: signal_config.state_window_periods,
            rest_tail_s: signal_config.rest_tail_s,
            kept: keeper.and_then(FrameKeeper::finish),
            known_flags,
            top_rim_leaning,
        })
    };
    let mut first = plan_span.first_span();
    let mut attempts = 1;
    let measured = loop {
        let result = measure_span(first);
        let earlier = match &result {
            Ok(m) => plan_span.earlier_start(first, Some(m), window_s),
            Err(AnalyseError::Signal { .. } | AnalyseError::Clip { .. }) => {
                plan_span.earlier_start(first, None, window_s)
            }
            Err(_) => None,
        };
        match earlier {
            Some(earlier) => {
                first = earlier;
                attempts += 1;
            }
            None => break result?,
        }
    };
    let MeasuredSpan {
        frames,
        series,
        fps,
        frame_times,
        mut warnings,
        highest,
        rim,
        mut rim_zero_row_px,
        reading,
        mut zero,
        scale,
        metres_per_px,
        rest_tail_s,
        kept,
        mut known_flags,
        top_rim_leaning,
        ..
    } = measured;
    let decoded = plan_span.decoded(first, attempts, frames.len());
    let halt_choice = config.fit.as_ref().and_then(|f| f.halt).unwrap_or_default();
    let profile = motion_profile(config.rim_zero(), &scale, &params);
    // The rest level's height above the zero the motion placed (−c): the detector's
    // rises are above the rest, the energies' heights above the zero.
    let rest_above_zero_m = zero.map_or(0.0, |z| -z.zero.offset);
    // `bounded`: t_φ was bounded by a law of the motion ([`law_bound`]), which leaves the
    // halt seen no measurement of t0.
    // `turns`: the turns' timing law of `series`, whose end T checks the halt seen.
    let halt_for =
        |series: &StateSeries, bounded: bool, turns: Option<&TurnTimingFit>| match halt_choice {
            HaltChoice::Measured => HaltTime::Fixed(series.halt.last_motion_seen()),
            HaltChoice::Free => HaltTime::Free,
            HaltChoice::Combined if bounded => HaltTime::Free,
            // The sighting is checked against the turns' end T of the same series.
            HaltChoice::Combined => HaltTime::Sighted(HaltSighting {
                turns_end: turns
                    .filter(|f| f.t_end.is_finite() && f.se_t_end.is_finite())
                    .map(|f| TurnsEnd {
                        t_end: f.t_end,
                        se: f.se_t_end,
                    }),
                ..halt_sighting(&params, &series.halt, rest_above_zero_m, 1.0 / fps.fps)
            }),
        };
    // The fit window and the rest tail must each lie in one section of constant
    // frame interval (footage::timing): a slowed section's boundary inside them
    // is known only to within a few frames. Then the energy's fits.
    let clip_end = frames.last().map_or(0.0, |f| f.t_capture);
    let fit_span = |series: &StateSeries, bounded: bool| -> Result<Fits, AnalyseError> {
        let (start, end) = series.peaks.window;
        let t_phi = series.halt.t_phi;
        for (span, start_s, end_s) in [
            ("fit window", t_phi + start, t_phi + end),
            ("rest tail", clip_end - rest_tail_s, clip_end),
        ] {
            if !frame_times.within_one_section(start_s, end_s) {
                return Err(AnalyseError::AcrossSections {
                    path: clip.to_path_buf(),
                    span,
                    start_s,
                    end_s,
                    sections: frame_times.sections_text(),
                });
            }
        }
        let timing = turn_timing_fit(&series.peaks);
        let halt = halt_for(series, bounded, timing.as_ref().ok());
        let peak_samples = peak_energies(&params, series);
        let peaks =
            fit_series("eq. 3.8 at peaks", peak_samples, window_s, halt, &[]).map_err(|error| {
                AnalyseError::Fit {
                    path: clip.to_path_buf(),
                    error,
                }
            })?;
        // Each state is a local fit over frames shared with its neighbours, and a
        // turn's frames share its errors: the fits' intervals are estimated over the
        // frames and over the turns the peaks separate, the wider kept.
        let turns: Vec<f64> = series.peaks.peaks.iter().map(|p| p.t).collect();
        let frame_samples = frame_energies(&params, series, None);
        let frames = fit_series("eq. 3.8 per frame", frame_samples, window_s, halt, &turns).ok();
        let full_state = series.strip.as_ref().and_then(|strip| {
            let samples = frame_energies(&params, series, Some(strip));
            fit_series(
                "eq. 3.6 per frame, θ̇ = β̇ − ψ̇ (eq. 3.22)",
                samples,
                window_s,
                halt,
                &turns,
            )
            .ok()
        });
        Ok(Fits {
            peaks,
            frames,
            full_state,
            turns: timing,
        })
    };
    let (mut frames, mut series) = (frames, series);
    let mut fits = fit_span(&series, false)?;
    // The signal stage again on the frames measured, with `config`: its series and
    // fits, and its frames, whose heights it re-zeroes (the zero's fit moves within
    // its standard error as its window does; the zero row follows it).
    let signal_again = |frames: &[FrameRecord],
                        known_flags: &[signal::FrameFlag],
                        config: &SignalConfig,
                        bounded: bool| {
        let mut frames = frames.to_vec();
        let (series, zero) = signal_series(
            &mut frames,
            known_flags,
            two_view,
            config,
            rim_model(&scale, &params).as_ref(),
            profile.as_ref(),
            metres_per_px,
        )
        .ok()?;
        let fits = fit_span(&series, bounded).ok()?;
        Some((frames, series, zero, fits))
    };
    let mut zero_moved = |again: Option<ZeroFromMotion>| {
        if let Some(again) = again {
            rim_zero_row_px -= again.shift_m / metres_per_px;
            zero = Some(match zero {
                Some(z) => ZeroFromMotion {
                    shift_m: z.shift_m + again.shift_m,
                    ..again
                },
                None => again,
            });
        }
    };
    // The signal stage's config for the passes after the first: each keeps what the
    // one before it set.
    let mut config_again = signal_config(window_s, metres_per_px);
    // A halt seen well after a law of the motion's is a coded picture, not motion: the
    // rim is looked for again up to the law's halt ([`law_bound`]), and t0 is then the
    // fits' own.
    let mut bounded = false;
    if let Some(bound) = law_bound(&fits, fits.turns.as_ref().ok(), 1.0 / fps.fps) {
        let mut config = config_again.clone();
        config.motion_until = Some(series.halt.t_phi + bound.bound);
        if let Some((frames_again, again, zero_again, fits_again)) =
            signal_again(&frames, &known_flags, &config, true)
            && again.halt.index < series.halt.index
        {
            warnings.push(format!(
                "the rim seemed to move until t = {:.4} s, {:.1} ± {:.1} ms after the halt of \
                 {}: a rise after t = {:.4} s (that halt + 3σ + one frame) is taken for a \
                 coded picture, not motion, so the last motion seen moves {} frame(s) \
                 earlier, to t = {:.4} s, and t0 is fitted free of the halt seen",
                series.halt.t_phi,
                -1e3 * bound.halt,
                1e3 * bound.se,
                bound.law,
                series.halt.t_phi + bound.bound,
                series.halt.index - again.halt.index,
                again.halt.t_phi,
            ));
            (frames, series, fits, bounded) = (frames_again, again, fits_again, true);
            zero_moved(zero_again);
            config_again = config;
            // The drops counted on the first pass's halt, checked against this one;
            // kept only if the signal stage and the fits run on the clock without them.
            let (mut frames_fixed, mut flags_fixed) = (frames.clone(), known_flags.clone());
            let period = 1.0 / fps.fps;
            let withdrawn = withdraw_hidden_drops(
                &mut frames_fixed,
                &mut flags_fixed,
                &series.halt.shifted_t,
                period,
            );
            if !withdrawn.is_empty() {
                // The law's halt on the clock without them: they all lie before it.
                let mut config = config_again.clone();
                config.motion_until = config
                    .motion_until
                    .map(|t| t - withdrawn.len() as f64 * period);
                if let Some((frames_again, again, zero_again, fits_again)) =
                    signal_again(&frames_fixed, &flags_fixed, &config, true)
                {
                    let at: Vec<String> = withdrawn
                        .iter()
                        .map(|&i| frames[i].index.to_string())
                        .collect();
                    warnings.push(format!(
                        "the rim's phase step at frame(s) {} lies within its test's reach of \
                         the halt the law places: the still pictures' step, not a frame \
                         missing, so the capture times after it are no longer counted a frame \
                         later (signal::missing_frames)",
                        at.join(", ")
                    ));
                    (frames, series, fits) = (frames_again, again, fits_again);
                    zero_moved(zero_again);
                    (known_flags, config_again) = (flags_fixed, config);
                }
            }
        }
    }
    // t_φ where the motion's laws place the halt ([`law_halt`]), not where the last
    // rise was seen: the same frames, peaks and fits on a clock that starts there.
    let mut halt_placement = None;
    if halt_choice != HaltChoice::Measured
        && let Some((offset, placement)) =
            law_halt(&fits.peaks.fit, fits.turns.as_ref().ok(), &series.halt)
    {
        config_again.halt_at = Some(series.halt.t_phi + offset);
        match signal_again(&frames, &known_flags, &config_again, bounded) {
            Some((frames_again, again, zero_again, fits_again)) => {
                (frames, series, fits) = (frames_again, again, fits_again);
                zero_moved(zero_again);
                halt_placement = Some(placement.shifted(offset));
            }
            None => warnings.push(format!(
                "the laws place the halt {:+.1} ms from the last motion seen, but the signal \
                 stage or the fits failed on that clock: t_φ is the last motion seen",
                1e3 * offset
            )),
        }
    }
    let Fits {
        peaks: peaks_fit,
        frames: frames_fit,
        full_state: full_state_fit,
        turns: turn_timing,
    } = fits;
    if let Some(seen) = peaks_fit
        .fit
        .halt_sighting
        .filter(|s| s.disagrees_with_turns)
        && let Some(turns) = seen.turns_end
    {
        warnings.push(format!(
            "the halt seen puts t0 at {:+.1} ± {:.1} ms, the turns' end at {:+.1} ± {:.1} ms: \
             more than 3σ apart, as when the encoder holds the last pictures; t0 is the \
             energies' alone",
            1e3 * seen.t0_seen,
            1e3 * seen.se_t0_seen,
            1e3 * turns.t_end,
            1e3 * turns.se
        ));
    }
    let halt = halt_for(&series, bounded, turn_timing.as_ref().ok());
    let window = series.peaks.window;
    let in_window = signal::flags_within(&series.flags, window.0, window.1);
    let skips_in_window = in_window.len();
    if skips_in_window > 0 {
        let gaps: Vec<String> = in_window
            .iter()
            .filter_map(|f| match f.reason {
                signal::SkipReason::TimestampGap { missing_frames, .. } => Some(format!(
                    "{missing_frames} frame(s) missing before t = {:.4} s",
                    f.t
                )),
                _ => None,
            })
            .collect();
        let gaps = if gaps.is_empty() {
            String::new()
        } else {
            format!(" (timestamp gaps: {})", gaps.join("; "))
        };
        warnings.push(format!(
            "{skips_in_window} flagged frame(s) (skips, jumps or repeated frames) inside the fit window{gaps}"
        ));
    }

    // The zero of z_rim (placed by the motion, or the edge at rest) is shared by every
    // height, so an error in it moves n without a trace in the residuals: each fit is
    // made again with the zero moved down and up by its uncertainty, and half the
    // change of n enters n's interval.
    let zero_px = config
        .rim_zero_uncertainty_px()
        .unwrap_or_else(|| match &zero {
            Some(z) => RimReading::motion_zero_uncertainty_px(z.zero.se / metres_per_px),
            None => reading.zero_uncertainty_px(),
        });
    let model = rim_model(&scale, &params);
    let (t, z) = rim_series(&frames);
    let moved = [-1.0, 1.0].map(|sign| {
        signal::with_zero_moved(
            &t,
            &z,
            &series,
            sign * zero_px * metres_per_px,
            model.as_ref(),
            &signal_config(window_s, metres_per_px),
        )
        .ok()
    });
    let peaks_fit = with_zero_error(
        peaks_fit,
        &moved,
        |s| peak_energies(&params, s),
        window_s,
        halt,
    );
    let frames_fit = frames_fit.map(|f| {
        with_zero_error(
            f,
            &moved,
            |s| frame_energies(&params, s, None),
            window_s,
            halt,
        )
    });
    let full_state_fit = full_state_fit.map(|f| {
        with_zero_error(
            f,
            &moved,
            |s| frame_energies(&params, s, s.strip.as_ref()),
            window_s,
            halt,
        )
    });

    // A state far from stationary rolling is left out of the per-frame fits
    // (frame_energies).
    let unsteady: Vec<String> = (series.states.iter())
        .filter(|s| s.is_determined() && !near_stationary_rolling(&params, s))
        .map(|s| format!("{:.4}", s.t))
        .collect();
    if !unsteady.is_empty() {
        warnings.push(format!(
            "{} per-frame state(s) left out of the per-frame fits: their precession rate lies \
             more than {STATIONARY_RATE_FACTOR} times from stationary rolling's at their φ \
             (eq. 4.40), which eq. 3.8 assumes (t = {} s from the halt)",
            unsteady.len(),
            unsteady.join(", ")
        ));
    }
    // A peak whose height no φ reads is left out of the peaks fit (peak_energies).
    let unread: Vec<String> = (series.peaks.peaks.iter())
        .filter(|p| !p.phi.is_finite())
        .map(|p| format!("{:.4}", p.t))
        .collect();
    if !unread.is_empty() {
        warnings.push(format!(
            "{} of {} peaks left out of the peaks fit: their heights lie outside the \
             rim model's range, so no φ reads them (t = {} s from the halt)",
            unread.len(),
            series.peaks.peaks.len(),
            unread.join(", ")
        ));
    }

    // φ from the heights against φ from the precession rate (crate::precession): a
    // check of the scale and the zero that shares neither; reported, never applied.
    let precession = precession::precession_check(
        &series.states,
        &params,
        series.peaks.window,
        signal_config(window_s, metres_per_px).state_window_periods,
    );
    if let Some(check) = precession.filter(|c| !c.agrees()) {
        warnings.push(format!(
            "the heights' φ and the precession's disagree by more than {:.0} %: {}. Check the \
             scale (the near top rim z_t, the disk's R, H and inertia in the config) and the \
             zero of z_rim",
            100.0 * precession::AGREEMENT,
            check.describe()
        ));
    }

    // n from the turning points' times alone (crate::turn_timing): no height, scale or zero
    // enters its n, reported beside the fits, never combined with them.
    if let Ok(timing) = &turn_timing
        && let Some(gap) = disjoint_intervals(timing.ci95_n, peaks_fit.fit.ci95_n)
    {
        warnings.push(format!(
            "n from the turns' timing alone, {:.3} ({:.3} … {:.3}), and from the energies at \
             the peaks, {:.3} ({:.3} … {:.3}), have disjoint 95 % intervals ({gap:.3} apart): the \
             heights' zero, a codec's smoothing of the swing, or rolling away from the \
             stationary state (nutation, slip) moves one and not the other",
            timing.n,
            timing.ci95_n.0,
            timing.ci95_n.1,
            peaks_fit.fit.n,
            peaks_fit.fit.ci95_n.0,
            peaks_fit.fit.ci95_n.1,
        ));
    }

    let threshold_png = highest.map_or_else(Vec::new, |(_, edge_row, frame)| {
        png(&diagnostics::threshold_image(
            &frame.view(),
            calibration.threshold.gamma,
            calibration.calibration.x_centre(),
            side_config.half_width_px,
            Some(edge_row),
        ))
    });
    let calibration = CalibrationReport {
        calibration: vision::Calibration {
            z_t: top_rim_leaning.map_or(calibration.calibration.z_t, |l| l.reading.z_t),
            ..calibration.calibration
        },
        ..calibration
    };
    let calibration_png = png(&diagnostics::calibration_image(
        &rest_side.view(),
        &calibration.calibration,
    ));
    let plan = ExperimentPlan {
        clip: clip.to_path_buf(),
        clip_hash: clip_hash(clip)?,
        crate_version: env!("CARGO_PKG_VERSION").into(),
        config: config.clone(),
        fps,
        frame_times: Some(frame_times),
        frames: frames.len(),
        decoded: Some(decoded),
        width,
        height,
        orientation: source.orientation(),
        video_signal: source.video_signal(),
        disk: params,
        layout,
        plate,
        split_row,
        calibration,
        top_rim_leaning,
        metres_per_px,
        scale,
        band_half_width_px: side_config.half_width_px,
        rim,
        rim_zero_row_px: Some(rim_zero_row_px),
        rim_zero_from_motion: zero,
        rim_zero_uncertainty_px: zero_px,
        rim_reading: Some(reading),
        colour_thresholds,
        window_s,
        halt: config.fit.as_ref().and_then(|f| f.halt).unwrap_or_default(),
    };
    Ok(Experiment {
        plan,
        frames,
        series,
        peaks_fit,
        frames_fit,
        full_state_fit,
        skips_in_window,
        precession,
        turn_timing: Some(turn_timing),
        halt_placement,
        warnings,
        diagnostics: Diagnostics {
            calibration_png,
            threshold_png,
        },
        kept,
    })
}

/// The signal stage (thesis §3.2.4–§3.3.3) on the measured frames: t_φ, the peaks,
/// the states, β and the skip flags, with the `known_flags` ([`known_flags`]) among
/// them (by the clip's frame numbers); sets each frame's time from the halt
/// ([`FrameRecord::t`]).
fn signal_series(
    frames: &mut [FrameRecord],
    known_flags: &[signal::FrameFlag],
    two_view: bool,
    config: &SignalConfig,
    model: &dyn RimModel,
    motion_profile: Option<&SideViewRim>,
    metres_per_px: f64,
) -> Result<(StateSeries, Option<ZeroFromMotion>), SignalError> {
    let (t, z) = rim_series(frames);
    let beta = strip_angles(frames, two_view);
    let mut series = signal::analyse(&t, &z, beta.as_deref(), model, config)?;
    // The heights from the zero the motion places (signal::motion_zero), with the
    // camera's own profile: every height moves by the rest level and the motion's
    // offset from it, and the peaks and states are found again on them.
    let motion = motion_profile.and_then(|camera| signal::motion_zero(&t, &z, &series, camera));
    let zero = motion.map(|zero| {
        let shift_m = series.halt.rest_level + zero.offset;
        for record in frames.iter_mut() {
            record.z_rim_m = record.z_rim_m.map(|z| z - shift_m);
            record.z_rim_px = record.z_rim_px.map(|z| z - shift_m / metres_per_px);
        }
        ZeroFromMotion { zero, shift_m }
    });
    if zero.is_some() {
        let (t, z) = rim_series(frames);
        series.halt.rest_level = 0.0;
        series = signal::with_zero_moved(&t, &z, &series, 0.0, model, config)?;
    }
    // The flags found before the stage ([`known_flags`]), on its time axis. A frame
    // missing where the timestamps show none is flagged by the rim's phase step that
    // showed it, not by the gap its count left in the capture times.
    let missing =
        |f: &signal::FrameFlag| matches!(f.reason, signal::SkipReason::RimPhaseStep { .. });
    let counted = |f: &signal::FrameFlag| {
        known_flags.iter().any(|k| missing(k) && k.index == f.index)
            && matches!(
                f.reason,
                signal::SkipReason::TimestampGap { .. } | signal::SkipReason::RimPhaseStep { .. }
            )
    };
    series.flags.retain(|f| !counted(f));
    series
        .flags
        .extend(known_flags.iter().map(|k| signal::FrameFlag {
            t: series.halt.shifted_t[k.index],
            ..k.clone()
        }));
    series.flags.sort_by_key(|f| f.index);
    // Flags carry the clip's frame numbers (a span's positions are not).
    for flag in &mut series.flags {
        flag.index = frames[flag.index].index;
    }
    for (record, shifted) in frames.iter_mut().zip(&series.halt.shifted_t) {
        record.t = *shifted;
    }
    Ok((series, zero))
}

/// The repeated frames (`repeated`, their readings taken out of `frames` and kept in
/// `set_aside`: each one's z_rim in px and β) up to the last frame of motion the rim
/// heights show ([`signal::halt_time`]); the readings of those after it go back.
/// After the halt every frame repeats the one before it, so none can be told a
/// repeat: a mark there is the codec's refresh of the still picture
/// ([`footage::RepeatGauge`]). With no halt found, every mark stays.
fn repeats_in_motion(
    frames: &mut [FrameRecord],
    mut repeated: Vec<footage::RepeatedFrame>,
    set_aside: Vec<(Option<f64>, Option<f64>)>,
    config: &SignalConfig,
    metres_per_px: f64,
) -> Vec<footage::RepeatedFrame> {
    if repeated.is_empty() {
        return repeated;
    }
    let (t, z) = rim_series(frames);
    let Ok(halt) = signal::halt_time(&t, &z, config) else {
        return repeated;
    };
    for (r, (z_rim_px, beta_raw)) in repeated.iter().zip(set_aside) {
        if r.index > halt.index {
            let record = &mut frames[r.index];
            record.z_rim_px = z_rim_px;
            record.z_rim_m = z_rim_px.map(|z| z * metres_per_px);
            record.beta_raw = beta_raw;
        }
    }
    repeated.retain(|r| r.index <= halt.index);
    repeated
}

/// The flags known before the signal stage, at their positions in the frames (their
/// times are set on the stage's axis, [`signal_series`]): the duplicated and
/// interpolated frames (`repeated`, left out of the fits) and the frames missing
/// where the timestamps show no gap (`hidden`, [`hidden_drops`]).
fn known_flags(
    repeated: &[footage::RepeatedFrame],
    hidden: Vec<signal::FrameFlag>,
) -> Vec<signal::FrameFlag> {
    repeated
        .iter()
        .map(|r| signal::FrameFlag {
            index: r.index,
            t: f64::NAN,
            reason: match r.kind {
                footage::RepeatKind::Duplicated => signal::SkipReason::DuplicatedFrame {
                    step: r.statistic,
                    neighbours: r.neighbours,
                },
                footage::RepeatKind::Interpolated => signal::SkipReason::InterpolatedFrame {
                    residual: r.statistic,
                    neighbours: r.neighbours,
                },
            },
        })
        .chain(hidden)
        .collect()
}

/// Frames missing from the clip where its timestamps show no gap
/// ([`signal::missing_frames`], from a first pass of the signal stage over the heights
/// as measured): each such frame and every one after it moves one nominal period
/// later on the capture clock (`t_capture`), so that no local fit, precession rate or
/// energy time spans a frame that is not there. Returns the rim phase steps that
/// showed them (positions in `frames`; `period` is the nominal frame interval \[s\]);
/// none when the first pass fails (the signal stage then reports why).
fn hidden_drops(
    frames: &mut [FrameRecord],
    repeated: &[footage::RepeatedFrame],
    two_view: bool,
    config: &SignalConfig,
    model: &dyn RimModel,
    period: f64,
) -> Vec<signal::FrameFlag> {
    let (t, z) = rim_series(frames);
    let beta = strip_angles(frames, two_view);
    let Ok(series) = signal::analyse(&t, &z, beta.as_deref(), model, config) else {
        return Vec::new();
    };
    let repeated: Vec<usize> = repeated.iter().map(|r| r.index).collect();
    let steps = signal::missing_frames(&series.flags, period, &repeated);
    let positions: Vec<usize> = steps.iter().map(|f| f.index).collect();
    shift_capture_clock(frames, &positions, period);
    steps
}

/// Moves each frame's capture time by `by` \[s\] for every one of `positions` (in
/// `frames`) at or before it: a frame missing before each, counted (`by` the nominal
/// period) or withdrawn (minus it).
fn shift_capture_clock(frames: &mut [FrameRecord], positions: &[usize], by: f64) {
    for (i, record) in frames.iter_mut().enumerate() {
        let count = positions.iter().filter(|&&p| p <= i).count();
        record.t_capture += count as f64 * by;
    }
}

/// The frames [`hidden_drops`] counted missing whose phase step no longer passes
/// [`signal::missing_frames`] on the halt-shifted times `shifted_t` (positions in
/// `frames`) of a halt placed earlier, by a law of the motion ([`law_bound`]): the
/// first pass measured the step test's margin from a halt that still pictures made
/// late. Each is taken out of `known_flags`, and the frames from it on lose the
/// nominal `period` their capture time gained. Returns their positions.
fn withdraw_hidden_drops(
    frames: &mut [FrameRecord],
    known_flags: &mut Vec<signal::FrameFlag>,
    shifted_t: &[f64],
    period: f64,
) -> Vec<usize> {
    let is_step =
        |k: &signal::FrameFlag| matches!(k.reason, signal::SkipReason::RimPhaseStep { .. });
    let hidden: Vec<signal::FrameFlag> = known_flags
        .iter()
        .filter(|k| is_step(k))
        .map(|k| signal::FrameFlag {
            t: shifted_t[k.index],
            ..k.clone()
        })
        .collect();
    let kept = signal::missing_frames(&hidden, period, &[]);
    let withdrawn: Vec<usize> = hidden
        .iter()
        .filter(|h| kept.iter().all(|k| k.index != h.index))
        .map(|h| h.index)
        .collect();
    shift_capture_clock(frames, &withdrawn, -period);
    known_flags.retain(|k| !(is_step(k) && withdrawn.contains(&k.index)));
    withdrawn
}

/// The rim's profile the peaks and the states are read with: the camera's
/// ([`SideViewRim`]) when its elevation ε at the near rim is known, else eq. 3.9's
/// level camera ([`ThesisRim`]). At the peaks the camera's profile is
/// 2R sin φ − H φ tan ε, so eq. 3.9 reads φ low by H tan ε/(2R), 0.44 % at ε = 3°
/// for Euler's disk; the local fits, which weigh the turn's mean with its swing,
/// read it low by about 2/3 of that (`signal::tests::exact_geometry_is_a_drop_in_model`).
fn rim_model(scale: &ScaleReport, disk: &DiskParams) -> Box<dyn RimModel> {
    match scale.side_view_rim(disk) {
        Some(camera) => Box::new(camera),
        None => Box::new(ThesisRim {
            radius: disk.radius,
        }),
    }
}

/// The rim's profile the motion's zero is fitted with ([`signal::motion_zero`]): the
/// camera's ([`ScaleReport::side_view_rim`]) when `choice` asks for the motion's zero.
/// `None` keeps the still disk's edge: asked for, or the camera's elevation not known,
/// where the first-order profile would read 0.05–0.12 px of offset that is not there
/// (BENCHMARKS.md, "The zero from the motion").
fn motion_profile(
    choice: RimZeroChoice,
    scale: &ScaleReport,
    disk: &DiskParams,
) -> Option<SideViewRim> {
    match choice {
        RimZeroChoice::Motion => scale.side_view_rim(disk),
        RimZeroChoice::Rest => None,
    }
}

/// The strip angles β \[rad\] of a two-view clip's frames (NaN: no strip), as the
/// signal stage reads them; `None` for a side view.
fn strip_angles(frames: &[FrameRecord], two_view: bool) -> Option<Vec<f64>> {
    two_view.then(|| {
        frames
            .iter()
            .map(|f| f.beta_raw.unwrap_or(f64::NAN))
            .collect()
    })
}

/// The frames' capture times \[s\] and rim heights z_rim \[m\] (NaN: no edge), as the
/// signal stage reads them.
fn rim_series(frames: &[FrameRecord]) -> (Vec<f64>, Vec<f64>) {
    let t = frames.iter().map(|f| f.t_capture).collect();
    let z = frames
        .iter()
        .map(|f| f.z_rim_m.unwrap_or(f64::NAN))
        .collect();
    (t, z)
}

/// The energy's fits of one span: at the peaks, per frame, and per frame with the
/// strip's θ̇ (two-view); and the turns' timing law of the same series
/// ([`turn_timing_fit`]), whose end checks the halt seen.
struct Fits {
    peaks: EnergyFit,
    frames: Option<EnergyFit>,
    full_state: Option<EnergyFit>,
    turns: Result<TurnTimingFit, String>,
}

/// A bound on the motion from a law of it whose halt the halt seen lies well after
/// ([`law_bound`]).
#[derive(Debug, Clone, Copy, PartialEq)]
struct LawBound {
    /// The latest time at which the law leaves the rim any motion, on the fits' clock
    /// (t_φ at 0) \[s\]: its halt + 3 σ + one frame.
    bound: f64,
    /// The law, as a warning names it.
    law: &'static str,
    /// Its halt \[s\] and that halt's standard error \[s\].
    halt: f64,
    se: f64,
}

/// The latest time at which the motion's laws leave the rim any motion, on the fits'
/// clock (t_φ = 0), when the halt seen lies after a law's: a fit's sighting of the
/// halt (at the peaks or per frame, [`HaltSighting`]) lies late, by more than
/// [`energy::SIGHTING_DISAGREEMENT`] standard deviations of their difference, of that
/// fit's t0 or of the end T of the turns' timing law (`turns`, [`turn_timing_fit`]).
/// A disk whose energy E = A_e (t0 − t)^n (eq. 3.2) has gone to zero lies flat and
/// does not rise again, and its turns, ψ̇ ∝ (T − t)^{−n/2}, end at T, so a rise seen
/// after the halt is a coded picture: an encoder that shows earlier pictures again
/// for a few frames after the halt, or settles on the still disk over many, read as
/// motion (o05 of the open footage re-encoded at CRF 20: t_φ 9.5 frames late, a
/// spurious peak). Either fit may see it alone: the spurious low peaks pull the peaks
/// fit's free t0 onto the last of them (the same clip re-encoded by libx264
/// 0.164.3095: peaks of 0.21 and 0.20 px at frames 623 and 625, the disk flat from
/// 615.5; the peaks fit's t0 5.6 ms before the halt seen, within 3σ of 7.4 ms, while
/// the per-frame fit's lay 21 ± 0.5 ms before it, 0.3 frames from the truth). The
/// turns' law may see it where neither fit can: where the final peaks barely fix the
/// energies' t0 (±13 ms on seed 7's robustness scene s03, crf 23), the halt seen
/// decides the combined t0, and its coded pictures 4 frames after the true halt made
/// n +0.046, while the turns ended 0.5 frames from the truth, ±1.2 ms. The bound is
/// the earliest over the laws that disagree of their halt + 3 σ + one frame
/// `frame_s` (the last frame of motion falls up to a frame after the halt,
/// [`HaltSighting`]); `None` when the halt seen agrees, or the bound does not lie
/// before t_φ. A halt seen *before* a law's is the motion's last part too small to
/// see or hidden by its phase, which the sighting models, or held pictures, which it
/// does not: no bound (the fits leave such a sighting out when it lies more than 3σ
/// before T, `HaltSighting::fit`).
fn law_bound(fits: &Fits, turns: Option<&TurnTimingFit>, frame_s: f64) -> Option<LawBound> {
    let sightings = [
        Some(("the energy law fitted at the peaks", &fits.peaks)),
        fits.frames
            .as_ref()
            .map(|f| ("the energy law fitted per frame", f)),
    ];
    sightings
        .into_iter()
        .flatten()
        .filter_map(|(law, f)| f.fit.halt_sighting.map(|s| (law, s)))
        .flat_map(|(law, s)| {
            let fitted = (law, s.t0_fitted, s.se_t0_fitted);
            let timed = turns.map(|f| ("the turns' timing law", f.t_end, f.se_t_end));
            [Some(fitted), timed]
                .into_iter()
                .flatten()
                .filter(move |&(_, halt, se)| {
                    s.t0_seen - halt > energy::SIGHTING_DISAGREEMENT * s.se_t0_seen.hypot(se)
                })
        })
        .map(|(law, halt, se)| LawBound {
            bound: halt + energy::SIGHTING_DISAGREEMENT * se + frame_s,
            law,
            halt,
            se,
        })
        .filter(|b| b.bound < 0.0 && b.se.is_finite() && b.se > 0.0)
        .min_by(|a, b| a.bound.total_cmp(&b.bound))
}

/// PNG bytes of a diagnostic image; empty if encoding fails (the images are for
/// looking at, never an input to a number).
fn png(image: &image::RgbImage) -> Vec<u8> {
    diagnostics::png_bytes(image).unwrap_or_default()
}

/// The halt as the footage shows it: motion last seen at the halt detector's last
/// frame of motion (on the fit's clock, t_φ at 0), one frame `frame_s` apart, down to
/// the least rise the halt detector sees above the heights' zero (its threshold above
/// the rest level, which lies `rest_above_zero_m` above the zero the motion placed), a
/// rim rise a peak of stationary rolling reaches at sin φ = z/(2R), over its rest
/// noise.
fn halt_sighting(
    params: &DiskParams,
    halt: &signal::Halt,
    rest_above_zero_m: f64,
    frame_s: f64,
) -> HaltSighting {
    let seen = HaltSighting {
        t_last: halt.last_motion_seen(),
        frame_s,
        visible_energy: 0.0,
        threshold_m: halt.threshold,
        noise_m: halt.noise,
        visible_precession: 0.0,
        rest_above_zero_m,
        turns_end: None,
    };
    let phi = (seen.visible_rise() / (2.0 * params.radius))
        .clamp(0.0, 1.0)
        .asin();
    HaltSighting {
        visible_energy: energy::stationary_energy_at(params, phi).unwrap_or(0.0),
        visible_precession: closed_form::stationary_rolling(params, phi)
            .map_or(0.0, |(psi_dot, _)| psi_dot.abs()),
        ..seen
    }
}

/// Where the motion's laws place the halt on the clock of `series` (t_φ at 0) \[s\],
/// and the [`HaltPlacement`] on that clock: the mean of the energy law's t0 fitted at
/// the peaks (`peaks`, combined with the halt seen, [`HaltSighting`]) and the end T of
/// the turns' timing law (`turns`, [`turn_timing_fit`] of the same series), or t0
/// alone when the turns cannot be timed; `None` when t0 is not finite.
///
/// The halt detector's last frame of motion is a rule, a rise above the rest's noise,
/// and comes early by the frames whose motion the footage does not show: the last
/// rises fall below the threshold, and an encoder holds pictures whose change is
/// below its quantiser (7 frames early on the robustness gate's s17, crf 28; on 8 of
/// its 24 scenes more than 2 frames off, RMS 6.4 ms). The laws' halts follow every
/// turn of the window: over those 24 scenes t0 is off by 2.0 ms RMS and T by 1.1; over
/// the open footage and its five re-encodings (48 clips) by 0.54 and 0.61 frames, and
/// their errors are independent enough that the mean is off by 1.1 ms and 0.36
/// frames RMS (BENCHMARKS.md, "t_φ where the laws place the halt"). T needs no height
/// and t0 no count of the turns, so a codec's shaved swings move one and not the
/// other.
fn law_halt(
    peaks: &PowerLawFit,
    turns: Option<&TurnTimingFit>,
    halt: &signal::Halt,
) -> Option<(f64, HaltPlacement)> {
    let t0 = Some(peaks.t0).filter(|t| t.is_finite())?;
    let se_t0 = peaks.se_t0.filter(|se| se.is_finite());
    let turns = turns.filter(|f| f.t_end.is_finite() && f.se_t_end.is_finite());
    let (placed, se_s) = match &turns {
        Some(f) => (
            0.5 * (t0 + f.t_end),
            se_t0.map(|se| 0.5 * se.hypot(f.se_t_end)),
        ),
        None => (t0, se_t0),
    };
    let placement = HaltPlacement {
        t0_s: t0,
        turns_end_s: turns.map(|f| f.t_end),
        se_s,
        last_motion_seen_s: halt.last_motion_seen(),
    };
    Some((placed, placement))
}

/// The timing law of the turns fitted to the turning points of z_rim (peaks and the
/// troughs between them, half a turn apart) in the peaks' window (`series.window`), at
/// their counted ψ ([`turn_timing::fit_turn_timing`]), up to the last peak the local
/// fit located. A parabolic peak after it is the last rise at the halt or a turn the
/// halt cuts short (the local fit spans 1.5 turns): its time marks where the motion
/// stopped, not a crest of the turn (on the open footage re-encoded at CRF 26 such
/// peaks made the timing's n +0.046 and +0.058 on two clips; BENCHMARKS.md, *n from
/// the turns' timing*). The troughs halve the timing's scatter over the peaks alone
/// (the same BENCHMARKS section).
fn turn_timing_fit(series: &PeakSeries) -> Result<TurnTimingFit, String> {
    let last_crest = series
        .peaks
        .iter()
        .rev()
        .find(|p| p.method == signal::ExtremumMethod::LocalFit)
        .map_or(f64::NEG_INFINITY, |p| p.t);
    let (t, psi): (Vec<f64>, Vec<f64>) = series
        .precession_half_turns
        .iter()
        .filter(|s| s.t >= series.window.0 && s.t <= last_crest)
        .map(|s| (s.t, s.psi))
        .unzip();
    turn_timing::fit_turn_timing(&t, &psi).map_err(|e| e.to_string())
}

/// How far apart two intervals lie, `None` when they overlap.
fn disjoint_intervals(a: (f64, f64), b: (f64, f64)) -> Option<f64> {
    let gap = (a.0 - b.1).max(b.0 - a.1);
    (gap > 0.0).then_some(gap)
}

/// Eq. 3.8 at each peak of the window, with ψ̇ by central differences over the
/// neighbouring peaks, and by eq. 3.11 (the forward difference to the next peak) at
/// the first. Eq. 3.11 is the mean rate over the following turn: as ψ̇ grows
/// towards the halt it reads high at the peak, by 1 % 0.4 s before the halt and by
/// 5–10 % in the last 0.05 s on exact rim heights of an n = 0.67 motion, which
/// raised the fitted n by 0.01; the central difference is centred on the peak.
///
/// A difference across a timestamp gap counts one turn where the gap hid more (its
/// peaks are missing): there the forward difference is used if it does not cross
/// the gap, else the peak is left out. So is a peak whose height no φ reads (it lies
/// outside the rim model's range, `RimModel::phi_from_peak`); the caller warns.
fn peak_energies(params: &DiskParams, series: &StateSeries) -> Vec<EnergySample> {
    let precession = &series.peaks.precession;
    let peaks = &series.peaks.peaks;
    // Times (halt at 0) of the frames that follow a timestamp gap.
    let gaps: Vec<f64> = series
        .flags
        .iter()
        .filter(|f| matches!(f.reason, signal::SkipReason::TimestampGap { .. }))
        .map(|f| f.t)
        .collect();
    let clear = |a: usize, b: usize| {
        let (ta, tb) = (peaks[a].t, peaks[b].t);
        !gaps.iter().any(|&g| ta < g && g <= tb)
    };
    let last = peaks.len().saturating_sub(1);
    peaks
        .iter()
        .zip(precession)
        .enumerate()
        .filter_map(|(k, (peak, p))| {
            let central = p
                .psi_dot_central
                .filter(|_| k > 0 && k < last && clear(k - 1, k + 1));
            let forward = p.psi_dot_forward.filter(|_| k < last && clear(k, k + 1));
            let psi_dot = central.or(forward)?;
            peak.phi.is_finite().then_some(EnergySample {
                t: peak.t,
                phi: peak.phi,
                psi_dot,
                theta_dot: None,
                energy: energy::stationary_rolling_energy(params, peak.phi, psi_dot),
            })
        })
        .collect()
}

/// How far a state's precession rate may lie from stationary rolling's at its φ
/// (eq. 4.40, corrected) for eq. 3.8, which assumes stationary rolling, to read its
/// energy: a factor of 2 either way (ψ̇² by 4). On the open footage, as given,
/// mirrored, with drops and under another tone curve, every state lies within 0.73 …
/// 1.13 of it (nutation and the local fits' noise) but two: one 3.5 ms before the
/// halt of o02 under gamma 0.7 at 5.8 (its window cut by the halt; its energy 27
/// times its neighbours', the per-frame n −0.034), and one of o08 mirrored at 0.37.
const STATIONARY_RATE_FACTOR: f64 = 2.0;

/// Whether `state`'s |ψ̇| lies within [`STATIONARY_RATE_FACTOR`] of stationary
/// rolling's at its φ; a φ with no stationary rolling is not.
fn near_stationary_rolling(params: &DiskParams, state: &signal::FrameState) -> bool {
    closed_form::stationary_rolling(params, state.phi).is_ok_and(|(psi_dot, _)| {
        let ratio = state.psi_dot.abs() / psi_dot.abs();
        (1.0 / STATIONARY_RATE_FACTOR..=STATIONARY_RATE_FACTOR).contains(&ratio)
    })
}

/// Energies at every frame state: eq. 3.8, or with a strip, eq. 3.6 with
/// θ̇ = β̇ − ψ̇ (eq. 3.22) and φ̇ = 0.
fn frame_energies(
    params: &DiskParams,
    series: &StateSeries,
    strip: Option<&signal::StripAnalysis>,
) -> Vec<EnergySample> {
    // A state whose local fit is poorly determined (its window cut short at the
    // start of the series, or too few rim heights) is left out.
    series
        .states
        .iter()
        .filter(|s| s.is_determined() && near_stationary_rolling(params, s))
        .filter_map(|s| {
            // The side view gives |ψ̇| only. Near stationary rolling β̇ = ψ̇ + θ̇ =
            // ψ̇ (1 − cos φ + h sin φ) (eqs. 3.7, 3.22) has the sign of ψ̇, so the
            // strip supplies the sense of precession.
            let (psi_dot, theta_dot) = match strip {
                Some(strip) => {
                    let beta_dot = *strip.series.beta_dot.get(s.index)?;
                    let psi_dot = s.psi_dot.abs().copysign(beta_dot);
                    (psi_dot, Some(beta_dot - psi_dot))
                }
                None => (s.psi_dot, None),
            };
            let energy = match theta_dot {
                Some(theta_dot) => energy::rolling_energy(params, s.phi, 0.0, psi_dot, theta_dot),
                None => energy::stationary_rolling_energy(params, s.phi, psi_dot),
            };
            energy.is_finite().then_some(EnergySample {
                t: s.t,
                phi: s.phi,
                psi_dot,
                theta_dot,
                energy,
            })
        })
        .collect()
}

/// Frames in the rest tail ([`SignalConfig::rest_tail_s`]) at `fps`, at least
/// [`REST_FRAMES`].
fn rest_tail_frames(fps: f64) -> usize {
    ((SignalConfig::default().rest_tail_s * fps).round() as usize).max(REST_FRAMES)
}

/// The rest window whose fitted edge is the zero of z_rim on a dark plate
/// (vision::mirror_edge): the mean of the band windows of the last `tail` frames
/// that hold the same rows as pass 1's mean of the last [`REST_FRAMES`], else pass
/// 1's.
///
/// Each picture of a still disk carries its own coding error, and an encoder may
/// code a clip's last frames apart from the ones before. The rest fit (edge,
/// plate line and reflectivity at once) then moves with the frames it is given: on
/// o05 of the open footage re-encoded at CRF 20 pass 1's five frames put the edge
/// at rest at 429.35 px, the tail's 48 frames at 429.74 px, where the original
/// clip's five and 48 put it (429.71, 429.74), and every lifted height had read
/// 0.33 px low. The halt's analysis checks that the same tail is at rest.
fn tail_rest_window(windows: &[Option<BandWindow>], pass1: &BandWindow, tail: usize) -> BandWindow {
    BandWindow::tail_mean(windows, pass1, tail, REST_FRAMES).unwrap_or_else(|| pass1.clone())
}

/// Moves the zero of `heights` \[px\] to the median of the last `tail` frames'
/// readings (light plate, vision::shadow_edge), when [`REST_FRAMES`] of them have
/// one; returns the shift (0 otherwise).
///
/// On a light plate the zero is the shadow-edge contour's crossing at rest alone,
/// so the rest tail's frames can each be read with it and the median taken: it
/// passes over a codec refresh that a mean profile would take in, and over the
/// last frames' own coding error.
fn tail_median_shift(heights: &mut [Option<f64>], tail: usize) -> f64 {
    let rest: Vec<f64> = heights[heights.len().saturating_sub(tail)..]
        .iter()
        .flatten()
        .copied()
        .collect();
    if rest.len() < REST_FRAMES {
        return 0.0;
    }
    let shift = signal::median(&rest);
    for z in heights.iter_mut().flatten() {
        *z -= shift;
    }
    shift
}

/// The signal stage's settings for a clip measured at `metres_per_px`.
fn signal_config(window_s: f64, metres_per_px: f64) -> SignalConfig {
    SignalConfig {
        window_s,
        // The rim is located to about 0.01 px on lossless frames (the edge, and
        // the gap's darkness below 2 px), so a clean rest tail can have almost no
        // spread: floor the noise at 0.02 px (motion from 0.1 px on), and ask a
        // peak to stand 0.2 px above its surroundings.
        noise_floor: 0.02 * metres_per_px,
        min_prominence: 0.2 * metres_per_px,
        ..SignalConfig::default()
    }
}

/// `fit` with the standard error of its n from the zero of z_rim: half the change of
/// n between the fits of the same samples from `moved` (the series with the zero
/// moved down and up by its uncertainty), or the whole change when only one fits.
fn with_zero_error(
    fit: EnergyFit,
    moved: &[Option<StateSeries>; 2],
    samples: impl Fn(&StateSeries) -> Vec<EnergySample>,
    window_s: f64,
    halt: HaltTime,
) -> EnergyFit {
    let n: Vec<f64> = moved
        .iter()
        .flatten()
        .filter_map(|series| {
            let s = samples(series);
            let t: Vec<f64> = s.iter().map(|s| s.t).collect();
            let e: Vec<f64> = s.iter().map(|s| s.energy).collect();
            energy::fit_window(&t, &e, window_s, halt).ok().map(|f| f.n)
        })
        .collect();
    let se_zero = match n[..] {
        [low, high] => 0.5 * (high - low).abs(),
        [one] => (one - fit.fit.n).abs(),
        _ => return fit,
    };
    EnergyFit {
        fit: fit.fit.with_zero_error(se_zero),
        ..fit
    }
}

/// The power law fitted to `samples` over the final `window_s`, and its window
/// sensitivity, with the covariances estimated over the samples and also over `turns`
/// (the peaks' times; empty for one sample a turn), as `energy::fit_window_in_turns`.
fn fit_series(
    method: &str,
    samples: Vec<EnergySample>,
    window_s: f64,
    halt: HaltTime,
    turns: &[f64],
) -> Result<EnergyFit, FitError> {
    let t: Vec<f64> = samples.iter().map(|s| s.t).collect();
    let e: Vec<f64> = samples.iter().map(|s| s.energy).collect();
    let fit = energy::fit_window_in_turns(&t, &e, window_s, halt, turns)?;
    let windows = energy::window_sensitivity(&t, &e, &SENSITIVITY_WINDOWS_S, halt, turns)
        .into_iter()
        .map(|(w, r)| (w, r.map_err(|e| e.to_string())))
        .collect();
    Ok(EnergyFit {
        method: method.into(),
        samples,
        fit,
        windows,
    })
}

/// A signal-stage failure of `clip`. A slow-motion clip stored at a playback rate
/// (24–60 fps, below 100) with no `fps` in the config is timed 8× too slow: its
/// rest tail, motion and peaks all look wrong, and the frame rate is the probable
/// cause, so it is named first.
fn signal_error(clip: &Path, fps: &CaptureFps, error: SignalError) -> AnalyseError {
    let stored_rate = matches!(
        fps.source,
        footage::FpsSource::ContainerFps | footage::FpsSource::ContainerTimestamps
    );
    if stored_rate && fps.fps < 100.0 {
        return AnalyseError::Clip {
            path: clip.to_path_buf(),
            reason: format!(
                "probably the frame rate: the clip is stored at {:.2} fps and no `fps` is \
                 configured; if it was filmed in slow motion, set `fps` (e.g. fps = 480) in \
                 eulerdisk.toml or the clip's own .toml. The analysis said: {error}",
                fps.fps
            ),
        };
    }
    AnalyseError::Signal {
        path: clip.to_path_buf(),
        error,
    }
}

/// The config that applies to `clip`: the folder files from `root` down, the
/// clip's own `CLIP.toml`, then `extra` (a `-c` file) last.
///
/// # Errors
/// A config file that cannot be read or is invalid (named in the message).
pub fn config_for(
    root: &Path,
    clip: &Path,
    extra: Option<&Path>,
) -> Result<ExperimentConfig, crate::config::ConfigError> {
    let mut layers = ExperimentConfig::layers_for(root, clip);
    if let Some(extra) = extra {
        if !extra.is_file() {
            return Err(crate::config::ConfigError::Unreadable {
                path: extra.to_path_buf(),
                reason: if extra.is_dir() {
                    "a folder, not a config file (-c takes a TOML file)".into()
                } else {
                    "no such file".into()
                },
            });
        }
        layers.push(extra.to_path_buf());
    }
    ExperimentConfig::load_layered(&layers)
}

/// The resume key of a clip under a config: BLAKE3 of the clip's hash, the config
/// (as JSON) and the crate version.
///
/// # Errors
/// The clip cannot be read.
pub fn resume_key(clip: &Path, config: &ExperimentConfig) -> Result<String, FootageError> {
    let mut hasher = blake3::Hasher::new();
    hasher.update(clip_hash(clip)?.as_bytes());
    hasher.update(serde_json::to_string(config).unwrap_or_default().as_bytes());
    hasher.update(env!("CARGO_PKG_VERSION").as_bytes());
    Ok(hasher.finalize().to_hex().to_string())
}

/// A study's per-clip work: configs inherited from the study root, one
/// [`analyse_clip`] and [`write_experiment`](crate::report::experiment::write_experiment)
/// per clip.
pub struct StudyAnalyser {
    pub root: PathBuf,
    /// The overlays each clip gets (`None`: none).
    pub overlay: Option<crate::overlay::OverlaySpec>,
}

impl crate::study::ClipAnalyser for StudyAnalyser {
    fn resume_key(&self, clip: &crate::study::ClipEntry) -> Result<String, String> {
        let config = config_for(&self.root, &clip.path, None).map_err(|e| e.to_string())?;
        resume_key(&clip.path, &config).map_err(|e| e.to_string())
    }

    fn analyse(
        &self,
        clip: &crate::study::ClipEntry,
        dir: &Path,
        key: &str,
    ) -> Result<crate::study::ExperimentSummary, String> {
        let config = config_for(&self.root, &clip.path, None).map_err(|e| e.to_string())?;
        let experiment = analyse_clip_keeping(
            &clip.path,
            &config,
            Decoding::NearTheEnd,
            self.overlay.as_ref(),
            &|_, _| {},
        )
        .map_err(|e| e.to_string())?;
        crate::report::experiment::write_experiment(dir, &experiment, self.overlay.as_ref())
            .map_err(|e| e.to_string())?;
        let mut meta = clip.meta.clone();
        meta.material = meta.material.or(config.material.clone());
        meta.disk = meta.disk.or(config.disk_name.clone());
        meta.orientation = meta.orientation.or(config.orientation.clone());
        Ok(summary(&experiment, &clip.relative, meta, key))
    }
}

/// What a study keeps of an experiment.
pub fn summary(
    experiment: &Experiment,
    clip: &str,
    meta: crate::study::ClipMeta,
    key: &str,
) -> crate::study::ExperimentSummary {
    let fit = &experiment.peaks_fit.fit;
    crate::study::ExperimentSummary {
        clip: clip.into(),
        meta,
        resume_key: key.into(),
        n: fit.n,
        n_ci95: [fit.ci95_n.0, fit.ci95_n.1],
        t0_s: fit.t0,
        r_squared: fit.r_squared,
        points: fit.points,
        fps: experiment.plan.fps.fps,
        fps_source: format!("{:?}", experiment.plan.fps.source),
        phi_vs_precession: experiment.precession.map(|c| c.agreement() - 1.0),
        n_turn_timing: match &experiment.turn_timing {
            Some(Ok(t)) => Some((t.n, [t.ci95_n.0, t.ci95_n.1])),
            _ => None,
        },
        warnings: experiment.warnings.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Peak energies of E = A_e (t0 − t)^n with 2 % noise, one every 6 ms up to
    /// `last` (t_φ = 0 on this clock), fitted as `analyse` fits them with the halt seen.
    fn sighted_peaks_fit(t0: f64, last: f64) -> EnergyFit {
        let (a_e, n, frame_s) = (0.5, 0.55, 1.0 / 480.0);
        let samples: Vec<EnergySample> = (0..80)
            .map(|k| last - 0.006 * k as f64)
            .rev()
            .enumerate()
            .map(|(k, t)| EnergySample {
                t,
                phi: 0.0,
                psi_dot: 0.0,
                theta_dot: None,
                energy: a_e * (t0 - t).powf(n) * (1.0 + 0.02 * (k as f64 * 2.39).sin()),
            })
            .collect();
        let halt = HaltTime::Sighted(HaltSighting {
            t_last: 0.0,
            frame_s,
            visible_energy: a_e * (0.3 * frame_s).powf(n),
            threshold_m: 2e-5,
            noise_m: 2e-6,
            visible_precession: 1400.0,
            rest_above_zero_m: 0.0,
            turns_end: None,
        });
        fit_series("eq. 3.8 at peaks", samples, 0.5, halt, &[]).expect("fit")
    }

    /// Two frames counted missing on a first pass (positions 100 and 380, so the
    /// capture clock runs one period ahead from 100 and two from 380), and a
    /// duplicated frame at 50. A law places the halt at position 390: the step at
    /// 380, whose test spans 1.5 turns either side (9.4 frames at 1 rad a frame),
    /// lies closer to it than two such spans (18.8 frames) and is withdrawn; the one
    /// at 100 stays.
    /// A state at the precession rate of stationary rolling at its φ (eq. 4.40), or
    /// within the 0.73 … 1.13 of it that the open footage's states show, is read by
    /// eq. 3.8; the outliers seen (5.8 and 0.37 times it) are not, nor is a φ where no
    /// stationary rolling exists.
    #[test]
    fn a_state_far_from_stationary_rolling_is_not_read_by_eq_3_8() {
        let params = crate::model::params::Preset::EulerDisk.params();
        let phi = 0.003;
        let (rate, _) = closed_form::stationary_rolling(&params, phi).expect("exists");
        let state = |psi_dot: f64, phi: f64| signal::FrameState {
            index: 0,
            t: -0.01,
            phi,
            sigma_phi: 1e-5,
            psi: 0.0,
            sigma_psi: 0.01,
            psi_dot,
            sigma_psi_dot: 1.0,
            residual_rms: 1e-6,
            points: 12,
        };
        for factor in [1.0, 0.73, 1.13, -1.0] {
            assert!(
                near_stationary_rolling(&params, &state(factor * rate, phi)),
                "{factor}"
            );
        }
        for factor in [5.8, 0.37] {
            assert!(
                !near_stationary_rolling(&params, &state(factor * rate, phi)),
                "{factor}"
            );
        }
        // Beyond φ_d = 71.7° Euler's disk has no stationary rolling.
        assert!(!near_stationary_rolling(&params, &state(rate, 1.3)));
    }

    #[test]
    fn a_drop_counted_on_still_pictures_is_withdrawn_at_the_laws_halt() {
        let period = 1.0 / 480.0;
        let true_t = |k: usize| k as f64 * period;
        let drops_before = |k: usize| usize::from(k >= 100) + usize::from(k >= 380);
        let mut frames: Vec<FrameRecord> = (0..420)
            .map(|k| FrameRecord {
                index: k,
                t_capture: true_t(k) + drops_before(k) as f64 * period,
                t: 0.0,
                container_time_s: None,
                picture_type: None,
                z_rim_px: None,
                z_rim_m: None,
                beta_raw: None,
            })
            .collect();
        let step = |index| signal::FrameFlag {
            index,
            t: 0.0,
            reason: signal::SkipReason::RimPhaseStep {
                phase_step: 1.0,
                statistic: 100.0,
            },
        };
        let duplicate = signal::FrameFlag {
            index: 50,
            t: 0.0,
            reason: signal::SkipReason::DuplicatedFrame {
                step: 0.1,
                neighbours: 1.0,
            },
        };
        let mut known = vec![duplicate.clone(), step(100), step(380)];
        let halt = frames[390].t_capture;
        let shifted: Vec<f64> = frames.iter().map(|f| f.t_capture - halt).collect();
        let withdrawn = withdraw_hidden_drops(&mut frames, &mut known, &shifted, period);
        assert_eq!(withdrawn, vec![380]);
        assert_eq!(known, vec![duplicate, step(100)]);
        for (k, f) in frames.iter().enumerate() {
            let want = true_t(k) + usize::from(k >= 100) as f64 * period;
            assert!(
                (f.t_capture - want).abs() < 1e-12,
                "frame {k}: {}",
                f.t_capture
            );
        }
        // Nothing is left to withdraw at that halt.
        assert!(withdraw_hidden_drops(&mut frames, &mut known, &shifted, period).is_empty());
    }

    /// A rim turning every 10 frames (480 fps, 0.1 mm/px) down to the halt at frame
    /// 300, then still: a frame marked repeated in the motion stays out of the fits; one
    /// marked 50 frames after the halt (a refresh of the still picture) gets its
    /// reading back and is no repeat.
    #[test]
    fn only_frames_in_motion_are_repeats() {
        let metres_per_px = 1e-4;
        let mut frames: Vec<FrameRecord> = (0..420)
            .map(|k| {
                let x = k as f64;
                let lift = if k < 300 {
                    4.0 * (1.0 - x / 300.0) * (std::f64::consts::PI * x / 10.0).sin().abs()
                } else {
                    0.02 * (1.7 * x).sin()
                };
                FrameRecord {
                    index: k,
                    t_capture: x / 480.0,
                    t: 0.0,
                    container_time_s: None,
                    picture_type: None,
                    z_rim_px: Some(lift),
                    z_rim_m: Some(lift * metres_per_px),
                    beta_raw: None,
                }
            })
            .collect();
        let marked = |index| footage::RepeatedFrame {
            index,
            kind: footage::RepeatKind::Interpolated,
            statistic: 0.1,
            neighbours: 1.0,
            noise: 0.1,
        };
        let repeated = vec![marked(150), marked(350)];
        let set_aside: Vec<_> = repeated
            .iter()
            .map(|r| {
                let record = &mut frames[r.index];
                record.z_rim_m = None;
                (record.z_rim_px.take(), None)
            })
            .collect();
        let in_motion = repeats_in_motion(
            &mut frames,
            repeated,
            set_aside,
            &signal_config(0.5, metres_per_px),
            metres_per_px,
        );
        assert_eq!(in_motion.iter().map(|r| r.index).collect::<Vec<_>>(), [150]);
        assert_eq!(frames[150].z_rim_px, None);
        let back = 0.02 * (1.7f64 * 350.0).sin();
        assert_eq!(frames[350].z_rim_px, Some(back));
        assert_eq!(frames[350].z_rim_m, Some(back * metres_per_px));
    }

    /// The turns' timing law takes the turning points up to the last peak the local fit
    /// located: 25 crests of an exact law (n = 0.55) and the troughs between them give
    /// n back, and a parabolic last rise at the halt a quarter period early is left out
    /// (with the trough before it); read as a crest, it would move n.
    #[test]
    fn the_turns_timing_ends_at_the_last_crest() {
        use std::f64::consts::{PI, TAU};
        let (n, turns) = (0.55, 25);
        let q = 1.0 / (1.0 - n / 2.0);
        let c = 0.5 / (TAU * turns as f64).powf(q);
        let at = |psi: f64| 0.004 - c * (0.5 - psi).powf(q);
        let extremum = |t: f64, method| signal::Peak {
            index: 0,
            t,
            z: 1e-4,
            phi: 0.01,
            sigma_phi: None,
            psi_dot_local: None,
            sample: (t, 1e-4),
            parabolic: (t, 1e-4),
            prominence: 1e-4,
            method,
        };
        // Crests at ψ = −2π·25 … −2π, troughs half a turn after each, and the last
        // rise at the halt a quarter period before the crest at ψ = 0 it never reached.
        let crest_psi: Vec<f64> = (0..turns).map(|k| -TAU * (turns - k) as f64).collect();
        let mut crests: Vec<f64> = crest_psi.iter().map(|&p| at(p)).collect();
        let troughs: Vec<f64> = crest_psi.iter().map(|&p| at(p + PI)).collect();
        crests.push(at(0.0) - 0.25 * (at(0.0) - at(-TAU)));
        let series = |last: signal::ExtremumMethod| {
            let local = signal::ExtremumMethod::LocalFit;
            let peaks: Vec<signal::Peak> = crests
                .iter()
                .enumerate()
                .map(|(k, &t)| extremum(t, if k == turns { last } else { local }))
                .collect();
            let mut turning: Vec<(f64, bool)> = crests
                .iter()
                .map(|&t| (t, true))
                .chain(troughs.iter().map(|&t| (t, false)))
                .collect();
            turning.sort_by(|a, b| a.0.total_cmp(&b.0));
            PeakSeries {
                window: (-0.6, 0.0),
                precession: signal::precession(&crests, TAU),
                precession_half_turns: signal::precession_half_turns(&turning),
                peaks,
                troughs: troughs
                    .iter()
                    .map(|&t| signal::Trough {
                        index: 0,
                        t,
                        method: local,
                    })
                    .collect(),
            }
        };
        let fit = turn_timing_fit(&series(signal::ExtremumMethod::Parabolic)).expect("fit");
        assert_eq!(fit.points, 2 * turns - 1);
        assert!((fit.n - n).abs() < 1e-6, "n = {}", fit.n);
        let as_crest = turn_timing_fit(&series(signal::ExtremumMethod::LocalFit)).expect("fit");
        assert_eq!(as_crest.points, 2 * turns + 1);
        assert!((as_crest.n - n).abs() > 1e-3, "n = {}", as_crest.n);
    }

    /// The halt seen 20 ms (nearly 10 frames) after the law's, as an encoder showing
    /// earlier pictures again after the halt makes it: the bound lies between the
    /// law's t0 and t_φ, within three standard errors and a frame of t0. Seen where
    /// the law has it, or before it (the last motion too small to see), no bound.
    #[test]
    fn a_halt_seen_after_the_laws_is_bounded_by_it() {
        let frame_s = 1.0 / 480.0;
        let late = sighted_peaks_fit(-0.020, -0.023);
        assert!(late.fit.halt_sighting.is_some_and(|s| !s.combined));
        let fits = Fits {
            peaks: late,
            frames: None,
            full_state: None,
            turns: Err("not timed".into()),
        };
        let bound = law_bound(&fits, None, frame_s).expect("a bound").bound;
        let t0 = fits.peaks.fit.t0;
        let se = fits.peaks.fit.se_t0.expect("t0 free");
        assert!((t0 + 0.020).abs() < 3.0 * se, "t0 {t0}");
        assert!(bound > t0 && bound < 0.0, "bound {bound}, t0 {t0}");
        assert!((bound - (t0 + 3.0 * se + frame_s)).abs() < 1e-12);
        for t0 in [0.001, 0.006] {
            let fits = Fits {
                peaks: sighted_peaks_fit(t0, -0.002),
                frames: None,
                full_state: None,
                turns: Err("not timed".into()),
            };
            assert_eq!(law_bound(&fits, None, frame_s), None, "t0 {t0}");
        }
        // The peaks fit agreeing with the halt seen (spurious low peaks after the halt
        // pull its free t0 onto them) does not hide the per-frame fit's disagreement.
        let frames = sighted_peaks_fit(-0.020, -0.023);
        let frames_t0 = frames.fit.t0 + 3.0 * frames.fit.se_t0.expect("t0 free") + frame_s;
        let fits = Fits {
            peaks: sighted_peaks_fit(0.001, -0.002),
            frames: Some(frames),
            full_state: None,
            turns: Err("not timed".into()),
        };
        assert_eq!(
            law_bound(&fits, None, frame_s).map(|b| b.bound),
            Some(frames_t0)
        );
    }

    /// The turns' timing law bounds the halt seen where the energies barely fix t0:
    /// a peaks fit whose t0 agrees with the halt seen (its own σ wide), and turns that
    /// end 12 ± 1 ms before it, bound the motion at T + 3σ + one frame. Turns ending
    /// where the halt is seen, no bound.
    #[test]
    fn a_halt_seen_after_the_turns_end_is_bounded_by_them() {
        let frame_s = 1.0 / 480.0;
        let turns = |t_end: f64| TurnTimingFit {
            n: 0.55,
            ci95_n: (0.54, 0.56),
            se_n: 0.005,
            se_n_least_squares: 0.005,
            se_n_jackknife: 0.005,
            t_end,
            se_t_end: 0.001,
            remaining_psi: 1.0,
            c: 1e-3,
            times: Vec::new(),
            psi: Vec::new(),
            points: 40,
            residual_rms_s: 1e-4,
        };
        let fits = Fits {
            peaks: sighted_peaks_fit(0.001, -0.002),
            frames: None,
            full_state: None,
            turns: Err("not timed".into()),
        };
        assert_eq!(law_bound(&fits, None, frame_s), None);
        let bound = law_bound(&fits, Some(&turns(-0.012)), frame_s).expect("a bound");
        assert_eq!(bound.law, "the turns' timing law");
        assert!((bound.bound - (-0.012 + 0.003 + frame_s)).abs() < 1e-12);
        assert_eq!(law_bound(&fits, Some(&turns(-0.001)), frame_s), None);
    }

    #[test]
    fn the_light_plates_zero_is_the_rest_tails_median_reading() {
        // A clip whose rest tail (48 frames) reads 0.03 px above the zero pass 1
        // gave, but for a codec refresh 0.3 px high over 12 of them, and whose
        // lifted frames read the rim 0.03 px high too: the median moves the zero by
        // the tail's 0.03 px, whatever the refresh.
        let tail = rest_tail_frames(480.0);
        assert_eq!(tail, 48);
        let truth: Vec<f64> = (0..100)
            .map(|k| 3.0 * (1.0 - k as f64 / 60.0).max(0.0))
            .collect();
        let mut heights: Vec<Option<f64>> = truth.iter().map(|z| Some(z + 0.03)).collect();
        for z in heights[70..82].iter_mut().flatten() {
            *z += 0.3;
        }
        heights[10] = None;
        let shift = tail_median_shift(&mut heights, tail);
        assert!((shift - 0.03).abs() < 1e-12, "shift {shift}");
        assert_eq!(heights[10], None);
        for (k, z) in heights
            .iter()
            .enumerate()
            .filter(|(k, _)| !(70..82).contains(k))
        {
            if let Some(z) = z {
                assert!(
                    (z - truth[k]).abs() < 1e-12,
                    "frame {k}: {z} against {}",
                    truth[k]
                );
            }
        }
        // Fewer readings in the tail than the rest frames: the zero stays.
        let mut few: Vec<Option<f64>> = vec![None; 60];
        few[59] = Some(0.2);
        assert_eq!(tail_median_shift(&mut few, tail), 0.0);
        assert_eq!(few[59], Some(0.2));
    }
}
