//! Experiment configuration: what a user writes in `experiment.toml`.
//!
//! Every field is optional; what is missing is found automatically (threshold,
//! calibration, split row) or defaulted (the Euler's-disk preset, a dark plate, a
//! 0.5 s fit window). Unknown keys are errors, so a typo (`fsp = 480`) is reported
//! with its line and column instead of silently ignored; so is a value outside its
//! physical range, with the unit.
//!
//! Configs are layered: a study folder's `eulerdisk.toml` applies to every clip
//! below it, a deeper folder's file overrides it key by key, and a clip's own
//! `CLIP.toml` (beside `CLIP.mp4`) comes last. [`ExperimentConfig::load_layered`]
//! merges the TOML tables in that order before checking them.
//!
//! ```toml
//! fps = 480                      # capture frame rate [1/s]
//! plate = "dark"                 # dark (reflective) | light (shadow contrast)
//! two_view = false               # mirror side view above, plan view below
//! material = "stainless steel"   # base plate; Table 3.1 names give μ and the trends
//!
//! [disk]
//! preset = "euler-disk"          # euler-disk | brass-disk | food-can
//! radius_m = 0.0381              # optional overrides of the preset
//! half_thickness_m = 0.00635
//!
//! [vision]
//! gamma = 0.45                   # threshold on mean RGB intensity, 0–1; default Otsu
//! band_half_width_px = 3         # columns each side of the centre line
//! split_row = 640                # two-view: first row of the plan view [px]
//! roi = [0, 0, 720, 1280]        # x, y, width, height [px]
//!
//! [calibration]                  # rest-frame points [px]; default: found automatically
//! x_l = 112.0
//! x_r = 608.0
//! z_t = 700.0
//! z_base = 742.0
//!
//! [fit]
//! window_s = 0.5                 # fit the last 0.5 s before the halt
//! halt = "combined"              # combined (t0 fitted, with the halt seen) | free (fitted only) | measured (fixed at the halt)
//! rim_zero = "motion"            # z_rim's zero: motion (placed by the turns) | rest (the still disk's edge)
//! rim_zero_uncertainty_px = 0.08 # 1σ of z_rim's zero, in n's interval (0: left out;
//!                                # default: the motion's, else measured for how the rim is read)
//! ```

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::model::params::{DiskParams, Preset};

/// The name of a folder-level config file, inherited by every clip below it.
pub const FOLDER_CONFIG: &str = "eulerdisk.toml";

/// A config that could not be read or does not make sense, naming the file.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    #[error("{}: {reason}", path.display())]
    Unreadable { path: PathBuf, reason: String },
    #[error("{}: {reason}", path.display())]
    Invalid { path: PathBuf, reason: String },
}

/// Base plate appearance in the side view (thesis §3.2.4, figs. 3.7 and 3.9).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Plate {
    /// Dark, reflective: the white disk above its mirror image.
    #[default]
    Dark,
    /// Light: a dark shadow under the disk gives the contrast.
    Light,
}

/// How the halt time t0 of the power law is treated in the fit, and so where t_φ lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum HaltChoice {
    /// t0 fixed at the measured halt t_φ = 0, the last frame with visible motion (the
    /// thesis's choice), which comes early by the time the last sub-threshold rocking
    /// takes, and that biases n low.
    Measured,
    /// t0 a free parameter of the fit, from the energy samples alone. With this and
    /// the default, t_φ is placed by the laws of the motion (`analyse::law_halt`).
    Free,
    /// t0 fitted, and combined with the halt seen in the footage as a second
    /// measurement of it (the default; [`crate::energy::HaltSighting`]).
    #[default]
    Combined,
}

/// Where the zero of z_rim comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RimZeroChoice {
    /// Placed by the motion: the rim's profile fitted with an offset over the turns
    /// of the fit window (the default; [`crate::signal::motion_zero`]).
    #[default]
    Motion,
    /// The still disk's edge after the halt (the thesis's choice).
    Rest,
}

