//! The footage gate of issue 12 (§6): runs `eulerdisk analyse CLIP -o OUT/NAME` on every
//! `*.mp4` of a folder of independently rendered clips **with no config at all**, scores
//! each result against the clip's `NAME.gt.json` on the targets of issue 12 §5, prints one
//! row per clip, and exits 1 when any target on any clip is missed (0 only when every
//! target on every clip is met; 2 on a usage or I/O error).
//!
//! ```sh
//! scripts/check-footage [DIR] [--json FILE] [--out DIR] [--no-run]
//! ```
//!
//! # Time bases
//!
//! * **File clock**: `index / fps` from the clip's first frame, fps from `result.json`
//!   `plan.fps.fps`. eulerdisk's own clock, `frames.csv` `t_capture_s`, is the file
//!   clock but one frame later after each frame the rim's phase shows missing
//!   (`signal::missing_frames`). `frames.csv` has `index`, `t_s` (halt at 0) and
//!   `t_capture_s`, so the measured halt t_φ on eulerdisk's clock is
//!   `t_capture_s − t_s` (one value for every row). `peaks_fit.fit.t0` and
//!   `frames_fit.fit.t0` are relative to t_φ (fitted halt = t_φ + fit.t0); `peaks.csv`
//!   `t_s` is relative to t_φ; two-view t_β is `series.strip.stop.t_beta` in
//!   `result.json`, on eulerdisk's clock; `flags.csv` is scored by its file frame `index`.
//! * **Capture clock**: the truth's (`t0`, `t_phi`, `true_peaks.t`, `frames.t_true`).
//!   After a dropped frame the file clock lags the capture clock by a frame per drop.
//!
//! Every measured instant is taken to the capture clock through the frame index:
//! eulerdisk's time → fractional file index (`t_capture_s` interpolated over `index`;
//! t·fps, [`capture_time`], when frames.csv has fewer than two rows) →
//! `frames.t_true` interpolated over `frames.index`. Differences of capture times are
//! then compared with the truth.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

use serde::Serialize;
use serde_json::Value;

/// One frame at 480 fps, the unit of the "within 2 frames" targets [s].
const FRAME_S: f64 = 1.0 / 480.0;
/// The window before the halt in which z_rim and peaks are scored [s] (§5: "the last 0.5 s").
const WINDOW_S: f64 = 0.5;

// ---------------------------------------------------------------- ground truth

/// What the scorer reads from `NAME.gt.json` (see the footage set's README).
#[derive(Debug, Clone, Default)]
struct Truth {
    n: f64,
    /// The halt, capture clock [s].
    t0: f64,
    /// Two-view: the halt seen in the side view, t_φ (capture clock) [s].
    t_phi: Option<f64>,
    /// Two-view: t_β − t_φ [s].
    t_beta_minus_t_phi: Option<f64>,
    /// Amplitude of φ's oscillation about stationary rolling (0: none).
    osc_amp: f64,
    /// Capture indices that never reached the file.
    dropped: Vec<i64>,
    /// Per file frame (parallel): file index, capture index, capture time [s], true z_rim [px].
    index: Vec<f64>,
    capture_index: Vec<i64>,
    t_true: Vec<f64>,
    z_rim_px: Vec<f64>,
    /// True peaks of z_rim: capture time [s], φ [rad], at least 0.5 px.
    peak_t: Vec<f64>,
    peak_phi: Vec<f64>,
    peak_detectable: Vec<bool>,
    /// The elevation of the side camera's ray to the disk's near bottom rim at rest
    /// [rad], from `cameras` (the first whose name starts with "side"), the disk's final
    /// place `trajectory.X_f, Y_f` and its radius `disk.R`: atan(z_cam / (d_c − R)), d_c
    /// the camera's horizontal distance from the disk's centre. `None` without a camera.
    near_rim_elevation_rad: Option<f64>,
}

fn f64s(v: &Value, what: &str) -> Result<Vec<f64>, String> {
    v.as_array()
        .ok_or_else(|| format!("{what}: not an array"))?
        .iter()
        .map(|x| x.as_f64().ok_or_else(|| format!("{what}: not a number")))
        .collect()
}

fn num(v: &Value, what: &str) -> Result<f64, String> {
    v.as_f64()
        .ok_or_else(|| format!("{what}: missing or not a number"))
}

impl Truth {
    fn from_json(v: &Value) -> Result<Truth, String> {
        let fr = &v["frames"];
        let tp = &v["true_peaks"];
        Ok(Truth {
            n: num(&v["n"], "n")?,
            t0: num(&v["t0"], "t0")?,
            t_phi: v["t_phi"].as_f64(),
            t_beta_minus_t_phi: v["t_beta_minus_t_phi"].as_f64(),
            osc_amp: v["trajectory"]["osc_amp"].as_f64().unwrap_or(0.0),
            dropped: f64s(&v["dropped_capture_frames"], "dropped_capture_frames")
                .unwrap_or_default()
                .into_iter()
                .map(|k| k as i64)
                .collect(),
            index: f64s(&fr["index"], "frames.index")?,
            capture_index: f64s(&fr["capture_index"], "frames.capture_index")?
                .into_iter()
                .map(|k| k as i64)
                .collect(),
            t_true: f64s(&fr["t_true"], "frames.t_true")?,
            z_rim_px: f64s(&fr["z_rim_px"], "frames.z_rim_px")?,
            peak_t: f64s(&tp["t"], "true_peaks.t")?,
            peak_phi: f64s(&tp["phi"], "true_peaks.phi")?,
            peak_detectable: tp["detectable"]
                .as_array()
                .ok_or("true_peaks.detectable: not an array")?
                .iter()
                .map(|b| b.as_bool().unwrap_or(false))
                .collect(),
            near_rim_elevation_rad: near_rim_elevation(v),
        })
    }
}

/// See [`Truth::near_rim_elevation_rad`].
fn near_rim_elevation(v: &Value) -> Option<f64> {
    let (_, camera) = v["cameras"]
        .as_object()?
        .iter()
        .find(|(name, _)| name.starts_with("side"))?;
    let pos = f64s(&camera["pos"], "pos").ok()?;
    let trajectory = &v["trajectory"];
    let (x, y) = (
        trajectory["X_f"].as_f64().unwrap_or(0.0),
        trajectory["Y_f"].as_f64().unwrap_or(0.0),
    );
    let d_c = (pos.first()? - x).hypot(pos.get(1)? - y);
    Some(pos.get(2)?.atan2(d_c - v["disk"]["R"].as_f64()?))
}

// ---------------------------------------------------------------- metrics

/// A file-clock instant `t_file` [s] on the capture clock: the fractional file index
/// t·fps, with `t_true` interpolated linearly over `index` (extrapolated with the end
/// segments' slopes). This is what undoes dropped frames: the file clock assumes every
/// frame is 1/fps after the last, `t_true` knows the gaps.
fn capture_time(index: &[f64], t_true: &[f64], fps: f64, t_file: f64) -> f64 {
    interpolate(index, t_true, t_file * fps)
}

