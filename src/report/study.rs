//! The study report: `OUT/index.html` with the exponent table, per-material
//! summaries, box plots (figs. 3.15, 3.17), pairwise t-tests with Bonferroni and
//! Holm corrections (Tables 3.2, 3.3), trends against the material properties of
//! Table 3.1 (fig. 3.16) and the list of failed clips; the tables also as CSV and
//! Markdown in `OUT/tables/`, the plots as SVG in `OUT/plots/`.
//!
//! The page is a pure function of [`StudyResults`], so a merged set of shards
//! gives the same report as one run.

use std::collections::BTreeMap;
use std::path::Path;

use maud::{Markup, html};

use super::ReportError;
use super::html::{linked_table, page, svg_figure, table, url_path};
use super::study_plots::{BoxPlot, BoxSeries, box_plot_svg, trend_plot_svg};
use crate::output::{write_atomic, write_csv_rows};
use crate::stats::{
    self, Correction, Group, MaterialProperty, PValueMatrix, THESIS_ALPHA, Trend, VarianceModel,
};
use crate::summary::{ExperimentSummary, StudyResults};

/// Choices of the statistics in a study report.
#[derive(Debug, Clone, Copy)]
pub struct StudyReportOptions {
    /// Pooled variance reproduces the thesis; Welch does not assume equal variances.
    pub variance: VarianceModel,
    /// Family-wise significance level.
    pub alpha: f64,
}

impl Default for StudyReportOptions {
    fn default() -> Self {
        Self {
            variance: VarianceModel::Pooled,
            alpha: THESIS_ALPHA,
        }
    }
}

/// Exponents grouped by a label (material, or disk within a material), in
/// first-seen order of the sorted results.
fn groups_by(
    results: &StudyResults,
    label: impl Fn(&crate::summary::ExperimentSummary) -> String,
) -> Vec<Group> {
    let mut order: Vec<String> = Vec::new();
    let mut values: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for e in &results.experiments {
        let key = label(e);
        if !values.contains_key(&key) {
            order.push(key.clone());
        }
        values.entry(key).or_default().push(e.n);
    }
    order
        .into_iter()
        .map(|name| {
            let v = values.remove(&name).unwrap_or_default();
            Group::new(name, v)
        })
        .collect()
}

/// Material names match ignoring case, spaces, `-` and `_`: the folder
/// `stainless-steel` is Table 3.1's "stainless steel".
fn same_material(a: &str, b: &str) -> bool {
    let norm = |s: &str| {
        s.chars()
            .filter(|c| !matches!(c, '-' | '_' | ' '))
            .flat_map(char::to_lowercase)
            .collect::<String>()
    };
    norm(a) == norm(b)
}

fn fmt(x: f64, digits: usize) -> String {
    if x.is_finite() {
        format!("{x:.digits$}")
    } else {
        "–".into()
    }
}

fn p_text(p: f64) -> String {
    if p < 1e-4 {
        format!("{p:.1e}")
    } else {
        format!("{p:.4}")
    }
}

/// The p-value matrix as rows for an HTML table (upper triangle), with the
/// significant cells to highlight.
fn matrix_rows(m: &PValueMatrix) -> (Vec<Vec<String>>, Vec<(usize, usize)>) {
    let mut rows = Vec::new();
    let mut marked = Vec::new();
    for (i, a) in m.groups.iter().enumerate() {
        let mut row = vec![a.clone()];
        for (j, b) in m.groups.iter().enumerate() {
            row.push(match m.get(a, b) {
                Some(c) if j > i => {
                    if c.significant {
                        marked.push((i, j + 1));
                    }
                    p_text(c.test.p)
                }
                _ => String::new(),
            });
        }
        rows.push(row);
    }
    (rows, marked)
}

