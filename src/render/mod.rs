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
//! shadow under the disk gives the contrast (fig. 3.9). The side camera is orthographic,
//! looks along +y and is tilted down by a small elevation ε (default 3°). In the
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
//! # Camera artefacts
//!
//! Sensor noise (Gaussian, σ grey levels, a SplitMix64 generator seeded per frame and
//! row, so frames are reproducible in any order), Gaussian blur (σ px), 50 Hz mains
//! flicker (intensity × (1 + A sin(2π·100 Hz·t))), lateral drift (px/s, ending at the
//! rest position at the halt) and dropped frames (missing from the output; the truth
//! keeps every written frame's capture index and true time). Pixels are anti-aliased:
//! rays are cast at the corners of 2 × 2 pixel blocks, then at the pixel corners of
//! blocks whose corners see different surfaces, then 16 rays (a rank-1 lattice, so
//! axis-aligned edges get 16 coverage levels; 8 where only the plate's shadow or
//! mirror image changes) in pixels whose corners disagree. A feature thinner than
//! 2 px that no block corner sees (the strip seen edge-on in the side view) can be
//! missed. Rays are cast only inside the exact image extent of the disk, its mirror
//! image and its shadow; the rest of the frame is a background rendered once.

pub mod motion;
pub mod scene;
pub mod write;

use crate::rng::SplitMix64;
use std::path::PathBuf;

use image::RgbImage;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::model::params::DiskParams;
pub use motion::{
    DiskState, Motion, MotionSource, PostFlatSpin, PowerLaw, Timing, power_law_motion,
    trajectory_motion,
};
pub use scene::Plate;
use scene::{Camera, DiskShape, Look, PLATE_CLASSES, Pose, Prepared, Sample, Scene, View};
pub use write::{ClipFormat, DEFAULT_CRF, truth_path, write_clip};

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
}

impl RenderError {
    fn invalid(reason: impl Into<String>) -> Self {
        RenderError::Invalid(reason.into())
    }
}

/// Camera artefacts applied after rendering.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Effects {
    /// Sensor noise σ [grey levels], Gaussian, per channel.
    pub noise_sigma: f64,
    /// Gaussian blur σ [px].
    pub blur_sigma: f64,
    /// Mains flicker amplitude A: intensity × (1 + A sin(2π·100 Hz·t_clip)).
    pub flicker_amplitude: f64,
    /// Lateral drift of the disk [px/s] before the halt (it arrives at rest there).
    pub drift_px_per_s: f64,
    /// Seed of the noise generator.
    pub seed: u64,
}

impl Default for Effects {
    fn default() -> Self {
        Effects {
            noise_sigma: 0.0,
            blur_sigma: 0.0,
            flicker_amplitude: 0.0,
            drift_px_per_s: 0.0,
            seed: 1,
        }
    }
}

/// Everything about the picture (not the motion).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RenderSpec {
    /// Frame width [px].
    pub width: u32,
    /// Frame height [px].
    pub height: u32,
    /// Plate type.
    pub plate: Plate,
    /// Side view above, plan view with the strip below (fig. 3.19).
    pub two_view: bool,
    /// Camera elevation ε of the side view [deg], in (0, 30].
    pub elevation_deg: f64,
    /// Image scale [m/px]; `None` fits the disk's diameter into 90 % of the width
    /// (and of the plan view's height).
    pub metres_per_px: Option<f64>,
    /// Width of the red strip [m].
    pub strip_width: f64,
    /// Camera artefacts.
    pub effects: Effects,
    /// Capture indices (0-based) of frames missing from the output.
    pub dropped: Vec<usize>,
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
            strip_width: 0.005,
            effects: Effects::default(),
            dropped: Vec::new(),
        }
    }
}

/// Calibration points of the rest frame (thesis fig. 3.3, ERRATA): image coordinates
/// in px, pixel centres at integers, rows growing downward.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Left edge of the bottom of the disk [px].
    pub x_l: f64,
    /// Right edge of the bottom of the disk [px].
    pub x_r: f64,
    /// Centre column (x_l + x_r)/2 [px].
    pub x_centre: f64,
    /// Near top rim on the centre column [row].
    pub z_t: f64,
    /// Plate line: the bottom rim on the centre column [row].
    pub z_base: f64,
}

