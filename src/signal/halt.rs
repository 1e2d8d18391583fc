//! The halt time t_φ (thesis §3.2.4, §3.3.2): the last frame whose rim height rises
//! above its rest level by more than the noise measured after the halt.
//!
//! A disk that has fallen flat does not rise again, and before that its rim rises
//! once per precession turn, a turn that shortens towards the halt (to a few ms at
//! 480 fps), with an amplitude that only decays. So a span with no rise as long as
//! the rest tail, or as three of the final turns (two turns missed, whatever the
//! sampling's phase), means the disk lies flat or moves below the threshold for good:
//! t_φ is the last rise before the first such span, and a later lone excursion
//! (an H.264 refresh of the still picture tens of frames on, read up to 0.15 px high)
//! is noise, not motion resumed. Nor is a picture held level for most of a final turn
//! and repeating an earlier reading, whatever its height: the rim comes down to the
//! plate every turn, and an encoder may show an earlier picture again for several
//! frames after the halt. After its last rise the rim comes down to the plate: the
//! frames that continue that descent above both the rest level and the still picture
//! that follows them (by more than the noise σ, not necessarily the threshold) are
//! motion too.
//!
//! A still picture is not motion at any height: the rim comes down to the plate once
//! a turn, so a run of more than [`STILL_READINGS`] readings (more than the final
//! turns at 480 fps) that stays level is not the rim moving. An encoder may redraw a
//! still disk in steps and hold each picture for many frames (I and P pictures
//! only, a drifting disk: some 30 frames held 1.5 thresholds above the later rest,
//! from a few frames after the halt into the rest tail); a reading that begins or
//! ends such a run ([`in_still_picture`]) is no rise. Shorter holds need more evidence
//! ([`held`]).
//!
//! Motion is one-sided: the rim of a rolling disk is never below its rest on the plate
//! (z_rim = R sin φ (1 + cos χ) ≥ 0, see the module docs of `signal`), so a reading
//! below the rest level is measurement noise, however large. On H.264 footage of a
//! still disk, the frames where the encoder refreshes the picture read the edge up to
//! 0.2 px low (14 σ of the copied frames around them) on the light-plate fixture.

use super::{SignalConfig, SignalError, finite_samples};
use crate::numeric::{mad_sigma, median};
use serde::{Deserialize, Serialize};

/// The halt of the rim motion, t_φ, and the noise it was measured against.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Halt {
    /// Index of the last frame with rim motion (in the caller's series).
    pub index: usize,
    /// t_φ on the caller's time axis \[s\]: that frame's time, or where
    /// [`SignalConfig::halt_at`] places the halt.
    pub t_phi: f64,
    /// Rest level of z_rim after the halt (median of the rest tail) \[m\].
    pub rest_level: f64,
    /// Noise σ of z_rim at rest (robust: a 3σ-clipped RMS started from the MAD), at
    /// least [`SignalConfig::noise_floor`] \[m\].
    pub noise: f64,
    /// Motion threshold: a frame moves if z_rim − rest level exceeds it \[m\].
    pub threshold: f64,
    /// Frames after t_φ with a rim height (the rest tail the noise came from).
    pub rest_frames: usize,
    /// Times shifted so that the halt is t = 0 (t − t_φ) \[s\], one per input frame.
    pub shifted_t: Vec<f64>,
    /// Whether [`SignalConfig::motion_until`] cut the motion: without it a later
    /// frame is motion, so the frames after the last one are no rest.
    #[serde(default)]
    pub motion_cut: bool,
}

impl Halt {
    /// The time of the last frame of motion seen, on the clock that starts at t_φ \[s\]
    /// (0 unless [`SignalConfig::halt_at`] placed t_φ elsewhere).
    pub fn last_motion_seen(&self) -> f64 {
        self.shifted_t[self.index]
    }
}

