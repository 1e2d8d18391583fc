//! One clip from pixels to the energy exponent: the stages of DESIGN.md chained.
//!
//! ```text
//! open       [`open`]:      frame source, capture fps, frame count, the container's index
//!   ▼
//! calibrate  [`calibrate`]: pass 1, the rest frames at the end → layout, plate, x_l, x_r,
//!   │                       z_t, z_base, γ (thesis §3.2.4); two-view: split row, colours
//!   ▼                       (§3.3.2); the gauges pass 2 reads every frame with
//! measure    [`measure`]:   pass 2, streamed: z_rim [px] per frame (edge, gap darkness,
//!   │                       then the rim's edge model, [`rim_heights`]); β; repeated
//!   │                       frames; the near top rim; the scale (eq. 3.10, [`scale`]);
//!   ▼                       frame times on the capture clock
//! signal     [`series`]:    halt t_φ, peaks, φ (eq. 3.9), ψ, ψ̇ (eq. 3.11), per-frame
//!   │                       states, β unwrapped, t_β, flags; the zero of z_rim from the
//!   │                       motion. A long clip's span is grown back until it holds
//!   ▼                       the fits' motion ([`span`])
//! fit        [`fits`]:      E at the peaks and per frame (eq. 3.8), eq. 3.6 for two-view
//!   │                       clips; E = A_e (t0 − t)^n over the window and 1 … 0.1 s;
//!   │                       the turns' timing law. [`halt`] repeats signal and fit while
//!   ▼                       the laws move the halt (at most twice, each once)
//! assemble   [`checks`], [`assemble`]: the zero's share of n's interval, the checks'
//!                           warnings, the plan (provenance) and the [`Experiment`]
//! ```
//!
//! [`analyse_clip`] reads the clip twice (the calibration must be known before the
//! rim can be measured) and keeps only scalars per frame, so memory does not grow
//! with frame size or, beyond a few numbers per frame, with clip length. A video
//! longer than [`WHOLE_CLIP_UP_TO_S`] is measured in pass 2 from a key frame near
//! its end ([`Decoding::NearTheEnd`], the span grown back until it holds the fits'
//! motion), so a minutes-long clip costs about what its last seconds cost.

use std::path::{Path, PathBuf};

use crate::config::ExperimentConfig;
use crate::energy::FitError;
use crate::footage::{self, FootageError};
use crate::signal::SignalError;
use crate::vision::VisionError;

mod assemble;
mod calibrate;
mod checks;
pub mod diagnostics;
mod fits;
mod halt;
mod keep;
mod measure;
mod open;
mod result;
mod rim_heights;
mod scale;
mod series;
mod span;
mod views;

pub use keep::{FrameKeeping, KeepFrames, KeepNothing, LayoutGeometry, StripMark};
pub use result::{
    Diagnostics, EnergyFit, EnergySample, Experiment, ExperimentPlan, FrameRecord, HaltPlacement,
    TopRimLeaning, ZeroFromMotion,
};
pub use scale::ScaleReport;
pub use span::{DecodedSpan, Decoding, FIRST_SPAN_S, WHOLE_CLIP_UP_TO_S};

/// Frames at the end of a clip that must show the disk at rest (calibration).
pub const REST_FRAMES: usize = 5;

/// The windows of the window-sensitivity table \[s\] (issue: 1, 0.5, 0.25, 0.1 s).
pub const SENSITIVITY_WINDOWS_S: [f64; 4] = [1.0, 0.5, 0.25, 0.1];

