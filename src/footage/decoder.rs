//! Video decoding with FFmpeg's own libraries (through `ffmpeg-next`), converting
//! to colour only the pixels that the caller will read.
//!
//! OpenCV's `VideoCapture` decodes with the same libavcodec, and then converts
//! every pixel of every frame from the codec's YUV to BGR (libswscale) and copies
//! the result into a `Mat`: for a 720×1280 clip that conversion and copy cost a
//! third of the time of decoding itself. The side-view stage reads a band of a few
//! columns, so [`VideoDecoder::set_columns`] converts only that band, with the same
//! libswscale routine and flags as OpenCV (`SWS_BICUBIC`, BGR24), which gives
//! the same bytes (tested against `VideoCapture::read` in this module).
//!
//! A stream tagged with a display matrix (a phone's rotation, a mirror flip; see
//! [`super::orientation`]) is lent out as displayed: the columns asked for are
//! the displayed frame's, converted from the stored rectangle that holds them and
//! copied into place.
//!
//! Seeking lands on the key frame before the target and decodes forward from
//! there, discarding frames, as a decoder must; unlike OpenCV's seek it does not
//! back off a further 16 frames first, but it goes back further when the first
//! frame out lies past the target (an open GOP: MP4 seeks by decoding time, and
//! the B-frames shown before a key frame but decoded after it need the GOP before).

use std::ops::Range;
use std::path::{Path, PathBuf};

use ff::ffi;
use ff::format::Pixel;
use ff::software::scaling;
use ffmpeg_next as ff;

use super::FootageError;
use super::colour::VideoSignal;
use super::orientation::{Orientation, PixelMap};

/// libswscale's interpolation flag as OpenCV 4.6 passes it; for a conversion
/// without scaling it selects the same YUV→RGB routine whatever the width.
const SWS_FLAGS: scaling::Flags = scaling::Flags::BICUBIC;

/// Frames by which a frame's decoding may precede its display (B-frame
/// reordering; x264's default pyramid needs 3, HEVC encoders up to 16).
const REORDER_MARGIN: usize = 16;

/// Bytes past the end of the BGR buffer that libswscale's vector code may write
/// when a conversion ends at the frame's last row and column: it stores whole
/// 8- and 16-byte words (valgrind: 8-byte writes 0 and 8 bytes past a
/// 1280 × 720 × 3 buffer, which corrupted the heap when the overlays converted a
/// band reaching the right edge). FFmpeg pads its own buffers by 64 bytes.
const SWSCALE_OVERRUN: usize = 64;

/// One video stream being decoded frame by frame.
pub(super) struct VideoDecoder {
    path: PathBuf,
    input: ff::format::context::Input,
    stream: usize,
    decoder: ff::decoder::Video,
    /// Seconds per timestamp unit of the stream.
    time_base: f64,
    /// The stream's first timestamp (its time zero), in timestamp units.
    start: i64,
    /// The container's frame rate (average, else nominal), frames/s.
    fps: Option<f64>,
    /// Frames the container says it holds (or its duration times its fps).
    frames: Option<usize>,
    /// The stored (coded) frame's width \[px\].
    width: usize,
    /// The stored (coded) frame's height \[px\].
    height: usize,
    /// The display matrix's rotation and mirror.
    orientation: Orientation,
    /// Stored → displayed pixels, when the orientation is not the identity.
    map: Option<PixelMap>,
    /// Bit depth, range, matrix and transfer function of the samples.
    signal: VideoSignal,
    /// The current decoded frame, in the codec's pixel format.
    yuv: ff::frame::Video,
    /// A frame decoded while seeking that is the next one to lend out.
    pending: bool,
    /// While seeking: packets stamped before this are decoded only if other
    /// frames refer to them (the frames themselves are dropped anyway).
    skip_before: Option<i64>,
    eof_sent: bool,
    /// The current stored frame in BGR, 3 bytes a pixel, rows `3 · width` apart.
    bgr: Vec<u8>,
    /// The displayed frame in BGR (rows `3 ·` displayed width apart), when a
    /// display matrix turns the stored frame.
    shown: Vec<u8>,
    whole: Option<scaling::Context>,
    /// Only these columns are converted (`None`: all of them).
    band: Option<Band>,
}

