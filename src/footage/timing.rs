//! Frame times on the capture clock: the container's per-frame timestamps where a
//! clip has them, index / fps where it does not (issue 14 §2).
//!
//! A container's presentation timestamps run on the playback clock. A slow-motion
//! clip captured at 480 fps and stored for playback at 30 fps advances 1/30 s a
//! frame, so its timestamps are mapped to capture time by the slow-down factor
//! capture fps × (timestamp interval): 16 there, 1 for a clip stored at its
//! capture rate. The mapping keeps what index / fps loses: a variable-frame-rate
//! clip whose timestamps skip 25 frames keeps the 26-frame interval, which
//! [`crate::signal::timestamp_gaps`] then flags, rather than closing it up and
//! compressing the motion's time.
//!
//! # Sections
//!
//! A phone's slow-motion clip changes its playback rate inside the clip: real-time
//! ramps stored at the capture rate (1/240 s a frame) around a slowed section stored
//! for playback at 30 fps (1/30 s a frame), every one of whose frames is still
//! 1/240 s of capture. The model:
//!
//! * every interval between consecutive frames is one capture interval, 1/fps (a
//!   longer one, a gap, is as many as it spans: frames missing);
//! * the timestamps fall into [`TimeSection`]s of constant interval: a running
//!   median over [`SECTION_MEDIAN_SPAN`] intervals (blind to a phone's jitter of a
//!   few % and to a gap of a few frames) starts a new section where it leaves the
//!   current section's first value by more than [`SECTION_TOLERANCE`];
//! * each section has its own slow-down factor fps × (its mean interval, gaps left
//!   out), and its intervals are divided by it: capture time is continuous across
//!   sections.
//!
//! A clip stored at one rate is one section. An analysis needs its fit window, and
//! its rest tail, each inside one section ([`FrameTiming::within_one_section`]): a
//! rate that changes within the window would time it by a boundary found only to
//! within the running median's few frames. With no capture fps given (the
//! container's average rate, [`FpsSource::ContainerFps`]), the fastest section is
//! taken to be real time. A phone that keeps only every n-th capture in its
//! real-time ramps, stored at the same interval as its slowed frames, leaves no
//! trace in the timestamps: this model cannot tell such ramps from the slowed
//! section.
//!
//! [`frame_times`] turns the timestamps the [`super::FrameSource`] lent out into
//! times and a [`FrameTiming`] for the plan (where the times came from, the
//! sections, the median and spread of the frame interval); [`time_sections`] finds
//! the sections alone (for `eulerdisk info`).

use serde::{Deserialize, Serialize};

use super::{CaptureFps, FpsSource};
use crate::numeric::{mad_sigma, median};

/// A slow-down factor within this of 1 is a section stored at its capture rate:
/// its timestamps are capture times as they stand (a phone's real-time clip
/// jitters by a few % about its nominal rate, which the mean interval follows).
const SAME_CLOCK: f64 = 0.01;

/// Intervals in the running median that finds sections: 4 on either side, so a
/// section of 5 frames or more is found exactly, and up to 4 jittered or gapped
/// intervals among 9 leave it unmoved.
pub const SECTION_MEDIAN_SPAN: usize = 9;

/// A running median more than this fraction from the current section's first
/// value starts a new section. Phones jitter by a few %; slow motion changes the
/// interval 2× or more (30 fps playback of 60 fps capture).
pub const SECTION_TOLERANCE: f64 = 0.2;

/// An interval more than this fraction longer (or shorter) than its section's
/// median is a gap (frames missing), left out of the section's mean interval.
const GAP_EXCESS: f64 = 0.5;

/// Where an analysis's frame times came from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeSource {
    /// The container's presentation timestamps, mapped to capture time.
    ContainerPts,
    /// Frame index / capture fps.
    IndexOverFps,
}

impl TimeSource {
    /// "container pts" or "index / fps".
    pub fn label(&self) -> &'static str {
        match self {
            TimeSource::ContainerPts => "container pts",
            TimeSource::IndexOverFps => "index / fps",
        }
    }
}

