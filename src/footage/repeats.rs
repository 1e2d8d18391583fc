//! Frames that bring no new capture (issue 14 §2): duplicated frames, which repeat
//! the previous frame (bit for bit, or within the codec's noise), and interpolated
//! frames, which a phone computes as the blend of their neighbours to reach 240 or
//! 960 fps. Neither shows the disk at its own time, so the fits leave them out.
//!
//! [`RepeatGauge`] is fed, frame by frame, brightness samples spread over the
//! whole frame ([`super::FrameSource::brightness_samples`]: the luma plane as
//! decoded) and keeps two differences per frame k (means over the samples, grey
//! levels):
//!
//! * the step a_k = |f_k − s f_{k−1}|, zero for a duplicate;
//! * the blend residual b_k = |f_k − s (f_{k−1} + f_{k+1})/2|, zero for an
//!   interpolated frame;
//!
//! each with s the light's gain from the compared frame or blend g to f_k: the median
//! of the samples' ratios f_k/g (where g is above [`LEAST_GREY`]), which the few
//! samples the disk moves over do not move. A light flickering at the mains' 100 Hz
//! or 50 Hz scales every pixel by its gain, frame by frame: unscaled, the steps
//! follow the gain's changes, which at the flicker's extremes all but vanish between
//! two frames (under 5 % + 2 % flicker the gain may change by 0.3 % between frames
//! whose neighbours' steps are 6 %), so a frame whose rim moved 0.7 px can look like
//! a duplicate (its step 0.30 of its neighbours', 0.89 with the gain divided out)
//! and lose its height. A duplicate or a blend repeats its neighbours' gain with
//! their pixels, so s = 1 there. The median, not a least-squares s (Σ f g / Σ g²):
//! the moving disk's own samples weigh in the latter, which on coarsely coded
//! footage raises the steps of moving frames and takes some for duplicates.
//!
//! A still disk gives both at the noise level, so the noise is read at rest (the
//! clip's last frames, which the calibration requires at rest) and a frame is judged
//! only where its neighbours move well beyond it. A real frame in motion has a step
//! like its neighbours' and a blend residual comparable to theirs (the motion's
//! curvature; half the step at an edge sharper than the motion); a duplicate's step
//! falls to the codec's error while its neighbours' stay; an interpolated frame's
//! residual falls to the codec's error while its neighbours' grow (their blends now
//! straddle the inserted frame). The samples span the whole frame: the rim height on
//! the centre line stands still at each of its peaks, but the precessing disk's
//! silhouette does not.
//!
//! After the halt every frame repeats the one before it, so no frame there can be
//! told a repeat: the caller judges only the frames up to the last frame of motion
//! (`analyse` drops the marks after the halt the signal stage finds on the heights).
//! With the flicker divided out the still frames' steps fall to the codec's noise,
//! and an encoder's refresh of the still picture (tens of frames after the halt)
//! stands above them and would be marked as interpolated.

use serde::{Deserialize, Serialize};

use crate::numeric::median;

/// The neighbours' statistic must stand this many noise levels above the rest
/// frames' for a frame to be judged (there is motion to miss).
const MOTION_NOISE_LEVELS: f64 = 3.0;

/// A marked frame's statistic is below this fraction of the smaller of its
/// neighbours'. On rendered clips in motion (H.264 at crf 23, with and without
/// sensor noise) a real frame's step or blend residual stood at 0.65 or more of
/// its neighbours', a duplicate's step at 0.07 or less and an interpolated frame's
/// residual at 0.12 or less.
const NEIGHBOUR_FRACTION: f64 = 0.3;

/// The least noise level [grey levels, mean over the samples]: H.264 repeats a
/// still scene's blocks, so the rest frames can differ by a hundredth of a grey
/// level where the codec's error in motion reaches a few hundredths.
const NOISE_FLOOR: f64 = 0.05;

/// The least grey level [of 255] whose ratio between two frames measures the light's
/// gain: below it a step of one level is more than 12 %.
const LEAST_GREY: f64 = 8.0;

/// What a flagged frame repeats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RepeatKind {
    /// The previous frame again.
    Duplicated,
    /// The blend of the previous and next frames.
    Interpolated,
}