/// Ground truth of one written frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrameTruth {
    /// Capture index (0-based; dropped frames keep their numbers).
    pub index: usize,
    /// Position in the written clip (0-based; `frame_{file_index + 1:06}.png`).
    pub file_index: usize,
    /// Time relative to the halt [s] (t = 0 at the halt).
    pub t: f64,
    /// Nutation φ [rad].
    pub phi: f64,
    /// Precession ψ [rad] (z_rim peaks at ψ ≡ −π/2 mod 2π).
    pub psi: f64,
    /// Spin θ [rad].
    pub theta: f64,
    /// Strip angle β seen from above (eq. 3.20), unwrapped, counter-clockwise from
    /// the image's +x axis with image up = +y [rad].
    pub beta: f64,
    /// ψ̇ [rad/s].
    pub psi_dot: f64,
    /// θ̇ [rad/s].
    pub theta_dot: f64,
    /// β̇ [rad/s].
    pub beta_dot: f64,
    /// Energy above the flat rest state [J].
    pub energy: f64,
    /// Bottom edge of the white disk on the centre column above the plate line,
    /// z_base − row [px]; `None` if the disk is not on the column.
    pub z_rim_px: Option<f64>,
    /// z_rim_px · δ [m].
    pub z_rim_m: Option<f64>,
    /// Horizontal offset of the disk's centre from its rest column (drift) [px].
    pub drift_px: f64,
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
    /// Frame width [px].
    pub width: u32,
    /// Frame height [px].
    pub height: u32,
    /// Capture rate [frames/s].
    pub fps: f64,
    /// Captured frames, including dropped ones.
    pub captured_frames: usize,
    /// Clip time of the halt [s] (first captured frame at 0).
    pub halt_time: f64,
    /// Stop of the strip after the halt, t_β [s] (eq. 4.113).
    pub t_beta: f64,
    /// β̇ just after the halt [rad/s].
    pub post_flat_beta_dot: f64,
    /// True energy exponent n (prescribed, or the model's analytic one).
    pub true_n: Option<f64>,
    /// Prescribed A_e [J s^-n].
    pub a_e: Option<f64>,
    /// Disk parameters.
    pub disk: DiskParams,
    /// Strip angle on the top face β0 [rad] (eq. 3.13).
    pub beta0: f64,
    /// Side camera elevation ε [rad].
    pub elevation: f64,
    /// Orthographic image scale s [m/px].
    pub metres_per_px_image: f64,
    /// δ = 2H/(z_base − z_t) [m/px] (eq. 3.10 corrected) = s / cos ε.
    pub delta: f64,
    /// Rest-frame calibration points.
    pub calibration: Calibration,
    /// Camera artefacts.
    pub effects: Effects,
    /// Capture indices missing from the output.
    pub dropped: Vec<usize>,
    /// One entry per written frame, in output order.
    pub frames: Vec<FrameTruth>,
}

/// z_rim at a peak (ψ ≡ −π/2, contact point straight behind) as the thesis converts
/// it, 2R sin φ + (R(1 − cos φ) − H sin φ) tan ε [m] (see the module docs).
pub fn peak_z_rim(params: &DiskParams, phi: f64, elevation: f64) -> f64 {
    let (r, h) = (params.radius, params.half_thickness);
    2.0 * r * phi.sin() + (r * (1.0 - phi.cos()) - h * phi.sin()) * elevation.tan()
}

/// Largest frame rendered [px] (3840 × 2160, 4K UHD): a frame and its background
/// are held in memory as floats, 16 frames at a time.
pub const MAX_FRAME_PIXELS: u64 = 3840 * 2160;