/// Lags over which the rest tail is checked for oscillation.
const MAX_LAG: usize = 24;
/// Autocorrelation above which a tail oscillates instead of resting: white noise of
/// 48 samples gives |r| < 0.6 at 4 standard errors (1/√48 ≈ 0.14).
const OSCILLATION_CORRELATION: f64 = 0.6;
/// The autocorrelation at half a period of an oscillation whose full-period
/// correlation exceeds [`OSCILLATION_CORRELATION`] is below −0.6 (a sinusoid in white
/// noise has r(T/2) = −r(T)); a correlated still tail of 48 samples stays above
/// −0.45 (3 standard errors).
const OSCILLATION_TROUGH: f64 = -0.45;
/// The motion threshold is at least the band of the still disk (thesis fig. 3.22: the
/// largest |z_rim − rest| over the later half of the rest tail) times this. Gaussian
/// noise keeps the band near 2.5 σ, below the `motion_sigmas` threshold; H.264 codes
/// most frames of a still disk as copies (σ of 0.02 px on light-plate renders with
/// sensor noise) and refreshes a few, which read up to 0.2 px off: the band covers
/// those.
const BAND_WIDENING: f64 = 1.5;
/// The most new readings in a run of risen frames in the rest tail that is still read
/// as a codec refresh rather than a disk moving at the clip's end: a refresh redraws
/// the picture in one frame, and the next may still carry part of it.
const REFRESH_FRAMES: usize = 2;
/// Turns over which the final precession period is taken (the median interval).
const PERIOD_TURNS: usize = 3;
/// A span without a rise this many final turns long ends the motion (below the rest
/// tail's span): the oscillation's amplitude only decays towards the halt, so once
/// it has stayed below the threshold for whole turns, a later rise is the codec's or
/// the sensor's, not the disk's. Two turns missed, with the sampling's phase: three
/// periods from one rise to the next.
const MISSED_TURNS: f64 = 3.0;
/// Fraction of the final turn over which a level run of readings is a held picture,
/// not the rim's motion ([`held`]).
const HELD_TURN_FRACTION: f64 = 0.75;
/// Pictures an H.264 decoder keeps for reference (the standard's largest list): a
/// held picture repeats one of them.
const REFERENCE_PICTURES: usize = 16;
/// Two readings this fraction of the noise σ apart or closer are one picture read
/// twice ([`held`]): distinct pictures under sensor noise differ by about σ√2, while
/// a codec's copy read at another frame's light gain (flicker) moves by about 1e-5 px
/// at σ 0.05 px, 2e-4 σ.
const COPY_FRACTION: f64 = 1e-3;
/// Noise σ by which every reading of a level window must clear the motion threshold
/// for the level to be a held picture without a repeated reading ([`held`]): well
/// beyond the noise, so that motion too small to resolve, read near the threshold,
/// stays motion.
pub(crate) const RESOLVED_SIGMAS: f64 = 4.0;
/// Readings beyond its own that a level run needs to be a still picture
/// ([`in_still_picture`]): more than the final turns at 480 fps (5–7 frames), and as
/// many as make a rest tail.
const STILL_READINGS: usize = MIN_REST_FRAMES;
/// Re-measurements of the rest segment before t_φ is taken as settled.
const MAX_HALT_ITERATIONS: usize = 8;
/// Fewest rim heights a rest tail needs to measure its noise.
pub(crate) const MIN_REST_FRAMES: usize = 8;

/// Finds t_φ from per-frame times `t` \[s\] and rim heights `z_rim` \[m\] (NaN where a
/// frame has no edge).
///
/// 1. The rest tail is the last [`SignalConfig::rest_tail_s`] seconds. Its median is
///    the rest level; its noise σ is the RMS of the deviations within 3σ, σ started
///    from 1.4826 × MAD (floored at `noise_floor`); the motion threshold is
///    `motion_sigmas` × σ, and at least [`BAND_WIDENING`] × the band of the still
///    disk.
/// 2. The tail must be at rest: no rise in it above the threshold (a reading that
///    begins or ends a still picture, [`in_still_picture`], is none) but one short run
///    (at most [`REFRESH_FRAMES`] new readings, a codec refresh), and no
///    oscillation (autocorrelation below −0.45 at some lag and above 0.6 at a
///    later one, up to 24 frames, at which the readings do not repeat as the
///    encoder's frame-type cadence does, checked when the tail's spread exceeds
///    twice `noise_floor`).
/// 3. t_φ is the last frame of motion, the last rise before the first span with
///    none as long as `rest_tail_s` or [`MISSED_TURNS`] final turns (the median
///    interval of the last [`PERIOD_TURNS`] turns' peaks; module docs) and holding
///    [`MIN_REST_FRAMES`] readings, where a rise that repeats an earlier reading
///    exactly (a reference picture shown again, [`repeated`]) within
///    [`RESOLVED_SIGMAS`] σ of the threshold, or lies inside a picture held level
///    for [`HELD_TURN_FRACTION`] of the final turn ([`held`]), is no rise; the
///    noise is then re-measured over every frame after t_φ but those of still
///    pictures above the threshold, the threshold raised to
///    [`BAND_WIDENING`] × the deepest reading below the rest level there (noise: the
///    rim is never below its rest) and × the highest reading more than that span
///    after t_φ (noise: a flat disk does not rise again), and t_φ found again, until
///    it settles.
/// 4. t_φ then follows the final descent: each next frame that lies lower than the
///    one before and more than σ above both the rest level and the rest right after
///    it (the median of the next [`MIN_REST_FRAMES`] readings) is still motion,
///    unless it is a rise inside a held picture (a repeated reading may be motion
///    here: a descent is no rise).
///
/// With [`SignalConfig::motion_until`] set, no frame after it is motion in steps 3
/// and 4 (a law of the motion fitted to the clip has the disk flat by then), and
/// [`Halt::motion_cut`] says whether that moved the last frame of motion. With
/// [`SignalConfig::halt_at`] set, t_φ is that time and the last frame of motion
/// only marks where the rest tail begins.
///
/// Errors: [`SignalError::RestTailTooShort`], [`SignalError::TailNotAtRest`],
/// [`SignalError::TailOscillates`], [`SignalError::NoMotion`], or invalid input.
pub fn halt_time(t: &[f64], z_rim: &[f64], config: &SignalConfig) -> Result<Halt, SignalError> {
    super::check_series(t, z_rim, "z_rim")?;
    config.validate()?;
    let series = RimSeries::new(t, z_rim, config);
    let tail = series.rest_tail()?;
    series.check_tail_settled(&tail)?;
    series.check_tail_not_oscillating(&tail)?;
    let Some(first_guess) = series.last_motion(tail.rest) else {
        return Err(SignalError::NoMotion {
            threshold: tail.rest.threshold,
            max_deviation: series.max_deviation(tail.rest.level),
        });
    };
    let (motion, rest) = series.settle(first_guess, tail.rest, tail.band);
    let index = series.follow_descent(&motion, rest);
    let t_phi = config.halt_at.unwrap_or(t[index]);
    Ok(Halt {
        index,
        t_phi,
        rest_level: rest.level,
        noise: rest.noise,
        threshold: rest.threshold,
        rest_frames: series.samples.iter().filter(|&&i| i > index).count(),
        shifted_t: t.iter().map(|&x| x - t_phi).collect(),
        motion_cut: motion_cut(t, z_rim, config, index),
    })
}

