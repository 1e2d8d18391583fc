//! The built-in demonstration (`eulerdisk demo`): the whole chain on footage whose
//! truth is known, with no network and no input.
//!
//! 1. `render` a small study: two base-plate materials × four side-view clips with
//!    different true exponents n, and one two-view clip (figs. 3.3, 3.19);
//! 2. `study`: analyse every clip (calibration, rim height, peaks, energy, power
//!    law), per-material tables, box plot, t-test, trends;
//! 3. `compare`: the two-view clip against the simulator (augmented contour
//!    friction, thesis §4.7.1);
//! 4. an index page with the recovered n beside the true n for every clip.
//!
//! Clips are small (480 × 320 px, 0.75 s at 480 fps) so the demo runs in well
//! under two minutes on two cores.

use std::path::{Path, PathBuf};

use maud::html;
use rayon::prelude::*;

use crate::model::params::Preset;
use crate::output::write_atomic;
use crate::render::{
    DEFAULT_ENCODING, Plate, PostFlatSpin, PowerLaw, RenderError, RenderSpec, Renderer, Timing,
    power_law_motion, write_clip,
};
use crate::report::ReportError;
use crate::report::html::{page, table, video_figure};
use crate::summary::StudyResults;

/// One demo clip: where it goes below the footage root and its true exponent.
#[derive(Debug, Clone)]
pub struct DemoClip {
    /// Path below the footage root, e.g. `euler/oak/run2.mp4`.
    pub relative: String,
    pub true_n: f64,
    pub two_view: bool,
}

/// The demo study: true exponents chosen so the two materials differ clearly
/// (as stainless steel and oak do in thesis Table B.1).
pub fn demo_clips() -> Vec<DemoClip> {
    let mut clips = Vec::new();
    for (material, ns) in [
        ("stainless steel", [0.62, 0.66, 0.70, 0.74]),
        ("oak", [0.44, 0.48, 0.52, 0.56]),
    ] {
        for (i, n) in ns.into_iter().enumerate() {
            clips.push(DemoClip {
                relative: format!("euler/{material}/run{}.mp4", i + 1),
                true_n: n,
                two_view: false,
            });
        }
    }
    clips.push(DemoClip {
        relative: "two-view/stainless steel/run1.mp4".into(),
        true_n: 0.45,
        two_view: true,
    });
    clips
}

/// Render the demo clips below `root` (in parallel), with the study's config
/// (`eulerdisk.toml`: fps = 480; the two-view folder's own file: two_view = true).
///
/// # Errors
/// A clip or a config file cannot be written.
pub fn render_demo_footage(root: &Path, clips: &[DemoClip]) -> Result<Vec<PathBuf>, RenderError> {
    let write_config = |path: PathBuf, text: &str| {
        write_atomic(&path, text.as_bytes()).map_err(|e| RenderError::Write {
            path,
            reason: e.to_string(),
        })
    };
    write_config(root.join("eulerdisk.toml"), "fps = 480\n")?;
    write_config(
        root.join("two-view").join("eulerdisk.toml"),
        "two_view = true\n",
    )?;
    let params = Preset::EulerDisk.params();
    clips
        .par_iter()
        .enumerate()
        .map(|(k, clip)| {
            let mut spec = RenderSpec::thesis(Plate::Dark, clip.two_view);
            (spec.width, spec.height) = if clip.two_view {
                (320, 480)
            } else {
                (480, 320)
            };
            spec.effects.noise_sigma = 1.0;
            spec.effects.seed = k as u64 + 1;
            let timing = Timing {
                fps: 480.0,
                halt_time: 0.6,
                after_halt: 0.15,
                jitter: None,
            };
            let post_flat = PostFlatSpin {
                beta_dot0: -2.8,
                mu: 0.134,
            };
            let motion =
                power_law_motion(&params, &PowerLaw::thesis(clip.true_n), &timing, post_flat)?;
            let renderer = Renderer::new(&spec, &motion)?;
            Ok(write_clip(&renderer, &root.join(&clip.relative), DEFAULT_ENCODING)?.clip)
        })
        .collect()
}

