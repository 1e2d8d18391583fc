//! Two-view clips (thesis §3.3.2, figs. 3.19–3.20): a portrait frame whose top
//! part is the side view seen in a mirror and whose bottom part is the plan
//! view of the disk with a red strip across its top face.
//!
//! The top part goes through the side-view stage as a frame of its own
//! ([`split_views`] makes it a [`FrameView`] without copying); the bottom part
//! gives the strip angle β by eq. 3.23 (colour thresholds on RGB normalised
//! by the image mean), the largest connected component (as MATLAB's
//! BWCONNCOMP) and its first principal component (eq. 3.24).
//!
//! β lies in (−π/2, π/2]: a strip has no head, so β and β + π are the same
//! strip. Making β continuous across ±π/2 is the signal stage's job.
//!
//! # Angle convention
//!
//! β is measured from the image's x axis (columns, rightward) towards the
//! image's *up* direction, i.e. counter-clockwise as the frame is displayed
//! (the thesis's "position in the image" with y pointing up). It is the angle
//! of the strip as seen in the frame: a mirror or camera that flips the image
//! flips the sign of β̇.

use std::ops::Range;

use serde::{Deserialize, Serialize};

use super::VisionError;
use super::components::Labeller;
use super::profile::check_frame;
use crate::footage::{ChannelOrder, FrameView};

/// The top (mirror side view, rows `0..split_row`) and bottom (plan view, rows
/// `split_row..height`) parts of a two-view frame, as views of the same bytes.
pub fn split_views<'a>(
    frame: &FrameView<'a>,
    split_row: usize,
    index: usize,
) -> Result<(FrameView<'a>, FrameView<'a>), VisionError> {
    check_frame(frame, index)?;
    if split_row == 0 || split_row >= frame.height {
        return Err(VisionError::InvalidSetting {
            name: "split_row",
            value: split_row as f64,
            reason: "the split row must leave rows above and below it",
        });
    }
    let top = FrameView {
        height: split_row,
        ..*frame
    };
    let bottom = FrameView {
        height: frame.height - split_row,
        data: &frame.data[split_row * frame.stride..],
        ..*frame
    };
    Ok((top, bottom))
}

/// Finds the row that separates the mirror side view (top) from the plan view
/// (bottom), for clips whose configuration does not give it.
///
/// Assumption: the two views are separated by a full-width band of dark,
/// uniform rows (the mirror's edge or frame, a black divider), somewhere in the
/// middle three quarters of the frame. Each row is scored by its mean intensity
/// plus its mean absolute deviation; the best row of the middle three quarters
/// must score at most half their median row's and be dark (score ≤ 64 of 255).
/// Rows scoring at most 1.5 × best + 2 are dark; the divider is the longest run
/// of them that has a view on either side: a run reaching the frame's first or
/// last row is a margin (the black above a side view's disk, which a darker
/// exposure or tone curve makes as black as the divider), not a divider. Its
/// middle row is returned.
///
/// Without a dark divider (a light plate in both views, two camera images
/// stacked), the views are still apart where no disk is: the plate below the side
/// view's disk and shadow and above the plan view's disk, whose rows are uniform.
/// The middle of the longest run of rows whose mean absolute deviation is at most
/// [`UNIFORM_FRACTION`] of the 90th percentile row's (rows across a disk) is
/// returned, the run at least 1 % of the frame tall.
///
/// Scans the whole frame: call it once per clip, e.g. on the calibration frame.
pub fn find_split_row(frame: &FrameView, index: usize) -> Result<usize, VisionError> {
    check_frame(frame, index)?;
    let (w, h) = (frame.width, frame.height);
    let (lo, hi) = (h / 8, h - h / 8);
    if hi <= lo + 2 {
        return Err(VisionError::NoSplit { frame: index });
    }
    // (mean, mean absolute deviation) of each row's intensity.
    let rows: Vec<(f32, f32)> = (0..h)
        .map(|y| {
            let row = frame.row(y);
            let values = row
                .chunks_exact(3)
                .map(|p| (f32::from(p[0]) + f32::from(p[1]) + f32::from(p[2])) / 3.0);
            let mean = values.clone().sum::<f32>() / w as f32;
            let dev = values.map(|v| (v - mean).abs()).sum::<f32>() / w as f32;
            (mean, dev)
        })
        .collect();
    let scores: Vec<f32> = rows.iter().map(|(mean, dev)| mean + dev).collect();
    let middle = &scores[lo..hi];
    let mut sorted = middle.to_vec();
    sorted.sort_by(f32::total_cmp);
    let median = sorted[sorted.len() / 2];
    let best_score = sorted[0];
    let divider = (best_score <= 0.5 * median && best_score <= 64.0)
        .then(|| {
            // Rows nearly as dark and uniform as the best one: the divider's, or a
            // margin's.
            let near = 1.5 * best_score + 2.0;
            dark_runs(&scores, near)
                .filter(|run| run.start > 0 && run.end < h)
                .filter(|run| (lo..hi).contains(&((run.start + run.end - 1) / 2)))
                .max_by_key(|run| run.len())
        })
        .flatten();
    match divider {
        Some(run) => Ok((run.start + run.end - 1) / 2),
        None => {
            let deviations: Vec<f32> = rows[lo..hi].iter().map(|r| r.1).collect();
            uniform_band(&deviations, h)
                .map(|middle| lo + middle)
                .ok_or(VisionError::NoSplit { frame: index })
        }
    }
}

