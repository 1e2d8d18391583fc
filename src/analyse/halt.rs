//! The halt t_φ settled by the laws of the motion. The signal stage first places
//! t_φ at the last frame of motion seen; the fits then know two laws that end the
//! motion, the energy's E = A_e (t0 − t)^n and the turns' timing. The signal stage
//! and the fits are run again, each step at most once and in this order:
//!
//! 1. a halt seen well after a law's is a coded picture, not motion: the rim is
//!    looked for again up to the law's halt ([`law_bound`]), t0 then fitted free;
//! 2. after 1, a frame counted missing whose phase step lies within its test's
//!    reach of the new halt is withdrawn (`series::withdraw_hidden_drops`);
//! 3. t_φ is placed where the laws put the halt ([`law_halt`]), not where the last
//!    rise was seen.
//!
//! Each step keeps the series and fits it made only when they succeed; each
//! re-zeroes the heights, so the zero of z_rim follows the motion's fit.

use std::path::Path;

use super::calibrate::RestCalibration;
use super::fits::{FitPlan, Fits};
use super::series::{MeasuredSpan, SignalPlan, signal_config, withdraw_hidden_drops};
use super::{AnalyseError, FrameRecord, HaltPlacement, ZeroFromMotion};
use crate::config::{ExperimentConfig, HaltChoice};
use crate::energy::{self, HaltSighting, PowerLawFit};
use crate::model::closed_form;
use crate::model::params::DiskParams;
use crate::signal::{self, SignalConfig, StateSeries};
use crate::turn_timing::TurnTimingFit;

/// The signal stage and fits once the laws settled the halt.
pub(super) struct Settled<'a> {
    /// The span, its frames, series, zero, zero row, flags and warnings those of the
    /// last step taken.
    pub(super) span: MeasuredSpan,
    pub(super) fits: Fits,
    /// Whether a law bounded t_φ (step 1).
    pub(super) bounded: bool,
    /// Where the laws placed t_φ (step 3), when they did.
    pub(super) halt_placement: Option<HaltPlacement>,
    /// The signal stage's config of the last step taken.
    pub(super) signal_config: SignalConfig,
    pub(super) plan: FitPlan<'a>,
}

/// One run of the signal stage and the fits on a copy of the frames.
struct Pass {
    frames: Vec<FrameRecord>,
    series: StateSeries,
    zero: Option<ZeroFromMotion>,
    fits: Fits,
}

/// Fits the span as measured, then takes the steps of the module docs.
///
/// # Errors
/// The first fit fails (see [`FitPlan::fit`]); later steps that fail are not taken.
pub(super) fn settle<'a>(
    clip: &'a Path,
    config: &ExperimentConfig,
    params: &'a DiskParams,
    rest: &RestCalibration,
    span: MeasuredSpan,
) -> Result<Settled<'a>, AnalyseError> {
    let plan = FitPlan::new(clip, config, params, &span);
    let signal = SignalPlan::new(
        rest.two_view,
        config.rim_zero(),
        &span.measured.scale,
        params,
    );
    let fits = plan.fit(&span.series, false)?;
    let signal_config = signal_config(plan.window_s, span.measured.metres_per_px);
    let mut settled = Settled {
        span,
        fits,
        bounded: false,
        halt_placement: None,
        signal_config,
        plan,
    };
    if settled.bound_by_laws(&signal) {
        settled.withdraw_drops(&signal);
    }
    if settled.plan.halt_choice != HaltChoice::Measured {
        settled.place_by_laws(&signal);
    }
    Ok(settled)
}

