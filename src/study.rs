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
//!        OUT/experiments/<clip path with extension>/ and returns an ExperimentSummary
//!   ▼
//! OUT/study.json                 StudyResults: summaries + failures, sorted
//! ```
//!
//! One clip, one folder, by construction: the folder is the clip's path below the
//! root *with* its extension, so `run1.mp4` and `run1.mov` never share one. A clip's
//! folder is written whole ([`output::write_folder`]: staged, renamed into place,
//! under a lock), and holds `summary.json` with the clip's resume key (a hash of the
//! clip's bytes, its resolved plan and the crate version): `--resume` reuses a
//! clip whose key is unchanged and redoes the rest, including every clip that
//! failed or was interrupted. A study holds the lock of its output folder for the
//! whole run, so two studies (or two shards) never write one folder at once.
//!
//! The report tells the truth: a run that would lose a clip the previous
//! `study.json` had analysed keeps the previous report unless forced
//! ([`RunOptions::force`]). `--shard K/N` takes every N-th clip of the sorted list
//! starting at the K-th and records K/N and its clip list; [`merge`] refuses a
//! missing shard or a shard with a clip unaccounted for, and otherwise writes the
//! `study.json` a single run makes.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::analyse;
use crate::footage::{FRAME_EXTENSIONS, VIDEO_EXTENSIONS, natural_cmp};
use crate::output::{self, OutputError};
pub use crate::summary::{
    ClipFailure, ClipMeta, ExperimentSummary, ShardRecord, StudyResults, summary,
};

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
    Write(#[from] OutputError),
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
    /// The clip's experiment folder below `out`: its relative path with the
    /// extension, so `euler/steel/run07.mp4` → `OUT/experiments/euler/steel/run07.mp4`
    /// and two clips never share a folder.
    pub fn experiment_dir(&self, out: &Path) -> PathBuf {
        out.join("experiments").join(&self.relative)
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
/// further). Symbolic links are followed; a link back into its own ancestry (a
/// loop) is skipped, and two paths to one clip or folder are refused, rather than
/// counted twice. Output folders are never footage: `exclude` (the study's own output)
/// and any folder holding an eulerdisk result (`study.json`, `summary.json` or
/// `result.json`) are skipped. Metadata comes from `root/study.toml` or `root/study.csv` when present
/// (a listed clip missing on disk is an error; an unlisted clip gets folder-name
/// metadata), else from the folder names: `DISK/MATERIAL/RUN`, `MATERIAL/RUN`, or
/// `DISK/MATERIAL/ORIENTATION/RUN`.
///
/// A symbolic-link loop is skipped with a warning (the rest of the tree is
/// analysed).
///
/// # Errors
/// The root cannot be listed or holds no clip; a clip or folder reached twice; the
/// manifest is malformed or names a clip that does not exist.
pub fn discover(root: &Path, exclude: &Path) -> Result<Discovered, StudyError> {
    let root_error = |reason: String| StudyError::Root {
        path: root.to_path_buf(),
        reason,
    };
    if !root.is_dir() {
        return Err(root_error("not a folder".into()));
    }
    let mut walk = Walk {
        exclude: exclude.canonicalize().ok(),
        seen: Vec::new(),
        clips: Vec::new(),
        skipped: Vec::new(),
    };
    walk.visit(root, &mut Vec::new()).map_err(root_error)?;
    let paths = walk.clips;
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
    Ok(Discovered {
        root: root.canonicalize().map_err(|e| root_error(e.to_string()))?,
        clips,
        skipped: walk.skipped,
    })
}

/// What [`discover`] found below a footage root.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Discovered {
    /// The root's real path (symbolic links resolved): which footage a shard was
    /// made from.
    pub root: PathBuf,
    /// The clips, in natural order of their relative paths.
    pub clips: Vec<ClipEntry>,
    /// Why folders were left out (symbolic-link loops), one message each.
    pub skipped: Vec<String>,
}

/// The state of [`discover`]'s walk: every folder and clip reached so far by its
/// real (canonical) path, so nothing is counted twice.
struct Walk {
    exclude: Option<PathBuf>,
    /// (canonical path, path as reached).
    seen: Vec<(PathBuf, PathBuf)>,
    clips: Vec<PathBuf>,
    /// Symbolic-link loops left out, one message each.
    skipped: Vec<String>,
}

/// File names that mark a folder as eulerdisk output rather than footage.
const OUTPUT_MARKERS: [&str; 3] = [STUDY_FILE, SUMMARY_FILE, "result.json"];

impl Walk {
    /// Remembers `path` by its real path; a second path to it is an error.
    fn first_visit(&mut self, path: &Path) -> Result<(), String> {
        let real = path
            .canonicalize()
            .map_err(|e| format!("{}: {e}", path.display()))?;
        if let Some((_, earlier)) = self.seen.iter().find(|(r, _)| *r == real) {
            return Err(format!(
                "{} and {} are the same {} (a symbolic link); it would be counted twice, \
                 so remove one of them",
                earlier.display(),
                path.display(),
                if path.is_dir() { "folder" } else { "clip" }
            ));
        }
        self.seen.push((real, path.to_path_buf()));
        Ok(())
    }

    /// Collects the clips below `dir`; `ancestry` holds the real paths of the
    /// folders above it, to tell a loop from a mere second path.
    fn visit(&mut self, dir: &Path, ancestry: &mut Vec<PathBuf>) -> Result<(), String> {
        let real = dir
            .canonicalize()
            .map_err(|e| format!("{}: {e}", dir.display()))?;
        if ancestry.contains(&real) {
            // A loop holds nothing the walk has not reached already: skipping it
            // loses no clip.
            self.skipped.push(format!(
                "{}: a symbolic-link loop (it leads back to {}); skipped",
                dir.display(),
                real.display()
            ));
            return Ok(());
        }
        if self.exclude.as_ref() == Some(&real)
            || OUTPUT_MARKERS.iter().any(|m| dir.join(m).is_file())
        {
            return Ok(());
        }
        self.first_visit(dir)?;
        let listed = |e: std::io::Error| format!("{}: {e}", dir.display());
        let mut has_frames = false;
        let mut subdirs = Vec::new();
        let mut videos = Vec::new();
        for entry in std::fs::read_dir(dir).map_err(listed)? {
            let path = entry.map_err(listed)?.path();
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
            self.clips.push(dir.to_path_buf());
            return Ok(());
        }
        for video in videos {
            self.first_visit(&video)?;
            self.clips.push(video);
        }
        ancestry.push(real);
        for sub in subdirs {
            self.visit(&sub, ancestry)?;
        }
        ancestry.pop();
        Ok(())
    }
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

    /// Writes into `dir` the failure page of a clip [`Self::analyse`] refused, from
    /// what it had found (issue 72 §6); `Ok(false)` when there is none to write.
    ///
    /// # Errors
    /// A message naming the file that could not be written.
    fn explain(&self, _clip: &ClipEntry, _dir: &Path) -> Result<bool, String> {
        Ok(false)
    }
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
    /// Replace the previous `study.json` even when this run lost clips it had.
    pub force: bool,
}

/// What [`run`] did with the output folder's report.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyRun {
    /// This run's results.
    pub results: StudyResults,
    /// `Some` when the previous `study.json` was kept because this run would have
    /// lost clips it had analysed: those clips, in order.
    pub kept_previous: Option<KeptReport>,
}

