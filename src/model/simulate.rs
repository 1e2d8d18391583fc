//! The hybrid rolling/slipping simulation of thesis §4.3.1: integrate one mode
//! (tolerances 1e-12) until an event, locate the event by re-integrating from the last
//! accepted step, switch mode or stop, repeat. Rolling is integrated with DOP853;
//! slipping, which is stiff at small slip speeds, starts with the Rosenbrock method
//! RODAS4 and changes to DOP853 once the friction mode is no longer stiff
//! ([`integrate_slipping`]).
//!
//! Events (each located to 1e-13 in scaled time, well inside the thesis's 1e-10):
//! * rolling → slipping when |F|/N reaches μ (eq. 4.33); the slip is seeded with
//!   speed 1.1e-10 opposite to the required friction force (eqs. 4.35, 4.41; scaled
//!   units, ERRATA);
//! * slipping → rolling when the slip speed falls to 1e-10 (eq. 4.36) and rolling is
//!   feasible there; otherwise the disk slips on in the new direction (§4.3.1);
//! * terminal: φ below the flat angle (default 1e-10), the trajectory reaching the
//!   dissipation model's discontinuity set (e.g. θ̇ = 0 for contour friction, eq. 4.60),
//!   the normal force reaching zero (lift-off, outside the thesis's model), or t_end.
//!
//! Input and output are SI; the integration runs in the scaled units of eq. (4.21).

use differential_equations::prelude::*;
use serde::{Deserialize, Serialize};

use super::dissipation::Dissipation;
use super::dynamics::{
    Mode, PHI, PHI_DOT, PSI, PSI_DOT, ScaledDisk, StateVector, THETA, THETA_DOT, X, X_DOT, Y,
    Y_DOT, strip_angle, strip_rate, vertical_spin,
};
use super::params::DiskParams;
use super::rosenbrock::{Step, error_norm, step_factor};

/// Slip speed below which slipping ends (eq. 4.36), scaled.
const STICK_SPEED: f64 = 1e-10;
/// Slip speed seeded at a rolling → slipping transition (eq. 4.41), scaled.
const SLIP_SEED: f64 = 1.1e-10;
/// Relative and absolute integration tolerance (the thesis used atol 1e-13 with ODE15s).
const TOLERANCE: f64 = 1e-12;
/// Time tolerance of event location, scaled.
const EVENT_TOLERANCE: f64 = 1e-13;
/// First step of a slipping phase, scaled time; RODAS4 grows it by up to 6× a step.
const INITIAL_SLIP_STEP: f64 = 1e-6;
/// Step limit of a whole run (accepted and rejected, every phase): the thesis's runs
/// take 3 000–5 000 steps, Coulomb friction alone about 1 000 per second of motion.
/// A run that needs more makes no useful progress (a t_end far beyond any halt, or
/// steps shrunk by extreme rates) and stops with [`SimulationError::NoProgress`]
/// after some tens of seconds rather than running for hours.
pub const MAX_STEPS: usize = 5_000_000;
/// Guard against endless chattering between modes.
const MAX_SWITCHES: usize = 200_000;
/// Most output samples a run produces (100 s of motion at the default 0.1 ms): about
/// 200 MB in a [`Trajectory`] from [`simulate`], 330 MB of CSV from
/// [`simulate_streaming`] into a file. A run that needs more stops with
/// [`SimulationError::TooManySamples`]. Streamed, the run's memory does not depend
/// on t_end at all; this bounds what it writes.
pub const MAX_SAMPLES: usize = 1_000_000;
/// Fastest rim speed R·max(|ψ̇|, |θ̇|, |φ̇|) accepted at the start [m/s]: the speed
/// of sound in air. The rigid rolling disk of Chapter 4 (and its air film) has long
/// stopped describing anything real there, and the integrator's steps would shrink
/// without end.
pub const MAX_RIM_SPEED_M_S: f64 = 343.0;

/// Initial conditions in SI, ordered as eq. (4.43): angles in rad, rates in rad/s,
/// slip position in m and slip velocity in m/s (intermediate frame).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct InitialState {
    /// ψ \[rad\].
    pub psi: f64,
    /// ψ̇ [rad/s].
    pub psi_dot: f64,
    /// φ \[rad\].
    pub phi: f64,
    /// φ̇ [rad/s].
    pub phi_dot: f64,
    /// θ \[rad\].
    pub theta: f64,
    /// θ̇ [rad/s].
    pub theta_dot: f64,
    /// x \[m\].
    pub x: f64,
    /// ẋ [m/s].
    pub x_dot: f64,
    /// y \[m\].
    pub y: f64,
    /// ẏ [m/s].
    pub y_dot: f64,
}

impl InitialState {
    /// The experimentally determined state 0.5 s before the halt, eq. (4.43).
    pub fn thesis_eq_4_43() -> Self {
        InitialState {
            psi: 0.0,
            psi_dot: -188.5,
            phi: 0.0243,
            phi_dot: 0.0,
            theta: 0.0,
            theta_dot: 187.2,
            x: 0.0,
            x_dot: 0.0,
            y: 0.0,
            y_dot: 0.0,
        }
    }

    /// The rocking-can state of eq. (2.15), read in SI as ERRATA explains.
    pub fn thesis_eq_2_15() -> Self {
        InitialState {
            psi: 0.0,
            psi_dot: 0.1001,
            phi: std::f64::consts::PI / 100.0,
            phi_dot: 0.0,
            theta: 0.0,
            theta_dot: -0.1,
            x: 0.0,
            x_dot: 0.0,
            y: 0.0,
            y_dot: 0.0,
        }
    }
}

