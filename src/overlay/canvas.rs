//! The picture an overlay frame is drawn on: parts of a footage frame copied into
//! windows, each enlarged by a whole factor, under a header band for text; and the
//! marks drawn on it, placed in the footage's own pixel coordinates.
//!
//! Coordinates follow `vision`: pixel `y` of a frame covers rows [y, y + 1), so an
//! edge at 10.0 lies between pixels 9 and 10. A window shows the frame rectangle
//! from (`src_x`, `src_y`) at canvas (`dst_x`, `dst_y`), scaled s = `zoom` /
//! `shrink` times (enlarged by repeating pixels, or shrunk by averaging blocks):
//! the frame point (x, y) lands at (dst_x + s (x − src_x), dst_y + s (y − src_y)).
//! Lines along the rows and columns are anti-aliased by their area, so a line at a
//! fractional row is drawn there, not at the nearest pixel.
//!
//! The marks and the text are drawn on a [`Canvas`]: an RGB image (the contact
//! sheets, `compare`'s model overlay), or [`YuvCanvas`], the 4:2:0 samples the
//! H.264 encoder takes, which `overlay.mp4`'s frames are painted and drawn in
//! directly (no RGB picture, no conversion of the whole canvas a frame).

use std::cell::RefCell;
use std::collections::HashMap;
use std::sync::OnceLock;

use ab_glyph::{Font, FontRef, GlyphId, PxScaleFont, ScaleFont};
use image::{Rgb, RgbImage};
use serde::Serialize;

use crate::footage::{ChannelOrder, FrameView};

/// A rectangle of the footage frame shown enlarged on the canvas.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Window {
    /// What the window shows ("side view", "centre band ×8", "plan view").
    pub name: &'static str,
    /// The frame rectangle's first column and row \[px\].
    pub src_x: usize,
    pub src_y: usize,
    /// Its size \[px\].
    pub width: usize,
    pub height: usize,
    /// Where it starts on the canvas [canvas px].
    pub dst_x: u32,
    pub dst_y: u32,
    /// Canvas pixels per frame pixel along each axis (1 when shrunk).
    pub zoom: u32,
    /// Frame pixels per canvas pixel along each axis, averaged (1 when enlarged):
    /// the context views of large frames are shown at half size or less, so the
    /// overlay video stays small to encode.
    pub shrink: u32,
}

impl Window {
    /// Canvas pixels per frame pixel: `zoom` / `shrink`.
    pub fn scale(&self) -> f64 {
        f64::from(self.zoom) / f64::from(self.shrink)
    }

    /// The window's size on the canvas [canvas px].
    pub fn canvas_size(&self) -> (u32, u32) {
        let size = |n: usize| (n as u32 / self.shrink) * self.zoom;
        (size(self.width), size(self.height))
    }

    /// Canvas point of the frame point (x, y) [frame px, `vision` convention].
    pub fn to_canvas(&self, x: f64, y: f64) -> (f64, f64) {
        let z = self.scale();
        (
            f64::from(self.dst_x) + z * (x - self.src_x as f64),
            f64::from(self.dst_y) + z * (y - self.src_y as f64),
        )
    }

    /// Frame point of the canvas point (x, y): the inverse of [`Self::to_canvas`].
    pub fn to_frame(&self, x: f64, y: f64) -> (f64, f64) {
        let z = self.scale();
        (
            self.src_x as f64 + (x - f64::from(self.dst_x)) / z,
            self.src_y as f64 + (y - f64::from(self.dst_y)) / z,
        )
    }

    /// The window's extent on the canvas: x0, y0, x1, y1 (exclusive).
    fn extent(&self) -> (f64, f64, f64, f64) {
        let (w, h) = self.canvas_size();
        (
            f64::from(self.dst_x),
            f64::from(self.dst_y),
            f64::from(self.dst_x + w),
            f64::from(self.dst_y + h),
        )
    }

    /// Copies the window's rectangle of `frame` onto the canvas, each pixel
    /// repeated `zoom` × `zoom` times, or each block of `shrink` × `shrink`
    /// pixels averaged into one.
    pub fn paint(&self, frame: &FrameView, image: &mut RgbImage) {
        if self.shrink > 1 {
            self.paint_shrunk(frame, image);
            return;
        }
        let z = self.zoom as usize;
        let width = self.width.min(frame.width.saturating_sub(self.src_x));
        let height = self.height.min(frame.height.saturating_sub(self.src_y));
        let canvas_width = image.width() as usize;
        let (dst_x, dst_y) = (self.dst_x as usize, self.dst_y as usize);
        let bgr = matches!(frame.order, ChannelOrder::Bgr);
        let buffer: &mut [u8] = image;
        let mut line = vec![0u8; 3 * z * width];
        for y in 0..height {
            let src = &frame.row(self.src_y + y)[3 * self.src_x..3 * (self.src_x + width)];
            for (x, p) in src.chunks_exact(3).enumerate() {
                let rgb = if bgr {
                    [p[2], p[1], p[0]]
                } else {
                    [p[0], p[1], p[2]]
                };
                for k in 0..z {
                    line[3 * (z * x + k)..3 * (z * x + k + 1)].copy_from_slice(&rgb);
                }
            }
            for k in 0..z {
                let row = dst_y + z * y + k;
                let start = 3 * (row * canvas_width + dst_x);
                buffer[start..start + line.len()].copy_from_slice(&line);
            }
        }
    }

