//! The near top rim z_t from the frames in which the rolling disk leans towards the
//! camera.
//!
//! At rest the top face shows as an ellipse 2R sin ε_t tall (ε_t the camera's
//! elevation above the face's plane): a camera level with the face, as the thesis
//! used it (fig. 3.3), sees it a pixel or less tall, under a blur as wide, and no
//! reading of the rest frame ([`super::top_rim`]) can tell the near top rim from the
//! far one; the scale of eq. 3.10 then takes the silhouette's top for z_t. While the
//! disk rolls, the face tilts by φ towards the camera once a turn (the contact point
//! facing it, χ = π) and is then 2R sin(ε_t + φ) tall: 3–8 px more at φ = 0.01–0.03
//! on a disk 300 px wide. The near top rim does not move relative to the near bottom
//! rim, apart from terms of order 2Hφ tan ε_t and 2Hφ² (below 0.01 px): in every
//! frame it lies the rest thickness z_b − z_t above the bottom rim, whose lift z_rim
//! the rim gauge measures. So each frame that shows the face resolved gives
//!
//! ```text
//! z_t = near(frame) + z_rim(frame),
//! ```
//!
//! and z_t is the median over those frames.
//!
//! A frame's near rim comes from the centre band's profile across the top of the
//! disk, fitted with three levels, background B, top face T and side S, and two
//! edges blurred alike by a Gaussian σ and sampled by area (the model of
//! `top_rim::fit_thin_face`, here fitted by Levenberg–Marquardt from a few starts):
//!
//! ```text
//! p_k = B + (T − B) c_k(far) + (S − T) c_k(near),   c_k(e) = ∫_k^{k+1} Φ((u − e)/σ) du.
//! ```
//!
//! A frame counts when its face is resolved: at least 3σ tall (closer, the face's
//! level and height trade off, and a coded picture's near rim drifts), with levels
//! inside the profile's range and a face level apart from the side's. The rest of
//! the frames, the disk leaning away or the face lit like the side, are left out,
//! and so are B pictures when enough others count ([`near_top_rim_leaning`]).
//! `analyse` reads z_t so only when the rest frame's face is under
//! [`THIN_AT_REST_PX`]: a face the rest frame resolves is read there, still. A
//! face the rest frame ends by a rounded rim's band (`TopFace::Banded`) is read
//! again too: from the rest profile alone such a band cannot be told from the
//! face's own shading, and where it is shading the rest frame's z_t is pixels off
//! while the leaning frames are not.

use std::ops::Range;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use super::Calibration;
use super::calibration::REACH;
use super::profile::{blurred_step_coverage as coverage, row_band_mean};
use super::top_rim::TopFace;
use crate::footage::FrameView;
use crate::numeric::lsq::levenberg_marquardt;
use crate::numeric::{mad_sigma, median};

/// Largest tilt towards the camera the profile makes room for \[rad\]: the far top
/// rim rises by up to this fraction of the disk's diameter above its rest row.
const MAX_LEAN: f64 = 0.08;
/// Rows of the side below the rest frame's near top rim in the profile.
const SIDE_ROWS: usize = REACH + 8;
/// The face's level must differ from the side's by this fraction of the profile's
/// contrast (as [`super::top_rim`]'s plateaus).
const FACE_STEP_FRACTION: f64 = 0.15;
/// The face's height from the silhouette's top to the near rim's guess below which a
/// frame is not fitted \[px\].
const MIN_GUESS_PX: f64 = 2.0;
/// Fewest frames with a resolved face for a reading.
pub const MIN_FRAMES: usize = 10;

/// The tallest face at rest \[px\] this reading stands in for: the rest frame's own
/// readings need plateaus REACH rows clear of both edges, and below this leave the
/// face to `top_rim::fit_thin_face` or the silhouette's top.
pub const THIN_AT_REST_PX: f64 = (REACH + 2) as f64;

/// Where a frame's centre-band profile across the disk's top is read (side-view
/// rows and columns, px), and where the rest frame put the near top rim.
#[derive(Debug, Clone)]
pub struct LeanGauge {
    columns: Range<usize>,
    rows: Range<usize>,
    rest_near: f64,
}