/// Renders the frames of one clip on demand and holds its ground truth.
pub struct Renderer {
    spec: RenderSpec,
    motion: Motion,
    scene: Scene,
    cameras: Vec<Camera>,
    background: Vec<[f32; 3]>,
    truth: GroundTruth,
    /// Capture index of each written frame.
    written: Vec<usize>,
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
        let (w, hgt) = (spec.width, spec.height);
        let elevation = spec.elevation_deg.to_radians();
        let split = spec
            .two_view
            .then(|| (0.35 * f64::from(hgt)).round() as u32);
        let side_rows = split.unwrap_or(hgt);
        let scale = match spec.metres_per_px {
            Some(s) => s,
            None => {
                let by_width = 2.0 * r / (0.9 * f64::from(w));
                match split {
                    Some(sp) => by_width.max(2.0 * r / (0.9 * f64::from(hgt - sp))),
                    None => by_width,
                }
            }
        };
        let cx = f64::from(w / 2);
        let side = Camera {
            view: View::Side,
            cx,
            cy: 0.55 * f64::from(side_rows),
            scale,
            elevation,
            row_start: 0,
            row_end: side_rows,
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
            });
        }
        let scene = Scene {
            disk: DiskShape {
                radius: r,
                half_thickness: h,
                beta0: motion.beta0,
                strip_half_width: 0.5 * spec.strip_width,
            },
            look: Look::for_plate(spec.plate),
            plate_back: 0.15,
            plate_front: 1.0,
        };
        let calibration = Calibration {
            x_l: cx - r / scale,
            x_r: cx + r / scale,
            x_centre: cx,
            z_t: side.cy - (2.0 * h * elevation.cos() - r * elevation.sin()) / scale,
            z_base: side.cy + r * elevation.sin() / scale,
        };
        let delta = 2.0 * h / (calibration.z_base - calibration.z_t);
        let written: Vec<usize> = (0..motion.states.len())
            .filter(|k| !spec.dropped.contains(k))
            .collect();
        let mut renderer = Renderer {
            spec: spec.clone(),
            motion: motion.clone(),
            scene,
            cameras,
            background: Vec::new(),
            truth: GroundTruth {
                format_version: 1,
                source: motion.source,
                plate: spec.plate,
                two_view: spec.two_view,
                split_row: split,
                width: w,
                height: hgt,
                fps: motion.timing.fps,
                captured_frames: motion.states.len(),
                halt_time: motion.timing.halt_time,
                t_beta: motion.t_beta(),
                post_flat_beta_dot: motion.post_flat.beta_dot0,
                true_n: motion.true_n,
                a_e: motion.a_e,
                disk: params,
                beta0: motion.beta0,
                elevation,
                metres_per_px_image: scale,
                delta,
                calibration,
                effects: spec.effects,
                dropped: {
                    let mut d = spec.dropped.clone();
                    d.sort_unstable();
                    d.dedup();
                    d
                },
                frames: Vec::new(),
            },
            written,
        };
        renderer.background = renderer.render_background();
        let frames = renderer
            .written
            .par_iter()
            .enumerate()
            .map(|(file_index, &index)| renderer.frame_truth(file_index, index))
            .collect();
        renderer.truth.frames = frames;
        Ok(renderer)
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
        let drift = self.drift_px(s.t) * self.truth.metres_per_px_image;
        Pose::rolling(
            &self.motion.params,
            s.psi,
            s.phi,
            s.theta,
            s.centre[0] + drift,
            s.centre[1],
        )
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
        }
    }

    /// Row of the lowest point on the centre column whose ray first meets a white
    /// surface of the disk (ray casting; see the module docs).
    fn rim_edge_row(&self, pose: &Pose) -> Option<f64> {
        let cam = &self.cameras[0];
        let x = self.truth.calibration.x_centre;
        let white = |row: f64| {
            let (o, d) = cam.ray(x, row);
            self.scene
                .first_disk_hit(pose, o, d)
                .is_some_and(|hit| hit.surface.is_white_disk())
        };
        let corners = self.scene.disk.box_corners(pose);
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
                let mut above = row;
                for _ in 0..60 {
                    let mid = 0.5 * (above + below);
                    if white(mid) {
                        above = mid;
                    } else {
                        below = mid;
                    }
                }
                return Some(0.5 * (above + below));
            }
            below = row;
        }
        None
    }

    fn render_background(&self) -> Vec<[f32; 3]> {
        let (w, h) = (self.spec.width as usize, self.spec.height as usize);
        let mut buf = vec![[0.0f32; 3]; w * h];
        for cam in &self.cameras {
            let rect = Rect {
                x0: 0,
                x1: w,
                y0: cam.row_start as usize,
                y1: cam.row_end as usize,
            };
            self.render_rect(&mut buf, cam, None, rect);
        }
        buf
    }

    /// Renders written frame `file_index` (0-based position in the output).
    ///
    /// # Panics
    /// If `file_index >= self.frame_count()`.
    pub fn render_frame(&self, file_index: usize) -> RgbImage {
        let index = self.written[file_index];
        let pose = self.pose(index);
        let (w, h) = (self.spec.width as usize, self.spec.height as usize);
        let mut buf = self.background.clone();
        for cam in &self.cameras {
            if let Some(rect) = self.disk_rect(cam, &pose) {
                self.render_rect(&mut buf, cam, Some(&pose), rect);
            }
        }
        let fx = &self.spec.effects;
        if fx.blur_sigma > 0.0 {
            gaussian_blur(&mut buf, w, h, fx.blur_sigma);
        }
        let t_clip = index as f64 / self.motion.timing.fps;
        let gain = 1.0 + fx.flicker_amplitude * (2.0 * std::f64::consts::PI * 100.0 * t_clip).sin();
        let mut out = vec![0u8; w * h * 3];
        out.par_chunks_mut(3 * w)
            .zip(buf.par_chunks(w))
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
                        if fx.noise_sigma > 0.0 {
                            v += fx.noise_sigma * rng.gaussian();
                        }
                        *d = v.round().clamp(0.0, 255.0) as u8;
                    }
                }
            });
        // The buffer has exactly width × height × 3 bytes.
        RgbImage::from_raw(self.spec.width, self.spec.height, out)
            .unwrap_or_else(|| RgbImage::new(self.spec.width, self.spec.height))
    }

    /// Pixel rectangle of a view that the disk, its mirror image and its shadow can
    /// touch, with a 2 px margin (exact extents of the cylinder along the image axes).
    fn disk_rect(&self, cam: &Camera, pose: &Pose) -> Option<Rect> {
        let disk = &self.scene.disk;
        let key = self.scene.look.key_light;
        let (ax, up) = cam.axes();
        // The mirror image (z → −z) seen along `up` is the disk seen along `up` with
        // its z component negated; the shadow is p ↦ p − (p_z / L_z) L on the plate.
        let mirror_up = [up[0], up[1], -up[2]];
        let shadow = |u: [f64; 3]| [u[0], u[1], -(u[0] * key[0] + u[1] * key[1]) / key[2]];
        let xs = [disk.extent(pose, ax), disk.extent(pose, shadow(ax))];
        let mut ups = vec![disk.extent(pose, up), disk.extent(pose, shadow(up))];
        if self.scene.look.reflectivity > 0.0 && cam.view == View::Side {
            ups.push(disk.extent(pose, mirror_up));
        }
        let x0 = xs.iter().map(|e| e.0).fold(f64::INFINITY, f64::min);
        let x1 = xs.iter().map(|e| e.1).fold(f64::NEG_INFINITY, f64::max);
        let u0 = ups.iter().map(|e| e.0).fold(f64::INFINITY, f64::min);
        let u1 = ups.iter().map(|e| e.1).fold(f64::NEG_INFINITY, f64::max);
        let (s, w) = (cam.scale, f64::from(self.spec.width));
        let (r0, r1) = (f64::from(cam.row_start), f64::from(cam.row_end));
        let rect = Rect {
            x0: (cam.cx + x0 / s - 2.0).floor().clamp(0.0, w) as usize,
            x1: (cam.cx + x1 / s + 3.0).ceil().clamp(0.0, w) as usize,
            y0: (cam.cy - u1 / s - 2.0).floor().clamp(r0, r1) as usize,
            y1: (cam.cy - u0 / s + 3.0).ceil().clamp(r0, r1) as usize,
        };
        (rect.x0 < rect.x1 && rect.y0 < rect.y1).then_some(rect)
    }

    /// Renders the pixels of `rect` into `buf`. Rays are cast at the corners of 2 × 2
    /// pixel blocks; a block whose four corner rays see the same class is filled by
    /// bilinear interpolation, otherwise its pixel corners are cast, and a pixel whose
    /// corners disagree gets 16 rays.
    fn render_rect(&self, buf: &mut [[f32; 3]], cam: &Camera, pose: Option<&Pose>, rect: Rect) {
        let w = self.spec.width as usize;
        let (_, dir) = cam.ray(0.0, 0.0);
        let prepared = pose.map(|p| Prepared::new(&self.scene, p, dir));
        let trace = |x: f64, y: f64| -> Sample {
            let (o, d) = cam.ray(x, y);
            match &prepared {
                Some(prep) => self.scene.trace_prepared(prep, o),
                None => self.scene.trace_empty(o, d),
            }
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
                        for dy in 0..rows_here {
                            for dx in 0..cols_here {
                                // Pixel centres at 1/4 and 3/4 of the block.
                                let (fx, fy) = (0.25 + 0.5 * dx as f32, 0.25 + 0.5 * dy as f32);
                                let mut c = [0.0f32; 3];
                                for (k, ck) in c.iter_mut().enumerate() {
                                    let top = quad[0].rgb[k] * (1.0 - fx) + quad[1].rgb[k] * fx;
                                    let bot = quad[2].rgb[k] * (1.0 - fx) + quad[3].rgb[k] * fx;
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
                                    average(q.iter().map(|s| s.rgb), 4)
                                } else {
                                    let n = if q.iter().all(|s| s.class >= PLATE_CLASSES) {
                                        SUPERSAMPLES_PLATE
                                    } else {
                                        SUPERSAMPLES
                                    };
                                    average(
                                        (0..n).map(|k| {
                                            let (ox, oy) = supersample_offset(k, n);
                                            trace(x + ox, y + oy).rgb
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

#[derive(Clone, Copy, Debug)]
struct Rect {
    x0: usize,
    x1: usize,
    y0: usize,
    y1: usize,
}

fn average(colours: impl Iterator<Item = [f32; 3]>, n: usize) -> [f32; 3] {
    let mut sum = [0.0f32; 3];
    for c in colours {
        for (s, v) in sum.iter_mut().zip(c) {
            *s += v;
        }
    }
    sum.map(|s| s / n as f32)
}

fn validate(spec: &RenderSpec, motion: &Motion) -> Result<(), RenderError> {
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
    if !(spec.strip_width.is_finite()
        && spec.strip_width > 0.0
        && spec.strip_width < motion.params.radius)
    {
        return fail(format!(
            "the strip width must lie in (0, R), got {} m",
            spec.strip_width
        ));
    }
    let fx = &spec.effects;
    for (name, v) in [
        ("noise σ", fx.noise_sigma),
        ("blur σ", fx.blur_sigma),
        ("flicker amplitude", fx.flicker_amplitude),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return fail(format!("{name} must be finite and non-negative, got {v}"));
        }
    }
    if fx.flicker_amplitude >= 1.0 {
        return fail(format!(
            "the flicker amplitude must be below 1, got {}",
            fx.flicker_amplitude
        ));
    }
    if !fx.drift_px_per_s.is_finite() {
        return fail("the drift must be finite".into());
    }
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

/// Separable Gaussian blur with clamped borders.
fn gaussian_blur(buf: &mut [[f32; 3]], w: usize, h: usize, sigma: f64) {
    let radius = (3.0 * sigma).ceil() as isize;
    let kernel: Vec<f32> = (-radius..=radius)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp() as f32)
        .collect();
    let norm: f32 = kernel.iter().sum();
    let kernel: Vec<f32> = kernel.iter().map(|k| k / norm).collect();
    let convolve = |get: &dyn Fn(isize) -> [f32; 3]| -> [f32; 3] {
        let mut acc = [0.0f32; 3];
        for (j, k) in kernel.iter().enumerate() {
            let c = get(j as isize - radius);
            for (a, v) in acc.iter_mut().zip(c) {
                *a += k * v;
            }
        }
        acc
    };
    let mut tmp = vec![[0.0f32; 3]; w * h];
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::params::Preset;
    use std::f64::consts::PI;

    fn motion(fps: f64, halt: f64, after: f64) -> Motion {
        let timing = Timing {
            fps,
            halt_time: halt,
            after_halt: after,
        };
        let spin = PostFlatSpin {
            beta_dot0: -2.8,
            mu: 0.134,
        };
        power_law_motion(
            &Preset::EulerDisk.params(),
            &PowerLaw::thesis(0.5),
            &timing,
            spin,
        )
        .expect("motion")
    }

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
            let r = Renderer::new(&spec, &motion(480.0, 0.05, 0.0)).expect("renderer");
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

    /// The rendered bottom edge on the centre column, found by a sub-pixel threshold
    /// crossing, matches the truth z_rim: dark plate (first rising edge from the
    /// bottom) and light plate (second edge, fig. 3.9).
    #[test]
    fn rendered_bottom_edge_matches_truth_z_rim() {
        let m = motion(480.0, 0.4, 0.05);
        for plate in [Plate::Dark, Plate::Light] {
            let r = Renderer::new(&small_spec(plate, false), &m).expect("renderer");
            let truth = r.truth();
            let x = truth.calibration.x_centre as u32;
            let mut checked = 0;
            for f in truth.frames.iter().step_by(7) {
                let img = r.render_frame(f.file_index);
                let i = |row: u32| intensity(&img, x, row);
                let start = (truth.calibration.z_base + 30.0) as u32;
                let end = (truth.calibration.z_t - 20.0) as u32;
                // Dark plate: the first edge from the bottom; light plate: the second,
                // after the shadow (§3.2.4).
                let edges = crossings(&i, start, end, 130.0);
                let (row, rising) = match plate {
                    Plate::Dark => edges[0],
                    Plate::Light => edges[1],
                };
                assert!(rising, "{plate:?}, frame {}: {edges:?}", f.index);
                let col = |k: i64| intensity(&img, x, k as u32);
                let measured = truth.calibration.z_base - edge_1d(&col, i64::from(row));
                let expected = f.z_rim_px.expect("disk on the column");
                // Box-filtered edge read by linear interpolation: < 0.1 px; the
                // shading on either side of the edge varies by up to 0.15 px more.
                assert!(
                    (measured - expected).abs() < 0.3,
                    "{plate:?}, frame {}: measured {measured}, truth {expected}",
                    f.index
                );
                checked += 1;
            }
            assert!(checked > 25);
        }
    }

    /// The rest frame's calibration points x_l, x_r, z_t, z_base (fig. 3.3) measured
    /// by threshold crossings match the truth, and δ = 2H/(z_base − z_t) = s/cos ε.
    #[test]
    fn rest_frame_calibration_points_match_truth() {
        let m = motion(480.0, 0.02, 0.1);
        for plate in [Plate::Dark, Plate::Light] {
            let r = Renderer::new(&small_spec(plate, false), &m).expect("renderer");
            let truth = r.truth();
            let cal = truth.calibration;
            let img = r.render_frame(r.frame_count() - 1);
            let x = cal.x_centre as u32;
            let col = |row: i64| intensity(&img, x, row as u32);
            // Plate line: the first (dark plate) or second (light plate) edge going up
            // the centre column from well below the disk, as for z_rim.
            let edges = crossings(
                &|r| col(i64::from(r)),
                (cal.z_base + 30.0) as u32,
                cal.z_t as u32,
                130.0,
            );
            let base_row = match plate {
                Plate::Dark => edges[0].0,
                Plate::Light => edges[1].0,
            };
            let z_base = edge_1d(&col, i64::from(base_row));
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
        let m = motion(480.0, 0.2, 0.06);
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
        let m = motion(60.0, 0.2, 0.1);
        let mut spec = small_spec(Plate::Dark, false);
        (spec.width, spec.height) = (96, 64);
        spec.dropped = vec![7, 3];
        let r = Renderer::new(&spec, &m).expect("renderer");
        assert_eq!(m.states.len(), 19);
        let dir = tempfile::tempdir().expect("tempdir");
        let folder = dir.path().join("clip");
        let written = write_clip(&r, &folder, DEFAULT_CRF).expect("write");
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
        write_clip(&r, &mp4, DEFAULT_CRF).expect("mp4");
        assert_eq!(crate::footage::probe(&mp4).expect("probe").frame_count, 17);
    }

    /// The same renderer and crf give the same MP4 bytes, also for the later of
    /// several encodes in one process (x264's macroblock tree, on by default, read
    /// uninitialised heap memory and changed them; see `write::write_mp4`), and a
    /// lower crf decodes closer to the rendered frames.
    #[test]
    fn mp4_bytes_repeat_and_crf_sets_the_quality() {
        let m = motion(240.0, 0.4, 0.1);
        let mut spec = small_spec(Plate::Dark, false);
        (spec.width, spec.height) = (160, 96);
        spec.effects.noise_sigma = 1.0;
        let r = Renderer::new(&spec, &m).expect("renderer");
        let dir = tempfile::tempdir().expect("tempdir");
        let encode = |name: &str, crf: u8| {
            let path = dir.path().join(name);
            write_clip(&r, &path, crf).expect("mp4");
            path
        };
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
}
