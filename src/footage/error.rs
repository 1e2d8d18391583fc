//! Why a clip could not be read, always naming the file.

use std::path::{Path, PathBuf};

/// A clip (video file or frame folder) that `footage` could not read.
///
/// Every variant names the file or folder, so a study can list its failures
/// and a user knows which clip to look at.
#[derive(Debug, thiserror::Error)]
pub enum FootageError {
    /// Nothing exists at the given path.
    #[error("{}: no such file or folder", path.display())]
    NotFound { path: PathBuf },

    /// A file whose extension is neither a video container nor usable alone.
    #[error(
        "{}: unknown clip type '.{ext}' (expected a video .mp4/.mov/.avi/.m4v/.mkv, \
         or a folder of .png/.tif/.tiff/.jpg/.jpeg frames)",
        path.display()
    )]
    UnknownExtension { path: PathBuf, ext: String },

    /// A folder that holds no frame images.
    #[error("{}: folder holds no frames (.png/.tif/.tiff/.jpg/.jpeg)", path.display())]
    EmptyFolder { path: PathBuf },

    /// The file exists but OpenCV (or the file system) could not read it.
    #[error("{}: unreadable: {reason}", path.display())]
    Unreadable { path: PathBuf, reason: String },
}

impl FootageError {
    /// The file or folder the error is about.
    pub fn path(&self) -> &Path {
        match self {
            Self::NotFound { path }
            | Self::UnknownExtension { path, .. }
            | Self::EmptyFolder { path }
            | Self::Unreadable { path, .. } => path,
        }
    }

    /// The file-system metadata of `path`: `NotFound` when nothing is there,
    /// `Unreadable` for any other failure.
    pub(crate) fn metadata(path: &Path) -> Result<std::fs::Metadata, Self> {
        std::fs::metadata(path).map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => Self::NotFound {
                path: path.to_path_buf(),
            },
            _ => Self::unreadable(path, e),
        })
    }

    pub(crate) fn unreadable(path: &Path, reason: impl std::fmt::Display) -> Self {
        Self::Unreadable {
            path: path.to_path_buf(),
            reason: reason.to_string(),
        }
    }
}