/// Everything that defines one simulation.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct SimulationSpec {
    /// Disk parameters (SI).
    pub params: DiskParams,
    /// Coefficient of Coulomb friction μ; `f64::INFINITY` forbids slip (Chapter 2).
    pub mu: f64,
    /// Coefficient of rolling friction η (eq. 4.5).
    pub eta: f64,
    /// The dissipative moment's model.
    pub dissipation: Dissipation,
    /// Initial state (SI).
    pub initial: InitialState,
    /// Integration stops at this time at the latest \[s\].
    pub t_end: f64,
    /// Output sampling interval \[s\]; events are always recorded as well.
    pub output_interval: f64,
    /// The disk counts as fallen flat below this φ \[rad\] (thesis: 1e-10).
    pub flat_angle: f64,
    /// Angle of the strip on the top face at θ = 0 \[rad\] (eq. 3.13).
    pub beta0: f64,
}

impl SimulationSpec {
    /// Thesis defaults: Euler's disk from eq. (4.43) with μ = 0.134 (Table 3.1,
    /// stainless steel), φ_flat = 1e-10, output every 0.1 ms.
    pub fn thesis_default(params: DiskParams, dissipation: Dissipation, eta: f64) -> Self {
        SimulationSpec {
            params,
            mu: 0.134,
            eta,
            dissipation,
            initial: InitialState::thesis_eq_4_43(),
            t_end: 5.0,
            output_interval: 1e-4,
            flat_angle: 1e-10,
            beta0: 0.0,
        }
    }
}

/// Why a simulation stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EndReason {
    /// φ fell below the flat angle.
    FallenFlat,
    /// The trajectory reached the dissipation model's discontinuity set (eq. 4.60).
    DiscontinuitySet,
    /// The normal force reached zero: the disk would leave the plane.
    LiftOff,
    /// t reached t_end.
    TimeLimit,
}

/// One output sample, SI.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize)]
pub struct Sample {
    /// Time \[s\].
    pub t: f64,
    /// ψ \[rad\].
    pub psi: f64,
    /// ψ̇ [rad/s].
    pub psi_dot: f64,
    /// φ \[rad\].
    pub phi: f64,
    /// φ̇ [rad/s].
    pub phi_dot: f64,
    /// θ \[rad\].
    pub theta: f64,
    /// θ̇ [rad/s].
    pub theta_dot: f64,
    /// x \[m\].
    pub x: f64,
    /// ẋ [m/s].
    pub x_dot: f64,
    /// y \[m\].
    pub y: f64,
    /// ẏ [m/s].
    pub y_dot: f64,
    /// Contact mode.
    pub mode: Mode,
    /// Energy above the flat rest state, eq. (4.94) − mgH \[J\].
    pub energy: f64,
    /// Normal force N \[N\].
    pub normal_force: f64,
    /// Friction ratio |F|/N (eq. 4.33).
    pub friction_ratio: f64,
    /// Strip angle β (eq. 3.20), unwrapped \[rad\].
    pub beta: f64,
    /// Strip rate β̇ (eq. 3.21) [rad/s].
    pub beta_dot: f64,
    /// Vertical spin ω_z = ψ̇ + θ̇ cos φ (eq. 4.54) [rad/s].
    pub omega_z: f64,
    /// Distance from the stationary-rolling manifold (eqs. 4.39–4.40), scaled rates.
    pub stationary_distance: f64,
}

/// An interval of one contact mode.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Phase {
    /// Mode during the interval.
    pub mode: Mode,
    /// Start \[s\].
    pub start: f64,
    /// End \[s\].
    pub end: f64,
}

/// Work done by the integrator.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize)]
pub struct SolverStats {
    /// Right-hand-side evaluations.
    pub rhs_evaluations: usize,
    /// Accepted steps.
    pub accepted_steps: usize,
    /// Rejected steps.
    pub rejected_steps: usize,
}

/// What a streamed run ([`simulate_streaming`]) returns: everything of a
/// [`Trajectory`] but its samples, which went to the caller's sink.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunSummary {
    /// Contact phases in order.
    pub phases: Vec<Phase>,
    /// Why it stopped.
    pub end_reason: EndReason,
    /// The first sample (the initial state, SI).
    pub start: Sample,
    /// Final state (SI).
    pub end: Sample,
    /// Samples produced.
    pub samples: usize,
    /// Solver work.
    pub stats: SolverStats,
}

impl RunSummary {
    /// The slipping phases.
    pub fn slip_phases(&self) -> impl Iterator<Item = &Phase> {
        self.phases.iter().filter(|p| p.mode == Mode::Slipping)
    }
}

/// A simulated trajectory.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Trajectory {
    /// Output samples (uniform in time, plus each event).
    pub samples: Vec<Sample>,
    /// Contact phases in order.
    pub phases: Vec<Phase>,
    /// Why it stopped.
    pub end_reason: EndReason,
    /// Final state (SI).
    pub end: Sample,
    /// Solver work.
    pub stats: SolverStats,
}

impl Trajectory {
    /// End time \[s\].
    pub fn end_time(&self) -> f64 {
        self.end.t
    }

    /// The slipping phases.
    pub fn slip_phases(&self) -> impl Iterator<Item = &Phase> {
        self.phases.iter().filter(|p| p.mode == Mode::Slipping)
    }
}

/// Errors of the simulator.
#[derive(Debug, thiserror::Error)]
pub enum SimulationError {
    /// Invalid parameters or initial conditions.
    #[error("invalid simulation input: {0}")]
    BadInput(String),
    /// The integrator failed.
    #[error("integration failed at t = {t:.6} s: {reason}")]
    Integration {
        /// Time of failure \[s\].
        t: f64,
        /// Integrator message.
        reason: String,
    },
    /// The equations of motion became singular.
    #[error("equations of motion singular at t = {t:.6} s (φ = {phi:e} rad)")]
    Singular {
        /// Time \[s\].
        t: f64,
        /// Nutation \[rad\].
        phi: f64,
    },
    /// Rolling and slipping switched too many times.
    #[error("more than {MAX_SWITCHES} rolling/slipping switches by t = {t:.6} s")]
    Chattering {
        /// Time \[s\].
        t: f64,
    },
    /// The run took [`MAX_STEPS`] integrator steps without ending.
    #[error(
        "no progress: {MAX_STEPS} integrator steps reached only t = {t:.6} s of t_end = \
         {t_end} s; lower t_end (--t-end), or check the initial rates"
    )]
    NoProgress {
        /// Time reached \[s\].
        t: f64,
        /// The time asked for \[s\].
        t_end: f64,
    },
    /// The run would produce more output samples than [`MAX_SAMPLES`].
    #[error(
        "stopped at t = {t:.6} s: {MAX_SAMPLES} output samples reached before the motion \
         ended (a bound on the output); lower t_end (--t-end) or raise the output interval \
         (--dt)"
    )]
    TooManySamples {
        /// Time reached \[s\].
        t: f64,
    },
    /// The caller's sink refused a sample (e.g. the CSV could not be written).
    #[error("output failed at t = {t:.6} s: {reason}")]
    Output {
        /// Time of the sample \[s\].
        t: f64,
        /// The sink's message.
        reason: String,
    },
}

