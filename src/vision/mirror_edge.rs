//! The rim on a dark plate as a fitted model of the known edge: the disk's own
//! bottom-edge profile, learned from the clip, plus its mirror image in the plate
//! (thesis §3.2.4, fig. 3.7).
//!
//! # Why a model
//!
//! [`RimGauge`](super::RimGauge) places the bottom edge by the area of the step
//! from the disk's level to the gap's, over three rows either side. That is exact
//! for a sharp edge seen through a symmetric blur. A real disk's rim is rounded:
//! its bottom millimetre darkens gradually (a white side may fade over 4–6 rows,
//! ending 1–2.6 px above the true rim). Then the step's
//! reading depends on what lies below it: with the gap open, the plate's own dark
//! level; at rest, the mirror image's own rounded rim right against the disk's.
//! The rest frame, which gives the zero of z_rim, reads the edge 0.2–0.4 px lower
//! than the same disk lifted, so every lifted height came out that much low
//! (φ at the peaks 4–9 % low on the small two-view side views, and n +0.1).
//!
//! On a sharp rim the step reads the edge without bias, but from three rows of
//! one frame, and heights below 2 px from the gap's darkness
//! ([`GapGauge`](super::GapGauge)); the model reads every row of the band with the
//! profile the whole clip taught. On rendered dark-plate scenes that halves the
//! peaks fit's mean |Δn| against the step's reading (0.022 → 0.011; the per-frame
//! fit's 0.019 → 0.013).
//!
//! # The model
//!
//! Let D(u) be the band's profile at row offset u = (row centre − e) from the
//! disk's edge e, divided by the disk's level: 1 on the side, falling through the
//! rounded rim to the gap's level f. Lifted far enough, a frame shows D alone; at
//! rest, or nearly touching, the mirror image adds its own, reflected about the
//! plate's line y_p with the plate's reflectivity ρ:
//!
//! ```text
//! p(y) = g · [ D(y + ½ − e) + ρ (D(2 y_p − (y + ½) − e) − f) ]
//! ```
//!
//! (pixel y covers [y, y + 1); its mirror pixel's centre is 2 y_p − y − ½, and a
//! symmetric blur commutes with the reflection; g is the frame's light, which
//! divides out flicker).
//!
//! 1. **D from the clip.** Each frame whose first-pass height z₀ (the edge and
//!    the gap gauge) shows an open gap contributes the rows its mirror image
//!    cannot reach, u < 2 z₀ − [`MIRROR_REACH_PX`], aligned on its first-pass
//!    edge and divided by its own disk level; D is their mean in
//!    [`BIN_PX`] bins. Every sub-pixel phase occurs over a clip, so D is resolved
//!    finer than a pixel, with the blur, the rounded rim and the shading in it.
//! 2. **The rest frames** give ρ, y_p and the edge at rest e_rest: the least
//!    squares fit of the model to their mean profile over the rows down to
//!    [`REST_ROWS_BELOW_PX`] below their edge. y_p is where the rim meets its
//!    mirror image: on rounded rims within 0.5 px of the true rim, where the edge
//!    at rest lies 0.8–2.3 px above it. It is the bottom of the disk's
//!    thickness in eq. 3.10's scale (`analyse::ScaleReport`); z_rim's zero stays
//!    the edge at rest, the same edge definition as every lifted frame's.
//! 3. **Sharp or rounded.** The rest frames alone cannot tell a sharp edge
//!    meeting its mirror image (c = y_p − e_rest = 0) from a slightly higher edge
//!    over a thin blurred gap (c ≈ 0.5 px): on six of our sharp renders the rest
//!    frames alone gave c = −0.46 … +0.67 px (0.56–0.67 on three blurred ones,
//!    which the model then took for rounded and read 0.12–0.19 px high when
//!    lifted). The frames near contact can, as the gap 2 (c + z) opens through the
//!    blur: c fitted to them and the rest frames together
//!    ([`MirrorEdgeModel::plate_offset_near_contact`]) is +0.03 … +0.16 px on
//!    those renders and 0.75–2.51 px on rounded rims. Below
//!    [`SHARP_RIM_PX`] the rim is sharp: its mirror image is D reflected, and the
//!    model takes that c, with e_rest and ρ refitted to the rest frames. A
//!    rounded rim keeps the rest frames' own fit: its mirror image shows the
//!    rounding from below, lit unlike D, which the frames near contact see.
//! 4. **A rough plate** blurs its reflection: the rest frames cannot see it (the
//!    mirror image meets the rim at its full level), the frames near contact can,
//!    as the blurred mirror light fills the opening gap. The blur σ_m is fitted to
//!    them with c ([`PlateBlur`]); when it fits better than a sharp reflection, D is
//!    learned again from rows the blurred mirror light cannot reach and the model
//!    refitted with it.
//! 5. **Every frame** is fitted for e (and g) with ρ and y_p known, and
//!    z_rim = e_rest − e: one edge definition, the same at rest and lifted, near
//!    touching or not.
//!
//! A template learned from first-pass edges carries their alignment noise as a
//! slight extra blur of D, the same in every fit; it does not move e_rest − e.

use std::ops::Range;

use rayon::prelude::*;

use super::band_window::{BandWindow, ROWS_ABOVE, ROWS_BELOW};
use super::profile::steps;
use crate::numeric::minimise::{Stop, golden_section};