/// The maximal runs of rows whose score is at most `limit`, as row ranges.
fn dark_runs(scores: &[f32], limit: f32) -> impl Iterator<Item = Range<usize>> + '_ {
    let mut start = None;
    scores
        .iter()
        .chain(std::iter::once(&f32::INFINITY))
        .enumerate()
        .filter_map(move |(k, &score)| match (score <= limit, start) {
            (true, None) => {
                start = Some(k);
                None
            }
            (false, Some(s)) => {
                start = None;
                Some(s..k)
            }
            _ => None,
        })
}

/// A row is uniform, for [`find_split_row`]'s band without a dark divider, when its
/// mean absolute deviation is at most this fraction of the 90th percentile row's
/// (a row across a disk: the disk against the plate). A plate's grain leaves its
/// rows a deviation of their own: a textured light plate (`render --texture 0.1`)
/// 7–12 grey levels, against 30–55 across a disk.
const UNIFORM_FRACTION: f32 = 0.25;

/// The middle of the longest run of uniform rows ([`UNIFORM_FRACTION`]) among rows
/// of mean absolute deviations `deviations` (an index into it), the run at least
/// 1 % of the `height` of the frame; `None` without one.
fn uniform_band(deviations: &[f32], height: usize) -> Option<usize> {
    let mut sorted = deviations.to_vec();
    sorted.sort_by(f32::total_cmp);
    let p90 = *sorted.get(sorted.len() * 9 / 10)?;
    let limit = UNIFORM_FRACTION * p90;
    let mut best: Option<(usize, usize)> = None;
    let mut start = None;
    for (k, &dev) in deviations
        .iter()
        .chain(std::iter::once(&f32::INFINITY))
        .enumerate()
    {
        match (dev <= limit, start) {
            (true, None) => start = Some(k),
            (false, Some(s)) => {
                if best.is_none_or(|(a, b)| k - s > b - a) {
                    best = Some((s, k));
                }
                start = None;
            }
            _ => {}
        }
    }
    let (a, b) = best.filter(|(a, b)| b - a >= (height / 100).max(4))?;
    Some((a + b) / 2)
}

/// Whether a frame is a two-view frame (thesis fig. 3.20), and why.
#[derive(Clone, Debug, PartialEq)]
pub struct LayoutDetection {
    pub two_view: bool,
    /// What was found, for the plan and the report.
    pub evidence: String,
}

/// Least eccentricity of the plan view's red component for it to be a strip: a
/// strip 10 times longer than wide has 0.995; a round red speck 0.
const MIN_STRIP_ECCENTRICITY: f64 = 0.9;

/// A pixel is red when its red channel exceeds this (0–255) and both others
/// times [`RED_DOMINANCE`]: the strip of eq. 3.23 under any white light; white
/// paper (R ≈ G ≈ B) never is.
const RED_MIN_LEVEL: f32 = 60.0;
const RED_DOMINANCE: f32 = 1.6;

