//! Energy estimates and the energy power law (thesis §3.2.1–§3.2.5, §4.6).
//!
//! # Role in the data flow
//!
//! ```text
//! signal::  state series φ(t), ψ̇(t) (and, when known, φ̇, θ̇)
//!   │
//!   ▼  energy::
//!   │   stationary_rolling_energy  E from eq. (3.8), zero when the disk lies flat
//!   │   rolling_energy             E from eq. (3.6) (full rolling state), same zero
//!   │   fit_power_law / fit_window E = A_e (t0 − t)^n, eq. (1.2) = (3.2) = (4.93),
//!   │                              with standard errors and 95 % confidence intervals
//!   ▼
//! experiment result (report::), per-material statistics (stats::)
//! ```
//!
//! The stage is pure: slices in, numbers and a [`PowerLawFit`] out; it reads no files
//! and prints nothing.
//!
//! # The fit
//!
//! The power law is fitted by nonlinear least squares on E itself (not on log E, which
//! would weight the tiny energies next to the halt far too heavily), as the thesis does
//! in §3.2.5 and §4.6. The model is *separable*: A_e enters linearly, so for given
//! (n, t0) the best A_e is a closed-form projection. The search therefore runs over the
//! one or two nonlinear parameters only (n, and t0 when it is free) by variable
//! projection (Golub & Pereyra 1973), solved by the crate's Levenberg–Marquardt
//! ([`crate::numeric::lsq`]) with a trust radius on the parameters' steps.
//!
//! * t0 is searched as `t0 = t_last + T·e^s` (T the time span of the data), so every
//!   trial t0 lies strictly after the last sample and (t0 − t)^n stays defined.
//! * Starting values come from a linear fit of log E against log(t0 − t): directly for
//!   a fixed t0, and for a free t0 at each offset of a logarithmic grid, keeping the one
//!   whose power law has the smallest squared error on E.
//! * Iteration stops when the Bates–Watts relative offset (the distance to the minimum
//!   in standard errors) falls below 1e-10, or, at the floating-point limit, when steps
//!   shrink below 1e-12 (relative) or stop lowering the squared error while that offset
//!   is below 1e-6; or when the residual is rounding noise (exact data).
//! * With [`HaltTime::Sighted`], the halt seen in the footage is a second measurement
//!   of t0 ([`HaltSighting`]), combined with the free fit's on the energies' profile in
//!   t0 (fits with t0 held), unless the two disagree, or it disagrees with a third, the
//!   turns' end T ([`TurnsEnd`]).
//! * Standard errors allow for autocorrelated residuals, as measured energies have:
//!   one sample per turn at the peaks (a turn's calibration and edge errors linger
//!   into the next), and per frame 5–30 samples per turn, each a local fit over
//!   frames its neighbours share. The covariance is the sandwich
//!   (JᵀJ)⁻¹ Ω (JᵀJ)⁻¹ · N/(N − p), J the Jacobian of the model in (A_e, n[, t0]) and
//!   Ω the long-run covariance of the scores g_i = J_iᵀ r_i in time order, estimated
//!   from the residuals r themselves: prewhitened Newey–West (Andrews & Monahan
//!   1992) — an AR(1) filter e_i = g_i − ρ g_{i−1} with ρ ≥ 0 the residuals' lag-1
//!   autocorrelation, Bartlett weights w_l = 1 − |l|/S on what it leaves with S by
//!   Andrews' (1991) AR(1) plug-in, and Ω = Σ_l w_l Σ_i e_i e_{i+l}ᵀ / (1 − ρ)². The
//!   95 % intervals use the Student t quantile with dof = points − parameters plus
//!   the fixed-b correction of Kiefer & Vogelsang (2005) for b = S/N. For
//!   uncorrelated residuals ρ, S → 0 and this is the usual s² (JᵀJ)⁻¹ interval
//!   (White's form of it), kept for comparison as `se_n_uncorrelated`. On AR(1)
//!   residuals with ρ = 0.8 it covers the true n in 92–97 % of trials where that
//!   one covers 47 % (tested).
//! * A per-frame series ([`fit_window_in_turns`]) is not one sample a turn: a turn's
//!   frames share its local fits and its coded pictures, and so their errors, which
//!   the AR(1) filter over frames (one ρ for turns of 20 frames at the window's start
//!   and of 5 at its end) does not follow. So the covariance is also estimated with
//!   the residuals and scores summed over each turn (the frames between consecutive
//!   peaks), whose N, p and Student t then count turns: the analytic form of a block
//!   bootstrap over turns. The two see different correlations: the turns' sums a
//!   turn's shared errors, the frames a smooth error slower than a turn (a φ
//!   oscillating at 0.41 of the turn rate alternates in sign over the turns' sums), so
//!   the wider interval of n is kept. On `scripts/coverage 120` renders the per-frame
//!   fit's errors are 0.96 of its stated errors RMS (1.14 with the frames' covariance
//!   alone); on real-rim footage at four codings 0.83–1.08 (0.86–1.43 with the
//!   frames' alone; tested).
//! * t0's interval, with t0 free, is the wider of the sandwich's and the delete-a-block
//!   jackknife's ([`jackknife_se_t0`]: each turn, or each peak, left out in turn and
//!   the law fitted again). The final few samples, close together in time and
//!   small, fix t0 alone, and the fit bends through them, so their residuals
//!   understate their errors (their leverage, which the sandwich's N/(N − p) spreads
//!   over every sample). Left out one by one they show how much t0 rides on each,
//!   as HC3 does analytically (MacKinnon & White 1985). On a synthetic peaks series
//!   the sandwich's t0 interval covered the true halt in 72–80 % of trials, the
//!   jackknife's in 89–95 % (tested). It matters where the halt seen is combined
//!   ([`HaltSighting::fit`]): the free t0 is weighed by its variance. The free fit's
//!   n interval stays the sandwich's, which the coverage runs find honest; the
//!   combined fit's widens with t0's variance.

use crate::model::closed_form;
use crate::model::params::DiskParams;
use crate::numeric::lsq::{self, Limits, Problem};
use crate::numeric::minimise::{Stop, golden_section};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, StudentsT};
use thiserror::Error;

/// Energy under stationary rolling, thesis eq. (3.8) \[J\], measured from the flat rest
/// state (E − m g H), so it is zero when the disk lies flat (φ = 0):
///
/// E = C/2 (H/R ψ̇ sin φ)² + A/2 ψ̇² sin² φ + m g (R sin φ + H cos φ) − m g H.
///
/// It is eq. (3.6) with φ̇ = 0 and the stationary-rolling relation eq. (3.7),
/// R θ̇ = −ψ̇ (R cos φ − H sin φ): then θ̇ + ψ̇ cos φ = (H/R) ψ̇ sin φ, the centre of mass
/// is at rest and the translational term of eq. (3.6) vanishes.
///
/// `phi` is the nutation angle φ \[rad\], `psi_dot` the precession rate ψ̇ [rad/s].
pub fn stationary_rolling_energy(params: &DiskParams, phi: f64, psi_dot: f64) -> f64 {
    let spin_about_axis = params.half_thickness / params.radius * psi_dot * phi.sin();
    params.inertia_c / 2.0 * spin_about_axis * spin_about_axis
        + params.inertia_a / 2.0 * (psi_dot * phi.sin()).powi(2)
        + potential_above_flat(params, phi)
}

/// Energy of stationary rolling at nutation φ \[J\]: eq. (3.8) with the stationary
/// precession rate ψ̇(φ) of eq. (4.40) (the sense of ψ̇ does not change it). The error
/// is [`closed_form::stationary_rolling`]'s, where no stationary rolling exists.
pub fn stationary_energy_at(params: &DiskParams, phi: f64) -> Result<f64, String> {
    closed_form::stationary_rolling(params, phi)
        .map(|(psi_dot, _)| stationary_rolling_energy(params, phi, psi_dot))
}

/// Energy of the rolling disk in its full state, thesis eq. (3.6) \[J\], measured from
/// the flat rest state (minus m g H, as eq. 3.8):
///
/// E = φ̇²/2 (A + mH² + mR²) + C/2 (θ̇ + ψ̇ cos φ)² + m/2 (R(θ̇ + ψ̇ cos φ) − H ψ̇ sin φ)²
///     + A/2 ψ̇² sin² φ + m g (R sin φ + H cos φ) − m g H.
///
/// Rolling without slip is assumed (the contact point is at rest, eq. 3.5). Angles in
/// rad, rates in rad/s.
pub fn rolling_energy(
    params: &DiskParams,
    phi: f64,
    phi_dot: f64,
    psi_dot: f64,
    theta_dot: f64,
) -> f64 {
    let DiskParams {
        mass: m,
        radius: r,
        half_thickness: h,
        inertia_a: a,
        inertia_c: c,
        ..
    } = *params;
    let (sin_phi, cos_phi) = phi.sin_cos();
    let axial = theta_dot + psi_dot * cos_phi;
    let centre_speed = r * axial - h * psi_dot * sin_phi;
    phi_dot * phi_dot / 2.0 * (a + m * h * h + m * r * r)
        + c / 2.0 * axial * axial
        + m / 2.0 * centre_speed * centre_speed
        + a / 2.0 * (psi_dot * sin_phi).powi(2)
        + potential_above_flat(params, phi)
}

/// m g (R sin φ + H cos φ) − m g H, written with cos φ − 1 = −2 sin²(φ/2) so that it
/// keeps full relative precision as φ → 0, where the fit needs it most.
fn potential_above_flat(params: &DiskParams, phi: f64) -> f64 {
    let half = (phi / 2.0).sin();
    params.mass
        * params.gravity
        * (params.radius * phi.sin() - 2.0 * params.half_thickness * half * half)
}

/// The halt time t0 of the power law E = A_e (t0 − t)^n.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum HaltTime {
    /// t0 is known (e.g. the last frame with rim motion) and held fixed \[s\].
    Fixed(f64),
    /// t0 is fitted together with A_e and n (as in thesis §4.6).
    Free,
    /// t0 is fitted, and the halt seen in the footage is a second measurement of it
    /// ([`HaltSighting`]): the two are combined on the energies' profile in t0
    /// ([`HaltSighting::fit`]).
    Sighted(HaltSighting),
}

/// The halt as the footage shows it, a measurement of t0 beside the fit's own.
///
/// The last frame with rim motion is at t_last, and the disk stops at t0 after it. How
/// long after follows from the final turns and from how the halt detector
/// (`signal::halt`) reads them. Near the halt the rim's rise on the centre column is
/// z = h (1 + cos χ)/2, χ the precession phase from the rim's highest point, with
///
/// * its peak h = z_v (τ/Δ)^n (τ = t0 − t) falling with the energy, since
///   h ∝ φ ∝ E = A_e τ^n there (eq. 4.96): Δ = (E_v/A_e)^{1/n} is where the peak
///   falls to the least rise the detector sees, z_v, whose stationary-rolling energy
///   is E_v. The detector's threshold is a rise above the still disk's rest level,
///   and the energies' heights are measured from the zero the moving rim places
///   (`signal::motion_zero`), which an encoder can code below the rest (by 0.045 px,
///   half a 0.1 px threshold): z_v is the threshold plus the rest's height above
///   that zero ([`HaltSighting::visible_rise`]), and each drawn reading is the rim's
///   rise less that height;
/// * χ turning ever faster, ψ̇ = ψ̇_v (τ/Δ)^{−n/2}, as stationary rolling has
///   ψ̇² ∝ 1/φ at small φ (eq. 4.40; ψ̇_v at the tilt whose peak rise is z_v).
///
/// Where the frames fall within a frame interval of t0, and the phase at t0, are
/// unknown: over both, drawn uniformly, with the rest noise σ on every reading, the
/// detector is run back from t0 — the last frame rising more than z_v above rest,
/// then each later frame that continues its descent more than σ above rest, on
/// into the readings of the still disk after t0 while their noise keeps it up. Its
/// distance from t0 has a mean and a variance over [`SIGHTING_DRAWS`] draws; t0 =
/// t_last + that mean, with one frame² of variance more for where t_last itself falls
/// (exposure and the codec move the last moving frame by up to a frame either way).
/// With all motion visible (Δ → 0) this is t0 − t_last uniform over a frame. On 320 px
/// renders, whose final frames read the rim near contact or below z_v, it puts t0
/// 1–5 frames after t_last; on footage whose disk spans 900 px, within a frame or
/// two.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HaltSighting {
    /// t_last, the time of the last frame with rim motion \[s\].
    pub t_last: f64,
    /// The frame interval δt \[s\].
    pub frame_s: f64,
    /// Energy of stationary rolling at the smallest rim rise the footage shows
    /// ([`HaltSighting::visible_rise`]) \[J\].
    pub visible_energy: f64,
    /// The halt detector's threshold: the smallest rise of the rim above its rest
    /// that it takes for motion \[m\] (z_v when the rest level is the zero).
    #[serde(default)]
    pub threshold_m: f64,
    /// Noise σ of the rim at rest \[m\]: a frame continuing the rim's descent after a
    /// rise is motion while it stays more than σ above rest.
    #[serde(default)]
    pub noise_m: f64,
    /// ψ̇ of stationary rolling at the tilt whose peak rise is the visible rise
    /// [rad/s] (eq. 4.40).
    #[serde(default)]
    pub visible_precession: f64,
    /// How far the still disk's rest level lies above the zero the energies' heights
    /// are measured from \[m\]: −c of the zero the motion places (`signal::MotionZero`),
    /// 0 when the rest level is the zero. The detector counts rises above the rest,
    /// so a peak is seen when it reaches [`HaltSighting::visible_rise`] above the zero.
    #[serde(default)]
    pub rest_above_zero_m: f64,
    /// The end T of the turns' timing law on the same clock, a third measurement of
    /// t0 that the sighting must agree with to be combined; `None` when the turns
    /// could not be timed.
    #[serde(default)]
    pub turns_end: Option<TurnsEnd>,
}

/// The end T of the turns' timing law (`turn_timing::TurnTimingFit`), fitted to the
/// times of the turning points alone: a measurement of t0 that needs no height, so
/// that neither a codec's shaved swings nor its held pictures move it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TurnsEnd {
    /// T \[s\].
    pub t_end: f64,
    /// Its standard error \[s\] (the timing law's delete-a-block jackknife).
    pub se: f64,
}

/// Draws of the phase and frame offset at t0 over which a [`HaltSighting`] runs the
/// halt detector: the mean of t0 − t_last to about 1 % of a frame.
pub const SIGHTING_DRAWS: usize = 2000;
/// Frames before t0 within which a draw must find the last rise (beyond them the
/// final turns are far above any threshold).
const SIGHTING_FRAMES: usize = 400;
/// The least Δ the model is run with, as a fraction of a frame: Δ = 0 (all motion
/// visible) would make the peak infinite.
const LEAST_UNSEEN_FRAMES: f64 = 1e-3;

/// A sighting of the halt differing from the fit's t0 by more than this many standard
/// deviations of their difference is not combined: one of them is wrong (an encoder
/// holding a picture past the halt, or a last motion too small to see), and which is
/// not known.
pub const SIGHTING_DISAGREEMENT: f64 = 3.0;

