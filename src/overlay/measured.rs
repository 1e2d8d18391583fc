//! What `analyse` measured, drawn on the frames it came from: `overlay.mp4` (a span
//! around the halt, slowed down) and `last-turns.png` (the frames at the last
//! peaks), with `overlay.json`, which says which clip frame each video frame shows
//! and where each window of the picture comes from.
//!
//! The frames come from what `analyse` kept while it read the clip
//! ([`super::keep`]); when it kept none of them (some formats, a span not kept)
//! the span is decoded again ([`FrameSource`], seeked to the span,
//! one frame in memory at a time). The video's frames are drawn on the
//! encoder's 4:2:0 samples ([`YuvCanvas`]), the contact sheet's in RGB, with the
//! same marks. Each shows:
//!
//! * the side view around the disk and, enlarged, the centre band around the rim
//!   edge (the rows z_rim is read on);
//! * the band's columns (blue), the plate line z_base (red, beside the band), the
//!   measured rim edge (green, at the row where z_rim = 0 less z_rim; see
//!   [`ExperimentPlan::rim_edge_row`]);
//! * a peak's height (magenta cross) on the frame nearest each detected peak;
//! * the halt frame t_φ (orange border) and flagged frames (red border, with the
//!   reason);
//! * on two-view clips, the plan view with the strip's mask outline (cyan) and its
//!   principal axis (yellow), with β (eq. 3.24) in the header.

use std::path::Path;

use image::{Rgb, RgbImage};
use serde::Serialize;

use super::OverlayError;
use super::canvas::{Canvas, Window, YuvCanvas, text_lines};
use super::keep::KeptFrames;
use crate::analyse::{Experiment, ExperimentPlan, LayoutGeometry, StripMark};
use crate::footage::Orientation;
use crate::footage::{FrameSource, FrameView};
use crate::output::{write_atomic, write_json};
use crate::render::{ChromaFilter, H264Settings, H264Writer, RateControl, SampleStorage};
use crate::signal::FrameFlag;
use crate::vision::{self, StripFinder};

/// The video's name in the experiment folder.
pub const OVERLAY_VIDEO: &str = "overlay.mp4";
/// The contact sheet's name in the experiment folder.
pub const LAST_TURNS_IMAGE: &str = "last-turns.png";
/// The index of the video's frames and windows.
pub const OVERLAY_INDEX: &str = "overlay.json";

const BAND: Rgb<u8> = Rgb([60, 140, 255]);
const PLATE: Rgb<u8> = Rgb([255, 40, 40]);
const RIM: Rgb<u8> = Rgb([0, 255, 0]);
const PEAK: Rgb<u8> = Rgb([255, 0, 255]);
const HALT: Rgb<u8> = Rgb([255, 150, 0]);
const FLAG: Rgb<u8> = Rgb([255, 40, 40]);
const STRIP: Rgb<u8> = Rgb([0, 220, 255]);
const AXIS: Rgb<u8> = Rgb([255, 220, 0]);
const TEXT: Rgb<u8> = Rgb([235, 235, 235]);
const LEGEND: Rgb<u8> = Rgb([150, 150, 150]);
pub(super) const BACKGROUND: Rgb<u8> = Rgb([20, 20, 20]);

/// Frames handed to the encoder's thread at a time.
const BATCH: usize = 8;
/// Header band above the picture [canvas px]: three lines of text.
const HEADER_PX: u32 = 62;
/// Text size in the header \[px\].
const TEXT_PX: u32 = 14;
/// Widest context (side, plan) view on the canvas before it is shrunk [canvas px].
const CONTEXT_PX: usize = 360;

/// Which part of a clip the overlay shows, and how slowly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OverlaySpec {
    /// Start and end of the span, t − t_φ \[s\] (default: the last 0.5 s before the
    /// halt and 0.1 s after it).
    pub span_s: (f64, f64),
    /// Frames per second the video plays at (default 30: a 480 fps clip plays
    /// 16 × slower than it happened).
    pub playback_fps: f64,
    /// Oscillations (peaks) on the contact sheet, the last ones before the halt.
    pub last_turns: usize,
}

impl Default for OverlaySpec {
    fn default() -> Self {
        Self {
            span_s: (-0.5, 0.1),
            playback_fps: 30.0,
            last_turns: 8,
        }
    }
}