/// A run of frames whose container timestamps keep one interval (see the module
/// doc): one slow-down factor maps them to capture time. Consecutive sections
/// share their boundary frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TimeSection {
    /// The section's first frame (0-based, in the clip as stored).
    pub first_frame: usize,
    /// Its last frame: the next section's first.
    pub last_frame: usize,
    /// Container time of the first frame from the clip's first [s, playback clock].
    pub container_start_s: f64,
    /// Container time of the last frame from the clip's first [s, playback clock].
    pub container_end_s: f64,
    /// Mean interval between its frames, gaps left out [s, playback clock].
    pub container_interval_s: f64,
    /// Capture time of the first frame from the clip's first \[s\].
    pub start_s: f64,
    /// Capture time of the last frame from the clip's first \[s\].
    pub end_s: f64,
    /// Container (playback) seconds per capture second: fps × the mean interval,
    /// 1 within 1 % (a section stored at the capture rate).
    pub slowdown: f64,
}

impl std::fmt::Display for TimeSection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "frames {}–{}: t = {:.4}–{:.4} s captured, {:.4}–{:.4} s in the container, \
             {:.4} ms a frame ({:.3} fps), {}",
            self.first_frame,
            self.last_frame,
            self.start_s,
            self.end_s,
            self.container_start_s,
            self.container_end_s,
            1e3 * self.container_interval_s,
            1.0 / self.container_interval_s,
            if self.slowdown == 1.0 {
                "real time".to_string()
            } else {
                format!("slowed {:.3}×", self.slowdown)
            }
        )
    }
}

/// How frames were timed, recorded in the plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameTiming {
    pub source: TimeSource,
    /// How: the mapping from the container's clock, or why there were no
    /// timestamps to use.
    pub detail: String,
    /// Container (playback) seconds per capture second of the clip's last section
    /// (where the disk halts; see `sections` for the others): 16 for 480 fps
    /// stored at 30 fps, 1 when the container's clock is the capture clock (or
    /// with no timestamps).
    pub slowdown: f64,
    /// The sections of constant frame interval, in clip order (one for a clip
    /// stored at one rate; empty without timestamps or in results written before
    /// sections were recorded).
    #[serde(default)]
    pub sections: Vec<TimeSection>,
    /// Median interval between consecutive frames, capture clock \[s\].
    pub median_interval_s: f64,
    /// Spread of the intervals: 1.4826 × their median absolute deviation \[s\].
    pub interval_spread_s: f64,
    /// Shortest interval \[s\].
    pub min_interval_s: f64,
    /// Longest interval \[s\] (a gap in the timestamps shows here).
    pub max_interval_s: f64,
}

impl FrameTiming {
    /// Whether capture times `start_s..=end_s` [s from the clip's first frame]
    /// lie in one section (the first section reaches back before the clip, the
    /// last on after it); always for frames timed by index / fps.
    pub fn within_one_section(&self, start_s: f64, end_s: f64) -> bool {
        let last = self.sections.len().saturating_sub(1);
        self.sections.is_empty()
            || self
                .sections
                .iter()
                .enumerate()
                .any(|(k, s)| (k == 0 || s.start_s <= start_s) && (k == last || end_s <= s.end_s))
    }

    /// The sections, separated by "; ", for an error message or the report.
    pub fn sections_text(&self) -> String {
        let lines: Vec<String> = self.sections.iter().map(ToString::to_string).collect();
        lines.join("; ")
    }
}

/// The capture time of every frame from the first \[s\], and how it was found.
///
/// `container_times` holds each frame's container timestamp [s, playback clock]
/// in clip order. They are used when every frame has one and they increase;
/// otherwise frames are timed by index / `fps.fps`. When `fps` came from the
/// container's stored rate ([`FpsSource::ContainerFps`]: an average, which a gap
/// or a slowed section lowers), it is replaced by the rate of the fastest
/// section's mean interval ([`FpsSource::ContainerTimestamps`]) and its warning
/// rewritten.
pub fn frame_times(
    container_times: &[Option<f64>],
    fps: &mut CaptureFps,
) -> (Vec<f64>, FrameTiming) {
    match usable_timestamps(container_times) {
        Ok(stamps) => from_timestamps(&stamps, fps),
        Err(why) => {
            let times: Vec<f64> = (0..container_times.len())
                .map(|i| i as f64 / fps.fps)
                .collect();
            let period = 1.0 / fps.fps;
            let timing = FrameTiming {
                source: TimeSource::IndexOverFps,
                detail: format!("frame index / {} fps: {why}", fps.fps),
                slowdown: 1.0,
                sections: Vec::new(),
                median_interval_s: period,
                interval_spread_s: 0.0,
                min_interval_s: period,
                max_interval_s: period,
            };
            (times, timing)
        }
    }
}

