//! Peaks and troughs of z_rim with sub-frame interpolation, φ at peaks (eq. 3.9), ψ by
//! counting turns and ψ̇ (eq. 3.11) (thesis §3.2.5).

use super::local::{LocalInit, PhaseTrack, Terms, fit_local, widened};
use super::{Halt, RimModel, SignalConfig, SignalError, finite_samples};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// How a peak or trough was located between frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ExtremumMethod {
    /// The rim model fitted over 1.5 oscillations and at least nine frames: the peak
    /// is where its phase χ is 0 (π for a trough). Not limited by truncated samples.
    LocalFit,
    /// A parabola through the extreme sample and its two neighbours (fewer than nine
    /// samples in the whole series, the local fit failed, or it disagreed with the
    /// parabola by more than a frame).
    Parabolic,
}

/// A peak of z_rim: the raised side of the disk faces the camera (fig. 3.6).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Peak {
    /// Frame of the highest sample.
    pub index: usize,
    /// Interpolated peak time, halt at t = 0 \[s\].
    pub t: f64,
    /// Interpolated peak height above the rest level \[m\].
    pub z: f64,
    /// Nutation angle at the peak \[rad\]: eq. (3.9) (corrected, φ = arcsin(z/2R)) for
    /// [`ThesisRim`](super::ThesisRim), its analogue for other rim models.
    pub phi: f64,
    /// Standard error of φ from the local fit \[rad\]; `None` for a parabolic peak.
    pub sigma_phi: Option<f64>,
    /// Precession rate ω = ψ̇ of the local fit and its standard error [rad/s].
    pub psi_dot_local: Option<(f64, f64)>,
    /// Time \[s\] and height \[m\] of the highest sample (no interpolation).
    pub sample: (f64, f64),
    /// Time \[s\] and height \[m\] of the parabolic vertex through three samples.
    pub parabolic: (f64, f64),
    /// Topographic prominence of the peak \[m\].
    pub prominence: f64,
    /// How `t` and `z` were found.
    pub method: ExtremumMethod,
}

/// A trough of z_rim: the contact point faces the camera.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Trough {
    /// Frame of the lowest sample between two peaks.
    pub index: usize,
    /// Interpolated trough time, halt at t = 0 \[s\].
    pub t: f64,
    /// How `t` was found.
    pub method: ExtremumMethod,
}

/// ψ and ψ̇ at the turning points of z_rim (thesis §3.2.5).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PrecessionSample {
    /// Time, halt at t = 0 \[s\].
    pub t: f64,
    /// Precession angle ψ \[rad\], zero at the last turning point (the thesis zeroes ψ
    /// where the motion ends) and increasing.
    pub psi: f64,
    /// ψ̇ by eq. (3.11), the slope of the succeeding segment [rad/s]; `None` at the last.
    pub psi_dot_forward: Option<f64>,
    /// ψ̇ by central differences over the neighbouring samples [rad/s]; `None` at the
    /// ends.
    pub psi_dot_central: Option<f64>,
}

/// Peaks in the analysis window before the halt, with φ and ψ.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PeakSeries {
    /// Analysis window (start, end), halt at t = 0 \[s\]: the `window_s` up to the halt's
    /// last frame of motion, and a quarter turn before it ([`find_peaks`]).
    pub window: (f64, f64),
    /// Peaks in the window, in time order.
    pub peaks: Vec<Peak>,
    /// Troughs between consecutive peaks of the window.
    pub troughs: Vec<Trough>,
    /// ψ advanced by 2π per peak (the thesis's method), with ψ̇.
    pub precession: Vec<PrecessionSample>,
    /// ψ advanced by π per peak and per trough (the thesis's doubled resolution).
    pub precession_half_turns: Vec<PrecessionSample>,
}

