//! Signal (thesis §3.2.4–§3.3.3) on a measured span: the repeated frames left out
//! up to the halt, the frames missing where the timestamps show no gap, then the
//! signal stage proper (`crate::signal`): t_φ, peaks, φ, ψ̇, per-frame states, β,
//! the skip flags, and the zero of z_rim the motion places.

use std::path::Path;

use super::measure::MeasuredFrames;
use super::{AnalyseError, FrameRecord, ScaleReport, ZeroFromMotion};
use crate::config::{ExperimentConfig, RimZeroChoice};
use crate::footage::{self, CaptureFps};
use crate::model::params::DiskParams;
use crate::signal::{
    self, RimModel, SideViewRim, SignalConfig, SignalError, StateSeries, ThesisRim,
};

/// Pass 2's measurements of one span, through the signal analysis.
pub(super) struct MeasuredSpan {
    /// The span as measured, after the signal stage: each frame's time set from the
    /// halt and z_rim from the zero the motion places, the rim's zero row moved with
    /// it, and the repeated frames only those in the motion.
    pub(super) measured: MeasuredFrames,
    pub(super) series: StateSeries,
    /// The zero the motion placed.
    pub(super) zero: Option<ZeroFromMotion>,
    /// Width of the local fits' window [turns of the rim].
    pub(super) local_fit_periods: f64,
    /// The rest tail's length \[s\] (SignalConfig::rest_tail_s).
    pub(super) rest_tail_s: f64,
    /// Flags found before the signal stage ([`known_flags`]), positions in the frames.
    pub(super) known_flags: Vec<signal::FrameFlag>,
}

/// How the signal stage reads a clip's heights: the layout, the rim's profile for
/// the peaks and states ([`rim_model`]), the camera's for the motion's zero
/// ([`motion_profile`]) and the scale.
pub(super) struct SignalPlan {
    pub(super) two_view: bool,
    pub(super) model: Box<dyn RimModel>,
    pub(super) profile: Option<SideViewRim>,
    pub(super) metres_per_px: f64,
}

impl SignalPlan {
    pub(super) fn new(
        two_view: bool,
        rim_zero: RimZeroChoice,
        scale: &ScaleReport,
        params: &DiskParams,
    ) -> Self {
        SignalPlan {
            two_view,
            model: rim_model(scale, params),
            profile: motion_profile(rim_zero, scale, params),
            metres_per_px: scale.metres_per_px(),
        }
    }

    /// [`signal_series`] with this plan.
    pub(super) fn series(
        &self,
        frames: &mut [FrameRecord],
        known_flags: &[signal::FrameFlag],
        config: &SignalConfig,
    ) -> Result<(StateSeries, Option<ZeroFromMotion>), SignalError> {
        signal_series(
            frames,
            known_flags,
            self.two_view,
            config,
            self.model.as_ref(),
            self.profile.as_ref(),
            self.metres_per_px,
        )
    }
}

/// The signal stage on a measured span: the repeated frames in the motion left out
/// ([`repeats_in_motion`]), the frames missing where the timestamps show none
/// counted ([`hidden_drops`]), then [`signal_series`]; the zero the motion places
/// moves the rim's zero row ([`move_rim_zero`]).
///
/// # Errors
/// The signal stage fails (no halt, too few peaks; [`signal_error`]).
pub(super) fn signal_stage(
    clip: &Path,
    mut measured: MeasuredFrames,
    two_view: bool,
    config: &ExperimentConfig,
    params: &DiskParams,
) -> Result<MeasuredSpan, AnalyseError> {
    let signal_config = signal_config(config.window_s(), measured.metres_per_px);
    keep_repeats_in_motion(&mut measured, &signal_config);
    let plan = SignalPlan::new(two_view, config.rim_zero(), &measured.scale, params);
    if config.rim_zero() == RimZeroChoice::Motion && plan.profile.is_none() {
        measured.warnings.push(
            "the camera's elevation is not known (the silhouette's top was not found above \
             the top face): the zero of z_rim stays the still disk's edge"
                .into(),
        );
    }
    let known_flags = count_hidden_drops(&mut measured, &plan, &signal_config);
    let (series, zero) = plan
        .series(&mut measured.frames, &known_flags, &signal_config)
        .map_err(|error| signal_error(clip, &measured.fps, error))?;
    if let Some(zero) = &zero {
        move_rim_zero(&mut measured, zero);
    }
    Ok(MeasuredSpan {
        measured,
        series,
        zero,
        local_fit_periods: signal_config.state_window_periods,
        rest_tail_s: signal_config.rest_tail_s,
        known_flags,
    })
}

