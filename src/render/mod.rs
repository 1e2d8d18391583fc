//! Synthetic footage of Euler's disk with known ground truth: the test bed of every
//! vision and signal stage and the built-in demo (DESIGN.md, `render::`).
//!
//! # Role in the data flow
//!
//! ```text
//! PowerLaw (n, A_e, halt) ──► motion::power_law_motion ─┐
//! model::simulate Trajectory ► motion::trajectory_motion ┴► Motion (one DiskState per frame)
//!   │
//!   ▼  Renderer::new(&RenderSpec, &Motion)
//!   │    render_frame(i) → image::RgbImage      (pure, deterministic)
//!   │    truth()         → GroundTruth           (serde, the per-frame answers)
//!   ▼  write::write_clip → MP4 (H.264, libx264) or PNG folder + `<clip>.truth.json`
//! ```
//!
//! # The scene (thesis §3.2.3, figs. 3.3, 3.4, 3.9, 3.19)
//!
//! A white (paper-wrapped, §3.2.3) solid cylinder of radius R and half-thickness H
//! with an untouched dark bottom face stands on a 30 × 30 cm plate: a dark reflective
//! plate (steel, with the disk's mirror image, fig. 3.7) or a light matt one where the
//! shadow under the disk gives the contrast (fig. 3.9). The side camera is orthographic
//! (or a pinhole, see "Perspective" below), looks along +y and is tilted down by a
//! small elevation ε (default 3°). In the
//! two-view layout (fig. 3.19, portrait) the side view fills the rows above
//! `split_row` and a plan view from above, showing the red strip across the top face
//! (eq. 3.13), fills the rows below. See [`scene`] for frames and lights.
//!
//! # What the camera sees on the centre column, and z_rim
//!
//! The thesis measures z_rim on the centre column x_centre = (x_l + x_r)/2 of the rest
//! frame (ERRATA, §3.2.4) as the bottom edge of the white disk relative to the plate
//! line z_base, converted with δ = 2H/(z_base − z_t) (ERRATA, eq. 3.10), z_t the near
//! top rim on the centre column. [`GroundTruth`] records exactly that: for every frame
//! the lowest image point on the column x_centre whose ray first meets a white surface
//! (side or top face), found by ray casting the rendered geometry (marching up the
//! column in quarter pixels, then bisection to 1e-9 px), never by measuring the image.
//!
//! Geometry. With the symmetry axis along (−sin φ cos ψ, −sin φ sin ψ, cos φ) (eq.
//! 3.14) the contact point lies in the direction −e1 = −(cos ψ, sin ψ) from G, and the
//! bottom rim point at angle α from the high point is
//!
//! ```text
//! p(α) = G_xy + (H sin φ + R cos φ cos α) e1 + R sin α e2,   z(α) = R sin φ (1 + cos α),
//! ```
//!
//! e1 = (cos ψ, sin ψ), e2 = (−sin ψ, cos ψ). The column x = G_x cuts the rim where
//! (H sin φ + R cos φ cos α) cos ψ = R sin α sin ψ. The camera (looking along +y) sees
//! the underside when the contact point is behind the disk, and the white edge is the
//! near crossing; when the disk leans towards the camera it sees the lower silhouette,
//! which reaches down to the contact point while that is near the column (z_rim =
//! (R(1 − cos φ) + H sin φ) tan ε there, zero for ε = 0: seen from above, a contact
//! point in front of the rest rim sits higher in the image). So
//! z_rim(ψ) has period 2π in ψ: **one peak per precession cycle**, at ψ ≡ −π/2, when
//! the contact point is straight behind G and the high point of the bottom rim (α = 0)
//! faces the camera (fig. 3.6). The rim height there is exactly 2R sin φ; the image
//! height (v = y sin ε + z cos ε) relative to the rest frame's near bottom rim
//! (v = −R sin ε), divided by cos ε because δ = s/cos ε for a scale s m/px, gives
//!
//! ```text
//! z_rim,peak = 2R sin φ + (R (1 − cos φ) − H sin φ) tan ε        [m]   ([peak_z_rim])
//! ```
//!
//! so φ = arcsin(z_rim/2R) (eq. 3.9 as corrected) is exact for ε = 0, and for ε > 0
//! reads φ (1 − (h/2) tan ε) + (φ²/4) tan ε to first order: −0.44 % of φ for Euler's
//! disk (h = 0.167) at ε = 3°, −0.15 % at 1°. Sampling at 480 fps catches the peak
//! only to within a frame, which costs far more near the halt (§3.2.4).
//!
//! # Motions, post-flat spin and rest frames
//!
//! See [`motion`]: a power law E = A_e (t_halt − t)^n under stationary rolling or an
//! interpolated simulation; after the halt the disk is flat and the strip turns on
//! until t_β (eq. 4.113); the clip goes on for `after_halt` seconds (default 0.15 s)
//! of flat disk, whose last frames are the rest frames calibration uses.
//!
//! # Perspective (`camera_distance_m`)
//!
//! By default the side camera is orthographic, the limit of a distant camera. With
//! `camera_distance_m = Some(d)` it is a pinhole (see [`scene::Camera`]) looking along
//! f = (0, cos ε, −sin ε) through the plate point under the disk's centre at rest,
//! which the image point (cx, cy) shows as before; d is the depth along f of the near
//! rim's mid-height point (0, −R, H) at rest, so the centre (0, 0, H) is at depth
//! d + R cos ε, and the focal length makes the scale there `metres_per_px` (by default,
//! the diameter spans 90 % of the width at the centre's depth). The plan view stays
//! orthographic. The rays are cast one by one from the pinhole (the orthographic
//! views' parallel-ray shortcuts are kept for them), and the ground truth is exact for
//! this projection:
//!
//! * x_l, x_r: the ends of the bottom rim's silhouette at rest, the extremes of the
//!   image x of (R cos a, R sin a, 0) over a, by golden-section search (the thesis's
//!   "edges of the bottom of the disk", fig. 3.3; the top rim, nearer the camera, is
//!   wider: [`CameraTruth::x_l_top`]); x_centre their midpoint.
//! * z_base: the rim edge on the column x_centre at rest, ray cast as every frame's
//!   z_rim is, so z_rim = 0 at rest; z_t: where that column's rays pass from the side
//!   face to the top face (the near top rim), by bisection to 1e-9 px;
//!   [`CameraTruth::z_t_far`] the silhouette's top (the far top rim).
//! * z_rim_px: as for the orthographic camera, the lowest white point on the column
//!   x_centre, now along the pinhole's rays: the image height of the near bottom rim
//!   above its rest row in the perspective projection, of the true pose (with φ's
//!   nutation, if any, and drift).
//! * [`CameraTruth`]: the perspective factor (d + R cos ε)/d (depth of the centre over
//!   depth of the near rim), the vertical scale at the near bottom rim (0, −R, 0),
//!   1/|∂row/∂z| = (q·f)² / (F |u_z (q·f) − (q·u) f_z|) with q = N − C, and the
//!   scale at the centre's depth; δ = 2H/(z_base − z_t) (eq. 3.10) from the exact
//!   points. peak_z_rim's closed form is the orthographic one only.
//!
//! # Scenery
//!
//! [`Scenery`] overrides the paper's and the plate's grey levels (a light plate
//! brighter than the disk's side), adds a seeded grain texture to the plate
//! ([`scene::PlateTexture`]; it covers the whole plate, to the frame's edges), sets the
//! plate's reflectivity and blurs its mirror image (a Gaussian of σ px applied to the
//! mirror image alone: the blurred background's plus the blurred change the disk
//! makes), and moves the fill light (above 45° the top face is brighter than the side).
//!
//! # Camera artefacts
//!
//! Sensor noise: read noise σ and shot noise k, σ² = σ_read² + k² v for a pixel of
//! level v (Gaussian, a SplitMix64 generator seeded per frame and row, so frames are
//! reproducible in any order); Gaussian blur (σ px); mains flicker, the light gain
//! 1 + A₁₀₀ sin(2π·100 Hz·t + p₁₀₀) + A₅₀ sin(2π·50 Hz·t + p₅₀), recorded per frame as
//! [`FrameTruth::light_gain`]; motion smear (the mean of `exposure_samples` poses over
//! the exposure time, centred on the capture time, which the truth describes); lateral
//! drift (px/s at the disk's centre, ending at the rest position at the halt) and
//! dropped frames (missing from the output; the truth keeps every written frame's
//! capture index and true time); duplicated frames (a written frame that repeats the
//! previous one's bytes, as a phone that misses a capture does) and interpolated
//! frames (the rounded mean of the previous and next frames, as a phone inserts to
//! reach 240 or 960 fps): the truth keeps their true pose and lists them. Camera
//! shake ([`shake`]: a vibration, a slow sway and a roll, seeded) moves each view's
//! principal point and turns its rays' image coordinates, at each pose of the
//! exposure; a shaken frame's background is rendered anew, and the truth records
//! each frame's shake at its capture time ([`FrameTruth::camera_shake`]). The motion
//! may carry a nutation about stationary
//! rolling ([`Nutation`]). Pixels are anti-aliased:
//! rays are cast at the corners of 2 × 2 pixel blocks, then at the pixel corners of
//! blocks whose corners see different surfaces, then 16 rays (a rank-1 lattice, so
//! axis-aligned edges get 16 coverage levels; 8 where only the plate's shadow or
//! mirror image changes) in pixels whose corners disagree. A feature thinner than
//! 2 px that no block corner sees (the strip seen edge-on in the side view) can be
//! missed. Rays are cast only inside the image extent of the disk, its mirror
//! image and its shadow; the rest of the frame is a background rendered once.

pub mod motion;
pub mod scene;
pub mod shake;
pub mod write;

use crate::rng::SplitMix64;
use std::path::PathBuf;

use image::RgbImage;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::footage::Orientation;
use crate::model::params::DiskParams;
pub use motion::{
    CaptureJitter, DiskState, Motion, MotionSource, Nutation, PostFlatSpin, PowerLaw,
    TICKS_PER_FRAME, Timing, add_nutation, power_law_motion, trajectory_motion,
};
pub use scene::Plate;
use scene::{
    Camera, Channels, DiskShape, Look, PLATE_CLASSES, Pinhole, Pose, Prepared, Sample, Scene,
    Surface, View,
};
use shake::Roll;
pub use shake::{Shake, ShakeMotion, ShakeOffset};
use std::f64::consts::PI;
pub use write::{
    ChromaFilter, ClipEncoding, ClipFormat, DEFAULT_CRF, DEFAULT_ENCODING, H264Settings,
    H264Writer, HdrTransfer, RateControl, SampleStorage, truth_path, write_clip,
};

/// Errors of the render stage; file errors name the file.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Invalid options or motion.
    #[error("invalid render input: {0}")]
    Invalid(String),
    /// A file or folder could not be written.
    #[error("cannot write {}: {reason}", path.display())]
    Write {
        /// The file or folder being written.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// A file that could not be written through its temporary file.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
}

impl RenderError {
    fn invalid(reason: impl Into<String>) -> Self {
        RenderError::Invalid(reason.into())
    }
}

/// Camera artefacts applied after rendering.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Effects {
    /// Read noise σ [grey levels], Gaussian, per channel.
    pub noise_sigma: f64,
    /// Gaussian blur σ \[px\].
    pub blur_sigma: f64,
    /// Mains flicker at 100 Hz (50 Hz mains, full-wave): relative amplitude A₁₀₀ of
    /// the light gain 1 + A₁₀₀ sin(2π·100 Hz·t + p₁₀₀) + A₅₀ sin(2π·50 Hz·t + p₅₀),
    /// t the capture time from the first frame.
    pub flicker_amplitude: f64,
    /// Relative amplitude A₅₀ of the 50 Hz flicker (a lamp that flickers at the mains
    /// frequency itself).
    #[serde(default)]
    pub flicker_50hz_amplitude: f64,
    /// Phase p₁₀₀ of the 100 Hz flicker \[rad\].
    #[serde(default)]
    pub flicker_phase_100: f64,
    /// Phase p₅₀ of the 50 Hz flicker \[rad\].
    #[serde(default)]
    pub flicker_phase_50: f64,
    /// Shot noise k [grey levels^½]: a pixel of level v has noise σ² = σ_read² + k² v
    /// (v after the light gain; k² is grey levels per photo-electron).
    #[serde(default)]
    pub shot_noise: f64,
    /// Exposure time \[s\]: each frame averages `exposure_samples` poses evenly spread
    /// over it, centred on the capture time (motion smear). 0: instantaneous.
    #[serde(default)]
    pub exposure_s: f64,
    /// Poses averaged over the exposure (1: none).
    #[serde(default = "one")]
    pub exposure_samples: usize,
    /// Lateral drift of the disk [px/s] before the halt (it arrives at rest there);
    /// px at the disk's centre.
    pub drift_px_per_s: f64,
    /// Camera shake ([`shake`]); `None`: a still camera.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shake: Option<Shake>,
    /// Seed of the noise generator, of the plate's texture and of the shake.
    pub seed: u64,
}

fn one() -> usize {
    1
}

impl Default for Effects {
    fn default() -> Self {
        Effects {
            noise_sigma: 0.0,
            blur_sigma: 0.0,
            flicker_amplitude: 0.0,
            flicker_50hz_amplitude: 0.0,
            flicker_phase_100: 0.0,
            flicker_phase_50: 0.0,
            shot_noise: 0.0,
            exposure_s: 0.0,
            exposure_samples: 1,
            drift_px_per_s: 0.0,
            shake: None,
            seed: 1,
        }
    }
}

impl Effects {
    /// The light gain at clip time `t` \[s\] (first captured frame at 0): mains flicker.
    pub fn light_gain(&self, t: f64) -> f64 {
        let tau = 2.0 * std::f64::consts::PI;
        1.0 + self.flicker_amplitude * (tau * 100.0 * t + self.flicker_phase_100).sin()
            + self.flicker_50hz_amplitude * (tau * 50.0 * t + self.flicker_phase_50).sin()
    }
}

/// The look of the scene beyond the plate type: grey levels, grain, reflection and
/// light (the defaults are [`Plate`]'s look).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Scenery {
    /// Paper (the disk's side and top face) albedo × 255, red channel [grey level].
    pub paper_grey: f64,
    /// Lit plate albedo × 255, red channel [grey level]; `None`: 24 (dark), 205 (light).
    pub plate_grey: Option<f64>,
    /// RMS relative variation of the plate's albedo, a seeded grain texture
    /// ([`scene::PlateTexture`]); 0: plain.
    pub texture_contrast: f64,
    /// Fraction of the plate's radiance that is mirror image; `None`: 0.25 (dark),
    /// 0 (light).
    pub reflectivity: Option<f64>,
    /// Gaussian σ of the mirror image's blur \[px\] (a rough or brushed plate).
    pub reflection_blur_px: f64,
    /// Elevation of the fill light that shades the paper \[deg\]: 20° lights the side
    /// more than the top face, above 45° the top face more.
    pub fill_elevation_deg: f64,
}

impl Scenery {
    /// The paper's grey level by default.
    pub const DEFAULT_PAPER_GREY: f64 = 238.0;
    /// The fill light's elevation by default \[deg\].
    pub const DEFAULT_FILL_ELEVATION_DEG: f64 = 20.0;
}

impl Default for Scenery {
    fn default() -> Self {
        Scenery {
            paper_grey: Self::DEFAULT_PAPER_GREY,
            plate_grey: None,
            texture_contrast: 0.0,
            reflectivity: None,
            reflection_blur_px: 0.0,
            fill_elevation_deg: Self::DEFAULT_FILL_ELEVATION_DEG,
        }
    }
}

/// Everything about the picture (not the motion).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RenderSpec {
    /// Frame width \[px\].
    pub width: u32,
    /// Frame height \[px\].
    pub height: u32,
    /// Plate type.
    pub plate: Plate,
    /// Side view above, plan view with the strip below (fig. 3.19).
    pub two_view: bool,
    /// Camera elevation ε of the side view \[deg\], in (0, 30].
    pub elevation_deg: f64,
    /// Image scale [m/px] (at the disk's centre for a pinhole); `None` fits the
    /// disk's diameter into 90 % of the width (and of the plan view's height).
    pub metres_per_px: Option<f64>,
    /// Pinhole side camera at this depth from the near rim \[m\] (along its optical
    /// axis, to the rim's mid-height at rest); `None`: orthographic (infinitely far).
    #[serde(default)]
    pub camera_distance_m: Option<f64>,
    /// Grey levels, texture, reflection and light.
    #[serde(default)]
    pub scenery: Scenery,
    /// Width of the red strip \[m\].
    pub strip_width: f64,
    /// Radius of the rounding of the disk's two rims \[m\] ([`DiskShape::edge_radius`]);
    /// 0: sharp.
    #[serde(default)]
    pub edge_radius: f64,
    /// Camera artefacts.
    pub effects: Effects,
    /// Capture indices (0-based) of frames missing from the output.
    pub dropped: Vec<usize>,
    /// The display matrix an MP4 is tagged with, as a phone tags its clips: the
    /// frames are stored turned the other way, so that the displayed frames are
    /// the rendered ones (issue 14 §1).
    #[serde(default)]
    pub display_orientation: Orientation,
    /// How an MP4 stores its samples: bit depth, range, HDR tags.
    #[serde(default)]
    pub storage: SampleStorage,
    /// Capture indices whose written frame repeats the previous written frame.
    #[serde(default)]
    pub duplicated: Vec<usize>,
    /// Capture indices whose written frame is the blend (rounded mean) of the
    /// previous and next written frames.
    #[serde(default)]
    pub interpolated: Vec<usize>,
    /// Spans of capture time an MP4 stores slowed for playback, as a phone's
    /// slow-motion section between real-time ramps (issue 14 §2).
    #[serde(default)]
    pub slowed_sections: Vec<SlowedSection>,
}