/// H.264 settings of the overlays: libx264's fastest preset (the overlays are
/// looked at, not measured, and this keeps them a small part of `analyse`'s
/// time) at a constant quantiser of 20 (marks one pixel wide stay sharp; about
/// crf 20's size, without crf's per-frame complexity estimate, which took a
/// third of x264's time here). The overlays hand the
/// writer 4:2:0 samples (`overlay::canvas::YuvCanvas`), so the chroma filter is
/// libswscale's only for a frame given as RGB.
pub const OVERLAY_H264: H264Settings = H264Settings {
    rate: RateControl::Qp(20),
    keyint: None,
    bframes: None,
    preset: "ultrafast",
    chroma: ChromaFilter::FastBilinear,
    storage: SampleStorage {
        ten_bit: false,
        full_range: false,
        hdr: None,
    },
    orientation: Orientation::IDENTITY,
};

/// One video frame: the clip frame it shows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct OverlayFrame {
    /// Frame index in the clip (as `frames.csv`'s `index`).
    pub index: usize,
    /// t − t_φ \[s\].
    pub t: f64,
}

/// What [`write_measurement_overlays`] wrote, as `overlay.json`.
#[derive(Debug, Clone, Serialize)]
pub struct OverlayIndex {
    /// The video's file name.
    pub video: String,
    /// Its frame rate [frames/s].
    pub playback_fps: f64,
    /// How many times slower than it happened the video plays.
    pub slow_down: f64,
    /// The span asked for, t − t_φ \[s\].
    pub span_s: (f64, f64),
    /// Video frame k shows `frames[k]`.
    pub frames: Vec<OverlayFrame>,
    /// The contact sheet's file name and its tiles, in order (`None`: no peaks).
    pub last_turns: Option<(String, Vec<OverlayFrame>)>,
    /// Canvas size \[px\].
    pub width: u32,
    pub height: u32,
    /// Where each part of the picture comes from in the clip's frames.
    pub windows: Vec<Window>,
}

/// The windows of an overlay frame for an experiment: the side view around the
/// disk, the centre band enlarged beside it, the plan view below (two-view).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Layout {
    pub width: u32,
    pub height: u32,
    pub side: Window,
    pub band: Window,
    pub plan: Option<Window>,
}

impl Layout {
    /// Lays out the windows for `plan`, the band window tall enough for rim
    /// heights up to `z_max_px`.
    pub fn new(plan: &ExperimentPlan, z_max_px: f64) -> Self {
        Self::from_geometry(&LayoutGeometry::of(plan), z_max_px)
    }

    /// [`Self::new`] from the geometry alone.
    pub fn from_geometry(g: &LayoutGeometry, z_max_px: f64) -> Self {
        let c = &g.calibration;
        let (ox, oy) = g.origin;
        let (view_w, view_h) = g.view;
        let side_h = g.split_row.unwrap_or(view_h);
        let diameter = c.x_r - c.x_l;
        let thickness = c.z_base - c.z_t;
        let clamp = |v: f64, hi: usize| (v.max(0.0) as usize).min(hi);
        // The disk with room to lean (2R sin φ above the top rim at φ ≈ 20°) and
        // its mirror image or shadow below the plate line.
        let x0 = clamp((c.x_l - 0.12 * diameter).floor(), view_w - 1);
        let x1 = clamp((c.x_r + 0.12 * diameter).ceil(), view_w).max(x0 + 1);
        let y0 = clamp((c.z_t - 0.35 * diameter).floor(), side_h - 1);
        let y1 = clamp((c.z_base + 0.12 * diameter + thickness).ceil(), side_h).max(y0 + 1);
        // Side views wider than CONTEXT_PX are shrunk by a whole factor (their
        // size trimmed to a multiple of it), narrower ones enlarged up to 4 ×.
        let (zoom, shrink) = if x1 - x0 > CONTEXT_PX {
            (1, (x1 - x0).div_ceil(CONTEXT_PX))
        } else {
            ((CONTEXT_PX / (x1 - x0)).clamp(1, 4) as u32, 1)
        };
        let trim = |n: usize| (n - n % shrink).max(shrink);
        let (side_w, side_rows) = (trim(x1 - x0), trim(y1 - y0));
        let shrink = shrink as u32;
        let side = Window {
            name: "side view",
            src_x: ox + x0,
            src_y: oy + y0,
            width: side_w,
            height: side_rows,
            dst_x: 0,
            dst_y: HEADER_PX,
            zoom,
            shrink,
        };
        let (left_w, side_h_canvas) = side.canvas_size();
        let plan_window = g.split_row.map(|row| Window {
            name: "plan view",
            src_x: ox,
            src_y: oy + row,
            width: trim(view_w),
            height: trim(view_h - row),
            dst_x: 0,
            dst_y: HEADER_PX + side_h_canvas,
            zoom,
            shrink,
        });
        // The centre band at full resolution, enlarged: 8 columns either side,
        // from 5 px above the highest rim to 6 px below the rest edge.
        let zero = g.zero_row;
        let centre = c.x_centre().floor();
        let half = g.band_half_width_px as f64 + 8.0;
        let bx0 = clamp(centre - half, view_w - 1);
        let bx1 = clamp(centre + half + 1.0, view_w).max(bx0 + 1);
        let by0 = clamp((zero - z_max_px.max(4.0) - 5.0).floor(), side_h - 1);
        let by1 = clamp((zero + 6.0).ceil(), side_h).max(by0 + 1);
        let band_zoom = (side_h_canvas / (by1 - by0) as u32).clamp(2, 16);
        let band = Window {
            name: "centre band, enlarged",
            src_x: ox + bx0,
            src_y: oy + by0,
            width: bx1 - bx0,
            height: by1 - by0,
            dst_x: left_w + 4,
            dst_y: HEADER_PX,
            zoom: band_zoom,
            shrink: 1,
        };
        let even = |v: u32| v + v % 2;
        let (band_w, band_h) = band.canvas_size();
        let (plan_w, plan_h) = plan_window.map_or((0, 0), |p| p.canvas_size());
        let width = even((left_w + 4 + band_w).max(plan_w).max(480));
        let height = even(HEADER_PX + (side_h_canvas + plan_h).max(band_h));
        Self {
            width,
            height,
            side,
            band,
            plan: plan_window,
        }
    }

