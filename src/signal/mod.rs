//! Signal: per-frame series from `vision` turned into state series for `energy`
//! (thesis §3.2.4–§3.2.5, §3.3.2–§3.3.3).
//!
//! # Role in the data flow
//!
//! ```text
//! vision::  per-frame t_i [s], z_rim_i [m] (NaN: no edge), β_i [rad] mod π (two-view)
//!   │
//!   ▼  signal::
//!   │   halt_time         t_φ: last frame with rim motion above the rest noise; t − t_φ
//!   │   find_peaks        peaks (sub-frame), φ at peaks (eq. 3.9), ψ by turns, ψ̇ (3.11)
//!   │   frame_states      φ, ψ, ψ̇ at every frame, with standard errors (local fits)
//!   │   strip_series      β unwrapped by ±π, 5-point moving average, β̇ (eq. 3.22)
//!   │   strip_stop_time   t_β: Coulomb stop fit (eq. 4.112), band of fig. 3.22; t_β − t_φ
//!   │   frame_skips       timestamp gaps, β̇ spikes, rim phase steps, with reasons
//!   │   analyse           all of the above → StateSeries
//!   ▼
//! energy::  E from eq. (3.8) with φ, ψ̇; power-law fit
//! ```
//!
//! Everything here is a pure function over slices: no files, no printing. Times are
//! seconds; after [`halt_time`] they are shifted so that the halt is t = 0 (fields
//! say which axis they use). Heights are metres above the rest level.
//!
//! # What the side camera sees: the rim-height model
//!
//! Frames: the global frame G has z up; eq. (3.14) turns it by ψ about z (frame I),
//! then by φ about y_I (body frame B, symmetry axis z_B). The contact point is at
//! G + (−R, 0, −H) in B (H the half-thickness), so x_B points from the contact point
//! through the centre to the highest point of the rim, and its horizontal direction
//! x_I = (cos ψ, sin ψ, 0) has azimuth ψ. A bottom-rim point at body angle α is
//!
//! ```text
//! p(α) = G + R cos α e_x + R sin α e_y − H e_z,   height  z(α) = R sin φ (1 + cos α),
//! e_x = (cos φ cos ψ, cos φ sin ψ, sin φ),  e_y = (−sin ψ, cos ψ, 0),
//! e_z = (−sin φ cos ψ, −sin φ sin ψ, cos φ).
//! ```
//!
//! Under stationary rolling (eq. 3.7) the centre G does not move, so the centre column
//! of the image (x_l + x_r)/2 of the rest frame (ERRATA, §3.2.4) is the vertical plane
//! through G facing the camera. Put the camera far away at azimuth ψ_c and write
//! χ = ψ − ψ_c: χ = 0 when the raised side faces the camera (fig. 3.6). The column
//! meets the bottom rim where
//!
//! ```text
//! R cos φ sin χ cos α + R cos χ sin α = −H sin φ sin χ,
//! ```
//!
//! twice: near the camera and far from it. The underside of the disk is not wrapped
//! (§3.2.3), so the white region the vision stage thresholds ends at the **front** rim
//! point, whichever side of the disk is seen; the far one is hidden or dark. Solving
//! for the front root and expanding in φ:
//!
//! ```text
//! α = −χ + h φ sin χ + O(φ²),   h = H/R
//! z_rim = R sin φ (1 + cos χ − h φ sin²χ) − H φ cos χ tan ε + O(R φ³),
//! ```
//!
//! where the last term appears for a camera at elevation ε (image rows measured from
//! the rest frame's front rim, divided by cos ε: the front rim moves by H φ cos χ
//! towards or away from the camera). So, to first order in φ, the profile between
//! peaks is **z_rim = R sin φ (1 + cos χ)**: it peaks at 2R sin φ when the raised side
//! faces the camera (eq. 3.9 is exact there for a level camera) and touches zero once a
//! turn, when the contact point faces it. The next terms are relative O(h φ) (h φ ≈
//! 0.5 % at φ = 0.03 for Euler's disk, and zero at the peaks) and O(h tan ε) (0.8 % of
//! the oscillating part at ε = 5°). Neglected altogether: perspective (relative depth
//! changes O(R/D) for a camera at distance D), lateral motion of the centre (the
//! thesis's reason to keep only the final 0.5 s), the rounded rim, and refraction of
//! the edge by shadows and reflections (vision's business).
//!
//! The model is the [`RimModel`] trait: [`ThesisRim`] is the first-order profile,
//! [`SideViewRim`] the exact front-rim solution with H and ε. The fits below take any
//! `&dyn RimModel`, so a corrected geometry (e.g. the renderer's exact camera) drops in.
//! The model is even in χ: one side view cannot tell the sense of precession, so ψ̇ is
//! reported positive.
//!
//! # Methods
//!
//! * **Halt** ([`halt_time`]): the rest tail (last `rest_tail_s`) gives the rest level
//!   (median) and noise (3σ-clipped RMS from the MAD); t_φ is the last frame whose rim
//!   rises `motion_sigmas` × noise above the rest (the rim is never below it); the tail
//!   is checked to be at rest (nothing above the threshold, no
//!   oscillation), the noise re-measured over the whole rest and t_φ found again.
//! * **Peaks** ([`find_peaks`]): local maxima with prominence above
//!   `prominence_sigmas` × noise, in the `window_s` before the halt, and the halt's last
//!   moving frame when it is a maximum lower than the peak before it. At 480 fps the last
//!   oscillations have 5–7 frames, so the highest sample misses the true peak (the
//!   thesis notes the truncation, §3.2.4). Each peak is refined by fitting the rim model
//!   over 1.5 oscillations with φ = φ₀ + φ₁τ, χ = χ₀ + ωτ + ½ω̇τ² (ψ̇ ∝ τ^{−1/4}
//!   grows within a turn; without the chirp the peaks came out up to 0.4 frame early),
//!   and over at least nine frames where turns are shorter (a parabola through three
//!   samples of a 4–5-frame turn reads the peak 3–15 % low). The peak is where χ = 0;
//!   the parabola is the fallback where the fit fails or lands over a frame from it.
//!   φ at the peak follows from the model (eq. 3.9 for [`ThesisRim`]). ψ grows by 2π
//!   per peak, or by π per peak and trough, zero at the last; ψ̇ by eq. (3.11) and by
//!   central differences.
//! * **Per-frame states** ([`frame_states`]): the same chirped local model fitted over
//!   `state_window_periods` (1.5) turns centred on every frame, started from the
//!   peak/trough phase track; standard errors from s² (JᵀJ)⁻¹ with s² = SSR/dof. On
//!   synthetic data they are somewhat small (83–91 % of truths within 3σ), as the
//!   residuals also carry the model error.
//! * **Strip** ([`strip_series`], [`strip_stop_time`]): unwrapping, the 5-point moving
//!   average and β̇ as §3.3.2; t_β by fitting the stop of a flat disk braked by rim
//!   friction (eq. 4.112), with the band of fig. 3.22 beside it.
//! * **Frame skips** ([`frame_skips`]): see [`SkipReason`].
//!
//! # Known limits
//!
//! The local model has a linearly changing ψ̇ over its window; in the last ~0.03 s ψ̇
//! changes faster than that within a turn, and φ, ψ, ψ̇ and the peak times there carry a
//! model error (peak times up to half a frame) that the residual scaling of the
//! standard errors only partly shows. Peaks below `prominence_sigmas` ×
//! noise (the final tiny oscillations) are not found, unless at the halt's last frame.
//! The phase-step test needs at least six frames per oscillation and an oscillation
//! well above the noise.

