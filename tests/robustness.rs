//! Robustness of the measuring chain (issue 12 §4): 24 small scenes drawn from a fixed
//! seed across what real footage has — dark plates with sharp or blurred reflections
//! of any strength, light plates brighter than the disk's side, textured plates, a
//! top face lit brighter than the side, pinhole cameras 0.2–1 m from the near rim or
//! orthographic, 100 Hz and 50 Hz flicker, lateral drift, φ oscillating about
//! stationary rolling, any phase of the precession at the halt, read and shot noise,
//! blur, exposure smear, H.264 at crf 18–23 with libx264's picture structure or a
//! phone's (I and P pictures only, keyed every 16–240 frames), side views and
//! two-view layouts — each rendered with its ground truth, encoded, and analysed
//! **with no config beyond the frame rate**. Every scene must be measured, and at
//! accuracies that follow from its resolution and the targets of issue 12 §5 (see
//! [`Tolerances`]). The scenes coded at crf 20 are coded again at crf 28, coarser than
//! any footage §5's targets are set on: those must be measured, and their rows are
//! information ([`COARSE_CRF`]).
//!
//! The test prints one row per scene (`cargo test --release --test integration --
//! --nocapture robustness::drawn_scenes`) and fails listing every scene that misses
//! a target, with the metric and by how much. One column is for information only: the heights' offset
//! (a of z − z_true = a + b·z_true over the scored window, the error of z_rim's zero),
//! the error of the camera's elevation at the near rim as measured, and the precession
//! check (`eulerdisk::precession`: φ from the heights over φ from the precession rate,
//! − 1, which our renders' stationary rolling makes the heights' φ error), and the
//! codec's smoothing over time, α of the P and of the B pictures
//! (`eulerdisk::footage::smoothing_by_picture_type`); and, after the n column's
//! tolerance, n from the turns' timing alone (`eulerdisk::turn_timing`, no height in
//! it) against the truth, and after the fitted halt's error that of the turns' end T of
//! the same law. Under the table, [`error_budget`] says how much of each fit's Δn the
//! heights' offset explains. `EULERDISK_ROBUSTNESS_KEEP=DIR` keeps the clips (`sNN.mp4`) and
//! their ground truths (`sNN.truth.json`) in DIR; `EULERDISK_ROBUSTNESS_SEED=N` draws
//! another 24 scenes (the gate's verdicts are for the default seed).

use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::f64::consts::TAU;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::{Mutex, OnceLock};

use eulerdisk::analyse::{Experiment, analyse_clip};
use eulerdisk::config::ExperimentConfig;
use eulerdisk::model::params::Preset;
use eulerdisk::render::{
    ClipEncoding, Effects, GroundTruth, Nutation, Plate, PostFlatSpin, PowerLaw, RenderSpec,
    Renderer, Scenery, Shake, Timing, add_nutation, power_law_motion, write_clip,
};
use eulerdisk::rng::SplitMix64;
use rayon::prelude::*;

/// Seed of the scene draw (`EULERDISK_ROBUSTNESS_SEED` overrides it).
const SEED: u64 = 0x12_0004;
/// Scenes drawn.
const SCENES: usize = 24;
/// The constant-rate factors the gate's scenes are coded at, in turn by threes of the
/// scene's index: 18, libx264's default 23, and the independent footage's 20 (every
/// clip of `../shared/footage-open` is libx264 at crf 20, 0.043 bit a pixel). The
/// targets are §5's, set on footage of that quality, and scaled here for the disk's
/// size only, not for a coarser code.
const GATE_CRF: [u8; 3] = [18, 23, 20];
/// A coarser code than any footage the targets are set on: the scenes the gate
/// codes at 20 are also coded at crf 28 (a quantiser step 2.5 times the open
/// footage's; 0.02 bit a pixel on the side views), must be measured, and are scored
/// for information (docs/validation.md, "Robustness gate").
const COARSE_CRF: u8 = 28;
/// Capture rate [frames/s], the only config the analysis is given.
const FPS: f64 = 480.0;
/// Renderer → vision coordinates: the renderer puts pixel centres at integers, vision
/// at c + ½ (tests/vision_render.rs).
const HALF: f64 = 0.5;
/// The window before the halt that §5 scores [s].
const WINDOW_S: f64 = 0.5;

/// One drawn scene: the picture, the motion's exponent and nutation, the encoding.
#[derive(Debug, Clone)]
struct SceneSpec {
    name: String,
    /// The picture; camera shake, if any, is its `effects.shake` ([`shaken`]; the
    /// default draw has none).
    spec: RenderSpec,
    n: f64,
    nutation: Option<Nutation>,
    encoding: ClipEncoding,
    /// The precession angle at the halt [rad] ([`PowerLaw::psi_halt`]).
    psi_halt: f64,
}

impl SceneSpec {
    /// A short description of the conditions, for the table.
    fn conditions(&self) -> String {
        let s = &self.spec;
        let sc = &s.scenery;
        let fx = &s.effects;
        let mut c = vec![format!(
            "{}{}",
            match s.plate {
                Plate::Dark => "dark",
                Plate::Light => "light",
            },
            if s.two_view { " 2-view" } else { "" }
        )];
        if let Some(g) = sc.plate_grey {
            c.push(format!("plate {g:.0}/paper {:.0}", sc.paper_grey));
        }
        if sc.texture_contrast > 0.0 {
            c.push(format!("texture {:.2}", sc.texture_contrast));
        }
        if let Some(rho) = sc.reflectivity {
            c.push(format!("refl {rho:.2} σ{:.1}", sc.reflection_blur_px));
        }
        if sc.fill_elevation_deg != Scenery::DEFAULT_FILL_ELEVATION_DEG {
            c.push(format!("top lit ({:.0}°)", sc.fill_elevation_deg));
        }
        c.push(match s.camera_distance_m {
            Some(d) => format!("cam {d:.2} m"),
            None => "ortho".into(),
        });
        c.push(format!("ε {:.1}°", s.elevation_deg));
        if fx.flicker_amplitude > 0.0 {
            c.push(format!(
                "flicker {:.2}+{:.2}",
                fx.flicker_amplitude, fx.flicker_50hz_amplitude
            ));
        }
        if let Some(nu) = &self.nutation {
            c.push(format!("nutation {:.3}×{:.2}", nu.amplitude, nu.ratio));
        }
        if fx.drift_px_per_s != 0.0 {
            c.push(format!("drift {:.1} px/s", fx.drift_px_per_s));
        }
        if let Some(shake) = fx.shake.filter(|s| !s.is_still()) {
            c.push(shake_conditions(&shake));
        }
        if fx.exposure_s > 0.0 {
            c.push("smear".into());
        }
        c.push(format!(
            "noise {:.1}/{:.2} blur {:.1} crf {}",
            fx.noise_sigma, fx.shot_noise, fx.blur_sigma, self.encoding.crf
        ));
        if let (Some(keyint), Some(0)) = (self.encoding.keyint, self.encoding.bframes) {
            c.push(format!("I/P key {keyint}"));
        }
        c.join(", ")
    }
}

