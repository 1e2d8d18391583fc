//! The crate's one nonlinear least-squares solver: Levenberg–Marquardt (Marquardt
//! 1963) with Nielsen's damping update, an optional trust radius, and the Bates–Watts
//! stopping rule. It serves the power law's variable projection (`energy`), the local
//! rim fits and the zero of the heights (`signal`), the turns' timing law
//! (`turn_timing`) and the leaning top face's profile (`vision`).
//!
//! The caller states the problem ([`Problem`]): residuals r(p), their Jacobian
//! ∂r/∂p (the caller's, from the model's partial derivatives, which is most of the
//! local fits' speed), and optionally how many linear parameters it has projected out,
//! the scale of each parameter's step, and where the parameters leave the model's
//! domain. [`levenberg_marquardt`] wraps two closures for the common case.
//!
//! The `levenberg-marquardt` crate was not used: its 0.15 release is built on
//! nalgebra 0.34, not the crate's 0.35.

use nalgebra::{DMatrix, DVector};

/// A nonlinear least-squares problem: minimise ‖r(p)‖² over p (scaled to order one).
pub(crate) trait Problem {
    /// Number of residuals m.
    fn residual_count(&self) -> usize;

    /// Fills `r` (length m) with r(p); `false` where the model is not defined at p.
    fn residuals(&self, p: &[f64], r: &mut [f64]) -> bool;

    /// Fills the m × k matrix ∂r_i/∂p_j at p.
    fn jacobian(&self, p: &[f64], jac: &mut DMatrix<f64>);

    /// Linear parameters eliminated from r by projection (variable projection): they
    /// count in the relative offset's degrees of freedom.
    fn eliminated(&self) -> usize {
        0
    }

    /// The scale of parameter j at p: a step is small when it changes every p_j by
    /// less than `XTOL` times this.
    fn step_scale(&self, p: &[f64], j: usize) -> f64 {
        1.0 + p[j].abs()
    }

    /// Whether p has left the region where the problem is meaningful (the search
    /// then stops, not converged).
    fn off_limits(&self, _p: &[f64]) -> bool {
        false
    }

    /// ‖r‖² below which the residual is rounding noise (exact data): converged.
    fn rounding_ssr(&self) -> f64 {
        0.0
    }
}

/// How far the search may go.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Limits {
    /// Most iterations (each ends in an accepted step or a stop).
    pub max_iterations: usize,
    /// Largest change of any parameter in one step (the initial trust radius); it
    /// shrinks when clamped steps predict the reduction badly.
    pub max_step: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_iterations: 100,
            max_step: f64::INFINITY,
        }
    }
}

/// Result of a least-squares fit.
#[derive(Debug, Clone)]
pub(crate) struct LsqFit {
    /// Parameters at the optimum.
    pub params: DVector<f64>,
    /// Residuals r at the optimum.
    pub residuals: DVector<f64>,
    /// ∂r/∂p at the optimum.
    pub jacobian: DMatrix<f64>,
    /// Sum of squared residuals at the optimum.
    pub ssr: f64,
    /// Residuals minus parameters (the eliminated ones included).
    pub dof: usize,
    /// Iterations used.
    pub iterations: usize,
    /// Whether the search stopped at a minimum (see [`levenberg_marquardt`]), not at
    /// the iteration limit, off limits, or stalled away from a minimum.
    pub converged: bool,
}

impl LsqFit {
    /// s² (JᵀJ)⁻¹ with s² = SSR/dof: the linearised covariance; `None` when dof = 0 or
    /// JᵀJ is singular.
    pub fn covariance(&self) -> Option<DMatrix<f64>> {
        if self.dof == 0 {
            return None;
        }
        (self.jacobian.transpose() * &self.jacobian)
            .try_inverse()
            .map(|inv| inv * (self.ssr / self.dof as f64))
            .filter(|c| c.iter().all(|x| x.is_finite()))
    }
}

