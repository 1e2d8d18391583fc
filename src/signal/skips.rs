//! Frame skips (thesis §3.3.2: "spikes appear due to frame skips occurring in the
//! footage"): timestamp gaps, and dropped frames that the timestamps hide but the motion
//! shows, as a step in the strip's angle or in the rim's phase. Duplicated and
//! interpolated frames, found on the pixels by `footage::RepeatGauge`, are flagged
//! with the same type.

use super::local::{LocalInit, PhaseTrack, Terms, fit_local};
use super::peaks::nominal_period;
use super::{Halt, RimModel, SignalConfig, finite_samples, samples_to_the_halt};
use crate::numeric::mad_sigma;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Why a frame was flagged.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum SkipReason {
    /// The time since the previous frame exceeds `gap_factor` nominal periods.
    TimestampGap {
        /// Time since the previous frame \[s\].
        gap_s: f64,
        /// Nominal frame period (median interval) \[s\].
        nominal_s: f64,
        /// Frames missing by the gap: round(gap / nominal) − 1.
        missing_frames: usize,
    },
    /// The strip's angle from this frame on stands a step away from where the frames
    /// before it lead (the thesis saw such skips as spikes in β̇, fig. 3.24).
    StripAngleStep {
        /// The after-fit minus the before-fit between this frame and the previous
        /// \[rad\].
        step: f64,
        /// One frame's turn at the local rate, β̇ × nominal period: the step that a
        /// dropped frame makes \[rad\].
        frame_turn: f64,
        /// Robust spread of the steps over the clip (1.4826 × MAD, at least the
        /// configured floor) \[rad\].
        sigma: f64,
    },
    /// The rim's phase jumps between the previous frame and this one: the local rim fit
    /// improves greatly when the frames from this one on are taken one period later.
    RimPhaseStep {
        /// Phase step ψ̇ × (one frame) that the hypothesis inserts \[rad\].
        phase_step: f64,
        /// (SSR without − SSR with the step) / (residual variance with it).
        statistic: f64,
        /// The step the turns' timing shows there ([`timing_step`]); `None` with too
        /// few turning points on either side, and in results written before it was
        /// measured.
        #[serde(default)]
        timing: Option<TimingStep>,
    },
    /// The frame repeats the previous one (`footage::RepeatGauge`): its capture is
    /// missing, and the frame is left out of the fits.
    DuplicatedFrame {
        /// Mean |difference| from the previous frame [grey levels].
        step: f64,
        /// The smaller of the neighbouring frames' steps [grey levels].
        neighbours: f64,
    },
    /// The frame is the blend of its neighbours, inserted by the camera: its
    /// capture is missing, and the frame is left out of the fits.
    InterpolatedFrame {
        /// Mean |frame − mean of its neighbours| [grey levels].
        residual: f64,
        /// The smaller of the neighbouring frames' residuals [grey levels].
        neighbours: f64,
    },
}

impl SkipReason {
    /// The flag's kind, as `result.json` tags it (`timestamp-gap`, …): a name a
    /// table can be filtered by.
    pub fn kind(&self) -> &'static str {
        match self {
            SkipReason::TimestampGap { .. } => "timestamp-gap",
            SkipReason::StripAngleStep { .. } => "strip-angle-step",
            SkipReason::RimPhaseStep { .. } => "rim-phase-step",
            SkipReason::DuplicatedFrame { .. } => "duplicated-frame",
            SkipReason::InterpolatedFrame { .. } => "interpolated-frame",
        }
    }

    /// Whether the flag shows a frame missing beyond doubt: every kind does but a rim
    /// phase step, which does when the turns' timing confirms it ([`TimingStep`]).
    pub fn confirmed(&self) -> bool {
        match self {
            SkipReason::RimPhaseStep { timing, .. } => timing.is_some_and(|s| s.confirmed),
            _ => true,
        }
    }

    /// A short description for a person looking at the frame.
    pub fn label(&self) -> String {
        match self {
            SkipReason::TimestampGap {
                gap_s,
                missing_frames,
                ..
            } => format!(
                "timestamp gap of {:.2} ms, {missing_frames} frame(s) missing before this one",
                1e3 * gap_s
            ),
            SkipReason::StripAngleStep { step, .. } => {
                format!(
                    "the strip angle steps by {:.2}° (dropped frame?)",
                    step.to_degrees()
                )
            }
            SkipReason::RimPhaseStep {
                phase_step, timing, ..
            } => {
                let timing = match timing {
                    Some(s) => format!(
                        "; the turns' timing steps by {:.2} ± {:.2} ms",
                        1e3 * s.step_s,
                        1e3 * s.se_s
                    ),
                    None => "; too few turns either side to time".to_string(),
                };
                format!(
                    "the rim's phase jumps by {:.2}° (dropped frame?){timing}",
                    phase_step.to_degrees()
                )
            }
            SkipReason::DuplicatedFrame { step, neighbours } => format!(
                "a copy of the frame before (changed {step:.2} grey levels, its neighbours \
                 {neighbours:.2})"
            ),
            SkipReason::InterpolatedFrame {
                residual,
                neighbours,
            } => format!(
                "a blend of its neighbours (off it by {residual:.2} grey levels, they by \
                 {neighbours:.2})"
            ),
        }
    }
}