fn matrix_section(m: &PValueMatrix, what: &str) -> Markup {
    let (rows, marked) = matrix_rows(m);
    let mut header = vec![""];
    header.extend(m.groups.iter().map(String::as_str));
    let k = m.family.comparisons.len();
    html! {
        p class="note" {
            (what) ": two-sided two-sample t-tests ("
            (format!("{:?}", m.family.variance).to_lowercase()) " variance), "
            (k) " comparisons, " (format!("{:?}", m.family.correction)) " correction at α = "
            (m.family.alpha) ". Highlighted: significant after correction."
        }
        (table(&header, &rows, |i, j| marked.contains(&(i, j))))
    }
}

/// The columns of `tables/exponents.csv`.
const EXPONENT_COLUMNS: [&str; 17] = [
    "clip",
    "disk",
    "material",
    "orientation",
    "run",
    "n",
    "n_ci_low",
    "n_ci_high",
    "t0_s",
    "r_squared",
    "points",
    "fps",
    "fps_source",
    "phi_vs_precession",
    "n_turn_timing",
    "n_turn_timing_ci_low",
    "n_turn_timing_ci_high",
];

/// One clip's row of `tables/exponents.csv` ([`EXPONENT_COLUMNS`]): numbers in
/// their shortest exact form, missing values empty.
fn exponent_row(e: &ExperimentSummary) -> Vec<String> {
    let m = &e.meta;
    let text = |s: &Option<String>| s.clone().unwrap_or_default();
    let (timing_n, timing_low, timing_high) =
        e.n_turn_timing.map_or_else(Default::default, |(n, ci)| {
            (n.to_string(), ci[0].to_string(), ci[1].to_string())
        });
    vec![
        e.clip.clone(),
        text(&m.disk),
        text(&m.material),
        text(&m.orientation),
        text(&m.run),
        e.n.to_string(),
        e.n_ci95[0].to_string(),
        e.n_ci95[1].to_string(),
        e.t0_s.to_string(),
        e.r_squared.to_string(),
        e.points.to_string(),
        e.fps.to_string(),
        e.fps_source.clone(),
        e.phi_vs_precession.map_or(String::new(), |d| d.to_string()),
        timing_n,
        timing_low,
        timing_high,
    ]
}

/// The page of each failed clip of `results` below `out`, relative to the report,
/// where its folder has one (`None` else, as after a merge of shards).
fn failure_pages(out: &Path, results: &StudyResults) -> Vec<Option<String>> {
    results
        .failures
        .iter()
        .map(|f| {
            let page = format!("experiments/{}/index.html", f.clip);
            out.join(&page)
                .is_file()
                .then(|| format!("experiments/{}/index.html", url_path(&f.clip)))
        })
        .collect()
}

/// Write `OUT/index.html`, `OUT/tables/*` and `OUT/plots/*` for a study.
///
/// # Errors
/// A file that cannot be written, or a plot that cannot be drawn.
pub fn write_study_report(
    out: &Path,
    results: &StudyResults,
    options: StudyReportOptions,
) -> Result<(), ReportError> {
    let tables = out.join("tables");
    let plots = out.join("plots");
    let materials = groups_by(results, |e| e.meta.material_or_all().to_string());
    let summaries: Vec<_> = materials
        .iter()
        .filter_map(|g| stats::summarise(g).ok())
        .collect();
    let exponents: Vec<Vec<String>> = results.experiments.iter().map(exponent_row).collect();
    write_csv_rows(&tables.join("exponents.csv"), &EXPONENT_COLUMNS, &exponents)?;
    let summary_rows = summary_rows(&summaries);
    write_atomic(
        &tables.join("summary.md"),
        summary_markdown(&summary_rows).as_bytes(),
    )?;
    let study_page = StudyPage {
        results,
        experiment_rows: experiment_rows(results),
        box_svg: write_box_plot(&plots, &summaries)?,
        summary_rows,
        matrices: write_material_tests(&tables, &materials, options)?,
        disk_matrices: disk_tests(results, &materials, options),
        trend_svgs: write_trends(&plots, results)?,
        failure_pages: failure_pages(out, results),
    };
    write_atomic(
        &out.join("index.html"),
        page("eulerdisk study", study_page.body()).as_bytes(),
    )?;
    Ok(())
}

