//! Outputs of `eulerdisk compare` (thesis §4.7.1, figs. 4.15–4.16, §4.8): in
//! `EXPERIMENT_OUT/compare-<model>/`
//!
//! | file | content |
//! |---|---|
//! | `summary.json` | the [`Comparison`] without the trajectory |
//! | `model.csv` | the model's trajectory (every millisecond and the end) |
//! | `overlay.svg`, `overlay.png` | measured points, the model's curve, the model at the measured instants |
//! | `index.html` | self-contained page: options, initial state, errors, residual spin, post-flat |
//! | `model-overlay.mp4`, `model-last-turns.png`, `model-overlay.csv`, `model-overlay.json` | the model drawn over the footage ([`crate::overlay::write_model_overlay`]), when made |
//!
//! and for `--all-models` in `EXPERIMENT_OUT/compare-all/`: `ranking.json`,
//! `ranking.csv` and `index.html`.

use std::path::{Path, PathBuf};

use image::ImageEncoder;
use maud::{Markup, html};
use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Serialize;

use super::ReportError;
use super::html::{page, png_figure, svg_figure, table, video_figure};
use crate::compare::{Comparison, EtaMethod, Ranked};
use crate::model::dissipation::ModelKind;
use crate::model::simulate::Sample;
use crate::output::{write_atomic, write_csv, write_json};
use crate::overlay::ModelOverlay;

/// Colour of the measured series (green, as the thesis's figures).
const MEASURED: RGBColor = RGBColor(0, 140, 60);
/// Colour of the model (orange, as the thesis's figures).
const MODEL: RGBColor = RGBColor(230, 110, 0);
/// Overlay figure width \[px\].
const WIDTH: u32 = 1100;
/// Height per panel \[px\].
const PANEL_H: u32 = 260;

/// The kebab-case name of a model, as on the command line ("augmented-contour").
pub fn model_name(kind: ModelKind) -> String {
    serde_json::to_value(kind)
        .ok()
        .and_then(|v| v.as_str().map(str::to_owned))
        .unwrap_or_else(|| format!("{kind:?}").to_lowercase())
}

/// The folder of one model's comparison inside an experiment folder.
pub fn comparison_dir(experiment_dir: &Path, kind: ModelKind) -> PathBuf {
    experiment_dir.join(format!("compare-{}", model_name(kind)))
}

fn plot_error(e: impl std::fmt::Display) -> ReportError {
    ReportError::Plot(e.to_string())
}

/// One panel of the overlay: the model's curve, measured points and the model at
/// the measured instants, on the experiment's time axis.
struct OverlayPanel {
    label: &'static str,
    curve: Vec<(f64, f64)>,
    measured: Vec<(f64, f64)>,
    sampled: Vec<(f64, f64)>,
}

fn overlay_panels(c: &Comparison) -> Vec<OverlayPanel> {
    let lead = c.options.lead_s;
    let s = &c.trajectory.samples;
    let step = (s.len() / 3000).max(1);
    let curve = |f: fn(&Sample) -> f64| -> Vec<(f64, f64)> {
        s.iter()
            .step_by(step)
            .chain(s.last())
            .map(|x| (x.t - lead, f(x)))
            .filter(|p| p.1.is_finite())
            .collect()
    };
    let m = &c.measured;
    let mut panels = vec![
        OverlayPanel {
            label: "φ [rad]",
            curve: curve(|x| x.phi),
            measured: m.phi.iter().map(|p| (p.t, p.value)).collect(),
            sampled: c.sampled.phi.iter().map(|p| (p.t, p.value)).collect(),
        },
        OverlayPanel {
            label: "ψ̇ [rad/s]",
            curve: curve(|x| x.psi_dot),
            measured: m.psi_dot.iter().map(|p| (p.t, p.value)).collect(),
            sampled: c.sampled.psi_dot.iter().map(|p| (p.t, p.value)).collect(),
        },
    ];
    if !m.theta_dot.is_empty() {
        panels.push(OverlayPanel {
            label: "θ̇ [rad/s]",
            curve: curve(|x| x.theta_dot),
            measured: m.theta_dot.iter().map(|p| (p.t, p.value)).collect(),
            sampled: Vec::new(),
        });
    }
    if !m.beta_dot.is_empty() {
        panels.push(OverlayPanel {
            label: "β̇ [rad/s]",
            curve: curve(|x| x.beta_dot),
            measured: m.beta_dot.iter().map(|p| (p.t, p.value)).collect(),
            sampled: c.sampled.beta_dot.iter().map(|p| (p.t, p.value)).collect(),
        });
    }
    panels
}

