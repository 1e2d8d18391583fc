//! Scene geometry of the synthetic footage: the disk as a solid cylinder, the plate
//! (plain or with a seeded grain texture), two cameras (side view, orthographic or a
//! pinhole at a chosen distance; plan view, orthographic), lights, and the ray casting
//! that both the rasteriser and the ground truth use.
//!
//! World frame G (thesis fig. 3.1): the plate is z = 0, x points right in both views,
//! the side camera looks along +y (tilted down by the elevation ε), the plan camera
//! looks down −z with +y up in the image. The origin is the plate point under the
//! centre of mass G at the halt (the rest position).
//!
//! The disk's orientation is eq. (3.14): a point with body (F) coordinates `p` is at
//! `G + R_z(ψ) R_IB^T R_z(θ) p`, with `R_IB^T e3 = (−sin φ, 0, cos φ)`, so the symmetry
//! axis leans towards −e1^I = −(cos ψ, sin ψ, 0), where the contact point lies; the
//! centre of mass is at height Z_G = R sin φ + H cos φ (eq. 4.12).

use crate::model::params::DiskParams;

/// What a ray hit first; the class drives anti-aliasing (pixels whose corner rays
/// disagree are supersampled) and the ground truth's "white disk" predicate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Surface {
    /// The paper-wrapped curved surface.
    Side,
    /// The paper-wrapped top face (z_body = +H), outside the strip.
    Top,
    /// The red strip on the top face (eq. 3.13, across the diameter at angle β0).
    Strip,
    /// The untouched (metal) bottom face (z_body = −H).
    Bottom,
}

impl Surface {
    /// True for the paper-wrapped (white) surfaces whose lower edge is the rim that
    /// §3.2.4 thresholds for, and for the strip drawn on the white top face.
    pub fn is_white_disk(self) -> bool {
        matches!(self, Surface::Side | Surface::Top | Surface::Strip)
    }

    fn class(self) -> u8 {
        match self {
            Surface::Side => 1,
            Surface::Top => 2,
            Surface::Strip => 3,
            Surface::Bottom => 4,
        }
    }
}

/// The base plate's look (thesis §3.2.4, figs. 3.7 and 3.9).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum Plate {
    /// Dark, reflective metal (mild or stainless steel): the disk's mirror image
    /// appears below the plate line (fig. 3.7).
    Dark,
    /// Light, matt (Teflon, acrylic): only the shadow under the disk separates the
    /// white rim from the plate (fig. 3.9).
    Light,
}

/// A rigid placement of the disk: its centre of mass and body-to-world rotation.
#[derive(Clone, Copy, Debug)]
pub struct Pose {
    /// Centre of mass G in the world frame \[m\].
    pub centre: [f64; 3],
    /// Body (F) → world rotation, row-major: world = centre + m · body.
    pub m: [[f64; 3]; 3],
}

impl Pose {
    /// The pose of a disk rolling on the plate with Euler angles (ψ, φ, θ) of eq.
    /// (3.14) and its centre of mass above the horizontal point `(gx, gy)` \[m\].
    pub fn rolling(params: &DiskParams, psi: f64, phi: f64, theta: f64, gx: f64, gy: f64) -> Self {
        let (sp, cp) = psi.sin_cos();
        let (sf, cf) = phi.sin_cos();
        let (st, ct) = theta.sin_cos();
        let rz_psi = [[cp, -sp, 0.0], [sp, cp, 0.0], [0.0, 0.0, 1.0]];
        let r_ib_t = [[cf, 0.0, -sf], [0.0, 1.0, 0.0], [sf, 0.0, cf]];
        let rz_theta = [[ct, -st, 0.0], [st, ct, 0.0], [0.0, 0.0, 1.0]];
        let m = mat_mul(&mat_mul(&rz_psi, &r_ib_t), &rz_theta);
        let z_g = params.radius * sf + params.half_thickness * cf;
        Pose {
            centre: [gx, gy, z_g],
            m,
        }
    }

    fn body_from_world(&self, p: [f64; 3]) -> [f64; 3] {
        let d = sub(p, self.centre);
        // mᵀ d
        [
            self.m[0][0] * d[0] + self.m[1][0] * d[1] + self.m[2][0] * d[2],
            self.m[0][1] * d[0] + self.m[1][1] * d[1] + self.m[2][1] * d[2],
            self.m[0][2] * d[0] + self.m[1][2] * d[1] + self.m[2][2] * d[2],
        ]
    }

