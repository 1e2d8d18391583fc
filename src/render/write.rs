//! Writing a rendered clip: an H.264 MP4 through FFmpeg's libavcodec (libx264 at a
//! chosen crf, one encoder thread, so the bytes are reproducible) or a folder of PNG
//! frames `frame_000001.png …`, plus the ground truth as `<clip stem>.truth.json`
//! beside it. An MP4 stamps written frame k at k / fps, or, for a jittered capture
//! or a slowed section, each frame at the container time its truth gives, on a
//! clock of [`TICKS_PER_FRAME`] ticks a frame.
//!
//! Both are written under a temporary name in the destination folder and renamed into
//! place when complete, so an interrupted run never leaves a clip that looks finished.

use std::path::{Path, PathBuf};

use ff::ffi;
use ff::format::Pixel;
use ff::software::scaling;
use ffmpeg_next as ff;
use rayon::prelude::*;

use super::{RenderError, Renderer, TICKS_PER_FRAME};
use crate::footage::Orientation;
use crate::output::{write_json, write_through_temporary};

/// Container of a written clip.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ClipFormat {
    /// MP4 video (H.264, libx264).
    Mp4,
    /// A folder of PNG frames.
    PngFolder,
}

impl ClipFormat {
    /// MP4 for a path ending in `.mp4` (any case), a PNG folder otherwise.
    pub fn for_path(path: &Path) -> Self {
        match path.extension().and_then(|e| e.to_str()) {
            Some(ext) if ext.eq_ignore_ascii_case("mp4") => ClipFormat::Mp4,
            _ => ClipFormat::PngFolder,
        }
    }
}

/// How an MP4 stores its samples (issue 14 §4): phones write 8-bit limited range,
/// full range, or 10-bit HDR with a BT.2020 matrix and the HLG or PQ transfer
/// function. The samples always encode the rendered grey levels (an HDR tag is a
/// tag: no tone curve is applied), so every storage shows one scene.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SampleStorage {
    /// 10-bit samples (`yuv420p10le`) rather than 8-bit (`yuv420p`).
    pub ten_bit: bool,
    /// Full range (JPEG style, `color_range = pc`) rather than limited.
    pub full_range: bool,
    /// An HDR transfer function to tag, with BT.2020 primaries and matrix.
    pub hdr: Option<HdrTransfer>,
}

/// The HDR transfer functions phones record with.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "snake_case")]
pub enum HdrTransfer {
    /// Hybrid log-gamma (ARIB STD-B67).
    Hlg,
    /// Perceptual quantiser (SMPTE ST 2084).
    Pq,
}

/// What [`write_clip`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct WrittenClip {
    /// The clip (file or folder).
    pub clip: PathBuf,
    /// The ground-truth JSON.
    pub truth: PathBuf,
    /// Frames written.
    pub frames: usize,
    /// The fourcc of an MP4's codec (`avc1`).
    pub codec: Option<String>,
}

/// The ground-truth file of a clip: `clip.mp4` → `clip.truth.json`, `clip/` →
/// `clip.truth.json`.
pub fn truth_path(clip: &Path) -> PathBuf {
    let stem = clip
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "clip".to_owned());
    clip.with_file_name(format!("{stem}.truth.json"))
}

/// Frames rendered in parallel before they are written in order.
const BATCH: usize = 16;

/// Threads of the H.264 encoder: one, so the bytes depend on the frames and the
/// crf only (see [`write_mp4`]).
const X264_THREADS: usize = 1;

/// The H.264 constant-rate factor of `eulerdisk render` by default: libx264's
/// default and what OpenCV's `VideoWriter` wrote before (lower is better quality;
/// 0 is lossless in luma, 51 the worst).
pub const DEFAULT_CRF: u8 = 23;

