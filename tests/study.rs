//! `eulerdisk study` and `merge` end to end on a footage tree built from the
//! rendered fixtures plus three broken clips, each test in a fresh folder.

use std::path::Path;
use std::process::Command;

use serde_json::Value;

use crate::util::{eulerdisk, fixture};

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
    let clip_page = dir.path().join("full/experiments/euler/oak/run1.mp4");
    assert!(clip_page.join("index.html").is_file());
    // Issue 72 §6: each refused clip has a failure page in its folder, naming the
    // stage and the reason; the clip of black frames was refused at calibration.
    for clip in ["corrupt.mp4", "truncated.mp4", "nodisk"] {
        let folder = dir.path().join("full/experiments/euler/oak").join(clip);
        let record: Value =
            serde_json::from_slice(&std::fs::read(folder.join("failure.json")).unwrap()).unwrap();
        assert_eq!(record["reason"].as_str().unwrap(), reason(clip), "{record}");
        assert!(folder.join("index.html").is_file(), "{clip}");
        assert!(!folder.join("summary.json").exists(), "{clip}");
    }
    let nodisk: Value = serde_json::from_slice(
        &std::fs::read(
            dir.path()
                .join("full/experiments/euler/oak/nodisk/failure.json"),
        )
        .unwrap(),
    )
    .unwrap();
    assert_eq!(nodisk["stage"], "opening and calibration");
    assert!(
        page.contains("href=\"experiments/euler/oak/nodisk/index.html\""),
        "the study page does not link the failed clip's page"
    );
    // The turns' timing: its plot beside the energy's, and its n within its interval in
    // the exponents table (the last three columns: rsplitn gives the high end, the low
    // end, then n).
    assert!(clip_page.join("timing.svg").is_file());
    let exponents = std::fs::read_to_string(dir.path().join("full/tables/exponents.csv")).unwrap();
    let timing: Vec<f64> = exponents
        .lines()
        .nth(1)
        .unwrap()
        .rsplitn(4, ',')
        .take(3)
        .map(|v| v.parse().unwrap())
        .collect();
    assert!(
        timing[1] <= timing[2] && timing[2] <= timing[0],
        "{exponents}"
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

/// The study pages load in headless Chromium with no console messages (the study
/// pages carry no scripts; an experiment page's scripts log nothing, so any
/// message is an error), and an experiment page's overlay video plays: after
/// Chromium's virtual time has run, the page's script has recorded the
/// `<video>`'s duration (`data-duration`, as long as overlay.json's frames at its rate)
/// and no media error (`data-error`). Fails, naming it, when Chromium is not
/// installed (`scripts/setup-deps --tests` installs it).
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
        panic!(
            "no chromium, chromium-browser or google-chrome on PATH: \
             `scripts/setup-deps --tests` installs Debian's chromium"
        );
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
                // Lets the video's metadata load before the DOM is dumped.
                "--virtual-time-budget=5000",
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
        if page.contains("experiments") {
            let video = dom
                .split("<video")
                .nth(1)
                .and_then(|v| v.split('>').next())
                .unwrap_or_else(|| panic!("{page}: no <video> element"));
            assert!(
                !video.contains("data-error"),
                "{page}: media error: {video}"
            );
            let duration: f64 = video
                .split("data-duration=\"")
                .nth(1)
                .and_then(|d| d.split('"').next())
                .and_then(|d| d.parse().ok())
                .unwrap_or_else(|| panic!("{page}: the video reports no duration: {video}"));
            let index: Value = serde_json::from_str(
                &std::fs::read_to_string(dir.path().join(page).with_file_name("overlay.json"))
                    .unwrap(),
            )
            .unwrap();
            let frames = index["frames"].as_array().unwrap().len() as f64;
            let fps = index["playback_fps"].as_f64().unwrap();
            assert!(
                (duration - frames / fps).abs() < 1.5 / fps,
                "{page}: duration {duration} s, overlay.json: {frames} frames at {fps} frames/s"
            );
        }
    }
}

/// Issue 13, fault injection with real kills: a 20-clip study (4 broken clips) is
/// killed with SIGKILL three times, each after a random number of finished clips
/// (seeded), and resumed; the final report equals an uninterrupted run's, lists
/// the 4 failures, exits 2, and no staging folder of a killed run is left.
#[test]
fn a_study_killed_three_times_resumes_to_the_uninterrupted_report() {
    use std::io::BufRead;
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("footage");
    let good = std::fs::read(fixture("side-dark-n050.mp4")).unwrap();
    std::fs::create_dir_all(&root).unwrap();
    std::fs::write(root.join("eulerdisk.toml"), "fps = 480\n").unwrap();
    for i in 0..20 {
        let folder = root.join(format!("m{}", i % 2));
        std::fs::create_dir_all(&folder).unwrap();
        let bytes: &[u8] = if i % 5 == 4 { b"not a video" } else { &good };
        std::fs::write(folder.join(format!("run{i}.mp4")), bytes).unwrap();
    }
    clips_failed(&eulerdisk(
        dir.path(),
        &["study", "footage", "-o", "reference"],
    ));

    let mut rng = eulerdisk::rng::SplitMix64::new(13);
    let mut kills = 0;
    for _ in 0..3 {
        // Killed after 1–3 clips this run analysed (reused ones do not count): at
        // most 9 of the 16 good ones are done before the last run, and the 4 broken
        // clips are tried in every run, so a kill always comes before the end.
        let kill_after = 1 + (rng.next_u64() % 3) as usize;
        let mut child = Command::new(env!("CARGO_BIN_EXE_eulerdisk"))
            .args(["study", "footage", "-o", "killed", "--resume"])
            .current_dir(dir.path())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let stderr = std::io::BufReader::new(child.stderr.take().unwrap());
        let mut finished = 0;
        for line in stderr.lines() {
            let line = line.unwrap();
            if line.starts_with('[') && !line.contains("reused") {
                finished += 1;
                if finished == kill_after {
                    child.kill().unwrap();
                    kills += 1;
                    break;
                }
            }
        }
        child.wait().unwrap();
    }
    assert_eq!(kills, 3);
    let last = eulerdisk(
        dir.path(),
        &["study", "footage", "-o", "killed", "--resume"],
    );
    clips_failed(&last);
    let reference = study_json(&dir.path().join("reference"));
    let resumed = study_json(&dir.path().join("killed"));
    assert_eq!(resumed, reference);
    assert_eq!(resumed["failures"].as_array().unwrap().len(), 4);
    for m in ["m0", "m1"] {
        for entry in std::fs::read_dir(dir.path().join("killed/experiments").join(m)).unwrap() {
            let name = entry.unwrap().file_name().to_string_lossy().into_owned();
            assert!(
                !name.contains("staging") && !name.contains("replaced"),
                "{name}"
            );
        }
    }
}

/// Issue 13.1/13.2: two runs into one output folder at once (two shards into one
/// `-o`) mixed their results; the second is refused while the first holds the
/// folder's lock, with exit status 1 and the reason.
#[test]
fn a_second_study_into_a_held_folder_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("footage");
    footage_tree(&root);
    let held = eulerdisk::output::OutputLock::acquire(&dir.path().join("out")).unwrap();
    let out = eulerdisk(
        dir.path(),
        &["study", "footage", "-o", "out", "--shard", "1/2"],
    );
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("another eulerdisk run"), "{err}");
    assert!(!dir.path().join("out/study.json").exists());
    drop(held);
}
