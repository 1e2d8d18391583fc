//! The near top rim z_t (thesis fig. 3.3): where the top face, seen from a camera
//! a little above the plate, meets the camera-facing side, on the centre line.
//! With the plate line it sets the vertical scale δ = 2H/(z_base − z_t) (eq. 3.10
//! corrected), so an error of 1 px in z_t is 2–5 % in φ and E on a disk 20–50 px
//! thick.
//!
//! Three readings, tried in turn ([`read_near_top_rim`]):
//!
//! 1. [`near_top_rim_across`]: the two-plateau edge ([`near_top_rim`]) on bands of
//!    columns across the face, carried to the centre line along the face's
//!    ellipse, the median over the bands. The strip on the top face (two-view
//!    set-ups, fig. 3.19; any marked disk) passes through the face's centre: when
//!    it points at the camera it covers the centre band from the far rim to the
//!    near one, and its own edge is taken for the rim there; elsewhere it crosses
//!    only a few bands near the rim.
//! 2. [`near_top_rim`] on the centre band alone, when too few bands see a rim (a
//!    narrow face, a small disk).
//! 3. [`fit_thin_face`]: a face up to [`REACH`] + 2 px tall, fitted with its blur
//!    and the band of a rounded rim below it. The plateaus leave its rows out; when
//!    they see the band and the side instead, their edge is the band's lower one,
//!    and the fit's rim replaces it.
//!
//! When none sees a face the silhouette's top (the far top rim) stands for z_t
//! ([`TopFace::Unseen`]). A face under [`super::leaning_face::THIN_AT_REST_PX`] is
//! read again, in the frames in which the rolling disk leans towards the camera
//! and shows it several pixels tall ([`super::leaning_face`]), and `analyse` takes
//! that reading. [`TopFace`] records which reading the rest frame took.

use std::ops::RangeInclusive;

use nalgebra::{DMatrix, Matrix4, Vector4};
use serde::{Deserialize, Serialize};

use super::calibration::REACH;
use super::profile::{area_edge, blurred_step_coverage, row_band_mean};
use crate::footage::FrameView;
use crate::numeric::{mad_sigma, median, upper_median};

/// Farthest band from the centre line, as a fraction of the disk's half-width a.
/// There the near top rim lies b (1 − √(1 − 0.4²)) = 0.083 b above its lowest point
/// and the far top rim as far below it (b, the face's half-height): within the
/// [`REACH`] rows that [`near_top_rim`] leaves out of the face for faces up to
/// 72 px tall.
const ACROSS_SPAN: f64 = 0.4;

/// How a rest frame saw the top face: its near rim read between plateaus, ended
/// by a rounded rim's band, read within the blur, or not seen (the silhouette's
/// top, the far top rim, standing in).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TopFace {
    /// Read between the plateaus either side of the near rim.
    Plateaus,
    /// A face thinner than the plateaus reach, ended by the band of a rounded rim
    /// below it: the thin face's fit places its end by the band's.
    Banded,
    /// A face thinner than the plateaus reach above a sharp edge: the thin face's
    /// fit ends it within about σ of the blur.
    Thin,
    /// Not seen: z_t is the far top rim.
    #[default]
    Unseen,
    /// Not read: the config gives z_t.
    Given,
}

/// The face's place on the centre band, as the calibration found it (frame rows
/// and columns, px).
pub(super) struct CentreBand {
    /// Centre line x_c and the disk's half-width a.
    pub x_centre: f64,
    pub half_span: f64,
    /// Half-width of a band of columns (a band is 2·half_width + 1 wide).
    pub half_width: usize,
    /// The silhouette's first row and its area edge, the far top rim.
    pub top: usize,
    pub far: f64,
    /// The side's last row.
    pub side_end: usize,
    /// The disk's contrast with what lies below it.
    pub contrast: f32,
}