/// A frame flagged as following a skip (something is missing between frame
/// `index − 1` and frame `index`), or as showing no capture of its own.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameFlag {
    /// The frame after the suspected skip.
    pub index: usize,
    /// Its time on the caller's axis \[s\].
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

/// Frames on each side of a boundary whose angles give where the strip stands there.
const STEP_NEIGHBOURS: usize = 12;
/// How many errors from a whole number of frame turns a skip's step may lie: a
/// looser test than the `sigmas` from zero that finds it (two-sided 99.99 % of a
/// normal error), so that a drop seen is not rejected for the fits' own bias.
const CONSISTENT_SIGMAS: f64 = 4.0;

/// Frames after which the strip's angle stands a step away from where the frames
/// before it lead: a dropped frame whose timestamp was renumbered.
///
/// At each boundary between frames k − 1 and k, β (unwrapped) over the 12 frames
/// before and over the 12 from k on are each fitted with a quadratic in the stamped
/// time, and the step is the after-fit minus the before-fit halfway between the two
/// frames. A renumbered dropped frame advances every later angle by one frame's turn,
/// β̇·Δt, and the step shows it in full. A change of rate leaves the angle continuous:
/// a Coulomb stop is a quadratic, and a frame the codec left behind and then caught
/// up (H.264 on the slow strip) gives a step near zero. The thesis looked for spikes
/// in the raw β̇ instead (fig. 3.24), which such lags raise too, as does a sudden
/// change of β̇.
///
/// A boundary is flagged when its step stands `sigmas` errors e from zero and lies
/// within [`CONSISTENT_SIGMAS`] errors of a whole number m ≥ 1 of frame turns (e
/// combined with m × the turn's own error), a turn itself standing that many errors
/// from zero (on a still strip any step is some number of turns). e is the larger of the robust spread of
/// the steps over the clip (at least `floor` \[rad\]) and the step's own standard
/// error from the two fits' residuals (a jump of β̇ inside a window, which the
/// quadratics cannot follow, raises the residual and the error with it, and hides a
/// skip within 12 frames of it). A skip is thus seen only where the strip turns by
/// more than `sigmas` spreads in a frame. The test against zero alone is not enough:
/// a two-view clip with no frame dropped can show a step of half a frame's turn (7
/// errors from zero, 6 from a turn), while a dropped frame reads 0.74–1.13 turns,
/// within 3.2 errors of one. Of flags within 6 frames, the largest step is
/// kept.
///
/// Only frames before `t_beta`, the strip's stop, are flagged, and the window after
/// such a frame is fitted with the quadratic held at its value from the stop on: a
/// stopped strip shows no skip, and a strip that stops at once (a few frames after
/// the fall) puts a kink in the windows across its stop, which a quadratic does not
/// follow: it reads as a step of 0.9–1.4 frames' turn within two frames of the stop,
/// as a dropped frame would. A window ending at the stop instead keeps too few
/// frames to see a drop three frames after the fall, with the strip still turning
/// (`tests/analyse.rs`). The spread of the steps is still taken over the whole clip.
pub fn strip_angle_steps(
    t: &[f64],
    beta_unwrapped: &[f64],
    t_beta: f64,
    sigmas: f64,
    floor: f64,
) -> Vec<FrameFlag> {
    let idx = finite_samples(t, beta_unwrapped);
    let frame = nominal_period(t);
    if frame.is_nan() || frame <= 0.0 {
        return Vec::new();
    }
    // A quadratic in the stamped time, held at its value from `stop` on.
    let fit = |range: &[usize], t_mid: f64, stop: f64| {
        QuadraticFit::new(
            range
                .iter()
                .map(|&i| (t[i].min(stop) - t_mid, beta_unwrapped[i])),
        )
    };
    let n = STEP_NEIGHBOURS;
    if idx.len() < 2 * n {
        return Vec::new();
    }
    // (sample k, step, frame turn, standard errors of the step and of the turn)
    let boundaries: Vec<(usize, f64, f64, f64, f64)> = (n..=idx.len() - n)
        .filter_map(|k| {
            let t_mid = 0.5 * (t[idx[k - 1]] + t[idx[k]]);
            let before = fit(&idx[k - n..k], t_mid, f64::INFINITY)?;
            // Before the stop, the window after the boundary stops with the strip.
            let stop = if t[idx[k]] < t_beta {
                t_beta
            } else {
                f64::INFINITY
            };
            let after = fit(&idx[k..k + n], t_mid, stop)?;
            let step = after.value - before.value;
            let frame_turn = 0.5 * (before.slope + after.slope) * frame;
            let turn_se = 0.5 * before.slope_se.hypot(after.slope_se) * frame;
            Some((
                k,
                step,
                frame_turn,
                before.value_se.hypot(after.value_se),
                turn_se,
            ))
        })
        .collect();
    let steps: Vec<f64> = boundaries.iter().map(|b| b.1).collect();
    let sigma = mad_sigma(&steps, 0.0).max(floor);
    // A dropped frame moves the strip on by whole frames' turns: the step must be
    // m ≥ 1 of them within CONSISTENT_SIGMAS errors of both, and a turn must stand
    // that many errors from zero (else any step is some number of them).
    let whole_turns = |step: f64, turn: f64, error: f64, turn_se: f64| {
        let m = (step / turn).round();
        turn.abs() > CONSISTENT_SIGMAS * error
            && m >= 1.0
            && (step - m * turn).abs() <= CONSISTENT_SIGMAS * error.hypot(m * turn_se)
    };
    let mut candidates: Vec<(usize, f64, f64)> = boundaries
        .iter()
        .filter(|&&(k, step, turn, se, turn_se)| {
            let error = sigma.max(se);
            t[idx[k]] < t_beta
                && step.abs() > sigmas * error
                && whole_turns(step, turn, error, turn_se)
        })
        .map(|&(k, step, turn, _, _)| (k, step, turn))
        .collect();
    // The largest steps first; a smaller one within 6 frames of a kept one is the
    // same skip seen from a window that straddles it.
    candidates.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
    let mut kept: Vec<(usize, f64, f64)> = Vec::new();
    for c in candidates {
        if kept.iter().all(|k| k.0.abs_diff(c.0) > n / 2) {
            kept.push(c);
        }
    }
    kept.sort_by_key(|c| c.0);
    kept.into_iter()
        .map(|(k, step, frame_turn)| {
            let i = idx[k];
            FrameFlag {
                index: i,
                t: t[i],
                reason: SkipReason::StripAngleStep {
                    step,
                    frame_turn,
                    sigma,
                },
            }
        })
        .collect()
}