/// `ys` at `x`, linear between the sorted `xs` and extrapolated with the end segments'
/// slopes.
fn interpolate(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    let n = xs.len();
    assert!(n >= 2 && n == ys.len());
    let k = xs.partition_point(|&i| i <= x).clamp(1, n - 1);
    let (x0, x1, y0, y1) = (xs[k - 1], xs[k], ys[k - 1], ys[k]);
    y0 + (x - x0) * (y1 - y0) / (x1 - x0)
}

/// n within tolerance and the 95 % interval covering the truth (§5: "n within ±0.02 of
/// the truth (±0.03 on o04, whose φ oscillates …) … and each 95 % interval covers the
/// truth"). The ±0.03 applies to every clip whose truth has `trajectory.osc_amp > 0`.
fn n_tolerance(osc_amp: f64) -> f64 {
    if osc_amp > 0.0 { 0.03 } else { 0.02 }
}

/// How the measured peaks meet the true ones (§5: "every true peak of at least 0.5 px in
/// the last 0.5 s found, none spurious").
#[derive(Debug, Clone, PartialEq, Serialize)]
struct PeakMatch {
    /// Detectable true peaks in the window, and how many of them were matched.
    n_true: usize,
    found: usize,
    /// Measured peaks at or after the window's start matched to no true peak.
    spurious: usize,
    /// (measured, true) index pairs whose true peak is detectable and in the window:
    /// the peaks over which φ is scored.
    pairs: Vec<(usize, usize)>,
}

/// Matches measured peak times to true ones (all on the capture clock). Each measured
/// peak goes to its nearest true peak if it lies within a quarter of that peak's local
/// spacing (the smaller of its gaps to its neighbours in the true list, so the
/// tolerances of adjacent peaks never overlap); a true peak keeps only its nearest
/// measured peak, the others are duplicates and count as spurious. Scored: detectable
/// true peaks with t in [t0 − 0.5, t0]; measured peaks at t ≥ t0 − 0.5 (a measured peak
/// after the true halt is spurious too). Non-detectable true peaks are never required
/// but do excuse a measured peak that matches them.
fn match_peaks(
    true_t: &[f64],
    detectable: &[bool],
    meas_t: &[f64],
    t0: f64,
    window: f64,
) -> PeakMatch {
    let spacing = |j: usize| -> f64 {
        let before = (j > 0).then(|| true_t[j] - true_t[j - 1]);
        let after = (j + 1 < true_t.len()).then(|| true_t[j + 1] - true_t[j]);
        match (before, after) {
            (Some(a), Some(b)) => a.min(b),
            (Some(a), None) | (None, Some(a)) => a,
            (None, None) => f64::INFINITY,
        }
    };
    // For each true peak, the nearest measured peak within tolerance.
    let mut best: BTreeMap<usize, (usize, f64)> = BTreeMap::new();
    let mut unmatched = Vec::new();
    for (i, &t) in meas_t.iter().enumerate() {
        let nearest = (0..true_t.len())
            .min_by(|&a, &b| (true_t[a] - t).abs().total_cmp(&(true_t[b] - t).abs()));
        match nearest {
            Some(j) if (true_t[j] - t).abs() <= spacing(j) / 4.0 => {
                let d = (true_t[j] - t).abs();
                match best.get(&j) {
                    Some(&(_, od)) if od <= d => unmatched.push(i),
                    Some(&(other, _)) => {
                        unmatched.push(other);
                        best.insert(j, (i, d));
                    }
                    None => {
                        best.insert(j, (i, d));
                    }
                }
            }
            _ => unmatched.push(i),
        }
    }
    let in_window = |t: f64| t >= t0 - window && t <= t0;
    let required: Vec<usize> = (0..true_t.len())
        .filter(|&j| detectable[j] && in_window(true_t[j]))
        .collect();
    let pairs: Vec<(usize, usize)> = required
        .iter()
        .filter_map(|j| best.get(j).map(|&(i, _)| (i, *j)))
        .collect();
    PeakMatch {
        n_true: required.len(),
        found: pairs.len(),
        spurious: unmatched
            .iter()
            .filter(|&&i| meas_t[i] >= t0 - window)
            .count(),
        pairs,
    }
}

/// Median of |φ_meas/φ_true − 1| (§5: "φ at the peaks: median relative error ≤ 2 %").
fn median_rel_error(pairs: impl Iterator<Item = (f64, f64)>) -> Option<f64> {
    let mut e: Vec<f64> = pairs.map(|(m, t)| (m / t - 1.0).abs()).collect();
    if e.is_empty() {
        return None;
    }
    e.sort_by(f64::total_cmp);
    let k = e.len() / 2;
    Some(if e.len() % 2 == 1 {
        e[k]
    } else {
        (e[k - 1] + e[k]) / 2.0
    })
}

/// Dropped frames against eulerdisk's flags (§5: "every dropped frame flagged, no other
/// frame flagged").
#[derive(Debug, Clone, PartialEq, Serialize)]
struct DropScore {
    n_true: usize,
    flagged: usize,
    false_flags: usize,
}

/// A dropped capture frame k shows in the file at the first file frame whose capture
/// index exceeds k; a flag on that file frame or either neighbour (±1 file frame) counts
/// for it. Flags within ±1 of no true drop are false. A drop after the file's last frame
/// cannot show and is not counted.
fn score_drops(index: &[f64], capture_index: &[i64], dropped: &[i64], flags: &[i64]) -> DropScore {
    let shown: Vec<i64> = dropped
        .iter()
        .filter_map(|&k| {
            capture_index
                .iter()
                .position(|&c| c > k)
                .map(|p| index[p] as i64)
        })
        .collect();
    let near = |a: i64, b: i64| (a - b).abs() <= 1;
    DropScore {
        n_true: shown.len(),
        flagged: shown
            .iter()
            .filter(|&&s| flags.iter().any(|&f| near(f, s)))
            .count(),
        false_flags: flags
            .iter()
            .filter(|&&f| !shown.iter().any(|&s| near(f, s)))
            .count(),
    }
}

/// z_rim against the truth over the file frames with t_true in [t0 − 0.5, t0] (§5: "z_rim
/// RMS over the last 0.5 s before the halt ≤ 0.25 px"). Returns (RMS over frames with a
/// value, frames without one). `measured` maps file index → z_rim [px] (NaN: none).
fn zrim_rms(truth: &Truth, measured: &BTreeMap<i64, f64>) -> (Option<f64>, usize) {
    let (mut sum, mut count, mut misses) = (0.0, 0usize, 0usize);
    for k in 0..truth.index.len() {
        let t = truth.t_true[k];
        if t < truth.t0 - WINDOW_S || t > truth.t0 {
            continue;
        }
        match measured.get(&(truth.index[k] as i64)) {
            Some(z) if z.is_finite() => {
                sum += (z - truth.z_rim_px[k]).powi(2);
                count += 1;
            }
            _ => misses += 1,
        }
    }
    ((count > 0).then(|| (sum / count as f64).sqrt()), misses)
}