/// One mode's vector field, for the integrator.
struct PhaseField<'a> {
    disk: &'a ScaledDisk,
    mode: Mode,
}

impl ODE<f64, StateVector> for PhaseField<'_> {
    fn diff(&self, _t: f64, y: &StateVector, dydt: &mut StateVector) {
        *dydt = self
            .disk
            .derivative(y, self.mode)
            .unwrap_or_else(|| StateVector::repeat(f64::NAN));
    }
}

/// What can end a phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Trigger {
    Slip,
    Stick,
    Flat,
    Discontinuity,
    LiftOff,
}

/// Event functions of one phase; each is positive while the phase may go on.
struct Events<'a> {
    disk: &'a ScaledDisk,
    mode: Mode,
    flat_angle: f64,
    /// Sign of the discontinuity function at the start of the phase.
    discontinuity_sign: f64,
}

impl Events<'_> {
    /// The event functions at `y`, inside a step that started at `start`. The stick
    /// function is |v| − 1e-10 (eq. 4.36) while the slip velocity keeps the half-plane
    /// of its direction at the step start, and −|v| − 1e-10 once it has turned through
    /// zero, so that a step jumping across |v| = 0 counts as reaching the stick speed.
    fn values(&self, y: &StateVector, start: &StateVector) -> [(Trigger, f64); 4] {
        let acc = self.disk.accelerations(y, self.mode);
        let normal = acc.map_or(f64::NAN, |a| a.normal);
        let mode_event = match self.mode {
            Mode::Rolling => (
                Trigger::Slip,
                acc.map_or(f64::NAN, |a| self.disk.mu - a.friction_ratio()),
            ),
            Mode::Slipping => {
                let speed = y[X_DOT].hypot(y[Y_DOT]);
                let along = y[X_DOT] * start[X_DOT] + y[Y_DOT] * start[Y_DOT];
                let signed = if along < 0.0 { -speed } else { speed };
                (Trigger::Stick, signed - STICK_SPEED)
            }
        };
        let discontinuity = self
            .disk
            .dissipation
            .discontinuity(&ScaledDisk::rates(y))
            .map_or(1.0, |d| d * self.discontinuity_sign);
        [
            mode_event,
            (Trigger::Flat, y[PHI] - self.flat_angle),
            (Trigger::Discontinuity, discontinuity),
            (Trigger::LiftOff, normal),
        ]
    }
}

/// Where a phase's uniform output samples go (scaled time, state) as they are
/// found; an error stops the run.
type Emit<'e> = dyn FnMut(f64, &StateVector) -> Result<(), SimulationError> + 'e;

/// What one phase produced: uniform output samples, handed to `emit` as they are
/// found, and the event that ended it.
struct PhaseOutput<'e> {
    next_output: f64,
    output_step: f64,
    emit: &'e mut Emit<'e>,
    previous: Option<[(Trigger, f64); 4]>,
    hit: Option<(Trigger, f64, StateVector)>,
    last: (f64, StateVector),
    /// Set when the integration stopped, without an event, to change integrator.
    handover: bool,
    /// Set when `emit` failed; the phase stopped there.
    error: Option<SimulationError>,
}

/// Records the uniform output samples inside one accepted step [t_prev, t_curr] and
/// finds the earliest event in it (Illinois root location on `state_at`, the state at
/// a time inside the step); returns true when an event ends the phase.
fn record_step(
    events: &Events,
    out: &mut PhaseOutput,
    t_prev: f64,
    y_prev: &StateVector,
    t_curr: f64,
    y_curr: &StateVector,
    state_at: impl Fn(f64) -> StateVector,
) -> bool {
    let previous = out
        .previous
        .unwrap_or_else(|| events.values(y_prev, y_prev));
    let current = events.values(y_curr, y_prev);
    out.previous = Some(current);
    out.last = (t_curr, *y_curr);

    // The earliest event whose function crossed from positive to non-positive.
    let mut earliest: Option<(Trigger, f64)> = None;
    for (k, &(trigger, g1)) in current.iter().enumerate() {
        let g0 = previous[k].1;
        let crossed = g0 > 0.0 && (g1 <= 0.0 || g1.is_nan());
        if !crossed {
            continue;
        }
        let t_root = locate_root(t_prev, t_curr, g0, |t| {
            events.values(&state_at(t), y_prev)[k].1
        });
        if earliest.is_none_or(|(_, t)| t_root < t) {
            earliest = Some((trigger, t_root));
        }
    }

    let t_stop = earliest.map_or(t_curr, |(_, t)| t);
    while out.next_output <= t_stop {
        let t = out.next_output;
        if let Err(e) = (out.emit)(t, &state_at(t)) {
            out.error = Some(e);
            return true;
        }
        out.next_output += out.output_step;
    }
    match earliest {
        Some((trigger, t)) => {
            out.hit = Some((trigger, t, state_at(t)));
            true
        }
        None => false,
    }
}

