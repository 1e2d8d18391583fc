//! The `eulerdisk` command line: clap definitions and dispatch only; every
//! computation lives in the library.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::builder::TypedValueParser;
use clap::{Args, Parser, Subcommand};

use eulerdisk::compare::CompareOptions;
use eulerdisk::footage::Orientation;
use eulerdisk::model::dissipation::{Dissipation, ModelKind};
use eulerdisk::model::params::{DiskParams, Preset};
use eulerdisk::model::simulate::{
    InitialState, MAX_SAMPLES, RunSummary, SimulationSpec, simulate, simulate_streaming,
};
use eulerdisk::model::tuning::tune_eta;
use eulerdisk::output::OutputLock;
use eulerdisk::overlay::{OverlaySpec, write_model_overlay};
use eulerdisk::render::{
    CaptureJitter, ClipEncoding, DEFAULT_CRF, Effects, HdrTransfer, Motion, Nutation, Plate,
    PostFlatSpin, PowerLaw, RenderSpec, Renderer, SampleStorage, Scenery, Shake, SlowedSection,
    Timing, add_nutation, power_law_motion, trajectory_motion, write_clip,
};
use eulerdisk::report::compare::{comparison_dir, write_comparison};
use eulerdisk::report::experiment::write_experiment;
use eulerdisk::report::failure::write_failure;
use eulerdisk::report::simulation::{TrajectoryWriter, write_simulation};
use eulerdisk::report::study::{StudyReportOptions, write_published_report, write_study_report};
use eulerdisk::stats::VarianceModel;
use eulerdisk::study::{self, Outcome, StudyEvent};
use eulerdisk::{analyse, demo, footage, reproduce};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;

/// Slow-motion footage of spinning disks, turned into physics.
#[derive(Parser)]
#[command(
    version,
    about,
    propagate_version = true,
    after_help = "Exit status: 0 success; 1 error (nothing could run); \
                  2 a study or merge finished but some clips failed, or a previous \
                  report was kept; 64 a command line that cannot be parsed (an \
                  unknown flag, a value out of range)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print what OpenCV reports about a video file or a folder of frames.
    Info {
        /// A video (MP4, MOV, AVI) or a folder of PNG/TIFF/JPEG frames.
        clip: PathBuf,
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Simulate the rolling/slipping disk (thesis Chapter 4) and write a trajectory
    /// CSV, a JSON summary and a plot panel.
    Simulate(SimulateArgs),
    /// Render synthetic footage (MP4 or PNG folder) of a prescribed power-law motion
    /// or a simulated one, with its ground truth as `<clip>.truth.json`.
    Render(Box<RenderArgs>),
    /// Measure one clip (thesis Chapter 3): calibration, rim height, peaks, φ, ψ̇,
    /// energy and its power law; writes CSV, JSON, plots and an HTML page.
    Analyse {
        /// A video (MP4, MOV, AVI) or a folder of PNG/TIFF/JPEG frames.
        clip: PathBuf,
        /// Experiment config (TOML), applied after the folder's `eulerdisk.toml`
        /// and the clip's own `CLIP.toml`.
        #[arg(short, long)]
        config: Option<PathBuf>,
        /// Output folder (default: out/<clip file name>, extension included).
        #[arg(short, long)]
        out: Option<PathBuf>,
        /// Replace an output folder that holds another clip's analysis.
        #[arg(long)]
        force: bool,
        /// Decode every frame. By default a video longer than 8 s is decoded
        /// from a key frame a few seconds before its end, grown back until the
        /// fits' motion and the rest tail are in (the plan records the span).
        #[arg(long)]
        whole: bool,
        #[command(flatten)]
        overlay: OverlayArgs,
    },
    /// Analyse every clip below a folder, in parallel, and write the study report:
    /// per-material tables, box plots, t-tests (Tables 3.2, 3.3), trends.
    Study(StudyArgs),
    /// Combine the outputs of `study --shard K/N` runs into one study report.
    Merge {
        /// The shard output folders.
        #[arg(required = true)]
        shards: Vec<PathBuf>,
        /// Output folder of the combined report.
        #[arg(short, long, default_value = "out/study")]
        out: PathBuf,
        /// Welch's t-test instead of the pooled-variance test of the thesis.
        #[arg(long)]
        welch: bool,
    },
    /// Overlay a simulated model on a measured experiment (thesis §4.7.1, §4.8):
    /// initial state from the footage, η tuned to the halt or fitted, error table,
    /// residual spin and post-flat prediction, in EXPERIMENT_OUT/compare-<model>/.
    Compare(CompareArgs),
    /// Recompute the thesis's published numbers and show them side by side.
    Reproduce {
        /// Output folder for the table (Markdown, CSV, JSON).
        #[arg(short, long, default_value = "out/reproduce")]
        out: PathBuf,
        /// Leave out Table 4.1 (ten η tunings; several seconds of computing).
        #[arg(long)]
        skip_table_4_1: bool,
    },
    /// Run the built-in demonstration: render a small study with known exponents,
    /// analyse it, and write out/demo/index.html (recovered n beside true n).
    Demo {
        /// Output folder.
        #[arg(short, long, default_value = "out/demo")]
        out: PathBuf,
    },
}

/// The overlays `analyse` and `study` draw on the footage (overlay.mp4,
/// last-turns.png).
#[derive(Args)]
struct OverlayArgs {
    /// Write no overlay video or contact sheet.
    #[arg(long)]
    no_overlay: bool,
    /// The overlay video's span, t − t_φ from,to [s].
    #[arg(long, value_name = "FROM,TO", default_value = "-0.5,0.1", allow_hyphen_values = true, value_parser = parse_span)]
    overlay_span: (f64, f64),
    /// Frames per second the overlay video plays at, 1–1000 (a 480 fps clip at 30
    /// plays 16 × slower than filmed).
    #[arg(long, value_name = "FPS", default_value_t = 30.0, value_parser = parse_overlay_fps)]
    overlay_fps: f64,
}

impl OverlayArgs {
    /// The overlays asked for, `None` with `--no-overlay`.
    fn spec(&self) -> Option<OverlaySpec> {
        (!self.no_overlay).then(|| OverlaySpec {
            span_s: self.overlay_span,
            playback_fps: self.overlay_fps,
            ..OverlaySpec::default()
        })
    }
}

/// Slowest and fastest overlay playback [frames/s]: a video player shows neither a
/// frame that stays for seconds nor a thousand frames a second.
const OVERLAY_FPS: (f64, f64) = (1.0, 1000.0);