/// A least-squares quadratic a + b·τ + c·τ² through points (τ, y): its value a and
/// slope b at τ = 0, and their standard errors from the residual.
struct QuadraticFit {
    value: f64,
    slope: f64,
    value_se: f64,
    slope_se: f64,
}

impl QuadraticFit {
    fn new(points: impl Iterator<Item = (f64, f64)> + Clone) -> Option<Self> {
        let mut normal = nalgebra::Matrix3::<f64>::zeros();
        let mut rhs = nalgebra::Vector3::<f64>::zeros();
        let mut count = 0usize;
        // Times in units of the span keep the normal equations well scaled.
        let scale = points.clone().map(|(x, _)| x.abs()).fold(0.0, f64::max);
        if scale.is_nan() || scale <= 0.0 {
            return None;
        }
        for (x, y) in points.clone() {
            let u = x / scale;
            let basis = nalgebra::Vector3::new(1.0, u, u * u);
            normal += basis * basis.transpose();
            rhs += basis * y;
            count += 1;
        }
        if count < 4 {
            return None;
        }
        let cholesky = normal.cholesky()?;
        let coef = cholesky.solve(&rhs);
        let ssr: f64 = points
            .map(|(x, y)| {
                let u = x / scale;
                (y - (coef[0] + coef[1] * u + coef[2] * u * u)).powi(2)
            })
            .sum();
        let variance = ssr / (count - 3) as f64;
        let covariance = cholesky.inverse() * variance;
        Some(Self {
            value: coef[0],
            slope: coef[1] / scale,
            value_se: covariance[(0, 0)].sqrt(),
            slope_se: covariance[(1, 1)].sqrt() / scale,
        })
    }
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
    let (idx, st, v) = samples_to_the_halt(t, z_rim, halt);
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
            // A window across a timestamp gap is left to the gap's own flag: the
            // phase track lacks the peaks inside the gap, and on a render whose
            // timestamps skip 25 frames the stepped fit flagged the frame 10
            // before the gap (F = 78).
            if spans_gap(&t[idx[lo]..=idx[hi - 1]], frame, config.gap_factor) {
                return None;
            }
            let init = LocalInit {
                phi,
                phi_slope: phi_dot,
                chi: psi,
                omega: psi_dot,
            };
            let (tw, zw) = (&st[lo..hi], &v[lo..hi]);
            let plain = fit_local(model, tw, zw, t_c, init, Terms::CHIRP, None);
            let stepped = fit_local(model, tw, zw, t_c, init, Terms::CHIRP, Some((t_c, frame)));
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
    let kept: Vec<(usize, f64, f64)> = candidates
        .iter()
        .filter(|&&(k, statistic, _, m)| {
            candidates
                .iter()
                .filter(|&&(j, ..)| j.abs_diff(k) < m)
                .all(|&(j, s, ..)| s < statistic || (s == statistic && j >= k))
        })
        .map(|&(k, statistic, step, _)| (k, statistic, step))
        .collect();
    let times: Vec<f64> = kept.iter().map(|&(k, ..)| st[k]).collect();
    kept.iter()
        .zip(timed_steps(track.psi_knots(), &times, frame))
        .map(|(&(k, statistic, step), timing)| FrameFlag {
            index: idx[k],
            t: t[idx[k]],
            reason: SkipReason::RimPhaseStep {
                phase_step: step,
                statistic,
                timing,
            },
        })
        .collect()
}

