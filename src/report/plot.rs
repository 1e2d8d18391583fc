//! Stacked time-series figures, written as SVG and PNG.
//!
//! [`time_panels`] draws one or more [`Panel`]s (a y-quantity against time each)
//! stacked vertically and sharing one time axis, in the style of the thesis's
//! figures of slip phases: the curve is drawn in blue, every sample whose time lies
//! inside one of the [`Highlight`] intervals is redrawn in red on top, the intervals
//! are lightly shaded, and a small legend ("rolling" / `highlight_name`) is shown in
//! the top panel when there are highlights.
//!
//! Robustness:
//! * non-finite samples (NaN, ±inf, and non-positive values on a log axis) are skipped;
//! * constant series get a padded y-range, so they show as a flat line mid-panel;
//! * long series are decimated to the min and max of each pixel column
//!   (≤ 2 points per column, ≤ ~2,200 points per panel), so spikes survive;
//! * both files are written atomically: drawn to a temporary file in the target
//!   directory, then renamed over `<stem>.svg` / `<stem>.png`.
//!
//! Fonts: the SVG only names the `sans-serif` family in its `<text>` elements and
//! does not depend on any font file. The PNG's text is rasterised with DejaVu Sans,
//! embedded in the binary from `data/fonts/DejaVuSans.ttf` (Bitstream Vera licence,
//! see `data/fonts/DejaVuSans-LICENSE.txt`) and registered with plotters' `ab_glyph`
//! font backend, so no system fonts or fontconfig are needed.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use image::ImageEncoder;
use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// One stacked panel: a y-quantity against time.
#[derive(Debug, Clone, Copy)]
pub struct Panel<'a> {
    /// Y-axis label, e.g. `"φ [rad]"`.
    pub label: &'a str,
    /// One value per time sample (same length as `t`).
    pub values: &'a [f64],
    /// Logarithmic y-axis (non-positive values are skipped).
    pub log_y: bool,
}

/// A time interval to shade/colour (e.g. a slip phase). Its legend name is the
/// `highlight_name` given to [`time_panels`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Highlight {
    pub start: f64,
    pub end: f64,
}

/// Why a figure could not be written; every variant names the file concerned.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The inputs cannot be plotted (no panels, mismatched lengths, ...).
    #[error("cannot plot {}: {reason}", path.display())]
    Input { path: PathBuf, reason: String },
    /// plotters failed while drawing or encoding the figure.
    #[error("drawing {} failed: {reason}", path.display())]
    Draw { path: PathBuf, reason: String },
    /// Creating the directory, writing the temporary file or renaming it failed.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
}

/// Figure width in pixels (PNG) / user units (SVG).
const WIDTH: u32 = 1200;
/// Height of the title strip.
const TITLE_H: u32 = 48;
/// Height of each panel's share of the figure.
const PANEL_H: u32 = 220;
/// Extra height below the bottom panel for the time tick labels and axis label.
const X_AXIS_H: u32 = 64;
/// Width of the y tick labels + y-axis label.
const Y_LABEL_W: u32 = 100;
const LEFT_MARGIN: u32 = 8;
const RIGHT_MARGIN: u32 = 24;
const PANEL_GAP: u32 = 10;
/// Pixel columns of the plotting area (the decimation resolution).
const PLOT_COLUMNS: usize = (WIDTH - Y_LABEL_W - LEFT_MARGIN - RIGHT_MARGIN) as usize;

const FONT_FAMILY: &str = "sans-serif";

/// Curve colour outside highlights.
const BASE_COLOR: RGBColor = RGBColor(0, 0, 255);
/// Colour of samples inside highlights (and of the legend entry).
const HIGHLIGHT_COLOR: RGBColor = RGBColor(220, 0, 0);
/// Legend name of the samples outside the highlights.
const BASE_NAME: &str = "rolling";

/// Pixel size `(width, height)` of the PNG written for `n_panels` panels (and the
/// SVG's `width`/`height`).
pub fn figure_size(n_panels: usize) -> (u32, u32) {
    let n = u32::try_from(n_panels.max(1)).unwrap_or(u32::MAX / PANEL_H);
    (WIDTH, TITLE_H + n * PANEL_H + X_AXIS_H)
}

/// Where the time axis of a [`time_panels`] figure of times `t` lies: the times
/// at the plot areas' left and right edges and their `x` in the SVG's pixels,
/// `(t0, t1, x0, x1)`, for a page that maps a click on the figure to an instant.
pub fn time_axis_px(t: &[f64]) -> (f64, f64, f64, f64) {
    let (t0, t1) = time_range(t);
    let left = LEFT_MARGIN + Y_LABEL_W;
    // plotters maps the range onto the area's first to last pixel column.
    (t0, t1, f64::from(left), f64::from(WIDTH - RIGHT_MARGIN - 1))
}

