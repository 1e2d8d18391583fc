//! One decoded frame, borrowed: the currency between `footage` and `vision`.
//!
//! OpenCV decodes video into BGR `Mat`s and the `image` crate reads frame files
//! into RGB buffers. Copying every 720×1280 frame into a common type would cost as
//! much as the side-view stage itself, so `vision` works on a borrowed view that
//! knows its channel order and row stride instead.

/// Byte order of the three colour channels of a pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChannelOrder {
    /// Red, green, blue (the `image` crate).
    Rgb,
    /// Blue, green, red (OpenCV).
    Bgr,
}

/// A borrowed 8-bit, 3-channel frame. Row `y` starts at byte `y * stride`;
/// rows grow downward, as image rows do.
#[derive(Clone, Copy, Debug)]
pub struct FrameView<'a> {
    pub width: usize,
    pub height: usize,
    /// Bytes from the start of one row to the start of the next (≥ 3 · width).
    pub stride: usize,
    pub order: ChannelOrder,
    pub data: &'a [u8],
}

impl<'a> FrameView<'a> {
    /// A view of an `image` crate RGB buffer.
    pub fn from_rgb(image: &'a image::RgbImage) -> Self {
        let (width, height) = image.dimensions();
        Self {
            width: width as usize,
            height: height as usize,
            stride: 3 * width as usize,
            order: ChannelOrder::Rgb,
            data: image.as_raw(),
        }
    }

    /// The region `width × height` at column `x`, row `y` (a region of interest),
    /// sharing this view's buffer; `None` when it does not fit inside the frame.
    pub fn crop(&self, x: usize, y: usize, width: usize, height: usize) -> Option<Self> {
        if width == 0 || height == 0 || x + width > self.width || y + height > self.height {
            return None;
        }
        Some(Self {
            width,
            height,
            stride: self.stride,
            order: self.order,
            data: &self.data[y * self.stride + 3 * x..],
        })
    }

    /// The bytes of row `y` (3 · width of them, in this view's channel order).
    pub fn row(&self, y: usize) -> &'a [u8] {
        let start = y * self.stride;
        &self.data[start..start + 3 * self.width]
    }

    /// The pixel at column `x`, row `y`, as `[r, g, b]` whatever the storage order.
    pub fn rgb(&self, x: usize, y: usize) -> [u8; 3] {
        let p = &self.row(y)[3 * x..3 * x + 3];
        match self.order {
            ChannelOrder::Rgb => [p[0], p[1], p[2]],
            ChannelOrder::Bgr => [p[2], p[1], p[0]],
        }
    }

    /// Mean of the three channels at (x, y), 0–255: the intensity that the
    /// side-view threshold γ is compared with (thesis §3.2.4).
    pub fn intensity(&self, x: usize, y: usize) -> f32 {
        let p = &self.row(y)[3 * x..3 * x + 3];
        (p[0] as f32 + p[1] as f32 + p[2] as f32) / 3.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channel_order_is_respected() {
        let rgb =
            image::RgbImage::from_fn(2, 2, |x, y| image::Rgb([10 * x as u8, 20 * y as u8, 7]));
        let view = FrameView::from_rgb(&rgb);
        assert_eq!(view.rgb(1, 1), [10, 20, 7]);
        let bgr: Vec<u8> = rgb.pixels().flat_map(|p| [p[2], p[1], p[0]]).collect();
        let bgr_view = FrameView {
            order: ChannelOrder::Bgr,
            data: &bgr,
            ..view
        };
        assert_eq!(bgr_view.rgb(1, 1), [10, 20, 7]);
        assert_eq!(bgr_view.intensity(1, 0), (10.0 + 0.0 + 7.0) / 3.0);
        let corner = view.crop(1, 1, 1, 1).unwrap();
        assert_eq!(corner.rgb(0, 0), [10, 20, 7]);
        assert!(view.crop(1, 1, 2, 1).is_none(), "outside the frame");
    }
}