/// Detects the two-view layout on a rest frame: a frame is two-view when it
/// holds all that makes one, a dark full-width divider ([`find_split_row`]), a
/// side view above it (at least 1 % of it brighter than the frame's Otsu level:
/// a side view's dark background above the disk is no view) and, below it, a
/// strip: at least 1/1000 of the plan view's area red, and an
/// elongated component ([`auto_colour_thresholds`], then [`StripFinder`],
/// eccentricity at least 0.9) of that size. A side view has no strip below its darkest band (the shadow under
/// a light plate, the black below a plate's front edge), so either test failing
/// makes it a side view.
pub fn detect_two_view(frame: &FrameView, index: usize) -> LayoutDetection {
    let side = |evidence: String| LayoutDetection {
        two_view: false,
        evidence,
    };
    let Ok(row) = find_split_row(frame, index) else {
        return side("no dark or uniform full-width band to divide two views".into());
    };
    let Ok((upper, plan)) = split_views(frame, row, index) else {
        return side(format!("no plan view below row {row}"));
    };
    // A side view above the divider: something as bright as the frame's bright
    // class (Otsu) on at least 1 % of it, not only the dark above a disk.
    let level = super::threshold::Threshold::otsu(frame, index).map_or(f32::MAX, |t| t.level());
    let bright = (0..upper.height)
        .flat_map(|y| (0..upper.width).map(move |x| (x, y)))
        .filter(|&(x, y)| upper.intensity(x, y) > level)
        .count();
    if bright * 100 < upper.width * upper.height {
        return side(format!("nothing bright above the band at row {row}"));
    }
    let min_pixels = (plan.width * plan.height / 1000).max(StripFinder::MIN_PIXELS);
    // Red, not merely redder than the rest (white paper over a bluish plate is).
    let red = (0..plan.height)
        .flat_map(|y| (0..plan.width).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let [r, g, b] = plan.rgb(x, y).map(f32::from);
            r > RED_MIN_LEVEL && r > RED_DOMINANCE * g && r > RED_DOMINANCE * b
        })
        .count();
    if red < min_pixels {
        return side(format!(
            "{red} red pixels below the band at row {row}, fewer than a strip's {min_pixels}"
        ));
    }
    let strip = auto_colour_thresholds(&plan, index).ok().and_then(|t| {
        StripFinder::new(t, ThresholdSource::Automatic)
            .with_min_pixels(min_pixels)
            .measure(&plan, index)
            .ok()
    });
    match strip {
        Some(s) if s.eccentricity >= MIN_STRIP_ECCENTRICITY => LayoutDetection {
            two_view: true,
            evidence: format!(
                "views divided at row {row} (a dark or uniform band); below it a red strip of {} px, eccentricity {:.3}",
                s.pixels, s.eccentricity
            ),
        },
        Some(s) => side(format!(
            "below the band at row {row} the red component ({} px) is not a strip: \
             eccentricity {:.3} < {MIN_STRIP_ECCENTRICITY}",
            s.pixels, s.eccentricity
        )),
        None => side(format!("no red strip below the band at row {row}")),
    }
}

/// Colour thresholds of eq. 3.23 on the channels divided by the image's mean
/// intensity: a pixel is strip when R > r, G < g and B < b.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ColourThresholds {
    pub r: f64,
    pub g: f64,
    pub b: f64,
}

/// How the colour thresholds were chosen: recorded as provenance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ThresholdSource {
    Given,
    /// [`auto_colour_thresholds`] on a plan-view frame.
    Automatic,
}

/// The strip found in one plan-view frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Strip {
    /// Strip angle β ∈ (−π/2, π/2], rad (eq. 3.24; see the module's convention).
    pub beta: f64,
    /// Pixels in the largest connected component (the strip).
    pub pixels: usize,
    /// Pixels that passed the colour thresholds (strip plus isolated specks).
    pub candidates: usize,
    /// Centroid of the strip, px, image coordinates of the plan view.
    pub centroid_px: [f64; 2],
    /// √(1 − λ₂/λ₁) of the strip's covariance: 1 for a line, 0 for a disc.
    /// An angle from a blob with eccentricity well below 1 is not to be trusted.
    pub eccentricity: f64,
    /// Standard deviations along the principal axes, √λ₁ and √λ₂, px
    /// (a strip of length L and width W gives L/√12 and W/√12).
    pub axes_sd_px: [f64; 2],
}