/// A span of capture time stored slowed: each frame interval that starts in
/// [`start_s`, `end_s`) of clip time advances the container's clock `factor` ×
/// as far as the capture clock.
///
/// [`start_s`]: SlowedSection::start_s
/// [`end_s`]: SlowedSection::end_s
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SlowedSection {
    /// Clip time where the slowing starts [s, capture clock, first frame at 0].
    pub start_s: f64,
    /// Clip time where it ends \[s\].
    pub end_s: f64,
    /// Container seconds per capture second, > 1 (16: 480 fps played at 30).
    pub factor: f64,
}

impl RenderSpec {
    /// Thesis-like defaults: 1280 × 720 landscape for the side view (§3.2.3: 480 fps,
    /// 720 × 1280 px, the disk about 200 px tall), 720 × 1280 portrait for two views
    /// (§3.3.2, the disk about 100 px tall); 3° elevation; a 5 mm strip.
    pub fn thesis(plate: Plate, two_view: bool) -> Self {
        let (width, height) = if two_view { (720, 1280) } else { (1280, 720) };
        RenderSpec {
            width,
            height,
            plate,
            two_view,
            elevation_deg: 3.0,
            metres_per_px: None,
            camera_distance_m: None,
            scenery: Scenery::default(),
            strip_width: 0.005,
            edge_radius: 0.0,
            effects: Effects::default(),
            dropped: Vec::new(),
            display_orientation: Orientation::IDENTITY,
            storage: SampleStorage::default(),
            duplicated: Vec::new(),
            interpolated: Vec::new(),
            slowed_sections: Vec::new(),
        }
    }
}

/// Calibration points of the rest frame (thesis fig. 3.3, ERRATA): image coordinates
/// in px, pixel centres at integers, rows growing downward.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Left edge of the bottom of the disk \[px\].
    pub x_l: f64,
    /// Right edge of the bottom of the disk \[px\].
    pub x_r: f64,
    /// Centre column (x_l + x_r)/2 \[px\].
    pub x_centre: f64,
    /// Near top rim on the centre column \[row\].
    pub z_t: f64,
    /// Plate line: the bottom rim on the centre column \[row\].
    pub z_base: f64,
}

/// Ground truth of one written frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrameTruth {
    /// Capture index (0-based; dropped frames keep their numbers).
    pub index: usize,
    /// Position in the written clip (0-based; `frame_{file_index + 1:06}.png`).
    pub file_index: usize,
    /// Time relative to the halt \[s\] (t = 0 at the halt).
    pub t: f64,
    /// Nutation φ \[rad\].
    pub phi: f64,
    /// Precession ψ \[rad\] (z_rim peaks at ψ ≡ −π/2 mod 2π).
    pub psi: f64,
    /// Spin θ \[rad\].
    pub theta: f64,
    /// Strip angle β seen from above (eq. 3.20), unwrapped, counter-clockwise from
    /// the image's +x axis with image up = +y \[rad\].
    pub beta: f64,
    /// ψ̇ [rad/s].
    pub psi_dot: f64,
    /// θ̇ [rad/s].
    pub theta_dot: f64,
    /// β̇ [rad/s].
    pub beta_dot: f64,
    /// Energy above the flat rest state \[J\].
    pub energy: f64,
    /// Bottom edge of the white disk on the centre column above the plate line,
    /// z_base − row \[px\]; `None` if the disk is not on the column.
    pub z_rim_px: Option<f64>,
    /// z_rim_px · δ \[m\].
    pub z_rim_m: Option<f64>,
    /// Horizontal offset of the disk's centre from its rest column (drift) \[px\].
    pub drift_px: f64,
    /// Light gain of the frame (mains flicker, [`Effects::light_gain`]).
    #[serde(default = "unit_gain")]
    pub light_gain: f64,
    /// The MP4 timestamp of this frame [s, playback clock, first frame at 0] when
    /// the clip is stamped frame by frame ([`GroundTruth::stamped`]); otherwise
    /// absent, and an MP4 stamps written frame k at k / fps.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub container_time_s: Option<f64>,
    /// The camera's shake at the capture time (mid-exposure) when the clip is
    /// shaken ([`Effects::shake`]): dx_px > 0 moves the picture right, dy_px > 0 down,
    /// roll_deg > 0 turns it counter-clockwise as displayed about
    /// [`GroundTruth::camera_shake_centre_px`] ([`shake`]). A duplicated frame's
    /// entry is its capture's, which its picture does not show. φ, ψ, z_rim and the
    /// rest are the still camera's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera_shake: Option<ShakeOffset>,
}

fn unit_gain() -> f64 {
    1.0
}

/// How the side camera projects.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Projection {
    /// Parallel rays (a camera infinitely far away).
    Orthographic,
    /// A pinhole at a finite distance.
    Perspective,
}

/// The side camera and the scales it gives, at rest (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CameraTruth {
    /// Orthographic or perspective.
    pub projection: Projection,
    /// Depth of the near rim's mid-height point (0, −R, H) at rest along the
    /// optical axis \[m\] (perspective).
    pub distance_to_near_rim_m: Option<f64>,
    /// Centre of projection \[m\], world frame (origin on the plate under the disk's
    /// centre at rest, y away from the camera, z up) (perspective).
    pub position_m: Option<[f64; 3]>,
    /// Focal length \[px\] (perspective).
    pub focal_px: Option<f64>,
    /// Perspective factor: depth of the disk's centre (0, 0, H) over depth of the
    /// near rim (0, −R, H) at rest, (d + R cos ε)/d; 1 for orthographic.
    pub perspective_factor: f64,
    /// Vertical scale at the near bottom rim (0, −R, 0) at rest, 1/|∂row/∂z| [m/px],
    /// the scale at the point where z_rim is read (s/cos ε for orthographic).
    pub near_rim_metres_per_px: f64,
    /// Horizontal scale at the depth of the disk's centre [m/px] (the orthographic s).
    pub centre_metres_per_px: f64,
    /// Left end of the top rim's silhouette at rest \[px\] (x_l is the bottom's;
    /// through a pinhole the top, nearer the camera, is wider).
    pub x_l_top: f64,
    /// Right end of the top rim's silhouette at rest \[px\].
    pub x_r_top: f64,
    /// Top of the silhouette on the centre column at rest: the far top rim \[row\]
    /// (z_t is the near top rim, below it by the top face's image height).
    pub z_t_far: f64,
}

/// The ground truth of a rendered clip.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GroundTruth {
    /// Version of this schema.
    pub format_version: u32,
    /// Power law or simulation.
    pub source: MotionSource,
    /// Plate type.
    pub plate: Plate,
    /// Two views (side above, plan below).
    pub two_view: bool,
    /// First row of the plan view (two views only); the side view is above it.
    pub split_row: Option<u32>,
    /// Frame width \[px\].
    pub width: u32,
    /// Frame height \[px\].
    pub height: u32,
    /// Capture rate [frames/s].
    pub fps: f64,
    /// Captured frames, including dropped ones.
    pub captured_frames: usize,
    /// Clip time of the halt \[s\] (first captured frame at 0).
    pub halt_time: f64,
    /// Stop of the strip after the halt, t_β \[s\] (eq. 4.113).
    pub t_beta: f64,
    /// β̇ just after the halt [rad/s].
    pub post_flat_beta_dot: f64,
    /// True energy exponent n (prescribed, or the model's analytic one).
    pub true_n: Option<f64>,
    /// Prescribed A_e [J s^-n].
    pub a_e: Option<f64>,
    /// Disk parameters.
    pub disk: DiskParams,
    /// Strip angle on the top face β0 \[rad\] (eq. 3.13).
    pub beta0: f64,
    /// Side camera elevation ε \[rad\].
    pub elevation: f64,
    /// Image scale s [m/px]: orthographic, or a pinhole's at the disk's centre.
    pub metres_per_px_image: f64,
    /// δ = 2H/(z_base − z_t) [m/px] (eq. 3.10 corrected) from the true calibration
    /// points; s / cos ε for orthographic.
    pub delta: f64,
    /// The side camera: projection, pose, perspective factor and scales.
    pub camera: CameraTruth,
    /// Grey levels, texture, reflection and light.
    pub scenery: Scenery,
    /// φ's oscillation about stationary rolling, if any (φ in `frames` includes it).
    pub nutation: Option<Nutation>,
    /// Rest-frame calibration points.
    pub calibration: Calibration,
    /// Camera artefacts.
    pub effects: Effects,
    /// Capture indices missing from the output.
    pub dropped: Vec<usize>,
    /// The display matrix of the MP4: its stored frames are the rendered ones
    /// turned the other way (`width` × `height` is the displayed size).
    #[serde(default)]
    pub display_orientation: Orientation,
    /// How the MP4 stores its samples (bit depth, range, HDR tags).
    #[serde(default)]
    pub storage: SampleStorage,
    /// Capture indices whose frame repeats the previous written frame's bytes
    /// (their `frames` entries keep the true pose, which the image does not show).
    #[serde(default)]
    pub duplicated: Vec<usize>,
    /// Capture indices whose frame is the rounded mean of the previous and next
    /// written frames.
    #[serde(default)]
    pub interpolated: Vec<usize>,
    /// Capture times jittered about k/fps (a variable frame rate); `frames` hold
    /// the jittered times.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vfr_jitter: Option<CaptureJitter>,
    /// Spans stored slowed for playback.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub slowed_sections: Vec<SlowedSection>,
    /// Whether an MP4 is stamped frame by frame, each frame's timestamp in
    /// [`FrameTruth::container_time_s`] on a clock of [`TICKS_PER_FRAME`] ticks a
    /// frame (with a jitter or a slowed section; dropped frames then leave a gap).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub stamped: bool,
    /// With camera shake: the point c its roll turns the picture about \[px\], the
    /// side view's principal point (the image of the world origin) of the still
    /// camera; a shaken frame shows the still picture's point p0 at
    /// c + (dx, dy) + R(roll) (p0 − c) ([`FrameTruth::camera_shake`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera_shake_centre_px: Option<[f64; 2]>,
    /// One entry per written frame, in output order.
    pub frames: Vec<FrameTruth>,
}

/// Every capture's container timestamp in ticks of 1 / (fps · [`TICKS_PER_FRAME`])
/// s from the first: the capture clock (whole ticks, jittered or not), each
/// interval starting inside a slowed section stretched by its factor.
fn container_ticks(motion: &Motion, slowed: &[SlowedSection]) -> Vec<i64> {
    let timing = &motion.timing;
    let per_s = timing.fps * f64::from(TICKS_PER_FRAME);
    // Capture times in whole ticks (k / fps less the halt plus the halt is not
    // always k / fps in floating point).
    let capture: Vec<i64> = motion
        .states
        .iter()
        .map(|s| ((s.t + timing.halt_time) * per_s).round() as i64)
        .collect();
    let mut ticks = Vec::with_capacity(capture.len());
    let mut at = 0i64;
    ticks.push(at);
    for w in capture.windows(2) {
        let start = w[0] as f64 / per_s;
        let factor = slowed
            .iter()
            .find(|s| (s.start_s..s.end_s).contains(&start))
            .map_or(1.0, |s| s.factor);
        at += ((w[1] - w[0]) as f64 * factor).round() as i64;
        ticks.push(at);
    }
    ticks
}

/// Capture indices sorted, each once.
fn sorted(indices: &[usize]) -> Vec<usize> {
    let mut v = indices.to_vec();
    v.sort_unstable();
    v.dedup();
    v
}

/// z_rim at a peak (ψ ≡ −π/2, contact point straight behind) as the thesis converts
/// it, 2R sin φ + (R(1 − cos φ) − H sin φ) tan ε \[m\] (see the module docs).
pub fn peak_z_rim(params: &DiskParams, phi: f64, elevation: f64) -> f64 {
    let (r, h) = (params.radius, params.half_thickness);
    2.0 * r * phi.sin() + (r * (1.0 - phi.cos()) - h * phi.sin()) * elevation.tan()
}

/// Largest frame rendered \[px\] (3840 × 2160, 4K UHD): a frame and its background
/// are held in memory as floats, 16 frames at a time.
pub const MAX_FRAME_PIXELS: u64 = 3840 * 2160;

/// Renders the frames of one clip on demand and holds its ground truth.
pub struct Renderer {
    spec: RenderSpec,
    motion: Motion,
    scene: Scene,
    cameras: Vec<Camera>,
    /// The static background: colour, then (when the look keeps it apart) the
    /// plate's mirror image and coverage.
    background: Vec<Channels>,
    /// The background's mirror image and plate coverage blurred by the reflection
    /// blur (empty without).
    background_mirror: Vec<[f32; 4]>,
    truth: GroundTruth,
    /// Capture index of each written frame.
    written: Vec<usize>,
    /// The camera's shake drawn from the seed, if the spec asks for one.
    shake: Option<ShakeMotion>,
}

/// Supersampling patterns: rank-1 lattices (i/n, g·i/n mod 1), centred, so that
/// axis-aligned edges get n coverage levels: 16 rays (g = 5) where a direct view of
/// the disk is involved, 8 rays (g = 3) where only the plate's shadow and mirror
/// image differ.
const SUPERSAMPLES: usize = 16;
const SUPERSAMPLES_PLATE: usize = 8;

fn supersample_offset(i: usize, n: usize) -> (f64, f64) {
    let g = if n == SUPERSAMPLES { 5 } else { 3 };
    let nf = n as f64;
    (
        (i as f64 + 0.5) / nf - 0.5,
        ((g * i) % n) as f64 / nf + 0.5 / nf - 0.5,
    )
}

impl Renderer {
    /// Prepares a clip: validates the options, lays out the views, renders the static
    /// background and computes the ground truth.
    pub fn new(spec: &RenderSpec, motion: &Motion) -> Result<Self, RenderError> {
        validate(spec, motion)?;
        let params = motion.params;
        let (r, h) = (params.radius, params.half_thickness);
        let split = spec
            .two_view
            .then(|| (0.35 * f64::from(spec.height)).round() as u32);
        let scale = image_scale(spec, r, split);
        let cameras = cameras(spec, &params, scale, split);
        let side = cameras[0];
        let scene = Scene {
            disk: DiskShape {
                radius: r,
                half_thickness: h,
                beta0: motion.beta0,
                strip_half_width: 0.5 * spec.strip_width,
                edge_radius: spec.edge_radius,
            },
            look: Look::with_scenery(spec.plate, &spec.scenery, spec.effects.seed),
            plate_back: 0.15,
            plate_front: 1.0,
        };
        let (calibration, camera) = match spec.camera_distance_m {
            None => orthographic_calibration(&side, &params),
            Some(d) => pinhole_calibration(&scene, &side, &params, d)?,
        };
        let delta = 2.0 * h / (calibration.z_base - calibration.z_t);
        let written: Vec<usize> = (0..motion.states.len())
            .filter(|k| !spec.dropped.contains(k))
            .collect();
        let mut truth = ground_truth(spec, motion, split, scale, delta, camera, calibration);
        truth.camera_shake_centre_px = spec.effects.shake.map(|_| [side.cx, side.cy]);
        let mut renderer = Renderer {
            spec: spec.clone(),
            motion: motion.clone(),
            scene,
            cameras,
            background: Vec::new(),
            background_mirror: Vec::new(),
            truth,
            written,
            shake: spec
                .effects
                .shake
                .map(|s| ShakeMotion::new(&s, spec.effects.seed)),
        };
        renderer.background = renderer.render_background(&renderer.cameras, None);
        if renderer.scene.look.separate_mirror {
            renderer.background_mirror = renderer.blurred_background_mirror();
        }
        renderer.add_frame_truth();
        Ok(renderer)
    }

    /// Each written frame's ground truth, with its container time where the frames
    /// are stamped (capture jitter or slowed sections).
    fn add_frame_truth(&mut self) {
        let frames = self
            .written
            .par_iter()
            .enumerate()
            .map(|(file_index, &index)| self.frame_truth(file_index, index))
            .collect();
        self.truth.frames = frames;
        if self.truth.stamped {
            let stamps = container_ticks(&self.motion, &self.spec.slowed_sections);
            let tick_s = 1.0 / (self.motion.timing.fps * f64::from(TICKS_PER_FRAME));
            for frame in &mut self.truth.frames {
                frame.container_time_s = Some(stamps[frame.index] as f64 * tick_s);
            }
        }
    }

    /// The ground truth of the clip.
    pub fn truth(&self) -> &GroundTruth {
        &self.truth
    }

    /// Number of written (not dropped) frames.
    pub fn frame_count(&self) -> usize {
        self.written.len()
    }

    /// The disk's pose at capture index `index`, with drift.
    fn pose(&self, index: usize) -> Pose {
        let s = &self.motion.states[index];
        self.pose_of(s.psi, s.phi, s.theta, s.centre, s.t)
    }

    fn pose_of(&self, psi: f64, phi: f64, theta: f64, centre: [f64; 2], t: f64) -> Pose {
        let drift = self.drift_px(t) * self.truth.metres_per_px_image;
        Pose::rolling(
            &self.motion.params,
            psi,
            phi,
            theta,
            centre[0] + drift,
            centre[1],
        )
    }