/// Whether [`SignalConfig::motion_until`] cut the motion: without it, the last frame
/// of motion found would lie after `index`.
fn motion_cut(t: &[f64], z_rim: &[f64], config: &SignalConfig, index: usize) -> bool {
    let unbounded = SignalConfig {
        motion_until: None,
        ..config.clone()
    };
    config.motion_until.is_some()
        && halt_time(t, z_rim, &unbounded).is_ok_and(|free| free.index > index)
}

/// The rest about which motion is measured: a frame moves if its rim height stands
/// more than `threshold` above `level`.
#[derive(Debug, Clone, Copy)]
struct Rest {
    /// Rest level of z_rim (a median) \[m\].
    level: f64,
    /// Noise σ of z_rim at rest \[m\].
    noise: f64,
    /// Motion threshold over the rest level \[m\].
    threshold: f64,
}

/// The rest tail at the end of the clip (step 1 of [`halt_time`]).
struct RestTail {
    /// Time at which the tail begins \[s\].
    start: f64,
    /// The frames of the tail with a rim height.
    frames: Vec<usize>,
    /// Its level, noise and threshold.
    rest: Rest,
    /// [`BAND_WIDENING`] × the band of the still disk over the later half of the tail
    /// \[m\]: a floor of every threshold.
    band: f64,
}

/// The last frame of motion found by one search (step 3 of [`halt_time`]).
#[derive(Debug, Clone, Copy)]
struct LastMotion {
    /// The frame index of the last rise.
    index: usize,
    /// The span without a rise that ended the motion \[s\].
    span: f64,
    /// The final precession turn, once enough turns' peaks were seen \[s\].
    period: Option<f64>,
}

/// A rim-height series and the rules that tell the rim's motion from rest in it.
struct RimSeries<'a> {
    t: &'a [f64],
    z_rim: &'a [f64],
    config: &'a SignalConfig,
    /// The frames with a rim height, in order.
    samples: Vec<usize>,
    /// The position of each frame's reading in `samples` (`usize::MAX` where none).
    position: Vec<usize>,
    /// No frame after this time is motion: after [`SignalConfig::motion_until`] the
    /// energy law has the disk flat.
    until: f64,
}

impl<'a> RimSeries<'a> {
    fn new(t: &'a [f64], z_rim: &'a [f64], config: &'a SignalConfig) -> Self {
        let samples = finite_samples(t, z_rim);
        let mut position = vec![usize::MAX; t.len()];
        for (n, &i) in samples.iter().enumerate() {
            position[i] = n;
        }
        RimSeries {
            t,
            z_rim,
            config,
            samples,
            position,
            until: config.motion_until.unwrap_or(f64::INFINITY),
        }
    }

    /// Whether frame `i` begins or ends a still picture ([`in_still_picture`]), level
    /// within half the threshold.
    fn still(&self, i: usize, threshold: f64) -> bool {
        in_still_picture(&self.samples, self.z_rim, self.position[i], 0.5 * threshold)
    }

    /// Whether frame `i` stands above the threshold over the rest level.
    fn risen(&self, i: usize, rest: Rest) -> bool {
        self.z_rim[i] - rest.level > rest.threshold
    }