mod halt;
mod local;
mod peaks;
mod rim;
mod skips;
mod strip;
#[cfg(test)]
mod tests;
mod zero;

pub use halt::{Halt, halt_time};
pub use peaks::{
    ExtremumMethod, Peak, PeakSeries, PrecessionSample, Trough, find_peaks, precession,
    precession_half_turns,
};
pub use rim::{RimModel, SideViewRim, ThesisRim};
pub use skips::{
    FrameFlag, SkipReason, TimingStep, flags_within, missing_frames, strip_angle_steps,
    timestamp_gaps,
};
pub use strip::{
    StripSeries, StripStop, derivative, moving_average, strip_series, strip_stop_time,
    unwrap_half_turns,
};
pub use zero::{MotionZero, motion_zero};

use local::{LocalInit, Terms, fit_local};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use thiserror::Error;

/// Settings of the signal stage; [`Default`] gives the thesis's choices where it has
/// them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SignalConfig {
    /// Analysis window before the halt \[s\]; the thesis keeps the final 0.5 s (§3.2.4).
    pub window_s: f64,
    /// Length of the rest tail at the end of the clip that measures the noise \[s\].
    pub rest_tail_s: f64,
    /// The rim moves where z_rim rises above its rest level by this many noise σ.
    pub motion_sigmas: f64,
    /// Lower bound of the noise σ \[m\]; for edges quantised to pixels of δ metres
    /// (eq. 3.10) a constant rest tail has MAD 0, and δ/√12 is a sensible floor.
    pub noise_floor: f64,
    /// The step \[m\] in which the heights are read, when they are read on whole pixels
    /// (δ of eq. 3.10, as the thesis did); `None` for sub-pixel readings. Sub-pixel
    /// readings never repeat exactly unless the decoder showed a picture again, which
    /// the halt then takes as no new motion (`halt::repeated`); readings on whole
    /// pixels repeat all the time.
    pub quantum: Option<f64>,
    /// A peak needs a prominence above this many noise σ.
    pub prominence_sigmas: f64,
    /// A peak needs a prominence above this \[m\] in any case (e.g. one pixel).
    pub min_prominence: f64,
    /// Width of the per-frame fit window in oscillation periods.
    pub state_window_periods: f64,
    /// Points of the centred moving average of β (5 in the thesis).
    pub smoothing_points: usize,
    /// Time [s, caller's axis] after which β has certainly settled (fig. 3.22); `None`:
    /// the last `strip_settled_tail_s` of the clip.
    pub strip_settled_after: Option<f64>,
    /// Length of the settled part of β when `strip_settled_after` is `None` \[s\].
    pub strip_settled_tail_s: f64,
    /// A frame interval above this many nominal periods is a timestamp gap.
    pub gap_factor: f64,
    /// A step of the strip's angle this many robust σ from zero is a skip.
    pub strip_step_sigmas: f64,
    /// Lower bound of the steps' spread in that test \[rad\].
    pub strip_step_floor: f64,
    /// The phase-step test runs where the peak height exceeds this many noise σ.
    pub skip_min_snr: f64,
    /// Time [s, caller's axis] after which no rise of the rim is motion: a law of the
    /// motion fitted to the clip (the energy law's t0, the turns' end T) has the disk
    /// flat by then (`analyse` sets it when the halt seen lies after the law's,
    /// [`halt::halt_time`]); `None`: no bound.
    pub motion_until: Option<f64>,
    /// t_φ, the halt \[s, caller's axis\], where the motion's laws place it (`analyse`
    /// sets it from the energy law's t0 and the turns' end, a second pass); `None`:
    /// the last frame of motion seen ([`halt::halt_time`]). The detector's last frame
    /// of motion, the rest tail and every window of the local fits stay as found.
    pub halt_at: Option<f64>,
    /// F statistic above which a rim phase step is flagged. Frames more than three
    /// from a skip give F ≤ 0 (the stepped model fits them worse) on dark, light and
    /// two-view renders; dropped frames on light renders give F = 21 to 297.
    pub phase_step_statistic: f64,
}