/// Narrows the span's repeated frames to those in the motion ([`repeats_in_motion`]):
/// the readings of the others go back to their frames, and a warning names the ones
/// left out of the fits.
fn keep_repeats_in_motion(measured: &mut MeasuredFrames, config: &SignalConfig) {
    let repeated = std::mem::take(&mut measured.repeated);
    let set_aside = std::mem::take(&mut measured.set_aside);
    measured.repeated = repeats_in_motion(
        &mut measured.frames,
        repeated,
        set_aside,
        config,
        measured.metres_per_px,
    );
    let warning = repeats_warning(&measured.frames, &measured.repeated);
    measured.warnings.extend(warning);
}

/// Counts the frames missing where the timestamps show none ([`hidden_drops`], one
/// nominal period each on the capture clock) and warns of them; returns the flags
/// known before the signal stage ([`known_flags`]).
fn count_hidden_drops(
    measured: &mut MeasuredFrames,
    plan: &SignalPlan,
    config: &SignalConfig,
) -> Vec<signal::FrameFlag> {
    let hidden = hidden_drops(
        &mut measured.frames,
        &measured.repeated,
        plan.two_view,
        config,
        plan.model.as_ref(),
        1.0 / measured.fps.fps,
    );
    let warning = hidden_drops_warning(&measured.frames, &hidden);
    measured.warnings.extend(warning);
    known_flags(&measured.repeated, hidden)
}

/// Moves the rim's zero row by the shift of the zero the motion placed, so that the
/// row still reads z_rim = 0, and adds to the rim's description where it now lies.
fn move_rim_zero(measured: &mut MeasuredFrames, zero: &ZeroFromMotion) {
    let rim = &mut measured.rim;
    rim.zero_row_px -= zero.shift_m / measured.metres_per_px;
    rim.description += &zero_description(
        zero,
        measured.metres_per_px,
        rim.zero_row_px,
        &measured.scale,
    );
}

/// How far the motion moved the zero of z_rim from the still disk's edge, to the row
/// `zero_row_px`, for the plan's description of the rim's reading.
fn zero_description(
    zero: &ZeroFromMotion,
    metres_per_px: f64,
    zero_row_px: f64,
    scale: &ScaleReport,
) -> String {
    let shift_px = zero.shift_m / metres_per_px;
    format!(
        "; the motion places the zero of z_rim {:.3} ± {:.3} px {} the still disk's \
         edge, at row {zero_row_px:.2} px (signal::motion_zero, {} heights between {} \
         turning points, the profile at ε = {:.2}°)",
        shift_px.abs(),
        zero.zero.se / metres_per_px,
        if shift_px >= 0.0 { "above" } else { "below" },
        zero.zero.points,
        zero.zero.turning_points,
        scale.near_rim_elevation_rad.unwrap_or(0.0).to_degrees()
    )
}