/// Draws the scenes. Conditions are stratified by the scene's index so that each
/// appears several times (plate looks in turn: dark with a sharp reflection, light
/// brighter than the side, dark with a blurred reflection, textured dark or light;
/// two-view on dark plates every fourth scene; orthographic every fifth; top face
/// lit brighter every seventh; flicker on odd scenes; nutation, drift and smear each
/// on a third), with their strengths drawn from the seeded generator, and the
/// precession's phase at the halt spread over the turn.
fn draw_scenes() -> Vec<SceneSpec> {
    draw_scenes_of(
        std::env::var("EULERDISK_ROBUSTNESS_SEED")
            .ok()
            .map_or(SEED, |s| {
                s.parse().expect("EULERDISK_ROBUSTNESS_SEED: an integer")
            }),
    )
}

/// [`draw_scenes`] with the generator's seed given.
fn draw_scenes_of(seed: u64) -> Vec<SceneSpec> {
    let mut rng = SplitMix64::new(seed);
    // The encoder's picture structure from a generator of its own, so that the
    // other draws stay as they were before it was drawn.
    let mut structures = SplitMix64::new(seed ^ STRUCTURE_STREAM);
    (0..SCENES)
        .map(|i| {
            let look = i % 4;
            let two_view = i % 8 == 0 || i % 8 == 6;
            let textured_light = look == 3 && (i / 4) % 2 == 0;
            let plate = if look == 1 || textured_light {
                Plate::Light
            } else {
                Plate::Dark
            };
            let mut spec = RenderSpec::thesis(plate, two_view);
            (spec.width, spec.height) = if two_view { (240, 400) } else { (320, 180) };
            spec.elevation_deg = rng.range(1.5, 5.0);
            spec.camera_distance_m =
                (i % 5 != 4).then(|| rng.range(0.2f64.ln(), 1.0f64.ln()).exp());
            let sc = &mut spec.scenery;
            match look {
                0 => sc.reflectivity = Some(rng.range(0.1, 0.6)),
                1 => {
                    sc.paper_grey = rng.range(140.0, 185.0);
                    sc.plate_grey = Some(rng.range(195.0, 230.0));
                }
                2 => {
                    sc.reflectivity = Some(rng.range(0.2, 0.6));
                    sc.reflection_blur_px = rng.range(0.5, 2.5);
                }
                _ => {
                    sc.texture_contrast = if textured_light {
                        rng.range(0.05, 0.2)
                    } else {
                        rng.range(0.1, 0.3)
                    }
                }
            }
            if i % 7 == 3 {
                sc.fill_elevation_deg = 60.0;
            }
            let fx = &mut spec.effects;
            *fx = Effects {
                noise_sigma: rng.range(0.5, 2.5),
                shot_noise: rng.range(0.0, 0.5),
                blur_sigma: rng.range(0.0, 1.0),
                seed: 1000 + i as u64,
                ..Effects::default()
            };
            if i % 2 == 1 {
                fx.flicker_amplitude = rng.range(0.02, 0.1);
                fx.flicker_50hz_amplitude = rng.range(0.0, 0.05);
                fx.flicker_phase_100 = rng.range(0.0, TAU);
                fx.flicker_phase_50 = rng.range(0.0, TAU);
            }
            if i % 3 == 2 {
                let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
                fx.drift_px_per_s = sign * rng.range(2.0, 8.0);
            }
            if i % 3 == 0 {
                fx.exposure_s = 0.5e-3;
                fx.exposure_samples = 2;
            }
            let nutation = (i % 3 == 1).then(|| Nutation {
                amplitude: rng.range(0.02, 0.06),
                ratio: rng.range(0.3, 0.8),
                phase: rng.range(0.0, TAU),
            });
            SceneSpec {
                name: format!("s{i:02}"),
                spec,
                n: rng.range(0.4, 0.7),
                nutation,
                encoding: ClipEncoding {
                    crf: GATE_CRF[(i / 3) % 3],
                    ..picture_structure(&mut structures)
                },
                // Spread evenly over the turn by the golden ratio, apart from the
                // generator so that the other draws stay as they were.
                psi_halt: TAU * ((i + 1) as f64 * 0.618_033_988_7).fract(),
            }
        })
        .collect()
}

/// Salt of the generator that draws the encoder's picture structure.
const STRUCTURE_STREAM: u64 = 0x4950_5f47_4f50;

/// The encoder's picture structure, half the scenes each way: libx264's defaults
/// (three quarters of the pictures B, an I picture at most every 250 frames), or I
/// and P pictures only with an I picture every 16–240 frames (log-uniform), as a
/// phone's hardware encoder writes them (`render::ClipEncoding`).
fn picture_structure(rng: &mut SplitMix64) -> ClipEncoding {
    let phone = rng.uniform() < 0.5;
    let keyint = rng.range(16f64.ln(), 240f64.ln()).exp().round() as u32;
    ClipEncoding {
        keyint: phone.then_some(keyint),
        bframes: phone.then_some(0),
        ..eulerdisk::render::DEFAULT_ENCODING
    }
}

