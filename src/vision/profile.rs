//! Intensity profiles along a band of columns (or rows) and the sub-pixel
//! position of a step in them: the building blocks of calibration and rim height.

use super::VisionError;
use crate::footage::FrameView;

/// Checks that a view's buffer holds what its size and stride claim.
pub(crate) fn check_frame(frame: &FrameView, index: usize) -> Result<(), VisionError> {
    let needed = frame
        .height
        .checked_sub(1)
        .map(|rows| rows * frame.stride + 3 * frame.width);
    let ok = frame.width > 0
        && frame.stride >= 3 * frame.width
        && needed.is_some_and(|n| frame.data.len() >= n);
    if ok {
        Ok(())
    } else {
        Err(VisionError::MalformedFrame {
            frame: index,
            width: frame.width,
            height: frame.height,
            stride: frame.stride,
            len: frame.data.len(),
        })
    }
}

/// Mean intensity (mean of the three channels, 0–255) of columns `x0..x1` of
/// row `y`. Channel order does not matter for a mean, so this is a plain sum of
/// contiguous bytes.
#[inline]
pub(crate) fn row_band_mean(frame: &FrameView, y: usize, x0: usize, x1: usize) -> f32 {
    let start = y * frame.stride + 3 * x0;
    let bytes = &frame.data[start..start + 3 * (x1 - x0)];
    let sum: u32 = bytes.iter().map(|&b| u32::from(b)).sum();
    sum as f32 / (3 * (x1 - x0)) as f32
}

/// Mean intensity of rows `y0..y1` at column `x`.
pub(crate) fn column_band_mean(frame: &FrameView, x: usize, y0: usize, y1: usize) -> f32 {
    let mut sum = 0u32;
    for y in y0..y1 {
        let p = &frame.data[y * frame.stride + 3 * x..y * frame.stride + 3 * x + 3];
        sum += u32::from(p[0]) + u32::from(p[1]) + u32::from(p[2]);
    }
    sum as f32 / (3 * (y1 - y0)) as f32
}

/// Sub-pixel position of the step between samples `i` and `i + 1` of a profile
/// whose sample `k` covers [origin + k, origin + k + 1), by its area: the
/// transition is the monotone run of samples through the step, at most `reach`
/// either side, from level `a` (its first sample) to level `b` (its last), and
/// the edge lies `Σ (p_k − b)/(a − b)` px after the start of the run.
///
/// For a step sampled by area (anti-aliased), blurred by any symmetric kernel
/// narrower than the run, this is exact whatever the edge's sub-pixel phase,
/// where linear interpolation of the crossing of the local half level is off by
/// up to ±0.086 px depending on it (a bias, not noise, for an edge that barely moves,
/// such as the plate line). Only the run's monotone part counts, so a rise
/// beyond the step (a mirror image below a narrow gap) is not taken for part of
/// it. `None` when the run is flat.
pub(crate) fn area_edge(p: &[f32], i: usize, reach: usize, origin: f64) -> Option<f64> {
    if i + 1 >= p.len() || reach == 0 {
        return None;
    }
    let falling = p[i] > p[i + 1];
    // `towards_a(x, y)`: x lies at or beyond y on the side of level a.
    let towards_a = |x: f32, y: f32| if falling { x >= y } else { x <= y };
    let mut a = i;
    while a > 0 && i + 1 - a < reach && towards_a(p[a - 1], p[a]) {
        a -= 1;
    }
    let mut b = i + 1;
    while b + 1 < p.len() && b - i < reach && towards_a(p[b], p[b + 1]) {
        b += 1;
    }
    let (hi, lo) = (p[a], p[b]);
    if (hi - lo).abs() < 1e-3 {
        return None;
    }
    let sum: f64 = p[a..=b]
        .iter()
        .map(|&v| f64::from((v - lo) / (hi - lo)))
        .sum();
    Some(origin + a as f64 + sum)
}

/// start, start + step, … up to end (inclusive within half a step).
pub(super) fn steps((start, end, step): (f64, f64, f64)) -> impl Iterator<Item = f64> {
    let n = ((end - start) / step + 0.5).floor().max(0.0) as usize;
    (0..=n).map(move |k| start + k as f64 * step)
}