/// How a [`HaltSighting`] entered the fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SightingUse {
    /// t0 as the sighting gives it, t_last plus the mean of t0 − t_last \[s\], for the Δ of
    /// the combined law (of the free fit's when not combined).
    pub t0_seen: f64,
    /// Its standard deviation \[s\].
    pub se_t0_seen: f64,
    /// Δ, the time before t0 over which the motion is too small to see \[s\], of the
    /// same law.
    pub unseen_s: f64,
    /// t0 from the energy alone \[s\].
    pub t0_fitted: f64,
    /// Standard error of `t0_fitted` \[s\].
    pub se_t0_fitted: f64,
    /// Whether it was combined: false when it and the fit's t0, or it and the turns'
    /// end T, differ by more than 3 standard deviations of their difference.
    pub combined: bool,
    /// The turns' end T it was checked against ([`HaltSighting::turns_end`]).
    #[serde(default)]
    pub turns_end: Option<TurnsEnd>,
    /// Not combined because it disagrees with the turns' end T.
    #[serde(default)]
    pub disagrees_with_turns: bool,
    /// The least rise above the heights' zero the detector sees
    /// ([`HaltSighting::visible_rise`]) \[m\].
    #[serde(default)]
    pub visible_rise_m: f64,
    /// The still disk's rest level above the heights' zero
    /// ([`HaltSighting::rest_above_zero_m`]) \[m\].
    #[serde(default)]
    pub rest_above_zero_m: f64,
}

/// Result of fitting E = A_e (t0 − t)^n, eq. (3.2)/(4.93), by least squares on E.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PowerLawFit {
    /// Multiplicative constant A_e [J s^-n].
    pub a_e: f64,
    /// Energy exponent n (dimensionless).
    pub n: f64,
    /// Halt time t0 \[s\], fitted or the fixed value.
    pub t0: f64,
    /// Standard error of A_e [J s^-n].
    pub se_a_e: f64,
    /// Standard error of n, allowing for the residuals' autocorrelation (module docs).
    pub se_n: f64,
    /// Standard error of n if the residuals were uncorrelated, √(s² (JᵀJ)⁻¹): with
    /// `se_n` it shows how much their measured autocorrelation widens the interval.
    #[serde(default)]
    pub se_n_uncorrelated: f64,
    /// Bartlett bandwidth S \[blocks\] of the prewhitened long-run covariance
    /// (Andrews' AR(1) plug-in; 0: nothing correlated left after the AR(1) filter).
    #[serde(default)]
    pub bandwidth: f64,
    /// Standard error of t0 \[s\]: the wider of the sandwich's and the jackknife's for a
    /// free t0 (module docs), the combination's for a sighted one; `None` when t0 was
    /// fixed.
    pub se_t0: Option<f64>,
    /// 95 % confidence interval of A_e [J s^-n].
    pub ci95_a_e: (f64, f64),
    /// Standard error of n from how well the zero of the measured heights is known:
    /// a systematic every sample shares, which the residuals cannot show (`analyse`
    /// refits with the zero moved by ± its uncertainty, [`PowerLawFit::with_zero_error`]);
    /// 0 when not assessed.
    #[serde(default)]
    pub se_n_zero: f64,
    /// 95 % confidence interval of n: the statistical half-width (Student t, from
    /// `se_n`) and the zero's (normal, from `se_n_zero`) added in quadrature.
    pub ci95_n: (f64, f64),
    /// 95 % confidence interval of t0 \[s\]; `None` when t0 was fixed.
    pub ci95_t0: Option<(f64, f64)>,
    /// The halt seen in the footage as a second measurement of t0, when given.
    #[serde(default)]
    pub halt_sighting: Option<SightingUse>,
    /// Coefficient of determination 1 − SSR/SST on E.
    pub r_squared: f64,
    /// Root-mean-square residual √(SSR/points) \[J\].
    pub residual_rms: f64,
    /// Number of samples fitted.
    pub points: usize,
    /// Blocks the covariance was estimated over: the turns of a per-frame series
    /// where they gave the wider interval of n ([`fit_window_in_turns`]), else the
    /// samples. The intervals' Student t has blocks − parameters degrees of freedom.
    #[serde(default)]
    pub blocks: usize,
    /// Degrees of freedom: points − fitted parameters (2 or 3).
    pub dof: usize,
    /// Levenberg–Marquardt iterations used.
    pub iterations: usize,
}

impl PowerLawFit {
    /// The fit with `se_zero`, the standard error of n from the zero of the measured
    /// heights, in its interval of n: half-width √(h² + (1.96 se_zero)²), h the
    /// statistical half-width (replacing an earlier zero error, not adding to it).
    pub fn with_zero_error(mut self, se_zero: f64) -> Self {
        let z = 1.959_963_984_540_054;
        let half = 0.5 * (self.ci95_n.1 - self.ci95_n.0);
        let statistical = (half * half - (z * self.se_n_zero).powi(2)).max(0.0);
        let half = (statistical + (z * se_zero).powi(2)).sqrt();
        self.se_n_zero = se_zero;
        self.ci95_n = (self.n - half, self.n + half);
        self
    }

    /// The fitted energy A_e (t0 − t)^n at time `t` \[J\]; zero at and after the halt.
    pub fn energy_at(&self, t: f64) -> f64 {
        if t < self.t0 {
            self.a_e * (self.t0 - t).powf(self.n)
        } else {
            0.0
        }
    }
}

/// Why a power-law fit could not be made.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum FitError {
    /// Fewer samples than fitted parameters plus one (no error estimate possible).
    #[error(
        "the power-law fit needs at least {needed} energy samples (one more than its \
         parameters, to estimate the scatter), got {got}"
    )]
    TooFewPoints { needed: usize, got: usize },
    /// The time and energy series differ in length.
    #[error("{times} times but {energies} energies: the series must pair up sample by sample")]
    LengthMismatch { times: usize, energies: usize },
    /// A time or energy is NaN or infinite.
    #[error("sample {index} is not a finite number (t = {t} s, E = {energy} J)")]
    NonFinite { index: usize, t: f64, energy: f64 },
    /// An energy is zero or negative: the disk is flat, so the sample is at or after
    /// the halt, where the power law does not apply.
    #[error(
        "sample {index} at t = {t} s has energy {energy} J ≤ 0: the disk is flat there, so \
         it lies at or after the halt; fit only samples before the halt"
    )]
    NonPositiveEnergy { index: usize, t: f64, energy: f64 },
    /// The fixed halt time is not finite.
    #[error("the halt time t0 = {t0} s is not a finite number")]
    InvalidHaltTime { t0: f64 },
    /// A sample lies at or after the fixed halt time.
    #[error(
        "sample {index} at t = {t} s is not before the halt t0 = {t0} s; the power law holds \
         only before the halt (a fit window drops later samples)"
    )]
    SampleAtOrAfterHalt { index: usize, t: f64, t0: f64 },
    /// The fit window is not a positive duration.
    #[error("the fit window must be a positive number of seconds, got {window_s}")]
    InvalidWindow { window_s: f64 },
    /// The least-squares search did not settle.
    #[error(
        "the power-law fit did not converge after {iterations} iterations (last estimate \
         n = {n}, t0 = {t0} s); the energy may not follow a power law in this window: try a \
         shorter window before the halt, or fix t0 at the observed stop"
    )]
    NotConverged { iterations: usize, n: f64, t0: f64 },
    /// With t0 free, the least-squares halt falls on or before the last sample, where
    /// E = A_e (t0 − t)^n cannot reach: the search runs into the bound t0 > t_last.
    #[error(
        "with t0 free, the best fit puts the halt at or before the last sample \
         (t = {t_last} s; n ≈ {n}), where the power law cannot follow: the final samples \
         fall faster than any power law that ends after them. Fix t0 at the observed stop \
         instead of fitting it, or end the window earlier"
    )]
    HaltAtLastSample { t_last: f64, n: f64 },
    /// The data cannot determine the parameters.
    #[error("the data cannot determine the power law: {reason}")]
    Degenerate { reason: String },
}

impl FitError {
    fn degenerate(reason: &str) -> Self {
        FitError::Degenerate {
            reason: reason.to_owned(),
        }
    }

    /// Translates sample indices of a selection back to the caller's series.
    fn reindex(self, selected: &[usize]) -> Self {
        let map = |index: usize| selected.get(index).copied().unwrap_or(index);
        match self {
            FitError::NonFinite { index, t, energy } => FitError::NonFinite {
                index: map(index),
                t,
                energy,
            },
            FitError::NonPositiveEnergy { index, t, energy } => FitError::NonPositiveEnergy {
                index: map(index),
                t,
                energy,
            },
            FitError::SampleAtOrAfterHalt { index, t, t0 } => FitError::SampleAtOrAfterHalt {
                index: map(index),
                t,
                t0,
            },
            other => other,
        }
    }
}

/// Fits E = A_e (t0 − t)^n, eq. (3.2)/(4.93), to samples (`t` \[s\], `energy` \[J\]) by
/// nonlinear least squares on E, with t0 fixed or free (see the module docs for the
/// method). Every sample must be finite, have E > 0 and, for a fixed t0, lie before t0.
/// Times need not be sorted.
pub fn fit_power_law(t: &[f64], energy: &[f64], t0: HaltTime) -> Result<PowerLawFit, FitError> {
    fit_in_turns(t, energy, t0, &[])
}

/// [`fit_power_law`] with the covariance estimated over turns: the samples between
/// consecutive `turns` (times \[s\], sorted: the peaks) form one block (module docs).
fn fit_in_turns(
    t: &[f64],
    energy: &[f64],
    t0: HaltTime,
    turns: &[f64],
) -> Result<PowerLawFit, FitError> {
    match t0 {
        HaltTime::Sighted(sighting) => sighting.fit(t, energy, turns),
        HaltTime::Free => fit_free(t, energy, turns),
        HaltTime::Fixed(_) => fit_with_limit(t, energy, t0, MAX_ITERATIONS, turns),
    }
}

/// The fit with t0 free, t0's standard error and interval the wider of the sandwich's
/// and the delete-a-block jackknife's ([`jackknife_se_t0`], module docs).
fn fit_free(t: &[f64], energy: &[f64], turns: &[f64]) -> Result<PowerLawFit, FitError> {
    let mut fit = fit_with_limit(t, energy, HaltTime::Free, MAX_ITERATIONS, turns)?;
    if let (Some(se), Some((lo, hi)), Some(jackknife)) =
        (fit.se_t0, fit.ci95_t0, jackknife_se_t0(t, energy, turns))
        && jackknife > se
    {
        let widen = jackknife / se;
        fit.se_t0 = Some(jackknife);
        fit.ci95_t0 = Some((
            fit.t0 - widen * (fit.t0 - lo),
            fit.t0 + widen * (hi - fit.t0),
        ));
    }
    Ok(fit)
}

/// The delete-a-block jackknife's standard error of a free fit's t0,
/// √((g − 1)/g · Σ (t0₍ᵢ₎ − t̄0)²) over the g blocks left out in turn: the turns between
/// consecutive `turns` where the samples span at least [`LEAST_TURN_BLOCKS`] of them;
/// otherwise each sample, or, beyond [`JACKKNIFE_BLOCKS`] samples, that many runs of
/// consecutive samples in time. A leave-out whose fit fails (its t0 pinned onto its
/// last sample) is not counted; `None` when more than one fails, or with fewer than
/// four blocks.
fn jackknife_se_t0(t: &[f64], energy: &[f64], turns: &[f64]) -> Option<f64> {
    let turn: Vec<usize> = t
        .iter()
        .map(|&ti| turns.partition_point(|&start| start <= ti))
        .collect();
    let spanned = turn.iter().max()? - turn.iter().min()? + 1;
    let block = if spanned >= LEAST_TURN_BLOCKS {
        turn
    } else {
        let mut by_time: Vec<usize> = (0..t.len()).collect();
        by_time.sort_by(|&i, &j| t[i].total_cmp(&t[j]));
        let mut run = vec![0; t.len()];
        for (rank, &i) in by_time.iter().enumerate() {
            run[i] = rank * JACKKNIFE_BLOCKS.min(t.len()) / t.len();
        }
        run
    };
    let mut labels = block.clone();
    labels.sort_unstable();
    labels.dedup();
    if labels.len() < 4 {
        return None;
    }
    let t0s: Vec<f64> = labels
        .iter()
        .filter_map(|&left_out| {
            let (ts, es): (Vec<f64>, Vec<f64>) = (0..t.len())
                .filter(|&i| block[i] != left_out)
                .map(|i| (t[i], energy[i]))
                .unzip();
            // t0 alone is wanted, which does not depend on the covariance's blocks.
            fit_with_limit(&ts, &es, HaltTime::Free, MAX_ITERATIONS, &[])
                .ok()
                .map(|fit| fit.t0)
        })
        .collect();
    if t0s.len() + 1 < labels.len() {
        return None;
    }
    let g = t0s.len() as f64;
    let mean = t0s.iter().sum::<f64>() / g;
    let spread: f64 = t0s.iter().map(|t0| (t0 - mean).powi(2)).sum();
    Some(((g - 1.0) / g * spread).sqrt())
}

/// Fits the power law to the samples within `window_s` seconds before the halt: before
/// the fixed t0 (samples at or after it are dropped), or, for a free t0, up to and
/// including the last sample. The thesis fits the final 0.5 s (§3.2.4). Error indices
/// refer to the full series.
pub fn fit_window(
    t: &[f64],
    energy: &[f64],
    window_s: f64,
    t0: HaltTime,
) -> Result<PowerLawFit, FitError> {
    fit_window_in_turns(t, energy, window_s, t0, &[])
}

/// [`fit_window`] for samples that are not one a turn (per frame): the covariance is
/// estimated over the samples and over the turns that `turns` (the peaks' times \[s\],
/// sorted) separate, and the one with the wider interval of n kept, as the module
/// docs say; with fewer than [`LEAST_TURN_BLOCKS`] turns in the window, or none
/// given, over the samples only.
pub fn fit_window_in_turns(
    t: &[f64],
    energy: &[f64],
    window_s: f64,
    t0: HaltTime,
    turns: &[f64],
) -> Result<PowerLawFit, FitError> {
    if t.len() != energy.len() {
        return Err(FitError::LengthMismatch {
            times: t.len(),
            energies: energy.len(),
        });
    }
    if !(window_s.is_finite() && window_s > 0.0) {
        return Err(FitError::InvalidWindow { window_s });
    }
    if let Some(index) = t.iter().position(|x| !x.is_finite()) {
        return Err(FitError::NonFinite {
            index,
            t: t[index],
            energy: energy[index],
        });
    }
    let end = match t0 {
        HaltTime::Fixed(t0) if !t0.is_finite() => return Err(FitError::InvalidHaltTime { t0 }),
        HaltTime::Fixed(t0) => t0,
        HaltTime::Free | HaltTime::Sighted(_) => {
            t.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        }
    };
    let start = end - window_s;
    let selected: Vec<usize> = (0..t.len())
        .filter(|&i| {
            t[i] >= start
                && match t0 {
                    HaltTime::Fixed(_) => t[i] < end,
                    HaltTime::Free | HaltTime::Sighted(_) => t[i] <= end,
                }
        })
        .collect();
    let ts: Vec<f64> = selected.iter().map(|&i| t[i]).collect();
    let es: Vec<f64> = selected.iter().map(|&i| energy[i]).collect();
    fit_in_turns(&ts, &es, t0, turns).map_err(|e| e.reindex(&selected))
}