/// The warning for the duplicated and interpolated frames left out of the fits.
fn repeats_warning(frames: &[FrameRecord], repeated: &[footage::RepeatedFrame]) -> Option<String> {
    if repeated.is_empty() {
        return None;
    }
    let count = |kind| repeated.iter().filter(|r| r.kind == kind).count();
    let list: Vec<String> = repeated
        .iter()
        .map(|r| frames[r.index].index.to_string())
        .collect();
    Some(format!(
        "{} duplicated and {} interpolated frame(s) (frames {}) show no capture of \
     their own: left out of the fits",
        count(footage::RepeatKind::Duplicated),
        count(footage::RepeatKind::Interpolated),
        list.join(", ")
    ))
}

/// The warning for the frames counted missing where the timestamps show no gap.
fn hidden_drops_warning(frames: &[FrameRecord], hidden: &[signal::FrameFlag]) -> Option<String> {
    if hidden.is_empty() {
        return None;
    }
    let at: Vec<String> = hidden
        .iter()
        .map(|f| {
            format!(
                "{} (t = {:.4} s)",
                frames[f.index].index, frames[f.index].t_capture
            )
        })
        .collect();
    Some(format!(
        "the rim's phase steps by a frame's turn at frame(s) {} where the timestamps \
         show no gap: a frame missing from the clip before each, so the capture times \
         from there on are counted one frame later (signal::missing_frames)",
        at.join(", ")
    ))
}

/// The signal stage (thesis §3.2.4–§3.3.3) on the measured frames: t_φ, the peaks,
/// the states, β and the skip flags, with the `known_flags` ([`known_flags`]) among
/// them (by the clip's frame numbers); sets each frame's time from the halt
/// ([`FrameRecord::t`]).
pub(super) fn signal_series(
    frames: &mut [FrameRecord],
    known_flags: &[signal::FrameFlag],
    two_view: bool,
    config: &SignalConfig,
    model: &dyn RimModel,
    motion_profile: Option<&SideViewRim>,
    metres_per_px: f64,
) -> Result<(StateSeries, Option<ZeroFromMotion>), SignalError> {
    let (t, z) = rim_series(frames);
    let beta = strip_angles(frames, two_view);
    let mut series = signal::analyse(&t, &z, beta.as_deref(), model, config)?;
    // The heights from the zero the motion places (signal::motion_zero), with the
    // camera's own profile: every height moves by the rest level and the motion's
    // offset from it, and the peaks and states are found again on them.
    let motion = motion_profile.and_then(|camera| signal::motion_zero(&t, &z, &series, camera));
    let zero = motion.map(|zero| {
        let shift_m = series.halt.rest_level + zero.offset;
        for record in frames.iter_mut() {
            record.z_rim_m = record.z_rim_m.map(|z| z - shift_m);
            record.z_rim_px = record.z_rim_px.map(|z| z - shift_m / metres_per_px);
        }
        ZeroFromMotion { zero, shift_m }
    });
    if zero.is_some() {
        let (t, z) = rim_series(frames);
        series.halt.rest_level = 0.0;
        series = signal::with_zero_moved(&t, &z, &series, 0.0, model, config)?;
    }
    merge_known_flags(&mut series, known_flags, frames);
    for (record, shifted) in frames.iter_mut().zip(&series.halt.shifted_t) {
        record.t = *shifted;
    }
    Ok((series, zero))
}

/// Adds the flags found before the stage (`known_flags`, [`known_flags`]) to the
/// `series`' flags, on its time axis, in frame order. A frame missing where the
/// timestamps show none is flagged by the rim's phase step that showed it, not by
/// the gap its count left in the capture times. Every flag then carries the clip's
/// frame number (a span's positions in `frames` are not).
fn merge_known_flags(
    series: &mut StateSeries,
    known_flags: &[signal::FrameFlag],
    frames: &[FrameRecord],
) {
    let missing =
        |f: &signal::FrameFlag| matches!(f.reason, signal::SkipReason::RimPhaseStep { .. });
    let counted = |f: &signal::FrameFlag| {
        known_flags.iter().any(|k| missing(k) && k.index == f.index)
            && matches!(
                f.reason,
                signal::SkipReason::TimestampGap { .. } | signal::SkipReason::RimPhaseStep { .. }
            )
    };
    series.flags.retain(|f| !counted(f));
    series.suspected_skips.retain(|f| !counted(f));
    series
        .flags
        .extend(known_flags.iter().map(|k| signal::FrameFlag {
            t: series.halt.shifted_t[k.index],
            ..k.clone()
        }));
    series.flags.sort_by_key(|f| f.index);
    for flag in series.flags.iter_mut().chain(&mut series.suspected_skips) {
        flag.index = frames[flag.index].index;
    }
}