impl Default for SignalConfig {
    fn default() -> Self {
        SignalConfig {
            window_s: 0.5,
            rest_tail_s: 0.1,
            motion_sigmas: 5.0,
            noise_floor: 0.0,
            quantum: None,
            prominence_sigmas: 6.0,
            min_prominence: 0.0,
            state_window_periods: 1.5,
            smoothing_points: 5,
            strip_settled_after: None,
            strip_settled_tail_s: 0.1,
            gap_factor: 1.5,
            strip_step_sigmas: 6.0,
            strip_step_floor: 1e-6,
            skip_min_snr: 20.0,
            motion_until: None,
            halt_at: None,
            phase_step_statistic: 10.0,
        }
    }
}

impl SignalConfig {
    fn validate(&self) -> Result<(), SignalError> {
        let positive = [
            ("window_s", self.window_s),
            ("rest_tail_s", self.rest_tail_s),
            ("motion_sigmas", self.motion_sigmas),
            ("state_window_periods", self.state_window_periods),
            ("strip_settled_tail_s", self.strip_settled_tail_s),
            ("gap_factor", self.gap_factor),
            ("strip_step_sigmas", self.strip_step_sigmas),
            ("phase_step_statistic", self.phase_step_statistic),
        ];
        let non_negative = [
            ("noise_floor", self.noise_floor),
            ("prominence_sigmas", self.prominence_sigmas),
            ("min_prominence", self.min_prominence),
            ("strip_step_floor", self.strip_step_floor),
            ("skip_min_snr", self.skip_min_snr),
        ];
        for (field, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(SignalError::InvalidConfig {
                    field,
                    value,
                    expected: "a finite positive number",
                });
            }
        }
        for (field, value) in non_negative {
            if !(value.is_finite() && value >= 0.0) {
                return Err(SignalError::InvalidConfig {
                    field,
                    value,
                    expected: "a finite number ≥ 0",
                });
            }
        }
        if let Some(value) = self.halt_at.filter(|t| !t.is_finite()) {
            return Err(SignalError::InvalidConfig {
                field: "halt_at",
                value,
                expected: "a finite time",
            });
        }
        if self.smoothing_points == 0 {
            return Err(SignalError::InvalidConfig {
                field: "smoothing_points",
                value: 0.0,
                expected: "at least 1",
            });
        }
        Ok(())
    }
}

