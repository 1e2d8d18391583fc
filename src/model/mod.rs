//! The embedded rigid-body simulator (thesis Chapter 4, Appendix C, Chapter 2).
pub mod closed_form;
pub mod dissipation;
pub mod dynamics;
pub mod params;
pub mod post_flat;
pub mod rosenbrock;
pub mod simulate;
pub mod tuning;
