//! Study figures as SVG: box plots of the energy exponent per base-plate material
//! (thesis figs 3.15 and 3.17) and the trends of n against material properties
//! (fig. 3.16).
//!
//! Inputs are the [`crate::stats`] types ([`Summary`], [`Trend`]); outputs are SVG
//! strings, which [`write_svg`] writes atomically. Boxes span the quartiles of
//! [`crate::stats::summarise`] (Hazen / MATLAB definition, as the thesis), the centre
//! line is the median, whiskers reach the most extreme values inside the 1.5·IQR fences
//! and values beyond them are marked with a red `+` (fig. 3.15: "Outlier shown in red").
//!
//! Text is laid out with the embedded DejaVu Sans registered by
//! [`super::plot`]; the SVG itself only names the `sans-serif` family.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::output::OutputError;
use crate::stats::{
    DiskSetup, ExponentRecord, MaterialProperties, StatsError, Summary, Trend, TrendPoints,
    material_groups, material_trends, summarise,
};

/// Why a study figure could not be drawn or written.
#[derive(Debug, thiserror::Error)]
pub enum StudyPlotError {
    /// The inputs cannot be plotted.
    #[error("cannot plot {figure}: {reason}")]
    Input {
        /// The figure's title.
        figure: String,
        /// Why.
        reason: String,
    },
    /// plotters failed while drawing.
    #[error("drawing {figure} failed: {reason}")]
    Draw {
        /// The figure's title.
        figure: String,
        /// Why.
        reason: String,
    },
    /// The statistics behind the figure failed.
    #[error(transparent)]
    Stats(#[from] StatsError),
    /// Writing the file failed.
    #[error(transparent)]
    Write(#[from] OutputError),
}

/// Figure size in SVG user units.
const SIZE: (u32, u32) = (960, 600);
const FONT: &str = "sans-serif";
/// Box fill colours, one per series (the first is also used for single-series plots).
/// Boxes are the only filled rectangles in these colours, which the tests rely on.
pub const SERIES_COLOURS: [RGBColor; 4] = [
    RGBColor(120, 160, 230),
    RGBColor(240, 170, 90),
    RGBColor(130, 200, 130),
    RGBColor(200, 140, 200),
];
/// Outlier marks.
const OUTLIER_COLOUR: RGBColor = RGBColor(220, 0, 0);

/// One series of boxes: a summary per category (`None` where the series has no data,
/// e.g. the brass disk on the concave plate).
#[derive(Debug, Clone, PartialEq)]
pub struct BoxSeries {
    /// Legend name (shown when there is more than one series).
    pub name: String,
    /// One entry per category of the [`BoxPlot`].
    pub boxes: Vec<Option<Summary>>,
}

/// A box plot with categories on the x-axis and one box per category and series.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxPlot {
    /// Figure title.
    pub title: String,
    /// Y-axis label.
    pub y_label: String,
    /// Category names (x-axis), e.g. materials.
    pub categories: Vec<String>,
    /// The series, drawn side by side within each category.
    pub series: Vec<BoxSeries>,
}

/// Draws `plot` as an SVG string.
pub fn box_plot_svg(plot: &BoxPlot) -> Result<String, StudyPlotError> {
    let input = |reason: String| StudyPlotError::Input {
        figure: plot.title.clone(),
        reason,
    };
    if plot.categories.is_empty() || plot.series.is_empty() {
        return Err(input("no categories or no series".into()));
    }
    if plot.series.len() > SERIES_COLOURS.len() {
        return Err(input(format!(
            "{} series; at most {} can be told apart",
            plot.series.len(),
            SERIES_COLOURS.len()
        )));
    }
    for s in &plot.series {
        if s.boxes.len() != plot.categories.len() {
            return Err(input(format!(
                "series {:?} has {} boxes for {} categories",
                s.name,
                s.boxes.len(),
                plot.categories.len()
            )));
        }
    }
    let boxes = || plot.series.iter().flat_map(|s| s.boxes.iter().flatten());
    let (lo, hi) = boxes().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), b| {
        (lo.min(b.min), hi.max(b.max))
    });
    if lo > hi {
        return Err(input("every box is empty".into()));
    }
    let (ylo, yhi) = padded(lo, hi);
    render(&plot.title, |root| draw_boxes(root, plot, ylo, yhi))
}

