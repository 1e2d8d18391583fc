//! Outputs of `eulerdisk simulate`: the trajectory CSV, a JSON summary and the plot
//! panel of φ, ψ̇, θ̇, β̇ and |F|/N with slip phases coloured (thesis figs. 4.3–4.7,
//! 4.12–4.13).
//!
//! A [`TrajectoryWriter`] takes the samples as the simulator produces them
//! ([`crate::model::simulate::simulate_streaming`]): each goes into the CSV at once,
//! and the plot keeps a min/max envelope of at most [`ENVELOPE_BUCKETS`] time
//! buckets, so writing a trajectory takes the same memory whatever its length.

use std::fs::Permissions;
use std::io::BufWriter;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::ReportError;
use super::plot::{Highlight, Panel, time_panels};
use crate::model::dynamics::Mode;
use crate::model::simulate::{
    EndReason, Phase, RunSummary, Sample, SimulationSpec, SolverStats, Trajectory,
};
use crate::output::{OutputError, create_folder, io_error, write_json};

/// The JSON summary of one simulation.
#[derive(Debug, Clone, Serialize)]
pub struct SimulationSummary {
    /// Crate version that produced it.
    pub eulerdisk_version: &'static str,
    /// The full input.
    pub spec: SimulationSpec,
    /// Why the integration stopped.
    pub end_reason: EndReason,
    /// End time \[s\].
    pub end_time: f64,
    /// φ at the end \[rad\].
    pub end_phi: f64,
    /// ψ̇ at the end [rad/s].
    pub end_psi_dot: f64,
    /// θ̇ at the end [rad/s].
    pub end_theta_dot: f64,
    /// Energy at the start and the end \[J\].
    pub energy_start: f64,
    /// Energy at the end \[J\].
    pub energy_end: f64,
    /// The slipping phases.
    pub slip_phases: Vec<Phase>,
    /// Number of slipping phases.
    pub slip_phase_count: usize,
    /// Integrator work.
    pub solver: SolverStats,
}

impl SimulationSummary {
    /// Summarises a run.
    pub fn new(spec: &SimulationSpec, run: &RunSummary) -> Self {
        let slip_phases: Vec<Phase> = run.slip_phases().copied().collect();
        SimulationSummary {
            eulerdisk_version: env!("CARGO_PKG_VERSION"),
            spec: *spec,
            end_reason: run.end_reason,
            end_time: run.end.t,
            end_phi: run.end.phi,
            end_psi_dot: run.end.psi_dot,
            end_theta_dot: run.end.theta_dot,
            energy_start: run.start.energy,
            energy_end: run.end.energy,
            slip_phase_count: slip_phases.len(),
            slip_phases,
            solver: run.stats,
        }
    }
}

/// Writes `trajectory.csv`, `summary.json` and `panel.svg`/`panel.png` into `dir`
/// for a trajectory held in memory; returns the paths written.
pub fn write_simulation(
    dir: &Path,
    title: &str,
    spec: &SimulationSpec,
    trajectory: &Trajectory,
) -> Result<Vec<PathBuf>, ReportError> {
    let mut writer = TrajectoryWriter::create(dir)?;
    for sample in &trajectory.samples {
        writer.push(sample)?;
    }
    let (Some(&start), Some(&end)) = (trajectory.samples.first(), trajectory.samples.last()) else {
        return Err(ReportError::from(OutputError::Serialise {
            path: dir.join("trajectory.csv"),
            reason: "a trajectory without samples".into(),
        }));
    };
    let run = RunSummary {
        phases: trajectory.phases.clone(),
        end_reason: trajectory.end_reason,
        start,
        end,
        samples: trajectory.samples.len(),
        stats: trajectory.stats,
    };
    writer.finish(title, spec, &run)
}

/// Time buckets the plot's envelope keeps at most: four per pixel column of the
/// widest figure, so the panel shows every excursion the samples make.
pub const ENVELOPE_BUCKETS: usize = 4096;

/// The plotted quantities of a sample: φ, ψ̇, θ̇, β̇, |F|/N.
fn plotted(s: &Sample) -> [f64; 5] {
    [s.phi, s.psi_dot, s.theta_dot, s.beta_dot, s.friction_ratio]
}