/// The heights' offset and gain against the truth over the last 0.5 s: the least-squares
/// line z − z_true = a + b·z_true [px, 1]. a is the error of z_rim's zero (the row
/// heights are counted from), b a scale or swing error; `None` with fewer than 3 frames.
fn height_offset_and_gain(truth: &Truth, measured: &BTreeMap<i64, f64>) -> Option<(f64, f64)> {
    let pairs: Vec<(f64, f64)> = (0..truth.index.len())
        .filter(|&k| (truth.t0 - WINDOW_S..=truth.t0).contains(&truth.t_true[k]))
        .filter_map(|k| {
            let z = *measured.get(&(truth.index[k] as i64))?;
            z.is_finite()
                .then(|| (truth.z_rim_px[k], z - truth.z_rim_px[k]))
        })
        .collect();
    if pairs.len() < 3 {
        return None;
    }
    let m = pairs.len() as f64;
    let (sx, sy) = pairs
        .iter()
        .fold((0.0, 0.0), |(sx, sy), &(x, y)| (sx + x, sy + y));
    let (mx, my) = (sx / m, sy / m);
    let (sxx, sxy) = pairs.iter().fold((0.0, 0.0), |(sxx, sxy), &(x, y)| {
        (sxx + (x - mx).powi(2), sxy + (x - mx) * (y - my))
    });
    let b = sxy / sxx;
    Some((my - b * mx, b))
}

/// The codec's smoothing over time, for information
/// ([`eulerdisk::footage::smoothing_by_picture_type`]): over the scored window, each
/// frame's error against the true second difference of the heights (per frame, from
/// the frames captured just before and after it, so not beside a dropped frame).
fn codec_smoothing(
    truth: &Truth,
    measured: &BTreeMap<i64, f64>,
    types: &BTreeMap<i64, char>,
) -> [Option<f64>; 2] {
    let frames = (1..truth.index.len().saturating_sub(1)).filter_map(|k| {
        let consecutive = truth.capture_index[k - 1] + 1 == truth.capture_index[k]
            && truth.capture_index[k] + 1 == truth.capture_index[k + 1];
        if !consecutive || !(truth.t0 - WINDOW_S..=truth.t0).contains(&truth.t_true[k]) {
            return None;
        }
        let file = truth.index[k] as i64;
        let z = *measured.get(&file)?;
        let second = truth.z_rim_px[k + 1] - 2.0 * truth.z_rim_px[k] + truth.z_rim_px[k - 1];
        z.is_finite()
            .then(|| (types.get(&file).copied(), second, z - truth.z_rim_px[k]))
    });
    eulerdisk::footage::smoothing_by_picture_type(frames)
}

// ---------------------------------------------------------------- eulerdisk's output

/// A power-law fit from `result.json` (`peaks_fit.fit` or `frames_fit.fit`).
#[derive(Debug, Clone, Copy, Serialize)]
struct Fit {
    n: f64,
    ci95_n: (f64, f64),
    /// Fitted halt relative to t_φ [s].
    t0: f64,
}

fn fit(v: &Value) -> Option<Fit> {
    Some(Fit {
        n: v["n"].as_f64()?,
        ci95_n: (v["ci95_n"][0].as_f64()?, v["ci95_n"][1].as_f64()?),
        t0: v["t0"].as_f64()?,
    })
}

/// What the scorer reads from one `analyse` output folder.
#[derive(Debug, Clone, Default)]
struct Measured {
    fps: f64,
    /// t_φ on eulerdisk's clock [s].
    t_phi: f64,
    /// eulerdisk's clock: (`t_capture_s`, file `index`) of every frames.csv row.
    clock: Vec<(f64, f64)>,
    peaks_fit: Option<Fit>,
    frames_fit: Option<Fit>,
    /// Two-view t_β on eulerdisk's clock [s].
    t_beta: Option<f64>,
    /// File index → z_rim [px] (NaN: no value).
    z_rim_px: BTreeMap<i64, f64>,
    /// File index → the codec's picture type (frames.csv `picture_type`).
    picture_types: BTreeMap<i64, char>,
    /// Peaks: time relative to t_φ [s], φ [rad].
    peaks: Vec<(f64, f64)>,
    /// Flagged file frames.
    flags: Vec<i64>,
    /// `plan.scale.near_rim_elevation_rad`: the camera's elevation at the near rim as
    /// measured [rad].
    near_rim_elevation_rad: Option<f64>,
    /// `precession`: the heights' φ over the precession's at the window's mean, k + c/x̄
    /// (eulerdisk::precession).
    precession_agreement: Option<f64>,
    /// `turn_timing.Ok`: n from the turns' timing alone and its 95 % interval
    /// (eulerdisk::turn_timing).
    turn_timing: Option<(f64, (f64, f64))>,
    /// `motion_fit`: n and t0 (on the halt's clock) of the motion fitted to every
    /// frame (eulerdisk::motion_fit).
    motion_fit: Option<(f64, f64)>,
}

