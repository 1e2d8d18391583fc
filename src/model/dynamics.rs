//! Equations of motion of the disk (thesis §4.2, eqs. 4.2–4.36, Appendix C), in the
//! scaled units of eq. (4.21): lengths in R, masses in m, time in √(R/g).
//!
//! Rather than transcribing the printed closed forms (eqs. 4.25, 4.32 and C.1–C.7,
//! which carry conversion typos, see ERRATA), the accelerations are obtained at each
//! state by solving the six Newton–Euler equations (4.2a, 4.2b) together with the
//! contact kinematics, which are linear in the unknowns
//! `(ψ̈, φ̈, θ̈, λ₁, λ₂, n)`:
//!
//! * rolling (eq. 4.6, V_P = 0): λ = the friction force (f_x, f_y) in the intermediate
//!   frame, and the slip velocity stays zero;
//! * slipping (eqs. 4.11, 4.28–4.29): λ = (ẍ, ÿ), the rate of change of the slip
//!   velocity's intermediate-frame components, with f = −μ n v̂.
//!
//! The residual of the six equations is written once, as vector physics, and the
//! linear system is assembled from it by evaluating it at the unit vectors. The
//! printed forms corrected by ERRATA (C.1–C.3) are checked against this solve in the
//! tests, and energy is conserved to round-off when μ = η = 0.
//!
//! Frames (eq. 4.1): G (global) → I (rotated by ψ about z) → B (rotated by φ; the
//! body frame of the symmetric disk). In I the contact point is at
//! GP = (−(cos φ − h sin φ), 0, −(sin φ + h cos φ)), and the disk's angular velocity is
//! Ω = (−θ̇ sin φ, −φ̇, ψ̇ + θ̇ cos φ).

use nalgebra::{Matrix3, Matrix6, SMatrix, SVector, Vector2, Vector3, Vector6};

use super::closed_form::stationary_precession_squared;
use super::dissipation::{Dissipation, Rates};
use super::rosenbrock::Lu;

/// Scaled state `(ψ, ψ̇, φ, φ̇, θ, θ̇, x, ẋ, y, ẏ)` of eq. (4.43); (ẋ, ẏ) is the slip
/// velocity of the contact point in the intermediate frame (eq. 4.28).
pub type StateVector = SVector<f64, 10>;

/// Index of ψ in [`StateVector`].
pub const PSI: usize = 0;
/// Index of ψ̇.
pub const PSI_DOT: usize = 1;
/// Index of φ.
pub const PHI: usize = 2;
/// Index of φ̇.
pub const PHI_DOT: usize = 3;
/// Index of θ.
pub const THETA: usize = 4;
/// Index of θ̇.
pub const THETA_DOT: usize = 5;
/// Index of x (integral of the slip velocity ẋ).
pub const X: usize = 6;
/// Index of ẋ.
pub const X_DOT: usize = 7;
/// Index of y (integral of ẏ).
pub const Y: usize = 8;
/// Index of ẏ.
pub const Y_DOT: usize = 9;

/// Contact mode of the disk (§4.2.1). The default is rolling, the thesis's initial
/// state (eq. 4.43); it gives a [`Sample`](super::simulate::Sample) its default,
/// whose field names head an empty CSV table.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Rolling without slip: the contact point is at rest (eq. 4.6).
    #[default]
    Rolling,
    /// Slipping: Coulomb friction −μN V̂_P opposes the slip (eq. 4.11).
    Slipping,
}

/// The scaled dynamical system: disk constants, Coulomb μ and the dissipative moment.
#[derive(Debug, Clone, Copy)]
pub struct ScaledDisk {
    /// h = H/R.
    pub h: f64,
    /// a = A/(mR²).
    pub a: f64,
    /// c = C/(mR²).
    pub c: f64,
    /// Coefficient of Coulomb friction μ.
    pub mu: f64,
    /// Coefficient of rolling friction η (eq. 4.5).
    pub eta: f64,
    /// Shape of the dissipative moment q (eq. 4.5).
    pub dissipation: Dissipation,
    /// Branch of a discontinuous moment: `Some(±1)` evaluates q with the sign of the
    /// discontinuity function fixed ([`Dissipation::q_body_on_side`]), `None` with its
    /// sign at each state ([`Dissipation::q_body`]).
    pub branch: Option<f64>,
}

