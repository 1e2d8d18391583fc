//! The disk on a plate brighter than its side (thesis fig. 3.9), found by its
//! edges instead of by a global threshold.
//!
//! On a light plate no global γ separates the disk: its side is shaded darker
//! towards its ends (a lit cylinder), darker than the plate and sometimes than
//! the shadow in front of it, while the background above the plate is darker
//! still. What every such scene keeps is the disk's outline, an edge of either
//! sign all along it:
//!
//! 1. The disk's ends x_l and x_r are the two columns where the most horizontal
//!    change accumulates over the frame's rows (a vertical edge as tall as the
//!    disk, against the background above the plate's horizon and the plate
//!    below it); plate texture and the horizontal edges of plate and shadow add
//!    little to any one column. Each end is then placed sub-pixel on every row
//!    the end's edge crosses (the steepest step within a few pixels, by its
//!    area) and the median over those rows is taken.
//! 2. Those rows give the disk's box. On its centre band the profile is walked
//!    from the row of the ends' lowest edge (inside the side, for a camera less
//!    than 9° above the plate) down to the first departure from the side's level,
//!    either way (a shadow or a plate brighter than the disk): z_base; and up to
//!    the largest change of level, the silhouette's top, below which the near top
//!    rim z_t is found as on a dark plate.
//! 3. The rim's threshold is local: halfway between the side's level on the
//!    centre band and the darkest level of the shadow just below the rim. The
//!    rim gauge's "second edge from the bottom" (plate → shadow → disk) then
//!    holds whatever the frame's overall histogram.

use super::VisionError;
use super::calibration::{Calibration, band};
use super::components::Component;
use super::profile::{area_edge, column_band_mean, row_band_mean};
use super::top_rim::{CentreBand, NEAR_RIM_STEP_FRACTION, TopFace, read_near_top_rim};
use crate::footage::FrameView;
use crate::numeric::{mad_sigma, median};

/// Least departure from the side's level that ends it, 0–255 intensity, and as a
/// fraction of that level: above codec noise and the side's shading.
const MIN_DEPARTURE: f32 = 8.0;
const DEPARTURE_FRACTION: f32 = 0.12;