/// How `render` encodes an MP4 clip: libx264's quality and its pictures' structure.
///
/// libx264's defaults (an I picture at most every 250 frames, up to 3 B pictures in
/// a row, placed adaptively) code three quarters of a slow-motion clip as B
/// pictures, predicted from both sides, and keep one I picture per half second at
/// 480 fps. Phones and other encoders' settings code differently: clips may hold
/// 5–27 I pictures in 768 frames and 81–91 % P pictures in their side views, and a
/// phone's hardware encoder often writes none but I and P. The two structures lose a
/// moving edge differently, so a render can draw either.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ClipEncoding {
    /// Constant-rate factor (0 lossless in luma, 23 libx264's default, 51 the worst).
    pub crf: u8,
    /// Most frames from one I picture to the next (libx264's `keyint`); `None` its
    /// default, 250.
    pub keyint: Option<u32>,
    /// Most B pictures in a row (libx264's `bframes`); 0 codes I and P pictures only,
    /// `None` its default, 3.
    pub bframes: Option<u32>,
}

impl ClipEncoding {
    /// libx264's picture structure at constant-rate factor `crf`.
    pub const fn crf(crf: u8) -> Self {
        Self {
            crf,
            keyint: None,
            bframes: None,
        }
    }
}

/// `render`'s encoding by default: [`DEFAULT_CRF`] and libx264's picture structure.
pub const DEFAULT_ENCODING: ClipEncoding = ClipEncoding::crf(DEFAULT_CRF);

/// Renders every frame of `renderer` and writes the clip and its truth to `path`
/// (MP4 if it ends in `.mp4`, H.264 as `encoding` says, else a PNG folder, where
/// `encoding` is unused). An existing clip at `path` is replaced only after the new
/// one is complete. The same renderer and encoding always give the same bytes.
pub fn write_clip(
    renderer: &Renderer,
    path: &Path,
    encoding: ClipEncoding,
) -> Result<WrittenClip, RenderError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let fail = |p: &Path, reason: String| RenderError::Write {
        path: p.to_path_buf(),
        reason,
    };
    std::fs::create_dir_all(&dir).map_err(|e| fail(path, e.to_string()))?;
    let name = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .ok_or_else(|| fail(path, "the output path has no file name".into()))?;
    let codec = match ClipFormat::for_path(path) {
        ClipFormat::Mp4 => Some(write_through_temporary(path, |tmp| {
            write_mp4(renderer, tmp, encoding).map_err(|reason| fail(path, reason))
        })?),
        ClipFormat::PngFolder if renderer.truth().storage != SampleStorage::default() => {
            return Err(fail(
                path,
                "10-bit, full-range and HDR storage apply to an MP4 only: give a path \
                 ending in .mp4"
                    .into(),
            ));
        }
        ClipFormat::PngFolder if renderer.truth().stamped => {
            return Err(fail(
                path,
                "per-frame timestamps (a jitter, a slowed section) are written into an MP4 \
                 only: give a path ending in .mp4"
                    .into(),
            ));
        }
        ClipFormat::PngFolder if !renderer.truth().display_orientation.is_identity() => {
            return Err(fail(
                path,
                "a display matrix (rotation tag) is written into an MP4 only: give a path \
                 ending in .mp4"
                    .into(),
            ));
        }
        ClipFormat::PngFolder => {
            // 0777 less the umask, as any folder the user makes (not tempfile's 0700).
            let tmp = tempfile::Builder::new()
                .prefix(&format!(".{name}.partial-"))
                .permissions(std::os::unix::fs::PermissionsExt::from_mode(0o777))
                .tempdir_in(&dir)
                .map_err(|e| fail(path, e.to_string()))?;
            write_pngs(renderer, tmp.path()).map_err(|(p, reason)| fail(&p, reason))?;
            let staged = tmp.keep();
            if path.exists() {
                let old = dir.join(format!(".{name}.replaced-{}", std::process::id()));
                std::fs::rename(path, &old).map_err(|e| fail(path, e.to_string()))?;
                std::fs::rename(&staged, path).map_err(|e| fail(path, e.to_string()))?;
                std::fs::remove_dir_all(&old).map_err(|e| fail(&old, e.to_string()))?;
            } else {
                std::fs::rename(&staged, path).map_err(|e| fail(path, e.to_string()))?;
            }
            None
        }
    };
    let truth = truth_path(path);
    write_json(&truth, renderer.truth()).map_err(|e| fail(&truth, e.to_string()))?;
    Ok(WrittenClip {
        clip: path.to_path_buf(),
        truth,
        frames: renderer.frame_count(),
        codec,
    })
}

