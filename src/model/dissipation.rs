//! Dissipative (rolling-friction) moments of thesis §§4.4, 4.5 and 4.7.1.
//!
//! Every model is written in the form of eq. (4.5), `Q = −η N R q`, with the
//! components of `q` in the **body frame** B (ERRATA, text under eq. 4.10). In the
//! scaled units of eq. (4.21) (lengths in R, time in √(R/g), forces in mg) this is
//!
//! ```text
//! Q^B = −η n q^B,   n = N/(mg),
//! ```
//!
//! and the power of the moment is `Q·Ω = −η n q^B·Ω^B`, with the body-frame angular
//! velocity `Ω^B = (ψ̇ sin φ, −φ̇, ψ̇ cos φ + θ̇)` (§4.2). Every model here satisfies
//! `q^B·Ω^B ≥ 0` for every state (so it never injects energy), with equality only on
//! the model's discontinuity set; the tests check this.
//!
//! # Role
//!
//! The simulator in `src/model` ([`super::dynamics`]) calls [`Dissipation::q_body`]
//! at every right-hand-side evaluation, so `q_body` is allocation-free and cheap (a
//! few trigonometric functions and at most two `powf`). It also calls
//! [`Dissipation::discontinuity`] as an event function: the thesis ends the
//! integration when the trajectory reaches a codimension-1 discontinuity set (§4.3.1,
//! third terminal condition; eq. 4.60 for contour friction).
//!
//! On a discontinuity set the thesis's moment is set-valued (eq. 4.49); the thesis
//! disregards the dynamics there (§4.4: "rolling friction dissipates no energy when
//! the system is on the discontinuity set"). This module returns the element `q = 0`
//! there (`sign(0) = 0`), which keeps `q_body` finite everywhere except where the
//! model itself is singular (φ = 0 for the contour-like models).
//!
//! # Domain
//!
//! `φ ∈ (0, π/2)`. The contour-like models (contour, curvature-dependent offset,
//! the Hertzian models, augmented contour) are singular as φ → 0 by design (§4.4.4);
//! the simulator stops before φ = 0.
//!
//! # The offset models and their common form (eq. 4.62)
//!
//! A centre of pressure offset by `δ^I = (U, V, 0)` from the rigid contact point adds
//! the moment `δ × N` (eq. 4.61). With `N^I = (0, 0, n)`, `δ × N = n(V, −U, 0)^I`, and
//! with `R_IB` of eq. (4.1) this is `n(V cos φ, −U, −V sin φ)^B`. Its power is
//! `n(−V θ̇ sin φ + U φ̇)`, so the offset dissipates iff `V = v sign(θ̇)` and
//! `U = −u sign(φ̇)` with `u, v ≥ 0`, which is eq. (4.62):
//!
//! ```text
//! q^B = ( −v sign(θ̇) cos φ,  −u sign(φ̇),  v sign(θ̇) sin φ ),   q·Ω = v |θ̇| sin φ + u |φ̇|.
//! ```
//!
//! The models of §4.5 differ only in how the offsets `v(φ)` and `u(φ)` depend on φ:
//! `v = const` (4.63), `v = k_v / sin φ` (4.69), and `v = k_v φ^{p_v}`,
//! `u = k_u φ^{p_u}` for the Hertzian models (4.83, 4.87, 4.90, 4.92). The scale `k_v`
//! (a length divided by R, which for the Hertzian models carries `(3W/4E*)^{1/3}`,
//! `R_x`, `d_f`, `K`, … — material constants that only scale the moment) is folded
//! into η, as the thesis does ("v takes the place of η", after eq. 4.63; "k_v takes
//! the role of η", after eq. 4.69). What remains is the ratio `k_u/k_v`, exposed as
//! [`Dissipation::ku_over_kv`].
//!
//! # Energy exponents (Table 4.1)
//!
//! On the stationary-rolling manifold (eqs. 4.39–4.40) as φ → 0, `ψ̇² ≈ 1/(aφ)`,
//! `θ̇ ≈ −ψ̇`, `φ̇ = 0`, and `E ≈ (ch² + 3a)/(2a) φ` (eq. 4.96). For an offset model
//! with `v ∝ φ^p`, `Ė ∝ −v|θ̇| sin φ ∝ −φ^{p+1/2} ∝ −E^{p+1/2}`, whence
//! `E ∝ (t₀ − t)^n` with `n = 1/(1/2 − p)`: 2 (constant, p = 0), 2/3 (curvature and
//! contour, p = −1), 18/17 (Greenwood, p = −4/9), 1/0.924 (Brewe–Hamrock, p = −0.424),
//! 8/7 (Winkler, p = −3/8), 1 (cylinder, p = −1/2), and `1/(3/2 + p)` for augmented
//! contour (p → −1 − p). Classical, pivoting and general rolling give `Ė ∝ √φ`, n = 2.
//! The tests re-derive every one of these from `q_body` numerically.
//!
//! # Ambiguities resolved and typos found (beyond ERRATA.md)
//!
//! 1. **Hertzian moments: full eq. (4.62) form, not the printed small-angle vectors.**
//!    Eqs. (4.83), (4.87), (4.90), (4.92) print `(−k_v φ^p, −k_u φ^{p_u}, k_v φ^{p+1})`,
//!    i.e. eq. (4.62) with `v = k_v φ^p` *and* `cos φ → 1`, `sin φ → φ`. That
//!    small-angle vector is not dissipative at finite φ: its power is
//!    `k_v φ^p sign(θ̇)(ψ̇(φ cos φ − sin φ) + φ θ̇)`, negative e.g. at φ = 1, ψ̇ = 10,
//!    θ̇ = 0.1. Following ERRATA ("same content as eq. 4.62 with v = k_v φ^p") we keep
//!    the exact `cos φ`, `sin φ` of eq. (4.62) and multiply by `sign(θ̇)` (and the `u`
//!    term by `sign(φ̇)`, as in 4.62). Both forms agree to relative O(φ²) as φ → 0,
//!    so Table 4.1 is unaffected.
//! 2. **φ^p versus (sin φ)^p.** The contact formulas give powers of
//!    `κ_y = sin φ/(2R)` (plus corrections in `κ_y/κ_x`); the thesis then assumes
//!    small φ and prints `φ^p`. We use the printed `φ^p` (as ERRATA); the difference is
//!    relative O(φ²).
//! 3. **k_u.** The thesis sets `u = 0` (after eq. 4.62: the contact region is long and
//!    thin) and says `k_u = 0` is "a reasonable approximation" (after eq. 4.69), yet
//!    prints the `k_u` terms in 4.69–4.90. [`Dissipation::ku_over_kv`] defaults to 0
//!    (the thesis's choice); the cylinder model (4.92) has no `u` term at all. When
//!    `k_u ≠ 0`, `φ̇ = 0` is a second discontinuity set, but one that trajectories
//!    cross transversally twice per nutation oscillation (the jump in q_y is a tiny
//!    perturbation of gravity's restoring moment), so it is not reported by
//!    [`Dissipation::discontinuity`] (the simulator must not stop there).
//! 4. **Signs of the offsets.** The text after eq. (4.62) defines
//!    `U = uR sign(φ̇)`, `V = vR sign(−θ̇)`, and eq. (4.68) `U = k_u R sign(φ̇)`; the
//!    cross product above shows the printed moment (4.62) needs `V ∝ sign(θ̇)` (as
//!    eq. 4.68 and the sentence "if G moves in +y^I then V must be positive" say) and
//!    `U ∝ −sign(φ̇)`. The printed *moments* are right (dissipative), so we use them.
//! 5. **Eq. (4.81).** The factor `(R/(R_x sin φ))` in 4.81a and `(R_x sin φ/R)` in
//!    4.81b lack the exponent 1/3 (`a = c (κ_x/κ_y)^{1/3}`, `b = c (κ_y/κ_x)^{1/3}`
//!    from `c² = ab` and eq. 4.80); without it `a ∝ φ^{−10/9}`, contradicting the
//!    printed `∝ φ^{−4/9}`. Also, eq. (4.79) gives `16R²R_x²` rather than `2R²R_x²`
//!    inside the 1/9 power — a constant, folded into η.
//! 6. **Eq. (4.89b).** `b ∝ sin^{−1/8} φ` should read `sin^{+1/8} φ`: solving eq.
//!    (4.88), `δ² = d_f W/(Kπ√(R_x R_y)) ∝ sin^{1/2} φ`, so `b = (2δR_x)^{1/2} ∝
//!    sin^{1/8} φ`, consistent with the printed `∝ φ^{1/8}` and with eq. (4.90). The
//!    printed prefactor of 4.89b is right. (Tested: `hertzian_axes_follow_power_laws`.)
//! 7. **Eq. (4.84)** uses `R` for the effective radius `1/R = κ_y + κ_x` (not the disk
//!    radius) and `mg` in `a` but `W` in `b` (the same load). Constants only.
//! 8. **Eqs. (4.90), (4.92)** print `Q = +n(k_v φ^p, …, −k_v φ^{p+1})`, which expands
//!    to the same moment as 4.83's `−n(−k_v φ^p, …, k_v φ^{p+1})`; what matters is the
//!    missing `sign(θ̇)` (ERRATA), applied here.
//! 9. **Contour power.** From eq. (4.59), `q·Ω = sign(θ̇)(−cot φ · ψ̇ sin φ + ψ̇ cos φ
//!    + θ̇) = |θ̇|` — not `|θ̇|/sin φ`: the `1/sin φ` of "contour = classical with φ̇
//!    dropped, × 1/sin φ" cancels the `sin φ` of the classical power `|θ̇| sin φ`. This
//!    is what Table 4.1's `Ė ∝ 1/√E` requires (`|θ̇| ∝ φ^{−1/2}` on the stationary
//!    manifold; `|θ̇|/sin φ` would give `E^{−3/2}` and n = 2/5). Contour power is also
//!    the virtual power of a force `ηN` opposing the contour speed `R|θ̇|` (eq. 4.58).
//! 10. Table 4.1 prints the contour exponent as 0.67, §4.7.1 as 0.66; the exact value
//!     is 2/3, returned by [`Dissipation::analytic_exponent`].