/// Width of the template's bins \[px\].
pub const BIN_PX: f64 = 0.1;
/// Samples a bin needs to count.
const MIN_BIN_SAMPLES: usize = 3;
/// How far above its own edge a mirror image's light can reach \[px\]: three
/// rows of blur. A frame's rows at u < 2 z₀ − this see no mirror light.
pub const MIRROR_REACH_PX: f64 = 3.0;
/// Frames with an open gap the template needs.
pub const MIN_TEMPLATE_FRAMES: usize = 20;
/// How far from its first-pass edge a frame's fitted edge may lie \[px\].
const SEARCH_PX: f64 = 2.0;
/// How far either side of its least-squares edge a frame's likelihood is averaged
/// ([`MirrorEdgeModel::edge`]) \[px\]: four times the 0.1 px between the near-equal
/// minima that codec ringing makes. On the long clip's frame that showed them, 0.3 px
/// off the minimum the SSR is already larger by 13 times 2s².
const LIKELIHOOD_PX: f64 = 0.4;
/// The rim is sharp at this resolution when the plate line lies less than this
/// below the edge at rest \[px\]: a rim rounded over less than half a pixel. Decided
/// on c as the frames near contact fit it
/// ([`MirrorEdgeModel::plate_offset_near_contact`]): our own sharp renders, blurred
/// or not, +0.03 … +0.16 px; rounded rims 0.75–2.51 px.
pub const SHARP_RIM_PX: f64 = 0.5;
/// The frames that decide c with the rest frames: first-pass lifts up to this
/// \[px\], over which the gap between the rim and its mirror image (2 (c + z) wide)
/// opens through the blur ([`MIRROR_REACH_PX`]).
const NEAR_CONTACT_PX: f64 = MIRROR_REACH_PX;
/// Frames near contact the test needs; with fewer the rest frames' own c decides.
const MIN_NEAR_CONTACT_FRAMES: usize = MIN_TEMPLATE_FRAMES;
/// The lowest c the test searches \[px\]: a plate line above the edge at rest is not
/// physical (the mirror image would overlap the disk); half a pixel is left for
/// noise.
const MIN_PLATE_OFFSET_PX: f64 = -0.5;
/// Rows below the rest frames' first-pass edge that the rest fit reads \[px\]: a
/// rounded band of 2 px (a real rim's is 1–2.6 px) and the mirror's blur
/// ([`MIRROR_REACH_PX`]).
const REST_ROWS_BELOW_PX: f64 = 2.0 + MIRROR_REACH_PX;
/// The distance from the edge to the plate line at rest searched, c = y_p − e
/// \[px\]: from a sharp rim (c ≈ 0) to one rounded over most of the window below.
const PLATE_OFFSET_PX: Range<f64> = -1.0..(ROWS_BELOW as f64 - 3.0);

/// D(u): the disk's bottom-edge profile divided by the disk's level, at offsets u
/// from the edge \[px\], tabulated every [`BIN_PX`] (bins with too few samples
/// between two others interpolated linearly).
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeTemplate {
    /// The first bin's centre \[px\].
    first: f64,
    /// Mean normalised level per bin, one every [`BIN_PX`] from `first`.
    levels: Vec<f64>,
}

impl EdgeTemplate {
    /// Learns D from frames with an open gap: (window, first-pass edge row,
    /// first-pass z_rim \[px\]), each read above 2 z − `reach` \[px\], where its mirror
    /// image's light cannot reach ([`MIRROR_REACH_PX`], more on a rough plate).
    /// `None` with fewer than [`MIN_TEMPLATE_FRAMES`] frames lifted past `reach`, or
    /// no bin below the edge.
    pub fn learn<'a>(
        frames: impl Iterator<Item = (&'a BandWindow, f64, f64)>,
        reach: f64,
    ) -> Option<Self> {
        let lo = -(ROWS_ABOVE as f64);
        let bins = ((ROWS_ABOVE + ROWS_BELOW) as f64 / BIN_PX).round() as usize;
        let mut sum = vec![0.0; bins];
        let mut count = vec![0usize; bins];
        let mut used = 0;
        for (window, edge, z) in frames {
            let clear = 2.0 * z - reach;
            if clear <= 0.0 {
                continue;
            }
            let level = window.level();
            if level <= 0.0 {
                continue;
            }
            used += 1;
            for (centre, v) in window.samples() {
                let u = centre - edge;
                let bin = ((u - lo) / BIN_PX).floor();
                if u < clear && bin >= 0.0 && (bin as usize) < bins {
                    sum[bin as usize] += v / level;
                    count[bin as usize] += 1;
                }
            }
        }
        if used < MIN_TEMPLATE_FRAMES {
            return None;
        }
        let centre = |b: usize| lo + (b as f64 + 0.5) * BIN_PX;
        let filled: Vec<usize> = (0..bins).filter(|&b| count[b] >= MIN_BIN_SAMPLES).collect();
        let (&b0, &b1) = (filled.first()?, filled.last()?);
        if centre(b1) <= 1.0 {
            return None;
        }
        let mean = |b: usize| sum[b] / count[b] as f64;
        let mut levels = Vec::with_capacity(b1 - b0 + 1);
        for pair in filled.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            levels.extend(
                (a..b).map(|k| mean(a) + (k - a) as f64 / (b - a) as f64 * (mean(b) - mean(a))),
            );
        }
        levels.push(mean(b1));
        Some(Self {
            first: centre(b0),
            levels,
        })
    }

    /// D(u), linear between bins, constant beyond the first and last.
    pub fn at(&self, u: f64) -> f64 {
        let x = (u - self.first) / BIN_PX;
        let last = self.levels.len() - 1;
        if x <= 0.0 {
            return self.levels[0];
        }
        if x >= last as f64 {
            return self.levels[last];
        }
        let k = x as usize;
        let w = x - k as f64;
        self.levels[k] + w * (self.levels[k + 1] - self.levels[k])
    }

    /// The gap's level f: D far below the edge.
    pub fn floor(&self) -> f64 {
        self.levels[self.levels.len() - 1]
    }

    /// The width of D's fall from the side to the gap, as a Gaussian's σ \[px\]: half
    /// the distance between its 84 % and 16 % levels. For a sharp rim it is the
    /// camera's blur; a rounded rim widens it.
    fn edge_width(&self) -> f64 {
        let (top, f) = (self.levels[0], self.floor());
        let crossing = |share: f64| {
            let level = f + share * (top - f);
            let k = self.levels.iter().position(|&v| v < level)?;
            let (a, b) = (self.levels[k.checked_sub(1)?], self.levels[k]);
            Some(self.first + BIN_PX * ((k - 1) as f64 + (a - level) / (a - b)))
        };
        match (crossing(0.84), crossing(0.16)) {
            (Some(hi), Some(lo)) => 0.5 * (lo - hi),
            _ => 0.0,
        }
    }
}

