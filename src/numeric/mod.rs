//! The crate's numerics, written once: the least-squares solver of the local fits
//! ([`lsq`]), the 1-D minimiser ([`minimise`]) and the robust statistics
//! ([`robust`]) that every stage uses.
//!
//! The power law's fit (`crate::energy`) keeps its own Levenberg–Marquardt: a
//! variable projection over one or two nonlinear parameters with a trust radius on
//! the bounded t0 and the Bates–Watts stopping rule, which the local fits do not
//! need and whose different stopping rule would move their numbers.

pub mod lsq;
pub mod minimise;
pub mod robust;

pub use minimise::{GoldenSection, bracket_minimum, golden_section};
pub use robust::{QuantileMethod, mad_sigma, median, quantile_sorted, upper_median};
