//! Camera shake: the picture's motion in the image plane of a camera on a vibrating
//! tripod or held by hand (issue 72 §1), with its exact truth.
//!
//! # The model
//!
//! [`Shake`] describes three motions, each a sum of sinusoids whose phases (and the
//! vibration's frequencies within its band) are drawn from the render's seed
//! ([`ShakeMotion::new`]), t the clip time (the first captured frame at 0):
//!
//! ```text
//! dx(t) = Σ_k A sin(2π f_x,k t + p_x,k) + S sin(2π f_s t + q_x)      [px]
//! dy(t) = Σ_k A sin(2π f_y,k t + p_y,k) + S sin(2π f_s t + q_y)      [px]
//! ρ(t)  = P sin(2π f_s t + q_ρ)                                      [deg]
//! ```
//!
//! * the **vibration**: K = 8 sinusoids per axis with equal amplitudes A = σ √(2/K),
//!   so that each axis's RMS (over a long clip) is σ = [`Shake::vibration_rms_px`];
//!   the band [f_lo, f_hi] ([`Shake::vibration_band_hz`]) is cut into K equal
//!   strata and f_k is drawn in the middle half of stratum k, so that no two
//!   frequencies are closer than (f_hi − f_lo)/2K. A band of one frequency
//!   (f_lo = f_hi) is one sinusoid per axis of amplitude σ √2;
//! * the **sway**: one sinusoid per axis of peak amplitude S = [`Shake::sway_px`]
//!   at f_s = [`Shake::sway_hz`];
//! * the **roll** about the optical axis: peak P = [`Shake::roll_deg`] at the sway's
//!   frequency.
//!
//! # What it does to the picture, and the signs
//!
//! The camera is shaken, not the scene: the image point p0 = (x, row) of the still
//! camera is seen at
//!
//! ```text
//! p = c + (dx, dy) + R(ρ) (p0 − c),    R(ρ) (u, v) = (u cos ρ + v sin ρ, −u sin ρ + v cos ρ)
//! ```
//!
//! with c the side view's principal point (the image of the world origin, on the
//! plate under the disk's centre at rest). **dx > 0 moves the picture right, dy > 0
//! moves it down (rows grow downward), ρ > 0 turns it counter-clockwise as
//! displayed.** The renderer shifts each view's principal point by (dx, dy) and turns
//! the image coordinates of its rays by ρ about c (so a two-view frame moves as one
//! picture; each view keeps its rows). For an orthographic camera the shift is a
//! translation of the camera across its line of sight; for a pinhole it is, to first
//! order in the angle, what a small rotation of the camera does to the picture.
//! Either way the disk's heights above the plate are what they were: the truth's
//! z_rim and calibration are the still camera's, and [`ShakeOffset`] records the
//! shake at each frame's capture time (mid-exposure).

use serde::{Deserialize, Serialize};

use crate::rng::SplitMix64;

/// Camera shake (see the module docs): a vibration, a slow sway and a roll, drawn
/// from the render's seed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Shake {
    /// RMS of the vibration's displacement along each image axis \[px\] (over a long
    /// clip; the RMS length of the 2-D displacement is √2 times this).
    pub vibration_rms_px: f64,
    /// The band the vibration's frequencies are drawn in, [low, high] \[Hz\].
    pub vibration_band_hz: [f64; 2],
    /// Peak amplitude of the sway along each image axis \[px\].
    pub sway_px: f64,
    /// Frequency of the sway and of the roll \[Hz\].
    pub sway_hz: f64,
    /// Peak roll about the optical axis \[deg\], at the sway's frequency.
    pub roll_deg: f64,
}

impl Shake {
    /// The vibration's band by default \[Hz\]: a tripod's legs and a hand's tremor.
    pub const DEFAULT_BAND_HZ: [f64; 2] = [20.0, 80.0];
    /// The sway's frequency by default \[Hz\].
    pub const DEFAULT_SWAY_HZ: f64 = 1.0;
    /// Sinusoids per axis in the vibration.
    pub const VIBRATION_WAVES: usize = 8;

    /// Whether it moves the picture at all.
    pub fn is_still(&self) -> bool {
        self.vibration_rms_px == 0.0 && self.sway_px == 0.0 && self.roll_deg == 0.0
    }
}

impl Default for Shake {
    fn default() -> Self {
        Shake {
            vibration_rms_px: 0.0,
            vibration_band_hz: Self::DEFAULT_BAND_HZ,
            sway_px: 0.0,
            sway_hz: Self::DEFAULT_SWAY_HZ,
            roll_deg: 0.0,
        }
    }
}