/// A rough plate's reflection: the mirror image blurred by a Gaussian of width σ
/// over the plate's own rows, a normalised convolution (the plate shows the
/// reflection where it is seen, below the disk's edge, not on the disk). The
/// reflected scene is sharp before the blur: the mirror image of the disk's side,
/// 1 − f above the gap's level f, from the reflected edge at u = g down, so
///
/// ```text
/// M(u, g) = (1 − f) Φ((u − max(g, 0))/σ) / Φ(u/σ),
/// ```
///
/// u = y + ½ − e the row's offset below the edge and g = 2 (y_p − e) the
/// reflected edge's. σ is fitted, so it holds the camera's blur of the mirror
/// image with the plate's. The camera's blur of the plate's own boundary is D's:
/// the plate is seen on the share v = (1 − D(u))/(1 − f) of the row, so the model
/// is D(u) + ρ v M(u, g). At rest (g ≤ 0) that is D + ρ (1 − D), the step from the
/// side to the plate's mirror level that the sharp model gives too; under a
/// lifted rim the blurred mirror light fills the gap. Read with a sharp
/// reflection, rims lifted by 0.5–2 px come out up to 0.44 px low under a 2.4 px
/// plate blur (n +0.07 to +0.21).
#[derive(Clone, Copy, Debug, PartialEq)]
struct PlateBlur {
    sigma: f64,
}

/// The widest plate blur searched \[px\].
const MAX_PLATE_BLUR_PX: f64 = 4.0;

impl PlateBlur {
    /// M(u, g)/(1 − f), the mirror image's level in the plate's rows as a share of
    /// its full level (0 well above them, where the row shows the disk alone).
    fn level(&self, u: f64, g: f64) -> f64 {
        let cdf = |x: f64| 0.5 * (1.0 + statrs::function::erf::erf(x / std::f64::consts::SQRT_2));
        let seen = cdf(u / self.sigma);
        if seen > 1e-12 {
            cdf((u - g.max(0.0)) / self.sigma) / seen
        } else {
            0.0
        }
    }
}

/// The fitted model: D, the plate's line and reflectivity, and the edge at rest.
#[derive(Clone, Debug, PartialEq)]
pub struct MirrorEdgeModel {
    template: EdgeTemplate,
    /// The mirror image's blur on a rough plate (`None`: a sharp reflection).
    plate_blur: Option<PlateBlur>,
    /// y_p: the plate's line under the centre column, where the resting rim meets
    /// its mirror image (continuous row, px).
    pub plate_row: f64,
    /// ρ: the mirror image's contrast relative to the disk's.
    pub reflectivity: f64,
    /// e_rest: the fitted edge of the rest frames (continuous row, px).
    pub rest_edge: f64,
    /// RMS of the rest fit relative to the disk's level.
    pub rest_rms: f64,
    /// c = y_p − e_rest as the test of a sharp rim ([`SHARP_RIM_PX`]) has it: fitted
    /// with the frames near contact ([`MirrorEdgeModel::plate_offset_near_contact`])
    /// when there are enough, else the rest frames' own.
    pub plate_offset_test: f64,
    /// The frames near contact that fitted `plate_offset_test` (0: the rest frames
    /// alone did).
    pub near_contact_frames: usize,
}

/// One frame near contact as [`MirrorEdgeModel::near_contact_ssr`] reads it: its
/// rows (centre, value over its own level) and its first-pass edge.
type NearContact = (Vec<(f64, f64)>, f64);

/// The rest frames' rows (centre, value over their level) and the frames near
/// contact, the inputs of the fits of c and of the plate's blur.
type NearContactInputs = (Vec<(f64, f64)>, Vec<NearContact>);

impl MirrorEdgeModel {
    /// Fits ρ, y_p and e_rest to the rest frames' mean window, `rest_edge0` their
    /// first-pass edge (or the calibrated plate line when they read contact), for a
    /// sharp reflection.
    pub fn fit(template: EdgeTemplate, rest: &BandWindow, rest_edge0: f64) -> Self {
        Self::fit_with_blur(template, None, rest, rest_edge0)
    }

    /// [`MirrorEdgeModel::fit`] with the plate's blur of the mirror image.
    fn fit_with_blur(
        template: EdgeTemplate,
        plate_blur: Option<PlateBlur>,
        rest: &BandWindow,
        rest_edge0: f64,
    ) -> Self {
        let profile = Profile {
            template: &template,
            blur: plate_blur.as_ref(),
        };
        let samples = rest_samples(rest, rest_edge0);
        // Coarse grid over (ρ, c, e), then two finer ones about the best.
        let mut best = (f64::INFINITY, rest_edge0, 0.0, 0.0);
        rest_grid(
            profile,
            &samples,
            &mut best,
            (rest_edge0 - SEARCH_PX, rest_edge0 + SEARCH_PX, 0.1),
            (PLATE_OFFSET_PX.start, PLATE_OFFSET_PX.end, 0.1),
            (0.0, 1.0, 0.05),
        );
        for step in [0.01, 0.001] {
            let (_, e, c, rho) = best;
            let span = 10.0 * step;
            rest_grid(
                profile,
                &samples,
                &mut best,
                (e - span, e + span, step),
                (c - span, c + span, step),
                rho_about(rho, step),
            );
        }
        let (ssr, e, c, rho) = best;
        Self {
            template,
            plate_blur,
            plate_row: e + c,
            reflectivity: rho,
            rest_edge: e,
            rest_rms: (ssr / samples.len() as f64).sqrt(),
            plate_offset_test: c,
            near_contact_frames: 0,
        }
    }