/// Writes `<stem>.svg` and `<stem>.png`: `panels` stacked vertically sharing the
/// time axis `t` (labelled `time_label`), each curve drawn in blue with the samples
/// inside any of `highlights` drawn in red on top, and — when there are highlights —
/// a small legend "rolling" / `highlight_name`. Returns `[svg_path, png_path]`.
///
/// Every panel's `values` must have the same length as `t`. Non-finite times or
/// values are skipped. The parent directory of `stem` is created if missing.
pub fn time_panels(
    stem: &Path,
    title: &str,
    time_label: &str,
    t: &[f64],
    panels: &[Panel],
    highlights: &[Highlight],
    highlight_name: &str,
) -> Result<[PathBuf; 2], PlotError> {
    let svg_path = with_suffix(stem, "svg");
    let png_path = with_suffix(stem, "png");
    let input_err = |reason: String| PlotError::Input {
        path: svg_path.clone(),
        reason,
    };
    if panels.is_empty() {
        return Err(input_err("no panels to draw".into()));
    }
    for p in panels {
        if p.values.len() != t.len() {
            return Err(input_err(format!(
                "panel {:?} has {} values but there are {} time samples",
                p.label,
                p.values.len(),
                t.len()
            )));
        }
    }
    ensure_font().map_err(|reason| PlotError::Draw {
        path: png_path.clone(),
        reason,
    })?;

    let fig = Figure::prepare(title, time_label, t, panels, highlights, highlight_name);
    let size = figure_size(panels.len());

    let dir = match stem.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    crate::output::create_folder(&dir)?;

    // SVG
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        fig.render(&root).map_err(|reason| PlotError::Draw {
            path: svg_path.clone(),
            reason,
        })?;
        root.present().map_err(|e| PlotError::Draw {
            path: svg_path.clone(),
            reason: e.to_string(),
        })?;
    }
    crate::output::write_atomic(&svg_path, svg.as_bytes())?;

    // PNG
    let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        fig.render(&root).map_err(|reason| PlotError::Draw {
            path: png_path.clone(),
            reason,
        })?;
        root.present().map_err(|e| PlotError::Draw {
            path: png_path.clone(),
            reason: e.to_string(),
        })?;
    }
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(&rgb, size.0, size.1, image::ExtendedColorType::Rgb8)
        .map_err(|e| PlotError::Draw {
            path: png_path.clone(),
            reason: format!("PNG encoding: {e}"),
        })?;
    crate::output::write_atomic(&png_path, &png)?;

    Ok([svg_path, png_path])
}

/// `stem` with `.ext` appended (not replacing a dot already in the file name).
fn with_suffix(stem: &Path, ext: &str) -> PathBuf {
    let mut s = stem.as_os_str().to_owned();
    s.push(".");
    s.push(ext);
    PathBuf::from(s)
}

/// Registers the embedded font with plotters once per process.
pub(crate) fn ensure_font() -> Result<(), String> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        // Also register the other generic families so nothing falls through to a
        // "font unavailable" error if a style names them.
        [FONT_FAMILY, "serif", "monospace"].iter().all(|fam| {
            plotters::style::register_font(fam, FontStyle::Normal, crate::overlay::FONT_BYTES)
                .is_ok()
        })
    });
    if ok {
        Ok(())
    } else {
        Err("the embedded font DejaVuSans.ttf could not be loaded".into())
    }
}

/// The y-range of one panel.
#[derive(Debug, Clone, Copy, PartialEq)]
enum YRange {
    Linear(f64, f64),
    Log(f64, f64),
}

/// One panel, ready to draw (shared by the SVG and PNG renderings).
struct PreparedPanel<'a> {
    label: &'a str,
    y: YRange,
    /// Whether the panel had no plottable sample at all.
    empty: bool,
    /// Decimated full series (blue).
    base: Vec<(f64, f64)>,
    /// Decimated runs of consecutive samples inside highlights (red).
    highlighted: Vec<Vec<(f64, f64)>>,
}

struct Figure<'a> {
    title: &'a str,
    time_label: &'a str,
    highlight_name: &'a str,
    x: (f64, f64),
    /// Sorted, merged, finite highlight intervals.
    intervals: Vec<(f64, f64)>,
    panels: Vec<PreparedPanel<'a>>,
}

