//! Writing a rendered clip: an MP4 through OpenCV's `VideoWriter` (fourcc `avc1`,
//! else `mp4v`) or a folder of PNG frames `frame_000001.png …`, plus the ground truth
//! as `<clip stem>.truth.json` beside it.
//!
//! Both are written under a temporary name in the destination folder and renamed into
//! place when complete, so an interrupted run never leaves a clip that looks finished.

use std::path::{Path, PathBuf};

use opencv::core::{CV_8UC3, Mat, MatTraitManual, Scalar};
use opencv::prelude::{VideoWriterTrait, VideoWriterTraitConst};
use opencv::videoio::VideoWriter;
use rayon::prelude::*;

use super::{RenderError, Renderer};
use crate::report::write_json;

/// Container of a written clip.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ClipFormat {
    /// MP4 video (OpenCV).
    Mp4,
    /// A folder of PNG frames.
    PngFolder,
}

impl ClipFormat {
    /// MP4 for a path ending in `.mp4` (any case), a PNG folder otherwise.
    pub fn for_path(path: &Path) -> Self {
        match path.extension().and_then(|e| e.to_str()) {
            Some(ext) if ext.eq_ignore_ascii_case("mp4") => ClipFormat::Mp4,
            _ => ClipFormat::PngFolder,
        }
    }
}

/// What [`write_clip`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct WrittenClip {
    /// The clip (file or folder).
    pub clip: PathBuf,
    /// The ground-truth JSON.
    pub truth: PathBuf,
    /// Frames written.
    pub frames: usize,
    /// The fourcc used for an MP4.
    pub codec: Option<String>,
}

/// The ground-truth file of a clip: `clip.mp4` → `clip.truth.json`, `clip/` →
/// `clip.truth.json`.
pub fn truth_path(clip: &Path) -> PathBuf {
    let stem = clip
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "clip".to_owned());
    clip.with_file_name(format!("{stem}.truth.json"))
}

/// Frames rendered in parallel before they are written in order.
const BATCH: usize = 16;

/// Renders every frame of `renderer` and writes the clip and its truth to `path`
/// (MP4 if it ends in `.mp4`, else a PNG folder). An existing clip at `path` is
/// replaced only after the new one is complete.
pub fn write_clip(renderer: &Renderer, path: &Path) -> Result<WrittenClip, RenderError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let fail = |p: &Path, reason: String| RenderError::Write {
        path: p.to_path_buf(),
        reason,
    };
    std::fs::create_dir_all(&dir).map_err(|e| fail(path, e.to_string()))?;
    let name = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .ok_or_else(|| fail(path, "the output path has no file name".into()))?;
    let codec = match ClipFormat::for_path(path) {
        ClipFormat::Mp4 => {
            let tmp = dir.join(format!(".{name}.partial-{}.mp4", std::process::id()));
            let result = write_mp4(renderer, &tmp);
            match result {
                Ok(codec) => {
                    std::fs::rename(&tmp, path).map_err(|e| fail(path, e.to_string()))?;
                    Some(codec)
                }
                Err(reason) => {
                    // Best effort: a half-written temporary file is useless.
                    let _ = std::fs::remove_file(&tmp);
                    return Err(fail(path, reason));
                }
            }
        }
        ClipFormat::PngFolder => {
            // 0777 less the umask, as any folder the user makes (not tempfile's 0700).
            let tmp = tempfile::Builder::new()
                .prefix(&format!(".{name}.partial-"))
                .permissions(std::os::unix::fs::PermissionsExt::from_mode(0o777))
                .tempdir_in(&dir)
                .map_err(|e| fail(path, e.to_string()))?;
            write_pngs(renderer, tmp.path()).map_err(|(p, reason)| fail(&p, reason))?;
            let staged = tmp.keep();
            if path.exists() {
                let old = dir.join(format!(".{name}.replaced-{}", std::process::id()));
                std::fs::rename(path, &old).map_err(|e| fail(path, e.to_string()))?;
                std::fs::rename(&staged, path).map_err(|e| fail(path, e.to_string()))?;
                std::fs::remove_dir_all(&old).map_err(|e| fail(&old, e.to_string()))?;
            } else {
                std::fs::rename(&staged, path).map_err(|e| fail(path, e.to_string()))?;
            }
            None
        }
    };
    let truth = truth_path(path);
    write_json(&truth, renderer.truth()).map_err(|e| fail(&truth, e.to_string()))?;
    Ok(WrittenClip {
        clip: path.to_path_buf(),
        truth,
        frames: renderer.frame_count(),
        codec,
    })
}

fn write_pngs(renderer: &Renderer, dir: &Path) -> Result<(), (PathBuf, String)> {
    (0..renderer.frame_count())
        .into_par_iter()
        .try_for_each(|i| {
            let file = dir.join(format!("frame_{:06}.png", i + 1));
            renderer
                .render_frame(i)
                .save(&file)
                .map_err(|e| (file, e.to_string()))
        })
}

fn write_mp4(renderer: &Renderer, path: &Path) -> Result<String, String> {
    let truth = renderer.truth();
    let (w, h) = (truth.width as i32, truth.height as i32);
    let size = opencv::core::Size::new(w, h);
    let cv = |e: opencv::Error| format!("OpenCV: {}", e.message);
    let mut chosen = None;
    for code in ["avc1", "mp4v"] {
        let c: Vec<char> = code.chars().collect();
        let fourcc = VideoWriter::fourcc(c[0], c[1], c[2], c[3]).map_err(cv)?;
        // Some builds print a warning and fail to open for a missing encoder.
        if let Ok(writer) = VideoWriter::new(path, fourcc, truth.fps, size, true)
            && writer.is_opened().unwrap_or(false)
        {
            chosen = Some((code.to_owned(), writer));
            break;
        }
    }
    let (codec, mut writer) =
        chosen.ok_or_else(|| "OpenCV has neither an avc1 nor an mp4v MP4 encoder".to_owned())?;
    let mut frame = Mat::new_rows_cols_with_default(h, w, CV_8UC3, Scalar::all(0.0)).map_err(cv)?;
    let n = renderer.frame_count();
    for start in (0..n).step_by(BATCH) {
        let images: Vec<_> = (start..(start + BATCH).min(n))
            .into_par_iter()
            .map(|i| renderer.render_frame(i))
            .collect();
        for image in images {
            let bytes = frame.data_bytes_mut().map_err(cv)?;
            for (dst, src) in bytes
                .chunks_exact_mut(3)
                .zip(image.as_raw().chunks_exact(3))
            {
                dst.copy_from_slice(&[src[2], src[1], src[0]]);
            }
            writer.write(&frame).map_err(cv)?;
        }
    }
    writer.release().map_err(cv)?;
    Ok(codec)
}
