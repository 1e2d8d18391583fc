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
    /// known mod π) \[rad\].
    pub beta: Vec<f64>,
    /// `beta` after the centred moving average (5 points in the thesis) \[rad\].
    pub beta_smoothed: Vec<f64>,
    /// β̇ from `beta_smoothed` by central differences on the (possibly uneven) frame
    /// times [rad/s]; eq. (3.22): β̇ = ψ̇ + θ̇ + O(φ²).
    pub beta_dot: Vec<f64>,
}

/// Unwraps, smooths (`points`-point centred moving average) and differentiates β
/// (thesis §3.3.2). `t` \[s\] and `beta` [rad, in (−π/2, π/2], NaN for no strip] pair up
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

/// The stop of the strip's rotation, t_β: the Coulomb stop fitted to β
/// ([`CoulombStop`]), with the band of fig. 3.22 beside it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StripStop {
    /// First frame at or after t_β.
    pub index: usize,
    /// t_β on the caller's time axis \[s\]: the fitted stop ([`CoulombStop::t_stop`]), or
    /// the band's first intersection when no fit could be made.
    pub t_beta: f64,
    /// The band: minimum and maximum of β after `settled_after` \[rad\].
    pub band: (f64, f64),
    /// The time after which β was taken as settled \[s\].
    pub settled_after: f64,
    /// Frames in the settled part that defined the band.
    pub settled_frames: usize,
    /// The thesis's t_β: the frame at which β first enters the band on its final
    /// approach (fig. 3.22).
    #[serde(default)]
    pub band_index: usize,
    /// The time of `band_index` \[s\].
    #[serde(default)]
    pub band_t_beta: f64,
    /// The fitted stop, if the approach held enough frames.
    #[serde(default)]
    pub fit: Option<CoulombStop>,
}

/// The end of the strip's rotation fitted by the model of a flat disk braked by rim
/// friction (eqs. 4.112–4.113): β̇ = v until `t_decel`, then falling linearly to zero at
/// `t_stop` (a constant torque μ m g R), then β constant. The flat part is fig. 3.31's
/// "flat section … succeeded by a decreasing section until the stop"; on a disk that
/// brakes from the halt on, `t_decel` comes out at the start of the fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CoulombStop {
    /// First time in the fit \[s\]: where the smoothed |β̇| peaks after the halt.
    pub fit_from: f64,
    /// Start of the linear deceleration \[s\].
    pub t_decel: f64,
    /// The stop, t_β \[s\].
    pub t_stop: f64,
    /// β̇ before the deceleration [rad/s].
    pub rate: f64,
    /// The final angle \[rad\].
    pub beta_final: f64,
    /// |β̇| / (t_stop − t_decel): the friction's angular deceleration [rad/s²]; eq.
    /// (4.112) gives μ m g R / C = 2μg/R for a uniform disk (69 rad/s² for Euler's disk
    /// on steel).
    pub deceleration: f64,
    /// RMS residual of the fit over the frames before `t_stop` \[rad\].
    pub rms_residual: f64,
    /// Frames in the fit (before and after the stop).
    pub frames: usize,
}

/// Fewest settled samples that define a band.
const MIN_SETTLED_FRAMES: usize = 5;

/// Fewest frames of motion (before the stop) that the Coulomb fit needs: four
/// parameters.
const MIN_MOVING_FRAMES: usize = 4;