/// The near top rim z_t on the centre line from bands of columns across the face
/// (see the module docs): on the band centred u = (x − x_c)/a from the centre
/// line, with |u| ≤ [`ACROSS_SPAN`], [`near_top_rim`] reads the near rim z_u. The
/// face is an ellipse of half-width a and half-height b = (z_t − far)/2 about the
/// centre line (also in perspective, for a camera facing the disk's centre), so
///
/// ```text
/// z_t = z_u + b (1 − √(1 − u²)),
/// ```
///
/// and z_t is the median of that over the bands, b taken from z_t itself (three
/// passes from the bands' own median; the term is at most 8 % of b). Each band's
/// side ends higher by as much as the bottom rim rises there (bounded by the
/// face's largest b, half the rows from the far rim to the side's end). `None`
/// unless more than half of the bands see a rim.
pub(super) fn near_top_rim_across(frame: &FrameView, centre: &CentreBand) -> Option<f64> {
    let step = 2 * centre.half_width + 1;
    let reach = (ACROSS_SPAN * centre.half_span / step as f64).floor() as i64;
    let c = centre.x_centre.floor() as i64;
    let largest_b = 0.5 * (centre.side_end as f64 - centre.far);
    let y0 = centre.top.checked_sub(REACH + 1)?;
    let mut bands = 0;
    let mut rims: Vec<(f64, f64)> = Vec::new();
    for k in -reach..=reach {
        let column = c + k * step as i64;
        let x0 = column - centre.half_width as i64;
        let x1 = column + centre.half_width as i64 + 1;
        if x0 < 0 || x1 > frame.width as i64 {
            continue;
        }
        bands += 1;
        let u = (column as f64 + 0.5 - centre.x_centre) / centre.half_span;
        let drop = 1.0 - (1.0 - u * u).sqrt();
        let side_end = centre.side_end - (largest_b * drop).ceil() as usize;
        let y1 = (side_end + REACH + 2).min(frame.height);
        let p: Vec<f32> = (y0..y1)
            .map(|y| row_band_mean(frame, y, x0 as usize, x1 as usize))
            .collect();
        if let Some(z) = near_top_rim(
            &p,
            centre.top - y0,
            side_end - y0,
            centre.contrast,
            y0 as f64,
        ) {
            rims.push((z, drop));
        }
    }
    if 2 * rims.len() <= bands {
        return None;
    }
    let mut z_t = robust_median(rims.iter().map(|r| r.0).collect());
    for _ in 0..3 {
        let b = 0.5 * (z_t - centre.far);
        z_t = robust_median(rims.iter().map(|&(z, drop)| z + b * drop).collect());
    }
    Some(z_t)
}

/// The silhouette's top on the centre line (the far top rim; thesis fig. 3.3) of a
/// frame at rest: going down a band of five columns about `cal`'s centre line from
/// the frame's first row, where the mean level crosses halfway from the first row's
/// (what lies behind the disk) to the top face's, 1.5 px above z_t (rows' centres at
/// y + ½). z_t − top is the top face's height on the centre line, from which the
/// camera's elevation follows (`analyse::ScaleReport`). `None` when the disk's top
/// is at the frame's first row or the face is as bright as what lies behind it.
pub fn silhouette_top(frame: &FrameView, cal: &super::Calibration) -> Option<f64> {
    let x = cal.x_centre().floor() as usize;
    if x < 2 || x + 3 > frame.width {
        return None;
    }
    let face_row = (cal.z_t - 1.5).floor();
    if !(1.0..frame.height as f64).contains(&face_row) {
        return None;
    }
    let face_row = face_row as usize;
    let band = |y: usize| f64::from(row_band_mean(frame, y, x - 2, x + 3));
    let (behind, face) = (band(0), band(face_row));
    let half = 0.5 * (behind + face);
    if (face - behind).abs() < 1.0 {
        return None;
    }
    let beyond = |v: f64| (v - half) * (face - half) < 0.0;
    (0..face_row).find_map(|y| {
        let (a, b) = (band(y), band(y + 1));
        (beyond(a) && !beyond(b)).then(|| y as f64 + 0.5 + (half - a) / (b - a))
    })
}

/// Least difference between the top face's and the side's mean levels, as a
/// fraction of the disk's contrast with what lies below it, for the near top rim
/// to count as seen (a sub-pixel edge between levels closer than this is noise).
pub(super) const NEAR_RIM_STEP_FRACTION: f32 = 0.15;