fn write_pngs(renderer: &Renderer, dir: &Path) -> Result<(), (PathBuf, String)> {
    (0..renderer.frame_count())
        .into_par_iter()
        .try_for_each(|i| {
            let file = dir.join(format!("frame_{:06}.png", i + 1));
            renderer
                .render_frame(i)
                .save(&file)
                .map_err(|e| (file, e.to_string()))
        })
}

/// Encodes the frames as H.264 through [`H264Writer`] (preset `medium`, constant
/// quality and picture structure from `encoding`), rendering [`BATCH`] frames at a
/// time in parallel.
fn write_mp4(renderer: &Renderer, path: &Path, encoding: ClipEncoding) -> Result<String, String> {
    let truth = renderer.truth();
    let settings = H264Settings {
        rate: RateControl::Crf(encoding.crf),
        keyint: encoding.keyint,
        bframes: encoding.bframes,
        preset: "medium",
        chroma: ChromaFilter::Bicubic,
        storage: truth.storage,
        orientation: truth.display_orientation,
    };
    let ticks_per_frame = if truth.stamped { TICKS_PER_FRAME } else { 1 };
    let mut writer = H264Writer::create_with_clock(
        path,
        truth.width,
        truth.height,
        truth.fps,
        ticks_per_frame,
        settings,
    )?;
    let tick_s = 1.0 / (truth.fps * f64::from(ticks_per_frame));
    let n = renderer.frame_count();
    for start in (0..n).step_by(BATCH) {
        let images: Vec<_> = (start..(start + BATCH).min(n))
            .into_par_iter()
            .map(|i| renderer.render_frame(i))
            .collect();
        for (i, image) in (start..).zip(&images) {
            match truth.frames[i].container_time_s {
                Some(t) => writer.push_at(image, (t / tick_s).round() as i64)?,
                None => writer.push(image)?,
            }
        }
    }
    writer.finish()?;
    Ok("avc1".to_owned())
}

/// How [`H264Writer`] encodes: libx264's rate control and preset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct H264Settings {
    pub rate: RateControl,
    /// Most frames from one I picture to the next; `None` libx264's default.
    pub keyint: Option<u32>,
    /// Most B pictures in a row; `None` libx264's default.
    pub bframes: Option<u32>,
    /// libx264 preset (`ultrafast` … `veryslow`): speed against size at equal quality.
    pub preset: &'static str,
    /// How colour is subsampled to 4:2:0 (libswscale's filter).
    pub chroma: ChromaFilter,
    /// Bit depth, range and HDR transfer of the stored samples.
    pub storage: SampleStorage,
    /// The display orientation the stream declares (a rotation tag).
    pub orientation: Orientation,
}

/// How libx264 chooses each frame's quantiser.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RateControl {
    /// Constant-rate factor (0 lossless in luma, 23 libx264's default, 51 the
    /// worst): the quantiser follows each frame's complexity, which x264
    /// estimates on a half-size copy of every frame.
    Crf(u8),
    /// Constant quantiser (P frames at this QP, I frames a little finer): no
    /// complexity estimate, which at the `ultrafast` preset is 30 to 40 % of
    /// x264's time on the overlays' small frames.
    Qp(u8),
}

/// libswscale's filter for the RGB → YUV 4:2:0 conversion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChromaFilter {
    /// Bicubic: what OpenCV's writer used, kept so rendered clips keep their bytes.
    Bicubic,
    /// Fast bilinear: about half the conversion time, for pictures that are
    /// looked at rather than measured.
    FastBilinear,
}