    /// The windows, for `overlay.json`.
    pub fn windows(&self) -> Vec<Window> {
        [Some(self.side), Some(self.band), self.plan]
            .into_iter()
            .flatten()
            .collect()
    }

    /// A blank canvas with the frame's windows painted in.
    pub fn paint(&self, frame: &FrameView) -> RgbImage {
        let mut image = RgbImage::from_pixel(self.width, self.height, BACKGROUND);
        for window in self.windows() {
            window.paint(frame, &mut image);
        }
        image
    }
}

/// What one frame's overlay shows beyond the picture.
struct FrameMarks<'a> {
    /// Position in [`Experiment::frames`].
    position: usize,
    /// Detected peaks nearest this frame: (peak number, height above the rest
    /// level \[m\], φ \[rad\]).
    peaks: Vec<(usize, f64, f64)>,
    halt: bool,
    flags: Vec<&'a FrameFlag>,
}

impl<'a> FrameMarks<'a> {
    /// The marks of the frame at `position` of `e.frames`; `peak_frames` as
    /// [`peak_positions`] gives them.
    fn of(e: &'a Experiment, position: usize, peak_frames: &[usize]) -> Self {
        let peaks = &e.series.peaks.peaks;
        Self {
            position,
            peaks: peak_frames
                .iter()
                .enumerate()
                .filter(|&(_, &k)| k == position)
                .map(|(n, _)| (n + 1, peaks[n].z, peaks[n].phi))
                .collect(),
            halt: position == e.series.halt.index,
            flags: e
                .series
                .flags
                .iter()
                .filter(|f| f.index == e.frames[position].index)
                .collect(),
        }
    }
}