/// The scene's clip: 0.65 s of the power law before the halt (the 0.5 s window and
/// some lead), 0.15 s of flat disk after it (the post-flat spin and the rest frames).
fn render(scene: &SceneSpec, dir: &Path) -> (std::path::PathBuf, GroundTruth) {
    let params = Preset::EulerDisk.params();
    let timing = Timing {
        fps: FPS,
        halt_time: 0.65,
        after_halt: 0.15,
        jitter: None,
    };
    let spin = PostFlatSpin {
        beta_dot0: -2.8,
        mu: 0.134,
    };
    let law = PowerLaw {
        psi_halt: scene.psi_halt,
        ..PowerLaw::thesis(scene.n)
    };
    let mut motion = power_law_motion(&params, &law, &timing, spin).expect("motion");
    if let Some(nu) = scene.nutation {
        add_nutation(&mut motion, nu).expect("nutation");
    }
    let renderer = Renderer::new(&scene.spec, &motion).expect("renderer");
    let path = dir.join(format!("{}.mp4", scene.name));
    write_clip(&renderer, &path, scene.encoding).expect("write");
    (path, renderer.truth().clone())
}

/// A scene as the gate measures it: its ground truth and its analysis with no config
/// beyond the frame rate, or the error (without the clip's path).
type Measured = (GroundTruth, Result<Experiment, String>);

/// The scene rendered and analysed ([`Measured`]), once for the test binary where
/// one measurement ends before the next asks: the tests of single drawn scenes (run
/// first, in name order) and the gate read one result. A scene asked for while it is
/// being measured is measured again rather than waited for: a rayon thread of the
/// gate that waited could hold up the pool that the other measurement needs.
fn measured(scene: &SceneSpec) -> &'static Measured {
    enum Slot {
        Measuring,
        Done(&'static Measured),
    }
    static SCENES: OnceLock<Mutex<HashMap<String, Slot>>> = OnceLock::new();
    let scenes = SCENES.get_or_init(Default::default);
    // Every field of the scene, so that only the same scene is shared.
    let key = format!("{scene:?}");
    let first = match scenes.lock().expect("scenes").entry(key.clone()) {
        Entry::Occupied(slot) => match slot.get() {
            Slot::Done(m) => return m,
            Slot::Measuring => false,
        },
        Entry::Vacant(slot) => {
            slot.insert(Slot::Measuring);
            true
        }
    };
    let m: &'static Measured = Box::leak(Box::new(render_and_analyse(scene)));
    if first {
        scenes.lock().expect("scenes").insert(key, Slot::Done(m));
    }
    m
}

/// Renders the scene into `EULERDISK_ROBUSTNESS_KEEP`'s folder, where the clip and its
/// truth are kept, or into a temporary folder, removed; analyses it with no config
/// beyond the frame rate.
fn render_and_analyse(scene: &SceneSpec) -> Measured {
    let keep = std::env::var_os("EULERDISK_ROBUSTNESS_KEEP").map(std::path::PathBuf::from);
    let temp = tempfile::tempdir().expect("tempdir");
    let dir = keep.unwrap_or_else(|| temp.path().to_path_buf());
    std::fs::create_dir_all(&dir).expect("clip folder");
    let config =
        ExperimentConfig::parse("fps = 480\n", Path::new("robustness.toml")).expect("config");
    let (clip, truth) = render(scene, &dir);
    let result = analyse_clip(&clip, &config, &|_, _| {})
        .map_err(|e| format!("{e:#}").replace(&format!("{}: ", clip.display()), ""));
    (truth, result)
}

/// How close each measurement must be, and why.
///
/// * Calibration points x_l, x_r, z_t, z_base within [`CAL_PX`] = 0.5 px: a point
///   found only to the nearest pixel is within 0.5 px, so a sub-pixel method must
///   beat that on every clean rest frame whatever the plate. Through a pinhole the
///   disk's ends are a short silhouette from the bottom rim's ends (the truth's x_l,
///   x_r) to the top rim's (wider by up to 0.5 px here), so an end counts from that
///   interval.
/// * The scale used, at the near rim, within 2·[`CAL_PX`]/(z_base − z_t): the two
///   points' errors through δ = 2H/(z_base − z_t) (eq. 3.10), plus the truth's own
///   difference between eq. 3.10's δ and the vertical scale at the near bottom rim.
/// * z_rim within [`Z_RIM_RMS_PX`] = 0.25 px RMS over the last 0.5 s before the halt,
///   on every frame (§5; an edge's per-frame accuracy is in pixels, whatever the frame
///   size), and every true peak of at least 0.5 px in that window found (within a
///   frame), none spurious (§5).
/// * t_φ within [`HALT_FRAMES`] = 2 frames of the true halt (§5). The fitted t0 is
///   information: it comes from the heights of the last turns, which a small frame
///   and a coarse codec read least well (up to 4.4 ms off here, against §5's 2 ms on
///   the open footage's larger disks).
/// * n (both fits) within ±0.02 (±0.03 when φ oscillates about stationary rolling)
///   and φ at the peaks within a median relative error of 2 % (§5), targets that §5
///   sets on footage whose disk spans x_r − x_l ≥ [`REFERENCE_DIAMETER_PX`] = 461 px
///   (the open set's smallest, its two-view clips). They come from z_rim read to a
///   fraction of a pixel at the peaks, whose relative error scales as 1/(x_r − x_l)
///   at a given motion, so on a smaller disk they are scaled by 461/(x_r − x_l) (1.6
///   for the side views here, 2.1 for the two-view ones); φ's also by no less than
///   the scale's tolerance plus 2 %, since φ inherits the scale's error.
struct Tolerances {
    scale: f64,
    n: f64,
    phi: f64,
}

const CAL_PX: f64 = 0.5;
/// t_φ within 2 frames of the true halt (§5), whatever the frame size: it is placed by
/// the laws of the motion (`analyse::law_halt`), the turns' timing needing no height.
const HALT_FRAMES: f64 = 2.0;
const Z_RIM_RMS_PX: f64 = 0.25;
/// Smallest true peak that must be found [px] (§5).
const DETECTABLE_PX: f64 = 0.5;
/// The smallest disk (x_r − x_l, px) on which §5 asks its n and φ targets: the open
/// footage's two-view clips (461–485 px; its side views 871–1108 px).
const REFERENCE_DIAMETER_PX: f64 = 461.0;