    /// [`Self::paint`] for a shrunk window: the mean of each block, rounded.
    fn paint_shrunk(&self, frame: &FrameView, image: &mut RgbImage) {
        let s = self.shrink as usize;
        let (w, h) = self.canvas_size();
        let width = (w as usize).min(frame.width.saturating_sub(self.src_x) / s);
        let height = (h as usize).min(frame.height.saturating_sub(self.src_y) / s);
        let canvas_width = image.width() as usize;
        let (dst_x, dst_y) = (self.dst_x as usize, self.dst_y as usize);
        let order = match frame.order {
            ChannelOrder::Bgr => [2, 1, 0],
            ChannelOrder::Rgb => [0, 1, 2],
        };
        let buffer: &mut [u8] = image;
        // Sums in the frame's channel order, each row of blocks at a time.
        let mut sums = vec![0u32; 3 * width];
        // The mean by a multiplication (a division per sample costs as much as
        // the rest of the copy).
        let inverse = 1.0 / (s * s) as f32;
        for y in 0..height {
            sums.fill(0);
            for dy in 0..s {
                let row = self.src_y + s * y + dy;
                let src = &frame.row(row)[3 * self.src_x..3 * (self.src_x + s * width)];
                for (sum, block) in sums.chunks_exact_mut(3).zip(src.chunks_exact(3 * s)) {
                    for p in block.chunks_exact(3) {
                        sum[0] += u32::from(p[0]);
                        sum[1] += u32::from(p[1]);
                        sum[2] += u32::from(p[2]);
                    }
                }
            }
            let start = 3 * ((dst_y + y) * canvas_width + dst_x);
            let out = &mut buffer[start..start + 3 * width];
            for (pixel, sum) in out.chunks_exact_mut(3).zip(sums.chunks_exact(3)) {
                for (c, &k) in order.iter().enumerate() {
                    pixel[c] = (sum[k] as f32 * inverse + 0.5) as u8;
                }
            }
        }
    }

    /// A line along a row at frame row `y` from frame column `x0` to `x1`, `width`
    /// canvas px thick and centred on the row, clipped to the window.
    pub fn row_line(
        &self,
        image: &mut impl Canvas,
        y: f64,
        (x0, x1): (f64, f64),
        width: f64,
        colour: Rgb<u8>,
    ) {
        let (cx0, cy) = self.to_canvas(x0, y);
        let (cx1, _) = self.to_canvas(x1, y);
        let (ex0, ey0, ex1, ey1) = self.extent();
        image.fill_box(
            (cx0.max(ex0), cx1.min(ex1)),
            ((cy - 0.5 * width).max(ey0), (cy + 0.5 * width).min(ey1)),
            colour,
        );
    }

    /// A line along a column at frame column `x` from frame row `y0` to `y1`,
    /// `width` canvas px thick and centred on the column, clipped to the window.
    pub fn column_line(
        &self,
        image: &mut impl Canvas,
        x: f64,
        (y0, y1): (f64, f64),
        width: f64,
        colour: Rgb<u8>,
    ) {
        let (cx, cy0) = self.to_canvas(x, y0);
        let (_, cy1) = self.to_canvas(x, y1);
        let (ex0, ey0, ex1, ey1) = self.extent();
        image.fill_box(
            ((cx - 0.5 * width).max(ex0), (cx + 0.5 * width).min(ex1)),
            (cy0.max(ey0), cy1.min(ey1)),
            colour,
        );
    }

    /// An upright cross of half-size `arm` canvas px centred on the frame point
    /// (x, y), if it lies in the window.
    pub fn cross(&self, image: &mut impl Canvas, (x, y): (f64, f64), arm: f64, colour: Rgb<u8>) {
        let (cx, cy) = self.to_canvas(x, y);
        let (ex0, ey0, ex1, ey1) = self.extent();
        if cx < ex0 || cx >= ex1 || cy < ey0 || cy >= ey1 {
            return;
        }
        image.fill_box(
            ((cx - arm).max(ex0), (cx + arm).min(ex1)),
            ((cy - 1.0).max(ey0), (cy + 1.0).min(ey1)),
            colour,
        );
        image.fill_box(
            ((cx - 1.0).max(ex0), (cx + 1.0).min(ex1)),
            ((cy - arm).max(ey0), (cy + arm).min(ey1)),
            colour,
        );
    }

    /// A straight segment between two frame points, one canvas px wide (not
    /// anti-aliased: for marks whose place is not a measurement, such as the
    /// strip's principal axis), clipped to the window.
    pub fn segment(
        &self,
        image: &mut impl Canvas,
        from: (f64, f64),
        to: (f64, f64),
        colour: Rgb<u8>,
    ) {
        let (ax, ay) = self.to_canvas(from.0, from.1);
        let (bx, by) = self.to_canvas(to.0, to.1);
        let (ex0, ey0, ex1, ey1) = self.extent();
        let steps = (bx - ax).abs().max((by - ay).abs()).ceil().max(1.0) as usize;
        let mut pixels: Vec<(u32, u32)> = (0..=steps)
            .map(|k| {
                let s = k as f64 / steps as f64;
                (ax + s * (bx - ax), ay + s * (by - ay))
            })
            .filter(|&(x, y)| x >= ex0 && x < ex1 && y >= ey0 && y < ey1)
            .map(|(x, y)| (x as u32, y as u32))
            .collect();
        // The steps are monotonic: a pixel reached twice is reached in a row.
        pixels.dedup();
        image.set_pixels(&pixels, colour);
    }

    /// Paints the frame pixels (x, y) of a mask that have an unset 4-neighbour
    /// (the mask's outline), `mask` row-major with `mask_width` columns, its
    /// pixel (0, 0) at frame point `origin`.
    pub fn outline(
        &self,
        image: &mut impl Canvas,
        (mask, mask_width): (&[bool], usize),
        origin: (usize, usize),
        colour: Rgb<u8>,
    ) {
        let height = mask.len() / mask_width.max(1);
        let set = |x: isize, y: isize| {
            x >= 0
                && y >= 0
                && (x as usize) < mask_width
                && (y as usize) < height
                && mask[y as usize * mask_width + x as usize]
        };
        for y in 0..height as isize {
            for x in 0..mask_width as isize {
                if !set(x, y) || (set(x - 1, y) && set(x + 1, y) && set(x, y - 1) && set(x, y + 1))
                {
                    continue;
                }
                let (fx, fy) = (origin.0 as f64 + x as f64, origin.1 as f64 + y as f64);
                let (cx, cy) = self.to_canvas(fx, fy);
                let z = self.scale();
                let (ex0, ey0, ex1, ey1) = self.extent();
                image.fill_box(
                    (cx.max(ex0), (cx + z).min(ex1)),
                    (cy.max(ey0), (cy + z).min(ey1)),
                    colour,
                );
            }
        }
    }
}

