//! One model of the motion fitted to every frame of the window: a fourth estimate of
//! n beside the two fits of eq. (3.2) and the turns' timing, and the halt t0 placed by
//! every height at once.
//!
//! Near the halt the disk rolls stationarily. Its energy E = A_e τ^n (eq. 3.2,
//! τ = t0 − t) is E ≈ (3/2) m g R φ as φ → 0 (eq. 3.8), so the nutation follows
//! φ = Φ τ^n; and its precession follows the turns' timing law
//! ([`crate::turn_timing`]), τ = c (ψ_end − ψ)^q. The camera's profile of the rim
//! ([`crate::signal::RimModel`]) turns the two into the height of every frame:
//!
//! ```text
//! z(t) = z_rim(Φ τ^n, ψ_end − (τ/c)^{1/q}) + z0   (t < t0),    z(t) = z0   (t ≥ t0),
//! ```
//!
//! with ψ ≡ 0 mod 2π at the crests (the raised side facing the camera). Its
//! parameters (Φ, n, t0, c, q, ψ_end, z0, and the codec's α below) are fitted by least squares to the heights
//! of the window and of the rest just after it. No peak, threshold or halt rule enters:
//! the crests are where the fitted phase puts them, including a last one that the
//! frames straddle or the codec shaved, and t0 is where the fitted motion ends. The
//! timing law keeps its own exponent q, so a precession that departs from the
//! stationary rate (the model's or the disk's) moves q, not n.
//!
//! A codec smooths the heights over time: it codes each picture from its neighbours,
//! and what it leaves out of a fast swing reads the crests low and the troughs high,
//! the more so the shorter the turn. The fit models it as z + α z″, z″ the heights'
//! second difference over one frame (the form `scripts/check-footage` measures against
//! the truth, 0.01–0.06 frame² on the open footage's H.264), with α an eighth
//! parameter: the turns shorten across the window, so a smoothing and a steeper decay
//! of φ are told apart. Without it n reads high as the peaks fit's does.
//!
//! What it does not model: φ oscillating about stationary rolling. Its standard errors
//! are the least-squares ones, s² (JᵀJ)⁻¹, which take the frames' errors as
//! independent: they are shared over a turn, so the errors are too small to be an
//! interval, and none is given.

use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

use crate::numeric::lsq::{LsqFit, levenberg_marquardt};
use crate::numeric::median;
use crate::signal::RimModel;
use crate::turn_timing::TurnTimingFit;

/// Rest after t0 fitted with the motion \[s\]: ten frames at 480 fps, which fix z0
/// and the end of the motion.
const REST_AFTER_S: f64 = 0.02;
/// Standard errors of t0 by which a crest the motion places must come before its end
/// ([`MotionFit::unresolved_crests`]).
const CREST_BEFORE_END_SE: f64 = 2.0;
/// Restarts of a fit that stopped before converging ([`settled_fit`]).
const RESTARTS: usize = 2;
/// Fewest heights the model is fitted to.
const MIN_FRAMES: usize = 40;
/// Central-difference steps of the Jacobian, per parameter (ln Φ, n, t0 \[s\], ln c,
/// q, ψ_end \[rad\], z0 \[px\], α \[frame²\]).
const STEPS: [f64; 8] = [1e-6, 1e-6, 1e-6, 1e-6, 1e-7, 1e-6, 1e-6, 1e-6];

/// The motion fitted to every frame of the window.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MotionFit {
    /// The energy's exponent n (φ = Φ τ^n).
    pub n: f64,
    /// Least-squares standard error of n (independent frames: too small, see the
    /// module docs).
    pub se_n: f64,
    /// When the motion ends, halt at t = 0 \[s\].
    pub t0: f64,
    /// Least-squares standard error of t0 \[s\].
    pub se_t0: f64,
    /// Φ of φ = Φ τ^n \[rad s^−n\].
    pub phi_scale: f64,
    /// q and c of the timing law τ = c (ψ_end − ψ)^q.
    pub q: f64,
    pub c: f64,
    /// ψ where the motion ends, crests at ψ ≡ 0 mod 2π \[rad\].
    pub psi_end: f64,
    /// The heights' zero z0 \[px\].
    pub zero_px: f64,
    /// The codec's smoothing over time, α of z + α z″ (z″ the second difference over
    /// a frame) \[frame²\], and its least-squares standard error; `None` where the fit
    /// with it left the motion's ([`Motion::sane_beside`]), and in results written
    /// before it was fitted.
    #[serde(default)]
    pub codec_smoothing: Option<f64>,
    #[serde(default)]
    pub se_codec_smoothing: Option<f64>,
    /// RMS of the heights about the model \[px\].
    pub residual_rms_px: f64,
    /// Heights fitted.
    pub frames: usize,
    /// The model's crests in the window, in time order, halt at t = 0 \[s\].
    pub crests: Vec<f64>,
    /// The crests after the last one the frames resolved that rise above the halt's
    /// motion threshold ([`MotionFit::unresolved_crests`]); empty in results written
    /// before they were recorded.
    #[serde(default)]
    pub unresolved_crests: Vec<PlacedCrest>,
}

