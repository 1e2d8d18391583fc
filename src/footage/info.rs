//! Clip metadata as OpenCV reports it: `eulerdisk info CLIP`.
//!
//! [`probe`] opens a video with `videoio::VideoCapture` (or the first frame of a
//! frame folder with `imgcodecs`) and reports size, frame count, the fps stored in
//! the container, codec and backend, without decoding the whole clip. The frame
//! size and orientation are FFmpeg's, as every other command decodes them: the
//! displayed frame, after the display matrix's rotation and mirror.

use std::cmp::Ordering;
use std::fmt;
use std::path::{Path, PathBuf};

use opencv::core::Mat;
use opencv::prelude::*;
use opencv::{imgcodecs, videoio};
use serde::{Deserialize, Serialize};

use super::FootageError;
use super::capture_rate::{ContainerCaptureRate, container_capture_rate};
use super::colour::VideoSignal;
use super::decoder::VideoDecoder;
use super::orientation::Orientation;
use super::timing::{TimeSection, time_sections};
use crate::numeric::{mad_sigma, median};

/// Video containers that [`probe`] hands to OpenCV (lower case, no dot).
pub const VIDEO_EXTENSIONS: &[&str] = &["mp4", "m4v", "mov", "avi", "mkv"];

/// Frame image formats of a frame folder (lower case, no dot).
pub const FRAME_EXTENSIONS: &[&str] = &["png", "tif", "tiff", "jpg", "jpeg"];

/// A stored fps at or below this is taken to be a playback rate, not a capture rate:
/// phone slow-motion clips (240/480/960 fps) are stored for playback at 30 fps.
pub const LOW_FPS_LIMIT: f64 = 60.0;

/// What a clip is on disk.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClipKind {
    /// One video file, decoded by `videoio`.
    Video,
    /// A folder of still frames, read by `imgcodecs` in natural name order.
    FrameFolder,
}

impl fmt::Display for ClipKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Video => "video",
            Self::FrameFolder => "frame folder",
        })
    }
}

/// What OpenCV says about a clip. Pixel sizes are in px; times in seconds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClipInfo {
    /// The file or folder probed.
    pub path: PathBuf,
    pub kind: ClipKind,
    /// Frame width \[px\].
    pub width: u32,
    /// Frame height \[px\].
    pub height: u32,
    /// The display matrix's rotation and mirror (a phone's orientation tag), which
    /// every command applies: `width` × `height` is the displayed size.
    #[serde(default)]
    pub orientation: Orientation,
    /// A video's pixel format, bit depth, range, YUV matrix and transfer function
    /// (`None` for a frame folder): every command converts frames from it to 8-bit
    /// full-range colour.
    #[serde(default)]
    pub signal: Option<VideoSignal>,
    /// Frames in the clip (as the container states it; for a folder, the frame files).
    pub frame_count: u64,
    /// The fps stored in the container: often the playback rate, not the capture
    /// rate. `None` for a frame folder or a container without one.
    pub container_fps: Option<f64>,
    /// A capture rate the container stores beside its playback fps (Android's
    /// capture-fps tag, an iPhone's slowing edit list), when there is one.
    pub capture_rate: Option<ContainerCaptureRate>,
    /// `frame_count / container_fps` \[s\]: the playback duration.
    pub duration_s: Option<f64>,
    /// The intervals between the container's per-frame timestamps (what `analyse`
    /// times frames by), when every packet has one.
    #[serde(default)]
    pub timestamps: Option<TimestampSummary>,
    /// FOURCC of a video (`MJPG`, `avc1`, `hvc1`, …); image format of a folder (`PNG`).
    pub codec: String,
    /// The OpenCV backend that read it (`FFMPEG`, …; `imgcodecs` for a folder).
    pub backend: String,
    /// Things a user must know before analysing the clip (fps, odd sizes, …).
    pub warnings: Vec<String>,
}

