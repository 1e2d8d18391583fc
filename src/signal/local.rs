//! Local fits of the rim-height model over about one oscillation, and the phase track
//! (ψ at peaks and troughs) that starts them.
//!
//! Over a short window around a centre time t_c the state is taken as
//! φ(τ) = φ₀ + φ₁ τ and χ(τ) = χ₀ + ω τ (+ ½ ω̇ τ² with `chirp`), τ = t − t_c, and
//! z_rim(t) = [`RimModel::z_rim`] (φ(τ), χ(τ)) is fitted by
//! least squares. ω is the precession rate ψ̇ at t_c and χ₀ the phase there. The model is
//! even in χ, so (χ₀, ω) and (−χ₀, −ω) fit alike; the fit returns ω ≥ 0 (a side view
//! cannot tell the sense of precession).

use super::RimModel;
use crate::numeric::lsq::{LsqFit, levenberg_marquardt};
use std::f64::consts::PI;

/// Starting values of a local fit.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LocalInit {
    pub phi: f64,
    pub phi_slope: f64,
    pub chi: f64,
    pub omega: f64,
}

/// Which terms beyond φ₀, φ₁, χ₀ and ω a local fit has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Terms {
    /// ½ ω̇ τ² in the phase.
    pub chirp: bool,
}

impl Terms {
    /// φ₀, φ₁, χ₀, ω only.
    #[cfg(test)]
    pub const PLAIN: Terms = Terms { chirp: false };
    /// With the chirp ½ ω̇ τ².
    pub const CHIRP: Terms = Terms { chirp: true };

    fn parameters(self) -> usize {
        4 + usize::from(self.chirp)
    }

    /// (φ, χ) at scaled time `u` for the scaled parameters `p`: φ = p₀ + p₁u,
    /// χ = p₂ + p₃u (+ p₄u² with the chirp).
    fn state(self, p: &[f64], u: f64) -> (f64, f64) {
        let mut chi = p[2] + p[3] * u;
        if self.chirp {
            chi += p[4] * u * u;
        }
        (p[0] + p[1] * u, chi)
    }
}

/// A converged local fit, in physical units (rad, rad/s, rad/s²).
#[derive(Debug, Clone, Copy)]
pub(crate) struct LocalFit {
    pub phi: f64,
    pub phi_slope: f64,
    /// Phase at t_c, not wrapped.
    pub chi: f64,
    pub omega: f64,
    /// dω/dt of the chirp (0 without it).
    pub omega_dot: f64,
    pub sigma_phi: f64,
    pub sigma_chi: f64,
    pub sigma_omega: f64,
    pub ssr: f64,
    pub dof: usize,
    pub points: usize,
}

/// Fits the local model to the window samples (`t`, `z`, all finite) around `t_c`.
/// With `shift = Some((t_from, dt))`, samples at or after `t_from` are taken to have
/// been recorded `dt` later than stamped (the dropped-frame hypothesis of the
/// frame-skip test). Returns `None` when the fit cannot be made (too few samples, or
/// a non-finite or non-positive tilt).
pub(crate) fn fit_local(
    model: &dyn RimModel,
    t: &[f64],
    z: &[f64],
    t_c: f64,
    init: LocalInit,
    terms: Terms,
    shift: Option<(f64, f64)>,
) -> Option<LocalFit> {
    if t.len() <= terms.parameters() {
        return None;
    }
    let half_width = t
        .iter()
        .map(|&x| (x - t_c).abs())
        .fold(0.0, f64::max)
        .max(1e-9);
    // Scaled time u = τ/w, so that every parameter is of order one or φ.
    let u: Vec<f64> = t
        .iter()
        .map(|&x| {
            let late = shift.map_or(0.0, |(from, dt)| if x >= from { dt } else { 0.0 });
            (x + late - t_c) / half_width
        })
        .collect();
    let mut p0 = vec![
        init.phi,
        init.phi_slope * half_width,
        init.chi,
        init.omega * half_width,
    ];
    if terms.chirp {
        p0.push(0.0);
    }
    let fit = fit_scaled(model, &u, z, &p0, terms)?;
    LocalFit::from_scaled(&fit, half_width, terms)
}