impl<'a> Figure<'a> {
    fn prepare(
        title: &'a str,
        time_label: &'a str,
        t: &[f64],
        panels: &[Panel<'a>],
        highlights: &[Highlight],
        highlight_name: &'a str,
    ) -> Self {
        let (x0, x1) = time_range(t);
        let intervals = merge_intervals(highlights);
        let runs = highlight_runs(t, &intervals);
        let panels = panels
            .iter()
            .map(|p| {
                let v = p.values;
                let log = p.log_y;
                let valid = |i: usize| t[i].is_finite() && v[i].is_finite() && (!log || v[i] > 0.0);
                let (lo, hi, count) = (0..t.len()).filter(|&i| valid(i)).fold(
                    (f64::INFINITY, f64::NEG_INFINITY, 0usize),
                    |(lo, hi, n), i| (lo.min(v[i]), hi.max(v[i]), n + 1),
                );
                let empty = count == 0;
                let y = if log {
                    let (lo, hi) = if empty { (1.0, 10.0) } else { (lo, hi) };
                    let (lo, hi) = pad_log(lo, hi);
                    YRange::Log(lo, hi)
                } else {
                    let (lo, hi) = if empty { (0.0, 1.0) } else { (lo, hi) };
                    let (lo, hi) = pad_linear(lo, hi);
                    YRange::Linear(lo, hi)
                };
                let base = decimate(t, v, 0..t.len(), &valid, x0, x1, PLOT_COLUMNS);
                let highlighted = runs
                    .iter()
                    .map(|r| decimate(t, v, r.clone(), &valid, x0, x1, PLOT_COLUMNS))
                    .filter(|pts| !pts.is_empty())
                    .collect();
                PreparedPanel {
                    label: p.label,
                    y,
                    empty,
                    base,
                    highlighted,
                }
            })
            .collect();
        Figure {
            title,
            time_label,
            highlight_name,
            x: (x0, x1),
            intervals,
            panels,
        }
    }

    fn render<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (title_area, mut rest) = root.split_vertically(TITLE_H);
        let (w, h) = title_area.dim_in_pixel();
        let title_style = TextStyle::from((FONT_FAMILY, 22).into_font())
            .color(&BLACK)
            .pos(Pos::new(HPos::Center, VPos::Center));
        title_area
            .draw(&Text::new(
                self.title,
                (w as i32 / 2, h as i32 / 2 + 4),
                title_style,
            ))
            .map_err(|e| e.to_string())?;

        let n = self.panels.len();
        for (i, panel) in self.panels.iter().enumerate() {
            let area = if i + 1 < n {
                let (a, r) = rest.split_vertically(PANEL_H);
                rest = r;
                a
            } else {
                rest.clone()
            };
            let bottom = i + 1 == n;
            let top = i == 0;
            match panel.y {
                YRange::Linear(lo, hi) => {
                    let span = hi - lo;
                    let fmt = move |v: &f64| fmt_linear_tick(*v, span);
                    self.draw_panel(&area, panel, lo..hi, (lo, hi), &fmt, top, bottom)?
                }
                YRange::Log(lo, hi) => {
                    let fmt = |v: &f64| fmt_sig(*v, 3);
                    self.draw_panel(
                        &area,
                        panel,
                        (lo..hi).log_scale(),
                        (lo, hi),
                        &fmt,
                        top,
                        bottom,
                    )?
                }
            }
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn draw_panel<DB, Y>(
        &self,
        area: &DrawingArea<DB, Shift>,
        panel: &PreparedPanel,
        y_spec: Y,
        (ylo, yhi): (f64, f64),
        y_fmt: &dyn Fn(&f64) -> String,
        top: bool,
        bottom: bool,
    ) -> Result<(), String>
    where
        DB: DrawingBackend,
        Y: AsRangedCoord<Value = f64>,
        Y::CoordDescType: ValueFormatter<f64>,
    {
        let (x0, x1) = self.x;
        let x_span = x1 - x0;
        let x_fmt = move |v: &f64| fmt_linear_tick(*v, x_span);

        let mut chart = ChartBuilder::on(area)
            .margin_top(PANEL_GAP)
            .margin_left(LEFT_MARGIN)
            .margin_right(RIGHT_MARGIN)
            .y_label_area_size(Y_LABEL_W)
            .x_label_area_size(if bottom { X_AXIS_H } else { 0 })
            .build_cartesian_2d(x0..x1, y_spec)
            .map_err(drawing_error)?;

        {
            let mut mesh = chart.configure_mesh();
            mesh.x_labels(12)
                .y_labels(6)
                .x_label_formatter(&x_fmt)
                .y_label_formatter(y_fmt)
                .label_style((FONT_FAMILY, 14))
                .axis_desc_style((FONT_FAMILY, 16))
                .bold_line_style(RGBColor(215, 215, 215))
                .light_line_style(RGBColor(240, 240, 240))
                .y_desc(panel.label);
            if bottom {
                mesh.x_desc(self.time_label);
            }
            mesh.draw().map_err(drawing_error)?;
        }

        self.shade_highlights(&mut chart, (ylo, yhi))?;
        // The legend sits in the top panel, when there is something to tell apart.
        let with_legend = top && !self.intervals.is_empty();
        draw_base(&mut chart, panel, with_legend)?;
        draw_highlighted(&mut chart, panel)?;
        if panel.empty {
            self.mark_empty(&mut chart, panel)?;
        }
        if with_legend {
            self.draw_legend(&mut chart)?;
        }
        Ok(())
    }

    /// Shades the highlight intervals, clipped to the time axis, over the panel's
    /// height `(ylo, yhi)`.
    fn shade_highlights<DB: DrawingBackend, YC: Ranged<ValueType = f64>>(
        &self,
        chart: &mut PanelChart<'_, DB, YC>,
        (ylo, yhi): (f64, f64),
    ) -> Result<(), String> {
        let (x0, x1) = self.x;
        let shade = HIGHLIGHT_COLOR.mix(0.10).filled();
        chart
            .draw_series(self.intervals.iter().filter_map(|&(a, b)| {
                let (a, b) = (a.max(x0), b.min(x1));
                (a <= b).then(|| Rectangle::new([(a, ylo), (b, yhi)], shade))
            }))
            .map_err(drawing_error)?;
        Ok(())
    }

    /// Writes "no finite data" in the middle of a panel without a plottable sample.
    fn mark_empty<DB: DrawingBackend, YC: Ranged<ValueType = f64>>(
        &self,
        chart: &mut PanelChart<'_, DB, YC>,
        panel: &PreparedPanel,
    ) -> Result<(), String> {
        let (x0, x1) = self.x;
        let ymid = match panel.y {
            YRange::Linear(lo, hi) => 0.5 * (lo + hi),
            YRange::Log(lo, hi) => (lo * hi).sqrt(),
        };
        let style = TextStyle::from((FONT_FAMILY, 16).into_font())
            .color(&RGBColor(120, 120, 120))
            .pos(Pos::new(HPos::Center, VPos::Center));
        chart
            .draw_series(std::iter::once(Text::new(
                "no finite data",
                (0.5 * (x0 + x1), ymid),
                style,
            )))
            .map_err(drawing_error)?;
        Ok(())
    }

    /// The legend, upper right: the full series in blue (labelled when it was
    /// drawn), the highlights' samples in red.
    fn draw_legend<'c, DB: DrawingBackend + 'c, YC: Ranged<ValueType = f64>>(
        &self,
        chart: &mut PanelChart<'c, DB, YC>,
    ) -> Result<(), String> {
        chart
            .draw_series(LineSeries::new(
                std::iter::empty::<(f64, f64)>(),
                HIGHLIGHT_COLOR.stroke_width(2),
            ))
            .map_err(drawing_error)?
            .label(self.highlight_name)
            .legend(|(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], HIGHLIGHT_COLOR.stroke_width(2))
            });
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .margin(8)
            .legend_area_size(26)
            .label_font((FONT_FAMILY, 14))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .draw()
            .map_err(drawing_error)?;
        Ok(())
    }
}

