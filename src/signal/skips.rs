//! Frame skips (thesis §3.3.2: "spikes appear due to frame skips occurring in the
//! footage"): timestamp gaps, and dropped frames that the timestamps hide but the motion
//! shows, as a spike in the strip's rate or a step in the rim's phase.

use super::local::{LocalInit, PhaseTrack, fit_local};
use super::peaks::nominal_period;
use super::{Halt, RimModel, SignalConfig, finite_samples, mad_sigma, median};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Why a frame was flagged.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum SkipReason {
    /// The time since the previous frame exceeds `gap_factor` nominal periods.
    TimestampGap {
        /// Time since the previous frame [s].
        gap_s: f64,
        /// Nominal frame period (median interval) [s].
        nominal_s: f64,
        /// Frames missing by the gap: round(gap / nominal) − 1.
        missing_frames: usize,
    },
    /// The strip turned much further since the previous frame than its neighbours do: a
    /// spike in the raw β̇ (fig. 3.24).
    StripRateSpike {
        /// Raw β̇ from the previous frame [rad/s].
        rate: f64,
        /// Local level of β̇: the nearer of the medians of the 12 frames before and
        /// the 12 after [rad/s].
        local_rate: f64,
        /// Robust spread of β̇ about its local level over the clip (1.4826 × MAD, at
        /// least the configured floor) [rad/s].
        local_sigma: f64,
    },
    /// The rim's phase jumps between the previous frame and this one: the local rim fit
    /// improves greatly when the frames from this one on are taken one period later.
    RimPhaseStep {
        /// Phase step ψ̇ × (one frame) that the hypothesis inserts [rad].
        phase_step: f64,
        /// (SSR without − SSR with the step) / (residual variance with it).
        statistic: f64,
    },
}

/// A frame flagged as following a skip: something is missing between frame
/// `index − 1` and frame `index`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameFlag {
    /// The frame after the suspected skip.
    pub index: usize,
    /// Its time on the caller's axis [s].
    pub t: f64,
    /// Why it was flagged.
    pub reason: SkipReason,
}

impl FrameFlag {
    /// Whether the flagged frame lies in the analysis window [`start`, `end`] (same
    /// time axis as [`FrameFlag::t`]).
    pub fn within(&self, start: f64, end: f64) -> bool {
        self.t >= start && self.t <= end
    }
}

/// The flags whose frames lie in [`start`, `end`].
pub fn flags_within(flags: &[FrameFlag], start: f64, end: f64) -> Vec<&FrameFlag> {
    flags.iter().filter(|f| f.within(start, end)).collect()
}

/// Frames that follow a timestamp gap longer than `gap_factor` × the nominal period
/// (the median frame interval).
pub fn timestamp_gaps(t: &[f64], gap_factor: f64) -> Vec<FrameFlag> {
    let nominal = nominal_period(t);
    if nominal.is_nan() || nominal <= 0.0 {
        return Vec::new();
    }
    (1..t.len())
        .filter_map(|i| {
            let gap = t[i] - t[i - 1];
            (gap > gap_factor * nominal).then(|| FrameFlag {
                index: i,
                t: t[i],
                reason: SkipReason::TimestampGap {
                    gap_s: gap,
                    nominal_s: nominal,
                    missing_frames: ((gap / nominal).round() as usize).saturating_sub(1),
                },
            })
        })
        .collect()
}

/// Neighbouring rates on each side that define the local level of β̇.
const RATE_NEIGHBOURS: usize = 12;

/// Frames whose raw β̇ from the previous frame, (β_i − β_{i−1}) / (t_i − t_{i−1}) on
/// the unwrapped β, lies beyond both the median of the 12 rates before it and that of
/// the 12 after it by more than `sigmas` × the robust spread of such departures over
/// the clip (1.4826 × MAD, at least `rate_floor` [rad/s]). A rate between the two
/// medians is a change of rate, not a skip.
/// A dropped frame whose timestamp was renumbered doubles one step of β.
pub fn strip_rate_spikes(
    t: &[f64],
    beta_unwrapped: &[f64],
    sigmas: f64,
    rate_floor: f64,
) -> Vec<FrameFlag> {
    let idx = finite_samples(t, beta_unwrapped);
    // rates[k] is the rate from sample k to sample k + 1 (frame idx[k + 1]).
    let rates: Vec<f64> = idx
        .windows(2)
        .map(|w| (beta_unwrapped[w[1]] - beta_unwrapped[w[0]]) / (t[w[1]] - t[w[0]]))
        .collect();
    // Local levels: the medians of the 12 rates before and of the 12 after. A skip is
    // a one-frame spike beyond both; a change of rate (the strip slowing to a stop
    // within a few frames) passes between them. The departure is the distance from the
    // interval between the two levels. The spread is the robust σ of these departures
    // over the whole clip (the angle noise is the camera's, the same throughout; 24
    // neighbours alone would estimate it to only ±25 %).
    let levels: Vec<Option<f64>> = (0..rates.len())
        .map(|k| {
            let before = &rates[k.saturating_sub(RATE_NEIGHBOURS)..k];
            let after =
                &rates[(k + 1).min(rates.len())..(k + 1 + RATE_NEIGHBOURS).min(rates.len())];
            if before.len() < RATE_NEIGHBOURS / 2 || after.len() < RATE_NEIGHBOURS / 2 {
                return None;
            }
            let (left, right) = (median(before), median(after));
            Some(rates[k].clamp(left.min(right), left.max(right)))
        })
        .collect();
    let departures: Vec<f64> = rates
        .iter()
        .zip(&levels)
        .filter_map(|(r, l)| l.map(|l| r - l))
        .collect();
    if departures.is_empty() {
        return Vec::new();
    }
    let sigma = mad_sigma(&departures, 0.0).max(rate_floor);
    let mut flags = Vec::new();
    for (k, level) in levels.iter().enumerate() {
        let Some(level) = *level else { continue };
        if (rates[k] - level).abs() > sigmas * sigma {
            let i = idx[k + 1];
            flags.push(FrameFlag {
                index: i,
                t: t[i],
                reason: SkipReason::StripRateSpike {
                    rate: rates[k],
                    local_rate: level,
                    local_sigma: sigma,
                },
            });
        }
    }
    flags
}