/// The header of the per-material summary table.
const SUMMARY_HEADER: [&str; 7] = [
    "material",
    "clips",
    "mean n",
    "median n",
    "sd",
    "IQR",
    "outliers (1.5 IQR)",
];

/// Errors of the study's plots as the report's.
fn plot_error(e: super::study_plots::StudyPlotError) -> ReportError {
    ReportError::Plot(e.to_string())
}

/// The exponents table of the page: each clip's n, interval, fit and checks.
fn experiment_rows(results: &StudyResults) -> Vec<Vec<String>> {
    results
        .experiments
        .iter()
        .map(|e| {
            vec![
                e.clip.clone(),
                e.meta.disk.clone().unwrap_or_default(),
                e.meta.material.clone().unwrap_or_default(),
                fmt(e.n, 3),
                format!("{} … {}", fmt(e.n_ci95[0], 3), fmt(e.n_ci95[1], 3)),
                fmt(e.r_squared, 4),
                e.points.to_string(),
                format!("{} ({})", fmt(e.fps, 0), e.fps_source),
                e.phi_vs_precession
                    .map_or("–".into(), |d| format!("{:+.1}", 100.0 * d)),
                e.n_turn_timing.map_or("–".into(), |(n, ci)| {
                    format!("{} ({} … {})", fmt(n, 3), fmt(ci[0], 3), fmt(ci[1], 3))
                }),
                e.warnings.len().to_string(),
            ]
        })
        .collect()
}

/// The per-material summary rows ([`SUMMARY_HEADER`]).
fn summary_rows(summaries: &[stats::Summary]) -> Vec<Vec<String>> {
    summaries
        .iter()
        .map(|s| {
            vec![
                s.group.clone(),
                s.count.to_string(),
                fmt(s.mean, 3),
                fmt(s.median, 3),
                fmt(s.std_dev, 3),
                fmt(s.iqr, 3),
                s.outliers
                    .iter()
                    .map(|o| fmt(*o, 3))
                    .collect::<Vec<_>>()
                    .join(", "),
            ]
        })
        .collect()
}

/// `tables/summary.md`: the summary rows as a Markdown table.
fn summary_markdown(summary_rows: &[Vec<String>]) -> String {
    let mut md = format!(
        "| {} |\n|{}\n",
        SUMMARY_HEADER.join(" | "),
        "---|".repeat(SUMMARY_HEADER.len())
    );
    for row in summary_rows {
        md += &format!("| {} |\n", row.join(" | "));
    }
    md
}

/// `plots/box_materials.svg`: n per material as a box plot (figs. 3.15, 3.17), or
/// `None` without a summary; the SVG is returned for the page.
fn write_box_plot(
    plots: &Path,
    summaries: &[stats::Summary],
) -> Result<Option<String>, ReportError> {
    Ok(if summaries.is_empty() {
        None
    } else {
        let plot = BoxPlot {
            title: "Energy exponent n per base-plate material".into(),
            y_label: "n".into(),
            categories: summaries.iter().map(|s| s.group.clone()).collect(),
            series: vec![BoxSeries {
                name: "all disks".into(),
                boxes: summaries.iter().cloned().map(Some).collect(),
            }],
        };
        let svg = box_plot_svg(&plot).map_err(plot_error)?;
        write_atomic(&plots.join("box_materials.svg"), svg.as_bytes())?;
        Some(svg)
    })
}

