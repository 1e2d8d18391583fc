//! The centre band's rows about one frame's first-pass rim edge, kept through the
//! streamed pass so that the rim can be re-measured once the whole clip has taught
//! the edge's appearance (vision::mirror_edge on a dark plate, vision::shadow_edge
//! on a light one).

use std::ops::Range;

use super::profile::row_band_mean;
use crate::footage::FrameView;
use crate::numeric::median;

/// Rows recorded per frame above the first-pass edge (the disk's level is read on
/// the top [`LEVEL_ROWS`] of them).
pub const ROWS_ABOVE: usize = 14;
/// Rows recorded per frame below the first-pass edge.
pub const ROWS_BELOW: usize = 12;
/// Rows at the top of a window whose median is the disk's level.
pub(super) const LEVEL_ROWS: usize = 6;

/// The band's mean intensities on consecutive rows of one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct BandWindow {
    /// The first row.
    pub first_row: usize,
    /// Band means, one per row from `first_row`.
    pub values: Vec<f32>,
    /// The camera's vertical shift in this frame against the rest tail \[px\]
    /// (vision::registration; positive: the picture moved down): row k of the
    /// window shows the scene's rows from `first_row + k − shift`.
    pub shift: f64,
}

impl BandWindow {
    /// The rows [round(`edge`) − [`ROWS_ABOVE`], round(`edge`) + [`ROWS_BELOW`])
    /// of `columns`, clipped to the frame; `None` when fewer than
    /// [`LEVEL_ROWS`] + 4 rows remain.
    pub fn read(frame: &FrameView, columns: &Range<usize>, edge: f64) -> Option<Self> {
        let centre = edge.round();
        if !centre.is_finite() {
            return None;
        }
        let first = (centre - ROWS_ABOVE as f64).max(0.0) as usize;
        let end = ((centre + ROWS_BELOW as f64).max(0.0) as usize).min(frame.height);
        if end < first + LEVEL_ROWS + 4 {
            return None;
        }
        let values = (first..end)
            .map(|y| row_band_mean(frame, y, columns.start, columns.end))
            .collect();
        Some(Self {
            first_row: first,
            values,
            shift: 0.0,
        })
    }

    /// The mean of several windows of the same rows (the rest frames); `None` when
    /// there are none or their rows differ.
    pub fn mean<'a>(windows: impl IntoIterator<Item = &'a Self>) -> Option<Self> {
        let windows: Vec<&Self> = windows.into_iter().collect();
        let first = windows.first()?;
        if windows.iter().any(|w| !w.same_rows(first)) {
            return None;
        }
        let n = windows.len() as f32;
        let values = (0..first.values.len())
            .map(|k| windows.iter().map(|w| w.values[k]).sum::<f32>() / n)
            .collect();
        let shift = windows.iter().map(|w| w.shift).sum::<f64>() / f64::from(n);
        Some(Self {
            first_row: first.first_row,
            values,
            shift,
        })
    }

    /// Whether `other` holds the same rows.
    pub fn same_rows(&self, other: &Self) -> bool {
        self.first_row == other.first_row && self.values.len() == other.values.len()
    }

    /// The mean of the windows among the last `tail` of a clip's `windows` (one per
    /// frame, `None` without an edge) that hold the same rows as `like`, or `None`
    /// when fewer than `min` do.
    pub fn tail_mean(
        windows: &[Option<Self>],
        like: &Self,
        tail: usize,
        min: usize,
    ) -> Option<Self> {
        let same: Vec<&Self> = windows[windows.len().saturating_sub(tail)..]
            .iter()
            .flatten()
            .filter(|w| w.same_rows(like))
            .collect();
        if same.len() < min {
            return None;
        }
        Self::mean(same)
    }

    /// The disk's level: the median of the top [`LEVEL_ROWS`] rows.
    pub(super) fn level(&self) -> f64 {
        let top: Vec<f64> = self.values[..LEVEL_ROWS]
            .iter()
            .map(|&v| f64::from(v))
            .collect();
        median(&top)
    }

    /// The top of the window's row `k` in the scene's rows (the rest tail's) \[px\].
    pub(super) fn row_top(&self, k: usize) -> f64 {
        (self.first_row + k) as f64 - self.shift
    }

    /// The index of the window's row that shows the scene's row `y`, if any.
    pub(super) fn index_of(&self, y: f64) -> Option<usize> {
        let k = (y + self.shift).floor() - self.first_row as f64;
        (k >= 0.0 && (k as usize) < self.values.len()).then_some(k as usize)
    }

    /// (row centre, value) pairs, rows in the scene's rows.
    pub(super) fn samples(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.values
            .iter()
            .enumerate()
            .map(|(k, &v)| (self.row_top(k) + 0.5, f64::from(v)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A window of 26 rows from `first_row` with a step from the disk's 200 to the
    /// gap's 40 at row `edge`, sampled by area.
    fn step(first_row: usize, edge: f64) -> BandWindow {
        let values = (0..26)
            .map(|k| {
                let cover = (edge - (first_row + k) as f64).clamp(0.0, 1.0) as f32;
                40.0 + 160.0 * cover
            })
            .collect();
        BandWindow {
            first_row,
            values,
            shift: 0.0,
        }
    }

    /// The edge of a window by the area of its step.
    fn area(w: &BandWindow) -> f64 {
        w.first_row as f64
            + w.values
                .iter()
                .map(|&v| f64::from((v - 40.0) / 160.0))
                .sum::<f64>()
    }

    #[test]
    fn the_rest_tail_mean_follows_the_tail_not_its_last_frames() {
        // A still disk whose last five frames were coded apart, 0.3 px lower, after
        // 43 others at 30.2 px; before them the rim moved (other rows, and no edge).
        let mut windows: Vec<Option<BandWindow>> = vec![None, Some(step(12, 24.0))];
        windows.extend((0..43).map(|_| Some(step(16, 30.2))));
        windows.extend((0..5).map(|_| Some(step(16, 30.5))));
        let last_five = BandWindow::mean(windows[windows.len() - 5..].iter().flatten()).unwrap();
        assert!((area(&last_five) - 30.5).abs() < 1e-4);
        let tail = BandWindow::tail_mean(&windows, &last_five, 60, 5).expect("a tail");
        let expected = (43.0 * 30.2 + 5.0 * 30.5) / 48.0;
        assert!(
            (area(&tail) - expected).abs() < 1e-4,
            "tail edge {} (expected {expected})",
            area(&tail)
        );
        // Too few frames of the same rows: none.
        assert_eq!(
            BandWindow::tail_mean(&windows, &step(12, 24.0), 60, 5),
            None
        );
    }
}
