//! After the fits: the zero of z_rim's share of n's interval, and the checks that
//! are reported beside the fits, never applied to them (flagged frames in the
//! window, states and peaks left out, the precession check, the turns' timing).

use super::fits::{
    Fits, STATIONARY_RATE_FACTOR, frame_energies, near_stationary_rolling, peak_energies,
    with_zero_error,
};
use super::halt::Settled;
use super::series::{MeasuredSpan, rim_model, rim_series, signal_config};
use super::{EnergyFit, HaltPlacement};
use crate::config::ExperimentConfig;
use crate::energy::HaltTime;
use crate::model::params::DiskParams;
use crate::motion_fit::{self, MotionFit};
use crate::precession::{self, PrecessionCheck};
use crate::signal::{self, StateSeries};
use crate::turn_timing::TurnTimingFit;
use crate::vision::RimReading;

/// The fits as reported, with the checks' findings among the span's warnings.
pub(super) struct Fitted {
    pub(super) span: MeasuredSpan,
    /// The settled fits, their intervals of n widened by the zero of z_rim.
    pub(super) fits: Fits,
    pub(super) halt_placement: Option<HaltPlacement>,
    pub(super) skips_in_window: usize,
    pub(super) precession: Option<PrecessionCheck>,
    /// The motion fitted to every frame of the window.
    pub(super) motion: Option<MotionFit>,
    /// 1σ uncertainty of the zero of z_rim \[px\], carried into n's intervals.
    pub(super) zero_px: f64,
}

/// The settled fits with the zero's share of their intervals, and the checks'
/// warnings, in the order a reader meets them: the halt seen, flagged frames,
/// states and peaks left out, the precession, the turns' timing.
pub(super) fn finish_fits(
    config: &ExperimentConfig,
    params: &DiskParams,
    settled: Settled,
) -> Fitted {
    let Settled {
        mut span,
        fits,
        bounded,
        halt_placement,
        plan,
        ..
    } = settled;
    let halt_sighting = halt_sighting_disagrees(&fits.peaks);
    let halt = plan.halt(&span.series, bounded, fits.turns.as_ref().ok());
    let (start, end) = span.series.peaks.window;
    let skips = signal::flags_within(&span.series.flags, start, end);
    let skips_in_window = skips.len();
    let zero_px = zero_uncertainty_px(config, &span);
    let fits = with_zero_errors(fits, &span, params, zero_px, plan.window_s, halt);
    // φ from the heights against φ from the precession rate (crate::precession): a
    // check of the scale and the zero that shares neither; reported, never applied.
    let precession = precession::precession_check(
        &span.series.states,
        params,
        span.series.peaks.window,
        signal_config(plan.window_s, span.measured.metres_per_px).state_window_periods,
    );
    let motion = motion(&span, params, &fits, plan.window_s);
    let warnings = &mut span.measured.warnings;
    warnings.extend(halt_sighting);
    warnings.extend(flagged_in_window(&skips));
    warnings.extend(suspected_skips(&span.series.suspected_skips));
    warnings.extend(unsteady_states(&span.series, params));
    warnings.extend(unread_peaks(&span.series));
    warnings.extend(precession_disagrees(precession.as_ref()));
    warnings.extend(timing_disagrees(&fits.turns, &fits.peaks));
    Fitted {
        span,
        fits,
        halt_placement,
        skips_in_window,
        precession,
        motion,
        zero_px,
    }
}

/// The motion fitted to every frame of the window ([`crate::motion_fit`]), started
/// from the turns' timing law and the peaks fit; reported beside the fits.
fn motion(
    span: &MeasuredSpan,
    params: &DiskParams,
    fits: &Fits,
    window_s: f64,
) -> Option<MotionFit> {
    let timing = fits.turns.as_ref().ok()?;
    let (t, z): (Vec<f64>, Vec<f64>) = (span.measured.frames.iter())
        .map(|f| (f.t, f.z_rim_px.unwrap_or(f64::NAN)))
        .unzip();
    let peaks: Vec<(f64, f64)> = (span.series.peaks.peaks.iter())
        .map(|p| (p.t, p.phi))
        .collect();
    let model = rim_model(&span.measured.scale, params);
    let heights = motion_fit::Heights {
        t: &t,
        z_px: &z,
        metres_per_px: span.measured.metres_per_px,
        frame_s: 1.0 / span.measured.fps.fps,
    };
    let fit = motion_fit::fit_motion(
        &heights,
        model.as_ref(),
        timing,
        &peaks,
        fits.peaks.fit.n,
        window_s,
    )?;
    let unresolved = fit.unresolved_crests(
        last_crest_reach(&peaks),
        model.as_ref(),
        span.series.halt.threshold,
    );
    Some(MotionFit {
        unresolved_crests: unresolved,
        ..fit
    })
}