/// Finds the peaks of z_rim in the window of [`SignalConfig::window_s`] seconds
/// that ends at the halt's last frame of motion (t_φ, unless [`SignalConfig::halt_at`]
/// places the halt elsewhere: the window stays where the motion was seen, as the
/// energy fits' window ends at their last sample), reaching back a quarter turn
/// further ([`window_margin`]; the energy fits take their own `window_s` from their
/// last sample), interpolates them between frames,
/// and derives φ at each peak (eq. 3.9) and ψ, ψ̇ (eq. 3.11 and central differences).
///
/// Peaks are local maxima (a plateau counts once, at its middle) of z_rim − rest
/// level whose prominence exceeds `prominence_sigmas` × the rest noise (and
/// `min_prominence`), and the halt's last moving frame when it is such a maximum and
/// lower than the peak before it by more than the noise: the halt has already told it
/// from noise (it rises above the motion threshold and the rim rests after it), so it
/// is the last turn's peak whatever its prominence over the single noisy reading after
/// it (on a noisy light plate a true last peak of 0.71 px, read 0.78 px, falls short
/// of a 6σ prominence test of 0.92 px).
/// Where two peaks lie two turns apart or more, the turns between them are the
/// highest maxima above the motion threshold where the turns around place them
/// ([`with_missed_turns`]), and so is a final turn after the last peak
/// ([`final_turn`]). Each is refined by the local fit of `model` over 1.5
/// oscillations (module docs), falling back to the parabola through three samples.
///
/// Errors with [`SignalError::TooFewPeaks`] when fewer than three peaks lie in the
/// window.
pub fn find_peaks(
    t: &[f64],
    z_rim: &[f64],
    halt: &Halt,
    model: &dyn RimModel,
    config: &SignalConfig,
) -> Result<PeakSeries, SignalError> {
    super::check_series(t, z_rim, "z_rim")?;
    config.validate()?;
    let seen = halt.last_motion_seen();
    let nominal = (seen - config.window_s, seen);
    let (mut peaks, mut troughs) = extrema(t, z_rim, halt, model, config, nominal.0);
    let window = (nominal.0 - window_margin(&peaks), seen);
    if window.0 < nominal.0 {
        (peaks, troughs) = extrema(t, z_rim, halt, model, config, window.0);
    }
    if peaks.len() < 3 {
        return Err(SignalError::TooFewPeaks {
            found: peaks.len(),
            needed: 3,
            window_start: window.0,
            window_end: window.1,
        });
    }
    let peak_times: Vec<f64> = peaks.iter().map(|p| p.t).collect();
    let mut turning: Vec<(f64, bool)> = peak_times
        .iter()
        .map(|&t| (t, true))
        .chain(troughs.iter().map(|tr| (tr.t, false)))
        .collect();
    turning.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(PeakSeries {
        window,
        precession: precession(&peak_times, 2.0 * PI),
        precession_half_turns: precession_half_turns(&turning),
        peaks,
        troughs,
    })
}

/// The fraction of the turn at the window's start by which the window reaches back
/// before its nominal start ([`window_margin`]).
const WINDOW_MARGIN_TURNS: f64 = 0.25;

/// How far the window reaches back before its nominal start \[s\]: a quarter of the
/// turn there (the interval between the first two peaks found from the nominal start),
/// 0 with fewer than two. The window ends at the last frame of motion seen, which the
/// codec or the sampling can put a frame or two after the true halt; the nominal start
/// moves with it, and a crest within that of the start would be counted or not by
/// chance. A quarter turn keeps such a crest, and reaches no turn beyond it.
fn window_margin(peaks: &[Peak]) -> f64 {
    match peaks {
        [first, second, ..] => WINDOW_MARGIN_TURNS * (second.t - first.t),
        _ => 0.0,
    }
}

/// ψ advanced by `step` per turn between the sorted `times`, zero at the last, with
/// ψ̇ by eq. (3.11) (forward) and by central differences (non-uniform spacing).
///
/// Consecutive times are usually one turn (`step`) apart; where an interval spans
/// several local periods (frames missing from the clip, or a peak lost in the
/// noise), it counts as that many turns: round(Δt / T), T the median of the two to
/// four intervals around it, at least one (one turn each with fewer neighbours). The precession period changes by a few
/// per cent a turn, so a missing turn doubles an interval against its neighbours.
pub fn precession(times: &[f64], step: f64) -> Vec<PrecessionSample> {
    counted(times, step, |_, ratio| ratio.round().max(1.0))
}