/// Feeds DOP853's accepted steps (rolling phases) to [`record_step`].
///
/// States between step ends (output samples, event roots) are computed by a short
/// DOP853 integration from the last accepted step (see [`advance`]) rather than by the
/// solver's dense output, which was measured to lose up to 1e-7 relative energy on
/// this system (tests/simulator.rs, energy conservation at the samples).
///
/// While slipping, it stops the integration (a hand-over to RODAS4, no event) once the
/// slip speed falls below `hand_back_speed`, where the slip equations become stiff.
struct PhaseRecorder<'a, 'b, 'e> {
    events: Events<'a>,
    out: &'b mut PhaseOutput<'e>,
    hand_back_speed: f64,
}

impl Solout<f64, StateVector> for PhaseRecorder<'_, '_, '_> {
    fn solout<I>(
        &mut self,
        t_curr: f64,
        t_prev: f64,
        y_curr: &StateVector,
        y_prev: &StateVector,
        _interpolator: &mut I,
        _solution: &mut Solution<f64, StateVector>,
    ) -> ControlFlag<f64, StateVector>
    where
        I: Interpolation<f64, StateVector> + ?Sized,
    {
        let (disk, mode) = (self.events.disk, self.events.mode);
        let state_at = |t: f64| -> StateVector {
            if t <= t_prev {
                *y_prev
            } else if t >= t_curr {
                *y_curr
            } else {
                advance(disk, mode, t_prev, y_prev, t).unwrap_or(*y_curr)
            }
        };
        if record_step(
            &self.events,
            self.out,
            t_prev,
            y_prev,
            t_curr,
            y_curr,
            state_at,
        ) {
            return ControlFlag::Terminate;
        }
        if mode == Mode::Slipping && y_curr[X_DOT].hypot(y_curr[Y_DOT]) < self.hand_back_speed {
            self.out.handover = true;
            return ControlFlag::Terminate;
        }
        ControlFlag::Continue
    }
}

/// Integrates a slipping interval from (t0, y0) towards t_end with RODAS4 (see
/// [`super::rosenbrock`]), tolerances [`TOLERANCE`], feeding each accepted step to
/// [`record_step`] until an event ends the phase. States inside a step are one RODAS4
/// step from its start with the same Jacobian.
///
/// RODAS4 (order 4) pays off only while the friction mode is stiff. Its decay rate ρ
/// is read off the slip block ∂(ẍ, ÿ)/∂(ẋ, ẏ) of the Jacobian (≈ 0.45/|v| for the
/// thesis's disk); once ρ h ≤ 1 for the next step h, an explicit step of that size is
/// stable and DOP853 (order 8) is cheaper, so the interval is handed over
/// (`out.handover`) at the end of the step.
fn integrate_slipping(
    events: &Events,
    out: &mut PhaseOutput,
    t0: f64,
    y0: StateVector,
    t_end: f64,
    stats: &mut SolverStats,
) -> Result<(), SimulationError> {
    let disk = events.disk;
    let evaluations = std::cell::Cell::new(0usize);
    let f = |y: &StateVector| {
        evaluations.set(evaluations.get() + 1);
        disk.derivative(y, Mode::Slipping)
    };
    let failure = |t: f64, reason: &str| SimulationError::Integration {
        t,
        reason: reason.into(),
    };
    let (mut t, mut y) = (t0, y0);
    let mut h = INITIAL_SLIP_STEP;
    let result = loop {
        if t >= t_end {
            out.last = (t, y);
            break Ok(());
        }
        let Some(f0) = f(&y) else {
            break Err(failure(t, "slipping equations singular"));
        };
        let Some(jacobian) = disk.jacobian(&y, Mode::Slipping, &f0) else {
            break Err(failure(t, "slipping Jacobian singular"));
        };
        evaluations.set(evaluations.get() + 6);
        let stiffness = slip_decay_rate(&jacobian);
        let step = Step::new(y, f0, jacobian);
        // Attempt steps until one passes the error test.
        let accepted = loop {
            let h_try = h.min(t_end - t);
            if h_try <= 1e-14 * t.abs().max(1.0) {
                break None;
            }
            let attempt = step
                .to(h_try, &f)
                .filter(|r| r.y.iter().all(|v| v.is_finite()));
            let err = attempt
                .as_ref()
                .map_or(f64::INFINITY, |r| error_norm(&y, r, TOLERANCE, TOLERANCE));
            if err <= 1.0 {
                h = h_try * step_factor(err);
                break attempt.map(|r| (h_try, r.y));
            }
            stats.rejected_steps += 1;
            h = h_try * step_factor(err).min(1.0);
        };
        let Some((h_done, y_next)) = accepted else {
            break Err(failure(t, "RODAS4 step size underflow"));
        };
        stats.accepted_steps += 1;
        if stats.accepted_steps + stats.rejected_steps > MAX_STEPS {
            break Err(SimulationError::NoProgress { t, t_end });
        }
        let t_next = if h_done == t_end - t {
            t_end
        } else {
            t + h_done
        };
        let state_at = |s: f64| -> StateVector {
            if s <= t {
                y
            } else if s >= t_next {
                y_next
            } else {
                step.to(s - t, &f).map_or(y_next, |r| r.y)
            }
        };
        if record_step(events, out, t, &y, t_next, &y_next, state_at) {
            break Ok(());
        }
        (t, y) = (t_next, y_next);
        if stiffness * h <= 1.0 {
            out.last = (t, y);
            out.handover = true;
            break Ok(());
        }
    };
    stats.rhs_evaluations += evaluations.get();
    result
}