fn read_csv(path: &Path) -> Result<Vec<BTreeMap<String, String>>, String> {
    let mut reader =
        csv::Reader::from_path(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let headers = reader.headers().map_err(|e| e.to_string())?.clone();
    reader
        .records()
        .map(|r| {
            let r = r.map_err(|e| format!("{}: {e}", path.display()))?;
            Ok(headers
                .iter()
                .zip(r.iter())
                .map(|(h, x)| (h.to_string(), x.to_string()))
                .collect())
        })
        .collect()
}

fn field(row: &BTreeMap<String, String>, name: &str) -> f64 {
    row.get(name)
        .and_then(|x| x.trim().parse().ok())
        .unwrap_or(f64::NAN)
}

impl Measured {
    fn read(dir: &Path) -> Result<Measured, String> {
        let text = fs::read_to_string(dir.join("result.json"))
            .map_err(|e| format!("{}/result.json: {e}", dir.display()))?;
        let result: Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
        let frames = read_csv(&dir.join("frames.csv"))?;
        let first = frames.first().ok_or("frames.csv: no rows")?;
        Ok(Measured {
            fps: num(&result["plan"]["fps"]["fps"], "result.json plan.fps.fps")?,
            t_phi: field(first, "t_capture_s") - field(first, "t_s"),
            clock: frames
                .iter()
                .map(|r| (field(r, "t_capture_s"), field(r, "index")))
                .filter(|(t, i)| t.is_finite() && i.is_finite())
                .collect(),
            peaks_fit: fit(&result["peaks_fit"]["fit"]),
            frames_fit: fit(&result["frames_fit"]["fit"]),
            t_beta: result["series"]["strip"]["stop"]["t_beta"].as_f64(),
            picture_types: frames
                .iter()
                .filter_map(|r| {
                    let kind = r.get("picture_type")?.chars().next()?;
                    Some((field(r, "index") as i64, kind))
                })
                .collect(),
            z_rim_px: frames
                .iter()
                .map(|r| (field(r, "index") as i64, field(r, "z_rim_px")))
                .collect(),
            peaks: read_csv(&dir.join("peaks.csv"))?
                .iter()
                .map(|r| (field(r, "t_s"), field(r, "phi_rad")))
                .collect(),
            flags: {
                // One entry per flagged frame (a frame may carry several reasons).
                let mut f: Vec<i64> = read_csv(&dir.join("flags.csv"))?
                    .iter()
                    .map(|r| field(r, "index") as i64)
                    .collect();
                f.sort_unstable();
                f.dedup();
                f
            },
            near_rim_elevation_rad: result["plan"]["scale"]["near_rim_elevation_rad"].as_f64(),
            turn_timing: {
                let t = &result["turn_timing"]["Ok"];
                match (
                    t["n"].as_f64(),
                    t["ci95_n"][0].as_f64(),
                    t["ci95_n"][1].as_f64(),
                ) {
                    (Some(n), Some(lo), Some(hi)) => Some((n, (lo, hi))),
                    _ => None,
                }
            },
            motion_fit: {
                let m = &result["motion_fit"];
                m["n"].as_f64().zip(m["t0"].as_f64())
            },
            precession_agreement: {
                let p = &result["precession"];
                match (
                    p["ratio"].as_f64(),
                    p["offset"].as_f64(),
                    p["mean_sin_phi"].as_f64(),
                ) {
                    (Some(k), Some(c), Some(mean)) => Some(k + c / mean),
                    _ => None,
                }
            },
        })
    }
}

// ---------------------------------------------------------------- scoring

/// One fit's n against the truth.
#[derive(Debug, Clone, Serialize)]
struct NScore {
    n: f64,
    delta: f64,
    covers: bool,
    ok: bool,
}

/// An estimate of n and its 95 % interval against the truth.
fn score_n(estimate: Option<(f64, (f64, f64))>, truth: &Truth) -> Option<NScore> {
    let (n, (lo, hi)) = estimate?;
    let delta = n - truth.n;
    let covers = lo <= truth.n && truth.n <= hi;
    Some(NScore {
        n,
        delta,
        covers,
        ok: delta.abs() <= n_tolerance(truth.osc_amp) && covers,
    })
}

/// One clip's scores; `None` where the clip was not measured or the quantity is absent.
#[derive(Debug, Clone, Default, Serialize)]
struct Score {
    clip: String,
    measured: bool,
    error: Option<String>,
    n_true: f64,
    n_tolerance: f64,
    n_peaks: Option<NScore>,
    n_frames: Option<NScore>,
    /// Fitted halt − true t0, capture clock [ms]: peaks fit (scored), per-frame fit (information).
    t0_err_ms: Option<f64>,
    t0_frames_fit_err_ms: Option<f64>,
    /// t_φ − true t_φ (two-view) or t0 (side), capture clock [frames of 1/480 s].
    t_phi_err_frames: Option<f64>,
    zrim_rms_px: Option<f64>,
    zrim_misses: usize,
    peaks: Option<PeakMatch>,
    phi_median_err: Option<f64>,
    /// Two-view: (t_β − t_φ) − truth [frames].
    t_beta_err_frames: Option<f64>,
    drops: Option<DropScore>,
    /// For information: the heights' offset a [px] and gain b of z − z_true = a + b·z_true
    /// over the last 0.5 s ([`height_offset_and_gain`]).
    height_offset_px: Option<f64>,
    height_gain: Option<f64>,
    /// For information: measured − true elevation of the camera at the near rim [°].
    elevation_err_deg: Option<f64>,
    /// The codec's smoothing over time, α of P and B pictures [frame²] (information).
    smoothing: [Option<f64>; 2],
    /// φ at the peaks, signed median of φ/φ_true − 1 (information).
    phi_signed_median_err: Option<f64>,
    /// The precession check's heights' φ over the precession's, − 1 (information).
    precession_err: Option<f64>,
    /// n from the turns' timing alone against the truth (information).
    n_turn_timing: Option<NScore>,
    /// The motion fitted to every frame: its n − the truth's, and its t0's error \[ms\]
    /// (information).
    motion_fit_err: Option<(f64, f64)>,
    /// Targets missed, by short name (see the legend).
    failed: Vec<&'static str>,
}

fn score(clip: &str, truth: &Truth, m: Option<&Measured>, error: Option<String>) -> Score {
    let mut s = Score {
        clip: clip.to_string(),
        measured: m.is_some(),
        error,
        n_true: truth.n,
        n_tolerance: n_tolerance(truth.osc_amp),
        ..Score::default()
    };
    let Some(m) = m else {
        s.failed.push("measured");
        return s;
    };
    // eulerdisk's clock to its fractional file index (frames.csv: `t_capture_s` by
    // `index`; the file clock unless the motion showed frames missing), then to the
    // truth's capture clock.
    let (times, index): (Vec<f64>, Vec<f64>) = m.clock.iter().copied().unzip();
    let cap = |t: f64| {
        if times.len() >= 2 {
            interpolate(&truth.index, &truth.t_true, interpolate(&times, &index, t))
        } else {
            capture_time(&truth.index, &truth.t_true, m.fps, t)
        }
    };
    let t_phi = cap(m.t_phi);

    // n: both fits within tolerance, intervals covering the truth.
    s.n_peaks = score_n(m.peaks_fit.map(|f| (f.n, f.ci95_n)), truth);
    s.n_frames = score_n(m.frames_fit.map(|f| (f.n, f.ci95_n)), truth);
    // Fitted halt within 2 ms (peaks fit).
    s.t0_err_ms = m.peaks_fit.map(|f| (cap(m.t_phi + f.t0) - truth.t0) * 1e3);
    s.t0_frames_fit_err_ms = m.frames_fit.map(|f| (cap(m.t_phi + f.t0) - truth.t0) * 1e3);
    // t_φ within 2 frames.
    let t_phi_err = t_phi - truth.t_phi.unwrap_or(truth.t0);
    s.t_phi_err_frames = Some(t_phi_err / FRAME_S);
    // z_rim RMS over the last 0.5 s.
    (s.zrim_rms_px, s.zrim_misses) = zrim_rms(truth, &m.z_rim_px);
    s.smoothing = codec_smoothing(truth, &m.z_rim_px, &m.picture_types);
    (s.height_offset_px, s.height_gain) = height_offset_and_gain(truth, &m.z_rim_px)
        .map_or((None, None), |(a, b)| (Some(a), Some(b)));
    s.elevation_err_deg = m
        .near_rim_elevation_rad
        .zip(truth.near_rim_elevation_rad)
        .map(|(got, want)| (got - want).to_degrees());
    // Peaks found, none spurious; φ at the peaks.
    let meas_t: Vec<f64> = m.peaks.iter().map(|&(t, _)| cap(m.t_phi + t)).collect();
    let pm = match_peaks(
        &truth.peak_t,
        &truth.peak_detectable,
        &meas_t,
        truth.t0,
        WINDOW_S,
    );
    let phi_pairs = || {
        pm.pairs
            .iter()
            .map(|&(i, j)| (m.peaks[i].1, truth.peak_phi[j]))
    };
    s.phi_median_err = median_rel_error(phi_pairs());
    s.phi_signed_median_err = {
        let mut e: Vec<f64> = phi_pairs().map(|(m, t)| m / t - 1.0).collect();
        e.sort_by(f64::total_cmp);
        (!e.is_empty()).then(|| e[e.len() / 2])
    };
    s.precession_err = m.precession_agreement.map(|a| a - 1.0);
    s.n_turn_timing = score_n(m.turn_timing, truth);
    s.motion_fit_err = m
        .motion_fit
        .map(|(n, t0)| (n - truth.n, (cap(m.t_phi + t0) - truth.t0) * 1e3));
    s.peaks = Some(pm);
    // Two-view: t_β − t_φ within 2 frames.
    if let Some(truth_gap) = truth.t_beta_minus_t_phi {
        s.t_beta_err_frames = m.t_beta.map(|tb| (cap(tb) - t_phi - truth_gap) / FRAME_S);
    }
    s.drops = Some(score_drops(
        &truth.index,
        &truth.capture_index,
        &truth.dropped,
        &m.flags,
    ));

    let n_ok = |x: &Option<NScore>| x.as_ref().is_some_and(|x| x.ok);
    if !n_ok(&s.n_peaks) {
        s.failed.push("n_peaks");
    }
    if !n_ok(&s.n_frames) {
        s.failed.push("n_frames");
    }
    if !s.t0_err_ms.is_some_and(|e| e.abs() <= 2.0) {
        s.failed.push("t0");
    }
    if !s.t_phi_err_frames.is_some_and(|e| e.abs() <= 2.0) {
        s.failed.push("t_phi");
    }
    if !(s.zrim_rms_px.is_some_and(|r| r <= 0.25) && s.zrim_misses == 0) {
        s.failed.push("zrim");
    }
    if s.peaks
        .as_ref()
        .is_none_or(|p| p.found < p.n_true || p.spurious > 0)
    {
        s.failed.push("peaks");
    }
    if !s.phi_median_err.is_some_and(|e| e <= 0.02) {
        s.failed.push("phi");
    }
    if truth.t_beta_minus_t_phi.is_some() && !s.t_beta_err_frames.is_some_and(|e| e.abs() <= 2.0) {
        s.failed.push("t_beta");
    }
    if s.drops
        .as_ref()
        .is_none_or(|d| d.flagged < d.n_true || d.false_flags > 0)
    {
        s.failed.push("drops");
    }
    s
}

// ---------------------------------------------------------------- table

fn mark(ok: bool) -> &'static str {
    if ok { "" } else { " ✗" }
}

