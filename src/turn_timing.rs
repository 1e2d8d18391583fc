//! n from the turns' timing alone: a third estimate of the exponent, beside the two
//! fits of eq. (3.2), that needs no height, no scale and no zero of z_rim.
//!
//! Near the halt the disk rolls stationarily, where eq. (2.29) (its sign corrected,
//! [`crate::model::closed_form::stationary_precession_squared`]) gives
//! ψ̇² R/g ≈ 1/(a φ) and eq. (3.8) gives E ≈ (3/2) m g R φ as φ → 0. The power law
//! E = A_e (t0 − t)^n (eq. 3.2) then makes ψ̇ ∝ τ^{−n/2}, τ = T − t, and integrating,
//! each turning point of z_rim (its peaks, where the raised side faces the camera,
//! and its troughs, where the contact does: half a turn apart, counted by
//! [`crate::signal::precession`]) comes at its ψ_k at
//!
//! ```text
//! t_k = T − c (ψ_end − ψ_k)^q,    q = 1/(1 − n/2),    n = 2 (1 − 1/q),
//! ```
//!
//! T the time the turns end and ψ_end the precession angle there. The turning points'
//! times are fitted with T, c, ψ_end and q free (least squares on the times, whose
//! errors a turn's rate does not scale), so n comes from the clock and the count of
//! turns. Whatever moves the heights, a misread scale, an offset of the zero, or a
//! codec's smoothing that shaves every swing, moves no turning point in time.
//!
//! What it assumes instead: stationary rolling and the small-angle limit. For a disk
//! following the corrected eq. (2.29) the pure power law reads n 0.0012–0.0016 low
//! (n = 0.4–0.7, φ falling from 0.025 to 0.0015 rad; unit test below); eq. (2.29) as
//! printed (`+ c h sin² φ`, which the independent footage's renderer follows) makes
//! it high, by +0.005 on that renderer's true peaks. A φ oscillating about
//! stationary rolling, or slip, moves the turns' rate and so this estimate, not the
//! heights'. n is reported, with its interval, never combined into
//! the fits; T, the same halt as the energy law's t0, helps place t_φ and bounds a
//! halt seen after it (`analyse::law_halt`, `analyse::law_bound`).
//!
//! The interval: the wider of the least-squares standard error, s² (JᵀJ)⁻¹ at the
//! optimum, and a delete-a-block jackknife (the turning points of two turns left out
//! together and the law fitted again: each point's time comes from a local fit over
//! 1.5 turns, shared with its neighbours, and a point coded late shows in it), with
//! Student's t at the jackknife's B − 1 degrees of freedom for B blocks. Where a last
//! point comes early the optimum lies on the boundary ψ_end = ψ_last, and the law is
//! fitted there.

use std::f64::consts::{PI, TAU};

use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, StudentsT};
use thiserror::Error;

use crate::numeric::lsq::levenberg_marquardt;

/// Fewest turning points the timing law is fitted to: sixteen, eight turns, so that the
/// jackknife has four blocks of two turns and each refit keeps twelve points for four
/// parameters.
pub const MIN_POINTS: usize = 16;

/// Turns the jackknife leaves out together: each turning point's time comes from a
/// local fit over 1.5 turns, so its error is shared with the points of the next turn
/// as well as with its own turn's other point.
const JACKKNIFE_TURNS: f64 = 2.0;

/// Starting grid: ψ_end − ψ_last from [`REMAINING_PSI_RANGE`] (the last point lies up
/// to about a turn before the turns end; log-spaced, [`REMAINING_PSI_STEPS`] values)
/// and q from [`Q_RANGE`] in steps of [`Q_STEP`] (n = 0.10 … 1.11, beyond Appendix B's
/// 0.31–0.89); each point solved for T and c by linear least squares, the best one
/// starts the full fit. The grid is fine because the sum of squares is steep in q:
/// over 25 turns Δq = 0.05 changes (ψ_end − ψ)^q by a factor up to 1.29 across the
/// window, and a coarser start let the search settle on the boundary ψ_end = ψ_last.
const REMAINING_PSI_RANGE: (f64, f64) = (0.05, 4.0 * PI);
const REMAINING_PSI_STEPS: usize = 24;
const Q_RANGE: (f64, f64) = (1.05, 2.25);
const Q_STEP: f64 = 0.01;

