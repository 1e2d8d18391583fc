//! The capture frame rate that a phone hides in an MP4/MOV container.
//!
//! Slow-motion phone clips are stored for playback at about 30 fps. OpenCV reports
//! that playback rate; the rate the camera captured at lives elsewhere:
//!
//! * Android's camera app writes an Apple-style metadata item
//!   `com.android.capture.fps` (a big-endian `f32`) under `moov/meta`
//!   (`hdlr` = `mdta`, a `keys` list and an `ilst` whose items are numbered by key).
//! * iPhones keep the frames timed at the capture rate in the media time line
//!   (`stts` sample durations in the `mdhd` time scale) and slow the middle of the
//!   clip down with an edit list (`elst` entries whose media rate is below 1).
//!
//! [`container_capture_rate`] walks the ISO base-media boxes for these two cases;
//! OpenCV does not expose them. Only `moov` is read (it is small), not the media.

use std::path::Path;

/// A capture rate found in a container, and how it was found.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContainerCaptureRate {
    /// Frames per second of capture.
    pub fps: f64,
    /// Human-readable origin: which tag or which timing table.
    pub source: String,
}

/// The capture rate stored in an MP4/MOV file, if the file holds one (see the
/// module doc); `None` for other containers, files without such metadata, and
/// files whose boxes cannot be walked (the decoder will report those).
pub fn container_capture_rate(path: &Path) -> Option<ContainerCaptureRate> {
    let bytes = read_moov(path)?;
    capture_rate_in_moov(&bytes)
}

/// The payload of the top-level `moov` box (read by seeking past `mdat`).
fn read_moov(path: &Path) -> Option<Vec<u8>> {
    use std::io::{Read, Seek, SeekFrom};
    let mut file = std::fs::File::open(path).ok()?;
    let len = file.metadata().ok()?.len();
    let mut at = 0u64;
    while at + 8 <= len {
        file.seek(SeekFrom::Start(at)).ok()?;
        let mut head = [0u8; 16];
        file.read_exact(&mut head[..8]).ok()?;
        let mut size = u64::from(u32::from_be_bytes(head[..4].try_into().ok()?));
        let mut header = 8;
        if size == 1 {
            file.read_exact(&mut head[8..16]).ok()?;
            size = u64::from_be_bytes(head[8..16].try_into().ok()?);
            header = 16;
        } else if size == 0 {
            size = len - at;
        }
        if size < header || at + size > len {
            return None;
        }
        if &head[4..8] == b"moov" {
            let mut payload = vec![0u8; usize::try_from(size - header).ok()?];
            file.read_exact(&mut payload).ok()?;
            return Some(payload);
        }
        at += size;
    }
    None
}

/// The child boxes of a box payload: (type, payload) pairs. Stops quietly at a
/// malformed size.
fn boxes(mut data: &[u8]) -> Vec<([u8; 4], &[u8])> {
    let mut out = Vec::new();
    while data.len() >= 8 {
        let size = u32::from_be_bytes([data[0], data[1], data[2], data[3]]) as usize;
        let kind = [data[4], data[5], data[6], data[7]];
        let (size, header) = match size {
            0 => (data.len(), 8),
            1 if data.len() >= 16 => {
                let Ok(large) = data[8..16].try_into().map(u64::from_be_bytes) else {
                    break;
                };
                (usize::try_from(large).unwrap_or(usize::MAX), 16)
            }
            _ => (size, 8),
        };
        if size < header || size > data.len() {
            break;
        }
        out.push((kind, &data[header..size]));
        data = &data[size..];
    }
    out
}

fn child<'a>(data: &'a [u8], kind: &[u8; 4]) -> Option<&'a [u8]> {
    boxes(data)
        .into_iter()
        .find(|(k, _)| k == kind)
        .map(|(_, p)| p)
}

fn be_u32(data: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_be_bytes(data.get(at..at + 4)?.try_into().ok()?))
}

fn capture_rate_in_moov(moov: &[u8]) -> Option<ContainerCaptureRate> {
    android_capture_fps(moov).or_else(|| edit_list_capture_fps(moov))
}

