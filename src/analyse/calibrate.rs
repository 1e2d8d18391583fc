//! Calibrate (pass 1, thesis §3.2.4, §3.3.2): the last frames, where the disk lies at
//! rest, give the layout (side view or two-view), the plate kind, the disk's ends
//! x_l, x_r, its top z_t and bottom z_base, the threshold γ, and the gauges with
//! which pass 2 reads every frame.

use std::path::Path;

use super::open::OpenedClip;
use super::scale::PERSPECTIVE_FACTOR_RANGE;
use super::views::{OwnedFrame, side_view};
use super::{AnalyseError, LayoutGeometry, REST_FRAMES, ScaleReport};
use crate::config::{ExperimentConfig, Plate, VisionConfig};
use crate::footage::FrameView;
use crate::model::params::DiskParams;
use crate::vision::{
    self, BandWindow, CalibrationOverride, CalibrationReport, ColourThresholds, GapGauge,
    LeanGauge, RimGauge, RimHeight, SceneStrips, SideViewConfig, ThresholdSource, VisionError,
};

/// A two-view clip's first row of the plan view \[px\], and whether the config gave it.
type SplitRow = (usize, bool);

/// What the rest frames fixed for the rest of the analysis.
pub(super) struct RestCalibration {
    pub(super) two_view: bool,
    /// Side view or two-view, and whether the config said so or how it was detected.
    pub(super) layout: String,
    /// Two-view clips: the first row of the plan view \[px\] and whether the config gave it.
    pub(super) split_row: Option<(usize, bool)>,
    /// The config's region of interest [x, y, width, height] \[px\].
    pub(super) roi: Option<[u32; 4]>,
    pub(super) side_config: SideViewConfig,
    /// The calibration points the config gives, if any.
    pub(super) given: Option<CalibrationOverride>,
    pub(super) calibration: CalibrationReport,
    /// Dark or light plate, and whether the config said so or how it was detected.
    pub(super) plate: String,
    /// The top face's far rim at rest, for the camera's elevation (ScaleReport).
    pub(super) silhouette_top: Option<f64>,
    pub(super) gauges: Gauges,
    pub(super) colour_thresholds: Option<(ColourThresholds, ThresholdSource)>,
    /// Displayed frame size \[px\].
    pub(super) width: usize,
    pub(super) height: usize,
    /// The last rest frame's side view, for the calibration diagnostic.
    pub(super) rest_side: OwnedFrame,
}

/// How pass 2 reads each frame's side view.
pub(super) struct Gauges {
    /// The rim's edge on the centre line (vision::rim).
    pub(super) rim: RimGauge,
    /// The profile across the disk's top on the centre line, read in every frame for
    /// the near top rim of the frames that lean towards the camera
    /// (vision::near_top_rim_leaning).
    pub(super) lean: Option<LeanGauge>,
    /// Dark plate: rim heights below 2 px from the darkness of the gap (vision::gap).
    pub(super) gap: Option<GapGauge>,
    /// The rest frames' mean band window about their edge, and that edge's row: the
    /// zero of the rim's edge model (vision::mirror_edge, vision::shadow_edge).
    pub(super) rest_window: Option<(BandWindow, f64)>,
    /// The scene beside the disk, on which each frame's camera shift is measured
    /// (vision::registration); `None` when no strip fits beside the disk.
    pub(super) scene: Option<SceneStrips>,
}

impl RestCalibration {
    /// The first row of a two-view clip's plan view \[px\].
    pub(super) fn split(&self) -> Option<usize> {
        self.split_row.map(|(row, _)| row)
    }

    /// The overlay's geometry of the frame: calibration, view and band.
    pub(super) fn layout_geometry(&self) -> LayoutGeometry {
        let (roi, cal) = (self.roi, self.calibration.calibration);
        LayoutGeometry {
            calibration: cal,
            origin: roi.map_or((0, 0), |[x, y, _, _]| (x as usize, y as usize)),
            view: roi.map_or((self.width, self.height), |r| {
                (r[2] as usize, r[3] as usize)
            }),
            split_row: self.split(),
            band_half_width_px: self.side_config.half_width_px,
            zero_row: cal.z_base,
        }
    }
}