/// A previous report kept in place of a worse run (see [`RunOptions::force`]).
#[derive(Debug, Clone, PartialEq)]
pub struct KeptReport {
    /// Clips analysed in the kept report.
    pub analysed: usize,
    /// Clips the kept report had analysed that this run failed or did not run.
    pub lost: Vec<String>,
}

impl StudyRun {
    /// True when every clip of this run was analysed and the report was written.
    pub fn is_complete(&self) -> bool {
        self.results.failures.is_empty() && self.kept_previous.is_none()
    }
}

/// Analyse the clips (of this shard) in parallel and write `study.json` into the
/// locked output folder `out` (the caller keeps the lock for the report pages).
/// A failing clip is listed and never stops the others. When the previous `out/study.json` has analysed clips that
/// this run failed or left out, it is kept (unless `options.force`), and the
/// returned [`StudyRun`] says so.
///
/// # Errors
/// `study.json` cannot be written.
pub fn run(
    footage: Discovered,
    out: &output::OutputLock,
    options: RunOptions,
    analyser: &dyn ClipAnalyser,
    events: &(dyn Fn(StudyEvent) + Sync),
) -> Result<StudyRun, StudyError> {
    let out = out.folder();
    output::remove_stale(&out.join("experiments"));
    let study_clips: Vec<String> = footage.clips.iter().map(|c| c.relative.clone()).collect();
    let clips = match options.shard {
        Some(shard) => shard.select(footage.clips),
        None => footage.clips,
    };
    let shard = options.shard.map(|s| ShardRecord {
        k: s.k,
        n: s.n,
        clips: clips.iter().map(|c| c.relative.clone()).collect(),
        footage: footage.root,
        study_clips,
    });
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
        shard,
        ..StudyResults::default()
    };
    for outcome in outcomes {
        match outcome {
            Ok(summary) => results.experiments.push(summary),
            Err(failure) => results.failures.push(*failure),
        }
    }
    results.sort();
    let study_file = out.join(STUDY_FILE);
    let kept_previous = if options.force {
        None
    } else {
        lost_from_previous(&study_file, &results)
    };
    if kept_previous.is_none() {
        output::write_json(&study_file, &results)?;
    }
    Ok(StudyRun {
        results,
        kept_previous,
    })
}

/// The clips the previous report at `path` analysed and `results` does not have:
/// `Some` when there is at least one (an unreadable previous report counts as none).
fn lost_from_previous(path: &Path, results: &StudyResults) -> Option<KeptReport> {
    let bytes = std::fs::read(path).ok()?;
    let previous: StudyResults = serde_json::from_slice(&bytes).ok()?;
    let now: BTreeSet<&str> = results
        .experiments
        .iter()
        .map(|e| e.clip.as_str())
        .collect();
    let lost: Vec<String> = previous
        .experiments
        .iter()
        .filter(|e| !now.contains(e.clip.as_str()))
        .map(|e| e.clip.clone())
        .collect();
    (!lost.is_empty()).then_some(KeptReport {
        analysed: previous.experiments.len(),
        lost,
    })
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
    if resume {
        let previous = std::fs::read(dir.join(SUMMARY_FILE))
            .ok()
            .and_then(|bytes| serde_json::from_slice::<ExperimentSummary>(&bytes).ok());
        if let Some(previous) = previous.filter(|p| p.resume_key == key) {
            return Ok((previous, true));
        }
    }
    let summary = output::write_folder(&dir, |staging| {
        let summary = analyser
            .analyse(clip, staging, &key)
            .map_err(Failed::Clip)?;
        output::write_json(&staging.join(SUMMARY_FILE), &summary)?;
        Ok::<_, Failed>(summary)
    });
    match summary {
        Ok(summary) => Ok((summary, false)),
        Err(Failed::Clip(reason)) => {
            explain_refusal(clip, &dir, analyser);
            Err(fail(reason))
        }
        Err(e) => Err(fail(e.to_string())),
    }
}