/// What the overlays draw marks and text on: an RGB image, or the encoder's
/// 4:2:0 samples ([`YuvCanvas`]). Colours are given in RGB.
pub trait Canvas {
    /// Width and height \[px\].
    fn size(&self) -> (u32, u32);

    /// Blends `colour` over the canvas box [x0, x1) × [y0, y1) (canvas px), each
    /// pixel by the fraction of its area the box covers.
    fn fill_box(&mut self, xs: (f64, f64), ys: (f64, f64), colour: Rgb<u8>);

    /// Sets each of `pixels` (x, y), listed once each and inside the canvas, to
    /// `colour`.
    fn set_pixels(&mut self, pixels: &[(u32, u32)], colour: Rgb<u8>);

    /// Blends `colour` over the pixels from (x, y) on by `mask`'s coverage,
    /// clipped to the canvas: a glyph.
    fn blend_mask(&mut self, at: (i32, i32), mask: &Mask, colour: Rgb<u8>);
}

/// A glyph's coverage of the pixels of its box.
#[derive(Debug, Clone, Default)]
pub struct Mask {
    /// Pixels a row.
    pub width: usize,
    /// 0–1, row-major.
    pub coverage: Vec<f32>,
    /// The same in 1/255ths, rounded (for [`YuvCanvas`]'s integer blending).
    pub alpha: Vec<u8>,
}

impl Mask {
    fn new(width: usize, coverage: Vec<f32>) -> Self {
        let alpha = coverage
            .iter()
            .map(|&c| (c.clamp(0.0, 1.0) * 255.0 + 0.5) as u8)
            .collect();
        Self {
            width,
            coverage,
            alpha,
        }
    }
}

/// The rounded means of 2 × 2 samples, two rows `a` and `b` at a time: `out[i]`
/// of `a[2i]`, `a[2i + 1]`, `b[2i]`, `b[2i + 1]`, each clamped to
/// `black..=white` first; `sums` is scratch space. Compiled for AVX2 too, taken
/// where the CPU has it: the baseline x86-64 build (SSE2) took 2.5 times as
/// long, and this runs on every moving frame a clip's overlay keeps
/// ([`super::keep`]) and on every frame of the video.
pub(super) fn means_2x2(
    (a, b): (&[u8], &[u8]),
    out: &mut [u8],
    greys: (u8, u8),
    sums: &mut Vec<u16>,
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        #[target_feature(enable = "avx2")]
        fn avx2(rows: (&[u8], &[u8]), out: &mut [u8], greys: (u8, u8), sums: &mut Vec<u16>) {
            means_2x2_inline(rows, out, greys, sums);
        }
        // SAFETY: the CPU has AVX2 (checked above).
        unsafe { avx2((a, b), out, greys, sums) };
        return;
    }
    means_2x2_inline((a, b), out, greys, sums);
}

#[inline(always)]
fn means_2x2_inline(
    (a, b): (&[u8], &[u8]),
    out: &mut [u8],
    (black, white): (u8, u8),
    sums: &mut Vec<u16>,
) {
    // Vertical sums first, then pairs of them: both loops vectorise.
    let n = 2 * out.len();
    sums.resize(n, 0);
    for ((sum, &a), &b) in sums.iter_mut().zip(&a[..n]).zip(&b[..n]) {
        *sum = u16::from(a.max(black).min(white)) + u16::from(b.max(black).min(white));
    }
    for (mean, pair) in out.iter_mut().zip(sums.chunks_exact(2)) {
        *mean = ((pair[0] + pair[1] + 2) >> 2) as u8;
    }
}

/// The fraction of pixel [p, p + 1) that [a, b) covers.
fn cover(a: f64, b: f64, p: f64) -> f64 {
    (b.min(p + 1.0) - a.max(p)).clamp(0.0, 1.0)
}

/// `p` blended towards `q` by `c` (0–1), rounded (half up: the value is not
/// negative; `f64::round` was a call per sample).
fn blend(p: u8, q: u8, c: f64) -> u8 {
    (f64::from(p) * (1.0 - c) + f64::from(q) * c + 0.5) as u8
}

impl Canvas for RgbImage {
    fn size(&self) -> (u32, u32) {
        self.dimensions()
    }

    fn fill_box(&mut self, (x0, x1): (f64, f64), (y0, y1): (f64, f64), colour: Rgb<u8>) {
        if x1 <= x0 || y1 <= y0 {
            return;
        }
        let (w, h) = (f64::from(self.width()), f64::from(self.height()));
        let (x0, x1, y0, y1) = (x0.max(0.0), x1.min(w), y0.max(0.0), y1.min(h));
        for py in y0.floor() as u32..y1.ceil() as u32 {
            let cy = cover(y0, y1, f64::from(py));
            for px in x0.floor() as u32..x1.ceil() as u32 {
                let c = cy * cover(x0, x1, f64::from(px));
                if c <= 0.0 {
                    continue;
                }
                let pixel = self.get_pixel_mut(px, py);
                for (p, q) in pixel.0.iter_mut().zip(colour.0) {
                    *p = blend(*p, q, c);
                }
            }
        }
    }

    fn set_pixels(&mut self, pixels: &[(u32, u32)], colour: Rgb<u8>) {
        for &(x, y) in pixels {
            self.put_pixel(x, y, colour);
        }
    }

