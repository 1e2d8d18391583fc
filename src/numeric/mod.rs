//! The crate's numerics, written once: the least-squares solver ([`lsq`]) of the power
//! law, the local fits, the turns' timing and the top face's profile; the 1-D
//! minimiser ([`minimise`]); and the robust statistics ([`robust`]) that every stage
//! uses.

pub mod lsq;
pub mod minimise;
pub mod robust;

pub use minimise::{GoldenSection, bracket_minimum, golden_section};
pub use robust::{QuantileMethod, mad_sigma, median, quantile_sorted, upper_median};