/// ψ advanced by π per half-turn between the sorted turning points of z_rim, each a
/// peak (`true`) or a trough, zero at the last, with ψ̇ as in [`precession`]. Each
/// interval counts the half-turns of its parity nearest Δt / T (T as in
/// [`precession`]): an odd number from a peak to a trough or back, an even one, two
/// at least, between two peaks or two troughs. Plain rounding takes a trough 1.5
/// half-turns before a last peak (5.4 ms between half-turns of 3–4 ms) for a whole
/// turn, and so puts every peak before it at a trough's χ.
pub fn precession_half_turns(turning: &[(f64, bool)]) -> Vec<PrecessionSample> {
    let times: Vec<f64> = turning.iter().map(|&(t, _)| t).collect();
    counted(&times, PI, |j, ratio| {
        if turning[j].1 == turning[j + 1].1 {
            (2.0 * (0.5 * ratio).round()).max(2.0)
        } else {
            2.0 * (0.5 * (ratio - 1.0)).round().max(0.0) + 1.0
        }
    })
}

/// ψ advanced by `step` times `steps(j, Δt_j / T_j)` over each interval j between the
/// sorted `times` (T_j the median of the two to four intervals around it; the ratio
/// is 1 with fewer), zero at the last, with ψ̇ forward and central.
fn counted(times: &[f64], step: f64, steps: impl Fn(usize, f64) -> f64) -> Vec<PrecessionSample> {
    let n = times.len();
    let intervals: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    let turns: Vec<f64> = (0..intervals.len())
        .map(|j| {
            let around: Vec<f64> = (j.saturating_sub(2)..(j + 3).min(intervals.len()))
                .filter(|&i| i != j)
                .map(|i| intervals[i])
                .collect();
            let period = crate::numeric::median(&around);
            let ratio = if around.len() >= 2 && period.is_finite() && period > 0.0 {
                intervals[j] / period
            } else {
                1.0
            };
            steps(j, ratio)
        })
        .collect();
    // ψ at each time, counted back from the last.
    let mut psi = vec![0.0; n];
    for k in (0..n.saturating_sub(1)).rev() {
        psi[k] = psi[k + 1] - step * turns[k];
    }
    (0..n)
        .map(|k| PrecessionSample {
            t: times[k],
            psi: psi[k],
            psi_dot_forward: (k + 1 < n).then(|| step * turns[k] / intervals[k]),
            psi_dot_central: (k > 0 && k + 1 < n)
                .then(|| step * (turns[k - 1] + turns[k]) / (times[k + 1] - times[k - 1])),
        })
        .collect()
}