/// The failure page of a refused clip in its folder `dir`, unless the folder holds an
/// earlier result, which a failure page never replaces. A page that cannot be
/// written leaves the folder as it was: the study's report names the reason anyway.
fn explain_refusal(clip: &ClipEntry, dir: &Path, analyser: &dyn ClipAnalyser) {
    if dir.join(SUMMARY_FILE).is_file() {
        return;
    }
    let written = output::write_folder(dir, |staging| match analyser.explain(clip, staging) {
        Ok(true) => Ok(()),
        Ok(false) => Err(Failed::Clip("no failure page".into())),
        Err(reason) => Err(Failed::Clip(reason)),
    });
    if let Err(Failed::Write(e)) = written {
        eprintln!("warning: {}: its failure page: {e}", clip.path.display());
    }
}

/// Why one clip's folder was not written: the analysis, or the writing.
#[derive(Debug, thiserror::Error)]
enum Failed {
    #[error("{0}")]
    Clip(String),
    #[error(transparent)]
    Write(#[from] OutputError),
}

/// Combine the `study.json` of shard output folders into one [`StudyResults`],
/// identical to what a single run over all clips writes. Every shard must be
/// there: each records its K/N, the clips it owns, the footage root and the whole
/// study's clips, and merge refuses a set that lacks a K, repeats one, mixes N,
/// mixes footage or clip lists, or has a clip without a result.
///
/// # Errors
/// A shard folder without `study.json`, an unreadable one, one not written by
/// `--shard`, a missing or repeated shard, a clip a shard owns but has no result
/// for, or a clip that two shards both analysed.
pub fn merge(shard_dirs: &[PathBuf]) -> Result<StudyResults, StudyError> {
    let mut shards = ShardSet::default();
    for dir in shard_dirs {
        let path = dir.join(STUDY_FILE);
        let bad = |reason: String| StudyError::Merge {
            path: path.clone(),
            reason,
        };
        let shard = read_shard(&path, &shards.merged.crate_version).map_err(bad)?;
        shards.add(shard).map_err(bad)?;
    }
    shards.complete(shard_dirs)
}

/// A shard's `study.json` at `path`, written by this `version` of eulerdisk; the
/// reason when it cannot be read or was written by another version.
fn read_shard(path: &Path, version: &str) -> Result<StudyResults, String> {
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    let shard: StudyResults = serde_json::from_slice(&bytes).map_err(|e| e.to_string())?;
    if shard.crate_version != version {
        return Err(format!(
            "written by eulerdisk {}, this is {version}",
            shard.crate_version
        ));
    }
    Ok(shard)
}

/// The shards merged so far, and what each further shard must agree with.
struct ShardSet {
    merged: StudyResults,
    /// The shards' K so far.
    ks: BTreeSet<usize>,
    /// The first shard's N.
    total: Option<usize>,
    /// The footage and the clip list of the first shard, which every other must share.
    first_study: Option<(PathBuf, Vec<String>)>,
}

impl Default for ShardSet {
    fn default() -> Self {
        ShardSet {
            merged: StudyResults {
                crate_version: env!("CARGO_PKG_VERSION").into(),
                ..StudyResults::default()
            },
            ks: BTreeSet::new(),
            total: None,
            first_study: None,
        }
    }
}

impl ShardSet {
    /// Adds a shard's experiments and failures; the reason when it is not a shard,
    /// does not belong with the others, lacks a result for a clip it owns, or holds
    /// a clip that an earlier shard holds.
    fn add(&mut self, shard: StudyResults) -> Result<(), String> {
        let Some(record) = &shard.shard else {
            return Err("not a shard: written by a `study` run without --shard".into());
        };
        self.check_belongs(record)?;
        let has = |clip: &str| {
            shard.experiments.iter().any(|e| e.clip == clip)
                || shard.failures.iter().any(|f| f.clip == clip)
        };
        if let Some(missing) = record.clips.iter().find(|c| !has(c)) {
            return Err(format!(
                "shard {}/{} owns clip '{missing}' but has no result for it \
                 (interrupted? run the shard again with --resume)",
                record.k, record.n
            ));
        }
        let seen = |clip: &str| {
            self.merged.experiments.iter().any(|e| e.clip == clip)
                || self.merged.failures.iter().any(|f| f.clip == clip)
        };
        for clip in shard
            .experiments
            .iter()
            .map(|e| &e.clip)
            .chain(shard.failures.iter().map(|f| &f.clip))
        {
            if seen(clip) {
                return Err(format!("clip '{clip}' appears in more than one shard"));
            }
        }
        self.merged.experiments.extend(shard.experiments);
        self.merged.failures.extend(shard.failures);
        Ok(())
    }