/// The displayed columns lent out, and the stored rectangle converted for them.
struct Band {
    /// Displayed columns.
    shown: Range<usize>,
    /// Stored columns and rows (even bounds: a chroma sample covers 2 × 2 pixels).
    columns: Range<usize>,
    rows: Range<usize>,
    context: scaling::Context,
}

impl VideoDecoder {
    /// Open the best video stream of `path`, with frame-threaded decoding.
    pub(super) fn open(path: &Path) -> Result<Self, FootageError> {
        let err = |e: ff::Error| {
            FootageError::unreadable(
                path,
                format!(
                    "FFmpeg could not open it ({e}): truncated, not a video, or an unsupported codec"
                ),
            )
        };
        ff::init().map_err(err)?;
        // Failures come back as errors naming the file; FFmpeg's own log lines
        // (a damaged packet, a missing index) would only clutter the terminal.
        ff::util::log::set_level(ff::util::log::Level::Quiet);
        let input = ff::format::input(path).map_err(err)?;
        let Some(stream) = input.streams().best(ff::media::Type::Video) else {
            return Err(FootageError::unreadable(
                path,
                "the file holds no video stream",
            ));
        };
        let index = stream.index();
        let time_base = f64::from(stream.time_base());
        let start = match stream.start_time() {
            ffi::AV_NOPTS_VALUE => 0,
            t => t,
        };
        let rate = |r: ff::Rational| {
            let fps = f64::from(r);
            (r.denominator() != 0 && fps.is_finite() && fps > 0.0).then_some(fps)
        };
        let fps = rate(stream.avg_frame_rate()).or_else(|| rate(stream.rate()));
        let frames = match stream.frames() {
            n if n > 0 => Some(n as usize),
            _ => {
                // No stored count: the stream's (or the file's) duration times fps.
                let secs = if stream.duration() > 0 {
                    stream.duration() as f64 * time_base
                } else {
                    input.duration() as f64 / f64::from(ffi::AV_TIME_BASE)
                };
                fps.map(|fps| (secs * fps).round())
                    .filter(|n| *n >= 1.0)
                    .map(|n| n as usize)
            }
        };
        let mut context =
            ff::codec::context::Context::from_parameters(stream.parameters()).map_err(err)?;
        context.set_threading(ff::threading::Config {
            kind: ff::threading::Type::Frame,
            ..Default::default()
        });
        let orientation = stream
            .side_data()
            .find(|d| d.kind() == ff::codec::packet::side_data::Type::DisplayMatrix)
            .map(|d| Orientation::from_display_matrix(d.data()))
            .transpose()
            .map_err(|reason| FootageError::unreadable(path, reason))?
            .unwrap_or_default();
        let decoder = context.decoder().video().map_err(err)?;
        let (width, height) = (decoder.width() as usize, decoder.height() as usize);
        if width == 0 || height == 0 {
            return Err(FootageError::unreadable(
                path,
                "the video stream has no frame size",
            ));
        }
        let map = (!orientation.is_identity())
            .then(|| orientation.displayed_from_stored((width, height)));
        let signal = VideoSignal::new(
            decoder.format(),
            decoder.color_range(),
            decoder.color_space(),
            decoder.color_transfer_characteristic(),
        );
        Ok(Self {
            path: path.to_path_buf(),
            input,
            stream: index,
            decoder,
            time_base,
            start,
            fps,
            frames,
            width,
            height,
            orientation,
            map,
            signal,
            yuv: ff::frame::Video::empty(),
            pending: false,
            skip_before: None,
            eof_sent: false,
            bgr: vec![0; 3 * width * height + SWSCALE_OVERRUN],
            shown: if map.is_some() {
                vec![0; 3 * width * height]
            } else {
                Vec::new()
            },
            whole: None,
            band: None,
        })
    }

    pub(super) fn frame_count(&self) -> Option<usize> {
        self.frames
    }

    pub(super) fn fps(&self) -> Option<f64> {
        self.fps
    }

    /// The displayed frame's (width, height) \[px\].
    pub(super) fn size(&self) -> (usize, usize) {
        self.orientation.displayed_size((self.width, self.height))
    }

    /// The rotation and mirror of the stream's display matrix.
    pub(super) fn orientation(&self) -> Orientation {
        self.orientation
    }