/// A true peak: frame index (file order), z_rim [px], φ [rad].
struct TruePeak {
    index: usize,
    z_px: f64,
    phi: f64,
}

/// Local maxima of the truth's z_rim in the window before the halt (all heights).
fn true_peaks(truth: &GroundTruth) -> Vec<TruePeak> {
    let f = &truth.frames;
    let z = |i: usize| f[i].z_rim_px.unwrap_or(f64::NAN);
    (1..f.len() - 1)
        .filter(|&i| f[i].t < 0.0 && f[i].t >= -WINDOW_S && z(i) > z(i - 1) && z(i) >= z(i + 1))
        .map(|i| TruePeak {
            index: i,
            z_px: z(i),
            phi: f[i].phi,
        })
        .collect()
}

/// One scene's scores: the table's row and the targets it misses.
struct Score {
    row: String,
    failures: Vec<String>,
    /// The errors the gate's closing summary is made of, for a measured scene.
    errors: Option<SceneErrors>,
}

/// A measured scene's errors against its truth, for [`error_budget`].
#[derive(Debug, Clone, Copy)]
struct SceneErrors {
    /// Δn of the peaks fit and of the per-frame fit.
    n_peaks: f64,
    n_frames: Option<f64>,
    /// The heights' offset a of z − z_true = a + b·z_true [px] (the zero's error).
    offset_px: f64,
    /// The peaks fit's halt and the turns' end T (`eulerdisk::turn_timing`) against
    /// the true halt [ms].
    t0_ms: f64,
    turns_end_ms: Option<f64>,
}

/// The least-squares line y = slope·x + intercept through (x, y) pairs, with the
/// share of y's variance it explains.
struct StraightLine {
    slope: f64,
    intercept: f64,
    r_squared: f64,
}

impl StraightLine {
    fn through(pairs: &[(f64, f64)]) -> Self {
        let k = pairs.len() as f64;
        let (mx, my) = pairs
            .iter()
            .fold((0.0, 0.0), |(a, b), &(x, y)| (a + x / k, b + y / k));
        let (sxx, sxy, syy) = pairs.iter().fold((0.0, 0.0, 0.0), |(a, b, c), &(x, y)| {
            (
                a + (x - mx).powi(2),
                b + (x - mx) * (y - my),
                c + (y - my).powi(2),
            )
        });
        let slope = sxy / sxx;
        Self {
            slope,
            intercept: my - slope * mx,
            r_squared: sxy * sxy / (sxx * syy),
        }
    }
}

/// Where n's error comes from, over the measured scenes (information, printed under
/// the table): the RMS of each fit's Δn, how much of it a straight line in the
/// heights' offset explains (least squares Δn = s·a + d, with R²), and how far the
/// fitted halt and the turns' end lie from the true halt (RMS). R² is a correlation,
/// not the zero's share: a zero 15 % closer to the truth left Δn as it was, since the
/// coding that moves the zero shaves the peaks too.
fn error_budget(errors: &[SceneErrors]) -> String {
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    let peaks: Vec<(f64, f64)> = errors.iter().map(|e| (e.offset_px, e.n_peaks)).collect();
    let frames: Vec<(f64, f64)> = errors
        .iter()
        .filter_map(|e| Some((e.offset_px, e.n_frames?)))
        .collect();
    let t0: Vec<f64> = errors.iter().map(|e| e.t0_ms).collect();
    let turns_end: Vec<f64> = errors.iter().filter_map(|e| e.turns_end_ms).collect();
    let column = |pairs: &[(f64, f64)]| pairs.iter().map(|p| p.1).collect::<Vec<_>>();
    let (on_peaks, on_frames) = (
        StraightLine::through(&peaks),
        StraightLine::through(&frames),
    );
    format!(
        "Where n's error comes from (information), over {} measured scenes: Δn RMS {:.4} \
         (peaks fit), {:.4} (per frame); heights' offset RMS {:.4} px; a straight line in \
         the offset explains {:.0} % of the peaks fit's Δn (slope {:+.2} per px) and {:.0} % \
         of the per-frame fit's ({:+.2} per px). Halt error RMS: the peaks fit's t0 {:.2} ms, \
         the turns' end {:.2} ms ({} scenes).",
        errors.len(),
        rms(&column(&peaks)),
        rms(&column(&frames)),
        rms(&errors.iter().map(|e| e.offset_px).collect::<Vec<_>>()),
        100.0 * on_peaks.r_squared,
        on_peaks.slope,
        100.0 * on_frames.r_squared,
        on_frames.slope,
        rms(&t0),
        rms(&turns_end),
        turns_end.len(),
    )
}

/// Every crest the analysis reports, as (frame, φ): the peaks of the heights, and
/// the crests the motion fitted to every frame places after them, at the frame
/// nearest their time.
fn crests(e: &Experiment) -> Vec<(usize, f64)> {
    let nearest_frame = |t: f64| {
        (0..e.frames.len())
            .min_by(|&a, &b| {
                (e.frames[a].t - t)
                    .abs()
                    .total_cmp(&(e.frames[b].t - t).abs())
            })
            .expect("frames")
    };
    let placed = (e.motion_fit.iter())
        .flat_map(|m| &m.unresolved_crests)
        .map(|c| (nearest_frame(c.t), c.phi));
    (e.series.peaks.peaks.iter())
        .map(|p| (p.index, p.phi))
        .chain(placed)
        .collect()
}

