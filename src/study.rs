//! Studies: every clip below a footage root, analysed in parallel, resumable and
//! shardable, with the failures listed beside the results.
//!
//! ```text
//! ROOT/                          discover(): videos and frame folders, natural order
//!   eulerdisk.toml               config inherited by every clip below (config::)
//!   study.toml | study.csv       optional manifest: metadata and per-clip overrides
//!   euler/stainless-steel/run07.mp4   metadata from folder names: disk/material/run
//!   ▼
//! run(): rayon over the clips of this shard; per clip a ClipAnalyser writes
//!        OUT/experiments/<clip>/ and returns an ExperimentSummary
//!   ▼
//! OUT/study.json                 StudyResults: summaries + failures, sorted
//! ```
//!
//! Each clip's folder holds `summary.json`, written last and atomically, with the
//! clip's resume key (a hash of the clip's bytes, its resolved plan and the crate
//! version): `--resume` reuses a clip whose key is unchanged and redoes the rest,
//! including every clip that failed or was interrupted. `--shard K/N` takes every
//! N-th clip of the sorted list starting at the K-th; [`merge`] combines the
//! shards' `study.json` into the one a single run makes.

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::footage::{FRAME_EXTENSIONS, VIDEO_EXTENSIONS, natural_cmp};
use crate::report::{self, ReportError};

/// File name of a clip's summary inside its experiment folder (written last).
pub const SUMMARY_FILE: &str = "summary.json";
/// File name of the study's results inside the output folder.
pub const STUDY_FILE: &str = "study.json";

/// Why a study could not run at all (a single clip's failure is not one of these).
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    #[error("{}: {reason}", path.display())]
    Root { path: PathBuf, reason: String },
    #[error("{}: manifest: {reason}", path.display())]
    Manifest { path: PathBuf, reason: String },
    #[error("--shard {text}: {reason}")]
    Shard { text: String, reason: String },
    #[error("{}: {reason}", path.display())]
    Merge { path: PathBuf, reason: String },
    #[error(transparent)]
    Write(#[from] ReportError),
}

/// What a study knows about a clip besides its pixels.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClipMeta {
    pub disk: Option<String>,
    pub material: Option<String>,
    pub orientation: Option<String>,
    pub run: Option<String>,
}

/// One clip of a study.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ClipEntry {
    pub path: PathBuf,
    /// Path below the study root with `/` separators: the clip's name in reports.
    pub relative: String,
    pub meta: ClipMeta,
}

impl ClipEntry {
    /// The clip's experiment folder below `out`: its relative path without the
    /// extension, so `euler/steel/run07.mp4` → `OUT/experiments/euler/steel/run07`.
    pub fn experiment_dir(&self, out: &Path) -> PathBuf {
        let mut dir = out.join("experiments").join(&self.relative);
        if self.path.is_file() {
            dir.set_extension("");
        }
        dir
    }
}

/// One manifest row: a clip path relative to the root and its metadata.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct ManifestRow {
    path: String,
    disk: Option<String>,
    material: Option<String>,
    orientation: Option<String>,
    run: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ManifestToml {
    clip: Vec<ManifestRow>,
}

