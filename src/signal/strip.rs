//! The strip angle β of the top view (thesis §3.3.2): unwrapping by ±π, the 5-point
//! moving average, β̇, and the stop time t_β by the band method of fig. 3.22.

use super::SignalError;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// β unwrapped, smoothed and differentiated; one entry per input frame (NaN where the
/// frame has no strip angle).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StripSeries {
    /// β made continuous by adding multiples of π (the PCA angle, eq. 3.24, is only
    /// known mod π) [rad].
    pub beta: Vec<f64>,
    /// `beta` after the centred moving average (5 points in the thesis) [rad].
    pub beta_smoothed: Vec<f64>,
    /// β̇ from `beta_smoothed` by central differences on the (possibly uneven) frame
    /// times [rad/s]; eq. (3.22): β̇ = ψ̇ + θ̇ + O(φ²).
    pub beta_dot: Vec<f64>,
}

/// Unwraps, smooths (`points`-point centred moving average) and differentiates β
/// (thesis §3.3.2). `t` [s] and `beta` [rad, in (−π/2, π/2], NaN for no strip] pair up
/// frame by frame.
pub fn strip_series(t: &[f64], beta: &[f64], points: usize) -> Result<StripSeries, SignalError> {
    super::check_series(t, beta, "beta")?;
    let unwrapped = unwrap_half_turns(beta);
    let smoothed = moving_average(&unwrapped, points);
    let beta_dot = derivative(t, &smoothed);
    Ok(StripSeries {
        beta: unwrapped,
        beta_smoothed: smoothed,
        beta_dot,
    })
}

/// Makes an angle known mod π continuous: each value is moved by the multiple of π
/// that brings it within π/2 of the previous finite value (thesis: "at each v_x = 0, we
/// increment β by ±π depending on the direction of rotation"). NaN stays NaN.
pub fn unwrap_half_turns(beta: &[f64]) -> Vec<f64> {
    let mut previous: Option<f64> = None;
    beta.iter()
        .map(|&b| {
            if !b.is_finite() {
                return f64::NAN;
            }
            let value = match previous {
                Some(p) => b + PI * ((p - b) / PI).round(),
                None => b,
            };
            previous = Some(value);
            value
        })
        .collect()
}

/// Centred moving average over `points` samples (odd; an even count is rounded up),
/// with the span shrunk symmetrically at the ends (1, 3, … points), as MATLAB's
/// `smooth`. NaN samples are left out of each average; a window without finite values
/// gives NaN.
pub fn moving_average(values: &[f64], points: usize) -> Vec<f64> {
    let half = points / 2;
    let n = values.len();
    (0..n)
        .map(|i| {
            let h = half.min(i).min(n - 1 - i);
            let (sum, count) = values[i - h..=i + h]
                .iter()
                .filter(|x| x.is_finite())
                .fold((0.0, 0usize), |(s, c), &x| (s + x, c + 1));
            if count == 0 {
                f64::NAN
            } else {
                sum / count as f64
            }
        })
        .collect()
}

/// dy/dt by the three-point central difference for uneven spacing (exact for
/// quadratics), one-sided at the ends and next to NaN samples.
pub fn derivative(t: &[f64], y: &[f64]) -> Vec<f64> {
    let n = y.len();
    let ok = |i: usize| y[i].is_finite();
    (0..n)
        .map(|i| {
            if !ok(i) {
                return f64::NAN;
            }
            let left = i > 0 && ok(i - 1);
            let right = i + 1 < n && ok(i + 1);
            match (left, right) {
                (true, true) => {
                    let (hm, hp) = (t[i] - t[i - 1], t[i + 1] - t[i]);
                    (hm * hm * y[i + 1] - hp * hp * y[i - 1] + (hp * hp - hm * hm) * y[i])
                        / (hm * hp * (hm + hp))
                }
                (true, false) => (y[i] - y[i - 1]) / (t[i] - t[i - 1]),
                (false, true) => (y[i + 1] - y[i]) / (t[i + 1] - t[i]),
                (false, false) => f64::NAN,
            }
        })
        .collect()
}

/// The stop of the strip's rotation, t_β, by the band method of fig. 3.22.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StripStop {
    /// Frame of t_β.
    pub index: usize,
    /// t_β on the caller's time axis [s].
    pub t_beta: f64,
    /// The band: minimum and maximum of β after `settled_after` [rad].
    pub band: (f64, f64),
    /// The time after which β was taken as settled [s].
    pub settled_after: f64,
    /// Frames in the settled part that defined the band.
    pub settled_frames: usize,
}

/// Fewest settled samples that define a band.
const MIN_SETTLED_FRAMES: usize = 5;

/// t_β by the band method of fig. 3.22: take the band between the minimum and maximum
/// of β after `settled_after` (a time by which the disk has certainly stopped); t_β is
/// the first frame at which the trajectory enters the band on its final approach.
///
/// "Final approach": noise can carry β just outside a band made from a finite sample
/// of it, so the approach starts after the last frame that lies outside the band by
/// more than its width; t_β is the first frame inside the band after it. On noiseless
/// or monotone data this is exactly the thesis's first intersection. Use the unwrapped
/// β ([`StripSeries::beta`]), not the smoothed one, whose band would be narrower than
/// the noise the thesis measured.
///
/// Errors: [`SignalError::SettledTooShort`] with fewer than 5 settled samples,
/// [`SignalError::StripNeverMoves`] if β never leaves the widened band before it.
pub fn strip_stop_time(
    t: &[f64],
    beta: &[f64],
    settled_after: f64,
) -> Result<StripStop, SignalError> {
    super::check_series(t, beta, "beta")?;
    let finite = |i: &usize| beta[*i].is_finite();
    let first_settled = t.partition_point(|&x| x < settled_after);
    let settled: Vec<f64> = (first_settled..t.len())
        .filter(finite)
        .map(|i| beta[i])
        .collect();
    if settled.len() < MIN_SETTLED_FRAMES {
        return Err(SignalError::SettledTooShort {
            settled_after,
            frames: settled.len(),
            needed: MIN_SETTLED_FRAMES,
        });
    }
    let lo = settled.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = settled.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let width = hi - lo;
    let clearly_outside = |i: usize| beta[i] < lo - width || beta[i] > hi + width;
    let inside = |i: usize| beta[i] >= lo && beta[i] <= hi;
    let Some(last_outside) = (0..first_settled)
        .rev()
        .filter(finite)
        .find(|&i| clearly_outside(i))
    else {
        return Err(SignalError::StripNeverMoves {
            settled_after,
            band_low: lo,
            band_high: hi,
        });
    };
    // A frame inside the band exists: at the latest the first settled one.
    let index = (last_outside + 1..t.len())
        .filter(finite)
        .find(|&i| inside(i))
        .unwrap_or(first_settled);
    Ok(StripStop {
        index,
        t_beta: t[index],
        band: (lo, hi),
        settled_after,
        settled_frames: settled.len(),
    })
}