/// The disk: a preset, optionally with measured values overriding it.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiskConfig {
    pub preset: Option<Preset>,
    pub mass_kg: Option<f64>,
    pub radius_m: Option<f64>,
    pub half_thickness_m: Option<f64>,
    /// Moment of inertia about a diameter [kg m²].
    pub inertia_a_kg_m2: Option<f64>,
    /// Moment of inertia about the symmetry axis [kg m²].
    pub inertia_c_kg_m2: Option<f64>,
}

/// Image-stage settings.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VisionConfig {
    /// Threshold γ on the mean RGB intensity as a fraction of white, 0–1 (thesis §3.2.4).
    pub gamma: Option<f64>,
    /// Columns each side of the centre line searched for the rim edge \[px\].
    #[serde(default, deserialize_with = "band_half_width_px")]
    pub band_half_width_px: Option<u32>,
    /// Two-view clips: the first row of the plan view \[px\].
    #[serde(default, deserialize_with = "split_row")]
    pub split_row: Option<u32>,
    /// Region of interest `[x, y, width, height]` \[px\].
    #[serde(default, deserialize_with = "roi")]
    pub roi: Option<[u32; 4]>,
}

/// A count of pixels for `key`: any TOML integer is read, and one that is negative
/// or beyond 32 bits is refused naming the key, the value, the unit and the range
/// (rather than serde's bare "expected u32").
fn pixels<E: serde::de::Error>(key: &str, value: i64) -> Result<u32, E> {
    u32::try_from(value).map_err(|_| {
        E::custom(format!(
            "`{key}` = {value} must be a whole number of pixels from 0 to {} [px]",
            u32::MAX
        ))
    })
}

fn band_half_width_px<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<u32>, D::Error> {
    Option::<i64>::deserialize(d)?
        .map(|v| pixels("vision.band_half_width_px", v))
        .transpose()
}

fn split_row<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<u32>, D::Error> {
    Option::<i64>::deserialize(d)?
        .map(|v| pixels("vision.split_row", v))
        .transpose()
}

fn roi<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<[u32; 4]>, D::Error> {
    let Some(values) = Option::<[i64; 4]>::deserialize(d)? else {
        return Ok(None);
    };
    let mut roi = [0; 4];
    for (px, value) in roi.iter_mut().zip(values) {
        *px = pixels("vision.roi", value)?;
    }
    Ok(Some(roi))
}

/// Rest-frame calibration points \[px\] (thesis §3.2.4, eq. 3.10 with ERRATA).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationConfig {
    pub x_l: f64,
    pub x_r: f64,
    pub z_t: f64,
    pub z_base: f64,
}

/// Power-law fit settings (thesis §3.2.5).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitConfig {
    /// Length of the fit window before the halt \[s\].
    pub window_s: Option<f64>,
    pub halt: Option<HaltChoice>,
    /// Where the zero of z_rim comes from (default: the motion).
    pub rim_zero: Option<RimZeroChoice>,
    /// 1σ uncertainty of the zero of z_rim \[px\], carried into the interval of n
    /// (default: the motion's ([`RimReading::motion_zero_uncertainty_px`]), else the
    /// one measured for how the rim was read
    /// ([`RimReading::zero_uncertainty_px`](crate::vision::RimReading::zero_uncertainty_px));
    /// 0 leaves it out).
    ///
    /// [`RimReading::motion_zero_uncertainty_px`]: crate::vision::RimReading::motion_zero_uncertainty_px
    pub rim_zero_uncertainty_px: Option<f64>,
}

/// One experiment's configuration, as written (before automatic choices).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExperimentConfig {
    /// Capture frame rate [1/s].
    pub fps: Option<f64>,
    pub plate: Option<Plate>,
    pub two_view: Option<bool>,
    /// Base-plate material (a thesis Table 3.1 name) for studies and `compare`.
    pub material: Option<String>,
    /// Disk name for studies with several disks.
    pub disk_name: Option<String>,
    /// Plate orientation or any other grouping label of the study.
    pub orientation: Option<String>,
    pub disk: Option<DiskConfig>,
    /// The camera's distance from the disk's near rim, measured along the plate \[m\]:
    /// overrides the distance the perspective factor gives (`analyse::ScaleReport`),
    /// from which the camera's elevation at the near rim and the local scale there
    /// follow.
    pub camera_distance_m: Option<f64>,
    pub vision: Option<VisionConfig>,
    pub calibration: Option<CalibrationConfig>,
    pub fit: Option<FitConfig>,
}

