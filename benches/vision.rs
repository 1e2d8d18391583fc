//! Per-frame cost of the side-view rim-height stage on 720×1280 frames
//! (the thesis's footage size), and of the plan-view strip stage.
//!
//! Run: `cargo bench --bench vision`. The rim stage must sustain ≥ 5,000
//! frames/s on one core, i.e. ≤ 200 µs per frame.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use eulerdisk::footage::{ChannelOrder, FrameView};
use eulerdisk::vision::{
    ColourThresholds, RimGauge, SideViewConfig, StripFinder, ThresholdSource, calibrate_at_rest,
};

const W: usize = 1280;
const H: usize = 720;

/// BGR bytes of a side view: a white disk (x 400.3–880.6, 60.4 px thick) whose
/// bottom edge is `lift` px above the plate line at row 500.7, a dark plate and
/// the disk's dimmer mirror image. Edges are anti-aliased along rows.
fn side_frame(lift: f64) -> Vec<u8> {
    let (x_l, x_r, z_base, thick) = (400.3, 880.6, 500.7, 60.4);
    let cover = |a0: f64, a1: f64, k: usize| (a1.min(k as f64 + 1.0) - a0.max(k as f64)).max(0.0);
    let mut out = vec![0u8; 3 * W * H];
    for r in 0..H {
        let disk = cover(z_base - lift - thick, z_base - lift, r);
        let mirror = cover(z_base + lift, z_base + lift + thick, r);
        let plate = cover(z_base, H as f64, r) - mirror;
        let background = 1.0 - disk - mirror - plate;
        for c in 0..W {
            let inside = cover(x_l, x_r, c);
            let v = inside * (230.0 * disk + 140.0 * mirror + 35.0 * plate + 25.0 * background)
                + (1.0 - inside) * (35.0 * (plate + mirror) + 25.0 * (disk + background));
            let v = v.round() as u8;
            out[3 * (r * W + c)..3 * (r * W + c) + 3].copy_from_slice(&[v, v, v]);
        }
    }
    out
}

fn view(bytes: &[u8], width: usize, height: usize) -> FrameView<'_> {
    FrameView {
        width,
        height,
        stride: 3 * width,
        order: ChannelOrder::Bgr,
        data: bytes,
    }
}

fn rim_height(c: &mut Criterion) {
    let config = SideViewConfig::default();
    let rest = side_frame(0.0);
    let report = calibrate_at_rest(&[view(&rest, W, H)], 0, &config, None)
        .expect("the synthetic rest frame calibrates");
    let gauge = RimGauge::new(&report.calibration, &report.threshold, &config, W, H)
        .expect("the calibration fits the frame");
    let rolling = side_frame(3.3);
    let empty = vec![25u8; 3 * W * H];
    let mut group = c.benchmark_group("rim_height_720x1280");
    for (name, bytes) in [("edge", &rolling), ("contact", &rest), ("no_edge", &empty)] {
        let frame = view(bytes, W, H);
        group.bench_function(name, |b| {
            b.iter(|| gauge.measure(black_box(&frame), 0).expect("same size"))
        });
    }
    group.finish();
}

fn strip_angle(c: &mut Criterion) {
    // Plan view, 720 × 640: grey field with a red 300 × 16 px strip at 0.5 rad.
    let (w, h) = (720, 640);
    let (cx, cy, beta) = (360.0f64, 320.0f64, 0.5f64);
    let mut bytes = vec![0u8; 3 * w * h];
    for r in 0..h {
        for col in 0..w {
            let (x, y) = (col as f64 + 0.5 - cx, r as f64 + 0.5 - cy);
            let along = x * beta.cos() - y * beta.sin();
            let across = x * beta.sin() + y * beta.cos();
            let px = if along.abs() < 150.0 && across.abs() < 8.0 {
                [40, 45, 205]
            } else {
                [150, 150, 150]
            };
            bytes[3 * (r * w + col)..3 * (r * w + col) + 3].copy_from_slice(&px);
        }
    }
    let frame = view(&bytes, w, h);
    let thresholds = ColourThresholds {
        r: 1.3,
        g: 0.9,
        b: 0.9,
    };
    let mut finder = StripFinder::new(thresholds, ThresholdSource::Given);
    c.bench_function("strip_angle_720x640", |b| {
        b.iter(|| finder.measure(black_box(&frame), 0).expect("strip in view"))
    });
}

criterion_group! {
    name = benches;
    // No plots: the report needs fonts that a headless machine may lack.
    config = Criterion::default().without_plots();
    targets = rim_height, strip_angle
}
criterion_main!(benches);
