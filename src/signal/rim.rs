//! What the side camera sees: the rim height z_rim as a function of the nutation
//! angle φ and the precession phase χ = ψ − ψ_c (see the derivation in the
//! [module docs](super)).
//!
//! The model is a trait, [`RimModel`], so the local fits and the peak interpolation
//! work with any geometry: [`ThesisRim`] is the small-angle profile
//! R sin φ (1 + cos χ) whose peaks are eq. (3.9); [`SideViewRim`] is the exact
//! front-rim intersection for a disk of half-thickness H seen from a camera at
//! elevation ε. When the renderer's camera is known exactly, a new implementation
//! replaces either without touching the fits.

use std::f64::consts::FRAC_PI_2;

/// Rim height on the centre column above the plate as the camera sees it \[m\].
pub trait RimModel: Sync {
    /// z_rim for nutation `phi` = φ \[rad\] and precession phase `chi` = χ = ψ − ψ_c
    /// \[rad\], where χ = 0 is the orientation of fig. 3.6 (the raised side of the
    /// disk, and its underside, face the camera; the contact point is farthest away).
    /// Must be even and 2π-periodic in χ, and largest at χ = 0.
    fn z_rim(&self, phi: f64, chi: f64) -> f64;

    /// (∂z_rim/∂φ, ∂z_rim/∂χ) at (`phi`, `chi`), for the Jacobians of the local fits.
    /// The default takes central differences (steps 1e-6 of φ, floored at 1e-12 rad,
    /// and 1e-6 rad in χ); a model with a closed form overrides it.
    fn z_rim_partials(&self, phi: f64, chi: f64) -> (f64, f64) {
        let h_phi = 1e-6 * phi.abs().max(1e-6);
        let h_chi = 1e-6;
        (
            (self.z_rim(phi + h_phi, chi) - self.z_rim(phi - h_phi, chi)) / (2.0 * h_phi),
            (self.z_rim(phi, chi + h_chi) - self.z_rim(phi, chi - h_chi)) / (2.0 * h_chi),
        )
    }

    /// The nutation angle φ whose peak height z_rim(φ, 0) is `z_peak` \[m\]; eq. (3.9)
    /// for [`ThesisRim`]. The default solves z_rim(φ, 0) = z_peak by bisection on
    /// [0, π/2] (z_rim(·, 0) must increase there); NaN when z_peak lies outside.
    fn phi_from_peak(&self, z_peak: f64) -> f64 {
        let (mut lo, mut hi) = (0.0, FRAC_PI_2);
        let (z_lo, z_hi) = (self.z_rim(lo, 0.0), self.z_rim(hi, 0.0));
        if !(z_peak >= z_lo && z_peak <= z_hi) {
            return f64::NAN;
        }
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if self.z_rim(mid, 0.0) < z_peak {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }
}

/// The thesis's reading of the footage: z_rim = R sin φ (1 + cos χ), the height of the
/// bottom-rim point that lies in the camera's vertical plane through the centre, to
/// first order in φ (module docs). Its peaks are 2R sin φ, so φ = arcsin(z/2R),
/// eq. (3.9) as corrected in ERRATA.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThesisRim {
    /// Disk radius R \[m\].
    pub radius: f64,
}

impl RimModel for ThesisRim {
    fn z_rim(&self, phi: f64, chi: f64) -> f64 {
        self.radius * phi.sin() * (1.0 + chi.cos())
    }

    fn z_rim_partials(&self, phi: f64, chi: f64) -> (f64, f64) {
        let (sin_phi, cos_phi) = phi.sin_cos();
        let (sin_chi, cos_chi) = chi.sin_cos();
        (
            self.radius * cos_phi * (1.0 + cos_chi),
            -self.radius * sin_phi * sin_chi,
        )
    }

    /// Eq. (3.9): φ = arcsin(z_peak / 2R).
    fn phi_from_peak(&self, z_peak: f64) -> f64 {
        (z_peak / (2.0 * self.radius)).asin()
    }
}