/// The overlay's playback rate, within [`OVERLAY_FPS`].
fn parse_overlay_fps(text: &str) -> Result<f64, String> {
    let (lo, hi) = OVERLAY_FPS;
    match text.trim().parse::<f64>() {
        Ok(fps) if (lo..=hi).contains(&fps) => Ok(fps),
        _ => Err(format!(
            "`{text}`: give a playback rate from {lo} to {hi} frames/s"
        )),
    }
}

/// `FROM,TO` in seconds, FROM < TO.
fn parse_span(text: &str) -> Result<(f64, f64), String> {
    let (from, to) = text
        .split_once(',')
        .ok_or_else(|| format!("`{text}`: give FROM,TO in seconds, e.g. -0.5,0.1"))?;
    let number = |s: &str| s.trim().parse::<f64>().map_err(|e| format!("`{s}`: {e}"));
    let (from, to) = (number(from)?, number(to)?);
    if from.is_finite() && to.is_finite() && from < to {
        Ok((from, to))
    } else {
        Err(format!("`{text}`: FROM must be before TO"))
    }
}

/// `START:END:FACTOR`: a slowed section's clip times [s] and slow-down (checked
/// further by the renderer).
fn parse_slowed_section(text: &str) -> Result<SlowedSection, String> {
    let parts: Vec<&str> = text.split(':').collect();
    let [start, end, factor] = parts.as_slice() else {
        return Err(format!(
            "`{text}`: give START:END:FACTOR, clip times in seconds and the slow-down, \
             e.g. 0.1:0.3:16"
        ));
    };
    let number = |s: &str| s.trim().parse::<f64>().map_err(|e| format!("`{s}`: {e}"));
    Ok(SlowedSection {
        start_s: number(start)?,
        end_s: number(end)?,
        factor: number(factor)?,
    })
}

/// A band of frequencies `LOW:HIGH` [Hz] (`--shake-band`).
fn parse_band(text: &str) -> Result<[f64; 2], String> {
    let parsed = text.split_once(':').and_then(|(lo, hi)| {
        Some([
            lo.trim().parse::<f64>().ok()?,
            hi.trim().parse::<f64>().ok()?,
        ])
    });
    parsed.ok_or_else(|| format!("`{text}`: give LOW:HIGH in Hz, e.g. 20:80"))
}

#[derive(Args)]
struct SimulateArgs {
    /// Disk parameters.
    #[arg(long, value_enum, default_value = "euler-disk")]
    preset: Preset,
    /// Dissipation model of the rolling-friction moment (thesis §4.4–4.7).
    #[arg(long, value_enum, default_value = "contour")]
    model: ModelKind,
    /// Coefficient of rolling friction η (eq. 4.5).
    #[arg(long, conflicts_with = "stop_at")]
    eta: Option<f64>,
    /// Tune η so that the motion ends at this time [s] instead of giving --eta.
    #[arg(long)]
    stop_at: Option<f64>,
    /// Exponent p of augmented contour friction, contour × φ^(−p) (§4.7.1).
    #[arg(long, default_value_t = 0.722)]
    p: f64,
    /// Coefficient of Coulomb friction μ (Table 3.1: 0.134 for stainless steel).
    #[arg(long, default_value_t = 0.134)]
    mu: f64,
    /// Initial ψ [rad] (default: eq. 4.43).
    #[arg(long)]
    psi: Option<f64>,
    /// Initial ψ̇ [rad/s] (default: eq. 4.43, −188.5).
    #[arg(long, allow_hyphen_values = true)]
    psi_dot: Option<f64>,
    /// Initial φ [rad] (default: eq. 4.43, 0.0243).
    #[arg(long)]
    phi: Option<f64>,
    /// Initial φ̇ [rad/s] (default 0).
    #[arg(long, allow_hyphen_values = true)]
    phi_dot: Option<f64>,
    /// Initial θ̇ [rad/s] (default: eq. 4.43, 187.2).
    #[arg(long, allow_hyphen_values = true)]
    theta_dot: Option<f64>,
    /// Stop at this time at the latest [s].
    #[arg(long, default_value_t = 1.0)]
    t_end: f64,
    /// Output sampling interval [s].
    #[arg(long, default_value_t = 1e-4)]
    dt: f64,
    /// The disk counts as flat below this φ [rad] (thesis: 1e-10).
    #[arg(long, default_value_t = 1e-10)]
    flat_angle: f64,
    /// Output folder.
    #[arg(short, long, default_value = "out/simulate")]
    out: PathBuf,
}

#[derive(Args)]
struct CompareArgs {
    /// An experiment folder written by `eulerdisk analyse` (holds result.json).
    experiment: PathBuf,
    /// Dissipation model (thesis §4.4–4.7).
    #[arg(long, value_enum, required_unless_present = "all_models")]
    model: Option<ModelKind>,
    /// Fit η (and p for augmented contour) by least squares on φ, ψ̇ and β̇ instead
    /// of tuning η to the measured halt.
    #[arg(long)]
    fit: bool,
    /// Rank every dissipation model on this experiment (in compare-all/); the
    /// best one is drawn over the footage (unless --no-overlay).
    #[arg(long)]
    all_models: bool,
    /// Time of the initial state before the halt [s] (default 0.5, eq. 4.43; when the
    /// measurement does not reach back that far, the earliest measured state, with a
    /// warning naming the lead used). A value given that the measurement does not
    /// reach is refused, naming the longest lead that fits.
    #[arg(long)]
    lead: Option<f64>,
    /// Exponent p of augmented contour friction (start value with --fit).
    #[arg(long, default_value_t = 0.722)]
    p: f64,
    /// Coulomb friction μ (default: Table 3.1 for the experiment's material).
    #[arg(long)]
    mu: Option<f64>,
    /// Gap at which the air film of eq. 4.104 gives way to contact [m].
    #[arg(long, default_value_t = eulerdisk::compare::DEFAULT_CONTACT_GAP_M)]
    contact_gap: f64,
    /// Draw no model over the footage (model-overlay.mp4, model-last-turns.png).
    #[arg(long)]
    no_overlay: bool,
}

#[derive(Args)]
struct StudyArgs {
    /// Footage root: clips in folders such as DISK/MATERIAL/run07.mp4.
    #[arg(required_unless_present = "published")]
    root: Option<PathBuf>,
    /// Output folder.
    #[arg(short, long, default_value = "out/study")]
    out: PathBuf,
    /// Analyse only share K of N (Slurm array jobs); combine with `eulerdisk merge`.
    #[arg(long)]
    shard: Option<study::Shard>,
    /// Reuse results whose clip, config and eulerdisk version are unchanged.
    #[arg(long)]
    resume: bool,
    /// Replace the previous report even when this run lost clips it had analysed
    /// (without it, such a run keeps the previous report and exits with status 2).
    #[arg(long)]
    force: bool,
    /// Welch's t-test instead of the pooled-variance test of the thesis.
    #[arg(long)]
    welch: bool,
    /// Regenerate Tables 3.2 and 3.3 from the thesis's published exponents
    /// (Appendix B) instead of analysing footage.
    #[arg(long, conflicts_with = "root")]
    published: bool,
    /// Write no overlay video or contact sheet for the clips.
    #[arg(long)]
    no_overlay: bool,
}