/// The near top rim z_t (thesis fig. 3.3) on the band profile `p` of the disk's
/// silhouette, rows `top..=side_end` (silhouette top to the last row of the
/// side): where the top face, seen from above, meets the camera-facing side.
///
/// The two faces are lit differently, either brighter, so the profile is two
/// plateaus: the change point that minimises the absolute deviations from the
/// median on each side (a thin line across a face, such as a strip, moves neither
/// median, where a local gradient or a mean would take its edge). The edge is then placed sub-pixel
/// by the area of the steepest step of the right sign within [`REACH`] px of it.
/// `None` when the two levels differ by less than [`NEAR_RIM_STEP_FRACTION`] of
/// `contrast`: the top face is not seen (camera at the plate's height) or is lit
/// like the side, and the silhouette's top is then the near top rim's estimate.
pub(super) fn near_top_rim(
    p: &[f32],
    top: usize,
    side_end: usize,
    contrast: f32,
    origin: f64,
) -> Option<f64> {
    // Leave the silhouette's own edges out of both plateaus.
    let (lo, hi) = (top + REACH, side_end.checked_sub(REACH)?);
    if hi < lo + 4 {
        return None;
    }
    let seg = &p[lo..=hi];
    let median = |part: &[f32]| {
        let mut v = part.to_vec();
        v.sort_by(f32::total_cmp);
        v[v.len() / 2]
    };
    let deviation = |part: &[f32]| {
        let m = median(part);
        part.iter().map(|&v| (v - m).abs()).sum::<f32>()
    };
    let n = seg.len();
    let split = (2..=n - 2).min_by(|&a, &b| {
        let cost = |k: usize| deviation(&seg[..k]) + deviation(&seg[k..]);
        cost(a).total_cmp(&cost(b))
    })?;
    let difference = median(&seg[split..]) - median(&seg[..split]);
    if difference.abs() < NEAR_RIM_STEP_FRACTION * contrast {
        return None;
    }
    // The steepest step of the plateaus' sign near the split (sample lo + split − 1
    // is the last of the top face).
    let centre = lo + split - 1;
    let (from, to) = (
        centre.saturating_sub(REACH).max(top),
        (centre + REACH).min(side_end - 1),
    );
    let rising = difference > 0.0;
    let i = (from..=to).max_by(|&a, &b| {
        let d = |k: usize| {
            if rising {
                p[k + 1] - p[k]
            } else {
                p[k] - p[k + 1]
            }
        };
        d(a).total_cmp(&d(b))
    })?;
    area_edge(p, i, REACH, origin)
}

/// The median of `v` after leaving out the values more than three robust standard
/// deviations (1.4826 × the median absolute deviation) from the median: the bands
/// a strip crosses near the rim read its edge, all on the face's side of the rim,
/// and would pull a plain median towards it.
fn robust_median(mut v: Vec<f64>) -> f64 {
    let m = median(&v);
    let deviations: Vec<f64> = v.iter().map(|x| (x - m).abs()).collect();
    let cut = 3.0 * 1.4826 * median(&deviations);
    v.retain(|x| (x - m).abs() <= cut);
    median(&v)
}