/// The camera's shake at one instant (see the module docs for the signs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ShakeOffset {
    /// Shift of the picture along the image's x \[px\], > 0 to the right.
    pub dx_px: f64,
    /// Shift of the picture along the rows \[px\], > 0 downward.
    pub dy_px: f64,
    /// Roll of the picture about the principal point \[deg\], > 0 counter-clockwise
    /// as displayed (0 without roll).
    pub roll_deg: f64,
}

/// One sinusoid: amplitude, frequency \[Hz\], phase \[rad\].
#[derive(Debug, Clone, Copy, PartialEq)]
struct Wave {
    amplitude: f64,
    hz: f64,
    phase: f64,
}

impl Wave {
    fn at(&self, t: f64) -> f64 {
        self.amplitude * (std::f64::consts::TAU * self.hz * t + self.phase).sin()
    }
}

/// Salt of the shake's generator, so that its draws are apart from the noise's.
const SHAKE_STREAM: u64 = 0x5348_414b_4531;

/// A [`Shake`] drawn from a seed: its sinusoids.
#[derive(Debug, Clone, PartialEq)]
pub struct ShakeMotion {
    x: Vec<Wave>,
    y: Vec<Wave>,
    roll: Wave,
}

impl ShakeMotion {
    /// The shake's sinusoids drawn from `seed` (the render's): for x, then y, the
    /// vibration's frequencies and phases, then the sway's phase; then the roll's
    /// phase. The draws do not depend on the amplitudes.
    pub fn new(shake: &Shake, seed: u64) -> Self {
        let mut rng = SplitMix64::new(seed ^ SHAKE_STREAM);
        let [lo, hi] = shake.vibration_band_hz;
        let k = if hi > lo { Shake::VIBRATION_WAVES } else { 1 };
        let amplitude = shake.vibration_rms_px * (2.0 / k as f64).sqrt();
        let tau = std::f64::consts::TAU;
        let axis = |rng: &mut SplitMix64| {
            let mut waves: Vec<Wave> = (0..Shake::VIBRATION_WAVES)
                .map(|i| {
                    let u = rng.uniform();
                    let phase = rng.range(0.0, tau);
                    Wave {
                        amplitude,
                        hz: lo + (hi - lo) * (i as f64 + 0.25 + 0.5 * u) / k as f64,
                        phase,
                    }
                })
                .take(k)
                .collect();
            // The draws of the waves not used keep the sway's phase where it was.
            for _ in k..Shake::VIBRATION_WAVES {
                rng.uniform();
                rng.uniform();
            }
            waves.push(Wave {
                amplitude: shake.sway_px,
                hz: shake.sway_hz,
                phase: rng.range(0.0, tau),
            });
            waves
        };
        let x = axis(&mut rng);
        let y = axis(&mut rng);
        let roll = Wave {
            amplitude: shake.roll_deg,
            hz: shake.sway_hz,
            phase: rng.range(0.0, tau),
        };
        ShakeMotion { x, y, roll }
    }

    /// The shake at clip time `t` \[s\] (the first captured frame at 0).
    pub fn at(&self, t: f64) -> ShakeOffset {
        ShakeOffset {
            dx_px: self.x.iter().map(|w| w.at(t)).sum(),
            dy_px: self.y.iter().map(|w| w.at(t)).sum(),
            roll_deg: self.roll.at(t),
        }
    }
}

/// A roll of the picture by ρ about `centre` (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Roll {
    /// The point the picture turns about \[px\].
    pub centre: (f64, f64),
    sin: f64,
    cos: f64,
}

impl Roll {
    /// A turn by `deg` about `centre`; `None` for no turn.
    pub fn new(centre: (f64, f64), deg: f64) -> Option<Self> {
        (deg != 0.0).then(|| {
            let (sin, cos) = deg.to_radians().sin_cos();
            Roll { centre, sin, cos }
        })
    }

    /// Where the turned picture shows the point `(x, row)` of the picture before.
    pub fn apply(&self, x: f64, row: f64) -> (f64, f64) {
        let (u, v) = (x - self.centre.0, row - self.centre.1);
        (
            self.centre.0 + u * self.cos + v * self.sin,
            self.centre.1 - u * self.sin + v * self.cos,
        )
    }

    /// The point of the picture before that the turned picture shows at `(x, row)`.
    pub fn undo(&self, x: f64, row: f64) -> (f64, f64) {
        let (u, v) = (x - self.centre.0, row - self.centre.1);
        (
            self.centre.0 + u * self.cos - v * self.sin,
            self.centre.1 + u * self.sin + v * self.cos,
        )
    }
}