/// Consecutive samples merged: their time span and each plotted quantity's range.
#[derive(Clone, Copy, Debug)]
struct Bucket {
    t0: f64,
    t1: f64,
    min: [f64; 5],
    max: [f64; 5],
    samples: usize,
}

impl Bucket {
    fn of(t: f64, values: [f64; 5]) -> Self {
        let finite = values.map(|v| if v.is_finite() { Some(v) } else { None });
        Bucket {
            t0: t,
            t1: t,
            min: finite.map(|v| v.unwrap_or(f64::INFINITY)),
            max: finite.map(|v| v.unwrap_or(f64::NEG_INFINITY)),
            samples: 1,
        }
    }

    fn absorb(&mut self, other: &Bucket) {
        self.t1 = other.t1;
        for k in 0..5 {
            self.min[k] = self.min[k].min(other.min[k]);
            self.max[k] = self.max[k].max(other.max[k]);
        }
        self.samples += other.samples;
    }
}

/// A min/max envelope of the plotted quantities in at most [`ENVELOPE_BUCKETS`]
/// buckets of equal sample counts: when the buckets run out, neighbours merge in
/// pairs and each bucket takes twice the samples from then on. Up to
/// [`ENVELOPE_BUCKETS`] samples are kept exactly.
#[derive(Debug, Default)]
struct Envelope {
    buckets: Vec<Bucket>,
    per_bucket: usize,
}

impl Envelope {
    fn push(&mut self, t: f64, values: [f64; 5]) {
        let bucket = Bucket::of(t, values);
        let per_bucket = self.per_bucket.max(1);
        match self.buckets.last_mut() {
            Some(last) if last.samples < per_bucket => last.absorb(&bucket),
            _ => {
                if self.buckets.len() == ENVELOPE_BUCKETS {
                    self.halve();
                    return self.push(t, values);
                }
                self.buckets.push(bucket);
            }
        }
    }

    fn halve(&mut self) {
        let merged: Vec<Bucket> = self
            .buckets
            .chunks(2)
            .map(|pair| {
                let mut b = pair[0];
                if let Some(second) = pair.get(1) {
                    b.absorb(second);
                }
                b
            })
            .collect();
        self.buckets = merged;
        self.per_bucket = 2 * self.per_bucket.max(1);
    }

    /// Times and the five series to draw: a bucket of one sample as that sample;
    /// a larger one as its minima at its start and its maxima at its end.
    fn series(&self) -> (Vec<f64>, [Vec<f64>; 5]) {
        let mut t = Vec::with_capacity(2 * self.buckets.len());
        let mut values: [Vec<f64>; 5] = Default::default();
        let shown = |v: f64| if v.is_finite() { v } else { f64::NAN };
        for b in &self.buckets {
            t.push(b.t0);
            for (series, &min) in values.iter_mut().zip(&b.min) {
                series.push(shown(min));
            }
            if b.samples > 1 {
                t.push(b.t1);
                for (series, &max) in values.iter_mut().zip(&b.max) {
                    series.push(shown(max));
                }
            }
        }
        (t, values)
    }
}

/// Writes a simulation's outputs into one folder as its samples come:
/// `trajectory.csv` row by row (through a temporary file that replaces the old
/// CSV only once the run is complete), then `summary.json` and the panel.
pub struct TrajectoryWriter {
    dir: PathBuf,
    csv: csv::Writer<BufWriter<tempfile::NamedTempFile>>,
    envelope: Envelope,
}

impl TrajectoryWriter {
    /// Start writing into `dir` (created if missing).
    ///
    /// # Errors
    /// `dir` cannot be created or written.
    pub fn create(dir: &Path) -> Result<Self, ReportError> {
        create_folder(dir)?;
        let csv_path = dir.join("trajectory.csv");
        let file = tempfile::Builder::new()
            .permissions(Permissions::from_mode(0o666))
            .tempfile_in(dir)
            .map_err(io_error(&csv_path))?;
        Ok(TrajectoryWriter {
            dir: dir.to_path_buf(),
            csv: csv::Writer::from_writer(BufWriter::new(file)),
            envelope: Envelope::default(),
        })
    }