/// The near top rim on a top face too thin for [`near_top_rim`]'s plateaus (a camera
/// looking down by 1–3° from a few decimetres shows it 1–5 px tall, within the
/// [`REACH`] rows those leave out), by fitting the band profile `p` about the
/// silhouette's top `far` (its area edge, the far top rim, in `p`'s rows) with the
/// levels of the background B, the top face T, a band D and the side S, and three
/// edges blurred alike by a Gaussian σ and sampled by area:
///
/// ```text
/// p_k = B + (T − B) c_k(far′) + (D − T) c_k(near) + (S − D) c_k(near + w),
/// c_k(e) = ∫_k^{k+1} Φ((u − e)/σ) du.
/// ```
///
/// The band is the rounded or chamfered edge between the face and the side (real
/// disks' rims are rounded): it faces neither the light nor the camera as the face
/// and side do, so it shows as a line of its own, w px tall (w = 0: a sharp edge).
/// The near top rim, where the face's plane meets the side's, is the face's end,
/// `near`; the band's lower edge, which a two-plateau split takes for the rim when
/// the face is thinner than the rows it leaves out, lies w lower.
///
/// The levels come by least squares for each (far′, near, w, σ) of a coarse grid,
/// then of a fine one about the best ([`fit_face_model`]); the face at most
/// [`REACH`] + 2 px tall, the band at most [`BAND_FRACTION`] of the side. The model
/// is fitted with a band and with a sharp edge (w = 0), and the band is taken when
/// it leaves at most [`BAND_GAIN`] of the sharp edge's misfit.
///
/// A face less than 2σ tall is not resolved: two edges blurred alike are told apart
/// only that far apart, and closer the face's level and height trade off (its
/// level may even leave the profile's range, by more than a tenth of it). What the
/// blurred bump fixes is its centre and its area, so the near rim, half the fitted
/// height below the centre, is off by less than σ, where the silhouette's top is
/// off by the whole face. Alone, such a face may be no more than the far rim's
/// anti-aliased row; a band under it shows where it ends.
/// The answer is refused (`None`) when
/// - the fitted S is not the side's own level (the median of the side's rows from
///   `REACH` + 3 px below the silhouette's top to `side_end`, which a thin line across
///   the face, a strip, does not move), or T differs from it by less than
///   [`NEAR_RIM_STEP_FRACTION`] of `contrast` (no face seen);
/// - the band's level D differs from T by less than that: the face goes on beyond
///   the rows fitted, and the plateaus read it.
fn fit_thin_face(p: &[f32], far: f64, side_end: usize, contrast: f32) -> Option<ThinFace> {
    let top = far.ceil() as usize;
    let side_rows = p.get(top + REACH + 3..side_end.checked_sub(REACH)?)?;
    if side_rows.len() < 3 {
        return None;
    }
    let mut side_rows: Vec<f64> = side_rows.iter().map(|&v| f64::from(v)).collect();
    let side_level = upper_median(&mut side_rows);
    let widest_band = BAND_FRACTION * (side_end as f64 - far);
    let first = (far.floor() as usize).checked_sub(REACH)?;
    let last = side_end.min(top + REACH + 5 + widest_band.ceil() as usize);
    let rows: Vec<(f64, f64)> = (first..last).map(|k| (k as f64, f64::from(p[k]))).collect();
    // A band is taken only where it explains the profile far better than a sharp
    // edge: with a face up to 5 px tall, a sharp rim's face can also be fitted as a
    // sliver at the far rim above a "band" that is the face itself.
    let sharp = fit_face_model(&rows, far, 0.0)?;
    let best = fit_face_model(&rows, far, widest_band)
        .filter(|banded| banded.ssr < BAND_GAIN * sharp.ssr)
        .unwrap_or(sharp);
    let (lo, hi) = rows
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| {
            (lo.min(r.1), hi.max(r.1))
        });
    let margin = 0.1 * (hi - lo);
    let in_range = best
        .levels
        .iter()
        .all(|&v| (lo - margin..=hi + margin).contains(&v));
    let resolved = in_range && best.near - best.far >= 2.0 * best.sigma;
    let [_, face, band, side] = best.levels.into();
    let least_step = f64::from(NEAR_RIM_STEP_FRACTION * contrast);
    let step = (face - side_level).abs();
    let side_agrees = (side - side_level).abs() < 0.5 * step;
    // A band lit like the face is the face going on beyond the rows fitted.
    let band_distinct = best.band == 0.0 || (band - face).abs() >= least_step;
    // A band is told from the face's own shading, or the side's, only when it is
    // darker or brighter than both (a level between theirs may be a face taller
    // than the fit reaches, shaded across). And a face above a band must show:
    // some row of it beyond the band's level, on the face's side, by more than the
    // noise. Else the "face" is the blur of a sharp far rim, and the "band" a face
    // taller than the fit reaches.
    let noise = mad_sigma(&side_rows, side_level).max(1.0);
    let face_rows = (best.far.floor().max(0.0) as usize)..(best.near.ceil() as usize).min(p.len());
    let face_seen = p[face_rows]
        .iter()
        .any(|&v| (f64::from(v) - band) * (face - band).signum() > FACE_SEEN_SIGMAS * noise);
    let beyond_both = (band - face) * (band - side) > 0.0;
    let band_seen = (band - side).abs() >= least_step && beyond_both && face_seen;
    (side_agrees && band_distinct && step >= least_step).then_some(ThinFace {
        near: best.near,
        band: if band_seen { best.band } else { 0.0 },
        side: side_level,
        least_step,
        resolved,
    })
}

