//! eulerdisk: slow-motion footage of spinning disks turned into physics.
pub mod energy;
pub mod footage;
pub mod model;
pub mod report;
pub mod reproduce;
pub mod signal;