    /// Whether the shard `record` belongs with those so far: the same study's clips,
    /// the same footage, the same N, and a K not given before (which it records).
    fn check_belongs(&mut self, record: &ShardRecord) -> Result<(), String> {
        let study = self
            .first_study
            .get_or_insert_with(|| (record.footage.clone(), record.study_clips.clone()));
        if study.1 != record.study_clips {
            return Err(format!(
                "shard {}/{} was made from a study of {} clips, the other shards from one of \
                 {} (clips added or removed between the runs?); run every shard on the same \
                 footage",
                record.k,
                record.n,
                record.study_clips.len(),
                study.1.len()
            ));
        }
        if study.0 != record.footage {
            return Err(format!(
                "shard {}/{} was made from the footage in {}, the other shards from {}; \
                 give the shards of one study",
                record.k,
                record.n,
                record.footage.display(),
                study.0.display()
            ));
        }
        if *self.total.get_or_insert(record.n) != record.n {
            return Err(format!(
                "shard {}/{} does not belong with shards of {}",
                record.k,
                record.n,
                self.total.unwrap_or(0)
            ));
        }
        if !self.ks.insert(record.k) {
            return Err(format!(
                "shard {}/{} given more than once (more than one shard folder holds it)",
                record.k, record.n
            ));
        }
        Ok(())
    }

    /// The merged results, sorted as a single run sorts them, once every K of N is
    /// there; the error names the missing shards against the first folder.
    fn complete(self, shard_dirs: &[PathBuf]) -> Result<StudyResults, StudyError> {
        let n = self.total.unwrap_or(0);
        let missing: Vec<String> = (1..=n)
            .filter(|k| !self.ks.contains(k))
            .map(|k| format!("{k}/{n}"))
            .collect();
        if !missing.is_empty() {
            return Err(StudyError::Merge {
                path: shard_dirs.first().cloned().unwrap_or_default(),
                reason: format!(
                    "incomplete: shard {} missing ({} of {n} given); give every shard's folder",
                    missing.join(", "),
                    self.ks.len()
                ),
            });
        }
        let mut merged = self.merged;
        merged.sort();
        Ok(merged)
    }
}

/// Copies each analysed clip's folder from the shard folder that holds it into
/// `out/experiments/`, as a single run writes it, so the merged report's links lead
/// to the clips' pages (hard links where the file system allows: no bytes are
/// copied); and each failed clip's folder where a shard holds one.
///
/// # Errors
/// An analysed clip whose folder no shard holds (its page would be missing), or a
/// folder that cannot be copied.
pub fn gather_experiments(
    shard_dirs: &[PathBuf],
    results: &StudyResults,
    out: &output::OutputLock,
) -> Result<(), StudyError> {
    for e in &results.experiments {
        let from = shard_dirs
            .iter()
            .map(|dir| dir.join("experiments").join(&e.clip))
            .find(|dir| dir.join(SUMMARY_FILE).is_file())
            .ok_or_else(|| StudyError::Merge {
                path: shard_dirs.first().cloned().unwrap_or_default(),
                reason: format!(
                    "no shard folder holds experiments/{}/ (the clip's page); give the \
                     shards' output folders as the shard runs wrote them",
                    e.clip
                ),
            })?;
        let to = out.folder().join("experiments").join(&e.clip);
        output::write_folder(&to, |staging| output::copy_tree(&from, staging))?;
    }
    // A failed clip's folder, where a shard wrote one (its failure page, or an
    // earlier result it kept), so that the merged report links it as the shard's did.
    for f in &results.failures {
        let from = shard_dirs
            .iter()
            .map(|dir| dir.join("experiments").join(&f.clip))
            .find(|dir| dir.join("index.html").is_file());
        if let Some(from) = from {
            let to = out.folder().join("experiments").join(&f.clip);
            output::write_folder(&to, |staging| output::copy_tree(&from, staging))?;
        }
    }
    Ok(())
}

/// A study's per-clip work: configs inherited from the study root, one
/// [`analyse::analyse_clip`] and [`write_experiment`](crate::report::experiment::write_experiment)
/// per clip.
pub struct StudyAnalyser {
    root: PathBuf,
    /// The overlays each clip gets (`None`: none).
    overlay: Option<crate::overlay::OverlaySpec>,
    /// What each refused clip's analysis had found, for its failure page.
    refused: std::sync::Mutex<std::collections::HashMap<PathBuf, Box<analyse::Failure>>>,
}

impl StudyAnalyser {
    /// The analyser of the clips below `root`, with the overlays of `overlay`.
    pub fn new(root: PathBuf, overlay: Option<crate::overlay::OverlaySpec>) -> Self {
        StudyAnalyser {
            root,
            overlay,
            refused: Default::default(),
        }
    }
}

impl ClipAnalyser for StudyAnalyser {
    fn resume_key(&self, clip: &ClipEntry) -> Result<String, String> {
        let config =
            analyse::config_for(&self.root, &clip.path, None).map_err(|e| e.to_string())?;
        analyse::resume_key(&clip.path, &config).map_err(|e| e.to_string())
    }

