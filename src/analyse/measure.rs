//! Measure (pass 2): every frame of a span, streamed, read with the rest frames'
//! gauges: the rim height z_rim [px] on the centre line, the gap's darkness, the
//! top face's profile, the band window about the edge, the strip angle β of a
//! two-view clip, and the pixels that find repeated frames. Then, over the span:
//! the heights re-measured with the rim's edge model ([`super::rim_heights`]), the
//! repeated frames set aside, the near top rim, the scale (eq. 3.10) and the frame
//! times on the capture clock.

use std::path::Path;

use super::calibrate::RestCalibration;
use super::open::OpenedClip;
use super::rim_heights::{self, RimHeights};
use super::span::SpanPlan;
use super::views::{OwnedFrame, side_view};
use super::{
    AnalyseError, FrameKeeping, FrameRecord, KeepFrames, REST_FRAMES, ScaleReport, StripMark,
    TopRimLeaning,
};
use crate::config::ExperimentConfig;
use crate::footage::{
    self, CaptureFps, FootageError, Frame, FrameSource, FrameTiming, FrameView, RepeatedFrame,
};
use crate::model::params::DiskParams;
use crate::vision::{
    self, BandWindow, GapSample, Registration, RimHeight, SceneStrips, Strip, StripFinder,
    StripProfiles,
};

/// Every second pixel of every second row is compared with the neighbouring
/// frames' to find duplicated and interpolated frames (footage::RepeatGauge).
const REPEAT_SAMPLE_STEP: usize = 2;

/// The camera's RMS motion above which the report warns, and above which the clip
/// is refused \[px\].
const SHAKY_CAMERA_PX: f64 = 1.0;
const HAND_HELD_PX: f64 = 2.0;

/// A frame's rim height \[px\] and its edge's row \[px\].
type RimCrest = (f64, f64);

/// A repeated frame's readings, set aside: z_rim \[px\] and β \[rad\].
pub(super) type SetAside = (Option<f64>, Option<f64>);

/// What one frame gave: its z_rim \[px\], its rim's height and edge row when the
/// highest so far, and its strip (two-view).
type FrameRead = (Option<f64>, Option<RimCrest>, Option<Strip>);

/// What pass 2 read of a span, frame by frame.
pub(super) struct FrameReadings {
    /// One record per frame, its times still unset (NaN).
    pub(super) frames: Vec<FrameRecord>,
    /// The gap's darkness per frame (dark plate).
    pub(super) gaps: Vec<GapSample>,
    /// The top face's profile per frame (LeanGauge).
    pub(super) profiles: Vec<Vec<f32>>,
    /// The band window about each frame's edge (the rim's edge model).
    pub(super) windows: Vec<Option<BandWindow>>,
    /// The scene beside the disk per frame (vision::registration).
    pub(super) scene: Vec<StripProfiles>,
    pub(super) repeats: footage::RepeatGauge,
    /// Frames in which no rim edge was found.
    pub(super) no_edge: usize,
    /// The frame with the highest rim: its height, edge row and side view, for the
    /// threshold diagnostic.
    pub(super) highest: Option<(f64, f64, OwnedFrame)>,
}

/// A span measured, before the signal stage.
pub(super) struct MeasuredFrames {
    /// The frames, z_rim in px and m, capture times set.
    pub(super) frames: Vec<FrameRecord>,
    /// The capture rate after the frame times (their warnings).
    pub(super) fps: CaptureFps,
    pub(super) frame_times: FrameTiming,
    pub(super) warnings: Vec<String>,
    pub(super) highest: Option<(f64, f64, OwnedFrame)>,
    pub(super) rim: RimHeights,
    /// Duplicated and interpolated frames, and their readings (z_rim \[px\], β) set
    /// aside until the halt is known; after the signal stage only those in the
    /// motion, nothing set aside (`series::signal_stage`).
    pub(super) repeated: Vec<RepeatedFrame>,
    pub(super) set_aside: Vec<SetAside>,
    pub(super) top_rim_leaning: Option<TopRimLeaning>,
    pub(super) scale: ScaleReport,
    pub(super) metres_per_px: f64,
    /// The camera's motion against the scene, by which the heights were corrected.
    pub(super) registration: Option<Registration>,
}