/// A crest of z_rim the fitted motion places where the frames resolve none.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlacedCrest {
    /// Its time, halt at t = 0 \[s\].
    pub t: f64,
    /// φ there, Φ τ^n \[rad\].
    pub phi: f64,
    /// Its height above the zero, z_rim(φ, 0) \[m\].
    pub z_m: f64,
}

impl MotionFit {
    /// The model's crests after `after` and before t0 by more than
    /// [`CREST_BEFORE_END_SE`] standard errors of t0, whose height at their top,
    /// z_rim(Φ τ^n, 0) for the profile `model`, exceeds `threshold_m`: the motion the
    /// halt detector takes for motion when it sees it. The last turns last a few frames
    /// and end at the halt, so the frames can straddle a final crest or the codec can
    /// shave it below the prominence the peaks need; where the motion fitted to every
    /// frame puts one high enough to be seen, it is a crest of the motion. One lower is
    /// not claimed, nor one so near the fitted end that the motion may have ended
    /// before it.
    pub fn unresolved_crests(
        &self,
        after: f64,
        model: &dyn RimModel,
        threshold_m: f64,
    ) -> Vec<PlacedCrest> {
        self.crests
            .iter()
            .filter(|&&t| t > after && t < self.t0 - CREST_BEFORE_END_SE * self.se_t0)
            .map(|&t| {
                let phi = self.phi_scale * (self.t0 - t).powf(self.n);
                PlacedCrest {
                    t,
                    phi,
                    z_m: model.z_rim(phi, 0.0),
                }
            })
            .filter(|c| c.z_m > threshold_m)
            .collect()
    }
}

/// The parameters in the fit's own scale: p = (ln Φ, n, t0, ln c, q, ψ_end, z0, α).
struct Motion {
    phi_scale: f64,
    n: f64,
    t0: f64,
    c: f64,
    q: f64,
    psi_end: f64,
    zero_px: f64,
    smoothing: f64,
}

impl Motion {
    fn from_params(p: &[f64]) -> Self {
        Motion {
            phi_scale: p[0].exp(),
            n: p[1],
            t0: p[2],
            c: p[3].exp(),
            q: p[4],
            psi_end: p[5],
            zero_px: p[6],
            smoothing: p.get(7).copied().unwrap_or(0.0),
        }
    }

    fn params(&self) -> [f64; 8] {
        [
            self.phi_scale.ln(),
            self.n,
            self.t0,
            self.c.ln(),
            self.q,
            self.psi_end,
            self.zero_px,
            self.smoothing,
        ]
    }

    /// The height at `t` as the codec shows it \[px\]: the motion's, low-passed over
    /// time by α times its second difference over one frame `frame_s`.
    fn coded_height(&self, model: &dyn RimModel, metres_per_px: f64, frame_s: f64, t: f64) -> f64 {
        let at = |x: f64| self.height(model, metres_per_px, x);
        let here = at(t);
        here + self.smoothing * (at(t + frame_s) - 2.0 * here + at(t - frame_s))
    }

    /// The height at `t` \[px\] for the profile `model` at `metres_per_px`.
    fn height(&self, model: &dyn RimModel, metres_per_px: f64, t: f64) -> f64 {
        let tau = self.t0 - t;
        if tau <= 0.0 {
            return self.zero_px;
        }
        let phi = self.phi_scale * tau.powf(self.n);
        let chi = self.psi_end - (tau / self.c).powf(1.0 / self.q);
        model.z_rim(phi, chi) / metres_per_px + self.zero_px
    }

    /// The crests (ψ ≡ 0 mod 2π) from `from` up to t0, in time order.
    fn crests(&self, from: f64) -> Vec<f64> {
        let mut crests = Vec::new();
        let mut k = (self.psi_end / TAU).floor();
        loop {
            let tau = self.c * (self.psi_end - TAU * k).powf(self.q);
            if !(tau.is_finite() && self.t0 - tau >= from) {
                break;
            }
            if tau > 0.0 {
                crests.push(self.t0 - tau);
            }
            k -= 1.0;
        }
        crests.reverse();
        crests
    }

