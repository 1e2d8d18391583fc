//! What a study keeps of each analysed clip ([`ExperimentSummary`], made by
//! [`summary`] from an [`Experiment`]), of each failed one ([`ClipFailure`]), and of
//! a whole study or one shard of it ([`StudyResults`]): what the study page and its
//! statistics read, and what `merge` combines.

use serde::{Deserialize, Serialize};

use crate::analyse::Experiment;
use crate::footage::natural_cmp;

/// What a study knows about a clip besides its pixels.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClipMeta {
    pub disk: Option<String>,
    pub material: Option<String>,
    pub orientation: Option<String>,
    pub run: Option<String>,
}

impl ClipMeta {
    /// `DISK/MATERIAL/ORIENTATION/RUN`: the third folder is the orientation.
    pub(crate) fn with_orientation(self, folders: &[&str]) -> Self {
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
    /// Fitted halt time t0 \[s\] relative to the measured halt.
    pub t0_s: f64,
    pub r_squared: f64,
    pub points: usize,
    /// Frames per second used, and where that number came from.
    pub fps: f64,
    pub fps_source: String,
    /// The precession check: φ from the heights over φ from the precession rate at
    /// the window's mean, − 1 ([`crate::precession::PrecessionCheck::agreement`]);
    /// `None` when not made, and in summaries written before it was recorded.
    #[serde(default)]
    pub phi_vs_precession: Option<f64>,
    /// n from the turns' timing alone and its 95 % interval
    /// ([`crate::turn_timing::fit_turn_timing`]); `None` when not fitted, and in
    /// summaries written before it was recorded.
    #[serde(default)]
    pub n_turn_timing: Option<(f64, [f64; 2])>,
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
    /// Set by a `--shard K/N` run: which share, and every clip it owns, so
    /// [`merge`](crate::study::merge) can tell a complete set of shards from an incomplete one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<ShardRecord>,
}

/// What a shard's `study.json` records about the share it ran, and about the
/// whole study it is a share of.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShardRecord {
    pub k: usize,
    pub n: usize,
    /// The clips of this share (relative paths), each of which must appear among
    /// its experiments or failures.
    pub clips: Vec<String>,
    /// The footage root's real path: shards of one study share it.
    pub footage: std::path::PathBuf,
    /// Every clip of the whole study (relative paths, sorted): shards of one study
    /// share the list, and together own every clip of it.
    pub study_clips: Vec<String>,
}

impl StudyResults {
    pub(crate) fn sort(&mut self) {
        self.experiments
            .sort_by(|a, b| natural_cmp(&a.clip, &b.clip));
        self.failures.sort_by(|a, b| natural_cmp(&a.clip, &b.clip));
    }
}

/// What a study keeps of an experiment.
pub fn summary(
    experiment: &Experiment,
    clip: &str,
    meta: ClipMeta,
    key: &str,
) -> ExperimentSummary {
    let fit = &experiment.peaks_fit.fit;
    ExperimentSummary {
        clip: clip.into(),
        meta,
        resume_key: key.into(),
        n: fit.n,
        n_ci95: [fit.ci95_n.0, fit.ci95_n.1],
        t0_s: fit.t0,
        r_squared: fit.r_squared,
        points: fit.points,
        fps: experiment.plan.fps.fps,
        fps_source: format!("{:?}", experiment.plan.fps.source),
        phi_vs_precession: experiment.precession.map(|c| c.agreement() - 1.0),
        n_turn_timing: match &experiment.turn_timing {
            Some(Ok(t)) => Some((t.n, [t.ci95_n.0, t.ci95_n.1])),
            _ => None,
        },
        warnings: experiment.warnings.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 73.7: a resumed or merged clip's r² differed by one ulp from the
    /// uninterrupted run's, because `summary.json` was read back by a parser that
    /// does not round every decimal correctly. Every number of a summary reads back
    /// as the value written, bit for bit.
    #[test]
    fn a_summary_reads_back_bit_for_bit() {
        let mut rng = crate::rng::SplitMix64::new(73);
        for _ in 0..20_000 {
            let n = rng.range(0.1, 2.0);
            let summary = ExperimentSummary {
                clip: "oak/run1.mp4".into(),
                meta: ClipMeta::default(),
                resume_key: String::new(),
                n,
                n_ci95: [n - rng.uniform() * 1e-2, n + rng.uniform() * 1e-2],
                t0_s: rng.range(-1e-3, 1e-3),
                r_squared: 1.0 - rng.uniform() * 1e-3,
                points: 20,
                fps: 480.0,
                fps_source: "Config".into(),
                phi_vs_precession: Some(rng.range(-0.1, 0.1)),
                n_turn_timing: Some((n, [n - 1e-3, n + 1e-3])),
                warnings: vec![],
            };
            let text = serde_json::to_string_pretty(&summary).unwrap();
            let back: ExperimentSummary = serde_json::from_str(&text).unwrap();
            assert_eq!(back, summary, "{text}");
        }
    }
}