use nalgebra::Vector3;

/// Angles and rates that a dissipative moment depends on, scaled units (time unit √(R/g)).
#[derive(Debug, Clone, Copy)]
pub struct Rates {
    /// Nutation angle φ (φ → 0 is flat), rad.
    pub phi: f64,
    /// φ̇.
    pub phi_dot: f64,
    /// Precession rate ψ̇.
    pub psi_dot: f64,
    /// Rotation (spin) rate θ̇.
    pub theta_dot: f64,
}

impl Rates {
    /// Body-frame angular velocity of the disk, `Ω^B = (ψ̇ sin φ, −φ̇, ψ̇ cos φ + θ̇)` (§4.2).
    pub fn omega_body(&self) -> Vector3<f64> {
        let (s, c) = self.phi.sin_cos();
        Vector3::new(
            self.psi_dot * s,
            -self.phi_dot,
            self.psi_dot * c + self.theta_dot,
        )
    }

    /// Horizontal (rolling) part of the angular velocity in the body frame: the
    /// components about `x^I` (`−θ̇ sin φ`) and `y^I` (`−φ̇`) of eq. (4.50), expressed
    /// in B with `x^I = (cos φ, 0, −sin φ)^B`: `(−θ̇ sin φ cos φ, −φ̇, θ̇ sin² φ)`, the
    /// vector of eq. (4.52). Its norm is `√(φ̇² + θ̇² sin² φ)`.
    fn horizontal_omega_body(&self) -> Vector3<f64> {
        let (s, c) = self.phi.sin_cos();
        Vector3::new(
            -self.theta_dot * s * c,
            -self.phi_dot,
            self.theta_dot * s * s,
        )
    }
}

/// Which dissipation model; a clap::ValueEnum + serde (kebab-case) so the CLI can name it.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum ModelKind {
    /// No dissipative moment, q = 0 (eq. 4.5 with η = 0 in effect).
    None,
    /// Classical rolling friction, eq. (4.53): a moment of constant modulus ηRN
    /// opposing the horizontal (rolling) angular velocity.
    ClassicalRolling,
    /// Viscous classical rolling, end of §4.4.1: eq. (4.52) without the square-root
    /// normalisation, a moment proportional to the horizontal angular velocity.
    ViscousRolling,
    /// Pivoting friction, eq. (4.55): a constant moment opposing the spin about the
    /// vertical, `ω_z^G = ψ̇ + θ̇ cos φ`.
    Pivoting,
    /// General rolling friction, eq. (4.56): a constant moment opposing the total
    /// angular velocity, q = Ω̂.
    GeneralRolling,
    /// Contour friction, eq. (4.59): resistance to the motion of the contact point
    /// along the rim; singular as φ → 0.
    Contour,
    /// Constant offset of the centre of pressure, eq. (4.63) (v folded into η).
    ConstantOffset,
    /// Curvature-dependent offset, eq. (4.69): offset ∝ the rim's radius of curvature
    /// R/sin φ seen by the plane; equals contour friction when k_u = 0.
    CurvatureOffset,
    /// Hertzian contact, Greenwood's equivalent-circle approximation, eq. (4.83):
    /// offset ∝ semi-axis a ∝ φ^(−4/9).
    Greenwood,
    /// Hertzian contact, Brewe–Hamrock approximation, eq. (4.87): offset ∝ φ^(−0.424).
    BreweHamrock,
    /// Winkler elastic-foundation (mattress) contact, eq. (4.90): offset ∝ φ^(−3/8).
    Winkler,
    /// Two-dimensional cylindrical (line) contact, eq. (4.92): offset ∝ φ^(−1/2).
    Cylinder,
    /// Augmented contour friction, §4.7.1: contour friction × φ^(−p), p = 0.722,
    /// tuned to the experimental energy exponent n = 0.45.
    AugmentedContour,
}

impl ModelKind {
    /// Every model, in the order of the thesis.
    pub const ALL: [ModelKind; 13] = [
        ModelKind::None,
        ModelKind::ClassicalRolling,
        ModelKind::ViscousRolling,
        ModelKind::Pivoting,
        ModelKind::GeneralRolling,
        ModelKind::Contour,
        ModelKind::ConstantOffset,
        ModelKind::CurvatureOffset,
        ModelKind::Greenwood,
        ModelKind::BreweHamrock,
        ModelKind::Winkler,
        ModelKind::Cylinder,
        ModelKind::AugmentedContour,
    ];

