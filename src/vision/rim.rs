//! Rim height per frame (thesis §3.2.4, figs. 3.7–3.9): the bottom edge of the
//! disk on the centre line, sub-pixel, as z_rim = z_base − edge row (px, up).
//!
//! # The edge
//!
//! The search walks *up* a band of columns around the centre line, from just
//! below the plate line (z_base + `search_below_px`), and stops at the first
//! dark-to-bright step: the bottom edge of the disk. One rule serves both kinds
//! of plate:
//!
//! - dark plate: below the rolling disk lies its mirror image, and the two are
//!   separated by a dark gap of height 2·z_rim centred on the plate line. The
//!   walk starts in that gap (or in the mirror image, when the gap is narrower
//!   than `search_below_px`, and then crosses the gap), and the first rise is
//!   the disk's bottom edge, never the reflection's top edge.
//! - light plate: the walk starts on the bright plate or in the shadow under
//!   the disk; going up it meets plate → shadow (falling) and then shadow →
//!   disk (rising): the "second edge from the bottom" of §3.2.4.
//!
//! When the band stays bright from the start up past the middle of the disk,
//! the gap has closed: the rim touches the plate ([`RimHeight::Contact`],
//! z_rim = 0). A gap narrower than the optical blur, whose dip never falls
//! below γ, reads as contact too.
//!
//! # Sub-pixel position and cost
//!
//! The band's intensities are averaged across its columns row by row (one
//! profile, the same as averaging the columns' edges for a straight edge, with
//! less noise), and the edge is placed by the area of the step: the transition
//! from the disk above to the gap or shadow below is the monotone run of rows
//! through the first rise (at most three either side), and the edge lies as
//! far below the run's top as the run's summed coverage of the disk level
//! (`area_edge`). For an anti-aliased edge, blurred or not, that is exact at any
//! sub-pixel phase; linear interpolation of the half level, used before, erred
//! by up to ±0.086 px with the phase, and by ≈ +0.07 px on the rendered dark
//! fixture's plate line (a constant bias in every z_rim). Only the rows
//! walked, plus four either side of the edge, are read, each (2·half_width + 1)
//! pixels wide: a few hundred bytes per frame, never the whole frame.

use std::ops::Range;

use super::VisionError;
use super::calibration::{Calibration, SideViewConfig, band};
use super::profile::{area_edge, check_frame, row_band_mean};
use super::threshold::Threshold;
use crate::footage::FrameView;

/// The rim measured on one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RimHeight {
    /// The bottom edge of the disk was found; z_rim = z_base − edge row, px, up.
    Edge { z_rim_px: f64, edge_row: f64 },
    /// No gap or shadow between plate and disk: the rim touches the plate.
    Contact,
    /// No edge on the centre line (the disk has left it, or the frame is dark).
    NoEdge,
}

impl RimHeight {
    /// z_rim in px: the edge's height, 0 on contact, `None` with no edge.
    pub fn z_rim_px(&self) -> Option<f64> {
        match *self {
            Self::Edge { z_rim_px, .. } => Some(z_rim_px),
            Self::Contact => Some(0.0),
            Self::NoEdge => None,
        }
    }
}

/// Measures the rim height of one frame after another, with everything that
/// does not change between frames resolved once.
#[derive(Clone, Debug)]
pub struct RimGauge {
    columns: Range<usize>,
    z_base: f64,
    /// First row read (below the plate line); the walk goes up from here.
    start_row: usize,
    /// Last row read going up (inclusive).
    stop_row: usize,
    /// Bright all the way up to this row (exclusive) from the start: contact.
    contact_row: f64,
    level: f32,
    width: usize,
    height: usize,
}