/// The repeated frames (`repeated`, their readings taken out of `frames` and kept in
/// `set_aside`: each one's z_rim in px and β) up to the last frame of motion the rim
/// heights show ([`signal::halt_time`]); the readings of those after it go back.
/// After the halt every frame repeats the one before it, so none can be told a
/// repeat: a mark there is the codec's refresh of the still picture
/// ([`footage::RepeatGauge`]). With no halt found, every mark stays.
pub(super) fn repeats_in_motion(
    frames: &mut [FrameRecord],
    mut repeated: Vec<footage::RepeatedFrame>,
    set_aside: Vec<(Option<f64>, Option<f64>)>,
    config: &SignalConfig,
    metres_per_px: f64,
) -> Vec<footage::RepeatedFrame> {
    if repeated.is_empty() {
        return repeated;
    }
    let (t, z) = rim_series(frames);
    let Ok(halt) = signal::halt_time(&t, &z, config) else {
        return repeated;
    };
    for (r, (z_rim_px, beta_raw)) in repeated.iter().zip(set_aside) {
        if r.index > halt.index {
            let record = &mut frames[r.index];
            record.z_rim_px = z_rim_px;
            record.z_rim_m = z_rim_px.map(|z| z * metres_per_px);
            record.beta_raw = beta_raw;
        }
    }
    repeated.retain(|r| r.index <= halt.index);
    repeated
}

/// The flags known before the signal stage, at their positions in the frames (their
/// times are set on the stage's axis, [`signal_series`]): the duplicated and
/// interpolated frames (`repeated`, left out of the fits) and the frames missing
/// where the timestamps show no gap (`hidden`, [`hidden_drops`]).
pub(super) fn known_flags(
    repeated: &[footage::RepeatedFrame],
    hidden: Vec<signal::FrameFlag>,
) -> Vec<signal::FrameFlag> {
    repeated
        .iter()
        .map(|r| signal::FrameFlag {
            index: r.index,
            t: f64::NAN,
            reason: match r.kind {
                footage::RepeatKind::Duplicated => signal::SkipReason::DuplicatedFrame {
                    step: r.statistic,
                    neighbours: r.neighbours,
                },
                footage::RepeatKind::Interpolated => signal::SkipReason::InterpolatedFrame {
                    residual: r.statistic,
                    neighbours: r.neighbours,
                },
            },
        })
        .chain(hidden)
        .collect()
}

/// Frames missing from the clip where its timestamps show no gap
/// ([`signal::missing_frames`], from a first pass of the signal stage over the heights
/// as measured): each such frame and every one after it moves one nominal period
/// later on the capture clock (`t_capture`), so that no local fit, precession rate or
/// energy time spans a frame that is not there. Returns the rim phase steps that
/// showed them (positions in `frames`; `period` is the nominal frame interval \[s\]);
/// none when the first pass fails (the signal stage then reports why).
pub(super) fn hidden_drops(
    frames: &mut [FrameRecord],
    repeated: &[footage::RepeatedFrame],
    two_view: bool,
    config: &SignalConfig,
    model: &dyn RimModel,
    period: f64,
) -> Vec<signal::FrameFlag> {
    let (t, z) = rim_series(frames);
    let beta = strip_angles(frames, two_view);
    let Ok(series) = signal::analyse(&t, &z, beta.as_deref(), model, config) else {
        return Vec::new();
    };
    let repeated: Vec<usize> = repeated.iter().map(|r| r.index).collect();
    let steps = signal::missing_frames(&series.flags, period, &repeated);
    let positions: Vec<usize> = steps.iter().map(|f| f.index).collect();
    shift_capture_clock(frames, &positions, period);
    steps
}