/// A panel's chart: linear time across, `YC` (linear or logarithmic) up.
type PanelChart<'a, DB, YC> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, YC>>;

/// A drawing error as text.
fn drawing_error<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> String {
    e.to_string()
}

/// The full curve in blue (a dot when it is a single sample), labelled for the
/// legend when `with_legend`.
fn draw_base<DB: DrawingBackend, YC: Ranged<ValueType = f64>>(
    chart: &mut PanelChart<'_, DB, YC>,
    panel: &PreparedPanel,
    with_legend: bool,
) -> Result<(), String> {
    let base_style = BASE_COLOR.stroke_width(1);
    let anno = chart
        .draw_series(LineSeries::new(panel.base.iter().copied(), base_style))
        .map_err(drawing_error)?;
    if with_legend {
        anno.label(BASE_NAME).legend(|(x, y)| {
            PathElement::new(vec![(x, y), (x + 20, y)], BASE_COLOR.stroke_width(2))
        });
    }
    if panel.base.len() == 1 {
        chart
            .draw_series(std::iter::once(Circle::new(
                panel.base[0],
                2,
                BASE_COLOR.filled(),
            )))
            .map_err(drawing_error)?;
    }
    Ok(())
}

/// The samples inside highlights in red, on top of the full curve: each run a
/// line, or a dot when it is a single sample.
fn draw_highlighted<DB: DrawingBackend, YC: Ranged<ValueType = f64>>(
    chart: &mut PanelChart<'_, DB, YC>,
    panel: &PreparedPanel,
) -> Result<(), String> {
    let red = HIGHLIGHT_COLOR.stroke_width(2);
    for run in &panel.highlighted {
        if run.len() == 1 {
            chart
                .draw_series(std::iter::once(Circle::new(
                    run[0],
                    2,
                    HIGHLIGHT_COLOR.filled(),
                )))
                .map_err(drawing_error)?;
        } else {
            chart
                .draw_series(LineSeries::new(run.iter().copied(), red))
                .map_err(drawing_error)?;
        }
    }
    Ok(())
}