/// Frames after which the rim's phase steps by one frame's worth of precession.
///
/// For each pair of consecutive rim heights before the halt, where the oscillation
/// stands clear of the noise (peak height above `skip_min_snr` × noise), the local
/// model with a chirp (φ₀ + φ₁τ, χ₀ + ωτ + ½ω̇τ²) is fitted over 1.5 periods on each
/// side (the period from the phase track's advance over one period either side) twice: with the stamped times (A), and with every later frame taken one
/// nominal period later (B, the dropped-frame hypothesis). The frame is flagged when
/// F = (SSR_A − SSR_B) / (SSR_B / dof_B) exceeds `phase_step_statistic`; of flags
/// closer than a period, the strongest is kept. Times in `track` are halt-shifted.
pub(crate) fn rim_phase_steps(
    t: &[f64],
    z_rim: &[f64],
    halt: &Halt,
    model: &dyn RimModel,
    track: &PhaseTrack,
    config: &SignalConfig,
) -> Vec<FrameFlag> {
    let frame = nominal_period(t);
    let ts = &halt.shifted_t;
    let idx: Vec<usize> = finite_samples(t, z_rim)
        .into_iter()
        .filter(|&i| i <= halt.index)
        .collect();
    let v: Vec<f64> = idx.iter().map(|&i| z_rim[i] - halt.rest_level).collect();
    let st: Vec<f64> = idx.iter().map(|&i| ts[i]).collect();
    // (sample k, statistic, phase step, half-width in samples) of each candidate.
    // Two independent local fits per sample: spread over the cores.
    let candidates: Vec<(usize, f64, f64, usize)> = (1..idx.len())
        .into_par_iter()
        .filter_map(|k| {
            let t_c = st[k];
            let (Some((psi, psi_dot)), Some((phi, phi_dot))) =
                (track.psi_at(t_c), track.phi_at(t_c))
            else {
                return None;
            };
            if !(psi_dot > 0.0 && phi > 0.0)
                || model.z_rim(phi, 0.0) < config.skip_min_snr * halt.noise
            {
                return None;
            }
            // The rate over a period on each side: the track's own rate between two
            // extrema is one frame short across a dropped frame (25 % at 8 frames per
            // period) and would shrink the window.
            let span = 2.0 * PI / psi_dot;
            let psi_dot = match (track.psi_at(t_c - span), track.psi_at(t_c + span)) {
                (Some((before, _)), Some((after, _))) if after > before => {
                    (after - before) / (2.0 * span)
                }
                _ => psi_dot,
            };
            let per_period = (2.0 * PI / psi_dot / frame).round() as usize;
            if per_period < MIN_FRAMES_PER_PERIOD {
                return None;
            }
            let m = ((per_period as f64 * WINDOW_PERIODS).round() as usize).max(6);
            if k < m || k + m > idx.len() {
                return None;
            }
            let (lo, hi) = (k - m, k + m);
            let init = LocalInit {
                phi,
                phi_slope: phi_dot,
                chi: psi,
                omega: psi_dot,
            };
            let (tw, zw) = (&st[lo..hi], &v[lo..hi]);
            let plain = fit_local(model, tw, zw, t_c, init, true, None);
            let stepped = fit_local(model, tw, zw, t_c, init, true, Some((t_c, frame)));
            let (Some(a), Some(b)) = (plain, stepped) else {
                return None;
            };
            let dof = b.dof.saturating_sub(1).max(1) as f64;
            let variance = (b.ssr / dof).max(f64::MIN_POSITIVE);
            let statistic = (a.ssr - b.ssr) / variance;
            (statistic > config.phase_step_statistic).then_some((k, statistic, b.omega * frame, m))
        })
        .collect();
    // Keep the strongest of candidates closer than a period.
    let mut flags = Vec::new();
    for &(k, statistic, step, m) in &candidates {
        let strongest = candidates
            .iter()
            .filter(|&&(j, ..)| j.abs_diff(k) < m)
            .all(|&(j, s, ..)| s < statistic || (s == statistic && j >= k));
        if strongest {
            let i = idx[k];
            flags.push(FrameFlag {
                index: i,
                t: t[i],
                reason: SkipReason::RimPhaseStep {
                    phase_step: step,
                    statistic,
                },
            });
        }
    }
    flags
}

/// Half-width of the phase-step fits in oscillation periods. The statistic grows with
/// the samples after the step: on the light fixture the drop at frame 171 (8 frames per
/// period, peaks 3 px over 0.05 px of noise) gives F = 30 with one period on each side
/// and 83 with 1.5, while frames without a skip stay below F = 0 (the stepped model
/// fits them worse).
const WINDOW_PERIODS: f64 = 1.5;

/// Below this many frames per oscillation the local fits of the phase-step test are
/// too short to be trusted (the last few oscillations before the halt).
const MIN_FRAMES_PER_PERIOD: usize = 6;