    fn dir_to_body(&self, d: [f64; 3]) -> [f64; 3] {
        [
            self.m[0][0] * d[0] + self.m[1][0] * d[1] + self.m[2][0] * d[2],
            self.m[0][1] * d[0] + self.m[1][1] * d[1] + self.m[2][1] * d[2],
            self.m[0][2] * d[0] + self.m[1][2] * d[1] + self.m[2][2] * d[2],
        ]
    }

    fn dir_to_world(&self, d: [f64; 3]) -> [f64; 3] {
        [
            self.m[0][0] * d[0] + self.m[0][1] * d[1] + self.m[0][2] * d[2],
            self.m[1][0] * d[0] + self.m[1][1] * d[1] + self.m[1][2] * d[2],
            self.m[2][0] * d[0] + self.m[2][1] * d[1] + self.m[2][2] * d[2],
        ]
    }

    /// World position of the body point `p`.
    pub fn world_from_body(&self, p: [f64; 3]) -> [f64; 3] {
        add(self.centre, self.dir_to_world(p))
    }
}

/// The disk's shape and the strip drawn on its top face.
#[derive(Clone, Copy, Debug)]
pub struct DiskShape {
    /// Radius R \[m\].
    pub radius: f64,
    /// Half-thickness H \[m\].
    pub half_thickness: f64,
    /// Strip angle β0 on the top face (eq. 3.13) \[rad\].
    pub beta0: f64,
    /// Half-width of the strip \[m\].
    pub strip_half_width: f64,
    /// Radius of the rounding of both rims \[m\]; 0: sharp. The rounding is drawn in
    /// the shading: over the last `edge_radius` of the side and of each face the
    /// normal turns as a quarter circle's of that radius does, seen along the face
    /// (sin α = depth into the band / radius), from the face's to the other face's (a
    /// real disk's rim, whose bottom 1–2.6 px may fade from the side's level). The
    /// outline stays the cylinder's: the true rim, where z_rim is measured, is the
    /// corner.
    pub edge_radius: f64,
}

/// A family of parallel rays (one orthographic view, the shadow rays or the mirrored
/// rays of one frame) with its direction precomputed in the disk's body frame.
#[derive(Clone, Copy, Debug)]
pub struct RayFamily {
    world: [f64; 3],
    body: [f64; 3],
    inv_dz: Option<f64>,
    a: f64,
    inv_a: Option<f64>,
}

impl RayFamily {
    /// The family of rays along the unit vector `dir` for the disk at `pose`.
    pub fn new(pose: &Pose, dir: [f64; 3]) -> Self {
        let body = pose.dir_to_body(dir);
        let a = body[0] * body[0] + body[1] * body[1];
        RayFamily {
            world: dir,
            body,
            inv_dz: (body[2].abs() >= 1e-300).then(|| 1.0 / body[2]),
            a,
            inv_a: (a >= 1e-300).then(|| 1.0 / a),
        }
    }
}

/// A ray's first entry into the disk.
#[derive(Clone, Copy, Debug)]
pub struct DiskHit {
    /// Ray parameter of the entry point.
    pub t: f64,
    /// Surface entered.
    pub surface: Surface,
    /// Outward normal at the entry point, world frame.
    pub normal: [f64; 3],
    /// Fraction of the ambient light (the room above) that reaches the point: 1,
    /// but on a rounded rim turned down, 1 + n_z (it sees the plate instead, and
    /// none of the room facing straight down).
    pub sky: f32,
}

impl DiskShape {
    /// First entry of the ray `origin + t dir` (t > 0) into the solid cylinder
    /// x² + y² ≤ R², |z| ≤ H of the body frame, or `None`.
    pub fn intersect(&self, pose: &Pose, origin: [f64; 3], dir: [f64; 3]) -> Option<DiskHit> {
        self.intersect_family(pose, &RayFamily::new(pose, dir), origin)
    }

