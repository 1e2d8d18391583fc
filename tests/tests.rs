//! The integration tests, one binary (`cargo test --release --test integration`;
//! `… --test integration cli::` runs one module): each file in `tests/` is a
//! module, so OpenCV and FFmpeg are linked once, and tests of different modules
//! run side by side. Shared helpers are in `util`.

mod util;

mod analyse;
mod cli;
mod compare;
mod determinism;
mod docs_reference;
mod integrity;
mod long_clip;
mod overlay;
mod phone_footage;
mod power_law;
mod robustness;
mod simulate_stream;
mod simulator;
mod study;
mod trust;
mod vision_render;