/// Measures the frames of `opened` from `first` to the end ([`read_frames`]), then
/// their heights, scale and times; returns them and what the span's keeper kept.
///
/// # Errors
/// A frame cannot be read or measured, or no frame shows a rim edge.
#[allow(clippy::too_many_arguments)]
pub(super) fn measure_frames<K: FrameKeeping>(
    clip: &Path,
    opened: &mut OpenedClip,
    rest: &RestCalibration,
    plan_span: &SpanPlan,
    first: usize,
    config: &ExperimentConfig,
    params: &DiskParams,
    keeping: Option<&K>,
    progress: &dyn Fn(usize, Option<usize>),
) -> Result<(MeasuredFrames, Option<K::Kept>), AnalyseError> {
    let mut fps = opened.fps.clone();
    let (readings, kept) = read_frames(clip, opened, rest, plan_span, first, keeping, progress)?;
    let FrameReadings {
        mut frames,
        gaps,
        profiles,
        mut windows,
        scene,
        repeats,
        no_edge,
        highest,
    } = readings;
    let mut warnings = Vec::new();
    let registration = rim_heights::register(&mut frames, &mut windows, &scene, rest, fps.fps);
    drop(scene);
    if let Some(reason) = registration.as_ref().and_then(camera_motion_refusal) {
        return Err(AnalyseError::Clip {
            path: clip.to_path_buf(),
            reason,
        });
    }
    warnings.extend(registration.as_ref().and_then(camera_motion_warning));
    if let Some(gauge) = &rest.gauges.gap {
        warnings.extend(rim_heights::resolve_gap(&mut frames, gauge, &gaps));
    }
    let rim = rim_heights::remeasure(&mut frames, &windows, rest, fps.fps);
    let (repeated, set_aside) = set_repeats_aside(&mut frames, repeats);
    let top_rim_leaning = top_rim_leaning(&frames, &profiles, rest);
    drop(profiles);
    let scale = scale(rest, &rim, top_rim_leaning.as_ref(), config, params);
    warnings.extend(in_metres(&mut frames, &scale));
    warnings.extend(frames_without_edge(clip, no_edge, frames.len(), rest)?);
    let frame_times = set_capture_times(&mut frames, plan_span, first, &mut fps);
    warnings.splice(0..0, fps.warnings.iter().cloned());
    let measured = MeasuredFrames {
        frames,
        fps,
        frame_times,
        warnings,
        highest,
        rim,
        repeated,
        set_aside,
        top_rim_leaning,
        metres_per_px: scale.metres_per_px(),
        scale,
        registration,
    };
    Ok((measured, kept))
}

/// Sets the repeated frames of the span aside: duplicated and interpolated frames
/// show no capture of their own, so no rim height or strip angle from them reaches
/// the fits. Returns them, and their readings (z_rim \[px\], β), kept until the
/// halt is known (the signal stage).
fn set_repeats_aside(
    frames: &mut [FrameRecord],
    repeats: footage::RepeatGauge,
) -> (Vec<RepeatedFrame>, Vec<SetAside>) {
    let repeated = repeats.repeated(REST_FRAMES);
    let set_aside = repeated
        .iter()
        .map(|r| {
            let record = &mut frames[r.index];
            (record.z_rim_px.take(), record.beta_raw.take())
        })
        .collect();
    (repeated, set_aside)
}

/// Converts every height z_rim to metres at the `scale` (once, after every
/// correction of z_rim in px); a warning when the scale is not the near rim's.
fn in_metres(frames: &mut [FrameRecord], scale: &ScaleReport) -> Option<String> {
    let metres_per_px = scale.metres_per_px();
    for record in frames {
        record.z_rim_m = record.z_rim_px.map(|z| z * metres_per_px);
    }
    (!scale.at_near_rim()).then(|| format!("scale from the {}", scale.used))
}