impl fmt::Display for ClipInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let fps = match (self.container_fps, self.kind) {
            (Some(fps), _) => format!("{} (stored in the container)", number(fps)),
            (None, ClipKind::FrameFolder) => "none (a frame folder stores no fps)".into(),
            (None, ClipKind::Video) => "none (the container stores no fps)".into(),
        };
        let capture = self.capture_rate.as_ref().map_or_else(
            || "not stored in the container".into(),
            |r| format!("{} ({})", number(r.fps), r.source),
        );
        let duration = self.duration_s.map_or_else(
            || "unknown".into(),
            |d| format!("{} s at the stored fps", number(d)),
        );
        let timestamps = self
            .timestamps
            .as_ref()
            .map_or_else(|| "none per frame".into(), ToString::to_string);
        let rows = [
            ("path", self.path.display().to_string()),
            ("kind", self.kind.to_string()),
            ("size", format!("{} x {} px", self.width, self.height)),
            ("rotation", self.orientation.to_string()),
            (
                "signal",
                self.signal
                    .as_ref()
                    .map_or_else(|| "frame images (8-bit)".into(), ToString::to_string),
            ),
            ("frames", self.frame_count.to_string()),
            ("fps", fps),
            ("capture", capture),
            ("duration", duration),
            ("timestamps", timestamps),
            ("codec", self.codec.clone()),
            ("backend", self.backend.clone()),
        ];
        for (name, value) in rows {
            writeln!(f, "{name:<11}{value}")?;
        }
        for warning in &self.warnings {
            writeln!(f, "{:<11}{warning}", "warning")?;
        }
        Ok(())
    }
}