/// y-range covering the measured points and the model within the time range, with
/// the model's spikes (e.g. ψ̇ just before the end) clipped to 3× the data's span.
fn y_range(p: &OverlayPanel, t: (f64, f64)) -> (f64, f64) {
    let data: Vec<f64> = p
        .measured
        .iter()
        .chain(&p.sampled)
        .map(|q| q.1)
        .filter(|v| v.is_finite())
        .collect();
    let model: Vec<f64> = p
        .curve
        .iter()
        .filter(|q| q.0 >= t.0 && q.0 <= t.1)
        .map(|q| q.1)
        .collect();
    let (dlo, dhi) = data
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let (mut lo, mut hi) = model
        .iter()
        .fold((dlo, dhi), |(a, b), &v| (a.min(v), b.max(v)));
    if dlo.is_finite() {
        let span = (dhi - dlo).max(1e-9);
        lo = lo.max(dlo - 3.0 * span);
        hi = hi.min(dhi + 3.0 * span);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (-1.0, 1.0);
    }
    let pad = 0.05 * (hi - lo).max(1e-9 * hi.abs().max(1.0));
    (lo - pad, hi + pad)
}

fn draw_overlay<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    panels: &[OverlayPanel],
    t: (f64, f64),
) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let root = root
        .titled(title, ("sans-serif", 20))
        .map_err(|e| e.to_string())?;
    let areas = root.split_evenly((panels.len(), 1));
    for (k, (area, p)) in areas.iter().zip(panels).enumerate() {
        let (lo, hi) = y_range(p, t);
        let mut chart = ChartBuilder::on(area)
            .margin(8)
            .x_label_area_size(if k + 1 == panels.len() { 40 } else { 18 })
            .y_label_area_size(90)
            .build_cartesian_2d(t.0..t.1, lo..hi)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc(if k + 1 == panels.len() {
                "t − t_φ [s]"
            } else {
                ""
            })
            .y_desc(p.label)
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(|e| e.to_string())?;
        let curve: Vec<(f64, f64)> = p.curve.iter().map(|&(x, y)| (x, y.clamp(lo, hi))).collect();
        chart
            .draw_series(LineSeries::new(curve, MODEL.stroke_width(1)))
            .map_err(|e| e.to_string())?
            .label("model")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], MODEL.stroke_width(2)));
        chart
            .draw_series(
                p.measured
                    .iter()
                    .map(|&q| Circle::new(q, 3, MEASURED.filled())),
            )
            .map_err(|e| e.to_string())?
            .label("measured")
            .legend(|(x, y)| Circle::new((x + 8, y), 3, MEASURED.filled()));
        if !p.sampled.is_empty() {
            chart
                .draw_series(
                    p.sampled
                        .iter()
                        .map(|&(x, y)| Cross::new((x, y.clamp(lo, hi)), 4, MODEL.stroke_width(2))),
                )
                .map_err(|e| e.to_string())?
                .label("model at the measured instants")
                .legend(|(x, y)| Cross::new((x + 8, y), 4, MODEL.stroke_width(2)));
        }
        if k == 0 {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK.mix(0.3))
                .label_font(("sans-serif", 13))
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(|e| e.to_string())?;
        }
    }
    Ok(())
}