/// Pairwise t-tests between the materials with at least two clips each (Table 3.2),
/// with Bonferroni's and Holm's corrections, written to `tables/p_values_*`; none
/// with fewer than two such materials.
fn write_material_tests(
    tables: &Path,
    materials: &[Group],
    options: StudyReportOptions,
) -> Result<Vec<PValueMatrix>, ReportError> {
    let testable: Vec<Group> = materials
        .iter()
        .filter(|g| g.values.len() >= 2)
        .cloned()
        .collect();
    let mut matrices = Vec::new();
    if testable.len() >= 2 {
        for correction in [Correction::Bonferroni, Correction::Holm] {
            if let Ok(m) =
                stats::pairwise_t_tests(&testable, options.variance, correction, options.alpha)
            {
                let name = format!("{correction:?}").to_lowercase();
                write_atomic(
                    &tables.join(format!("p_values_{name}.csv")),
                    m.to_csv().as_bytes(),
                )?;
                write_atomic(
                    &tables.join(format!("p_values_{name}.md")),
                    m.to_markdown().as_bytes(),
                )?;
                matrices.push(m);
            }
        }
    }
    Ok(matrices)
}

/// The disks compared within each material (Table 3.3), where it has two or more
/// disks with two clips each.
fn disk_tests(
    results: &StudyResults,
    materials: &[Group],
    options: StudyReportOptions,
) -> Vec<(String, PValueMatrix)> {
    let mut disk_matrices = Vec::new();
    for material in materials {
        let within: Vec<Group> = groups_by(results, |e| {
            if e.meta.material_or_all() == material.name {
                e.meta.disk.clone().unwrap_or_else(|| "disk".into())
            } else {
                String::new()
            }
        })
        .into_iter()
        .filter(|g| !g.name.is_empty() && g.values.len() >= 2)
        .collect();
        if within.len() >= 2
            && let Ok(m) = stats::pairwise_t_tests(
                &within,
                options.variance,
                Correction::Bonferroni,
                options.alpha,
            )
        {
            disk_matrices.push((material.name.clone(), m));
        }
    }
    disk_matrices
}

/// n against each property of thesis Table 3.1 (fig. 3.16), for the materials the
/// table knows, where two of them and three clips give a line: `plots/trend_*.svg`,
/// the SVGs returned for the page.
fn write_trends(plots: &Path, results: &StudyResults) -> Result<Vec<String>, ReportError> {
    let known = stats::materials().unwrap_or_default();
    let mut trend_svgs = Vec::new();
    for property in MaterialProperty::ALL {
        let points: Vec<(String, f64, f64)> = results
            .experiments
            .iter()
            .filter_map(|e| {
                let m = known.iter().find(|k| {
                    same_material(&k.material, e.meta.material.as_deref().unwrap_or(""))
                })?;
                Some((m.material.clone(), property.of(m), e.n))
            })
            .collect();
        let distinct = points
            .iter()
            .map(|p| p.0.as_str())
            .collect::<std::collections::BTreeSet<_>>();
        if distinct.len() < 2 || points.len() < 3 {
            continue;
        }
        let x: Vec<f64> = points.iter().map(|p| p.1).collect();
        let y: Vec<f64> = points.iter().map(|p| p.2).collect();
        if let Ok(fit) = stats::ordinary_least_squares(&x, &y, property.label()) {
            let trend = Trend {
                property,
                points,
                fit,
            };
            let svg = trend_plot_svg(&trend).map_err(plot_error)?;
            let file = format!("trend_{}.svg", format!("{property:?}").to_lowercase());
            write_atomic(&plots.join(file), svg.as_bytes())?;
            trend_svgs.push(svg);
        }
    }
    Ok(trend_svgs)
}

/// What the study page shows beside the results.
struct StudyPage<'a> {
    results: &'a StudyResults,
    experiment_rows: Vec<Vec<String>>,
    summary_rows: Vec<Vec<String>>,
    box_svg: Option<String>,
    matrices: Vec<PValueMatrix>,
    disk_matrices: Vec<(String, PValueMatrix)>,
    trend_svgs: Vec<String>,
    /// Each failed clip's page below the report, where its folder has one.
    failure_pages: Vec<Option<String>>,
}