/// Default fit window before the halt \[s\] (the thesis's last 0.5 s).
pub const DEFAULT_WINDOW_S: f64 = 0.5;

impl ExperimentConfig {
    /// Parse one TOML text; `path` names it in errors.
    ///
    /// # Errors
    /// `Invalid` with TOML's line and column for syntax errors, unknown keys and
    /// values out of range.
    pub fn parse(text: &str, path: &Path) -> Result<Self, ConfigError> {
        Self::load_texts(&[(path.to_path_buf(), text.to_string())])
    }

    /// Read and merge config files in order (later files override earlier ones key
    /// by key, tables merged recursively); missing files are skipped.
    ///
    /// # Errors
    /// The first file that cannot be read or parsed; a value out of range, named
    /// by the file, line and column where it is set.
    pub fn load_layered(files: &[PathBuf]) -> Result<Self, ConfigError> {
        let mut texts = Vec::new();
        for file in files.iter().filter(|f| f.is_file()) {
            let text = std::fs::read_to_string(file).map_err(|e| ConfigError::Unreadable {
                path: file.clone(),
                reason: e.to_string(),
            })?;
            texts.push((file.clone(), text));
        }
        Self::load_texts(&texts)
    }

    /// Parse, check and merge layers given as (file, text), outermost first.
    fn load_texts(layers: &[(PathBuf, String)]) -> Result<Self, ConfigError> {
        let mut merged = toml::Table::new();
        for (file, text) in layers {
            // Deserialised from the text itself, so TOML's errors carry the line
            // and column, and a typo is blamed on its own file.
            let alone: Self = toml::from_str(text).map_err(|e| invalid(file, e))?;
            alone
                .validate()
                .map_err(|(key, reason)| out_of_range(layers, &key, &reason))?;
            let table: toml::Table = toml::from_str(text).map_err(|e| invalid(file, e))?;
            merge(&mut merged, table);
        }
        let last = layers
            .last()
            .map_or_else(|| PathBuf::from("(defaults)"), |(f, _)| f.clone());
        let config: Self = toml::Value::Table(merged)
            .try_into()
            .map_err(|e| invalid(&last, e))?;
        config
            .validate()
            .map_err(|(key, reason)| out_of_range(layers, &key, &reason))?;
        Ok(config)
    }

    /// The config files that apply to `clip` below the study `root`, outermost
    /// first: every `eulerdisk.toml` from `root` down to the clip's folder, then
    /// the clip's own `CLIP.toml`. For a single clip (`root` = its folder) that is
    /// the folder's `eulerdisk.toml` and the clip's own file.
    pub fn layers_for(root: &Path, clip: &Path) -> Vec<PathBuf> {
        let mut folders: Vec<&Path> = clip
            .ancestors()
            .skip(1)
            .take_while(|dir| dir.starts_with(root))
            .collect();
        folders.reverse();
        let mut files: Vec<PathBuf> = folders.iter().map(|d| d.join(FOLDER_CONFIG)).collect();
        files.push(clip.with_extension("toml"));
        files
    }

    /// Every value against its physical range; an error is (the key, the reason
    /// with the unit).
    fn validate(&self) -> Result<(), (String, String)> {
        if let Some(fps) = self.fps
            && !(MIN_FPS..=MAX_FPS).contains(&fps)
        {
            return Err((
                "fps".to_string(),
                format!("`fps` = {fps} frames/s must lie within {MIN_FPS}–{MAX_FPS} frames/s"),
            ));
        }
        positive("camera_distance_m", self.camera_distance_m, "m")?;
        if let Some(disk) = &self.disk {
            validate_disk(disk)?;
        }
        let vision = self.vision.clone().unwrap_or_default();
        validate_vision(&vision)?;
        if let Some(c) = &self.calibration {
            validate_calibration(c, &vision)?;
        }
        match &self.fit {
            Some(fit) => validate_fit(fit),
            None => Ok(()),
        }
    }

