//! Owned copies of frames and the side and plan views cut from a frame.

use crate::footage::{self, FrameView};
use crate::vision::{self, VisionError};

/// An owned copy of a frame (for the few rest frames kept in pass 1).
pub(super) struct OwnedFrame {
    pub(super) index: usize,
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) order: footage::ChannelOrder,
    pub(super) data: Vec<u8>,
}

impl OwnedFrame {
    pub(super) fn copy(index: usize, view: &FrameView) -> Self {
        let mut data = Vec::with_capacity(3 * view.width * view.height);
        for y in 0..view.height {
            data.extend_from_slice(view.row(y));
        }
        Self {
            index,
            width: view.width,
            height: view.height,
            order: view.order,
            data,
        }
    }

    pub(super) fn view(&self) -> FrameView<'_> {
        FrameView {
            width: self.width,
            height: self.height,
            stride: 3 * self.width,
            order: self.order,
            data: &self.data,
        }
    }
}

/// The side view of a frame: the region of interest (or the whole frame), or its
/// top part in a two-view clip; and the plan view below the split.
pub(super) fn side_view<'a>(
    frame: &FrameView<'a>,
    roi: Option<[u32; 4]>,
    split: Option<usize>,
    index: usize,
) -> Result<(FrameView<'a>, Option<FrameView<'a>>), VisionError> {
    let frame = match roi {
        Some([x, y, w, h]) => frame
            .crop(x as usize, y as usize, w as usize, h as usize)
            .ok_or(VisionError::InvalidSetting {
                name: "roi",
                value: f64::from(x + w).max(f64::from(y + h)),
                reason: "the region of interest [x, y, width, height] reaches outside the frame",
            })?,
        None => *frame,
    };
    match split {
        Some(row) => {
            let (side, plan) = vision::split_views(&frame, row, index)?;
            Ok((side, Some(plan)))
        }
        None => Ok((frame, None)),
    }
}
