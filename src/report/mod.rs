//! Output writers: atomic file writes, Matrix Market, VTU mode shapes.

pub mod atomic;
pub mod mtx;
pub mod png;
pub mod vtu;
