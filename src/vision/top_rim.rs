//! The near top rim z_t (thesis fig. 3.3): where the top face, seen from a camera
//! a little above the plate, meets the camera-facing side, on the centre line.
//! With the plate line it sets the vertical scale δ = 2H/(z_base − z_t) (eq. 3.10
//! corrected), so an error of 1 px in z_t is 2–5 % in φ and E on a disk 20–50 px
//! thick.
//!
//! Three readings, tried in turn:
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
//! 3. [`thin_top_face`]: a face too thin for the plateaus, fitted with its blur.
//!
//! When none sees a face the silhouette's top (the far top rim) stands for z_t.
//! A face under [`super::leaning_face::THIN_AT_REST_PX`] is read again, in the
//! frames in which the rolling disk leans towards the camera and shows it several
//! pixels tall ([`super::leaning_face`]), and `analyse` takes that reading.

use nalgebra::{Matrix3, Vector3};

use super::calibration::REACH;
use super::profile::{area_edge, blurred_step_coverage, row_band_mean};
use crate::footage::FrameView;
use crate::numeric::median;

/// Farthest band from the centre line, as a fraction of the disk's half-width a.
/// There the near top rim lies b (1 − √(1 − 0.4²)) = 0.083 b above its lowest point
/// and the far top rim as far below it (b, the face's half-height): within the
/// [`REACH`] rows that [`near_top_rim`] leaves out of the face for faces up to
/// 72 px tall.
const ACROSS_SPAN: f64 = 0.4;

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
const NEAR_RIM_STEP_FRACTION: f32 = 0.15;

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
/// looking down by 1–3° from a few decimetres shows it 1–3 px tall, within the
/// [`REACH`] rows those leave out), by fitting the band profile `p` about the
/// silhouette's top `far` (its area edge, the far top rim, in `p`'s rows) with three
/// levels, background B, top face T and side S, and two edges blurred alike by a
/// Gaussian σ and sampled by area:
///
/// ```text
/// p_k = B + (T − B) c_k(far′) + (S − T) c_k(near),   c_k(e) = ∫_k^{k+1} Φ((u − e)/σ) du
/// ```
///
/// (B, T, S) by least squares for each (far′, near, σ) of a grid, the face at most
/// [`REACH`] + 2 px tall. The answer is refused (`None`) when
/// - the face is less than 2σ tall: two edges blurred alike are told apart only that
///   far apart, and closer the face's level and height trade off;
/// - a fitted level lies beyond the profile's range by more than a tenth of it (the
///   same trade-off);
/// - the fitted S is not the side's own level (the median of the side's rows from
///   `REACH` + 3 px below the silhouette's top to `side_end`, which a thin line across
///   the face, a strip, does not move), or T differs from it by less than
///   [`NEAR_RIM_STEP_FRACTION`] of `contrast` (no face seen).
pub(super) fn thin_top_face(p: &[f32], far: f64, side_end: usize, contrast: f32) -> Option<f64> {
    let top = far.ceil() as usize;
    let side_rows = p.get(top + REACH + 3..side_end.checked_sub(REACH)?)?;
    if side_rows.len() < 3 {
        return None;
    }
    let mut sorted = side_rows.to_vec();
    sorted.sort_by(f32::total_cmp);
    let side_level = f64::from(sorted[sorted.len() / 2]);
    let first = (far.floor() as usize).checked_sub(REACH)?;
    let last = side_end.min(top + REACH + 5);
    let rows: Vec<(f64, f64)> = (first..last).map(|k| (k as f64, f64::from(p[k]))).collect();
    let coverage = |k: f64, e: f64, sigma: f64| blurred_step_coverage(k, e, sigma).0;
    let yy: f64 = rows.iter().map(|r| r.1 * r.1).sum();
    // (SSR, face's height, σ, near, levels)
    let mut best: Option<(f64, f64, f64, f64, Vector3<f64>)> = None;
    for si in 0..18 {
        let sigma = 0.3 + 0.1 * f64::from(si);
        for fi in 0..=40 {
            let far = far - 1.0 + 0.05 * f64::from(fi);
            for ni in 0..=(20 * (REACH + 2) - 4) {
                let near = far + 0.2 + 0.05 * ni as f64;
                // Normal equations of the three levels.
                let (mut xx, mut xy) = (Matrix3::zeros(), Vector3::zeros());
                for &(k, v) in &rows {
                    let (a, b) = (coverage(k, far, sigma), coverage(k, near, sigma));
                    let x = Vector3::new(1.0 - a, a - b, b);
                    xx += x * x.transpose();
                    xy += x * v;
                }
                let Some(levels) = xx.cholesky().map(|c| c.solve(&xy)) else {
                    continue;
                };
                let ssr = yy - 2.0 * levels.dot(&xy) + levels.dot(&(xx * levels));
                if best.as_ref().is_none_or(|b| ssr < b.0) {
                    best = Some((ssr, near - far, sigma, near, levels));
                }
            }
        }
    }
    let (_, height, sigma, near, levels) = best?;
    let (lo, hi) = rows
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| {
            (lo.min(r.1), hi.max(r.1))
        });
    let margin = 0.1 * (hi - lo);
    let in_range = levels
        .iter()
        .all(|&v| (lo - margin..=hi + margin).contains(&v));
    let step = (levels[1] - side_level).abs();
    let resolved = height >= 2.0 * sigma;
    let side_agrees = (levels[2] - side_level).abs() < 0.5 * step;
    (resolved && in_range && side_agrees && step >= f64::from(NEAR_RIM_STEP_FRACTION * contrast))
        .then_some(near)
}
