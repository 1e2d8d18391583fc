//! Frame times on the capture clock: the container's per-frame timestamps where a
//! clip has them, index / fps where it does not (issue 14 §2).
//!
//! A container's presentation timestamps run on the playback clock. A slow-motion
//! clip captured at 480 fps and stored for playback at 30 fps advances 1/30 s a
//! frame, so its timestamps are mapped to capture time by the slow-down factor
//! capture fps × (median timestamp interval): 16 there, 1 for a clip stored at its
//! capture rate. The mapping keeps what index / fps loses: a variable-frame-rate
//! clip whose timestamps skip 25 frames keeps the 26-frame interval, which
//! [`crate::signal::timestamp_gaps`] then flags, rather than closing it up and
//! compressing the motion's time.
//!
//! [`frame_times`] turns the timestamps the [`super::FrameSource`] lent out into
//! times and a [`FrameTiming`] for the plan (where the times came from, the median
//! and spread of the frame interval).

use serde::{Deserialize, Serialize};

use super::{CaptureFps, FpsSource};
use crate::signal::{mad_sigma, median};

/// A slow-down factor within this of 1 is a clip stored at its capture rate: its
/// timestamps are capture times as they stand (a phone's real-time clip jitters
/// by a few % about its nominal rate, which the median interval follows).
const SAME_CLOCK: f64 = 0.01;

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

/// How frames were timed, recorded in the plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameTiming {
    pub source: TimeSource,
    /// How: the mapping from the container's clock, or why there were no
    /// timestamps to use.
    pub detail: String,
    /// Container (playback) seconds per capture second: 16 for 480 fps stored at
    /// 30 fps, 1 when the container's clock is the capture clock (or with no
    /// timestamps).
    pub slowdown: f64,
    /// Median interval between consecutive frames, capture clock [s].
    pub median_interval_s: f64,
    /// Spread of the intervals: 1.4826 × their median absolute deviation [s].
    pub interval_spread_s: f64,
    /// Shortest interval [s].
    pub min_interval_s: f64,
    /// Longest interval [s] (a gap in the timestamps shows here).
    pub max_interval_s: f64,
}

/// The capture time of every frame from the first [s], and how it was found.
///
/// `container_times` holds each frame's container timestamp [s, playback clock]
/// in clip order. They are used when every frame has one and they increase;
/// otherwise frames are timed by index / `fps.fps`. When `fps` came from the
/// container's stored rate ([`FpsSource::ContainerFps`]: an average, which a gap
/// lowers), it is replaced by the rate of the median timestamp interval
/// ([`FpsSource::ContainerTimestamps`]) and its warning rewritten.
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

fn from_timestamps(stamps: &[f64], fps: &mut CaptureFps) -> (Vec<f64>, FrameTiming) {
    let intervals: Vec<f64> = stamps.windows(2).map(|w| w[1] - w[0]).collect();
    let median_stamp = median(&intervals);
    // To a micro-frame per second: 1 / (32 × 1/15360 s) is 480.0000000000017 in
    // floating point, and no container stores a rate finer than that.
    let file_rate = (1e6 / median_stamp).round() / 1e6;
    if fps.source == FpsSource::ContainerFps {
        let stored = fps.fps;
        fps.fps = file_rate;
        fps.source = FpsSource::ContainerTimestamps;
        fps.warnings = vec![format!(
            "no capture fps in the config or the container: timing frames by the \
             container's timestamps, {file_rate:.6} fps by their median interval (the \
             container's stored rate is {stored:.6} fps); if this is a slow-motion clip \
             stored for playback, set `fps` in the experiment config"
        )];
    }
    let mut slowdown = fps.fps * median_stamp;
    let detail = if (slowdown - 1.0).abs() <= SAME_CLOCK {
        slowdown = 1.0;
        format!(
            "container timestamps as they stand: the container's {file_rate:.6} fps (median \
             interval) is the capture rate {} fps within {} %",
            fps.fps,
            100.0 * SAME_CLOCK
        )
    } else {
        format!(
            "container timestamps ÷ {slowdown:.6}: stored at {file_rate:.6} fps (median \
             interval), captured at {} fps",
            fps.fps
        )
    };
    let times: Vec<f64> = stamps.iter().map(|t| (t - stamps[0]) / slowdown).collect();
    let capture: Vec<f64> = intervals.iter().map(|d| d / slowdown).collect();
    let median_interval_s = median(&capture);
    let timing = FrameTiming {
        source: TimeSource::ContainerPts,
        detail,
        slowdown,
        median_interval_s,
        interval_spread_s: mad_sigma(&capture, median_interval_s),
        min_interval_s: capture.iter().copied().fold(f64::INFINITY, f64::min),
        max_interval_s: capture.iter().copied().fold(0.0, f64::max),
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
}