    /// The disk parameters: the preset (Euler's disk by default) with any measured
    /// values put in.
    pub fn disk_params(&self) -> DiskParams {
        let disk = self.disk.clone().unwrap_or_default();
        let mut params = disk.preset.unwrap_or(Preset::EulerDisk).params();
        let set = |field: &mut f64, value: Option<f64>| {
            if let Some(v) = value {
                *field = v;
            }
        };
        set(&mut params.mass, disk.mass_kg);
        set(&mut params.radius, disk.radius_m);
        set(&mut params.half_thickness, disk.half_thickness_m);
        set(&mut params.inertia_a, disk.inertia_a_kg_m2);
        set(&mut params.inertia_c, disk.inertia_c_kg_m2);
        params
    }

    /// The fit window before the halt \[s\].
    pub fn window_s(&self) -> f64 {
        self.fit
            .as_ref()
            .and_then(|f| f.window_s)
            .unwrap_or(DEFAULT_WINDOW_S)
    }

    /// The 1σ uncertainty of the zero of z_rim \[px\] carried into n's interval, when
    /// the config sets it; `None`: the one measured for how the rim was read
    /// ([`RimReading::zero_uncertainty_px`](crate::vision::RimReading::zero_uncertainty_px)).
    pub fn rim_zero_uncertainty_px(&self) -> Option<f64> {
        self.fit.as_ref().and_then(|f| f.rim_zero_uncertainty_px)
    }

    /// Where the zero of z_rim comes from ([`FitConfig::rim_zero`]).
    pub fn rim_zero(&self) -> RimZeroChoice {
        self.fit
            .as_ref()
            .and_then(|f| f.rim_zero)
            .unwrap_or_default()
    }
}

/// An error of [`ExperimentConfig::validate`]: the key and the reason with the unit.
type Invalid = (String, String);

/// `value`, if given, must be a positive number in `unit`.
fn positive(key: &str, value: Option<f64>, unit: &str) -> Result<(), Invalid> {
    match value {
        Some(v) if !(v.is_finite() && v > 0.0) => Err((
            key.to_string(),
            format!("`{key}` = {v} must be a positive number [{unit}]"),
        )),
        _ => Ok(()),
    }
}

/// `value`, if given, must lie above 0 and at most `max` in `unit`.
fn up_to(key: &str, value: Option<f64>, max: f64, unit: &str) -> Result<(), Invalid> {
    match value {
        Some(v) if !(v > 0.0 && v <= max) => Err((
            key.to_string(),
            format!("`{key}` = {v} must lie above 0 and at most {max} [{unit}]"),
        )),
        _ => Ok(()),
    }
}

/// The disk's mass, size and moments of inertia within [`DISK_LIMITS`].
fn validate_disk(disk: &DiskConfig) -> Result<(), Invalid> {
    let (mass, length, inertia) = DISK_LIMITS;
    up_to("disk.mass_kg", disk.mass_kg, mass, "kg")?;
    up_to("disk.radius_m", disk.radius_m, length, "m")?;
    up_to("disk.half_thickness_m", disk.half_thickness_m, length, "m")?;
    up_to(
        "disk.inertia_a_kg_m2",
        disk.inertia_a_kg_m2,
        inertia,
        "kg m²",
    )?;
    up_to(
        "disk.inertia_c_kg_m2",
        disk.inertia_c_kg_m2,
        inertia,
        "kg m²",
    )?;
    Ok(())
}