/// A number with at most three decimals and no trailing zeros: `30`, `29.97`, `0.104`.
fn number(x: f64) -> String {
    let s = format!("{x:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

/// Report what OpenCV says about a video file or a folder of frames.
///
/// Reads the container's metadata and decodes only the first frame (of a folder:
/// the first and last), so it is quick on long clips. Nothing is printed.
///
/// # Errors
/// [`FootageError::NotFound`] when nothing is at `path`; `UnknownExtension` for a
/// file that is not a video container; `EmptyFolder` for a folder without frames;
/// `Unreadable` when OpenCV cannot open the video or decode its first frame.
pub fn probe(path: &Path) -> Result<ClipInfo, FootageError> {
    let meta = FootageError::metadata(path)?;
    if meta.is_dir() {
        probe_folder(path)
    } else {
        probe_video(path)
    }
}

pub(super) fn lower_extension(path: &Path) -> Option<String> {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
}

fn probe_video(path: &Path) -> Result<ClipInfo, FootageError> {
    let ext = lower_extension(path).unwrap_or_default();
    if !VIDEO_EXTENSIONS.contains(&ext.as_str()) {
        return Err(FootageError::UnknownExtension {
            path: path.to_path_buf(),
            ext,
        });
    }
    // Size and orientation as `analyse` decodes them (FFmpeg's display matrix,
    // mirror flips included), so that the two commands agree. Opened first: it
    // silences FFmpeg's log, so an unreadable file is one error naming it, never
    // a raw FFmpeg line from OpenCV's open before it.
    let mut decoder = VideoDecoder::open(path)?;
    let cv = |e| opencv_error(path, e);
    let mut cap = open_capture(path)?;
    let mut first = Mat::default();
    if !cap.read(&mut first).map_err(cv)? || first.empty() {
        return Err(FootageError::unreadable(
            path,
            "the header opened but frame 0 could not be decoded (truncated or unsupported codec)",
        ));
    }
    let backend = cap.get_backend_name().map_err(cv)?;
    let fourcc = cap.get(videoio::CAP_PROP_FOURCC).map_err(cv)?;
    let stored_fps = cap.get(videoio::CAP_PROP_FPS).map_err(cv)?;
    let stored_count = cap.get(videoio::CAP_PROP_FRAME_COUNT).map_err(cv)?;

    let mut warnings = Vec::new();
    let frame_count = if stored_count.is_finite() && stored_count >= 1.0 {
        stored_count.round() as u64
    } else {
        // Some streams carry no frame count: count the frames, which reads (and
        // with FFmpeg decodes) the whole file.
        let mut n = 1;
        while cap.grab().map_err(cv)? {
            n += 1;
        }
        warnings.push(format!(
            "the container stores no frame count; {n} frames counted by decoding the file"
        ));
        n
    };
    let container_fps = (stored_fps.is_finite() && stored_fps > 0.0).then_some(stored_fps);
    let (width, height) = decoder.size();
    let orientation = decoder.orientation();
    let signal = Some(decoder.signal().clone());
    let capture_rate = container_capture_rate(path);
    match (container_fps, &capture_rate) {
        (_, Some(rate)) => warnings.push(format!(
            "the container stores a capture rate of {} fps ({}); analyses time frames \
             with it unless the experiment config sets `fps`",
            number(rate.fps),
            rate.source
        )),
        (Some(fps), None) if fps <= LOW_FPS_LIMIT => warnings.push(format!(
            "stored fps {} is probably the playback rate (phone slow-motion clips are \
             stored at 30 fps), not the capture rate: give the capture fps \
             (e.g. 240, 480, 960) in the experiment config",
            number(fps)
        )),
        (Some(_), None) => {}
        (None, None) => warnings.push(
            "the container stores no fps: give the capture fps in the experiment config".into(),
        ),
    }
    let timestamps = TimestampSummary::read(&mut decoder, capture_rate.as_ref().map(|r| r.fps))?;
    if let Some(stamps) = timestamps.as_ref().filter(|s| s.sections.len() > 1) {
        warnings.push(format!(
            "the frame interval changes inside the clip ({} sections, a slow-motion \
             section's start or end): `analyse` times each section by its own slow-down \
             and needs the fit window and the rest tail each inside one section",
            stamps.sections.len()
        ));
    } else if let (Some(stamps), Some(fps)) = (&timestamps, container_fps) {
        let by_stamps = 1.0 / stamps.median_interval_s;
        if (by_stamps / fps - 1.0).abs() > FPS_AGREEMENT {
            warnings.push(format!(
                "the stored fps {} is an average: the frames' timestamps are {} fps apart \
                 (median interval), with {} gap(s) of more than 1.5 intervals; `analyse` \
                 times frames by their timestamps",
                number(fps),
                number(by_stamps),
                stamps.gaps
            ));
        }
    }
    Ok(ClipInfo {
        path: path.to_path_buf(),
        kind: ClipKind::Video,
        width: width as u32,
        height: height as u32,
        orientation,
        signal,
        frame_count,
        container_fps,
        capture_rate,
        duration_s: container_fps.map(|fps| frame_count as f64 / fps),
        timestamps,
        codec: fourcc_string(fourcc),
        backend,
        warnings,
    })
}

/// Relative difference between the stored fps and the timestamps' rate above which
/// `info` warns: a variable frame rate or missing frames (one frame missing in 100
/// moves the average by 1 %).
const FPS_AGREEMENT: f64 = 0.005;

/// The intervals between a video's per-frame container timestamps, read from its
/// packets without decoding (`VideoDecoder::packet_stamps`, playback clock).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TimestampSummary {
    /// Median interval \[s\].
    pub median_interval_s: f64,
    /// 1.4826 × the intervals' median absolute deviation \[s\]: a phone's jitter.
    pub interval_spread_s: f64,
    /// Longest interval \[s\].
    pub max_interval_s: f64,
    /// Intervals longer than 1.5 × their section's median: frames missing there.
    pub gaps: usize,
    /// The sections of constant interval ([`time_sections`]), mapped to capture
    /// time at the container's capture rate when it stores one, else with the
    /// fastest section taken as real time.
    #[serde(default)]
    pub sections: Vec<TimeSection>,
}

impl TimestampSummary {
    /// The summary of an open video's packet timestamps, `None` when a packet has
    /// none or fewer than three frames have one; `capture_fps` maps the sections
    /// to capture time (`None`: the fastest section's rate).
    fn read(
        decoder: &mut VideoDecoder,
        capture_fps: Option<f64>,
    ) -> Result<Option<Self>, FootageError> {
        let Some(stamps) = decoder.packet_stamps()? else {
            return Ok(None);
        };
        let times: Vec<f64> = stamps.iter().map(|s| s.0).collect();
        let intervals: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
        if intervals.len() < 2 {
            return Ok(None);
        }
        let median_interval_s = median(&intervals);
        if median_interval_s <= 0.0 || intervals.iter().any(|&d| d <= 0.0) {
            return Ok(None);
        }
        let fastest = time_sections(&times, 1.0)
            .iter()
            .map(|s| s.container_interval_s)
            .fold(f64::INFINITY, f64::min);
        let sections = time_sections(&times, capture_fps.unwrap_or(1.0 / fastest));
        let gaps = sections
            .iter()
            .map(|s| {
                let own = median(&intervals[s.first_frame..s.last_frame]);
                intervals[s.first_frame..s.last_frame]
                    .iter()
                    .filter(|&&d| d > 1.5 * own)
                    .count()
            })
            .sum();
        Ok(Some(Self {
            median_interval_s,
            interval_spread_s: mad_sigma(&intervals, median_interval_s),
            max_interval_s: intervals.iter().copied().fold(0.0, f64::max),
            gaps,
            sections,
        }))
    }
}

impl fmt::Display for TimestampSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "median interval {} ms ({} fps), spread {} ms, longest {} ms, {} gap(s)",
            number(1e3 * self.median_interval_s),
            number(1.0 / self.median_interval_s),
            number(1e3 * self.interval_spread_s),
            number(1e3 * self.max_interval_s),
            self.gaps
        )?;
        if self.sections.len() > 1 {
            write!(
                f,
                "; {} sections of constant interval:",
                self.sections.len()
            )?;
            for section in &self.sections {
                write!(f, "\n{:<11}{section}", "")?;
            }
        }
        Ok(())
    }
}

