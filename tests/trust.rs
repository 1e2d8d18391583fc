//! Issue 13 (results a lab can trust) end to end on the fixtures: dropped frames
//! inside the fit window warn in the printed line, on the page and in flags.csv
//! (halt at 0), for skips the images show and for gaps in the container's
//! timestamps; a slow-motion clip stored at a playback rate is blamed on its
//! frame rate first. Each test in a fresh temporary folder.

use crate::util::{eulerdisk, fixture};
use std::path::Path;

/// Issue 13.3: skip flags were timed from the clip's start but checked against the
/// window measured from the halt, so `skips_in_window` was always 0 and no warning
/// fired. The light fixture lost captures 40 and 171 (truth file), 200 and 69
/// frames before its halt at capture 240: both inside the 0.5 s window.
#[test]
fn dropped_frames_in_the_window_warn_everywhere() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        fixture("side-light-n067-artefacts.mp4"),
        dir.path().join("light.mp4"),
    )
    .unwrap();
    std::fs::write(
        dir.path().join("light.toml"),
        "fps = 480\nplate = \"light\"\n",
    )
    .unwrap();
    let out = eulerdisk(dir.path(), &["analyse", "light.mp4"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("WARNING: 2 flagged frame(s)"), "{stdout}");
    let experiment = dir.path().join("out/light.mp4");
    let page = std::fs::read_to_string(experiment.join("index.html")).unwrap();
    assert!(page.contains("2 flagged frame(s)"));
    let result: serde_json::Value =
        serde_json::from_slice(&std::fs::read(experiment.join("result.json")).unwrap()).unwrap();
    assert_eq!(result["skips_in_window"], 2);
    // flags.csv on the halt time base: both inside the window before the halt, and
    // as far apart as their captures: the clock counts the frame the rim shows
    // missing before the second (the measured halt itself sits some frames before
    // the true one, so the absolute times are checked by the window only).
    let flags = std::fs::read_to_string(experiment.join("flags.csv")).unwrap();
    let rows: Vec<(f64, f64)> = flags
        .lines()
        .skip(1)
        .map(|l| {
            let mut cells = l.split(',');
            let index: f64 = cells.next().unwrap().parse().unwrap();
            (index, cells.next().unwrap().parse().unwrap())
        })
        .collect();
    assert_eq!(rows.len(), 2, "{flags}");
    assert!(
        rows.iter().all(|(_, t)| (-0.5..=0.0).contains(t)),
        "{flags}"
    );
    let truth: serde_json::Value = serde_json::from_slice(
        &std::fs::read(fixture("side-light-n067-artefacts.truth.json")).unwrap(),
    )
    .unwrap();
    let capture = |file_index: f64| {
        truth["frames"][file_index as usize]["index"]
            .as_f64()
            .unwrap()
    };
    let captures_apart = capture(rows[1].0) - capture(rows[0].0);
    assert!(
        ((rows[1].1 - rows[0].1) * 480.0 - captures_apart).abs() < 1e-6,
        "{flags}"
    );
}