#[derive(Args)]
struct RenderArgs {
    /// Energy exponent n of E = A_e (t_halt − t)^n (prescribed motion), in (0, 2).
    #[arg(long, default_value_t = 0.5)]
    n: f64,
    /// Clip time of the halt [s] (prescribed motion; the first frame is at 0).
    #[arg(long, default_value_t = 1.0)]
    halt: f64,
    /// A_e [J s^-n] (thesis fig. 3.14: 0.0063).
    #[arg(long, default_value_t = 0.0063)]
    a_e: f64,
    /// Base plate: dark reflective steel or a light plate with a shadow (fig. 3.9).
    #[arg(long, value_enum, default_value = "dark")]
    plate: Plate,
    /// Side view above, plan view with the red strip below (fig. 3.19).
    #[arg(long)]
    two_view: bool,
    /// Pinhole side camera at this distance from the disk's near rim [m], 0.1–10
    /// (phones: 0.2–0.5 m); default: orthographic (infinitely far). The truth gives the
    /// perspective factor and the scale at the near rim.
    #[arg(long, value_name = "METRES")]
    camera_distance: Option<f64>,
    /// Lit plate's grey level [0–255] (default 24 dark, 205 light); a light plate
    /// brighter than the disk's side needs it above the side's (--paper-grey).
    #[arg(long, value_name = "GREY")]
    plate_grey: Option<f64>,
    /// Paper's (the disk's side and top face) grey level [0–255].
    #[arg(long, default_value_t = 238.0, value_name = "GREY")]
    paper_grey: f64,
    /// Radius of the rounding of the disk's rims [mm] (shaded, as on a real disk
    /// whose side fades into the plate over its last fraction of a millimetre);
    /// 0 = sharp.
    #[arg(long, default_value_t = 0.0, value_name = "MM")]
    edge_radius: f64,
    /// Plate texture: RMS relative albedo variation of a seeded grain [0–1]; 0 = plain.
    #[arg(long, default_value_t = 0.0, value_name = "CONTRAST")]
    texture: f64,
    /// Plate reflectivity: fraction of its light that is mirror image [0–0.9]
    /// (default 0.25 dark, 0 light).
    #[arg(long, value_name = "FRACTION")]
    reflection: Option<f64>,
    /// Gaussian blur σ of the plate's mirror image [px] (a rough or brushed plate).
    #[arg(long, default_value_t = 0.0, value_name = "PX")]
    reflection_blur: f64,
    /// Elevation of the fill light that shades the paper [deg]: below 45° the side is
    /// brighter than the top face, above it darker.
    #[arg(long, default_value_t = 20.0, value_name = "DEG")]
    fill_elevation: f64,
    /// Read noise σ [grey levels].
    #[arg(long, default_value_t = 0.0, value_name = "GREY")]
    noise: f64,
    /// Shot noise k [grey levels^½]: σ² = noise² + k² × level.
    #[arg(long, default_value_t = 0.0, value_name = "K")]
    shot_noise: f64,
    /// Gaussian blur σ [px].
    #[arg(long, default_value_t = 0.0, value_name = "PX")]
    blur: f64,
    /// Mains flicker at 100 Hz: relative amplitude of the light (0.1 = ±10 %).
    #[arg(long, default_value_t = 0.0, value_name = "FRACTION")]
    flicker: f64,
    /// Flicker at 50 Hz: relative amplitude of the light.
    #[arg(long, default_value_t = 0.0, value_name = "FRACTION")]
    flicker_50: f64,
    /// Phase of the 100 Hz flicker at the first frame [rad].
    #[arg(
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true,
        value_name = "RAD"
    )]
    flicker_phase_100: f64,
    /// Phase of the 50 Hz flicker at the first frame [rad].
    #[arg(
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true,
        value_name = "RAD"
    )]
    flicker_phase_50: f64,
    /// Exposure time [s], at most 1/fps: each frame averages --exposure-samples poses
    /// over it (motion smear).
    #[arg(long, default_value_t = 0.0, value_name = "SECONDS")]
    exposure: f64,
    /// Poses averaged over the exposure [1–16].
    #[arg(long, default_value_t = 2, value_name = "N")]
    exposure_samples: usize,
    /// φ oscillating about stationary rolling: relative amplitude a of
    /// φ = φ_stat (1 + a sin χ) [0–0.5] (prescribed motion).
    #[arg(long, default_value_t = 0.0, value_name = "FRACTION")]
    nutation: f64,
    /// Frequency of the nutation over the precession rate, ω/|ψ̇| (0–10].
    #[arg(long, default_value_t = 0.5, value_name = "RATIO")]
    nutation_ratio: f64,
    /// Phase of the nutation at the halt [rad].
    #[arg(
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true,
        value_name = "RAD"
    )]
    nutation_phase: f64,
    /// Lateral drift before the halt [px/s] (px at the disk's centre).
    #[arg(
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true,
        value_name = "PX_PER_S"
    )]
    drift: f64,
    /// Camera shake: RMS of a vibration of the picture along each image axis [px],
    /// sinusoids in --shake-band drawn from --seed (a tripod's or a hand's).
    #[arg(long, default_value_t = 0.0, value_name = "PX")]
    shake_vibration: f64,
    /// Band of the shake's vibration LOW:HIGH [Hz]; LOW = HIGH: one sinusoid.
    #[arg(long, default_value = "20:80", value_name = "LOW:HIGH", value_parser = parse_band)]
    shake_band: [f64; 2],
    /// Camera shake: peak amplitude of a slow sway of the picture along each image
    /// axis [px].
    #[arg(long, default_value_t = 0.0, value_name = "PX")]
    shake_sway: f64,
    /// Frequency of the sway and the roll [Hz].
    #[arg(long, default_value_t = 1.0, value_name = "HZ")]
    shake_sway_hz: f64,
    /// Camera shake: peak roll of the picture about the optical axis [deg], at the
    /// sway's frequency.
    #[arg(long, default_value_t = 0.0, value_name = "DEG")]
    shake_roll: f64,
    /// Capture indices (0-based) of frames to drop, e.g. 10,57.
    #[arg(long, value_delimiter = ',')]
    drop: Vec<usize>,
    /// Capture indices (0-based) whose frame repeats the previous frame's bytes, as a
    /// phone that misses a capture writes it, e.g. 120,181.
    #[arg(long, value_delimiter = ',')]
    duplicate: Vec<usize>,
    /// Capture indices (0-based) whose frame is the rounded mean of the previous and
    /// next frames, as a phone inserts to reach 240 or 960 fps, e.g. 150.
    #[arg(long, value_delimiter = ',')]
    interpolate: Vec<usize>,
    /// Tag the MP4 with a display matrix rotating it this far clockwise [deg: 0, 90,
    /// 180, 270], as a phone tags its clips: the frames are stored turned the other
    /// way, so the displayed frames are the rendered ones.
    #[arg(long, default_value_t = 0, value_name = "DEG", value_parser = clap::builder::PossibleValuesParser::new(["0", "90", "180", "270"]).map(|s| s.parse::<u16>().expect("a listed value")))]
    rotation_tag: u16,
    /// Store 10-bit samples (yuv420p10le), as phones record HDR.
    #[arg(long)]
    ten_bit: bool,
    /// Store full-range samples (JPEG style, color_range = pc) instead of limited.
    #[arg(long)]
    full_range: bool,
    /// Tag the MP4 as HDR with this transfer function and BT.2020 primaries and
    /// matrix (the samples keep the rendered grey levels).
    #[arg(long, value_enum, value_name = "TRANSFER")]
    hdr: Option<HdrTransfer>,
    /// Tag the MP4's display matrix with a left–right mirror (before the rotation),
    /// as a front camera does; the frames are stored mirrored.
    #[arg(long)]
    mirror_tag: bool,
    /// Store a span of capture time slowed for playback in the MP4, as a phone's
    /// slow-motion section between real-time ramps: START:END:FACTOR, clip times
    /// [s] and the slow-down (16: 480 fps played at 30), e.g. 0.1:0.3:16;
    /// repeatable. The truth gives every frame's container time.
    #[arg(long, value_name = "START:END:FACTOR", value_parser = parse_slowed_section)]
    slow_section: Vec<SlowedSection>,
    /// Capture frames at times jittered about k/fps by up to ±FRACTION/2 of a frame
    /// (seeded by --seed), as a phone's variable frame rate, and stamp them so in
    /// the MP4 [0–0.5]; the truth gives every frame's capture and container time.
    #[arg(long, value_name = "FRACTION")]
    vfr_jitter: Option<f64>,
    /// Frame rate [frames/s] (thesis: 480).
    #[arg(long, default_value_t = 480.0)]
    fps: f64,
    /// Frame size WxH (default 1280x720, or 720x1280 with --two-view).
    #[arg(long)]
    size: Option<String>,
    /// Image scale [m/px] (default: the disk spans 90 % of the width).
    #[arg(long)]
    scale: Option<f64>,
    /// Camera elevation of the side view [deg], in (0, 30].
    #[arg(long, default_value_t = 3.0, value_name = "DEG")]
    elevation: f64,
    /// Flat disk filmed after the halt [s] (post-flat spin, then rest frames).
    #[arg(long, default_value_t = 0.15)]
    after_halt: f64,
    /// β̇ just after the halt [rad/s] (prescribed motion); it stops by eq. 4.113.
    #[arg(long, default_value_t = -2.8, allow_hyphen_values = true)]
    beta_dot_flat: f64,
    /// Coulomb friction μ of the post-flat spin (Table 3.1, stainless steel).
    #[arg(long, default_value_t = 0.134)]
    mu: f64,
    /// Strip angle on the top face β0 [rad] (eq. 3.13).
    #[arg(long, default_value_t = 0.3, allow_hyphen_values = true)]
    beta0: f64,
    /// Precession angle ψ at the halt [rad] (prescribed motion): 0 puts the contact
    /// point facing the camera as the disk falls flat (the thesis's ψ = 0 there), so
    /// the last frames show the rim at its lowest; real footage stops at any phase.
    #[arg(
        long,
        default_value_t = 0.0,
        allow_hyphen_values = true,
        value_name = "RAD"
    )]
    psi_halt: f64,
    /// Seed of the sensor noise and the plate's texture.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// H.264 constant-rate factor of an MP4 (libx264: 0 = lossless luma, 51 = worst);
    /// the same options and crf always give the same bytes.
    #[arg(long, default_value_t = DEFAULT_CRF, value_parser = clap::value_parser!(u8).range(0..=51))]
    crf: u8,
    /// Most frames from one I picture to the next in an MP4 (libx264's keyint;
    /// default 250). Phones key every second or less; other encoders' median gaps
    /// run from 10 to about 150 frames.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    keyint: Option<u32>,
    /// Most B pictures in a row in an MP4 (libx264's bframes; default 3). 0 codes I
    /// and P pictures only, as a phone's hardware encoder often does.
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=16))]
    bframes: Option<u32>,
    /// Disk parameters.
    #[arg(long, value_enum, default_value = "euler-disk")]
    preset: Preset,
    /// Render a simulated trajectory (eq. 4.43 start, the halt where it ends) instead
    /// of a prescribed power law.
    #[arg(long)]
    simulate: bool,
    /// Dissipation model for --simulate.
    #[arg(long, value_enum, default_value = "contour")]
    model: ModelKind,
    /// η for --simulate (default: the thesis's 2.43e-4 for contour, 1.1e-5 for
    /// augmented contour).
    #[arg(long)]
    eta: Option<f64>,
    /// Output: a path ending in .mp4, or a folder for PNG frames.
    #[arg(short, long)]
    out: PathBuf,
}