/// t_β, the stop of the strip (thesis §3.3.2, fig. 3.22), for a flat disk braked by rim
/// friction.
///
/// First the thesis's band: the band between the minimum and maximum of β after
/// `settled_after` (a time by which the disk has certainly stopped); its first
/// intersection with the trajectory's final approach is `band_t_beta`. "Final
/// approach": noise can carry β just outside a band made from a finite sample of it,
/// so the approach starts after the last frame that lies outside the band by more than
/// its width.
///
/// The band alone is biased either way. A Coulomb stop approaches its final angle
/// quadratically, β − β_∞ = ½ a (t_β − t)², so a band of half-width w is entered
/// √(2w/a) early (2.7 ms, 1.3 frames at 480 fps, for the thesis's w = 2.5e-4 rad and
/// a = 69 rad/s²). On compressed footage it is entered late: still frames are coded
/// exactly, so the band is as narrow as 1e-5 rad, while frames in motion carry coding
/// errors of 3e-4 rad that can hold β off it for 2–6 frames after the stop. So t_β is
/// fitted instead ([`CoulombStop`]): β̇ constant, then linear to zero (eq. 4.112), then
/// zero, by least squares on the unwrapped β from the frame where the smoothed |β̇|
/// peaks after `flat_from` (the halt t_φ: the post-flat spin has begun) to the end of
/// the clip. The fit uses every frame of the approach rather than the last few near the
/// noise, and gives t_β to a fraction of a frame. With fewer than four frames of motion
/// in the fit, t_β is the band's.
///
/// Errors: [`SignalError::SettledTooShort`] with fewer than 5 settled samples,
/// [`SignalError::StripNeverMoves`] if β never leaves the widened band before it.
pub fn strip_stop_time(
    t: &[f64],
    series: &StripSeries,
    flat_from: f64,
    settled_after: f64,
) -> Result<StripStop, SignalError> {
    let beta = &series.beta;
    super::check_series(t, beta, "beta")?;
    super::check_series(t, &series.beta_dot, "beta_dot")?;
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
    let band_index = (last_outside + 1..t.len())
        .filter(finite)
        .find(|&i| inside(i))
        .unwrap_or(first_settled);
    let fit = coulomb_stop(t, series, flat_from, band_index);
    let t_beta = fit.as_ref().map_or(t[band_index], |f| f.t_stop);
    let index = t.partition_point(|&x| x < t_beta).min(t.len() - 1);
    Ok(StripStop {
        index,
        t_beta,
        band: (lo, hi),
        settled_after,
        settled_frames: settled.len(),
        band_index,
        band_t_beta: t[band_index],
        fit,
    })
}

/// The Coulomb-stop fit of [`strip_stop_time`]: the fit starts where the smoothed |β̇|
/// peaks in [`flat_from`, t\[band_index\]], and runs to the end of the clip. `None` with
/// fewer than [`MIN_MOVING_FRAMES`] frames of motion in it.
fn coulomb_stop(
    t: &[f64],
    series: &StripSeries,
    flat_from: f64,
    band_index: usize,
) -> Option<CoulombStop> {
    let (beta, rate) = (&series.beta, &series.beta_dot);
    let start = (t.partition_point(|&x| x < flat_from)..band_index)
        .filter(|&i| beta[i].is_finite() && rate[i].is_finite())
        .max_by(|&i, &j| rate[i].abs().total_cmp(&rate[j].abs()))?;
    let (tw, bw): (Vec<f64>, Vec<f64>) = (start..t.len())
        .filter(|&i| beta[i].is_finite())
        .map(|i| (t[i], beta[i]))
        .unzip();
    let moving = tw.iter().filter(|&&x| x < t[band_index]).count();
    if moving < MIN_MOVING_FRAMES {
        return None;
    }
    let frame = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
    let (t_first, t_last) = (tw[0], tw[tw.len() - 1]);
    let profile = Profile::new(&tw, &bw);
    let ssr = |td: f64, ts: f64| -> f64 {
        let td = td.clamp(t_first, ts);
        profile.fit(td, ts).map_or(f64::INFINITY, |(s, ..)| s)
    };
    // A coarse grid (t_stop every half frame, t_decel every frame), then rounds of a
    // finer local grid around the best point, down to 1e-3 frame.
    let mut best = (f64::INFINITY, t_first, t_first);
    let mut ts = t_first + 0.5 * frame;
    while ts <= t_last {
        let mut td = t_first;
        while td < ts {
            let s = ssr(td, ts);
            if s < best.0 {
                best = (s, td, ts);
            }
            td += frame;
        }
        ts += 0.5 * frame;
    }
    let (mut step_d, mut step_s) = (frame, 0.5 * frame);
    for _ in 0..4 {
        let (_, td0, ts0) = best;
        for a in -10..=10 {
            for b in -10..=10 {
                let ts = (ts0 + f64::from(b) * step_s / 5.0).clamp(t_first, t_last);
                let td = (td0 + f64::from(a) * step_d / 5.0).clamp(t_first, ts);
                let s = ssr(td, ts);
                if s < best.0 {
                    best = (s, td, ts);
                }
            }
        }
        step_d /= 5.0;
        step_s /= 5.0;
    }
    let (_, t_decel, t_stop) = best;
    let (_, beta_final, v) = profile.fit(t_decel, t_stop)?;
    let residuals: Vec<f64> = tw
        .iter()
        .zip(&bw)
        .filter(|&(&x, _)| x < t_stop)
        .map(|(&x, &b)| b - beta_final - v * remaining_turn(x, t_decel, t_stop))
        .collect();
    let rms_residual =
        (residuals.iter().map(|r| r * r).sum::<f64>() / residuals.len().max(1) as f64).sqrt();
    Some(CoulombStop {
        fit_from: t_first,
        t_decel,
        t_stop,
        rate: v,
        beta_final,
        deceleration: if t_stop > t_decel {
            v.abs() / (t_stop - t_decel)
        } else {
            f64::INFINITY
        },
        rms_residual,
        frames: tw.len(),
    })
}