    /// Whether frame `i` has risen and is no still picture.
    fn moving(&self, i: usize, rest: Rest) -> bool {
        self.risen(i, rest) && !self.still(i, rest.threshold)
    }

    /// Whether frame `i` is moving and not after [`SignalConfig::motion_until`].
    fn motion(&self, i: usize, rest: Rest) -> bool {
        self.t[i] <= self.until && self.moving(i, rest)
    }

    /// Whether the reading at position `n` of `samples` is in a held picture over the
    /// final turn `period` ([`held`]).
    fn in_held_picture(&self, n: usize, period: f64, rest: Rest) -> bool {
        held(
            &self.samples,
            self.t,
            self.z_rim,
            n,
            period,
            rest.level,
            rest.threshold,
            rest.noise,
            self.config.quantum,
        )
    }

    /// The largest rise of any reading over `level` (0 if none rises) \[m\].
    fn max_deviation(&self, level: f64) -> f64 {
        self.samples
            .iter()
            .map(|&i| self.z_rim[i] - level)
            .fold(0.0, f64::max)
    }

    /// Step 1: the last [`SignalConfig::rest_tail_s`] seconds, their level, noise and
    /// threshold. The threshold is `motion_sigmas` σ, and at least the band of fig.
    /// 3.22 over the later half of the tail, widened by half ([`BAND_WIDENING`]).
    fn rest_tail(&self) -> Result<RestTail, SignalError> {
        let (t, z_rim, config) = (self.t, self.z_rim, self.config);
        let start = t[t.len() - 1] - config.rest_tail_s;
        let frames: Vec<usize> = self
            .samples
            .iter()
            .copied()
            .filter(|&i| t[i] >= start)
            .collect();
        if frames.len() < MIN_REST_FRAMES {
            return Err(SignalError::RestTailTooShort {
                tail_s: config.rest_tail_s,
                frames: frames.len(),
                needed: MIN_REST_FRAMES,
            });
        }
        let (level, noise) = rest_statistics(z_rim, &frames, config.noise_floor);
        let later = &frames[frames.len() / 2..];
        let band = BAND_WIDENING
            * later
                .iter()
                .map(|&i| (z_rim[i] - level).abs())
                .fold(0.0, f64::max);
        let threshold = (config.motion_sigmas * noise).max(band);
        Ok(RestTail {
            start,
            frames,
            rest: Rest {
                level,
                noise,
                threshold,
            },
            band,
        })
    }

    /// Step 2, the rises: a disk still moving at the clip's end lifts its rim once a
    /// turn, turn after turn, or holds it up, so the tail is refused for rises in two
    /// runs or more, or in one run of more than [`REFRESH_FRAMES`] readings. A frame
    /// that repeats the previous frame's reading exactly is the codec's copy of that
    /// picture (a moving rim, or a still one under sensor noise, never reads the same
    /// twice), no new reading: at coarse quantisers a still disk's picture is redrawn
    /// every 20–30 frames and held, 0.25 px up or down, in between. One short run
    /// alone is such a redraw, which the halt then measures as noise.
    ///
    /// A short run whose readings just before and just after it lie in the still band
    /// (within half the threshold of the rest level) is an impulse: the picture
    /// redrawn in one frame and back at rest in the next, as H.264 does again and
    /// again under a darker tone curve (single frames 0.2–0.3 px up, their neighbours
    /// within 0.03 px). A rim that lifts is smooth over the final turn's frames and
    /// is not back at rest in one frame; impulses are not counted among the runs.
    fn check_tail_settled(&self, tail: &RestTail) -> Result<(), SignalError> {
        let (z_rim, rest) = (self.z_rim, tail.rest);
        let runs = rise_runs(&tail.frames, |i| self.moving(i, rest));
        let readings = |run: &[usize]| {
            run.iter()
                .filter(|&&i| i == 0 || z_rim[i] != z_rim[i - 1])
                .count()
        };
        let at_rest = |n: Option<usize>| {
            n.and_then(|n| self.samples.get(n))
                .is_some_and(|&i| (z_rim[i] - rest.level).abs() <= 0.5 * rest.threshold)
        };
        let impulse = |run: &[usize]| {
            let (first, last) = (self.position[run[0]], self.position[run[run.len() - 1]]);
            readings(run) <= REFRESH_FRAMES
                && at_rest(first.checked_sub(1))
                && at_rest(Some(last + 1))
        };
        let lifts = runs.iter().filter(|run| !impulse(run)).count();
        if lifts > 1 || runs.iter().any(|run| readings(run) > REFRESH_FRAMES) {
            let i = *runs.last().and_then(|run| run.last()).expect("a rise");
            return Err(SignalError::TailNotAtRest {
                tail_start: tail.start,
                t_moving: self.t[i],
                deviation: z_rim[i] - rest.level,
                threshold: rest.threshold,
            });
        }
        Ok(())
    }

