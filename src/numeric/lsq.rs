//! A small Levenberg–Marquardt least-squares solver for the local rim fits
//! (`signal`) and the leaning top face's profile (`vision`) (a handful of
//! parameters, tens of residuals), and the linearised covariance s² (JᵀJ)⁻¹,
//! s² = SSR/dof, at the optimum. The Jacobian is the caller's: the local fits build
//! it from the rim model's partial derivatives, which is most of their speed.

use nalgebra::{DMatrix, DVector};

/// Result of a least-squares fit.
#[derive(Debug, Clone)]
pub(crate) struct LsqFit {
    /// Parameters at the optimum.
    pub params: DVector<f64>,
    /// s² (JᵀJ)⁻¹ with s² = SSR/dof; `None` when dof = 0 or JᵀJ is singular.
    pub covariance: Option<DMatrix<f64>>,
    /// Sum of squared residuals at the optimum.
    pub ssr: f64,
    /// Residuals minus parameters.
    pub dof: usize,
}

const MAX_ITERATIONS: usize = 100;
/// Relative decrease of the SSR below which the search has settled.
const SSR_TOL: f64 = 1e-12;
/// Relative step below which the search has settled.
const STEP_TOL: f64 = 1e-12;

/// Minimises Σ r_i(p)² from `p0` (parameters scaled to order one). `residuals(p,
/// out)` fills `out` (length `count`); `jacobian(p, jac)` fills the `count` ×
/// `p0.len()` matrix ∂r_i/∂p_j at `p`. Returns `None` if a residual is not finite at
/// `p0`.
pub(crate) fn levenberg_marquardt(
    residuals: impl Fn(&[f64], &mut [f64]),
    jacobian: impl Fn(&[f64], &mut DMatrix<f64>),
    p0: &[f64],
    count: usize,
) -> Option<LsqFit> {
    let n = p0.len();
    let mut p = DVector::from_column_slice(p0);
    let mut r = DVector::zeros(count);
    residuals(p.as_slice(), r.as_mut_slice());
    let mut ssr = r.norm_squared();
    if !ssr.is_finite() {
        return None;
    }
    let mut lambda = 1e-3;
    let mut jac = DMatrix::zeros(count, n);
    jacobian(p.as_slice(), &mut jac);
    // One trial vector for the whole search, swapped with `r` on success.
    let mut r_trial = DVector::zeros(count);
    // Whether `p` moved since `jac` was taken.
    let mut stale = false;
    for _ in 0..MAX_ITERATIONS {
        let jtj = jac.transpose() * &jac;
        let jtr = jac.transpose() * &r;
        let mut improved = false;
        let mut settled = false;
        while lambda < 1e12 {
            let mut a = jtj.clone();
            for j in 0..n {
                a[(j, j)] += lambda * jtj[(j, j)].max(1e-30);
            }
            let Some(step) = a.cholesky().map(|c| c.solve(&(-&jtr))) else {
                lambda *= 10.0;
                continue;
            };
            let trial = &p + &step;
            residuals(trial.as_slice(), r_trial.as_mut_slice());
            let ssr_trial = r_trial.norm_squared();
            if ssr_trial.is_finite() && ssr_trial <= ssr {
                settled = ssr - ssr_trial <= SSR_TOL * ssr
                    || step.norm() <= STEP_TOL * (p.norm() + STEP_TOL);
                p = trial;
                std::mem::swap(&mut r, &mut r_trial);
                ssr = ssr_trial;
                lambda = (lambda / 10.0).max(1e-12);
                improved = true;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
        if settled {
            stale = true;
            break;
        }
        jacobian(p.as_slice(), &mut jac);
    }
    // The covariance takes the Jacobian at the optimum: recompute it only if the
    // last accepted step moved `p` since it was taken (the same numbers otherwise).
    if stale {
        jacobian(p.as_slice(), &mut jac);
    }
    let dof = count.saturating_sub(n);
    let covariance = if dof > 0 {
        (jac.transpose() * &jac)
            .try_inverse()
            .map(|inv| inv * (ssr / dof as f64))
            .filter(|c| c.iter().all(|x| x.is_finite()))
    } else {
        None
    };
    Some(LsqFit {
        params: p,
        covariance,
        ssr,
        dof,
    })
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
}