/// The peaks (and the troughs between them) at shifted times ≥ `from` up to the halt.
pub(crate) fn extrema(
    t: &[f64],
    z_rim: &[f64],
    halt: &Halt,
    model: &dyn RimModel,
    config: &SignalConfig,
    from: f64,
) -> (Vec<Peak>, Vec<Trough>) {
    let ts = &halt.shifted_t;
    // Samples up to one past the halt (so the last moving frame can be a maximum).
    let idx: Vec<usize> = finite_samples(t, z_rim)
        .into_iter()
        .filter(|&i| i <= halt.index + 1)
        .collect();
    let v: Vec<f64> = idx.iter().map(|&i| z_rim[i] - halt.rest_level).collect();
    let min_prominence = (config.prominence_sigmas * halt.noise).max(config.min_prominence);
    let frame = nominal_period(t);
    let maxima: Vec<(usize, f64)> = local_maxima(&v)
        .into_iter()
        .map(|k| (k, prominence(&v, k)))
        .filter(|&(k, _)| ts[idx[k]] >= from && idx[k] <= halt.index)
        .collect();
    let mut raw: Vec<(usize, f64)> = maxima
        .iter()
        .copied()
        .filter(|&(_, p)| p > min_prominence)
        .collect();
    // The halt's last rise as the last turn's peak (see above): above the motion
    // threshold, and lower than the peak before it by more than the noise, as the
    // rim's amplitude decays (a picture the encoder holds after the halt repeats a
    // height to 1e-5 px, for several frames; taken as a peak it puts t_φ frames late).
    // Not where `motion_until` cut the motion there (`Halt::motion_cut`): the frames
    // after it are no rest then, only rises a law of the motion left out, so the halt
    // has told the last rise from nothing (coded pictures after the halt may rise
    // 0.27 px above the rest right at the cut).
    if let (Some(&(k, p)), Some(&(previous, _))) = (maxima.last(), raw.last())
        && idx[k] == halt.index
        && k != previous
        && v[k] > halt.threshold
        && v[k] < v[previous] - halt.noise
        && !halt.motion_cut
    {
        raw.push((k, p));
    }
    let sample_times: Vec<f64> = idx.iter().map(|&i| ts[i]).collect();
    // A final turn the prominence test missed; not the rise `motion_until` cut the
    // motion at, which the halt has not told from the coded rises after it (above).
    let uncut: Vec<(usize, f64)> = maxima
        .iter()
        .copied()
        .filter(|&(k, _)| !(halt.motion_cut && idx[k] == halt.index))
        .collect();
    let last_turn = final_turn(&raw, &uncut, &sample_times, &v, halt);
    raw = with_missed_turns(&raw, &maxima, &sample_times, &v, halt.threshold);
    raw.extend(last_turn);
    // Motion samples only (through the halt) for the local fits.
    let fit_end = idx.partition_point(|&i| i <= halt.index);
    let mut peaks = Vec::with_capacity(raw.len());
    for (n, &(k, prom)) in raw.iter().enumerate() {
        let period = local_period(&raw, &sample_times, n);
        let parabolic = parabolic_vertex(&sample_times, &v, k);
        let refined = period.and_then(|period| {
            refine(
                model,
                &sample_times[..fit_end],
                &v[..fit_end],
                k,
                period,
                parabolic,
                0.0,
                frame,
            )
        });
        let (t_peak, z_peak, phi, sigma_phi, psi_dot_local, method) = match refined {
            Some((tp, phi, fit)) => (
                tp,
                model.z_rim(phi, 0.0),
                phi,
                Some(fit.sigma_phi),
                Some((fit.omega, fit.sigma_omega)),
                ExtremumMethod::LocalFit,
            ),
            None => (
                parabolic.0,
                parabolic.1,
                model.phi_from_peak(parabolic.1),
                None,
                None,
                ExtremumMethod::Parabolic,
            ),
        };
        peaks.push(Peak {
            index: idx[k],
            t: t_peak,
            z: z_peak,
            phi,
            sigma_phi,
            psi_dot_local,
            sample: (sample_times[k], v[k]),
            parabolic,
            prominence: prom,
            method,
        });
    }
    let mut troughs = Vec::new();
    for pair in raw.windows(2) {
        let (a, b) = (pair[0].0, pair[1].0);
        let Some(k) = (a + 1..b).min_by(|&x, &y| v[x].total_cmp(&v[y])) else {
            continue;
        };
        let period = sample_times[b] - sample_times[a];
        // A parabola through the lowest sample: its vertex is the minimum.
        let parabolic = parabolic_vertex(&sample_times, &v, k);
        let refined = refine(
            model,
            &sample_times[..fit_end],
            &v[..fit_end],
            k,
            period,
            parabolic,
            PI,
            frame,
        );
        let (t_trough, method) = match refined {
            Some((tt, _, _)) => (tt, ExtremumMethod::LocalFit),
            None => (parabolic.0, ExtremumMethod::Parabolic),
        };
        troughs.push(Trough {
            index: idx[k],
            t: t_trough,
            method,
        });
    }
    (peaks, troughs)
}