/// Fraction of the last turn after the last crest found within which a crest the
/// motion places is that one, not another.
const SAME_CREST_TURNS: f64 = 0.25;

/// The time after which a crest the motion places is not the last crest found: a
/// quarter of the last turn after it \[s\].
fn last_crest_reach(peaks: &[(f64, f64)]) -> f64 {
    match peaks {
        [.., (before, _), (last, _)] => last + SAME_CREST_TURNS * (last - before),
        [(last, _)] => *last,
        [] => f64::NEG_INFINITY,
    }
}

/// 1σ uncertainty of the zero of z_rim \[px\]: the config's, else the motion's
/// ([`RimReading::motion_zero_uncertainty_px`]), else the rim reading's.
fn zero_uncertainty_px(config: &ExperimentConfig, span: &MeasuredSpan) -> f64 {
    config
        .rim_zero_uncertainty_px()
        .unwrap_or_else(|| match &span.zero {
            Some(z) => {
                RimReading::motion_zero_uncertainty_px(z.zero.se / span.measured.metres_per_px)
            }
            None => span.measured.rim.reading.zero_uncertainty_px(),
        })
}

/// The fits with n's interval widened by the zero of z_rim. The zero (placed by the
/// motion, or the edge at rest) is shared by every height, so an error in it moves n
/// without a trace in the residuals: each fit is made again with the zero moved
/// down and up by its uncertainty `zero_px`, and half the change of n enters n's
/// interval.
fn with_zero_errors(
    fits: Fits,
    span: &MeasuredSpan,
    params: &DiskParams,
    zero_px: f64,
    window_s: f64,
    halt: HaltTime,
) -> Fits {
    let moved = zero_moved_series(span, params, zero_px, window_s);
    let peaks = with_zero_error(
        fits.peaks,
        &moved,
        |s| peak_energies(params, s),
        window_s,
        halt,
    );
    let frames = fits.frames.map(|f| {
        with_zero_error(
            f,
            &moved,
            |s| frame_energies(params, s, None),
            window_s,
            halt,
        )
    });
    let full_state = fits.full_state.map(|f| {
        let samples = |s: &StateSeries| frame_energies(params, s, s.strip.as_ref());
        with_zero_error(f, &moved, samples, window_s, halt)
    });
    Fits {
        peaks,
        frames,
        full_state,
        turns: fits.turns,
    }
}

/// The span's series with the zero of z_rim moved down and up by `zero_px`.
fn zero_moved_series(
    span: &MeasuredSpan,
    params: &DiskParams,
    zero_px: f64,
    window_s: f64,
) -> [Option<StateSeries>; 2] {
    let model = rim_model(&span.measured.scale, params);
    let (t, z) = rim_series(&span.measured.frames);
    [-1.0, 1.0].map(|sign| {
        signal::with_zero_moved(
            &t,
            &z,
            &span.series,
            sign * zero_px * span.measured.metres_per_px,
            model.as_ref(),
            &signal_config(window_s, span.measured.metres_per_px),
        )
        .ok()
    })
}

/// The halt seen and the turns' end more than 3σ apart: t0 is the energies' alone.
fn halt_sighting_disagrees(peaks_fit: &EnergyFit) -> Option<String> {
    let seen = peaks_fit
        .fit
        .halt_sighting
        .filter(|s| s.disagrees_with_turns)?;
    let turns = seen.turns_end?;
    Some(format!(
        "the halt seen puts t0 at {:+.1} ± {:.1} ms, the turns' end at {:+.1} ± {:.1} ms: \
         more than 3σ apart, as when the encoder holds the last pictures; t0 is the \
         energies' alone",
        1e3 * seen.t0_seen,
        1e3 * seen.se_t0_seen,
        1e3 * turns.t_end,
        1e3 * turns.se
    ))
}