/// The fraction of row k (covering [k, k + 1)) below a step at e blurred by a
/// Gaussian σ, c_k(e) = ∫_k^{k+1} Φ((u − e)/σ) du = σ [I(a) − I(b)] with
/// I(x) = x Φ(x) + φ(x), a = (k + 1 − e)/σ, b = (k − e)/σ; with its derivatives in e
/// and in ln σ. The sampled edge of the top-face fits (`top_rim::fit_thin_face`,
/// `leaning_face`).
pub(super) fn blurred_step_coverage(k: f64, e: f64, sigma: f64) -> (f64, f64, f64) {
    use std::f64::consts::{PI, SQRT_2};
    let cdf = |x: f64| 0.5 * (1.0 + statrs::function::erf::erf(x / SQRT_2));
    let pdf = |x: f64| (-0.5 * x * x).exp() / (2.0 * PI).sqrt();
    let integral = |x: f64| x * cdf(x) + pdf(x);
    let (a, b) = ((k + 1.0 - e) / sigma, (k - e) / sigma);
    (
        sigma * (integral(a) - integral(b)),
        -(cdf(a) - cdf(b)),
        sigma * (pdf(a) - pdf(b)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An ideal step from `hi` (above) to `lo` (below) at position `e`, sampled by area.
    fn step(e: f64, hi: f32, lo: f32, n: usize) -> Vec<f32> {
        (0..n)
            .map(|k| {
                let cover = (e - k as f64).clamp(0.0, 1.0) as f32;
                lo + (hi - lo) * cover
            })
            .collect()
    }

    /// As `step`, blurred by a Gaussian of `sigma` px, sampled by area (finely).
    fn blurred_step(e: f64, hi: f32, lo: f32, n: usize, sigma: f64) -> Vec<f32> {
        (0..n)
            .map(|k| {
                let sub = 64;
                let cover: f64 = (0..sub)
                    .map(|s| {
                        let x = k as f64 + (s as f64 + 0.5) / sub as f64;
                        // Φ((e − x)/σ) by erf's series-free approximation (A&S 7.1.26).
                        let z = (e - x) / (sigma * std::f64::consts::SQRT_2);
                        let t = 1.0 / (1.0 + 0.3275911 * z.abs());
                        let poly = t
                            * (0.254829592
                                + t * (-0.284496736
                                    + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
                        let erf = 1.0 - poly * (-z * z).exp();
                        0.5 * (1.0 + erf.copysign(z))
                    })
                    .sum::<f64>()
                    / sub as f64;
                lo + (hi - lo) * cover as f32
            })
            .collect()
    }

    #[test]
    fn area_edge_is_exact_at_any_phase() {
        for e in [10.0, 10.1, 10.25, 10.5, 10.707, 10.9] {
            // Falling (bright above) and rising (dark above), γ far from halfway.
            let p = step(e, 200.0, 30.0, 20);
            let i = (0..19).find(|&k| p[k] > 60.0 && p[k + 1] <= 60.0).unwrap();
            let x = area_edge(&p, i, 3, 0.0).unwrap();
            assert!((x - e).abs() < 1e-5, "edge {e}: found {x}");
            let q: Vec<f32> = p.iter().map(|v| 230.0 - v).collect();
            let i = (0..19).find(|&k| q[k] <= 60.0 && q[k + 1] > 60.0).unwrap();
            let x = area_edge(&q, i, 3, 5.0).unwrap();
            assert!((x - 5.0 - e).abs() < 1e-5, "rising edge {e}: found {x}");
            // Blurred (σ = 0.6 px, as the light fixture): the three samples either
            // side hold all but 1e-3 of the transition.
            let b = blurred_step(e, 200.0, 30.0, 20, 0.6);
            let i = (0..19)
                .find(|&k| b[k] > 115.0 && b[k + 1] <= 115.0)
                .unwrap();
            let x = area_edge(&b, i, 3, 0.0).unwrap();
            assert!((x - e).abs() < 0.01, "blurred edge {e}: found {x}");
        }
    }

    #[test]
    fn area_edge_stops_at_a_rise_beyond_the_step() {
        // Bright disk, a 2.5 px dark gap, then a mirror image: the mirror is not
        // part of the step.
        let mut p = step(10.3, 220.0, 20.0, 20);
        for v in &mut p[13..] {
            *v = 80.0;
        }
        p[12] = 20.0 + 60.0 * 0.2;
        let x = area_edge(&p, 10, 3, 0.0).unwrap();
        assert!((x - 10.3).abs() < 1e-5, "found {x}");
        assert_eq!(area_edge(&[50.0; 8], 3, 3, 0.0), None);
    }
}