/// The four characters of a FOURCC code as OpenCV returns it (a little-endian
/// `u32` stored in an `f64`), or `unknown` when the container gives none.
fn fourcc_string(code: f64) -> String {
    if !code.is_finite() || code <= 0.0 || code > f64::from(u32::MAX) {
        return "unknown".into();
    }
    let code = code as u32;
    let bytes = code.to_le_bytes();
    let text: String = bytes.iter().map(|&b| char::from(b)).collect();
    let text = text.trim_end_matches(['\0', ' ']);
    if !text.is_empty() && text.chars().all(|c| c.is_ascii_graphic() || c == ' ') {
        text.to_string()
    } else {
        format!("0x{code:08x}")
    }
}

/// Image format name of a frame extension: `PNG`, `TIFF`, `JPEG`.
fn frame_format(path: &Path) -> &'static str {
    match lower_extension(path).as_deref() {
        Some("png") => "PNG",
        Some("tif" | "tiff") => "TIFF",
        _ => "JPEG",
    }
}

fn probe_folder(dir: &Path) -> Result<ClipInfo, FootageError> {
    let frames = frame_files(dir)?;
    let (Some(first), Some(last)) = (frames.first(), frames.last()) else {
        return Err(FootageError::EmptyFolder {
            path: dir.to_path_buf(),
        });
    };
    let (width, height) = image_size(first)?;

    let mut warnings = Vec::new();
    let mut formats: Vec<&str> = frames.iter().map(|p| frame_format(p)).collect();
    formats.sort_unstable();
    formats.dedup();
    if formats.len() > 1 {
        warnings.push(format!("frames mix formats: {}", formats.join(", ")));
    }
    let last_size = image_size(last)?;
    if last_size != (width, height) {
        warnings.push(format!(
            "frame sizes differ: {} is {width} x {height} px, {} is {} x {} px",
            file_name(first),
            file_name(last),
            last_size.0,
            last_size.1
        ));
    }
    warnings
        .push("a frame folder stores no fps: give the capture fps in the experiment config".into());
    Ok(ClipInfo {
        path: dir.to_path_buf(),
        kind: ClipKind::FrameFolder,
        width,
        height,
        orientation: Orientation::IDENTITY,
        signal: None,
        frame_count: frames.len() as u64,
        container_fps: None,
        capture_rate: None,
        duration_s: None,
        timestamps: None,
        codec: formats.join("+"),
        backend: "imgcodecs".into(),
        warnings,
    })
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
}

/// Width and height \[px\] of one frame image, decoded by OpenCV.
fn image_size(path: &Path) -> Result<(u32, u32), FootageError> {
    let image = imgcodecs::imread(path, imgcodecs::IMREAD_UNCHANGED)
        .map_err(|e| FootageError::unreadable(path, format!("OpenCV: {}", e.message)))?;
    if image.empty() {
        return Err(FootageError::unreadable(
            path,
            "OpenCV could not decode this frame image",
        ));
    }
    Ok((image.cols().unsigned_abs(), image.rows().unsigned_abs()))
}

