//! The `eulerdisk` command line: clap definitions and dispatch only; every
//! computation lives in the library.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::{Args, Parser, Subcommand};
use rayon::prelude::*;

use eulerdisk::model::dissipation::{Dissipation, ModelKind};
use eulerdisk::model::params::Preset;
use eulerdisk::model::simulate::{InitialState, SimulationSpec, simulate};
use eulerdisk::model::tuning::tune_eta;
use eulerdisk::render::{
    Effects, Plate, PostFlatSpin, PowerLaw, RenderSpec, Renderer, Timing, power_law_motion,
    trajectory_motion, write_clip,
};
use eulerdisk::report::simulation::write_simulation;
use eulerdisk::{footage, reproduce};

/// Slow-motion footage of spinning disks, turned into physics.
#[derive(Parser)]
#[command(version, about, propagate_version = true)]
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
    Render(RenderArgs),
    /// Recompute the thesis's published numbers and show them side by side.
    Reproduce {
        /// Output folder for the table (Markdown, CSV, JSON).
        #[arg(short, long, default_value = "out/reproduce")]
        out: PathBuf,
        /// Leave out Table 4.1 (ten η tunings; several seconds of computing).
        #[arg(long)]
        skip_table_4_1: bool,
    },
    /// Run the built-in demonstration: the reproduction table and simulator plots.
    Demo {
        /// Output folder.
        #[arg(short, long, default_value = "out/demo")]
        out: PathBuf,
    },
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
    /// Sensor noise σ [grey levels].
    #[arg(long, default_value_t = 0.0)]
    noise: f64,
    /// Gaussian blur σ [px].
    #[arg(long, default_value_t = 0.0)]
    blur: f64,
    /// 50 Hz mains flicker: amplitude of the 100 Hz intensity modulation.
    #[arg(long, default_value_t = 0.0)]
    flicker: f64,
    /// Lateral drift before the halt [px/s].
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    drift: f64,
    /// Capture indices (0-based) of frames to drop, e.g. 10,57.
    #[arg(long, value_delimiter = ',')]
    drop: Vec<usize>,
    /// Frame rate [frames/s] (thesis: 480).
    #[arg(long, default_value_t = 480.0)]
    fps: f64,
    /// Frame size WxH (default 1280x720, or 720x1280 with --two-view).
    #[arg(long)]
    size: Option<String>,
    /// Image scale [m/px] (default: the disk spans 90 % of the width).
    #[arg(long)]
    scale: Option<f64>,
    /// Camera elevation of the side view [deg].
    #[arg(long, default_value_t = 3.0)]
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
    /// Seed of the sensor noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
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

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err:#}");
            ExitCode::from(1)
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Info { clip, json } => {
            let info = footage::probe(&clip)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&info)?);
            } else {
                println!("{info}");
            }
            Ok(())
        }
        Command::Simulate(args) => run_simulate(&args),
        Command::Render(args) => run_render(&args),
        Command::Reproduce {
            out,
            skip_table_4_1,
        } => run_reproduce(&out, !skip_table_4_1),
        Command::Demo { out } => run_demo(&out),
    }
}