/// A top face seen by [`fit_thin_face`]: the near top rim and the band's height
/// below it \[px\], the side's level, the least step between levels seen, and
/// whether the face's level and height were told apart.
struct ThinFace {
    near: f64,
    band: f64,
    side: f64,
    least_step: f64,
    resolved: bool,
}

impl ThinFace {
    /// Whether `edge`, the plateaus' reading on the profile `p`, is this face's
    /// band's lower edge, so that the plateaus were the band and the side: the
    /// band ends at `edge` (within a pixel), and the side follows it, its level
    /// on the band's height of rows below the edge's blur. Where the plateaus'
    /// edge is the rim itself, a band lies under it: a face taller than the fit
    /// reaches, which the fit can take for a sliver at the far rim above a band.
    fn band_ends_at(&self, p: &[f32], edge: f64) -> bool {
        let below = (edge + 2.0).ceil() as usize..(edge + 2.0 + self.band).ceil() as usize;
        self.band >= 1.0
            && (self.near + self.band - edge).abs() <= 1.0
            && p.get(below).is_some_and(|rows| {
                rows.iter()
                    .all(|&v| (f64::from(v) - self.side).abs() < self.least_step)
            })
    }
}

/// The near top rim z_t on the centre band's profile `p` (rows from the frame's
/// top) by the readers of the module docs in turn: the plateaus across the face,
/// then on the centre band; where those see none, the thin face's fit, when the face
/// is resolved or a band lies under it; else the far top rim `centre.far`.
///
/// A face thinner than the rows the plateaus leave out, above the band of a
/// rounded rim, leaves the band and the side as the two plateaus, and their edge
/// is the band's lower one, the band's height (a few px) below the rim. So when
/// the thin face's fit puts its band's end at the plateaus' edge, its near rim is
/// taken. `thin_face` false leaves the thin face out (a silhouette's top that may
/// not be the disk's). Returns z_t and whether the face was seen.
pub(super) fn read_near_top_rim(
    frame: &FrameView,
    centre: &CentreBand,
    p: &[f32],
    thin_face: bool,
) -> (f64, TopFace) {
    let across = near_top_rim_across(frame, centre);
    near_top_rim_on_profile(p, centre, across, thin_face)
}

/// [`read_near_top_rim`] once the bands across the face have read `across`: the
/// plateaus on the centre band `p` where they read none, then the thin face's fit.
fn near_top_rim_on_profile(
    p: &[f32],
    centre: &CentreBand,
    across: Option<f64>,
    thin_face: bool,
) -> (f64, TopFace) {
    let thin = || {
        thin_face
            .then(|| fit_thin_face(p, centre.far, centre.side_end, centre.contrast))
            .flatten()
    };
    let plateaus =
        across.or_else(|| near_top_rim(p, centre.top, centre.side_end, centre.contrast, 0.0));
    match plateaus {
        Some(edge) => thin()
            .filter(|face| face.band_ends_at(p, edge))
            .map_or((edge, TopFace::Plateaus), |face| {
                (face.near, TopFace::Banded)
            }),
        None => match thin() {
            Some(face) if face.band > 0.0 => (face.near, TopFace::Banded),
            Some(face) if face.resolved => (face.near, TopFace::Thin),
            _ => (centre.far, TopFace::Unseen),
        },
    }
}