    /// As [`DiskShape::intersect`] for a ray of a family of parallel rays.
    pub fn intersect_family(
        &self,
        pose: &Pose,
        family: &RayFamily,
        origin: [f64; 3],
    ) -> Option<DiskHit> {
        let (t_in, cap, p) = self.entry(pose, family, origin)?;
        let d = family.body;
        let (surface, normal_body) = if cap {
            if d[2] < 0.0 {
                let across = -self.beta0.sin() * p[0] + self.beta0.cos() * p[1];
                let surface = if across.abs() <= self.strip_half_width {
                    Surface::Strip
                } else {
                    Surface::Top
                };
                (surface, [0.0, 0.0, 1.0])
            } else {
                (Surface::Bottom, [0.0, 0.0, -1.0])
            }
        } else {
            let rho = (p[0] * p[0] + p[1] * p[1]).sqrt().max(1e-300);
            (Surface::Side, [p[0] / rho, p[1] / rho, 0.0])
        };
        let (normal_body, rounded) = self.rounded_normal(cap, p, normal_body);
        let normal = pose.dir_to_world(normal_body);
        Some(DiskHit {
            t: t_in,
            surface,
            normal,
            sky: if rounded {
                (1.0 + normal[2].min(0.0)) as f32
            } else {
                1.0
            },
        })
    }

    /// The normal at body-frame point `p` of a face (`cap`) or of the side, turned
    /// towards the other face within [`DiskShape::edge_radius`] of a rim, by α with
    /// sin α = the depth into that band over its width (90° at the corner), and
    /// whether it was turned.
    fn rounded_normal(&self, cap: bool, p: [f64; 3], face: [f64; 3]) -> ([f64; 3], bool) {
        let r = self.edge_radius;
        if r <= 0.0 {
            return (face, false);
        }
        let rho = (p[0] * p[0] + p[1] * p[1]).sqrt().max(1e-300);
        let radial = [p[0] / rho, p[1] / rho, 0.0];
        let axial = [0.0, 0.0, p[2].signum()];
        // The depth into the band, and the direction the normal turns towards.
        let (depth, towards) = if cap {
            (rho - (self.radius - r), radial)
        } else {
            (p[2].abs() - (self.half_thickness - r), axial)
        };
        if depth <= 0.0 {
            return (face, false);
        }
        let sin = (depth / r).min(1.0);
        let cos = (1.0 - sin * sin).sqrt();
        let turned = normalise([
            cos * face[0] + sin * towards[0],
            cos * face[1] + sin * towards[1],
            cos * face[2] + sin * towards[2],
        ]);
        (turned, true)
    }

    /// Whether a ray of the family meets the disk at all (shadow rays).
    pub fn blocks(&self, pose: &Pose, family: &RayFamily, origin: [f64; 3]) -> bool {
        self.entry(pose, family, origin).is_some()
    }

    /// Entry parameter, whether it is on a cap, and the body-frame entry point.
    fn entry(
        &self,
        pose: &Pose,
        family: &RayFamily,
        origin: [f64; 3],
    ) -> Option<(f64, bool, [f64; 3])> {
        // Bounding sphere first: most rays of a frame miss the disk.
        let oc = sub(origin, pose.centre);
        let b_sphere = dot(oc, family.world);
        if b_sphere * b_sphere - (dot(oc, oc) - self.bounding_radius_sq()) < 0.0 {
            return None;
        }
        let o = pose.body_from_world(origin);
        let d = family.body;
        let (r, h) = (self.radius, self.half_thickness);
        // Slab |z| ≤ H.
        let (slab_in, slab_out) = match family.inv_dz {
            None => {
                if o[2].abs() > h {
                    return None;
                }
                (f64::NEG_INFINITY, f64::INFINITY)
            }
            Some(inv) => {
                let t1 = (-h - o[2]) * inv;
                let t2 = (h - o[2]) * inv;
                (t1.min(t2), t1.max(t2))
            }
        };
        // Infinite cylinder x² + y² ≤ R².
        let c = o[0] * o[0] + o[1] * o[1] - r * r;
        let (cyl_in, cyl_out) = match family.inv_a {
            None => {
                if c > 0.0 {
                    return None;
                }
                (f64::NEG_INFINITY, f64::INFINITY)
            }
            Some(inv_a) => {
                let b = o[0] * d[0] + o[1] * d[1];
                let disc = b * b - family.a * c;
                if disc < 0.0 {
                    return None;
                }
                let sq = disc.sqrt();
                ((-b - sq) * inv_a, (-b + sq) * inv_a)
            }
        };
        let t_in = slab_in.max(cyl_in);
        let t_out = slab_out.min(cyl_out);
        if t_in > t_out || t_out <= 0.0 || t_in <= 0.0 {
            return None;
        }
        let p = [o[0] + t_in * d[0], o[1] + t_in * d[1], o[2] + t_in * d[2]];
        Some((t_in, slab_in >= cyl_in, p))
    }

