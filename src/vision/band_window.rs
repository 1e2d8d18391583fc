//! The centre band's rows about one frame's first-pass rim edge, kept through the
//! streamed pass so that the rim can be re-measured once the whole clip has taught
//! the edge's appearance (vision::mirror_edge on a dark plate, vision::shadow_edge
//! on a light one).

use std::ops::Range;

use super::profile::row_band_mean;
use crate::footage::FrameView;
use crate::signal::median;

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
        })
    }

    /// The mean of several windows of the same rows (the rest frames).
    pub fn mean(windows: &[Self]) -> Option<Self> {
        let first = windows.first()?;
        if windows
            .iter()
            .any(|w| w.first_row != first.first_row || w.values.len() != first.values.len())
        {
            return None;
        }
        let n = windows.len() as f32;
        let values = (0..first.values.len())
            .map(|k| windows.iter().map(|w| w.values[k]).sum::<f32>() / n)
            .collect();
        Some(Self {
            first_row: first.first_row,
            values,
        })
    }

    /// The disk's level: the median of the top [`LEVEL_ROWS`] rows.
    pub(super) fn level(&self) -> f64 {
        let top: Vec<f64> = self.values[..LEVEL_ROWS]
            .iter()
            .map(|&v| f64::from(v))
            .collect();
        median(&top)
    }

    /// (row centre, value) pairs.
    pub(super) fn samples(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.values
            .iter()
            .enumerate()
            .map(|(k, &v)| ((self.first_row + k) as f64 + 0.5, f64::from(v)))
    }
}