/// β(t) − β_∞ for a unit rate: −∫_t^∞ of the rate profile (1 until `td`, linear to 0
/// at `ts`, 0 after) \[s\].
fn remaining_turn(t: f64, td: f64, ts: f64) -> f64 {
    if t >= ts {
        0.0
    } else if t >= td {
        -(ts - t) * (ts - t) / (2.0 * (ts - td))
    } else {
        -((td - t) + 0.5 * (ts - td))
    }
}

/// The samples of a Coulomb-stop fit, with sums over every suffix (the frames after a
/// trial stop, where the profile is zero) so that a trial costs only the frames before
/// it.
struct Profile<'a> {
    t: &'a [f64],
    /// β relative to its last sample (for precision) \[rad\].
    y: Vec<f64>,
    y0: f64,
    /// (Σy, Σy²) over samples k.. [rad, rad²].
    suffix: Vec<(f64, f64)>,
}

impl<'a> Profile<'a> {
    fn new(t: &'a [f64], beta: &[f64]) -> Self {
        let y0 = beta[beta.len() - 1];
        let y: Vec<f64> = beta.iter().map(|b| b - y0).collect();
        let mut suffix = vec![(0.0, 0.0); y.len() + 1];
        for k in (0..y.len()).rev() {
            suffix[k] = (suffix[k + 1].0 + y[k], suffix[k + 1].1 + y[k] * y[k]);
        }
        Profile { t, y, y0, suffix }
    }

    /// Least squares of β = β_∞ + v × [`remaining_turn`] for a decelerating start `td`
    /// and stop `ts`: (SSR, β_∞, v), `None` if the profile does not vary over the
    /// samples.
    fn fit(&self, td: f64, ts: f64) -> Option<(f64, f64, f64)> {
        let n = self.y.len() as f64;
        let moving = self.t.partition_point(|&x| x < ts);
        let (mut sx, mut sxx, mut sxy) = (0.0, 0.0, 0.0);
        let (mut sy, mut syy) = self.suffix[moving];
        for (&x, &y) in self.t[..moving].iter().zip(&self.y) {
            let g = remaining_turn(x, td, ts);
            sx += g;
            sy += y;
            sxx += g * g;
            sxy += g * y;
            syy += y * y;
        }
        let det = n * sxx - sx * sx;
        if det <= 0.0 || !det.is_finite() {
            return None;
        }
        let v = (n * sxy - sx * sy) / det;
        let c = (sy - v * sx) / n;
        // At the least-squares solution Σ(y − c − v g)² = Σy² − c Σy − v Σgy.
        let ssr = syy - c * sy - v * sxy;
        Some((ssr.max(0.0), c + self.y0, v))
    }
}
