//! eulerdisk: slow-motion footage of spinning disks turned into physics.
//!
//! The modules are layered; a module names only modules below it (`crate::…`
//! paths outside comments), which [`LAYERS`] lists bottom first and a test checks:
//!
//! ```text
//! commands  study · reproduce · demo      resolve a plan, run, write (main.rs: the CLI)
//! pages     report · overlay              pages, plots, overlay videos: read results
//! results   compare · summary             the simulator against a measured experiment;
//!                                         what a study keeps of each clip
//! chain     analyse                       open → calibrate → measure → signal → fit
//! render    render                        synthetic footage with known truth
//! stages    stats · precession · turn_timing · vision · signal · footage · energy
//! model     config · model                the experiment's config; the simulator
//! base      output · rng · numeric        file writing; seeded noise; solver,
//!                                         minimiser, robust statistics
//! ```
//!
//! The measurement hands the frames it reads to the overlay through a trait it
//! defines ([`analyse::FrameKeeping`]); files are written through [`output`].
//!
//! The docs name the constants and helpers each method's numbers come from, most of
//! them private: read them with `cargo doc --document-private-items`.
#![allow(rustdoc::private_intra_doc_links)]
pub mod analyse;
pub mod compare;
pub mod config;
pub mod demo;
pub mod energy;
pub mod footage;
pub mod model;
pub mod motion_fit;
pub mod numeric;
pub mod output;
pub mod overlay;
pub mod precession;
pub mod render;
pub mod report;
pub mod reproduce;
pub mod rng;
pub mod signal;
pub mod stats;
pub mod study;
pub mod summary;
pub mod turn_timing;
pub mod vision;

/// The top-level modules, bottom layer first: each may name only those before it.
pub const LAYERS: [&str; 22] = [
    "numeric",
    "rng",
    "output",
    "model",
    "config",
    "energy",
    "footage",
    "signal",
    "vision",
    "turn_timing",
    "motion_fit",
    "precession",
    "stats",
    "render",
    "analyse",
    "summary",
    "compare",
    "overlay",
    "report",
    "reproduce",
    "study",
    "demo",
];

#[cfg(test)]
mod layers {
    use std::path::Path;

    use super::LAYERS;

    /// The top-level modules a source text names by `crate::NAME`, outside comments.
    fn named_modules(text: &str) -> Vec<String> {
        let mut names = Vec::new();
        for line in text.lines() {
            let code = line.split("//").next().unwrap_or("");
            let mut rest = code;
            while let Some(at) = rest.find("crate::") {
                rest = &rest[at + "crate::".len()..];
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                names.push(name);
            }
        }
        names
    }

    /// Every `.rs` file under `dir`.
    fn sources(dir: &Path, files: &mut Vec<std::path::PathBuf>) {
        for entry in std::fs::read_dir(dir).expect("read src") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                sources(&path, files);
            } else if path.extension().is_some_and(|e| e == "rs") {
                files.push(path);
            }
        }
    }

    /// No module names one at or above its own layer, so the layers have no cycle;
    /// and every top-level module has a layer.
    #[test]
    fn modules_import_only_the_layers_below_them() {
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut files = Vec::new();
        sources(&src, &mut files);
        let layer = |name: &str| LAYERS.iter().position(|m| *m == name);
        let mut wrong = Vec::new();
        for file in &files {
            let relative = file.strip_prefix(&src).expect("under src");
            let top = relative
                .components()
                .next()
                .and_then(|c| c.as_os_str().to_str())
                .map(|s| s.trim_end_matches(".rs").to_string())
                .expect("a name");
            if top == "main" || top == "lib" {
                continue;
            }
            let Some(own) = layer(&top) else {
                wrong.push(format!("{top}: not in LAYERS"));
                continue;
            };
            let text = std::fs::read_to_string(file).expect("read");
            for name in named_modules(&text) {
                match layer(&name) {
                    Some(other) if other >= own && name != top => wrong.push(format!(
                        "{} names crate::{name}, which is not below {top}",
                        relative.display()
                    )),
                    _ => {}
                }
            }
        }
        wrong.sort();
        wrong.dedup();
        assert!(wrong.is_empty(), "layering broken:\n{}", wrong.join("\n"));
    }

    /// The check sees a `crate::` path in code and not in a comment.
    #[test]
    fn the_check_reads_code_not_comments() {
        let text = "use crate::report::write; // crate::study\n/// [`crate::demo`]\n";
        assert_eq!(named_modules(text), ["report"]);
    }
}
