//! Streaming frames off the disk, one at a time, in clip order.
//!
//! A [`FrameSource`] decodes a video with FFmpeg's libraries ([`VideoDecoder`],
//! the same libavcodec as OpenCV's `VideoCapture`, without converting pixels
//! nobody reads) or reads a frame folder through the `image` crate, in natural
//! name order. It holds one decoded frame at a time and lends it out as a
//! [`FrameView`], so memory stays bounded whatever the clip length. A video
//! tagged with a display matrix is lent out as displayed ([`Orientation`]).

use std::ops::Range;
use std::path::{Path, PathBuf};

use super::decoder::VideoDecoder;
use super::info::{VIDEO_EXTENSIONS, frame_files, lower_extension};
use super::{ChannelOrder, FootageError, FrameView, Orientation, VideoSignal};

/// One frame lent out by [`FrameSource::next_frame`].
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    /// 0-based position in the clip as stored (dropped frames leave no gap here).
    pub index: usize,
    /// The container's presentation time of this frame [s, playback clock], when
    /// the container has per-frame timestamps (videos); `None` for frame folders.
    pub container_time_s: Option<f64>,
    /// How the codec coded it: 'I', 'P' or 'B' (libavutil's picture type); `None` for
    /// frame folders.
    pub picture_type: Option<char>,
    pub view: FrameView<'a>,
}

/// A video's frames as its container lists them, read without decoding
/// ([`FrameSource::stream_index`]).
#[derive(Clone, Debug)]
pub struct StreamIndex {
    /// Every frame's container timestamp [s, playback clock] in display order:
    /// entry `i` is frame `i` of the clip.
    pub container_times_s: Vec<f64>,
    /// The frames decoding can start from (key frames), ascending.
    pub key_frames: Vec<usize>,
}