    /// The bit depth, range, matrix and transfer function of the samples.
    pub(super) fn signal(&self) -> &VideoSignal {
        &self.signal
    }

    /// A libswscale context from `w × h` of the codec's format to BGR24, set up
    /// for the stream's range and matrix.
    fn bgr_context(&self, w: usize, h: usize) -> Result<scaling::Context, FootageError> {
        let mut context = scaling::Context::get(
            self.decoder.format(),
            w as u32,
            h as u32,
            Pixel::BGR24,
            w as u32,
            h as u32,
            SWS_FLAGS,
        )
        .map_err(|e| self.error(format!("libswscale: {e}")))?;
        self.signal
            .configure(&mut context)
            .map_err(|reason| self.error(reason))?;
        Ok(context)
    }

    /// Every `step`-th luma sample of every `step`-th row of the current stored
    /// frame, in grey levels of 8 bits (a deeper format is scaled down), or `None`
    /// when the codec's format has no plain luma plane. The order of the samples
    /// is the stored frame's, the same every frame.
    pub(super) fn luma_samples(&self, step: usize) -> Option<Vec<f32>> {
        self.check_decoded().ok()?;
        let descriptor = self.yuv.format().descriptor()?;
        // SAFETY: the descriptor is libavutil's static table entry for the format.
        let (flags, depth) = unsafe {
            let d = &*descriptor.as_ptr();
            (d.flags, d.comp[0].depth as usize)
        };
        let planar_yuv = descriptor.nb_components() >= 3
            && flags & ffi::AV_PIX_FMT_FLAG_RGB as u64 == 0
            && flags & ffi::AV_PIX_FMT_FLAG_PLANAR as u64 != 0;
        if !planar_yuv || !(8..=16).contains(&depth) {
            return None;
        }
        let (stride, data) = (self.yuv.stride(0), self.yuv.data(0));
        let scale = 1.0 / f32::from(1u16 << (depth - 8));
        let step = step.max(1);
        let mut samples = Vec::with_capacity((self.width / step + 1) * (self.height / step + 1));
        for y in (0..self.height).step_by(step) {
            let row = &data[y * stride..];
            for x in (0..self.width).step_by(step) {
                let v = if depth > 8 {
                    f32::from(u16::from_le_bytes([row[2 * x], row[2 * x + 1]]))
                } else {
                    f32::from(row[x])
                };
                samples.push(v * scale);
            }
        }
        Some(samples)
    }

    /// The current frame's planes of 8-bit planar 4:2:0 samples as stored, each
    /// (samples, row stride): Y, then U and V at half the width and height;
    /// `None` for other formats, a display matrix that turns the frame, or no
    /// frame at hand.
    pub(super) fn yuv420_planes(&self) -> Option<[(&[u8], usize); 3]> {
        self.check_decoded().ok()?;
        let planar = matches!(self.yuv.format(), Pixel::YUV420P | Pixel::YUVJ420P);
        if !planar || self.map.is_some() {
            return None;
        }
        Some([0, 1, 2].map(|i| (self.yuv.data(i), self.yuv.stride(i))))
    }

    /// Convert only the displayed `columns` of the following frames (`None`: whole
    /// frames). Only planar 4:2:0 video is converted by columns; other formats
    /// always whole.
    pub(super) fn set_columns(
        &mut self,
        columns: Option<Range<usize>>,
    ) -> Result<(), FootageError> {
        self.band = None;
        let Some(columns) = columns else {
            return Ok(());
        };
        let format = self.decoder.format();
        if !matches!(
            format,
            Pixel::YUV420P | Pixel::YUVJ420P | Pixel::YUV420P10LE
        ) {
            return Ok(());
        }
        let shown_width = self.size().0;
        let shown = columns.start.min(shown_width)..columns.end.min(shown_width);
        if shown.is_empty() {
            return Ok(());
        }
        let (columns, rows) = match &self.map {
            Some(map) => map.stored_rect(shown.clone()),
            None => (shown.clone(), 0..self.height),
        };
        // Even bounds: a chroma sample covers two columns and two rows.
        let even = |r: Range<usize>, size: usize| (r.start & !1)..((r.end + 1).min(size) & !1);
        let (columns, rows) = (even(columns, self.width), even(rows, self.height));
        if columns.is_empty() || rows.is_empty() {
            return Ok(());
        }
        let context = self.bgr_context(columns.len(), rows.len())?;
        self.band = Some(Band {
            shown,
            columns,
            rows,
            context,
        });
        Ok(())
    }