/// A step is small when it changes each p_j by < XTOL × its scale.
const XTOL: f64 = 1e-12;
/// Converged when the relative offset (about the distance to the minimum in standard
/// errors, see [`relative_offset`]) is below this: with standard errors of ~1 % of a
/// parameter, it then changes by ~1e-12 relative.
const RO_TOL: f64 = 1e-10;
/// A small step, or a point where no step lowers ‖r‖² any more (floating point), counts
/// as converged only if the relative offset is at least this small (a millionth of a
/// standard error).
const STALL_RO: f64 = 1e-6;
/// Relative rounding error of a computed ‖r‖² (a few hundred terms summed).
const SSR_ROUNDING: f64 = 64.0 * f64::EPSILON;
/// Damping beyond which no step can lower the error.
const LAMBDA_MAX: f64 = 1e16;
/// Smallest damping kept (below it the step is Gauss–Newton's anyway).
const LAMBDA_MIN: f64 = 1e-12;

/// The problem at one p: residuals, ‖r‖² and the Jacobian.
struct Point {
    p: DVector<f64>,
    resid: DVector<f64>,
    ssr: f64,
    jac: DMatrix<f64>,
}

impl Point {
    /// The residuals at p; `None` where the model is undefined or ‖r‖² not finite.
    /// The Jacobian is left to [`Point::differentiate`].
    fn at(problem: &impl Problem, p: DVector<f64>) -> Option<Point> {
        let mut resid = DVector::zeros(problem.residual_count());
        if !problem.residuals(p.as_slice(), resid.as_mut_slice()) {
            return None;
        }
        let ssr = resid.norm_squared();
        ssr.is_finite().then(|| Point {
            jac: DMatrix::zeros(resid.len(), p.len()),
            p,
            resid,
            ssr,
        })
    }

    fn differentiate(mut self, problem: &impl Problem) -> Point {
        problem.jacobian(self.p.as_slice(), &mut self.jac);
        self
    }

    /// The relative offset at this point (infinite where undefined).
    fn relative_offset(&self, eliminated: usize) -> f64 {
        relative_offset(self, &self.jac.tr_mul(&self.resid), eliminated).unwrap_or(f64::INFINITY)
    }
}

/// The relative offset of Bates & Watts (1981): the part of the residual that the
/// parameters can still remove, q = rᵀJ (JᵀJ)⁻¹ Jᵀr (the Gauss–Newton reduction of
/// ‖r‖²), compared with the rest,
/// RO = √( (q/k) / ((‖r‖² − q)/(m − k − l)) ),
/// with k nonlinear parameters and l eliminated linear ones. RO is about the distance
/// to the minimum in standard errors, independent of the parametrisation and of
/// parameter correlations; zero at a stationary point. `None` when JᵀJ is singular or
/// there are no degrees of freedom.
fn relative_offset(point: &Point, gradient: &DVector<f64>, eliminated: usize) -> Option<f64> {
    if point.ssr == 0.0 {
        return Some(0.0);
    }
    let (m, k) = point.jac.shape();
    let dof = m.checked_sub(k + eliminated).filter(|&d| d > 0)?;
    let q = gradient.dot(&point.jac.tr_mul(&point.jac).cholesky()?.solve(gradient));
    let rest = (point.ssr - q).max(f64::MIN_POSITIVE);
    Some(((q / k as f64) / (rest / dof as f64)).sqrt())
}

/// The damping λ and its growth factor ν (Nielsen), and the trust radius.
struct Damping {
    lambda: f64,
    nu: f64,
    radius: f64,
    max_step: f64,
}

impl Damping {
    /// After a refused step: λ ← ν λ, ν doubling.
    fn raise(&mut self) {
        self.lambda *= self.nu;
        self.nu *= 2.0;
    }

    /// After a step that lowered ‖r‖² by the ratio ρ of actual to predicted reduction:
    /// λ ← λ max(1/3, 1 − (2ρ − 1)³); the radius shrinks when a clamped step predicted
    /// badly and grows when a step predicted well.
    fn accept(&mut self, rho: f64, clamped: bool) {
        self.lambda =
            (self.lambda * (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0)).max(LAMBDA_MIN);
        self.nu = 2.0;
        if clamped && rho < 0.25 {
            self.radius /= 4.0;
        } else if rho > 0.75 {
            self.radius = (2.0 * self.radius).min(self.max_step);
        }
    }

