//! η tuning (thesis §4.6–4.7): find the coefficient of rolling friction for which
//! the motion ends at a given time, by bracketing and a safeguarded secant search in
//! log η. The end is any terminal event (fallen flat or the discontinuity set).

use serde::{Deserialize, Serialize};

use super::simulate::{EndReason, SimulationError, SimulationSpec, Trajectory, simulate};

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
        /// Target end time [s].
        target: f64,
        /// Lowest η tried.
        low: f64,
        /// Highest η tried.
        high: f64,
        /// End time at the lowest η [s].
        t_low: f64,
        /// End time at the highest η [s].
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
    let mut simulations = 0usize;
    // Signed miss: end time minus target; runs that never end count as t_end.
    let mut run = |eta: f64| -> Result<(f64, Trajectory), TuningError> {
        let mut s = base;
        s.eta = eta;
        simulations += 1;
        let trajectory = simulate(&s)?;
        let end = match trajectory.end_reason {
            EndReason::TimeLimit => base.t_end,
            _ => trajectory.end_time(),
        };
        Ok((end - target, trajectory))
    };

    // Bracket: the end time falls as η grows.
    let (mut lo, mut hi) = (eta_guess, eta_guess);
    let (mut f_lo, mut traj_lo) = run(lo)?;
    let (mut f_hi, mut traj_hi) = (f_lo, traj_lo.clone());
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
            hi = lo;
            f_hi = f_lo;
            traj_hi = traj_lo.clone();
            lo /= 4.0;
            (f_lo, traj_lo) = run(lo)?;
        } else {
            lo = hi;
            f_lo = f_hi;
            traj_lo = traj_hi.clone();
            hi *= 4.0;
            (f_hi, traj_hi) = run(hi)?;
        }
    }

    // Illinois search in log η.
    let (mut x_lo, mut x_hi) = (lo.ln(), hi.ln());
    let mut best = if f_lo.abs() < f_hi.abs() {
        (lo, f_lo, traj_lo)
    } else {
        (hi, f_hi, traj_hi)
    };
    let mut side = 0;
    for _ in 0..100 {
        if best.1.abs() <= time_tolerance || (x_hi - x_lo).abs() < 1e-12 {
            break;
        }
        let mut x = (x_lo * f_hi - x_hi * f_lo) / (f_hi - f_lo);
        if !(x > x_lo.min(x_hi) && x < x_lo.max(x_hi)) {
            x = 0.5 * (x_lo + x_hi);
        }
        let (f, traj) = run(x.exp())?;
        if f.abs() < best.1.abs() {
            best = (x.exp(), f, traj);
        }
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
    Ok(EtaTuning {
        eta: best.0,
        trajectory: best.2,
        simulations,
    })
}