/// A frame that brings no capture of its own.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RepeatedFrame {
    /// 0-based frame in the clip as stored.
    pub index: usize,
    pub kind: RepeatKind,
    /// The frame's statistic (step or blend residual) [grey levels, mean over the
    /// band's pixels].
    pub statistic: f64,
    /// The smaller of its neighbours' statistics [grey levels].
    pub neighbours: f64,
    /// The statistic's level at rest [grey levels].
    pub noise: f64,
}

/// Streams frames' band intensities and finds the repeated frames.
#[derive(Default)]
pub struct RepeatGauge {
    /// The last two frames' pixels, older first.
    previous: [Vec<f32>; 2],
    frames: usize,
    /// a_k per frame (NaN for the first).
    steps: Vec<f64>,
    /// b_k per frame (NaN for the first and, until the next is seen, the last).
    blends: Vec<f64>,
    /// The samples' ratios of the last comparison, kept so that each frame reuses
    /// their buffer ([`scaled_difference`]).
    ratios: Vec<f64>,
}

impl RepeatGauge {
    /// An empty gauge.
    pub fn new() -> Self {
        Self::default()
    }

    /// The next frame's pixels (the same pixels, in the same order, every frame).
    pub fn push(&mut self, pixels: Vec<f32>) {
        let [older, last] = &self.previous;
        let step = if last.len() == pixels.len() && self.frames > 0 {
            scaled_difference(
                &pixels,
                last.iter().map(|&b| f64::from(b)),
                &mut self.ratios,
            )
        } else {
            f64::NAN
        };
        if self.frames >= 2 && older.len() == pixels.len() {
            let blend = older
                .iter()
                .zip(&pixels)
                .map(|(&a, &b)| 0.5 * (f64::from(a) + f64::from(b)));
            if let Some(b) = self.blends.last_mut() {
                *b = scaled_difference(last, blend, &mut self.ratios);
            }
        }
        self.steps.push(step);
        self.blends.push(f64::NAN);
        self.previous.swap(0, 1);
        self.previous[1] = pixels;
        self.frames += 1;
    }

    /// The repeated frames, judged against the noise of the last `rest` frames
    /// (at rest), in clip order.
    pub fn repeated(&self, rest: usize) -> Vec<RepeatedFrame> {
        let n = self.frames;
        if n < rest + 3 || rest < 3 {
            return Vec::new();
        }
        let noise = |series: &[f64]| {
            let tail: Vec<f64> = series[n - rest..]
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .collect();
            median(&tail)
        };
        let mut found = Vec::new();
        for (series, kind) in [
            (&self.steps, RepeatKind::Duplicated),
            (&self.blends, RepeatKind::Interpolated),
        ] {
            let level = noise(series);
            if !level.is_finite() {
                continue;
            }
            for k in 1..n - 1 {
                let (before, this, after) = (series[k - 1], series[k], series[k + 1]);
                let neighbours = before.min(after);
                if !(neighbours.is_finite() && this.is_finite()) {
                    continue;
                }
                let moving = neighbours > MOTION_NOISE_LEVELS * level.max(NOISE_FLOOR);
                if moving && this < NEIGHBOUR_FRACTION * neighbours {
                    found.push(RepeatedFrame {
                        index: k,
                        kind,
                        statistic: this,
                        neighbours,
                        noise: level,
                    });
                }
            }
        }
        found.sort_by_key(|f| f.index);
        found
    }
}

