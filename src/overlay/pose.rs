//! The side camera's pose, as far as the rest-frame calibration tells it: the
//! camera that draws the simulated disk over the footage (`compare`'s
//! `model-overlay.mp4`).
//!
//! There is no full pose estimate (no checkerboard, no vanishing points); what the
//! calibration gives is used, and this is the approximation:
//!
//! * **Scale.** 2R/(x_r − x_l), the diameter's scale, is the scale at the depth of
//!   the disk's centre ([`crate::analyse::ScaleReport`]).
//! * **Elevation ε.** The top face is a circle of radius R seen as an ellipse whose
//!   height, from the near top rim z_t up to the far top rim (the silhouette's
//!   top on the centre column, `z_top`), is 2R sin ε at the centre's scale:
//!   sin ε = (z_t − z_top) · s / 2R. A camera level with the top face sees no
//!   ellipse and gets ε = 0.
//! * **Distance.** Through a pinhole at elevation ε the diameter's scale (at the
//!   centre's depth d + R cos ε) over the thickness's (2H/(z_base − z_t), at the
//!   near rim's depth d, foreshortened by cos ε) is the perspective factor
//!   f = cos ε (d + R cos ε)/d, so d = R cos² ε / (f − cos ε). Where f ≤ cos ε + 0.002
//!   (a distant camera, or f not measured) the camera is orthographic. The config's
//!   `camera_distance_m`, when given, is taken instead.
//! * **Placement.** The optical axis passes through the plate point under the
//!   disk's rest centre, on the centre line x_centre; the row is chosen so that the
//!   resting disk's near bottom rim (0, −R, 0) lands on the row where z_rim = 0.
//!
//! The camera is [`crate::render::scene::Camera`], the renderer's (pixel centres
//! at integers, so `vision`'s rows and columns are 0.5 more).

use crate::analyse::ExperimentPlan;
use crate::render::scene::{Camera, Pinhole, View};

/// The pose and how it was found, for the compare report.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct CameraPose {
    /// Elevation ε \[rad\].
    pub elevation: f64,
    /// Depth of the near rim's mid-height point along the optical axis \[m\]; `None`:
    /// orthographic.
    pub distance_m: Option<f64>,
    /// Scale at the disk centre's depth [m/px].
    pub centre_metres_per_px: f64,
    /// The silhouette's top on the centre column at rest [row, `vision`'s convention].
    pub z_top: f64,
}

impl CameraPose {
    /// The pose from the calibration of `plan` and the silhouette's top `z_top`.
    pub fn from_calibration(plan: &ExperimentPlan, z_top: f64) -> Self {
        let c = &plan.calibration.calibration;
        let radius = plan.disk.radius;
        let scale = plan.scale.diameter_metres_per_px;
        let sin_e = ((c.z_t - z_top).max(0.0) * scale / (2.0 * radius)).min(0.5);
        let cos_e = (1.0 - sin_e * sin_e).sqrt();
        let factor = plan.scale.perspective_factor;
        let measured = (plan.scale.at_near_rim() && factor > cos_e + 0.002)
            .then(|| radius * cos_e * cos_e / (factor - cos_e));
        // A distance the config gives was measured (along the plate; along the
        // optical axis within cos ε).
        let distance_m = plan.config.camera_distance_m.or(measured);
        Self {
            elevation: sin_e.asin(),
            distance_m,
            centre_metres_per_px: scale,
            z_top,
        }
    }

    /// The side camera in the side view's pixel coordinates (the renderer's
    /// convention: pixel centres at integers).
    pub fn camera(&self, plan: &ExperimentPlan) -> Camera {
        let c = &plan.calibration.calibration;
        let (radius, half) = (plan.disk.radius, plan.disk.half_thickness);
        let (se, ce) = self.elevation.sin_cos();
        let cx = c.x_centre() - 0.5;
        let zero_row = plan.rim_edge_row(0.0) - 0.5;
        let mut camera = Camera {
            view: View::Side,
            cx,
            cy: 0.0,
            scale: self.centre_metres_per_px,
            elevation: self.elevation,
            row_start: 0,
            row_end: plan.height as u32,
            pinhole: None,
        };
        if let Some(d) = self.distance_m {
            // C = −D f with D the depth of the origin: d + R cos ε + H sin ε.
            let depth_origin = d + radius * ce + half * se;
            let position = [0.0, -depth_origin * ce, depth_origin * se];
            let focal_px = (d + radius * ce) / self.centre_metres_per_px;
            camera.pinhole = Some(Pinhole { position, focal_px });
        }
        // Place the near bottom rim at rest on the zero row.
        let (_, row) = camera.project([0.0, -radius, 0.0]);
        camera.cy = zero_row - row;
        camera
    }
}

#[cfg(test)]
mod tests {
    /// The distance formula inverts the perspective factor of a pinhole at
    /// elevation ε: f = cos ε (d + R cos ε)/d.
    #[test]
    fn distance_inverts_the_perspective_factor() {
        let (r, d, e) = (0.038f64, 0.3f64, 5f64.to_radians());
        let f = e.cos() * (d + r * e.cos()) / d;
        let back = r * e.cos() * e.cos() / (f - e.cos());
        assert!((back - d).abs() < 1e-12, "{back}");
    }
}