    fn blend_mask(&mut self, (x, y): (i32, i32), mask: &Mask, colour: Rgb<u8>) {
        let (w, h) = (self.width() as i32, self.height() as i32);
        let (coverage, width) = (&mask.coverage, mask.width);
        for (dy, row) in coverage.chunks_exact(width.max(1)).enumerate() {
            let py = y + dy as i32;
            for (dx, &a) in row.iter().enumerate() {
                let px = x + dx as i32;
                if a <= 0.0 || px < 0 || py < 0 || px >= w || py >= h {
                    continue;
                }
                let a = f64::from(a.min(1.0));
                let pixel = self.get_pixel_mut(px as u32, py as u32);
                for (p, q) in pixel.0.iter_mut().zip(colour.0) {
                    *p = blend(*p, q, a);
                }
            }
        }
    }
}

/// BT.601 limited-range Y, Cb, Cr in 16.16 fixed point: the overlay videos'
/// samples ([`yuv420_of`]).
pub(super) const Y_OF_RGB: [i32; 3] = [16829, 33039, 6416];
pub(super) const U_OF_RGB: [i32; 3] = [-9714, -19071, 28784];
pub(super) const V_OF_RGB: [i32; 3] = [28784, -24103, -4681];

/// The overlay videos' Y, Cb, Cr of a colour (as [`yuv420_of`] codes a 2 × 2
/// block of it).
pub fn yuv_of(colour: Rgb<u8>) -> [u8; 3] {
    let [r, g, b] = colour.0.map(i32::from);
    let luma = (Y_OF_RGB[0] * r + Y_OF_RGB[1] * g + Y_OF_RGB[2] * b + (16 << 16) + (1 << 15)) >> 16;
    let chroma = |k: [i32; 3]| (k[0] * r + k[1] * g + k[2] * b + (128 << 16) + (1 << 15)) >> 16;
    [luma, chroma(U_OF_RGB), chroma(V_OF_RGB)].map(|v| v as u8)
}

/// An overlay frame as the encoder takes it: 8-bit 4:2:0, BT.601 limited range
/// (the samples [`yuv420_of`] makes of an RGB canvas), drawn in directly.
///
/// Marks are blended as on RGB ([`Canvas`]): luma pixel by pixel, each chroma
/// sample by the mean coverage of its 2 × 2 pixels. Both codings are affine in
/// the colour, so a mark over a block of one colour gives the samples the RGB
/// canvas converted would (to rounding), and a mark covering its pixels wholly
/// gives exactly the mark's colour's samples ([`yuv_of`]).
#[derive(Debug, Clone, Default)]
pub struct YuvCanvas {
    width: u32,
    height: u32,
    /// Y at the canvas's size, then U and V at half of it each way, rows packed.
    planes: [Vec<u8>; 3],
    /// The samples of the colour [`Self::fill`] filled it with.
    background: [u8; 3],
    /// Scratch: a row of luma, and the chroma samples the pixels under a
    /// picture's columns and rows take ([`Self::paint`]).
    line: Vec<u8>,
    column_taps: Vec<[Option<usize>; 2]>,
    row_taps: Vec<[Option<usize>; 2]>,
    whole_columns: Vec<[usize; 2]>,
    sums: Vec<u16>,
    /// A glyph's coverage summed over each chroma sample's pixels [1/255].
    coverage: Vec<u32>,
}

/// A picture to paint on a [`YuvCanvas`], in its coding (BT.601 limited range):
/// luma a pixel, `luma_stride` apart a row, from the first pixel shown; and the
/// chroma sample each column and each row shown takes in the chroma planes.
pub struct YuvPicture<'a> {
    pub luma: &'a [u8],
    pub luma_stride: usize,
    /// U and V.
    pub chroma: [&'a [u8]; 2],
    pub chroma_stride: usize,
    /// Per column shown, its chroma column; per row shown, its chroma row.
    pub columns: &'a [usize],
    pub rows: &'a [usize],
}

/// How the chroma samples a painted picture covers wholly take the picture's:
/// their columns' two taps each.
#[derive(Debug, Clone, Copy)]
enum WholeColumns {
    /// Both taps the same sample.
    Shared,
    /// Consecutive samples, from this one on, two a sample.
    Pairs(usize),
    Other,
}

impl WholeColumns {
    fn of(taps: &[[usize; 2]]) -> Self {
        if taps.iter().all(|&[a, b]| a == b) {
            Self::Shared
        } else if let Some(&[first, _]) = taps.first()
            && (first..)
                .step_by(2)
                .zip(taps)
                .all(|(c, &[a, b])| a == c && b == c + 1)
        {
            Self::Pairs(first)
        } else {
            Self::Other
        }
    }
}

impl YuvCanvas {
    /// Sizes the canvas `width` × `height` (even) and fills it with `colour`.
    pub fn fill(&mut self, width: u32, height: u32, colour: Rgb<u8>) {
        let (w, h) = (width as usize, height as usize);
        self.width = width;
        self.height = height;
        self.background = yuv_of(colour);
        for (k, plane) in self.planes.iter_mut().enumerate() {
            let n = if k == 0 { w * h } else { w / 2 * (h / 2) };
            plane.clear();
            plane.resize(n, self.background[k]);
        }
    }

    /// The samples of an RGB picture of the canvas ([`yuv420_of`]).
    pub fn set_rgb(&mut self, image: &RgbImage) {
        self.width = image.width();
        self.height = image.height();
        yuv420_of(image, &mut self.planes);
    }

    /// Y, U and V, rows packed.
    pub fn planes(&self) -> [&[u8]; 3] {
        let [y, u, v] = &self.planes;
        [y, u, v]
    }