/// Exit status of a command line that cannot be parsed (an unknown flag, a value
/// out of range): BSD's `EX_USAGE`, apart from 2, which says a study finished with
/// failed clips.
const EXIT_USAGE: u8 = 64;

/// How a command that ran ended (an error is exit status 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Status {
    /// Everything asked for was done: exit status 0.
    Complete,
    /// A study or merge finished, but some clips failed or the previous report was
    /// kept: exit status 2.
    ClipsFailed,
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(err) => {
            // `--help` and `--version` are not errors; clap prints them to stdout.
            let status = if err.use_stderr() { EXIT_USAGE } else { 0 };
            let _ = err.print();
            return ExitCode::from(status);
        }
    };
    match run(cli) {
        Ok(Status::Complete) => ExitCode::SUCCESS,
        Ok(Status::ClipsFailed) => ExitCode::from(2),
        Err(err) => {
            eprintln!("error: {}", error_chain(&err));
            ExitCode::from(1)
        }
    }
}

/// The error and its causes, joined by ": ", leaving out a cause whose text the
/// message already carries (an I/O error the message quotes would otherwise be
/// printed twice: "… (os error 2): No such file or directory (os error 2)").
fn error_chain(err: &anyhow::Error) -> String {
    let mut text = err.to_string();
    for cause in err.chain().skip(1) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text.push_str(": ");
            text.push_str(&cause);
        }
    }
    text
}

