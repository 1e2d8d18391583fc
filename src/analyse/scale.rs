//! The side view's two scales, eq. 3.10's at the near rim and the diameter's at the
//! disk's centre, and what they say about the camera: its distance, its elevation at
//! the near bottom rim and the local scale there (issue 12 §2).

use serde::{Deserialize, Serialize};

use crate::model::params::DiskParams;
use crate::signal::SideViewRim;
use crate::vision;

/// The side view's two scales and what they say about the camera.
///
/// The diameter 2R/(x_r − x_l) gives the scale at the disk's centre; the thickness
/// 2H/(z_b − z_t) (eq. 3.10, z_t the near top rim, z_b the near bottom rim's row on
/// the plate) the scale at the near rim,
/// where z_rim is read. Through a pinhole the near rim is larger by the
/// perspective factor f = (distance to the centre)/(distance to the near rim), so
/// the distance from the camera to the near rim is about R/(f − 1) (exact for a
/// camera at the plate's height; within cos ε at an elevation ε).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ScaleReport {
    /// 2R/(x_r − x_l) [m/px].
    pub diameter_metres_per_px: f64,
    /// 2H/(z_b − z_t) [m/px] (eq. 3.10 with ERRATA).
    pub thickness_metres_per_px: f64,
    /// z_b \[px\]: the row where the near bottom rim meets the plate. The calibration's
    /// z_base, the edge of the side at rest, unless the mirror-edge model measured
    /// the rim (a dark plate): then the plate line where the rim meets its mirror
    /// image (on rounded rims z_base lies 0.8–2.3 px above the true rim, the plate
    /// line within 0.5 px of it, and eq. 3.10's scale from z_base is 1.0–1.4 % large;
    /// a sharp rim's plate line lies within 0.2 px of its edge).
    /// `None` in results written before it was recorded (then z_base).
    #[serde(default)]
    pub bottom_rim_row_px: Option<f64>,
    /// diameter ÷ thickness scale: 1 for a distant (orthographic) camera.
    pub perspective_factor: f64,
    /// The camera's distance from the near rim \[m\]: R/(f − 1) when f > 1, or the
    /// config's `camera_distance_m` ([`Self::camera_distance_from_config`]).
    pub camera_distance_m: Option<f64>,
    /// Whether [`Self::camera_distance_m`] is the config's (false in results written
    /// before it could be).
    #[serde(default)]
    pub camera_distance_from_config: bool,
    /// Which scale is used: "thickness (eq. 3.10, at the near rim)" or
    /// "diameter (…reason)".
    pub used: String,
    /// The silhouette's top on the centre line at rest, the top face's far rim \[px\]
    /// ([`vision::silhouette_top`]; where that sees no face 1.5 px above the rest
    /// frames' z_t and the leaning frames read the near top rim
    /// ([`super::TopRimLeaning`]), the rest frames' z_t, which is then the silhouette's
    /// top); `None` when not seen, and in results written before it was recorded.
    #[serde(default)]
    pub silhouette_top_px: Option<f64>,
    /// ε: the elevation of the camera's ray to the near bottom rim \[rad\], where
    /// z_rim is read ([`Self::with_near_rim_elevation`]); `None` without the
    /// silhouette's top.
    #[serde(default)]
    pub near_rim_elevation_rad: Option<f64>,
    /// s_b/δ: the camera's local vertical scale at the near bottom rim, where z_rim is
    /// read, over eq. 3.10's δ, the mean over the rim's thickness
    /// ([`Self::with_local_scale_at_near_rim`]); `None` (taken as 1) without the
    /// camera's distance and elevation, and in results written before it was recorded.
    #[serde(default)]
    pub near_rim_local_factor: Option<f64>,
    /// The row of the camera's principal point in the side view \[px\] that
    /// [`Self::near_rim_local_factor`] assumes: the centre of the frame's side view.
    #[serde(default)]
    pub principal_row_px: Option<f64>,
}

/// The perspective factors eq. 3.10's thickness scale is trusted within: a camera
/// 0.1 m from a 38 mm disk gives 1.38; below 1 the near rim would be farther than
/// the centre, which no side view shows, so z_t is not the near top rim (a top face
/// lit like the side leaves only the silhouette's far rim) beyond a 3 % margin for
/// the edges' errors.
pub(super) const PERSPECTIVE_FACTOR_RANGE: (f64, f64) = (0.97, 1.5);