    /// Paints `picture`, its pixel (0, 0) at canvas pixel `(dst_x, dst_y)`, each
    /// pixel repeated `zoom` × `zoom` times, its luma clamped to 16–235 (greys
    /// within 0–255, as RGB clamps them), clipped to the canvas. The canvas
    /// under it must show the colour it was filled with ([`Self::fill`]) and no
    /// other picture: a chroma sample that the picture covers in part keeps the
    /// background's share (the windows of a layout do not overlap).
    pub fn paint(&mut self, picture: &YuvPicture, (dst_x, dst_y): (u32, u32), zoom: u32) {
        let z = zoom.max(1) as usize;
        let (canvas_w, canvas_h) = (self.width as usize, self.height as usize);
        let (x0, y0) = (dst_x as usize, dst_y as usize);
        let x1 = (x0 + z * picture.columns.len()).min(canvas_w);
        let y1 = (y0 + z * picture.rows.len()).min(canvas_h);
        if x0 >= x1 || y0 >= y1 {
            return;
        }
        let n = x1 - x0;
        let shown = n.div_ceil(z);
        self.line.resize(z * shown, 0);
        for j in 0..(y1 - y0).div_ceil(z) {
            let src = &picture.luma[j * picture.luma_stride..][..shown];
            let rows = y0 + z * j..(y0 + z * (j + 1)).min(y1);
            if z == 1 {
                let out = &mut self.planes[0][rows.start * canvas_w + x0..][..n];
                for (p, &s) in out.iter_mut().zip(src) {
                    *p = s.clamp(16, 235);
                }
                continue;
            }
            for (run, &s) in self.line.chunks_exact_mut(z).zip(src) {
                run.fill(s.clamp(16, 235));
            }
            for row in rows {
                self.planes[0][row * canvas_w + x0..][..n].copy_from_slice(&self.line[..n]);
            }
        }
        // The chroma samples under the picture, and which of the picture's
        // chroma samples each of their two columns (rows) takes, if inside it.
        let taps = |start: usize, end: usize, map: &[usize], taps: &mut Vec<[Option<usize>; 2]>| {
            taps.clear();
            taps.extend((start / 2..end.div_ceil(2)).map(|c| {
                [2 * c, 2 * c + 1].map(|p| (start..end).contains(&p).then(|| map[(p - start) / z]))
            }));
        };
        taps(x0, x1, picture.columns, &mut self.column_taps);
        taps(y0, y1, picture.rows, &mut self.row_taps);
        // Only the first and last sample along each axis can be covered in part.
        let whole = |taps: &[[Option<usize>; 2]]| {
            let n = taps.len();
            let full = |k: usize| taps[k].iter().all(Option::is_some);
            let first = usize::from(n > 0 && !full(0));
            let last = if n > first && !full(n - 1) { n - 1 } else { n };
            first..last
        };
        let (columns_whole, rows_whole) = (whole(&self.column_taps), whole(&self.row_taps));
        self.whole_columns.clear();
        self.whole_columns.extend(
            self.column_taps[columns_whole.clone()]
                .iter()
                .map(|t| t.map(|c| c.unwrap_or(0))),
        );
        let whole_kind = WholeColumns::of(&self.whole_columns);
        let chroma_w = canvas_w / 2;
        let stride = picture.chroma_stride;
        for (k, source) in picture.chroma.into_iter().enumerate() {
            let background = i32::from(self.background[k + 1]);
            let plane = &mut self.planes[k + 1];
            for (j, rows) in self.row_taps.iter().enumerate() {
                let out = &mut plane[(y0 / 2 + j) * chroma_w + x0 / 2..][..self.column_taps.len()];
                if let [Some(r0), Some(r1)] = *rows {
                    // Whole samples: the mean of the four pixels' chroma.
                    let (a, b) = (&source[r0 * stride..], &source[r1 * stride..]);
                    let whole = &mut out[columns_whole.clone()];
                    match whole_kind {
                        // An enlarged picture: the four pixels take one sample.
                        WholeColumns::Shared if r0 == r1 => {
                            for (p, &[c, _]) in whole.iter_mut().zip(&self.whole_columns) {
                                *p = a[c];
                            }
                        }
                        // Shown as kept: four samples in a square.
                        WholeColumns::Pairs(first) if r1 == r0 + 1 => {
                            means_2x2((&a[first..], &b[first..]), whole, (0, 255), &mut self.sums);
                        }
                        _ => {
                            for (p, &[c0, c1]) in whole.iter_mut().zip(&self.whole_columns) {
                                let sum = u16::from(a[c0])
                                    + u16::from(a[c1])
                                    + u16::from(b[c0])
                                    + u16::from(b[c1]);
                                *p = ((sum + 2) >> 2) as u8;
                            }
                        }
                    }
                }
                let n = self.column_taps.len();
                let edges = if rows_whole.contains(&j) {
                    (0..columns_whole.start).chain(columns_whole.end..n)
                } else {
                    (0..n).chain(n..n)
                };
                for i in edges {
                    let columns = &self.column_taps[i];
                    let (mut sum, mut count) = (0i32, 0i32);
                    for r in rows.iter().flatten() {
                        let line = &source[r * stride..];
                        for &c in columns.iter().flatten() {
                            sum += i32::from(line[c]);
                            count += 1;
                        }
                    }
                    // The pixels covered replace the background's share.
                    let total = 4 * i32::from(out[i]) + sum - count * background;
                    out[i] = ((total + 2) >> 2).clamp(0, 255) as u8;
                }
            }
        }
    }

    /// Blends the chroma sample (cx, cy) towards `q`'s chroma by `c`.
    fn blend_chroma(&mut self, (cx, cy): (usize, usize), q: [u8; 3], c: f64) {
        let at = cy * (self.width as usize / 2) + cx;
        for (plane, q) in self.planes[1..].iter_mut().zip(&q[1..]) {
            plane[at] = blend(plane[at], *q, c);
        }
    }
}

