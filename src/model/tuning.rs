//! η tuning (thesis §4.6–4.7): find the coefficient of rolling friction for which
//! the motion ends at a given time, by bracketing and a safeguarded secant search in
//! log η. The end is any terminal event (fallen flat or the discontinuity set).

use serde::{Deserialize, Serialize};

use super::dissipation::ModelKind;
use super::simulate::{EndReason, SimulationError, SimulationSpec, Trajectory, simulate};

/// The ten models of Table 4.1 with their end times (pivoting 0.7 s, §4.6) and the η
/// at which the search for the tuned η starts (earlier tunings, rounded; a guess only
/// saves bracketing runs, the search then tunes to [`TABLE_4_1_TIME_TOLERANCE`]).
pub const TABLE_4_1: [(ModelKind, f64, f64); 10] = [
    (ModelKind::ClassicalRolling, 0.5, 2.9e-2),
    (ModelKind::Pivoting, 0.7, 1.2e-1),
    (ModelKind::GeneralRolling, 0.5, 2.9e-2),
    (ModelKind::Contour, 0.5, 2.3e-4),
    (ModelKind::ConstantOffset, 0.5, 2.9e-2),
    (ModelKind::CurvatureOffset, 0.5, 2.3e-4),
    (ModelKind::Greenwood, 0.5, 2.9e-3),
    (ModelKind::BreweHamrock, 0.5, 3.2e-3),
    (ModelKind::Winkler, 0.5, 4.1e-3),
    (ModelKind::Cylinder, 0.5, 2.2e-3),
];

/// Tolerance on the end time when tuning η for Table 4.1 \[s\].
pub const TABLE_4_1_TIME_TOLERANCE: f64 = 1e-4;

/// Result of an η search.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct EtaTuning {
    /// The tuned η.
    pub eta: f64,
    /// The trajectory with that η.
    pub trajectory: Trajectory,
    /// Number of simulations run.
    pub simulations: usize,
}

/// Errors of the η search.
#[derive(Debug, thiserror::Error)]
pub enum TuningError {
    /// A simulation failed.
    #[error(transparent)]
    Simulation(#[from] SimulationError),
    /// No η in the searched range ends the motion at the target.
    #[error(
        "no η in [{low:e}, {high:e}] ends the motion at {target} s \
         (end times {t_low} s and {t_high} s)"
    )]
    NoBracket {
        /// Target end time \[s\].
        target: f64,
        /// Lowest η tried.
        low: f64,
        /// Highest η tried.
        high: f64,
        /// End time at the lowest η \[s\].
        t_low: f64,
        /// End time at the highest η \[s\].
        t_high: f64,
    },
}

/// Finds η such that the motion ends (terminally, not by t_end) at `target` seconds,
/// to within `time_tolerance` seconds. `spec.t_end` is raised above the target so that
/// too-weak dissipation shows as a late (or no) end. `eta_guess` starts the bracket.
pub fn tune_eta(
    spec: &SimulationSpec,
    target: f64,
    eta_guess: f64,
    time_tolerance: f64,
) -> Result<EtaTuning, TuningError> {
    let mut base = *spec;
    base.t_end = spec.t_end.max(2.0 * target);
    let mut search = Search {
        base,
        target,
        simulations: 0,
        best: None,
    };

    // Bracket: the end time falls as η grows.
    let (mut lo, mut hi) = (eta_guess, eta_guess);
    let mut f_lo = search.miss(lo)?;
    let mut f_hi = f_lo;
    let mut expansions = 0;
    while f_lo < 0.0 || f_hi > 0.0 {
        expansions += 1;
        if expansions > 40 {
            return Err(TuningError::NoBracket {
                target,
                low: lo,
                high: hi,
                t_low: f_lo + target,
                t_high: f_hi + target,
            });
        }
        if f_lo < 0.0 {
            (hi, f_hi) = (lo, f_lo);
            lo /= 4.0;
            f_lo = search.miss(lo)?;
        } else {
            (lo, f_lo) = (hi, f_hi);
            hi *= 4.0;
            f_hi = search.miss(hi)?;
        }
    }

    // Illinois search in log η.
    let (mut x_lo, mut x_hi) = (lo.ln(), hi.ln());
    let mut side = 0;
    for _ in 0..100 {
        if search.best_miss() <= time_tolerance || (x_hi - x_lo).abs() < 1e-12 {
            break;
        }
        let mut x = (x_lo * f_hi - x_hi * f_lo) / (f_hi - f_lo);
        if !(x > x_lo.min(x_hi) && x < x_lo.max(x_hi)) {
            x = 0.5 * (x_lo + x_hi);
        }
        let f = search.miss(x.exp())?;
        if f > 0.0 {
            x_lo = x;
            f_lo = f;
            if side == -1 {
                f_hi *= 0.5;
            }
            side = -1;
        } else {
            x_hi = x;
            f_hi = f;
            if side == 1 {
                f_lo *= 0.5;
            }
            side = 1;
        }
    }
    let simulations = search.simulations;
    let (eta, _, trajectory) = search.best.expect("at least one simulation ran");
    Ok(EtaTuning {
        eta,
        trajectory,
        simulations,
    })
}

/// The state of an η search: every run's miss is measured, and only the closest
/// run's trajectory is kept.
struct Search {
    base: SimulationSpec,
    target: f64,
    simulations: usize,
    /// (η, miss, trajectory) of the run ending closest to the target.
    best: Option<(f64, f64, Trajectory)>,
}

impl Search {
    /// Signed miss of the run with this η: end time minus target \[s\]; a run that
    /// never ends counts as ending at t_end.
    fn miss(&mut self, eta: f64) -> Result<f64, TuningError> {
        let mut spec = self.base;
        spec.eta = eta;
        self.simulations += 1;
        let trajectory = simulate(&spec)?;
        let end = match trajectory.end_reason {
            EndReason::TimeLimit => spec.t_end,
            _ => trajectory.end_time(),
        };
        let miss = end - self.target;
        if self.best.as_ref().is_none_or(|b| miss.abs() < b.1.abs()) {
            self.best = Some((eta, miss, trajectory));
        }
        Ok(miss)
    }

    /// |miss| of the closest run so far.
    fn best_miss(&self) -> f64 {
        self.best.as_ref().map_or(f64::INFINITY, |b| b.1.abs())
    }
}