impl Settled<'_> {
    /// The signal stage and the fits again on `frames` with `config`; `None` when
    /// either fails.
    fn again(
        &self,
        signal: &SignalPlan,
        frames: &[FrameRecord],
        known_flags: &[signal::FrameFlag],
        config: &SignalConfig,
        bounded: bool,
    ) -> Option<Pass> {
        let mut frames = frames.to_vec();
        let (series, zero) = signal.series(&mut frames, known_flags, config).ok()?;
        let fits = self.plan.fit(&series, bounded).ok()?;
        Some(Pass {
            frames,
            series,
            zero,
            fits,
        })
    }

    /// Takes `pass`: its frames, series and fits, and the zero it moved (its fit
    /// moves within its standard error as its window does; the zero row follows).
    fn take(&mut self, pass: Pass) {
        let span = &mut self.span;
        (span.measured.frames, span.series, self.fits) = (pass.frames, pass.series, pass.fits);
        if let Some(again) = pass.zero {
            span.measured.rim.zero_row_px -= again.shift_m / span.measured.metres_per_px;
            span.zero = Some(match span.zero {
                Some(z) => ZeroFromMotion {
                    shift_m: z.shift_m + again.shift_m,
                    ..again
                },
                None => again,
            });
        }
    }

    /// Step 1: the rim looked for again up to a law's halt ([`law_bound`]), taken
    /// when it moves the halt earlier. Returns whether it was taken.
    fn bound_by_laws(&mut self, signal: &SignalPlan) -> bool {
        let Some(bound) = law_bound(&self.fits, self.fits.turns.as_ref().ok(), self.plan.frame_s)
        else {
            return false;
        };
        let series = &self.span.series;
        let mut config = self.signal_config.clone();
        config.motion_until = Some(series.halt.t_phi + bound.bound);
        let Some(pass) = self.again(
            signal,
            &self.span.measured.frames,
            &self.span.known_flags,
            &config,
            true,
        ) else {
            return false;
        };
        if pass.series.halt.index >= series.halt.index {
            return false;
        }
        let warning = format!(
            "the rim seemed to move until t = {:.4} s, {:.1} ± {:.1} ms after the halt of \
             {}: a rise after t = {:.4} s (that halt + 3σ + one frame) is taken for a \
             coded picture, not motion, so the last motion seen moves {} frame(s) \
             earlier, to t = {:.4} s, and t0 is fitted free of the halt seen",
            series.halt.t_phi,
            -1e3 * bound.halt,
            1e3 * bound.se,
            bound.law,
            series.halt.t_phi + bound.bound,
            series.halt.index - pass.series.halt.index,
            pass.series.halt.t_phi,
        );
        self.span.measured.warnings.push(warning);
        self.take(pass);
        self.bounded = true;
        self.signal_config = config;
        true
    }

    /// Step 2: the drops counted on the first pass's halt, checked against the
    /// bounded one; withdrawn only if the signal stage and the fits run on the
    /// clock without them.
    fn withdraw_drops(&mut self, signal: &SignalPlan) {
        let span = &self.span;
        let (mut frames, mut flags) = (span.measured.frames.clone(), span.known_flags.clone());
        let period = self.plan.frame_s;
        let withdrawn =
            withdraw_hidden_drops(&mut frames, &mut flags, &span.series.halt.shifted_t, period);
        if withdrawn.is_empty() {
            return;
        }
        // The law's halt on the clock without them: they all lie before it.
        let mut config = self.signal_config.clone();
        config.motion_until = config
            .motion_until
            .map(|t| t - withdrawn.len() as f64 * period);
        let Some(pass) = self.again(signal, &frames, &flags, &config, true) else {
            return;
        };
        let at: Vec<String> = withdrawn
            .iter()
            .map(|&i| span.measured.frames[i].index.to_string())
            .collect();
        let warning = format!(
            "the rim's phase step at frame(s) {} lies within its test's reach of the halt \
             the law places: the still pictures' step, not a frame missing, so the capture \
             times after it are no longer counted a frame later (signal::missing_frames)",
            at.join(", ")
        );
        self.span.measured.warnings.push(warning);
        self.take(pass);
        (self.span.known_flags, self.signal_config) = (flags, config);
    }

    /// Step 3: t_φ where the motion's laws place the halt ([`law_halt`]): the same
    /// frames, peaks and fits on a clock that starts there.
    fn place_by_laws(&mut self, signal: &SignalPlan) {
        let series = &self.span.series;
        let Some((offset, placement)) = law_halt(
            &self.fits.peaks.fit,
            self.fits.turns.as_ref().ok(),
            &series.halt,
        ) else {
            return;
        };
        self.signal_config.halt_at = Some(series.halt.t_phi + offset);
        let span = &self.span;
        match self.again(
            signal,
            &span.measured.frames,
            &span.known_flags,
            &self.signal_config,
            self.bounded,
        ) {
            Some(pass) => {
                self.take(pass);
                self.halt_placement = Some(placement.shifted(offset));
            }
            None => self.span.measured.warnings.push(format!(
                "the laws place the halt {:+.1} ms from the last motion seen, but the signal \
                 stage or the fits failed on that clock: t_φ is the last motion seen",
                1e3 * offset
            )),
        }
    }
}