    /// The poses a frame's exposure averages: `exposure_samples` evenly spread over
    /// `exposure_s` about the capture time (one, at the capture time, without smear).
    /// Between frames ψ and θ follow cubic Hermite polynomials with their rates, φ and
    /// the centre straight lines.
    fn exposure_poses(&self, index: usize) -> Vec<Pose> {
        let offsets = self.exposure_offsets();
        if let [_] = offsets.as_slice() {
            return vec![self.pose(index)];
        }
        let states = &self.motion.states;
        offsets
            .into_iter()
            .map(|dt| {
                let s = &states[index];
                let t = s.t + dt;
                let pair = if dt >= 0.0 {
                    states.get(index + 1).map(|b| (s, b))
                } else {
                    index.checked_sub(1).map(|k| (&states[k], s))
                };
                let Some((a, b)) = pair else {
                    return self.pose_of(s.psi, s.phi, s.theta, s.centre, t);
                };
                let u = (t - a.t) / (b.t - a.t);
                let lerp = |x: f64, y: f64| x + u * (y - x);
                let psi = motion::hermite(a.t, a.psi, a.psi_dot, b.t, b.psi, b.psi_dot, t);
                let theta =
                    motion::hermite(a.t, a.theta, a.theta_dot, b.t, b.theta, b.theta_dot, t);
                let centre = [
                    lerp(a.centre[0], b.centre[0]),
                    lerp(a.centre[1], b.centre[1]),
                ];
                self.pose_of(psi, lerp(a.phi, b.phi).max(0.0), theta, centre, t)
            })
            .collect()
    }

    /// The times of the poses a frame's exposure averages, from the capture time
    /// \[s\]: `exposure_samples` evenly spread over `exposure_s` (one, 0, without
    /// smear).
    fn exposure_offsets(&self) -> Vec<f64> {
        let fx = &self.spec.effects;
        let m = fx.exposure_samples.max(1);
        if m == 1 || fx.exposure_s <= 0.0 {
            return vec![0.0];
        }
        (0..m)
            .map(|j| fx.exposure_s * ((j as f64 + 0.5) / m as f64 - 0.5))
            .collect()
    }

    /// The shake, if it moves the picture.
    fn moving_shake(&self) -> Option<&ShakeMotion> {
        self.shake
            .as_ref()
            .filter(|_| self.spec.effects.shake.is_some_and(|s| !s.is_still()))
    }

    /// The cameras shaken by `offset`: each view's principal point shifted by
    /// (dx, dy), and the roll that turns the rays' image coordinates about the side
    /// view's shifted principal point ([`shake`]).
    fn shaken_cameras(&self, offset: &ShakeOffset) -> (Vec<Camera>, Option<Roll>) {
        let cameras = self
            .cameras
            .iter()
            .map(|c| Camera {
                cx: c.cx + offset.dx_px,
                cy: c.cy + offset.dy_px,
                ..*c
            })
            .collect();
        let side = &self.cameras[0];
        let centre = (side.cx + offset.dx_px, side.cy + offset.dy_px);
        (cameras, Roll::new(centre, offset.roll_deg))
    }

    fn drift_px(&self, t: f64) -> f64 {
        self.spec.effects.drift_px_per_s * t.min(0.0)
    }

    fn frame_truth(&self, file_index: usize, index: usize) -> FrameTruth {
        let s = &self.motion.states[index];
        let pose = self.pose(index);
        let z_rim_px = self
            .rim_edge_row(&pose)
            .map(|row| self.truth.calibration.z_base - row);
        FrameTruth {
            index,
            file_index,
            t: s.t,
            phi: s.phi,
            psi: s.psi,
            theta: s.theta,
            beta: s.beta,
            psi_dot: s.psi_dot,
            theta_dot: s.theta_dot,
            beta_dot: s.beta_dot,
            energy: s.energy,
            z_rim_px,
            z_rim_m: z_rim_px.map(|z| z * self.truth.delta),
            drift_px: self.drift_px(s.t) + s.centre[0] / self.truth.metres_per_px_image,
            light_gain: self
                .spec
                .effects
                .light_gain(index as f64 / self.motion.timing.fps),
            container_time_s: None,
            camera_shake: self
                .shake
                .as_ref()
                .map(|m| m.at(s.t + self.motion.timing.halt_time)),
        }
    }

    /// Row of the lowest point on the centre column whose ray first meets a white
    /// surface of the disk (ray casting; see the module docs).
    fn rim_edge_row(&self, pose: &Pose) -> Option<f64> {
        rim_edge_row(
            &self.scene.disk,
            &self.cameras[0],
            self.truth.calibration.x_centre,
            pose,
        )
    }

    /// The frame without the disk through `cameras` (rolled by `roll`).
    fn render_background(&self, cameras: &[Camera], roll: Option<&Roll>) -> Vec<Channels> {
        let (w, h) = (self.spec.width as usize, self.spec.height as usize);
        let mut buf = vec![[0.0f32; 7]; w * h];
        for cam in cameras {
            let rect = Rect {
                x0: 0,
                x1: w,
                y0: cam.row_start as usize,
                y1: cam.row_end as usize,
            };
            self.render_rect(&mut buf, cam, None, rect, roll);
        }
        buf
    }

    /// The background's mirror image and plate coverage, blurred view by view.
    fn blurred_background_mirror(&self) -> Vec<[f32; 4]> {
        self.blurred_mirror_channels(&self.background)
    }

    /// A frame's mirror image and plate coverage, blurred view by view.
    fn blurred_mirror_channels(&self, buf: &[Channels]) -> Vec<[f32; 4]> {
        let w = self.spec.width as usize;
        let sigma = self.spec.scenery.reflection_blur_px;
        let mut mirror: Vec<[f32; 4]> = buf.iter().map(|p| [p[3], p[4], p[5], p[6]]).collect();
        for cam in &self.cameras {
            let (y0, y1) = (cam.row_start as usize, cam.row_end as usize);
            gaussian_blur(&mut mirror[y0 * w..y1 * w], w, y1 - y0, sigma);
        }
        mirror
    }

    /// Renders written frame `file_index` (0-based position in the output): the
    /// capture, or for a duplicated frame the previous written frame, for an
    /// interpolated one the rounded mean of its written neighbours.
    ///
    /// # Panics
    /// If `file_index >= self.frame_count()`.
    pub fn render_frame(&self, file_index: usize) -> RgbImage {
        let index = self.written[file_index];
        if self.truth.duplicated.contains(&index) {
            // `validate` keeps the first written frame a capture.
            return self.render_frame(file_index - 1);
        }
        if self.truth.interpolated.contains(&index) {
            // `validate` makes both neighbours captures.
            let (before, after) = (
                self.render_capture(file_index - 1),
                self.render_capture(file_index + 1),
            );
            let mut blend = before;
            for (b, a) in blend.iter_mut().zip(after.iter()) {
                *b = (u16::from(*b) + u16::from(*a)).div_ceil(2) as u8;
            }
            return blend;
        }
        self.render_capture(file_index)
    }

