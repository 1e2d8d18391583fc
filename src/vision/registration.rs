//! The camera's motion, frame by frame, against what does not move: the picture's
//! vertical shift at the centre line, by which every rim height is corrected.
//!
//! z_rim is the rim's edge row read against the plate line found at rest. A
//! camera on a table the disk clatters on vibrates (tens of Hz, tenths of a
//! pixel), sways slowly, or is held by hand (pixels): the whole picture moves, and
//! every height reads the picture's vertical shift d as −d. The scene beside the
//! disk does not move: the plate's far edge (the side view's horizon), its front
//! edge, its texture, the backdrop. So each frame's shift is measured there and
//! z_rim read in the frame's own scene.
//!
//! On two strips of columns, left and right of the disk (clear of it by
//! [`MARGIN_FRACTION`] of its width, for drift, lean and a light plate's shadow),
//! each row's mean is taken in every frame: a profile P(y), whose horizontal edges
//! carry the vertical shift. Against the reference R(y), the mean profile of the
//! rest tail (the frames that give z_rim's zero),
//!
//! ```text
//! P(y) = a R(y − d) + b
//! ```
//!
//! with a gain a and an offset b for flicker and exposure: d first on whole rows
//! (least squares over ±[`MAX_SHIFT_PX`]), then by Gauss–Newton on R interpolated
//! (cubic), and once more without the rows whose misfit exceeds
//! [`OUTLIER_SIGMAS`] robust σ (a moving shadow, a passing reflection). A second
//! pass weights each row by the inverse of its misfit's variance over the clip,
//! so rows whose content changes as the disk moves count less. The shift
//! at the centre line is interpolated between the two strips' centres, so a roll
//! of the camera is followed too; with one strip, it is that strip's.
//!
//! The shift's error σ is measured by the two strips' disagreement (a camera's
//! motion moves both alike), or, with one strip, from the fit's own standard
//! error. The heights are corrected only when the camera's motion stands out of
//! that error ([`SIGNIFICANT_MOTION`]): a still camera's registration is error
//! alone, and a featureless scene (a uniform backdrop and plate) gives no shift.
//!
//! On lossless frames the shift follows a render's truth within 0.02 px a frame;
//! on H.264 of a shaking picture within 0.2 px, as the coder moves the still
//! background by its own motion vectors (docs/limits.md).

use std::ops::Range;

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::Calibration;
use crate::numeric::{mad_sigma, median};

/// The strips keep clear of the disk's ends at rest by this fraction of its width
/// (and at least [`MIN_MARGIN_PX`]): room for the disk drifting and leaning while
/// it rolls, and for a light plate's shadow beside it.
pub const MARGIN_FRACTION: f64 = 0.08;
const MIN_MARGIN_PX: f64 = 16.0;
/// Narrowest strip read \[px\], and the widest (the columns nearest the disk).
const MIN_STRIP_PX: usize = 8;
const MAX_STRIP_PX: usize = 192;
/// Largest shift searched \[px\]: a hand-held camera's.
pub const MAX_SHIFT_PX: usize = 12;
/// Rows whose misfit exceeds this many robust σ are left out of the final fit.
const OUTLIER_SIGMAS: f64 = 4.0;
/// The least σ of a row's misfit \[grey levels\]: the cubic interpolation of a
/// blurred edge misses by about this much, which is no sign of a moving scene.
const MIN_MISFIT_SIGMA: f64 = 1.0;
/// The heights are corrected only when the shift's RMS exceeds its error σ this
/// many times: a still camera's registration is its error alone, and that error,
/// kept from frame to frame by the codec, is slow enough to move the peaks'
/// heights together and with them n.
pub const SIGNIFICANT_MOTION: f64 = 3.0;
/// With one strip, σ is the fit's own standard error times this: on the open
/// footage, with two strips to tell, the shift's error is 3–4 times the one the
/// fit reports, its rows' coding errors being kept from frame to frame.
const ONE_STRIP_SIGMA_FACTOR: f64 = 4.0;
/// Gauss–Newton steps, and the step below which they stop \[px\].
const GN_STEPS: usize = 8;
const GN_TOL_PX: f64 = 1e-4;

/// Where the scene beside the disk is read: columns of the side view left and
/// right of the disk (either may be missing), over all its rows.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneStrips {
    pub left: Option<Range<usize>>,
    pub right: Option<Range<usize>>,
    /// The side view's height \[px\].
    pub height: usize,
}