/// Fits the power law over each window in `windows` \[s\] (see [`fit_window_in_turns`],
/// `turns` as there), to show how the exponent depends on the window (ERRATA:
/// pivoting friction gives n ≈ 2.21 or 2.13 depending on it).
pub fn window_sensitivity(
    t: &[f64],
    energy: &[f64],
    windows: &[f64],
    t0: HaltTime,
    turns: &[f64],
) -> Vec<(f64, Result<PowerLawFit, FitError>)> {
    windows
        .iter()
        .map(|&w| (w, fit_window_in_turns(t, energy, w, t0, turns)))
        .collect()
}

/// Iteration limit of the Levenberg–Marquardt search.
const MAX_ITERATIONS: usize = 200;
/// Largest change of n, and of ln(t0 − t_last), in one step (initial trust radius).
const MAX_STEP: f64 = 2.0;
/// t0 − t_last beyond e^20 ≈ 5e8 data spans: t0 has run off to infinity (the data
/// decay exponentially rather than as a power law).
const MAX_LOG_OFFSET: f64 = 20.0;
/// A free-t0 search that reaches t0 − t_last below this many data spans (0.5 ns for a
/// 0.5 s window, far below any frame interval) has run into the bound t0 > t_last.
const PINNED_OFFSET: f64 = 1e-9;
/// Most blocks [`jackknife_se_t0`] leaves out in turn when no turns are given: a
/// peaks series (one sample a turn, 20–40 in the final 0.5 s) is left out sample by
/// sample, a longer series in this many runs of consecutive samples.
const JACKKNIFE_BLOCKS: usize = 40;
/// Fewest turns a per-frame series must span for its covariance to be estimated over
/// them as well ([`fit_window_in_turns`]): below it the blocks are too few to show how
/// the turns' sums vary, and the samples alone are used.
pub const LEAST_TURN_BLOCKS: usize = 8;
/// Grid of log10((t0 − t_last)/T) tried for the starting value of a free t0: 1e-7 … 10.
const LOG10_OFFSET_GRID: (f64, f64, usize) = (-7.0, 1.0, 33);

/// The 95 % intervals' quantile: Student's t at `dof` degrees of freedom plus the
/// fixed-b correction for a Bartlett `bandwidth` over `points` samples (module docs).
fn interval_quantile(dof: usize, bandwidth: f64, points: usize) -> Result<f64, FitError> {
    Ok(StudentsT::new(0.0, 1.0, dof as f64)
        .map_err(|_| {
            FitError::degenerate("no Student t distribution for these degrees of freedom")
        })?
        .inverse_cdf(0.975)
        + fixed_b_excess(bandwidth / points as f64))
}

/// The least-squares power law of [`fit_power_law`] with the search stopped after
/// `max_iterations`, its covariance estimated over the samples and, where they span
/// [`LEAST_TURN_BLOCKS`] of the `turns`, over those too (module docs).
fn fit_with_limit(
    t: &[f64],
    energy: &[f64],
    halt: HaltTime,
    max_iterations: usize,
    turns: &[f64],
) -> Result<PowerLawFit, FitError> {
    let parameters = check_samples(t, energy, halt)?;
    let free = parameters == 3;
    let scaled = ScaledSeries::new(t, energy, halt)?;
    let solution = scaled.solve(max_iterations)?;
    let (n, points) = (solution.n, scaled.tail.len());
    let jac = scaled.jacobian(&solution);
    let dof = points - parameters;
    let ssr_scaled = solution.outcome.ssr;
    let s2 = ssr_scaled / dof as f64;
    let bread = inverse_normal_matrix(&jac)?;
    let residuals = &solution.outcome.residuals;
    let long_run = LongRun::over_samples_or_turns(t, &scaled.tail, residuals, &jac, &bread, turns)?;
    let se_n_uncorrelated = (bread[(1, 1)] * s2).sqrt();
    let a_e = scaled.e_scale * solution.amp * scaled.span.powf(-n);
    let se = scaled.standard_errors(&long_run.cov_scaled, a_e, n)?;
    let (t0, quantile) = (solution.t0, long_run.quantile);
    let ci = |value: f64, se: f64| (value - quantile * se, value + quantile * se);
    let ssr = ssr_scaled * scaled.e_scale * scaled.e_scale;
    Ok(PowerLawFit {
        a_e,
        n,
        t0,
        se_a_e: se[0],
        se_n: se[1],
        se_n_uncorrelated,
        bandwidth: long_run.bandwidth,
        se_t0: free.then(|| se[2]),
        ci95_a_e: ci(a_e, se[0]),
        se_n_zero: 0.0,
        ci95_n: ci(n, se[1]),
        ci95_t0: free.then(|| ci(t0, se[2])),
        halt_sighting: None,
        r_squared: 1.0 - ssr / scaled.sst,
        residual_rms: (ssr / points as f64).sqrt(),
        points,
        blocks: long_run.blocks,
        dof,
        iterations: solution.outcome.iterations,
    })
}

/// The number of parameters of the fit (A_e and n, and t0 unless `halt` fixes it),
/// once the samples are fit to give them: as many times as energies, more samples
/// than parameters, a finite fixed t0, and every sample finite, with E > 0 and, for a
/// fixed t0, before it.
fn check_samples(t: &[f64], energy: &[f64], halt: HaltTime) -> Result<usize, FitError> {
    if t.len() != energy.len() {
        return Err(FitError::LengthMismatch {
            times: t.len(),
            energies: energy.len(),
        });
    }
    let parameters = if matches!(halt, HaltTime::Fixed(_)) {
        2
    } else {
        3
    };
    if t.len() < parameters + 1 {
        return Err(FitError::TooFewPoints {
            needed: parameters + 1,
            got: t.len(),
        });
    }
    if let HaltTime::Fixed(t0) = halt
        && !t0.is_finite()
    {
        return Err(FitError::InvalidHaltTime { t0 });
    }
    for (index, (&ti, &ei)) in t.iter().zip(energy).enumerate() {
        if !(ti.is_finite() && ei.is_finite()) {
            return Err(FitError::NonFinite {
                index,
                t: ti,
                energy: ei,
            });
        }
        if ei <= 0.0 {
            return Err(FitError::NonPositiveEnergy {
                index,
                t: ti,
                energy: ei,
            });
        }
        if let HaltTime::Fixed(t0) = halt
            && ti >= t0
        {
            return Err(FitError::SampleAtOrAfterHalt { index, t: ti, t0 });
        }
    }
    Ok(parameters)
}

/// The samples in the units of the search: time in units of the data span T,
/// measured back from the last sample; energy in units of its root mean square. Then
/// y = a u^n with u = (t0 − t)/T = tail + d, d = (t0 − t_last)/T, and
/// E = e_scale · a · (τ/T)^n.
struct ScaledSeries {
    /// The last sample's time \[s\].
    t_last: f64,
    /// The data span T \[s\].
    span: f64,
    /// The energies' root mean square \[J\].
    e_scale: f64,
    /// Σ (E − mean E)², for R² \[J²\].
    sst: f64,
    /// (t_last − t)/T of each sample.
    tail: Vec<f64>,
    /// E/e_scale of each sample.
    y: DVector<f64>,
    /// d, or free.
    offset: Offset,
}

/// The solution of the scaled problem.
struct Solution {
    /// The exponent n.
    n: f64,
    /// d = (t0 − t_last)/T.
    d: f64,
    /// t0 \[s\].
    t0: f64,
    /// a of y = a u^n.
    amp: f64,
    /// The search's outcome (residuals, ssr, iterations).
    outcome: lsq::LsqFit,
}

impl ScaledSeries {
    /// The scaled samples; an error if they span no time or the energy does not vary.
    fn new(t: &[f64], energy: &[f64], halt: HaltTime) -> Result<Self, FitError> {
        let t_last = t.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let t_first = t.iter().copied().fold(f64::INFINITY, f64::min);
        let span = t_last - t_first;
        // The samples are finite here, so the span is too.
        if span <= 0.0 {
            return Err(FitError::degenerate(
                "all samples are at the same time, so there is no decay to fit",
            ));
        }
        let points = t.len();
        let mean_energy = energy.iter().sum::<f64>() / points as f64;
        let sst: f64 = energy.iter().map(|e| (e - mean_energy).powi(2)).sum();
        if energy.iter().all(|&e| e == energy[0]) {
            return Err(FitError::degenerate(
                "the energy is the same in every sample, so it does not decay",
            ));
        }
        let e_scale = (energy.iter().map(|e| e * e).sum::<f64>() / points as f64).sqrt();
        Ok(ScaledSeries {
            t_last,
            span,
            e_scale,
            sst,
            tail: t.iter().map(|ti| (t_last - ti) / span).collect(),
            y: DVector::from_iterator(points, energy.iter().map(|e| e / e_scale)),
            offset: match halt {
                HaltTime::Fixed(t0) => Offset::Fixed((t0 - t_last) / span),
                HaltTime::Free | HaltTime::Sighted(_) => Offset::Free,
            },
        })
    }

    /// Whether t0 is a parameter of the fit.
    fn free(&self) -> bool {
        matches!(self.offset, Offset::Free)
    }

    /// The Levenberg–Marquardt search of the projected problem from its starting
    /// values, with the amplitude rescaled from (u/u_max)^n to u^n. Errors: t0 pinned
    /// to the last sample, no convergence, or no positive finite amplitude.
    fn solve(&self, max_iterations: usize) -> Result<Solution, FitError> {
        let problem = Projection {
            tail: &self.tail,
            y: &self.y,
            offset: self.offset,
        };
        let start = problem.starting_values();
        let limits = Limits {
            max_iterations,
            max_step: MAX_STEP,
        };
        let outcome = lsq::minimise(&problem, start, limits).ok_or_else(|| {
            FitError::degenerate(
                "the starting power law is not finite (energies span too many decades)",
            )
        })?;
        let p = &outcome.params;
        let n = p[0];
        let d = problem.offset(p.as_slice());
        let t0 = self.t_last + d * self.span;
        if self.free() && d < PINNED_OFFSET {
            return Err(FitError::HaltAtLastSample {
                t_last: self.t_last,
                n,
            });
        }
        if !outcome.converged {
            return Err(FitError::NotConverged {
                iterations: outcome.iterations,
                n,
                t0,
            });
        }
        let amp = problem.amplitude(p.as_slice()) * (1.0 + d).powf(-n);
        if !(amp.is_finite() && amp > 0.0) {
            return Err(FitError::degenerate(
                "the fitted amplitude is not a positive finite number",
            ));
        }
        Ok(Solution {
            n,
            d,
            t0,
            amp,
            outcome,
        })
    }

    /// The Jacobian of y = a u^n at the solution with respect to the scaled
    /// parameters (a, n[, d]), one row a sample.
    fn jacobian(&self, solution: &Solution) -> DMatrix<f64> {
        let Solution { n, d, amp, .. } = *solution;
        let parameters = if self.free() { 3 } else { 2 };
        let mut jac = DMatrix::zeros(self.tail.len(), parameters);
        for (i, tail) in self.tail.iter().enumerate() {
            let u = tail + d;
            let f = u.powf(n);
            jac[(i, 0)] = f;
            jac[(i, 1)] = amp * f * u.ln();
            if self.free() {
                jac[(i, 2)] = amp * n * f / u;
            }
        }
        jac
    }

    /// The standard errors of (A_e, n[, t0]), mapped from the covariance `cov_scaled`
    /// of (a, n[, d]) by their Jacobian at A_e = `a_e` and `n`; an error if one is not
    /// finite (the parameters are not separately determined).
    fn standard_errors(
        &self,
        cov_scaled: &DMatrix<f64>,
        a_e: f64,
        n: f64,
    ) -> Result<Vec<f64>, FitError> {
        let parameters = cov_scaled.nrows();
        let mut g = DMatrix::zeros(parameters, parameters);
        g[(0, 0)] = self.e_scale * self.span.powf(-n);
        g[(0, 1)] = -a_e * self.span.ln();
        g[(1, 1)] = 1.0;
        if self.free() {
            g[(2, 2)] = self.span;
        }
        let cov = &g * cov_scaled * g.transpose();
        let se: Vec<f64> = (0..parameters).map(|j| cov[(j, j)].sqrt()).collect();
        if se.iter().any(|s| !s.is_finite()) {
            return Err(FitError::degenerate(
                "the parameter covariance is not finite (the parameters are not separately determined)",
            ));
        }
        Ok(se)
    }
}

/// A prewhitened Newey–West covariance of the fit's scaled parameters, estimated over
/// blocks of consecutive samples (each sample alone, or the turns), with the Student t
/// quantile of its 95 % intervals.
struct LongRun {
    /// Covariance of the scaled parameters (a, n[, d]).
    cov_scaled: DMatrix<f64>,
    /// Bartlett bandwidth S \[blocks\].
    bandwidth: f64,
    /// Blocks the residuals and scores were summed over.
    blocks: usize,
    /// Student t quantile with the fixed-b correction, blocks − parameters dof.
    quantile: f64,
}

impl LongRun {
    /// The covariance over the samples, and where the series spans
    /// [`LEAST_TURN_BLOCKS`] of the `turns` (the peaks' times \[s\]), over those too,
    /// the one with the wider interval of n kept (module docs). The residuals and
    /// scores g_i = J_iᵀ r_i are summed in time order: by the samples' `tail`, the
    /// scaled time back from the last one, with `t` their times \[s\].
    fn over_samples_or_turns(
        t: &[f64],
        tail: &[f64],
        residuals: &DVector<f64>,
        jac: &DMatrix<f64>,
        bread: &DMatrix<f64>,
        turns: &[f64],
    ) -> Result<Self, FitError> {
        let (points, parameters) = jac.shape();
        let mut by_time: Vec<usize> = (0..points).collect();
        by_time.sort_by(|&i, &j| tail[j].total_cmp(&tail[i]));
        let resid: Vec<f64> = by_time.iter().map(|&i| residuals[i]).collect();
        let scores: Vec<DVector<f64>> = by_time
            .iter()
            .map(|&i| jac.row(i).transpose() * residuals[i])
            .collect();
        let each_sample: Vec<usize> = (0..points).collect();
        let over_samples = Self::over_blocks(bread, &resid, &scores, &each_sample, parameters)?;
        let turn: Vec<usize> = by_time
            .iter()
            .map(|&i| turns.partition_point(|&start| start <= t[i]))
            .collect();
        if turn[points - 1] - turn[0] + 1 >= LEAST_TURN_BLOCKS {
            let over_turns = Self::over_blocks(bread, &resid, &scores, &turn, parameters)?;
            if over_turns.half_width_n() > over_samples.half_width_n() {
                return Ok(over_turns);
            }
        }
        Ok(over_samples)
    }