    fn analyse(
        &self,
        clip: &ClipEntry,
        dir: &Path,
        key: &str,
    ) -> Result<ExperimentSummary, String> {
        let config =
            analyse::config_for(&self.root, &clip.path, None).map_err(|e| e.to_string())?;
        let analysed = analyse::analyse_clip_explaining(
            &clip.path,
            &config,
            analyse::Decoding::NearTheEnd,
            self.overlay.as_ref(),
            &|_, _| {},
        );
        let (experiment, kept) = match analysed {
            Ok(analysed) => analysed,
            Err(failure) => {
                let reason = failure.error.to_string();
                if failure.deserves_a_page()
                    && let Ok(mut refused) = self.refused.lock()
                {
                    refused.insert(clip.path.clone(), failure);
                }
                return Err(reason);
            }
        };
        crate::report::experiment::write_experiment(
            dir,
            &experiment,
            self.overlay.as_ref(),
            kept.as_ref(),
        )
        .map_err(|e| e.to_string())?;
        let mut meta = clip.meta.clone();
        meta.material = meta.material.or(config.material.clone());
        meta.disk = meta.disk.or(config.disk_name.clone());
        meta.orientation = meta.orientation.or(config.orientation.clone());
        Ok(summary(&experiment, &clip.relative, meta, key))
    }