/// The decay rate of the stiffest slip-velocity mode: max(0, −Re λ) over the
/// eigenvalues λ of the 2×2 block ∂(ẍ, ÿ)/∂(ẋ, ẏ) of the Jacobian. Coulomb friction
/// (eq. 4.32d–e) gives it a real eigenvalue ∝ −μ n/|v|; the frame rotation adds
/// ±iψ̇, which is not stiff.
fn slip_decay_rate(jacobian: &nalgebra::SMatrix<f64, 10, 10>) -> f64 {
    let (a, b) = (jacobian[(X_DOT, X_DOT)], jacobian[(X_DOT, Y_DOT)]);
    let (c, d) = (jacobian[(Y_DOT, X_DOT)], jacobian[(Y_DOT, Y_DOT)]);
    let mean = 0.5 * (a + d);
    let discriminant = mean * mean - (a * d - b * c);
    let most_negative = if discriminant >= 0.0 {
        mean - discriminant.sqrt()
    } else {
        mean
    };
    (-most_negative).max(0.0)
}

/// Integrates one mode from (t0, y0) to t1 without events (DOP853, same tolerances),
/// starting with a single step of size t1 − t0: called with t0 the start of an
/// accepted step and t1 inside it, that step is no longer than the accepted one and
/// so passes the same error test (the solver shortens it if not); `None` if the
/// integrator fails.
fn advance(
    disk: &ScaledDisk,
    mode: Mode,
    t0: f64,
    y0: &StateVector,
    t1: f64,
) -> Option<StateVector> {
    let field = PhaseField { disk, mode };
    let solution = IVP::ode(&field, t0, t1, *y0)
        .method(
            ExplicitRungeKutta::dop853()
                .rtol(TOLERANCE)
                .atol(TOLERANCE)
                .h0(t1 - t0),
        )
        .solve()
        .ok()?;
    match (solution.t.last(), solution.y.last()) {
        (Some(&t), Some(&y)) if (t - t1).abs() <= 1e-12 * t1.abs().max(1.0) => Some(y),
        _ => None,
    }
}

/// Finds the time in [a, b] where g changes sign from positive (at a) to
/// non-positive, by the Illinois variant of regula falsi; returns the first time at
/// which g ≤ 0 within [`EVENT_TOLERANCE`].
fn locate_root(a: f64, b: f64, ga: f64, mut g: impl FnMut(f64) -> f64) -> f64 {
    let (mut lo, mut hi) = (a, b);
    let (mut g_lo, mut g_hi) = (ga, g(b));
    if !g_hi.is_finite() {
        g_hi = -f64::MIN_POSITIVE;
    }
    let mut side = 0;
    for _ in 0..200 {
        if hi - lo <= EVENT_TOLERANCE {
            break;
        }
        let mut t = (lo * g_hi - hi * g_lo) / (g_hi - g_lo);
        if !(t > lo && t < hi) {
            t = 0.5 * (lo + hi);
        }
        let gt = g(t);
        if gt > 0.0 {
            lo = t;
            g_lo = gt;
            if side == -1 {
                g_hi *= 0.5;
            }
            side = -1;
        } else {
            hi = t;
            g_hi = if gt.is_finite() {
                gt
            } else {
                -f64::MIN_POSITIVE
            };
            if side == 1 {
                g_lo *= 0.5;
            }
            side = 1;
        }
    }
    hi
}

/// Runs a simulation and keeps its samples (at most [`MAX_SAMPLES`]).
pub fn simulate(spec: &SimulationSpec) -> Result<Trajectory, SimulationError> {
    let mut samples = Vec::new();
    let run = simulate_streaming(spec, &mut |s: &Sample| {
        samples.push(*s);
        Ok(())
    })?;
    Ok(Trajectory {
        samples,
        phases: run.phases,
        end_reason: run.end_reason,
        end: run.end,
        stats: run.stats,
    })
}

/// Runs a simulation, handing each output sample to `sink` as it is produced (in
/// time order: the uniform samples, each event's state, the final state). The run
/// holds no sample but the last, so its memory does not depend on t_end; it stops
/// with [`SimulationError::TooManySamples`] after [`MAX_SAMPLES`] samples, and with
/// [`SimulationError::Output`] when `sink` fails.
pub fn simulate_streaming(
    spec: &SimulationSpec,
    sink: &mut dyn FnMut(&Sample) -> Result<(), String>,
) -> Result<RunSummary, SimulationError> {
    check_spec(spec)?;
    let units = Units::of(&spec.params);
    let mut y = units.to_scaled(&spec.initial);
    // The discontinuity function's value at the start of the run: its zero is terminal,
    // and the run integrates the moment's branch on this side of it.
    let discontinuity = spec.dissipation.discontinuity(&ScaledDisk::rates(&y));
    let disk = scaled_disk(spec, discontinuity);
    let setup = RunSetup {
        disk: &disk,
        units: &units,
        flat_angle: spec.flat_angle,
        discontinuity_sign: discontinuity.map_or(1.0, f64::signum),
        tau_end: spec.t_end / units.time,
        output_step: spec.output_interval / units.time,
        t_end: spec.t_end,
    };
    let mode = initial_mode(&disk, &mut y, 0.0)?;
    let mut run = RunState::start(y, mode);
    let mut emitter = Emitter {
        disk: &disk,
        units: &units,
        beta0: spec.beta0,
        unwrap: Unwrapper::default(),
        sink,
        count: 0,
        first: None,
        last: None,
    };
    let end_reason = loop {
        let end = integrate_phase(&setup, &mut run, &mut emitter)?;
        if end.hit.is_none() && end.handover {
            // Same phase, other integrator.
            (run.tau, run.y) = end.last;
            run.stiff = !run.stiff;
            continue;
        }
        let Some(hit) = end.hit else {
            // Reached t_end.
            run.tau = setup.tau_end;
            run.y = end.last.1;
            break EndReason::TimeLimit;
        };
        if let Some(reason) = run.take_event(hit, &disk, &units, &mut emitter)? {
            break reason;
        }
    };
    run.finish(end_reason, &units, &mut emitter)
}