    /// Step 2, the oscillation ([`oscillation`]). A correlated tail whose spread stays
    /// within twice the noise floor is codec or sensor texture on a still frame, not
    /// a disk still rocking, and is not checked.
    fn check_tail_not_oscillating(&self, tail: &RestTail) -> Result<(), SignalError> {
        let (z_rim, Rest { level, noise, .. }) = (self.z_rim, tail.rest);
        let oscillating = noise > 2.0 * self.config.noise_floor;
        let Some((lag, correlation)) =
            oscillation(z_rim, &tail.frames, level, noise).filter(|_| oscillating)
        else {
            return Ok(());
        };
        let frames = &tail.frames;
        let rms = (frames
            .iter()
            .map(|&i| (z_rim[i] - level).powi(2))
            .sum::<f64>()
            / frames.len() as f64)
            .sqrt();
        Err(SignalError::TailOscillates {
            tail_start: tail.start,
            lag,
            correlation,
            rms,
        })
    }

    /// Step 3, one search: the last frame of motion, the last rise before the first
    /// span without one that is as long as the rest tail or as [`MISSED_TURNS`] turns
    /// (module docs: a disk lying flat does not rise again, and a decaying oscillation
    /// that stays below the threshold for whole turns does not rise above it again
    /// either). `None` if no frame moves.
    fn last_motion(&self, rest: Rest) -> Option<LastMotion> {
        let (t, z_rim, samples) = (self.t, self.z_rim, &self.samples);
        let first = samples.iter().position(|&i| self.motion(i, rest))?;
        // The last rise, as a position in `samples` and as a frame index.
        let (mut last_n, mut last) = (first, samples[first]);
        // The times of the turns' peaks so far: a rise higher than its neighbours that
        // stands more than the threshold above the lowest reading since the last one.
        let mut turns: Vec<f64> = Vec::new();
        let mut low = rest.level;
        let span = |turns: &[f64]| {
            turn_period(turns).map_or(self.config.rest_tail_s, |p| {
                (MISSED_TURNS * p).min(self.config.rest_tail_s)
            })
        };
        for (n, &i) in samples.iter().enumerate().skip(first + 1) {
            if self.no_rise(n, rest, &turns) {
                low = low.min(z_rim[i]);
                continue;
            }
            // A gap ends the motion when it lasts the span and holds readings enough to
            // show it (a run of frames without an edge is no evidence of rest).
            let readings = n - last_n - 1;
            if t[i] - t[last] >= span(&turns) && readings >= MIN_REST_FRAMES {
                break;
            }
            let before = z_rim[samples[n - 1]];
            let after = samples.get(n + 1).map_or(f64::NEG_INFINITY, |&j| z_rim[j]);
            if z_rim[i] >= before && z_rim[i] > after && z_rim[i] - low > rest.threshold {
                turns.push(t[i]);
                low = z_rim[i];
            } else {
                low = low.min(z_rim[i]);
            }
            (last_n, last) = (n, i);
        }
        Some(LastMotion {
            index: last,
            span: span(&turns),
            period: final_turn(&turns),
        })
    }

    /// Whether the reading at position `n` of `samples` is no rise for the search of
    /// step 3: no motion, or a rise that repeats an earlier reading exactly (a
    /// reference picture shown again, [`repeated`]) within [`RESOLVED_SIGMAS`] σ of
    /// the threshold, or one inside a picture held level for [`HELD_TURN_FRACTION`]
    /// of the final turn of the peaks `turns` so far ([`held`]).
    fn no_rise(&self, n: usize, rest: Rest, turns: &[f64]) -> bool {
        let i = self.samples[n];
        let copy = repeated(
            &self.samples,
            self.z_rim,
            n,
            rest.noise,
            self.config.quantum,
        ) && self.z_rim[i] - rest.level <= rest.threshold + RESOLVED_SIGMAS * rest.noise;
        !self.motion(i, rest)
            || copy
            || final_turn(turns).is_some_and(|p| self.in_held_picture(n, p, rest))
    }

    /// Step 3, the iteration: the rest re-measured over the whole rest segment after
    /// the last frame of motion found, and that frame found again with it, until it
    /// stays put (at most [`MAX_HALT_ITERATIONS`] times). Returns the settled last
    /// motion and the rest of the last measurement.
    fn settle(&self, first_guess: LastMotion, rest: Rest, band: f64) -> (LastMotion, Rest) {
        let (mut motion, mut rest) = (first_guess, rest);
        for _ in 0..MAX_HALT_ITERATIONS {
            rest = self.remeasure_rest(&motion, rest, band);
            let next = self.last_motion(rest).unwrap_or(motion);
            if next.index == motion.index {
                break;
            }
            motion = next;
        }
        (motion, rest)
    }