    /// Decode the next frame; its presentation time [s from the stream's start]
    /// if it has one. `None` at the end of the stream.
    pub(super) fn next(&mut self) -> Result<Option<Option<f64>>, FootageError> {
        if self.pending {
            self.pending = false;
            return Ok(Some(self.time()));
        }
        if self.receive()? {
            Ok(Some(self.time()))
        } else {
            Ok(None)
        }
    }

    /// Every frame's timestamp [s from the stream's start, playback clock] in
    /// display order, and whether the frame is a key frame, read from the
    /// container's packets without decoding them; `None` when a packet carries
    /// no presentation timestamp. The stream is rewound to its first frame.
    pub(super) fn packet_stamps(&mut self) -> Result<Option<Vec<(f64, bool)>>, FootageError> {
        // SAFETY: the format context is open and owned by `self.input`.
        let ret = unsafe {
            ffi::av_seek_frame(
                self.input.as_mut_ptr(),
                self.stream as i32,
                self.start,
                ffi::AVSEEK_FLAG_BACKWARD,
            )
        };
        if ret < 0 {
            return Err(self.error(format!(
                "cannot rewind to read the packets' timestamps: {}",
                ff::Error::from(ret)
            )));
        }
        let mut stamps = Vec::with_capacity(self.frames.unwrap_or(0));
        let mut complete = true;
        for (stream, packet) in self.input.packets() {
            if stream.index() != self.stream {
                continue;
            }
            match packet.pts() {
                Some(pts) => {
                    stamps.push(((pts - self.start) as f64 * self.time_base, packet.is_key()))
                }
                None => complete = false,
            }
        }
        stamps.sort_by(|a, b| a.0.total_cmp(&b.0));
        self.seek(0)?;
        Ok(complete.then_some(stamps))
    }

    /// Position the stream so that [`Self::next`] returns the frame at `index`
    /// (counted from 0 at the container's frame rate).
    pub(super) fn seek(&mut self, index: usize) -> Result<(), FootageError> {
        let fps = self.fps.unwrap_or(1.0);
        // Half a frame early: frames whose timestamp rounds to the target count.
        self.seek_time(index as f64 / fps, 0.5 / fps, &format!("frame {index}"))
    }

    /// Position the stream so that [`Self::next`] returns the first frame whose
    /// timestamp is at or after `time_s` [s from the stream's start] less
    /// `early_s` \[s\]; `what` names the target in an error.
    pub(super) fn seek_time(
        &mut self,
        time_s: f64,
        early_s: f64,
        what: &str,
    ) -> Result<(), FootageError> {
        let fps = self.fps.unwrap_or(1.0);
        let target = self.start + (time_s / self.time_base).round() as i64;
        let tolerance = (early_s / self.time_base).floor().min(i64::MAX as f64) as i64;
        // Frames more than REORDER_MARGIN before the target cannot be lent out
        // (in decoding order they may stand that far from their display place).
        let margin = (REORDER_MARGIN as f64 / fps / self.time_base).ceil() as i64;
        let mut seek_to = target;
        let landed = loop {
            // SAFETY: the format context is open and owned by `self.input`.
            let ret = unsafe {
                ffi::av_seek_frame(
                    self.input.as_mut_ptr(),
                    self.stream as i32,
                    seek_to,
                    ffi::AVSEEK_FLAG_BACKWARD,
                )
            };
            if ret < 0 {
                return Err(self.error(format!("cannot seek to {what}: {}", ff::Error::from(ret))));
            }
            self.decoder.flush();
            self.eof_sent = false;
            self.pending = false;
            self.skip_before = Some(target - margin);
            let mut first = None;
            let mut landed = false;
            while self.receive()? {
                let ts = self.yuv.timestamp().unwrap_or(target);
                first.get_or_insert(ts);
                if ts >= target - tolerance {
                    landed = true;
                    break;
                }
            }
            // An MP4's index holds decoding times: a key frame decoded before the
            // target may be shown after it, with the frames shown before it (an
            // open GOP's B-frames) decoded after it but not decodable from it. The
            // seek then lands past the target: go back further.
            let overshot = first.is_some_and(|ts| ts > target + tolerance);
            if !overshot || seek_to <= self.start {
                break landed;
            }
            seek_to = (seek_to - margin).max(self.start);
        };
        self.skip_before = None;
        self.decoder.skip_frame(ff::Discard::Default);
        self.pending = landed;
        Ok(())
    }

