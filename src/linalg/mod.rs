//! Linear algebra: the shared sparse K/M pattern, METIS ordering, faer factorisations, and the
//! dense vector kernels of the transient.

pub mod dense;
pub mod factor;
pub mod kernels;
pub mod ordering;
pub mod sparse;