impl StudyPage<'_> {
    /// The page: the exponents (each clip linked to its page), the per-material
    /// summary and box plot, the tests, the trends and the failed clips.
    fn body(&self) -> Markup {
        html! {
            (self.exponents_section())
            (self.materials_section())
            (self.failures_section())
        }
    }

    /// What was analysed, and each clip's n with its checks, linked to its page.
    fn exponents_section(&self) -> Markup {
        let results = self.results;
        let clip_pages: Vec<String> = results
            .experiments
            .iter()
            .map(|e| format!("experiments/{}/index.html", url_path(&e.clip)))
            .collect();
        html! {
            p class="note" {
                (results.experiments.len()) " clips analysed, " (results.failures.len())
                " failed · eulerdisk " (results.crate_version)
                " · E = A_e (t0 − t)^n fitted per clip (thesis §3.2.5); tables as CSV and Markdown in "
                code { "tables/" } ", plots as SVG in " code { "plots/" } "."
            }
            h2 { "Exponents" }
            (linked_table(
                &["clip", "disk", "material", "n", "95 % CI", "R²", "points", "fps (source)", "φ vs precession %", "n from the turns' timing (95 % CI)", "warnings"],
                &self.experiment_rows,
                &clip_pages,
                |_, _| false,
            ))
            p class="note" {
                "φ vs precession: φ from the rim heights over the φ that stationary rolling (eq. 2.29) \
                 gives the measured precession rate, at the fit window's mean, − 1: a check of the \
                 scale and the zero that shares neither (a warning beyond ±3 %; see each clip's page). \
                 n from the turns' timing: the exponent from the times of z_rim's peaks and troughs \
                 alone, with no height, scale or zero in it (a check of n, never combined with it; a \
                 warning where the two intervals are disjoint)."
            }
            p class="note" { "Each clip's name links to its own page." }
        }
    }

    /// The materials: the summary and box plot, the materials and the disks compared,
    /// and the trends against the materials' properties.
    fn materials_section(&self) -> Markup {
        html! {
            h2 { "Per material" }
            (table(&SUMMARY_HEADER, &self.summary_rows, |_, _| false))
            @if let Some(svg) = &self.box_svg {
                (svg_figure(svg, "Box plot of n per material (figs. 3.15, 3.17): whiskers to 1.5 IQR, outliers marked."))
            }
            h2 { "Materials compared (Table 3.2)" }
            @if self.matrices.is_empty() {
                p { "Fewer than two materials with two or more clips each: no pairwise tests." }
            }
            @for m in &self.matrices {
                (matrix_section(m, "Materials"))
            }
            @if !self.disk_matrices.is_empty() {
                h2 { "Disks compared within each material (Table 3.3)" }
                @for (material, m) in &self.disk_matrices {
                    h3 { (material) }
                    (matrix_section(m, "Disks"))
                }
            }
            @if !self.trend_svgs.is_empty() {
                h2 { "Trends against material properties (fig. 3.16)" }
                @for svg in &self.trend_svgs {
                    (svg_figure(svg, "n against a property of thesis Table 3.1, OLS line with the slope's 95 % CI."))
                }
            }
        }
    }

    /// The clips that failed, and why, each linked to its folder's page where there is
    /// one (its failure page, or an earlier result kept).
    fn failures_section(&self) -> Markup {
        let failures = &self.results.failures;
        html! {
            h2 { "Failed clips" }
            @if failures.is_empty() {
                p { "None." }
            } @else {
                table {
                    tr { th class="text" { "clip" } th { "reason" } }
                    @for (f, page) in failures.iter().zip(&self.failure_pages) {
                        tr {
                            td class="text" {
                                @match page {
                                    Some(href) => a href=(href) { (f.clip) },
                                    None => (f.clip),
                                }
                            }
                            td { (f.reason) }
                        }
                    }
                }
            }
        }
    }
}