/// Pass 1: reads the last [`REST_FRAMES`] frames of `opened` and calibrates on them.
///
/// # Errors
/// The last frames cannot be read, or the rest frames do not calibrate (no disk,
/// a disk not at rest, a band that does not fit on it).
pub(super) fn calibrate(
    clip: &Path,
    opened: &mut OpenedClip,
    config: &ExperimentConfig,
    params: &DiskParams,
) -> Result<RestCalibration, AnalyseError> {
    let vision_err = |error| AnalyseError::Vision {
        path: clip.to_path_buf(),
        error,
    };
    let vision_config = config.vision.clone().unwrap_or_default();
    let roi = vision_config.roi;
    let rest = read_rest_frames(clip, opened)?;
    let last = &rest[rest.len() - 1];
    let last_view = side_view(&last.view(), roi, None, last.index)
        .map_err(vision_err)?
        .0;
    let (two_view, layout, split_row) =
        rest_layout(config, &vision_config, &last_view, last.index).map_err(vision_err)?;
    let split = split_row.map(|(row, _)| row);
    let rest_sides = rest_side_views(&rest, roi, split).map_err(vision_err)?;
    let first_index = rest[0].index;
    let (side_config, given, calibration, plate) = calibrate_sides(
        clip,
        config,
        &vision_config,
        &rest_sides,
        first_index,
        params,
    )?;
    let (silhouette_top, gauges) =
        gauges(&calibration, &side_config, &rest_sides, first_index).map_err(vision_err)?;
    let colour_thresholds = split
        .map(|row| colour_thresholds(&last_view, row, last.index))
        .transpose()
        .map_err(vision_err)?;
    Ok(RestCalibration {
        two_view,
        layout,
        split_row,
        roi,
        side_config,
        given,
        calibration,
        plate,
        silhouette_top,
        gauges,
        colour_thresholds,
        width: last.width,
        height: last.height,
        // The calibration diagnostic shows the z_t used (the leaning frames' when read).
        rest_side: OwnedFrame::copy(last.index, &rest_sides[rest_sides.len() - 1]),
    })
}

/// The last [`REST_FRAMES`] frames of the clip, copied.
///
/// # Errors
/// The seek fails, or fewer than two frames can be read there.
fn read_rest_frames(clip: &Path, opened: &mut OpenedClip) -> Result<Vec<OwnedFrame>, AnalyseError> {
    let (source, expected) = (&mut opened.source, opened.expected);
    match &opened.index {
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
    Ok(rest)
}

/// The layout on the last rest frame's view `last_view` ([`detect_layout`]): side
/// view or two-view, its description, and a two-view clip's split row
/// ([`split_row`]).
fn rest_layout(
    config: &ExperimentConfig,
    vision_config: &VisionConfig,
    last_view: &FrameView,
    index: usize,
) -> Result<(bool, String, Option<SplitRow>), VisionError> {
    let (two_view, layout) = detect_layout(config, last_view, index);
    let split_row = two_view
        .then(|| split_row(vision_config, last_view, index))
        .transpose()?;
    Ok((two_view, layout, split_row))
}

/// The side view of each rest frame (above the `split` row of a two-view clip,
/// within the config's `roi`).
fn rest_side_views<'a>(
    rest: &'a [OwnedFrame],
    roi: Option<[u32; 4]>,
    split: Option<usize>,
) -> Result<Vec<FrameView<'a>>, VisionError> {
    rest.iter()
        .map(|frame| side_view(&frame.view(), roi, split, frame.index).map(|(side, _)| side))
        .collect()
}

/// Side view or two-view: the config's `two_view`, else detected on the last frame.
fn detect_layout(config: &ExperimentConfig, last_view: &FrameView, index: usize) -> (bool, String) {
    match config.two_view {
        Some(two_view) => (
            two_view,
            format!("{} (config `two_view`)", layout_name(two_view)),
        ),
        None => {
            let detected = vision::detect_two_view(last_view, index);
            (
                detected.two_view,
                format!(
                    "{} (detected: {})",
                    layout_name(detected.two_view),
                    detected.evidence
                ),
            )
        }
    }
}

