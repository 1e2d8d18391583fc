//! Post-falling-flat dynamics of Euler's disk (thesis §4.8).
//!
//! In the thesis's simulations the disk hits the discontinuity set of contour
//! friction and falls flat with a residual spin β̇ = ψ̇ (fig. 4.17a). What follows
//! is split into two phases:
//!
//! 1. **Contactless phase** (§4.8.1, flat base-plates only). The air trapped under
//!    the face is squeezed out; the lubrication force of eq. (4.103) supports the
//!    disk, whose gap Z_b obeys eq. (4.104). The gap never reaches zero in that model,
//!    so the phase ends when Z_b reaches a *contact gap* set by surface roughness, a
//!    number the thesis does not give. [`air_film_closing_time`] integrates eq.
//!    (4.104) with a hand-written classical RK4 ([`rk4_step`]) under a stiffness-aware
//!    step control and locates the crossing; [`air_film_state_at`] gives the gap at a
//!    given time (fig. 4.18). Two exact or asymptotic results check the integrator:
//!    the first integral [`air_film_first_integral`] and the lubrication
//!    (inertia-free) limit [`air_film_closing_time_asymptotic`].
//! 2. **Contact phase** (§4.8.2). Coulomb friction decelerates the spin linearly to
//!    rest: over the whole face on a flat plate ([`flat_plate_stop_time`], eq. 4.111),
//!    along the rim on a concave plate ([`concave_plate_stop_time`], eq. 4.113 with the
//!    ERRATA correction of eq. 4.112).
//!
//! Everything is in SI units. The thesis's inputs and printed results are exposed as
//! `THESIS_*` constants so that a reproduction report can print "thesis vs ours".

use crate::model::params::{DiskParams, Preset};

// ---------------------------------------------------------------------------
// Thesis inputs and printed results (§4.8)
// ---------------------------------------------------------------------------

/// Viscosity of air μ_air = 1.8e-5 kg m⁻¹ s⁻¹ (§4.8.1, below eq. 4.103).
pub const THESIS_AIR_VISCOSITY: f64 = 1.8e-5;

/// Initial gap Z_b(0) = 1.0e-4 m between the bottom face and the plate (§4.8.1:
/// half of the last rim height z_rim = 2.0e-4 m of fig. 3.11; caption of fig. 4.18).
pub const THESIS_INITIAL_GAP: f64 = 1.0e-4;

/// Initial gap velocity Ż_b(0) = φ̇R = −0.18 rad/s × 0.0381 m ≈ −0.007 m/s, as the
/// thesis rounds it (§4.8.1, caption of fig. 4.18).
pub const THESIS_INITIAL_GAP_VELOCITY: f64 = -0.007;

/// Duration of the contactless phase the thesis reads off fig. 4.18: "≈ 0.03 s"
/// (§4.8.2, last paragraph). The thesis gives no contact gap; see
/// [`air_film_state_at`] for the gap our integration has at that time.
pub const THESIS_CONTACTLESS_DURATION: f64 = 0.03;

/// Coefficient of Coulomb friction of Euler's disk on stainless steel, μ = 0.134
/// (Table 3.1; used for eq. 4.111 and, as an estimate, for the concave plate in
/// eq. 4.113).
pub const THESIS_FRICTION_COEFFICIENT: f64 = 0.134;

/// Residual spin when the disk falls flat on the flat stainless-steel plate,
/// β̇(0) = −0.23 rad/s (§4.8.2, average of the experiments of §3.3).
pub const THESIS_FLAT_BETA_DOT0: f64 = -0.23;

/// Stop time printed for the flat plate, eq. (4.111): 0.0050 s (with μ = 0.134,
/// β̇(0) = −0.23 rad/s and the Euler's-disk parameters of eq. 4.42).
pub const THESIS_FLAT_STOP_TIME: f64 = 0.0050;

/// Residual spin on the concave plate printed with eq. (4.113), β̇(0) = −0.19 rad/s
/// (fig. 3.30).
pub const THESIS_CONCAVE_BETA_DOT0: f64 = -0.19;

/// Stop time printed for the concave plate, eq. (4.113): 0.0033 s. ERRATA: eq.
/// (4.113) with β̇(0) = −0.19 rad/s gives 0.00275 s; 0.0033 s corresponds to
/// β̇(0) = −0.23 rad/s (the flat-plate value).
pub const THESIS_CONCAVE_STOP_TIME: f64 = 0.0033;

/// Measured interval between falling flat and stopping on the flat stainless-steel
/// plate, t_β − t_φ = 0.04 s (§4.8.1–4.8.2).
pub const THESIS_FLAT_MEASURED_INTERVAL: f64 = 0.04;

/// Measured interval between falling flat and stopping on the concave plate,
/// t_β − t_φ = 0.0058 s (§4.8.2).
pub const THESIS_CONCAVE_MEASURED_INTERVAL: f64 = 0.0058;

/// Default step fraction κ of the air-film integration: each RK4 step is κ times
/// the shortest local time scale (see [`air_film_closing_time_with`]). κ = 0.05 puts
/// the closing time within about 1e-10 s of the converged value for the thesis's
/// inputs (measured by halving κ; the method is fourth order in κ).
pub const DEFAULT_STEP_FRACTION: f64 = 0.05;