/// One frame's 8-bit planar 4:2:0 samples ([`FrameSource::yuv420`]).
#[derive(Clone, Copy, Debug)]
pub struct Yuv420<'a> {
    /// Frame size \[px\].
    pub width: usize,
    pub height: usize,
    /// (samples, row stride) of Y, U and V; U and V cover 2 × 2 pixels each.
    pub planes: [(&'a [u8], usize); 3],
}

/// The frames of one clip, decoded one at a time.
pub struct FrameSource {
    path: PathBuf,
    next: usize,
    /// Frames the container says it holds (a folder: its files).
    expected: Option<usize>,
    reader: Reader,
}

enum Reader {
    Video(Box<VideoDecoder>),
    Folder {
        files: Vec<PathBuf>,
        frame: image::RgbImage,
    },
}

impl FrameSource {
    /// Open a video file or a frame folder for streaming.
    ///
    /// # Errors
    /// `NotFound`, `UnknownExtension`, `EmptyFolder`, or `Unreadable` when FFmpeg
    /// cannot open the video.
    pub fn open(path: &Path) -> Result<Self, FootageError> {
        let meta = FootageError::metadata(path)?;
        if meta.is_dir() {
            // `frame_files` refuses a folder without frames.
            let files = frame_files(path)?;
            return Ok(Self {
                path: path.to_path_buf(),
                next: 0,
                expected: Some(files.len()),
                reader: Reader::Folder {
                    files,
                    frame: image::RgbImage::new(0, 0),
                },
            });
        }
        let ext = lower_extension(path).unwrap_or_default();
        if !VIDEO_EXTENSIONS.contains(&ext.as_str()) {
            return Err(FootageError::UnknownExtension {
                path: path.to_path_buf(),
                ext,
            });
        }
        let decoder = VideoDecoder::open(path)?;
        Ok(Self {
            path: path.to_path_buf(),
            next: 0,
            expected: decoder.frame_count(),
            reader: Reader::Video(Box::new(decoder)),
        })
    }

    /// The clip's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Frames the container says it holds (a folder: its frame files), if known.
    pub fn expected_frames(&self) -> Option<usize> {
        self.expected
    }

    /// The frame rate the container stores (average, else nominal) [frames/s];
    /// `None` for a frame folder or a container without one.
    pub fn container_fps(&self) -> Option<f64> {
        match &self.reader {
            Reader::Video(decoder) => decoder.fps(),
            Reader::Folder { .. } => None,
        }
    }

    /// The rotation and mirror that turn the stored frames into the displayed
    /// ones, which are what this source lends out (identity for a frame folder).
    pub fn orientation(&self) -> Orientation {
        match &self.reader {
            Reader::Video(decoder) => decoder.orientation(),
            Reader::Folder { .. } => Orientation::IDENTITY,
        }
    }

    /// The bit depth, range, matrix and transfer function of a video's samples,
    /// which frames are converted from to 8-bit full-range colour; `None` for a
    /// frame folder.
    pub fn video_signal(&self) -> Option<VideoSignal> {
        match &self.reader {
            Reader::Video(decoder) => Some(decoder.signal().clone()),
            Reader::Folder { .. } => None,
        }
    }

    /// From the next frame on, lend frames in which only `columns` need to be
    /// right (`None`: every column). A video then converts just those columns
    /// from the codec's YUV to colour, and the other columns of a lent frame
    /// hold stale pixels: for callers that read a band of columns, such as the
    /// side-view stage. [`Self::whole_frame`] converts the rest on demand.
    ///
    /// # Errors
    /// `Unreadable` when libswscale refuses the conversion.
    pub fn convert_only_columns(
        &mut self,
        columns: Option<Range<usize>>,
    ) -> Result<(), FootageError> {
        match &mut self.reader {
            Reader::Video(decoder) => decoder.set_columns(columns),
            Reader::Folder { .. } => Ok(()),
        }
    }

    /// The frame last returned by [`Self::next_frame`], every column converted.
    ///
    /// # Errors
    /// `Unreadable` when no frame has been read or the conversion fails.
    pub fn whole_frame(&mut self) -> Result<FrameView<'_>, FootageError> {
        match &mut self.reader {
            Reader::Video(decoder) => {
                let (width, height) = decoder.size();
                Ok(bgr_view(decoder.bgr_whole()?, width, height))
            }
            Reader::Folder { frame, .. } => {
                if frame.width() == 0 {
                    return Err(FootageError::unreadable(&self.path, "no frame read yet"));
                }
                Ok(FrameView::from_rgb(frame))
            }
        }
    }

    /// Every `step`-th brightness sample of every `step`-th row of the frame last
    /// returned by [`Self::next_frame`] [grey levels of 8 bits], the same pixels
    /// every frame: a video's luma plane as decoded (no colour conversion), a
    /// frame folder's mean of the three channels. For comparing frames with their
    /// neighbours ([`super::RepeatGauge`]).
    ///
    /// # Errors
    /// `Unreadable` when no frame has been read.
    pub fn brightness_samples(&mut self, step: usize) -> Result<Vec<f32>, FootageError> {
        let step = step.max(1);
        if let Reader::Video(decoder) = &self.reader
            && let Some(samples) = decoder.luma_samples(step)
        {
            return Ok(samples);
        }
        let view = self.whole_frame()?;
        let mut samples = Vec::with_capacity((view.width / step + 1) * (view.height / step + 1));
        for y in (0..view.height).step_by(step) {
            for x in (0..view.width).step_by(step) {
                samples.push(view.intensity(x, y));
            }
        }
        Ok(samples)
    }

    /// The frame last returned by [`Self::next_frame`] as the codec stores it,
    /// when that is 8-bit planar 4:2:0 in the displayed orientation: samples not
    /// yet converted to colour, for keeping parts of frames cheaply (the
    /// overlays'); `None` otherwise (frame folders, other formats, turned video).
    pub fn yuv420(&self) -> Option<Yuv420<'_>> {
        let Reader::Video(decoder) = &self.reader else {
            return None;
        };
        let (width, height) = decoder.size();
        Some(Yuv420 {
            width,
            height,
            planes: decoder.yuv420_planes()?,
        })
    }

    /// Skip ahead so that the next frame returned is `index` (for a video, by
    /// seeking; a codec may land on a nearby key frame, so the caller should
    /// read [`Frame::index`] rather than assume it).
    ///
    /// # Errors
    /// `Unreadable` when the container refuses the seek.
    pub fn seek(&mut self, index: usize) -> Result<(), FootageError> {
        if let Reader::Video(decoder) = &mut self.reader {
            decoder.seek(index)?;
        }
        self.next = index;
        Ok(())
    }

    /// Every frame's container timestamp and the key frames, from the packets
    /// (demuxing, no decoding), so that a span of the clip can be decoded with
    /// each frame's number in the whole clip known; `None` for a frame folder or
    /// a video whose packets lack timestamps. Rewinds to the first frame.
    ///
    /// # Errors
    /// `Unreadable` when the container refuses the rewind.
    pub fn stream_index(&mut self) -> Result<Option<StreamIndex>, FootageError> {
        let Reader::Video(decoder) = &mut self.reader else {
            return Ok(None);
        };
        let stamps = decoder.packet_stamps()?;
        self.next = 0;
        Ok(stamps.map(|stamps| StreamIndex {
            container_times_s: stamps.iter().map(|s| s.0).collect(),
            key_frames: (0..stamps.len()).filter(|&i| stamps[i].1).collect(),
        }))
    }

    /// Skip to frame `index` of a video as `stream` (its [`Self::stream_index`])
    /// lists it: the next frame returned is that frame, numbered `index`. Seeking
    /// to the listed timestamp, less half the interval before it, lands on the
    /// right frame in a variable-rate clip (jitter, a slowed section), where
    /// [`Self::seek`]'s index / average fps would not.
    ///
    /// # Errors
    /// `Unreadable` when the container refuses the seek or `stream` lists no
    /// frame `index`.
    pub fn seek_frame(&mut self, index: usize, stream: &StreamIndex) -> Result<(), FootageError> {
        if let Reader::Video(decoder) = &mut self.reader {
            let times = &stream.container_times_s;
            let Some(&time_s) = times.get(index) else {
                return Err(FootageError::unreadable(
                    &self.path,
                    format!(
                        "cannot seek to frame {index}: the container lists {}",
                        times.len()
                    ),
                ));
            };
            let interval = match index {
                0 => times.get(1).map_or(f64::INFINITY, |t| t - time_s),
                _ => time_s - times[index - 1],
            };
            decoder.seek_time(
                time_s,
                0.5 * interval,
                &format!("frame {index} ({time_s} s)"),
            )?;
        }
        self.next = index;
        Ok(())
    }

    /// Decode the next frame, or `None` at the end of the clip.
    ///
    /// # Errors
    /// `Unreadable` naming the frame file (folders) or the frame number (videos)
    /// when a frame cannot be decoded, when a folder's frames change size, or when
    /// a video ends more than one frame before the count its container states (a
    /// truncated file).
    pub fn next_frame(&mut self) -> Result<Option<Frame<'_>>, FootageError> {
        let index = self.next;
        match &mut self.reader {
            Reader::Folder { files, frame } => {
                let Some(file) = files.get(index) else {
                    return Ok(None);
                };
                let decoded = image::open(file)
                    .map_err(|e| FootageError::unreadable(file, format!("frame {index}: {e}")))?
                    .into_rgb8();
                if frame.width() > 0 && decoded.dimensions() != frame.dimensions() {
                    let (w, h) = decoded.dimensions();
                    let (w0, h0) = frame.dimensions();
                    return Err(FootageError::unreadable(
                        file,
                        format!("frame {index} is {w} x {h} px, earlier frames {w0} x {h0} px"),
                    ));
                }
                *frame = decoded;
                self.next += 1;
                Ok(Some(Frame {
                    index,
                    container_time_s: None,
                    picture_type: None,
                    view: FrameView::from_rgb(frame),
                }))
            }
            Reader::Video(decoder) => {
                let Some(time_s) = decoder.next()? else {
                    return match self.expected {
                        Some(expected) if index + 1 < expected => Err(FootageError::unreadable(
                            &self.path,
                            format!(
                                "decoding stopped at frame {index} of the {expected} \
                                     the container states (truncated or corrupt file)"
                            ),
                        )),
                        _ => Ok(None),
                    };
                };
                self.next += 1;
                let (width, height) = decoder.size();
                Ok(Some(Frame {
                    index,
                    container_time_s: time_s.filter(|t| t.is_finite() && *t >= 0.0),
                    picture_type: decoder.picture_type(),
                    view: bgr_view(decoder.bgr()?, width, height),
                }))
            }
        }
    }
}