impl ScaleReport {
    /// The scale to use from the calibration, the near bottom rim's row on the
    /// plate `bottom_rim_row` (z_b) and the disk's size.
    pub(super) fn new(cal: &vision::Calibration, bottom_rim_row: f64, disk: &DiskParams) -> Self {
        let diameter = 2.0 * disk.radius / (cal.x_r - cal.x_l);
        let thickness = cal.metres_per_px(disk.half_thickness, bottom_rim_row);
        let factor = diameter / thickness;
        let (lo, hi) = PERSPECTIVE_FACTOR_RANGE;
        let used = if (lo..=hi).contains(&factor) {
            "thickness (eq. 3.10, at the near rim)".to_string()
        } else {
            format!(
                "diameter: the thickness scale 2H/(z_b − z_t) = {thickness:.4e} m/px gives a \
                 perspective factor {factor:.3}, outside {lo}–{hi} (the near top rim z_t was not \
                 told from the top face's far rim, or the disk parameters do not match the disk \
                 filmed); φ is then too small by about the perspective factor"
            )
        };
        ScaleReport {
            diameter_metres_per_px: diameter,
            thickness_metres_per_px: thickness,
            bottom_rim_row_px: Some(bottom_rim_row),
            perspective_factor: factor,
            camera_distance_m: (factor > 1.0 && factor <= hi).then(|| disk.radius / (factor - 1.0)),
            camera_distance_from_config: false,
            used,
            silhouette_top_px: None,
            near_rim_elevation_rad: None,
            near_rim_local_factor: None,
            principal_row_px: None,
        }
    }

    /// The scale with the camera's distance from the near rim measured, `given` \[m\]
    /// (the config's `camera_distance_m`), in place of the perspective factor's; the
    /// scale itself stays eq. 3.10's, and the elevation and the local scale at the
    /// near bottom rim follow from the distance.
    pub fn with_camera_distance(mut self, given: Option<f64>) -> Self {
        if let Some(d) = given {
            self.camera_distance_m = Some(d);
            self.camera_distance_from_config = true;
        }
        self
    }

    /// The scale with the elevation ε of the camera's ray to the near bottom rim,
    /// from the top face's height F = z_t − `silhouette_top` on the centre line (the
    /// near top rim to the far one) at the centre's scale δ_c = 2R/(x_r − x_l):
    ///
    /// * a distant camera sees the face's diameter 2R foreshortened to 2R sin ε, so
    ///   sin ε = F δ_c / 2R;
    /// * a pinhole at the distance d from the near rim ([`Self::camera_distance_m`])
    ///   and Δh above the top face sees its near and far rims, at d_c ∓ R from below
    ///   the camera (d_c = d + R), F = f Δh (1/(d_c − R) − 1/(d_c + R)) apart with
    ///   f = d_c/δ_c, so Δh = F δ_c (d_c² − R²)/(2R d_c); the camera is Δh + 2H above
    ///   the plate and tan ε = (Δh + 2H)/d at the near bottom rim. Close to the disk
    ///   that is 0.5–1.5° more than the top face's own elevation (at 0.45 m: 2.53° at
    ///   the bottom rim, 0.91° at the top face).
    pub fn with_near_rim_elevation(
        mut self,
        cal: &vision::Calibration,
        silhouette_top: Option<f64>,
        disk: &DiskParams,
    ) -> Self {
        let (r, thickness) = (disk.radius, 2.0 * disk.half_thickness);
        let delta_c = self.diameter_metres_per_px;
        self.silhouette_top_px = silhouette_top;
        self.near_rim_elevation_rad = silhouette_top.map(|top| {
            let face = (cal.z_t - top).max(0.0) * delta_c;
            match self.camera_distance_m {
                Some(d) => {
                    let d_c = d + r;
                    let above_face = face * (d_c * d_c - r * r) / (2.0 * r * d_c);
                    ((above_face + thickness) / d).atan()
                }
                None => (face / (2.0 * r)).min(1.0).asin(),
            }
        });
        self
    }

    /// The scale at the point measured (issue 12 §2): eq. 3.10's δ = 2H/(z_b − z_t) is
    /// the mean vertical scale over the near rim's thickness, while z_rim is read at its
    /// bottom. Through a pinhole pitched down by p, a point at the horizontal distance d
    /// seen θ below the horizontal has the vertical scale s(θ) = d cos²(θ − p)/(F cos²θ)
    /// [m/px] (F the focal length in px), so at the near bottom rim, θ_b = ε
    /// ([`Self::near_rim_elevation_rad`]),
    ///
    /// ```text
    /// s_b/δ = d cos²(θ_b − p) [tan(θ_b − p) − tan(θ_t − p)] / (2H cos²θ_b),
    /// tan θ_t = tan θ_b − 2H/d            (the near top rim, 2H higher),
    /// tan(θ_b − p) = (z_b − c_y)/F,  F = (d + R)/δ_c,
    /// ```
    ///
    /// with d the camera's distance from the near rim ([`Self::camera_distance_m`]),
    /// δ_c the diameter's scale at the disk's centre and c_y the principal point's
    /// row, `principal_row`: the centre of the frame's side view, where a phone's
    /// camera and other renderers have it (ours aims at the disk's centre on the
    /// plate, 0.05 of the rows lower, which moves the factor by about a tenth of its
    /// departure from 1). To first order s_b/δ − 1 = (2H/d)(tan θ_b − tan(θ_b − p)):
    /// +0.1 … +0.5 % for a camera 0.2–0.6 m away looking down by 2–5°, by which δ
    /// alone read the scale, and so φ, too small; 1 for a distant camera. Left at 1
    /// when δ is not used or the distance or ε is not known.
    pub fn with_local_scale_at_near_rim(mut self, principal_row: f64, disk: &DiskParams) -> Self {
        let (Some(d), Some(theta_b), Some(z_b)) = (
            self.camera_distance_m,
            self.near_rim_elevation_rad,
            self.bottom_rim_row_px,
        ) else {
            return self;
        };
        if !self.at_near_rim() {
            return self;
        }
        let thickness = 2.0 * disk.half_thickness;
        let focal_px = (d + disk.radius) / self.diameter_metres_per_px;
        let off_axis_b = (z_b - principal_row) / focal_px; // tan(θ_b − p)
        let pitch = theta_b - off_axis_b.atan();
        let theta_t = (theta_b.tan() - thickness / d).atan();
        let off_axis_t = (theta_t - pitch).tan();
        let factor = d * (off_axis_b.atan().cos().powi(2)) * (off_axis_b - off_axis_t)
            / (thickness * theta_b.cos().powi(2));
        self.near_rim_local_factor = factor.is_finite().then_some(factor);
        self.principal_row_px = Some(principal_row);
        self
    }