/// Finds the strip frame after frame, reusing its buffers.
#[derive(Debug)]
pub struct StripFinder {
    thresholds: ColourThresholds,
    source: ThresholdSource,
    min_pixels: usize,
    mask: Vec<bool>,
    labeller: Labeller,
    /// The last strip's first pixel and the plan view's size, for [`Self::strip_mask`].
    last: Option<((usize, usize), usize, usize)>,
}

impl StripFinder {
    /// Default smallest strip, px.
    pub const MIN_PIXELS: usize = 20;

    pub fn new(thresholds: ColourThresholds, source: ThresholdSource) -> Self {
        Self {
            thresholds,
            source,
            min_pixels: Self::MIN_PIXELS,
            mask: Vec::new(),
            labeller: Labeller::default(),
            last: None,
        }
    }

    /// The smallest component accepted as the strip.
    pub fn with_min_pixels(mut self, min_pixels: usize) -> Self {
        self.min_pixels = min_pixels.max(2);
        self
    }

    pub fn thresholds(&self) -> (ColourThresholds, ThresholdSource) {
        (self.thresholds, self.source)
    }

    /// The strip's pixels in the last frame [`Self::measure`] found one in: its
    /// connected component of the colour mask (eq. 3.23), row-major over the plan
    /// view, with the view's width; `None` when the last frame had no strip.
    pub fn strip_mask(&mut self) -> Option<(Vec<bool>, usize)> {
        let (seed, w, h) = self.last?;
        Some((self.labeller.pixels_of(&self.mask, w, h, seed), w))
    }

    /// β and the strip's statistics in one plan-view frame.
    pub fn measure(&mut self, plan: &FrameView, index: usize) -> Result<Strip, VisionError> {
        check_frame(plan, index)?;
        let (w, h) = (plan.width, plan.height);
        self.last = None;
        let mean = mean_intensity(plan);
        let [rt, gt, bt] =
            [self.thresholds.r, self.thresholds.g, self.thresholds.b].map(|t| (t * mean) as f32);
        self.mask.clear();
        self.mask.reserve(w * h);
        let (ri, bi) = match plan.order {
            ChannelOrder::Rgb => (0, 2),
            ChannelOrder::Bgr => (2, 0),
        };
        for y in 0..h {
            self.mask.extend(
                plan.row(y).chunks_exact(3).map(|p| {
                    f32::from(p[ri]) > rt && f32::from(p[1]) < gt && f32::from(p[bi]) < bt
                }),
            );
        }
        let candidates = self.mask.iter().filter(|&&on| on).count();
        let no_strip = |pixels| VisionError::NoStrip {
            frame: index,
            pixels,
            min_pixels: self.min_pixels,
        };
        if candidates < self.min_pixels {
            return Err(no_strip(candidates));
        }
        let comps = self.labeller.components(&self.mask, w, h, |_| true);
        let strip = comps.first().ok_or_else(|| no_strip(0))?;
        if strip.pixels < self.min_pixels {
            return Err(no_strip(strip.pixels));
        }
        self.last = Some((strip.seed, w, h));
        let (cx, cy) = strip.centroid();
        let (sxx, syy, sxy_image) = strip.covariance();
        let (beta, l1, l2) = principal_axis(sxx, syy, -sxy_image);
        Ok(Strip {
            beta,
            pixels: strip.pixels,
            candidates,
            centroid_px: [cx, cy],
            eccentricity: if l1 > 0.0 {
                (1.0 - l2 / l1).max(0.0).sqrt()
            } else {
                0.0
            },
            axes_sd_px: [l1.max(0.0).sqrt(), l2.max(0.0).sqrt()],
        })
    }
}

/// Angle of the first principal component of a 2-D covariance (x right, y up)
/// in (−π/2, π/2], eq. 3.24, with the eigenvalues λ₁ ≥ λ₂.
fn principal_axis(sxx: f64, syy: f64, sxy: f64) -> (f64, f64, f64) {
    let half_diff = 0.5 * (sxx - syy);
    let root = half_diff.hypot(sxy);
    let centre = 0.5 * (sxx + syy);
    let mut beta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    if beta <= -std::f64::consts::FRAC_PI_2 {
        beta += std::f64::consts::PI;
    }
    (beta, centre + root, centre - root)
}