    /// The covariance from residuals `resid` and scores g_i = J_iᵀ r_i in time order,
    /// summed over runs of equal `block` (a label per sample), with `bread` = (JᵀJ)⁻¹.
    fn over_blocks(
        bread: &DMatrix<f64>,
        resid: &[f64],
        scores: &[DVector<f64>],
        block: &[usize],
        parameters: usize,
    ) -> Result<Self, FitError> {
        let (mut r_sums, mut g_sums) = (Vec::<f64>::new(), Vec::<DVector<f64>>::new());
        for (k, (r, g)) in resid.iter().zip(scores).enumerate() {
            match (r_sums.last_mut(), g_sums.last_mut()) {
                (Some(r_sum), Some(g_sum)) if block[k - 1] == block[k] => {
                    *r_sum += r;
                    *g_sum += g;
                }
                _ => {
                    r_sums.push(*r);
                    g_sums.push(g.clone());
                }
            }
        }
        let blocks = r_sums.len();
        // Prewhitened (Andrews & Monahan 1992): an AR(1) filter with the residuals'
        // lag-1 autocorrelation ρ, Newey–West on what it leaves, recoloured by
        // 1/(1 − ρ)². ρ < 0 would narrow the interval below the plain one; over the
        // ~20–40 samples of a peaks series ρ̂ is biased low by about (1 + 3ρ)/N, so a
        // negative one is not trusted.
        let rho = lag1_autocorrelation(&r_sums).max(0.0);
        let whitened: Vec<f64> = r_sums.windows(2).map(|w| w[1] - rho * w[0]).collect();
        let bandwidth = bartlett_bandwidth(&whitened);
        let innovations: Vec<DVector<f64>> =
            g_sums.windows(2).map(|w| &w[1] - &w[0] * rho).collect();
        let meat = long_run_covariance(&innovations, bandwidth) / (1.0 - rho).powi(2);
        let dof = blocks - parameters;
        Ok(Self {
            cov_scaled: bread * meat * bread * (blocks as f64 / dof as f64),
            bandwidth,
            blocks,
            quantile: interval_quantile(dof, bandwidth, blocks)?,
        })
    }

    /// Half-width of the 95 % interval of n (scaled n is n itself).
    fn half_width_n(&self) -> f64 {
        self.quantile * self.cov_scaled[(1, 1)].sqrt()
    }
}

impl HaltSighting {
    /// The least peak rise above the energies' zero the detector sees, z_v \[m\]: its
    /// threshold above the rest level plus the rest level's height above the zero, at
    /// least the rest noise σ (a rise smaller than the noise is no rise).
    pub fn visible_rise(&self) -> f64 {
        (self.threshold_m + self.rest_above_zero_m).max(self.noise_m)
    }

    /// Mean and variance of t0 − t_last [s, s²] (the model of the type's docs) for the
    /// time `unseen_s` (Δ) over which the peak rise is below the visible rise
    /// ([`Self::visible_rise`]) and the fitted exponent `n`. Draws are seeded, so the
    /// same inputs give the same numbers.
    pub fn gap(&self, unseen_s: f64, n: f64) -> (f64, f64) {
        let dt = self.frame_s;
        let unseen = unseen_s.max(LEAST_UNSEEN_FRAMES * dt);
        // χ(τ) = χ0 + ∫ψ̇ dτ = χ0 + ψ̇_v Δ^{n/2} τ^{1−n/2}/(1 − n/2); for n ≥ 2 the
        // turns before t0 are unbounded and each frame's phase is its own draw.
        let power = 1.0 - 0.5 * n;
        let turning = self.visible_precession * unseen.powf(0.5 * n) / power;
        let visible_rise = self.visible_rise();
        let mut rng = crate::rng::SplitMix64::new(0x5157_4854);
        let mut readings = Vec::with_capacity(SIGHTING_FRAMES);
        let (mut sum, mut sum_sq, mut draws) = (0.0, 0.0, 0usize);
        for _ in 0..SIGHTING_DRAWS {
            let offset = dt * rng.uniform();
            let phase = std::f64::consts::TAU * rng.uniform();
            readings.clear();
            // Frames back from t0 (k = 0 the last before it) up to the last rise.
            let last_rise = (0..SIGHTING_FRAMES).find(|&k| {
                let tau = offset + k as f64 * dt;
                let chi = if power > 0.0 {
                    phase + turning * tau.powf(power)
                } else {
                    std::f64::consts::TAU * rng.uniform()
                };
                // The reading above the rest level, as the detector takes it.
                let peak = visible_rise * (tau / unseen).powf(n);
                let z = 0.5 * peak * (1.0 + chi.cos()) - self.rest_above_zero_m
                    + self.noise_m * rng.gaussian();
                readings.push(z);
                z > self.threshold_m
            });
            let Some(mut last) = last_rise else { continue };
            // The descent after it, towards t0, and on into the readings after t0
            // (rest, with its noise) while they keep falling more than σ above rest.
            while last > 0
                && readings[last - 1] < readings[last]
                && readings[last - 1] > self.noise_m
            {
                last -= 1;
            }
            let mut after = 0.0;
            if last == 0 {
                let mut previous = readings[0];
                loop {
                    let z = self.noise_m * rng.gaussian();
                    if !(z < previous && z > self.noise_m) {
                        break;
                    }
                    (previous, after) = (z, after + 1.0);
                }
            }
            let gap = offset + (last as f64 - after) * dt;
            sum += gap;
            sum_sq += gap * gap;
            draws += 1;
        }
        if draws == 0 {
            // No rise within SIGHTING_FRAMES: Δ spans them all, and t0 − t_last is
            // taken uniform over δt + Δ.
            let width = dt + unseen_s;
            return (0.5 * width, width * width / 12.0 + dt * dt);
        }
        let mean = sum / draws as f64;
        (
            mean,
            (sum_sq / draws as f64 - mean * mean).max(0.0) + dt * dt,
        )
    }

    /// Fits the power law with t0 measured twice: by the energies (the free-t0 fit)
    /// and by this sighting. The two are combined on the energies' profile in t0, not
    /// on a straight line through the free fit: for each trial t0 the law is fitted
    /// with t0 held (A_e(t0), n(t0), its squared residual S(t0)), and the combined t0
    /// minimises
    ///
    /// ```text
    /// Q(t0) = (S(t0) − S_free)/k + (t0 − t_seen(t0))²/σ_seen²(t0),
    /// ```
    ///
    /// k scaling the profile so that its curvature at the free fit gives the free
    /// fit's own σ_t0 (the wider of the sandwich's and the jackknife's, module docs),
    /// t_seen = t_last + the mean of t0 − t_last and σ_seen² its variance
    /// ([`HaltSighting::gap`]), both for the Δ = (E_v/A_e)^{1/n} of the law at that t0.
    /// Where the energies fix t0 well, Q is two parabolas and this is the
    /// covariance-weighted mean of two Gaussian measurements. Where they barely fix it
    /// (a free t0 tens of ms after the last sample, as a codec's shrunken final swings
    /// give), n is the law's at the combined t0, where a straight line through the
    /// free fit would carry it over the curve's whole span, and Δ is the combined
    /// law's, so the sighting does not follow the fit it checks.
    ///
    /// n and A_e are the held fit's at the minimum, their variances its own plus
    /// (∂n/∂t0)² var t0 (the law of total variance), var t0 = 1/(1/var_S + 1/σ_seen²)
    /// with var_S = 2k/S″ there. Not combined, and the free fit returned, when the
    /// sighting at the free fit's law and the free t0 differ by more than
    /// [`SIGHTING_DISAGREEMENT`] standard deviations of their difference: one of them
    /// is wrong (an encoder holding a picture past the halt, or a last motion too
    /// small to see), and which is not known. Nor when it and the turns' end T
    /// ([`Self::turns_end`]) differ by as much: T, fitted to the times of every turn of
    /// the window, is a third measurement, and a sighting that two others do not both
    /// bear out is not used. Held pictures end the motion seen early: with I and P
    /// pictures at a coarse quantiser the sighting can put t0 13–22 ms early while T
    /// lies within 2.3 ms of the truth, and a combination that followed the sighting
    /// would move n by −0.06.
    fn fit(&self, t: &[f64], energy: &[f64], turns: &[f64]) -> Result<PowerLawFit, FitError> {
        let free = fit_free(t, energy, turns)?;
        let profile = HeldProfile::new(t, energy, turns, &free);
        let used = self.use_at_free_fit(&free);
        let unchanged = |used: SightingUse| {
            Ok(PowerLawFit {
                halt_sighting: Some(used),
                ..free.clone()
            })
        };
        if let Some(refused) = self.refused(&free, used) {
            return unchanged(refused);
        }
        let Some(k) = profile.scale() else {
            return unchanged(used);
        };
        let Some(combined) = self.combine(&profile, k, &used) else {
            return unchanged(used);
        };
        let Some((se_a_e, se_n, se_t0)) = profile.spread(&combined, k) else {
            return unchanged(used);
        };
        // The free fit's quantile: its degrees of freedom and bandwidth.
        let quantile = interval_quantile(free.blocks - 3, free.bandwidth, free.blocks)?;
        let ci = |value: f64, se: f64| (value - quantile * se, value + quantile * se);
        let Combined { t0, fit, .. } = combined;
        Ok(PowerLawFit {
            a_e: fit.a_e,
            n: fit.n,
            t0,
            se_a_e,
            se_n,
            se_t0: Some(se_t0),
            ci95_a_e: ci(fit.a_e, se_a_e),
            ci95_n: ci(fit.n, se_n),
            ci95_t0: Some(ci(t0, se_t0)),
            halt_sighting: Some(SightingUse {
                t0_seen: combined.seen,
                se_t0_seen: combined.var_seen.sqrt(),
                unseen_s: combined.unseen_s,
                combined: true,
                ..used
            }),
            r_squared: fit.r_squared,
            residual_rms: fit.residual_rms,
            ..free
        })
    }

    /// The sighting at the free fit's law, as reported when the two are not combined.
    fn use_at_free_fit(&self, free: &PowerLawFit) -> SightingUse {
        let (t0_seen, var, unseen_s) = self.seen_at(free.a_e, free.n);
        SightingUse {
            t0_seen,
            se_t0_seen: var.sqrt(),
            unseen_s,
            t0_fitted: free.t0,
            se_t0_fitted: free.se_t0.unwrap_or(f64::NAN),
            combined: false,
            turns_end: self.turns_end,
            disagrees_with_turns: false,
            visible_rise_m: self.visible_rise(),
            rest_above_zero_m: self.rest_above_zero_m,
        }
    }

    /// The sighting `used`, as reported, when it is not to be combined: two
    /// measurements more than [`SIGHTING_DISAGREEMENT`] standard deviations of their
    /// difference apart are not (the sighting at the free fit's law and the free
    /// fit's σ_t0); nor when it and the turns' end T are as far apart, as the
    /// sighting rests on the last frames, which a held picture ends early, T on every
    /// turn's time. `None` when it is to be combined.
    fn refused(&self, free: &PowerLawFit, used: SightingUse) -> Option<SightingUse> {
        let se_t0_free = free.se_t0.unwrap_or(f64::NAN);
        if (used.t0_seen - free.t0).abs()
            > SIGHTING_DISAGREEMENT * se_t0_free.hypot(used.se_t0_seen)
        {
            return Some(used);
        }
        if let Some(turns) = self.turns_end
            && (used.t0_seen - turns.t_end).abs()
                > SIGHTING_DISAGREEMENT * turns.se.hypot(used.se_t0_seen)
        {
            return Some(SightingUse {
                disagrees_with_turns: true,
                ..used
            });
        }
        None
    }

    /// The t0 that minimises Q (the profile's rise over `k` plus the sighting's
    /// squared distance over its variance), searched over both measurements and four
    /// standard deviations beyond, after the last sample by at least
    /// [`LEAST_UNSEEN_FRAMES`] frames; with the held fit and the sighting there.
    fn combine(&self, profile: &HeldProfile, k: f64, used: &SightingUse) -> Option<Combined> {
        let free = profile.free;
        let q = |t0: f64| -> Option<(f64, PowerLawFit, (f64, f64, f64))> {
            let fit = profile.held(t0)?;
            let seen = self.seen_at(fit.a_e, fit.n);
            let value = (squared_residual(&fit) - squared_residual(free)) / k
                + (t0 - seen.0).powi(2) / seen.1;
            value.is_finite().then_some((value, fit, seen))
        };
        let reach = 4.0 * profile.se_t0_free.hypot(used.se_t0_seen);
        let lowest = profile.t_last + LEAST_UNSEEN_FRAMES * self.frame_s;
        let low = (free.t0.min(used.t0_seen) - reach).max(lowest);
        let high = free.t0.max(used.t0_seen) + reach;
        let t0 = minimise(|x| q(x).map_or(f64::INFINITY, |v| v.0), low, high)?;
        let (_, fit, (seen, var_seen, unseen_s)) = q(t0)?;
        Some(Combined {
            t0,
            fit,
            seen,
            var_seen,
            unseen_s,
        })
    }

    /// The sighting for the law E = A_e (t0 − t)^n: t0 as seen (t_last plus the mean of
    /// t0 − t_last), its variance, and Δ ([`Self::gap`], [`Self::unseen`]).
    fn seen_at(&self, a_e: f64, n: f64) -> (f64, f64, f64) {
        let unseen_s = self.unseen(a_e, n);
        let (mean, var) = self.gap(unseen_s, n);
        (self.t_last + mean, var, unseen_s)
    }

    /// Δ = (E_v/A_e)^{1/n}, the time before t0 over which the law E = A_e (t0 − t)^n
    /// lies below the visible energy E_v \[s\]; 0 without one.
    fn unseen(&self, a_e: f64, n: f64) -> f64 {
        if self.visible_energy > 0.0 && self.visible_energy.is_finite() && n > 0.0 && a_e > 0.0 {
            (self.visible_energy / a_e).powf(1.0 / n)
        } else {
            0.0
        }
    }
}

/// The squared residual S of a fit.
fn squared_residual(fit: &PowerLawFit) -> f64 {
    fit.residual_rms.powi(2) * fit.points as f64
}

/// The energies' profile in t0 ([`HaltSighting::fit`]): the law fitted with t0 held,
/// beside the free fit.
struct HeldProfile<'a> {
    t: &'a [f64],
    energy: &'a [f64],
    turns: &'a [f64],
    /// The fit with t0 free.
    free: &'a PowerLawFit,
    /// Its σ_t0 (NaN if none) \[s\].
    se_t0_free: f64,
    /// The last sample's time \[s\].
    t_last: f64,
}

/// The combined t0 and what holds there.
struct Combined {
    /// The combined t0 \[s\].
    t0: f64,
    /// The fit with t0 held there.
    fit: PowerLawFit,
    /// t0 as the sighting gives it for that fit's law, and its variance \[s, s²\].
    seen: f64,
    var_seen: f64,
    /// Δ for that law \[s\].
    unseen_s: f64,
}