/// Moves each frame's capture time by `by` \[s\] for every one of `positions` (in
/// `frames`) at or before it: a frame missing before each, counted (`by` the nominal
/// period) or withdrawn (minus it).
fn shift_capture_clock(frames: &mut [FrameRecord], positions: &[usize], by: f64) {
    for (i, record) in frames.iter_mut().enumerate() {
        let count = positions.iter().filter(|&&p| p <= i).count();
        record.t_capture += count as f64 * by;
    }
}

/// The frames [`hidden_drops`] counted missing whose phase step no longer passes
/// [`signal::missing_frames`] on the halt-shifted times `shifted_t` (positions in
/// `frames`) of a halt placed earlier, by a law of the motion ([`law_bound`]): the
/// first pass measured the step test's margin from a halt that still pictures made
/// late. Each is taken out of `known_flags`, and the frames from it on lose the
/// nominal `period` their capture time gained. Returns their positions.
pub(super) fn withdraw_hidden_drops(
    frames: &mut [FrameRecord],
    known_flags: &mut Vec<signal::FrameFlag>,
    shifted_t: &[f64],
    period: f64,
) -> Vec<usize> {
    let is_step =
        |k: &signal::FrameFlag| matches!(k.reason, signal::SkipReason::RimPhaseStep { .. });
    let hidden: Vec<signal::FrameFlag> = known_flags
        .iter()
        .filter(|k| is_step(k))
        .map(|k| signal::FrameFlag {
            t: shifted_t[k.index],
            ..k.clone()
        })
        .collect();
    let kept = signal::missing_frames(&hidden, period, &[]);
    let withdrawn: Vec<usize> = hidden
        .iter()
        .filter(|h| kept.iter().all(|k| k.index != h.index))
        .map(|h| h.index)
        .collect();
    shift_capture_clock(frames, &withdrawn, -period);
    known_flags.retain(|k| !(is_step(k) && withdrawn.contains(&k.index)));
    withdrawn
}

/// The rim's profile the peaks and the states are read with: the camera's
/// ([`SideViewRim`]) when its elevation ε at the near rim is known, else eq. 3.9's
/// level camera ([`ThesisRim`]). At the peaks the camera's profile is
/// 2R sin φ − H φ tan ε, so eq. 3.9 reads φ low by H tan ε/(2R), 0.44 % at ε = 3°
/// for Euler's disk; the local fits, which weigh the turn's mean with its swing,
/// read it low by about 2/3 of that (`signal::tests::exact_geometry_is_a_drop_in_model`).
pub(super) fn rim_model(scale: &ScaleReport, disk: &DiskParams) -> Box<dyn RimModel> {
    match scale.side_view_rim(disk) {
        Some(camera) => Box::new(camera),
        None => Box::new(ThesisRim {
            radius: disk.radius,
        }),
    }
}

/// The rim's profile the motion's zero is fitted with ([`signal::motion_zero`]): the
/// camera's ([`ScaleReport::side_view_rim`]) when `choice` asks for the motion's zero.
/// `None` keeps the still disk's edge: asked for, or the camera's elevation not known,
/// where the first-order profile would read 0.05–0.12 px of offset that is not there.
pub(super) fn motion_profile(
    choice: RimZeroChoice,
    scale: &ScaleReport,
    disk: &DiskParams,
) -> Option<SideViewRim> {
    match choice {
        RimZeroChoice::Motion => scale.side_view_rim(disk),
        RimZeroChoice::Rest => None,
    }
}