/// Why the signal stage could not produce a result.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SignalError {
    /// Times and values differ in length.
    #[error(
        "{times} frame times but {values} {series} values: the series must pair up frame by frame"
    )]
    LengthMismatch {
        times: usize,
        values: usize,
        series: &'static str,
    },
    /// Fewer than two frames.
    #[error("{frames} frame(s): the signal stage needs a series of frames")]
    TooShort { frames: usize },
    /// A frame time is NaN or infinite.
    #[error("frame {index} has time {t} s, not a finite number")]
    NonFiniteTime { index: usize, t: f64 },
    /// Frame times do not increase.
    #[error("frame {index} at t = {t} s does not come after frame {} at {previous} s", index - 1)]
    TimesNotIncreasing { index: usize, previous: f64, t: f64 },
    /// A setting is out of range.
    #[error("setting {field} = {value} must be {expected}")]
    InvalidConfig {
        field: &'static str,
        value: f64,
        expected: &'static str,
    },
    /// Too few rim heights in the rest tail to measure the noise.
    #[error(
        "the last {tail_s} s hold {frames} rim heights, fewer than the {needed} needed to \
         measure the noise at rest: the clip must run on after the disk has stopped"
    )]
    RestTailTooShort {
        tail_s: f64,
        frames: usize,
        needed: usize,
    },
    /// The rest tail contains motion beyond the threshold it defines.
    #[error(
        "no rest tail: the rim still moves at t = {t_moving} s (z_rim − rest = {deviation} m \
         > threshold {threshold} m), after the tail's start at {tail_start} s; the clip may \
         end before the halt, or film too little rest after it (at least 0.1 s is needed)"
    )]
    TailNotAtRest {
        tail_start: f64,
        t_moving: f64,
        deviation: f64,
        threshold: f64,
    },
    /// The rest tail oscillates.
    #[error(
        "no rest tail: z_rim after t = {tail_start:.4} s oscillates by {rms:.2e} m RMS about \
         its rest level (autocorrelation {correlation:.2} at a lag of {lag} frames); the clip \
         seems to end before the disk stops"
    )]
    TailOscillates {
        tail_start: f64,
        lag: usize,
        correlation: f64,
        /// RMS of the tail's readings about their median \[m\].
        rms: f64,
    },
    /// Nothing moves beyond the noise.
    #[error(
        "no rim motion: z_rim never rises above its rest level by more than the threshold \
         {threshold} m (highest rise {max_deviation} m)"
    )]
    NoMotion { threshold: f64, max_deviation: f64 },
    /// Fewer than three peaks in the analysis window.
    #[error(
        "{found} peak(s) of z_rim in the window [{window_start}, {window_end}] s before the \
         halt; at least {needed} are needed for φ, ψ and ψ̇ (lengthen `fit.window_s` in the \
         config, or check the frame rate: too few frames per precession turn hide peaks)"
    )]
    TooFewPeaks {
        found: usize,
        needed: usize,
        window_start: f64,
        window_end: f64,
    },
    /// Too few strip angles after the settling time.
    #[error(
        "only {frames} strip angles after t = {settled_after} s, fewer than the {needed} \
         needed for the band of fig. 3.22"
    )]
    SettledTooShort {
        settled_after: f64,
        frames: usize,
        needed: usize,
    },
    /// β never leaves the band: no rotation to stop.
    #[error(
        "the strip angle never leaves the band [{band_low}, {band_high}] rad (widened by its \
         width) before t = {settled_after} s: no rotation to stop"
    )]
    StripNeverMoves {
        settled_after: f64,
        band_low: f64,
        band_high: f64,
    },
}