/// One frame's row means over each strip (empty where the strip is missing).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StripProfiles {
    pub left: Vec<f32>,
    pub right: Vec<f32>,
}

/// The camera's vertical shift in every frame, measured on the scene strips.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Registration {
    /// Per frame, the picture's shift at the centre line \[px\], positive when the
    /// picture moved down against the rest tail (`None`: not measured).
    #[serde(skip)]
    pub shifts: Vec<Option<f64>>,
    /// Which strips were read: "left and right", "left", "right".
    pub strips: String,
    /// The shift's RMS and its largest magnitude over the frames \[px\].
    pub rms_px: f64,
    pub peak_px: f64,
    /// The shift's error σ \[px\]: from the two strips' disagreement, else
    /// [`ONE_STRIP_SIGMA_FACTOR`] times the fit's median standard error.
    pub sigma_px: f64,
    /// Whether the heights were corrected: the RMS exceeds
    /// [`SIGNIFICANT_MOTION`] σ.
    pub applied: bool,
}

impl SceneStrips {
    /// The strips beside the disk of the rest calibration `cal`, in a side view
    /// `width` × `height`; `None` when neither side leaves [`MIN_STRIP_PX`]
    /// columns, or the view is too short to search a shift in.
    pub fn new(cal: &Calibration, width: usize, height: usize) -> Option<Self> {
        let margin = (MARGIN_FRACTION * (cal.x_r - cal.x_l)).max(MIN_MARGIN_PX);
        let left_end = (cal.x_l - margin).floor().max(0.0) as usize;
        let right_start = ((cal.x_r + margin).ceil().max(0.0) as usize).min(width);
        let left =
            (left_end >= MIN_STRIP_PX).then(|| left_end.saturating_sub(MAX_STRIP_PX)..left_end);
        let right = (width >= right_start + MIN_STRIP_PX)
            .then(|| right_start..(right_start + MAX_STRIP_PX).min(width));
        let tall_enough = height > 4 * MAX_SHIFT_PX;
        (tall_enough && (left.is_some() || right.is_some())).then_some(Self {
            left,
            right,
            height,
        })
    }

    /// One frame's profiles, from `row_mean(y, columns)`: the mean intensity of
    /// row y over those columns of the side view.
    pub fn read(&self, row_mean: impl Fn(usize, &Range<usize>) -> f32) -> StripProfiles {
        let profile = |strip: &Option<Range<usize>>| -> Vec<f32> {
            strip.as_ref().map_or_else(Vec::new, |cols| {
                (0..self.height).map(|y| row_mean(y, cols)).collect()
            })
        };
        StripProfiles {
            left: profile(&self.left),
            right: profile(&self.right),
        }
    }

    /// The centre column of each strip read \[px\].
    fn centres(&self) -> [Option<f64>; 2] {
        [&self.left, &self.right].map(|s| s.as_ref().map(|r| 0.5 * (r.start + r.end) as f64))
    }
}

/// Registers every frame's `profiles` against the mean of those at `reference`
/// (indices into `profiles`: the rest tail), and interpolates the shift to the
/// centre column `x_centre`. `None` when no reference frame was read.
pub fn register(
    strips: &SceneStrips,
    profiles: &[StripProfiles],
    reference: Range<usize>,
    x_centre: f64,
) -> Option<Registration> {
    let tail = profiles.get(reference)?;
    if tail.is_empty() {
        return None;
    }
    let sides: [fn(&StripProfiles) -> &Vec<f32>; 2] = [|p| &p.left, |p| &p.right];
    let per_strip = sides.map(|side| {
        let reference = mean_profile(tail.iter().map(side));
        let strip = Strip::new(&reference)?;
        Some(strip.shifts(&profiles.iter().map(side).collect::<Vec<_>>()))
    });
    let centres = strips.centres();
    let fits: Vec<Option<(f64, f64)>> = (0..profiles.len())
        .map(|k| {
            let at = |s: &Option<Vec<Option<(f64, f64)>>>| s.as_ref().and_then(|v| v[k]);
            at_centre(&[at(&per_strip[0]), at(&per_strip[1])], &centres, x_centre)
        })
        .collect();
    let sigmas: Vec<f64> = fits.iter().flatten().map(|&(_, s)| s).collect();
    let sigma_px = match noise_from_disagreement(&per_strip, &centres, x_centre) {
        Some(sigma) => sigma,
        None if !sigmas.is_empty() => ONE_STRIP_SIGMA_FACTOR * median(&sigmas),
        None => f64::INFINITY,
    };
    let shifts: Vec<Option<f64>> = fits.iter().map(|f| f.map(|(d, _)| d)).collect();
    let measured: Vec<f64> = shifts.iter().flatten().copied().collect();
    let rms_px = rms(&measured);
    let peak_px = measured.iter().fold(0.0_f64, |m, d| m.max(d.abs()));
    let strips_read = match (&strips.left, &strips.right) {
        (Some(_), Some(_)) => "left and right",
        (Some(_), None) => "left",
        _ => "right",
    };
    Some(Registration {
        shifts,
        strips: strips_read.into(),
        rms_px,
        peak_px,
        sigma_px,
        applied: rms_px > SIGNIFICANT_MOTION * sigma_px,
    })
}

