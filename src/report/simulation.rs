//! Outputs of `eulerdisk simulate`: the trajectory CSV, a JSON summary and the plot
//! panel of φ, ψ̇, θ̇, β̇ and |F|/N with slip phases coloured (thesis figs. 4.3–4.7,
//! 4.12–4.13).

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::plot::{Highlight, Panel, time_panels};
use super::{ReportError, write_csv, write_json};
use crate::model::dynamics::Mode;
use crate::model::simulate::{EndReason, Phase, SimulationSpec, SolverStats, Trajectory};

/// The JSON summary of one simulation.
#[derive(Debug, Clone, Serialize)]
pub struct SimulationSummary {
    /// Crate version that produced it.
    pub eulerdisk_version: &'static str,
    /// The full input.
    pub spec: SimulationSpec,
    /// Why the integration stopped.
    pub end_reason: EndReason,
    /// End time [s].
    pub end_time: f64,
    /// φ at the end [rad].
    pub end_phi: f64,
    /// ψ̇ at the end [rad/s].
    pub end_psi_dot: f64,
    /// θ̇ at the end [rad/s].
    pub end_theta_dot: f64,
    /// Energy at the start and the end [J].
    pub energy_start: f64,
    /// Energy at the end [J].
    pub energy_end: f64,
    /// The slipping phases.
    pub slip_phases: Vec<Phase>,
    /// Number of slipping phases.
    pub slip_phase_count: usize,
    /// Integrator work.
    pub solver: SolverStats,
}

impl SimulationSummary {
    /// Summarises a trajectory.
    pub fn new(spec: &SimulationSpec, trajectory: &Trajectory) -> Self {
        let slip_phases: Vec<Phase> = trajectory.slip_phases().copied().collect();
        SimulationSummary {
            eulerdisk_version: env!("CARGO_PKG_VERSION"),
            spec: *spec,
            end_reason: trajectory.end_reason,
            end_time: trajectory.end_time(),
            end_phi: trajectory.end.phi,
            end_psi_dot: trajectory.end.psi_dot,
            end_theta_dot: trajectory.end.theta_dot,
            energy_start: trajectory.samples.first().map_or(f64::NAN, |s| s.energy),
            energy_end: trajectory.end.energy,
            slip_phase_count: slip_phases.len(),
            slip_phases,
            solver: trajectory.stats,
        }
    }
}

/// Writes `trajectory.csv`, `summary.json` and `panel.svg`/`panel.png` into `dir`;
/// returns the paths written.
pub fn write_simulation(
    dir: &Path,
    title: &str,
    spec: &SimulationSpec,
    trajectory: &Trajectory,
) -> Result<Vec<PathBuf>, ReportError> {
    let csv_path = dir.join("trajectory.csv");
    write_csv(&csv_path, &trajectory.samples)?;
    let json_path = dir.join("summary.json");
    write_json(&json_path, &SimulationSummary::new(spec, trajectory))?;

    let s = &trajectory.samples;
    let column =
        |f: fn(&crate::model::simulate::Sample) -> f64| s.iter().map(f).collect::<Vec<_>>();
    let t = column(|x| x.t);
    let (phi, psi_dot, theta_dot) = (
        column(|x| x.phi),
        column(|x| x.psi_dot),
        column(|x| x.theta_dot),
    );
    let (beta_dot, ratio) = (column(|x| x.beta_dot), column(|x| x.friction_ratio));
    let panels = [
        Panel {
            label: "φ [rad]",
            values: &phi,
            log_y: false,
        },
        Panel {
            label: "ψ̇ [rad/s]",
            values: &psi_dot,
            log_y: false,
        },
        Panel {
            label: "θ̇ [rad/s]",
            values: &theta_dot,
            log_y: false,
        },
        Panel {
            label: "β̇ [rad/s]",
            values: &beta_dot,
            log_y: false,
        },
        Panel {
            label: "|F|/N",
            values: &ratio,
            log_y: false,
        },
    ];
    let highlights: Vec<Highlight> = trajectory
        .phases
        .iter()
        .filter(|p| p.mode == Mode::Slipping)
        .map(|p| Highlight {
            start: p.start,
            end: p.end,
        })
        .collect();
    let plots = time_panels(
        &dir.join("panel"),
        title,
        "t [s]",
        &t,
        &panels,
        &highlights,
        "slipping",
    )
    .map_err(|e| ReportError::Serialise {
        path: dir.join("panel"),
        reason: e.to_string(),
    })?;
    let mut written = vec![csv_path, json_path];
    written.extend(plots);
    Ok(written)
}