fn run(cli: Cli) -> Result<Status> {
    let done = |r: Result<()>| r.map(|()| Status::Complete);
    match cli.command {
        Command::Info { clip, json } => {
            let info = footage::probe(&clip)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&info)?);
            } else {
                println!("{info}");
            }
            Ok(Status::Complete)
        }
        Command::Simulate(args) => done(run_simulate(&args)),
        Command::Render(args) => done(run_render(&args)),
        Command::Analyse {
            clip,
            config,
            out,
            force,
            whole,
            overlay,
        } => done(run_analyse(
            &clip,
            config.as_deref(),
            out,
            force,
            if whole {
                analyse::Decoding::Whole
            } else {
                analyse::Decoding::NearTheEnd
            },
            overlay.spec(),
        )),
        Command::Study(args) => run_study(&args),
        Command::Merge { shards, out, welch } => run_merge(&shards, &out, welch),
        Command::Compare(args) => done(run_compare(&args)),
        Command::Reproduce {
            out,
            skip_table_4_1,
        } => done(run_reproduce(&out, !skip_table_4_1)),
        Command::Demo { out } => done(run_demo(&out)),
    }
}

/// The error of a refused clip, with its failure page written to `out`
/// ([`write_failure`]) unless `out` holds an earlier result, which is kept.
fn explain_failure(clip: &Path, out: &Path, failure: &analyse::Failure) -> anyhow::Error {
    let why = &failure.error;
    if !failure.deserves_a_page() {
        return anyhow::anyhow!("{why}");
    }
    if out.join("result.json").is_file() {
        return anyhow::anyhow!(
            "{why}\n{} is kept: it holds an earlier result, which a failure page does not \
             replace",
            out.display()
        );
    }
    match eulerdisk::output::write_folder(out, |dir| write_failure(dir, clip, failure)) {
        Ok(()) => anyhow::anyhow!(
            "{why}\nnot measured: the reason, what to try and what was found are on {}",
            out.join("index.html").display()
        ),
        Err(e) => anyhow::anyhow!("{why}\nnot measured, and its failure page failed: {e}"),
    }
}

/// A progress bar on a terminal; `None` (plain log lines) otherwise, e.g. in Slurm logs.
fn progress_bar(len: u64, what: &str) -> Option<ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = ProgressBar::new(len);
    let style = ProgressStyle::with_template(&format!(
        "{what} {{bar:40}} {{pos}}/{{len}} {{msg}} [{{elapsed_precise}}]"
    ))
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    Some(bar)
}

fn run_analyse(
    clip: &Path,
    config: Option<&Path>,
    out: Option<PathBuf>,
    force: bool,
    decoding: analyse::Decoding,
    overlay: Option<OverlaySpec>,
) -> Result<()> {
    let root = clip.parent().unwrap_or(Path::new("."));
    let config = analyse::config_for(root, clip, config)?;
    let name = clip
        .file_name()
        .map_or_else(|| "clip".into(), |s| s.to_string_lossy().into_owned());
    let out = out.unwrap_or_else(|| Path::new("out").join(&name));
    eulerdisk::output::check_folder(&out)?;
    if !force && let Some(other) = eulerdisk::report::experiment::other_clip_in(&out, clip) {
        bail!(
            "{} holds the analysis of {}; refusing to replace it with {} \
             (give another -o, or --force)",
            out.display(),
            other.display(),
            clip.display()
        );
    }
    let bar = progress_bar(0, "frames");
    let analysed = analyse::analyse_clip_explaining(
        clip,
        &config,
        decoding,
        overlay.as_ref(),
        &|done, total| {
            if let Some(bar) = &bar {
                bar.set_length(total.unwrap_or(0) as u64);
                bar.set_position(done as u64);
            }
        },
    );
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let (experiment, kept) = match analysed {
        Ok(analysed) => analysed,
        Err(failure) => return Err(explain_failure(clip, &out, &failure)),
    };
    eulerdisk::output::write_folder(&out, |dir| {
        write_experiment(dir, &experiment, overlay.as_ref(), kept.as_ref())
    })?;
    let fit = &experiment.peaks_fit.fit;
    for warning in &experiment.warnings {
        eprintln!("warning: {warning}");
    }
    let flagged = match experiment.skips_in_window {
        0 => String::new(),
        k => format!("; WARNING: {k} flagged frame(s) (dropped or repeated frames?) in the window"),
    };
    println!(
        "{}: n = {:.3} (95 % CI {:.3} … {:.3}), {} peaks in the last {} s; fps {} ({:?}), \
         frame times from {}{flagged}",
        clip.display(),
        fit.n,
        fit.ci95_n.0,
        fit.ci95_n.1,
        fit.points,
        experiment.plan.window_s,
        experiment.plan.fps.fps,
        experiment.plan.fps.source,
        experiment
            .plan
            .frame_times
            .as_ref()
            .map_or("index / fps", |f| f.source.label())
    );
    if let Some(decoded) = &experiment.plan.decoded {
        println!("{}", decoded.summary());
    }
    if let Some(timing) = experiment
        .plan
        .frame_times
        .as_ref()
        .filter(|t| t.sections.len() > 1)
    {
        println!(
            "frame times in {} sections of constant interval: {}",
            timing.sections.len(),
            timing.sections_text()
        );
    }
    println!("report: {}", out.join("index.html").display());
    Ok(())
}

fn report_options(welch: bool) -> StudyReportOptions {
    StudyReportOptions {
        variance: if welch {
            VarianceModel::Welch
        } else {
            VarianceModel::Pooled
        },
        ..StudyReportOptions::default()
    }
}