    /// Renders the capture shown by written frame `file_index`.
    fn render_capture(&self, file_index: usize) -> RgbImage {
        let index = self.written[file_index];
        let poses = self.exposure_poses(index);
        // With shake, each pose's cameras, shaken at its time.
        let shaken: Option<Vec<(Vec<Camera>, Option<Roll>)>> = self.moving_shake().map(|m| {
            let t = self.motion.states[index].t + self.motion.timing.halt_time;
            self.exposure_offsets()
                .iter()
                .map(|dt| self.shaken_cameras(&m.at(t + dt)))
                .collect()
        });
        let (w, h) = (self.spec.width as usize, self.spec.height as usize);
        // The pixels each view's disk, mirror image and shadow may touch.
        let mut touched: Vec<Option<Rect>> = vec![None; self.cameras.len()];
        // Pose j on its background: the still one, or the shaken cameras' own.
        let mut render_pose = |j: usize| -> Vec<Channels> {
            let pose = &poses[j];
            let (cameras, roll, mut buf) = match &shaken {
                None => (self.cameras.as_slice(), None, self.background.clone()),
                Some(views) => {
                    let (cameras, roll) = &views[j];
                    let buf = self.render_background(cameras, roll.as_ref());
                    (cameras.as_slice(), roll.as_ref(), buf)
                }
            };
            for (c, cam) in cameras.iter().enumerate() {
                if let Some(rect) = self.disk_rect(cam, pose, roll) {
                    self.render_rect(&mut buf, cam, Some(pose), rect, roll);
                    touched[c] = Some(touched[c].map_or(rect, |t| t.union(&rect)));
                }
            }
            buf
        };
        let buf = if poses.len() == 1 {
            render_pose(0)
        } else {
            // Motion smear: the mean of the exposure's poses.
            let k = 1.0 / poses.len() as f32;
            let mut sum = vec![[0.0f32; 7]; w * h];
            for j in 0..poses.len() {
                let one = render_pose(j);
                sum.par_iter_mut().zip(&one).for_each(|(s, o)| {
                    for (a, b) in s.iter_mut().zip(o) {
                        *a += k * b;
                    }
                });
            }
            sum
        };
        let mut rgb: Vec<[f32; 3]> = if self.scene.look.separate_mirror {
            let mirror = if shaken.is_some() {
                // The background moved too: the whole mirror image is blurred.
                seen_mirror(&buf, &self.blurred_mirror_channels(&buf))
            } else {
                self.blurred_mirror(&buf, &touched)
            };
            buf.iter()
                .zip(&mirror)
                .map(|(p, m)| [p[0] + m[0], p[1] + m[1], p[2] + m[2]])
                .collect()
        } else {
            buf.iter()
                .map(|p| [p[0] + p[3], p[1] + p[4], p[2] + p[5]])
                .collect()
        };
        let fx = &self.spec.effects;
        if fx.blur_sigma > 0.0 {
            gaussian_blur(&mut rgb, w, h, fx.blur_sigma);
        }
        let gain = fx.light_gain(index as f64 / self.motion.timing.fps);
        let read_var = fx.noise_sigma * fx.noise_sigma;
        let mut out = vec![0u8; w * h * 3];
        out.par_chunks_mut(3 * w)
            .zip(rgb.par_chunks(w))
            .enumerate()
            .for_each(|(row, (dst, src))| {
                let mut rng = SplitMix64::new(
                    fx.seed
                        ^ (index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
                        ^ (row as u64).wrapping_mul(0xD1B5_4A32_D192_ED03),
                );
                for (px, rgb) in dst.chunks_mut(3).zip(src) {
                    for (d, &c) in px.iter_mut().zip(rgb) {
                        let mut v = f64::from(c) * gain;
                        let sigma = if fx.shot_noise > 0.0 {
                            (read_var + fx.shot_noise * fx.shot_noise * v.max(0.0)).sqrt()
                        } else {
                            fx.noise_sigma
                        };
                        if sigma > 0.0 {
                            v += sigma * rng.gaussian();
                        }
                        *d = v.round().clamp(0.0, 255.0) as u8;
                    }
                }
            });
        // The buffer has exactly width × height × 3 bytes.
        RgbImage::from_raw(self.spec.width, self.spec.height, out)
            .unwrap_or_else(|| RgbImage::new(self.spec.width, self.spec.height))
    }

    /// The frame's mirror image blurred by the reflection blur, seen where the plate
    /// is: coverage × blur(mirror)/blur(coverage) (a normalised convolution, so the
    /// mirror image neither spills onto the disk nor fades where the disk hides the
    /// plate). Blurring is linear: blur(frame) is the blurred background's plus the
    /// blurred change the disk made, which is zero outside the touched rectangles and
    /// is blurred within them widened by 3σ and within the view.
    fn blurred_mirror(&self, buf: &[Channels], touched: &[Option<Rect>]) -> Vec<[f32; 3]> {
        let (w, h) = (self.spec.width as usize, self.spec.height as usize);
        let sigma = self.spec.scenery.reflection_blur_px;
        let radius = (3.0 * sigma).ceil() as usize;
        let mut blurred = self.background_mirror.clone();
        for (cam, rect) in self.cameras.iter().zip(touched) {
            let Some(rect) = rect else { continue };
            let e = Rect {
                x0: rect.x0.saturating_sub(radius),
                x1: (rect.x1 + radius).min(w),
                y0: rect.y0.saturating_sub(radius).max(cam.row_start as usize),
                y1: (rect.y1 + radius).min(cam.row_end as usize).min(h),
            };
            let ew = e.x1 - e.x0;
            let mut diff = vec![[0.0f32; 4]; ew * (e.y1 - e.y0)];
            for (j, row) in diff.chunks_mut(ew).enumerate() {
                for (i, d) in row.iter_mut().enumerate() {
                    let p = (e.y0 + j) * w + e.x0 + i;
                    for (k, dk) in d.iter_mut().enumerate() {
                        *dk = buf[p][3 + k] - self.background[p][3 + k];
                    }
                }
            }
            gaussian_blur(&mut diff, ew, e.y1 - e.y0, sigma);
            for (j, row) in diff.chunks(ew).enumerate() {
                let start = (e.y0 + j) * w + e.x0;
                for (m, d) in blurred[start..start + ew].iter_mut().zip(row) {
                    for (a, b) in m.iter_mut().zip(d) {
                        *a += b;
                    }
                }
            }
        }
        seen_mirror(buf, &blurred)
    }

    /// Pixel rectangle of a view that the disk, its mirror image and its shadow can
    /// touch, with a 2 px margin (exact extents of the cylinder along the image axes
    /// for an orthographic view; for a pinhole, the images of the corners of the
    /// disk's bounding box, of its mirror image and of its shadow, which enclose
    /// them). With a textured plate it starts on the background's 2 × 2 block grid,
    /// so the plate's texture is interpolated alike inside and outside it.
    fn disk_rect(&self, cam: &Camera, pose: &Pose, roll: Option<&Roll>) -> Option<Rect> {
        let disk = &self.scene.disk;
        let key = self.scene.look.key_light;
        let reflects = self.scene.look.reflectivity > 0.0 && cam.view == View::Side;
        let (xa, xb, ua, ub) = if cam.pinhole.is_some() {
            let mut points = Vec::with_capacity(24);
            for c in disk.box_corners(pose) {
                points.push(c);
                if reflects {
                    points.push([c[0], c[1], -c[2]]);
                }
                let t = c[2] / key[2];
                points.push([c[0] - t * key[0], c[1] - t * key[1], 0.0]);
            }
            let (mut xa, mut xb, mut ra, mut rb) = (
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            );
            for p in points {
                let (x, row) = cam.project(p);
                (xa, xb, ra, rb) = (xa.min(x), xb.max(x), ra.min(row), rb.max(row));
            }
            (xa, xb, ra, rb)
        } else {
            let (ax, up) = cam.axes();
            // The mirror image (z → −z) seen along `up` is the disk seen along `up`
            // with its z component negated; the shadow is p ↦ p − (p_z / L_z) L on
            // the plate.
            let mirror_up = [up[0], up[1], -up[2]];
            let shadow = |u: [f64; 3]| [u[0], u[1], -(u[0] * key[0] + u[1] * key[1]) / key[2]];
            let xs = [disk.extent(pose, ax), disk.extent(pose, shadow(ax))];
            let mut ups = vec![disk.extent(pose, up), disk.extent(pose, shadow(up))];
            if reflects {
                ups.push(disk.extent(pose, mirror_up));
            }
            let x0 = xs.iter().map(|e| e.0).fold(f64::INFINITY, f64::min);
            let x1 = xs.iter().map(|e| e.1).fold(f64::NEG_INFINITY, f64::max);
            let u0 = ups.iter().map(|e| e.0).fold(f64::INFINITY, f64::min);
            let u1 = ups.iter().map(|e| e.1).fold(f64::NEG_INFINITY, f64::max);
            let s = cam.scale;
            (
                cam.cx + x0 / s,
                cam.cx + x1 / s,
                cam.cy - u1 / s,
                cam.cy - u0 / s,
            )
        };
        // A rolled picture: the box around the turned box.
        let (xa, xb, ua, ub) = match roll {
            None => (xa, xb, ua, ub),
            Some(roll) => [(xa, ua), (xb, ua), (xa, ub), (xb, ub)]
                .map(|(x, row)| roll.apply(x, row))
                .iter()
                .fold(
                    (
                        f64::INFINITY,
                        f64::NEG_INFINITY,
                        f64::INFINITY,
                        f64::NEG_INFINITY,
                    ),
                    |(xa, xb, ua, ub), &(x, row)| (xa.min(x), xb.max(x), ua.min(row), ub.max(row)),
                ),
        };
        let w = f64::from(self.spec.width);
        let (r0, r1) = (f64::from(cam.row_start), f64::from(cam.row_end));
        let mut rect = Rect {
            x0: (xa - 2.0).floor().clamp(0.0, w) as usize,
            x1: (xb + 3.0).ceil().clamp(0.0, w) as usize,
            y0: (ua - 2.0).floor().clamp(r0, r1) as usize,
            y1: (ub + 3.0).ceil().clamp(r0, r1) as usize,
        };
        if self.scene.look.texture.is_some() {
            rect.x0 -= rect.x0 % 2;
            rect.y0 -= (rect.y0 - cam.row_start as usize) % 2;
        }
        (rect.x0 < rect.x1 && rect.y0 < rect.y1).then_some(rect)
    }

    /// Renders the pixels of `rect` into `buf`. Rays are cast at the corners of 2 × 2
    /// pixel blocks; a block whose four corner rays see the same class is filled by
    /// bilinear interpolation, otherwise its pixel corners are cast, and a pixel whose
    /// corners disagree gets 16 rays.
    fn render_rect(
        &self,
        buf: &mut [Channels],
        cam: &Camera,
        pose: Option<&Pose>,
        rect: Rect,
        roll: Option<&Roll>,
    ) {
        let w = self.spec.width as usize;
        let prepared = Prepared::new(&self.scene, pose, cam);
        let trace = |x: f64, y: f64| -> Sample {
            let (x, y) = roll.map_or((x, y), |r| r.undo(x, y));
            let (o, d) = cam.ray(x, y);
            self.scene.trace(&prepared, cam, o, d)
        };
        let (pw, ph) = (rect.x1 - rect.x0, rect.y1 - rect.y0);
        let (bw, bh) = (pw.div_ceil(2), ph.div_ceil(2));
        let corner =
            |i: usize, j: usize| trace((rect.x0 + i) as f64 - 0.5, (rect.y0 + j) as f64 - 0.5);
        let coarse: Vec<Vec<Sample>> = (0..=bh)
            .into_par_iter()
            .map(|j| (0..=bw).map(|i| corner(2 * i, 2 * j)).collect())
            .collect();
        buf[rect.y0 * w..rect.y1 * w]
            .par_chunks_mut(2 * w)
            .enumerate()
            .for_each(|(bj, rows)| {
                let (above, below) = (&coarse[bj], &coarse[bj + 1]);
                let rows_here = rows.len() / w;
                for bi in 0..bw {
                    let quad = [above[bi], above[bi + 1], below[bi], below[bi + 1]];
                    let cols_here = (pw - 2 * bi).min(2);
                    if quad.iter().all(|s| s.class == quad[0].class) {
                        let q = quad.map(|s| s.channels());
                        for dy in 0..rows_here {
                            for dx in 0..cols_here {
                                // Pixel centres at 1/4 and 3/4 of the block.
                                let (fx, fy) = (0.25 + 0.5 * dx as f32, 0.25 + 0.5 * dy as f32);
                                let mut c = [0.0f32; 7];
                                for (k, ck) in c.iter_mut().enumerate() {
                                    let top = q[0][k] * (1.0 - fx) + q[1][k] * fx;
                                    let bot = q[2][k] * (1.0 - fx) + q[3][k] * fx;
                                    *ck = top * (1.0 - fy) + bot * fy;
                                }
                                rows[dy * w + rect.x0 + 2 * bi + dx] = c;
                            }
                        }
                        continue;
                    }
                    // Fine corners of the block: a 3 × 3 grid.
                    let mut fine = [[quad[0]; 3]; 3];
                    for (fj, fine_row) in fine.iter_mut().enumerate() {
                        for (fi, f) in fine_row.iter_mut().enumerate() {
                            *f = match (fi, fj) {
                                (0, 0) => quad[0],
                                (2, 0) => quad[1],
                                (0, 2) => quad[2],
                                (2, 2) => quad[3],
                                _ => corner(2 * bi + fi, 2 * bj + fj),
                            };
                        }
                    }
                    for dy in 0..rows_here {
                        for dx in 0..cols_here {
                            let q = [
                                fine[dy][dx],
                                fine[dy][dx + 1],
                                fine[dy + 1][dx],
                                fine[dy + 1][dx + 1],
                            ];
                            let (x, y) = (
                                (rect.x0 + 2 * bi + dx) as f64,
                                (rect.y0 + 2 * bj + dy) as f64,
                            );
                            rows[dy * w + rect.x0 + 2 * bi + dx] =
                                if q.iter().all(|s| s.class == q[0].class) {
                                    average(q.iter().map(|s| s.channels()), 4)
                                } else {
                                    let n = if q.iter().all(|s| s.class >= PLATE_CLASSES) {
                                        SUPERSAMPLES_PLATE
                                    } else {
                                        SUPERSAMPLES
                                    };
                                    average(
                                        (0..n).map(|k| {
                                            let (ox, oy) = supersample_offset(k, n);
                                            trace(x + ox, y + oy).channels()
                                        }),
                                        n,
                                    )
                                };
                        }
                    }
                }
            });
    }
}

/// The image scale \[m/px\]: the spec's, or the disk's diameter over 90 % of the
/// width, and of the side view's height in a two-view clip split at row `split`.
fn image_scale(spec: &RenderSpec, r: f64, split: Option<u32>) -> f64 {
    let (w, hgt) = (spec.width, spec.height);
    match spec.metres_per_px {
        Some(s) => s,
        None => {
            let by_width = 2.0 * r / (0.9 * f64::from(w));
            match split {
                Some(sp) => by_width.max(2.0 * r / (0.9 * f64::from(hgt - sp))),
                None => by_width,
            }
        }
    }
}

/// The side camera (first), orthographic or a pinhole, and in a two-view clip the
/// plan camera below row `split`.
fn cameras(spec: &RenderSpec, params: &DiskParams, scale: f64, split: Option<u32>) -> Vec<Camera> {
    let (r, h) = (params.radius, params.half_thickness);
    let (w, hgt) = (spec.width, spec.height);
    let elevation = spec.elevation_deg.to_radians();
    let side_rows = split.unwrap_or(hgt);
    let cx = f64::from(w / 2);
    let (se, ce) = elevation.sin_cos();
    // A pinhole looking along f = (0, cos ε, −sin ε) through the world origin
    // (which the principal point (cx, cy) shows, as for the orthographic camera),
    // with the near rim's mid-height (0, −R, H) at depth d and the disk's centre
    // (0, 0, H) at depth d + R cos ε, where the scale is `scale`.
    let pinhole = spec.camera_distance_m.map(|d| {
        let depth_origin = d + r * ce + h * se;
        Pinhole {
            position: [0.0, -depth_origin * ce, depth_origin * se],
            focal_px: (d + r * ce) / scale,
        }
    });
    let side = Camera {
        view: View::Side,
        cx,
        cy: 0.55 * f64::from(side_rows),
        scale,
        elevation,
        row_start: 0,
        row_end: side_rows,
        pinhole,
    };
    let mut cameras = vec![side];
    if let Some(sp) = split {
        cameras.push(Camera {
            view: View::Plan,
            cx,
            cy: f64::from(sp) + 0.5 * f64::from(hgt - sp),
            scale,
            elevation,
            row_start: sp,
            row_end: hgt,
            pinhole: None,
        });
    }
    cameras
}

/// The calibration an orthographic `side` camera gives, and its truth: the disk's
/// edges and rims at the image scale, the near rim's scale that scale over cos ε.
fn orthographic_calibration(side: &Camera, params: &DiskParams) -> (Calibration, CameraTruth) {
    let (r, h) = (params.radius, params.half_thickness);
    let (scale, elevation, cx) = (side.scale, side.elevation, side.cx);
    let (se, ce) = elevation.sin_cos();
    let calibration = Calibration {
        x_l: cx - r / scale,
        x_r: cx + r / scale,
        x_centre: cx,
        z_t: side.cy - (2.0 * h * elevation.cos() - r * elevation.sin()) / scale,
        z_base: side.cy + r * elevation.sin() / scale,
    };
    let camera = CameraTruth {
        projection: Projection::Orthographic,
        distance_to_near_rim_m: None,
        position_m: None,
        focal_px: None,
        perspective_factor: 1.0,
        near_rim_metres_per_px: scale / ce,
        centre_metres_per_px: scale,
        x_l_top: calibration.x_l,
        x_r_top: calibration.x_r,
        // The far top rim (0, R, 2H): v = R sin ε + 2H cos ε.
        z_t_far: side.cy - (r * se + 2.0 * h * ce) / scale,
    };
    (calibration, camera)
}

/// The clip's ground truth but for its frames ([`Renderer::add_frame_truth`]).
fn ground_truth(
    spec: &RenderSpec,
    motion: &Motion,
    split: Option<u32>,
    scale: f64,
    delta: f64,
    camera: CameraTruth,
    calibration: Calibration,
) -> GroundTruth {
    GroundTruth {
        format_version: 2,
        source: motion.source,
        plate: spec.plate,
        two_view: spec.two_view,
        split_row: split,
        width: spec.width,
        height: spec.height,
        fps: motion.timing.fps,
        captured_frames: motion.states.len(),
        halt_time: motion.timing.halt_time,
        t_beta: motion.t_beta(),
        post_flat_beta_dot: motion.post_flat.beta_dot0,
        true_n: motion.true_n,
        a_e: motion.a_e,
        disk: motion.params,
        beta0: motion.beta0,
        elevation: spec.elevation_deg.to_radians(),
        metres_per_px_image: scale,
        delta,
        camera,
        scenery: spec.scenery,
        nutation: motion.nutation,
        calibration,
        effects: spec.effects,
        dropped: {
            let mut d = spec.dropped.clone();
            d.sort_unstable();
            d.dedup();
            d
        },
        display_orientation: spec.display_orientation,
        storage: spec.storage,
        duplicated: sorted(&spec.duplicated),
        interpolated: sorted(&spec.interpolated),
        vfr_jitter: motion.timing.jitter,
        slowed_sections: spec.slowed_sections.clone(),
        stamped: motion.timing.jitter.is_some() || !spec.slowed_sections.is_empty(),
        camera_shake_centre_px: None,
        frames: Vec::new(),
    }
}

/// Row of the lowest point on column `x` of `cam` whose ray first meets a white
/// surface of the disk at `pose`: marching up the column in quarter pixels from below
/// the disk's bounding box, then bisection to 1e-9 px (see the module docs).
pub(crate) fn rim_edge_row(disk: &DiskShape, cam: &Camera, x: f64, pose: &Pose) -> Option<f64> {
    let white = |row: f64| {
        let (o, d) = cam.ray(x, row);
        disk.intersect(pose, o, d)
            .is_some_and(|hit| hit.surface.is_white_disk())
    };
    let corners = disk.box_corners(pose);
    let (mut top, mut bottom) = (f64::INFINITY, f64::NEG_INFINITY);
    for c in corners {
        let (_, row) = cam.project(c);
        top = top.min(row);
        bottom = bottom.max(row);
    }
    let mut below = bottom + 1.0;
    let mut row = below;
    while row > top - 1.0 {
        row -= 0.25;
        if white(row) {
            return Some(bisect(&white, row, below));
        }
        below = row;
    }
    None
}

/// The boundary between `inside` (true at `above`) and not (at `below`), to 1e-9 px.
fn bisect(inside: &dyn Fn(f64) -> bool, mut above: f64, mut below: f64) -> f64 {
    for _ in 0..60 {
        let mid = 0.5 * (above + below);
        if inside(mid) {
            above = mid;
        } else {
            below = mid;
        }
    }
    0.5 * (above + below)
}

/// Maximum of a unimodal `f` on [lo, hi] by golden-section search (80 steps: to
/// 1e-15 of the interval): its argument.
fn golden_max(f: &dyn Fn(f64) -> f64, lo: f64, hi: f64) -> f64 {
    crate::numeric::golden_section(|x| -f(x), lo, hi, crate::numeric::minimise::Stop::Steps(80))
        .midpoint()
}

/// The rest frame's calibration points and the camera's scales through the pinhole
/// `cam` at depth `d` from the near rim (module docs, "Perspective"): x_l, x_r the
/// ends of the bottom rim's silhouette (the extremes of the image x of (R cos a,
/// R sin a, 0)), x_centre their midpoint, z_base the rim edge on that column (ray cast,
/// so that z_rim is 0 at rest), z_t the side face's upper edge there (ray cast).
fn pinhole_calibration(
    scene: &Scene,
    cam: &Camera,
    params: &DiskParams,
    d: f64,
) -> Result<(Calibration, CameraTruth), RenderError> {
    let (r, h) = (params.radius, params.half_thickness);
    let pinhole = cam
        .pinhole
        .ok_or_else(|| RenderError::invalid("the side camera is not a pinhole"))?;
    let end = |z: f64, right: bool| {
        let x = |a: f64| cam.project([r * a.cos(), r * a.sin(), z]).0;
        let half = 0.5 * PI;
        if right {
            x(golden_max(&x, -half, half))
        } else {
            x(golden_max(&|a| -x(a), half, 3.0 * half))
        }
    };
    let (x_l, x_r) = (end(0.0, false), end(0.0, true));
    let x_centre = 0.5 * (x_l + x_r);
    let rest = Pose::rolling(params, 0.0, 0.0, 0.0, 0.0, 0.0);
    let missing = |what: &str| {
        RenderError::invalid(format!(
            "the camera {d} m from the near rim does not see the disk's {what} on its centre \
             column (frame too small for the disk?)"
        ))
    };
    let z_base =
        rim_edge_row(&scene.disk, cam, x_centre, &rest).ok_or_else(|| missing("bottom rim"))?;
    let side = |row: f64| {
        let (o, dir) = cam.ray(x_centre, row);
        scene
            .first_disk_hit(&rest, o, dir)
            .is_some_and(|hit| hit.surface == Surface::Side)
    };
    let (mut below, mut row) = (z_base - 0.01, z_base - 0.01);
    if !side(row) {
        return Err(missing("side"));
    }
    // The side is 2H tall: at most 2H cos ε / (its scale) rows, which a pinhole
    // enlarges by less than 2 at 0.1 m.
    let limit = z_base - 4.0 * h / cam.footprint(d);
    while side(row) {
        below = row;
        row -= 0.25;
        if row < limit {
            return Err(missing("top face"));
        }
    }
    let z_t = bisect(&side, below, row);
    // The far top rim: the silhouette's top, where the column leaves the disk.
    let on_disk = |row: f64| {
        let (o, dir) = cam.ray(x_centre, row);
        scene.first_disk_hit(&rest, o, dir).is_some()
    };
    let (mut below, mut row) = (z_t, z_t);
    while on_disk(row) {
        below = row;
        row -= 0.25;
        if row < limit {
            return Err(missing("top of the silhouette"));
        }
    }
    let z_t_far = bisect(&on_disk, below, row);
    let ce = cam.elevation.cos();
    let (f, u) = cam.side_frame();
    // ∂row/∂z at the near bottom rim N = (0, −R, 0): row = cy − F (q·u)/(q·f) with
    // q = N − C, so ∂row/∂z = −F (u_z (q·f) − (q·u) f_z)/(q·f)².
    let q = [
        -pinhole.position[0],
        -r - pinhole.position[1],
        -pinhole.position[2],
    ];
    let (qf, qu) = (
        q[1] * f[1] + q[2] * f[2] + q[0] * f[0],
        q[1] * u[1] + q[2] * u[2] + q[0] * u[0],
    );
    let drow_dz = pinhole.focal_px * (u[2] * qf - qu * f[2]) / (qf * qf);
    let camera = CameraTruth {
        projection: Projection::Perspective,
        distance_to_near_rim_m: Some(d),
        position_m: Some(pinhole.position),
        focal_px: Some(pinhole.focal_px),
        perspective_factor: (d + r * ce) / d,
        near_rim_metres_per_px: 1.0 / drow_dz.abs(),
        centre_metres_per_px: cam.scale,
        x_l_top: end(2.0 * h, false),
        x_r_top: end(2.0 * h, true),
        z_t_far,
    };
    Ok((
        Calibration {
            x_l,
            x_r,
            x_centre,
            z_t,
            z_base,
        },
        camera,
    ))
}

#[derive(Clone, Copy, Debug)]
struct Rect {
    x0: usize,
    x1: usize,
    y0: usize,
    y1: usize,
}

impl Rect {
    fn union(&self, other: &Rect) -> Rect {
        Rect {
            x0: self.x0.min(other.x0),
            x1: self.x1.max(other.x1),
            y0: self.y0.min(other.y0),
            y1: self.y1.max(other.y1),
        }
    }
}

/// The mirror image seen where the plate is, from the frame `buf` and its blurred
/// mirror image and plate coverage: coverage × blur(mirror)/blur(coverage).
fn seen_mirror(buf: &[Channels], blurred: &[[f32; 4]]) -> Vec<[f32; 3]> {
    buf.par_iter()
        .zip(blurred)
        .map(|(p, b)| {
            if p[6] > 0.0 && b[3] > 1e-6 {
                let k = p[6] / b[3];
                [k * b[0], k * b[1], k * b[2]]
            } else {
                [0.0; 3]
            }
        })
        .collect()
}

fn average<const N: usize>(colours: impl Iterator<Item = [f32; N]>, n: usize) -> [f32; N] {
    let mut sum = [0.0f32; N];
    for c in colours {
        for (s, v) in sum.iter_mut().zip(c) {
            *s += v;
        }
    }
    sum.map(|s| s / n as f32)
}

/// Refuses a render no camera or disk could give: every check below, in turn (the
/// first failure is reported).
fn validate(spec: &RenderSpec, motion: &Motion) -> Result<(), RenderError> {
    validate_frame_and_camera(spec, motion)?;
    validate_scenery(&spec.scenery)?;
    validate_effects(&spec.effects, motion.timing.fps)?;
    validate_dropped(spec, motion)?;
    validate_slowed_sections(spec, motion)?;
    validate_substituted(spec, motion)
}

/// The frame size (16 × 16 px up to [`MAX_FRAME_PIXELS`]), the camera (elevation in
/// (0°, 30°], a positive scale, a distance in [`CAMERA_DISTANCE_RANGE_M`]) and the
/// disk's strip and rounded rims, which must fit within its radius and half-thickness.
fn validate_frame_and_camera(spec: &RenderSpec, motion: &Motion) -> Result<(), RenderError> {
    let fail = |m: String| Err(RenderError::Invalid(m));
    if spec.width < 16 || spec.height < 16 {
        return fail(format!(
            "frames must be at least 16 × 16 px, got {} × {}",
            spec.width, spec.height
        ));
    }
    if u64::from(spec.width) * u64::from(spec.height) > MAX_FRAME_PIXELS {
        return fail(format!(
            "frames of {} × {} px exceed the limit of {MAX_FRAME_PIXELS} px (3840 × 2160, \
             4K UHD): each is rendered in memory, 16 at a time",
            spec.width, spec.height
        ));
    }
    if !(spec.elevation_deg > 0.0 && spec.elevation_deg <= 30.0) {
        return fail(format!(
            "the camera elevation must lie in (0°, 30°], got {}°",
            spec.elevation_deg
        ));
    }
    if let Some(s) = spec.metres_per_px
        && !(s.is_finite() && s > 0.0)
    {
        return fail(format!("the image scale must be positive, got {s} m/px"));
    }
    if let Some(d) = spec.camera_distance_m {
        let (lo, hi) = CAMERA_DISTANCE_RANGE_M;
        if !(d.is_finite() && (lo..=hi).contains(&d)) {
            return fail(format!(
                "the camera distance from the near rim must lie in {lo}–{hi} m, got {d} m \
                 (leave it out for an orthographic camera)"
            ));
        }
    }
    if !(spec.strip_width.is_finite()
        && spec.strip_width > 0.0
        && spec.strip_width < motion.params.radius)
    {
        return fail(format!(
            "the strip width must lie in (0, R), got {} m",
            spec.strip_width
        ));
    }
    if !(spec.edge_radius.is_finite()
        && spec.edge_radius >= 0.0
        && spec.edge_radius <= motion.params.half_thickness)
    {
        return fail(format!(
            "the rims' rounding radius must lie in [0, H] = [0, {} m], got {} m",
            motion.params.half_thickness, spec.edge_radius
        ));
    }
    Ok(())
}

/// The scenery: grey levels within [0, 255] (the paper's not black), the plate's
/// texture contrast within [0, 1], its reflectivity within [0, 0.9], the reflection
/// blur within [0, 20] px and the fill light above the horizon.
fn validate_scenery(sc: &Scenery) -> Result<(), RenderError> {
    let fail = |m: String| Err(RenderError::Invalid(m));
    let grey_ok = |g: f64| g.is_finite() && (0.0..=255.0).contains(&g);
    if !(grey_ok(sc.paper_grey) && sc.paper_grey > 0.0) {
        return fail(format!(
            "the paper's grey level must lie in (0, 255], got {}",
            sc.paper_grey
        ));
    }
    if let Some(g) = sc.plate_grey
        && !grey_ok(g)
    {
        return fail(format!(
            "the plate's grey level must lie in [0, 255], got {g}"
        ));
    }
    if !(sc.texture_contrast.is_finite() && (0.0..=1.0).contains(&sc.texture_contrast)) {
        return fail(format!(
            "the plate texture's contrast (RMS relative albedo variation) must lie in [0, 1], \
             got {}",
            sc.texture_contrast
        ));
    }
    if let Some(rho) = sc.reflectivity
        && !(rho.is_finite() && (0.0..=0.9).contains(&rho))
    {
        return fail(format!(
            "the plate's reflectivity (mirror fraction) must lie in [0, 0.9], got {rho}"
        ));
    }
    if !(sc.reflection_blur_px.is_finite() && (0.0..=20.0).contains(&sc.reflection_blur_px)) {
        return fail(format!(
            "the reflection blur σ must lie in [0, 20] px, got {} px",
            sc.reflection_blur_px
        ));
    }
    if !(sc.fill_elevation_deg.is_finite()
        && sc.fill_elevation_deg > 0.0
        && sc.fill_elevation_deg < 90.0)
    {
        return fail(format!(
            "the fill light's elevation must lie in (0°, 90°), got {}°",
            sc.fill_elevation_deg
        ));
    }
    Ok(())
}

/// The camera's effects: noise, blur, flicker and exposure finite and non-negative,
/// the flicker never putting the light out, the exposure within the frame interval
/// 1/`fps` and averaging 1 to [`MAX_EXPOSURE_SAMPLES`] poses, and a finite drift.
fn validate_effects(fx: &Effects, fps: f64) -> Result<(), RenderError> {
    let fail = |m: String| Err(RenderError::Invalid(m));
    for (name, v) in [
        ("the read noise σ [grey levels]", fx.noise_sigma),
        ("the shot noise k [grey levels^½]", fx.shot_noise),
        ("the blur σ [px]", fx.blur_sigma),
        (
            "the 100 Hz flicker amplitude (fraction of the light)",
            fx.flicker_amplitude,
        ),
        (
            "the 50 Hz flicker amplitude (fraction of the light)",
            fx.flicker_50hz_amplitude,
        ),
        ("the exposure time [s]", fx.exposure_s),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return fail(format!("{name} must be finite and non-negative, got {v}"));
        }
    }
    if fx.flicker_amplitude + fx.flicker_50hz_amplitude >= 1.0 {
        return fail(format!(
            "the flicker amplitudes at 100 Hz and 50 Hz must sum to less than 1 (the light \
             would go out), got {} + {}",
            fx.flicker_amplitude, fx.flicker_50hz_amplitude
        ));
    }
    if !(fx.flicker_phase_100.is_finite() && fx.flicker_phase_50.is_finite()) {
        return fail("the flicker phases [rad] must be finite".into());
    }
    let frame_s = 1.0 / fps;
    if fx.exposure_s > frame_s * (1.0 + 1e-12) {
        return fail(format!(
            "the exposure time must not exceed the frame interval 1/fps = {frame_s:.6} s, got \
             {} s",
            fx.exposure_s
        ));
    }
    if !(1..=MAX_EXPOSURE_SAMPLES).contains(&fx.exposure_samples) {
        return fail(format!(
            "the exposure averages 1 to {MAX_EXPOSURE_SAMPLES} poses, got {}",
            fx.exposure_samples
        ));
    }
    if !fx.drift_px_per_s.is_finite() {
        return fail("the drift [px/s] must be finite".into());
    }
    match &fx.shake {
        Some(shake) => validate_shake(shake),
        None => Ok(()),
    }
}