/// A warning when `no_edge` of the span's `frames` showed no rim edge.
///
/// # Errors
/// None of them did: the threshold finds no rim on the centre line.
fn frames_without_edge(
    clip: &Path,
    no_edge: usize,
    frames: usize,
    rest: &RestCalibration,
) -> Result<Option<String>, AnalyseError> {
    if no_edge == frames {
        return Err(AnalyseError::Clip {
            path: clip.to_path_buf(),
            reason: format!(
                "no rim edge found on the centre line in any of the {frames} frames (γ = {:.1})",
                rest.calibration.threshold.gamma
            ),
        });
    }
    Ok((no_edge > 0).then(|| format!("no rim edge found in {no_edge} of {frames} frames")))
}

/// Pass 2's stream: the frames from `first` to the end, each read with the rest
/// frames' gauges. A side view reads only the band of columns about the centre
/// line, so only that band is converted to colour. Each frame is offered to the
/// span's keeper, if `keeping` makes one.
///
/// # Errors
/// A frame cannot be decoded, is not numbered as the container's index lists it,
/// or its side view cannot be cut.
fn read_frames<K: FrameKeeping>(
    clip: &Path,
    opened: &mut OpenedClip,
    rest: &RestCalibration,
    plan_span: &SpanPlan,
    first: usize,
    keeping: Option<&K>,
    progress: &dyn Fn(usize, Option<usize>),
) -> Result<(FrameReadings, Option<K::Kept>), AnalyseError> {
    let vision_err = |error| AnalyseError::Vision {
        path: clip.to_path_buf(),
        error,
    };
    let source = &mut opened.source;
    seek_span(source, plan_span, first, rest)?;
    let mut strip_finder = rest
        .colour_thresholds
        .as_ref()
        .map(|(t, s)| StripFinder::new(*t, *s));
    let mut keeper =
        keeping.and_then(|k| k.keeper(&rest.layout_geometry(), opened.fps.fps, source));
    let span_frames = opened.expected - first;
    let mut readings = FrameReadings::with_capacity(span_frames, rest);
    while let Some(frame) = source.next_frame()? {
        let index = frame.index;
        if first > 0 {
            plan_span.check_frame(clip, index, frame.container_time_s)?;
        }
        let (z_rim_px, new_highest, strip) = readings
            .read_frame(frame, rest, strip_finder.as_mut())
            .map_err(vision_err)?;
        if index % 256 == 0 {
            progress(index - first, Some(span_frames));
        }
        readings
            .repeats
            .push(source.brightness_samples(REPEAT_SAMPLE_STEP)?);
        if let Some(strips) = &rest.gauges.scene {
            readings.scene.push(read_scene(source, strips, rest.roi)?);
        }
        if let Some(keeper) = &mut keeper {
            let position = readings.frames.len() - 1;
            let finder = strip_finder.as_mut();
            offer(keeper, position, z_rim_px, source, finder, strip)?;
        }
        if let Some(crest) = new_highest {
            readings.keep_highest(clip, source, rest, index, crest)?;
        }
    }
    progress(readings.frames.len(), Some(span_frames));
    Ok((readings, keeper.and_then(KeepFrames::finish)))
}

/// One frame's scene beside the disk (vision::registration): the rows' means over
/// the `strips` of the side view (at the `roi`'s corner in the frame), from the
/// codec's luma plane where the decoder lends it, else from the frame converted
/// whole (a turned video, a frame folder).
///
/// # Errors
/// The frame cannot be converted whole.
fn read_scene(
    source: &mut FrameSource,
    strips: &SceneStrips,
    roi: Option<[u32; 4]>,
) -> Result<StripProfiles, FootageError> {
    let (x0, y0) = roi.map_or((0, 0), |r| (r[0] as usize, r[1] as usize));
    if let Some(yuv) = source.yuv420() {
        let (luma, stride) = yuv.planes[0];
        return Ok(strips.read(|y, columns| {
            let start = (y0 + y) * stride + x0;
            let row = &luma[start + columns.start..start + columns.end];
            row.iter().map(|&v| u32::from(v)).sum::<u32>() as f32 / row.len() as f32
        }));
    }
    let whole = source.whole_frame()?;
    Ok(strips.read(|y, columns| {
        columns
            .clone()
            .map(|x| whole.intensity(x0 + x, y0 + y))
            .sum::<f32>()
            / columns.len() as f32
    }))
}

