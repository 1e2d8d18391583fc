//! Phone footage as it comes (issue 14): clips that `render` writes the way phones
//! store them, analysed with no hand-set option beyond the capture fps, against the
//! rendered truth and the same clip written plainly.

mod util;

use std::path::{Path, PathBuf};

use eulerdisk::analyse::{Experiment, analyse_clip};
use eulerdisk::config::ExperimentConfig;
use eulerdisk::footage::{self, Orientation};

/// `eulerdisk render` of a small side-view clip (n = 0.5, halt at 0.5 s, dark
/// plate) with `extra` options, into `dir/name`.
fn render(dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let mut args = vec![
        "render", "--n", "0.5", "--halt", "0.5", "--size", "480x320", "-o", name,
    ];
    args.extend_from_slice(extra);
    let out = util::eulerdisk(dir, &args);
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
    let plain = analyse(&render(dir.path(), "plain.mp4", &["--crf", "0"]));
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
        let dz = max_difference(&z_rim(&plain), &z_rim(&tagged));
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

    let plain = analyse(&render(dir.path(), "plain.mp4", &[]));
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
    let base = render(dir.path(), "limited.mp4", &["--crf", "0"]);
    let reference = analyse(&base);
    let signal = reference.plan.video_signal.clone().unwrap();
    assert_eq!((signal.bit_depth, signal.full_range), (8, false));
    let grey = last_frame_mean(&base);
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
        let dz = max_difference(&z_rim(&reference), &z_rim(&e));
        assert!(dz < 0.05, "{name}: z_rim differs by {dz} px");
    }
}