/// The clips below `root`, in natural order of their relative paths: video files,
/// and folders of frame images (a frame folder is one clip; it is not searched
/// further). Metadata comes from `root/study.toml` or `root/study.csv` when present
/// (a listed clip missing on disk is an error; an unlisted clip gets folder-name
/// metadata), else from the folder names: `DISK/MATERIAL/RUN`, `MATERIAL/RUN`, or
/// `DISK/MATERIAL/ORIENTATION/RUN`.
///
/// # Errors
/// The root cannot be listed or holds no clip; the manifest is malformed or names
/// a clip that does not exist.
pub fn discover(root: &Path) -> Result<Vec<ClipEntry>, StudyError> {
    let root_error = |reason: String| StudyError::Root {
        path: root.to_path_buf(),
        reason,
    };
    if !root.is_dir() {
        return Err(root_error("not a folder".into()));
    }
    let mut paths = Vec::new();
    collect_clips(root, &mut paths).map_err(|e| root_error(e.to_string()))?;
    let mut clips: Vec<ClipEntry> = paths
        .into_iter()
        .map(|path| {
            let relative = relative_name(root, &path);
            let meta = meta_from_folders(&relative);
            ClipEntry {
                path,
                relative,
                meta,
            }
        })
        .collect();
    clips.sort_by(|a, b| natural_cmp(&a.relative, &b.relative));
    if let Some((manifest_path, rows)) = read_manifest(root)? {
        for row in rows {
            let relative = row.path.trim_start_matches("./").to_string();
            let Some(clip) = clips.iter_mut().find(|c| c.relative == relative) else {
                return Err(StudyError::Manifest {
                    path: manifest_path,
                    reason: format!("lists '{relative}', which is not a clip below the root"),
                });
            };
            clip.meta = ClipMeta {
                disk: row.disk,
                material: row.material,
                orientation: row.orientation,
                run: row.run,
            };
        }
    }
    if clips.is_empty() {
        return Err(root_error(
            "no clips found (video files or folders of frame images)".into(),
        ));
    }
    Ok(clips)
}

fn collect_clips(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    let mut has_frames = false;
    let mut subdirs = Vec::new();
    let mut videos = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
        if name.as_deref().is_none_or(|n| n.starts_with('.')) {
            continue;
        }
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        if path.is_dir() {
            subdirs.push(path);
        } else if VIDEO_EXTENSIONS.contains(&ext.as_str()) {
            videos.push(path);
        } else if FRAME_EXTENSIONS.contains(&ext.as_str()) {
            has_frames = true;
        }
    }
    if has_frames {
        out.push(dir.to_path_buf());
        return Ok(());
    }
    out.extend(videos);
    for sub in subdirs {
        collect_clips(&sub, out)?;
    }
    Ok(())
}

fn relative_name(root: &Path, path: &Path) -> String {
    let rel = path.strip_prefix(root).unwrap_or(path);
    let parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if parts.is_empty() {
        ".".into()
    } else {
        parts.join("/")
    }
}

/// Metadata from the folder names of a relative clip path (see [`discover`]).
fn meta_from_folders(relative: &str) -> ClipMeta {
    let parts: Vec<&str> = relative.split('/').collect();
    let run = parts.last().map(|name| {
        let stem = Path::new(name)
            .file_stem()
            .map_or(*name, |s| s.to_str().unwrap_or(name));
        stem.to_string()
    });
    let folders = &parts[..parts.len().saturating_sub(1)];
    let own = |s: &&str| Some(s.to_string());
    match folders {
        [] => ClipMeta {
            run,
            ..ClipMeta::default()
        },
        [material] => ClipMeta {
            material: own(material),
            run,
            ..ClipMeta::default()
        },
        [.., disk, material] => ClipMeta {
            disk: own(disk),
            material: own(material),
            run,
            orientation: None,
        },
    }
    .with_orientation(folders)
}

impl ClipMeta {
    /// `DISK/MATERIAL/ORIENTATION/RUN`: the third folder is the orientation.
    fn with_orientation(self, folders: &[&str]) -> Self {
        match folders {
            [.., disk, material, orientation] if folders.len() >= 3 => ClipMeta {
                disk: Some(disk.to_string()),
                material: Some(material.to_string()),
                orientation: Some(orientation.to_string()),
                run: self.run,
            },
            _ => self,
        }
    }

    /// The group a clip's exponent is pooled in: material, else "all".
    pub fn material_or_all(&self) -> &str {
        self.material.as_deref().unwrap_or("all")
    }
}

fn read_manifest(root: &Path) -> Result<Option<(PathBuf, Vec<ManifestRow>)>, StudyError> {
    let toml_path = root.join("study.toml");
    let csv_path = root.join("study.csv");
    let bad = |path: &Path, reason: String| StudyError::Manifest {
        path: path.to_path_buf(),
        reason,
    };
    if toml_path.is_file() {
        let text =
            std::fs::read_to_string(&toml_path).map_err(|e| bad(&toml_path, e.to_string()))?;
        let manifest: ManifestToml =
            toml::from_str(&text).map_err(|e| bad(&toml_path, e.to_string()))?;
        return Ok(Some((toml_path, manifest.clip)));
    }
    if csv_path.is_file() {
        let mut reader =
            csv::Reader::from_path(&csv_path).map_err(|e| bad(&csv_path, e.to_string()))?;
        let rows = reader
            .deserialize()
            .collect::<Result<Vec<ManifestRow>, _>>()
            .map_err(|e| bad(&csv_path, e.to_string()))?;
        return Ok(Some((csv_path, rows)));
    }
    Ok(None)
}