/// The ψ track through peaks (2πk) and troughs (2πk + π), zero at the last peak, and φ
/// at the peaks: starting values for the per-frame fits and the frame-skip test.
pub(crate) fn phase_track(peaks: &[Peak], troughs: &[Trough]) -> PhaseTrack {
    let last = peaks.len() as f64 - 1.0;
    let mut psi: Vec<(f64, f64)> = peaks
        .iter()
        .enumerate()
        .map(|(k, p)| (p.t, 2.0 * PI * (k as f64 - last)))
        .collect();
    // Trough k lies between peaks k and k + 1 (one per consecutive pair).
    psi.extend(
        troughs
            .iter()
            .enumerate()
            .map(|(k, tr)| (tr.t, 2.0 * PI * (k as f64 - last) + PI)),
    );
    let phi = peaks.iter().map(|p| (p.t, p.phi)).collect();
    PhaseTrack::new(psi, phi)
}

/// Median frame interval \[s\] (the nominal period of the footage).
pub(crate) fn nominal_period(t: &[f64]) -> f64 {
    let dt: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    if dt.is_empty() {
        f64::NAN
    } else {
        crate::numeric::median(&dt)
    }
}

/// Indices of local maxima; a plateau counts once, at its middle.
fn local_maxima(v: &[f64]) -> Vec<usize> {
    let mut out = Vec::new();
    let mut i = 1;
    while i + 1 < v.len() {
        if v[i] > v[i - 1] {
            let mut j = i;
            while j + 1 < v.len() && v[j + 1] == v[i] {
                j += 1;
            }
            if j + 1 < v.len() && v[j + 1] < v[i] {
                out.push((i + j) / 2);
            }
            i = j + 1;
        } else {
            i += 1;
        }
    }
    out
}

/// Topographic prominence of the maximum at `k`: its height above the higher of the two
/// lowest points between it and the nearest higher sample on each side (or the end).
fn prominence(v: &[f64], k: usize) -> f64 {
    let peak = v[k];
    let mut left = peak;
    for &x in v[..k].iter().rev() {
        if x > peak {
            break;
        }
        left = left.min(x);
    }
    let mut right = peak;
    for &x in &v[k + 1..] {
        if x > peak {
            break;
        }
        right = right.min(x);
    }
    peak - left.max(right)
}

/// Vertex (time, value) of the parabola through samples k − 1, k, k + 1 (non-uniform
/// times), kept between the outer two; the sample itself when the three are collinear
/// or k is at an end.
fn parabolic_vertex(t: &[f64], v: &[f64], k: usize) -> (f64, f64) {
    if k == 0 || k + 1 >= v.len() {
        return (t[k], v[k]);
    }
    let (t0, t1, t2) = (t[k - 1], t[k], t[k + 1]);
    let (y0, y1, y2) = (v[k - 1], v[k], v[k + 1]);
    let d01 = (y1 - y0) / (t1 - t0);
    let d12 = (y2 - y1) / (t2 - t1);
    let curvature = (d12 - d01) / (t2 - t0); // second divided difference
    if curvature == 0.0 || !curvature.is_finite() {
        return (t1, y1);
    }
    // y = y1 + d (t − t1) + c (t − t1)(t − t0'), written about t1.
    let slope_at_t1 = d01 + curvature * (t1 - t0);
    let dt = (-slope_at_t1 / (2.0 * curvature)).clamp(t0 - t1, t2 - t1);
    (t1 + dt, y1 + slope_at_t1 * dt + curvature * dt * dt)
}

/// Intervals on either side of a gap between peaks that give the turn it is measured
/// in ([`with_missed_turns`]).
const NEIGHBOUR_INTERVALS: usize = 2;