impl<'a> HeldProfile<'a> {
    fn new(t: &'a [f64], energy: &'a [f64], turns: &'a [f64], free: &'a PowerLawFit) -> Self {
        HeldProfile {
            t,
            energy,
            turns,
            free,
            se_t0_free: free.se_t0.unwrap_or(f64::NAN),
            t_last: t.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }

    /// The law fitted with t0 held, if the fit succeeds.
    fn held(&self, t0: f64) -> Option<PowerLawFit> {
        fit_with_limit(
            self.t,
            self.energy,
            HaltTime::Fixed(t0),
            MAX_ITERATIONS,
            self.turns,
        )
        .ok()
    }

    /// k: the profile's mean rise one σ_t0 either side of the free t0 (the later side
    /// alone where the earlier reaches the last sample), so that the profile's
    /// curvature there gives the free fit's σ_t0; `None` unless positive and finite.
    fn scale(&self) -> Option<f64> {
        let (free, se) = (self.free, self.se_t0_free);
        let rise = |t0: f64| {
            self.held(t0)
                .map(|f| squared_residual(&f) - squared_residual(free))
        };
        let k = match (
            rise(free.t0 + se),
            (free.t0 - se > self.t_last)
                .then(|| rise(free.t0 - se))
                .flatten(),
        ) {
            (Some(later), Some(earlier)) => 0.5 * (later + earlier),
            (Some(later), None) => later,
            _ => f64::NAN,
        };
        (k.is_finite() && k > 0.0).then_some(k)
    }

    /// The standard errors of A_e, n and t0 at the combined t0: var t0 =
    /// 1/(1/var_S + 1/σ_seen²) with var_S = 2k/S″, and A_e's and n's variances the
    /// held fit's plus their slope in t0 squared times var t0 (the law of total
    /// variance). S″ and the slopes by central differences a tenth of the free σ_t0
    /// (or of the room left) apart; `None` if a held fit there fails.
    fn spread(&self, combined: &Combined, k: f64) -> Option<(f64, f64, f64)> {
        let Combined { t0, ref fit, .. } = *combined;
        let h = (0.1 * self.se_t0_free).min(0.5 * (t0 - self.t_last));
        let (before, after) = (self.held(t0 - h)?, self.held(t0 + h)?);
        let curvature = (squared_residual(&after) - 2.0 * squared_residual(fit)
            + squared_residual(&before))
            / (h * h);
        let var_profile = if curvature > 0.0 {
            2.0 * k / curvature
        } else {
            f64::INFINITY
        };
        let var_t0 = 1.0 / (1.0 / var_profile + 1.0 / combined.var_seen);
        let slope_n = (after.n - before.n) / (2.0 * h);
        let slope_a = (after.a_e - before.a_e) / (2.0 * h);
        let se_n = (fit.se_n.powi(2) + slope_n.powi(2) * var_t0).sqrt();
        let se_a_e = (fit.se_a_e.powi(2) + slope_a.powi(2) * var_t0).sqrt();
        Some((se_a_e, se_n, var_t0.sqrt()))
    }
}

/// Grid points over which [`minimise`] looks for the lowest before refining.
const SEARCH_GRID: usize = 24;
/// Golden-section steps of [`minimise`]'s refinement: the bracket shrinks by
/// 0.618^30 ≈ 5e-7 of its two grid steps.
const GOLDEN_STEPS: usize = 30;

/// The x in [low, high] where `f` is lowest: the lowest of [`SEARCH_GRID`] evenly
/// spaced points, refined by golden-section search between its neighbours. `None`
/// when `f` is infinite at every grid point.
fn minimise(f: impl Fn(f64) -> f64, low: f64, high: f64) -> Option<f64> {
    let step = (high - low) / (SEARCH_GRID - 1) as f64;
    let grid: Vec<f64> = (0..SEARCH_GRID).map(|i| low + step * i as f64).collect();
    let values: Vec<f64> = grid.iter().map(|&x| f(x)).collect();
    let best = (0..SEARCH_GRID)
        .filter(|&i| values[i].is_finite())
        .min_by(|&i, &j| values[i].total_cmp(&values[j]))?;
    let (a, b) = (
        grid[best.saturating_sub(1)],
        grid[(best + 1).min(SEARCH_GRID - 1)],
    );
    let x = golden_section(&f, a, b, Stop::Steps(GOLDEN_STEPS)).midpoint();
    Some(if f(x) <= values[best] { x } else { grid[best] })
}

/// Largest lag-1 autocorrelation used for the bandwidth: ρ → 1 would make it
/// infinite (the series then holds about one independent sample anyway).
const MAX_RHO: f64 = 0.98;

/// Lag-1 autocorrelation of `r` (mean zero: residuals), at most MAX_RHO; 0 for a
/// zero series.
fn lag1_autocorrelation(r: &[f64]) -> f64 {
    let var: f64 = r.iter().map(|x| x * x).sum();
    if !(var.is_finite() && var > 0.0) {
        return 0.0;
    }
    let lag1: f64 = r.windows(2).map(|w| w[0] * w[1]).sum();
    (lag1 / var).min(MAX_RHO)
}

/// Andrews' (1991) automatic bandwidth of the Bartlett kernel for residuals `r` in
/// time order, from an AR(1) model of them: S = 1.1447 (α N)^⅓ with
/// α = 4ρ² / (1 − ρ²)², ρ their lag-1 autocorrelation (0 if negative), at most N.
fn bartlett_bandwidth(r: &[f64]) -> f64 {
    let rho = lag1_autocorrelation(r).max(0.0);
    let alpha = 4.0 * rho * rho / (1.0 - rho * rho).powi(2);
    (1.1447 * (alpha * r.len() as f64).cbrt()).min(r.len() as f64)
}

/// Newey–West long-run covariance Σ_l w_l Γ_l of the scores g_i = J_iᵀ r_i (in time
/// order), with Bartlett weights w_l = 1 − |l|/S for |l| < S; S = 0 gives White's
/// Σ g_i g_iᵀ.
fn long_run_covariance(scores: &[DVector<f64>], bandwidth: f64) -> DMatrix<f64> {
    let k = scores.first().map_or(0, |g| g.len());
    let mut sum = DMatrix::zeros(k, k);
    for (lag, weight) in (0..scores.len())
        .map(|l| (l, 1.0 - l as f64 / bandwidth.max(1.0)))
        .take_while(|&(_, w)| w > 0.0)
    {
        let mut gamma = DMatrix::zeros(k, k);
        for (a, b) in scores.iter().zip(&scores[lag..]) {
            gamma += a * b.transpose();
        }
        sum += if lag == 0 {
            gamma
        } else {
            (&gamma + gamma.transpose()) * weight
        };
    }
    sum
}

/// How far the 97.5 % critical value of a t ratio with a Bartlett long-run variance
/// of bandwidth b = S/N lies beyond the normal one under fixed-b asymptotics
/// (Kiefer & Vogelsang 2005, Table 1 fit: 1.96 + 2.9694 b + 0.4160 b² − 0.5324 b³),
/// for the uncertainty of the estimated long-run variance itself.
fn fixed_b_excess(b: f64) -> f64 {
    let b = b.clamp(0.0, 1.0);
    2.9694 * b + 0.4160 * b * b - 0.5324 * b * b * b
}

/// (JᵀJ)⁻¹ by a singular-value decomposition of J with unit-norm columns, which keeps
/// the strongly correlated n and t0 of a free-t0 fit accurate.
fn inverse_normal_matrix(jac: &DMatrix<f64>) -> Result<DMatrix<f64>, FitError> {
    let norms: Vec<f64> = jac.column_iter().map(|c| c.norm()).collect();
    if norms.iter().any(|&c| !(c.is_finite() && c > 0.0)) {
        return Err(FitError::degenerate(
            "a parameter has no effect on the fitted energy",
        ));
    }
    let mut scaled = jac.clone();
    for (j, &norm) in norms.iter().enumerate() {
        scaled.column_mut(j).scale_mut(1.0 / norm);
    }
    let svd = scaled.svd(false, true);
    let v_t = svd
        .v_t
        .ok_or_else(|| FitError::degenerate("the singular-value decomposition failed"))?;
    let sigma = &svd.singular_values;
    let (lo, hi) = (sigma.min(), sigma.max());
    if lo.is_nan() || lo <= 1e-13 * hi {
        return Err(FitError::degenerate(
            "A_e, n and t0 are not separately determined by these samples (singular \
             covariance); fix t0 or use a longer window",
        ));
    }
    let k = norms.len();
    let mut inv = DMatrix::zeros(k, k);
    for r in 0..k {
        for c in 0..k {
            let mut sum = 0.0;
            for s in 0..k {
                sum += v_t[(s, r)] * v_t[(s, c)] / (sigma[s] * sigma[s]);
            }
            inv[(r, c)] = sum / (norms[r] * norms[c]);
        }
    }
    Ok(inv)
}

/// How t0 enters the scaled problem: d = (t0 − t_last)/T, fixed or d = e^s with s the
/// second nonlinear parameter.
#[derive(Clone, Copy)]
enum Offset {
    Fixed(f64),
    Free,
}

/// The variable-projection form of y ≈ a u^n, u = tail + d: for given nonlinear
/// parameters p = (n) or (n, s = ln d), the linear amplitude a is eliminated by its
/// least-squares value a = fᵀy / fᵀf, f ∝ u^n.
struct Projection<'a> {
    tail: &'a [f64],
    y: &'a DVector<f64>,
    offset: Offset,
}

/// The projected problem evaluated at one p.
struct Evaluation {
    /// Optimal linear amplitude a at p.
    amp: f64,
    /// Residual r = y − a f.
    resid: DVector<f64>,
    /// ‖r‖².
    ssr: f64,
    /// ∂r/∂p (Golub–Pereyra, exact).
    jac: DMatrix<f64>,
}

impl Projection<'_> {
    fn nonlinear_parameters(&self) -> usize {
        match self.offset {
            Offset::Fixed(_) => 1,
            Offset::Free => 2,
        }
    }

    fn offset(&self, p: &[f64]) -> f64 {
        match self.offset {
            Offset::Fixed(d) => d,
            Offset::Free => p[1].exp(),
        }
    }

    /// Projected residual and its Jacobian at p; `None` where the model is not finite.
    ///
    /// With r(p) = y − a(p) f(p) and a = fᵀy/fᵀf, differentiating gives, for each
    /// nonlinear parameter with g = ∂f/∂p_j,
    /// ∂r/∂p_j = −a (g − f fᵀg/fᵀf) − f (gᵀr)/fᵀf.
    ///
    /// r depends on f only through its direction, so f is taken as (u/u_max)^n with
    /// u_max = 1 + d (so f ≤ 1: no overflow when t0 wanders far); then ∂f/∂n = f ln(u/u_max)
    /// and ∂f/∂s = n f (d/u − d/u_max). The returned `amp` refers to this f.
    fn evaluate(&self, p: &[f64]) -> Option<Evaluation> {
        let m = self.tail.len();
        let k = self.nonlinear_parameters();
        let n = p[0];
        let d = self.offset(p);
        let u_max = 1.0 + d;
        let mut f = DVector::zeros(m);
        let mut df = DMatrix::zeros(m, k);
        for (i, &tail) in self.tail.iter().enumerate() {
            let u = tail + d;
            if u.is_nan() || u <= 0.0 {
                return None;
            }
            let fi = (u / u_max).powf(n);
            f[i] = fi;
            df[(i, 0)] = fi * (u / u_max).ln();
            if k == 2 {
                df[(i, 1)] = n * fi * (d / u - d / u_max);
            }
        }
        let ff = f.norm_squared();
        if !(ff.is_finite() && ff > 0.0) {
            return None;
        }
        let amp = f.dot(self.y) / ff;
        let resid = self.y - &f * amp;
        let mut jac = DMatrix::zeros(m, k);
        for j in 0..k {
            let g = df.column(j);
            let fg = f.dot(&g);
            let gr = g.dot(&resid);
            for i in 0..m {
                jac[(i, j)] = -amp * (g[i] - f[i] * fg / ff) - f[i] * gr / ff;
            }
        }
        let ssr = resid.norm_squared();
        (amp.is_finite() && ssr.is_finite() && jac.iter().all(|x| x.is_finite())).then_some(
            Evaluation {
                amp,
                resid,
                ssr,
                jac,
            },
        )
    }

    /// The slope of log y against log u: the exponent of the power law through the data
    /// on log–log axes for a given offset d.
    fn log_log_exponent(&self, d: f64) -> f64 {
        let m = self.tail.len() as f64;
        let xs: Vec<f64> = self.tail.iter().map(|t| (t + d).ln()).collect();
        let ys: Vec<f64> = self.y.iter().map(|y| y.ln()).collect();
        let (xm, ym) = (xs.iter().sum::<f64>() / m, ys.iter().sum::<f64>() / m);
        let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - xm) * (y - ym)).sum();
        let sxx: f64 = xs.iter().map(|x| (x - xm) * (x - xm)).sum();
        sxy / sxx
    }

    /// Starting p: the log–log exponent at the fixed offset, or, for a free t0, the
    /// grid offset whose log–log power law has the smallest squared error on y.
    fn starting_values(&self) -> DVector<f64> {
        match self.offset {
            Offset::Fixed(d) => DVector::from_vec(vec![self.log_log_exponent(d)]),
            Offset::Free => {
                let (lo, hi, count) = LOG10_OFFSET_GRID;
                let mut best: Option<(f64, DVector<f64>)> = None;
                for step in 0..count {
                    let d = 10f64.powf(lo + (hi - lo) * step as f64 / (count - 1) as f64);
                    let p = DVector::from_vec(vec![self.log_log_exponent(d), d.ln()]);
                    if let Some(eval) = self.evaluate(p.as_slice())
                        && best.as_ref().is_none_or(|(ssr, _)| eval.ssr < *ssr)
                    {
                        best = Some((eval.ssr, p));
                    }
                }
                // Every grid point non-finite only for pathological data; the search then
                // starts from n = 1 and d = 1e-3, and reports what it finds.
                best.map_or_else(|| DVector::from_vec(vec![1.0, (1e-3f64).ln()]), |(_, p)| p)
            }
        }
    }

    /// The optimal linear amplitude a at p (for f = (u/u_max)^n); NaN where the model
    /// is not finite.
    fn amplitude(&self, p: &[f64]) -> f64 {
        self.evaluate(p).map_or(f64::NAN, |eval| eval.amp)
    }
}

