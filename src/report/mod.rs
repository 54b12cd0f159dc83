//! Output writers: Matrix Market, VTU mode shapes.

pub mod mtx;
pub mod png;
pub mod vtu;