    /// Whether this motion, fitted with the codec's smoothing from `still`, stays a
    /// motion and ends within the window's last turn of it: a smoothing that took the
    /// fit elsewhere is not the codec's.
    fn sane_beside(&self, still: &LsqFit) -> bool {
        let still = Motion::from_params(still.params.as_slice());
        let last_turn = still.c * TAU.powf(still.q);
        self.sane() && (self.t0 - still.t0).abs() < last_turn && self.smoothing.abs() < 0.5
    }

    fn sane(&self) -> bool {
        self.n > 0.0 && self.n < 2.0 && self.q > 1.0 && self.phi_scale > 0.0 && self.c > 0.0
    }
}

/// A clip's rim heights: times t (halt at t = 0) \[s\] and z_rim \[px\] (NaN where no
/// edge was read), and the scale they were read at \[m/px\].
pub struct Heights<'a> {
    pub t: &'a [f64],
    pub z_px: &'a [f64],
    pub metres_per_px: f64,
    /// The capture's frame interval \[s\].
    pub frame_s: f64,
}

impl Heights<'_> {
    /// The times and heights read from `from` to `to` \[s\].
    fn between(&self, from: f64, to: f64) -> (Vec<f64>, Vec<f64>) {
        (self.t.iter().zip(self.z_px))
            .filter(|&(&x, z)| x >= from && x <= to && z.is_finite())
            .map(|(&x, &z)| (x, z))
            .unzip()
    }
}

/// ∂r/∂p by central differences of `residuals` at `p`, steps [`STEPS`], into `jac`.
fn central_differences(
    residuals: &impl Fn(&[f64], &mut [f64]),
    p: &[f64],
    jac: &mut nalgebra::DMatrix<f64>,
) {
    let count = jac.nrows();
    let (mut plus, mut minus) = (vec![0.0; count], vec![0.0; count]);
    for (j, h) in STEPS.iter().enumerate().take(p.len()) {
        let mut q = p.to_vec();
        q[j] = p[j] + h;
        residuals(&q, &mut plus);
        q[j] = p[j] - h;
        residuals(&q, &mut minus);
        for i in 0..count {
            jac[(i, j)] = (plus[i] - minus[i]) / (2.0 * h);
        }
    }
}

/// The motion fitted to the `heights` over the `window_s` before the timing law's end
/// and [`REST_AFTER_S`] after it, with the camera's profile `model`. Started from the
/// turns' timing law `timing` (t0, c, q, ψ_end) and the peaks' tilt `peaks` ((t, φ)
/// pairs) with the exponent `n0`. `None` when too few heights lie in the window or
/// the fit does not settle on a motion.
pub fn fit_motion(
    heights: &Heights,
    model: &dyn RimModel,
    timing: &TurnTimingFit,
    peaks: &[(f64, f64)],
    n0: f64,
    window_s: f64,
) -> Option<MotionFit> {
    let (metres_per_px, frame_s) = (heights.metres_per_px, heights.frame_s);
    let start = starting_motion(timing, peaks, n0)?;
    let from = start.t0 - window_s;
    let (times, heights) = heights.between(from, start.t0 + REST_AFTER_S);
    if times.len() < MIN_FRAMES {
        return None;
    }
    let residuals = |p: &[f64], out: &mut [f64]| {
        let motion = Motion::from_params(p);
        for (o, (&x, &z)) in out.iter_mut().zip(times.iter().zip(&heights)) {
            *o = motion.coded_height(model, metres_per_px, frame_s, x) - z;
        }
    };
    let jacobian = |p: &[f64], jac: &mut nalgebra::DMatrix<f64>| {
        central_differences(&residuals, p, jac);
    };
    // The motion first, then with the codec's smoothing from there: α and a steeper
    // decay of φ are told apart only near the motion's own optimum.
    let still = settled_fit(&residuals, &jacobian, &start.params()[..7], times.len())?;
    let smoothed = {
        let mut p = still.params.as_slice().to_vec();
        p.push(0.0);
        settled_fit(&residuals, &jacobian, &p, times.len())
    };
    let fit = match smoothed {
        Some(f) if Motion::from_params(f.params.as_slice()).sane_beside(&still) => f,
        _ => still,
    };
    let motion = Motion::from_params(fit.params.as_slice());
    if !motion.sane() {
        return None;
    }
    let covariance = fit.covariance()?;
    let smoothing = (fit.params.len() == 8).then(|| (motion.smoothing, covariance[(7, 7)].sqrt()));
    Some(MotionFit {
        n: motion.n,
        se_n: covariance[(1, 1)].sqrt(),
        t0: motion.t0,
        se_t0: covariance[(2, 2)].sqrt(),
        phi_scale: motion.phi_scale,
        q: motion.q,
        c: motion.c,
        psi_end: motion.psi_end,
        zero_px: motion.zero_px,
        codec_smoothing: smoothing.map(|s| s.0),
        se_codec_smoothing: smoothing.map(|s| s.1),
        residual_rms_px: (fit.ssr / times.len() as f64).sqrt(),
        frames: times.len(),
        crests: motion.crests(from),
        unresolved_crests: Vec::new(),
    })
}