impl Canvas for YuvCanvas {
    fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    fn fill_box(&mut self, (x0, x1): (f64, f64), (y0, y1): (f64, f64), colour: Rgb<u8>) {
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        let (x0, x1, y0, y1) = (x0.max(0.0), x1.min(w), y0.max(0.0), y1.min(h));
        if x1 <= x0 || y1 <= y0 {
            return;
        }
        let q = yuv_of(colour);
        // Each column's and row's covered fraction, from an even one on (the
        // chroma samples take them in pairs).
        let (px0, px1) = (x0.floor() as usize & !1, x1.ceil() as usize);
        let (py0, py1) = (y0.floor() as usize & !1, y1.ceil() as usize);
        let covers = |a: f64, b: f64, from: usize, to: usize| -> Vec<f64> {
            (from..to.next_multiple_of(2))
                .map(|p| cover(a, b, p as f64))
                .collect()
        };
        let (columns, rows) = (covers(x0, x1, px0, px1), covers(y0, y1, py0, py1));
        let stride = self.width as usize;
        for (py, &cy) in (py0..py1).zip(&rows) {
            let row = &mut self.planes[0][py * stride + px0..py * stride + px1];
            for (p, &cx) in row.iter_mut().zip(&columns) {
                let c = cy * cx;
                if c > 0.0 {
                    *p = blend(*p, q[0], c);
                }
            }
        }
        // A chroma sample by the mean coverage of its 2 × 2 pixels.
        for (cy, pair) in (py0 / 2..).zip(rows.chunks_exact(2)) {
            let c_y = 0.5 * (pair[0] + pair[1]);
            for (cx, pair) in (px0 / 2..).zip(columns.chunks_exact(2)) {
                let c = c_y * 0.5 * (pair[0] + pair[1]);
                if c > 0.0 {
                    self.blend_chroma((cx, cy), q, c);
                }
            }
        }
    }

    fn set_pixels(&mut self, pixels: &[(u32, u32)], colour: Rgb<u8>) {
        let q = yuv_of(colour);
        let stride = self.width as usize;
        let mut samples: Vec<(u32, u32)> = pixels
            .iter()
            .filter(|&&(x, y)| x < self.width && y < self.height)
            .map(|&(x, y)| {
                self.planes[0][y as usize * stride + x as usize] = q[0];
                (y / 2, x / 2)
            })
            .collect();
        // Each chroma sample by the share of its 2 × 2 pixels set.
        samples.sort_unstable();
        for run in samples.chunk_by(|a, b| a == b) {
            let (cy, cx) = run[0];
            let share = (run.len().min(4) as f64) / 4.0;
            self.blend_chroma((cx as usize, cy as usize), q, share);
        }
    }

    fn blend_mask(&mut self, (x, y): (i32, i32), mask: &Mask, colour: Rgb<u8>) {
        let width = mask.width.max(1);
        let height = (mask.alpha.len() / width) as i32;
        let (w, h) = (self.width as i32, self.height as i32);
        let (px0, px1) = (x.max(0), (x + width as i32).min(w));
        let (py0, py1) = (y.max(0), (y + height).min(h));
        if px0 >= px1 || py0 >= py1 {
            return;
        }
        let q = yuv_of(colour);
        let stride = self.width as usize;
        // Luma pixel by pixel, in integers (within a level of `blend`); each
        // chroma sample by its pixels' summed coverage.
        let (cx0, cy0) = (px0 / 2, py0 / 2);
        let columns = ((px1 + 1) / 2 - cx0) as usize;
        let rows = ((py1 + 1) / 2 - cy0) as usize;
        self.coverage.clear();
        self.coverage.resize(columns * rows, 0);
        let qy = u32::from(q[0]);
        for py in py0..py1 {
            let glyph = &mask.alpha[(py - y) as usize * width..][..width];
            let luma = &mut self.planes[0][py as usize * stride..][..stride];
            let sums = &mut self.coverage[(py / 2 - cy0) as usize * columns..][..columns];
            for px in px0..px1 {
                let a = u32::from(glyph[(px - x) as usize]);
                if a > 0 {
                    let p = &mut luma[px as usize];
                    *p = ((u32::from(*p) * (255 - a) + qy * a + 127) / 255) as u8;
                    sums[(px / 2 - cx0) as usize] += a;
                }
            }
        }
        for k in 0..self.coverage.len() {
            let sum = self.coverage[k];
            if sum > 0 {
                let at = ((cx0 as usize) + k % columns, (cy0 as usize) + k / columns);
                self.blend_chroma(at, q, f64::from(sum) / (4.0 * 255.0));
            }
        }
    }
}

/// One character of the embedded font at one size, rasterised as plotters
/// rasterises it: coverage over its pixel bounds, placed `y_shift` rows below
/// the line's top, then `advance` px to the next.
struct Glyph {
    id: GlyphId,
    mask: Mask,
    y_shift: i32,
    advance: f32,
}

impl Glyph {
    fn new(font: &PxScaleFont<&FontRef<'static>>, c: char, size: u32) -> Self {
        let id = font.glyph_id(c);
        let (mut width, mut coverage, mut y_shift) = (0, Vec::new(), 0);
        if let Some(outline) = font.outline_glyph(font.scaled_glyph(c)) {
            let bounds = outline.px_bounds();
            y_shift = (size as f32 / 2.0 + bounds.min.y) as i32;
            width = bounds.width() as usize;
            coverage = vec![0.0; width * bounds.height() as usize];
            outline.draw(|x, y, c| coverage[y as usize * width + x as usize] = c);
        }
        Self {
            id,
            mask: Mask::new(width, coverage),
            y_shift,
            advance: font.h_advance(id),
        }
    }
}

pub static FONT_BYTES: &[u8] = include_bytes!("../../data/fonts/DejaVuSans.ttf");

/// The embedded font (the report's, DejaVu Sans).
fn font() -> Result<&'static FontRef<'static>, String> {
    static FONT: OnceLock<Option<FontRef<'static>>> = OnceLock::new();
    FONT.get_or_init(|| FontRef::try_from_slice(FONT_BYTES).ok())
        .as_ref()
        .ok_or_else(|| "the embedded font DejaVuSans.ttf could not be loaded".into())
}

thread_local! {
    /// Glyphs rasterised so far on this thread, by (size, character): the
    /// overlays write three header lines on every frame, and rasterising their
    /// outlines each time cost 5 % of `analyse` (issue 15 §3).
    static GLYPHS: RefCell<HashMap<(u32, char), Glyph>> = RefCell::new(HashMap::new());
}