/// The timing step ([`timing_step`]) at each of the suspected skips at the sorted
/// times `at`, each on the turning points between its neighbours, so that one skip's
/// step does not bend the law another's is measured against.
fn timed_steps(knots: &[(f64, f64)], at: &[f64], frame_s: f64) -> Vec<Option<TimingStep>> {
    (0..at.len())
        .map(|j| {
            let after_previous = j.checked_sub(1).map_or(f64::NEG_INFINITY, |i| at[i]);
            let before_next = at.get(j + 1).copied().unwrap_or(f64::INFINITY);
            let between: Vec<(f64, f64)> = knots
                .iter()
                .filter(|knot| knot.0 >= after_previous && knot.0 < before_next)
                .copied()
                .collect();
            timing_step(&between, at[j], frame_s)
        })
        .collect()
}

/// The step in the turning points' times at a suspected dropped frame: the times of
/// the peaks and troughs (the phase track's knots) on either side, each turn at its
/// counted ψ, fitted as one smooth law t(ψ) (a cubic over [`TIMING_TURNS`] turns on
/// each side) plus a step δ from the suspected frame on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TimingStep {
    /// δ \[s\]: the later turning points' times minus the law's through the earlier
    /// ones. A capture missing before a frame whose timestamp follows on makes it one
    /// frame period early, −Δt.
    pub step_s: f64,
    /// δ's standard error from the law's residuals \[s\].
    pub se_s: f64,
    /// Turning points fitted.
    pub points: usize,
    /// A frame missing (δ = −Δt) is [`MIN_LOG_ODDS`] likelier than none (δ = 0), and δ
    /// lies within [`CONSISTENT_SIGMAS`] errors of −Δt.
    pub confirmed: bool,
}

/// Turns on each side of a suspected skip whose turning points time it: 6, twelve
/// points a side, so the law's cubic is held by as many points as the step.
const TIMING_TURNS: f64 = 6.0;

/// Fewest turning points on each side for a timing step: one turn's. The law's
/// cubic is held by the side with more; near the clip's start or the halt the
/// step's error grows with the side that has fewer.
const MIN_TIMING_POINTS: usize = 2;

/// Fewest degrees of freedom of the timing law's residuals (points − 5), for an
/// error of the step worth the name.
const MIN_TIMING_DOF: usize = 4;