/// Checks a spec before a run: valid disk parameters, μ ≥ 0 and finite η ≥ 0,
/// positive t_end, output interval and flat angle, an initial φ between the flat
/// angle and π/2, and finite initial rates that move the rim slower than
/// [`MAX_RIM_SPEED_M_S`].
fn check_spec(spec: &SimulationSpec) -> Result<(), SimulationError> {
    let p = &spec.params;
    p.validate().map_err(SimulationError::BadInput)?;
    let eta_ok = spec.eta.is_finite() && spec.eta >= 0.0;
    if spec.mu.is_nan() || spec.mu < 0.0 || !eta_ok {
        return Err(SimulationError::BadInput(format!(
            "need μ ≥ 0 and finite η ≥ 0, got μ = {}, η = {}",
            spec.mu, spec.eta
        )));
    }
    if !(spec.t_end > 0.0 && spec.output_interval > 0.0 && spec.flat_angle > 0.0) {
        return Err(SimulationError::BadInput(
            "t_end, output interval and flat angle must be positive".into(),
        ));
    }
    if !(spec.initial.phi > spec.flat_angle && spec.initial.phi < std::f64::consts::FRAC_PI_2) {
        return Err(SimulationError::BadInput(format!(
            "initial φ = {} rad must lie between the flat angle and π/2",
            spec.initial.phi
        )));
    }
    let i = &spec.initial;
    let fastest = i.psi_dot.abs().max(i.theta_dot.abs()).max(i.phi_dot.abs());
    let finite = [i.psi_dot, i.theta_dot, i.phi_dot]
        .iter()
        .all(|v| v.is_finite());
    if !finite || fastest * p.radius > MAX_RIM_SPEED_M_S {
        return Err(SimulationError::BadInput(format!(
            "an initial rate of {fastest} rad/s moves the rim at {:.3e} m/s, beyond \
             {MAX_RIM_SPEED_M_S} m/s (the speed of sound in air): give rates below {:.0} rad/s",
            fastest * p.radius,
            MAX_RIM_SPEED_M_S / p.radius
        )));
    }
    Ok(())
}

/// The spec's disk in the scaled units of eq. (4.21), integrating the dissipative
/// moment's branch on the side of its discontinuity where the run starts
/// (`discontinuity`, the discontinuity function's value there).
fn scaled_disk(spec: &SimulationSpec, discontinuity: Option<f64>) -> ScaledDisk {
    let p = &spec.params;
    ScaledDisk {
        h: p.h(),
        a: p.a(),
        c: p.c(),
        mu: spec.mu,
        eta: spec.eta,
        dissipation: spec.dissipation,
        branch: discontinuity.filter(|d| *d != 0.0).map(f64::signum),
    }
}

/// What stays fixed through a run, in scaled units: the disk, the event settings,
/// the end time and the output step.
struct RunSetup<'a> {
    disk: &'a ScaledDisk,
    units: &'a Units,
    flat_angle: f64,
    /// Sign of the discontinuity function at the start of the run.
    discontinuity_sign: f64,
    tau_end: f64,
    output_step: f64,
    /// t_end in SI \[s\], for [`SimulationError::NoProgress`].
    t_end: f64,
}

/// Where a run stands between phases (scaled time and state).
struct RunState {
    tau: f64,
    y: StateVector,
    mode: Mode,
    /// Time of the next uniform output sample.
    next_output: f64,
    stats: SolverStats,
    /// Slipping is integrated by RODAS4 while stiff, else by DOP853 (see
    /// `integrate_slipping`); DOP853 hands back below a quarter of the slip speed at
    /// which RODAS4 handed over.
    stiff: bool,
    hand_back_speed: f64,
    /// Contact phases so far, the last still open.
    phases: Vec<Phase>,
    /// Mode changes so far, against [`MAX_SWITCHES`].
    switches: usize,
}

/// How one phase's integration ended: at an event (trigger, time, state), or without
/// one at its last state, `handover` set when only the integrator changes.
struct PhaseEnd {
    hit: Option<(Trigger, f64, StateVector)>,
    last: (f64, StateVector),
    handover: bool,
}

impl RunState {
    /// A run at τ = 0 in state `y` and `mode`, its first phase open.
    fn start(y: StateVector, mode: Mode) -> Self {
        RunState {
            tau: 0.0,
            y,
            mode,
            next_output: 0.0,
            stats: SolverStats::default(),
            stiff: true,
            hand_back_speed: 0.0,
            phases: vec![Phase {
                mode,
                start: 0.0,
                end: 0.0,
            }],
            switches: 0,
        }
    }

    /// Moves the run to the event `hit`. A terminal event ends the run (its reason
    /// returned); a slip or stick event seeds the slip or ends it (eqs. 4.33–4.41),
    /// records the event's state in the mode that reached it, and opens a new phase
    /// when the mode changes.
    fn take_event(
        &mut self,
        (trigger, t_hit, y_hit): (Trigger, f64, StateVector),
        disk: &ScaledDisk,
        units: &Units,
        emitter: &mut Emitter,
    ) -> Result<Option<EndReason>, SimulationError> {
        self.tau = t_hit;
        self.y = y_hit;
        if !self.y.iter().all(|v| v.is_finite()) {
            return Err(SimulationError::Singular {
                t: self.tau * units.time,
                phi: self.y[PHI],
            });
        }
        let new_mode = match trigger {
            Trigger::Flat => return Ok(Some(EndReason::FallenFlat)),
            Trigger::Discontinuity => return Ok(Some(EndReason::DiscontinuitySet)),
            Trigger::LiftOff => return Ok(Some(EndReason::LiftOff)),
            Trigger::Slip => {
                seed_slip(disk, &mut self.y, self.tau)?;
                Mode::Slipping
            }
            Trigger::Stick => stick_or_slip_on(disk, &mut self.y, self.tau)?,
        };
        // A (re)seeded slip starts at the stiff slip speed of eq. (4.41).
        self.stiff = true;
        self.hand_back_speed = 0.0;
        emitter.emit(self.tau, &self.y, self.mode)?;
        if new_mode != self.mode {
            self.switch_to(new_mode, units)?;
        }
        Ok(None)
    }

