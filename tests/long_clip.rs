//! Long clips (issue 14 §3): `analyse` decodes a span at the end of a clip longer
//! than 8 s, found from the container's index and grown back by key frames, and
//! measures the frames it decodes as the whole-clip pass does.

use std::path::Path;

use eulerdisk::analyse::{Decoding, analyse_clip_decoding};
use eulerdisk::config::ExperimentConfig;
use eulerdisk::report::experiment::write_experiment;
use eulerdisk::signal::SkipReason;
use serde_json::Value;

/// A 12.5 s clip (n = 0.5, halt at 9 s, 3.5 s of post-flat spin and rest after
/// it, x264's key frame every 250 frames, capture 4200 (8.75 s) a duplicate of
/// the one before) analysed near its end and whole. The first span, the last
/// 4 s, holds only 0.5 s of motion, so it must grow back.
#[test]
fn a_span_near_the_end_measures_as_the_whole_clip() {
    let dir = tempfile::tempdir().unwrap();
    let out = crate::util::eulerdisk(
        dir.path(),
        &[
            "render",
            "--n",
            "0.5",
            "--halt",
            "9",
            "--after-halt",
            "3.5",
            "--duplicate",
            "4200",
            "--size",
            "240x180",
            "-o",
            "long.mp4",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let clip = dir.path().join("long.mp4");
    let truth: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("long.truth.json")).unwrap())
            .unwrap();
    let halt = truth["halt_time"].as_f64().unwrap();
    let captured = truth["captured_frames"].as_u64().unwrap() as usize;
    let config = ExperimentConfig::parse("fps = 480\n", Path::new("test.toml")).unwrap();
    let quiet = |_: usize, _: Option<usize>| {};
    let span = analyse_clip_decoding(&clip, &config, Decoding::NearTheEnd, &quiet).unwrap();
    let whole = analyse_clip_decoding(&clip, &config, Decoding::Whole, &quiet).unwrap();

    let decoded = span.plan.decoded.as_ref().unwrap();
    assert!(decoded.first_frame > 0, "{decoded:?}");
    assert_eq!(decoded.attempts, 2, "{decoded:?}");
    assert_eq!(decoded.clip_frames, captured);
    assert_eq!(decoded.last_frame, captured - 1);
    assert_eq!(span.frames.len(), captured - decoded.first_frame);
    // The span holds the sensitivity table's widest window (1 s) before the halt.
    assert!(decoded.first_t_capture_s < halt - 1.0, "{decoded:?}");
    let whole_decoded = whole.plan.decoded.as_ref().unwrap();
    assert!(whole_decoded.is_whole() && whole_decoded.reason == "--whole");
    assert_eq!(whole.frames.len(), captured);

    // The halt: the same last frame of motion seen, and t_φ, where the laws fitted
    // to the heights place the halt, within half a frame. The heights differ by
    // the rim models' spread (below), learned from other frames: over this clip
    // rendered at n = 0.45, 0.5, 0.55 and 0.6 the two t_φ differ by −0.03 … +0.17
    // frames, and by −0.24 … +0.11 with libswscale's exact conversions
    // (the history of 5374188's BENCHMARKS.md, "libswscale's rounding on every CPU").
    let seen = |e: &eulerdisk::analyse::Experiment| e.frames[e.series.halt.index].index;
    assert_eq!(seen(&span), seen(&whole));
    let (t_span, t_whole) = (span.series.halt.t_phi, whole.series.halt.t_phi);
    assert!((t_span - t_whole).abs() < 0.5 / 480.0, "{t_span} {t_whole}");
    assert!(
        (t_span - halt).abs() < 2.0 / 480.0,
        "t_φ {t_span}, truth {halt}"
    );
    // Frames keep their numbers and capture times in the whole clip, and their times
    // from the halt differ by t_φ's difference.
    for (k, f) in span.frames.iter().enumerate() {
        let w = &whole.frames[f.index];
        assert_eq!(f.index, decoded.first_frame + k);
        assert!(
            (f.t_capture - w.t_capture).abs() < 1e-9,
            "frame {}",
            f.index
        );
        assert!(
            (f.t - w.t + t_span - t_whole).abs() < 1e-9,
            "frame {}",
            f.index
        );
        assert_eq!(f.container_time_s, w.container_time_s);
    }
    // Flags carry the clip's frame numbers, in result.json as in flags.csv: the
    // duplicate is frame 4200 in the span (position 4200 − first) and whole.
    let duplicates = |e: &eulerdisk::analyse::Experiment| -> Vec<usize> {
        e.series
            .flags
            .iter()
            .filter(|f| matches!(f.reason, SkipReason::DuplicatedFrame { .. }))
            .map(|f| f.index)
            .collect()
    };
    assert_eq!(duplicates(&span), vec![4200], "{:?}", span.series.flags);
    assert_eq!(duplicates(&whole), vec![4200], "{:?}", whole.series.flags);
    assert!(span.frames[4200 - decoded.first_frame].z_rim_px.is_none());
    let report = dir.path().join("report");
    write_experiment(&report, &span, None, None).unwrap();
    let result: Value =
        serde_json::from_str(&std::fs::read_to_string(report.join("result.json")).unwrap())
            .unwrap();
    let flags_json: Vec<u64> = result["series"]["flags"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["index"].as_u64().unwrap())
        .collect();
    let flags_csv: Vec<u64> = std::fs::read_to_string(report.join("flags.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|line| line.split(',').next().unwrap().parse().unwrap())
        .collect();
    assert!(flags_json.contains(&4200), "{flags_json:?}");
    assert_eq!(flags_json, flags_csv);

    // The gap's darkness per pixel and the mirror-edge model are learned from the
    // decoded frames (vision::gap, vision::mirror_edge): from fewer frames in the
    // span, so its rim heights differ by the models' spread, measured 0.001 px on
    // average here. The span's profile D differs from the whole clip's by 0.01 at
    // the rim's foot; a frame is read as the mean over its fit's likelihood, which
    // moves as little as D does (`MirrorEdgeModel::edge`): single frames more than
    // 1 s before the halt differ by up to 0.045 px (0.1 px allowed there; with the
    // least-squares edge alone, 0.106). Within the widest fit window (the last 1 s)
    // every frame agrees within the 0.05 px of the 10-bit test (measured 0.022).
    let differences: Vec<(f64, f64)> = span
        .frames
        .iter()
        .filter_map(|f| Some((f.t, f.z_rim_px? - whole.frames[f.index].z_rim_px?)))
        .collect();
    let mean = differences.iter().map(|d| d.1).sum::<f64>() / differences.len() as f64;
    assert!(mean.abs() < 0.01, "mean difference {mean} px");
    for &(t, d) in &differences {
        let limit = if t >= -1.0 { 0.05 } else { 0.1 };
        assert!(d.abs() < limit, "t = {t} s: {d:+} px");
    }
    // Both recover the true n; measured 0.505 and 0.508.
    let true_n = truth["true_n"].as_f64().unwrap();
    for e in [&span, &whole] {
        let fit = &e.peaks_fit.fit;
        assert!(
            fit.ci95_n.0 < true_n && true_n < fit.ci95_n.1,
            "n = {} ({:?})",
            fit.n,
            fit.ci95_n
        );
    }
    assert!((span.peaks_fit.fit.n - whole.peaks_fit.fit.n).abs() < 0.01);
}