    /// The η the thesis gives for this model, when it gives one: 2.43e-4 for contour
    /// friction (§4.7), 1.1e-5 for augmented contour friction (§4.7.1); the other
    /// models' η are tuned to an end time (Table 4.1, [`super::tuning::TABLE_4_1`]).
    pub fn thesis_eta(self) -> Option<f64> {
        match self {
            ModelKind::Contour => Some(2.43e-4),
            ModelKind::AugmentedContour => Some(1.1e-5),
            _ => None,
        }
    }

    /// For the offset models (eq. 4.62): the exponent `p_v` of `v ∝ φ^{p_v}` and
    /// `p_u` of `u ∝ φ^{p_u}` (None for models without a `u` term).
    ///
    /// * Greenwood (§4.5.3.1): `c² = ab`, `c ∝ R_e^{1/3}` (4.78),
    ///   `R_e = (κ_y κ_x (κ_y + κ_x)/2)^{−1/3}` (4.79) `≈ (κ_y κ_x²/2)^{−1/3}` for
    ///   `κ_y = sin φ/(2R) ≪ κ_x = 1/(2R_x)`, so `c ∝ κ_y^{−1/9}`; with
    ///   `b/a = (κ_y/κ_x)^{2/3}` (4.80), `a = c (κ_x/κ_y)^{1/3} ∝ κ_y^{−4/9}` and
    ///   `b = c (κ_y/κ_x)^{1/3} ∝ κ_y^{2/9}` (4.81), hence `v ∝ φ^{−4/9}`,
    ///   `u ∝ φ^{2/9}` (4.82).
    /// * Brewe–Hamrock (§4.5.3.2): `a = (3k²E(e)W R'/(πE*))^{1/3}`,
    ///   `b = (3E(e)W R'/(πkE*))^{1/3}` (4.84) with `1/R' = κ_y + κ_x → κ_x`,
    ///   `E(e) ≈ 1.0003 + 0.5968 κ_y/κ_x → 1.0003` and `k ≈ 1.0339 (κ_x/κ_y)^{0.636}`
    ///   (4.85), so `a ∝ k^{2/3} ∝ κ_y^{−0.424}`, `b ∝ k^{−1/3} ∝ κ_y^{0.212}` (4.86).
    /// * Winkler (§4.5.3.3): from eq. (4.88), `ab = 2δ√(R_x R_y)` and
    ///   `δ = 2d_f W/(Kπab)` give `δ² = d_f W/(Kπ√(R_x R_y)) ∝ R_y^{−1/2}`, so
    ///   `a = (2δR_y)^{1/2} ∝ R_y^{3/8} ∝ φ^{−3/8}` and `b = (2δR_x)^{1/2} ∝
    ///   R_y^{−1/8} ∝ φ^{+1/8}` (eq. 4.89b prints `sin^{−1/8} φ`: a typo).
    /// * Cylinder (§4.5.3.4): line contact, `a = (4WR_y/(πE*))^{1/2} ∝ φ^{−1/2}`
    ///   (4.91); no transverse offset.
    fn hertzian_exponents(self) -> Option<(f64, Option<f64>)> {
        match self {
            ModelKind::Greenwood => Some((-4.0 / 9.0, Some(2.0 / 9.0))),
            ModelKind::BreweHamrock => Some((-0.424, Some(0.212))),
            ModelKind::Winkler => Some((-3.0 / 8.0, Some(1.0 / 8.0))),
            ModelKind::Cylinder => Some((-0.5, None)),
            _ => None,
        }
    }
}

/// Default exponent p of augmented contour friction (§4.7.1).
pub const DEFAULT_AUGMENTED_EXPONENT: f64 = 0.722;

fn default_augmented_exponent() -> f64 {
    DEFAULT_AUGMENTED_EXPONENT
}

/// A dissipation model with its shape parameters (not η, which the simulator owns).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Dissipation {
    /// Which model.
    pub kind: ModelKind,
    /// Exponent p of augmented contour friction, `q = φ^{−p} q_contour` (§4.7.1);
    /// default 0.722 (n = 1/(3/2 + p) = 0.45). Used only by
    /// [`ModelKind::AugmentedContour`].
    #[serde(default = "default_augmented_exponent")]
    pub augmented_exponent: f64,
    /// Ratio `k_u/k_v` of the transverse (`x^I`, resisting φ̇) to the longitudinal
    /// (`y^I`, resisting θ̇) offset scale of eq. (4.62): `u/v` for the constant offset,
    /// `k_u/k_v` for eqs. (4.69), (4.83), (4.87), (4.90). Default 0, the thesis's
    /// choice (`u = 0` after eq. 4.62, "k_u = 0 … a reasonable approximation" after
    /// eq. 4.69). Ignored by the other models (the cylinder model has no `u`).
    #[serde(default)]
    pub ku_over_kv: f64,
}