/// The vision keys: a band of at least one column either side, γ within (0, 1), and
/// a region of interest of some width and height that fits in pixel coordinates and
/// holds the band.
fn validate_vision(vision: &VisionConfig) -> Result<(), Invalid> {
    let fail = |key: &str, reason: String| Err((key.to_string(), reason));
    if vision.band_half_width_px == Some(0) {
        return fail(
            "vision.band_half_width_px",
            "`vision.band_half_width_px` = 0 px: the band needs at least 1 column either \
             side of the centre line (leave the key out for the default, 2 % of the \
             disk's width)"
                .into(),
        );
    }
    if let Some(gamma) = vision.gamma
        && !(gamma > 0.0 && gamma < 1.0)
    {
        return fail(
            "vision.gamma",
            format!(
                "`vision.gamma` = {gamma} must lie strictly between 0 and 1 \
                 (a fraction of full white, as MATLAB's im2bw level)"
            ),
        );
    }
    if let Some([x, y, w, h]) = vision.roi {
        let fits = |start: u32, len: u32| len > 0 && start.checked_add(len).is_some();
        if !(fits(x, w) && fits(y, h)) {
            return fail(
                "vision.roi",
                format!(
                    "`vision.roi` = [{x}, {y}, {w}, {h}] px ([x, y, width, height]) needs a \
                     width and height above 0 and x + width, y + height below {} px",
                    u32::MAX
                ),
            );
        }
        if let Some(band) = vision.band_half_width_px
            && 2 * u64::from(band) + 1 > u64::from(w)
        {
            return fail(
                "vision.band_half_width_px",
                format!(
                    "`vision.band_half_width_px` = {band} px: the band (2 × {band} + 1 \
                     columns) is wider than the region of interest ({w} px)"
                ),
            );
        }
    }
    Ok(())
}

/// A calibration given in the config: the right edge right of the left, the base
/// below the top, and the band within the disk.
fn validate_calibration(c: &CalibrationConfig, vision: &VisionConfig) -> Result<(), Invalid> {
    let fail = |key: &str, reason: String| Err((key.to_string(), reason));
    if c.x_r.partial_cmp(&c.x_l) != Some(std::cmp::Ordering::Greater) {
        return fail(
            "calibration.x_r",
            format!(
                "calibration: x_r = {} px must lie right of x_l = {} px",
                c.x_r, c.x_l
            ),
        );
    }
    if c.z_base.partial_cmp(&c.z_t) != Some(std::cmp::Ordering::Greater) {
        return fail(
            "calibration.z_base",
            format!(
                "calibration: z_base = {} px must lie below z_t = {} px \
                 (image rows grow downward)",
                c.z_base, c.z_t
            ),
        );
    }
    // analyse checks the same against a calibration it finds.
    if let Some(band) = vision.band_half_width_px {
        band_fits_disk(band, c.x_r - c.x_l)
            .or_else(|reason| fail("vision.band_half_width_px", reason))?;
    }
    Ok(())
}

/// The fit window within [`MAX_WINDOW_S`] and the zero's uncertainty a number ≥ 0.
fn validate_fit(fit: &FitConfig) -> Result<(), Invalid> {
    let fail = |key: &str, reason: String| Err((key.to_string(), reason));
    up_to("fit.window_s", fit.window_s, MAX_WINDOW_S, "s")?;
    if let Some(u) = fit.rim_zero_uncertainty_px
        && !(u.is_finite() && u >= 0.0)
    {
        return fail(
            "fit.rim_zero_uncertainty_px",
            format!("`fit.rim_zero_uncertainty_px` = {u} must be a number ≥ 0 [px]"),
        );
    }
    Ok(())
}

/// The band's half-width when the config names none: [`BAND_FRACTION`] of the disk's
/// width at rest, `x_r − x_l` \[px\], and at least `default_px` (the side view's own
/// default).
///
/// Why a fixed fraction of the width. Across the band the rim's edge slopes: the
/// bottom rim point at column offset x = R sin δ from the centre line stands at
/// z = R sin φ (1 + cos(χ + δ)), so dz/dx = −sin φ sin(χ + δ)/cos δ: at most sin φ
/// per column near the centre line (cos δ ≥ 0.999 across a band of 2 % of the width).
/// A band of ±w columns therefore holds edges within ±w sin φ of the centre line's,
/// which is ±w/(x_r − x_l) of the peak height 2R sin φ whatever the resolution and
/// the tilt. An edge read linearly in the profile (the area of the step) of the band's
/// mean profile is the mean of the columns' edges, which is the centre line's to the
/// rim's curvature, (w/R)²/6 of the peak (0.03 % at 2 %); the noise of the mean falls
/// as 1/√(2w + 1) (on 720 × 1280 side views, 5 → 35–45 columns).
/// The other edge readers (a level's crossing, the mirror-edge model's fit) are
/// linear only for small spreads, which the 2 % keeps small: ±0.4 px at a 20 px peak.
pub fn band_for_disk(disk_width_px: f64, default_px: usize) -> usize {
    ((BAND_FRACTION * disk_width_px).floor() as usize).max(default_px)
}