/// `OUT/index.html`: recovered n beside the true n, with links to the study report
/// and each clip's page.
///
/// # Errors
/// The page cannot be written.
/// The two-view clip's measurement overlay, relative to the demo's folder.
fn two_view_overlay(study_dir: &str) -> String {
    format!(
        "{study_dir}/experiments/two-view/stainless steel/run1.mp4/{}",
        crate::overlay::OVERLAY_VIDEO
    )
}

pub fn write_demo_index(
    out: &Path,
    clips: &[DemoClip],
    results: &StudyResults,
    study_dir: &str,
    comparison: Option<&Path>,
) -> Result<(), ReportError> {
    let rows: Vec<Vec<String>> = clips
        .iter()
        .map(|clip| {
            let found = results.experiments.iter().find(|e| e.clip == clip.relative);
            let failed = results.failures.iter().find(|f| f.clip == clip.relative);
            match (found, failed) {
                (Some(e), _) => vec![
                    clip.relative.clone(),
                    format!("{:.3}", clip.true_n),
                    format!("{:.3}", e.n),
                    format!("{:.3} … {:.3}", e.n_ci95[0], e.n_ci95[1]),
                    format!("{:+.3}", e.n - clip.true_n),
                    if (e.n_ci95[0]..=e.n_ci95[1]).contains(&clip.true_n) {
                        "yes"
                    } else {
                        "no"
                    }
                    .into(),
                ],
                (None, Some(f)) => vec![
                    clip.relative.clone(),
                    format!("{:.3}", clip.true_n),
                    "failed".into(),
                    f.reason.clone(),
                    String::new(),
                    String::new(),
                ],
                (None, None) => vec![
                    clip.relative.clone(),
                    format!("{:.3}", clip.true_n),
                    "not run".into(),
                    String::new(),
                    String::new(),
                    String::new(),
                ],
            }
        })
        .collect();
    let body = html! {
        p {
            "Synthetic footage of Euler's disk, rendered with a prescribed power law "
            "E = A_e (t0 − t)^n (known n), analysed by the same chain as real footage "
            "(thesis Chapter 3). Every number below is recomputed by " code { "eulerdisk demo" } "."
        }
        h2 { "Recovered exponents" }
        (table(&["clip", "true n", "recovered n", "95 % CI", "error", "CI covers truth"], &rows, |_, _| false))
        @if let Some(link) = comparison {
            h2 { "On the footage: the two-view clip" }
            (video_figure(&two_view_overlay(study_dir), "overlay", "What was measured, on the frames of the two-view clip: the band, the plate line, the rim edge, the peaks, the halt, the strip's mask and axis (from the clip's own page)."))
            (video_figure(&link.with_file_name(crate::overlay::MODEL_OVERLAY_VIDEO).display().to_string(), "model-overlay", "The simulated disk (augmented contour friction) drawn over the same frames, with its rim edge against the measured one (from the comparison's page)."))
        }
        h2 { "Reports" }
        ul {
            li { a href=(format!("{study_dir}/index.html")) { "Study report" } ": per-material tables, box plot, t-tests, trends" }
            @for e in &results.experiments {
                li {
                    a href=(format!("{study_dir}/experiments/{}/index.html", e.clip)) { (e.clip) }
                }
            }
            @if let Some(link) = comparison {
                li { a href=(link.display().to_string()) { "The two-view clip against the simulator" } " (augmented contour friction, η tuned to the measured halt; thesis §4.7.1)" }
            }
            li { a href="reproduce/reproduce.md" { "The thesis's published numbers, recomputed" } " (" code { "eulerdisk reproduce" } ")" }
        }
    };
    write_atomic(
        &out.join("index.html"),
        page("eulerdisk demo", body).as_bytes(),
    )?;
    Ok(())
}