/// The exponent from the turning points' times.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TurnTimingFit {
    /// n = 2 (1 − 1/q).
    pub n: f64,
    /// 95 % interval of n.
    pub ci95_n: (f64, f64),
    /// Standard error of n: the wider of the two below.
    pub se_n: f64,
    /// Least-squares standard error of n, s² (JᵀJ)⁻¹ at the optimum.
    pub se_n_least_squares: f64,
    /// Delete-a-block jackknife standard error of n (two turns a block).
    pub se_n_jackknife: f64,
    /// T, when the fitted turns end, halt at t = 0 \[s\].
    pub t_end: f64,
    /// Delete-a-block jackknife standard error of T \[s\], from the same refits as
    /// n's; 0 in results written before it was recorded.
    #[serde(default)]
    pub se_t_end: f64,
    /// ψ_end − ψ at the last point \[rad\]: how far the fitted turns run past it.
    pub remaining_psi: f64,
    /// c of the law \[s rad^−q\].
    pub c: f64,
    /// The turning points fitted: their times, halt at t = 0 \[s\], and counted ψ
    /// \[rad\].
    pub times: Vec<f64>,
    pub psi: Vec<f64>,
    /// Peaks fitted.
    pub points: usize,
    /// RMS of the points' times about the law \[s\].
    pub residual_rms_s: f64,
}

/// Why the timing law could not be fitted.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum TurnTimingError {
    #[error("the turns' timing law needs at least {needed} turning points, got {found}")]
    TooFewPoints { found: usize, needed: usize },
    #[error("{times} times but {psi} precession angles")]
    LengthMismatch { times: usize, psi: usize },
    #[error("the turns' timing law did not converge to a finite exponent: {0}")]
    NoFit(&'static str),
}

/// A fitted law, times in ms from the last point of the full series and ψ from the
/// last point of the series fitted.
#[derive(Debug, Clone, Copy)]
struct Law {
    /// T \[ms\].
    end: f64,
    /// ln c (c in ms rad^−q).
    ln_c: f64,
    /// ψ_end − ψ_last \[rad\]; 0 when the turns end at the last point.
    remaining: f64,
    q: f64,
    /// Least-squares standard error of q.
    se_q: f64,
    /// Sum of squares \[ms²\].
    ssr: f64,
}

/// Below this ψ_end − ψ_last \[rad\] the turns are taken to end at the last point: the
/// law's sum of squares can have its minimum on that boundary (a last point that comes
/// early against the turns before it), where ln(ψ_end − ψ_last) runs off and its
/// covariance with it.
const REMAINING_FLOOR: f64 = 1e-3;

