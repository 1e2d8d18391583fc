//! The hybrid rolling/slipping simulation of thesis §4.3.1: integrate one mode with
//! DOP853 (tolerances 1e-12) until an event, locate the event by re-integrating
//! from the last accepted step, switch mode or stop, repeat.
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

/// Slip speed below which slipping ends (eq. 4.36), scaled.
const STICK_SPEED: f64 = 1e-10;
/// Slip speed seeded at a rolling → slipping transition (eq. 4.41), scaled.
const SLIP_SEED: f64 = 1.1e-10;
/// Relative and absolute integration tolerance (the thesis used atol 1e-13 with ODE15s).
const TOLERANCE: f64 = 1e-12;
/// Time tolerance of event location, scaled.
const EVENT_TOLERANCE: f64 = 1e-13;
/// Guard against endless chattering between modes.
const MAX_SWITCHES: usize = 200_000;

/// Initial conditions in SI, ordered as eq. (4.43): angles in rad, rates in rad/s,
/// slip position in m and slip velocity in m/s (intermediate frame).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct InitialState {
    /// ψ [rad].
    pub psi: f64,
    /// ψ̇ [rad/s].
    pub psi_dot: f64,
    /// φ [rad].
    pub phi: f64,
    /// φ̇ [rad/s].
    pub phi_dot: f64,
    /// θ [rad].
    pub theta: f64,
    /// θ̇ [rad/s].
    pub theta_dot: f64,
    /// x [m].
    pub x: f64,
    /// ẋ [m/s].
    pub x_dot: f64,
    /// y [m].
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
    /// Integration stops at this time at the latest [s].
    pub t_end: f64,
    /// Output sampling interval [s]; events are always recorded as well.
    pub output_interval: f64,
    /// The disk counts as fallen flat below this φ [rad] (thesis: 1e-10).
    pub flat_angle: f64,
    /// Angle of the strip on the top face at θ = 0 [rad] (eq. 3.13).
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
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct Sample {
    /// Time [s].
    pub t: f64,
    /// ψ [rad].
    pub psi: f64,
    /// ψ̇ [rad/s].
    pub psi_dot: f64,
    /// φ [rad].
    pub phi: f64,
    /// φ̇ [rad/s].
    pub phi_dot: f64,
    /// θ [rad].
    pub theta: f64,
    /// θ̇ [rad/s].
    pub theta_dot: f64,
    /// x [m].
    pub x: f64,
    /// ẋ [m/s].
    pub x_dot: f64,
    /// y [m].
    pub y: f64,
    /// ẏ [m/s].
    pub y_dot: f64,
    /// Contact mode.
    pub mode: Mode,
    /// Energy above the flat rest state, eq. (4.94) − mgH [J].
    pub energy: f64,
    /// Normal force N [N].
    pub normal_force: f64,
    /// Friction ratio |F|/N (eq. 4.33).
    pub friction_ratio: f64,
    /// Strip angle β (eq. 3.20), unwrapped [rad].
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
    /// Start [s].
    pub start: f64,
    /// End [s].
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
    /// End time [s].
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
        /// Time of failure [s].
        t: f64,
        /// Integrator message.
        reason: String,
    },
    /// The equations of motion became singular.
    #[error("equations of motion singular at t = {t:.6} s (φ = {phi:e} rad)")]
    Singular {
        /// Time [s].
        t: f64,
        /// Nutation [rad].
        phi: f64,
    },
    /// Rolling and slipping switched too many times.
    #[error("more than {MAX_SWITCHES} rolling/slipping switches by t = {t:.6} s")]
    Chattering {
        /// Time [s].
        t: f64,
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
    fn values(&self, y: &StateVector) -> [(Trigger, f64); 4] {
        let acc = self.disk.accelerations(y, self.mode);
        let normal = acc.map_or(f64::NAN, |a| a.normal);
        let mode_event = match self.mode {
            Mode::Rolling => (
                Trigger::Slip,
                acc.map_or(f64::NAN, |a| self.disk.mu - a.friction_ratio()),
            ),
            Mode::Slipping => (Trigger::Stick, y[X_DOT].hypot(y[Y_DOT]) - STICK_SPEED),
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

/// What one phase produced: uniform output samples and the event that ended it.
struct PhaseOutput {
    next_output: f64,
    output_step: f64,
    states: Vec<(f64, StateVector)>,
    previous: Option<[(Trigger, f64); 4]>,
    hit: Option<(Trigger, f64, StateVector)>,
    last: (f64, StateVector),
}

/// Records uniform output, watches the events and stops the integrator at the first.
///
/// States between step ends (output samples, event roots) are computed by a short
/// DOP853 integration from the last accepted step (see [`advance`]) rather than by the
/// solver's dense output, which was measured to lose up to 1e-7 relative energy on
/// this system (tests/simulator.rs, energy conservation at the samples).
struct PhaseRecorder<'a, 'b> {
    events: Events<'a>,
    out: &'b mut PhaseOutput,
}

impl Solout<f64, StateVector> for PhaseRecorder<'_, '_> {
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
        let previous = self
            .out
            .previous
            .unwrap_or_else(|| self.events.values(y_prev));
        let current = self.events.values(y_curr);
        self.out.previous = Some(current);
        self.out.last = (t_curr, *y_curr);
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

        // The earliest event whose function crossed from positive to non-positive.
        let mut earliest: Option<(Trigger, f64)> = None;
        for (k, &(trigger, g1)) in current.iter().enumerate() {
            let g0 = previous[k].1;
            let crossed = g0 > 0.0 && (g1 <= 0.0 || g1.is_nan());
            if !crossed {
                continue;
            }
            let t_root = locate_root(t_prev, t_curr, g0, |t| {
                self.events.values(&state_at(t))[k].1
            });
            if earliest.is_none_or(|(_, t)| t_root < t) {
                earliest = Some((trigger, t_root));
            }
        }

        let t_stop = earliest.map_or(t_curr, |(_, t)| t);
        let out = &mut *self.out;
        while out.next_output <= t_stop {
            let t = out.next_output;
            out.states.push((t, state_at(t)));
            out.next_output += out.output_step;
        }
        match earliest {
            Some((trigger, t)) => {
                out.hit = Some((trigger, t, state_at(t)));
                ControlFlag::Terminate
            }
            None => ControlFlag::Continue,
        }
    }
}

/// Integrates one mode from (t0, y0) to t1 without events (DOP853, same tolerances);
/// `None` if the integrator fails.
fn advance(
    disk: &ScaledDisk,
    mode: Mode,
    t0: f64,
    y0: &StateVector,
    t1: f64,
) -> Option<StateVector> {
    let field = PhaseField { disk, mode };
    let solution = IVP::ode(&field, t0, t1, *y0)
        .method(ExplicitRungeKutta::dop853().rtol(TOLERANCE).atol(TOLERANCE))
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

/// Runs a simulation.
pub fn simulate(spec: &SimulationSpec) -> Result<Trajectory, SimulationError> {
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

    let disk = ScaledDisk {
        h: p.h(),
        a: p.a(),
        c: p.c(),
        mu: spec.mu,
        eta: spec.eta,
        dissipation: spec.dissipation,
    };
    let units = Units::of(p);
    let mut y = units.to_scaled(&spec.initial);
    let tau_end = spec.t_end / units.time;
    let output_step = spec.output_interval / units.time;

    let mut tau = 0.0;
    let mut mode = initial_mode(&disk, &mut y, tau)?;
    let mut phases = vec![Phase {
        mode,
        start: 0.0,
        end: 0.0,
    }];
    let mut scaled_samples: Vec<(f64, StateVector, Mode)> = Vec::new();
    let mut next_output = 0.0;
    let mut stats = SolverStats::default();
    let mut switches = 0usize;
    // The discontinuity function's sign at the start of the run: its zero is terminal.
    let discontinuity_sign = disk
        .dissipation
        .discontinuity(&ScaledDisk::rates(&y))
        .map_or(1.0, f64::signum);

    let end_reason = loop {
        let field = PhaseField { disk: &disk, mode };
        let events = Events {
            disk: &disk,
            mode,
            flat_angle: spec.flat_angle,
            discontinuity_sign,
        };
        let mut out = PhaseOutput {
            next_output,
            output_step,
            states: Vec::new(),
            previous: Some(events.values(&y)),
            hit: None,
            last: (tau, y),
        };
        let recorder = PhaseRecorder {
            events,
            out: &mut out,
        };
        // DOP853 in both modes. Slip phases are stiff near small slip speeds (friction
        // turns the slip direction at a rate ∝ μ/|v|), so they cost many small steps;
        // the implicit solvers of `differential-equations` 0.7 (Radau5, BDF) chatter
        // around |v| = 0 or fail to start from the 1.1e-10 seed (see BENCHMARKS.md).
        let solution = IVP::ode(&field, tau, tau_end, y)
            .method(
                ExplicitRungeKutta::dop853()
                    .rtol(TOLERANCE)
                    .atol(TOLERANCE)
                    .max_steps(50_000_000),
            )
            .solout(recorder)
            .solve()
            .map_err(|e| SimulationError::Integration {
                t: tau * units.time,
                reason: format!("{e:?}").chars().take(200).collect(),
            })?;
        stats.rhs_evaluations += solution.evals.function;
        stats.accepted_steps += solution.steps.accepted;
        stats.rejected_steps += solution.steps.rejected;
        next_output = out.next_output;
        scaled_samples.extend(out.states.iter().map(|&(t, s)| (t, s, mode)));

        let Some((trigger, t_hit, y_hit)) = out.hit else {
            // Reached t_end.
            tau = tau_end;
            y = out.last.1;
            break EndReason::TimeLimit;
        };
        tau = t_hit;
        y = y_hit;
        if !y.iter().all(|v| v.is_finite()) {
            return Err(SimulationError::Singular {
                t: tau * units.time,
                phi: y[PHI],
            });
        }
        let new_mode = match trigger {
            Trigger::Flat => break EndReason::FallenFlat,
            Trigger::Discontinuity => break EndReason::DiscontinuitySet,
            Trigger::LiftOff => break EndReason::LiftOff,
            Trigger::Slip => {
                seed_slip(&disk, &mut y, tau)?;
                Mode::Slipping
            }
            Trigger::Stick => stick_or_slip_on(&disk, &mut y, tau)?,
        };
        scaled_samples.push((tau, y, mode));
        if new_mode != mode {
            switches += 1;
            if switches > MAX_SWITCHES {
                return Err(SimulationError::Chattering {
                    t: tau * units.time,
                });
            }
            if let Some(last) = phases.last_mut() {
                last.end = tau * units.time;
            }
            phases.push(Phase {
                mode: new_mode,
                start: tau * units.time,
                end: tau * units.time,
            });
            mode = new_mode;
        }
    };
    if let Some(last) = phases.last_mut() {
        last.end = tau * units.time;
    }
    scaled_samples.push((tau, y, mode));

    let samples = unscale_samples(&disk, &units, spec.beta0, &scaled_samples);
    let end = *samples
        .last()
        .ok_or_else(|| SimulationError::BadInput("no samples".into()))?;
    Ok(Trajectory {
        samples,
        phases,
        end_reason,
        end,
        stats,
    })
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
    /// √(R/g) [s].
    time: f64,
    /// R [m].
    length: f64,
    /// mg [N].
    force: f64,
    /// mgR [J].
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

/// Converts scaled samples to SI with the derived quantities; β is unwrapped.
fn unscale_samples(
    disk: &ScaledDisk,
    units: &Units,
    beta0: f64,
    scaled: &[(f64, StateVector, Mode)],
) -> Vec<Sample> {
    let rate = 1.0 / units.time;
    let speed = units.length / units.time;
    let mut unwrap = Unwrapper::default();
    scaled
        .iter()
        .map(|&(tau, y, mode)| {
            let acc = disk.accelerations(&y, mode);
            let (normal, ratio) =
                acc.map_or((f64::NAN, f64::NAN), |a| (a.normal, a.friction_ratio()));
            let (phi, psi_dot, theta_dot) = (y[PHI], y[PSI_DOT] * rate, y[THETA_DOT] * rate);
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
                energy: disk.energy(&y) * units.energy,
                normal_force: normal * units.force,
                friction_ratio: ratio,
                beta: unwrap.next(strip_angle(y[PSI], phi, y[THETA], beta0)),
                beta_dot: strip_rate(phi, y[PHI_DOT] * rate, psi_dot, y[THETA], theta_dot, beta0),
                omega_z: vertical_spin(psi_dot, phi, theta_dot),
                stationary_distance: disk.stationary_distance(&y),
            }
        })
        .collect()
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