/// A two-view clip's first row of the plan view \[px\]: the config's `split_row`, else
/// found on the last frame; and whether the config gave it.
fn split_row(
    vision_config: &VisionConfig,
    last_view: &FrameView,
    index: usize,
) -> Result<SplitRow, VisionError> {
    Ok(match vision_config.split_row {
        Some(row) => (row as usize, true),
        None => (vision::find_split_row(last_view, index)?, false),
    })
}

/// The strip's colour thresholds, found on the plan view of the last frame (below
/// the split `row`).
fn colour_thresholds(
    last_view: &FrameView,
    row: usize,
    index: usize,
) -> Result<(ColourThresholds, ThresholdSource), VisionError> {
    let (_, plan) = vision::split_views(last_view, row, index)?;
    let thresholds = vision::auto_colour_thresholds(&plan, index)?;
    Ok((thresholds, ThresholdSource::Automatic))
}

/// The side view's settings for the rest frames, the calibration points the config
/// gives, and the rest frames' calibration with the plate kind's description: the
/// plate kind the config names or the one detected ([`calibrate_plate`]), on a band
/// that fits the disk ([`fit_band_to_disk`]).
///
/// # Errors
/// The rest frames do not calibrate, or the config's band does not fit on the disk.
fn calibrate_sides(
    clip: &Path,
    config: &ExperimentConfig,
    vision_config: &VisionConfig,
    rest_sides: &[FrameView],
    first_index: usize,
    params: &DiskParams,
) -> Result<
    (
        SideViewConfig,
        Option<CalibrationOverride>,
        CalibrationReport,
        String,
    ),
    AnalyseError,
> {
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
    let rest = RestSides {
        sides: rest_sides,
        first_index,
        given: given.as_ref(),
    };
    let vision_err = |error| AnalyseError::Vision {
        path: clip.to_path_buf(),
        error,
    };
    let (calibration, plate) =
        calibrate_plate(config, &rest, &mut side_config, params).map_err(vision_err)?;
    let calibration = fit_band_to_disk(clip, vision_config, &rest, &mut side_config, calibration)?;
    Ok((side_config, given, calibration, plate))
}

/// The rest frames' side views, the first one's frame number, and the calibration
/// points the config gives.
struct RestSides<'a> {
    sides: &'a [FrameView<'a>],
    first_index: usize,
    given: Option<&'a CalibrationOverride>,
}

impl RestSides<'_> {
    /// The rest frames calibrated with `side_config` (vision::calibrate_at_rest).
    fn calibrate(&self, side_config: &SideViewConfig) -> Result<CalibrationReport, VisionError> {
        vision::calibrate_at_rest(self.sides, self.first_index, side_config, self.given)
    }
}

/// The rest frames' calibration for the config's plate kind, or for the kind
/// detected ([`calibrate_detecting_plate`], which then sets `side_config.plate`),
/// and its description.
fn calibrate_plate(
    config: &ExperimentConfig,
    rest: &RestSides,
    side_config: &mut SideViewConfig,
    params: &DiskParams,
) -> Result<(CalibrationReport, String), VisionError> {
    Ok(match config.plate {
        Some(plate) => (
            rest.calibrate(side_config)?,
            format!("{} (config `plate`)", plate_name(plate)),
        ),
        None => {
            let (report, kind, evidence) = calibrate_detecting_plate(rest, side_config, params)?;
            side_config.plate = kind;
            (
                report,
                format!("{} (detected: {evidence})", plate_name(kind)),
            )
        }
    })
}

/// The band on which the rest frames are read, fitted to the disk: a band named in
/// the config must fit on the disk (config::band_fits_disk); otherwise the band
/// grows with the disk (config::band_for_disk), and where it grew the rest frames
/// are calibrated again on it.
///
/// # Errors
/// The config's band does not fit on the disk, or the wider band does not calibrate.
fn fit_band_to_disk(
    clip: &Path,
    vision_config: &VisionConfig,
    rest: &RestSides,
    side_config: &mut SideViewConfig,
    calibration: CalibrationReport,
) -> Result<CalibrationReport, AnalyseError> {
    let disk_width = calibration.calibration.x_r - calibration.calibration.x_l;
    if let Some(band) = vision_config.band_half_width_px {
        crate::config::band_fits_disk(band, disk_width).map_err(|reason| {
            AnalyseError::Setting {
                path: clip.to_path_buf(),
                reason,
            }
        })?;
        return Ok(calibration);
    }
    let band = crate::config::band_for_disk(disk_width, side_config.half_width_px);
    if band == side_config.half_width_px {
        return Ok(calibration);
    }
    side_config.half_width_px = band;
    rest.calibrate(side_config)
        .map_err(|error| AnalyseError::Vision {
            path: clip.to_path_buf(),
            error,
        })
}