/// Every frame's timestamp when all have one and they increase, else why not.
fn usable_timestamps(container_times: &[Option<f64>]) -> Result<Vec<f64>, String> {
    if container_times.len() < 2 {
        return Err(format!(
            "{} frame(s), too few for timestamps",
            container_times.len()
        ));
    }
    if container_times.iter().all(Option::is_none) {
        return Err("no per-frame timestamps (a frame folder, or a container without them)".into());
    }
    let mut stamps = Vec::with_capacity(container_times.len());
    for (i, t) in container_times.iter().enumerate() {
        let Some(t) = *t else {
            return Err(format!("the container gives no timestamp for frame {i}"));
        };
        if let Some(&previous) = stamps.last()
            && t <= previous
        {
            return Err(format!(
                "frame {i}'s timestamp {t} s does not come after frame {}'s {previous} s",
                i - 1
            ));
        }
        stamps.push(t);
    }
    Ok(stamps)
}

/// The sections of constant interval of increasing container timestamps `stamps`
/// [s, playback clock] (at least two), each mapped to capture time at
/// `capture_fps` (see the module doc).
pub fn time_sections(stamps: &[f64], capture_fps: f64) -> Vec<TimeSection> {
    let intervals: Vec<f64> = stamps.windows(2).map(|w| w[1] - w[0]).collect();
    let n = intervals.len();
    let half = SECTION_MEDIAN_SPAN / 2;
    let running: Vec<f64> = (0..n)
        .map(|i| median(&intervals[i.saturating_sub(half)..(i + half + 1).min(n)]))
        .collect();
    // Interval ranges [a, b) of the sections.
    let mut starts = vec![0];
    let mut reference = running[0];
    for (i, &m) in running.iter().enumerate().skip(1) {
        if (m / reference - 1.0).abs() > SECTION_TOLERANCE {
            starts.push(i);
            reference = m;
        }
    }
    starts.push(n);
    let mut sections = Vec::with_capacity(starts.len() - 1);
    let mut start_s = 0.0;
    for w in starts.windows(2) {
        let (a, b) = (w[0], w[1]);
        // The mean interval: a jitter about a steady clock cancels in it, where a
        // median of a few hundred jittered intervals can stand 1 % off. Gaps
        // (frames missing) are left out.
        let typical = median(&intervals[a..b]);
        let steady: Vec<f64> = intervals[a..b]
            .iter()
            .copied()
            .filter(|d| (d / typical - 1.0).abs() <= GAP_EXCESS)
            .collect();
        let container_interval_s = steady.iter().sum::<f64>() / steady.len() as f64;
        let mut slowdown = capture_fps * container_interval_s;
        if (slowdown - 1.0).abs() <= SAME_CLOCK {
            slowdown = 1.0;
        }
        let end_s = start_s + (stamps[b] - stamps[a]) / slowdown;
        sections.push(TimeSection {
            first_frame: a,
            last_frame: b,
            container_start_s: stamps[a] - stamps[0],
            container_end_s: stamps[b] - stamps[0],
            container_interval_s,
            start_s,
            end_s,
            slowdown,
        });
        start_s = end_s;
    }
    sections
}