    /// Write one sample (the next in time).
    ///
    /// # Errors
    /// The CSV cannot be written (a full disk).
    pub fn push(&mut self, sample: &Sample) -> Result<(), ReportError> {
        self.csv.serialize(sample).map_err(|e| {
            ReportError::from(OutputError::Serialise {
                path: self.dir.join("trajectory.csv"),
                reason: e.to_string(),
            })
        })?;
        self.envelope.push(sample.t, plotted(sample));
        Ok(())
    }

    /// Put the CSV in place and write `summary.json` and the panel; returns the
    /// paths written.
    ///
    /// # Errors
    /// A file cannot be written or the panel cannot be drawn.
    pub fn finish(
        self,
        title: &str,
        spec: &SimulationSpec,
        run: &RunSummary,
    ) -> Result<Vec<PathBuf>, ReportError> {
        let TrajectoryWriter { dir, csv, envelope } = self;
        let csv_path = dir.join("trajectory.csv");
        let failed = |reason: String| {
            ReportError::from(OutputError::Serialise {
                path: csv_path.clone(),
                reason,
            })
        };
        let file = csv
            .into_inner()
            .map_err(|e| failed(e.to_string()))?
            .into_inner()
            .map_err(|e| failed(e.to_string()))?;
        file.as_file().sync_all().map_err(io_error(&csv_path))?;
        file.persist(&csv_path).map_err(|e| {
            ReportError::from(OutputError::Io {
                path: csv_path.clone(),
                source: e.error,
            })
        })?;
        let json_path = dir.join("summary.json");
        write_json(&json_path, &SimulationSummary::new(spec, run))?;
        let mut written = vec![csv_path, json_path];
        written.extend(draw_panel(&dir, title, &envelope, &run.phases)?);
        Ok(written)
    }
}

/// The panel of φ, ψ̇, θ̇, β̇ and |F|/N with the slipping phases highlighted.
fn draw_panel(
    dir: &Path,
    title: &str,
    envelope: &Envelope,
    phases: &[Phase],
) -> Result<[PathBuf; 2], ReportError> {
    let (t, [phi, psi_dot, theta_dot, beta_dot, ratio]) = envelope.series();
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
    let highlights: Vec<Highlight> = phases
        .iter()
        .filter(|p| p.mode == Mode::Slipping)
        .map(|p| Highlight {
            start: p.start,
            end: p.end,
        })
        .collect();
    time_panels(
        &dir.join("panel"),
        title,
        "t [s]",
        &t,
        &panels,
        &highlights,
        "slipping",
    )
    .map_err(|e| {
        ReportError::from(OutputError::Serialise {
            path: dir.join("panel"),
            reason: e.to_string(),
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_envelope_keeps_every_extreme_in_bounded_buckets() {
        let mut envelope = Envelope::default();
        // Up to ENVELOPE_BUCKETS samples: kept exactly.
        for i in 0..ENVELOPE_BUCKETS {
            envelope.push(i as f64, [i as f64; 5]);
        }
        let (t, v) = envelope.series();
        assert_eq!(t.len(), ENVELOPE_BUCKETS);
        assert_eq!(v[0][17], 17.0);
        // 100 × as many samples, one spike of 1e3 among values in [0, 1) and a NaN
        // in |F|/N: the buckets stay bounded, the range covers all samples and the
        // spike is drawn.
        let mut envelope = Envelope::default();
        let n = 100 * ENVELOPE_BUCKETS;
        for i in 0..n {
            let x = (i % 7) as f64 / 7.0;
            let spike = if i == 123_457 { 1e3 } else { x };
            let ratio = if i == 5 { f64::NAN } else { x };
            envelope.push(i as f64, [x, x, x, spike, ratio]);
        }
        assert!(envelope.buckets.len() <= ENVELOPE_BUCKETS);
        assert_eq!(envelope.buckets.iter().map(|b| b.samples).sum::<usize>(), n);
        let (t, v) = envelope.series();
        assert_eq!((t[0], t[t.len() - 1]), (0.0, (n - 1) as f64));
        assert!(t.windows(2).all(|w| w[0] <= w[1]));
        assert_eq!(v[3].iter().copied().fold(0.0, f64::max), 1e3);
        assert_eq!(v[0].iter().copied().fold(1.0, f64::min), 0.0);
        assert!(v[4].iter().all(|x| x.is_finite()));
    }
}