    /// Closes the current phase at τ and opens one of `new_mode`; more than
    /// [`MAX_SWITCHES`] changes are chattering.
    fn switch_to(&mut self, new_mode: Mode, units: &Units) -> Result<(), SimulationError> {
        self.switches += 1;
        if self.switches > MAX_SWITCHES {
            return Err(SimulationError::Chattering {
                t: self.tau * units.time,
            });
        }
        if let Some(last) = self.phases.last_mut() {
            last.end = self.tau * units.time;
        }
        self.phases.push(Phase {
            mode: new_mode,
            start: self.tau * units.time,
            end: self.tau * units.time,
        });
        self.mode = new_mode;
        Ok(())
    }

    /// Closes the last phase, records the final state and sums the run up.
    fn finish(
        mut self,
        end_reason: EndReason,
        units: &Units,
        emitter: &mut Emitter,
    ) -> Result<RunSummary, SimulationError> {
        if let Some(last) = self.phases.last_mut() {
            last.end = self.tau * units.time;
        }
        emitter.emit(self.tau, &self.y, self.mode)?;
        let (Some(start), Some(end)) = (emitter.first, emitter.last) else {
            return Err(SimulationError::BadInput("no samples".into()));
        };
        Ok(RunSummary {
            phases: self.phases,
            end_reason,
            start,
            end,
            samples: emitter.count,
            stats: self.stats,
        })
    }
}

/// Integrates the run's current phase from its state until an event, t_end or a
/// change of integrator (RODAS4 while slipping is stiff, else DOP853), handing the
/// uniform output samples to `emitter` as they are found.
fn integrate_phase(
    setup: &RunSetup,
    run: &mut RunState,
    emitter: &mut Emitter,
) -> Result<PhaseEnd, SimulationError> {
    let events = Events {
        disk: setup.disk,
        mode: run.mode,
        flat_angle: setup.flat_angle,
        discontinuity_sign: setup.discontinuity_sign,
    };
    let phase_mode = run.mode;
    let mut emit = |t: f64, y: &StateVector| emitter.emit(t, y, phase_mode);
    let mut out = PhaseOutput {
        next_output: run.next_output,
        output_step: setup.output_step,
        emit: &mut emit,
        previous: Some(events.values(&run.y, &run.y)),
        hit: None,
        last: (run.tau, run.y),
        handover: false,
        error: None,
    };
    let slip_speed = run.y[X_DOT].hypot(run.y[Y_DOT]);
    if run.mode == Mode::Slipping && run.stiff {
        // Stiff slipping (small slip speed): RODAS4.
        integrate_slipping(
            &events,
            &mut out,
            run.tau,
            run.y,
            setup.tau_end,
            &mut run.stats,
        )
        .map_err(|e| setup.in_si(e))?;
        run.hand_back_speed = 0.25 * out.last.1[X_DOT].hypot(out.last.1[Y_DOT]);
    } else {
        // Rolling, and slipping once the friction mode is no longer stiff: DOP853.
        let recorder = PhaseRecorder {
            events,
            out: &mut out,
            hand_back_speed: run.hand_back_speed.min(slip_speed),
        };
        integrate_explicit(setup, recorder, run.tau, run.y, &mut run.stats)?;
    }
    let PhaseOutput {
        next_output,
        hit,
        last,
        handover,
        error,
        ..
    } = out;
    if let Some(error) = error {
        return Err(error);
    }
    run.next_output = next_output;
    Ok(PhaseEnd {
        hit,
        last,
        handover,
    })
}

impl RunSetup<'_> {
    /// An error of [`integrate_slipping`], which counts in scaled time, with its
    /// times in SI.
    fn in_si(&self, e: SimulationError) -> SimulationError {
        match e {
            SimulationError::Integration { t, reason } => SimulationError::Integration {
                t: t * self.units.time,
                reason,
            },
            SimulationError::NoProgress { t, .. } => SimulationError::NoProgress {
                t: t * self.units.time,
                t_end: self.t_end,
            },
            other => other,
        }
    }
}

/// Integrates a phase with DOP853 from (tau, y) towards t_end, feeding its accepted
/// steps to `recorder`, within the steps of [`MAX_STEPS`] the run has left (at least
/// one); errors in SI.
fn integrate_explicit(
    setup: &RunSetup,
    recorder: PhaseRecorder,
    tau: f64,
    y: StateVector,
    stats: &mut SolverStats,
) -> Result<(), SimulationError> {
    let field = PhaseField {
        disk: setup.disk,
        mode: recorder.events.mode,
    };
    let time = setup.units.time;
    let solution = IVP::ode(&field, tau, setup.tau_end, y)
        .method(
            ExplicitRungeKutta::dop853()
                .rtol(TOLERANCE)
                .atol(TOLERANCE)
                .max_steps(
                    MAX_STEPS
                        .saturating_sub(stats.accepted_steps + stats.rejected_steps)
                        .max(1),
                ),
        )
        .solout(recorder)
        .solve()
        .map_err(|e| match e {
            Error::MaxSteps { t, .. } => SimulationError::NoProgress {
                t: t * time,
                t_end: setup.t_end,
            },
            e => SimulationError::Integration {
                t: tau * time,
                reason: format!("{e:?}").chars().take(200).collect(),
            },
        })?;
    stats.rhs_evaluations += solution.evals.function;
    stats.accepted_steps += solution.steps.accepted;
    stats.rejected_steps += solution.steps.rejected;
    Ok(())
}

/// Turns scaled states into SI samples as they are produced and hands them on,
/// counting them against [`MAX_SAMPLES`]; keeps only the first and the last.
struct Emitter<'a> {
    disk: &'a ScaledDisk,
    units: &'a Units,
    beta0: f64,
    /// β is unwrapped across the whole run, sample by sample.
    unwrap: Unwrapper,
    sink: &'a mut dyn FnMut(&Sample) -> Result<(), String>,
    count: usize,
    first: Option<Sample>,
    last: Option<Sample>,
}

