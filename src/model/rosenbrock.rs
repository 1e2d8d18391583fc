//! RODAS4, a linearly implicit, L-stable, stiffly accurate Rosenbrock method of order 4
//! with an embedded order-3 error estimate (Hairer & Wanner, *Solving Ordinary
//! Differential Equations II*, §IV.7, coefficients of their code RODAS), for autonomous
//! systems ẏ = f(y).
//!
//! The simulator uses it for the slipping phases of thesis §4.3.1, which are stiff:
//! Coulomb friction −μN V̂_P (eq. 4.11) turns the slip direction at a rate ∝ μ/|V_P|,
//! so the slip equations (4.32d–e) have a real eigenvalue of about −0.45/|v| (scaled)
//! that reaches −4e9 at the slip seed of eq. (4.41). The thesis integrated with the
//! stiff solver ODE15s (§4.3.1) for the same reason.
//!
//! One step of size h from y₀ solves six linear systems with the matrix
//! W = I/(γh) − J, J = ∂f/∂y at y₀ (γ = 1/4):
//!
//! ```text
//! W k_i = f(y₀ + Σ_{j<i} a_ij k_j) + Σ_{j<i} (c_ij / h) k_j,   i = 1…6,
//! y₁ = y₀ + Σ_{j≤5} a_6j k_j + k₆  (a_6j = a_5j + δ_j5, the last stage is y₁),
//! ```
//!
//! and the embedded solution differs from y₁ by k₆, the error estimate. A step from y₀
//! to any time inside an accepted step (output samples, event roots) reuses f(y₀) and
//! J; [`Step::to`] takes it with the shorter step size, so states between step ends
//! have the local accuracy of a step ("exact re-integration", as the simulator's
//! explicit phases do).

use nalgebra::{SMatrix, SVector};

/// γ, the diagonal of RODAS4.
const GAMMA: f64 = 0.25;
/// Stage coefficients a_ij (a_21; a_31, a_32; …; a_51 … a_54).
const A: [[f64; 4]; 4] = [
    [1.544, 0.0, 0.0, 0.0],
    [0.946_678_528_081_582_6, 0.255_701_169_898_328_4, 0.0, 0.0],
    [
        3.314_825_187_068_521,
        2.896_124_015_972_201,
        0.998_641_913_997_781_7,
        0.0,
    ],
    [
        1.221_224_509_226_641,
        6.019_134_481_288_629,
        12.537_083_329_320_87,
        -0.687_886_036_105_895,
    ],
];
/// Coupling coefficients c_ij (c_21; c_31, c_32; …; c_61 … c_65).
const C: [[f64; 5]; 5] = [
    [-5.6688, 0.0, 0.0, 0.0, 0.0],
    [
        -2.430_093_356_833_875,
        -0.206_359_915_709_191_5,
        0.0,
        0.0,
        0.0,
    ],
    [
        -0.107_352_905_815_137_5,
        -9.594_562_251_023_355,
        -20.470_286_148_096_16,
        0.0,
        0.0,
    ],
    [
        7.496_443_313_967_647,
        -10.246_804_314_643_52,
        -33.999_903_528_199_05,
        11.708_908_932_061_6,
        0.0,
    ],
    [
        8.083_246_795_921_522,
        -7.981_132_988_064_893,
        -31.521_594_328_743_71,
        16.319_305_431_231_36,
        -6.058_818_238_834_054,
    ],
];

/// The start of a step: state, f(y₀) and the Jacobian there.
#[derive(Debug, Clone)]
pub struct Step<const N: usize> {
    /// y₀.
    pub y: SVector<f64, N>,
    f0: SVector<f64, N>,
    jacobian: SMatrix<f64, N, N>,
}

/// The result of one step: the order-4 solution and the error estimate.
#[derive(Debug, Clone, Copy)]
pub struct StepResult<const N: usize> {
    /// y₁.
    pub y: SVector<f64, N>,
    /// y₁ minus the embedded order-3 solution.
    pub error: SVector<f64, N>,
}

impl<const N: usize> Step<N> {
    /// Prepares a step from `y` with f(y) = `f0` and the Jacobian `jacobian`.
    pub fn new(y: SVector<f64, N>, f0: SVector<f64, N>, jacobian: SMatrix<f64, N, N>) -> Self {
        Step { y, f0, jacobian }
    }