/// One share of a study: clips `K-1, K-1+N, K-1+2N, …` of the sorted list.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// 1-based index of this share.
    pub k: usize,
    pub n: usize,
}

impl std::str::FromStr for Shard {
    type Err = StudyError;

    /// Parse `K/N` with 1 ≤ K ≤ N (Slurm: `--shard $((SLURM_ARRAY_TASK_ID+1))/N`).
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let err = |reason: &str| StudyError::Shard {
            text: text.into(),
            reason: reason.into(),
        };
        let (k, n) = text
            .split_once('/')
            .ok_or_else(|| err("expected K/N, e.g. 2/8"))?;
        let k: usize = k
            .trim()
            .parse()
            .map_err(|_| err("K is not a whole number"))?;
        let n: usize = n
            .trim()
            .parse()
            .map_err(|_| err("N is not a whole number"))?;
        if n == 0 || k == 0 || k > n {
            return Err(err("need 1 ≤ K ≤ N"));
        }
        Ok(Shard { k, n })
    }
}

impl Shard {
    /// The clips of this share.
    pub fn select(self, clips: Vec<ClipEntry>) -> Vec<ClipEntry> {
        clips
            .into_iter()
            .enumerate()
            .filter(|(i, _)| i % self.n == self.k - 1)
            .map(|(_, c)| c)
            .collect()
    }
}

/// What the study keeps of one analysed clip (the experiment folder holds the rest).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExperimentSummary {
    pub clip: String,
    pub meta: ClipMeta,
    /// Hash of the clip's bytes, its resolved plan and the crate version.
    pub resume_key: String,
    /// Fitted exponent n of E = A_e (t0 − t)^n and its 95 % interval.
    pub n: f64,
    pub n_ci95: [f64; 2],
    /// Fitted halt time t0 [s] relative to the measured halt.
    pub t0_s: f64,
    pub r_squared: f64,
    pub points: usize,
    /// Frames per second used, and where that number came from.
    pub fps: f64,
    pub fps_source: String,
    /// Warnings and frame flags a reader should see beside the number.
    pub warnings: Vec<String>,
}

/// A clip that failed, and why (the message names the file and, where relevant,
/// the frame).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClipFailure {
    pub clip: String,
    pub meta: ClipMeta,
    pub reason: String,
}

/// The results of a study (or of one shard of it).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct StudyResults {
    pub experiments: Vec<ExperimentSummary>,
    pub failures: Vec<ClipFailure>,
    pub crate_version: String,
}

impl StudyResults {
    fn sort(&mut self) {
        self.experiments
            .sort_by(|a, b| natural_cmp(&a.clip, &b.clip));
        self.failures.sort_by(|a, b| natural_cmp(&a.clip, &b.clip));
    }
}

/// The per-clip work a study runs.
pub trait ClipAnalyser: Sync {
    /// The resume key of a clip: changes whenever its bytes, its resolved plan or
    /// the crate version change.
    ///
    /// # Errors
    /// A message (naming the file) when the clip or its config cannot be read.
    fn resume_key(&self, clip: &ClipEntry) -> Result<String, String>;

    /// Analyse one clip, writing its outputs into `dir`.
    ///
    /// # Errors
    /// A message naming the file, the frame where relevant, and the reason.
    fn analyse(&self, clip: &ClipEntry, dir: &Path, key: &str)
    -> Result<ExperimentSummary, String>;
}

/// Something a study tells its caller while it runs (the CLI shows it).
#[derive(Debug, Clone)]
pub enum StudyEvent<'a> {
    Started { clips: usize },
    Finished { clip: &'a str, outcome: Outcome<'a> },
}