/// The gauges of pass 2 ([`Gauges`]), and the top face's far rim on the last rest
/// frame (vision::silhouette_top) with which the lean gauge reads the near one. On
/// a dark plate, rim heights below 2 px come from the darkness of the gap
/// (vision::gap); then, on either plate, every height is re-measured with a model
/// of the rim's edge learned from the clip ([`rest_window`]).
fn gauges(
    calibration: &CalibrationReport,
    side_config: &SideViewConfig,
    rest_sides: &[FrameView],
    first_index: usize,
) -> Result<(Option<f64>, Gauges), VisionError> {
    let cal = calibration.calibration;
    let silhouette_top = rest_sides
        .last()
        .and_then(|side| vision::silhouette_top(side, &cal));
    let side0 = &rest_sides[0];
    let rim = RimGauge::new(
        &cal,
        &calibration.threshold,
        side_config,
        side0.width,
        side0.height,
    )?;
    let lean = LeanGauge::new(
        &cal,
        calibration.top_face,
        silhouette_top,
        rim.band_columns(),
        side0.height,
    );
    let gap = match side_config.plate {
        Plate::Dark => GapGauge::new(&cal, side_config, rest_sides)?,
        Plate::Light => None,
    };
    let rest_window = rest_window(&rim, cal.z_base, rest_sides, first_index);
    let scene = SceneStrips::new(&cal, side0.width, side0.height);
    let gauges = Gauges {
        rim,
        lean,
        gap,
        rest_window,
        scene,
    };
    Ok((silhouette_top, gauges))
}

/// The zero of the rim's edge model (vision::mirror_edge on a dark plate,
/// vision::shadow_edge on a light one): the rest frames' mean band window about
/// the first rest frame's edge (z_base where it shows none), and that edge's row.
/// These are pass 1's [`REST_FRAMES`]; the whole rest tail's replace them after
/// pass 2 ([`super::rim_heights`]).
fn rest_window(
    rim: &RimGauge,
    z_base: f64,
    rest_sides: &[FrameView],
    first_index: usize,
) -> Option<(BandWindow, f64)> {
    let edge0 = match rim.measure(&rest_sides[0], first_index) {
        Ok(RimHeight::Edge { edge_row, .. }) => edge_row,
        _ => z_base,
    };
    let columns = rim.band_columns();
    let windows: Option<Vec<BandWindow>> = rest_sides
        .iter()
        .map(|f| BandWindow::read(f, &columns, edge0))
        .collect();
    windows
        .and_then(|w| BandWindow::mean(&w))
        .map(|w| (w, edge0))
}