    /// Takes one RODAS4 step of size `h` > 0; `None` if W is singular or f fails.
    pub fn to(
        &self,
        h: f64,
        f: &impl Fn(&SVector<f64, N>) -> Option<SVector<f64, N>>,
    ) -> Option<StepResult<N>> {
        let w = SMatrix::<f64, N, N>::identity() / (GAMMA * h) - self.jacobian;
        let lu = Lu::new(w)?;
        let mut k = [SVector::<f64, N>::zeros(); 6];
        k[0] = lu.solve(&self.f0);
        for i in 1..6 {
            // Stage state: y₀ + Σ a_ij k_j; the sixth stage starts from the fifth's state
            // plus k₅ (stiffly accurate: a_6j = a_5j + δ_j5).
            let mut u = self.y;
            for (j, kj) in k.iter().enumerate().take(i.min(5)) {
                let a = if i == 5 {
                    if j == 4 { 1.0 } else { A[3][j] }
                } else {
                    A[i - 1][j]
                };
                u += kj * a;
            }
            let mut rhs = f(&u)?;
            for (j, kj) in k.iter().enumerate().take(i) {
                rhs += kj * (C[i - 1][j] / h);
            }
            k[i] = lu.solve(&rhs);
        }
        let mut y = self.y;
        for (j, kj) in k.iter().enumerate().take(4) {
            y += kj * A[3][j];
        }
        y += k[4] + k[5];
        Some(StepResult { y, error: k[5] })
    }
}

/// LU factorisation with partial pivoting of a small fixed-size matrix (Doolittle,
/// in place), for the N×N systems of a Rosenbrock step and the 6×6 Newton–Euler solve.
#[derive(Debug, Clone, Copy)]
pub struct Lu<const N: usize> {
    lu: SMatrix<f64, N, N>,
    pivots: [usize; N],
}

impl<const N: usize> Lu<N> {
    /// Factorises `m`; `None` if a pivot is zero or not finite (singular matrix).
    pub fn new(mut m: SMatrix<f64, N, N>) -> Option<Self> {
        let mut pivots = [0; N];
        for k in 0..N {
            let mut p = k;
            for i in k + 1..N {
                if m[(i, k)].abs() > m[(p, k)].abs() {
                    p = i;
                }
            }
            pivots[k] = p;
            if p != k {
                m.swap_rows(p, k);
            }
            let pivot = m[(k, k)];
            if pivot == 0.0 || !pivot.is_finite() {
                return None;
            }
            for i in k + 1..N {
                let factor = m[(i, k)] / pivot;
                m[(i, k)] = factor;
                for j in k + 1..N {
                    m[(i, j)] -= factor * m[(k, j)];
                }
            }
        }
        Some(Lu { lu: m, pivots })
    }

    /// Solves m x = b.
    pub fn solve(&self, b: &SVector<f64, N>) -> SVector<f64, N> {
        let mut x = *b;
        for k in 0..N {
            x.swap_rows(k, self.pivots[k]);
        }
        for i in 0..N {
            for j in 0..i {
                x[i] -= self.lu[(i, j)] * x[j];
            }
        }
        for i in (0..N).rev() {
            for j in i + 1..N {
                x[i] -= self.lu[(i, j)] * x[j];
            }
            x[i] /= self.lu[(i, i)];
        }
        x
    }
}

/// Error norm of a step: root mean square of e_i / (atol + rtol · max(|y₀_i|, |y₁_i|)).
pub fn error_norm<const N: usize>(
    y0: &SVector<f64, N>,
    result: &StepResult<N>,
    rtol: f64,
    atol: f64,
) -> f64 {
    let sum: f64 = (0..N)
        .map(|i| {
            let scale = atol + rtol * y0[i].abs().max(result.y[i].abs());
            (result.error[i] / scale).powi(2)
        })
        .sum();
    (sum / N as f64).sqrt()
}