/// Writes lines of text, each in its colour, from canvas point (x, y) down, in
/// the report's embedded font at `size` px, placed and anti-aliased as plotters
/// draws text (kerning, whole-pixel glyph positions), each glyph rasterised once
/// per thread ([`GLYPHS`]).
///
/// # Errors
/// The font cannot be loaded.
pub fn text_lines(
    image: &mut impl Canvas,
    (x, y): (i32, i32),
    size: u32,
    lines: &[(String, Rgb<u8>)],
) -> Result<(), String> {
    let font = font()?.as_scaled(size as f32);
    let step = (f64::from(size) * 1.3).round() as i32;
    GLYPHS.with_borrow_mut(|glyphs| {
        for (k, (line, colour)) in lines.iter().enumerate() {
            let top = y + step * k as i32;
            let mut x_shift = 0f32;
            let mut previous = None;
            for c in line.chars() {
                let glyph = glyphs
                    .entry((size, c))
                    .or_insert_with(|| Glyph::new(&font, c, size));
                if let Some(previous) = previous {
                    x_shift += font.kern(previous, glyph.id);
                }
                previous = Some(glyph.id);
                let at = (x + x_shift as i32, top + glyph.y_shift);
                image.blend_mask(at, &glyph.mask, *colour);
                x_shift += glyph.advance;
            }
        }
    });
    Ok(())
}