    /// c = y_p − e_rest fitted to the rest frames and the frames near contact
    /// together (first-pass lifts up to [`NEAR_CONTACT_PX`]; `near`: window,
    /// first-pass edge and lift), each frame with its own edge and light, ρ and
    /// e_rest refitted to the rest frames at each c. Each frame is read down to
    /// [`REST_ROWS_BELOW_PX`] below its mirror image's rest position (its
    /// first-pass edge + 2 × lift), the same rows for every c, as the rest frames
    /// are. The rest frames are one window among the hundreds near contact, so c
    /// comes mostly from those. `None` with fewer than
    /// [`MIN_NEAR_CONTACT_FRAMES`] frames, or no finite fit; c is searched from
    /// [`MIN_PLATE_OFFSET_PX`].
    ///
    /// The rest frames alone see one step where the rim meets its mirror image,
    /// which a sharp edge with c = 0 and a slightly higher edge over a thin blurred
    /// gap (c ≈ 0.4–0.7 px) explain alike; the frames near contact do not, as the
    /// gap 2 (c + z) opens through the blur. On our own sharp renders, blurred or
    /// not, this gives c = +0.03 … +0.16 px where the rest frames alone gave
    /// −0.46 … +0.67. A rounded rim's mirror image shows the rounding from below,
    /// lit unlike D, so for it this c is only a test (0.75–2.51 px on rounded
    /// rims; taken as the plate line, it puts their heights off by enough to miss
    /// the targets) and the rest frames' own fit is kept ([`remeasure`]).
    pub fn plate_offset_near_contact(
        &self,
        rest: &BandWindow,
        near: &[(&BandWindow, f64, f64)],
    ) -> Option<f64> {
        let (rest_samples, near_samples) = self.near_contact_inputs(rest, near)?;
        let total = |c: f64| self.near_contact_ssr(self.profile(), &rest_samples, &near_samples, c);
        let mut best = (f64::INFINITY, f64::NAN);
        for c in steps((MIN_PLATE_OFFSET_PX, PLATE_OFFSET_PX.end, 0.25)) {
            let ssr = total(c);
            if ssr < best.0 {
                best = (ssr, c);
            }
        }
        if !best.1.is_finite() {
            return None;
        }
        let c = golden_section(
            total,
            (best.1 - 0.25).max(MIN_PLATE_OFFSET_PX),
            best.1 + 0.25,
            Stop::Width(0.01),
        )
        .midpoint();
        c.is_finite().then_some(c)
    }

    /// The plate's blur of the mirror image, σ_m \[px\] ([`PlateBlur`]), fitted to
    /// the rest frames and the frames near contact together at the model's c
    /// (`plate_offset_test`), as [`MirrorEdgeModel::plate_offset_near_contact`]
    /// reads them: as the gap under the rim opens, a blurred reflection fills it
    /// with light, where a sharp one leaves it dark to its mirror edge. Searched
    /// over 0 … [`MAX_PLATE_BLUR_PX`]; `None` for a sharp reflection (σ_m = 0 fits
    /// best, or the plate's share of σ is not resolved beyond D's own width), or
    /// with fewer than [`MIN_NEAR_CONTACT_FRAMES`] frames.
    fn plate_blur_near_contact(
        &self,
        rest: &BandWindow,
        near: &[(&BandWindow, f64, f64)],
    ) -> Option<f64> {
        let (rest_samples, near_samples) = self.near_contact_inputs(rest, near)?;
        let c = self.plate_offset_test;
        let total = |sigma: f64| {
            let blur = (sigma > 0.0).then_some(PlateBlur { sigma });
            let profile = Profile {
                template: &self.template,
                blur: blur.as_ref(),
            };
            self.near_contact_ssr(profile, &rest_samples, &near_samples, c)
        };
        let grid = [0.0, 0.5, 1.0, 1.5, 2.0, 3.0, MAX_PLATE_BLUR_PX];
        let ssr: Vec<f64> = grid.iter().map(|&sigma| total(sigma)).collect();
        let k = (0..grid.len()).min_by(|&a, &b| ssr[a].total_cmp(&ssr[b]))?;
        if k == 0 {
            return None;
        }
        let sigma = golden_section(
            total,
            grid[k - 1],
            grid[(k + 1).min(grid.len() - 1)],
            Stop::Width(0.05),
        )
        .midpoint();
        // The plate's own share of σ, √(σ² − w²) with w D's own width (the camera's
        // blur of a sharp rim), must be resolved, at least w: below it the sharp
        // model, whose mirror image is D reflected with the camera's blur exact, is
        // the better description (on 2-view renders with no plate blur σ came out
        // as the camera's 1.0 px, and read with it φ at the peaks went +1.7 → +6.9 %).
        let width = self.template.edge_width();
        (sigma.is_finite() && total(sigma) < ssr[0] && sigma * sigma > 2.0 * width * width)
            .then_some(sigma)
    }

    /// The rest frames' rows about the model's edge at rest and the frames near
    /// contact as [`near_contact_samples`] reads them; `None` with fewer than
    /// [`MIN_NEAR_CONTACT_FRAMES`] frames.
    fn near_contact_inputs(
        &self,
        rest: &BandWindow,
        near: &[(&BandWindow, f64, f64)],
    ) -> Option<NearContactInputs> {
        (near.len() >= MIN_NEAR_CONTACT_FRAMES).then(|| {
            (
                rest_samples(rest, self.rest_edge),
                near_contact_samples(near),
            )
        })
    }

    /// The rest frames' and the frames near contact's SSR with the plate line c
    /// below the edge at rest, ρ and e_rest refitted to the rest frames at that c
    /// and each frame near contact fitted for its own edge and light.
    fn near_contact_ssr(
        &self,
        profile: Profile,
        rest_samples: &[(f64, f64)],
        near_samples: &[NearContact],
        c: f64,
    ) -> f64 {
        let (rest_ssr, e_rest, rho) = rest_fit_at(
            profile,
            rest_samples,
            (self.rest_edge, self.reflectivity),
            c,
        );
        // Collected in order and summed in order: the same c on every run.
        let frames: Vec<f64> = near_samples
            .par_iter()
            .map(|(samples, edge0)| edge_fit(profile, samples, *edge0, e_rest + c, rho, 0.2).1)
            .collect();
        rest_ssr + frames.iter().sum::<f64>()
    }

    /// D and the plate's blur, as the fits read them.
    fn profile(&self) -> Profile<'_> {
        Profile {
            template: &self.template,
            blur: self.plate_blur.as_ref(),
        }
    }

    /// The rest fit with c fixed: (SSR, e_rest, ρ).
    fn rest_fit_at(&self, samples: &[(f64, f64)], c: f64) -> (f64, f64, f64) {
        rest_fit_at(
            self.profile(),
            samples,
            (self.rest_edge, self.reflectivity),
            c,
        )
    }
}