/// The exact rim height for a rigid disk of radius R and half-thickness H, tilted by φ,
/// its centre at rest (stationary rolling, eq. 3.7), seen by a distant camera at
/// elevation ε that looks at the centre column (module docs, "Exact form").
///
/// z_rim is the height of the *front* bottom-rim point on the column (the one nearer
/// the camera: the underside is unwrapped and dark, so the white region ends there),
/// converted as the vision stage does: image rows relative to the rest frame's front
/// rim, divided by cos ε.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SideViewRim {
    /// Disk radius R \[m\].
    pub radius: f64,
    /// Half-thickness H \[m\] (the bottom face is at −H from the centre).
    pub half_thickness: f64,
    /// Camera elevation ε above the plate's plane \[rad\]; 0 for a level camera.
    pub camera_elevation: f64,
}

impl SideViewRim {
    /// The front bottom-rim point on the centre column, as (α, height above the plate
    /// \[m\], horizontal offset towards the camera from the centre \[m\]); α is the body
    /// angle from the body x axis (which points from the contact point to the centre).
    pub fn front_rim_point(&self, phi: f64, chi: f64) -> (f64, f64, f64) {
        let (r, h) = (self.radius, self.half_thickness);
        let (sin_phi, cos_phi) = phi.sin_cos();
        let (sin_chi, cos_chi) = chi.sin_cos();
        // Column condition X = X_G for a point on the bottom rim:
        // a cos α + b sin α = c.
        let a = r * cos_phi * sin_chi;
        let b = r * cos_chi;
        let c = -h * sin_phi * sin_chi;
        let rho = a.hypot(b);
        let gamma = b.atan2(a);
        let spread = (c / rho).clamp(-1.0, 1.0).acos();
        let depth = |alpha: f64| {
            r * cos_phi * cos_chi * alpha.cos() - r * sin_chi * alpha.sin() + h * sin_phi * cos_chi
        };
        let (alpha_1, alpha_2) = (gamma + spread, gamma - spread);
        let alpha = if depth(alpha_1) >= depth(alpha_2) {
            alpha_1
        } else {
            alpha_2
        };
        (alpha, r * sin_phi * (1.0 + alpha.cos()), depth(alpha))
    }
}