/// Why a clip is refused whose camera moved by more than [`HAND_HELD_PX`] RMS: the
/// heights are corrected for the picture's vertical shift, but the band of columns
/// moves along the rim as far, and the rest frames, which give the heights' zero,
/// move too.
fn camera_motion_refusal(registration: &Registration) -> Option<String> {
    (registration.applied && registration.rms_px > HAND_HELD_PX).then(|| {
        format!(
            "the camera moves by {:.1} px RMS ({:.1} px at most) against the scene beside \
             the disk, more than the {HAND_HELD_PX} px the rim's band can follow (a camera \
             held by hand?): film from a tripod that does not stand on the table the disk \
             spins on",
            registration.rms_px, registration.peak_px
        )
    })
}

/// A warning when the camera moved by more than [`SHAKY_CAMERA_PX`] RMS: the
/// heights are corrected for the picture's vertical shift, but not for the band's
/// columns moving along the rim.
fn camera_motion_warning(registration: &Registration) -> Option<String> {
    if !registration.applied {
        return None;
    }
    (registration.rms_px > SHAKY_CAMERA_PX).then(|| {
        format!(
            "the camera moves by {:.2} px RMS ({:.1} px at most) against the scene beside \
             the disk: the rim heights are corrected for it, but the band of columns read \
             moves along the rim with it; a tripod would be better",
            registration.rms_px, registration.peak_px
        )
    })
}

/// Offers the frame just read (at `position` in the span) to the span's `keeper`,
/// with its raw z_rim \[px\] and the strip as measured; the strip's mask for the
/// outline is made only when the keeper keeps the frame.
///
/// # Errors
/// The frame cannot be lent whole.
fn offer<Keeper: KeepFrames>(
    keeper: &mut Keeper,
    position: usize,
    z_rim_px: Option<f64>,
    source: &mut FrameSource,
    strip_finder: Option<&mut StripFinder>,
    strip: Option<Strip>,
) -> Result<(), FootageError> {
    let mark = || {
        let finder = strip_finder?;
        Some(StripMark {
            strip: strip?,
            mask: finder.strip_mask(),
        })
    };
    keeper.offer(position, z_rim_px, source, mark)
}

/// Puts the clip's `source` at the span's `first` frame (by the container's index,
/// `plan_span`), or at the clip's start. A side view reads only the band of columns
/// about the centre line, so only that band is converted to colour.
///
/// # Errors
/// The seek fails.
fn seek_span(
    source: &mut FrameSource,
    plan_span: &SpanPlan,
    first: usize,
    rest: &RestCalibration,
) -> Result<(), FootageError> {
    match &plan_span.index {
        Some(index) if first > 0 => source.seek_frame(first, index)?,
        _ => source.seek(0)?,
    }
    if rest.split().is_none() {
        source.convert_only_columns(Some(band_columns(rest)))?;
    }
    Ok(())
}

/// The frame's columns a side view's gauges read: the rim gauge's band and the gap
/// gauge's \[px\].
fn band_columns(rest: &RestCalibration) -> std::ops::Range<usize> {
    let x = rest.roi.map_or(0, |r| r[0] as usize);
    let mut band = rest.gauges.rim.band_columns();
    if let Some(gap) = &rest.gauges.gap {
        let columns = gap.band_columns();
        band = band.start.min(columns.start)..band.end.max(columns.end);
    }
    x + band.start..x + band.end
}