/// A bound on the motion from a law of it whose halt the halt seen lies well after
/// ([`law_bound`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct LawBound {
    /// The latest time at which the law leaves the rim any motion, on the fits' clock
    /// (t_φ at 0) \[s\]: its halt + 3 σ + one frame.
    pub(super) bound: f64,
    /// The law, as a warning names it.
    pub(super) law: &'static str,
    /// Its halt \[s\] and that halt's standard error \[s\].
    pub(super) halt: f64,
    pub(super) se: f64,
}

/// The latest time at which the motion's laws leave the rim any motion, on the fits'
/// clock (t_φ = 0), when the halt seen lies after a law's: a fit's sighting of the
/// halt (at the peaks or per frame, [`HaltSighting`]) lies late, by more than
/// [`energy::SIGHTING_DISAGREEMENT`] standard deviations of their difference, of that
/// fit's t0 or of the end T of the turns' timing law (`turns`, [`turn_timing_fit`]).
/// A disk whose energy E = A_e (t0 − t)^n (eq. 3.2) has gone to zero lies flat and
/// does not rise again, and its turns, ψ̇ ∝ (T − t)^{−n/2}, end at T, so a rise seen
/// after the halt is a coded picture: an encoder that shows earlier pictures again
/// for a few frames after the halt, or settles on the still disk over many, read as
/// motion (t_φ up to 10 frames late, with a spurious peak). Either fit may see it
/// alone: spurious low peaks (0.2 px, several frames after the disk lay flat) pull
/// the peaks fit's free t0 onto the last of them, within its 3σ of the halt seen,
/// while the per-frame fit's t0 lies 20 ms before it, near the truth. The turns' law
/// may see it where neither fit can: where the final peaks barely fix the energies'
/// t0 (±13 ms), the halt seen decides the combined t0, and coded pictures 4 frames
/// after the true halt make n +0.05, while the turns end within a frame of the
/// truth, ±1.2 ms. The bound is
/// the earliest over the laws that disagree of their halt + 3 σ + one frame
/// `frame_s` (the last frame of motion falls up to a frame after the halt,
/// [`HaltSighting`]); `None` when the halt seen agrees, or the bound does not lie
/// before t_φ. A halt seen *before* a law's is the motion's last part too small to
/// see or hidden by its phase, which the sighting models, or held pictures, which it
/// does not: no bound (the fits leave such a sighting out when it lies more than 3σ
/// before T, `HaltSighting::fit`).
pub(super) fn law_bound(
    fits: &Fits,
    turns: Option<&TurnTimingFit>,
    frame_s: f64,
) -> Option<LawBound> {
    let sightings = [
        Some(("the energy law fitted at the peaks", &fits.peaks)),
        fits.frames
            .as_ref()
            .map(|f| ("the energy law fitted per frame", f)),
    ];
    sightings
        .into_iter()
        .flatten()
        .filter_map(|(law, f)| f.fit.halt_sighting.map(|s| (law, s)))
        .flat_map(|(law, s)| {
            let fitted = (law, s.t0_fitted, s.se_t0_fitted);
            let timed = turns.map(|f| ("the turns' timing law", f.t_end, f.se_t_end));
            [Some(fitted), timed]
                .into_iter()
                .flatten()
                .filter(move |&(_, halt, se)| {
                    s.t0_seen - halt > energy::SIGHTING_DISAGREEMENT * s.se_t0_seen.hypot(se)
                })
        })
        .map(|(law, halt, se)| LawBound {
            bound: halt + energy::SIGHTING_DISAGREEMENT * se + frame_s,
            law,
            halt,
            se,
        })
        .filter(|b| b.bound < 0.0 && b.se.is_finite() && b.se > 0.0)
        .min_by(|a, b| a.bound.total_cmp(&b.bound))
}