fn score(scene: &SceneSpec, truth: &GroundTruth, result: Result<&Experiment, &str>) -> Score {
    let mut failures = Vec::new();
    let e = match result {
        Ok(e) => e,
        Err(err) => {
            return Score {
                row: format!(
                    "| {} | {} | **not measured**: {} | | | | | | | | | |",
                    scene.name,
                    scene.conditions(),
                    err.lines().next().unwrap_or("").replace('|', "/")
                ),
                failures: vec![format!("not measured: {err}")],
                errors: None,
            };
        }
    };
    let tc = &truth.calibration;
    let cam = &truth.camera;
    let cal = &e.plan.calibration.calibration;
    // Calibration points, in vision's coordinates.
    let interval = |got: f64, a: f64, b: f64| {
        let (lo, hi) = (a.min(b) + HALF, a.max(b) + HALF);
        if got < lo {
            got - lo
        } else if got > hi {
            got - hi
        } else {
            0.0
        }
    };
    let cal_err = [
        ("x_l", interval(cal.x_l, tc.x_l, cam.x_l_top)),
        ("x_r", interval(cal.x_r, tc.x_r, cam.x_r_top)),
        ("z_t", cal.z_t - tc.z_t - HALF),
        ("z_base", cal.z_base - tc.z_base - HALF),
    ];
    for (name, err) in cal_err {
        if err.abs() > CAL_PX {
            // z_t: how far the measured point lies below the silhouette's top (the
            // far top rim), for a measurement that took one for the other.
            let far = if name == "z_t" {
                format!(
                    "; {:+.2} px from the far top rim",
                    cal.z_t - cam.z_t_far - HALF
                )
            } else {
                String::new()
            };
            failures.push(format!("{name} off by {err:+.2} px (≤ {CAL_PX}{far})"));
        }
    }
    let worst_cal = cal_err
        .iter()
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .expect("four points");
    // Scale at the near rim.
    let thickness_px = tc.z_base - tc.z_t;
    let near = cam.near_rim_metres_per_px;
    let resolution = (REFERENCE_DIAMETER_PX / (tc.x_r - tc.x_l)).max(1.0);
    let nutating = scene.nutation.is_some_and(|nu| nu.amplitude > 0.0);
    let tol = {
        let scale = 2.0 * CAL_PX / thickness_px + (truth.delta / near - 1.0).abs();
        Tolerances {
            scale,
            n: if nutating { 0.03 } else { 0.02 } * resolution,
            phi: (0.02 * resolution).max(0.02 + scale),
        }
    };
    let scale_err = e.plan.metres_per_px / near - 1.0;
    if scale_err.abs() > tol.scale {
        failures.push(format!(
            "scale off by {:+.2} % (≤ {:.2} %)",
            100.0 * scale_err,
            100.0 * tol.scale
        ));
    }
    // z_rim over the last 0.5 s before the halt.
    let (mut sum_sq, mut count, mut missing) = (0.0, 0usize, 0usize);
    for (m, t) in e.frames.iter().zip(&truth.frames) {
        if t.t >= 0.0 || t.t < -WINDOW_S {
            continue;
        }
        let Some(want) = t.z_rim_px else { continue };
        match m.z_rim_px {
            Some(got) => {
                sum_sq += (got - want).powi(2);
                count += 1;
            }
            None => missing += 1,
        }
    }
    let rms = (sum_sq / count.max(1) as f64).sqrt();
    // For information: the heights' offset a of z − z_true = a + b·z_true over the same
    // frames (the error of z_rim's zero), and the camera's elevation at the near bottom
    // rim (0, −R, 0) as measured against the truth's.
    let offset = {
        let pairs: Vec<(f64, f64)> = e
            .frames
            .iter()
            .zip(&truth.frames)
            .filter(|(_, t)| t.t < 0.0 && t.t >= -WINDOW_S)
            .filter_map(|(m, t)| Some((t.z_rim_px?, m.z_rim_px? - t.z_rim_px?)))
            .collect();
        StraightLine::through(&pairs).intercept
    };
    // The codec's smoothing over time, α of the P and B pictures (frame²), over the
    // same frames (eulerdisk::footage::smoothing_by_picture_type).
    let smoothing = eulerdisk::footage::smoothing_by_picture_type(
        (1..truth.frames.len().min(e.frames.len()).saturating_sub(1)).filter_map(|k| {
            let (before, t, after) = (&truth.frames[k - 1], &truth.frames[k], &truth.frames[k + 1]);
            let consecutive = before.index + 1 == t.index && t.index + 1 == after.index;
            if !(consecutive && t.t < 0.0 && t.t >= -WINDOW_S) {
                return None;
            }
            let z = t.z_rim_px?;
            let second = after.z_rim_px? - 2.0 * z + before.z_rim_px?;
            Some((e.frames[k].picture_type, second, e.frames[k].z_rim_px? - z))
        }),
    );
    let true_elevation = cam.position_m.map_or(truth.elevation, |p| {
        p[2].atan2(p[0].hypot(-truth.disk.radius - p[1]))
    });
    let elevation_err_deg = e
        .plan
        .scale
        .near_rim_elevation_rad
        .map(|got| (got - true_elevation).to_degrees());
    if rms > Z_RIM_RMS_PX || missing > 0 || e.frames.len() != truth.frames.len() {
        failures.push(format!(
            "z_rim RMS {rms:.3} px (≤ {Z_RIM_RMS_PX}), {missing} frames without an edge"
        ));
    }
    // Peaks: matched by frame (±1) to the truth's local maxima; those of the heights
    // and the crests the motion fit places after them (peaks.csv lists both).
    let peaks = true_peaks(truth);
    let measured = crests(e);
    let near_true = |index: usize| {
        peaks
            .iter()
            .filter(|p| p.index.abs_diff(index) <= 1)
            .min_by_key(|p| p.index.abs_diff(index))
    };
    let detectable: Vec<&TruePeak> = peaks.iter().filter(|p| p.z_px >= DETECTABLE_PX).collect();
    let found = detectable
        .iter()
        .filter(|p| measured.iter().any(|m| m.0.abs_diff(p.index) <= 1))
        .count();
    let window_start = truth.halt_time - WINDOW_S;
    let spurious = measured
        .iter()
        .filter(|m| e.frames[m.0].t_capture >= window_start && near_true(m.0).is_none())
        .count();
    if found < detectable.len() || spurious > 0 {
        failures.push(format!(
            "peaks: {found} of {} found, {spurious} spurious",
            detectable.len()
        ));
    }
    // φ at the matched peaks: the median |error| and, for the table, the median
    // signed error.
    let mut signed: Vec<f64> = measured
        .iter()
        .filter_map(|m| near_true(m.0).map(|p| m.1 / p.phi - 1.0))
        .collect();
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    let phi_med = median(&mut signed.iter().map(|x| x.abs()).collect());
    let phi_signed = median(&mut signed);
    // NaN (no peak matched) fails too.
    if phi_med.is_nan() || phi_med > tol.phi {
        failures.push(format!(
            "φ at the peaks: median error {:.2} % (≤ {:.2} %; median signed {:+.2} %)",
            100.0 * phi_med,
            100.0 * tol.phi,
            100.0 * phi_signed
        ));
    }
    // n, both fits.
    let n_peaks = e.peaks_fit.fit.n - scene.n;
    let n_frames = e.frames_fit.as_ref().map(|f| f.fit.n - scene.n);
    let ci = e.peaks_fit.fit.ci95_n;
    if n_peaks.is_nan() || n_peaks.abs() > tol.n {
        failures.push(format!("n (peaks) off by {n_peaks:+.3} (≤ {:.3})", tol.n));
    }
    match n_frames {
        Some(d) if d.abs() <= tol.n => {}
        Some(d) => failures.push(format!("n (per frame) off by {d:+.3} (≤ {:.3})", tol.n)),
        None => failures.push("no per-frame fit".into()),
    }
    // The halt t_φ, where the laws place it, within [`HALT_FRAMES`] (§5).
    let t_phi = e.series.halt.t_phi;
    let halt_frames = (t_phi - truth.halt_time) * FPS;
    if halt_frames.is_nan() || halt_frames.abs() > HALT_FRAMES {
        failures.push(format!(
            "t_φ off by {halt_frames:+.1} frames (≤ {HALT_FRAMES})"
        ));
    }
    // For information: the fitted t0 (§5: within 2 ms) and the turns' end.
    let t0_ms = 1e3 * (t_phi + e.peaks_fit.fit.t0 - truth.halt_time);
    let turns_end_ms = match &e.turn_timing {
        Some(Ok(t)) => Some(1e3 * (t_phi + t.t_end - truth.halt_time)),
        _ => None,
    };
    let row = format!(
        "| {} | {} | {} {:+.2} | {:+.2} / {:.2} | {:.3} | {:+.3} / {} / {} / {} | {found}/{}, {spurious} | {:.1} ({:+.1}) / {:.1} | {:+.3}{} / {} / {:.3} · {} | {:+.1} | {:+.1} · {} | {} |",
        scene.name,
        scene.conditions(),
        worst_cal.0,
        worst_cal.1,
        100.0 * scale_err,
        100.0 * tol.scale,
        rms,
        offset,
        elevation_err_deg.map_or("–".into(), |d| format!("{d:+.2}")),
        e.precession.map_or("–".into(), |c| format!(
            "{:+.1}",
            100.0 * (c.agreement() - 1.0)
        )),
        smoothing
            .map(|a| a.map_or("–".into(), |a| format!("{a:+.2}")))
            .join(", "),
        detectable.len(),
        100.0 * phi_med,
        100.0 * phi_signed,
        100.0 * tol.phi,
        n_peaks,
        if (ci.0..=ci.1).contains(&scene.n) {
            " (CI ✓)"
        } else {
            " (CI ✗)"
        },
        n_frames.map_or("–".into(), |d| format!("{d:+.3}")),
        tol.n,
        match &e.turn_timing {
            Some(Ok(t)) => format!(
                "{:+.3}{}",
                t.n - scene.n,
                if (t.ci95_n.0..=t.ci95_n.1).contains(&scene.n) {
                    " (CI ✓)"
                } else {
                    " (CI ✗)"
                }
            ),
            _ => "–".into(),
        },
        halt_frames,
        t0_ms,
        turns_end_ms.map_or("–".into(), |d| format!("{d:+.1}")),
        if failures.is_empty() {
            "pass"
        } else {
            "**FAIL**"
        },
    );
    let errors = Some(SceneErrors {
        n_peaks,
        n_frames,
        offset_px: offset,
        t0_ms,
        turns_end_ms,
    });
    Score {
        row,
        failures,
        errors,
    }
}