/// Range of the finite times, padded when degenerate; `(0, 1)` when there are none.
fn time_range(t: &[f64]) -> (f64, f64) {
    let (lo, hi) = t
        .iter()
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
            (lo.min(x), hi.max(x))
        });
    if lo > hi {
        return (0.0, 1.0);
    }
    if lo < hi && (hi - lo).is_finite() {
        return (lo, hi);
    }
    pad_linear(lo, hi)
}

/// Pads a linear range by 5 % of its span, or — for a constant series — by 5 % of
/// its magnitude (1 if zero), so the line sits mid-panel.
fn pad_linear(lo: f64, hi: f64) -> (f64, f64) {
    let span = hi - lo;
    let mag = lo.abs().max(hi.abs());
    let pad = if span > mag * 1e-12 && span.is_finite() {
        0.05 * span
    } else if mag > 0.0 {
        0.05 * mag
    } else {
        1.0
    };
    let (a, b) = (lo - pad, hi + pad);
    if a.is_finite() && b.is_finite() && a < b {
        (a, b)
    } else if lo.is_finite() && hi.is_finite() && lo < hi {
        (lo, hi)
    } else {
        (-1.0, 1.0)
    }
}

/// Pads a positive log range by 5 % of its span in decades, or a factor of 2 for a
/// constant series.
fn pad_log(lo: f64, hi: f64) -> (f64, f64) {
    let ratio = hi / lo;
    let f = if ratio > 1.0 + 1e-12 && ratio.is_finite() {
        ratio.powf(0.05)
    } else {
        2.0
    };
    let (a, b) = (lo / f, hi * f);
    if a > 0.0 && b.is_finite() && a < b {
        (a, b)
    } else if lo > 0.0 && hi.is_finite() && lo < hi {
        (lo, hi)
    } else {
        (1.0, 10.0)
    }
}

/// Finite highlight intervals (reversed ones swapped), sorted and merged.
fn merge_intervals(highlights: &[Highlight]) -> Vec<(f64, f64)> {
    let mut iv: Vec<(f64, f64)> = highlights
        .iter()
        .filter(|h| h.start.is_finite() && h.end.is_finite())
        .map(|h| (h.start.min(h.end), h.start.max(h.end)))
        .collect();
    iv.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut merged: Vec<(f64, f64)> = Vec::with_capacity(iv.len());
    for (a, b) in iv {
        match merged.last_mut() {
            Some(last) if a <= last.1 => last.1 = last.1.max(b),
            _ => merged.push((a, b)),
        }
    }
    merged
}

/// Index of the interval among the sorted, disjoint closed `intervals` that
/// contains `x`, if any.
fn interval_of(intervals: &[(f64, f64)], x: f64) -> Option<usize> {
    let k = intervals.partition_point(|&(a, _)| a <= x);
    (k > 0 && x <= intervals[k - 1].1).then(|| k - 1)
}

/// Index ranges of consecutive samples whose (finite) time lies in the same
/// highlight interval (a run never bridges the gap between two intervals).
fn highlight_runs(t: &[f64], intervals: &[(f64, f64)]) -> Vec<Range<usize>> {
    let mut runs = Vec::new();
    if intervals.is_empty() {
        return runs;
    }
    // (first index, interval) of the current run
    let mut current: Option<(usize, usize)> = None;
    for (i, &x) in t.iter().enumerate() {
        let which = if x.is_finite() {
            interval_of(intervals, x)
        } else {
            None
        };
        match (current, which) {
            (Some((_, k)), Some(w)) if k == w => {}
            (Some((s, _)), w) => {
                runs.push(s..i);
                current = w.map(|w| (i, w));
            }
            (None, w) => current = w.map(|w| (i, w)),
        }
    }
    if let Some((s, _)) = current {
        runs.push(s..t.len());
    }
    runs
}