impl FrameReadings {
    /// Empty readings for `frames` frames, with room for the gauges `rest` has.
    fn with_capacity(frames: usize, rest: &RestCalibration) -> Self {
        let room = |used: bool| if used { frames } else { 0 };
        let gauges = &rest.gauges;
        FrameReadings {
            frames: Vec::with_capacity(frames),
            gaps: Vec::with_capacity(room(gauges.gap.is_some())),
            profiles: Vec::with_capacity(room(gauges.lean.is_some())),
            windows: Vec::with_capacity(room(gauges.rest_window.is_some())),
            scene: Vec::with_capacity(room(gauges.scene.is_some())),
            repeats: footage::RepeatGauge::new(),
            no_edge: 0,
            highest: None,
        }
    }

    /// Keeps the frame whose rim is the highest so far (`crest`), for the threshold
    /// diagnostic: its whole side view, so the columns outside the band are
    /// converted too.
    ///
    /// # Errors
    /// The frame cannot be converted whole, or its side view cannot be cut.
    fn keep_highest(
        &mut self,
        clip: &Path,
        source: &mut FrameSource,
        rest: &RestCalibration,
        index: usize,
        (z_rim_px, edge_row): RimCrest,
    ) -> Result<(), AnalyseError> {
        let whole = source.whole_frame()?;
        let side = side_view(&whole, rest.roi, rest.split(), index)
            .map_err(|error| AnalyseError::Vision {
                path: clip.to_path_buf(),
                error,
            })?
            .0;
        self.highest = Some((z_rim_px, edge_row, OwnedFrame::copy(index, &side)));
        Ok(())
    }

    /// Reads one `frame`: its side view with every gauge ([`Self::read_side`]) and,
    /// in a two-view clip, the strip on its plan view with the `strip_finder`; adds
    /// its record (times still unset). Returns its z_rim \[px\], its rim's height
    /// and edge row when the highest so far, and its strip.
    fn read_frame(
        &mut self,
        frame: Frame,
        rest: &RestCalibration,
        strip_finder: Option<&mut StripFinder>,
    ) -> Result<FrameRead, vision::VisionError> {
        let index = frame.index;
        let (side, plan) = side_view(&frame.view, rest.roi, rest.split(), index)?;
        let (z_rim_px, new_highest) = self.read_side(&side, index, rest)?;
        let strip = match (strip_finder, plan) {
            (Some(finder), Some(plan)) => finder.measure(&plan, index).ok(),
            _ => None,
        };
        self.frames.push(FrameRecord {
            index,
            // Set from the container's timestamps once every frame is read.
            t_capture: f64::NAN,
            t: f64::NAN,
            container_time_s: frame.container_time_s,
            picture_type: frame.picture_type,
            z_rim_px,
            camera_shift_px: None,
            z_rim_m: None,
            beta_raw: strip.map(|s| s.beta),
        });
        Ok((z_rim_px, new_highest, strip))
    }

    /// Reads one frame's side view with every gauge: returns its z_rim \[px\] (0 at
    /// contact, `None` without an edge) and, when its rim is the highest so far, its
    /// height and edge row.
    fn read_side(
        &mut self,
        side: &FrameView,
        index: usize,
        rest: &RestCalibration,
    ) -> Result<(Option<f64>, Option<RimCrest>), vision::VisionError> {
        let gauges = &rest.gauges;
        let z_base = rest.calibration.calibration.z_base;
        let rim = gauges.rim.measure(side, index)?;
        if gauges.rest_window.is_some() {
            let edge0 = match rim {
                RimHeight::Edge { edge_row, .. } => Some(edge_row),
                RimHeight::Contact => Some(z_base),
                RimHeight::NoEdge => None,
            };
            let columns = gauges.rim.band_columns();
            self.windows
                .push(edge0.and_then(|e| BandWindow::read(side, &columns, e)));
        }
        let mut new_highest = None;
        let z_rim_px = match rim {
            RimHeight::Edge { z_rim_px, edge_row } => {
                if self.highest.as_ref().is_none_or(|(z, _, _)| z_rim_px > *z) {
                    new_highest = Some((z_rim_px, edge_row));
                }
                Some(z_rim_px)
            }
            RimHeight::Contact => Some(0.0),
            RimHeight::NoEdge => {
                self.no_edge += 1;
                None
            }
        };
        if let Some(gauge) = &gauges.gap {
            self.gaps.push(gauge.measure(side));
        }
        if let Some(gauge) = &gauges.lean {
            self.profiles.push(gauge.read(side));
        }
        Ok((z_rim_px, new_highest))
    }
}