    /// The current displayed frame in BGR (rows `3 ·` displayed width apart): the
    /// columns set by [`Self::set_columns`], or all.
    pub(super) fn bgr(&mut self) -> Result<&[u8], FootageError> {
        self.check_decoded()?;
        match &mut self.band {
            Some(band) => {
                let path = &self.path;
                let origin = (band.columns.start, band.rows.start);
                let sample_bytes = if self.signal.bit_depth > 8 { 2 } else { 1 };
                convert(
                    &mut band.context,
                    &self.yuv,
                    origin,
                    sample_bytes,
                    &mut self.bgr,
                    self.width,
                )
                .map_err(|e| FootageError::unreadable(path, format!("libswscale: {e}")))?;
                if let Some(map) = &self.map {
                    map.copy_columns(&self.bgr, &mut self.shown, band.shown.clone());
                }
            }
            None => self.convert_whole()?,
        }
        Ok(self.displayed())
    }

    /// The current displayed frame in BGR, every column.
    pub(super) fn bgr_whole(&mut self) -> Result<&[u8], FootageError> {
        self.convert_whole()?;
        Ok(self.displayed())
    }

    /// The displayed frame's buffer: the stored one unless a display matrix turns it.
    fn displayed(&self) -> &[u8] {
        if self.map.is_some() {
            &self.shown
        } else {
            &self.bgr[..3 * self.width * self.height]
        }
    }

    fn convert_whole(&mut self) -> Result<(), FootageError> {
        self.check_decoded()?;
        if self.whole.is_none() {
            self.whole = Some(self.bgr_context(self.width, self.height)?);
        }
        let context = self.whole.as_mut().expect("just made");
        convert(context, &self.yuv, (0, 0), 1, &mut self.bgr, self.width)
            .map_err(|e| FootageError::unreadable(&self.path, format!("libswscale: {e}")))?;
        if let Some(map) = &self.map {
            map.copy_columns(&self.bgr, &mut self.shown, 0..map.displayed.0);
        }
        Ok(())
    }

    /// Decode until a frame is out (true) or the stream has ended (false).
    fn receive(&mut self) -> Result<bool, FootageError> {
        loop {
            match self.decoder.receive_frame(&mut self.yuv) {
                Ok(()) => {
                    if (self.yuv.width() as usize, self.yuv.height() as usize)
                        != (self.width, self.height)
                    {
                        return Err(self.error(format!(
                            "a frame of {} x {} px in a {} x {} px stream",
                            self.yuv.width(),
                            self.yuv.height(),
                            self.width,
                            self.height
                        )));
                    }
                    return Ok(true);
                }
                Err(ff::Error::Eof) => return Ok(false),
                Err(ff::Error::Other { errno }) if errno == ffi::EAGAIN => {}
                Err(e) => return Err(self.error(format!("decoding failed: {e}"))),
            }
            if self.eof_sent {
                return Ok(false);
            }
            let mut packet = ff::Packet::empty();
            match packet.read(&mut self.input) {
                Ok(()) if packet.stream() == self.stream => {
                    if let Some(limit) = self.skip_before {
                        let early = packet.pts().is_some_and(|pts| pts < limit);
                        self.decoder.skip_frame(if early {
                            ff::Discard::NonReference
                        } else {
                            ff::Discard::Default
                        });
                    }
                    // A corrupt packet is skipped, as FFmpeg's own tools do; a
                    // stream that ends early is caught by the frame count.
                    let _ = self.decoder.send_packet(&packet);
                }
                Ok(()) => {}
                Err(ff::Error::Eof) => {
                    self.decoder
                        .send_eof()
                        .map_err(|e| self.error(format!("decoding failed: {e}")))?;
                    self.eof_sent = true;
                }
                Err(e) => return Err(self.error(format!("reading failed: {e}"))),
            }
        }
    }

