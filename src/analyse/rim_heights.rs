//! The rim heights of a span re-measured with a model of the rim's edge learned
//! from the clip: on a dark plate the mirror-edge model (vision::mirror_edge), on a
//! light one the shadow-edge contour (vision::shadow_edge). Their zero is the edge
//! at rest, read from the whole rest tail.

use super::FrameRecord;
use super::REST_FRAMES;
use super::calibrate::RestCalibration;
use crate::config::Plate;
use crate::signal::SignalConfig;
use crate::vision::{
    self, BandWindow, GapGauge, GapSample, Registration, RimReading, StripProfiles,
};

/// How the span's rim heights were read.
pub(super) struct RimHeights {
    /// How z_rim was measured, for the plan.
    pub(super) description: String,
    /// The side view's row where z_rim = 0 \[px\]: the model's edge at rest, else
    /// z_base; moved with the zero the motion places (the signal stage).
    pub(super) zero_row_px: f64,
    /// z_b of eq. 3.10: the plate line where the mirror-edge model finds the rim
    /// meets its mirror image (ScaleReport), else z_base.
    pub(super) bottom_rim_row: f64,
    /// Which reading, which decides how well the zero is known when the motion does
    /// not place it.
    pub(super) reading: RimReading,
}

/// Dark plate: rim heights below 2 px from the darkness of the gap (vision::gap).
/// Returns a warning when the rim never lifts far enough to learn that darkness.
pub(super) fn resolve_gap(
    frames: &mut [FrameRecord],
    gauge: &GapGauge,
    gaps: &[GapSample],
) -> Option<String> {
    let mut heights: Vec<Option<f64>> = frames.iter().map(|f| f.z_rim_px).collect();
    let warning = gauge.resolve(&mut heights, gaps).is_none().then(|| {
        "the rim never lifts 2.5–4.5 px, so the darkness of the gap per pixel is unknown: \
         rim heights below 2 px come from the edge alone and read up to 0.2 px high"
            .to_string()
    });
    for (record, z) in frames.iter_mut().zip(heights) {
        record.z_rim_px = z;
    }
    warning
}

/// The camera's shift in every frame against the rest tail (vision::registration),
/// from the scene beside the disk `scene` (one per frame), and the first-pass
/// heights and band `windows` moved into the rest tail's scene by it, when it is
/// measured well enough to apply. A frame read at contact (`RimHeight::Contact`,
/// height 0) touches the plate in its own scene: it stays at 0.
pub(super) fn register(
    frames: &mut [FrameRecord],
    windows: &mut [Option<BandWindow>],
    scene: &[StripProfiles],
    rest: &RestCalibration,
    fps: f64,
) -> Option<Registration> {
    let strips = rest.gauges.scene.as_ref()?;
    let tail = rest_tail_frames(fps).min(scene.len());
    let x_centre = rest.calibration.calibration.x_centre();
    let registration = vision::register(strips, scene, scene.len() - tail..scene.len(), x_centre)?;
    if registration.applied {
        for (k, d) in registration.shifts.iter().enumerate() {
            let Some(d) = *d else { continue };
            let frame = &mut frames[k];
            frame.camera_shift_px = Some(d);
            // The picture moved down by d: the edge's row reads d too low.
            if let Some(z) = frame.z_rim_px.as_mut().filter(|z| **z != 0.0) {
                *z += d;
            }
            if let Some(w) = windows.get_mut(k).and_then(Option::as_mut) {
                w.shift = d;
            }
        }
    }
    Some(registration)
}