/// An H.264 MP4 being written frame by frame: libx264 through libavcodec, yuv420p,
/// constant quality, with two settings that make the bytes a function of the
/// frames and the settings alone:
///
/// - `mbtree=0`: x264's macroblock-tree rate control (on by default, and in
///   OpenCV's writer) reads heap memory it has not initialised. Identical YUV
///   input gave different bitstreams for the second and later clips encoded in one
///   process, or for different `MALLOC_PERTURB_` fillings, and identical ones with
///   the tree off. This is why two runs of `eulerdisk demo` (nine clips in one
///   process) wrote different MP4s, while separate `render` processes agreed.
/// - one encoder thread ([`X264_THREADS`]): x264's output depends on its thread
///   count, which by default follows the machine's cores.
///
/// Used by `render` (clips) and by the overlays of `analyse` and `compare`.
pub struct H264Writer {
    output: ff::format::context::Output,
    encoder: ff::encoder::Video,
    scaler: scaling::Context,
    rgb: ff::frame::Video,
    yuv: ff::frame::Video,
    packet: ff::Packet,
    time_base: ff::Rational,
    stream_time_base: ff::Rational,
    /// The displayed frame's size, which `push` takes.
    width: u32,
    height: u32,
    /// How a displayed frame is stored (turned the other way under a display
    /// matrix, or as it is).
    orientation: Orientation,
    stored: (usize, usize),
    frames: i64,
    /// Timestamp ticks per frame at the nominal fps (1 unless stamped one by one).
    ticks_per_frame: i64,
}

fn av(what: &'static str) -> impl Fn(ff::Error) -> String {
    move |e| format!("FFmpeg: {what}: {e}")
}

impl H264Writer {
    /// Opens `path` for a `width` × `height` clip (as displayed) played at `fps`
    /// frames/s. With a display orientation (`settings.orientation`, a rotation
    /// tag), each frame is stored turned the other way and the stream carries the
    /// display matrix that turns it back, as a phone's MP4 does; with
    /// `settings.storage`, 10-bit samples, full range and an HDR transfer's tags.
    ///
    /// # Errors
    /// An odd frame size (4:2:0 needs even sizes), no libx264 in this FFmpeg, or
    /// FFmpeg failing to open the file or the encoder (the reason, without the path).
    pub fn create(
        path: &Path,
        width: u32,
        height: u32,
        fps: f64,
        settings: H264Settings,
    ) -> Result<Self, String> {
        Self::create_with_clock(path, width, height, fps, 1, settings)
    }

    /// [`Self::create`] with timestamps counted in ticks of 1 / (fps ·
    /// `ticks_per_frame`) s, for frames stamped one by one ([`Self::push_at`]: a
    /// variable frame rate, a slowed section).
    ///
    /// # Errors
    /// As [`Self::create`].
    pub fn create_with_clock(
        path: &Path,
        width: u32,
        height: u32,
        fps: f64,
        ticks_per_frame: u32,
        settings: H264Settings,
    ) -> Result<Self, String> {
        let orientation = settings.orientation;
        let stored = orientation.stored_size((width as usize, height as usize));
        let (w, h) = (stored.0 as u32, stored.1 as u32);
        if w % 2 == 1 || h % 2 == 1 {
            return Err(format!(
                "H.264 (4:2:0) needs an even frame size, got {w} × {h}: render a PNG folder or an even size"
            ));
        }
        ff::init().map_err(av("init"))?;
        ff::util::log::set_level(ff::util::log::Level::Quiet);
        let codec = ff::encoder::find_by_name("libx264").ok_or_else(|| {
            "this FFmpeg (libavcodec) has no libx264 encoder; render a PNG folder instead"
                .to_owned()
        })?;
        let mut output = ff::format::output_as(path, "mp4").map_err(av("open the MP4"))?;
        let global_header = output
            .format()
            .flags()
            .contains(ff::format::Flags::GLOBAL_HEADER);
        let format = StoredFormat {
            width: w,
            height: h,
            pixel: if settings.storage.ten_bit {
                Pixel::YUV420P10LE
            } else {
                Pixel::YUV420P
            },
            clock: Clock::new(fps, ticks_per_frame)?,
        };
        let encoder = open_encoder(codec, &format, global_header, &settings)?;
        let stream_time_base = start_mp4(&mut output, codec, &encoder, &format, orientation)?;
        let scaler = yuv_scaler(&format, &settings)?;
        Ok(Self {
            output,
            encoder,
            scaler,
            rgb: ff::frame::Video::new(Pixel::RGB24, w, h),
            yuv: ff::frame::Video::new(format.pixel, w, h),
            packet: ff::Packet::empty(),
            time_base: format.clock.time_base,
            stream_time_base,
            width,
            height,
            orientation,
            stored,
            frames: 0,
            ticks_per_frame: i64::from(ticks_per_frame),
        })
    }