/// The points `(t[i], v[i])` for `i` in `idx` with `valid(i)`, in order. When there
/// are more than `2 * columns` of them, they are reduced to the minimum and maximum
/// value of each of `columns` equal time bins over `x0..x1` (in their original
/// order), so the result has at most `2 * columns` points per time-ordered series
/// and every local extreme that would be visible on screen is kept.
fn decimate(
    t: &[f64],
    v: &[f64],
    idx: Range<usize>,
    valid: &dyn Fn(usize) -> bool,
    x0: f64,
    x1: f64,
    columns: usize,
) -> Vec<(f64, f64)> {
    let columns = columns.max(1);
    let count = idx.clone().filter(|&i| valid(i)).count();
    if count <= 2 * columns {
        return idx.filter(|&i| valid(i)).map(|i| (t[i], v[i])).collect();
    }
    let span = x1 - x0;
    let column_of = |x: f64| -> usize {
        let c = if span > 0.0 {
            ((x - x0) / span * columns as f64).floor()
        } else {
            0.0
        };
        // NaN-safe clamp (NaN casts to 0).
        (c.max(0.0) as usize).min(columns - 1)
    };
    let mut out = Vec::with_capacity(2 * columns + 2);
    let flush = |out: &mut Vec<(f64, f64)>, lo: usize, hi: usize| {
        let (a, b) = if lo <= hi { (lo, hi) } else { (hi, lo) };
        out.push((t[a], v[a]));
        if b != a {
            out.push((t[b], v[b]));
        }
    };
    // (column, index of min, index of max)
    let mut bin: Option<(usize, usize, usize)> = None;
    for i in idx.filter(|&i| valid(i)) {
        let c = column_of(t[i]);
        bin = match bin {
            Some((bc, lo, hi)) if bc == c => Some((
                bc,
                if v[i] < v[lo] { i } else { lo },
                if v[i] > v[hi] { i } else { hi },
            )),
            Some((_, lo, hi)) => {
                flush(&mut out, lo, hi);
                Some((c, i, i))
            }
            None => Some((c, i, i)),
        };
    }
    if let Some((_, lo, hi)) = bin {
        flush(&mut out, lo, hi);
    }
    out
}

/// Tick label for a linear axis whose range spans `span`: fixed-point with enough
/// decimals for the tick spacing, or scientific for very large/small magnitudes.
fn fmt_linear_tick(v: f64, span: f64) -> String {
    let step = (span / 10.0).abs();
    if v == 0.0 || !v.is_finite() {
        return if v == 0.0 { "0".into() } else { format!("{v}") };
    }
    if step > 0.0 && v.abs() < step * 1e-6 {
        // A tick that should be zero but carries rounding noise.
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        let digits = if step > 0.0 && step.is_finite() {
            ((a.log10() - step.log10()).ceil() as i64 + 1).clamp(1, 10) as usize
        } else {
            4
        };
        return fmt_sig(v, digits);
    }
    let decimals = if step > 0.0 && step.is_finite() {
        (-(step.log10() + 1e-9).floor()).clamp(0.0, 12.0) as usize
    } else {
        3
    };
    trim_zeros(format!("{v:.decimals$}"))
}