/// Issue 13.6: a 480 fps clip stored at 60 fps (no capture rate in the container,
/// no `fps` in the config) was blamed on a missing rest tail; the frame rate is now
/// named as the probable cause, with the key to set. The clip is the dark fixture
/// (480 frames/s) stored at 60 frames/s, its timestamps 8× apart ([`restamp`]).
#[test]
fn a_clip_stored_at_playback_rate_is_blamed_on_its_frame_rate() {
    let dir = tempfile::tempdir().unwrap();
    restamp(
        &fixture("side-dark-n050.mp4"),
        &dir.path().join("slow.mp4"),
        0..0,
        60,
    );
    let out = eulerdisk(dir.path(), &["analyse", "slow.mp4"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("slow.mp4: probably the frame rate") && err.contains("set `fps`"),
        "{err}"
    );
    // Issue 72 §6: the refusal explains itself on a page of its own, with the rest
    // frame and the heights as measured, and says where it is.
    let page = dir.path().join("out/slow.mp4");
    assert!(err.contains("out/slow.mp4/index.html"), "{err}");
    let record: serde_json::Value =
        serde_json::from_slice(&std::fs::read(page.join("failure.json")).unwrap()).unwrap();
    assert_eq!(record["stage"], "the signal stage and the fits", "{record}");
    assert!(
        record["reason"]
            .as_str()
            .unwrap()
            .contains("probably the frame rate"),
        "{record}"
    );
    assert!(!record["try_next"].as_array().unwrap().is_empty());
    assert!(
        record["plate"].as_str().unwrap().starts_with("dark plate"),
        "{record}"
    );
    let html = std::fs::read_to_string(page.join("index.html")).unwrap();
    assert!(
        html.contains("not measured") && html.contains("<svg"),
        "{html}"
    );
    for file in ["calibration.png", "heights.svg", "heights.png"] {
        assert!(page.join(file).is_file(), "{file}");
    }
    assert!(!page.join("result.json").exists());

    // A failure page never replaces an earlier result: the clip measured at its true
    // rate into a folder, then the slowed one forced into the same folder.
    std::fs::copy(fixture("side-dark-n050.mp4"), dir.path().join("good.mp4")).unwrap();
    let out = eulerdisk(dir.path(), &["analyse", "good.mp4", "-o", "kept"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let before = std::fs::read(dir.path().join("kept/result.json")).unwrap();
    let out = eulerdisk(
        dir.path(),
        &["analyse", "slow.mp4", "-o", "kept", "--force"],
    );
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("kept is kept: it holds an earlier result"),
        "{err}"
    );
    assert_eq!(
        std::fs::read(dir.path().join("kept/result.json")).unwrap(),
        before
    );
    assert!(!dir.path().join("kept/failure.json").exists());
}

/// Issue 13, property: random bytes and random TOML never panic. Configs built from
/// the real keys with values of random type and size, and raw random text, parse
/// to a config or an error naming the file; random bytes as a video, as a frame
/// folder's PNG, as a shard's study.json and as a compare experiment give errors.
#[test]
fn random_bytes_and_random_toml_never_panic() {
    use eulerdisk::analyse::analyse_clip;
    use eulerdisk::config::ExperimentConfig;
    use eulerdisk::rng::SplitMix64;
    use std::path::Path;

    let mut rng = SplitMix64::new(13);
    let keys = [
        "fps",
        "plate",
        "two_view",
        "material",
        "disk.preset",
        "disk.radius_m",
        "disk.mass_kg",
        "vision.gamma",
        "vision.band_half_width_px",
        "vision.split_row",
        "vision.roi",
        "calibration.x_l",
        "calibration.x_r",
        "calibration.z_t",
        "calibration.z_base",
        "fit.window_s",
        "fit.halt",
    ];
    let values = [
        "0",
        "-1",
        "1e308",
        "-1e308",
        "nan",
        "inf",
        "-inf",
        "4294967295",
        "4294967296",
        "18446744073709551615",
        "0.5",
        "480",
        "true",
        "\"dark\"",
        "\"free\"",
        "\"\"",
        "[]",
        "[0, 0, 4294967295, 4294967295]",
        "[4294967295, 4294967295, 1, 1]",
        "[1, 2, 3]",
        "{}",
        "1979-05-27",
        "'''x'''",
    ];
    let pick = |rng: &mut SplitMix64, n: usize| (rng.next_u64() % n as u64) as usize;
    for _ in 0..2000 {
        let mut text = String::new();
        for _ in 0..1 + pick(&mut rng, 6) {
            let key = keys[pick(&mut rng, keys.len())];
            let value = values[pick(&mut rng, values.len())];
            match key.split_once('.') {
                Some((table, leaf)) => text.push_str(&format!("[{table}]\n{leaf} = {value}\n")),
                None => text.push_str(&format!("{key} = {value}\n")),
            }
        }
        if let Err(e) = ExperimentConfig::parse(&text, Path::new("r.toml")) {
            assert!(e.to_string().contains("r.toml"), "{text}: {e}");
        }
        let bytes: Vec<u8> = (0..pick(&mut rng, 200))
            .map(|_| rng.next_u64() as u8)
            .collect();
        let raw = String::from_utf8_lossy(&bytes);
        if let Err(e) = ExperimentConfig::parse(&raw, Path::new("r.toml")) {
            assert!(e.to_string().contains("r.toml"), "{e}");
        }
    }

    let dir = tempfile::tempdir().unwrap();
    let config: ExperimentConfig =
        ExperimentConfig::parse("fps = 480\n", Path::new("c.toml")).unwrap();
    let quiet = |_: usize, _: Option<usize>| {};
    for i in 0..20 {
        let len = 1 + pick(&mut rng, 5000);
        let bytes: Vec<u8> = (0..len).map(|_| rng.next_u64() as u8).collect();
        let video = dir.path().join(format!("r{i}.mp4"));
        std::fs::write(&video, &bytes).unwrap();
        let err = analyse_clip(&video, &config, &quiet)
            .unwrap_err()
            .to_string();
        assert!(err.contains(&format!("r{i}.mp4")), "{err}");
        let frames = dir.path().join(format!("frames{i}"));
        std::fs::create_dir(&frames).unwrap();
        std::fs::write(frames.join("f1.png"), &bytes).unwrap();
        std::fs::write(frames.join("f2.png"), &bytes).unwrap();
        assert!(analyse_clip(&frames, &config, &quiet).is_err());
        let shard = dir.path().join(format!("shard{i}"));
        std::fs::create_dir(&shard).unwrap();
        std::fs::write(shard.join("study.json"), &bytes).unwrap();
        assert!(eulerdisk::study::merge(std::slice::from_ref(&shard)).is_err());
        std::fs::write(shard.join("result.json"), &bytes).unwrap();
        assert!(eulerdisk::compare::load_experiment(&shard).is_err());
    }
}

/// Issue 13.5: `band_half_width_px = 100000` changed n from 0.431 to 0.395 without
/// a word. Checked against the disk's width as calibrated (the dark fixture's disk
/// is about 430 px wide: at most 21 px either side), it is refused with the unit.
#[test]
fn a_band_wider_than_the_disk_allows_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(fixture("side-dark-n050.mp4"), dir.path().join("clip.mp4")).unwrap();
    std::fs::write(
        dir.path().join("clip.toml"),
        "fps = 480\n[vision]\nband_half_width_px = 100000\n",
    )
    .unwrap();
    let out = eulerdisk(dir.path(), &["analyse", "clip.mp4"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("clip.mp4") && err.contains("`vision.band_half_width_px` = 100000 px"),
        "{err}"
    );
    assert!(!dir.path().join("out/clip.mp4").exists(), "nothing written");
}

/// Issue 13.6: errors advised keys that do not exist (`prominence_sigmas`,
/// `rest_tail_s`, "the calibration override"). Every backticked dotted or plain key
/// in the advice of these errors is a key the config accepts (a type error is
/// fine; an unknown field is not).
#[test]
fn advice_names_only_real_config_keys() {
    use eulerdisk::config::ExperimentConfig;
    use eulerdisk::signal::SignalError;
    use eulerdisk::vision::VisionError;
    use std::path::Path;
    let messages = [
        SignalError::TooFewPeaks {
            found: 1,
            needed: 3,
            window_start: -0.5,
            window_end: 0.0,
        }
        .to_string(),
        VisionError::NoDisk {
            frame: 1,
            gamma: 0.5,
        }
        .to_string(),
        VisionError::NoSplit { frame: 1 }.to_string(),
        VisionError::CalibrationPointNotFound {
            frame: 1,
            point: "x_l",
        }
        .to_string(),
    ];
    let mut checked = 0;
    for message in &messages {
        assert!(!message.contains("prominence_sigmas") && !message.contains("override"));
        for key in message.split('`').skip(1).step_by(2) {
            let text = match key.split_once('.') {
                Some((table, leaf)) => format!("[{table}]\n{leaf} = 0\n"),
                None => format!("{key} = 0\n"),
            };
            if let Err(e) = ExperimentConfig::parse(&text, Path::new("k.toml")) {
                assert!(!e.to_string().contains("unknown field"), "{key}: {e}");
            }
            checked += 1;
        }
    }
    assert!(checked >= 4, "{messages:#?}");
}

/// A copy of the rendered clip `src` (480 fps) with the frames `dropped` left out
/// and the others keeping their capture times: frame i at pts i in a time base of
/// 1/`stored_fps` s, so a clip stored at 30 fps plays 16× slowed, as a phone
/// stores slow motion. The frames are re-encoded losslessly (libx264 at crf 0,
/// the encoder `render` uses), so every copy holds the same pixels as decoded from
/// `src`, and copies differ only in their timestamps.
fn restamp(src: &Path, dst: &Path, dropped: std::ops::Range<usize>, stored_fps: i32) {
    use ffmpeg_next as ff;
    ff::init().unwrap();
    ff::util::log::set_level(ff::util::log::Level::Quiet);
    let mut input = ff::format::input(src).unwrap();
    let stream = input.streams().best(ff::media::Type::Video).unwrap();
    let stream_index = stream.index();
    let mut decoder = ff::codec::context::Context::from_parameters(stream.parameters())
        .unwrap()
        .decoder()
        .video()
        .unwrap();
    let codec = ff::encoder::find_by_name("libx264").expect("libx264, as `render` needs");
    let mut output = ff::format::output_as(dst, "mp4").unwrap();
    let rate = ff::Rational::new(stored_fps, 1);
    let time_base = rate.invert();
    let mut encoder = ff::codec::context::Context::new_with_codec(codec)
        .encoder()
        .video()
        .unwrap();
    encoder.set_width(decoder.width());
    encoder.set_height(decoder.height());
    encoder.set_format(decoder.format());
    encoder.set_time_base(time_base);
    encoder.set_frame_rate(Some(rate));
    if output
        .format()
        .flags()
        .contains(ff::format::Flags::GLOBAL_HEADER)
    {
        encoder.set_flags(ff::codec::Flags::GLOBAL_HEADER);
    }
    let mut options = ff::Dictionary::new();
    options.set("crf", "0");
    options.set("preset", "ultrafast");
    options.set("threads", "1");
    let mut encoder = encoder.open_with(options).unwrap();
    output.add_stream(codec).unwrap().set_parameters(&encoder);
    output.stream_mut(0).unwrap().set_time_base(time_base);
    output.write_header().unwrap();
    let out_time_base = output.stream(0).unwrap().time_base();

    let mut frame = ff::frame::Video::empty();
    let mut packet = ff::Packet::empty();
    let mut next = 0usize;
    let mut drain = |encoder: &mut ff::encoder::Video, output: &mut ff::format::context::Output| {
        while encoder.receive_packet(&mut packet).is_ok() {
            packet.set_stream(0);
            packet.set_duration(1);
            packet.rescale_ts(time_base, out_time_base);
            packet.write_interleaved(output).unwrap();
        }
    };
    let mut pass_on = |decoder: &mut ff::decoder::Video,
                       encoder: &mut ff::encoder::Video,
                       output: &mut ff::format::context::Output| {
        while decoder.receive_frame(&mut frame).is_ok() {
            let i = next;
            next += 1;
            if dropped.contains(&i) {
                continue;
            }
            frame.set_pts(Some(i as i64));
            // Let x264 choose the picture types, not the source's.
            frame.set_kind(ff::picture::Type::None);
            encoder.send_frame(&frame).unwrap();
            drain(encoder, output);
        }
    };
    let packets: Vec<ff::Packet> = input
        .packets()
        .filter(|(s, _)| s.index() == stream_index)
        .map(|(_, p)| p)
        .collect();
    for p in packets {
        decoder.send_packet(&p).unwrap();
        pass_on(&mut decoder, &mut encoder, &mut output);
    }
    decoder.send_eof().unwrap();
    pass_on(&mut decoder, &mut encoder, &mut output);
    encoder.send_eof().unwrap();
    drain(&mut encoder, &mut output);
    output.write_trailer().unwrap();
}

/// `eulerdisk analyse CLIP` in `dir` (succeeding), its printed line and result.json.
fn analysed(dir: &Path, clip: &str) -> (String, serde_json::Value) {
    let out = eulerdisk(dir, &["analyse", clip]);
    assert!(
        out.status.success(),
        "{clip}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let result = dir.join("out").join(clip).join("result.json");
    let result = serde_json::from_slice(&std::fs::read(result).unwrap()).unwrap();
    (String::from_utf8_lossy(&out.stdout).into_owned(), result)
}

/// The timestamp-gap flags of a result: (frame, missing frames).
fn timestamp_gaps(result: &serde_json::Value) -> Vec<(u64, u64)> {
    result["series"]["flags"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["reason"]["kind"] == "timestamp-gap")
        .map(|f| {
            (
                f["index"].as_u64().unwrap(),
                f["reason"]["missing_frames"].as_u64().unwrap(),
            )
        })
        .collect()
}

/// Issue 13.3 with issue 14 §2: a variable-frame-rate clip whose timestamps skip 25
/// frames was timed by index / fps at the container's average rate: n 0.407 for
/// 0.431, fps "446.76", no warning. Now the container's timestamps time the frames
/// (mapped to capture time), the gap is flagged, a gap in the fit window warns,
/// and n is what the same frames without the gap give.
#[test]
fn container_timestamp_gaps_are_flagged_and_keep_the_time() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = eulerdisk(d, &["render", "--size", "640x360", "-o", "render.mp4"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let truth: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("render.truth.json")).unwrap()).unwrap();
    let true_n = truth["true_n"].as_f64().unwrap();
    let halt_frame = (truth["halt_time"].as_f64().unwrap() * 480.0).round() as usize;
    assert_eq!(halt_frame, 480);
    let render = d.join("render.mp4");
    // Frames 300..325 lie 0.32 s before the halt, inside the 0.5 s window; frames
    // 100..125 0.74 s before it, outside.
    restamp(&render, &d.join("whole.mp4"), 0..0, 480);
    restamp(&render, &d.join("gap.mp4"), 300..325, 480);
    restamp(&render, &d.join("early.mp4"), 100..125, 480);
    restamp(&render, &d.join("phone.mp4"), 300..325, 30);
    // The phone clip is stored at 30 fps: its capture rate comes from the config.
    std::fs::write(d.join("phone.toml"), "fps = 480\n").unwrap();

    let n = |r: &serde_json::Value| r["peaks_fit"]["fit"]["n"].as_f64().unwrap();
    let fps = |r: &serde_json::Value| r["plan"]["fps"]["fps"].as_f64().unwrap();
    // The same frames without a gap: no fps configured, the container's 480.
    let (_, whole) = analysed(d, "whole.mp4");
    assert!(
        (fps(&whole) - 480.0).abs() < 1e-9,
        "{}",
        whole["plan"]["fps"]
    );
    assert_eq!(whole["series"]["flags"], serde_json::json!([]));
    // ±0.02: the tolerance on rendered clips (tests/analyse.rs).
    assert!((n(&whole) - true_n).abs() < 0.02, "n = {}", n(&whole));

    let (line, gap) = analysed(d, "gap.mp4");
    // The container's average rate is 528 frames over 553 frame times, 458.3 fps;
    // the median timestamp interval gives the capture rate.
    assert!((fps(&gap) - 480.0).abs() < 1e-9, "{}", gap["plan"]["fps"]);
    assert_eq!(gap["plan"]["fps"]["source"]["kind"], "container_timestamps");
    // `info` reads the same timestamps: the median interval, the gap, and a warning
    // that the stored fps (an average over the gap) is not the frames' rate.
    let info = eulerdisk(d, &["info", "gap.mp4"]);
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(
        text.contains("median interval 2.083 ms (480 fps)")
            && text.contains("longest 54.167 ms, 1 gap(s)")
            && text.contains("is an average: the frames' timestamps are 480 fps apart"),
        "{text}"
    );
    let timing = &gap["plan"]["frame_times"];
    assert_eq!(timing["source"], "container_pts");
    assert!((timing["median_interval_s"].as_f64().unwrap() - 1.0 / 480.0).abs() < 1e-12);
    assert!((timing["max_interval_s"].as_f64().unwrap() - 26.0 / 480.0).abs() < 1e-9);
    // Frames after the gap keep their capture times: file frame 300 is capture 325.
    let frames = gap["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 553 - 25);
    for (k, capture) in [(299, 299.0), (300, 325.0), (527, 552.0)] {
        let t = frames[k]["t_capture"].as_f64().unwrap();
        assert!((t - capture / 480.0).abs() < 1e-9, "frame {k}: {t}");
    }
    // The gap's first frame is flagged with the 25 frames missing before it, and
    // nothing else is.
    assert_eq!(
        timestamp_gaps(&gap),
        vec![(300, 25)],
        "{}",
        gap["series"]["flags"]
    );
    assert_eq!(gap["series"]["flags"].as_array().unwrap().len(), 1);
    // Inside the window: a warning in the result, the printed line and the page.
    assert_eq!(gap["skips_in_window"], 1);
    assert!(
        line.contains("WARNING: 1 flagged frame(s)")
            && line.contains("fps 480 (ContainerTimestamps)")
            && line.contains("frame times from container pts"),
        "{line}"
    );
    let page = std::fs::read_to_string(d.join("out/gap.mp4/index.html")).unwrap();
    assert!(page.contains("25 frame(s) missing before t = "));
    assert!(page.contains("container pts"));
    // n within the same ±0.02 of the truth, and within 0.005 of the same frames
    // without the gap (the gap hides 3 of 24 peaks; measured 0.0005 apart).
    assert!((n(&gap) - true_n).abs() < 0.02, "n = {}", n(&gap));
    assert!(
        (n(&gap) - n(&whole)).abs() < 0.005,
        "n = {} and {}",
        n(&gap),
        n(&whole)
    );

    // Stored at 30 fps with fps = 480 configured: the timestamps ÷ 16 give the same
    // times (to 4e-15 s), flags and n. n within 0.002: on times that differ by
    // 4e-15 s one peak's refinement lands 0.05 frame elsewhere (measured 5e-4 in n).
    let (_, phone) = analysed(d, "phone.mp4");
    assert!((phone["plan"]["frame_times"]["slowdown"].as_f64().unwrap() - 16.0).abs() < 1e-9);
    assert_eq!(fps(&phone), 480.0);
    let phone_frames = phone["frames"].as_array().unwrap();
    for (a, b) in frames.iter().zip(phone_frames) {
        let (ta, tb) = (
            a["t_capture"].as_f64().unwrap(),
            b["t_capture"].as_f64().unwrap(),
        );
        assert!((ta - tb).abs() < 1e-9, "{ta} {tb}");
    }
    assert_eq!(timestamp_gaps(&phone), vec![(300, 25)]);
    assert!((n(&phone) - n(&gap)).abs() < 0.002, "n = {}", n(&phone));

    // A gap before the window: flagged, no warning.
    let (line, early) = analysed(d, "early.mp4");
    assert_eq!(timestamp_gaps(&early), vec![(100, 25)]);
    assert_eq!(early["skips_in_window"], 0);
    assert!(!line.contains("WARNING"), "{line}");
    assert!((n(&early) - true_n).abs() < 0.02, "n = {}", n(&early));
}

/// Issue 72 §2: a calibration whose side reads far thicker, against the diameter, than
/// the disk's dimensions allow (here the config's disk a third as thick as the one
/// filmed, as a reflection taken for part of the disk would read) stops with an error
/// that names the factor and what to check, instead of running on with the diameter's
/// scale and the rim gauge on the wrong edge; and the failure page says so.
#[test]
fn a_side_thicker_than_the_disk_allows_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(fixture("side-dark-n050.mp4"), dir.path().join("clip.mp4")).unwrap();
    std::fs::write(
        dir.path().join("clip.toml"),
        "[disk]\nhalf_thickness_m = 0.00212\n",
    )
    .unwrap();
    let out = eulerdisk(dir.path(), &["analyse", "clip.mp4"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("times as thick, against its diameter")
            && err.contains("half_thickness_m")
            && err.contains("perspective factor"),
        "{err}"
    );
    let record: serde_json::Value = serde_json::from_slice(
        &std::fs::read(dir.path().join("out/clip.mp4/failure.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(record["stage"], "opening and calibration");
}