/// The least-squares fit of the model in scaled time `u` to the heights `z`, from
/// the scaled parameters `p0` (φ₀, φ₁w, χ₀, ωw[, ½ω̇w²]). The Jacobian by the chain
/// rule: with φ_i = p₀ + p₁u_i and χ_i = p₂ + p₃u_i (+ p₄u_i²),
/// ∂r_i/∂p = (∂z/∂φ [1, u_i], ∂z/∂χ [1, u_i, u_i²]), from the model's partials: two
/// sin/cos pairs per sample instead of the ten model evaluations of central
/// differences in all parameters.
fn fit_scaled(
    model: &dyn RimModel,
    u: &[f64],
    z: &[f64],
    p0: &[f64],
    terms: Terms,
) -> Option<LsqFit> {
    levenberg_marquardt(
        |p, out| {
            for ((o, &ui), &zi) in out.iter_mut().zip(u).zip(z) {
                let (phi, chi) = terms.state(p, ui);
                *o = model.z_rim(phi, chi) - zi;
            }
        },
        |p, jac| {
            for (i, &ui) in u.iter().enumerate() {
                let (phi, chi) = terms.state(p, ui);
                let (dz_dphi, dz_dchi) = model.z_rim_partials(phi, chi);
                jac[(i, 0)] = dz_dphi;
                jac[(i, 1)] = dz_dphi * ui;
                jac[(i, 2)] = dz_dchi;
                jac[(i, 3)] = dz_dchi * ui;
                if terms.chirp {
                    jac[(i, 4)] = dz_dchi * ui * ui;
                }
            }
        },
        p0,
        u.len(),
    )
}

impl LocalFit {
    /// The fit in physical units from the scaled one (time in units of the window's
    /// `half_width` \[s\]), with ω ≥ 0: the model is even in χ, so (χ₀, ω) and (−χ₀, −ω)
    /// fit alike. `None` unless every value and σ is finite and the tilt positive.
    fn from_scaled(fit: &LsqFit, half_width: f64, terms: Terms) -> Option<Self> {
        let p = &fit.params;
        let cov = fit.covariance()?;
        let sign = if p[3] < 0.0 { -1.0 } else { 1.0 };
        let result = LocalFit {
            phi: p[0],
            phi_slope: p[1] / half_width,
            chi: sign * p[2],
            omega: sign * p[3] / half_width,
            omega_dot: if terms.chirp {
                sign * 2.0 * p[4] / (half_width * half_width)
            } else {
                0.0
            },
            sigma_phi: cov[(0, 0)].sqrt(),
            sigma_chi: cov[(2, 2)].sqrt(),
            sigma_omega: cov[(3, 3)].sqrt() / half_width,
            ssr: fit.ssr,
            dof: fit.dof,
            points: fit.residuals.len(),
        };
        let finite = [
            result.phi,
            result.phi_slope,
            result.chi,
            result.omega,
            result.sigma_phi,
            result.sigma_chi,
            result.sigma_omega,
        ]
        .iter()
        .all(|x| x.is_finite());
        (finite && result.phi > 0.0).then_some(result)
    }

    /// The time near `t_c` at which the phase is `target` mod 2π (0 for a peak, π for a
    /// trough), and the tilt φ there: χ₀ + ω τ + ½ ω̇ τ² = target, solved by Newton's
    /// method from the linear root.
    pub(crate) fn time_of_phase(&self, t_c: f64, target: f64) -> (f64, f64) {
        let offset = wrap_pi(self.chi - target);
        let mut dt = -offset / self.omega;
        for _ in 0..4 {
            let f = offset + self.omega * dt + 0.5 * self.omega_dot * dt * dt;
            let df = self.omega + self.omega_dot * dt;
            if df <= 0.0 {
                break;
            }
            dt -= f / df;
        }
        (t_c + dt, self.phi + self.phi_slope * dt)
    }
}

/// The sample range `lo..hi` of a local fit's window, grown by a sample on each side
/// in turn (the earlier first) until it holds `least` samples or spans all `len`.
pub(crate) fn widened(lo: usize, hi: usize, len: usize, least: usize) -> (usize, usize) {
    let (mut lo, mut hi) = (lo, hi);
    while hi - lo < least && (lo > 0 || hi < len) {
        lo = lo.saturating_sub(1);
        if hi - lo < least && hi < len {
            hi += 1;
        }
    }
    (lo, hi)
}