/// The frame images of a folder, in natural name order (`frame2` before `frame10`).
///
/// Frames are the files with a [`FRAME_EXTENSIONS`] extension (any case); other
/// files and hidden files (`.DS_Store`, `._frame1.png`) are skipped.
///
/// # Errors
/// `NotFound`, `EmptyFolder`, or `Unreadable` when the folder cannot be listed.
pub fn frame_files(dir: &Path) -> Result<Vec<PathBuf>, FootageError> {
    let entries = std::fs::read_dir(dir).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => FootageError::NotFound {
            path: dir.to_path_buf(),
        },
        _ => FootageError::unreadable(dir, e),
    })?;
    let mut frames = Vec::new();
    for entry in entries {
        let path = entry.map_err(|e| FootageError::unreadable(dir, e))?.path();
        let is_frame =
            lower_extension(&path).is_some_and(|ext| FRAME_EXTENSIONS.contains(&ext.as_str()));
        if is_frame && !file_name(&path).starts_with('.') && path.is_file() {
            frames.push(path);
        }
    }
    if frames.is_empty() {
        return Err(FootageError::EmptyFolder {
            path: dir.to_path_buf(),
        });
    }
    frames.sort_by(|a, b| natural_cmp(&file_name(a), &file_name(b)));
    Ok(frames)
}

/// Natural order of names: runs of digits compare as numbers, so `frame2 < frame10`.
///
/// Equal numbers with different zero padding (`frame01`, `frame1`) put the shorter
/// first, so only equal strings compare equal.
pub fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (mut a, mut b) = (a, b);
    loop {
        let (run_a, rest_a) = split_run(a);
        let (run_b, rest_b) = split_run(b);
        if run_a.is_empty() || run_b.is_empty() {
            return run_a.len().cmp(&run_b.len());
        }
        let digits = |s: &str| s.starts_with(|c: char| c.is_ascii_digit());
        let order = if digits(run_a) && digits(run_b) {
            let (trim_a, trim_b) = (run_a.trim_start_matches('0'), run_b.trim_start_matches('0'));
            trim_a
                .len()
                .cmp(&trim_b.len())
                .then_with(|| trim_a.cmp(trim_b))
                .then_with(|| run_a.len().cmp(&run_b.len()))
        } else {
            run_a.cmp(run_b)
        };
        if order != Ordering::Equal {
            return order;
        }
        (a, b) = (rest_a, rest_b);
    }
}

/// The leading run of `s` (all digits or all non-digits) and the rest.
fn split_run(s: &str) -> (&str, &str) {
    let is_digit = |c: char| c.is_ascii_digit();
    let leading_digit = s.starts_with(is_digit);
    let end = s
        .find(|c: char| is_digit(c) != leading_digit)
        .unwrap_or(s.len());
    s.split_at(end)
}

/// Open a video with FFmpeg when this OpenCV has it (the same decoder and frame
/// count on every machine), else with whatever backend OpenCV picks.
fn open_capture(path: &Path) -> Result<videoio::VideoCapture, FootageError> {
    let cv = |e| opencv_error(path, e);
    let has_ffmpeg = videoio::has_backend(videoio::VideoCaptureAPIs::CAP_FFMPEG).map_err(cv)?;
    let api = if has_ffmpeg {
        videoio::CAP_FFMPEG
    } else {
        videoio::CAP_ANY
    };
    let capture = videoio::VideoCapture::from_file(path, api).map_err(cv)?;
    if !capture.is_opened().map_err(cv)? {
        let backend = if has_ffmpeg {
            "FFmpeg"
        } else {
            "no OpenCV video backend"
        };
        return Err(FootageError::unreadable(
            path,
            format!(
                "{backend} could not open it (truncated, not a video, or an unsupported codec)"
            ),
        ));
    }
    Ok(capture)
}

fn opencv_error(path: &Path, e: opencv::Error) -> FootageError {
    FootageError::unreadable(path, format!("OpenCV: {}", e.message))
}

#[cfg(test)]
mod tests {
    use super::*;
    use opencv::core::{CV_8UC3, Point, Scalar, Size};
    use opencv::imgproc;