/// x_l, x_r, z_t and z_base on a light plate (see the module docs).
pub(super) fn calibrate(
    frame: &FrameView,
    index: usize,
    half_width: usize,
) -> Result<(Calibration, TopFace), VisionError> {
    let missing = |point| VisionError::CalibrationPointNotFound {
        frame: index,
        point,
    };
    let (disk, x_l, x_r) = disk_by_edges(frame).ok_or(VisionError::NoDisk {
        frame: index,
        gamma: f64::NAN,
    })?;
    let (x0, x1) = band(0.5 * (x_l + x_r), half_width, frame.width);
    let p: Vec<f32> = (0..frame.height)
        .map(|y| row_band_mean(frame, y, x0, x1))
        .collect();
    let start = disk.row_max.saturating_sub(1).max(disk.row_min);
    let level = {
        let mut v = p[start.saturating_sub(2)..=start].to_vec();
        v.sort_by(f32::total_cmp);
        v[v.len() / 2]
    };
    let tolerance = MIN_DEPARTURE.max(DEPARTURE_FRACTION * level);
    let departs = |k: usize| (p[k] - level).abs() > tolerance;
    // Down to the bottom edge: the steepest step of the departure's sign.
    let down = (start..p.len())
        .find(|&k| departs(k))
        .ok_or_else(|| missing("z_base"))?;
    let falling = p[down] < level;
    let step = |k: usize| {
        if falling {
            p[k] - p[k + 1]
        } else {
            p[k + 1] - p[k]
        }
    };
    let i = (down.saturating_sub(REACH)..down.min(p.len() - 1))
        .max_by(|&a, &b| step(a).total_cmp(&step(b)))
        .ok_or_else(|| missing("z_base"))?;
    let z_base = area_edge(&p, i, REACH, 0.0).ok_or_else(|| missing("z_base"))?;
    // Up to the silhouette's top: the largest change of level (three rows
    // either side) above the start, within half the disk's width (a camera up to
    // 30° above the plate sees no more of the top face).
    let windowed = |k: usize| {
        let above: f32 = p[k + 1 - REACH..=k].iter().sum();
        let below: f32 = p[k + 1..=k + REACH].iter().sum();
        (below - above).abs() / REACH as f32
    };
    let lo = start
        .saturating_sub(((x_r - x_l) / 2.0) as usize)
        .max(REACH);
    let k = (lo..start.saturating_sub(REACH))
        .max_by(|&a, &b| windowed(a).total_cmp(&windowed(b)))
        .ok_or_else(|| missing("z_t"))?;
    let rising = p[k + 1] > p[k];
    let step = |k: usize| {
        if rising {
            p[k + 1] - p[k]
        } else {
            p[k] - p[k + 1]
        }
    };
    let j = (k.saturating_sub(REACH)..(k + REACH).min(p.len() - 1))
        .max_by(|&a, &b| step(a).total_cmp(&step(b)))
        .ok_or_else(|| missing("z_t"))?;
    let silhouette = area_edge(&p, j, REACH, 0.0).ok_or_else(|| missing("z_t"))?;
    let centre = CentreBand {
        x_centre: 0.5 * (x_l + x_r),
        half_span: 0.5 * (x_r - x_l),
        half_width,
        top: j + 1,
        far: silhouette,
        side_end: i,
        contrast: windowed(k),
    };
    // A face too thin for the plateaus is looked for only below a silhouette that
    // is the disk's top: where the level just above the edge is still the
    // backdrop's (the rows at the top of the search, above any face), within three
    // of their robust standard deviations (at least one grey level). A top face
    // darker than both the backdrop and the side makes the near rim the largest
    // step, and the blur of that edge would be read as a thin face below it (a
    // backdrop at 11, face 60, side 177: z_t 0.64 px low); such an edge is itself the
    // near rim. A backdrop may shade over the frame (a vignette, a lamp's fall-off),
    // so "the backdrop's level" allows as much change as a face lit like the side
    // would show: the fraction of the disk's contrast below which a face is not seen.
    let levels = |rows: std::ops::Range<usize>| -> Vec<f64> {
        p[rows].iter().map(|&v| f64::from(v)).collect()
    };
    let backdrop_levels = levels(lo - REACH..lo + REACH + 1);
    let backdrop = median(&backdrop_levels);
    let spread = mad_sigma(&backdrop_levels, backdrop).max(1.0);
    let above = j.saturating_sub(2 * REACH).max(lo - REACH);
    let top_is_backdrop = above + 1 >= j.saturating_sub(REACH)
        || (median(&levels(above..j.saturating_sub(REACH))) - backdrop).abs()
            <= (3.0 * spread).max(f64::from(NEAR_RIM_STEP_FRACTION * windowed(k)));
    let (z_t, face) = read_near_top_rim(frame, &centre, &p, top_is_backdrop);
    let calibration = Calibration {
        x_l,
        x_r,
        z_t,
        z_base,
    };
    Ok((calibration, face))
}

/// Pixels of horizontal change summed down each column: the grey image's
/// |I(x + 1) − I(x − 1)| per row.
fn column_edge_energy(frame: &FrameView) -> Vec<f32> {
    let (w, h) = (frame.width, frame.height);
    let mut energy = vec![0f32; w];
    let mut grey = vec![0f32; w];
    for y in 0..h {
        for (g, p) in grey.iter_mut().zip(frame.row(y).chunks_exact(3)) {
            *g = f32::from(p[0]) + f32::from(p[1]) + f32::from(p[2]);
        }
        for x in 1..w.saturating_sub(1) {
            energy[x] += (grey[x + 1] - grey[x - 1]).abs() / 3.0;
        }
    }
    energy
}

/// Narrowest disk, px, and the columns either side of an end searched for it.
const MIN_WIDTH_PX: usize = 16;
const END_REACH: usize = 4;
/// Samples either side of a step used for its area.
const REACH: usize = 3;