/// ln 100: a frame missing must be a hundred times likelier than none, given the
/// timing step, before the capture clock counts it (the local fit that suspected it
/// already made it a fair guess).
const MIN_LOG_ODDS: f64 = 4.605_170_185_988_092;

/// The timing step at `t_c` (halt-shifted, between the frames either side of the
/// suspected skip) from the `knots` (t, ψ) of the phase track, for frames `frame_s`
/// apart. A dropped frame moves every later turning point by one frame, whatever the
/// rim's shape does; a φ oscillating about stationary rolling, which a local fit of
/// the heights can take for a phase step, moves the turns' times by a wobble the
/// smooth law leaves in its residuals, not by a frame.
pub(crate) fn timing_step(knots: &[(f64, f64)], t_c: f64, frame_s: f64) -> Option<TimingStep> {
    let split = knots.partition_point(|k| k.0 < t_c);
    let per_side = (2.0 * TIMING_TURNS) as usize;
    let (before, after) = (
        &knots[split.saturating_sub(per_side)..split],
        &knots[split..(split + per_side).min(knots.len())],
    );
    if before.len() < MIN_TIMING_POINTS || after.len() < MIN_TIMING_POINTS {
        return None;
    }
    // ψ from the first turning point after the skip: the origin of the law's cubic.
    let psi_c = after[0].1;
    let span = before
        .iter()
        .chain(after)
        .map(|k| (k.1 - psi_c).abs())
        .fold(0.0, f64::max);
    // t = c0 + c1 u + c2 u² + c3 u³ + δ [after], u = (ψ − ψ_c)/span.
    let rows: Vec<[f64; 5]> = before
        .iter()
        .map(|k| (k, 0.0))
        .chain(after.iter().map(|k| (k, 1.0)))
        .map(|(k, h)| {
            let u = (k.1 - psi_c) / span;
            [1.0, u, u * u, u * u * u, h]
        })
        .collect();
    let times: Vec<f64> = before.iter().chain(after).map(|k| k.0 - t_c).collect();
    let x = nalgebra::DMatrix::from_fn(rows.len(), 5, |i, j| rows[i][j]);
    let y = nalgebra::DVector::from_column_slice(&times);
    let normal = (x.transpose() * &x).cholesky()?;
    let coef = normal.solve(&(x.transpose() * &y));
    let dof = rows.len().checked_sub(5).filter(|&d| d >= MIN_TIMING_DOF)? as f64;
    let variance = (&y - &x * &coef).norm_squared() / dof;
    let se_s = (variance * normal.inverse()[(4, 4)]).sqrt();
    let step_s = coef[4];
    // The two simple hypotheses, δ = −Δt (a frame missing) and δ = 0 (none), by their
    // likelihood ratio under the step's normal error; and δ no farther from −Δt than a
    // drop's own step would stand.
    let log_ratio = (step_s.powi(2) - (step_s + frame_s).powi(2)) / (2.0 * se_s * se_s);
    let confirmed =
        log_ratio >= MIN_LOG_ODDS && (step_s + frame_s).abs() <= CONSISTENT_SIGMAS * se_s;
    Some(TimingStep {
        step_s,
        se_s,
        points: rows.len(),
        confirmed,
    })
}

/// Whether two consecutive frame times in `t` lie more than `gap_factor` frame
/// periods apart (a timestamp gap, as [`timestamp_gaps`] flags it).
pub(crate) fn spans_gap(t: &[f64], frame: f64, gap_factor: f64) -> bool {
    t.windows(2).any(|w| w[1] - w[0] > gap_factor * frame)
}

/// Half-width of the phase-step fits in oscillation periods. The statistic grows with
/// the samples after the step: on a light-plate render the drop at capture 171 (8
/// frames per period, peaks 3 px over 0.05 px of noise) gave F = 30 with one period on
/// each side and 83 with 1.5, while frames without a skip stay below F = 0 (the
/// stepped model fits them worse).
const WINDOW_PERIODS: f64 = 1.5;

