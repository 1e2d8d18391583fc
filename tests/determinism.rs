//! Rendering is deterministic (issue 12 §4): demo clips rendered twice in one
//! process, in parallel as `eulerdisk demo` renders them, are the same bytes, and
//! their analyses are the same numbers.

use std::path::Path;

use eulerdisk::analyse::analyse_clip;
use eulerdisk::config::ExperimentConfig;
use eulerdisk::demo::{demo_clips, render_demo_footage};

#[test]
fn demo_clips_rendered_twice_are_identical_and_analyse_identically() {
    // One clip of each material, as the demo renders them (480 × 320, 480 fps,
    // noise σ = 1, seeds by position).
    let clips: Vec<_> = demo_clips()
        .into_iter()
        .filter(|c| c.relative.ends_with("run2.mp4") && !c.two_view)
        .collect();
    assert_eq!(clips.len(), 2);
    let dir = tempfile::tempdir().unwrap();
    let (first, second) = (dir.path().join("first"), dir.path().join("second"));
    render_demo_footage(&first, &clips).unwrap();
    render_demo_footage(&second, &clips).unwrap();
    let config =
        ExperimentConfig::parse("fps = 480\n[fit]\nhalt = \"free\"\n", Path::new("t.toml"))
            .unwrap();
    for clip in &clips {
        let (a, b) = (first.join(&clip.relative), second.join(&clip.relative));
        assert!(
            std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
            "{}: the two renders differ",
            clip.relative
        );
        let (ea, eb) = (
            analyse_clip(&a, &config, &|_, _| {}).unwrap(),
            analyse_clip(&b, &config, &|_, _| {}).unwrap(),
        );
        // Everything but the path: the frames' measurements, the fits, the plan.
        let mut va = serde_json::to_value(&ea).unwrap();
        let mut vb = serde_json::to_value(&eb).unwrap();
        va["plan"]["clip"] = serde_json::Value::Null;
        vb["plan"]["clip"] = serde_json::Value::Null;
        assert!(va == vb, "{}: the analyses differ", clip.relative);
        assert_eq!(ea.peaks_fit.fit.n, eb.peaks_fit.fit.n);
        // And the recovered n is the rendered one to within the demo's accuracy.
        assert!(
            (ea.peaks_fit.fit.n - clip.true_n).abs() < 0.05,
            "{}: n {} vs {}",
            clip.relative,
            ea.peaks_fit.fit.n,
            clip.true_n
        );
    }
}
