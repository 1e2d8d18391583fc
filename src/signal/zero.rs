//! The zero of z_rim as the motion places it.
//!
//! The heights are measured from the edge at rest, but a still picture is not read
//! like a moving one: the codec codes a still disk once and keeps it (its error is
//! then the same in every rest frame), the blur, the rounded rim, the mirror image or
//! the shadow under a lifted rim all differ between rest and lift. So every lifted
//! height can carry one shared offset, 0.03–0.10 px on coded clips, and the energy
//! fits cannot see it in their residuals.
//!
//! The motion itself fixes the zero. Over one turn the rim's height follows the
//! model's profile, z = R sin φ (1 + cos χ) to first order (module docs): its mean is
//! R sin φ and its swing about the mean R sin φ too, so the heights' mean and their
//! swing disagree by exactly an offset c. Every height of the fit window, from its
//! first turning point to its last, is fitted with one such profile and one c:
//!
//! ```text
//! z_i = z_rim(φ(t_i), χ(t_i)) + c,
//! ```
//!
//! χ(t) the precession phase counted at the turning points (the peaks at χ ≡ 0 mod
//! 2π, the troughs at π: [`super::PeakSeries::precession_half_turns`], which is zero
//! at the last turning point, a peak) and linear in t between them, φ(t) piecewise
//! linear with a knot every [`KNOT_TURNS`] turns (a last piece shorter than a turn
//! joins the one before). Least squares (Levenberg–Marquardt from the peaks' φ), c's
//! standard error the linearised one, s² (JᵀJ)⁻¹: the zero's RMS error is 0.7 of it
//! on sharp rendered rims, 1.3 of it on rounded rims under lossy coding. There side
//! views read their heights 0.02–0.03 px low after it, as the codec smooths their
//! swing over time: the fit takes a swing shrunk about its mean for an offset, and no
//! fit of the heights can tell the two apart; `vision::MOTION_ZERO_PROFILE_PX` is
//! added for it.
//!
//! One fit of the whole window, not a mean over windows of 1.5 turns each fitted
//! with its own φ, φ̇, χ, ψ̇, ψ̈ and c: the turning points fix the phase, so the
//! heights are left to fix φ and c alone, and every frame counts for all of them
//! (the heights' offset from the truth about 15 % smaller RMS than with the windows'
//! mean; see docs/validation.md, "Open footage", for the zero's error today).
//!
//! The profile must be the camera's: a camera at elevation ε sees the front rim move
//! by H φ cos χ in depth, which tilts the swing against the mean by (H/R) tan ε and
//! reads as an offset of (H/R) tan ε · R sin φ, 0.02–0.05 px at elevations of a few
//! degrees. `analyse` passes [`super::SideViewRim`] with the clip's ε for that reason.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use super::{Peak, PrecessionSample, RimModel, StateSeries, samples_to_the_halt};
use crate::numeric::lsq::levenberg_marquardt;

/// Turns between φ's knots: φ changes by a few per cent a turn near the halt, so a
/// straight line over two turns leaves it within a fraction of that.
pub const KNOT_TURNS: usize = 2;
/// Fewest turning points the zero is fitted between: two pieces of φ.
pub const MIN_TURNING_POINTS: usize = 4 * KNOT_TURNS + 1;
/// Fewest degrees of freedom left for s².
const MIN_DOF: usize = 10;

/// The zero of the rim heights as the motion places it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MotionZero {
    /// c: the moving rim's zero above the zero the heights were measured from (the
    /// rest level of [`super::Halt`]) \[m\]. Subtract it from the heights.
    pub offset: f64,
    /// Standard error of c \[m\], √(s² (JᵀJ)⁻¹) of the fit.
    pub se: f64,
    /// Turning points the heights were fitted between.
    #[serde(default)]
    pub turning_points: usize,
    /// Heights fitted.
    #[serde(default)]
    pub points: usize,
}

/// The zero of `z_rim` \[m\] (times `t` \[s\]) over the fit window of `series` (from
/// [`super::analyse`] of the same heights), with the profile `model`, or `None` when
/// fewer than `MIN_TURNING_POINTS` (nine) turning points lie in the window or the fit
/// fails.
pub fn motion_zero(
    t: &[f64],
    z_rim: &[f64],
    series: &StateSeries,
    model: &dyn RimModel,
) -> Option<MotionZero> {
    let turning = &series.peaks.precession_half_turns;
    if turning.len() < MIN_TURNING_POINTS {
        return None;
    }
    let (first, last) = (turning[0].t, turning[turning.len() - 1].t);
    let (_, st, v) = samples_to_the_halt(t, z_rim, &series.halt);
    let (times, heights): (Vec<f64>, Vec<f64>) = st
        .iter()
        .zip(&v)
        .filter(|&(&x, _)| x >= first && x <= last)
        .unzip();
    let knots = phi_knots(turning);
    let parameters = knots.len() + 1;
    if times.len() < parameters + MIN_DOF {
        return None;
    }
    let profile = Profile {
        model,
        chi: precession_phase(turning, &times),
        place: knot_places(&knots, &times),
        heights: &heights,
    };
    let mut p0 = peaks_phi_at(&series.peaks.peaks, &knots)?;
    p0.push(0.0);
    let (offset, se) = profile.fit_offset(&p0)?;
    (offset.is_finite() && se.is_finite() && se > 0.0).then_some(MotionZero {
        offset,
        se,
        turning_points: turning.len(),
        points: times.len(),
    })
}

