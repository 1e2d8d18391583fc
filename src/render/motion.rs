//! The motions that `render` draws, sampled at the capture times of the frames:
//!
//! * a prescribed power law E = A_e (t_halt − t)^n (eqs. 1.2/3.2) under stationary
//!   rolling (eqs. 3.7, 3.8 and 4.40 with the corrected sign, see
//!   [`stationary_rolling`]): φ(t) inverts E(φ) = eq. (3.8) with ψ̇(φ) of stationary
//!   rolling, ψ integrates ψ̇, θ integrates θ̇ = −ψ̇ (cos φ − h sin φ) (eq. 3.7) plus
//!   a constant slip β̇₀ (see [`power_law_motion`]);
//! * a simulated [`Trajectory`] of the `model` stage, interpolated at the frame times,
//!   with the centre of mass moving as the simulation says (eq. 4.15).
//!
//! After the halt the disk lies flat (φ = 0) and the strip turns on with a linearly
//! decaying β̇ (Coulomb friction on the rim, eq. 4.112 as corrected in ERRATA), so it
//! stops at t_β = C |β̇₀| / (μ m g R) (eq. 4.113 for C = mR²/2).
//!
//! Time convention: `t` is relative to the halt (t = 0 at the halt, negative before);
//! the clip's own time is `t + halt_time`, with the first frame at clip time 0.

use serde::{Deserialize, Serialize};

use super::RenderError;
use crate::model::closed_form::{balancing_angle, stationary_divergence_angle, stationary_rolling};
use crate::model::dynamics::strip_angle;
use crate::model::params::DiskParams;
use crate::model::simulate::{EndReason, Sample, Trajectory};
use std::f64::consts::PI;

/// State of the disk at one frame (SI; t relative to the halt).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DiskState {
    /// Time relative to the halt \[s\].
    pub t: f64,
    /// Nutation φ \[rad\].
    pub phi: f64,
    /// Precession ψ \[rad\] (zero at the halt for a prescribed motion).
    pub psi: f64,
    /// Spin θ \[rad\].
    pub theta: f64,
    /// Strip angle β seen from above, eq. (3.20), unwrapped \[rad\].
    pub beta: f64,
    /// ψ̇ [rad/s].
    pub psi_dot: f64,
    /// θ̇ [rad/s].
    pub theta_dot: f64,
    /// Strip rate β̇ [rad/s] (eq. 3.21 before the halt, the post-flat spin after).
    pub beta_dot: f64,
    /// Energy above the flat rest state \[J\] (eq. 3.8 for a prescribed motion, the
    /// simulator's eq. 4.94 − mgH for a trajectory; zero after the halt).
    pub energy: f64,
    /// Horizontal position of the centre of mass relative to its rest position \[m\].
    pub centre: [f64; 2],
}

/// Frame times of a clip.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Timing {
    /// Capture rate [frames/s] (thesis: 480).
    pub fps: f64,
    /// Clip time of the halt \[s\] (the first frame is at clip time 0).
    pub halt_time: f64,
    /// Duration filmed after the halt \[s\]: the post-flat spin and the rest frames
    /// that calibration uses.
    pub after_halt: f64,
    /// Capture times jittered about k/fps, as a phone's variable frame rate
    /// (`None`: exactly k/fps).
    #[serde(default)]
    pub jitter: Option<CaptureJitter>,
}

/// Ticks per nominal frame interval of the clock that jittered capture times lie
/// on, and that the MP4 timestamps of a clip stamped frame by frame count in
/// (`render --vfr-jitter`, `--slow-section`): a capture time is a whole number of
/// ticks, so the container holds it exactly.
pub const TICKS_PER_FRAME: u32 = 1000;

/// A variable frame rate: capture k at (k + a·(u_k − ½))/fps, u_k uniform in
/// [0, 1) from a SplitMix64 stream of the seed (frame 0 unjittered), rounded to
/// the [`TICKS_PER_FRAME`] clock. Intervals vary by up to ±a of 1/fps.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CaptureJitter {
    /// The jitter's full width a [frame intervals], in [0, 0.5].
    pub fraction: f64,
    /// Seed of the jitter's stream.
    pub seed: u64,
}

impl Timing {
    /// Number of captured frames: clip times k/fps ≤ halt_time + after_halt.
    pub fn frame_count(&self) -> usize {
        ((self.halt_time + self.after_halt) * self.fps + 1e-9).floor() as usize + 1
    }

    /// Capture times relative to the halt, one per captured frame \[s\].
    pub fn times(&self) -> Vec<f64> {
        let Some(jitter) = self.jitter else {
            return (0..self.frame_count())
                .map(|k| k as f64 / self.fps - self.halt_time)
                .collect();
        };
        let mut rng = crate::rng::SplitMix64::new(jitter.seed);
        let ticks = f64::from(TICKS_PER_FRAME);
        (0..self.frame_count())
            .map(|k| {
                let u = rng.uniform() - 0.5;
                let offset = if k == 0 { 0.0 } else { jitter.fraction * u };
                let tick = (k as f64 * ticks + (offset * ticks).round()) / ticks;
                tick / self.fps - self.halt_time
            })
            .collect()
    }

