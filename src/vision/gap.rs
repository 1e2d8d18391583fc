//! Narrow gaps on a dark plate: the rim height from the darkness of the gap
//! between the disk and its mirror image (thesis §3.2.4, fig. 3.7), where the
//! edge of [`RimGauge`](super::RimGauge) cannot be placed.
//!
//! # Why the edge fails there
//!
//! On a dark reflective plate the rolling disk and its mirror image are separated
//! by a dark gap of height 2·z_rim centred on the plate line z_base. The edge
//! method places the disk's bottom edge by the area of the step from the disk's
//! level down to the gap's. While the gap is narrower than about two pixels no
//! row shows the gap's own level: the darkest row still mixes in disk above and
//! mirror below, the step's lower level is read too bright, and the edge lands on
//! the darkest row's boundary. On a clean rendered clip that read z_rim 0.15–0.2 px
//! high for 0.2 px < z_rim < 0.7 px: the troughs of every turn, and every peak of
//! the last 0.05 s, which biased φ low (through the troughs) and then high (at the
//! last peaks), and the power-law exponent of an n = 0.67 motion by +0.04.
//!
//! # The darkness of the gap
//!
//! Take a window of rows [y₀, y₁) around the plate line, wider than the gap and
//! its blur, and the band profile p_ref(y) of the rest frames (the disk lying on
//! the plate, no gap). When the rim lifts by z, the disk's rows move up by z, the
//! mirror's down by z, and the gap between them shows the plate at level G. Then
//!
//! ```text
//! Σ_window p = ∫_{y₀+z}^{z_base} p_ref + 2 z G + ∫_{z_base}^{y₁−z} p_ref,
//! D := Σ_window (p_ref − p) = z (p_ref(y₀) + p_ref(y₁) − 2 G),
//! ```
//!
//! so z = D / (p_ref(y₀) + p_ref(y₁) − 2G): the gap's missing light over the
//! light it replaces. Blur moves light between rows but keeps the window's sum,
//! so the result holds at any sub-pixel phase and blur narrower than the margin,
//! and for any shading of the disk and its mirror that is smooth over z at the
//! window's ends. A global change of brightness (50 Hz flicker) is divided out
//! by the ratio of the frame to the reference on rows just outside the window.
//!
//! The light a unit lift removes, p_ref(y₀) + p_ref(y₁) − 2G, depends on G, the
//! plate's level seen through the gap (which neither the rest frame, where the
//! gap is closed, nor the plate beside the disk, lit where the gap lies in the
//! disk's shadow, shows). It is learned from the clip itself, against the edge
//! where the edge is exact: in frames whose rim lifts [`CALIBRATION_GAP_PX`] by
//! the edge method, the gap's middle rows show its own level and the edge is
//! placed to about 0.01 px, so D / z_rim there gives the darkness per pixel of
//! lift (the median over those frames). The two methods then agree where they
//! meet, whatever the plate's levels and the disk's shading.

use std::ops::Range;

use super::VisionError;
use super::calibration::{Calibration, SideViewConfig, band};
use super::profile::row_band_mean;
use crate::footage::FrameView;

/// Rows of the window either side of the plate line: a gap of up to
/// [`NARROW_GAP_PX`] either side and three rows of blur margin.
const HALF_WINDOW: usize = 5;
/// Rows just outside the window, each side, that measure the frame's brightness.
const SCALE_ROWS: usize = 2;
/// Below this rim height from the edge method (px), the gap's darkness gives z_rim.
pub const NARROW_GAP_PX: f64 = 2.0;
/// Rim heights from the edge method (px) at which the edge is exact and the gap
/// still lies inside the window (with half a row of margin at the top of the
/// range, enough for sharp frames): the darkness per pixel of lift is learned
/// there, as the median over those frames. Narrowing it to 2.5–3.5 px left too few
/// frames on the small two-view side view (per-frame n 0.430 for 0.45).
pub const CALIBRATION_GAP_PX: std::ops::RangeInclusive<f64> = 2.5..=4.5;

/// Measures the gap's darkness on the centre band, one frame after another.
#[derive(Clone, Debug)]
pub struct GapGauge {
    columns: Range<usize>,
    /// The window's rows.
    window: Range<usize>,
    /// Rest-frame band means of the window's rows.
    reference: Vec<f32>,
    /// Rest-frame band means of the scale rows (above, then below the window).
    scale_reference: f64,
}

/// One frame's gap, in the rest frames' brightness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GapSample {
    /// Σ_window (p_ref − p), grey levels × rows.
    pub deficit: f64,
}

impl GapGauge {
    /// A gauge from the rest frames (the calibration frames, disk at rest).
    /// `None` when the window and its scale rows do not fit in the frame.
    pub fn new(
        calibration: &Calibration,
        config: &SideViewConfig,
        rest: &[FrameView],
    ) -> Result<Option<Self>, VisionError> {
        let Some(first) = rest.first() else {
            return Ok(None);
        };
        let (width, height) = (first.width, first.height);
        calibration.validate(width, height)?;
        let base = calibration.z_base.floor() as usize;
        let (Some(top), true) = (
            base.checked_sub(HALF_WINDOW + SCALE_ROWS),
            base + HALF_WINDOW + 1 + SCALE_ROWS <= height,
        ) else {
            return Ok(None);
        };
        let window = top + SCALE_ROWS..base + HALF_WINDOW + 1;
        let (x0, x1) = band(calibration.x_centre(), config.half_width_px, width);
        let rows = window.start - SCALE_ROWS..window.end + SCALE_ROWS;
        let mut mean = vec![0f32; rows.len()];
        for frame in rest {
            for (m, y) in mean.iter_mut().zip(rows.clone()) {
                *m += row_band_mean(frame, y, x0, x1) / rest.len() as f32;
            }
        }
        let reference = mean[SCALE_ROWS..mean.len() - SCALE_ROWS].to_vec();
        let scale_reference = mean[..SCALE_ROWS]
            .iter()
            .chain(&mean[mean.len() - SCALE_ROWS..])
            .map(|&v| f64::from(v))
            .sum();
        Ok(Some(Self {
            columns: x0..x1,
            window,
            reference,
            scale_reference,
        }))
    }