const HEADER: &str = "| scene | conditions | worst cal. point, err px | scale err % / tol | z_rim RMS px | heights' offset px / ε err ° / precession % / codec α P, B frame² | peaks found/true ≥0.5 px, spurious | φ med abs (signed) err % / tol | Δn peaks (95 % CI covers?) / per frame / tol · turns' timing (information) | t_φ err frames | fitted t0 err ms · turns' end (information) | verdict |\n|---|---|---|---|---|---|---|---|---|---|---|---|";

/// Two-view clips on light plates, one brighter than the disk's side and one darker
/// and textured, measured with no config to the same targets: the views split where
/// no dark band divides them (the plate's uniform rows between the two views,
/// `vision::find_split_row`) and the strip read against a plate brighter than its
/// red (`vision::auto_colour_thresholds`). Not in the seeded draw, whose two-view
/// scenes stay on dark plates so that it draws the scenes the gate has scored.
#[test]
fn two_view_scenes_on_light_plates_are_measured_with_no_config() {
    let temp = tempfile::tempdir().expect("tempdir");
    let config =
        ExperimentConfig::parse("fps = 480\n", Path::new("robustness.toml")).expect("config");
    let mut failed = Vec::new();
    for (k, (paper, plate, texture)) in [(170.0, Some(215.0), 0.0), (238.0, Some(200.0), 0.1)]
        .into_iter()
        .enumerate()
    {
        let mut spec = RenderSpec::thesis(Plate::Light, true);
        (spec.width, spec.height) = (240, 400);
        spec.camera_distance_m = Some(0.4);
        spec.elevation_deg = 3.0;
        let sc = &mut spec.scenery;
        (sc.paper_grey, sc.plate_grey, sc.texture_contrast) = (paper, plate, texture);
        spec.effects = Effects {
            noise_sigma: 1.0,
            seed: 2000 + k as u64,
            ..Effects::default()
        };
        let scene = SceneSpec {
            name: format!("light two-view {k}"),
            spec,
            n: 0.55,
            nutation: None,
            encoding: ClipEncoding::crf(18),
            psi_halt: 1.0,
        };
        let (clip, truth) = render(&scene, temp.path());
        let result = analyse_clip(&clip, &config, &|_, _| {}).map_err(|e| format!("{e:#}"));
        if let Ok(e) = &result {
            assert!(
                e.plan.layout.starts_with("two-view") && e.plan.plate.starts_with("light"),
                "{}: {} / {}",
                scene.name,
                e.plan.layout,
                e.plan.plate
            );
        }
        let s = score(&scene, &truth, result.as_ref().map_err(String::as_str));
        eprintln!("{}", s.row);
        if !s.failures.is_empty() {
            failed.push(format!("{}: {}", scene.name, s.failures.join("; ")));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// The default draw's s05, a light plate whose top face (grey 60) is darker than both
/// the backdrop above it (11) and the side (177): the face's near rim is the largest
/// step and so is taken for the silhouette, and it is the near top rim itself. The
/// thin-face fit tried below such an edge read the edge's own blur as a face 1 px
/// below it (z_t 0.64 px low) until the level just above the edge had to be the
/// backdrop's (`vision::light_plate`). Run with no config, as the gate does.
#[test]
fn a_dark_top_face_on_a_light_plate_is_not_read_as_thin() {
    let scene = draw_scenes_of(SEED).swap_remove(5);
    assert_eq!(scene.spec.plate, Plate::Light, "{}", scene.name);
    let (truth, result) = measured(&scene);
    let e = result.as_ref().expect("analysed");
    let error = e.plan.calibration.calibration.z_t - truth.calibration.z_t - HALF;
    assert!(error.abs() <= CAL_PX, "{}: z_t {error:+.2} px", scene.name);
}

/// The default draw's s08, a two-view dark plate whose top face is 0.87 px tall at
/// rest under a 1 px blur, coded at [`COARSE_CRF`] (28): the rest frame cannot tell its near
/// rim from its far one (z_t read 0.52 px off), but the frames in which the rolling
/// disk leans towards the camera show the face 3–5 px tall, and z_t follows from
/// them (`vision::near_top_rim_leaning`). Run with no config, as the gate does.
#[test]
fn a_face_thinner_than_its_blur_is_read_where_the_disk_leans() {
    // As the gate codes the scenes at crf 20 again.
    let scene = coarse(&draw_scenes_of(SEED).swap_remove(8));
    let (truth, result) = measured(&scene);
    let face = truth.calibration.z_t - truth.camera.z_t_far;
    assert!(face < 1.0, "{}: the face is {face:.2} px tall", scene.name);
    let e = result.as_ref().expect("analysed");
    let leaning = e.plan.top_rim_leaning.expect("z_t from the leaning frames");
    let error = e.plan.calibration.calibration.z_t - truth.calibration.z_t - HALF;
    assert!(
        error.abs() <= CAL_PX,
        "{}: z_t {error:+.2} px from {} frames (the rest frame's {:+.2})",
        scene.name,
        leaning.reading.frames,
        leaning.rest_z_t - truth.calibration.z_t - HALF
    );
}

/// The camera shake, for the table: e.g. "shake 1.0 px rms 20–80 Hz, sway 3.0 px
/// 1.0 Hz, roll 0.30°" (the parts that move).
fn shake_conditions(shake: &Shake) -> String {
    let mut parts = Vec::new();
    if shake.vibration_rms_px > 0.0 {
        let [lo, hi] = shake.vibration_band_hz;
        parts.push(format!(
            "{:.1} px rms {lo:.0}–{hi:.0} Hz",
            shake.vibration_rms_px
        ));
    }
    if shake.sway_px > 0.0 {
        parts.push(format!(
            "sway {:.1} px {:.1} Hz",
            shake.sway_px, shake.sway_hz
        ));
    }
    if shake.roll_deg > 0.0 {
        parts.push(format!("roll {:.2}°", shake.roll_deg));
    }
    format!("shake {}", parts.join(", "))
}

/// The scene filmed by a shaken camera (its name marked, so that it is measured and
/// kept apart from the scene itself).
fn shaken(scene: &SceneSpec, shake: Shake) -> SceneSpec {
    let mut spec = scene.spec.clone();
    spec.effects.shake = Some(shake);
    SceneSpec {
        name: format!("{}~shake", scene.name),
        spec,
        ..scene.clone()
    }
}

/// A camera on a tripod that vibrates (0.35 px RMS over 20–80 Hz, a 0.3 px sway at
/// 1.3 Hz, as a table the disk clatters on shakes it) filming the default draw's
/// s15 (a textured dark plate under flicker), framed wider (480 px, the disk at 60 %
/// of the width: the drawn scenes fill 90 % of it, and leave no scene beside the
/// disk to register on). Unregistered, the shaken clip shows no peak at all (0 in
/// the window: refused). Registered (`vision::registration`), its shifts follow the
/// truth's (correlation 0.91 measured; the rest tail's mean shift is the zero),
/// the heights are corrected, n lies within 0.02 of the still camera's reading
/// (0.013 measured: issue 72 §1 asks 0.01) and the peaks fit's interval covers the
/// truth. The still camera's own registration is its error alone, and is not
/// applied.
#[test]
fn a_vibrating_tripod_is_registered_to_the_scene() {
    let mut scene = draw_scenes_of(SEED).swap_remove(15);
    let diameter = 2.0 * Preset::EulerDisk.params().radius;
    scene.spec.metres_per_px = Some(diameter / (0.9 * f64::from(scene.spec.width)));
    scene.spec.width = 480;
    scene.name = format!("{}~wide", scene.name);
    let vibrating = shaken(
        &scene,
        Shake {
            vibration_rms_px: 0.35,
            sway_px: 0.3,
            sway_hz: 1.3,
            ..Shake::default()
        },
    );
    let still = measured(&scene)
        .1
        .as_ref()
        .expect("the still scene analysed");
    let (truth, result) = measured(&vibrating);
    let e = result.as_ref().expect("the shaken scene analysed");
    let registration = |e: &Experiment| e.plan.registration.clone().expect("registered");
    assert!(!registration(still).applied, "{:?}", registration(still));
    let r = registration(e);
    assert!(r.applied, "{r:?}");
    // The shift read against the truth's, frame by frame (the truth's dy at
    // mid-exposure; both positive down; ours from the rest tail's mean).
    let pairs: Vec<(f64, f64)> = e
        .frames
        .iter()
        .filter_map(|f| {
            let frame = truth.frames.iter().find(|t| t.file_index == f.index)?;
            Some((f.camera_shift_px?, frame.camera_shake.as_ref()?.dy_px))
        })
        .collect();
    let line = StraightLine::through(&pairs);
    let correlation = line.slope.signum() * line.r_squared.sqrt();
    assert!(
        pairs.len() > 100 && correlation > 0.85,
        "{} frames, correlation {correlation:.3}",
        pairs.len()
    );
    let dn = e.peaks_fit.fit.n - still.peaks_fit.fit.n;
    assert!(
        dn.abs() <= 0.02,
        "n {:.4} shaken, {:.4} still",
        e.peaks_fit.fit.n,
        still.peaks_fit.fit.n
    );
    let (lo, hi) = e.peaks_fit.fit.ci95_n;
    assert!(
        (lo..=hi).contains(&scene.n),
        "n {} outside {lo:.4}…{hi:.4}",
        scene.n
    );
}

/// The gate's draw has no camera shake (its scenes and verdicts are as they were
/// before shake could be drawn); a scene given one says so in its conditions.
#[test]
fn drawn_scenes_carry_shake_only_when_given() {
    let scenes = draw_scenes_of(SEED);
    assert!(scenes.iter().all(|s| s.spec.effects.shake.is_none()));
    assert!(scenes.iter().all(|s| !s.conditions().contains("shake")));
    let scene = shaken(
        &scenes[3],
        Shake {
            vibration_rms_px: 0.5,
            sway_px: 2.0,
            roll_deg: 0.3,
            ..Shake::default()
        },
    );
    assert_eq!(scene.name, "s03~shake");
    let conditions = scene.conditions();
    assert!(
        conditions.contains("shake 0.5 px rms 20–80 Hz, sway 2.0 px 1.0 Hz, roll 0.30°"),
        "{conditions}"
    );
    assert_eq!(
        conditions.replace(
            ", shake 0.5 px rms 20–80 Hz, sway 2.0 px 1.0 Hz, roll 0.30°",
            ""
        ),
        scenes[3].conditions()
    );
}

/// The scene coded again at [`COARSE_CRF`].
fn coarse(scene: &SceneSpec) -> SceneSpec {
    SceneSpec {
        name: format!("{}@{COARSE_CRF}", scene.name),
        encoding: ClipEncoding {
            crf: COARSE_CRF,
            ..scene.encoding
        },
        ..scene.clone()
    }
}

/// The gate (§4): the 24 drawn scenes at [`GATE_CRF`] meet every target; the six
/// coded at 20 are coded again at [`COARSE_CRF`], must be measured, and are scored
/// for information (docs/validation.md, "Robustness gate").
#[test]
fn drawn_scenes_are_measured_with_no_config_to_their_resolution() {
    let scenes = draw_scenes();
    assert!(scenes.len() >= 24);
    // Render, measure and score one scene ([`measured`]: its clip is removed unless
    // EULERDISK_ROBUSTNESS_KEEP=DIR keeps it). Every scene must be measured, the
    // coarse codes too.
    let measure = |scene: &SceneSpec| {
        let (truth, result) = measured(scene);
        let s = score(scene, truth, result.as_ref().map_err(String::as_str));
        eprintln!("{}", s.row);
        s
    };
    // The same frames coded coarser than the targets' footage: measured, and scored
    // for information.
    let coarse_scenes: Vec<SceneSpec> = scenes
        .iter()
        .filter(|s| s.encoding.crf == GATE_CRF[2])
        .map(coarse)
        .collect();
    // As many scenes at a time as rayon has threads (two on the CI's two cores):
    // rendering is parallel, the analysis mostly not, so one scene at a time left a
    // core idle for much of the test (216 s; 149 s so, docs/validation.md, "The test suite").
    // Each scene's bytes and result are its own, whatever runs beside it
    // (tests/determinism.rs).
    let (gate, coarse): (Vec<_>, Vec<_>) = rayon::join(
        || scenes.par_iter().map(measure).collect(),
        || coarse_scenes.par_iter().map(measure).collect(),
    );
    let mut table = String::from(HEADER);
    let mut failed = Vec::new();
    let mut errors = Vec::new();
    for (scene, s) in scenes.iter().zip(gate) {
        write!(table, "\n{}", s.row).expect("string");
        if !s.failures.is_empty() {
            failed.push(format!("{}: {}", scene.name, s.failures.join("; ")));
        }
        errors.extend(s.errors);
    }
    write!(table, "\n\n{}", error_budget(&errors)).expect("string");
    write!(table, "\n\nAt crf {COARSE_CRF}, for information:\n{HEADER}").expect("string");
    let mut coarse_misses = 0;
    for (scene, s) in coarse_scenes.iter().zip(coarse) {
        write!(table, "\n{}", s.row).expect("string");
        coarse_misses += usize::from(!s.failures.is_empty());
        // A scene's errors are missing only where it was not measured.
        if s.errors.is_none() {
            failed.push(format!("{}: {}", scene.name, s.failures.join("; ")));
        }
    }
    write!(
        table,
        "\n\n{coarse_misses} of the coarse codes miss a target of the gate's."
    )
    .expect("string");
    eprintln!("{table}");
    assert!(
        failed.is_empty(),
        "{} of {} scenes miss a target:\n{}\n\n{table}",
        failed.len(),
        scenes.len(),
        failed.join("\n")
    );
}