/// Fits t_k = T − c (ψ_end − ψ_k)^q to the turning points' times `t` \[s\] (halt at 0, any
/// origin) and counted precession angles `psi` \[rad\] (increasing), see the module
/// docs.
pub fn fit_turn_timing(t: &[f64], psi: &[f64]) -> Result<TurnTimingFit, TurnTimingError> {
    if t.len() != psi.len() {
        return Err(TurnTimingError::LengthMismatch {
            times: t.len(),
            psi: psi.len(),
        });
    }
    if t.len() < MIN_POINTS {
        return Err(TurnTimingError::TooFewPoints {
            found: t.len(),
            needed: MIN_POINTS,
        });
    }
    // Milliseconds and ψ from the last point keep the parameters of order one.
    let (t_last, psi_last) = (t[t.len() - 1], psi[psi.len() - 1]);
    let t_ms: Vec<f64> = t.iter().map(|&x| (x - t_last) * 1e3).collect();
    let psi0: Vec<f64> = psi.iter().map(|&x| x - psi_last).collect();
    let start = starting_point(&t_ms, &psi0).ok_or(TurnTimingError::NoFit("no starting point"))?;
    let law =
        fit_law(&t_ms, &psi0, &start).ok_or(TurnTimingError::NoFit("no least-squares optimum"))?;
    let n = exponent(law.q);
    let se_n_least_squares = 2.0 / (law.q * law.q) * law.se_q;
    // Delete-a-block jackknife: the points of [`JACKKNIFE_TURNS`] turns left out
    // together, each refit started from the full fit (ψ_end measured from the
    // subset's own last point).
    let count = t.len();
    let block_of: Vec<i64> = psi0
        .iter()
        .map(|&p| ((p - psi0[0]) / (JACKKNIFE_TURNS * TAU) + 1e-6).floor() as i64)
        .collect();
    let mut blocks = block_of.clone();
    blocks.dedup();
    let leave_out: Vec<(f64, f64)> = blocks
        .iter()
        .filter_map(|&block| {
            let (tk, pk): (Vec<f64>, Vec<f64>) = t_ms
                .iter()
                .zip(&psi0)
                .zip(&block_of)
                .filter(|&(_, &of)| of != block)
                .map(|((&a, &b), _)| (a, b))
                .unzip();
            let start = Law {
                remaining: law.remaining - pk[pk.len() - 1],
                ..law
            };
            fit_law(&tk, &pk, &start).map(|l| (exponent(l.q), l.end))
        })
        .collect();
    if leave_out.len() != blocks.len() {
        return Err(TurnTimingError::NoFit("a jackknife refit failed"));
    }
    let m = blocks.len() as f64;
    let jackknife_se = |values: &[f64]| {
        let mean = values.iter().sum::<f64>() / m;
        ((m - 1.0) / m * values.iter().map(|x| (x - mean).powi(2)).sum::<f64>()).sqrt()
    };
    let (n_left, end_left): (Vec<f64>, Vec<f64>) = leave_out.into_iter().unzip();
    let se_n_jackknife = jackknife_se(&n_left);
    let se_n = se_n_least_squares.max(se_n_jackknife);
    // The jackknife's degrees of freedom, B − 1 for B blocks (fewer than the points'
    // N − 4: neighbouring points share their errors).
    let quantile = StudentsT::new(0.0, 1.0, (m - 1.0).max(1.0))
        .map_err(|_| TurnTimingError::NoFit("no Student t for these degrees of freedom"))?
        .inverse_cdf(0.975);
    if !(n.is_finite() && se_n.is_finite()) {
        return Err(TurnTimingError::NoFit("n or its error is not finite"));
    }
    Ok(TurnTimingFit {
        n,
        ci95_n: (n - quantile * se_n, n + quantile * se_n),
        se_n,
        se_n_least_squares,
        se_n_jackknife,
        t_end: t_last + law.end * 1e-3,
        se_t_end: jackknife_se(&end_left) * 1e-3,
        remaining_psi: law.remaining,
        c: law.ln_c.exp() * 1e-3,
        times: t.to_vec(),
        psi: psi.to_vec(),
        points: count,
        residual_rms_s: (law.ssr / count as f64).sqrt() * 1e-3,
    })
}

impl TurnTimingFit {
    /// q = 1/(1 − n/2).
    pub fn q(&self) -> f64 {
        1.0 / (1.0 - self.n / 2.0)
    }

    /// ψ_end − ψ \[rad\] at each fitted point: the turns still to go.
    pub fn psi_to_go(&self) -> Vec<f64> {
        let last = self.psi.last().copied().unwrap_or(0.0);
        self.psi
            .iter()
            .map(|&p| last + self.remaining_psi - p)
            .collect()
    }

    /// T − t \[s\] the law gives with `psi_to_go` \[rad\] of turns left.
    pub fn time_to_go(&self, psi_to_go: f64) -> f64 {
        self.c * psi_to_go.powf(self.q())
    }
}

/// n = 2 (1 − 1/q).
fn exponent(q: f64) -> f64 {
    2.0 * (1.0 - 1.0 / q)
}

