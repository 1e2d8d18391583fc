//! The rim on a light plate at one fixed level of the disk's own contrast
//! (thesis §3.2.4, fig. 3.9: the disk's bottom edge above its shadow).
//!
//! # Why not the first pass
//!
//! [`RimGauge`](super::RimGauge) places the edge by the area of the step between
//! the levels at the two ends of the monotone run through it, three rows either
//! side. A real rim is rounded and blurred over 4–5 rows, so those ends lie inside
//! whatever is next to the edge, and below the edge that changes: with the rim
//! lifted it is the disk's shadow on the plate (about 0.58 of the side's level); at
//! rest, the rounded rim standing on the lit plate (0.67–0.68). The rest frames,
//! which give the zero of z_rim, read their edge lower than the same disk lifted,
//! and every lifted height comes out 0.5–0.9 px low.
//!
//! # The rule
//!
//! The edge is where the centre band's profile, walked down from the disk's side,
//! first falls below the level
//!
//! ```text
//! L = s · (1 + f) / 2
//! ```
//!
//! s the frame's own side level (the top rows of its window: flicker divides out)
//! and f the shadow's level relative to the side's, learned from the frames that
//! lift the rim past [`OPEN_GAP_PX`] (the darkest of the [`SHADOW_ROWS`] rows
//! under their edge, median over the frames). One level for every frame, at rest
//! and lifted, is one contour of one disk's edge; walking down from the side, the
//! crossing reads only the row above it and the one below, so the shadow or the
//! lit plate under the rim barely reaches it, and z_rim = e_rest − e.
//!
//! # The crossing inside a pixel
//!
//! A pixel is the mean of the picture over its row, not a sample at its centre.
//! Where the edge is sharper than a pixel, the two rows either side of the
//! crossing hold a flat level and a mixed one, and a straight line between their
//! centres misplaces the edge by up to ±0.09 px with the edge's phase in its row.
//! The lifted frames take every phase and average that out; the rest frames, which
//! give the zero, hold one phase, and every lifted height inherits their error (on
//! a sharp render 320 px wide: −0.09 px, φ at the peaks 5 % low). So the crossing
//! is the edge e of the model whose pixel means those rows are: a step from the
//! side's level s to the shadow's f·s, which L is halfway down, blurred by a
//! Gaussian of the clip's own width σ,
//!
//! ```text
//! v_j = f·s + (1 − f)·s · ∫_j^{j+1} Φ((e − y)/σ) dy
//! ```
//!
//! fitted to the row above the crossing and the row below (σ → 0: the mixed
//! row's level places e exactly; a wide blur: the straight line's answer). σ is
//! learned with f from the frames with an open gap: the median of the width
//! fitted with e to the two rows either side of each one's crossing.

use rayon::prelude::*;

use super::band_window::{BandWindow, LEVEL_ROWS, ROWS_ABOVE};
use super::profile::steps;
use crate::numeric::minimise::{Stop, golden_section};

/// Lift past which the rows just under the edge show the shadow \[px\]: the
/// rounded band and the blur (≈ 3 rows) no longer reach the plate.
pub const OPEN_GAP_PX: f64 = 3.0;
/// Rows under a frame's edge whose darkest is the shadow's level.
const SHADOW_ROWS: usize = 4;
/// Frames with an open gap the shadow's level needs.
pub const MIN_OPEN_FRAMES: usize = 20;
/// How far from its first-pass edge a frame's crossing may lie \[px\]; further,
/// the window did not start on the disk's side and the first pass is kept.
const SEARCH_PX: f64 = 2.0;
/// Widest blur σ of the edge that is searched for \[px\].
const MAX_BLUR_PX: f64 = 3.0;

/// The light-plate rim model: the shadow's relative level and the edge at rest.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowEdgeModel {
    /// f: the shadow under a lifted rim, relative to the disk's side.
    pub shadow_ratio: f64,
    /// σ: the width of the Gaussian blur of the edge \[px\].
    pub blur_px: f64,
    /// e_rest: the rest frames' crossing (continuous row, px), the zero of z_rim.
    pub rest_edge: f64,
    /// Frames whose crossing was not found within [`SEARCH_PX`] of the first
    /// pass, which keep their first-pass height.
    pub kept_first_pass: usize,
}

impl ShadowEdgeModel {
    /// The relative level L/s = (1 + f)/2 the edge is placed at.
    pub fn edge_level(&self) -> f64 {
        0.5 * (1.0 + self.shadow_ratio)
    }