pub(super) fn plate_name(plate: Plate) -> &'static str {
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
/// ([`plausible_end_step`]); of the plausible ones the first is taken, unless a
/// later one's ends are edges where its ends are not, or the plate under the disk
/// shows a shadow ([`takes_over`]).
///
/// With none plausible, the first whose side reads thinner than the range allows is
/// taken (a top face lit like the side leaves z_t at the far rim: its scale then falls
/// back to the diameter, with a warning). One that reads the side thicker (the
/// reflection or shadow taken for part of the disk) puts the rim gauge on the wrong
/// edge, and no scale mends that: with only such, the clip is refused
/// ([`VisionError::ImpossibleScale`]).
///
/// A dark-plate calibration of a light plate finds a sliver of the plate, an
/// unsteady blob, or (on a plate brighter than the disk's side) a run that stops
/// inside the disk where its side's shading crosses γ, with a plausible camera;
/// a light-plate calibration of a dark plate takes the reflection for part of the
/// disk. The description lists what each kind showed; with no calibration, the
/// error of [`no_plate`] is returned.
fn calibrate_detecting_plate(
    rest: &RestSides,
    side_config: &SideViewConfig,
    disk: &DiskParams,
) -> Result<(CalibrationReport, Plate, String), VisionError> {
    let last = rest.sides.last().ok_or(VisionError::NoFrames)?;
    let mut taken: Option<(CalibrationReport, Plate, f64)> = None;
    let mut fallback = None;
    let mut thickest: Option<f64> = None;
    let mut tried = Vec::new();
    let mut errors = Vec::new();
    for plate in [Plate::Dark, Plate::Light] {
        let config = SideViewConfig {
            plate,
            ..*side_config
        };
        let report = match rest.calibrate(&config) {
            Ok(report) => report,
            Err(e) => {
                tried.push(format!("{}: {e}", plate_name(plate)));
                errors.push(e);
                continue;
            }
        };
        match plausible_end_step(&report, plate, last, disk, &mut tried) {
            None => {
                let factor = perspective_factor(&report, disk);
                if factor > PERSPECTIVE_FACTOR_RANGE.1 {
                    thickest = Some(thickest.map_or(factor, |f| f.min(factor)));
                } else {
                    fallback.get_or_insert((report, plate));
                }
            }
            Some(step) => {
                let first = taken.as_ref().map(|(report, _, step)| (report, *step));
                if takes_over(first, &report, step, last, &mut tried) {
                    taken = Some((report, plate, step));
                }
            }
        }
    }
    match (
        taken.map(|(report, plate, _)| (report, plate)).or(fallback),
        thickest,
    ) {
        (Some((report, plate)), _) => Ok((report, plate, tried.join("; "))),
        (None, Some(factor)) => Err(VisionError::ImpossibleScale {
            factor,
            max: PERSPECTIVE_FACTOR_RANGE.1,
            tried: tried.join("; "),
        }),
        (None, None) => Err(no_plate(&errors, &tried)),
    }
}

/// The diameter's scale over the thickness's (eq. 3.10) of a calibration: the
/// camera's perspective factor ([`ScaleReport`]).
fn perspective_factor(report: &CalibrationReport, disk: &DiskParams) -> f64 {
    let cal = &report.calibration;
    ScaleReport::new(cal, cal.z_base, disk).perspective_factor
}

/// How sharply a plate kind's calibration changes across the disk's ends on the
/// `last` rest frame ([`vision::Calibration::end_step`]), when the calibration is
/// plausible: its two scales imply a camera a side view can have (perspective
/// factor within [`PERSPECTIVE_FACTOR_RANGE`]). `None` when not; either way,
/// what it showed is added to `tried`.
fn plausible_end_step(
    report: &CalibrationReport,
    plate: Plate,
    last: &FrameView,
    disk: &DiskParams,
    tried: &mut Vec<String>,
) -> Option<f64> {
    let (lo, hi) = PERSPECTIVE_FACTOR_RANGE;
    let cal = &report.calibration;
    let factor = perspective_factor(report, disk);
    if !(lo..=hi).contains(&factor) {
        tried.push(format!(
            "{}: perspective factor {factor:.3}, outside {lo}–{hi}",
            plate_name(plate)
        ));
        return None;
    }
    let step = cal.end_step(last);
    tried.push(format!(
        "{}: perspective factor {factor:.3}, step at the ends {step:.1}",
        plate_name(plate)
    ));
    Some(step)
}