    /// The rest measured over every frame after the last motion, but for still
    /// pictures held above the rest (module docs): they are the codec's, not the
    /// noise about the rest, and when they make up a third of the segment they would
    /// raise the noise and the level, then the threshold, move t_φ earlier and take
    /// the final turns into the segment in turn.
    ///
    /// The rim is never below its rest, so every reading below the rest level in
    /// that segment is noise: the deepest one, widened as the tail's `band` is,
    /// bounds the noise's own excursions (H.264 refresh frames, 4–6 σ of the copied
    /// frames, in either direction) wherever they fall in the segment, not only in
    /// the tail. A frame more than the span that ends the motion after t_φ is rest by
    /// the definition of t_φ (a disk lying flat does not rise again), so its rise, a
    /// lone excursion above the threshold included, is noise too.
    fn remeasure_rest(&self, motion: &LastMotion, previous: Rest, band: f64) -> Rest {
        let (t, z_rim) = (self.t, self.z_rim);
        let frames: Vec<usize> = self
            .samples
            .iter()
            .copied()
            .filter(|&i| {
                i > motion.index && !(self.risen(i, previous) && self.still(i, previous.threshold))
            })
            .collect();
        let (level, noise) = rest_statistics(z_rim, &frames, self.config.noise_floor);
        let below = BAND_WIDENING * frames.iter().map(|&i| level - z_rim[i]).fold(0.0, f64::max);
        let lone = BAND_WIDENING
            * frames
                .iter()
                .filter(|&&i| {
                    t[i] - t[motion.index] >= motion.span && !self.still(i, previous.threshold)
                })
                .map(|&i| z_rim[i] - level)
                .fold(0.0, f64::max);
        let threshold = (self.config.motion_sigmas * noise)
            .max(band)
            .max(below)
            .max(lone);
        Rest {
            level,
            noise,
            threshold,
        }
    }

    /// Step 4: the last frame of motion after the final descent. The last rise is the
    /// last peak or a frame on its way up; the rim then comes down to the plate, and
    /// frames that continue that descent by more than the noise above the rest level
    /// are motion still, below the threshold or not (under flicker the rest noise is
    /// large: a descent of 0.33 and 0.22 px after a 1.23 px peak lies under a 5σ
    /// threshold of 0.9 px, yet is the rim coming down). They must stand as far above
    /// the picture right after them too (the median of the next [`MIN_REST_FRAMES`]
    /// readings): an encoder settles on a still disk over many frames, so its first
    /// still pictures may read the edge above the later level by more than σ (about
    /// 3 σ), and the frames after them read the same. Against that median alone,
    /// white noise would extend the descent more often (its own noise adds to the
    /// test's).
    fn follow_descent(&self, motion: &LastMotion, rest: Rest) -> usize {
        let (t, z_rim, samples) = (self.t, self.z_rim, &self.samples);
        let mut index = motion.index;
        while let Some(n) = samples
            .iter()
            .position(|&i| i > index && t[i] <= self.until)
        {
            let next = samples[n];
            // A rise that the search took for a held picture is no descent either (a
            // repeated reading may be: the decoder may show a picture again while the
            // rim comes down, repeating a reading two frames back to 1e-8 px a frame
            // before the halt, at the true height of the descent).
            if self.moving(next, rest)
                && motion
                    .period
                    .is_some_and(|p| self.in_held_picture(n, p, rest))
            {
                break;
            }
            let after: Vec<f64> = samples[n + 1..]
                .iter()
                .take(MIN_REST_FRAMES)
                .map(|&i| z_rim[i])
                .collect();
            let still = if after.is_empty() {
                rest.level
            } else {
                median(&after).max(rest.level)
            };
            if z_rim[next] - still > rest.noise && z_rim[next] < z_rim[index] {
                index = next;
            } else {
                break;
            }
        }
        index
    }
}