/// The peaks `raw` (positions in the samples, prominences) with the turns the
/// prominence test missed between them: where two consecutive peaks lie m + 1 turns
/// apart (m ≥ 1; the turn T the median of up to [`NEIGHBOUR_INTERVALS`] intervals
/// between peaks on either side, two at least), the rim rose m times in between, once
/// in each of m equal parts of the gap between its troughs (half a turn from either
/// peak). In each part, the highest local maximum of `maxima` whose height `v` over
/// the rest level exceeds the motion `threshold` is that turn's peak.
///
/// The prominence test asks `prominence_sigmas` σ of any local maximum, since most of
/// them are noise. Where the turns around it place a turn and the rim is moving (all
/// of this lies before t_φ), a turn is there; its peak needs only to rise as the halt
/// asks any motion to. Near the halt of a noisy clip a final turn read low by the codec
/// can fall below 6σ of prominence and still clear the threshold (at σ 0.09 px, a
/// turn of 0.78 px read at 0.50 px over a trough at 0.04 px, 5.2σ of prominence,
/// between two peaks found two turns apart).
fn with_missed_turns(
    raw: &[(usize, f64)],
    maxima: &[(usize, f64)],
    t: &[f64],
    v: &[f64],
    threshold: f64,
) -> Vec<(usize, f64)> {
    let intervals: Vec<f64> = raw.windows(2).map(|w| t[w[1].0] - t[w[0].0]).collect();
    let mut out = Vec::with_capacity(raw.len());
    for (g, pair) in raw.windows(2).enumerate() {
        out.push(pair[0]);
        let around: Vec<f64> = (g.saturating_sub(NEIGHBOUR_INTERVALS)..g)
            .chain(g + 1..(g + 1 + NEIGHBOUR_INTERVALS).min(intervals.len()))
            .map(|j| intervals[j])
            .collect();
        if around.len() < NEIGHBOUR_INTERVALS {
            continue;
        }
        let turn = crate::numeric::median(&around);
        let (start, gap) = (t[pair[0].0], intervals[g]);
        let turns = (gap / turn).round() as usize;
        if turns < 2 {
            continue;
        }
        // The m turns' parts, from half a turn after the first peak to half a turn
        // before the second.
        let part = (gap - turn) / (turns - 1) as f64;
        for j in 0..turns - 1 {
            let from = start + 0.5 * turn + j as f64 * part;
            let turn_peak = maxima
                .iter()
                .filter(|&&(k, _)| t[k] > from && t[k] <= from + part && v[k] > threshold)
                .max_by(|a, b| v[a.0].total_cmp(&v[b.0]));
            out.extend(turn_peak);
        }
    }
    out.extend(raw.last());
    out
}

/// The turn after the last of the peaks `raw` where the prominence test missed it, as
/// [`with_missed_turns`] finds one between two peaks: where the turns before place
/// the next crest (half a turn to one and a half after the last peak, the turn T the
/// median of the last [`NEIGHBOUR_INTERVALS`] intervals) and the rim still moves (all
/// of `maxima` lie up to the halt's last frame of motion), the highest local maximum
/// above the halt's motion threshold and lower than the last peak by more than the
/// noise σ is that turn's peak: the rim's amplitude decays, while a picture the
/// encoder holds repeats a height (as for the halt's last rise, [`extrema`]).
///
/// The rule that takes the halt's last rise as the last peak needs the last frame of
/// motion to be the crest; where the rim is still seen coming down a frame after it,
/// the crest stood only on its prominence, which a final crest read low by the codec
/// (0.45 px for a true 0.56 px, one or two frames before the last frame of motion)
/// may not have against the 6σ test.
fn final_turn(
    raw: &[(usize, f64)],
    maxima: &[(usize, f64)],
    t: &[f64],
    v: &[f64],
    halt: &Halt,
) -> Option<(usize, f64)> {
    let &(last, _) = raw.last()?;
    let intervals: Vec<f64> = raw.windows(2).map(|w| t[w[1].0] - t[w[0].0]).collect();
    let latest = intervals.len().checked_sub(NEIGHBOUR_INTERVALS)?;
    let turn = crate::numeric::median(&intervals[latest..]);
    let (from, to) = (t[last] + 0.5 * turn, t[last] + 1.5 * turn);
    maxima
        .iter()
        .copied()
        .filter(|&(k, _)| {
            t[k] > from && t[k] <= to && v[k] > halt.threshold && v[k] < v[last] - halt.noise
        })
        .max_by(|a, b| v[a.0].total_cmp(&v[b.0]))
}