/// One strip's (shift, σ) per frame \[px\] (`None`: not fitted).
type StripShifts = Vec<Option<(f64, f64)>>;

/// The root mean square of `values` (0 when empty).
fn rms(values: &[f64]) -> f64 {
    (values.iter().map(|d| d * d).sum::<f64>() / values.len().max(1) as f64).sqrt()
}

/// The centre line's shift error σ from the two strips' disagreement: a camera
/// that moves moves both alike (a roll apart, which the interpolation follows),
/// so their difference is their errors', each of variance ⟨(d_l − d_r)²⟩/2, and
/// the centre's, interpolated with weight w, ((1 − w)² + w²) of that. `None`
/// with one strip.
fn noise_from_disagreement(
    per_strip: &[Option<StripShifts>; 2],
    centres: &[Option<f64>; 2],
    x_centre: f64,
) -> Option<f64> {
    let (left, right) = (per_strip[0].as_ref()?, per_strip[1].as_ref()?);
    let (xl, xr) = (centres[0]?, centres[1]?);
    let differences: Vec<f64> = left
        .iter()
        .zip(right)
        .filter_map(|(l, r)| Some(l.as_ref()?.0 - r.as_ref()?.0))
        .collect();
    if differences.len() < 2 || xr <= xl {
        return None;
    }
    let w = (x_centre - xl) / (xr - xl);
    let strip_variance = 0.5 * rms(&differences).powi(2);
    Some((((1.0 - w).powi(2) + w * w) * strip_variance).sqrt())
}

/// The mean of several profiles, row by row (empty when they are).
fn mean_profile<'a>(profiles: impl Iterator<Item = &'a Vec<f32>>) -> Vec<f64> {
    let mut sum: Vec<f64> = Vec::new();
    let mut n = 0.0;
    for p in profiles {
        if sum.is_empty() {
            sum = vec![0.0; p.len()];
        }
        for (s, &v) in sum.iter_mut().zip(p) {
            *s += f64::from(v);
        }
        n += 1.0;
    }
    sum.iter().map(|s| s / n).collect()
}

/// The shift at the centre column from the strips' (shift, σ): interpolated
/// linearly between the strips' centres (a roll tilts the picture), else the one
/// strip's.
fn at_centre(
    per_strip: &[Option<(f64, f64)>; 2],
    centres: &[Option<f64>; 2],
    x_centre: f64,
) -> Option<(f64, f64)> {
    match (per_strip[0], per_strip[1], centres[0], centres[1]) {
        (Some((dl, sl)), Some((dr, sr)), Some(xl), Some(xr)) if xr > xl => {
            let w = (x_centre - xl) / (xr - xl);
            let d = dl + w * (dr - dl);
            let s = ((1.0 - w).powi(2) * sl * sl + w * w * sr * sr).sqrt();
            Some((d, s))
        }
        (Some(f), _, _, _) | (None, Some(f), _, _) => Some(f),
        _ => None,
    }
}

/// One strip's reference profile R and the rows a shift is fitted on (clear of
/// the ends by the largest shift).
struct Strip<'a> {
    reference: &'a [f64],
    rows: Range<usize>,
}

/// One frame's fit on a strip: the shift, its standard error, and each row's
/// misfit (over the strip's rows; single precision, as it is kept for every
/// frame of a clip until the rows' weights are known).
struct ShiftFit {
    shift: f64,
    se: f64,
    misfit: Vec<f32>,
}

impl<'a> Strip<'a> {
    /// `None` when the reference is too short to search a shift in.
    fn new(reference: &'a [f64]) -> Option<Self> {
        let rows = MAX_SHIFT_PX + 2..reference.len().checked_sub(MAX_SHIFT_PX + 2)?;
        (rows.len() > 2 * MAX_SHIFT_PX).then_some(Self { reference, rows })
    }