/// The state of the disk at one frame, from the local rim fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrameState {
    /// Frame index.
    pub index: usize,
    /// Time, halt at t = 0 \[s\].
    pub t: f64,
    /// Nutation angle φ \[rad\].
    pub phi: f64,
    /// Standard error of φ \[rad\].
    pub sigma_phi: f64,
    /// Precession angle ψ \[rad\] on the peak series' scale (2πk at peaks, 0 at the last
    /// peak of the window).
    pub psi: f64,
    /// Standard error of ψ \[rad\].
    pub sigma_psi: f64,
    /// Precession rate ψ̇ [rad/s].
    pub psi_dot: f64,
    /// Standard error of ψ̇ [rad/s].
    pub sigma_psi_dot: f64,
    /// Root-mean-square residual of the fit \[m\].
    pub residual_rms: f64,
    /// Rim heights in the fit.
    pub points: usize,
}

impl FrameState {
    /// Whether the local fit determined the state: φ and ψ̇ with standard errors
    /// below 10 %. A fit whose window was cut short (at the series' start, or at a
    /// halt the codec moved) can converge on a ψ̇ far from its neighbours' with an
    /// error larger than itself.
    pub fn is_determined(&self) -> bool {
        self.sigma_phi < 0.1 * self.phi.abs() && self.sigma_psi_dot < 0.1 * self.psi_dot.abs()
    }
}

/// φ, ψ and ψ̇ with standard errors at every frame of the peak window that has a rim
/// height, by fitting `model` over about `state_window_periods` oscillations centred
/// on the frame (module docs). Frames whose fit fails, or whose window spans a
/// timestamp gap, are left out. Only frames up to the halt enter the fits.
pub fn frame_states(
    t: &[f64],
    z_rim: &[f64],
    halt: &Halt,
    peaks: &PeakSeries,
    model: &dyn RimModel,
    config: &SignalConfig,
) -> Vec<FrameState> {
    let track = peaks::phase_track(&peaks.peaks, &peaks.troughs);
    let frame = peaks::nominal_period(t);
    let (idx, st, v) = samples_to_the_halt(t, z_rim, halt);
    // One independent local fit per frame: spread over the cores.
    idx.par_iter()
        .enumerate()
        .filter_map(|(k, &i)| {
            let t_c = st[k];
            if t_c < peaks.window.0 {
                return None;
            }
            let (Some((psi0, omega)), Some((phi0, phi_slope))) =
                (track.psi_at(t_c), track.phi_at(t_c))
            else {
                return None;
            };
            if !(omega > 0.0 && phi0 > 0.0) {
                return None;
            }
            let half = (0.5 * config.state_window_periods * 2.0 * PI / omega).max(3.5 * frame);
            // A window cut short by the clip's start is one-sided and its state an
            // extrapolation (a clip starting 0.5 s before the halt read φ 80 % high
            // over its first turn, with standard errors under 10 %).
            if t_c - half < st[0] - 0.5 * frame {
                return None;
            }
            // At least eight samples (four parameters, four degrees of freedom).
            let (lo, hi) = local::widened(
                st.partition_point(|&x| x < t_c - half),
                st.partition_point(|&x| x <= t_c + half),
                st.len(),
                8,
            );
            // Across a timestamp gap the phase track miscounts the turns (the peaks
            // inside it are missing): no state there.
            if skips::spans_gap(&t[idx[lo]..=idx[hi - 1]], frame, config.gap_factor) {
                return None;
            }
            let init = LocalInit {
                phi: phi0,
                phi_slope,
                chi: psi0,
                omega,
            };
            let fit = fit_local(
                model,
                &st[lo..hi],
                &v[lo..hi],
                t_c,
                init,
                Terms::CHIRP,
                None,
            )?;
            let psi = fit.chi + 2.0 * PI * ((psi0 - fit.chi) / (2.0 * PI)).round();
            Some(FrameState {
                index: i,
                t: t_c,
                phi: fit.phi,
                sigma_phi: fit.sigma_phi,
                psi,
                sigma_psi: fit.sigma_chi,
                psi_dot: fit.omega,
                sigma_psi_dot: fit.sigma_omega,
                residual_rms: (fit.ssr / fit.points as f64).sqrt(),
                points: fit.points,
            })
        })
        .collect()
}