/// Width of the chirped local fit at a peak or trough, in turns.
const CHIRP_WINDOW_PERIODS: f64 = 1.5;
/// Fewest samples for the chirped (five-parameter) local fit.
const MIN_CHIRP_SAMPLES: usize = 9;

/// Local oscillation period at the n-th raw peak: the mean spacing to its neighbours.
fn local_period(raw: &[(usize, f64)], t: &[f64], n: usize) -> Option<f64> {
    let spacing = |a: usize, b: usize| t[raw[b].0] - t[raw[a].0];
    match (n > 0, n + 1 < raw.len()) {
        (true, true) => Some(0.5 * (spacing(n - 1, n) + spacing(n, n + 1))),
        (true, false) => Some(spacing(n - 1, n)),
        (false, true) => Some(spacing(n, n + 1)),
        (false, false) => None,
    }
}

/// Chirped local fit over 1.5 periods (at least [`MIN_CHIRP_SAMPLES`] frames) centred
/// on sample k (motion samples `t`, `v`); returns the time nearest the parabolic
/// vertex where the phase is `target` (0 peak, π trough), φ there and the fit, if the
/// fit converged and lands within a frame of the parabola.
#[allow(clippy::too_many_arguments)]
fn refine(
    model: &dyn RimModel,
    t: &[f64],
    v: &[f64],
    k: usize,
    period: f64,
    parabolic: (f64, f64),
    target: f64,
    frame: f64,
) -> Option<(f64, f64, super::local::LocalFit)> {
    if k >= t.len() {
        return None;
    }
    let t_c = t[k];
    let window = |periods: f64| {
        let half = 0.5 * periods * period;
        (
            t.partition_point(|&x| x < t_c - half),
            t.partition_point(|&x| x <= t_c + half),
        )
    };
    // ψ̇ grows within a turn near the halt: a chirp over 1.5 turns, the window grown
    // to MIN_CHIRP_SAMPLES frames where the turns are shorter than six (the final
    // turns of a fast precession, 4–5 frames each: a parabola through three of them
    // reads the peak 3–15 % low), as the per-frame states grow theirs.
    let (lo, hi) = window(CHIRP_WINDOW_PERIODS);
    let (lo, hi) = widened(lo, hi, t.len(), MIN_CHIRP_SAMPLES);
    if hi - lo < MIN_CHIRP_SAMPLES {
        return None;
    }
    let omega = 2.0 * PI / period;
    let phi_guess = if target == 0.0 {
        model.phi_from_peak(parabolic.1)
    } else {
        // At a trough the height says little; the mean over the window is R φ.
        let mean = v[lo..hi].iter().sum::<f64>() / (hi - lo) as f64;
        model.phi_from_peak(2.0 * mean)
    };
    if !(phi_guess.is_finite() && phi_guess > 0.0) {
        return None;
    }
    let init = LocalInit {
        phi: phi_guess,
        phi_slope: 0.0,
        chi: target + omega * (t_c - parabolic.0),
        omega,
    };
    let fit = fit_local(model, &t[lo..hi], &v[lo..hi], t_c, init, Terms::CHIRP, None)?;
    let (t_x, phi_x) = fit.time_of_phase(t_c, target);
    let plausible = (t_x - parabolic.0).abs() <= frame
        && phi_x > 0.0
        && fit.omega > 0.5 * omega
        && fit.omega < 2.0 * omega;
    plausible.then_some((t_x, phi_x, fit))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plateaus_and_prominence() {
        let v = [0.0, 1.0, 3.0, 3.0, 3.0, 1.0, 2.0, 1.5, 5.0, 0.0];
        assert_eq!(local_maxima(&v), vec![3, 6, 8]);
        assert_eq!(prominence(&v, 3), 2.0); // down to 1.0 on the right before 5.0
        assert_eq!(prominence(&v, 6), 0.5);
        assert_eq!(prominence(&v, 8), 5.0);
    }

    #[test]
    fn parabola_vertex_on_uneven_times() {
        let t = [0.0, 1.0, 3.0];
        let v: Vec<f64> = t.iter().map(|&x: &f64| 4.0 - (x - 1.4).powi(2)).collect();
        let (tv, yv) = parabolic_vertex(&t, &v, 1);
        assert!((tv - 1.4).abs() < 1e-12 && (yv - 4.0).abs() < 1e-12);
    }

    /// An ending with a trough 5.4 ms before the last peak, after half-turns of 4.1
    /// and 3.0 ms. Δt / T = 1.5 there,
    /// which plain rounding counts as a whole turn; from a trough to a peak it is an odd
    /// number of half-turns, one. Peaks stay at even multiples of π all the way back,
    /// and a peak lost between two troughs leaves them two half-turns apart.
    #[test]
    fn a_peak_and_a_trough_lie_an_odd_number_of_half_turns_apart() {
        let mut turning: Vec<(f64, bool)> = (0..12)
            .map(|k| (-0.0113 - 0.0041 * (11 - k) as f64, k % 2 == 1))
            .chain([(-0.0072, true), (-0.0042, false), (0.0012, true)])
            .collect();
        turning.sort_by(|a, b| a.0.total_cmp(&b.0));
        let count = |turning: &[(f64, bool)]| {
            precession_half_turns(turning)
                .iter()
                .map(|s| (s.psi / PI).round() as i64)
                .collect::<Vec<_>>()
        };
        let half_turns = count(&turning);
        for (&(_, peak), k) in turning.iter().zip(&half_turns) {
            assert_eq!(k.rem_euclid(2) == 0, peak, "{half_turns:?}");
        }
        assert_eq!(half_turns[turning.len() - 2], -1, "{half_turns:?}");
        let rounded: Vec<f64> = turning.iter().map(|&(t, _)| t).collect();
        assert_eq!(
            (precession(&rounded, PI)[turning.len() - 2].psi / PI).round(),
            -2.0,
            "plain rounding"
        );
        // A peak lost between two troughs: two half-turns.
        let mut lost = turning.clone();
        lost.remove(5);
        let counted = count(&lost);
        assert_eq!(counted[4] - counted[5], -2, "{counted:?}");
    }

    #[test]
    fn a_turn_lost_in_a_gap_is_still_counted() {
        // Turns every 10 ms shortening by 2 % each; the 6th turning point missing.
        let mut times = vec![0.0];
        for k in 0..12 {
            times.push(times[k] + 0.01 * 0.98f64.powi(k as i32));
        }
        let truth = precession(&times, 2.0 * PI);
        let mut gapped = times.clone();
        gapped.remove(6);
        let samples = precession(&gapped, 2.0 * PI);
        for (s, k) in samples.iter().zip((0..times.len()).filter(|&k| k != 6)) {
            assert!((s.psi - truth[k].psi).abs() < 1e-12, "ψ at {k}");
        }
        // ψ̇ over the gap: two turns over its two intervals.
        let over = samples[5].psi_dot_forward.expect("3.11");
        let mean = 4.0 * PI / (times[7] - times[5]);
        assert!((over - mean).abs() < 1e-9 * mean);
    }

    #[test]
    fn precession_counts_turns_and_differentiates() {
        let times = [0.0, 0.1, 0.3];
        let samples = precession(&times, 2.0 * PI);
        assert_eq!(samples[2].psi, 0.0);
        assert!((samples[0].psi + 4.0 * PI).abs() < 1e-12);
        assert!((samples[0].psi_dot_forward.expect("3.11") - 20.0 * PI).abs() < 1e-9);
        assert!((samples[1].psi_dot_central.expect("central") - 4.0 * PI / 0.3).abs() < 1e-9);
        assert!(samples[2].psi_dot_forward.is_none() && samples[0].psi_dot_central.is_none());
    }
}
