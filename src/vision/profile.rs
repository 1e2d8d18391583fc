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
/// whose sample `k` sits at position `origin + k + ½` (a pixel centre).
///
/// The step is located where the profile crosses the *local* half level
/// (hi + lo)/2, with hi and lo the extremes of the `reach` samples on either
/// side, interpolated linearly between the two samples that straddle it. For
/// an ideal edge sampled by area (anti-aliased) this is within 0.09 px of the
/// true edge whatever γ was used to find it; a global γ that is not halfway
/// between the two levels would bias the edge by up to half a pixel.
pub(crate) fn half_level_crossing(p: &[f32], i: usize, reach: usize, origin: f64) -> Option<f64> {
    if i + 1 >= p.len() {
        return None;
    }
    let before = i.saturating_sub(reach - 1)..=i;
    let after = i + 1..=(i + reach).min(p.len() - 1);
    let falling = p[i] > p[i + 1];
    let (a, b) = (
        before
            .map(|k| p[k])
            .fold(f32::NAN, |m, v| if falling { m.max(v) } else { m.min(v) }),
        after
            .map(|k| p[k])
            .fold(f32::NAN, |m, v| if falling { m.min(v) } else { m.max(v) }),
    );
    if (a - b).abs() < 1e-3 {
        return None;
    }
    let level = 0.5 * (a + b);
    // The straddling pair nearest the coarse step, searching outward from it.
    let lo = i.saturating_sub(reach - 1);
    let hi = (i + reach).min(p.len() - 1);
    for d in 0..reach {
        for j in [i.checked_sub(d), i.checked_add(d)].into_iter().flatten() {
            if j < lo || j + 1 > hi {
                continue;
            }
            let (u, v) = (p[j], p[j + 1]);
            let straddles = if falling {
                u >= level && v < level
            } else {
                u < level && v >= level
            };
            if straddles {
                let t = f64::from((u - level) / (u - v));
                return Some(origin + j as f64 + 0.5 + t);
            }
        }
    }
    None
}

/// Sub-pixel position of the step between samples `i` and `i + 1` of a profile
/// whose sample `k` covers [origin + k, origin + k + 1), by its area: the
/// transition is the monotone run of samples through the step, at most `reach`
/// either side, from level `a` (its first sample) to level `b` (its last), and
/// the edge lies `Σ (p_k − b)/(a − b)` px after the start of the run.
///
/// For a step sampled by area (anti-aliased), blurred by any symmetric kernel
/// narrower than the run, this is exact whatever the edge's sub-pixel phase,
/// where [`half_level_crossing`]'s linear interpolation is off by up to
/// ±0.086 px depending on it (a bias, not noise, for an edge that barely moves,
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

    #[test]
    fn half_level_crossing_of_area_sampled_step() {
        for e in [10.0, 10.1, 10.25, 10.5, 10.707, 10.9] {
            let p = step(e, 200.0, 30.0, 20);
            // Coarse step as a γ far from halfway would find it: γ = 60.
            let i = (0..19).find(|&k| p[k] > 60.0 && p[k + 1] <= 60.0).unwrap();
            let x = half_level_crossing(&p, i, 3, 0.0).unwrap();
            // Linear interpolation of an area-sampled step: worst case 0.086 px
            // (at a coverage of 1/√2).
            assert!((x - e).abs() < 0.09, "edge {e}: found {x}");
        }
    }
}