/// Why a clip could not be analysed. Every message names the clip; vision errors
/// name the frame.
#[derive(Debug, thiserror::Error)]
pub enum AnalyseError {
    #[error(transparent)]
    Footage(#[from] FootageError),
    #[error("{}: {reason}", path.display())]
    Fps { path: PathBuf, reason: String },
    #[error("{}: {error}", path.display())]
    Vision { path: PathBuf, error: VisionError },
    #[error("{}: {error}", path.display())]
    Signal { path: PathBuf, error: SignalError },
    #[error("{}: energy fit: {error}", path.display())]
    Fit { path: PathBuf, error: FitError },
    #[error("{}: {reason}", path.display())]
    Clip { path: PathBuf, reason: String },
    /// A setting of the config that this clip cannot be measured with (the reason
    /// names the key and the range the clip allows).
    #[error("{}: {reason}", path.display())]
    Setting { path: PathBuf, reason: String },
    /// The fit window or the rest tail crosses a change of the container's frame
    /// interval (a slowed section's start or end).
    #[error(
        "{}: the {span} (t = {start_s:.4}–{end_s:.4} s from the first frame, capture clock) \
         crosses a change of the frame rate: trim the clip, or shorten `window_s` in the \
         config's [fit] table, so that it lies inside one section. Sections: {sections}",
        path.display()
    )]
    AcrossSections {
        path: PathBuf,
        /// "fit window" or "rest tail".
        span: &'static str,
        /// The span's capture times from the clip's first frame \[s\].
        start_s: f64,
        end_s: f64,
        /// The clip's sections, as [`footage::FrameTiming::sections_text`] lists them.
        sections: String,
    },
}

/// Analyse one clip with its (merged) config. `progress(done, total)` is called
/// every few hundred frames of the measuring pass.
///
/// # Errors
/// See [`AnalyseError`]: unreadable or truncated footage, no usable fps, no disk in
/// view, a calibration frame not at rest, too few peaks, a failed energy fit.
pub fn analyse_clip(
    clip: &Path,
    config: &ExperimentConfig,
    progress: &dyn Fn(usize, Option<usize>),
) -> Result<Experiment, AnalyseError> {
    analyse_clip_decoding(clip, config, Decoding::NearTheEnd, progress)
}

/// [`analyse_clip`], decoding the whole clip or a span at its end (`decoding`).
///
/// # Errors
/// As [`analyse_clip`].
pub fn analyse_clip_decoding(
    clip: &Path,
    config: &ExperimentConfig,
    decoding: Decoding,
    progress: &dyn Fn(usize, Option<usize>),
) -> Result<Experiment, AnalyseError> {
    analyse_clip_keeping::<KeepNothing>(clip, config, decoding, None, progress).map(|(e, _)| e)
}

/// [`analyse_clip_decoding`], offering every frame read to the keepers `keeping`
/// makes (the measurement overlay keeps its pictures, so that it need not decode the
/// clip again), and returning what the last span's keeper kept.
///
/// # Errors
/// As [`analyse_clip`].
pub fn analyse_clip_keeping<K: FrameKeeping>(
    clip: &Path,
    config: &ExperimentConfig,
    decoding: Decoding,
    keeping: Option<&K>,
    progress: &dyn Fn(usize, Option<usize>),
) -> Result<(Experiment, Option<K::Kept>), AnalyseError> {
    analyse_clip_explaining(clip, config, decoding, keeping, progress).map_err(|f| f.error)
}

/// What the chain had found when a stage refused the clip: the failure page's
/// evidence (issue 72 §6).
#[derive(Debug, Default)]
pub struct Partial {
    /// The rest frame with the calibration points (PNG), once the clip was calibrated.
    pub calibration_png: Option<Vec<u8>>,
    /// The plate kind the calibration took, and how it was told (what each kind
    /// showed), once calibrated.
    pub plate: Option<String>,
    /// The rim heights as measured, once every frame was read: (capture time \[s\],
    /// z_rim \[px\], NaN where no edge was found) per frame.
    pub heights: Option<(Vec<f64>, Vec<f64>)>,
}

/// A clip the chain refused: why, and what it had found before.
#[derive(Debug)]
pub struct Failure {
    pub error: AnalyseError,
    pub partial: Partial,
}

impl Failure {
    /// Whether a page would explain anything: not for a setting out of its range,
    /// which the message names with the key and the range.
    pub fn deserves_a_page(&self) -> bool {
        !matches!(
            self.error,
            AnalyseError::Setting { .. }
                | AnalyseError::Vision {
                    error: VisionError::InvalidSetting { .. },
                    ..
                }
        )
    }
}