/// Frame skips of every kind, sorted by frame: timestamp gaps over the whole clip;
/// strip-angle steps while the strip turns (if `strip` is given: β unwrapped and the
/// strip's stop t_β on the clip's time); rim phase
/// steps before the halt, where the peaks (found over the whole motion, not only the
/// window) give a phase track. A frame can carry several flags, one per reason.
pub fn frame_skips(
    t: &[f64],
    z_rim: &[f64],
    strip: Option<(&[f64], f64)>,
    halt: &Halt,
    model: &dyn RimModel,
    config: &SignalConfig,
) -> Result<Vec<FrameFlag>, SignalError> {
    check_series(t, z_rim, "z_rim")?;
    config.validate()?;
    let mut flags = timestamp_gaps(t, config.gap_factor);
    if let Some((beta, t_beta)) = strip {
        check_series(t, beta, "beta")?;
        flags.extend(strip_angle_steps(
            t,
            beta,
            t_beta,
            config.strip_step_sigmas,
            config.strip_step_floor,
        ));
    }
    let (all_peaks, all_troughs) = peaks::extrema(t, z_rim, halt, model, config, f64::NEG_INFINITY);
    let track = peaks::phase_track(&all_peaks, &all_troughs);
    flags.extend(skips::rim_phase_steps(
        t, z_rim, halt, model, &track, config,
    ));
    flags.sort_by_key(|f| f.index);
    Ok(flags)
}

/// The strip's side of a two-view clip.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StripAnalysis {
    /// β unwrapped, smoothed and differentiated.
    pub series: StripSeries,
    /// t_β by the band method.
    pub stop: StripStop,
    /// t_β − t_φ \[s\] (§3.3.3: 0.04 s on unlubricated stainless steel).
    pub rotation_after_flat: f64,
}

/// Everything the signal stage derives from one clip.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StateSeries {
    /// t_φ and the rest noise; `halt.shifted_t` is the time axis with the halt at 0.
    pub halt: Halt,
    /// Peaks, troughs, φ at peaks, ψ and ψ̇ in the window.
    pub peaks: PeakSeries,
    /// Per-frame φ, ψ, ψ̇ with standard errors in the window.
    pub states: Vec<FrameState>,
    /// β analysis, for two-view clips.
    pub strip: Option<StripAnalysis>,
    /// Frame-skip flags over the whole clip, timed with the halt at 0: frames missing
    /// beyond doubt ([`SkipReason::confirmed`]).
    pub flags: Vec<FrameFlag>,
    /// Rim phase steps the turns' timing does not confirm: reported, never counted
    /// as a frame missing from the capture clock.
    #[serde(default)]
    pub suspected_skips: Vec<FrameFlag>,
}