    /// Write an MJPG AVI of `n` frames, `w` x `h` px, stored at `fps`: a white disk
    /// moving across a black frame, so every frame differs.
    fn write_avi(path: &Path, w: i32, h: i32, n: i32, fps: f64) {
        let fourcc = videoio::VideoWriter::fourcc('M', 'J', 'P', 'G').unwrap();
        let mut writer =
            videoio::VideoWriter::new(path, fourcc, fps, Size::new(w, h), true).unwrap();
        assert!(writer.is_opened().unwrap(), "no MJPG writer in this OpenCV");
        for i in 0..n {
            let mut frame =
                Mat::new_rows_cols_with_default(h, w, CV_8UC3, Scalar::all(0.0)).unwrap();
            let centre = Point::new(8 + 4 * i, h / 2);
            imgproc::circle(
                &mut frame,
                centre,
                6,
                Scalar::all(255.0),
                -1,
                imgproc::LINE_8,
                0,
            )
            .unwrap();
            writer.write(&frame).unwrap();
        }
        writer.release().unwrap();
    }

    fn write_png(path: &Path, w: u32, h: u32) {
        image::RgbImage::from_fn(w, h, |x, y| image::Rgb([x as u8, y as u8, 128]))
            .save(path)
            .unwrap();
    }

    #[test]
    fn probe_reports_the_written_video_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("spin.avi");
        write_avi(&path, 160, 120, 25, 240.0);

        let info = probe(&path).unwrap();
        assert_eq!(info.path, path);
        assert_eq!(info.kind, ClipKind::Video);
        assert_eq!((info.width, info.height), (160, 120));
        assert_eq!(info.frame_count, 25);
        assert_eq!(info.container_fps, Some(240.0));
        // 25 frames at 240 fps; the only rounding is one f64 division.
        let duration = info.duration_s.unwrap();
        assert!((duration - 25.0 / 240.0).abs() < 1e-12, "{duration}");
        assert_eq!(info.codec, "MJPG");
        assert!(!info.backend.is_empty());
        // 240 fps is a capture rate: nothing to warn about.
        assert!(info.warnings.is_empty(), "{:?}", info.warnings);