fn overlay_title(c: &Comparison) -> String {
    let p = if c.options.model == ModelKind::AugmentedContour {
        format!(", p = {:.3}", c.dissipation.augmented_exponent)
    } else {
        String::new()
    };
    format!(
        "{} {}: η = {:.3e}{p} ({})",
        model_name(c.options.model),
        c.equation,
        c.eta,
        method_name(c.options.method)
    )
}

fn method_name(m: EtaMethod) -> &'static str {
    match m {
        EtaMethod::TunedToHalt => "tuned to the measured halt",
        EtaMethod::LeastSquares => "least squares on φ, ψ̇, β̇",
    }
}

/// The overlay as (SVG text, PNG bytes).
fn overlay(c: &Comparison) -> Result<(String, Vec<u8>), String> {
    super::plot::ensure_font()?;
    let panels = overlay_panels(c);
    let lead = c.options.lead_s;
    let end = if c.end_time_s.is_finite() {
        c.end_time_s - lead
    } else {
        0.0
    };
    let t = (-lead, end.max(0.0) + 0.01);
    let size = (WIDTH, 40 + PANEL_H * panels.len() as u32);
    let title = overlay_title(c);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw_overlay(&root, &title, &panels, t)?;
        root.present().map_err(|e| e.to_string())?;
    }
    let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        draw_overlay(&root, &title, &panels, t)?;
        root.present().map_err(|e| e.to_string())?;
    }
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(&rgb, size.0, size.1, image::ExtendedColorType::Rgb8)
        .map_err(|e| e.to_string())?;
    Ok((svg, png))
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.4}")
    } else {
        "—".into()
    }
}

fn sci(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3e}")
    } else {
        "—".into()
    }
}

fn opt(v: Option<f64>, f: fn(f64) -> String) -> String {
    v.map_or_else(|| "—".into(), f)
}

/// "On the footage": the model's outline over the frames, the last turns side by
/// side, and the distance between the model's rim edge and the footage's.
fn model_overlay_section(o: &ModelOverlay, dir: &Path) -> Markup {
    let sheet = o
        .last_turns
        .as_ref()
        .and_then(|name| std::fs::read(dir.join(name)).ok());
    let pose = &o.pose;
    html! {
        h2 { "On the footage" }
        (video_figure(&o.video, "model-overlay", "The model's outline (orange) over the footage, with its rim edge on the centre band (orange) against the measured one (green); left the side view, right the centre band enlarged."))
        @if let Some(png) = &sheet {
            (png_figure(png, "The last turns: the footage with the model's outline, and the model alone at the same place and scale."))
        }
        @if let Some(err) = &o.edge_error {
            p { (format!(
                "Rim edge on the centre band, model − footage, over {} frames: mean {:+.2} px ({:+.3} mm),                  RMS {:.2} px ({:.3} mm), largest {:.2} px ({:.3} mm). Per frame: {}.",
                err.frames, err.mean_px, 1e3 * err.mean_m, err.rms_px, 1e3 * err.rms_m,
                err.max_abs_px, 1e3 * err.max_abs_m, o.errors_csv)) }
        }
        p class="note" { (format!(
            "Camera pose from the calibration (overlay::pose): elevation {:.2}° (from the top face's \
             image height, silhouette top at row {:.2}), {}, scale {:.4e} m/px at the disk's centre. \
             The model's precession phase is set to the measured peaks (offset {:.3} rad){}.",
            pose.elevation.to_degrees(), pose.z_top,
            pose.distance_m.map_or_else(|| "orthographic (no perspective measured)".to_string(),
                |d| format!("pinhole {d:.3} m from the near rim")),
            pose.centre_metres_per_px, o.psi_offset_rad,
            if o.mirrored { "; mirrored to the plan view's sense of precession" } else { "" })) }
    }
}

