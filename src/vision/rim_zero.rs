//! How well the zero of z_rim is known, by how the rim was read.
//!
//! The zero is the edge at rest. A lifted rim's edge is read the same way, but not
//! exactly: blur, the rim's rounding, the mirror image or the shadow under it and the
//! codec differ between rest and lift, so every lifted height of a clip carries one
//! shared offset (on sharp rendered rims a clip's heights are off by the same amount to
//! ±0.03 px from 0.25 to 6 px; on rounded rims the offset also changes with the
//! height). The residuals of the energy fits cannot show it; `analyse` refits with the
//! zero moved by ± its 1σ uncertainty and carries half the change of n into n's
//! interval.
//!
//! That uncertainty is a property of the reading, measured against ground truth as
//! the RMS over clips of the mean error of z_rim over the frames lifted past 0.5 px
//! in the last 0.5 s before the halt (`scripts/zero-error` for the renders). Each
//! value below was measured on footage other than the renders `scripts/coverage`
//! scores the intervals on (its seeds 1–120), so that coverage is an out-of-sample
//! test of it.

use serde::{Deserialize, Serialize};

/// How far the zero the motion places lies from the truth beyond its fit's
/// standard error \[px\]: the camera's elevation in the profile is known to ±0.5°, φ
/// may oscillate about stationary rolling, and a renderer's or a camera's pictures
/// of a lifted rim may share an error no fit of the motion sees. Measured as the RMS
/// over clips of the difference from the truth's offset of the lifted heights:
/// 0.024 px on rounded rims coded at the footage's quality (the largest 0.044 px
/// with φ oscillating; side views all 0.02–0.04 px low), 0.008–0.009 px on rendered
/// scenes (the largest 0.037 px at a quantiser coarser than the footage's); 0.03 px.
/// docs/validation.md, "Open footage", gives today's figure.
pub const MOTION_ZERO_PROFILE_PX: f64 = 0.03;

/// The method that read the rim's heights, as far as it decides how well their zero
/// is known.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RimReading {
    /// The mirror-edge model on a rim it found sharp
    /// ([`MirrorEdgeModel::is_sharp`](super::MirrorEdgeModel::is_sharp)).
    SharpMirrorEdge,
    /// The mirror-edge model on a rounded rim.
    RoundedMirrorEdge,
    /// The shadow-edge contour of a light plate.
    ShadowEdge,
    /// The first pass (threshold edge and gap darkness), when no model could be fitted.
    FirstPass,
}

impl RimReading {
    /// 1σ of the zero of z_rim \[px\] for heights read this way.
    ///
    /// * Sharp rim, mirror-edge model: RMS 0.039 px (mean −0.028, −0.094 … +0.011 px)
    ///   over the 50 dark-plate renders of `scripts/coverage`'s conditions drawn with
    ///   seeds 1001–1060 (dark, blurred, flickering, drifting, two-view); 0.04 px.
    /// * Shadow edge (light plate): RMS 0.056 px over the 10 light-plate renders of
    ///   those seeds and 0.070 px over the open set's two light clips (−0.098,
    ///   −0.011 px); 0.06 px over all 12.
    /// * Rounded rim, mirror-edge model: 0.08 px. The open set's six dark clips, the
    ///   only rounded rims with a truth, measure RMS 0.060 px (−0.10 … +0.10 px)
    ///   today and measured 0.073 px before each edge became the mean over its
    ///   likelihood; six clips do not pin it down better than that, and the footage
    ///   we are scored on is like them, so the earlier, larger value stays.
    /// * First pass: 0.08 px, as the rounded rim; its lifted heights were measured
    ///   0.02–0.12 px low on sharp renders before the model read them.
    pub fn zero_uncertainty_px(self) -> f64 {
        match self {
            RimReading::SharpMirrorEdge => 0.04,
            RimReading::ShadowEdge => 0.06,
            RimReading::RoundedMirrorEdge | RimReading::FirstPass => 0.08,
        }
    }

    /// 1σ of the zero of z_rim \[px\] where the motion places it (`signal::motion_zero`),
    /// from the fit's standard error `se_px`: that and the profile's own error,
    /// [`MOTION_ZERO_PROFILE_PX`], in quadrature.
    pub fn motion_zero_uncertainty_px(se_px: f64) -> f64 {
        se_px.hypot(MOTION_ZERO_PROFILE_PX)
    }

    /// The reading in words, for the report.
    pub fn describe(self) -> &'static str {
        match self {
            RimReading::SharpMirrorEdge => "a sharp rim read by the mirror-edge model",
            RimReading::RoundedMirrorEdge => "a rounded rim read by the mirror-edge model",
            RimReading::ShadowEdge => "the shadow edge of a light plate",
            RimReading::FirstPass => "the first pass (threshold edge and gap darkness)",
        }
    }
}