/// The grid point (ψ_end, q) whose linear least squares in (T, c), c > 0, leaves the
/// smallest sum of squares.
fn starting_point(t_ms: &[f64], psi: &[f64]) -> Option<Law> {
    let mut best: Option<Law> = None;
    let (lo, hi) = REMAINING_PSI_RANGE;
    let remaining_grid = (0..REMAINING_PSI_STEPS)
        .map(|i| lo * (hi / lo).powf(i as f64 / (REMAINING_PSI_STEPS - 1) as f64));
    let q_steps = ((Q_RANGE.1 - Q_RANGE.0) / Q_STEP).round() as usize;
    for remaining in remaining_grid {
        for q in (0..=q_steps).map(|i| Q_RANGE.0 + i as f64 * Q_STEP) {
            // t = T − c x, x = (ψ_end − ψ)^q: a straight line in x.
            let x: Vec<f64> = psi.iter().map(|&p| (remaining - p).powf(q)).collect();
            let m = x.len() as f64;
            let (mx, mt) = (x.iter().sum::<f64>() / m, t_ms.iter().sum::<f64>() / m);
            let sxx: f64 = x.iter().map(|v| (v - mx).powi(2)).sum();
            let sxt: f64 = x.iter().zip(t_ms).map(|(v, w)| (v - mx) * (w - mt)).sum();
            let c = -sxt / sxx;
            if !(c > 0.0 && c.is_finite()) {
                continue;
            }
            let end = mt + c * mx;
            let ssr: f64 = x
                .iter()
                .zip(t_ms)
                .map(|(v, w)| (end - c * v - w).powi(2))
                .sum();
            if best.is_none_or(|b| ssr < b.ssr) {
                best = Some(Law {
                    end,
                    ln_c: c.ln(),
                    remaining,
                    q,
                    se_q: f64::NAN,
                    ssr,
                });
            }
        }
    }
    best
}

/// The law fitted from `start` with the turns' end free; where its optimum lies on
/// the boundary (ψ_end − ψ_last below [`REMAINING_FLOOR`], or no optimum inside),
/// fitted again with the turns ending at the last point. `None` without a finite
/// optimum and covariance.
fn fit_law(t_ms: &[f64], psi: &[f64], start: &Law) -> Option<Law> {
    let last = psi[psi.len() - 1];
    least_squares(t_ms, psi, last, start, true)
        .filter(|law| law.remaining >= REMAINING_FLOOR)
        .or_else(|| least_squares(t_ms, psi, last, start, false))
}