    fn bounding_radius_sq(&self) -> f64 {
        self.radius * self.radius + self.half_thickness * self.half_thickness
    }

    /// Range of `u · p` over the points p of the disk at `pose` (`u` any vector):
    /// u·G ± (R √(|u|² − (a·u)²) + H |a·u|), with a the symmetry axis.
    pub fn extent(&self, pose: &Pose, u: [f64; 3]) -> (f64, f64) {
        let axis = [pose.m[0][2], pose.m[1][2], pose.m[2][2]];
        let au = dot(axis, u);
        let half =
            self.radius * (dot(u, u) - au * au).max(0.0).sqrt() + self.half_thickness * au.abs();
        let mid = dot(pose.centre, u);
        (mid - half, mid + half)
    }

    /// The eight corners of the body-frame bounding box, in the world.
    pub fn box_corners(&self, pose: &Pose) -> [[f64; 3]; 8] {
        let (r, h) = (self.radius, self.half_thickness);
        let mut out = [[0.0; 3]; 8];
        for (i, c) in out.iter_mut().enumerate() {
            let p = [
                if i & 1 == 0 { -r } else { r },
                if i & 2 == 0 { -r } else { r },
                if i & 4 == 0 { -h } else { h },
            ];
            *c = pose.world_from_body(p);
        }
        out
    }
}

/// The look of the scene: colours (0–255 per channel, linear) and lights.
#[derive(Clone, Copy, Debug)]
pub struct Look {
    /// Paper albedo × 255.
    pub paper: [f32; 3],
    /// Red strip albedo × 255.
    pub strip: [f32; 3],
    /// Untouched bottom face (metal seen in the dark) × 255.
    pub bottom: [f32; 3],
    /// Plate albedo × 255.
    pub plate: [f32; 3],
    /// Plate reflectivity (mirror fraction) in [0, 1).
    pub reflectivity: f32,
    /// Factor of the plate's brightness inside the disk's shadow.
    pub shadow_factor: f32,
    /// Background beyond the plate × 255.
    pub background: [f32; 3],
    /// Ambient part of the paper shading.
    pub ambient: f32,
    /// Direction towards the fill light that shades the paper (unit, world).
    pub fill_light: [f64; 3],
    /// Direction towards the key light that casts the disk's shadow (unit, world).
    pub key_light: [f64; 3],
    /// Grain of the plate's albedo, if any.
    pub texture: Option<PlateTexture>,
    /// Keep the plate's mirror image apart from the rest of a sample
    /// ([`Sample::mirror`]), so that it can be blurred on its own.
    pub separate_mirror: bool,
}

impl Look {
    /// The look of a plate type. The fill light comes from the camera side, 20°
    /// above the horizon, so the camera-facing side is brighter than the top face
    /// (the near top rim z_t is visible in the rest frame). The key light shines from
    /// behind the disk, 35° above the horizon, so its shadow falls towards the camera:
    /// the dark band that separates the white rim from a light plate (fig. 3.9).
    pub fn for_plate(plate: Plate) -> Self {
        let fill = normalise([0.0, -(20f64.to_radians().cos()), 20f64.to_radians().sin()]);
        let key = normalise([0.0, 35f64.to_radians().cos(), 35f64.to_radians().sin()]);
        let (plate_rgb, reflectivity) = match plate {
            Plate::Dark => ([24.0, 24.0, 27.0], 0.25),
            Plate::Light => ([205.0, 205.0, 200.0], 0.0),
        };
        Look {
            paper: [238.0, 238.0, 235.0],
            strip: [215.0, 28.0, 24.0],
            bottom: [40.0, 40.0, 42.0],
            plate: plate_rgb,
            reflectivity,
            shadow_factor: 0.28,
            background: [12.0, 12.0, 14.0],
            ambient: 0.55,
            fill_light: fill,
            key_light: key,
            texture: None,
            separate_mirror: false,
        }
    }