/// Every height of `frames` re-measured with the plate's edge model, from the band
/// `windows` read about each frame's edge, with the rest tail (at `fps`) as its
/// zero; where the model cannot be learned, the first pass's heights stay and the
/// description says why.
pub(super) fn remeasure(
    frames: &mut [FrameRecord],
    windows: &[Option<BandWindow>],
    rest: &RestCalibration,
    fps: f64,
) -> RimHeights {
    let plate = rest.side_config.plate;
    let z_base = rest.calibration.calibration.z_base;
    let first_pass = match plate {
        Plate::Dark => "edge and gap darkness (vision::rim, vision::gap)",
        Plate::Light => "edge (vision::rim): the second edge from the bottom on a light plate",
    };
    let unchanged = |description: String| RimHeights {
        description,
        zero_row_px: z_base,
        bottom_rim_row: z_base,
        reading: RimReading::FirstPass,
    };
    let Some((pass1, edge0)) = &rest.gauges.rest_window else {
        return unchanged(first_pass.into());
    };
    let tail = rest_tail_frames(fps);
    let mut heights: Vec<Option<f64>> = frames.iter().map(|f| f.z_rim_px).collect();
    let refit = match plate {
        Plate::Dark => {
            let rest_window = tail_rest_window(windows, pass1, tail);
            vision::remeasure_dark_rim(&mut heights, windows, z_base, &rest_window, *edge0)
                .map(|model| mirror_edge_heights(&model))
        }
        Plate::Light => vision::remeasure_light_rim(&mut heights, windows, z_base, pass1)
            .map(|model| shadow_edge_heights(&model, z_base))
            .map_err(String::from),
    };
    match refit {
        Ok(mut rim) => {
            if plate == Plate::Light {
                let shift = tail_median_shift(&mut heights, tail);
                rim.zero_row_px -= shift;
                rim.description += &format!(
                    "; the rest tail's median reading ({shift:+.3} px) moves the zero to {:.2} px",
                    rim.zero_row_px
                );
            }
            for (record, z) in frames.iter_mut().zip(heights) {
                record.z_rim_px = z;
            }
            rim
        }
        Err(reason) => unchanged(format!("{first_pass}: {reason}")),
    }
}

/// The heights as the mirror-edge model reads them (dark plate).
fn mirror_edge_heights(model: &vision::MirrorEdgeModel) -> RimHeights {
    let kind = if model.is_sharp() {
        "a sharp rim (the plate line from the test)"
    } else {
        "a rounded rim (the plate line from the rest frames)"
    };
    let test = match model.near_contact_frames {
        0 => "too few frames near contact: the rest frames alone put the plate line".to_string(),
        frames => format!("the rest frames and {frames} frames near contact put the plate line"),
    };
    let description = format!(
        "mirror-edge model (vision::mirror_edge): the rim's profile learned from the frames \
         with an open gap; edge at rest {:.2} px, the zero of z_rim; plate line {:.2} px, \
         where the rim meets its mirror image (z_b of eq. 3.10's scale), reflectivity {:.2}, \
         the reflection blurred by σ {:.2} px; rest fit RMS {:.1} % of the disk's level; \
         {kind}: {test} {:+.2} px below the edge (sharp under {sharp} px)",
        model.rest_edge,
        model.plate_row,
        model.reflectivity,
        model.mirror_blur_px(),
        100.0 * model.rest_rms,
        model.plate_offset_test,
        sharp = vision::SHARP_RIM_PX,
    );
    RimHeights {
        description,
        zero_row_px: model.rest_edge,
        bottom_rim_row: model.plate_row,
        reading: if model.is_sharp() {
            RimReading::SharpMirrorEdge
        } else {
            RimReading::RoundedMirrorEdge
        },
    }
}

/// The heights as the shadow-edge contour reads them (light plate); it measures no
/// plate line, so z_b stays `z_base`.
fn shadow_edge_heights(model: &vision::ShadowEdgeModel, z_base: f64) -> RimHeights {
    let description = format!(
        "shadow-edge contour (vision::shadow_edge): the edge where the band falls to {:.3} \
         of the disk's side, halfway to the shadow under the lifted rim ({:.3}), placed by \
         the pixel means of a step blurred by σ = {:.2} px; edge at rest {:.2} px, the zero \
         of z_rim; {} frame(s) kept the first pass",
        model.edge_level(),
        model.shadow_ratio,
        model.blur_px,
        model.rest_edge,
        model.kept_first_pass
    );
    RimHeights {
        description,
        zero_row_px: model.rest_edge,
        bottom_rim_row: z_base,
        reading: RimReading::ShadowEdge,
    }
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
/// plate line and reflectivity at once) then moves with the frames it is given:
/// five last frames coded apart can put the edge at rest 0.4 px off the whole
/// tail's, which agrees with the uncoded clip's (every lifted height 0.33 px low
/// from the five). The halt's analysis checks that the same tail is at rest.
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
    let shift = crate::numeric::median(&rest);
    for z in heights.iter_mut().flatten() {
        *z -= shift;
    }
    shift
}

#[cfg(test)]
mod tests {
    use super::*;

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