/// Draws on an SVG string with the embedded font registered; `draw` errors become
/// [`StudyPlotError::Draw`].
fn render(
    title: &str,
    draw: impl FnOnce(&DrawingArea<SVGBackend, Shift>) -> Result<(), String>,
) -> Result<String, StudyPlotError> {
    let fail = |reason: String| StudyPlotError::Draw {
        figure: title.to_string(),
        reason,
    };
    super::plot::ensure_font().map_err(fail)?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        draw(&root).map_err(fail)?;
        root.present().map_err(|e| fail(e.to_string()))?;
    }
    Ok(svg)
}

fn e2s<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// A range padded by 8 % of its span (or ±0.05 when constant).
fn padded(lo: f64, hi: f64) -> (f64, f64) {
    let pad = if hi > lo { 0.08 * (hi - lo) } else { 0.05 };
    (lo - pad, hi + pad)
}

fn draw_boxes<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    plot: &BoxPlot,
    ylo: f64,
    yhi: f64,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(e2s)?;
    let n_cat = plot.categories.len();
    let n_ser = plot.series.len();
    let mut chart = ChartBuilder::on(root)
        .caption(&plot.title, (FONT, 22))
        .margin(16)
        .x_label_area_size(56)
        .y_label_area_size(72)
        .build_cartesian_2d(-0.5..(n_cat as f64 - 0.5), ylo..yhi)
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_desc(plot.y_label.as_str())
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .draw()
        .map_err(e2s)?;

    // Each category spans 0.8 of its unit slot, split between the series.
    let slot = 0.8 / n_ser as f64;
    let half_box = 0.35 * slot;
    for (si, series) in plot.series.iter().enumerate() {
        let colour = SERIES_COLOURS[si];
        for (ci, summary) in series.boxes.iter().enumerate() {
            let Some(b) = summary else { continue };
            let x = ci as f64 - 0.4 + slot * (si as f64 + 0.5);
            let (x0, x1) = (x - half_box, x + half_box);
            let black = BLACK.stroke_width(1);
            // The box: one filled rectangle (counted by the tests), then its outline.
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(x0, b.q1), (x1, b.q3)],
                    colour.filled(),
                )))
                .map_err(e2s)?;
            let cap = |y: f64| vec![(x - half_box / 2.0, y), (x + half_box / 2.0, y)];
            let lines = [
                vec![(x0, b.q1), (x1, b.q1), (x1, b.q3), (x0, b.q3), (x0, b.q1)],
                vec![(x, b.q3), (x, b.whisker_high)],
                vec![(x, b.q1), (x, b.whisker_low)],
                cap(b.whisker_high),
                cap(b.whisker_low),
            ];
            chart
                .draw_series(lines.into_iter().map(|l| PathElement::new(l, black)))
                .map_err(e2s)?;
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(x0, b.median), (x1, b.median)],
                    BLACK.stroke_width(3),
                )))
                .map_err(e2s)?;
            chart
                .draw_series(
                    b.outliers
                        .iter()
                        .map(|&o| Cross::new((x, o), 5, OUTLIER_COLOUR.stroke_width(2))),
                )
                .map_err(e2s)?;
        }
    }

    // Category names under the axis, centred on their slot.
    let style = TextStyle::from((FONT, 14).into_font()).pos(Pos::new(HPos::Center, VPos::Top));
    for (ci, name) in plot.categories.iter().enumerate() {
        let (px, py) = chart.backend_coord(&(ci as f64, ylo));
        root.draw(&Text::new(name.clone(), (px, py + 8), style.clone()))
            .map_err(e2s)?;
    }

    // Legend for several series: coloured bars (lines, not rectangles, so that the
    // boxes stay the only filled rectangles of their colour).
    if n_ser > 1 {
        let (mut px, py) = chart.backend_coord(&(-0.5, yhi));
        px += 12;
        let label = TextStyle::from((FONT, 14).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
        for (si, series) in plot.series.iter().enumerate() {
            let y = py + 14 + 20 * si as i32;
            root.draw(&PathElement::new(
                vec![(px, y), (px + 22, y)],
                SERIES_COLOURS[si].stroke_width(10),
            ))
            .map_err(e2s)?;
            root.draw(&Text::new(series.name.clone(), (px + 30, y), label.clone()))
                .map_err(e2s)?;
        }
    }
    Ok(())
}

