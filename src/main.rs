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