fn comparison_body(
    c: &Comparison,
    svg: &str,
    overlay: Option<&ModelOverlay>,
    dir: &Path,
) -> Markup {
    let s = &c.initial.state;
    let errors: Vec<Vec<String>> = c
        .errors
        .iter()
        .map(|e| {
            vec![
                e.variable.clone(),
                e.points.to_string(),
                format!("{} {}", sci(e.rms), e.unit),
                format!("{} {}", sci(e.scale), e.unit),
                num(e.normalised_rms),
            ]
        })
        .collect();
    let r = &c.residual;
    let pf = &c.post_flat;
    html! {
        p class="note" {
            "Experiment " code { (c.experiment.display()) } " (clip " code { (c.clip.display()) }
            "), eulerdisk " (c.eulerdisk_version) ". Model: " (c.equation) ", η "
            (method_name(c.options.method)) ". Initial state " (format!("{:.4}", c.options.lead_s))
            " s before the measured halt (eq. 4.43 convention: ψ̇ < 0, θ̇ > 0; the side view gives |ψ̇|)."
        }
        @if !c.warnings.is_empty() {
            h2 { "Warnings" }
            ul { @for w in &c.warnings { li class="bad" { (w) } } }
        }
        h2 { "Overlay (figs. 4.15–4.16)" }
        (svg_figure(svg, "Measured (green dots), the model (orange line) and the model at the measured instants (orange crosses; ψ̇ as the mean over the same turn, eq. 3.11). Time: t − t_φ of the experiment."))
        @if let Some(o) = overlay { (model_overlay_section(o, dir)) }
        h2 { "Parameters" }
        (table(&["quantity", "value", "note"], &[
            vec!["η".into(), sci(c.eta), method_name(c.options.method).into()],
            vec!["η tuned to the halt".into(), opt(c.tuned_eta, sci), format!("end at t = 0 (model time {} s)", c.options.lead_s)],
            vec!["p (augmented contour)".into(), num(c.dissipation.augmented_exponent), "used by augmented contour only".into()],
            vec!["μ".into(), num(c.mu), c.mu_source.clone()],
            vec!["simulations".into(), c.simulations.to_string(), format!("stopping angle {:.0e} rad", crate::compare::FLAT_ANGLE)],
        ], |_, _| false))
        h2 { "Initial state" }
        (table(&["variable", "value", "source"], &[
            vec!["t".into(), format!("{:.4} s", c.initial.t), "experiment time, halt at 0".into()],
            vec!["φ".into(), format!("{:.5} rad", s.phi), c.initial.phi_source.clone()],
            vec!["ψ̇".into(), format!("{:.2} rad/s", s.psi_dot), c.initial.psi_dot_source.clone()],
            vec!["θ̇".into(), format!("{:.2} rad/s", s.theta_dot), c.initial.theta_dot_source.clone()],
            vec!["φ̇, ψ, θ, x, ẋ, y, ẏ".into(), "0".into(), "eq. 4.43".into()],
        ], |_, _| false))
        h2 { "Errors" }
        (table(&["variable", "points", "RMS", "scale (RMS of data)", "RMS / scale"], &errors, |_, _| false))
        (table(&["quantity", "value"], &[
            vec!["misfit Σ (RMS/scale)²".into(), num(c.misfit)],
            vec!["model end (after the initial state)".into(), format!("{} s ({:?})", num(c.end_time_s), r.end_reason)],
            vec!["end-time error (model − measured halt)".into(), format!("{} s", num(c.end_time_error_s))],
            vec!["model's rim last above the halt threshold".into(), format!("{} s", opt(c.observable_end_s, num))],
            vec!["energy exponent n of the model's E(t)".into(), opt(c.energy_exponent, num)],
            vec!["analytic n (Table 4.1)".into(), opt(c.analytic_exponent, num)],
        ], |_, _| false))
        h2 { "Residual spin at the end (§4.7.1)" }
        (table(&["quantity", "this comparison", "thesis"], &[
            vec!["model ψ̇ at the end".into(), format!("{} rad/s", num(r.psi_dot)), format!("{} rad/s (augmented contour on D_c)", r.thesis_model)],
            vec!["model β̇ at the end (eq. 4.102)".into(), format!("{} rad/s", num(r.beta_dot)), String::new()],
            vec!["model φ, θ̇ at the end".into(), format!("{} rad, {} rad/s", sci(r.phi), num(r.theta_dot)), "4.65e-4 rad".into()],
            vec!["measured β̇ at t_φ".into(), format!("{} rad/s", opt(r.measured_beta_dot, num)), format!("{} rad/s (stainless steel)", r.thesis_measured)],
        ], |_, _| false))
        h2 { "After falling flat (§4.8)" }
        (table(&["quantity", "value"], &[
            vec!["plate".into(), pf.plate.clone()],
            vec!["Z_b(0) = z_rim/2 of the last peak".into(), format!("{} m", opt(pf.initial_gap_m, sci))],
            vec!["Ż_b(0) = φ̇ R over the last peaks".into(), format!("{} m/s", opt(pf.initial_gap_velocity_m_s, sci))],
            vec!["contact gap (asperities)".into(), format!("{} m", sci(pf.contact_gap_m))],
            vec!["contactless phase, eq. 4.104".into(), format!("{} s{}", opt(pf.contactless_s, num), pf.contactless_note.as_ref().map(|n| format!(" ({n})")).unwrap_or_default())],
            vec!["contact phase from the model's β̇ (eq. 4.111 / 4.113)".into(), format!("{} s", opt(pf.contact_from_model_s, num))],
            vec!["contact phase from the measured β̇".into(), format!("{} s", opt(pf.contact_from_measured_s, num))],
            vec!["predicted t_β − t_φ".into(), format!("{} s", opt(pf.predicted_s, num))],
            vec!["measured t_β − t_φ".into(), format!("{} s", opt(pf.measured_s, num))],
        ], |_, _| false))
        p class="note" { "Data: summary.json, model.csv, overlay.svg, overlay.png in this folder." }
    }
}