        let table = info.to_string();
        assert!(table.contains("160 x 120 px"), "{table}");
        assert!(table.contains("240 (stored in the container)"), "{table}");
    }

    #[test]
    fn playback_fps_is_flagged() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("phone.avi");
        write_avi(&path, 64, 48, 10, 30.0);

        let info = probe(&path).unwrap();
        assert_eq!(info.container_fps, Some(30.0));
        assert_eq!(info.warnings.len(), 1, "{:?}", info.warnings);
        let warning = &info.warnings[0];
        assert!(warning.contains("playback rate"), "{warning}");
        assert!(warning.contains("experiment config"), "{warning}");
        assert!(
            info.to_string().contains("warning    stored fps 30"),
            "{info}"
        );
    }

    #[test]
    fn clip_info_serialises_to_json_and_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("spin.avi");
        write_avi(&path, 64, 48, 5, 480.0);
        let info = probe(&path).unwrap();

        let json = serde_json::to_string(&info).unwrap();
        assert!(json.contains(r#""kind":"video""#), "{json}");
        assert!(json.contains(r#""container_fps":480.0"#), "{json}");
        let back: ClipInfo = serde_json::from_str(&json).unwrap();
        assert_eq!(back, info);
    }

    #[test]
    fn frame_folder_is_listed_in_natural_order_and_probed() {
        let dir = tempfile::tempdir().unwrap();
        // Written out of order, so directory order cannot pass for sorted order.
        for i in [7, 12, 1, 10, 3, 2, 11, 5, 9, 4, 8, 6] {
            write_png(&dir.path().join(format!("frame{i}.png")), 40, 30);
        }
        std::fs::write(dir.path().join("notes.txt"), "not a frame").unwrap();
        std::fs::write(dir.path().join("._frame1.png"), "macOS metadata").unwrap();

        let names: Vec<String> = frame_files(dir.path())
            .unwrap()
            .iter()
            .map(|p| file_name(p))
            .collect();
        let expected: Vec<String> = (1..=12).map(|i| format!("frame{i}.png")).collect();
        assert_eq!(names, expected);

        let info = probe(dir.path()).unwrap();
        assert_eq!(info.kind, ClipKind::FrameFolder);
        assert_eq!((info.width, info.height), (40, 30));
        assert_eq!(info.frame_count, 12);
        assert_eq!(info.container_fps, None);
        assert_eq!(info.duration_s, None);
        assert_eq!(info.codec, "PNG");
        assert_eq!(info.backend, "imgcodecs");
        assert_eq!(info.warnings.len(), 1, "{:?}", info.warnings);
        assert!(info.warnings[0].contains("no fps"));
    }

    #[test]
    fn natural_order_compares_digit_runs_as_numbers() {
        assert_eq!(natural_cmp("frame2", "frame10"), Ordering::Less);
        assert_eq!(natural_cmp("frame10", "frame9"), Ordering::Greater);
        assert_eq!(natural_cmp("frame002", "frame10"), Ordering::Less);
        assert_eq!(natural_cmp("frame1", "frame01"), Ordering::Less);
        assert_eq!(natural_cmp("frame", "frame1"), Ordering::Less);
        assert_eq!(natural_cmp("a10b2", "a10b10"), Ordering::Less);
        assert_eq!(natural_cmp("take2_0005", "take10_0001"), Ordering::Less);
        assert_eq!(natural_cmp("x7.png", "x7.png"), Ordering::Equal);
    }

    /// The error is about `path` and its message names it.
    fn assert_names(err: &FootageError, path: &Path) {
        assert_eq!(err.path(), path);
        let message = err.to_string();
        assert!(message.contains(&path.display().to_string()), "{message}");
    }

    #[test]
    fn empty_folder_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("readme.txt"), "no frames here").unwrap();
        let err = probe(dir.path()).unwrap_err();
        assert!(matches!(err, FootageError::EmptyFolder { .. }), "{err:?}");
        assert_names(&err, dir.path());
    }

    #[test]
    fn missing_file_is_not_found() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("nowhere.mp4");
        let err = probe(&path).unwrap_err();
        assert!(matches!(err, FootageError::NotFound { .. }), "{err:?}");
        assert_names(&err, &path);
    }

    #[test]
    fn non_video_extension_is_rejected_before_opencv() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("config.toml");
        std::fs::write(&path, "fps = 480\n").unwrap();
        let err = probe(&path).unwrap_err();
        match &err {
            FootageError::UnknownExtension { ext, .. } => assert_eq!(ext, "toml"),
            other => panic!("expected UnknownExtension, got {other:?}"),
        }
        assert_names(&err, &path);
    }

    #[test]
    fn garbage_mp4_is_unreadable() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("garbage.mp4");
        let bytes: Vec<u8> = (0..4096u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 24) as u8)
            .collect();
        std::fs::write(&path, bytes).unwrap();
        let err = probe(&path).unwrap_err();
        assert!(matches!(err, FootageError::Unreadable { .. }), "{err:?}");
        assert_names(&err, &path);
    }

    #[test]
    fn truncated_mp4_is_unreadable() {
        let dir = tempfile::tempdir().unwrap();
        let whole = dir.path().join("whole.mp4");
        let fourcc = videoio::VideoWriter::fourcc('m', 'p', '4', 'v').unwrap();
        let size = Size::new(64, 48);
        let mut writer = videoio::VideoWriter::new(&whole, fourcc, 240.0, size, true).unwrap();
        assert!(writer.is_opened().unwrap(), "no mp4v writer in this OpenCV");
        for i in 0..20 {
            let frame =
                Mat::new_rows_cols_with_default(48, 64, CV_8UC3, Scalar::all(f64::from(i * 10)))
                    .unwrap();
            writer.write(&frame).unwrap();
        }
        writer.release().unwrap();
        assert_eq!(probe(&whole).unwrap().frame_count, 20);

        // The index (moov atom) is written last, so the first half has none.
        let bytes = std::fs::read(&whole).unwrap();
        let path = dir.path().join("truncated.mp4");
        std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
        let err = probe(&path).unwrap_err();
        assert!(matches!(err, FootageError::Unreadable { .. }), "{err:?}");
        assert_names(&err, &path);
    }

    #[test]
    fn fourcc_codes_read_as_text() {
        let mjpg = videoio::VideoWriter::fourcc('M', 'J', 'P', 'G').unwrap();
        assert_eq!(fourcc_string(f64::from(mjpg)), "MJPG");
        assert_eq!(fourcc_string(0.0), "unknown");
        assert_eq!(fourcc_string(f64::from(0x0102_0304_u32)), "0x01020304");
    }
}