    fn validate(&self) -> Result<(), RenderError> {
        let ok = self.fps.is_finite()
            && self.fps > 0.0
            && self.halt_time.is_finite()
            && self.halt_time >= 0.0
            && self.after_halt.is_finite()
            && self.after_halt >= 0.0
            && self
                .jitter
                .is_none_or(|j| j.fraction.is_finite() && (0.0..=0.5).contains(&j.fraction));
        if !ok {
            return Err(RenderError::invalid(format!(
                "timing needs fps > 0, non-negative halt time and after-halt duration and a \
                 jitter in [0, 0.5] of a frame, got fps = {}, halt = {} s, after halt = {} s, \
                 jitter {:?}",
                self.fps,
                self.halt_time,
                self.after_halt,
                self.jitter.map(|j| j.fraction)
            )));
        }
        let frames = self.fps * (self.halt_time + self.after_halt);
        if !(self.fps <= MAX_FPS && frames <= MAX_FRAMES as f64) {
            return Err(RenderError::invalid(format!(
                "{frames:.0} frames at {} frames/s over {} s: a clip holds at most {MAX_FRAMES} \
                 frames at up to {MAX_FPS} frames/s (shorten --halt/--after-halt or lower --fps)",
                self.fps,
                self.halt_time + self.after_halt
            )));
        }
        Ok(())
    }
}

/// Most frames in one rendered clip (about 3.5 min at the thesis's 480 fps): the
/// motion is held in memory frame by frame.
pub const MAX_FRAMES: usize = 100_000;
/// Fastest frame rate rendered [frames/s], as the analysis accepts (config::MAX_FPS).
const MAX_FPS: f64 = crate::config::MAX_FPS;

/// The spin after the disk has fallen flat: β̇ starts at `beta_dot0` and decays
/// linearly under the rim friction torque μ m g R (eq. 4.112, ERRATA), stopping at
/// t_β = C |β̇₀| / (μ m g R) (eq. 4.113).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PostFlatSpin {
    /// β̇ just after the halt [rad/s].
    pub beta_dot0: f64,
    /// Coefficient of Coulomb friction μ (Table 3.1: 0.134 for stainless steel).
    pub mu: f64,
}

impl PostFlatSpin {
    /// Stop time t_β after the halt \[s\], eq. (4.113) with the disk's own C.
    pub fn stop_time(&self, params: &DiskParams) -> f64 {
        if self.beta_dot0 == 0.0 {
            return 0.0;
        }
        params.inertia_c * self.beta_dot0.abs()
            / (self.mu * params.mass * params.gravity * params.radius)
    }

    /// (Δβ, β̇) at time `t` ≥ 0 after the halt.
    fn at(&self, params: &DiskParams, t: f64) -> (f64, f64) {
        let stop = self.stop_time(params);
        if stop == 0.0 {
            return (0.0, 0.0);
        }
        let s = t.clamp(0.0, stop);
        (
            self.beta_dot0 * (s - s * s / (2.0 * stop)),
            // `+ 0.0` turns the −0 at the stop into 0.
            self.beta_dot0 * (1.0 - s / stop) + 0.0,
        )
    }
}

/// A prescribed energy power law under stationary rolling.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PowerLaw {
    /// Energy exponent n ∈ (0, 2) (ψ stays finite at the halt only for n < 2).
    pub n: f64,
    /// A_e [J s^-n] (thesis fig. 3.14: 0.0063 with n = 0.502).
    pub a_e: f64,
    /// Sign of ψ̇ (Euler's disk of eq. 4.43 turns with ψ̇ < 0).
    pub precession_sign: f64,
    /// Strip angle β0 on the top face (eq. 3.13) \[rad\].
    pub beta0: f64,
    /// Precession angle ψ at the halt \[rad\]: where the disk falls flat, as seen from
    /// the camera. 0 (the thesis zeroes ψ there, §3.2.5) puts the contact point
    /// facing the camera at the halt, so the rim is at its lowest in the last frames;
    /// real footage stops at any phase.
    pub psi_halt: f64,
}

impl PowerLaw {
    /// The thesis's fitted example (fig. 3.14): A_e = 0.0063 J s^-n, with exponent `n`.
    pub fn thesis(n: f64) -> Self {
        PowerLaw {
            n,
            a_e: 0.0063,
            precession_sign: -1.0,
            beta0: 0.3,
            psi_halt: 0.0,
        }
    }
}

/// Where a clip's motion came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MotionSource {
    /// [`PowerLaw`] under stationary rolling.
    PowerLaw,
    /// An interpolated simulator trajectory.
    Simulation,
}