/// `com.android.capture.fps` from `moov/meta` (or `moov/udta/meta`).
fn android_capture_fps(moov: &[u8]) -> Option<ContainerCaptureRate> {
    let meta = child(moov, b"meta").or_else(|| child(child(moov, b"udta")?, b"meta"))?;
    // QuickTime's `meta` is a plain box; ISO's is a full box (4 bytes of version
    // and flags first). Try the plain layout, then skip the four bytes.
    let meta = if child(meta, b"keys").is_some() {
        meta
    } else {
        meta.get(4..)?
    };
    let keys = child(meta, b"keys")?;
    let count = be_u32(keys, 4)? as usize;
    let mut at = 8;
    let mut index = None;
    for i in 1..=count {
        let size = be_u32(keys, at)? as usize;
        let name = keys.get(at + 8..at + size)?;
        if name == b"com.android.capture.fps" {
            index = Some(i as u32);
        }
        at += size.max(8);
    }
    let index = index?;
    let ilst = child(meta, b"ilst")?;
    let item = boxes(ilst)
        .into_iter()
        .find(|(k, _)| u32::from_be_bytes(*k) == index)?
        .1;
    let data = child(item, b"data")?;
    // data: type indicator (23 = big-endian f32, 24 = f64), locale, value.
    let value = match be_u32(data, 0)? {
        23 => f64::from(f32::from_be_bytes(data.get(8..12)?.try_into().ok()?)),
        24 => f64::from_be_bytes(data.get(8..16)?.try_into().ok()?),
        _ => return None,
    };
    (value.is_finite() && value > 0.0).then(|| ContainerCaptureRate {
        fps: value,
        source: "Android capture-fps tag (com.android.capture.fps)".into(),
    })
}

/// The media-time frame rate of a video track whose edit list plays part of it
/// slower than recorded (iPhone slow motion).
fn edit_list_capture_fps(moov: &[u8]) -> Option<ContainerCaptureRate> {
    for (kind, trak) in boxes(moov) {
        if &kind != b"trak" {
            continue;
        }
        let mdia = child(trak, b"mdia")?;
        if child(mdia, b"hdlr").and_then(|h| h.get(8..12)) != Some(b"vide".as_slice()) {
            continue;
        }
        let slowed = child(trak, b"edts")
            .and_then(|e| child(e, b"elst"))
            .is_some_and(edit_list_slows);
        if !slowed {
            continue;
        }
        let mdhd = child(mdia, b"mdhd")?;
        let timescale = match mdhd.first()? {
            1 => be_u32(mdhd, 20)?,
            _ => be_u32(mdhd, 12)?,
        };
        let stts = child(child(child(mdia, b"minf")?, b"stbl")?, b"stts")?;
        let delta = most_common_sample_delta(stts)?;
        if timescale == 0 || delta == 0 {
            return None;
        }
        return Some(ContainerCaptureRate {
            fps: f64::from(timescale) / f64::from(delta),
            source: "media time line under a slowing edit list (iPhone slow motion)".into(),
        });
    }
    None
}

/// Does an `elst` payload hold an entry played at a media rate below 1?
fn edit_list_slows(elst: &[u8]) -> bool {
    let Some(&version) = elst.first() else {
        return false;
    };
    let Some(count) = be_u32(elst, 4) else {
        return false;
    };
    let entry = if version == 1 { 20 } else { 12 };
    (0..count as usize).any(|i| {
        let rate_at = 8 + i * entry + entry - 4;
        be_u32(elst, rate_at).is_some_and(|fixed| {
            let rate = f64::from(fixed as i32) / 65536.0;
            rate > 0.0 && rate < 1.0
        })
    })
}

/// The sample duration that covers most samples of an `stts` table.
fn most_common_sample_delta(stts: &[u8]) -> Option<u32> {
    let count = be_u32(stts, 4)? as usize;
    (0..count)
        .filter_map(|i| Some((be_u32(stts, 8 + 8 * i)?, be_u32(stts, 12 + 8 * i)?)))
        .max_by_key(|&(samples, _)| samples)
        .map(|(_, delta)| delta)
}

