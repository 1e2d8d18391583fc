//! Test frames drawn with exact (anti-aliased) pixel coverage, whose edges sit
//! at known sub-pixel positions: the ground truth of the vision tests.

use crate::footage::{ChannelOrder, FrameView};

/// An RGB canvas in floating point; pixel (c, r) covers [c, c+1) × [r, r+1).
#[derive(Clone, Debug)]
pub(crate) struct Canvas {
    pub w: usize,
    pub h: usize,
    px: Vec<[f64; 3]>,
}

impl Canvas {
    pub fn new(w: usize, h: usize, background: [f64; 3]) -> Self {
        Self {
            w,
            h,
            px: vec![background; w * h],
        }
    }

    /// A scene of axis-aligned rectangles `(x0, y0, x1, y1, colour)` over a
    /// background, later ones on top, with each pixel the exact area average of
    /// the scene inside it (blending rectangle after rectangle would darken
    /// pixels where two edges meet).
    pub fn from_rects(w: usize, h: usize, background: [f64; 3], rects: &[Rect]) -> Self {
        let mut canvas = Self::new(w, h, background);
        for r in 0..h {
            for c in 0..w {
                let cuts = |lo: f64, edges: &mut dyn Iterator<Item = f64>| {
                    let mut v: Vec<f64> = std::iter::once(lo)
                        .chain(edges.filter(|&e| e > lo && e < lo + 1.0))
                        .chain(std::iter::once(lo + 1.0))
                        .collect();
                    v.sort_by(f64::total_cmp);
                    v
                };
                let xs = cuts(c as f64, &mut rects.iter().flat_map(|q| [q.0, q.2]));
                let ys = cuts(r as f64, &mut rects.iter().flat_map(|q| [q.1, q.3]));
                let mut acc = [0.0; 3];
                for xw in xs.windows(2) {
                    for yw in ys.windows(2) {
                        let (x, y) = (0.5 * (xw[0] + xw[1]), 0.5 * (yw[0] + yw[1]));
                        let area = (xw[1] - xw[0]) * (yw[1] - yw[0]);
                        let colour = rects
                            .iter()
                            .rev()
                            .find(|q| x >= q.0 && x < q.2 && y >= q.1 && y < q.3)
                            .map_or(background, |q| q.4);
                        for k in 0..3 {
                            acc[k] += area * colour[k];
                        }
                    }
                }
                canvas.px[r * w + c] = acc;
            }
        }
        canvas
    }

    /// Paints the set where `inside(x, y)` holds, within the box
    /// [x0, x1) × [y0, y1), by n × n supersampling of each pixel.
    pub fn shape(
        &mut self,
        box_: (f64, f64, f64, f64),
        n: usize,
        inside: impl Fn(f64, f64) -> bool,
        colour: [f64; 3],
    ) {
        self.paint(box_, n, |x, y| inside(x, y).then_some(colour));
    }

    /// Paints `colour_at(x, y)` where it is `Some`, within the box [x0, x1) ×
    /// [y0, y1), by n × n supersampling of each pixel: regions of different colours
    /// that share an edge, painted at once, mix in each pixel by their areas.
    pub fn paint(
        &mut self,
        (x0, y0, x1, y1): (f64, f64, f64, f64),
        n: usize,
        colour_at: impl Fn(f64, f64) -> Option<[f64; 3]>,
    ) {
        let (c0, c1) = (
            x0.floor().max(0.0) as usize,
            (x1.ceil() as usize).min(self.w),
        );
        let (r0, r1) = (
            y0.floor().max(0.0) as usize,
            (y1.ceil() as usize).min(self.h),
        );
        let samples = (n * n) as f64;
        for r in r0..r1 {
            for c in c0..c1 {
                let mut painted = [0.0; 3];
                let mut hits = 0;
                for i in 0..n {
                    for j in 0..n {
                        let x = c as f64 + (i as f64 + 0.5) / n as f64;
                        let y = r as f64 + (j as f64 + 0.5) / n as f64;
                        if let Some(colour) = colour_at(x, y) {
                            hits += 1;
                            for k in 0..3 {
                                painted[k] += colour[k] / samples;
                            }
                        }
                    }
                }
                let keep = 1.0 - hits as f64 / samples;
                let p = &mut self.px[r * self.w + c];
                for k in 0..3 {
                    p[k] = keep * p[k] + painted[k];
                }
            }
        }
    }

    /// Adds uniform noise in ±`amplitude` to every channel (a fixed LCG, so
    /// tests are reproducible).
    pub fn noise(&mut self, amplitude: f64, seed: u64) {
        let mut s = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        for p in &mut self.px {
            for v in p.iter_mut() {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let u = (s >> 11) as f64 / (1u64 << 53) as f64;
                *v += amplitude * (2.0 * u - 1.0);
            }
        }
    }

    /// Multiplies every channel by `gain` (a change of the light).
    pub fn scale(&mut self, gain: f64) {
        for v in self.px.iter_mut().flatten() {
            *v *= gain;
        }
    }