/// How one clip ended.
#[derive(Debug, Clone)]
pub enum Outcome<'a> {
    Analysed(&'a ExperimentSummary),
    Reused(&'a ExperimentSummary),
    Failed(&'a str),
}

/// Options of [`run`].
#[derive(Debug, Clone, Copy, Default)]
pub struct RunOptions {
    pub shard: Option<Shard>,
    pub resume: bool,
}

/// Analyse the clips (of this shard) in parallel and write `out/study.json`.
/// A failing clip is listed and never stops the others.
///
/// # Errors
/// Only when `study.json` cannot be written.
pub fn run(
    clips: Vec<ClipEntry>,
    out: &Path,
    options: RunOptions,
    analyser: &dyn ClipAnalyser,
    events: &(dyn Fn(StudyEvent) + Sync),
) -> Result<StudyResults, StudyError> {
    let clips = match options.shard {
        Some(shard) => shard.select(clips),
        None => clips,
    };
    events(StudyEvent::Started { clips: clips.len() });
    let outcomes: Vec<Result<ExperimentSummary, Box<ClipFailure>>> = clips
        .par_iter()
        .map(|clip| {
            let outcome = analyse_one(clip, out, options.resume, analyser);
            match &outcome {
                Ok((summary, reused)) => events(StudyEvent::Finished {
                    clip: &clip.relative,
                    outcome: if *reused {
                        Outcome::Reused(summary)
                    } else {
                        Outcome::Analysed(summary)
                    },
                }),
                Err(failure) => events(StudyEvent::Finished {
                    clip: &clip.relative,
                    outcome: Outcome::Failed(&failure.reason),
                }),
            }
            outcome.map(|(summary, _)| summary)
        })
        .collect();
    let mut results = StudyResults {
        crate_version: env!("CARGO_PKG_VERSION").into(),
        ..StudyResults::default()
    };
    for outcome in outcomes {
        match outcome {
            Ok(summary) => results.experiments.push(summary),
            Err(failure) => results.failures.push(*failure),
        }
    }
    results.sort();
    report::write_json(&out.join(STUDY_FILE), &results)?;
    Ok(results)
}

fn analyse_one(
    clip: &ClipEntry,
    out: &Path,
    resume: bool,
    analyser: &dyn ClipAnalyser,
) -> Result<(ExperimentSummary, bool), Box<ClipFailure>> {
    let fail = |reason: String| {
        Box::new(ClipFailure {
            clip: clip.relative.clone(),
            meta: clip.meta.clone(),
            reason,
        })
    };
    let key = analyser.resume_key(clip).map_err(fail)?;
    let dir = clip.experiment_dir(out);
    let summary_path = dir.join(SUMMARY_FILE);
    if resume {
        let previous = std::fs::read(&summary_path)
            .ok()
            .and_then(|bytes| serde_json::from_slice::<ExperimentSummary>(&bytes).ok());
        if let Some(previous) = previous.filter(|p| p.resume_key == key) {
            return Ok((previous, true));
        }
    }
    let summary = analyser.analyse(clip, &dir, &key).map_err(fail)?;
    report::write_json(&summary_path, &summary).map_err(|e| fail(e.to_string()))?;
    Ok((summary, false))
}

/// Combine the `study.json` of shard output folders into one [`StudyResults`],
/// identical to what a single run over all clips writes.
///
/// # Errors
/// A shard folder without `study.json`, an unreadable one, or a clip that two
/// shards both analysed.
pub fn merge(shard_dirs: &[PathBuf]) -> Result<StudyResults, StudyError> {
    let mut merged = StudyResults {
        crate_version: env!("CARGO_PKG_VERSION").into(),
        ..StudyResults::default()
    };
    for dir in shard_dirs {
        let path = dir.join(STUDY_FILE);
        let bad = |reason: String| StudyError::Merge {
            path: path.clone(),
            reason,
        };
        let bytes = std::fs::read(&path).map_err(|e| bad(e.to_string()))?;
        let shard: StudyResults = serde_json::from_slice(&bytes).map_err(|e| bad(e.to_string()))?;
        if shard.crate_version != merged.crate_version {
            return Err(bad(format!(
                "written by eulerdisk {}, this is {}",
                shard.crate_version, merged.crate_version
            )));
        }
        let seen = |clip: &str| {
            merged.experiments.iter().any(|e| e.clip == clip)
                || merged.failures.iter().any(|f| f.clip == clip)
        };
        for clip in shard
            .experiments
            .iter()
            .map(|e| &e.clip)
            .chain(shard.failures.iter().map(|f| &f.clip))
        {
            if seen(clip) {
                return Err(bad(format!("clip '{clip}' appears in more than one shard")));
            }
        }
        merged.experiments.extend(shard.experiments);
        merged.failures.extend(shard.failures);
    }
    merged.sort();
    Ok(merged)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    fn touch(root: &Path, rel: &str) {
        let path = root.join(rel);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, rel.as_bytes()).unwrap();
    }

    #[test]
    fn folder_names_give_disk_material_orientation_and_run() {
        let m = meta_from_folders("euler/stainless-steel/run07.mp4");
        assert_eq!(m.disk.as_deref(), Some("euler"));
        assert_eq!(m.material.as_deref(), Some("stainless-steel"));
        assert_eq!(m.run.as_deref(), Some("run07"));
        assert_eq!(
            meta_from_folders("glass/run1.mp4").material.as_deref(),
            Some("glass")
        );
        let m = meta_from_folders("brass/glass/vertical/run2.avi");
        assert_eq!(
            (
                m.disk.as_deref(),
                m.material.as_deref(),
                m.orientation.as_deref()
            ),
            (Some("brass"), Some("glass"), Some("vertical"))
        );
    }

    #[test]
    fn discover_finds_videos_and_frame_folders_in_natural_order() {
        let root = tempfile::tempdir().unwrap();
        for rel in [
            "euler/steel/run10.mp4",
            "euler/steel/run2.mp4",
            "euler/glass/run1/frame_0001.png",
            "euler/glass/run1/frame_0002.png",
            "euler/glass/notes.txt",
        ] {
            touch(root.path(), rel);
        }
        let clips = discover(root.path()).unwrap();
        let names: Vec<&str> = clips.iter().map(|c| c.relative.as_str()).collect();
        assert_eq!(
            names,
            [
                "euler/glass/run1",
                "euler/steel/run2.mp4",
                "euler/steel/run10.mp4"
            ]
        );
        assert_eq!(clips[0].meta.run.as_deref(), Some("run1"));
        let out = Path::new("/o");
        assert_eq!(
            clips[1].experiment_dir(out),
            Path::new("/o/experiments/euler/steel/run2")
        );
        assert_eq!(
            clips[0].experiment_dir(out),
            Path::new("/o/experiments/euler/glass/run1")
        );
    }

    #[test]
    fn a_manifest_overrides_metadata_and_must_name_real_clips() {
        let root = tempfile::tempdir().unwrap();
        touch(root.path(), "a.mp4");
        std::fs::write(
            root.path().join("study.csv"),
            "path,disk,material,orientation,run\na.mp4,brass,glass,,3\n",
        )
        .unwrap();
        let clips = discover(root.path()).unwrap();
        assert_eq!(clips[0].meta.material.as_deref(), Some("glass"));
        assert_eq!(clips[0].meta.run.as_deref(), Some("3"));
        std::fs::write(
            root.path().join("study.csv"),
            "path,material\nb.mp4,glass\n",
        )
        .unwrap();
        let err = discover(root.path()).unwrap_err().to_string();
        assert!(err.contains("study.csv") && err.contains("b.mp4"), "{err}");
    }

    #[test]
    fn an_empty_root_is_an_error() {
        let root = tempfile::tempdir().unwrap();
        assert!(
            discover(root.path())
                .unwrap_err()
                .to_string()
                .contains("no clips")
        );
    }

    #[test]
    fn shards_partition_the_clips() {
        let clips: Vec<ClipEntry> = (0..7)
            .map(|i| ClipEntry {
                path: PathBuf::from(format!("{i}.mp4")),
                relative: format!("{i}.mp4"),
                meta: ClipMeta::default(),
            })
            .collect();
        let mut all: Vec<String> = (1..=3)
            .flat_map(|k| Shard { k, n: 3 }.select(clips.clone()))
            .map(|c| c.relative)
            .collect();
        all.sort();
        assert_eq!(all.len(), 7);
        all.dedup();
        assert_eq!(all.len(), 7);
        assert!("0/3".parse::<Shard>().is_err());
        assert!("4/3".parse::<Shard>().is_err());
        assert_eq!("2/3".parse::<Shard>().unwrap(), Shard { k: 2, n: 3 });
    }

    /// An analyser whose "n" is the clip's byte length and that fails on clips
    /// named `bad*`; it counts its analyses.
    struct Fake {
        calls: Mutex<Vec<String>>,
    }

    impl ClipAnalyser for Fake {
        fn resume_key(&self, clip: &ClipEntry) -> Result<String, String> {
            let bytes = std::fs::read(&clip.path).map_err(|e| e.to_string())?;
            Ok(blake3::hash(&bytes).to_hex().to_string())
        }

        fn analyse(
            &self,
            clip: &ClipEntry,
            dir: &Path,
            key: &str,
        ) -> Result<ExperimentSummary, String> {
            self.calls.lock().unwrap().push(clip.relative.clone());
            if clip.relative.contains("bad") {
                return Err(format!("{}: no disk in view", clip.path.display()));
            }
            std::fs::create_dir_all(dir).unwrap();
            let n = std::fs::metadata(&clip.path).unwrap().len() as f64;
            Ok(ExperimentSummary {
                clip: clip.relative.clone(),
                meta: clip.meta.clone(),
                resume_key: key.into(),
                n,
                n_ci95: [n - 1.0, n + 1.0],
                t0_s: 0.0,
                r_squared: 1.0,
                points: 10,
                fps: 480.0,
                fps_source: "config".into(),
                warnings: vec![],
            })
        }
    }

    #[test]
    fn failures_are_listed_resume_redoes_only_what_changed_and_shards_merge_to_one_run() {
        let root = tempfile::tempdir().unwrap();
        for rel in ["m1/a.mp4", "m1/bad.mp4", "m2/b.mp4", "m2/c.mp4", "m2/d.mp4"] {
            touch(root.path(), rel);
        }
        let clips = discover(root.path()).unwrap();
        let out = tempfile::tempdir().unwrap();
        let fake = Fake {
            calls: Mutex::new(vec![]),
        };
        let quiet = |_: StudyEvent| {};
        let full = run(
            clips.clone(),
            out.path(),
            RunOptions::default(),
            &fake,
            &quiet,
        )
        .unwrap();
        assert_eq!(full.experiments.len(), 4);
        assert_eq!(full.failures.len(), 1);
        assert!(full.failures[0].reason.contains("bad.mp4"));

        // Change one clip; resume redoes it and the failed one only.
        std::fs::write(root.path().join("m2/c.mp4"), b"changed bytes").unwrap();
        fake.calls.lock().unwrap().clear();
        let resumed = RunOptions {
            resume: true,
            shard: None,
        };
        let again = run(clips.clone(), out.path(), resumed, &fake, &quiet).unwrap();
        let mut redone = fake.calls.lock().unwrap().clone();
        redone.sort();
        assert_eq!(redone, ["m1/bad.mp4", "m2/c.mp4"]);
        assert_eq!(again.experiments.len(), 4);

        // Shards in their own folders, merged, equal one run.
        let shard_dirs: Vec<PathBuf> = (1..=2)
            .map(|k| out.path().join(format!("shard-{k}")))
            .collect();
        for (k, dir) in shard_dirs.iter().enumerate() {
            let options = RunOptions {
                resume: false,
                shard: Some(Shard { k: k + 1, n: 2 }),
            };
            run(clips.clone(), dir, options, &fake, &quiet).unwrap();
        }
        assert_eq!(merge(&shard_dirs).unwrap(), again);
        // Merging a shard twice is refused.
        let twice = [shard_dirs[0].clone(), shard_dirs[0].clone()];
        assert!(
            merge(&twice)
                .unwrap_err()
                .to_string()
                .contains("more than one shard")
        );
    }
}
