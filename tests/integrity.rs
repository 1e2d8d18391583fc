//! Issue 73, tables a lab can trust: every CSV and JSON file reads back with a
//! standard reader, names of any characters round-trip, shards of different
//! footage are refused, a merged report links to every clip's page, no lock or
//! staging file is left behind, and each command ends with the status it promises.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crate::util::{eulerdisk, fixture};

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Exit status `code`, or a panic showing what the command printed.
fn status(out: &Output, code: i32) {
    assert_eq!(
        out.status.code(),
        Some(code),
        "stdout: {}\nstderr: {}",
        String::from_utf8_lossy(&out.stdout),
        stderr(out)
    );
}

/// Every path below `dir` (symbolic links not followed).
fn tree(dir: &Path) -> Vec<PathBuf> {
    let mut paths = Vec::new();
    let mut folders = vec![dir.to_path_buf()];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let entry = entry.unwrap();
            if entry.file_type().unwrap().is_dir() {
                folders.push(entry.path());
            }
            paths.push(entry.path());
        }
    }
    paths.sort();
    paths
}

/// Issue 73.6 and 73.9: usage errors exited 2, the status of "finished but some
/// clips failed"; `--overlay-fps 0` failed after the whole analysis, `1e9` was
/// taken. A command line that cannot be parsed exits 64 at once, naming the flag,
/// and writes nothing.
#[test]
fn usage_errors_exit_64_naming_the_flag_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let clip = fixture("side-dark-n050.mp4");
    let clip = clip.to_str().unwrap();
    for (args, flag) in [
        (&["study", ".", "--shard", "3/2"][..], "--shard"),
        (&["render", "--crf", "99", "-o", "x.mp4"], "--crf"),
        (&["study", ".", "--no-such-flag"], "--no-such-flag"),
        (&["analyse", clip, "--overlay-fps", "0"], "--overlay-fps"),
        (&["analyse", clip, "--overlay-fps", "1e9"], "--overlay-fps"),
    ] {
        let out = eulerdisk(dir.path(), args);
        status(&out, 64);
        assert!(stderr(&out).contains(flag), "{args:?}: {}", stderr(&out));
    }
    assert!(tree(dir.path()).is_empty(), "{:?}", tree(dir.path()));
    status(&eulerdisk(dir.path(), &["study", "--help"]), 0);
}

/// Issue 73.11: `info` on an unreadable file printed FFmpeg's raw log line before
/// its own error. The error is the only line.
#[test]
fn info_on_an_unreadable_file_prints_one_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = eulerdisk::rng::SplitMix64::new(73);
    let bytes: Vec<u8> = (0..20_000).map(|_| rng.next_u64() as u8).collect();
    std::fs::write(dir.path().join("random.mp4"), bytes).unwrap();
    let out = eulerdisk(dir.path(), &["info", "random.mp4"]);
    status(&out, 1);
    let err = stderr(&out);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("error: random.mp4"), "{err}");
}

/// Issue 73.3: a model that had not halted by the simulation's end was rendered
/// rolling to the last frame, then flat, with a halt and n in its truth. It is
/// refused, and nothing is written.
#[test]
fn render_refuses_a_simulation_that_does_not_halt() {
    let dir = tempfile::tempdir().unwrap();
    let out = eulerdisk(
        dir.path(),
        &[
            "render",
            "--simulate",
            "--eta",
            "1e-12",
            "--size",
            "320x180",
            "--after-halt",
            "0.02",
            "-o",
            "x.mp4",
        ],
    );
    status(&out, 1);
    assert!(stderr(&out).contains("did not halt"), "{}", stderr(&out));
    assert!(tree(dir.path()).is_empty(), "{:?}", tree(dir.path()));
}

/// Issue 73.8: a failed `simulate` left its empty output folder.
#[test]
fn a_failed_simulate_leaves_no_folder() {
    let dir = tempfile::tempdir().unwrap();
    let out = eulerdisk(
        dir.path(),
        &["simulate", "--model", "none", "--t-end", "1e9", "-o", "sim"],
    );
    status(&out, 1);
    assert!(!dir.path().join("sim").exists());
}