    /// Blurs with a Gaussian of standard deviation `sigma` px (separable, kernel
    /// cut at 4σ, edges clamped): a lens out of focus.
    pub fn blur(&mut self, sigma: f64) {
        if sigma <= 0.0 {
            return;
        }
        let reach = (4.0 * sigma).ceil() as isize;
        let kernel: Vec<f64> = (-reach..=reach)
            .map(|k| (-0.5 * (k as f64 / sigma).powi(2)).exp())
            .collect();
        let total: f64 = kernel.iter().sum();
        let (w, h) = (self.w as isize, self.h as isize);
        for (dx, dy) in [(1, 0), (0, 1)] {
            let src = self.px.clone();
            for r in 0..h {
                for c in 0..w {
                    let mut acc = [0.0; 3];
                    for (k, weight) in (-reach..=reach).zip(&kernel) {
                        let (cc, rr) = ((c + k * dx).clamp(0, w - 1), (r + k * dy).clamp(0, h - 1));
                        let p = src[(rr * w + cc) as usize];
                        for j in 0..3 {
                            acc[j] += weight * p[j];
                        }
                    }
                    self.px[(r * w + c) as usize] = acc.map(|v| v / total);
                }
            }
        }
    }

    /// 8-bit bytes in BGR order (as OpenCV delivers frames), with `pad` spare
    /// bytes at the end of every row.
    pub fn to_bgr(&self, pad: usize) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.h * (3 * self.w + pad));
        for r in 0..self.h {
            for c in 0..self.w {
                let p = self.px[r * self.w + c];
                out.extend([p[2], p[1], p[0]].map(|v| v.round().clamp(0.0, 255.0) as u8));
            }
            out.extend(std::iter::repeat_n(0u8, pad));
        }
        out
    }

    /// A view of bytes made by [`to_bgr`](Self::to_bgr) with the same `pad`.
    pub fn view<'a>(&self, bytes: &'a [u8], pad: usize) -> FrameView<'a> {
        FrameView {
            width: self.w,
            height: self.h,
            stride: 3 * self.w + pad,
            order: ChannelOrder::Bgr,
            data: bytes,
        }
    }
}

/// An axis-aligned rectangle [x0, x1) × [y0, y1) and its colour.
pub(crate) type Rect = (f64, f64, f64, f64, [f64; 3]);

pub(crate) fn grey(v: f64) -> [f64; 3] {
    [v, v, v]
}

/// A disk seen edge-on from the side: a white band x_l..x_r, `thickness` px
/// tall, its bottom edge `lift` px above the plate line `z_base`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SideScene {
    pub w: usize,
    pub h: usize,
    pub x_l: f64,
    pub x_r: f64,
    pub z_base: f64,
    pub thickness: f64,
    pub disk: f64,
    pub background: f64,
}

impl SideScene {
    pub fn standard() -> Self {
        Self {
            w: 640,
            h: 360,
            x_l: 200.3,
            x_r: 439.6,
            z_base: 190.7,
            thickness: 40.35,
            disk: 230.0,
            background: 25.0,
        }
    }

    /// True z_t at rest.
    pub fn z_t(&self) -> f64 {
        self.z_base - self.thickness
    }

    /// A dark, mirror-like plate (grey 35) below the plate line, with the disk's
    /// mirror image at `reflectance` separated from it by a gap of 2·lift.
    pub fn dark_plate(&self, lift: f64, reflectance: f64) -> Canvas {
        let plate = 35.0;
        let mirror = plate + reflectance * (self.disk - plate);
        let (bottom, top) = (self.z_base - lift, self.z_base + lift);
        let (w, h) = (self.w as f64, self.h as f64);
        let rects = [
            (0.0, self.z_base, w, h, grey(plate)),
            (
                self.x_l,
                bottom - self.thickness,
                self.x_r,
                bottom,
                grey(self.disk),
            ),
            (self.x_l, top, self.x_r, top + self.thickness, grey(mirror)),
        ];
        Canvas::from_rects(self.w, self.h, grey(self.background), &rects)
    }

    /// A light plate (grey 210) with the dark shadow (grey 40) under the disk,
    /// `shadow` px deep below the plate line, filling any gap above it.
    pub fn light_plate(&self, lift: f64, shadow: f64) -> Canvas {
        let bottom = self.z_base - lift;
        let (w, h) = (self.w as f64, self.h as f64);
        let rects = [
            (0.0, self.z_base, w, h, grey(210.0)),
            (
                self.x_l - 4.0,
                bottom,
                self.x_r + 4.0,
                self.z_base + shadow,
                grey(40.0),
            ),
            (
                self.x_l,
                bottom - self.thickness,
                self.x_r,
                bottom,
                grey(self.disk),
            ),
        ];
        Canvas::from_rects(self.w, self.h, grey(self.background + 35.0), &rects)
    }
}
