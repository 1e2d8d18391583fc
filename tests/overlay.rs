//! The overlays of issue 15 (`overlay.mp4`, `last-turns.png`), decoded again and
//! checked against what was measured and against the ground truth of rendered
//! clips.

use std::path::{Path, PathBuf};

use crate::util::{f, fixture, json};
use eulerdisk::footage::FrameSource;

fn run(dir: &Path, args: &[&str]) {
    let out = crate::util::eulerdisk(dir, args);
    assert!(
        out.status.success(),
        "eulerdisk {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// `eulerdisk analyse` of the two-view fixture (`fps = 480`, two-view) in `dir`,
/// writing to `dir/out_name`, with `extra` arguments (e.g. `--no-overlay`).
fn analyse_two_view(dir: &Path, out_name: &str, extra: &[&str]) -> PathBuf {
    std::fs::write(dir.join("c.toml"), "fps = 480\ntwo_view = true\n").unwrap();
    let clip = fixture("two-view-n045.mp4");
    let mut args = vec![
        "analyse",
        clip.to_str().unwrap(),
        "-c",
        "c.toml",
        "-o",
        out_name,
    ];
    args.extend_from_slice(extra);
    run(dir, &args);
    dir.join(out_name)
}

/// Rows of `frames.csv`: (index, t − t_φ, z_rim_px).
fn frame_rows(dir: &Path) -> Vec<(usize, f64, Option<f64>)> {
    let mut reader = csv::Reader::from_path(dir.join("frames.csv")).unwrap();
    let header = reader.headers().unwrap().clone();
    let column = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (i, t, z) = (column("index"), column("t_s"), column("z_rim_px"));
    reader
        .records()
        .map(|r| {
            let r = r.unwrap();
            (
                r[i].parse().unwrap(),
                r[t].parse().unwrap(),
                r[z].parse().ok(),
            )
        })
        .collect()
}

/// Every frame of a video with its size: (width, height, RGB rows).
fn decode(video: &Path) -> (f64, Vec<(usize, usize, Vec<u8>)>) {
    let mut source = FrameSource::open(video).unwrap();
    let fps = source.container_fps().unwrap();
    let mut frames = Vec::new();
    while let Some(frame) = source.next_frame().unwrap() {
        let v = frame.view;
        let mut rgb = Vec::with_capacity(3 * v.width * v.height);
        for y in 0..v.height {
            for x in 0..v.width {
                rgb.extend_from_slice(&v.rgb(x, y));
            }
        }
        frames.push((v.width, v.height, rgb));
    }
    (fps, frames)
}

/// The two-view fixture (H.264, container timestamps): the video holds one frame
/// per analysed frame of the default span (the last 0.5 s before the halt and 0.1 s
/// after), in order, at 30 frames/s (16 × slower than the 480 fps capture), at the
/// size `overlay.json` states; the contact sheet holds the last 8 peaks; the page
/// embeds both.
#[test]
fn overlay_video_holds_the_span_at_its_rate_and_size() {
    let dir = tempfile::tempdir().unwrap();
    let out = analyse_two_view(dir.path(), "out", &[]);
    let index = json(&out.join("overlay.json"));
    let span: Vec<usize> = frame_rows(&out)
        .into_iter()
        .filter(|&(_, t, _)| (-0.5..=0.1).contains(&t))
        .map(|(i, _, _)| i)
        .collect();
    let listed: Vec<usize> = index["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["index"].as_u64().unwrap() as usize)
        .collect();
    assert_eq!(
        listed, span,
        "overlay.json lists the span's frames in order"
    );
    let (fps, frames) = decode(&out.join("overlay.mp4"));
    assert_eq!(
        frames.len(),
        span.len(),
        "one video frame per frame of the span"
    );
    assert!((fps - 30.0).abs() < 1e-6, "plays at 30 frames/s: {fps}");
    assert!((f(&index["slow_down"]) - 16.0).abs() < 1e-9);
    let (w, h) = (
        index["width"].as_u64().unwrap(),
        index["height"].as_u64().unwrap(),
    );
    assert!(
        frames
            .iter()
            .all(|(fw, fh, _)| (*fw as u64, *fh as u64) == (w, h))
    );
    let names: Vec<&str> = index["windows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w["name"].as_str().unwrap())
        .collect();
    assert!(names.contains(&"plan view"), "two-view: {names:?}");
    let tiles = index["last_turns"][1].as_array().unwrap();
    assert_eq!(tiles.len(), 8, "the last 8 oscillations");
    assert!(
        tiles.iter().all(|t| f(&t["t"]) <= 0.0),
        "all before the halt"
    );
    let sheet = image::open(out.join("last-turns.png")).unwrap();
    assert!(sheet.width() > 4 * w as u32 / 2 && sheet.height() > 2 * h as u32 / 2);
    let page = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(
        page.contains(r#"<video id="overlay" src="overlay.mp4""#),
        "video embedded"
    );
    assert!(page.contains("showFrame("), "peaks link to their frames");

    // --no-overlay writes neither.
    let bare = analyse_two_view(dir.path(), "bare", &["--no-overlay"]);
    assert!(!bare.join("overlay.mp4").exists() && !bare.join("last-turns.png").exists());
    assert!(
        !std::fs::read_to_string(bare.join("index.html"))
            .unwrap()
            .contains("<video")
    );
}

/// A rendered side view stored losslessly (PNG frames, so the measured z_rim is
/// within a few hundredths of a pixel of the truth): in every frame of the video,
/// the green rim-edge line drawn in the enlarged centre band lies on the measured
/// z_rim and on the true one, within 0.5 px, read back from the decoded H.264 by
/// the line's colour and placed through the window map of `overlay.json`.
#[test]
fn drawn_rim_edge_lies_on_the_measured_and_true_rim() {
    let dir = tempfile::tempdir().unwrap();
    run(
        dir.path(),
        &[
            "render", "--n", "0.5", "--halt", "0.5", "--size", "320x240", "-o", "clip",
        ],
    );
    std::fs::write(dir.path().join("c.toml"), "fps = 480\n").unwrap();
    run(
        dir.path(),
        &["analyse", "clip", "-c", "c.toml", "-o", "out"],
    );
    let out = dir.path().join("out");
    let truth = json(&dir.path().join("clip.truth.json"));
    let plan = json(&out.join("plan.json"));
    let index = json(&out.join("overlay.json"));
    let zero_row = f(&plan["rim_zero_row_px"]);
    let x_centre = {
        let c = &plan["calibration"]["calibration"];
        0.5 * (f(&c["x_l"]) + f(&c["x_r"]))
    };
    let band = index["windows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|w| w["name"] == "centre band, enlarged")
        .unwrap()
        .clone();
    let u = |k: &str| band[k].as_u64().unwrap() as f64;
    let zoom = u("zoom");
    // The canvas column through the middle of the band's column left of the
    // centre (a peak's cross covers the centre column).
    let column = (u("dst_x") + zoom * (x_centre.floor() - 0.5 - u("src_x"))) as usize;
    let rows = (u("dst_y") as usize)..(u("dst_y") + zoom * u("height")) as usize;
    let measured: Vec<Option<f64>> = frame_rows(&out).into_iter().map(|r| r.2).collect();
    let true_z: Vec<Option<f64>> = truth["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|fr| fr["z_rim_px"].as_f64())
        .collect();
    let (_, frames) = decode(&out.join("overlay.mp4"));
    let listed = index["frames"].as_array().unwrap();
    assert_eq!(frames.len(), listed.len());
    let mut checked = 0;
    let (mut worst_measured, mut worst_true) = (0.0f64, 0.0f64);
    for ((width, _, rgb), entry) in frames.iter().zip(listed) {
        let i = entry["index"].as_u64().unwrap() as usize;
        let Some(z) = measured[i] else { continue };
        // Greenness g − (r + b)/2 down the column: the line's weight per row.
        let (mut mass, mut moment) = (0.0, 0.0);
        for row in rows.clone() {
            let p = &rgb[3 * (row * width + column)..][..3];
            let green = f64::from(p[1]) - 0.5 * (f64::from(p[0]) + f64::from(p[2]));
            let w = (green - 40.0).max(0.0);
            mass += w;
            moment += w * (row as f64 + 0.5);
        }
        assert!(mass > 0.0, "frame {i}: no rim line drawn");
        let canvas_row = moment / mass;
        let frame_row = u("src_y") + (canvas_row - u("dst_y")) / zoom;
        let drawn = zero_row - frame_row;
        // The line is placed exactly; the H.264 coding (4:2:0 colour in 2 × 2
        // blocks of the enlarged picture) moves its colour centre by at most a
        // canvas pixel, 1/zoom of a frame pixel.
        assert!(
            (drawn - z).abs() < 0.5,
            "frame {i}: drawn {drawn:.3} px, measured {z:.3} px"
        );
        worst_measured = worst_measured.max((drawn - z).abs());
        if let Some(t) = true_z[i] {
            worst_true = worst_true.max((drawn - t).abs());
            // Lossless frames: the measurement is within 0.05 px of the truth.
            assert!(
                (drawn - t).abs() < 0.5,
                "frame {i}: drawn {drawn:.3} px, true {t:.3} px"
            );
        }
        checked += 1;
    }
    eprintln!(
        "{checked} frames: drawn rim edge within {worst_measured:.3} px of the measured z_rim, \
         {worst_true:.3} px of the true one"
    );
    assert!(checked > 250, "checked {checked} frames");
}

/// `compare` draws the model over the two-view fixture: the camera pose found from
/// the calibration has the rendered camera's elevation (the truth's, 3°), the video
/// has a frame per analysed frame of the span that the model covers, and the
/// report summarises the rim-edge distance between model and footage.
#[test]
fn compare_draws_the_model_with_the_calibrated_pose() {
    let dir = tempfile::tempdir().unwrap();
    analyse_two_view(dir.path(), "out", &["--no-overlay"]);
    run(
        dir.path(),
        &[
            "compare",
            "out",
            "--model",
            "augmented-contour",
            "--lead",
            "0.45",
        ],
    );
    let cmp = dir.path().join("out/compare-augmented-contour");
    let truth = json(&fixture("two-view-n045.truth.json"));
    let overlay = json(&cmp.join("model-overlay.json"));
    let elevation = f(&overlay["pose"]["elevation"]);
    // The top face's image height is read to about 0.3 px of the 2R sin ε ≈ 15 px.
    assert!(
        (elevation - f(&truth["elevation"])).abs() < 0.3f64.to_radians(),
        "elevation {:.3}°",
        elevation.to_degrees()
    );
    // The model starts 0.45 s before the halt: the span's frames from there on.
    let span = frame_rows(&dir.path().join("out"))
        .into_iter()
        .filter(|&(_, t, _)| (-0.45 - 1e-9..=0.1).contains(&t))
        .count();
    let (fps, frames) = decode(&cmp.join("model-overlay.mp4"));
    assert_eq!(frames.len(), span);
    assert!((fps - 30.0).abs() < 1e-6);
    let err = &overlay["edge_error"];
    assert!(err["frames"].as_u64().unwrap() as usize > span / 2);
    assert!(f(&err["rms_px"]).is_finite() && f(&err["rms_m"]) > 0.0);
    let page = std::fs::read_to_string(cmp.join("index.html")).unwrap();
    assert!(page.contains("model-overlay.mp4") && page.contains("model − footage"));
}

/// `compare --all-models` draws the best model (ranked first) over the footage,
/// in its own comparison folder, and the ranking page plays that video; the
/// other models' folders have their plots only. With no `--lead` (issue 72 §6): the
/// fixture's peaks begin inside 0.5 s of the halt, so the comparison starts from the
/// earliest measured state, the first peak, and says so.
#[test]
fn compare_all_models_draws_the_best_model() {
    let dir = tempfile::tempdir().unwrap();
    analyse_two_view(dir.path(), "out", &["--no-overlay"]);
    run(dir.path(), &["compare", "out", "--all-models"]);
    let out = dir.path().join("out");
    let result = json(&out.join("result.json"));
    let first_peak = f(&result["series"]["peaks"]["peaks"][0]["t"]);
    assert!(first_peak > -0.5, "first peak {first_peak}");
    let ranking = json(&out.join("compare-all/ranking.json"));
    let ranked = ranking.as_array().unwrap();
    let best = ranked[0]["model"].as_str().unwrap();
    let folder = out.join(format!("compare-{best}"));
    let summary = json(&folder.join("summary.json"));
    assert_eq!(f(&summary["options"]["lead_s"]), -first_peak);
    assert!(
        summary["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w.as_str().unwrap().contains("earliest measured state")),
        "{}",
        summary["warnings"]
    );
    let overlay = json(&folder.join("model-overlay.json"));
    assert!(overlay["edge_error"]["frames"].as_u64().unwrap() > 0);
    let (_, frames) = decode(&folder.join("model-overlay.mp4"));
    assert!(!frames.is_empty());
    let page = std::fs::read_to_string(out.join("compare-all/index.html")).unwrap();
    assert!(
        page.contains(&format!("src=\"../compare-{best}/model-overlay.mp4\"")),
        "the ranking page does not play the best model's overlay"
    );
    for other in &ranked[1..] {
        let name = other["model"].as_str().unwrap();
        assert!(
            !out.join(format!("compare-{name}/model-overlay.mp4"))
                .exists(),
            "{name} drawn too"
        );
    }
}