/// The strip angles β \[rad\] of a two-view clip's frames (NaN: no strip), as the
/// signal stage reads them; `None` for a side view.
pub(super) fn strip_angles(frames: &[FrameRecord], two_view: bool) -> Option<Vec<f64>> {
    two_view.then(|| {
        frames
            .iter()
            .map(|f| f.beta_raw.unwrap_or(f64::NAN))
            .collect()
    })
}

/// The frames' capture times \[s\] and rim heights z_rim \[m\] (NaN: no edge), as the
/// signal stage reads them.
pub(super) fn rim_series(frames: &[FrameRecord]) -> (Vec<f64>, Vec<f64>) {
    series_of(frames, |f| f.z_rim_m)
}

/// Each frame's capture time \[s\] and z_rim \[px\] (NaN with no edge).
pub(super) fn rim_series_px(frames: &[FrameRecord]) -> (Vec<f64>, Vec<f64>) {
    series_of(frames, |f| f.z_rim_px)
}

/// The frames' capture times \[s\] and one reading of each (NaN where it is missing).
fn series_of(
    frames: &[FrameRecord],
    reading: impl Fn(&FrameRecord) -> Option<f64>,
) -> (Vec<f64>, Vec<f64>) {
    let t = frames.iter().map(|f| f.t_capture).collect();
    let z = frames
        .iter()
        .map(|f| reading(f).unwrap_or(f64::NAN))
        .collect();
    (t, z)
}

/// The signal stage's settings for a clip measured at `metres_per_px`.
pub(super) fn signal_config(window_s: f64, metres_per_px: f64) -> SignalConfig {
    SignalConfig {
        window_s,
        // The rim is located to about 0.01 px on lossless frames (the edge, and
        // the gap's darkness below 2 px), so a clean rest tail can have almost no
        // spread: floor the noise at 0.02 px (motion from 0.1 px on), and ask a
        // peak to stand 0.2 px above its surroundings.
        noise_floor: 0.02 * metres_per_px,
        min_prominence: 0.2 * metres_per_px,
        ..SignalConfig::default()
    }
}