fn row(s: &Score) -> String {
    let dash = || "–".to_string();
    if !s.measured {
        let e = s.error.as_deref().unwrap_or("no result");
        return format!(
            "| {} | no: {} | – | – | – | – | – | – | – | – | – | FAIL(measured) |",
            s.clip,
            e.replace('|', "/")
        );
    }
    let n = |x: &Option<NScore>| {
        x.as_ref().map_or("none ✗".into(), |x| {
            format!(
                "{:.3} ({:+.3}, {}){}",
                x.n,
                x.delta,
                if x.covers { "covers" } else { "misses" },
                mark(x.ok)
            )
        })
    };
    let fails = |name| s.failed.contains(&name);
    let t0 = s.t0_err_ms.map_or("– ✗".into(), |e| {
        let info = s
            .t0_frames_fit_err_ms
            .map_or(String::new(), |f| format!(" [frames {f:+.1}]"));
        format!("{e:+.2}{info}{}", mark(!fails("t0")))
    });
    let tphi = s
        .t_phi_err_frames
        .map_or(dash(), |e| format!("{e:+.2}{}", mark(!fails("t_phi"))));
    let zrim = s.zrim_rms_px.map_or("– ✗".into(), |r| {
        let misses = if s.zrim_misses > 0 {
            format!(", {} missing", s.zrim_misses)
        } else {
            String::new()
        };
        format!("{r:.3}{misses}{}", mark(!fails("zrim")))
    });
    let peaks = s.peaks.as_ref().map_or(dash(), |p| {
        format!(
            "{}/{}, {} spurious{}",
            p.found,
            p.n_true,
            p.spurious,
            mark(!fails("peaks"))
        )
    });
    let phi = s.phi_median_err.map_or("– ✗".into(), |e| {
        format!("{:.2}{}", e * 100.0, mark(!fails("phi")))
    });
    let tbeta = match (s.t_beta_err_frames, fails("t_beta")) {
        (Some(e), f) => format!("{e:+.2}{}", mark(!f)),
        (None, true) => "none ✗".into(),
        (None, false) => dash(),
    };
    let drops = s.drops.as_ref().map_or(dash(), |d| {
        format!(
            "{}/{}, {} false{}",
            d.flagged,
            d.n_true,
            d.false_flags,
            mark(!fails("drops"))
        )
    });
    let verdict = if s.failed.is_empty() {
        "PASS".into()
    } else {
        format!("FAIL({})", s.failed.join(","))
    };
    format!(
        "| {} | yes | {} | {} | {t0} | {tphi} | {zrim} | {peaks} | {phi} | {tbeta} | {drops} | {verdict} |",
        s.clip,
        n(&s.n_peaks),
        n(&s.n_frames)
    )
}

const HEADER: &str = "| clip | measured | n peaks fit (Δ, CI) | n per-frame fit (Δ, CI) | t0 err ms | tφ err frames | z_rim RMS px | peaks found/true, spurious | φ med err % | tβ−tφ err frames | drops flagged/true, false | verdict |\n|---|---|---|---|---|---|---|---|---|---|---|---|";

/// The information table: what the targets rest on, not scored.
const INFO_HEADER: &str = "| clip | heights' offset a px | heights' gain b % | ε at the near rim, err ° | φ at the peaks, signed median err % | precession check: φ heights/precession − 1, % | codec smoothing α P / B, frame² | n from the turns' timing (Δ, CI) | motion fit: n Δ, t0 err ms |\n|---|---|---|---|---|---|---|---|---|";