impl RimModel for SideViewRim {
    fn z_rim(&self, phi: f64, chi: f64) -> f64 {
        let (_, height, depth) = self.front_rim_point(phi, chi);
        // Rows relative to the rest frame's front rim (height 0, depth R), over cos ε.
        height - (depth - self.radius) * self.camera_elevation.tan()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const R: f64 = 0.0381;
    const H: f64 = 0.00635;

    /// Brute force: walk the bottom rim circle in the global frame built from the
    /// thesis's rotations, eq. (3.14), keep the points on the camera's vertical plane
    /// through the centre, and take the one nearest the camera; its image height.
    fn brute_force(phi: f64, chi: f64, eps: f64) -> f64 {
        // Camera far along +Y: ψ_c = π/2.
        let psi = chi + PI / 2.0;
        let (sp, cp) = phi.sin_cos();
        let (ss, cs) = psi.sin_cos();
        let e_x = [cp * cs, cp * ss, sp];
        let e_y = [-ss, cs, 0.0];
        let e_z = [-sp * cs, -sp * ss, cp];
        let z_g = R * sp + H * cp;
        let point = |alpha: f64| {
            let (sa, ca) = alpha.sin_cos();
            let p: Vec<f64> = (0..3)
                .map(|k| R * ca * e_x[k] + R * sa * e_y[k] - H * e_z[k])
                .collect();
            (p[0], p[1], z_g + p[2])
        };
        // Roots of X(α) = 0 by sign changes and bisection.
        let n = 20_000;
        let mut best: Option<(f64, f64)> = None;
        for k in 0..n {
            let (mut lo, mut hi) = (
                2.0 * PI * k as f64 / n as f64,
                2.0 * PI * (k + 1) as f64 / n as f64,
            );
            if point(lo).0.signum() == point(hi).0.signum() {
                continue;
            }
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if point(mid).0.signum() == point(lo).0.signum() {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let (_, y, z) = point(0.5 * (lo + hi));
            if best.is_none_or(|(y_best, _)| y > y_best) {
                best = Some((y, z));
            }
        }
        let (y, z) = best.expect("the column meets the rim");
        z - (y - R) * eps.tan()
    }

    #[test]
    fn exact_model_matches_brute_force_geometry() {
        for &eps in &[0.0, 0.1] {
            let model = SideViewRim {
                radius: R,
                half_thickness: H,
                camera_elevation: eps,
            };
            for &phi in &[0.001, 0.02, 0.2] {
                for k in 0..24 {
                    let chi = -PI + 2.0 * PI * (k as f64 + 0.3) / 24.0;
                    let (exact, brute) = (model.z_rim(phi, chi), brute_force(phi, chi, eps));
                    // Bisection to 1e-15 rad in α: rounding only.
                    assert!(
                        (exact - brute).abs() < 1e-12,
                        "φ {phi} χ {chi} ε {eps}: {exact} vs {brute}"
                    );
                }
            }
        }
    }

    /// Module docs: z = R sin φ (1 + cos χ − h φ sin²χ) − H φ cos χ tan ε + O(R φ³)
    /// + O(R φ² tan ε).
    #[test]
    fn exact_model_reduces_to_the_thesis_profile_for_small_tilt() {
        let thesis = ThesisRim { radius: R };
        for &eps in &[0.0, 0.05] {
            let exact = SideViewRim {
                radius: R,
                half_thickness: H,
                camera_elevation: eps,
            };
            for &phi in &[1e-4, 1e-3, 1e-2] {
                for k in 0..16 {
                    let chi = 2.0 * PI * k as f64 / 16.0;
                    let first_order = thesis.z_rim(phi, chi)
                        - R * phi * phi * (H / R) * chi.sin().powi(2)
                        - H * phi * chi.cos() * eps.tan();
                    let z = exact.z_rim(phi, chi);
                    // The neglected terms are O(R φ³) and O((R + H) φ² tan ε).
                    let bound = 2.0 * R * phi.powi(3) + (R + H) * phi * phi * eps.tan() + 1e-17;
                    assert!((z - first_order).abs() < bound, "φ {phi} χ {chi}");
                }
            }
        }
    }

    /// The closed-form partials of the thesis profile agree with the default central
    /// differences, which the exact model uses.
    #[test]
    fn partials_match_central_differences() {
        struct Numeric(ThesisRim);
        impl RimModel for Numeric {
            fn z_rim(&self, phi: f64, chi: f64) -> f64 {
                self.0.z_rim(phi, chi)
            }
        }
        let thesis = ThesisRim { radius: R };
        for &phi in &[1e-4, 0.01, 0.3] {
            for k in 0..16 {
                let chi = 2.0 * PI * k as f64 / 16.0 - 0.1;
                let (a_phi, a_chi) = thesis.z_rim_partials(phi, chi);
                let (n_phi, n_chi) = Numeric(thesis).z_rim_partials(phi, chi);
                assert!((a_phi - n_phi).abs() < 1e-8 * R, "φ {phi} χ {chi}");
                assert!((a_chi - n_chi).abs() < 1e-8 * R * phi, "φ {phi} χ {chi}");
            }
        }
    }

    #[test]
    fn peaks_give_eq_3_9() {
        let thesis = ThesisRim { radius: R };
        let exact = SideViewRim {
            radius: R,
            half_thickness: H,
            camera_elevation: 0.0,
        };
        for &phi in &[1e-4, 0.01, 0.3] {
            // Level camera: the peak is exactly 2R sin φ, so eq. (3.9) inverts it.
            assert!((exact.z_rim(phi, 0.0) - 2.0 * R * phi.sin()).abs() < 1e-15);
            assert!((thesis.phi_from_peak(thesis.z_rim(phi, 0.0)) - phi).abs() < 1e-14);
            // The generic inversion (bisection) agrees.
            assert!((exact.phi_from_peak(exact.z_rim(phi, 0.0)) - phi).abs() < 1e-14);
            // χ = 0 is the maximum over the turn.
            for k in 1..64 {
                let chi = 2.0 * PI * k as f64 / 64.0;
                assert!(exact.z_rim(phi, chi) < exact.z_rim(phi, 0.0));
            }
        }
    }
}