    /// Whether eq. 3.10's scale at the near rim is used (its perspective factor is
    /// plausible), rather than the diameter's.
    pub fn at_near_rim(&self) -> bool {
        let (lo, hi) = PERSPECTIVE_FACTOR_RANGE;
        (lo..=hi).contains(&self.perspective_factor)
    }

    /// The rim's profile as this camera sees it: [`SideViewRim`] at the near rim's
    /// elevation; `None` when the elevation is not known.
    pub fn side_view_rim(&self, disk: &DiskParams) -> Option<SideViewRim> {
        self.near_rim_elevation_rad
            .map(|camera_elevation| SideViewRim {
                radius: disk.radius,
                half_thickness: disk.half_thickness,
                camera_elevation,
            })
    }

    /// The scale used [m/px]: at the near bottom rim, eq. 3.10's times
    /// [`Self::near_rim_local_factor`].
    pub fn metres_per_px(&self) -> f64 {
        if self.at_near_rim() {
            self.thickness_metres_per_px * self.near_rim_local_factor.unwrap_or(1.0)
        } else {
            self.diameter_metres_per_px
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pinhole 4° above the near rim and pitched down by 3°, seen exactly. At
    /// 0.25 m, with the distance from the perspective factor: eq. 3.10's δ, the mean
    /// over the thickness, is 0.3 % under the scale at the near bottom rim (the rows'
    /// derivative there), and the local factor gives that scale to 0.02 %. At 50 m,
    /// with the distance given: the factor tends to 1 and still gives the tiny
    /// departure there (1.3e-5) to 1e-6.
    #[test]
    fn the_scale_is_the_local_one_at_the_near_bottom_rim() {
        let disk = DiskParams::solid_disk_thesis(0.4, 0.0381, 0.00635);
        let (r, thickness) = (disk.radius, 2.0 * disk.half_thickness);
        for (d, focal_px) in [(0.25, 1500.0), (50.0, 300_000.0)] {
            let (elevation, pitch, principal_row) = (4f64.to_radians(), 3f64.to_radians(), 120.0);
            let camera_height = d * elevation.tan();
            // The row of a point `h` above the plate at the horizontal distance `x`.
            let row = |h: f64, x: f64| {
                principal_row + focal_px * (((camera_height - h) / x).atan() - pitch).tan()
            };
            let (z_b, z_t) = (row(0.0, d), row(thickness, d));
            let half_diameter = focal_px * r / (d + r);
            let cal = vision::Calibration {
                x_l: 200.0 - half_diameter,
                x_r: 200.0 + half_diameter,
                z_t,
                z_base: z_b,
            };
            let step = 1e-7;
            let local = step / (row(0.0, d) - row(step, d));
            let mut scale = ScaleReport::new(&cal, z_b, &disk);
            scale.near_rim_elevation_rad = Some(elevation);
            let eq_3_10 = scale.metres_per_px();
            if d < 1.0 {
                let scale = scale.with_local_scale_at_near_rim(principal_row, &disk);
                let factor = scale.near_rim_local_factor.expect("a factor");
                assert!(local / eq_3_10 - 1.0 > 0.002, "{local} vs {eq_3_10}");
                let error = scale.metres_per_px() / local - 1.0;
                assert!(error.abs() < 2e-4, "error {error:e}, factor {factor}");
            } else {
                // The perspective factor reads under 1 here (cos²θ at 4°), which
                // gives no distance: it is given, as the config would.
                assert_eq!(scale.camera_distance_m, None);
                let scale = scale
                    .with_camera_distance(Some(d))
                    .with_local_scale_at_near_rim(principal_row, &disk);
                let factor = scale.near_rim_local_factor.expect("a factor");
                assert!((factor - 1.0).abs() < 1e-4, "factor {factor}");
                let error = scale.metres_per_px() / local - 1.0;
                assert!(error.abs() < 1e-6, "error {error:e}, factor {factor}");
            }
        }
    }
}