    /// Every frame's (shift, σ) on this strip (`profiles`, one per frame): each
    /// fitted with equal weights, then again with each row weighted by the
    /// inverse of its misfit's variance over the clip. A row whose content
    /// changes as the disk moves (the disk's light on a brushed plate, a shadow)
    /// varies more than its noise, and counts less.
    fn shifts(&self, profiles: &[&Vec<f32>]) -> Vec<Option<(f64, f64)>> {
        let equal = vec![1.0; self.reference.len()];
        let first: Vec<Option<ShiftFit>> = profiles
            .par_iter()
            .map(|p| self.fit(p, None, &equal))
            .collect();
        let weights = self.row_weights(&first);
        let starts: Vec<Option<f64>> = first.iter().map(|f| f.as_ref().map(|f| f.shift)).collect();
        drop(first);
        profiles
            .par_iter()
            .zip(&starts)
            .map(|(p, start)| {
                let fit = self.fit(p, *start, &weights)?;
                Some((fit.shift, fit.se))
            })
            .collect()
    }

    /// 1/(σ_y² + [`MIN_MISFIT_SIGMA`]²) per row, σ_y the robust spread of the
    /// row's misfit over the frames `fits`.
    fn row_weights(&self, fits: &[Option<ShiftFit>]) -> Vec<f64> {
        let mut weights = vec![0.0; self.reference.len()];
        for (i, y) in self.rows.clone().enumerate() {
            let misfits: Vec<f64> = fits
                .iter()
                .flatten()
                .map(|f| f64::from(f.misfit[i]))
                .collect();
            if misfits.is_empty() {
                continue;
            }
            let sigma = mad_sigma(&misfits, 0.0);
            weights[y] = 1.0 / (sigma * sigma + MIN_MISFIT_SIGMA * MIN_MISFIT_SIGMA);
        }
        weights
    }

    /// The shift of `profile` (P(y) = a R(y − d) + b) with the row `weights`: from
    /// `start`, else from the best whole-row shift; by Gauss–Newton, then again
    /// without the rows misfitted by more than [`OUTLIER_SIGMAS`] of their σ.
    /// `None` when the fit fails (no gradient).
    fn fit(&self, profile: &[f32], start: Option<f64>, weights: &[f64]) -> Option<ShiftFit> {
        if profile.len() < self.reference.len() {
            return None;
        }
        let p: Vec<f64> = profile.iter().map(|&v| f64::from(v)).collect();
        let d0 = match start {
            Some(d) => d,
            None => self.whole_shift(&p)?,
        };
        let first = self.refine(&p, d0, weights)?;
        // Each row's σ: its weight's, scaled by the frame's misfit.
        let scale = {
            let z: Vec<f64> = self
                .rows
                .clone()
                .zip(&first.misfit)
                .map(|(y, &r)| f64::from(r) * weights[y].sqrt())
                .collect();
            mad_sigma(&z, 0.0).max(1e-9)
        };
        let mut kept = weights.to_vec();
        for (y, &r) in self.rows.clone().zip(&first.misfit) {
            if (f64::from(r) * weights[y].sqrt()).abs() > OUTLIER_SIGMAS * scale.max(1.0) {
                kept[y] = 0.0;
            }
        }
        self.refine(&p, first.shift, &kept)
    }

