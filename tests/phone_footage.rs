//! Phone footage as it comes (issue 14): clips that `render` writes the way phones
//! store them, analysed with no hand-set option beyond the capture fps, against the
//! rendered truth and the same clip written plainly.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use eulerdisk::analyse::{Experiment, analyse_clip};
use eulerdisk::config::ExperimentConfig;
use eulerdisk::footage::{self, Orientation};

/// `eulerdisk render` of a small side-view clip (n = 0.5, halt at 0.5 s unless
/// `extra` sets `--halt`, dark plate) with `extra` options, into `dir/name`.
fn render(dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let mut args = vec!["render", "--n", "0.5", "--size", "480x320", "-o", name];
    if !extra.contains(&"--halt") {
        args.extend_from_slice(&["--halt", "0.5"]);
    }
    args.extend_from_slice(extra);
    let out = crate::util::eulerdisk(dir, &args);
    assert!(
        out.status.success(),
        "render {extra:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    dir.join(name)
}

fn analyse(clip: &Path) -> Experiment {
    let config = ExperimentConfig::parse("fps = 480\n", Path::new("test.toml")).unwrap();
    analyse_clip(clip, &config, &|_, _| {}).unwrap_or_else(|e| panic!("{e}"))
}

/// The plain clip lossless (`render … --crf 0`) and its analysis, made once for the
/// test binary ([`shared`]).
fn plain_lossless() -> &'static (PathBuf, Experiment) {
    static CLIP: OnceLock<(PathBuf, Experiment)> = OnceLock::new();
    CLIP.get_or_init(|| shared("plain-crf0.mp4", &["--crf", "0"]))
}

/// The plain clip at `render`'s default crf and its analysis, made once for the test
/// binary ([`shared`]).
fn plain_default() -> &'static (PathBuf, Experiment) {
    static CLIP: OnceLock<(PathBuf, Experiment)> = OnceLock::new();
    CLIP.get_or_init(|| shared("plain.mp4", &[]))
}

/// A clip that two tests compare against, rendered with `extra` and analysed: into
/// Cargo's folder for test data (the same bytes on every run; `render` writes a
/// clip whole or not at all), not a temporary folder that one test would remove.
fn shared(name: &str, extra: &[&str]) -> (PathBuf, Experiment) {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("phone_footage");
    std::fs::create_dir_all(&dir).unwrap();
    let clip = render(&dir, name, extra);
    let e = analyse(&clip);
    (clip, e)
}

fn z_rim(e: &Experiment) -> Vec<Option<f64>> {
    e.frames.iter().map(|f| f.z_rim_px).collect()
}

/// The largest |Δz_rim| [px] between two series of the same frames.
fn max_difference(a: &[Option<f64>], b: &[Option<f64>]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| match (x, y) {
            (Some(x), Some(y)) => (x - y).abs(),
            (None, None) => 0.0,
            _ => f64::INFINITY,
        })
        .fold(0.0, f64::max)
}

/// §1: a clip stored turned and tagged with a display matrix (as a phone held
/// upright writes it) measures as the untagged original, for a quarter turn each
/// way, a half turn, and a mirror flip; `info` and the plan report the tag.
#[test]
fn a_rotation_tagged_clip_measures_as_the_original() {
    let dir = tempfile::tempdir().unwrap();
    // crf 0: lossless, so the only difference left is libswscale's chroma
    // filtering, which is not symmetric under a quarter turn.
    let (_, plain) = plain_lossless();
    let truth_n = 0.5;
    assert!(
        (plain.peaks_fit.fit.n - truth_n).abs() < 0.01,
        "{}",
        plain.peaks_fit.fit.n
    );
    assert!(plain.plan.orientation.is_identity());
    for (rotation, mirrored) in [("90", false), ("180", false), ("270", true), ("0", true)] {
        let mut extra = vec!["--crf", "0", "--rotation-tag", rotation];
        if mirrored {
            extra.push("--mirror-tag");
        }
        let name = format!("r{rotation}{}.mp4", if mirrored { "m" } else { "" });
        let clip = render(dir.path(), &name, &extra);
        let expected = Orientation::new(rotation.parse().unwrap(), mirrored).unwrap();

        let info = footage::probe(&clip).unwrap();
        assert_eq!(info.orientation, expected);
        assert_eq!(
            (info.width, info.height),
            (480, 320),
            "{expected}: displayed size"
        );

        let tagged = analyse(&clip);
        assert_eq!(tagged.plan.orientation, expected);
        assert_eq!((tagged.plan.width, tagged.plan.height), (480, 320));
        // The grey scene has no chroma but at the disk's anti-aliased edges: the
        // rotated chroma filter moves a rim height by under 0.01 px (0.0068 px
        // measured for a quarter turn, 0 for the mirror alone).
        let dz = max_difference(&z_rim(plain), &z_rim(&tagged));
        assert!(dz < 0.02, "{expected}: z_rim differs by {dz} px");
        let dn = (tagged.peaks_fit.fit.n - plain.peaks_fit.fit.n).abs();
        assert!(dn < 1e-3, "{expected}: n differs by {dn}");
    }
}