/// The best fit of [`fit_thin_face`]'s model to `rows` (row, level) about the far rim
/// `far`, with bands up to `widest_band` px (0: a sharp edge): on a coarse grid, then
/// on a fine one about its best.
fn fit_face_model(rows: &[(f64, f64)], far: f64, widest_band: f64) -> Option<FaceFit> {
    let sigmas = |first: f64, step: f64, count: usize| -> Vec<f64> {
        (0..=count).map(|i| first + step * i as f64).collect()
    };
    // Coarse: edges every 0.2 px, the band in 0.4 px steps.
    let coarse = FaceGrid {
        origin: far - 0.6,
        step: 0.2,
        sigmas: sigmas(0.4, 0.2, 8),
        far: 0..=6,
        height: 1..=5 * (REACH + 2),
        band: (0, 2, (widest_band / 0.4) as usize),
    };
    let best = coarse.best(rows)?;
    // Fine: every 0.05 px about the coarse best, the band in 0.1 px steps.
    let band_from = ((best.band - 0.4) / 0.05).round().max(0.0) as usize;
    let fine = FaceGrid {
        origin: best.far - 0.2,
        step: 0.05,
        sigmas: sigmas((best.sigma - 0.2).max(0.3), 0.05, 8),
        far: 0..=8,
        height: (((best.near - best.far - 0.2) / 0.05).round().max(1.0) as usize)
            ..=((best.near - best.far + 0.2) / 0.05).round() as usize,
        band: (band_from, 2, if widest_band > 0.0 { 8 } else { 0 }),
    };
    Some(
        fine.best(rows)
            .filter(|b| b.ssr <= best.ssr)
            .unwrap_or(best),
    )
}

/// Noise σ (the side's rows') by which a thin face must show beyond its band.
const FACE_SEEN_SIGMAS: f64 = 3.0;

/// How much of a sharp edge's squared misfit a band must leave, at most, to be
/// taken: a rounded rim's band, lit like neither face nor side, leaves a sharp
/// edge's fit a dip of its own depth over several rows.
const BAND_GAIN: f64 = 0.5;

/// The widest band between the top face and the side that [`fit_thin_face`] fits, as
/// a fraction of the rows from the far top rim to the side's end: a rim rounded to
/// a tenth of the disk's thickness.
const BAND_FRACTION: f64 = 0.1;

/// One fit of [`fit_thin_face`]'s model: its edges, blur, levels (B, T, D, S) and
/// squared error.
struct FaceFit {
    far: f64,
    near: f64,
    band: f64,
    sigma: f64,
    levels: Vector4<f64>,
    ssr: f64,
}

/// A grid of [`fit_thin_face`]'s model. Every edge lies on a lattice of positions
/// `origin + step·i`: the far rim at i ∈ `far`, the near rim j ∈ `height` steps
/// below it, the band's end `band.0 + band.1 · m` steps below that, m = 0 ..= `band.2`.
struct FaceGrid {
    origin: f64,
    step: f64,
    sigmas: Vec<f64>,
    far: RangeInclusive<usize>,
    height: RangeInclusive<usize>,
    band: (usize, usize, usize),
}

impl FaceGrid {
    /// The grid point whose least-squares levels fit `rows` (row, level) best.
    fn best(&self, rows: &[(f64, f64)]) -> Option<FaceFit> {
        let (first, stride, count) = self.band;
        let size = self.far.end() + self.height.end() + first + stride * count + 1;
        let edges: Vec<f64> = (0..size)
            .map(|i| self.origin + self.step * i as f64)
            .collect();
        let mut best: Option<FaceFit> = None;
        for &sigma in &self.sigmas {
            let gram = Gram::new(rows, &edges, sigma);
            for i in self.far.clone() {
                for j in self.height.clone() {
                    for m in 0..=count {
                        let end = i + j + first + stride * m;
                        if let Some(levels) = gram.levels([i, i + j, end])
                            && best.as_ref().is_none_or(|b| levels.1 < b.ssr)
                        {
                            best = Some(FaceFit {
                                far: edges[i],
                                near: edges[i + j],
                                band: edges[end] - edges[i + j],
                                sigma,
                                levels: levels.0,
                                ssr: levels.1,
                            });
                        }
                    }
                }
            }
        }
        best
    }
}

/// The sums of products over the fitted rows of the blurred steps c(e) at each
/// lattice edge e, and of them with the levels, for one σ: the normal equations of
/// any three edges' levels follow without going over the rows again.
struct Gram {
    /// Rows fitted, Σ v and Σ v².
    count: f64,
    sum: f64,
    sum_sq: f64,
    /// Σ c_e, Σ c_e v per edge, and Σ c_e c_f per pair.
    cover: Vec<f64>,
    cover_v: Vec<f64>,
    cross: DMatrix<f64>,
}

