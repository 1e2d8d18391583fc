//! What the measurement shows of the frames it reads, to a layer above it that
//! keeps pictures of them (the measurement overlay), so that the clip need not be
//! decoded again: the frame's geometry once calibrated, then every frame of the
//! span read, with its raw rim height and, on demand, the strip as measured. The
//! measurement defines these traits and never names their implementations.

use super::ExperimentPlan;
use crate::footage::{FootageError, FrameSource};
use crate::vision;

/// Makes a keeper for each span pass 2 reads ([`crate::analyse::analyse_clip_keeping`]).
pub trait FrameKeeping {
    /// The keeper of one span's frames.
    type Keeper: KeepFrames<Kept = Self::Kept>;
    /// What a keeper keeps.
    type Kept;
    /// A keeper for a span read from `source` with the frame's `geometry`, at `fps`
    /// frames per second of capture; `None` when this clip's frames cannot be kept.
    fn keeper(
        &self,
        geometry: &LayoutGeometry,
        fps: f64,
        source: &FrameSource,
    ) -> Option<Self::Keeper>;
}

/// Keeps pictures of the frames of one span as pass 2 reads them.
pub trait KeepFrames {
    /// What is kept.
    type Kept;
    /// Frame `position` of the span, just read from `source`, with its raw rim
    /// height \[px\] and the strip as measured (made only when asked for).
    ///
    /// # Errors
    /// The frame cannot be lent whole.
    fn offer(
        &mut self,
        position: usize,
        z_rim_px: Option<f64>,
        source: &mut FrameSource,
        strip: impl FnOnce() -> Option<StripMark>,
    ) -> Result<(), FootageError>;
    /// What was kept, `None` if nothing could be.
    fn finish(self) -> Option<Self::Kept>;
}

/// Keeps nothing: the measurement alone.
pub struct KeepNothing;

impl FrameKeeping for KeepNothing {
    type Keeper = KeepNothing;
    type Kept = ();
    fn keeper(&self, _: &LayoutGeometry, _: f64, _: &FrameSource) -> Option<KeepNothing> {
        None
    }
}

impl KeepFrames for KeepNothing {
    type Kept = ();
    fn offer(
        &mut self,
        _: usize,
        _: Option<f64>,
        _: &mut FrameSource,
        _: impl FnOnce() -> Option<StripMark>,
    ) -> Result<(), FootageError> {
        Ok(())
    }
    fn finish(self) -> Option<()> {
        None
    }
}

/// What the windows of an overlay frame are placed by: known once the clip is
/// calibrated, before its frames are measured (so that a [`FrameKeeping`] can keep the
/// windows' pixels while the measurement reads them).
#[derive(Debug, Clone, Copy)]
pub struct LayoutGeometry {
    pub calibration: vision::Calibration,
    /// The side view's pixel (0, 0) in the frame ([`ExperimentPlan::side_view_origin`]).
    pub origin: (usize, usize),
    /// The region of interest's size, else the frame's \[px\].
    pub view: (usize, usize),
    /// The row splitting the side view (above) from the plan view (two-view clips).
    pub split_row: Option<usize>,
    pub band_half_width_px: usize,
    /// The side view's row where z_rim = 0 ([`ExperimentPlan::rim_edge_row`]).
    pub zero_row: f64,
}

impl LayoutGeometry {
    /// The geometry of an analysed clip.
    pub fn of(plan: &ExperimentPlan) -> Self {
        let roi = plan.config.vision.as_ref().and_then(|v| v.roi);
        Self {
            calibration: plan.calibration.calibration,
            origin: plan.side_view_origin(),
            view: roi.map_or((plan.width, plan.height), |r| {
                (r[2] as usize, r[3] as usize)
            }),
            split_row: plan.split_row.map(|(row, _)| row),
            band_half_width_px: plan.band_half_width_px,
            zero_row: plan.rim_edge_row(0.0),
        }
    }
}

/// The strip found in a plan view: the mask's outline and principal axis drawn.
pub struct StripMark {
    pub strip: vision::Strip,
    /// The mask over the plan view from the window's corner, row-major, and its
    /// width.
    pub mask: Option<(Vec<bool>, usize)>,
}