    /// The look of a plate type with the paper's and the plate's grey levels, the
    /// plate's reflectivity and grain, and the fill light's elevation overridden by
    /// `scenery` (each `None`/default keeps [`Look::for_plate`]'s value). Colours keep
    /// their tint: a grey level g scales the default colour so its red channel is g.
    pub fn with_scenery(plate: Plate, scenery: &super::Scenery, seed: u64) -> Self {
        let mut look = Look::for_plate(plate);
        let tinted = |rgb: [f32; 3], grey: f64| {
            let k = (grey / f64::from(rgb[0])) as f32;
            rgb.map(|c| c * k)
        };
        if scenery.paper_grey != super::Scenery::DEFAULT_PAPER_GREY {
            look.paper = tinted(look.paper, scenery.paper_grey);
        }
        if let Some(g) = scenery.plate_grey {
            look.plate = tinted(look.plate, g);
        }
        if let Some(rho) = scenery.reflectivity {
            look.reflectivity = rho as f32;
        }
        if scenery.fill_elevation_deg != super::Scenery::DEFAULT_FILL_ELEVATION_DEG {
            let e = scenery.fill_elevation_deg.to_radians();
            look.fill_light = normalise([0.0, -e.cos(), e.sin()]);
        }
        if scenery.texture_contrast > 0.0 {
            look.texture = Some(PlateTexture::grain(
                seed ^ TEXTURE_SEED,
                scenery.texture_contrast,
            ));
        }
        look.separate_mirror = scenery.reflection_blur_px > 0.0 && look.reflectivity > 0.0;
        look
    }

    /// Albedo × 255 of the lit plate at the plate point `q`, seen with a pixel
    /// footprint of `footprint` = (m/px along x, m/px along y) there.
    fn plate_at(&self, q: [f64; 3], footprint: (f64, f64)) -> [f32; 3] {
        match &self.texture {
            None => self.plate,
            Some(tex) => {
                let k = tex.factor(q, footprint) as f32;
                self.plate.map(|c| c * k)
            }
        }
    }

    fn disk_colour(&self, hit: &DiskHit) -> [f32; 3] {
        let base = match hit.surface {
            Surface::Side | Surface::Top => self.paper,
            Surface::Strip => self.strip,
            Surface::Bottom => return self.bottom,
        };
        let diffuse = dot(hit.normal, self.fill_light).max(0.0) as f32;
        let shade = self.ambient * hit.sky + (1.0 - self.ambient) * diffuse;
        [base[0] * shade, base[1] * shade, base[2] * shade]
    }
}

/// Seed offset of the plate texture (so it differs from the noise's stream).
const TEXTURE_SEED: u64 = 0x7E47_17E5_0F9A_7E11;

/// Waves in a [`PlateTexture`].
const TEXTURE_WAVES: usize = 12;

/// Shortest and longest wavelength of the texture's waves \[m\].
const TEXTURE_WAVELENGTHS: (f64, f64) = (1.5e-3, 30e-3);

/// Width σ of the pixel filter the texture is seen through \[px\]: waves are
/// attenuated by exp(−σ²ω²/2) at their image frequency ω [rad/px], so that the 2 × 2
/// blocks of the rasteriser (sampled every 2 px, Nyquist π/2 rad/px, attenuated to
/// 0.29 there and 0.007 at π) do not alias them.
const TEXTURE_FILTER_PX: f64 = 1.0;

/// A deterministic wood-grain-like albedo texture of the plate: a sum of plane waves
/// over the plate (8 of 12 with crests within ±9° of the image's x axis, as grain or
/// brushing seen from the side; 4 in any direction), wavelengths log-uniform in 1.5–30
/// mm with amplitudes ∝ √λ, scaled to unit RMS. The albedo is the plate's times
/// 1 + contrast · (sum), at least 0, each wave seen through a Gaussian pixel filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlateTexture {
    /// (k_x, k_y) [rad/m], phase \[rad\], amplitude.
    waves: [([f64; 2], f64, f64); TEXTURE_WAVES],
    /// RMS relative albedo variation (before the pixel filter).
    contrast: f64,
}