/// The camera shake: amplitudes within [0, [`MAX_SHAKE_PX`]] px and a roll within
/// [0, [`MAX_SHAKE_ROLL_DEG`]]°, a band of positive frequencies low to high and a
/// positive sway frequency.
fn validate_shake(shake: &Shake) -> Result<(), RenderError> {
    let fail = |m: String| Err(RenderError::Invalid(m));
    for (name, v, max) in [
        (
            "the shake's vibration RMS [px]",
            shake.vibration_rms_px,
            MAX_SHAKE_PX,
        ),
        (
            "the shake's sway amplitude [px]",
            shake.sway_px,
            MAX_SHAKE_PX,
        ),
        ("the shake's roll [deg]", shake.roll_deg, MAX_SHAKE_ROLL_DEG),
    ] {
        if !(v.is_finite() && (0.0..=max).contains(&v)) {
            return fail(format!("{name} must lie in [0, {max}], got {v}"));
        }
    }
    let [lo, hi] = shake.vibration_band_hz;
    if !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo <= hi) {
        return fail(format!(
            "the shake's vibration band must be LOW:HIGH with 0 < LOW ≤ HIGH [Hz], got \
             {lo}:{hi}"
        ));
    }
    if !(shake.sway_hz.is_finite() && shake.sway_hz > 0.0) {
        return fail(format!(
            "the shake's sway frequency must be positive [Hz], got {}",
            shake.sway_hz
        ));
    }
    Ok(())
}

/// Dropped frames: each one captured, and not all of them.
fn validate_dropped(spec: &RenderSpec, motion: &Motion) -> Result<(), RenderError> {
    let fail = |m: String| Err(RenderError::Invalid(m));
    if let Some(&bad) = spec.dropped.iter().find(|&&k| k >= motion.states.len()) {
        return fail(format!(
            "dropped frame {bad} does not exist (the clip captures {} frames, 0-based)",
            motion.states.len()
        ));
    }
    if motion.states.len() <= spec.dropped.len() {
        return fail("every frame would be dropped".into());
    }
    Ok(())
}

/// Slowed sections: each a finite span starting within the clip, slowed by a factor
/// in (1, [`MAX_SLOWING`]], and none overlapping the next.
fn validate_slowed_sections(spec: &RenderSpec, motion: &Motion) -> Result<(), RenderError> {
    let fail = |m: String| Err(RenderError::Invalid(m));
    let clip_s = motion.timing.halt_time + motion.timing.after_halt;
    let mut sections = spec.slowed_sections.clone();
    sections.sort_by(|a, b| a.start_s.total_cmp(&b.start_s));
    for (k, section) in sections.iter().enumerate() {
        let SlowedSection {
            start_s,
            end_s,
            factor,
        } = *section;
        if !(start_s.is_finite() && end_s.is_finite() && 0.0 <= start_s && start_s < end_s) {
            return fail(format!(
                "a slowed section must start at or after 0 s and end after it starts, got \
                 {start_s}–{end_s} s"
            ));
        }
        if start_s >= clip_s {
            return fail(format!(
                "the slowed section {start_s}–{end_s} s starts after the clip's {clip_s} s"
            ));
        }
        if !(factor.is_finite() && factor > 1.0 && factor <= MAX_SLOWING) {
            return fail(format!(
                "a slowed section's factor must lie in (1, {MAX_SLOWING}], got {factor}"
            ));
        }
        if let Some(next) = sections.get(k + 1)
            && next.start_s < end_s
        {
            return fail(format!(
                "the slowed sections {start_s}–{end_s} s and {}–{} s overlap",
                next.start_s, next.end_s
            ));
        }
    }
    Ok(())
}

