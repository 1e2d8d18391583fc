//! Footage: the first stage of the data flow, and one of only two that read files.
//!
//! Input is a clip as the user filmed it: a video file (MP4/MOV/AVI, decoded by
//! FFmpeg's libavcodec, the library behind OpenCV's `videoio`, called directly so
//! that only the pixels the side view reads are converted to colour) or a folder
//! of PNG/TIFF/JPEG frames (read by the `image` crate, in natural name order).
//! This stage owns everything about frames as they come off the disk: metadata,
//! the capture fps and where it came from, frame times (the container's
//! timestamps mapped to capture time section by section, [`frame_times`]), the display matrix a phone
//! tags its frames with ([`Orientation`]: frames are lent out as displayed), the
//! samples' bit depth, range, matrix and transfer function ([`VideoSignal`]:
//! frames are converted to one 8-bit brightness scale), duplicated and
//! interpolated frames ([`RepeatGauge`]), frame-skip flags, the region of interest
//! and the mirror split. The frames it delivers go on to
//! `vision`, which turns them into `z_rim(t)` and `β(t)`.
//!
//! [`FrameSource`] streams a clip's frames; [`probe`] reports what OpenCV says
//! about a clip ([`ClipInfo`], shown by `eulerdisk info CLIP`), and
//! [`frame_files`] lists a frame folder in the order its frames are analysed.
//! Failures are [`FootageError`]s that name the file.

mod capture_rate;
mod colour;
mod decoder;
mod error;
mod frame;
mod info;
mod orientation;
mod repeats;
mod smoothing;
mod source;
mod timing;

pub use capture_rate::{
    CaptureFps, ContainerCaptureRate, FpsSource, container_capture_rate, resolve_capture_fps,
};
pub use colour::VideoSignal;
pub use error::FootageError;
pub use frame::{ChannelOrder, FrameView};
pub use info::{
    ClipInfo, ClipKind, FRAME_EXTENSIONS, LOW_FPS_LIMIT, VIDEO_EXTENSIONS, frame_files,
    natural_cmp, probe,
};
pub use orientation::{Orientation, PixelMap};
pub use repeats::{RepeatGauge, RepeatKind, RepeatedFrame};
pub use smoothing::smoothing_by_picture_type;
pub use source::{Frame, FrameSource, StreamIndex, Yuv420};
pub use timing::{FrameTiming, TimeSection, TimeSource, frame_times, time_sections};
