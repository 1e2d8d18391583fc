//! Which frames pass 2 decodes: the whole clip, or a span at the end of a long
//! video, found from the container's index and grown back by key frames until it
//! holds the fits' motion and the rest tail.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::calibrate::RestCalibration;
use super::open::OpenedClip;
use super::series::{self, MeasuredSpan};
use super::{AnalyseError, FrameKeeping, SENSITIVITY_WINDOWS_S, measure};
use crate::config::ExperimentConfig;
use crate::footage;
use crate::model::params::DiskParams;

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
pub(super) struct SpanPlan {
    /// The index, when a span may be decoded (`None`: the whole clip is).
    pub(super) index: Option<footage::StreamIndex>,
    /// Capture time of every frame from the clip's first \[s\] (empty without index).
    pub(super) times: Vec<f64>,
    pub(super) clip_frames: usize,
    /// Why the whole clip is decoded, when it is.
    pub(super) whole_reason: String,
}

impl SpanPlan {
    /// Plan from the clip's `index` (the packets' timestamps, `None` for a frame
    /// folder or a video whose packets lack them): the whole clip when
    /// `decoding` is [`Decoding::Whole`], without an index, when the clip is at
    /// most [`WHOLE_CLIP_UP_TO_S`] long, or when the index does not list the
    /// `expected` frames.
    pub(super) fn new(
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
    pub(super) fn first_span(&self) -> usize {
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
    pub(super) fn earlier_start(
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
                let span_start = m.measured.frames.first().map_or(f64::INFINITY, |f| f.t);
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
    pub(super) fn check_frame(
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
    pub(super) fn decoded(&self, first: usize, attempts: usize, decoded: usize) -> DecodedSpan {
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

/// Measures and runs the signal stage on the span [`SpanPlan`] starts with, and on
/// earlier ones while [`SpanPlan::earlier_start`] asks for one: a span that failed
/// to analyse or misses motion the fits need is grown back, at least to twice its
/// length, until it starts at the clip's first frame.
///
/// # Errors
/// The last span's error: unreadable frames, no rim, the signal stage's.
/// Returns the last span's, its decoding and what its keeper kept.
#[allow(clippy::too_many_arguments)]
pub(super) fn measure_spans<K: FrameKeeping>(
    clip: &Path,
    opened: &mut OpenedClip,
    rest: &RestCalibration,
    config: &ExperimentConfig,
    params: &DiskParams,
    decoding: Decoding,
    keeping: Option<&K>,
    progress: &dyn Fn(usize, Option<usize>),
    partial: &mut super::Partial,
) -> Result<(MeasuredSpan, DecodedSpan, Option<K::Kept>), AnalyseError> {
    let window_s = config.window_s();
    let plan = SpanPlan::new(opened.index.take(), decoding, opened.expected, &opened.fps);
    let mut first = plan.first_span();
    let mut attempts = 1;
    let (span, kept) = loop {
        let result = measure::measure_frames(
            clip, opened, rest, &plan, first, config, params, keeping, progress,
        )
        .and_then(|(frames, kept)| {
            partial.heights = Some(series::rim_series_px(&frames.frames));
            series::signal_stage(clip, frames, rest.two_view, config, params).map(|m| (m, kept))
        });
        let earlier = match &result {
            Ok((m, _)) => plan.earlier_start(first, Some(m), window_s),
            Err(AnalyseError::Signal { .. } | AnalyseError::Clip { .. }) => {
                plan.earlier_start(first, None, window_s)
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
    let decoded = plan.decoded(first, attempts, span.measured.frames.len());
    Ok((span, decoded, kept))
}