/// Draws the span of the clip (from the frames `analyse` kept, else decoded
/// again) and writes `overlay.mp4`, `last-turns.png` and `overlay.json` into `dir`.
///
/// # Errors
/// The clip cannot be opened or decoded (it moved, or changed since it was
/// analysed: its frame times no longer match), no frame lies in the span, the
/// encoder fails, or a file cannot be written; each names the file.
pub fn write_measurement_overlays(
    dir: &Path,
    e: &Experiment,
    spec: &OverlaySpec,
    kept: Option<&KeptFrames>,
) -> Result<OverlayIndex, OverlayError> {
    let plan = &e.plan;
    let clip = &plan.clip;
    let in_span: Vec<usize> = (0..e.frames.len())
        .filter(|&k| e.frames[k].t >= spec.span_s.0 && e.frames[k].t <= spec.span_s.1)
        .collect();
    let (Some(&first), Some(&last)) = (in_span.first(), in_span.last()) else {
        return Err(OverlayError::EmptySpan {
            clip: clip.clone(),
            from: spec.span_s.0,
            to: spec.span_s.1,
        });
    };
    let turns = last_turns(e, &peak_positions(e), spec.last_turns);
    let start = turns.first().map_or(first, |&k| k.min(first));
    let z_max = in_span
        .iter()
        .chain(&turns)
        .filter_map(|&k| e.frames[k].z_rim_px)
        .fold(0.0, f64::max);
    let layout = Layout::new(plan, z_max);

    let video = dir.join(OVERLAY_VIDEO);
    let encode_err = |path: &Path| {
        let path = path.to_path_buf();
        move |reason: String| OverlayError::Encode {
            path: path.clone(),
            reason,
        }
    };
    // Frames are encoded on a second thread while the next ones are decoded and
    // drawn, handed over in batches (a thread woken for every frame cost 2 % of
    // `analyse`); two batches wait in the channel at most. The encoded canvases
    // come back to be drawn on again (new ones cost page faults).
    let (frames_out, frames_in) = std::sync::mpsc::sync_channel::<Vec<YuvCanvas>>(2);
    let (spent_out, spent_in) = std::sync::mpsc::channel::<Vec<YuvCanvas>>();
    let encoder = std::thread::spawn({
        let video = video.clone();
        let (width, height, fps) = (layout.width, layout.height, spec.playback_fps);
        move || -> Result<usize, String> {
            let mut writer = H264Writer::create(&video, width, height, fps, OVERLAY_H264)?;
            for batch in frames_in.iter() {
                for canvas in &batch {
                    writer.push_yuv420(canvas.planes())?;
                }
                // The drawing may have ended: the canvases are then dropped.
                let _ = spent_out.send(batch);
            }
            writer.finish()
        }
    });
    let video_out = VideoOut {
        frames: frames_out,
        spent: spent_in,
        batch: Vec::with_capacity(BATCH),
        free: Vec::new(),
    };
    let drawn = draw_span(e, kept, &layout, spec, (start, first, last), video_out);
    let encoded = encoder
        .join()
        .unwrap_or_else(|_| Err("the encoder thread panicked".into()))
        .map_err(encode_err(&video));
    let (shown, tiles) = match (drawn, encoded) {
        (Err(e), _) | (Ok(_), Err(e)) => return Err(e),
        (Ok(drawn), Ok(_)) => drawn,
    };
    if shown.len() != in_span.len() {
        return Err(OverlayError::Changed {
            clip: clip.clone(),
            reason: format!(
                "the span holds {} analysed frames, decoding again gave {}",
                in_span.len(),
                shown.len()
            ),
        });
    }
    let last_turns = if tiles.is_empty() {
        None
    } else {
        let sheet = super::last_turns::contact_sheet(&tiles, plan).map_err(|reason| {
            OverlayError::Draw {
                clip: clip.clone(),
                frame: tiles[0].0.index,
                reason,
            }
        })?;
        let bytes = crate::output::png_bytes(&sheet).map_err(|e| OverlayError::Encode {
            path: dir.join(LAST_TURNS_IMAGE),
            reason: e.to_string(),
        })?;
        write_atomic(&dir.join(LAST_TURNS_IMAGE), &bytes)?;
        Some((
            LAST_TURNS_IMAGE.to_string(),
            tiles.iter().map(|(r, _)| *r).collect(),
        ))
    };
    let index = OverlayIndex {
        video: OVERLAY_VIDEO.into(),
        playback_fps: spec.playback_fps,
        slow_down: plan.fps.fps / spec.playback_fps,
        span_s: spec.span_s,
        frames: shown,
        last_turns,
        width: layout.width,
        height: layout.height,
        windows: layout.windows(),
    };
    write_json(&dir.join(OVERLAY_INDEX), &index)?;
    Ok(index)
}

/// Frames shown in the video, and the contact sheet's tiles.
type DrawnSpan = (Vec<OverlayFrame>, Vec<(OverlayFrame, RgbImage)>);

/// The drawing side of the encoder's thread: batches of canvases to encode,
/// and the canvases it encoded, to draw on again.
struct VideoOut {
    frames: std::sync::mpsc::SyncSender<Vec<YuvCanvas>>,
    spent: std::sync::mpsc::Receiver<Vec<YuvCanvas>>,
    batch: Vec<YuvCanvas>,
    free: Vec<YuvCanvas>,
}

impl VideoOut {
    /// A canvas to draw the next frame on: one the encoder is done with, else a
    /// new one.
    fn canvas(&mut self) -> YuvCanvas {
        if self.free.is_empty() {
            while let Ok(spent) = self.spent.try_recv() {
                self.free.extend(spent);
            }
        }
        self.free.pop().unwrap_or_default()
    }

    /// Queues a drawn frame; `false` if the encoder stopped (its error is the one
    /// to report).
    fn push(&mut self, canvas: YuvCanvas) -> bool {
        self.batch.push(canvas);
        self.batch.len() < BATCH || self.flush()
    }

    fn flush(&mut self) -> bool {
        let batch = std::mem::replace(&mut self.batch, Vec::with_capacity(BATCH));
        self.frames.send(batch).is_ok()
    }
}

