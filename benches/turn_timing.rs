//! Cost of n from the turns' timing (`eulerdisk::turn_timing`) on one clip's turning
//! points: the starting grid, the Levenberg–Marquardt fit and its delete-a-block
//! jackknife over 25 turns' peaks and troughs (the last 0.5 s of a 480 fps clip),
//! timing noise 0.3 ms.
//!
//! Run: `cargo bench --bench turn_timing`.

use std::f64::consts::{PI, TAU};
use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use eulerdisk::rng::SplitMix64;
use eulerdisk::turn_timing::fit_turn_timing;

fn turn_timing(c: &mut Criterion) {
    let (n, turns) = (0.55, 25);
    let q = 1.0 / (1.0 - n / 2.0);
    let scale = 0.5 / (TAU * turns as f64).powf(q);
    let mut rng = SplitMix64::new(3);
    let psi: Vec<f64> = (0..2 * turns)
        .map(|k| -PI * (2 * turns - 1 - k) as f64)
        .collect();
    let t: Vec<f64> = psi
        .iter()
        .map(|&p| 0.003 - scale * (1.5 - p).powf(q) + 3e-4 * rng.gaussian())
        .collect();
    c.bench_function("turn_timing_25_turns", |b| {
        b.iter(|| fit_turn_timing(black_box(&t), black_box(&psi)).expect("fit"))
    });
}

criterion_group! {
    name = benches;
    // No plots: the report needs fonts that a headless machine may lack.
    config = Criterion::default().without_plots();
    targets = turn_timing
}
criterion_main!(benches);