/// A motion sampled at every captured frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Motion {
    /// Disk parameters.
    pub params: DiskParams,
    /// Where the motion came from.
    pub source: MotionSource,
    /// The true energy exponent: the prescribed n, or the dissipation model's
    /// analytic exponent for a simulation (if it has one).
    pub true_n: Option<f64>,
    /// The prescribed A_e [J s^-n], if any.
    pub a_e: Option<f64>,
    /// Strip angle β0 on the top face \[rad\].
    pub beta0: f64,
    /// The post-flat spin.
    pub post_flat: PostFlatSpin,
    /// Frame times.
    pub timing: Timing,
    /// One state per captured frame, in capture order.
    pub states: Vec<DiskState>,
    /// φ's oscillation about stationary rolling, if [`add_nutation`] added one.
    #[serde(default)]
    pub nutation: Option<Nutation>,
}

impl Motion {
    /// Stop time of the strip t_β after the halt \[s\] (eq. 4.113).
    pub fn t_beta(&self) -> f64 {
        self.post_flat.stop_time(&self.params)
    }
}

/// Stationary-rolling ψ̇(φ) (eqs. 2.29/4.40, sign corrected) with the chosen sign.
fn stationary_psi_dot(params: &DiskParams, phi: f64, sign: f64) -> Result<f64, RenderError> {
    stationary_rolling(params, phi)
        .map(|(psi_dot, _)| sign * psi_dot)
        .map_err(RenderError::invalid)
}

/// Energy of stationary rolling at nutation φ, eq. (3.8) with ψ̇ of eq. (4.40) \[J\].
pub fn stationary_energy_at(params: &DiskParams, phi: f64) -> Result<f64, RenderError> {
    crate::energy::stationary_energy_at(params, phi).map_err(RenderError::invalid)
}