/// The rest fit with c fixed: (SSR, e_rest, ρ), on grids of 0.05, 0.01 and 0.001
/// about the last best, starting from `(e_rest, ρ)`.
fn rest_fit_at(
    profile: Profile,
    samples: &[(f64, f64)],
    (rest_edge, reflectivity): (f64, f64),
    c: f64,
) -> (f64, f64, f64) {
    let at_c = (c, c, 1.0);
    let mut best = (f64::INFINITY, rest_edge, c, reflectivity);
    rest_grid(
        profile,
        samples,
        &mut best,
        (rest_edge - SEARCH_PX, rest_edge + SEARCH_PX, 0.05),
        at_c,
        (0.0, 1.0, 0.05),
    );
    for step in [0.01, 0.001] {
        let (_, e, _, rho) = best;
        rest_grid(
            profile,
            samples,
            &mut best,
            (e - 5.0 * step, e + 5.0 * step, step),
            at_c,
            rho_about(rho, step),
        );
    }
    let (ssr, e, _, rho) = best;
    (ssr, e, rho)
}

impl MirrorEdgeModel {
    /// The edge row of one frame's window: the mean of e under the fit's likelihood
    /// about the least-squares edge, which is sought within ±[`SEARCH_PX`] of the
    /// first-pass edge `edge0` (a 0.05 px grid, then golden-section search).
    ///
    /// The least-squares edge alone is not a continuous function of the model. A
    /// frame whose rows the template does not quite describe (codec ringing over
    /// the edge) can have two minima of nearly equal SSR a tenth of a pixel apart,
    /// and which of them is lower then turns on the third decimal of D. On a long
    /// clip (`tests/long_clip.rs`), D learned from the last 5 s and from all 12 s
    /// differ by 0.01 at the rim's foot, and such frames read 0.1 px apart
    /// (+0.13 px and +0.03 px from the truth). The mean over the likelihood,
    /// exp(−ΔSSR / 2s²) with s² = SSR_min / (rows − 2) (the edge and the light
    /// fitted), weighs both minima by how well each fits, so it changes little
    /// when the model changes little; where there is one clear minimum it is the
    /// least-squares edge. `tests/long_clip.rs` guards it: with the least-squares
    /// edge alone that frame fails the test's 0.1 px bound.
    pub fn edge(&self, window: &BandWindow, edge0: f64) -> f64 {
        // Rows down to the mirror image's edge, 2 y_p − e, and its blur (as at rest).
        let mirror = 2.0 * self.plate_row - edge0;
        let last = edge0.max(mirror) + self.mirror_reach();
        let samples: Vec<(f64, f64)> = window.samples().filter(|&(y, _)| y <= last).collect();
        let (profile, plate_row, rho) = (self.profile(), self.plate_row, self.reflectivity);
        let (e_min, ssr_min) = edge_fit(profile, &samples, edge0, plate_row, rho, 0.05);
        let two_s2 = 2.0 * ssr_min / samples.len().saturating_sub(2).max(1) as f64;
        if !(two_s2 > 0.0 && two_s2.is_finite()) {
            return e_min;
        }
        let (mut weights, mut moment) = (0.0, 0.0);
        for e in steps((e_min - LIKELIHOOD_PX, e_min + LIKELIHOOD_PX, 0.02)) {
            let ssr = edge_ssr(profile, &samples, e, plate_row, rho);
            let w = (-(ssr - ssr_min) / two_s2).exp();
            weights += w;
            moment += w * e;
        }
        moment / weights
    }

    /// How far below its edge a mirror image's light reaches \[px\]:
    /// [`MIRROR_REACH_PX`], and three σ_m more on a rough plate.
    fn mirror_reach(&self) -> f64 {
        MIRROR_REACH_PX + self.plate_blur.as_ref().map_or(0.0, |b| 3.0 * b.sigma)
    }

    /// The plate's blur of the mirror image, σ_m \[px\] (0: a sharp reflection).
    pub fn mirror_blur_px(&self) -> f64 {
        self.plate_blur.as_ref().map_or(0.0, |b| b.sigma)
    }

    /// Whether the rim is sharp at this resolution: the test's c
    /// (`plate_offset_test`) puts the plate line less than [`SHARP_RIM_PX`] below
    /// the edge at rest.
    pub fn is_sharp(&self) -> bool {
        self.plate_offset_test < SHARP_RIM_PX
    }

    /// z_rim \[px\] of one frame: e_rest − e.
    pub fn z_rim_px(&self, window: &BandWindow, edge0: f64) -> f64 {
        self.rest_edge - self.edge(window, edge0)
    }
}

/// The SSR of the model (`profile`, plate line `plate_row`, reflectivity `rho`)
/// with its edge at row `e` against one frame's samples, the light fitted.
fn edge_ssr(profile: Profile, samples: &[(f64, f64)], e: f64, plate_row: f64, rho: f64) -> f64 {
    best_gain_ssr(samples, |y| profile.value(y, e, plate_row, rho))
}

/// The edge row fitted to one frame's (row centre, value) `samples` within
/// ±[`SEARCH_PX`] of `edge0`, and its SSR: a grid of `step` \[px\], then
/// golden-section search.
fn edge_fit(
    profile: Profile,
    samples: &[(f64, f64)],
    edge0: f64,
    plate_row: f64,
    rho: f64,
    step: f64,
) -> (f64, f64) {
    let cost = |e: f64| edge_ssr(profile, samples, e, plate_row, rho);
    let mut best = (f64::INFINITY, edge0);
    for e in steps((edge0 - SEARCH_PX, edge0 + SEARCH_PX, step)) {
        let ssr = cost(e);
        if ssr < best.0 {
            best = (ssr, e);
        }
    }
    let e = golden_section(cost, best.1 - step, best.1 + step, Stop::Width(1e-4)).midpoint();
    (e, cost(e))
}

/// The frames near contact (window, first-pass edge, lift) as the test of c reads
/// them: each down to [`REST_ROWS_BELOW_PX`] below its mirror image's rest
/// position (its first-pass edge + 2 × lift), divided by its own level.
fn near_contact_samples(near: &[(&BandWindow, f64, f64)]) -> Vec<NearContact> {
    near.iter()
        .map(|&(window, edge0, lift)| {
            let last = edge0 + 2.0 * lift + REST_ROWS_BELOW_PX;
            let level = window.level();
            let samples = window
                .samples()
                .filter(|&(y, _)| y <= last)
                .map(|(y, v)| (y, v / level))
                .collect();
            (samples, edge0)
        })
        .collect()
}

