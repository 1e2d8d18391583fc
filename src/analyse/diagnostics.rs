//! Diagnostic images of the image stage, as the thesis shows them: the
//! calibration frame with the points found (figs. 3.3, 3.4) and a thresholded
//! frame with the centre band and the rim edge found (figs. 3.7, 3.8, 3.20).
//! A user checks these first when a number looks wrong.

use image::{Rgb, RgbImage};

use crate::footage::FrameView;
use crate::vision::Calibration;
use crate::vision::INTENSITY_SCALE;

const RED: Rgb<u8> = Rgb([230, 30, 30]);
const GREEN: Rgb<u8> = Rgb([40, 200, 60]);
const BLUE: Rgb<u8> = Rgb([60, 120, 255]);
const YELLOW: Rgb<u8> = Rgb([250, 210, 0]);

fn to_image(frame: &FrameView) -> RgbImage {
    RgbImage::from_fn(frame.width as u32, frame.height as u32, |x, y| {
        Rgb(frame.rgb(x as usize, y as usize))
    })
}

fn put(image: &mut RgbImage, x: i64, y: i64, colour: Rgb<u8>) {
    if x >= 0 && y >= 0 && (x as u32) < image.width() && (y as u32) < image.height() {
        image.put_pixel(x as u32, y as u32, colour);
    }
}

fn horizontal(image: &mut RgbImage, y: f64, x0: f64, x1: f64, colour: Rgb<u8>) {
    let y = y.round() as i64;
    for x in x0.round() as i64..=x1.round() as i64 {
        put(image, x, y, colour);
    }
}

fn vertical(image: &mut RgbImage, x: f64, y0: f64, y1: f64, colour: Rgb<u8>) {
    let x = x.round() as i64;
    for y in y0.round() as i64..=y1.round() as i64 {
        put(image, x, y, colour);
    }
}

fn cross(image: &mut RgbImage, x: f64, y: f64, colour: Rgb<u8>) {
    horizontal(image, y, x - 6.0, x + 6.0, colour);
    vertical(image, x, y - 6.0, y + 6.0, colour);
}

/// The rest frame with x_l, x_r (green verticals), z_t (yellow), z_base (red) and
/// the centre line x_centre (blue), as in figs. 3.3–3.4.
pub fn calibration_image(frame: &FrameView, calibration: &Calibration) -> RgbImage {
    let mut image = to_image(frame);
    let c = calibration;
    let h = image.height() as f64;
    let x_centre = c.x_centre();
    vertical(&mut image, x_centre, 0.0, h, BLUE);
    vertical(&mut image, c.x_l, c.z_t - 20.0, c.z_base + 20.0, GREEN);
    vertical(&mut image, c.x_r, c.z_t - 20.0, c.z_base + 20.0, GREEN);
    horizontal(&mut image, c.z_t, x_centre - 40.0, x_centre + 40.0, YELLOW);
    horizontal(&mut image, c.z_base, c.x_l - 20.0, c.x_r + 20.0, RED);
    cross(&mut image, x_centre, c.z_t, YELLOW);
    cross(&mut image, x_centre, c.z_base, RED);
    image
}

/// A frame thresholded at γ (a fraction of white) on the mean RGB intensity (white above, black below),
/// with the measuring band around the centre line (blue) and the rim edge found
/// (red), as in figs. 3.7–3.8.
pub fn threshold_image(
    frame: &FrameView,
    gamma: f64,
    x_centre: f64,
    band_half_width_px: usize,
    edge_row: Option<f64>,
) -> RgbImage {
    let mut image = RgbImage::from_fn(frame.width as u32, frame.height as u32, |x, y| {
        if f64::from(frame.intensity(x as usize, y as usize)) > gamma * INTENSITY_SCALE {
            Rgb([255, 255, 255])
        } else {
            Rgb([0, 0, 0])
        }
    });
    let h = image.height() as f64;
    let half = band_half_width_px as f64;
    vertical(&mut image, x_centre - half - 1.0, 0.0, h, BLUE);
    vertical(&mut image, x_centre + half + 1.0, 0.0, h, BLUE);
    if let Some(row) = edge_row {
        horizontal(
            &mut image,
            row,
            x_centre - half - 12.0,
            x_centre + half + 12.0,
            RED,
        );
    }
    image
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markers_land_on_the_calibration_points() {
        let frame = RgbImage::new(100, 80);
        let view = FrameView::from_rgb(&frame);
        let c = Calibration {
            x_l: 20.0,
            x_r: 80.0,
            z_t: 40.0,
            z_base: 50.0,
        };
        let image = calibration_image(&view, &c);
        assert_eq!(*image.get_pixel(50, 50), RED, "z_base on the centre line");
        assert_eq!(*image.get_pixel(50, 40), YELLOW, "z_t on the centre line");
        assert_eq!(*image.get_pixel(20, 45), GREEN, "x_l");
        let bytes = crate::output::png_bytes(&image).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
    }
}