    /// The whole-row shift in ±[`MAX_SHIFT_PX`] whose least-squares (a, b) leave
    /// the least misfit.
    fn whole_shift(&self, p: &[f64]) -> Option<f64> {
        let m = MAX_SHIFT_PX as i64;
        (-m..=m)
            .filter_map(|s| {
                let pairs = self
                    .rows
                    .clone()
                    .map(|y| (self.reference[(y as i64 - s) as usize], p[y], 1.0));
                Some((s, line_fit(pairs)?.2))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(s, _)| s as f64)
    }

    /// Gauss–Newton for (a, b, d) from the shift `d0`: P ≈ a R(y − d) + b, linear in
    /// (a, b, c = −a δ) about d, rows weighted by `w`.
    fn refine(&self, p: &[f64], d0: f64, w: &[f64]) -> Option<ShiftFit> {
        let mut d = d0;
        for _ in 0..GN_STEPS {
            let (normal, rhs) = self.normal_equations(p, d, w);
            let x = normal.lu().solve(&rhs)?;
            if x[0].abs() <= 1e-6 || x[0].is_nan() {
                return None;
            }
            let step = (-x[2] / x[0]).clamp(-1.0, 1.0);
            d += step;
            if d.abs() > MAX_SHIFT_PX as f64 + 1.0 {
                return None;
            }
            if step.abs() < GN_TOL_PX {
                break;
            }
        }
        let pairs = self
            .rows
            .clone()
            .map(|y| (sample(self.reference, y as f64 - d).0, p[y], w[y]));
        let (a, b, ssr) = line_fit(pairs)?;
        let misfit: Vec<f32> = self
            .rows
            .clone()
            .map(|y| (p[y] - a * sample(self.reference, y as f64 - d).0 - b) as f32)
            .collect();
        let used = self.rows.clone().filter(|&y| w[y] > 0.0).count();
        let s2 = ssr / used.saturating_sub(3).max(1) as f64;
        let cov = self.normal_equations(p, d, w).0.try_inverse()?;
        // Var(c) = s² (JᵀWJ)⁻¹₂₂, and δ = −c/a.
        let se = (s2 * cov[(2, 2)]).sqrt() / a.abs();
        Some(ShiftFit {
            shift: d,
            se,
            misfit,
        })
    }

    /// JᵀWJ and JᵀWP of the linear model a R(y − d) + b + c R′(y − d).
    fn normal_equations(&self, p: &[f64], d: f64, w: &[f64]) -> (Matrix3<f64>, Vector3<f64>) {
        let mut normal = Matrix3::zeros();
        let mut rhs = Vector3::zeros();
        for y in self.rows.clone().filter(|&y| w[y] > 0.0) {
            let (r, slope) = sample(self.reference, y as f64 - d);
            let j = Vector3::new(r, 1.0, slope);
            normal += w[y] * j * j.transpose();
            rhs += w[y] * p[y] * j;
        }
        (normal, rhs)
    }
}

/// R and its slope at y, by cubic (Catmull–Rom) interpolation.
fn sample(reference: &[f64], y: f64) -> (f64, f64) {
    let last = reference.len() as i64 - 1;
    let k = y.floor() as i64;
    let t = y - k as f64;
    let at = |i: i64| reference[i.clamp(0, last) as usize];
    let (p0, p1, p2, p3) = (at(k - 1), at(k), at(k + 1), at(k + 2));
    let a = -0.5 * p0 + 1.5 * p1 - 1.5 * p2 + 0.5 * p3;
    let b = p0 - 2.5 * p1 + 2.0 * p2 - 0.5 * p3;
    let c = -0.5 * p0 + 0.5 * p2;
    let value = ((a * t + b) * t + c) * t + p1;
    let slope = (3.0 * a * t + 2.0 * b) * t + c;
    (value, slope)
}

/// The weighted least-squares line p ≈ a r + b through (r, p, weight) triples, and
/// its weighted misfit; `None` when r does not vary.
fn line_fit(pairs: impl Iterator<Item = (f64, f64, f64)>) -> Option<(f64, f64, f64)> {
    let (mut sw, mut sr, mut sp, mut srr, mut srp, mut spp) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for (r, p, w) in pairs {
        sw += w;
        sr += w * r;
        sp += w * p;
        srr += w * r * r;
        srp += w * r * p;
        spp += w * p * p;
    }
    let var_r = srr - sr * sr / sw;
    if var_r <= 1e-9 || var_r.is_nan() {
        return None;
    }
    let cov = srp - sr * sp / sw;
    let a = cov / var_r;
    let b = (sp - a * sr) / sw;
    let ssr = (spp - sp * sp / sw) - cov * cov / var_r;
    Some((a, b, ssr.max(0.0)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::profile::blurred_step_coverage;

    /// A side view's column profile: backdrop 30, the plate's far edge (the
    /// horizon) at row 300 up to 140, brushed streaks, its front edge at 600 down
    /// to 10; every edge blurred by σ = 0.9 px and sampled by area, moved down by
    /// `d` px, under the light gain `gain`.
    fn scene(d: f64, gain: f64) -> Vec<f32> {
        (0..720)
            .map(|k| {
                let c = |e: f64| blurred_step_coverage(k as f64, e + d, 0.9).0;
                let streaks: f64 = [(380.0, 12.0), (431.5, -9.0), (502.2, 7.0)]
                    .iter()
                    .map(|&(e, h)| h * (c(e) - c(e + 3.0)))
                    .sum();
                (gain * (30.0 + 110.0 * c(300.0) + streaks - 130.0 * c(600.0))) as f32
            })
            .collect()
    }

    fn strips() -> SceneStrips {
        SceneStrips {
            left: Some(0..100),
            right: Some(1180..1280),
            height: 720,
        }
    }

    /// Sub-pixel and whole-pixel shifts, under flicker, are read within 0.01 px,
    /// and a roll (left and right strips shifted apart) is interpolated to the
    /// centre line.
    #[test]
    fn a_shifted_scene_is_registered_at_the_centre_line() {
        let rest: Vec<StripProfiles> = (0..5)
            .map(|_| StripProfiles {
                left: scene(0.0, 1.0),
                right: scene(0.0, 1.0),
            })
            .collect();
        for (dl, dr, gain) in [
            (0.3, 0.3, 1.08),
            (-0.17, -0.17, 0.93),
            (0.5, 0.5, 1.0),
            (-0.75, -0.75, 1.0),
            (4.6, 4.6, 1.0),
            (0.2, 0.6, 1.0),
        ] {
            let mut profiles = rest.clone();
            profiles.insert(
                0,
                StripProfiles {
                    left: scene(dl, gain),
                    right: scene(dr, gain),
                },
            );
            let r = register(&strips(), &profiles, 1..6, 640.0).expect("registered");
            let expected = dl + (640.0 - 50.0) / (1230.0 - 50.0) * (dr - dl);
            let d = r.shifts[0].expect("measured");
            assert!((d - expected).abs() < 0.01, "shift {expected}, read {d}");
            assert!(r.shifts[1].is_some_and(|d| d.abs() < 1e-6));
        }
    }

    /// A still camera's registration is its error alone, and is not applied; a
    /// camera that vibrates (0.3 px at 38 Hz, sampled at 480 fps) is followed
    /// within 0.03 px, and applied. Each strip carries its own noise (σ 0.5
    /// grey levels a row), so the strips disagree by their errors only.
    #[test]
    fn only_a_camera_that_moves_is_corrected() {
        let mut seed = 7_u64;
        let mut noise = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 33) as f64 / (1u64 << 31) as f64 - 0.5) * 1.7
        };
        let mut noisy =
            |d: f64| -> Vec<f32> { scene(d, 1.0).iter().map(|&v| v + noise() as f32).collect() };
        for amplitude in [0.0, 0.3] {
            let motion =
                |k: usize| amplitude * (2.0 * std::f64::consts::PI * 38.0 * k as f64 / 480.0).sin();
            let profiles: Vec<StripProfiles> = (0..300)
                .map(|k| {
                    let d = if k < 250 { motion(k) } else { 0.0 };
                    StripProfiles {
                        left: noisy(d),
                        right: noisy(d),
                    }
                })
                .collect();
            let r = register(&strips(), &profiles, 250..300, 640.0).expect("registered");
            assert_eq!(r.applied, amplitude > 0.0, "{r:?}");
            if r.applied {
                for (k, d) in r.shifts.iter().enumerate().take(250) {
                    let d = d.expect("measured");
                    assert!(
                        (d - motion(k)).abs() < 0.03,
                        "frame {k}: {} read {d}",
                        motion(k)
                    );
                }
            }
        }
    }