impl LeanGauge {
    /// The profile's place from the rest calibration `cal` and the silhouette's top
    /// at rest `far` (the far top rim; `None` when `top_rim::silhouette_top` saw no
    /// face 1.5 px above z_t), on the columns `band` the frames are read on (the
    /// centre line's five columns within it), in a side view `height` rows tall.
    /// `None` when the rest frame shows a face of [`THIN_AT_REST_PX`] or more (read
    /// there, without the motion's blur and the codec's work on moving pictures),
    /// when the config gives z_t (`top_face` [`TopFace::Given`]), or when the
    /// disk's top leaves no room.
    pub fn new(
        cal: &Calibration,
        top_face: TopFace,
        far: Option<f64>,
        band: Range<usize>,
        height: usize,
    ) -> Option<Self> {
        let far = far.unwrap_or(cal.z_t);
        if top_face == TopFace::Given || cal.z_t - far >= THIN_AT_REST_PX {
            return None;
        }
        let centre = cal.x_centre().floor() as usize;
        let columns = centre.saturating_sub(2).max(band.start)..(centre + 3).min(band.end);
        let lean = MAX_LEAN * (cal.x_r - cal.x_l);
        let top = (far - lean).floor() - (REACH + 2) as f64;
        let top = top.max(0.0) as usize;
        let bottom = ((cal.z_t.ceil() as usize) + SIDE_ROWS)
            .min((0.5 * (cal.z_t + cal.z_base)).floor() as usize)
            .min(height);
        (columns.len() >= 3 && bottom > top + 2 * REACH + 8).then_some(LeanGauge {
            columns,
            rows: top..bottom,
            rest_near: cal.z_t,
        })
    }

    /// The frame's profile: the mean level of each row over the gauge's columns.
    pub fn read(&self, side: &FrameView) -> Vec<f32> {
        self.rows
            .clone()
            .map(|y| row_band_mean(side, y, self.columns.start, self.columns.end))
            .collect()
    }
}

/// z_t from the frames that show the face leaning towards the camera.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LeaningTopRim {
    /// The near top rim's row at rest \[px\]: the median of near + z_rim.
    pub z_t: f64,
    /// Its standard error \[px\]: 1.2533 × the robust σ over √N.
    pub se: f64,
    /// Frames with a resolved face, N.
    pub frames: usize,
    /// Whether B pictures that showed the face were left out (enough others did).
    #[serde(default)]
    pub b_pictures_left_out: bool,
    /// The tallest face among them \[px\] (near − far).
    pub tallest_face_px: f64,
}

/// z_t from the frames' `profiles` (from `gauge`), their rim
/// heights `z_rim_px` (from the rest edge, `None` where not measured) and the
/// codec's `picture_types` ('I', 'P', 'B'; `None` for a folder of frames), or `None`
/// when fewer than [`MIN_FRAMES`] frames show the face resolved.
///
/// B pictures are left out when at least [`MIN_FRAMES`] others show the face: a B
/// picture is coded as a blend of the pictures before and after it, and the far rim
/// sweeps by the near one within a coding block. With a face under 5 px at rest, the
/// B pictures' near rim reads 0.07–0.30 px higher than the P pictures' or 0.03–0.13
/// px lower (up to 0.53 px off the truth), at quantisers from fine to coarse, while
/// lossless frames read within 0.05 px of the truth.
pub fn near_top_rim_leaning(
    gauge: &LeanGauge,
    profiles: &[Vec<f32>],
    z_rim_px: &[Option<f64>],
    picture_types: &[Option<char>],
) -> Option<LeaningTopRim> {
    use rayon::prelude::*;
    let origin = gauge.rows.start as f64;
    // (z_t, the face's height, a B picture)
    let readings: Vec<(f64, f64, bool)> = profiles
        .par_iter()
        .zip(z_rim_px)
        .zip(picture_types)
        .filter_map(|((p, z), kind)| {
            let z = (*z)?;
            let face = resolved_face(p, gauge.rest_near - origin - z)?;
            Some((
                origin + face.near + z,
                face.near - face.far,
                *kind == Some('B'),
            ))
        })
        .collect();
    let predicted = readings.iter().filter(|r| !r.2).count();
    let b_pictures_left_out = predicted >= MIN_FRAMES && predicted < readings.len();
    let readings: Vec<&(f64, f64, bool)> = readings
        .iter()
        .filter(|r| predicted < MIN_FRAMES || !r.2)
        .collect();
    if readings.len() < MIN_FRAMES {
        return None;
    }
    let values: Vec<f64> = readings.iter().map(|r| r.0).collect();
    let z_t = median(&values);
    let spread = mad_sigma(&values, z_t);
    Some(LeaningTopRim {
        z_t,
        se: 1.2533 * spread / (values.len() as f64).sqrt(),
        frames: values.len(),
        b_pictures_left_out,
        tallest_face_px: readings.iter().map(|r| r.1).fold(0.0, f64::max),
    })
}