/// Runs the whole stage on one clip: `t` \[s\], `z_rim` \[m\] (NaN: no edge) and, for
/// two-view clips, `beta` \[rad\] in (−π/2, π/2] (NaN: no strip), frame by frame.
pub fn analyse(
    t: &[f64],
    z_rim: &[f64],
    beta: Option<&[f64]>,
    model: &dyn RimModel,
    config: &SignalConfig,
) -> Result<StateSeries, SignalError> {
    let halt = halt_time(t, z_rim, config)?;
    let peaks = find_peaks(t, z_rim, &halt, model, config)?;
    let states = frame_states(t, z_rim, &halt, &peaks, model, config);
    let strip = match beta {
        Some(beta) => {
            let series = strip_series(t, beta, config.smoothing_points)?;
            let settled_after = config
                .strip_settled_after
                .unwrap_or(t[t.len() - 1] - config.strip_settled_tail_s);
            // The strip stops after the rim's last motion seen, wherever t_φ lies.
            let stop = strip_stop_time(t, &series, t[halt.index], settled_after)?;
            let rotation_after_flat = stop.t_beta - halt.t_phi;
            Some(StripAnalysis {
                series,
                stop,
                rotation_after_flat,
            })
        }
        None => None,
    };
    let mut flags = frame_skips(
        t,
        z_rim,
        strip
            .as_ref()
            .map(|s| (s.series.beta.as_slice(), s.stop.t_beta)),
        &halt,
        model,
        config,
    )?;
    // One time base for everything returned: the halt at 0, as the peaks, states
    // and fit window are (flags were found on the caller's clip time).
    for flag in &mut flags {
        flag.t = halt.shifted_t[flag.index];
    }
    let (flags, suspected_skips) = flags.into_iter().partition(|f| f.reason.confirmed());
    Ok(StateSeries {
        halt,
        peaks,
        states,
        strip,
        flags,
        suspected_skips,
    })
}

/// The peaks and states of `series` (from [`analyse`] of `t`, `z_rim`) again, with
/// every rim height up to the halt's last frame of motion moved up by `shift` \[m\]: a
/// zero of z_rim that much lower, as an error of the edge at rest would make it. The
/// halt, strip and flags stay. How the energy fits respond to it is the zero's share
/// of their errors.
pub fn with_zero_moved(
    t: &[f64],
    z_rim: &[f64],
    series: &StateSeries,
    shift: f64,
    model: &dyn RimModel,
    config: &SignalConfig,
) -> Result<StateSeries, SignalError> {
    check_series(t, z_rim, "z_rim")?;
    let z: Vec<f64> = z_rim
        .iter()
        .enumerate()
        .map(|(i, &z)| if i <= series.halt.index { z + shift } else { z })
        .collect();
    let peaks = find_peaks(t, &z, &series.halt, model, config)?;
    let states = frame_states(t, &z, &series.halt, &peaks, model, config);
    Ok(StateSeries {
        peaks,
        states,
        ..series.clone()
    })
}

/// The samples the local fits take: those up to the halt with a rim height, as their
/// indices, their times from the halt \[s\] and their heights above the rest level \[m\].
fn samples_to_the_halt(t: &[f64], z_rim: &[f64], halt: &Halt) -> (Vec<usize>, Vec<f64>, Vec<f64>) {
    let idx: Vec<usize> = finite_samples(t, z_rim)
        .into_iter()
        .filter(|&i| i <= halt.index)
        .collect();
    let st = idx.iter().map(|&i| halt.shifted_t[i]).collect();
    let v = idx.iter().map(|&i| z_rim[i] - halt.rest_level).collect();
    (idx, st, v)
}

/// Checks that `t` and `values` pair up and that `t` is finite and increasing.
fn check_series(t: &[f64], values: &[f64], series: &'static str) -> Result<(), SignalError> {
    if t.len() != values.len() {
        return Err(SignalError::LengthMismatch {
            times: t.len(),
            values: values.len(),
            series,
        });
    }
    if t.len() < 2 {
        return Err(SignalError::TooShort { frames: t.len() });
    }
    if let Some(index) = t.iter().position(|x| !x.is_finite()) {
        return Err(SignalError::NonFiniteTime { index, t: t[index] });
    }
    if let Some(index) = (1..t.len()).find(|&i| t[i] <= t[i - 1]) {
        return Err(SignalError::TimesNotIncreasing {
            index,
            previous: t[index - 1],
            t: t[index],
        });
    }
    Ok(())
}

/// Indices of frames with a finite value.
fn finite_samples(t: &[f64], values: &[f64]) -> Vec<usize> {
    (0..t.len().min(values.len()))
        .filter(|&i| values[i].is_finite())
        .collect()
}