/// The frames missing from a clip whose timestamps show no gap (a camera or an
/// encoder that drops a capture and stamps the next frame a period on): the rim
/// phase steps among `flags` (halt-shifted times) that the turns' timing confirms
/// ([`TimingStep`]), at no timestamp gap and at no
/// duplicated or interpolated frame or beside one (`repeated`: file positions of
/// frames kept without a capture of their own), whose test window of
/// [`WINDOW_PERIODS`] oscillations on each side ends at least one more window before
/// the halt. Each is one frame missing just before it, so the capture clock runs one
/// nominal period ahead of the timestamps from it on.
///
/// The margin is the halt's: the test's window after a step reaches the frames it holds
/// up to the halt, and a halt seen late by an encoder's still pictures (up to 12–15 ms
/// on coded footage, which the energy law's bound moves back later in `analyse`) puts
/// those pictures inside a step test near it, which may then flag the last moving frame
/// (F = 17.5 against a halt 6 frames late). A flag is enough to warn; counting a frame
/// that is not missing would move every time after it, so the clock is corrected only
/// where the window is clear of the halt.
pub fn missing_frames(flags: &[FrameFlag], frame_s: f64, repeated: &[usize]) -> Vec<FrameFlag> {
    flags
        .iter()
        .filter(|f| {
            let SkipReason::RimPhaseStep { phase_step, .. } = f.reason else {
                return false;
            };
            let gap = flags
                .iter()
                .any(|g| g.index == f.index && matches!(g.reason, SkipReason::TimestampGap { .. }));
            let beside_repeated = repeated
                .iter()
                .any(|&r| r + 1 >= f.index && r <= f.index + 1);
            // The test's window: WINDOW_PERIODS periods of 2π/phase_step frames.
            let window_s = WINDOW_PERIODS * 2.0 * PI / phase_step * frame_s;
            f.reason.confirmed() && !gap && !beside_repeated && f.t <= -2.0 * window_s
        })
        .cloned()
        .collect()
}

/// Below this many frames per oscillation the local fits of the phase-step test are
/// too short to be trusted (the last few oscillations before the halt).
const MIN_FRAMES_PER_PERIOD: usize = 6;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    const FRAME: f64 = 1.0 / 480.0;

    /// Turning points half a turn apart on the stationary-rolling timing law
    /// t = −c (ψ_end − ψ)^q (n = 0.6; about 11 frames a half-turn at the start, the
    /// whole over 1 s), each time with a 0.1 ms error, and `shift(t)` added to the
    /// times.
    fn knots(seed: u64, shift: impl Fn(f64) -> f64) -> Vec<(f64, f64)> {
        let (q, c, psi_end) = (1.0 / 0.7, 5.5e-4, 61.0 * PI);
        let mut rng = SplitMix64::new(seed);
        (0..60)
            .map(|k| {
                let psi = k as f64 * PI;
                let t = -c * (psi_end - psi).powf(q);
                (t + shift(t) + 1e-4 * rng.gaussian(), psi)
            })
            .collect()
    }

    /// A frame missing at t_c moves every later turning point a frame early: the
    /// timing step reads −Δt and confirms it, for any noise seed.
    #[test]
    fn a_dropped_frame_steps_the_turns_timing_by_a_frame() {
        let t_c = -0.6;
        for seed in 1..=20 {
            let knots = knots(seed, |t| if t >= t_c { -FRAME } else { 0.0 });
            let step = timing_step(&knots, t_c, FRAME).expect("enough turns");
            assert!(step.confirmed, "seed {seed}: {step:?}");
            assert!((step.step_s + FRAME).abs() < 4.0 * step.se_s, "{step:?}");
            assert_eq!(step.points, 24);
        }
    }

    /// With no frame missing the step is noise, and a wobble of the turns' times
    /// (a φ oscillating about stationary rolling: ±0.5 ms every 2.7 turns, which a
    /// local fit of the heights can take for a phase step) confirms no drop.
    #[test]
    fn no_frame_missing_confirms_no_drop_under_a_wobble() {
        for seed in 1..=20 {
            for wobble in [0.0, 5e-4] {
                let knots = knots(seed, |t| wobble * (2.0 * PI * t / 0.06).sin());
                let step = timing_step(&knots, -0.6, FRAME).expect("enough turns");
                assert!(!step.confirmed, "seed {seed}, wobble {wobble}: {step:?}");
            }
        }
    }

    /// Without a turn on one side (the clip's first frames) there is no step to time.
    #[test]
    fn no_timing_without_turns_on_both_sides() {
        let knots = knots(1, |_| 0.0);
        let first = knots[0].0;
        assert_eq!(timing_step(&knots, first + 0.5 * FRAME, FRAME), None);
    }
}