/// The nutation angle φ whose stationary-rolling energy (eq. 3.8) is `energy` \[J\]:
/// bisection on (0, φ_max], with φ_max half the smaller of the balancing angle and the
/// angle where ψ̇ of eq. (4.40) diverges (E(φ) increases there).
pub fn invert_stationary_energy(params: &DiskParams, energy: f64) -> Result<f64, RenderError> {
    let phi_max = 0.5 * balancing_angle(params).min(stationary_divergence_angle(params));
    let e_max = stationary_energy_at(params, phi_max)?;
    if !(energy.is_finite() && energy > 0.0 && energy <= e_max) {
        return Err(RenderError::invalid(format!(
            "energy {energy} J has no stationary rolling below φ = {phi_max:.3} rad \
             (E there = {e_max:.4} J): lower A_e or the time before the halt"
        )));
    }
    let (mut lo, mut hi) = (0.0_f64, phi_max);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if stationary_energy_at(params, mid)? < energy {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// Nodes and weights of 8-point Gauss–Legendre quadrature on [−1, 1].
const GAUSS_8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
];

/// The prescribed power-law motion (see the module docs) at the frames of `timing`,
/// with the post-flat spin `post_flat` after the halt.
///
/// Under pure stationary rolling β̇ ≈ ψ̇ + θ̇ (eq. 3.22) vanishes at the halt, while
/// a real disk falls flat still turning (thesis §3.3.3, fig. 3.28: β̇ is of order
/// 1 rad/s before t_φ and continuous at t_φ). So the disk slips about its axis at the
/// constant rate β̇₀ of the post-flat spin: θ̇ = θ̇ of eq. (3.7) + β̇₀. The centre of
/// mass stays at rest (the contact slides at R β̇₀), φ and ψ are unchanged, and β̇ is
/// continuous at the halt, as on real footage.
///
/// θ is zero at the halt and ψ is [`PowerLaw::psi_halt`] (0 by default, as the
/// thesis zeroes ψ, §3.2.5); the strip then lies at β = ψ + β0 on the flat disk. They
/// are integrals of ψ̇ ∝ (t_halt − t)^(−n/2) near the halt, computed in the variable
/// u = (t_halt − t)^(1 − n/2), in which the integrand is smooth, by 8-point
/// Gauss–Legendre quadrature between consecutive frames.
pub fn power_law_motion(
    params: &DiskParams,
    law: &PowerLaw,
    timing: &Timing,
    post_flat: PostFlatSpin,
) -> Result<Motion, RenderError> {
    params.validate().map_err(RenderError::invalid)?;
    timing.validate()?;
    if !(law.n > 0.0 && law.n < 2.0) {
        return Err(RenderError::invalid(format!(
            "the energy exponent n must lie in (0, 2) (ψ diverges at the halt for n ≥ 2), got {}",
            law.n
        )));
    }
    if !(law.a_e.is_finite() && law.a_e > 0.0) {
        return Err(RenderError::invalid(format!(
            "A_e must be finite and positive, got {}",
            law.a_e
        )));
    }
    let sign = if law.precession_sign < 0.0 { -1.0 } else { 1.0 };
    let q = 1.0 - law.n / 2.0;
    let h = params.h();
    // Precession and spin rates at time τ before the halt.
    let rates = |tau: f64| -> Result<(f64, f64, f64), RenderError> {
        let phi = invert_stationary_energy(params, law.a_e * tau.powf(law.n))?;
        let psi_dot = stationary_psi_dot(params, phi, sign)?;
        // Eq. (3.7): R θ̇ = −ψ̇ (R cos φ − H sin φ).
        let theta_dot = -psi_dot * (phi.cos() - h * phi.sin());
        Ok((phi, psi_dot, theta_dot))
    };
    // ∫ over τ ∈ [τa, τb] of (ψ̇, θ̇), in u = τ^q.
    let integrate = |tau_a: f64, tau_b: f64| -> Result<(f64, f64), RenderError> {
        let (ua, ub) = (tau_a.powf(q), tau_b.powf(q));
        let (mid, half) = (0.5 * (ua + ub), 0.5 * (ub - ua));
        let (mut psi, mut theta) = (0.0, 0.0);
        for (x, w) in GAUSS_8 {
            let u = mid + half * x;
            let tau = u.powf(1.0 / q);
            let jacobian = u.powf(1.0 / q - 1.0) / q;
            let (_, psi_dot, theta_dot) = rates(tau)?;
            psi += w * half * psi_dot * jacobian;
            theta += w * half * theta_dot * jacobian;
        }
        Ok((psi, theta))
    };

    let times = timing.times();
    let mut states = vec![None; times.len()];
    // Walk backwards from the halt, accumulating ψ(τ) = −∫₀^τ ψ̇ dτ'.
    let (mut tau_prev, mut psi, mut theta) = (0.0, law.psi_halt, 0.0);
    for (k, &t) in times.iter().enumerate().rev() {
        if t >= 0.0 {
            continue;
        }
        let tau = -t;
        let (dpsi, dtheta) = integrate(tau_prev, tau)?;
        psi -= dpsi;
        theta -= dtheta;
        tau_prev = tau;
        let (phi, psi_dot, rolling_theta_dot) = rates(tau)?;
        let (slipped_theta, theta_dot) = (
            theta + post_flat.beta_dot0 * t,
            rolling_theta_dot + post_flat.beta_dot0,
        );
        let energy = law.a_e * tau.powf(law.n);
        let (beta, beta_dot) = strip_state(psi, phi, slipped_theta, psi_dot, theta_dot, law.beta0);
        states[k] = Some(DiskState {
            t,
            phi,
            psi,
            theta: slipped_theta,
            beta,
            psi_dot,
            theta_dot,
            beta_dot,
            energy,
            centre: [0.0, 0.0],
        });
    }
    let halt = DiskState::fallen_flat(law.psi_halt, 0.0, law.psi_halt + law.beta0);
    let states = times
        .iter()
        .zip(states)
        .map(|(&t, s)| s.unwrap_or_else(|| flat_state(params, &halt, post_flat, t)))
        .collect();
    Ok(Motion {
        params: *params,
        source: MotionSource::PowerLaw,
        true_n: Some(law.n),
        a_e: Some(law.a_e),
        beta0: law.beta0,
        post_flat,
        timing: *timing,
        states,
        nutation: None,
    })
}

/// An oscillation of the nutation angle about stationary rolling (a disk released
/// off its steady motion, as real disks are; thesis §4.6.2 attributes the large β̇
/// oscillations of fig. 3.28 to it):
///
/// ```text
/// φ(t) = φ_stat(t) (1 + a sin χ(t)),   χ(t) = r |ψ(t) − ψ_halt| + χ₀,
/// ```
///
/// so the oscillation's frequency is r times the precession rate |ψ̇| and follows it
/// as it grows towards the halt, and its relative amplitude a stays fixed (φ → 0 at
/// the halt as before). ψ, θ and the energy keep their stationary-rolling values (E
/// is the prescribed power law; eq. 3.8 on the oscillating φ oscillates with it).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Nutation {
    /// Relative amplitude a of φ's oscillation, in [0, 0.5].
    pub amplitude: f64,
    /// Frequency ratio r = ω/|ψ̇| (> 0).
    pub ratio: f64,
    /// Phase χ₀ at the halt \[rad\].
    pub phase: f64,
}

/// Adds `nutation` to a prescribed power-law motion: φ oscillates about its
/// stationary-rolling value before the halt (see [`Nutation`]); β and β̇ follow
/// (eqs. 3.20, 3.21).
pub fn add_nutation(motion: &mut Motion, nutation: Nutation) -> Result<(), RenderError> {
    let Nutation {
        amplitude,
        ratio,
        phase,
    } = nutation;
    if !(amplitude.is_finite() && (0.0..=0.5).contains(&amplitude)) {
        return Err(RenderError::invalid(format!(
            "the nutation amplitude (relative to φ) must lie in [0, 0.5], got {amplitude}"
        )));
    }
    if !(ratio.is_finite() && ratio > 0.0 && ratio <= 10.0) {
        return Err(RenderError::invalid(format!(
            "the nutation frequency ratio ω/|ψ̇| must lie in (0, 10], got {ratio}"
        )));
    }
    if !phase.is_finite() {
        return Err(RenderError::invalid(format!(
            "the nutation phase must be finite, got {phase} rad"
        )));
    }
    if motion.source != MotionSource::PowerLaw {
        return Err(RenderError::invalid(
            "nutation is added to a prescribed power law only (a simulation has its own)",
        ));
    }
    let psi_halt = motion
        .states
        .iter()
        .find(|s| s.t >= 0.0)
        .map_or(0.0, |s| s.psi);
    let beta0 = motion.beta0;
    for s in motion.states.iter_mut().filter(|s| s.t < 0.0) {
        let chi = ratio * (s.psi - psi_halt).abs() + phase;
        s.phi *= 1.0 + amplitude * chi.sin();
        let theta_dot = s.theta_dot;
        (s.beta, s.beta_dot) = strip_state(s.psi, s.phi, s.theta, s.psi_dot, theta_dot, beta0);
    }
    motion.nutation = Some(nutation);
    Ok(())
}