/// Whether the reading at position `n` of `samples` belongs to a held picture: some
/// window of consecutive readings that contains it and spans at least
/// [`HELD_TURN_FRACTION`] of the final turn `period` \[s\] has all its readings
/// within half the motion `threshold` of each other, and either one of them repeats
/// one of the [`REFERENCE_PICTURES`] readings before it ([`repeated`]; in the window
/// or before it), or all of them stand more than [`RESOLVED_SIGMAS`] σ above the
/// threshold over the rest `level`.
///
/// The rim of a rolling disk comes down to the plate once a turn, z_rim = R sin φ
/// (1 + cos χ): three quarters of a turn sampled at least four times a turn, at any
/// phase, hold a reading within 45° of the peak and one within 45° of the trough,
/// which differ by at least 0.85 × (peak − trough), near the threshold for a turn
/// whose peak rises above it and well over half of it. A span of readings that
/// stays level for that long does not show the rim moving: either one picture is
/// shown again, as an encoder may after the halt (five or six frames held at
/// 0.4–0.55 px, some after the disk lay flat, repeating a near-contact frame several
/// frames before to 1e-5 px), or the motion is too small to
/// resolve (a two-view render whose last turns rock by 0.15 px at a 0.1 px
/// threshold reads 0.10–0.12 px, all distinct, for five frames before the halt).
/// A repeated reading tells the first: a moving rim, or a still one under sensor
/// noise, never reads the same twice. So does a level that every reading holds
/// clearly above the threshold: motion that high is resolved, and would swing by
/// 0.85 of its peak, more than 0.85 of the threshold, within a window whose
/// readings spread by less than half of it. An encoder that shows an earlier
/// picture again with the light's flicker coded over it repeats no reading exactly
/// (0.33–0.40 px for five frames after the disk lay flat, at a 0.16 px threshold and
/// σ 0.02 px). The final turn is the shortest of the last ones ([`final_turn`]): the
/// turn shortens towards the halt, and the median that sizes the span ending the
/// motion lags it (7 frames against a last turn of 5).
#[allow(clippy::too_many_arguments)]
fn held(
    samples: &[usize],
    t: &[f64],
    z: &[f64],
    n: usize,
    period: f64,
    level: f64,
    threshold: f64,
    noise: f64,
    quantum: Option<f64>,
) -> bool {
    let span = HELD_TURN_FRACTION * period;
    let time = |m: usize| t[samples[m]];
    let level_over = |a: usize, b: usize| spread(&samples[a..=b], z) < 0.5 * threshold;
    // Some reading of the window repeats an earlier one, in it or among the
    // encoder's references before it.
    let copied = |a: usize, b: usize| (a..=b).any(|m| repeated(samples, z, m, noise, quantum));
    // Every reading of the window clearly above the threshold.
    let resolved = |a: usize, b: usize| {
        samples[a..=b]
            .iter()
            .all(|&i| z[i] - level > threshold + RESOLVED_SIGMAS * noise)
    };
    for a in (0..=n).rev() {
        // The shortest window from `a` that spans the fraction of a turn and holds n.
        let Some(b) = (n..samples.len()).find(|&b| time(b) - time(a) >= span) else {
            continue;
        };
        if level_over(a, b) && (copied(a, b) || resolved(a, b)) {
            return true;
        }
        if time(n) - time(a) >= span {
            break;
        }
    }
    false
}

/// Whether the reading at position `n` of `samples` repeats one of the
/// [`REFERENCE_PICTURES`] readings before it to [`COPY_FRACTION`] of the `noise` σ
/// (never for readings on whole pixels, [`SignalConfig::quantum`]): the
/// decoder showed a picture it holds for reference again. A moving rim, or a still
/// one under sensor noise, never reads the same twice; an encoder shows a picture
/// again where the frame differs from it by less than its quantiser resolves, so the
/// copy says only that the rim is near the copied height. Near the threshold that is
/// no evidence of motion (at a coarse quantiser with B pictures, P pictures after the
/// halt repeat a reading just over the threshold between B pictures read at rest, so
/// no span of them is level; taken as rises they would put t_φ several frames late,
/// on the last copy, and make that copy a spurious peak). Well above it, it is (a
/// copy 0.31 px over the rest level at a 0.10 px threshold, σ 0.02 px, is the rim
/// still up, within 0.04 px of its true height).
fn repeated(samples: &[usize], z: &[f64], n: usize, noise: f64, quantum: Option<f64>) -> bool {
    quantum.is_none()
        && (n.saturating_sub(REFERENCE_PICTURES)..n)
            .any(|j| (z[samples[n]] - z[samples[j]]).abs() <= COPY_FRACTION * noise)
}

/// The precession turn near the end of the motion: the median interval between the
/// last [`PERIOD_TURNS`] + 1 turns' peaks (each turn lifts the rim once), or `None`
/// before there are that many.
fn turn_period(peaks: &[f64]) -> Option<f64> {
    let recent = peaks.get(peaks.len().checked_sub(PERIOD_TURNS + 1)?..)?;
    let intervals: Vec<f64> = recent.windows(2).map(|w| w[1] - w[0]).collect();
    Some(median(&intervals))
}

/// The final precession turn: the shortest interval between the last
/// [`PERIOD_TURNS`] + 1 turns' peaks (the turn shortens towards the halt, so the
/// latest intervals are the shortest, up to the peaks' timing), or `None` before
/// there are that many.
fn final_turn(peaks: &[f64]) -> Option<f64> {
    let recent = peaks.get(peaks.len().checked_sub(PERIOD_TURNS + 1)?..)?;
    recent.windows(2).map(|w| w[1] - w[0]).reduce(f64::min)
}