/// A canvas's samples as the overlay videos store them: 8-bit 4:2:0, limited
/// range, BT.601 (what [`crate::render::H264Writer::push`] makes of RGB with
/// libswscale, within a level), each chroma sample from the mean colour of its
/// 2 × 2 pixels. Converting here, in one pass of integer arithmetic, costs a
/// third of libswscale's RGB24 path, which the overlays paid on every frame.
/// `planes` is resized to Y, U, V; the canvas's size must be even.
pub fn yuv420_of(image: &RgbImage, planes: &mut [Vec<u8>; 3]) {
    // BT.601 with Y in 16–235 and chroma in 16–240, 16.16 fixed point.
    const Y: [i32; 3] = Y_OF_RGB;
    const U: [i32; 3] = U_OF_RGB;
    const V: [i32; 3] = V_OF_RGB;
    let (w, h) = (image.width() as usize, image.height() as usize);
    let [luma, u, v] = planes;
    luma.resize(w * h, 0);
    u.resize(w / 2 * (h / 2), 0);
    v.resize(w / 2 * (h / 2), 0);
    let row = 3 * w;
    let rows = image.as_raw().chunks_exact(2 * row);
    let luma_rows = luma.chunks_exact_mut(2 * w);
    let chroma_rows = u.chunks_exact_mut(w / 2).zip(v.chunks_exact_mut(w / 2));
    for ((pair, luma_pair), (u_row, v_row)) in rows.zip(luma_rows).zip(chroma_rows) {
        let (top, bottom) = pair.split_at(row);
        let (luma_top, luma_bottom) = luma_pair.split_at_mut(w);
        for (rgb, out) in [(top, luma_top), (bottom, luma_bottom)] {
            for (p, y) in rgb.chunks_exact(3).zip(out.iter_mut()) {
                let (r, g, b) = (i32::from(p[0]), i32::from(p[1]), i32::from(p[2]));
                *y = ((Y[0] * r + Y[1] * g + Y[2] * b + (16 << 16) + (1 << 15)) >> 16) as u8;
            }
        }
        let blocks = top.chunks_exact(6).zip(bottom.chunks_exact(6));
        for ((a, b), (u, v)) in blocks.zip(u_row.iter_mut().zip(v_row.iter_mut())) {
            let sum = |c: usize| {
                i32::from(a[c]) + i32::from(a[c + 3]) + i32::from(b[c]) + i32::from(b[c + 3])
            };
            let (r, g, b) = (sum(0), sum(1), sum(2));
            let chroma = |k: [i32; 3]| {
                ((k[0] * r + k[1] * g + k[2] * b + (128 << 18) + (1 << 17)) >> 18) as u8
            };
            *u = chroma(U);
            *v = chroma(V);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row line at a fractional row is drawn there: the coverage-weighted centre
    /// of its rows is the line's row, whatever its sub-pixel phase.
    #[test]
    fn a_row_line_lies_on_its_fractional_row() {
        let window = Window {
            name: "test",
            src_x: 10,
            src_y: 20,
            width: 20,
            height: 20,
            dst_x: 0,
            dst_y: 4,
            zoom: 4,
            shrink: 1,
        };
        for y in [25.0, 25.13, 25.5, 31.87] {
            let mut image = RgbImage::new(80, 90);
            window.row_line(&mut image, y, (12.0, 18.0), 2.0, Rgb([0, 255, 0]));
            let column: Vec<f64> = (0..90)
                .map(|r| f64::from(image.get_pixel(20, r)[1]) / 255.0)
                .collect();
            let (mass, centre) = mass_and_centre(&column);
            // 8-bit levels: 1/255 of a canvas px per row touched.
            assert!((mass - 2.0).abs() < 0.02, "mass {mass}");
            let (_, drawn) = window.to_frame(0.0, centre);
            assert!((drawn - y).abs() < 0.01, "row {y}: drawn at {drawn}");
        }
    }

    /// The total of a column's coverages [canvas px] and their centroid, each
    /// row's at its centre r + ½ [canvas rows].
    fn mass_and_centre(column: &[f64]) -> (f64, f64) {
        let mass: f64 = column.iter().sum();
        let moment: f64 = column
            .iter()
            .enumerate()
            .map(|(r, w)| (r as f64 + 0.5) * w)
            .sum();
        (mass, moment / mass)
    }

    /// On the encoder's samples too: the luma of a row line at a fractional row
    /// is centred on it, and a box covering whole 2 × 2 blocks takes exactly its
    /// colour's samples.
    #[test]
    fn a_row_line_on_yuv_samples_lies_on_its_fractional_row() {
        let window = Window {
            name: "test",
            src_x: 10,
            src_y: 20,
            width: 20,
            height: 20,
            dst_x: 0,
            dst_y: 4,
            zoom: 4,
            shrink: 1,
        };
        let black = yuv_of(Rgb([0, 0, 0]))[0];
        let green = yuv_of(Rgb([0, 255, 0]));
        for y in [25.0, 25.13, 25.75, 31.87] {
            let mut canvas = YuvCanvas::default();
            canvas.fill(80, 90, Rgb([0, 0, 0]));
            window.row_line(&mut canvas, y, (12.0, 18.0), 2.0, Rgb([0, 255, 0]));
            let [luma, u, v] = canvas.planes();
            let column: Vec<f64> = (0..90)
                .map(|r| f64::from(luma[r * 80 + 20] - black) / f64::from(green[0] - black))
                .collect();
            let (mass, centre) = mass_and_centre(&column);
            // 8-bit levels of a 129-level luma step: 1/129 of a canvas px a row.
            assert!((mass - 2.0).abs() < 0.03, "mass {mass}");
            let (_, drawn) = window.to_frame(0.0, centre);
            assert!((drawn - y).abs() < 0.02, "row {y}: drawn at {drawn}");
            if y == 25.75 {
                // Canvas rows 26 and 27, one chroma row, wholly covered.
                assert_eq!((u[13 * 40 + 10], v[13 * 40 + 10]), (green[1], green[2]));
            }
        }
    }

    /// A picture painted at odd canvas offsets, enlarged 1 to 3 times, gives
    /// each chroma sample the mean of what its four pixels take: the picture's
    /// chroma where they lie on it, the background's elsewhere.
    #[test]
    fn painted_chroma_is_the_mean_of_its_pixels() {
        let (w, h) = (7usize, 5usize);
        let luma = vec![120u8; w * h];
        // One chroma sample a pixel pair along rows, one a row: odd sizes.
        let (cw, ch) = (4usize, 5usize);
        let u: Vec<u8> = (0..cw * ch).map(|k| (40 + 11 * k) as u8).collect();
        let v: Vec<u8> = (0..cw * ch).map(|k| (200 - 7 * k) as u8).collect();
        let columns: Vec<usize> = (0..w).map(|x| x / 2).collect();
        let rows: Vec<usize> = (0..h).collect();
        for (dst, zoom) in [((3, 5), 1), ((4, 2), 2), ((1, 3), 3), ((2, 2), 1)] {
            let mut canvas = YuvCanvas::default();
            canvas.fill(40, 30, Rgb([20, 20, 20]));
            let background = canvas.background;
            let picture = YuvPicture {
                luma: &luma,
                luma_stride: w,
                chroma: [&u, &v],
                chroma_stride: cw,
                columns: &columns,
                rows: &rows,
            };
            canvas.paint(&picture, dst, zoom);
            let z = zoom as usize;
            let (x0, y0) = (dst.0 as usize, dst.1 as usize);
            let take = |plane: &[u8], k: usize, x: usize, y: usize| -> f64 {
                if (x0..x0 + z * w).contains(&x) && (y0..y0 + z * h).contains(&y) {
                    let (i, j) = ((x - x0) / z, (y - y0) / z);
                    f64::from(plane[rows[j] * cw + columns[i]])
                } else {
                    f64::from(background[k])
                }
            };
            let [luma_out, u_out, v_out] = canvas.planes();
            for cy in 0..15 {
                for cx in 0..20 {
                    for (k, (plane, out)) in [(&u, u_out), (&v, v_out)].into_iter().enumerate() {
                        let mean = [(0, 0), (1, 0), (0, 1), (1, 1)]
                            .iter()
                            .map(|&(dx, dy)| take(plane, k + 1, 2 * cx + dx, 2 * cy + dy))
                            .sum::<f64>()
                            / 4.0;
                        let got = f64::from(out[cy * 20 + cx]);
                        assert!(
                            (got - mean).abs() <= 0.5,
                            "dst {dst:?}, zoom {zoom}, sample ({cx}, {cy}), plane {k}: {got}, \
                             the pixels' mean {mean}"
                        );
                    }
                }
            }
            assert_eq!(luma_out[(y0 + z * h - 1) * 40 + x0], 120);
            assert_eq!(luma_out[(y0 + z * h) * 40 + x0], background[0]);
        }
    }

    /// The BT.601 limited-range samples of the primaries, white and black
    /// (ITU-R BT.601 §2.5: Y = 16 + 219 E'y, C = 128 + 224 E'c, rounded), and a
    /// chroma sample from the mean colour of its 2 × 2 pixels.
    #[test]
    fn canvas_samples_are_bt601_limited_range() {
        let colours = [
            ([255, 255, 255], [235, 128, 128]),
            ([0, 0, 0], [16, 128, 128]),
            ([255, 0, 0], [81, 90, 240]),
            ([0, 255, 0], [145, 54, 34]),
            ([0, 0, 255], [41, 240, 110]),
        ];
        for (rgb, [y, u, v]) in colours {
            let image = RgbImage::from_pixel(4, 2, Rgb(rgb));
            let mut planes = Default::default();
            yuv420_of(&image, &mut planes);
            assert_eq!(planes[0], vec![y; 8], "{rgb:?}");
            assert_eq!(
                (planes[1].clone(), planes[2].clone()),
                (vec![u; 2], vec![v; 2]),
                "{rgb:?}"
            );
        }
        // Red beside blue in each 2 × 2 block: the chroma of their mean colour.
        let mut image = RgbImage::new(2, 2);
        for (x, y) in [(0, 0), (0, 1)] {
            image.put_pixel(x, y, Rgb([255, 0, 0]));
            image.put_pixel(x + 1, y, Rgb([0, 0, 255]));
        }
        let mut planes = Default::default();
        yuv420_of(&image, &mut planes);
        assert_eq!(planes[0], vec![81, 41, 81, 41]);
        // Chroma is linear in the colour: the mean of red's (90, 240) and blue's
        // (240, 110).
        assert_eq!((planes[1][0], planes[2][0]), (165, 175));
    }
}