fn run_study(args: &StudyArgs) -> Result<Status> {
    let options = report_options(args.welch);
    if args.published {
        write_published_report(&args.out, options)?;
        println!("report: {}", args.out.join("index.html").display());
        return Ok(Status::Complete);
    }
    let Some(root) = &args.root else {
        bail!("give a footage folder, or --published");
    };
    eulerdisk::output::check_folder(&args.out)?;
    let footage = study::discover(root, &args.out)?;
    for skipped in &footage.skipped {
        eprintln!("warning: {skipped}");
    }
    let out = OutputLock::acquire(&args.out)?;
    let analyser =
        study::StudyAnalyser::new(root.clone(), (!args.no_overlay).then(OverlaySpec::default));
    let bar = progress_bar(0, "clips");
    let done = std::sync::atomic::AtomicUsize::new(0);
    let events = |event: StudyEvent| match event {
        StudyEvent::Started { clips } => {
            if let Some(bar) = &bar {
                bar.set_length(clips as u64);
            } else {
                eprintln!("study: {clips} clips");
            }
        }
        StudyEvent::Finished { clip, outcome } => {
            let k = done.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
            let line = match outcome {
                Outcome::Analysed(s) if !s.warnings.is_empty() => format!(
                    "{clip}: n = {:.3} ({} warning(s): {})",
                    s.n,
                    s.warnings.len(),
                    s.warnings.join("; ")
                ),
                Outcome::Analysed(s) => format!("{clip}: n = {:.3}", s.n),
                Outcome::Reused(s) => format!("{clip}: n = {:.3} (unchanged, reused)", s.n),
                Outcome::Failed(reason) => format!("{clip}: FAILED: {reason}"),
            };
            match &bar {
                Some(bar) => {
                    bar.set_position(k as u64);
                    bar.println(line);
                }
                None => eprintln!("[{k}] {line}"),
            }
        }
    };
    let run_options = study::RunOptions {
        shard: args.shard,
        resume: args.resume,
        force: args.force,
    };
    let study_run = study::run(footage, &out, run_options, &analyser, &events)?;
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let results = &study_run.results;
    let counts = format!(
        "{} clips analysed, {} failed",
        results.experiments.len(),
        results.failures.len()
    );
    if let Some(kept) = &study_run.kept_previous {
        eprintln!(
            "{counts}; kept the previous report ({} clips analysed) because this run \
             did not analyse {} of its clips: {}. Fix the cause and run again, or give \
             --force to replace it; report: {}",
            kept.analysed,
            kept.lost.len(),
            kept.lost.join(", "),
            args.out.join("index.html").display()
        );
        return Ok(Status::ClipsFailed);
    }
    write_study_report(&args.out, results, options)?;
    println!(
        "{counts}; report: {}",
        args.out.join("index.html").display()
    );
    Ok(if study_run.is_complete() {
        Status::Complete
    } else {
        Status::ClipsFailed
    })
}

fn run_merge(shards: &[PathBuf], out: &Path, welch: bool) -> Result<Status> {
    let results = study::merge(shards)?;
    let lock = OutputLock::acquire(out)?;
    study::gather_experiments(shards, &results, &lock)?;
    eulerdisk::output::write_json(&out.join(study::STUDY_FILE), &results)?;
    write_study_report(out, &results, report_options(welch))?;
    println!(
        "merged {} shards: {} clips analysed, {} failed; report: {}",
        shards.len(),
        results.experiments.len(),
        results.failures.len(),
        out.join("index.html").display()
    );
    Ok(if results.failures.is_empty() {
        Status::Complete
    } else {
        Status::ClipsFailed
    })
}

/// `simulate`, leaving no empty output folder behind when it fails: a folder this
/// run created is removed again if nothing was written into it.
fn run_simulate(args: &SimulateArgs) -> Result<()> {
    let existed = args.out.exists();
    let outcome = simulate_into(args);
    if outcome.is_err() && !existed {
        // Removes the folder only when empty.
        let _ = std::fs::remove_dir(&args.out);
    }
    outcome
}