/// The halt as the footage shows it: motion last seen at the halt detector's last
/// frame of motion (on the fit's clock, t_φ at 0), one frame `frame_s` apart, down to
/// the least rise the halt detector sees above the heights' zero (its threshold above
/// the rest level, which lies `rest_above_zero_m` above the zero the motion placed), a
/// rim rise a peak of stationary rolling reaches at sin φ = z/(2R), over its rest
/// noise.
pub(super) fn halt_sighting(
    params: &DiskParams,
    halt: &signal::Halt,
    rest_above_zero_m: f64,
    frame_s: f64,
) -> HaltSighting {
    let seen = HaltSighting {
        t_last: halt.last_motion_seen(),
        frame_s,
        visible_energy: 0.0,
        threshold_m: halt.threshold,
        noise_m: halt.noise,
        visible_precession: 0.0,
        rest_above_zero_m,
        turns_end: None,
    };
    let phi = (seen.visible_rise() / (2.0 * params.radius))
        .clamp(0.0, 1.0)
        .asin();
    HaltSighting {
        visible_energy: energy::stationary_energy_at(params, phi).unwrap_or(0.0),
        visible_precession: closed_form::stationary_rolling(params, phi)
            .map_or(0.0, |(psi_dot, _)| psi_dot.abs()),
        ..seen
    }
}