/// The mean |f − s g| over the samples [grey levels] of `frame` (f) and `compared` (g,
/// the same samples), s the median of f/g over the samples where g exceeds
/// [`LEAST_GREY`]: the light's gain divided out (module docs); 1 where none does.
/// `ratios` is a buffer for the ratios, overwritten.
fn scaled_difference(
    frame: &[f32],
    compared: impl Iterator<Item = f64> + Clone,
    ratios: &mut Vec<f64>,
) -> f64 {
    ratios.clear();
    ratios.extend(
        frame
            .iter()
            .zip(compared.clone())
            .filter(|&(_, g)| g > LEAST_GREY)
            .map(|(&f, g)| f64::from(f) / g),
    );
    let scale = if ratios.is_empty() {
        1.0
    } else {
        crate::numeric::upper_median(ratios)
    };
    frame
        .iter()
        .zip(compared)
        .map(|(&f, g)| (f64::from(f) - scale * g).abs())
        .sum::<f64>()
        / frame.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bright disk's edge at `position` [px] on a row of 64 samples, anti-aliased.
    fn edge(position: f64) -> Vec<f32> {
        (0..64)
            .map(|x| (200.0 * (position - f64::from(x)).clamp(0.0, 1.0)) as f32 + 20.0)
            .collect()
    }

    /// A precessing disk seen from the side, reduced to two rows: the rim on the
    /// centre line oscillates 10 px with 8 frames a period (each turning point
    /// halfway between two frames, where those two frames show the rim at one
    /// height), and the silhouette's side a quarter period out of phase; still for
    /// the last 8 frames.
    fn moving_disk() -> Vec<Vec<f32>> {
        let phase = |k: i32, shift: f64| {
            (2.0 * std::f64::consts::PI * (f64::from(k) + 0.5 + shift) / 8.0).sin()
        };
        (0..48)
            .map(|k| {
                [
                    edge(30.0 + 10.0 * phase(k, 0.0)),
                    edge(30.0 + 10.0 * phase(k, 2.0)),
                ]
                .concat()
            })
            .chain(std::iter::repeat_n([edge(30.0), edge(30.0)].concat(), 8))
            .collect()
    }

    /// Frame 13 repeats frame 12, and frame 30 is the blend of 29 and 31.
    fn with_a_repeat_and_a_blend(mut frames: Vec<Vec<f32>>) -> Vec<Vec<f32>> {
        frames[13] = frames[12].clone();
        frames[30] = frames[29]
            .iter()
            .zip(&frames[31])
            .map(|(a, b)| ((a + b) / 2.0).round())
            .collect();
        frames
    }

    /// The frames [`RepeatGauge`] marks, judged against the last 5.
    fn repeated(frames: Vec<Vec<f32>>) -> Vec<(usize, RepeatKind)> {
        let mut gauge = RepeatGauge::new();
        for f in frames {
            gauge.push(f);
        }
        gauge
            .repeated(5)
            .into_iter()
            .map(|r| (r.index, r.kind))
            .collect()
    }

    #[test]
    fn a_repeat_and_a_blend_of_a_moving_edge_are_found_and_the_rest_is_not() {
        assert_eq!(
            repeated(with_a_repeat_and_a_blend(moving_disk())),
            vec![(13, RepeatKind::Duplicated), (30, RepeatKind::Interpolated)]
        );
    }

    /// The same disk beside a still textured plate ten times its size, under a light
    /// flickering by 6 % at 100 Hz and 2 % at 50 Hz (480 fps), every pixel scaled by
    /// the gain frame by frame and read in whole grey levels. Unscaled, the plate's
    /// steps follow the gain: here the still frames' steps are the flicker's, and
    /// neither frame is found; where the gain turns between two frames, a moving frame
    /// can be taken for a duplicate. The gain divided out, the
    /// same two frames are found and no other.
    #[test]
    fn a_flickering_light_makes_no_repeat() {
        use std::f64::consts::TAU;
        let gain = |k: usize| {
            let t = k as f64 / 480.0;
            1.0 + 0.06 * (TAU * 100.0 * t + 0.4).sin() + 0.02 * (TAU * 50.0 * t + 1.1).sin()
        };
        let plate: Vec<f32> = (0..1280)
            .map(|x| {
                let x = f64::from(x);
                (60.0 + 40.0 * (0.37 * x).sin() * (0.11 * x).cos()) as f32
            })
            .collect();
        let frames: Vec<Vec<f32>> = moving_disk()
            .into_iter()
            .enumerate()
            .map(|(k, disk)| {
                disk.iter()
                    .chain(&plate)
                    .map(|&p| (f64::from(p) * gain(k)).round() as f32)
                    .collect()
            })
            .collect();
        assert_eq!(
            repeated(with_a_repeat_and_a_blend(frames)),
            vec![(13, RepeatKind::Duplicated), (30, RepeatKind::Interpolated)]
        );
    }
}