/// Whether the reading at position `n` of `samples` begins or ends a run of
/// [`STILL_READINGS`] + 1 readings whose spread is below `tolerance`: a still
/// picture (module docs). Half the motion threshold, as for [`held`]: a run that
/// long spans more than three quarters of a final turn, over which a moving rim
/// swings by 0.85 of its rise at least.
fn in_still_picture(samples: &[usize], z: &[f64], n: usize, tolerance: f64) -> bool {
    let level = |run: &[usize]| spread(run, z) < tolerance;
    (n >= STILL_READINGS && level(&samples[n - STILL_READINGS..=n]))
        || (n + STILL_READINGS < samples.len() && level(&samples[n..=n + STILL_READINGS]))
}

/// The largest minus the smallest of `z` over the frames `run`.
fn spread(run: &[usize], z: &[f64]) -> f64 {
    let (lo, hi) = run
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &i| {
            (lo.min(z[i]), hi.max(z[i]))
        });
    hi - lo
}

/// The runs of consecutive `indices` (consecutive within the slice) for which
/// `rises` holds.
fn rise_runs(indices: &[usize], rises: impl Fn(usize) -> bool) -> Vec<Vec<usize>> {
    let mut runs: Vec<Vec<usize>> = Vec::new();
    let mut previous_rose = false;
    for &i in indices {
        let rose = rises(i);
        match (rose, previous_rose, runs.last_mut()) {
            (true, true, Some(run)) => run.push(i),
            (true, _, _) => runs.push(vec![i]),
            _ => {}
        }
        previous_rose = rose;
    }
    runs
}

/// Median and robust σ of `z` over `indices`, at least `floor`: the root mean square
/// of the deviations within 3σ of the median, σ starting from 1.4826 × MAD and
/// iterated twice, over 0.9866 (the σ of a Gaussian cut at ±3σ). The MAD alone is
/// robust but inefficient (±17 % over 48 samples), which made 4σ thresholds trip on
/// the noise.
fn rest_statistics(z: &[f64], indices: &[usize], floor: f64) -> (f64, f64) {
    let values: Vec<f64> = indices.iter().map(|&i| z[i]).collect();
    let level = median(&values);
    let mut sigma = mad_sigma(&values, level);
    for _ in 0..2 {
        let (sum, count) = values
            .iter()
            .map(|x| x - level)
            .filter(|d| d.abs() <= 3.0 * sigma)
            .fold((0.0, 0usize), |(s, c), d| (s + d * d, c + 1));
        if count == 0 || sigma == 0.0 {
            break;
        }
        sigma = (sum / count as f64).sqrt() / 0.9866;
    }
    (level, sigma.max(floor))
}

/// The lag and value of the autocorrelation peak of the tail deviations, if they
/// oscillate.
///
/// A rocking disk is periodic: its rim's autocorrelation falls below zero at half a
/// period and comes back above [`OSCILLATION_CORRELATION`] at a full period. A still
/// disk on H.264 footage is not: the encoder copies a frame's picture to the next
/// ones, so the readings are correlated over a few frames (lag-one correlation about
/// 0.7), but that correlation decays without a
/// trough. An oscillation therefore needs a correlation above the threshold at some
/// lag *after* one below [`OSCILLATION_TROUGH`].
///
/// Nor is the encoder's cadence: x264 codes a still picture as a repeating group of
/// frame types (a P frame and three B frames), each type read a little differently,
/// so a still tail can correlate at the group's length. Those readings repeat
/// exactly, one group to the next (on a dark plate about 70 % of a still tail's
/// readings equal the one 4 frames before, to 1e-9 m), while a moving rim, or a still
/// one under sensor noise, never reads the same twice. A lag at which at least half
/// the readings repeat the one a lag before (to [`COPY_FRACTION`] of the `noise` σ)
/// is the codec's cadence, not the disk's period.
fn oscillation(z: &[f64], tail: &[usize], level: f64, noise: f64) -> Option<(usize, f64)> {
    let dev: Vec<f64> = tail.iter().map(|&i| z[i] - level).collect();
    let mean = dev.iter().sum::<f64>() / dev.len() as f64;
    let var: f64 = dev.iter().map(|d| (d - mean).powi(2)).sum();
    if var <= 0.0 {
        return None;
    }
    let correlation = |lag: usize| {
        (lag..dev.len())
            .map(|i| (dev[i] - mean) * (dev[i - lag] - mean))
            .sum::<f64>()
            / var
    };
    let cadence = |lag: usize| {
        let repeats = (lag..dev.len())
            .filter(|&i| (dev[i] - dev[i - lag]).abs() <= COPY_FRACTION * noise)
            .count();
        2 * repeats >= dev.len() - lag
    };
    let mut trough = false;
    let mut best: Option<(usize, f64)> = None;
    for lag in 1..=MAX_LAG.min(dev.len() / 3) {
        let r = correlation(lag);
        trough |= r < OSCILLATION_TROUGH;
        if trough && r > OSCILLATION_CORRELATION && best.is_none_or(|(_, b)| r > b) && !cadence(lag)
        {
            best = Some((lag, r));
        }
    }
    best
}