/// A signal-stage failure of `clip`. A slow-motion clip stored at a playback rate
/// (24–60 fps, below 100) with no `fps` in the config is timed 8× too slow: its
/// rest tail, motion and peaks all look wrong, and the frame rate is the probable
/// cause, so it is named first.
pub(super) fn signal_error(clip: &Path, fps: &CaptureFps, error: SignalError) -> AnalyseError {
    let stored_rate = matches!(
        fps.source,
        footage::FpsSource::ContainerFps | footage::FpsSource::ContainerTimestamps
    );
    if stored_rate && fps.fps < 100.0 {
        return AnalyseError::Clip {
            path: clip.to_path_buf(),
            reason: format!(
                "probably the frame rate: the clip is stored at {:.2} fps and no `fps` is \
                 configured; if it was filmed in slow motion, set `fps` (e.g. fps = 480) in \
                 eulerdisk.toml or the clip's own .toml. The analysis said: {error}",
                fps.fps
            ),
        };
    }
    AnalyseError::Signal {
        path: clip.to_path_buf(),
        error,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two frames counted missing on a first pass (positions 100 and 380, so the
    /// capture clock runs one period ahead from 100 and two from 380), and a
    /// duplicated frame at 50. A law places the halt at position 390: the step at
    /// 380, whose test spans 1.5 turns either side (9.4 frames at 1 rad a frame),
    /// lies closer to it than two such spans (18.8 frames) and is withdrawn; the one
    /// at 100 stays.

    #[test]
    fn a_drop_counted_on_still_pictures_is_withdrawn_at_the_laws_halt() {
        let period = 1.0 / 480.0;
        let true_t = |k: usize| k as f64 * period;
        let drops_before = |k: usize| usize::from(k >= 100) + usize::from(k >= 380);
        let mut frames: Vec<FrameRecord> = (0..420)
            .map(|k| FrameRecord {
                index: k,
                t_capture: true_t(k) + drops_before(k) as f64 * period,
                t: 0.0,
                container_time_s: None,
                picture_type: None,
                z_rim_px: None,
                camera_shift_px: None,
                z_rim_m: None,
                beta_raw: None,
            })
            .collect();
        let step = |index| signal::FrameFlag {
            index,
            t: 0.0,
            reason: signal::SkipReason::RimPhaseStep {
                phase_step: 1.0,
                statistic: 100.0,
                timing: Some(signal::TimingStep {
                    step_s: -period,
                    se_s: 0.1 * period,
                    points: 24,
                    confirmed: true,
                }),
            },
        };
        let duplicate = signal::FrameFlag {
            index: 50,
            t: 0.0,
            reason: signal::SkipReason::DuplicatedFrame {
                step: 0.1,
                neighbours: 1.0,
            },
        };
        let mut known = vec![duplicate.clone(), step(100), step(380)];
        let halt = frames[390].t_capture;
        let shifted: Vec<f64> = frames.iter().map(|f| f.t_capture - halt).collect();
        let withdrawn = withdraw_hidden_drops(&mut frames, &mut known, &shifted, period);
        assert_eq!(withdrawn, vec![380]);
        assert_eq!(known, vec![duplicate, step(100)]);
        for (k, f) in frames.iter().enumerate() {
            let want = true_t(k) + usize::from(k >= 100) as f64 * period;
            assert!(
                (f.t_capture - want).abs() < 1e-12,
                "frame {k}: {}",
                f.t_capture
            );
        }
        // Nothing is left to withdraw at that halt.
        assert!(withdraw_hidden_drops(&mut frames, &mut known, &shifted, period).is_empty());
    }

    /// A rim turning every 10 frames (480 fps, 0.1 mm/px) down to the halt at frame
    /// 300, then still: a frame marked repeated in the motion stays out of the fits; one
    /// marked 50 frames after the halt (a refresh of the still picture) gets its
    /// reading back and is no repeat.
    #[test]
    fn only_frames_in_motion_are_repeats() {
        let metres_per_px = 1e-4;
        let mut frames: Vec<FrameRecord> = (0..420)
            .map(|k| {
                let x = k as f64;
                let lift = if k < 300 {
                    4.0 * (1.0 - x / 300.0) * (std::f64::consts::PI * x / 10.0).sin().abs()
                } else {
                    0.02 * (1.7 * x).sin()
                };
                FrameRecord {
                    index: k,
                    t_capture: x / 480.0,
                    t: 0.0,
                    container_time_s: None,
                    picture_type: None,
                    z_rim_px: Some(lift),
                    camera_shift_px: None,
                    z_rim_m: Some(lift * metres_per_px),
                    beta_raw: None,
                }
            })
            .collect();
        let marked = |index| footage::RepeatedFrame {
            index,
            kind: footage::RepeatKind::Interpolated,
            statistic: 0.1,
            neighbours: 1.0,
            noise: 0.1,
        };
        let repeated = vec![marked(150), marked(350)];
        let set_aside: Vec<_> = repeated
            .iter()
            .map(|r| {
                let record = &mut frames[r.index];
                record.z_rim_m = None;
                (record.z_rim_px.take(), None)
            })
            .collect();
        let in_motion = repeats_in_motion(
            &mut frames,
            repeated,
            set_aside,
            &signal_config(0.5, metres_per_px),
            metres_per_px,
        );
        assert_eq!(in_motion.iter().map(|r| r.index).collect::<Vec<_>>(), [150]);
        assert_eq!(frames[150].z_rim_px, None);
        let back = 0.02 * (1.7f64 * 350.0).sin();
        assert_eq!(frames[350].z_rim_px, Some(back));
        assert_eq!(frames[350].z_rim_m, Some(back * metres_per_px));
    }
}