impl Gram {
    fn new(rows: &[(f64, f64)], edges: &[f64], sigma: f64) -> Self {
        let columns: Vec<Vec<f64>> = edges
            .iter()
            .map(|&e| {
                rows.iter()
                    .map(|&(k, _)| blurred_step_coverage(k, e, sigma).0)
                    .collect()
            })
            .collect();
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let values: Vec<f64> = rows.iter().map(|r| r.1).collect();
        Gram {
            count: rows.len() as f64,
            sum: values.iter().sum(),
            sum_sq: dot(&values, &values),
            cover: columns.iter().map(|c| c.iter().sum()).collect(),
            cover_v: columns.iter().map(|c| dot(c, &values)).collect(),
            cross: DMatrix::from_fn(edges.len(), edges.len(), |e, f| {
                dot(&columns[e], &columns[f])
            }),
        }
    }

    /// The levels (B, T, D, S) for the edges at lattice points `[far, near, end]`, and
    /// their squared error: with u = (1, c_far, c_near, c_end) the model's regressors
    /// are x = M u, x = (1 − c_far, c_far − c_near, c_near − c_end, c_end), so the
    /// normal equations are M (Σ u uᵀ) Mᵀ L = M Σ u v. With no band (end = near), D is
    /// T's and the model has three levels.
    fn levels(&self, edges: [usize; 3]) -> Option<(Vector4<f64>, f64)> {
        let u_sum = |e: Option<usize>, f: Option<usize>| match (e, f) {
            (None, None) => self.count,
            (Some(e), None) | (None, Some(e)) => self.cover[e],
            (Some(e), Some(f)) => self.cross[(e, f)],
        };
        let index = |r: usize| (r > 0).then(|| edges[r - 1]);
        let uu = Matrix4::from_fn(|r, c| u_sum(index(r), index(c)));
        let uv = Vector4::from_fn(|r, _| index(r).map_or(self.sum, |e| self.cover_v[e]));
        #[rustfmt::skip]
        let m = Matrix4::new(
            1.0, -1.0, 0.0, 0.0,
            0.0, 1.0, -1.0, 0.0,
            0.0, 0.0, 1.0, -1.0,
            0.0, 0.0, 0.0, 1.0,
        );
        let mut xx = m * uu * m.transpose();
        let mut xy = m * uv;
        let banded = edges[2] != edges[1];
        if !banded {
            // D has no rows: tie it to T.
            xx.row_mut(2).fill(0.0);
            xx.column_mut(2).fill(0.0);
            xx[(2, 2)] = 1.0;
            xy[2] = 0.0;
        }
        let mut levels = xx.cholesky()?.solve(&xy);
        let ssr = self.sum_sq - 2.0 * levels.dot(&xy) + levels.dot(&(xx * levels));
        if !banded {
            levels[2] = levels[1];
        }
        Some((levels, ssr))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A column's profile down the disk's top: background, a thin top face, a band
    /// `band` px tall (the rounded rim) and the side, each edge blurred by σ and
    /// sampled by area, as [`fit_thin_face`] models it.
    fn profile(far: f64, near: f64, band: f64, levels: [f64; 4]) -> Vec<f32> {
        let sigma = 0.8;
        let [b, t, d, s] = levels;
        (0..120)
            .map(|k| {
                let c = |e: f64| blurred_step_coverage(k as f64, e, sigma).0;
                let band_edge = if band > 0.0 { c(near + band) } else { c(near) };
                (b + (t - b) * c(far) + (d - t) * c(near) + (s - d) * band_edge) as f32
            })
            .collect()
    }

    /// The face's end is the rim, whether a band darker than face and side lies below
    /// it or the edge is sharp; the band's own lower edge is not taken for it.
    #[test]
    fn a_thin_face_ends_at_the_rim_above_a_rounded_edge() {
        for (near, band) in [(42.0, 5.0), (41.37, 3.5), (42.6, 0.0)] {
            let far = 38.2;
            let p = profile(far, near, band, [25.0, 198.0, 111.0, 160.0]);
            let face = fit_thin_face(&p, far, 110, 140.0).expect("a face is seen");
            assert!(
                (face.near - near).abs() < 0.06,
                "band {band}: rim at {near}, found {}",
                face.near
            );
            assert!(
                (face.band - band).abs() < 0.15,
                "band {band}: {}",
                face.band
            );
        }
    }

    /// The centre band of [`profile`]'s disk: far rim `far`, side to row 110.
    fn centre_band(far: f64, contrast: f32) -> CentreBand {
        CentreBand {
            x_centre: 0.0,
            half_span: 0.0,
            half_width: 2,
            top: far.ceil() as usize,
            far,
            side_end: 110,
            contrast,
        }
    }

    /// A face 1 px tall above a band 5.5 px tall (a rounded rim seen from 2° above,
    /// blurred by σ = 0.8 px): the plateaus read the band's lower edge, 5.5 px below
    /// the rim; the fit, which cannot tell the face's level from its height, ends
    /// the face within σ/2 of the rim, and its rim is taken.
    #[test]
    fn the_plateaus_edge_under_a_face_thinner_than_the_blur_is_the_bands() {
        let (far, near, band) = (40.7, 41.7, 5.5);
        let p = profile(far, near, band, [25.0, 200.0, 116.0, 160.0]);
        let plateaus = near_top_rim(&p, far.ceil() as usize, 110, 135.0, 0.0)
            .expect("the band and the side are two plateaus");
        assert!(
            (plateaus - (near + band)).abs() < 0.3,
            "plateaus at {plateaus}"
        );
        let (z_t, face) = near_top_rim_on_profile(&p, &centre_band(far, 135.0), None, true);
        assert!((z_t - near).abs() < 0.4, "rim at {near}, read {z_t}");
        assert_eq!(face, TopFace::Banded);
    }

    /// Above a sharp edge, blurred by σ = 0.8 px: a face 0.3 px tall shows nothing
    /// to read, so the far rim stands in (`Unseen`); a face 2.5 px tall is fitted
    /// and ended within σ (`Thin`).
    #[test]
    fn a_thin_face_above_a_sharp_edge_is_read_within_the_blur() {
        let far = 40.7;
        let p = profile(far, far + 0.3, 0.0, [25.0, 200.0, 160.0, 160.0]);
        let (z_t, face) = near_top_rim_on_profile(&p, &centre_band(far, 135.0), None, true);
        assert_eq!(face, TopFace::Unseen);
        assert!((z_t - far).abs() < 1e-9, "far rim {far}, read {z_t}");
        let near = far + 2.5;
        let p = profile(far, near, 0.0, [25.0, 200.0, 160.0, 160.0]);
        let (z_t, face) = near_top_rim_on_profile(&p, &centre_band(far, 135.0), None, true);
        assert_eq!(face, TopFace::Thin);
        assert!((z_t - near).abs() < 0.8, "rim at {near}, read {z_t}");
    }

    /// The plateaus' edge is the rim itself, and no band of the fit replaces it: a
    /// face 11 px tall above a band (the fit reaches 5 px faces, and may take a
    /// sliver at the far rim for one), and a face 9 px tall shaded across (its
    /// lower half between its upper half's level and the side's, as a face lit
    /// from above and behind shows).
    #[test]
    fn a_face_taller_than_the_fit_keeps_the_plateaus_edge() {
        // (far rim, the face's end or its shading's step, the side's start, levels
        // B T D S, contrast, the rim)
        for (far, split, side, levels, contrast, rim) in [
            (38.2, 49.2, 53.2, [23.0, 197.0, 114.0, 159.0], 136.0, 49.2),
            (47.3, 52.5, 56.7, [12.0, 89.0, 100.0, 143.0], 130.0, 56.7),
        ] {
            let p = profile(far, split, side - split, levels);
            let (z_t, face) = near_top_rim_on_profile(&p, &centre_band(far, contrast), None, true);
            assert!((z_t - rim).abs() < 0.3, "rim at {rim}, read {z_t}");
            assert_eq!(face, TopFace::Plateaus);
        }
    }

    /// A face that goes on past the rows fitted (a thick face) is left to the
    /// plateaus, not cut short by a band lit like the face.
    #[test]
    fn a_thick_face_is_left_to_the_plateaus() {
        let p = profile(38.2, 52.0, 0.0, [25.0, 198.0, 198.0, 120.0]);
        assert!(fit_thin_face(&p, 38.2, 110, 140.0).is_none());
    }
}