/// [`analyse_clip_keeping`], keeping on a refusal what the stages before it found.
///
/// The thesis's chain: open, calibrate on the rest frames, measure every frame and
/// run the signal stage (on a span grown back as the fits need), fit the energy
/// while the laws settle the halt, then the zero's share of the intervals, the
/// checks and the result.
///
/// # Errors
/// As [`analyse_clip`], with the [`Partial`] evidence.
pub fn analyse_clip_explaining<K: FrameKeeping>(
    clip: &Path,
    config: &ExperimentConfig,
    decoding: Decoding,
    keeping: Option<&K>,
    progress: &dyn Fn(usize, Option<usize>),
) -> Result<(Experiment, Option<K::Kept>), Box<Failure>> {
    let mut partial = Partial::default();
    let refused = |error, partial| Box::new(Failure { error, partial });
    // The rest frame's evidence is drawn only for a refusal: a PNG costs tens of ms.
    let after_calibration = |error, mut partial: Partial, rest: &calibrate::RestCalibration| {
        partial.calibration_png = Some(assemble::calibration_png(rest));
        partial.plate = Some(rest.plate.clone());
        refused(error, partial)
    };
    let params = config.disk_params();
    let mut opened = open::open_clip(clip, config).map_err(|e| refused(e, Partial::default()))?;
    let rest = calibrate::calibrate(clip, &mut opened, config, &params)
        .map_err(|e| refused(e, Partial::default()))?;
    let measured = span::measure_spans(
        clip,
        &mut opened,
        &rest,
        config,
        &params,
        decoding,
        keeping,
        progress,
        &mut partial,
    );
    let (measured, decoded, kept) = match measured {
        Ok(m) => m,
        Err(error) => return Err(after_calibration(error, partial, &rest)),
    };
    let settled = match halt::settle(clip, config, &params, &rest, measured) {
        Ok(s) => s,
        Err(error) => return Err(after_calibration(error, partial, &rest)),
    };
    let fitted = checks::finish_fits(config, &params, settled);
    let experiment = assemble::experiment(clip, config, params, &opened, rest, decoded, fitted)
        .map_err(|error| refused(error, partial))?;
    Ok((experiment, kept))
}

/// The config that applies to `clip`: the folder files from `root` down, the
/// clip's own `CLIP.toml`, then `extra` (a `-c` file) last.
///
/// # Errors
/// A config file that cannot be read or is invalid (named in the message).
pub fn config_for(
    root: &Path,
    clip: &Path,
    extra: Option<&Path>,
) -> Result<ExperimentConfig, crate::config::ConfigError> {
    let mut layers = ExperimentConfig::layers_for(root, clip);
    if let Some(extra) = extra {
        if !extra.is_file() {
            return Err(crate::config::ConfigError::Unreadable {
                path: extra.to_path_buf(),
                reason: if extra.is_dir() {
                    "a folder, not a config file (-c takes a TOML file)".into()
                } else {
                    "no such file".into()
                },
            });
        }
        layers.push(extra.to_path_buf());
    }
    ExperimentConfig::load_layered(&layers)
}

/// The resume key of a clip under a config: BLAKE3 of the clip's hash, the config
/// (as JSON) and the crate version.
///
/// # Errors
/// The clip cannot be read.
pub fn resume_key(clip: &Path, config: &ExperimentConfig) -> Result<String, FootageError> {
    let mut hasher = blake3::Hasher::new();
    hasher.update(clip_hash(clip)?.as_bytes());
    hasher.update(serde_json::to_string(config).unwrap_or_default().as_bytes());
    hasher.update(env!("CARGO_PKG_VERSION").as_bytes());
    Ok(hasher.finalize().to_hex().to_string())
}

/// BLAKE3 of a clip's bytes: the file, or every frame file of a folder in order.
///
/// # Errors
/// The file or a frame cannot be read.
pub fn clip_hash(clip: &Path) -> Result<String, FootageError> {
    let mut hasher = blake3::Hasher::new();
    let files = if clip.is_dir() {
        footage::frame_files(clip)?
    } else {
        vec![clip.to_path_buf()]
    };
    for file in files {
        let unreadable = |e: std::io::Error| FootageError::Unreadable {
            path: file.clone(),
            reason: e.to_string(),
        };
        let mut reader = std::fs::File::open(&file).map_err(unreadable)?;
        std::io::copy(&mut reader, &mut hasher).map_err(unreadable)?;
    }
    Ok(hasher.finalize().to_hex().to_string())
}