/// Draws the frames at positions `start..=last`, from the frames `analyse` kept
/// or else decoded again, sends those from `first` on to `video` (drawn on its
/// 4:2:0 samples), and keeps the contact sheet's (drawn in RGB).
fn draw_span(
    e: &Experiment,
    kept: Option<&KeptFrames>,
    layout: &Layout,
    spec: &OverlaySpec,
    (start, first, last): (usize, usize, usize),
    mut video: VideoOut,
) -> Result<DrawnSpan, OverlayError> {
    let plan = &e.plan;
    let clip = &plan.clip;
    let peak_frames = peak_positions(e);
    let turns = last_turns(e, &peak_frames, spec.last_turns);
    let slow_down = plan.fps.fps / spec.playback_fps;
    let mut tiles = Vec::new();
    let mut shown = Vec::new();
    // Draws the frame at `position` on the video's canvas (`paint_video`) and,
    // for the contact sheet, on an RGB image (`paint_tile`); `false` once the
    // encoder stopped.
    let mut each = |position: usize,
                    paint_video: &mut dyn FnMut(&mut YuvCanvas),
                    paint_tile: &mut dyn FnMut() -> RgbImage,
                    strip: Option<StripMark>|
     -> Result<bool, OverlayError> {
        let marks = FrameMarks::of(e, position, &peak_frames);
        let draw_err = |reason: String| OverlayError::Draw {
            clip: clip.clone(),
            frame: e.frames[position].index,
            reason,
        };
        let record = OverlayFrame {
            index: e.frames[position].index,
            t: e.frames[position].t,
        };
        if turns.contains(&position) {
            let mut image = paint_tile();
            draw_frame(e, layout, &mut image, &marks, strip.as_ref(), slow_down)
                .map_err(draw_err)?;
            tiles.push((record, image));
        }
        if position >= first {
            let mut canvas = video.canvas();
            paint_video(&mut canvas);
            draw_frame(e, layout, &mut canvas, &marks, strip.as_ref(), slow_down)
                .map_err(draw_err)?;
            shown.push(record);
            if !video.push(canvas) {
                return Ok(false);
            }
        }
        Ok(true)
    };
    if let Some(kept) = kept
        && let Some(frames) = kept.span((start, last), layout)
    {
        for frame in frames {
            let paint_video = &mut |canvas: &mut YuvCanvas| kept.paint_yuv(frame, layout, canvas);
            let paint_tile = &mut || kept.paint(frame, layout);
            if !each(frame.position, paint_video, paint_tile, frame.strip_mark())? {
                break;
            }
        }
    } else {
        let mut strip_finder = plan.colour_thresholds.map(|(t, s)| StripFinder::new(t, s));
        decode_positions(e, (start, last), layout, |position, view| {
            let strip = match (&layout.plan, strip_finder.as_mut()) {
                (Some(window), Some(finder)) => view
                    .crop(window.src_x, window.src_y, window.width, window.height)
                    .and_then(|plan_view| finder.measure(&plan_view, e.frames[position].index).ok())
                    .map(|strip| StripMark {
                        strip,
                        mask: finder.strip_mask(),
                    }),
                _ => None,
            };
            let image = layout.paint(view);
            let paint_video = &mut |canvas: &mut YuvCanvas| canvas.set_rgb(&image);
            let paint_tile = &mut || image.clone();
            each(position, paint_video, paint_tile, strip)
        })?;
    }
    // An encoder that stopped reports its own error.
    video.flush();
    Ok((shown, tiles))
}

/// Decodes the clip's frames at positions `first..=last` of `e.frames` again,
/// converting only the columns `layout`'s windows show, and calls `each(position,
/// frame)` on each in order until it returns `false`.
///
/// # Errors
/// The clip cannot be decoded, or it changed since it was analysed; whatever
/// `each` returns.
pub(super) fn decode_positions(
    e: &Experiment,
    (first, last): (usize, usize),
    layout: &Layout,
    mut each: impl FnMut(usize, &FrameView) -> Result<bool, OverlayError>,
) -> Result<(), OverlayError> {
    let mut source = FrameSource::open(&e.plan.clip)?;
    // Only the windows' columns are converted from the codec's colours.
    let columns = layout
        .windows()
        .iter()
        .map(|w| w.src_x..w.src_x + w.width)
        .reduce(|a, b| a.start.min(b.start)..a.end.max(b.end));
    source.convert_only_columns(columns)?;
    let matcher = FrameMatcher::new(e, first, last);
    // A seek lands by time on a nearby frame: start a few frames early (by the
    // time the container lists for that frame, else by number / average fps),
    // and from the beginning if it still landed late.
    let early = e.frames[first].index.saturating_sub(8);
    match source.stream_index()? {
        Some(index) if early < index.container_times_s.len() => source.seek_frame(early, &index)?,
        _ => source.seek(early)?,
    }
    let mut landed = false;
    while let Some(frame) = source.next_frame()? {
        let position = match matcher.locate(e, frame.index, frame.container_time_s)? {
            Match::Before => continue,
            Match::After => break,
            Match::At(position) if !landed && position > first => {
                // Landed past the first frame: read the clip from its start.
                landed = true;
                source.seek(0)?;
                continue;
            }
            Match::At(position) => position,
        };
        landed = true;
        if !each(position, &frame.view)? || position == last {
            break;
        }
    }
    Ok(())
}