/// Whether a later plausible calibration, whose ends step by `step`, is taken
/// instead of the `first` plausible one (its report and step). The later is
/// taken when its ends step more than [`END_STEP_RATIO`] times as sharply (its
/// ends are edges where the first's are not), never when the first's step that
/// much more sharply. Where neither does (the two found the same disk), the plate
/// under the disk decides ([`vision::Calibration::under_rim_light`], on the `last`
/// rest frame, added to `tried`): darker there than beside the disk is a light
/// plate's shadow, brighter a dark plate's mirror image. (A light plate under a
/// darker tone curve can give both kinds the same disk; read as dark, its heights
/// come out 2.5 % low and n +0.02.)
///
/// Before any of that, a later calibration whose disk is the first's mirror image
/// (its top at the first's plate line, as tall) is never taken: on a plate that
/// mirrors the disk, a light plate's reading of the rest frame can take the image
/// below the plate line for the disk, with ends as sharp as the disk's.
fn takes_over(
    first: Option<(&CalibrationReport, f64)>,
    later: &CalibrationReport,
    step: f64,
    last: &FrameView,
    tried: &mut Vec<String>,
) -> bool {
    let Some((first, first_step)) = first else {
        return true;
    };
    if is_mirror_image(&later.calibration, &first.calibration) {
        tried.push("the later kind's disk is the first's mirror image".into());
        return false;
    }
    if step > END_STEP_RATIO * first_step {
        return true;
    }
    if first_step > END_STEP_RATIO * step {
        return false;
    }
    let under = first.calibration.under_rim_light(last);
    if let Some(light) = under {
        tried.push(format!(
            "under the disk {light:+.1} of 255 against the plate beside it ({})",
            if light < 0.0 {
                "a shadow"
            } else {
                "a mirror image"
            }
        ));
    }
    under.is_some_and(|light| light < 0.0)
}

/// Whether `image`'s disk is `disk`'s mirror image in the plate: its top lies at
/// `disk`'s plate line, its ends at the disk's, each within [`MIRROR_TOLERANCE`] of
/// the disk's height, and it is no taller than the disk. It may be shorter: the
/// reflection fades away from the plate line, and a threshold's run stops where it
/// falls below.
fn is_mirror_image(image: &vision::Calibration, disk: &vision::Calibration) -> bool {
    let height = disk.disk_height_px();
    let tolerance = MIRROR_TOLERANCE * height;
    (image.z_t - disk.z_base).abs() <= tolerance
        && (image.x_l - disk.x_l).abs() <= tolerance
        && (image.x_r - disk.x_r).abs() <= tolerance
        && image.disk_height_px() <= height + tolerance
}

/// How close, as a fraction of the disk's height, a mirror image's top lies to the
/// plate line and its ends to the disk's (the rounded bottom rim and the blur move
/// the edges by a few px; a light plate's disk found as a sliver or a blob inside
/// it lies elsewhere).
const MIRROR_TOLERANCE: f64 = 0.05;

/// The error when no plate kind calibrated: for the same reason each time (a disk
/// not yet at rest, say), that reason; for different ones, each kind's (`tried`).
fn no_plate(errors: &[VisionError], tried: &[String]) -> VisionError {
    match errors {
        [first, rest @ ..]
            if rest
                .iter()
                .all(|e| std::mem::discriminant(e) == std::mem::discriminant(first)) =>
        {
            first.clone()
        }
        _ => VisionError::PlateNotRecognised {
            tried: tried.join("; "),
        },
    }
}

fn layout_name(two_view: bool) -> &'static str {
    if two_view { "two-view" } else { "side view" }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cal(z_t: f64, z_base: f64) -> vision::Calibration {
        vision::Calibration {
            x_l: 86.0,
            x_r: 1138.0,
            z_t,
            z_base,
        }
    }

    /// The readings of a drifting clip at rest: the dark plate's disk (rows
    /// 238–436) and the light plate's, which is its mirror image (437–613, shorter:
    /// the reflection fades); a disk's own second reading, a sliver inside it, and
    /// anything taller or with other ends are not.
    #[test]
    fn a_disk_below_the_plate_line_with_the_same_ends_is_the_mirror_image() {
        let disk = cal(238.5, 436.4);
        assert!(is_mirror_image(&cal(437.0, 613.0), &disk));
        assert!(!is_mirror_image(&cal(247.4, 434.0), &disk));
        assert!(!is_mirror_image(&cal(300.0, 480.0), &disk));
        // Taller than the disk: not its image.
        assert!(!is_mirror_image(&cal(437.0, 680.0), &disk));
        // Other ends: another object under the plate line.
        let narrower = vision::Calibration {
            x_l: 300.0,
            ..cal(437.0, 613.0)
        };
        assert!(!is_mirror_image(&narrower, &disk));
    }
}