impl RimGauge {
    /// A gauge for `width × height` frames, from the calibration and γ.
    pub fn new(
        calibration: &Calibration,
        threshold: &Threshold,
        config: &SideViewConfig,
        width: usize,
        height: usize,
    ) -> Result<Self, VisionError> {
        calibration.validate(width, height)?;
        if config.search_below_px.is_nan() || config.search_below_px < 1.0 {
            return Err(VisionError::InvalidSetting {
                name: "search_below_px",
                value: config.search_below_px,
                reason: "the search must start at least 1 px below the plate line",
            });
        }
        let z_base = calibration.z_base;
        let start = (z_base + config.search_below_px).floor();
        if start > (height - 1) as f64 {
            return Err(VisionError::InvalidCalibration {
                x_l: calibration.x_l,
                x_r: calibration.x_r,
                z_t: calibration.z_t,
                z_base,
                width,
                height,
                reason: "the plate line is too close to the bottom of the frame to search below it",
            });
        }
        let stop = match config.max_rim_px {
            Some(m) if m > 0.0 => (z_base - m).floor().max(0.0) as usize,
            Some(m) => {
                return Err(VisionError::InvalidSetting {
                    name: "max_rim_px",
                    value: m,
                    reason: "must be positive",
                });
            }
            None => 0,
        };
        let (x0, x1) = band(calibration.x_centre(), config.half_width_px, width);
        Ok(Self {
            columns: x0..x1,
            z_base,
            start_row: start as usize,
            stop_row: stop,
            contact_row: z_base - (0.5 * calibration.disk_height_px()).max(1.0),
            level: threshold.level(),
            width,
            height,
        })
    }

    /// The columns read on every frame.
    pub fn band_columns(&self) -> Range<usize> {
        self.columns.clone()
    }

    /// The rim height in frame `index` (the index only labels errors, which
    /// arise only for a frame of the wrong size or a malformed view).
    pub fn measure(&self, frame: &FrameView, index: usize) -> Result<RimHeight, VisionError> {
        if (frame.width, frame.height) != (self.width, self.height) {
            return Err(VisionError::SizeMismatch {
                frame: index,
                width: frame.width,
                height: frame.height,
                expected_width: self.width,
                expected_height: self.height,
            });
        }
        check_frame(frame, index)?;
        let (x0, x1) = (self.columns.start, self.columns.end);
        let mean = |y: usize| row_band_mean(frame, y, x0, x1);
        let level = self.level;

        let mut below = mean(self.start_row);
        let mut seen_dark = below <= level;
        for y in (self.stop_row..self.start_row).rev() {
            let here = mean(y);
            if below <= level && here > level {
                return Ok(self.edge_at(frame, y, here, below));
            }
            seen_dark |= here <= level;
            if !seen_dark && (y as f64) < self.contact_row {
                return Ok(RimHeight::Contact);
            }
            below = here;
        }
        Ok(RimHeight::NoEdge)
    }