/// The position in [`Experiment::frames`] of the frame nearest each peak.
pub(super) fn peak_positions(e: &Experiment) -> Vec<usize> {
    let nearest = |t: f64| {
        let k = e
            .frames
            .partition_point(|f| f.t < t)
            .min(e.frames.len() - 1);
        if k > 0 && (e.frames[k - 1].t - t).abs() <= (e.frames[k].t - t).abs() {
            k - 1
        } else {
            k
        }
    };
    e.series.peaks.peaks.iter().map(|p| nearest(p.t)).collect()
}

/// The positions of the last `n` peaks' frames up to the halt, oldest first.
pub(super) fn last_turns(e: &Experiment, peak_frames: &[usize], n: usize) -> Vec<usize> {
    let before: Vec<usize> = peak_frames
        .iter()
        .copied()
        .filter(|&k| e.frames[k].t <= 0.0)
        .collect();
    before[before.len().saturating_sub(n)..].to_vec()
}
/// Where a decoded frame stands against the frames wanted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Match {
    /// Before the first one wanted.
    Before,
    /// The analysed frame at this position of [`Experiment::frames`].
    At(usize),
    /// After the last one wanted.
    After,
}

/// Finds which analysed frame a decoded frame is: by the container's timestamp
/// when both have one (a seek lands by time, which stays right where the
/// container skips frames and an index would not), else by its index (frame
/// folders, whose index is exact).
struct FrameMatcher {
    /// (container time \[s\], position) of the frames wanted, in order; empty
    /// without timestamps.
    stamps: Vec<(f64, usize)>,
    /// Half the shortest interval between them \[s\].
    tolerance: f64,
    first: usize,
    last: usize,
}

impl FrameMatcher {
    /// For the frames at positions `first..=last` of `e`.
    fn new(e: &Experiment, first: usize, last: usize) -> Self {
        let stamps: Vec<(f64, usize)> = (first..=last)
            .filter_map(|k| Some((e.frames[k].container_time_s?, k)))
            .collect();
        let stamps = if stamps.len() == last + 1 - first {
            stamps
        } else {
            Vec::new()
        };
        let tolerance = 0.5
            * stamps
                .windows(2)
                .map(|w| w[1].0 - w[0].0)
                .fold(1.0, f64::min);
        Self {
            stamps,
            tolerance,
            first,
            last,
        }
    }

    /// Where the decoded frame `index` with container time `time_s` stands.
    ///
    /// # Errors
    /// `Changed` when a timed frame among the wanted ones matches none of them.
    fn locate(
        &self,
        e: &Experiment,
        index: usize,
        time_s: Option<f64>,
    ) -> Result<Match, OverlayError> {
        let (Some(t), Some(&(t0, _)), Some(&(t1, _))) =
            (time_s, self.stamps.first(), self.stamps.last())
        else {
            return Ok(if index < self.first {
                Match::Before
            } else if index > self.last {
                Match::After
            } else {
                Match::At(index)
            });
        };
        if t < t0 - self.tolerance {
            return Ok(Match::Before);
        }
        if t > t1 + self.tolerance {
            return Ok(Match::After);
        }
        let k = self.stamps.partition_point(|s| s.0 < t - self.tolerance);
        match self.stamps.get(k) {
            Some(&(s, position)) if (s - t).abs() <= self.tolerance => Ok(Match::At(position)),
            _ => Err(OverlayError::Changed {
                clip: e.plan.clip.clone(),
                reason: format!(
                    "a frame at {t:.6} s (container time) matches none of the frames analysed"
                ),
            }),
        }
    }
}