/// Removes trailing zeros after a decimal point (`"0.250"` → `"0.25"`, `"3.0"` → `"3"`).
fn trim_zeros(s: String) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// `v` in scientific notation with `digits` significant digits, trailing zeros of
/// the mantissa removed (`1e-3`, `2.5e4`); plain for magnitudes in `[1e-3, 1e5)`.
pub(crate) fn fmt_sig(v: f64, digits: usize) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = digits.max(1);
    if (1e-3..1e5).contains(&a) {
        let decimals = (digits as i64 - 1 - a.log10().floor() as i64).max(0) as usize;
        return trim_zeros(format!("{v:.decimals$}"));
    }
    let s = format!("{:.*e}", digits - 1, v);
    match s.split_once('e') {
        Some((m, e)) if m.contains('.') => {
            format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
        }
        _ => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn is_red(p: &image::Rgb<u8>) -> bool {
        p[0] > 180 && p[1] < 90 && p[2] < 90
    }

    fn count_red(img: &image::RgbImage) -> usize {
        img.pixels().filter(|p| is_red(p)).count()
    }

    /// A crude well-formedness check: every `<tag>` is closed in order.
    fn assert_xmlish(svg: &str) {
        assert!(svg.trim_start().starts_with("<svg") || svg.contains("<svg"));
        assert!(svg.trim_end().ends_with("</svg>"));
        let mut stack: Vec<String> = Vec::new();
        let mut rest = svg;
        while let Some(open) = rest.find('<') {
            let close = rest[open..].find('>').expect("unterminated tag") + open;
            let tag = &rest[open + 1..close];
            rest = &rest[close + 1..];
            if tag.starts_with('?') || tag.starts_with('!') {
                continue;
            }
            if let Some(name) = tag.strip_prefix('/') {
                let top = stack.pop().expect("closing tag without opening");
                assert_eq!(top, name.trim(), "mismatched closing tag");
            } else if !tag.ends_with('/') {
                let name = tag.split_whitespace().next().unwrap_or("").to_string();
                stack.push(name);
            }
        }
        assert!(stack.is_empty(), "unclosed tags: {stack:?}");
    }

    struct Series {
        t: Vec<f64>,
        phi: Vec<f64>,
        omega: Vec<f64>,
        energy: Vec<f64>,
        flat: Vec<f64>,
    }

    fn series(n: usize) -> Series {
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
        let phi = t
            .iter()
            .map(|&x| 0.3 * (-0.1 * x).exp() * (5.0 * x).sin())
            .collect();
        let mut omega: Vec<f64> = t.iter().map(|&x| 20.0 + 5.0 * (0.7 * x).cos()).collect();
        omega[10] = f64::NAN;
        omega[20] = f64::INFINITY;
        let energy = t
            .iter()
            .map(|&x| 1e-3 * (1.0 + 100.0 * (-x).exp()))
            .collect();
        let flat = vec![2.5; n];
        Series {
            t,
            phi,
            omega,
            energy,
            flat,
        }
    }

    fn panels(s: &Series) -> Vec<Panel<'_>> {
        vec![
            Panel {
                label: "φ [rad]",
                values: &s.phi,
                log_y: false,
            },
            Panel {
                label: "ω [rad/s]",
                values: &s.omega,
                log_y: false,
            },
            Panel {
                label: "E [J]",
                values: &s.energy,
                log_y: true,
            },
            Panel {
                label: "flat",
                values: &s.flat,
                log_y: false,
            },
        ]
    }

    #[test]
    fn writes_svg_and_png_with_highlights() {
        let dir = tempfile::tempdir().unwrap();
        let s = series(6000);
        let p = panels(&s);
        let hl = [
            Highlight {
                start: 5.0,
                end: 12.0,
            },
            Highlight {
                start: 40.0,
                end: 41.5,
            },
        ];
        let stem = dir.path().join("sub").join("run1.v2");
        let [svg_path, png_path] =
            time_panels(&stem, "Disk run 1", "t [s]", &s.t, &p, &hl, "slipping").unwrap();
        assert_eq!(svg_path, dir.path().join("sub/run1.v2.svg"));
        assert_eq!(png_path, dir.path().join("sub/run1.v2.png"));
        assert!(svg_path.is_file() && png_path.is_file());

        // No temporary files are left behind.
        let leftovers: Vec<_> = std::fs::read_dir(dir.path().join("sub"))
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .filter(|n| n.to_string_lossy().ends_with(".tmp"))
            .collect();
        assert!(leftovers.is_empty(), "{leftovers:?}");

        let img = image::open(&png_path).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), figure_size(p.len()));
        let non_white = img.pixels().filter(|px| px.0 != [255, 255, 255]).count();
        assert!(
            non_white > 10_000,
            "PNG looks blank ({non_white} non-white pixels)"
        );
        let blue = img
            .pixels()
            .filter(|px| px[2] > 180 && px[0] < 90 && px[1] < 90)
            .count();
        assert!(blue > 500, "too few blue pixels: {blue}");
        assert!(
            count_red(&img) > 200,
            "too few red pixels: {}",
            count_red(&img)
        );

        // Red pixels lie (mostly) in the highlighted time columns: column 0 of the
        // plot is t=0, so nothing red should appear in the t∈(15, 38) stretch.
        let plot_x0 = (LEFT_MARGIN + Y_LABEL_W) as f64;
        let px_per_s = PLOT_COLUMNS as f64 / 59.99;
        let (a, b) = (
            (plot_x0 + 15.0 * px_per_s) as u32,
            (plot_x0 + 38.0 * px_per_s) as u32,
        );
        let legend_y = TITLE_H + PANEL_H / 2; // legend lives in the top half of panel 1
        let stray = img
            .enumerate_pixels()
            .filter(|(x, y, px)| *x > a && *x < b && *y > legend_y && is_red(px))
            .count();
        assert_eq!(stray, 0, "red pixels outside highlights");

        let svg = std::fs::read_to_string(&svg_path).unwrap();
        assert_xmlish(&svg);
        for label in [
            "Disk run 1",
            "t [s]",
            "φ [rad]",
            "ω [rad/s]",
            "E [J]",
            "flat",
        ] {
            assert!(svg.contains(label), "SVG lacks {label:?}");
        }
        assert!(svg.contains("rolling") && svg.contains("slipping"));
    }

    #[test]
    fn no_highlights_means_no_red_and_no_legend() {
        let dir = tempfile::tempdir().unwrap();
        let s = series(3000);
        let p = panels(&s);
        let stem = dir.path().join("plain");
        let [svg_path, png_path] =
            time_panels(&stem, "a < b & c", "time [s]", &s.t, &p, &[], "slipping").unwrap();
        let img = image::open(&png_path).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), figure_size(p.len()));
        assert!(img.pixels().any(|px| px.0 != [255, 255, 255]));
        assert_eq!(count_red(&img), 0);
        let svg = std::fs::read_to_string(&svg_path).unwrap();
        assert_xmlish(&svg);
        assert!(!svg.contains("slipping") && !svg.contains("rolling"));
        assert!(svg.contains("time [s]") && svg.contains("a &lt; b &amp; c"));
    }

    #[test]
    fn degenerate_inputs_still_draw() {
        let dir = tempfile::tempdir().unwrap();
        // All-NaN panel, a single sample, a log panel with no positive values.
        let t = [0.0, f64::NAN, 1.0];
        let nan = [f64::NAN; 3];
        let one = [f64::NAN, f64::NAN, 4.0];
        let neg = [-1.0, 0.0, -3.0];
        let p = [
            Panel {
                label: "nan",
                values: &nan,
                log_y: false,
            },
            Panel {
                label: "one",
                values: &one,
                log_y: false,
            },
            Panel {
                label: "neg",
                values: &neg,
                log_y: true,
            },
        ];
        let hl = [Highlight {
            start: f64::NAN,
            end: 1.0,
        }];
        let [svg, png] = time_panels(&dir.path().join("d"), "", "t", &t, &p, &hl, "x").unwrap();
        assert!(svg.is_file() && png.is_file());
        assert!(
            std::fs::read_to_string(&svg)
                .unwrap()
                .contains("no finite data")
        );

        // Empty time series.
        let p = [Panel {
            label: "empty",
            values: &[],
            log_y: false,
        }];
        time_panels(&dir.path().join("e"), "e", "t", &[], &p, &[], "x").unwrap();
    }

    #[test]
    fn input_errors_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let stem = dir.path().join("bad");
        let p = [Panel {
            label: "y",
            values: &[1.0, 2.0],
            log_y: false,
        }];
        let err = time_panels(&stem, "", "t", &[0.0], &p, &[], "x").unwrap_err();
        assert!(matches!(err, PlotError::Input { .. }));
        assert!(err.to_string().contains("bad.svg"), "{err}");
        let err = time_panels(&stem, "", "t", &[0.0], &[], &[], "x").unwrap_err();
        assert!(err.to_string().contains("no panels"), "{err}");
    }

    #[test]
    fn decimation_keeps_spikes() {
        let n = 1_000_000;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 1e-3).collect();
        let mut v: Vec<f64> = (0..n).map(|i| (i as f64 * 0.001).sin()).collect();
        v[123_457] = 50.0; // one-sample spikes
        v[876_543] = -70.0;
        v[500] = f64::NAN;
        let valid = |i: usize| t[i].is_finite() && v[i].is_finite();
        let columns = 1000;
        let pts = decimate(&t, &v, 0..n, &valid, t[0], t[n - 1], columns);
        assert!(pts.len() <= 2 * columns, "{} points", pts.len());
        let max = pts.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
        let min = pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        assert_eq!(max, 50.0);
        assert_eq!(min, -70.0);
        assert!(pts.iter().all(|p| p.1.is_finite()));
        assert!(pts.windows(2).all(|w| w[0].0 <= w[1].0), "not time-ordered");
        assert!(pts.contains(&(t[123_457], 50.0)));

        // Short series are kept whole.
        let pts = decimate(&t, &v, 0..100, &valid, 0.0, 1.0, columns);
        assert_eq!(pts.len(), 100);
    }

    #[test]
    fn intervals_and_runs() {
        let iv = merge_intervals(&[
            Highlight {
                start: 5.0,
                end: 3.0,
            },
            Highlight {
                start: 1.0,
                end: 2.0,
            },
            Highlight {
                start: 4.0,
                end: 6.0,
            },
            Highlight {
                start: f64::NAN,
                end: 1.0,
            },
        ]);
        assert_eq!(iv, vec![(1.0, 2.0), (3.0, 6.0)]);
        assert_eq!(interval_of(&iv, 1.0), Some(0));
        assert_eq!(interval_of(&iv, 6.0), Some(1));
        assert_eq!(interval_of(&iv, 2.5), None);
        assert_eq!(interval_of(&iv, 0.0), None);
        let t: Vec<f64> = (0..8).map(|i| i as f64).collect();
        assert_eq!(highlight_runs(&t, &iv), vec![1..3, 3..7]);
    }

    #[test]
    fn ranges_and_ticks() {
        assert_eq!(pad_linear(2.0, 2.0), (1.9, 2.1));
        assert_eq!(pad_linear(0.0, 0.0), (-1.0, 1.0));
        let (a, b) = pad_log(5.0, 5.0);
        assert!(a < 5.0 && b > 5.0 && a > 0.0);
        assert_eq!(time_range(&[f64::NAN]), (0.0, 1.0));
        assert_eq!(fmt_linear_tick(0.30000000000000004, 1.0), "0.3");
        assert_eq!(fmt_linear_tick(0.25, 0.9), "0.25");
        assert_eq!(fmt_linear_tick(20_000.0, 50_000.0), "20000");
        assert_eq!(fmt_linear_tick(5.551115123125783e-17, 1.0), "0");
        assert_eq!(fmt_linear_tick(250_000.0, 1e6), "2.5e5");
        assert_eq!(fmt_sig(0.001, 3), "0.001");
        assert_eq!(fmt_sig(1e-6, 3), "1e-6");
    }
}