fn info_row(s: &Score) -> String {
    let show = |x: Option<f64>, scale: f64, digits: usize| {
        x.map_or("–".into(), |x| format!("{:+.*}", digits, scale * x))
    };
    let timing = s.n_turn_timing.as_ref().map_or("–".into(), |x| {
        format!(
            "{:.3} ({:+.3}, {})",
            x.n,
            x.delta,
            if x.covers { "covers" } else { "misses" }
        )
    });
    let motion = s
        .motion_fit_err
        .map_or("–".into(), |(dn, dt0)| format!("{dn:+.3}, {dt0:+.2}"));
    format!(
        "| {} | {} | {} | {} | {} | {} | {} / {} | {timing} | {motion} |",
        s.clip,
        show(s.height_offset_px, 1.0, 3),
        show(s.height_gain, 100.0, 2),
        show(s.elevation_err_deg, 1.0, 2),
        show(s.phi_signed_median_err, 100.0, 2),
        show(s.precession_err, 100.0, 2),
        show(s.smoothing[0], 1.0, 3),
        show(s.smoothing[1], 1.0, 3)
    )
}

/// RMS and largest magnitude of the values present, as "RMS r (largest m)".
fn rms_and_largest(values: impl Iterator<Item = Option<f64>>) -> String {
    let v: Vec<f64> = values.flatten().collect();
    if v.is_empty() {
        return "–".into();
    }
    let rms = (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    let largest = v
        .iter()
        .copied()
        .fold(0.0, |m: f64, x| if x.abs() > m.abs() { x } else { m });
    format!("RMS {rms:.3} (largest {largest:+.3})")
}

const INFO_LEGEND: &str = "\
For information, not targets: the heights against the truth over the same 0.5 s as a least-squares
line z − z_true = a + b·z_true (a: the error of z_rim's zero, b: of its scale or swing), and the
camera's elevation at the near bottom rim as measured (plan.json scale.near_rim_elevation_rad)
against the truth's side camera; φ at the peaks' signed error, and the precession check
(result.json precession: φ from the heights over φ that stationary rolling, eq. 2.29 corrected,
gives the precession rate, at the window's mean), which needs no truth. This footage's truth
follows eq. 2.29 as printed, whose φ(ψ̇) is 0.3–1.3 % smaller at φ = 0.005–0.02 rad. Last, the
codec's smoothing over time: each frame's error against the true heights' second difference per
frame, e = a + α z″, one α for the P and one for the B pictures (frames.csv picture_type): a
temporal low-pass of variance 2α frame² that reads the peaks low and the troughs high. And n from
the turns' timing alone (result.json turn_timing: the times of the peaks and troughs at their
counted ψ, no height, scale or zero), with its 95 % interval; the truth's eq. 2.29 as printed
reads it about 0.005 high (0.0047–0.0056 fitted to the true peaks' times). Last, the motion
fitted to every frame of the window (result.json motion_fit): its n against the truth's and its t0
(the end of the motion) against the truth's t0, on the capture clock.";

const LEGEND: &str = "\
Targets (issue 12 §5), per clip, no config: measured; n within ±0.02 of the truth (±0.03 when the
truth's φ oscillates, trajectory.osc_amp > 0) and the 95 % CI covering it, for both fits (n_peaks,
n_frames); fitted halt (peaks fit) within 2 ms of t0 (t0; the per-frame fit's is in brackets, for
information); t_φ within 2 frames (t_phi); z_rim RMS over t_true in [t0 − 0.5 s, t0] ≤ 0.25 px with
no frame missing (zrim); every true peak ≥ 0.5 px in that window found, none spurious (peaks); φ at
the peaks, median |φ/φ_true − 1| ≤ 2 % (phi); two-view: t_β − t_φ within 2 frames (t_beta); every
dropped frame flagged (±1 file frame), no other (drops). Errors are measured − true, on the capture
clock; a frame is 1/480 s. ✗ marks a missed target.";

// ---------------------------------------------------------------- main

struct Args {
    dir: PathBuf,
    bin: PathBuf,
    out: Option<PathBuf>,
    json: Option<PathBuf>,
    no_run: bool,
}

const USAGE: &str = "usage: check_footage [--bin EULERDISK] [--out DIR] [--no-run] [--json FILE] [FOOTAGE_DIR]
  FOOTAGE_DIR  clips NAME.mp4 with NAME.gt.json (default: ../shared/footage-open beside the repository)
  --bin        the eulerdisk binary (default: target/release/eulerdisk of the repository)
  --out DIR    keep the analyses in DIR/NAME (and DIR/NAME.log) instead of a temporary folder
  --no-run     score the analyses already in --out DIR without running analyse
  --json FILE  also write the scores as JSON";

fn parse_args() -> Result<Args, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut a = Args {
        dir: root.join("../shared/footage-open"),
        bin: root.join("target/release/eulerdisk"),
        out: None,
        json: None,
        no_run: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut value = |name: &str| {
            it.next()
                .map(PathBuf::from)
                .ok_or(format!("{name} needs a value"))
        };
        match arg.as_str() {
            "--bin" => a.bin = value("--bin")?,
            "--out" => a.out = Some(value("--out")?),
            "--json" => a.json = Some(value("--json")?),
            "--no-run" => a.no_run = true,
            "-h" | "--help" => return Err(String::new()),
            s if s.starts_with('-') => return Err(format!("unknown option {s}")),
            _ => a.dir = PathBuf::from(arg),
        }
    }
    if a.no_run && a.out.is_none() {
        return Err("--no-run needs --out DIR".into());
    }
    Ok(a)
}

/// The first line of the analyser's error (the first `error:` line, else the last
/// line), without the `error: CLIP: ` prefix that every row would repeat.
fn first_error_line(log: &str, clip: &Path) -> String {
    let line = log
        .lines()
        .find(|l| l.starts_with("error"))
        .or_else(|| log.lines().rfind(|l| !l.trim().is_empty()))
        .unwrap_or("no output");
    let line = line.strip_prefix("error: ").unwrap_or(line);
    let prefix = format!("{}: ", clip.display());
    line.strip_prefix(prefix.as_str())
        .unwrap_or(line)
        .to_string()
}

/// Runs `analyse` on one clip (unless `no_run`) and reads its output, or the error.
fn analyse(args: &Args, clip: &Path, out: &Path) -> Result<Measured, String> {
    let mut log = out.as_os_str().to_owned();
    log.push(".log");
    let log = PathBuf::from(log);
    if !args.no_run {
        let _ = fs::remove_dir_all(out);
        let run = Command::new(&args.bin)
            .arg("analyse")
            .arg(clip)
            .arg("-o")
            .arg(out)
            .output()
            .map_err(|e| format!("cannot run {}: {e}", args.bin.display()))?;
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&run.stderr),
            String::from_utf8_lossy(&run.stdout)
        );
        let _ = fs::write(&log, &text);
        if !run.status.success() {
            return Err(first_error_line(
                &String::from_utf8_lossy(&run.stderr),
                clip,
            ));
        }
    }
    if !out.join("result.json").exists() {
        let text = fs::read_to_string(&log).unwrap_or_default();
        return Err(first_error_line(&text, clip));
    }
    Measured::read(out)
}