/// The fixture with `fps = 480` beside it, analysed into `dir/exp`.
fn analysed_experiment(dir: &Path) -> PathBuf {
    std::fs::copy(fixture("side-dark-n050.mp4"), dir.join("clip.mp4")).unwrap();
    std::fs::write(dir.join("clip.toml"), "fps = 480\n").unwrap();
    let out = eulerdisk(dir, &["analyse", "clip.mp4", "-o", "exp", "--no-overlay"]);
    status(&out, 0);
    dir.join("exp")
}

/// Issue 73.4: `compare --all-models` exited 0 when every model failed. It is an
/// error naming the experiment.
#[test]
fn compare_fails_when_every_model_fails() {
    let dir = tempfile::tempdir().unwrap();
    analysed_experiment(dir.path());
    let out = eulerdisk(
        dir.path(),
        &[
            "compare",
            "exp",
            "--all-models",
            "--lead",
            "100",
            "--no-overlay",
        ],
    );
    status(&out, 1);
    assert!(
        stderr(&out).contains("every model failed"),
        "{}",
        stderr(&out)
    );
}

/// The clips of the awkward-name study: a comma, quotes, spaces, non-ASCII, `#`
/// and `%` in folder and file names.
const AWKWARD: [&str; 3] = [
    "oak, old/run1.mp4",
    "say \"hi\"/run 2.mp4",
    "ébène/#3 100%.mp4",
];

/// `root` holding the fixture under each of [`AWKWARD`]'s names, `fps = 480`, and
/// a symbolic-link loop.
fn awkward_footage(root: &Path) {
    let bytes = std::fs::read(fixture("side-dark-n050.mp4")).unwrap();
    for name in AWKWARD {
        let path = root.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, &bytes).unwrap();
    }
    std::fs::write(root.join("eulerdisk.toml"), "fps = 480\n").unwrap();
    std::os::unix::fs::symlink("..", root.join("oak, old/loop")).unwrap();
}

/// `merge`'s `%XX` escapes decoded.
fn percent_decoded(url: &str) -> String {
    percent_encoding::percent_decode_str(url)
        .decode_utf8()
        .unwrap()
        .into_owned()
}

/// Every CSV below `dir` reads back with the `csv` crate, each row as wide as its
/// header; every JSON file parses. Returns exponents.csv's clip column.
fn read_back(dir: &Path) -> Vec<String> {
    let mut clips = Vec::new();
    for path in tree(dir) {
        match path.extension().and_then(|e| e.to_str()) {
            Some("csv") => {
                let mut reader = csv::Reader::from_path(&path).unwrap();
                let width = reader.headers().unwrap().len();
                assert!(width > 0, "{}: no header", path.display());
                for row in reader.records() {
                    let row = row.unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                    assert_eq!(row.len(), width, "{}: {row:?}", path.display());
                    if path.ends_with("tables/exponents.csv") {
                        clips.push(row[0].to_string());
                    }
                }
            }
            Some("json") => {
                let text = std::fs::read_to_string(&path).unwrap();
                serde_json::from_str::<serde_json::Value>(&text)
                    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            }
            _ => {}
        }
    }
    clips
}