/// Draws one overlay frame's marks and header on `image`, its windows painted.
fn draw_frame(
    e: &Experiment,
    layout: &Layout,
    image: &mut impl Canvas,
    marks: &FrameMarks,
    strip: Option<&StripMark>,
    slow_down: f64,
) -> Result<(), String> {
    let plan = &e.plan;
    let c = &plan.calibration.calibration;
    let record = &e.frames[marks.position];
    let (ox, oy) = plan.side_view_origin();
    let (ox, oy) = (ox as f64, oy as f64);
    let (b0, b1) = vision::band(
        c.x_centre(),
        plan.band_half_width_px,
        plan.side_view_width(),
    );
    let (b0, b1) = (b0 as f64 + ox, b1 as f64 + ox);
    for (window, line) in [(&layout.side, 1.0), (&layout.band, 2.0)] {
        let top = window.src_y as f64;
        let bottom = top + window.height as f64;
        window.column_line(image, b0, (top, bottom), line, BAND);
        window.column_line(image, b1, (top, bottom), line, BAND);
        let plate = c.z_base + oy;
        window.row_line(image, plate, (c.x_l + ox, b0 - 1.0), line, PLATE);
        window.row_line(image, plate, (b1 + 1.0, c.x_r + ox), line, PLATE);
        if let Some(z) = record.z_rim_px {
            let row = plan.rim_edge_row(z) + oy;
            window.row_line(image, row, (b0 - 2.0, b1 + 2.0), line, RIM);
        }
        for &(_, z, _) in &marks.peaks {
            let z_px = (z + e.series.halt.rest_level) / plan.metres_per_px;
            let at = (c.x_centre() + ox, plan.rim_edge_row(z_px) + oy);
            window.cross(image, at, 4.0 * line, PEAK);
        }
    }
    let mut beta = None;
    if let (Some(window), Some(StripMark { strip, mask })) = (&layout.plan, strip) {
        if let Some((mask, w)) = mask {
            window.outline(image, (mask, *w), (window.src_x, window.src_y), STRIP);
        }
        // The principal axis through the centroid, β counter-clockwise from
        // the image's x axis with image up (eq. 3.24), 1.2 strip lengths long.
        let length = 1.2 * 12f64.sqrt() * strip.axes_sd_px[0];
        let (dx, dy) = (
            0.5 * length * strip.beta.cos(),
            -0.5 * length * strip.beta.sin(),
        );
        let [cx, cy] = strip.centroid_px;
        let (cx, cy) = (cx + window.src_x as f64, cy + window.src_y as f64);
        window.segment(image, (cx - dx, cy - dy), (cx + dx, cy + dy), AXIS);
        beta = Some(strip.beta);
    }

    let name = plan
        .clip
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let mut lines = vec![(
        format!(
            "{name}  frame {}  t − t_φ = {:+.1} ms  ({slow_down:.0}× slower)",
            record.index,
            1e3 * record.t
        ),
        TEXT,
    )];
    let mut measured = match (record.z_rim_px, record.z_rim_m) {
        (Some(px), Some(m)) => format!("z_rim = {px:.2} px = {:.3} mm", 1e3 * m),
        _ => "z_rim: no rim edge found".into(),
    };
    if let Some(beta) = beta {
        measured.push_str(&format!("   β = {:.1}°", beta.to_degrees()));
    }
    lines.push((measured, TEXT));
    let mut events = Vec::new();
    for &(n, z, phi) in &marks.peaks {
        events.push((
            format!(
                "PEAK {n}: z = {:.2} px above rest, φ = {:.2}°",
                z / plan.metres_per_px,
                phi.to_degrees()
            ),
            PEAK,
        ));
    }
    if marks.halt {
        events.push(("HALT t_φ: the last frame of motion".into(), HALT));
    }
    for flag in &marks.flags {
        events.push((format!("FLAGGED: {}", flag.reason.label()), FLAG));
    }
    match events.first() {
        Some(&(_, colour)) => {
            let text: Vec<String> = events.iter().map(|(t, _)| t.clone()).collect();
            lines.push((text.join("; "), colour));
        }
        None => lines.push((
            "blue: band · red: plate z_base · green: rim edge · magenta: peak".into(),
            LEGEND,
        )),
    }
    text_lines(image, (8, 4), TEXT_PX, &lines)?;
    let border = if !marks.flags.is_empty() {
        Some(FLAG)
    } else if marks.halt {
        Some(HALT)
    } else {
        None
    };
    if let Some(colour) = border {
        let (w, h) = image.size();
        let (w, h) = (f64::from(w), f64::from(h));
        image.fill_box((0.0, w), (0.0, 4.0), colour);
        image.fill_box((0.0, w), (h - 4.0, h), colour);
        image.fill_box((0.0, 4.0), (4.0, h - 4.0), colour);
        image.fill_box((w - 4.0, w), (4.0, h - 4.0), colour);
    }
    Ok(())
}

