//! Writers for results: CSV, JSON and plots, each written to a temporary file in
//! the destination folder and renamed into place, so an interrupted run never
//! leaves a half-written result (DESIGN.md, conventions).

pub mod compare;
pub mod diagnostics;
pub mod experiment;
pub mod html;
pub mod plot;
pub mod simulation;
pub mod study;
pub mod study_plots;

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::Serialize;

/// Errors while writing results; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// File-system failure.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file being written.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// Serialisation failure.
    #[error("cannot serialise {path}: {reason}")]
    Serialise {
        /// The file being written.
        path: PathBuf,
        /// Why.
        reason: String,
    },
    /// A figure or table that could not be made from its inputs.
    #[error("cannot draw a figure: {0}")]
    Plot(String),
}

fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes `bytes` to `path` atomically (temporary file in the same folder, then rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), ReportError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir).map_err(io_error(path))?;
    let mut tmp = tempfile::NamedTempFile::new_in(dir).map_err(io_error(path))?;
    tmp.write_all(bytes).map_err(io_error(path))?;
    tmp.persist(path).map_err(|e| ReportError::Io {
        path: path.to_path_buf(),
        source: e.error,
    })?;
    Ok(())
}

/// Writes a value as pretty JSON, atomically.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), ReportError> {
    let text = serde_json::to_string_pretty(value).map_err(|e| ReportError::Serialise {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    write_atomic(path, text.as_bytes())
}

/// Writes records as CSV with a header row, atomically.
pub fn write_csv<T: Serialize>(path: &Path, records: &[T]) -> Result<(), ReportError> {
    let serialise = |reason: String| ReportError::Serialise {
        path: path.to_path_buf(),
        reason,
    };
    let mut writer = csv::Writer::from_writer(Vec::new());
    for record in records {
        writer
            .serialize(record)
            .map_err(|e| serialise(e.to_string()))?;
    }
    let bytes = writer.into_inner().map_err(|e| serialise(e.to_string()))?;
    write_atomic(path, &bytes)
}
