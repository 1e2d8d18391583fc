//! The intensity threshold γ of the side view (thesis §3.2.4): a pixel is
//! white when the mean of its channels, (1/3)(R/256 + G/256 + B/256), exceeds γ.

use super::VisionError;
use super::profile::check_frame;
use crate::footage::FrameView;

/// The thesis scales the mean channel value by 1/256 to get γ ∈ [0, 1].
pub const INTENSITY_SCALE: f64 = 256.0;

/// How γ was chosen: recorded as provenance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GammaSource {
    /// Given in the configuration.
    Given,
    /// Otsu's method on the intensity histogram of the calibration frame.
    Otsu,
    /// Light plate: halfway between the disk's side and the shadow below its rim
    /// on the centre band of the rest frame.
    RimContrast,
}

/// The side-view threshold γ and where it came from.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Threshold {
    /// γ ∈ (0, 1): white when the mean channel value / 256 exceeds it (§3.2.4).
    pub gamma: f64,
    pub source: GammaSource,
}

impl Threshold {
    /// A γ from the configuration; must lie strictly between 0 and 1.
    pub fn given(gamma: f64) -> Result<Self, VisionError> {
        if gamma > 0.0 && gamma < 1.0 {
            Ok(Self {
                gamma,
                source: GammaSource::Given,
            })
        } else {
            Err(VisionError::InvalidSetting {
                name: "gamma",
                value: gamma,
                reason: "γ must lie strictly between 0 and 1",
            })
        }
    }

    /// γ by Otsu's method on the whole frame: the level that maximises the
    /// between-class variance of the intensity histogram (the frame is scanned
    /// once; meant for the calibration frame). When a range of levels ties, as
    /// with two pure grey levels, the middle of the range is taken.
    pub fn otsu(frame: &FrameView, index: usize) -> Result<Self, VisionError> {
        check_frame(frame, index)?;
        // Histogram of R + G + B (0..=765): exact, no rounding of the mean.
        let mut hist = vec![0u64; 766];
        for y in 0..frame.height {
            for p in frame.row(y).chunks_exact(3) {
                hist[usize::from(p[0]) + usize::from(p[1]) + usize::from(p[2])] += 1;
            }
        }
        // One level only: nothing stands out; report that level as γ.
        let uniform = hist.iter().position(|&n| n > 0).unwrap_or(0) as f64;
        let sum = otsu_level(&hist).ok_or(VisionError::NoDisk {
            frame: index,
            gamma: uniform / 3.0 / INTENSITY_SCALE,
        })?;
        Ok(Self {
            gamma: sum / 3.0 / INTENSITY_SCALE,
            source: GammaSource::Otsu,
        })
    }

    /// γ given, or else Otsu's on `frame`.
    pub fn given_or_otsu(
        gamma: Option<f64>,
        frame: &FrameView,
        index: usize,
    ) -> Result<Self, VisionError> {
        match gamma {
            Some(g) => Self::given(g),
            None => Self::otsu(frame, index),
        }
    }

    /// The same threshold as a mean intensity on the 0–255 scale.
    pub fn level(&self) -> f32 {
        (self.gamma * INTENSITY_SCALE) as f32
    }
}

/// Otsu's threshold on a histogram, as a value between bins: pixels in bins
/// `> level` are the bright class. `None` when the histogram has one level only.
pub(crate) fn otsu_level(hist: &[u64]) -> Option<f64> {
    let total: u64 = hist.iter().sum();
    let total_sum: f64 = hist
        .iter()
        .enumerate()
        .map(|(v, &n)| v as f64 * n as f64)
        .sum();
    let (mut w0, mut sum0) = (0u64, 0.0f64);
    let mut best = -1.0f64;
    let (mut first, mut last) = (0usize, 0usize);
    for (t, &n) in hist.iter().enumerate().take(hist.len() - 1) {
        w0 += n;
        sum0 += t as f64 * n as f64;
        let w1 = total - w0;
        if w0 == 0 || w1 == 0 {
            continue;
        }
        let (m0, m1) = (sum0 / w0 as f64, (total_sum - sum0) / w1 as f64);
        let between = w0 as f64 * w1 as f64 * (m1 - m0) * (m1 - m0);
        // Relative tolerance: ties across empty bins must count as ties.
        if between > best * (1.0 + 1e-12) {
            best = between;
            first = t;
            last = t;
        } else if between >= best * (1.0 - 1e-12) {
            last = t;
        }
    }
    // Split between bin `t` and `t + 1`: the class boundary is at t + ½.
    (best > 0.0).then(|| 0.5 * (first + last) as f64 + 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::footage::ChannelOrder;

    #[test]
    fn otsu_between_two_grey_levels() {
        // 40 % of the pixels at grey 40, the rest at grey 200.
        let (w, h) = (50, 20);
        let data: Vec<u8> = (0..w * h)
            .flat_map(|i| {
                let g = if i % 5 < 2 { 40 } else { 200 };
                [g, g, g]
            })
            .collect();
        let frame = FrameView {
            width: w,
            height: h,
            stride: 3 * w,
            order: ChannelOrder::Rgb,
            data: &data,
        };
        let t = Threshold::otsu(&frame, 0).unwrap();
        assert_eq!(t.source, GammaSource::Otsu);
        let level = t.level();
        assert!(level > 40.0 && level < 200.0, "level {level}");
        // Two pure levels tie over the whole gap: the middle is chosen.
        assert!((level - 120.0).abs() < 1.0, "level {level}");
    }

    #[test]
    fn one_level_has_no_threshold_and_bad_gamma_is_refused() {
        let data = vec![90u8; 3 * 8 * 8];
        let frame = FrameView {
            width: 8,
            height: 8,
            stride: 24,
            order: ChannelOrder::Bgr,
            data: &data,
        };
        assert!(matches!(
            Threshold::otsu(&frame, 7),
            Err(VisionError::NoDisk { frame: 7, .. })
        ));
        assert!(Threshold::given(1.2).is_err());
        assert_eq!(Threshold::given(0.35).unwrap().source, GammaSource::Given);
    }
}