/// φ's knots: the time of every [`KNOT_TURNS`]th turn's turning point (twice as many
/// turning points), and the last; a last piece of less than a turn joins the one
/// before it, as it holds too few heights to fix its own slope.
fn phi_knots(turning: &[PrecessionSample]) -> Vec<f64> {
    let last = turning[turning.len() - 1].t;
    let step = 2 * KNOT_TURNS;
    let mut knots: Vec<f64> = turning.iter().step_by(step).map(|s| s.t).collect();
    match (turning.len() - 1) % step {
        0 => {}
        rest if rest < KNOT_TURNS => *knots.last_mut().expect("a knot") = last,
        _ => knots.push(last),
    }
    knots
}

/// χ at each of the `times`: linear in t between the turning points, which fix it
/// (module docs).
fn precession_phase(turning: &[PrecessionSample], times: &[f64]) -> Vec<f64> {
    times
        .iter()
        .map(|&x| {
            let k = turning
                .partition_point(|s| s.t <= x)
                .clamp(1, turning.len() - 1);
            let (a, b) = (&turning[k - 1], &turning[k]);
            a.psi + (b.psi - a.psi) * (x - a.t) / (b.t - a.t)
        })
        .collect()
}

/// The place of each of the `times` among the `knots`: the piece j of φ it lies on and
/// the weight of knot j + 1 there.
fn knot_places(knots: &[f64], times: &[f64]) -> Vec<(usize, f64)> {
    times
        .iter()
        .map(|&x| {
            let j = (knots.partition_point(|&k| k <= x).max(1) - 1).min(knots.len() - 2);
            (j, (x - knots[j]) / (knots[j + 1] - knots[j]))
        })
        .collect()
}

/// The starting φ at each of the `knots`: the tilt of the `peaks` (those with a finite
/// positive one), interpolated, or the last beyond them; `None` where there is none.
fn peaks_phi_at(peaks: &[Peak], knots: &[f64]) -> Option<Vec<f64>> {
    let peaks: Vec<&Peak> = peaks
        .iter()
        .filter(|pk| pk.phi.is_finite() && pk.phi > 0.0)
        .collect();
    let p0: Vec<f64> = knots
        .iter()
        .map(|&k| {
            let i = peaks
                .partition_point(|pk| pk.t <= k)
                .clamp(1, peaks.len().max(2) - 1);
            match (peaks.get(i - 1), peaks.get(i)) {
                (Some(a), Some(b)) => {
                    a.phi + (b.phi - a.phi) * ((k - a.t) / (b.t - a.t)).clamp(0.0, 1.0)
                }
                (Some(a), None) => a.phi,
                _ => f64::NAN,
            }
        })
        .collect();
    p0.iter().all(|x| x.is_finite()).then_some(p0)
}

/// The rim heights of the fit window and the profile they are fitted with: φ
/// piecewise linear between the knots, χ from the turning points, and one offset c.
struct Profile<'a> {
    model: &'a dyn RimModel,
    /// χ at each height.
    chi: Vec<f64>,
    /// Each height's piece of φ and the weight of its later knot ([`knot_places`]).
    place: Vec<(usize, f64)>,
    heights: &'a [f64],
}

impl Profile<'_> {
    /// φ at the place `(j, w)` for the knots' values `p`.
    fn phi_at(p: &[f64], (j, w): (usize, f64)) -> f64 {
        (1.0 - w) * p[j] + w * p[j + 1]
    }

    /// c and its standard error from a Levenberg–Marquardt fit of φ at the knots and
    /// c (the last parameter), started from `p0`; `None` if the fit fails.
    fn fit_offset(&self, p0: &[f64]) -> Option<(f64, f64)> {
        let (model, chi, place) = (self.model, &self.chi, &self.place);
        let c = p0.len() - 1;
        let fit = levenberg_marquardt(
            |p, out| {
                for (i, o) in out.iter_mut().enumerate() {
                    *o = model.z_rim(Self::phi_at(p, place[i]), chi[i]) + p[c] - self.heights[i];
                }
            },
            |p, jac: &mut DMatrix<f64>| {
                jac.fill(0.0);
                for (i, &(j, w)) in place.iter().enumerate() {
                    let (dz_dphi, _) = model.z_rim_partials(Self::phi_at(p, (j, w)), chi[i]);
                    jac[(i, j)] = dz_dphi * (1.0 - w);
                    jac[(i, j + 1)] = dz_dphi * w;
                    jac[(i, c)] = 1.0;
                }
            },
            p0,
            self.heights.len(),
        )?;
        let se = fit.covariance()?[(c, c)].sqrt();
        Some((fit.params[c], se))
    }
}