/// The near top rim from the frames that lean towards the camera
/// ([`TopRimLeaning`]), unless the config gives z_t.
fn top_rim_leaning(
    frames: &[FrameRecord],
    profiles: &[Vec<f32>],
    rest: &RestCalibration,
) -> Option<TopRimLeaning> {
    rest.gauges
        .lean
        .as_ref()
        .filter(|_| rest.given.is_none_or(|g| g.z_t.is_none()))
        .and_then(|gauge| {
            let heights: Vec<Option<f64>> = frames.iter().map(|f| f.z_rim_px).collect();
            let kinds: Vec<Option<char>> = frames.iter().map(|f| f.picture_type).collect();
            vision::near_top_rim_leaning(gauge, profiles, &heights, &kinds)
        })
        .map(|reading| TopRimLeaning {
            reading,
            rest_z_t: rest.calibration.calibration.z_t,
        })
}

/// The scale at the near rim (eq. 3.10), checked against the diameter's
/// ([`ScaleReport`]), with the leaning frames' z_t when read. z_rim is converted
/// to metres once, after every correction of z_rim in px. The principal point is
/// the centre of the frame's side view (above the split in a two-view clip).
fn scale(
    rest: &RestCalibration,
    rim: &RimHeights,
    top_rim_leaning: Option<&TopRimLeaning>,
    config: &ExperimentConfig,
    params: &DiskParams,
) -> ScaleReport {
    let mut cal = rest.calibration.calibration;
    if let Some(leaning) = top_rim_leaning {
        cal.z_t = leaning.reading.z_t;
    }
    // No face 1.5 px above the rest frames' z_t (vision::silhouette_top): their
    // z_t is then the silhouette's top, the far top rim, unless below the
    // leaning frames' near rim.
    let silhouette_top = rest
        .silhouette_top
        .or_else(|| top_rim_leaning.map(|l| l.rest_z_t.min(l.reading.z_t)));
    let roi_top = rest.roi.map_or(0.0, |r| f64::from(r[1]));
    let side_rows = rest
        .split()
        .map_or(rest.height as f64, |s| roi_top + s as f64);
    ScaleReport::new(&cal, rim.bottom_rim_row, params)
        .with_camera_distance(config.camera_distance_m)
        .with_near_rim_elevation(&cal, silhouette_top, params)
        .with_local_scale_at_near_rim(0.5 * side_rows - roi_top, params)
}

/// Sets each frame's capture time: the container's timestamps on the capture
/// clock, else index / fps; a span's from the timestamps of the whole clip (its
/// index), so that they count from the clip's first frame.
fn set_capture_times(
    frames: &mut [FrameRecord],
    plan_span: &SpanPlan,
    first: usize,
    fps: &mut CaptureFps,
) -> FrameTiming {
    let (t, frame_times) = match &plan_span.index {
        Some(index) if first > 0 => {
            let stamps: Vec<Option<f64>> =
                index.container_times_s.iter().copied().map(Some).collect();
            let (mut t, timing) = footage::frame_times(&stamps, fps);
            (t.split_off(first), timing)
        }
        _ => {
            let stamps: Vec<Option<f64>> = frames.iter().map(|f| f.container_time_s).collect();
            footage::frame_times(&stamps, fps)
        }
    };
    for (record, &t) in frames.iter_mut().zip(&t) {
        record.t_capture = t;
    }
    frame_times
}