impl PlateTexture {
    /// The texture of `seed` with RMS relative albedo variation `contrast`.
    pub fn grain(seed: u64, contrast: f64) -> Self {
        let mut rng = crate::rng::SplitMix64::new(seed);
        let mut waves = [([0.0; 2], 0.0, 0.0); TEXTURE_WAVES];
        let (lo, hi) = TEXTURE_WAVELENGTHS;
        for (i, w) in waves.iter_mut().enumerate() {
            let lambda = rng.range(lo.ln(), hi.ln()).exp();
            let angle = if i < 8 {
                0.5 * std::f64::consts::PI + rng.range(-0.15, 0.15)
            } else {
                rng.range(0.0, std::f64::consts::PI)
            };
            let k = 2.0 * std::f64::consts::PI / lambda;
            let phase = rng.range(0.0, 2.0 * std::f64::consts::PI);
            *w = (
                [k * angle.cos(), k * angle.sin()],
                phase,
                (lambda / hi).sqrt(),
            );
        }
        // Unit RMS: a wave of amplitude a has mean square a²/2.
        let rms = (waves.iter().map(|w| w.2 * w.2).sum::<f64>() / 2.0).sqrt();
        for w in &mut waves {
            w.2 /= rms;
        }
        PlateTexture { waves, contrast }
    }

    /// Albedo factor at the plate point `q` with pixel footprint (m/px along x, along y).
    pub fn factor(&self, q: [f64; 3], footprint: (f64, f64)) -> f64 {
        let s2 = TEXTURE_FILTER_PX * TEXTURE_FILTER_PX;
        let sum: f64 = self
            .waves
            .iter()
            .map(|&([kx, ky], phase, amp)| {
                let (wx, wy) = (kx * footprint.0, ky * footprint.1);
                let atten = (-0.5 * s2 * (wx * wx + wy * wy)).exp();
                if atten < 1e-4 {
                    return 0.0;
                }
                amp * atten * (kx * q[0] + ky * q[1] + phase).sin()
            })
            .sum();
        (1.0 + self.contrast * sum).max(0.0)
    }
}

/// Which camera a region of the frame shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// Side view (front elevation, fig. 3.3), camera along +y tilted down by ε.
    Side,
    /// Plan view from above (fig. 3.19, bottom).
    Plan,
}

/// A camera mapping a rectangle of image rows to the world: orthographic, or (side
/// view only) a pinhole.
///
/// Image coordinates are pixel units with pixel centres at integers; rows grow
/// downward. Orthographic side view: image x = `cx + X/s`, row = `cy − v/s` with the
/// image-up coordinate v = y sin ε + z cos ε. Plan view: image x = `cx + X/s`, row =
/// `cy − Y/s`. Pinhole side view at C with focal length F \[px\], looking along
/// f = (0, cos ε, −sin ε) with up u = (0, sin ε, cos ε) and right (1, 0, 0): with
/// d = p − C, image x = `cx + F d_x/(d·f)`, row = `cy − F (d·u)/(d·f)`.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    /// Which view.
    pub view: View,
    /// Image column of the world origin.
    pub cx: f64,
    /// Image row of the world origin.
    pub cy: f64,
    /// Metres per pixel of the image plane (orthographic scale s).
    pub scale: f64,
    /// Elevation ε of the side camera \[rad\] (unused in plan view).
    pub elevation: f64,
    /// First image row of this view's region.
    pub row_start: u32,
    /// One past the last image row of this view's region.
    pub row_end: u32,
    /// A pinhole side camera; `None`: orthographic.
    pub pinhole: Option<Pinhole>,
}

/// Centre of projection and focal length of a pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pinhole {
    /// Centre of projection C \[m\].
    pub position: [f64; 3],
    /// Focal length F \[px\].
    pub focal_px: f64,
}

/// Distance from which rays start \[m\] (far outside the scene).
const RAY_START: f64 = 2.0;

impl Camera {
    /// The world ray (origin, unit direction) through the image point (x, row).
    pub fn ray(&self, x: f64, row: f64) -> ([f64; 3], [f64; 3]) {
        if let Some(p) = &self.pinhole {
            let (f, u) = self.side_frame();
            let (a, b) = ((x - self.cx) / p.focal_px, (self.cy - row) / p.focal_px);
            let dir = normalise([a, f[1] + b * u[1], f[2] + b * u[2]]);
            return (p.position, dir);
        }
        let wx = (x - self.cx) * self.scale;
        let up = (self.cy - row) * self.scale;
        match self.view {
            View::Side => {
                let (se, ce) = self.elevation.sin_cos();
                let dir = [0.0, ce, -se];
                let u = [0.0, se, ce];
                let origin = [
                    wx,
                    up * u[1] - RAY_START * dir[1],
                    up * u[2] - RAY_START * dir[2],
                ];
                (origin, dir)
            }
            View::Plan => ([wx, up, RAY_START], [0.0, 0.0, -1.0]),
        }
    }