    /// Encodes the next frame, stamped a nominal frame interval after the last.
    ///
    /// # Errors
    /// A frame of another size than the clip's, or FFmpeg failing to encode or write.
    pub fn push(&mut self, image: &image::RgbImage) -> Result<(), String> {
        self.push_at(image, self.frames * self.ticks_per_frame)
    }

    /// Encodes the next frame with timestamp `pts` [ticks of the clock set at
    /// [`Self::create_with_clock`], increasing frame by frame].
    ///
    /// # Errors
    /// As [`Self::push`].
    pub fn push_at(&mut self, image: &image::RgbImage, pts: i64) -> Result<(), String> {
        if image.dimensions() != (self.width, self.height) {
            let (w, h) = image.dimensions();
            return Err(format!(
                "frame {} is {w} × {h} px, the clip {} × {} px",
                self.frames, self.width, self.height
            ));
        }
        let row = 3 * self.width as usize;
        let stride = self.rgb.stride(0);
        if self.orientation.is_identity() {
            for (dst, src) in self
                .rgb
                .data_mut(0)
                .chunks_mut(stride)
                .zip(image.as_raw().chunks_exact(row))
            {
                dst[..row].copy_from_slice(src);
            }
        } else {
            let map = self.orientation.displayed_from_stored(self.stored);
            let data = self.rgb.data_mut(0);
            for q in 0..self.stored.1 {
                for p in 0..self.stored.0 {
                    let (x, y) = map.displayed(p, q);
                    let at = q * stride + 3 * p;
                    data[at..at + 3].copy_from_slice(&image.get_pixel(x as u32, y as u32).0);
                }
            }
        }
        self.scaler
            .run(&self.rgb, &mut self.yuv)
            .map_err(av("libswscale"))?;
        self.yuv.set_pts(Some(pts));
        self.frames += 1;
        self.encoder
            .send_frame(&self.yuv)
            .map_err(av("encode a frame"))?;
        self.drain()
    }

    /// Writes the packets the encoder has ready.
    fn drain(&mut self) -> Result<(), String> {
        while self.encoder.receive_packet(&mut self.packet).is_ok() {
            self.packet.set_stream(0);
            // One nominal frame each: without a duration the MP4's edit list ends
            // at the last frame's start and decoders drop that frame (the muxer
            // takes the others' durations from the next frame's timestamp).
            self.packet.set_duration(self.ticks_per_frame);
            self.packet
                .rescale_ts(self.time_base, self.stream_time_base);
            self.packet
                .write_interleaved(&mut self.output)
                .map_err(av("write a packet"))?;
        }
        Ok(())
    }

    /// Flushes the encoder and writes the MP4's trailer; returns the frames written.
    ///
    /// # Errors
    /// FFmpeg failing to flush or to write the trailer.
    pub fn finish(mut self) -> Result<usize, String> {
        self.encoder.send_eof().map_err(av("flush the encoder"))?;
        self.drain()?;
        self.output
            .write_trailer()
            .map_err(av("write the MP4 trailer"))?;
        Ok(self.frames as usize)
    }