/// Re-measures a clip's rim heights with the model (module docs): `heights` are
/// the first-pass z_rim per frame \[px\] (`None`: no edge, left alone), `windows`
/// each frame's band rows about its first-pass edge z_base − z, `rest` the rest
/// frames' mean window about `rest_edge0`. Returns the model, or why it was not
/// used (and then changes nothing): too few frames open the gap to learn D.
pub fn remeasure(
    heights: &mut [Option<f64>],
    windows: &[Option<BandWindow>],
    z_base: f64,
    rest: &BandWindow,
    rest_edge0: f64,
) -> Result<MirrorEdgeModel, String> {
    let learn = |reach: f64| {
        EdgeTemplate::learn(
            heights
                .iter()
                .zip(windows.iter())
                .filter_map(|(z, w)| Some((w.as_ref()?, z_base - (*z)?, (*z)?))),
            reach,
        )
    };
    let template = learn(MIRROR_REACH_PX)
        .ok_or("too few frames lift the rim far enough to learn its profile")?;
    let mut model = MirrorEdgeModel::fit(template, rest, rest_edge0);
    let near: Vec<(&BandWindow, f64, f64)> = heights
        .iter()
        .zip(windows)
        .filter_map(|(z, w)| {
            let z = (*z)?;
            (z > 0.0 && z <= NEAR_CONTACT_PX).then_some((w.as_ref()?, z_base - z, z))
        })
        .filter(|(w, _, _)| w.level() > 0.0)
        .collect();
    if let Some(c) = model.plate_offset_near_contact(rest, &near) {
        model.plate_offset_test = c;
        model.near_contact_frames = near.len();
    }
    // A rough plate: D learned again from the rows its blurred mirror image cannot
    // reach, and the model fitted again with the blur.
    if let Some(sigma) = model.plate_blur_near_contact(rest, &near) {
        let template =
            learn(MIRROR_REACH_PX + 3.0 * sigma).unwrap_or_else(|| model.template.clone());
        let blur = PlateBlur { sigma };
        let test = (model.plate_offset_test, model.near_contact_frames);
        model = MirrorEdgeModel::fit_with_blur(template, Some(blur), rest, rest_edge0);
        (model.plate_offset_test, model.near_contact_frames) = test;
        if let Some(c) = model.plate_offset_near_contact(rest, &near) {
            model.plate_offset_test = c;
        }
    }
    if model.is_sharp() {
        // The mirror image of a sharp rim is D reflected, as the model has it, and
        // the frames near contact fix c where the rest frames alone cannot.
        let c = model.plate_offset_test;
        let samples = rest_samples(rest, model.rest_edge);
        let (ssr, e, rho) = model.rest_fit_at(&samples, c);
        model.rest_edge = e;
        model.plate_row = e + c;
        model.reflectivity = rho;
        model.rest_rms = (ssr / samples.len() as f64).sqrt();
    }
    for (z, w) in heights.iter_mut().zip(windows) {
        if let (Some(height), Some(window)) = (z.as_mut(), w) {
            *height = model.z_rim_px(window, z_base - *height);
        }
    }
    Ok(model)
}

/// The rest frames' rows down to [`REST_ROWS_BELOW_PX`] below their edge
/// `rest_edge0`, divided by the disk's level. Further down the mirror image shows
/// the plate's own texture and the disk's shadow on it (a 13-level step 5 rows
/// down on our renders), which the model does not describe and which pulled y_p by
/// 0.3 px.
fn rest_samples(rest: &BandWindow, rest_edge0: f64) -> Vec<(f64, f64)> {
    let level = rest.level();
    let last = rest_edge0 + REST_ROWS_BELOW_PX;
    rest.samples()
        .filter(|&(y, _)| y <= last)
        .map(|(y, v)| (y, v / level))
        .collect()
}

/// The rest fit's grid search: every (ρ, c, e) of the three (start, end, step)
/// ranges, keeping in `best` = (SSR, e, c, ρ) the least SSR of the model (edge e,
/// plate line e + c, reflectivity ρ) against the rest frames' `samples`.
fn rest_grid(
    profile: Profile,
    samples: &[(f64, f64)],
    best: &mut (f64, f64, f64, f64),
    e_range: (f64, f64, f64),
    c_range: (f64, f64, f64),
    rho_range: (f64, f64, f64),
) {
    for rho in steps(rho_range) {
        for c in steps(c_range) {
            for e in steps(e_range) {
                let ssr = best_gain_ssr(samples, |y| profile.value(y, e, e + c, rho));
                if ssr < best.0 {
                    *best = (ssr, e, c, rho);
                }
            }
        }
    }
}

/// ρ ± 5 `step`s, within [0, 1].
fn rho_about(rho: f64, step: f64) -> (f64, f64, f64) {
    (
        (rho - 5.0 * step).max(0.0),
        (rho + 5.0 * step).min(1.0),
        step,
    )
}

/// D and, on a rough plate, the mirror image's blur: what the model's value at a
/// row is made of.
#[derive(Clone, Copy)]
struct Profile<'a> {
    template: &'a EdgeTemplate,
    blur: Option<&'a PlateBlur>,
}

impl Profile<'_> {
    /// The model's normalised value at row centre `y` (module docs; on a rough
    /// plate the mirror term of [`PlateBlur`]).
    fn value(&self, y: f64, edge: f64, plate_row: f64, rho: f64) -> f64 {
        let d = self.template;
        let (u, g) = (y - edge, 2.0 * (plate_row - edge));
        let own = d.at(u);
        let mirror = match self.blur {
            Some(blur) => {
                // The share of the row where the plate is seen, times the side's
                // contrast: 1 − D(u).
                let plate_seen = (1.0 - own).max(0.0);
                plate_seen * blur.level(u, g)
            }
            None => d.at(g - u) - d.floor(),
        };
        own + rho * mirror
    }
}