    /// The next point: raises the damping until a step lowers ‖r‖² (or, next to the
    /// minimum, keeps it within rounding while at least halving the relative offset
    /// `offset`), and returns it with the step taken; `None` when no step does, or the
    /// steps became small (`is_small`) without lowering it.
    fn step(
        &mut self,
        problem: &impl Problem,
        current: &Point,
        gradient: &DVector<f64>,
        offset: f64,
        is_small: impl Fn(&DVector<f64>, &DVector<f64>) -> bool,
    ) -> Option<(Point, DVector<f64>)> {
        let normal = current.jac.tr_mul(&current.jac);
        let diag_floor = 1e-12 * normal.diagonal().max();
        loop {
            if self.lambda > LAMBDA_MAX {
                return None;
            }
            let mut damped = normal.clone();
            for j in 0..damped.nrows() {
                damped[(j, j)] += self.lambda * normal[(j, j)].max(diag_floor);
            }
            let Some(cholesky) = damped.cholesky() else {
                self.raise();
                continue;
            };
            let mut step = cholesky.solve(&(-gradient));
            let largest = step.amax();
            let clamped = largest > self.radius;
            if clamped {
                step *= self.radius / largest;
            }
            let predicted = -(gradient.dot(&step) + 0.5 * step.dot(&(&normal * &step)));
            let trial = Point::at(problem, &current.p + &step);
            match trial {
                Some(trial) if trial.ssr < current.ssr && predicted > 0.0 => {
                    self.accept(0.5 * (current.ssr - trial.ssr) / predicted, clamped);
                    return Some((trial.differentiate(problem), step));
                }
                // Next to the minimum the change of ‖r‖² drowns in its rounding error,
                // but the gradient is still informative: accept a step that keeps ‖r‖²
                // within rounding and at least halves the relative offset (a smaller
                // gain is rounding noise too, and would let the search zigzag).
                Some(trial) if trial.ssr - current.ssr <= SSR_ROUNDING * current.ssr => {
                    let trial = trial.differentiate(problem);
                    if trial.relative_offset(problem.eliminated()) < 0.5 * offset {
                        self.lambda = (self.lambda / 3.0).max(LAMBDA_MIN);
                        self.nu = 2.0;
                        return Some((trial, step));
                    }
                    if is_small(&step, &current.p) {
                        return None;
                    }
                    self.raise();
                }
                // Steps below the tolerance no longer lower the error: stalled.
                _ if is_small(&step, &current.p) => return None,
                _ => self.raise(),
            }
        }
    }
}

/// Minimises ‖r(p)‖² from `p0`: solve (JᵀJ + λ diag(JᵀJ)) δ = −Jᵀr, clamp δ to the
/// trust radius, accept δ when it lowers ‖r‖², and adapt λ (see [`Damping`]).
///
/// Converged when the residual is rounding noise, when the relative offset is below
/// [`RO_TOL`], or when a step is below [`XTOL`] or no step lowers ‖r‖² any more while
/// the relative offset is below [`STALL_RO`] (so a step made tiny by heavy damping far
/// from the minimum is not taken for convergence). `None` when r is not finite at p0.
pub(crate) fn minimise(problem: &impl Problem, p0: DVector<f64>, limits: Limits) -> Option<LsqFit> {
    let l = problem.eliminated();
    let mut current = Point::at(problem, p0)?.differentiate(problem);
    let is_small = |step: &DVector<f64>, p: &DVector<f64>| {
        (0..p.len()).all(|j| step[j].abs() <= XTOL * problem.step_scale(p.as_slice(), j))
    };
    let mut damping = Damping {
        lambda: 1e-3,
        nu: 2.0,
        radius: limits.max_step,
        max_step: limits.max_step,
    };
    let mut iterations = 0;
    let converged = loop {
        let gradient = current.jac.tr_mul(&current.resid);
        let offset = relative_offset(&current, &gradient, l).unwrap_or(f64::INFINITY);
        if current.ssr <= problem.rounding_ssr() || offset <= RO_TOL {
            break true;
        }
        if iterations == limits.max_iterations || problem.off_limits(current.p.as_slice()) {
            break false;
        }
        iterations += 1;
        let Some((next, step)) = damping.step(problem, &current, &gradient, offset, is_small)
        else {
            // No step lowers the error in floating point: a minimum if flat enough.
            break offset <= STALL_RO;
        };
        let small = is_small(&step, &current.p);
        current = next;
        if small && current.relative_offset(l) <= STALL_RO {
            break true;
        }
    };
    let dof = current.resid.len().saturating_sub(current.p.len() + l);
    Some(LsqFit {
        params: current.p,
        residuals: current.resid,
        jacobian: current.jac,
        ssr: current.ssr,
        dof,
        iterations,
        converged,
    })
}