/// β unwrapped as ψ + θ + β0 plus the (small, O(φ²)) wrapped difference to eq. (3.20),
/// and β̇ from eq. (3.21) with φ̇ = 0.
fn strip_state(
    psi: f64,
    phi: f64,
    theta: f64,
    psi_dot: f64,
    theta_dot: f64,
    beta0: f64,
) -> (f64, f64) {
    let naive = psi + theta + beta0;
    let beta = naive + wrap_pi(strip_angle(psi, phi, theta, beta0) - naive);
    let (sf, cf) = phi.sin_cos();
    let cb = (theta + beta0).cos();
    let beta_dot = psi_dot + theta_dot * cf / (1.0 - sf * sf * cb * cb);
    (beta, beta_dot)
}

/// Wraps an angle into (−π, π].
fn wrap_pi(a: f64) -> f64 {
    let w = a.rem_euclid(2.0 * PI);
    if w > PI { w - 2.0 * PI } else { w }
}

impl DiskState {
    /// The disk just fallen flat at the halt (t = 0), with the angles it ended on,
    /// at rest over its rest position.
    fn fallen_flat(psi: f64, theta: f64, beta: f64) -> Self {
        DiskState {
            t: 0.0,
            phi: 0.0,
            psi,
            theta,
            beta,
            psi_dot: 0.0,
            theta_dot: 0.0,
            beta_dot: 0.0,
            energy: 0.0,
            centre: [0.0, 0.0],
        }
    }
}

/// The flat disk at `t` ≥ 0 after the halt state `halt`: φ = 0, the strip (and θ)
/// turning with the post-flat spin.
fn flat_state(params: &DiskParams, halt: &DiskState, spin: PostFlatSpin, t: f64) -> DiskState {
    let (dbeta, beta_dot) = spin.at(params, t);
    DiskState {
        t,
        phi: 0.0,
        psi: halt.psi,
        theta: halt.theta + dbeta,
        beta: halt.beta + dbeta,
        psi_dot: 0.0,
        theta_dot: beta_dot,
        beta_dot,
        energy: 0.0,
        centre: halt.centre,
    }
}

/// Horizontal velocity of the centre of mass in the global frame [m/s]:
/// V_G = V_P − Ω × GP in the intermediate frame (eq. 4.15, ERRATA), rotated by ψ.
fn centre_velocity(params: &DiskParams, s: &Sample) -> [f64; 2] {
    let (r, hh) = (params.radius, params.half_thickness);
    let (sf, cf) = s.phi.sin_cos();
    let omega = [-s.theta_dot * sf, -s.phi_dot, s.psi_dot + s.theta_dot * cf];
    let gp = [-(r * cf - hh * sf), 0.0, -(r * sf + hh * cf)];
    let cross = [
        omega[1] * gp[2] - omega[2] * gp[1],
        omega[2] * gp[0] - omega[0] * gp[2],
    ];
    let v = [s.x_dot - cross[0], s.y_dot - cross[1]];
    let (sp, cp) = s.psi.sin_cos();
    [cp * v[0] - sp * v[1], sp * v[0] + cp * v[1]]
}

/// Cubic Hermite interpolation of a value with its derivative.
pub(super) fn hermite(t0: f64, y0: f64, d0: f64, t1: f64, y1: f64, d1: f64, t: f64) -> f64 {
    let h = t1 - t0;
    if h <= 0.0 {
        return y1;
    }
    let s = (t - t0) / h;
    let (s2, s3) = (s * s, s * s * s);
    (2.0 * s3 - 3.0 * s2 + 1.0) * y0
        + (s3 - 2.0 * s2 + s) * h * d0
        + (-2.0 * s3 + 3.0 * s2) * y1
        + (s3 - s2) * h * d1
}