/// min over g of Σ (g m(y) − v)²: the least squares with the light g free.
fn best_gain_ssr(samples: &[(f64, f64)], model: impl Fn(f64) -> f64) -> f64 {
    let (mut mm, mut mv, mut vv) = (0.0, 0.0, 0.0);
    for &(y, v) in samples {
        let m = model(y);
        mm += m * m;
        mv += m * v;
        vv += v * v;
    }
    if mm <= 0.0 { vv } else { vv - mv * mv / mm }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rounded rim seen through blur: the side's level 1 falls to a dark band
    /// (0.1) over the last `round_px` above the rim, then the gap (0.15); the
    /// mirror image below the plate line with contrast ρ. Sampled by area, 8-bit.
    fn profile(
        rows: Range<usize>,
        (rim, plate, round_px): (f64, f64, f64),
        rho: f64,
        gain: f64,
    ) -> BandWindow {
        let disk = |x: f64| -> f64 {
            // x: distance above the rim (px); the rounded part shades smoothly.
            if x <= 0.0 {
                0.15
            } else if x < round_px {
                let s = x / round_px;
                0.1 + 0.9 * s * s * (3.0 - 2.0 * s)
            } else {
                1.0
            }
        };
        let blurred = |y: f64| -> f64 {
            // Area sampling with a 0.8 px Gaussian, by fine quadrature.
            let (sub, sigma) = (40, 0.8f64);
            let mut acc = 0.0;
            let mut wsum = 0.0;
            for i in 0..sub {
                let yy = y + (i as f64 + 0.5) / sub as f64;
                for j in -24..=24 {
                    let d = j as f64 * 0.125;
                    let w = (-0.5 * (d / sigma).powi(2)).exp();
                    let at = yy + d;
                    let own = disk(rim - at);
                    let mirror = disk(at - (2.0 * plate - rim));
                    acc += w * (own + rho * (mirror - 0.15));
                    wsum += w;
                }
            }
            acc / wsum
        };
        BandWindow {
            first_row: rows.start,
            values: rows
                .map(|y| ((200.0 * gain * blurred(y as f64)).round()) as f32)
                .collect(),
            shift: 0.0,
        }
    }

    /// The band rows of a rim rounded over `round_px`, lifted by `z` above `plate`.
    fn lifted(plate: f64, round_px: f64, rho: f64, z: f64, gain: f64) -> BandWindow {
        let rim = plate - z;
        let first = (rim.round() as usize) - ROWS_ABOVE;
        profile(
            first..first + ROWS_ABOVE + ROWS_BELOW,
            (rim, plate, round_px),
            rho,
            gain,
        )
    }

    /// A sharp rim, its first-pass heights off by up to ±0.2 px: found sharp, its
    /// plate line at the edge, and every height refitted to the truth.
    #[test]
    fn a_sharp_rims_heights_are_refitted_at_its_plate_line() {
        let plate = 60.3;
        let lifts: Vec<f64> = (0..120).map(|k| 0.05 + 0.11 * k as f64).collect();
        let windows: Vec<Option<BandWindow>> = lifts
            .iter()
            .map(|&z| Some(lifted(plate, 0.05, 0.4, z, 1.0)))
            .collect();
        let mut heights: Vec<Option<f64>> = lifts
            .iter()
            .enumerate()
            .map(|(k, &z)| Some(z + 0.2 * (k as f64 * 2.39).sin()))
            .collect();
        let rest = lifted(plate, 0.05, 0.4, 0.0, 1.0);
        let model = remeasure(&mut heights, &windows, plate, &rest, plate).expect("model");
        assert!(model.is_sharp(), "c {}", model.plate_offset_test);
        assert!(model.near_contact_frames >= MIN_NEAR_CONTACT_FRAMES);
        assert!((model.plate_row - plate).abs() < 0.1, "{}", model.plate_row);
        for (z, found) in lifts.iter().zip(&heights) {
            let found = found.expect("a height");
            assert!((found - z).abs() < 0.05, "lift {z}: found {found}");
        }
    }

    #[test]
    fn lifted_heights_and_the_plate_line_of_a_rounded_rim() {
        // Truth: plate line at row 60.3; the rim lifted by z is at 60.3 − z.
        let plate = 60.3;
        let rho = 0.4;
        let window = |z: f64, gain: f64| lifted(plate, 2.2, rho, z, gain);
        // First-pass edges: the rim plus the rounded band's half (a fixed offset
        // the model must not need), with ±0.15 px of alignment noise.
        let first_pass = |z: f64, k: usize| plate - z - 1.1 + 0.15 * ((k as f64 * 2.39).sin());
        let lifts: Vec<f64> = (0..120).map(|k| 0.05 + 0.11 * k as f64).collect();
        let windows: Vec<BandWindow> = lifts
            .iter()
            .enumerate()
            .map(|(k, &z)| window(z, 1.0 + 0.08 * (k as f64).sin()))
            .collect();
        let template = EdgeTemplate::learn(
            windows
                .iter()
                .zip(&lifts)
                .enumerate()
                .map(|(k, (w, &z))| (w, first_pass(z, k), z)),
            MIRROR_REACH_PX,
        )
        .expect("template");
        let rest = window(0.0, 1.0);
        let model = MirrorEdgeModel::fit(template, &rest, plate - 1.1);
        assert!(
            (model.plate_row - plate).abs() < 0.05,
            "plate line {} vs {plate}",
            model.plate_row
        );
        assert!((model.reflectivity - rho).abs() < 0.05);
        for (k, (&z, w)) in lifts.iter().zip(&windows).enumerate().step_by(7) {
            let found = model.z_rim_px(w, first_pass(z, k));
            assert!((found - z).abs() < 0.05, "lift {z}: found {found}");
        }
        // The frames near contact agree on the rounded rim's plate line: the
        // mirror image here is D reflected, as the model has it.
        let near: Vec<(&BandWindow, f64, f64)> = windows
            .iter()
            .zip(&lifts)
            .enumerate()
            .filter(|(_, (_, z))| **z <= NEAR_CONTACT_PX)
            .map(|(k, (w, &z))| (w, first_pass(z, k), plate - 1.1 - first_pass(z, k)))
            .collect();
        let c = model.plate_offset_near_contact(&rest, &near).expect("c");
        let c_rest = model.plate_row - model.rest_edge;
        assert!(
            c > SHARP_RIM_PX && (c - c_rest).abs() < 0.1,
            "c {c} vs {c_rest}"
        );
    }

    /// A sharp rim under a 0.8 px blur, its first-pass heights off by up to
    /// ±0.3 px (which blurs the template D a little): the rest frame alone leaves
    /// its edge and the plate line free to trade (edge up to 0.16 px off and c from
    /// −0.17 to +0.08 px here; −0.46 … +0.67 px on six of our renders); the frames
    /// near contact put the plate line at the edge.
    #[test]
    fn the_frames_near_contact_find_a_sharp_rims_plate_line() {
        let plate = 60.3;
        let lifts: Vec<f64> = (0..200).map(|k| 0.02 + 0.07 * k as f64).collect();
        let windows: Vec<BandWindow> = lifts
            .iter()
            .map(|&z| lifted(plate, 0.05, 0.3, z, 1.0))
            .collect();
        let rest = lifted(plate, 0.05, 0.3, 0.0, 1.0);
        for error in [0.0, 0.15, 0.3] {
            let first_pass: Vec<f64> = lifts
                .iter()
                .enumerate()
                .map(|(k, &z)| z + error * (k as f64 * 2.39).sin())
                .collect();
            let template = EdgeTemplate::learn(
                windows
                    .iter()
                    .zip(&first_pass)
                    .map(|(w, &z)| (w, plate - z, z)),
                MIRROR_REACH_PX,
            )
            .expect("template");
            let model = MirrorEdgeModel::fit(template, &rest, plate);
            let near: Vec<(&BandWindow, f64, f64)> = windows
                .iter()
                .zip(&first_pass)
                .filter(|(_, z)| **z > 0.0 && **z <= NEAR_CONTACT_PX)
                .map(|(w, &z)| (w, plate - z, z))
                .collect();
            let c = model.plate_offset_near_contact(&rest, &near).expect("c");
            assert!(c.abs() < 0.1, "first-pass error {error}: c {c}");
        }
    }

    /// The band rows of a sharp rim lifted by `z` above `plate` on a rough plate:
    /// the mirror image (contrast ρ) blurred by `sigma_m` over the plate's own rows
    /// (a normalised convolution, as `render` draws a blurred reflection), then the
    /// whole picture by a 0.8 px Gaussian, sampled by area, 8-bit.
    fn rough_plate_window(plate: f64, rho: f64, sigma_m: f64, z: f64) -> BandWindow {
        let rim = plate - z;
        let mirror_rim = plate + z;
        let first = (rim.round() as usize) - ROWS_ABOVE;
        let rows = ROWS_ABOVE + ROWS_BELOW;
        // The picture before the camera's blur, on a fine grid.
        let fine = 0.025;
        let (x0, x1) = (first as f64 - 4.0, (first + rows) as f64 + 4.0);
        let xs: Vec<f64> = steps((x0, x1, fine)).collect();
        let mirror = |x: f64| if x >= mirror_rim { 0.85 } else { 0.0 };
        let picture: Vec<f64> = xs
            .iter()
            .map(|&x| {
                if x < rim {
                    return 1.0;
                }
                let (mut num, mut den) = (0.0, 0.0);
                for s in steps((-4.0 * sigma_m, 4.0 * sigma_m, 0.05)) {
                    if x + s >= rim {
                        let w = (-0.5 * (s / sigma_m).powi(2)).exp();
                        num += w * mirror(x + s);
                        den += w;
                    }
                }
                0.15 + rho * num / den
            })
            .collect();
        let at = |x: f64| picture[(((x - x0) / fine).round() as usize).min(xs.len() - 1)];
        let values = (first..first + rows)
            .map(|y| {
                let (mut acc, mut wsum) = (0.0, 0.0);
                for i in 0..40 {
                    let yy = y as f64 + (i as f64 + 0.5) / 40.0;
                    for j in -24..=24 {
                        let d = j as f64 * 0.125;
                        let w = (-0.5 * (d / 0.8f64).powi(2)).exp();
                        acc += w * at(yy + d);
                        wsum += w;
                    }
                }
                (200.0 * acc / wsum).round() as f32
            })
            .collect();
        BandWindow {
            first_row: first,
            values,
            shift: 0.0,
        }
    }

    /// A sharp rim over a rough plate, whose reflection is blurred by 2 px: the
    /// blur is found, and the lifted heights are read within 0.1 px (0.025 px RMS).
    /// Read with a sharp reflection, the blurred mirror light that fills the gap
    /// under the rim made them up to 0.25 px low here (0.073 px RMS).
    #[test]
    fn a_rough_plates_blurred_reflection_is_fitted() {
        let (plate, rho, sigma_m) = (60.3, 0.5, 2.0);
        let lifts: Vec<f64> = (0..120).map(|k| 0.05 + 0.11 * k as f64).collect();
        let windows: Vec<Option<BandWindow>> = lifts
            .iter()
            .map(|&z| Some(rough_plate_window(plate, rho, sigma_m, z)))
            .collect();
        let mut heights: Vec<Option<f64>> = lifts
            .iter()
            .enumerate()
            .map(|(k, &z)| Some(z + 0.2 * (k as f64 * 2.39).sin()))
            .collect();
        let rest = rough_plate_window(plate, rho, sigma_m, 0.0);
        let model = remeasure(&mut heights, &windows, plate, &rest, plate).expect("model");
        assert!(model.is_sharp(), "c {}", model.plate_offset_test);
        // σ holds the camera's blur of the mirror image with the plate's.
        let blur = model.mirror_blur_px();
        let combined = sigma_m.hypot(0.8);
        assert!((blur - combined).abs() < 0.3, "σ {blur} vs {combined}");
        let errors: Vec<f64> = lifts
            .iter()
            .zip(&heights)
            .map(|(z, found)| found.expect("a height") - z)
            .collect();
        let worst = errors.iter().fold(0.0f64, |w, e| w.max(e.abs()));
        let rms = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt();
        assert!(
            worst < 0.1 && rms < 0.035,
            "worst {worst:.3} px, RMS {rms:.3} px"
        );
    }

    #[test]
    fn too_few_open_gaps_give_no_template() {
        let w = BandWindow {
            first_row: 0,
            values: vec![100.0; ROWS_ABOVE + ROWS_BELOW],
            shift: 0.0,
        };
        let frames = vec![(&w, 14.0, 1.0); 100];
        assert_eq!(
            EdgeTemplate::learn(frames.into_iter(), MIRROR_REACH_PX),
            None
        );
    }
}