/// Accelerations and contact forces at one state, scaled (forces in mg).
#[derive(Debug, Clone, Copy)]
pub struct Accelerations {
    /// ψ̈.
    pub psi_ddot: f64,
    /// φ̈.
    pub phi_ddot: f64,
    /// θ̈.
    pub theta_ddot: f64,
    /// (ẍ, ÿ): rate of the slip velocity's I-frame components (zero when rolling).
    pub slip_accel: Vector2<f64>,
    /// Friction force in the intermediate frame, (f_x^I, f_y^I) (eq. 4.34).
    pub friction: Vector2<f64>,
    /// Normal force n = N/(mg) (eq. 4.23).
    pub normal: f64,
}

impl Accelerations {
    /// The friction ratio |F|/N (eq. 4.33).
    pub fn friction_ratio(&self) -> f64 {
        self.friction.norm() / self.normal
    }
}

/// Position of the contact point relative to G in the intermediate frame, and its
/// rate of change at fixed frame: GP = (−(cos φ − h sin φ), 0, −(sin φ + h cos φ)).
fn contact_arm(h: f64, phi: f64, phi_dot: f64) -> (Vector3<f64>, Vector3<f64>) {
    let (s, c) = phi.sin_cos();
    let cbar = c - h * s;
    let sbar = s + h * c;
    (
        Vector3::new(-cbar, 0.0, -sbar),
        Vector3::new(sbar * phi_dot, 0.0, -cbar * phi_dot),
    )
}