/// Where the motion's laws place the halt on the clock of `series` (t_φ at 0) \[s\],
/// and the [`HaltPlacement`] on that clock: the mean of the energy law's t0 fitted at
/// the peaks (`peaks`, combined with the halt seen, [`HaltSighting`]) and the end T of
/// the turns' timing law (`turns`, [`turn_timing_fit`] of the same series), or t0
/// alone when the turns cannot be timed; `None` when t0 is not finite.
///
/// The halt detector's last frame of motion is a rule, a rise above the rest's noise,
/// and comes early by the frames whose motion the footage does not show: the last
/// rises fall below the threshold, and an encoder holds pictures whose change is
/// below its quantiser (on rendered scenes up to 7 frames early at a coarse
/// quantiser, a third of them more than 2 frames off, RMS 6.4 ms). The laws' halts
/// follow every turn of the window: on rendered scenes t0 is off by 2.0 ms RMS and
/// T by 1.1; on real-rim footage coded five ways by 0.54 and 0.61 frames, and their
/// errors are independent enough that the mean is off by 1.1 ms and 0.36 frames RMS
/// (docs/validation.md, "Where the halt lies"). T needs no height
/// and t0 no count of the turns, so a codec's shaved swings move one and not the
/// other.
pub(super) fn law_halt(
    peaks: &PowerLawFit,
    turns: Option<&TurnTimingFit>,
    halt: &signal::Halt,
) -> Option<(f64, HaltPlacement)> {
    let t0 = Some(peaks.t0).filter(|t| t.is_finite())?;
    let se_t0 = peaks.se_t0.filter(|se| se.is_finite());
    let turns = turns.filter(|f| f.t_end.is_finite() && f.se_t_end.is_finite());
    let (placed, se_s) = match &turns {
        Some(f) => (
            0.5 * (t0 + f.t_end),
            se_t0.map(|se| 0.5 * se.hypot(f.se_t_end)),
        ),
        None => (t0, se_t0),
    };
    let placement = HaltPlacement {
        t0_s: t0,
        turns_end_s: turns.map(|f| f.t_end),
        se_s,
        last_motion_seen_s: halt.last_motion_seen(),
    };
    Some((placed, placement))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analyse::fits::fit_series;
    use crate::analyse::{EnergyFit, EnergySample};
    use crate::energy::HaltTime;

    /// Peak energies of E = A_e (t0 − t)^n with 2 % noise, one every 6 ms up to
    /// `last` (t_φ = 0 on this clock), fitted as `analyse` fits them with the halt seen.
    fn sighted_peaks_fit(t0: f64, last: f64) -> EnergyFit {
        let (a_e, n, frame_s) = (0.5, 0.55, 1.0 / 480.0);
        let samples: Vec<EnergySample> = (0..80)
            .map(|k| last - 0.006 * k as f64)
            .rev()
            .enumerate()
            .map(|(k, t)| EnergySample {
                t,
                phi: 0.0,
                psi_dot: 0.0,
                theta_dot: None,
                energy: a_e * (t0 - t).powf(n) * (1.0 + 0.02 * (k as f64 * 2.39).sin()),
            })
            .collect();
        let halt = HaltTime::Sighted(HaltSighting {
            t_last: 0.0,
            frame_s,
            visible_energy: a_e * (0.3 * frame_s).powf(n),
            threshold_m: 2e-5,
            noise_m: 2e-6,
            visible_precession: 1400.0,
            rest_above_zero_m: 0.0,
            turns_end: None,
        });
        fit_series("eq. 3.8 at peaks", samples, 0.5, halt, &[]).expect("fit")
    }

    /// The halt seen 20 ms (nearly 10 frames) after the law's, as an encoder showing
    /// earlier pictures again after the halt makes it: the bound lies between the
    /// law's t0 and t_φ, within three standard errors and a frame of t0. Seen where
    /// the law has it, or before it (the last motion too small to see), no bound.
    #[test]
    fn a_halt_seen_after_the_laws_is_bounded_by_it() {
        let frame_s = 1.0 / 480.0;
        let late = sighted_peaks_fit(-0.020, -0.023);
        assert!(late.fit.halt_sighting.is_some_and(|s| !s.combined));
        let fits = Fits {
            peaks: late,
            frames: None,
            full_state: None,
            turns: Err("not timed".into()),
        };
        let bound = law_bound(&fits, None, frame_s).expect("a bound").bound;
        let t0 = fits.peaks.fit.t0;
        let se = fits.peaks.fit.se_t0.expect("t0 free");
        assert!((t0 + 0.020).abs() < 3.0 * se, "t0 {t0}");
        assert!(bound > t0 && bound < 0.0, "bound {bound}, t0 {t0}");
        assert!((bound - (t0 + 3.0 * se + frame_s)).abs() < 1e-12);
        for t0 in [0.001, 0.006] {
            let fits = Fits {
                peaks: sighted_peaks_fit(t0, -0.002),
                frames: None,
                full_state: None,
                turns: Err("not timed".into()),
            };
            assert_eq!(law_bound(&fits, None, frame_s), None, "t0 {t0}");
        }
        // The peaks fit agreeing with the halt seen (spurious low peaks after the halt
        // pull its free t0 onto them) does not hide the per-frame fit's disagreement.
        let frames = sighted_peaks_fit(-0.020, -0.023);
        let frames_t0 = frames.fit.t0 + 3.0 * frames.fit.se_t0.expect("t0 free") + frame_s;
        let fits = Fits {
            peaks: sighted_peaks_fit(0.001, -0.002),
            frames: Some(frames),
            full_state: None,
            turns: Err("not timed".into()),
        };
        assert_eq!(
            law_bound(&fits, None, frame_s).map(|b| b.bound),
            Some(frames_t0)
        );
    }

    /// The turns' timing law bounds the halt seen where the energies barely fix t0:
    /// a peaks fit whose t0 agrees with the halt seen (its own σ wide), and turns that
    /// end 12 ± 1 ms before it, bound the motion at T + 3σ + one frame. Turns ending
    /// where the halt is seen, no bound.
    #[test]
    fn a_halt_seen_after_the_turns_end_is_bounded_by_them() {
        let frame_s = 1.0 / 480.0;
        let turns = |t_end: f64| TurnTimingFit {
            n: 0.55,
            ci95_n: (0.54, 0.56),
            se_n: 0.005,
            se_n_least_squares: 0.005,
            se_n_jackknife: 0.005,
            t_end,
            se_t_end: 0.001,
            remaining_psi: 1.0,
            c: 1e-3,
            times: Vec::new(),
            psi: Vec::new(),
            points: 40,
            residual_rms_s: 1e-4,
        };
        let fits = Fits {
            peaks: sighted_peaks_fit(0.001, -0.002),
            frames: None,
            full_state: None,
            turns: Err("not timed".into()),
        };
        assert_eq!(law_bound(&fits, None, frame_s), None);
        let bound = law_bound(&fits, Some(&turns(-0.012)), frame_s).expect("a bound");
        assert_eq!(bound.law, "the turns' timing law");
        assert!((bound.bound - (-0.012 + 0.003 + frame_s)).abs() < 1e-12);
        assert_eq!(law_bound(&fits, Some(&turns(-0.001)), frame_s), None);
    }
}
