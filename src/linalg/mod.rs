//! Sparse linear algebra: the shared K/M pattern, METIS ordering, faer factorisations.

pub mod factor;
pub mod ordering;
pub mod sparse;