    fn explain(&self, clip: &ClipEntry, dir: &Path) -> Result<bool, String> {
        let failure = self
            .refused
            .lock()
            .ok()
            .and_then(|mut refused| refused.remove(&clip.path));
        match failure {
            Some(failure) => crate::report::failure::write_failure(dir, &clip.path, &failure)
                .map(|()| true)
                .map_err(|e| e.to_string()),
            None => Ok(false),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

    fn quiet(_: StudyEvent) {}

    fn lock(dir: &Path) -> output::OutputLock {
        output::OutputLock::acquire(dir).unwrap()
    }

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
        let clips = discover(root.path(), Path::new("/o")).unwrap();
        let names: Vec<&str> = clips.clips.iter().map(|c| c.relative.as_str()).collect();
        assert_eq!(
            names,
            [
                "euler/glass/run1",
                "euler/steel/run2.mp4",
                "euler/steel/run10.mp4"
            ]
        );
        assert_eq!(clips.clips[0].meta.run.as_deref(), Some("run1"));
        let out = Path::new("/o");
        assert_eq!(
            clips.clips[1].experiment_dir(out),
            Path::new("/o/experiments/euler/steel/run2.mp4")
        );
        assert_eq!(
            clips.clips[0].experiment_dir(out),
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
        let clips = discover(root.path(), Path::new("/o")).unwrap();
        assert_eq!(clips.clips[0].meta.material.as_deref(), Some("glass"));
        assert_eq!(clips.clips[0].meta.run.as_deref(), Some("3"));
        std::fs::write(
            root.path().join("study.csv"),
            "path,material\nb.mp4,glass\n",
        )
        .unwrap();
        let err = discover(root.path(), Path::new("/o"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("study.csv") && err.contains("b.mp4"), "{err}");
    }

    #[test]
    fn an_empty_root_is_an_error() {
        let root = tempfile::tempdir().unwrap();
        assert!(
            discover(root.path(), Path::new("/o"))
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
    /// named `bad*` (or on every clip once `fail_all` is set); it counts its
    /// analyses. It writes `frames.csv` then `result.json`, and dies (panics, as a
    /// killed process stops) at the `kill_at`-th file write of the run.
    struct Fake {
        calls: Mutex<Vec<String>>,
        fail_all: AtomicBool,
        kill_at: AtomicUsize,
    }

    impl Fake {
        fn new() -> Self {
            Fake {
                calls: Mutex::new(vec![]),
                fail_all: AtomicBool::new(false),
                kill_at: AtomicUsize::new(usize::MAX),
            }
        }

        fn write(&self, path: &Path, text: &str) {
            if self.kill_at.fetch_sub(1, Ordering::SeqCst) == 1 {
                panic!("killed while writing {}", path.display());
            }
            std::fs::write(path, text).unwrap();
        }
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
            if clip.relative.contains("bad") || self.fail_all.load(Ordering::SeqCst) {
                return Err(format!("{}: no disk in view", clip.path.display()));
            }
            let n = std::fs::metadata(&clip.path).unwrap().len() as f64;
            self.write(&dir.join("frames.csv"), "t_s,z_rim_m\n");
            self.write(&dir.join("result.json"), &format!("{{\"n\": {n}}}"));
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
                phi_vs_precession: None,
                n_turn_timing: None,
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
        let clips = discover(root.path(), Path::new("/o")).unwrap();
        let out_dir = tempfile::tempdir().unwrap();
        let out = output::OutputLock::acquire(out_dir.path()).unwrap();
        let fake = Fake::new();
        let full = run(clips.clone(), &out, RunOptions::default(), &fake, &quiet)
            .unwrap()
            .results;
        assert_eq!(full.experiments.len(), 4);
        assert_eq!(full.failures.len(), 1);
        assert!(full.failures[0].reason.contains("bad.mp4"));

        // Change one clip; resume redoes it and the failed one only.
        std::fs::write(root.path().join("m2/c.mp4"), b"changed bytes").unwrap();
        fake.calls.lock().unwrap().clear();
        let resumed = RunOptions {
            resume: true,
            ..RunOptions::default()
        };
        let again = run(clips.clone(), &out, resumed, &fake, &quiet)
            .unwrap()
            .results;
        let mut redone = fake.calls.lock().unwrap().clone();
        redone.sort();
        assert_eq!(redone, ["m1/bad.mp4", "m2/c.mp4"]);
        assert_eq!(again.experiments.len(), 4);

        // Shards in their own folders, merged, equal one run.
        let shard_dirs: Vec<PathBuf> = (1..=2)
            .map(|k| out_dir.path().join(format!("shard-{k}")))
            .collect();
        for (k, dir) in shard_dirs.iter().enumerate() {
            let options = RunOptions {
                shard: Some(Shard { k: k + 1, n: 2 }),
                ..RunOptions::default()
            };
            let lock = output::OutputLock::acquire(dir).unwrap();
            run(clips.clone(), &lock, options, &fake, &quiet).unwrap();
        }
        assert_eq!(merge(&shard_dirs).unwrap(), again);
        // Merging a shard twice is refused.
        let twice = [shard_dirs[0].clone(), shard_dirs[0].clone()];
        assert!(
            merge(&twice)
                .unwrap_err()
                .to_string()
                .contains("more than once")
        );
    }

    /// Runs a study of `clips` into `out` with `options`.
    fn study(clips: &Discovered, out: &Path, options: RunOptions, fake: &Fake) -> StudyRun {
        run(clips.clone(), &lock(out), options, fake, &quiet).unwrap()
    }

    fn experiments_of(run: &StudyRun) -> Vec<&str> {
        run.results
            .experiments
            .iter()
            .map(|e| e.clip.as_str())
            .collect()
    }

    /// Issue 13.1: `oak/run1.mp4` and `oak/run1.mov` both wrote
    /// `experiments/oak/run1`, so one result was lost and `--resume` redid one
    /// every time. Each now has its own folder, and a resume reuses both.
    #[test]
    fn two_clips_with_one_name_get_two_folders() {
        let root = tempfile::tempdir().unwrap();
        touch(root.path(), "oak/run1.mp4");
        touch(root.path(), "oak/run1.mov");
        let clips = discover(root.path(), Path::new("/o")).unwrap();
        let out = tempfile::tempdir().unwrap();
        assert_ne!(
            clips.clips[0].experiment_dir(out.path()),
            clips.clips[1].experiment_dir(out.path())
        );
        let fake = Fake::new();
        study(&clips, out.path(), RunOptions::default(), &fake);
        for clip in ["oak/run1.mp4", "oak/run1.mov"] {
            let summary = out.path().join("experiments").join(clip).join(SUMMARY_FILE);
            let summary: ExperimentSummary =
                serde_json::from_slice(&std::fs::read(summary).unwrap()).unwrap();
            assert_eq!(summary.clip, clip, "each folder holds its own clip");
        }
        fake.calls.lock().unwrap().clear();
        let resumed = RunOptions {
            resume: true,
            ..RunOptions::default()
        };
        let again = study(&clips, out.path(), resumed, &fake);
        assert!(fake.calls.lock().unwrap().is_empty(), "both reused");
        assert_eq!(again.results.experiments.len(), 2);
    }

    /// Issue 13.2: a symlink loop counted one clip 41 times; issue 73.12: refusing
    /// the whole study for it lost every other clip. A loop is skipped with a
    /// warning naming the link, and the rest is analysed; a second path to one clip
    /// is refused.
    #[test]
    fn a_symlink_loop_is_skipped_and_a_clip_reached_twice_is_refused() {
        let root = tempfile::tempdir().unwrap();
        touch(root.path(), "oak/run1.mp4");
        touch(root.path(), "pine/run2.mp4");
        std::os::unix::fs::symlink("..", root.path().join("oak/loop")).unwrap();
        let found = discover(root.path(), Path::new("/o")).unwrap();
        let names: Vec<&str> = found.clips.iter().map(|c| c.relative.as_str()).collect();
        assert_eq!(names, ["oak/run1.mp4", "pine/run2.mp4"]);
        assert_eq!(found.skipped.len(), 1, "{:?}", found.skipped);
        assert!(
            found.skipped[0].contains("loop") && found.skipped[0].contains("oak/loop"),
            "{:?}",
            found.skipped
        );
        std::fs::remove_file(root.path().join("oak/loop")).unwrap();
        std::os::unix::fs::symlink(root.path().join("oak"), root.path().join("oak/again")).unwrap();
        assert_eq!(
            discover(root.path(), Path::new("/o")).unwrap().clips.len(),
            2
        );
        std::fs::remove_file(root.path().join("oak/again")).unwrap();
        std::os::unix::fs::symlink(
            root.path().join("oak/run1.mp4"),
            root.path().join("oak/run2.mp4"),
        )
        .unwrap();
        let err = discover(root.path(), Path::new("/o"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("counted twice") && err.contains("run2.mp4"),
            "{err}"
        );
        // A link to footage kept elsewhere is followed (once).
        std::fs::remove_file(root.path().join("oak/run2.mp4")).unwrap();
        let elsewhere = tempfile::tempdir().unwrap();
        touch(elsewhere.path(), "run9.mp4");
        std::os::unix::fs::symlink(elsewhere.path(), root.path().join("glass")).unwrap();
        let clips = discover(root.path(), Path::new("/o")).unwrap();
        let names: Vec<&str> = clips.clips.iter().map(|c| c.relative.as_str()).collect();
        assert_eq!(names, ["glass/run9.mp4", "oak/run1.mp4", "pine/run2.mp4"]);
    }

    /// Issue 13.2: `study .` twice took its own output (plots are PNG frames) for
    /// clips. The output folder, and any folder of eulerdisk results, is skipped.
    #[test]
    fn the_output_folder_is_never_footage() {
        let root = tempfile::tempdir().unwrap();
        touch(root.path(), "oak/run1.mp4");
        let out = root.path().join("out/study");
        let first = discover(root.path(), &out).unwrap();
        // Outputs as a real run leaves them: a plot in an experiment folder, and
        // an `analyse` folder elsewhere below the root.
        touch(&out, "experiments/oak/run1.mp4/series.png");
        touch(&out, "experiments/oak/run1.mp4/summary.json");
        touch(root.path(), "out/run1.mp4/calibration.png");
        touch(root.path(), "out/run1.mp4/result.json");
        let again = discover(root.path(), &out).unwrap();
        assert_eq!(again, first);
    }

    /// Issue 13.2: `merge` of 1 of 2 shards said "merged 1 shards" and exited 0.
    /// A missing shard, a shard with a clip unaccounted for (an interrupted run),
    /// and a study that was not sharded are refused.
    #[test]
    fn merge_refuses_a_missing_shard() {
        let root = tempfile::tempdir().unwrap();
        for rel in ["a.mp4", "b.mp4", "c.mp4"] {
            touch(root.path(), rel);
        }
        let clips = discover(root.path(), Path::new("/o")).unwrap();
        let out = tempfile::tempdir().unwrap();
        let fake = Fake::new();
        let dirs: Vec<PathBuf> = (1..=2).map(|k| out.path().join(format!("s{k}"))).collect();
        for (k, dir) in dirs.iter().enumerate() {
            let options = RunOptions {
                shard: Some(Shard { k: k + 1, n: 2 }),
                ..RunOptions::default()
            };
            study(&clips, dir, options, &fake);
        }
        let err = merge(&dirs[..1]).unwrap_err().to_string();
        assert!(err.contains("shard 2/2 missing"), "{err}");
        assert_eq!(merge(&dirs).unwrap().experiments.len(), 3);

        // Shard 1 lost a clip's result (as a run killed before study.json was
        // complete would).
        let path = dirs[0].join(STUDY_FILE);
        let mut shard: StudyResults =
            serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        shard.experiments.pop();
        output::write_json(&path, &shard).unwrap();
        let err = merge(&dirs).unwrap_err().to_string();
        assert!(err.contains("has no result for it"), "{err}");

        let whole = out.path().join("whole");
        study(&clips, &whole, RunOptions::default(), &fake);
        let err = merge(&[whole]).unwrap_err().to_string();
        assert!(err.contains("not a shard"), "{err}");
    }

    /// Issue 73.2: `merge` took shard 1/2 of one footage folder and shard 2/2 of
    /// another, and left out the clips of both missing halves. Each shard records
    /// its footage and the whole study's clips; shards that differ are refused.
    #[test]
    fn merge_refuses_shards_of_another_footage() {
        let fake = Fake::new();
        let out = tempfile::tempdir().unwrap();
        let shard = |root: &Path, k: usize, name: &str| {
            let dir = out.path().join(name);
            let options = RunOptions {
                shard: Some(Shard { k, n: 2 }),
                ..RunOptions::default()
            };
            study(
                &discover(root, Path::new("/o")).unwrap(),
                &dir,
                options,
                &fake,
            );
            dir
        };
        let [a, b, same_names] = [(); 3].map(|()| tempfile::tempdir().unwrap());
        for rel in ["a.mp4", "b.mp4", "c.mp4"] {
            touch(a.path(), rel);
            touch(same_names.path(), rel);
        }
        for rel in ["x.mp4", "y.mp4"] {
            touch(b.path(), rel);
        }
        let first = shard(a.path(), 1, "a1");
        for (other, name, words) in [
            (&b, "b2", "a study of 2 clips"),
            (&same_names, "same2", "made from the footage in"),
        ] {
            let second = shard(other.path(), 2, name);
            let err = merge(&[first.clone(), second]).unwrap_err().to_string();
            assert!(err.contains(words), "{err}");
        }
        let second = shard(a.path(), 2, "a2");
        assert_eq!(merge(&[first, second]).unwrap().experiments.len(), 3);
    }

    /// Issue 73.8: kill -9 left `.NAME.staging-*` folders and `.NAME.lock` files
    /// that a resume kept, and every run left a `.NAME.lock` beside each output. A
    /// run leaves no lock, staging or replaced folder in the output tree or beside
    /// it, and removes those a killed run left.
    #[test]
    fn a_run_leaves_no_lock_or_staging_and_removes_a_killed_runs() {
        let root = tempfile::tempdir().unwrap();
        for rel in ["m1/a.mp4", "m1/b.mp4"] {
            touch(root.path(), rel);
        }
        let clips = discover(root.path(), Path::new("/o")).unwrap();
        let top = tempfile::tempdir().unwrap();
        let out = top.path().join("out");
        let fake = Fake::new();
        study(&clips, &out, RunOptions::default(), &fake);
        // What kill -9 leaves while a.mp4 is written again.
        let m1 = out.join("experiments/m1");
        touch(&m1, ".a.mp4.staging-x1y2/frames.csv");
        touch(&m1, ".a.mp4.replaced-4242/result.json");
        touch(&m1, ".a.mp4.lock");
        touch(&m1, ".c.mp4.staging-zz/result.json");
        let resumed = RunOptions {
            resume: true,
            ..RunOptions::default()
        };
        study(&clips, &out, resumed, &fake);
        let mut left = Vec::new();
        let mut folders = vec![top.path().to_path_buf()];
        while let Some(dir) = folders.pop() {
            for entry in std::fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                let name = path.file_name().unwrap().to_string_lossy().into_owned();
                if name.contains(".lock")
                    || name.contains(".staging-")
                    || name.contains(".replaced-")
                {
                    left.push(path.clone());
                }
                if path.is_dir() {
                    folders.push(path);
                }
            }
        }
        assert!(left.is_empty(), "left behind: {left:?}");
        assert!(m1.join("a.mp4/summary.json").is_file());
    }

    /// Issue 13.2: a typo in the root `eulerdisk.toml` made every clip fail and the
    /// re-run replaced the previous complete report. The previous report is kept,
    /// the lost clips are named, and `force` replaces it.
    #[test]
    fn a_failed_rerun_keeps_the_better_report() {
        let root = tempfile::tempdir().unwrap();
        for rel in ["a.mp4", "b.mp4"] {
            touch(root.path(), rel);
        }
        let clips = discover(root.path(), Path::new("/o")).unwrap();
        let out = tempfile::tempdir().unwrap();
        let fake = Fake::new();
        let good = study(&clips, out.path(), RunOptions::default(), &fake);
        assert!(good.is_complete());
        let before = std::fs::read(out.path().join(STUDY_FILE)).unwrap();

        fake.fail_all.store(true, Ordering::SeqCst);
        let failed = study(&clips, out.path(), RunOptions::default(), &fake);
        assert!(!failed.is_complete());
        assert_eq!(
            failed.kept_previous,
            Some(KeptReport {
                analysed: 2,
                lost: vec!["a.mp4".into(), "b.mp4".into()]
            })
        );
        assert_eq!(std::fs::read(out.path().join(STUDY_FILE)).unwrap(), before);
        // The failed analyses did not touch the clips' folders either.
        assert!(out.path().join("experiments/a.mp4/result.json").is_file());

        let forced = RunOptions {
            force: true,
            ..RunOptions::default()
        };
        let replaced = study(&clips, out.path(), forced, &fake);
        assert_eq!(replaced.kept_previous, None);
        let now: StudyResults =
            serde_json::from_slice(&std::fs::read(out.path().join(STUDY_FILE)).unwrap()).unwrap();
        assert_eq!(now.failures.len(), 2);
    }

    /// Issue 13, fault injection: a 40-clip study with 8 broken clips, killed at
    /// three random points (mid-write of a clip's files), then resumed, gives the
    /// report an uninterrupted run gives, lists the 8 failures, is not complete,
    /// and leaves no half-written folder behind.
    #[test]
    fn a_study_killed_three_times_and_resumed_equals_an_uninterrupted_run() {
        let root = tempfile::tempdir().unwrap();
        for i in 0..40 {
            let name = if i % 5 == 3 { "bad" } else { "run" };
            // Different bytes per clip, so every clip has its own n.
            let path = root.path().join(format!("m{}/{name}{i}.mp4", i % 4));
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, vec![b'x'; 100 + i]).unwrap();
        }
        let clips = discover(root.path(), Path::new("/o")).unwrap();
        let reference_out = tempfile::tempdir().unwrap();
        let reference = study(
            &clips,
            reference_out.path(),
            RunOptions::default(),
            &Fake::new(),
        );
        assert_eq!(reference.results.failures.len(), 8);

        let out = tempfile::tempdir().unwrap();
        let resumed = RunOptions {
            resume: true,
            ..RunOptions::default()
        };
        let fake = Fake::new();
        let mut rng = crate::rng::SplitMix64::new(13);
        for _ in 0..3 {
            // Each good clip not yet done writes 2 files: kill somewhere among them.
            let to_do = clips
                .clips
                .iter()
                .filter(|c| !c.relative.contains("bad"))
                .filter(|c| !c.experiment_dir(out.path()).join(SUMMARY_FILE).is_file())
                .count();
            let kill_at = 1 + (rng.next_u64() % (2 * to_do as u64)) as usize;
            fake.kill_at.store(kill_at, Ordering::SeqCst);
            let killed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                study(&clips, out.path(), resumed, &fake)
            }));
            assert!(killed.is_err(), "the run was killed at write {kill_at}");
        }
        fake.kill_at.store(usize::MAX, Ordering::SeqCst);
        let last = study(&clips, out.path(), resumed, &fake);
        assert_eq!(last.results, reference.results);
        assert!(!last.is_complete());
        let failed: Vec<&str> = last
            .results
            .failures
            .iter()
            .map(|f| f.clip.as_str())
            .collect();
        assert_eq!(failed.len(), 8);
        assert!(failed.iter().all(|c| c.contains("/bad")), "{failed:?}");
        let on_disk: StudyResults =
            serde_json::from_slice(&std::fs::read(out.path().join(STUDY_FILE)).unwrap()).unwrap();
        assert_eq!(on_disk, reference.results);
        for e in &last.results.experiments {
            let dir = out.path().join("experiments").join(&e.clip);
            let result = std::fs::read_to_string(dir.join("result.json")).unwrap();
            assert_eq!(result, format!("{{\"n\": {}}}", e.n), "{}", e.clip);
            let siblings = std::fs::read_dir(dir.parent().unwrap()).unwrap();
            for s in siblings {
                let name = s.unwrap().file_name().to_string_lossy().into_owned();
                assert!(
                    !name.contains("staging") && !name.contains("replaced"),
                    "{name}"
                );
            }
        }
        assert_eq!(experiments_of(&last).len(), 32);
    }
}
