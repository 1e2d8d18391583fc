//! Vision: the second stage of the data flow, frames → pixel measurements.
//!
//! Input is a [`FrameView`](crate::footage::FrameView) per frame, as `footage`
//! decodes it; output is, per frame, the rim height `z_rim` in px
//! ([`RimHeight`]) and, for two-view clips, the strip angle β ([`Strip`]).
//! The conversion to metres happens once, with [`Calibration::metres_per_px`]
//! (thesis eq. 3.10 as corrected in ERRATA), at the boundary to `signal`.
//! This module neither reads files nor prints.
//!
//! # Side view (thesis §3.2.3–3.2.5)
//!
//! 1. [`calibrate_at_rest`] looks at the last frames, after the halt, with the
//!    disk lying flat: it picks γ ([`Threshold`]: given, or Otsu on the rest
//!    frame), finds x_l, x_r, z_t and z_base ([`Calibration`], each
//!    overridable by hand as the thesis did), and fails with
//!    [`VisionError::NotAtRest`] when the frames differ.
//! 2. [`RimGauge::measure`] then reads one frame: it touches only a band of
//!    columns around the centre line x_centre = (x_l + x_r)/2 and returns
//!    z_rim = z_base − (bottom edge row), sub-pixel. On a dark plate,
//!    [`GapGauge`] reads the rim heights below 2 px from the darkness of the gap
//!    between the disk and its mirror image instead, where no row shows the gap's
//!    own level and the edge cannot be placed.
//!
//! # Two views (thesis §3.3.2)
//!
//! [`find_split_row`] and [`split_views`] cut a portrait frame into the mirror
//! side view (top, measured as above) and the plan view (bottom), in which
//! [`StripFinder`] finds the red strip (eq. 3.23 on RGB normalised by the image
//! mean, largest connected component) and its principal axis (eq. 3.24).
//!
//! # Coordinates
//!
//! Image coordinates are continuous, in px: pixel (column c, row r) covers
//! [c, c+1) × [r, r+1), so its centre is (c + ½, r + ½). Rows grow downward;
//! heights such as z_rim are positive upward. Intensities are the mean of the
//! three channels, 0–255; the thesis's γ is that mean divided by 256.

mod band_window;
mod calibration;
mod components;
mod error;
mod gap;
mod leaning_face;
mod light_plate;
mod mirror_edge;
mod profile;
mod registration;
mod rim;
mod rim_zero;
mod shadow_edge;
mod threshold;
mod top_rim;
mod two_view;

#[cfg(test)]
mod synthetic;

pub use band_window::BandWindow;
pub(crate) use calibration::band;
pub use calibration::{
    Calibration, CalibrationOverride, CalibrationReport, PointSource, SideViewConfig,
    calibrate_at_rest, calibrate_frame,
};
pub use error::VisionError;
pub use gap::{GapGauge, GapSample};
pub use leaning_face::{LeanGauge, LeaningTopRim, THIN_AT_REST_PX, near_top_rim_leaning};
pub use mirror_edge::{
    EdgeTemplate, MirrorEdgeModel, SHARP_RIM_PX, remeasure as remeasure_dark_rim,
};
pub use registration::{Registration, SceneStrips, StripProfiles, register};
pub use rim::{RimGauge, RimHeight};
pub use rim_zero::{MOTION_ZERO_PROFILE_PX, RimReading};
pub use shadow_edge::{ShadowEdgeModel, remeasure as remeasure_light_rim};
pub use threshold::{GammaSource, INTENSITY_SCALE, Threshold};
pub use top_rim::{TopFace, silhouette_top};
pub use two_view::{
    ColourThresholds, LayoutDetection, Strip, StripFinder, ThresholdSource, auto_colour_thresholds,
    detect_two_view, find_split_row, split_views,
};
