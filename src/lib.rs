//! eulerdisk: slow-motion footage of spinning disks turned into physics.
pub mod analyse;
pub mod compare;
pub mod config;
pub mod demo;
pub mod energy;
pub mod footage;
pub mod model;
pub mod overlay;
pub mod precession;
pub mod render;
pub mod report;
pub mod reproduce;
pub mod rng;
pub mod signal;
pub mod stats;
pub mod study;
pub mod vision;