impl Emitter<'_> {
    fn emit(&mut self, tau: f64, y: &StateVector, mode: Mode) -> Result<(), SimulationError> {
        if self.count >= MAX_SAMPLES {
            return Err(SimulationError::TooManySamples {
                t: tau * self.units.time,
            });
        }
        let sample = self.in_si(tau, y, mode);
        (self.sink)(&sample).map_err(|reason| SimulationError::Output {
            t: sample.t,
            reason,
        })?;
        self.count += 1;
        self.first.get_or_insert(sample);
        self.last = Some(sample);
        Ok(())
    }

    /// One scaled state in SI with the derived quantities; β unwrapped.
    fn in_si(&mut self, tau: f64, y: &StateVector, mode: Mode) -> Sample {
        let (disk, units) = (self.disk, self.units);
        let rate = 1.0 / units.time;
        let speed = units.length / units.time;
        let acc = disk.accelerations(y, mode);
        let (normal, ratio) = acc.map_or((f64::NAN, f64::NAN), |a| (a.normal, a.friction_ratio()));
        let (phi, psi_dot, theta_dot) = (y[PHI], y[PSI_DOT] * rate, y[THETA_DOT] * rate);
        let beta0 = self.beta0;
        Sample {
            t: tau * units.time,
            psi: y[PSI],
            psi_dot,
            phi,
            phi_dot: y[PHI_DOT] * rate,
            theta: y[THETA],
            theta_dot,
            x: y[X] * units.length,
            x_dot: y[X_DOT] * speed,
            y: y[Y] * units.length,
            y_dot: y[Y_DOT] * speed,
            mode,
            energy: disk.energy(y) * units.energy,
            normal_force: normal * units.force,
            friction_ratio: ratio,
            beta: self.unwrap.next(strip_angle(y[PSI], phi, y[THETA], beta0)),
            beta_dot: strip_rate(phi, y[PHI_DOT] * rate, psi_dot, y[THETA], theta_dot, beta0),
            omega_z: vertical_spin(psi_dot, phi, theta_dot),
            stationary_distance: disk.stationary_distance(y),
        }
    }
}

/// Chooses the starting mode: given slip velocity → slipping; otherwise rolling if
/// feasible (eq. 4.33), else slipping seeded along eq. (4.35) (as the thesis finds for
/// eq. 4.43).
fn initial_mode(disk: &ScaledDisk, y: &mut StateVector, tau: f64) -> Result<Mode, SimulationError> {
    if y[X_DOT].hypot(y[Y_DOT]) > STICK_SPEED {
        return Ok(Mode::Slipping);
    }
    stick_or_slip_on(disk, y, tau)
}

/// At zero slip speed: roll if the friction needed is within the cone (eq. 4.33),
/// otherwise start slipping opposite to the required friction (eqs. 4.35, 4.41).
fn stick_or_slip_on(
    disk: &ScaledDisk,
    y: &mut StateVector,
    tau: f64,
) -> Result<Mode, SimulationError> {
    y[X_DOT] = 0.0;
    y[Y_DOT] = 0.0;
    let acc = disk
        .accelerations(y, Mode::Rolling)
        .ok_or(SimulationError::Singular {
            t: tau,
            phi: y[PHI],
        })?;
    if acc.friction_ratio() < disk.mu {
        Ok(Mode::Rolling)
    } else {
        seed_slip(disk, y, tau)?;
        Ok(Mode::Slipping)
    }
}

/// Seeds the slip velocity 1.1e-10 along −F̂ (eq. 4.41 with eq. 4.35 taken four-quadrant,
/// ERRATA), F being the friction force rolling would need.
fn seed_slip(disk: &ScaledDisk, y: &mut StateVector, tau: f64) -> Result<(), SimulationError> {
    y[X_DOT] = 0.0;
    y[Y_DOT] = 0.0;
    let acc = disk
        .accelerations(y, Mode::Rolling)
        .ok_or(SimulationError::Singular {
            t: tau,
            phi: y[PHI],
        })?;
    let xi = acc.friction.y.atan2(acc.friction.x) - std::f64::consts::PI;
    y[X_DOT] = SLIP_SEED * xi.cos();
    y[Y_DOT] = SLIP_SEED * xi.sin();
    Ok(())
}

/// Conversion between SI and the scaled units of eq. (4.21).
struct Units {
    /// √(R/g) \[s\].
    time: f64,
    /// R \[m\].
    length: f64,
    /// mg \[N\].
    force: f64,
    /// mgR \[J\].
    energy: f64,
}

impl Units {
    fn of(p: &DiskParams) -> Self {
        Units {
            time: p.time_unit(),
            length: p.radius,
            force: p.mass * p.gravity,
            energy: p.energy_unit(),
        }
    }

    fn to_scaled(&self, s: &InitialState) -> StateVector {
        let (t, l) = (self.time, self.length);
        let mut y = StateVector::zeros();
        y[PSI] = s.psi;
        y[PSI_DOT] = s.psi_dot * t;
        y[PHI] = s.phi;
        y[PHI_DOT] = s.phi_dot * t;
        y[THETA] = s.theta;
        y[THETA_DOT] = s.theta_dot * t;
        y[X] = s.x / l;
        y[X_DOT] = s.x_dot * t / l;
        y[Y] = s.y / l;
        y[Y_DOT] = s.y_dot * t / l;
        y
    }
}

/// Removes the 2π jumps of an angle sequence.
#[derive(Default)]
struct Unwrapper {
    last: Option<f64>,
    offset: f64,
}

impl Unwrapper {
    fn next(&mut self, angle: f64) -> f64 {
        use std::f64::consts::{PI, TAU};
        if let Some(last) = self.last {
            let jump = angle + self.offset - last;
            if jump > PI {
                self.offset -= TAU * ((jump + PI) / TAU).floor();
            } else if jump < -PI {
                self.offset += TAU * ((-jump + PI) / TAU).floor();
            }
        }
        let value = angle + self.offset;
        self.last = Some(value);
        value
    }
}
