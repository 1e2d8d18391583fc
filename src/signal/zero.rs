//! The zero of z_rim as the motion places it.
//!
//! The heights are measured from the edge at rest, but a still picture is not read
//! like a moving one: the codec codes a still disk once and keeps it (its error is
//! then the same in every rest frame), the blur, the rounded rim, the mirror image or
//! the shadow under a lifted rim all differ between rest and lift. So every lifted
//! height can carry one shared offset, 0.03–0.10 px on our renders and on the open
//! footage (BENCHMARKS.md "The zero from the motion"), and the energy fits cannot
//! see it in their residuals.
//!
//! The motion itself fixes the zero. Over one turn the rim's height follows the
//! model's profile, z = R sin φ (1 + cos χ) to first order (module docs): its mean is
//! R sin φ and its swing about the mean R sin φ too, so the heights' mean and their
//! swing disagree by exactly an offset c. Over windows of `state_window_periods`
//! turns, one after another through the fit window, the local model (φ = φ₀ + φ₁τ,
//! χ = χ₀ + ωτ + ½ω̇τ²) is fitted with c as one more term ([`Terms::offset`]); the
//! zero is the windows' mean of c, its standard error their standard deviation over
//! √N. Not a mean weighted by each window's own error: those errors (from the
//! residuals and the window's geometry) range over a factor of seven, and on a light
//! plate brighter than the disk (robustness scene s05, in the prototype) one window
//! of the seventeen, with a fifth of the others' error, read 0.09 px and moved the
//! weighted zero 0.04 px off, the plain mean 0.01 px.
//!
//! The profile must be the camera's: a camera at elevation ε sees the front rim move
//! by H φ cos χ in depth, which tilts the swing against the mean by (H/R) tan ε and
//! reads as an offset of (H/R) tan ε · R sin φ, 0.02–0.05 px on the open footage.
//! `analyse` passes [`super::SideViewRim`] with the clip's ε for that reason.

use std::f64::consts::PI;

use serde::{Deserialize, Serialize};

use super::local::{LocalInit, Terms, fit_local};
use super::{RimModel, SignalConfig, StateSeries, peaks, samples_to_the_halt, skips};

/// Fewest windows the zero is taken from: fewer do not show whether they agree.
pub const MIN_WINDOWS: usize = 5;

/// The zero of the rim heights as the motion places it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MotionZero {
    /// c: the moving rim's zero above the zero the heights were measured from (the
    /// rest level of [`super::Halt`]) [m]. Subtract it from the heights.
    pub offset: f64,
    /// Standard error of c [m]: the windows' standard deviation over √N.
    pub se: f64,
    /// Windows fitted, N.
    pub windows: usize,
}

/// The zero of `z_rim` [m] (times `t` [s]) over the window of `series` (from
/// [`super::analyse`] of the same heights), with the profile `model`, or `None` when
/// fewer than [`MIN_WINDOWS`] windows fit.
pub fn motion_zero(
    t: &[f64],
    z_rim: &[f64],
    series: &StateSeries,
    model: &dyn RimModel,
    config: &SignalConfig,
) -> Option<MotionZero> {
    let halt = &series.halt;
    let frame = peaks::nominal_period(t);
    let (idx, st, v) = samples_to_the_halt(t, z_rim, halt);
    let states = &series.states;
    let mut offsets = Vec::new();
    let mut k = states.partition_point(|s| s.t < series.peaks.window.0);
    while let Some(state) = states.get(k) {
        // A window is 1.5 turns of the state's ψ̇: an undetermined ψ̇ (11 rad/s
        // beside 490, after a halt the codec moved, robustness scene s14) spanned
        // 214 frames and read c 0.43 mm (1.8 px) off, which moved the mean by 0.12 px.
        if !state.is_determined() {
            k += 1;
            continue;
        }
        let t_c = state.t;
        let half = (0.5 * config.state_window_periods * 2.0 * PI / state.psi_dot).max(3.5 * frame);
        let next = t_c + 2.0 * half;
        k += states[k..].partition_point(|s| s.t <= next).max(1);
        let (lo, hi) = (
            st.partition_point(|&x| x < t_c - half),
            st.partition_point(|&x| x <= t_c + half),
        );
        // Six parameters and two degrees of freedom at least; no window across a
        // timestamp gap (the phase would miscount the turns in it).
        if hi - lo < 8 || skips::spans_gap(&t[idx[lo]..=idx[hi - 1]], frame, config.gap_factor) {
            continue;
        }
        let init = LocalInit {
            phi: state.phi,
            phi_slope: 0.0,
            chi: state.psi,
            omega: state.psi_dot,
        };
        let terms = Terms {
            chirp: true,
            offset: true,
        };
        if let Some(fit) = fit_local(model, &st[lo..hi], &v[lo..hi], t_c, init, terms, None)
            && fit.sigma_offset > 0.0
        {
            offsets.push(fit.offset);
        }
    }
    let windows = offsets.len();
    if windows < MIN_WINDOWS {
        return None;
    }
    let offset = offsets.iter().sum::<f64>() / windows as f64;
    let variance = offsets.iter().map(|c| (c - offset).powi(2)).sum::<f64>() / (windows - 1) as f64;
    Some(MotionZero {
        offset,
        se: (variance / windows as f64).sqrt(),
        windows,
    })
}