/// Default step budget of the air-film integration. Below a gap of a few µm eq.
/// (4.104) is so stiff that an explicit method needs more steps than this; use
/// [`air_film_closing_time_asymptotic`] there.
pub const DEFAULT_MAX_STEPS: usize = 20_000_000;

// ---------------------------------------------------------------------------
// Classical RK4
// ---------------------------------------------------------------------------

/// One step of the classical fourth-order Runge–Kutta method for y' = f(t, y).
///
/// Global error O(h⁴); see the convergence tests in this module.
pub fn rk4_step<const N: usize, F>(f: &F, t: f64, y: &[f64; N], h: f64) -> [f64; N]
where
    F: Fn(f64, &[f64; N]) -> [f64; N],
{
    let shifted = |k: &[f64; N], scale: f64| -> [f64; N] {
        let mut out = *y;
        for (o, ki) in out.iter_mut().zip(k.iter()) {
            *o += scale * ki;
        }
        out
    };
    let k1 = f(t, y);
    let k2 = f(t + 0.5 * h, &shifted(&k1, 0.5 * h));
    let k3 = f(t + 0.5 * h, &shifted(&k2, 0.5 * h));
    let k4 = f(t + h, &shifted(&k3, h));
    let mut out = *y;
    for i in 0..N {
        out[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    out
}

// ---------------------------------------------------------------------------
// Contactless phase: eq. (4.104)
// ---------------------------------------------------------------------------

/// Inputs of the contactless (air-film) phase, eqs. (4.103)–(4.104), in SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AirFilm {
    /// Disk mass m \[kg\].
    pub mass: f64,
    /// Disk radius R \[m\]; the film covers the whole face.
    pub radius: f64,
    /// Gravitational acceleration g [m/s²].
    pub gravity: f64,
    /// Viscosity of the film μ_air [kg m⁻¹ s⁻¹]. Zero is allowed (free fall).
    pub air_viscosity: f64,
    /// Gap Z_b(0) between the bottom face and the plate at loss of contact \[m\].
    pub initial_gap: f64,
    /// Gap velocity Ż_b(0) [m/s] (negative when closing).
    pub initial_velocity: f64,
}

impl Default for AirFilm {
    /// The thesis's inputs, [`AirFilm::thesis`].
    fn default() -> Self {
        AirFilm::thesis()
    }
}

impl AirFilm {
    /// The thesis's inputs (§4.8.1, fig. 4.18): Euler's disk of eq. (4.42)
    /// (m = 0.443 kg, R = 0.0381 m), μ_air = 1.8e-5 kg m⁻¹ s⁻¹, Z_b(0) = 1.0e-4 m,
    /// Ż_b(0) = −0.007 m/s, g = 9.81 m/s².
    pub fn thesis() -> Self {
        AirFilm::for_disk(&Preset::EulerDisk.params())
    }

    /// The thesis's film inputs (μ_air, Z_b(0), Ż_b(0)) for another disk.
    pub fn for_disk(params: &DiskParams) -> Self {
        AirFilm {
            mass: params.mass,
            radius: params.radius,
            gravity: params.gravity,
            air_viscosity: THESIS_AIR_VISCOSITY,
            initial_gap: THESIS_INITIAL_GAP,
            initial_velocity: THESIS_INITIAL_GAP_VELOCITY,
        }
    }

    /// Checks that every input is finite, m, R, g, Z_b(0) are positive and
    /// μ_air is non-negative.
    pub fn validate(&self) -> Result<(), String> {
        let positive = [
            ("mass", self.mass),
            ("radius", self.radius),
            ("gravity", self.gravity),
            ("initial_gap", self.initial_gap),
        ];
        for (name, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(format!("{name} must be finite and positive, got {value}"));
            }
        }
        if !(self.air_viscosity.is_finite() && self.air_viscosity >= 0.0) {
            return Err(format!(
                "air_viscosity must be finite and non-negative, got {}",
                self.air_viscosity
            ));
        }
        if !self.initial_velocity.is_finite() {
            return Err(format!(
                "initial_velocity must be finite, got {}",
                self.initial_velocity
            ));
        }
        Ok(())
    }

    /// Squeeze-film coefficient k = 3π μ_air R⁴ / 2 [kg m³ s⁻¹], so that the film
    /// force of eq. (4.103) is F = −k Ż_b / Z_b³.
    pub fn squeeze_coefficient(&self) -> f64 {
        1.5 * std::f64::consts::PI * self.air_viscosity * self.radius.powi(4)
    }

    /// Film force of eq. (4.103), F = −(3π μ_air R⁴/2) Ż_b / Z_b³ \[N\].
    pub fn film_force(&self, gap: f64, velocity: f64) -> f64 {
        -self.squeeze_coefficient() * velocity / gap.powi(3)
    }

    /// Relaxation time of the gap velocity, τ = m Z_b³ / k \[s\]: the inverse of the
    /// damping rate in eq. (4.104). It sets the stiffness of the ODE.
    pub fn damping_time(&self, gap: f64) -> f64 {
        self.mass * gap.powi(3) / self.squeeze_coefficient()
    }

    /// Terminal (lubrication-limit) gap velocity at which the film force of eq.
    /// (4.103) balances the weight: Ż = −m g Z_b³ / k [m/s].
    pub fn terminal_velocity(&self, gap: f64) -> f64 {
        -self.gravity * self.damping_time(gap)
    }
}