/// A decoded BGR buffer (rows `3 · width` bytes apart) as a [`FrameView`].
fn bgr_view(data: &[u8], width: usize, height: usize) -> FrameView<'_> {
    FrameView {
        width,
        height,
        stride: 3 * width,
        order: ChannelOrder::Bgr,
        data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use opencv::core::Mat;
    use opencv::prelude::*;
    use opencv::videoio;

    fn write_frames(dir: &Path, sizes: &[(u32, u32)]) {
        for (i, &(w, h)) in sizes.iter().enumerate() {
            let img = image::RgbImage::from_pixel(w, h, image::Rgb([i as u8 * 10, 0, 0]));
            img.save(dir.join(format!("f{}.png", i + 1))).unwrap();
        }
    }

    #[test]
    fn folder_frames_stream_in_natural_order() {
        let dir = tempfile::tempdir().unwrap();
        write_frames(dir.path(), &[(4, 3); 12]);
        let mut source = FrameSource::open(dir.path()).unwrap();
        assert_eq!(source.expected_frames(), Some(12));
        let mut reds = Vec::new();
        while let Some(frame) = source.next_frame().unwrap() {
            assert_eq!((frame.view.width, frame.view.height), (4, 3));
            reds.push(frame.view.rgb(0, 0)[0]);
        }
        // f2.png (red 10) comes before f10.png (red 90): natural, not lexical, order.
        assert_eq!(reds, (0..12).map(|i| i * 10).collect::<Vec<u8>>());
    }

    #[test]
    fn a_frame_of_another_size_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        write_frames(dir.path(), &[(4, 3), (4, 3), (5, 3)]);
        let mut source = FrameSource::open(dir.path()).unwrap();
        source.next_frame().unwrap();
        source.next_frame().unwrap();
        let err = source.next_frame().unwrap_err().to_string();
        assert!(err.contains("f3.png") && err.contains("frame 2"), "{err}");
    }

    #[test]
    fn a_corrupt_frame_file_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        write_frames(dir.path(), &[(4, 3)]);
        std::fs::write(dir.path().join("f2.png"), b"not a png").unwrap();
        let mut source = FrameSource::open(dir.path()).unwrap();
        source.next_frame().unwrap();
        let err = source.next_frame().unwrap_err().to_string();
        assert!(err.contains("f2.png"), "{err}");
    }

    /// An MJPG AVI of `n` frames whose blue channel encodes the frame number.
    fn write_avi(path: &Path, n: usize) {
        use opencv::core::{CV_8UC3, Scalar, Size};
        let fourcc = videoio::VideoWriter::fourcc('M', 'J', 'P', 'G').unwrap();
        let mut writer = videoio::VideoWriter::new(
            path.to_str().unwrap(),
            fourcc,
            480.0,
            Size::new(32, 24),
            true,
        )
        .unwrap();
        for i in 0..n {
            let frame = Mat::new_rows_cols_with_default(
                24,
                32,
                CV_8UC3,
                Scalar::new(8.0 * i as f64, 0.0, 0.0, 0.0),
            )
            .unwrap();
            writer.write(&frame).unwrap();
        }
        writer.release().unwrap();
    }

    #[test]
    fn video_frames_stream_with_timestamps() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("clip.avi");
        write_avi(&path, 20);
        let mut source = FrameSource::open(&path).unwrap();
        assert_eq!(source.expected_frames(), Some(20));
        let mut count = 0;
        while let Some(frame) = source.next_frame().unwrap() {
            // MJPG is lossy: the blue level comes back within a few grey levels.
            let blue = frame.view.rgb(16, 12)[2] as f64;
            assert!(
                (blue - 8.0 * frame.index as f64).abs() < 4.0,
                "frame {}: {blue}",
                frame.index
            );
            // The container clock runs at the stored 480 fps.
            let t = frame.container_time_s.unwrap();
            assert!(
                (t - frame.index as f64 / 480.0).abs() < 1e-6,
                "frame {}: {t}",
                frame.index
            );
            count += 1;
        }
        assert_eq!(count, 20);
    }

    #[test]
    fn a_truncated_video_is_an_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cut.avi");
        write_avi(&path, 40);
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
        let result = FrameSource::open(&path).and_then(|mut source| {
            while source.next_frame()?.is_some() {}
            Ok(())
        });
        let err = result.unwrap_err().to_string();
        assert!(err.contains("cut.avi"), "{err}");
    }

    #[test]
    fn a_text_file_is_not_a_clip() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("notes.txt");
        std::fs::write(&file, b"hello").unwrap();
        let err = FrameSource::open(&file).err().unwrap();
        assert!(matches!(err, FootageError::UnknownExtension { .. }));
    }
}