/// Where the capture fps of an analysis came from.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", content = "detail")]
pub enum FpsSource {
    /// The experiment config's `fps`.
    Config,
    /// A capture rate stored in the container (see [`ContainerCaptureRate`]).
    ContainerCaptureRate(String),
    /// The container's stored (playback) fps, used for want of anything better.
    ContainerFps,
    /// The rate of the container's median timestamp interval, for want of anything
    /// better: it replaces [`FpsSource::ContainerFps`] once the timestamps are read
    /// (a stored average rate is lowered by gaps; see [`super::frame_times`]).
    ContainerTimestamps,
}

/// The capture fps used to time frames, with its source and any warning.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CaptureFps {
    pub fps: f64,
    pub source: FpsSource,
    pub warnings: Vec<String>,
}

/// Choose the capture fps: the config's when given, else a capture rate stored in
/// the container, else the container's fps with a warning.
///
/// # Errors
/// A message when no source gives a usable fps (a frame folder without a
/// configured fps) or the configured fps is not a positive number.
pub fn resolve_capture_fps(
    configured: Option<f64>,
    container_rate: Option<ContainerCaptureRate>,
    container_fps: Option<f64>,
) -> Result<CaptureFps, String> {
    let mut warnings = Vec::new();
    if let Some(fps) = configured {
        if !(fps.is_finite() && fps > 0.0) {
            return Err(format!("configured fps {fps} is not a positive number"));
        }
        if let Some(stored) = &container_rate
            && (stored.fps - fps).abs() > 0.01 * fps
        {
            warnings.push(format!(
                "configured fps {fps} differs from the container's capture rate {} ({}); \
                 using the configured value",
                stored.fps, stored.source
            ));
        }
        return Ok(CaptureFps {
            fps,
            source: FpsSource::Config,
            warnings,
        });
    }
    if let Some(stored) = container_rate {
        return Ok(CaptureFps {
            fps: stored.fps,
            source: FpsSource::ContainerCaptureRate(stored.source),
            warnings,
        });
    }
    match container_fps {
        Some(fps) if fps.is_finite() && fps > 0.0 => {
            warnings.push(format!(
                "no capture fps in the config or the container: timing frames at the \
                 container's {fps} fps; if this is a slow-motion clip stored for playback, \
                 set `fps` in the experiment config"
            ));
            Ok(CaptureFps {
                fps,
                source: FpsSource::ContainerFps,
                warnings,
            })
        }
        _ => Err(
            "no capture fps: a frame folder stores none; set `fps` in the experiment config".into(),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bx(kind: &[u8; 4], payload: &[u8]) -> Vec<u8> {
        let mut out = ((payload.len() + 8) as u32).to_be_bytes().to_vec();
        out.extend_from_slice(kind);
        out.extend_from_slice(payload);
        out
    }

    fn cat(parts: &[Vec<u8>]) -> Vec<u8> {
        parts.concat()
    }

    /// `moov/meta` as Android's MediaMuxer writes it, with `key` as second key.
    fn android_moov(key: &str, fps: f32) -> Vec<u8> {
        let mut keys = vec![0, 0, 0, 0, 0, 0, 0, 2];
        for name in ["com.android.version", key] {
            keys.extend_from_slice(&((name.len() + 8) as u32).to_be_bytes());
            keys.extend_from_slice(b"mdta");
            keys.extend_from_slice(name.as_bytes());
        }
        let mut data = 23u32.to_be_bytes().to_vec();
        data.extend_from_slice(&[0; 4]);
        data.extend_from_slice(&fps.to_be_bytes());
        let version_item = bx(
            &1u32.to_be_bytes(),
            &bx(b"data", &[0, 0, 0, 1, 0, 0, 0, 0, b'1', b'3']),
        );
        let fps_item = bx(&2u32.to_be_bytes(), &bx(b"data", &data));
        let ilst = bx(b"ilst", &cat(&[version_item, fps_item]));
        let hdlr = bx(b"hdlr", &cat(&[vec![0; 8], b"mdta".to_vec(), vec![0; 12]]));
        cat(&[
            bx(b"mvhd", &[0; 100]),
            bx(b"meta", &cat(&[hdlr, bx(b"keys", &keys), ilst])),
        ])
    }

    /// One video track: 1000 samples of `delta` ticks at `timescale`, and an
    /// edit list of entries (duration, media time, rate).
    fn iphone_moov(timescale: u32, delta: u32, rates: &[f64]) -> Vec<u8> {
        let mut elst = vec![0, 0, 0, 0];
        elst.extend_from_slice(&(rates.len() as u32).to_be_bytes());
        for &rate in rates {
            elst.extend_from_slice(&100u32.to_be_bytes());
            elst.extend_from_slice(&0u32.to_be_bytes());
            elst.extend_from_slice(&((rate * 65536.0) as i32).to_be_bytes());
        }
        let mut mdhd = vec![0; 12];
        mdhd.extend_from_slice(&timescale.to_be_bytes());
        mdhd.extend_from_slice(&[0; 8]);
        let mut stts = vec![0, 0, 0, 0, 0, 0, 0, 2];
        for (samples, d) in [(1000u32, delta), (1, 7)] {
            stts.extend_from_slice(&samples.to_be_bytes());
            stts.extend_from_slice(&d.to_be_bytes());
        }
        let hdlr = bx(b"hdlr", &cat(&[vec![0; 8], b"vide".to_vec(), vec![0; 12]]));
        let stbl = bx(b"stbl", &bx(b"stts", &stts));
        let mdia = bx(
            b"mdia",
            &cat(&[bx(b"mdhd", &mdhd), hdlr, bx(b"minf", &stbl)]),
        );
        let trak = bx(b"trak", &cat(&[bx(b"edts", &bx(b"elst", &elst)), mdia]));
        cat(&[bx(b"mvhd", &[0; 100]), trak])
    }

    #[test]
    fn android_capture_fps_tag_is_found() {
        let rate = capture_rate_in_moov(&android_moov("com.android.capture.fps", 480.0)).unwrap();
        assert_eq!(rate.fps, 480.0);
        assert!(rate.source.contains("Android"));
        assert_eq!(
            capture_rate_in_moov(&android_moov("com.android.other", 480.0)),
            None
        );
    }

    #[test]
    fn iphone_edit_list_gives_the_media_rate() {
        // 240 fps in media time (2400 ticks/s, 10 ticks a frame), slowed 8× in
        // the middle of the clip.
        let rate = capture_rate_in_moov(&iphone_moov(2400, 10, &[1.0, 0.125, 1.0])).unwrap();
        assert_eq!(rate.fps, 240.0);
        // The same track without a slowing edit is an ordinary clip: no claim.
        assert_eq!(capture_rate_in_moov(&iphone_moov(2400, 10, &[1.0])), None);
    }

    #[test]
    fn capture_fps_prefers_config_then_container_tag_then_container_fps() {
        let tag = || {
            Some(ContainerCaptureRate {
                fps: 240.0,
                source: "tag".into(),
            })
        };
        let from_config = resolve_capture_fps(Some(480.0), tag(), Some(30.0)).unwrap();
        assert_eq!(
            (from_config.fps, from_config.source),
            (480.0, FpsSource::Config)
        );
        assert_eq!(from_config.warnings.len(), 1, "config and tag disagree");
        let from_tag = resolve_capture_fps(None, tag(), Some(30.0)).unwrap();
        assert_eq!(from_tag.fps, 240.0);
        let fallback = resolve_capture_fps(None, None, Some(30.0)).unwrap();
        assert_eq!(
            (fallback.fps, fallback.source),
            (30.0, FpsSource::ContainerFps)
        );
        assert!(fallback.warnings[0].contains("set `fps`"));
        assert!(resolve_capture_fps(None, None, None).is_err());
        assert!(resolve_capture_fps(Some(-480.0), None, None).is_err());
    }

    #[test]
    fn a_file_without_moov_has_no_capture_rate() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.mp4");
        std::fs::write(&path, bx(b"ftyp", b"isom0000")).unwrap();
        assert_eq!(container_capture_rate(&path), None);
        let moov_file = dir.path().join("a.mp4");
        let file = cat(&[
            bx(b"ftyp", b"isom0000"),
            bx(b"mdat", &[0; 64]),
            bx(b"moov", &android_moov("com.android.capture.fps", 960.0)),
        ]);
        std::fs::write(&moov_file, file).unwrap();
        assert_eq!(container_capture_rate(&moov_file).unwrap().fps, 960.0);
    }
}