    /// A featureless strip (a uniform backdrop and plate) gives no shift to apply.
    #[test]
    fn a_featureless_scene_is_not_registered() {
        let flat = StripProfiles {
            left: vec![40.0; 720],
            right: vec![40.0; 720],
        };
        let profiles = vec![flat; 4];
        let r = register(&strips(), &profiles, 1..4, 640.0);
        assert!(r.is_none_or(|r| !r.applied && r.shifts.iter().all(Option::is_none)));
    }

    /// Rows where something moves (a shadow beside the disk) are left out: a dark
    /// band that comes and goes over 30 rows does not move the shift.
    #[test]
    fn a_moving_shadow_in_a_strip_is_left_out() {
        let rest = StripProfiles {
            left: scene(0.0, 1.0),
            right: vec![],
        };
        let mut shadowed = scene(0.25, 1.0);
        for v in &mut shadowed[420..450] {
            *v *= 0.6;
        }
        let profiles = vec![
            StripProfiles {
                left: shadowed,
                right: vec![],
            },
            rest.clone(),
            rest,
        ];
        let one = SceneStrips {
            right: None,
            ..strips()
        };
        let r = register(&one, &profiles, 1..3, 640.0).expect("registered");
        let d = r.shifts[0].expect("measured");
        assert!((d - 0.25).abs() < 0.01, "shift 0.25, read {d}");
    }
}