/// Mean intensity of a whole view (mean of all channels of all pixels).
fn mean_intensity(frame: &FrameView) -> f64 {
    let total: u64 = (0..frame.height)
        .map(|y| u64::from(frame.row(y).iter().map(|&b| u32::from(b)).sum::<u32>()))
        .sum();
    total as f64 / (3 * frame.width * frame.height) as f64
}

/// Colour thresholds (eq. 3.23) chosen from one plan-view frame, for clips whose
/// configuration does not give them.
///
/// With every channel divided by the image mean, the pixels are split by
/// Otsu's method on their redness r − max(g, b); the redder class is the strip.
/// r_thresh lies halfway between the strip's mean r and the rest's; g_thresh
/// and b_thresh halfway between the strip's mean and that of the non-strip
/// pixels bright enough to pass r_thresh (the grey or white top face), or of
/// the rest when none is. On a light plate the rest's mean r is above the strip's
/// (a white plate's red over the image mean is 1.0–1.1, the strip's 0.9), and that
/// r_thresh shut the strip out: there g_thresh and b_thresh lie halfway between the
/// strip's mean and that of the pixels brighter than the strip in g or b, and
/// r_thresh halfway between the strip's mean r and that of the pixels those let
/// through (a shadow, the disk's side), or half the strip's when none is.
pub fn auto_colour_thresholds(
    plan: &FrameView,
    index: usize,
) -> Result<ColourThresholds, VisionError> {
    check_frame(plan, index)?;
    let mean = mean_intensity(plan);
    let no_strip = |pixels| VisionError::NoStrip {
        frame: index,
        pixels,
        min_pixels: StripFinder::MIN_PIXELS,
    };
    if mean <= 0.0 {
        return Err(no_strip(0));
    }
    let pixels: Vec<[f64; 3]> = (0..plan.height)
        .flat_map(|y| (0..plan.width).map(move |x| (x, y)))
        .map(|(x, y)| plan.rgb(x, y).map(|c| f64::from(c) / mean))
        .collect();
    let redness = |p: &[f64; 3]| p[0] - p[1].max(p[2]);
    // Redness lies in [−255/mean, 255/mean]; 1024 bins resolve it finely.
    let span = 255.0 / mean;
    const BINS: usize = 1024;
    let bin = |d: f64| (((d + span) / (2.0 * span)) * (BINS - 1) as f64).round() as usize;
    let mut hist = vec![0u64; BINS];
    for p in &pixels {
        hist[bin(redness(p)).min(BINS - 1)] += 1;
    }
    let cut = super::threshold::otsu_level(&hist).ok_or_else(|| no_strip(0))?;
    let is_red = |p: &[f64; 3]| bin(redness(p)) as f64 > cut;
    let mean_of = |sel: &dyn Fn(&[f64; 3]) -> bool| {
        let (mut s, mut n) = ([0.0; 3], 0usize);
        for p in pixels.iter().filter(|p| sel(p)) {
            for c in 0..3 {
                s[c] += p[c];
            }
            n += 1;
        }
        (s.map(|v| v / n.max(1) as f64), n)
    };
    let (red, n_red) = mean_of(&is_red);
    let (rest, n_rest) = mean_of(&|p| !is_red(p));
    // The strip is a minority that is clearly red.
    if n_red < StripFinder::MIN_PIXELS || n_rest < n_red || redness(&red) < 0.2 {
        return Err(no_strip(n_red));
    }
    let halfway = |a: [f64; 3], b: [f64; 3]| [0, 1, 2].map(|c| 0.5 * (a[c] + b[c]));
    // r halfway to the rest's mean r, g and b halfway to what passes that r (the grey
    // or white top face)...
    let r = halfway(red, rest)[0];
    if r < red[0] {
        let (bright, n_bright) = mean_of(&|p| !is_red(p) && p[0] > r);
        let [_, g, b] = halfway(red, if n_bright > 0 { bright } else { rest });
        return Ok(ColourThresholds { r, g, b });
    }
    // ...unless the rest is redder than the strip (a light plate): then g and b
    // shut out what is brighter than the strip in them, and r what they let through
    // (a shadow, the disk's side), or nothing darker than half the strip's r.
    let (bright, n_bright) = mean_of(&|p| !is_red(p) && p[1].max(p[2]) > red[1].max(red[2]));
    let [_, g, b] = halfway(red, if n_bright > 0 { bright } else { rest });
    let (dark, n_dark) = mean_of(&|p| !is_red(p) && p[1] < g && p[2] < b);
    let r = 0.5 * (red[0] + if n_dark > 0 { dark[0] } else { 0.0 });
    Ok(ColourThresholds { r, g, b })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::synthetic::{Canvas, SideScene, grey};

    const RED: [f64; 3] = [205.0, 45.0, 40.0];

    /// Plan view: a grey disk on a dark plate, a red strip of `length × width`
    /// px through (cx, cy) at angle β (counter-clockwise from +x, y up).
    fn plan_view(beta: f64, centre: (f64, f64), length: f64, width: f64) -> Canvas {
        plan_view_on(30.0, beta, centre, length, width)
    }

    /// [`plan_view`] on a plate of grey level `plate`.
    fn plan_view_on(
        plate: f64,
        beta: f64,
        (cx, cy): (f64, f64),
        length: f64,
        width: f64,
    ) -> Canvas {
        let (w, h) = (400, 300);
        let mut c = Canvas::new(w, h, grey(plate));
        let (dx, dy) = (200.0, 150.0);
        c.shape(
            (60.0, 10.0, 340.0, 290.0),
            8,
            |x, y| (x - dx).hypot(y - dy) < 135.0,
            grey(150.0),
        );
        let (ux, uy) = (beta.cos(), -beta.sin());
        let strip = |x: f64, y: f64| {
            let (rx, ry) = (x - cx, y - cy);
            let along = rx * ux + ry * uy;
            let across = -rx * uy + ry * ux;
            along.abs() < 0.5 * length && across.abs() < 0.5 * width
        };
        let r = 0.5 * length + width;
        c.shape((cx - r, cy - r, cx + r, cy + r), 8, strip, RED);
        c
    }

    #[test]
    fn strip_angle_by_pca() {
        let first = plan_view(0.4, (200.3, 150.2), 180.0, 12.0);
        let bytes = first.to_bgr(2);
        let thresholds = auto_colour_thresholds(&first.view(&bytes, 2), 0).unwrap();
        let mut finder = StripFinder::new(thresholds, ThresholdSource::Automatic);
        // Near-vertical strips on both sides of ±π/2, and exactly vertical.
        let near_vertical = std::f64::consts::FRAC_PI_2 - 1e-4;
        for beta in [
            0.4,
            0.0,
            -1.2,
            near_vertical,
            -near_vertical,
            0.9,
            std::f64::consts::FRAC_PI_2,
        ] {
            let c = plan_view(beta, (200.3, 150.2), 180.0, 12.0);
            let bytes = c.to_bgr(2);
            let strip = finder.measure(&c.view(&bytes, 2), 3).unwrap();
            // β in (−π/2, π/2]: a strip at −π/2 + ε is the same as one at π/2 + ε.
            let mut err = (strip.beta - beta).rem_euclid(std::f64::consts::PI);
            if err > std::f64::consts::FRAC_PI_2 {
                err -= std::f64::consts::PI;
            }
            // The thesis's noise floor for β at rest is 5e-3 rad (§3.3.2).
            assert!(err.abs() < 0.005, "β {beta}: found {}", strip.beta);
            assert!(strip.beta > -std::f64::consts::FRAC_PI_2);
            assert!(strip.beta <= std::f64::consts::FRAC_PI_2);
            // 180 × 12 px strip: about 2160 pixels; a line-like blob.
            assert!(
                (strip.pixels as f64 - 2160.0).abs() < 100.0,
                "{}",
                strip.pixels
            );
            assert!(strip.eccentricity > 0.99);
            assert!((strip.axes_sd_px[0] - 180.0 / 12f64.sqrt()).abs() < 1.0);
            // Binarising moves each end of the strip by up to ½ px.
            assert!((strip.centroid_px[0] - 200.3).abs() < 0.5, "{strip:?}");
        }
    }

    #[test]
    fn isolated_specks_are_dropped_and_missing_strips_reported() {
        let mut c = plan_view(-0.3, (190.0, 160.0), 150.0, 10.0);
        // Red specks away from the strip, as the thesis found (fig. 3.20).
        for (x, y) in [(120.0, 80.0), (280.0, 230.0), (300.0, 100.0)] {
            c.shape((x, y, x + 3.0, y + 3.0), 1, |_, _| true, RED);
        }
        let bytes = c.to_bgr(0);
        let thresholds = ColourThresholds {
            r: 1.5,
            g: 1.0,
            b: 1.0,
        };
        let mut finder = StripFinder::new(thresholds, ThresholdSource::Given);
        let strip = finder.measure(&c.view(&bytes, 0), 0).unwrap();
        assert_eq!(strip.candidates, strip.pixels + 27);
        assert!((strip.beta + 0.3).abs() < 0.005);

        let bare = plan_view(0.0, (200.0, 150.0), 0.0, 0.0);
        let bytes = bare.to_bgr(0);
        let err = finder.measure(&bare.view(&bytes, 0), 17).unwrap_err();
        assert!(
            matches!(
                err,
                VisionError::NoStrip {
                    frame: 17,
                    pixels: 0,
                    ..
                }
            ),
            "{err}"
        );
        let err = auto_colour_thresholds(&bare.view(&bytes, 0), 17).unwrap_err();
        assert!(
            matches!(err, VisionError::NoStrip { frame: 17, .. }),
            "{err}"
        );
    }

    /// A portrait two-view frame's bytes: the side view's middle 400 columns (rows
    /// 0..300), a black divider (rows 300..312) and `plan` (400 × 300) below.
    fn stacked(plan: &Canvas) -> Vec<u8> {
        let top = SideScene::standard().dark_plate(3.0, 0.55);
        let top_bytes = top.to_bgr(0);
        let mut bytes = Vec::new();
        for r in 0..300 {
            bytes.extend_from_slice(&top_bytes[r * 3 * top.w + 3 * 120..r * 3 * top.w + 3 * 520]);
        }
        bytes.extend(std::iter::repeat_n(4u8, 12 * 3 * 400));
        bytes.extend(plan.to_bgr(0));
        bytes
    }

    fn portrait(bytes: &[u8]) -> FrameView<'_> {
        FrameView {
            width: 400,
            height: 612,
            stride: 3 * 400,
            order: crate::footage::ChannelOrder::Bgr,
            data: bytes,
        }
    }

    #[test]
    fn two_view_layout_needs_a_divider_and_a_strip_below_it() {
        let with_strip = stacked(&plan_view(0.7, (200.0, 150.0), 180.0, 12.0));
        let found = detect_two_view(&portrait(&with_strip), 0);
        assert!(found.two_view, "{}", found.evidence);
        // The same divider above a plain disk (a side view over a light plate's
        // dark shadow or a black band below the plate): a side view.
        let mut plain = Canvas::new(400, 300, grey(30.0));
        plain.shape(
            (60.0, 10.0, 340.0, 290.0),
            8,
            |x, y| (x - 200.0).hypot(y - 150.0) < 135.0,
            grey(150.0),
        );
        let found = detect_two_view(&portrait(&stacked(&plain)), 0);
        assert!(!found.two_view, "{}", found.evidence);
        // A red round speck is no strip.
        let speck = stacked(&plan_view(0.7, (200.0, 150.0), 14.0, 14.0));
        assert!(!detect_two_view(&portrait(&speck), 0).two_view);
        // Dark above the band (a side view's background above a disk with its
        // strip): no side view there, so no two-view frame.
        let mut dark_above = stacked(&plan_view(0.7, (200.0, 150.0), 180.0, 12.0));
        dark_above[..300 * 3 * 400].fill(6);
        let found = detect_two_view(&portrait(&dark_above), 0);
        assert!(!found.two_view, "{}", found.evidence);
        // No divider: a side view whatever lies below.
        let side = SideScene::standard().dark_plate(3.0, 0.55);
        let side_bytes = side.to_bgr(0);
        assert!(!detect_two_view(&side.view(&side_bytes, 0), 0).two_view);
    }

    /// A portrait two-view frame of 400 × 612 px: `side`'s view over a dark plate
    /// (rows 0..300, its middle 400 columns: the disk is in them), a black divider
    /// of level 4 (rows 300..312), a plan view (rows 312..612).
    fn side_over_plan(side: &SideScene) -> Vec<u8> {
        let top = side.dark_plate(3.0, 0.55);
        let plan = plan_view(0.7, (200.0, 150.0), 180.0, 12.0);
        let mut bytes = Vec::new();
        let top_bytes = top.to_bgr(0);
        for r in 0..300 {
            bytes.extend_from_slice(&top_bytes[r * 3 * top.w + 3 * 120..r * 3 * top.w + 3 * 520]);
        }
        bytes.extend(std::iter::repeat_n(4u8, 12 * 3 * 400));
        bytes.extend(plan.to_bgr(0));
        bytes
    }

    #[test]
    fn split_between_side_and_plan_views() {
        let plan = plan_view(0.7, (200.0, 150.0), 180.0, 12.0);
        let w = 400;
        let bytes = side_over_plan(&SideScene::standard());
        let frame = FrameView {
            width: w,
            height: 612,
            stride: 3 * w,
            order: crate::footage::ChannelOrder::Bgr,
            data: &bytes,
        };
        let split = find_split_row(&frame, 0).unwrap();
        assert!((300..312).contains(&split), "split {split}");
        let (upper, lower) = split_views(&frame, split, 0).unwrap();
        assert_eq!(upper.height + lower.height, 612);
        // The bottom view measures the strip as the plan view alone does.
        let thresholds = auto_colour_thresholds(&lower, 0).unwrap();
        let strip = StripFinder::new(thresholds, ThresholdSource::Automatic)
            .measure(&lower, 0)
            .unwrap();
        assert!((strip.beta - 0.7).abs() < 0.005);
        // A frame without a divider has no split.
        let plain = plan.to_bgr(0);
        assert!(matches!(
            find_split_row(&plan.view(&plain, 0), 9),
            Err(VisionError::NoSplit { frame: 9 })
        ));
        assert!(split_views(&frame, 0, 0).is_err());
    }

    /// A darker tone curve (as `scripts/reencode-footage --eq gamma=0.7` makes) can
    /// turn the black above a two-view clip's side-view disk as black as the
    /// divider: that band reaches the frame's top row, a margin, and the divider is
    /// still found below the side view.
    #[test]
    fn split_passes_over_a_margin_as_black_as_the_divider() {
        let side = SideScene {
            background: 4.0,
            ..SideScene::standard()
        };
        let bytes = side_over_plan(&side);
        let frame = FrameView {
            width: 400,
            height: 612,
            stride: 3 * 400,
            order: crate::footage::ChannelOrder::Bgr,
            data: &bytes,
        };
        let split = find_split_row(&frame, 0).unwrap();
        assert!((300..312).contains(&split), "split {split}");
        let found = detect_two_view(&frame, 0);
        assert!(found.two_view, "{}", found.evidence);
    }

    /// Two camera images stacked with no divider, a light plate in both (the side
    /// view's plate reaching its last row, the plan view's around the disk): the
    /// views are split in the uniform plate rows between the side view's shadow and
    /// the plan view's disk, and the frame is detected as two-view.
    #[test]
    fn split_without_a_dark_divider_on_a_light_plate() {
        let side = SideScene::standard();
        let top = side.light_plate(0.0, 4.0);
        let plan = plan_view_on(210.0, 0.7, (200.0, 150.0), 180.0, 12.0);
        let (w, rows) = (400, 300);
        let top_bytes = top.to_bgr(0);
        let mut bytes = Vec::new();
        for r in 0..rows {
            // The side view's middle 400 columns from its row 100 (the dark above
            // the disk, a dark band of its own, stays in the frame's top eighth),
            // its plate continued below its last row.
            let r = (r + 100).min(top.h - 1);
            bytes.extend_from_slice(&top_bytes[r * 3 * top.w + 3 * 120..r * 3 * top.w + 3 * 520]);
        }
        bytes.extend(plan.to_bgr(0));
        let frame = FrameView {
            width: w,
            height: 2 * rows,
            stride: 3 * w,
            order: crate::footage::ChannelOrder::Bgr,
            data: &bytes,
        };
        // Between the shadow's last row and the plan view's disk (its top at 300 + 15).
        let shadow_end = (side.z_base + 4.0).ceil() as usize - 100;
        let split = find_split_row(&frame, 0).unwrap();
        assert!((shadow_end..rows + 15).contains(&split), "split {split}");
        let found = detect_two_view(&frame, 0);
        assert!(found.two_view, "{}", found.evidence);
    }
}