/// §2: duplicated frames (the previous frame's bytes again) and interpolated frames
/// (the rounded mean of their neighbours), written at known captures, are flagged
/// as such and left out of the fits; a clip without them has no such flag.
#[test]
fn duplicated_and_interpolated_frames_are_flagged_and_left_out() {
    use eulerdisk::signal::SkipReason;
    let dir = tempfile::tempdir().unwrap();
    let clip = render(
        dir.path(),
        "repeats.mp4",
        &["--duplicate", "100,181", "--interpolate", "150,220"],
    );
    let truth: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("repeats.truth.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(truth["duplicated"], serde_json::json!([100, 181]));
    assert_eq!(truth["interpolated"], serde_json::json!([150, 220]));

    let e = analyse(&clip);
    let flagged = |duplicated: bool| -> Vec<usize> {
        e.series
            .flags
            .iter()
            .filter(|f| match f.reason {
                SkipReason::DuplicatedFrame { .. } => duplicated,
                SkipReason::InterpolatedFrame { .. } => !duplicated,
                _ => false,
            })
            .map(|f| f.index)
            .collect()
    };
    // No frame is dropped, so file frames are captures.
    assert_eq!(flagged(true), vec![100, 181], "{:?}", e.series.flags);
    assert_eq!(flagged(false), vec![150, 220], "{:?}", e.series.flags);
    for k in [100, 150, 181, 220] {
        assert!(e.frames[k].z_rim_px.is_none(), "frame {k} reaches the fits");
    }
    // Prescribed n = 0.5; 24 peaks over 0.5 s at crf 23 fit it within 0.01 (the
    // four repeated frames left in moved it to 0.512 on this clip).
    let n = e.peaks_fit.fit.n;
    assert!((n - 0.5).abs() < 0.01, "n = {n}");

    let (_, plain) = plain_default();
    let repeats = plain.series.flags.iter().filter(|f| {
        matches!(
            f.reason,
            SkipReason::DuplicatedFrame { .. } | SkipReason::InterpolatedFrame { .. }
        )
    });
    assert_eq!(repeats.count(), 0, "{:?}", plain.series.flags);
}

/// The mean grey level of a clip's last frame (the disk at rest), as decoded.
fn last_frame_mean(clip: &Path) -> f64 {
    let mut source = footage::FrameSource::open(clip).unwrap();
    let last = source.expected_frames().unwrap() - 1;
    source.seek(last).unwrap();
    let v = source.next_frame().unwrap().unwrap().view;
    let sum: f64 = (0..v.height)
        .flat_map(|y| (0..v.width).map(move |x| (x, y)))
        .map(|(x, y)| f64::from(v.intensity(x, y)))
        .sum();
    sum / (v.width * v.height) as f64
}

/// §4: one scene stored 8-bit limited range, 8-bit full range, and 10-bit HDR (HLG
/// limited, PQ full, BT.2020) decodes to one brightness scale and gives one z_rim
/// series; the plan names the format, range, matrix and transfer function found.
#[test]
fn ten_bit_and_full_range_clips_measure_as_eight_bit_limited() {
    let dir = tempfile::tempdir().unwrap();
    // crf 0 (lossless) so that what differs is the storage, not the codec's error.
    let (base, reference) = plain_lossless();
    let signal = reference.plan.video_signal.clone().unwrap();
    assert_eq!((signal.bit_depth, signal.full_range), (8, false));
    let grey = last_frame_mean(base);
    for (name, extra, depth, full, transfer) in [
        ("full.mp4", &["--full-range"][..], 8, true, "unspecified"),
        (
            "hlg.mp4",
            &["--ten-bit", "--hdr", "hlg"][..],
            10,
            false,
            "HLG (ARIB STD-B67)",
        ),
        (
            "pq.mp4",
            &["--ten-bit", "--full-range", "--hdr", "pq"][..],
            10,
            true,
            "PQ (SMPTE ST 2084)",
        ),
    ] {
        let mut args = vec!["--crf", "0"];
        args.extend_from_slice(extra);
        let clip = render(dir.path(), name, &args);
        let e = analyse(&clip);
        let signal = e.plan.video_signal.clone().unwrap();
        assert_eq!(
            (signal.bit_depth, signal.full_range),
            (depth, full),
            "{name}: {signal}"
        );
        assert_eq!(signal.transfer, transfer, "{name}");
        if depth == 10 {
            assert_eq!(signal.matrix, "BT.2020", "{name}");
        }
        // One brightness scale: the rest frame's mean grey level agrees to half a
        // level (8-bit limited range rounds to 220 steps; a range read wrongly
        // moves it by 7 % of the level).
        let mean = last_frame_mean(&clip);
        assert!(
            (mean - grey).abs() < 0.5,
            "{name}: mean grey {mean} against {grey}"
        );
        // Issue §4: the same z_rim series within 0.05 px (0.027 px measured).
        let dz = max_difference(&z_rim(reference), &z_rim(&e));
        assert!(dz < 0.05, "{name}: z_rim differs by {dz} px");
    }
}

/// A clip's ground truth, `<stem>.truth.json` beside it.
fn truth(clip: &Path) -> serde_json::Value {
    let path = clip.with_file_name(format!(
        "{}.truth.json",
        clip.file_stem().unwrap().to_string_lossy()
    ));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Every written frame's MP4 timestamp as the truth gives it [s].
fn truth_container_times(truth: &serde_json::Value) -> Vec<f64> {
    truth["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["container_time_s"].as_f64().unwrap())
        .collect()
}

/// §2: a slow-motion section (capture 0.05–0.2 s stored 16× slowed, as a phone
/// stores 480 fps for playback at 30 between real-time ramps) away from the fit
/// window is found from the timestamps alone, timed by its own slow-down, and
/// the clip measures as the same frames stored at one rate: the same capture
/// times, t_φ and n. `info` lists the three sections.
#[test]
fn a_slowed_section_away_from_the_window_measures_as_the_plain_clip() {
    let dir = tempfile::tempdir().unwrap();
    // Halt at 0.8 s: the 0.5 s window starts at 0.3 s. crf 0 (lossless) so that
    // the two clips hold the same pixels and differ in their timestamps only.
    let long = ["--halt", "0.8", "--crf", "0"];
    let plain = analyse(&render(dir.path(), "plain.mp4", &long));
    let mut extra = long.to_vec();
    extra.extend_from_slice(&["--slow-section", "0.05:0.2:16"]);
    let clip = render(dir.path(), "slowed.mp4", &extra);

    // The truth: captures 24..96 (clip times 0.05–0.2 s at 480 fps) are 1/30 s
    // apart in the container, the others 1/480 s.
    let written = truth_container_times(&truth(&clip));
    for (k, w) in written.windows(2).enumerate() {
        let stored = if (24..96).contains(&k) { 30.0 } else { 480.0 };
        assert!((w[1] - w[0] - 1.0 / stored).abs() < 1e-9, "interval {k}");
    }

    let info = footage::probe(&clip).unwrap();
    let stamps = info.timestamps.as_ref().unwrap();
    let bounds: Vec<(usize, usize)> = stamps
        .sections
        .iter()
        .map(|s| (s.first_frame, s.last_frame))
        .collect();
    assert_eq!(bounds, vec![(0, 24), (24, 96), (96, 456)]);
    assert!(info.to_string().contains("3 sections of constant interval"));

    // With the capture fps configured, and with none (the fastest section is
    // taken as real time): the same sections and times.
    let none = ExperimentConfig::parse("", Path::new("test.toml")).unwrap();
    let unconfigured = analyse_clip(&clip, &none, &|_, _| {}).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(unconfigured.plan.fps.fps, 480.0);
    for slowed in [analyse(&clip), unconfigured] {
        let timing = slowed.plan.frame_times.as_ref().unwrap();
        let found: Vec<(usize, usize, f64)> = timing
            .sections
            .iter()
            .map(|s| (s.first_frame, s.last_frame, s.slowdown))
            .collect();
        assert_eq!(found.len(), 3, "{found:?}");
        for ((first, last, slowdown), (bounds, truth)) in
            found
                .into_iter()
                .zip([((0, 24), 1.0), ((24, 96), 16.0), ((96, 456), 1.0)])
        {
            assert_eq!((first, last), bounds);
            assert!((slowdown - truth).abs() < 1e-9, "{slowdown}");
        }
        for (a, b) in slowed.frames.iter().zip(&plain.frames) {
            assert!(
                (a.t_capture - b.t_capture).abs() < 1e-9,
                "frame {}",
                a.index
            );
            assert!(
                (a.container_time_s.unwrap() - written[a.index]).abs() < 1e-9,
                "frame {}",
                a.index
            );
        }
        // The same last frame of motion seen; t_φ, where the laws fitted to the
        // heights place the halt, moves with them as n does below: within a twentieth
        // of a frame (measured 1.2e-5 s).
        let seen = |e: &Experiment| e.frames[e.series.halt.index].index;
        assert_eq!(seen(&slowed), seen(&plain));
        let dt = (slowed.series.halt.t_phi - plain.series.halt.t_phi).abs();
        assert!(dt < 0.05 / 480.0, "t_φ differs by {dt} s");
        // The same pixels (lossless), so the same rim heights, up to the zero the
        // motion places: it reads its phase at the turning points, whose times are
        // themselves fitted from frame times that differ by 4e-15 s (measured 9e-6 px;
        // polishing the zero's own fit to convergence left that unchanged).
        let dz = max_difference(&z_rim(&slowed), &z_rim(&plain));
        assert!(dz < 1e-4, "z_rim differs by {dz} px");
        // The same exponent: within 0.002, as in tests/trust.rs, where times that
        // differ by 4e-15 s move one peak's refinement (measured 1.7e-4 here).
        let dn = (slowed.peaks_fit.fit.n - plain.peaks_fit.fit.n).abs();
        assert!(dn < 0.002, "n differs by {dn}");
    }
    // The plain clip's own n against the prescribed 0.5.
    assert!((plain.peaks_fit.fit.n - 0.5).abs() < 0.01);
}

/// §2: a slowed section (0.5–0.7 s, 8×) across the fit window (the last 0.5 s
/// before the halt at 0.8 s) is refused, and the message lists the sections'
/// frames, capture and container times and rates.
#[test]
fn a_slowed_section_across_the_window_is_refused_with_the_sections() {
    use eulerdisk::analyse::AnalyseError;
    let dir = tempfile::tempdir().unwrap();
    let clip = render(
        dir.path(),
        "crossing.mp4",
        &["--halt", "0.8", "--slow-section", "0.5:0.7:8"],
    );
    let config = ExperimentConfig::parse("fps = 480\n", Path::new("test.toml")).unwrap();
    let err = analyse_clip(&clip, &config, &|_, _| {}).unwrap_err();
    assert!(
        matches!(
            err,
            AnalyseError::AcrossSections {
                span: "fit window",
                ..
            }
        ),
        "{err}"
    );
    let message = err.to_string();
    for part in [
        "crossing.mp4",
        "fit window",
        "frames 0–240: t = 0.0000–0.5000 s captured",
        "frames 240–336: t = 0.5000–0.7000 s captured, 0.5000–2.1000 s in the container, \
         16.6667 ms a frame (60.000 fps), slowed 8.000×",
        "frames 336–456: t = 0.7000–0.9500 s captured",
    ] {
        assert!(message.contains(part), "`{part}` not in: {message}");
    }
}

/// §2/§5: `render --vfr-jitter` captures frames at jittered times (±5 % of a
/// frame here) and stamps them so; the same command writes the same bytes.
/// `analyse` times every frame by its timestamp (the truth's capture time, to
/// the container's 1/480000 s clock), `info` and the plan report the intervals'
/// spread, and the fit recovers n as on the unjittered clip.
#[test]
fn jittered_timestamps_are_the_frames_capture_times() {
    let dir = tempfile::tempdir().unwrap();
    let clip = render(dir.path(), "jittered.mp4", &["--vfr-jitter", "0.1"]);
    let bytes = std::fs::read(&clip).unwrap();
    let again = render(dir.path(), "again.mp4", &["--vfr-jitter", "0.1"]);
    assert!(
        bytes == std::fs::read(&again).unwrap(),
        "same command, same bytes"
    );
    let truth = truth(&clip);
    let halt = truth["halt_time"].as_f64().unwrap();
    let written = truth_container_times(&truth);
    let captured: Vec<f64> = truth["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["t"].as_f64().unwrap() + halt)
        .collect();
    // Jittered capture, stored at the capture clock: the container time is the
    // capture time.
    for (c, t) in written.iter().zip(&captured) {
        assert!((c - t).abs() < 1e-12, "{c} {t}");
    }
    let intervals: Vec<f64> = captured.windows(2).map(|w| w[1] - w[0]).collect();
    let longest = intervals.iter().copied().fold(0.0, f64::max);
    let shortest = intervals.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(longest > 1.04 / 480.0 && shortest < 0.96 / 480.0);

    let tick = 1.0 / 480_000.0;
    let jittered = analyse(&clip);
    let timing = jittered.plan.frame_times.as_ref().unwrap();
    assert_eq!(timing.sections.len(), 1);
    assert_eq!(timing.slowdown, 1.0);
    for (f, (c, t)) in jittered.frames.iter().zip(written.iter().zip(&captured)) {
        assert!(
            (f.container_time_s.unwrap() - c).abs() < 0.5 * tick,
            "{}",
            f.index
        );
        assert!((f.t_capture - t).abs() < 0.5 * tick, "frame {}", f.index);
    }
    // The spread reported is the written intervals' (1.4826 × MAD), as `info`
    // reads it from the packets.
    let median = |v: &[f64]| {
        let mut v = v.to_vec();
        v.sort_by(f64::total_cmp);
        0.5 * (v[(v.len() - 1) / 2] + v[v.len() / 2])
    };
    let m = median(&intervals);
    let deviations: Vec<f64> = intervals.iter().map(|d| (d - m).abs()).collect();
    let spread = 1.4826 * median(&deviations);
    assert!(spread > 0.02 / 480.0, "{spread}");
    assert!(
        (timing.interval_spread_s - spread).abs() < tick,
        "{timing:?}"
    );
    let info = footage::probe(&clip).unwrap();
    let stamps = info.timestamps.unwrap();
    assert!((stamps.interval_spread_s - spread).abs() < tick);
    assert_eq!(stamps.sections.len(), 1);

    // As good a fit as the unjittered clip's: n within 0.01 of the prescribed 0.5
    // for both (0.506 and 0.500 measured), the truth inside the 95 % interval.
    let (_, plain) = plain_default();
    for e in [&jittered, plain] {
        let fit = &e.peaks_fit.fit;
        assert!((fit.n - 0.5).abs() < 0.01, "n = {}", fit.n);
        assert!(fit.ci95_n.0 < 0.5 && 0.5 < fit.ci95_n.1, "{:?}", fit.ci95_n);
    }
    // The halt: t_φ, where the laws place it, a quarter frame after the true halt on
    // both (0.500525 s jittered, 0.500522 s plain), so within half a frame; the last
    // frame of motion seen before it (0.499925 s and 0.497917 s), within two frames.
    for e in [&jittered, plain] {
        let dt = (e.series.halt.t_phi - halt).abs();
        assert!(dt < 0.5 / 480.0, "t_φ {}", e.series.halt.t_phi);
        let seen = e.frames[e.series.halt.index].t_capture;
        assert!(
            seen <= halt && halt - seen < 2.05 / 480.0,
            "last motion seen {seen}"
        );
    }
}

/// §2 (the rest frames' seek): in a clip whose frame interval changes, a frame
/// sought by the time the container's packets list for it is that frame, where
/// frame number / average fps lands elsewhere.
#[test]
fn frames_are_sought_by_their_listed_times_in_a_variable_rate_clip() {
    let dir = tempfile::tempdir().unwrap();
    let clip = render(
        dir.path(),
        "slowed.mp4",
        &["--halt", "0.8", "--slow-section", "0.05:0.2:16"],
    );
    let mut source = footage::FrameSource::open(&clip).unwrap();
    let index = source.stream_index().unwrap().unwrap();
    let last = index.container_times_s.len() - 1;
    for k in [last - 4, 30, 100, 0, last] {
        source.seek_frame(k, &index).unwrap();
        let frame = source.next_frame().unwrap().unwrap();
        assert_eq!(frame.index, k);
        let t = frame.container_time_s.unwrap();
        assert!(
            (t - index.container_times_s[k]).abs() < 1e-9,
            "frame {k}: {t}"
        );
    }
    // By number / average fps, the rest frames' first lands elsewhere.
    source.seek(last - 4).unwrap();
    let t = source
        .next_frame()
        .unwrap()
        .unwrap()
        .container_time_s
        .unwrap();
    assert!((t - index.container_times_s[last - 4]).abs() > 1e-3, "{t}");
}