/// Step-size factor after a step with error norm `err` (order 4 controller, safety
/// 0.9, growth at most 6, shrink at most 5, as RODAS).
pub fn step_factor(err: f64) -> f64 {
    if !err.is_finite() {
        return 0.2;
    }
    (0.9 * err.max(1e-16).powf(-0.25)).clamp(0.2, 6.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Vector3};

    /// A stiff autonomous test problem with a known solution
    /// y = (1/(1+t), sin t, cos t, cos t): ẏ₀ = −y₀², (y₁, y₃) a unit-speed rotation
    /// (ẏ₁ = y₃, ẏ₃ = −y₁), and ẏ₂ = −y₁ + λ(y₂ − y₃) with λ = −1e6, which relaxes y₂
    /// onto y₃ = cos t and is solved by y₂ = cos t exactly.
    fn f(y: &SVector<f64, 4>) -> Option<SVector<f64, 4>> {
        let lambda = -1e6;
        Some(SVector::<f64, 4>::new(
            -y[0] * y[0],
            y[3],
            -y[1] + lambda * (y[2] - y[3]),
            -y[1],
        ))
    }

    fn jacobian(y: &SVector<f64, 4>) -> SMatrix<f64, 4, 4> {
        let lambda = -1e6;
        let mut j = SMatrix::<f64, 4, 4>::zeros();
        j[(0, 0)] = -2.0 * y[0];
        j[(1, 3)] = 1.0;
        j[(2, 1)] = -1.0;
        j[(2, 2)] = lambda;
        j[(2, 3)] = -lambda;
        j[(3, 1)] = -1.0;
        j
    }

    fn exact(t: f64) -> SVector<f64, 4> {
        SVector::<f64, 4>::new(1.0 / (1.0 + t), t.sin(), t.cos(), t.cos())
    }

    fn integrate(steps: usize) -> f64 {
        let h = 1.0 / steps as f64;
        let mut y = exact(0.0);
        for _ in 0..steps {
            let f0 = f(&y).unwrap();
            y = Step::new(y, f0, jacobian(&y)).to(h, &f).unwrap().y;
        }
        (y - exact(1.0)).amax()
    }

    /// The global error at t = 1 falls as h⁴ (order 4), with a stiff component
    /// (λ = −1e6, λh up to −1e5) present: L-stability keeps it from spoiling the order.
    #[test]
    fn rodas4_converges_with_order_four_on_a_stiff_problem() {
        let errors: Vec<f64> = [10, 20, 40, 80].iter().map(|&n| integrate(n)).collect();
        for pair in errors.windows(2) {
            let order = (pair[0] / pair[1]).log2();
            assert!(
                (3.7..4.6).contains(&order),
                "observed order {order}, errors {errors:?}"
            );
        }
        assert!(errors[3] < 1e-8, "errors {errors:?}");
    }

    /// The embedded estimate is of third order: it falls as h⁴ per step.
    #[test]
    fn error_estimate_is_local_order_four() {
        let y = SVector::<f64, 4>::new(1.0, 0.3, 0.2, 0.9);
        let step = Step::new(y, f(&y).unwrap(), jacobian(&y));
        let e1 = step.to(0.02, &f).unwrap().error[0].abs();
        let e2 = step.to(0.01, &f).unwrap().error[0].abs();
        let order = (e1 / e2).log2();
        assert!((3.6..4.4).contains(&order), "estimate order {order}");
    }

    /// The LU solve agrees with a direct check of the residual, with pivoting needed.
    #[test]
    fn lu_solves_with_pivoting() {
        let m = Matrix3::new(0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 3.0, 0.0, 1e-3);
        let b = Vector3::new(1.0, -2.0, 0.5);
        let x = Lu::new(m).unwrap().solve(&b);
        assert!((m * x - b).amax() < 1e-14, "{x}");
        assert!(Lu::new(Matrix3::new(1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 0.0, 0.0, 1.0)).is_none());
    }

    /// A linear rotation-plus-decay system is solved to the matrix exponential.
    #[test]
    fn linear_system_matches_matrix_exponential() {
        let a = Matrix3::new(0.0, 1.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, -1e8);
        let f = |y: &SVector<f64, 3>| Some(a * y);
        let mut y = Vector3::new(1.0, 0.0, 1.0);
        let h = 0.01;
        for _ in 0..100 {
            y = Step::new(y, a * y, a).to(h, &f).unwrap().y;
        }
        assert!((y[0] - 1f64.cos()).abs() < 1e-9, "{y}");
        assert!((y[1] + 1f64.sin()).abs() < 1e-9, "{y}");
        // L-stable: the stiff component is damped, not amplified.
        assert!(y[2].abs() < 1e-12, "{y}");
    }
}