    /// Image-plane functionals (x, up) of the view: image x = cx + (x·p)/s and
    /// row = cy − (up·p)/s.
    pub fn axes(&self) -> ([f64; 3], [f64; 3]) {
        match self.view {
            View::Side => {
                let (se, ce) = self.elevation.sin_cos();
                ([1.0, 0.0, 0.0], [0.0, se, ce])
            }
            View::Plan => ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        }
    }

    /// Forward and up unit vectors of the side view, f = (0, cos ε, −sin ε) and
    /// u = (0, sin ε, cos ε).
    pub fn side_frame(&self) -> ([f64; 3], [f64; 3]) {
        let (se, ce) = self.elevation.sin_cos();
        ([0.0, ce, -se], [0.0, se, ce])
    }

    /// Depth of a world point along a pinhole's optical axis, (p − C)·f \[m\].
    pub fn depth(&self, p: [f64; 3]) -> Option<f64> {
        self.pinhole
            .map(|ph| dot(sub(p, ph.position), self.side_frame().0))
    }

    /// Metres per pixel across a ray at distance `t` from a pinhole (on the optical
    /// axis; at the image's corners 1 % less), or the orthographic scale.
    pub fn footprint(&self, t: f64) -> f64 {
        match &self.pinhole {
            Some(p) => t / p.focal_px,
            None => self.scale,
        }
    }

    /// Image (x, row) of a world point.
    pub fn project(&self, p: [f64; 3]) -> (f64, f64) {
        if let Some(ph) = &self.pinhole {
            let (f, u) = self.side_frame();
            let d = sub(p, ph.position);
            let depth = dot(d, f);
            return (
                self.cx + ph.focal_px * d[0] / depth,
                self.cy - ph.focal_px * dot(d, u) / depth,
            );
        }
        match self.view {
            View::Side => {
                let (se, ce) = self.elevation.sin_cos();
                let v = p[1] * se + p[2] * ce;
                (self.cx + p[0] / self.scale, self.cy - v / self.scale)
            }
            View::Plan => (self.cx + p[0] / self.scale, self.cy - p[1] / self.scale),
        }
    }
}

/// Everything static about a clip's scene.
#[derive(Clone, Copy, Debug)]
pub struct Scene {
    /// Disk shape and strip.
    pub disk: DiskShape,
    /// Colours and lights.
    pub look: Look,
    /// How far the plate reaches behind the disk's rest position (+y) \[m\]; its far
    /// edge is the horizon of the side view (the 30 cm plate of §3.2.3: 0.15 m).
    pub plate_back: f64,
    /// How far the plate reaches in front (−y) and to either side (±x) \[m\]: far
    /// enough to fill the frame below the disk.
    pub plate_front: f64,
}

/// Classes at or above this are the plate (lit or shadowed, with its mirror image).
pub const PLATE_CLASSES: u8 = 8;

/// One ray's colour and class.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    /// Colour, 0–255 per channel (not yet quantised): everything but the mirror
    /// image when the look keeps that apart, else everything.
    pub rgb: [f32; 3],
    /// The plate's mirror image (reflectivity × what the mirrored ray sees), when
    /// [`Look::separate_mirror`]; zero otherwise.
    pub mirror: [f32; 3],
    /// 1 if the ray meets the plate and the look keeps the mirror image apart (the
    /// plate's coverage of a pixel, which bounds where its blurred mirror image is
    /// seen), else 0.
    pub plate: f32,
    /// Class of what the ray saw (surface and reflection/shadow), for anti-aliasing.
    pub class: u8,
}

/// A pixel's colour (0–2), the plate's mirror image kept apart (3–5) and the plate's
/// coverage (6); see [`Sample`].
pub type Channels = [f32; 7];

impl Sample {
    /// The sample as [`Channels`].
    pub fn channels(&self) -> Channels {
        let (c, m) = (self.rgb, self.mirror);
        [c[0], c[1], c[2], m[0], m[1], m[2], self.plate]
    }
}

impl Scene {
    /// First disk surface along the ray, if it is hit before the plate.
    pub fn first_disk_hit(&self, pose: &Pose, origin: [f64; 3], dir: [f64; 3]) -> Option<DiskHit> {
        self.disk.intersect(pose, origin, dir)
    }