/// A fitted face: its edges in the profile's rows (row k covers [k, k+1)).
#[derive(Debug, Clone, Copy)]
struct Face {
    far: f64,
    near: f64,
}

/// The three-level fit of one profile (module docs), started from the near rim at
/// `near_guess` (the rest frame's reading carried by the rim's lift) and at a few
/// heights below the silhouette's top; `None` unless the face is resolved.
fn resolved_face(p: &[f32], near_guess: f64) -> Option<Face> {
    let n = p.len();
    let v: Vec<f64> = p.iter().map(|&x| f64::from(x)).collect();
    let background = median(&v[..3]);
    let side = median(&v[n - 5..]);
    let contrast = (side - background).abs();
    if contrast < 1.0 {
        return None;
    }
    // The silhouette's first row: the first to depart from the background by as
    // much as a face must differ from the side, whichever the face's level.
    let first = v
        .iter()
        .position(|&x| (x - background).abs() > FACE_STEP_FRACTION * contrast)?;
    let far0 = first as f64 - 0.5;
    // A face guessed under MIN_GUESS_PX is not fitted: it could not be told from its
    // blur, and most frames, the disk leaning away, are such (this keeps the fits to
    // the frames that count).
    if near_guess - far0 < MIN_GUESS_PX {
        return None;
    }
    let model = |q: &[f64], out: &mut [f64]| {
        let sigma = q[5].exp();
        for (k, o) in out.iter_mut().enumerate() {
            let (cf, _, _) = coverage(k as f64, q[3], sigma);
            let (cn, _, _) = coverage(k as f64, q[4], sigma);
            *o = q[0] * (1.0 - cf) + q[1] * (cf - cn) + q[2] * cn - v[k];
        }
    };
    let jacobian = |q: &[f64], jac: &mut DMatrix<f64>| {
        let sigma = q[5].exp();
        for k in 0..n {
            let (cf, df, sf) = coverage(k as f64, q[3], sigma);
            let (cn, dn, sn) = coverage(k as f64, q[4], sigma);
            jac[(k, 0)] = 1.0 - cf;
            jac[(k, 1)] = cf - cn;
            jac[(k, 2)] = cn;
            jac[(k, 3)] = (q[1] - q[0]) * df;
            jac[(k, 4)] = (q[2] - q[1]) * dn;
            jac[(k, 5)] = (q[1] - q[0]) * sf + (q[2] - q[1]) * sn;
        }
    };
    let best = [near_guess - far0, 3.0, 5.0, 8.0]
        .iter()
        .filter_map(|&height| {
            let near0 = far0 + height.max(1.0);
            if near0 > (n - 4) as f64 {
                return None;
            }
            let face = median(&v[(far0 + 1.0) as usize..=(near0 - 0.5).max(far0 + 1.0) as usize]);
            let q0 = [background, face, side, far0, near0, 0.0];
            levenberg_marquardt(model, jacobian, &q0, n)
        })
        .min_by(|a, b| a.ssr.total_cmp(&b.ssr))?;
    let q = best.params.as_slice();
    let (levels, far, near, sigma) = ([q[0], q[1], q[2]], q[3], q[4], q[5].exp());
    let (lo, hi) = v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
            (lo.min(x), hi.max(x))
        });
    let margin = 0.1 * (hi - lo);
    let in_range = levels
        .iter()
        .all(|x| (lo - margin..=hi + margin).contains(x));
    let resolved = near - far >= 3.0 * sigma && (0.2..=4.0).contains(&sigma);
    let inside = far > 0.0 && near < (n - 3) as f64;
    let face_seen = (levels[1] - levels[2]).abs() >= FACE_STEP_FRACTION * contrast;
    (in_range && resolved && inside && face_seen).then_some(Face { far, near })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A profile drawn from the model itself: edges at `far` and `near`, blur σ.
    fn drawn(levels: [f64; 3], far: f64, near: f64, sigma: f64, n: usize) -> Vec<f32> {
        (0..n)
            .map(|k| {
                let (cf, _, _) = coverage(k as f64, far, sigma);
                let (cn, _, _) = coverage(k as f64, near, sigma);
                (levels[0] * (1.0 - cf) + levels[1] * (cf - cn) + levels[2] * cn) as f32
            })
            .collect()
    }

    /// Frames of a disk rolling with a face 0.8 px tall at rest: once a turn it
    /// leans towards the camera and the face grows to 0.8 + 5 sin²(χ/2) px, while the
    /// near top rim rides the bottom rim's lift z = 2 cos²(χ/2) px (rows grow
    /// downward, so it sits z higher). z_t comes back as the rest row of the near rim
    /// from the frames that show the face resolved, and not from the others.
    #[test]
    fn the_leaning_frames_give_the_rest_row_of_the_near_top_rim() {
        let (rows, rest_near) = (10..44, 30.4);
        let gauge = LeanGauge {
            columns: 0..5,
            rows: rows.clone(),
            rest_near,
        };
        let origin = rows.start as f64;
        let (mut profiles, mut heights) = (Vec::new(), Vec::new());
        for frame in 0..120 {
            let chi = 0.45 * f64::from(frame);
            let lift = 2.0 * (0.5 * chi).cos().powi(2);
            let face = 0.8 + 5.0 * (0.5 * chi).sin().powi(2);
            let near = rest_near - lift - origin;
            profiles.push(drawn(
                [15.0, 150.0, 210.0],
                near - face,
                near,
                0.9,
                rows.len(),
            ));
            heights.push(Some(lift));
        }
        let reading = near_top_rim_leaning(&gauge, &profiles, &heights, &vec![None; heights.len()])
            .expect("a reading");
        assert!((reading.z_t - rest_near).abs() < 0.02, "{reading:?}");
        assert!(
            reading.frames >= MIN_FRAMES && reading.frames < 120,
            "{reading:?}"
        );
        assert!((reading.tallest_face_px - 5.8).abs() < 0.1, "{reading:?}");
    }

    /// The fit recovers the near rim of a face 4 px tall under a 1 px blur, brighter
    /// or darker than the side, and refuses one of 0.8 px.
    #[test]
    fn a_leaning_face_is_resolved_and_a_thin_one_refused() {
        for levels in [
            [12.0, 170.0, 230.0],
            [12.0, 60.0, 200.0],
            [220.0, 90.0, 160.0],
        ] {
            let p = drawn(levels, 10.3, 14.4, 1.0, 30);
            let face = resolved_face(&p, 13.0)
                .unwrap_or_else(|| panic!("{levels:?}: a 4 px face not resolved"));
            assert!((face.near - 14.4).abs() < 0.02, "{levels:?}: {face:?}");
            assert!((face.far - 10.3).abs() < 0.05, "{levels:?}: {face:?}");
            let thin = drawn(levels, 10.3, 11.1, 1.0, 30);
            assert!(
                resolved_face(&thin, 11.0).is_none(),
                "{levels:?}: 0.8 px face resolved"
            );
        }
    }
}