/// Half-width of the default band as a fraction of the disk's width (see
/// [`band_for_disk`]): the edges across it lie within ±2 % of the peak height.
pub const BAND_FRACTION: f64 = 0.02;

/// Checks the rim band against the disk's width at rest, `x_r − x_l` \[px\]. The rim
/// height is read on the centre line; a band wider than a tenth of the radius either
/// side reads it where the rim is lower by more than 0.5 % (√(1 − 0.1²) = 0.995).
///
/// # Errors
/// The reason, naming the key, both widths and the unit.
pub fn band_fits_disk(band_half_width_px: u32, disk_width_px: f64) -> Result<(), String> {
    let widest = (0.05 * disk_width_px).max(1.0).floor();
    if f64::from(band_half_width_px) > widest {
        return Err(format!(
            "`vision.band_half_width_px` = {band_half_width_px} px is more than a tenth of the \
             disk's radius either side of the centre line (the disk is {disk_width_px:.0} px \
             wide, so at most {widest:.0} px): the rim would be read where it is lower than \
             on the centre line"
        ));
    }
    Ok(())
}

/// Longest fit window before the halt \[s\]: the power law describes the last
/// moments of the motion (the thesis fits 0.5 s); a window of minutes would fit it
/// where the disk still rolls at large angles.
pub const MAX_WINDOW_S: f64 = 10.0;

/// Largest disk accepted in `[disk]`: mass \[kg\], radius and half-thickness \[m\],
/// moments of inertia \[kg m²\]. A disk that spins on a table is centimetres across
/// and weighs grams to kilograms; beyond these the config holds a unit slip (mm
/// written as m), which would fail far later as a clip with no energy samples.
pub const DISK_LIMITS: (f64, f64, f64) = (100.0, 1.0, 10.0);

/// Lowest and highest capture frame rate accepted [frames/s]: a 1 fps time-lapse
/// to the fastest high-speed cameras.
pub const MIN_FPS: f64 = 1.0;
pub const MAX_FPS: f64 = 100_000.0;

/// A value out of range, named by the last layer that sets `key` (a dotted path)
/// with the line and column of its value.
fn out_of_range(layers: &[(PathBuf, String)], key: &str, reason: &str) -> ConfigError {
    for (file, text) in layers.iter().rev() {
        if let Some((line, column)) = locate(text, key) {
            return ConfigError::Invalid {
                path: file.clone(),
                reason: format!("line {line}, column {column}: {reason}"),
            };
        }
    }
    ConfigError::Invalid {
        path: layers
            .last()
            .map_or_else(|| PathBuf::from("(defaults)"), |(f, _)| f.clone()),
        reason: reason.to_string(),
    }
}

/// Line and column (1-based) of the value of the dotted `key` in a TOML text.
fn locate(text: &str, key: &str) -> Option<(usize, usize)> {
    let root = toml::de::DeTable::parse(text).ok()?;
    let mut table = root.get_ref();
    let mut parts = key.split('.').peekable();
    while let Some(part) = parts.next() {
        let value = table.get(part)?;
        if parts.peek().is_none() {
            let start = value.span().start;
            let before = &text[..start];
            let line = before.matches('\n').count() + 1;
            let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
            return Some((line, column));
        }
        match value.get_ref() {
            toml::de::DeValue::Table(t) => table = t,
            _ => return None,
        }
    }
    None
}

fn invalid(path: &Path, e: impl std::fmt::Display) -> ConfigError {
    ConfigError::Invalid {
        path: path.to_path_buf(),
        reason: e.to_string().trim_end().to_string(),
    }
}