/// Right-hand side of eq. (4.104) for the state `[Z_b, Ż_b]` (m, m/s):
/// d/dt (Z_b, Ż_b) = (Ż_b, −(3π μ_air R⁴ / 2m) Ż_b / Z_b³ − g).
pub fn air_film_rhs(film: &AirFilm, state: &[f64; 2]) -> [f64; 2] {
    let [gap, velocity] = *state;
    [
        velocity,
        -film.squeeze_coefficient() / film.mass * velocity / gap.powi(3) - film.gravity,
    ]
}

/// Exact first integral of eq. (4.104), zero along every solution:
///
/// I(t, Z, Ż) = m(Ż − Ż₀) − (k/2)(Z⁻² − Z₀⁻²) + m g t,  k = 3π μ_air R⁴/2,
///
/// obtained by integrating eq. (4.104) once in time, since Ż/Z³ = −½ d(Z⁻²)/dt.
/// Units: kg m/s (momentum). Used to check the integrator.
pub fn air_film_first_integral(film: &AirFilm, t: f64, state: &[f64; 2]) -> f64 {
    let [gap, velocity] = *state;
    film.mass * (velocity - film.initial_velocity)
        - 0.5 * film.squeeze_coefficient() * (gap.powi(-2) - film.initial_gap.powi(-2))
        + film.mass * film.gravity * t
}

/// Time for the gap to fall from Z_b(0) to `gap` in the lubrication (inertia-free)
/// limit of eq. (4.104), where the film force balances the weight:
/// t = k (Z⁻² − Z₀⁻²) / (2 m g) \[s\]. Ignores the initial velocity and the
/// acceleration phase.
pub fn air_film_lubrication_time(film: &AirFilm, gap: f64) -> f64 {
    film.squeeze_coefficient() * (gap.powi(-2) - film.initial_gap.powi(-2))
        / (2.0 * film.mass * film.gravity)
}

/// Asymptotic closing time of eq. (4.104) for small gaps \[s\].
///
/// The first integral ([`air_film_first_integral`]) gives, exactly,
/// t = k (Z⁻² − Z₀⁻²)/(2mg) + (Ż₀ − Ż(Z))/g. Once the disk has reached the slow
/// (lubrication) manifold, Ż(Z) is the terminal velocity −m g Z³/k; substituting it
/// leaves an error of about 3 τ(Z) Ż_term² / (g Z) (τ = m Z³/k), e.g. 5e-11 s at
/// Z = 10 µm for the thesis's inputs. Valid when τ(Z) is much shorter than the
/// elapsed time; it is the practical answer for gaps of a few µm and below, where
/// the explicit integration of [`air_film_closing_time`] becomes too expensive.
pub fn air_film_closing_time_asymptotic(film: &AirFilm, gap: f64) -> f64 {
    air_film_lubrication_time(film, gap)
        + (film.initial_velocity - film.terminal_velocity(gap)) / film.gravity
}

/// Result of [`air_film_closing_time`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AirFilmClosing {
    /// Time at which the gap reaches the contact gap \[s\].
    pub time: f64,
    /// Gap velocity Ż_b at that time [m/s].
    pub velocity: f64,
    /// Number of accepted RK4 steps.
    pub steps: usize,
}

/// Step control of the air-film integration: κ times the shortest of the damping
/// time m Z³/k, the closing time Z/|Ż| and the free-fall time √(2Z/g).
fn air_film_step(film: &AirFilm, state: &[f64; 2], step_fraction: f64) -> f64 {
    let [gap, velocity] = *state;
    let damping = film.damping_time(gap);
    let closing = if velocity != 0.0 {
        gap / velocity.abs()
    } else {
        f64::INFINITY
    };
    let fall = (2.0 * gap / film.gravity).sqrt();
    step_fraction * damping.min(closing).min(fall)
}

fn check_step_fraction(step_fraction: f64) -> Result<(), String> {
    if step_fraction.is_finite() && step_fraction > 0.0 && step_fraction <= 0.5 {
        Ok(())
    } else {
        Err(format!(
            "step_fraction must lie in (0, 0.5] for RK4 stability, got {step_fraction}"
        ))
    }
}

/// Time for the air-film gap of eq. (4.104) to close from Z_b(0) to `contact_gap`
/// (the height at which asperities touch), with the default step fraction
/// [`DEFAULT_STEP_FRACTION`] and budget [`DEFAULT_MAX_STEPS`].
///
/// `contact_gap` must lie in (0, Z_b(0)). The thesis gives no value for it; its
/// "≈ 0.03 s" contactless phase ([`THESIS_CONTACTLESS_DURATION`]) corresponds, for
/// the thesis's inputs, to a contact gap of about 25 µm.
pub fn air_film_closing_time(film: &AirFilm, contact_gap: f64) -> Result<AirFilmClosing, String> {
    air_film_closing_time_with(film, contact_gap, DEFAULT_STEP_FRACTION, DEFAULT_MAX_STEPS)
}