    /// The columns read on every frame (the rim gauge's band).
    pub fn band_columns(&self) -> Range<usize> {
        self.columns.clone()
    }

    /// The gap of one frame (of the calibration frames' size; the rim gauge has
    /// checked that).
    pub fn measure(&self, frame: &FrameView) -> GapSample {
        let (x0, x1) = (self.columns.start, self.columns.end);
        let mean = |y: usize| f64::from(row_band_mean(frame, y, x0, x1));
        let (y0, y1) = (self.window.start, self.window.end);
        let scale_rows = (y0 - SCALE_ROWS..y0).chain(y1..y1 + SCALE_ROWS);
        let scale = scale_rows.map(mean).sum::<f64>() / self.scale_reference;
        let deficit = self
            .window
            .clone()
            .zip(&self.reference)
            .map(|(y, &r)| f64::from(r) - mean(y) / scale)
            .sum();
        GapSample { deficit }
    }

    /// Replaces the rim heights of narrow gaps (below [`NARROW_GAP_PX`], contact
    /// included) by the gap's darkness over the darkness per pixel of lift, learned
    /// from the frames whose edge lies in [`CALIBRATION_GAP_PX`] (module docs).
    /// `heights` are the edge method's z_rim per frame (`None`: no edge, left
    /// alone), `samples` the gap of the same frames. Returns the darkness per pixel
    /// of lift [grey levels], or `None` (and changes nothing) when fewer than three
    /// frames lift the rim that far.
    pub fn resolve(&self, heights: &mut [Option<f64>], samples: &[GapSample]) -> Option<f64> {
        let mut per_px: Vec<f64> = heights
            .iter()
            .zip(samples)
            .filter_map(|(z, s)| {
                let z = (*z)?;
                CALIBRATION_GAP_PX.contains(&z).then(|| s.deficit / z)
            })
            .collect();
        if per_px.len() < 3 {
            return None;
        }
        let darkness = crate::numeric::upper_median(&mut per_px);
        if darkness.is_nan() || darkness <= 0.0 {
            return None;
        }
        for (z, sample) in heights.iter_mut().zip(samples) {
            if let Some(height) = z
                && *height < NARROW_GAP_PX
            {
                *height = sample.deficit / darkness;
            }
        }
        Some(darkness)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::synthetic::SideScene;
    use crate::vision::{RimGauge, calibrate_at_rest};

    /// On the synthetic dark plate (exact area sampling; the gap shows the
    /// background above the plate line and the plate below it): z_rim of narrow
    /// gaps within 0.01 px at any sub-pixel phase, where the edge reads up to
    /// 0.3 px off, and unchanged rim heights from 2 px up.
    #[test]
    fn narrow_gaps_from_their_darkness() {
        let s = SideScene::standard();
        let config = SideViewConfig::default();
        let rest = s.dark_plate(0.0, 0.55);
        let rest_bytes = rest.to_bgr(3);
        let rest_view = [rest.view(&rest_bytes, 3)];
        let report = calibrate_at_rest(&rest_view, 0, &config, None).unwrap();
        let gauge = GapGauge::new(&report.calibration, &config, &rest_view)
            .unwrap()
            .expect("the window fits");
        let rim = RimGauge::new(&report.calibration, &report.threshold, &config, s.w, s.h).unwrap();
        let lifts = [
            0.0, 0.13, 0.37, 0.6, 0.85, 1.2, 1.55, 1.9, 2.6, 3.0, 3.3, 3.8, 7.0,
        ];
        let (mut heights, mut samples) = (Vec::new(), Vec::new());
        for &lift in &lifts {
            let frame = s.dark_plate(lift, 0.55);
            let bytes = frame.to_bgr(3);
            let view = frame.view(&bytes, 3);
            heights.push(rim.measure(&view, 0).unwrap().z_rim_px());
            samples.push(gauge.measure(&view));
        }
        let edge = heights.clone();
        let darkness = gauge
            .resolve(&mut heights, &samples)
            .expect("three wide gaps");
        // Disk 230 above, mirror 35 + 0.55 (230 − 35) below; background 25 and
        // plate 35 in the gap.
        let expected = 230.0 + (35.0 + 0.55 * 195.0) - 25.0 - 35.0;
        assert!(
            (darkness / expected - 1.0).abs() < 0.01,
            "darkness {darkness}"
        );
        for ((&lift, z), z_edge) in lifts.iter().zip(&heights).zip(&edge) {
            let z = z.unwrap();
            if lift < NARROW_GAP_PX {
                assert!(
                    (z - lift).abs() < 0.01,
                    "lift {lift}: {z} (edge {z_edge:?})"
                );
            } else {
                assert_eq!(Some(z), *z_edge, "lift {lift}");
            }
        }
        // Without wide gaps G is unknown: nothing changes.
        let mut few = edge[..4].to_vec();
        assert_eq!(gauge.resolve(&mut few, &samples[..4]), None);
        assert_eq!(few, &edge[..4]);
    }
}