    /// The crossing of [`Self::edge_level`] in one window (continuous row, px): the
    /// edge of the blurred step (module docs) fitted to the rows either side of it.
    pub fn edge(&self, window: &BandWindow) -> Option<f64> {
        let step = Step::crossed(window, self.shadow_ratio)?;
        Some(step.fit_edge(&[step.below - 1, step.below], self.blur_px))
    }
}

/// A window's profile where, walked down from the top, it first falls below the
/// level halfway from the side's level s to the shadow's f·s.
struct Step<'a> {
    window: &'a BandWindow,
    /// s: the side's level.
    side: f64,
    /// f·s: the shadow's level.
    shadow: f64,
    /// Index of the first row below the level (≥ 1).
    below: usize,
}

impl<'a> Step<'a> {
    fn crossed(window: &'a BandWindow, shadow_ratio: f64) -> Option<Self> {
        let side = window.level();
        let level = 0.5 * (1.0 + shadow_ratio) * side;
        let below =
            (LEVEL_ROWS..window.values.len()).find(|&k| f64::from(window.values[k]) < level)?;
        Some(Self {
            window,
            side,
            shadow: shadow_ratio * side,
            below,
        })
    }

    /// Squared misfit of the step with its edge at row `edge` blurred by `sigma`,
    /// over the window's rows `rows` (indices; those past its end are skipped).
    fn misfit(&self, rows: &[usize], edge: f64, sigma: f64) -> f64 {
        rows.iter()
            .filter_map(|&k| {
                let v = f64::from(*self.window.values.get(k)?);
                let top = self.window.row_top(k);
                let model = self.shadow + (self.side - self.shadow) * covered(edge - top, sigma);
                Some((v - model).powi(2))
            })
            .sum()
    }

    /// The edge row best fitted to `rows` with the blur `sigma`: within a row of the
    /// top of the first row below the level, on a grid of 0.05 px, then by
    /// golden-section search.
    fn fit_edge(&self, rows: &[usize], sigma: f64) -> f64 {
        let top = self.window.row_top(self.below);
        let cost = |e: f64| self.misfit(rows, e, sigma);
        let mut best = (f64::INFINITY, top);
        for e in steps((top - 1.0, top + 1.0, 0.05)) {
            let c = cost(e);
            if c < best.0 {
                best = (c, e);
            }
        }
        golden_section(cost, best.1 - 0.05, best.1 + 0.05, Stop::Width(1e-4)).midpoint()
    }

    /// The blur σ \[px\] best fitted, with the edge, to the two rows either side of
    /// the crossing (a frame whose rim is clear of its shadow).
    fn fit_blur(&self) -> f64 {
        let rows: Vec<usize> = (self.below.saturating_sub(2)..self.below + 2).collect();
        let cost = |sigma: f64| self.misfit(&rows, self.fit_edge(&rows, sigma), sigma);
        let mut best = (f64::INFINITY, 0.0);
        for sigma in steps((0.0, MAX_BLUR_PX, 0.1)) {
            let c = cost(sigma);
            if c < best.0 {
                best = (c, sigma);
            }
        }
        golden_section(
            cost,
            (best.1 - 0.1).max(0.0),
            best.1 + 0.1,
            Stop::Width(1e-3),
        )
        .midpoint()
    }
}

/// The share of pixel row [j, j + 1) above a step at j + `depth` blurred by a
/// Gaussian of `sigma` \[px\]: ∫_j^{j+1} Φ((e − y)/σ) dy = σ [G((e − j)/σ) −
/// G((e − j − 1)/σ)] with G(u) = u Φ(u) + φ(u) (Φ, φ: the standard normal's
/// distribution and density); the area clamp(e − j, 0, 1) when σ → 0.
fn covered(depth: f64, sigma: f64) -> f64 {
    if sigma < 1e-6 {
        return depth.clamp(0.0, 1.0);
    }
    let g = |u: f64| {
        let cdf = 0.5 * (1.0 + statrs::function::erf::erf(u / std::f64::consts::SQRT_2));
        u * cdf + (-0.5 * u * u).exp() / (2.0 * std::f64::consts::PI).sqrt()
    };
    sigma * (g(depth / sigma) - g((depth - 1.0) / sigma))
}