/// Fig. 3.15: box plots of n for Euler's disk on every base-plate (Table B.1), in the
/// thesis's order (decreasing Young's modulus, then the concave plate).
pub fn figure_3_15(records: &[ExponentRecord]) -> Result<BoxPlot, StudyPlotError> {
    let groups = material_groups(records, DiskSetup::Euler);
    let boxes = groups
        .iter()
        .map(|g| summarise(g).map(Some))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(BoxPlot {
        title: "Energy exponent n of Euler's disk per base-plate (fig. 3.15)".into(),
        y_label: "energy exponent n".into(),
        categories: groups.into_iter().map(|g| g.name).collect(),
        series: vec![BoxSeries {
            name: DiskSetup::Euler.label().into(),
            boxes,
        }],
    })
}

/// Fig. 3.17: box plots of n for Euler's disk, the flipped Euler's disk and the brass
/// disk per base-plate (Tables B.1–B.3); materials missing for a disk get no box, and
/// materials present for the Euler disk only (the concave plate) are left out.
pub fn figure_3_17(records: &[ExponentRecord]) -> Result<BoxPlot, StudyPlotError> {
    let per_setup: Vec<_> = DiskSetup::ALL
        .iter()
        .map(|&s| (s, material_groups(records, s)))
        .collect();
    let mut categories: Vec<String> = Vec::new();
    for (_, groups) in &per_setup {
        for g in groups {
            let shared = per_setup
                .iter()
                .filter(|(_, gs)| gs.iter().any(|h| h.name == g.name))
                .count();
            if shared > 1 && !categories.contains(&g.name) {
                categories.push(g.name.clone());
            }
        }
    }
    let series = per_setup
        .iter()
        .map(|(setup, groups)| {
            let boxes = categories
                .iter()
                .map(|c| {
                    groups
                        .iter()
                        .find(|g| &g.name == c)
                        .map(summarise)
                        .transpose()
                })
                .collect::<Result<Vec<_>, _>>()?;
            Ok(BoxSeries {
                name: setup.label().into(),
                boxes,
            })
        })
        .collect::<Result<Vec<_>, StatsError>>()?;
    Ok(BoxPlot {
        title: "Energy exponent n per disk and base-plate (fig. 3.17)".into(),
        y_label: "energy exponent n".into(),
        categories,
        series,
    })
}

/// Draws a trend: the points, the OLS line over their x-range, and the slope with its
/// standard error, 95 % CI and R² in the title (fig. 3.16).
pub fn trend_plot_svg(trend: &Trend) -> Result<String, StudyPlotError> {
    let fit = &trend.fit;
    let title = format!(
        "n against {}: slope {:.3} ± {:.3} (95 % CI {:.3} … {:.3}), R² = {:.2}",
        trend.property.label(),
        fit.slope,
        fit.slope_std_error,
        fit.slope_ci95.0,
        fit.slope_ci95.1,
        fit.r_squared
    );
    let input = |reason: &str| StudyPlotError::Input {
        figure: title.clone(),
        reason: reason.into(),
    };
    let pts: Vec<(f64, f64)> = trend
        .points
        .iter()
        .map(|p| (p.1, p.2))
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    if pts.is_empty() {
        return Err(input("no finite points"));
    }
    let fold = |f: fn(&(f64, f64)) -> f64| {
        pts.iter()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            })
    };
    let (xl, xh) = fold(|p| p.0);
    let (yl, yh) = fold(|p| p.1);
    let line = [(xl, fit.predict(xl)), (xh, fit.predict(xh))];
    let (yl, yh) = (
        yl.min(line[0].1).min(line[1].1),
        yh.max(line[0].1).max(line[1].1),
    );
    let (x0, x1) = padded(xl, xh);
    let (y0, y1) = padded(yl, yh);
    render(&title, |root| {
        draw_trend(root, trend, &title, &pts, line, (x0, x1), (y0, y1))
    })
}