/// Writes one comparison into `dir`; returns the files written.
///
/// # Errors
/// A file cannot be written or the figure cannot be drawn.
pub fn write_comparison(
    dir: &Path,
    c: &Comparison,
    model_overlay: Option<&ModelOverlay>,
) -> Result<Vec<PathBuf>, ReportError> {
    let summary = dir.join("summary.json");
    write_json(&summary, c)?;
    if let Some(o) = model_overlay {
        write_json(&dir.join("model-overlay.json"), o)?;
    }
    let csv = dir.join("model.csv");
    let s = &c.trajectory.samples;
    let step = ((1e-3 / crate::compare::OUTPUT_INTERVAL_S).round() as usize).max(1);
    let rows: Vec<Sample> = s.iter().step_by(step).chain(s.last()).copied().collect();
    write_csv(&csv, &rows)?;
    let (svg, png) = overlay(c).map_err(plot_error)?;
    let (svg_path, png_path) = (dir.join("overlay.svg"), dir.join("overlay.png"));
    write_atomic(&svg_path, svg.as_bytes())?;
    write_atomic(&png_path, &png)?;
    let html_path = dir.join("index.html");
    let title = format!("{} vs {}", model_name(c.options.model), c.clip.display());
    write_atomic(
        &html_path,
        page(&title, comparison_body(c, &svg, model_overlay, dir)).as_bytes(),
    )?;
    Ok(vec![summary, csv, svg_path, png_path, html_path])
}

#[derive(Serialize, Default)]
struct RankRow {
    rank: usize,
    model: String,
    eta: Option<f64>,
    p: Option<f64>,
    misfit: Option<f64>,
    energy_exponent: Option<f64>,
    analytic_exponent: Option<f64>,
    end_time_error_s: Option<f64>,
    error: Option<String>,
}

