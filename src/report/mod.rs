//! The pages of the top layer: an experiment's, a study's, a comparison's and a
//! simulation's HTML pages, their plots and tables. They read results and never
//! measure; files are written through [`crate::output`].

pub mod compare;
pub mod experiment;
pub mod failure;
pub mod html;
pub mod plot;
pub mod simulation;
pub mod study;
pub mod study_plots;

/// Errors while making a page; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A file that could not be written.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    /// A figure or table that could not be made from its inputs.
    #[error("cannot draw a figure: {0}")]
    Plot(String),
    /// An overlay (video or contact sheet) that could not be written.
    #[error(transparent)]
    Overlay(Box<crate::overlay::OverlayError>),
}

impl From<crate::overlay::OverlayError> for ReportError {
    fn from(error: crate::overlay::OverlayError) -> Self {
        ReportError::Overlay(Box::new(error))
    }
}