/// x wrapped into (−π, π].
pub(crate) fn wrap_pi(x: f64) -> f64 {
    let y = x.rem_euclid(2.0 * PI);
    if y > PI { y - 2.0 * PI } else { y }
}

/// ψ(t) and φ(t) known at peaks (ψ = 2πk) and troughs (ψ = 2πk + π), linearly
/// interpolated between them: the starting values of the per-frame fits.
#[derive(Debug, Clone, Default)]
pub(crate) struct PhaseTrack {
    /// (t, ψ) knots, sorted by time.
    psi: Vec<(f64, f64)>,
    /// (t, φ) knots at peaks, sorted by time.
    phi: Vec<(f64, f64)>,
}

impl PhaseTrack {
    pub(crate) fn new(mut psi: Vec<(f64, f64)>, mut phi: Vec<(f64, f64)>) -> Self {
        psi.sort_by(|a, b| a.0.total_cmp(&b.0));
        phi.sort_by(|a, b| a.0.total_cmp(&b.0));
        PhaseTrack { psi, phi }
    }

    /// ψ and ψ̇ at `t` (linear between knots, extrapolated with the end slopes).
    pub(crate) fn psi_at(&self, t: f64) -> Option<(f64, f64)> {
        interpolate(&self.psi, t)
    }

    /// The (t, ψ) knots, sorted by time: the turning points with their counted ψ.
    pub(crate) fn psi_knots(&self) -> &[(f64, f64)] {
        &self.psi
    }

    /// φ and φ̇ at `t`.
    pub(crate) fn phi_at(&self, t: f64) -> Option<(f64, f64)> {
        interpolate(&self.phi, t)
    }
}

fn interpolate(knots: &[(f64, f64)], t: f64) -> Option<(f64, f64)> {
    if knots.len() < 2 {
        return None;
    }
    let k = knots.partition_point(|&(tk, _)| tk <= t);
    let j = k.clamp(1, knots.len() - 1);
    let ((t0, y0), (t1, y1)) = (knots[j - 1], knots[j]);
    let slope = (y1 - y0) / (t1 - t0);
    Some((y0 + slope * (t - t0), slope))
}

#[cfg(test)]
mod tests {
    use super::super::ThesisRim;
    use super::*;

    #[test]
    fn local_fit_recovers_a_drifting_oscillation() {
        let model = ThesisRim { radius: 0.0381 };
        let (phi0, phi1, chi0, omega) = (0.01, -0.02, 0.4, 300.0);
        let t: Vec<f64> = (-6..=6).map(|i| i as f64 / 480.0).collect();
        let z: Vec<f64> = t
            .iter()
            .map(|&x| model.z_rim(phi0 + phi1 * x, chi0 + omega * x))
            .collect();
        let init = LocalInit {
            phi: 0.011,
            phi_slope: 0.0,
            chi: 0.2,
            omega: 280.0,
        };
        let fit = fit_local(&model, &t, &z, 0.0, init, Terms::PLAIN, None).expect("fit");
        assert!((fit.phi - phi0).abs() < 1e-10, "{fit:?}");
        assert!((fit.chi - chi0).abs() < 1e-8 && (fit.omega - omega).abs() < 1e-6);
        let (t_peak, phi_peak) = fit.time_of_phase(0.0, 0.0);
        assert!((t_peak + chi0 / omega).abs() < 1e-10);
        assert!((phi_peak - (phi0 - phi1 * chi0 / omega)).abs() < 1e-10);
    }

    #[test]
    fn phase_track_interpolates() {
        let track = PhaseTrack::new(vec![(1.0, 2.0 * PI), (0.0, 0.0)], vec![]);
        let (psi, rate) = track.psi_at(0.25).expect("ψ");
        assert!((psi - PI / 2.0).abs() < 1e-12 && (rate - 2.0 * PI).abs() < 1e-12);
        assert!(track.phi_at(0.5).is_none());
        assert!((wrap_pi(3.0 * PI) - PI).abs() < 1e-12 && (wrap_pi(-0.5) + 0.5).abs() < 1e-15);
    }
}