/// The projected residual for the crate's solver: one linear parameter (a)
/// eliminated; n's step scaled by 1 + |n|, ln d's absolutely; t0 off limits when it
/// runs off to infinity or onto the bound t0 > t_last (the caller reports which).
impl Problem for Projection<'_> {
    fn residual_count(&self) -> usize {
        self.tail.len()
    }

    fn residuals(&self, p: &[f64], r: &mut [f64]) -> bool {
        self.evaluate(p)
            .map(|eval| r.copy_from_slice(eval.resid.as_slice()))
            .is_some()
    }

    fn jacobian(&self, p: &[f64], jac: &mut DMatrix<f64>) {
        if let Some(eval) = self.evaluate(p) {
            jac.copy_from(&eval.jac);
        }
    }

    fn eliminated(&self) -> usize {
        1
    }

    fn step_scale(&self, p: &[f64], j: usize) -> f64 {
        if j == 0 { 1.0 + p[0].abs() } else { 1.0 }
    }

    fn off_limits(&self, p: &[f64]) -> bool {
        matches!(self.offset, Offset::Free) && (p[1] > MAX_LOG_OFFSET || p[1] < PINNED_OFFSET.ln())
    }

    /// Below this the residual is rounding noise: the data are an exact power law.
    fn rounding_ssr(&self) -> f64 {
        (16.0 * f64::EPSILON).powi(2) * self.y.norm_squared()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::params::Preset;
    use crate::rng::SplitMix64;
    use nalgebra::Vector3;

    const PRESETS: [Preset; 3] = [Preset::EulerDisk, Preset::BrassDisk, Preset::FoodCan];
    const EXPONENTS: [f64; 4] = [0.45, 0.5, 2.0 / 3.0, 2.2];

    /// Eq. (3.4) computed from its vectors: V_G from eq. (3.5), Ω = (ψ̇ sin φ, −φ̇,
    /// ψ̇ cos φ + θ̇), I = diag(A, A, C); minus m g H.
    fn energy_eq_3_4(
        p: &DiskParams,
        phi: f64,
        phi_dot: f64,
        psi: f64,
        psi_dot: f64,
        theta_dot: f64,
    ) -> f64 {
        let v = centre_of_mass_velocity(p, phi, phi_dot, psi, psi_dot, theta_dot);
        let omega = Vector3::new(
            psi_dot * phi.sin(),
            -phi_dot,
            psi_dot * phi.cos() + theta_dot,
        );
        let i_omega = Vector3::new(
            p.inertia_a * omega.x,
            p.inertia_a * omega.y,
            p.inertia_c * omega.z,
        );
        p.mass * v.dot(&v) / 2.0
            + i_omega.dot(&omega) / 2.0
            + p.mass * p.gravity * (p.radius * phi.sin() + p.half_thickness * phi.cos())
            - p.mass * p.gravity * p.half_thickness
    }

    /// Eq. (3.5): velocity of the centre of mass of the rolling disk.
    fn centre_of_mass_velocity(
        p: &DiskParams,
        phi: f64,
        phi_dot: f64,
        psi: f64,
        psi_dot: f64,
        theta_dot: f64,
    ) -> Vector3<f64> {
        let (r, h) = (p.radius, p.half_thickness);
        let (s, c) = phi.sin_cos();
        let lever = r * s + h * c;
        let roll = psi_dot * (r * c - h * s) + r * theta_dot;
        Vector3::new(
            -phi_dot * psi.cos() * lever - psi.sin() * roll,
            -phi_dot * psi.sin() * lever + psi.cos() * roll,
            phi_dot * (r * c - h * s),
        )
    }

    /// Eq. (3.7) solved for θ̇: θ̇ = −ψ̇ (R cos φ − H sin φ)/R.
    fn stationary_theta_dot(p: &DiskParams, phi: f64, psi_dot: f64) -> f64 {
        -psi_dot * (p.radius * phi.cos() - p.half_thickness * phi.sin()) / p.radius
    }

    fn relative_error(value: f64, truth: f64) -> f64 {
        (value - truth).abs() / truth.abs()
    }

    #[test]
    fn flat_disk_has_zero_energy() {
        for preset in PRESETS {
            let p = preset.params();
            for psi_dot in [0.0, -0.23, 50.0, 3000.0] {
                assert_eq!(stationary_rolling_energy(&p, 0.0, psi_dot), 0.0);
                assert_eq!(rolling_energy(&p, 0.0, 0.0, psi_dot, -psi_dot), 0.0);
            }
        }
    }

    /// Eq. (3.6) is eq. (3.4) with eq. (3.5) substituted, for any rolling state.
    #[test]
    fn eq_3_6_equals_eq_3_4_at_random_states() {
        let mut rng = SplitMix64::new(36);
        for preset in PRESETS {
            let p = preset.params();
            for _ in 0..1000 {
                let phi = rng.range(0.0, 1.5);
                let (phi_dot, psi) = (rng.range(-20.0, 20.0), rng.range(-10.0, 10.0));
                let (psi_dot, theta_dot) = (rng.range(-300.0, 300.0), rng.range(-300.0, 300.0));
                let direct = energy_eq_3_4(&p, phi, phi_dot, psi, psi_dot, theta_dot);
                let reduced = rolling_energy(&p, phi, phi_dot, psi_dot, theta_dot);
                // Both sum the same positive terms; rounding only.
                assert!(
                    relative_error(reduced, direct) < 1e-12,
                    "{reduced} vs {direct}"
                );
            }
        }
    }

    /// Eq. (3.7) with φ̇ = 0 puts the centre of mass at rest (eq. 3.5), which is what
    /// "stationary rolling" means.
    #[test]
    fn stationary_rolling_keeps_the_centre_of_mass_still() {
        let mut rng = SplitMix64::new(37);
        let p = Preset::EulerDisk.params();
        for _ in 0..1000 {
            let (phi, psi, psi_dot) = (
                rng.range(0.0, 1.5),
                rng.range(-10.0, 10.0),
                rng.range(-300.0, 300.0),
            );
            let theta_dot = stationary_theta_dot(&p, phi, psi_dot);
            let v = centre_of_mass_velocity(&p, phi, 0.0, psi, psi_dot, theta_dot);
            // The rim speed is R|θ̇| ≤ 0.04 × 300 m/s; cancellation leaves rounding.
            assert!(v.norm() < 1e-12, "|V_G| = {}", v.norm());
        }
    }

    /// Eq. (3.8) is eq. (3.6) − mgH under stationary rolling: θ̇ from eq. (3.7), φ̇ = 0.
    /// Derivation: θ̇ + ψ̇ cos φ = ψ̇ (H/R) sin φ, so the C term becomes C/2 (H/R ψ̇ sin φ)²
    /// and R(θ̇ + ψ̇ cos φ) − H ψ̇ sin φ = 0 removes the translational term.
    #[test]
    fn eq_3_8_equals_eq_3_6_under_stationary_rolling() {
        let mut rng = SplitMix64::new(38);
        for preset in PRESETS {
            let p = preset.params();
            for _ in 0..1000 {
                let phi = rng.range(1e-6, 1.5);
                let psi_dot = rng.range(-300.0, 300.0);
                let theta_dot = stationary_theta_dot(&p, phi, psi_dot);
                let general = rolling_energy(&p, phi, 0.0, psi_dot, theta_dot);
                let direct = energy_eq_3_4(&p, phi, 0.0, 0.3, psi_dot, theta_dot);
                let stationary = stationary_rolling_energy(&p, phi, psi_dot);
                // The translational term cancels to rounding of R θ̇ (~1e-16 of 12 m/s).
                assert!(
                    relative_error(stationary, general) < 1e-10,
                    "{stationary} vs {general}"
                );
                assert!(
                    relative_error(stationary, direct) < 1e-10,
                    "{stationary} vs {direct}"
                );
            }
        }
    }

    /// Thesis eq. (4.96): on the stationary-rolling manifold, ψ̇² from eq. (4.40), the
    /// scaled energy E/(mgR) → (c h² + 3a)/(2a) φ as φ → 0. Eq. (4.40) prints
    /// `a sin φ cos φ + c h sin² φ` in the denominator; model::dynamics derives `−`. The
    /// term is O(φ) relative, so the limit holds with either sign; both are checked.
    #[test]
    fn small_angle_energy_matches_eq_4_96() {
        for preset in PRESETS {
            let p = preset.params();
            let (a, c, h) = (p.a(), p.c(), p.h());
            let slope = (c * h * h + 3.0 * a) / (2.0 * a);
            for sign in [1.0, -1.0] {
                for phi in [1e-4, 1e-5, 1e-6] {
                    let (s, co) = (f64::sin(phi), f64::cos(phi));
                    let psi_dot_sq = (co - h * s) / (a * s * co + sign * c * h * s * s);
                    let psi_dot = psi_dot_sq.sqrt() / p.time_unit();
                    let scaled = stationary_rolling_energy(&p, phi, psi_dot) / p.energy_unit();
                    // The next order is O(φ²): a relative error of O(φ), whose factor
                    // is 1.9 at most (the food can, h = 1.47, printed sign).
                    assert!(
                        relative_error(scaled, slope * phi) < 3.0 * phi,
                        "{preset:?} φ = {phi}, sign {sign}"
                    );
                }
            }
        }
    }

    /// Thesis-like sampling (§3.2.4): 480 fps over the last 0.5 s, last frame 1/480 s
    /// before the halt, A_e = 0.0063 J s^-n (fig. 3.14), t0 = 3.096 s.
    fn thesis_series(n: f64) -> (Vec<f64>, Vec<f64>, f64, f64) {
        let (a_e, t0) = (0.0063, 3.096);
        let t: Vec<f64> = (1..=240).rev().map(|k| t0 - k as f64 / 480.0).collect();
        let e = t.iter().map(|ti| a_e * (t0 - ti).powf(n)).collect();
        (t, e, a_e, t0)
    }

    #[test]
    fn exact_power_law_recovered_with_fixed_t0() {
        for n in EXPONENTS {
            let (t, e, a_e, t0) = thesis_series(n);
            let fit = fit_power_law(&t, &e, HaltTime::Fixed(t0)).expect("fit");
            // Noise-free data: limited by rounding only.
            assert!((fit.n - n).abs() < 1e-8, "n = {} vs {n}", fit.n);
            assert!(relative_error(fit.a_e, a_e) < 1e-8, "A_e = {}", fit.a_e);
            assert_eq!(fit.t0, t0);
            assert_eq!((fit.se_t0, fit.ci95_t0), (None, None));
            assert_eq!((fit.points, fit.dof), (240, 238));
            assert!(fit.r_squared > 1.0 - 1e-12 && fit.residual_rms < 1e-12 * a_e);
        }
    }

    #[test]
    fn exact_power_law_recovered_with_free_t0() {
        for n in EXPONENTS {
            let (t, e, a_e, t0) = thesis_series(n);
            let fit = fit_power_law(&t, &e, HaltTime::Free).expect("fit");
            assert!((fit.n - n).abs() < 1e-8, "n = {} vs {n}", fit.n);
            assert!(relative_error(fit.a_e, a_e) < 1e-8, "A_e = {}", fit.a_e);
            assert!((fit.t0 - t0).abs() < 1e-8, "t0 = {} vs {t0}", fit.t0);
            assert!(fit.se_t0.is_some() && fit.ci95_t0.is_some());
            assert_eq!((fit.points, fit.dof), (240, 237));
            assert!(fit.r_squared > 1.0 - 1e-12);
        }
    }

    /// Table 4.1 set-up: the halt at t0 = 0.5 s, times shifted so that the stop is at
    /// t = 0 works the same (§3.2.5: E = A_e t^n after shifting).
    #[test]
    fn shifted_time_origin_gives_the_same_exponent() {
        let (t, e, _, t0) = thesis_series(2.0 / 3.0);
        let shifted: Vec<f64> = t.iter().map(|ti| ti - t0).collect();
        let a = fit_power_law(&t, &e, HaltTime::Fixed(t0)).expect("fit");
        let b = fit_power_law(&shifted, &e, HaltTime::Fixed(0.0)).expect("fit");
        assert!((a.n - b.n).abs() < 1e-10 && (a.se_n - b.se_n).abs() < 1e-6 * a.se_n);
    }

    /// Noisy synthetic series for the coverage test: 181 samples 0.1–1.0 s before
    /// t0 = 0.5 s, homoscedastic Gaussian noise of σ = E_min/8 (so no sample turns
    /// negative: 8σ has probability 6e-16), which is 4.4 % of E_max for n = 0.45.
    fn noisy_series(n: f64, rng: &mut SplitMix64) -> (Vec<f64>, Vec<f64>) {
        let (a_e, t0) = (0.0063, 0.5);
        let t: Vec<f64> = (0..=180).map(|i| -0.5 + 0.005 * i as f64).collect();
        let sigma = a_e * 0.1f64.powf(n) / 8.0;
        let e = law_with_noise(&t, a_e, t0, n, sigma, rng);
        (t, e)
    }

    /// E = A_e (t0 − t)^n at the times `t`, each with Gaussian noise of σ = `sigma`.
    fn law_with_noise(
        t: &[f64],
        a_e: f64,
        t0: f64,
        n: f64,
        sigma: f64,
        rng: &mut SplitMix64,
    ) -> Vec<f64> {
        t.iter()
            .map(|ti| a_e * (t0 - ti).powf(n) + sigma * rng.gaussian())
            .collect()
    }

    /// The 95 % interval for n must cover the true n in about 95 % of repeated
    /// experiments. With 200 trials the count of covers is binomial(200, 0.95): mean 190,
    /// sd 3.1; requiring ≥ 180 (90 %) is 3.2 sd below the mean, so a correct interval
    /// fails with probability < 0.1 %, while an interval too narrow by a factor 1.3
    /// covers only 87 % (one that dropped s², or the n–t0 correlation, fails by far).
    /// A fit error counts as a miss. The seed is fixed, so the test is deterministic;
    /// these seeds give 192/200 (fixed t0) and 187–189/200 (free t0), and 2000 trials
    /// give 94.7–95.4 %.
    #[test]
    fn confidence_interval_for_n_covers_the_truth() {
        for (halt, seed) in [(HaltTime::Fixed(0.5), 11), (HaltTime::Free, 12)] {
            for n in EXPONENTS {
                let mut rng = SplitMix64::new(seed);
                let mut covered = 0;
                let mut failed = 0;
                for _ in 0..200 {
                    let (t, e) = noisy_series(n, &mut rng);
                    match fit_power_law(&t, &e, halt) {
                        Ok(fit) if fit.ci95_n.0 <= n && n <= fit.ci95_n.1 => covered += 1,
                        Ok(_) => {}
                        Err(_) => failed += 1,
                    }
                }
                assert!(
                    covered >= 180,
                    "{halt:?}, n = {n}: covered {covered}/200, {failed} failed"
                );
            }
        }
    }

    /// AR(1) residuals (ρ = 0.8, as per-frame states sharing their frames give) on an
    /// exact power law, 720 samples 0.65–0.05 s before the halt (σ = E_min/8, so no
    /// sample turns negative): the plain interval
    /// n ± t·`se_n_uncorrelated` is about 3 × too narrow (√((1 + ρ)/(1 − ρ)) = 3) and
    /// covers far less than 95 %; the interval from the residuals' autocorrelation
    /// covers 90–98 % (binomial(200, 0.95): mean 190, sd 3.1; 180–196 is −3.2 … +2 sd).
    /// Fixed seeds, so deterministic: 193 and 191/200 with t0 fixed, 183 and 184/200
    /// with it free; the plain interval 93–94/200.
    #[test]
    fn autocorrelated_residuals_widen_the_interval_to_cover_the_truth() {
        let (a_e, t0, rho) = (0.0063, 0.0, 0.8);
        for (halt, seed) in [(HaltTime::Fixed(t0), 21), (HaltTime::Free, 22)] {
            for n in [0.45, 2.0 / 3.0] {
                let mut rng = SplitMix64::new(seed);
                let (mut plain, mut hac, mut failed) = (0, 0, 0);
                for _ in 0..200 {
                    let t: Vec<f64> = (0..720).map(|i| -0.65 + 0.6 * i as f64 / 719.0).collect();
                    let sigma = a_e * 0.05f64.powf(n) / 8.0;
                    let mut ar = sigma * rng.gaussian();
                    let e: Vec<f64> = t
                        .iter()
                        .map(|ti| {
                            ar = rho * ar + (1.0 - rho * rho).sqrt() * sigma * rng.gaussian();
                            a_e * (t0 - ti).powf(n) + ar
                        })
                        .collect();
                    let Ok(fit) = fit_power_law(&t, &e, halt) else {
                        failed += 1;
                        continue;
                    };
                    let q = StudentsT::new(0.0, 1.0, fit.dof as f64)
                        .expect("t")
                        .inverse_cdf(0.975);
                    plain += usize::from((fit.n - n).abs() <= q * fit.se_n_uncorrelated);
                    hac += usize::from(fit.ci95_n.0 <= n && n <= fit.ci95_n.1);
                }
                assert!(
                    (180..=196).contains(&hac) && failed == 0,
                    "{halt:?}, n = {n}: covered {hac}/200 ({failed} failed)"
                );
                assert!(plain < 150, "{halt:?}, n = {n}: plain covered {plain}/200");
            }
        }
    }

    /// The free-t0 interval for t0 also covers (same binomial argument).
    #[test]
    fn confidence_interval_for_t0_covers_the_truth() {
        for n in EXPONENTS {
            let mut rng = SplitMix64::new(13);
            let covered = (0..200)
                .filter(|_| {
                    let (t, e) = noisy_series(n, &mut rng);
                    fit_power_law(&t, &e, HaltTime::Free)
                        .ok()
                        .and_then(|fit| fit.ci95_t0)
                        .is_some_and(|(lo, hi)| lo <= 0.5 && 0.5 <= hi)
                })
                .count();
            assert!(covered >= 180, "n = {n}: covered {covered}/200");
        }
    }

    /// Times [s] of `turns` peaks a turn apart over the final 0.5 s before `t0`,
    /// crowding towards the halt as ψ ∝ τ^{1 − n/2} steps by a turn (stationary
    /// rolling's ψ̇ ∝ τ^{−n/2}, eq. 4.40).
    fn crowding_peaks(n: f64, t0: f64, turns: usize) -> Vec<f64> {
        (0..turns)
            .map(|k| {
                let phase_left = 1.0 - (k as f64 + 0.5) / turns as f64;
                t0 - 0.5 * phase_left.powf(1.0 / (1.0 - 0.5 * n))
            })
            .collect()
    }

    /// A peaks series: 26 energies a turn apart over the final 0.5 s, crowding towards
    /// the halt as ψ ∝ τ^{1 − n/2} steps by a turn (stationary rolling's
    /// ψ̇ ∝ τ^{−n/2}, eq. 4.40), with Gaussian noise of σ = E_min/6 on every energy.
    /// The final few energies, close together in time and small, fix t0 alone: the
    /// fit bends through them, so their residuals understate their errors, and the
    /// sandwich's t0 interval covers the true halt in 144–160 of 200 series (72–80 %;
    /// three seeds each). Left out in turn, they show how much t0 rides on each: with
    /// the jackknife's error the interval covers in 179–190 (89–95 %; binomial(200,
    /// 0.95) has sd 3.1). The test asks 176–196 of the jackknife and under 170 of the
    /// sandwich. The interval of n is the sandwich's either way.
    #[test]
    fn the_jackknife_keeps_the_interval_of_t0_honest_where_the_last_peaks_fix_it() {
        let (a_e, t0, turns) = (0.0063, 0.0, 26);
        for (n, seed) in [(0.45, 31), (2.0 / 3.0, 32)] {
            let t = crowding_peaks(n, t0, turns);
            let sigma = a_e * (t0 - t[turns - 1]).powf(n) / 6.0;
            let mut rng = SplitMix64::new(seed);
            let (mut covered, mut sandwich_covered) = (0, 0);
            for _ in 0..200 {
                let e = law_with_noise(&t, a_e, t0, n, sigma, &mut rng);
                let fit = fit_power_law(&t, &e, HaltTime::Free).expect("fit");
                let sandwich =
                    fit_with_limit(&t, &e, HaltTime::Free, MAX_ITERATIONS, &[]).expect("fit");
                let covers =
                    |f: &PowerLawFit| f.ci95_t0.is_some_and(|(lo, hi)| lo <= t0 && t0 <= hi);
                covered += usize::from(covers(&fit));
                sandwich_covered += usize::from(covers(&sandwich));
                assert_eq!(fit.ci95_n, sandwich.ci95_n);
            }
            assert!(
                (176..=196).contains(&covered) && sandwich_covered < 170,
                "n = {n}: covered {covered}/200, the sandwich's {sandwich_covered}/200"
            );
        }
    }

    /// The same crowding peaks series with the halt seen within a frame of the truth
    /// (all motion visible): combined, the intervals of both t0 and n are honest, their
    /// errors 0.9–1.05 of their stated errors rms, and cover the truth in 183–195 of
    /// 200. With the free t0 weighed by the sandwich's error alone the combination
    /// leaned on it: t0's errors were 1.65–2.61 of its stated ones, covering in
    /// 152–160, and n's 1.09–1.27.
    #[test]
    fn the_halt_seen_combined_with_crowding_peaks_keeps_both_intervals_honest() {
        let (a_e, t0, turns) = (0.0063, 0.0, 26);
        let frame_s = 1.0 / 480.0;
        for (n, seed) in [(0.45, 31), (2.0 / 3.0, 32)] {
            let t = crowding_peaks(n, t0, turns);
            let sigma = a_e * (t0 - t[turns - 1]).powf(n) / 6.0;
            let mut rng = SplitMix64::new(seed);
            let (mut z_n, mut z_t0, mut n_covered, mut t0_covered) = (0.0, 0.0, 0, 0);
            for _ in 0..200 {
                let e = law_with_noise(&t, a_e, t0, n, sigma, &mut rng);
                let sighting = HaltSighting {
                    t_last: t0 - frame_s * rng.uniform(),
                    ..visible_to_the_end(frame_s)
                };
                let fit = fit_power_law(&t, &e, HaltTime::Sighted(sighting)).expect("fit");
                let (lo, hi) = fit.ci95_t0.expect("t0 fitted");
                z_n += ((fit.n - n) / fit.se_n).powi(2) / 200.0;
                z_t0 += ((fit.t0 - t0) / fit.se_t0.expect("t0 fitted")).powi(2) / 200.0;
                n_covered += usize::from(fit.ci95_n.0 <= n && n <= fit.ci95_n.1);
                t0_covered += usize::from(lo <= t0 && t0 <= hi);
            }
            let (z_n, z_t0) = (z_n.sqrt(), z_t0.sqrt());
            assert!(
                n_covered >= 180 && t0_covered >= 176 && z_n < 1.15 && z_t0 < 1.2,
                "n = {n}: n covered {n_covered}/200 (rms error / se {z_n:.2}), \
                 t0 {t0_covered}/200 ({z_t0:.2})"
            );
        }
    }

    /// Per-frame energies whose errors a turn's frames share, as the states of one
    /// turn share its local fits and coded pictures: 240 frames at 480 fps over the
    /// final 0.5 s, 26 turns quickening towards the halt (peaks where ψ ∝ τ^{1 − n/2}
    /// steps by a turn, as stationary rolling's ψ̇ ∝ φ^{−1/2} ∝ τ^{−n/2} gives, eq.
    /// 4.40), each turn's frames off by one Gaussian draw of σ = E_min/6 and each frame
    /// by another of the same σ. Correlated 0.5 within a turn of 16 frames or of 4 and
    /// not across, the frames' errors follow no AR(1): estimated over the frames alone
    /// the intervals were too narrow, the errors 1.36–1.46 of their stated standard
    /// errors rms, 162–171 of 200 covering n. Estimated over the turns the peaks
    /// separate as well, the intervals cover n in 90–98 % of trials (binomial(200,
    /// 0.95): 180–196 is −3.2 … +2 sd; 190–191 with these seeds) and the errors are
    /// 0.9–1.15 of the stated errors rms (1.00–1.06 here); no interval is narrower
    /// than the frames' alone.
    #[test]
    fn per_frame_intervals_are_estimated_over_the_turns() {
        let (a_e, t0, turns) = (0.0063, 0.0, 26);
        for halt in [HaltTime::Fixed(t0), HaltTime::Free] {
            for n in [0.45, 2.0 / 3.0] {
                let peaks = crowding_peaks(n, t0, turns);
                let t: Vec<f64> = (1..=240).rev().map(|k| t0 - k as f64 / 480.0).collect();
                let sigma = a_e * (t0 - t[239]).powf(n) / 6.0;
                let mut rng = SplitMix64::new(9);
                let (mut covered, mut z_squared) = (0, 0.0);
                for _ in 0..200 {
                    let turn_error: Vec<f64> =
                        (0..=turns).map(|_| sigma * rng.gaussian()).collect();
                    let e: Vec<f64> = t
                        .iter()
                        .map(|&ti| {
                            let turn = peaks.partition_point(|&p| p <= ti);
                            a_e * (t0 - ti).powf(n) + turn_error[turn] + sigma * rng.gaussian()
                        })
                        .collect();
                    let fit = fit_window_in_turns(&t, &e, 0.5, halt, &peaks).expect("fit");
                    let frames = fit_window(&t, &e, 0.5, halt).expect("fit over the frames");
                    let width = |f: &PowerLawFit| f.ci95_n.1 - f.ci95_n.0;
                    assert!(
                        width(&fit) >= width(&frames),
                        "narrower than over the frames"
                    );
                    covered += usize::from(fit.ci95_n.0 <= n && n <= fit.ci95_n.1);
                    z_squared += ((fit.n - n) / fit.se_n).powi(2);
                }
                let rms_z = (z_squared / 200.0).sqrt();
                assert!(
                    (180..=196).contains(&covered) && (0.9..=1.15).contains(&rms_z),
                    "{halt:?}, n = {n}: covered {covered}/200, rms error / se {rms_z:.2}"
                );
            }
        }
    }

    /// The halt seen in the footage is a second measurement of t0: t_last the last frame
    /// before the true halt (δt = 5 ms apart, at a random phase u: t_last = t0 − u δt),
    /// all motion visible (Δ = 0). Combined with the fit, t0 is closer to the truth than
    /// the fit's own, and within 1.5 times the RMS error of two independent Gaussian
    /// measurements combined by their variances (the fit's t0 errors have heavier
    /// tails, and the fits left alone keep theirs; 200 noisy series), and the
    /// intervals of t0 and of n, with n moved by its covariance with t0, still cover
    /// the truth at least 90 % of the time (binomial(200, 0.95): ≥ 180 is 3.2 sd
    /// below the mean). A fit whose t0 lies more than 3 sd of the difference away is
    /// left alone; with Gaussian errors that is 0.3 % of them, and at most 5 % may be.
    #[test]
    fn a_sighted_halt_sharpens_t0_and_keeps_the_intervals_honest() {
        let frame_s = 0.005;
        for n in EXPONENTS {
            let mut rng = SplitMix64::new(21);
            let (mut sq_fitted, mut sq_combined) = (0.0, 0.0);
            let (mut t0_covered, mut n_covered, mut combined) = (0, 0, 0);
            for _ in 0..200 {
                let (t, e) = noisy_series(n, &mut rng);
                let sighting = HaltSighting {
                    t_last: 0.5 - frame_s * rng.uniform(),
                    ..visible_to_the_end(frame_s)
                };
                let fit = fit_power_law(&t, &e, HaltTime::Sighted(sighting)).expect("fit");
                let used = fit.halt_sighting.expect("sighting reported");
                combined += usize::from(used.combined);
                sq_fitted += (used.t0_fitted - 0.5).powi(2);
                sq_combined += (fit.t0 - 0.5).powi(2);
                let (lo, hi) = fit.ci95_t0.expect("t0 free");
                t0_covered += usize::from(lo <= 0.5 && 0.5 <= hi);
                n_covered += usize::from(fit.ci95_n.0 <= n && n <= fit.ci95_n.1);
            }
            // Two independent measurements of variances v_f and v_s combine to
            // 1/(1/v_f + 1/v_s); the fit's variance taken from its own errors here.
            let v_sighting = frame_s * frame_s * (1.0 / 12.0 + 1.0);
            let v_best = 1.0 / (200.0 / sq_fitted + 1.0 / v_sighting);
            assert!(
                (sq_combined / 200.0).sqrt() < 1.5 * v_best.sqrt() && sq_combined < sq_fitted,
                "n = {n}: RMS t0 error {} combined, {} fitted, {} at best",
                (sq_combined / 200.0).sqrt(),
                (sq_fitted / 200.0).sqrt(),
                v_best.sqrt()
            );
            assert!(combined >= 190, "n = {n}: combined {combined}/200");
            assert!(t0_covered >= 180, "n = {n}: t0 covered {t0_covered}/200");
            assert!(n_covered >= 180, "n = {n}: n covered {n_covered}/200");
        }
    }

    /// Energies of the law n = 0.6, t0 = 0 that end 0.1 s before the halt, with 3 %
    /// noise: their free t0 is uncertain by 16 ms. Times, energies and t0.
    fn ending_early() -> (Vec<f64>, Vec<f64>, f64) {
        let (a_e, n, t0) = (0.0063, 0.6, 0.0);
        let t: Vec<f64> = (0..60).map(|k| -0.5 + 0.4 * k as f64 / 59.0).collect();
        let mut rng = SplitMix64::new(31);
        let e = t
            .iter()
            .map(|&ti| a_e * (t0 - ti).powf(n) * (1.0 + 0.03 * rng.gaussian()))
            .collect();
        (t, e, t0)
    }

    /// A sighting far sharper than the energies' own t0 fixes t0, and the law is then
    /// the one fitted with t0 held there: the limit σ_seen → 0 of the profile
    /// combination. The energies end 0.1 s before the halt and carry 3 % noise, so
    /// their free t0 is uncertain by 16 ms and their n (0.560) differs from the held
    /// fit's (0.599, the truth 0.6) by four standard errors: the sighting matters.
    /// The variance of n is the held fit's, plus the little that the sighting's σ
    /// leaves.
    #[test]
    fn a_sharp_sighting_gives_the_law_with_t0_held_at_it() {
        let (t, e, t0) = ending_early();
        let frame_s = 1e-4;
        let free = fit_power_law(&t, &e, HaltTime::Free).expect("free fit");
        let se_free = free.se_t0.expect("free t0");
        assert!(se_free > 0.01, "the energies fix t0 to {se_free} s");
        let sighting = HaltSighting {
            t_last: t0 - 0.5 * frame_s,
            ..visible_to_the_end(frame_s)
        };
        let sighted = fit_power_law(&t, &e, HaltTime::Sighted(sighting)).expect("sighted");
        let used = sighted.halt_sighting.expect("sighting reported");
        assert!(used.combined);
        let se_t0 = sighted.se_t0.expect("t0 fitted");
        assert!((sighted.t0 - t0).abs() < 2.0 * frame_s, "t0 {}", sighted.t0);
        assert!(se_t0 < 1.1 * used.se_t0_seen, "se t0 {se_t0}");
        let held = fit_power_law(&t, &e, HaltTime::Fixed(sighted.t0)).expect("held fit");
        assert!(
            (sighted.n - held.n).abs() < 1e-6 && sighted.se_n >= held.se_n,
            "n {} ± {} against the held fit's {} ± {}",
            sighted.n,
            sighted.se_n,
            held.n,
            held.se_n
        );
        assert!(sighted.se_n < 1.05 * held.se_n, "se n {}", sighted.se_n);
        assert!(
            (free.n - held.n).abs() > 3.0 * held.se_n,
            "the free fit's n {} already agrees with the held fit's {}",
            free.n,
            held.n
        );
    }

    /// A sighting far from the fitted halt (an encoder holding the picture 40 frames
    /// past it) disagrees with the energy by far more than their uncertainties: it is
    /// reported and left out, and the fit is the free-t0 fit.
    #[test]
    fn a_sighting_that_disagrees_with_the_energy_is_left_out() {
        let (t, e, _, t0) = thesis_series(0.5);
        let frame_s = 1.0 / 480.0;
        let sighting = HaltSighting {
            t_last: t0 + 40.0 * frame_s,
            ..visible_to_the_end(frame_s)
        };
        let free = fit_power_law(&t, &e, HaltTime::Free).expect("free fit");
        let sighted = fit_power_law(&t, &e, HaltTime::Sighted(sighting)).expect("sighted fit");
        let used = sighted.halt_sighting.expect("sighting reported");
        assert!(!used.combined);
        assert!((used.t0_seen - (t0 + 40.5 * frame_s)).abs() < 0.05 * frame_s);
        assert_eq!((sighted.n, sighted.t0), (free.n, free.t0));
    }

    /// A sighting that agrees with the energies (their free t0 uncertain by 16 ms) but
    /// lies 12 ms before the halt, as a held picture ends the motion seen early, is
    /// combined without the turns' end, and with a turns' end T at the halt to 1 ms it
    /// disagrees with T by 8 standard deviations: it is reported and left out, and the
    /// fit is the free-t0 fit. With T where the sighting puts t0 it is combined.
    #[test]
    fn a_sighting_that_disagrees_with_the_turns_end_is_left_out() {
        let (t, e, t0) = ending_early();
        let frame_s = 1e-3;
        let free = fit_power_law(&t, &e, HaltTime::Free).expect("free fit");
        let held_early = HaltSighting {
            t_last: t0 - 12.0 * frame_s,
            ..visible_to_the_end(frame_s)
        };
        let fit = |turns_end| {
            let sighting = HaltSighting {
                turns_end,
                ..held_early
            };
            let fit = fit_power_law(&t, &e, HaltTime::Sighted(sighting)).expect("fit");
            let used = fit.halt_sighting.expect("sighting reported");
            (fit, used)
        };
        let (alone, used) = fit(None);
        assert!(used.combined && !used.disagrees_with_turns);
        assert!(alone.t0 < t0 - 8.0 * frame_s, "t0 {}", alone.t0);
        let at_halt = TurnsEnd {
            t_end: t0,
            se: frame_s,
        };
        let (refereed, used) = fit(Some(at_halt));
        assert!(!used.combined && used.disagrees_with_turns);
        assert_eq!((refereed.n, refereed.t0), (free.n, free.t0));
        let where_seen = TurnsEnd {
            t_end: used.t0_seen,
            ..at_halt
        };
        let (agreed, used) = fit(Some(where_seen));
        assert!(used.combined && !used.disagrees_with_turns);
        assert_eq!((agreed.n, agreed.t0), (alone.n, alone.t0));
    }

    /// A sighting whose motion is visible to the end (E_v = 0, so Δ = 0; no noise):
    /// t0 − t_last is uniform over a frame. The threshold, 10 μm, and ψ̇ there do not
    /// matter when Δ = 0.
    fn visible_to_the_end(frame_s: f64) -> HaltSighting {
        HaltSighting {
            t_last: 0.0,
            frame_s,
            visible_energy: 0.0,
            threshold_m: 1e-5,
            noise_m: 0.0,
            visible_precession: 1400.0,
            rest_above_zero_m: 0.0,
            turns_end: None,
        }
    }

    /// With all motion visible, the sighting is close to t0 − t_last uniform over a frame
    /// (mean δt/2, variance δt²/12), with one frame² more for where t_last falls: only a
    /// last frame that catches the rim at contact, where even a large peak reads
    /// below the threshold, moves t_last a frame earlier.
    /// A threshold that hides the final peaks moves t0 later and makes it less
    /// certain, the more so the longer Δ is.
    #[test]
    fn the_sighting_is_a_frame_when_all_motion_is_seen() {
        let frame_s = 1.0 / 480.0;
        let (mean, var) = visible_to_the_end(frame_s).gap(0.0, 0.5);
        assert!((mean / frame_s - 0.5).abs() < 0.05, "mean {mean}");
        let sd = (var / frame_s / frame_s - 1.0).sqrt();
        assert!((sd - (1.0f64 / 12.0).sqrt()).abs() < 0.05, "sd {sd} frames");
        // A 20 μm threshold (0.25 px at 80 μm/px), ψ̇ 1400 rad/s there.
        let hidden = HaltSighting {
            threshold_m: 2e-5,
            noise_m: 2e-6,
            visible_precession: 1400.0,
            ..visible_to_the_end(frame_s)
        };
        let gaps: Vec<(f64, f64)> = [0.5, 2.0, 5.0]
            .iter()
            .map(|&d| hidden.gap(d * frame_s, 0.5))
            .collect();
        for pair in gaps.windows(2) {
            assert!(pair[1].0 > pair[0].0 && pair[1].1 > pair[0].1, "{gaps:?}");
        }
        assert!(gaps[0].0 > 0.5 * frame_s, "{gaps:?}");
    }

    /// An offset every sample shares, as an error of the heights' zero makes, moves n
    /// without a trace in the residuals: the statistical interval alone covers the
    /// true n far less often than 95 %. With the offset's own standard error σ carried
    /// in (each fit made again with the energies moved by ±σ, half the change of n as
    /// `se_n_zero`), the intervals cover it as often as they say. Energies near the
    /// halt are ∝ φ ∝ z_rim, so a zero error δ adds about (E/z) δ to each: here a
    /// constant c δ, δ ~ N(0, σ), with white noise besides.
    #[test]
    fn a_shared_offset_is_carried_into_the_interval_of_n() {
        let (a_e, n, t0) = (0.0063, 0.55, 0.0);
        let t: Vec<f64> = (0..40).map(|k| -0.5 + 0.0125 * k as f64).collect();
        let truth: Vec<f64> = t.iter().map(|&ti| a_e * (t0 - ti).powf(n)).collect();
        let sigma = 1.5e-5; // the shared offset's σ [J], about 1 % of E at the window's end
        let mut rng = crate::rng::SplitMix64::new(12);
        let (mut statistical, mut with_zero) = (0, 0);
        let trials = 200;
        for _ in 0..trials {
            let offset = sigma * rng.gaussian();
            let e: Vec<f64> = truth
                .iter()
                .map(|&x| x + offset + 2e-6 * rng.gaussian())
                .collect();
            let fit = fit_window(&t, &e, 0.5, HaltTime::Free).expect("fit");
            let moved = |shift: f64| {
                let e: Vec<f64> = e.iter().map(|&x| x + shift).collect();
                fit_window(&t, &e, 0.5, HaltTime::Free).expect("moved").n
            };
            let se_zero = 0.5 * (moved(sigma) - moved(-sigma)).abs();
            let covers = |f: &PowerLawFit| f.ci95_n.0 <= n && n <= f.ci95_n.1;
            statistical += usize::from(covers(&fit));
            let fit = fit.with_zero_error(se_zero);
            assert_eq!(fit.se_n_zero, se_zero);
            with_zero += usize::from(covers(&fit));
        }
        assert!(
            statistical < trials * 80 / 100,
            "statistical {statistical}/{trials}"
        );
        assert!(
            (trials * 90 / 100..=trials * 99 / 100).contains(&with_zero),
            "with the zero {with_zero}/{trials}"
        );
    }

    /// Carrying a zero error in twice replaces it: the statistical half-width stays.
    #[test]
    fn the_zero_error_replaces_an_earlier_one() {
        let t: Vec<f64> = (0..30).map(|k| -0.5 + 0.016 * k as f64).collect();
        let e: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(k, &ti)| 0.0063 * (0.01 - ti).powf(0.5) * (1.0 + 0.01 * (k as f64).sin()))
            .collect();
        let fit = fit_window(&t, &e, 0.5, HaltTime::Free).expect("fit");
        let once = fit.clone().with_zero_error(0.02);
        let twice = once.clone().with_zero_error(0.01).with_zero_error(0.02);
        assert!((once.ci95_n.1 - twice.ci95_n.1).abs() < 1e-12);
        let half = |f: &PowerLawFit| 0.5 * (f.ci95_n.1 - f.ci95_n.0);
        let z = 1.959_963_984_540_054;
        assert!((half(&once).powi(2) - half(&fit).powi(2) - (z * 0.02f64).powi(2)).abs() < 1e-12);
    }

    /// Student t quantiles t_{0.975}(dof) from standard tables.
    #[test]
    fn student_quantile_matches_tables() {
        for (dof, q) in [(1.0, 12.706), (10.0, 2.228), (100.0, 1.984)] {
            let t = StudentsT::new(0.0, 1.0, dof).expect("t").inverse_cdf(0.975);
            assert!((t - q).abs() < 1e-3, "dof {dof}: {t}");
        }
    }

    #[test]
    fn window_keeps_only_the_final_seconds_before_the_halt() {
        // n = 0.5 in the last 0.5 s; earlier an unrelated (constant) energy; after the
        // halt the disk is flat (E = 0), as in the footage.
        let (a_e, t0, n) = (0.0063, 3.0, 0.5);
        let t: Vec<f64> = (0..1800).map(|i| i as f64 / 480.0).collect();
        let e: Vec<f64> = t
            .iter()
            .map(|&ti| match ti {
                ti if ti >= t0 => 0.0,
                ti if ti < t0 - 0.5 => 1.0,
                ti => a_e * (t0 - ti).powf(n),
            })
            .collect();
        let fixed = fit_window(&t, &e, 0.5, HaltTime::Fixed(t0)).expect("fixed");
        assert!(
            (fixed.n - n).abs() < 1e-8 && fixed.points == 240,
            "{fixed:?}"
        );
        // Free t0 windows back from the last sample: drop the flat tail first.
        let before: usize = t.iter().take_while(|&&ti| ti < t0).count();
        // The window runs back from the last sample, 1/480 s before t0; 0.49 s keeps it
        // inside the power-law stretch.
        let free = fit_window(&t[..before], &e[..before], 0.49, HaltTime::Free).expect("free");
        assert!(
            (free.n - n).abs() < 1e-8 && (free.t0 - t0).abs() < 1e-8,
            "{free:?}"
        );
        // With the flat samples kept, a free-t0 window runs back from the last (flat)
        // sample: an error naming the first flat sample in it, indexed in the full series.
        // (0.5 s at 480 fps spans 241 samples, both ends included.)
        let first = t.len() - 241;
        assert_eq!(
            fit_window(&t, &e, 0.5, HaltTime::Free).map(|f| f.n),
            Err(FitError::NonPositiveEnergy {
                index: first,
                t: t[first],
                energy: 0.0
            })
        );
        let sweep = window_sensitivity(&t, &e, &[0.2, 0.4], HaltTime::Fixed(t0), &[]);
        assert!(
            sweep
                .iter()
                .all(|(_, fit)| fit.as_ref().is_ok_and(|f| (f.n - n).abs() < 1e-8))
        );
        assert_eq!(
            fit_window(&t, &e, 0.0, HaltTime::Fixed(t0)),
            Err(FitError::InvalidWindow { window_s: 0.0 })
        );
    }

    #[test]
    fn error_cases_name_the_problem() {
        let (t, e, _, t0) = thesis_series(0.5);
        assert_eq!(
            fit_power_law(&t[..2], &e[..2], HaltTime::Fixed(t0)),
            Err(FitError::TooFewPoints { needed: 3, got: 2 })
        );
        assert_eq!(
            fit_power_law(&t[..3], &e[..3], HaltTime::Free),
            Err(FitError::TooFewPoints { needed: 4, got: 3 })
        );
        assert_eq!(
            fit_power_law(&t, &e[..10], HaltTime::Free),
            Err(FitError::LengthMismatch {
                times: 240,
                energies: 10
            })
        );
        let mut bad = e.clone();
        bad[7] = -1e-6;
        assert!(matches!(
            fit_power_law(&t, &bad, HaltTime::Free),
            Err(FitError::NonPositiveEnergy { index: 7, .. })
        ));
        bad[7] = f64::NAN;
        assert!(matches!(
            fit_power_law(&t, &bad, HaltTime::Free),
            Err(FitError::NonFinite { index: 7, .. })
        ));
        assert!(matches!(
            fit_power_law(&t, &e, HaltTime::Fixed(t[100])),
            Err(FitError::SampleAtOrAfterHalt { index: 100, .. })
        ));
        assert_eq!(
            fit_power_law(&t, &e, HaltTime::Fixed(f64::INFINITY)),
            Err(FitError::InvalidHaltTime { t0: f64::INFINITY })
        );
        let same_time = vec![1.0; 5];
        assert!(matches!(
            fit_power_law(&same_time, &e[..5], HaltTime::Fixed(2.0)),
            Err(FitError::Degenerate { .. })
        ));
        let constant = vec![0.01; 240];
        assert!(matches!(
            fit_power_law(&t, &constant, HaltTime::Free),
            Err(FitError::Degenerate { .. })
        ));
        let message = FitError::TooFewPoints { needed: 4, got: 3 }.to_string();
        assert!(
            message.contains("at least 4") && message.contains("got 3"),
            "{message}"
        );
    }

    /// Exponential decay is the t0 → ∞ limit of a power law: with t0 free the search
    /// runs off and must say so rather than return a number.
    #[test]
    fn exponential_decay_is_not_a_power_law() {
        let t: Vec<f64> = (0..200).map(|i| i as f64 * 0.01).collect();
        let e: Vec<f64> = t.iter().map(|ti| (-3.0 * ti).exp()).collect();
        let result = fit_power_law(&t, &e, HaltTime::Free);
        // The search follows t0 → ∞ with n/t0 → 3 s⁻¹ until the iteration limit.
        assert!(
            matches!(result, Err(FitError::NotConverged { n, t0, .. }) if t0 > 10.0 && (n / t0 - 3.0).abs() < 0.1),
            "{result:?}"
        );
    }

    /// Final samples that drop faster than the power law (here the last five fall to a
    /// thousandth) pull a free t0 onto the last sample; the error says so. For n < 1,
    /// where the energy is still large next to the halt (for n = 2.2 those samples hold
    /// ~1e-6 of E_max and barely move the fit).
    #[test]
    fn halt_pulled_onto_the_last_sample_is_reported() {
        for n in [0.45, 0.5, 2.0 / 3.0] {
            let (t, mut e, _, _) = thesis_series(n);
            for value in e.iter_mut().rev().take(5) {
                *value *= 1e-3;
            }
            let result = fit_power_law(&t, &e, HaltTime::Free);
            assert!(
                matches!(result, Err(FitError::HaltAtLastSample { t_last, .. }) if t_last == t[239]),
                "n = {n}: {result:?}"
            );
        }
    }

    #[test]
    fn iteration_limit_reports_not_converged() {
        let (t, e, _, _) = thesis_series(2.2);
        let result = fit_with_limit(&t, &e, HaltTime::Free, 1, &[]);
        assert!(
            matches!(result, Err(FitError::NotConverged { iterations: 1, .. })),
            "{result:?}"
        );
    }

    #[test]
    fn fit_serialises_to_json_and_back() {
        let (t, e, _, t0) = thesis_series(0.5);
        let fit = fit_power_law(&t, &e, HaltTime::Fixed(t0)).expect("fit");
        let json = serde_json::to_string(&fit).expect("json");
        assert!(json.contains("\"se_t0\":null"), "{json}");
        let back: PowerLawFit = serde_json::from_str(&json).expect("parse");
        // serde_json's default float parser may differ in the last bit.
        assert!(
            relative_error(back.n, fit.n) < 1e-15 && relative_error(back.se_n, fit.se_n) < 1e-15
        );
        assert_eq!(
            (back.se_t0, back.points, back.dof),
            (None, fit.points, fit.dof)
        );
        let halt: HaltTime = serde_json::from_str("{\"fixed\":0.5}").expect("halt");
        assert_eq!(halt, HaltTime::Fixed(0.5));
        assert!(
            fit.energy_at(t0) == 0.0 && relative_error(fit.energy_at(t0 - 0.25), e[120]) < 1e-8
        );
    }
}