/// The disk's box on a light plate: the columns of its ends (coarse), the rows
/// over which its ends' edges stand out, and the ends placed sub-pixel. `None`
/// when no two columns stand out.
pub(super) fn disk_by_edges(frame: &FrameView) -> Option<(Component, f64, f64)> {
    let (w, h) = (frame.width, frame.height);
    if w < MIN_WIDTH_PX + 2 * END_REACH + 4 || h < 8 {
        return None;
    }
    let energy = column_edge_energy(frame);
    let smooth: Vec<f32> = (0..w)
        .map(|x| energy[x.saturating_sub(1)..(x + 2).min(w)].iter().sum())
        .collect();
    let inner = END_REACH + 1..w - END_REACH - 1;
    let first = inner
        .clone()
        .max_by(|&a, &b| smooth[a].total_cmp(&smooth[b]))?;
    let second = inner
        .filter(|&x| x.abs_diff(first) >= MIN_WIDTH_PX)
        .max_by(|&a, &b| smooth[a].total_cmp(&smooth[b]))?;
    let (left, right) = (first.min(second), first.max(second));
    // The rows the ends stand out on: the change across each end well above its
    // typical level over the frame's rows (the noise, where no disk is).
    let change = |x: usize, y: usize| {
        (column_band_mean(frame, x + 2, y, y + 1) - column_band_mean(frame, x - 2, y, y + 1)).abs()
    };
    let strength: Vec<f32> = (0..h)
        .map(|y| change(left, y).min(change(right, y)))
        .collect();
    let mut sorted = strength.clone();
    sorted.sort_by(f32::total_cmp);
    let noise = sorted[h / 2];
    let peak = sorted[h - 1];
    let cut = (4.0 * noise).max(0.15 * peak);
    let rows: Vec<usize> = (0..h).filter(|&y| strength[y] > cut).collect();
    // The longest run of such rows, gaps of two rows bridged.
    let mut best = (0, 0);
    let mut start = *rows.first()?;
    for pair in rows.windows(2) {
        if pair[1] > pair[0] + 3 {
            if pair[0] - start > best.1 - best.0 {
                best = (start, pair[0]);
            }
            start = pair[1];
        }
    }
    let last = *rows.last()?;
    if last - start > best.1 - best.0 {
        best = (start, last);
    }
    let (top, bottom) = best;
    if bottom < top + 2 {
        return None;
    }
    let end = |x: usize| sub_pixel_end(frame, x, top + 1, bottom);
    let (x_l, x_r) = (end(left)?, end(right)?);
    Some((Component::bounding_box(left, right, top, bottom), x_l, x_r))
}

/// The median over rows `y0..y1` of the sub-pixel edge nearest column `x`: the
/// steepest step within [`END_REACH`] columns, placed by its area.
fn sub_pixel_end(frame: &FrameView, x: usize, y0: usize, y1: usize) -> Option<f64> {
    let c0 = x.checked_sub(END_REACH + REACH)?;
    let c1 = (x + END_REACH + REACH + 2).min(frame.width);
    let mut ends: Vec<f64> = (y0..y1)
        .filter_map(|y| {
            let q: Vec<f32> = (c0..c1)
                .map(|c| column_band_mean(frame, c, y, y + 1))
                .collect();
            let i = (REACH..q.len() - REACH - 1)
                .max_by(|&a, &b| (q[a + 1] - q[a]).abs().total_cmp(&(q[b + 1] - q[b]).abs()))?;
            area_edge(&q, i, REACH, c0 as f64)
        })
        .collect();
    if ends.is_empty() {
        return None;
    }
    Some(crate::numeric::upper_median(&mut ends))
}

/// The rim threshold on a light plate: halfway between the side's median level
/// on the band `x0..x1` (rows `z_t..z_base`) and the darkest level within
/// `reach` rows below z_base (the shadow). `None` when the shadow is not darker
/// than the side.
pub(super) fn rim_level(
    frame: &FrameView,
    x0: usize,
    x1: usize,
    z_t: f64,
    z_base: f64,
    reach: usize,
) -> Option<f32> {
    let (top, base) = (z_t.ceil() as usize + 1, z_base.floor() as usize);
    if base <= top + 1 || base + 2 >= frame.height {
        return None;
    }
    let mut side: Vec<f32> = (top..base - 1)
        .map(|y| row_band_mean(frame, y, x0, x1))
        .collect();
    side.sort_by(f32::total_cmp);
    let side_level = side[side.len() / 2];
    let shadow = (base + 1..(base + 1 + reach).min(frame.height))
        .map(|y| row_band_mean(frame, y, x0, x1))
        .fold(f32::MAX, f32::min);
    (shadow < side_level).then_some(0.5 * (side_level + shadow))
}