/// For tests: the positions in `e.frames` of the frames in `spec`'s span, and the
/// layout for the span's highest rim.
#[cfg(test)]
pub(super) fn span_and_layout(e: &Experiment, spec: &OverlaySpec) -> (Vec<usize>, Layout) {
    let span: Vec<usize> = (0..e.frames.len())
        .filter(|&k| (spec.span_s.0..=spec.span_s.1).contains(&e.frames[k].t))
        .collect();
    let z_max = span
        .iter()
        .filter_map(|&k| e.frames[k].z_rim_px)
        .fold(0.0, f64::max);
    let layout = Layout::new(&e.plan, z_max);
    (span, layout)
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::analyse::{Decoding, analyse_clip_keeping};
    use crate::config::ExperimentConfig;
    use crate::overlay::canvas::yuv420_of;

    /// `overlay.mp4`'s frames, painted from the kept samples and drawn on the
    /// encoder's 4:2:0 samples, are the RGB canvas (painted and drawn as the
    /// contact sheet's tiles are) converted, on the committed fixtures' spans:
    /// all but 1 in 10⁴ luma samples within 2 levels (the rest where x264's
    /// ringing puts the red strip's edge out of gamut, which RGB clamps channel
    /// by channel: 13 levels at most), all but 1 in 200 chroma samples within 2
    /// levels. The rest are where a mark covers part of a 2 × 2 block whose
    /// pixels differ in colour (the strip's outline on its red edge, the rim
    /// line across the plate line): the samples blend the block's mean colour by
    /// the mark's mean coverage, RGB blends each pixel, up to a quarter of the
    /// colours' difference apart (50 levels of Cr at the outline). The same on a
    /// rendered clip stored at full range, whose samples are recoded to the
    /// video's limited range first.
    #[test]
    fn frames_drawn_in_yuv_are_the_rgb_canvas_converted() {
        let dir = tempfile::tempdir().unwrap();
        let full_range = full_range_clip(dir.path());
        let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures");
        for (clip, config) in [
            (fixtures.join("side-dark-n050.mp4"), "fps = 480"),
            (
                fixtures.join("two-view-n045.mp4"),
                "fps = 480\ntwo_view = true",
            ),
            (full_range, "fps = 480"),
        ] {
            let fixture = clip.file_name().unwrap().to_string_lossy().into_owned();
            let config: ExperimentConfig = toml::from_str(config).unwrap();
            let spec = OverlaySpec::default();
            let (e, kept) =
                analyse_clip_keeping(&clip, &config, Decoding::Whole, Some(&spec), &|_, _| {})
                    .unwrap();
            let (span, layout) = span_and_layout(&e, &spec);
            let kept = kept.as_ref().expect("frames kept");
            assert_eq!(kept.recodes(), fixture == "full-range.mp4", "{fixture}");
            let frames = kept
                .span((span[0], span[span.len() - 1]), &layout)
                .expect("the span kept");
            let peak_frames = peak_positions(&e);
            let (mut planes, mut canvas) = (Default::default(), YuvCanvas::default());
            let mut histogram = [[0usize; 256]; 3];
            for frame in frames {
                let marks = FrameMarks::of(&e, frame.position, &peak_frames);
                let strip = frame.strip_mark();
                let mut image = kept.paint(frame, &layout);
                draw_frame(&e, &layout, &mut image, &marks, strip.as_ref(), 16.0).unwrap();
                yuv420_of(&image, &mut planes);
                kept.paint_yuv(frame, &layout, &mut canvas);
                draw_frame(&e, &layout, &mut canvas, &marks, strip.as_ref(), 16.0).unwrap();
                for (k, (a, b)) in planes.iter().zip(canvas.planes()).enumerate() {
                    assert_eq!(a.len(), b.len());
                    for (&a, &b) in a.iter().zip(b) {
                        histogram[k][usize::from(a.abs_diff(b))] += 1;
                    }
                }
            }
            for (k, h) in histogram.iter().enumerate() {
                let total: usize = h.iter().sum();
                let worst = h.iter().rposition(|&n| n > 0).unwrap();
                let within_2 = h[..=2].iter().sum::<usize>() as f64 / total as f64;
                eprintln!("{fixture}, plane {k}: {within_2:.5} within 2 levels, worst {worst}");
                let (share, most) = if k == 0 { (0.9999, 16) } else { (0.995, 64) };
                assert!(
                    within_2 >= share && worst <= most,
                    "{fixture}, plane {k}: {within_2:.5} of the samples within 2 levels, \
                     the worst {worst} levels off"
                );
            }
        }
    }

    /// A 480×320 clip rendered here (0.5 s to the halt), stored as full-range
    /// 8-bit samples (JPEG style): not the overlay video's coding.
    fn full_range_clip(dir: &Path) -> std::path::PathBuf {
        use crate::render::{
            DEFAULT_ENCODING, Plate, RenderSpec, Renderer, SampleStorage, test_motion, write_clip,
        };
        let motion = test_motion(480.0, 0.5, 0.15);
        let mut spec = RenderSpec::thesis(Plate::Dark, false);
        (spec.width, spec.height) = (480, 320);
        spec.storage = SampleStorage {
            ten_bit: false,
            full_range: true,
            hdr: None,
        };
        let renderer = Renderer::new(&spec, &motion).unwrap();
        let path = dir.join("full-range.mp4");
        write_clip(&renderer, &path, DEFAULT_ENCODING).unwrap().clip
    }
}