/// f of one frame lifted past [`OPEN_GAP_PX`]: the darkest of the [`SHADOW_ROWS`]
/// rows under its first-pass `edge`, over its side level.
fn shadow_ratio(window: &BandWindow, edge: f64) -> Option<f64> {
    let level = window.level();
    let first = window.index_of(edge)? + 1;
    let rows = window.values.get(first..first + SHADOW_ROWS)?;
    let darkest = rows.iter().copied().fold(f32::INFINITY, f32::min);
    (level > 0.0).then(|| f64::from(darkest) / level)
}

/// Re-measures a clip's rim heights on a light plate (module docs): `heights` are
/// the first-pass z_rim per frame \[px\] (`None`: no edge, left alone), `windows`
/// each frame's band rows about its first-pass edge z_base − z, `rest` the rest
/// frames' mean window. Returns the model, or why it was not used (and then
/// changes nothing).
pub fn remeasure(
    heights: &mut [Option<f64>],
    windows: &[Option<BandWindow>],
    z_base: f64,
    rest: &BandWindow,
) -> Result<ShadowEdgeModel, &'static str> {
    // The frames with an open gap, each with its first-pass edge.
    let open: Vec<(&BandWindow, f64)> = heights
        .iter()
        .zip(windows)
        .filter_map(|(z, w)| {
            let z = (*z)?;
            (z >= OPEN_GAP_PX).then_some((w.as_ref()?, z_base - z))
        })
        .collect();
    let ratios: Vec<f64> = open
        .iter()
        .filter_map(|&(w, edge)| shadow_ratio(w, edge))
        .collect();
    if ratios.len() < MIN_OPEN_FRAMES {
        return Err("too few frames lift the rim off its shadow to measure the shadow's level");
    }
    let shadow_ratio = crate::numeric::median(&ratios);
    if !(0.0..0.9).contains(&shadow_ratio) {
        return Err("the shadow under the lifted rim is not darker than the disk's side");
    }
    let blurs: Vec<f64> = open
        .par_iter()
        .filter_map(|&(w, _)| Some(Step::crossed(w, shadow_ratio)?.fit_blur()))
        .collect();
    if blurs.is_empty() {
        return Err("no frame with an open gap falls to the edge's level");
    }
    let mut model = ShadowEdgeModel {
        shadow_ratio,
        blur_px: crate::numeric::median(&blurs),
        rest_edge: f64::NAN,
        kept_first_pass: 0,
    };
    let rest_edge0 = rest.row_top(ROWS_ABOVE);
    model.rest_edge = model
        .edge(rest)
        .filter(|e| (e - rest_edge0).abs() <= SEARCH_PX + 0.5)
        .ok_or("the rest frames' profile never falls to the edge's level")?;
    for (z, w) in heights.iter_mut().zip(windows) {
        if let (Some(height), Some(window)) = (z.as_mut(), w) {
            let edge0 = z_base - *height;
            match model
                .edge(window)
                .filter(|e| (e - edge0).abs() <= SEARCH_PX)
            {
                Some(e) => *height = model.rest_edge - e,
                None => model.kept_first_pass += 1,
            }
        }
    }
    Ok(model)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vision::band_window::ROWS_BELOW;

    /// A rim rounded over 2 px and blurred, above a shadow of 0.58 of the side's
    /// level when lifted and, at rest, above the lit plate at 0.68 (the open
    /// footage's levels), with flicker `gain`. Sampled by area, 8-bit.
    fn window(rim: f64, resting: bool, gain: f64) -> BandWindow {
        let below = if resting { 0.68 } else { 0.58 };
        let disk = |x: f64| -> f64 {
            // x: distance above the rim (px).
            if x <= 0.0 {
                below
            } else if x < 2.0 {
                let s = x / 2.0;
                0.3 + 0.7 * s * s * (3.0 - 2.0 * s)
            } else {
                1.0
            }
        };
        let blurred = |y: f64| -> f64 {
            let (sub, sigma) = (20, 0.9f64);
            let (mut acc, mut wsum) = (0.0, 0.0);
            for i in 0..sub {
                let yy = y + (i as f64 + 0.5) / sub as f64;
                for j in -24..=24 {
                    let d = j as f64 * 0.125;
                    let w = (-0.5 * (d / sigma).powi(2)).exp();
                    acc += w * disk(rim - (yy + d));
                    wsum += w;
                }
            }
            acc / wsum
        };
        rows_about(rim, |y| 120.0 * gain * blurred(y))
    }

    /// The band window about row `rim` whose row y (its top) reads `value(y)`,
    /// rounded to 8 bits.
    fn rows_about(rim: f64, value: impl Fn(f64) -> f64) -> BandWindow {
        let first = rim.round() as usize - ROWS_ABOVE;
        BandWindow {
            first_row: first,
            values: (first..first + ROWS_ABOVE + ROWS_BELOW)
                .map(|y| value(y as f64).round() as f32)
                .collect(),
            shift: 0.0,
        }
    }

    #[test]
    fn lifted_heights_share_the_rest_frames_contour() {
        let plate = 80.35;
        let lifts: Vec<f64> = (0..150).map(|k| 0.13 * k as f64).collect();
        let windows: Vec<Option<BandWindow>> = lifts
            .iter()
            .enumerate()
            .map(|(k, &z)| Some(window(plate - z, false, 1.0 + 0.1 * (k as f64).sin())))
            .collect();
        // First pass: 0.6 px low and noisy, as on rounded rims over a light plate.
        let mut heights: Vec<Option<f64>> = lifts
            .iter()
            .enumerate()
            .map(|(k, &z)| Some(z - 0.6 + 0.2 * (k as f64 * 2.39).sin()))
            .collect();
        let rest = window(plate, true, 1.0);
        // z_base − height = the rim + 0.2 ± 0.2 px, the crossing ≈ 1 px above it.
        let model = remeasure(&mut heights, &windows, plate - 0.4, &rest).expect("model");
        assert!((model.shadow_ratio - 0.58).abs() < 0.02, "{model:?}");
        assert_eq!(model.kept_first_pass, 0);
        // The blur carries the lit plate under the resting rim 0.065 px into the rest
        // frames' crossing (the first pass's area edge: 0.5–0.9 px on the footage),
        // and linear interpolation of the curved edge errs by ±0.04 px with its phase.
        let errors: Vec<f64> = lifts
            .iter()
            .zip(&heights)
            .map(|(&z, found)| found.unwrap() - z)
            .collect();
        let mean = errors.iter().sum::<f64>() / errors.len() as f64;
        assert!(mean.abs() < 0.08, "mean error {mean}");
        for (&z, e) in lifts.iter().zip(&errors) {
            assert!(e.abs() < 0.12, "lift {z}: error {e}");
        }
    }

    /// A sharp edge from the side's 150 to the shadow's 50 at row `rim`, under the
    /// light's `gain`, sampled by area, 8-bit.
    fn sharp_window(rim: f64, gain: f64) -> BandWindow {
        rows_about(rim, |y| gain * (50.0 + 100.0 * (rim - y).clamp(0.0, 1.0)))
    }

    #[test]
    fn a_sharp_edge_is_read_at_every_phase_in_its_row() {
        // The rest frames' edge 0.35 into its row, where a straight line between
        // the crossing's rows reads it 0.08 px high; the lifted edges at every phase.
        let plate = 80.35;
        let lifts: Vec<f64> = (0..150).map(|k| 0.137 * k as f64).collect();
        let windows: Vec<Option<BandWindow>> = lifts
            .iter()
            .enumerate()
            .map(|(k, &z)| Some(sharp_window(plate - z, 1.0 + 0.1 * (k as f64).sin())))
            .collect();
        let mut heights: Vec<Option<f64>> = lifts.iter().map(|&z| Some(z + 0.1)).collect();
        let rest = sharp_window(plate, 1.0);
        let model = remeasure(&mut heights, &windows, plate, &rest).expect("model");
        assert!((model.shadow_ratio - 1.0 / 3.0).abs() < 0.01, "{model:?}");
        assert!(model.blur_px < 0.2, "{model:?}");
        assert!((model.rest_edge - plate).abs() < 0.01, "{model:?}");
        for (&z, found) in lifts.iter().zip(&heights) {
            let error = found.unwrap() - z;
            assert!(error.abs() < 0.02, "lift {z}: error {error}");
        }
    }

    #[test]
    fn a_clip_that_never_lifts_off_its_shadow_keeps_the_first_pass() {
        let plate = 80.35;
        let lifts: Vec<f64> = (0..100).map(|k| 0.02 * k as f64).collect();
        let windows: Vec<Option<BandWindow>> = lifts
            .iter()
            .map(|&z| Some(window(plate - z, false, 1.0)))
            .collect();
        let mut heights: Vec<Option<f64>> = lifts.iter().map(|&z| Some(z)).collect();
        let before = heights.clone();
        let rest = window(plate, true, 1.0);
        assert!(remeasure(&mut heights, &windows, plate, &rest).is_err());
        assert_eq!(heights, before);
    }
}