/// Draws the points and fitted line of a trend (fig. 3.16).
fn draw_trend<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    trend: &Trend,
    title: &str,
    pts: &[(f64, f64)],
    line: [(f64, f64); 2],
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Result<(), String> {
    root.fill(&WHITE).map_err(e2s)?;
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, 17))
        .margin(16)
        .x_label_area_size(56)
        .y_label_area_size(72)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .x_desc(trend.property.label())
        .y_desc("energy exponent n")
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .draw()
        .map_err(e2s)?;
    chart
        .draw_series(
            pts.iter()
                .map(|&p| Circle::new(p, 4, SERIES_COLOURS[0].filled())),
        )
        .map_err(e2s)?;
    chart
        .draw_series(std::iter::once(PathElement::new(
            line.to_vec(),
            BLACK.stroke_width(2),
        )))
        .map_err(e2s)?;
    Ok(())
}

/// Fig. 3.16: the three trend plots (log10 E, ν, μ) for Euler's disk (Table B.1),
/// fitted to every spin.
pub fn figure_3_16(
    records: &[ExponentRecord],
    materials: &[MaterialProperties],
) -> Result<Vec<(Trend, String)>, StudyPlotError> {
    material_trends(records, materials, DiskSetup::Euler, TrendPoints::EverySpin)?
        .into_iter()
        .map(|t| {
            let svg = trend_plot_svg(&t)?;
            Ok((t, svg))
        })
        .collect()
}

/// Writes an SVG string to `path` atomically.
pub fn write_svg(path: &Path, svg: &str) -> Result<(), StudyPlotError> {
    crate::output::write_atomic(path, svg.as_bytes())?;
    Ok(())
}

#[cfg(test)]
mod stats_tests {
    use super::*;
    use crate::stats::{materials, published_exponents};

    /// Number of filled rectangles in `colour` (the boxes).
    fn count_boxes(svg: &str, colour: RGBColor) -> usize {
        let fill = format!("fill=\"#{:02X}{:02X}{:02X}\"", colour.0, colour.1, colour.2);
        svg.split("<rect")
            .skip(1)
            .filter(|r| {
                r.split('>')
                    .next()
                    .is_some_and(|attrs| attrs.contains(&fill))
            })
            .count()
    }

    #[test]
    fn figure_3_15_has_one_box_per_material_and_one_outlier() {
        let recs = published_exponents().unwrap();
        let plot = figure_3_15(&recs).unwrap();
        let svg = box_plot_svg(&plot).unwrap();
        assert!(svg.trim_end().ends_with("</svg>"));
        assert_eq!(count_boxes(&svg, SERIES_COLOURS[0]), 8);
        for m in ["mild steel", "stainless steel", "silicone", "concave"] {
            assert!(svg.contains(m), "missing label {m}");
        }
        // One outlier (stainless steel, 0.3053): a cross is two red line segments.
        let red = svg.matches("stroke=\"#DC0000\"").count();
        assert_eq!(red, 2, "red elements: {red}");
    }

    #[test]
    fn figure_3_17_has_one_box_per_disk_and_material() {
        let recs = published_exponents().unwrap();
        let plot = figure_3_17(&recs).unwrap();
        assert_eq!(plot.categories.len(), 7, "{:?}", plot.categories);
        let svg = box_plot_svg(&plot).unwrap();
        for colour in &SERIES_COLOURS[..3] {
            assert_eq!(count_boxes(&svg, *colour), 7);
        }
        for name in ["Euler", "Euler flipped", "Brass"] {
            assert!(svg.contains(name));
        }
        // A missing box is allowed and simply not drawn.
        let mut plot = plot;
        plot.series[2].boxes[0] = None;
        let svg = box_plot_svg(&plot).unwrap();
        assert_eq!(count_boxes(&svg, SERIES_COLOURS[2]), 6);
    }

    #[test]
    fn trend_plots_and_input_errors() {
        let recs = published_exponents().unwrap();
        let mats = materials().unwrap();
        let figs = figure_3_16(&recs, &mats).unwrap();
        assert_eq!(figs.len(), 3);
        for (trend, svg) in &figs {
            // 84 points, one circle each.
            assert_eq!(svg.matches("<circle").count(), trend.points.len());
            assert!(svg.contains("R² ="));
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("fig3_16a.svg");
        write_svg(&path, &figs[0].1).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), figs[0].1);

        let bad = BoxPlot {
            title: "bad".into(),
            y_label: "n".into(),
            categories: vec!["a".into()],
            series: vec![BoxSeries {
                name: "s".into(),
                boxes: vec![],
            }],
        };
        let err = box_plot_svg(&bad).unwrap_err();
        assert!(err.to_string().contains("1 categories"), "{err}");
    }
}