/// Tables 3.2 and 3.3 and figs. 3.15–3.17 regenerated from the thesis's published
/// exponents (Appendix B) into `OUT/` (`eulerdisk study --published`).
///
/// # Errors
/// The embedded data cannot be read (a build defect) or a file cannot be written.
pub fn write_published_report(out: &Path, options: StudyReportOptions) -> Result<(), ReportError> {
    let stats_error = |e: stats::StatsError| ReportError::Plot(e.to_string());
    let plot_error = |e: super::study_plots::StudyPlotError| ReportError::Plot(e.to_string());
    let records = stats::published_exponents().map_err(stats_error)?;
    let materials = stats::materials().map_err(stats_error)?;
    let t32 = stats::table_3_2(&records, options.variance).map_err(stats_error)?;
    let t33 = stats::table_3_3(&records, options.variance).map_err(stats_error)?;
    let tables = out.join("tables");
    let plots = out.join("plots");
    write_atomic(&tables.join("table_3_2.md"), t32.to_markdown().as_bytes())?;
    write_atomic(&tables.join("table_3_2.csv"), t32.to_csv().as_bytes())?;
    write_atomic(&tables.join("table_3_3.md"), t33.to_markdown().as_bytes())?;
    write_atomic(&tables.join("table_3_3.csv"), t33.to_csv().as_bytes())?;
    let fig_3_15 = box_plot_svg(&super::study_plots::figure_3_15(&records).map_err(plot_error)?)
        .map_err(plot_error)?;
    let fig_3_17 = box_plot_svg(&super::study_plots::figure_3_17(&records).map_err(plot_error)?)
        .map_err(plot_error)?;
    write_atomic(&plots.join("figure_3_15.svg"), fig_3_15.as_bytes())?;
    write_atomic(&plots.join("figure_3_17.svg"), fig_3_17.as_bytes())?;
    let trends = super::study_plots::figure_3_16(&records, &materials).map_err(plot_error)?;
    let body = html! {
        p class="note" {
            "Regenerated from the exponents the thesis publishes in Appendix B (Tables B.1–B.3), "
            "with Table 3.1's material properties. Tables as Markdown and CSV in " code { "tables/" } "."
        }
        h2 { "Table 3.2: base-plate materials compared (Euler's disk)" }
        (matrix_section(&t32, "Materials"))
        h2 { "Table 3.3: disks compared per material" }
        pre { (t33.to_markdown()) }
        h2 { "Fig. 3.15" }
        (svg_figure(&fig_3_15, "n per material, Euler's disk (Table B.1)."))
        h2 { "Fig. 3.17" }
        (svg_figure(&fig_3_17, "n per material for each disk set-up (Tables B.1–B.3)."))
        h2 { "Fig. 3.16" }
        @for (_, svg) in &trends {
            (svg_figure(svg, "n against a material property, OLS line with the slope's 95 % CI."))
        }
    };
    write_atomic(
        &out.join("index.html"),
        page("Thesis Tables 3.2 and 3.3 from Appendix B", body).as_bytes(),
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::summary::{ClipFailure, ClipMeta, ExperimentSummary};

    fn experiment(material: &str, run: usize, n: f64) -> ExperimentSummary {
        ExperimentSummary {
            clip: format!("{material}/run{run}.mp4"),
            meta: ClipMeta {
                material: Some(material.into()),
                run: Some(format!("run{run}")),
                ..ClipMeta::default()
            },
            resume_key: String::new(),
            n,
            n_ci95: [n - 0.02, n + 0.02],
            t0_s: 0.0,
            r_squared: 0.999,
            points: 20,
            fps: 480.0,
            fps_source: "config".into(),
            phi_vs_precession: Some(-0.01),
            n_turn_timing: Some((n + 0.003, [n - 0.007, n + 0.013])),
            warnings: vec![],
        }
    }

    #[test]
    fn study_page_holds_the_t_test_of_two_materials_and_the_failures() {
        let mut results = StudyResults {
            crate_version: "test".into(),
            ..StudyResults::default()
        };
        for (run, n) in [0.5, 0.6, 0.7, 0.8].into_iter().enumerate() {
            results.experiments.push(experiment("oak", run, n));
        }
        for (run, n) in [1.0, 1.1, 1.2, 1.3].into_iter().enumerate() {
            results
                .experiments
                .push(experiment("stainless steel", run, n));
        }
        results.failures.push(ClipFailure {
            clip: "oak/run9.mp4".into(),
            meta: ClipMeta::default(),
            reason: "oak/run9.mp4: no disk in view".into(),
        });
        let out = tempfile::tempdir().unwrap();
        write_study_report(out.path(), &results, StudyReportOptions::default()).unwrap();
        let html = std::fs::read_to_string(out.path().join("index.html")).unwrap();
        // Pooled t = 5.477 with 6 degrees of freedom: two-sided p = 0.001547
        // (numerical integral of the Student density); one comparison, so it
        // stays significant after Bonferroni at 0.05.
        assert!(
            html.contains("class=\"significant\">0.0015"),
            "p-value cell missing"
        );
        assert!(html.contains("no disk in view"));
        // Two Table 3.1 materials: the three fig. 3.16 trends are drawn.
        for file in ["box_materials.svg", "trend_log10youngsmodulus.svg"] {
            assert!(out.path().join("plots").join(file).is_file(), "{file}");
        }
        let csv =
            std::fs::read_to_string(out.path().join("tables/p_values_bonferroni.csv")).unwrap();
        assert!(csv.contains("0.0015"), "{csv}");
        // Each clip's n from the turns' timing sits beside its fitted n, in the table
        // and in the CSV's last three columns.
        assert!(html.contains("0.503 (0.493 … 0.513)"), "timing column");
        let exponents = std::fs::read_to_string(out.path().join("tables/exponents.csv")).unwrap();
        let first = exponents.lines().nth(1).unwrap();
        let timing: Vec<f64> = first
            .rsplitn(4, ',')
            .take(3)
            .map(|v| v.parse().unwrap())
            .collect();
        assert_eq!(timing.len(), 3, "{first}");
        assert!(
            (timing[2] - 0.503).abs() < 1e-9 && (timing[0] - 0.513).abs() < 1e-9,
            "{first}"
        );
    }

    /// Names with every character a table can trip on.
    const AWKWARD: [&str; 4] = ["oak, old", "say \"hi\"", "ébène # 100%", "two  spaces"];

    /// Issue 73.1: exponents.csv's fields were not quoted, so a material "oak, old"
    /// gave 19 fields under a 17-field header. Read back by the `csv` crate with its
    /// header, every row has the header's width and every name comes back as written.
    #[test]
    fn exponents_csv_reads_back_with_awkward_names() {
        let mut results = StudyResults::default();
        for (run, material) in AWKWARD.into_iter().enumerate() {
            let mut e = experiment(material, run, 0.5);
            e.meta.disk = Some(format!("{material} disk"));
            e.n_turn_timing = None;
            results.experiments.push(e);
        }
        let out = tempfile::tempdir().unwrap();
        write_study_report(out.path(), &results, StudyReportOptions::default()).unwrap();
        let mut reader = csv::Reader::from_path(out.path().join("tables/exponents.csv")).unwrap();
        let header = reader.headers().unwrap().clone();
        assert_eq!(header.len(), EXPONENT_COLUMNS.len());
        let rows: Vec<csv::StringRecord> = reader.records().map(Result::unwrap).collect();
        assert_eq!(rows.len(), AWKWARD.len());
        for (row, e) in rows.iter().zip(&results.experiments) {
            assert_eq!(row.len(), header.len(), "{row:?}");
            assert_eq!(&row[0], e.clip);
            assert_eq!(Some(&row[1]), e.meta.disk.as_deref());
            assert_eq!(Some(&row[2]), e.meta.material.as_deref());
            assert_eq!(row[9].parse::<f64>().unwrap(), e.r_squared);
        }
        // Issue 73.13: the page named no clip as a link. Each clip links to its page,
        // its path percent-encoded.
        let html = std::fs::read_to_string(out.path().join("index.html")).unwrap();
        for e in &results.experiments {
            let href = format!("href=\"experiments/{}/index.html\"", url_path(&e.clip));
            assert!(html.contains(&href), "{href}");
        }
    }
}