    /// The sub-pixel edge between bright row `y` and dark row `y + 1`.
    fn edge_at(&self, frame: &FrameView, y: usize, bright: f32, dark: f32) -> RimHeight {
        const REACH: usize = 3;
        let ys = y.saturating_sub(REACH);
        let ye = (y + REACH + 2).min(self.height);
        let mut buf = [0f32; 2 * REACH + 2];
        let p = &mut buf[..ye - ys];
        for (k, v) in p.iter_mut().enumerate() {
            *v = row_band_mean(frame, ys + k, self.columns.start, self.columns.end);
        }
        let edge_row = area_edge(p, y - ys, REACH, ys as f64).unwrap_or_else(|| {
            // Flat sides: interpolate the γ crossing itself.
            y as f64 + 0.5 + f64::from((bright - self.level) / (bright - dark))
        });
        RimHeight::Edge {
            z_rim_px: self.z_base - edge_row,
            edge_row,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::synthetic::{Canvas, SideScene, grey};
    use crate::vision::{CalibrationReport, calibrate_at_rest};

    fn calibrate(c: &Canvas, config: &SideViewConfig) -> CalibrationReport {
        let bytes = c.to_bgr(3);
        calibrate_at_rest(&[c.view(&bytes, 3)], 0, config, None).unwrap()
    }

    fn measure(gauge: &RimGauge, c: &Canvas) -> RimHeight {
        let bytes = c.to_bgr(3);
        gauge.measure(&c.view(&bytes, 3), 5).unwrap()
    }

    /// Checks every lift: the edge row against the drawn edge, and z_rim against
    /// the drawn lift through the *calibrated* z_base.
    fn check_lifts(
        s: &SideScene,
        draw: impl Fn(f64) -> Canvas,
        lifts: &[f64],
        edge_tol: f64,
        rim_tol: f64,
    ) {
        let config = SideViewConfig::default();
        let report = calibrate(&draw(0.0), &config);
        let gauge =
            RimGauge::new(&report.calibration, &report.threshold, &config, s.w, s.h).unwrap();
        assert_eq!(
            measure(&gauge, &draw(0.0))
                .z_rim_px()
                .map(|z| z.abs() < rim_tol),
            Some(true)
        );
        for &lift in lifts {
            match measure(&gauge, &draw(lift)) {
                RimHeight::Edge { z_rim_px, edge_row } => {
                    let truth = s.z_base - lift;
                    assert!(
                        (edge_row - truth).abs() < edge_tol,
                        "lift {lift}: edge {edge_row}, truth {truth}"
                    );
                    assert!(
                        (z_rim_px - lift).abs() < rim_tol,
                        "lift {lift}: z_rim {z_rim_px}"
                    );
                }
                other => panic!("lift {lift}: {other:?}"),
            }
        }
    }

    // Tolerances: a gap of ≥ 1.3 px shows both levels, so the half-level crossing
    // of an exactly anti-aliased edge is within 0.09 px (+ 8-bit rounding):
    // 0.1 px for the edge row; z_rim adds the calibrated z_base's own ≤ 0.1 px.
    const EDGE_TOL: f64 = 0.1;
    const RIM_TOL: f64 = 0.2;

    #[test]
    fn dark_plate_bright_reflection() {
        let s = SideScene::standard();
        let draw = |lift| s.dark_plate(lift, 0.55);
        check_lifts(&s, draw, &[1.3, 2.7, 5.25, 12.8, 60.4], EDGE_TOL, RIM_TOL);
        // At rest the gap is closed: contact, z_rim = 0.
        let config = SideViewConfig::default();
        let report = calibrate(&draw(0.0), &config);
        let gauge =
            RimGauge::new(&report.calibration, &report.threshold, &config, s.w, s.h).unwrap();
        assert_eq!(measure(&gauge, &draw(0.0)), RimHeight::Contact);
        assert_eq!(gauge.band_columns().len(), 5);
    }

    #[test]
    fn dark_plate_narrow_gap() {
        // A 1.2 px gap never shows the plate's own dark level (its darkest pixel is
        // 90 % gap), so the local half level sits ≈ 10 levels high: ≈ 0.1 px more
        // bias on the edge; 0.3 px covers it.
        let s = SideScene::standard();
        check_lifts(&s, |lift| s.dark_plate(lift, 0.55), &[0.6], 0.2, 0.3);
    }

    #[test]
    fn dark_plate_dim_reflection() {
        let s = SideScene::standard();
        check_lifts(
            &s,
            |lift| s.dark_plate(lift, 0.12),
            &[0.6, 1.3, 3.45, 20.0],
            EDGE_TOL,
            RIM_TOL,
        );
    }

    #[test]
    fn light_plate_second_edge_from_the_bottom() {
        let s = SideScene::standard();
        check_lifts(
            &s,
            |lift| s.light_plate(lift, 3.0),
            &[0.5, 1.3, 4.6, 15.1],
            EDGE_TOL,
            RIM_TOL,
        );
        // A deep shadow: the search starts inside it; the first rise is still the disk.
        check_lifts(
            &s,
            |lift| s.light_plate(lift, 8.0),
            &[0.5, 2.2],
            EDGE_TOL,
            RIM_TOL,
        );
    }

    #[test]
    fn noisy_frames() {
        // ±4 grey levels of uniform noise per channel: averaged over the band's
        // 5 columns × 3 channels the row mean has σ ≈ 0.6 levels against a 195-level
        // step, i.e. ≈ 0.01 px of edge noise; 0.2/0.3 px leaves room for the
        // calibration frame's own noise.
        let s = SideScene::standard();
        let draw = |lift: f64| {
            let mut c = s.dark_plate(lift, 0.55);
            c.noise(4.0, (lift * 100.0) as u64);
            c
        };
        check_lifts(&s, draw, &[1.3, 3.1, 7.7], 0.2, 0.3);
    }

    /// A tilted rim: the bottom edge slopes across the columns by sin φ per column (the
    /// steepest, at χ = 90°, `config::band_for_disk`), here 0.04 with the centre line
    /// lifted 4.8 px (φ = 0.04 rad on this 239 px disk). Read on the band of 2 % of the
    /// disk's width (±4 columns: edges within ±0.16 px) and on one of 5 % (±11: within
    /// ±0.44 px, the widest the config accepts), the band's mean reads the centre line's
    /// edge, as the area of a step is linear in the profile.
    #[test]
    fn a_tilted_rim_is_read_at_the_centre_line_on_a_wide_band() {
        let s = SideScene::standard();
        let x_c = 0.5 * (s.x_l + s.x_r);
        let (slope, lift) = (0.04, 4.8);
        let plate = 35.0;
        let mirror = plate + 0.55 * (s.disk - plate);
        let draw = |lift: f64, slope: f64| {
            let mut c = Canvas::from_rects(
                s.w,
                s.h,
                grey(s.background),
                &[(0.0, s.z_base, s.w as f64, s.h as f64, grey(plate))],
            );
            let bottom = move |x: f64| s.z_base - lift - slope * (x - x_c);
            let box_ = (s.x_l, s.z_t() - 20.0, s.x_r, s.z_base + s.thickness + 20.0);
            let inside_disk = |x: f64, y: f64| {
                (s.x_l..s.x_r).contains(&x) && y < bottom(x) && y >= bottom(x) - s.thickness
            };
            let inside_mirror = |x: f64, y: f64| {
                let top = 2.0 * s.z_base - bottom(x);
                (s.x_l..s.x_r).contains(&x) && y >= top && y < top + s.thickness
            };
            c.shape(box_, 8, inside_disk, grey(s.disk));
            c.shape(box_, 8, inside_mirror, grey(mirror));
            c
        };
        for half_width_px in [
            crate::config::band_for_disk(s.x_r - s.x_l, 2),
            (0.05 * (s.x_r - s.x_l)).floor() as usize,
        ] {
            let config = SideViewConfig {
                half_width_px,
                ..SideViewConfig::default()
            };
            let report = calibrate(&draw(0.0, 0.0), &config);
            let gauge =
                RimGauge::new(&report.calibration, &report.threshold, &config, s.w, s.h).unwrap();
            assert_eq!(gauge.band_columns().len(), 2 * half_width_px + 1);
            // The edge row against the drawn one (the rest frame's z_base is off by
            // the blending of two shapes in one pixel row, which is not the point here).
            let truth = s.z_base - lift;
            match measure(&gauge, &draw(lift, slope)) {
                RimHeight::Edge { edge_row, .. } => assert!(
                    (edge_row - truth).abs() < EDGE_TOL,
                    "band ±{half_width_px}: edge {edge_row}, centre line's {truth}"
                ),
                other => panic!("band ±{half_width_px}: {other:?}"),
            }
        }
    }

    #[test]
    fn no_edge_without_a_disk() {
        let s = SideScene::standard();
        let config = SideViewConfig::default();
        let report = calibrate(&s.dark_plate(0.0, 0.55), &config);
        let gauge =
            RimGauge::new(&report.calibration, &report.threshold, &config, s.w, s.h).unwrap();
        let gone = SideScene {
            x_l: 10.0,
            x_r: 60.0,
            ..s
        };
        assert_eq!(
            measure(&gauge, &gone.dark_plate(3.0, 0.55)),
            RimHeight::NoEdge
        );
        assert_eq!(RimHeight::NoEdge.z_rim_px(), None);
        // A frame of another size is an error naming the frame.
        let small = Canvas::new(100, 100, [0.0; 3]);
        let bytes = small.to_bgr(0);
        assert!(matches!(
            gauge.measure(&small.view(&bytes, 0), 12),
            Err(VisionError::SizeMismatch { frame: 12, .. })
        ));
    }
}