/// Writes the ranking of `--all-models` into `dir` (`ranking.json`, `ranking.csv`,
/// `index.html`); returns the files written. `best_overlay`: the best model
/// and its overlay on the footage, written in its own comparison folder
/// ([`comparison_dir`]), which the page shows.
///
/// # Errors
/// A file cannot be written.
pub fn write_ranking(
    dir: &Path,
    experiment_dir: &Path,
    method: EtaMethod,
    ranked: &[Ranked],
    best_overlay: Option<(ModelKind, &ModelOverlay)>,
) -> Result<Vec<PathBuf>, ReportError> {
    let json = dir.join("ranking.json");
    write_json(&json, &ranked)?;
    let rows: Vec<RankRow> = ranked
        .iter()
        .enumerate()
        .map(|(i, r)| RankRow {
            rank: i + 1,
            model: model_name(r.model),
            eta: r.eta,
            p: r.p,
            misfit: r.misfit,
            energy_exponent: r.energy_exponent,
            analytic_exponent: crate::model::dissipation::Dissipation::new(r.model)
                .analytic_exponent(),
            end_time_error_s: r.end_time_error_s,
            error: r.error.clone(),
        })
        .collect();
    let csv = dir.join("ranking.csv");
    write_csv(&csv, &rows)?;
    let variables: Vec<String> = ranked
        .iter()
        .find(|r| !r.normalised_rms.is_empty())
        .map(|r| r.normalised_rms.iter().map(|v| v.0.clone()).collect())
        .unwrap_or_default();
    let mut header: Vec<String> = vec!["model".into(), "η".into(), "p".into(), "misfit".into()];
    header.extend(variables.iter().map(|v| format!("RMS/scale {v}")));
    header.extend([
        "n (simulated E)".into(),
        "n (analytic)".into(),
        "end − halt [s]".into(),
        "note".into(),
    ]);
    let cells: Vec<Vec<String>> = ranked
        .iter()
        .zip(&rows)
        .map(|(r, row)| {
            let mut v = vec![
                format!("{}. {}", row.rank, row.model),
                opt(r.eta, sci),
                opt(r.p, num),
                opt(r.misfit, num),
            ];
            v.extend(variables.iter().map(|name| {
                opt(
                    r.normalised_rms.iter().find(|x| &x.0 == name).map(|x| x.1),
                    num,
                )
            }));
            v.extend([
                opt(r.energy_exponent, num),
                opt(row.analytic_exponent, num),
                opt(r.end_time_error_s, num),
                r.error.clone().unwrap_or_default(),
            ]);
            v
        })
        .collect();
    let header_refs: Vec<&str> = header.iter().map(String::as_str).collect();
    let body = html! {
        p class="note" {
            "Experiment " code { (experiment_dir.display()) } ". Every model simulated from the same measured initial state, η "
            (method_name(method)) "; ranked by the misfit Σ (RMS/scale)² over φ at peaks, ψ̇ at peaks and β̇ per frame. "
            "Each model's page: " code { "compare-<model>/index.html" } "."
        }
        p class="note" {
            "Contour (eq. 4.59) and curvature-dependent offset (eq. 4.69) with k_u = 0 are the same moment and tie exactly."
        }
        (table(&header_refs, &cells, |i, j| i == 0 && j == 3))
        @if let Some((model, overlay)) = best_overlay {
            @let folder = comparison_dir(Path::new(".."), model).display().to_string();
            h2 { "The best model on the footage" }
            (video_figure(&format!("{folder}/{}", overlay.video), "model-overlay", &format!(
                "{} (ranked first) drawn over the footage: its outline (orange), its rim edge on the \
                 centre band (orange) against the measured one (green). The other models' pages \
                 have their plots only; compare --model draws any one of them.",
                model_name(model))))
            @if let Some(err) = &overlay.edge_error {
                p { (format!(
                    "Rim edge on the centre band, model − footage, over {} frames: mean {:+.2} px, \
                     RMS {:.2} px, largest {:.2} px. ", err.frames, err.mean_px, err.rms_px,
                    err.max_abs_px))
                    a href=(format!("{folder}/index.html")) { "Its page." } }
            }
        }
    };
    let html_path = dir.join("index.html");
    write_atomic(
        &html_path,
        page("Dissipation models ranked", body).as_bytes(),
    )?;
    Ok(vec![json, csv, html_path])
}