/// The least-squares fit from `p0`, restarted from where it stopped when it did not
/// converge. Each frame's height has a slope ∝ τ^(n−1) in t0 that grows without bound
/// as the frame nears the halt, so the sum of squares has a kink wherever a frame
/// crosses t0, and the search can stop there with no step lowering it though the
/// gradient is not yet small: a fit that a restart cannot move is taken at that
/// point. `None` when the fit fails or the restarts keep moving it.
fn settled_fit(
    residuals: &impl Fn(&[f64], &mut [f64]),
    jacobian: &impl Fn(&[f64], &mut nalgebra::DMatrix<f64>),
    p0: &[f64],
    count: usize,
) -> Option<LsqFit> {
    let mut fit = levenberg_marquardt(residuals, jacobian, p0, count)?;
    for _ in 0..RESTARTS {
        if fit.converged {
            return Some(fit);
        }
        let again = levenberg_marquardt(residuals, jacobian, fit.params.as_slice(), count)?;
        if again.ssr >= fit.ssr {
            return Some(fit);
        }
        fit = again;
    }
    fit.converged.then_some(fit)
}

/// The start: the timing law's t0, c, q and ψ_end, and Φ the median of φ_k τ_k^−n0
/// over the `peaks` before that t0.
fn starting_motion(timing: &TurnTimingFit, peaks: &[(f64, f64)], n0: f64) -> Option<Motion> {
    let t0 = timing.t_end;
    let scales: Vec<f64> = peaks
        .iter()
        .filter(|&&(tk, phi)| tk < t0 && phi > 0.0)
        .map(|&(tk, phi)| (phi.ln() - n0 * (t0 - tk).ln()).exp())
        .collect();
    if scales.is_empty() {
        return None;
    }
    Some(Motion {
        phi_scale: median(&scales),
        n: n0,
        t0,
        c: timing.c,
        q: 1.0 / (1.0 - timing.n / 2.0),
        psi_end: timing.psi.last()? + timing.remaining_psi,
        zero_px: 0.0,
        smoothing: 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;
    use crate::signal::ThesisRim;

    const FRAME: f64 = 1.0 / 480.0;
    const METRES_PER_PX: f64 = 6.5e-5;

    /// A disk of R = 38.1 mm rolling stationarily to a halt at t0 = 0.7 ms (off the
    /// frames' grid): φ = Φ τ^n, its turns on the timing law with q = 1/(1 − n/2),
    /// read at 480 fps with 0.05 px of noise, low-passed over time by `smoothing`
    /// (α of z + α z″).
    fn clip(n: f64, seed: u64, smoothing: f64) -> (Vec<f64>, Vec<f64>, Motion) {
        let q = 1.0 / (1.0 - n / 2.0);
        let truth = Motion {
            phi_scale: 0.0155 / 0.5f64.powf(n),
            n,
            t0: 0.0007,
            // 25 turns over the last 0.5 s.
            c: 0.5 / (25.0 * TAU).powf(q),
            q,
            psi_end: 1.3,
            zero_px: 0.0,
            smoothing,
        };
        let model = ThesisRim { radius: 0.0381 };
        let mut rng = SplitMix64::new(seed);
        let t: Vec<f64> = (0..330).map(|i| -0.6 + i as f64 * FRAME).collect();
        let z = t
            .iter()
            .map(|&x| truth.coded_height(&model, METRES_PER_PX, FRAME, x) + 0.05 * rng.gaussian())
            .collect();
        (t, z, truth)
    }

    /// The turns' timing law as fitted to a clip: its end 1.5 ms late, its exponent
    /// and phase a little off.
    fn timing_start(truth: &Motion) -> TurnTimingFit {
        let n = 2.0 * (1.0 - 1.0 / truth.q) + 0.01;
        TurnTimingFit {
            n,
            ci95_n: (n - 0.01, n + 0.01),
            se_n: 0.005,
            se_n_least_squares: 0.005,
            se_n_jackknife: 0.005,
            t_end: truth.t0 + 0.0015,
            se_t_end: 0.001,
            remaining_psi: truth.psi_end.rem_euclid(TAU) + 0.3,
            c: truth.c * 1.02,
            times: vec![],
            psi: vec![0.0],
            points: 50,
            residual_rms_s: 1e-4,
        }
    }

    /// The last crest, less than two frames before the halt, is placed after the one
    /// before it when it rises above the threshold at its top, and not when it does
    /// not; none is placed after the halt.
    #[test]
    fn a_final_crest_is_placed_only_above_the_threshold() {
        let (t, z, truth) = clip(0.5, 4, 0.0);
        let crests = truth.crests(-0.5);
        let (before, last) = (crests[crests.len() - 2], crests[crests.len() - 1]);
        let model = ThesisRim { radius: 0.0381 };
        let peaks: Vec<(f64, f64)> = crests
            .iter()
            .map(|&tk| (tk, truth.phi_scale * (truth.t0 - tk).powf(0.5)))
            .collect();
        let heights = Heights {
            t: &t,
            z_px: &z,
            metres_per_px: METRES_PER_PX,
            frame_s: FRAME,
        };
        let fit =
            fit_motion(&heights, &model, &timing_start(&truth), &peaks, 0.5, 0.5).expect("fit");
        let top = model.z_rim(truth.phi_scale * (truth.t0 - last).powf(0.5), 0.0);
        let placed = fit.unresolved_crests(before + 1e-3, &model, 0.5 * top);
        assert_eq!(placed.len(), 1, "{placed:?}");
        assert!((placed[0].t - last).abs() < 0.1 * FRAME);
        assert!(
            (placed[0].z_m / top - 1.0).abs() < 0.2,
            "{} vs {top}",
            placed[0].z_m
        );
        assert!(
            fit.unresolved_crests(before + 1e-3, &model, 2.0 * top)
                .is_empty()
        );
        assert!(fit.unresolved_crests(fit.t0, &model, 0.0).is_empty());
    }

    /// Started from a timing law 1.5 ms late and the peaks' tilt, with the heights
    /// low-passed by α = 0, 0.03 and 0.015 frame², the fit recovers n within 0.005, α
    /// within 0.01 and t0 within a fifth of a frame and three of its standard errors
    /// (0.07–0.12 ms at 0.05 px of noise), and puts every crest of the window within a
    /// tenth of a frame, the last one, less than two frames before the halt, within a
    /// quarter.
    #[test]
    fn the_motion_is_recovered_from_every_frame() {
        for (n, seed, smoothing) in [(0.45, 1, 0.0), (0.6, 2, 0.03), (0.7, 3, 0.015)] {
            let (t, z, truth) = clip(n, seed, smoothing);
            let peaks: Vec<(f64, f64)> = truth
                .crests(-0.5)
                .iter()
                .map(|&tk| (tk, 1.03 * truth.phi_scale * (truth.t0 - tk).powf(n)))
                .collect();
            let model = ThesisRim { radius: 0.0381 };
            let start = timing_start(&truth);
            let heights = Heights {
                t: &t,
                z_px: &z,
                metres_per_px: METRES_PER_PX,
                frame_s: FRAME,
            };
            let fit = fit_motion(&heights, &model, &start, &peaks, n + 0.02, 0.5).expect("fit");
            assert!((fit.n - n).abs() < 0.005, "n {} vs {n}", fit.n);
            let alpha = fit.codec_smoothing.expect("α fitted");
            assert!((alpha - smoothing).abs() < 0.01, "α {alpha} vs {smoothing}");
            let t0_error = fit.t0 - truth.t0;
            assert!(
                t0_error.abs() < 0.2 * FRAME,
                "t0 {} vs {}",
                fit.t0,
                truth.t0
            );
            assert!(
                t0_error.abs() < 3.0 * fit.se_t0,
                "{t0_error} vs se {}",
                fit.se_t0
            );
            let true_crests = truth.crests(fit.t0 - 0.5 + FRAME);
            let last = *true_crests.last().expect("crests");
            assert!(
                truth.t0 - last < 2.0 * FRAME,
                "the last crest is near the halt"
            );
            for tc in true_crests {
                let nearest = fit
                    .crests
                    .iter()
                    .map(|&c| (c - tc).abs())
                    .fold(f64::INFINITY, f64::min);
                // The final crest, within two frames of the halt, turns in a frame.
                let tolerance = if truth.t0 - tc < 2.0 * FRAME {
                    0.25
                } else {
                    0.1
                };
                assert!(nearest < tolerance * FRAME, "crest at {tc}: {nearest}");
            }
        }
    }
}