/// Flagged frames (skips, jumps, repeats) inside the fit window, with the
/// timestamp gaps among them.
fn flagged_in_window(in_window: &[&signal::FrameFlag]) -> Option<String> {
    if in_window.is_empty() {
        return None;
    }
    let gaps: Vec<String> = in_window
        .iter()
        .filter_map(|f| match f.reason {
            signal::SkipReason::TimestampGap { missing_frames, .. } => Some(format!(
                "{missing_frames} frame(s) missing before t = {:.4} s",
                f.t
            )),
            _ => None,
        })
        .collect();
    let gaps = if gaps.is_empty() {
        String::new()
    } else {
        format!(" (timestamp gaps: {})", gaps.join("; "))
    };
    Some(format!(
        "{} flagged frame(s) (skips, jumps or repeated frames) inside the fit window{gaps}",
        in_window.len()
    ))
}

/// The rim phase steps the turns' timing did not confirm (`signal::TimingStep`):
/// a frame may be missing there, but none was counted.
fn suspected_skips(suspected: &[signal::FrameFlag]) -> Option<String> {
    if suspected.is_empty() {
        return None;
    }
    let at: Vec<String> = suspected
        .iter()
        .map(|f| format!("{} (t = {:.4} s: {})", f.index, f.t, f.reason.label()))
        .collect();
    Some(format!(
        "the rim's phase steps at frame(s) {} as after a dropped frame, but the turns' \
         timing does not confirm a frame missing there (a φ oscillating about stationary \
         rolling can do this): nothing was added to the capture clock",
        at.join("; ")
    ))
}

/// States far from stationary rolling, left out of the per-frame fits
/// ([`frame_energies`]).
fn unsteady_states(series: &StateSeries, params: &DiskParams) -> Option<String> {
    let unsteady: Vec<String> = (series.states.iter())
        .filter(|s| s.is_determined() && !near_stationary_rolling(params, s))
        .map(|s| format!("{:.4}", s.t))
        .collect();
    (!unsteady.is_empty()).then(|| {
        format!(
            "{} per-frame state(s) left out of the per-frame fits: their precession rate lies \
             more than {STATIONARY_RATE_FACTOR} times from stationary rolling's at their φ \
             (eq. 4.40), which eq. 3.8 assumes (t = {} s from the halt)",
            unsteady.len(),
            unsteady.join(", ")
        )
    })
}

/// Peaks whose height no φ reads, left out of the peaks fit ([`peak_energies`]).
fn unread_peaks(series: &StateSeries) -> Option<String> {
    let unread: Vec<String> = (series.peaks.peaks.iter())
        .filter(|p| !p.phi.is_finite())
        .map(|p| format!("{:.4}", p.t))
        .collect();
    (!unread.is_empty()).then(|| {
        format!(
            "{} of {} peaks left out of the peaks fit: their heights lie outside the \
             rim model's range, so no φ reads them (t = {} s from the halt)",
            unread.len(),
            series.peaks.peaks.len(),
            unread.join(", ")
        )
    })
}

/// The heights' φ and the precession's disagree beyond [`precession::AGREEMENT`].
fn precession_disagrees(check: Option<&PrecessionCheck>) -> Option<String> {
    let check = check.filter(|c| !c.agrees())?;
    Some(format!(
        "the heights' φ and the precession's disagree by more than {:.0} %: {}. Check the \
         scale (the near top rim z_t, the disk's R, H and inertia in the config) and the \
         zero of z_rim",
        100.0 * precession::AGREEMENT,
        check.describe()
    ))
}

/// n from the turning points' times alone (crate::turn_timing), where no height,
/// scale or zero enters, against the peaks fit's: disjoint 95 % intervals.
fn timing_disagrees(
    turn_timing: &Result<TurnTimingFit, String>,
    peaks_fit: &EnergyFit,
) -> Option<String> {
    let timing = turn_timing.as_ref().ok()?;
    let gap = disjoint_intervals(timing.ci95_n, peaks_fit.fit.ci95_n)?;
    Some(format!(
        "n from the turns' timing alone, {:.3} ({:.3} … {:.3}), and from the energies at \
         the peaks, {:.3} ({:.3} … {:.3}), have disjoint 95 % intervals ({gap:.3} apart): the \
         heights' zero, a codec's smoothing of the swing, or rolling away from the \
         stationary state (nutation, slip) moves one and not the other",
        timing.n,
        timing.ci95_n.0,
        timing.ci95_n.1,
        peaks_fit.fit.n,
        peaks_fit.fit.ci95_n.0,
        peaks_fit.fit.ci95_n.1,
    ))
}

/// How far apart two intervals lie, `None` when they overlap.
fn disjoint_intervals(a: (f64, f64), b: (f64, f64)) -> Option<f64> {
    let gap = (a.0 - b.1).max(b.0 - a.1);
    (gap > 0.0).then_some(gap)
}