/// Issues 73.1, 73.2, 73.8, 73.12, 73.13, and the CSV round trip. A study of clips
/// with awkward names, once whole with its output inside the footage folder and
/// once as two Slurm array tasks (`scripts/slurm/study-array.sh`) merged: the
/// symbolic-link loop is skipped with a warning; every CSV and JSON reads back and
/// every name comes back as written; the merged report equals the whole run's and
/// links to every clip's page, which exists; no lock or staging file is left, and
/// nothing but the output is written into the footage folder; a shard of other
/// footage is refused by `merge`.
#[test]
fn a_study_of_awkward_names_round_trips_and_merges_with_its_pages() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("foot");
    awkward_footage(&root);
    let footage_before = tree(&root);

    let out = eulerdisk(
        dir.path(),
        &["study", "foot", "-o", "foot/results", "--no-overlay"],
    );
    status(&out, 0);
    assert!(
        stderr(&out).contains("warning:") && stderr(&out).contains("loop"),
        "{}",
        stderr(&out)
    );
    let whole = root.join("results");
    let mut expected: Vec<String> = AWKWARD.iter().map(|s| s.to_string()).collect();
    expected.sort();
    let mut clips = read_back(&whole);
    clips.sort();
    assert_eq!(clips, expected);

    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/slurm/study-array.sh");
    let bin = Path::new(env!("CARGO_BIN_EXE_eulerdisk")).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    for k in ["1", "2"] {
        let out = Command::new("bash")
            .arg(&script)
            .args(["foot", "out"])
            .env("PATH", &path)
            .env("SLURM_ARRAY_TASK_ID", k)
            .env("SLURM_ARRAY_TASK_COUNT", "2")
            .current_dir(dir.path())
            .output()
            .unwrap();
        status(&out, 0);
    }
    let out = eulerdisk(
        dir.path(),
        &["merge", "out/shard-1", "out/shard-2", "-o", "merged"],
    );
    status(&out, 0);
    let merged = dir.path().join("merged");
    let mut clips = read_back(&merged);
    clips.sort();
    assert_eq!(clips, expected);
    let study = |dir: &Path| std::fs::read(dir.join("study.json")).unwrap();
    assert_eq!(study(&merged), study(&whole));
    let page = std::fs::read_to_string(merged.join("index.html")).unwrap();
    let links: Vec<&str> = page
        .split("href=\"")
        .skip(1)
        .filter_map(|s| s.split('"').next())
        .filter(|href| href.starts_with("experiments/"))
        .collect();
    assert_eq!(links.len(), AWKWARD.len(), "{page}");
    for href in links {
        let target = merged.join(percent_decoded(href));
        assert!(target.is_file(), "{href} → {}", target.display());
    }

    // Nothing but the output in the footage folder; no lock or staging anywhere.
    let footage_after: Vec<PathBuf> = tree(&root)
        .into_iter()
        .filter(|p| !p.starts_with(&whole))
        .collect();
    assert_eq!(footage_after, footage_before);
    let left: Vec<PathBuf> = tree(dir.path())
        .into_iter()
        .filter(|p| {
            let name = p.file_name().unwrap().to_string_lossy();
            name.ends_with(".lock") || name.contains(".staging-") || name.contains(".replaced-")
        })
        .collect();
    assert!(left.is_empty(), "{left:?}");

    // A shard of other footage (one clip of the same bytes) is refused.
    let other = dir.path().join("other");
    std::fs::create_dir(&other).unwrap();
    std::fs::copy(root.join(AWKWARD[0]), other.join("run1.mp4")).unwrap();
    std::fs::write(other.join("eulerdisk.toml"), "fps = 480\n").unwrap();
    let out = eulerdisk(
        dir.path(),
        &[
            "study",
            "other",
            "-o",
            "other-2",
            "--shard",
            "2/2",
            "--no-overlay",
        ],
    );
    status(&out, 0);
    let out = eulerdisk(
        dir.path(),
        &["merge", "out/shard-1", "other-2", "-o", "mixed"],
    );
    status(&out, 1);
    assert!(
        stderr(&out).contains("study of 1 clips"),
        "{}",
        stderr(&out)
    );
    assert!(!dir.path().join("mixed/study.json").exists());
}

/// Issue 73.5: the output lock was taken on the path as spelled, so a study into
/// `out` and one into a link to `out` ran at once. The second is refused while the
/// first runs.
#[test]
fn a_study_through_a_link_to_a_busy_output_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("foot");
    std::fs::create_dir(&root).unwrap();
    std::fs::copy(fixture("side-dark-n050.mp4"), root.join("run1.mp4")).unwrap();
    std::fs::write(root.join("eulerdisk.toml"), "fps = 480\n").unwrap();
    std::fs::create_dir(dir.path().join("out")).unwrap();
    std::os::unix::fs::symlink("out", dir.path().join("link-to-out")).unwrap();
    let first = Command::new(env!("CARGO_BIN_EXE_eulerdisk"))
        .args(["study", "foot", "-o", "out"])
        .current_dir(dir.path())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // The first run holds the lock once its lock file is there.
    let lock = dir.path().canonicalize().unwrap().join(".out.lock");
    let started = std::time::Instant::now();
    while !lock.exists() {
        assert!(
            started.elapsed().as_secs() < 30,
            "the first study took no lock"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    // The file is made a moment before it is locked.
    std::thread::sleep(std::time::Duration::from_millis(100));
    let second = eulerdisk(dir.path(), &["study", "foot", "-o", "link-to-out"]);
    let first = first.wait_with_output().unwrap();
    status(&first, 0);
    status(&second, 1);
    assert!(
        stderr(&second).contains("another eulerdisk run"),
        "{}",
        stderr(&second)
    );
    assert!(!lock.exists(), "the lock file is removed");
}