    /// Encodes the next frame from 8-bit 4:2:0 samples already in the clip's
    /// storage (its range, the BT.601 matrix; Y at the frame's size, U and V at
    /// half of it, rows packed), without [`Self::push`]'s conversion from RGB:
    /// for the overlays, which convert their canvas themselves. Upright 8-bit
    /// clips only.
    ///
    /// # Errors
    /// Planes of another size, a turned or 10-bit clip, or FFmpeg failing to
    /// encode or write.
    pub fn push_yuv420(&mut self, planes: [&[u8]; 3]) -> Result<(), String> {
        let (w, h) = (self.width as usize, self.height as usize);
        if !self.orientation.is_identity() || self.yuv.format() != Pixel::YUV420P {
            return Err("only an upright 8-bit clip takes 4:2:0 samples".into());
        }
        for (k, plane) in planes.into_iter().enumerate() {
            let (pw, ph) = if k == 0 { (w, h) } else { (w / 2, h / 2) };
            if plane.len() != pw * ph {
                return Err(format!(
                    "frame {}: plane {k} holds {} samples, the clip's {pw} × {ph}",
                    self.frames,
                    plane.len()
                ));
            }
            let stride = self.yuv.stride(k);
            for (dst, src) in self
                .yuv
                .data_mut(k)
                .chunks_mut(stride)
                .zip(plane.chunks_exact(pw))
            {
                dst[..pw].copy_from_slice(src);
            }
        }
        self.yuv.set_pts(Some(self.frames));
        self.frames += 1;
        self.encoder
            .send_frame(&self.yuv)
            .map_err(av("encode a frame"))?;
        self.drain()
    }
}

/// A clip's clock: its nominal frame rate, and the time base its timestamps count
/// in, `ticks_per_frame` ticks a frame.
#[derive(Clone, Copy)]
struct Clock {
    rate: ff::Rational,
    time_base: ff::Rational,
}

impl Clock {
    /// # Errors
    /// `ticks_per_frame` ticks a frame at `fps` overflow FFmpeg's 32-bit rationals.
    fn new(fps: f64, ticks_per_frame: u32) -> Result<Self, String> {
        let rate = ff::Rational::from(fps);
        let ticks = i32::try_from(ticks_per_frame)
            .ok()
            .and_then(|t| rate.numerator().checked_mul(t))
            .ok_or_else(|| format!("{ticks_per_frame} ticks a frame at {fps} fps overflow"))?;
        Ok(Clock {
            rate,
            time_base: ff::Rational::new(rate.denominator(), ticks),
        })
    }
}

/// How the frames are stored in the stream: their size (turned under a display
/// orientation), 4:2:0 pixel format (8 or 10 bits) and clock.
struct StoredFormat {
    width: u32,
    height: u32,
    pixel: Pixel,
    clock: Clock,
}

/// Opens libx264 for `format` with the settings' range, HDR tags, preset and
/// rate control, and the options that make its bytes reproducible (see
/// [`H264Writer`]: `mbtree=0`, [`X264_THREADS`]).
fn open_encoder(
    codec: ff::Codec,
    format: &StoredFormat,
    global_header: bool,
    settings: &H264Settings,
) -> Result<ff::encoder::Video, String> {
    let storage = settings.storage;
    let mut encoder = ff::codec::context::Context::new_with_codec(codec)
        .encoder()
        .video()
        .map_err(av("encoder"))?;
    encoder.set_width(format.width);
    encoder.set_height(format.height);
    encoder.set_format(format.pixel);
    encoder.set_color_range(if storage.full_range {
        ff::color::Range::JPEG
    } else {
        ff::color::Range::MPEG
    });
    if let Some(hdr) = storage.hdr {
        encoder.set_colorspace(ff::color::Space::BT2020NCL);
        encoder.set_color_primaries(ff::color::Primaries::BT2020);
        encoder.set_color_transfer_characteristic(match hdr {
            HdrTransfer::Hlg => ff::color::TransferCharacteristic::ARIB_STD_B67,
            HdrTransfer::Pq => ff::color::TransferCharacteristic::SMPTE2084,
        });
    }
    encoder.set_time_base(format.clock.time_base);
    encoder.set_frame_rate(Some(format.clock.rate));
    if global_header {
        encoder.set_flags(ff::codec::Flags::GLOBAL_HEADER);
    }
    encoder
        .open_with(x264_options(settings))
        .map_err(av("open libx264"))
}