/// Rotation from the intermediate to the body frame, R_IB of eq. (4.1): v^B = R_IB v^I.
fn body_from_intermediate(phi: f64) -> Matrix3<f64> {
    let (s, c) = phi.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

/// The state-dependent parts of the Newton–Euler residual at one state (see
/// [`ScaledDisk::residual_terms`]).
struct ResidualTerms {
    mode: Mode,
    mu: f64,
    inertia: Vector3<f64>,
    h: f64,
    s: f64,
    c: f64,
    psi_dot: f64,
    phi_dot: f64,
    theta_dot: f64,
    slip: Vector3<f64>,
    gp: Vector3<f64>,
    gp_rate: Vector3<f64>,
    /// η q^B (eq. 4.5): the dissipative moment is −η n q^B.
    eta_q: Vector3<f64>,
    body_from_intermediate: Matrix3<f64>,
}

impl ResidualTerms {
    /// Residual of Newton–Euler (eqs. 4.2a in I, 4.2b in B) for the unknowns
    /// `u = (ψ̈, φ̈, θ̈, λ₁, λ₂, n)`; affine in `u`.
    fn residual(&self, u: &Vector6<f64>) -> Vector6<f64> {
        let (s, c) = (self.s, self.c);
        let (psi_dot, phi_dot, theta_dot) = (self.psi_dot, self.phi_dot, self.theta_dot);
        let (psi_ddot, phi_ddot, theta_ddot) = (u[0], u[1], u[2]);
        let normal = u[5];
        let z_hat = Vector3::z();
        let frame_rate = z_hat * psi_dot; // angular velocity of I

        // Slip velocity, its rate, and the friction force, all in I.
        let slip = self.slip;
        let (slip_rate, friction) = match self.mode {
            Mode::Rolling => (Vector3::zeros(), Vector3::new(u[3], u[4], 0.0)),
            Mode::Slipping => {
                let speed = slip.norm();
                (
                    Vector3::new(u[3], u[4], 0.0),
                    -self.mu * normal * slip / speed,
                )
            }
        };

        // Centre-of-mass acceleration from V_G = V_P − Ω × GP (eq. 4.15).
        let omega = Vector3::new(-theta_dot * s, -phi_dot, psi_dot + theta_dot * c);
        let omega_rate = Vector3::new(
            -theta_ddot * s - theta_dot * phi_dot * c,
            -phi_ddot,
            psi_ddot + theta_ddot * c - theta_dot * phi_dot * s,
        );
        let (gp, gp_rate) = (self.gp, self.gp_rate);
        let w = omega.cross(&gp);
        let w_rate = omega_rate.cross(&gp) + omega.cross(&gp_rate) + frame_rate.cross(&w);
        let accel_g = slip_rate + frame_rate.cross(&slip) - w_rate;

        // Force balance, eq. (4.2a), scaled: a_G = F + (n − 1) ẑ.
        let force = accel_g - friction - z_hat * (normal - 1.0);

        // Moment balance about G in the body frame, eq. (4.2b).
        let inertia = self.inertia;
        let omega_b = Vector3::new(psi_dot * s, -phi_dot, psi_dot * c + theta_dot);
        let frame_b = Vector3::new(psi_dot * s, -phi_dot, psi_dot * c);
        let omega_b_rate = Vector3::new(
            psi_ddot * s + psi_dot * phi_dot * c,
            -phi_ddot,
            psi_ddot * c - psi_dot * phi_dot * s + theta_ddot,
        );
        let gp_b = Vector3::new(-1.0, 0.0, -self.h);
        let contact_b = self.body_from_intermediate * (friction + z_hat * normal);
        let moment_q = -normal * self.eta_q;
        let moment = inertia.component_mul(&omega_b_rate)
            + frame_b.cross(&inertia.component_mul(&omega_b))
            - gp_b.cross(&contact_b)
            - moment_q;

        Vector6::new(force.x, force.y, force.z, moment.x, moment.y, moment.z)
    }
}

impl ScaledDisk {
    /// The rates a dissipative moment depends on.
    pub fn rates(y: &StateVector) -> Rates {
        Rates {
            phi: y[PHI],
            phi_dot: y[PHI_DOT],
            psi_dot: y[PSI_DOT],
            theta_dot: y[THETA_DOT],
        }
    }

    /// The state-dependent terms of the Newton–Euler residual (eqs. 4.2a in I, 4.2b in
    /// B), computed once per state: trigonometric functions, the contact arm and the
    /// dissipative moment q (eq. 4.5) do not depend on the unknowns.
    fn residual_terms(&self, y: &StateVector, mode: Mode) -> ResidualTerms {
        let phi = y[PHI];
        let (s, c) = phi.sin_cos();
        let (gp, gp_rate) = contact_arm(self.h, phi, y[PHI_DOT]);
        ResidualTerms {
            mode,
            mu: self.mu,
            inertia: Vector3::new(self.a, self.a, self.c),
            h: self.h,
            s,
            c,
            psi_dot: y[PSI_DOT],
            phi_dot: y[PHI_DOT],
            theta_dot: y[THETA_DOT],
            slip: Vector3::new(y[X_DOT], y[Y_DOT], 0.0),
            gp,
            gp_rate,
            eta_q: self.eta * self.q_body(y),
            body_from_intermediate: body_from_intermediate(phi),
        }
    }

    /// Solves the Newton–Euler equations for the accelerations and contact forces.
    /// Returns `None` when the system is singular (which happens only at φ = 0 with
    /// h = 0 or a zero slip speed in slipping mode).
    pub fn accelerations(&self, y: &StateVector, mode: Mode) -> Option<Accelerations> {
        let terms = self.residual_terms(y, mode);
        let bias = terms.residual(&Vector6::zeros());
        let mut jacobian = Matrix6::zeros();
        for k in 0..6 {
            let column = terms.residual(&Vector6::ith(k, 1.0)) - bias;
            jacobian.set_column(k, &column);
        }
        let u = Lu::new(jacobian)?.solve(&(-bias));
        let normal = u[5];
        let (slip_accel, friction) = match mode {
            Mode::Rolling => (Vector2::zeros(), Vector2::new(u[3], u[4])),
            Mode::Slipping => {
                let slip = Vector2::new(y[X_DOT], y[Y_DOT]);
                (
                    Vector2::new(u[3], u[4]),
                    -self.mu * normal * slip / slip.norm(),
                )
            }
        };
        Some(Accelerations {
            psi_ddot: u[0],
            phi_ddot: u[1],
            theta_ddot: u[2],
            slip_accel,
            friction,
            normal,
        })
    }

    /// The first-order system ẏ = f(y) in the given mode.
    pub fn derivative(&self, y: &StateVector, mode: Mode) -> Option<StateVector> {
        let acc = self.accelerations(y, mode)?;
        let mut dy = StateVector::zeros();
        dy[PSI] = y[PSI_DOT];
        dy[PSI_DOT] = acc.psi_ddot;
        dy[PHI] = y[PHI_DOT];
        dy[PHI_DOT] = acc.phi_ddot;
        dy[THETA] = y[THETA_DOT];
        dy[THETA_DOT] = acc.theta_ddot;
        if mode == Mode::Slipping {
            dy[X] = y[X_DOT];
            dy[X_DOT] = acc.slip_accel.x;
            dy[Y] = y[Y_DOT];
            dy[Y_DOT] = acc.slip_accel.y;
        }
        Some(dy)
    }

    /// The dissipative moment's shape q^B at `y` (eq. 4.5), on [`ScaledDisk::branch`].
    pub fn q_body(&self, y: &StateVector) -> Vector3<f64> {
        let rates = Self::rates(y);
        match self.branch {
            Some(side) => self.dissipation.q_body_on_side(&rates, self.h, side),
            None => self.dissipation.q_body(&rates, self.h),
        }
    }

    /// The Jacobian ∂f/∂y of [`ScaledDisk::derivative`] at `y`, by forward differences,
    /// given `f0` = f(y). The cyclic coordinates ψ, θ, x, y do not appear in f (§4.2.3),
    /// so their columns are zero. The slip-velocity steps are relative to the slip speed,
    /// which sets the scale of the stiff friction terms (−μ n v/|v|, eq. 4.32d–e).
    pub fn jacobian(
        &self,
        y: &StateVector,
        mode: Mode,
        f0: &StateVector,
    ) -> Option<SMatrix<f64, 10, 10>> {
        let slip_speed = y[X_DOT].hypot(y[Y_DOT]);
        let mut jacobian = SMatrix::<f64, 10, 10>::zeros();
        for k in [PSI_DOT, PHI, PHI_DOT, THETA_DOT, X_DOT, Y_DOT] {
            let scale = match k {
                X_DOT | Y_DOT => y[k].abs().max(slip_speed),
                PHI => y[k].abs(),
                _ => y[k].abs().max(1.0),
            };
            let mut shifted = *y;
            shifted[k] += f64::EPSILON.sqrt() * scale;
            let step = shifted[k] - y[k];
            if step == 0.0 {
                continue;
            }
            jacobian.set_column(k, &((self.derivative(&shifted, mode)? - f0) / step));
        }
        Some(jacobian)
    }

    /// Centre-of-mass velocity in the intermediate frame, V_G = V_P − Ω × GP (eq. 4.15).
    pub fn centre_velocity(&self, y: &StateVector) -> Vector3<f64> {
        let (s, c) = y[PHI].sin_cos();
        let omega = Vector3::new(
            -y[THETA_DOT] * s,
            -y[PHI_DOT],
            y[PSI_DOT] + y[THETA_DOT] * c,
        );
        let (gp, _) = contact_arm(self.h, y[PHI], y[PHI_DOT]);
        Vector3::new(y[X_DOT], y[Y_DOT], 0.0) - omega.cross(&gp)
    }

    /// Total energy, eq. (4.94), scaled by mgR and measured from the disk lying flat
    /// at rest (the potential mgH is subtracted, as in eq. 3.8 and §4.6).
    pub fn energy(&self, y: &StateVector) -> f64 {
        let (s, c) = y[PHI].sin_cos();
        let v = self.centre_velocity(y);
        let omega_b = Vector3::new(y[PSI_DOT] * s, -y[PHI_DOT], y[PSI_DOT] * c + y[THETA_DOT]);
        let rotational =
            self.a * (omega_b.x.powi(2) + omega_b.y.powi(2)) + self.c * omega_b.z.powi(2);
        0.5 * v.norm_squared() + 0.5 * rotational + (s + self.h * c) - self.h
    }

    /// Stationary rolling at nutation φ (eqs. 4.40 and 2.29, sign corrected, see
    /// [`stationary_precession_squared`]): (ψ̇², θ̇/ψ̇) in scaled units.
    pub fn stationary_rolling(&self, phi: f64) -> (f64, f64) {
        let psi_dot_sq = stationary_precession_squared(self.h, self.a, self.c, phi);
        (psi_dot_sq, -(phi.cos() - self.h * phi.sin()))
    }

    /// Distance from the stationary-rolling manifold (eqs. 4.39–4.40, fig. 4.14),
    /// measured in the scaled rates at the state's own φ:
    /// |(ψ̇ − ψ̇*, θ̇ − θ̇*, φ̇, ẋ, ẏ)| with ψ̇* of the same sign as ψ̇.
    pub fn stationary_distance(&self, y: &StateVector) -> f64 {
        let (psi_dot_sq, theta_per_psi) = self.stationary_rolling(y[PHI]);
        let psi_star = psi_dot_sq.max(0.0).sqrt() * y[PSI_DOT].signum();
        let theta_star = theta_per_psi * psi_star;
        ((y[PSI_DOT] - psi_star).powi(2)
            + (y[THETA_DOT] - theta_star).powi(2)
            + y[PHI_DOT].powi(2)
            + y[X_DOT].powi(2)
            + y[Y_DOT].powi(2))
        .sqrt()
    }
}

/// Angular velocity of the disk about the global vertical, ω_z = ψ̇ + θ̇ cos φ (eq. 4.54).
pub fn vertical_spin(psi_dot: f64, phi: f64, theta_dot: f64) -> f64 {
    psi_dot + theta_dot * phi.cos()
}

/// Angle of a strip drawn at β0 on the top face, as seen from above (eq. 3.20),
/// computed as the direction of the projected strip (eq. 3.19), in (−π, π].
pub fn strip_angle(psi: f64, phi: f64, theta: f64, beta0: f64) -> f64 {
    let (sp, cp) = psi.sin_cos();
    let (sb, cb) = (theta + beta0).sin_cos();
    let lx = cp * phi.cos() * cb - sp * sb;
    let ly = sp * phi.cos() * cb + cp * sb;
    ly.atan2(lx)
}

/// Angular velocity of the strip seen from above (eq. 3.21).
pub fn strip_rate(
    phi: f64,
    phi_dot: f64,
    psi_dot: f64,
    theta: f64,
    theta_dot: f64,
    beta0: f64,
) -> f64 {
    let (sphi, cphi) = phi.sin_cos();
    let (sb, cb) = (theta + beta0).sin_cos();
    psi_dot + (phi_dot * sphi * sb * cb + theta_dot * cphi) / (1.0 - sphi * sphi * cb * cb)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::dissipation::ModelKind;
    use crate::model::params::Preset;

    fn disk(preset: Preset, mu: f64, eta: f64, kind: ModelKind) -> ScaledDisk {
        let p = preset.params();
        ScaledDisk {
            h: p.h(),
            a: p.a(),
            c: p.c(),
            mu,
            eta,
            dissipation: Dissipation::new(kind),
            branch: None,
        }
    }

    /// Deterministic pseudo-random numbers in [lo, hi).
    fn lcg(seed: &mut u64, lo: f64, hi: f64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((*seed >> 11) as f64 / (1u64 << 53) as f64)
    }

    fn random_state(seed: &mut u64, slipping: bool) -> StateVector {
        let mut y = StateVector::zeros();
        y[PSI] = lcg(seed, -3.0, 3.0);
        y[PSI_DOT] = lcg(seed, -5.0, 5.0);
        y[PHI] = lcg(seed, 0.05, 1.4);
        y[PHI_DOT] = lcg(seed, -2.0, 2.0);
        y[THETA] = lcg(seed, -3.0, 3.0);
        y[THETA_DOT] = lcg(seed, -5.0, 5.0);
        if slipping {
            y[X_DOT] = lcg(seed, -1.0, 1.0);
            y[Y_DOT] = lcg(seed, -1.0, 1.0);
        }
        y
    }

    /// The rolling accelerations agree with the printed closed forms of Appendix C
    /// as corrected in ERRATA (C.1 and C.2 with cot φ, C.3 re-bracketed), η = 0.
    #[test]
    fn rolling_matches_corrected_appendix_c() {
        let d = disk(Preset::EulerDisk, 10.0, 0.0, ModelKind::None);
        let (h, a, c) = (d.h, d.a, d.c);
        let (ap, cp) = (a + h * h, c + 1.0);
        let k = c / (c * ap + a);
        let mut seed = 7;
        for _ in 0..200 {
            let y = random_state(&mut seed, false);
            let (phi, pd, sd, td) = (y[PHI], y[PHI_DOT], y[PSI_DOT], y[THETA_DOT]);
            let (s, co) = phi.sin_cos();
            let cot = co / s;
            let g_psi = ((k * cp - 2.0) * cot - k * h) * sd * pd + k * cp / s * td * pd;
            let g_theta = (-k * cp * cot + k * h) * td * pd
                + (-k * cp * cot * co - k * ap * s + 2.0 * k * h * co + 2.0 / s) * sd * pd;
            let g_phi = (((ap - cp) * s * co - h * (2.0 * phi).cos()) * sd * sd
                - (cp * s + h * co) * td * sd
                - (co - h * s))
                / (ap + 1.0);
            let acc = d.accelerations(&y, Mode::Rolling).unwrap();
            assert!((acc.psi_ddot - g_psi).abs() < 1e-10 * (1.0 + g_psi.abs()));
            assert!((acc.theta_ddot - g_theta).abs() < 1e-10 * (1.0 + g_theta.abs()));
            assert!((acc.phi_ddot - g_phi).abs() < 1e-10 * (1.0 + g_phi.abs()));
            // Normal force, eq. (4.23).
            let n = 1.0 + acc.phi_ddot * (co - h * s) - pd * pd * (s + h * co);
            assert!((acc.normal - n).abs() < 1e-10 * (1.0 + n.abs()));
        }
    }

    /// Friction components in I as printed in eq. (4.34a), and eq. (4.34b) with the
    /// ERRATA sign.
    #[test]
    fn rolling_friction_matches_eq_4_34_with_errata_sign() {
        let d = disk(Preset::EulerDisk, 10.0, 0.0, ModelKind::None);
        let h = d.h;
        let mut seed = 11;
        for _ in 0..100 {
            let y = random_state(&mut seed, false);
            let acc = d.accelerations(&y, Mode::Rolling).unwrap();
            let (s, co) = y[PHI].sin_cos();
            let (pd, sd, td) = (y[PHI_DOT], y[PSI_DOT], y[THETA_DOT]);
            let fx = -(s + h * co) * acc.phi_ddot
                - (co - h * s) * sd * sd
                - td * sd
                - (co - h * s) * pd * pd;
            let fy = acc.psi_ddot * (co - h * s) + acc.theta_ddot - 2.0 * (s + h * co) * pd * sd;
            assert!((acc.friction.x - fx).abs() < 1e-9 * (1.0 + fx.abs()));
            assert!((acc.friction.y - fy).abs() < 1e-9 * (1.0 + fy.abs()));
        }
    }

    /// Slipping with μ = η = 0 matches the dissipation-free closed forms C.4–C.6, and
    /// the slip equations (4.32d–e).
    #[test]
    fn frictionless_slipping_matches_appendix_c() {
        let d = disk(Preset::EulerDisk, 0.0, 0.0, ModelKind::None);
        let (h, a, c) = (d.h, d.a, d.c);
        let mut seed = 3;
        for _ in 0..100 {
            let y = random_state(&mut seed, true);
            let (s, co) = y[PHI].sin_cos();
            let (pd, sd, td) = (y[PHI_DOT], y[PSI_DOT], y[THETA_DOT]);
            let acc = d.accelerations(&y, Mode::Slipping).unwrap();
            let h_psi = (c * td * pd - (2.0 * a - c) * sd * pd * co) / (a * s);
            let h_theta = ((c * a - c * c) * co * co + c * a) * sd * pd - c * c * td * pd * co;
            let h_theta = h_theta / (a * c * s);
            assert!((acc.psi_ddot - h_psi).abs() < 1e-9 * (1.0 + h_psi.abs()));
            assert!((acc.theta_ddot - h_theta).abs() < 1e-9 * (1.0 + h_theta.abs()));
            // Eq. (4.31a) with μ = η = 0: a φ̈ = a h_φ − n (cos φ − h sin φ).
            let h_phi = ((a - c) * co * s * sd * sd - c * s * sd * td) / a;
            let rhs = h_phi - acc.normal / a * (co - h * s);
            assert!((acc.phi_ddot - rhs).abs() < 1e-9 * (1.0 + rhs.abs()));
            // Eq. (4.32d), f = 0.
            let xdd = acc.phi_ddot * (s + h * co)
                + (sd * sd + pd * pd) * (co - h * s)
                + sd * td
                + sd * y[Y_DOT];
            assert!((acc.slip_accel.x - xdd).abs() < 1e-9 * (1.0 + xdd.abs()));
        }
    }

    /// dE/dt = F·V_P + Q·Ω (ERRATA preamble): zero power in rolling without η, and
    /// the Coulomb and rolling-friction powers in general.
    #[test]
    fn energy_rate_equals_contact_power() {
        for (mode, slipping) in [(Mode::Rolling, false), (Mode::Slipping, true)] {
            for kind in [
                ModelKind::None,
                ModelKind::Contour,
                ModelKind::ClassicalRolling,
            ] {
                let d = disk(Preset::EulerDisk, 0.3, 0.05, kind);
                let mut seed = 5;
                for _ in 0..50 {
                    let y = random_state(&mut seed, slipping);
                    let dy = d.derivative(&y, mode).unwrap();
                    // Directional derivative of E along the flow by central differences.
                    let step = 1e-6;
                    let rate =
                        (d.energy(&(y + dy * step)) - d.energy(&(y - dy * step))) / (2.0 * step);
                    let acc = d.accelerations(&y, mode).unwrap();
                    let slip = Vector2::new(y[X_DOT], y[Y_DOT]);
                    let (s, c) = y[PHI].sin_cos();
                    let omega_b =
                        Vector3::new(y[PSI_DOT] * s, -y[PHI_DOT], y[PSI_DOT] * c + y[THETA_DOT]);
                    let q = d.dissipation.q_body(&ScaledDisk::rates(&y), d.h);
                    let power = acc.friction.dot(&slip) - d.eta * acc.normal * q.dot(&omega_b);
                    assert!(
                        (rate - power).abs() < 1e-6 * (1.0 + power.abs()),
                        "{mode:?} {kind:?}: dE/dt = {rate}, power = {power}"
                    );
                }
            }
        }
    }

    /// Eq. (3.21) is the time derivative of eq. (3.20).
    #[test]
    fn strip_rate_is_derivative_of_strip_angle() {
        let mut seed = 9;
        for _ in 0..100 {
            let (psi, phi, theta) = (
                lcg(&mut seed, -3.0, 3.0),
                lcg(&mut seed, 0.0, 1.2),
                lcg(&mut seed, -3.0, 3.0),
            );
            let (psi_dot, phi_dot, theta_dot) = (
                lcg(&mut seed, -5.0, 5.0),
                lcg(&mut seed, -2.0, 2.0),
                lcg(&mut seed, -5.0, 5.0),
            );
            let beta0 = lcg(&mut seed, -3.0, 3.0);
            let dt = 1e-6;
            let at = |t: f64| {
                strip_angle(
                    psi + psi_dot * t,
                    phi + phi_dot * t,
                    theta + theta_dot * t,
                    beta0,
                )
            };
            let mut diff = at(dt) - at(-dt);
            // unwrap the ±2π jump of atan2
            diff -= (diff / std::f64::consts::TAU).round() * std::f64::consts::TAU;
            let numeric = diff / (2.0 * dt);
            let analytic = strip_rate(phi, phi_dot, psi_dot, theta, theta_dot, beta0);
            assert!(
                (numeric - analytic).abs() < 1e-5 * (1.0 + analytic.abs()),
                "numeric {numeric}, eq. 3.21 {analytic}"
            );
        }
    }

    /// On the stationary-rolling manifold (eq. 4.40) the centre of mass is at rest,
    /// there is no friction force, and φ̈ = 0 (a steady motion, eq. 4.38).
    #[test]
    fn stationary_rolling_is_steady_and_force_free() {
        let d = disk(Preset::EulerDisk, 0.134, 0.0, ModelKind::None);
        for phi in [0.01, 0.1, 0.5, 1.0] {
            let (psi_sq, ratio) = d.stationary_rolling(phi);
            let mut y = StateVector::zeros();
            y[PHI] = phi;
            y[PSI_DOT] = -psi_sq.sqrt();
            y[THETA_DOT] = ratio * y[PSI_DOT];
            let acc = d.accelerations(&y, Mode::Rolling).unwrap();
            assert!(d.centre_velocity(&y).norm() < 1e-12);
            assert!(acc.friction.norm() < 1e-12, "friction {}", acc.friction);
            assert!(
                acc.phi_ddot.abs() < 1e-12 && acc.psi_ddot.abs() < 1e-12,
                "φ = {phi}: φ̈ = {}, ψ̈ = {}",
                acc.phi_ddot,
                acc.psi_ddot
            );
            assert!((acc.normal - 1.0).abs() < 1e-12);
            assert!(d.stationary_distance(&y) < 1e-12);
        }
    }
}