fn run_simulate(args: &SimulateArgs) -> Result<()> {
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

    let trajectory = match (args.eta, args.stop_at) {
        (Some(eta), None) => {
            spec.eta = eta;
            simulate(&spec).context("simulation failed")?
        }
        (None, Some(target)) => {
            if args.model == ModelKind::None {
                bail!("--stop-at needs a dissipation model other than `none`");
            }
            let tuned = tune_eta(&spec, target, 1e-4, 1e-6)
                .with_context(|| format!("cannot tune η to stop at {target} s"))?;
            eprintln!(
                "tuned η = {:.6e} ({} simulations)",
                tuned.eta, tuned.simulations
            );
            spec.eta = tuned.eta;
            tuned.trajectory
        }
        (None, None) if args.model == ModelKind::None => simulate(&spec)?,
        _ => bail!("give --eta or --stop-at for the `{:?}` model", args.model),
    };
    let title = format!("{:?}, {:?}, η = {:.3e}", args.preset, args.model, spec.eta);
    let written = write_simulation(&args.out, &title, &spec, &trajectory)?;
    println!(
        "ended: {:?} at t = {:.6} s, φ = {:.3e} rad, ψ̇ = {:.4} rad/s, {} slip phase(s)",
        trajectory.end_reason,
        trajectory.end_time(),
        trajectory.end.phi,
        trajectory.end.psi_dot,
        trajectory.slip_phases().count()
    );
    for path in written {
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn run_render(args: &RenderArgs) -> Result<()> {
    let params = args.preset.params();
    let motion = if args.simulate {
        let eta = match (args.eta, args.model) {
            (Some(eta), _) => eta,
            (None, ModelKind::Contour) => 2.43e-4,
            (None, ModelKind::AugmentedContour) => 1.1e-5,
            (None, model) => bail!("give --eta for the `{model:?}` model"),
        };
        let dissipation = Dissipation::new(args.model);
        let mut spec = SimulationSpec::thesis_default(params, dissipation, eta);
        spec.t_end = 5.0;
        spec.mu = args.mu;
        spec.beta0 = args.beta0;
        let trajectory = simulate(&spec).context("simulation for render failed")?;
        trajectory_motion(
            &params,
            &trajectory,
            args.beta0,
            args.mu,
            args.fps,
            args.after_halt,
            dissipation.analytic_exponent(),
        )?
    } else {
        let law = PowerLaw {
            n: args.n,
            a_e: args.a_e,
            precession_sign: -1.0,
            beta0: args.beta0,
        };
        let timing = Timing {
            fps: args.fps,
            halt_time: args.halt,
            after_halt: args.after_halt,
        };
        let spin = PostFlatSpin {
            beta_dot0: args.beta_dot_flat,
            mu: args.mu,
        };
        power_law_motion(&params, &law, &timing, spin)?
    };
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
    spec.effects = Effects {
        noise_sigma: args.noise,
        blur_sigma: args.blur,
        flicker_amplitude: args.flicker,
        drift_px_per_s: args.drift,
        seed: args.seed,
    };
    spec.dropped = args.drop.clone();
    let renderer = Renderer::new(&spec, &motion)?;
    eprintln!(
        "rendering {} frames ({} × {} px, {} fps)…",
        renderer.frame_count(),
        spec.width,
        spec.height,
        args.fps
    );
    let written = write_clip(&renderer, &args.out)?;
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

fn run_reproduce(out: &Path, include_table_4_1: bool) -> Result<()> {
    if include_table_4_1 {
        eprintln!("reproducing the thesis's numbers, Table 4.1 included (a few minutes)…");
    }
    let table = reproduce::reproduce(include_table_4_1);
    println!("{}", table.to_markdown());
    for path in table.write(out)? {
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// The demo at this stage: the reproduction table (without the slow Table 4.1, which
/// `eulerdisk reproduce` computes) plus the simulator panels of the thesis's Coulomb,
/// contour and augmented-contour runs (figs. 4.3, 4.12, 4.16).
fn run_demo(out: &Path) -> Result<()> {
    run_reproduce(&out.join("reproduce"), false)?;
    let params = Preset::EulerDisk.params();
    let runs = [
        ("contour", ModelKind::Contour, 2.43e-4),
        ("augmented-contour", ModelKind::AugmentedContour, 1.1e-5),
        ("coulomb-only", ModelKind::None, 0.0),
    ];
    eprintln!("simulating {} thesis runs in parallel…", runs.len());
    let written: Vec<Vec<PathBuf>> = runs
        .par_iter()
        .map(|&(name, kind, eta)| -> Result<Vec<PathBuf>> {
            let mut spec = SimulationSpec::thesis_default(params, Dissipation::new(kind), eta);
            spec.t_end = 1.0;
            let trajectory =
                simulate(&spec).with_context(|| format!("demo simulation `{name}`"))?;
            let title = format!("Euler's disk, {name}, η = {eta:.3e}");
            Ok(write_simulation(
                &out.join(name),
                &title,
                &spec,
                &trajectory,
            )?)
        })
        .collect::<Result<_>>()?;
    for path in written.iter().flatten() {
        println!("wrote {}", path.display());
    }
    println!("demo finished: see {}", out.display());
    Ok(())
}