    /// A frame must be at hand (not before the first, not after the last).
    fn check_decoded(&self) -> Result<(), FootageError> {
        // SAFETY: `yuv` is an allocated AVFrame; its plane pointers are only read.
        let empty = unsafe { (*self.yuv.as_ptr()).data[0].is_null() };
        if empty {
            Err(self.error("no decoded frame at hand".into()))
        } else {
            Ok(())
        }
    }

    /// How the codec coded the frame at hand: 'I' (intra), 'P' (predicted from
    /// earlier pictures), 'B' (from pictures on both sides), or another of
    /// libavutil's letters (S, i, p, b); `None` when the decoder does not say.
    pub(super) fn picture_type(&self) -> Option<char> {
        use ff::picture::Type;
        match self.yuv.kind() {
            Type::None => None,
            Type::I => Some('I'),
            Type::P => Some('P'),
            Type::B => Some('B'),
            Type::S => Some('S'),
            Type::SI => Some('i'),
            Type::SP => Some('p'),
            Type::BI => Some('b'),
        }
    }

    fn time(&self) -> Option<f64> {
        self.yuv
            .timestamp()
            .map(|ts| (ts - self.start) as f64 * self.time_base)
    }

    fn error(&self, reason: String) -> FootageError {
        FootageError::unreadable(&self.path, reason)
    }
}