/// Levenberg–Marquardt over [T, ln c, ln(ψ_end − ψ_last), q] (`free_end`) or
/// [T, ln c, q] with ψ_end = ψ_last (the logarithms keep c and the turns left
/// positive, so that no step leaves the law's domain).
fn least_squares(t_ms: &[f64], psi: &[f64], last: f64, start: &Law, free_end: bool) -> Option<Law> {
    let q_at = if free_end { 3 } else { 2 };
    let remaining = |p: &[f64]| if free_end { p[2].exp() } else { 0.0 };
    let p0: Vec<f64> = if free_end {
        vec![
            start.end,
            start.ln_c,
            start.remaining.max(REMAINING_FLOOR).ln(),
            start.q,
        ]
    } else {
        vec![start.end, start.ln_c, start.q]
    };
    let fit = levenberg_marquardt(
        |p, out| {
            let (c, end) = (p[1].exp(), remaining(p) + last);
            for ((o, &tk), &pk) in out.iter_mut().zip(t_ms).zip(psi) {
                *o = p[0] - c * (end - pk).powf(p[q_at]) - tk;
            }
        },
        |p, jac| {
            let (c, left) = (p[1].exp(), remaining(p));
            for (k, &pk) in psi.iter().enumerate() {
                let d = left + last - pk;
                let term = c * d.powf(p[q_at]);
                jac[(k, 0)] = 1.0;
                jac[(k, 1)] = -term;
                if free_end {
                    jac[(k, 2)] = -p[q_at] * term / d * left;
                }
                // d = 0 only at the last point with the end there: no term to move.
                jac[(k, q_at)] = if d > 0.0 { -term * d.ln() } else { 0.0 };
            }
        },
        &p0,
        t_ms.len(),
    )?;
    let p = fit.params.as_slice();
    let se_q = fit.covariance()?[(q_at, q_at)].sqrt();
    let law = Law {
        end: p[0],
        ln_c: p[1],
        remaining: remaining(p),
        q: p[q_at],
        se_q,
        ssr: fit.ssr,
    };
    (p.iter().all(|v| v.is_finite()) && law.q > 1.0 && se_q.is_finite()).then_some(law)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::stationary_energy_at;
    use crate::model::closed_form::stationary_rolling;
    use crate::model::params::Preset;
    use crate::rng::SplitMix64;

    /// Peak times of an exact power law in ψ: t_k = T − c (ψ_end − ψ_k)^q.
    fn law_times(n: f64, turns: usize, end: f64, c: f64, remaining: f64) -> (Vec<f64>, Vec<f64>) {
        let q = 1.0 / (1.0 - n / 2.0);
        let psi: Vec<f64> = (0..turns)
            .map(|k| -2.0 * PI * (turns - 1 - k) as f64)
            .collect();
        let t = psi
            .iter()
            .map(|&p| end - c * (remaining - p).powf(q))
            .collect();
        (t, psi)
    }

    /// An exact law is recovered exactly, whatever the origin of t and ψ.
    #[test]
    fn the_law_of_the_turns_gives_n_back() {
        for n in [0.33, 0.5, 0.66, 0.89] {
            // About 25 turns over the last 0.5 s, the last 3 ms before the end.
            let q = 1.0 / (1.0 - n / 2.0);
            let c = 0.5 / (2.0 * PI * 25.0_f64).powf(q);
            let (t, psi) = law_times(n, 25, 0.003, c, 0.9);
            let psi: Vec<f64> = psi.iter().map(|p| p + 17.0).collect();
            let fit = fit_turn_timing(&t, &psi).expect("fit");
            assert!((fit.n - n).abs() < 1e-6, "n = {} for {n}", fit.n);
            assert!((fit.t_end - 0.003).abs() < 1e-8, "T = {}", fit.t_end);
            assert!((fit.remaining_psi - 0.9).abs() < 1e-5);
            for (&tk, go) in t.iter().zip(fit.psi_to_go()) {
                assert!((fit.t_end - fit.time_to_go(go) - tk).abs() < 1e-8);
            }
        }
    }

    /// Turning points half a turn apart whose times are read to 0.3 ms (a seventh of a
    /// frame at 480 fps), each error shared with the next point's (a moving average of
    /// two draws, correlation 0.5, as neighbouring local fits share frames): the 95 %
    /// interval covers the true n in 90–99 % of 200 draws, and T's errors are about
    /// its jackknife standard error, RMS.
    #[test]
    fn the_interval_covers_the_true_n() {
        let mut rng = SplitMix64::new(11);
        let mut covered = 0;
        let mut end_z2 = 0.0;
        let draws = 200;
        for _ in 0..draws {
            let n = rng.range(0.35, 0.8);
            let turns = 20 + (rng.uniform() * 10.0) as usize;
            let q = 1.0 / (1.0 - n / 2.0);
            let c = 0.5 / (TAU * turns as f64).powf(q);
            let (end, remaining) = (rng.range(0.0, 0.006), rng.range(0.2, 6.0));
            let psi: Vec<f64> = (0..2 * turns)
                .map(|k| -PI * (2 * turns - 1 - k) as f64)
                .collect();
            let mut previous = rng.gaussian();
            let t: Vec<f64> = psi
                .iter()
                .map(|&p| {
                    let draw = rng.gaussian();
                    let error = 3e-4 * (draw + previous) / 2.0_f64.sqrt();
                    previous = draw;
                    end - c * (remaining - p).powf(q) + error
                })
                .collect();
            let fit = fit_turn_timing(&t, &psi).expect("fit");
            if (fit.ci95_n.0..=fit.ci95_n.1).contains(&n) {
                covered += 1;
            }
            end_z2 += ((fit.t_end - end) / fit.se_t_end).powi(2);
        }
        let share = covered as f64 / draws as f64;
        assert!(
            (0.90..=0.99).contains(&share),
            "covered {covered} of {draws}"
        );
        // T's jackknife error is honest too: its errors are 0.94 of it, RMS.
        let end_rms_z = (end_z2 / draws as f64).sqrt();
        assert!(
            (0.75..=1.3).contains(&end_rms_z),
            "T's error / se_t_end RMS {end_rms_z}"
        );
    }

    /// The small-angle law against the disk's own stationary rolling (eq. 2.29
    /// corrected, eq. 3.8): the turns of E = A_e τ^n through φ = 0.025 … 0.0015 rad
    /// give n within 0.003 (the law reads it 0.001–0.002 low).
    #[test]
    fn stationary_rolling_gives_the_small_angle_law() {
        let disk = Preset::EulerDisk.params();
        for n in [0.4, 0.55, 0.7] {
            let window: f64 = 0.5;
            let a_e = stationary_energy_at(&disk, 0.025).expect("E") / window.powf(n);
            // φ at τ by bisection of E(φ) = A_e τ^n (E rises with φ here).
            let phi_at = |tau: f64| {
                let target = a_e * tau.powf(n);
                let (mut lo, mut hi) = (1e-9, 0.1);
                for _ in 0..100 {
                    let mid = 0.5 * (lo + hi);
                    if stationary_energy_at(&disk, mid).expect("E") < target {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                0.5 * (lo + hi)
            };
            // ψ(τ) = ∫₀^τ ψ̇ dτ' with τ' = u^{1/p}, p = 1 − n/2, which makes the
            // integrand ψ̇ τ'^{n/2}/p finite at u = 0: midpoint rule in u.
            let p = 1.0 - n / 2.0;
            let steps = 20_000;
            let u_end = window.powf(p);
            let du = u_end / steps as f64;
            let mut psi_of_u = vec![0.0];
            for i in 0..steps {
                let u = (i as f64 + 0.5) * du;
                let tau = u.powf(1.0 / p);
                let (psi_dot, _) = stationary_rolling(&disk, phi_at(tau)).expect("ψ̇");
                let integrand = psi_dot * tau.powf(n / 2.0) / p;
                psi_of_u.push(psi_of_u[i] + integrand * du);
            }
            // Peaks every 2π of ψ counted from the end, the last 2 ms before it.
            let total = psi_of_u[steps];
            let (mut t, mut psi) = (Vec::new(), Vec::new());
            let mut k = 0;
            for i in 1..=steps {
                let level = 2.0 * PI * k as f64 + 1.0;
                if psi_of_u[i] >= level && psi_of_u[i - 1] < level {
                    let f = (level - psi_of_u[i - 1]) / (psi_of_u[i] - psi_of_u[i - 1]);
                    let tau = ((i as f64 - 1.0 + f) * du).powf(1.0 / p);
                    t.push(-tau);
                    psi.push(-level);
                    k += 1;
                }
            }
            assert!(total > 2.0 * PI * 15.0, "{} turns", total / (2.0 * PI));
            t.reverse();
            psi.reverse();
            let fit = fit_turn_timing(&t, &psi).expect("fit");
            assert!(
                (fit.n - n).abs() < 0.003 && fit.n < n,
                "n = {:.4} for {n} from {} peaks",
                fit.n,
                t.len()
            );
        }
    }

    #[test]
    fn too_few_points_are_refused() {
        let (t, psi) = law_times(0.5, 7, 0.0, 1e-3, 1.0);
        assert_eq!(
            fit_turn_timing(&t, &psi),
            Err(TurnTimingError::TooFewPoints {
                found: 7,
                needed: MIN_POINTS
            })
        );
    }
}