fn run() -> Result<bool, String> {
    let args = parse_args()?;
    let mut clips: Vec<PathBuf> = fs::read_dir(&args.dir)
        .map_err(|e| format!("{}: {e}", args.dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "mp4"))
        .collect();
    clips.sort();
    if clips.is_empty() {
        return Err(format!("no *.mp4 in {}", args.dir.display()));
    }
    let temp = tempfile::tempdir().map_err(|e| e.to_string())?;
    let out_root = args
        .out
        .clone()
        .unwrap_or_else(|| temp.path().to_path_buf());
    fs::create_dir_all(&out_root).map_err(|e| e.to_string())?;

    println!("{HEADER}");
    let mut scores = Vec::new();
    for clip in &clips {
        let name = clip.file_stem().unwrap().to_string_lossy().to_string();
        let gt_path = clip.with_file_name(format!("{name}.gt.json"));
        let gt: Value = serde_json::from_str(
            &fs::read_to_string(&gt_path).map_err(|e| format!("{}: {e}", gt_path.display()))?,
        )
        .map_err(|e| format!("{}: {e}", gt_path.display()))?;
        let truth = Truth::from_json(&gt).map_err(|e| format!("{}: {e}", gt_path.display()))?;
        let s = match analyse(&args, clip, &out_root.join(&name)) {
            Ok(m) => score(&name, &truth, Some(&m), None),
            Err(e) => score(&name, &truth, None, Some(e)),
        };
        println!("{}", row(&s));
        scores.push(s);
    }
    println!("\n{INFO_HEADER}");
    for s in &scores {
        println!("{}", info_row(s));
    }
    println!(
        "| over the clips | offset {} px | | ε err {} ° | | {} % | | Δ {}, {} of {} cover | Δn {}, t0 {} ms |\n\n{INFO_LEGEND}",
        rms_and_largest(scores.iter().map(|s| s.height_offset_px)),
        rms_and_largest(scores.iter().map(|s| s.elevation_err_deg)),
        rms_and_largest(scores.iter().map(|s| s.precession_err.map(|x| 100.0 * x))),
        rms_and_largest(
            scores
                .iter()
                .map(|s| s.n_turn_timing.as_ref().map(|x| x.delta))
        ),
        scores
            .iter()
            .filter(|s| s.n_turn_timing.as_ref().is_some_and(|x| x.covers))
            .count(),
        scores.iter().filter(|s| s.n_turn_timing.is_some()).count(),
        rms_and_largest(scores.iter().map(|s| s.motion_fit_err.map(|e| e.0))),
        rms_and_largest(scores.iter().map(|s| s.motion_fit_err.map(|e| e.1))),
    );
    let measured = scores.iter().filter(|s| s.measured).count();
    let passed = scores.iter().filter(|s| s.failed.is_empty()).count();
    println!(
        "\n{measured} of {} measured, {passed} of {} meet every target.\n\n{LEGEND}",
        scores.len(),
        scores.len()
    );
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&scores).map_err(|e| e.to_string())?;
        fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(passed == scores.len())
}