/// Sign with `sign(0) = 0`: on a discontinuity set the moment is set-valued and the
/// thesis disregards the dynamics there, so the zero element is returned.
#[inline]
fn sgn(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Eq. (4.62): `q = (−v sign(θ̇) cos φ, −u sign(φ̇), v sign(θ̇) sin φ)`, the moment of a
/// centre of pressure offset by `v` along `y^I` and `u` along `x^I` (scaled by R);
/// `st` is sign(θ̇).
#[inline]
fn offset_q(r: &Rates, v: f64, u: f64, st: f64) -> Vector3<f64> {
    let (s, c) = r.phi.sin_cos();
    let vs = v * st;
    Vector3::new(-vs * c, -u * sgn(r.phi_dot), vs * s)
}

/// Eq. (4.59): `q = sign(θ̇)(−cot φ, 0, 1)`; `st` is sign(θ̇).
#[inline]
fn contour_q(r: &Rates, st: f64) -> Vector3<f64> {
    let (s, c) = r.phi.sin_cos();
    Vector3::new(-st * c / s, 0.0, st)
}

impl Dissipation {
    /// The model with the thesis's default shape parameters (p = 0.722, k_u = 0).
    pub fn new(kind: ModelKind) -> Self {
        Dissipation {
            kind,
            augmented_exponent: DEFAULT_AUGMENTED_EXPONENT,
            ku_over_kv: 0.0,
        }
    }

    /// q^B such that Q^B = −η n q^B (eq. 4.5), scaled. h = H/R. Zero vector for None.
    ///
    /// None of the thesis's moments depends on h (an offset moment is δ × N, which
    /// does not involve GP); `h` is accepted for API uniformity.
    ///
    /// Formulas (s = sin φ, c = cos φ, sign(0) = 0):
    /// * ClassicalRolling (4.53): `ω_h/|ω_h|`, `ω_h = (−θ̇sc, −φ̇, θ̇s²)`, `|ω_h| =
    ///   √(φ̇² + θ̇²s²)`; 0 on ω_h = 0.
    /// * ViscousRolling (4.52 without the root): `ω_h`.
    /// * Pivoting (4.55): `sign(ψ̇ + θ̇c)(s, 0, c)` (the unit vertical `ẑ^G` in B).
    /// * GeneralRolling (4.56): `Ω/|Ω|`; 0 on Ω = 0.
    /// * Contour (4.59): `sign(θ̇)(−c/s, 0, 1)`.
    /// * ConstantOffset (4.63, with 4.62's u): `(−sign(θ̇)c, −r_u sign(φ̇), sign(θ̇)s)`.
    /// * CurvatureOffset (4.69): `(−sign(θ̇)c/s, −r_u sign(φ̇), sign(θ̇))`.
    /// * Greenwood (4.83), BreweHamrock (4.87), Winkler (4.90), Cylinder (4.92):
    ///   eq. (4.62) with `v = φ^{p_v}`, `u = r_u φ^{p_u}`:
    ///   `(−φ^{p_v} sign(θ̇)c, −r_u φ^{p_u} sign(φ̇), φ^{p_v} sign(θ̇)s)` with
    ///   `(p_v, p_u) = (−4/9, 2/9), (−0.424, 0.212), (−3/8, 1/8), (−1/2, –)`.
    /// * AugmentedContour (§4.7.1): `φ^{−p} sign(θ̇)(−c/s, 0, 1)`.
    ///
    /// Here `r_u` is [`Dissipation::ku_over_kv`].
    pub fn q_body(&self, r: &Rates, h: f64) -> Vector3<f64> {
        let side = self.discontinuity(r).map_or(0.0, sgn);
        self.q_body_on_side(r, h, side)
    }

    /// q^B with the sign of the model's discontinuity function D ([`Self::discontinuity`])
    /// taken as `side` (±1) instead of sign(D): the smooth branch of the moment that
    /// holds where sign(D) = side, continued across D = 0. Reaching D = 0 ends a run
    /// (§4.3.1, third terminal condition), so the simulator integrates on the branch
    /// the run starts on; the vector field then stays smooth up to and across the
    /// terminal event, which its root location needs. Models without a discontinuity
    /// set ignore `side`.
    pub fn q_body_on_side(&self, r: &Rates, _h: f64, side: f64) -> Vector3<f64> {
        match self.kind {
            ModelKind::None => Vector3::zeros(),
            ModelKind::ClassicalRolling => {
                let w = r.horizontal_omega_body();
                let norm = w.norm();
                if norm > 0.0 {
                    w / norm
                } else {
                    Vector3::zeros()
                }
            }
            ModelKind::ViscousRolling => r.horizontal_omega_body(),
            ModelKind::Pivoting => {
                let (s, c) = r.phi.sin_cos();
                side * Vector3::new(s, 0.0, c)
            }
            ModelKind::GeneralRolling => {
                let w = r.omega_body();
                let norm = w.norm();
                if norm > 0.0 {
                    w / norm
                } else {
                    Vector3::zeros()
                }
            }
            ModelKind::Contour => contour_q(r, side),
            ModelKind::ConstantOffset => offset_q(r, 1.0, self.ku_over_kv, side),
            ModelKind::CurvatureOffset => {
                // v = k_v / sin φ (eq. 4.68) in eq. (4.62): v cos φ = cot φ, v sin φ = 1.
                let (s, c) = r.phi.sin_cos();
                Vector3::new(-side * c / s, -self.ku_over_kv * sgn(r.phi_dot), side)
            }
            ModelKind::Greenwood
            | ModelKind::BreweHamrock
            | ModelKind::Winkler
            | ModelKind::Cylinder => {
                let (pv, pu) = self.kind.hertzian_exponents().unwrap_or((0.0, None));
                let v = r.phi.powf(pv);
                let u = match pu {
                    Some(pu) if self.ku_over_kv != 0.0 => self.ku_over_kv * r.phi.powf(pu),
                    _ => 0.0,
                };
                offset_q(r, v, u, side)
            }
            ModelKind::AugmentedContour => {
                r.phi.powf(-self.augmented_exponent) * contour_q(r, side)
            }
        }
    }

    /// A signed function of the rates whose zero is the model's codimension-1
    /// discontinuity set; the simulator stops when it changes sign.
    ///
    /// * None, ViscousRolling: continuous moments → `None`.
    /// * ClassicalRolling: discontinuous only on `φ̇ = 0 ∧ θ̇ sin φ = 0` (where
    ///   `ω_h = 0`), a codimension-2 set that a trajectory does not cross
    ///   generically, and no single scalar changes sign across it → `None`.
    /// * GeneralRolling: discontinuous only at `Ω = 0` (`ψ̇ = φ̇ = θ̇ = 0`),
    ///   codimension 3 (§4.4.3) → `None`.
    /// * Pivoting: `ψ̇ + θ̇ cos φ = ω_z^G` (eq. 4.54; "the zero of ψ̇ + θ̇ cos φ is a
    ///   co-dimension one discontinuity", §4.4.2).
    /// * Contour, constant / curvature offset, Greenwood, Brewe–Hamrock, Winkler,
    ///   cylinder, augmented contour: `θ̇` (eq. 4.60, `D_c = {θ̇ = 0}`; the offset
    ///   models carry the same `sign(θ̇)`). If `ku_over_kv ≠ 0`, `φ̇ = 0` is also a
    ///   discontinuity, but a crossing one that the simulator must integrate through;
    ///   it is not reported.
    pub fn discontinuity(&self, r: &Rates) -> Option<f64> {
        match self.kind {
            ModelKind::None
            | ModelKind::ViscousRolling
            | ModelKind::ClassicalRolling
            | ModelKind::GeneralRolling => None,
            ModelKind::Pivoting => Some(r.psi_dot + r.theta_dot * r.phi.cos()),
            ModelKind::Contour
            | ModelKind::ConstantOffset
            | ModelKind::CurvatureOffset
            | ModelKind::Greenwood
            | ModelKind::BreweHamrock
            | ModelKind::Winkler
            | ModelKind::Cylinder
            | ModelKind::AugmentedContour => Some(r.theta_dot),
        }
    }

    /// Thesis equation reference, e.g. "eq. (4.59)".
    pub fn equation(&self) -> &'static str {
        match self.kind {
            ModelKind::None => "eq. (4.5) with q = 0",
            ModelKind::ClassicalRolling => "eq. (4.53)",
            ModelKind::ViscousRolling => "eq. (4.52) without the square root (end of §4.4.1)",
            ModelKind::Pivoting => "eq. (4.55)",
            ModelKind::GeneralRolling => "eq. (4.56)",
            ModelKind::Contour => "eq. (4.59)",
            ModelKind::ConstantOffset => "eq. (4.63)",
            ModelKind::CurvatureOffset => "eq. (4.69)",
            ModelKind::Greenwood => "eq. (4.83)",
            ModelKind::BreweHamrock => "eq. (4.87)",
            ModelKind::Winkler => "eq. (4.90)",
            ModelKind::Cylinder => "eq. (4.92)",
            ModelKind::AugmentedContour => "eq. (4.59) × φ^(−p) (§4.7.1)",
        }
    }

    /// The energy exponent n the thesis predicts analytically (Table 4.1 "analytic n",
    /// exact fractions of its `E` column), `E ∝ (t₀ − t)^n`.
    ///
    /// Augmented contour is not in Table 4.1; §4.7.1 designs it for n = 0.45, and the
    /// value returned is the same analysis, `1/(3/2 + p)` (0.450 at p = 0.722;
    /// ERRATA §4.7.1). None and the viscous variant have no finite-time halt
    /// (viscous: `Ė ∝ −E`, exponential decay) and no exponent → `None`.
    pub fn analytic_exponent(&self) -> Option<f64> {
        match self.kind {
            ModelKind::None | ModelKind::ViscousRolling => None,
            ModelKind::ClassicalRolling
            | ModelKind::Pivoting
            | ModelKind::GeneralRolling
            | ModelKind::ConstantOffset => Some(2.0),
            ModelKind::Contour | ModelKind::CurvatureOffset => Some(2.0 / 3.0),
            ModelKind::Greenwood => Some(18.0 / 17.0),
            ModelKind::BreweHamrock => Some(1.0 / (1.0 - 0.076)),
            ModelKind::Winkler => Some(8.0 / 7.0),
            ModelKind::Cylinder => Some(1.0),
            ModelKind::AugmentedContour => Some(1.0 / (1.5 + self.augmented_exponent)),
        }
    }

    /// Table 4.1 "numerical n" as printed in the thesis, if printed. (Pivoting's 2.13
    /// depends on the fit window, ERRATA.)
    pub fn thesis_numerical_exponent(&self) -> Option<f64> {
        match self.kind {
            ModelKind::None | ModelKind::ViscousRolling | ModelKind::AugmentedContour => None,
            ModelKind::ClassicalRolling => Some(2.01),
            ModelKind::Pivoting => Some(2.13),
            ModelKind::GeneralRolling => Some(2.01),
            ModelKind::Contour => Some(0.67),
            ModelKind::ConstantOffset => Some(2.00),
            ModelKind::CurvatureOffset => Some(0.67),
            ModelKind::Greenwood => Some(1.06),
            ModelKind::BreweHamrock => Some(1.09),
            ModelKind::Winkler => Some(1.15),
            ModelKind::Cylinder => Some(1.00),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn log_uniform(rng: &mut SplitMix64, lo: f64, hi: f64) -> f64 {
        (lo.ln() + (hi.ln() - lo.ln()) * rng.uniform()).exp()
    }

    /// A rate with random sign and magnitude spread over 1e-3..1e3.
    fn rate(rng: &mut SplitMix64) -> f64 {
        let m = log_uniform(rng, 1e-3, 1e3);
        if rng.uniform() < 0.5 { -m } else { m }
    }

    fn rates(rng: &mut SplitMix64) -> Rates {
        Rates {
            phi: log_uniform(rng, 1e-4, 1.4),
            phi_dot: rate(rng),
            psi_dot: rate(rng),
            theta_dot: rate(rng),
        }
    }

    /// Scaled constants of the commercial Euler's disk (§4.3.1, eq. 4.42).
    const H: f64 = 0.167;
    const A: f64 = 0.252;
    const C: f64 = 0.501;

    fn all_models() -> Vec<Dissipation> {
        let mut v: Vec<Dissipation> = ModelKind::ALL
            .iter()
            .map(|&k| Dissipation::new(k))
            .collect();
        // Non-default shape parameters too.
        for k in [
            ModelKind::ConstantOffset,
            ModelKind::CurvatureOffset,
            ModelKind::Greenwood,
            ModelKind::BreweHamrock,
            ModelKind::Winkler,
        ] {
            v.push(Dissipation {
                ku_over_kv: 0.3,
                ..Dissipation::new(k)
            });
        }
        for p in [0.0, 0.3, 1.5] {
            v.push(Dissipation {
                augmented_exponent: p,
                ..Dissipation::new(ModelKind::AugmentedContour)
            });
        }
        v
    }

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * (1.0 + a.abs().max(b.abs()))
    }

    fn close_vec(a: &Vector3<f64>, b: &Vector3<f64>, rel: f64) -> bool {
        (a - b).norm() <= rel * (1.0 + a.norm().max(b.norm()))
    }

    /// Stationary rolling, eq. (4.40), with ψ̇ > 0 (so θ̇ < 0) or the reverse.
    fn stationary(phi: f64, sign: f64) -> Rates {
        let (s, c) = phi.sin_cos();
        let psi_dot = sign * ((c - H * s) / (A * s * c + C * H * s * s)).sqrt();
        Rates {
            phi,
            phi_dot: 0.0,
            psi_dot,
            theta_dot: -psi_dot * (c - H * s),
        }
    }

    /// Q·Ω = −η n q·Ω ≤ 0 for every model and random rates, both spin directions,
    /// φ ∈ (1e-4, 1.4); strictly < 0 off the discontinuity set for all but None.
    #[test]
    fn every_model_dissipates() {
        let mut rng = SplitMix64::new(42);
        for d in all_models() {
            for _ in 0..20_000 {
                let mut r = rates(&mut rng);
                for spin in [1.0, -1.0] {
                    r.theta_dot = spin * r.theta_dot.abs();
                    let q = d.q_body(&r, H);
                    let w = r.omega_body();
                    let p = q.dot(&w);
                    assert!(q.iter().all(|x| x.is_finite()), "{d:?} {r:?}: q = {q}");
                    assert!(p >= -1e-12 * q.norm() * w.norm(), "{d:?} {r:?}: q·Ω = {p}");
                    let on_set = d.discontinuity(&r) == Some(0.0);
                    if d.kind != ModelKind::None && !on_set {
                        assert!(p > 0.0, "{d:?} {r:?}: q·Ω = {p} not > 0");
                    }
                }
            }
        }
    }

    /// q·Ω in closed form for every model (the dissipated power / (η n)).
    #[test]
    fn power_matches_closed_form() {
        let mut rng = SplitMix64::new(7);
        for d in all_models() {
            for _ in 0..2_000 {
                let r = rates(&mut rng);
                let (s, c) = r.phi.sin_cos();
                let (pd, sd, td) = (r.phi_dot, r.psi_dot, r.theta_dot);
                let ru = d.ku_over_kv;
                let offset = |pv: f64, u: f64| r.phi.powf(pv) * td.abs() * s + u * pd.abs();
                let expected = match d.kind {
                    ModelKind::None => 0.0,
                    ModelKind::ClassicalRolling => (pd * pd + td * td * s * s).sqrt(),
                    ModelKind::ViscousRolling => pd * pd + td * td * s * s,
                    ModelKind::Pivoting => (sd + td * c).abs(),
                    ModelKind::GeneralRolling => r.omega_body().norm(),
                    ModelKind::Contour => td.abs(),
                    ModelKind::ConstantOffset => td.abs() * s + ru * pd.abs(),
                    ModelKind::CurvatureOffset => td.abs() + ru * pd.abs(),
                    ModelKind::Greenwood => offset(-4.0 / 9.0, ru * r.phi.powf(2.0 / 9.0)),
                    ModelKind::BreweHamrock => offset(-0.424, ru * r.phi.powf(0.212)),
                    ModelKind::Winkler => offset(-3.0 / 8.0, ru * r.phi.powf(1.0 / 8.0)),
                    ModelKind::Cylinder => offset(-0.5, 0.0),
                    ModelKind::AugmentedContour => r.phi.powf(-d.augmented_exponent) * td.abs(),
                };
                let got = d.q_body(&r, H).dot(&r.omega_body());
                // Cancellations in q·Ω (e.g. contour's −cot φ ψ̇ sin φ + ψ̇ cos φ) lose
                // digits relative to |q||Ω|.
                let scale = d.q_body(&r, H).norm() * r.omega_body().norm();
                assert!(
                    (got - expected).abs() <= 1e-12 * (scale + expected.abs()),
                    "{d:?} {r:?}: q·Ω = {got}, expected {expected}"
                );
            }
        }
    }

    /// Classical rolling: |q| = 1 (modulus ηRN by construction, eq. 4.51), q is the
    /// unit horizontal angular velocity, and it has no vertical (ẑ^G) component.
    #[test]
    fn classical_rolling_is_unit_and_horizontal() {
        let d = Dissipation::new(ModelKind::ClassicalRolling);
        let mut rng = SplitMix64::new(1);
        for _ in 0..5_000 {
            let r = rates(&mut rng);
            let q = d.q_body(&r, H);
            assert!(close(q.norm(), 1.0, 1e-14), "{r:?}: |q| = {}", q.norm());
            let (s, c) = r.phi.sin_cos();
            let z_g = Vector3::new(s, 0.0, c);
            assert!(q.dot(&z_g).abs() < 1e-14, "{r:?}: q·ẑ^G = {}", q.dot(&z_g));
            // Eq. (4.53) transcribed.
            let norm = (r.phi_dot.powi(2) + r.theta_dot.powi(2) * s * s).sqrt();
            let printed =
                Vector3::new(-c * s * r.theta_dot, -r.phi_dot, r.theta_dot * s * s) / norm;
            assert!(close_vec(&q, &printed, 1e-14));
        }
        // On the codimension-2 set ω_h = 0 the zero element is returned.
        let r = Rates {
            phi: 0.3,
            phi_dot: 0.0,
            psi_dot: 2.0,
            theta_dot: 0.0,
        };
        assert_eq!(d.q_body(&r, H), Vector3::zeros());
    }

    /// General rolling: q = Ω̂ (eq. 4.56).
    #[test]
    fn general_rolling_is_unit_omega() {
        let d = Dissipation::new(ModelKind::GeneralRolling);
        let mut rng = SplitMix64::new(2);
        for _ in 0..5_000 {
            let r = rates(&mut rng);
            let w = r.omega_body();
            let q = d.q_body(&r, H);
            assert!(close(q.norm(), 1.0, 1e-14));
            assert!(close_vec(&q, &(w / w.norm()), 1e-14));
        }
        let r = Rates {
            phi: 0.3,
            phi_dot: 0.0,
            psi_dot: 0.0,
            theta_dot: 0.0,
        };
        assert_eq!(d.q_body(&r, H), Vector3::zeros());
    }

    /// Pivoting: |q| = 1, along the vertical ẑ^G = (sin φ, 0, cos φ)^B, opposing
    /// ω_z^G = ψ̇ + θ̇ cos φ (eqs. 4.54–4.55).
    #[test]
    fn pivoting_is_unit_vertical() {
        let d = Dissipation::new(ModelKind::Pivoting);
        let mut rng = SplitMix64::new(3);
        for _ in 0..5_000 {
            let r = rates(&mut rng);
            let q = d.q_body(&r, H);
            let (s, c) = r.phi.sin_cos();
            assert!(close(q.norm(), 1.0, 1e-14));
            assert!(q.cross(&Vector3::new(s, 0.0, c)).norm() < 1e-14);
            let omega_z = r.omega_body().dot(&Vector3::new(s, 0.0, c));
            assert!(close(omega_z, r.psi_dot + r.theta_dot * c, 1e-12));
            assert!(close(q.dot(&Vector3::new(s, 0.0, c)), sgn(omega_z), 1e-15));
        }
    }

    /// Contour friction (eq. 4.59): q·Ω = |θ̇| (not |θ̇|/sin φ: derived in the module
    /// doc, item 9), and contour = classical with φ̇ dropped, × 1/sin φ (§4.4.4).
    /// Also equal to the curvature-dependent offset with k_u = 0 (§4.5.2).
    #[test]
    fn contour_power_and_relation_to_classical() {
        let contour = Dissipation::new(ModelKind::Contour);
        let classical = Dissipation::new(ModelKind::ClassicalRolling);
        let curvature = Dissipation::new(ModelKind::CurvatureOffset);
        let mut rng = SplitMix64::new(4);
        for _ in 0..5_000 {
            let r = rates(&mut rng);
            let q = contour.q_body(&r, H);
            let w = r.omega_body();
            let scale = q.norm() * w.norm();
            assert!((q.dot(&w) - r.theta_dot.abs()).abs() <= 1e-12 * scale);
            let no_nutation = Rates { phi_dot: 0.0, ..r };
            let from_classical = classical.q_body(&no_nutation, H) / r.phi.sin();
            assert!(
                close_vec(&q, &from_classical, 1e-13),
                "{r:?}: {q} vs {from_classical}"
            );
            let printed = r.theta_dot.signum() * Vector3::new(-1.0 / r.phi.tan(), 0.0, 1.0);
            assert!(close_vec(&q, &printed, 1e-13));
            assert!(close_vec(&q, &curvature.q_body(&r, H), 1e-13));
        }
    }

    /// Augmented contour (§4.7.1) is contour × φ^(−p), and equals contour at p = 0.
    #[test]
    fn augmented_contour_scales_contour() {
        let contour = Dissipation::new(ModelKind::Contour);
        let mut rng = SplitMix64::new(5);
        for p in [0.0, DEFAULT_AUGMENTED_EXPONENT, 1.3] {
            let aug = Dissipation {
                augmented_exponent: p,
                ..Dissipation::new(ModelKind::AugmentedContour)
            };
            for _ in 0..2_000 {
                let r = rates(&mut rng);
                let qc = contour.q_body(&r, H);
                let qa = aug.q_body(&r, H);
                if p == 0.0 {
                    assert_eq!(qa, qc);
                }
                assert!(close_vec(&qa, &(qc * r.phi.powf(-p)), 1e-13));
            }
        }
        assert_eq!(
            Dissipation::new(ModelKind::AugmentedContour).augmented_exponent,
            0.722
        );
    }

    /// The viscous variant is classical × |ω_h| (the norm it discards, §4.4.1).
    #[test]
    fn viscous_is_classical_times_norm() {
        let classical = Dissipation::new(ModelKind::ClassicalRolling);
        let viscous = Dissipation::new(ModelKind::ViscousRolling);
        let mut rng = SplitMix64::new(6);
        for _ in 0..5_000 {
            let r = rates(&mut rng);
            let s = r.phi.sin();
            let norm = (r.phi_dot.powi(2) + r.theta_dot.powi(2) * s * s).sqrt();
            let qv = viscous.q_body(&r, H);
            assert!(close_vec(&qv, &(classical.q_body(&r, H) * norm), 1e-13));
            assert!(close(qv.norm(), norm, 1e-13));
        }
    }

    /// Offset models are eq. (4.62) (with the ERRATA sign(θ̇)) and reduce, as φ → 0,
    /// to the printed small-angle vectors of eqs. (4.83), (4.87), (4.90), (4.92)
    /// times sign(θ̇) (the u-term times sign(φ̇)); the constant offset is eq. (4.63).
    #[test]
    fn offset_models_match_printed_forms() {
        let cases = [
            (ModelKind::Greenwood, -4.0 / 9.0, 2.0 / 9.0),
            (ModelKind::BreweHamrock, -0.424, 0.212),
            (ModelKind::Winkler, -3.0 / 8.0, 1.0 / 8.0),
            (ModelKind::Cylinder, -0.5, f64::NAN),
        ];
        let mut rng = SplitMix64::new(8);
        for (kind, pv, pu) in cases {
            let ku = if kind == ModelKind::Cylinder {
                0.0
            } else {
                0.7
            };
            let d = Dissipation {
                ku_over_kv: ku,
                ..Dissipation::new(kind)
            };
            for _ in 0..1_000 {
                let mut r = rates(&mut rng);
                r.phi = log_uniform(&mut rng, 1e-6, 1e-4);
                let (st, sp) = (r.theta_dot.signum(), r.phi_dot.signum());
                let u = if ku == 0.0 { 0.0 } else { ku * r.phi.powf(pu) };
                // Printed: −n(−k_v φ^p, −k_u φ^{p_u}, k_v φ^{p+1}) (4.83, 4.87), or the
                // equal +n(k_v φ^p, k_u φ^{p_u}, −k_v φ^{p+1}) (4.90, 4.92).
                let printed =
                    Vector3::new(-st * r.phi.powf(pv), -sp * u, st * r.phi.powf(pv + 1.0));
                let q = d.q_body(&r, H);
                assert!(
                    (q - printed).norm() <= 1e-7 * printed.norm(),
                    "{kind:?} {r:?}: {q} vs {printed}"
                );
            }
        }
        let d = Dissipation::new(ModelKind::ConstantOffset);
        let r = Rates {
            phi: 0.4,
            phi_dot: 1.0,
            psi_dot: 3.0,
            theta_dot: -2.0,
        };
        let (s, c) = r.phi.sin_cos();
        assert_eq!(d.q_body(&r, H), Vector3::new(c, 0.0, -s)); // −1·(−cos φ, 0, sin φ)
    }

    /// The printed small-angle Hertzian vector is *not* dissipative at finite φ,
    /// which is why the eq. (4.62) form is implemented (module doc, item 1).
    #[test]
    fn small_angle_form_would_inject_energy() {
        let r = Rates {
            phi: 1.0,
            phi_dot: 0.0,
            psi_dot: 10.0,
            theta_dot: 0.1,
        };
        let p = -4.0 / 9.0;
        let printed = Vector3::new(-r.phi.powf(p), 0.0, r.phi.powf(p + 1.0));
        assert!(printed.dot(&r.omega_body()) < 0.0);
        let q = Dissipation::new(ModelKind::Greenwood).q_body(&r, H);
        assert!(q.dot(&r.omega_body()) > 0.0);
    }

    /// Semi-axes (a, b) of a contact region as functions of φ.
    type Axes = dyn Fn(f64) -> (f64, f64);

    /// The offset exponents follow from the contact-mechanics formulas of §4.5.3 at
    /// small φ (constants set to 1, scaled R = 1, R_x = 0.02): Greenwood (4.78–4.80),
    /// Brewe–Hamrock (4.84–4.85), Winkler (4.88, solved exactly) and the cylinder
    /// (4.91). This checks the derivation and the typo in eq. (4.89b).
    #[test]
    fn hertzian_axes_follow_power_laws() {
        use std::f64::consts::PI;
        const RX: f64 = 0.02;
        let greenwood = |phi: f64| {
            let (ky, kx) = (phi.sin() / 2.0, 1.0 / (2.0 * RX));
            let re = (ky * kx * (ky + kx) / 2.0).powf(-1.0 / 3.0);
            let c = (3.0 * re / 4.0).powf(1.0 / 3.0);
            let b_over_a = (ky / kx).powf(2.0 / 3.0);
            (c / b_over_a.sqrt(), c * b_over_a.sqrt())
        };
        let brewe_hamrock = |phi: f64| {
            let (ky, kx) = (phi.sin() / 2.0, 1.0 / (2.0 * RX));
            let k = 1.0339 * (kx / ky).powf(0.636);
            let e = 1.0003 + 0.5968 * ky / kx;
            let rp = 1.0 / (ky + kx);
            (
                (3.0 * k * k * e * rp / PI).powf(1.0 / 3.0),
                (3.0 * e * rp / (PI * k)).powf(1.0 / 3.0),
            )
        };
        let winkler = |phi: f64| {
            let ry = 1.0 / phi.sin();
            let df_w_over_k = 1.0;
            let delta = (df_w_over_k / (PI * (RX * ry).sqrt())).sqrt();
            let (a, b) = ((2.0 * delta * ry).sqrt(), (2.0 * delta * RX).sqrt());
            // Eq. (4.88) holds: δ = 2 d_f W/(Kπab).
            assert!(close(delta, 2.0 * df_w_over_k / (PI * a * b), 1e-12));
            // Printed prefactors of eq. (4.89) with sin^(−3/8) and sin^(+1/8).
            let s = phi.sin();
            let a89 = 2f64.sqrt()
                * (df_w_over_k.powi(2) / (RX * PI * PI)).powf(0.125)
                * s.powf(-3.0 / 8.0);
            let b89 = 2f64.sqrt()
                * (df_w_over_k.powi(2) * RX.powi(3) / (PI * PI)).powf(0.125)
                * s.powf(1.0 / 8.0);
            assert!(close(a, a89, 1e-12) && close(b, b89, 1e-12));
            (a, b)
        };
        let cylinder = |phi: f64| ((4.0 / (PI * phi.sin())).sqrt(), f64::NAN);
        let slope = |f: &Axes, which: usize| {
            let (p1, p2) = (1e-7, 1e-6);
            let pick = |p: f64| if which == 0 { f(p).0 } else { f(p).1 };
            (pick(p2) / pick(p1)).ln() / (p2 / p1).ln()
        };
        let models: [(ModelKind, &Axes); 4] = [
            (ModelKind::Greenwood, &greenwood),
            (ModelKind::BreweHamrock, &brewe_hamrock),
            (ModelKind::Winkler, &winkler),
            (ModelKind::Cylinder, &cylinder),
        ];
        for (kind, f) in models {
            let (pv, pu) = kind.hertzian_exponents().unwrap();
            let sv = slope(f, 0);
            assert!(
                (sv - pv).abs() < 2e-4,
                "{kind:?}: a ∝ φ^{sv}, model uses {pv}"
            );
            if let Some(pu) = pu {
                let su = slope(f, 1);
                assert!(
                    (su - pu).abs() < 2e-4,
                    "{kind:?}: b ∝ φ^{su}, model uses {pu}"
                );
            }
        }
    }

    /// Table 4.1: the analytic energy exponent re-derived from q_body on the
    /// stationary-rolling manifold (eq. 4.40): Ė ∝ φ^α with E ∝ φ (eq. 4.96) gives
    /// n = 1/(1 − α); both spin directions.
    #[test]
    fn analytic_exponents_follow_from_q_on_stationary_manifold() {
        let mut d_list = all_models();
        d_list.retain(|d| d.ku_over_kv == 0.0); // u-terms vanish when φ̇ = 0 anyway
        for d in d_list {
            for sign in [1.0, -1.0] {
                let power = |phi: f64| {
                    let r = stationary(phi, sign);
                    d.q_body(&r, H).dot(&r.omega_body())
                };
                let (p1, p2) = (1e-7, 1e-6);
                let alpha = (power(p2) / power(p1)).ln() / (p2 / p1).ln();
                match d.analytic_exponent() {
                    Some(n) => {
                        let n_q = 1.0 / (1.0 - alpha);
                        assert!(
                            (n_q - n).abs() < 1e-3 * n,
                            "{d:?}: from q, n = {n_q}; analytic_exponent = {n}"
                        );
                    }
                    None if d.kind == ModelKind::ViscousRolling => {
                        // Ė ∝ E: exponential decay, no finite-time halt.
                        assert!((alpha - 1.0).abs() < 1e-3, "viscous α = {alpha}");
                    }
                    None => assert_eq!(d.kind, ModelKind::None),
                }
            }
        }
        // §4.7.1: p = 0.722 gives n = 0.45 (ERRATA: Ė ∝ −E^(−1.22)).
        let aug = Dissipation::new(ModelKind::AugmentedContour);
        assert!((aug.analytic_exponent().unwrap() - 0.45).abs() < 5e-4);
    }

    /// Table 4.1 as printed; "in all cases the analytic n is a slight underestimate"
    /// of the numerical n (up to the table's rounding to two decimals).
    #[test]
    fn table_4_1_exponents() {
        let table = [
            (ModelKind::ClassicalRolling, 2.00, 2.01),
            (ModelKind::Pivoting, 2.00, 2.13),
            (ModelKind::GeneralRolling, 2.00, 2.01),
            (ModelKind::Contour, 0.67, 0.67),
            (ModelKind::ConstantOffset, 2.00, 2.00),
            (ModelKind::CurvatureOffset, 0.67, 0.67),
            (ModelKind::Greenwood, 1.06, 1.06),
            (ModelKind::BreweHamrock, 1.08, 1.09),
            (ModelKind::Winkler, 1.14, 1.15),
            (ModelKind::Cylinder, 1.00, 1.00),
        ];
        for (kind, analytic, numerical) in table {
            let d = Dissipation::new(kind);
            let n = d.analytic_exponent().unwrap();
            assert!(
                (n - analytic).abs() <= 0.005,
                "{kind:?}: {n} vs printed {analytic}"
            );
            assert_eq!(d.thesis_numerical_exponent(), Some(numerical));
            assert!(numerical >= n - 0.005);
        }
        for kind in [ModelKind::None, ModelKind::ViscousRolling] {
            let d = Dissipation::new(kind);
            assert_eq!(d.analytic_exponent(), None);
            assert_eq!(d.thesis_numerical_exponent(), None);
        }
    }

    /// Discontinuity functions: θ̇ for contour-type models (eq. 4.60), ψ̇ + θ̇ cos φ for
    /// pivoting (§4.4.2); q jumps exactly where the function changes sign and is
    /// continuous elsewhere; classical, general, viscous and none report None.
    #[test]
    fn discontinuities_change_sign_where_the_text_says() {
        let eps = 1e-9;
        let base = Rates {
            phi: 0.3,
            phi_dot: 0.2,
            psi_dot: 4.0,
            theta_dot: 0.0,
        };
        for d in all_models() {
            let jump = |a: &Rates, b: &Rates| (d.q_body(a, H) - d.q_body(b, H)).norm();
            match d.kind {
                ModelKind::None
                | ModelKind::ClassicalRolling
                | ModelKind::GeneralRolling
                | ModelKind::ViscousRolling => {
                    assert_eq!(d.discontinuity(&base), None, "{d:?}");
                    // Continuous across θ̇ = 0 when φ̇ ≠ 0 (classical's set is codim 2).
                    let (a, b) = (
                        Rates {
                            theta_dot: eps,
                            ..base
                        },
                        Rates {
                            theta_dot: -eps,
                            ..base
                        },
                    );
                    assert!(jump(&a, &b) < 1e-6, "{d:?}");
                }
                ModelKind::Pivoting => {
                    let c = base.phi.cos();
                    let t = 3.0;
                    let at = Rates {
                        theta_dot: t,
                        psi_dot: -t * c,
                        ..base
                    };
                    let (a, b) = (
                        Rates {
                            psi_dot: at.psi_dot + eps,
                            ..at
                        },
                        Rates {
                            psi_dot: at.psi_dot - eps,
                            ..at
                        },
                    );
                    let (fa, fb) = (d.discontinuity(&a).unwrap(), d.discontinuity(&b).unwrap());
                    assert!(fa > 0.0 && fb < 0.0, "{fa} {fb}");
                    assert!(d.discontinuity(&at).unwrap().abs() < 1e-12);
                    assert!(close(jump(&a, &b), 2.0, 1e-12));
                    // Continuous across θ̇ = 0 away from its set.
                    let (a, b) = (
                        Rates {
                            theta_dot: eps,
                            ..base
                        },
                        Rates {
                            theta_dot: -eps,
                            ..base
                        },
                    );
                    assert!(jump(&a, &b) < 1e-6);
                }
                _ => {
                    let (a, b) = (
                        Rates {
                            theta_dot: eps,
                            ..base
                        },
                        Rates {
                            theta_dot: -eps,
                            ..base
                        },
                    );
                    let (fa, fb) = (d.discontinuity(&a).unwrap(), d.discontinuity(&b).unwrap());
                    assert!(fa > 0.0 && fb < 0.0, "{d:?}: {fa} {fb}");
                    assert_eq!(d.discontinuity(&base), Some(0.0));
                    // q_x, q_z flip sign across θ̇ = 0; q_y (the u-term) does not.
                    let (qa, qb) = (d.q_body(&a, H), d.q_body(&b, H));
                    assert!(
                        qa.x < 0.0 && qb.x > 0.0 && qa.z > 0.0 && qb.z < 0.0,
                        "{d:?}"
                    );
                    assert_eq!(qa.x, -qb.x);
                    assert_eq!(qa.z, -qb.z);
                    assert_eq!(qa.y, qb.y);
                    // Continuous across ψ̇ + θ̇ cos φ = 0 (not its set).
                    let at = Rates {
                        theta_dot: 3.0,
                        psi_dot: -3.0 * base.phi.cos(),
                        ..base
                    };
                    let (a, b) = (
                        Rates {
                            psi_dot: at.psi_dot + eps,
                            ..at
                        },
                        Rates {
                            psi_dot: at.psi_dot - eps,
                            ..at
                        },
                    );
                    assert_eq!(jump(&a, &b), 0.0);
                }
            }
        }
    }

    /// Names for the CLI and config files, and defaults.
    #[test]
    fn names_and_defaults() {
        use clap::ValueEnum;
        assert_eq!(ModelKind::value_variants().len(), ModelKind::ALL.len());
        assert_eq!(
            serde_json::to_string(&ModelKind::BreweHamrock).unwrap(),
            "\"brewe-hamrock\""
        );
        assert_eq!(
            ModelKind::from_str("augmented-contour", false).unwrap(),
            ModelKind::AugmentedContour
        );
        let d: Dissipation = serde_json::from_str(r#"{"kind":"contour"}"#).unwrap();
        assert_eq!(d, Dissipation::new(ModelKind::Contour));
        assert_eq!(d.ku_over_kv, 0.0);
        for k in ModelKind::ALL {
            assert!(Dissipation::new(k).equation().starts_with("eq. (4."));
        }
        assert_eq!(
            Dissipation::new(ModelKind::Greenwood).equation(),
            "eq. (4.83)"
        );
    }
}