/// [`air_film_closing_time`] with explicit step control.
///
/// State `[Z_b, Ż_b]` in m and m/s, time in s, classical RK4 ([`rk4_step`]). Each
/// step is `step_fraction` (κ ∈ (0, 0.5]) times the shortest local time scale:
/// the damping time m Z³/k (the stiffness of eq. 4.104, which keeps RK4 inside its
/// stability region), Z/|Ż| and √(2Z/g). As the steps are a smooth function of the
/// state, the global error is O(κ⁴). The step that crosses `contact_gap` is
/// shortened by bisection on the RK4 step map so that the crossing is located to
/// rounding error. Fails if more than `max_steps` steps are needed (gaps of a few µm
/// or less: use [`air_film_closing_time_asymptotic`]).
pub fn air_film_closing_time_with(
    film: &AirFilm,
    contact_gap: f64,
    step_fraction: f64,
    max_steps: usize,
) -> Result<AirFilmClosing, String> {
    film.validate()?;
    check_step_fraction(step_fraction)?;
    if !(contact_gap.is_finite() && contact_gap > 0.0 && contact_gap < film.initial_gap) {
        return Err(format!(
            "contact_gap must lie in (0, Z_b(0) = {} m), got {contact_gap}",
            film.initial_gap
        ));
    }
    let rhs = |_t: f64, y: &[f64; 2]| air_film_rhs(film, y);
    let mut t = 0.0;
    let mut y = [film.initial_gap, film.initial_velocity];
    for steps in 1..=max_steps {
        let h = air_film_step(film, &y, step_fraction);
        if !(h.is_finite() && h > 0.0) {
            return Err(format!(
                "air-film step size broke down at t = {t} s, state {y:?}"
            ));
        }
        let next = rk4_step(&rhs, t, &y, h);
        if !(next[0].is_finite() && next[1].is_finite()) {
            return Err(format!("air-film integration diverged at t = {t} s"));
        }
        if next[0] <= contact_gap {
            // Bisection on the step length: the RK4 map is smooth in h and the gap
            // is above `contact_gap` at h = 0 and at or below it at h.
            let (mut lo, mut hi) = (0.0_f64, h);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                if rk4_step(&rhs, t, &y, mid)[0] > contact_gap {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let hit = rk4_step(&rhs, t, &y, hi);
            return Ok(AirFilmClosing {
                time: t + hi,
                velocity: hit[1],
                steps,
            });
        }
        t += h;
        y = next;
    }
    Err(format!(
        "air-film gap did not reach {contact_gap} m within {max_steps} RK4 steps \
         (t = {t} s, gap = {} m); eq. (4.104) is too stiff there for an explicit \
         method, use air_film_closing_time_asymptotic",
        y[0]
    ))
}

/// State `[Z_b, Ż_b]` (m, m/s) of eq. (4.104) at time `t` ≥ 0 (fig. 4.18), with
/// the step control of [`air_film_closing_time_with`] and the last step shortened
/// to land on `t`.
pub fn air_film_state_at(film: &AirFilm, t: f64, step_fraction: f64) -> Result<[f64; 2], String> {
    film.validate()?;
    check_step_fraction(step_fraction)?;
    if !(t.is_finite() && t >= 0.0) {
        return Err(format!("t must be finite and non-negative, got {t}"));
    }
    let rhs = |_t: f64, y: &[f64; 2]| air_film_rhs(film, y);
    let mut now = 0.0;
    let mut y = [film.initial_gap, film.initial_velocity];
    let mut steps = 0_usize;
    while now < t {
        if steps >= DEFAULT_MAX_STEPS {
            return Err(format!(
                "air-film integration to t = {t} s needs more than {DEFAULT_MAX_STEPS} steps"
            ));
        }
        let mut h = air_film_step(film, &y, step_fraction);
        if !(h.is_finite() && h > 0.0) {
            return Err(format!("air-film step size broke down at t = {now} s"));
        }
        let last = now + h >= t;
        if last {
            h = t - now;
        }
        y = rk4_step(&rhs, now, &y, h);
        if !(y[0].is_finite() && y[1].is_finite() && y[0] > 0.0) {
            return Err(format!("air-film integration diverged at t = {now} s"));
        }
        now = if last { t } else { now + h };
        steps += 1;
    }
    Ok(y)
}

// ---------------------------------------------------------------------------
// Contact phase: eqs. (4.105)–(4.113)
// ---------------------------------------------------------------------------

fn check_contact_inputs(params: &DiskParams, mu: f64, beta_dot0: f64) -> Result<(), String> {
    params.validate()?;
    if !(mu.is_finite() && mu > 0.0) {
        return Err(format!(
            "friction coefficient must be finite and positive, got {mu}"
        ));
    }
    if !beta_dot0.is_finite() {
        return Err(format!("beta_dot0 must be finite, got {beta_dot0}"));
    }
    Ok(())
}

/// Friction torque about the vertical when the whole face slips on a flat plate
/// under uniform pressure m g/(πR²) (eqs. 4.105–4.108):
/// T_z = −(2/3) sign(β̇) μ m g R [N m]. Zero when β̇ = 0.
pub fn flat_plate_friction_torque(params: &DiskParams, mu: f64, beta_dot: f64) -> f64 {
    -2.0 / 3.0 * signum0(beta_dot) * mu * params.mass * params.gravity * params.radius
}

/// Friction torque when only the rim touches a concave plate, eq. (4.112) as
/// corrected in ERRATA: T_z = −μ m g R sign(β̇) [N m] (printed with |β̇(0)|, which
/// is dimensionally wrong). Zero when β̇ = 0.
pub fn rim_friction_torque(params: &DiskParams, mu: f64, beta_dot: f64) -> f64 {
    -signum0(beta_dot) * mu * params.mass * params.gravity * params.radius
}

fn signum0(x: f64) -> f64 {
    if x == 0.0 { 0.0 } else { x.signum() }
}

/// Spin β̇(t) [rad/s] of the disk slipping flat on a flat plate, eq. (4.110):
/// β̇ = β̇(0) − (2 sign(β̇(0)) μ m g R / 3C) t until it reaches zero at
/// [`flat_plate_stop_time`], and zero afterwards (the torque cannot reverse the spin).
pub fn flat_plate_spin(
    params: &DiskParams,
    mu: f64,
    beta_dot0: f64,
    t: f64,
) -> Result<f64, String> {
    let stop = flat_plate_stop_time(params, mu, beta_dot0)?;
    if !(t.is_finite() && t >= 0.0) {
        return Err(format!("t must be finite and non-negative, got {t}"));
    }
    if t >= stop {
        return Ok(0.0);
    }
    Ok(beta_dot0 + flat_plate_friction_torque(params, mu, beta_dot0) / params.inertia_c * t)
}

/// Stop time of the contact phase on a flat plate, eq. (4.111):
/// t_stop = 3 C |β̇(0)| / (2 μ m g R) \[s\], with C = `params.inertia_c`.
///
/// Thesis: μ = 0.134 ([`THESIS_FRICTION_COEFFICIENT`]), β̇(0) = −0.23 rad/s
/// ([`THESIS_FLAT_BETA_DOT0`]) and Euler's disk (eq. 4.42) give 0.0050 s
/// ([`THESIS_FLAT_STOP_TIME`]).
pub fn flat_plate_stop_time(params: &DiskParams, mu: f64, beta_dot0: f64) -> Result<f64, String> {
    check_contact_inputs(params, mu, beta_dot0)?;
    Ok(3.0 * params.inertia_c * beta_dot0.abs()
        / (2.0 * mu * params.mass * params.gravity * params.radius))
}

/// Stop time of the contact phase on a concave plate, where only the rim touches:
/// C β̈ = −μ m g R sign(β̇(0)) (eq. 4.112 as corrected in ERRATA) gives
/// t_stop = C |β̇(0)| / (μ m g R) \[s\], with C = `params.inertia_c`. For
/// C = mR²/2, as the thesis assumes, this is eq. (4.113): t_stop = R|β̇(0)|/(2μg).
///
/// Thesis: μ = 0.134 and β̇(0) = −0.19 rad/s ([`THESIS_CONCAVE_BETA_DOT0`]) are
/// printed with 0.0033 s ([`THESIS_CONCAVE_STOP_TIME`]); eq. (4.113) gives
/// 0.00275 s for those inputs, and 0.0033 s for β̇(0) = −0.23 rad/s (ERRATA).
pub fn concave_plate_stop_time(
    params: &DiskParams,
    mu: f64,
    beta_dot0: f64,
) -> Result<f64, String> {
    check_contact_inputs(params, mu, beta_dot0)?;
    Ok(params.inertia_c * beta_dot0.abs() / (mu * params.mass * params.gravity * params.radius))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn euler() -> DiskParams {
        Preset::EulerDisk.params()
    }

    /// Fixed-step RK4 integration of eq. (4.104) from t = 0 to `t_end` in `n` steps.
    fn fixed_step(film: &AirFilm, t_end: f64, n: usize) -> [f64; 2] {
        let rhs = |_t: f64, y: &[f64; 2]| air_film_rhs(film, y);
        let h = t_end / n as f64;
        let mut y = [film.initial_gap, film.initial_velocity];
        for i in 0..n {
            y = rk4_step(&rhs, i as f64 * h, &y, h);
        }
        y
    }

    #[test]
    fn thesis_film_inputs() {
        let film = AirFilm::thesis();
        assert_eq!(film.mass, 0.443);
        assert_eq!(film.radius, 0.0381);
        assert_eq!(film.air_viscosity, 1.8e-5);
        assert_eq!(film.initial_gap, 1.0e-4);
        // §4.8.1: Ż_b(0) = φ̇ R with φ̇ = −0.18 rad/s, "−0.007 m/s".
        assert!((-0.18 * film.radius - film.initial_velocity).abs() < 5e-4);
        // k = 3π μ R⁴ / 2.
        let k = film.squeeze_coefficient();
        assert!((k - 1.787366e-10).abs() < 1e-15, "k = {k}");
        assert!(film.validate().is_ok());
        assert_eq!(AirFilm::default(), film);
    }

    /// RK4 is fourth order on a linear test problem (exact solution known).
    #[test]
    fn rk4_is_fourth_order_on_exponential_decay() {
        let f = |_t: f64, y: &[f64; 1]| [-2.0 * y[0]];
        let err = |n: usize| {
            let h = 1.0 / n as f64;
            let mut y = [1.0];
            for i in 0..n {
                y = rk4_step(&f, i as f64 * h, &y, h);
            }
            (y[0] - (-2.0_f64).exp()).abs()
        };
        let (e1, e2) = (err(20), err(40));
        let order = (e1 / e2).log2();
        assert!((order - 4.0).abs() < 0.1, "order = {order}");
    }

    /// RK4 is fourth order on eq. (4.104) itself: Richardson ratios of fixed-step
    /// solutions at h, h/2, h/4 approach 2⁴ = 16. Over 5 ms the damping time stays
    /// above 3.7e-4 s, so h ≤ 2e-5 s is well inside the asymptotic regime.
    #[test]
    fn rk4_is_fourth_order_on_air_film_ode() {
        let film = AirFilm::thesis();
        let t_end = 0.005;
        let sols: Vec<[f64; 2]> = [250, 500, 1000, 2000]
            .iter()
            .map(|&n| fixed_step(&film, t_end, n))
            .collect();
        for comp in 0..2 {
            for w in sols.windows(3) {
                let ratio = (w[0][comp] - w[1][comp]) / (w[1][comp] - w[2][comp]);
                assert!(
                    (ratio - 16.0).abs() < 1.5,
                    "component {comp}: ratio {ratio}"
                );
            }
        }
    }

    /// The κ-controlled integration converges at fourth order in κ: the closing
    /// time to 25 µm changes 16× less each time κ halves (ratios 17.5 and 16.6 at
    /// κ = 0.1, 0.05, 0.025, 0.0125; ±2 allows the pre-asymptotic excess).
    #[test]
    fn closing_time_converges_at_fourth_order_in_step_fraction() {
        let film = AirFilm::thesis();
        let t = |kappa: f64| {
            air_film_closing_time_with(&film, 25e-6, kappa, DEFAULT_MAX_STEPS)
                .expect("closing")
                .time
        };
        let times = [t(0.1), t(0.05), t(0.025), t(0.0125)];
        for w in times.windows(3) {
            let ratio = (w[0] - w[1]) / (w[1] - w[2]);
            assert!((ratio - 16.0).abs() < 2.0, "ratio {ratio}");
        }
        // With the default κ the closing time is converged to ~1e-10 s.
        let t_default = t(DEFAULT_STEP_FRACTION);
        let t_fine = t(0.0125);
        assert!((t_default - t_fine).abs() < 1e-9, "{t_default} vs {t_fine}");
    }

    /// The exact first integral of eq. (4.104) is preserved by the integration.
    /// Its defect divided by m g is the implied time error; bound 1e-9 s (we see
    /// 1.3e-10 s with the default κ, set in the initial transient).
    #[test]
    fn first_integral_is_preserved() {
        let film = AirFilm::thesis();
        let scale = film.mass * film.gravity * 1e-9;
        for gap in [5e-5, 2.5e-5, 1e-5] {
            let c = air_film_closing_time(&film, gap).expect("closing");
            let i = air_film_first_integral(&film, c.time, &[gap, c.velocity]);
            assert!(i.abs() < scale, "gap {gap}: I = {i}");
        }
        let y = air_film_state_at(&film, 0.03, DEFAULT_STEP_FRACTION).expect("state");
        assert!(air_film_first_integral(&film, 0.03, &y).abs() < scale);
    }

    /// Zero-damping limit μ_air = 0: free fall, Z = Z₀ + Ż₀t − g t²/2, reached at
    /// t = (Ż₀ + √(Ż₀² + 2g(Z₀ − Z_c)))/g. RK4 integrates the quadratic exactly, so
    /// only rounding and the bisection remain.
    #[test]
    fn zero_viscosity_is_free_fall() {
        let film = AirFilm {
            air_viscosity: 0.0,
            ..AirFilm::thesis()
        };
        let zc = 2e-5;
        let (v0, g) = (film.initial_velocity, film.gravity);
        let exact = (v0 + (v0 * v0 + 2.0 * g * (film.initial_gap - zc)).sqrt()) / g;
        let c = air_film_closing_time(&film, zc).expect("closing");
        assert!(
            (c.time - exact).abs() < 1e-12 * exact,
            "{} vs {exact}",
            c.time
        );
        assert!((c.velocity - (v0 - g * exact)).abs() < 1e-12);
    }

    /// Lubrication (inertia-free) limit: for small gaps the integration agrees with
    /// the asymptotic closing time. The neglected term is ≈ 3τŻ_term²/(gZ) =
    /// 5e-11 s at 10 µm, the integrator error ~1e-10 s; tolerance 1e-9 s.
    #[test]
    fn small_gap_matches_lubrication_limit() {
        let film = AirFilm::thesis();
        let gap = 1e-5;
        let c = air_film_closing_time(&film, gap).expect("closing");
        let asym = air_film_closing_time_asymptotic(&film, gap);
        assert!((c.time - asym).abs() < 1e-9, "{} vs {asym}", c.time);
        assert!((c.time - 0.202874028).abs() < 1e-8, "t = {}", c.time);
        // The gap velocity has relaxed to the terminal velocity.
        let vt = film.terminal_velocity(gap);
        assert!((c.velocity - vt).abs() < 1e-3 * vt.abs());
        // The pure lubrication time misses the initial-velocity/acceleration
        // correction (Ż₀ − Ż)/g ≈ −0.7 ms.
        let lub = air_film_lubrication_time(&film, gap);
        assert!(
            (lub - c.time - 7.11e-4).abs() < 1e-5,
            "lub - t = {}",
            lub - c.time
        );
    }

    /// Fig. 4.18: "the separation decreases rapidly until around t = 0.01 s, before
    /// slowing", and the contactless phase lasts "≈ 0.03 s". The thesis gives no
    /// contact gap; ours are regression values of this model: 40.4 µm at 0.01 s,
    /// 25.1 µm at 0.03 s (the gap whose closing time is the thesis's 0.03 s).
    #[test]
    fn fig_4_18_time_scale() {
        let film = AirFilm::thesis();
        let at = |t: f64| air_film_state_at(&film, t, DEFAULT_STEP_FRACTION).expect("state");
        let y01 = at(0.01);
        let y03 = at(THESIS_CONTACTLESS_DURATION);
        assert!((y01[0] - 40.39e-6).abs() < 0.01e-6, "Z(0.01) = {}", y01[0]);
        assert!((y03[0] - 25.07e-6).abs() < 0.01e-6, "Z(0.03) = {}", y03[0]);
        // Rapid then slow: the speed peaks before 0.01 s and has fallen below half
        // of its peak by then.
        let peak = (1..100)
            .map(|i| at(i as f64 * 1e-4)[1].abs())
            .fold(0.0_f64, f64::max);
        assert!(peak > film.initial_velocity.abs());
        assert!(
            y01[1].abs() < 0.5 * peak,
            "|Ż(0.01)| = {}, peak {peak}",
            y01[1]
        );
        // Closing to the gap found at 0.03 s takes 0.03 s (consistency of the two
        // entry points).
        let c = air_film_closing_time(&film, y03[0]).expect("closing");
        assert!((c.time - 0.03).abs() < 1e-9, "t = {}", c.time);
    }

    #[test]
    fn air_film_rejects_bad_inputs() {
        let film = AirFilm::thesis();
        assert!(air_film_closing_time(&film, 0.0).is_err());
        assert!(air_film_closing_time(&film, film.initial_gap).is_err());
        assert!(air_film_closing_time(&film, f64::NAN).is_err());
        assert!(air_film_closing_time_with(&film, 2e-5, 0.0, 10).is_err());
        assert!(air_film_closing_time_with(&film, 2e-5, 0.9, 10).is_err());
        // Too small a budget is an error, not a wrong answer.
        assert!(air_film_closing_time_with(&film, 2e-5, 0.05, 10).is_err());
        let bad = AirFilm {
            air_viscosity: -1.0,
            ..film
        };
        assert!(air_film_closing_time(&bad, 2e-5).is_err());
        let bad = AirFilm { mass: 0.0, ..film };
        assert!(bad.validate().is_err());
        assert!(air_film_state_at(&film, -1.0, 0.05).is_err());
    }

    /// Eq. (4.111): thesis 0.0050 s (μ = 0.134, β̇(0) = −0.23 rad/s, eq. 4.42).
    /// Ours 0.005007 s with the thesis's C = 3.22e-4 kg m²; tolerance ±5e-5 s, half
    /// a unit in the printed last digit.
    #[test]
    fn flat_plate_stop_time_matches_eq_4_111() {
        let t = flat_plate_stop_time(&euler(), THESIS_FRICTION_COEFFICIENT, THESIS_FLAT_BETA_DOT0)
            .expect("stop time");
        assert!((t - THESIS_FLAT_STOP_TIME).abs() < 5e-5, "t = {t}");
        assert!((t - 0.0050070).abs() < 1e-6, "t = {t}");
        // With C = mR²/2 it is 3R|β̇₀|/(4μg).
        let p = DiskParams::solid_disk_thesis(0.443, 0.0381, 0.00635);
        let t2 = flat_plate_stop_time(&p, 0.134, -0.23).expect("stop time");
        assert!((t2 - 3.0 * 0.0381 * 0.23 / (4.0 * 0.134 * 9.81)).abs() < 1e-15);
    }

    /// Eq. (4.110): linear deceleration that reaches zero exactly at t_stop and
    /// never reverses.
    #[test]
    fn flat_plate_spin_decelerates_linearly() {
        let p = euler();
        let stop = flat_plate_stop_time(&p, 0.134, -0.23).expect("stop time");
        let at = |t: f64| flat_plate_spin(&p, 0.134, -0.23, t).expect("spin");
        assert_eq!(at(0.0), -0.23);
        assert!((at(0.5 * stop) + 0.115).abs() < 1e-12);
        assert!(at(stop * (1.0 - 1e-12)).abs() < 1e-12);
        assert_eq!(at(2.0 * stop), 0.0);
        // Torque of eq. (4.108) opposes the spin.
        assert!(flat_plate_friction_torque(&p, 0.134, -0.23) > 0.0);
        assert_eq!(flat_plate_friction_torque(&p, 0.134, 0.0), 0.0);
    }

    /// Eq. (4.113) with the ERRATA on eq. (4.112). With the printed β̇(0) = −0.19
    /// rad/s it gives R|β̇₀|/(2μg) = 0.0027534 s (ERRATA: 0.00275 s), not the
    /// printed 0.0033 s; 0.0033 s is what β̇(0) = −0.23 rad/s gives. The preset's
    /// C = 3.22e-4 kg m² exceeds mR²/2 by 0.15 %, so ours is 0.0027574 s.
    /// Tolerances: ±5e-5 s against 2-digit printed values, 1e-12 relative against
    /// the formula.
    #[test]
    fn concave_plate_stop_time_matches_eq_4_113_with_errata() {
        let p = euler();
        let mu = THESIS_FRICTION_COEFFICIENT;
        let t19 = concave_plate_stop_time(&p, mu, THESIS_CONCAVE_BETA_DOT0).expect("stop");
        let eq_4_113 = 0.0381 * 0.19 / (2.0 * mu * 9.81);
        assert!((eq_4_113 - 0.0027534).abs() < 1e-7, "eq. 4.113: {eq_4_113}");
        let c_ratio = p.inertia_c / (0.5 * p.mass * p.radius * p.radius);
        assert!(
            (t19 - eq_4_113 * c_ratio).abs() < 1e-12 * t19,
            "t(-0.19) = {t19}"
        );
        assert!((t19 - 0.0027574).abs() < 1e-7, "t(-0.19) = {t19}");
        assert!(
            (t19 - THESIS_CONCAVE_STOP_TIME).abs() > 5e-4,
            "printed value reproduced?"
        );
        let t23 = concave_plate_stop_time(&p, mu, -0.23).expect("stop");
        assert!(
            (t23 - THESIS_CONCAVE_STOP_TIME).abs() < 5e-5,
            "t(-0.23) = {t23}"
        );
        // For C = mR²/2 the general form is exactly eq. (4.113): R|β̇₀|/(2μg).
        let disk = DiskParams::solid_disk_thesis(0.443, 0.0381, 0.00635);
        let t = concave_plate_stop_time(&disk, mu, -0.19).expect("stop");
        let eq_4_113 = 0.0381 * 0.19 / (2.0 * mu * 9.81);
        assert!((t - eq_4_113).abs() < 1e-15, "{t} vs {eq_4_113}");
        // The rim torque (corrected eq. 4.112) is 3/2 of the face torque (4.108).
        let ratio = rim_friction_torque(&p, mu, -0.19) / flat_plate_friction_torque(&p, mu, -0.19);
        assert!((ratio - 1.5).abs() < 1e-15);
        // It depends on the sign of β̇ only, not on its size (the ERRATA's point).
        assert_eq!(
            rim_friction_torque(&p, mu, -0.19),
            rim_friction_torque(&p, mu, -5.0)
        );
    }

    /// §4.8.2: contact (0.005 s) plus contactless (≈ 0.03 s) phases are "consistent
    /// with" the measured 0.04 s; the contact phase alone is far too short.
    #[test]
    fn flat_plate_phases_versus_measured_interval() {
        let contact = flat_plate_stop_time(&euler(), 0.134, -0.23).expect("stop");
        assert!(contact < 0.2 * THESIS_FLAT_MEASURED_INTERVAL);
        let total = contact + THESIS_CONTACTLESS_DURATION;
        assert!(
            (total - THESIS_FLAT_MEASURED_INTERVAL).abs() < 0.25 * THESIS_FLAT_MEASURED_INTERVAL
        );
        // Concave: the contact phase alone is of the order of the measured 0.0058 s.
        let concave = concave_plate_stop_time(&euler(), 0.134, -0.19).expect("stop");
        assert!(concave < THESIS_CONCAVE_MEASURED_INTERVAL);
    }

    #[test]
    fn contact_phase_rejects_bad_inputs() {
        let p = euler();
        assert!(flat_plate_stop_time(&p, 0.0, -0.23).is_err());
        assert!(flat_plate_stop_time(&p, f64::NAN, -0.23).is_err());
        assert!(concave_plate_stop_time(&p, 0.134, f64::INFINITY).is_err());
        let bad = DiskParams { mass: -1.0, ..p };
        assert!(concave_plate_stop_time(&bad, 0.134, -0.19).is_err());
        assert!(flat_plate_spin(&p, 0.134, -0.23, -1.0).is_err());
    }
}