fn main() -> ExitCode {
    match run() {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) if e.is_empty() => {
            println!("{USAGE}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("check_footage: {e}\n{USAGE}");
            ExitCode::from(2)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 10 file frames of a 480 fps clip whose capture frame 4 was dropped: file frame 4
    /// is capture frame 5.
    fn dropped_clip() -> (Vec<f64>, Vec<i64>, Vec<f64>) {
        let index: Vec<f64> = (0..10).map(f64::from).collect();
        let capture: Vec<i64> = (0..10).map(|i| if i < 4 { i } else { i + 1 }).collect();
        let t_true = capture.iter().map(|&c| c as f64 / 480.0).collect();
        (index, capture, t_true)
    }

    #[test]
    fn capture_time_follows_dropped_frames() {
        let (index, _, t_true) = dropped_clip();
        let at = |t| capture_time(&index, &t_true, 480.0, t);
        // Before the drop the clocks agree; after it, the capture clock is a frame ahead.
        assert!((at(2.0 / 480.0) - 2.0 / 480.0).abs() < 1e-12);
        assert!((at(6.0 / 480.0) - 7.0 / 480.0).abs() < 1e-12);
        // Half-way between file frames 3 and 4 (captures 3 and 5): capture frame 4.
        assert!((at(3.5 / 480.0) - 4.0 / 480.0).abs() < 1e-12);
        // Beyond the ends, the end segments' slopes.
        assert!((at(-1.0 / 480.0) + 1.0 / 480.0).abs() < 1e-12);
        assert!((at(11.0 / 480.0) - 12.0 / 480.0).abs() < 1e-12);
    }

    #[test]
    fn drops_accept_one_frame_either_side_and_count_false_flags() {
        let (index, capture, _) = dropped_clip();
        // Capture 4 shows at file frame 4 (first with capture index > 4).
        let s = |flags: &[i64]| score_drops(&index, &capture, &[4], flags);
        assert_eq!(
            s(&[4]),
            DropScore {
                n_true: 1,
                flagged: 1,
                false_flags: 0
            }
        );
        assert_eq!(
            s(&[3]),
            DropScore {
                n_true: 1,
                flagged: 1,
                false_flags: 0
            }
        );
        assert_eq!(
            s(&[5]),
            DropScore {
                n_true: 1,
                flagged: 1,
                false_flags: 0
            }
        );
        assert_eq!(
            s(&[6, 1]),
            DropScore {
                n_true: 1,
                flagged: 0,
                false_flags: 2
            }
        );
        assert_eq!(
            s(&[]),
            DropScore {
                n_true: 1,
                flagged: 0,
                false_flags: 0
            }
        );
        let none = score_drops(&index, &capture, &[], &[7]);
        assert_eq!(
            none,
            DropScore {
                n_true: 0,
                flagged: 0,
                false_flags: 1
            }
        );
    }

    #[test]
    fn peaks_match_within_a_quarter_spacing() {
        // True peaks every 10 ms up to 5 ms before the halt at 1.0 s, the last one too
        // small to detect; 49 detectable ones in the window [0.5, 1.0] s (k = 10 … 58).
        let true_t: Vec<f64> = (0..60).map(|k| 0.405 + 0.01 * k as f64).collect();
        let mut detectable = vec![true; 60];
        detectable[59] = false;
        let t0 = 1.0;
        // All detectable ones in the window, 2 ms off: all found, none spurious.
        let good: Vec<f64> = true_t[..59].iter().map(|t| t + 0.002).collect();
        let m = match_peaks(&true_t, &detectable, &good, t0, 0.5);
        assert_eq!((m.n_true, m.found, m.spurious), (49, 49, 0));
        assert_eq!(m.pairs.len(), 49);
        // One missing, one 3 ms off (beyond 10/4 = 2.5 ms: spurious and missing), one
        // duplicate, one on the undetectable peak (allowed), one after the halt.
        let mut meas = good.clone();
        meas.remove(20);
        meas[30] += 0.001;
        meas.push(true_t[40] + 0.0005);
        meas.push(true_t[59]);
        meas.push(1.02);
        let m = match_peaks(&true_t, &detectable, &meas, t0, 0.5);
        assert_eq!(m.n_true, 49);
        // Missing: peak 20 (removed) and 31 (meas[30] is true peak 31 + 3 ms).
        assert_eq!(m.found, 47);
        assert_eq!(m.spurious, 3, "3 ms off, duplicate, after the halt");
        // Measured peaks before the window are not scored.
        let early = match_peaks(&true_t, &detectable, &[0.3], t0, 0.5);
        assert_eq!(early.spurious, 0);
    }

    #[test]
    fn median_of_relative_errors() {
        let pairs = [(1.01, 1.0), (0.97, 1.0), (2.0, 2.0), (1.1, 1.0)];
        let e = median_rel_error(pairs.into_iter()).unwrap();
        assert!((e - 0.02).abs() < 1e-12, "{e}");
        assert_eq!(median_rel_error(std::iter::empty()), None);
    }

    #[test]
    fn scores_a_hand_made_result() {
        // Halt at capture 1.0 s, capture frame 100 dropped (the file clock lags by a frame
        // after it); measured t_φ on the file clock is 479/480 s = capture 1.0 s.
        let n_frames = 600;
        let capture: Vec<i64> = (0..n_frames)
            .map(|i| if i < 100 { i } else { i + 1 })
            .collect();
        let t_true: Vec<f64> = capture.iter().map(|&c| c as f64 / 480.0).collect();
        let z_rim_px: Vec<f64> = t_true.iter().map(|&t| (1.0 - t).max(0.0) * 10.0).collect();
        let truth = Truth {
            n: 0.5,
            t0: 1.0,
            dropped: vec![100],
            index: (0..n_frames).map(|i| i as f64).collect(),
            capture_index: capture,
            t_true,
            z_rim_px: z_rim_px.clone(),
            peak_t: vec![0.6, 0.7, 0.8, 0.9],
            peak_phi: vec![0.04, 0.03, 0.02, 0.01],
            peak_detectable: vec![true; 4],
            ..Truth::default()
        };
        let fit = Fit {
            n: 0.51,
            ci95_n: (0.49, 0.53),
            t0: 0.001,
        };
        let m = Measured {
            fps: 480.0,
            t_phi: 479.0 / 480.0,
            peaks_fit: Some(fit),
            frames_fit: Some(Fit {
                ci95_n: (0.505, 0.52),
                ..fit
            }),
            z_rim_px: (0..n_frames)
                .map(|i| (i as i64, z_rim_px[i as usize] + 0.1))
                .collect(),
            // Peak times relative to t_φ: exact.
            peaks: vec![(-0.4, 0.0404), (-0.3, 0.0303), (-0.2, 0.0198), (-0.1, 0.01)],
            flags: vec![100],
            ..Measured::default()
        };
        let s = score("c", &truth, Some(&m), None);
        assert_eq!(s.failed, vec!["n_frames"], "{s:?}");
        assert!((s.t_phi_err_frames.unwrap()).abs() < 1e-9);
        assert!((s.t0_err_ms.unwrap() - 1.0).abs() < 1e-9);
        assert!((s.zrim_rms_px.unwrap() - 0.1).abs() < 1e-9);
        // Every height 0.1 px high: an offset, no gain.
        assert!((s.height_offset_px.unwrap() - 0.1).abs() < 1e-9);
        assert!(s.height_gain.unwrap().abs() < 1e-9);
        assert!((s.phi_median_err.unwrap() - 0.01).abs() < 1e-9);
        // The same measurement on eulerdisk's clock with the lost capture counted
        // (frames.csv `t_capture_s` a frame later from file frame 100 on, t_φ at
        // capture 480): the same scores.
        let counted = Measured {
            clock: (0..n_frames as usize)
                .map(|i| (truth.capture_index[i] as f64 / 480.0, i as f64))
                .collect(),
            t_phi: 1.0,
            ..m.clone()
        };
        let on_capture_clock = score("c", &truth, Some(&counted), None);
        assert_eq!(on_capture_clock.failed, s.failed);
        assert!((on_capture_clock.t_phi_err_frames.unwrap()).abs() < 1e-9);
        assert!((on_capture_clock.t0_err_ms.unwrap() - 1.0).abs() < 1e-9);
        assert_eq!(on_capture_clock.peaks, s.peaks);
        let unmeasured = score("c", &truth, None, Some("error: x".into()));
        assert_eq!(unmeasured.failed, vec!["measured"]);
    }

    /// Heights low-passed over time by α = 0.02 frame² on P pictures and 0.15 on B
    /// (e = 0.03 + α z″, I pictures only offset), in a GOP of I B B P …, with capture
    /// frame 300 dropped: both α come back, and the frames beside the gap, whose
    /// second difference spans it, are left out.
    #[test]
    fn codec_smoothing_per_picture_type() {
        let n_frames = 480;
        let capture: Vec<i64> = (0..n_frames)
            .map(|i| if i < 300 { i } else { i + 1 })
            .collect();
        let t_true: Vec<f64> = capture.iter().map(|&c| c as f64 / 480.0).collect();
        let height = |c: f64| 3.0 * (1.0 + (0.6 * c).cos());
        let z_rim_px: Vec<f64> = capture.iter().map(|&c| height(c as f64)).collect();
        let truth = Truth {
            t0: 1.0,
            index: (0..n_frames).map(|i| i as f64).collect(),
            capture_index: capture.clone(),
            t_true,
            z_rim_px,
            ..Truth::default()
        };
        let kind = |i: i64| match i % 12 {
            0 => 'I',
            k if k % 3 == 0 => 'P',
            _ => 'B',
        };
        let measured = capture
            .iter()
            .enumerate()
            .map(|(i, &c)| {
                let c = c as f64;
                let second = height(c + 1.0) - 2.0 * height(c) + height(c - 1.0);
                let alpha = match kind(i as i64) {
                    'P' => 0.02,
                    'B' => 0.15,
                    _ => 0.0,
                };
                // Beside the gap the true second difference is not this one.
                let gap = if i == 299 || i == 300 { 5.0 } else { 0.0 };
                (i as i64, height(c) + 0.03 + alpha * second + gap)
            })
            .collect();
        let types = (0..n_frames).map(|i| (i, kind(i))).collect();
        let [p, b] = codec_smoothing(&truth, &measured, &types);
        assert!((p.unwrap() - 0.02).abs() < 1e-9, "{p:?}");
        assert!((b.unwrap() - 0.15).abs() < 1e-9, "{b:?}");
        assert_eq!(
            codec_smoothing(&truth, &measured, &BTreeMap::new()),
            [None, None]
        );
    }
}