fn from_timestamps(stamps: &[f64], fps: &mut CaptureFps) -> (Vec<f64>, FrameTiming) {
    // To a micro-frame per second: 1 / (32 × 1/15360 s) is 480.0000000000017 in
    // floating point, and no container stores a rate finer than that.
    let rate = |interval: f64| (1e6 / interval).round() / 1e6;
    if fps.source == FpsSource::ContainerFps {
        let fastest = time_sections(stamps, 1.0)
            .iter()
            .map(|s| s.container_interval_s)
            .fold(f64::INFINITY, f64::min);
        let stored = fps.fps;
        fps.fps = rate(fastest);
        fps.source = FpsSource::ContainerTimestamps;
        fps.warnings = vec![format!(
            "no capture fps in the config or the container: timing frames by the \
             container's timestamps, {:.6} fps by the mean interval of their fastest \
             section (the container's stored rate is {stored:.6} fps); if this is a \
             slow-motion clip stored for playback, set `fps` in the experiment config",
            fps.fps
        )];
    }
    let sections = time_sections(stamps, fps.fps);
    let detail = match sections.as_slice() {
        [one] if one.slowdown == 1.0 => format!(
            "container timestamps as they stand: the container's {:.6} fps (mean \
             interval) is the capture rate {} fps within {} %",
            rate(one.container_interval_s),
            fps.fps,
            100.0 * SAME_CLOCK
        ),
        [one] => format!(
            "container timestamps ÷ {:.6}: stored at {:.6} fps (mean interval), captured \
             at {} fps",
            one.slowdown,
            rate(one.container_interval_s),
            fps.fps
        ),
        _ => format!(
            "container timestamps in {} sections of constant interval, each ÷ its slow-down \
             factor, captured at {} fps (every interval one capture interval)",
            sections.len(),
            fps.fps
        ),
    };
    let mut times = Vec::with_capacity(stamps.len());
    let mut capture = Vec::with_capacity(stamps.len() - 1);
    times.push(0.0);
    for s in &sections {
        for i in s.first_frame..s.last_frame {
            let d = (stamps[i + 1] - stamps[i]) / s.slowdown;
            capture.push(d);
            times.push(s.start_s + (stamps[i + 1] - stamps[s.first_frame]) / s.slowdown);
        }
    }
    let median_interval_s = median(&capture);
    let timing = FrameTiming {
        source: TimeSource::ContainerPts,
        detail,
        slowdown: sections.last().map_or(1.0, |s| s.slowdown),
        median_interval_s,
        interval_spread_s: mad_sigma(&capture, median_interval_s),
        min_interval_s: capture.iter().copied().fold(f64::INFINITY, f64::min),
        max_interval_s: capture.iter().copied().fold(0.0, f64::max),
        sections,
    };
    (times, timing)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fps(value: f64, source: FpsSource) -> CaptureFps {
        CaptureFps {
            fps: value,
            source,
            warnings: vec!["old".into()],
        }
    }

    /// 40 frames at `stored` fps with frames 10..35 missing, timestamps kept.
    fn gapped(stored: f64) -> Vec<Option<f64>> {
        (0..65)
            .filter(|i| !(10..35).contains(i))
            .map(|i| Some(f64::from(i) / stored))
            .collect()
    }

    #[test]
    fn a_gap_in_the_timestamps_stays_a_gap_on_the_capture_clock() {
        // 480 fps captured, stored for playback at 30 fps: ÷ 16.
        let mut capture = fps(480.0, FpsSource::Config);
        let (t, timing) = frame_times(&gapped(30.0), &mut capture);
        assert_eq!(timing.source, TimeSource::ContainerPts);
        assert!((timing.slowdown - 16.0).abs() < 1e-9);
        assert!((t[10] - 35.0 / 480.0).abs() < 1e-12, "{}", t[10]);
        assert!((t[39] - 64.0 / 480.0).abs() < 1e-12);
        assert!((timing.median_interval_s - 1.0 / 480.0).abs() < 1e-12);
        assert!(timing.interval_spread_s < 1e-12);
        assert!((timing.max_interval_s - 26.0 / 480.0).abs() < 1e-12);
        // The config's fps stands.
        assert_eq!((capture.fps, capture.warnings.len()), (480.0, 1));
    }

    #[test]
    fn a_stored_average_rate_gives_way_to_the_median_interval() {
        // The container's average over the gap: 40 frames in 65 frame times.
        let average = 40.0 / 65.0 * 480.0;
        let mut capture = fps(average, FpsSource::ContainerFps);
        let (t, timing) = frame_times(&gapped(480.0), &mut capture);
        assert!((capture.fps - 480.0).abs() < 1e-9, "{}", capture.fps);
        assert_eq!(capture.source, FpsSource::ContainerTimestamps);
        assert!(capture.warnings[0].contains("set `fps`"));
        assert_eq!(timing.slowdown, 1.0);
        assert!((t[10] - 35.0 / 480.0).abs() < 1e-12);
    }

    #[test]
    fn without_usable_timestamps_frames_are_timed_by_index() {
        let mut capture = fps(480.0, FpsSource::Config);
        for (stamps, why) in [
            (vec![None; 5], "no per-frame timestamps"),
            (
                vec![Some(0.0), Some(0.1), None, Some(0.3)],
                "no timestamp for frame 2",
            ),
            (vec![Some(0.0), Some(0.1), Some(0.1)], "does not come after"),
        ] {
            let (t, timing) = frame_times(&stamps, &mut capture);
            assert_eq!(timing.source, TimeSource::IndexOverFps);
            assert!(timing.detail.contains(why), "{}", timing.detail);
            assert_eq!(t.len(), stamps.len());
            assert!((t[2] - 2.0 / 480.0).abs() < 1e-15);
        }
    }

    /// Container times of 300 frames captured at 480 fps: intervals 0..100 and
    /// 200..300 stored at the capture rate, 100..200 slowed 16× (1/30 s), each
    /// interval scaled by `jitter(i)`.
    fn slowed_middle(jitter: impl Fn(usize) -> f64) -> Vec<Option<f64>> {
        let mut t = 0.0;
        let mut stamps = vec![Some(0.0)];
        for i in 0..299 {
            let stored = if (100..200).contains(&i) { 30.0 } else { 480.0 };
            t += jitter(i) / stored;
            stamps.push(Some(t));
        }
        stamps
    }

    #[test]
    fn a_slowed_section_is_timed_on_its_own_and_capture_time_runs_on() {
        let mut capture = fps(480.0, FpsSource::Config);
        let (t, timing) = frame_times(&slowed_middle(|_| 1.0), &mut capture);
        let found: Vec<(usize, usize, f64)> = timing
            .sections
            .iter()
            .map(|s| {
                (
                    s.first_frame,
                    s.last_frame,
                    (1e9 * s.slowdown).round() / 1e9,
                )
            })
            .collect();
        assert_eq!(
            found,
            vec![(0, 100, 1.0), (100, 200, 16.0), (200, 299, 1.0)]
        );
        for (i, t) in t.iter().enumerate() {
            assert!((t - i as f64 / 480.0).abs() < 1e-12, "frame {i}: {t}");
        }
        let middle = &timing.sections[1];
        assert!((middle.start_s - 100.0 / 480.0).abs() < 1e-12);
        assert!((middle.end_s - 200.0 / 480.0).abs() < 1e-12);
        assert!((middle.container_start_s - 100.0 / 480.0).abs() < 1e-12);
        assert!((middle.container_end_s - (100.0 / 480.0 + 100.0 / 30.0)).abs() < 1e-12);
        assert!((timing.median_interval_s - 1.0 / 480.0).abs() < 1e-12);
        assert_eq!(timing.slowdown, 1.0);
        // A window inside a section passes; one across a boundary does not.
        assert!(timing.within_one_section(0.25, 0.4));
        assert!(timing.within_one_section(-1.0, 0.2));
        assert!(!timing.within_one_section(0.15, 0.3));
        assert!(timing.sections_text().contains("frames 100–200"));
    }

    #[test]
    fn jitter_and_a_gap_leave_the_sections_where_they_are() {
        // ±4 % jitter on every interval, and a gap of 6 frames at interval 50.
        let jitter = |i: usize| {
            if i == 50 {
                6.0
            } else {
                1.0 + 0.04 * (2.1 * i as f64).sin()
            }
        };
        let mut capture = fps(480.0, FpsSource::Config);
        let (t, timing) = frame_times(&slowed_middle(jitter), &mut capture);
        let bounds: Vec<usize> = timing.sections.iter().map(|s| s.first_frame).collect();
        assert_eq!(bounds, vec![0, 100, 200]);
        assert!((timing.sections[1].slowdown - 16.0).abs() < 0.3);
        // The gap stays 6 capture intervals long, to the jitter's shift of the
        // mean interval (0.06 % here; the median's was 1.2 %).
        let gap = t[51] - t[50];
        assert!((gap * 480.0 / 6.0 - 1.0).abs() < 0.002, "{gap}");
    }

    #[test]
    fn without_a_capture_fps_the_fastest_section_is_real_time() {
        // The container's average rate: 300 frames over its 3.5 s.
        let mut capture = fps(85.0, FpsSource::ContainerFps);
        let (t, timing) = frame_times(&slowed_middle(|_| 1.0), &mut capture);
        assert!((capture.fps - 480.0).abs() < 1e-9, "{}", capture.fps);
        assert_eq!(capture.source, FpsSource::ContainerTimestamps);
        assert!(capture.warnings[0].contains("fastest section"));
        assert!((timing.sections[1].slowdown - 16.0).abs() < 1e-9);
        assert!((t[299] - 299.0 / 480.0).abs() < 1e-12);
    }
}
