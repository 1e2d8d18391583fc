//! The rim on a light plate at one fixed level of the disk's own contrast
//! (thesis §3.2.4, fig. 3.9: the disk's bottom edge above its shadow).
//!
//! # Why not the first pass
//!
//! [`RimGauge`](super::RimGauge) places the edge by the area of the step between
//! the levels at the two ends of the monotone run through it, three rows either
//! side. A real rim is rounded and blurred over 4–5 rows, so those ends lie inside
//! whatever is next to the edge, and below the edge that changes: with the rim
//! lifted it is the disk's shadow on the plate (0.58 of the side's level on the
//! open footage); at rest, the rounded rim standing on the lit plate (0.67–0.68).
//! The rest frames, which give the zero of z_rim, read their edge lower than the
//! same disk lifted, and every lifted height came out 0.5–0.9 px low (o02, o03).
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
//! crossing reads only the rows above it and the one below, so the shadow or the
//! lit plate under the rim barely reaches it. The crossing is interpolated
//! linearly between those two rows, and z_rim = e_rest − e.

use super::band_window::{BandWindow, LEVEL_ROWS, ROWS_ABOVE};

/// Lift past which the rows just under the edge show the shadow [px]: the
/// rounded band and the blur (≈ 3 rows) no longer reach the plate.
pub const OPEN_GAP_PX: f64 = 3.0;
/// Rows under a frame's edge whose darkest is the shadow's level.
const SHADOW_ROWS: usize = 4;
/// Frames with an open gap the shadow's level needs.
pub const MIN_OPEN_FRAMES: usize = 20;
/// How far from its first-pass edge a frame's crossing may lie [px]; further,
/// the window did not start on the disk's side and the first pass is kept.
const SEARCH_PX: f64 = 2.0;

/// The light-plate rim model: the shadow's relative level and the edge at rest.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowEdgeModel {
    /// f: the shadow under a lifted rim, relative to the disk's side.
    pub shadow_ratio: f64,
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

    /// The crossing of [`Self::edge_level`] in one window (continuous row, px).
    pub fn edge(&self, window: &BandWindow) -> Option<f64> {
        crossing(window, self.edge_level())
    }
}

/// Where `window`'s profile, walked down from the top, first falls below
/// `ratio` × its side level: linear between the centres of the rows either side.
fn crossing(window: &BandWindow, ratio: f64) -> Option<f64> {
    let level = ratio * window.level();
    let v: Vec<f64> = window.values.iter().map(|&x| f64::from(x)).collect();
    let k = (LEVEL_ROWS..v.len()).find(|&k| v[k] < level)?;
    let (above, below) = (v[k - 1], v[k]);
    Some(window.first_row as f64 + (k - 1) as f64 + 0.5 + (above - level) / (above - below))
}

/// f of one frame lifted past [`OPEN_GAP_PX`]: the darkest of the [`SHADOW_ROWS`]
/// rows under its first-pass `edge`, over its side level.
fn shadow_ratio(window: &BandWindow, edge: f64) -> Option<f64> {
    let level = window.level();
    let first = (edge.floor() as usize + 1).checked_sub(window.first_row)?;
    let rows = window.values.get(first..first + SHADOW_ROWS)?;
    let darkest = rows.iter().copied().fold(f32::INFINITY, f32::min);
    (level > 0.0).then(|| f64::from(darkest) / level)
}

/// Re-measures a clip's rim heights on a light plate (module docs): `heights` are
/// the first-pass z_rim per frame [px] (`None`: no edge, left alone), `windows`
/// each frame's band rows about its first-pass edge z_base − z, `rest` the rest
/// frames' mean window. Returns the model, or why it was not used (and then
/// changes nothing).
pub fn remeasure(
    heights: &mut [Option<f64>],
    windows: &[Option<BandWindow>],
    z_base: f64,
    rest: &BandWindow,
) -> Result<ShadowEdgeModel, &'static str> {
    let ratios: Vec<f64> = heights
        .iter()
        .zip(windows)
        .filter_map(|(z, w)| {
            let z = (*z)?;
            (z >= OPEN_GAP_PX).then_some(())?;
            shadow_ratio(w.as_ref()?, z_base - z)
        })
        .collect();
    if ratios.len() < MIN_OPEN_FRAMES {
        return Err("too few frames lift the rim off its shadow to measure the shadow's level");
    }
    let shadow_ratio = crate::signal::median(&ratios);
    if !(0.0..0.9).contains(&shadow_ratio) {
        return Err("the shadow under the lifted rim is not darker than the disk's side");
    }
    let mut model = ShadowEdgeModel {
        shadow_ratio,
        rest_edge: f64::NAN,
        kept_first_pass: 0,
    };
    let rest_edge0 = rest.first_row as f64 + ROWS_ABOVE as f64;
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
        let first = rim.round() as usize - ROWS_ABOVE;
        BandWindow {
            first_row: first,
            values: (first..first + ROWS_ABOVE + ROWS_BELOW)
                .map(|y| (120.0 * gain * blurred(y as f64)).round() as f32)
                .collect(),
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
        // First pass: 0.6 px low and noisy, as on the open footage.
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
