//! eulerdisk: slow-motion footage of spinning disks turned into physics.
//!
//! The docs name the constants and helpers each method's numbers come from, most of
//! them private: read them with `cargo doc --document-private-items`.
#![allow(rustdoc::private_intra_doc_links)]
pub mod analyse;
pub mod compare;
pub mod config;
pub mod demo;
pub mod energy;
pub mod footage;
pub(crate) mod lsq;
pub mod model;
pub mod output;
pub mod overlay;
pub mod precession;
pub mod render;
pub mod report;
pub mod reproduce;
pub mod rng;
pub mod signal;
pub mod stats;
pub mod study;
pub mod summary;
pub mod turn_timing;
pub mod vision;
