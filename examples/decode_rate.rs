//! OpenCV's decode-only rate for a video: the ceiling for `eulerdisk analyse`,
//! used by `scripts/bench --footage`. Decodes every frame to BGR exactly as
//! `analyse` does (`VideoCapture::read`, FFmpeg) and prints frames, seconds and
//! frames/s. The printed seconds are in-process (no library loading, no start-up);
//! `scripts/bench` compares `analyse` with this program as whole processes, so
//! both sides pay the same start-up.
//!
//! cargo run --release --example decode_rate -- clip.mp4

use opencv::core::Mat;
use opencv::prelude::*;
use opencv::videoio;

fn main() -> opencv::Result<()> {
    let path = std::env::args().nth(1).expect("usage: decode_rate CLIP");
    let started = std::time::Instant::now();
    let mut capture = videoio::VideoCapture::from_file(&path, videoio::CAP_FFMPEG)?;
    let mut frame = Mat::default();
    let mut frames = 0u64;
    while capture.read(&mut frame)? && !frame.empty() {
        frames += 1;
    }
    let secs = started.elapsed().as_secs_f64();
    println!(
        "{frames} frames in {secs:.3} s: {:.0} frames/s",
        frames as f64 / secs
    );
    Ok(())
}