/// Duplicated and interpolated frames: each a written frame, not both, with the
/// captured frames it is made from beside it (a duplicate repeats the capture before
/// it; a blend needs a capture on each side).
fn validate_substituted(spec: &RenderSpec, motion: &Motion) -> Result<(), RenderError> {
    let fail = |m: String| Err(RenderError::Invalid(m));
    let written: Vec<usize> = (0..motion.states.len())
        .filter(|k| !spec.dropped.contains(k))
        .collect();
    let substituted = |k: usize| spec.duplicated.contains(&k) || spec.interpolated.contains(&k);
    for (list, what) in [
        (&spec.duplicated, "duplicated"),
        (&spec.interpolated, "interpolated"),
    ] {
        for &k in list.iter() {
            let Some(at) = written.iter().position(|&w| w == k) else {
                return fail(format!(
                    "{what} frame {k} is not a written frame (the clip captures {} frames, \
                     0-based; dropped frames are not written)",
                    motion.states.len()
                ));
            };
            if spec.duplicated.contains(&k) && spec.interpolated.contains(&k) {
                return fail(format!(
                    "frame {k} cannot be both duplicated and interpolated"
                ));
            }
            // A duplicate repeats a capture; a blend needs a capture on each side.
            let neighbours_needed: &[usize] = if what == "duplicated" {
                &[at.wrapping_sub(1)]
            } else {
                &[at.wrapping_sub(1), at + 1]
            };
            for &n in neighbours_needed {
                if written.get(n).is_none_or(|&w| substituted(w)) {
                    return fail(format!(
                        "{what} frame {k} needs a captured (not duplicated or interpolated) \
                         frame {} it",
                        if n < at { "before" } else { "after" }
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Distances of a pinhole side camera from the near rim that render accepts \[m\]
/// (phones are held at 0.2–0.5 m; beyond 10 m a pinhole is orthographic to 0.4 %).
pub const CAMERA_DISTANCE_RANGE_M: (f64, f64) = (0.1, 10.0);

/// The most a slowed section is slowed: 960 fps played at 1 fps.
pub const MAX_SLOWING: f64 = 960.0;

/// Most poses one frame's exposure averages.
pub const MAX_EXPOSURE_SAMPLES: usize = 16;

/// The largest vibration RMS and sway amplitude of a camera shake \[px\].
pub const MAX_SHAKE_PX: f64 = 50.0;

/// The largest roll of a camera shake \[deg\].
pub const MAX_SHAKE_ROLL_DEG: f64 = 10.0;

/// Separable Gaussian blur with clamped borders.
fn gaussian_blur<const N: usize>(buf: &mut [[f32; N]], w: usize, h: usize, sigma: f64) {
    let radius = (3.0 * sigma).ceil() as isize;
    let kernel: Vec<f32> = (-radius..=radius)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp() as f32)
        .collect();
    let norm: f32 = kernel.iter().sum();
    let kernel: Vec<f32> = kernel.iter().map(|k| k / norm).collect();
    let convolve = |get: &dyn Fn(isize) -> [f32; N]| -> [f32; N] {
        let mut acc = [0.0f32; N];
        for (j, k) in kernel.iter().enumerate() {
            let c = get(j as isize - radius);
            for (a, v) in acc.iter_mut().zip(c) {
                *a += k * v;
            }
        }
        acc
    };
    let mut tmp = vec![[0.0f32; N]; w * h];
    tmp.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let src = &buf[y * w..(y + 1) * w];
        for (x, out) in row.iter_mut().enumerate() {
            *out = convolve(&|d| src[(x as isize + d).clamp(0, w as isize - 1) as usize]);
        }
    });
    buf.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, out) in row.iter_mut().enumerate() {
            *out = convolve(&|d| tmp[(y as isize + d).clamp(0, h as isize - 1) as usize * w + x]);
        }
    });
}

/// For tests: Euler's disk on the thesis's n = 0.5 power law at `fps`, halting at
/// `halt` [s] and filmed `after` [s] more, spinning down on stainless steel.
#[cfg(test)]
pub(crate) fn test_motion(fps: f64, halt: f64, after: f64) -> Motion {
    let timing = Timing {
        fps,
        halt_time: halt,
        after_halt: after,
        jitter: None,
    };
    let spin = PostFlatSpin {
        beta_dot0: -2.8,
        mu: 0.134,
    };
    power_law_motion(
        &crate::model::params::Preset::EulerDisk.params(),
        &PowerLaw::thesis(0.5),
        &timing,
        spin,
    )
    .expect("motion")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::params::Preset;
    use std::f64::consts::PI;

    fn small_spec(plate: Plate, two_view: bool) -> RenderSpec {
        let mut spec = RenderSpec::thesis(plate, two_view);
        (spec.width, spec.height) = if two_view { (320, 480) } else { (480, 320) };
        spec
    }

    fn intensity(img: &RgbImage, x: u32, row: u32) -> f64 {
        let p = img.get_pixel(x, row);
        (f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2])) / 3.0
    }

    /// Rows (going up from `start` to `end`) where the column profile crosses
    /// `level`, with `true` for a rising edge (bright above, dark below).
    fn crossings(i: &dyn Fn(u32) -> f64, start: u32, end: u32, level: f64) -> Vec<(u32, bool)> {
        (end..start)
            .rev()
            .filter_map(|r| {
                let (above, below) = (i(r) >= level, i(r + 1) >= level);
                (above != below).then_some((r, above))
            })
            .collect()
    }

    /// Sub-pixel position of the edge of a box-filtered step near sample `k`: where
    /// the profile crosses the midpoint of its levels three samples either side,
    /// interpolated linearly between neighbouring samples.
    fn edge_1d(f: &dyn Fn(i64) -> f64, k: i64) -> f64 {
        let level = 0.5 * (f(k - 3) + f(k + 4));
        for j in k - 2..=k + 2 {
            let (a, b) = (f(j), f(j + 1));
            if (a - level) * (b - level) <= 0.0 && a != b {
                return j as f64 + (level - a) / (b - a);
            }
        }
        f64::NAN
    }

    /// The plate line on a rendered centre column `col`: the first (dark plate) or
    /// second (light plate) edge going up from well below the disk, as for z_rim.
    fn rendered_plate_line(f: &dyn Fn(i64) -> f64, cal: &Calibration, plate: Plate) -> f64 {
        let edges = crossings(
            &|r| f(i64::from(r)),
            (cal.z_base + 30.0) as u32,
            cal.z_t as u32,
            130.0,
        );
        let base_row = match plate {
            Plate::Dark => edges[0].0,
            Plate::Light => edges[1].0,
        };
        edge_1d(f, i64::from(base_row))
    }

    /// The pixel pair with the largest step within ±`window` of `coarse`.
    fn steepest(f: &dyn Fn(i64) -> f64, coarse: f64, window: i64) -> i64 {
        let c = coarse.floor() as i64;
        (c - window..=c + window)
            .max_by(|&a, &b| {
                let da = (f(a + 1) - f(a)).abs();
                let db = (f(b + 1) - f(b)).abs();
                da.total_cmp(&db)
            })
            .unwrap_or(c)
    }

    /// The ray-cast z_rim at a peak (ψ = −π/2) is the closed form of the module docs,
    /// and it is a maximum in ψ.
    #[test]
    fn z_rim_peak_matches_closed_form() {
        let params = Preset::EulerDisk.params();
        for elevation_deg in [0.5, 3.0, 8.0] {
            let mut spec = small_spec(Plate::Dark, false);
            spec.elevation_deg = elevation_deg;
            let r = Renderer::new(&spec, &test_motion(480.0, 0.05, 0.0)).expect("renderer");
            let truth = r.truth();
            for phi in [0.002, 0.0243, 0.1, 0.3] {
                let z = |psi: f64| {
                    let pose = Pose::rolling(&params, psi, phi, 0.7, 0.0, 0.0);
                    (truth.calibration.z_base - r.rim_edge_row(&pose).expect("on column"))
                        * truth.delta
                };
                let peak = z(-0.5 * PI);
                let expected = peak_z_rim(&params, phi, elevation_deg.to_radians());
                // Bisection to 1e-9 px; 1e-9 m is 4e-6 px here.
                assert!(
                    (peak - expected).abs() < 1e-9,
                    "ε = {elevation_deg}°, φ = {phi}: {peak} vs {expected}"
                );
                assert!(z(-0.5 * PI + 0.05) < peak && z(-0.5 * PI - 0.05) < peak);
                // Opposite side: the contact point faces the camera; seen from above it
                // sits (R(1 − cos φ) + H sin φ) tan ε higher than the rest rim.
                let trough = (params.radius * (1.0 - phi.cos())
                    + params.half_thickness * phi.sin())
                    * elevation_deg.to_radians().tan();
                assert!((z(0.5 * PI) - trough).abs() < 1e-9, "trough at ψ = π/2");
            }
        }
    }

    /// Every 7th frame's rendered bottom edge on the centre column, found by a
    /// sub-pixel threshold crossing (dark plate: the first rising edge from the
    /// bottom; light plate: the second, after the shadow, fig. 3.9), against the
    /// truth z_rim: a box-filtered edge read by linear interpolation is within 0.1 px,
    /// and the shading on either side of the edge moves it by up to 0.15 px more.
    fn check_bottom_edge_against_truth(r: &Renderer, plate: Plate) {
        let truth = r.truth();
        let x = truth.calibration.x_centre as u32;
        let mut checked = 0;
        for f in truth.frames.iter().step_by(7) {
            let img = r.render_frame(f.file_index);
            let i = |row: u32| intensity(&img, x, row);
            let start = (truth.calibration.z_base + 30.0) as u32;
            let end = (truth.calibration.z_t - 20.0) as u32;
            let edges = crossings(&i, start, end, 130.0);
            let (row, rising) = match plate {
                Plate::Dark => edges[0],
                Plate::Light => edges[1],
            };
            assert!(rising, "{plate:?}, frame {}: {edges:?}", f.index);
            let col = |k: i64| intensity(&img, x, k as u32);
            let measured = truth.calibration.z_base - edge_1d(&col, i64::from(row));
            let expected = f.z_rim_px.expect("disk on the column");
            assert!(
                (measured - expected).abs() < 0.3,
                "{plate:?}, frame {}: measured {measured}, truth {expected}",
                f.index
            );
            checked += 1;
        }
        assert!(checked > 25);
    }

    /// The rendered bottom edge on the centre column matches the truth z_rim on
    /// both plates (orthographic camera).
    #[test]
    fn rendered_bottom_edge_matches_truth_z_rim() {
        let m = test_motion(480.0, 0.4, 0.05);
        for plate in [Plate::Dark, Plate::Light] {
            let r = Renderer::new(&small_spec(plate, false), &m).expect("renderer");
            check_bottom_edge_against_truth(&r, plate);
        }
    }

    /// The rest frame's calibration points x_l, x_r, z_t, z_base (fig. 3.3) measured
    /// by threshold crossings match the truth, and δ = 2H/(z_base − z_t) = s/cos ε.
    #[test]
    fn rest_frame_calibration_points_match_truth() {
        let m = test_motion(480.0, 0.02, 0.1);
        for plate in [Plate::Dark, Plate::Light] {
            let r = Renderer::new(&small_spec(plate, false), &m).expect("renderer");
            let truth = r.truth();
            let cal = truth.calibration;
            let img = r.render_frame(r.frame_count() - 1);
            let x = cal.x_centre as u32;
            let col = |row: i64| intensity(&img, x, row as u32);
            let z_base = rendered_plate_line(&col, &cal, plate);
            // Near top rim: the camera-facing side (bright) meets the top face (dimmer);
            // the steepest step within 4 px of the expected row.
            let z_t = edge_1d(&col, steepest(&col, cal.z_t, 4));
            // Left and right edges of the disk on a row inside the side band.
            let y = (0.5 * (cal.z_base + cal.z_t)).round() as u32;
            let row = |xx: i64| intensity(&img, xx as u32, y);
            let x_l = edge_1d(&row, steepest(&row, cal.x_l, 4));
            let x_r = edge_1d(&row, steepest(&row, cal.x_r, 4));
            for (name, got, want) in [
                ("z_base", z_base, cal.z_base),
                ("z_t", z_t, cal.z_t),
                ("x_l", x_l, cal.x_l),
                ("x_r", x_r, cal.x_r),
            ] {
                // Sub-pixel crossing of a box-filtered edge: < 0.3 px.
                assert!(
                    (got - want).abs() < 0.3,
                    "{plate:?} {name}: {got} vs {want}"
                );
            }
            let e = truth.elevation;
            assert!((truth.delta - truth.metres_per_px_image / e.cos()).abs() < 1e-15);
            assert!(
                truth
                    .frames
                    .last()
                    .and_then(|f| f.z_rim_px)
                    .expect("z")
                    .abs()
                    < 1e-6
            );
        }
    }

    /// The strip's angle measured in the plan view by second moments of the red
    /// pixels equals the truth β (mod π), before the halt and during the post-flat
    /// spin (eq. 3.20).
    #[test]
    fn strip_angle_from_moments_matches_truth_beta() {
        let m = test_motion(480.0, 0.2, 0.06);
        let r = Renderer::new(&small_spec(Plate::Dark, true), &m).expect("renderer");
        let truth = r.truth();
        let split = truth.split_row.expect("two views");
        let mut post_flat = 0;
        for f in truth.frames.iter().step_by(5) {
            let img = r.render_frame(f.file_index);
            let (mut n, mut sx, mut sy, mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
            for (x, row, p) in img.enumerate_pixels() {
                if row < split || !(p[0] > 120 && p[1] < 90 && p[2] < 90) {
                    continue;
                }
                let (x, y) = (f64::from(x), -f64::from(row));
                n += 1.0;
                sx += x;
                sy += y;
                sxx += x * x;
                syy += y * y;
                sxy += x * y;
            }
            let (mx, my) = (sx / n, sy / n);
            let (cxx, cyy, cxy) = (sxx / n - mx * mx, syy / n - my * my, sxy / n - mx * my);
            let measured = 0.5 * (2.0 * cxy).atan2(cxx - cyy);
            let diff = (measured - f.beta).rem_euclid(PI);
            let diff = diff.min(PI - diff);
            // A 280 px strip on a pixel grid: about 1/280 rad.
            assert!(
                diff < 0.01,
                "frame {}: measured {measured}, β {}",
                f.index,
                f.beta
            );
            if f.t > 0.0 && f.t < truth.t_beta {
                post_flat += 1;
            }
        }
        assert!(post_flat >= 3, "frames during the post-flat spin");
        let last = truth.frames.last().expect("frames");
        let at_halt = truth.frames.iter().find(|f| f.t >= 0.0).expect("halt");
        // The strip turned on after the flat: β̇₀ t_β / 2.
        let turned = last.beta - at_halt.beta;
        let expected = truth.post_flat_beta_dot * truth.t_beta / 2.0;
        assert!((turned - expected).abs() < 1e-9, "{turned} vs {expected}");
    }

    /// Dropped frames are absent from the written clip and listed in the truth, which
    /// keeps the true capture times; the truth JSON reads back unchanged.
    #[test]
    fn dropped_frames_are_absent_and_listed() {
        let m = test_motion(60.0, 0.2, 0.1);
        let mut spec = small_spec(Plate::Dark, false);
        (spec.width, spec.height) = (96, 64);
        spec.dropped = vec![7, 3];
        let r = Renderer::new(&spec, &m).expect("renderer");
        assert_eq!(m.states.len(), 19);
        let dir = tempfile::tempdir().expect("tempdir");
        let folder = dir.path().join("clip");
        let written = write_clip(&r, &folder, DEFAULT_ENCODING).expect("write");
        let files = crate::footage::frame_files(&folder).expect("frames");
        assert_eq!(files.len(), 17);
        // Issue 13.7: the folder gets the umask's permissions, as one made by hand.
        let by_hand = dir.path().join("by-hand");
        std::fs::create_dir(&by_hand).expect("mkdir");
        let mode = |p: &std::path::Path| {
            std::os::unix::fs::PermissionsExt::mode(&p.metadata().unwrap().permissions())
        };
        assert_eq!(mode(&folder), mode(&by_hand));
        assert!(files[16].ends_with("frame_000017.png"));
        let text = std::fs::read_to_string(&written.truth).expect("truth");
        let truth: GroundTruth = serde_json::from_str(&text).expect("json");
        // serde_json may round the last bit of a float; compare the structure.
        assert_eq!(truth.frames.len(), r.truth().frames.len());
        assert_eq!(truth.dropped, vec![3, 7]);
        let indices: Vec<usize> = truth.frames.iter().map(|f| f.index).collect();
        let expected: Vec<usize> = (0..19).filter(|k| *k != 3 && *k != 7).collect();
        assert_eq!(indices, expected);
        for (i, f) in truth.frames.iter().enumerate() {
            assert_eq!(f.file_index, i);
            assert!((f.t - (f.index as f64 / 60.0 - 0.2)).abs() < 1e-12);
        }
        // The same clip as MP4: OpenCV counts the written frames.
        let mp4 = dir.path().join("clip.mp4");
        write_clip(&r, &mp4, DEFAULT_ENCODING).expect("mp4");
        assert_eq!(crate::footage::probe(&mp4).expect("probe").frame_count, 17);
    }

    /// A 160 × 96 clip of a dark plate with sensor noise, 0.5 s at 240 fps, halting
    /// at 0.4 s: small enough to encode several times in a test.
    fn small_noisy_renderer() -> Renderer {
        let m = test_motion(240.0, 0.4, 0.1);
        let mut spec = small_spec(Plate::Dark, false);
        (spec.width, spec.height) = (160, 96);
        spec.effects.noise_sigma = 1.0;
        Renderer::new(&spec, &m).expect("renderer")
    }

    /// The path of `r`'s clip written with `encoding` as `name` in `dir`.
    fn encoded(
        r: &Renderer,
        dir: &std::path::Path,
        name: &str,
        encoding: ClipEncoding,
    ) -> std::path::PathBuf {
        let path = dir.join(name);
        write_clip(r, &path, encoding).expect("mp4");
        path
    }

    /// The same renderer and crf give the same MP4 bytes, also for the later of
    /// several encodes in one process (x264's macroblock tree, on by default, read
    /// uninitialised heap memory and changed them; see `write::write_mp4`), and a
    /// lower crf decodes closer to the rendered frames.
    #[test]
    fn mp4_bytes_repeat_and_crf_sets_the_quality() {
        let r = small_noisy_renderer();
        let dir = tempfile::tempdir().expect("tempdir");
        let encode = |name: &str, crf: u8| encoded(&r, dir.path(), name, ClipEncoding::crf(crf));
        let first = std::fs::read(encode("a.mp4", DEFAULT_CRF)).expect("read");
        for k in 0..3 {
            let again = std::fs::read(encode(&format!("b{k}.mp4"), DEFAULT_CRF)).expect("read");
            assert!(again == first, "encode {} of the same clip differs", k + 2);
        }
        // Mean absolute error of the decoded grey levels against the rendered ones.
        let error = |crf: u8| {
            let mut source =
                crate::footage::FrameSource::open(&encode(&format!("crf{crf}.mp4"), crf))
                    .expect("open");
            let (mut sum, mut count) = (0.0, 0usize);
            while let Some(frame) = source.next_frame().expect("decode") {
                let truth = r.render_frame(frame.index);
                for (x, y, p) in truth.enumerate_pixels() {
                    let grey = (f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2])) / 3.0;
                    sum += (f64::from(frame.view.intensity(x as usize, y as usize)) - grey).abs();
                    count += 1;
                }
            }
            assert_eq!(count, 160 * 96 * r.frame_count());
            sum / count as f64
        };
        let (fine, default, coarse) = (error(8), error(DEFAULT_CRF), error(40));
        assert!(
            fine < default && default < coarse,
            "mean |error| at crf 8, 23, 40: {fine:.3}, {default:.3}, {coarse:.3}"
        );
    }

    /// The encoding's picture structure is the stream's: I and P pictures only with
    /// `bframes` 0 and an I picture at least every `keyint` frames, where libx264's
    /// defaults code most of a moving clip as B pictures and key it once.
    #[test]
    fn the_encoding_sets_the_picture_structure() {
        let r = small_noisy_renderer();
        let dir = tempfile::tempdir().expect("tempdir");
        let types = |name: &str, encoding: ClipEncoding| {
            let path = encoded(&r, dir.path(), name, encoding);
            let mut source = crate::footage::FrameSource::open(&path).expect("open");
            let mut types = String::new();
            while let Some(frame) = source.next_frame().expect("decode") {
                types.push(frame.picture_type.unwrap_or('?'));
            }
            types
        };
        let phone = types(
            "phone.mp4",
            ClipEncoding {
                keyint: Some(8),
                bframes: Some(0),
                ..DEFAULT_ENCODING
            },
        );
        assert_eq!(phone.len(), r.frame_count());
        assert!(!phone.contains('B') && !phone.contains('?'), "{phone}");
        let longest_run = phone.split('I').map(str::len).max().unwrap_or(0);
        assert!(longest_run < 8, "{phone}");
        let default = types("default.mp4", DEFAULT_ENCODING);
        assert!(
            default.matches('B').count() > default.len() / 2 && default.matches('I').count() == 1,
            "{default}"
        );
    }

    fn pinhole_spec(plate: Plate, d: f64) -> RenderSpec {
        let mut spec = small_spec(plate, false);
        spec.camera_distance_m = Some(d);
        spec
    }

    /// Through a pinhole the rest frame's calibration points match the rendered
    /// edges: z_base and z_t on the centre column, the ends of the disk on a row at
    /// mid-height between the bottom's (x_l, x_r) and the top's silhouette ends; the
    /// last frame's z_rim is 0.
    #[test]
    fn pinhole_rest_calibration_matches_rendered_edges() {
        let m = test_motion(480.0, 0.02, 0.1);
        for (plate, d) in [(Plate::Dark, 0.2), (Plate::Light, 0.35), (Plate::Dark, 1.0)] {
            let r = Renderer::new(&pinhole_spec(plate, d), &m).expect("renderer");
            let truth = r.truth();
            let (cal, cam) = (truth.calibration, truth.camera);
            assert_eq!(cam.projection, Projection::Perspective);
            let img = r.render_frame(r.frame_count() - 1);
            let x = cal.x_centre.round() as u32;
            // The pinhole is on the disk's symmetry plane: the centre column is cx.
            assert!((cal.x_centre - f64::from(x)).abs() < 1e-9);
            let col = |row: i64| intensity(&img, x, row as u32);
            let z_base = rendered_plate_line(&col, &cal, plate);
            let z_t = edge_1d(&col, steepest(&col, cal.z_t, 3));
            let y = (0.5 * (cal.z_base + cal.z_t)).round() as u32;
            let row = |xx: i64| intensity(&img, xx as u32, y);
            let mid_l = 0.5 * (cal.x_l + cam.x_l_top);
            let mid_r = 0.5 * (cal.x_r + cam.x_r_top);
            let x_l = edge_1d(&row, steepest(&row, mid_l, 4));
            let x_r = edge_1d(&row, steepest(&row, mid_r, 4));
            for (name, got, want) in [
                ("z_base", z_base, cal.z_base),
                ("z_t", z_t, cal.z_t),
                ("x_l", x_l, mid_l),
                ("x_r", x_r, mid_r),
            ] {
                // Sub-pixel crossing of a box-filtered edge: < 0.3 px, as orthographic.
                assert!(
                    (got - want).abs() < 0.3,
                    "{plate:?}, d = {d} m, {name}: {got} vs {want}"
                );
            }
            // A camera above the top face sees it between z_t and the far top rim above
            // it; one below it (0.2 m at 3°: 12.5 mm up, the top at 2H = 12.7 mm) sees
            // the near top rim as the silhouette's top.
            let above = cam.position_m.expect("pinhole")[2] > 2.0 * truth.disk.half_thickness;
            if above {
                assert!(
                    cam.z_t_far < cal.z_t - 0.5,
                    "{} vs {}",
                    cam.z_t_far,
                    cal.z_t
                );
            } else {
                assert!((cam.z_t_far - cal.z_t).abs() < 1e-6);
            }
            // Nearer the camera, the top rim's silhouette is wider than the bottom's.
            assert!(cam.x_l_top < cal.x_l && cam.x_r_top > cal.x_r);
            let last = truth.frames.last().and_then(|f| f.z_rim_px).expect("z");
            assert!(last.abs() < 1e-6, "z_rim at rest {last}");
        }
    }

    /// Through a pinhole the ray-cast z_rim is the rendered bottom edge on the centre
    /// column, as for the orthographic camera.
    #[test]
    fn pinhole_rendered_bottom_edge_matches_truth_z_rim() {
        let m = test_motion(480.0, 0.4, 0.05);
        for (plate, d) in [(Plate::Dark, 0.25), (Plate::Light, 0.5)] {
            let r = Renderer::new(&pinhole_spec(plate, d), &m).expect("renderer");
            check_bottom_edge_against_truth(&r, plate);
        }
    }

    /// The pinhole's scales: the perspective factor is the ratio of the horizontal
    /// scales at the near rim's and the centre's depths (F/depth); the vertical scale
    /// at the near bottom rim is the projection's own derivative; eq. 3.10's δ from the
    /// exact z_t, z_base is within the rim's height (2H over the distance) of it; a
    /// camera 10 m away is orthographic to within R/d.
    #[test]
    fn pinhole_scales_and_the_orthographic_limit() {
        let params = Preset::EulerDisk.params();
        let (r_m, h_m) = (params.radius, params.half_thickness);
        let m = test_motion(480.0, 0.02, 0.05);
        for d in [0.2, 0.3, 0.5, 1.0] {
            let r = Renderer::new(&pinhole_spec(Plate::Dark, d), &m).expect("renderer");
            let truth = r.truth();
            let cam = &r.cameras[0];
            let c = truth.camera;
            // Horizontal scale ∝ depth: a 1 mm step across at the centre and at the
            // near rim's mid-height.
            let span = |y: f64| cam.project([5e-4, y, h_m]).0 - cam.project([-5e-4, y, h_m]).0;
            let factor = span(-r_m) / span(0.0);
            assert!(
                (factor / c.perspective_factor - 1.0).abs() < 1e-9,
                "d = {d}: {factor} vs {}",
                c.perspective_factor
            );
            assert!((c.centre_metres_per_px - 1e-3 / span(0.0)).abs() < 1e-12);
            // Vertical scale at the near bottom rim, by central differences.
            let dz = 1e-7;
            let rows = cam.project([0.0, -r_m, -dz]).1 - cam.project([0.0, -r_m, dz]).1;
            let near = 2.0 * dz / rows;
            assert!(
                (near / c.near_rim_metres_per_px - 1.0).abs() < 1e-6,
                "d = {d}: {near} vs {}",
                c.near_rim_metres_per_px
            );
            let rel = (truth.delta / c.near_rim_metres_per_px - 1.0).abs();
            assert!(
                rel < 2.0 * h_m / d,
                "d = {d}: δ off the near-rim scale by {rel}"
            );
        }
        // 10 m: the calibration points are the orthographic ones to within R/d of
        // their distances from the image centre.
        let far = Renderer::new(&pinhole_spec(Plate::Dark, 10.0), &m).expect("far");
        let ortho = Renderer::new(&small_spec(Plate::Dark, false), &m).expect("ortho");
        let (a, b) = (far.truth().calibration, ortho.truth().calibration);
        let tol = |v: f64| (v - ortho.cameras[0].cy).abs().max(v - 240.0) * r_m / 10.0 + 0.01;
        for (name, x, y) in [
            ("x_l", a.x_l, b.x_l),
            ("x_r", a.x_r, b.x_r),
            ("z_t", a.z_t, b.z_t),
            ("z_base", a.z_base, b.z_base),
        ] {
            assert!((x - y).abs() < tol(y), "{name}: {x} vs {y}");
        }
    }

    /// Mains flicker: every frame is the unflickered frame times the truth's light
    /// gain, at 100 Hz and 50 Hz with their amplitudes and phases.
    #[test]
    fn flicker_gain_is_in_the_truth_and_in_the_frames() {
        let m = test_motion(480.0, 0.05, 0.05);
        let mut spec = small_spec(Plate::Light, false);
        (spec.width, spec.height) = (96, 64);
        let steady = Renderer::new(&spec, &m).expect("steady");
        spec.effects.flicker_amplitude = 0.08;
        spec.effects.flicker_50hz_amplitude = 0.03;
        spec.effects.flicker_phase_100 = 1.3;
        spec.effects.flicker_phase_50 = -0.4;
        let flickering = Renderer::new(&spec, &m).expect("flicker");
        for f in &flickering.truth().frames {
            let t = f.index as f64 / 480.0;
            let tau = 2.0 * PI;
            let expected =
                1.0 + 0.08 * (tau * 100.0 * t + 1.3).sin() + 0.03 * (tau * 50.0 * t - 0.4).sin();
            assert!((f.light_gain - expected).abs() < 1e-12);
            let (a, b) = (
                steady.render_frame(f.file_index),
                flickering.render_frame(f.file_index),
            );
            // Each is rounded to a grey level (±0.5) from its unrounded value, the
            // flickering one from the gain times the steady one's: ±(0.5 + 0.5 g).
            let g = f.light_gain;
            for (p, q) in a.pixels().zip(b.pixels()) {
                let (p, q) = (f64::from(p[1]), f64::from(q[1]));
                assert!(
                    (q - g * p).abs() <= 0.5 + 0.5 * g + 1e-6,
                    "frame {}: {q} vs {g} × {p}",
                    f.index
                );
            }
        }
    }

    /// Read and shot noise: the variance of a flat patch of plate at level v is
    /// σ_read² + k² v, on a dark plate and a light one.
    #[test]
    fn shot_noise_grows_with_the_level() {
        let m = test_motion(480.0, 0.02, 0.0);
        for plate in [Plate::Dark, Plate::Light] {
            let mut spec = small_spec(plate, false);
            (spec.width, spec.height) = (160, 120);
            spec.scenery.reflectivity = Some(0.0);
            let clean = Renderer::new(&spec, &m).expect("clean").render_frame(0);
            spec.effects.noise_sigma = 1.5;
            spec.effects.shot_noise = 0.45;
            let noisy = Renderer::new(&spec, &m).expect("noisy").render_frame(0);
            // The plate's bottom rows, far from the disk and its shadow.
            let (mut sum, mut sum_sq, mut level, mut n) = (0.0, 0.0, 0.0, 0.0);
            for row in 112..120 {
                for x in 0..160 {
                    let d = f64::from(noisy.get_pixel(x, row)[1])
                        - f64::from(clean.get_pixel(x, row)[1]);
                    sum += d;
                    sum_sq += d * d;
                    level += f64::from(clean.get_pixel(x, row)[1]);
                    n += 1.0;
                }
            }
            let var = sum_sq / n - (sum / n).powi(2);
            // Rounding adds 1/12 (uniform ±0.5) to the variance.
            let expected = 1.5f64.powi(2) + 0.45f64.powi(2) * level / n + 1.0 / 12.0;
            // 1280 samples: the variance's relative standard error is √(2/1280) = 4 %.
            assert!(
                (var / expected - 1.0).abs() < 0.15,
                "{plate:?}: variance {var} vs {expected}"
            );
        }
    }

    /// Nutation: φ = φ_stat (1 + a sin(r |ψ| + χ₀)) before the halt, unchanged after
    /// it; ψ, θ and the energy keep their stationary-rolling values, and the truth's
    /// z_rim follows the true φ (its peaks, closed form at ψ = −π/2, at the true φ).
    #[test]
    fn nutation_modulates_phi_and_the_truth_follows() {
        let plain = test_motion(480.0, 0.3, 0.05);
        let mut nutating = plain.clone();
        let nutation = Nutation {
            amplitude: 0.05,
            ratio: 0.41,
            phase: 0.3,
        };
        add_nutation(&mut nutating, nutation).expect("nutation");
        for (a, b) in plain.states.iter().zip(&nutating.states) {
            let expected = a.phi * (1.0 + 0.05 * (0.41 * a.psi.abs() + 0.3).sin());
            if a.t < 0.0 {
                assert!((b.phi - expected).abs() < 1e-15, "t = {}", a.t);
            } else {
                assert_eq!(b.phi, a.phi);
            }
            assert_eq!((a.psi, a.theta, a.energy), (b.psi, b.theta, b.energy));
        }
        let r = Renderer::new(&small_spec(Plate::Dark, false), &nutating).expect("renderer");
        let truth = r.truth();
        assert_eq!(truth.nutation, Some(nutation));
        let params = Preset::EulerDisk.params();
        for f in &truth.frames {
            let pose = Pose::rolling(&params, -0.5 * PI, f.phi, f.theta, 0.0, 0.0);
            let peak = (truth.calibration.z_base - r.rim_edge_row(&pose).expect("z")) * truth.delta;
            let expected = peak_z_rim(&params, f.phi, truth.elevation);
            assert!((peak - expected).abs() < 1e-9, "t = {}", f.t);
        }
        assert!(
            add_nutation(
                &mut nutating.clone(),
                Nutation {
                    amplitude: 0.7,
                    ..nutation
                }
            )
            .is_err()
        );
    }

    /// The plate's grain: seeded (the same seed, the same texture; another seed,
    /// another), of the chosen RMS contrast where the pixel filter passes it, and
    /// smoothed away where a pixel spans many of its waves.
    #[test]
    fn plate_texture_is_seeded_with_its_contrast() {
        use scene::PlateTexture;
        let (a, b, c) = (
            PlateTexture::grain(7, 0.2),
            PlateTexture::grain(7, 0.2),
            PlateTexture::grain(8, 0.2),
        );
        assert_eq!(a, b);
        assert_ne!(a, c);
        let mut rng = SplitMix64::new(3);
        let (mut sq, mut n) = (0.0, 0.0);
        for _ in 0..20_000 {
            let q = [rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 0.0];
            let f = a.factor(q, (1e-6, 1e-6));
            sq += (f - 1.0) * (f - 1.0);
            n += 1.0;
        }
        let rms = (sq / n).sqrt();
        // 20 000 samples of a sum of 12 waves: the RMS to a few per cent.
        assert!((rms / 0.2 - 1.0).abs() < 0.1, "RMS contrast {rms}");
        // A 1 cm footprint: every wave (≤ 3 cm) is attenuated by ≥ exp(−2π²/9).
        let blurred = a.factor([0.1, 0.2, 0.0], (0.01, 0.01));
        assert!((blurred - 1.0).abs() < 0.2 * 12.0 * (-2.0 * PI * PI / 9.0).exp());
    }

    /// A textured plate is rendered alike inside and outside the rectangle redrawn
    /// for the disk: a frame differs from the rest frame only near the disk, its
    /// shadow and its mirror image.
    #[test]
    fn textured_plate_has_no_seams() {
        let m = test_motion(480.0, 0.3, 0.05);
        for (plate, d) in [(Plate::Light, Some(0.3)), (Plate::Dark, None)] {
            let mut spec = small_spec(plate, false);
            spec.height = 480;
            spec.camera_distance_m = d;
            spec.scenery.texture_contrast = 0.15;
            let r = Renderer::new(&spec, &m).expect("renderer");
            let moving = r.render_frame(20);
            let rest = r.render_frame(r.frame_count() - 1);
            // The rows below the plate line beyond the mirror image (as tall as the
            // disk) and the shadow (5 px here), with 10 px to spare.
            let cal = r.truth().calibration;
            let below = (cal.z_base + 2.0 * (cal.z_base - cal.z_t) + 10.0) as u32;
            assert!(below + 20 < spec.height);
            for row in below..spec.height {
                for x in 0..spec.width {
                    assert_eq!(
                        moving.get_pixel(x, row),
                        rest.get_pixel(x, row),
                        "{plate:?}: ({x}, {row})"
                    );
                }
            }
            // And the texture is there: the bottom row varies.
            let levels: std::collections::BTreeSet<u8> = (0..spec.width)
                .map(|x| rest.get_pixel(x, spec.height - 1)[1])
                .collect();
            assert!(levels.len() >= 3, "{plate:?}: {levels:?}");
        }
    }

    /// The reflection blur spreads the mirror image only: the disk's own pixels are
    /// unchanged, the mirror image's total light is kept, and its edge below the plate
    /// line is wider.
    #[test]
    fn reflection_blur_spreads_only_the_mirror_image() {
        let m = test_motion(480.0, 0.1, 0.05);
        let mut spec = small_spec(Plate::Dark, false);
        spec.scenery.reflectivity = Some(0.5);
        let sharp = Renderer::new(&spec, &m).expect("sharp");
        spec.scenery.reflection_blur_px = 3.0;
        let blurred = Renderer::new(&spec, &m).expect("blurred");
        let cal = sharp.truth().calibration;
        let (a, b) = (sharp.render_frame(10), blurred.render_frame(10));
        let x = cal.x_centre as u32;
        for row in (cal.z_t + 2.0) as u32..(cal.z_base - 8.0) as u32 {
            assert_eq!(a.get_pixel(x, row), b.get_pixel(x, row), "side, row {row}");
        }
        let total = |img: &RgbImage| {
            let mut s = 0.0;
            for row in (cal.z_base + 2.0) as u32..spec.height {
                for xx in 0..spec.width {
                    s += f64::from(img.get_pixel(xx, row)[1]);
                }
            }
            s
        };
        let (ta, tb) = (total(&a), total(&b));
        assert!((tb / ta - 1.0).abs() < 0.01, "{ta} vs {tb}");
        // Width of the mirror image's lower edge on the centre column: rows between
        // 20 % and 80 % of the step.
        let width = |img: &RgbImage| {
            let col: Vec<f64> = (cal.z_base as u32..spec.height)
                .map(|row| f64::from(img.get_pixel(x, row)[1]))
                .collect();
            let (hi, lo) = (col[6], col[col.len() - 1]);
            col.iter()
                .filter(|&&v| v < lo + 0.8 * (hi - lo) && v > lo + 0.2 * (hi - lo))
                .count()
        };
        assert!(width(&b) > width(&a) + 2, "{} vs {}", width(&b), width(&a));
    }

    /// Motion smear: a frame at rest is unchanged, a moving one is the mean of its
    /// exposure's poses (so it differs from the instantaneous frame), and no exposure
    /// gives the instantaneous frames.
    #[test]
    fn exposure_smear_averages_moving_frames_only() {
        let m = test_motion(480.0, 0.2, 0.1);
        let mut spec = small_spec(Plate::Dark, false);
        (spec.width, spec.height) = (160, 96);
        let sharp = Renderer::new(&spec, &m).expect("sharp");
        spec.effects.exposure_samples = 4;
        let none = Renderer::new(&spec, &m).expect("no exposure");
        assert_eq!(none.render_frame(50), sharp.render_frame(50));
        spec.effects.exposure_s = 1.0 / 960.0;
        let smeared = Renderer::new(&spec, &m).expect("smeared");
        let last = sharp.frame_count() - 1;
        assert_eq!(smeared.render_frame(last), sharp.render_frame(last));
        assert_ne!(smeared.render_frame(90), sharp.render_frame(90));
        assert_eq!(smeared.truth().frames, sharp.truth().frames);
    }

    /// Bad options are refused with their units.
    #[test]
    fn new_options_are_validated_with_units() {
        let m = test_motion(480.0, 0.05, 0.05);
        let check = |edit: &dyn Fn(&mut RenderSpec), unit: &str| {
            let mut spec = small_spec(Plate::Dark, false);
            edit(&mut spec);
            match Renderer::new(&spec, &m) {
                Err(RenderError::Invalid(msg)) => assert!(msg.contains(unit), "{msg}"),
                Ok(_) => panic!("accepted"),
                Err(e) => panic!("{e}"),
            }
        };
        check(&|s| s.camera_distance_m = Some(0.05), " m");
        check(&|s| s.scenery.reflectivity = Some(0.95), "[0, 0.9]");
        check(&|s| s.scenery.reflection_blur_px = -1.0, "px");
        check(&|s| s.edge_radius = 0.01, "rounding radius");
        check(&|s| s.scenery.plate_grey = Some(300.0), "255");
        check(&|s| s.effects.exposure_s = 0.01, " s");
        check(&|s| s.effects.flicker_50hz_amplitude = 1.2, "50 Hz");
        check(&|s| s.effects.shot_noise = f64::NAN, "grey levels");
        for (shake, unit) in [
            (
                Shake {
                    vibration_rms_px: -1.0,
                    ..Shake::default()
                },
                "vibration RMS [px]",
            ),
            (
                Shake {
                    sway_px: 80.0,
                    ..Shake::default()
                },
                "sway amplitude [px]",
            ),
            (
                Shake {
                    roll_deg: 20.0,
                    ..Shake::default()
                },
                "roll [deg]",
            ),
            (
                Shake {
                    vibration_band_hz: [80.0, 20.0],
                    ..Shake::default()
                },
                "Hz",
            ),
            (
                Shake {
                    sway_hz: 0.0,
                    ..Shake::default()
                },
                "sway frequency",
            ),
        ] {
            check(&|s| s.effects.shake = Some(shake), unit);
        }
    }

    /// A slowed section stretches the container's clock over the frame intervals
    /// that start inside it, and only there; a dropped frame leaves its interval
    /// in the timestamps. Overlapping or empty sections are refused.
    #[test]
    fn a_slowed_section_stretches_the_container_clock_over_its_span() {
        let m = test_motion(480.0, 0.1, 0.05);
        let mut spec = small_spec(Plate::Dark, false);
        spec.slowed_sections = vec![SlowedSection {
            start_s: 0.025,
            end_s: 0.05,
            factor: 16.0,
        }];
        spec.dropped = vec![60];
        let r = Renderer::new(&spec, &m).expect("renderer");
        let truth = r.truth();
        assert!(truth.stamped);
        let frame_s = 1.0 / 480.0;
        for w in truth.frames.windows(2) {
            let (a, b) = (&w[0], &w[1]);
            // Captures 12..24 start inside 0.025–0.05 s.
            let slowed = (12..24).contains(&a.index);
            let expected = (b.index - a.index) as f64 * frame_s * if slowed { 16.0 } else { 1.0 };
            let interval = b.container_time_s.unwrap() - a.container_time_s.unwrap();
            assert!((interval - expected).abs() < 1e-12, "capture {}", a.index);
        }
        assert!(
            Renderer::new(&small_spec(Plate::Dark, false), &m)
                .expect("plain")
                .truth()
                .frames
                .iter()
                .all(|f| f.container_time_s.is_none())
        );
        for (sections, why) in [
            (vec![(0.02, 0.01, 8.0)], "end after it starts"),
            (vec![(0.0, 0.03, 0.5)], "factor"),
            (vec![(0.0, 0.03, 8.0), (0.02, 0.04, 8.0)], "overlap"),
            (vec![(1.0, 2.0, 8.0)], "starts after the clip"),
        ] {
            spec.slowed_sections = sections
                .into_iter()
                .map(|(start_s, end_s, factor)| SlowedSection {
                    start_s,
                    end_s,
                    factor,
                })
                .collect();
            let err = Renderer::new(&spec, &m).err().expect("refused").to_string();
            assert!(err.contains(why), "{err}");
        }
    }

    /// The shift of the picture along a line of pixels, from the still frame's
    /// profile `f0` to the shaken frame's `fs`, given its whole part `n` (the truth's,
    /// rounded): n plus the area between fs(j + n) and f0(j) over [a, b] over the step
    /// between f0's levels at the window's ends. A box-filtered picture moved by r
    /// changes that area by exactly r × the step when the picture is flat at the
    /// window's ends; `None` where it is not (a slope of more than 4 grey levels a
    /// pixel there). The supersampling's 16 coverage levels leave ±1/32 px in each
    /// profile.
    fn measured_shift(
        f0: &dyn Fn(i64) -> f64,
        fs: &dyn Fn(i64) -> f64,
        a: i64,
        b: i64,
        n: i64,
    ) -> Option<f64> {
        let flat = |k: i64| (f0(k - 1) - f0(k)).abs() <= 4.0 && (f0(k + 1) - f0(k)).abs() <= 4.0;
        let step = f0(a) - f0(b);
        if !(flat(a) && flat(b) && step.abs() > 50.0) {
            return None;
        }
        let area: f64 = (a..=b).map(|j| fs(j + n) - f0(j)).sum();
        Some(n as f64 + area / step)
    }

    /// A shake of every kind but roll, up to about 5 px.
    fn test_shake() -> Shake {
        Shake {
            vibration_rms_px: 1.0,
            sway_px: 3.0,
            ..Shake::default()
        }
    }

    /// The still camera's image of the plate's far edge (the horizon) \[row\].
    fn horizon_row(r: &Renderer) -> f64 {
        r.cameras[0].project([0.0, r.scene.plate_back, 0.0]).1
    }

    /// Camera shake moves the picture by the truth's (dx, dy). On rest frames
    /// rendered with and without shake, the shift is measured across edges that are
    /// straight where they are crossed, with nothing else near (the strip is not): the
    /// horizon on columns beside the disk (light plate), the disk's bottom rim on the
    /// centre column and its ends on a row through its side (dark plate), and in a
    /// two-view frame the plan view's disk at the top, bottom, left and right of its
    /// circle (those the strip does not reach).
    /// The supersampling's 16 coverage levels leave up to 1/16 px in each measured
    /// shift (1/32 in each profile): each is within 0.07 px of the truth's, the
    /// mean of a frame's shifts along each axis within 0.05 px. The rest of the
    /// truth is the still camera's.
    #[test]
    fn shake_moves_the_picture_by_the_truth() {
        let m = test_motion(480.0, 0.02, 0.1);
        for (plate, two_view) in [
            (Plate::Light, false),
            (Plate::Dark, false),
            (Plate::Dark, true),
        ] {
            let mut spec = small_spec(plate, two_view);
            let still = Renderer::new(&spec, &m).expect("still");
            spec.effects.shake = Some(test_shake());
            let shaken = Renderer::new(&spec, &m).expect("shaken");
            let truth = shaken.truth();
            let unshaken: Vec<FrameTruth> = truth
                .frames
                .iter()
                .map(|f| FrameTruth {
                    camera_shake: None,
                    ..*f
                })
                .collect();
            assert_eq!(unshaken, still.truth().frames, "{plate:?}");
            assert_eq!(truth.calibration, still.truth().calibration);
            let side = still.cameras[0];
            assert_eq!(truth.camera_shake_centre_px, Some([side.cx, side.cy]));
            let cal = truth.calibration;
            let r_px = m.params.radius / truth.metres_per_px_image;
            // (what, along a column?, the line's fixed coordinate, the edge's position
            // on it in the still frame).
            let mut lines: Vec<(&str, bool, i64, f64)> = Vec::new();
            if plate == Plate::Light {
                // The horizon; the disk's edges here are shaded too steeply for this
                // measure (its shading is sampled, not averaged, over a pixel).
                let h = horizon_row(&still);
                lines.push(("horizon, left", true, 8, h));
                lines.push(("horizon, right", true, i64::from(spec.width) - 9, h));
            } else {
                let (x, y) = (
                    cal.x_centre.round() as i64,
                    (0.5 * (cal.z_base + cal.z_t)).round() as i64,
                );
                lines.push(("bottom rim", true, x, cal.z_base));
                lines.push(("left end", false, y, cal.x_l));
                lines.push(("right end", false, y, cal.x_r));
            }
            if two_view {
                let plan = still.cameras[1];
                let (x, y) = (plan.cx.round() as i64, plan.cy.round() as i64);
                lines.push(("plan top", true, x, plan.cy - r_px));
                lines.push(("plan bottom", true, x, plan.cy + r_px));
                lines.push(("plan left", false, y, plan.cx - r_px));
                lines.push(("plan right", false, y, plan.cx + r_px));
            }
            let n = shaken.frame_count();
            let mut largest = (0.0f64, 0.0f64);
            let mut seen: Vec<&str> = Vec::new();
            for k in n - 8..n {
                let (img0, img) = (still.render_frame(k), shaken.render_frame(k));
                let d = truth.frames[k].camera_shake.expect("shaken frame");
                assert_eq!(d.roll_deg, 0.0);
                largest = (largest.0.max(d.dx_px.abs()), largest.1.max(d.dy_px.abs()));
                // Each axis's errors, measured less true shift.
                let mut errors = (Vec::new(), Vec::new());
                for &(what, along_column, at, edge) in &lines {
                    let (shift, other) = if along_column {
                        (d.dy_px, d.dx_px)
                    } else {
                        (d.dx_px, d.dy_px)
                    };
                    // The shaken line: the still one moved by the other shift, rounded
                    // (the edges are straight across it).
                    let at_s = at + other.round() as i64;
                    let level = |img: &RgbImage, along: i64, across: i64| {
                        if along_column {
                            intensity(img, across as u32, along as u32)
                        } else {
                            intensity(img, along as u32, across as u32)
                        }
                    };
                    let f0 = |j: i64| level(&img0, j, at);
                    let fs = |j: i64| level(&img, j, at_s);
                    let c = edge.round() as i64;
                    let Some(got) = measured_shift(&f0, &fs, c - 10, c + 10, shift.round() as i64)
                    else {
                        continue;
                    };
                    assert!(
                        (got - shift).abs() < 0.07,
                        "{plate:?} two-view {two_view}, frame {k}, {what}: moved by {got:.4} \
                         px, the truth says {shift:.4}"
                    );
                    if !seen.contains(&what) {
                        seen.push(what);
                    }
                    if along_column {
                        errors.1.push(got - shift);
                    } else {
                        errors.0.push(got - shift);
                    }
                }
                // The light plate's frames are measured along y only.
                let axes = if plate == Plate::Light {
                    vec![("dy", &errors.1)]
                } else {
                    vec![("dx", &errors.0), ("dy", &errors.1)]
                };
                for (axis, e) in axes {
                    assert!(!e.is_empty(), "{plate:?}, frame {k}: no {axis} measured");
                    let mean = e.iter().sum::<f64>() / e.len() as f64;
                    assert!(
                        mean.abs() < 0.05,
                        "{plate:?} two-view {two_view}, frame {k}: {axis} off by {mean:+.4} \
                         px on average ({e:?})"
                    );
                }
            }
            // The frames were moved by whole and fractional pixels, both ways, and
            // the edges that must be flat at their windows' ends were.
            assert!(largest.0 > 1.5 && largest.1 > 1.5, "{largest:?}");
            let must: &[&str] = match plate {
                Plate::Light => &["horizon, left", "horizon, right"],
                Plate::Dark => &["bottom rim", "left end", "right end"],
            };
            for what in must {
                assert!(seen.contains(what), "{plate:?}: {what} never measured");
            }
            if two_view {
                assert!(
                    seen.iter().filter(|w| w.starts_with("plan")).count() >= 2,
                    "{seen:?}"
                );
            }
        }
    }

    /// A rolled picture turns about the truth's centre: the horizon (light plate)
    /// crosses the frame's outer columns where c + R(ρ)(p0 − c) puts it, within
    /// 0.05 px (ρ > 0 raises the right side).
    #[test]
    fn shake_roll_turns_the_picture_about_its_centre() {
        let m = test_motion(480.0, 0.02, 0.05);
        let mut spec = small_spec(Plate::Light, false);
        let still = Renderer::new(&spec, &m).expect("still");
        spec.effects.shake = Some(Shake {
            roll_deg: 1.0,
            ..Shake::default()
        });
        let rolled = Renderer::new(&spec, &m).expect("rolled");
        let truth = rolled.truth();
        let [cx, cy] = truth.camera_shake_centre_px.expect("centre");
        let h = horizon_row(&still);
        let n = rolled.frame_count();
        let w = i64::from(spec.width);
        for k in [n - 1, n - 9] {
            let (img0, img) = (still.render_frame(k), rolled.render_frame(k));
            let d = truth.frames[k].camera_shake.expect("shake");
            assert!(d.roll_deg.abs() > 0.5 && d.dx_px == 0.0 && d.dy_px == 0.0);
            let rho = d.roll_deg.to_radians();
            for x in [8, w - 9] {
                // The turned horizon: row(x) = cy + (h − cy)/cos ρ − (x − cx) tan ρ.
                let want = cy + (h - cy) / rho.cos() - (x as f64 - cx) * rho.tan() - h;
                let f0 = |j: i64| intensity(&img0, x as u32, j as u32);
                let fs = |j: i64| intensity(&img, x as u32, j as u32);
                let c = h.round() as i64;
                let got =
                    measured_shift(&f0, &fs, c - 10, c + 10, want.round() as i64).expect("flat");
                assert!(
                    (got - want).abs() < 0.05,
                    "frame {k}, column {x}: {got:.4} px vs {want:.4} (roll {:.3}°)",
                    d.roll_deg
                );
            }
        }
    }

    /// With an exposure, each of its poses is seen through the camera shaken at its
    /// own time: a rest frame's horizon moves by the mean of the exposure's shifts
    /// (a 120 Hz vibration over a quarter of its period), not the mid-exposure shift
    /// the truth records.
    #[test]
    fn shake_is_sampled_over_the_exposure() {
        let m = test_motion(480.0, 0.02, 0.05);
        let mut spec = small_spec(Plate::Light, false);
        let still = Renderer::new(&spec, &m).expect("still");
        spec.effects.exposure_s = 1.0 / 480.0;
        spec.effects.exposure_samples = 4;
        spec.effects.shake = Some(Shake {
            vibration_rms_px: 2.0,
            vibration_band_hz: [120.0, 120.0],
            ..Shake::default()
        });
        let smeared = Renderer::new(&spec, &m).expect("smeared");
        let motion = smeared.shake.as_ref().expect("shake");
        let h = horizon_row(&still);
        let n = smeared.frame_count();
        let mut apart = 0.0f64;
        for k in n - 6..n {
            let (img0, img) = (still.render_frame(k), smeared.render_frame(k));
            let f = &smeared.truth().frames[k];
            let t = f.t + m.timing.halt_time;
            let offsets = smeared.exposure_offsets();
            assert_eq!(offsets.len(), 4);
            let mean = offsets
                .iter()
                .map(|dt| motion.at(t + dt).dy_px)
                .sum::<f64>()
                / offsets.len() as f64;
            let mid = f.camera_shake.expect("shake").dy_px;
            assert_eq!(mid, motion.at(t).dy_px);
            apart = apart.max((mean - mid).abs());
            let f0 = |j: i64| intensity(&img0, 8, j as u32);
            let fs = |j: i64| intensity(&img, 8, j as u32);
            let c = h.round() as i64;
            let got = measured_shift(&f0, &fs, c - 10, c + 10, mean.round() as i64).expect("flat");
            assert!(
                (got - mean).abs() < 0.05,
                "frame {k}: {got:.4} px vs the exposure's mean {mean:.4} (mid {mid:.4})"
            );
        }
        // The test tells the exposure's mean from its middle.
        assert!(apart > 0.15, "{apart}");
    }

    /// Power of `x` (its mean removed, a Hann window) at the DFT's frequencies
    /// k·fps/N \[Hz\].
    fn spectrum(x: &[f64], fps: f64) -> Vec<(f64, f64)> {
        let n = x.len();
        let mean = x.iter().sum::<f64>() / n as f64;
        let xw: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, v)| (v - mean) * (PI * i as f64 / n as f64).sin().powi(2))
            .collect();
        (1..n / 2)
            .map(|k| {
                let (mut re, mut im) = (0.0, 0.0);
                for (i, v) in xw.iter().enumerate() {
                    let a = 2.0 * PI * (k * i) as f64 / n as f64;
                    re += v * a.cos();
                    im -= v * a.sin();
                }
                (k as f64 * fps / n as f64, re * re + im * im)
            })
            .collect()
    }

    /// The mean interval between the upward and downward zero crossings of `x`
    /// sampled every `dt` \[s\] (linear interpolation): half the period.
    fn half_period(x: &[f64], dt: f64) -> f64 {
        let crossings: Vec<f64> = x
            .windows(2)
            .enumerate()
            .filter(|(_, w)| (w[0] < 0.0) != (w[1] < 0.0))
            .map(|(i, w)| (i as f64 + w[0] / (w[0] - w[1])) * dt)
            .collect();
        assert!(crossings.len() >= 3, "{} crossings", crossings.len());
        (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64
    }

    /// The truth's shake series have what was asked for, over 1.5 s at 480 fps: the
    /// vibration's RMS on each axis within 10 % of the asked RMS and ≥ 97 % of its
    /// power within the band (±2 Hz, the window's spread), a band of one frequency
    /// one spectral peak there; the sway's and the roll's peaks within 1 % and their
    /// half-period 1/(2 f) within 1 %. The same seed draws the same shake, another
    /// seed another.
    #[test]
    fn shake_truth_has_the_asked_amplitudes_and_frequencies() {
        let fps = 480.0;
        let m = test_motion(fps, 1.0, 0.5);
        let series = |shake: Shake, seed: u64| {
            let mut spec = small_spec(Plate::Dark, false);
            (spec.width, spec.height) = (160, 96);
            spec.effects.shake = Some(shake);
            spec.effects.seed = seed;
            let r = Renderer::new(&spec, &m).expect("renderer");
            let s: Vec<ShakeOffset> = r
                .truth()
                .frames
                .iter()
                .map(|f| f.camera_shake.expect("shake"))
                .collect();
            s
        };
        let rms = |x: &[f64]| (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt();
        let vibration = Shake {
            vibration_rms_px: 1.5,
            vibration_band_hz: [20.0, 80.0],
            ..Shake::default()
        };
        let s = series(vibration, 7);
        assert!(s.iter().all(|o| o.roll_deg == 0.0));
        let dx: Vec<f64> = s.iter().map(|o| o.dx_px).collect();
        let dy: Vec<f64> = s.iter().map(|o| o.dy_px).collect();
        assert_ne!(dx, dy);
        for (axis, x) in [("dx", &dx), ("dy", &dy)] {
            let got = rms(x);
            assert!((got / 1.5 - 1.0).abs() < 0.1, "{axis}: RMS {got}");
            let power = spectrum(x, fps);
            let total: f64 = power.iter().map(|p| p.1).sum();
            let inside: f64 = power
                .iter()
                .filter(|p| (18.0..=82.0).contains(&p.0))
                .map(|p| p.1)
                .sum();
            assert!(inside / total > 0.97, "{axis}: {} in band", inside / total);
        }
        // One frequency: one peak, at 50 Hz.
        let tone = series(
            Shake {
                vibration_band_hz: [50.0, 50.0],
                ..vibration
            },
            7,
        );
        let dx: Vec<f64> = tone.iter().map(|o| o.dx_px).collect();
        assert!((rms(&dx) / 1.5 - 1.0).abs() < 0.1, "RMS {}", rms(&dx));
        let peak = spectrum(&dx, fps)
            .into_iter()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .expect("spectrum");
        assert!((peak.0 - 50.0).abs() < 1.0, "peak at {} Hz", peak.0);
        // Sway and roll.
        let sway = Shake {
            sway_px: 3.0,
            sway_hz: 2.0,
            roll_deg: 0.8,
            ..Shake::default()
        };
        let s = series(sway, 7);
        for (name, x, peak) in [
            ("dx", s.iter().map(|o| o.dx_px).collect::<Vec<_>>(), 3.0),
            ("dy", s.iter().map(|o| o.dy_px).collect(), 3.0),
            ("roll", s.iter().map(|o| o.roll_deg).collect(), 0.8),
        ] {
            let top = x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            assert!((top / peak - 1.0).abs() < 0.01, "{name}: peak {top}");
            let half = half_period(&x, 1.0 / fps);
            assert!(
                (half * 2.0 * 2.0 - 1.0).abs() < 0.01,
                "{name}: half-period {half} s"
            );
        }
        assert_eq!(series(sway, 7), s);
        assert_ne!(series(sway, 8), s);
    }

    /// A shake that does not move renders as no shake, byte for byte; its truth
    /// records zero shifts.
    #[test]
    fn a_still_shake_renders_as_no_shake() {
        let m = test_motion(480.0, 0.05, 0.02);
        let mut spec = small_spec(Plate::Dark, false);
        (spec.width, spec.height) = (160, 96);
        spec.scenery.reflection_blur_px = 1.0;
        let plain = Renderer::new(&spec, &m).expect("plain");
        assert!(
            plain
                .truth()
                .frames
                .iter()
                .all(|f| f.camera_shake.is_none())
        );
        assert_eq!(plain.truth().camera_shake_centre_px, None);
        spec.effects.shake = Some(Shake::default());
        let still = Renderer::new(&spec, &m).expect("still shake");
        for k in [0, 20, still.frame_count() - 1] {
            assert_eq!(still.render_frame(k), plain.render_frame(k), "frame {k}");
            let zero = ShakeOffset {
                dx_px: 0.0,
                dy_px: 0.0,
                roll_deg: 0.0,
            };
            assert_eq!(still.truth().frames[k].camera_shake, Some(zero));
        }
    }
}