/// Convert the rectangle `w × h` at column `x0`, row `y0` of `yuv` (w, h: the
/// context's input size; planar samples of `sample_bytes` each) into the same
/// place of the BGR buffer `bgr` (`3 · width` bytes a row).
fn convert(
    context: &mut scaling::Context,
    yuv: &ff::frame::Video,
    (x0, y0): (usize, usize),
    sample_bytes: usize,
    bgr: &mut [u8],
    width: usize,
) -> Result<(), ff::Error> {
    let input = context.input();
    let (w, h) = (input.width as usize, input.height as usize);
    assert!(x0 + w <= width && bgr.len() >= 3 * width * (y0 + h));
    // SAFETY: the source planes are the decoded frame's (x0 and y0 are even, so
    // the chroma offsets x0 / 2, y0 / 2 address the sample of columns x0, x0 + 1
    // and rows y0, y0 + 1, and whole frames use x0 = y0 = 0); the destination
    // columns x0..x0 + w of rows y0..y0 + h fit in `bgr`, as asserted.
    let ret = unsafe {
        let frame = yuv.as_ptr();
        let planes = (*frame).data;
        let lines = (*frame).linesize;
        let at = |i: usize, x: usize, y: usize| {
            let p = planes[i];
            if p.is_null() {
                p
            } else {
                p.offset(y as isize * lines[i] as isize + (x * sample_bytes) as isize)
            }
        };
        let src = [
            at(0, x0, y0),
            at(1, x0 / 2, y0 / 2),
            at(2, x0 / 2, y0 / 2),
            planes[3],
        ];
        let dst = [
            bgr.as_mut_ptr().add(3 * (y0 * width + x0)),
            std::ptr::null_mut(),
            std::ptr::null_mut(),
            std::ptr::null_mut(),
        ];
        let dst_stride = [(3 * width) as i32, 0, 0, 0];
        ffi::sws_scale(
            context.as_mut_ptr(),
            src.as_ptr().cast(),
            (*frame).linesize.as_ptr(),
            0,
            h as i32,
            dst.as_ptr(),
            dst_stride.as_ptr(),
        )
    };
    if ret < 0 {
        Err(ff::Error::from(ret))
    } else {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use opencv::core::Mat;
    use opencv::prelude::*;
    use opencv::videoio;

    /// The committed dark-plate fixture: H.264 (x264's 250-frame GOPs), 480×320.
    fn fixture() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/side-dark-n050.mp4")
    }

    /// Every frame as OpenCV's `VideoCapture::read` gives it (BGR bytes).
    fn opencv_frames(path: &Path) -> Vec<Vec<u8>> {
        let mut capture =
            videoio::VideoCapture::from_file(path.to_str().unwrap(), videoio::CAP_FFMPEG).unwrap();
        let mut frame = Mat::default();
        let mut frames = Vec::new();
        while capture.read(&mut frame).unwrap() && !frame.empty() {
            frames.push(frame.data_bytes().unwrap().to_vec());
        }
        frames
    }

    #[test]
    fn whole_frames_and_bands_are_the_bytes_opencv_decodes() {
        let path = fixture();
        let reference = opencv_frames(&path);
        let mut whole = VideoDecoder::open(&path).unwrap();
        let mut banded = VideoDecoder::open(&path).unwrap();
        let (width, _) = banded.size();
        // An odd start and width: widened to even columns, still the same bytes.
        let band = 233..240;
        banded.set_columns(Some(band.clone())).unwrap();
        assert_eq!(whole.frame_count(), Some(reference.len()));
        for (index, expected) in reference.iter().enumerate() {
            whole.next().unwrap().expect("frame");
            assert!(whole.bgr().unwrap() == expected.as_slice(), "frame {index}");
            banded.next().unwrap().expect("frame");
            let got = banded.bgr().unwrap();
            for (row, (a, b)) in got
                .chunks(3 * width)
                .zip(expected.chunks(3 * width))
                .enumerate()
            {
                let columns = 3 * band.start..3 * band.end;
                assert!(a[columns.clone()] == b[columns], "frame {index}, row {row}");
            }
        }
        assert!(whole.next().unwrap().is_none(), "no frame after the last");
    }

    #[test]
    fn no_frame_is_lent_before_the_first_or_after_the_last() {
        let mut decoder = VideoDecoder::open(&fixture()).unwrap();
        assert!(decoder.bgr_whole().is_err(), "before the first frame");
        while decoder.next().unwrap().is_some() {}
        assert!(decoder.bgr().is_err(), "after the last frame");
    }

    #[test]
    fn a_seek_lands_on_the_frame_asked_for() {
        let path = fixture();
        let reference = opencv_frames(&path);
        let last = reference.len() - 1;
        let mut decoder = VideoDecoder::open(&path).unwrap();
        let fps = decoder.fps().unwrap();
        // Just after a key frame, before one, the last frames, and back to the start.
        for index in [260, 7, last - 4, last, 0] {
            assert_seek_lands(&mut decoder, index, fps, &reference[index]);
        }
    }

    /// A seek to frame `index` gives that frame next: its time at `fps` and the
    /// bytes OpenCV decodes for it.
    fn assert_seek_lands(decoder: &mut VideoDecoder, index: usize, fps: f64, expected: &[u8]) {
        decoder.seek(index).unwrap();
        let t = decoder.next().unwrap().expect("frame").unwrap();
        assert!(
            (t - index as f64 / fps).abs() < 1e-9,
            "frame {index}: t = {t}"
        );
        assert!(decoder.bgr_whole().unwrap() == expected, "frame {index}");
    }

    /// The presentation times of the stream's packets in decoding order, each
    /// with its key-frame flag.
    fn packets_in_decoding_order(path: &Path) -> Vec<(i64, bool)> {
        let mut input = ff::format::input(path).unwrap();
        let stream = input
            .streams()
            .best(ff::media::Type::Video)
            .unwrap()
            .index();
        input
            .packets()
            .filter(|(s, _)| s.index() == stream)
            .map(|(_, p)| (p.pts().unwrap(), p.is_key()))
            .collect()
    }

    /// An open GOP (`scripts/make-fixtures`' fixture `side-dark-open-gop.mp4`): the
    /// key frame 250 is decoded before frames 247–249, which are shown before it
    /// and reference the frames before it. The MP4's index holds decoding times,
    /// so a seek to any of those three finds that key frame first, and from it
    /// their own pictures cannot be decoded; the seek must go back further.
    #[test]
    fn a_seek_lands_before_an_open_gops_key_frame() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/side-dark-open-gop.mp4");
        let packets = packets_in_decoding_order(&path);
        let open: Vec<i64> = packets
            .iter()
            .enumerate()
            .filter(|&(i, &(pts, key))| key && packets[i + 1..].iter().any(|p| p.0 < pts))
            .map(|(_, p)| p.0)
            .collect();
        assert!(!open.is_empty(), "the fixture has no open GOP");
        let reference = opencv_frames(&path);
        let mut decoder = VideoDecoder::open(&path).unwrap();
        let fps = decoder.fps().unwrap();
        for &key_pts in &open {
            let key = ((key_pts - decoder.start) as f64 * decoder.time_base * fps).round() as usize;
            for (index, expected) in reference.iter().enumerate().take(key + 1).skip(key - 3) {
                assert_seek_lands(&mut decoder, index, fps, expected);
            }
        }
    }
}
