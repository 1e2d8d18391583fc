//! Open: the clip's frame source, its capture frame rate, its frame count and the
//! container's index, before any frame is decoded.

use std::path::Path;

use super::{AnalyseError, REST_FRAMES};
use crate::config::ExperimentConfig;
use crate::footage::{self, CaptureFps, FrameSource};

/// A clip opened for both passes: the rest frames at the end, then every frame of
/// a span from a key frame to the end.
pub(super) struct OpenedClip {
    pub(super) source: FrameSource,
    /// The capture frame rate: the config's, the container's capture tag, or its fps.
    pub(super) fps: CaptureFps,
    /// Frames in the clip.
    pub(super) expected: usize,
    /// The container's index (packet timestamps, read without decoding): the rest
    /// frames and a span near the end are sought by their listed times, which land
    /// on the frame asked for in a variable-rate clip, where index / average fps
    /// would not. `None` for a frame folder or packets without timestamps.
    pub(super) index: Option<footage::StreamIndex>,
}

/// Opens `clip` and resolves its capture frame rate (config, container tag,
/// container fps).
///
/// # Errors
/// Unreadable footage, no usable fps, or fewer frames than the rest frames need.
pub(super) fn open_clip(
    clip: &Path,
    config: &ExperimentConfig,
) -> Result<OpenedClip, AnalyseError> {
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
    let index = source.stream_index()?;
    Ok(OpenedClip {
        source,
        fps,
        expected,
        index,
    })
}
