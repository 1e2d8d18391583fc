//! `eulerdisk study` and `merge` end to end on a footage tree built from the
//! rendered fixtures plus three broken clips, each test in a fresh folder.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

mod util;
use util::eulerdisk;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
}

fn ok(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "stdout: {}\nstderr: {}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// ROOT/euler/{stainless steel,oak}/… with two good clips each (the same rendered
/// clip, so both materials give the same n), a corrupted file, a truncated file
/// and a clip of black frames (no disk in view).
fn footage_tree(root: &Path) {
    let good = std::fs::read(fixture("side-dark-n050.mp4")).unwrap();
    std::fs::create_dir_all(root).unwrap();
    std::fs::write(root.join("eulerdisk.toml"), "fps = 480\n").unwrap();
    for material in ["stainless steel", "oak"] {
        let dir = root.join("euler").join(material);
        std::fs::create_dir_all(&dir).unwrap();
        for run in ["run1.mp4", "run2.mp4"] {
            std::fs::write(dir.join(run), &good).unwrap();
        }
    }
    let oak = root.join("euler/oak");
    std::fs::write(oak.join("corrupt.mp4"), b"this is not a video").unwrap();
    std::fs::write(oak.join("truncated.mp4"), &good[..good.len() / 3]).unwrap();
    let black = oak.join("nodisk");
    std::fs::create_dir(&black).unwrap();
    for i in 0..20 {
        image::RgbImage::new(64, 48)
            .save(black.join(format!("f{i:02}.png")))
            .unwrap();
    }
}

/// Exit status 2: the study (or merge) finished, but clips failed or the
/// previous report was kept.
fn clips_failed(out: &std::process::Output) {
    assert_eq!(
        out.status.code(),
        Some(2),
        "stdout: {}\nstderr: {}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

fn study_json(dir: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(dir.join("study.json")).unwrap()).unwrap()
}

/// A study with three broken clips finishes, lists the three failures with their
/// reasons and keeps every other result; `--resume` redoes nothing that is
/// unchanged; two shards merged give the same results as one run.
#[test]
fn study_survives_bad_clips_resumes_and_merges_shards() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("footage");
    footage_tree(&root);

    let out = eulerdisk(dir.path(), &["study", "footage", "-o", "full"]);
    clips_failed(&out);
    let full = study_json(&dir.path().join("full"));
    let experiments = full["experiments"].as_array().unwrap();
    let failures = full["failures"].as_array().unwrap();
    assert_eq!(experiments.len(), 4, "{full:#}");
    assert_eq!(failures.len(), 3, "{full:#}");
    let reason = |clip: &str| {
        failures
            .iter()
            .find(|f| f["clip"].as_str().unwrap().ends_with(clip))
            .map(|f| f["reason"].as_str().unwrap().to_string())
            .unwrap_or_else(|| panic!("no failure listed for {clip}"))
    };
    assert!(reason("corrupt.mp4").contains("corrupt.mp4"));
    assert!(reason("truncated.mp4").contains("truncated.mp4"));
    assert!(reason("nodisk").contains("no disk"));
    // Folder names give the material; the same clip gives the same n in both.
    let n: Vec<f64> = experiments
        .iter()
        .map(|e| e["n"].as_f64().unwrap())
        .collect();
    assert!(n.iter().all(|v| (v - n[0]).abs() < 1e-12), "{n:?}");
    assert_eq!(experiments[0]["meta"]["material"], "oak");
    let page = std::fs::read_to_string(dir.path().join("full/index.html")).unwrap();
    assert!(page.contains("no disk in view"));
    assert!(
        dir.path()
            .join("full/experiments/euler/oak/run1.mp4/index.html")
            .is_file()
    );

    // Resume: every good clip is reused, the failed ones are tried again.
    let out = eulerdisk(dir.path(), &["study", "footage", "-o", "full", "--resume"]);
    clips_failed(&out);
    let log = String::from_utf8_lossy(&out.stderr);
    assert_eq!(log.matches("reused").count(), 4, "{log}");
    assert_eq!(log.matches("FAILED").count(), 3, "{log}");

    // Shards 1/2 and 2/2, merged, equal the single run.
    for k in ["1/2", "2/2"] {
        let name = format!("shard-{}", &k[..1]);
        clips_failed(&eulerdisk(
            dir.path(),
            &["study", "footage", "-o", &name, "--shard", k],
        ));
    }
    clips_failed(&eulerdisk(
        dir.path(),
        &["merge", "shard-1", "shard-2", "-o", "merged"],
    ));
    let merged = study_json(&dir.path().join("merged"));
    assert_eq!(merged, full);
    let merged_page = std::fs::read_to_string(dir.path().join("merged/index.html")).unwrap();
    assert_eq!(
        merged_page, page,
        "the merged report is the single run's report"
    );

    // Issue 13.2: merging 1 of 2 shards said "merged 1 shards" and exited 0.
    let out = eulerdisk(dir.path(), &["merge", "shard-1", "-o", "half"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("shard 2/2 missing"), "{stderr}");
    assert!(!dir.path().join("half/study.json").exists());

    // Issue 13.2: a typo in the root eulerdisk.toml made every clip fail, replaced
    // the complete report and exited 0. The report is kept, the run says so and
    // why (the file, the key and its line), and exits 2.
    let before = std::fs::read(dir.path().join("full/study.json")).unwrap();
    std::fs::write(root.join("eulerdisk.toml"), "fps = 480\nfsp = 480\n").unwrap();
    let out = eulerdisk(dir.path(), &["study", "footage", "-o", "full", "--resume"]);
    clips_failed(&out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("kept the previous report"), "{stderr}");
    assert!(
        stderr.contains("eulerdisk.toml") && stderr.contains("fsp") && stderr.contains("line 2"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read(dir.path().join("full/study.json")).unwrap(),
        before
    );
    assert_eq!(
        std::fs::read_to_string(dir.path().join("full/index.html")).unwrap(),
        page
    );
}

/// `study --published` regenerates Tables 3.2 and 3.3 from Appendix B (the ±0.002
/// check of every p-value is `stats`' unit test; here: the files and one value).
#[test]
fn published_tables_are_written() {
    let dir = tempfile::tempdir().unwrap();
    ok(&eulerdisk(
        dir.path(),
        &["study", "--published", "-o", "pub"],
    ));
    for file in [
        "index.html",
        "tables/table_3_2.md",
        "tables/table_3_3.csv",
        "plots/figure_3_15.svg",
    ] {
        assert!(dir.path().join("pub").join(file).is_file(), "{file}");
    }
}

/// The study page loads in headless Chromium with no console messages (the pages
/// carry no scripts, so any message is an error). Skipped, with a message, when
/// Chromium is not installed (`scripts/setup-deps --tests` installs it).
#[test]
fn study_page_loads_in_headless_chromium_without_errors() {
    let Some(chromium) = ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|c| {
            Command::new(c)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        })
    else {
        eprintln!("SKIPPED: no chromium on PATH (scripts/setup-deps --tests installs it)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    ok(&eulerdisk(
        dir.path(),
        &["study", "--published", "-o", "pub"],
    ));
    let root = dir.path().join("footage");
    footage_tree(&root);
    clips_failed(&eulerdisk(dir.path(), &["study", "footage", "-o", "full"]));
    for page in [
        "pub/index.html",
        "full/index.html",
        "full/experiments/euler/oak/run1.mp4/index.html",
    ] {
        let url = format!("file://{}", dir.path().join(page).display());
        let out = Command::new(chromium)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--enable-logging=stderr",
                "--v=0",
                "--dump-dom",
                &url,
            ])
            .output()
            .unwrap();
        let dom = String::from_utf8_lossy(&out.stdout);
        assert!(
            dom.contains("</table>") || dom.contains("<svg"),
            "{page}: nothing rendered"
        );
        let log = String::from_utf8_lossy(&out.stderr);
        let console: Vec<&str> = log.lines().filter(|l| l.contains("CONSOLE")).collect();
        assert!(console.is_empty(), "{page}: console messages: {console:#?}");
    }
}