fn simulate_into(args: &SimulateArgs) -> Result<()> {
    let mut dissipation = Dissipation::new(args.model);
    dissipation.augmented_exponent = args.p;
    let mut initial = InitialState::thesis_eq_4_43();
    initial.psi = args.psi.unwrap_or(initial.psi);
    initial.psi_dot = args.psi_dot.unwrap_or(initial.psi_dot);
    initial.phi = args.phi.unwrap_or(initial.phi);
    initial.phi_dot = args.phi_dot.unwrap_or(initial.phi_dot);
    initial.theta_dot = args.theta_dot.unwrap_or(initial.theta_dot);
    let mut spec = SimulationSpec::thesis_default(args.preset.params(), dissipation, 0.0);
    spec.mu = args.mu;
    spec.initial = initial;
    spec.t_end = args.t_end;
    spec.output_interval = args.dt;
    spec.flat_angle = args.flat_angle;

    let title = |spec: &SimulationSpec| {
        format!("{:?}, {:?}, η = {:.3e}", args.preset, args.model, spec.eta)
    };
    // The trajectory goes to the CSV as it is integrated: memory does not grow
    // with --t-end (tuning's runs, bounded by --stop-at's check, are kept whole).
    let streamed = |spec: &SimulationSpec| -> Result<(RunSummary, Vec<PathBuf>)> {
        let mut writer = TrajectoryWriter::create(&args.out)?;
        let run = simulate_streaming(spec, &mut |sample| {
            writer.push(sample).map_err(|e| e.to_string())
        })
        .context("simulation failed")?;
        let written = writer.finish(&title(spec), spec, &run)?;
        Ok((run, written))
    };
    let (run, written) = match (args.eta, args.stop_at) {
        (Some(eta), None) => {
            spec.eta = eta;
            streamed(&spec)?
        }
        (None, Some(target)) => {
            if args.model == ModelKind::None {
                bail!("--stop-at needs a dissipation model other than `none`");
            }
            // Tuning simulates to twice the target, sampled every --dt.
            let longest = MAX_SAMPLES as f64 * args.dt / 2.0;
            if !(target > 0.0 && target <= longest) {
                bail!(
                    "--stop-at {target} s: give a time between 0 and {longest} s \
                     (at most {MAX_SAMPLES} samples of --dt {} s to twice the target)",
                    args.dt
                );
            }
            let tuned = tune_eta(&spec, target, 1e-4, 1e-6)
                .with_context(|| format!("cannot tune η to stop at {target} s"))?;
            eprintln!(
                "tuned η = {:.6e} ({} simulations)",
                tuned.eta, tuned.simulations
            );
            spec.eta = tuned.eta;
            let trajectory = tuned.trajectory;
            let written = write_simulation(&args.out, &title(&spec), &spec, &trajectory)?;
            let run = RunSummary {
                samples: trajectory.samples.len(),
                start: *trajectory
                    .samples
                    .first()
                    .context("tuning kept no samples")?,
                phases: trajectory.phases,
                end_reason: trajectory.end_reason,
                end: trajectory.end,
                stats: trajectory.stats,
            };
            (run, written)
        }
        (None, None) if args.model == ModelKind::None => streamed(&spec)?,
        _ => bail!("give --eta or --stop-at for the `{:?}` model", args.model),
    };
    println!(
        "ended: {:?} at t = {:.6} s, φ = {:.3e} rad, ψ̇ = {:.4} rad/s, {} slip phase(s)",
        run.end_reason,
        run.end.t,
        run.end.phi,
        run.end.psi_dot,
        run.slip_phases().count()
    );
    for path in written {
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn run_render(args: &RenderArgs) -> Result<()> {
    if args.simulate && args.nutation > 0.0 {
        bail!("--nutation applies to a prescribed power law, not to --simulate");
    }
    if args.simulate && args.vfr_jitter.is_some() {
        bail!("--vfr-jitter applies to a prescribed power law, not to --simulate");
    }
    let params = args.preset.params();
    let motion = if args.simulate {
        simulated_motion(args, &params)?
    } else {
        prescribed_motion(args, &params)?
    };
    let spec = render_spec(args)?;
    let renderer = Renderer::new(&spec, &motion)?;
    eprintln!(
        "rendering {} frames ({} × {} px, {} fps)…",
        renderer.frame_count(),
        spec.width,
        spec.height,
        args.fps
    );
    let encoding = ClipEncoding {
        crf: args.crf,
        keyint: args.keyint,
        bframes: args.bframes,
    };
    let written = write_clip(&renderer, &args.out, encoding)?;
    let truth = renderer.truth();
    println!(
        "halt at clip time {:.4} s, t_β = {:.4} s after it, δ = {:.4e} m/px{}",
        truth.halt_time,
        truth.t_beta,
        truth.delta,
        written
            .codec
            .as_deref()
            .map(|c| format!(", codec {c}"))
            .unwrap_or_default()
    );
    println!(
        "wrote {} ({} frames)",
        written.clip.display(),
        written.frames
    );
    println!("wrote {}", written.truth.display());
    Ok(())
}

/// The motion of `render --simulate`: the model run from the thesis's initial state
/// with the given (or the thesis's) η, to 5 s, and filmed at the given frame rate.
fn simulated_motion(args: &RenderArgs, params: &DiskParams) -> Result<Motion> {
    let eta = match (args.eta, args.model.thesis_eta()) {
        (Some(eta), _) => eta,
        (None, Some(eta)) => eta,
        (None, None) => bail!("give --eta for the `{:?}` model", args.model),
    };
    let dissipation = Dissipation::new(args.model);
    let mut spec = SimulationSpec::thesis_default(*params, dissipation, eta);
    spec.t_end = 5.0;
    spec.mu = args.mu;
    spec.beta0 = args.beta0;
    let trajectory = simulate(&spec).context("simulation for render failed")?;
    Ok(trajectory_motion(
        params,
        &trajectory,
        args.beta0,
        args.mu,
        args.fps,
        args.after_halt,
        dissipation.analytic_exponent(),
    )?)
}

/// The motion of `render` by a prescribed power law E = A_e (t0 − t)^n, with the
/// post-flat spin, the capture's jitter and, if asked, a nutation added.
fn prescribed_motion(args: &RenderArgs, params: &DiskParams) -> Result<Motion> {
    let law = PowerLaw {
        n: args.n,
        a_e: args.a_e,
        precession_sign: -1.0,
        beta0: args.beta0,
        psi_halt: args.psi_halt,
    };
    let timing = Timing {
        fps: args.fps,
        halt_time: args.halt,
        after_halt: args.after_halt,
        jitter: args.vfr_jitter.map(|fraction| CaptureJitter {
            fraction,
            seed: args.seed,
        }),
    };
    let spin = PostFlatSpin {
        beta_dot0: args.beta_dot_flat,
        mu: args.mu,
    };
    let mut motion = power_law_motion(params, &law, &timing, spin)?;
    if args.nutation > 0.0 {
        add_nutation(
            &mut motion,
            Nutation {
                amplitude: args.nutation,
                ratio: args.nutation_ratio,
                phase: args.nutation_phase,
            },
        )?;
    }
    Ok(motion)
}

/// The render's camera, scenery, effects, frame edits and storage from the flags.
fn render_spec(args: &RenderArgs) -> Result<RenderSpec> {
    let mut spec = RenderSpec::thesis(args.plate, args.two_view);
    if let Some(size) = &args.size {
        let parsed = size
            .split_once(['x', 'X'])
            .and_then(|(w, h)| Some((w.trim().parse().ok()?, h.trim().parse().ok()?)));
        let Some((w, h)) = parsed else {
            bail!("--size must look like 320x480 (width x height), got `{size}`");
        };
        (spec.width, spec.height) = (w, h);
    }
    spec.metres_per_px = args.scale;
    spec.elevation_deg = args.elevation;
    spec.camera_distance_m = args.camera_distance;
    spec.edge_radius = 1e-3 * args.edge_radius;
    spec.scenery = Scenery {
        paper_grey: args.paper_grey,
        plate_grey: args.plate_grey,
        texture_contrast: args.texture,
        reflectivity: args.reflection,
        reflection_blur_px: args.reflection_blur,
        fill_elevation_deg: args.fill_elevation,
    };
    spec.effects = Effects {
        noise_sigma: args.noise,
        blur_sigma: args.blur,
        flicker_amplitude: args.flicker,
        flicker_50hz_amplitude: args.flicker_50,
        flicker_phase_100: args.flicker_phase_100,
        flicker_phase_50: args.flicker_phase_50,
        shot_noise: args.shot_noise,
        exposure_s: args.exposure,
        exposure_samples: if args.exposure > 0.0 {
            args.exposure_samples
        } else {
            1
        },
        drift_px_per_s: args.drift,
        shake: (args.shake_vibration != 0.0 || args.shake_sway != 0.0 || args.shake_roll != 0.0)
            .then_some(Shake {
                vibration_rms_px: args.shake_vibration,
                vibration_band_hz: args.shake_band,
                sway_px: args.shake_sway,
                sway_hz: args.shake_sway_hz,
                roll_deg: args.shake_roll,
            }),
        seed: args.seed,
    };
    spec.dropped = args.drop.clone();
    spec.storage = SampleStorage {
        ten_bit: args.ten_bit,
        full_range: args.full_range,
        hdr: args.hdr,
    };
    spec.duplicated = args.duplicate.clone();
    spec.interpolated = args.interpolate.clone();
    spec.slowed_sections = args.slow_section.clone();
    spec.display_orientation = Orientation::new(args.rotation_tag, args.mirror_tag)
        .map_err(|reason| anyhow::anyhow!("--rotation-tag: {reason}"))?;
    Ok(spec)
}

fn run_compare(args: &CompareArgs) -> Result<()> {
    use eulerdisk::compare::{self, CompareOptions, EtaMethod};
    use eulerdisk::report::compare::{comparison_dir, write_comparison, write_ranking};
    let experiment = compare::load_experiment(&args.experiment)?;
    let options = CompareOptions {
        model: args.model.unwrap_or(ModelKind::AugmentedContour),
        method: if args.fit {
            EtaMethod::LeastSquares
        } else {
            EtaMethod::TunedToHalt
        },
        lead_s: args.lead.unwrap_or(eulerdisk::compare::DEFAULT_LEAD_S),
        lead_falls_back: args.lead.is_none(),
        augmented_exponent: args.p,
        mu: args.mu,
        contact_gap_m: args.contact_gap,
    };
    let print = |c: &compare::Comparison| {
        for w in &c.warnings {
            eprintln!("warning: {w}");
        }
        println!(
            "{:?}: η = {:.4e}{}, misfit {:.4}, end {:+.4} s from the measured halt, n(model E) = {}",
            c.options.model,
            c.eta,
            if c.options.model == ModelKind::AugmentedContour {
                format!(", p = {:.3}", c.dissipation.augmented_exponent)
            } else {
                String::new()
            },
            c.misfit,
            c.end_time_error_s,
            c.energy_exponent
                .map_or_else(|| "—".into(), |n| format!("{n:.3}"))
        );
    };
    if args.all_models {
        let models = compare::rankable_models();
        eprintln!("comparing {} models…", models.len());
        let ranked = compare::rank_models(&experiment, &args.experiment, &options, &models);
        // The best model (ranked first; failures come last) is drawn over the footage.
        let mut best_overlay = None;
        for (i, r) in ranked.iter().enumerate() {
            match &r.outcome {
                Ok(c) => {
                    print!("{:>2}. ", i + 1);
                    print(c);
                    let dir = comparison_dir(&args.experiment, r.model);
                    let overlay = if i == 0 && !args.no_overlay {
                        eulerdisk::output::create_folder(&dir)?;
                        let overlay =
                            write_model_overlay(&dir, &experiment, c, &OverlaySpec::default())?;
                        print_edge_error(&overlay);
                        Some(overlay)
                    } else {
                        None
                    };
                    write_comparison(&dir, c, overlay.as_ref())?;
                    if let Some(overlay) = overlay {
                        best_overlay = Some((r.model, overlay));
                    }
                }
                Err(e) => println!("{:>2}. {:?}: failed: {e}", i + 1, r.model),
            }
        }
        let dir = args.experiment.join("compare-all");
        let best = best_overlay.as_ref().map(|(model, o)| (*model, o));
        write_ranking(&dir, &args.experiment, options.method, &ranked, best)?;
        println!("report: {}", dir.join("index.html").display());
        // A ranking of failures compares nothing: the run did not do what was asked.
        if ranked.iter().all(|r| r.outcome.is_err()) {
            bail!(
                "every model failed on {} (see each reason above, and {})",
                args.experiment.display(),
                dir.join("index.html").display()
            );
        }
        return Ok(());
    }
    let comparison = compare::compare(&experiment, &args.experiment, &options)?;
    print(&comparison);
    let dir = comparison_dir(&args.experiment, options.model);
    eulerdisk::output::create_folder(&dir)?;
    let overlay = (!args.no_overlay)
        .then(|| write_model_overlay(&dir, &experiment, &comparison, &OverlaySpec::default()))
        .transpose()?;
    if let Some(overlay) = &overlay {
        print_edge_error(overlay);
    }
    write_comparison(&dir, &comparison, overlay.as_ref())?;
    println!("report: {}", dir.join("index.html").display());
    Ok(())
}

/// The model overlay's rim-edge error, one line.
fn print_edge_error(overlay: &eulerdisk::overlay::ModelOverlay) {
    if let Some(err) = overlay.edge_error {
        println!(
            "model over the footage: rim edge model − footage {:+.2} px mean, {:.2} px RMS ({} frames)",
            err.mean_px, err.rms_px, err.frames
        );
    }
}

fn run_reproduce(out: &Path, include_table_4_1: bool) -> Result<()> {
    if include_table_4_1 {
        eprintln!("reproducing the thesis's numbers, Table 4.1 included (about ten seconds)…");
    }
    let table = reproduce::reproduce(include_table_4_1);
    println!("{}", table.to_markdown());
    for path in table.write(out)? {
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// The demo: render a small study with known exponents, analyse it as a study,
/// recompute the thesis's numbers, and write `OUT/index.html`.
fn run_demo(out: &Path) -> Result<()> {
    let started = std::time::Instant::now();
    let footage = out.join("footage");
    let clips = demo::demo_clips();
    eprintln!(
        "demo: rendering {} clips with known n into {}…",
        clips.len(),
        footage.display()
    );
    demo::render_demo_footage(&footage, &clips)?;
    eprintln!("demo: analysing them as a study…");
    let study_out = out.join("study");
    run_study(&StudyArgs {
        root: Some(footage.clone()),
        out: study_out.clone(),
        shard: None,
        resume: false,
        force: true,
        welch: false,
        published: false,
        no_overlay: false,
    })?;
    let bytes = std::fs::read(study_out.join(study::STUDY_FILE))?;
    let results: study::StudyResults = serde_json::from_slice(&bytes)?;
    // One comparison with the simulator: the two-view clip (true n = 0.45) against
    // augmented contour friction, whose p = 0.722 the thesis chose for n = 0.45.
    let experiment_dir = study_out.join("experiments/two-view/stainless steel/run1.mp4");
    let model = ModelKind::AugmentedContour;
    eprintln!("demo: comparing the two-view clip with {model:?} friction…");
    let compared = eulerdisk::compare::load_experiment(&experiment_dir).and_then(|e| {
        // Peaks exist only inside the 0.5 s fit window, so start just inside it.
        let options = CompareOptions {
            lead_s: 0.45,
            ..CompareOptions::new(model)
        };
        eulerdisk::compare::compare(&e, &experiment_dir, &options)
    });
    let compare_link = match compared {
        Ok(c) => {
            let dir = comparison_dir(&experiment_dir, model);
            eulerdisk::output::create_folder(&dir)?;
            let experiment = eulerdisk::compare::load_experiment(&experiment_dir)?;
            let overlay = write_model_overlay(&dir, &experiment, &c, &OverlaySpec::default())?;
            write_comparison(&dir, &c, Some(&overlay))?;
            Some(dir.strip_prefix(out).unwrap_or(&dir).join("index.html"))
        }
        Err(e) => {
            eprintln!("demo: the comparison failed: {e}");
            None
        }
    };
    eprintln!("demo: recomputing the thesis's published numbers…");
    let table = reproduce::reproduce(true);
    table.write(&out.join("reproduce"))?;
    demo::write_demo_index(out, &clips, &results, "study", compare_link.as_deref())?;
    println!(
        "demo finished in {:.0} s: open {}",
        started.elapsed().as_secs_f64(),
        out.join("index.html").display()
    );
    Ok(())
}