/// libx264's options: the preset, CRF or QP, one thread, and `x264-params` with
/// the macroblock tree off and the settings' keyframe interval and B-frames.
fn x264_options(settings: &H264Settings) -> ff::Dictionary<'static> {
    let mut options = ff::Dictionary::new();
    options.set("preset", settings.preset);
    match settings.rate {
        RateControl::Crf(crf) => options.set("crf", &crf.to_string()),
        RateControl::Qp(qp) => options.set("qp", &qp.to_string()),
    }
    options.set("threads", &X264_THREADS.to_string());
    let mut params = String::from("mbtree=0");
    if let Some(keyint) = settings.keyint {
        params += &format!(":keyint={keyint}");
    }
    if let Some(bframes) = settings.bframes {
        params += &format!(":bframes={bframes}");
    }
    options.set("x264-params", &params);
    options
}

/// Adds the video stream to `output` with the encoder's parameters, the clip's
/// time base and, under a display orientation, the display matrix that turns the
/// stored frames back; writes the header. Returns the time base the muxer kept.
fn start_mp4(
    output: &mut ff::format::context::Output,
    codec: ff::Codec,
    encoder: &ff::encoder::Video,
    format: &StoredFormat,
    orientation: Orientation,
) -> Result<ff::Rational, String> {
    let mut stream = output
        .add_stream(codec)
        .map_err(av("add the video stream"))?;
    stream.set_parameters(encoder);
    // The muxer keeps a multiple of the frame rate (480 fps: 1/15360 s) rather
    // than its default 1/90000 s, so frame times are exact.
    stream.set_time_base(format.clock.time_base);
    if !orientation.is_identity() {
        let matrix = orientation.display_matrix((format.width as usize, format.height as usize));
        // SAFETY: the stream belongs to `output`, whose header is not written
        // yet; FFmpeg allocates the 36 bytes it returns, which are filled at once.
        unsafe {
            let data = ffi::av_stream_new_side_data(
                stream.as_mut_ptr(),
                ffi::AVPacketSideDataType::AV_PKT_DATA_DISPLAYMATRIX,
                std::mem::size_of_val(&matrix),
            );
            if data.is_null() {
                return Err("FFmpeg: cannot attach the display matrix".to_owned());
            }
            std::ptr::copy_nonoverlapping(matrix.as_ptr().cast::<u8>(), data, 36);
        }
    }
    output.write_header().map_err(av("write the MP4 header"))?;
    output
        .stream(0)
        .map(|s| s.time_base())
        .ok_or_else(|| "FFmpeg: the MP4 lost its video stream".to_owned())
}

/// libswscale's RGB → YUV 4:2:0 conversion into `format`, with the settings'
/// chroma filter, and the matrix and range the stream declares (BT.601,
/// libswscale's default, when nothing is declared; BT.2020 under HDR).
fn yuv_scaler(format: &StoredFormat, settings: &H264Settings) -> Result<scaling::Context, String> {
    let (w, h) = (format.width, format.height);
    let storage = settings.storage;
    let mut scaler = scaling::Context::get(
        Pixel::RGB24,
        w,
        h,
        format.pixel,
        w,
        h,
        match settings.chroma {
            ChromaFilter::Bicubic => scaling::Flags::BICUBIC,
            ChromaFilter::FastBilinear => scaling::Flags::FAST_BILINEAR,
        },
    )
    .map_err(av("libswscale"))?;
    let matrix = if storage.hdr.is_some() {
        ffi::SWS_CS_BT2020
    } else {
        ffi::SWS_CS_DEFAULT
    };
    // SAFETY: a live SwsContext; the coefficient table is libswscale's static one.
    let ret = unsafe {
        let table = ffi::sws_getCoefficients(matrix);
        ffi::sws_setColorspaceDetails(
            scaler.as_mut_ptr(),
            table,
            1,
            table,
            i32::from(storage.full_range),
            0,
            1 << 16,
            1 << 16,
        )
    };
    if ret < 0 {
        return Err("libswscale: cannot set the matrix and range".to_owned());
    }
    Ok(scaler)
}