    fn plate_hit(&self, origin: [f64; 3], dir: [f64; 3]) -> Option<([f64; 3], f64)> {
        if dir[2] < 0.0 && origin[2] > 0.0 {
            let t = -origin[2] / dir[2];
            let q = [origin[0] + t * dir[0], origin[1] + t * dir[1], 0.0];
            let on_plate = q[0].abs() <= self.plate_front
                && q[1] >= -self.plate_front
                && q[1] <= self.plate_back;
            return on_plate.then_some((q, t));
        }
        None
    }

    /// Colour and class of the ray (origin, unit dir) of camera `cam`, with the disk
    /// as `prep` has it (no disk: the static background).
    pub fn trace(&self, prep: &Prepared, cam: &Camera, origin: [f64; 3], dir: [f64; 3]) -> Sample {
        let look = &self.look;
        if let Some(pose) = &prep.pose {
            let hit = match &prep.view {
                Some(family) => self.disk.intersect_family(pose, family, origin),
                None => self.disk.intersect(pose, origin, dir),
            };
            if let Some(hit) = hit {
                // The disk lies on the plate (z ≥ 0) and the cameras look down, so a
                // disk hit always comes before the plate.
                return Sample {
                    rgb: look.disk_colour(&hit),
                    mirror: [0.0; 3],
                    plate: 0.0,
                    class: hit.surface.class(),
                };
            }
        }
        let Some((q, t)) = self.plate_hit(origin, dir) else {
            return Sample {
                rgb: look.background,
                mirror: [0.0; 3],
                plate: 0.0,
                class: 0,
            };
        };
        let m = cam.footprint(t);
        let albedo = look.plate_at(q, (m, m / dir[2].abs()));
        let lifted = [q[0], q[1], 1e-12];
        let shadowed = match (&prep.pose, &prep.shadow) {
            (Some(pose), Some(shadow)) => self.disk.blocks(pose, shadow, lifted),
            _ => false,
        };
        let light = if shadowed { look.shadow_factor } else { 1.0 };
        let mut rgb = albedo.map(|c| c * light);
        let mut mirror_rgb = [0.0; 3];
        let mut class = 8 + u8::from(shadowed);
        if look.reflectivity > 0.0 {
            let hit = prep.pose.as_ref().and_then(|pose| match &prep.mirror {
                Some(family) => self.disk.intersect_family(pose, family, lifted),
                None => self.disk.intersect(pose, lifted, [dir[0], dir[1], -dir[2]]),
            });
            let (mirror, mirror_class) = match hit {
                Some(hit) => (look.disk_colour(&hit), 2 * hit.surface.class()),
                None => (look.background, 0),
            };
            let rho = look.reflectivity;
            if look.separate_mirror {
                for ((c, mo), m) in rgb.iter_mut().zip(&mut mirror_rgb).zip(mirror) {
                    *c *= 1.0 - rho;
                    *mo = rho * m;
                }
            } else {
                for (c, m) in rgb.iter_mut().zip(mirror) {
                    *c = (1.0 - rho) * *c + rho * m;
                }
            }
            class += 16 * mirror_class;
        }
        Sample {
            rgb,
            mirror: mirror_rgb,
            plate: if look.separate_mirror { 1.0 } else { 0.0 },
            class,
        }
    }
}

/// The ray families of one view and frame: camera rays and camera rays mirrored in
/// the plate (orthographic views, whose rays are parallel; a pinhole's are cast one
/// by one), and shadow rays towards the key light. No pose: the empty scene.
#[derive(Clone, Copy, Debug)]
pub struct Prepared {
    pose: Option<Pose>,
    view: Option<RayFamily>,
    shadow: Option<RayFamily>,
    mirror: Option<RayFamily>,
}

impl Prepared {
    /// Families for the rays of `cam` with the disk at `pose`.
    pub fn new(scene: &Scene, pose: Option<&Pose>, cam: &Camera) -> Self {
        let parallel = cam.pinhole.is_none().then(|| cam.ray(0.0, 0.0).1);
        Prepared {
            pose: pose.copied(),
            view: pose.zip(parallel).map(|(p, d)| RayFamily::new(p, d)),
            shadow: pose.map(|p| RayFamily::new(p, scene.look.key_light)),
            mirror: pose
                .zip(parallel)
                .map(|(p, d)| RayFamily::new(p, [d[0], d[1], -d[2]])),
        }
    }
}

fn mat_mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    out
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalise(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    [a[0] / n, a[1] / n, a[2] / n]
}