/// A [`Problem`] of two closures: `residuals(p, out)` fills the `count` residuals,
/// `jacobian(p, jac)` the `count` × k matrix ∂r_i/∂p_j.
struct Closures<R, J> {
    residuals: R,
    jacobian: J,
    count: usize,
}

impl<R, J> Problem for Closures<R, J>
where
    R: Fn(&[f64], &mut [f64]),
    J: Fn(&[f64], &mut DMatrix<f64>),
{
    fn residual_count(&self) -> usize {
        self.count
    }

    fn residuals(&self, p: &[f64], r: &mut [f64]) -> bool {
        (self.residuals)(p, r);
        true
    }

    fn jacobian(&self, p: &[f64], jac: &mut DMatrix<f64>) {
        (self.jacobian)(p, jac)
    }
}

/// Minimises Σ r_i(p)² from `p0` (parameters scaled to order one) with the default
/// [`Limits`]: `residuals(p, out)` fills `out` (length `count`); `jacobian(p, jac)`
/// fills the `count` × `p0.len()` matrix ∂r_i/∂p_j at `p`. Returns `None` if a
/// residual is not finite at `p0`.
pub(crate) fn levenberg_marquardt(
    residuals: impl Fn(&[f64], &mut [f64]),
    jacobian: impl Fn(&[f64], &mut DMatrix<f64>),
    p0: &[f64],
    count: usize,
) -> Option<LsqFit> {
    let problem = Closures {
        residuals,
        jacobian,
        count,
    };
    minimise(&problem, DVector::from_column_slice(p0), Limits::default())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sine with known amplitude, frequency and phase is recovered exactly, and the
    /// covariance of exact data is zero.
    #[test]
    fn recovers_a_sine() {
        let t: Vec<f64> = (0..30).map(|i| i as f64 * 0.1).collect();
        let y: Vec<f64> = t.iter().map(|&x| 1.5 * (2.0 * x + 0.3).sin()).collect();
        let fit = levenberg_marquardt(
            |p, out| {
                for (o, (&x, &yi)) in out.iter_mut().zip(t.iter().zip(&y)) {
                    *o = p[0] * (p[1] * x + p[2]).sin() - yi;
                }
            },
            |p, jac| {
                for (i, &x) in t.iter().enumerate() {
                    let (sin, cos) = (p[1] * x + p[2]).sin_cos();
                    jac[(i, 0)] = sin;
                    jac[(i, 1)] = p[0] * x * cos;
                    jac[(i, 2)] = p[0] * cos;
                }
            },
            &[1.0, 1.9, 0.0],
            t.len(),
        )
        .expect("fit");
        assert!((fit.params[0] - 1.5).abs() < 1e-9, "{:?}", fit.params);
        assert!((fit.params[1] - 2.0).abs() < 1e-9);
        assert!((fit.params[2] - 0.3).abs() < 1e-9);
        assert!(fit.ssr < 1e-18 && fit.dof == 27);
    }

    /// Noisy data: the search stops at a stationary point (the gradient Jᵀr vanishes
    /// to rounding against the residual's size) and reports convergence.
    #[test]
    fn stops_at_a_stationary_point_of_noisy_data() {
        let t: Vec<f64> = (0..40).map(|i| i as f64 * 0.05).collect();
        let noise = |i: usize| 0.01 * ((i * 7919 % 101) as f64 / 50.0 - 1.0);
        let y: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(i, &x)| 2.0 * (-1.3 * x).exp() + noise(i))
            .collect();
        let fit = levenberg_marquardt(
            |p, out| {
                for (o, (&x, &yi)) in out.iter_mut().zip(t.iter().zip(&y)) {
                    *o = p[0] * (-p[1] * x).exp() - yi;
                }
            },
            |p, jac| {
                for (i, &x) in t.iter().enumerate() {
                    let e = (-p[1] * x).exp();
                    jac[(i, 0)] = e;
                    jac[(i, 1)] = -p[0] * x * e;
                }
            },
            &[1.0, 0.5],
            t.len(),
        )
        .expect("fit");
        assert!(fit.converged);
        let gradient = fit.jacobian.tr_mul(&fit.residuals);
        assert!(gradient.amax() < 1e-9 * fit.ssr.sqrt(), "{gradient}");
        assert!((fit.params[1] - 1.3).abs() < 0.05, "{:?}", fit.params);
    }
}
