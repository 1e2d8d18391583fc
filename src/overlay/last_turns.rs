//! The contact sheet `last-turns.png`: the overlay frames at the last peaks before
//! the halt, one per oscillation, in a grid, each with its header (frame, t − t_φ,
//! z_rim) as drawn in the video.

use image::{Rgb, RgbImage, imageops};

use super::canvas::text_lines;
use super::measured::OverlayFrame;
use crate::analyse::ExperimentPlan;

/// Tiles per row of the sheet.
const COLUMNS: usize = 4;
/// Gap between tiles and around them \[px\].
const GAP: u32 = 6;
/// Title band \[px\].
const TITLE_PX: u32 = 30;
/// Tiles wider than this are halved.
const MAX_TILE_WIDTH: u32 = 720;

/// The sheet of `tiles` (overlay frames at the peaks, oldest first).
///
/// # Errors
/// The title cannot be drawn (font).
pub fn contact_sheet(
    tiles: &[(OverlayFrame, RgbImage)],
    plan: &ExperimentPlan,
) -> Result<RgbImage, String> {
    let (w, h) = tiles.first().map_or((0, 0), |(_, t)| t.dimensions());
    let (w, h) = if w > MAX_TILE_WIDTH {
        (w / 2, h / 2)
    } else {
        (w, h)
    };
    let columns = tiles.len().clamp(1, COLUMNS);
    let rows = tiles.len().div_ceil(columns);
    let width = GAP + columns as u32 * (w + GAP);
    let height = TITLE_PX + GAP + rows as u32 * (h + GAP);
    let mut sheet = RgbImage::from_pixel(width, height, Rgb([250, 250, 250]));
    for (k, (_, tile)) in tiles.iter().enumerate() {
        let tile = if tile.dimensions() == (w, h) {
            tile.clone()
        } else {
            imageops::resize(tile, w, h, imageops::FilterType::Triangle)
        };
        let x = GAP + (k % columns) as u32 * (w + GAP);
        let y = TITLE_PX + GAP + (k / columns) as u32 * (h + GAP);
        imageops::replace(&mut sheet, &tile, i64::from(x), i64::from(y));
    }
    let name = plan
        .clip
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let title = format!(
        "{name}: the last {} oscillations before the halt, each at the frame nearest its peak",
        tiles.len()
    );
    text_lines(&mut sheet, (8, 6), 16, &[(title, Rgb([20, 20, 20]))])?;
    Ok(sheet)
}
