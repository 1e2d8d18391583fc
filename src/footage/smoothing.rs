//! The codec's smoothing over time, measured against a truth.
//!
//! An encoder that predicts a picture from its neighbours and codes too little of the
//! difference leaves a moving edge part-way between where it was and where it will be:
//! a low-pass over time. Against the true heights z of a clip's frames, a low-pass of
//! variance 2α frame² reads each frame's error as
//!
//! ```text
//! e = z_measured − z = a + α z″,   z″ = z(k + 1) − 2 z(k) + z(k − 1)  [px/frame²],
//! ```
//!
//! so peaks read low and troughs high by α |z″|. The B pictures of an H.264 stream,
//! predicted from both sides, carry more of it than the P pictures (α ≤ 0.064 frame²
//! against ≤ 0.027: docs/validation.md, "Open footage"). [`smoothing_by_picture_type`]
//! fits one α per type; the robustness table and `scripts/check-footage` report it for
//! information. It needs the truth, so `analyse` does not use it.

/// Fewest frames of a picture type whose α is fitted.
const MIN_FRAMES: usize = 10;

/// α of the P and of the B pictures \[frame²\] from `(picture type, z″, e)` per frame
/// (z″ the true heights' second difference per frame, e the measured height's error,
/// both px), by least squares on e = a + α_P z″ \[P\] + α_B z″ \[B\] with one shared a
/// (I pictures and frames of no known type enter a only). `None` for a type with
/// fewer than [`MIN_FRAMES`] frames.
pub fn smoothing_by_picture_type(
    frames: impl IntoIterator<Item = (Option<char>, f64, f64)>,
) -> [Option<f64>; 2] {
    use nalgebra::{Matrix3, Vector3};
    let (mut xx, mut xy) = (Matrix3::<f64>::zeros(), Vector3::<f64>::zeros());
    let mut counts = [0usize; 2];
    for (kind, second, error) in frames {
        let mut x = Vector3::new(1.0, 0.0, 0.0);
        if let Some(j) = ['P', 'B'].iter().position(|&c| Some(c) == kind) {
            x[j + 1] = second;
            counts[j] += 1;
        }
        xx += x * x.transpose();
        xy += x * error;
    }
    // A type with too few frames is left out (its column held at zero).
    for (j, &count) in counts.iter().enumerate() {
        if count < MIN_FRAMES {
            xx[(j + 1, j + 1)] = 1.0;
        }
    }
    let Some(solution) = xx.try_inverse().map(|inverse| inverse * xy) else {
        return [None, None];
    };
    [0, 1].map(|j| (counts[j] >= MIN_FRAMES).then(|| solution[j + 1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Errors made exactly as a + α_T z″ (I pictures: a alone) give α_P and α_B back;
    /// a type seen too rarely has none.
    #[test]
    fn alpha_per_picture_type() {
        let frames: Vec<(Option<char>, f64, f64)> = (0..120)
            .map(|k| {
                let second = (0.7 * f64::from(k)).sin();
                match k % 4 {
                    0 => (Some('I'), second, 0.03),
                    1 => (Some('P'), second, 0.03 + 0.02 * second),
                    _ => (Some('B'), second, 0.03 + 0.15 * second),
                }
            })
            .collect();
        let [p, b] = smoothing_by_picture_type(frames.iter().copied());
        assert!((p.unwrap() - 0.02).abs() < 1e-12, "{p:?}");
        assert!((b.unwrap() - 0.15).abs() < 1e-12, "{b:?}");
        let few_p = frames
            .iter()
            .copied()
            .filter(|f| f.0 != Some('P'))
            .chain(frames.iter().copied().filter(|f| f.0 == Some('P')).take(9));
        let [p, b] = smoothing_by_picture_type(few_p);
        assert_eq!(p, None);
        // The nine P frames, left to a alone, move α_B a little.
        assert!((b.unwrap() - 0.15).abs() < 1e-4, "{b:?}");
    }
}