/// A simulated trajectory at the frames of a clip: the halt is the trajectory's end
/// (fallen flat or on the discontinuity set; a trajectory that ended otherwise, the
/// disk still rolling, is refused), clip time = simulation time, and
/// `after_halt` seconds of flat disk follow. Angles are interpolated by cubic Hermite
/// polynomials with their rates; the centre of mass integrates eq. (4.15) by the
/// trapezoidal rule on the samples and is placed so that it rests at the origin. The
/// post-flat spin starts from the trajectory's final β̇ (eq. 3.21) and stops by eq.
/// (4.113) with friction `mu`.
pub fn trajectory_motion(
    params: &DiskParams,
    trajectory: &Trajectory,
    beta0: f64,
    mu: f64,
    fps: f64,
    after_halt: f64,
    true_n: Option<f64>,
) -> Result<Motion, RenderError> {
    let samples = &trajectory.samples;
    let (Some(first), Some(last)) = (samples.first(), samples.last()) else {
        return Err(RenderError::invalid("the trajectory has no samples"));
    };
    if first.t != 0.0 {
        return Err(RenderError::invalid(format!(
            "the trajectory must start at t = 0, starts at {} s",
            first.t
        )));
    }
    // The clip's halt is the trajectory's end: one that stopped while the disk
    // still rolls would show it jump to flat, and its truth would give a halt and
    // an n the footage does not hold.
    if !matches!(
        trajectory.end_reason,
        EndReason::FallenFlat | EndReason::DiscontinuitySet
    ) {
        return Err(RenderError::invalid(format!(
            "the simulated disk did not halt: the simulation ended ({:?}) at t = {:.3} s \
             with φ = {:.3e} rad still rolling; give a larger η so that it halts within \
             the simulated time",
            trajectory.end_reason, last.t, last.phi
        )));
    }
    let timing = Timing {
        fps,
        halt_time: last.t,
        after_halt,
        jitter: None,
    };
    timing.validate()?;
    // Centre of mass by the trapezoidal rule, then shifted to rest at the origin.
    let mut centre = vec![[0.0, 0.0]; samples.len()];
    for i in 1..samples.len() {
        let dt = samples[i].t - samples[i - 1].t;
        let (va, vb) = (
            centre_velocity(params, &samples[i - 1]),
            centre_velocity(params, &samples[i]),
        );
        centre[i] = [
            centre[i - 1][0] + 0.5 * dt * (va[0] + vb[0]),
            centre[i - 1][1] + 0.5 * dt * (va[1] + vb[1]),
        ];
    }
    let end_centre = centre[samples.len() - 1];
    for c in &mut centre {
        c[0] -= end_centre[0];
        c[1] -= end_centre[1];
    }
    let post_flat = PostFlatSpin {
        beta_dot0: last.beta_dot,
        mu,
    };
    let halt = DiskState::fallen_flat(last.psi, last.theta, last.beta);
    let states = timing
        .times()
        .into_iter()
        .map(|t| {
            if t >= 0.0 {
                return flat_state(params, &halt, post_flat, t);
            }
            let ts = t + timing.halt_time;
            let j = samples
                .partition_point(|s| s.t <= ts)
                .clamp(1, samples.len() - 1);
            let (a, b) = (&samples[j - 1], &samples[j]);
            let w = if b.t > a.t {
                (ts - a.t) / (b.t - a.t)
            } else {
                1.0
            };
            let lerp = |x: f64, y: f64| x + w * (y - x);
            let (ca, cb) = (centre[j - 1], centre[j]);
            DiskState {
                t,
                phi: hermite(a.t, a.phi, a.phi_dot, b.t, b.phi, b.phi_dot, ts).max(0.0),
                psi: hermite(a.t, a.psi, a.psi_dot, b.t, b.psi, b.psi_dot, ts),
                theta: hermite(a.t, a.theta, a.theta_dot, b.t, b.theta, b.theta_dot, ts),
                beta: hermite(a.t, a.beta, a.beta_dot, b.t, b.beta, b.beta_dot, ts),
                psi_dot: lerp(a.psi_dot, b.psi_dot),
                theta_dot: lerp(a.theta_dot, b.theta_dot),
                beta_dot: lerp(a.beta_dot, b.beta_dot),
                energy: lerp(a.energy, b.energy),
                centre: [lerp(ca[0], cb[0]), lerp(ca[1], cb[1])],
            }
        })
        .collect();
    Ok(Motion {
        params: *params,
        source: MotionSource::Simulation,
        true_n,
        a_e: None,
        beta0,
        post_flat,
        timing,
        states,
        nutation: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::stationary_rolling_energy;
    use crate::model::params::Preset;

    fn timing() -> Timing {
        Timing {
            fps: 480.0,
            halt_time: 0.5,
            after_halt: 0.1,
            jitter: None,
        }
    }

    fn spin() -> PostFlatSpin {
        PostFlatSpin {
            beta_dot0: -2.8,
            mu: 0.134,
        }
    }

    #[test]
    fn jittered_capture_times_lie_on_the_tick_clock_within_the_jitter() {
        let jittered = Timing {
            jitter: Some(CaptureJitter {
                fraction: 0.1,
                seed: 3,
            }),
            ..timing()
        };
        let times = jittered.times();
        assert_eq!(times, jittered.times(), "the same seed, the same times");
        assert_eq!(times.len(), timing().frame_count());
        let ticks_per_s = 480.0 * f64::from(TICKS_PER_FRAME);
        let mut moved = 0;
        for (k, t) in times.iter().enumerate() {
            let tick = (t + 0.5) * ticks_per_s;
            assert!((tick - tick.round()).abs() < 1e-6, "frame {k}: {tick}");
            // Within half the jitter's width (0.05 of a frame) of k / fps.
            let offset = tick / f64::from(TICKS_PER_FRAME) - k as f64;
            assert!(offset.abs() <= 0.05 + 1e-9, "frame {k}: {offset}");
            moved += usize::from(offset.abs() > 0.01);
        }
        assert_eq!(times[0], -0.5, "the first frame at clip time 0");
        // Uniform offsets: 80 % of frames lie over 0.01 of a frame off.
        assert!(moved > times.len() * 7 / 10, "{moved} of {}", times.len());
    }

    /// Eq. (3.8) evaluated on the prescribed φ, ψ̇ reproduces E = A_e (t_halt − t)^n,
    /// and ψ̇, θ̇ satisfy stationary rolling (eqs. 3.7 and 4.40).
    #[test]
    fn prescribed_motion_follows_the_power_law_under_stationary_rolling() {
        let params = Preset::EulerDisk.params();
        for n in [0.45, 0.5, 2.0 / 3.0, 1.2] {
            let law = PowerLaw::thesis(n);
            let motion = power_law_motion(&params, &law, &timing(), spin()).expect("motion");
            let before: Vec<_> = motion.states.iter().filter(|s| s.t < 0.0).collect();
            assert_eq!(before.len(), 240, "0.5 s at 480 fps");
            for s in before {
                let e = stationary_rolling_energy(&params, s.phi, s.psi_dot);
                let target = law.a_e * (-s.t).powf(n);
                // Bisection to the last bit of φ; E(φ) is smooth: 1e-12 relative.
                assert!(
                    ((e - target) / target).abs() < 1e-12,
                    "n = {n}, t = {}: E = {e}, A_e τ^n = {target}",
                    s.t
                );
                let (psi_dot, _) = stationary_rolling(&params, s.phi).expect("stationary");
                assert!(
                    (s.psi_dot + psi_dot).abs() < 1e-9 * psi_dot,
                    "ψ̇ of eq. 4.40"
                );
                // Eq. (3.7) with the slip: ψ̇ (R cos φ − H sin φ) + R (θ̇ − β̇₀) = 0
                // (centre of mass at rest).
                let centre_speed = s.psi_dot
                    * (params.radius * s.phi.cos() - params.half_thickness * s.phi.sin())
                    + params.radius * (s.theta_dot - spin().beta_dot0);
                assert!(centre_speed.abs() < 1e-12 * params.radius * s.psi_dot.abs());
            }
        }
    }

    /// ψ is the integral of ψ̇: central differences of ψ on a fine clock match ψ̇,
    /// and ψ is zero at the halt.
    #[test]
    fn precession_angle_integrates_precession_rate() {
        let params = Preset::EulerDisk.params();
        let fine = Timing {
            fps: 20_000.0,
            halt_time: 0.3,
            after_halt: 0.0,
            jitter: None,
        };
        let motion = power_law_motion(&params, &PowerLaw::thesis(0.5), &fine, spin()).expect("m");
        let s = &motion.states;
        assert_eq!(s.last().map(|x| (x.t, x.psi)), Some((0.0, 0.0)));
        for k in (1..s.len() - 200).step_by(97) {
            let rate = (s[k + 1].psi - s[k - 1].psi) / (s[k + 1].t - s[k - 1].t);
            let theta_rate = (s[k + 1].theta - s[k - 1].theta) / (s[k + 1].t - s[k - 1].t);
            // Central difference error h² ψ⃛/6 with h = 50 µs: < 1e-5 relative here.
            assert!(
                ((rate - s[k].psi_dot) / s[k].psi_dot).abs() < 1e-5,
                "k = {k}"
            );
            assert!(((theta_rate - s[k].theta_dot) / s[k].theta_dot).abs() < 1e-5);
        }
    }

    /// The strip carries its spin into the flat: β̇ is continuous at the halt (it
    /// tends to the post-flat β̇₀ as φ → 0), and β is the integral of β̇ across it.
    #[test]
    fn strip_rate_is_continuous_at_the_halt() {
        let params = Preset::EulerDisk.params();
        let fine = Timing {
            fps: 20_000.0,
            halt_time: 0.05,
            after_halt: 0.01,
            jitter: None,
        };
        for n in [0.45, 2.0 / 3.0] {
            let motion =
                power_law_motion(&params, &PowerLaw::thesis(n), &fine, spin()).expect("motion");
            let s = &motion.states;
            let halt = s.iter().position(|x| x.t >= 0.0).expect("halt frame");
            let (before, after) = (&s[halt - 1], &s[halt + 1]);
            let beta_dot0 = spin().beta_dot0;
            // 50 µs either side: the rolling part of β̇ (≈ ψ̇ h φ, eq. 3.22) has nearly
            // vanished before, the Coulomb deceleration has barely begun after.
            assert!(
                (before.beta_dot - beta_dot0).abs() < 0.05 * beta_dot0.abs(),
                "n = {n}: β̇ = {} just before the halt",
                before.beta_dot
            );
            assert!((after.beta_dot - beta_dot0).abs() < 0.01 * beta_dot0.abs());
            // Without the slip β̇ would jump by β̇₀ = 2.8 rad/s at the halt, and the
            // central difference there would miss by half of that.
            for w in s.windows(3) {
                let rate = (w[2].beta - w[0].beta) / (w[2].t - w[0].t);
                assert!(
                    (rate - w[1].beta_dot).abs() < 0.05,
                    "n = {n}, t = {}: Δβ/Δt = {rate}, β̇ = {}",
                    w[1].t,
                    w[1].beta_dot
                );
            }
        }
    }

    /// ψ at the halt turns the whole precession by a constant: φ and the rates are
    /// unchanged, ψ moves by ψ_h at every frame, and the strip, continuous through
    /// the halt, lies at ψ_h + β0 on the flat disk.
    #[test]
    fn psi_at_the_halt_turns_the_precession_and_keeps_the_strip_continuous() {
        let params = Preset::EulerDisk.params();
        let zero = power_law_motion(&params, &PowerLaw::thesis(0.5), &timing(), spin()).expect("m");
        let psi_halt = 1.9;
        let law = PowerLaw {
            psi_halt,
            ..PowerLaw::thesis(0.5)
        };
        let turned = power_law_motion(&params, &law, &timing(), spin()).expect("m");
        for (a, b) in zero.states.iter().zip(&turned.states) {
            assert_eq!(a.phi, b.phi);
            assert_eq!(a.psi_dot, b.psi_dot);
            assert!((b.psi - a.psi - psi_halt).abs() < 1e-9, "t = {}", a.t);
        }
        let last_moving = turned.states.iter().rfind(|s| s.t < 0.0).expect("motion");
        let flat = turned.states.iter().find(|s| s.t >= 0.0).expect("rest");
        assert!((flat.psi - psi_halt).abs() < 1e-12);
        let rest_beta = psi_halt + law.beta0 + spin().beta_dot0 * flat.t;
        assert!(
            (flat.beta - rest_beta).abs() < 1e-3,
            "{} vs {rest_beta}",
            flat.beta
        );
        assert!(
            (last_moving.beta - flat.beta).abs() < 0.05,
            "β {} → {}",
            last_moving.beta,
            flat.beta
        );
    }

    /// After the halt the strip decelerates linearly and stops at t_β (eq. 4.113).
    #[test]
    fn post_flat_spin_stops_at_t_beta() {
        let params = Preset::EulerDisk.params();
        let motion =
            power_law_motion(&params, &PowerLaw::thesis(0.5), &timing(), spin()).expect("m");
        let t_beta = motion.t_beta();
        // Eq. 4.113 with C ≈ mR²/2: R|β̇₀|/(2μg) = 0.0406 s.
        let eq_4_113 = params.radius * 2.8 / (2.0 * 0.134 * params.gravity);
        assert!(
            (t_beta - eq_4_113).abs() < 2e-3 * eq_4_113,
            "{t_beta} vs {eq_4_113}"
        );
        let halt_beta = motion.beta0;
        for s in motion.states.iter().filter(|s| s.t >= 0.0) {
            assert_eq!(s.phi, 0.0);
            if s.t >= t_beta {
                assert_eq!(s.beta_dot, 0.0);
                assert!((s.beta - (halt_beta - 2.8 * t_beta / 2.0)).abs() < 1e-12);
            } else {
                assert!((s.beta_dot - (-2.8 * (1.0 - s.t / t_beta))).abs() < 1e-12);
            }
        }
    }

    /// Issue 73.3: a model that had not halted by the simulation's end was rendered
    /// with the disk rolling to the last frame and then flat, and a truth giving a
    /// halt and n. Such a trajectory is refused.
    #[test]
    fn a_trajectory_that_does_not_halt_is_refused() {
        use crate::model::dissipation::{Dissipation, ModelKind};
        use crate::model::simulate::{SimulationSpec, simulate};
        let params = Preset::EulerDisk.params();
        let mut spec =
            SimulationSpec::thesis_default(params, Dissipation::new(ModelKind::Contour), 1e-12);
        spec.t_end = 0.05;
        let trajectory = simulate(&spec).unwrap();
        assert_eq!(trajectory.end_reason, EndReason::TimeLimit);
        let err = trajectory_motion(&params, &trajectory, 0.3, 0.134, 480.0, 0.02, Some(1.0))
            .unwrap_err()
            .to_string();
        assert!(err.contains("did not halt") && err.contains("η"), "{err}");
    }
}