/// Merge `over` into `base`: tables recursively, any other value replaced.
fn merge(base: &mut toml::Table, over: toml::Table) {
    for (key, value) in over {
        match (base.get_mut(&key), value) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
            (_, value) => {
                base.insert(key, value);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_typo_is_an_error_naming_the_file_and_the_key() {
        let err = ExperimentConfig::parse("fsp = 480\n", Path::new("exp.toml"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("exp.toml") && err.contains("fsp"), "{err}");
        let err = ExperimentConfig::parse("[vision]\ngama = 3\n", Path::new("e.toml"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("gama"), "{err}");
    }

    #[test]
    fn nonsense_values_are_rejected() {
        for text in [
            "fps = -480",
            "fps = 0",
            "[vision]\ngamma = 1.5",
            "[calibration]\nx_l = 10\nx_r = 5\nz_t = 1\nz_base = 2",
            "[calibration]\nx_l = 1\nx_r = 5\nz_t = 3\nz_base = 2",
            "[fit]\nwindow_s = -1",
            "[fit]\nrim_zero = \"still\"",
            "plate = \"shiny\"",
            "camera_distance_m = 0",
            "camera_distance_m = -0.3",
        ] {
            assert!(
                ExperimentConfig::parse(text, Path::new("x.toml")).is_err(),
                "{text}"
            );
        }
    }

    /// Issue 73.9: `window_s = 1e9` and `band_half_width_px = 0` were accepted,
    /// `half_thickness_m = 1e6` failed only at the fit, a negative pixel count said
    /// "expected u32". Each is refused on reading, naming the key, the value, the
    /// unit and the range.
    #[test]
    fn out_of_range_values_are_refused_with_key_value_unit_and_range() {
        for (text, words) in [
            (
                "[fit]\nwindow_s = 1e9",
                &["fit.window_s", "1000000000", "s", "10"][..],
            ),
            (
                "[vision]\nband_half_width_px = 0",
                &["vision.band_half_width_px", "= 0", "px", "1 column"],
            ),
            (
                "[disk]\nhalf_thickness_m = 1e6",
                &["disk.half_thickness_m", "1000000", "m", "at most 1"],
            ),
            (
                "[vision]\nband_half_width_px = -3",
                &["vision.band_half_width_px", "-3", "px", "from 0"],
            ),
            (
                "[vision]\nsplit_row = -1",
                &["vision.split_row", "-1", "px"],
            ),
            (
                "[vision]\nroi = [0, -5, 10, 10]",
                &["vision.roi", "-5", "px"],
            ),
        ] {
            let err = ExperimentConfig::parse(text, Path::new("x.toml"))
                .unwrap_err()
                .to_string();
            for word in words {
                assert!(err.contains(word), "{text}: {word} missing from {err}");
            }
            assert!(err.contains("x.toml") && err.contains("line 2"), "{err}");
        }
        let fine = "[vision]\nband_half_width_px = 3\nroi = [0, 0, 720, 1280]\n[fit]\nwindow_s = 2";
        ExperimentConfig::parse(fine, Path::new("x.toml")).unwrap();
    }

    #[test]
    fn the_zero_of_z_rim_is_the_motions_unless_the_rest_is_asked_for() {
        let parse = |text| ExperimentConfig::parse(text, Path::new("z.toml")).expect(text);
        assert_eq!(parse("fps = 480\n").rim_zero(), RimZeroChoice::Motion);
        let rest = parse("fps = 480\n[fit]\nrim_zero = \"rest\"\n");
        assert_eq!(rest.rim_zero(), RimZeroChoice::Rest);
    }

    #[test]
    fn layers_override_key_by_key() {
        let root = tempfile::tempdir().unwrap();
        let material = root.path().join("euler/steel");
        std::fs::create_dir_all(&material).unwrap();
        std::fs::write(
            root.path().join(FOLDER_CONFIG),
            "fps = 480\n[vision]\ngamma = 0.4\nband_half_width_px = 4\n",
        )
        .unwrap();
        std::fs::write(material.join(FOLDER_CONFIG), "material = \"steel\"\n").unwrap();
        let clip = material.join("run07.mp4");
        std::fs::write(material.join("run07.toml"), "[vision]\ngamma = 0.5\n").unwrap();
        let layers = ExperimentConfig::layers_for(root.path(), &clip);
        assert_eq!(layers.len(), 4, "{layers:?}");
        let config = ExperimentConfig::load_layered(&layers).unwrap();
        assert_eq!(config.fps, Some(480.0));
        assert_eq!(config.material.as_deref(), Some("steel"));
        let vision = config.vision.unwrap();
        assert_eq!(vision.gamma, Some(0.5), "the clip's own file wins");
        assert_eq!(
            vision.band_half_width_px,
            Some(4),
            "inherited from the root"
        );
    }

    #[test]
    fn disk_overrides_replace_preset_values() {
        let config = ExperimentConfig::parse(
            "[disk]\npreset = \"brass-disk\"\nradius_m = 0.05\n",
            Path::new("x.toml"),
        )
        .unwrap();
        let params = config.disk_params();
        assert_eq!(params.radius, 0.05);
        assert_eq!(params.mass, Preset::BrassDisk.params().mass);
        assert_eq!(
            ExperimentConfig::default().disk_params(),
            Preset::EulerDisk.params()
        );
    }

    /// Issue 13.6: config errors named the key but not the line the README
    /// promises. Unknown keys, type errors and values out of range now carry the
    /// line and column, and the unknown-key message lists the real keys.
    #[test]
    fn errors_carry_the_line_and_column() {
        let err = |text: &str| {
            ExperimentConfig::parse(text, Path::new("e.toml"))
                .unwrap_err()
                .to_string()
        };
        let typo = err("fps = 480\n[vision]\ngama = 0.3\n");
        assert!(
            typo.contains("line 3, column 1") && typo.contains("gamma"),
            "{typo}"
        );
        let range = err("plate = \"dark\"\n[fit]\nwindow_s = -1\n");
        assert!(
            range.contains("line 3, column 12") && range.contains("[s]"),
            "{range}"
        );
        let wrong_type = err("\nfps = \"fast\"\n");
        assert!(wrong_type.contains("line 2"), "{wrong_type}");
        // Across layers, the value is blamed on the file that sets it.
        let dir = tempfile::tempdir().unwrap();
        let (outer, inner) = (dir.path().join("a.toml"), dir.path().join("b.toml"));
        std::fs::write(&outer, "\n\nfps = 1e9\n").unwrap();
        std::fs::write(&inner, "plate = \"light\"\n").unwrap();
        let e = ExperimentConfig::load_layered(&[outer, inner])
            .unwrap_err()
            .to_string();
        assert!(e.contains("a.toml") && e.contains("line 3"), "{e}");
    }

    /// Issue 13.5: values outside their physical range, with the unit: an fps
    /// outside 1–100 000 frames/s, an ROI whose integer arithmetic would wrap, and
    /// a band wider than the ROI or than a tenth of the calibrated disk's radius.
    #[test]
    fn values_outside_their_physical_range_are_refused_with_the_unit() {
        for (text, words) in [
            ("fps = 0.5", "frames/s"),
            ("fps = 1e6", "frames/s"),
            ("[vision]\nroi = [4294967295, 0, 10, 10]", "x + width"),
            ("[vision]\nroi = [0, 0, 0, 10]", "width and height above 0"),
            (
                "[vision]\nroi = [0, 0, 100, 100]\nband_half_width_px = 100000",
                "wider than the region",
            ),
            (
                "[vision]\nband_half_width_px = 100000\n\
                 [calibration]\nx_l = 100.0\nx_r = 600.0\nz_t = 700.0\nz_base = 742.0",
                "tenth of the disk's radius",
            ),
        ] {
            let err = ExperimentConfig::parse(text, Path::new("x.toml"))
                .unwrap_err()
                .to_string();
            assert!(err.contains(words) && err.contains("line"), "{text}: {err}");
        }
        assert!(
            ExperimentConfig::parse(
                "fps = 480\n[vision]\nband_half_width_px = 20\n\
            [calibration]\nx_l = 100.0\nx_r = 600.0\nz_t = 700.0\nz_base = 742.0",
                Path::new("x.toml")
            )
            .is_ok()
        );
    }
}
